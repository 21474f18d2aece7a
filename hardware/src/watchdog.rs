//! The independent watchdog (RM0090 §21) and the rule that feeds it.
//!
//! IWDG from the LSI (32 kHz nominal, 17–47 kHz over parts and temperature,
//! DS8626 Table 42): prescaler /8, reload 4095 → 1.02 s nominal (0.70–1.93 s).
//! It is started first in the bring-up, so that nothing after it can hang
//! the board for good.
//!
//! **Fed only while the streams move** ([`Liveness`]): the main loop feeds
//! it when both the DAC's half-transfers and the ADC's blocks have advanced
//! since the last feed. A stream that stopped without any flag (nothing
//! else would notice) then resets the board within the watchdog's period;
//! after the reset the DAC is off and `watchdog_reset` is latched.

use crate::Registers;

/// IWDG_KR: unlock PR/RLR.
pub const KEY_UNLOCK: u16 = 0x5555;
/// IWDG_KR: reload the counter.
pub const KEY_FEED: u16 = 0xAAAA;
/// IWDG_KR: start.
pub const KEY_START: u16 = 0xCCCC;
/// IWDG_PR value: /8.
pub const PRESCALER: u8 = 1;
/// IWDG_RLR value.
pub const RELOAD: u16 = 0xFFF;

/// Starts the watchdog (it cannot be stopped but by a reset).
pub fn start(r: &Registers) {
    r.iwdg.kr().write(|w| w.key().unlock());
    // SAFETY: PR 0..=6, RLR 12 bits.
    r.iwdg.pr().write(|w| unsafe { w.pr().bits(PRESCALER) });
    r.iwdg.rlr().write(|w| unsafe { w.rl().bits(RELOAD) });
    r.iwdg.kr().write(|w| w.key().start());
}

/// Reloads the watchdog.
pub fn feed(r: &Registers) {
    r.iwdg.kr().write(|w| w.key().feed());
}

/// Whether the last reset was the watchdog's (RCC_CSR.WDGRSTF); clears the
/// reset flags (RMVF).
pub fn take_reset_flag(r: &Registers) -> bool {
    let was = r.rcc.csr().read().wdgrstf().bit_is_set();
    r.rcc.csr().modify(|_, w| w.rmvf().set_bit());
    was
}

/// Feeds only while both streams move (module docs).
#[derive(Debug, Clone, Copy, Default)]
pub struct Liveness {
    dac: u32,
    adc: u32,
}

impl Liveness {
    /// Whether to feed now, given the counts of DAC half-transfers and ADC
    /// blocks so far: both advanced since the last `true`.
    pub fn check(&mut self, dac_halves: u32, adc_blocks: u32) -> bool {
        if dac_halves != self.dac && adc_blocks != self.adc {
            self.dac = dac_halves;
            self.adc = adc_blocks;
            true
        } else {
            false
        }
    }
}
