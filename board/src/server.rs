//! The device side of the protocol: decodes request frames, runs them on a
//! [`Device`], encodes the responses and the telemetry. The firmware feeds it
//! the bytes from USART2; the virtual device feeds it the bytes of a
//! pseudo-terminal — the same code.
//!
//! **Sessions.** `Measure` is idempotent per `seq`: the server remembers the
//! last accepted `Measure` (seq, periods) and answers a retry with the same
//! seq and periods `Ok` again without starting anything; a refused one
//! changed nothing and its retry is judged again. The
//! stream of estimates ends on `Stream{on: false}`, on `Reset`, or when its
//! next measurement is refused, and every end is announced by one
//! `StreamStopped` telemetry frame. `Reset` ends every session a crashed host
//! may have left behind (and switches the closed loop off, by stopping the
//! drive).
//!
//! **Closed loop.** `SetControl` is checked and planned here (the model's
//! inverse search runs on a snapshot, with the device released); the loop
//! itself runs in the device on every finished estimate, and each poll sends
//! the latest update as `Control` telemetry.

use crate::control;
use crate::device::{self, Device};
use crate::protocol::{
    decode, encode, Body, ControlSetting, Deframed, Deframer, Frame, Info, Request, Response,
    StreamEnd, Telemetry, WireError, MAX_FRAME, PROTOCOL_VERSION,
};

/// Access to the device for the server: on the host a plain `&mut Device`;
/// in the firmware a critical section around each call (the DMA handlers
/// masked: a closure longer than a half-buffer makes them late). So every
/// closure here is short: the model's work runs on copies with the device
/// released — `Predict` and `SetControl` copy the scene's parameters and
/// form the scene outside, `GetEstimate` and the stream copy the estimator
/// (`firmware/src/bin/predict_cost.rs` times each closure on the M4F).
pub trait DeviceAccess<const N: usize> {
    /// Runs `f` on the device.
    fn with<R>(&mut self, f: impl FnOnce(&mut Device<'_, N>) -> R) -> R;
}

impl<const N: usize> DeviceAccess<N> for Device<'_, N> {
    fn with<R>(&mut self, f: impl FnOnce(&mut Device<'_, N>) -> R) -> R {
        f(self)
    }
}

/// The last accepted `Measure` (for retries with the same seq).
#[derive(Debug, Clone, Copy)]
struct LastMeasure {
    seq: u32,
    periods: u32,
}

/// The stream of estimates.
#[derive(Debug, Clone, Copy, Default)]
struct Stream {
    /// Periods per estimate while on.
    periods: Option<u32>,
    /// The running measurement is the stream's.
    measuring: bool,
    /// A `StreamStopped` to announce.
    ended: Option<StreamEnd>,
}

/// Protocol state of a device.
pub struct Server {
    deframer: Deframer,
    info: Info,
    stream: Stream,
    last_measure: Option<LastMeasure>,
    telemetry_seq: u32,
    /// The device's ramp generation last answered with `RampDone`; `None`
    /// until the server first meets the device (what the device did before,
    /// at power-up, is not announced).
    reported_ramp: Option<u32>,
    last_faults: u32,
    /// `Status::rx_overflows` when last reported.
    reported_overflows: u32,
    /// The closed loop's update count last sent as telemetry.
    reported_update: u32,
}

impl Server {
    /// A server announcing `info`.
    pub fn new(info: Info) -> Self {
        Server {
            deframer: Deframer::default(),
            info,
            stream: Stream::default(),
            last_measure: None,
            telemetry_seq: 0,
            reported_ramp: None,
            last_faults: 0,
            reported_overflows: 0,
            reported_update: 0,
        }
    }

    /// Feeds bytes received at time `now_us` (µs, any origin, wrapping: the
    /// inter-byte timeout [`crate::protocol::BYTE_TIMEOUT_US`] is
    /// measured on it); every complete frame is answered by calling `send`
    /// with the encoded response (at most [`MAX_FRAME`] bytes).
    pub fn receive<const N: usize, A: DeviceAccess<N>>(
        &mut self,
        dev: &mut A,
        bytes: &[u8],
        now_us: u32,
        mut send: impl FnMut(&[u8]),
    ) {
        self.meet(dev);
        for &b in bytes {
            let reply = match self.deframer.push(b, now_us) {
                Deframed::Pending => None,
                Deframed::Oversize { seq } => {
                    Some(error_frame(seq.unwrap_or(0), WireError::Oversize))
                }
                Deframed::Frame(f) => Some(match decode(f) {
                    Ok(Frame {
                        seq,
                        body: Body::Request(r),
                        ..
                    }) => Frame {
                        version: PROTOCOL_VERSION,
                        seq,
                        body: Body::Response(self.handle(dev, seq, r)),
                    },
                    Ok(Frame { seq, .. }) => error_frame(seq, WireError::UnknownMessage),
                    Err((e, seq)) => error_frame(seq.unwrap_or(0), e),
                }),
            };
            if let Some(frame) = reply {
                send_frame(&frame, &mut send);
            }
            if let Some(end) = self.stream.ended.take() {
                self.telemetry(Telemetry::StreamStopped(end), &mut send);
            }
        }
    }

    /// Telemetry due now — ramps settled, newly latched faults, streamed
    /// estimates, the end of a stream — encoded into `send`. Call it from the
    /// main loop.
    pub fn poll<const N: usize, A: DeviceAccess<N>>(
        &mut self,
        dev: &mut A,
        mut send: impl FnMut(&[u8]),
    ) {
        self.meet(dev);
        // One RampDone per change of the ramp generation, once settled.
        // What the notices need, not the whole status (whose measured
        // motion is formed when asked: issue 35 keeps it out of the
        // critical section of every poll).
        let status = dev.with(|d| Brief {
            settled: d.drive_settled(),
            faults: d.faults(),
            rx_overflows: d.rx_overflow_count(),
        });
        let ramp = dev.with(|d| d.ramp_generation());
        if status.settled && Some(ramp) != self.reported_ramp {
            self.reported_ramp = Some(ramp);
            self.telemetry(Telemetry::RampDone, &mut send);
        }
        let new = status.faults & !self.last_faults;
        if new != 0 {
            self.telemetry(Telemetry::Fault(new), &mut send);
        }
        self.last_faults = status.faults;
        if status.rx_overflows != self.reported_overflows {
            self.reported_overflows = status.rx_overflows;
            self.telemetry(Telemetry::RxOverflow(status.rx_overflows), &mut send);
        }
        self.poll_stream(dev, &mut send);
        // The latest closed-loop update, once (a gap in `update` shows the
        // updates that fell between two polls).
        let last = dev.with(|d| d.control_on().then(|| d.control_state().last));
        if let Some(u) = last.filter(|u| u.update != self.reported_update) {
            self.reported_update = u.update;
            self.telemetry(Telemetry::Control(u), &mut send);
        }
        if let Some(end) = self.stream.ended.take() {
            self.telemetry(Telemetry::StreamStopped(end), &mut send);
        }
    }

    /// On the first call (the first bytes received or the first poll): takes
    /// the device's ramp generation as announced, so that the ramps of
    /// power-up (the default drive, a watchdog fault latched before the
    /// link is up) send no `RampDone` — "none is sent at power-up".
    fn meet<const N: usize, A: DeviceAccess<N>>(&mut self, dev: &mut A) {
        if self.reported_ramp.is_none() {
            self.reported_ramp = Some(dev.with(|d| d.ramp_generation()));
        }
    }

    /// Sends the stream's finished estimate and starts its next measurement
    /// (or ends the stream if the device refuses it).
    fn poll_stream<const N: usize, A: DeviceAccess<N>>(
        &mut self,
        dev: &mut A,
        send: &mut impl FnMut(&[u8]),
    ) {
        let Some(periods) = self.stream.periods else {
            return;
        };
        let measuring = dev.with(|d| d.measuring());
        if self.stream.measuring && !measuring {
            // A copy of the finished window, its estimate computed with the
            // device released.
            if let Ok(e) = device::estimate(&dev.with(|d| d.estimator().clone())) {
                self.telemetry(Telemetry::Estimate(e), &mut *send);
            }
            self.stream.measuring = false;
        }
        if !self.stream.measuring && !measuring {
            match dev.with(|d| d.measure(periods)) {
                Ok(()) => self.stream.measuring = true,
                Err(e) => self.end_stream(dev, StreamEnd::Refused(e.into())),
            }
        }
    }

    /// Ends the stream (aborting its running measurement) and queues the
    /// `StreamStopped` notice; nothing if no stream runs.
    fn end_stream<const N: usize, A: DeviceAccess<N>>(&mut self, dev: &mut A, why: StreamEnd) {
        if self.stream.periods.take().is_some() {
            if self.stream.measuring {
                dev.with(|d| d.abort_measurement());
            }
            self.stream.measuring = false;
            self.stream.ended = Some(why);
        }
    }

    /// Sends a telemetry frame (fault notices, ramp done).
    pub fn telemetry(&mut self, t: Telemetry, mut send: impl FnMut(&[u8])) {
        self.telemetry_seq = self.telemetry_seq.wrapping_add(1);
        let f = Frame {
            version: PROTOCOL_VERSION,
            seq: self.telemetry_seq,
            body: Body::Telemetry(t),
        };
        send_frame(&f, &mut send);
    }

    /// Runs one request; the answer is the one [`crate::protocol::ENDPOINTS`]
    /// names, or [`Response::Error`].
    fn handle<const N: usize, A: DeviceAccess<N>>(
        &mut self,
        dev: &mut A,
        seq: u32,
        r: Request,
    ) -> Response {
        let res = match r {
            Request::Measure { periods } => Ok(self.measure(dev, seq, periods)),
            Request::Stream { on, periods } => self.set_stream(dev, on, periods),
            Request::Reset => {
                self.end_stream(dev, StreamEnd::Reset);
                self.last_measure = None;
                dev.with(|d| {
                    d.abort_measurement();
                    d.stop();
                    d.clear_cpu_load_max();
                });
                Ok(Response::Ok)
            }
            Request::SetControl(s) => self.set_control(dev, s),
            other => run(&self.info, dev, other),
        };
        res.unwrap_or_else(Response::Error)
    }

    /// `Measure`, idempotent per seq.
    fn measure<const N: usize, A: DeviceAccess<N>>(
        &mut self,
        dev: &mut A,
        seq: u32,
        periods: u32,
    ) -> Response {
        if let Some(m) = self.last_measure {
            if m.seq == seq && m.periods == periods {
                return Response::Ok;
            }
        }
        let answer = if self.stream.periods.is_some() {
            // Faults and bad periods first, as for a device measurement.
            match dev.with(|d| {
                if d.status().faults != 0 {
                    Err(device::DeviceError::Faulted(d.status().faults))
                } else {
                    device::check_periods(periods)
                }
            }) {
                Ok(()) => Response::Error(WireError::Busy),
                Err(e) => e.into(),
            }
        } else {
            match dev.with(|d| d.measure(periods)) {
                Ok(()) => Response::Ok,
                Err(e) => e.into(),
            }
        };
        // Only an accepted Measure is remembered: a refusal changed nothing,
        // so its retry is simply judged again.
        if answer == Response::Ok {
            self.last_measure = Some(LastMeasure { seq, periods });
        }
        answer
    }

    /// `SetControl`: checked, planned on a scene formed from a copy of its
    /// parameters with the device released (the scene and the inverse search
    /// are slow), then installed.
    fn set_control<const N: usize, A: DeviceAccess<N>>(
        &mut self,
        dev: &mut A,
        s: ControlSetting,
    ) -> Result<Response, WireError> {
        let busy = self.stream.periods.is_some();
        let plan = if s.on {
            let (inputs, now, limit) =
                dev.with(|d| d.check_control(&s, busy).map(|()| d.control_plan_inputs()))?;
            let scene = inputs.scene()?;
            let p = control::plan(&scene, s.target_mu, s.v0_m_s, now, limit)
                .map_err(device::DeviceError::Control)?;
            Some(p)
        } else {
            None
        };
        if s.on && !dev.with(|d| d.control_on()) {
            // A fresh loop: its first update is a new count.
            self.reported_update = 0;
        }
        dev.with(|d| d.set_control(s, plan))?;
        Ok(Response::Control(dev.with(|d| d.control_state())))
    }

    /// `Stream`: on (replacing the periods of a running stream) or off.
    fn set_stream<const N: usize, A: DeviceAccess<N>>(
        &mut self,
        dev: &mut A,
        on: bool,
        periods: u32,
    ) -> Result<Response, WireError> {
        if on {
            let faults = dev.with(|d| d.faults());
            if faults != 0 {
                // As `Measure`: no stream starts (or changes) with a fault latched.
                return Err(WireError::Faulted(faults));
            }
            device::check_periods(periods)?;
            if self.stream.periods.is_none() && dev.with(|d| d.status().measuring || d.control_on())
            {
                // A host measurement runs: it would be stolen by the stream.
                return Err(WireError::Busy);
            }
            self.stream.periods = Some(periods);
        } else {
            self.end_stream(dev, StreamEnd::Requested);
        }
        Ok(Response::Ok)
    }
}

/// The requests without session state.
fn run<const N: usize, A: DeviceAccess<N>>(
    info: &Info,
    dev: &mut A,
    r: Request,
) -> Result<Response, WireError> {
    Ok(match r {
        Request::Hello => Response::Info(*info),
        Request::GetDrive => dev.with(|d| Response::Drive {
            setting: d.drive(),
            applied: d.applied(),
        }),
        Request::SetDrive(s) => dev.with(|d| {
            d.set_drive(s).map(|applied| Response::Drive {
                setting: d.drive(),
                applied,
            })
        })?,
        Request::Start => {
            dev.with(|d| d.start())?;
            Response::Ok
        }
        Request::Stop => {
            dev.with(|d| d.stop());
            Response::Ok
        }
        Request::GetContact => Response::Contact(dev.with(|d| d.contact())),
        Request::SetContact(c) => {
            dev.with(|d| d.set_contact(c))?;
            Response::Ok
        }
        Request::Predict { v0 } => {
            // Copy the scene's parameters, then form it and compute with the
            // device released.
            let scene = dev.with(|d| d.prediction_inputs()).scene()?;
            Response::Prediction {
                prediction: device::predict(&scene, v0)?,
                regime: device::regime(&scene)?,
            }
        }
        Request::GetEstimate => {
            // A copy of the window; the estimate with the device released.
            let est = dev.with(|d| d.estimator().clone());
            Response::Estimate(device::estimate(&est)?)
        }
        Request::GetStatus => Response::Status(dev.with(|d| d.status())),
        Request::ResetFaults => {
            dev.with(|d| d.reset_faults());
            Response::Ok
        }
        Request::SetLiftOff { allow } => {
            dev.with(|d| d.set_liftoff_allowed(allow))?;
            Response::Ok
        }
        Request::GetControl => Response::Control(dev.with(|d| d.control_state())),
        Request::SetTransducers(t) => {
            dev.with(|d| d.set_transducers(t))?;
            Response::Ok
        }
        Request::GetTransducers => Response::Transducers(dev.with(|d| d.transducers())),
        Request::SetDriveMode(m) => {
            dev.with(|d| d.set_drive_mode(m))?;
            Response::Ok
        }
        Request::SetDisplacementOptions(o) => {
            dev.with(|d| d.set_displacement_options(o))?;
            Response::Ok
        }
        // Handled with the session state in `Server::handle`: never here.
        Request::Measure { .. }
        | Request::Stream { .. }
        | Request::Reset
        | Request::SetControl(_) => return Err(WireError::Internal),
    })
}

/// What [`Server::poll`] reads of the device for its notices.
struct Brief {
    settled: bool,
    faults: u32,
    rx_overflows: u32,
}

fn send_frame(frame: &Frame, send: &mut impl FnMut(&[u8])) {
    let mut out = [0u8; MAX_FRAME];
    if let Ok(bytes) = encode(frame, &mut out) {
        send(bytes);
    }
}

fn error_frame(seq: u32, e: WireError) -> Frame {
    Frame {
        version: PROTOCOL_VERSION,
        seq,
        body: Body::Response(Response::Error(e)),
    }
}

impl From<crate::device::DeviceError> for Response {
    fn from(e: crate::device::DeviceError) -> Self {
        Response::Error(e.into())
    }
}
