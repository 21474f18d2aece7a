//! Cost of one model prediction on the Cortex-M4F (f32, exact solver), for
//! QEMU: `qemu-system-arm -machine netduinoplus2 -icount shift=0 … -kernel predict_cost`.
//! With `-icount shift=0` each instruction advances virtual time by 1 ns, and
//! SysTick counts virtual time at the core clock; a block of exactly 1000
//! `nop`s calibrates ticks per instruction. Prints instruction counts through
//! semihosting and exits with status 0 — or 1 if a critical section of the
//! protocol server exceeds its bound (below). (QEMU has no DWT cycle counter, and
//! its instruction count ignores pipeline and flash wait states: on the chip a
//! cycle count is ≈ 1–1.5× this.)
//!
//! Reports one f32 prediction as the device computes it today (`device::predict`,
//! libm backend), the same computation with the libm and the float-native
//! `FastF32` backend side by side, the cost of each transcendental function of
//! both backends, and the CPU share of one prediction per control period at
//! 1 kHz and 10 kHz next to the DDS refill's share at 500 kS/s (168 MHz core,
//! one instruction per cycle: a lower bound on the share). And the server's
//! critical sections (issue 42): one request of each kind through a
//! `DeviceAccess` that times every `with` closure, each against its bound
//! (`CRITICAL_BOUND`, 10 % of a half-buffer; the stated exception
//! `PLANNING_BOUND` for the drive-planning requests).
#![no_std]
#![no_main]

mod everything;

use board::device;
use cortex_m::peripheral::{syst::SystClkSource, SYST};
use cortex_m_rt::entry;
use cortex_m_semihosting::{debug, hprintln};
use defmt_rtt as _;
use model_core::analytic::CriticalVelocity;
use model_core::exact::{self, Solution};
use model_core::float::FastF32;
use model_core::{Libm, Math, Scene, SceneParams};
use panic_probe as _;
// Link the device crate for its interrupt vector table.
use stm32f4 as _;

fn ticks(f: impl FnOnce()) -> u32 {
    timed(f).1
}

/// `f`'s result and the SysTick ticks it took (24-bit down-counter). The
/// fences and `black_box` keep the work between the two reads: with the
/// DSP crates at opt-level 3, plain memory operations (a 1.2 KB copy)
/// could otherwise move across the counter's volatile reads.
fn timed<R>(f: impl FnOnce() -> R) -> (R, u32) {
    use core::sync::atomic::{compiler_fence, Ordering::SeqCst};
    let t0 = SYST::get_current();
    compiler_fence(SeqCst);
    let r = core::hint::black_box(f());
    compiler_fence(SeqCst);
    let t1 = SYST::get_current();
    (r, t0.wrapping_sub(t1) & 0x00FF_FFFF)
}

/// Exactly 1000 `nop`s (in their own function, so no literal pool spans them).
#[inline(never)]
fn nops_1000() {
    // SAFETY: `nop` has no effect.
    unsafe { core::arch::asm!(".rept 1000", "nop", ".endr", options(nomem, nostack)) }
}

/// What `device::predict` computes (critical velocities and the exact
/// solver's μ/μ₀), with a chosen backend.
#[inline(never)]
fn predict_with<M: Math<f32>>(scene: &Scene<f32>, v0: f32) -> Option<(f32, f32, f32)> {
    let (solution, vc) = exact::solve_with_critical::<f32, M>(scene, v0).ok()?;
    let m = match solution {
        Solution::Sliding { mu_over_mu0 } | Solution::StickSlip { mu_over_mu0 } => mu_over_mu0,
        Solution::AtRest { mu_0plus, .. } => mu_0plus,
    };
    Some((m, vc.forward, vc.backward))
}

/// Mean and worst instruction count of one prediction with backend `M` over
/// 16 velocities in (−0.95 v_c, 0.95 v_c); `None` if one fails.
fn predict_cost<M: Math<f32>>(
    scene: &Scene<f32>,
    vc: &CriticalVelocity<f32>,
    empty: u32,
    per_insn: f32,
) -> Option<(u32, u32)> {
    let (mut worst, mut sum) = (0u32, 0u32);
    let n = 16;
    for i in 0..n {
        let x = -0.95 + 1.9 * (i as f32 + 0.5) / n as f32;
        let v = core::hint::black_box(x * if x > 0.0 { vc.forward } else { vc.backward });
        let mut out = None;
        let t = ticks(|| out = predict_with::<M>(scene, v)).saturating_sub(empty);
        out?;
        let insn = (t as f32 / per_insn) as u32;
        worst = worst.max(insn);
        sum += insn;
    }
    Some((sum / n, worst))
}

/// Mean instruction count of one call of `f` over 16 arguments `arg(i)`
/// (the loop's own cost, measured with an identity `f`, subtracted by the caller).
fn fn_cost(empty: u32, per_insn: f32, arg: fn(f32) -> f32, f: fn(f32) -> f32) -> f32 {
    let mut sum = 0u32;
    for i in 0..16 {
        let x = core::hint::black_box(arg(i as f32 / 16.0));
        let t = ticks(|| {
            core::hint::black_box(f(x));
        })
        .saturating_sub(empty);
        sum += t;
    }
    sum as f32 / 16.0 / per_insn
}

#[inline(never)]
fn id(x: f32) -> f32 {
    x
}

/// One ADC block's integer pass (issue 35, `board::reference`): the
/// reference of 64 samples (eq. R1), one pair of signals' sums against it
/// (the forces, or the pickups), the reference's Gram sums (the pickups'
/// lock-ins only).
fn intake_costs(table: &board::dds::SineTable<1024>, empty: u32, per_insn: f32) {
    use board::reference::{Gram, PairSums, Reference};
    let pairs = core::hint::black_box([(2000u16, 3000u16); 64]);
    let mut r = None;
    let t1 = ticks(|| {
        r = Some(core::hint::black_box(Reference::new(
            table,
            12_345,
            171_798_692,
            64,
        )))
    });
    let Some(r) = r else { return };
    let w = core::hint::black_box(r.words());
    let t2 = ticks(|| {
        core::hint::black_box(PairSums::of(w, &pairs));
    });
    let t3 = ticks(|| {
        core::hint::black_box(Gram::of(w));
    });
    let n = |t: u32| (t.saturating_sub(empty) as f32 / per_insn) as u32;
    hprintln!(
        "ADC block's pass (64 samples): reference (R1) {} instructions ({} per sample); a pair of signals' sums {} ({} per sample); the Gram sums {} ({} per sample)",
        n(t1),
        n(t1) / 64,
        n(t2),
        n(t2) / 64,
        n(t3),
        n(t3) / 64
    );
}

/// The longest critical section the server may hold: 10 % of a half-buffer
/// (64 samples at 500 kS/s = 128 µs = 21 504 cycles at 168 MHz). Every
/// `DeviceAccess::with` closure runs with the DMA handlers masked; one longer
/// than this delays a refill by as much (issue 42: late handlers latch
/// `dac_underrun` / `adc_overrun`). No request may form a `Scene` inside
/// (`Scene::new` alone is ≈ 4 200 instructions; it was ≈ 22 000).
const CRITICAL_BOUND: u32 = 2_150;

/// A stated exception to [`CRITICAL_BOUND`], not a silent one (issue 42,
/// reported, not yet reduced): the requests that plan a drive inside the
/// device — `SetDrive`, `SetDriveMode`, `Start`: the whole validation, the
/// DDS tuning and phase words in soft-float f64 (`Dds::plan_frequency`
/// ≈ 880 instructions, `phase_word` ≈ 620, each more than once per
/// request), in displacement mode the voltage plan. Measured 2 900 – 7 370
/// instructions (14 – 34 % of a half-buffer); the bound catches a scene or
/// another long computation brought back into them.
const PLANNING_BOUND: u32 = 8_000;

/// A `DeviceAccess` that times every `with` closure (as the firmware's
/// critical sections run them, without the masking): the longest and the
/// number of calls since [`Timed::take`].
struct Timed<'d, 't> {
    dev: &'d mut board::device::Device<'t, 1024>,
    /// Ticks of an empty `timed` call.
    empty: u32,
    longest: u32,
    calls: u32,
}

impl Timed<'_, '_> {
    /// The longest `with` (ticks) and the calls since the last `take`.
    fn take(&mut self) -> (u32, u32) {
        let r = (self.longest, self.calls);
        self.longest = 0;
        self.calls = 0;
        r
    }
}

impl<'t> board::server::DeviceAccess<1024> for Timed<'_, 't> {
    fn with<R>(&mut self, f: impl FnOnce(&mut board::device::Device<'_, 1024>) -> R) -> R {
        let dev = &mut *self.dev;
        let (r, t) = timed(|| f(dev));
        self.longest = self.longest.max(t.saturating_sub(self.empty));
        self.calls += 1;
        r
    }
}

/// The longest critical section of a class of requests and which one.
#[derive(Clone, Copy)]
struct Longest {
    insn: u32,
    label: &'static str,
}

impl Longest {
    const NONE: Longest = Longest {
        insn: 0,
        label: "none",
    };

    fn note(&mut self, insn: u32, label: &'static str) {
        if insn > self.insn {
            *self = Longest { insn, label };
        }
    }

    fn percent(&self) -> f32 {
        self.insn as f32 * 100.0 / 21_504.0
    }
}

/// The server driven through [`Timed`]: requests, half-buffers, polls, and
/// the longest critical sections so far.
struct Bench<'d, 't> {
    acc: Timed<'d, 't>,
    server: board::server::Server,
    seq: u32,
    per_insn: f32,
    /// Longest `with` of all, of the requests under [`CRITICAL_BOUND`], of
    /// those under [`PLANNING_BOUND`], and of the polls.
    all: Longest,
    bounded: Longest,
    planning: Longest,
    poll: Longest,
    /// Every request stayed within its bound, and every one meant to be
    /// accepted was.
    ok: bool,
    dac: [u32; 64],
    forces: [(u16, u16); 64],
    pick: [(u16, u16); 64],
}

impl Bench<'_, '_> {
    fn insn(&self, t: u32) -> u32 {
        (t as f32 / self.per_insn) as u32
    }

    /// One request through the server (framed with the protocol's encoding,
    /// as the main loop feeds the received bytes): its answer; prints the
    /// longest `with` it took, judged against `bound`. `must_pass`: a
    /// refusal fails the run (its path would not have been measured).
    fn call(
        &mut self,
        label: &'static str,
        r: board::protocol::Request,
        must_pass: bool,
        bound: u32,
    ) -> Option<board::protocol::Response> {
        use board::protocol::{
            decode, encode, Body, Deframed, Deframer, Frame, Response, MAX_FRAME, PROTOCOL_VERSION,
        };
        self.seq += 1;
        let mut buf = [0u8; MAX_FRAME];
        let frame = Frame {
            version: PROTOCOL_VERSION,
            seq: self.seq,
            body: Body::Request(r),
        };
        let Ok(bytes) = encode(&frame, &mut buf) else {
            hprintln!("  {}: not encodable", label);
            self.ok = false;
            return None;
        };
        let mut answer = None;
        let mut df = Deframer::default();
        self.acc.take();
        self.server.receive(&mut self.acc, bytes, 0, |out| {
            for &b in out {
                if let Deframed::Frame(f) = df.push(b, 0) {
                    if let Ok(Frame {
                        body: Body::Response(r),
                        ..
                    }) = decode(f)
                    {
                        answer = Some(r);
                    }
                }
            }
        });
        let (t, calls) = self.acc.take();
        let n = self.insn(t);
        let over = if n > bound { "  OVER ITS BOUND" } else { "" };
        match answer {
            Some(Response::Error(e)) => {
                hprintln!(
                    "  {:<36} {:>6} instructions ({} with-calls; bound {}), refused: {:?}{}",
                    label,
                    n,
                    calls,
                    bound,
                    e,
                    over
                );
                self.ok &= !must_pass;
            }
            Some(_) => hprintln!(
                "  {:<36} {:>6} instructions ({} with-calls; bound {}){}",
                label,
                n,
                calls,
                bound,
                over
            ),
            None => {
                hprintln!("  {}: no answer", label);
                self.ok = false;
            }
        }
        self.ok &= n <= bound;
        self.all.note(n, label);
        if bound == CRITICAL_BOUND {
            self.bounded.note(n, label);
        } else {
            self.planning.note(n, label);
        }
        answer
    }

    /// `n` half-buffers as the DMA handlers run them (not timed: they are
    /// what the critical sections delay), each followed by the main loop's
    /// `Server::poll` (timed, bound [`CRITICAL_BOUND`]).
    fn halves(&mut self, n: u32) {
        for _ in 0..n {
            self.acc.dev.fill_dac(0, &mut self.dac);
            self.acc
                .dev
                .adc_block_with_pickups(0, &self.forces, &self.pick);
            self.acc.take();
            self.server.poll(&mut self.acc, |_| {});
            let t = self.acc.take().0;
            let n = self.insn(t);
            self.poll.note(n, "poll");
        }
    }
}

/// The critical sections of the protocol server: one request of each kind
/// that reaches the device (framed with the protocol's own encoding and fed
/// to `Server::receive`, as the firmware's main loop does), and the main
/// loop's `Server::poll`, on a device with the driver board's configuration
/// — in voltage mode, then in displacement mode with identified
/// transducers, the pickups' lock-ins and the resonance tracking. Prints
/// each request's longest `with` and the longest of all; returns false if
/// one exceeds its bound ([`CRITICAL_BOUND`], or the stated exception
/// [`PLANNING_BOUND`]) or a request meant to be accepted was refused.
fn critical_sections(table: &board::dds::SineTable<1024>, per_insn: f32) -> bool {
    with_bench(table, per_insn, requests).unwrap_or(false)
}

/// The driver board's device (contact μ₀ 0.3, k 1e7 N/m), a server and a
/// [`Bench`] over them, handed to `f`; `None` if the device refuses its
/// configuration.
fn with_bench<R>(
    table: &board::dds::SineTable<1024>,
    per_insn: f32,
    f: impl FnOnce(&mut Bench<'_, '_>) -> R,
) -> Option<R> {
    use board::device::{Contact, Device, DeviceConfig};
    use board::protocol::Info;
    use board::server::Server;

    let cfg = DeviceConfig::driver_board(1);
    let contact = Contact {
        mu0: 0.3,
        kz: 1e7,
        kx: 1e7,
    };
    let Ok(mut dev) = Device::new(cfg, table, contact) else {
        hprintln!("the device refused its configuration");
        return None;
    };
    let empty = timed(|| ()).1;
    // Pickups reading ≈ 2 µm and 0.3 µm at 20 kHz (0.04 cycle per sample).
    let mut pick = [(0u16, 0u16); 64];
    for (i, p) in pick.iter_mut().enumerate() {
        let (sn, cs) = FastF32::sin_cos(core::f32::consts::TAU * 0.04 * i as f32);
        *p = ((2048.0 + 400.0 * cs) as u16, (2048.0 + 60.0 * sn) as u16);
    }
    let mut b = Bench {
        acc: Timed {
            dev: &mut dev,
            empty,
            longest: 0,
            calls: 0,
        },
        server: Server::new(Info::for_config(&cfg, "predict_cost", [0, 1, 0])),
        seq: 0,
        per_insn,
        all: Longest::NONE,
        bounded: Longest::NONE,
        planning: Longest::NONE,
        poll: Longest::NONE,
        ok: true,
        dac: [0; 64],
        forces: [(2048, 2048); 64],
        pick,
    };
    Some(f(&mut b))
}

/// The drive of the benches: 20 kHz, Δu_z 2 µm, Δu_x 0.3 µm, u_z0 4 µm, φ 0.7 rad.
const DRIVE: board::device::DriveSetting = board::device::DriveSetting {
    freq_hz: 20_000.0,
    amp_z_m: 2e-6,
    amp_x_m: 3e-7,
    offset_z_m: 4e-6,
    phase_rad: 0.7,
};

/// The transducers the benches identified: z 20.3 kHz, Q 261; x 19.7 kHz, Q 182.
fn transducers() -> board::device::Transducers {
    let m = |f: f32, q: f32, g: f32| board::device::TransducerModel {
        resonance_hz: f,
        q,
        gain_m_per_v: g,
        phase_lag_rad: 0.126,
    };
    board::device::Transducers {
        z: m(20_300.0, 261.0, 8.27e-8),
        x: m(19_700.0, 182.0, 4.14e-8),
    }
}

/// Every request kind through `b` (voltage mode, then displacement mode):
/// see [`critical_sections`].
fn requests(b: &mut Bench<'_, '_>) -> bool {
    use board::device::{Contact, DisplacementOptions, DriveMode, Track};
    use board::protocol::{ControlSetting, Request, Response};
    let contact = Contact {
        mu0: 0.3,
        kz: 1e7,
        kx: 1e7,
    };
    let drive = DRIVE;
    let control = |on: bool, target_mu: f32| {
        Request::SetControl(ControlSetting {
            on,
            target_mu,
            v0_m_s: 4e-3,
            gain: 0.5,
            periods: 1,
            rate_m_per_s: 1e-3,
        })
    };
    let transducers = transducers();
    let predict = Request::Predict { v0: 4e-3 };
    let set_drive = Request::SetDrive(drive);
    let (c, p) = (CRITICAL_BOUND, PLANNING_BOUND);
    hprintln!("critical sections of the server (the longest with-closure of each request):");
    // Voltage mode.
    b.call("Hello", Request::Hello, true, c);
    b.call("SetContact", Request::SetContact(contact), true, c);
    b.call("SetDrive (stopped)", set_drive, true, p);
    b.call("GetDrive", Request::GetDrive, true, c);
    b.call("GetContact", Request::GetContact, true, c);
    b.call(
        "SetLiftOff (allow)",
        Request::SetLiftOff { allow: true },
        true,
        c,
    );
    b.call(
        "SetLiftOff (refuse)",
        Request::SetLiftOff { allow: false },
        true,
        c,
    );
    b.call("Predict (stopped)", predict, true, c);
    b.call("Start", Request::Start, true, p);
    b.halves(100);
    b.call("GetStatus", Request::GetStatus, true, c);
    let target = match b.call("Predict (running)", predict, true, c) {
        Some(Response::Prediction { prediction, .. }) => prediction.mu,
        _ => 0.1,
    };
    b.call("SetDrive (running)", set_drive, true, p);
    b.call(
        "SetContact (running)",
        Request::SetContact(contact),
        true,
        c,
    );
    b.halves(50);
    b.call("SetControl (on)", control(true, target), true, c);
    b.halves(50);
    b.call("GetControl", Request::GetControl, true, c);
    b.call(
        "SetControl (retarget)",
        control(true, 0.98 * target),
        true,
        c,
    );
    b.halves(20);
    b.call("SetControl (off)", control(false, target), true, c);
    b.call("Measure", Request::Measure { periods: 4 }, true, c);
    b.halves(4);
    b.call("GetEstimate", Request::GetEstimate, true, c);
    let stream = |on| Request::Stream { on, periods: 4 };
    b.call("Stream (on)", stream(true), true, c);
    b.halves(8);
    b.call("Stream (off)", stream(false), true, c);
    b.call("Stop", Request::Stop, true, c);
    b.halves(50);
    // Displacement mode.
    let t = Request::SetTransducers(Some(transducers));
    b.call("SetTransducers", t, true, c);
    b.call("GetTransducers", Request::GetTransducers, true, c);
    let mode = Request::SetDriveMode(DriveMode::Displacement);
    b.call("SetDriveMode (displacement)", mode, true, p);
    b.call("SetDrive (displacement, stopped)", set_drive, true, p);
    b.call("Start (displacement)", Request::Start, true, p);
    b.halves(300);
    b.call("SetDrive (displacement, running)", set_drive, true, p);
    b.halves(100);
    b.call("GetStatus (displacement)", Request::GetStatus, true, c);
    b.call("Predict (displacement)", predict, true, c);
    let track = Request::SetDisplacementOptions(DisplacementOptions {
        track: Track::Z,
        headroom: 2.0,
    });
    b.call("SetDisplacementOptions (track z)", track, true, c);
    b.halves(50);
    b.call("Predict (tracking)", predict, true, c);
    // (Accepted or refused, its checks and the scene's copy are timed.)
    b.call("SetControl (on, tracking)", control(true, target), false, c);
    b.halves(20);
    b.call(
        "SetControl (off, tracking)",
        control(false, target),
        true,
        c,
    );
    b.call("ResetFaults", Request::ResetFaults, true, c);
    b.call("Reset", Request::Reset, true, c);
    let mode = Request::SetDriveMode(DriveMode::OpenLoop);
    b.call("SetDriveMode (voltage)", mode, true, p);
    b.halves(20);
    hprintln!(
        "  {:<36} {:>6} instructions (the longest of all half-buffers' polls; bound {})",
        "poll",
        b.poll.insn,
        CRITICAL_BOUND
    );
    b.ok &= b.poll.insn <= CRITICAL_BOUND;
    b.all.note(b.poll.insn, "poll");
    b.bounded.note(b.poll.insn, "poll");
    hprintln!(
        "longest critical section: {} instructions ({}) = {} % of 21504",
        b.all.insn,
        b.all.label,
        b.all.percent()
    );
    hprintln!(
        "  bounded by 10 % of a half-buffer ({}): longest {} ({}) = {} %; stated exception (drive planning; bound {} = {} %): longest {} ({}) = {} %",
        CRITICAL_BOUND,
        b.bounded.insn,
        b.bounded.label,
        b.bounded.percent(),
        PLANNING_BOUND,
        PLANNING_BOUND as f32 * 100.0 / 21_504.0,
        b.planning.insn,
        b.planning.label,
        b.planning.percent()
    );
    if !b.ok {
        hprintln!("critical sections: a request exceeded its bound or was refused");
    }
    b.ok
}

#[entry]
fn main() -> ! {
    let Some(cp) = cortex_m::Peripherals::take() else {
        debug::exit(debug::EXIT_FAILURE);
        loop {
            cortex_m::asm::wfi();
        }
    };
    let mut syst = cp.SYST;
    syst.set_clock_source(SystClkSource::Core);
    syst.set_reload(0x00FF_FFFF);
    syst.clear_current();
    syst.enable_counter();

    // Calibration: exactly 1000 instructions.
    let cal = ticks(nops_1000);
    let empty = ticks(|| {});
    let per_insn = (cal.saturating_sub(empty)) as f32 / 1000.0;
    hprintln!(
        "calibration: {} ticks / 1000 nop ({} per instruction)",
        cal - empty,
        per_insn
    );

    let scene = match Scene::<f32>::new(SceneParams {
        mu0: 0.3,
        kz: 1e7,
        kx: 1e7,
        uz0: 4e-6,
        duz: 2e-6,
        dux: 0.3e-6,
        omega: 2.0 * core::f32::consts::PI * 20e3,
        phi: 0.7,
    }) {
        Ok(s) => s,
        Err(_) => {
            debug::exit(debug::EXIT_FAILURE);
            loop {
                cortex_m::asm::wfi();
            }
        }
    };
    let vc = model_core::analytic::CriticalVelocity::of(&scene);
    let mut worst = 0u32;
    let mut sum = 0u32;
    let n = 16;
    for i in 0..n {
        let x = -0.95 + 1.9 * (i as f32 + 0.5) / n as f32;
        let v = x * if x > 0.0 { vc.forward } else { vc.backward };
        let mut out = None;
        let t = ticks(|| out = Some(device::predict(&scene, v))).saturating_sub(empty);
        if !matches!(out, Some(Ok(_))) {
            debug::exit(debug::EXIT_FAILURE);
        }
        let insn = (t as f32 / per_insn) as u32;
        worst = worst.max(insn);
        sum += insn;
    }
    hprintln!(
        "predict (f32 exact, 16 velocities in (-v_c, v_c)): mean {} instructions, worst {}",
        sum / n,
        worst
    );
    let mut r = None;
    let t = ticks(|| r = Some(device::regime(&scene))).saturating_sub(empty);
    hprintln!(
        "regime classification: {} instructions",
        (t as f32 / per_insn) as u32
    );
    // What the server does for each Predict: form the scene of the drive
    // (validation, W0, the drive's sin/cos φ with libm).
    let params = *scene.params();
    let mut sc = None;
    let t =
        ticks(|| sc = Some(core::hint::black_box(Scene::<f32>::new(params)))).saturating_sub(empty);
    if !matches!(sc, Some(Ok(_))) {
        debug::exit(debug::EXIT_FAILURE);
    }
    hprintln!(
        "scene construction (Scene::new, f32: formed by the server for each Predict, with the device released): {} instructions",
        (t as f32 / per_insn) as u32
    );

    // The closed loop (model-core `board::control`): the plan (feedforward
    // search, once per setpoint) and one update (eqs. C1–C4, at most once
    // per ADC half-buffer of 64 samples at 500 kS/s = 0.128 ms = 21 504
    // cycles at 168 MHz). The estimate the update uses is the estimator's, not counted.
    // Target μ*: the model's μ at this drive's Δu_z and 4 mm/s (reachable by
    // construction); the search starts from Δu_z = 0.
    let limit = 0.95 * params.uz0;
    let target = match device::predict(&scene, 4e-3) {
        Ok(p) => p.mu,
        Err(_) => 0.0,
    };
    let mut plan = None;
    let t = ticks(|| plan = Some(board::control::plan(&scene, target, 4e-3, 0.0, limit)))
        .saturating_sub(empty);
    match plan {
        Some(Ok(p)) => {
            let plan_insn = (t as f32 / per_insn) as u32;
            let gains = board::control::Gains {
                kappa: 0.95,
                rate_m_per_s: 1.0,
            };
            let mut ctl = board::control::Controller::new(p, gains, params.duz);
            // The first update has no secant yet; the second one learns
            // from the step the first made (C5–C6): the one timed.
            let _ = core::hint::black_box(ctl.update(0.24, 0.384e-3));
            let mut out = None;
            let t = ticks(|| out = Some(core::hint::black_box(ctl.update(0.2, 0.512e-3))))
                .saturating_sub(empty);
            let upd = (t as f32 / per_insn) as u32;
            hprintln!(
                "closed loop: plan (feedforward search, per setpoint) {} instructions; update (learning a secant, C1–C7) {} instructions = {}% of a 0.128 ms half-buffer at 168 MHz",
                plan_insn,
                upd,
                upd as f32 * 100.0 / 21_504.0
            );
        }
        _ => hprintln!("closed loop: the plan was refused for this scene"),
    }

    // The same prediction with each backend.
    let mut means = [0u32; 2];
    for (k, (name, cost)) in [
        (
            <Libm as Math<f32>>::NAME,
            predict_cost::<Libm>(&scene, &vc, empty, per_insn),
        ),
        (
            <FastF32 as Math<f32>>::NAME,
            predict_cost::<FastF32>(&scene, &vc, empty, per_insn),
        ),
    ]
    .into_iter()
    .enumerate()
    {
        let Some((mean, worst)) = cost else {
            debug::exit(debug::EXIT_FAILURE);
            loop {
                cortex_m::asm::wfi();
            }
        };
        hprintln!(
            "predict with {} (critical velocities + exact solver, 16 velocities): mean {} instructions, worst {}",
            name,
            mean,
            worst
        );
        means[k] = mean;
    }

    // Each transcendental function, mean over 16 arguments, loop overhead removed.
    let base = fn_cost(empty, per_insn, |t| t, id);
    let c = |arg: fn(f32) -> f32, f: fn(f32) -> f32| fn_cost(empty, per_insn, arg, f) - base;
    let phase: fn(f32) -> f32 = |t| 6.2 * t + 0.01;
    let unit: fn(f32) -> f32 = |t| 0.999 * t + 0.003;
    let pos: fn(f32) -> f32 = |t| 50.0 * t + 0.02;
    hprintln!("per call, instructions (mean of 16 arguments):      libm  fast-f32");
    hprintln!(
        "  {:<40} {:>6} {:>9}",
        "sin_cos (x in [0, 2pi])",
        c(phase, |x| <Libm as Math<f32>>::sin_cos(x).0) as u32,
        c(phase, |x| <FastF32 as Math<f32>>::sin_cos(x).0) as u32
    );
    hprintln!(
        "  {:<40} {:>6} {:>9}",
        "asin (x in [0, 1])",
        c(unit, <Libm as Math<f32>>::asin) as u32,
        c(unit, <FastF32 as Math<f32>>::asin) as u32
    );
    hprintln!(
        "  {:<40} {:>6} {:>9}",
        "atan2 (y in [0,1], x=1-2y)",
        c(unit, |y| <Libm as Math<f32>>::atan2(y, 1.0 - 2.0 * y)) as u32,
        c(unit, |y| <FastF32 as Math<f32>>::atan2(y, 1.0 - 2.0 * y)) as u32
    );
    hprintln!(
        "  {:<40} {:>6} {:>9}",
        "sqrt (x in [0, 50])",
        c(pos, <Libm as Math<f32>>::sqrt) as u32,
        c(pos, <FastF32 as Math<f32>>::sqrt) as u32
    );
    hprintln!(
        "  {:<40} {:>6} {:>9}",
        "hypot (x in [0, 50], 0.3)",
        c(pos, |x| <Libm as Math<f32>>::hypot(x, 0.3)) as u32,
        c(pos, |x| <FastF32 as Math<f32>>::hypot(x, 0.3)) as u32
    );

    // DDS refill of one 256-sample half-buffer (two channels, packed words),
    // and building the 1024-entry table with libm and with micromath.
    use board::dds::{Dds, Level, SineTable, Slew};
    let mut tl = None;
    let t_libm = ticks(|| tl = Some(SineTable::<1024>::libm())).saturating_sub(empty);
    let mut tm = None;
    let t_mm = ticks(|| tm = Some(core::hint::black_box(SineTable::<1024>::micromath())))
        .saturating_sub(empty);
    core::hint::black_box(&tm);
    hprintln!(
        "sine table N=1024 build: libm {} instructions, micromath {}",
        (t_libm as f32 / per_insn) as u32,
        (t_mm as f32 / per_insn) as u32
    );
    let mut critical_ok = false;
    if let Some(table) = tl.as_ref() {
        let slew = Slew {
            amp_per_sample: 1.0,
            dc_per_sample: 1.0,
            phase_per_sample: 1 << 20,
        };
        if let Ok(mut dds) = Dds::new(table, 1e6, slew) {
            let _ = dds.set_frequency(40_000.0);
            let _ = dds.set_level(
                0,
                Level {
                    amp: 1000.0,
                    dc: 2048.0,
                },
            );
            let _ = dds.set_level(
                1,
                Level {
                    amp: 1000.0,
                    dc: 2048.0,
                },
            );
            let mut buf = [0u32; 256];
            let t = ticks(|| dds.fill(&mut buf)).saturating_sub(empty);
            hprintln!(
                "DDS fill while ramping: {} instructions per sample (both channels, the table's codes and the ADC's reference words)",
                (t as f32 / per_insn / 256.0) as u32
            );
            while !dds.settled() {
                dds.fill(&mut buf);
            }
            let t = ticks(|| dds.fill(&mut buf)).saturating_sub(empty);
            let dds_per_sample = t as f32 / per_insn / 256.0;
            hprintln!(
                "DDS fill, settled: {} instructions per sample (both channels' codes from the reference words, eq. Q6, and those words, R1)",
                dds_per_sample as u32
            );
            // CPU shares at 168 MHz, one instruction per cycle.
            let clock = 168e6f32;
            hprintln!(
                "CPU share at 168 MHz: DDS refill at 500 kS/s {:.1} %; one prediction per control period: libm {:.2} % at 1 kHz, {:.1} % at 10 kHz; fast-f32 {:.2} % at 1 kHz, {:.1} % at 10 kHz",
                dds_per_sample * 500e3 / clock * 100.0,
                means[0] as f32 * 1e3 / clock * 100.0,
                means[0] as f32 * 1e4 / clock * 100.0,
                means[1] as f32 * 1e3 / clock * 100.0,
                means[1] as f32 * 1e4 / clock * 100.0
            );
            // The QEMU build's plant (module `qemu` of the firmware): one
            // half-buffer at 40 kHz, 8 sub-steps per sample, fast-f32 sine.
            {
                use board::plant::{HalfDrive, Plant, SampleConditions};
                let d = HalfDrive {
                    before: *dds.channels(),
                    after: *dds.channels(),
                    acc0: dds.accumulator(),
                    tw: dds.tuning_word(),
                    slew: dds.slew(),
                };
                let cfg = device::DeviceConfig::driver_board(1);
                let mut plant = Plant::<f32>::new(0.24, 1e7, 1e7);
                let mut out = [(0u16, 0u16); 256];
                let t = ticks(|| {
                    plant.run_half::<FastF32>(
                        &cfg,
                        &d,
                        8,
                        0.0,
                        |_| SampleConditions {
                            mu0: 0.24,
                            v0: 0.004,
                            counts_z: 0.0,
                            counts_x: 0.0,
                        },
                        &mut out,
                    )
                })
                .saturating_sub(empty);
                core::hint::black_box(&out);
                hprintln!(
                    "QEMU plant (8 sub-steps, fast-f32): {} instructions per sample",
                    (t as f32 / per_insn / 256.0) as u32
                );
            }
            intake_costs(table, empty, per_insn);
            critical_ok = critical_sections(table, per_insn);
            let load = with_bench(table, per_insn, |b| everything::run(b, DRIVE)).flatten();
            match load {
                Some(l) => {
                    let pct = everything::report(&l);
                    if pct > everything::LIMIT_PCT || l.faults != 0 {
                        hprintln!(
                            "worst half-buffer over {} % (or a fault latched): the handlers would miss their deadline",
                            everything::LIMIT_PCT
                        );
                        critical_ok = false;
                    }
                }
                None => {
                    hprintln!("everything on: a request was refused");
                    critical_ok = false;
                }
            }
            core::hint::black_box(&buf);
        }
    }
    if !critical_ok {
        debug::exit(debug::EXIT_FAILURE);
    }
    debug::exit(debug::EXIT_SUCCESS);
    loop {
        cortex_m::asm::wfi();
    }
}
