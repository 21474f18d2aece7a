//! Results as plain attributes: a [`Record`] holds the fields of a result
//! (the keys of the CLI's `--json` document, the same names and units) and
//! prints them in its `repr`.

use pyo3::exceptions::PyAttributeError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use serde::Serialize;

/// A result whose fields are attributes (`r.mu0`, `r.stall_force`), in the
/// order and with the names of the CLI's JSON keys.
#[pyclass(frozen, module = "fricctl")]
pub struct Record {
    kind: &'static str,
    fields: Vec<(String, Py<PyAny>)>,
}

impl Record {
    /// A record of kind `kind` from a serialisable result: its JSON keys,
    /// in the order of the CLI's `--json` document.
    pub fn of(py: Python<'_>, kind: &'static str, value: &impl Serialize) -> PyResult<Record> {
        let text = serde_json::to_string(value)
            .map_err(|e| PyErr::new::<pyo3::exceptions::PyRuntimeError, _>(e.to_string()))?;
        let d = py.import("json")?.call_method1("loads", (text,))?;
        let d = d.cast_into::<PyDict>()?;
        let fields = d
            .iter()
            .map(|(k, v)| Ok((k.extract::<String>()?, v.unbind())))
            .collect::<PyResult<Vec<_>>>()?;
        Ok(Record { kind, fields })
    }

    /// Adds a field (arrays such as residuals or trajectories).
    pub fn with(mut self, name: &str, value: Py<PyAny>) -> Record {
        self.fields.push((name.to_string(), value));
        self
    }
}

#[pymethods]
impl Record {
    fn __getattr__(&self, py: Python<'_>, name: &str) -> PyResult<Py<PyAny>> {
        self.fields
            .iter()
            .find(|(k, _)| k == name)
            .map(|(_, v)| v.clone_ref(py))
            .ok_or_else(|| {
                PyAttributeError::new_err(format!("{} has no field '{name}'", self.kind))
            })
    }

    fn __dir__(&self) -> Vec<String> {
        self.fields.iter().map(|(k, _)| k.clone()).collect()
    }

    /// The fields as a dict (name → value), in order.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        for (k, v) in &self.fields {
            d.set_item(k, v.clone_ref(py))?;
        }
        Ok(d)
    }

    fn __repr__(&self, py: Python<'_>) -> PyResult<String> {
        let mut parts = Vec::with_capacity(self.fields.len());
        for (k, v) in &self.fields {
            let r = v.bind(py).repr()?.to_string();
            // Arrays and long lists: their shape, not their contents.
            let r = if r.len() > 60 {
                match v.bind(py).getattr("shape") {
                    Ok(s) => format!("<array {}>", s.repr()?),
                    Err(_) => format!(
                        "{}…",
                        &r[..r.char_indices().nth(57).map_or(r.len(), |c| c.0)]
                    ),
                }
            } else {
                r
            };
            parts.push(format!("    {k}={r},"));
        }
        Ok(format!("{}(\n{}\n)", self.kind, parts.join("\n")))
    }
}
