//! `fricctl` — the model tool for dual-mode active friction control.
//!
//! Commands: `mu`, `curve`, `static`, `classify`, `map`, `tune`, `figures`. Data go to
//! stdout (JSON/CSV, full precision), messages and progress to stderr. Bad
//! input exits with status 2 and one line naming the parameter; a failed
//! computation exits with status 1.

mod args;
mod bench;
mod cmd;
mod device;
mod error;
mod eval;
mod figures;
mod output;
mod plot;
mod progress;
mod scene_args;

// The analysis lives in the library; these paths keep `crate::fit`,
// `crate::motion` and `crate::sweep_file` for the commands.
use fric_analysis::{fit, motion, sweep_file};

use std::io::Write;
use std::process::ExitCode;

use clap::error::ErrorKind;
use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};

/// Model tool for dual-mode (normal + tangential) ultrasonic friction control
/// (Popov & Li single-spring model).
#[derive(Parser, Debug)]
#[command(name = "fricctl", version, about, long_about = None, after_help = EXIT_STATUS)]
struct Cli {
    /// Replace output files that exist (--csv, --out FILE, --plot); without it such a file is refused before any work
    #[arg(long, global = true)]
    force: bool,
    #[command(subcommand)]
    cmd: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// μ at one sliding velocity
    Mu(cmd::mu::MuCmd),
    /// μ(v) over a velocity range: CSV rows v0,v_rel,mu,mu_over_mu0,method,error_bound_over_mu0
    Curve(cmd::curve::CurveCmd),
    /// Critical velocities, the exact static interval and static friction beside the paper's eqs. 18/19
    Static(cmd::statics::StaticCmd),
    /// The regime: active_control, dynamic_ratchet or actuator, with the numbers it rests on
    Classify(cmd::classify::ClassifyCmd),
    /// Regime map over phase φ and amplitude ratio kxΔux/(μ0 kz Δuz) at fixed Δuz/uz0
    Map(cmd::map::MapCmd),
    /// Inverse design: the Δuz, Δux or φ that attains a target μ, or maximises ratchet asymmetry or stall force
    Tune(cmd::tune::TuneCmd),
    /// Fit the contact (μ0, kx/kz) to a measured sweep: weighted least squares with the exact solver, 95 % intervals
    Fit(cmd::fit::FitCmd),
    /// The contact as an actuator: stall forces, no-load velocities, powers and efficiency
    LoadLine(cmd::load_line::LoadLineCmd),
    /// A body moved by the vibrated contact under a slow force: drift, stick fraction, trajectory
    Motion(cmd::motion::MotionCmd),
    /// Talk to the driver board (or QEMU, or the virtual device)
    Device {
        #[command(flatten)]
        target: device::Target,
        // Boxed: the device commands' flags are the largest of any command.
        #[command(subcommand)]
        cmd: Box<device::DeviceCmd>,
    },
    /// Benchmarks: work-precision, methods, stability, dac, motion, control
    Bench {
        #[command(subcommand)]
        cmd: bench::BenchCmd,
    },
    /// Serve the virtual device on a pseudo-terminal or TCP
    SimDevice(device::SimArgs),
    /// Regenerate the paper's Figs. 2–7 and the regime map (SVG and PNG)
    Figures {
        /// Output directory (created if missing)
        #[arg(long, value_name = "DIR")]
        out: std::path::PathBuf,
        /// Map resolution (cells per axis, 2 to 2000)
        #[arg(long, default_value_t = 160, value_parser = args::Count::<usize>::at_least(2).at_most(2000, "a finer map is not drawn"))]
        map_res: usize,
    },
}

/// The exit statuses, shown by `fricctl --help`.
const EXIT_STATUS: &str = "Exit status: 0 success; 1 the computation or the device failed, or a result is printed but doubtful (the message says why); 2 bad input (one line naming the flag); 130 interrupted (Ctrl-C).";

fn main() -> ExitCode {
    // Every numeric flag takes values that start with `-` (args module).
    let parsed = args::numbers_take_hyphens(Cli::command())
        .try_get_matches()
        .and_then(|m| Cli::from_arg_matches(&m));
    let cli = match parsed {
        Ok(c) => c,
        Err(e) => return clap_error(e),
    };
    output::set_force(cli.force);
    let mut out = std::io::stdout();
    let r = match cli.cmd {
        Command::Mu(c) => c.run(&mut out),
        Command::Curve(c) => c.run(&mut out),
        Command::Static(c) => c.run(&mut out),
        Command::Classify(c) => c.run(&mut out),
        Command::Map(c) => c.run(&mut out),
        Command::Fit(c) => c.run(&mut out),
        Command::LoadLine(c) => c.run(&mut out),
        Command::Tune(c) => c.run(&mut out),
        Command::Motion(c) => c.run(&mut out),
        Command::Figures { out, map_res } => figures::run(&out, map_res),
        Command::Device { target, cmd } => device::run(&target, &cmd),
        Command::SimDevice(a) => device::serve(&a),
        Command::Bench { cmd } => bench::run(&cmd),
    };
    let _ = out.flush();
    match r {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {}", e.msg);
            ExitCode::from(e.code)
        }
    }
}

/// Prints a clap error as one line naming the argument (help and version as usual).
fn clap_error(e: clap::Error) -> ExitCode {
    match e.kind() {
        ErrorKind::DisplayHelp
        | ErrorKind::DisplayVersion
        | ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand => {
            let _ = e.print();
            return if e.kind() == ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand {
                ExitCode::from(2)
            } else {
                ExitCode::SUCCESS
            };
        }
        _ => {}
    }
    let msg = args::clap_message(&e);
    eprintln!("error: {msg}");
    ExitCode::from(2)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every numeric flag of every command is read by the project's parsers
    /// (`args::Real`, `args::Count`): NaN, infinities and subnormal values
    /// are refused at parse time (`inf` only where a flag gives it a meaning,
    /// `--plant-load-q`), and a leading `-` reaches the parser.
    /// (clap's own `f64` parser would accept all of these.)
    #[test]
    fn every_numeric_flag_uses_the_checking_parsers() {
        fn walk(cmd: &clap::Command, path: &str, seen: &mut usize) {
            for a in cmd.get_arguments() {
                if !args::is_numeric(a) {
                    continue;
                }
                *seen += 1;
                assert!(a.is_allow_hyphen_values_set(), "{path} --{:?}", a.get_id());
                // The flag alone in a command of its own (its relations to
                // other flags dropped), as `--name value`.
                let alone = a
                    .clone()
                    .required(false)
                    .requires(clap::builder::Resettable::<clap::Id>::Reset)
                    .conflicts_with(clap::builder::Resettable::<clap::Id>::Reset)
                    .required_unless_present(clap::builder::Resettable::<clap::Id>::Reset)
                    .global(false);
                let long = a.get_long().unwrap_or_default().to_string();
                for bad in ["nan", "-inf", "1e-320", "-1e308", "1e308"] {
                    let r = clap::Command::new("t")
                        .no_binary_name(true)
                        .arg(alone.clone())
                        .try_get_matches_from([format!("--{long}"), bad.to_string()]);
                    let kind = r.err().map(|e| e.kind());
                    assert_eq!(
                        kind,
                        Some(clap::error::ErrorKind::ValueValidation),
                        "{path} --{long} accepts {bad}"
                    );
                }
            }
            for sub in cmd.get_subcommands() {
                walk(sub, &format!("{path} {}", sub.get_name()), seen);
            }
        }
        let mut cmd = args::numbers_take_hyphens(Cli::command());
        cmd.build();
        let mut seen = 0;
        walk(&cmd, "fricctl", &mut seen);
        assert!(seen > 150, "{seen} numeric flags");
    }
}
