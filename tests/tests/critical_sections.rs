//! Issue 42: the server holds the device only for copies. Every
//! `DeviceAccess::with` closure runs with the DMA handlers masked in the
//! firmware, so no scene (`Scene::new`, thousands of instructions on the
//! Cortex-M4F; ≈ 22 000 before) and no estimate's arithmetic is formed
//! inside one: `Predict` and `SetControl` copy the scene's parameters out
//! and form the scene with the device released, `GetEstimate` copies the
//! estimator. Checked here through a `DeviceAccess` that counts the
//! critical sections, with the answers compared to the model computed
//! independently from the known drive and contact, and to the device's own
//! conveniences (`Device::predict`, `Device::regime`, `Device::estimate`).
//! The contact check forms no scene either and refuses exactly what a scene
//! of the contact refused. (The cost of each critical section on the M4F:
//! `firmware/src/bin/predict_cost.rs` under QEMU.)

use board::control;
use board::dds::SineTable;
use board::device::{self, Contact, Device, DeviceConfig, DeviceError, DriveSetting};
use board::protocol::{
    decode, encode, Body, ControlSetting, Deframed, Deframer, Frame, Info, Request, Response,
    MAX_FRAME, PROTOCOL_VERSION,
};
use board::server::{DeviceAccess, Server};
use model_core::scene::ContactMode;
use model_core::{Scene, SceneParams};

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

/// A `DeviceAccess` that counts its `with` calls: the firmware's critical
/// sections.
struct Counting<'d, 't> {
    dev: &'d mut Device<'t, 256>,
    calls: u32,
}

impl DeviceAccess<256> for Counting<'_, '_> {
    fn with<R>(&mut self, f: impl FnOnce(&mut Device<'_, 256>) -> R) -> R {
        self.calls += 1;
        f(self.dev)
    }
}

fn info() -> Info {
    Info::for_config(&cfg(), "virtual", [0, 1, 0])
}

/// One request through the server (framed with the protocol's encoding):
/// its answer and the critical sections it took.
fn call(s: &mut Server, acc: &mut Counting<'_, '_>, seq: u32, r: Request) -> (Response, u32) {
    let mut buf = [0u8; MAX_FRAME];
    let bytes = encode(
        &Frame {
            version: PROTOCOL_VERSION,
            seq,
            body: Body::Request(r),
        },
        &mut buf,
    )
    .unwrap()
    .to_vec();
    let mut answers = Vec::new();
    let mut df = Deframer::default();
    acc.calls = 0;
    s.receive(acc, &bytes, 0, |out| {
        for &b in out {
            if let Deframed::Frame(f) = df.push(b, 0) {
                if let Body::Response(r) = decode(f).unwrap().body {
                    answers.push(r);
                }
            }
        }
    });
    assert_eq!(answers.len(), 1, "{answers:?}");
    (answers[0], acc.calls)
}

/// The scene of `CONTACT` with drive `d` as the DDS applies it, formed
/// here from the known values (not through the device).
fn scene_of(dev: &Device<'_, 256>, d: &DriveSetting, mode: ContactMode) -> Scene<f32> {
    let a = dev.applied();
    Scene::new_with_contact(
        SceneParams {
            mu0: CONTACT.mu0,
            kz: CONTACT.kz,
            kx: CONTACT.kx,
            uz0: d.offset_z_m,
            duz: d.amp_z_m,
            dux: d.amp_x_m,
            omega: (std::f64::consts::TAU * a.achieved.freq_hz) as f32,
            phi: a.phase_rad as f32,
        },
        mode,
    )
    .unwrap()
}

#[test]
fn predict_forms_its_scene_outside_the_one_critical_section() {
    let t = SineTable::<256>::libm();
    let mut dev = Device::new(cfg(), &t, CONTACT).unwrap();
    let mut s = Server::new(info());
    let mut acc = Counting {
        dev: &mut dev,
        calls: 0,
    };
    // The first exchange also meets the device (one more section).
    assert_eq!(call(&mut s, &mut acc, 1, Request::Hello).1, 1);
    // No offset yet: the scene is refused (formed outside, the same error).
    let (r, n) = call(&mut s, &mut acc, 2, Request::Predict { v0: 4e-3 });
    assert_eq!(r, Response::Error(board::protocol::WireError::BadScene));
    assert_eq!(n, 1);
    let (r, n) = call(&mut s, &mut acc, 3, Request::SetDrive(drive()));
    assert!(matches!(r, Response::Drive { .. }), "{r:?}");
    assert_eq!(n, 1);
    let mut seq = 4;
    for (allow, d) in [
        (false, drive()),
        // Lift-off allowed, a drive above the limit: the lift-off model
        // on an intermittent contact.
        (
            true,
            DriveSetting {
                amp_z_m: 3e-6,
                ..drive()
            },
        ),
    ] {
        let (r, _) = call(&mut s, &mut acc, seq, Request::SetLiftOff { allow });
        assert_eq!(r, Response::Ok);
        let (r, _) = call(&mut s, &mut acc, seq + 1, Request::SetDrive(d));
        assert!(matches!(r, Response::Drive { .. }), "{r:?}");
        seq += 2;
        let mode = if allow {
            ContactMode::Intermittent
        } else {
            ContactMode::Permanent
        };
        let scene = scene_of(acc.dev, &d, mode);
        for v0 in [-0.02f32, -1e-3, 0.0, 4e-3, 0.05] {
            let (r, n) = call(&mut s, &mut acc, seq, Request::Predict { v0 });
            seq += 1;
            // One critical section: the copy of the scene's parameters.
            assert_eq!(n, 1, "v0 {v0}");
            let want = Response::Prediction {
                prediction: device::predict(&scene, v0).unwrap(),
                regime: device::regime(&scene).unwrap(),
            };
            assert_eq!(r, want, "v0 {v0}, lift-off {allow}");
            assert_eq!(r, {
                let d = &*acc.dev;
                Response::Prediction {
                    prediction: d.predict(v0).unwrap(),
                    regime: d.regime().unwrap(),
                }
            });
        }
        assert_eq!(
            acc.dev.scene_inputs().scene().unwrap(),
            scene,
            "lift-off {allow}"
        );
    }
}

#[test]
fn set_control_plans_on_a_scene_formed_outside_the_critical_sections() {
    let t = SineTable::<256>::libm();
    let mut dev = Device::new(cfg(), &t, CONTACT).unwrap();
    dev.set_drive(drive()).unwrap();
    dev.start().unwrap();
    let scene = scene_of(&dev, &drive(), ContactMode::Permanent);
    let target = 0.9 * device::predict(&scene, 4e-3).unwrap().mu;
    let mut s = Server::new(info());
    let mut acc = Counting {
        dev: &mut dev,
        calls: 0,
    };
    call(&mut s, &mut acc, 1, Request::Hello);
    let setting = ControlSetting {
        on: true,
        target_mu: target,
        v0_m_s: 4e-3,
        gain: 0.5,
        periods: 4,
        rate_m_per_s: 1e-3,
    };
    let (r, n) = call(&mut s, &mut acc, 2, Request::SetControl(setting));
    // Four short sections: the check with the copy of the scene's
    // parameters, whether the loop runs, the installation, the state.
    assert_eq!(n, 4);
    let cfg = cfg();
    let limit = cfg
        .liftoff_limit_m(drive().offset_z_m)
        .min(cfg.max_offset_z_m() - drive().offset_z_m);
    let plan = control::plan(&scene, target, 4e-3, drive().amp_z_m, limit).unwrap();
    let Response::Control(c) = r else {
        panic!("{r:?}")
    };
    assert_eq!(c.setting, setting);
    assert_eq!(
        (c.feedforward_m, c.slope_per_m, c.limit_m),
        (plan.feedforward_m, plan.slope_per_m, plan.limit_m)
    );
}

#[test]
fn get_estimate_computes_on_a_copy_of_the_estimator() {
    let t = SineTable::<256>::libm();
    let mut dev = Device::new(cfg(), &t, CONTACT).unwrap();
    dev.set_drive(drive()).unwrap();
    dev.start().unwrap();
    let mut s = Server::new(info());
    let mut acc = Counting {
        dev: &mut dev,
        calls: 0,
    };
    call(&mut s, &mut acc, 1, Request::Hello);
    let (r, n) = call(&mut s, &mut acc, 2, Request::Measure { periods: 40 });
    assert_eq!((r, n), (Response::Ok, 1));
    let (mut dac, samples) = ([0u32; 64], [(2100u16, 2600u16); 64]);
    for _ in 0..100 {
        acc.dev.fill_dac(0, &mut dac);
        acc.dev.adc_block(0, &samples);
    }
    let (r, n) = call(&mut s, &mut acc, 3, Request::GetEstimate);
    assert_eq!(n, 1);
    let want = acc.dev.estimate().unwrap();
    assert_eq!(r, Response::Estimate(want));
    assert_eq!(device::estimate(acc.dev.estimator()), Ok(want));
    assert!(want.periods == 40 && want.samples > 0, "{want:?}");
}

/// The contact check (no scene formed) refuses exactly what the scene of
/// the contact with the nominal drive refused before, with the same error,
/// and a refused contact changes nothing.
#[test]
fn set_contact_refuses_what_the_scene_refused() {
    let t = SineTable::<256>::libm();
    let mut dev = Device::new(cfg(), &t, CONTACT).unwrap();
    let nominal = |c: &Contact| {
        Scene::new(SceneParams {
            mu0: c.mu0,
            kz: c.kz,
            kx: c.kx,
            uz0: 1e-6,
            duz: 0.0,
            dux: 0.0,
            omega: 1.0,
            phi: 0.0,
        })
        .map(|_| ())
        .map_err(DeviceError::Scene)
    };
    let values = [
        f32::NAN,
        f32::INFINITY,
        -1.0,
        0.0,
        1e-40,
        f32::MIN_POSITIVE,
        1e-30,
        1e-6,
        0.3,
        1e7,
        1e30,
        f32::MAX,
    ];
    let mut refused = 0;
    for &mu0 in &values {
        for &kz in &values {
            for &kx in &values {
                let c = Contact { mu0, kz, kx };
                let want = nominal(&c);
                let got = dev.set_contact(c);
                assert_eq!(got, want, "{c:?}");
                if got.is_err() {
                    refused += 1;
                    assert_eq!(dev.contact(), CONTACT);
                } else {
                    dev.set_contact(CONTACT).unwrap();
                }
                assert_eq!(Device::new(cfg(), &t, c).err(), want.err(), "{c:?}");
            }
        }
    }
    // W₀ out of range at 1 µm, with every parameter valid on its own.
    let extreme = Contact {
        mu0: 1e30,
        kz: 1e30,
        kx: 1e-30,
    };
    assert!(matches!(
        dev.set_contact(extreme),
        Err(DeviceError::Scene(model_core::SceneError::OutOfRange(_)))
    ));
    assert!(refused > 1000, "{refused}");
}
