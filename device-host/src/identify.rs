//! The identification of the transducers (`fricctl device identify`): a
//! stepped-sine sweep of each transducer, the
//! fit of its mode ([`board::identify`], eq. 1: f_r, Q, static
//! gain, extra lag, with 95 % intervals), the result stored on the device
//! (`SetTransducers`, kept by `Reset`) and optionally in a file and a Bode
//! plot. Also the drive-mode choice of `drive set` ([`select_mode`]).
//!
//! **The sweep**, per channel, the other at zero amplitude, the normal
//! offset of the accepted drive (the preload the contact is identified
//! under), in voltage mode:
//! 1. a coarse pass of `--points` frequencies over `[--from, --to]`
//!    (default ±5 % around the drive's frequency) at most at a small
//!    amplitude: 1 % of the channel's bound B (normal: the lift-off limit;
//!    tangential: the largest amplitude), in the DAC calibration's metres;
//! 2. a fine pass of `--fine-points` over ±2 coarse steps around the
//!    coarse peak, at most at the voltage that puts the coarse pass's
//!    largest response at [`PEAK_FRACTION`] of B (never a step beyond the
//!    DAC).
//!
//! **Every point's voltage is planned** from what the sweep measured so
//! far, so that no mode up to [`Q_MAX`] is driven toward B, wherever its
//! peak hides between the points (docs/transducers.md, "A sweep that
//! cannot ring a mode up", eqs. I1–I4). For one mode of eq. 1 (any f_r,
//! gain and lag, Q ≤ Q_MAX) the response at f is bounded by the response
//! measured at any f_k:
//!
//! ```text
//! |H(f)| ≤ |H(f_k)|·G(f_k/f),   G(ρ) = 1 + ρ + (Q_MAX + ½)·|1 − ρ²|        (I1)
//! ```
//!
//! (`D(r) = √((1 − r²)² + (r/Q)²)`, `|H| = g/D`; `D(ρr) ≤ |1 − r²| +
//! r²|1 − ρ²| + ρr/Q` and `r²/D(r) ≤ Q + ½`). The point's voltage is
//!
//! ```text
//! V = min(V_cap, SAFE_FRACTION·B / min_k(1.1·|H(f_k)|·G(f_k/f)))           (I2)
//! ```
//!
//! (the first point of a channel, with nothing measured, at `V_cap/100`).
//! A point measured below [`PEAK_FRACTION`]·B is raised at its own
//! frequency to `min(V_cap, PEAK_FRACTION·B/|H(f)|)` and measured again
//! (I3; only when that at least doubles the voltage, at most
//! [`MAX_RAISES`] times; a displacement below one pickup count counts as
//! one): at one frequency the response is known, the raise safe. The
//! coarse peak is the largest response among the points the pickup
//! resolves (3 counts or more). While a point settles its measured amplitude is
//! watched: past [`ABORT_FRACTION`]·B the voltage is cut at once to put it
//! at SAFE_FRACTION·B/2 and the point settles again (I4; at most
//! [`MAX_CUTS`] times, then the sweep stops, nothing stored).
//!
//! At each frequency the mode is left `--settle-ms`, then the device's
//! measured response `X/U` (`Status.measured`) of [`WINDOWS_PER_POINT`]
//! successive lock-in windows is averaged. The coarse pass settles for five
//! envelope time constants of a Q-[`Q_MAX`] mode, `5·Q/(π f)` (the transient
//! after a step of frequency is then below e⁻⁵ = 0.7 % of the step's
//! change); the fine pass for [`FINE_SETTLE_TAUS`] time constants of the
//! coarse pass's own fit (never longer than the coarse settling), unless
//! `--settle-ms` is given. Only the fine pass is fitted: a resonance that
//! drifts (heating, preload) moves between the passes, and the fine pass,
//! four times shorter at Q ≈ 300, sees the least of it (at −20 Hz/s, 12 Hz
//! over its 0.6 s; the tracking, `drive set --track`, follows the rest).

use std::time::{Duration, Instant};

use board::device::{DriveMode, DriveSetting, TransducerModel, Transducers};
use board::identify::{self as fitid, Fit, FitConfig, Sample};
use board::protocol::{Info, Request, Response, Status};

use crate::answers::{expect, unexpected};
use crate::client::Client;
use crate::names::fault_names;
use crate::{Error, Result};

/// The fine pass's voltage puts the coarse pass's largest response at this
/// fraction of the channel's bound B (normal: the lift-off limit;
/// tangential: the largest amplitude), and a point measured below it is
/// raised to it at its own frequency (eq. I3).
pub const PEAK_FRACTION: f64 = 0.25;

/// The largest Q the sweep is planned for: the default settling time
/// (`5·Q_MAX/(π f)`) and the bound on an unseen peak (eq. I1) hold up to
/// it. Unloaded transducers reach Q 500–1500.
pub const Q_MAX: f64 = 2000.0;

/// A point's voltage is planned so that the bound on its steady response
/// (eq. I1 from every point measured so far) is at most this fraction of B.
pub const SAFE_FRACTION: f64 = 0.3;

/// A point whose measured amplitude passes this fraction of B while it
/// settles is cut at once (eq. I4), before the device's own guard (the
/// normal channel faults at the offset, B/(1 − margin)).
pub const ABORT_FRACTION: f64 = 0.8;

/// Cuts allowed per point before the sweep gives up (nothing stored).
pub const MAX_CUTS: u32 = 4;

/// Raises of one point at its own frequency at most (eq. I3).
pub const MAX_RAISES: u32 = 2;

/// A coarse point's displacement counts for the peak's place from this
/// many pickup counts on.
const RESOLVED_COUNTS: f64 = 3.0;

/// The measured |X/U| a bound starts from is taken this much larger: the
/// pickups' rounding and the settling residue (e⁻⁵ = 0.7 %) of a point.
const MEASURE_MARGIN: f64 = 1.1;

/// The fine pass's settling, in envelope time constants of the coarse fit.
pub const FINE_SETTLE_TAUS: f64 = 8.0;

/// Lock-in windows averaged per point.
pub const WINDOWS_PER_POINT: u32 = 8;

/// The transducers to identify (`--channel`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Channels {
    /// Both, normal first.
    Both,
    /// The normal one (the tangential keeps its stored model).
    Z,
    /// The tangential one (the normal keeps its stored model).
    X,
}

/// How to identify: each field is a flag of `fricctl device identify`,
/// named in errors.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IdentifyOptions {
    /// Lowest frequency of the sweep, Hz (`--from`; default: the drive's − 5 %).
    pub from: Option<f64>,
    /// Highest frequency of the sweep, Hz (`--to`; default: the drive's + 5 %).
    pub to: Option<f64>,
    /// Frequencies of the coarse pass, 6 … 1000 (`--points`).
    pub points: u32,
    /// Frequencies of the fine pass, 6 … 1000 (`--fine-points`).
    pub fine_points: u32,
    /// Settling time per frequency, ms (`--settle-ms`; default 5·Q/(π f)
    /// for Q = [`Q_MAX`]).
    pub settle_ms: Option<f64>,
    /// Which transducers (`--channel`).
    pub channels: Channels,
}

impl Default for IdentifyOptions {
    /// `fricctl device identify` without flags.
    fn default() -> Self {
        IdentifyOptions {
            from: None,
            to: None,
            points: 21,
            fine_points: 31,
            settle_ms: None,
            channels: Channels::Both,
        }
    }
}

impl IdentifyOptions {
    /// Each value within its domain, named by its flag.
    fn check(&self) -> Result<()> {
        use fric_analysis::numbers::{short, Real};
        for (v, flag, d) in [
            (self.from, "--from", Real::positive()),
            (self.to, "--to", Real::positive()),
            (
                self.settle_ms,
                "--settle-ms",
                Real::positive()
                    .at_most(10_000.0)
                    .because("ten seconds per point"),
            ),
        ] {
            if let Some(x) = v {
                d.check(x, &short(x))
                    .map_err(|r| Error::usage(format!("{flag}: {r}")))?;
            }
        }
        for (n, flag) in [
            (self.points, "--points"),
            (self.fine_points, "--fine-points"),
        ] {
            if !(6..=1000).contains(&n) {
                return Err(Error::usage(format!(
                    "{flag}: must be in [6, 1000] (got {n}; a longer sweep is a chirp's job)"
                )));
            }
        }
        Ok(())
    }
}

/// One channel's record and fit.
#[derive(Debug, Clone)]
pub struct ChannelFit {
    /// `normal` or `tangential`.
    pub name: &'static str,
    /// The fine pass's measured response, sorted by frequency.
    pub record: Vec<Sample>,
    /// Its fit (eq. 1 of `board::identify`), or why it was refused.
    pub fit: std::result::Result<Fit, fitid::FitError>,
}

/// An identification: the channels swept, in order, and what to store.
#[derive(Debug, Clone)]
pub struct Identification {
    /// Per channel swept.
    pub channels: Vec<ChannelFit>,
    /// The span swept, Hz.
    pub span_hz: (f64, f64),
    /// Wall-clock time of the sweeps, s.
    pub elapsed_s: f64,
    /// The transducers the device would hold: the fitted channels, the
    /// other one's stored model (None when a channel has neither).
    pub transducers: Option<Transducers>,
}

impl Identification {
    /// The first channel whose fit was refused, as one line.
    pub fn refused(&self) -> Option<Error> {
        self.channels.iter().find_map(|ch| {
            ch.fit.as_ref().err().map(|e| {
                Error::failure(format!(
                    "identify: the {} transducer's fit was refused: {e}; nothing stored",
                    ch.name
                ))
            })
        })
    }

    /// Stores the transducers on the device (kept by `Reset`); false when
    /// there is nothing to store.
    ///
    /// # Errors
    /// The device's refusal or a lost link.
    pub fn store(&self, c: &mut Client) -> Result<bool> {
        match self.transducers {
            Some(t) => {
                expect(c.call(Request::SetTransducers(Some(t)))?)?;
                Ok(true)
            }
            None => Ok(false),
        }
    }
}

/// Sweeps and fits each channel of `o` (module documentation). The drive
/// is stopped and put back as it was after each channel, whatever happened;
/// the device's drive mode is left in voltage mode, nothing is stored.
///
/// # Errors
/// One line: bad span, a running drive, no normal offset, a fault during
/// the sweep.
pub fn identify(c: &mut Client, o: &IdentifyOptions) -> Result<Identification> {
    identify_with_progress(c, o, &mut |_| {})
}

/// Where an identification is: `done` of `points` frequencies measured
/// (both passes of every channel), and the plan's device time at most,
/// s (each point's settling, at most the coarse pass's, plus its
/// [`WINDOWS_PER_POINT`] lock-in windows, 1 + [`MAX_RAISES`] times; the
/// cuts of eq. I4, rare, not counted).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Progress {
    /// Frequencies measured so far.
    pub done: u32,
    /// Frequencies in all.
    pub points: u32,
    /// The whole plan's device time at most, s.
    pub device_s_max: f64,
}

/// [`identify`], telling `progress` the plan before the first frequency
/// and after each one.
///
/// # Errors
/// As [`identify`].
pub fn identify_with_progress(
    c: &mut Client,
    o: &IdentifyOptions,
    progress: &mut dyn FnMut(Progress),
) -> Result<Identification> {
    o.check()?;
    let info = match expect(c.call(Request::Hello)?)? {
        Response::Info(i) => i,
        other => return Err(unexpected(other)),
    };
    let base = match expect(c.call(Request::GetDrive)?)? {
        Response::Drive { setting, .. } => setting,
        other => return Err(unexpected(other)),
    };
    let st = status(c)?;
    if st.running || st.measuring {
        return Err(Error::usage(
            "identify: the drive is running: `fricctl device stop` first (identify drives each transducer alone)",
        ));
    }
    check_faults(&st)?;
    let (from, to) = span(o, &info, base.freq_hz)?;
    if base.offset_z_m <= 0.0 {
        return Err(Error::usage(
            "identify: the drive has no normal offset: set the preload the transducers work under \
             first (`fricctl device drive set ... --offset-z M --open-loop`)",
        ));
    }
    let f_mid = 0.5 * (from + to);
    let settle = Duration::from_secs_f64(
        o.settle_ms
            .map_or(5.0 * Q_MAX / (std::f64::consts::PI * f_mid), |ms| ms * 1e-3),
    );
    let old_t = match expect(c.call(Request::GetTransducers)?)? {
        Response::Transducers(t) => t,
        other => return Err(unexpected(other)),
    };
    expect(c.call(Request::SetDriveMode(DriveMode::OpenLoop))?)?;
    let chans: &[usize] = match o.channels {
        Channels::Z => &[0],
        Channels::X => &[1],
        Channels::Both => &[0, 1],
    };
    let mut p = plan(o, &info, chans.len(), f_mid, settle);
    progress(p);
    let mut tick = || {
        p.done += 1;
        progress(p);
    };
    let mut channels = Vec::new();
    let t0 = Instant::now();
    for &ch in chans {
        let r = identify_channel(c, o, &info, &base, ch, (from, to), settle, &mut tick);
        // Stop and put the drive back whatever happened.
        let _ = c.call(Request::Stop);
        let _ = c.call(Request::SetDrive(base));
        channels.push(r?);
    }
    let transducers = merged(&channels, old_t);
    Ok(Identification {
        channels,
        span_hz: (from, to),
        elapsed_s: t0.elapsed().as_secs_f64(),
        transducers,
    })
}

/// The fitted channels' models, the other one's from `old` (None when a
/// channel has neither, or a fit was refused).
fn merged(channels: &[ChannelFit], old: Option<Transducers>) -> Option<Transducers> {
    if channels.iter().any(|c| c.fit.is_err()) {
        return None;
    }
    let model = |f: &Fit| TransducerModel {
        resonance_hz: f.model.resonance_hz as f32,
        q: f.model.q as f32,
        gain_m_per_v: f.model.gain_m_per_v as f32,
        phase_lag_rad: f.model.phase_lag_rad as f32,
    };
    let pick = |name: &str| {
        channels
            .iter()
            .find(|c| c.name == name)
            .and_then(|c| c.fit.as_ref().ok().map(model))
    };
    match (pick("normal"), pick("tangential"), old) {
        (Some(z), Some(x), _) => Some(Transducers { z, x }),
        (Some(z), None, Some(o)) => Some(Transducers { z, x: o.x }),
        (None, Some(x), Some(o)) => Some(Transducers { z: o.z, x }),
        _ => None,
    }
}

/// Switches the device to the drive mode `drive set` asks for: voltage
/// mode with `--open-loop`, else the displacement mode, which needs
/// identified transducers (one line saying to run `identify` otherwise).
///
/// # Errors
/// The refusal, as one line.
pub fn select_mode(c: &mut Client, open_loop: bool) -> Result<()> {
    let mode =
        if open_loop {
            DriveMode::OpenLoop
        } else {
            match expect(c.call(Request::GetTransducers)?)? {
                Response::Transducers(Some(_)) => DriveMode::Displacement,
                Response::Transducers(None) => return Err(Error::usage(
                    "drive set: the transducers are not identified: run `fricctl device identify` \
                     first, or pass --open-loop (voltage mode: the DAC calibration taken as the \
                     displacement)",
                )),
                other => return Err(unexpected(other)),
            }
        };
    expect(c.call(Request::SetDriveMode(mode))?)?;
    Ok(())
}

fn status(c: &mut Client) -> Result<Status> {
    match expect(c.call(Request::GetStatus)?)? {
        Response::Status(s) => Ok(s),
        other => Err(unexpected(other)),
    }
}

/// The watch on a settling point (eq. I4): channel `ch`'s measured
/// amplitude must stay at most `abort_m`.
#[derive(Debug, Clone, Copy)]
struct Watch {
    ch: usize,
    abort_m: f64,
}

impl Watch {
    /// The measured amplitude if it passed the abort level.
    fn passed(&self, s: &Status) -> Option<f64> {
        let m = s.measured?;
        let a = f64::from(if self.ch == 0 { m.amp_z_m } else { m.amp_x_m });
        (a > self.abort_m).then_some(a)
    }
}

/// Waits `d` of *device* time at drive frequency `f_hz`, counted in the
/// pickups' lock-in windows (`MeasuredDrive::windows`): a window is the
/// whole 64-sample ADC blocks spanning one drive period,
/// `⌈f_s/(64 f)⌉·64/f_s` s (`device::motion`). Under QEMU, or on a loaded
/// machine, device time runs slower than the host's clock: a wall-clock
/// wait would cut the settling short. `Err(a)` inside: the watched
/// amplitude passed its abort level at `a` m.
fn wait(
    c: &mut Client,
    d: Duration,
    f_hz: f64,
    fs: f64,
    watch: Watch,
) -> Result<std::result::Result<(), f64>> {
    let block = 64.0;
    let window_s = (fs / (block * f_hz)).ceil() * block / fs;
    let n = (d.as_secs_f64() / window_s).ceil() as u64;
    let windows = |s: &Status| s.measured.map(|m| u64::from(m.windows));
    let start = Instant::now();
    let w0 = windows(&status(c)?);
    loop {
        let s = status(c)?;
        check_faults(&s)?;
        if let Some(a) = watch.passed(&s) {
            return Ok(Err(a));
        }
        if let (Some(a), Some(b)) = (w0, windows(&s)) {
            if b.wrapping_sub(a) & 0xffff_ffff >= n {
                return Ok(Ok(()));
            }
        }
        if start.elapsed() > Duration::from_secs(30) + 20 * d {
            return Err(Error::failure(
                "identify: the device's lock-in windows do not advance (are its pickups wired?)",
            ));
        }
        let _ = c.next_telemetry(Duration::from_millis(2))?;
    }
}

/// Waits for the drive's ramps, up to `limit`.
fn wait_settled(c: &mut Client, limit: Duration) -> Result<Status> {
    let start = Instant::now();
    loop {
        let s = status(c)?;
        check_faults(&s)?;
        if s.settled {
            return Ok(s);
        }
        if start.elapsed() > limit {
            return Err(Error::failure(
                "identify: the drive did not settle within 10 s",
            ));
        }
        let _ = c.next_telemetry(Duration::from_millis(5))?;
    }
}

fn check_faults(s: &Status) -> Result<()> {
    if s.faults != 0 {
        let names = fault_names(s.faults).join(", ");
        let hint = if s.faults & board::device::faults::MEASURED_LIFTOFF != 0 {
            " (the normal transducer rang beyond the offset although every point was planned \
             below it: a Q above the sweep's Q_MAX, or more than one mode near the span? \
             identify at a larger --offset-z of the drive, or over a narrower --from/--to)"
        } else {
            ""
        };
        return Err(Error::failure(format!(
            "identify: a fault was latched ({names}){hint}; the drive is stopped, nothing stored"
        )));
    }
    Ok(())
}

/// The mean measured response of channel `ch` over [`WINDOWS_PER_POINT`]
/// new lock-in windows, m/V; `Err(a)` inside when the watched amplitude
/// passed its abort level at `a` m meanwhile.
fn response(c: &mut Client, watch: Watch) -> Result<std::result::Result<(f64, f64), f64>> {
    let mut last = None;
    let (mut re, mut im, mut n) = (0.0, 0.0, 0u32);
    let start = Instant::now();
    while n < WINDOWS_PER_POINT {
        let s = status(c)?;
        check_faults(&s)?;
        if let Some(a) = watch.passed(&s) {
            return Ok(Err(a));
        }
        if let Some(m) = s.measured {
            let r = if watch.ch == 0 {
                m.response_z_m_per_v
            } else {
                m.response_x_m_per_v
            };
            if last != Some(m.windows) {
                if let Some([a, b]) = r {
                    re += f64::from(a);
                    im += f64::from(b);
                    n += 1;
                }
                last = Some(m.windows);
            }
        }
        if start.elapsed() > Duration::from_secs(10) {
            return Err(Error::failure(
                "identify: the device reports no measured motion (are its pickups wired?)",
            ));
        }
        // Between polls the link is left to the device (an in-process
        // virtual device advances its clock only while the client waits).
        let _ = c.next_telemetry(Duration::from_millis(2))?;
    }
    Ok(Ok((re / f64::from(n), im / f64::from(n))))
}

/// The bound G of eq. I1 on the growth of one mode's response |H| from a
/// frequency f_k to f, `ρ = f_k/f`, for any f_r, gain and lag and
/// Q ≤ [`Q_MAX`].
pub fn growth_bound(rho: f64) -> f64 {
    1.0 + rho + (Q_MAX + 0.5) * (1.0 - rho * rho).abs()
}

/// The voltage of a point at `f` (eq. I2): at most `cap` V, and at most
/// what puts the bound of eq. I1, from every point `known` so far
/// (`(f_k, |H_k|)`, Hz and m/V), at [`SAFE_FRACTION`] of `bound` m; with
/// nothing known, `cap/100`.
pub fn planned_volts(f: f64, cap: f64, bound: f64, known: &[(f64, f64)]) -> f64 {
    let worst = known
        .iter()
        .map(|&(fk, hk)| MEASURE_MARGIN * hk * growth_bound(fk / f))
        .fold(f64::INFINITY, f64::min);
    if known.is_empty() {
        cap / 100.0
    } else {
        cap.min(SAFE_FRACTION * bound / worst)
    }
}

/// One point of a sweep: what it drives and where.
struct Point<'a> {
    base: &'a DriveSetting,
    ch: usize,
    f: f64,
    settle: Duration,
    bound: f64,
    fs: f64,
}

impl Point<'_> {
    /// The drive of this point at `volts` on its channel.
    fn drive(&self, volts: f64) -> DriveSetting {
        let amp =
            (volts / board::dds::DAC_VOLTS_PER_CODE * f64::from(metres_per_code(self.ch))) as f32;
        DriveSetting {
            freq_hz: self.f,
            amp_z_m: if self.ch == 0 { amp } else { 0.0 },
            amp_x_m: if self.ch == 1 { amp } else { 0.0 },
            phase_rad: 0.0,
            ..*self.base
        }
    }

    /// Drives the point at `volts` (starting the drive if `started` is
    /// false), lets it settle and measures its response, cutting the
    /// voltage whenever the measured amplitude passes [`ABORT_FRACTION`]
    /// of the bound (eq. I4). Returns the voltage used and `X/U` (m/V).
    fn measure(
        &self,
        c: &mut Client,
        mut volts: f64,
        started: &mut bool,
    ) -> Result<(f64, f64, f64)> {
        let watch = Watch {
            ch: self.ch,
            abort_m: ABORT_FRACTION * self.bound,
        };
        for _ in 0..=MAX_CUTS {
            expect(c.call(Request::SetDrive(self.drive(volts)))?)?;
            if !*started {
                expect(c.call(Request::Start)?)?;
                wait_settled(c, Duration::from_secs(10))?;
                *started = true;
            }
            let got = match wait(c, self.settle, self.f, self.fs, watch)? {
                Ok(()) => response(c, watch)?,
                Err(a) => Err(a),
            };
            match got {
                Ok((re, im)) => return Ok((volts, re, im)),
                // I4: put the amplitude seen at half the safe fraction.
                Err(a) => volts *= 0.5 * SAFE_FRACTION * self.bound / a,
            }
        }
        Err(Error::failure(format!(
            "identify: the {} response at {:.1} Hz kept passing {} % of its bound after {MAX_CUTS} \
             cuts of the voltage (a mode of Q above {Q_MAX}, or more than one mode?); the drive \
             is stopped, nothing stored",
            if self.ch == 0 { "normal" } else { "tangential" },
            self.f,
            ABORT_FRACTION * 100.0
        )))
    }
}

/// The plan of an identification of `n_chans` channels: its frequencies and
/// its device time at most.
fn plan(
    o: &IdentifyOptions,
    info: &Info,
    n_chans: usize,
    f_mid: f64,
    settle: Duration,
) -> Progress {
    let fs = info.sample_rate_hz;
    let window_s = (fs / (64.0 * f_mid)).ceil() * 64.0 / fs;
    let points = n_chans as u32 * (o.points + o.fine_points);
    // A point may be measured 1 + MAX_RAISES times (raised, eq. I3); cuts
    // (I4) are not counted.
    let settles = n_chans as u32 * (o.points + o.fine_points) * (1 + MAX_RAISES);
    Progress {
        done: 0,
        points,
        device_s_max: f64::from(settles)
            * (settle.as_secs_f64() + f64::from(WINDOWS_PER_POINT) * window_s),
    }
}

/// How a pass drives its channel.
struct Pass<'a> {
    base: &'a DriveSetting,
    ch: usize,
    /// The most voltage a point gets, V.
    cap_v: f64,
    /// The channel's bound B, m.
    bound: f64,
    settle: Duration,
    fs: f64,
}

/// Sweeps a pass over `freqs`, each point's voltage planned (eq. I2) from
/// `known` (`(f, |H|)` of every point measured so far on the channel,
/// appended to), appending `(f, re, im, volts)` to `rec`; returns the
/// largest measured displacement amplitude, m.
fn sweep(
    c: &mut Client,
    p: &Pass<'_>,
    freqs: &[f64],
    known: &mut Vec<(f64, f64)>,
    rec: &mut Vec<(f64, f64, f64, f64)>,
    tick: &mut dyn FnMut(),
) -> Result<f64> {
    let mut peak = 0.0f64;
    let mut started = false;
    // A displacement below one pickup count is not resolved: |H| is at
    // least a count over the voltage for the bound.
    let count_m = f64::from(pickup_metres_per_count(p.ch));
    for &f in freqs {
        let point = Point {
            base: p.base,
            ch: p.ch,
            f,
            settle: p.settle,
            bound: p.bound,
            fs: p.fs,
        };
        let planned = planned_volts(f, p.cap_v, p.bound, known);
        let (mut v, mut re, mut im) = point.measure(c, planned, &mut started)?;
        for raise in 0..=MAX_RAISES {
            let h = re.hypot(im).max(count_m / v);
            known.push((f, h));
            // I3: at this frequency |H| is known (an unresolved one at
            // most a count over the voltage): raise toward PEAK_FRACTION·B.
            let up = p.cap_v.min(PEAK_FRACTION * p.bound / h);
            if raise == MAX_RAISES || up < 2.0 * v {
                break;
            }
            (v, re, im) = point.measure(c, up, &mut started)?;
        }
        peak = peak.max(re.hypot(im) * v);
        rec.push((f, re, im, v));
        tick();
    }
    Ok(peak)
}

/// The board's pickup calibration of channel `ch`, m per count.
fn pickup_metres_per_count(ch: usize) -> f32 {
    let cfg = crate::virtual_device::config();
    if ch == 0 {
        cfg.pickup_z.gain
    } else {
        cfg.pickup_x.gain
    }
}

/// The board's calibration of channel `ch`, m per code (as the device's).
fn metres_per_code(ch: usize) -> f32 {
    let cfg = crate::virtual_device::config();
    if ch == 0 {
        cfg.dac_z.metres_per_code
    } else {
        cfg.dac_x.metres_per_code
    }
}

fn linspace(a: f64, b: f64, n: u32) -> Vec<f64> {
    (0..n)
        .map(|i| a + (b - a) * f64::from(i) / f64::from(n - 1))
        .collect()
}

/// The sweep's span: `--from`/`--to` as given (each refused by name
/// outside the device's range: nothing is clamped silently), by default
/// ±5 % around the drive's frequency `f` within that range.
fn span(a: &IdentifyOptions, info: &Info, f: f64) -> Result<(f64, f64)> {
    let (lo, hi) = info.freq_range_hz;
    for (flag, v) in [("--from", a.from), ("--to", a.to)] {
        if let Some(v) = v.filter(|v| !(lo..=hi).contains(v)) {
            return Err(Error::usage(format!(
                "{flag}: {} Hz is outside the device's range {lo} … {hi} Hz",
                fric_analysis::numbers::short(v)
            )));
        }
    }
    let from = a.from.unwrap_or(0.95 * f).max(lo);
    let to = a.to.unwrap_or(1.05 * f).min(hi);
    if from >= to {
        return Err(Error::usage(format!(
            "--from/--to: --from ({} Hz) must be below --to ({} Hz)",
            fric_analysis::numbers::short(from),
            fric_analysis::numbers::short(to)
        )));
    }
    Ok((from, to))
}

#[allow(clippy::too_many_arguments)]
fn identify_channel(
    c: &mut Client,
    a: &IdentifyOptions,
    info: &Info,
    base: &DriveSetting,
    ch: usize,
    (from, to): (f64, f64),
    settle: Duration,
    tick: &mut dyn FnMut(),
) -> Result<ChannelFit> {
    // The bound B: lift-off limit or largest Δu_x.
    let bound = if ch == 0 {
        f64::from(1.0 - info.liftoff_margin) * f64::from(base.offset_z_m)
    } else {
        f64::from(info.max_amp_x_m)
    };
    let volts_of = |m: f64| m / f64::from(metres_per_code(ch)) * board::dds::DAC_VOLTS_PER_CODE;
    let mut rec = Vec::new();
    let mut known = Vec::new();
    let coarse = linspace(from, to, a.points);
    let fs = info.sample_rate_hz;
    let cap0 = volts_of(0.01 * bound);
    let mut pass = Pass {
        base,
        ch,
        cap_v: cap0,
        bound,
        settle,
        fs,
    };
    let peak = sweep(c, &pass, &coarse, &mut known, &mut rec, tick)?;
    // The coarse peak among the points whose displacement the pickup
    // resolves (at least RESOLVED_COUNTS counts): below, X/U is mostly
    // rounding over a small voltage. All points if none is.
    let count_m = f64::from(pickup_metres_per_count(ch));
    let resolved = |r: &(f64, f64, f64, f64)| r.1.hypot(r.2) * r.3 >= RESOLVED_COUNTS * count_m;
    let any_resolved = rec.iter().any(resolved);
    let k = rec
        .iter()
        .enumerate()
        .filter(|(_, r)| !any_resolved || resolved(r))
        .max_by(|x, y| {
            let m = |r: &(f64, f64, f64, f64)| r.1.hypot(r.2);
            m(x.1).total_cmp(&m(y.1))
        })
        .map_or(0, |(i, _)| i);
    let step = (to - from) / f64::from(a.points - 1);
    let f_pk = rec[k].0;
    // The fine pass's cap puts the coarse peak's response at
    // PEAK_FRACTION of B (at most 100 × the coarse cap: the bound in the
    // calibration's metres, which the device accepts).
    let h_pk = rec[k].1.hypot(rec[k].2);
    pass.cap_v = if peak > 0.0 && h_pk > 0.0 {
        (PEAK_FRACTION * bound / h_pk).min(100.0 * cap0)
    } else {
        cap0
    };
    let fine = linspace(
        (f_pk - 2.0 * step).max(from),
        (f_pk + 2.0 * step).min(to),
        a.fine_points,
    );
    // The fine pass settles for FINE_SETTLE_TAUS of the coarse fit's τ̂.
    pass.settle = match (
        a.settle_ms,
        fitid::fit(&samples(&rec), None, &FitConfig::DEFAULT),
    ) {
        (None, Ok(f)) => {
            let tau = f.model.q / (std::f64::consts::PI * f.model.resonance_hz);
            Duration::from_secs_f64(FINE_SETTLE_TAUS * tau).min(settle)
        }
        _ => settle,
    };
    expect(c.call(Request::Stop)?)?;
    let mut rec = Vec::new();
    sweep(c, &pass, &fine, &mut known, &mut rec, tick)?;
    rec.sort_by(|x, y| x.0.total_cmp(&y.0));
    rec.dedup_by(|x, y| x.0 == y.0);
    let record = samples(&rec);
    let fit = fitid::fit(&record, None, &FitConfig::DEFAULT);
    Ok(ChannelFit {
        name: if ch == 0 { "normal" } else { "tangential" },
        record,
        fit,
    })
}

/// A sweep's record as the fit's samples.
fn samples(rec: &[(f64, f64, f64, f64)]) -> Vec<Sample> {
    rec.iter()
        .map(|&(f, re, im, _)| Sample {
            freq_hz: f,
            re_m_per_v: re,
            im_m_per_v: im,
        })
        .collect()
}
