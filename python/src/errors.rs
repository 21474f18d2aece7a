//! Errors across the boundary: the library's one-line message becomes
//! `ValueError` (bad input) or `fricctl.SolverError` (the computation
//! failed), the Python keyword first and the CLI's text after it
//! (`mu0: --mu0: must be > 0 (got -1)`); a Rust panic becomes `SolverError`
//! too.

use std::panic::{catch_unwind, AssertUnwindSafe};

use fric_analysis::Error;
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;

pyo3::create_exception!(
    fricctl,
    SolverError,
    PyRuntimeError,
    "A solver could not produce a result within its bound (the CLI's exit status 1)."
);

/// Whether a bad-input message is a tolerance that no method meets: a
/// solver that cannot meet the tolerance is a `SolverError` in Python
/// (the CLI refuses it as bad input, exit status 2).
fn tolerance_unmet(e: &Error) -> bool {
    e.msg.starts_with("--tol:") && e.msg.contains("is tighter than")
}

/// Whether `e` is a failure of the computation (not of the input).
pub fn is_solver_failure(e: &Error) -> bool {
    !e.is_bad_input() || tolerance_unmet(e)
}

/// The Python exception of a library error, its message led by the
/// keyword of the flag it names ([`crate::args::named`]).
pub fn to_py(e: Error) -> PyErr {
    let msg = crate::args::named(&e.msg);
    if is_solver_failure(&e) {
        SolverError::new_err(msg)
    } else {
        PyValueError::new_err(msg)
    }
}

/// Runs `f`, turning a panic into an [`Error`] (a failure).
pub fn guard<T>(f: impl FnOnce() -> Result<T, Error>) -> Result<T, Error> {
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok(r) => r,
        Err(p) => {
            let what = p
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| p.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "unknown".to_string());
            Err(Error::failure(format!(
                "internal error (a bug; please report it): {what}"
            )))
        }
    }
}

/// [`guard`] with the result as a Python exception.
pub fn run<T>(f: impl FnOnce() -> Result<T, Error>) -> PyResult<T> {
    guard(f).map_err(to_py)
}

/// Issues a `RuntimeWarning` with `msg`.
pub fn warn(py: Python<'_>, msg: &str) -> PyResult<()> {
    let category = py.get_type::<pyo3::exceptions::PyRuntimeWarning>();
    PyErr::warn(
        py,
        &category,
        &std::ffi::CString::new(msg).unwrap_or_default(),
        1,
    )
}
