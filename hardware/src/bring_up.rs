//! The bring-up in its order (each step's reason in its module):
//!
//! 1. [`Step::WatchdogStarted`] — the independent watchdog, first, and the
//!    debug freeze bits;
//! 2. [`Step::PullUpArmed`] — the fault input's pull-up, early, so that it
//!    settles while the clocks start;
//! 3. [`Step::ClocksStarted`] — crystal, PLL, flash, with time-outs and
//!    measurements; on failure the core stays on the HSI, steps 4–8 are
//!    skipped (nothing drives the transducers) and the self-test says why;
//! 4. [`Step::PinsSet`] — peripheral clocks and pin modes;
//! 5. [`Step::SampleClockLoaded`] — TIM2 loaded (UG) before any consumer;
//! 6. [`Step::StreamsSet`] — both DMA streams, read back;
//! 7. [`Step::DacArmed`] — the DAC, DHR preloaded;
//! 8. [`Step::AdcArmed`] — the ADC pair, stabilised;
//! 9. [`Step::FaultInputRead`] — EXTI0 armed, the input read (settled);
//! 10. [`Step::LinkUp`] — USART2 at the clock in force.
//!
//! Then the firmware hands the device to the handlers, unmasks them, and
//! calls [`start_sampling`] ([`Step::SampleClockStarted`]).
//!
//! Each step is reported to an observer with the registers: the firmware's
//! does nothing; the native tests' snapshot the register file, so that the
//! order is tested, not only the final values.

use crate::buffers::DmaBuffer;
use crate::clocks::{self, ClockOutcome, Clocks};
use crate::sampling::{self, AdcReady};
use crate::{fault_input, streams, usart, watchdog, Delay, Registers};

/// A step of the bring-up, reported when it is done.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Step {
    /// The watchdog runs.
    WatchdogStarted,
    /// The fault input's pull-up is on.
    PullUpArmed,
    /// The clocks are set (PLL, or HSI after a failure).
    ClocksStarted,
    /// Peripheral clocks and pins are set.
    PinsSet,
    /// TIM2 is loaded, stopped.
    SampleClockLoaded,
    /// Both DMA streams are set and enabled.
    StreamsSet,
    /// The DAC is armed on TRGO.
    DacArmed,
    /// The ADC pair is armed on TRGO and stabilised.
    AdcArmed,
    /// The fault input is armed and was read.
    FaultInputRead,
    /// USART2 is on.
    LinkUp,
    /// TIM2 runs: the first trigger comes one sample later.
    SampleClockStarted,
}

/// The buffers the streams run over.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Buffers {
    /// The DAC buffer ([`crate::buffers::DAC_WORDS`] words).
    pub dac: DmaBuffer,
    /// The ADC buffer ([`crate::buffers::ADC_WORDS`] words).
    pub adc: DmaBuffer,
    /// The DAC buffer's last word (DHR12RD's preload).
    pub dac_preload: u32,
}

/// What the bring-up left, before the sample clock starts.
#[derive(Debug)]
pub struct Prepared {
    /// The clocks' outcome.
    pub clock: ClockOutcome,
    /// Both streams read back their set-up (`None`: not set up).
    pub dma_setup: Option<bool>,
    /// The fault input was active at power-up.
    pub fault_input_active: bool,
    /// The last reset was the watchdog's.
    pub watchdog_reset: bool,
    /// [`start_sampling`] started the sample clock.
    pub sampling: bool,
    adc: Option<AdcReady>,
}

impl Prepared {
    /// The clocks in force.
    pub fn clocks(&self) -> Clocks {
        self.clock.clocks
    }

    /// For an emulator without RCC, DMA or DAC (QEMU's STM32F405): the HSI,
    /// nothing set up, nothing measured.
    pub fn without_hardware() -> Prepared {
        Prepared {
            clock: ClockOutcome::RESET,
            dma_setup: None,
            fault_input_active: false,
            watchdog_reset: false,
            sampling: false,
            adc: None,
        }
    }

    /// Whether the sample clock can start (clocks and DMA set up).
    pub fn can_sample(&self) -> bool {
        self.adc.is_some() && self.dma_setup == Some(true)
    }
}

/// Counts the time it passes on to `inner`, µs.
struct Counting<'d, D> {
    inner: &'d mut D,
    us: u32,
}

impl<D: Delay> Delay for Counting<'_, D> {
    fn wait_us(&mut self, us: u32, sysclk_hz: u32) {
        self.us = self.us.saturating_add(us);
        self.inner.wait_us(us, sysclk_hz);
    }
}

/// Steps 1–10 (module docs).
pub fn prepare(
    r: &Registers,
    bufs: &Buffers,
    delay: &mut impl Delay,
    observe: &mut impl FnMut(Step, &Registers),
) -> Prepared {
    let watchdog_reset = watchdog::take_reset_flag(r);
    watchdog::start(r);
    clocks::debug_freeze(r);
    observe(Step::WatchdogStarted, r);
    let mut pull_up = fault_input::arm_pull_up(r);
    observe(Step::PullUpArmed, r);
    let mut delay = Counting {
        inner: delay,
        us: 0,
    };
    let clock = clocks::start(r, &mut delay);
    observe(Step::ClocksStarted, r);
    let c = clock.clocks;
    let mut out = Prepared {
        clock,
        dma_setup: None,
        fault_input_active: false,
        watchdog_reset,
        sampling: false,
        adc: None,
    };
    if clock.ready && clock.clocks == Clocks::PLL {
        sampling::enable_clocks_and_pins(r);
        observe(Step::PinsSet, r);
        let loaded = sampling::load_sample_clock(r, &c);
        observe(Step::SampleClockLoaded, r);
        streams::setup_dac_stream(r, &bufs.dac);
        streams::setup_adc_stream(r, &bufs.adc);
        out.dma_setup = Some(streams::streams_read_back(r, &bufs.dac, &bufs.adc));
        observe(Step::StreamsSet, r);
        sampling::arm_dac(r, bufs.dac_preload, &loaded);
        observe(Step::DacArmed, r);
        out.adc = Some(sampling::arm_adc(r, &c, &mut delay, &loaded));
        observe(Step::AdcArmed, r);
    } else {
        // The link still comes up (on the HSI), to report the failure.
        r.rcc.ahb1enr().modify(|_, w| w.gpioaen().enabled());
        r.rcc.apb1enr().modify(|_, w| w.usart2en().enabled());
        r.gpioa
            .moder()
            .modify(|_, w| w.moder2().alternate().moder3().alternate());
        r.gpioa.afrl().modify(|_, w| w.afrl2().af7().afrl3().af7());
        sampling::link_rx_pull_up(r);
    }
    pull_up.elapsed_us = delay.us;
    out.fault_input_active = fault_input::read_and_arm(r, &c, &mut delay, pull_up);
    observe(Step::FaultInputRead, r);
    usart::setup(r, &c);
    observe(Step::LinkUp, r);
    out
}

/// Starts the sample clock if the bring-up allows it (returns whether it
/// did).
pub fn start_sampling(
    r: &Registers,
    p: &mut Prepared,
    observe: &mut impl FnMut(Step, &Registers),
) -> bool {
    if p.dma_setup != Some(true) {
        return false;
    }
    match p.adc.take() {
        Some(ready) => {
            sampling::start_sample_clock(r, ready);
            p.sampling = true;
            observe(Step::SampleClockStarted, r);
            true
        }
        None => false,
    }
}
