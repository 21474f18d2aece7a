//! `fricctl bench dac` (placeholder replaced below).
use clap::Args;

use crate::error::CliResult;

/// Flags of `bench dac`.
#[derive(Args, Debug, Clone)]
pub struct DacArgs {
    /// Output directory
    #[arg(long, value_name = "DIR")]
    pub out: std::path::PathBuf,
}

/// `fricctl bench dac`.
pub fn run(_a: &DacArgs) -> CliResult {
    Ok(())
}
