//! STM32F405 driver-board firmware: two phase-locked DAC drives (DDS), force
//! and motion sampling on the same timer, the friction estimate, and the
//! postcard/COBS link on USART2. All logic is `model_core::{device, server}`
//! (tested on the host); every register access is the `hardware` crate's
//! (typed, tested natively against a register file). This file wires them:
//! the statics the handlers share, the handlers, and the main loop.
//!
//! Pins: PA4 = DAC1 (normal transducer), PA5 = DAC2 (tangential), PA0 = ADC1
//! IN0 (normal force), PA1 = ADC2 IN1 (tangential force), PA6/PA7 the motion
//! pickups, PA2/PA3 = USART2 TX/RX (AF7), PB0 = external fault input (active
//! low, pull-up; EXTI0). Bring-up and what to see at first flash:
//! `docs/guide/bringup.md`.
//!
//! **Contexts** (levels of `hardware::nvic`, more urgent first):
//! * level 0, `EXTI0` — the fault input: raises a pending fault bit;
//! * level 1, `USART2`, `TIM6_DAC` (DAC underrun), `ADC` (overrun) — bytes
//!   into the receive ring, out of the transmit ring; stall flags;
//! * level 2, `DMA1_STREAM5` (DAC refill) and `DMA2_STREAM0` (ADC block) —
//!   the DSP: they own the device under its lock (ceiling 2) and fold the
//!   pending faults into it through its one fault path;
//! * thread — the main loop: the link's requests (each a short lock of the
//!   device; the model's scenes and plans are formed with the device
//!   released), the watchdog, and under QEMU the emulated analog side.
//!
//! No lock masks all interrupts, and none masks a more urgent level than
//! the data it guards needs (`lock.rs`).
//!
//! The DSP handlers time their work (module `cycles`: the DWT cycle
//! counter; under QEMU SysTick, calibrated) and the device reports it as
//! `Status.cpu_load_pct` (protocol v8).
//!
//! Under QEMU (`--features qemu`) the DMA streams, DAC, RCC and analog
//! world are missing: the clocks stay on the 16 MHz HSI, and module `qemu`
//! refills the DAC halves from the main loop on a SysTick tick and feeds the
//! ADC intake from a simulated plant instead.
#![no_std]
#![no_main]

mod cycles;
mod lock;
mod panic;
#[cfg(feature = "qemu")]
mod qemu;
#[cfg(feature = "qemu")]
mod systick;

use core::sync::atomic::{AtomicBool, AtomicU32, Ordering};

use board::dds::SineTable;
use board::device::{faults, Contact, Device, DeviceConfig, DriveSetting};
use board::link::{self, Core, LinkIo, RxQueue, TxRing, RX_CAPACITY, TX_CAPACITY};
use board::protocol::{Info, SelfTest, PROTOCOL_VERSION};
use board::server::{DeviceAccess, Server};
use cortex_m_rt::entry;
use defmt_rtt as _;
use hardware::bring_up::{self, Buffers};
use hardware::buffers::{DmaBuffer, ADC_WORDS, DAC_WORDS, HALF};
use hardware::streams::StreamEvent;
use hardware::{nvic, Registers};
use lock::Shared;
use model_core::float::FastF32;
use stm32f4::stm32f405::{self as pac, interrupt, Interrupt};

/// DDS/ADC sample rate (`hardware::sampling::FS_HZ`): 12.5 samples per
/// period at 40 kHz.
const FS_HZ: u32 = hardware::sampling::FS_HZ;
const TABLE_N: usize = 1024;

/// The DAC's circular buffer: two halves of `HALF` packed DHR12RD words.
/// Its length is the DAC stream's NDTR (`hardware::buffers`).
static mut DAC_BUF: [u32; DAC_WORDS] = [0; DAC_WORDS];
/// The ADC's circular buffer: two CDR words per tick (word 0 the forces,
/// ADC1 IN0 f_z and ADC2 IN1 f_x; word 1 the pickups, IN6 and IN7), two
/// halves of `HALF` ticks.
static mut ADC_BUF: [u32; ADC_WORDS] = [0; ADC_WORDS];

/// DAC half-buffers handed over since power-up: the server's clock (one
/// half = `HALF/FS_HZ` = 128 µs) and the watchdog's sign of life.
static HALVES: AtomicU32 = AtomicU32::new(0);
/// ADC blocks handed over since power-up (the other sign of life).
static ADC_BLOCKS: AtomicU32 = AtomicU32::new(0);
/// Fault bits raised by contexts that do not own the device (the fault
/// input, the stall handlers), folded into it by the next device lock.
static PENDING_FAULTS: AtomicU32 = AtomicU32::new(0);
/// Received bytes lost (USART overrun or a full ring), folded likewise.
static RX_LOST: AtomicU32 = AtomicU32::new(0);
/// The DAC word of zero displacement on both channels (the safe state of a
/// stopped DAC stream).
static REST_WORD: AtomicU32 = AtomicU32::new(0);
/// Set when the self-test failed: the `self_test` fault is latched again
/// whenever it was reset.
static SELF_TEST_FAILED: AtomicU32 = AtomicU32::new(0);
/// Set when a stream's stop was handled (a fault latched, the outputs held
/// at rest): the watchdog is then fed without stream progress, so that the
/// latched cause stays readable instead of being lost to a reset.
static HELD: AtomicBool = AtomicBool::new(false);

/// Microseconds since power-up (wrapping), at the resolution of one half-buffer.
fn now_us() -> u32 {
    HALVES
        .load(Ordering::Relaxed)
        .wrapping_mul(HALF as u32 * 1_000_000 / FS_HZ)
}

type Dev = Device<'static, TABLE_N>;
/// The device: the DSP handlers (level 2) and the main loop.
static DEVICE: Shared<Option<Dev>, { nvic::DSP }> = Shared::new(None);
/// Bytes received on USART2 (level 1) for the main loop.
static RX: Shared<RxQueue<RX_CAPACITY>, { nvic::LINK }> = Shared::new(RxQueue::new());
/// Frames to transmit, emptied by USART2 (level 1) and the main loop.
static TX: Shared<TxRing<TX_CAPACITY>, { nvic::LINK }> = Shared::new(TxRing::new());

/// The chip's registers. The firmware owns the peripherals (it took
/// `pac::Peripherals` in `main`); handlers touch only their own
/// peripheral's registers.
fn regs() -> Registers<'static> {
    // SAFETY: see above.
    unsafe { Registers::chip() }
}

/// Runs `f` on the device, first folding in what other contexts raised.
fn with_device<R>(f: impl FnOnce(&mut Dev) -> R) -> R {
    DEVICE.lock(|d| match d.as_mut() {
        Some(dev) => {
            fold_pending(dev);
            f(dev)
        }
        None => defmt::panic!("device not initialised"),
    })
}

/// Pending faults and lost bytes into the device (its one fault path).
fn fold_pending(dev: &mut Dev) {
    let f = PENDING_FAULTS.swap(0, Ordering::Relaxed);
    if f != 0 {
        dev.fault(f);
    }
    // Re-latched only when it was reset (a fault enters the safe state anew).
    let st = SELF_TEST_FAILED.load(Ordering::Relaxed);
    if st != 0 && dev.faults() & st == 0 {
        dev.fault(st);
    }
    let lost = RX_LOST.swap(0, Ordering::Relaxed);
    if lost != 0 {
        dev.count_rx_overflow(lost);
    }
}

/// The device for the server: one short lock per call (the server forms
/// scenes and plans with the device released).
struct Locked;

impl DeviceAccess<TABLE_N> for Locked {
    fn with<R>(&mut self, f: impl FnOnce(&mut Device<'_, TABLE_N>) -> R) -> R {
        with_device(|d| f(d))
    }
}

/// The link seen by the loop: each access a short lock at the link's level.
struct Usart2Link;

impl LinkIo for Usart2Link {
    fn pop_rx(&mut self) -> Option<u8> {
        RX.lock(|q| q.pop())
    }

    fn tx_free(&mut self) -> usize {
        TX.lock(|t| t.free())
    }

    fn send(&mut self, frame: &[u8]) {
        if TX.lock(|t| t.push_frame(frame)).is_err() {
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
/// whatever PRIMASK says (ARMv7-M ARM B1.5.19). The masked section is the
/// check alone (two queue lengths): a few cycles of added latency.
struct CortexM4;

impl Core for CortexM4 {
    fn masked<R>(&mut self, f: impl FnOnce(&mut Self) -> R) -> R {
        cortex_m::interrupt::free(|_| f(self))
    }

    fn wait_for_interrupt(&mut self) {
        // Three NOPs after WFI: errata ES0182 §2.1.3 (DBG_SLEEP is set).
        // SAFETY: WFI and NOPs touch no memory.
        unsafe { core::arch::asm!("wfi", "nop", "nop", "nop", options(nomem, nostack)) };
    }
}

/// Busy waits for the bring-up, at the clock in force.
struct BusyWait;

impl hardware::Delay for BusyWait {
    fn wait_us(&mut self, us: u32, sysclk_hz: u32) {
        cortex_m::asm::delay(us.saturating_mul(sysclk_hz / 1_000_000));
    }
}

fn config() -> DeviceConfig {
    // The ADC converts on the trigger that moved DAC word k−1 to the output.
    let cfg = DeviceConfig::driver_board(1);
    debug_assert!(cfg.sample_rate_hz == FS_HZ as f64);
    cfg
}

/// The packed DHR12RD word of zero displacement.
fn rest_word(cfg: &DeviceConfig) -> u32 {
    let code = |c: f32| (c + 0.5) as u32 & 0xFFF;
    code(cfg.dac_z.zero_code) | (code(cfg.dac_x.zero_code) << 16)
}

#[entry]
fn main() -> ! {
    let _dp = pac::Peripherals::take().unwrap_or_else(|| defmt::panic!("peripherals taken"));
    let mut cp =
        cortex_m::Peripherals::take().unwrap_or_else(|| defmt::panic!("core peripherals taken"));
    let r = regs();

    // The device: table built once (FastF32, the solver's backend), then the logic of model-core.
    let table: &'static SineTable<TABLE_N> =
        cortex_m::singleton!(: SineTable<TABLE_N> = SineTable::build::<FastF32>())
            .unwrap_or_else(|| defmt::panic!("table"));
    let cfg = config();
    REST_WORD.store(rest_word(&cfg), Ordering::Relaxed);
    let contact = Contact {
        mu0: 0.3,
        kz: 1e7,
        kx: 1e7,
    };
    let mut dev =
        Device::new(cfg, table, contact).unwrap_or_else(|_| defmt::panic!("device config"));
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
    let dac_preload = unsafe {
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
        // The word before word 0 in the circular order: DHR12RD's preload.
        buf[DAC_WORDS - 1]
    };
    let bufs = Buffers {
        dac: DmaBuffer::of_ptr(core::ptr::addr_of!(DAC_BUF)),
        adc: DmaBuffer::of_ptr(core::ptr::addr_of!(ADC_BUF)),
        dac_preload,
    };

    let mut prepared = bring_up_or_qemu(&r, &bufs);
    if prepared.watchdog_reset {
        defmt::warn!("reset by the independent watchdog");
        dev.fault(faults::WATCHDOG_RESET);
    }
    // An alarm already raised at power-up is latched now (its edge came
    // before the interrupt was armed).
    if prepared.fault_input_active {
        defmt::warn!("external fault input active at power-up");
        dev.fault(faults::EXTERNAL);
    }
    DEVICE.lock(|d| *d = Some(dev));

    // SAFETY: the handlers share state with the loop only through `Shared`
    // locks and atomics; the DMA buffers they touch are reached through raw
    // pointers to the half the DMA has left.
    unsafe {
        for (i, level) in nvic::PRIORITIES {
            cp.NVIC.set_priority(i, nvic::byte(level));
            // Under QEMU the fault input is not wired (its GPIO is a stub).
            if cfg!(feature = "qemu") && i == Interrupt::EXTI0 {
                continue;
            }
            pac::NVIC::unmask(i);
        }
    }
    // A byte may have arrived before RXNEIE was set (it then raises no edge):
    // let the handler look once.
    pac::NVIC::pend(Interrupt::USART2);

    // The DSP time count (`Status.cpu_load_pct`): on the chip before the
    // streams start; under QEMU once SysTick runs (its calibration needs it).
    #[cfg(not(feature = "qemu"))]
    cycles::start(&mut cp, prepared.clocks().sysclk_hz);
    let report = start_and_test(&r, &mut prepared, &mut cp);
    #[cfg(feature = "qemu")]
    cycles::start(&mut cp, qemu::QEMU_SYSCLK_HZ);
    if report.ran != 0 && report.failed != 0 {
        defmt::error!("self-test failed: {=u16:#x}", report.failed);
        SELF_TEST_FAILED.store(faults::SELF_TEST, Ordering::Relaxed);
        if prepared.sampling {
            // The streams started but did not deliver: stop them, hold.
            hardware::sampling::stop(&r, REST_WORD.load(Ordering::Relaxed));
            HELD.store(true, Ordering::Relaxed);
        }
    }
    let mut server =
        Server::new(Info::for_config(&cfg, "STM32F405", [0, 2, 0]).with_self_test(report));
    defmt::info!(
        "driver board up: {} Hz sample rate, protocol v{}",
        FS_HZ,
        PROTOCOL_VERSION
    );

    let mut io = Usart2Link;
    let mut live = hardware::watchdog::Liveness::default();
    loop {
        // Feed the watchdog only while both streams move (under QEMU, whose
        // IWDG is not emulated, device time is the sign of life).
        let (dac, adc) = (
            HALVES.load(Ordering::Relaxed),
            ADC_BLOCKS.load(Ordering::Relaxed),
        );
        #[cfg(feature = "qemu")]
        let adc = adc.max(dac);
        // A board that never started its streams (a failed self-test), or
        // whose stream stop was handled (fault latched, outputs held), has
        // nothing to watch: it is fed, and stays in its safe state with the
        // cause readable. An unexplained stall stops the feeding: a reset.
        if live.check(dac, adc) || !prepared.sampling || HELD.load(Ordering::Relaxed) {
            hardware::watchdog::feed(&r);
        }
        // Requests in, answers and telemetry into the transmit ring; never waits.
        link::serve(&mut server, &mut Locked, &mut io, now_us());
        if PENDING_FAULTS.load(Ordering::Relaxed) != 0 || RX_LOST.load(Ordering::Relaxed) != 0 {
            with_device(|_| ());
        }
        // QEMU: one due DAC half through the emulated plant (module `qemu`).
        #[cfg(feature = "qemu")]
        analog.step();
        // The only wait of the loop: check and WFI with interrupts masked, so
        // a byte that lands after the check still wakes the core.
        link::sleep_unless(&mut CortexM4, |_| {
            link::has_work(RX.lock(|q| q.len()), TX.lock(|t| t.free())) || analog_due()
        });
    }
}

/// The bring-up (`hardware::bring_up`); under QEMU, whose RCC, DMA, DAC and
/// TIM11 are stubs, only the watchdog and the link on the HSI.
#[cfg(not(feature = "qemu"))]
fn bring_up_or_qemu(r: &Registers, bufs: &Buffers) -> bring_up::Prepared {
    let p = bring_up::prepare(
        r,
        bufs,
        &mut BusyWait,
        &mut |_: bring_up::Step, _: &Registers| {},
    );
    defmt::info!("clocks: {}", p.clock);
    p
}

#[cfg(feature = "qemu")]
fn bring_up_or_qemu(r: &Registers, _bufs: &Buffers) -> bring_up::Prepared {
    let _ = BusyWait;
    hardware::watchdog::start(r);
    hardware::usart::setup(r, &hardware::clocks::Clocks::HSI);
    bring_up::Prepared::without_hardware()
}

/// Starts the sample clock and checks that both streams deliver (the
/// self-test's last check); under QEMU starts the emulated half-buffer tick.
#[cfg(not(feature = "qemu"))]
fn start_and_test(
    r: &Registers,
    p: &mut bring_up::Prepared,
    _cp: &mut cortex_m::Peripherals,
) -> SelfTest {
    let started = bring_up::start_sampling(r, p, &mut |_: bring_up::Step, _: &Registers| {});
    let first_halves = started.then(|| {
        let clocks = p.clocks();
        let _ = hardware::wait_until(
            &mut BusyWait,
            clocks.sysclk_hz,
            10,
            hardware::self_test::FIRST_BLOCKS_US,
            || {
                HALVES.load(Ordering::Relaxed) >= hardware::self_test::FIRST_HALVES
                    && ADC_BLOCKS.load(Ordering::Relaxed) >= hardware::self_test::FIRST_HALVES
            },
        );
        (
            HALVES.load(Ordering::Relaxed),
            ADC_BLOCKS.load(Ordering::Relaxed),
        )
    });
    hardware::self_test::report(&hardware::self_test::Findings {
        clock: p.clock,
        dma_setup: p.dma_setup,
        first_halves,
    })
}

#[cfg(feature = "qemu")]
fn start_and_test(
    _r: &Registers,
    _p: &mut bring_up::Prepared,
    cp: &mut cortex_m::Peripherals,
) -> SelfTest {
    qemu::tick(&mut cp.SYST);
    SelfTest::NOT_RUN
}

/// Whether emulated analog work waits (QEMU only; never on the board).
fn analog_due() -> bool {
    #[cfg(feature = "qemu")]
    return qemu::due();
    #[cfg(not(feature = "qemu"))]
    false
}

/// Moves bytes from the transmit ring into USART2 while its data register is
/// empty, without waiting: on the board at most two bytes (data register and
/// shift register), under QEMU (synchronous transmit) the whole ring. Leaves
/// TXEIE set while bytes remain, so the interrupt continues. Called from the
/// USART2 handler and from the loop after queuing a frame (QEMU 7.2's USART
/// raises no transmit-empty interrupt; there the loop's call does it all).
fn tx_pump() {
    let r = regs();
    TX.lock(|tx| {
        while hardware::usart::tx_empty(&r) {
            match tx.pop() {
                Some(b) => hardware::usart::tx_write(&r, b),
                None => break,
            }
        }
        hardware::usart::tx_interrupt(&r, !tx.is_empty());
    });
}

#[interrupt]
fn DMA1_STREAM5() {
    let t0 = cycles::now();
    let r = regs();
    let flags = hardware::streams::take_dac_flags(&r);
    let buf = DmaBuffer::of_ptr(core::ptr::addr_of!(DAC_BUF));
    match flags.event(&buf) {
        StreamEvent::Half(ev) => {
            HALVES.fetch_add(1, Ordering::Relaxed);
            // SAFETY: `ev.half` is the half the DMA has left (`half_event`:
            // from NDTR when the handler is late); the DMA reads only the
            // other half until this handler's next run, 128 µs later, and no
            // other code touches DAC_BUF after `main`'s pre-fill. So this is
            // the only reference to these words. The release fence orders
            // the refill before the DMA's later reads as seen by the compiler.
            let half = unsafe {
                let first = core::ptr::addr_of_mut!(DAC_BUF).cast::<u32>();
                core::slice::from_raw_parts_mut(first.add(ev.half * HALF), HALF)
            };
            with_device(|dev| dev.dac_half_done(ev, half));
            core::sync::atomic::compiler_fence(Ordering::Release);
            cycles::fill_done(cycles::since(t0));
        }
        StreamEvent::Stopped => {
            // The stream disabled itself: hold the outputs at rest, latch.
            hardware::sampling::hold_dac(&r, REST_WORD.load(Ordering::Relaxed));
            HELD.store(true, Ordering::Relaxed);
            with_device(|dev| dev.fault(faults::DAC_UNDERRUN));
        }
        StreamEvent::None => {}
    }
}

#[interrupt]
fn DMA2_STREAM0() {
    let t0 = cycles::now();
    let r = regs();
    let flags = hardware::streams::take_adc_flags(&r);
    let buf = DmaBuffer::of_ptr(core::ptr::addr_of!(ADC_BUF));
    let ev = match flags.event(&buf) {
        StreamEvent::Half(ev) => ev,
        StreamEvent::Stopped => {
            // The DDS ramps the drive down on the latched fault; the DAC's
            // stream goes on, the ADC's does not: held.
            HELD.store(true, Ordering::Relaxed);
            with_device(|dev| dev.fault(faults::ADC_OVERRUN));
            return;
        }
        StreamEvent::None => return,
    };
    ADC_BLOCKS.fetch_add(1, Ordering::Relaxed);
    // The DMA wrote the finished half before raising its flag; the acquire
    // fence keeps the reads below after the flag read.
    core::sync::atomic::fence(Ordering::Acquire);
    let mut samples = [(0u16, 0u16); HALF];
    let mut pickups = [(0u16, 0u16); HALF];
    let words = hardware::buffers::ADC_WORDS_PER_TICK;
    // SAFETY: a raw pointer to the finished half only (no reference to the
    // buffer the DMA writes into); each word read with `read_volatile`, as
    // memory another bus master owns. The DMA writes the other half for the
    // next 128 µs; the copy takes well under 1 µs.
    let first = unsafe {
        core::ptr::addr_of!(ADC_BUF)
            .cast::<u32>()
            .add(ev.half * words * HALF)
    };
    for (k, (s, p)) in samples.iter_mut().zip(pickups.iter_mut()).enumerate() {
        let (w0, w1) = unsafe {
            (
                first.add(words * k).read_volatile(),
                first.add(words * k + 1).read_volatile(),
            )
        };
        // CDR: ADC1 in bits 0–15, ADC2 in bits 16–31. Word 0: f_z, f_x;
        // word 1: the normal pickup (IN6), the tangential one (IN7).
        *s = ((w0 >> 16) as u16, (w0 & 0xFFFF) as u16);
        *p = ((w1 & 0xFFFF) as u16, (w1 >> 16) as u16);
    }
    // A late handler (both flags) is the fault ADC_OVERRUN, through the
    // device's one fault path.
    with_device(|dev| {
        dev.adc_half_done_with_pickups(ev, &samples, &pickups);
        // This half-buffer's DSP work: the refill's and this block's.
        cycles::record(dev, cycles::since(t0));
    });
}

/// DAC underrun: channel 1 stopped requesting; hold the outputs at rest.
#[interrupt]
fn TIM6_DAC() {
    let r = regs();
    if hardware::sampling::take_dac_underrun(&r) {
        hardware::sampling::hold_dac(&r, REST_WORD.load(Ordering::Relaxed));
        HELD.store(true, Ordering::Relaxed);
        PENDING_FAULTS.fetch_or(faults::DAC_UNDERRUN, Ordering::Relaxed);
    }
}

/// ADC overrun: the DMA stopped taking conversions.
#[interrupt]
fn ADC() {
    if hardware::sampling::take_adc_overrun(&regs()) {
        HELD.store(true, Ordering::Relaxed);
        PENDING_FAULTS.fetch_or(faults::ADC_OVERRUN, Ordering::Relaxed);
    }
}

/// The external fault input (PB0, active low: an amplifier alarm): latched
/// through the device's one fault path at the next lock (within a
/// half-buffer). Not wired under QEMU (its GPIO is a stub that reads 0).
#[cfg(not(feature = "qemu"))]
#[interrupt]
fn EXTI0() {
    if hardware::fault_input::take_pending(&regs()) {
        PENDING_FAULTS.fetch_or(faults::EXTERNAL, Ordering::Relaxed);
    }
}

#[interrupt]
fn USART2() {
    let r = regs();
    if let Some((b, overrun)) = hardware::usart::take_rx(&r) {
        // ORE: a byte was lost in the USART itself (the handler was late).
        let lost = u32::from(overrun) + u32::from(RX.lock(|q| q.push(b).is_err()));
        if lost > 0 {
            RX_LOST.fetch_add(lost, Ordering::Relaxed);
        }
    }
    tx_pump();
}
