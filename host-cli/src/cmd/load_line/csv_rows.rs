//! `load-line --csv FILE`: the force–velocity line(s) as rows of
//! `v, force, p_out, p_in, p_friction, efficiency`, units in the header
//! (`v` signed, negative on the backward line; `force` the contact's force
//! on the body `−μ(v)F̄z` along `+x`, so `p_out = force·v`).

use std::path::Path;

use super::{Sample, Units};
use crate::error::{CliError, CliResult};
use crate::output::AtomicFile;

/// Writes the rows of every line in `lines` to `path` (complete or not at
/// all); errors name `--csv`.
pub(super) fn write(path: &Path, lines: &[Vec<Sample>], u: &Units) -> CliResult {
    let (fu, vu, pu) = u.names();
    let mut w = csv::Writer::from_writer(Vec::new());
    let err = |e: csv::Error| CliError::failure(format!("--csv: {e}"));
    w.write_record([
        format!("v [{vu}]"),
        format!("force [{fu}]"),
        format!("p_out [{pu}]"),
        format!("p_in [{pu}]"),
        format!("p_friction [{pu}]"),
        "efficiency [1]".to_string(),
    ])
    .map_err(err)?;
    for (v, p) in lines.iter().flatten() {
        w.write_record([
            format!("{:e}", v * u.velocity),
            format!("{:e}", -p.mu_over_mu0 * u.force),
            format!("{:e}", p.output * u.power),
            format!("{:e}", p.input * u.power),
            format!("{:e}", p.friction * u.power),
            format!("{:e}", p.efficiency()),
        ])
        .map_err(err)?;
    }
    let bytes = w
        .into_inner()
        .map_err(|e| CliError::failure(format!("--csv: {e}")))?;
    let mut f = AtomicFile::create(path, "csv")?;
    f.write_all(&bytes)?;
    f.commit()
}
