//! `fricctl bench …`: speed against accuracy, measured in one process. The
//! model benches' runs and measurements live in [`fric_analysis::bench`],
//! the control bench's in `device_host`; these modules hold their flags,
//! progress, text, files and figures.
//!
//! * [`work_precision`] — error against time for every μ computation
//!   (with the flat punch and a sphere across a = 1);
//! * [`methods`] — `--method auto` against always-exact and always-fixed-step
//!   on the curve and map commands;
//! * [`stability`] — maps of where each method stops being trustworthy;
//! * [`dac`] — the DAC waveform path: spectral purity against time per sample;
//! * [`motion`] — the slow dynamics: homogenised against resolved over scale
//!   separation and mass, the drift map, the Fig. 6 load lines;
//! * [`control`] — the board's closed μ loop on resonant transducers: settling
//!   against Q, resonance and headroom, and a drifting plant with and without
//!   resonance tracking.

use clap::Subcommand;

use crate::error::CliResult;

pub mod control;
pub mod dac;
pub mod methods;
pub mod motion;
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
