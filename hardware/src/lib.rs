//! The driver board's register layer (STM32F405, RM0090): everything the
//! firmware writes to or reads from a peripheral register, typed through the
//! PAC's field writers, and written once here so that it runs natively too.
//!
//! Every function takes the register blocks it uses as references
//! ([`Registers`]): the firmware passes the chip's (`&*pac::DMA1::ptr()` …),
//! the native tests (`hardware/tests/`) the same PAC blocks placed in RAM, a
//! *register file*, with a small simulation of the hardware behind it (ready
//! bits, input captures, the DMA's NDTR and flags). Time passes only through
//! [`Delay`]: on the chip a busy wait, in the tests the simulation's clock.
//!
//! Modules, in the order of the bring-up ([`bring_up`]):
//! * [`watchdog`] — the independent watchdog, the debug freeze bits, and the
//!   rule that feeds it only while both DMA streams move;
//! * [`fault_input`] — PB0, the amplifier's alarm input (pull-up, EXTI0);
//! * [`clocks`] — HSE → PLL → 168 MHz for any crystal set at build time
//!   (`FIRMWARE_HSE_HZ`), with time-outs, the flash wait states read back,
//!   and the crystal and core clock measured against the internal HSI;
//! * [`buffers`] — the DMA buffers' lengths from one constant;
//! * [`streams`] — DMA1 Stream5 (DAC) and DMA2 Stream0 (ADC): set-up, read
//!   back, and the handlers' flag decisions (which half, which error);
//! * [`sampling`] — DAC, ADC pair and TIM2: the sample clock and its
//!   consumers, armed in an order that loses no trigger;
//! * [`usart`] — USART2 for the link;
//! * [`nvic`] — the interrupt priorities;
//! * [`self_test`] — the power-up self-test reported in `Info`.
#![no_std]
#![deny(missing_docs)]

pub mod bring_up;
pub mod buffers;
pub mod clocks;
pub mod fault_input;
pub mod nvic;
pub mod sampling;
pub mod self_test;
pub mod streams;
pub mod usart;
pub mod watchdog;

pub use stm32f4::stm32f405 as pac;

/// The register blocks the board uses, by reference: the chip's in the
/// firmware, a register file in RAM in the tests.
#[derive(Clone, Copy)]
pub struct Registers<'a> {
    /// Reset and clock control.
    pub rcc: &'a pac::rcc::RegisterBlock,
    /// Flash interface (wait states, caches).
    pub flash: &'a pac::flash::RegisterBlock,
    /// Debug MCU (revision id, freeze bits).
    pub dbgmcu: &'a pac::dbgmcu::RegisterBlock,
    /// Port A: forces, pickups, DAC outputs, USART2.
    pub gpioa: &'a pac::gpioa::RegisterBlock,
    /// Port B: the fault input PB0.
    pub gpiob: &'a pac::gpiob::RegisterBlock,
    /// EXTI line routing.
    pub syscfg: &'a pac::syscfg::RegisterBlock,
    /// External interrupt controller.
    pub exti: &'a pac::exti::RegisterBlock,
    /// DMA1 (Stream5: the DAC).
    pub dma1: &'a pac::dma2::RegisterBlock,
    /// DMA2 (Stream0: the ADC pair).
    pub dma2: &'a pac::dma2::RegisterBlock,
    /// The dual DAC.
    pub dac: &'a pac::dac::RegisterBlock,
    /// ADC1 (master of the pair).
    pub adc1: &'a pac::adc1::RegisterBlock,
    /// ADC2 (slave).
    pub adc2: &'a pac::adc1::RegisterBlock,
    /// ADC common registers (dual mode).
    pub adc_common: &'a pac::adc_common::RegisterBlock,
    /// TIM2: the sample clock.
    pub tim2: &'a pac::tim2::RegisterBlock,
    /// TIM11: the clock measurement (input capture of HSE/RTCPRE).
    pub tim11: &'a pac::tim11::RegisterBlock,
    /// USART2: the link.
    pub usart2: &'a pac::usart1::RegisterBlock,
    /// Independent watchdog.
    pub iwdg: &'a pac::iwdg::RegisterBlock,
}

impl Registers<'static> {
    /// The chip's register blocks.
    ///
    /// # Safety
    /// The caller owns the peripherals (it took `pac::Peripherals`) and
    /// shares them with interrupt handlers only under the rules of the
    /// firmware's locks.
    pub unsafe fn chip() -> Self {
        // SAFETY: the fixed addresses of RM0090's memory map, valid for the
        // program's life; exclusivity is the caller's promise.
        unsafe {
            Registers {
                rcc: &*pac::RCC::ptr(),
                flash: &*pac::FLASH::ptr(),
                dbgmcu: &*pac::DBGMCU::ptr(),
                gpioa: &*pac::GPIOA::ptr(),
                gpiob: &*pac::GPIOB::ptr(),
                syscfg: &*pac::SYSCFG::ptr(),
                exti: &*pac::EXTI::ptr(),
                dma1: &*pac::DMA1::ptr(),
                dma2: &*pac::DMA2::ptr(),
                dac: &*pac::DAC::ptr(),
                adc1: &*pac::ADC1::ptr(),
                adc2: &*pac::ADC2::ptr(),
                adc_common: &*pac::ADC_COMMON::ptr(),
                tim2: &*pac::TIM2::ptr(),
                tim11: &*pac::TIM11::ptr(),
                usart2: &*pac::USART2::ptr(),
                iwdg: &*pac::IWDG::ptr(),
            }
        }
    }
}

/// Time passing during the bring-up: a busy wait on the chip; the tests'
/// simulated clock, which moves the simulated hardware on.
pub trait Delay {
    /// Waits at least `us` microseconds, the core running at `sysclk_hz`.
    fn wait_us(&mut self, us: u32, sysclk_hz: u32);
}

/// Polls `ready` every `step_us` until it holds or `limit_us` have passed:
/// the only way the bring-up waits for the hardware (no unbounded loop).
/// Returns whether it became ready.
pub fn wait_until(
    delay: &mut impl Delay,
    sysclk_hz: u32,
    step_us: u32,
    limit_us: u32,
    mut ready: impl FnMut() -> bool,
) -> bool {
    let mut waited = 0;
    loop {
        if ready() {
            return true;
        }
        if waited >= limit_us {
            return false;
        }
        delay.wait_us(step_us, sysclk_hz);
        waited += step_us;
    }
}
