//! The sweep file: one CSV row per measured drive point, written by
//! `fricctl device sweep` and read by `fricctl fit`.
//!
//! Columns (SI units; the header names them, the order is the struct's):
//!
//! | column | meaning |
//! |---|---|
//! | `param` | the swept parameter (`phase-deg`, `amp-z`, `amp-x`, `offset-z`, `freq`) |
//! | `value` | its value at this row, in the parameter's unit (°, m, m, m, Hz) |
//! | `freq_hz` | drive frequency as produced, Hz |
//! | `amp_z` | normal amplitude Δu_z, m |
//! | `amp_x` | tangential amplitude Δu_x, m |
//! | `offset_z` | mean indentation u_z0, m |
//! | `phi_deg` | phase φ of the tangential oscillation, ° |
//! | `v0` | sliding velocity, m/s |
//! | `model_mu0`, `model_kz`, `model_kx` | the device model's contact (μ₀, N/m, N/m) |
//! | `measured_mu` | μ from the board's estimator (eq. 20) |
//! | `std_error` | its standard error (0 when unknown) |
//! | `predicted_mu` | the device model's μ for this drive |
//! | `valid` | the estimate passed the board's quality checks |
//! | `reasons` | why not, `;`-separated (empty when valid) |

use std::path::Path;

use model_core::{Scene, SceneParams};
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// One measured point of a sweep.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SweepRow {
    /// The swept parameter's name.
    pub param: String,
    /// The swept parameter's value (°, m or Hz).
    pub value: f64,
    /// Drive frequency, Hz.
    pub freq_hz: f64,
    /// Δu_z, m.
    pub amp_z: f64,
    /// Δu_x, m.
    pub amp_x: f64,
    /// u_z0, m.
    pub offset_z: f64,
    /// φ, degrees.
    pub phi_deg: f64,
    /// v₀, m/s.
    pub v0: f64,
    /// The device model's μ₀.
    pub model_mu0: f64,
    /// The device model's k_z, N/m.
    pub model_kz: f64,
    /// The device model's k_x, N/m.
    pub model_kx: f64,
    /// Measured μ.
    pub measured_mu: f64,
    /// Standard error of `measured_mu` (0 = unknown).
    pub std_error: f64,
    /// The device model's μ.
    pub predicted_mu: f64,
    /// The estimate passed the board's checks.
    pub valid: bool,
    /// Reasons for an invalid estimate, `;`-separated.
    pub reasons: String,
}

impl SweepRow {
    /// The scene of this row with contact `mu0`, `kz`, `kx` (the drive from the row).
    ///
    /// # Errors
    /// A one-line usage error naming the row when the drive is not a valid scene.
    pub fn scene(&self, mu0: f64, kz: f64, kx: f64, line: usize) -> Result<Scene<f64>> {
        Scene::new(SceneParams {
            mu0,
            kz,
            kx,
            uz0: self.offset_z,
            duz: self.amp_z,
            dux: self.amp_x,
            omega: std::f64::consts::TAU * self.freq_hz,
            phi: self.phi_deg.to_radians(),
        })
        .map_err(|e| Error::usage(format!("--data: line {line}: {e}")))
    }
}

/// Reads a sweep file.
///
/// # Errors
/// A one-line error naming the file and the row for unreadable or malformed data.
pub fn read(path: &Path) -> Result<Vec<SweepRow>> {
    read_as(path, "data")
}

/// Reads a sweep file given by the flag `--{flag}` (named in errors).
///
/// # Errors
/// As [`read`].
pub fn read_as(path: &Path, flag: &str) -> Result<Vec<SweepRow>> {
    if path.is_dir() {
        return Err(Error::usage(format!(
            "--{flag}: {} is a directory",
            path.display()
        )));
    }
    let mut r = csv::Reader::from_path(path)
        .map_err(|e| Error::usage(format!("--{flag}: cannot read {}: {e}", path.display())))?;
    let mut rows = Vec::new();
    for (i, rec) in r.deserialize::<SweepRow>().enumerate() {
        // Row numbers as a spreadsheet shows them: the header is line 1.
        let line = i + 2;
        let row = rec
            .map_err(|e| Error::usage(format!("--{flag}: {} line {line}: {e}", path.display())))?;
        rows.push(row);
    }
    Ok(rows)
}
