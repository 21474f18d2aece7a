//! Byte links to a device: a serial port (real board or a pty), TCP (QEMU,
//! `fricctl sim-device --tcp`), or the in-process virtual device.

use std::io::{self, Read, Write};
use std::net::TcpStream;
use std::time::{Duration, Instant};

use std::path::PathBuf;

use crate::virtual_device::{PlantOptions, SimState, VirtualDevice};
use crate::{Error, Result};

/// A bidirectional byte stream with read timeouts (`Send`: a client may run
/// on another thread, e.g. with Python's GIL released).
pub trait Link: Send {
    /// Writes all bytes.
    fn send(&mut self, bytes: &[u8]) -> io::Result<()>;
    /// Reads what is available within `timeout` (0 bytes on timeout).
    fn recv(&mut self, buf: &mut [u8], timeout: Duration) -> io::Result<usize>;
    /// What answered (for messages).
    fn describe(&self) -> String;
    /// The clock the client's timeouts run on: the host's, except for a
    /// link whose device keeps its own simulated time and runs it while
    /// the client waits (a test's bench), where a wait of `d` is `d` of the
    /// device's time whatever the host's speed.
    fn now(&self) -> Instant {
        Instant::now()
    }
}

/// A serial port (board or pty).
pub struct SerialLink {
    port: Box<dyn serialport::SerialPort>,
    name: String,
}

impl SerialLink {
    /// Opens `path` at 115 200 Bd.
    pub fn open(path: &str) -> io::Result<Self> {
        let port = serialport::new(path, 115_200)
            .timeout(Duration::from_millis(50))
            .open()
            .map_err(|e| io::Error::other(format!("{path}: {e}")))?;
        Ok(SerialLink {
            port,
            name: path.to_string(),
        })
    }
}

impl Link for SerialLink {
    fn send(&mut self, bytes: &[u8]) -> io::Result<()> {
        self.port.write_all(bytes)?;
        self.port.flush()
    }
    fn recv(&mut self, buf: &mut [u8], timeout: Duration) -> io::Result<usize> {
        self.port
            .set_timeout(timeout.max(Duration::from_millis(1)))
            .map_err(io::Error::other)?;
        empty_on_timeout(self.port.read(buf))
    }
    fn describe(&self) -> String {
        format!("serial port {}", self.name)
    }
}

/// A read that timed out, would block or was interrupted by a signal (Ctrl-C
/// during `watch`, whose handler then stops the stream) is "no bytes yet",
/// not a lost link.
fn empty_on_timeout(r: io::Result<usize>) -> io::Result<usize> {
    match r {
        Err(e)
            if matches!(
                e.kind(),
                io::ErrorKind::TimedOut | io::ErrorKind::WouldBlock | io::ErrorKind::Interrupted
            ) =>
        {
            Ok(0)
        }
        r => r,
    }
}

/// TCP (QEMU's serial backend, or `fricctl sim-device --tcp`).
pub struct TcpLink {
    s: TcpStream,
    addr: String,
}

impl TcpLink {
    /// Connects to `addr`.
    pub fn connect(addr: &str) -> io::Result<Self> {
        let s = TcpStream::connect(addr)
            .map_err(|e| io::Error::new(e.kind(), format!("{addr}: {e}")))?;
        s.set_nodelay(true)?;
        Ok(TcpLink {
            s,
            addr: addr.to_string(),
        })
    }
}

impl Link for TcpLink {
    fn send(&mut self, bytes: &[u8]) -> io::Result<()> {
        self.s.write_all(bytes)
    }
    fn recv(&mut self, buf: &mut [u8], timeout: Duration) -> io::Result<usize> {
        self.s
            .set_read_timeout(Some(timeout.max(Duration::from_millis(1))))?;
        match self.s.read(buf) {
            Ok(0) => Err(io::Error::new(
                io::ErrorKind::ConnectionAborted,
                "the device closed the connection",
            )),
            r => empty_on_timeout(r),
        }
    }
    fn describe(&self) -> String {
        format!("tcp {}", self.addr)
    }
}

/// The virtual device in this process; simulated time advances while the
/// client waits (at the device's sample rate, as fast as the CPU allows).
/// Its drive, contact and run state persist between invocations in a small
/// JSON file (`$FRICCTL_SIM_STATE`, default `fricctl-sim-state.json` in the
/// temporary directory), so `drive set`, `start`, `measure` work as on a board.
pub struct SimLink {
    dev: VirtualDevice,
    pending: Vec<u8>,
    /// Where the state is kept between invocations (None: nowhere).
    state_file: Option<PathBuf>,
}

impl SimLink {
    /// The virtual device, restored from the state file if there is one.
    pub fn new(opts: PlantOptions) -> Self {
        let state_file = std::env::var_os("FRICCTL_SIM_STATE")
            .map(PathBuf::from)
            .unwrap_or_else(|| std::env::temp_dir().join("fricctl-sim-state.json"));
        let mut dev = VirtualDevice::new(opts);
        if let Ok(text) = std::fs::read_to_string(&state_file) {
            if let Ok(st) = serde_json::from_str::<SimState>(&text) {
                dev.restore(&st);
            }
        }
        SimLink {
            dev,
            pending: Vec::new(),
            state_file: Some(state_file),
        }
    }

    /// Reseeds the plant's ADC noise (0 keeps the default record).
    pub fn set_noise_seed(&mut self, seed: u64) {
        self.dev.set_noise_seed(seed);
    }

    /// A fresh virtual device at power-up that keeps no state file (a
    /// notebook's or a test's: it lives as long as its client).
    pub fn ephemeral(opts: PlantOptions) -> Self {
        SimLink {
            dev: VirtualDevice::new(opts),
            pending: Vec::new(),
            state_file: None,
        }
    }
}

impl Drop for SimLink {
    fn drop(&mut self) {
        if let Some(f) = &self.state_file {
            if let Ok(text) = serde_json::to_string(&self.dev.snapshot()) {
                let _ = std::fs::write(f, text);
            }
        }
    }
}

impl Link for SimLink {
    fn send(&mut self, bytes: &[u8]) -> io::Result<()> {
        let out = self.dev.receive(bytes);
        self.pending.extend(out);
        Ok(())
    }
    fn recv(&mut self, buf: &mut [u8], timeout: Duration) -> io::Result<usize> {
        let start = Instant::now();
        while self.pending.is_empty() && start.elapsed() < timeout {
            // 10 ms of simulated time per turn.
            let n = (self.dev.sample_rate() / 100.0) as usize;
            let t = self.dev.advance(n);
            self.pending.extend(t);
            if self.pending.is_empty() {
                return Ok(0);
            }
        }
        let n = self.pending.len().min(buf.len());
        buf[..n].copy_from_slice(&self.pending[..n]);
        self.pending.drain(..n);
        Ok(n)
    }
    fn describe(&self) -> String {
        "the virtual device (in process)".to_string()
    }
}

/// Where a device is (`fricctl device --port | --tcp | --sim`, or none).
#[derive(Debug, Clone, PartialEq)]
pub enum Where {
    /// A serial port (the board, or a pty of `fricctl sim-device --pty`).
    Serial(String),
    /// A TCP address HOST:PORT (QEMU, `fricctl sim-device --tcp`).
    Tcp(String),
    /// The in-process virtual device with this plant.
    Virtual(PlantOptions),
    /// The only USB serial device, or the virtual device with this plant
    /// when there is none; several are refused (`--port`).
    Auto(PlantOptions),
}

/// An opened link, and what a person should be told about the choice.
pub struct Opened {
    /// The link.
    pub link: Box<dyn Link>,
    /// For stderr: which device `Where::Auto` chose.
    pub note: Option<String>,
}

/// Opens the link to `w`; a path or an address is checked before any I/O.
///
/// # Errors
/// One line naming `--port` or `--tcp`: a path that is not a serial device
/// or an address that is not HOST:PORT (exit 2), a link that cannot be
/// opened (exit 1), several USB serial devices for `Auto`.
pub fn open(w: Where) -> Result<Opened> {
    let opened = |link: Box<dyn Link>| Opened { link, note: None };
    match w {
        Where::Serial(p) => {
            check_serial_path(&p)?;
            let l = SerialLink::open(&p).map_err(|e| serial_open_error(&p, e))?;
            Ok(opened(Box::new(l)))
        }
        Where::Tcp(a) => {
            check_host_port(&a)?;
            let l = TcpLink::connect(&a).map_err(|e| Error::failure(format!("--tcp: {e}")))?;
            Ok(opened(Box::new(l)))
        }
        Where::Virtual(plant) => Ok(opened(Box::new(SimLink::new(plant)))),
        Where::Auto(plant) => match usb_ports().as_slice() {
            [one] => Ok(Opened {
                link: Box::new(
                    SerialLink::open(one).map_err(|e| Error::failure(format!("{one}: {e}")))?,
                ),
                note: Some(format!("using the only USB serial device, {one}")),
            }),
            [] => Ok(Opened {
                link: Box::new(SimLink::new(plant)),
                note: Some("no USB serial device found: using the virtual device".to_string()),
            }),
            many => Err(Error::usage(format!(
                "--port: several USB serial devices ({}); choose one",
                many.join(", ")
            ))),
        },
    }
}

/// The serial ports present: (name, kind: `usb VID:PID`, `pci`,
/// `bluetooth` or `unknown`).
///
/// # Errors
/// The system's listing failed.
pub fn ports() -> Result<Vec<(String, String)>> {
    let ports =
        serialport::available_ports().map_err(|e| Error::failure(format!("listing ports: {e}")))?;
    Ok(ports
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
        .collect())
}

/// `--port` must name a character device (a tty); a missing path, a regular
/// file or a directory is refused before any I/O.
pub fn check_serial_path(p: &str) -> Result<()> {
    use std::os::unix::fs::FileTypeExt;
    match std::fs::metadata(p) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Err(Error::usage(format!(
            "--port: {p} does not exist (`fricctl device ports` lists serial devices)"
        ))),
        Ok(m) if !m.file_type().is_char_device() => Err(not_serial(p)),
        _ => Ok(()),
    }
}

fn not_serial(p: &str) -> Error {
    Error::usage(format!("--port: {p} is not a serial device"))
}

/// A character device that is not a terminal (e.g. `/dev/null`) fails the
/// serial set-up with ENOTTY: that is bad input, not a failed link.
pub fn serial_open_error(p: &str, e: std::io::Error) -> Error {
    const ENOTTY: i32 = 25;
    let text = e.to_string();
    if e.raw_os_error() == Some(ENOTTY)
        || text.contains("Inappropriate ioctl")
        || text.contains("Not a typewriter")
    {
        not_serial(p)
    } else {
        Error::failure(format!("--port: {e}"))
    }
}

/// `--tcp` must be HOST:PORT with a numeric port.
pub fn check_host_port(a: &str) -> Result<()> {
    let ok = a
        .rsplit_once(':')
        .is_some_and(|(host, port)| !host.is_empty() && port.parse::<u16>().is_ok());
    if ok {
        Ok(())
    } else {
        Err(Error::usage(format!(
            "--tcp: '{a}' is not HOST:PORT (e.g. 127.0.0.1:7777)"
        )))
    }
}

/// The USB serial devices present.
pub fn usb_ports() -> Vec<String> {
    serialport::available_ports()
        .unwrap_or_default()
        .into_iter()
        .filter(|p| matches!(p.port_type, serialport::SerialPortType::UsbPort(_)))
        .map(|p| p.port_name)
        .collect()
}
