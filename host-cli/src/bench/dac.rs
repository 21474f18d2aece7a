//! `fricctl bench dac`: the DAC waveform path — spectral purity against cost.
//!
//! For every sine table size `N` (16 … 65 536), interpolation (nearest entry,
//! linear) and table backend (libm, micromath), the board's DDS
//! ([`board::dds`]) produces 2¹⁶ samples of one channel at the board's
//! sample rate (500 kS/s) near full scale (amplitude 2047, DC 2047.5 codes)
//! at 83 885 cycles per 2²⁰ samples (40.0 kHz; an odd count, so the sampling
//! is coherent and visits 2²⁰ distinct phases). Measured:
//!
//! * **SFDR**, dBc: carrier power over the largest other bin of the 2²⁰-point
//!   FFT (rustfft), DC excluded;
//! * **worst error**, LSB: `max |code − (dc + amp·sin θ)|` with the ideal sine
//!   in f64 (0.5 LSB is rounding alone);
//! * **time**, ns per sample: the settled refill loop (`Dds::fill`, both
//!   channels packed for the DHR12RD register) on this host, the minimum of
//!   repeated batches after a warm-up.
//!
//! "direct" rows compute `sin` per sample with the backend instead of reading
//! a table (what the table saves). On the Cortex-M4F the relative costs
//! differ (no data cache; libm's `sinf` is ≈ 2.5 k instructions there,
//! README): the host numbers rank the options, the QEMU numbers in the README
//! give the board's budget.

use std::fmt::Write as _;
use std::hint::black_box;

use board::dds::{phase_rad, quantise, Dds, Interp, Level, SineTable, Slew};
use clap::Args;
use fric_analysis::bench::time_min_of;
use model_core::{Libm, Math, Micromath};
use rustfft::{num_complex::Complex, FftPlanner};

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

/// Samples per measurement (FFT length). 2²⁰: the phases then lie on a grid
/// 16 times finer than the largest table, so every table's interpolation
/// error is sampled (with 2¹⁶ samples a 65 536-entry table would be read
/// only at its entries and look perfect).
pub const SAMPLES: usize = 1 << 20;
/// Cycles in [`SAMPLES`] (odd: coherent, every phase distinct; 39.999 kHz).
pub const CYCLES: u32 = 83_885;
/// The board's DAC sample rate, S/s.
pub const FS: f64 = 500_000.0;
const AMP: f32 = 2047.0;
const DC: f32 = 2047.5;

/// One measured configuration.
#[derive(Debug, Clone)]
pub struct DacPoint {
    /// Table entries (0 for direct computation).
    pub table: usize,
    /// `nearest`, `linear` or `direct`.
    pub interp: &'static str,
    /// `libm` or `micromath`.
    pub backend: &'static str,
    /// SFDR, dBc.
    pub sfdr_db: f64,
    /// Worst |code − ideal|, LSB.
    pub worst_lsb: f64,
    /// Host time per sample (both channels), ns.
    pub ns_per_sample: f64,
}

/// SFDR (dBc) and worst error (LSB) of a code sequence whose sample `k` has
/// drive phase word `start + k·tw` (near-full-scale sine, [`CYCLES`] cycles).
pub fn spectral(codes: &[u16], tw: u32, start: u32) -> (f64, f64) {
    let mut worst = 0.0f64;
    let mut buf: Vec<Complex<f64>> = Vec::with_capacity(codes.len());
    let mut acc = start;
    for &c in codes {
        let ideal = f64::from(DC) + f64::from(AMP) * phase_rad(acc).sin();
        worst = worst.max((f64::from(c) - ideal).abs());
        buf.push(Complex::new(f64::from(c), 0.0));
        acc = acc.wrapping_add(tw);
    }
    let n = buf.len();
    FftPlanner::new().plan_fft_forward(n).process(&mut buf);
    let p: Vec<f64> = buf[..n / 2].iter().map(|c| c.norm_sqr()).collect();
    let k = CYCLES as usize;
    let spur = p
        .iter()
        .enumerate()
        .filter(|(i, _)| *i != 0 && *i != k)
        .map(|(_, v)| *v)
        .fold(f64::MIN_POSITIVE, f64::max);
    (10.0 * (p[k] / spur).log10(), worst)
}

fn slew() -> Slew {
    Slew {
        amp_per_sample: 1e9,
        dc_per_sample: 1e9,
        phase_per_sample: u32::MAX / 2,
    }
}

/// A configuration whose timing loop is still to run.
type Timer = Box<dyn FnMut()>;

fn table_point<const N: usize>(
    t: &'static SineTable<N>,
    interp: Interp,
    backend: &'static str,
) -> CliResult<(DacPoint, Timer)> {
    let err = |e| CliError::failure(format!("DDS: {e}"));
    let mut d = Dds::new(t, FS, slew()).map_err(err)?;
    d.set_interp(interp);
    let a = d
        .set_frequency(f64::from(CYCLES) * FS / SAMPLES as f64)
        .map_err(err)?;
    let lvl = Level { amp: AMP, dc: DC };
    d.set_level(0, lvl).map_err(err)?;
    d.set_level(1, lvl).map_err(err)?;
    // The first sample is still silent (it applies the levels); the next
    // SAMPLES start at phase word tw.
    let mut words = vec![0u32; SAMPLES + 1];
    d.fill(&mut words);
    let codes: Vec<u16> = words[1..].iter().map(|w| (w & 0x0FFF) as u16).collect();
    let (sfdr, worst) = spectral(&codes, a.tuning_word, a.tuning_word);
    let mut buf = vec![0u32; BATCH];
    let timer: Timer = Box::new(move || d.fill(black_box(&mut buf)));
    Ok((
        DacPoint {
            table: N,
            interp: match interp {
                Interp::Nearest => "nearest",
                Interp::Linear => "linear",
            },
            backend,
            sfdr_db: sfdr,
            worst_lsb: worst,
            ns_per_sample: f64::NAN,
        },
        timer,
    ))
}

/// Samples per timed call.
const BATCH: usize = 1024;

fn direct_point<M: Math<f32> + 'static>() -> (DacPoint, Timer) {
    let tw = (u64::from(CYCLES) << 12) as u32;
    let code = |acc: u32| {
        let x = (acc as i32) as f32 * (core::f32::consts::PI / 2_147_483_648.0);
        quantise(DC + AMP * M::sin_cos(x).0)
    };
    let mut codes = Vec::with_capacity(SAMPLES);
    let mut acc = 0u32;
    for _ in 0..SAMPLES {
        codes.push(code(acc));
        acc = acc.wrapping_add(tw);
    }
    let (sfdr, worst) = spectral(&codes, tw, 0);
    let mut buf = vec![0u32; BATCH];
    let mut acc = 0u32;
    let timer: Timer = Box::new(move || {
        for w in buf.iter_mut() {
            let a = code(acc);
            let b = code(acc.wrapping_add(0x4000_0000));
            *w = u32::from(a) | (u32::from(b) << 16);
            acc = acc.wrapping_add(tw);
        }
        black_box(&buf);
    });
    (
        DacPoint {
            table: 0,
            interp: "direct",
            backend: M::NAME,
            sfdr_db: sfdr,
            worst_lsb: worst,
            ns_per_sample: f64::NAN,
        },
        timer,
    )
}

fn tables<const N: usize>(out: &mut Vec<(DacPoint, Timer)>) -> CliResult {
    // The tables live as long as the bench process (≤ 1 MiB each).
    let l: &'static SineTable<N> = Box::leak(Box::new(SineTable::<N>::libm()));
    let m: &'static SineTable<N> = Box::leak(Box::new(SineTable::<N>::micromath()));
    for interp in [Interp::Nearest, Interp::Linear] {
        out.push(table_point(l, interp, "libm")?);
        out.push(table_point(m, interp, "micromath")?);
    }
    Ok(())
}

/// All configurations: spectra first, then timing in interleaved rounds (a
/// noisy host changes speed over seconds; every configuration gets a batch in
/// every round and keeps its fastest).
pub fn measure(rounds: usize) -> CliResult<Vec<DacPoint>> {
    let mut out = Vec::new();
    tables::<16>(&mut out)?;
    tables::<64>(&mut out)?;
    tables::<256>(&mut out)?;
    tables::<1024>(&mut out)?;
    tables::<4096>(&mut out)?;
    tables::<16384>(&mut out)?;
    tables::<65536>(&mut out)?;
    out.push(direct_point::<Libm>());
    out.push(direct_point::<Micromath>());
    for _ in 0..rounds.max(1) {
        for (p, timer) in out.iter_mut() {
            let t = time_min_of(1, &mut *timer) * 1e9 / BATCH as f64;
            p.ns_per_sample = if p.ns_per_sample.is_nan() {
                t
            } else {
                p.ns_per_sample.min(t)
            };
        }
    }
    Ok(out.into_iter().map(|(p, _)| p).collect())
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
const TABLE_SERIES: [(&str, &str, usize, Marker, &str); 4] = [
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
];
/// The direct rows: (backend, palette index, legend text).
const DIRECT_SERIES: [(&str, usize, &str); 2] = [
    ("libm", 6, "sin per sample, libm (no table)"),
    ("micromath", 8, "sin per sample, micromath (no table)"),
];
/// The board's setting, marked in every panel.
const CHOSEN: (usize, &str, &str) = (1024, "linear", "libm");

/// Three panels over the table size N: SFDR, worst error (log) and cost.
fn chart(pts: &[DacPoint]) -> Figure {
    let (n_lo, n_hi) = (10.0, 1.0e5);
    let panel = |title: &str, y_label: &str, y: (f64, f64), value: fn(&DacPoint) -> f64| {
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
    };
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
        label: "the board's setting: libm table, N = 1024, linear".to_string(),
        points: Vec::new(),
        mark: Mark::Markers(Marker::Highlight),
        color: 6,
    });
    Figure {
        panels: vec![
            (
                panel(
                    "Spectral purity",
                    "SFDR, dBc",
                    (0.0, max(|p| p.sfdr_db) + 10.0),
                    |p| p.sfdr_db,
                ),
                log.clone(),
            ),
            (
                panel(
                    "Worst error",
                    "max |code − ideal|, LSB",
                    (0.3, (max(|p| p.worst_lsb) * 2.0).max(10.0)),
                    |p| p.worst_lsb,
                ),
                log_log,
            ),
            (
                panel(
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
        legend,
        caption: vec![format!(
            "DDS of the board: 12-bit DAC at {:.0} kS/s, {:.1} kHz ({CYCLES} cycles in {SAMPLES} \
             samples, coherent), amplitude 2047 codes; SFDR over the {SAMPLES}-point FFT; \
             error against the ideal sine in f64 (0.5 LSB = rounding alone).",
            FS / 1e3,
            f64::from(CYCLES) * FS / SAMPLES as f64 / 1e3
        )],
    }
}
