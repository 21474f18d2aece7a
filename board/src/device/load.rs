//! The board's own measure of its DSP time (protocol v8:
//! [`Status::cpu_load_pct`](crate::device::Status::cpu_load_pct) and
//! [`Status::cpu_load_max_pct`](crate::device::Status::cpu_load_max_pct)).
//!
//! Each half-buffer the DMA plays and samples must be refilled (the DAC
//! handler, `Device::dac_half_done`) and analysed (the ADC handler,
//! `Device::adc_half_done_with_pickups`) before the stream wraps. The
//! firmware counts the cycles `c` both handlers took for the same
//! half-buffer — the DWT cycle counter on silicon, SysTick calibrated to
//! instructions under QEMU — and hands them here with the half-buffer's
//! budget `B`. The load reported is
//!
//! ```text
//! (L1)  load = 100 · c / B   %,   B = f_core · HALF / f_s   cycles
//! ```
//!
//! (`B` = 168 MHz · 64 / 500 kS/s = 21 504 cycles on the STM32F405). Above
//! 100 % a handler is late: the DMA has wrapped onto a half not yet refilled.
//! The maximum is kept since power-up and cleared by `Reset`. A device
//! whose firmware never records a half-buffer (the virtual device) reports
//! neither (`None`).
//!
//! Context: `record` runs in the ADC handler (the DSP level, under the
//! device's lock); the percentages are formed only when a `Status` is read
//! (the main loop), in f32: `c` and `B` below 2²⁴ are exact in f32, so
//! (L1) is the f32-rounded quotient, relative error ≤ 2⁻²³ per operation.

use core::num::NonZeroU32;

/// The last half-buffer's DSP cycles and the largest since power-up or
/// the last `Reset`, with the budget they were counted against.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct CpuLoad {
    /// Cycles of the last recorded half-buffer and its budget (`None`:
    /// none recorded since power-up).
    last: Option<(u32, NonZeroU32)>,
    /// The largest recorded since power-up or [`CpuLoad::clear_max`], with
    /// its budget.
    max: Option<(u32, NonZeroU32)>,
}

/// Eq. (L1): `100 · cycles / budget`, %.
fn pct((cycles, budget): (u32, NonZeroU32)) -> f32 {
    cycles as f32 * 100.0 / budget.get() as f32
}

impl CpuLoad {
    /// Nothing recorded.
    pub const fn new() -> Self {
        CpuLoad {
            last: None,
            max: None,
        }
    }

    /// Records one half-buffer's DSP work: `cycles` spent, out of `budget`
    /// cycles per half-buffer. The maximum compares the loads (L1), so a
    /// change of budget (clock) keeps it meaningful.
    pub fn record(&mut self, cycles: u32, budget: NonZeroU32) {
        let now = (cycles, budget);
        self.last = Some(now);
        // Compare c/B without division: c·B' vs c'·B in u64 (exact).
        let larger = match self.max {
            None => true,
            Some((c, b)) => {
                u64::from(cycles) * u64::from(b.get()) > u64::from(c) * u64::from(budget.get())
            }
        };
        if larger {
            self.max = Some(now);
        }
    }

    /// Forgets the maximum (`Reset`); the last half-buffer stays.
    pub fn clear_max(&mut self) {
        self.max = None;
    }

    /// The last half-buffer's load (L1), %; `None` before the first record.
    pub fn last_pct(&self) -> Option<f32> {
        self.last.map(pct)
    }

    /// The largest load (L1) since power-up or the last `Reset`, %; `None`
    /// when no half-buffer was recorded since.
    pub fn max_pct(&self) -> Option<f32> {
        self.max.map(pct)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const B: NonZeroU32 = match NonZeroU32::new(21_504) {
        Some(b) => b,
        None => panic!(),
    };

    #[test]
    fn nothing_recorded_is_none() {
        let l = CpuLoad::new();
        assert_eq!((l.last_pct(), l.max_pct()), (None, None));
        assert_eq!(l, CpuLoad::default());
    }

    #[test]
    fn load_is_cycles_over_the_budget() {
        let mut l = CpuLoad::new();
        // 6 451.2 cycles would be 30 %: 6 452 is just above, in f64.
        for (c, want) in [
            (0u32, 0.0f64),
            (6_452, 30.003_720),
            (21_504, 100.0),
            (43_008, 200.0),
        ] {
            l.record(c, B);
            let got = f64::from(l.last_pct().unwrap());
            let exact = f64::from(c) * 100.0 / 21_504.0;
            assert!((exact - want).abs() < 1e-6, "{c}: {exact}");
            // c·100 < 2²⁴ is exact in f32; the quotient is rounded once:
            // ≤ 2⁻²⁴ relative (f32::EPSILON = 2⁻²³).
            assert!((got - exact).abs() <= exact * f64::from(f32::EPSILON) / 2.0);
        }
    }

    #[test]
    fn max_holds_the_largest_until_cleared() {
        let mut l = CpuLoad::new();
        l.record(5_000, B);
        l.record(9_000, B);
        l.record(2_000, B);
        assert_eq!(l.last_pct(), Some(2_000.0 * 100.0 / 21_504.0));
        assert_eq!(l.max_pct(), Some(9_000.0 * 100.0 / 21_504.0));
        l.clear_max();
        assert_eq!(l.max_pct(), None);
        assert_eq!(l.last_pct(), Some(2_000.0 * 100.0 / 21_504.0));
        l.record(1_000, B);
        assert_eq!(l.max_pct(), Some(1_000.0 * 100.0 / 21_504.0));
    }

    #[test]
    fn max_compares_loads_not_cycles() {
        // 10 000 of 40 000 (25 %) is less than 6 000 of 21 504 (27.9 %).
        let mut l = CpuLoad::new();
        l.record(6_000, B);
        l.record(10_000, NonZeroU32::new(40_000).unwrap());
        assert_eq!(l.max_pct(), Some(6_000.0 * 100.0 / 21_504.0));
        assert_eq!(l.last_pct(), Some(25.0));
    }
}
