//! `fricctl device sweep`: one drive parameter stepped over a grid; per
//! point the drive is set (the other drive values stay as set on the
//! device), the ramps and `--settle-periods` more periods are waited for,
//! μ is measured over `--periods` periods and the device's model predicts μ
//! at `--v0`; each point becomes one row of the sweep file
//! ([`crate::sweep_file`]), written whole as soon as it is measured, so an
//! interrupted sweep continues with `--resume`. Also `scene set --from-fit`.

use std::io::Write;
use std::path::{Path, PathBuf};

use board::device::{Contact, DriveSetting};
use board::protocol::{Request, Response};
use clap::Args;
use serde::Serialize;

use device_host::sweep;
pub use device_host::sweep::{
    ask, drive_of, fixed_columns, measure_here, set_point, PointOptions, SweepParam,
};

use super::client::Client;
use crate::args::{short, Count, Real};
use crate::error::{CliError, CliResult};
use crate::sweep_file::{self, SweepRow};

pub use device_host::sweep::MAX_POINTS;

/// Flags of `fricctl device sweep`.
#[derive(Args, Debug, Clone)]
pub struct SweepArgs {
    /// The drive parameter to sweep (its unit: ° for phase-deg, Hz for freq, m otherwise)
    #[arg(long, value_enum)]
    pub param: SweepParam,
    /// First value
    #[arg(long, value_parser = Real::ANY.single_precision())]
    pub from: f64,
    /// Last value
    #[arg(long, value_parser = Real::ANY.single_precision())]
    pub to: f64,
    /// Number of points, evenly spaced from --from to --to (1 to 10⁴)
    #[arg(long, value_parser = Count::<usize>::at_least(1).at_most(MAX_POINTS as u64, "sweep in several files for more"))]
    pub points: usize,
    /// Drive periods measured per point (≥ 1)
    #[arg(long, value_parser = Count::<u32>::at_least(1))]
    pub periods: u32,
    /// Extra drive periods waited (in device time: a discarded measurement) after the device's ramps have settled, for a lagging plant
    #[arg(long, default_value_t = 0, value_parser = Count::<u32>::at_least(0))]
    pub settle_periods: u32,
    /// Stage (sliding) velocity during the sweep, m/s: the device cannot know it; used for its prediction and written to every row
    #[arg(long, value_parser = Real::ANY.single_precision())]
    pub v0: f64,
    /// The sweep file (one row per point; refused if it exists, unless --resume)
    #[arg(long, value_name = "FILE")]
    pub csv: PathBuf,
    /// Plot measured μ (±1 standard error) and the device's predicted μ against the swept value to FILE.svg or FILE.png
    #[arg(long, value_name = "FILE")]
    pub plot: Option<PathBuf>,
    /// Continue the sweep in --csv: its rows must be this sweep's first points (same parameter and grid, v0, other drive values and device contact); the remaining points are measured and appended
    #[arg(long)]
    pub resume: bool,
}

impl SweepArgs {
    /// How each point is measured.
    pub fn point_options(&self) -> PointOptions {
        PointOptions {
            settle_periods: self.settle_periods,
            periods: self.periods,
            v0: self.v0,
        }
    }

    /// Checks the flags before connecting.
    ///
    /// # Errors
    /// One line naming the flag.
    pub fn check(&self) -> CliResult {
        // Each value is in its domain (the flags' parsers; `--points` is
        // capped before anything is allocated).
        if self.points == 1 && self.from != self.to {
            return Err(CliError::usage(
                "--points: 1 point needs --from equal to --to",
            ));
        }
        if !self.resume {
            if self.csv.exists() && !crate::output::force() {
                return Err(CliError::usage(format!(
                    "--csv: {} exists (--resume to continue that sweep, --force to replace it, or choose another file)",
                    self.csv.display()
                )));
            }
            crate::output::may_write(&self.csv, "csv")?;
        }
        crate::output::distinct_outputs(&[
            (Some(self.csv.as_path()), "csv"),
            (self.plot.as_deref(), "plot"),
        ])?;
        if let Some(p) = &self.plot {
            crate::plot::ext(p)?;
            crate::output::may_write(p, "plot")?;
        }
        Ok(())
    }

    /// The swept values, evenly spaced (exact end points).
    pub fn values(&self) -> Vec<f64> {
        fric_analysis::grid::linspace(self.from, self.to, self.points)
    }
}

/// Equal to 1e-9 relative (values written to and read from the file).
fn same(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-9 * a.abs().max(b.abs()).max(f64::MIN_POSITIVE)
}

/// The rows already in `path` for `--resume` (a cut-off last line is
/// dropped from the file), checked against this sweep; `probe` is a row
/// with the device's current non-swept drive, v0 and contact.
fn resume_rows(a: &SweepArgs, values: &[f64], probe: &SweepRow) -> CliResult<Vec<SweepRow>> {
    let path = &a.csv;
    let text = match std::fs::read(path) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Vec::new()),
        Err(e) => {
            return Err(CliError::failure(format!("--csv: {}: {e}", path.display())));
        }
    };
    if text.is_empty() {
        return Ok(Vec::new());
    }
    if !text.ends_with(b"\n") {
        // A row cut off by a kill: drop it (it is measured again).
        let keep = text.iter().rposition(|b| *b == b'\n').map_or(0, |i| i + 1);
        let f = std::fs::OpenOptions::new()
            .write(true)
            .open(path)
            .map_err(|e| CliError::failure(format!("--csv: {}: {e}", path.display())))?;
        f.set_len(keep as u64)
            .map_err(|e| CliError::failure(format!("--csv: {}: {e}", path.display())))?;
        eprintln!(
            "--resume: dropped a cut-off last line of {}",
            path.display()
        );
        if keep == 0 {
            return Ok(Vec::new());
        }
    }
    let rows = sweep_file::read_as(path, "csv")?;
    if rows.len() > values.len() {
        return Err(CliError::usage(format!(
            "--resume: {} has {} rows, more than --points {}",
            path.display(),
            rows.len(),
            values.len()
        )));
    }
    let other = |line: usize, what: String| {
        CliError::usage(format!(
            "--resume: {} line {line} belongs to another sweep: {what}",
            path.display()
        ))
    };
    for (i, r) in rows.iter().enumerate() {
        let line = i + 2;
        if r.param != a.param.name() {
            return Err(other(
                line,
                format!("param {} (this sweep: {})", r.param, a.param.name()),
            ));
        }
        if !same(r.value, values[i]) {
            return Err(other(
                line,
                format!(
                    "value {} (this sweep's point {}: {})",
                    r.value,
                    i + 1,
                    values[i]
                ),
            ));
        }
        let mut checks = fixed_columns(a.param, r);
        checks.extend([
            ("v0", r.v0),
            ("model_mu0", r.model_mu0),
            ("model_kz", r.model_kz),
            ("model_kx", r.model_kx),
        ]);
        let mut now = fixed_columns(a.param, probe);
        now.extend([
            ("v0", probe.v0),
            ("model_mu0", probe.model_mu0),
            ("model_kz", probe.model_kz),
            ("model_kx", probe.model_kx),
        ]);
        for ((n, x), (_, y)) in checks.iter().zip(&now) {
            if !same(*x, *y) {
                return Err(other(line, format!("{n} {x} (now {y})")));
            }
        }
    }
    Ok(rows)
}

/// `fricctl device sweep`.
///
/// # Errors
/// One line: bad flags or a file of another sweep (exit 2), a device that
/// refuses or does not answer, or invalid estimates at some points (exit 1,
/// after all rows are written).
pub fn run(c: &mut Client, a: &SweepArgs, json: bool) -> CliResult {
    // The drive is stepped for the sweep's own purpose: put back as it was
    // on every way out (the end, a refusal, an error, SIGINT or SIGTERM).
    let rows = device_host::state::restoring(c, |c| sweep_rows(c, a))?;
    if let Some(p) = &a.plot {
        crate::figures::device_sweep::plot(p, a.param, a.v0, &rows)?;
        eprintln!("wrote {}", p.display());
    }
    print_rows(a, &rows, json)?;
    let bad = rows.iter().filter(|r| !r.valid).count();
    if bad > 0 {
        return Err(CliError::failure(format!(
            "{bad} of {} points gave invalid estimates (kept in {} with valid = false; fit skips them)",
            rows.len(),
            a.csv.display()
        )));
    }
    Ok(())
}

/// The sweep's rows (those of `--resume` first), each written to the file
/// as soon as it is measured. A failure before the first row of a new
/// file removes the file: no header-only file is left behind
/// (docs/guide/output-files.md).
fn sweep_rows(c: &mut Client, a: &SweepArgs) -> CliResult<Vec<SweepRow>> {
    let values = a.values();
    let (base, freq0, phi0) = drive_of(ask(c, Request::GetDrive)?)?;
    let Response::Contact(contact) = ask(c, Request::GetContact)? else {
        return Err(CliError::failure("the device did not report its contact"));
    };
    let Response::Status(st) = ask(c, Request::GetStatus)? else {
        return Err(CliError::failure("the device did not report its status"));
    };
    if !st.running {
        return Err(CliError::failure(
            "the drive is stopped: `fricctl device start` first (a sweep measures a running drive)",
        ));
    }
    // A row with the device's current drive: the fixed columns of this sweep.
    let probe = row_for(a, f64::NAN, &base, freq0, phi0, contact);
    let mut rows = if a.resume {
        resume_rows(a, &values, &probe)?
    } else {
        Vec::new()
    };
    // Without --resume the file is new or replaced (--force): written from the start.
    let fresh =
        !a.resume || (rows.is_empty() && std::fs::metadata(&a.csv).map_or(true, |m| m.len() == 0));
    let file = std::fs::OpenOptions::new()
        .create(true)
        .append(!fresh)
        .write(true)
        .truncate(fresh)
        .open(&a.csv)
        .map_err(|e| CliError::failure(format!("--csv: {}: {e}", a.csv.display())))?;
    let io = |e: csv::Error| CliError::failure(format!("--csv: {}: {e}", a.csv.display()));
    let mut w = csv::WriterBuilder::new()
        .has_headers(false)
        .from_writer(file);
    if fresh {
        // The header first, on disk before any measurement.
        w.write_record(HEADER).map_err(io)?;
        w.flush().map_err(|e| io(e.into()))?;
    }
    if !rows.is_empty() {
        eprintln!(
            "resuming: {} of {} points already in {}",
            rows.len(),
            values.len(),
            a.csv.display()
        );
    }
    let bar = indicatif::ProgressBar::new(values.len() as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{bar:30} {pos}/{len} points  {msg}  [{elapsed_precise}, eta {eta}]",
        )
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    bar.set_position(rows.len() as u64);
    let before = rows.len();
    let r = measure_points(c, a, &values, base, contact, &mut w, &mut rows, &bar);
    bar.finish_and_clear();
    if r.is_err() && fresh && rows.len() == before {
        drop(w);
        // Only a regular file: never a device or FIFO (`--csv /dev/null`).
        if std::fs::symlink_metadata(&a.csv).is_ok_and(|m| m.is_file()) {
            let _ = std::fs::remove_file(&a.csv);
        }
    }
    r.map(|()| rows)
}

/// Measures the points after those in `rows`, appending each to `rows` and
/// to the file.
#[allow(clippy::too_many_arguments)]
fn measure_points(
    c: &mut Client,
    a: &SweepArgs,
    values: &[f64],
    base: DriveSetting,
    contact: Contact,
    w: &mut csv::Writer<std::fs::File>,
    rows: &mut Vec<SweepRow>,
    bar: &indicatif::ProgressBar,
) -> CliResult {
    let io = |e: csv::Error| CliError::failure(format!("--csv: {}: {e}", a.csv.display()));
    for &x in &values[rows.len()..] {
        bar.set_message(format!(
            "{} = {} {}",
            a.param.name(),
            short(x),
            a.param.unit()
        ));
        // A value the device refuses is named by the end of the sweep that
        // reaches it (the points lie between --from and --to).
        let end = if x == a.from { "--from" } else { "--to" };
        let (setting, freq, phi) = set_point(c, base, a.param, x)
            .map_err(|e| e.renamed(&format!("--{}", a.param.name()), end))?;
        let (e, prediction) = measure_here(c, freq, &a.point_options())?;
        let r = sweep::measured(row_for(a, x, &setting, freq, phi, contact), &e, &prediction);
        w.serialize(&r).map_err(io)?;
        w.flush().map_err(|e| io(e.into()))?;
        bar.inc(1);
        rows.push(r);
    }
    Ok(())
}

/// The file's header (the field names of [`SweepRow`], in order).
const HEADER: [&str; 16] = [
    "param",
    "value",
    "freq_hz",
    "amp_z",
    "amp_x",
    "offset_z",
    "phi_deg",
    "v0",
    "model_mu0",
    "model_kz",
    "model_kx",
    "measured_mu",
    "std_error",
    "predicted_mu",
    "valid",
    "reasons",
];

/// A row with the drive and contact filled in (results empty).
fn row_for(a: &SweepArgs, x: f64, d: &DriveSetting, freq: f64, phi: f64, k: Contact) -> SweepRow {
    sweep::row(a.param, x, d, (freq, phi), k, a.v0)
}

#[derive(Serialize)]
struct SweepOut<'a> {
    csv: String,
    param: &'a str,
    v0: f64,
    periods: u32,
    settle_periods: u32,
    rows: &'a [SweepRow],
}

fn print_rows(a: &SweepArgs, rows: &[SweepRow], json: bool) -> CliResult {
    let mut out = std::io::stdout().lock();
    let fail = |e: std::io::Error| CliError::failure(format!("stdout: {e}"));
    if json {
        let s = serde_json::to_string_pretty(&SweepOut {
            csv: a.csv.display().to_string(),
            param: a.param.name(),
            v0: a.v0,
            periods: a.periods,
            settle_periods: a.settle_periods,
            rows,
        })
        .map_err(|e| CliError::failure(format!("JSON: {e}")))?;
        return writeln!(out, "{s}").map_err(fail);
    }
    let head = format!("{} ({})", a.param.name(), a.param.unit());
    writeln!(
        out,
        "{head:>16}  {:>10}  {:>9}  {:>10}  {:>10}  valid",
        "measured μ", "± std err", "predicted", "meas−pred"
    )
    .map_err(fail)?;
    for r in rows {
        let value = match a.param {
            SweepParam::PhaseDeg | SweepParam::Freq => format!("{:.4}", r.value),
            _ => format!("{:.4e}", r.value),
        };
        writeln!(
            out,
            "{value:>16}  {:>10.6}  {:>9.2e}  {:>10.6}  {:>10.2e}  {}",
            r.measured_mu,
            r.std_error,
            r.predicted_mu,
            r.measured_mu - r.predicted_mu,
            if r.valid {
                "yes".to_string()
            } else {
                format!("no ({})", r.reasons)
            }
        )
        .map_err(fail)?;
    }
    writeln!(
        out,
        "{} points, v0 = {} m/s, {} periods each (+{} settle), rows in {}",
        rows.len(),
        a.v0,
        a.periods,
        a.settle_periods,
        a.csv.display()
    )
    .map_err(fail)
}

/// The domain of `--kz` and `--kx` (N/m): the device model's
/// ([`board::device::STIFFNESS_RANGE_N_PER_M`]).
pub const STIFFNESS: Real = Real::positive()
    .at_least(board::device::STIFFNESS_RANGE_N_PER_M.0)
    .at_most(board::device::STIFFNESS_RANGE_N_PER_M.1)
    .single_precision()
    .because("the contact stiffness the device's f32 model takes, N/m");

/// μ0, k_z, k_x for `scene set`: from the flags, or from the JSON that
/// `fricctl fit --out` wrote (keys `mu0`, `kz`, `kx`).
///
/// # Errors
/// One line naming the flag (or the file and key) for a value outside its domain
/// (μ0 > 0, the stiffnesses [`STIFFNESS`]) or a file that is not a fit result.
pub fn scene_values(
    mu0: Option<f64>,
    kz: Option<f64>,
    kx: Option<f64>,
    from_fit: Option<&Path>,
) -> CliResult<(f64, f64, f64)> {
    let (vals, src): ([Option<f64>; 3], String) = match from_fit {
        Some(p) => {
            let text = std::fs::read_to_string(p).map_err(|e| {
                CliError::usage(format!("--from-fit: cannot read {}: {e}", p.display()))
            })?;
            let v: serde_json::Value = serde_json::from_str(&text).map_err(|e| {
                CliError::usage(format!(
                    "--from-fit: {} is not JSON (expected `fricctl fit --out` output): {e}",
                    p.display()
                ))
            })?;
            let get = |k: &str| v.get(k).and_then(serde_json::Value::as_f64);
            (
                [get("mu0"), get("kz"), get("kx")],
                format!("--from-fit: {} key ", p.display()),
            )
        }
        None => ([mu0, kz, kx], "--".to_string()),
    };
    let mut out = [0.0; 3];
    let domains = [Real::positive().single_precision(), STIFFNESS, STIFFNESS];
    for (((x, name), o), domain) in vals
        .iter()
        .zip(["mu0", "kz", "kx"])
        .zip(&mut out)
        .zip(domains)
    {
        // The flags' own domain, for the values of a fit file too.
        match x {
            Some(x) => {
                *o = domain
                    .check(*x, &short(*x))
                    .map_err(|r| CliError::usage(format!("{src}{name}: {r}")))?;
            }
            None => return Err(CliError::usage(format!("{src}{name}: missing"))),
        }
    }
    Ok((out[0], out[1], out[2]))
}
