//! The clock tree (RM0090 §6): SYSCLK = 168 MHz from the crystal (HSE)
//! through the main PLL, for any crystal the board carries, and the check
//! that it really runs at that speed.
//!
//! **The crystal is a build-time setting**: `FIRMWARE_HSE_HZ` in the
//! environment of the firmware's build (8 MHz when unset; the pyboard and
//! the Feather F405 carry 12 MHz). [`PllConfig::for_hse`] turns it into PLL
//! factors with every range RM0090 §6.3.2 states asserted at compile time:
//! f_HSE in 4–26 MHz, the VCO input f_HSE/M in 1–2 MHz (2 MHz preferred, it
//! lowers the PLL's jitter), the VCO output in 100–432 MHz with
//! 50 ≤ N ≤ 432, SYSCLK = VCO/P ≤ 168 MHz with P ∈ {2, 4, 6, 8}, and the USB
//! clock VCO/Q = 48 MHz with 2 ≤ Q ≤ 15. A crystal that gives no exact
//! 168 MHz fails the build.
//!
//! **Every wait has a time-out** ([`crate::wait_until`]): HSE ready within
//! [`HSE_TIMEOUT_US`], PLL lock within [`PLL_TIMEOUT_US`], the switch within
//! [`SWITCH_TIMEOUT_US`]. A dead crystal leaves the core on the internal
//! 16 MHz HSI with the PLL off ([`ClockOutcome::clocks`] says which), and the
//! self-test reports it; the bring-up never hangs.
//!
//! **The frequencies are measured** against the HSI (factory-trimmed to ±1 %
//! at 25 °C, −8 %/+4.5 % over −40…105 °C, datasheet DS8626 Table 39):
//! TIM11's channel 1 can capture HSE/RTCPRE (TIM11_OR.RMP = 10, RM0090
//! §19.5), with the HSI as the system clock. That measures the crystal
//! before the PLL starts; a crystal outside the HSI's tolerance of the
//! build's `HSE_HZ` ([`within_tolerance`]: a 12 MHz crystal on an 8 MHz
//! build would run the core at 252 MHz) keeps the PLL off. SYSCLK is then
//! *derived*, not measured: the measured crystal times N/(M·P), with the
//! PLL's factors read back from RCC_PLLCFGR and SWS showing the PLL.
//!
//! **Flash**: 5 wait states for 150 < HCLK ≤ 168 MHz at 2.7–3.6 V (RM0090
//! Table 10), read back before the switch (a latency that did not take
//! would crash the core at 168 MHz: then the PLL is not selected).
//! Instruction and data caches on; prefetch on, except on revision A
//! silicon (DBGMCU_IDCODE.REV_ID = 0x1000), where errata ES0182 §2.1.9
//! requires it off.

use crate::{wait_until, Delay, Registers};

/// The internal RC oscillator, Hz.
pub const HSI_HZ: u32 = 16_000_000;
/// The core clock the board runs at, Hz.
pub const SYSCLK_HZ: u32 = 168_000_000;
/// The USB/SDIO clock the PLL's Q output must give, Hz.
pub const PLL48_HZ: u32 = 48_000_000;
/// The crystal's frequency, Hz: `FIRMWARE_HSE_HZ` at build time, 8 MHz
/// when unset.
pub const HSE_HZ: u32 = match option_env!("FIRMWARE_HSE_HZ") {
    Some(s) => parse_hz(s),
    None => 8_000_000,
};
/// The PLL factors for [`HSE_HZ`] (checked at compile time).
pub const PLL: PllConfig = PllConfig::for_hse(HSE_HZ);
/// Flash wait states at 168 MHz, 2.7–3.6 V (RM0090 Table 10).
pub const FLASH_LATENCY: u8 = 5;
/// HSE start-up time-out, µs (the datasheet's typical start-up is 2 ms;
/// ST's own default is 100 ms, well inside the watchdog's 0.7 s).
pub const HSE_TIMEOUT_US: u32 = 100_000;
/// PLL lock time-out, µs (lock takes ≈ 100–300 µs).
pub const PLL_TIMEOUT_US: u32 = 2_000;
/// Clock-switch time-out, µs (a few clock cycles).
pub const SWITCH_TIMEOUT_US: u32 = 100;
/// How much slower than its nominal 16 MHz the HSI may run, in 0.1 %:
/// −8 % over −40…105 °C (DS8626 Table 39, ±1 % only at 25 °C), plus the
/// capture's resolution (±2 ticks in 4 096 = 0.05 %) and margin: 8.5 %.
pub const HSI_SLOW_PERMILLE: u32 = 85;
/// How much faster it may run: +4.5 % over temperature, plus the same: 5 %.
pub const HSI_FAST_PERMILLE: u32 = 50;
/// DBGMCU_IDCODE.REV_ID of revision A silicon.
pub const REV_A: u16 = 0x1000;

/// `s` as a decimal number of Hz, in a constant (a build-time setting).
///
/// # Panics
/// (At compile time for a constant.) An empty string, a character that is
/// not a digit, or a value above `u32::MAX`.
pub const fn parse_hz(s: &str) -> u32 {
    let b = s.as_bytes();
    assert!(!b.is_empty(), "FIRMWARE_HSE_HZ is empty");
    let mut v: u64 = 0;
    let mut i = 0;
    while i < b.len() {
        let d = b[i];
        assert!(
            d >= b'0' && d <= b'9',
            "FIRMWARE_HSE_HZ must be a whole number of Hz"
        );
        v = v * 10 + (d - b'0') as u64;
        assert!(v <= u32::MAX as u64, "FIRMWARE_HSE_HZ is too large");
        i += 1;
    }
    v as u32
}

/// Main PLL factors (RCC_PLLCFGR, RM0090 §6.3.2).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PllConfig {
    /// Input division: VCO input = f_HSE / M (2 ≤ M ≤ 63).
    pub m: u8,
    /// VCO multiplication (50 ≤ N ≤ 432).
    pub n: u16,
    /// SYSCLK division (2, 4, 6 or 8).
    pub p: u8,
    /// USB clock division (2 ≤ Q ≤ 15).
    pub q: u8,
}

impl PllConfig {
    /// The factors that give [`SYSCLK_HZ`] and [`PLL48_HZ`] from a crystal
    /// of `hse_hz`, with the highest VCO input in 1–2 MHz (least jitter).
    ///
    /// # Panics
    /// (At compile time for a constant.) A crystal outside 4–26 MHz, or one
    /// from which no factors give exactly 168 and 48 MHz within the ranges.
    pub const fn for_hse(hse_hz: u32) -> PllConfig {
        assert!(
            hse_hz >= 4_000_000 && hse_hz <= 26_000_000,
            "HSE must be 4-26 MHz"
        );
        let mut m = 2u32;
        while m <= 63 {
            let vin = hse_hz / m;
            if hse_hz % m == 0 && vin >= 1_000_000 && vin <= 2_000_000 {
                // SYSCLK = vin·N/P with P = 2, the VCO at 336 MHz.
                let vco = 2 * SYSCLK_HZ;
                if vco % vin == 0 {
                    let n = vco / vin;
                    let q = vco / PLL48_HZ;
                    if n >= 50 && n <= 432 && vco % PLL48_HZ == 0 && q >= 2 && q <= 15 {
                        assert!(vco >= 100_000_000 && vco <= 432_000_000);
                        return PllConfig {
                            m: m as u8,
                            n: n as u16,
                            p: 2,
                            q: q as u8,
                        };
                    }
                }
            }
            m += 1;
        }
        panic!("no PLL factors give 168 MHz from this HSE");
    }

    /// SYSCLK these factors give from `hse_hz`, Hz.
    pub const fn sysclk_hz(&self, hse_hz: u32) -> u32 {
        (hse_hz as u64 * self.n as u64 / self.m as u64 / self.p as u64) as u32
    }
}

/// The bus clocks in force.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Clocks {
    /// Core clock (= HCLK), Hz.
    pub sysclk_hz: u32,
    /// APB1 clock (USART2), Hz.
    pub pclk1_hz: u32,
    /// APB1 timer clock (TIM2), Hz: 2·PCLK1 when APB1 is divided (§6.2).
    pub tim_apb1_hz: u32,
    /// APB2 timer clock (TIM11), Hz.
    pub tim_apb2_hz: u32,
}

impl Clocks {
    /// After reset: HSI, no prescalers.
    pub const HSI: Clocks = Clocks {
        sysclk_hz: HSI_HZ,
        pclk1_hz: HSI_HZ,
        tim_apb1_hz: HSI_HZ,
        tim_apb2_hz: HSI_HZ,
    };
    /// The PLL at 168 MHz: AHB /1, APB1 /4 (42 MHz), APB2 /2 (84 MHz).
    pub const PLL: Clocks = Clocks {
        sysclk_hz: SYSCLK_HZ,
        pclk1_hz: SYSCLK_HZ / 4,
        tim_apb1_hz: SYSCLK_HZ / 2,
        tim_apb2_hz: SYSCLK_HZ,
    };
}

/// What [`start`] achieved.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ClockOutcome {
    /// The clocks in force afterwards ([`Clocks::PLL`] or [`Clocks::HSI`]).
    pub clocks: Clocks,
    /// Every oscillator started was ready within its time-out: the crystal,
    /// and where they were started the PLL and the switch (a crystal of the
    /// wrong frequency is ready: [`ClockOutcome::hse_hz`] tells).
    pub ready: bool,
    /// The crystal measured against the HSI, Hz (`None`: not measured).
    pub hse_hz: Option<u32>,
    /// SYSCLK derived from the measured crystal and the PLL factors read
    /// back, Hz (`None`: the PLL is not in use, or did not read back).
    pub sysclk_hz: Option<u32>,
    /// FLASH_ACR read back the latency written.
    pub latency_ok: bool,
    /// Prefetch was enabled (off on revision A).
    pub prefetch: bool,
}

impl ClockOutcome {
    /// The clocks after reset, before anything was started or measured.
    pub const RESET: ClockOutcome = ClockOutcome {
        clocks: Clocks::HSI,
        ready: false,
        hse_hz: None,
        sysclk_hz: None,
        latency_ok: false,
        prefetch: false,
    };
}

/// Whether a frequency measured against the HSI, `measured`, can be
/// `expected`: an HSI slow by up to [`HSI_SLOW_PERMILLE`] reads it high by
/// up to 1/(1 − 0.085) = +9.3 %, a fast one low by up to 1/1.05 = −4.8 %.
/// Crystals 25 % apart (8/10, 12/16, 16/20 MHz) are told apart; 24 and
/// 25 MHz (4 %) are not.
pub fn within_tolerance(measured: u32, expected: u32) -> bool {
    let (m, e) = (u64::from(measured), u64::from(expected));
    m * (1000 + u64::from(HSI_FAST_PERMILLE)) >= e * 1000
        && m * (1000 - u64::from(HSI_SLOW_PERMILLE)) <= e * 1000
}

/// RTCPRE for the measurement with a crystal of `hse_hz`: HSE/RTCPRE ≤ 1 MHz,
/// the least such divider within its field's 2 ≤ RTCPRE ≤ 31.
pub const fn rtcpre_for(hse_hz: u32) -> u8 {
    let p = hse_hz.div_ceil(1_000_000);
    if p < 2 {
        2
    } else if p > 31 {
        31
    } else {
        p as u8
    }
}

/// RTCPRE for [`HSE_HZ`].
pub const RTCPRE: u8 = rtcpre_for(HSE_HZ);
/// Input-capture events per measurement: [`CAPTURES`] captures of 8 edges
/// each (IC1PSC = /8).
pub const CAPTURES: u32 = 32;
/// Edges per capture (IC1PSC = 11).
pub const EDGES_PER_CAPTURE: u32 = 8;

/// Timer ticks over [`CAPTURES`]·[`EDGES_PER_CAPTURE`] edges of HSE/RTCPRE
/// on TIM11 (input capture of the remapped HSE_RTC, RM0090 §19.5); `None`
/// if a capture does not come within 1 ms or one was missed (CC1OF).
pub fn capture_hse_rtc(r: &Registers, delay: &mut impl Delay, sysclk_hz: u32) -> Option<u32> {
    let t = r.tim11;
    t.cr1().write(|w| w.cen().disabled());
    t.psc().write(|w| w.psc().set(0));
    t.arr().write(|w| w.arr().set(0xFFFF));
    // SAFETY: RMP is a 2-bit field; 0b10 = HSE_RTC (RM0090 §19.5).
    t.or().write(|w| unsafe { w.rmp().bits(0b10) });
    t.ccmr1_input()
        .write(|w| w.cc1s().ti1().ic1psc().eight_events().ic1f().no_filter());
    t.ccer()
        .write(|w| w.cc1e().set_bit().cc1p().clear_bit().cc1np().clear_bit());
    t.sr().write(|w| w.cc1if().clear_bit().cc1of().clear_bit());
    t.cr1().write(|w| w.cen().enabled());
    let mut next = || -> Option<u16> {
        if !wait_until(delay, sysclk_hz, 1, 1_000, || {
            t.sr().read().cc1if().bit_is_set()
        }) {
            return None;
        }
        let c = t.ccr1().read().bits() as u16;
        let missed = t.sr().read().cc1of().bit_is_set();
        t.sr().write(|w| w.cc1if().clear_bit().cc1of().clear_bit());
        (!missed).then_some(c)
    };
    let first = next();
    let mut ticks = 0u32;
    let mut prev = first;
    for _ in 0..CAPTURES {
        let c = next();
        match (prev, c) {
            (Some(a), Some(b)) => ticks += u32::from(b.wrapping_sub(a)),
            _ => {
                prev = None;
                break;
            }
        }
        prev = c;
    }
    t.cr1().write(|w| w.cen().disabled());
    t.ccer().write(|w| w.cc1e().clear_bit());
    (prev.is_some() && ticks > 0).then_some(ticks)
}

/// The frequency of the captured source, Hz, from the ticks of
/// [`capture_hse_rtc`] at a timer clock of `timer_hz`.
pub fn source_hz(ticks: u32, timer_hz: u32) -> u32 {
    let edges = u64::from(CAPTURES * EDGES_PER_CAPTURE);
    ((edges * u64::from(timer_hz) + u64::from(ticks) / 2) / u64::from(ticks)) as u32
}

/// Starts the crystal, measures it, starts the PLL and switches to it
/// (module docs). Never waits without a time-out; on any failure the core
/// stays on the HSI with the PLL and HSE off.
pub fn start(r: &Registers, delay: &mut impl Delay) -> ClockOutcome {
    let rcc = r.rcc;
    let mut out = ClockOutcome::RESET;
    let back_to_hsi = |out: ClockOutcome| {
        rcc.cfgr().modify(|_, w| w.sw().hsi());
        rcc.cr().modify(|_, w| w.pllon().off().hseon().off());
        out
    };
    rcc.cr().modify(|_, w| w.hseon().on());
    if !wait_until(delay, HSI_HZ, 10, HSE_TIMEOUT_US, || {
        rcc.cr().read().hserdy().is_ready()
    }) {
        return back_to_hsi(out);
    }
    // The crystal against the HSI: TIM11 on APB2 at HSI (no prescaler yet).
    rcc.apb2enr().modify(|_, w| w.tim11en().enabled());
    // SAFETY: RTCPRE is 2..=31 (asserted in its constant).
    rcc.cfgr().modify(|_, w| unsafe { w.rtcpre().bits(RTCPRE) });
    out.hse_hz = capture_hse_rtc(r, delay, HSI_HZ)
        .map(|t| source_hz(t, Clocks::HSI.tim_apb2_hz) * u32::from(RTCPRE));
    if !out.hse_hz.is_some_and(|f| within_tolerance(f, HSE_HZ)) {
        out.ready = true; // the crystal started; it is the wrong one.
        return back_to_hsi(out);
    }
    // SAFETY: the factors' ranges are asserted in `PllConfig::for_hse`.
    rcc.pllcfgr().write(|w| unsafe {
        w.pllm()
            .bits(PLL.m)
            .plln()
            .bits(PLL.n)
            .pllp()
            .div2()
            .pllq()
            .bits(PLL.q)
            .pllsrc()
            .hse()
    });
    const _: () = assert!(PLL.p == 2);
    rcc.cr().modify(|_, w| w.pllon().on());
    if !wait_until(delay, HSI_HZ, 10, PLL_TIMEOUT_US, || {
        rcc.cr().read().pllrdy().is_ready()
    }) {
        return back_to_hsi(out);
    }
    let rev = r.dbgmcu.idcode().read().rev_id().bits();
    out.prefetch = rev != REV_A;
    // SAFETY: LATENCY is a 3-bit field (0..=7 wait states).
    r.flash.acr().write(|w| unsafe {
        w.latency()
            .bits(FLASH_LATENCY)
            .icen()
            .set_bit()
            .dcen()
            .set_bit()
            .prften()
            .bit(out.prefetch)
    });
    out.latency_ok = r.flash.acr().read().latency().bits() == FLASH_LATENCY;
    if !out.latency_ok {
        return back_to_hsi(out);
    }
    // The bus prescalers first: they take effect 1–16 AHB cycles later
    // (RM0090 §6.3.3), and APB1 must never see more than 42 MHz.
    rcc.cfgr()
        .modify(|_, w| w.hpre().div1().ppre1().div4().ppre2().div2());
    delay.wait_us(1, HSI_HZ);
    rcc.cfgr().modify(|_, w| w.sw().pll());
    if !wait_until(delay, SYSCLK_HZ, 1, SWITCH_TIMEOUT_US, || {
        rcc.cfgr().read().sws().is_pll()
    }) {
        return back_to_hsi(out);
    }
    out.ready = true;
    out.clocks = Clocks::PLL;
    // SYSCLK from the measured crystal and the factors as read back.
    let p = rcc.pllcfgr().read();
    let read_back = PllConfig {
        m: p.pllm().bits(),
        n: p.plln().bits(),
        p: 2 * (p.pllp().bits() + 1),
        q: p.pllq().bits(),
    };
    let hse = out.hse_hz.unwrap_or(0);
    out.sysclk_hz = (read_back == PLL && hse != 0).then(|| read_back.sysclk_hz(hse));
    out
}

/// Keeps the debugger usable: HCLK runs on in sleep (DBG_SLEEP: a probe can
/// attach while the core waits in `WFI`; it costs the sleep's power saving,
/// which this board does not need) and the watchdog stops while the core is
/// halted (DBG_IWDG_STOP; no effect without a debugger) (RM0090 §38.16.3).
/// With DBG_SLEEP set, errata ES0182 §2.1.3 asks for no instruction right
/// after `WFI` that the debugger's resumption could mis-execute: the
/// firmware's `WFI` is followed by three `NOP`s.
pub fn debug_freeze(r: &Registers) {
    r.dbgmcu.cr().modify(|_, w| w.dbg_sleep().set_bit());
    r.dbgmcu
        .apb1_fz()
        .modify(|_, w| w.dbg_iwdg_stop().set_bit());
}
