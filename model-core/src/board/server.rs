//! The device side of the protocol: decodes request frames, runs them on a
//! [`Device`], encodes the responses and the telemetry. The firmware feeds it
//! the bytes from USART2; the virtual device feeds it the bytes of a
//! pseudo-terminal — the same code.

use crate::board::device::{self, Device};

/// Access to the device for the server: on the host a plain `&mut Device`;
/// in the firmware a critical section around each call, so that long model
/// computations ([`Request::Predict`]) run on a snapshot with interrupts on.
pub trait DeviceAccess<const N: usize> {
    /// Runs `f` on the device.
    fn with<R>(&mut self, f: impl FnOnce(&mut Device<'_, N>) -> R) -> R;
}

impl<const N: usize> DeviceAccess<N> for Device<'_, N> {
    fn with<R>(&mut self, f: impl FnOnce(&mut Device<'_, N>) -> R) -> R {
        f(self)
    }
}
use crate::board::protocol::{
    decode, encode, Body, Deframed, Deframer, Frame, Info, Request, Response, Telemetry, WireError,
    MAX_FRAME, PROTOCOL_VERSION,
};

/// Protocol state of a device.
pub struct Server {
    deframer: Deframer,
    info: Info,
    stream: Option<u32>,
    telemetry_seq: u32,
    measuring_for_stream: bool,
    /// The device's ramp generation last answered with `RampDone`.
    reported_ramp: u32,
    last_faults: u32,
}

impl Server {
    /// A server announcing `info`.
    pub fn new(info: Info) -> Self {
        Server {
            deframer: Deframer::default(),
            info,
            stream: None,
            telemetry_seq: 0,
            measuring_for_stream: false,
            reported_ramp: 0,
            last_faults: 0,
        }
    }

    /// Feeds bytes received at time `now_us` (µs, any origin, wrapping: the
    /// inter-byte timeout [`crate::board::protocol::BYTE_TIMEOUT_US`] is
    /// measured on it); every complete frame is answered by calling `send`
    /// with the encoded response (at most [`MAX_FRAME`] bytes).
    pub fn receive<const N: usize, A: DeviceAccess<N>>(
        &mut self,
        dev: &mut A,
        bytes: &[u8],
        now_us: u32,
        mut send: impl FnMut(&[u8]),
    ) {
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
                        body: Body::Response(handle(&self.info, &mut self.stream, dev, r)),
                    },
                    Ok(Frame { seq, .. }) => error_frame(seq, WireError::UnknownMessage),
                    Err((e, seq)) => error_frame(seq.unwrap_or(0), e),
                }),
            };
            if let Some(frame) = reply {
                let mut out = [0u8; MAX_FRAME];
                if let Ok(bytes) = encode(&frame, &mut out) {
                    send(bytes);
                }
            }
        }
    }

    /// Telemetry due now — ramps settled, newly latched faults, streamed
    /// estimates — encoded into `send`. Call it from the main loop.
    pub fn poll<const N: usize, A: DeviceAccess<N>>(
        &mut self,
        dev: &mut A,
        mut send: impl FnMut(&[u8]),
    ) {
        // One RampDone per change of the ramp generation, once settled.
        let (status, ramp) = dev.with(|d| (d.status(), d.ramp_generation()));
        if status.settled && ramp != self.reported_ramp {
            self.reported_ramp = ramp;
            self.telemetry(Telemetry::RampDone, &mut send);
        }
        let new = status.faults & !self.last_faults;
        if new != 0 {
            self.telemetry(Telemetry::Fault(new), &mut send);
        }
        self.last_faults = status.faults;

        let Some(periods) = self.stream else {
            self.measuring_for_stream = false;
            return;
        };
        let measuring = dev.with(|d| d.status().measuring);
        if self.measuring_for_stream && !measuring {
            if let Ok(e) = dev.with(|d| d.estimate()) {
                self.telemetry_seq = self.telemetry_seq.wrapping_add(1);
                let f = Frame {
                    version: PROTOCOL_VERSION,
                    seq: self.telemetry_seq,
                    body: Body::Telemetry(Telemetry::Estimate(e)),
                };
                let mut out = [0u8; MAX_FRAME];
                if let Ok(bytes) = encode(&f, &mut out) {
                    send(bytes);
                }
            }
            self.measuring_for_stream = false;
        }
        if !self.measuring_for_stream
            && !dev.with(|d| d.status().measuring)
            && dev.with(|d| d.measure(periods)).is_ok()
        {
            self.measuring_for_stream = true;
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
        let mut out = [0u8; MAX_FRAME];
        if let Ok(bytes) = encode(&f, &mut out) {
            send(bytes);
        }
    }
}

fn error_frame(seq: u32, e: WireError) -> Frame {
    Frame {
        version: PROTOCOL_VERSION,
        seq,
        body: Body::Response(Response::Error(e)),
    }
}

fn handle<const N: usize, A: DeviceAccess<N>>(
    info: &Info,
    stream: &mut Option<u32>,
    dev: &mut A,
    r: Request,
) -> Response {
    let res: Result<Response, WireError> = (|| {
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
                // Snapshot the scene, then compute with the device released.
                let scene = dev.with(|d| d.scene())?;
                Response::Prediction {
                    prediction: device::predict(&scene, v0)?,
                    regime: device::regime(&scene)?,
                }
            }
            Request::Measure { periods } => {
                if stream.is_some() {
                    return Err(WireError::Busy);
                }
                dev.with(|d| d.measure(periods))?;
                Response::Ok
            }
            Request::GetEstimate => Response::Estimate(dev.with(|d| d.estimate())?),
            Request::Stream { on, periods } => {
                if on {
                    device::check_periods(periods)?;
                    *stream = Some(periods);
                } else {
                    *stream = None;
                }
                Response::Ok
            }
            Request::GetStatus => Response::Status(dev.with(|d| d.status())),
            Request::ResetFaults => {
                dev.with(|d| d.reset_faults());
                Response::Ok
            }
        })
    })();
    res.unwrap_or_else(Response::Error)
}

impl From<crate::board::device::DeviceError> for Response {
    fn from(e: crate::board::device::DeviceError) -> Self {
        Response::Error(e.into())
    }
}
