//! `fricctl curve`: μ(v) over a velocity range as CSV rows.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use clap::Args;
use model_core::mdr::Profile;
use model_core::scene::ContactMode;

use crate::args::{Count, Real, Rounded};
use crate::error::{CliError, CliResult};
use crate::eval::{critical_velocity, from_rel, MethodArgs};
use crate::output::{csv_bytes, stdout_error, AtomicFile};
use crate::plot::{render_panels, Mark, Panel, Series};
use crate::progress::progress_bar;
use fric_analysis::grid::{curve_rows_with, linspace_at, MethodMix};

/// Flags of `fricctl curve`.
#[derive(Args, Debug, Clone)]
pub struct CurveCmd {
    #[command(flatten)]
    scene: crate::scene_args::SceneArgs,
    /// Lowest velocity, m/s
    #[arg(long, value_parser = Real::ANY, requires = "v_max", conflicts_with_all = ["v_rel_min", "v_rel_max"])]
    v_min: Option<f64>,
    /// Highest velocity, m/s
    #[arg(long, value_parser = Real::ANY, requires = "v_min")]
    v_max: Option<f64>,
    /// Lowest velocity relative to v_c (negative: relative to the backward v_c)
    #[arg(long, value_parser = Real::ANY, requires = "v_rel_max")]
    v_rel_min: Option<f64>,
    /// Highest velocity relative to v_c
    #[arg(long, value_parser = Real::ANY, requires = "v_rel_min")]
    v_rel_max: Option<f64>,
    /// Number of velocities (≥ 2, at most 10⁷; written like any number: 1e6)
    #[arg(long, value_parser = Count::<usize>::at_least(2).at_most(MAX_POINTS as u64, "write several curves for more"))]
    points: usize,
    #[command(flatten)]
    how: MethodArgs,
    /// A curved --profile: compute every velocity by its own MDR quadrature (default: runs of velocities where μ(v) is smooth come from an interpolant through quadratures, method mdr-interpolated, with its bound)
    #[arg(long)]
    per_point: bool,
    /// Write the CSV to FILE instead of stdout
    #[arg(long, value_name = "FILE")]
    csv: Option<PathBuf>,
    /// Plot μ/μ0 against v to FILE.svg or FILE.png
    #[arg(long, value_name = "FILE")]
    plot: Option<PathBuf>,
}

/// Velocities computed and written per step: whole chunks of rows are
/// written at once, progress advances and Ctrl-C is honoured between chunks
/// (≈ 50 ms each with the exact solver).
const CHUNK: usize = 1 << 16;

/// At most this many points go to the plot: beyond it each run of
/// consecutive rows keeps its lowest and highest μ (the line's envelope).
const PLOT_POINTS: usize = 8_000;

/// The largest `--points` (≈ 10 s with the exact solver).
const MAX_POINTS: usize = 10_000_000;

/// Where the velocities lie.
#[derive(Debug, Clone, Copy)]
enum Axis {
    /// v0 from `lo` to `hi`, m/s (units of ωW0 for a dimensionless scene).
    Absolute(f64, f64),
    /// v0 = x·v_c with x from `lo` to `hi`.
    Relative(f64, f64),
}

/// Where the CSV goes.
enum Sink<'a, W: Write> {
    Stdout(&'a mut W),
    File(AtomicFile, &'a Path),
}

impl CurveCmd {
    /// Runs the command: computes the rows chunk by chunk in parallel and
    /// writes each chunk's whole rows before computing the next, so memory
    /// stays bounded by a chunk whatever `--points` is.
    pub fn run(mut self, out: &mut impl Write) -> CliResult {
        let rs = self.scene.resolve_with(ContactMode::Intermittent)?;
        self.how.profile = rs.profile;
        if self.per_point && rs.profile == Profile::Flat {
            return Err(CliError::usage(
                "--per-point: only for a curved --profile (a flat punch is computed point by point)",
            ));
        }
        let n = self.points;
        if let Some(p) = &self.plot {
            crate::plot::ext(p)?;
        }
        crate::output::check_outputs(&[
            (self.plot.as_deref(), "plot"),
            (self.csv.as_deref(), "csv"),
        ])?;
        let vc = critical_velocity(&rs.scene)?;
        let axis = match (
            self.v_min.zip(self.v_max),
            self.v_rel_min.zip(self.v_rel_max),
        ) {
            (Some((lo, hi)), None) => {
                check_range(lo, hi, "v-min", "v-max")?;
                rs.velocity(lo, "--v-min")?;
                rs.velocity(hi, "--v-max")?;
                Axis::Absolute(lo, hi)
            }
            (None, Some((lo, hi))) => {
                check_range(lo, hi, "v-rel-min", "v-rel-max")?;
                // The ends decide whether each direction's v_c is needed.
                rs.velocity(from_rel(&vc, lo, "v-rel-min")?, "--v-rel-min")?;
                rs.velocity(from_rel(&vc, hi, "v-rel-max")?, "--v-rel-max")?;
                Axis::Relative(lo, hi)
            }
            (None, None) => {
                return Err(CliError::usage(
                    "--v-min: missing (give --v-min/--v-max or --v-rel-min/--v-rel-max)",
                ))
            }
            _ => {
                return Err(CliError::usage(
                    "--v-rel-min: cannot be used with --v-min/--v-max",
                ))
            }
        };
        self.how.validate()?;
        let velocity = |i: usize| -> CliResult<f64> {
            match axis {
                Axis::Absolute(lo, hi) => Ok(linspace_at(lo, hi, n, i)),
                Axis::Relative(lo, hi) => {
                    let x = linspace_at(lo, hi, n, i);
                    from_rel(&vc, x, if x < 0.0 { "v-rel-min" } else { "v-rel-max" })
                }
            }
        };
        let mut sink = match &self.csv {
            Some(path) => Sink::File(AtomicFile::create(path, "csv")?, path.as_path()),
            None => Sink::Stdout(out),
        };
        let interrupted = interrupt_flag();
        let pb = progress_bar(n as u64, "curve {bar:40} {pos}/{len} velocities ({eta})");
        let mut mix = MethodMix::default();
        let mut worst = 0.0f64;
        let mut rows_written = 0usize;
        let mut plot = self
            .plot
            .as_ref()
            .map(|_| Envelope::new(n.div_ceil(PLOT_POINTS / 2)));
        let mut vs = Vec::with_capacity(CHUNK.min(n));
        for start in (0..n).step_by(CHUNK) {
            if interrupted.load(Ordering::SeqCst) {
                pb.finish_and_clear();
                let what = match &sink {
                    Sink::File(_, p) => format!("{} not written", p.display()),
                    Sink::Stdout(_) => format!("{rows_written} whole rows written"),
                };
                return Err(CliError {
                    code: 130,
                    msg: format!("interrupted after {start} of {n} velocities ({what})"),
                });
            }
            vs.clear();
            for i in start..(start + CHUNK).min(n) {
                vs.push(velocity(i)?);
            }
            // A velocity between the ends that the solver refuses is named
            // by the range's upper flag.
            let upper = match axis {
                Axis::Absolute(..) => "--v-max",
                Axis::Relative(..) => "--v-rel-max",
            };
            let rows = curve_rows_with(&rs.scene, &vs, &self.how.options(), !self.per_point)
                .map_err(|e| e.renamed("--v0", upper))?;
            for r in &rows {
                mix.add(r.method);
                worst = worst.max(r.error_bound_over_mu0);
                if let Some(e) = plot.as_mut() {
                    let x = match axis {
                        Axis::Absolute(..) => r.v0,
                        Axis::Relative(..) => r.v_rel.unwrap_or(f64::NAN),
                    };
                    e.push((x, r.mu_over_mu0));
                }
            }
            let bytes = csv_bytes(&rows, start == 0)?;
            match &mut sink {
                Sink::File(f, _) => f.write_all(&bytes)?,
                Sink::Stdout(o) => {
                    o.write_all(&bytes).map_err(stdout_error)?;
                    o.flush().map_err(stdout_error)?;
                }
            }
            rows_written += rows.len();
            pb.inc(vs.len() as u64);
        }
        pb.finish_and_clear();
        eprintln!(
            "methods: {} (largest error bound {worst:e} mu0)",
            mix.text(", ")
        );
        if let Sink::File(f, path) = sink {
            f.commit()?;
            eprintln!("wrote {rows_written} rows to {}", path.display());
        }
        if let (Some(p), Some(e)) = (&self.plot, plot) {
            let x_label = match axis {
                Axis::Relative(..) => {
                    "v0 / v_c  (forward v_c for v0 > 0, backward for v0 < 0)".to_string()
                }
                Axis::Absolute(..) if rs.dimensionless => "v0 / (ω μ0 k_z u_z0 / k_x)".to_string(),
                Axis::Absolute(..) => "v0, m/s".to_string(),
            };
            let pts = e.finish();
            let (x0, x1) = pts
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
                    (a.min(p.0), b.max(p.0))
                });
            let ymin = pts.iter().fold(0.0f64, |m, p| m.min(p.1));
            let g = rs.scene.groups();
            // The tangential group the user gave: the ratio (eq. 26) if
            // given, else k_xΔu_x/(μ0 k_z u_z0) (eq. 25).
            let tangential = match rs.scene.ratio() {
                Some(r) => format!("k_xΔu_x/(μ0 k_z Δu_z) = {}", Rounded(r)),
                None => format!("k_xΔu_x/(μ0 k_z u_z0) = {}", Rounded(g.dux_rel)),
            };
            let panel = Panel {
                title: format!(
                    "μ(v), {}: Δu_z/u_z0 = {}, {tangential}, φ = {}°{}",
                    crate::scene_args::profile_text(&rs.profile),
                    Rounded(g.duz_rel),
                    Rounded(g.phi.to_degrees()),
                    if rs.scene.lifts_off() {
                        " (lifts off: μ = ⟨f_x⟩/⟨f_z⟩)"
                    } else {
                        ""
                    }
                ),
                x_label,
                y_label: "μ / μ0".to_string(),
                x: (x0, if x1 > x0 { x1 } else { x0 + 1.0 }),
                y: (ymin.min(-0.05) - 0.05, 1.08),
                // One curve: no legend (the methods and the bound are on stderr).
                series: vec![Series {
                    label: String::new(),
                    points: pts,
                    mark: Mark::Line,
                    color: 0,
                }],
            };
            render_panels(p, &[panel], 1, 1, (1000, 650))?;
            eprintln!("wrote {}", p.display());
        }
        Ok(())
    }
}

/// A flag set by Ctrl-C (SIGINT) once the handler is installed; if it cannot
/// be installed, Ctrl-C ends the program as usual (a `--csv` file is then
/// still never left truncated: it is renamed into place only when complete).
fn interrupt_flag() -> Arc<AtomicBool> {
    let flag = Arc::new(AtomicBool::new(false));
    let f = flag.clone();
    let _ = ctrlc::set_handler(move || f.store(true, Ordering::SeqCst));
    flag
}

/// The points of a line thinned to its envelope: of each run of `run`
/// consecutive points, the one with the lowest and the one with the highest
/// y, in their original order (all points when `run` is 1).
struct Envelope {
    run: usize,
    current: Vec<(f64, f64)>,
    points: Vec<(f64, f64)>,
}

impl Envelope {
    fn new(run: usize) -> Self {
        Envelope {
            run: run.max(1),
            current: Vec::new(),
            points: Vec::new(),
        }
    }

    fn push(&mut self, p: (f64, f64)) {
        if self.run == 1 {
            self.points.push(p);
            return;
        }
        self.current.push(p);
        if self.current.len() == self.run {
            self.flush();
        }
    }

    fn flush(&mut self) {
        let lo = self
            .current
            .iter()
            .enumerate()
            .min_by(|a, b| a.1 .1.total_cmp(&b.1 .1));
        let hi = self
            .current
            .iter()
            .enumerate()
            .max_by(|a, b| a.1 .1.total_cmp(&b.1 .1));
        if let (Some((i, &l)), Some((j, &h))) = (lo, hi) {
            match i.cmp(&j) {
                std::cmp::Ordering::Less => self.points.extend([l, h]),
                std::cmp::Ordering::Greater => self.points.extend([h, l]),
                std::cmp::Ordering::Equal => self.points.push(l),
            }
        }
        self.current.clear();
    }

    fn finish(mut self) -> Vec<(f64, f64)> {
        self.flush();
        self.points
    }
}

/// `lo < hi` (both in their domain: the flags' parsers).
fn check_range(lo: f64, hi: f64, a: &str, b: &str) -> CliResult {
    if hi <= lo {
        return Err(CliError::usage(format!(
            "--{b}: must be greater than --{a} (got {} ≤ {})",
            crate::args::short(hi),
            crate::args::short(lo)
        )));
    }
    Ok(())
}
