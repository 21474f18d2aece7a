//! `fricctl` — the model tool for dual-mode active friction control.
//!
//! Commands: `mu`, `curve`, `static`, `classify`, `map`, `figures`. Data go to
//! stdout (JSON/CSV, full precision), messages and progress to stderr. Bad
//! input exits with status 2 and one line naming the parameter; a failed
//! computation exits with status 1.

mod bench;
mod commands;
mod compute;
mod device;
mod error;
mod figures;
mod fit;
mod map;
mod plot;
mod scene_args;
mod sweep_file;

use std::process::ExitCode;

use clap::error::{ContextKind, ContextValue, ErrorKind};
use clap::{Parser, Subcommand};

use crate::scene_args::SceneArgs;

/// Model tool for dual-mode (normal + tangential) ultrasonic friction control
/// (Popov & Li single-spring model).
#[derive(Parser, Debug)]
#[command(name = "fricctl", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    cmd: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// μ at one sliding velocity
    Mu {
        #[command(flatten)]
        scene: SceneArgs,
        /// Sliding velocity v0, m/s (units of ωW0 for a dimensionless scene)
        #[arg(
            long,
            allow_hyphen_values = true,
            conflicts_with = "v_rel",
            required_unless_present = "v_rel"
        )]
        v0: Option<f64>,
        /// Velocity relative to v_c: v0 = X·v_c (forward v_c for X > 0, backward for X < 0)
        #[arg(long, allow_hyphen_values = true, value_name = "X")]
        v_rel: Option<f64>,
        #[command(flatten)]
        how: compute::MethodArgs,
        /// JSON output
        #[arg(long)]
        json: bool,
    },
    /// μ(v) over a velocity range: CSV rows v0,v_rel,mu,mu_over_mu0
    Curve {
        #[command(flatten)]
        scene: SceneArgs,
        /// Lowest velocity, m/s
        #[arg(long, allow_hyphen_values = true, requires = "v_max", conflicts_with_all = ["v_rel_min", "v_rel_max"])]
        v_min: Option<f64>,
        /// Highest velocity, m/s
        #[arg(long, allow_hyphen_values = true, requires = "v_min")]
        v_max: Option<f64>,
        /// Lowest velocity relative to v_c (negative: relative to the backward v_c)
        #[arg(long, allow_hyphen_values = true, requires = "v_rel_max")]
        v_rel_min: Option<f64>,
        /// Highest velocity relative to v_c
        #[arg(long, allow_hyphen_values = true, requires = "v_rel_min")]
        v_rel_max: Option<f64>,
        /// Number of velocities (≥ 2)
        #[arg(long)]
        points: usize,
        #[command(flatten)]
        how: compute::MethodArgs,
        /// Write the CSV to FILE instead of stdout
        #[arg(long, value_name = "FILE")]
        csv: Option<std::path::PathBuf>,
        /// Plot μ/μ0 against v to FILE.svg or FILE.png
        #[arg(long, value_name = "FILE")]
        plot: Option<std::path::PathBuf>,
    },
    /// Critical velocities, the exact static interval and static friction beside the paper's eqs. 18/19
    Static {
        #[command(flatten)]
        scene: SceneArgs,
        /// JSON output
        #[arg(long)]
        json: bool,
    },
    /// The regime: active_control, dynamic_ratchet or actuator, with the numbers it rests on
    Classify {
        #[command(flatten)]
        scene: SceneArgs,
        /// JSON output
        #[arg(long)]
        json: bool,
    },
    /// Regime map over phase φ and amplitude ratio kxΔux/(μ0 kz Δuz) at fixed Δuz/uz0
    Map(map::MapArgs),
    /// Talk to the driver board (or QEMU, or the virtual device)
    Device {
        #[command(flatten)]
        target: device::Target,
        #[command(subcommand)]
        cmd: device::DeviceCmd,
    },
    /// Speed against accuracy: work-precision charts
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
        /// Map resolution (cells per axis)
        #[arg(long, default_value_t = 160)]
        map_res: usize,
    },
}

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(c) => c,
        Err(e) => return clap_error(e),
    };
    let r = match cli.cmd {
        Command::Mu {
            scene,
            v0,
            v_rel,
            how,
            json,
        } => commands::mu(&scene, v0, v_rel, &how, json),
        Command::Curve {
            scene,
            v_min,
            v_max,
            v_rel_min,
            v_rel_max,
            points,
            how,
            csv,
            plot,
        } => commands::curve(commands::CurveArgs {
            scene,
            v_range: v_min.zip(v_max),
            v_rel_range: v_rel_min.zip(v_rel_max),
            points,
            how,
            csv,
            plot,
        }),
        Command::Static { scene, json } => commands::statics(&scene, json),
        Command::Classify { scene, json } => commands::classify(&scene, json),
        Command::Map(a) => map::run(&a),
        Command::Figures { out, map_res } => figures::run(&out, map_res),
        Command::Device { target, cmd } => device::run(&target, &cmd),
        Command::SimDevice(a) => device::serve(&a),
        Command::Bench { cmd } => bench::run(&cmd),
    };
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
    let ctx = |k: ContextKind| match e.get(k) {
        Some(ContextValue::String(s)) => Some(s.clone()),
        Some(ContextValue::Strings(v)) => Some(v.join(", ")),
        _ => None,
    };
    let arg = ctx(ContextKind::InvalidArg)
        .map(|a| a.split_whitespace().next().unwrap_or("").to_string())
        .unwrap_or_default();
    let msg = match e.kind() {
        ErrorKind::InvalidValue | ErrorKind::ValueValidation => {
            let val = ctx(ContextKind::InvalidValue).unwrap_or_default();
            let reason = e
                .source()
                .map(|s| s.to_string())
                .unwrap_or_else(|| "invalid value".to_string());
            format!("{arg}: invalid value '{val}': {reason}")
        }
        ErrorKind::MissingRequiredArgument => {
            let what = ctx(ContextKind::InvalidArg).unwrap_or_default();
            format!(
                "{}: missing",
                what.split_whitespace().next().unwrap_or("argument")
            )
        }
        ErrorKind::ArgumentConflict => {
            let other = ctx(ContextKind::PriorArg).unwrap_or_default();
            format!(
                "{arg}: cannot be used with {}",
                other.split_whitespace().next().unwrap_or("")
            )
        }
        ErrorKind::UnknownArgument => format!(
            "{}: unknown option",
            ctx(ContextKind::InvalidArg).unwrap_or_default()
        ),
        _ => {
            // Fall back to clap's first line.
            let s = e.render().to_string();
            s.lines()
                .next()
                .unwrap_or("invalid arguments")
                .trim_start_matches("error: ")
                .to_string()
        }
    };
    eprintln!("error: {msg}");
    ExitCode::from(2)
}

use std::error::Error as _;
