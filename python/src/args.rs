//! Arguments read by keyword: integers of any size (never pyo3's unnamed
//! `OverflowError`), and the keyword in front of every refusal.
//!
//! pyo3 names the argument of a `TypeError` raised while extracting it
//! (`argument 'mu0': must be real number, not str`), but not of any other
//! error: an `OverflowError` for a negative or huge integer reaches the
//! user without it. [`Int`] takes any Python integer, and [`Int::get`]
//! checks its range with the keyword in the message.

use pyo3::exceptions::{PyOverflowError, PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyFloat, PyInt, PyString};

/// A Python integer as given: its value when it fits an `i64`, else its
/// decimal text (beyond every count's range).
#[derive(Clone, Debug)]
pub enum Int {
    /// The value.
    Small(i64),
    /// The decimal text of an integer beyond `i64`, and its sign.
    Big(String, bool),
}

impl<'py> FromPyObject<'_, 'py> for Int {
    type Error = PyErr;

    fn extract(ob: Borrowed<'_, 'py, PyAny>) -> PyResult<Self> {
        // bool is an int in Python, but True steps are a mistake; a float is
        // not an integer (3.0 would be, 3.5 not: neither is taken).
        if ob.is_instance_of::<PyBool>()
            || ob.is_instance_of::<PyFloat>()
            || ob.is_instance_of::<PyString>()
        {
            return Err(PyTypeError::new_err(format!(
                "expected an integer, got {}",
                type_name(&ob)
            )));
        }
        // Python ints, and numpy's integers through __index__.
        let i = if ob.is_instance_of::<PyInt>() {
            ob.to_owned().into_any()
        } else if ob.hasattr("__index__")? {
            ob.call_method0("__index__")?
        } else {
            return Err(PyTypeError::new_err(format!(
                "expected an integer, got {}",
                type_name(&ob)
            )));
        };
        match i.extract::<i64>() {
            Ok(v) => Ok(Int::Small(v)),
            Err(_) => {
                let negative = i.lt(0)?;
                Ok(Int::Big(i.str()?.to_string(), negative))
            }
        }
    }
}

/// A real number as Python gives it: anything pyo3 reads as an `f64` (a
/// float, an int, a numpy scalar), or an int beyond the `f64` range
/// (`10**400`), which pyo3 would refuse with an `OverflowError` that does
/// not name the argument: [`Float::get`] names it.
#[derive(Clone, Copy, Debug)]
pub enum Float {
    /// The value.
    Num(f64),
    /// An int beyond ±f64::MAX: its number of decimal digits and sign.
    Huge(usize, bool),
}

impl<'py> FromPyObject<'_, 'py> for Float {
    type Error = PyErr;

    fn extract(ob: Borrowed<'_, 'py, PyAny>) -> PyResult<Self> {
        match ob.extract::<f64>() {
            Ok(x) => Ok(Float::Num(x)),
            Err(e)
                if ob.is_instance_of::<PyInt>() && e.is_instance_of::<PyOverflowError>(ob.py()) =>
            {
                let text = ob.str()?.to_string();
                let negative = text.starts_with('-');
                Ok(Float::Huge(text.trim_start_matches('-').len(), negative))
            }
            // A TypeError: pyo3 names the argument.
            Err(e) => Err(e),
        }
    }
}

impl Float {
    /// The value, or an `OverflowError` naming `kw`.
    pub fn get(self, kw: &str) -> PyResult<f64> {
        match self {
            Float::Num(x) => Ok(x),
            Float::Huge(digits, negative) => Err(PyOverflowError::new_err(format!(
                "{kw}: {}an int of {digits} digits is beyond the range of a float (magnitude ≤ 1.8e308)",
                if negative { "-" } else { "" }
            ))),
        }
    }

    /// [`Float::get`] of an optional argument.
    pub fn opt(x: Option<Float>, kw: &str) -> PyResult<Option<f64>> {
        x.map(|x| x.get(kw)).transpose()
    }
}

/// Why a count is out of its range: below (a `ValueError`) or beyond its
/// type (an `OverflowError`), with the message.
#[derive(Debug, PartialEq, Eq)]
pub enum OutOfRange {
    /// Below the least value.
    Below(String),
    /// Above the greatest value the quantity's type holds.
    Above(String),
}

impl Int {
    /// The value in `[lo, hi]`, or why not (naming `kw`).
    pub fn check(&self, kw: &str, lo: u64, hi: u64) -> Result<u64, OutOfRange> {
        let below = |got: &dyn std::fmt::Display| {
            OutOfRange::Below(format!("{kw}: must be ≥ {lo} (got {got})"))
        };
        let above = |got: &dyn std::fmt::Display| {
            OutOfRange::Above(format!("{kw}: must be ≤ {hi} (got {got})"))
        };
        match self {
            Int::Small(v) if *v < 0 || (*v as u64) < lo => Err(below(v)),
            Int::Small(v) if (*v as u64) > hi => Err(above(v)),
            Int::Small(v) => Ok(*v as u64),
            Int::Big(t, true) => Err(below(t)),
            Int::Big(t, false) => Err(above(t)),
        }
    }

    /// The value in `[lo, hi]`, as `u64`: below `lo` a `ValueError`, above
    /// `hi` an `OverflowError` (`hi` is the largest the quantity's type
    /// holds), each naming `kw`.
    pub fn get(&self, kw: &str, lo: u64, hi: u64) -> PyResult<u64> {
        self.check(kw, lo, hi).map_err(|e| match e {
            OutOfRange::Below(m) => PyValueError::new_err(m),
            OutOfRange::Above(m) => PyOverflowError::new_err(m),
        })
    }

    /// [`Int::get`] into a `u32` (its whole range above `lo`).
    pub fn u32(&self, kw: &str, lo: u32) -> PyResult<u32> {
        // In range by `get`'s bound.
        Ok(self.get(kw, u64::from(lo), u64::from(u32::MAX))? as u32)
    }
}

/// The name of an object's type, for messages.
pub fn type_name(ob: &Bound<'_, PyAny>) -> String {
    ob.get_type()
        .name()
        .map(|n| n.to_string())
        .unwrap_or_else(|_| "?".to_string())
}

/// The Python keyword of a CLI flag: `--phi-deg` → `phi_deg`.
pub fn keyword_of(flag: &str) -> String {
    flag.trim_start_matches('-').replace('-', "_")
}

/// A library message in Python's words: the keyword first, then the CLI's
/// own text (`--mu0: must be > 0 (got -1)` → `mu0: --mu0: must be > 0 (got
/// -1)`). A message that does not start with a flag is returned as it is.
pub fn named(msg: &str) -> String {
    if let Some(rest) = msg.strip_prefix("--") {
        if let Some(end) = rest.find(':') {
            let flag = &rest[..end];
            if !flag.is_empty()
                && flag
                    .chars()
                    .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '-')
            {
                return format!("{}: {msg}", keyword_of(flag));
            }
        }
    }
    msg.to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keyword_leads_and_the_cli_text_follows() {
        assert_eq!(
            named("--mu0: must be > 0 (got -1)"),
            "mu0: --mu0: must be > 0 (got -1)"
        );
        assert_eq!(
            named("--phi-deg: must be of magnitude ≤ 1e100 (got inf)"),
            "phi_deg: --phi-deg: must be of magnitude ≤ 1e100 (got inf)"
        );
        assert_eq!(named("errors: invalid value"), "errors: invalid value");
        assert_eq!(named("-- odd"), "-- odd");
    }

    #[test]
    fn int_ranges_name_the_keyword() {
        let max = u64::from(u32::MAX);
        assert_eq!(
            Int::Small(-5).check("steps_per_period", 1, max),
            Err(OutOfRange::Below(
                "steps_per_period: must be ≥ 1 (got -5)".into()
            ))
        );
        assert_eq!(
            Int::Big("1180591620717411303424".into(), false).check("steps_per_period", 1, max),
            Err(OutOfRange::Above(
                "steps_per_period: must be ≤ 4294967295 (got 1180591620717411303424)".into()
            ))
        );
        assert_eq!(
            Int::Small(1 << 40).check("n", 0, max),
            Err(OutOfRange::Above(format!(
                "n: must be ≤ 4294967295 (got {})",
                1u64 << 40
            )))
        );
        assert_eq!(Int::Small(7).check("n", 1, max), Ok(7));
        assert_eq!(Int::Small(0).check("n", 0, max), Ok(0));
    }
}
