//! The DAC refill and ADC intake bookkeeping (which drive phase each ADC
//! sample belongs to) and the friction measurement.

use super::config::PERIODS_RANGE;
use super::{faults, Device, DeviceError, DriveParam};
use crate::dma::HalfEvent;
use crate::estimator::{reasons, Estimate, Estimator};
use crate::reference::{Reference, BLOCK};

/// Fills whose start phase and conditions are kept (fill `n` is sampled by
/// ADC block `n`, which may arrive after fills `n + 1` and `n + 2`).
pub(super) const FILL_RING: usize = 4;

impl<const N: usize> Device<'_, N> {
    /// Refills DAC half-buffer `half` (0 or 1) with packed words and records
    /// the drive phase of its first sample for the ADC intake (per fill
    /// number: ADC block `n` is the output of the `n`-th fill).
    pub fn fill_dac(&mut self, _half: usize, buf: &mut [u32]) {
        probe!(0);
        let fill = self.fills;
        self.fills = fill.wrapping_add(1);
        self.control_fill(fill);
        probe!(1);
        self.displacement_fill(fill, buf.len());
        probe!(2);
        let slot = fill as usize % FILL_RING;
        self.half[slot] = (self.dds.accumulator(), self.dds.tuning_word());
        // Settled before the fill stays settled through it (targets change
        // only between fills).
        let mut cond = 0;
        if !self.running {
            cond |= reasons::NOT_RUNNING;
        }
        if !self.drive_settled() {
            cond |= reasons::NOT_SETTLED;
        }
        if self.latch.any() {
            cond |= reasons::FAULT;
        }
        self.half_conditions[slot] = cond;
        // The reference words the codes are formed from are kept for the
        // ADC blocks this fill drives, as they see them (`kept_reference`):
        // its first BLOCK − L words end block `fill`'s, its last L begin
        // block `fill + 1`'s.
        let lag = self.cfg.adc_lag_samples as usize;
        if buf.len() == BLOCK && lag < BLOCK {
            let next = (slot + 1) % FILL_RING;
            let (cur, nxt) = two_slots(&mut self.fill_refs, slot, next);
            self.dds
                .fill_with_reference(buf, &mut cur[lag..], &mut nxt[..lag]);
            self.fill_refs_by[slot].1 = fill;
            self.fill_refs_by[next].0 = fill;
        } else {
            self.dds.fill(buf);
        }
        probe!(3);
    }

    /// Whether ADC block `block` of `len` samples has its reference words
    /// whole in its slot of `fill_refs`: `L` words from fill `block − 1`
    /// and the rest from fill `block` (sample `i` saw DAC word `i − L`, `L`
    /// = [`DeviceConfig::adc_lag_samples`], each word formed at the tuning
    /// word it was played at). Not for a block of another length, or before
    /// both fills ran (power-up), or once a later fill reused the slot.
    ///
    /// [`DeviceConfig::adc_lag_samples`]: super::DeviceConfig::adc_lag_samples
    fn kept_reference(&self, block: u32, len: usize) -> bool {
        let slot = block as usize % FILL_RING;
        len == BLOCK && self.fill_refs_by[slot] == (block.wrapping_sub(1), block)
    }

    /// The DAC interrupt's work: refills the half `ev` names with
    /// [`Device::fill_dac`] (`buf` is that half only) and, if the handler was
    /// late ([`HalfEvent::late`]: the DMA output a stale half), latches
    /// [`faults::DAC_UNDERRUN`] through [`Device::fault`].
    pub fn dac_half_done(&mut self, ev: HalfEvent, buf: &mut [u32]) {
        self.fill_dac(ev.half, buf);
        if ev.late {
            self.fault(faults::DAC_UNDERRUN);
        }
    }

    /// The ADC interrupt's work: if the handler was late
    /// ([`HalfEvent::late`]), the block before this one was overwritten
    /// unread: it is counted as missed (so that block `n` stays the output of
    /// fill `n`) and [`faults::ADC_OVERRUN`] is latched through
    /// [`Device::fault`]; then `samples` (the half `ev` names) are taken with
    /// [`Device::adc_block`].
    pub fn adc_half_done(&mut self, ev: HalfEvent, samples: &[(u16, u16)]) {
        if ev.late {
            self.adc_blocks = self.adc_blocks.wrapping_add(1);
            self.fault(faults::ADC_OVERRUN);
        }
        self.adc_block(ev.half, samples);
    }

    /// [`Device::adc_half_done`] with the motion pickups' samples `(z, x)`
    /// of the same ticks ([`Device::adc_block_with_pickups`]): the board's
    /// ADC interrupt, whose DMA brings forces and pickups together.
    pub fn adc_half_done_with_pickups(
        &mut self,
        ev: HalfEvent,
        samples: &[(u16, u16)],
        pickups: &[(u16, u16)],
    ) {
        if ev.late {
            self.adc_blocks = self.adc_blocks.wrapping_add(1);
            self.fault(faults::ADC_OVERRUN);
        }
        self.adc_block_with_pickups(ev.half, samples, pickups);
    }

    /// ADC blocks (64-sample chunks of them) whose drive-phase reference
    /// the ADC formed itself since power-up, because the words their DAC
    /// fills formed were not kept whole (`kept_reference`): the first block,
    /// blocks of another length than [`BLOCK`], a lag of a block or more.
    /// In steady running on the board it stays at 1; each one more costs
    /// ≈ 1 950 instructions in the ADC handler (issue 35).
    pub fn adc_references_formed(&self) -> u32 {
        self.references_formed
    }

    /// ADC blocks taken or missed since power-up (the number of the next).
    pub fn adc_blocks(&self) -> u32 {
        self.adc_blocks
    }

    /// Takes the ADC samples `(f_x, f_z)` of the DAC half-buffer `_half`
    /// (ADC block `n` must be the output of the `n`-th [`Device::fill_dac`]:
    /// the half index itself is not needed)
    /// (same timer ticks, same indices).
    pub fn adc_block(&mut self, _half: usize, samples: &[(u16, u16)]) {
        self.intake(samples, &[]);
    }

    /// One ADC block in one pass per [`BLOCK`] samples (issue 35): the drive
    /// phase's Q15 reference formed once ([`Reference`], eq. R1) and every
    /// signal summed against it in integers — the forces into the
    /// estimator, the pickups (`(z, x)`, as many as the forces or none)
    /// into their lock-ins ([`Device::adc_block_with_pickups`]). Then the
    /// pickups' window, if it spans enough phase, and the μ loop's update,
    /// if its estimate closed.
    pub(super) fn intake(&mut self, samples: &[(u16, u16)], pickups: &[(u16, u16)]) {
        probe!(10);
        let block = self.adc_blocks;
        self.adc_blocks = block.wrapping_add(1);
        let open_at = self.control_block_start(block, samples.len());
        // Block n samples the output of fill n: on the board fill n + 2 has
        // already run when block n arrives (the DAC's interrupt is first), so
        // the records are kept per fill number, not per half.
        let slot = block as usize % FILL_RING;
        let (acc0, tw) = self.half[slot];
        let acc = self.cfg.adc_reference_word(acc0, tw);
        self.est.set_conditions(self.half_conditions[slot]);
        let mut closed = false;
        // The closed loop's estimates leave gaps (the dead time, the
        // transitions, the wait for a period start, the sample that closes
        // a window: `closed_loop.rs`); while it runs every sample is
        // checked, and a railed one latches the fault at once.
        if self.control_on() && crate::reference::any_railed(samples) {
            self.fault(faults::ADC_SATURATED);
        }
        // The fill's own words when they are kept whole (one product per
        // sample for the DAC and the ADC, eq. R3), else formed here (`r`).
        let kept = self.kept_reference(block, samples.len());
        let mut r = Reference::EMPTY;
        let mut pickup_railed = false;
        probe!(11);
        for (k, chunk) in samples.chunks(BLOCK).enumerate() {
            let start = k * BLOCK;
            let a = acc.wrapping_add(tw.wrapping_mul(start as u32));
            if !kept {
                r.set(self.table, a, tw, chunk.len());
                self.references_formed = self.references_formed.wrapping_add(1);
            }
            // The words, borrowed afresh at each use (the device is
            // changed in between).
            macro_rules! words {
                () => {
                    if kept {
                        &self.fill_refs[slot][..]
                    } else {
                        r.words()
                    }
                };
            }
            if let Some(p) = pickups.get(start..start + chunk.len()) {
                pickup_railed = self.motion.push_block(words!(), p, tw) || pickup_railed;
            }
            probe!(12);
            // Split where the μ loop opens its estimate (`control_open`).
            let cut = open_at
                .filter(|&o| (start..start + chunk.len()).contains(&o))
                .map_or(chunk.len(), |o| o - start);
            if self
                .est
                .push_block(&words!()[..cut], a, tw, &chunk[..cut])
                .is_some()
            {
                closed = true;
            }
            if cut < chunk.len() {
                self.control_open();
                let a = a.wrapping_add(tw.wrapping_mul(cut as u32));
                if self
                    .est
                    .push_block(&words!()[cut..], a, tw, &chunk[cut..])
                    .is_some()
                {
                    closed = true;
                }
            }
            probe!(13);
        }
        // A railed sample in the window: the contact is pressed too hard
        // (or a sensor is broken): the safe state, through the one path.
        if closed && self.est.saturated() {
            self.fault(faults::ADC_SATURATED);
        }
        // A railed pickup while the displacement loop acts on the pickups:
        // the window's amplitude is clipped (too small), so the loop would
        // drive harder and the lift-off guard would read too little — the
        // safe state, through the one path. (Outside the mode an unused
        // pickup input may sit at a rail: not a fault.)
        if pickup_railed && self.running && self.displacement_mode() {
            self.fault(faults::ADC_SATURATED);
        }
        probe!(14);
        if !pickups.is_empty() {
            self.motion_window(block);
        }
        probe!(15);
        self.control_block_end(block, samples.len(), closed);
        probe!(16);
    }

    /// Starts a measurement over `periods` drive periods.
    ///
    /// # Errors
    /// In this order: [`DeviceError::Faulted`] while a fault is latched (like
    /// [`Device::start`]); [`DeviceError::OutOfRange`] outside
    /// [`PERIODS_RANGE`]; [`DeviceError::Busy`] if one is running or the
    /// closed loop runs (its estimates are the loop's).
    pub fn measure(&mut self, periods: u32) -> Result<(), DeviceError> {
        if self.latch.any() {
            return Err(DeviceError::Faulted(self.latch.bits()));
        }
        check_periods(periods)?;
        if self.est.busy() || self.control_on() {
            return Err(DeviceError::Busy);
        }
        self.est.start(periods).map_err(DeviceError::Estimate)
    }

    /// Abandons a running measurement (nothing if none runs); the last
    /// estimate is gone too.
    pub fn abort_measurement(&mut self) {
        if self.est.busy() {
            self.est.abort();
        }
    }

    /// The last finished measurement ([`estimate`] of [`Device::estimator`]).
    ///
    /// # Errors
    /// [`DeviceError::Estimate`] (`NotReady` while running).
    pub fn estimate(&self) -> Result<Estimate, DeviceError> {
        estimate(&self.est)
    }

    /// The estimator: its window's sums, state and calibration. The server
    /// clones it (≈ 1.3 KB) out of the device's critical section and
    /// computes [`estimate`] on the copy with the device released: the
    /// means, lock-in harmonics and standard error in soft-float f64 cost
    /// ≈ 9 000 instructions on the Cortex-M4F.
    pub fn estimator(&self) -> &Estimator {
        &self.est
    }
}

/// The estimate of an estimator's finished window (what
/// [`Device::estimate`] answers; callable on a copy, [`Device::estimator`],
/// outside the device's critical section).
///
/// # Errors
/// [`DeviceError::Estimate`] (`NotReady` while running).
pub fn estimate(est: &Estimator) -> Result<Estimate, DeviceError> {
    est.estimate().map_err(DeviceError::Estimate)
}

/// `Ok` for a number of periods in [`PERIODS_RANGE`].
///
/// # Errors
/// [`DeviceError::OutOfRange`] naming [`DriveParam::Periods`].
pub fn check_periods(periods: u32) -> Result<(), DeviceError> {
    let (lo, hi) = PERIODS_RANGE;
    if (lo..=hi).contains(&periods) {
        Ok(())
    } else {
        Err(DeviceError::OutOfRange {
            param: DriveParam::Periods,
            min: lo as f32,
            max: hi as f32,
        })
    }
}

/// Slots `a` and `b` (different) of `r`, both mutable.
fn two_slots<T>(r: &mut [T; FILL_RING], a: usize, b: usize) -> (&mut T, &mut T) {
    if a < b {
        let (lo, hi) = r.split_at_mut(b);
        (&mut lo[a], &mut hi[0])
    } else {
        let (lo, hi) = r.split_at_mut(a);
        (&mut hi[0], &mut lo[b])
    }
}
