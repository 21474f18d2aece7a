//! The DAC waveform path's bench: spectral purity against cost of the
//! board's DDS ([`board::dds`]); `fricctl bench dac` writes its CSV, table
//! and chart.
//!
//! For every sine table size `N` (16 … 65 536), reading (the table's nearest
//! entry or linear interpolation per channel, eqs. Q1–Q5, or the drive
//! phase's reference words, eqs. Q6–Q7: the board's) and table backend
//! (libm, micromath), the DDS produces 2²⁰ samples
//! ([`SAMPLES`]) of one channel at the board's sample rate ([`FS`], 500 kS/s)
//! near full scale (amplitude 2047, DC 2047.5 codes) at [`CYCLES`] cycles
//! (40.0 kHz; an odd count, so the sampling is coherent and visits 2²⁰
//! distinct phases). Measured:
//!
//! * **SFDR**, dBc: carrier power over the largest other bin of the 2²⁰-point
//!   FFT (rustfft), DC excluded;
//! * **worst error**, LSB: `max |code − (dc + amp·sin θ)|` with the ideal sine
//!   in f64 (0.5 LSB is rounding alone);
//! * **time**, ns per sample: the settled refill loop (`Dds::fill`, both
//!   channels packed for the DHR12RD register) on this host, the minimum of
//!   repeated batches after a warm-up ([`fric_analysis::bench::time_min_of`]).
//!
//! "direct" rows compute `sin` per sample with the backend instead of reading
//! a table (what the table saves). On the Cortex-M4F the relative costs
//! differ (no data cache; libm's `sinf` is ≈ 2.5 k instructions there): the
//! host numbers rank the options, the QEMU numbers in the README give the
//! board's budget.

use std::hint::black_box;

use board::dds::{phase_rad, quantise, Dds, Interp, Level, SineTable, Slew};
use fric_analysis::bench::time_min_of;
use model_core::{Libm, Math, Micromath};
use rustfft::{num_complex::Complex, FftPlanner};

use crate::{Error, Result};

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
    /// `nearest`, `linear`, `reference` or `direct`.
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
) -> Result<(DacPoint, Timer)> {
    let err = |e| Error::failure(format!("DDS: {e}"));
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
                Interp::Reference => "reference",
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

fn tables<const N: usize>(out: &mut Vec<(DacPoint, Timer)>) -> Result {
    // The tables live as long as the bench process (≤ 1 MiB each).
    let l: &'static SineTable<N> = Box::leak(Box::new(SineTable::<N>::libm()));
    let m: &'static SineTable<N> = Box::leak(Box::new(SineTable::<N>::micromath()));
    for interp in [Interp::Nearest, Interp::Linear, Interp::Reference] {
        out.push(table_point(l, interp, "libm")?);
        out.push(table_point(m, interp, "micromath")?);
    }
    Ok(())
}

/// All configurations: spectra first, then timing in `rounds` interleaved
/// rounds (`--rounds`, at least 1; a noisy host changes speed over seconds:
/// every configuration gets a batch in every round and keeps its fastest).
pub fn measure(rounds: usize) -> Result<Vec<DacPoint>> {
    if rounds == 0 {
        return Err(Error::usage("--rounds: must be at least 1 (got 0)"));
    }
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
