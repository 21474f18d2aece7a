//! `fricctl.Scene`: a checked scene and μ over any array of velocities.

use std::path::PathBuf;

use fric_analysis::eval::{self, Method, MethodArgs, MuOutcome};
use fric_analysis::numbers::{short, Real};
use fric_analysis::scene::{self as lib, ProfileInput, ResolvedScene, SceneInput};
use fric_analysis::Error;
use model_core::analytic::{CriticalVelocity, StaticFriction};
use model_core::mdr::Profile;
use model_core::scene::ContactMode;
use numpy::{PyArrayDyn, PyArrayMethods, PyUntypedArrayMethods};
use std::sync::atomic::{AtomicUsize, Ordering};

use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyBytes, PyComplex, PyFloat, PyInt, PyString};
use rayon::prelude::*;

use crate::args::{named, type_name, Float, Int};
use crate::errors::{guard, is_solver_failure, run, to_py, warn};
use crate::record::Record;

/// A scene: the contact, its drive and its profile, checked as the CLI
/// checks its scene flags. Immutable, so one Scene may be used from many
/// threads at once.
#[pyclass(frozen, module = "fricctl")]
pub struct Scene {
    input: SceneInput,
    rs: ResolvedScene,
}

/// One point of `mu`: μ and its bound (units of μ), or μ two-sided at rest.
enum Point {
    Mu(f64, f64),
    AtRest,
}

impl Scene {
    /// The resolved scene.
    pub fn resolved(&self) -> &ResolvedScene {
        &self.rs
    }

    /// The scene as given (for analyses that resolve it their own way).
    pub fn input(&self) -> &SceneInput {
        &self.input
    }

    /// μ at `v0`, with the CLI's checks of `--v0`.
    fn point(&self, v0: f64, how: &MethodArgs) -> Result<Point, Error> {
        lib::check(Real::ANY, v0, "--v0")?;
        self.rs.velocity(v0, "--v0")?;
        let o: MuOutcome = eval::mu_at(&self.rs.scene, v0, how)?;
        if let Some(e) = o.not_converged() {
            return Err(e);
        }
        match (o.mu, o.error_bound_over_mu0) {
            (Some(m), b) => Ok(Point::Mu(m, b.unwrap_or(f64::NAN) * self.rs.scene.mu0())),
            (None, _) => Ok(Point::AtRest),
        }
    }

    /// μ (and its bound) over a C-contiguous float64 array, in parallel
    /// without the GIL, written straight into the result arrays: nothing
    /// else grows with the input (the one per-point allocation, an error's
    /// message, lives only until its chunk's tally).
    fn mu_array(
        &self,
        py: Python<'_>,
        arr: &Bound<'_, PyArrayDyn<f64>>,
        how: &MethodArgs,
        policy: OnError,
        return_bound: bool,
    ) -> PyResult<Py<PyAny>> {
        let shape: Vec<usize> = arr.shape().to_vec();
        let mu_arr = PyArrayDyn::<f64>::zeros(py, shape.as_slice(), false);
        let bound_arr = return_bound.then(|| PyArrayDyn::<f64>::zeros(py, shape.as_slice(), false));
        let tally = {
            let input = arr.readonly();
            let xs = input.as_slice()?;
            let mut mu_rw = mu_arr.readwrite();
            let mut bound_rw = bound_arr.as_ref().map(|b| b.readwrite());
            let mus = mu_rw.as_slice_mut()?;
            let bounds = match bound_rw.as_mut() {
                Some(b) => Some(b.as_slice_mut()?),
                None => None,
            };
            py.detach(|| guard(|| Ok(self.mu_chunks(xs, mus, bounds, how, policy))))
                .map_err(to_py)?
        };
        if let Some((i, e)) = tally.first_error {
            return Err(to_py(
                e.with_context(&format!("v0[{}]", flat_index(&shape, i))),
            ));
        }
        if tally.at_rest > 0 {
            warn(py, &format!("{AT_REST} ({} point(s))", tally.at_rest))?;
        }
        if let Some((_, msg)) = tally.first_failure {
            warn(
                py,
                &format!(
                    "mu: NaN returned at {} point(s); the first: {}",
                    tally.failed,
                    named(&msg)
                ),
            )?;
        }
        let mu_obj = mu_arr.into_any().unbind();
        match bound_arr {
            Some(b) => Ok((mu_obj, b.into_any().unbind())
                .into_pyobject(py)?
                .into_any()
                .unbind()),
            None => Ok(mu_obj),
        }
    }

    /// μ of `xs` into `mus` (and `bounds`), in chunks on the thread pool:
    /// the tally of points at rest and failures, the first error (by index)
    /// that `policy` does not turn into NaN. Once an error is found, chunks
    /// after it are skipped.
    fn mu_chunks(
        &self,
        xs: &[f64],
        mus: &mut [f64],
        bounds: Option<&mut [f64]>,
        how: &MethodArgs,
        policy: OnError,
    ) -> Tally {
        const CHUNK: usize = 1024;
        let stop = AtomicUsize::new(usize::MAX);
        let n_chunks = xs.len().div_ceil(CHUNK);
        let bound_chunks: Vec<Option<&mut [f64]>> = match bounds {
            Some(b) => b.chunks_mut(CHUNK).map(Some).collect(),
            None => (0..n_chunks).map(|_| None).collect(),
        };
        mus.par_chunks_mut(CHUNK)
            .zip(bound_chunks)
            .enumerate()
            .map(|(c, (mu_c, mut bound_c))| {
                let mut t = Tally::default();
                let base = c * CHUNK;
                if base > stop.load(Ordering::Relaxed) {
                    return t;
                }
                for (j, (&x, m_out)) in xs[base..].iter().zip(mu_c.iter_mut()).enumerate() {
                    let (m, b) = match guard(|| self.point(x, how)) {
                        Ok(Point::Mu(m, b)) => (m, b),
                        Ok(Point::AtRest) => {
                            t.at_rest += 1;
                            (f64::NAN, f64::NAN)
                        }
                        Err(e) if policy == OnError::Nan && nan_allowed(&e) => {
                            t.failed += 1;
                            if t.first_failure.is_none() {
                                t.first_failure = Some((base + j, e.msg));
                            }
                            (f64::NAN, f64::NAN)
                        }
                        Err(e) => {
                            t.first_error = Some((base + j, e));
                            stop.fetch_min(base + j, Ordering::Relaxed);
                            break;
                        }
                    };
                    *m_out = m;
                    if let Some(bc) = bound_c.as_deref_mut() {
                        bc[j] = b;
                    }
                }
                t
            })
            .reduce(Tally::default, Tally::merge)
    }

    fn how(&self, method: &str, tol: Option<f64>, steps: Option<u32>) -> PyResult<MethodArgs> {
        let how = MethodArgs {
            method: Method::from_name(method).map_err(to_py)?,
            steps_per_period: steps,
            tol,
            profile: self.rs.profile,
        };
        how.validate().map_err(to_py)?;
        Ok(how)
    }
}

/// The `errors=` policy of `mu`.
#[derive(Clone, Copy, PartialEq, Eq)]
enum OnError {
    Raise,
    Nan,
}

fn on_error(errors: &str) -> PyResult<OnError> {
    match errors {
        "raise" => Ok(OnError::Raise),
        "nan" => Ok(OnError::Nan),
        other => Err(PyValueError::new_err(format!(
            "errors: invalid value '{other}' (one of: raise, nan)"
        ))),
    }
}

const AT_REST: &str = "mu: at v0 = 0 the friction is two-sided (any value between mu(0-) and mu(0+) holds the body at rest): NaN returned; Scene.mu_limits() gives (mu(0-), mu(0+))";

#[pymethods]
impl Scene {
    #[new]
    #[pyo3(signature = (*, mu0=None, kz=None, kx=None, uz0=None, duz=None, dux=None, freq=None, omega=None, phi_deg=None, phi_rad=None, duz_rel=None, dux_rel=None, ratio=None, profile=None, exponent=None, scene=None, liftoff=true))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        mu0: Option<Float>,
        kz: Option<Float>,
        kx: Option<Float>,
        uz0: Option<Float>,
        duz: Option<Float>,
        dux: Option<Float>,
        freq: Option<Float>,
        omega: Option<Float>,
        phi_deg: Option<Float>,
        phi_rad: Option<Float>,
        duz_rel: Option<Float>,
        dux_rel: Option<Float>,
        ratio: Option<Float>,
        profile: Option<&str>,
        exponent: Option<Float>,
        scene: Option<PathBuf>,
        liftoff: bool,
    ) -> PyResult<Scene> {
        let mu0 = Float::opt(mu0, "mu0")?;
        let kz = Float::opt(kz, "kz")?;
        let kx = Float::opt(kx, "kx")?;
        let uz0 = Float::opt(uz0, "uz0")?;
        let duz = Float::opt(duz, "duz")?;
        let dux = Float::opt(dux, "dux")?;
        let freq = Float::opt(freq, "freq")?;
        let omega = Float::opt(omega, "omega")?;
        let phi_deg = Float::opt(phi_deg, "phi_deg")?;
        let phi_rad = Float::opt(phi_rad, "phi_rad")?;
        let duz_rel = Float::opt(duz_rel, "duz_rel")?;
        let dux_rel = Float::opt(dux_rel, "dux_rel")?;
        let ratio = Float::opt(ratio, "ratio")?;
        let exponent = Float::opt(exponent, "exponent")?;
        let profile = match profile {
            None => None,
            Some(name) => Some(lib::ProfileKind::from_flag(name).map_err(to_py)?),
        };
        let input = SceneInput {
            scene,
            mu0,
            kz,
            kx,
            uz0,
            duz,
            dux,
            freq,
            omega,
            phi_deg,
            phi_rad,
            duz_rel,
            dux_rel,
            ratio,
            contact: ProfileInput { profile, exponent },
        };
        let mode = if liftoff {
            ContactMode::Intermittent
        } else {
            ContactMode::Permanent
        };
        let rs = run(|| input.resolve_with(mode))?;
        Ok(Scene { input, rs })
    }

    /// μ at sliding velocity `v0` (m/s; units of ωW0 for a dimensionless
    /// scene): a float for a number, an ndarray of the same shape for an
    /// array-like of numbers. The result array is the only allocation that
    /// grows with the input (an input that is not already a C-contiguous
    /// float64 array is converted to one first).
    #[pyo3(signature = (v0, method="auto", tol=None, steps_per_period=None, return_bound=false, errors="raise"))]
    #[allow(clippy::too_many_arguments)]
    fn mu(
        &self,
        py: Python<'_>,
        v0: &Bound<'_, PyAny>,
        method: &str,
        tol: Option<Float>,
        steps_per_period: Option<Int>,
        return_bound: bool,
        errors: &str,
    ) -> PyResult<Py<PyAny>> {
        let tol = Float::opt(tol, "tol")?;
        let steps = steps_per_period
            .map(|n| n.u32("steps_per_period", 1))
            .transpose()?;
        let how = self.how(method, tol, steps)?;
        let policy = on_error(errors)?;
        let np = py.import("numpy")?;
        match velocities(&np, v0)? {
            Velocities::Scalar(x) => {
                let (m, b) = match guard(|| self.point(x, &how)) {
                    Ok(Point::Mu(m, b)) => (m, b),
                    Ok(Point::AtRest) => {
                        warn(py, AT_REST)?;
                        (f64::NAN, f64::NAN)
                    }
                    Err(e) if policy == OnError::Nan && nan_allowed(&e) => {
                        warn(py, &format!("mu: NaN returned: {}", named(&e.msg)))?;
                        (f64::NAN, f64::NAN)
                    }
                    Err(e) => return Err(to_py(e)),
                };
                if return_bound {
                    Ok((m, b).into_pyobject(py)?.into_any().unbind())
                } else {
                    Ok(m.into_pyobject(py)?.into_any().unbind())
                }
            }
            Velocities::Array(arr) => self.mu_array(py, &arr, &how, policy, return_bound),
        }
    }

    /// Critical velocities (forward, backward), m/s (eq. 8; eq. L5 of the
    /// lift-off model when the contact lifts off).
    fn critical_velocity(&self) -> PyResult<(f64, f64)> {
        let vc: CriticalVelocity<f64> = run(|| eval::critical_velocity(&self.rs.scene))?;
        Ok((vc.forward, vc.backward))
    }

    /// (μ(0⁻), μ(0⁺)): the limits of μ as v0 → 0 from below and above
    /// (equal when the contact lifts off: the force at rest is unique).
    fn mu_limits(&self) -> PyResult<(f64, f64)> {
        let how = self.how("auto", None, None)?;
        let o = run(|| eval::mu_at(&self.rs.scene, 0.0, &how))?;
        let mu0 = self.rs.scene.mu0();
        match (o.mu, o.mu_0minus_over_mu0, o.mu_0plus_over_mu0) {
            (Some(m), _, _) => Ok((m, m)),
            (None, Some(lo), Some(hi)) => Ok((lo * mu0, hi * mu0)),
            _ => Err(to_py(Error::failure(
                "mu_limits: no limits at rest (internal)",
            ))),
        }
    }

    /// The exact static interval of the equilibrium displacement u_x0, m:
    /// (lo, hi), or None when it is empty or when the contact lifts off
    /// (`fricctl static`'s interval_lo_m, interval_hi_m).
    fn static_interval(&self) -> PyResult<Option<(f64, f64)>> {
        if self.rs.profile != Profile::Flat {
            return Err(to_py(Error::usage(format!(
                "--profile: the interval of u_x0 is the flat punch's (the springs of a {} profile hold different stretches); its static interval is the held force mu/mu0 in [mu(0-), mu(0+)], Scene.mu_limits() (fricctl static --profile)",
                self.rs.profile.name()
            ))));
        }
        let s = &self.rs.scene;
        if s.lifts_off() {
            return Ok(None);
        }
        Ok(StaticFriction::of(s).interval_m(s))
    }

    /// The state of the contact at sliding velocity v0: "rest" (v0 = 0),
    /// "stick_slip" (0 < |v0| < v_c in its direction) or "sliding" (|v0| ≥ v_c,
    /// μ = ±μ0).
    fn regime(&self, v0: Float) -> PyResult<&'static str> {
        let v0 = v0.get("v0")?;
        run(|| lib::check(Real::ANY, v0, "--v0"))?;
        let vc = run(|| eval::critical_velocity(&self.rs.scene))?;
        Ok(if v0 == 0.0 {
            "rest"
        } else if v0.abs() >= vc.for_velocity(v0) {
            "sliding"
        } else {
            "stick_slip"
        })
    }

    /// The regime of the scene as `fricctl classify` gives it: active_control,
    /// dynamic_ratchet or actuator, with the numbers it rests on.
    fn classify(&self, py: Python<'_>) -> PyResult<Record> {
        let c = run(|| eval::classify_scene_profile(&self.rs.scene, &self.rs.profile))?;
        let unit = self.rs.scene.velocity_scale();
        #[derive(serde::Serialize)]
        struct Out {
            regime: &'static str,
            mu_0plus_over_mu0: f64,
            mu_0minus_over_mu0: f64,
            vc_forward: f64,
            vc_backward: f64,
            asymmetry: f64,
        }
        Record::of(
            py,
            "Regime",
            &Out {
                regime: c.regime.name(),
                mu_0plus_over_mu0: c.mu_0plus,
                mu_0minus_over_mu0: c.mu_0minus,
                vc_forward: c.c_forward * unit,
                vc_backward: c.c_backward * unit,
                asymmetry: c.asymmetry,
            },
        )
    }

    /// Whether the contact lifts off once per period (Δu_z ≥ u_z0).
    #[getter]
    fn lifts_off(&self) -> bool {
        self.rs.scene.lifts_off()
    }

    /// Whether the scene was given by its dimensionless groups.
    #[getter]
    fn dimensionless(&self) -> bool {
        self.rs.dimensionless
    }

    /// The contact profile's name: flat, sphere, cone or power.
    #[getter]
    fn profile(&self) -> &'static str {
        self.rs.profile.name()
    }

    /// μ0.
    #[getter]
    fn mu0(&self) -> f64 {
        self.rs.scene.mu0()
    }

    /// W0 = μ0 k_z u_z0/k_x, m.
    #[getter]
    fn w0(&self) -> f64 {
        self.rs.scene.w0()
    }

    /// The velocity unit ωW0, m/s.
    #[getter]
    fn velocity_scale(&self) -> f64 {
        self.rs.scene.velocity_scale()
    }

    fn __repr__(&self) -> String {
        let i = &self.input;
        let mut parts = Vec::new();
        if let Some(p) = &i.scene {
            parts.push(format!("scene={:?}", p.display().to_string()));
        }
        for (name, x) in [
            ("mu0", i.mu0),
            ("kz", i.kz),
            ("kx", i.kx),
            ("uz0", i.uz0),
            ("duz", i.duz),
            ("dux", i.dux),
            ("freq", i.freq),
            ("omega", i.omega),
            ("phi_deg", i.phi_deg),
            ("phi_rad", i.phi_rad),
            ("duz_rel", i.duz_rel),
            ("dux_rel", i.dux_rel),
            ("ratio", i.ratio),
        ] {
            if let Some(x) = x {
                parts.push(format!("{name}={}", short(x)));
            }
        }
        if let Some(k) = i.contact.profile {
            parts.push(format!("profile='{}'", k.name()));
        }
        if let Some(n) = i.contact.exponent {
            parts.push(format!("exponent={}", short(n)));
        }
        format!(
            "Scene({}) # {}{}",
            parts.join(", "),
            if self.rs.scene.lifts_off() {
                "lifts off, "
            } else {
                ""
            },
            match self.rs.profile {
                Profile::Flat => "flat punch".to_string(),
                p => format!("{} profile", p.name()),
            }
        )
    }
}

/// What `mu` was given: one number, or an array of numbers (C-contiguous
/// float64).
enum Velocities<'py> {
    Scalar(f64),
    Array(Bound<'py, PyArrayDyn<f64>>),
}

/// `v0` read as numbers: a Python or numpy real number (not a bool), or
/// anything numpy reads as an array of integers or floats. A string, None,
/// a bool, a complex number, or an array of anything else is a TypeError
/// naming `v0` (numpy would read "0.01" as a number and None as NaN).
fn velocities<'py>(np: &Bound<'py, PyModule>, v0: &Bound<'py, PyAny>) -> PyResult<Velocities<'py>> {
    let wrong = |what: String| {
        PyTypeError::new_err(format!(
            "v0: expected a number or an array of numbers, got {what}"
        ))
    };
    if v0.is_none()
        || v0.is_instance_of::<PyString>()
        || v0.is_instance_of::<PyBytes>()
        || v0.is_instance_of::<PyBool>()
        || v0.is_instance(&np.getattr("bool_")?)?
        || v0.is_instance(&np.getattr("complexfloating")?)?
        || v0.is_instance_of::<PyComplex>()
    {
        return Err(wrong(type_name(v0)));
    }
    let is_array = v0.is_instance(&np.getattr("ndarray")?)?;
    if !is_array
        && (v0.is_instance_of::<PyFloat>()
            || v0.is_instance_of::<PyInt>()
            || v0.is_instance(&np.getattr("number")?)?)
    {
        // A Python int beyond f64 (10**400) is a value error, named.
        return v0
            .extract::<f64>()
            .map(Velocities::Scalar)
            .map_err(|e| PyValueError::new_err(format!("v0: {}", e.value(v0.py()))));
    }
    let arr = np.call_method1("asarray", (v0,)).map_err(|e| {
        wrong(format!(
            "{} that numpy cannot read as an array ({})",
            type_name(v0),
            e.value(v0.py())
        ))
    })?;
    let kind: String = arr.getattr("dtype")?.getattr("kind")?.extract()?;
    if !matches!(kind.as_str(), "i" | "u" | "f") {
        let dtype = arr.getattr("dtype")?.str()?.to_string();
        return Err(wrong(format!("{} of dtype {dtype}", type_name(v0))));
    }
    // asarray, not ascontiguousarray: that one makes a 0-d array 1-d.
    let kwargs = pyo3::types::PyDict::new(v0.py());
    kwargs.set_item("dtype", np.getattr("float64")?)?;
    kwargs.set_item("order", "C")?;
    let arr = np
        .call_method("asarray", (arr,), Some(&kwargs))
        .map_err(|e| PyValueError::new_err(format!("v0: {}", e.value(v0.py()))))?;
    Ok(Velocities::Array(arr.cast_into::<PyArrayDyn<f64>>()?))
}

/// The outcome of a chunk of `mu` (merged over the chunks).
#[derive(Default)]
struct Tally {
    at_rest: usize,
    failed: usize,
    /// The first failure turned into NaN: (index, message).
    first_failure: Option<(usize, String)>,
    /// The first error raised: (index, error).
    first_error: Option<(usize, Error)>,
}

impl Tally {
    fn merge(a: Tally, b: Tally) -> Tally {
        fn first<T>(x: Option<(usize, T)>, y: Option<(usize, T)>) -> Option<(usize, T)> {
            match (x, y) {
                (Some(x), Some(y)) => Some(if x.0 <= y.0 { x } else { y }),
                (x, y) => x.or(y),
            }
        }
        Tally {
            at_rest: a.at_rest + b.at_rest,
            failed: a.failed + b.failed,
            first_failure: first(a.first_failure, b.first_failure),
            first_error: first(a.first_error, b.first_error),
        }
    }
}

/// Whether `errors="nan"` may turn `e` into NaN: solver failures, and
/// velocities that are not numbers in the domain (NaN, ±inf).
fn nan_allowed(e: &Error) -> bool {
    is_solver_failure(e) || e.msg.starts_with("--v0:")
}

/// The index of the `i`-th element (C order) of an array of `shape`, as text.
fn flat_index(shape: &[usize], mut i: usize) -> String {
    if shape.len() <= 1 {
        return i.to_string();
    }
    let mut idx = vec![0; shape.len()];
    for (k, &n) in shape.iter().enumerate().rev() {
        idx[k] = i % n.max(1);
        i /= n.max(1);
    }
    idx.iter()
        .map(|x| x.to_string())
        .collect::<Vec<_>>()
        .join(", ")
}
