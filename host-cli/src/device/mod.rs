//! `fricctl device …` (talk to a board, QEMU or the virtual device) and
//! `fricctl sim-device` (serve the virtual device on a pty or TCP).

pub mod client;
pub mod link;
pub mod sim;
pub mod sweep;

use std::io::{Read, Write};
use std::path::PathBuf;
use std::time::{Duration, Instant};

use clap::{Args, Subcommand};
use model_core::device::{Contact, DriveSetting};
use model_core::protocol::{Request, Response, Telemetry, WireError};
use serde::Serialize;
use serialport::SerialPort;

use self::client::Client;
use self::link::{Link, SerialLink, SimLink, TcpLink};
use self::sim::VirtualDevice;
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
    /// Per-attempt timeout, ms (≥ 1)
    #[arg(long, default_value_t = 500, allow_hyphen_values = true, value_parser = crate::args::count::<u64, 1>)]
    pub timeout_ms: u64,
    /// Attempts per request (≥ 1; retries keep the sequence number)
    #[arg(long, default_value_t = 3, allow_hyphen_values = true, value_parser = crate::args::count::<u32, 1>)]
    pub attempts: u32,
    /// Virtual device: stage velocity v0, m/s
    #[arg(long, default_value_t = 0.004, allow_hyphen_values = true)]
    pub sim_v0: f64,
    /// Virtual device: ADC noise, ± counts
    #[arg(long, default_value_t = 1.0, allow_hyphen_values = true)]
    pub sim_noise: f64,
    /// Virtual device: uncalibrated ADC offset, counts
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub sim_offset: f64,
    /// Virtual device: the plant (true contact and transducers)
    #[command(flatten)]
    pub plant: sim::PlantArgs,
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
        #[arg(long, allow_hyphen_values = true)]
        v0: f64,
    },
    /// Measure μ over N drive periods (exit 1 if the estimate is not valid)
    Measure {
        /// Drive periods
        #[arg(long, default_value_t = 1000)]
        periods: u32,
        /// Accept an estimate the device marks as not valid (drive stopped or
        /// ramping, saturated, too few periods, fault)
        #[arg(long)]
        allow_invalid: bool,
    },
    /// Status and latched faults
    Status,
    /// Clear latched faults
    ResetFaults,
    /// End every stream and measurement and stop the drive (after a host
    /// crash); settings and latched faults are kept
    Reset,
    /// Stream estimates (Ctrl-C to stop, or --count)
    Watch {
        /// Periods per estimate
        #[arg(long, default_value_t = 1000)]
        periods: u32,
        /// Stop after this many estimates
        #[arg(long)]
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
    /// Sweep one drive parameter: per point set the drive, settle, measure, predict; one CSV row each
    Sweep(sweep::SweepArgs),
}

/// `drive get|set`.
#[derive(Subcommand, Debug, Clone)]
pub enum DriveCmd {
    /// The accepted drive and what the DDS produces
    Get,
    /// Set the drive (refused as a whole if any value is out of range)
    Set {
        /// Frequency, Hz
        #[arg(long)]
        freq: f64,
        /// Normal amplitude Δu_z, m
        #[arg(long)]
        amp_z: f64,
        /// Tangential amplitude Δu_x, m
        #[arg(long)]
        amp_x: f64,
        /// Normal offset = mean indentation u_z0, m
        #[arg(long)]
        offset_z: f64,
        /// Phase φ, degrees
        #[arg(long, allow_hyphen_values = true, default_value_t = 0.0)]
        phase_deg: f64,
    },
}

/// `scene get|set`.
#[derive(Subcommand, Debug, Clone)]
pub enum SceneCmd {
    /// The contact parameters
    Get,
    /// Set μ0, k_z, k_x (or all three from `fricctl fit --out FILE`)
    Set {
        /// μ0 (> 0)
        #[arg(long, allow_hyphen_values = true, required_unless_present = "from_fit")]
        mu0: Option<f64>,
        /// k_z, N/m (> 0)
        #[arg(long, allow_hyphen_values = true, required_unless_present = "from_fit")]
        kz: Option<f64>,
        /// k_x, N/m (> 0)
        #[arg(long, allow_hyphen_values = true, required_unless_present = "from_fit")]
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

fn wire_error(e: WireError) -> CliError {
    use model_core::device::DriveParam;
    let name = |p: DriveParam| match p {
        DriveParam::Freq => "--freq",
        DriveParam::AmpZ => "--amp-z",
        DriveParam::AmpX => "--amp-x",
        DriveParam::OffsetZ => "--offset-z",
        DriveParam::Phase => "--phase-deg",
        DriveParam::Periods => "--periods",
        DriveParam::Velocity => "--v0",
    };
    match e {
        WireError::OutOfRange { param, min, max } => {
            CliError::usage(format!("{}: refused by the device: allowed range [{min}, {max}]", name(param)))
        }
        WireError::LiftOffRefused { amp_z_m, limit_m } => CliError::usage(format!(
            "--amp-z: refused by the device: {amp_z_m} m would lift the contact off (limit {limit_m} m)"
        )),
        WireError::BadScene => CliError::usage(
            "--offset-z: the device has no valid scene: it needs a contact (scene set) and a drive with a normal offset (drive set)"
                .to_string(),
        ),
        other => CliError::failure(format!("device error: {other}")),
    }
}

fn expect(r: Response) -> CliResult<Response> {
    match r {
        Response::Error(e) => Err(wire_error(e)),
        other => Ok(other),
    }
}

fn out<T: Serialize + std::fmt::Debug>(json: bool, v: &T) -> CliResult {
    if json {
        let s =
            serde_json::to_string_pretty(v).map_err(|e| CliError::failure(format!("JSON: {e}")))?;
        println!("{s}");
    } else {
        println!("{v:#?}");
    }
    Ok(())
}

#[derive(Serialize, Debug)]
struct InfoOut {
    answered_by: String,
    firmware: String,
    protocol: u16,
    board: String,
    sample_rate_hz: f64,
    freq_range_hz: (f64, f64),
    max_amp_x_m: f32,
    max_offset_z_m: f32,
    liftoff_margin: f32,
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
        return out(t.json, &list);
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
    let mut c = open(t)?;
    if !t.json {
        eprintln!("talking to {}", c.describe());
    }
    match cmd {
        DeviceCmd::Info => match expect(c.call(Request::Hello)?)? {
            Response::Info(i) => out(
                t.json,
                &InfoOut {
                    answered_by: c.describe(),
                    firmware: format!("{}.{}.{}", i.firmware[0], i.firmware[1], i.firmware[2]),
                    protocol: i.protocol,
                    board: String::from_utf8_lossy(&i.board)
                        .trim_end_matches('\0')
                        .to_string(),
                    sample_rate_hz: i.sample_rate_hz,
                    freq_range_hz: i.freq_range_hz,
                    max_amp_x_m: i.max_amp_x_m,
                    max_offset_z_m: i.max_offset_z_m,
                    liftoff_margin: i.liftoff_margin,
                },
            ),
            other => Err(unexpected(other)),
        },
        DeviceCmd::Drive { cmd: DriveCmd::Get } => {
            out(t.json, &expect(c.call(Request::GetDrive)?)?)
        }
        DeviceCmd::Drive {
            cmd:
                DriveCmd::Set {
                    freq,
                    amp_z,
                    amp_x,
                    offset_z,
                    phase_deg,
                },
        } => {
            for (v, n) in [
                (*freq, "freq"),
                (*amp_z, "amp-z"),
                (*amp_x, "amp-x"),
                (*offset_z, "offset-z"),
                (*phase_deg, "phase-deg"),
            ] {
                if !v.is_finite() {
                    return Err(CliError::usage(format!("--{n}: must be a finite number")));
                }
            }
            let d = DriveSetting {
                freq_hz: *freq,
                amp_z_m: *amp_z as f32,
                amp_x_m: *amp_x as f32,
                offset_z_m: *offset_z as f32,
                phase_rad: phase_deg.to_radians() as f32,
            };
            out(t.json, &expect(c.call(Request::SetDrive(d))?)?)
        }
        DeviceCmd::Start => out(t.json, &expect(c.call(Request::Start)?)?),
        DeviceCmd::Stop => out(t.json, &expect(c.call(Request::Stop)?)?),
        DeviceCmd::Scene { cmd: SceneCmd::Get } => {
            out(t.json, &expect(c.call(Request::GetContact)?)?)
        }
        DeviceCmd::Scene {
            cmd: SceneCmd::Set { .. },
        } => {
            let (mu0, kz, kx) = scene.unwrap_or_default();
            let contact = Contact {
                mu0: mu0 as f32,
                kz: kz as f32,
                kx: kx as f32,
            };
            out(t.json, &expect(c.call(Request::SetContact(contact))?)?)
        }
        DeviceCmd::Predict { v0 } => {
            if !v0.is_finite() {
                return Err(CliError::usage("--v0: must be a finite number"));
            }
            out(
                t.json,
                &expect(c.call(Request::Predict { v0: *v0 as f32 })?)?,
            )
        }
        DeviceCmd::Measure {
            periods,
            allow_invalid,
        } => {
            expect(c.call(Request::Measure { periods: *periods })?)?;
            // Wait for the window to close (the virtual device advances while we wait).
            let start = Instant::now();
            loop {
                let _ = c.next_telemetry(Duration::from_millis(20))?;
                if let Response::Status(s) = expect(c.call(Request::GetStatus)?)? {
                    if !s.measuring {
                        break;
                    }
                }
                if start.elapsed() > Duration::from_secs(120) {
                    return Err(CliError::failure("measurement did not finish within 120 s"));
                }
            }
            let r = expect(c.call(Request::GetEstimate)?)?;
            let Response::Estimate(e) = r else {
                return Err(unexpected(r));
            };
            check_valid(&e, *allow_invalid)?;
            out(
                t.json,
                &serde_json::json!({ "Estimate": estimate_json(&e) }),
            )
        }
        DeviceCmd::Status => out(t.json, &expect(c.call(Request::GetStatus)?)?),
        DeviceCmd::ResetFaults => out(t.json, &expect(c.call(Request::ResetFaults)?)?),
        DeviceCmd::Reset => out(t.json, &expect(c.call(Request::Reset)?)?),
        DeviceCmd::Watch {
            periods,
            count,
            csv,
            allow_invalid,
        } => watch(t, c, *periods, *count, csv.as_deref(), *allow_invalid),
        DeviceCmd::Ports => unreachable!("handled above"),
        DeviceCmd::Sweep(a) => sweep::run(&mut c, a, t.json),
    }
}

/// The names of the reason bits of an estimate.
fn reason_names(bits: u32) -> Vec<&'static str> {
    model_core::estimator::reasons::NAMES
        .iter()
        .filter(|(b, _)| bits & b != 0)
        .map(|(_, n)| *n)
        .collect()
}

/// An estimate as JSON: its fields, with `reasons` as names and `valid`.
fn estimate_json(e: &model_core::estimator::Estimate) -> serde_json::Value {
    let mut v = serde_json::to_value(e).unwrap_or_default();
    if let Some(o) = v.as_object_mut() {
        o.insert("valid".into(), e.valid().into());
        o.insert("reasons".into(), reason_names(e.reasons).into());
    }
    v
}

/// `Err` (exit 1, one line naming the reasons) for an invalid estimate
/// unless `allow_invalid`.
fn check_valid(e: &model_core::estimator::Estimate, allow_invalid: bool) -> CliResult {
    if e.valid() || allow_invalid {
        return Ok(());
    }
    Err(CliError::failure(format!(
        "invalid estimate (mu = {}): {} (--allow-invalid to accept it)",
        e.mu,
        reason_names(e.reasons).join(", ")
    )))
}

fn unexpected(r: Response) -> CliError {
    CliError::failure(format!("unexpected response: {r:?}"))
}

fn watch(
    t: &Target,
    mut c: Client,
    periods: u32,
    count: Option<u64>,
    csv: Option<&std::path::Path>,
    allow_invalid: bool,
) -> CliResult {
    use std::io::IsTerminal;
    let live = !t.json && std::io::stdout().is_terminal();
    expect(c.call(Request::Stream { on: true, periods })?)?;
    let mut w = match csv {
        Some(p) => Some(
            std::fs::File::create(p)
                .map(std::io::BufWriter::new)
                .map_err(|e| CliError::failure(format!("--csv: {}: {e}", p.display())))?,
        ),
        None => None,
    };
    if let Some(w) = w.as_mut() {
        let _ = writeln!(
            w,
            "seq,mu,fx_mean,fz_mean,samples,periods,saturated,dropped,std_error,valid,reasons"
        );
    }
    let mut last_seq: Option<u32> = None;
    let mut n = 0u64;
    let mut idle = Instant::now();
    while count.is_none_or(|k| n < k) {
        let got = match c.next_telemetry(Duration::from_millis(200)) {
            Ok(g) => g,
            Err(e) => {
                // The link is gone: reconnect (same target) for up to 30 s.
                eprintln!("\n{}; reconnecting", e.msg);
                c = reconnect(t, periods)?;
                last_seq = None;
                idle = Instant::now();
                continue;
            }
        };
        match got {
            Some((seq, Telemetry::Estimate(e))) => {
                idle = Instant::now();
                let dropped = last_seq.map_or(0, |l| seq.wrapping_sub(l).saturating_sub(1));
                last_seq = Some(seq);
                n += 1;
                if t.json {
                    println!(
                        "{}",
                        serde_json::json!({"seq": seq, "estimate": estimate_json(&e), "dropped": dropped})
                    );
                } else {
                    let line = format!(
                        "#{seq:<6} mu {:>10.6} ± {:<9.2e} fx {:>9.4} N  fz {:>9.4} N  {} samples{}{}{}",
                        e.mu,
                        e.std_error,
                        e.fx_mean,
                        e.fz_mean,
                        e.samples,
                        if e.saturated { "  SATURATED" } else { "" },
                        if e.valid() {
                            String::new()
                        } else {
                            format!("  INVALID ({})", reason_names(e.reasons).join(", "))
                        },
                        if dropped > 0 {
                            format!("  ({dropped} dropped)")
                        } else {
                            String::new()
                        }
                    );
                    if live {
                        // One line, updated in place.
                        print!("\r\x1b[2K{line}");
                        let _ = std::io::stdout().flush();
                    } else {
                        println!("{line}");
                    }
                }
                if let Some(w) = w.as_mut() {
                    let _ = writeln!(
                        w,
                        "{seq},{},{},{},{},{},{},{dropped},{},{},{}",
                        e.mu,
                        e.fx_mean,
                        e.fz_mean,
                        e.samples,
                        e.periods,
                        e.saturated,
                        e.std_error,
                        e.valid(),
                        reason_names(e.reasons).join(" ")
                    );
                    let _ = w.flush();
                }
                if let Err(err) = check_valid(&e, allow_invalid) {
                    if live {
                        println!();
                    }
                    let _ = c.call(Request::Stream { on: false, periods });
                    return Err(err);
                }
            }
            Some((_, Telemetry::StreamStopped(end))) => {
                use model_core::protocol::StreamEnd;
                if live {
                    println!();
                }
                return Err(CliError::failure(match end {
                    StreamEnd::Requested => {
                        "the stream was stopped (by another request)".to_string()
                    }
                    StreamEnd::Reset => "the stream was ended by a device reset".to_string(),
                    StreamEnd::Refused(e) => format!("the device ended the stream: {e}"),
                }));
            }
            Some(_) => {}
            None => {
                if idle.elapsed() > Duration::from_secs(10) {
                    return Err(CliError::failure(format!(
                        "no estimate from {} for 10 s",
                        c.describe()
                    )));
                }
            }
        }
    }
    if live {
        println!();
    }
    let _ = c.call(Request::Stream { on: false, periods });
    Ok(())
}

fn reconnect(t: &Target, periods: u32) -> CliResult<Client> {
    let start = Instant::now();
    loop {
        if let Ok(mut c) = open(t) {
            if c.call(Request::Stream { on: true, periods }).is_ok() {
                eprintln!("reconnected to {}", c.describe());
                return Ok(c);
            }
        }
        if start.elapsed() > Duration::from_secs(30) {
            return Err(CliError::failure(
                "the device is gone (no reconnection within 30 s)",
            ));
        }
        std::thread::sleep(Duration::from_secs(1));
    }
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
    #[arg(long, default_value_t = 0.004, allow_hyphen_values = true)]
    pub v0: f64,
    /// ADC noise, ± counts
    #[arg(long, default_value_t = 1.0, allow_hyphen_values = true)]
    pub noise: f64,
    /// Uncalibrated ADC offset, counts
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub offset: f64,
    /// The plant (true contact and transducers)
    #[command(flatten)]
    pub plant: sim::PlantArgs,
    /// Stop after this many seconds (default: run until killed)
    #[arg(long, allow_hyphen_values = true)]
    pub seconds: Option<f64>,
}

/// `fricctl sim-device`: the virtual device in real time on a pty or TCP.
pub fn serve(a: &SimArgs) -> CliResult {
    let plant = a
        .plant
        .options(a.v0, a.noise, a.offset, ["v0", "noise", "offset"])?;
    if let Some(sec) = a.seconds {
        if !(sec.is_finite() && sec >= 0.0) {
            return Err(CliError::usage("--seconds: must be a finite number >= 0"));
        }
    }
    let mut dev = VirtualDevice::new(plant);
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
        master
            .set_timeout(Duration::from_millis(2))
            .map_err(|e| CliError::failure(e.to_string()))?;
        let _keep = slave;
        pump(&mut dev, &mut master, deadline)
    } else if let Some(addr) = &a.tcp {
        let l = std::net::TcpListener::bind(addr)
            .map_err(|e| CliError::failure(format!("--tcp: {addr}: {e}")))?;
        println!(
            "{}",
            l.local_addr().map(|a| a.to_string()).unwrap_or_default()
        );
        let _ = std::io::stdout().flush();
        loop {
            let (mut s, peer) = l
                .accept()
                .map_err(|e| CliError::failure(format!("--tcp: {e}")))?;
            eprintln!("client {peer}");
            s.set_read_timeout(Some(Duration::from_millis(2)))
                .map_err(|e| CliError::failure(e.to_string()))?;
            let _ = pump(&mut dev, &mut s, deadline);
            if deadline.is_some_and(|d| Instant::now() >= d) {
                return Ok(());
            }
        }
    } else {
        Err(CliError::usage("--pty: give --pty or --tcp ADDR"))
    }
}

/// Moves bytes between a stream and the virtual device, advancing the
/// simulation in real time.
fn pump<S: Read + Write>(
    dev: &mut VirtualDevice,
    s: &mut S,
    deadline: Option<Instant>,
) -> CliResult {
    let mut buf = [0u8; 512];
    let mut last = Instant::now();
    let mut debt = 0.0f64;
    loop {
        if deadline.is_some_and(|d| Instant::now() >= d) {
            return Ok(());
        }
        match s.read(&mut buf) {
            Ok(0) => return Ok(()),
            Ok(n) => {
                let reply = dev.receive(&buf[..n]);
                if !reply.is_empty() && s.write_all(&reply).is_err() {
                    return Ok(());
                }
            }
            Err(e)
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::TimedOut | std::io::ErrorKind::WouldBlock
                ) => {}
            Err(_) => return Ok(()),
        }
        let now = Instant::now();
        debt += now.duration_since(last).as_secs_f64() * dev.sample_rate();
        last = now;
        // At most 50 ms of simulation per turn, so requests stay responsive.
        let n = debt.min(dev.sample_rate() / 20.0);
        if n >= sim::HALF as f64 {
            let t = dev.advance(n as usize);
            debt -= (n as usize).div_ceil(sim::HALF) as f64 * sim::HALF as f64;
            if !t.is_empty() && s.write_all(&t).is_err() {
                return Ok(());
            }
        }
        debt = debt.min(dev.sample_rate());
    }
}
