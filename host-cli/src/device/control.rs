//! `fricctl device control …` (the board's closed loop: on with a setpoint,
//! `off`, `status`) and `fricctl device control-bench` (the loop on the
//! mismatched virtual plant: step response, steady state, velocity step,
//! drift; numbers and a chart).

use std::io::Write;
use std::path::PathBuf;

use board::device::{DisplacementOptions, DriveMode, DriveSetting};
use board::protocol::{
    decode, encode, Body, ControlSetting, ControlState, ControlUpdate, Deframed, Deframer, Frame,
    Request, Response, Telemetry, MAX_FRAME, PROTOCOL_VERSION,
};
use clap::Args;
use serde::Serialize;

use super::client::Client;
use super::render;
use super::sim::{PlantOptions, VirtualDevice, HALF};
use super::{expect, out, unexpected};
use crate::args::{Count, Real};
use crate::error::{CliError, CliResult};
use crate::plot::{render_figure, Corner, Extras, Figure, Mark, Panel, Series};

/// Default κ (fraction of the error removed per update, with the plant's
/// gain learned: eqs. C5–C7 of `board::control`).
pub const DEFAULT_GAIN: f64 = 0.95;
/// The loop gain's domain: a fraction of the error removed per update.
const GAIN: Real = Real::ANY.at_least(0.01).at_most(1.0);

pub use crate::args::{parse_periods, Periods};

/// Default rate limit of the commanded Δu_z, m/s (the driver board's slew).
pub const DEFAULT_RATE: f64 = 1e-3;

/// Flags of `fricctl device control`.
#[derive(Args, Debug, Clone)]
pub struct ControlArgs {
    /// `off` (the last command stays applied) or `status`; without it the loop
    /// is switched on (or retargeted) with --target-mu and --v0
    #[arg(value_parser = ["off", "status"])]
    pub action: Option<String>,
    /// Setpoint μ* (|μ*| < μ0 of the device's contact)
    #[arg(long, value_name = "X", value_parser = Real::ANY.single_precision())]
    pub target_mu: Option<f64>,
    /// Sliding velocity v0 the setpoint holds at, m/s (≠ 0)
    #[arg(long, value_name = "V", value_parser = Real::ANY.single_precision())]
    pub v0: Option<f64>,
    /// κ: fraction of the error removed per update, in [0.01, 1]
    #[arg(long, default_value_t = DEFAULT_GAIN, value_parser = GAIN)]
    pub gain: f64,
    /// Drive periods per estimate (one update each), 1 … 10 000, or `auto`:
    /// as many as fit one DAC half-buffer at the drive frequency (1 at
    /// 20 kHz, 4 at 40 kHz), the shortest update interval
    #[arg(long, default_value = "auto", value_parser = parse_periods)]
    pub periods: Periods,
    /// Rate limit of the commanded Δu_z, m/s (at most the board's slew, 1e-3)
    #[arg(long, default_value_t = DEFAULT_RATE, value_parser = Real::positive().single_precision())]
    pub rate: f64,
    /// The displacement loop's headroom while the loop runs (displacement
    /// mode; the tracking in force is kept)
    #[arg(long, value_name = "H", value_parser = Real::ANY.at_least(1.0).at_most(8.0).because("1 is no overdrive").single_precision())]
    pub headroom: Option<f64>,
}

impl ControlArgs {
    /// The request, checked before connecting (each bad flag named).
    ///
    /// # Errors
    /// One line naming the flag.
    pub fn request(&self) -> CliResult<Request> {
        match self.action.as_deref() {
            Some("status") => return Ok(Request::GetControl),
            Some(_) => {
                return Ok(Request::SetControl(ControlSetting {
                    on: false,
                    target_mu: 0.0,
                    v0_m_s: 0.0,
                    gain: self.gain as f32,
                    periods: 1,
                    rate_m_per_s: self.rate as f32,
                }))
            }
            None => {}
        }
        let target = self.target_mu.ok_or_else(|| {
            CliError::usage("--target-mu: missing (or `device control off|status`)")
        })?;
        let v0 = self.v0.ok_or_else(|| {
            CliError::usage("--v0: missing (the setpoint holds at a sliding velocity)")
        })?;
        // Each value is in its domain (the flags' parsers).
        if v0 == 0.0 {
            return Err(CliError::usage("--v0: must be != 0 (got 0)"));
        }
        Ok(Request::SetControl(ControlSetting {
            on: true,
            target_mu: target as f32,
            v0_m_s: v0 as f32,
            gain: self.gain as f32,
            // `auto` is resolved on the device's frequency by `run`.
            periods: match self.periods {
                Periods::Fixed(n) => n,
                Periods::Auto => 1,
            },
            rate_m_per_s: self.rate as f32,
        }))
    }
}

/// `fricctl device control …` on a connected device (`--headroom` first,
/// keeping the tracking in force; put back if the device refuses the
/// control request, so that a refused command changes nothing).
pub fn run(c: &mut Client, req: Request, a: &ControlArgs, json: bool) -> CliResult {
    let mut req = req;
    if let (Request::SetControl(s), Periods::Auto) = (&mut req, a.periods) {
        if s.on {
            let fs = match expect(c.call(Request::Hello)?)? {
                Response::Info(i) => i.sample_rate_hz,
                other => return Err(unexpected(other)),
            };
            let f = match expect(c.call(Request::GetStatus)?)? {
                Response::Status(st) => f64::from(st.frequency_hz),
                other => return Err(unexpected(other)),
            };
            s.periods = a.periods.at(f, fs);
        }
    }
    let mut before = None;
    if let Some(h) = a.headroom {
        let st = match expect(c.call(Request::GetStatus)?)? {
            Response::Status(s) => s,
            other => return Err(unexpected(other)),
        };
        expect(c.call(Request::SetDisplacementOptions(
            board::device::DisplacementOptions {
                headroom: h as f32,
                ..st.options
            },
        ))?)?;
        before = Some(st.options);
    }
    match c.call(req).and_then(expect) {
        Ok(Response::Control(s)) => out(json, &render::control(&s)),
        Ok(other) => Err(unexpected(other)),
        Err(e) => {
            if let Some(o) = before {
                // The refusal is the error reported; a failure to restore
                // is named after it.
                if let Err(r) = c.call(Request::SetDisplacementOptions(o)).and_then(expect) {
                    return Err(CliError::failure(format!(
                        "{e}; and the headroom could not be put back to {}: {r}",
                        o.headroom
                    )));
                }
            }
            Err(e)
        }
    }
}

/// Flags of `fricctl device control-bench`.
#[derive(Args, Debug, Clone)]
pub struct BenchArgs {
    /// Chart of the run (PNG or SVG)
    #[arg(long, value_name = "FILE")]
    pub plot: Option<PathBuf>,
    /// True μ0 of the plant relative to the device's model μ0 = 0.3 (0.8: 20 % lower)
    #[arg(long, default_value_t = 0.8, value_parser = Real::positive())]
    pub mu0_ratio: f64,
    /// Transducer amplitude lag of the plant, drive periods
    #[arg(long, default_value_t = 2.0, value_parser = Real::non_negative())]
    pub lag_periods: f64,
    /// Drift of the plant's μ0, per second of device time (the bench's
    /// disturbance is a step of μ0, at the third event)
    #[arg(long, default_value_t = 0.0, value_parser = Real::ANY)]
    pub drift: f64,
    /// ADC noise, ± counts
    #[arg(long, default_value_t = 2.0, value_parser = super::sim::NOISE_COUNTS)]
    pub noise: f64,
    /// κ of the loop, in [0.01, 1]
    #[arg(long, default_value_t = DEFAULT_GAIN, value_parser = GAIN)]
    pub gain: f64,
    /// Drive periods per update, or `auto` (as `device control`)
    #[arg(long, default_value = "auto", value_parser = parse_periods)]
    pub periods: Periods,
    /// Half-buffers the DAC fills run ahead of the output: 2 as on the board
    /// (a command reaches the output 2 half-buffers after the next), 0 for
    /// the fastest possible pipeline (at most 16)
    #[arg(long, default_value_t = 2, value_parser = Count::<usize>::at_least(0).at_most(16, "the board fills 2 ahead"))]
    pub fill_lead: usize,
    /// Seed of the plant's ADC noise (0: the virtual device's default record)
    #[arg(long, default_value_t = 0, value_parser = Count::<u64>::at_least(0))]
    pub seed: u64,
    /// The transducers (resonant by default; ideal with
    /// --plant-ideal-transducers, then with --lag-periods).
    #[command(flatten)]
    pub transducers: super::transducers::TransducerArgs,
    /// The displacement loop's headroom (resonant transducers).
    #[command(flatten)]
    pub headroom: super::HeadroomArg,
    /// Resonance tracking during the run, as `device drive set --track`:
    /// the drive frequency follows this transducer's resonance (resonant
    /// transducers); `none` keeps the normal mode's resonance at rest
    #[arg(long, value_enum, default_value_t = super::TrackArg::None)]
    pub track: super::TrackArg,
    /// After the four events, hold the last setpoint this many seconds of
    /// device time (a drifting plant: μ error, tracking error, lock), 0 … 600
    #[arg(long, value_name = "S", default_value_t = 0.0, value_parser = Real::non_negative().at_most(MAX_HOLD_S))]
    pub hold_s: f64,
}

/// The longest `--hold-s`, s of device time (ten minutes).
pub const MAX_HOLD_S: f64 = 600.0;

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
}

/// One event's response.
#[derive(Serialize, Debug, Clone)]
pub struct Response2 {
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
    pub events: Vec<Response2>,
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
    /// The chart, if any.
    pub plot: Option<String>,
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

/// An in-process virtual device with a request/telemetry helper.
struct Bench {
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
    /// Progress over the run's device time (ms), if shown.
    bar: Option<indicatif::ProgressBar>,
}

impl Bench {
    fn call(&mut self, req: Request) -> CliResult<Response> {
        self.seq += 1;
        let f = Frame {
            version: PROTOCOL_VERSION,
            seq: self.seq,
            body: Body::Request(req),
        };
        let mut buf = [0u8; MAX_FRAME];
        let bytes = encode(&f, &mut buf)
            .map_err(|_| CliError::failure("request too large"))?
            .to_vec();
        let reply = self.dev.receive(&bytes);
        let mut answer = None;
        for fr in self.frames(&reply) {
            if let Body::Response(r) = fr.body {
                answer = Some(r);
            }
        }
        answer.ok_or_else(|| CliError::failure("the virtual device did not answer"))
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
            let dev = self.dev.device();
            let volts = f64::from(dev.dds().channels()[0].amp) * board::dds::DAC_VOLTS_PER_CODE;
            let st = dev.status();
            self.trace.push(Half {
                t,
                volts,
                excursion_m: self.dev.plant().peak_excursion_m,
                freq_hz: f64::from(st.frequency_hz),
                tracking_error_hz: st.tracking_error_hz,
                locked: st.locked,
                resonance_z_hz: self
                    .dev
                    .plant()
                    .resonant
                    .as_ref()
                    .map(|r| r.params_now()[0].resonance_hz),
            });
            for fr in self.frames(&tel) {
                if let Body::Telemetry(Telemetry::Control(u)) = fr.body {
                    self.log.push((t, u));
                }
            }
            if let Some(b) = &self.bar {
                if k % 64 == 0 {
                    b.set_position((t * 1e3) as u64);
                }
            }
            if st.faults != 0 {
                self.faults = (st.faults, t);
                return false;
            }
        }
        true
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

/// `fricctl device control-bench`. A plant whose forces leave the ADC's
/// range latches the device's saturation fault: that ends the bench with
/// the verdict (exit 1) rather than the device's raw refusal.
pub fn bench(a: &BenchArgs, json: bool) -> CliResult {
    if let Some(p) = &a.plot {
        crate::plot::ext(p)?;
        crate::output::may_write(p, "plot")?;
    }
    let o = bench_out(a, true)?;
    let mut w = std::io::stdout().lock();
    let r = if json {
        writeln!(
            w,
            "{}",
            serde_json::to_string_pretty(&o).unwrap_or_default()
        )
    } else {
        write_text(&mut w, &o)
    };
    r.map_err(crate::output::stdout_error)?;
    if !o.faults.is_empty() {
        return Err(CliError::failure(format!(
            "the run ended at {:.3} s of device time: the device latched {}",
            o.fault_at_s.unwrap_or(0.0),
            o.faults.join(", ")
        )));
    }
    let bad = o.commands_above_limit > 0
        || o.commanded_above_limit > 0
        || o.events.iter().any(|e| e.settle_updates.is_none());
    if bad {
        return Err(CliError::failure(
            "the loop did not settle within 2 % after every event, or a command exceeded the lift-off limit",
        ));
    }
    Ok(())
}

/// The bench's run and its result, without printing (`fricctl bench
/// control` runs it over a grid): the chart of `--plot` is written (the
/// caller has applied the overwrite policy); `progress` shows a bar on
/// stderr for runs longer than 5 s of device time. A fault latched during
/// the run ends it and is reported in [`BenchOut::faults`]; a plant whose
/// forces leave the ADC's range (the device then refuses the loop's
/// requests) is an error.
///
/// # Errors
/// One line naming the flag out of its domain, or the failure.
pub fn bench_out(a: &BenchArgs, progress: bool) -> CliResult<BenchOut> {
    bench_run(a, progress).map_err(|e| {
        if e.msg.contains("a fault is latched") {
            CliError::failure(format!(
                "the loop did not settle: the plant latched a device fault ({}); its forces leave the ADC's range",
                e.msg.trim_start_matches("device error: ")
            ))
        } else {
            e
        }
    })
}

fn bench_run(a: &BenchArgs, progress: bool) -> CliResult<BenchOut> {
    use scenario::*;
    // Every value is in its domain (the flags' parsers).
    let wall = std::time::Instant::now();
    let cfg = super::sim::config();
    let resonant = a
        .transducers
        .options((cfg.dac_z.metres_per_code, cfg.dac_x.metres_per_code), true)?;
    if resonant.is_none() && a.track != super::TrackArg::None {
        return Err(CliError::usage(
            "--track: needs resonant transducers (not --plant-ideal-transducers)",
        ));
    }
    // On resonant transducers: the drive at the normal mode's resonance,
    // times scaled by the slower mode's τ = Q/(π f_r) (the plant's Q).
    let tau_s = resonant.as_ref().map_or(0.0, |r| {
        r.modes
            .iter()
            .map(|m| m.q / (std::f64::consts::PI * m.resonance_hz))
            .fold(0.0, f64::max)
    });
    let freq_hz = resonant
        .as_ref()
        .map_or(FREQ_HZ, |r| r.modes[0].resonance_hz);
    if let Some(r) = &resonant {
        check_bench_plant(r, &cfg, tau_s)?;
    }
    let periods = a.periods.at(freq_hz, cfg.sample_rate_hz);
    let seg_ms = |k: usize| (EVENTS_MS[k + 1] - EVENTS_MS[k]).max(8.0 * tau_s * 1e3);
    let model_mu0 = super::sim::DEFAULT_CONTACT.0;
    // Settle 20 ms (or 10 τ), then the events: each at the end of the
    // segment before it (device time).
    let settle_s = 0.02f64.max(10.0 * tau_s);
    let mut t_at = vec![settle_s];
    for k in 0..4 {
        t_at.push(t_at[k] + seg_ms(k) * 1e-3);
    }
    let (t_d, t_v) = (t_at[2], t_at[3]);
    let opts = PlantOptions {
        v0: V0,
        noise_counts: a.noise,
        offset_counts: 0.0,
        mu0: model_mu0 * a.mu0_ratio,
        kz: super::sim::DEFAULT_CONTACT.1,
        kx: super::sim::DEFAULT_CONTACT.2,
        lag_periods: a.lag_periods,
        mu0_drift: a.drift,
        v0_profile: Some(vec![(t_v, V0), (t_v + V_RAMP_MS * 1e-3, V1)]),
        mu0_steps: vec![(t_d, MU0_STEP)],
        resonant,
    };
    let total_ms = (t_at[4] + a.hold_s) * 1e3;
    let bar = (progress && total_ms > 5e3).then(|| {
        let b = indicatif::ProgressBar::new(total_ms as u64);
        b.set_style(
            indicatif::ProgressStyle::with_template(
                "{bar:30} {pos}/{len} ms of device time  [{elapsed_precise}, eta {eta}]",
            )
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        b
    });
    let mut b = Bench {
        dev: VirtualDevice::new(opts),
        seq: 0,
        samples: 0,
        log: Vec::new(),
        trace: Vec::new(),
        deframer: Deframer::default(),
        faults: (0, 0.0),
        bar,
    };
    b.dev.set_fill_lead(a.fill_lead);
    if a.seed != 0 {
        b.dev.set_noise_seed(a.seed);
    }
    b.dev.plant_mut().excursion_limit_m = f64::from(cfg.liftoff_limit_m(OFFSET_Z_M));
    if let Some(r) = &resonant {
        // The model an exact identification finds (see the docs).
        expect(b.call(Request::SetTransducers(Some(
            r.identified(cfg.sample_rate_hz),
        )))?)?;
        expect(b.call(Request::SetDriveMode(DriveMode::Displacement))?)?;
        expect(b.call(Request::SetDisplacementOptions(DisplacementOptions {
            track: a.track.into(),
            headroom: a.headroom.headroom as f32,
        }))?)?;
    }
    let drive = DriveSetting {
        freq_hz,
        amp_z_m: AMP_Z0_M,
        amp_x_m: AMP_X_M,
        offset_z_m: OFFSET_Z_M,
        phase_rad: PHASE_DEG.to_radians(),
    };
    expect(b.call(Request::SetDrive(drive))?)?;
    expect(b.call(Request::Start)?)?;
    let t_start = b.t();
    b.run_ms(settle_s * 1e3);
    let setting = |target: f32| ControlSetting {
        on: true,
        target_mu: target,
        v0_m_s: V0 as f32,
        gain: a.gain as f32,
        periods,
        rate_m_per_s: DEFAULT_RATE as f32,
    };
    let mut t_events = Vec::new();
    let mut states = Vec::new();
    let targets = if resonant.is_some() {
        TARGETS_RESONANT
    } else {
        TARGETS
    };
    for (i, target) in [targets.0, targets.1].into_iter().enumerate() {
        t_events.push(b.t());
        if b.faults.0 != 0 {
            // A fault latched before the event: the device refuses the
            // loop; the events after it have no updates.
            match states.last().copied() {
                Some(s) => states.push(s),
                None => {
                    return Err(CliError::failure(format!(
                        "the loop did not settle: the device latched {} before the loop was switched on ({:.3} s of device time)",
                        super::render::fault_names(b.faults.0).join(", "),
                        b.faults.1
                    )))
                }
            }
            continue;
        }
        match expect(b.call(Request::SetControl(setting(target)))?)? {
            Response::Control(s) => states.push(s),
            other => return Err(unexpected(other)),
        }
        b.run_ms(seg_ms(i));
    }
    // The disturbance and the velocity step happen in the plant (device time).
    t_events.push(t_d);
    t_events.push(t_v);
    b.run_ms((t_at[4] - b.t()) * 1e3);
    // The events end here; the hold (if any) goes on with the last setpoint.
    let t_end = b.t();
    if a.hold_s > 0.0 {
        b.run_ms(a.hold_s * 1e3);
    }
    let t_hold_end = b.t();
    if let Some(bar) = &b.bar {
        bar.finish_and_clear();
    }
    if b.faults.0 == 0 {
        expect(b.call(Request::SetControl(ControlSetting {
            on: false,
            ..setting(targets.1)
        }))?)?;
    }
    let limit = f64::from(states[0].limit_m);
    let names = ["switch_on", "setpoint_step", "disturbance", "velocity_step"];
    let pair = targets;
    let targets = [pair.0, pair.1, pair.1, pair.1];
    let mut events = Vec::new();
    // The estimates' own scatter in each segment: the standard deviation of
    // μ̂ over the segment's last half (about its mean; at least 4 updates),
    // the loop's own noise at that operating point (the velocity step's
    // segment runs at 6 mm/s). The device's standard error (median,
    // reported per event) is 0 for estimates of fewer than 2 periods.
    let scatters: Vec<Option<f64>> = (0..4)
        .map(|k| {
            let (t0, t1) = (t_events[k], if k < 3 { t_events[k + 1] } else { t_end });
            let seg: Vec<f64> = b
                .log
                .iter()
                .filter(|(t, _)| *t > t0 && *t <= t1)
                .map(|(_, u)| f64::from(u.measured_mu))
                .collect();
            let tail = &seg[seg.len() / 2..];
            (tail.len() >= 4).then(|| {
                let n = tail.len() as f64;
                let m = tail.iter().sum::<f64>() / n;
                (tail.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0)).sqrt()
            })
        })
        .collect();
    let least = scatters
        .iter()
        .flatten()
        .copied()
        .fold(f64::INFINITY, f64::min);
    let least = if least.is_finite() { least } else { 0.0 };
    for k in 0..4 {
        let (t0, t1) = (t_events[k], if k < 3 { t_events[k + 1] } else { t_end });
        let seg: Vec<&(f64, ControlUpdate)> =
            b.log.iter().filter(|(t, _)| *t > t0 && *t <= t1).collect();
        let target = f64::from(targets[k]);
        let err = |u: &ControlUpdate| f64::from(u.measured_mu) - target;
        // The step the event asks the loop to make: the setpoint's change,
        // the error the loop first measures at switch-on, the largest error
        // the velocity step causes.
        let step = match k {
            0 => seg.first().map_or(0.0, |(_, u)| err(u).abs()),
            1 => (target - f64::from(targets[0])).abs(),
            _ => seg.iter().map(|(_, u)| err(u).abs()).fold(0.0, f64::max),
        };
        // Settled: within 2 % of the step, or within four times the
        // segment's scatter (above) when that is wider: no single estimate
        // resolves less, and a settled loop's estimates leave ±4σ once in
        // ≈ 16 000 (Gaussian), not once in a segment's 20–250 updates as
        // they would ±3σ (once in 370).
        let mut se: Vec<f64> = seg.iter().map(|(_, u)| f64::from(u.std_error)).collect();
        se.sort_by(f64::total_cmp);
        let std_error = se.get(se.len() / 2).copied().unwrap_or(0.0);
        let scatter = scatters[k].unwrap_or(least);
        let band = (0.02 * step).max(4.0 * scatter);
        let mut settle = None;
        for (i, _) in seg.iter().enumerate() {
            if seg[i..].iter().all(|(_, u)| err(u).abs() <= band) {
                settle = Some(i);
                break;
            }
        }
        let tail = &seg[seg.len() / 2..];
        let n = tail.len().max(1) as f64;
        let mean = tail.iter().map(|(_, u)| err(u)).sum::<f64>() / n;
        let rms = (tail.iter().map(|(_, u)| err(u).powi(2)).sum::<f64>() / n).sqrt();
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
        events.push(Response2 {
            event: names[k],
            target_mu: target,
            step,
            band,
            scatter,
            std_error,
            duz_feedforward: f64::from(states[k.min(1)].feedforward_m),
            slope_per_m: f64::from(states[k.min(1)].slope_per_m),
            settle_updates: settle.map(|i| i as u32 + 1),
            settle_periods: settle_s.map(|s| periods_between(&b.trace, t0, t0 + s)),
            settle_ms: settle_s.map(|s| s * 1e3),
            overshoot_pct: overshoot,
            overshoot: overshoot.map(|p| p / 100.0),
            steady_error: mean,
            steady_rms: rms,
            peak_error_pct: 100.0 * peak / target.abs(),
        });
    }
    // The hold: μ̂ − μ* of its updates (the last setpoint).
    let hold: Vec<f64> = b
        .log
        .iter()
        .filter(|(t, _)| *t > t_end)
        .map(|(_, u)| f64::from(u.measured_mu) - f64::from(pair.1))
        .collect();
    let hold_err = (!hold.is_empty()).then(|| {
        let rms = (hold.iter().map(|e| e * e).sum::<f64>() / hold.len() as f64).sqrt();
        (rms, hold.iter().map(|e| e.abs()).fold(0.0, f64::max))
    });
    // The lock (device time from the start, the first half-buffer that
    // reports it), then the tracking errors after it (and in the hold, if
    // any): the device's own and against the plant's true resonance.
    let lock_at = b.trace.iter().find(|h| h.locked).map(|h| h.t - t_start);
    let from = if a.hold_s > 0.0 { t_end } else { t_start };
    let after_lock = b
        .trace
        .iter()
        .filter(|h| h.t > from && lock_at.is_some_and(|l| h.t - t_start >= l))
        .fold((0.0f64, 0.0f64), |(e, o), h| {
            (
                e.max(h.tracking_error_hz.map_or(0.0, |x| f64::from(x).abs())),
                o.max(h.resonance_z_hz.map_or(0.0, |r| (h.freq_hz - r).abs())),
            )
        });
    let last = b.trace.last();
    let max_duz = b
        .log
        .iter()
        .map(|(_, u)| f64::from(u.amp_z_m))
        .fold(0.0, f64::max);
    let o = BenchOut {
        transducers: if resonant.is_some() {
            "resonant"
        } else {
            "ideal"
        },
        track: match a.track {
            super::TrackArg::None => "none",
            super::TrackArg::Z => "z",
            super::TrackArg::X => "x",
        },
        tau_ms: tau_s * 1e3,
        freq_hz,
        headroom: a.headroom.headroom,
        mu0_ratio: a.mu0_ratio,
        lag_periods: a.lag_periods,
        drift_per_s: a.drift,
        noise_counts: a.noise,
        gain: a.gain,
        periods,
        half_buffer_samples: HALF,
        fill_lead: a.fill_lead,
        noise_seed: a.seed,
        updates: b.log.last().map_or(0, |(_, u)| u.update),
        max_duz,
        liftoff_limit: limit,
        commands_above_limit: b.dev.plant().samples_above,
        commanded_above_limit: b
            .log
            .iter()
            .filter(|(_, u)| f64::from(u.amp_z_m) > limit)
            .count() as u32,
        max_excursion_m: b.trace.iter().map(|h| h.excursion_m).fold(0.0, f64::max),
        saturated_updates: b.log.iter().filter(|(_, u)| u.saturated).count() as u32,
        events,
        hold_s: a.hold_s,
        hold_run_s: t_hold_end - t_end,
        hold_mu_error_rms: hold_err.as_ref().map(|e| e.0),
        hold_mu_error_max: hold_err.as_ref().map(|e| e.1),
        lock_ms: lock_at.map(|t| t * 1e3),
        tracking_error_max_hz: lock_at.map(|_| after_lock.0),
        true_offset_max_hz: lock_at.and(resonant.as_ref()).map(|_| after_lock.1),
        frequency_end_hz: last.map_or(freq_hz, |h| h.freq_hz),
        resonance_z_end_hz: last.and_then(|h| h.resonance_z_hz),
        tracking_error_hz: last.and_then(|h| h.tracking_error_hz.map(f64::from)),
        locked: last.is_some_and(|h| h.locked),
        faults: super::render::fault_names(b.faults.0),
        fault_at_s: (b.faults.0 != 0).then_some(b.faults.1),
        wall_s: wall.elapsed().as_secs_f64(),
        plot: a.plot.as_ref().map(|p| p.display().to_string()),
    };
    if let Some(p) = &a.plot {
        let log: Vec<(f64, ControlUpdate)> =
            b.log.iter().filter(|(t, _)| *t <= t_end).copied().collect();
        let trace: Vec<(f64, f64, f64)> = b
            .trace
            .iter()
            .filter(|h| h.t <= t_end)
            .map(|h| (h.t, h.volts, h.excursion_m))
            .collect();
        chart(
            p, &log, &trace, &t_events, t_end, &states, &o, model_mu0, pair,
        )?;
    }
    Ok(o)
}

/// The longest τ the bench runs (its segments last 8 τ each): 50 ms,
/// Q ≈ 3 000 at 20 kHz.
pub const MAX_BENCH_TAU_S: f64 = 0.05;

/// The resonant plant's modes as the device must hold them (the bench
/// stores their exact identification): each in the model's domain and the
/// drive frequency inside the board's range, named by flag.
fn check_bench_plant(
    r: &board::plant::ResonantOptions<f64>,
    cfg: &board::device::DeviceConfig,
    tau_s: f64,
) -> CliResult {
    let t = r.identified(cfg.sample_rate_hz);
    for (m, ch) in [(t.z, "z"), (t.x, "x")] {
        if let Err(board::device::DeviceError::OutOfRange { param, min, max }) =
            board::device::displacement::check_model(&m)
        {
            let flag = match param {
                board::device::DriveParam::Resonance => "resonance",
                board::device::DriveParam::Quality => "q",
                board::device::DriveParam::TransducerGain => "gain",
                _ => "resonance",
            };
            return Err(CliError::usage(format!(
                "--plant-{flag}-{ch}: outside what the device's transducer model holds ([{}, {}])",
                crate::args::short(f64::from(min)),
                crate::args::short(f64::from(max))
            )));
        }
    }
    let f = r.modes[0].resonance_hz;
    let (lo, hi) = cfg.freq_range_hz;
    if !(lo..=hi).contains(&f) {
        return Err(CliError::usage(format!(
            "--plant-resonance-z: the bench drives at it, so it must be within the board's range [{lo}, {hi}] Hz",
        )));
    }
    if tau_s > MAX_BENCH_TAU_S {
        let tau =
            |m: &board::resonator::ModeParams<f64>| m.q / (std::f64::consts::PI * m.resonance_hz);
        let ch = if tau(&r.modes[0]) >= tau(&r.modes[1]) {
            "z"
        } else {
            "x"
        };
        return Err(CliError::usage(format!(
            "--plant-q-{ch}: τ = Q/(π f_r) = {:.3e} s exceeds the bench's {MAX_BENCH_TAU_S} s (each segment lasts 8 τ)",
            tau_s
        )));
    }
    Ok(())
}

fn opt(x: Option<f64>, prec: usize) -> String {
    x.map_or("never".to_string(), |v| format!("{v:.prec$}"))
}

fn write_text(w: &mut impl Write, o: &BenchOut) -> std::io::Result<()> {
    writeln!(
        w,
        "plant: mu0 = {} x model, lag {} periods, drift {} /s, noise ±{} counts; loop: gain {}, {} periods/update, {} samples/half-buffer, fills {} half-buffers ahead",
        o.mu0_ratio, o.lag_periods, o.drift_per_s, o.noise_counts, o.gain, o.periods, o.half_buffer_samples, o.fill_lead
    )?;
    writeln!(
        w,
        "{:<14} {:>8} {:>8} {:>9} {:>9} {:>10} {:>11} {:>10} {:>10}",
        "event", "target", "updates", "periods", "ms", "overshoot", "steady err", "rms", "peak err"
    )?;
    for e in &o.events {
        writeln!(
            w,
            "{:<14} {:>8.4} {:>8} {:>9} {:>9} {:>9} {:>11.2e} {:>10.2e} {:>9.1}%",
            e.event,
            e.target_mu,
            e.settle_updates.map_or("never".into(), |u| u.to_string()),
            opt(e.settle_periods, 1),
            opt(e.settle_ms, 3),
            e.overshoot_pct.map_or("-".into(), |x| format!("{x:.1}%")),
            e.steady_error,
            e.steady_rms,
            e.peak_error_pct
        )?;
    }
    writeln!(
        w,
        "max duz {:.4e} m of lift-off limit {:.4e} m ({} commands above it); {} of {} updates rate- or bound-limited",
        o.max_duz, o.liftoff_limit, o.commands_above_limit, o.saturated_updates, o.updates
    )?;
    if o.hold_s > 0.0 {
        writeln!(
            w,
            "hold {:.3} s of {} s: mu error rms {}, max {}",
            o.hold_run_s,
            o.hold_s,
            o.hold_mu_error_rms
                .map_or("-".into(), |x| format!("{x:.2e}")),
            o.hold_mu_error_max
                .map_or("-".into(), |x| format!("{x:.2e}")),
        )?;
    }
    if o.track != "none" {
        writeln!(
            w,
            "tracking {}: locked after {} ms; after the lock |tracking error| <= {} Hz, |f - true f_r| <= {} Hz",
            o.track,
            opt(o.lock_ms, 2),
            opt(o.tracking_error_max_hz, 3),
            opt(o.true_offset_max_hz, 3),
        )?;
        writeln!(
            w,
            "at the end: f = {:.2} Hz, true f_r = {}, locked {}",
            o.frequency_end_hz,
            o.resonance_z_end_hz
                .map_or("-".into(), |f| format!("{f:.2} Hz")),
            o.locked
        )?;
    }
    if !o.faults.is_empty() {
        writeln!(
            w,
            "ended by a fault at {:.3} s: {}",
            o.fault_at_s.unwrap_or(0.0),
            o.faults.join(", ")
        )?;
    }
    writeln!(
        w,
        "settling: to within 2 % of the step (or 4 x the estimates' scatter in the segment if wider), every later estimate too;"
    )?;
    writeln!(
        w,
        "time to the end of the half-buffer of that update (drive {:.0} Hz at the start: 1 period = {:.2} µs)",
        o.freq_hz,
        1e6 / o.freq_hz
    )
}

#[allow(clippy::too_many_arguments)]
fn chart(
    path: &std::path::Path,
    log: &[(f64, ControlUpdate)],
    trace: &[(f64, f64, f64)],
    t_events: &[f64],
    t_end: f64,
    states: &[ControlState],
    o: &BenchOut,
    model_mu0: f64,
    targets: (f32, f32),
) -> CliResult {
    use scenario::*;
    let resonant = o.transducers == "resonant";
    let t0 = t_events[0] - 0.002;
    let ms = |t: f64| (t - t0) * 1e3;
    let x = (0.0, ms(t_end));
    let meas: Vec<(f64, f64)> = log
        .iter()
        .map(|(t, u)| (ms(*t), f64::from(u.measured_mu)))
        .collect();
    let setp: Vec<(f64, f64)> = {
        let mut v = vec![(ms(t_events[0]), f64::from(targets.0))];
        v.push((ms(t_events[1]), f64::from(targets.0)));
        v.push((ms(t_events[1]), f64::from(targets.1)));
        v.push((ms(t_end), f64::from(targets.1)));
        v
    };
    let band = |s: f64| -> Vec<(f64, f64)> {
        vec![
            (ms(t_events[0]), f64::from(targets.0) * (1.0 + s)),
            (ms(t_events[1]), f64::from(targets.0) * (1.0 + s)),
            (ms(t_events[1]), f64::NAN),
            (ms(t_events[1]), f64::from(targets.1) * (1.0 + s)),
            (ms(t_end), f64::from(targets.1) * (1.0 + s)),
        ]
    };
    let cmd: Vec<(f64, f64)> = log
        .iter()
        .map(|(t, u)| (ms(*t), f64::from(u.amp_z_m) * 1e6))
        .collect();
    let ff: Vec<(f64, f64)> = vec![
        (ms(t_events[0]), f64::from(states[0].feedforward_m) * 1e6),
        (ms(t_events[1]), f64::from(states[0].feedforward_m) * 1e6),
        (ms(t_events[1]), f64::from(states[1].feedforward_m) * 1e6),
        (ms(t_end), f64::from(states[1].feedforward_m) * 1e6),
    ];
    let lim = vec![(x.0, o.liftoff_limit * 1e6), (x.1, o.liftoff_limit * 1e6)];
    let events_note = format!(
        "events: loop on at {:.1} ms, setpoint step at {:.1} ms, μ0 × {MU0_STEP} at {:.1} ms, v0 {}→{} mm/s at {:.1} ms",
        ms(t_events[0]),
        ms(t_events[1]),
        ms(t_events[2]),
        V0 * 1e3,
        V1 * 1e3,
        ms(t_events[3])
    );
    let p1 = Panel {
        title: "Closed loop on the mismatched virtual plant: μ".into(),
        x_label: "device time, ms".into(),
        y_label: "μ".into(),
        x,
        y: if resonant { (0.03, 0.14) } else { (0.04, 0.17) },
        // The estimates first, the setpoint over them: its line stays
        // visible where the markers sit on it.
        series: vec![
            Series {
                label: "μ* ± 2 %".into(),
                points: band(0.02),
                mark: Mark::Dashed,
                color: 2,
            },
            Series {
                label: String::new(),
                points: band(-0.02),
                mark: Mark::Dashed,
                color: 2,
            },
            Series {
                label: format!(
                    "μ estimate ({} drive period{} per update)",
                    o.periods,
                    if o.periods == 1 { "" } else { "s" }
                ),
                points: meas,
                mark: Mark::LineMarkers(crate::plot::Marker::Ring),
                color: 0,
            },
            Series {
                label: "μ* setpoint".into(),
                points: setp,
                mark: Mark::Line,
                color: 1,
            },
        ],
    };
    let p2 = Panel {
        title: "Commanded normal amplitude (the loop's output)".into(),
        x_label: "device time, ms".into(),
        y_label: "Δu_z, µm".into(),
        x,
        y: (0.0, 5.5),
        series: vec![
            Series {
                label: "commanded Δu_z".into(),
                points: cmd,
                mark: Mark::LineMarkers(crate::plot::Marker::Circle),
                color: 0,
            },
            Series {
                label: "model feedforward".into(),
                points: ff,
                mark: Mark::Dashed,
                color: 4,
            },
            Series {
                label: "true normal excursion (plant)".into(),
                points: trace.iter().map(|r| (ms(r.0), r.2 * 1e6)).collect(),
                mark: Mark::Line,
                color: 2,
            },
            Series {
                label: "lift-off limit (1 − 0.05)·u_z0".into(),
                points: lim,
                mark: Mark::Line,
                color: 3,
            },
        ],
    };
    let vmax = trace.iter().map(|r| r.1).fold(0.0, f64::max);
    let p3 = Panel {
        title: "Normal channel's voltage (DAC amplitude)".into(),
        x_label: "device time, ms".into(),
        y_label: "voltage amplitude, V".into(),
        x,
        y: (0.0, (vmax * 1.15).max(1e-3)),
        series: vec![Series {
            label: format!("voltage (headroom {} × steady)", o.headroom),
            points: trace.iter().map(|r| (ms(r.0), r.1)).collect(),
            mark: Mark::Line,
            color: 0,
        }],
    };
    let plant_note = if resonant {
        format!(
            "resonant transducers, slower τ = Q/(π f_r) = {:.2} ms; model: exact identification",
            o.tau_ms
        )
    } else {
        format!("ideal transducers, lag {} periods", o.lag_periods)
    };
    let notes = vec![
        format!(
            "plant μ0 = {:.3} (model {model_mu0}), {plant_note}, μ0 drift {} /s, ADC noise ±{} counts",
            model_mu0 * o.mu0_ratio,
            o.drift_per_s,
            o.noise_counts
        ),
        format!(
            "drive {:.0} Hz, u_z0 = 4 µm, Δu_x = 0.3 µm, φ = 40°, k_z = k_x = 1e7 N/m; loop v0 = {} mm/s, κ = {}",
            o.freq_hz,
            V0 * 1e3,
            o.gain
        ),
        events_note,
    ];
    let fig = Figure {
        panels: vec![
            (
                p1,
                Extras {
                    notes: notes.clone(),
                    notes_at: Corner::UpperLeft,
                    legend_at: Corner::LowerRight,
                    ..Extras::default()
                },
            ),
            (
                p2,
                Extras {
                    legend_at: Corner::UpperRight,
                    ..Extras::default()
                },
            ),
            (
                p3,
                Extras {
                    legend_at: Corner::UpperRight,
                    ..Extras::default()
                },
            ),
        ],
        rows: 3,
        cols: 1,
        size: (1200, 1250),
        legend: Vec::new(),
        caption: vec![
            format!(
                "fricctl device control-bench --fill-lead {}: the setpoint step settles within ±{:.2e} in {} periods ({} ms)",
                o.fill_lead,
                o.events[1].band,
                opt(o.events[1].settle_periods, 0),
                opt(o.events[1].settle_ms, 3),
            ),
            format!(
                "(band: 2 % of the step, or 4 × the estimates' scatter over the segment's last half if wider); DAC fills {} half-buffers of {} samples ahead",
                o.fill_lead, o.half_buffer_samples
            ),
        ],
    };
    render_figure(path, &fig)
}

/// Flags of `fricctl device tune`: those of `fricctl tune` without the scene
/// (the device's contact and drive are the scene).
#[derive(Args, Debug, Clone)]
pub struct DeviceTuneArgs {
    /// `fricctl tune` flags: --v0 V (--target-mu X | --target-mu-rel T |
    /// --maximize OBJECTIVE) --adjust duz|dux|phase [--max-duz M] [--max-dux M]
    #[arg(trailing_var_arg = true, allow_hyphen_values = true, num_args = 1..)]
    pub tune: Vec<String>,
}

/// `fricctl tune` parsed from an argument list.
#[derive(clap::Parser, Debug)]
#[command(name = "device tune", no_binary_name = true)]
struct TuneOnly {
    #[command(flatten)]
    tune: crate::cmd::tune::TuneCmd,
}

/// `fricctl device tune …`: `fricctl tune`'s solver on the device's contact
/// and drive (its lift-off margin too), then `SetDrive` with the result.
pub fn tune(c: &mut Client, a: &DeviceTuneArgs, json: bool) -> CliResult {
    let contact = match expect(c.call(Request::GetContact)?)? {
        Response::Contact(k) => k,
        other => return Err(unexpected(other)),
    };
    let (drive, applied) = match expect(c.call(Request::GetDrive)?)? {
        Response::Drive { setting, applied } => (setting, applied),
        other => return Err(unexpected(other)),
    };
    let margin = match expect(c.call(Request::Hello)?)? {
        Response::Info(i) => i.liftoff_margin,
        other => return Err(unexpected(other)),
    };
    let s = |x: f64| x.to_string();
    let mut argv: Vec<String> = vec![
        "--mu0".into(),
        s(render::f32v(contact.mu0)),
        "--kz".into(),
        s(render::f32v(contact.kz)),
        "--kx".into(),
        s(render::f32v(contact.kx)),
        "--uz0".into(),
        s(render::f32v(drive.offset_z_m)),
        "--duz".into(),
        s(render::f32v(drive.amp_z_m)),
        "--dux".into(),
        s(render::f32v(drive.amp_x_m)),
        "--freq".into(),
        s(applied.achieved.freq_hz),
        "--phi-deg".into(),
        s(applied.phase_rad.to_degrees()),
        "--liftoff-margin".into(),
        s(render::f32v(margin)),
        "--json".into(),
    ];
    // `--json` among the tune flags (`device tune … --json`, where a user
    // puts it) is the device command's own output flag, not a tune flag.
    let mut json = json;
    for t in &a.tune {
        if t == "--json" {
            json = true;
        } else {
            argv.push(t.clone());
        }
    }
    let parsed = crate::args::numbers_take_hyphens(<TuneOnly as clap::CommandFactory>::command())
        .try_get_matches_from(&argv)
        .and_then(|m| <TuneOnly as clap::FromArgMatches>::from_arg_matches(&m))
        .map_err(|e| CliError::usage(format!("device tune: {}", crate::args::clap_message(&e))))?;
    let mut buf = Vec::new();
    parsed.tune.run(&mut buf)?;
    let v: serde_json::Value =
        serde_json::from_slice(&buf).map_err(|e| CliError::failure(format!("tune result: {e}")))?;
    let get = |k: &str| {
        v[k].as_f64()
            .ok_or_else(|| CliError::failure(format!("tune result without {k}")))
    };
    let d = DriveSetting {
        freq_hz: drive.freq_hz,
        amp_z_m: get("duz")? as f32,
        amp_x_m: get("dux")? as f32,
        offset_z_m: drive.offset_z_m,
        phase_rad: get("phi_deg")?.to_radians() as f32,
    };
    let r = match expect(c.call(Request::SetDrive(d))?)? {
        Response::Drive { setting, applied } => render::drive(&setting, &applied),
        other => return Err(unexpected(other)),
    };
    let mut w = std::io::stdout().lock();
    let shown = if json {
        let mut o = r.json();
        if let (Some(m), Some(t)) = (o.as_object_mut(), v.as_object()) {
            for k in [
                "adjust",
                "v0",
                "target_mu",
                "mu",
                "mu_over_mu0",
                "residual_over_mu0",
                "error_bound_over_mu0",
                "objective",
                "value",
            ] {
                if let Some(x) = t.get(k) {
                    m.insert(k.to_string(), x.clone());
                }
            }
        }
        writeln!(w, "{o}")
    } else {
        let mu = match (
            v["mu"].as_f64(),
            v["objective"].as_str(),
            v["value"].as_f64(),
        ) {
            (Some(m), ..) => format!(", model mu = {m}"),
            (None, Some(o), Some(x)) => format!(", model {o} = {x} (maximised)"),
            _ => String::new(),
        };
        writeln!(
            w,
            "tuned {} on the device's model{mu}; drive set:",
            v["adjust"].as_str().unwrap_or("?")
        )
        .and_then(|()| r.print(false, &mut w))
    };
    shown.map_err(crate::output::stdout_error)
}
