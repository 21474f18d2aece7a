//! STM32F405 driver-board firmware: two phase-locked DAC drives (DDS), force
//! sampling on the same timer, the friction estimate, and the postcard/COBS
//! link on USART2. All logic is `model_core::{device, server}` (tested on the
//! host); this file only wires it to the peripherals, at register level where
//! no HAL supports the configuration (DMA into the dual DAC register).
//!
//! Pins: PA4 = DAC1 (normal transducer), PA5 = DAC2 (tangential), PA0 = ADC1
//! IN0 (normal force), PA1 = ADC2 IN1 (tangential force), PA2/PA3 = USART2
//! TX/RX (AF7), PB0 = external fault input (active low, pull-up; EXTI0). Register facts cite RM0090 (STM32F405/407 reference manual).
//!
//! Data path, per sample tick (TIM2 update → TRGO, 500 kS/s):
//! * DAC: the trigger moves DHR → DOR on both channels and raises one DMA
//!   request; DMA1 Stream5/Channel7 writes the next packed word into DHR12RD
//!   (circular, double buffer). Half/full-transfer interrupts refill the half
//!   the DMA has just left with the DDS.
//! * ADC: ADC1+ADC2 in regular simultaneous mode, triggered by the same TRGO;
//!   DMA2 Stream0/Channel0 moves ADC_CDR (ADC2 << 16 | ADC1, DMA mode 2) into a
//!   buffer of the same length, whose halves go to the estimator with the drive
//!   phase of each sample.
//! * Closed loop (`model_core::control`, protocol `SetControl`): the device
//!   runs one update per finished estimate inside `adc_block` (the ADC
//!   interrupt; a few hundred instructions, no model call) and applies the
//!   command at the next DAC refill. The feedforward's model search runs in
//!   the main loop on a snapshot (`Server`), with interrupts enabled.
//! * Under QEMU (`--features qemu`) the DMA streams, DAC and analog world are
//!   missing: module `qemu` refills the DAC halves from the main loop on a
//!   SysTick tick and feeds the ADC intake from a simulated plant instead.
#![no_std]
#![no_main]

mod panic;
#[cfg(feature = "qemu")]
mod qemu;

use core::cell::RefCell;

use cortex_m::interrupt::Mutex;
use cortex_m_rt::entry;
use defmt_rtt as _;
use model_core::board::dma;
use model_core::board::link::{self, Core, LinkIo, RxQueue, TxRing, RX_CAPACITY, TX_CAPACITY};
use model_core::dds::SineTable;
use model_core::device::{faults, Contact, Device, DeviceConfig, DriveSetting};
use model_core::float::FastF32;
use model_core::protocol::{Info, PROTOCOL_VERSION};
use model_core::server::{DeviceAccess, Server};
use stm32f4::stm32f405::{self as pac, interrupt, Interrupt};

/// Samples per DMA half-buffer (model-core's `HALF_BUFFER`: 64, 128 µs at 500 kS/s).
const HALF: usize = model_core::device::HALF_BUFFER;
/// DDS/ADC sample rate: 12.5 samples per period at 40 kHz. The DDS refill costs
/// 97 instructions per sample once settled (125 while ramping; measured under
/// QEMU at `opt-level = "z"`, see `src/bin/predict_cost.rs`), i.e. ≈ 29 % of
/// the 168 MHz core here.
const FS_HZ: u32 = 500_000;
/// TIM2 kernel clock: APB1 = 42 MHz, ×2 for timers when APB1 is divided (RM0090 §6.2).
const TIMCLK_HZ: u32 = 84_000_000;
/// APB1 clock for the USART baud rate.
#[cfg(not(feature = "qemu"))]
const PCLK1_HZ: u32 = 42_000_000;
#[cfg(feature = "qemu")]
const PCLK1_HZ: u32 = 16_000_000;
const TABLE_N: usize = 1024;

static mut DAC_BUF: [u32; 2 * HALF] = [0; 2 * HALF];
/// DAC half-buffers refilled since power-up: the server's clock (one half =
/// `HALF/FS_HZ` = 128 µs) for the protocol's inter-byte timeout.
static HALVES: core::sync::atomic::AtomicU32 = core::sync::atomic::AtomicU32::new(0);

/// Microseconds since power-up (wrapping), at the resolution of one half-buffer.
fn now_us() -> u32 {
    HALVES
        .load(core::sync::atomic::Ordering::Relaxed)
        .wrapping_mul(HALF as u32 * 1_000_000 / FS_HZ)
}
/// Two 32-bit words per ADC tick (dual regular simultaneous, DMA mode 2,
/// a scan of two conversions per ADC): word 0 the forces (ADC1 IN0 f_z,
/// ADC2 IN1 f_x), word 1 the motion pickups (ADC1 IN6 = PA6 normal,
/// ADC2 IN7 = PA7 tangential).
static mut ADC_BUF: [u32; 4 * HALF] = [0; 4 * HALF];

type Dev = Device<'static, TABLE_N>;
static DEVICE: Mutex<RefCell<Option<Dev>>> = Mutex::new(RefCell::new(None));
/// Bytes received on USART2, handed from the interrupt to the main loop. A
/// byte that does not fit is counted in `Status::rx_overflows`.
static RX: Mutex<RefCell<RxQueue<RX_CAPACITY>>> = Mutex::new(RefCell::new(RxQueue::new()));
/// Frames to transmit on USART2, emptied by the transmit-empty interrupt (and
/// by [`tx_pump`] from the loop), so the loop never waits on the line.
static TX: Mutex<RefCell<TxRing<TX_CAPACITY>>> = Mutex::new(RefCell::new(TxRing::new()));

/// The device behind a critical section per call: requests run with
/// interrupts enabled, so the DMA refills are never held up by a long model
/// computation (the server computes predictions on a snapshot).
struct Shared;

impl DeviceAccess<TABLE_N> for Shared {
    fn with<R>(&mut self, f: impl FnOnce(&mut Device<'_, TABLE_N>) -> R) -> R {
        cortex_m::interrupt::free(|cs| match DEVICE.borrow(cs).borrow_mut().as_mut() {
            Some(d) => f(d),
            None => defmt::panic!("device not initialised"),
        })
    }
}

/// The link seen by the loop: each access in its own short critical section.
struct Usart2Link;

impl LinkIo for Usart2Link {
    fn pop_rx(&mut self) -> Option<u8> {
        cortex_m::interrupt::free(|cs| RX.borrow(cs).borrow_mut().pop())
    }

    fn tx_free(&mut self) -> usize {
        cortex_m::interrupt::free(|cs| TX.borrow(cs).borrow().free())
    }

    fn send(&mut self, frame: &[u8]) {
        let queued = cortex_m::interrupt::free(|cs| TX.borrow(cs).borrow_mut().push_frame(frame));
        if queued.is_err() {
            // Unreachable: `link::serve` checks the room before every call.
            defmt::error!("transmit ring full, {} bytes not sent", frame.len());
        }
        tx_pump();
    }
}

/// The Cortex-M4 for `link::sleep_unless`: PRIMASK and `WFI`.
///
/// Why `WFI` under PRIMASK and not `WFE`/`SEV`: the masked section makes the
/// check and the sleep one step without any extra state — an interrupt after
/// the check stays pending and `WFI` does not sleep on a pending interrupt,
/// whatever PRIMASK says (ARMv7-M ARM B1.5.19). `WFE` would need every
/// handler that produces work to `SEV` (or SCR.SEVONPEND), and its event
/// register is one more piece of state that any event sets, so the loop
/// would have to be proved against it as well. The price of the masked
/// section is a few cycles of added interrupt latency (the check reads two
/// queue lengths).
struct CortexM4;

impl Core for CortexM4 {
    fn masked<R>(&mut self, f: impl FnOnce(&mut Self) -> R) -> R {
        cortex_m::interrupt::free(|_| f(self))
    }

    fn wait_for_interrupt(&mut self) {
        cortex_m::asm::wfi();
    }
}

fn config() -> DeviceConfig {
    // The ADC converts on the trigger that moved DAC word k−1 to the output.
    let cfg = DeviceConfig::driver_board(1);
    debug_assert!(cfg.sample_rate_hz == FS_HZ as f64);
    cfg
}

fn info(cfg: &DeviceConfig) -> Info {
    Info::for_config(cfg, "STM32F405", [0, 1, 0])
}

#[entry]
fn main() -> ! {
    let dp = pac::Peripherals::take().unwrap_or_else(|| defmt::panic!("peripherals taken"));
    let mut cp =
        cortex_m::Peripherals::take().unwrap_or_else(|| defmt::panic!("core peripherals taken"));

    let watchdog_reset = dp.RCC.csr().read().bits() & (1 << 29) != 0; // IWDGRSTF (RM0090 §7.3.21)
    dp.RCC
        .csr()
        .modify(|r, w| unsafe { w.bits(r.bits() | (1 << 24)) }); // RMVF: clear reset flags

    clocks(&dp);

    // Clocks for GPIOA, DMA1, DMA2 (AHB1ENR bits 0, 21, 22), TIM2, USART2, DAC
    // (APB1ENR bits 0, 17, 29), ADC1, ADC2 (APB2ENR bits 8, 9).
    dp.RCC
        .ahb1enr()
        .modify(|r, w| unsafe { w.bits(r.bits() | 1 | (1 << 21) | (1 << 22)) });
    dp.RCC
        .apb1enr()
        .modify(|r, w| unsafe { w.bits(r.bits() | 1 | (1 << 17) | (1 << 29)) });
    dp.RCC
        .apb2enr()
        .modify(|r, w| unsafe { w.bits(r.bits() | (1 << 8) | (1 << 9)) });

    // PA0, PA1 (forces), PA4, PA5 (DAC), PA6, PA7 (motion pickups) analog
    // (MODER = 11); PA2, PA3 alternate function (10), AF7.
    dp.GPIOA.moder().modify(|r, w| unsafe {
        let m = r.bits() & !0xFFFF;
        w.bits(
            m | 0b11
                | (0b11 << 2)
                | (0b10 << 4)
                | (0b10 << 6)
                | (0b11 << 8)
                | (0b11 << 10)
                | (0b11 << 12)
                | (0b11 << 14),
        )
    });
    dp.GPIOA
        .afrl()
        .modify(|r, w| unsafe { w.bits((r.bits() & !(0xFF << 8)) | (7 << 8) | (7 << 12)) });

    // The device: table built once (FastF32, the solver's backend), then the logic of model-core.
    let table: &'static SineTable<TABLE_N> =
        cortex_m::singleton!(: SineTable<TABLE_N> = SineTable::build::<FastF32>())
            .unwrap_or_else(|| defmt::panic!("table"));
    let cfg = config();
    let contact = Contact {
        mu0: 0.3,
        kz: 1e7,
        kx: 1e7,
    };
    let mut dev =
        Device::new(cfg, table, contact).unwrap_or_else(|_| defmt::panic!("device config"));
    if watchdog_reset {
        defmt::warn!("reset by the independent watchdog");
        dev.fault(faults::WATCHDOG_RESET);
    }
    // The external fault input: an alarm already raised at power-up is
    // latched now (its edge came before the interrupt was armed).
    if fault_input(&dp) {
        defmt::warn!("external fault input active at power-up");
        dev.fault(faults::EXTERNAL);
    }
    // A safe default drive (stopped): 40 kHz, zero amplitudes, no preload.
    let _ = dev.set_drive(DriveSetting {
        freq_hz: 40_000.0,
        amp_z_m: 0.0,
        amp_x_m: 0.0,
        offset_z_m: 0.0,
        phase_rad: 0.0,
    });
    // Pre-fill both halves before the DMA starts (under QEMU through the
    // emulated analog side, which then knows what they drive).
    #[cfg(feature = "qemu")]
    let mut analog = qemu::Analog::new(cfg);
    // SAFETY: the DMA is not running yet; nothing else aliases the buffers.
    unsafe {
        let buf = &mut *core::ptr::addr_of_mut!(DAC_BUF);
        let (a, b) = buf.split_at_mut(HALF);
        #[cfg(not(feature = "qemu"))]
        {
            dev.fill_dac(0, a);
            dev.fill_dac(1, b);
        }
        #[cfg(feature = "qemu")]
        {
            analog.prefill(&mut dev, 0, a);
            analog.prefill(&mut dev, 1, b);
        }
    }
    let mut server = Server::new(info(&cfg));
    cortex_m::interrupt::free(|cs| DEVICE.borrow(cs).replace(Some(dev)));

    dac_dma(&dp);
    adc_dma(&dp);
    usart2(&dp);
    tim2(&dp);
    #[cfg(feature = "qemu")]
    qemu::tick(&mut cp.SYST);
    watchdog(&dp);

    // SAFETY: the handlers share state with the loop and each other only
    // behind critical sections (DEVICE, RX, TX) or atomics (HALVES); the DMA
    // buffers they touch are reached through raw pointers to the half the
    // DMA has left (DAC: the only reference to those words; ADC: volatile
    // reads after an acquire fence), never through a reference to a whole
    // buffer the DMA is using. Unmasking cannot break a critical section in
    // progress (there is none here).
    unsafe {
        cp.NVIC.set_priority(Interrupt::DMA1_STREAM5, 0x10);
        cp.NVIC.set_priority(Interrupt::DMA2_STREAM0, 0x20);
        cp.NVIC.set_priority(Interrupt::USART2, 0x30);
        pac::NVIC::unmask(Interrupt::DMA1_STREAM5);
        pac::NVIC::unmask(Interrupt::DMA2_STREAM0);
        pac::NVIC::unmask(Interrupt::USART2);
        #[cfg(not(feature = "qemu"))]
        {
            cp.NVIC.set_priority(Interrupt::EXTI0, 0x08);
            pac::NVIC::unmask(Interrupt::EXTI0);
        }
    }
    // A byte may have arrived before RXNEIE was set (it then raises no edge):
    // let the handler look once.
    pac::NVIC::pend(Interrupt::USART2);
    defmt::info!(
        "driver board up: {} Hz sample rate, protocol v{}",
        FS_HZ,
        PROTOCOL_VERSION
    );

    let mut io = Usart2Link;
    loop {
        // Feed the independent watchdog (KR = 0xAAAA, RM0090 §21.4.1).
        dp.IWDG.kr().write(|w| unsafe { w.bits(0xAAAA) });
        // Requests in, answers and telemetry into the transmit ring; never waits.
        link::serve(&mut server, &mut Shared, &mut io, now_us());
        // QEMU: one due DAC half through the emulated plant (module `qemu`).
        #[cfg(feature = "qemu")]
        analog.step();
        // The only wait of the loop: check and WFI with interrupts masked, so
        // a byte that lands after the check still wakes the core (the
        // USART2 handler runs right after the masked section). The
        // transmit-empty interrupt wakes it when the ring has room again.
        link::sleep_unless(&mut CortexM4, |_| {
            cortex_m::interrupt::free(|cs| {
                link::has_work(RX.borrow(cs).borrow().len(), TX.borrow(cs).borrow().free())
                    || analog_due()
            })
        });
    }
}

/// Whether emulated analog work waits (QEMU only; never on the board).
fn analog_due() -> bool {
    #[cfg(feature = "qemu")]
    return qemu::due();
    #[cfg(not(feature = "qemu"))]
    false
}

/// 168 MHz from an 8 MHz HSE: PLL M = 8, N = 336, P = 2, Q = 7; AHB/1,
/// APB1/4 (42 MHz), APB2/2 (84 MHz); flash 5 wait states (RM0090 §3.5.1, §6.3).
#[cfg(not(feature = "qemu"))]
fn clocks(dp: &pac::Peripherals) {
    let rcc = &dp.RCC;
    rcc.cr()
        .modify(|r, w| unsafe { w.bits(r.bits() | (1 << 16)) }); // HSEON
    while rcc.cr().read().bits() & (1 << 17) == 0 {} // HSERDY
    rcc.pllcfgr()
        .write(|w| unsafe { w.bits(8 | (336 << 6) | (1 << 22) | (7 << 24)) }); // M = 8, N = 336, P = 2 (PLLP = 00), PLLSRC = HSE, Q = 7
    rcc.cr()
        .modify(|r, w| unsafe { w.bits(r.bits() | (1 << 24)) }); // PLLON
    while rcc.cr().read().bits() & (1 << 25) == 0 {} // PLLRDY
    dp.FLASH
        .acr()
        .write(|w| unsafe { w.bits(5 | (1 << 8) | (1 << 9) | (1 << 10)) }); // LATENCY 5, PRFTEN, ICEN, DCEN
    rcc.cfgr()
        .write(|w| unsafe { w.bits((0b101 << 10) | (0b100 << 13) | 0b10) }); // PPRE1 /4, PPRE2 /2, SW = PLL
    while (rcc.cfgr().read().bits() >> 2) & 0b11 != 0b10 {} // SWS = PLL
}

/// QEMU: RCC is a stub whose ready bits never set; stay on the 16 MHz HSI.
#[cfg(feature = "qemu")]
fn clocks(_dp: &pac::Peripherals) {}

/// DAC1 both channels triggered by TIM2 TRGO, DMA1 Stream5 Channel7 writing
/// DHR12RD (0x4000_7420), 32-bit, circular, half/full-transfer interrupts.
fn dac_dma(dp: &pac::Peripherals) {
    let st = dp.DMA1.st(5);
    st.cr().write(|w| unsafe { w.bits(0) });
    while st.cr().read().bits() & 1 != 0 {}
    let dhr12rd = 0x4000_7400u32 + 0x20;
    st.par().write(|w| unsafe { w.bits(dhr12rd) });
    st.m0ar()
        .write(|w| unsafe { w.bits(core::ptr::addr_of!(DAC_BUF) as u32) });
    // Two words per tick (forces, pickups), two halves.
    st.ndtr().write(|w| unsafe { w.bits((4 * HALF) as u32) });
    // CHSEL = 7, PL = high, MSIZE = PSIZE = 32 bit, MINC, CIRC, DIR = memory→peripheral, TCIE, HTIE.
    st.cr().write(|w| unsafe {
        w.bits(
            (7 << 25)
                | (0b10 << 16)
                | (0b10 << 13)
                | (0b10 << 11)
                | (1 << 10)
                | (1 << 8)
                | (0b01 << 6)
                | (1 << 4)
                | (1 << 3),
        )
    });
    st.cr().modify(|r, w| unsafe { w.bits(r.bits() | 1) }); // EN
                                                            // DAC_CR: EN1, TEN1, TSEL1 = 100 (TIM2 TRGO), DMAEN1; EN2, TEN2, TSEL2 = 100.
                                                            // One request (channel 1) per trigger updates both channels via DHR12RD (RM0090 §14.3.7).
    dp.DAC.cr().write(|w| unsafe {
        w.bits(1 | (1 << 2) | (0b100 << 3) | (1 << 12) | (1 << 16) | (1 << 18) | (0b100 << 19))
    });
}

/// ADC1 (IN0, f_z) and ADC2 (IN1, f_x) regular simultaneous on TIM2 TRGO
/// (EXTSEL = 0110), DMA mode 2 via ADC_CDR (0x4001_2308) on DMA2 Stream0 Channel0.
fn adc_dma(dp: &pac::Peripherals) {
    let st = dp.DMA2.st(0);
    st.cr().write(|w| unsafe { w.bits(0) });
    while st.cr().read().bits() & 1 != 0 {}
    st.par().write(|w| unsafe { w.bits(0x4001_2308) });
    st.m0ar()
        .write(|w| unsafe { w.bits(core::ptr::addr_of!(ADC_BUF) as u32) });
    // Two words per tick (forces, pickups), two halves.
    st.ndtr().write(|w| unsafe { w.bits((4 * HALF) as u32) });
    // CHSEL = 0, PL = very high, 32 bit both sides, MINC, CIRC, DIR = peripheral→memory, TCIE, HTIE.
    st.cr().write(|w| unsafe {
        w.bits(
            (0b11 << 16) | (0b10 << 13) | (0b10 << 11) | (1 << 10) | (1 << 8) | (1 << 4) | (1 << 3),
        )
    });
    st.cr().modify(|r, w| unsafe { w.bits(r.bits() | 1) });
    // Common: ADCPRE = /4 (21 MHz), DMA mode 2, DDS, MULTI = 00110 (regular simultaneous).
    dp.ADC_COMMON
        .ccr()
        .write(|w| unsafe { w.bits((0b01 << 16) | (0b10 << 14) | (1 << 13) | 0b00110) });
    // A scan of two conversions each (SQR1 L = 1): ADC1 SQ1 = IN0 (f_z),
    // SQ2 = IN6 (PA6, normal pickup); ADC2 SQ1 = IN1 (f_x), SQ2 = IN7 (PA7,
    // tangential pickup); 3-cycle sampling: 15 ADC clocks = 0.71 µs per
    // conversion, 1.43 µs per tick of 2 µs. DMA mode 2 requests one word per
    // pair of simultaneous conversions (RM0090 §13.9.3): two per tick.
    dp.ADC1.sqr1().write(|w| unsafe { w.bits(1 << 20) });
    dp.ADC2.sqr1().write(|w| unsafe { w.bits(1 << 20) });
    dp.ADC1.sqr3().write(|w| unsafe { w.bits(6 << 5) });
    dp.ADC2.sqr3().write(|w| unsafe { w.bits(1 | (7 << 5)) });
    dp.ADC1.smpr2().write(|w| unsafe { w.bits(0) });
    dp.ADC2.smpr2().write(|w| unsafe { w.bits(0) });
    // SCAN (CR1 bit 8) on both.
    dp.ADC1.cr1().write(|w| unsafe { w.bits(1 << 8) });
    dp.ADC2.cr1().write(|w| unsafe { w.bits(1 << 8) });
    dp.ADC2.cr2().write(|w| unsafe { w.bits(1) }); // ADON (slave)
                                                   // Master: ADON, EXTEN = rising, EXTSEL = TIM2 TRGO.
    dp.ADC1
        .cr2()
        .write(|w| unsafe { w.bits(1 | (0b0110 << 24) | (0b01 << 28)) });
}

/// The external fault input on PB0 (active low, pull-up: an amplifier's
/// alarm output, open drain): EXTI line 0 on the falling edge (RM0090 §9.2.3
/// SYSCFG_EXTICR1, §12.3 EXTI). Returns whether the input is already active.
#[cfg(not(feature = "qemu"))]
fn fault_input(dp: &pac::Peripherals) -> bool {
    // Clocks: GPIOB (AHB1ENR bit 1), SYSCFG (APB2ENR bit 14).
    dp.RCC
        .ahb1enr()
        .modify(|r, w| unsafe { w.bits(r.bits() | (1 << 1)) });
    dp.RCC
        .apb2enr()
        .modify(|r, w| unsafe { w.bits(r.bits() | (1 << 14)) });
    // PB0: input (MODER = 00), pull-up (PUPDR = 01).
    dp.GPIOB
        .moder()
        .modify(|r, w| unsafe { w.bits(r.bits() & !0b11) });
    dp.GPIOB
        .pupdr()
        .modify(|r, w| unsafe { w.bits((r.bits() & !0b11) | 0b01) });
    // EXTI0 ← port B (EXTICR1[3:0] = 0001), falling edge, unmasked.
    dp.SYSCFG
        .exticr1()
        .modify(|r, w| unsafe { w.bits((r.bits() & !0xF) | 0b0001) });
    dp.EXTI
        .ftsr()
        .modify(|r, w| unsafe { w.bits(r.bits() | 1) });
    dp.EXTI.pr().write(|w| unsafe { w.bits(1) });
    dp.EXTI.imr().modify(|r, w| unsafe { w.bits(r.bits() | 1) });
    // The pull-up needs a few cycles before the pin reads high.
    cortex_m::asm::delay(100);
    dp.GPIOB.idr().read().bits() & 1 == 0
}

/// QEMU: the GPIO is a stub (it reads 0): no external input.
#[cfg(feature = "qemu")]
fn fault_input(_dp: &pac::Peripherals) -> bool {
    false
}

/// TIM2: update event every TIMCLK/FS ticks, TRGO on update (MMS = 010).
fn tim2(dp: &pac::Peripherals) {
    let t = &dp.TIM2;
    t.psc().write(|w| unsafe { w.bits(0) });
    t.arr().write(|w| unsafe { w.bits(TIMCLK_HZ / FS_HZ - 1) });
    t.cr2().write(|w| unsafe { w.bits(0b010 << 4) });
    t.egr().write(|w| unsafe { w.bits(1) }); // UG: load PSC/ARR
    t.cr1().write(|w| unsafe { w.bits(1) }); // CEN
}

/// USART2 115 200 8N1, RXNE interrupt; TXEIE is set while the transmit
/// ring holds bytes (RM0090 §30.6).
fn usart2(dp: &pac::Peripherals) {
    let u = &dp.USART2;
    u.brr()
        .write(|w| unsafe { w.bits(((PCLK1_HZ + 57_600) / 115_200) as u16) });
    u.cr1()
        .write(|w| unsafe { w.bits(CR1_UE | CR1_RXNEIE | CR1_TE | CR1_RE) });
}

/// USART_CR1 bits (RM0090 §30.6.4).
const CR1_UE: u16 = 1 << 13;
const CR1_TXEIE: u16 = 1 << 7;
const CR1_RXNEIE: u16 = 1 << 5;
const CR1_TE: u16 = 1 << 3;
const CR1_RE: u16 = 1 << 2;
/// USART_SR bits (RM0090 §30.6.1).
const SR_TXE: u16 = 1 << 7;
const SR_RXNE: u16 = 1 << 5;
const SR_ORE: u16 = 1 << 3;

/// Independent watchdog ≈ 1 s: prescaler /8, reload 4095 at 32 kHz LSI.
fn watchdog(dp: &pac::Peripherals) {
    let i = &dp.IWDG;
    i.kr().write(|w| unsafe { w.bits(0x5555) });
    i.pr().write(|w| unsafe { w.bits(1) });
    i.rlr().write(|w| unsafe { w.bits(0xFFF) });
    i.kr().write(|w| unsafe { w.bits(0xCCCC) });
}

/// Moves bytes from the transmit ring into USART2 while its data register is
/// empty, without waiting: on the board at most two bytes (data register and
/// shift register), under QEMU (synchronous transmit) the whole ring. Leaves
/// TXEIE set while bytes remain, so the interrupt continues. Called from the
/// USART2 handler and from the loop after queuing a frame (QEMU 7.2's USART
/// raises no transmit-empty interrupt; there the loop's call does it all).
fn tx_pump() {
    // SAFETY: register access only, inside the critical section.
    let u = unsafe { &*pac::USART2::ptr() };
    cortex_m::interrupt::free(|cs| {
        let mut tx = TX.borrow(cs).borrow_mut();
        while u.sr().read().bits() & SR_TXE != 0 {
            match tx.pop() {
                Some(b) => {
                    u.dr().write(|w| unsafe { w.bits(u16::from(b)) });
                }
                None => break,
            }
        }
        let cr1 = u.cr1().read().bits();
        let cr1 = if tx.is_empty() {
            cr1 & !CR1_TXEIE
        } else {
            cr1 | CR1_TXEIE
        };
        u.cr1().write(|w| unsafe { w.bits(cr1) });
    });
}

#[interrupt]
fn DMA1_STREAM5() {
    // SAFETY: register access only; HISR/HIFCR and NDTR of DMA1 stream 5.
    let dma = unsafe { &*pac::DMA1::ptr() };
    let isr = dma.hisr().read().bits();
    let ndtr = dma.st(5).ndtr().read().bits();
    let (ht, tc) = (isr & (1 << 10) != 0, isr & (1 << 11) != 0); // HTIF5, TCIF5
    dma.hifcr()
        .write(|w| unsafe { w.bits((1 << 10) | (1 << 11) | (1 << 9) | (1 << 8) | (1 << 6)) });
    // Half-buffers of 2·HALF words (forces and pickups of HALF ticks).
    let Some(ev) = dma::half_event(ht, tc, ndtr, 2 * HALF as u32) else {
        return;
    };
    HALVES.fetch_add(1, core::sync::atomic::Ordering::Relaxed);
    cortex_m::interrupt::free(|cs| {
        if let Some(dev) = DEVICE.borrow(cs).borrow_mut().as_mut() {
            // SAFETY: `ev.half` is the half the DMA has left (`half_event`:
            // from NDTR when the handler is late); the DMA reads only the
            // other half until this handler's next run, 128 µs later, and no
            // other code touches DAC_BUF after `main`'s pre-fill. So this is
            // the only reference to these words, and nothing reads them
            // while it lives. The release fence orders the refill before the
            // DMA's later reads as seen by the compiler.
            let buf = unsafe {
                let first = core::ptr::addr_of_mut!(DAC_BUF).cast::<u32>();
                core::slice::from_raw_parts_mut(first.add(ev.half * HALF), HALF)
            };
            dev.dac_half_done(ev, buf);
            core::sync::atomic::compiler_fence(core::sync::atomic::Ordering::Release);
        }
    });
}

#[interrupt]
fn DMA2_STREAM0() {
    // SAFETY: register access only; LISR/LIFCR and NDTR of DMA2 stream 0.
    let dma = unsafe { &*pac::DMA2::ptr() };
    let isr = dma.lisr().read().bits();
    let ndtr = dma.st(0).ndtr().read().bits();
    let (ht, tc) = (isr & (1 << 4) != 0, isr & (1 << 5) != 0); // HTIF0, TCIF0
    dma.lifcr().write(|w| unsafe { w.bits(0b11_1101) });
    // Half-buffers of 2·HALF words (forces and pickups of HALF ticks).
    let Some(ev) = dma::half_event(ht, tc, ndtr, 2 * HALF as u32) else {
        return;
    };
    // The DMA wrote the finished half before raising its flag; the acquire
    // fence keeps the reads below after the flag read.
    core::sync::atomic::fence(core::sync::atomic::Ordering::Acquire);
    let mut samples = [(0u16, 0u16); HALF];
    let mut pickups = [(0u16, 0u16); HALF];
    // SAFETY: a raw pointer to the finished half only (no reference to the
    // buffer the DMA writes into); each word read with `read_volatile`, as
    // memory another bus master owns. The DMA writes the other half for the
    // next 128 µs; the copy takes well under 1 µs.
    let first = unsafe {
        core::ptr::addr_of!(ADC_BUF)
            .cast::<u32>()
            .add(ev.half * 2 * HALF)
    };
    for (k, (s, p)) in samples.iter_mut().zip(pickups.iter_mut()).enumerate() {
        let (w0, w1) = unsafe {
            (
                first.add(2 * k).read_volatile(),
                first.add(2 * k + 1).read_volatile(),
            )
        };
        // CDR: ADC1 in bits 0–15, ADC2 in bits 16–31. Word 0: f_z, f_x;
        // word 1: the normal pickup (IN6), the tangential one (IN7).
        *s = ((w0 >> 16) as u16, (w0 & 0xFFFF) as u16);
        *p = ((w1 & 0xFFFF) as u16, (w1 >> 16) as u16);
    }
    cortex_m::interrupt::free(|cs| {
        if let Some(dev) = DEVICE.borrow(cs).borrow_mut().as_mut() {
            // A late handler (both flags) is the fault ADC_OVERRUN, through
            // the device's one fault path.
            dev.adc_half_done_with_pickups(ev, &samples, &pickups);
        }
    });
}

/// The external fault input (PB0, active low: an amplifier alarm): the
/// falling edge latches `faults::EXTERNAL` through the device's one fault
/// path. Not wired under QEMU (its GPIO is a stub that reads 0).
#[cfg(not(feature = "qemu"))]
#[interrupt]
fn EXTI0() {
    // SAFETY: register access only; EXTI_PR bit 0 is cleared by writing 1.
    let exti = unsafe { &*pac::EXTI::ptr() };
    exti.pr().write(|w| unsafe { w.bits(1) });
    cortex_m::interrupt::free(|cs| {
        if let Some(dev) = DEVICE.borrow(cs).borrow_mut().as_mut() {
            dev.fault(faults::EXTERNAL);
        }
    });
}

#[interrupt]
fn USART2() {
    // SAFETY: register access only.
    let u = unsafe { &*pac::USART2::ptr() };
    let sr = u.sr().read().bits();
    if sr & (SR_RXNE | SR_ORE) != 0 {
        // Reading DR clears RXNE (and ORE after the SR read).
        let b = u.dr().read().bits() as u8;
        // ORE: a byte was lost in the USART itself (the handler was late).
        let lost = u32::from(sr & SR_ORE != 0)
            + cortex_m::interrupt::free(|cs| {
                u32::from(RX.borrow(cs).borrow_mut().push(b).is_err())
            });
        if lost > 0 {
            cortex_m::interrupt::free(|cs| {
                if let Some(dev) = DEVICE.borrow(cs).borrow_mut().as_mut() {
                    dev.count_rx_overflow(lost);
                }
            });
        }
    }
    tx_pump();
}
