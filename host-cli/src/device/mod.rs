//! `fricctl device …` (talk to a board, QEMU or the virtual device) and
//! `fricctl sim-device` (serve the virtual device on a pty or TCP).

pub mod control;
pub mod identify;
pub mod plant_args;
pub mod sweep;
pub mod view;
pub mod watch;

pub use device_host::answers::{expect, unexpected};
pub use device_host::{client, link, measure, report as render, serve, virtual_device as sim};

use std::io::Write;
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;
use std::time::{Duration, Instant};

use board::device::{Contact, DriveSetting};
use board::protocol::{Request, Response, WireError};
use clap::{Args, Subcommand};
use serialport::SerialPort;

use self::client::Client;
use self::link::Where;
use self::render::Report;
use self::sim::VirtualDevice;
use crate::args::{Count, Real};
use crate::error::{CliError, CliResult};

/// Where the device is.
#[derive(Args, Debug, Clone)]
pub struct Target {
    /// Serial port of the board (or a pty)
    #[arg(long, value_name = "PATH", conflicts_with_all = ["tcp", "sim"])]
    pub port: Option<String>,
    /// TCP address (QEMU's serial backend, `fricctl sim-device --tcp`)
    #[arg(long, value_name = "HOST:PORT", conflicts_with = "sim")]
    pub tcp: Option<String>,
    /// The virtual device, in process
    #[arg(long)]
    pub sim: bool,
    /// Per-attempt timeout, ms (1 ms to 1 hour)
    #[arg(long, default_value_t = 500, value_parser = Count::<u64>::at_least(1).at_most(3_600_000, "one hour"))]
    pub timeout_ms: u64,
    /// Attempts per request (1 to 100; retries keep the sequence number)
    #[arg(long, default_value_t = 3, value_parser = Count::<u32>::at_least(1).at_most(100, "a device that does not answer 100 times is gone"))]
    pub attempts: u32,
    /// Virtual device: stage velocity v0, m/s
    #[arg(long, default_value_t = 0.004, value_parser = Real(sim::STAGE_VELOCITY))]
    pub sim_v0: f64,
    /// Virtual device: ADC noise, ± counts
    #[arg(long, default_value_t = 1.0, value_parser = Real(sim::NOISE_COUNTS))]
    pub sim_noise: f64,
    /// Virtual device: uncalibrated ADC offset, counts
    #[arg(long, default_value_t = 0.0, value_parser = Real(sim::OFFSET_COUNTS))]
    pub sim_offset: f64,
    /// Virtual device: the plant (true contact and transducers)
    #[command(flatten)]
    pub plant: plant_args::PlantArgs,
    /// JSON output
    #[arg(long, global = true)]
    pub json: bool,
}

/// Device commands.
#[derive(Subcommand, Debug, Clone)]
pub enum DeviceCmd {
    /// Identify the device (firmware, protocol, board, limits)
    Info,
    /// Get or set the drive
    Drive {
        #[command(subcommand)]
        cmd: DriveCmd,
    },
    /// Start the drive (soft start)
    Start,
    /// Stop the drive (ramped)
    Stop,
    /// Get or set the contact parameters the device predicts with
    Scene {
        #[command(subcommand)]
        cmd: SceneCmd,
    },
    /// The model's μ at a sliding velocity for the current drive
    Predict {
        /// Sliding velocity, m/s
        #[arg(long, value_parser = Real::ANY.single_precision())]
        v0: f64,
    },
    /// Measure μ over N drive periods (exit 1 if the estimate is not valid)
    Measure {
        /// Drive periods (1 … 10⁶, as the device's Info advertises)
        #[arg(long, default_value_t = 1000, value_parser = Count::<u32>::at_least(1))]
        periods: u32,
        /// Accept an estimate the device marks as not valid (drive stopped or
        /// ramping, saturated, too few periods, fault)
        #[arg(long)]
        allow_invalid: bool,
        /// Measure at once, without waiting for the ramps to settle (a
        /// measurement during a ramp is marked `not_settled`, not valid)
        #[arg(long)]
        no_wait: bool,
    },
    /// Status and latched faults
    Status,
    /// Clear latched faults
    ResetFaults,
    /// Device settings: allow or refuse drives that lift the contact off
    Config {
        /// Allow Δu_z above the lift-off limit (1 − margin)·u_z0 on purpose:
        /// the contact may lift off (intermittent contact) and `predict` uses
        /// the lift-off model; the DAC range still bounds Δu_z
        #[arg(
            long,
            conflicts_with = "refuse_liftoff",
            required_unless_present = "refuse_liftoff"
        )]
        allow_liftoff: bool,
        /// Refuse such drives again (the power-up state; refused itself
        /// while the accepted drive is above the limit)
        #[arg(long)]
        refuse_liftoff: bool,
    },
    /// End every stream and measurement and stop the drive (after a host
    /// crash); settings and latched faults are kept
    Reset,
    /// Stream estimates (Ctrl-C to stop, or --count)
    Watch {
        /// Periods per estimate (1 … 10⁶)
        #[arg(long, default_value_t = 1000, value_parser = Count::<u32>::at_least(1))]
        periods: u32,
        /// Stop after this many estimates
        #[arg(long, value_parser = Count::<u64>::at_least(1))]
        count: Option<u64>,
        /// Also record to CSV
        #[arg(long, value_name = "FILE")]
        csv: Option<PathBuf>,
        /// Keep going on estimates the device marks as not valid (otherwise
        /// the first one stops the stream and exits 1)
        #[arg(long)]
        allow_invalid: bool,
    },
    /// List candidate serial ports
    Ports,
    /// Identify the transducers: a stepped-sine sweep of each channel, a fit of f_r, Q, gain and lag with 95 % intervals, stored on the device (and --out)
    Identify(identify::IdentifyArgs),
    /// Sweep one drive parameter: per point set the drive, settle, measure, predict; one CSV row each
    Sweep(sweep::SweepArgs),
    /// The closed loop: hold μ at --target-mu at sliding velocity --v0 by adjusting Δu_z; `off`; `status`
    Control(control::ControlArgs),
    /// The closed loop on the mismatched virtual plant (in process): step response, steady state, velocity step; numbers and a chart
    ControlBench(control::BenchArgs),
    /// `fricctl tune` on the device's contact and drive, then set the drive to the result (e.g. `device tune --v0 0.004 --target-mu 0.1 --adjust duz`)
    Tune(control::DeviceTuneArgs),
    /// A live view in a local web page: plots of μ, the measured drive, the
    /// frequency and the lift-off margin; the state; start, stop, setpoints,
    /// tracking and the μ loop through the CLI's own commands
    View(view::ViewArgs),
}

/// `drive get|set`.
#[derive(Subcommand, Debug, Clone)]
pub enum DriveCmd {
    /// The accepted drive and what the DDS produces
    Get,
    /// Set the drive (refused as a whole if any value is out of range)
    Set {
        /// Frequency, Hz
        #[arg(long, value_parser = Real::ANY.single_precision())]
        freq: f64,
        /// Normal amplitude Δu_z, m
        #[arg(long, value_parser = Real::ANY.single_precision())]
        amp_z: f64,
        /// Tangential amplitude Δu_x, m
        #[arg(long, value_parser = Real::ANY.single_precision())]
        amp_x: f64,
        /// Normal offset = mean indentation u_z0, m
        #[arg(long, value_parser = Real::ANY.single_precision())]
        offset_z: f64,
        /// Phase φ, degrees
        #[arg(long, default_value_t = 0.0, value_parser = Real::ANY.single_precision())]
        phase_deg: f64,
        /// Voltage mode: the DAC calibration is taken to be the displacement
        /// (no identification needed; on resonant transducers amplitudes and
        /// φ are then off by the modes' response)
        #[arg(long)]
        open_loop: bool,
        /// Resonance tracking: the drive frequency follows this transducer's
        /// resonance (a PLL on its measured phase); `none` keeps --freq
        #[arg(long, value_enum, default_value_t = TrackArg::None)]
        track: TrackArg,
        #[command(flatten)]
        headroom: HeadroomArg,
    },
}

/// `--track z|x|none`.
#[derive(clap::ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub enum TrackArg {
    /// No tracking.
    None,
    /// The normal transducer.
    Z,
    /// The tangential transducer.
    X,
}

impl From<TrackArg> for board::device::Track {
    fn from(t: TrackArg) -> Self {
        match t {
            TrackArg::None => board::device::Track::None,
            TrackArg::Z => board::device::Track::Z,
            TrackArg::X => board::device::Track::X,
        }
    }
}

/// `--headroom H` of `drive set`, `control` and `control-bench`.
#[derive(clap::Args, Debug, Clone, Copy)]
pub struct HeadroomArg {
    /// Voltage headroom of the displacement loop's transitions: the voltage
    /// may reach H times the identified model's steady-state voltage
    /// (1 = no overdrive; at most 8; default 2; displacement mode only)
    #[arg(long, value_name = "H", value_parser = Real::ANY.at_least(1.0).at_most(8.0).because("1 is no overdrive").single_precision())]
    pub headroom: Option<f64>,
}

impl HeadroomArg {
    /// The headroom given, or the device's default.
    pub fn value(&self) -> f64 {
        self.headroom
            .unwrap_or(f64::from(board::device::displacement::DEFAULT_HEADROOM))
    }
}

/// `scene get|set`.
#[derive(Subcommand, Debug, Clone)]
pub enum SceneCmd {
    /// The contact parameters
    Get,
    /// Set μ0, k_z, k_x (or all three from `fricctl fit --out FILE`)
    Set {
        /// μ0 (> 0)
        #[arg(long, required_unless_present = "from_fit", value_parser = Real::positive().single_precision())]
        mu0: Option<f64>,
        /// k_z, N/m (1 … 1e12: `board::device::STIFFNESS_RANGE_N_PER_M`)
        #[arg(long, required_unless_present = "from_fit", value_parser = sweep::STIFFNESS)]
        kz: Option<f64>,
        /// k_x, N/m (1 … 1e12)
        #[arg(long, required_unless_present = "from_fit", value_parser = sweep::STIFFNESS)]
        kx: Option<f64>,
        /// Take mu0, kz, kx from the JSON written by `fricctl fit --out FILE`
        #[arg(long, value_name = "FILE", conflicts_with_all = ["mu0", "kz", "kx"])]
        from_fit: Option<PathBuf>,
    },
}

pub(crate) fn open(t: &Target) -> CliResult<Client> {
    let plant = t.plant.options(
        t.sim_v0,
        t.sim_noise,
        t.sim_offset,
        ["sim-v0", "sim-noise", "sim-offset"],
    )?;
    let w = if let Some(p) = &t.port {
        Where::Serial(p.clone())
    } else if let Some(a) = &t.tcp {
        Where::Tcp(a.clone())
    } else if t.sim {
        Where::Virtual(plant)
    } else {
        Where::Auto(plant)
    };
    let opened = link::open(w)?;
    if let Some(n) = &opened.note {
        eprintln!("{n}");
    }
    Ok(Client::new(
        opened.link,
        Duration::from_millis(t.timeout_ms),
        t.attempts,
    ))
}

/// Prints a report (text or `--json`) to stdout.
pub(crate) fn out(json: bool, r: &Report) -> CliResult {
    r.print(json, &mut std::io::stdout().lock())
        .map_err(crate::output::stdout_error)
}

/// The report of a `Drive` answer.
fn drive_report(r: Response) -> CliResult<Report> {
    match expect(r)? {
        Response::Drive { setting, applied } => Ok(render::drive(&setting, &applied)),
        other => Err(unexpected(other)),
    }
}

/// The report of an `Ok` answer.
fn done(r: Response, command: &'static str, what: &'static str) -> CliResult<Report> {
    match expect(r)? {
        Response::Ok => Ok(render::done(command, what)),
        other => Err(unexpected(other)),
    }
}

/// `fricctl device …`.
pub fn run(t: &Target, cmd: &DeviceCmd) -> CliResult {
    match cmd {
        DeviceCmd::Ports => return print_ports(t.json, &link::ports()?),
        DeviceCmd::ControlBench(a) => return control::bench(a, t.json),
        _ => {}
    }
    // Checked before connecting: the parameters are named, not the device's refusal.
    let mut checked = Checked::of(cmd)?;
    let mut c = open(t)?;
    // Which device answers: for a person at a terminal (a script reads the
    // exit status and a refusal's one line).
    if !t.json && std::io::IsTerminal::is_terminal(&std::io::stderr()) {
        eprintln!("talking to {}", c.describe());
    }
    // One handler for SIGINT, SIGTERM and SIGHUP: `measure` and `watch`
    // watch the flag; `identify` and `sweep` stop at their next request and
    // put the device back as they found it.
    let flag = watch::interrupt_flag();
    if let (DeviceCmd::View(a), Some(l)) = (cmd, checked.view.take()) {
        // The view owns the link: one connection, its requests in turn.
        return view::run(c, a, l, flag);
    }
    dispatch(&mut c, t, cmd, checked, &flag)
}

/// What a command's flags give before the device is asked.
#[derive(Default)]
struct Checked {
    /// `scene set`: (μ0, k_z, k_x).
    scene: Option<(f64, f64, f64)>,
    /// `control`: the request.
    control: Option<Request>,
    /// `view`: the page's socket, bound before the device is opened.
    view: Option<std::net::TcpListener>,
}

impl Checked {
    fn of(cmd: &DeviceCmd) -> CliResult<Checked> {
        let mut k = Checked::default();
        match cmd {
            DeviceCmd::Scene {
                cmd:
                    SceneCmd::Set {
                        mu0,
                        kz,
                        kx,
                        from_fit,
                    },
            } => k.scene = Some(sweep::scene_values(*mu0, *kz, *kx, from_fit.as_deref())?),
            DeviceCmd::Sweep(a) => a.check()?,
            DeviceCmd::Control(a) => k.control = Some(a.request()?),
            DeviceCmd::View(a) => k.view = Some(a.bind()?),
            _ => {}
        }
        Ok(k)
    }
}

/// Runs `cmd` on the open device.
fn dispatch(
    c: &mut Client,
    t: &Target,
    cmd: &DeviceCmd,
    checked: Checked,
    flag: &Arc<AtomicBool>,
) -> CliResult {
    let json = t.json;
    match cmd {
        DeviceCmd::Info => match expect(c.call(Request::Hello)?)? {
            Response::Info(i) => out(json, &render::info(&c.describe(), &i)),
            other => Err(unexpected(other)),
        },
        DeviceCmd::Drive { cmd: DriveCmd::Get } => {
            out(json, &drive_report(c.call(Request::GetDrive)?)?)
        }
        DeviceCmd::Drive { cmd } => out(json, &drive_set(c, cmd)?),
        DeviceCmd::Start => out(json, &start(c)?),
        DeviceCmd::Stop => out(json, &stop(c)?),
        DeviceCmd::Scene { cmd: SceneCmd::Get } => match expect(c.call(Request::GetContact)?)? {
            Response::Contact(k) => out(json, &render::contact(&k)),
            other => Err(unexpected(other)),
        },
        DeviceCmd::Scene { .. } => scene_set(c, checked.scene.unwrap_or_default(), json),
        DeviceCmd::Predict { v0 } => match expect(c.call(Request::Predict { v0: *v0 as f32 })?)? {
            Response::Prediction { prediction, regime } => out(
                json,
                &render::prediction(render::f32v(*v0 as f32), &prediction, regime),
            ),
            other => Err(unexpected(other)),
        },
        DeviceCmd::Measure {
            periods,
            allow_invalid,
            no_wait,
        } => measure_cmd(c, *periods, !*no_wait, *allow_invalid, json, flag),
        DeviceCmd::Status => match expect(c.call(Request::GetStatus)?)? {
            Response::Status(st) => out(json, &render::status(&st)),
            other => Err(unexpected(other)),
        },
        DeviceCmd::Config { allow_liftoff, .. } => config_cmd(c, *allow_liftoff, json),
        DeviceCmd::ResetFaults => out(json, &reset_faults(c)?),
        DeviceCmd::Reset => out(
            json,
            &done(
                c.call(Request::Reset)?,
                "reset",
                "streams and measurements ended, drive stopping",
            )?,
        ),
        DeviceCmd::Watch {
            periods,
            count,
            csv,
            allow_invalid,
        } => watch::watch(t, c, flag, *periods, *count, csv.as_deref(), *allow_invalid),
        DeviceCmd::Sweep(a) => {
            c.interrupt_on(flag.clone());
            sweep::run(c, a, json)
        }
        DeviceCmd::Identify(a) => {
            c.interrupt_on(flag.clone());
            identify::run(c, a, json)
        }
        DeviceCmd::Control(a) => {
            let req = match checked.control {
                Some(r) => r,
                None => a.request()?,
            };
            control::run(c, req, a, json)
        }
        DeviceCmd::Tune(a) => control::tune(c, a, json),
        DeviceCmd::View(_) => Err(CliError::failure(
            "device view needs the link to itself (answered by `run`)",
        )),
        DeviceCmd::Ports => print_ports(json, &link::ports()?),
        DeviceCmd::ControlBench(a) => control::bench(a, json),
    }
}

/// `start`: the drive on (soft start).
pub(crate) fn start(c: &mut Client) -> CliResult<Report> {
    done(
        c.call(Request::Start)?,
        "start",
        "drive starting (soft start; `status` shows when settled)",
    )
}

/// `stop`: the drive off (ramped).
pub(crate) fn stop(c: &mut Client) -> CliResult<Report> {
    done(c.call(Request::Stop)?, "stop", "drive stopping (ramped)")
}

/// `reset-faults`: the latched faults cleared.
pub(crate) fn reset_faults(c: &mut Client) -> CliResult<Report> {
    done(
        c.call(Request::ResetFaults)?,
        "reset-faults",
        "latched faults cleared",
    )
}

/// `drive set`: the drive mode (voltage with `--open-loop`, else
/// displacement with the tracking and headroom), then the drive; the drive
/// as the device accepted it. `device view`'s setpoints call this.
pub(crate) fn drive_set(c: &mut Client, cmd: &DriveCmd) -> CliResult<Report> {
    let DriveCmd::Set {
        freq,
        amp_z,
        amp_x,
        offset_z,
        phase_deg,
        open_loop,
        track,
        headroom,
    } = cmd
    else {
        unreachable!("drive get is answered by dispatch")
    };
    // Each value is a normal f32 number or 0 (the flags' parsers); the
    // device checks its ranges and names the flag.
    let d = DriveSetting {
        freq_hz: *freq,
        amp_z_m: *amp_z as f32,
        amp_x_m: *amp_x as f32,
        offset_z_m: *offset_z as f32,
        phase_rad: phase_deg.to_radians() as f32,
    };
    if *open_loop && *track != TrackArg::None {
        return Err(CliError::usage(
            "--track: needs the displacement mode (identified transducers), not --open-loop",
        ));
    }
    // The tracked mode needs an amplitude its pickup can phase (the
    // device refuses less at SetDrive; checked here before the mode and
    // the options go to the device, so a refusal changes nothing).
    let least = board::device::tracking::TRACK_MIN_AMP_M;
    let tracked = match track {
        TrackArg::Z => Some(("--amp-z", *amp_z)),
        TrackArg::X => Some(("--amp-x", *amp_x)),
        TrackArg::None => None,
    };
    if let Some((flag, a)) = tracked.filter(|&(_, a)| !*open_loop && a < f64::from(least)) {
        return Err(CliError::usage(format!(
            "{flag}: --track needs at least {} m of the tracked mode (got {}): \
             below it no lock-in window can phase the mode",
            fric_analysis::numbers::short(device_host::answers::f32v(least)),
            fric_analysis::numbers::short(a)
        )));
    }
    if *open_loop && headroom.headroom.is_some() {
        return Err(CliError::usage(
            "--headroom: is the displacement mode's (identified transducers), not --open-loop's",
        ));
    }
    // The mode, the options, then the drive: all or nothing (a refused
    // drive puts the mode and the options back as they were).
    device_host::state::all_or_nothing(c, |c| {
        identify::select_mode(c, *open_loop)?;
        if !*open_loop {
            expect(c.call(Request::SetDisplacementOptions(
                board::device::DisplacementOptions {
                    track: (*track).into(),
                    headroom: headroom.value() as f32,
                },
            ))?)?;
        }
        drive_report(c.call(Request::SetDrive(d))?)
    })
}

/// `scene set`: the contact, then the contact as set.
fn scene_set(c: &mut Client, (mu0, kz, kx): (f64, f64, f64), json: bool) -> CliResult {
    let contact = Contact {
        mu0: mu0 as f32,
        kz: kz as f32,
        kx: kx as f32,
    };
    done(
        c.call(Request::SetContact(contact))?,
        "scene set",
        "contact set",
    )?;
    out(json, &render::contact(&contact))
}

/// `measure`: Ctrl-C (or SIGTERM, SIGHUP) while the device measures aborts
/// the measurement on the device ([`device_host::measure`]). Exit 1: no
/// estimate, or an invalid one without `--allow-invalid` (its numbers are
/// shown all the same).
fn measure_cmd(
    c: &mut Client,
    periods: u32,
    wait: bool,
    allow_invalid: bool,
    json: bool,
    interrupted: &AtomicBool,
) -> CliResult {
    let m = measure::measure(c, periods, wait, interrupted, &mut |n| eprintln!("{n}"))?;
    out(
        json,
        &render::estimate(&m.estimate).measured(m.measured.as_ref()),
    )?;
    check_valid(&m.estimate, allow_invalid)
}

/// `config`: lift-off allowed or refused, then the configuration.
fn config_cmd(c: &mut Client, allow_liftoff: bool, json: bool) -> CliResult {
    match c.call(Request::SetLiftOff {
        allow: allow_liftoff,
    })? {
        Response::Error(WireError::LiftOffRefused { amp_z_m, limit_m }) => {
            return Err(CliError::usage(format!(
                "--refuse-liftoff: refused by the device: the accepted drive's Δu_z = {amp_z_m:e} m \
                 is above the lift-off limit {limit_m:e} m; set a smaller --amp-z first"
            )))
        }
        r => expect(r)?,
    };
    match expect(c.call(Request::GetStatus)?)? {
        Response::Status(st) => out(json, &render::config(&st)),
        other => Err(unexpected(other)),
    }
}

/// `Err` (exit 1, one line naming the reasons) for an invalid estimate
/// unless `allow_invalid`.
pub(crate) fn check_valid(e: &board::estimator::Estimate, allow_invalid: bool) -> CliResult {
    if e.valid() || allow_invalid {
        return Ok(());
    }
    Err(CliError::failure(format!(
        "invalid estimate (mu = {}): {} (--allow-invalid to accept it)",
        render::f32v(e.mu),
        render::reason_names(e.reasons).join(", ")
    )))
}

/// `ports`: an aligned table, or a JSON array of `{port, kind}`.
fn print_ports(json: bool, list: &[(String, String)]) -> CliResult {
    let mut o = std::io::stdout().lock();
    let r = if json {
        let v: Vec<_> = list
            .iter()
            .map(|(p, k)| serde_json::json!({"port": p, "kind": k}))
            .collect();
        writeln!(
            o,
            "{}",
            serde_json::to_string_pretty(&v).unwrap_or_default()
        )
    } else if list.is_empty() {
        writeln!(o, "no serial ports found")
    } else {
        let w = list.iter().map(|(p, _)| p.len()).max().unwrap_or(0);
        list.iter()
            .try_for_each(|(p, k)| writeln!(o, "{p:<w$}  {k}"))
    };
    r.map_err(crate::output::stdout_error)
}

/// Flags of `fricctl sim-device`.
#[derive(Args, Debug, Clone)]
pub struct SimArgs {
    /// Serve on a new pseudo-terminal (prints its path)
    #[arg(long, conflicts_with = "tcp")]
    pub pty: bool,
    /// Serve on a TCP address (one client at a time)
    #[arg(long, value_name = "ADDR")]
    pub tcp: Option<String>,
    /// Stage velocity v0, m/s
    #[arg(long, default_value_t = 0.004, value_parser = Real(sim::STAGE_VELOCITY))]
    pub v0: f64,
    /// ADC noise, ± counts
    #[arg(long, default_value_t = 1.0, value_parser = Real(sim::NOISE_COUNTS))]
    pub noise: f64,
    /// Uncalibrated ADC offset, counts
    #[arg(long, default_value_t = 0.0, value_parser = Real(sim::OFFSET_COUNTS))]
    pub offset: f64,
    /// The plant (true contact and transducers)
    #[command(flatten)]
    pub plant: plant_args::PlantArgs,
    /// Stop after this many seconds (default: run until killed)
    #[arg(long, value_parser = Real::non_negative().at_most(1e9).because("about 30 years; omit it to run until killed"))]
    pub seconds: Option<f64>,
    /// A side channel that provokes faults (loopback addresses only): each
    /// line sent to it, a fault's name (`external`, `dac_underrun`,
    /// `watchdog_reset`, `adc_overrun`, …) or bit, latches that fault
    /// (docs/protocol.md, "Provoking each fault on the virtual device")
    #[arg(long, value_name = "ADDR")]
    pub fault_listen: Option<String>,
}

/// `fricctl sim-device`: the virtual device in real time on a pty or TCP.
pub fn serve(a: &SimArgs) -> CliResult {
    let plant = a
        .plant
        .options(a.v0, a.noise, a.offset, ["v0", "noise", "offset"])?;
    // The address is checked before the device starts: bad input, exit 2.
    if let Some(addr) = &a.tcp {
        link::check_host_port(addr)?;
    }
    let faults = a
        .fault_listen
        .as_deref()
        .map(fault_side_channel)
        .transpose()?;
    let mut dev = VirtualDevice::new(plant);
    // Ctrl-C, SIGTERM or SIGHUP end the server (exit 130), also when the
    // shell that started it ignores SIGINT (a background job): the handler
    // is installed explicitly, not inherited.
    let _ = ctrlc::set_handler(|| {
        eprintln!("interrupted: virtual device stopped");
        std::process::exit(130);
    });
    let deadline = a
        .seconds
        .map(|s| Instant::now() + Duration::from_secs_f64(s.max(0.0)));
    if a.pty {
        let (mut master, slave) =
            serialport::TTYPort::pair().map_err(|e| CliError::failure(format!("--pty: {e}")))?;
        let name = slave.name().unwrap_or_default();
        println!("{name}");
        let _ = std::io::stdout().flush();
        eprintln!("virtual device serving on {name}");
        let _keep = slave;
        serve::serve_pty(&mut dev, &mut master, deadline, faults)
    } else if let Some(addr) = &a.tcp {
        let l = std::net::TcpListener::bind(addr)
            .map_err(|e| CliError::failure(format!("--tcp: {addr}: {e}")))?;
        println!(
            "{}",
            l.local_addr().map(|a| a.to_string()).unwrap_or_default()
        );
        let _ = std::io::stdout().flush();
        serve::serve_tcp(&mut dev, l, deadline, faults)
    } else {
        Err(CliError::usage("--pty: give --pty or --tcp ADDR"))
    }
}

/// `sim-device --fault-listen ADDR`: the side channel, bound before the
/// device starts (a bad or taken address is named); its address on stderr.
fn fault_side_channel(addr: &str) -> CliResult<serve::FaultSource> {
    link::check_host_port(addr)
        .map_err(|e| CliError::usage(e.msg.replace("--tcp", "--fault-listen")))?;
    let l = std::net::TcpListener::bind(addr)
        .map_err(|e| CliError::failure(format!("--fault-listen: {addr}: {e}")))?;
    let local = l
        .local_addr()
        .map_err(|e| CliError::failure(format!("--fault-listen: {addr}: {e}")))?;
    if !local.ip().is_loopback() {
        return Err(CliError::usage(format!(
            "--fault-listen: {addr} is not a loopback address (127.0.0.1, ::1): the side channel has no authentication"
        )));
    }
    eprintln!("fault side channel on {local} (one fault name or bit per line)");
    Ok(serve::fault_listener(l))
}
