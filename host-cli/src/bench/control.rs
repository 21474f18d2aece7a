//! `fricctl bench control`: the board's closed μ loop on resonant
//! transducers ([`crate::device::control`], `device control-bench`) over a
//! grid, and on a drifting plant with and without resonance tracking.
//!
//! * **Grid** (`control_grid.csv`, `.json`): Q ∈ {100, 300, 1000} of the
//!   normal mode, the tangential mode's Q two thirds of it (the defaults'
//!   300 : 200); the normal resonance at 20 kHz and at 40 kHz, the
//!   tangential one below it in the defaults' ratio 19 700 / 20 300 (2.96 %
//!   below); headroom 1 (no overdrive) and 2. Every run is `device
//!   control-bench` with these flags and its defaults otherwise (plant μ0
//!   20 % below the model, ±2 counts ADC noise, κ 0.95, `--periods auto`,
//!   fills 2 half-buffers ahead), once per noise record (`--seeds`, seed 0
//!   the default record): per grid point and event the median and the
//!   largest settling time over the records, the median overshoot, τ and
//!   the samples above the lift-off limit of all the runs.
//! * **Drift** (`control_drift.csv`, `.json`): the default transducers
//!   (20 300 Hz, Q 300; 19 700 Hz, Q 200), the normal resonance drifting
//!   ([`DRIFTS_HZ_PER_S`]) and both self-heating [`THERMAL_HZ_PER_UM2`], the
//!   four events and then [`HOLD_S`] s of device time at the last setpoint,
//!   tracking the normal mode (`--track z`) and not (`--track none`): μ
//!   error of the hold, lock time, tracking error, the fault that ended
//!   the run if one did.
//! * **Figure** `settle_vs_tau.png`: settling time against τ, log–log.
//!
//! `--quick` runs a reduced grid (Q 100 and 300 at 20 kHz, headroom 2)
//! and holds [`QUICK_HOLD_S`] s: the files and their columns, not the
//! numbers of the full grid.

use std::path::{Path, PathBuf};

use board::device::Track;
use clap::Args;
use serde::Serialize;

use device_host::control_bench::BenchOut;
pub use device_host::control_grid::*;

use crate::error::{CliError, CliResult};
use crate::plot::{prepare_out_dir, render_figure};

/// Flags of `bench control`.
#[derive(Args, Debug, Clone)]
pub struct ControlArgs {
    /// Output directory (control_grid.csv/.json, control_drift.csv/.json,
    /// settle_vs_tau.png); existing files are refused without --force
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// The reduced grid and a short hold (checks the files, not the numbers)
    #[arg(long)]
    pub quick: bool,
    /// Noise records per grid point (seeds 0 … N − 1 of `device
    /// control-bench --seed`): the grid reports the median and the largest
    /// settling time over them. 1 … 100
    #[arg(long, default_value_t = 5, value_parser = crate::args::Count::<u32>::at_least(1).at_most(100, "a record runs in 0.01–0.5 s"))]
    pub seeds: u32,
}

/// The grid's JSON document.
#[derive(Serialize, Debug)]
struct GridJson<'a> {
    command: String,
    runs: Vec<GridJsonRun<'a>>,
}

#[derive(Serialize, Debug)]
struct GridJsonRun<'a> {
    q_z: f64,
    q_x: f64,
    resonance_z_hz: f64,
    resonance_x_hz: f64,
    headroom: f64,
    command: &'a str,
    /// One result per seed (0 first; `--seed S` reproduces seed S).
    results: &'a [BenchOut],
}

fn files(out: &Path) -> [PathBuf; 5] {
    [
        out.join("control_grid.csv"),
        out.join("control_grid.json"),
        out.join("control_drift.csv"),
        out.join("control_drift.json"),
        out.join("settle_vs_tau.png"),
    ]
}

/// `fricctl bench control`.
pub fn run(a: &ControlArgs) -> CliResult {
    prepare_out_dir(&a.out)?;
    let paths = files(&a.out);
    let named: Vec<(Option<&Path>, &str)> =
        paths.iter().map(|p| (Some(p.as_path()), "out")).collect();
    crate::output::check_outputs(&named)?;
    let g = grid(a.quick);
    let hold = if a.quick { QUICK_HOLD_S } else { HOLD_S };
    let n_seeds = if a.quick { 1 } else { a.seeds };
    let bar = indicatif::ProgressBar::new((g.len() + 2 * DRIFTS_HZ_PER_S.len()) as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{bar:30} {pos}/{len} runs  {msg}  [{elapsed_precise}, eta {eta}]",
        )
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    let mut runs = Vec::new();
    for (q, f, h) in g {
        bar.set_message(format!("Q {q}, {f} Hz, headroom {h}"));
        let run = grid_run(q, f, h, n_seeds)?;
        bar.println(grid_line(&run, n_seeds));
        bar.inc(1);
        runs.push(run);
    }
    let mut drift = Vec::new();
    for (rate, track) in DRIFTS_HZ_PER_S
        .iter()
        .flat_map(|r| [(*r, Track::None), (*r, Track::Z)])
    {
        let name = if track == Track::Z { "z" } else { "none" };
        bar.set_message(format!("drift {rate} Hz/s, tracking {name}, hold {hold} s"));
        let d = drift_run(rate, track, hold)?;
        let out = &d.out;
        bar.println(format!(
            "drift {rate} Hz/s, tracking {name}: hold {:.2} s, mu error rms {}, lock {} ms, faults [{}], {:.1} s",
            out.hold_run_s,
            out.hold_mu_error_rms.map_or("-".into(), |x| format!("{x:.2e}")),
            out.lock_ms.map_or("-".into(), |x| format!("{x:.1}")),
            out.faults.join(", "),
            out.wall_s
        ));
        bar.inc(1);
        drift.push(d);
    }
    bar.finish_and_clear();
    write_outputs(a, &paths, &runs, &drift)?;
    // Events that never settle and faults that end a drift run are
    // measurements (the files and the figure show them); a sample of the
    // true normal excursion above the lift-off limit is a safety failure.
    let above = above_limit(&runs, &drift);
    match above.first() {
        None => Ok(()),
        Some(first) => Err(CliError::failure(format!(
            "bench control: {} run(s) put samples of the true normal excursion above the lift-off limit (first: {first})",
            above.len()
        ))),
    }
}

/// The progress line of a grid point.
fn grid_line(run: &GridRun, n_seeds: u32) -> String {
    let med = |e: &str| {
        run.median_settle(e)
            .map_or("never".into(), |s| format!("{s:.2}"))
    };
    format!(
        "Q {:>5}, f_r {:>6} Hz, headroom {}: tau {:.2} ms, median settle over {n_seeds} (ms) {} / {} / {} / {}, above limit {}, {:.1} s",
        run.q_z,
        run.resonance_z_hz,
        run.headroom,
        run.out.tau_ms,
        med("switch_on"),
        med("setpoint_step"),
        med("disturbance"),
        med("velocity_step"),
        run.seeds.iter().map(|o| o.commands_above_limit).sum::<u64>(),
        run.seeds.iter().map(|o| o.wall_s).sum::<f64>()
    )
}

fn write_outputs(
    a: &ControlArgs,
    paths: &[PathBuf; 5],
    runs: &[GridRun],
    drift: &[DriftRun],
) -> CliResult {
    let cmd = format!(
        "fricctl bench control --out {}{}",
        a.out.display(),
        if a.quick {
            " --quick".to_string()
        } else if a.seeds != 5 {
            format!(" --seeds {}", a.seeds)
        } else {
            String::new()
        }
    );
    let rows: Vec<GridRow> = runs.iter().flat_map(GridRun::rows).collect();
    write_file(&paths[0], &crate::output::csv_bytes(&rows, true)?)?;
    let doc = GridJson {
        command: cmd.clone(),
        runs: runs
            .iter()
            .map(|r| GridJsonRun {
                q_z: r.q_z,
                q_x: r.q_x,
                resonance_z_hz: r.resonance_z_hz,
                resonance_x_hz: r.resonance_x_hz,
                headroom: r.headroom,
                command: &r.command,
                results: &r.seeds,
            })
            .collect(),
    };
    write_file(&paths[1], &json_bytes(&doc)?)?;
    let drows: Vec<DriftRow> = drift.iter().map(DriftRun::row).collect();
    write_file(&paths[2], &crate::output::csv_bytes(&drows, true)?)?;
    #[derive(Serialize)]
    struct DriftJson<'a> {
        command: String,
        runs: &'a [DriftRun],
    }
    write_file(
        &paths[3],
        &json_bytes(&DriftJson {
            command: cmd.clone(),
            runs: drift,
        })?,
    )?;
    render_figure(&paths[4], &crate::figures::control_grid::figure(runs))?;
    eprintln!("wrote {}", paths[4].display());
    Ok(())
}

fn json_bytes<T: Serialize>(v: &T) -> CliResult<Vec<u8>> {
    let mut s =
        serde_json::to_vec_pretty(v).map_err(|e| CliError::failure(format!("JSON: {e}")))?;
    s.push(b'\n');
    Ok(s)
}

fn write_file(p: &Path, bytes: &[u8]) -> CliResult {
    let mut f = crate::output::AtomicFile::create(p, "out")?;
    f.write_all(bytes)?;
    f.commit()?;
    eprintln!("wrote {}", p.display());
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::device::control::BenchArgs;
    use clap::{CommandFactory, FromArgMatches, Parser};
    use device_host::control_bench::BenchConfig;
    use device_host::control_grid::{drift_point, grid_point, Point};

    #[derive(Parser, Debug)]
    #[command(name = "device control-bench", no_binary_name = true)]
    struct BenchOnly {
        #[command(flatten)]
        bench: BenchArgs,
    }

    /// The configuration `fricctl` builds from a command line.
    fn parsed(command: &str) -> BenchConfig {
        let argv: Vec<&str> = command
            .trim_start_matches("fricctl device control-bench")
            .trim_end_matches("--json")
            .split_whitespace()
            .collect();
        let m = crate::args::numbers_take_hyphens(BenchOnly::command())
            .try_get_matches_from(argv)
            .expect("the command parses");
        BenchOnly::from_arg_matches(&m).unwrap().bench.config()
    }

    /// The library's default bench is the one `device control-bench` runs
    /// without flags, and each grid or drift run's `command` reproduces the
    /// configuration the grid ran (the files' promise), parsed by the CLI's
    /// own flags.
    #[test]
    fn each_run_is_reproduced_by_its_command() {
        assert_eq!(parsed(""), BenchConfig::default());
        let mut points: Vec<Point> = grid(false)
            .into_iter()
            .chain(grid(true))
            .map(|(q, f, h)| grid_point(q, f, h))
            .collect();
        for rate in DRIFTS_HZ_PER_S {
            for track in [Track::None, Track::Z] {
                points.push(drift_point(rate, track, HOLD_S));
                points.push(drift_point(rate, track, QUICK_HOLD_S));
            }
        }
        assert_eq!(points.len(), 12 + 2 + 8);
        for p in points {
            assert_eq!(parsed(&p.command), p.config, "{}", p.command);
        }
    }
}
