//! `fricctl bench …`: speed against accuracy, measured in one process.
//!
//! * [`work_precision`] — error against time for every μ computation
//!   (with [`across_lift_off`]: the flat punch and a sphere across a = 1);
//! * [`methods`] — `--method auto` against always-exact and always-fixed-step
//!   on the curve and map commands;
//! * [`stability`] — maps of where each method stops being trustworthy;
//! * [`dac`] — the DAC waveform path: spectral purity against time per sample;
//! * [`motion`] — the slow dynamics: homogenised against resolved over scale
//!   separation and mass, the drift map, the Fig. 6 load lines;
//! * [`control`] — the board's closed μ loop on resonant transducers: settling
//!   against Q, resonance and headroom, and a drifting plant with and without
//!   resonance tracking;
//! * [`point`] — the measured point both work-precision modules produce.

use std::time::Instant;

use clap::Subcommand;

use crate::error::CliResult;

pub mod across_lift_off;
pub mod control;
pub mod dac;
pub mod methods;
pub mod motion;
pub mod point;
pub mod springs;
pub mod stability;
pub mod work_precision;

/// `fricctl bench …`.
#[derive(Subcommand, Debug, Clone)]
pub enum BenchCmd {
    /// Work-precision charts of every μ computation (CSV + SVG + PNG)
    WorkPrecision(work_precision::WpArgs),
    /// `--method auto` against always-exact and always-fixed-step on curves and maps (CSV)
    Methods(methods::MethodsArgs),
    /// Stability maps: where each method fails, and how it says so (CSV + PNG)
    Stability(stability::StabilityArgs),
    /// DAC waveform path: SFDR and worst error (LSB) against ns per sample (CSV + SVG + PNG)
    Dac(dac::DacArgs),
    /// Slow dynamics: homogenised vs resolved error against cost, drift map, Fig. 6 load lines (CSV + PNG)
    Motion(motion::MotionArgs),
    /// The closed μ loop on resonant transducers: settling vs Q, resonance, headroom; drift with and without tracking (CSV + JSON + PNG)
    Control(control::ControlArgs),
}

/// Runs a bench.
pub fn run(cmd: &BenchCmd) -> CliResult {
    match cmd {
        BenchCmd::WorkPrecision(a) => work_precision::run(a),
        BenchCmd::Methods(a) => methods::run(a),
        BenchCmd::Stability(a) => stability::run(a),
        BenchCmd::Dac(a) => dac::run(a),
        BenchCmd::Motion(a) => motion::run(a),
        BenchCmd::Control(a) => control::run(a),
    }
}

/// Minimum time per call over batches, after a warm-up (the DiffEqDevTools
/// convention: the minimum is the least noisy estimate of the cost).
pub fn time_min(f: impl FnMut()) -> f64 {
    time_min_of(5, f)
}

/// [`time_min`] over `batches` batches of ≈ 0.2 ms each.
pub fn time_min_of(batches: usize, mut f: impl FnMut()) -> f64 {
    f();
    let t0 = Instant::now();
    f();
    let once = t0.elapsed().as_secs_f64().max(1e-9);
    let k = ((2e-4 / once).ceil() as usize).clamp(1, 100_000);
    let mut best = f64::INFINITY;
    for _ in 0..batches.max(1) {
        let t = Instant::now();
        for _ in 0..k {
            f();
        }
        best = best.min(t.elapsed().as_secs_f64() / k as f64);
    }
    best
}
