//! `fricctl device control …` (the board's closed loop: on with a setpoint,
//! `off`, `status`) and `fricctl device control-bench` (the loop on the
//! mismatched virtual plant: step response, steady state, velocity step,
//! drift; numbers and a chart).

use std::io::Write;
use std::path::PathBuf;

use board::device::DriveSetting;
use board::protocol::{ControlSetting, Request, Response};
use clap::Args;

use device_host::control_bench::{self, BenchConfig, BenchOut, BenchRun};

use super::client::Client;
use super::render;
use super::{expect, out, unexpected};
use crate::args::{Count, Real};
use crate::error::{CliError, CliResult};

pub use device_host::control_bench::{DEFAULT_GAIN, DEFAULT_RATE, MAX_HOLD_S};
/// The loop gain's domain: a fraction of the error removed per update.
const GAIN: Real = Real::ANY.at_least(0.01).at_most(1.0);

pub use crate::args::{parse_periods, Periods};

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
    /// κ: fraction of the error removed per update, in [0.01, 1] (default 0.95)
    #[arg(long, value_parser = GAIN)]
    pub gain: Option<f64>,
    /// Drive periods per estimate (one update each), 1 … 10 000, or `auto`
    /// (the default): as many as fit one DAC half-buffer at the drive
    /// frequency (1 at 20 kHz, 4 at 40 kHz), the shortest update interval
    #[arg(long, value_parser = parse_periods)]
    pub periods: Option<Periods>,
    /// Rate limit of the commanded Δu_z, m/s (at most the board's slew;
    /// default 1e-3)
    #[arg(long, value_parser = Real::positive().single_precision())]
    pub rate: Option<f64>,
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
        let gain = self.gain.unwrap_or(DEFAULT_GAIN);
        let rate = self.rate.unwrap_or(DEFAULT_RATE);
        if let Some(action) = self.action.as_deref() {
            // `status` only asks and `off` only switches off: a setting
            // flag would be ignored, so it is refused by name.
            let given = [
                (self.target_mu.is_some(), "--target-mu"),
                (self.v0.is_some(), "--v0"),
                (self.gain.is_some(), "--gain"),
                (self.periods.is_some(), "--periods"),
                (self.rate.is_some(), "--rate"),
                (self.headroom.is_some(), "--headroom"),
            ];
            if let Some((_, flag)) = given.iter().find(|(g, _)| *g) {
                return Err(CliError::usage(format!(
                    "{flag}: `device control {action}` takes no setting (it {})",
                    if action == "status" {
                        "only asks the device"
                    } else {
                        "switches the loop off, the last command staying applied"
                    }
                )));
            }
            return Ok(if action == "status" {
                Request::GetControl
            } else {
                Request::SetControl(ControlSetting {
                    on: false,
                    target_mu: 0.0,
                    v0_m_s: 0.0,
                    gain: gain as f32,
                    periods: 1,
                    rate_m_per_s: rate as f32,
                })
            });
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
            gain: gain as f32,
            // `auto` is resolved on the device's frequency by `run`.
            periods: match self.periods {
                Some(Periods::Fixed(n)) => n,
                _ => 1,
            },
            rate_m_per_s: rate as f32,
        }))
    }
}

/// `fricctl device control …` on a connected device, printed.
pub fn run(c: &mut Client, req: Request, a: &ControlArgs, json: bool) -> CliResult {
    out(json, &apply(c, req, a)?)
}

/// `fricctl device control …` on a connected device (`--headroom` first,
/// keeping the tracking in force; put back if the device refuses the
/// control request, so that a refused command changes nothing): the loop's
/// state as the device answers it. `device view`'s loop controls call this.
pub fn apply(c: &mut Client, req: Request, a: &ControlArgs) -> CliResult<render::Report> {
    let mut req = req;
    if let (Request::SetControl(s), None | Some(Periods::Auto)) = (&mut req, a.periods) {
        if s.on {
            let fs = match expect(c.call(Request::Hello)?)? {
                Response::Info(i) => i.sample_rate_hz,
                other => return Err(unexpected(other)),
            };
            let f = match expect(c.call(Request::GetStatus)?)? {
                Response::Status(st) => f64::from(st.frequency_hz),
                other => return Err(unexpected(other)),
            };
            s.periods = Periods::Auto.at(f, fs);
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
        Ok(Response::Control(s)) => Ok(render::control(&s)),
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
    #[arg(long, default_value_t = 2.0, value_parser = Real(super::sim::NOISE_COUNTS))]
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
    pub transducers: super::plant_args::TransducerArgs,
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

/// `fricctl device control-bench`. A plant whose forces leave the ADC's
/// range latches the device's saturation fault: that ends the bench with
/// the verdict (exit 1) rather than the device's raw refusal.
pub fn bench(a: &BenchArgs, json: bool) -> CliResult {
    crate::output::check_outputs(&[(a.plot.as_deref(), "plot")])?;
    let o = run_bench(a)?;
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
    if !o.passed() {
        return Err(CliError::failure(
            "the loop did not settle within 2 % after every event, or a command exceeded the lift-off limit",
        ));
    }
    Ok(())
}

impl BenchArgs {
    /// The bench the flags ask for.
    pub fn config(&self) -> BenchConfig {
        BenchConfig {
            mu0_ratio: self.mu0_ratio,
            lag_periods: self.lag_periods,
            drift: self.drift,
            noise: self.noise,
            gain: self.gain,
            periods: self.periods,
            fill_lead: self.fill_lead,
            seed: self.seed,
            transducers: self.transducers.spec(),
            headroom: self.headroom.value(),
            track: self.track.into(),
            hold_s: self.hold_s,
        }
    }
}

/// The run, with a progress bar on stderr for runs longer than 5 s of
/// device time, and its chart (`--plot`; the caller applied the overwrite
/// policy).
fn run_bench(a: &BenchArgs) -> CliResult<BenchOut> {
    let cfg = a.config();
    let total_ms = control_bench::device_time_ms(&cfg)?;
    let bar = (total_ms > 5e3).then(|| {
        let b = indicatif::ProgressBar::new(total_ms as u64);
        b.set_style(
            indicatif::ProgressStyle::with_template(
                "{bar:30} {pos}/{len} ms of device time  [{elapsed_precise}, eta {eta}]",
            )
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        b
    });
    let run = control_bench::run(&cfg, &mut |done, _| {
        if let Some(b) = &bar {
            b.set_position(done as u64);
        }
    });
    if let Some(b) = &bar {
        b.finish_and_clear();
    }
    let BenchRun { mut out, trace } = run?;
    if let Some(p) = &a.plot {
        out.plot = Some(p.display().to_string());
        crate::figures::control_bench::chart(p, &trace, &out)?;
    }
    Ok(out)
}

fn opt(x: Option<f64>, prec: usize) -> String {
    x.map_or("never".to_string(), |v| format!("{v:.prec$}"))
}

fn write_text(w: &mut impl Write, o: &BenchOut) -> std::io::Result<()> {
    // The amplitude's lag: a fixed delay for ideal transducers, the modes'
    // own dynamics (τ = Q/(π f_r), answered by the headroom) for resonant ones.
    let lag = if o.transducers == "resonant" {
        format!(
            "resonant transducers (slower tau = Q/(pi f_r) = {:.2} ms, headroom {})",
            o.tau_ms, o.headroom
        )
    } else {
        format!("ideal transducers lagging {} periods", o.lag_periods)
    };
    writeln!(
        w,
        "plant: mu0 = {} x model, {lag}, mu0 drift {} /s, noise ±{} counts",
        o.mu0_ratio, o.drift_per_s, o.noise_counts
    )?;
    writeln!(
        w,
        "loop:  gain {}, {} periods/update, {} samples/half-buffer, fills {} half-buffers ahead",
        o.gain, o.periods, o.half_buffer_samples, o.fill_lead
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

/// `fricctl tune`'s scene flags, which `device tune` fills from the device,
/// and the device command that sets each value (same units).
const DEVICE_FLAGS: [(&str, &str, &str); 8] = [
    ("--uz0", "--offset-z", "drive set"),
    ("--duz", "--amp-z", "drive set"),
    ("--dux", "--amp-x", "drive set"),
    ("--freq", "--freq", "drive set"),
    ("--phi-deg", "--phase-deg", "drive set"),
    ("--mu0", "--mu0", "scene set"),
    ("--kz", "--kz", "scene set"),
    ("--kx", "--kx", "scene set"),
];

/// An error of `fricctl tune` about a value `device tune` took from the
/// device (`--uz0: must be > 0 (got 0)` on a device with no drive set)
/// named as the device's setting and the command that sets it: `device
/// tune` has no `--uz0`.
fn device_flag_names(e: CliError) -> CliError {
    for (tune_flag, device_flag, cmd) in DEVICE_FLAGS {
        if let Some(rest) = e.msg.strip_prefix(tune_flag) {
            if let Some(rest) = rest.strip_prefix(':') {
                return CliError {
                    code: e.code,
                    msg: format!(
                        "the device's {device_flag} (from `device {cmd}`):{rest}; set it with `device {cmd} {device_flag} …` first"
                    ),
                };
            }
        }
    }
    e
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
        .map_err(|e| {
            let e = device_flag_names(CliError::usage(crate::args::clap_message(&e)));
            CliError::usage(format!("device tune: {}", e.msg))
        })?;
    let mut buf = Vec::new();
    parsed.tune.run(&mut buf).map_err(|e| {
        let e = device_flag_names(e);
        CliError {
            code: e.code,
            msg: format!("device tune: {}", e.msg),
        }
    })?;
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
