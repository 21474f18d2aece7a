//! The DAC refill and ADC intake bookkeeping (which drive phase each ADC
//! sample belongs to) and the friction measurement.

use super::config::PERIODS_RANGE;
use super::{faults, Device, DeviceError, DriveParam};
use crate::board::estimator::{reasons, Estimate};

impl<const N: usize> Device<'_, N> {
    /// Refills DAC half-buffer `half` (0 or 1) with packed words and records
    /// the drive phase of its first sample for the ADC intake.
    pub fn fill_dac(&mut self, half: usize, buf: &mut [u32]) {
        let fill = self.fills;
        self.fills = fill.wrapping_add(1);
        self.control_fill(fill);
        self.half[half & 1] = (self.dds.accumulator(), self.dds.tuning_word());
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
        self.half_conditions[half & 1] = cond;
        self.dds.fill(buf);
    }

    /// Takes the ADC samples `(f_x, f_z)` of the DAC half-buffer `half`
    /// (same timer ticks, same indices).
    pub fn adc_block(&mut self, half: usize, samples: &[(u16, u16)]) {
        let block = self.adc_blocks;
        self.adc_blocks = block.wrapping_add(1);
        self.control_block_start(block);
        let (acc0, tw) = self.half[half & 1];
        let mut acc = acc0.wrapping_sub(tw.wrapping_mul(self.cfg.adc_lag_samples));
        self.est.set_conditions(self.half_conditions[half & 1]);
        let mut closed = false;
        for &(x, z) in samples {
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
        self.control_block_end(samples.len(), closed);
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
