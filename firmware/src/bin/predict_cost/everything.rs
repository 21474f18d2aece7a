//! The worst half-buffer with everything on (issue 35's figure): the
//! driver board's device in displacement mode on both channels with
//! identified transducers, the two pickups' lock-ins and the force
//! estimator in the ADC handler's pass, the resonance tracked (`--track z`),
//! the μ loop on (its estimate, its update) and a telemetry stream running.
//! Every half-buffer runs what the firmware runs for it, timed part by part:
//!
//! * the DAC handler's work, `Device::dac_half_done` (the refill);
//! * the ADC handler's work, `Device::adc_half_done_with_pickups` (the
//!   intake, the windows it closes, the loops it steps);
//! * the main loop's `Server::poll` (the stream's samples and telemetry),
//!   which runs in the time the handlers leave.
//!
//! The figure is the largest sum of the three over
//! [`HALVES`] half-buffers, against the budget of one half-buffer
//! (21 504 cycles at 168 MHz; here instructions: a lower bound on cycles).

use super::{Bench, CRITICAL_BOUND, PLANNING_BOUND};
use board::device::{DeviceConfig, DisplacementOptions, DriveMode, DriveSetting, Track};
use board::dma::HalfEvent;
use board::plant::{HalfDrive, Plant, Resonant, ResonantOptions, SampleConditions};
use board::protocol::{ControlSetting, Request, Response};
use cortex_m_semihosting::hprintln;
use model_core::float::FastF32;

/// The share of a half-buffer above which `predict_cost` fails (and with
/// it `.ci/run`): the deadline itself, instructions being a lower bound on
/// the chip's cycles. Issue 35's target is 30 % ([`TARGET_PCT`]); the run
/// prints the distance to it.
pub const LIMIT_PCT: f32 = 100.0;

/// Issue 35's target for the worst half-buffer, % (not yet met: printed).
pub const TARGET_PCT: f32 = 30.0;

/// Half-buffers timed (≈ 0.26 s of device time: many windows, tracking
/// steps and μ-loop updates).
pub const HALVES: u32 = 2_000;

/// One half-buffer's parts, instructions.
#[derive(Clone, Copy, Default)]
pub struct Parts {
    /// The DAC handler.
    pub fill: u32,
    /// The ADC handler.
    pub intake: u32,
    /// The main loop's poll.
    pub poll: u32,
}

impl Parts {
    /// The three together.
    pub fn total(&self) -> u32 {
        self.fill + self.intake + self.poll
    }
}

/// What the run measured: the worst half-buffer (its parts), the largest of
/// each part on its own, the mean of the totals, and what ran.
pub struct Load {
    /// The half-buffer with the largest total.
    pub worst: Parts,
    /// The largest of each part over all half-buffers.
    pub largest: Parts,
    /// The mean total, instructions.
    pub mean: u32,
    /// μ-loop updates during the run.
    pub updates: u32,
    /// Lock-in windows closed during the run.
    pub windows: u32,
    /// Telemetry frames sent during the run.
    pub frames: u32,
    /// The ADC handler's work by what happened in its block: the largest
    /// and the mean of blocks that only accumulated, that closed a lock-in
    /// window (fit, guard, D3, tracking T1–T3), and that ran a μ-loop update
    /// (its estimate and C1–C7; with or without a window).
    pub intake_by_event: [(u32, u32); 3],
    /// The DAC handler's work: the largest of fills right after a μ-loop
    /// update (the new command planned into the drive) and of the others.
    pub fill_after_update: (u32, u32),
    /// Tracking was on and locked at the end.
    pub locked: bool,
    /// Faults latched at the end.
    pub faults: u32,
}

/// The bench's analog side: the resonant transducers and the contact
/// (`board::plant`, as the firmware's `qemu-resonant` build), whose force
/// and pickup samples the ADC handler takes, two half-buffers after the
/// fill that drove them (as on the board).
struct Analog {
    plant: Plant<f32>,
    cfg: DeviceConfig,
    pending: [Option<HalfDrive>; 2],
    forces: [(u16, u16); 64],
    pickups: [(u16, u16); 64],
}

/// Plant sub-steps per sample (fewer than the QEMU build's 8: the run
/// times the device, not the plant, whose error here only moves μ).
const SUB: u32 = 4;

impl Analog {
    fn new(cfg: DeviceConfig) -> Self {
        let mut plant = Plant::new(0.24, 1e7, 1e7);
        let h = 1.0 / (cfg.sample_rate_hz as f32 * SUB as f32);
        plant.resonant = Resonant::new(ResonantOptions::bench(&cfg), h).ok();
        Analog {
            plant,
            cfg,
            pending: [None, None],
            forces: [(0, 0); 64],
            // At rest until the plant's first half arrives (two fills
            // late): the pickups at their offset, no motion — not at a
            // rail, which the displacement mode takes for a fault.
            pickups: [(cfg.pickup_z.offset as u16, cfg.pickup_x.offset as u16); 64],
        }
    }

    /// One half-buffer as the firmware runs it, timed part by part (the
    /// plant between the handlers is not timed).
    fn half(&mut self, b: &mut Bench<'_, '_>, frames: &mut u32) -> Parts {
        let ev = HalfEvent {
            half: 0,
            late: false,
        };
        let dev = &mut *b.acc.dev;
        let (before, acc0, tw) = (
            *dev.dds().channels(),
            dev.dds().accumulator(),
            dev.dds().tuning_word(),
        );
        let fill = super::timed(|| dev.dac_half_done(ev, &mut b.dac)).1;
        let made = HalfDrive {
            before,
            after: *dev.dds().channels(),
            acc0,
            tw,
            slew: dev.dds().slew(),
        };
        let oldest = self.pending[0];
        self.pending = [self.pending[1], Some(made)];
        if let Some(d) = oldest {
            self.plant.run_half_with_pickups::<FastF32>(
                &self.cfg,
                &d,
                SUB,
                0.0,
                |_| SampleConditions {
                    mu0: 0.24,
                    v0: 4e-3,
                    counts_z: 0.0,
                    counts_x: 0.0,
                },
                &mut self.forces,
                &mut self.pickups,
            );
        }
        let (forces, pick) = (&self.forces, &self.pickups);
        let intake = super::timed(|| dev.adc_half_done_with_pickups(ev, forces, pick)).1;
        let server = &mut b.server;
        let acc = &mut b.acc;
        let poll = super::timed(|| server.poll(acc, |_| *frames += 1)).1;
        let e = b.acc.empty;
        Parts {
            fill: b.insn(fill.saturating_sub(e)),
            intake: b.insn(intake.saturating_sub(e)),
            poll: b.insn(poll.saturating_sub(e)),
        }
    }

    fn halves(&mut self, b: &mut Bench<'_, '_>, n: u32) {
        let mut frames = 0;
        for _ in 0..n {
            self.half(b, &mut frames);
        }
    }
}

/// Sets everything on through the server (as `fricctl` would, with the
/// transducers its identification finds) and times [`HALVES`]
/// half-buffers; `None` if a request meant to be accepted was refused.
pub fn run(b: &mut Bench<'_, '_>, drive: DriveSetting) -> Option<Load> {
    let (c, p) = (CRITICAL_BOUND, PLANNING_BOUND);
    let ok = |r: Option<Response>| !matches!(r, None | Some(Response::Error(_)));
    hprintln!("everything on (displacement mode, two pickups, force estimator, --track z, μ loop, stream):");
    let cfg = DeviceConfig::driver_board(1);
    let mut analog = Analog::new(cfg);
    let identified = ResonantOptions::<f32>::bench(&cfg).identified(cfg.sample_rate_hz);
    let mode = Request::SetDriveMode(DriveMode::Displacement);
    let t = Request::SetTransducers(Some(identified));
    if !ok(b.call("  SetTransducers", t, true, c))
        || !ok(b.call("  SetDriveMode (displacement)", mode, true, p))
        || !ok(b.call("  SetDrive", Request::SetDrive(drive), true, p))
        || !ok(b.call("  Start", Request::Start, true, p))
    {
        return None;
    }
    analog.halves(b, 300);
    let track = Request::SetDisplacementOptions(DisplacementOptions {
        track: Track::Z,
        headroom: 2.0,
    });
    if !ok(b.call("  SetDisplacementOptions (track z)", track, true, c)) {
        return None;
    }
    analog.halves(b, 400);
    let target_mu = match b.call("  Predict", Request::Predict { v0: 4e-3 }, true, c) {
        Some(Response::Prediction { prediction, .. }) => prediction.mu,
        _ => return None,
    };
    let control = Request::SetControl(ControlSetting {
        on: true,
        target_mu,
        v0_m_s: 4e-3,
        gain: 0.5,
        periods: 1,
        rate_m_per_s: 1e-3,
    });
    if !ok(b.call("  SetControl (on)", control, true, c)) {
        return None;
    }
    let stream = Request::Stream {
        on: true,
        periods: 4,
    };
    // Refused (Busy) while the μ loop owns the force estimator: then its
    // updates are the telemetry stream (one `Telemetry::Control` each).
    b.call("  Stream (on)", stream, false, c);
    let (u0, w0) = {
        let d = &*b.acc.dev;
        (
            d.control_state().last.update,
            d.measured_drive().map_or(0, |m| m.windows),
        )
    };
    let (mut worst, mut largest, mut sum, mut frames) =
        (Parts::default(), Parts::default(), 0u64, 0);
    // Per event: (largest, sum, count).
    let mut by = [(0u32, 0u64, 0u32); 3];
    let (mut after, mut fill_after) = (false, (0u32, 0u32));
    #[cfg(feature = "probe")]
    board::probe::set_hook(prof::hook);
    for _ in 0..HALVES {
        let (u, w) = events(b);
        let h = analog.half(b, &mut frames);
        let (u1, w1) = events(b);
        let e = if u1 != u {
            2
        } else if w1 != w {
            1
        } else {
            0
        };
        by[e] = (
            by[e].0.max(h.intake),
            by[e].1 + u64::from(h.intake),
            by[e].2 + 1,
        );
        if after {
            fill_after.0 = fill_after.0.max(h.fill);
        } else {
            fill_after.1 = fill_after.1.max(h.fill);
        }
        after = u1 != u;
        if h.total() > worst.total() {
            worst = h;
        }
        largest.fill = largest.fill.max(h.fill);
        largest.intake = largest.intake.max(h.intake);
        largest.poll = largest.poll.max(h.poll);
        sum += u64::from(h.total());
    }
    #[cfg(feature = "probe")]
    prof::print(b);
    let d = &*b.acc.dev;
    let st = d.status();
    Some(Load {
        worst,
        largest,
        mean: (sum / u64::from(HALVES)) as u32,
        updates: d.control_state().last.update.wrapping_sub(u0),
        windows: d.measured_drive().map_or(0, |m| m.windows).wrapping_sub(w0),
        frames,
        intake_by_event: by.map(|(m, s, n)| (m, (s / u64::from(n.max(1))) as u32)),
        fill_after_update: fill_after,
        locked: st.options.track == Track::Z && st.locked,
        faults: st.faults,
    })
}

/// The μ-loop updates and lock-in windows so far.
fn events(b: &Bench<'_, '_>) -> (u32, u32) {
    let d = &*b.acc.dev;
    (
        d.control_state().last.update,
        d.measured_drive().map_or(0, |m| m.windows),
    )
}

/// Prints the figure and its parts; returns the worst half-buffer's share
/// of the budget, %.
pub fn report(l: &Load) -> f32 {
    let pct = |n: u32| n as f32 * 100.0 / 21_504.0;
    hprintln!(
        "  {} half-buffers: {} μ-loop updates, {} lock-in windows, {} telemetry frames; tracking locked {}, faults {}",
        HALVES,
        l.updates,
        l.windows,
        l.frames,
        l.locked,
        l.faults
    );
    hprintln!(
        "  worst half-buffer's parts: DAC handler {} + ADC handler {} + main loop's poll {} instructions; largest of each alone {} / {} / {}; mean half-buffer {} = {:.1} %",
        l.worst.fill,
        l.worst.intake,
        l.worst.poll,
        l.largest.fill,
        l.largest.intake,
        l.largest.poll,
        l.mean,
        pct(l.mean)
    );
    let [acc, win, upd] = l.intake_by_event;
    hprintln!(
        "  ADC handler, largest / mean: accumulating only {} / {}; closing a lock-in window {} / {}; with a μ-loop update {} / {}",
        acc.0,
        acc.1,
        win.0,
        win.1,
        upd.0,
        upd.1
    );
    hprintln!(
        "  DAC handler, largest: after a μ-loop update {}, otherwise {}",
        l.fill_after_update.0,
        l.fill_after_update.1
    );
    let n = l.worst.total();
    hprintln!(
        "worst half-buffer, everything on: {} instructions = {:.1} % of 21504",
        n,
        pct(n)
    );
    hprintln!(
        "  limit {} % (the deadline; fails above), target {} %: {}",
        LIMIT_PCT,
        TARGET_PCT,
        if pct(n) <= TARGET_PCT {
            "met"
        } else {
            "not met yet"
        }
    );
    pct(n)
}

/// The probe's hook (feature `probe`): the time since the previous mark,
/// summed and maximised per part (`board::probe::PARTS`).
#[cfg(feature = "probe")]
mod prof {
    use core::sync::atomic::{AtomicU32, Ordering::Relaxed};
    use cortex_m::peripheral::SYST;
    static LAST: AtomicU32 = AtomicU32::new(0);
    static SUM: [AtomicU32; 32] = [const { AtomicU32::new(0) }; 32];
    static MAX: [AtomicU32; 32] = [const { AtomicU32::new(0) }; 32];
    pub fn hook(id: u8) {
        let now = SYST::get_current();
        let i = id as usize;
        if i != 0 && i != 10 {
            let d = LAST.load(Relaxed).wrapping_sub(now) & 0x00FF_FFFF;
            SUM[i].fetch_add(d, Relaxed);
            if d > MAX[i].load(Relaxed) {
                MAX[i].store(d, Relaxed);
            }
        }
        LAST.store(SYST::get_current(), Relaxed);
    }
    pub fn print(b: &super::Bench<'_, '_>) {
        cortex_m_semihosting::hprintln!(
            "  parts (probe marks; each mark adds its own cost to the totals below), mean / largest instructions:"
        );
        for (i, name) in board::probe::PARTS {
            let i = usize::from(i);
            cortex_m_semihosting::hprintln!(
                "    {:<64} {:>5} / {:>5}",
                name,
                b.insn(SUM[i].load(Relaxed) / super::HALVES),
                b.insn(MAX[i].load(Relaxed))
            );
        }
    }
}
