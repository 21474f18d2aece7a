//! The external fault input: PB0, active low, an amplifier's open-drain
//! alarm output held high by the internal pull-up; EXTI line 0 on the
//! falling edge (RM0090 §9.2.3 SYSCFG_EXTICR1, §12.3 EXTI).
//!
//! **Settling.** The pull-up is 30–50 kΩ (DS8626 Table 47); with the cable
//! and the amplifier's output the pin sees up to [`INPUT_CAPACITANCE_PF`]
//! (a stated assumption: ~100 pF/m of cable). The pin reads high once the
//! RC charge passes V_IH = 0.7·V_DD, after R·C·ln(1/0.3) = 1.2·RC; the
//! input is read no earlier than [`PULLUP_SETTLE_US`] = 5·R_max·C after the
//! pull-up was switched on (a margin of 4 over the threshold time). The
//! pull-up is armed first in the bring-up ([`arm_pull_up`]) and read last
//! ([`read_and_arm`]), which waits out whatever of that time is left.

use crate::clocks::Clocks;
use crate::{Delay, Registers};

/// The pull-up's largest resistance, Ω (DS8626 Table 47).
pub const PULL_UP_MAX_OHM: u32 = 50_000;
/// The largest capacitance on the input this firmware allows for, pF.
pub const INPUT_CAPACITANCE_PF: u32 = 1_000;
/// Time from switching the pull-up on to reading the input, µs: 5·R·C.
pub const PULLUP_SETTLE_US: u32 =
    (5 * PULL_UP_MAX_OHM as u64 * INPUT_CAPACITANCE_PF as u64 / 1_000_000) as u32;

/// Proof that the pull-up is on, with the time spent since, µs.
#[derive(Debug)]
pub struct PullUpArmed {
    /// Microseconds known to have passed since the pull-up was switched
    /// on (the bring-up adds its waits).
    pub elapsed_us: u32,
}

/// PB0 as input with pull-up (GPIOB, SYSCFG clocks on).
pub fn arm_pull_up(r: &Registers) -> PullUpArmed {
    r.rcc.ahb1enr().modify(|_, w| w.gpioben().enabled());
    r.rcc.apb2enr().modify(|_, w| w.syscfgen().enabled());
    r.gpiob.moder().modify(|_, w| w.moder0().input());
    r.gpiob.pupdr().modify(|_, w| w.pupdr0().pull_up());
    PullUpArmed { elapsed_us: 0 }
}

/// Waits out the rest of [`PULLUP_SETTLE_US`], routes PB0 to EXTI0 on the
/// falling edge, clears a stale pending bit, unmasks the line, and returns
/// whether the input is already active (an alarm raised before the edge
/// detector was armed).
pub fn read_and_arm(
    r: &Registers,
    clocks: &Clocks,
    delay: &mut impl Delay,
    armed: PullUpArmed,
) -> bool {
    if armed.elapsed_us < PULLUP_SETTLE_US {
        delay.wait_us(PULLUP_SETTLE_US - armed.elapsed_us, clocks.sysclk_hz);
    }
    // SAFETY: EXTI0 = 0b0001 selects port B (§9.2.3).
    r.syscfg
        .exticr1()
        .modify(|_, w| unsafe { w.exti0().bits(0b0001) });
    r.exti.ftsr().modify(|_, w| w.tr0().enabled());
    r.exti.pr().write(|w| w.pr0().clear());
    r.exti.imr().modify(|_, w| w.mr0().unmasked());
    r.gpiob.idr().read().idr0().is_low()
}

/// Whether EXTI line 0 fired since the last call (the pending bit, cleared).
pub fn take_pending(r: &Registers) -> bool {
    let p = r.exti.pr().read().pr0().bit_is_set();
    if p {
        r.exti.pr().write(|w| w.pr0().clear());
    }
    p
}
