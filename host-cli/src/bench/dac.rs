//! `fricctl bench dac`: the DAC waveform path — spectral purity against cost.
//!
//! [`device_host::dac_bench`] measures the board's DDS ([`board::dds`]) for
//! every sine table size, reading (nearest entry, linear interpolation,
//! or from the drive phase's reference words) and table backend, and sin per
//! sample without a table: SFDR (dBc), worst error (LSB) and host time per
//! sample. This module writes `dac.csv`, the table on stdout and the chart
//! (SVG + PNG), the board's setting marked in every panel.

use std::fmt::Write as _;

use clap::Args;
use device_host::dac_bench::{measure, DacPoint, CYCLES, FS, SAMPLES};

use crate::error::{CliError, CliResult};
use crate::plot::{prepare_out_dir, render_figure, Extras, Figure, Mark, Marker, Panel, Series};

/// Flags of `bench dac`.
#[derive(Args, Debug, Clone)]
pub struct DacArgs {
    /// Output directory (dac.csv, dac.svg, dac.png)
    #[arg(long, value_name = "DIR")]
    pub out: std::path::PathBuf,
    /// Timing rounds (every configuration is timed once per round; the fastest is kept)
    #[arg(long, default_value_t = 60, value_parser = crate::args::Count::<usize>::at_least(1).at_most(10_000, "the fastest of 10⁴ rounds is as good as it gets"))]
    pub rounds: usize,
}

/// `fricctl bench dac`.
pub fn run(a: &DacArgs) -> CliResult {
    // `a.rounds` is in 1..=10⁴ (the flag's parser).
    prepare_out_dir(&a.out)?;
    let pts = measure(a.rounds)?;
    let mut csv = String::from("table_size,interp,backend,sfdr_db,worst_lsb,ns_per_sample\n");
    for p in &pts {
        let _ = writeln!(
            csv,
            "{},{},{},{:.2},{:.4},{:.3}",
            p.table, p.interp, p.backend, p.sfdr_db, p.worst_lsb, p.ns_per_sample
        );
        println!(
            "{:>6} {:8} {:10} SFDR {:6.1} dB  worst {:7.3} LSB  {:6.2} ns/sample",
            if p.table == 0 {
                "-".to_string()
            } else {
                p.table.to_string()
            },
            p.interp,
            p.backend,
            p.sfdr_db,
            p.worst_lsb,
            p.ns_per_sample
        );
    }
    let p = a.out.join("dac.csv");
    std::fs::write(&p, csv).map_err(|e| CliError::failure(format!("{}: {e}", p.display())))?;
    for ext in ["svg", "png"] {
        let path = a.out.join(format!("dac.{ext}"));
        render_figure(&path, &chart(&pts))?;
        eprintln!("wrote {}", path.display());
    }
    eprintln!("wrote {}", p.display());
    Ok(())
}

/// The table series: (interp, backend, palette index, marker, legend text).
const TABLE_SERIES: [(&str, &str, usize, Marker, &str); 6] = [
    (
        "nearest",
        "libm",
        0,
        Marker::Square,
        "nearest entry, libm table",
    ),
    (
        "nearest",
        "micromath",
        5,
        Marker::OpenSquare,
        "nearest entry, micromath table",
    ),
    (
        "linear",
        "libm",
        1,
        Marker::Circle,
        "linear interpolation, libm table",
    ),
    (
        "linear",
        "micromath",
        4,
        Marker::Ring,
        "linear interpolation, micromath table",
    ),
    (
        "reference",
        "libm",
        2,
        Marker::Triangle,
        "from the reference words (eq. Q6), libm table",
    ),
    (
        "reference",
        "micromath",
        3,
        Marker::OpenTriangle,
        "from the reference words (eq. Q6), micromath table",
    ),
];
/// The direct rows: (backend, palette index, legend text).
const DIRECT_SERIES: [(&str, usize, &str); 2] = [
    ("libm", 6, "sin per sample, libm (no table)"),
    ("micromath", 8, "sin per sample, micromath (no table)"),
];
/// The board's setting, marked in every panel.
const CHOSEN: (usize, &str, &str) = (1024, "reference", "libm");

/// The table size axis of every panel.
const N_RANGE: (f64, f64) = (10.0, 1.0e5);

/// One panel over the table size N: a line per table series, a dashed level
/// per direct row, and the board's setting highlighted.
fn panel(
    pts: &[DacPoint],
    title: &str,
    y_label: &str,
    y: (f64, f64),
    value: fn(&DacPoint) -> f64,
) -> Panel {
    let (n_lo, n_hi) = N_RANGE;
    let mut series = Vec::new();
    for (interp, backend, color, marker, _) in TABLE_SERIES {
        series.push(Series {
            label: String::new(),
            points: pts
                .iter()
                .filter(|p| p.interp == interp && p.backend == backend)
                .map(|p| (p.table as f64, value(p)))
                .collect(),
            mark: Mark::LineMarkers(marker),
            color,
        });
    }
    for (backend, color, _) in DIRECT_SERIES {
        if let Some(p) = pts
            .iter()
            .find(|p| p.interp == "direct" && p.backend == backend)
        {
            series.push(Series {
                label: String::new(),
                points: vec![(n_lo, value(p)), (n_hi, value(p))],
                mark: Mark::Dashed,
                color,
            });
        }
    }
    series.push(Series {
        label: String::new(),
        points: pts
            .iter()
            .filter(|p| (p.table, p.interp, p.backend) == CHOSEN)
            .map(|p| (p.table as f64, value(p)))
            .collect(),
        mark: Mark::Markers(Marker::Highlight),
        color: 6,
    });
    Panel {
        title: title.to_string(),
        x_label: "sine table entries N".to_string(),
        y_label: y_label.to_string(),
        x: (n_lo, n_hi),
        y,
        series,
    }
}

/// The legend: the table series, the direct rows, the board's setting.
fn legend() -> Vec<Series> {
    let mut legend: Vec<Series> = TABLE_SERIES
        .iter()
        .map(|&(_, _, color, marker, text)| Series {
            label: text.to_string(),
            points: Vec::new(),
            mark: Mark::LineMarkers(marker),
            color,
        })
        .collect();
    legend.extend(DIRECT_SERIES.iter().map(|&(_, color, text)| Series {
        label: text.to_string(),
        points: Vec::new(),
        mark: Mark::Dashed,
        color,
    }));
    legend.push(Series {
        label: "the board's setting: libm table, N = 1024, from the reference".to_string(),
        points: Vec::new(),
        mark: Mark::Markers(Marker::Highlight),
        color: 6,
    });
    legend
}

/// Three panels over the table size N: SFDR, worst error (log) and cost.
fn chart(pts: &[DacPoint]) -> Figure {
    let max = |f: fn(&DacPoint) -> f64| pts.iter().map(f).fold(0.0, f64::max);
    let log = Extras {
        log_x: true,
        ..Extras::default()
    };
    let log_log = Extras {
        log_x: true,
        log_y: true,
        ..Extras::default()
    };
    Figure {
        panels: vec![
            (
                panel(
                    pts,
                    "Spectral purity",
                    "SFDR, dBc",
                    (0.0, max(|p| p.sfdr_db) + 10.0),
                    |p| p.sfdr_db,
                ),
                log.clone(),
            ),
            (
                panel(
                    pts,
                    "Worst error",
                    "max |code − ideal|, LSB",
                    (0.3, (max(|p| p.worst_lsb) * 2.0).max(10.0)),
                    |p| p.worst_lsb,
                ),
                log_log,
            ),
            (
                panel(
                    pts,
                    "Cost on this host",
                    "ns per sample (both channels)",
                    (0.0, max(|p| p.ns_per_sample) * 1.15),
                    |p| p.ns_per_sample,
                ),
                log,
            ),
        ],
        rows: 1,
        cols: 3,
        size: (1800, 740),
        legend: legend(),
        caption: vec![
            format!(
                "DDS of the board: 12-bit DAC at {:.0} kS/s, {:.1} kHz ({CYCLES} cycles in \
                 {SAMPLES} samples, coherent), amplitude 2047 codes, DC 2047.5 codes.",
                FS / 1e3,
                f64::from(CYCLES) * FS / SAMPLES as f64 / 1e3
            ),
            format!(
                "SFDR over the {SAMPLES}-point FFT; error against the ideal sine in f64 \
                 (0.5 LSB = rounding alone)."
            ),
        ],
    }
}
