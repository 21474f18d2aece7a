//! Scene validation: every invalid input class gives its typed error.

use model_core::exact;
use model_core::{Drive, Groups, Libm, Param, Scene, SceneError, SceneParams};

fn ok() -> SceneParams<f64> {
    SceneParams {
        mu0: 0.3,
        kz: 1e6,
        kx: 1e6,
        uz0: 1e-6,
        duz: 0.5e-6,
        dux: 0.1e-6,
        omega: 2.5e5,
        phi: 0.5,
    }
}

fn with(f: impl FnOnce(&mut SceneParams<f64>)) -> Result<Scene<f64>, SceneError> {
    let mut p = ok();
    f(&mut p);
    Scene::new(p)
}

#[test]
fn valid_scene_is_accepted() {
    let s = Scene::new(ok()).unwrap();
    assert!((s.w0() - 0.3e-6).abs() < 1e-21);
    assert_eq!(s.groups().duz_rel, 0.5);
}

#[test]
fn every_invalid_class_has_its_error() {
    use Param::*;
    for (p, set) in [
        (
            Mu0,
            &(|p: &mut SceneParams<f64>, x| p.mu0 = x) as &dyn Fn(&mut SceneParams<f64>, f64),
        ),
        (Kz, &|p, x| p.kz = x),
        (Kx, &|p, x| p.kx = x),
        (Uz0, &|p, x| p.uz0 = x),
        (Duz, &|p, x| p.duz = x),
        (Dux, &|p, x| p.dux = x),
        (Omega, &|p, x| p.omega = x),
        (Phi, &|p, x| p.phi = x),
    ] {
        for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            assert_eq!(
                with(|q| set(q, bad)),
                Err(SceneError::NonFinite(p)),
                "{p:?} = {bad}"
            );
        }
    }
    for (p, set) in [
        (
            Mu0,
            &(|p: &mut SceneParams<f64>, x| p.mu0 = x) as &dyn Fn(&mut SceneParams<f64>, f64),
        ),
        (Kz, &|p, x| p.kz = x),
        (Kx, &|p, x| p.kx = x),
        (Uz0, &|p, x| p.uz0 = x),
        (Omega, &|p, x| p.omega = x),
    ] {
        assert_eq!(with(|q| set(q, 0.0)), Err(SceneError::NotPositive(p)));
        assert_eq!(with(|q| set(q, -1.0)), Err(SceneError::NotPositive(p)));
    }
    assert_eq!(with(|q| q.duz = -1e-9), Err(SceneError::Negative(Duz)));
    assert_eq!(with(|q| q.dux = -1e-9), Err(SceneError::Negative(Dux)));
    assert_eq!(with(|q| q.duz = q.uz0), Err(SceneError::LiftOff));
    assert_eq!(with(|q| q.duz = 2.0 * q.uz0), Err(SceneError::LiftOff));
    // Just below lift-off is fine.
    assert!(with(|q| q.duz = q.uz0 * (1.0 - 1e-12)).is_ok());
    // Combinations that over/underflow the derived scales.
    assert_eq!(
        with(|q| {
            q.kz = 1e-300;
            q.kx = 1e300
        }),
        Err(SceneError::OutOfRange(Kx))
    );
    assert_eq!(with(|q| q.dux = 1e308), Err(SceneError::OutOfRange(Dux)));
    assert_eq!(
        with(|q| q.omega = 1e-303),
        Err(SceneError::OutOfRange(Omega))
    );
}

#[test]
fn groups_validation() {
    assert_eq!(
        Groups::from_ratio(0.0, 1.0, 0.0),
        Err(SceneError::RatioNeedsNormalAmplitude)
    );
    assert_eq!(Groups::from_ratio(1.0, 1.0, 0.0), Err(SceneError::LiftOff));
    assert_eq!(
        Groups::from_ratio(0.5, -1.0, 0.0),
        Err(SceneError::Negative(Param::Ratio))
    );
    assert_eq!(
        Groups::from_ratio(0.5, f64::NAN, 0.0),
        Err(SceneError::NonFinite(Param::Ratio))
    );
    let g = Groups::from_ratio(0.5, 2.0, 0.1).unwrap();
    assert_eq!(g.dux_rel, 1.0);
    let bad = Groups {
        duz_rel: 0.5,
        dux_rel: -0.1,
        phi: 0.0,
    };
    assert_eq!(
        Scene::dimensionless(bad),
        Err(SceneError::Negative(Param::DuxRel))
    );
    let bad = Groups {
        duz_rel: -0.5,
        dux_rel: 0.1,
        phi: 0.0,
    };
    assert_eq!(
        Scene::<f64>::dimensionless(bad),
        Err(SceneError::Negative(Param::DuzRel))
    );
}

#[test]
fn errors_print_one_line_naming_the_parameter() {
    for e in [
        SceneError::NonFinite(Param::Kz),
        SceneError::NotPositive(Param::Mu0),
        SceneError::Negative(Param::Dux),
        SceneError::LiftOff,
        SceneError::RatioNeedsNormalAmplitude,
        SceneError::OutOfRange(Param::Omega),
    ] {
        let s = e.to_string();
        assert!(!s.contains('\n'));
        let name = match e {
            SceneError::NonFinite(p)
            | SceneError::NotPositive(p)
            | SceneError::Negative(p)
            | SceneError::OutOfRange(p) => p.name(),
            SceneError::LiftOff => "duz",
            SceneError::RatioNeedsNormalAmplitude => "ratio",
        };
        assert!(s.starts_with(name), "{s}");
    }
}

#[test]
fn extreme_si_magnitudes_in_f32_give_the_f64_value() {
    // µm amplitudes and GPa/m stiffnesses together, in f32.
    let s = Scene::<f32>::new(SceneParams {
        mu0: 0.2,
        kz: 5e9,
        kx: 3e9,
        uz0: 2e-7,
        duz: 1e-7,
        dux: 3e-8,
        omega: 2.5e5,
        phi: 1.0,
    })
    .unwrap();
    let vc = model_core::analytic::CriticalVelocity::of(&s);
    let v0 = 0.5 * vc.forward;
    let m = model_core::exact::solve(&s, v0)
        .unwrap()
        .mu_over_mu0()
        .unwrap();
    // Groups: a = Δu_z/u_z0 = 0.5, b = k_xΔu_x/(μ₀k_z u_z0) = 0.45, φ = 1 — the
    // value must be the f64 solver's on the very drive and velocity the f32
    // scene holds, within the f32 solver's stated bound 1e-6·(1 + b) (plus the
    // f64 one): only the arithmetic differs.
    let d32 = s.drive();
    assert!(
        (d32.a - 0.5).abs() < 1e-6 && (d32.b - 0.45).abs() < 1e-6,
        "{d32:?}"
    );
    let d = Drive::new::<Libm>(f64::from(d32.a), f64::from(d32.b), 1.0);
    let v = f64::from(s.dimensionless_velocity(v0).unwrap());
    let reference = exact::mu_over_mu0::<f64, Libm>(&d, v).unwrap();
    let allowed =
        f64::from(exact::error_bound::<f32, Libm>(&d32)) + exact::error_bound::<f64, Libm>(&d);
    println!("f32 SI scene: {m} vs f64 {reference} (allowed {allowed:.1e})");
    assert!(
        (f64::from(m) - reference).abs() <= allowed,
        "{m} vs {reference}"
    );
}
