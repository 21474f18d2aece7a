//! The board's device logic, run natively: lift-off guard and refusals that
//! change nothing, ramps on start/stop, the fault safe state, the f32
//! prediction against the f64 model, and a closed loop with a simulated plant
//! whose measured μ agrees with the prediction.

use std::f64::consts::TAU;

use board::dds::{unpack_dual, SineTable};
use board::device::{
    faults, ConfigError, Contact, Device, DeviceConfig, DeviceError, DriveParam, DriveSetting,
};
use model_core::fixed_step::{run_dimensionless, FixedStepConfig, Start, State, Stepper};
use model_core::{exact, Libm, Scene, SceneParams};

fn cfg() -> DeviceConfig {
    integration_tests::board_config_1mhz()
}

const CONTACT: Contact = Contact {
    mu0: 0.3,
    kz: 1e7,
    kx: 1e7,
};

fn drive() -> DriveSetting {
    DriveSetting {
        freq_hz: 20_000.0,
        amp_z_m: 2e-6,
        amp_x_m: 0.3e-6,
        offset_z_m: 4e-6,
        phase_rad: 0.7,
    }
}

/// The frequency range must lie strictly below half the sample rate
/// (`ConfigError::FreqRange`'s text): at 1 MHz a top of exactly 500 kHz is
/// refused, the next f64 below it accepted.
#[test]
fn a_frequency_range_up_to_half_the_sample_rate_is_refused() {
    let t = SineTable::<1024>::libm();
    let nyquist = cfg().sample_rate_hz / 2.0;
    assert_eq!(nyquist, 500_000.0);
    let with_top = |hi: f64| DeviceConfig {
        freq_range_hz: (1_000.0, hi),
        ..cfg()
    };
    assert!(matches!(
        Device::new(with_top(nyquist), &t, CONTACT),
        Err(DeviceError::Config(ConfigError::FreqRange))
    ));
    assert!(Device::new(with_top(nyquist.next_down()), &t, CONTACT).is_ok());
}

#[test]
fn liftoff_and_range_refusals_leave_the_state_untouched() {
    let t = SineTable::<1024>::libm();
    let mut d = Device::new(cfg(), &t, CONTACT).unwrap();
    d.set_drive(drive()).unwrap();
    d.start().unwrap();
    for _ in 0..10 {
        let mut buf = [0u32; 256];
        d.fill_dac(0, &mut buf);
    }
    let before = (
        d.drive(),
        d.applied(),
        *d.dds().channels(),
        d.dds().tuning_word(),
    );
    // Δu_z above (1 − 0.05)·u_z0 = 3.8 µm: lift-off refused, with the limit.
    let r = d.set_drive(DriveSetting {
        amp_z_m: 3.9e-6,
        ..drive()
    });
    match r {
        Err(DeviceError::LiftOff { limit_m, .. }) => assert!((limit_m - 3.8e-6).abs() < 1e-12),
        other => panic!("{other:?}"),
    }
    for bad in [
        DriveSetting {
            freq_hz: 500.0,
            ..drive()
        },
        DriveSetting {
            freq_hz: f64::NAN,
            ..drive()
        },
        DriveSetting {
            amp_x_m: 3e-6,
            ..drive()
        },
        DriveSetting {
            amp_x_m: -1e-9,
            ..drive()
        },
        DriveSetting {
            offset_z_m: 9e-6,
            ..drive()
        },
        DriveSetting {
            phase_rad: f32::INFINITY,
            ..drive()
        },
        DriveSetting {
            amp_z_m: f32::NAN,
            ..drive()
        },
    ] {
        assert!(d.set_drive(bad).is_err(), "{bad:?}");
        assert_eq!(
            (
                d.drive(),
                d.applied(),
                *d.dds().channels(),
                d.dds().tuning_word()
            ),
            before
        );
    }
    match d.set_drive(DriveSetting {
        freq_hz: 500.0,
        ..drive()
    }) {
        Err(DeviceError::OutOfRange {
            param: DriveParam::Freq,
            min,
            max,
        }) => assert_eq!((min, max), (1000.0, 100_000.0)),
        other => panic!("{other:?}"),
    }
    assert!(matches!(
        d.set_contact(Contact {
            kz: -1.0,
            ..CONTACT
        }),
        Err(DeviceError::Scene(_))
    ));
    assert_eq!(d.contact(), CONTACT);
}

#[test]
fn dac_codes_follow_the_drive_and_never_leave_the_range() {
    let t = SineTable::<1024>::libm();
    let mut d = Device::new(cfg(), &t, CONTACT).unwrap();
    let a = d.set_drive(drive()).unwrap();
    assert!((a.achieved.freq_hz - 20_000.0).abs() < 1e-3);
    assert!((a.phase_rad - 0.7).abs() < 1e-7);
    d.start().unwrap();
    // Soft start at 1 code/sample (offset 2000 codes) and the phase offsets at
    // 100 rad/s = 1e-4 rad/sample (π/2 + 0.7 rad on channel 2: 22 708 samples).
    let mut buf = vec![0u32; 22_000];
    d.fill_dac(0, &mut buf);
    assert!(!d.status().settled);
    let mut buf = vec![0u32; 1_000];
    d.fill_dac(1, &mut buf);
    assert!(d.status().settled);
    // Steady: ch1 = (4 µm − 2 µm cos θ)/2 nm, ch2 = 2048 + 0.3 µm cos(θ + 0.7)/1 nm.
    let acc0 = d.dds().accumulator();
    let mut buf = vec![0u32; 1000];
    d.fill_dac(0, &mut buf);
    let tw = d.dds().tuning_word();
    for (k, w) in buf.iter().enumerate() {
        let th = TAU * f64::from(acc0.wrapping_add(tw.wrapping_mul(k as u32))) / 4_294_967_296.0;
        let (c1, c2) = unpack_dual(*w);
        let e1 = (4e-6 - 2e-6 * th.cos()) / 2e-9;
        let e2 = 2048.0 + 0.3e-6 * (th + 0.7).cos() / 1e-9;
        assert!((f64::from(c1) - e1).abs() <= 0.6, "{k}: {c1} vs {e1}");
        assert!((f64::from(c2) - e2).abs() <= 0.6, "{k}: {c2} vs {e2}");
    }
    // Stop ramps the amplitudes to 0 and keeps the preload.
    d.stop();
    let mut buf = vec![0u32; 5000];
    d.fill_dac(1, &mut buf);
    let (c1, c2) = unpack_dual(*buf.last().unwrap());
    assert_eq!((c1, c2), (2000, 2048));
}

#[test]
fn fault_enters_the_safe_state_and_blocks_start() {
    let t = SineTable::<256>::libm();
    let mut d = Device::new(cfg(), &t, CONTACT).unwrap();
    d.set_drive(drive()).unwrap();
    d.start().unwrap();
    let mut buf = vec![0u32; 10_000];
    d.fill_dac(0, &mut buf);
    d.fault(faults::EXTERNAL);
    assert_eq!(d.status().faults, faults::EXTERNAL);
    assert!(!d.status().running);
    assert_eq!(d.start(), Err(DeviceError::Faulted(faults::EXTERNAL)));
    let mut buf = vec![0u32; 10_000];
    d.fill_dac(0, &mut buf);
    // Everything at zero displacement (ramped, no jump larger than the slew + waveform step).
    assert_eq!(unpack_dual(*buf.last().unwrap()), (0, 2048));
    d.reset_faults();
    d.start().unwrap();
}

#[test]
fn prediction_in_f32_matches_the_f64_model() {
    let t = SineTable::<256>::libm();
    let mut d = Device::new(cfg(), &t, CONTACT).unwrap();
    let a = d.set_drive(drive()).unwrap();
    let s64 = Scene::new(SceneParams {
        mu0: 0.3,
        kz: 1e7,
        kx: 1e7,
        uz0: 4e-6,
        duz: 2e-6,
        dux: 0.3e-6,
        omega: TAU * a.achieved.freq_hz,
        phi: a.phase_rad,
    })
    .unwrap();
    for v0 in [-0.02f32, -0.001, 0.001, 0.01, 0.05] {
        let p = d.predict(v0).unwrap();
        let m = exact::solve(&s64, f64::from(v0))
            .unwrap()
            .mu_over_mu0()
            .unwrap();
        assert!(
            (f64::from(p.mu_over_mu0) - m).abs() <= 1e-5,
            "v0={v0}: {} vs {m}",
            p.mu_over_mu0
        );
    }
    assert!(matches!(
        d.predict(f32::NAN),
        Err(DeviceError::OutOfRange {
            param: DriveParam::Velocity,
            ..
        })
    ));
    assert!(d.regime().is_ok());
}

#[test]
fn closed_loop_measurement_agrees_with_prediction() {
    let c = cfg();
    // A simulated plant driven at the DDS rate: the model's forces digitised by
    // the ADC calibrations, fed back per half-buffer like the DMA does.
    let t = SineTable::<1024>::libm();
    let mut d = Device::new(cfg(), &t, CONTACT).unwrap();
    d.set_drive(drive()).unwrap();
    d.start().unwrap();
    let s = d.scene().unwrap();
    let v0 = 0.004f32;
    let pred = d.predict(v0).unwrap();
    let sd = s.drive();
    let d64 = model_core::Drive::new::<Libm>(f64::from(sd.a), f64::from(sd.b), 0.7);
    let v = f64::from(v0) / f64::from(s.velocity_scale());
    let mut buf = vec![0u32; 500];
    // Settle the DAC ramps first (the phase ramp takes ≈ 22 700 samples).
    while !d.status().settled {
        d.fill_dac(0, &mut buf);
        // ADC block n is the output of fill n (as on the board): keep them in step.
        d.adc_block(0, &[]);
    }
    let acc = d.dds().accumulator();
    let tw = d.dds().tuning_word();
    let delta = TAU * f64::from(tw) / 4_294_967_296.0;
    let th0 = TAU * f64::from(acc) / 4_294_967_296.0;
    let mut plant = Stepper::<f64>::new::<Libm>(d64, v, th0, 0.0, delta);
    let (fz0, fx_scale) = (
        f64::from(CONTACT.kz) * 4e-6,
        f64::from(CONTACT.kx) * f64::from(s.w0()),
    );
    let mut half = 0;
    let mut samples = Vec::with_capacity(500);
    let mut first = true;
    // One DMA half-buffer: the plant's forces at the DAC's samples, digitised.
    let mut run_half = |d: &mut Device<'_, 1024>, half: usize| {
        d.fill_dac(half, &mut buf);
        samples.clear();
        for _ in 0..buf.len() {
            let (_, st, w) = if first {
                first = false;
                // θ0 is the phase of the first sample of this half: no step yet.
                let c = th0.cos();
                (
                    c,
                    0.0f64.max(-(1.0 - f64::from(sd.a) * c)),
                    1.0 - f64::from(sd.a) * c,
                )
            } else {
                plant.step()
            };
            let fz = fz0 * w;
            let fx = fx_scale * st;
            samples.push((
                (fx / f64::from(c.adc_x.gain) + f64::from(c.adc_x.offset)).round() as u16,
                (fz / f64::from(c.adc_z.gain) + f64::from(c.adc_z.offset)).round() as u16,
            ));
        }
        d.adc_block(half, &samples);
    };
    // Pre-roll past the plant's transient from s = 0: a clamp in the direction
    // of motion comes within D/(2πV) + 1 periods, D = 2(1 + a + b) = 3.5, V = 0.027
    // (the bound derived in tests/stability.rs), i.e. ≤ 22 periods; 10 halves
    // are 100 periods, after which the discrete plant is exactly periodic.
    for _ in 0..10 {
        run_half(&mut d, half);
        half ^= 1;
    }
    d.measure(400).unwrap();
    assert_eq!(d.measure(10), Err(DeviceError::Busy));
    // The μ loop is refused while a host measurement runs (the estimator is
    // the measurement's), and while the server says it is busy (a stream);
    // accepted once neither holds (its other checks pass: running, a target
    // within ±μ₀).
    let control = board::protocol::ControlSetting {
        on: true,
        target_mu: 0.1,
        v0_m_s: v0,
        gain: 0.7,
        periods: 4,
        rate_m_per_s: 1e-4,
    };
    assert_eq!(d.check_control(&control, false), Err(DeviceError::Busy));
    assert_eq!(d.check_control(&control, true), Err(DeviceError::Busy));
    while d.status().measuring {
        run_half(&mut d, half);
        half ^= 1;
    }
    assert_eq!(d.check_control(&control, true), Err(DeviceError::Busy));
    assert_eq!(d.check_control(&control, false), Ok(()));
    let e = d.estimate().unwrap();
    let measured = f64::from(e.mu) / 0.3;
    // Reference: the same discrete plant (the paper's scheme at the DDS's
    // 50 samples per period, on the same phase grid) in its steady state, by
    // an independent run of the fixed-step scheme. What separates the two is
    // the ADC: each sample rounds by ≤ 0.5 LSB, so the window means of f_x and
    // f_z are off by ≤ 0.5·g_x and 0.5·g_z (g the calibration gains, N/count),
    // and μ = f̄_x/f̄_z by ≤ (0.5g_x + |μ|·0.5g_z)/f̄_z; plus the f32 rounding of
    // μ (2⁻²⁴ relative). In units of μ₀ = 0.3: 5.1e-4 here.
    let mut fcfg = FixedStepConfig::<f64>::new(50);
    fcfg.max_periods = 10_000;
    let steady = run_dimensionless::<f64, Libm>(
        &d64,
        v,
        &fcfg,
        Start::State(State {
            phase: th0,
            stretch: 0.0,
        }),
    )
    .unwrap();
    let (gx, gz) = (f64::from(c.adc_x.gain), f64::from(c.adc_z.gain));
    let mu = f64::from(e.mu);
    let q = ((0.5 * gx + mu.abs() * 0.5 * gz) / f64::from(e.fz_mean) + mu.abs() * 6e-8) / 0.3;
    println!(
        "measured {measured}, plant steady state {} (ADC bound {q:.2e}), predicted {}",
        steady.mu_over_mu0, pred.mu_over_mu0
    );
    assert!(
        (measured - steady.mu_over_mu0).abs() <= q,
        "measured {measured}, plant {} (bound {q:e})",
        steady.mu_over_mu0
    );
    // The plant (50 steps per period) against the device's prediction (the
    // exact solver in f32): the scheme's stated bound (1 + b)(10/N² + Nε) plus
    // the prediction's f32 bound 1e-6(1 + b) (`prediction_in_f32_matches_the_f64_model`).
    let allowed = steady.error_bound + 1e-6 * (1.0 + f64::from(sd.b));
    assert!(
        (steady.mu_over_mu0 - f64::from(pred.mu_over_mu0)).abs() <= allowed,
        "plant {} vs predicted {} (bound {allowed:e})",
        steady.mu_over_mu0,
        pred.mu_over_mu0
    );
    assert!(!e.saturated);
    assert!(e.valid(), "{e:?}");
    // The discrete plant is exactly periodic here (50 samples per period,
    // noiseless): every batch has the same samples, rounded alike, and the
    // window's edges are exact (the same ε at every wrap), so the batches
    // agree and the standard error is 0 up to the f32 rounding of the edge
    // corrections (≤ 2.4e-4 counts on batch sums of ≈ 1e5 counts: < 1e-8).
    assert!(e.std_error < 1e-8, "{e:?}");
}

/// Runs the device's DAC/ADC loop with constant forces (f_x = 2100, f_z = 2000
/// counts) until its measurement closes; returns the estimate.
fn measure_constant(d: &mut Device<'_, 256>, periods: u32) -> board::estimator::Estimate {
    d.measure(periods).unwrap();
    let mut buf = vec![0u32; 500];
    let samples = vec![(2100u16, 2000u16); 500];
    let mut half = 0;
    for _ in 0..100_000 {
        if !d.status().measuring {
            return d.estimate().unwrap();
        }
        d.fill_dac(half, &mut buf);
        d.adc_block(half, &samples);
        half ^= 1;
    }
    panic!("measurement did not close");
}

#[test]
fn estimates_say_why_they_are_not_valid() {
    use board::estimator::reasons;
    let t = SineTable::<256>::libm();
    let mut d = Device::new(cfg(), &t, CONTACT).unwrap();
    d.set_drive(drive()).unwrap();
    // The preload ramps in while stopped: not settled and not running.
    let e = measure_constant(&mut d, 40);
    assert_eq!(
        e.reasons,
        reasons::NOT_RUNNING | reasons::NOT_SETTLED,
        "{e:?}"
    );
    let mut buf = vec![0u32; 500];
    while !d.status().settled {
        d.fill_dac(0, &mut buf);
        // ADC block n is the output of fill n (as on the board): keep them in step.
        d.adc_block(0, &[]);
    }
    // Drive stopped and settled: the window runs on a silent DAC.
    let e = measure_constant(&mut d, 40);
    assert_eq!(e.reasons, reasons::NOT_RUNNING, "{e:?}");
    assert!(!e.valid());
    // Started: the soft start (2000 codes at 1 code/sample) is inside the window.
    d.start().unwrap();
    let e = measure_constant(&mut d, 40);
    assert_eq!(e.reasons, reasons::NOT_SETTLED, "{e:?}");
    // Settled: valid, unless too few periods.
    let e = measure_constant(&mut d, 40);
    assert_eq!(e.reasons, 0, "{e:?}");
    // Constant forces: every batch has the same ratio, σ_μ is 0 up to rounding.
    assert!(e.std_error <= 1e-6, "{e:?}");
    let e = measure_constant(&mut d, 31);
    assert_eq!(e.reasons, reasons::FEW_PERIODS, "{e:?}");
    // A latched fault refuses the measurement, like Start.
    d.fault(faults::EXTERNAL);
    assert_eq!(d.measure(40), Err(DeviceError::Faulted(faults::EXTERNAL)));
}

/// A board whose normal transducer reaches 2.048 µm below the surface
/// (`zero_code` 1024 of 2 nm/code), so that a drive may lift the contact off.
fn cfg_with_retract() -> DeviceConfig {
    let mut c = cfg();
    c.dac_z.zero_code = 1024.0;
    c
}

/// Δu_z = 1.5·u_z0 (a = 1.5): lifts off; within the DAC's reach (2 µm offset
/// + 2.048 µm below the surface) and headroom ((4095 − 1024)·2 nm − 2 µm).
fn liftoff_drive() -> DriveSetting {
    DriveSetting {
        amp_z_m: 3e-6,
        offset_z_m: 2e-6,
        ..drive()
    }
}

#[test]
fn liftoff_is_refused_until_allowed_and_refusals_change_nothing() {
    let t = SineTable::<1024>::libm();
    let mut d = Device::new(cfg_with_retract(), &t, CONTACT).unwrap();
    d.set_drive(drive()).unwrap();
    d.start().unwrap();
    let mut buf = [0u32; 256];
    for _ in 0..10 {
        d.fill_dac(0, &mut buf);
    }
    let snapshot = |d: &Device<'_, 1024>| {
        (
            d.drive(),
            d.applied(),
            *d.dds().channels(),
            d.dds().tuning_word(),
            d.status(),
        )
    };
    let before = snapshot(&d);
    assert!(!before.4.liftoff_allowed, "power-up state: refuse");
    // Default: refused with the limit (1 − 0.05)·2 µm = 1.9 µm, nothing changed.
    match d.set_drive(liftoff_drive()) {
        Err(DeviceError::LiftOff { amp_z_m, limit_m }) => {
            assert_eq!(amp_z_m, 3e-6);
            assert!((limit_m - 1.9e-6).abs() < 1e-12, "{limit_m}");
        }
        other => panic!("{other:?}"),
    }
    assert_eq!(snapshot(&d), before);
    // Allowed on purpose: accepted.
    assert!(!d.liftoff_allowed(), "refused at power-up");
    d.set_liftoff_allowed(true).unwrap();
    assert!(d.status().liftoff_allowed);
    assert!(d.liftoff_allowed());
    d.set_drive(liftoff_drive()).unwrap();
    assert_eq!(d.drive(), liftoff_drive());
    let accepted = snapshot(&d);
    // Beyond the DAC's reach below the surface (offset + 2.048 µm, f32): out of
    // range with that limit, nothing changed.
    match d.set_drive(DriveSetting {
        amp_z_m: 4.1e-6,
        ..liftoff_drive()
    }) {
        Err(DeviceError::OutOfRange {
            param: DriveParam::AmpZ,
            max,
            ..
        }) => assert!((max - 4.048e-6).abs() < 1e-12, "{max}"),
        other => panic!("{other:?}"),
    }
    assert_eq!(snapshot(&d), accepted);
    // A zero offset still takes no normal amplitude.
    assert!(matches!(
        d.set_drive(DriveSetting {
            offset_z_m: 0.0,
            ..liftoff_drive()
        }),
        Err(DeviceError::LiftOff { .. })
    ));
    assert_eq!(snapshot(&d), accepted);
    // Refusing again while the accepted drive is above the limit: refused,
    // nothing changed (still allowed).
    assert!(matches!(
        d.set_liftoff_allowed(false),
        Err(DeviceError::LiftOff { .. })
    ));
    assert_eq!(snapshot(&d), accepted);
    // With a drive within the limit the guard comes back and holds again.
    d.set_drive(drive()).unwrap();
    d.set_liftoff_allowed(false).unwrap();
    assert!(!d.status().liftoff_allowed);
    assert!(!d.liftoff_allowed());
    assert!(matches!(
        d.set_drive(liftoff_drive()),
        Err(DeviceError::LiftOff { .. })
    ));
}

#[test]
fn with_liftoff_allowed_predict_uses_the_liftoff_model() {
    use model_core::model::liftoff;
    let t = SineTable::<1024>::libm();
    let mut d = Device::new(cfg_with_retract(), &t, CONTACT).unwrap();
    d.set_liftoff_allowed(true).unwrap();
    // Within the limit the permanent-contact solver still answers.
    d.set_drive(drive()).unwrap();
    let p = d.predict(0.004).unwrap();
    assert!(!p.liftoff);
    d.set_drive(liftoff_drive()).unwrap();
    // The independent reference: the fixed-step scheme with exact landing
    // (liftoff::stepping, f64, N = 20 000 steps per period) on the very scene the
    // device formed (its f32 parameters, widened exactly to f64).
    let s32 = d.scene().unwrap();
    let p32 = *s32.params();
    let s64 = Scene::new_with_contact(
        SceneParams {
            mu0: f64::from(p32.mu0),
            kz: f64::from(p32.kz),
            kx: f64::from(p32.kx),
            uz0: f64::from(p32.uz0),
            duz: f64::from(p32.duz),
            dux: f64::from(p32.dux),
            omega: f64::from(p32.omega),
            phi: f64::from(p32.phi),
        },
        model_core::scene::ContactMode::Intermittent,
    )
    .unwrap();
    assert!((s64.drive().a - 1.5).abs() < 1e-6);
    // Tolerance: the stepping's stated bound plus the f32 lift-off solver's
    // stated bound with FastF32 (liftoff::error_bound: precision constant +
    // the backend's error, times 1 + a + b).
    let dev_bound = f64::from(liftoff::error_bound::<f32, model_core::FastF32>(
        &s32.drive(),
    ));
    let scale = s64.velocity_scale();
    for v0 in [-0.02f32, -0.003, 0.0, 0.002, 0.01] {
        let p = d.predict(v0).unwrap();
        assert!(p.liftoff, "v0 = {v0}");
        let v = f64::from(v0) / scale;
        let r = liftoff::stepping::mu_over_mu0::<f64, Libm>(&s64.drive(), v, 20_000).unwrap();
        let tol = r.error_bound + dev_bound;
        let got = f64::from(p.mu_over_mu0);
        assert!(
            (got - r.mu_over_mu0).abs() <= tol,
            "v0 = {v0}: device {got} vs stepping {} (tol {tol:.2e})",
            r.mu_over_mu0
        );
        // μ is continuous at rest with lift-off: one value on both sides.
        assert_eq!(p.mu_0minus_over_mu0, p.mu_over_mu0);
        assert!((f64::from(p.mu) - 0.3 * got).abs() <= 1e-7 * got.abs().max(1.0));
    }
    // Critical velocities: eq. L5 of the contact window, in m/s (f64 reference).
    let (cf, cb) = liftoff::critical_velocities::<f64, Libm>(&s64.drive()).unwrap();
    let p = d.predict(0.0).unwrap();
    for (got, want) in [(p.vc.0, cf * scale), (p.vc.1, cb * scale)] {
        // f32: a few ulps of the trig (FastF32 ≤ 3e-7) and the scaling.
        assert!(
            (f64::from(got) - want).abs() <= 1e-6 * want.abs().max(1e-9),
            "{got} vs {want}"
        );
    }
    assert!(d.regime().is_ok());
}

#[test]
fn the_prediction_follows_every_change_of_contact_drive_and_liftoff_setting() {
    // The device takes its scene's parameters when one of them changes (the
    // scene is formed from them per Predict, outside the device's critical
    // section): each change must show in the next prediction. Reference: the f64 exact
    // solver on the changed scene; 1e-5 as in prediction_in_f32_matches_the_f64_model.
    let t = SineTable::<256>::libm();
    let mut d = Device::new(cfg(), &t, CONTACT).unwrap();
    let want = |mu0: f64, drive: &DriveSetting, a: &board::device::Applied| {
        let s = Scene::new(SceneParams {
            mu0,
            kz: 1e7,
            kx: 1e7,
            uz0: f64::from(drive.offset_z_m),
            duz: f64::from(drive.amp_z_m),
            dux: f64::from(drive.amp_x_m),
            omega: TAU * a.achieved.freq_hz,
            phi: a.phase_rad,
        })
        .unwrap();
        mu0 * exact::solve(&s, 0.004).unwrap().mu_over_mu0().unwrap()
    };
    // No drive yet (zero offset): no scene.
    assert!(matches!(d.predict(0.004), Err(DeviceError::Scene(_))));
    let a = d.set_drive(drive()).unwrap();
    let got = f64::from(d.predict(0.004).unwrap().mu);
    assert!((got - want(0.3, &drive(), &a)).abs() <= 1e-5);
    d.set_contact(Contact {
        mu0: 0.24,
        ..CONTACT
    })
    .unwrap();
    let got = f64::from(d.predict(0.004).unwrap().mu);
    assert!((got - want(0.24, &drive(), &a)).abs() <= 1e-5, "{got}");
    let other = DriveSetting {
        amp_x_m: 0.5e-6,
        phase_rad: 1.9,
        ..drive()
    };
    let a = d.set_drive(other).unwrap();
    let got = f64::from(d.predict(0.004).unwrap().mu);
    assert!((got - want(0.24, &other, &a)).abs() <= 1e-5, "{got}");
    // A refused change changes nothing, the prediction included.
    let before = d.predict(0.004).unwrap();
    assert!(d
        .set_contact(Contact {
            mu0: -1.0,
            ..CONTACT
        })
        .is_err());
    assert!(d
        .set_drive(DriveSetting {
            amp_z_m: 3.9e-6,
            ..other
        })
        .is_err());
    assert_eq!(d.predict(0.004).unwrap(), before);
    // The lift-off setting: same drive, same (permanent-contact) prediction.
    d.set_liftoff_allowed(true).unwrap();
    assert_eq!(d.predict(0.004).unwrap(), before);
}
