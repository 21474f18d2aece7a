//! The model benchmarks: speed against accuracy of the project's μ
//! computations and slow-dynamics models, measured in one process. Each
//! module holds what a `fricctl bench …` command computes and measures —
//! the runs, the references, the timings, the error measures and the rows —
//! and the CLI keeps its flags, progress, text, files and figures.
//!
//! * [`work_precision`] — error against time for every μ computation
//!   (with [`across_lift_off`]: the flat punch and a sphere across a = 1);
//! * [`methods`] — `--method auto` against always-exact and always-fixed-step
//!   on the curve and map commands' bodies;
//! * [`stability`] — maps of where each method stops being trustworthy;
//! * [`motion`] — the slow dynamics: homogenised against resolved over scale
//!   separation and mass, the drift map, the Fig. 6 load lines;
//! * [`springs`] — a brute force over the springs of the MDR foundation, the
//!   curved profiles' independent reference;
//! * [`point`] — the measured point both work-precision modules produce;
//! * [`timing`] — the minimum time per call.
//!
//! The DAC bench measures the board's DDS, which this library does not
//! import; it lives with the host's device library (`device-host`).

pub mod across_lift_off;
pub mod methods;
pub mod motion;
pub mod point;
pub mod springs;
pub mod stability;
pub mod timing;
pub mod work_precision;

pub use timing::{time_min, time_min_of};
