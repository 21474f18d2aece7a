//! Every fault source reaches the safe state through the device's one fault
//! path (docs/protocol.md, "Fault bits"; `board/src/device/fault.rs`),
//! checked natively through the protocol server as a host sees it:
//!
//! * ADC saturation (a railed sample in a finished estimate) with a stream
//!   running, and with the closed loop on;
//! * DAC underrun and ADC overrun (a DMA handler late by a half: both flags
//!   set, the half decided from NDTR, `board::dma`);
//! * the external input, while the closed loop runs;
//! * the watchdog reset, latched at power-up before the link is up.
//!
//! For each: `running` false, every output at zero displacement once the
//! ramps end, the loop off, exactly one `RampDone` and one `Fault(bit)`
//! after the fault, `Start`/`Measure`/`SetControl` refused with
//! `Faulted(bit)`, and `ResetFaults` then `Start` running the drive again.
//! Also: no `RampDone` at power-up, and the closed-loop reach is a closed
//! interval (a target equal to a reported end is accepted; at the top of the
//! offset range the reach is one point, never `BadScene`).

use board::dds::SineTable;
use board::device::{faults, Contact, Device, DeviceConfig, DriveSetting, HALF_BUFFER};
use board::dma::{half_event, HalfEvent};
use board::protocol::{
    decode, encode, Body, ControlSetting, Deframed, Deframer, Frame, Info, Request, Response,
    StreamEnd, Telemetry, WireError, MAX_FRAME, PROTOCOL_VERSION,
};
use board::server::Server;

fn cfg() -> DeviceConfig {
    integration_tests::board_config_1mhz()
}

const CONTACT: Contact = Contact {
    mu0: 0.3,
    kz: 1e7,
    kx: 1e7,
};

/// A drive well inside the limits: 1 µm < (1 − 0.05)·3 µm.
fn drive() -> DriveSetting {
    DriveSetting {
        freq_hz: 40e3,
        amp_z_m: 1e-6,
        amp_x_m: 2e-7,
        offset_z_m: 3e-6,
        phase_rad: 0.5,
    }
}

/// ADC counts of an ordinary sample (mid-scale, away from both rails).
const MID: (u16, u16) = (2100, 2600);
/// A sample at the lower rail (the estimator's saturation test: a count of 0
/// or ≥ full scale).
const RAIL: (u16, u16) = (2100, 0);

/// A device, its server and everything the server sent, as a host sees it.
struct Bench<'t> {
    dev: Device<'t, 256>,
    server: Server,
    seq: u32,
    tele: Vec<Telemetry>,
    df: Deframer,
    /// DAC fills and ADC blocks so far (the next half is `halves % 2`).
    halves: usize,
}

impl<'t> Bench<'t> {
    fn new(t: &'t SineTable<256>) -> Self {
        let c = cfg();
        Bench {
            dev: Device::new(c, t, CONTACT).unwrap(),
            server: Server::new(Info::for_config(&c, "faults", [0, 1, 0])),
            seq: 0,
            tele: Vec::new(),
            df: Deframer::default(),
            halves: 0,
        }
    }

    fn collect(
        tele: &mut Vec<Telemetry>,
        df: &mut Deframer,
        out: &[u8],
        answers: &mut Vec<Response>,
    ) {
        for &b in out {
            if let Deframed::Frame(f) = df.push(b, 0) {
                match decode(f).unwrap().body {
                    Body::Telemetry(t) => tele.push(t),
                    Body::Response(r) => answers.push(r),
                    Body::Request(r) => panic!("a request from the device: {r:?}"),
                }
            }
        }
    }

    /// One request through the server; its one answer.
    fn call(&mut self, r: Request) -> Response {
        self.seq += 1;
        let mut buf = [0u8; MAX_FRAME];
        let bytes = encode(
            &Frame {
                version: PROTOCOL_VERSION,
                seq: self.seq,
                body: Body::Request(r),
            },
            &mut buf,
        )
        .unwrap()
        .to_vec();
        let mut answers = Vec::new();
        let (tele, df) = (&mut self.tele, &mut self.df);
        self.server.receive(&mut self.dev, &bytes, 0, |out| {
            Self::collect(tele, df, out, &mut answers)
        });
        assert_eq!(answers.len(), 1, "one answer per request: {answers:?}");
        answers[0]
    }

    fn poll(&mut self) {
        let mut answers = Vec::new();
        let (tele, df) = (&mut self.tele, &mut self.df);
        self.server.poll(&mut self.dev, |out| {
            Self::collect(tele, df, out, &mut answers)
        });
        assert!(answers.is_empty(), "poll sends telemetry only: {answers:?}");
    }

    /// One half-buffer as the board runs it: DAC refill, ADC block of
    /// `sample`s, the main loop's poll.
    fn half(&mut self, sample: (u16, u16)) {
        let h = self.halves % 2;
        let mut dac = [0u32; HALF_BUFFER];
        self.dev.fill_dac(h, &mut dac);
        self.dev.adc_block(h, &[sample; HALF_BUFFER]);
        self.halves += 1;
        self.poll();
    }

    /// Half-buffers of `sample` until the ramps have settled (at most `max`).
    fn settle(&mut self, sample: (u16, u16), max: usize) {
        for _ in 0..max {
            self.half(sample);
            if self.dev.status().settled {
                // One more poll sends the RampDone of the settled state.
                self.poll();
                return;
            }
        }
        panic!("ramps not settled after {max} halves");
    }

    fn status(&mut self) -> board::device::Status {
        match self.call(Request::GetStatus) {
            Response::Status(s) => s,
            r => panic!("{r:?}"),
        }
    }

    /// SetDrive, Start, settled; the telemetry so far cleared.
    fn running(&mut self) {
        assert!(matches!(
            self.call(Request::SetDrive(drive())),
            Response::Drive { .. }
        ));
        assert_eq!(self.call(Request::Start), Response::Ok);
        self.settle(MID, 2000);
        self.tele.clear();
    }

    /// The model's μ at v0 for the running drive (a target the loop reaches).
    fn predicted_mu(&mut self, v0: f32) -> f32 {
        match self.call(Request::Predict { v0 }) {
            Response::Prediction { prediction, .. } => prediction.mu,
            r => panic!("{r:?}"),
        }
    }

    fn control_on(&mut self, target_mu: f32) -> Response {
        self.call(Request::SetControl(control(target_mu)))
    }
}

fn control(target_mu: f32) -> ControlSetting {
    ControlSetting {
        on: true,
        target_mu,
        v0_m_s: 0.004,
        gain: 0.5,
        periods: 2,
        rate_m_per_s: 1e-3,
    }
}

/// The safe state after a fault of `bit`, then its recovery: the checks
/// every fault source must pass (module documentation).
fn assert_safe_state_and_recovery(b: &mut Bench<'_>, bit: u32, ramp_done_expected: usize) {
    // Ramps to rest (at most 2 µm at 1 µm/ms: 2000 samples, 32 halves; the
    // phase does not move).
    b.settle(MID, 400);
    let s = b.status();
    assert!(!s.running, "{s:?}");
    assert!(s.settled, "{s:?}");
    assert_eq!(s.faults, bit, "{s:?}");
    // Zero displacement: the DDS ramps end exactly on their targets (the
    // zero codes), so each output is exactly 0 m.
    assert_eq!(
        (s.out_amp_z_m, s.out_amp_x_m, s.out_offset_z_m),
        (0.0, 0.0, 0.0),
        "{s:?}"
    );
    let n_ramp = b.tele.iter().filter(|t| **t == Telemetry::RampDone).count();
    assert_eq!(
        n_ramp, ramp_done_expected,
        "RampDone after the fault: {:?}",
        b.tele
    );
    let n_fault: Vec<_> = b
        .tele
        .iter()
        .filter(|t| matches!(t, Telemetry::Fault(_)))
        .collect();
    assert_eq!(n_fault, [&Telemetry::Fault(bit)], "{:?}", b.tele);
    // The loop is off and says so.
    match b.call(Request::GetControl) {
        Response::Control(c) => assert!(!c.setting.on, "{c:?}"),
        r => panic!("{r:?}"),
    }
    // Refusals name the latched bits; a refusal changes nothing.
    let faulted = Response::Error(WireError::Faulted(bit));
    assert_eq!(b.call(Request::Start), faulted);
    assert_eq!(b.call(Request::Measure { periods: 4 }), faulted);
    assert_eq!(b.control_on(0.1), faulted);
    // A drive set while faulted is stored, and nothing moves.
    assert!(matches!(
        b.call(Request::SetDrive(drive())),
        Response::Drive { .. }
    ));
    b.half(MID);
    let s = b.status();
    assert_eq!(
        (s.out_amp_z_m, s.out_offset_z_m, s.running),
        (0.0, 0.0, false),
        "{s:?}"
    );
    // ResetFaults then Start: the drive runs again, up to the setting.
    assert_eq!(b.call(Request::ResetFaults), Response::Ok);
    assert_eq!(b.call(Request::Start), Response::Ok);
    b.settle(MID, 2000);
    let s = b.status();
    let d = drive();
    assert!(s.running && s.faults == 0, "{s:?}");
    // Within one DAC code of the setting (metres_per_code of the board).
    let code = cfg().dac_z.metres_per_code;
    assert!((s.out_amp_z_m - d.amp_z_m).abs() <= code, "{s:?}");
    assert!((s.out_offset_z_m - d.offset_z_m).abs() <= code, "{s:?}");
    assert_eq!(b.call(Request::Measure { periods: 4 }), Response::Ok);
}

#[test]
fn adc_saturation_with_a_stream_reaches_the_safe_state() {
    // The case: the stream's estimate sees a railed normal force.
    let t = SineTable::<256>::libm();
    let mut b = Bench::new(&t);
    b.running();
    let on = Request::Stream {
        on: true,
        periods: 4,
    };
    assert_eq!(b.call(on), Response::Ok);
    // Ordinary samples: estimates stream, no fault.
    for _ in 0..20 {
        b.half(MID);
    }
    assert!(b.tele.iter().any(|t| matches!(t, Telemetry::Estimate(_))));
    assert_eq!(b.status().faults, 0);
    b.tele.clear();
    // Railed samples: the next estimate closes saturated → the fault.
    for _ in 0..10 {
        b.half(RAIL);
    }
    assert_eq!(b.status().faults, faults::ADC_SATURATED);
    // The stream ended, refused by the fault.
    assert!(
        b.tele
            .contains(&Telemetry::StreamStopped(StreamEnd::Refused(
                WireError::Faulted(faults::ADC_SATURATED)
            ))),
        "{:?}",
        b.tele
    );
    // A new stream with the fault latched is refused like `Measure`
    // (docs/protocol.md, `Stream`): nothing starts, no telemetry follows.
    let before = b.tele.len();
    assert_eq!(
        b.call(on),
        Response::Error(WireError::Faulted(faults::ADC_SATURATED))
    );
    for _ in 0..10 {
        b.half(MID);
    }
    assert!(
        !b.tele[before..]
            .iter()
            .any(|t| matches!(t, Telemetry::Estimate(_) | Telemetry::StreamStopped(_))),
        "{:?}",
        b.tele
    );
    assert_safe_state_and_recovery(&mut b, faults::ADC_SATURATED, 1);
}

#[test]
fn adc_saturation_with_the_loop_on_switches_the_loop_off() {
    let t = SineTable::<256>::libm();
    let mut b = Bench::new(&t);
    b.running();
    let target = b.predicted_mu(0.004);
    assert!(matches!(b.control_on(target), Response::Control(c) if c.setting.on));
    for _ in 0..20 {
        b.half(MID);
    }
    assert!(b.tele.iter().any(|t| matches!(t, Telemetry::Control(_))));
    b.tele.clear();
    for _ in 0..10 {
        b.half(RAIL);
    }
    assert_eq!(b.status().faults, faults::ADC_SATURATED);
    // No loop update after the fault (the last ones before it may be held).
    let after_fault = b
        .tele
        .iter()
        .skip_while(|t| !matches!(t, Telemetry::Fault(_)))
        .filter(|t| matches!(t, Telemetry::Control(_)))
        .count();
    assert_eq!(after_fault, 0, "{:?}", b.tele);
    assert_safe_state_and_recovery(&mut b, faults::ADC_SATURATED, 1);
}

/// The half event of a handler that found both flags set (late), with the
/// stream in the first half (NDTR > HALF): the second half is the free one.
fn late_event() -> HalfEvent {
    let ev = half_event(true, true, HALF_BUFFER as u32 + 3, HALF_BUFFER as u32).unwrap();
    assert_eq!(
        ev,
        HalfEvent {
            half: 1,
            late: true
        }
    );
    ev
}

#[test]
fn dac_underrun_reaches_the_safe_state() {
    let t = SineTable::<256>::libm();
    let mut b = Bench::new(&t);
    b.running();
    let mut dac = [0u32; HALF_BUFFER];
    // An on-time refill changes nothing.
    let on_time = half_event(true, false, HALF_BUFFER as u32, HALF_BUFFER as u32).unwrap();
    b.dev.dac_half_done(on_time, &mut dac);
    b.dev.adc_block(0, &[MID; HALF_BUFFER]);
    b.poll();
    assert_eq!(b.status().faults, 0);
    assert!(b.status().running);
    b.dev.dac_half_done(late_event(), &mut dac);
    b.dev.adc_block(1, &[MID; HALF_BUFFER]);
    b.poll();
    assert_safe_state_and_recovery(&mut b, faults::DAC_UNDERRUN, 1);
}

#[test]
fn adc_overrun_reaches_the_safe_state_and_keeps_blocks_numbered() {
    let t = SineTable::<256>::libm();
    let mut b = Bench::new(&t);
    b.running();
    let blocks = b.dev.adc_blocks();
    let mut dac = [0u32; HALF_BUFFER];
    b.dev.fill_dac(0, &mut dac);
    b.dev.fill_dac(1, &mut dac);
    // The handler missed one block: the late one counts it as missed, so
    // the next block it takes is the second fill's.
    b.dev.adc_half_done(late_event(), &[MID; HALF_BUFFER]);
    assert_eq!(b.dev.adc_blocks(), blocks + 2);
    b.poll();
    assert_safe_state_and_recovery(&mut b, faults::ADC_OVERRUN, 1);
}

#[test]
fn external_fault_with_the_loop_on_reaches_the_safe_state() {
    let t = SineTable::<256>::libm();
    let mut b = Bench::new(&t);
    b.running();
    let target = b.predicted_mu(0.004);
    assert!(matches!(b.control_on(target), Response::Control(c) if c.setting.on));
    for _ in 0..10 {
        b.half(MID);
    }
    b.tele.clear();
    // The firmware's EXTI0 handler does exactly this.
    b.dev.fault(faults::EXTERNAL);
    // At once, before any DAC fill: the loop is off, the drive stopped.
    match b.call(Request::GetControl) {
        Response::Control(c) => assert!(!c.setting.on, "{c:?}"),
        r => panic!("{r:?}"),
    }
    assert!(!b.status().running);
    b.poll();
    assert_safe_state_and_recovery(&mut b, faults::EXTERNAL, 1);
}

#[test]
fn watchdog_fault_at_power_up_is_safe_and_announced_without_ramp_done() {
    // The firmware's power-up: the watchdog fault and the default drive
    // before the server first meets the device.
    let t = SineTable::<256>::libm();
    let mut b = Bench::new(&t);
    b.dev.fault(faults::WATCHDOG_RESET);
    let _ = b.dev.set_drive(DriveSetting {
        freq_hz: 40e3,
        amp_z_m: 0.0,
        amp_x_m: 0.0,
        offset_z_m: 0.0,
        phase_rad: 0.0,
    });
    // "None [RampDone] is sent at power-up": the safe state is the power-up
    // state, so the fault's RampDone is not sent either (0 expected); the
    // Fault telemetry is.
    assert_safe_state_and_recovery(&mut b, faults::WATCHDOG_RESET, 0);
}

#[test]
fn no_ramp_done_at_power_up_but_one_per_command() {
    let t = SineTable::<256>::libm();
    let mut b = Bench::new(&t);
    // The virtual device's and the firmware's power-up: a default drive set
    // before the link is up.
    let _ = b.dev.set_drive(DriveSetting {
        freq_hz: 40e3,
        amp_z_m: 0.0,
        amp_x_m: 0.0,
        offset_z_m: 0.0,
        phase_rad: 0.0,
    });
    for _ in 0..50 {
        b.half(MID);
    }
    assert!(b.tele.is_empty(), "{:?}", b.tele);
    assert!(matches!(
        b.call(Request::SetDrive(drive())),
        Response::Drive { .. }
    ));
    b.settle(MID, 2000);
    assert_eq!(b.tele, [Telemetry::RampDone]);
}

#[test]
fn a_second_fault_while_faulted_adds_its_bit() {
    let t = SineTable::<256>::libm();
    let mut b = Bench::new(&t);
    b.running();
    b.dev.fault(faults::EXTERNAL);
    b.settle(MID, 400);
    b.dev.fault(faults::DAC_UNDERRUN);
    b.settle(MID, 400);
    let s = b.status();
    assert_eq!(s.faults, faults::EXTERNAL | faults::DAC_UNDERRUN);
    assert_eq!(
        b.call(Request::Start),
        Response::Error(WireError::Faulted(faults::EXTERNAL | faults::DAC_UNDERRUN))
    );
    // Each fault's safe state is announced by one RampDone; each new bit by
    // one Fault frame.
    let faults_sent: Vec<_> = b
        .tele
        .iter()
        .filter(|t| matches!(t, Telemetry::Fault(_)))
        .collect();
    assert_eq!(
        faults_sent,
        [
            &Telemetry::Fault(faults::EXTERNAL),
            &Telemetry::Fault(faults::DAC_UNDERRUN)
        ]
    );
    assert_eq!(
        b.tele.iter().filter(|t| **t == Telemetry::RampDone).count(),
        2
    );
}

#[test]
fn half_selection_follows_the_flags_and_ndtr() {
    let h = HALF_BUFFER as u32;
    // No flag: a spurious entry.
    assert_eq!(half_event(false, false, 7, h), None);
    // One flag: the half it names, on time, whatever NDTR says.
    for ndtr in [1, h, h + 1, 2 * h] {
        assert_eq!(
            half_event(true, false, ndtr, h),
            Some(HalfEvent {
                half: 0,
                late: false
            })
        );
        assert_eq!(
            half_event(false, true, ndtr, h),
            Some(HalfEvent {
                half: 1,
                late: false
            })
        );
    }
    // Both flags: late; the free half is the one the stream is not in
    // (NDTR counts down from 2·HALF: > HALF means the first half).
    for ndtr in h + 1..=2 * h {
        assert_eq!(
            half_event(true, true, ndtr, h),
            Some(HalfEvent {
                half: 1,
                late: true
            })
        );
    }
    for ndtr in 1..=h {
        assert_eq!(
            half_event(true, true, ndtr, h),
            Some(HalfEvent {
                half: 0,
                late: true
            })
        );
    }
}

#[test]
fn closed_loop_reach_is_a_closed_interval() {
    let t = SineTable::<256>::libm();
    let mut b = Bench::new(&t);
    b.running();
    // A target far above the reach: refused with the reach's ends.
    let (min, max) = match b.control_on(0.29) {
        Response::Error(WireError::OutOfReach { min, max }) => (min, max),
        r => panic!("{r:?}"),
    };
    assert!(min < max && max < 0.29, "{min} {max}");
    // Each reported end, sent back as the very f32 value, is accepted.
    for end in [max, min] {
        match b.control_on(end) {
            Response::Control(c) => {
                assert!(c.setting.on);
                assert_eq!(c.setting.target_mu, end);
                assert!((0.0..=c.limit_m).contains(&c.feedforward_m), "{c:?}");
            }
            r => panic!("target {end} at the reach's end: {r:?}"),
        }
        assert_eq!(
            b.call(Request::SetControl(ControlSetting {
                on: false,
                ..control(0.0)
            })),
            b.call(Request::GetControl)
        );
    }
    // One f32 step beyond an end is refused with the same reach.
    let beyond = f32::from_bits(max.to_bits() + 1);
    assert_eq!(
        b.control_on(beyond),
        Response::Error(WireError::OutOfReach { min, max })
    );
}

#[test]
fn loop_at_the_top_of_the_offset_range_has_a_one_point_reach() {
    // The drive at max_offset_z_m with amp_z 0: the bound on Δu_z is 0, so
    // the reach is the single μ at Δu_z = 0 — accepted when equal, else
    // OutOfReach{μ(0), μ(0)}; never BadScene (reserved for no offset).
    let t = SineTable::<256>::libm();
    let mut b = Bench::new(&t);
    let top = cfg().max_offset_z_m();
    let d = DriveSetting {
        amp_z_m: 0.0,
        offset_z_m: top,
        ..drive()
    };
    assert!(matches!(
        b.call(Request::SetDrive(d)),
        Response::Drive { .. }
    ));
    assert_eq!(b.call(Request::Start), Response::Ok);
    b.settle(MID, 4000);
    let mu_here = b.predicted_mu(0.004);
    match b.control_on(0.05) {
        Response::Error(WireError::OutOfReach { min, max }) => {
            assert_eq!((min, max), (mu_here, mu_here));
        }
        r => panic!("{r:?}"),
    }
    match b.control_on(mu_here) {
        Response::Control(c) => {
            assert!(c.setting.on);
            assert_eq!((c.feedforward_m, c.limit_m), (0.0, 0.0));
        }
        r => panic!("{r:?}"),
    }
    // A drive without normal offset is the one BadScene.
    assert_eq!(
        b.call(Request::SetControl(ControlSetting {
            on: false,
            ..control(0.0)
        })),
        b.call(Request::GetControl)
    );
    let no_offset = DriveSetting {
        amp_z_m: 0.0,
        offset_z_m: 0.0,
        ..drive()
    };
    assert!(matches!(
        b.call(Request::SetDrive(no_offset)),
        Response::Drive { .. }
    ));
    b.settle(MID, 4000);
    assert_eq!(b.control_on(0.05), Response::Error(WireError::BadScene));
}
