//! Writing results: JSON documents, CSV rows (always whole rows), and files
//! that appear only when complete (written to a temporary file in the same
//! directory, then renamed).

use std::io::Write;
use std::path::{Path, PathBuf};

use serde::Serialize;
use tempfile::NamedTempFile;

use crate::error::{CliError, CliResult};

/// The error of a failed write to stdout.
pub fn stdout_error(e: std::io::Error) -> CliError {
    CliError::failure(format!("stdout: {e}"))
}

/// Writes `v` as pretty JSON and a newline.
pub fn write_json<T: Serialize>(out: &mut impl Write, v: &T) -> CliResult {
    let s = serde_json::to_string_pretty(v).map_err(|e| CliError::failure(format!("JSON: {e}")))?;
    writeln!(out, "{s}").map_err(stdout_error)
}

/// Rows as CSV bytes (with the header line derived from `T`'s field names
/// when `header`): whole rows only, so that a consumer never sees half a row.
pub fn csv_bytes<T: Serialize>(rows: &[T], header: bool) -> CliResult<Vec<u8>> {
    let mut w = csv::WriterBuilder::new()
        .has_headers(header)
        .from_writer(Vec::with_capacity(rows.len() * 96));
    for r in rows {
        w.serialize(r)
            .map_err(|e| CliError::failure(format!("CSV: {e}")))?;
    }
    w.into_inner()
        .map_err(|e| CliError::failure(format!("CSV: {e}")))
}

/// A file that appears under its name only when [`AtomicFile::commit`]
/// succeeds: until then the bytes go to a temporary file in the same
/// directory (removed if the program stops first), so an interrupted run
/// never leaves a truncated file.
pub struct AtomicFile {
    tmp: NamedTempFile,
    path: PathBuf,
    flag: &'static str,
}

impl AtomicFile {
    /// Starts the file `path`; `flag` (e.g. `csv`) names it in errors.
    pub fn create(path: &Path, flag: &'static str) -> CliResult<Self> {
        let dir = match path.parent() {
            Some(d) if !d.as_os_str().is_empty() => d,
            _ => Path::new("."),
        };
        let tmp = tempfile::Builder::new()
            .prefix(".fricctl-")
            .suffix(".part")
            .tempfile_in(dir)
            .map_err(|e| {
                // Name the user's file, not the temporary one next to it.
                let why = if dir.is_dir() {
                    e.kind().to_string()
                } else {
                    format!("no directory {}", dir.display())
                };
                CliError::failure(format!("--{flag}: cannot create {}: {why}", path.display()))
            })?;
        Ok(AtomicFile {
            tmp,
            path: path.to_path_buf(),
            flag,
        })
    }

    /// Appends bytes.
    pub fn write_all(&mut self, bytes: &[u8]) -> CliResult {
        self.tmp.write_all(bytes).map_err(|e| self.error(e))
    }

    /// Flushes and renames the file to its name.
    pub fn commit(mut self) -> CliResult {
        self.tmp.flush().map_err(|e| self.error(e))?;
        let (flag, path) = (self.flag, self.path.clone());
        self.tmp.persist(&path).map_err(|e| {
            CliError::failure(format!(
                "--{flag}: cannot write {}: {}",
                path.display(),
                e.error
            ))
        })?;
        Ok(())
    }

    fn error(&self, e: std::io::Error) -> CliError {
        CliError::failure(format!("--{}: {}: {e}", self.flag, self.path.display()))
    }
}

/// Writes serialisable rows as a CSV file (complete or not at all).
pub fn write_rows<T: Serialize>(p: &Path, rows: &[T]) -> CliResult {
    let mut f = AtomicFile::create(p, "csv")?;
    f.write_all(&csv_bytes(rows, true)?)?;
    f.commit()?;
    eprintln!("wrote {}", p.display());
    Ok(())
}
