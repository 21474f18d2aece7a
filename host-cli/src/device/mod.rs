//! `fricctl device …` (talk to a board, QEMU or the virtual device) and
//! `fricctl sim-device` (serve the virtual device on a pty or TCP).

pub mod control;
pub mod identify;
pub mod plant_args;
pub mod render;
pub mod sweep;
pub mod watch;

pub use device_host::answers::{expect, unexpected};
pub use device_host::{client, link, serve, virtual_device as sim};

use std::io::Write;
use std::path::PathBuf;
use std::time::{Duration, Instant};

use board::device::{Contact, DriveSetting};
use board::protocol::{Request, Response, WireError};
use clap::{Args, Subcommand};
use serialport::SerialPort;

use self::client::Client;
use self::link::{Link, SerialLink, SimLink, TcpLink};
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
    /// (1 = no overdrive; at most 8)
    #[arg(long, value_name = "H", default_value_t = f64::from(board::device::displacement::DEFAULT_HEADROOM), value_parser = Real::ANY.at_least(1.0).at_most(8.0).because("1 is no overdrive").single_precision())]
    pub headroom: f64,
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
        /// k_z, N/m (> 0)
        #[arg(long, required_unless_present = "from_fit", value_parser = Real::positive().single_precision())]
        kz: Option<f64>,
        /// k_x, N/m (> 0)
        #[arg(long, required_unless_present = "from_fit", value_parser = Real::positive().single_precision())]
        kx: Option<f64>,
        /// Take mu0, kz, kx from the JSON written by `fricctl fit --out FILE`
        #[arg(long, value_name = "FILE", conflicts_with_all = ["mu0", "kz", "kx"])]
        from_fit: Option<PathBuf>,
    },
}

fn open(t: &Target) -> CliResult<Client> {
    let plant = t.plant.options(
        t.sim_v0,
        t.sim_noise,
        t.sim_offset,
        ["sim-v0", "sim-noise", "sim-offset"],
    )?;
    let timeout = Duration::from_millis(t.timeout_ms);
    let link: Box<dyn Link> = if let Some(p) = &t.port {
        check_serial_path(p)?;
        Box::new(SerialLink::open(p).map_err(|e| serial_open_error(p, e))?)
    } else if let Some(a) = &t.tcp {
        check_host_port(a)?;
        Box::new(TcpLink::connect(a).map_err(|e| CliError::failure(format!("--tcp: {e}")))?)
    } else if t.sim {
        Box::new(SimLink::new(plant))
    } else {
        let usb = usb_ports();
        match usb.as_slice() {
            [one] => {
                eprintln!("using the only USB serial device, {one}");
                Box::new(
                    SerialLink::open(one).map_err(|e| CliError::failure(format!("{one}: {e}")))?,
                )
            }
            [] => {
                eprintln!("no USB serial device found: using the virtual device");
                Box::new(SimLink::new(plant))
            }
            many => {
                return Err(CliError::usage(format!(
                    "--port: several USB serial devices ({}); choose one",
                    many.join(", ")
                )))
            }
        }
    };
    Ok(Client::new(link, timeout, t.attempts))
}

/// `--port` must name a character device (a tty); a missing path, a regular
/// file or a directory is refused before any I/O.
fn check_serial_path(p: &str) -> CliResult {
    use std::os::unix::fs::FileTypeExt;
    match std::fs::metadata(p) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Err(CliError::usage(format!(
            "--port: {p} does not exist (`fricctl device ports` lists serial devices)"
        ))),
        Ok(m) if !m.file_type().is_char_device() => Err(not_serial(p)),
        _ => Ok(()),
    }
}

fn not_serial(p: &str) -> CliError {
    CliError::usage(format!("--port: {p} is not a serial device"))
}

/// A character device that is not a terminal (e.g. `/dev/null`) fails the
/// serial set-up with ENOTTY: that is bad input, not a failed link.
fn serial_open_error(p: &str, e: std::io::Error) -> CliError {
    const ENOTTY: i32 = 25;
    let text = e.to_string();
    if e.raw_os_error() == Some(ENOTTY)
        || text.contains("Inappropriate ioctl")
        || text.contains("Not a typewriter")
    {
        not_serial(p)
    } else {
        CliError::failure(format!("--port: {e}"))
    }
}

/// `--tcp` must be HOST:PORT with a numeric port.
fn check_host_port(a: &str) -> CliResult {
    let ok = a
        .rsplit_once(':')
        .is_some_and(|(host, port)| !host.is_empty() && port.parse::<u16>().is_ok());
    if ok {
        Ok(())
    } else {
        Err(CliError::usage(format!(
            "--tcp: '{a}' is not HOST:PORT (e.g. 127.0.0.1:7777)"
        )))
    }
}

fn usb_ports() -> Vec<String> {
    serialport::available_ports()
        .unwrap_or_default()
        .into_iter()
        .filter(|p| matches!(p.port_type, serialport::SerialPortType::UsbPort(_)))
        .map(|p| p.port_name)
        .collect()
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
    if let DeviceCmd::Ports = cmd {
        let ports = serialport::available_ports()
            .map_err(|e| CliError::failure(format!("listing ports: {e}")))?;
        let list: Vec<(String, String)> = ports
            .into_iter()
            .map(|p| {
                let kind = match p.port_type {
                    serialport::SerialPortType::UsbPort(u) => {
                        format!("usb {:04x}:{:04x}", u.vid, u.pid)
                    }
                    serialport::SerialPortType::PciPort => "pci".to_string(),
                    serialport::SerialPortType::BluetoothPort => "bluetooth".to_string(),
                    serialport::SerialPortType::Unknown => "unknown".to_string(),
                };
                (p.port_name, kind)
            })
            .collect();
        return print_ports(t.json, &list);
    }
    // Checked before connecting: the parameters are named, not the device's refusal.
    let mut scene = None;
    if let DeviceCmd::Scene {
        cmd:
            SceneCmd::Set {
                mu0,
                kz,
                kx,
                from_fit,
            },
    } = cmd
    {
        scene = Some(sweep::scene_values(*mu0, *kz, *kx, from_fit.as_deref())?);
    }
    if let DeviceCmd::Sweep(a) = cmd {
        a.check()?;
    }
    if let DeviceCmd::ControlBench(a) = cmd {
        return control::bench(a, t.json);
    }
    let control_req = match cmd {
        DeviceCmd::Control(a) => Some(a.request()?),
        _ => None,
    };
    let mut c = open(t)?;
    // Which device answers: for a person at a terminal (a script reads the
    // exit status and a refusal's one line).
    if !t.json && std::io::IsTerminal::is_terminal(&std::io::stderr()) {
        eprintln!("talking to {}", c.describe());
    }
    match cmd {
        DeviceCmd::Info => match expect(c.call(Request::Hello)?)? {
            Response::Info(i) => out(t.json, &render::info(&c.describe(), &i)),
            other => Err(unexpected(other)),
        },
        DeviceCmd::Drive { cmd: DriveCmd::Get } => {
            out(t.json, &drive_report(c.call(Request::GetDrive)?)?)
        }
        DeviceCmd::Drive {
            cmd:
                DriveCmd::Set {
                    freq,
                    amp_z,
                    amp_x,
                    offset_z,
                    phase_deg,
                    open_loop,
                    track,
                    headroom,
                },
        } => {
            // Each value is a normal f32 number or 0 (the flags' parsers);
            // the device checks its ranges and names the flag.
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
            identify::select_mode(&mut c, *open_loop)?;
            if !*open_loop {
                expect(c.call(Request::SetDisplacementOptions(
                    board::device::DisplacementOptions {
                        track: (*track).into(),
                        headroom: headroom.headroom as f32,
                    },
                ))?)?;
            }
            out(t.json, &drive_report(c.call(Request::SetDrive(d))?)?)
        }
        DeviceCmd::Start => out(
            t.json,
            &done(
                c.call(Request::Start)?,
                "start",
                "drive starting (soft start; `status` shows when settled)",
            )?,
        ),
        DeviceCmd::Stop => out(
            t.json,
            &done(c.call(Request::Stop)?, "stop", "drive stopping (ramped)")?,
        ),
        DeviceCmd::Scene { cmd: SceneCmd::Get } => match expect(c.call(Request::GetContact)?)? {
            Response::Contact(k) => out(t.json, &render::contact(&k)),
            other => Err(unexpected(other)),
        },
        DeviceCmd::Scene {
            cmd: SceneCmd::Set { .. },
        } => {
            let (mu0, kz, kx) = scene.unwrap_or_default();
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
            out(t.json, &render::contact(&contact))
        }
        DeviceCmd::Predict { v0 } => match expect(c.call(Request::Predict { v0: *v0 as f32 })?)? {
            Response::Prediction { prediction, regime } => out(
                t.json,
                &render::prediction(render::f32v(*v0 as f32), &prediction, regime),
            ),
            other => Err(unexpected(other)),
        },
        DeviceCmd::Measure {
            periods,
            allow_invalid,
            no_wait,
        } => {
            // Ctrl-C (or SIGTERM, SIGHUP) while the device measures aborts the
            // measurement on the device with `Reset` (the protocol's one request
            // that ends a measurement): any stream ends too and the drive ramps
            // down, settings kept (`start` resumes). Exit 1: no estimate.
            let interrupted = watch::interrupt_flag();
            // The window lasts periods/f of device time: wait 4 times that
            // plus 10 s (ramps, the window opening at a wrap, a virtual device
            // that falls behind real time on a loaded machine), then give up.
            let f = match expect(c.call(Request::GetDrive)?)? {
                Response::Drive { applied, .. } => applied.achieved.freq_hz,
                other => return Err(unexpected(other)),
            };
            let window_s = f64::from(*periods) / f.max(1.0);
            let limit = Duration::from_secs_f64(4.0 * window_s + 10.0);
            if !*no_wait {
                wait_settled(&mut c, &interrupted)?;
            }
            expect(c.call(Request::Measure { periods: *periods })?)?;
            // Wait for the window to close (the virtual device advances while we wait).
            let start = Instant::now();
            // Ends the measurement on the device (`Reset`) before reporting `why`.
            let abort = |c: &mut Client, why: String| {
                match c.call(Request::Reset).map(expect) {
                Ok(Ok(_)) => CliError::failure(format!(
                    "{why}; measurement aborted (device reset: drive stopping, settings kept)"
                )),
                Ok(Err(e)) | Err(e) => CliError::failure(format!(
                    "{why}, but the measurement could not be aborted ({}); `fricctl device reset` ends it",
                    e.msg
                )),
            }
            };
            loop {
                if interrupted.load(std::sync::atomic::Ordering::SeqCst) {
                    return Err(abort(&mut c, "interrupted".to_string()));
                }
                let _ = c.next_telemetry(Duration::from_millis(20))?;
                if let Response::Status(s) = expect(c.call(Request::GetStatus)?)? {
                    if !s.measuring {
                        break;
                    }
                }
                if start.elapsed() > limit {
                    return Err(abort(
                        &mut c,
                        format!(
                            "no estimate within {:.0} s, though {periods} periods at {f:.3} Hz take \
                             {window_s:.3} s (is the device sampling its ADC?)",
                            limit.as_secs_f64()
                        ),
                    ));
                }
            }
            let r = expect(c.call(Request::GetEstimate)?)?;
            let Response::Estimate(e) = r else {
                return Err(unexpected(r));
            };
            // The drive that ran: the pickups' measured motion (the last
            // window, or in displacement mode its 1 ms average) at the end.
            let measured = match expect(c.call(Request::GetStatus)?)? {
                Response::Status(st) => st.measured,
                other => return Err(unexpected(other)),
            };
            // The numbers are shown even when invalid; the exit code says so.
            out(t.json, &render::estimate(&e).measured(measured.as_ref()))?;
            check_valid(&e, *allow_invalid)
        }
        DeviceCmd::Status => match expect(c.call(Request::GetStatus)?)? {
            Response::Status(st) => out(t.json, &render::status(&st)),
            other => Err(unexpected(other)),
        },
        DeviceCmd::Config { allow_liftoff, .. } => {
            match c.call(Request::SetLiftOff {
                allow: *allow_liftoff,
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
                Response::Status(st) => out(t.json, &render::config(&st)),
                other => Err(unexpected(other)),
            }
        }
        DeviceCmd::ResetFaults => out(
            t.json,
            &done(
                c.call(Request::ResetFaults)?,
                "reset-faults",
                "latched faults cleared",
            )?,
        ),
        DeviceCmd::Reset => out(
            t.json,
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
        } => watch::watch(t, c, *periods, *count, csv.as_deref(), *allow_invalid),
        DeviceCmd::Ports => unreachable!("handled above"),
        DeviceCmd::Sweep(a) => sweep::run(&mut c, a, t.json),
        DeviceCmd::Identify(a) => identify::run(&mut c, a, t.json),
        DeviceCmd::Control(a) => match control_req {
            Some(req) => control::run(&mut c, req, a, t.json),
            None => unreachable!("checked above"),
        },
        DeviceCmd::ControlBench(_) => unreachable!("handled above"),
        DeviceCmd::Tune(a) => control::tune(&mut c, a, t.json),
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
}

/// `fricctl sim-device`: the virtual device in real time on a pty or TCP.
pub fn serve(a: &SimArgs) -> CliResult {
    let plant = a
        .plant
        .options(a.v0, a.noise, a.offset, ["v0", "noise", "offset"])?;
    // The address is checked before the device starts: bad input, exit 2.
    if let Some(addr) = &a.tcp {
        check_host_port(addr)?;
    }
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
        serve::serve_pty(&mut dev, &mut master, deadline)
    } else if let Some(addr) = &a.tcp {
        let l = std::net::TcpListener::bind(addr)
            .map_err(|e| CliError::failure(format!("--tcp: {addr}: {e}")))?;
        println!(
            "{}",
            l.local_addr().map(|a| a.to_string()).unwrap_or_default()
        );
        let _ = std::io::stdout().flush();
        serve::serve_tcp(&mut dev, l, deadline)
    } else {
        Err(CliError::usage("--pty: give --pty or --tcp ADDR"))
    }
}

/// The longest wait of `measure` for the ramps to settle (a full-scale ramp
/// at the slowest slew rate the device accepts takes well under this).
const SETTLE_LIMIT: Duration = Duration::from_secs(60);

/// Waits until the device's ramps have settled (`Status::settled`), so that
/// `measure` right after `start` or `drive set` measures the drive it was
/// given; stderr says that it waits. Ctrl-C ends the wait (nothing to undo).
fn wait_settled(c: &mut Client, interrupted: &std::sync::atomic::AtomicBool) -> CliResult {
    let start = Instant::now();
    let mut said = false;
    loop {
        if let Response::Status(s) = expect(c.call(Request::GetStatus)?)? {
            if s.settled {
                if said {
                    eprintln!("ramps settled after {:.1} s", start.elapsed().as_secs_f64());
                }
                return Ok(());
            }
        }
        // Said only for a wait a person notices (the ramps of a small
        // change take milliseconds).
        if !said && start.elapsed() > Duration::from_millis(500) {
            eprintln!("waiting for the ramps to settle (--no-wait measures at once)");
            said = true;
        }
        if interrupted.load(std::sync::atomic::Ordering::SeqCst) {
            return Err(CliError::failure("interrupted while waiting for the ramps"));
        }
        if start.elapsed() > SETTLE_LIMIT {
            return Err(CliError::failure(format!(
                "the ramps did not settle within {} s (`fricctl device status` shows the drive)",
                SETTLE_LIMIT.as_secs()
            )));
        }
        let _ = c.next_telemetry(Duration::from_millis(20))?;
    }
}
