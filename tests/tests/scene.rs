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

/// W₀ as `Scene::new` formed it before issue 42 (the reference): the
/// operations ordered by `|ln r|` of each candidate intermediate `r` (here
/// std's `ln`; the model used libm's `log`), the first on a tie, every
/// intermediate checked to be normal.
fn w0_by_logarithms<T: model_core::Float>(mu0: T, kz: T, kx: T, uz0: T) -> Result<T, SceneError> {
    let mut acc = mu0;
    let mut ops = [
        (kz, false, Param::Kz),
        (uz0, false, Param::Uz0),
        (kx, true, Param::Kx),
    ];
    let mut left = ops.len();
    while left > 0 {
        let (mut best, mut best_mag) = (0, f64::INFINITY);
        for (i, &(x, div, _)) in ops[..left].iter().enumerate() {
            let r = if div { acc / x } else { acc * x };
            let mag = r.to_f64().ln().abs();
            if mag < best_mag {
                best = i;
                best_mag = mag;
            }
        }
        let (x, div, param) = ops[best];
        acc = if div { acc / x } else { acc * x };
        if !(acc.is_finite() && acc >= T::MIN_POSITIVE) {
            return Err(SceneError::OutOfRange(param));
        }
        ops.swap(best, left - 1);
        left -= 1;
    }
    Ok(acc)
}

/// A scene of these contact parameters and u_z0 with a zero drive (what
/// the device's contact check judged before issue 42).
fn zero_drive<T: model_core::Float>(mu0: T, kz: T, kx: T, uz0: T) -> SceneParams<T> {
    SceneParams {
        mu0,
        kz,
        kx,
        uz0,
        duz: T::ZERO,
        dux: T::ZERO,
        omega: T::ONE,
        phi: T::ZERO,
    }
}

/// A positive normal f32 of random exponent (the whole range) and mantissa.
fn random_normal_f32(r: &mut integration_tests::Rng) -> f32 {
    let exp = 1 + (r.uniform() * 254.0) as u32;
    let man = (r.uniform() * (1u32 << 23) as f64) as u32;
    f32::from_bits(exp << 23 | man)
}

/// A positive normal f64 of random exponent (the whole range) and mantissa.
fn random_normal_f64(r: &mut integration_tests::Rng) -> f64 {
    let exp = 1 + (r.uniform() * 2046.0) as u64;
    let man = (r.uniform() * (1u64 << 52) as f64) as u64;
    f64::from_bits(exp << 52 | man)
}

/// Issue 42: W₀'s operations are ordered by exact comparisons instead of six
/// logarithms (≈ 15 000 instructions on the Cortex-M4F). Same order, so the
/// same W₀ to the bit and the same error, over random f32 and f64 contacts
/// of the whole exponent range, the same near 1 (where candidates are
/// close) and exact ties (powers of two, `k_z·u_z0 = 1`, equal values).
#[test]
fn w0_is_ordered_as_by_logarithms() {
    let mut r = integration_tests::Rng::new(42);
    let mut compared = [0u32; 2];
    for i in 0..400_000 {
        let (mu0, kz, kx, uz0) = match i % 4 {
            // The whole range: over- and underflow of intermediates.
            0 | 1 => (
                random_normal_f32(&mut r),
                random_normal_f32(&mut r),
                random_normal_f32(&mut r),
                random_normal_f32(&mut r),
            ),
            // Within a few octaves of 1: the candidates are close.
            2 => {
                let mut near = || (r.range(-4.0, 4.0) as f32).exp2();
                (near(), near(), near(), near())
            }
            // Exact ties: powers of two, k_z·u_z0 = 1, k_x = k_z.
            _ => {
                let mut pow2 = || ((r.uniform() * 200.0) as i32 - 100) as f32;
                let (a, b) = (pow2().exp2(), pow2().exp2());
                (a, b, b, 1.0 / b)
            }
        };
        let got = Scene::new(zero_drive(mu0, kz, kx, uz0)).map(|s| s.w0().to_bits());
        let want = w0_by_logarithms(mu0, kz, kx, uz0).map(f32::to_bits);
        assert_eq!(got, want, "f32 {mu0:e} {kz:e} {kx:e} {uz0:e}");
        compared[usize::from(want.is_ok())] += 1;
    }
    // Both outcomes were exercised.
    assert!(compared.iter().all(|&n| n > 10_000), "{compared:?}");
    for i in 0..200_000 {
        let (mu0, kz, kx, uz0) = if i % 2 == 0 {
            (
                random_normal_f64(&mut r),
                random_normal_f64(&mut r),
                random_normal_f64(&mut r),
                random_normal_f64(&mut r),
            )
        } else {
            let mut near = || r.range(-4.0, 4.0).exp2();
            (near(), near(), near(), near())
        };
        let got = Scene::new(zero_drive(mu0, kz, kx, uz0)).map(|s| s.w0().to_bits());
        let want = w0_by_logarithms(mu0, kz, kx, uz0).map(f64::to_bits);
        assert_eq!(got, want, "f64 {mu0:e} {kz:e} {kx:e} {uz0:e}");
    }
}

/// `check_contact_params` (the device's contact check, issue 42: no scene
/// formed) returns exactly what `Scene::new` returns for a zero drive: the
/// same error for every class of bad input, the same W₀ otherwise.
#[test]
fn the_contact_check_is_the_scenes_own() {
    use model_core::scene::check_contact_params;
    let mut r = integration_tests::Rng::new(7);
    let special = [
        f32::NAN,
        f32::INFINITY,
        f32::NEG_INFINITY,
        0.0,
        -0.0,
        -1.0,
        1e-40,
        f32::MIN_POSITIVE,
        f32::MAX,
        1e-6,
        0.3,
        1e7,
    ];
    let pick = |r: &mut integration_tests::Rng| {
        if r.uniform() < 0.3 {
            special[(r.uniform() * special.len() as f64) as usize]
        } else {
            // Any bit pattern: negative, subnormal, NaN, ∞ included.
            f32::from_bits((r.uniform() * 4_294_967_296.0) as u32)
        }
    };
    let mut errors = std::collections::HashSet::new();
    for _ in 0..300_000 {
        let (mu0, kz, kx) = (pick(&mut r), pick(&mut r), pick(&mut r));
        let uz0 = if r.uniform() < 0.8 {
            1e-6
        } else {
            pick(&mut r)
        };
        let got = check_contact_params(mu0, kz, kx, uz0).map(f32::to_bits);
        let want = Scene::new(zero_drive(mu0, kz, kx, uz0)).map(|s| s.w0().to_bits());
        assert_eq!(got, want, "{mu0:e} {kz:e} {kx:e} {uz0:e}");
        if let Err(e) = want {
            errors.insert(format!("{e:?}"));
        }
    }
    // Every class of refusal of the four parameters was met.
    for p in ["Mu0", "Kz", "Kx", "Uz0"] {
        for class in ["NonFinite", "NotPositive", "OutOfRange"] {
            assert!(
                errors.contains(&format!("{class}({p})")),
                "{class}({p}): {errors:?}"
            );
        }
    }
}
