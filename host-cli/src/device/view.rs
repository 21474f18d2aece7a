//! `fricctl device view`: the live page ([`device_host::view`]), its flags,
//! and the page's controls as the CLI's own commands.
//!
//! A control from the page arrives as the words of a `fricctl device`
//! command (`drive set --freq 20000 … --phase-deg 30`); they are parsed by
//! the same clap definitions, with the same parsers, and run by the same
//! functions as on the command line (`start`, `stop`, `reset-faults`,
//! `drive set`, `control`), so that the page shows the CLI's refusals word
//! for word.

use std::net::{SocketAddr, TcpListener};
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;
use std::time::Duration;

use clap::{Args, CommandFactory, FromArgMatches, Parser};
use device_host::view::{self as live, Controls};

use super::client::Client;
use super::{DeviceCmd, DriveCmd};
use crate::args::{self, Count};
use crate::error::{CliError, CliResult};

/// Flags of `fricctl device view`.
#[derive(Args, Debug, Clone)]
pub struct ViewArgs {
    /// Address of the page, HOST:PORT (port 0: a free one; the address
    /// served is printed); loopback only unless --allow-remote
    #[arg(long, value_name = "HOST:PORT", default_value = "127.0.0.1:8080")]
    pub listen: String,
    /// Serve on an address that is not loopback. There is no
    /// authentication: whoever reaches the page drives the device (use
    /// with --read-only to show it)
    #[arg(long)]
    pub allow_remote: bool,
    /// The page shows the device; its controls are refused
    #[arg(long)]
    pub read_only: bool,
    /// Also write every row to this CSV file, with the CLI's keys
    #[arg(long, value_name = "FILE")]
    pub record: Option<PathBuf>,
    /// Drive periods per streamed estimate (1 … 10⁶; default: a tenth of a
    /// second's worth at the drive frequency, at least 32)
    #[arg(long, value_parser = Count::<u32>::at_least(1))]
    pub periods: Option<u32>,
    /// Interval of the status poll (measured drive, frequency, state), ms
    #[arg(long, default_value_t = 100, value_parser = Count::<u64>::at_least(10).at_most(10_000, "10 s"))]
    pub status_ms: u64,
}

impl ViewArgs {
    /// The listening socket, bound before the device is opened: a bad,
    /// taken or non-local address is refused by name.
    ///
    /// # Errors
    /// One line naming `--listen` (or `--record` for its file).
    pub fn bind(&self) -> CliResult<TcpListener> {
        if let Some(p) = &self.record {
            crate::output::check_outputs(&[(Some(p.as_path()), "record")])?;
        }
        let addr: SocketAddr = self.listen.parse().map_err(|_| {
            CliError::usage(format!(
                "--listen: '{}' is not IP:PORT (e.g. 127.0.0.1:8080, [::1]:8080)",
                self.listen
            ))
        })?;
        if !addr.ip().is_loopback() && !self.allow_remote {
            return Err(CliError::usage(format!(
                "--listen: {addr} is not a loopback address; the page has no authentication, \
                 so serving it to other machines needs --allow-remote"
            )));
        }
        let l = TcpListener::bind(addr)
            .map_err(|e| CliError::failure(format!("--listen: {addr}: {e}")))?;
        if !addr.ip().is_loopback() {
            eprintln!(
                "warning: --listen {addr}: the page is served beyond this machine and has no \
                 authentication: whoever reaches it {}",
                if self.read_only {
                    "sees the device"
                } else {
                    "can start the drive and change it (--read-only to prevent that)"
                }
            );
        }
        Ok(l)
    }
}

/// The page's controls: `fricctl device` commands, parsed and run as the
/// CLI runs them.
struct CliControls;

/// The words of a `fricctl device` command, as clap reads them.
#[derive(Parser, Debug)]
#[command(name = "fricctl device", no_binary_name = true)]
struct Words {
    #[command(subcommand)]
    cmd: DeviceCmd,
}

impl Controls for CliControls {
    fn run(&mut self, c: &mut Client, words: &[String]) -> CliResult<String> {
        let parsed = args::numbers_take_hyphens(Words::command())
            .try_get_matches_from(words)
            .and_then(|m| Words::from_arg_matches(&m))
            .map_err(|e| CliError::usage(args::clap_message(&e)))?;
        let report = match &parsed.cmd {
            DeviceCmd::Start => super::start(c)?,
            DeviceCmd::Stop => super::stop(c)?,
            DeviceCmd::ResetFaults => super::reset_faults(c)?,
            DeviceCmd::Drive {
                cmd: cmd @ DriveCmd::Set { .. },
            } => super::drive_set(c, cmd)?,
            DeviceCmd::Control(a) => super::control::apply(c, a.request()?, a)?,
            _ => {
                return Err(CliError::usage(format!(
                    "`{}`: not one of the view's controls (start, stop, reset-faults, drive set, control)",
                    words.join(" ")
                )))
            }
        };
        Ok(report.text())
    }
}

/// `fricctl device view`: serves the page until Ctrl-C; prints the page's
/// address on stdout (`http://127.0.0.1:8080/`) once it is served.
pub fn run(c: Client, a: &ViewArgs, listener: TcpListener, stop: Arc<AtomicBool>) -> CliResult {
    let addr = listener
        .local_addr()
        .map_err(|e| CliError::failure(format!("--listen: {e}")))?;
    let cfg = live::Config {
        read_only: a.read_only,
        periods: a.periods,
        record: a.record.clone(),
        status_every: Duration::from_millis(a.status_ms),
        link: c.describe(),
        ..live::Config::default()
    };
    println!("http://{addr}/");
    eprintln!(
        "serving the view of {} on http://{addr}/{} (Ctrl-C ends it)",
        c.describe(),
        if a.read_only { ", read-only" } else { "" }
    );
    let _ = std::io::Write::flush(&mut std::io::stdout());
    live::serve(c, listener, cfg, Box::new(CliControls), stop)
}
