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

use crate::pac::Interrupt;

/// Priority bits the chip implements.
pub const PRIO_BITS: u8 = 4;
/// The fault input's level.
pub const FAULT_INPUT: u8 = 0;
/// The link's and the stall handlers' level.
pub const LINK: u8 = 1;
/// The DSP handlers' level: the device's ceiling.
pub const DSP: u8 = 2;

/// Every interrupt the firmware unmasks, with its level (the firmware sets
/// the priorities and unmasks from this table).
pub const PRIORITIES: [(Interrupt, u8); 6] = [
    (Interrupt::EXTI0, FAULT_INPUT),
    (Interrupt::USART2, LINK),
    (Interrupt::TIM6_DAC, LINK),
    (Interrupt::ADC, LINK),
    (Interrupt::DMA1_STREAM5, DSP),
    (Interrupt::DMA2_STREAM0, DSP),
];

/// The interrupts that share the device (the DSP handlers): all at the
/// device's ceiling, [`DSP`]; nothing more urgent touches it.
pub const DEVICE_USERS: [Interrupt; 2] = [Interrupt::DMA1_STREAM5, Interrupt::DMA2_STREAM0];

/// The level of an interrupt in [`PRIORITIES`] (`None`: not used).
pub fn level_of(i: Interrupt) -> Option<u8> {
    PRIORITIES.iter().find(|(j, _)| *j == i).map(|(_, l)| *l)
}

/// The NVIC priority byte (and BASEPRI value) of a level.
pub const fn byte(level: u8) -> u8 {
    assert!(level < (1 << PRIO_BITS), "priority level out of range");
    level << (8 - PRIO_BITS)
}

// More urgent work never waits for less urgent work.
const _: () = assert!(FAULT_INPUT < LINK && LINK < DSP);
