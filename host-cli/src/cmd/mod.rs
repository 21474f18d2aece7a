//! One module per model command, each owning its arguments (a clap `Args`
//! struct) and its `run(self, out)`: data go to `out` (stdout), messages and
//! progress to stderr.

pub mod classify;
pub mod curve;
pub mod fit;
pub mod load_line;
pub mod map;
pub mod motion;
pub mod mu;
pub mod statics;
pub mod tune;
