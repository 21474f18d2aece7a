//! The DAC refill and ADC intake bookkeeping (which drive phase each ADC
//! sample belongs to) and the friction measurement.

use super::config::PERIODS_RANGE;
use super::{faults, Device, DeviceError, DriveParam};
use crate::board::estimator::{reasons, Estimate};

/// Fills whose start phase and conditions are kept (fill `n` is sampled by
/// ADC block `n`, which may arrive after fills `n + 1` and `n + 2`).
pub(super) const FILL_RING: usize = 4;

impl<const N: usize> Device<'_, N> {
    /// Refills DAC half-buffer `half` (0 or 1) with packed words and records
    /// the drive phase of its first sample for the ADC intake (per fill
    /// number: ADC block `n` is the output of the `n`-th fill).
    pub fn fill_dac(&mut self, _half: usize, buf: &mut [u32]) {
        let fill = self.fills;
        self.fills = fill.wrapping_add(1);
        self.control_fill(fill);
        let slot = fill as usize % FILL_RING;
        self.half[slot] = (self.dds.accumulator(), self.dds.tuning_word());
        // Settled before the fill stays settled through it (targets change
        // only between fills).
        let mut cond = 0;
        if !self.running {
            cond |= reasons::NOT_RUNNING;
        }
        if !self.dds.settled() {
            cond |= reasons::NOT_SETTLED;
        }
        if self.faults != 0 {
            cond |= reasons::FAULT;
        }
        self.half_conditions[slot] = cond;
        self.dds.fill(buf);
    }

    /// Takes the ADC samples `(f_x, f_z)` of the DAC half-buffer `_half`
    /// (ADC block `n` must be the output of the `n`-th [`Device::fill_dac`]:
    /// the half index itself is not needed)
    /// (same timer ticks, same indices).
    pub fn adc_block(&mut self, _half: usize, samples: &[(u16, u16)]) {
        let block = self.adc_blocks;
        self.adc_blocks = block.wrapping_add(1);
        let open_at = self.control_block_start(block, samples.len());
        // Block n samples the output of fill n: on the board fill n + 2 has
        // already run when block n arrives (the DAC's interrupt is first), so
        // the records are kept per fill number, not per half.
        let slot = block as usize % FILL_RING;
        let (acc0, tw) = self.half[slot];
        let mut acc = acc0.wrapping_sub(tw.wrapping_mul(self.cfg.adc_lag_samples));
        self.est.set_conditions(self.half_conditions[slot]);
        let mut closed = false;
        for (i, &(x, z)) in samples.iter().enumerate() {
            if open_at == Some(i) {
                self.control_open();
            }
            if self.est.push(self.table, acc, x, z) {
                closed = true;
                if let Ok(e) = self.est.estimate() {
                    if e.saturated {
                        self.faults |= faults::ADC_SATURATED;
                    }
                }
            }
            acc = acc.wrapping_add(tw);
        }
        self.control_block_end(block, samples.len(), closed);
    }

    /// Starts a measurement over `periods` drive periods.
    ///
    /// # Errors
    /// In this order: [`DeviceError::Faulted`] while a fault is latched (like
    /// [`Device::start`]); [`DeviceError::OutOfRange`] outside
    /// [`PERIODS_RANGE`]; [`DeviceError::Busy`] if one is running or the
    /// closed loop runs (its estimates are the loop's).
    pub fn measure(&mut self, periods: u32) -> Result<(), DeviceError> {
        if self.faults != 0 {
            return Err(DeviceError::Faulted(self.faults));
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

    /// The last finished measurement.
    ///
    /// # Errors
    /// [`DeviceError::Estimate`] (`NotReady` while running).
    pub fn estimate(&self) -> Result<Estimate, DeviceError> {
        self.est.estimate().map_err(DeviceError::Estimate)
    }
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
