//! The μ loop's bench (`fricctl device control-bench`): the board's closed
//! loop on an in-process virtual device whose plant is *not* the device's
//! model (μ₀ off by [`BenchConfig::mu0_ratio`], resonant or lagging
//! transducers, ADC noise), through four events — switch-on, a setpoint
//! step, a step of the plant's μ₀ (the disturbance) and a velocity step —
//! then an optional hold. It reports each event's settling, overshoot and
//! steady error ([`EventResponse`]), the lift-off margin sample by sample,
//! and the tracking's lock ([`BenchOut`]); the records behind them
//! ([`BenchTrace`]) are what a chart draws.
//!
//! Settling is judged against a band of 2 % of the event's step, or four
//! times the estimates' own scatter over the segment's last half when that
//! is wider: no single estimate resolves less, and a settled loop's
//! estimates leave ±4σ once in ≈ 16 000 (Gaussian), not once in a
//! segment's 20–250 updates as they would ±3σ (once in 370).

use board::device::{
    DeviceConfig, DeviceError, DisplacementOptions, DriveMode, DriveParam, DriveSetting, Track,
};
use board::plant::ResonantOptions;
use board::protocol::{
    decode, encode, Body, ControlSetting, ControlState, ControlUpdate, Deframed, Deframer, Frame,
    Request, Response, Telemetry, MAX_FRAME, PROTOCOL_VERSION,
};
use board::resonator::ModeParams;
use fric_analysis::numbers::short;
use serde::Serialize;

use crate::answers::{expect, unexpected};
use crate::names::fault_names;
use crate::periods::Periods;
use crate::transducers::TransducerSpec;
use crate::virtual_device::{self as vd, PlantOptions, VirtualDevice, DEFAULT_CONTACT, HALF};
use crate::{Error, Result};

/// Default κ (fraction of the error removed per update, with the plant's
/// gain learned: eqs. C5–C7 of `board::control`).
pub const DEFAULT_GAIN: f64 = 0.95;
/// Default rate limit of the commanded Δu_z, m/s (the driver board's slew).
pub const DEFAULT_RATE: f64 = 1e-3;
/// The longest hold after the events, s of device time (ten minutes).
pub const MAX_HOLD_S: f64 = 600.0;
/// The longest τ the bench runs (its segments last 8 τ each): 50 ms,
/// Q ≈ 3 000 at 20 kHz.
pub const MAX_BENCH_TAU_S: f64 = 0.05;

/// The bench's fixed drive and schedule (device time).
pub mod scenario {
    /// Drive frequency, Hz.
    pub const FREQ_HZ: f64 = 40_000.0;
    /// Normal offset u_z0, m.
    pub const OFFSET_Z_M: f32 = 4e-6;
    /// Δu_x, m.
    pub const AMP_X_M: f32 = 0.3e-6;
    /// Open-loop Δu_z before the loop, m.
    pub const AMP_Z0_M: f32 = 2e-6;
    /// φ, degrees.
    pub const PHASE_DEG: f32 = 40.0;
    /// Stage velocity before the velocity step (and the loop's v0), m/s.
    pub const V0: f64 = 0.004;
    /// Stage velocity after the step, m/s.
    pub const V1: f64 = 0.006;
    /// Setpoint at switch-on, then after the setpoint step.
    pub const TARGETS: (f32, f32) = (0.10, 0.13);
    /// The setpoints on resonant transducers (driven at the normal mode's
    /// resonance, ≈ 20 kHz: half the ideal bench's frequency doubles b and
    /// the tangential reduction alone leaves μ near 0.13, out of reach).
    pub const TARGETS_RESONANT: (f32, f32) = (0.08, 0.10);
    /// Loop on, setpoint step, disturbance, velocity step, end: ms after
    /// the drive has settled (on resonant transducers each segment lasts
    /// at least 8 τ).
    pub const EVENTS_MS: [f64; 5] = [0.0, 15.0, 30.0, 45.0, 60.0];
    /// The disturbance: the plant's μ0 multiplied by this.
    pub const MU0_STEP: f64 = 0.9;
    /// Duration of the velocity ramp, ms.
    pub const V_RAMP_MS: f64 = 0.1;
    /// The events' names, in order (JSON `event`).
    pub const EVENTS: [&str; 4] = ["switch_on", "setpoint_step", "disturbance", "velocity_step"];
}

/// What the bench runs: the plant's mismatch and the loop's settings. Each
/// field is a flag of `fricctl device control-bench`, named in errors.
#[derive(Debug, Clone, PartialEq)]
pub struct BenchConfig {
    /// True μ0 of the plant relative to the device's model μ0 = 0.3
    /// (`--mu0-ratio`, > 0).
    pub mu0_ratio: f64,
    /// Transducer amplitude lag of ideal transducers, drive periods
    /// (`--lag-periods`, ≥ 0).
    pub lag_periods: f64,
    /// Drift of the plant's μ0, per second of device time (`--drift`).
    pub drift: f64,
    /// ADC noise, ± counts (`--noise`).
    pub noise: f64,
    /// κ of the loop, in [0.01, 1] (`--gain`).
    pub gain: f64,
    /// Drive periods per update (`--periods`).
    pub periods: Periods,
    /// Half-buffers the DAC fills run ahead of the output, 0 … 16
    /// (`--fill-lead`; 2 as on the board).
    pub fill_lead: usize,
    /// Seed of the plant's ADC noise (0: the virtual device's default record).
    pub seed: u64,
    /// The transducers (resonant by default).
    pub transducers: TransducerSpec,
    /// The displacement loop's headroom (`--headroom`, 1 … 8).
    pub headroom: f64,
    /// Resonance tracking during the run (`--track`).
    pub track: Track,
    /// The hold after the four events, s of device time, 0 … 600 (`--hold-s`).
    pub hold_s: f64,
}

impl Default for BenchConfig {
    /// The bench of `fricctl device control-bench` without flags.
    fn default() -> Self {
        BenchConfig {
            mu0_ratio: 0.8,
            lag_periods: 2.0,
            drift: 0.0,
            noise: 2.0,
            gain: DEFAULT_GAIN,
            periods: Periods::Auto,
            fill_lead: 2,
            seed: 0,
            transducers: TransducerSpec::default(),
            headroom: f64::from(board::device::displacement::DEFAULT_HEADROOM),
            track: Track::None,
            hold_s: 0.0,
        }
    }
}

impl BenchConfig {
    /// Each value within its domain, named by its flag (the CLI's parsers
    /// check them too; a caller from elsewhere may not have).
    fn check(&self) -> Result<()> {
        use fric_analysis::numbers::Real;
        let fields = [
            (self.mu0_ratio, "--mu0-ratio", Real::positive()),
            (self.lag_periods, "--lag-periods", Real::non_negative()),
            (self.drift, "--drift", Real::ANY),
            (self.noise, "--noise", vd::NOISE_COUNTS),
            (self.gain, "--gain", Real::ANY.at_least(0.01).at_most(1.0)),
            (
                self.headroom,
                "--headroom",
                Real::ANY.at_least(1.0).at_most(8.0),
            ),
            (
                self.hold_s,
                "--hold-s",
                Real::non_negative().at_most(MAX_HOLD_S),
            ),
        ];
        for (x, flag, domain) in fields {
            domain
                .check(x, &short(x))
                .map_err(|r| Error::usage(format!("{flag}: {r}")))?;
        }
        if self.fill_lead > 16 {
            return Err(Error::usage(format!(
                "--fill-lead: must be ≤ 16 (got {}; the board fills 2 ahead)",
                self.fill_lead
            )));
        }
        if let Periods::Fixed(0) = self.periods {
            return Err(Error::usage("--periods: must be ≥ 1 (got 0)"));
        }
        Ok(())
    }
}

/// One event's response.
#[derive(Serialize, Debug, Clone)]
pub struct EventResponse {
    /// `switch_on`, `setpoint_step`, `disturbance` (μ0 × `MU0_STEP`) or
    /// `velocity_step`.
    pub event: &'static str,
    /// Setpoint after the event.
    pub target_mu: f64,
    /// The model's feedforward Δu_z for it, m.
    pub duz_feedforward: f64,
    /// The model's gain ∂μ/∂Δu_z there, 1/m.
    pub slope_per_m: f64,
    /// The event's step in μ: the setpoint's change, the first measured
    /// error at switch-on, the largest error after the disturbance or the
    /// velocity step.
    pub step: f64,
    /// The settling band: 2 % of the step, or 4 × `scatter` if wider.
    pub band: f64,
    /// The estimates' scatter in the event's segment: the standard
    /// deviation of μ̂ over the segment's last half (the smallest over the
    /// four segments if it has fewer than 4 updates there).
    pub scatter: f64,
    /// The device's standard error of the estimates, median over the
    /// segment (for comparison with `scatter`).
    pub std_error: f64,
    /// Updates from the event to the first one after which every estimate
    /// stays within the band (until the next event); None: never.
    pub settle_updates: Option<u32>,
    /// The same as device time, drive periods (to the end of the half-buffer
    /// in which that update ran).
    pub settle_periods: Option<f64>,
    /// The same, ms.
    pub settle_ms: Option<f64>,
    /// Largest excursion past the setpoint in the direction of the step,
    /// relative to the step (setpoint step only), %.
    pub overshoot_pct: Option<f64>,
    /// The same as a fraction of the step (setpoint step only).
    pub overshoot: Option<f64>,
    /// Mean of μ̂ − μ* over the last half of the segment.
    pub steady_error: f64,
    /// RMS of μ̂ − μ* over the last half of the segment.
    pub steady_rms: f64,
    /// Largest |μ̂ − μ*| after the event, relative to μ*, %.
    pub peak_error_pct: f64,
}

/// The bench's result (`--json`).
#[derive(Serialize, Debug, Clone)]
pub struct BenchOut {
    /// `resonant` or `ideal` transducers.
    pub transducers: &'static str,
    /// The slower transducer's τ = Q/(π f_r), ms (0 for ideal ones).
    pub tau_ms: f64,
    /// The drive frequency at the start, Hz (the normal mode's resonance at
    /// rest on resonant transducers; tracking moves it during the run).
    pub freq_hz: f64,
    /// Resonance tracking: `none`, `z` or `x` (`--track`).
    pub track: &'static str,
    /// The displacement loop's headroom (resonant transducers).
    pub headroom: f64,
    /// Plant μ0 / model μ0.
    pub mu0_ratio: f64,
    /// Plant lag, periods.
    pub lag_periods: f64,
    /// μ0 drift, 1/s.
    pub drift_per_s: f64,
    /// ADC noise, counts.
    pub noise_counts: f64,
    /// κ.
    pub gain: f64,
    /// Periods per update.
    pub periods: u32,
    /// Samples per half-buffer of the virtual device.
    pub half_buffer_samples: usize,
    /// Half-buffers the DAC fills run ahead of the output.
    pub fill_lead: usize,
    /// Seed of the ADC noise (0: the default record).
    pub noise_seed: u64,
    /// Updates run.
    pub updates: u32,
    /// Largest commanded Δu_z, m.
    pub max_duz: f64,
    /// The lift-off limit, m.
    pub liftoff_limit: f64,
    /// Samples whose true normal excursion (the plant's transducer, every
    /// sample) exceeded the lift-off limit (must be 0).
    pub commands_above_limit: u64,
    /// Commanded Δu_z above the limit (must be 0).
    pub commanded_above_limit: u32,
    /// The largest true normal excursion over the run, m.
    pub max_excursion_m: f64,
    /// Updates with the rate limit or a bound active.
    pub saturated_updates: u32,
    /// Per event.
    pub events: Vec<EventResponse>,
    /// The hold after the events asked for (`--hold-s`), s of device time.
    pub hold_s: f64,
    /// The hold actually run, s (shorter when a fault ended it).
    pub hold_run_s: f64,
    /// RMS of μ̂ − μ* over the updates of the hold (None without a hold or
    /// without updates in it).
    pub hold_mu_error_rms: Option<f64>,
    /// Largest |μ̂ − μ*| over the updates of the hold.
    pub hold_mu_error_max: Option<f64>,
    /// Device time from the drive's start to the first half-buffer with
    /// `locked`, ms (None: never locked, or no tracking).
    pub lock_ms: Option<f64>,
    /// Largest |`tracking_error_hz`| (the device's own estimate f̂_r − f)
    /// after the lock: over the hold with `--hold-s`, else over the whole
    /// run, Hz (None without a lock).
    pub tracking_error_max_hz: Option<f64>,
    /// Largest |f − f_r| over the same half-buffers, the drive frequency
    /// against the plant's true normal resonance (drift, heat), Hz.
    pub true_offset_max_hz: Option<f64>,
    /// The device's `frequency_hz` at the end of the run, Hz.
    pub frequency_end_hz: f64,
    /// The plant's true normal resonance at the end, Hz (resonant
    /// transducers).
    pub resonance_z_end_hz: Option<f64>,
    /// The device's last `tracking_error_hz` (None when not tracking).
    pub tracking_error_hz: Option<f64>,
    /// The device's `locked` at the end.
    pub locked: bool,
    /// Latched faults that ended the run early (`loss_of_lock`, …), empty
    /// if none.
    pub faults: Vec<String>,
    /// Device time since the drive's start at which the fault was seen, s.
    pub fault_at_s: Option<f64>,
    /// Wall-clock time the run took on this host, s.
    pub wall_s: f64,
    /// The chart, if any (the caller draws it and sets this).
    pub plot: Option<String>,
}

impl BenchOut {
    /// Whether the loop settled after every event with no command or
    /// excursion above the lift-off limit and no fault: the bench's verdict.
    pub fn passed(&self) -> bool {
        self.faults.is_empty()
            && self.commands_above_limit == 0
            && self.commanded_above_limit == 0
            && self.events.iter().all(|e| e.settle_updates.is_some())
    }
}

/// The records of a run up to the end of the events (not the hold), as a
/// chart draws them.
#[derive(Debug, Clone)]
pub struct BenchTrace {
    /// The loop's updates: (device time s, update).
    pub log: Vec<(f64, ControlUpdate)>,
    /// Per half-buffer: (device time s, normal DAC amplitude V, true normal
    /// excursion m).
    pub trace: Vec<(f64, f64, f64)>,
    /// Device times of the four events, s.
    pub t_events: Vec<f64>,
    /// Device time of the end of the events, s.
    pub t_end: f64,
    /// The loop's states at switch-on and after the setpoint step.
    pub states: Vec<ControlState>,
    /// The device's model μ0.
    pub model_mu0: f64,
    /// The two setpoints.
    pub targets: (f32, f32),
}

/// A bench's run: its result and its records.
#[derive(Debug, Clone)]
pub struct BenchRun {
    /// The result.
    pub out: BenchOut,
    /// The records.
    pub trace: BenchTrace,
}

/// Runs the bench. `progress(done_ms, total_ms)` is called every 64
/// half-buffers with the device time run so far. A fault latched during the
/// run ends it and is reported in [`BenchOut::faults`]; a plant whose forces
/// leave the ADC's range (the device then refuses the loop's requests) is
/// an error.
///
/// # Errors
/// One line naming the parameter out of its domain, or the failure.
pub fn run(cfg: &BenchConfig, progress: &mut dyn FnMut(f64, f64)) -> Result<BenchRun> {
    run_checked(cfg, progress).map_err(|e| {
        if e.msg.contains("a fault is latched") {
            Error::failure(format!(
                "the loop did not settle: the plant latched a device fault ({}); its forces leave the ADC's range",
                e.msg.trim_start_matches("device error: ")
            ))
        } else {
            e
        }
    })
}

/// The device time a run of `cfg` takes, ms (the events, then the hold).
///
/// # Errors
/// As [`run`], for the plant.
pub fn device_time_ms(cfg: &BenchConfig) -> Result<f64> {
    Ok(Plan::of(cfg)?.total_ms(cfg))
}

/// The run's fixed quantities, from the configuration.
struct Plan {
    cfg: DeviceConfig,
    resonant: Option<ResonantOptions<f64>>,
    /// The slower mode's τ = Q/(π f_r), s (0 for ideal transducers).
    tau_s: f64,
    freq_hz: f64,
    periods: u32,
    /// Device times of the events (the first after the drive settled) and
    /// of their end, s.
    t_at: [f64; 5],
    /// The segments' durations, ms (each at least 8 τ).
    seg_ms: [f64; 4],
    targets: (f32, f32),
}

impl Plan {
    fn of(c: &BenchConfig) -> Result<Plan> {
        use scenario::*;
        c.check()?;
        let cfg = vd::config();
        let resonant = c
            .transducers
            .options((cfg.dac_z.metres_per_code, cfg.dac_x.metres_per_code), true)?;
        if resonant.is_none() && c.track != Track::None {
            return Err(Error::usage(
                "--track: needs resonant transducers (not --plant-ideal-transducers)",
            ));
        }
        // On resonant transducers: the drive at the normal mode's
        // resonance, times scaled by the slower mode's τ (the plant's Q).
        let tau_s = resonant
            .as_ref()
            .map_or(0.0, |r| r.modes.iter().map(tau_of).fold(0.0, f64::max));
        let freq_hz = resonant
            .as_ref()
            .map_or(FREQ_HZ, |r| r.modes[0].resonance_hz);
        if let Some(r) = &resonant {
            check_bench_plant(r, &cfg, tau_s)?;
        }
        let seg_ms: [f64; 4] =
            std::array::from_fn(|k| (EVENTS_MS[k + 1] - EVENTS_MS[k]).max(8.0 * tau_s * 1e3));
        // Settle 20 ms (or 10 τ), then the events: each at the end of the
        // segment before it (device time).
        let mut t_at = [0.02f64.max(10.0 * tau_s); 5];
        for k in 0..4 {
            t_at[k + 1] = t_at[k] + seg_ms[k] * 1e-3;
        }
        Ok(Plan {
            periods: c.periods.at(freq_hz, cfg.sample_rate_hz),
            targets: if resonant.is_some() {
                TARGETS_RESONANT
            } else {
                TARGETS
            },
            cfg,
            resonant,
            tau_s,
            freq_hz,
            t_at,
            seg_ms,
        })
    }

    fn total_ms(&self, c: &BenchConfig) -> f64 {
        (self.t_at[4] + c.hold_s) * 1e3
    }

    /// The plant: the model's contact with μ0 off by the ratio, the
    /// disturbance and the velocity step in device time.
    fn plant(&self, c: &BenchConfig) -> PlantOptions {
        use scenario::*;
        let (t_d, t_v) = (self.t_at[2], self.t_at[3]);
        PlantOptions {
            v0: V0,
            noise_counts: c.noise,
            offset_counts: 0.0,
            mu0: DEFAULT_CONTACT.0 * c.mu0_ratio,
            kz: DEFAULT_CONTACT.1,
            kx: DEFAULT_CONTACT.2,
            lag_periods: c.lag_periods,
            mu0_drift: c.drift,
            v0_profile: Some(vec![(t_v, V0), (t_v + V_RAMP_MS * 1e-3, V1)]),
            mu0_steps: vec![(t_d, MU0_STEP)],
            resonant: self.resonant,
        }
    }

    fn setting(&self, c: &BenchConfig, target: f32) -> ControlSetting {
        ControlSetting {
            on: true,
            target_mu: target,
            v0_m_s: scenario::V0 as f32,
            gain: c.gain as f32,
            periods: self.periods,
            rate_m_per_s: DEFAULT_RATE as f32,
        }
    }
}

/// τ = Q/(π f_r) of a mode, s.
fn tau_of(m: &ModeParams<f64>) -> f64 {
    m.q / (std::f64::consts::PI * m.resonance_hz)
}

/// One half-buffer of the run as the bench records it.
#[derive(Debug, Clone, Copy)]
struct Half {
    /// Device time at its end, s.
    t: f64,
    /// Normal voltage amplitude, V.
    volts: f64,
    /// True normal excursion, m.
    excursion_m: f64,
    /// The device's drive frequency, Hz.
    freq_hz: f64,
    /// The device's tracking error, Hz.
    tracking_error_hz: Option<f32>,
    /// The tracking is locked.
    locked: bool,
    /// The plant's true normal resonance, Hz (resonant transducers).
    resonance_z_hz: Option<f64>,
}

/// What the hold keeps of its half-buffers and updates: running sums and
/// extremes instead of the records, so that memory stays bounded by the
/// output, not by the hold's duration (a 600 s hold is 4.7 million
/// half-buffers).
#[derive(Debug, Clone, Copy, Default)]
struct Tail {
    /// A half-buffer before the hold was locked.
    locked_before: bool,
    /// The setpoint of the hold.
    target: f32,
    /// The lift-off limit, m.
    limit_m: f64,
    /// The last update's number.
    last_update: Option<u32>,
    max_duz: f64,
    above_limit: u32,
    saturated: u32,
    /// Σ(μ̂ − μ*)², their count and the largest |μ̂ − μ*|.
    err_sq: f64,
    err_n: u32,
    err_max: f64,
    max_excursion_m: f64,
    /// Device time of the first locked half-buffer, s.
    first_locked: Option<f64>,
    /// Largest |tracking error| and |f − true f_r| after the lock, Hz.
    track_err_max: f64,
    true_off_max: f64,
    last: Option<Half>,
}

impl Tail {
    fn update(&mut self, u: &ControlUpdate) {
        self.last_update = Some(u.update);
        let duz = f64::from(u.amp_z_m);
        self.max_duz = self.max_duz.max(duz);
        self.above_limit += u32::from(duz > self.limit_m);
        self.saturated += u32::from(u.saturated);
        let e = f64::from(u.measured_mu) - f64::from(self.target);
        self.err_sq += e * e;
        self.err_n += 1;
        self.err_max = self.err_max.max(e.abs());
    }

    /// A half-buffer of the hold.
    fn half(&mut self, h: Half) {
        self.max_excursion_m = self.max_excursion_m.max(h.excursion_m);
        if h.locked && self.first_locked.is_none() {
            self.first_locked = Some(h.t);
        }
        if self.locked_before || self.first_locked.is_some() {
            self.track_err_max = self
                .track_err_max
                .max(h.tracking_error_hz.map_or(0.0, |x| f64::from(x).abs()));
            self.true_off_max = self
                .true_off_max
                .max(h.resonance_z_hz.map_or(0.0, |r| (h.freq_hz - r).abs()));
        }
        self.last = Some(h);
    }
}

/// An in-process virtual device with a request/telemetry helper.
struct Bench<'p> {
    dev: VirtualDevice,
    seq: u32,
    samples: u64,
    /// (device time s, update).
    log: Vec<(f64, ControlUpdate)>,
    /// Per half-buffer.
    trace: Vec<Half>,
    deframer: Deframer,
    /// Latched faults seen (0: none), and when (device time s).
    faults: (u32, f64),
    /// Progress over the run's device time (ms done, ms in all).
    progress: &'p mut dyn FnMut(f64, f64),
    total_ms: f64,
    /// In the hold: its running summary (the records stop at its start).
    tail: Option<Tail>,
}

impl Bench<'_> {
    fn call(&mut self, req: Request) -> Result<Response> {
        self.seq += 1;
        let f = Frame {
            version: PROTOCOL_VERSION,
            seq: self.seq,
            body: Body::Request(req),
        };
        let mut buf = [0u8; MAX_FRAME];
        let bytes = encode(&f, &mut buf)
            .map_err(|_| Error::failure("request too large"))?
            .to_vec();
        let reply = self.dev.receive(&bytes);
        let mut answer = None;
        for fr in self.frames(&reply) {
            if let Body::Response(r) = fr.body {
                answer = Some(r);
            }
        }
        answer.ok_or_else(|| Error::failure("the virtual device did not answer"))
    }

    /// A request whose answer must not be a refusal.
    fn ask(&mut self, req: Request) -> Result<Response> {
        expect(self.call(req)?)
    }

    fn frames(&mut self, bytes: &[u8]) -> Vec<Frame> {
        let mut v = Vec::new();
        for &b in bytes {
            if let Deframed::Frame(f) = self.deframer.push(b, 0) {
                if let Ok(fr) = decode(f) {
                    v.push(fr);
                }
            }
        }
        v
    }

    fn t(&self) -> f64 {
        self.samples as f64 / self.dev.sample_rate()
    }

    /// Runs `ms` of device time, logging the loop's updates; stops early
    /// at the first latched fault (false then).
    fn run_ms(&mut self, ms: f64) -> bool {
        if self.faults.0 != 0 {
            return false;
        }
        let halves = (ms * 1e-3 * self.dev.sample_rate() / HALF as f64).ceil() as usize;
        for k in 0..halves {
            let tel = self.dev.advance(HALF);
            self.samples += HALF as u64;
            let t = self.t();
            let faults = self.record_half(t);
            for fr in self.frames(&tel) {
                if let Body::Telemetry(Telemetry::Control(u)) = fr.body {
                    match &mut self.tail {
                        Some(tail) => tail.update(&u),
                        None => self.log.push((t, u)),
                    }
                }
            }
            if k % 64 == 0 {
                (self.progress)(t * 1e3, self.total_ms);
            }
            if faults != 0 {
                self.faults = (faults, t);
                return false;
            }
        }
        true
    }

    /// Records the half-buffer that ended at `t`; its latched faults.
    fn record_half(&mut self, t: f64) -> u32 {
        let dev = self.dev.device();
        let volts = f64::from(dev.dds().channels()[0].amp) * board::dds::DAC_VOLTS_PER_CODE;
        let st = dev.status();
        let plant = self.dev.plant();
        let h = Half {
            t,
            volts,
            excursion_m: plant.peak_excursion_m,
            freq_hz: f64::from(st.frequency_hz),
            tracking_error_hz: st.tracking_error_hz,
            locked: st.locked,
            resonance_z_hz: plant
                .resonant
                .as_ref()
                .map(|r| r.params_now()[0].resonance_hz),
        };
        match &mut self.tail {
            Some(tail) => tail.half(h),
            None => self.trace.push(h),
        }
        st.faults
    }
}

/// Drive periods between device times `t0` and `t1`: the drive frequency
/// of each half-buffer integrated over its duration (tracking moves it).
fn periods_between(trace: &[Half], t0: f64, t1: f64) -> f64 {
    let mut n = 0.0;
    let mut prev = None::<f64>;
    for h in trace {
        if let Some(start) = prev {
            let (a, b) = (start.max(t0), h.t.min(t1));
            if b > a {
                n += (b - a) * h.freq_hz;
            }
        }
        prev = Some(h.t);
    }
    n
}

/// Device times of the run's marks, s.
struct Marks {
    /// The drive's start.
    start: f64,
    /// The four events.
    events: Vec<f64>,
    /// The end of the events.
    end: f64,
    /// The end of the hold.
    hold_end: f64,
}

fn run_checked(c: &BenchConfig, progress: &mut dyn FnMut(f64, f64)) -> Result<BenchRun> {
    let wall = std::time::Instant::now();
    let plan = Plan::of(c)?;
    let mut b = set_up(&plan, c, progress)?;
    let (marks, states) = run_events(&mut b, &plan, c)?;
    let out = summarise(&b, &plan, c, &marks, &states, wall.elapsed().as_secs_f64());
    let trace = BenchTrace {
        log: b
            .log
            .iter()
            .filter(|(t, _)| *t <= marks.end)
            .copied()
            .collect(),
        trace: b
            .trace
            .iter()
            .filter(|h| h.t <= marks.end)
            .map(|h| (h.t, h.volts, h.excursion_m))
            .collect(),
        t_events: marks.events,
        t_end: marks.end,
        states,
        model_mu0: DEFAULT_CONTACT.0,
        targets: plan.targets,
    };
    Ok(BenchRun { out, trace })
}

/// The virtual device with the plan's plant, its transducers' exact
/// identification, the drive set and started.
fn set_up<'p>(
    plan: &Plan,
    c: &BenchConfig,
    progress: &'p mut dyn FnMut(f64, f64),
) -> Result<Bench<'p>> {
    use scenario::*;
    let mut b = Bench {
        dev: VirtualDevice::new(plan.plant(c)),
        seq: 0,
        samples: 0,
        log: Vec::new(),
        trace: Vec::new(),
        deframer: Deframer::default(),
        faults: (0, 0.0),
        progress,
        total_ms: plan.total_ms(c),
        tail: None,
    };
    b.dev.set_fill_lead(c.fill_lead);
    if c.seed != 0 {
        b.dev.set_noise_seed(c.seed);
    }
    b.dev.plant_mut().excursion_limit_m = f64::from(plan.cfg.liftoff_limit_m(OFFSET_Z_M));
    if let Some(r) = &plan.resonant {
        // The model an exact identification finds (see the docs).
        b.ask(Request::SetTransducers(Some(
            r.identified(plan.cfg.sample_rate_hz),
        )))?;
        b.ask(Request::SetDriveMode(DriveMode::Displacement))?;
        b.ask(Request::SetDisplacementOptions(DisplacementOptions {
            track: c.track,
            headroom: c.headroom as f32,
        }))?;
    }
    let drive = b.call(Request::SetDrive(DriveSetting {
        freq_hz: plan.freq_hz,
        amp_z_m: AMP_Z0_M,
        amp_x_m: AMP_X_M,
        offset_z_m: OFFSET_Z_M,
        phase_rad: PHASE_DEG.to_radians(),
    }))?;
    if let Response::Error(board::protocol::WireError::OutOfRange {
        param: p @ (DriveParam::AmpZ | DriveParam::AmpX),
        max,
        ..
    }) = drive
    {
        // The bench has no drive flags: the plant asked for cannot give its
        // fixed drive. Name the plant's flags of that channel.
        let f = short(plan.freq_hz);
        let t = &c.transducers;
        let (ch, want, candidates, hint) = if p == DriveParam::AmpZ {
            (
                "normal",
                AMP_Z0_M,
                vec![
                    (t.plant_gain_z, "--plant-gain-z"),
                    (t.plant_q_z, "--plant-q-z"),
                    (t.plant_resonance_z, "--plant-resonance-z"),
                ],
                "a larger gain or Q (the bench drives at this mode's own resonance)".to_string(),
            )
        } else {
            (
                "tangential",
                AMP_X_M,
                vec![
                    (t.plant_gain_x, "--plant-gain-x"),
                    (t.plant_resonance_x, "--plant-resonance-x"),
                    (t.plant_q_x, "--plant-q-x"),
                    (t.plant_resonance_z, "--plant-resonance-z"),
                ],
                format!("a larger gain, or a resonance nearer {f} Hz"),
            )
        };
        // The flags given first (the one the user typed leads the line).
        let given: Vec<&str> = candidates
            .iter()
            .filter(|(v, _)| v.is_some())
            .map(|(_, n)| *n)
            .collect();
        let flags = if given.is_empty() {
            candidates.iter().map(|(_, n)| *n).collect::<Vec<_>>()
        } else {
            given
        }
        .join(", ");
        return Err(Error::usage(format!(
            "{flags}: this plant's {ch} transducer cannot give the bench's fixed drive: {} m at \
             {f} Hz (the normal mode's resonance) needs more than the DAC reaches through it \
             ({} m at most there); {hint}",
            short(crate::answers::f32v(want)),
            short(crate::answers::f32v(max)),
        )));
    }
    expect(drive)?;
    b.ask(Request::Start)?;
    Ok(b)
}

/// Settles the drive, runs the four events and the hold; the marks and the
/// loop's states at switch-on and after the setpoint step.
fn run_events(b: &mut Bench, plan: &Plan, c: &BenchConfig) -> Result<(Marks, Vec<ControlState>)> {
    let start = b.t();
    b.run_ms(plan.t_at[0] * 1e3);
    let mut events = Vec::new();
    let mut states: Vec<ControlState> = Vec::new();
    for (i, target) in [plan.targets.0, plan.targets.1].into_iter().enumerate() {
        events.push(b.t());
        if b.faults.0 != 0 {
            // A fault latched before the event: the device refuses the
            // loop; the events after it have no updates.
            let Some(s) = states.last().copied() else {
                return Err(Error::failure(format!(
                    "the loop did not settle: the device latched {} before the loop was switched on ({:.3} s of device time)",
                    fault_names(b.faults.0).join(", "),
                    b.faults.1
                )));
            };
            states.push(s);
            continue;
        }
        match b.ask(Request::SetControl(plan.setting(c, target)))? {
            Response::Control(s) => states.push(s),
            other => return Err(unexpected(other)),
        }
        b.run_ms(plan.seg_ms[i]);
    }
    // The disturbance and the velocity step happen in the plant (device time).
    events.extend([plan.t_at[2], plan.t_at[3]]);
    b.run_ms((plan.t_at[4] - b.t()) * 1e3);
    // The events end here; the hold (if any) goes on with the last setpoint.
    let end = b.t();
    if c.hold_s > 0.0 {
        b.tail = Some(Tail {
            locked_before: b.trace.iter().any(|h| h.locked),
            target: plan.targets.1,
            limit_m: states
                .first()
                .map_or(f64::INFINITY, |s| f64::from(s.limit_m)),
            ..Tail::default()
        });
        b.run_ms(c.hold_s * 1e3);
    }
    let hold_end = b.t();
    if b.faults.0 == 0 {
        b.ask(Request::SetControl(ControlSetting {
            on: false,
            ..plan.setting(c, plan.targets.1)
        }))?;
    }
    let marks = Marks {
        start,
        events,
        end,
        hold_end,
    };
    Ok((marks, states))
}

/// The estimates of event `k`'s segment (after the event, up to the next
/// one or the end of the events).
fn segment<'a>(
    log: &'a [(f64, ControlUpdate)],
    m: &Marks,
    k: usize,
) -> Vec<&'a (f64, ControlUpdate)> {
    let (t0, t1) = (m.events[k], m.events.get(k + 1).copied().unwrap_or(m.end));
    log.iter().filter(|(t, _)| *t > t0 && *t <= t1).collect()
}

/// The estimates' own scatter in each segment: the standard deviation of
/// μ̂ over the segment's last half (about its mean; at least 4 updates),
/// the loop's own noise at that operating point (the velocity step's
/// segment runs at 6 mm/s).
fn scatters(log: &[(f64, ControlUpdate)], m: &Marks) -> Vec<Option<f64>> {
    (0..4)
        .map(|k| {
            let seg: Vec<f64> = segment(log, m, k)
                .iter()
                .map(|(_, u)| f64::from(u.measured_mu))
                .collect();
            let tail = &seg[seg.len() / 2..];
            (tail.len() >= 4).then(|| {
                let n = tail.len() as f64;
                let mean = tail.iter().sum::<f64>() / n;
                (tail.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt()
            })
        })
        .collect()
}

/// Event `k`'s response: its step, band, settling, overshoot and steady error.
fn event_response(
    b: &Bench,
    m: &Marks,
    k: usize,
    targets: [f32; 4],
    scatter: f64,
    state: &ControlState,
) -> EventResponse {
    let seg = segment(&b.log, m, k);
    let t0 = m.events[k];
    let target = f64::from(targets[k]);
    let err = |u: &ControlUpdate| f64::from(u.measured_mu) - target;
    // The step the event asks the loop to make: the error the loop first
    // measures at switch-on, the setpoint's change, the largest error the
    // disturbance or the velocity step causes.
    let step = match k {
        0 => seg.first().map_or(0.0, |(_, u)| err(u).abs()),
        1 => (target - f64::from(targets[0])).abs(),
        _ => seg.iter().map(|(_, u)| err(u).abs()).fold(0.0, f64::max),
    };
    let mut se: Vec<f64> = seg.iter().map(|(_, u)| f64::from(u.std_error)).collect();
    se.sort_by(f64::total_cmp);
    let band = (0.02 * step).max(4.0 * scatter);
    let settle = (0..seg.len()).find(|&i| seg[i..].iter().all(|(_, u)| err(u).abs() <= band));
    let tail = &seg[seg.len() / 2..];
    let n = tail.len().max(1) as f64;
    let overshoot = (k == 1).then(|| {
        let step = target - f64::from(targets[0]);
        let worst = seg
            .iter()
            .map(|(_, u)| err(u) * step.signum())
            .fold(0.0f64, f64::max);
        100.0 * worst / step.abs()
    });
    let peak = seg.iter().map(|(_, u)| err(u).abs()).fold(0.0f64, f64::max);
    let settle_s = settle.map(|i| seg[i].0 - t0);
    EventResponse {
        event: scenario::EVENTS[k],
        target_mu: target,
        step,
        band,
        scatter,
        std_error: se.get(se.len() / 2).copied().unwrap_or(0.0),
        duz_feedforward: f64::from(state.feedforward_m),
        slope_per_m: f64::from(state.slope_per_m),
        settle_updates: settle.map(|i| i as u32 + 1),
        settle_periods: settle_s.map(|s| periods_between(&b.trace, t0, t0 + s)),
        settle_ms: settle_s.map(|s| s * 1e3),
        overshoot_pct: overshoot,
        overshoot: overshoot.map(|p| p / 100.0),
        steady_error: tail.iter().map(|(_, u)| err(u)).sum::<f64>() / n,
        steady_rms: (tail.iter().map(|(_, u)| err(u).powi(2)).sum::<f64>() / n).sqrt(),
        peak_error_pct: 100.0 * peak / target.abs(),
    }
}

/// The lock and the tracking after it: (device time from the start to the
/// first locked half-buffer s, largest |tracking error| Hz, largest
/// |f − true f_r| Hz), over the hold if there is one, else the whole run.
fn tracking(b: &Bench, m: &Marks) -> (Option<f64>, f64, f64) {
    let first = b.trace.iter().find(|h| h.locked).map(|h| h.t);
    match &b.tail {
        Some(t) => (
            first.or(t.first_locked).map(|l| l - m.start),
            t.track_err_max,
            t.true_off_max,
        ),
        None => {
            let lock_at = first.map(|l| l - m.start);
            let (e, o) = b
                .trace
                .iter()
                .filter(|h| h.t > m.start && lock_at.is_some_and(|l| h.t - m.start >= l))
                .fold((0.0f64, 0.0f64), |(e, o), h| {
                    (
                        e.max(h.tracking_error_hz.map_or(0.0, |x| f64::from(x).abs())),
                        o.max(h.resonance_z_hz.map_or(0.0, |r| (h.freq_hz - r).abs())),
                    )
                });
            (lock_at, e, o)
        }
    }
}

/// The hold's μ̂ − μ*: (RMS, largest magnitude), None without a hold or
/// without updates in it.
fn hold_errors(tail: Option<&Tail>) -> Option<(f64, f64)> {
    tail.filter(|t| t.err_n > 0)
        .map(|t| ((t.err_sq / f64::from(t.err_n)).sqrt(), t.err_max))
}

/// The run's result.
fn summarise(
    b: &Bench,
    plan: &Plan,
    c: &BenchConfig,
    m: &Marks,
    states: &[ControlState],
    wall_s: f64,
) -> BenchOut {
    let (t0, t1) = plan.targets;
    let targets = [t0, t1, t1, t1];
    let sc = scatters(&b.log, m);
    // A segment with fewer than 4 updates in its last half takes the least
    // scatter of the others (0 if none has one).
    let least = sc.iter().flatten().copied().fold(f64::INFINITY, f64::min);
    let least = if least.is_finite() { least } else { 0.0 };
    let events = (0..4)
        .map(|k| event_response(b, m, k, targets, sc[k].unwrap_or(least), &states[k.min(1)]))
        .collect();
    let tail = b.tail.as_ref();
    let hold = hold_errors(tail);
    let (lock_at, track_err, true_off) = tracking(b, m);
    let last = tail.and_then(|t| t.last.as_ref()).or(b.trace.last());
    let limit = f64::from(states[0].limit_m);
    let t = tail.copied().unwrap_or_default();
    BenchOut {
        transducers: if plan.resonant.is_some() {
            "resonant"
        } else {
            "ideal"
        },
        track: match c.track {
            Track::None => "none",
            Track::Z => "z",
            Track::X => "x",
        },
        tau_ms: plan.tau_s * 1e3,
        freq_hz: plan.freq_hz,
        headroom: c.headroom,
        mu0_ratio: c.mu0_ratio,
        lag_periods: c.lag_periods,
        drift_per_s: c.drift,
        noise_counts: c.noise,
        gain: c.gain,
        periods: plan.periods,
        half_buffer_samples: HALF,
        fill_lead: c.fill_lead,
        noise_seed: c.seed,
        updates: t
            .last_update
            .or(b.log.last().map(|(_, u)| u.update))
            .unwrap_or(0),
        max_duz: b
            .log
            .iter()
            .map(|(_, u)| f64::from(u.amp_z_m))
            .fold(t.max_duz, f64::max),
        liftoff_limit: limit,
        commands_above_limit: b.dev.plant().samples_above,
        commanded_above_limit: b
            .log
            .iter()
            .filter(|(_, u)| f64::from(u.amp_z_m) > limit)
            .count() as u32
            + t.above_limit,
        max_excursion_m: b
            .trace
            .iter()
            .map(|h| h.excursion_m)
            .fold(t.max_excursion_m, f64::max),
        saturated_updates: b.log.iter().filter(|(_, u)| u.saturated).count() as u32 + t.saturated,
        events,
        hold_s: c.hold_s,
        hold_run_s: m.hold_end - m.end,
        hold_mu_error_rms: hold.map(|e| e.0),
        hold_mu_error_max: hold.map(|e| e.1),
        lock_ms: lock_at.map(|t| t * 1e3),
        tracking_error_max_hz: lock_at.map(|_| track_err),
        true_offset_max_hz: lock_at.and(plan.resonant.as_ref()).map(|_| true_off),
        frequency_end_hz: last.map_or(plan.freq_hz, |h| h.freq_hz),
        resonance_z_end_hz: last.and_then(|h| h.resonance_z_hz),
        tracking_error_hz: last.and_then(|h| h.tracking_error_hz.map(f64::from)),
        locked: last.is_some_and(|h| h.locked),
        faults: fault_names(b.faults.0),
        fault_at_s: (b.faults.0 != 0).then_some(b.faults.1),
        wall_s,
        plot: None,
    }
}

/// The resonant plant's modes as the device must hold them (the bench
/// stores their exact identification): each in the model's domain and the
/// drive frequency inside the board's range, named by flag.
fn check_bench_plant(r: &ResonantOptions<f64>, cfg: &DeviceConfig, tau_s: f64) -> Result<()> {
    let t = r.identified(cfg.sample_rate_hz);
    for (m, ch) in [(t.z, "z"), (t.x, "x")] {
        if let Err(DeviceError::OutOfRange { param, min, max }) =
            board::device::displacement::check_model(&m)
        {
            let flag = match param {
                DriveParam::Quality => "q",
                DriveParam::TransducerGain => "gain",
                _ => "resonance",
            };
            return Err(Error::usage(format!(
                "--plant-{flag}-{ch}: outside what the device's transducer model holds ([{}, {}])",
                short(f64::from(min)),
                short(f64::from(max))
            )));
        }
    }
    let f = r.modes[0].resonance_hz;
    let (lo, hi) = cfg.freq_range_hz;
    if !(lo..=hi).contains(&f) {
        return Err(Error::usage(format!(
            "--plant-resonance-z: the bench drives at it, so it must be within the board's range [{lo}, {hi}] Hz",
        )));
    }
    if tau_s > MAX_BENCH_TAU_S {
        let ch = if tau_of(&r.modes[0]) >= tau_of(&r.modes[1]) {
            "z"
        } else {
            "x"
        };
        return Err(Error::usage(format!(
            "--plant-q-{ch}: τ = Q/(π f_r) = {tau_s:.3e} s exceeds the bench's {MAX_BENCH_TAU_S} s (each segment lasts 8 τ)",
        )));
    }
    Ok(())
}
