//! `import fricctl`: the Python bindings of the dual-mode friction-control
//! analysis (pyo3 + rust-numpy). Thin: every number comes from
//! `fric-analysis` (the code behind the CLI `fricctl`), every refusal names the
//! Python keyword, then gives the CLI's one-line message, as `ValueError`
//! (bad input; `TypeError` for a value of the wrong type) or
//! `fricctl.SolverError` (a computation that failed); a panic never crosses
//! the boundary. `fricctl.Device` drives a board, the QEMU firmware or the
//! virtual device through the CLI's own device library (device-host). The
//! stub `fricctl.pyi` documents the API.

#![deny(missing_docs)]

mod analyses;
mod args;
mod device;
mod errors;
mod record;
mod scene;

use pyo3::prelude::*;

/// The module `fricctl`.
#[pymodule]
fn fricctl(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add("SolverError", m.py().get_type::<errors::SolverError>())?;
    m.add_class::<scene::Scene>()?;
    m.add_class::<record::Record>()?;
    m.add_class::<device::Device>()?;
    device::add_exceptions(m)?;
    m.add_function(wrap_pyfunction!(analyses::tune, m)?)?;
    m.add_function(wrap_pyfunction!(analyses::fit, m)?)?;
    m.add_function(wrap_pyfunction!(analyses::load_line, m)?)?;
    m.add_function(wrap_pyfunction!(analyses::motion, m)?)?;
    m.add_function(wrap_pyfunction!(_panic_for_tests, m)?)?;
    Ok(())
}

/// A panic inside a computation, for the tests: it must reach Python as
/// `SolverError`, never as a crash or a `PanicException`.
#[pyfunction]
fn _panic_for_tests() -> PyResult<()> {
    errors::run(|| -> Result<(), fric_analysis::Error> { panic!("deliberate test panic") })
}
