//! `fricctl.tune`, `fricctl.fit`, `fricctl.load_line`: the CLI's commands
//! of the same names, with results as [`Record`]s (their JSON keys as
//! attributes).

use fric_analysis::fit::{self as fitting, FitParam};
use fric_analysis::load_line as loadline;
use fric_analysis::motion::simulate::{self, MotionMethod, MotionRequest};
use fric_analysis::sweep_file::{self, SweepRow};
use fric_analysis::tune::{self as tuning, Adjust, Maximize, TuneOutcome, TuneRequest};
use model_core::scene::ContactMode;
use numpy::{PyArray1, PyArrayMethods};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyString, PyTuple};

use crate::args::{type_name, Float};
use crate::errors::{run, to_py, warn};
use crate::record::Record;
use crate::scene::Scene;

/// Inverse design (`fricctl tune`).
#[pyfunction]
#[pyo3(signature = (scene, *, adjust, target_mu_rel=None, target_mu=None, maximize=None, v0=None, v_rel=None, max_duz=None, max_dux=None, liftoff_margin=Float::Num(tuning::DEFAULT_LIFTOFF_MARGIN)), text_signature = "(scene, *, adjust, target_mu_rel=None, target_mu=None, maximize=None, v0=None, v_rel=None, max_duz=None, max_dux=None, liftoff_margin=0.05)")]
#[allow(clippy::too_many_arguments)]
pub fn tune(
    py: Python<'_>,
    scene: &Scene,
    adjust: &str,
    target_mu_rel: Option<Float>,
    target_mu: Option<Float>,
    maximize: Option<&str>,
    v0: Option<Float>,
    v_rel: Option<Float>,
    max_duz: Option<Float>,
    max_dux: Option<Float>,
    liftoff_margin: Float,
) -> PyResult<Record> {
    let target_mu_rel = Float::opt(target_mu_rel, "target_mu_rel")?;
    let target_mu = Float::opt(target_mu, "target_mu")?;
    let v0 = Float::opt(v0, "v0")?;
    let v_rel = Float::opt(v_rel, "v_rel")?;
    let max_duz = Float::opt(max_duz, "max_duz")?;
    let max_dux = Float::opt(max_dux, "max_dux")?;
    let liftoff_margin = liftoff_margin.get("liftoff_margin")?;
    let req = TuneRequest {
        v0,
        v_rel,
        target_mu_rel,
        target_mu,
        maximize: maximize
            .map(Maximize::from_name)
            .transpose()
            .map_err(to_py)?,
        adjust: Adjust::from_name(adjust).map_err(to_py)?,
        max_duz,
        max_dux,
        liftoff_margin,
    };
    let input = scene.input().clone();
    let out =
        py.detach(|| run(|| tuning::tune(&input.resolve_with(ContactMode::Permanent)?, &req)))?;
    match out {
        TuneOutcome::Target(o) => {
            if let Some(e) = o.doubtful() {
                warn(py, &e.msg)?;
            }
            Record::of(py, "TuneResult", &o)
        }
        TuneOutcome::Maximize(o) => Record::of(py, "TuneResult", &o),
    }
}

/// The load line (`fricctl load-line`).
#[pyfunction]
pub fn load_line(py: Python<'_>, scene: &Scene) -> PyResult<Record> {
    let input = scene.input().clone();
    let an = py.detach(|| {
        run(|| {
            let rs = input.resolve_with(ContactMode::Intermittent)?;
            loadline::analyse(&rs).map(|a| a.out)
        })
    })?;
    Record::of(py, "LoadLine", &an)
}

/// The sweep's columns: (name, required).
const COLUMNS: [(&str, bool); 16] = [
    ("param", false),
    ("value", false),
    ("freq_hz", true),
    ("amp_z", true),
    ("amp_x", true),
    ("offset_z", true),
    ("phi_deg", true),
    ("v0", true),
    ("model_mu0", true),
    ("model_kz", true),
    ("model_kx", true),
    ("measured_mu", true),
    ("std_error", false),
    ("predicted_mu", false),
    ("valid", false),
    ("reasons", false),
];

/// Column `name` of `data` (a mapping or a DataFrame) as floats, or None.
/// A column that is not numbers (strings, None, objects) is a TypeError
/// naming `data` and the column: numpy would read "0.1" as a number.
fn column(
    np: &Bound<'_, PyModule>,
    data: &Bound<'_, PyAny>,
    name: &str,
    n: Option<usize>,
) -> PyResult<Option<Vec<f64>>> {
    let named_err =
        |e: PyErr| PyTypeError::new_err(format!("data: column '{name}': {}", e.value(data.py())));
    let has = data
        .call_method1("__contains__", (name,))
        .and_then(|h| h.is_truthy())
        .map_err(named_err)?;
    if !has {
        return Ok(None);
    }
    let col = data.get_item(name).map_err(named_err)?;
    let arr = np.call_method1("asarray", (col,)).map_err(named_err)?;
    let kind: String = arr.getattr("dtype")?.getattr("kind")?.extract()?;
    if !matches!(kind.as_str(), "b" | "i" | "u" | "f") {
        return Err(PyTypeError::new_err(format!(
            "data: column '{name}' must hold numbers (got dtype {})",
            arr.getattr("dtype")?.str()?
        )));
    }
    let arr = arr
        .call_method1("astype", (np.getattr("float64")?,))?
        .call_method0("ravel")?;
    let arr = arr.cast_into::<PyArray1<f64>>()?;
    let v: Vec<f64> = arr.readonly().as_array().to_vec();
    if let Some(n) = n {
        if v.len() != n {
            return Err(PyValueError::new_err(format!(
                "data: column '{name}' has {} rows, the others {n}",
                v.len()
            )));
        }
    }
    Ok(Some(v))
}

/// The rows of a sweep given as columns.
fn rows_of(py: Python<'_>, data: &Bound<'_, PyAny>) -> PyResult<Vec<SweepRow>> {
    let np = py.import("numpy")?;
    let mut cols: Vec<Option<Vec<f64>>> = Vec::new();
    let mut n = None;
    for (name, required) in COLUMNS {
        if matches!(name, "param" | "reasons") {
            cols.push(None);
            continue;
        }
        let c = column(&np, data, name, n)?;
        if c.is_none() && required {
            return Err(PyValueError::new_err(format!(
                "data: missing column '{name}' (needed: freq_hz, amp_z, amp_x, offset_z, phi_deg, v0, model_mu0, model_kz, model_kx, measured_mu; optional: std_error, valid, value)"
            )));
        }
        if let Some(c) = &c {
            n = Some(c.len());
        }
        cols.push(c);
    }
    let n = n.unwrap_or(0);
    let get = |k: usize, i: usize, default: f64| cols[k].as_ref().map_or(default, |c| c[i]);
    Ok((0..n)
        .map(|i| SweepRow {
            param: String::new(),
            value: get(1, i, i as f64),
            freq_hz: get(2, i, 0.0),
            amp_z: get(3, i, 0.0),
            amp_x: get(4, i, 0.0),
            offset_z: get(5, i, 0.0),
            phi_deg: get(6, i, 0.0),
            v0: get(7, i, 0.0),
            model_mu0: get(8, i, 0.0),
            model_kz: get(9, i, 0.0),
            model_kx: get(10, i, 0.0),
            measured_mu: get(11, i, 0.0),
            std_error: get(12, i, 0.0),
            predicted_mu: get(13, i, f64::NAN),
            valid: get(14, i, 1.0) != 0.0,
            reasons: String::new(),
        })
        .collect())
}

/// `params` as the CLI's comma-separated text: None (the default), a
/// string, or a list or tuple of strings; anything else a TypeError naming
/// `params`.
fn params_text(params: Option<&Bound<'_, PyAny>>) -> PyResult<String> {
    let wrong = |what: String| {
        PyTypeError::new_err(format!(
            "params: expected a string or a list of strings, got {what}"
        ))
    };
    let Some(p) = params else {
        return Ok("mu0,kx_over_kz".to_string());
    };
    if p.is_instance_of::<PyString>() {
        return p.extract::<String>();
    }
    if !(p.is_instance_of::<PyList>() || p.is_instance_of::<PyTuple>()) {
        return Err(wrong(type_name(p)));
    }
    let mut names = Vec::new();
    for item in p.try_iter()? {
        let item = item?;
        if !item.is_instance_of::<PyString>() {
            return Err(wrong(format!(
                "a {} holding {}",
                type_name(p),
                type_name(&item)
            )));
        }
        names.push(item.extract::<String>()?);
    }
    Ok(names.join(","))
}

/// Identification (`fricctl fit`): `data` is the path of a sweep file, or
/// its columns (a dict of arrays or a pandas DataFrame).
#[pyfunction]
#[pyo3(signature = (data, params=None))]
pub fn fit(
    py: Python<'_>,
    data: &Bound<'_, PyAny>,
    params: Option<&Bound<'_, PyAny>>,
) -> PyResult<Record> {
    let which = FitParam::parse_list(&params_text(params)?).map_err(to_py)?;
    let rows = if data.is_instance_of::<PyString>() || data.hasattr("__fspath__")? {
        let path: std::path::PathBuf = data
            .extract()
            .map_err(|e: PyErr| PyTypeError::new_err(format!("data: {}", e.value(py))))?;
        run(|| sweep_file::read_as(&path, "data"))?
    } else if data.is_instance_of::<PyDict>()
        || (data.hasattr("__contains__")?
            && data.hasattr("__getitem__")?
            && data.hasattr("keys")?)
    {
        rows_of(py, data)?
    } else {
        return Err(PyTypeError::new_err(format!(
            "data: expected a sweep file path, a dict of arrays or a pandas DataFrame, got {}",
            type_name(data)
        )));
    };
    let (r, residuals) = py.detach(|| run(|| fitting::fit(&rows, &which)))?;
    let (value, residual_mu, std_error): (Vec<f64>, Vec<f64>, Vec<f64>) = residuals
        .iter()
        .map(|r| (r.value, r.residual_mu, r.std_error))
        .fold((vec![], vec![], vec![]), |mut acc, x| {
            acc.0.push(x.0);
            acc.1.push(x.1);
            acc.2.push(x.2);
            acc
        });
    if let Some(msg) = &r.doubtful {
        warn(py, msg)?;
    }
    let arr = |v: Vec<f64>| PyArray1::from_vec(py, v).into_any().unbind();
    Ok(Record::of(py, "FitResult", &r)?
        .with("residual_value", arr(value))
        .with("residual_mu", arr(residual_mu))
        .with("residual_std_error", arr(std_error)))
}

/// A body moved by the vibrated contact (`fricctl motion`): the result and
/// the trajectory (the last ≤ 50 load periods) as arrays.
#[pyfunction]
#[pyo3(signature = (scene, *, mass, force_amp_rel, force_omega, force_offset_rel=Float::Num(0.0), spring=Float::Num(0.0), duration=None, method="auto", tol=Float::Num(1e-3)), text_signature = "(scene, *, mass, force_amp_rel, force_omega, force_offset_rel=0.0, spring=0.0, duration=None, method=\"auto\", tol=0.001)")]
#[allow(clippy::too_many_arguments)]
pub fn motion(
    py: Python<'_>,
    scene: &Scene,
    mass: Float,
    force_amp_rel: Float,
    force_omega: Float,
    force_offset_rel: Float,
    spring: Float,
    duration: Option<Float>,
    method: &str,
    tol: Float,
) -> PyResult<Record> {
    let mass = mass.get("mass")?;
    let force_amp_rel = force_amp_rel.get("force_amp_rel")?;
    let force_omega = force_omega.get("force_omega")?;
    let force_offset_rel = force_offset_rel.get("force_offset_rel")?;
    let spring = spring.get("spring")?;
    let duration = Float::opt(duration, "duration")?;
    let tol = tol.get("tol")?;
    let req = MotionRequest {
        mass,
        force_amp_rel,
        force_omega,
        force_offset_rel,
        spring,
        duration,
        method: MotionMethod::from_name(method).map_err(to_py)?,
        tol,
    };
    let rs = *scene.resolved();
    let (sim, rows) = py.detach(|| {
        run(|| {
            let sim = simulate::simulate(&rs, &req, &mut |_| {})?;
            let rows = sim.rows(&rs, force_omega);
            Ok((sim, rows))
        })
    })?;
    let doubtful = sim.doubtful().map(|e| e.msg);
    if let Some(msg) = &doubtful {
        warn(py, msg)?;
    }
    let col = |f: &dyn Fn(&simulate::Row) -> f64| {
        PyArray1::from_vec(py, rows.iter().map(f).collect())
            .into_any()
            .unbind()
    };
    let stuck = PyArray1::from_vec(py, rows.iter().map(|r| r.stuck != 0).collect::<Vec<bool>>())
        .into_any()
        .unbind();
    Ok(Record::of(py, "Motion", &sim.outcome)?
        .with("doubtful", doubtful.into_pyobject(py)?.into_any().unbind())
        .with("t", col(&|r| r.t))
        .with("x", col(&|r| r.x))
        .with("v", col(&|r| r.v))
        .with("force", col(&|r| r.force))
        .with("stuck", stuck))
}
