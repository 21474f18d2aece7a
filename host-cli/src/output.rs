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
    if path.is_dir() {
        return Err(CliError::usage(format!(
            "--{flag}: {} is a directory (name a file in it)",
            path.display()
        )));
    }
    writable_parent(path, flag)?;
    let exists = std::fs::symlink_metadata(path).is_ok();
    if exists && !force() {
        return Err(CliError::usage(format!(
            "--{flag}: {} exists (give --force to replace it, or choose another file)",
            path.display()
        )));
    }
    Ok(exists)
}

/// The directory `path` would be written in exists, is a directory, and
/// takes a new file (a temporary one is created and removed): checked before
/// any work, so that a missing or read-only directory is refused by name
/// instead of failing after the computation (or the device's sweep).
fn writable_parent(path: &Path, flag: &str) -> CliResult {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    if !dir.is_dir() {
        let what = if dir.exists() {
            "is not a directory"
        } else {
            "does not exist"
        };
        return Err(CliError::usage(format!(
            "--{flag}: {}: the directory {} {what}",
            path.display(),
            dir.display()
        )));
    }
    tempfile::NamedTempFile::new_in(dir).map(drop).map_err(|e| {
        CliError::usage(format!(
            "--{flag}: {}: cannot write in {}: {}",
            path.display(),
            dir.display(),
            io_reason(&e)
        ))
    })
}

/// An I/O error's reason without the `(os error N)` suffix.
pub fn io_reason(e: &std::io::Error) -> String {
    let s = e.to_string();
    match s.find(" (os error") {
        Some(i) => s[..i].to_string(),
        None => s,
    }
}

/// The same file named twice, by `a` and by `b` (compared after resolving
/// the directory, so `./x.png` and `x.png` are one file).
fn same_file(a: &Path, b: &Path) -> bool {
    let resolve = |p: &Path| {
        let dir = match p.parent() {
            Some(d) if !d.as_os_str().is_empty() => d,
            _ => Path::new("."),
        };
        (
            std::fs::canonicalize(dir).unwrap_or_else(|_| dir.to_path_buf()),
            p.file_name().map(|n| n.to_os_string()),
        )
    };
    !special(a) && resolve(a) == resolve(b)
}

/// No two outputs of one command name the same file (`None`: not asked for).
pub fn distinct_outputs(files: &[(Option<&Path>, &str)]) -> CliResult {
    let named: Vec<(&Path, &str)> = files
        .iter()
        .filter_map(|(p, f)| p.map(|p| (p, *f)))
        .collect();
    for (i, (a, fa)) in named.iter().enumerate() {
        for (b, fb) in &named[i + 1..] {
            if same_file(a, b) {
                return Err(CliError::usage(format!(
                    "--{fb}: names the same file as --{fa} ({}); give each output its own file",
                    b.display()
                )));
            }
        }
    }
    Ok(())
}

/// Every output of a command checked before it computes or touches a
/// device (`None`: not asked for): each in a writable directory, not a
/// directory itself, an existing file only with `--force`, a `--plot` with
/// a figure's extension, and no two outputs naming the same file.
pub fn check_outputs(files: &[(Option<&Path>, &str)]) -> CliResult {
    distinct_outputs(files)?;
    let named: Vec<(&Path, &str)> = files
        .iter()
        .filter_map(|(p, f)| p.map(|p| (p, *f)))
        .collect();
    for (p, flag) in &named {
        if *flag == "plot" {
            crate::plot::ext(p)?;
        }
        refused(p, flag)?;
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
