//! `fricctl.Device`: a board, the QEMU firmware or the in-process virtual
//! device, driven from Python through the same library as `fricctl
//! device …` (device-host): the same requests, procedures and JSON keys
//! (each answer a [`Record`] whose attributes are the CLI's `--json` keys).
//!
//! Device I/O runs with the GIL released. A `KeyboardInterrupt` during a
//! call ends it at its next request, and what the call changed on the
//! device (drive, mode, options, running state) is put back before the
//! exception reaches Python, as the CLI does on SIGINT.

use std::time::Duration;

use board::device::{Contact, DisplacementOptions, DriveMode, DriveSetting, Track};
use board::protocol::{ControlSetting, Request, Response, WireError};
use device_host::client::Client;
use device_host::identify::{self, Channels, IdentifyOptions};
use device_host::link::{self, SimLink, Where};
use device_host::periods::Periods;
use device_host::report;
use device_host::sweep::{self, PointOptions, SweepParam};
use device_host::transducers::TransducerSpec;
use device_host::virtual_device::PlantSpec;
use fric_analysis::numbers::{short, Real};
use fric_analysis::Error;
use numpy::PyArray1;
use pyo3::exceptions::{PyKeyboardInterrupt, PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::args::{named, Float, Int};
use crate::errors::guard;
use crate::record::Record;

pyo3::create_exception!(
    fricctl,
    DeviceError,
    PyRuntimeError,
    "A device operation failed (base class of DeviceRefused, DeviceFault and LinkError)."
);
pyo3::create_exception!(
    fricctl,
    DeviceRefused,
    DeviceError,
    "The device refused a request: `kind` (e.g. 'OutOfRange'), `param`, `min`, `max` when it \
     names them; the message names the CLI flag."
);
pyo3::create_exception!(
    fricctl,
    DeviceFault,
    DeviceError,
    "The device latched a fault: `faults`, the bits by name."
);
pyo3::create_exception!(
    fricctl,
    LinkError,
    DeviceError,
    "The link to the device failed: no answer, a closed connection, a port that cannot be opened."
);

/// The Python exception of a device-host error.
fn to_py(e: Error) -> PyErr {
    if e.code == 130 {
        return PyKeyboardInterrupt::new_err(e.msg);
    }
    // Classified by the library's text, raised with the keyword first.
    let (raw, m) = (e.msg.as_str(), keyword_first(&e.msg));
    if raw.contains("refused by the device") || raw.contains("not identified") {
        return DeviceRefused::new_err(m);
    }
    if raw.starts_with("lost ")
        || raw.starts_with("no answer from")
        || raw.starts_with("--port:")
        || raw.starts_with("--tcp:")
    {
        return if e.is_bad_input() {
            PyValueError::new_err(m)
        } else {
            LinkError::new_err(m)
        };
    }
    if raw.contains("fault") && raw.contains("latched") {
        return DeviceFault::new_err(m);
    }
    if e.is_bad_input() {
        PyValueError::new_err(m)
    } else {
        DeviceError::new_err(m)
    }
}

/// A message in Python's words: the keyword of the flag it starts with,
/// then the CLI's text (`--freq: refused …` → `freq: --freq: refused …`);
/// a plant flag is `Device.virtual`'s `plant` key (`--plant-load-q: …` →
/// `plant['load_q']: --plant-load-q: …`).
fn keyword_first(msg: &str) -> String {
    if let Some((flag, _)) = msg
        .strip_prefix("--plant-")
        .and_then(|rest| rest.split_once(':'))
    {
        return format!("plant['{}']: {msg}", flag.replace('-', "_"));
    }
    // identify's `--from`/`--to` are `from_hz`/`to_hz` here.
    for (flag, kw) in [("--from:", "from_hz"), ("--to:", "to_hz")] {
        if msg.starts_with(flag) {
            return format!("{kw}: {msg}");
        }
    }
    named(msg)
}

/// `x` in `domain`, or a ValueError naming `kw` (`mu0: must be > 0 (got -1)`).
fn check_real(domain: Real, x: f64, kw: &str) -> PyResult<f64> {
    domain
        .check(x, &short(x))
        .map_err(|r| PyValueError::new_err(format!("{kw}: {r}")))
}

/// A device's refusal as `DeviceRefused` with its kind and range.
fn refused(py: Python<'_>, w: WireError) -> PyErr {
    let msg = keyword_first(&device_host::answers::wire_error(w).msg);
    let e = DeviceRefused::new_err(msg);
    let v = e.value(py);
    let (kind, param, range) = match w {
        WireError::OutOfRange { param, min, max } => {
            ("OutOfRange", Some(format!("{param:?}")), Some((min, max)))
        }
        WireError::LiftOffRefused { amp_z_m, limit_m } => (
            "LiftOffRefused",
            Some("AmpZ".into()),
            Some((0.0, limit_m.min(amp_z_m).max(limit_m))),
        ),
        other => (wire_kind(&other), None, None),
    };
    let _ = v.setattr("kind", kind);
    let _ = v.setattr("param", param);
    let _ = v.setattr("min", range.map(|r| f64::from(r.0)));
    let _ = v.setattr("max", range.map(|r| f64::from(r.1)));
    e
}

/// The name of a refusal's kind.
fn wire_kind(w: &WireError) -> &'static str {
    match w {
        WireError::OutOfRange { .. } => "OutOfRange",
        WireError::LiftOffRefused { .. } => "LiftOffRefused",
        WireError::BadScene => "BadScene",
        WireError::OutOfReach { .. } => "OutOfReach",
        WireError::NotIdentified => "NotIdentified",
        WireError::NotRunning => "NotRunning",
        WireError::Busy => "Busy",
        _ => "Other",
    }
}

/// Runs `f` on the client with the GIL released, a pending
/// `KeyboardInterrupt` ending it at its next request.
fn with_client<T: Send>(
    py: Python<'_>,
    dev: &mut Device,
    f: impl FnOnce(&mut Client) -> Result<T, Error> + Send,
) -> PyResult<T> {
    let mut lock = dev
        .client
        .lock()
        .map_err(|_| DeviceError::new_err("the device's client was poisoned by a panic"))?;
    let c = lock
        .as_mut()
        .ok_or_else(|| LinkError::new_err("the device is closed"))?;
    c.clear_interrupt();
    let r = py.detach(|| guard(|| f(c)));
    if c.interrupted() {
        // The signal was consumed by the poll: raise it now.
        return Err(PyKeyboardInterrupt::new_err("interrupted"));
    }
    r.map_err(to_py)
}

/// One request whose refusal raises `DeviceRefused` (with its kind).
fn ask(py: Python<'_>, dev: &mut Device, req: Request) -> PyResult<Response> {
    let r = with_client(py, dev, move |c| c.call(req))?;
    match r {
        Response::Error(w) => Err(refused(py, w)),
        other => Ok(other),
    }
}

fn record(py: Python<'_>, kind: &'static str, r: &report::Report) -> PyResult<Record> {
    Record::of(py, kind, &r.json())
}

fn unexpected(r: Response) -> PyErr {
    to_py(device_host::answers::unexpected(r))
}

/// A board, the QEMU firmware or the virtual device (`fricctl device`).
#[pyclass(module = "fricctl")]
pub struct Device {
    /// The client (None once closed); a mutex makes the class shareable
    /// between Python threads, one call at a time.
    client: std::sync::Mutex<Option<Client>>,
    describe: String,
}

impl Device {
    fn of(link: Box<dyn link::Link>, timeout_ms: u64, attempts: u32) -> Device {
        let mut client = Client::new(link, Duration::from_millis(timeout_ms), attempts);
        // A KeyboardInterrupt pending in Python ends the call at its next
        // request (checked with the GIL taken for an instant).
        client.interrupt_when(Box::new(|| {
            Python::attach(|py| py.check_signals().is_err())
        }));
        let describe = client.describe();
        Device {
            client: std::sync::Mutex::new(Some(client)),
            describe,
        }
    }
}

/// The plant options of `Device.virtual` from a dict whose keys are the
/// CLI's plant flags without `--plant-` and with `_` (`resonance_z`, `q_z`,
/// `mu0`, `ideal_transducers`, …).
fn plant_spec(plant: Option<&Bound<'_, PyDict>>) -> PyResult<PlantSpec> {
    let mut p = PlantSpec::default();
    let mut t = TransducerSpec::default();
    let Some(d) = plant else {
        return Ok(p);
    };
    for (k, v) in d.iter() {
        let key: String = k.extract()?;
        let num = || -> PyResult<f64> {
            v.extract::<f64>().map_err(|_| {
                pyo3::exceptions::PyTypeError::new_err(format!(
                    "plant['{key}']: must be a number (got {})",
                    v.get_type()
                        .name()
                        .map(|n| n.to_string())
                        .unwrap_or_default()
                ))
            })
        };
        match key.as_str() {
            "mu0" => p.plant_mu0 = num()?,
            "kz" => p.plant_kz = num()?,
            "kx" => p.plant_kx = num()?,
            "lag_periods" => p.plant_lag_periods = num()?,
            "mu0_drift" => p.plant_mu0_drift = num()?,
            "ideal_transducers" => t.plant_ideal_transducers = v.extract()?,
            "v0_profile" => p.v0_profile = Some(v.extract::<std::path::PathBuf>()?),
            "resonance_z" => t.plant_resonance_z = Some(num()?),
            "q_z" => t.plant_q_z = Some(num()?),
            "resonance_x" => t.plant_resonance_x = Some(num()?),
            "q_x" => t.plant_q_x = Some(num()?),
            "gain_z" => t.plant_gain_z = Some(num()?),
            "gain_x" => t.plant_gain_x = Some(num()?),
            "resonance_drift_z" => t.plant_resonance_drift_z = Some(num()?),
            "resonance_drift_x" => t.plant_resonance_drift_x = Some(num()?),
            "thermal_shift" => t.plant_thermal_shift = Some(num()?),
            "crosstalk" => t.plant_crosstalk = Some(num()?),
            "load_q" => t.plant_load_q = Some(num()?),
            other => {
                return Err(PyValueError::new_err(format!(
                    "plant: unknown option '{other}' (mu0, kz, kx, lag_periods, mu0_drift, \
                     v0_profile, ideal_transducers, resonance_z, q_z, resonance_x, q_x, gain_z, gain_x, \
                     resonance_drift_z, resonance_drift_x, thermal_shift, crosstalk, load_q)"
                )))
            }
        }
    }
    p.transducers = t;
    Ok(p)
}

/// A drive mode's name → the mode's option `track`.
fn track_of(track: &str) -> PyResult<Track> {
    match track {
        "none" => Ok(Track::None),
        "z" => Ok(Track::Z),
        "x" => Ok(Track::X),
        other => Err(PyValueError::new_err(format!(
            "track: must be 'none', 'z' or 'x' (got '{other}')"
        ))),
    }
}

#[pymethods]
impl Device {
    /// The in-process virtual device (`fricctl device --sim` without a
    /// state file): the board's own logic on the simulated plant, whose
    /// device time runs as fast as the host computes it.
    #[staticmethod]
    #[pyo3(name = "virtual", signature = (*, plant=None, v0=Float::Num(0.004), noise=Float::Num(1.0), offset=Float::Num(0.0), seed=Int::Small(0)), text_signature = "(*, plant=None, v0=0.004, noise=1.0, offset=0.0, seed=0)")]
    fn virtual_(
        plant: Option<&Bound<'_, PyDict>>,
        v0: Float,
        noise: Float,
        offset: Float,
        seed: Int,
    ) -> PyResult<Device> {
        let v0 = v0.get("v0")?;
        let noise = noise.get("noise")?;
        let offset = offset.get("offset")?;
        let seed = seed.get("seed", 0, u64::MAX)?;
        let spec = plant_spec(plant)?;
        let opts =
            guard(|| spec.options(v0, noise, offset, ["v0", "noise", "offset"])).map_err(to_py)?;
        let mut l = SimLink::ephemeral(opts);
        if seed != 0 {
            l.set_noise_seed(seed);
        }
        Ok(Device::of(Box::new(l), 2000, 3))
    }

    /// A serial port (`"/dev/ttyACM0"`, a pty of `fricctl sim-device
    /// --pty`) or, with `tcp="HOST:PORT"`, the QEMU firmware or
    /// `sim-device --tcp`.
    #[staticmethod]
    #[pyo3(signature = (port=None, *, tcp=None, timeout_ms=Int::Small(500), attempts=Int::Small(3)), text_signature = "(port=None, *, tcp=None, timeout_ms=500, attempts=3)")]
    fn open(
        port: Option<String>,
        tcp: Option<String>,
        timeout_ms: Int,
        attempts: Int,
    ) -> PyResult<Device> {
        let timeout_ms = timeout_ms.get("timeout_ms", 0, u64::MAX)?;
        let attempts = attempts.u32("attempts", 0)?;
        let w = match (port, tcp) {
            (Some(p), None) => Where::Serial(p),
            (None, Some(a)) => Where::Tcp(a),
            _ => {
                return Err(PyValueError::new_err(
                    "open: give a serial port or tcp='HOST:PORT' (one of them)",
                ))
            }
        };
        if timeout_ms == 0 || attempts == 0 {
            return Err(PyValueError::new_err("timeout_ms, attempts: must be ≥ 1"));
        }
        let opened = guard(|| link::open(w)).map_err(to_py)?;
        Ok(Device::of(opened.link, timeout_ms, attempts))
    }

    fn __enter__(slf: Py<Self>) -> Py<Self> {
        slf
    }

    #[pyo3(signature = (*_args))]
    fn __exit__(&mut self, _args: &Bound<'_, pyo3::types::PyTuple>) {
        self.close();
    }

    /// Closes the link (a virtual device ends).
    fn close(&mut self) {
        if let Ok(mut c) = self.client.lock() {
            *c = None;
        }
    }

    fn __repr__(&self) -> String {
        format!("Device({})", self.describe)
    }

    /// `device info`.
    fn info(&mut self, py: Python<'_>) -> PyResult<Record> {
        match ask(py, self, Request::Hello)? {
            Response::Info(i) => record(py, "Info", &report::info(&self.describe, &i)),
            other => Err(unexpected(other)),
        }
    }

    /// `device drive set` (m, Hz, degrees): voltage mode with
    /// `open_loop=True`, else the displacement mode (identified transducers)
    /// with `track` ('none', 'z', 'x') and `headroom`.
    #[pyo3(signature = (*, freq, amp_z, amp_x, offset_z, phase_deg=Float::Num(0.0), open_loop=false, track="none", headroom=None), text_signature = "($self, *, freq, amp_z, amp_x, offset_z, phase_deg=0.0, open_loop=False, track=\"none\", headroom=None)")]
    #[allow(clippy::too_many_arguments)]
    fn drive(
        &mut self,
        py: Python<'_>,
        freq: Float,
        amp_z: Float,
        amp_x: Float,
        offset_z: Float,
        phase_deg: Float,
        open_loop: bool,
        track: &str,
        headroom: Option<Float>,
    ) -> PyResult<Record> {
        let freq = freq.get("freq")?;
        let amp_z = amp_z.get("amp_z")?;
        let amp_x = amp_x.get("amp_x")?;
        let offset_z = offset_z.get("offset_z")?;
        let phase_deg = phase_deg.get("phase_deg")?;
        let headroom = Float::opt(headroom, "headroom")?;
        let track = track_of(track)?;
        if open_loop && (track != Track::None || headroom.is_some()) {
            return Err(PyValueError::new_err(
                "track, headroom: the displacement mode's, not open_loop's",
            ));
        }
        let d = DriveSetting {
            freq_hz: freq,
            amp_z_m: amp_z as f32,
            amp_x_m: amp_x as f32,
            offset_z_m: offset_z as f32,
            phase_rad: phase_deg.to_radians() as f32,
        };
        let mode = if open_loop {
            DriveMode::OpenLoop
        } else {
            DriveMode::Displacement
        };
        ask(py, self, Request::SetDriveMode(mode))?;
        if !open_loop {
            let headroom =
                headroom.unwrap_or(f64::from(board::device::displacement::DEFAULT_HEADROOM));
            ask(
                py,
                self,
                Request::SetDisplacementOptions(DisplacementOptions {
                    track,
                    headroom: headroom as f32,
                }),
            )?;
        }
        match ask(py, self, Request::SetDrive(d))? {
            Response::Drive { setting, applied } => {
                record(py, "Drive", &report::drive(&setting, &applied))
            }
            other => Err(unexpected(other)),
        }
    }

    /// `device drive get`.
    fn get_drive(&mut self, py: Python<'_>) -> PyResult<Record> {
        match ask(py, self, Request::GetDrive)? {
            Response::Drive { setting, applied } => {
                record(py, "Drive", &report::drive(&setting, &applied))
            }
            other => Err(unexpected(other)),
        }
    }

    /// `device start` (soft start).
    fn start(&mut self, py: Python<'_>) -> PyResult<()> {
        ask(py, self, Request::Start).map(drop)
    }

    /// `device stop` (ramped).
    fn stop(&mut self, py: Python<'_>) -> PyResult<()> {
        ask(py, self, Request::Stop).map(drop)
    }

    /// `device reset`: streams and measurements end, the drive stops.
    fn reset(&mut self, py: Python<'_>) -> PyResult<()> {
        ask(py, self, Request::Reset).map(drop)
    }

    /// `device reset-faults`.
    fn reset_faults(&mut self, py: Python<'_>) -> PyResult<()> {
        ask(py, self, Request::ResetFaults).map(drop)
    }

    /// `device status`.
    fn status(&mut self, py: Python<'_>) -> PyResult<Record> {
        match ask(py, self, Request::GetStatus)? {
            Response::Status(s) => record(py, "Status", &report::status(&s)),
            other => Err(unexpected(other)),
        }
    }

    /// `device scene set` (μ0, N/m, N/m), or the contact with no argument.
    #[pyo3(signature = (*, mu0=None, kz=None, kx=None))]
    fn scene(
        &mut self,
        py: Python<'_>,
        mu0: Option<Float>,
        kz: Option<Float>,
        kx: Option<Float>,
    ) -> PyResult<Record> {
        let mu0 = Float::opt(mu0, "mu0")?;
        let kz = Float::opt(kz, "kz")?;
        let kx = Float::opt(kx, "kx")?;
        let k = match (mu0, kz, kx) {
            (None, None, None) => match ask(py, self, Request::GetContact)? {
                Response::Contact(k) => k,
                other => return Err(unexpected(other)),
            },
            (Some(mu0), Some(kz), Some(kx)) => {
                // μ0 as `device scene set --mu0` takes it (> 0, an f32).
                check_real(Real::positive().single_precision(), mu0, "mu0")?;
                // The device model's stiffness domain, by keyword.
                let (lo, hi) = board::device::STIFFNESS_RANGE_N_PER_M;
                for (name, k) in [("kz", kz), ("kx", kx)] {
                    if !(lo..=hi).contains(&k) {
                        return Err(PyValueError::new_err(format!(
                            "{name}: must be in [{lo}, {hi:e}] N/m, the contact stiffness the device's f32 model takes (got {k})"
                        )));
                    }
                }
                let k = Contact {
                    mu0: mu0 as f32,
                    kz: kz as f32,
                    kx: kx as f32,
                };
                ask(py, self, Request::SetContact(k))?;
                k
            }
            _ => {
                return Err(PyValueError::new_err(
                    "mu0, kz, kx: give all three, or none to read the contact",
                ))
            }
        };
        record(py, "Contact", &report::contact(&k))
    }

    /// `device predict` at `v0` m/s.
    fn predict(&mut self, py: Python<'_>, v0: Float) -> PyResult<Record> {
        let v0 = v0.get("v0")?;
        match ask(py, self, Request::Predict { v0: v0 as f32 })? {
            Response::Prediction { prediction, regime } => record(
                py,
                "Prediction",
                &report::prediction(report::f32v(v0 as f32), &prediction, regime),
            ),
            other => Err(unexpected(other)),
        }
    }

    /// `device measure`: μ over `periods` drive periods (after the ramps
    /// settle unless `wait=False`), with the drive the pickups measured. An
    /// invalid estimate is returned (its `valid` is False), not raised.
    #[pyo3(signature = (periods, *, wait=true))]
    fn measure(&mut self, py: Python<'_>, periods: Int, wait: bool) -> PyResult<Record> {
        let periods = periods.u32("periods", 0)?;
        let flag = std::sync::atomic::AtomicBool::new(false);
        let m = with_client(py, self, |c| {
            device_host::measure::measure(c, periods, wait, &flag, &mut |_| {})
        })?;
        record(
            py,
            "Estimate",
            &report::estimate(&m.estimate).measured(m.measured.as_ref()),
        )
    }

    /// `device identify`: the transducers' modes (f_r, Q, gain with 95 %
    /// intervals), stored on the device unless `store=False`. The drive,
    /// its mode and options are put back afterwards, also on an error or a
    /// KeyboardInterrupt.
    #[pyo3(signature = (*, from_hz=None, to_hz=None, points=Int::Small(21), fine_points=Int::Small(31), settle_ms=None, channel="both", store=true), text_signature = "($self, *, from_hz=None, to_hz=None, points=21, fine_points=31, settle_ms=None, channel=\"both\", store=True)")]
    #[allow(clippy::too_many_arguments)]
    fn identify(
        &mut self,
        py: Python<'_>,
        from_hz: Option<Float>,
        to_hz: Option<Float>,
        points: Int,
        fine_points: Int,
        settle_ms: Option<Float>,
        channel: &str,
        store: bool,
    ) -> PyResult<Record> {
        let from_hz = Float::opt(from_hz, "from_hz")?;
        let to_hz = Float::opt(to_hz, "to_hz")?;
        let settle_ms = Float::opt(settle_ms, "settle_ms")?;
        let points = points.u32("points", 0)?;
        let fine_points = fine_points.u32("fine_points", 0)?;
        let channels = match channel {
            "both" => Channels::Both,
            "z" => Channels::Z,
            "x" => Channels::X,
            other => {
                return Err(PyValueError::new_err(format!(
                    "channel: must be 'both', 'z' or 'x' (got '{other}')"
                )))
            }
        };
        let o = IdentifyOptions {
            from: from_hz,
            to: to_hz,
            points,
            fine_points,
            settle_ms,
            channels,
        };
        let (id, stored) = with_client(py, self, move |c| {
            let id = device_host::state::restoring(c, |c| identify::identify(c, &o))?;
            if let Some(e) = id.refused() {
                return Err(e);
            }
            let stored = store && id.store(c)?;
            Ok((id, stored))
        })?;
        let r = device_host::report::identification(&id.channels, stored, id.elapsed_s);
        record(py, "Identification", &r)
    }

    /// `device sweep`: `param` ('phase_deg', 'amp_z', 'amp_x', 'offset_z',
    /// 'freq') from `start` to `end` over `points`; per point the drive is
    /// set, settled and measured over `periods`, and the device's model
    /// predicts μ at `v0`. The drive is put back afterwards, also on an
    /// error or a KeyboardInterrupt. Returns a dict of numpy arrays (the
    /// columns of the CLI's sweep file) that `fricctl.fit` takes.
    #[pyo3(signature = (param, start, end, *, points, periods, v0, settle_periods=Int::Small(0)), text_signature = "($self, param, start, end, *, points, periods, v0, settle_periods=0)")]
    #[allow(clippy::too_many_arguments)]
    fn sweep<'py>(
        &mut self,
        py: Python<'py>,
        param: &str,
        start: Float,
        end: Float,
        points: Int,
        periods: Int,
        v0: Float,
        settle_periods: Int,
    ) -> PyResult<Bound<'py, PyDict>> {
        let start = start.get("start")?;
        let end = end.get("end")?;
        let v0 = v0.get("v0")?;
        let points = points.get("points", 0, u32::MAX.into())? as usize;
        // The ends are numbers by keyword here; the device refuses a value
        // outside its range by the swept parameter's name.
        check_real(Real::ANY, start, "start")?;
        check_real(Real::ANY, end, "end")?;
        let periods = periods.u32("periods", 0)?;
        let settle_periods = settle_periods.u32("settle_periods", 0)?;
        let p = match param.replace('-', "_").as_str() {
            "phase_deg" => SweepParam::PhaseDeg,
            "amp_z" => SweepParam::AmpZ,
            "amp_x" => SweepParam::AmpX,
            "offset_z" => SweepParam::OffsetZ,
            "freq" => SweepParam::Freq,
            _ => {
                return Err(PyValueError::new_err(format!(
                    "param: must be 'phase_deg', 'amp_z', 'amp_x', 'offset_z' or 'freq' (got '{param}')"
                )))
            }
        };
        if !(1..=sweep::MAX_POINTS).contains(&points) || (points == 1 && start != end) {
            return Err(PyValueError::new_err(format!(
                "points: must be in [1, {}] (1 only with start == end)",
                sweep::MAX_POINTS
            )));
        }
        // The CLI's grid (`device sweep`): evenly spaced, exact end points.
        let values = fric_analysis::grid::linspace(start, end, points);
        let o = PointOptions {
            settle_periods,
            periods,
            v0,
        };
        let rows = with_client(py, self, move |c| {
            device_host::state::restoring(c, |c| sweep::run(c, p, &values, &o))
        })?;
        sweep_dict(py, &rows)
    }

    /// `device control`: the closed μ loop on with a setpoint μ* at `v0`
    /// m/s (κ `gain`, `periods` per update or as many as fit a
    /// half-buffer, rate limit m/s); `on=False` switches it off. Returns
    /// the loop's state.
    #[pyo3(signature = (target_mu=None, v0=None, *, on=true, gain=None, periods=None, rate=None))]
    #[allow(clippy::too_many_arguments)]
    fn control(
        &mut self,
        py: Python<'_>,
        target_mu: Option<Float>,
        v0: Option<Float>,
        on: bool,
        gain: Option<Float>,
        periods: Option<Int>,
        rate: Option<Float>,
    ) -> PyResult<Record> {
        let target_mu = Float::opt(target_mu, "target_mu")?;
        let v0 = Float::opt(v0, "v0")?;
        let gain = Float::opt(gain, "gain")?;
        let rate = Float::opt(rate, "rate")?;
        let periods = periods.map(|n| n.u32("periods", 0)).transpose()?;
        use device_host::control_bench::{DEFAULT_GAIN, DEFAULT_RATE};
        let setting = if on {
            let (Some(t), Some(v)) = (target_mu, v0) else {
                return Err(PyValueError::new_err(
                    "target_mu, v0: both are needed to switch the loop on",
                ));
            };
            let periods = match periods {
                Some(n) => n,
                None => {
                    let (fs, f) = with_client(py, self, |c| {
                        let fs = match device_host::answers::expect(c.call(Request::Hello)?)? {
                            Response::Info(i) => i.sample_rate_hz,
                            other => return Err(device_host::answers::unexpected(other)),
                        };
                        match device_host::answers::expect(c.call(Request::GetStatus)?)? {
                            Response::Status(s) => Ok((fs, f64::from(s.frequency_hz))),
                            other => Err(device_host::answers::unexpected(other)),
                        }
                    })?;
                    Periods::Auto.at(f, fs)
                }
            };
            ControlSetting {
                on: true,
                target_mu: t as f32,
                v0_m_s: v as f32,
                gain: gain.unwrap_or(DEFAULT_GAIN) as f32,
                periods,
                rate_m_per_s: rate.unwrap_or(DEFAULT_RATE) as f32,
            }
        } else {
            if target_mu.is_some() || v0.is_some() || gain.is_some() || periods.is_some() {
                return Err(PyValueError::new_err(
                    "on=False takes no setting (the last command stays applied)",
                ));
            }
            ControlSetting {
                on: false,
                target_mu: 0.0,
                v0_m_s: 0.0,
                gain: DEFAULT_GAIN as f32,
                periods: 1,
                rate_m_per_s: DEFAULT_RATE as f32,
            }
        };
        match ask(py, self, Request::SetControl(setting))? {
            Response::Control(s) => record(py, "Control", &report::control(&s)),
            other => Err(unexpected(other)),
        }
    }

    /// `device watch`: the device's stream of estimates of `periods`
    /// periods each, as an iterator of records (`count` of them, or until
    /// the loop ends). The stream stops when the iterator ends, is closed,
    /// is dropped, or raises (an error, a KeyboardInterrupt).
    #[pyo3(signature = (periods, *, count=None))]
    fn watch(slf: Bound<'_, Self>, periods: Int, count: Option<Int>) -> PyResult<Watch> {
        let periods = periods.u32("periods", 0)?;
        let count = count.map(|n| n.get("count", 0, u64::MAX)).transpose()?;
        if count == Some(0) {
            return Err(PyValueError::new_err("count: must be ≥ 1"));
        }
        if periods == 0 {
            return Err(PyValueError::new_err("periods: must be ≥ 1"));
        }
        Ok(Watch {
            dev: slf.unbind(),
            periods,
            left: count,
            stream: None,
            done: false,
        })
    }
}

/// The iterator of `Device.watch`.
#[pyclass(module = "fricctl")]
pub struct Watch {
    dev: Py<Device>,
    periods: u32,
    left: Option<u64>,
    stream: Option<device_host::measure::Stream>,
    done: bool,
}

impl Watch {
    /// Stops the stream if it runs.
    fn finish(&mut self, py: Python<'_>) -> PyResult<()> {
        self.done = true;
        let Some(s) = self.stream.take() else {
            return Ok(());
        };
        let mut dev = self.dev.bind(py).try_borrow_mut()?;
        with_client(py, &mut dev, move |c| s.stop(c))
    }
}

#[pymethods]
impl Watch {
    fn __iter__(slf: PyRef<'_, Self>) -> PyRef<'_, Self> {
        slf
    }

    fn __next__(&mut self, py: Python<'_>) -> PyResult<Option<Record>> {
        if self.done || self.left == Some(0) {
            self.finish(py)?;
            return Ok(None);
        }
        let periods = self.periods;
        let stream = self.stream.take();
        let r = {
            let mut dev = self.dev.bind(py).try_borrow_mut()?;
            with_client(py, &mut dev, move |c| {
                let s = match stream {
                    Some(s) => s,
                    None => device_host::measure::Stream::start(c, periods)?,
                };
                let e = s.next(c);
                Ok((s, e))
            })
        };
        match r {
            Ok((s, Ok(e))) => {
                self.stream = Some(s);
                if let Some(n) = &mut self.left {
                    *n -= 1;
                }
                record(py, "Estimate", &report::estimate(&e)).map(Some)
            }
            Ok((s, Err(e))) => {
                self.stream = Some(s);
                let _ = self.finish(py);
                Err(to_py(e))
            }
            Err(e) => {
                // Interrupted or failed before an estimate: the stream (if
                // started) was moved into the call; stop it by its periods.
                self.stream = Some(device_host::measure::Stream::for_periods(periods));
                let _ = self.finish(py);
                Err(e)
            }
        }
    }

    /// Stops the stream now.
    fn close(&mut self, py: Python<'_>) -> PyResult<()> {
        self.finish(py)
    }
}

impl Drop for Watch {
    fn drop(&mut self) {
        if self.stream.is_some() {
            Python::attach(|py| {
                let _ = self.finish(py);
            });
        }
    }
}

/// The sweep's rows as a dict of numpy arrays (the sweep file's columns).
fn sweep_dict<'py>(
    py: Python<'py>,
    rows: &[fric_analysis::sweep_file::SweepRow],
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    let col = |f: fn(&fric_analysis::sweep_file::SweepRow) -> f64| -> Vec<f64> {
        rows.iter().map(f).collect()
    };
    d.set_item(
        "param",
        rows.iter().map(|r| r.param.clone()).collect::<Vec<_>>(),
    )?;
    for (k, f) in [
        (
            "value",
            (|r: &fric_analysis::sweep_file::SweepRow| r.value) as fn(&_) -> f64,
        ),
        ("freq_hz", |r| r.freq_hz),
        ("amp_z", |r| r.amp_z),
        ("amp_x", |r| r.amp_x),
        ("offset_z", |r| r.offset_z),
        ("phi_deg", |r| r.phi_deg),
        ("v0", |r| r.v0),
        ("model_mu0", |r| r.model_mu0),
        ("model_kz", |r| r.model_kz),
        ("model_kx", |r| r.model_kx),
        ("measured_mu", |r| r.measured_mu),
        ("std_error", |r| r.std_error),
        ("predicted_mu", |r| r.predicted_mu),
    ] {
        d.set_item(k, PyArray1::from_vec(py, col(f)))?;
    }
    d.set_item(
        "valid",
        PyArray1::from_vec(py, rows.iter().map(|r| r.valid).collect::<Vec<bool>>()),
    )?;
    d.set_item(
        "reasons",
        rows.iter().map(|r| r.reasons.clone()).collect::<Vec<_>>(),
    )?;
    Ok(d)
}

/// The exception classes, for the module.
pub fn add_exceptions(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("DeviceError", py.get_type::<DeviceError>())?;
    m.add("DeviceRefused", py.get_type::<DeviceRefused>())?;
    m.add("DeviceFault", py.get_type::<DeviceFault>())?;
    m.add("LinkError", py.get_type::<LinkError>())?;
    m.add_class::<Watch>()?;
    Ok(())
}
