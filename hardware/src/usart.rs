//! USART2 for the link: 115 200 baud 8N1, receive interrupt; the transmit
//! interrupt is on while bytes wait (RM0090 §30).

use crate::clocks::Clocks;
use crate::Registers;

/// The link's baud rate.
pub const BAUD: u32 = 115_200;

/// USART_BRR for `pclk_hz` at 16× oversampling: USARTDIV = f/baud in 12.4
/// fixed point, rounded (§30.3.4).
pub const fn brr(pclk_hz: u32) -> u16 {
    ((pclk_hz + BAUD / 2) / BAUD) as u16
}

/// Enables USART2 (TE, RE, RXNEIE) at [`BAUD`] from the APB1 clock in force.
pub fn setup(r: &Registers, clocks: &Clocks) {
    let b = brr(clocks.pclk1_hz);
    r.usart2.brr().write(|w| {
        w.div_mantissa()
            .set(b >> 4)
            .div_fraction()
            .set((b & 0xF) as u8)
    });
    r.usart2.cr1().write(|w| {
        w.ue()
            .enabled()
            .te()
            .enabled()
            .re()
            .enabled()
            .rxneie()
            .enabled()
    });
}

/// A received byte, and whether bytes were lost before it in the USART
/// itself (ORE: the handler came late). Reading SR then DR clears both.
pub fn take_rx(r: &Registers) -> Option<(u8, bool)> {
    let sr = r.usart2.sr().read();
    if sr.rxne().bit_is_set() || sr.ore().bit_is_set() {
        let b = r.usart2.dr().read().dr().bits() as u8;
        Some((b, sr.ore().bit_is_set()))
    } else {
        None
    }
}

/// Whether the transmit data register is empty.
pub fn tx_empty(r: &Registers) -> bool {
    r.usart2.sr().read().txe().bit_is_set()
}

/// Writes one byte to the transmit data register.
pub fn tx_write(r: &Registers, b: u8) {
    r.usart2.dr().write(|w| w.dr().set(u16::from(b)));
}

/// The transmit-empty interrupt on or off.
pub fn tx_interrupt(r: &Registers, on: bool) {
    r.usart2.cr1().modify(|_, w| w.txeie().bit(on));
}
