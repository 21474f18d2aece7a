//! Interrupt priorities (PM0214 §4.3.7): the STM32F405 implements the top
//! four bits of each priority byte, so a level `0..=15` is the byte
//! `level << 4` ([`byte`]); a byte such as 0x08 would be level 0.
//!
//! Levels (lower is more urgent), and what each handler shares:
//! * [`FAULT_INPUT`] 0 — EXTI0 (the amplifier's alarm): sets a flag the DSP
//!   handlers latch; shares nothing else.
//! * [`LINK`] 1 — USART2, and the stall handlers (TIM6_DAC underrun, ADC
//!   overrun): the receive and transmit rings, shared with the main loop
//!   under a lock at this level; flags for the DSP.
//! * [`DSP`] 2 — the DMA handlers (DAC refill, ADC block): the device,
//!   shared with the main loop under a lock at this level (the ceiling),
//!   which never masks the link or the fault input.
//! * the main loop: thread mode, below all.

/// Priority bits the chip implements.
pub const PRIO_BITS: u8 = 4;
/// The fault input's level.
pub const FAULT_INPUT: u8 = 0;
/// The link's and the stall handlers' level.
pub const LINK: u8 = 1;
/// The DSP handlers' level: the device's ceiling.
pub const DSP: u8 = 2;

/// The NVIC priority byte (and BASEPRI value) of a level.
pub const fn byte(level: u8) -> u8 {
    assert!(level < (1 << PRIO_BITS), "priority level out of range");
    level << (8 - PRIO_BITS)
}

// More urgent work never waits for less urgent work.
const _: () = assert!(FAULT_INPUT < LINK && LINK < DSP);
