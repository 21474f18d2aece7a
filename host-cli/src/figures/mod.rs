//! Every figure `fricctl` draws, one module per figure family, each
//! building a [`crate::plot::Figure`] (or drawing through
//! [`crate::plot::write_chart`]) from the results its command computed:
//!
//! - [`paper`]: `fricctl figures`, the paper's Figs. 2–7 and the regime map;
//! - [`control_bench`]: `device control-bench --plot`, the loop's run;
//! - [`control_grid`]: `bench control`'s settling time against τ;
//! - [`bode`]: `device identify --plot`, the transducers' response and fit;
//! - [`device_sweep`]: `device sweep --plot`, measured against predicted μ.
//!
//! The commands compute and hand over their results; the machinery that
//! draws (panels, legends, fonts, SVG and PNG) is [`crate::plot`].

pub mod bode;
pub mod control_bench;
pub mod control_grid;
pub mod device_sweep;
pub mod paper;

pub use paper::run;
