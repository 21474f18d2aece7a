//! The displacement mode (`board::device::displacement`) on
//! resonant transducers (`plant::Resonant`), checked against the plant's
//! own state, not the device's lock-in: after each half-buffer the true
//! motion of each mode is read from its state (x, ẋ) — for a motion
//! `x = A cos(ωt + ψ)`, `A = √(x² + (ẋ/ω)²)` and `ωt + ψ = atan2(−ẋ/ω, x)` —
//! so φ between the modes is `ψ_x − ψ_z + π` (eq. M1) with the common time
//! cancelling.
//!
//! Bench: 20 kHz drive (1.5 % off both resonances: 20 300 Hz, Q 300 normal;
//! 19 700 Hz, Q 200 tangential; contact load Q 2000), Δu_z = 2 µm,
//! Δu_x = 0.3 µm, u_z0 = 4 µm, φ = 40°, the board's calibrations, pickups
//! without noise (the ADC's rounding only). The device's model is wrong on
//! purpose (unless stated): f_r 20 Hz high (normal) and 15 Hz low
//! (tangential), Q 10 % low, gain 5 % high — a feed-forward error of
//! ≈ 10 % that only the loop removes.
//!
//! Tolerances: the loop holds the smoothed lock-in's phasor within
//! `HOLD_TOLERANCE` (0.4 %) of the setting; the lock-in's own error on a
//! noiseless pickup is the rounding to ±½ count (5 nm/count): at most
//! ½ count / amplitude, 0.13 % of 2 µm and 0.83 % of 0.3 µm for a single
//! sample, its average over a window's 64 samples smaller by √(64/2) ≈ 5.7
//! (uniform, independent): 0.15 % at 0.3 µm. So the true amplitude is
//! within `0.4 % + 3·0.15 %` ≤ 0.85 % of Δu_x and 0.5 % of Δu_z, and φ
//! within the arcsine of the sum of the two channels' relative errors.

use board::dds::SineTable;
use board::device::displacement::SMOOTHING_S;
use board::device::{
    faults, Contact, Device, DeviceConfig, DriveMode, DriveSetting, TransducerModel, Transducers,
};
use integration_tests::resonant::{exact_model, model_of, opts, setting, true_modes, Bench, MU0};
use std::f64::consts::{PI, TAU};

fn wrong_model() -> Transducers {
    let m = true_modes();
    Transducers {
        z: model_of(m[0], 20.0, 0.9, 1.05),
        x: model_of(m[1], -15.0, 0.9, 1.05),
    }
}

/// ½ count of the pickup over `amp` metres, averaged over a window's 64
/// samples (module docs), three standard deviations.
fn rounding(amp: f64) -> f64 {
    3.0 * 0.5 * 5e-9 / amp / (64.0f64 / 2.0).sqrt()
}

/// The true motion over `n` halves, checked against the setting, from 10
/// smoothing times (`SMOOTHING_S`, 1 ms) after the call: the status'
/// smoothed phasor, which the holding test reads, lags the motion by about
/// one smoothing time while the loop still converges (seen: 0.55 % on Δu_z
/// at the moment the device first holds, 0.05 % 10 ms later).
fn check_holds(b: &mut Bench<'_>, s: &DriveSetting, n: usize) {
    let lag = (10.0 * f64::from(SMOOTHING_S) / b.t_half()).ceil() as usize;
    for _ in 0..lag {
        b.step();
    }
    // The holding tolerance as documented (docs/transducers.md: within 0.4 %
    // of the setting), not the implementation's constant.
    let tol = 0.004;
    let (ez, ex) = (
        tol + rounding(f64::from(s.amp_z_m)),
        tol + rounding(f64::from(s.amp_x_m)),
    );
    let ephi = (ez + ex).asin();
    let (mut worst_z, mut worst_x, mut worst_phi) = (0.0f64, 0.0f64, 0.0f64);
    for _ in 0..n {
        let t = b.step();
        worst_z = worst_z.max((t.amp_z / f64::from(s.amp_z_m) - 1.0).abs());
        worst_x = worst_x.max((t.amp_x / f64::from(s.amp_x_m) - 1.0).abs());
        worst_phi = worst_phi.max((t.phi - f64::from(s.phase_rad)).abs());
        if std::env::var("DEBUG_DISP").is_ok() {
            let m = b.dev.status().measured.unwrap();
            eprintln!(
                "true {:.5e} {:.5e} {:.3} | lock-in {:.5e} {:.5e} {:.3}",
                t.amp_z,
                t.amp_x,
                t.phi.to_degrees(),
                m.amp_z_m,
                m.amp_x_m,
                m.phase_rad.to_degrees()
            );
        }
    }
    assert!(
        worst_z <= ez,
        "Δu_z off by {worst_z:.2e} (allowed {ez:.2e})"
    );
    assert!(
        worst_x <= ex,
        "Δu_x off by {worst_x:.2e} (allowed {ex:.2e})"
    );
    assert!(
        worst_phi <= ephi,
        "φ off by {:.3}° (allowed {:.3}°)",
        worst_phi.to_degrees(),
        ephi.to_degrees()
    );
}

/// Start on the detuned pair with a 10 %-wrong model: the drive holds the
/// setting (true amplitudes and φ), within a time bounded by the dead-beat
/// start within the default headroom h = 2 (the model's envelope reaches the
/// setting in `τ̂·ln(h/(h − 1))` = 0.69 τ̂, `displacement` D5) plus the
/// loop's convergence, and the normal excursion stays below the lift-off
/// limit on the way.
#[test]
fn the_loop_holds_the_measured_drive_despite_a_wrong_model() {
    let table = SineTable::<1024>::libm();
    let mut b = Bench::new(&table, opts(), wrong_model());
    let s = setting(2e-6);
    b.dev.set_drive(s).unwrap();
    b.dev.start().unwrap();
    let (halves, peak) = b.until_settled(20_000);
    let t_ms = halves as f64 * b.t_half() * 1e3;
    // τ̂ of the slower (normal) model: Q̂/(π f̂_r).
    let tau_hat = f64::from(wrong_model().z.q) / (PI * f64::from(wrong_model().z.resonance_hz));
    // The start, 0.69 τ̂, then a critically damped loop of time constant
    // 2τ̂ bringing a ≤ 15 % error within 0.4 %: (1 + t/2τ̂)e^{−t/2τ̂} ≤ 0.4/15
    // at t = 2τ̂·6.0; with 20 % slack.
    let bound_ms = 1.2 * (2f64.ln() + 12.0) * tau_hat * 1e3;
    eprintln!("settled after {t_ms:.1} ms (bound {bound_ms:.1} ms), peak Δu_z {peak:.3e} m");
    assert!(t_ms <= bound_ms, "{t_ms} ms > {bound_ms} ms");
    let limit = f64::from(b.cfg.liftoff_limit_m(s.offset_z_m));
    assert!(peak < limit, "peak {peak:e} ≥ lift-off limit {limit:e}");
    check_holds(&mut b, &s, 400);
    assert_eq!(b.dev.status().faults, 0);
    // Holding in displacement mode, a prediction takes the measured drive
    // (`Device::prediction_inputs`): Status' amplitudes and φ, the
    // setting's offset, ω = 2π·f of the DDS (f32: a part in 10⁷).
    let st = b.dev.status();
    let m = st.measured.unwrap();
    let p = b.dev.prediction_inputs().params;
    assert_eq!(
        (p.duz, p.dux, p.phi, p.uz0),
        (m.amp_z_m, m.amp_x_m, m.phase_rad, s.offset_z_m)
    );
    let omega = 2.0 * PI * f64::from(st.frequency_hz);
    assert!(
        (f64::from(p.omega) / omega - 1.0).abs() <= 1e-6,
        "ω {} vs {omega}",
        p.omega
    );
}

/// A setpoint step after the loop has learned the model's error: the new
/// amplitude is met without learning again (the correction c is kept),
/// faster than the first start, and the excursion stays within the
/// dead-beat's bound: the model's envelope never passes the larger of the
/// old and new settings (`displacement` docs), so the true one passes it
/// only by the model's dynamics error over the transition — here τ̂ 10 %
/// short and ω̂_r − ω 20 Hz off 300 Hz (7 %): at most ≈ 10 % of the 1 µm
/// step before the observer (D7) takes it out.
#[test]
fn a_setpoint_step_is_met_within_the_headroom() {
    let table = SineTable::<1024>::libm();
    let mut b = Bench::new(&table, opts(), wrong_model());
    b.dev.set_drive(setting(2e-6)).unwrap();
    b.dev.start().unwrap();
    let (first, _) = b.until_settled(20_000);
    check_holds(&mut b, &setting(2e-6), 100);
    let s = setting(3e-6);
    b.dev.set_drive(s).unwrap();
    let (second, peak) = b.until_settled(20_000);
    eprintln!("first settle {first} halves, after the step {second} halves, peak {peak:e}");
    assert!(second < first, "{second} ≥ {first}");
    let bound = 3e-6 + 0.1 * 1e-6;
    assert!(peak <= bound, "peak {peak:e} > {bound:e}");
    check_holds(&mut b, &s, 400);
}

/// The resonance drifts (−20 Hz/s on the normal mode, the rate of the
/// issue's bench) and the model's Q is a third too high (τ̂ > τ: the loop
/// is overdamped, never oscillatory): the loop keeps the true motion on
/// the setting throughout.
#[test]
fn the_loop_follows_a_drifting_resonance_and_a_wrong_q() {
    let table = SineTable::<1024>::libm();
    let mut o = opts();
    o.drift_hz_per_s = [-20.0, 0.0];
    let m = true_modes();
    let model = Transducers {
        z: model_of(m[0], 0.0, 1.33, 1.0),
        x: model_of(m[1], 0.0, 1.33, 1.0),
    };
    let mut b = Bench::new(&table, o, model);
    let s = setting(2e-6);
    b.dev.set_drive(s).unwrap();
    b.dev.start().unwrap();
    b.until_settled(20_000);
    // 2 s of drift: 40 Hz, the normal mode's response at 20 kHz grows by
    // ≈ 15 % (detuning 300 → 260 Hz); per loop time constant 4τ̂ ≈ 22 ms
    // that is 0.16 %, which the integrator trails by: within tolerance.
    let halves = (2.0 / b.t_half()) as usize;
    check_holds(&mut b, &s, halves);
    assert_eq!(b.dev.status().faults, 0);
}

/// A model whose gain is half the true one asks for twice the voltage:
/// the normal mode rises to 4.2 µm, past the 4 µm offset, during the ramp
/// (before the loop acts), and the guard on the *measured* motion latches
/// `MEASURED_LIFTOFF`, which brings the drive to the safe state. (2.1 µm
/// is within the setting's lift-off limit, 3.8 µm, and the model's DAC
/// range, ≈ 2.18 µm at this gain.)
#[test]
fn a_measured_excursion_beyond_the_offset_latches_the_safe_state() {
    let table = SineTable::<1024>::libm();
    let m = true_modes();
    let model = Transducers {
        z: model_of(m[0], 0.0, 1.0, 0.5),
        x: model_of(m[1], 0.0, 1.0, 1.0),
    };
    let mut b = Bench::new(&table, opts(), model);
    b.dev.set_drive(setting(2.1e-6)).unwrap();
    b.dev.start().unwrap();
    let mut latched_at = None;
    for k in 0..5_000 {
        b.step();
        if b.dev.status().faults != 0 {
            latched_at = Some(k);
            break;
        }
    }
    let st = b.dev.status();
    assert_eq!(
        st.faults,
        faults::MEASURED_LIFTOFF,
        "{st:?} after {latched_at:?}"
    );
    assert!(!st.running);
    // The safe state: the outputs ramp to zero displacement.
    for _ in 0..5_000 {
        b.step();
    }
    let st = b.dev.status();
    assert_eq!(
        (st.out_amp_z_m, st.out_amp_x_m, st.out_offset_z_m),
        (0.0, 0.0, 0.0)
    );
    assert!(b.dev.start().is_err());
}

/// Without transducers the displacement mode is refused by name, and the
/// refusal changes nothing.
#[test]
fn the_displacement_mode_needs_transducers() {
    let table = SineTable::<1024>::libm();
    let cfg = DeviceConfig::driver_board(0);
    let contact = Contact {
        mu0: 0.3,
        kz: 1e7,
        kx: 1e7,
    };
    let mut dev = Device::new(cfg, &table, contact).unwrap();
    assert_eq!(
        dev.set_drive_mode(DriveMode::Displacement),
        Err(board::device::DeviceError::NotIdentified)
    );
    assert_eq!(dev.drive_mode(), DriveMode::OpenLoop);
    let bad = TransducerModel {
        resonance_hz: 20_000.0,
        q: 0.4,
        gain_m_per_v: 1e-7,
        phase_lag_rad: 0.0,
    };
    let e = dev
        .set_transducers(Some(Transducers { z: bad, x: bad }))
        .unwrap_err();
    assert!(e.to_string().starts_with("q out of range"), "{e}");
    assert_eq!(dev.transducers(), None);
}

/// The closed μ loop on top of the displacement loops: its commands of
/// Δu_z become displacement setpoints (the voltage through the model and
/// the learned correction), and it holds the measured μ at a setpoint the
/// device's model reaches — here μ* = the model's μ at Δu_z = 1.5 µm (the
/// device's contact is the plant's, so the loop should settle near
/// Δu_z = 1.5 µm, and the *true* normal amplitude there).
///
/// Bound: the estimate's error on noiseless forces (ADC rounding only,
/// 0.02 N and 0.01 N per count against f_z ≈ 40 N, f_x ≈ 4 N: ≈ 1e-3 of μ
/// per sample, averaged over a 4-period estimate's 100 samples) and the
/// fixed-step plant's μ error (≈ 10·(1+b)/N², N = 100 sub-steps a period:
/// 2e-3·μ₀): 1 % of μ; the amplitude follows μ through ∂μ/∂Δu_z, so within
/// 1 % · μ/(Δu_z·|∂μ/∂Δu_z|) ≈ 3 % of 1.5 µm.
#[test]
fn the_mu_loop_runs_on_the_displacement_loops() {
    use board::control;
    use board::protocol::ControlSetting;
    let table = SineTable::<1024>::libm();
    let mut b = Bench::new(&table, opts(), wrong_model());
    b.dev.set_drive(setting(2e-6)).unwrap();
    b.dev.start().unwrap();
    b.until_settled(20_000);
    // The target: the model's μ at Δu_z = 1.5 µm and 4 mm/s.
    let scene15 = model_core::Scene::new(model_core::SceneParams {
        mu0: MU0 as f32,
        kz: 1e7,
        kx: 1e7,
        uz0: 4e-6,
        duz: 1.5e-6,
        dux: 0.3e-6,
        omega: (TAU * 20_000.0) as f32,
        phi: 40f32.to_radians(),
    })
    .unwrap();
    let target = board::device::predict(&scene15, 0.004).unwrap().mu;
    let s = ControlSetting {
        on: true,
        target_mu: target,
        v0_m_s: 0.004,
        gain: 0.7,
        periods: 4,
        rate_m_per_s: 1e-3,
    };
    b.dev.check_control(&s, false).unwrap();
    let (inputs, now, limit) = b.dev.control_plan_inputs();
    let scene = inputs.scene().unwrap();
    let plan = control::plan(&scene, s.target_mu, s.v0_m_s, now, limit).unwrap();
    b.dev.set_control(s, Some(plan)).unwrap();
    // 0.5 s of loop.
    let mut last = None;
    for _ in 0..(0.5 / b.t_half()) as usize {
        last = Some(b.step());
    }
    let st = b.dev.control_state();
    let t = last.unwrap();
    eprintln!(
        "target {target}, measured {}, command {:e}, true Δu_z {:e}, updates {}",
        st.last.measured_mu, st.last.amp_z_m, t.amp_z, st.last.update
    );
    assert!(st.setting.on && st.last.update > 10, "{st:?}");
    assert!(
        (st.last.measured_mu / target - 1.0).abs() <= 0.01,
        "{} vs {target}",
        st.last.measured_mu
    );
    assert!(
        (t.amp_z / 1.5e-6 - 1.0).abs() <= 0.03,
        "true Δu_z {:e}",
        t.amp_z
    );
    assert_eq!(b.dev.status().faults, 0);
}

/// Anti-windup of the closed μ loop on the displacement loops: driven far
/// below the normal resonance the DAC reaches only a small Δu_z (the
/// model's largest displacement there, which `set_drive` names in its
/// refusal); a setpoint that needs more makes the loop command past it.
/// Each refused command puts the controller back on the amplitude in force
/// (`Controller::refused`, its trim with it), is reported (`saturated`), and
/// the loop goes on updating — it neither stalls nor winds up: once the
/// setpoint is reachable again it settles as from a fresh start (within
/// 1 % of μ*, the bound of `the_mu_loop_runs_on_the_displacement_loops`).
#[test]
fn the_mu_loop_holds_a_command_the_dac_cannot_take() {
    use board::control;
    use board::device::DeviceError;
    use board::protocol::ControlSetting;
    let table = SineTable::<1024>::libm();
    let m = true_modes();
    let exact = exact_model(m);
    let mut b = Bench::new(&table, opts(), exact);
    // The frequency where the model's largest Δu_z is about 1.5 µm.
    let mut s = setting(3e-6);
    let mut reach = 0.0f32;
    for f in (12_000..20_000).rev().step_by(100) {
        s.freq_hz = f64::from(f);
        match b.dev.set_drive(s) {
            Err(DeviceError::OutOfRange { max, .. }) if max < 1.5e-6 => {
                reach = max;
                break;
            }
            _ => {}
        }
    }
    assert!(reach > 0.5e-6, "no frequency found: {reach}");
    s.amp_z_m = 0.5 * reach;
    b.dev.set_drive(s).unwrap();
    b.dev.start().unwrap();
    b.until_settled(40_000);
    let scene_at = |duz: f32| {
        model_core::Scene::new(model_core::SceneParams {
            mu0: MU0 as f32,
            kz: 1e7,
            kx: 1e7,
            uz0: 4e-6,
            duz,
            dux: 0.3e-6,
            omega: (TAU * s.freq_hz) as f32,
            phi: 40f32.to_radians(),
        })
        .unwrap()
    };
    let mu_at = |duz: f32| board::device::predict(&scene_at(duz), 0.004).unwrap().mu;
    let run = |b: &mut Bench<'_>, target: f32, secs: f64| {
        let c = ControlSetting {
            on: true,
            target_mu: target,
            v0_m_s: 0.004,
            gain: 0.7,
            periods: 4,
            rate_m_per_s: 1e-3,
        };
        let (inputs, now, limit) = b.dev.control_plan_inputs();
        let scene = inputs.scene().unwrap();
        let plan = control::plan(&scene, c.target_mu, c.v0_m_s, now, limit).unwrap();
        b.dev.set_control(c, Some(plan)).unwrap();
        let (mut saturated, mut max_cmd) = (0u32, 0.0f32);
        let mut seen = 0;
        for _ in 0..(secs / b.t_half()) as usize {
            b.step();
            let st = b.dev.control_state();
            if st.last.update != seen {
                seen = st.last.update;
                saturated += u32::from(st.last.saturated);
                max_cmd = max_cmd.max(b.dev.drive().amp_z_m);
            }
        }
        (b.dev.control_state(), saturated, max_cmd)
    };
    // Out of reach: the setpoint of Δu_z = 1.5·reach.
    let (st, saturated, max_cmd) = run(&mut b, mu_at(1.5 * reach), 0.2);
    eprintln!(
        "reach {reach:e} at {} Hz: updates {}, saturated {saturated}, largest applied {max_cmd:e}",
        s.freq_hz, st.last.update
    );
    assert!(st.last.update > 50, "the loop stalled: {st:?}");
    assert!(saturated > 0, "{st:?}");
    assert!(max_cmd <= reach, "{max_cmd:e} applied beyond {reach:e}");
    assert_eq!(b.dev.status().faults, 0);
    // Reachable again: no wound-up trim to unwind.
    let target = mu_at(0.6 * reach);
    let (st, _, _) = run(&mut b, target, 0.2);
    assert!(
        (st.last.measured_mu / target - 1.0).abs() <= 0.01,
        "{} vs {target}",
        st.last.measured_mu
    );
}

/// Steps the bench `n` halves after the normal pickup's gain became `g`:
/// the largest relative error of the smoothed normal amplitude the status
/// reports, and whether the drive held at every half.
fn gain_step(b: &mut Bench<'_>, s: &DriveSetting, g: f64, n: usize) -> (f64, bool) {
    b.pickup_gain[0] = g;
    let z = f64::from(s.amp_z_m);
    run_held(b, n, |m| (f64::from(m.amp_z_m) / z - 1.0).abs())
}

/// `n` half-buffers: the largest of `err` over the measured drive, and
/// whether the drive stayed held throughout.
fn run_held(
    b: &mut Bench<'_>,
    n: usize,
    err: impl Fn(&board::protocol::MeasuredDrive) -> f64,
) -> (f64, bool) {
    let (mut worst, mut held) = (0.0f64, true);
    for _ in 0..n {
        b.step();
        let st = b.dev.status();
        worst = worst.max(err(&st.measured.expect("a window measured")));
        held &= st.settled;
    }
    (worst, held)
}

/// Hysteresis of the hold (`displacement::RELEASE_TOLERANCE`): a held drive
/// is released only when a channel's smoothed error leaves 0.8 % (twice the
/// 0.4 % it must reach to hold), so the smoothed error's noise (σ ≈ 0.08 %
/// at 0.3 µm, docs/protocol.md) never releases it during a measurement. A
/// step of the tangential pickup's gain is a measured error the loop then
/// removes (D3, time constant 4τ̂ ≈ 12 ms): a 0.6 % step takes the smoothed
/// error above 0.4 % and keeps it below 0.8 % — still held (a hold without
/// hysteresis is released); a 2 % step takes it above 0.8 % — released,
/// and held again once the loop has learned the new gain.
#[test]
fn a_held_drive_is_released_only_beyond_twice_the_hold_tolerance() {
    let table = SineTable::<1024>::libm();
    let mut b = Bench::new(&table, opts(), exact_model(true_modes()));
    let s = setting(2e-6);
    b.dev.set_drive(s).unwrap();
    b.dev.start().unwrap();
    b.until_settled(20_000);
    let t_half = b.t_half();
    let halves = |ms: f64| (ms * 1e-3 / t_half).ceil() as usize;
    let (n20, n60) = (halves(20.0), halves(60.0));
    // The loop converges on from the first hold (check_holds); 20 ms
    // later the smoothed error is the rounding's.
    let _ = gain_step(&mut b, &s, 1.0, n20);
    let (calm, held) = gain_step(&mut b, &s, 1.0, n20);
    assert!(
        held && calm < 0.002,
        "before the steps: {calm:.2e}, held {held}"
    );
    // The documented bounds (docs/protocol.md), not the constants.
    let (hold, release) = (0.004, 0.008);
    let (w, held) = gain_step(&mut b, &s, 1.007, n20);
    assert!(
        w > hold && w < release && held,
        "0.7 % step: smoothed error {w:.2e} (expected in ({hold}, {release})), held {held}"
    );
    let _ = gain_step(&mut b, &s, 1.0, n60);
    let (w, held) = gain_step(&mut b, &s, 1.02, n20);
    assert!(
        w > release && !held,
        "2 % step: smoothed error {w:.2e} (expected above {release}), held {held}"
    );
    // Held again once the loop has learned the new gain.
    b.until_settled(halves(100.0));
}

/// Steps the bench `n` halves with the plant's cross-talk at `k` (a
/// fraction of the normal channel's voltage driving the tangential mode):
/// the largest smoothed tangential amplitude the status reports, m, and
/// whether the drive held at every half.
fn crosstalk_step(b: &mut Bench<'_>, k: f64, n: usize) -> (f64, bool) {
    b.plant
        .resonant
        .as_mut()
        .expect("resonant plant")
        .opts
        .crosstalk = k;
    run_held(b, n, |m| f64::from(m.amp_x_m))
}

/// A bench with `model` driving `s`, started and run until it holds; with
/// the half-buffers of 20 ms (the tests' observation span).
fn held(table: &SineTable<1024>, model: Transducers, s: DriveSetting) -> (Bench<'_>, usize) {
    let mut b = Bench::new(table, opts(), model);
    b.dev.set_drive(s).unwrap();
    b.dev.start().unwrap();
    b.until_settled(20_000);
    let n = (20e-3 / b.t_half()).ceil() as usize;
    (b, n)
}

/// The hysteresis of an undriven channel (`displacement::RELEASE_FLOOR_M`):
/// with Δu_x = 0 the tangential channel holds while its smoothed amplitude
/// is below 2e-8 m and, once held, is released only above 4e-8 m. The
/// plant's cross-talk from the normal channel moves the undriven mode (the
/// loop does not correct an undriven channel): its amplitude is linear in
/// the cross-talk, so one step at `k₀` = 0.01 calibrates it, and steps to 3e-8 m
/// (held) and 6e-8 m (released) follow.
#[test]
fn an_undriven_channel_is_released_only_beyond_twice_the_floor() {
    let table = SineTable::<1024>::libm();
    let s = DriveSetting {
        amp_x_m: 0.0,
        ..setting(2e-6)
    };
    let (mut b, n) = held(&table, exact_model(true_modes()), s);
    let (calm, held) = crosstalk_step(&mut b, 0.0, n);
    assert!(
        held && calm < 1e-8,
        "undriven, no cross-talk: {calm:e} m, held {held}"
    );
    // Calibration, below the hold floor.
    let k0 = 1e-2;
    let (x0, held) = crosstalk_step(&mut b, k0, n);
    assert!(
        held && x0 > 2e-9 && x0 < 2e-8,
        "k {k0}: {x0:e} m, held {held}"
    );
    let (hold_floor, release_floor) = (2e-8, 4e-8); // docs/protocol.md
    let (x, held) = crosstalk_step(&mut b, k0 * 3e-8 / x0, n);
    assert!(
        x > hold_floor && x < release_floor && held,
        "3e-8 m wanted: {x:e} m (expected in ({hold_floor:e}, {release_floor:e})), held {held}"
    );
    let (x, held) = crosstalk_step(&mut b, k0 * 6e-8 / x0, n);
    assert!(
        x > release_floor && !held,
        "6e-8 m wanted: {x:e} m (expected above {release_floor:e}), held {held}"
    );
}

/// The reach a refusal reports uses the learned correction c (D2): with
/// the 10 %-wrong model, once the loop holds, the largest tangential
/// displacement `SetDrive` accepts is the plant's own — the DAC's room
/// around the channel's DC times its volts per code times the true
/// response |X/U|, read from the plant's state (true amplitude over the
/// DDS's amplitude) — within the hold's 0.4 % and the lock-in's rounding
/// (module docs), 1 % in all. The drive is at 20.5 kHz, 4 % above the
/// tangential resonance, where that reach (≈ 0.8 µm) is below the
/// calibration's own limit on Δu_x; half that reach is accepted with the
/// voltage the plant needs for it. Measured: −2.2e-4; a plan that divided
/// by c instead of multiplying (a mutant the suite let through) +6.4 %.
#[test]
fn the_reach_of_a_new_setting_is_the_plants_once_learned() {
    let table = SineTable::<1024>::libm();
    let s = DriveSetting {
        freq_hz: 20_500.0,
        ..setting(2e-6)
    };
    let (mut b, n) = held(&table, wrong_model(), s);
    for _ in 0..n {
        b.step();
    }
    let t = b.step();
    let ch = b.dev.dds().channels()[1];
    let v = board::dds::DAC_VOLTS_PER_CODE;
    let h_true = t.amp_x / (f64::from(ch.amp) * v);
    let room = f64::from(ch.dc.min(4095.0 - ch.dc));
    let reach = room * v * h_true;
    assert!(reach < 0.9 * f64::from(DeviceConfig::driver_board(1).max_amp_x_m()));
    // Beyond the plant's reach, within the calibration's limit.
    let far = DriveSetting {
        amp_x_m: 1.5e-6,
        ..s
    };
    match b.dev.set_drive(far) {
        Err(board::device::DeviceError::OutOfRange { max, .. }) => {
            let rel = f64::from(max) / reach - 1.0;
            println!("reach {max:e} m vs the plant's {reach:e} m: {rel:+.2e}");
            assert!(rel.abs() <= 0.01, "reach {max:e} vs {reach:e} ({rel:+.2e})");
        }
        other => panic!("1.5 µm accepted or refused otherwise: {other:?}"),
    }
    // Half the reach is accepted, and its planned voltage (the DDS's target
    // before the next fill's dead-beat level) is the setting over the
    // plant's response, within the same 1 %.
    let half = DriveSetting {
        amp_x_m: (0.5 * reach) as f32,
        ..s
    };
    b.dev.set_drive(half).unwrap();
    let planned = f64::from(b.dev.dds().channels()[1].amp_target) * v;
    let want = 0.5 * reach / h_true;
    let rel = planned / want - 1.0;
    println!("planned {planned:e} V vs {want:e} V: {rel:+.2e}");
    assert!(rel.abs() <= 0.01, "planned {planned:e} V vs {want:e} V");
}

/// The loops' magnitude comparisons (`norm_le`, `norm_gt`: squares where
/// they are normal f32, the norms otherwise) against the comparison of the
/// exact f64 magnitudes, `|a|` against `k·|b|`: over 200 000 random pairs
/// and factors k ∈ [0, 40) at magnitudes from 10⁻³⁰ to 10³⁰ (subnormal and
/// overflowing squares included), they agree wherever the exact sides
/// differ by more than 1e-6 of the larger (the f32 rounding of a square,
/// a product and a sum, or of a fast hypot, is a few parts in 10⁷); the
/// rounding band is counted and must stay small. Exact cases: zero
/// against zero (`|0| ≤ k·|0|`), NaN (never ≤, never >), and the loops'
/// own factors (20 for D3's gate, 10 for an open pickup, C_MAX for c).
#[test]
fn magnitude_comparisons_are_those_of_the_exact_norms() {
    use board::device::displacement::{norm_gt, norm_le, norm_le_real};
    use num_complex::Complex32 as C;
    let mut rng = integration_tests::Rng::new(9);
    let mut band = 0u32;
    let n = 200_000u32;
    for i in 0..n as usize {
        let mag = |rng: &mut integration_tests::Rng| 10f64.powf(rng.range(-30.0, 30.0));
        let (ma, mb) = (mag(&mut rng), mag(&mut rng));
        // Half the cases near the boundary |a| = k·|b|.
        let k = [rng.range(0.0, 40.0), 20.0, 10.0, 2.0][i % 4];
        let mb = if i % 2 == 0 {
            ma / k.max(1e-30) * rng.range(0.9, 1.1)
        } else {
            mb
        };
        let (pa, pb) = (rng.range(0.0, TAU), rng.range(0.0, TAU));
        let a = C::new((ma * pa.cos()) as f32, (ma * pa.sin()) as f32);
        let b = C::new((mb * pb.cos()) as f32, (mb * pb.sin()) as f32);
        let k = k as f32;
        let lhs = f64::from(a.re).hypot(f64::from(a.im));
        let rhs = f64::from(k) * f64::from(b.re).hypot(f64::from(b.im));
        if !(lhs.is_finite() && rhs.is_finite()) {
            continue;
        }
        if (lhs - rhs).abs() <= 1e-6 * lhs.max(rhs) {
            band += 1;
            continue;
        }
        assert_eq!(norm_le(a, k, b), lhs <= rhs, "norm_le({a}, {k}, {b})");
        assert_eq!(norm_gt(a, k, b), lhs > rhs, "norm_gt({a}, {k}, {b})");
    }
    // The band: pairs drawn within ±10 % of the boundary land in a 2e-6
    // wide band about 1e-5 of the time; far below 1 % of all pairs.
    assert!(band < n / 100, "{band} of {n} in the rounding band");
    let (zero, one) = (C::new(0.0, 0.0), C::new(1.0, 0.0));
    let nan = C::new(f32::NAN, 0.0);
    assert!(norm_le(zero, 3.0, zero) && !norm_gt(zero, 3.0, zero));
    assert!(!norm_le(nan, 1.0, one) && !norm_gt(nan, 1.0, one));
    assert!(!norm_le(one, 1.0, nan) && !norm_gt(one, 1.0, nan));
    // Exactly at the boundary: |3 + 4i| = 5 = 2.5·|2|.
    let (a, b) = (C::new(3.0, 4.0), C::new(0.0, 2.0));
    assert!(norm_le(a, 2.5, b) && !norm_gt(a, 2.5, b));
    assert!(!norm_le(a, 2.4, b) && norm_gt(a, 2.4, b));
    assert!(norm_le_real(a, 5.0) && !norm_le_real(a, 4.99));
    // The same at magnitudes whose squares underflow or overflow.
    for s in [1e-25f32, 1e25] {
        let (a, b) = (a * s, b * s);
        assert!(norm_le(a, 2.5001, b) && !norm_gt(a, 2.5001, b), "{s}");
        assert!(!norm_le(a, 2.4999, b) && norm_gt(a, 2.4999, b), "{s}");
    }
}

/// A setting whose dead-beat start asks for more voltage than the DAC
/// has: Δu_z = 2.8 µm on the exact model needs ≈ 1.04 V steady on the normal
/// channel (|H| ≈ 2.7 µm/V at 20 kHz, 300 Hz below its resonance), the
/// start within the headroom h = 2 twice that — beyond the room of
/// min(dc, 4095 − dc) codes at 3.3/4095 V a code (1.65 V at mid-scale).
/// The start is cut to the room, less the documented part in 10⁴ (D5):
/// no fill asks the DAC for more (a level beyond it would be refused and
/// the drive left where it was), some fill is at the room itself, and the
/// drive then holds the setting as documented.
#[test]
fn a_start_beyond_the_dacs_room_is_cut_to_it_and_holds() {
    let table = SineTable::<1024>::libm();
    // The normal channel's DC below mid-scale (u_z0 = 4 µm: the room is
    // the DC itself) and above it (DC at code 2 600: the room is the
    // distance to the top, 1 495 codes, 1.20 V, still below the start's
    // ≈ 2.1 V and above the 1.04 V steady).
    let mpc = f64::from(
        integration_tests::resonant::Bench::new(&table, opts(), exact_model(true_modes()))
            .cfg
            .dac_z
            .metres_per_code,
    );
    for offset in [4e-6, 2600.0 * mpc] {
        let mut b = Bench::new(&table, opts(), exact_model(true_modes()));
        let mut s = setting(2.8e-6);
        s.offset_z_m = offset as f32;
        b.dev.set_drive(s).unwrap();
        b.dev.start().unwrap();
        let (mut at_room, mut worst) = (0u32, 0.0f64);
        for _ in 0..4_000 {
            b.step();
            let c = b.dev.dds().channels()[0];
            let dc = f64::from(c.dc_target);
            // The room in codes, as D5 states it (0.9999 of the DC's
            // distance to the nearer rail).
            let room = dc.min(4095.0 - dc) * 0.9999;
            let a = f64::from(c.amp_target);
            worst = worst.max(a / room);
            if (a / room - 1.0).abs() <= 1e-5 {
                at_room += 1;
            }
        }
        let dc = f64::from(b.dev.dds().channels()[0].dc_target);
        assert!(
            worst <= 1.0 + 1e-5,
            "DC {dc}: a fill asked {worst} of the room"
        );
        assert!(at_room > 0, "DC {dc}: the start never reached the room");
        assert_eq!(b.dev.status().faults, 0, "DC {dc}");
        check_holds(&mut b, &s, 400);
    }
}

/// |Ĥ(f)| of a device model by eq. 1 written out (`g/|1 − r² + j r/Q|`,
/// r = f/f_r), in f64.
fn model_gain(m: &TransducerModel, f: f64) -> f64 {
    let r = f / f64::from(m.resonance_hz);
    let (re, im) = (1.0 - r * r, r / f64::from(m.q));
    f64::from(m.gain_m_per_v) / (re * re + im * im).sqrt()
}

/// D3 corrects a channel only while it is driven ("from a twentieth of the
/// setting up"): an undriven tangential channel, moved only by 2 % of
/// cross-talk from the driven normal one (≈ 19 nm, the plant's own
/// motion), keeps its correction c = 1 however long it runs. So when it is
/// then driven at the same frequency (c is kept, `displacement` docs), the
/// plan's voltage is D2 with c = 1 on the exact model: the DDS's target
/// level `Δu_x/(|Ĥ_x(f)|·v)` codes, Ĥ_x by eq. 1 here. The f32 model
/// response loses ≤ 1e-6 relative in `1 − r²` (r² to an ulp against
/// |1 − r²| = 0.03) and a few ulps in the division and norm: allowed 1e-5.
/// (Correcting the undriven channel from its cross-talk learns a c
/// far from 1: the first fills of the step then miss Δu_x by tens of %.)
#[test]
fn an_undriven_channel_learns_no_correction() {
    use board::plant::DAC_VOLTS_PER_CODE;
    let table = SineTable::<1024>::libm();
    let mut o = opts();
    o.crosstalk = 0.02;
    let model = exact_model(true_modes());
    let mut b = Bench::new(&table, o, model);
    let mut s = setting(2e-6);
    s.amp_x_m = 0.0;
    b.dev.set_drive(s).unwrap();
    b.dev.start().unwrap();
    b.until_settled(2_000);
    let mut xtalk = 0.0f64;
    for _ in 0..400 {
        xtalk = xtalk.max(b.step().amp_x);
    }
    // The undriven channel does move (so D3 would have something to learn).
    assert!(xtalk > 1e-8, "cross-talk motion {xtalk:e}");
    s.amp_x_m = 0.3e-6;
    b.dev.set_drive(s).unwrap();
    let f = b.dev.applied().achieved.freq_hz;
    let want = f64::from(s.amp_x_m) / (model_gain(&model.x, f) * DAC_VOLTS_PER_CODE);
    let got = f64::from(b.dev.dds().channels()[1].amp_target);
    assert!(
        (got / want - 1.0).abs() <= 1e-5,
        "tangential level {got} codes, D2 with c = 1: {want}"
    );
}

/// The largest displacement a new frequency allows is the model's at that
/// frequency (`displacement` docs: a setting whose voltage does not fit the
/// DAC is refused with the largest displacement the model gives there),
/// also while running, when the device holds the model's response at the
/// old frequency: from 20 kHz (Δu_z = 2 µm held), 15 kHz asks 2 µm, which
/// the model reaches at 20 kHz but not at 15 kHz. The refusal's maximum is
/// `room·v·|Ĥ_z(15 kHz)|` (c starts over at a new frequency), the room the
/// normal channel's DC codes to the nearer DAC end (u_z0 = 4 µm), Ĥ_z by
/// eq. 1 here; the DDS frequency is 15 kHz within 1.2e-4 Hz (|Ĥ| moves by
/// 1e-8 relative); f32 products and the model response's rounding: allowed
/// 1e-5 relative.
#[test]
fn a_new_frequency_is_refused_with_the_models_reach_there() {
    use board::device::DeviceError;
    use board::plant::DAC_VOLTS_PER_CODE;
    let table = SineTable::<1024>::libm();
    let model = exact_model(true_modes());
    let mut b = Bench::new(&table, opts(), model);
    let mut s = setting(2e-6);
    b.dev.set_drive(s).unwrap();
    b.dev.start().unwrap();
    b.until_settled(2_000);
    s.freq_hz = 15_000.0;
    let z = b.cfg.dac_z;
    let dc = f64::from(z.zero_code) + f64::from(s.offset_z_m) / f64::from(z.metres_per_code);
    let room = dc.min(4095.0 - dc);
    let want = room * DAC_VOLTS_PER_CODE * model_gain(&model.z, s.freq_hz);
    assert!(want < 2e-6 && want > 0.1e-6, "reach at 15 kHz {want:e}");
    match b.dev.set_drive(s) {
        Err(DeviceError::OutOfRange {
            param: board::device::DriveParam::AmpZ,
            max,
            ..
        }) => assert!(
            (f64::from(max) / want - 1.0).abs() <= 1e-5,
            "reported reach {max:e}, eq. 1: {want:e}"
        ),
        other => panic!("2 µm at 15 kHz: {other:?} (reach {want:e})"),
    }
    // Within the reach it is taken (Δu_x within its own, 0.16 µm there).
    s.amp_z_m = (0.9 * want) as f32;
    s.amp_x_m = 0.1e-6;
    b.dev.set_drive(s).unwrap();
}

/// D3 keeps the correction within its bounds, 1/C_MAX ≤ |c| ≤ C_MAX (C_MAX
/// = 2, `displacement` D3): a normal-mode model whose gain is four times
/// the true one would need |c| = ¼. Each window moves c by a factor
/// 1 + e·k with e ≈ ¼/|c| − 1 and k = window/(4τ̂) ≈ 0.03 (τ̂ ≈ 4 ms), so
/// the last step taken leaves |c| in [0.5, 0.5/(1 − 0.5·0.03)] ⊂ [0.5,
/// 0.51], and a step that would cross the bound is refused. Read through
/// D2: a new amplitude at the same frequency is planned at
/// |d|/(|Ĥ_z|·|c|·v) codes (Ĥ_z by eq. 1 written out), so within [0.5,
/// 0.52] of |c| the planned level lies between its values there (f32
/// products: 1e-5 more). A correction let past its bound (¼) would plan
/// twice the level.
#[test]
fn the_correction_stops_at_its_lower_bound() {
    use board::plant::DAC_VOLTS_PER_CODE;
    let table = SineTable::<1024>::libm();
    let m = true_modes();
    let model = Transducers {
        z: model_of(m[0], 0.0, 1.0, 4.0),
        x: model_of(m[1], 0.0, 1.0, 1.0),
    };
    let mut b = Bench::new(&table, opts(), model);
    let mut s = setting(1e-6);
    b.dev.set_drive(s).unwrap();
    b.dev.start().unwrap();
    for _ in 0..3_000 {
        b.step();
    }
    assert_eq!(b.dev.status().faults, 0);
    s.amp_z_m = 1.2e-6;
    b.dev.set_drive(s).unwrap();
    let f = b.dev.applied().achieved.freq_hz;
    let level = |c: f64| f64::from(s.amp_z_m) / (model_gain(&model.z, f) * c * DAC_VOLTS_PER_CODE);
    let got = f64::from(b.dev.dds().channels()[0].amp_target);
    let (lo, hi) = (level(0.52) * (1.0 - 1e-5), level(0.5) * (1.0 + 1e-5));
    assert!(
        got >= lo && got <= hi,
        "normal level {got} codes; with |c| in [0.5, 0.52]: [{lo}, {hi}]"
    );
}
