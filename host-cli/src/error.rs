//! CLI errors: the analysis library's one-line message and class, whose
//! `code` is the exit status (2 = bad input, 1 = the computation failed).

pub use fric_analysis::error::{Error as CliError, Result as CliResult};
