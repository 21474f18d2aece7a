//! Writing results: JSON documents, CSV rows (always whole rows), and files
//! that appear only when complete (written to a temporary file in the same
//! directory, then renamed).
//!
//! The overwrite policy, the same for every file named by a flag (`--csv`,
//! `--out FILE`): an existing file is refused, before any work, unless
//! `--force` is given; with `--force` it is replaced and stderr says so.
//! A new file gets the mode `File::create` would give it (0666 less the
//! umask); a replaced file keeps its mode.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};

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

/// `--force` (a flag of every command, set once by `main`).
static FORCE: AtomicBool = AtomicBool::new(false);

/// Sets the overwrite policy from `--force`.
pub fn set_force(force: bool) {
    FORCE.store(force, Ordering::SeqCst);
}

/// Whether an existing output file may be replaced (`--force`).
pub fn force() -> bool {
    FORCE.load(Ordering::SeqCst)
}

/// The overwrite policy for one output file: `Ok(())` if `path` does not
/// exist, or exists and `--force` is given (stderr then says that it will be
/// replaced); a usage error naming `--flag` if it exists without `--force`.
/// Commands call this before they compute, so that a refusal costs nothing.
pub fn may_write(path: &Path, flag: &str) -> CliResult {
    if refused(path, flag)? {
        eprintln!(
            "--{flag}: {} exists; replacing it (--force)",
            path.display()
        );
    }
    Ok(())
}

/// `Ok(true)` if `path` exists and may be replaced, `Ok(false)` if it does
/// not exist, the policy's error if it exists without `--force`.
fn refused(path: &Path, flag: &str) -> CliResult<bool> {
    // Only an existing regular file is "overwritten": a device, FIFO or
    // socket (`/dev/null`, `/dev/stdout`, a pipe) is written to as such.
    if special(path) {
        return Ok(false);
    }
    let exists = std::fs::symlink_metadata(path).is_ok();
    if exists && !force() {
        return Err(CliError::usage(format!(
            "--{flag}: {} exists (give --force to replace it, or choose another file)",
            path.display()
        )));
    }
    Ok(exists)
}

/// [`may_write`] for each named output (`None`: not asked for).
pub fn check_outputs(files: &[(Option<&Path>, &str)]) -> CliResult {
    for (p, flag) in files {
        if let Some(p) = p {
            refused(p, flag)?;
        }
    }
    for (p, flag) in files {
        if let Some(p) = p {
            may_write(p, flag)?;
        }
    }
    Ok(())
}

/// Whether `path` (followed through symlinks) exists and is not a regular
/// file or directory: a character or block device, a FIFO, a socket.
fn special(path: &Path) -> bool {
    std::fs::metadata(path).is_ok_and(|m| !m.is_file() && !m.is_dir())
}

/// A file that appears under its name only when [`AtomicFile::commit`]
/// succeeds: until then the bytes go to a temporary file in the same
/// directory (removed if the program stops first), so an interrupted run
/// never leaves a truncated file. A path that is a device, FIFO or socket
/// (`--csv /dev/null`, a pipe) is written to directly: renaming a temporary
/// file over it would replace the device node itself (as root, `/dev/null`
/// became a regular file that way).
pub struct AtomicFile {
    out: Target,
    path: PathBuf,
    flag: &'static str,
}

/// Where an [`AtomicFile`]'s bytes go.
enum Target {
    /// A temporary file renamed to the name at the end.
    Temp(NamedTempFile),
    /// A device, FIFO or socket, written to as it is.
    Special(std::fs::File),
}

impl AtomicFile {
    /// Starts the file `path`; `flag` (e.g. `csv`) names it in errors.
    /// Follows the overwrite policy (the command has called [`may_write`]
    /// before its work; this only repeats the refusal).
    pub fn create(path: &Path, flag: &'static str) -> CliResult<Self> {
        refused(path, flag)?;
        if special(path) {
            let f = std::fs::OpenOptions::new()
                .write(true)
                .open(path)
                .map_err(|e| CliError::failure(format!("--{flag}: {}: {e}", path.display())))?;
            return Ok(AtomicFile {
                out: Target::Special(f),
                path: path.to_path_buf(),
                flag,
            });
        }
        let dir = match path.parent() {
            Some(d) if !d.as_os_str().is_empty() => d,
            _ => Path::new("."),
        };
        let mut b = tempfile::Builder::new();
        b.prefix(".fricctl-").suffix(".part");
        // Not tempfile's private 0600: the mode an ordinary `File::create`
        // gives (0666 less the umask, applied by the kernel at creation).
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            b.permissions(std::fs::Permissions::from_mode(0o666));
        }
        let tmp = b.tempfile_in(dir).map_err(|e| {
            // Name the user's file, not the temporary one next to it.
            let why = if dir.is_dir() {
                e.kind().to_string()
            } else {
                format!("no directory {}", dir.display())
            };
            CliError::failure(format!("--{flag}: cannot create {}: {why}", path.display()))
        })?;
        // A replaced file keeps its mode.
        if let Ok(m) = std::fs::metadata(path) {
            let _ = std::fs::set_permissions(tmp.path(), m.permissions());
        }
        Ok(AtomicFile {
            out: Target::Temp(tmp),
            path: path.to_path_buf(),
            flag,
        })
    }

    /// Appends bytes.
    pub fn write_all(&mut self, bytes: &[u8]) -> CliResult {
        let r = match &mut self.out {
            Target::Temp(t) => t.write_all(bytes),
            Target::Special(f) => f.write_all(bytes),
        };
        r.map_err(|e| self.error(e))
    }

    /// Flushes and renames the file to its name (a device: flushes).
    pub fn commit(mut self) -> CliResult {
        let r = match &mut self.out {
            Target::Temp(t) => t.flush(),
            Target::Special(f) => f.flush(),
        };
        r.map_err(|e| self.error(e))?;
        let (flag, path) = (self.flag, self.path.clone());
        if let Target::Temp(t) = self.out {
            t.persist(&path).map_err(|e| {
                CliError::failure(format!(
                    "--{flag}: cannot write {}: {}",
                    path.display(),
                    e.error
                ))
            })?;
        }
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
