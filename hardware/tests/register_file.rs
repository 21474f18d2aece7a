//! The hardware layer against a register file in RAM (the PAC's own
//! register blocks at test addresses), with a small simulation of what the
//! silicon does behind them: HSE and PLL ready bits, the clock switch,
//! TIM11's input captures of HSE/RTCPRE, the fault input's RC charge, and
//! the two DMA streams' NDTR, addresses and flags.
//!
//! Expected register values are built by hand from RM0090's bit positions
//! and register offsets (the `rm` module), not through the PAC's field
//! writers the code uses: a wrong field, offset or count shows as a
//! mismatch. Each test names the defect of issue 42 it guards.

use std::cell::RefCell;
use std::rc::Rc;

use board::protocol::self_test as bits;
use hardware::bring_up::{self, Buffers, Prepared, Step};
use hardware::buffers::{DmaBuffer, ADC_WORDS, DAC_WORDS, HALF};
use hardware::clocks::{self, PllConfig};
use hardware::streams::{self, StreamEvent};
use hardware::{fault_input, nvic, pac, sampling, self_test, watchdog, Delay, Registers};

/// RM0090 register offsets and bits, written out by hand.
mod rm {
    pub const RCC_CR: usize = 0x00;
    pub const RCC_PLLCFGR: usize = 0x04;
    pub const RCC_CFGR: usize = 0x08;
    pub const RCC_AHB1ENR: usize = 0x30;
    pub const RCC_APB1ENR: usize = 0x40;
    pub const RCC_APB2ENR: usize = 0x44;
    pub const FLASH_ACR: usize = 0x00;
    pub const DBG_IDCODE: usize = 0x00;
    pub const DBG_CR: usize = 0x04;
    pub const DBG_APB1_FZ: usize = 0x08;
    pub const GPIO_MODER: usize = 0x00;
    pub const GPIO_PUPDR: usize = 0x0C;
    pub const GPIO_IDR: usize = 0x10;
    pub const GPIO_AFRL: usize = 0x20;
    pub const SYSCFG_EXTICR1: usize = 0x08;
    pub const EXTI_IMR: usize = 0x00;
    pub const EXTI_FTSR: usize = 0x0C;
    pub const DMA_LISR: usize = 0x00;
    pub const DMA_HISR: usize = 0x04;
    pub const DMA_LIFCR: usize = 0x08;
    pub const DMA_HIFCR: usize = 0x0C;
    pub const fn sxcr(x: usize) -> usize {
        0x10 + 0x18 * x
    }
    pub const fn sxndtr(x: usize) -> usize {
        0x14 + 0x18 * x
    }
    pub const fn sxpar(x: usize) -> usize {
        0x18 + 0x18 * x
    }
    pub const fn sxm0ar(x: usize) -> usize {
        0x1C + 0x18 * x
    }
    pub const DAC_CR: usize = 0x00;
    pub const DAC_DHR12RD: usize = 0x20;
    pub const DAC_SR: usize = 0x34;
    pub const ADC_SR: usize = 0x00;
    pub const ADC_CR1: usize = 0x04;
    pub const ADC_CR2: usize = 0x08;
    pub const ADC_SMPR2: usize = 0x10;
    pub const ADC_SQR1: usize = 0x2C;
    pub const ADC_SQR3: usize = 0x34;
    pub const ADC_CCR: usize = 0x04;
    pub const TIM_CR1: usize = 0x00;
    pub const TIM_CR2: usize = 0x04;
    pub const TIM_SR: usize = 0x10;
    pub const TIM_EGR: usize = 0x14;
    pub const TIM_CCMR1: usize = 0x18;
    pub const TIM_CCER: usize = 0x20;
    pub const TIM_PSC: usize = 0x28;
    pub const TIM_ARR: usize = 0x2C;
    pub const TIM_CCR1: usize = 0x34;
    pub const TIM11_OR: usize = 0x50;
    pub const USART_BRR: usize = 0x08;
    pub const USART_CR1: usize = 0x0C;
    pub const IWDG_KR: usize = 0x00;
    pub const IWDG_PR: usize = 0x04;
    pub const IWDG_RLR: usize = 0x08;
}

/// One peripheral's registers in RAM.
#[derive(Clone, Copy)]
struct Block(*mut u32);

impl Block {
    fn new<T>() -> Self {
        let words = std::mem::size_of::<T>().div_ceil(4).max(0x60);
        Block(Box::leak(vec![0u32; words].into_boxed_slice()).as_mut_ptr())
    }
    fn get(self, off: usize) -> u32 {
        // SAFETY: within the leaked block; volatile as the code's accesses.
        unsafe { self.0.add(off / 4).read_volatile() }
    }
    fn set(self, off: usize, v: u32) {
        unsafe { self.0.add(off / 4).write_volatile(v) }
    }
    fn as_ref<T>(self) -> &'static T {
        // SAFETY: a zeroed, 4-aligned block at least as large as T, alive
        // for the program; the PAC's blocks are registers of u32 cells.
        unsafe { &*(self.0 as *const T) }
    }
}

/// The register file.
#[derive(Clone, Copy)]
struct File {
    rcc: Block,
    flash: Block,
    dbgmcu: Block,
    gpioa: Block,
    gpiob: Block,
    syscfg: Block,
    exti: Block,
    dma1: Block,
    dma2: Block,
    dac: Block,
    adc1: Block,
    adc2: Block,
    adc_common: Block,
    tim2: Block,
    tim11: Block,
    usart2: Block,
    iwdg: Block,
}

/// Reset values that the code must preserve (RM0090 §6.3.1, §8.4.1).
const RCC_CR_RESET: u32 = 0x0000_0083; // HSION, HSIRDY, HSITRIM = 16
const GPIOA_MODER_RESET: u32 = 0xA800_0000; // PA13–15: JTAG/SWD
const GPIOB_MODER_RESET: u32 = 0x0000_0280; // PB3, PB4: JTAG
const GPIOB_PUPDR_RESET: u32 = 0x0000_0100;
const GPIOA_PUPDR_RESET: u32 = 0x6400_0000; // PA13 pull-up, PA14 pull-down, PA15 pull-up
const RCC_AHB1ENR_RESET: u32 = 0x0010_0000; // CCMDATARAMEN
const RCC_PLLCFGR_RESET: u32 = 0x2400_3010;

impl File {
    fn new(rev_id: u16) -> Self {
        let f = File {
            rcc: Block::new::<pac::rcc::RegisterBlock>(),
            flash: Block::new::<pac::flash::RegisterBlock>(),
            dbgmcu: Block::new::<pac::dbgmcu::RegisterBlock>(),
            gpioa: Block::new::<pac::gpioa::RegisterBlock>(),
            gpiob: Block::new::<pac::gpiob::RegisterBlock>(),
            syscfg: Block::new::<pac::syscfg::RegisterBlock>(),
            exti: Block::new::<pac::exti::RegisterBlock>(),
            dma1: Block::new::<pac::dma2::RegisterBlock>(),
            dma2: Block::new::<pac::dma2::RegisterBlock>(),
            dac: Block::new::<pac::dac::RegisterBlock>(),
            adc1: Block::new::<pac::adc1::RegisterBlock>(),
            adc2: Block::new::<pac::adc1::RegisterBlock>(),
            adc_common: Block::new::<pac::adc_common::RegisterBlock>(),
            tim2: Block::new::<pac::tim2::RegisterBlock>(),
            tim11: Block::new::<pac::tim11::RegisterBlock>(),
            usart2: Block::new::<pac::usart1::RegisterBlock>(),
            iwdg: Block::new::<pac::iwdg::RegisterBlock>(),
        };
        f.rcc.set(rm::RCC_CR, RCC_CR_RESET);
        f.rcc.set(rm::RCC_AHB1ENR, RCC_AHB1ENR_RESET);
        f.rcc.set(rm::RCC_PLLCFGR, RCC_PLLCFGR_RESET);
        f.gpioa.set(rm::GPIO_PUPDR, GPIOA_PUPDR_RESET);
        f.gpioa.set(rm::GPIO_MODER, GPIOA_MODER_RESET);
        f.gpiob.set(rm::GPIO_MODER, GPIOB_MODER_RESET);
        f.gpiob.set(rm::GPIO_PUPDR, GPIOB_PUPDR_RESET);
        f.dbgmcu
            .set(rm::DBG_IDCODE, (u32::from(rev_id) << 16) | 0x413);
        f
    }

    fn regs(&self) -> Registers<'static> {
        Registers {
            rcc: self.rcc.as_ref(),
            flash: self.flash.as_ref(),
            dbgmcu: self.dbgmcu.as_ref(),
            gpioa: self.gpioa.as_ref(),
            gpiob: self.gpiob.as_ref(),
            syscfg: self.syscfg.as_ref(),
            exti: self.exti.as_ref(),
            dma1: self.dma1.as_ref(),
            dma2: self.dma2.as_ref(),
            dac: self.dac.as_ref(),
            adc1: self.adc1.as_ref(),
            adc2: self.adc2.as_ref(),
            adc_common: self.adc_common.as_ref(),
            tim2: self.tim2.as_ref(),
            tim11: self.tim11.as_ref(),
            usart2: self.usart2.as_ref(),
            iwdg: self.iwdg.as_ref(),
        }
    }
}

/// The board behind the file.
#[derive(Clone, Copy)]
struct Board {
    /// The crystal's true frequency, Hz (`None`: dead).
    hse_hz: Option<f64>,
    /// The HSI's true frequency, Hz (16 MHz ± 1 %).
    hsi_hz: f64,
    /// The fault input's RC: time to V_IH after the pull-up is on, µs
    /// (`None`: held low by an active alarm).
    pin_rise_us: Option<f64>,
    /// The PLL locks.
    pll_locks: bool,
    /// RCC_PLLCFGR reads back another M once the PLL is on (a faulty RCC).
    pllcfgr_drifts: bool,
}

impl Board {
    const GOOD: Board = Board {
        hse_hz: Some(8e6),
        hsi_hz: 16e6,
        // 50 kΩ · 1 nF · ln(1/0.3): the module's worst case.
        pin_rise_us: Some(60.2), // 50 kΩ · 1 nF · ln(1/0.3) = 60.2 µs
        pll_locks: true,
        pllcfgr_drifts: false,
    };
}

/// Simulated time and the hardware it moves.
struct Sim {
    file: File,
    board: Board,
    t_us: f64,
    hse_on_at: Option<f64>,
    pll_on_at: Option<f64>,
    pull_up_at: Option<f64>,
    /// Index of the next capture edge group, and the time TIM11 started.
    capture: Option<(f64, u64)>,
}

const HSE_STARTUP_US: f64 = 1_500.0;
const PLL_LOCK_US: f64 = 150.0;

impl Sim {
    fn new(file: File, board: Board) -> Rc<RefCell<Sim>> {
        Rc::new(RefCell::new(Sim {
            file,
            board,
            t_us: 0.0,
            hse_on_at: None,
            pll_on_at: None,
            pull_up_at: None,
            capture: None,
        }))
    }

    /// SYSCLK and TIM11's clock from the registers (RM0090 §6.2).
    fn clocks(&self) -> (f64, f64) {
        let cfgr = self.file.rcc.get(rm::RCC_CFGR);
        let sws = (cfgr >> 2) & 3;
        let sys = if sws == 2 {
            let p = self.file.rcc.get(rm::RCC_PLLCFGR);
            let (m, n, pp) = (p & 0x3F, (p >> 6) & 0x1FF, 2 * (((p >> 16) & 3) + 1));
            self.board.hse_hz.unwrap_or(0.0) / f64::from(m) * f64::from(n) / f64::from(pp)
        } else {
            self.board.hsi_hz
        };
        let ppre2 = (cfgr >> 13) & 7;
        let div = if ppre2 < 4 {
            1.0
        } else {
            f64::from(2u32 << (ppre2 - 4))
        };
        let tim = if div == 1.0 { sys } else { 2.0 * sys / div };
        (sys, tim)
    }

    fn advance(&mut self, us: f64) {
        let f = self.file;
        let t0 = self.t_us;
        self.t_us += us;
        let t = self.t_us;
        let cr = f.rcc.get(rm::RCC_CR);
        // HSE: ready a start-up time after HSEON, if the crystal is alive.
        if cr & (1 << 16) != 0 {
            let at = *self.hse_on_at.get_or_insert(t0);
            if self.board.hse_hz.is_some() && t - at >= HSE_STARTUP_US {
                f.rcc.set(rm::RCC_CR, f.rcc.get(rm::RCC_CR) | (1 << 17));
            }
        } else {
            self.hse_on_at = None;
            f.rcc.set(rm::RCC_CR, f.rcc.get(rm::RCC_CR) & !(1 << 17));
        }
        let cr = f.rcc.get(rm::RCC_CR);
        if self.board.pllcfgr_drifts && cr & (1 << 24) != 0 {
            let p = f.rcc.get(rm::RCC_PLLCFGR);
            f.rcc.set(rm::RCC_PLLCFGR, (p & !0x3F) | 5);
        }
        if cr & (1 << 24) != 0 && cr & (1 << 17) != 0 {
            let at = *self.pll_on_at.get_or_insert(t0);
            if self.board.pll_locks && t - at >= PLL_LOCK_US {
                f.rcc.set(rm::RCC_CR, cr | (1 << 25));
            }
        } else {
            self.pll_on_at = None;
            f.rcc.set(rm::RCC_CR, cr & !(1 << 25));
        }
        // The switch: SWS follows SW if the source is ready.
        let cfgr = f.rcc.get(rm::RCC_CFGR);
        let sw = cfgr & 3;
        let ready = sw == 0 || (sw == 2 && f.rcc.get(rm::RCC_CR) & (1 << 25) != 0);
        if ready {
            f.rcc.set(rm::RCC_CFGR, (cfgr & !0xC) | (sw << 2));
        }
        // The fault input's pull-up charges the pin.
        let pupd = f.gpiob.get(rm::GPIO_PUPDR) & 3;
        if pupd == 1 {
            let at = *self.pull_up_at.get_or_insert(t0);
            let high = self.board.pin_rise_us.is_some_and(|r| t - at >= r);
            f.gpiob.set(rm::GPIO_IDR, u32::from(high));
        }
        self.captures(t0, t);
    }

    /// TIM11 input captures of HSE/RTCPRE, 8 edges each, in (t0, t].
    fn captures(&mut self, t0: f64, t: f64) {
        let f = self.file;
        // TIM11 clocked, counting, CC1 an input on TI1 (CC1S = 01), enabled,
        // rising edges, TI1 remapped to HSE_RTC.
        let on = f.rcc.get(rm::RCC_APB2ENR) & (1 << 18) != 0
            && f.tim11.get(rm::TIM_CR1) & 1 != 0
            && f.tim11.get(rm::TIM_CCMR1) & 3 == 0b01
            && f.tim11.get(rm::TIM_CCER) & 0b1011 == 0b0001
            && f.tim11.get(rm::TIM11_OR) & 3 == 0b10;
        let hse_ready = f.rcc.get(rm::RCC_CR) & (1 << 17) != 0;
        let (Some(hse), true, true) = (self.board.hse_hz, on, hse_ready) else {
            self.capture = None;
            return;
        };
        let rtcpre = (f.rcc.get(rm::RCC_CFGR) >> 16) & 0x1F;
        if rtcpre < 2 {
            // RTCPRE 0 and 1: no clock (RM0090 §6.3.3).
            self.capture = None;
            return;
        }
        let psc = (f.tim11.get(rm::TIM_CCMR1) >> 2) & 3;
        let edges = [1.0, 2.0, 4.0, 8.0][psc as usize];
        let period_us = edges * f64::from(rtcpre) / hse * 1e6;
        let (start, mut k) = *self.capture.get_or_insert((t0, 1));
        let (_, tim_hz) = self.clocks();
        let mut n = 0;
        while start + k as f64 * period_us <= t {
            let at = start + k as f64 * period_us;
            let count = ((at - start) * 1e-6 * tim_hz).floor() as u64 % 65_536;
            f.tim11.set(rm::TIM_CCR1, count as u32);
            let sr = f.tim11.get(rm::TIM_SR);
            let over = if sr & 2 != 0 { 1 << 9 } else { 0 };
            f.tim11.set(rm::TIM_SR, sr | 2 | over);
            k += 1;
            n += 1;
        }
        let _ = n;
        self.capture = Some((start, k));
    }
}

/// The test's delay: simulated time.
struct SimDelay(Rc<RefCell<Sim>>);

impl Delay for SimDelay {
    fn wait_us(&mut self, us: u32, _sysclk_hz: u32) {
        self.0.borrow_mut().advance(f64::from(us));
    }
}

const DAC_ADDR: u32 = 0x2000_0400;
const ADC_ADDR: u32 = 0x2000_0800;
const PRELOAD: u32 = (2048 << 16) | 1234;

fn buffers() -> Buffers {
    Buffers {
        dac: DmaBuffer {
            addr: DAC_ADDR,
            words: DAC_WORDS as u16,
        },
        adc: DmaBuffer {
            addr: ADC_ADDR,
            words: ADC_WORDS as u16,
        },
        dac_preload: PRELOAD,
    }
}

/// A step's time and the registers then.
#[derive(Clone, Debug)]
struct Snap {
    step: Step,
    t_us: f64,
    dac_cr: u32,
    adc1_cr2: u32,
    tim2_cr1: u32,
    tim2_cr2: u32,
    tim2_egr: u32,
    dhr12rd: u32,
    dma1_s5_cr: u32,
    gpiob_pupdr: u32,
}

struct Run {
    file: File,
    sim: Rc<RefCell<Sim>>,
    prepared: Prepared,
    snaps: Vec<Snap>,
    /// Each UG written to TIM2 (a TRGO with MMS = 010), seen at the step
    /// after it: (step, DAC triggers on, ADC trigger on).
    updates: Vec<(Step, bool, bool)>,
}

fn bring_up_with(board: Board, rev_id: u16) -> Run {
    let file = File::new(rev_id);
    let sim = Sim::new(file, board);
    let mut delay = SimDelay(sim.clone());
    let snaps = RefCell::new(Vec::new());
    let updates = RefCell::new(Vec::new());
    let mut observe = |step: Step, _r: &Registers| {
        // UG is self-clearing on the chip: record it and clear it here.
        if file.tim2.get(rm::TIM_EGR) & 1 != 0 {
            updates.borrow_mut().push((
                step,
                file.dac.get(rm::DAC_CR) & ((1 << 2) | (1 << 18)) != 0,
                file.adc1.get(rm::ADC_CR2) & (0b11 << 28) != 0,
            ));
        }
        snaps.borrow_mut().push(Snap {
            step,
            t_us: sim.borrow().t_us,
            dac_cr: file.dac.get(rm::DAC_CR),
            adc1_cr2: file.adc1.get(rm::ADC_CR2),
            tim2_cr1: file.tim2.get(rm::TIM_CR1),
            tim2_cr2: file.tim2.get(rm::TIM_CR2),
            tim2_egr: file.tim2.get(rm::TIM_EGR),
            dhr12rd: file.dac.get(rm::DAC_DHR12RD),
            dma1_s5_cr: file.dma1.get(rm::sxcr(5)),
            gpiob_pupdr: file.gpiob.get(rm::GPIO_PUPDR),
        });
        file.tim2.set(rm::TIM_EGR, 0);
    };
    let regs = file.regs();
    let mut prepared = bring_up::prepare(&regs, &buffers(), &mut delay, &mut observe);
    bring_up::start_sampling(&regs, &mut prepared, &mut observe);
    let snaps = snaps.into_inner();
    Run {
        file,
        sim,
        prepared,
        snaps,
        updates: updates.into_inner(),
    }
}

/// The self-test report of a bring-up, with the streams' first halves.
fn report(run: &Run, first_halves: Option<(u32, u32)>) -> board::protocol::SelfTest {
    self_test::report(&self_test::Findings {
        clock: run.prepared.clock,
        dma_setup: run.prepared.dma_setup,
        first_halves,
    })
}

fn snap(run: &Run, step: Step) -> &Snap {
    run.snaps
        .iter()
        .find(|s| s.step == step)
        .unwrap_or_else(|| panic!("step {step:?} not reached"))
}

/// One DMA stream as the controller runs it (RM0090 §10.3): each request
/// moves one word at M0AR + 4·(programmed − NDTR), NDTR counts down, HT is
/// raised when half the programmed count is done, TC at zero, and a
/// circular stream reloads the programmed count.
struct StreamSim {
    dma: Block,
    x: usize,
    programmed: u32,
    /// (HT, TC, TE, DME, FE) bit positions in LISR/HISR.
    flags_reg: usize,
    shift: u32,
}

impl StreamSim {
    fn new(dma: Block, x: usize) -> Self {
        let programmed = dma.get(rm::sxndtr(x));
        let (flags_reg, shift) = match x {
            0 => (rm::DMA_LISR, 0),
            1 => (rm::DMA_LISR, 6),
            2 => (rm::DMA_LISR, 16),
            3 => (rm::DMA_LISR, 22),
            _ => (rm::DMA_HISR, [0, 6, 16, 22][x - 4]),
        };
        StreamSim {
            dma,
            x,
            programmed,
            flags_reg,
            shift,
        }
    }
    /// One request: the address it moves a word at.
    fn request(&mut self) -> u32 {
        let cr = self.dma.get(rm::sxcr(self.x));
        assert!(cr & 1 != 0, "stream {} not enabled", self.x);
        let ndtr = self.dma.get(rm::sxndtr(self.x));
        let msize = 1 << ((cr >> 13) & 3);
        let addr = self.dma.get(rm::sxm0ar(self.x)) + msize * (self.programmed - ndtr);
        let left = ndtr - 1;
        let mut flags = self.dma.get(self.flags_reg);
        if left == self.programmed / 2 {
            flags |= 1 << (self.shift + 4); // HTIF
        }
        if left == 0 {
            flags |= 1 << (self.shift + 5); // TCIF
        }
        self.dma.set(self.flags_reg, flags);
        let circ = cr & (1 << 8) != 0;
        self.dma.set(
            rm::sxndtr(self.x),
            if left == 0 && circ {
                self.programmed
            } else {
                left
            },
        );
        addr
    }
    /// Applies the clear register the handler wrote (write-1-to-clear).
    fn apply_clear(&self) {
        let ifcr = if self.flags_reg == rm::DMA_LISR {
            rm::DMA_LIFCR
        } else {
            rm::DMA_HIFCR
        };
        let c = self.dma.get(ifcr);
        self.dma
            .set(self.flags_reg, self.dma.get(self.flags_reg) & !c);
        self.dma.set(ifcr, 0);
    }
}

/// Defect 1: the DAC's stream runs over its buffer and nothing else, and
/// hands over a half every HALF ticks, as the ADC's does.
#[test]
fn the_dac_stream_stays_in_its_buffer_and_pairs_with_the_adc() {
    let run = bring_up_with(Board::GOOD, 0x1001);
    let bufs = buffers();
    let regs = run.file.regs();
    let mut dac = StreamSim::new(run.file.dma1, 5);
    let mut adc = StreamSim::new(run.file.dma2, 0);
    assert_eq!(dac.programmed as usize, DAC_WORDS, "DAC NDTR");
    assert_eq!(adc.programmed as usize, ADC_WORDS, "ADC NDTR");
    let (mut dac_halves, mut adc_halves) = (Vec::new(), Vec::new());
    for tick in 1..=(3 * 2 * HALF) {
        // One trigger: one DAC word, two ADC words.
        let a = dac.request();
        assert!(
            bufs.dac.contains(a),
            "tick {tick}: the DAC stream reads {a:#x}, outside its buffer"
        );
        for _ in 0..2 {
            let a = adc.request();
            assert!(
                bufs.adc.contains(a),
                "tick {tick}: the ADC stream writes {a:#x}"
            );
        }
        let f = streams::take_dac_flags(&regs);
        dac.apply_clear();
        if let StreamEvent::Half(h) = f.event(&bufs.dac) {
            assert!(!h.late);
            dac_halves.push((tick, h.half));
        }
        let f = streams::take_adc_flags(&regs);
        adc.apply_clear();
        if let StreamEvent::Half(h) = f.event(&bufs.adc) {
            assert!(!h.late);
            adc_halves.push((tick, h.half));
        }
    }
    let expect: Vec<(usize, usize)> = (1..=6).map(|k| (k * HALF, (k + 1) % 2)).collect();
    assert_eq!(
        dac_halves, expect,
        "DAC halves: one every HALF ticks, 0, 1, 0, …"
    );
    assert_eq!(adc_halves, expect, "ADC blocks pair with the DAC refills");
}

/// Defect 1 (the registers): every stream register as RM0090 requires.
#[test]
fn the_streams_are_set_as_rm0090_requires() {
    let run = bring_up_with(Board::GOOD, 0x1001);
    let (d1, d2) = (run.file.dma1, run.file.dma2);
    // CHSEL 7, PL very high, MSIZE = PSIZE = 32 bit, MINC, CIRC,
    // DIR = memory→peripheral, TCIE, HTIE, TEIE, DMEIE, EN.
    let dac_cr = (7 << 25)
        | (0b11 << 16)
        | (0b10 << 13)
        | (0b10 << 11)
        | (1 << 10)
        | (1 << 8)
        | (0b01 << 6)
        | (1 << 4)
        | (1 << 3)
        | (1 << 2)
        | (1 << 1)
        | 1;
    assert_eq!(d1.get(rm::sxcr(5)), dac_cr, "DMA1_S5CR");
    assert_eq!(
        d1.get(rm::sxpar(5)),
        0x4000_7420,
        "DMA1_S5PAR = DAC_DHR12RD"
    );
    assert_eq!(d1.get(rm::sxm0ar(5)), DAC_ADDR);
    assert_eq!(d1.get(rm::sxndtr(5)), 2 * HALF as u32);
    // Channel 0, DIR = peripheral→memory.
    let adc_cr = (0b11 << 16)
        | (0b10 << 13)
        | (0b10 << 11)
        | (1 << 10)
        | (1 << 8)
        | (1 << 4)
        | (1 << 3)
        | (1 << 2)
        | (1 << 1)
        | 1;
    assert_eq!(d2.get(rm::sxcr(0)), adc_cr, "DMA2_S0CR");
    assert_eq!(d2.get(rm::sxpar(0)), 0x4001_2308, "DMA2_S0PAR = ADC_CDR");
    assert_eq!(d2.get(rm::sxm0ar(0)), ADC_ADDR);
    assert_eq!(d2.get(rm::sxndtr(0)), 4 * HALF as u32);
    assert_eq!(run.prepared.dma_setup, Some(true));
    // The PAC's blocks sit where RM0090's memory map puts them.
    assert_eq!(pac::DAC::ptr() as usize, 0x4000_7400);
    assert_eq!(pac::ADC_COMMON::ptr() as usize, 0x4001_2300);
    assert_eq!(pac::DMA1::ptr() as usize, 0x4002_6000);
    assert_eq!(pac::DMA2::ptr() as usize, 0x4002_6400);
}

/// Every other register of the set-up, against its RM0090 value.
#[test]
fn every_setup_register_has_its_rm0090_value() {
    let run = bring_up_with(Board::GOOD, 0x1001);
    let f = run.file;
    // RCC: PLL M = 4, N = 168, P = 2 (00), PLLSRC = HSE, Q = 7; bit 29 is
    // reserved and "must be kept at reset value" (1, reset 0x2400_3010).
    assert_eq!(
        f.rcc.get(rm::RCC_PLLCFGR),
        4 | (168 << 6) | (1 << 22) | (7 << 24) | (1 << 29)
    );
    // CFGR: SW = PLL, SWS = PLL, HPRE /1, PPRE1 /4, PPRE2 /2, RTCPRE 8.
    assert_eq!(
        f.rcc.get(rm::RCC_CFGR),
        0b10 | (0b10 << 2) | (0b101 << 10) | (0b100 << 13) | (8 << 16)
    );
    assert_eq!(
        f.rcc.get(rm::RCC_CR) & (1 << 16 | 1 << 24),
        1 << 16 | 1 << 24
    );
    // AHB1ENR: GPIOA, GPIOB, DMA1, DMA2; APB1ENR: TIM2, USART2, DAC;
    // APB2ENR: ADC1, ADC2, SYSCFG, TIM11.
    assert_eq!(
        f.rcc.get(rm::RCC_AHB1ENR),
        RCC_AHB1ENR_RESET | 1 | 2 | (1 << 21) | (1 << 22)
    );
    assert_eq!(f.rcc.get(rm::RCC_APB1ENR), 1 | (1 << 17) | (1 << 29));
    assert_eq!(
        f.rcc.get(rm::RCC_APB2ENR),
        (1 << 8) | (1 << 9) | (1 << 14) | (1 << 18)
    );
    // FLASH_ACR: 5 WS, PRFTEN (not revision A), ICEN, DCEN.
    assert_eq!(
        f.flash.get(rm::FLASH_ACR),
        5 | (1 << 8) | (1 << 9) | (1 << 10)
    );
    // DBGMCU: DBG_SLEEP, DBG_IWDG_STOP.
    assert_eq!(f.dbgmcu.get(rm::DBG_CR), 1);
    assert_eq!(f.dbgmcu.get(rm::DBG_APB1_FZ), 1 << 12);
    // GPIOA: PA0, 1, 4–7 analog, PA2, 3 AF7, PA13–15 (SWD) kept.
    assert_eq!(
        f.gpioa.get(rm::GPIO_MODER),
        GPIOA_MODER_RESET | 0b11 | (0b11 << 2) | (0b10 << 4) | (0b10 << 6) | (0xFF << 8)
    );
    assert_eq!(f.gpioa.get(rm::GPIO_AFRL), (7 << 8) | (7 << 12));
    // PA3 (USART2 RX) pulled up; the SWD pins' pulls kept.
    assert_eq!(f.gpioa.get(rm::GPIO_PUPDR), GPIOA_PUPDR_RESET | (0b01 << 6));
    // GPIOB: PB0 input with pull-up, the JTAG pins kept.
    assert_eq!(f.gpiob.get(rm::GPIO_MODER), GPIOB_MODER_RESET);
    assert_eq!(f.gpiob.get(rm::GPIO_PUPDR), GPIOB_PUPDR_RESET | 0b01);
    // EXTI0 ← PB, falling edge, unmasked.
    assert_eq!(f.syscfg.get(rm::SYSCFG_EXTICR1), 0b0001);
    assert_eq!(f.exti.get(rm::EXTI_FTSR), 1);
    assert_eq!(f.exti.get(rm::EXTI_IMR), 1);
    // DAC_CR: EN1, TEN1, TSEL1 = 100, DMAEN1, DMAUDRIE1; EN2, TEN2, TSEL2 = 100
    // (BOFF = 0: buffers on; DMAEN2 off).
    assert_eq!(
        f.dac.get(rm::DAC_CR),
        1 | (1 << 2) | (0b100 << 3) | (1 << 12) | (1 << 13) | (1 << 16) | (1 << 18) | (0b100 << 19)
    );
    assert_eq!(f.dac.get(rm::DAC_DHR12RD), PRELOAD);
    // ADC common: ADCPRE /4, DMA mode 2, DDS, MULTI = 00110.
    assert_eq!(
        f.adc_common.get(rm::ADC_CCR),
        (0b01 << 16) | (0b10 << 14) | (1 << 13) | 0b00110
    );
    // Scans of two: L = 1; ADC1 IN0, IN6; ADC2 IN1, IN7; 3-cycle sampling.
    for a in [f.adc1, f.adc2] {
        assert_eq!(a.get(rm::ADC_SQR1), 1 << 20);
        assert_eq!(a.get(rm::ADC_SMPR2), 0);
        // SCAN, OVRIE, 12 bits.
        assert_eq!(a.get(rm::ADC_CR1), (1 << 8) | (1 << 26));
    }
    assert_eq!(f.adc1.get(rm::ADC_SQR3), 6 << 5);
    assert_eq!(f.adc2.get(rm::ADC_SQR3), 1 | (7 << 5));
    // ADC1: ADON, EXTSEL = 0110 (TIM2 TRGO), EXTEN = rising; ADC2: ADON.
    assert_eq!(f.adc1.get(rm::ADC_CR2), 1 | (0b0110 << 24) | (0b01 << 28));
    assert_eq!(f.adc2.get(rm::ADC_CR2), 1);
    // TIM2: ARR = 84 MHz / 500 kHz − 1, PSC 0, MMS = 010, CEN (+URS).
    assert_eq!(f.tim2.get(rm::TIM_ARR), 167);
    assert_eq!(f.tim2.get(rm::TIM_PSC), 0);
    assert_eq!(f.tim2.get(rm::TIM_CR2), 0b010 << 4);
    assert_eq!(f.tim2.get(rm::TIM_CR1), 1 | (1 << 2));
    // USART2 at 42 MHz: BRR = 42e6/115200 = 364.58 → 365 (0x16D); UE, TE, RE, RXNEIE.
    assert_eq!(f.usart2.get(rm::USART_BRR), 365);
    assert_eq!(
        f.usart2.get(rm::USART_CR1),
        (1 << 13) | (1 << 3) | (1 << 2) | (1 << 5)
    );
    // IWDG: last key START, /8, reload 4095.
    assert_eq!(f.iwdg.get(rm::IWDG_KR), 0xCCCC);
    assert_eq!(f.iwdg.get(rm::IWDG_PR), 1);
    assert_eq!(f.iwdg.get(rm::IWDG_RLR), 0xFFF);
    // TIM11: TI1 ← HSE_RTC (OR.RMP = 10), CC1S = 01 (input TI1), IC1PSC =
    // 11 (/8), no filter; left stopped with its capture off.
    assert_eq!(f.tim11.get(rm::TIM11_OR), 0b10);
    assert_eq!(f.tim11.get(rm::TIM_CCMR1), 0b1101);
    assert_eq!(f.tim11.get(rm::TIM_CR1) & 1, 0);
    assert_eq!(f.tim11.get(rm::TIM_CCER), 0);
    assert_eq!(f.tim11.get(rm::TIM_PSC), 0);
    assert_eq!(f.tim11.get(rm::TIM_ARR), 0xFFFF);
}

/// Defect 4: the timer's UG (which raises TRGO) comes before any consumer
/// listens; the ADC is stabilised before the first trigger; the DAC's
/// holding register holds the word before word 0.
#[test]
fn the_sample_clock_starts_only_after_every_consumer_is_ready() {
    let run = bring_up_with(Board::GOOD, 0x1001);
    let loaded = snap(&run, Step::SampleClockLoaded);
    assert_eq!(loaded.tim2_egr & 1, 1, "UG issued");
    assert_eq!(
        run.updates,
        vec![(Step::SampleClockLoaded, false, false)],
        "one UG, with neither consumer listening"
    );
    assert_eq!(loaded.tim2_cr1 & 1, 0, "counter stopped at UG");
    assert_eq!(
        loaded.dac_cr & ((1 << 2) | (1 << 18)),
        0,
        "DAC triggers off at UG"
    );
    assert_eq!(loaded.adc1_cr2 & (0b11 << 28), 0, "ADC trigger off at UG");
    let armed = snap(&run, Step::AdcArmed);
    let started = snap(&run, Step::SampleClockStarted);
    assert_eq!(
        armed.tim2_cr1 & 1,
        0,
        "counter still stopped when the ADC is armed"
    );
    assert_eq!(started.tim2_cr1 & 1, 1);
    let dac = snap(&run, Step::DacArmed);
    assert_eq!(
        dac.dhr12rd, PRELOAD,
        "DHR preloaded before the first trigger"
    );
    assert_eq!(dac.tim2_cr1 & 1, 0);
    // ADON is written in `arm_adc`, which then waits t_STAB.
    let before = snap(&run, Step::DacArmed).t_us;
    assert!(
        armed.t_us - before >= f64::from(sampling::ADC_STAB_US),
        "ADC stabilisation: {} µs",
        armed.t_us - before
    );
    assert!(started.tim2_cr2 == 0b010 << 4);
    let streams = snap(&run, Step::StreamsSet);
    assert_eq!(streams.dma1_s5_cr & 1, 1, "streams on before the DAC asks");
}

/// Defect 5: the fault input is read only after the pull-up has charged
/// the worst-case input (50 kΩ, 1 nF) past V_IH: an idle input reads idle.
#[test]
fn the_fault_input_reads_idle_after_its_pull_up_settles() {
    let run = bring_up_with(Board::GOOD, 0x1001);
    assert!(
        !run.prepared.fault_input_active,
        "a quiet alarm line latched 'external'"
    );
    let armed = snap(&run, Step::PullUpArmed);
    let read = snap(&run, Step::FaultInputRead);
    assert_eq!(armed.gpiob_pupdr & 3, 1);
    // 5·R·C = 250 µs ≥ 4 × the threshold time 1.2·RC = 60 µs.
    assert_eq!(fault_input::PULLUP_SETTLE_US, 250);
    assert!(read.t_us - armed.t_us >= f64::from(fault_input::PULLUP_SETTLE_US));
    // An alarm held low is seen.
    let held = bring_up_with(
        Board {
            pin_rise_us: None,
            ..Board::GOOD
        },
        0x1001,
    );
    assert!(held.prepared.fault_input_active);
}

/// Defect 6: each way a stream stops is seen, and its flag cleared.
#[test]
fn stream_errors_underruns_and_overruns_are_seen() {
    let run = bring_up_with(Board::GOOD, 0x1001);
    let regs = run.file.regs();
    let bufs = buffers();
    let (d1, d2) = (run.file.dma1, run.file.dma2);
    // DMA1 Stream5 transfer error (HISR bit 9): seen, cleared by HIFCR bit 9.
    d1.set(rm::DMA_HISR, 1 << 9);
    let f = streams::take_dac_flags(&regs);
    assert!(f.te);
    assert_eq!(f.event(&bufs.dac), StreamEvent::Stopped);
    assert_eq!(d1.get(rm::DMA_HIFCR), 1 << 9, "exactly TEIF5 cleared");
    // Direct-mode error (bit 8) with a half-transfer: the error wins.
    d1.set(rm::DMA_HISR, (1 << 8) | (1 << 10));
    let f = streams::take_dac_flags(&regs);
    assert_eq!(f.event(&bufs.dac), StreamEvent::Stopped);
    assert_eq!(d1.get(rm::DMA_HIFCR), (1 << 8) | (1 << 10));
    // FIFO error alone (bit 6): cleared, nothing to do.
    d1.set(rm::DMA_HISR, 1 << 6);
    assert_eq!(
        streams::take_dac_flags(&regs).event(&bufs.dac),
        StreamEvent::None
    );
    assert_eq!(d1.get(rm::DMA_HIFCR), 1 << 6);
    // DMA2 Stream0 transfer error (LISR bit 3), cleared by LIFCR bit 3.
    d2.set(rm::DMA_LISR, 1 << 3);
    assert_eq!(
        streams::take_adc_flags(&regs).event(&bufs.adc),
        StreamEvent::Stopped
    );
    assert_eq!(d2.get(rm::DMA_LIFCR), 1 << 3);
    // DAC underrun (SR bit 13, write 1 to clear).
    assert!(!sampling::take_dac_underrun(&regs));
    run.file.dac.set(rm::DAC_SR, 1 << 13);
    assert!(sampling::take_dac_underrun(&regs));
    assert_eq!(run.file.dac.get(rm::DAC_SR), 1 << 13, "written 1 to clear");
    // ADC2 overrun (SR bit 5, write 0 to clear, the other flags written 1).
    run.file.dac.set(rm::DAC_SR, 0);
    assert!(!sampling::take_adc_overrun(&regs));
    run.file.adc2.set(rm::ADC_SR, 1 << 5);
    assert!(sampling::take_adc_overrun(&regs));
    assert_eq!(run.file.adc2.get(rm::ADC_SR) & (1 << 5), 0);
    assert_eq!(
        run.file.adc2.get(rm::ADC_SR) & 0x1F,
        0x1F,
        "other flags untouched"
    );
    // The safe state after a stopped DAC stream: DMA request off, rest word held.
    assert_eq!(d1.get(rm::sxcr(5)) & 1, 1);
    sampling::hold_dac(&regs, 0x0800_0800);
    assert_eq!(d1.get(rm::sxcr(5)) & 1, 0, "DAC stream disabled first");
    assert_eq!(run.file.dac.get(rm::DAC_CR) & (1 << 12), 0);
    assert_eq!(run.file.dac.get(rm::DAC_DHR12RD), 0x0800_0800);
    // The watchdog is fed only while both streams move.
    let mut live = watchdog::Liveness::default();
    assert!(live.check(1, 1));
    assert!(!live.check(2, 1), "ADC stalled: no feed");
    assert!(!live.check(9, 1));
    assert!(live.check(9, 2));
    assert!(!live.check(9, 3), "DAC stalled: no feed");
}

/// Defect 7: the PLL factors for the crystals boards carry, and a brute
/// force over 4–26 MHz in 1 kHz steps: wherever factors exist they give
/// exactly 168 and 48 MHz within RM0090's ranges, and for_hse finds them.
#[test]
fn pll_factors_for_any_crystal() {
    let f = |m, n, p, q| PllConfig { m, n, p, q };
    assert_eq!(PllConfig::for_hse(8_000_000), f(4, 168, 2, 7));
    assert_eq!(PllConfig::for_hse(12_000_000), f(6, 168, 2, 7));
    assert_eq!(PllConfig::for_hse(25_000_000), f(25, 336, 2, 7));
    assert_eq!(PllConfig::for_hse(16_000_000), f(8, 168, 2, 7));
    assert_eq!(clocks::PLL, f(4, 168, 2, 7), "default build: 8 MHz");
    let mut found = 0;
    for khz in 4_000..=26_000u32 {
        let hse = khz * 1000;
        // Brute force: any M whose VCO input is 1–2 MHz and divides 336 MHz.
        let exists = (2..=63u32).any(|m| {
            hse % m == 0
                && (1_000_000..=2_000_000).contains(&(hse / m))
                && 336_000_000 % (hse / m) == 0
                && (50..=432).contains(&(336_000_000 / (hse / m)))
        });
        let got = std::panic::catch_unwind(|| PllConfig::for_hse(hse));
        assert_eq!(got.is_ok(), exists, "{hse} Hz");
        if let Ok(p) = got {
            found += 1;
            let vin = hse / u32::from(p.m);
            assert!((1_000_000..=2_000_000).contains(&vin));
            let vco = u64::from(vin) * u64::from(p.n);
            assert!((100_000_000..=432_000_000).contains(&vco));
            assert_eq!(vco / u64::from(p.p), 168_000_000);
            assert_eq!(vco / u64::from(p.q), 48_000_000);
            assert_eq!(vco % u64::from(p.q), 0);
            assert_eq!(p.sysclk_hz(hse), 168_000_000);
        }
    }
    assert!(found > 20, "{found} crystals");
    assert!(std::panic::catch_unwind(|| PllConfig::for_hse(3_000_000)).is_err());
    assert!(std::panic::catch_unwind(|| PllConfig::for_hse(27_000_000)).is_err());
}

/// Defect 7: a 12 MHz crystal on the 8 MHz build is measured and refused
/// (it would run the core at 252 MHz); the board stays on the HSI, drives
/// nothing, and says why; the link runs at the HSI's clock.
#[test]
fn a_wrong_crystal_keeps_the_core_on_the_hsi() {
    let run = bring_up_with(
        Board {
            hse_hz: Some(12e6),
            ..Board::GOOD
        },
        0x1001,
    );
    let f = run.file;
    assert_eq!(f.rcc.get(rm::RCC_CFGR) & 0xF, 0, "SW = SWS = HSI");
    assert_eq!(
        f.rcc.get(rm::RCC_CR) & (1 << 24 | 1 << 16),
        0,
        "PLL and HSE off"
    );
    assert_eq!(f.dma1.get(rm::sxcr(5)) & 1, 0, "no DAC stream");
    assert_eq!(f.dac.get(rm::DAC_CR), 0, "DAC off");
    assert_eq!(f.tim2.get(rm::TIM_CR1) & 1, 0, "no sample clock");
    assert_eq!(f.usart2.get(rm::USART_BRR), 139, "16 MHz / 115200 = 138.9");
    assert!(!run.prepared.can_sample());
    assert!(!run.prepared.sampling);
    let t = report(&run, None);
    assert_eq!(t.failed, bits::HSE_FREQUENCY);
    // Measured against the HSI: 12 MHz within its resolution (32·8 edges of
    // 1 MHz... here 12 MHz/8 = 1.5 MHz over 4096 ticks at 16 MHz: ±1 tick).
    assert!(
        (f64::from(t.hse_hz) - 12e6).abs() <= 12e6 * 2.0 / 2731.0,
        "{}",
        t.hse_hz
    );
}

/// Defect 7: a dead crystal times out (the board neither hangs nor runs).
#[test]
fn a_dead_crystal_times_out_on_the_hsi() {
    let run = bring_up_with(
        Board {
            hse_hz: None,
            ..Board::GOOD
        },
        0x1001,
    );
    let t_end = run.sim.borrow().t_us;
    assert!(
        t_end <= f64::from(clocks::HSE_TIMEOUT_US + fault_input::PULLUP_SETTLE_US) + 100.0,
        "{t_end} µs"
    );
    assert_eq!(run.file.rcc.get(rm::RCC_CR) & (1 << 16), 0, "HSE off again");
    let t = report(&run, None);
    assert_eq!(t.ran, bits::CLOCK_READY);
    assert_eq!(t.failed, bits::CLOCK_READY);
    assert_eq!(t.hse_hz, 0);
}

/// The self-test on a good board: the crystal and SYSCLK measured against
/// an HSI that is itself 1 % fast (its datasheet bound), both within the
/// resolution-and-HSI bound, and a pass.
#[test]
fn the_self_test_measures_the_clocks_against_the_hsi() {
    // The HSI over −40…105 °C: −8 % … +4.5 % (DS8626 Table 39).
    for hsi in [16e6, 16.16e6, 15.84e6, 16e6 * 0.92, 16e6 * 1.045] {
        let run = bring_up_with(
            Board {
                hsi_hz: hsi,
                ..Board::GOOD
            },
            0x1001,
        );
        let t = report(&run, Some((2, 2)));
        assert!(t.passed(), "{t:?}");
        assert_eq!(t.ran, bits::ALL);
        // The HSI's error maps 1:1 into the measurement (f_HSE = edges·16 MHz
        // / ticks with ticks counted at the true HSI); ±1 tick in 4096.
        let expect = 8e6 * 16e6 / hsi;
        let res = 2.0 / 4096.0;
        assert!(
            (f64::from(t.hse_hz) / expect - 1.0).abs() <= res,
            "HSE {} vs {expect}",
            t.hse_hz
        );
        // SYSCLK = 168 MHz true; derived from the measured HSE (×21).
        let s = 168e6 * 16e6 / hsi;
        assert!(
            (f64::from(t.sysclk_hz) / s - 1.0).abs() <= res,
            "SYSCLK {} vs {s}",
            t.sysclk_hz
        );
    }
    let run = bring_up_with(Board::GOOD, 0x1001);
    let stalled = report(&run, Some((5, 1)));
    assert_eq!(stalled.failed, bits::STREAMS_RUNNING);
}

/// Defect 8: prefetch off on revision A; the flash latency read back.
#[test]
fn prefetch_is_off_on_revision_a() {
    let run = bring_up_with(Board::GOOD, clocks::REV_A);
    assert_eq!(run.file.flash.get(rm::FLASH_ACR), 5 | (1 << 9) | (1 << 10));
    assert!(run.prepared.clock.latency_ok);
    assert!(!run.prepared.clock.prefetch);
}

/// Defects 2 and 8: priority bytes use the four implemented bits, and the
/// device's lock (BASEPRI at the DSP level) never masks the link or the
/// fault input.
#[test]
fn priorities_use_the_implemented_bits_and_the_lock_spares_the_link() {
    for level in 0..16u8 {
        assert_eq!(nvic::byte(level) & 0x0F, 0);
        assert_eq!(nvic::byte(level) >> 4, level);
    }
    // The firmware's table: the fault input above the link above the DSP;
    // the device's users all at its ceiling.
    use hardware::pac::Interrupt;
    let l = |i| nvic::level_of(i).unwrap();
    assert!(l(Interrupt::EXTI0) < l(Interrupt::USART2));
    assert!(l(Interrupt::USART2) < l(Interrupt::DMA1_STREAM5));
    assert_eq!(l(Interrupt::TIM6_DAC), nvic::LINK);
    assert_eq!(l(Interrupt::ADC), nvic::LINK);
    for i in nvic::DEVICE_USERS {
        assert_eq!(l(i), nvic::DSP);
    }
    // BASEPRI = b masks every priority byte ≥ b (ARMv7-M B1.5.4).
    let masks = |basepri: u8, prio: u8| prio >= basepri;
    let ceiling = nvic::byte(nvic::DSP);
    assert!(masks(ceiling, nvic::byte(nvic::DSP)));
    assert!(!masks(ceiling, nvic::byte(nvic::LINK)));
    assert!(!masks(ceiling, nvic::byte(nvic::FAULT_INPUT)));
    assert!(!masks(
        nvic::byte(nvic::LINK),
        nvic::byte(nvic::FAULT_INPUT)
    ));
}

/// The pickups' delay after the forces: 15 ADC cycles at 21 MHz.
#[test]
fn the_pickups_are_sampled_15_adc_clocks_after_the_forces() {
    assert_eq!(sampling::ADC_CLOCK_HZ, 21_000_000);
    assert_eq!(sampling::CONVERSION_CYCLES, 15);
    assert_eq!(sampling::PICKUP_DELAY_NS, 714);
    // The delay the device corrects is this scan's (one fact, two crates).
    let scan = f64::from(sampling::CONVERSION_CYCLES) / f64::from(sampling::ADC_CLOCK_HZ);
    assert_eq!(board::device::config::PICKUP_DELAY_S, scan);
    assert_eq!(
        board::device::DeviceConfig::driver_board(1).pickup_delay_s,
        scan
    );
}

/// Defect 5, alone: read right after the pull-up is switched on (no clock
/// start in between), the input still reads idle: `read_and_arm` waits out
/// the settling time itself.
#[test]
fn the_fault_input_waits_for_its_pull_up_when_read_at_once() {
    let file = File::new(0x1001);
    let sim = Sim::new(file, Board::GOOD);
    let mut delay = SimDelay(sim.clone());
    let regs = file.regs();
    let armed = fault_input::arm_pull_up(&regs);
    sim.borrow_mut().advance(0.6); // the old code's 100 cycles at 168 MHz
    let active = fault_input::read_and_arm(&regs, &clocks::Clocks::PLL, &mut delay, armed);
    assert!(!active, "an idle alarm line read as active");
    assert!(sim.borrow().t_us >= f64::from(fault_input::PULLUP_SETTLE_US));
}

/// Defect 7: crystals 25 % apart are told apart whatever the HSI's error
/// over temperature; a PLL that never locks leaves the board on the HSI.
#[test]
fn near_crystals_are_refused_and_a_pll_that_never_locks_times_out() {
    for (hse, hsi) in [
        (10e6, 16e6 * 1.045),
        (10e6, 16e6 * 0.92),
        (6e6, 16e6 * 0.92),
    ] {
        let run = bring_up_with(
            Board {
                hse_hz: Some(hse),
                hsi_hz: hsi,
                ..Board::GOOD
            },
            0x1001,
        );
        let t = report(&run, None);
        assert_eq!(
            t.failed,
            bits::HSE_FREQUENCY,
            "{hse} Hz crystal, HSI {hsi} Hz"
        );
        assert_eq!(run.file.rcc.get(rm::RCC_CFGR) & 3, 0, "still on the HSI");
    }
    let run = bring_up_with(
        Board {
            pll_locks: false,
            ..Board::GOOD
        },
        0x1001,
    );
    let f = run.file;
    assert_eq!(f.rcc.get(rm::RCC_CFGR) & 0xF, 0, "SW = SWS = HSI");
    assert_eq!(
        f.rcc.get(rm::RCC_CR) & (1 << 24 | 1 << 16),
        0,
        "PLL and HSE off"
    );
    assert!(!run.prepared.clock.ready);
    let t = report(&run, None);
    assert_eq!(t.failed, bits::CLOCK_READY);
    assert!(t.hse_hz > 0, "the crystal was measured before the PLL");
}

/// The build-time crystal's parser, the capture divider, the DMA buffer's
/// arithmetic and the capture's conversion, against hand values.
#[test]
fn small_arithmetic_against_hand_values() {
    assert_eq!(clocks::parse_hz("8000000"), 8_000_000);
    assert_eq!(clocks::parse_hz("12000000"), 12_000_000);
    assert_eq!(clocks::parse_hz("4294967295"), u32::MAX);
    for bad in ["", "12a", "-1", "4294967296", "8 000 000"] {
        assert!(
            std::panic::catch_unwind(|| clocks::parse_hz(bad)).is_err(),
            "{bad:?}"
        );
    }
    // HSE/RTCPRE ≤ 1 MHz, the least divider, within 2…31.
    assert_eq!(clocks::rtcpre_for(4_000_000), 4);
    assert_eq!(clocks::rtcpre_for(8_000_000), 8);
    assert_eq!(clocks::rtcpre_for(8_000_001), 9);
    assert_eq!(clocks::rtcpre_for(1_000_000), 2);
    assert_eq!(clocks::rtcpre_for(26_000_000), 26);
    assert_eq!(clocks::rtcpre_for(40_000_000), 31);
    // 256 edges over 4 096 ticks of 16 MHz: 1 MHz exactly; rounded to the
    // nearest Hz (2 560 / 3 = 853.3).
    assert_eq!(clocks::source_hz(4096, 16_000_000), 1_000_000);
    assert_eq!(clocks::source_hz(3, 10), 853);
    assert_eq!(clocks::source_hz(3, 11), 939); // 2 816 / 3 = 938.67
    assert_eq!(clocks::source_hz(6, 10), 427); // 2 560 / 6 = 426.67
    let b = DmaBuffer {
        addr: 0x2000_0000,
        words: 128,
    };
    assert_eq!(b.half_words(), 64);
    assert!(b.contains(0x2000_0000));
    assert!(b.contains(0x2000_01FC));
    assert!(!b.contains(0x2000_0200), "one past the last word");
    assert!(!b.contains(0x1FFF_FFFC));
    assert_eq!(DAC_WORDS, 128);
    assert_eq!(ADC_WORDS, 256);
}

/// The runtime helpers of the handlers and the loop, on the register file.
#[test]
fn link_watchdog_and_fault_input_helpers() {
    let f = File::new(0x1001);
    let r = f.regs();
    use hardware::usart;
    // USART_SR: RXNE bit 5, ORE bit 3, TXE bit 7; DR at 0x04; CR1 TXEIE bit 7.
    assert_eq!(usart::take_rx(&r), None);
    f.usart2.set(0x04, 0x5A);
    f.usart2.set(0x00, 1 << 5);
    assert_eq!(usart::take_rx(&r), Some((0x5A, false)));
    f.usart2.set(0x00, 1 << 3);
    assert_eq!(
        usart::take_rx(&r),
        Some((0x5A, true)),
        "an overrun still yields its byte"
    );
    f.usart2.set(0x00, 0);
    assert!(!usart::tx_empty(&r));
    f.usart2.set(0x00, 1 << 7);
    assert!(usart::tx_empty(&r));
    usart::tx_write(&r, 0xA5);
    assert_eq!(f.usart2.get(0x04), 0xA5);
    usart::tx_interrupt(&r, true);
    assert_eq!(f.usart2.get(rm::USART_CR1) & (1 << 7), 1 << 7);
    usart::tx_interrupt(&r, false);
    assert_eq!(f.usart2.get(rm::USART_CR1) & (1 << 7), 0);
    // IWDG feed key; RCC_CSR WDGRSTF (bit 29) read, RMVF (bit 24) written.
    watchdog::feed(&r);
    assert_eq!(f.iwdg.get(rm::IWDG_KR), 0xAAAA);
    assert!(!watchdog::take_reset_flag(&r));
    f.rcc.set(0x74, 1 << 29);
    assert!(watchdog::take_reset_flag(&r));
    assert_eq!(f.rcc.get(0x74) & (1 << 24), 1 << 24);
    // EXTI_PR bit 0: pending, cleared by writing 1.
    assert!(!fault_input::take_pending(&r));
    f.exti.set(0x14, 1);
    assert!(fault_input::take_pending(&r));
    assert_eq!(f.exti.get(0x14), 1, "written 1 to clear");
}

/// The self-test's `dma_setup` fails for each field that does not read
/// back; `stop` halts the sample clock and holds the DAC.
#[test]
fn a_stream_that_does_not_read_back_fails_and_stop_halts_the_clock() {
    let bufs = buffers();
    for (what, off, bad) in [
        ("NDTR", rm::sxndtr(5), 127),
        ("M0AR", rm::sxm0ar(5), DAC_ADDR + 4),
        ("PAR", rm::sxpar(5), 0x4000_7408),
        ("CHSEL", rm::sxcr(5), 0x0E03_555F & !(7 << 25)),
        ("EN", rm::sxcr(5), 0x0E03_555E),
        ("CIRC", rm::sxcr(5), 0x0E03_555F & !(1 << 8)),
    ] {
        let run = bring_up_with(Board::GOOD, 0x1001);
        let regs = run.file.regs();
        assert!(streams::streams_read_back(&regs, &bufs.dac, &bufs.adc));
        run.file.dma1.set(off, bad);
        assert!(
            !streams::streams_read_back(&regs, &bufs.dac, &bufs.adc),
            "{what}"
        );
    }
    let run = bring_up_with(Board::GOOD, 0x1001);
    run.file.dma2.set(rm::sxndtr(0), 255);
    assert!(!streams::streams_read_back(
        &run.file.regs(),
        &bufs.dac,
        &bufs.adc
    ));
    let regs = run.file.regs();
    assert_eq!(run.file.tim2.get(rm::TIM_CR1) & 1, 1);
    sampling::stop(&regs, 0x0800_0100);
    assert_eq!(
        run.file.tim2.get(rm::TIM_CR1) & 1,
        0,
        "sample clock stopped"
    );
    assert_eq!(run.file.dac.get(rm::DAC_DHR12RD), 0x0800_0100);
    assert_eq!(run.file.dma1.get(rm::sxcr(5)) & 1, 0);
}

/// `can_sample` before the start; a capture that never comes, or comes
/// with no time between edges, measures nothing.
#[test]
fn the_start_needs_a_good_bring_up_and_a_dead_capture_measures_nothing() {
    let file = File::new(0x1001);
    let sim = Sim::new(file, Board::GOOD);
    let mut delay = SimDelay(sim.clone());
    let regs = file.regs();
    let mut p = bring_up::prepare(&regs, &buffers(), &mut delay, &mut |_, _| {});
    assert!(p.can_sample());
    assert!(bring_up::start_sampling(&regs, &mut p, &mut |_, _| {}));
    assert!(p.sampling);
    assert!(
        !bring_up::start_sampling(&regs, &mut p, &mut |_, _| {}),
        "only once"
    );
    // A register file with nothing behind it: CC1IF never sets.
    let quiet = File::new(0x1001);
    let mut d = SimDelay(Sim::new(quiet, Board::GOOD));
    assert_eq!(
        clocks::capture_hse_rtc(&quiet.regs(), &mut d, 16_000_000),
        None
    );
    // CC1IF stuck at 1 with a constant CCR1: zero ticks, no frequency.
    let stuck = File::new(0x1001);
    stuck.tim11.set(rm::TIM_SR, 0b10);
    stuck.tim11.set(rm::TIM_CCR1, 1234);
    let mut d = SimDelay(Sim::new(stuck, Board::GOOD));
    // The first capture is read and cleared; no second one comes: nothing.
    assert_eq!(
        clocks::capture_hse_rtc(&stuck.regs(), &mut d, 16_000_000),
        None
    );
}

/// The `sysclk` check: PLL factors that do not read back as written.
#[test]
fn pll_factors_that_do_not_read_back_fail_the_sysclk_check() {
    let run = bring_up_with(
        Board {
            pllcfgr_drifts: true,
            ..Board::GOOD
        },
        0x1001,
    );
    let t = report(&run, Some((2, 2)));
    assert_eq!(
        t.sysclk_hz, 0,
        "not derived from factors that did not read back"
    );
    assert_eq!(t.failed, bits::SYSCLK);
}
