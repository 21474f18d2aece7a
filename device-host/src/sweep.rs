//! One point of a drive sweep (`fricctl device sweep`): the drive set with
//! one parameter changed, the ramps and a number of settling periods waited
//! for in device time, μ measured over a number of periods and the
//! device's model asked for its prediction. The sweep file, its resumption
//! and the plot are the CLI's.

use std::time::{Duration, Instant};

use board::device::{Contact, DriveSetting};
use board::estimator::Estimate;
use board::protocol::{Prediction, Request, Response};
use fric_analysis::sweep_file::SweepRow;

use crate::answers::{expect, unexpected};
use crate::client::Client;
use crate::{Error, Result};

/// The drive parameter a sweep steps.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum SweepParam {
    /// Phase φ, degrees.
    PhaseDeg,
    /// Normal amplitude Δu_z, m.
    AmpZ,
    /// Tangential amplitude Δu_x, m.
    AmpX,
    /// Normal offset u_z0, m.
    OffsetZ,
    /// Frequency, Hz.
    Freq,
}

impl SweepParam {
    /// The name (as in `--param` and the file's `param` column).
    pub fn name(self) -> &'static str {
        match self {
            SweepParam::PhaseDeg => "phase-deg",
            SweepParam::AmpZ => "amp-z",
            SweepParam::AmpX => "amp-x",
            SweepParam::OffsetZ => "offset-z",
            SweepParam::Freq => "freq",
        }
    }

    /// The unit of the value.
    pub fn unit(self) -> &'static str {
        match self {
            SweepParam::PhaseDeg => "°",
            SweepParam::Freq => "Hz",
            _ => "m",
        }
    }

    /// `d` with this parameter set to `x`.
    pub fn apply(self, mut d: DriveSetting, x: f64) -> DriveSetting {
        match self {
            SweepParam::PhaseDeg => d.phase_rad = x.to_radians() as f32,
            SweepParam::AmpZ => d.amp_z_m = x as f32,
            SweepParam::AmpX => d.amp_x_m = x as f32,
            SweepParam::OffsetZ => d.offset_z_m = x as f32,
            SweepParam::Freq => d.freq_hz = x,
        }
        d
    }
}

/// Most points of one sweep: each is a measurement of at least one drive
/// period plus the device's ramps, so 10⁴ points are already hours of a
/// board's time.
pub const MAX_POINTS: usize = 10_000;

/// What one point measured.
#[derive(Debug, Clone, Copy)]
pub struct PointResult {
    /// The drive the device accepted.
    pub setting: DriveSetting,
    /// The frequency it produces, Hz.
    pub freq_hz: f64,
    /// The phase it produces, degrees.
    pub phi_deg: f64,
    /// The measured estimate.
    pub estimate: Estimate,
    /// The device's model at the point and `v0`.
    pub prediction: Prediction,
}

/// How a point is measured: each field is a flag of `fricctl device
/// sweep`, named in errors.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PointOptions {
    /// Periods waited for after the ramps, in device time (`--settle-periods`).
    pub settle_periods: u32,
    /// Periods measured (`--periods`).
    pub periods: u32,
    /// Velocity of the prediction, m/s (`--v0`).
    pub v0: f64,
}

/// Sets `param` of `base` to `x`, waits and measures (module
/// documentation). A refused value names `--{param}`.
///
/// # Errors
/// The device's refusal, a wait that does not end, a lost link.
pub fn measure_point(
    c: &mut Client,
    base: DriveSetting,
    param: SweepParam,
    x: f64,
    o: &PointOptions,
) -> Result<PointResult> {
    let (setting, freq_hz, phi_deg) = set_point(c, base, param, x)?;
    let (estimate, prediction) = measure_here(c, freq_hz, o)?;
    Ok(PointResult {
        setting,
        freq_hz,
        phi_deg,
        estimate,
        prediction,
    })
}

/// Sets `param` of `base` to `x`: the accepted drive, the frequency (Hz)
/// and the phase (°) it produces.
///
/// # Errors
/// The device's refusal (naming `--{param}`), a lost link.
pub fn set_point(
    c: &mut Client,
    base: DriveSetting,
    param: SweepParam,
    x: f64,
) -> Result<(DriveSetting, f64, f64)> {
    drive_of(ask(c, Request::SetDrive(param.apply(base, x)))?)
}

/// Waits for the ramps and the settling periods, measures, and asks for the
/// prediction, at the drive frequency `freq_hz`.
///
/// # Errors
/// The device's refusal, a wait that does not end, a lost link.
pub fn measure_here(
    c: &mut Client,
    freq_hz: f64,
    o: &PointOptions,
) -> Result<(Estimate, Prediction)> {
    wait_status(c, Duration::from_secs(60), "settling of the ramps", |s| {
        s.settled
    })?;
    if o.settle_periods > 0 {
        // S periods of *device* time: a measurement whose result is
        // dropped (a host clock would be wrong for a device that runs
        // slower than real time, like a virtual one on a busy machine).
        ask(
            c,
            Request::Measure {
                periods: o.settle_periods,
            },
        )
        .map_err(|e| Error {
            code: e.code,
            msg: e.msg.replace("--periods", "--settle-periods"),
        })?;
        let limit = Duration::from_secs_f64(60.0 + 10.0 * f64::from(o.settle_periods) / freq_hz);
        wait_status(c, limit, "the end of the settling periods", |s| {
            !s.measuring
        })?;
    }
    ask(c, Request::Measure { periods: o.periods })?;
    let limit = Duration::from_secs_f64(60.0 + 10.0 * f64::from(o.periods) / freq_hz);
    wait_status(c, limit, "the end of the measurement", |s| !s.measuring)?;
    let Response::Estimate(estimate) = ask(c, Request::GetEstimate)? else {
        return Err(Error::failure("the device did not answer with an estimate"));
    };
    let Response::Prediction { prediction, .. } = ask(c, Request::Predict { v0: o.v0 as f32 })?
    else {
        return Err(Error::failure(
            "the device did not answer with a prediction",
        ));
    };
    Ok((estimate, prediction))
}

/// What a request answered, or a one-line error.
pub fn ask(c: &mut Client, req: Request) -> Result<Response> {
    expect(c.call(req)?)
}

/// Polls the status until `done` or `limit` elapses.
pub fn wait_status(
    c: &mut Client,
    limit: Duration,
    what: &str,
    done: impl Fn(&board::protocol::Status) -> bool,
) -> Result<board::protocol::Status> {
    let start = Instant::now();
    loop {
        if let Response::Status(s) = ask(c, Request::GetStatus)? {
            if done(&s) {
                return Ok(s);
            }
        }
        if start.elapsed() > limit {
            return Err(Error::failure(format!(
                "{what} did not happen within {} s",
                limit.as_secs()
            )));
        }
        let _ = c.next_telemetry(Duration::from_millis(20))?;
    }
}

/// `(setting, produced frequency Hz, produced phase °)` of a `Drive` answer.
pub fn drive_of(r: Response) -> Result<(DriveSetting, f64, f64)> {
    match r {
        Response::Drive { setting, applied } => Ok((
            setting,
            applied.achieved.freq_hz,
            applied.phase_rad.to_degrees(),
        )),
        other => Err(unexpected(other)),
    }
}

/// The non-swept drive columns of a row, to compare with the device's.
pub fn fixed_columns(p: SweepParam, r: &SweepRow) -> Vec<(&'static str, f64)> {
    let mut v = vec![
        ("freq_hz", r.freq_hz),
        ("amp_z", r.amp_z),
        ("amp_x", r.amp_x),
        ("offset_z", r.offset_z),
        ("phi_deg", r.phi_deg),
    ];
    let skip = match p {
        SweepParam::Freq => "freq_hz",
        SweepParam::AmpZ => "amp_z",
        SweepParam::AmpX => "amp_x",
        SweepParam::OffsetZ => "offset_z",
        SweepParam::PhaseDeg => "phi_deg",
    };
    v.retain(|(n, _)| *n != skip);
    v
}

/// A row with the drive (as it runs: frequency Hz and phase ° produced)
/// and the device's contact filled in, the results empty.
pub fn row(
    param: SweepParam,
    x: f64,
    d: &DriveSetting,
    (freq_hz, phi_deg): (f64, f64),
    k: Contact,
    v0: f64,
) -> SweepRow {
    SweepRow {
        param: param.name().to_string(),
        value: x,
        freq_hz,
        amp_z: f64::from(d.amp_z_m),
        amp_x: f64::from(d.amp_x_m),
        offset_z: f64::from(d.offset_z_m),
        phi_deg,
        v0,
        model_mu0: f64::from(k.mu0),
        model_kz: f64::from(k.kz),
        model_kx: f64::from(k.kx),
        measured_mu: f64::NAN,
        std_error: 0.0,
        predicted_mu: f64::NAN,
        valid: false,
        reasons: String::new(),
    }
}

/// `r` with a point's estimate and prediction.
pub fn measured(mut r: SweepRow, e: &Estimate, p: &Prediction) -> SweepRow {
    r.measured_mu = f64::from(e.mu);
    r.std_error = f64::from(e.std_error);
    r.predicted_mu = f64::from(p.mu);
    r.valid = e.valid();
    r.reasons = crate::names::reason_names(e.reasons).join(";");
    r
}

/// A whole sweep of a running drive: `param` over `values`, each point set,
/// settled and measured ([`set_point`], [`measure_here`]). The drive is left
/// at the last point (callers put it back: [`crate::state::restoring`]).
///
/// # Errors
/// A stopped drive, a point the device refuses (naming `--{param}`), a wait
/// that does not end, a lost link.
pub fn run(
    c: &mut Client,
    param: SweepParam,
    values: &[f64],
    o: &PointOptions,
) -> Result<Vec<SweepRow>> {
    let (base, _, _) = drive_of(ask(c, Request::GetDrive)?)?;
    let Response::Contact(contact) = ask(c, Request::GetContact)? else {
        return Err(Error::failure("the device did not report its contact"));
    };
    let Response::Status(st) = ask(c, Request::GetStatus)? else {
        return Err(Error::failure("the device did not report its status"));
    };
    if !st.running {
        return Err(Error::usage(
            "the drive is stopped: start it first (a sweep measures a running drive)",
        ));
    }
    let mut rows = Vec::with_capacity(values.len());
    for &x in values {
        let (setting, freq, phi) = set_point(c, base, param, x)?;
        let (e, p) = measure_here(c, freq, o)?;
        rows.push(measured(
            row(param, x, &setting, (freq, phi), contact, o.v0),
            &e,
            &p,
        ));
    }
    Ok(rows)
}
