//! Stability where methods fail (issue 6 §2): every method returns a number
//! within its stated error bound or an explicit failure — never a silently
//! wrong number. One test per failure class, then randomised agreement tests
//! over wide parameter ranges where both methods claim success.
//!
//! References are independent computations: the exact solver checks the
//! fixed-step scheme and vice versa (they share no code beyond the drive), f64
//! checks f32, and the dimensionless scene checks extreme SI inputs.

use std::f64::consts::PI;

use model_core::exact::{self, ExactError, Solution};
use model_core::fixed_step::{self, run_dimensionless, FixedStepConfig, FixedStepError, Start};
use model_core::{Drive, Groups, Libm, Micromath, Param, Scene, SceneError, SceneParams};
use proptest::prelude::*;

fn d64(a: f64, b: f64, phi: f64) -> Drive<f64> {
    Drive::new::<Libm>(a, b, phi)
}

fn fixed_run<T: model_core::Float>(
    d: &Drive<T>,
    v: T,
    n: u32,
) -> Result<(f64, f64), FixedStepError<T>> {
    // A budget of 2·10⁷ steps: past it, "not converged" (an explicit failure).
    let mut cfg = FixedStepConfig::<T>::new(n);
    cfg.max_periods = (20_000_000 / n.max(1)).max(3);
    let r = run_dimensionless::<T, Libm>(d, v, &cfg, Start::Rest)?;
    Ok((r.mu_over_mu0.to_f64(), r.error_bound.to_f64()))
}

fn exact64(d: &Drive<f64>, v: f64) -> f64 {
    exact::mu_over_mu0::<f64, Libm>(d, v).expect("exact f64")
}

/// Fixed-step and exact agree within the sum of their stated bounds.
fn agree(d: &Drive<f64>, v: f64, n: u32) {
    let (m, b) = fixed_run(d, v, n).expect("fixed-step converges");
    let e = exact64(d, v);
    let allowed = b + exact::error_bound::<f64, Libm>(d);
    assert!(
        (m - e).abs() <= allowed,
        "a={} b={} v={v} N={n}: fixed {m} vs exact {e} (allowed {allowed:e})",
        d.a,
        d.b
    );
}

// ---------------------------------------------------------------- classes

/// Too few steps per period: refused below ⌈√(K_D(1 + b)/0.1)⌉, and the
/// first accepted N is within its bound.
#[test]
fn too_few_steps_is_refused_by_kind() {
    for (b, want) in [(0.0, 10u32), (0.25, 12), (3.0, 20), (99.0, 100)] {
        // K_D = 10: N_min = ⌈√(100(1 + b))⌉.
        let d = d64(0.5, b, 1.0);
        let v = 0.3 * d.c_forward::<Libm>();
        assert_eq!(
            fixed_run(&d, v, want - 1),
            Err(FixedStepError::TooFewSteps { min_steps: want }),
            "b = {b}"
        );
        agree(&d, v, want);
    }
}

/// v0 → v_c: the stick windows vanish. Both methods stay within their bounds
/// up to one ulp below v_c, and at v_c both give exactly ±1.
#[test]
fn velocity_to_critical() {
    let d = d64(0.5, 0.25, 1.0);
    let c = d.c_forward::<Libm>();
    for eps in [1e-2, 1e-4, 1e-8, 1e-12, 1e-15] {
        let v = c * (1.0 - eps);
        let e = exact64(&d, v);
        // 1 − μ shrinks faster than 1 − v/v_c: it rounds to 1 near the end.
        assert!(e <= 1.0 && e > 0.99, "{eps}: {e}");
        agree(&d, v, 4096);
    }
    assert_eq!(exact64(&d, c), 1.0);
    assert_eq!(
        exact64(&d.mirrored(), d.mirrored().c_forward::<Libm>()),
        1.0
    );
    let (m, _) = fixed_run(&d, c, 64).unwrap();
    assert!((m - 1.0).abs() < 1e-12, "{m}");
}

/// v0 → 0: the exact solver tends to the closed-form limit μ(0⁺); the paper's
/// method from rest needs ≈ 1/(2πV) periods and says "not converged" when
/// its budget ends — although the per-period change already passes a naive
/// tolerance test.
#[test]
fn velocity_to_zero() {
    // c = |b e^{iφ} + a| < 1: a static equilibrium exists, μ(0⁺) = 1 − c.
    let d = d64(0.3, 0.2, 2.5);
    let c = d.c_forward::<Libm>();
    assert!(c < 1.0);
    let (plus, _) = exact::limits_at_zero::<f64, Libm>(&d).unwrap();
    assert!((plus - (1.0 - c)).abs() < 1e-13);
    for v in [1e-6, 1e-10, 1e-100, 1e-300] {
        let m = exact64(&d, v * c);
        assert!(
            (m - plus).abs() <= 10.0 * v + 1e-13,
            "V = {v}: {m} vs {plus}"
        );
    }
    // From rest the stretch starts at b cos φ and must drift up to the band
    // edge at 2πV per period (the drive alone does not reach it here).
    let mut cfg = FixedStepConfig::<f64>::new(512);
    cfg.max_periods = 2000;
    cfg.tol = 1e-6;
    match run_dimensionless::<f64, Libm>(&d, 1e-7, &cfg, Start::Rest) {
        Err(FixedStepError::NotConverged {
            periods,
            last_change,
            ..
        }) => {
            assert_eq!(periods, 2000);
            assert!(last_change < cfg.tol, "{last_change}");
        }
        other => panic!("expected NotConverged, got {other:?}"),
    }
}

/// Δu_z → u_z0: the normal force nearly vanishes at the trough. Still within
/// bounds at a = 1 − 10⁻¹²; a = 1 is lift-off; in f32 1 − 10⁻⁹ rounds to 1 and
/// is lift-off too, explicitly.
#[test]
fn normal_amplitude_to_lift_off() {
    for gap in [1e-3, 1e-6, 1e-9, 1e-12] {
        let d = d64(1.0 - gap, 0.3, 2.0);
        for x in [0.01, 0.3, 0.9] {
            agree(&d, x * d.c_forward::<Libm>(), 4096);
        }
    }
    let g = |a: f64| Groups {
        duz_rel: a,
        dux_rel: 0.3,
        phi: 2.0,
    };
    assert_eq!(
        Scene::dimensionless(g(1.0)).err(),
        Some(SceneError::LiftOff)
    );
    let g32 = Groups {
        duz_rel: (1.0 - 1e-9) as f32,
        dux_rel: 0.3f32,
        phi: 2.0f32,
    };
    assert_eq!(Scene::dimensionless(g32).err(), Some(SceneError::LiftOff));
    // A hand-built drive with a ≥ 1 is refused by both methods.
    let bad = Drive {
        a: 1.0,
        b: 0.3,
        bc: 0.0,
        bs: 0.3,
    };
    assert_eq!(
        exact::mu_over_mu0::<f64, Libm>(&bad, 0.1),
        Err(ExactError::BadDrive)
    );
    assert_eq!(fixed_run(&bad, 0.1, 1024), Err(FixedStepError::BadDrive));
}

/// Huge and tiny tangential amplitudes: the exact f32 solver is within its
/// bound up to b ≈ 10⁴ and refuses beyond (ill-conditioned); f64 refuses past
/// 10⁷; the fixed-step scheme in f32 refuses past b ≈ 100. A tiny b is the
/// normal-only law.
#[test]
fn huge_and_tiny_ratios() {
    for b in [1.0, 1e2, 1e3, 5e3] {
        let d = d64(0.5, b, 1.0);
        let d32 = Drive::new::<Libm>(0.5f32, b as f32, 1.0f32);
        for x in [1e-3, 0.2, 0.9] {
            let v = x * d.c_forward::<Libm>();
            let m32 = exact::mu_over_mu0::<f32, Libm>(&d32, v as f32).unwrap();
            let allowed =
                exact::error_bound::<f32, Libm>(&d32) as f64 + exact::error_bound::<f64, Libm>(&d);
            let e = exact64(&d, v);
            assert!(
                (m32 as f64 - e).abs() <= allowed,
                "b={b} x={x}: {m32} vs {e}"
            );
        }
    }
    // 1e-6·(1 + b) > 1e-2 ⇔ b > 9999.
    let d32 = Drive::new::<Libm>(0.5f32, 2e4, 1.0);
    assert_eq!(
        exact::mu_over_mu0::<f32, Libm>(&d32, 0.1),
        Err(ExactError::IllConditioned)
    );
    let d = d64(0.5, 2e7, 1.0);
    assert_eq!(
        exact::mu_over_mu0::<f64, Libm>(&d, 1.0),
        Err(ExactError::IllConditioned)
    );
    // Large b in f64 is still within bounds against fixed-step.
    let d = d64(0.5, 1e4, 1.0);
    agree(&d, 0.3 * d.c_forward::<Libm>(), 8192);
    // Fixed-step f32: the best bound (N* = 551) exceeds 1e-2 for b ≳ 100.
    let d32 = Drive::new::<Libm>(0.5f32, 200.0, 1.0);
    assert_eq!(
        fixed_run(&d32, 10.0f32, 1024),
        Err(FixedStepError::IllConditioned)
    );
    // Tiny b: the normal-only law (b enters linearly at most).
    let tiny = d64(0.5, 1e-12, 1.0);
    let normal = d64(0.5, 0.0, 0.0);
    for x in [0.01, 0.5] {
        let v = x * normal.c_forward::<Libm>();
        assert!((exact64(&tiny, v) - exact64(&normal, v)).abs() < 1e-10);
    }
}

/// v_c = 0 exactly (no oscillation, or oscillations that cancel in one
/// direction): any motion slides with μ = ±μ0 exactly; at rest the static
/// interval is [−1, 1] and the limits are ±1.
#[test]
fn zero_critical_velocity() {
    let s = Scene::dimensionless(Groups {
        duz_rel: 0.0,
        dux_rel: 0.0,
        phi: 0.0,
    })
    .unwrap();
    for v in [1e-300, 1e-9, 1.0] {
        assert_eq!(
            exact::solve(&s, v),
            Ok(Solution::Sliding { mu_over_mu0: 1.0 })
        );
        assert_eq!(
            exact::solve(&s, -v),
            Ok(Solution::Sliding { mu_over_mu0: -1.0 })
        );
    }
    match exact::solve(&s, 0.0).unwrap() {
        Solution::AtRest {
            mu_0plus,
            mu_0minus,
            statics,
        } => {
            assert_eq!((mu_0plus, mu_0minus), (1.0, -1.0));
            assert_eq!((statics.lo, statics.hi), (-1.0, 1.0));
        }
        other => panic!("{other:?}"),
    }
    let (m, b) = fixed_run(&s.drive(), 1e-3, 64).unwrap();
    assert!((m - 1.0).abs() <= b.max(1e-15));
    // b e^{iφ} = −a: the forward v_c vanishes, the backward one is 2a.
    let d = d64(0.4, 0.4, PI);
    assert!(d.c_forward::<Libm>() < 1e-15);
    assert_eq!(exact64(&d, 1e-9), 1.0);
    assert!((d.c_backward::<Libm>() - 0.8).abs() < 1e-15);
    assert!(exact64(&d, -0.4) > -1.0);
}

/// f32 over long runs: past N = 4·N*, N* = (2K_D/(K_R ε))^{1/3} = 551 for
/// f32, rounding grows faster than discretisation shrinks (the measured f32
/// error grows with N beyond ≈ 500): refused. At the limit the answer is
/// within its bound; f64 accepts the same N.
#[test]
fn f32_long_runs_are_refused() {
    let n_star = (20.0 / f64::from(f32::EPSILON)).cbrt().floor() as u32;
    assert_eq!(n_star, 551);
    let d32 = Drive::new::<Libm>(0.5f32, 0.25, 1.0);
    let d = d64(0.5, 0.25, 1.0);
    let v = 0.3 * d.c_forward::<Libm>();
    assert_eq!(
        fixed_run(&d32, v as f32, 4 * n_star + 1),
        Err(FixedStepError::PrecisionLimit {
            max_steps: 4 * n_star
        })
    );
    let (m, b) = fixed_run(&d32, v as f32, 4 * n_star).unwrap();
    assert!((m - exact64(&d, v)).abs() <= b + 1e-9, "{m} (bound {b:e})");
    agree(&d, v, 65_536);
    assert_eq!(fixed_step::max_steps_per_period::<f32>(), 4 * n_star);
}

/// Extreme SI magnitudes (µm and GPa/m together, and far beyond): either the
/// answer equals the dimensionless one within the bound, or the scene is
/// refused as out of range — including subnormal f32 inputs, which have lost
/// their precision, and a subnormal k_z/k_x that the W₀ ordering avoids.
#[test]
fn extreme_si_magnitudes() {
    let g = Groups {
        duz_rel: 0.4,
        dux_rel: 0.3,
        phi: 1.0,
    };
    let reference = {
        let d = Scene::dimensionless(g).unwrap().drive();
        exact64(&d, 0.3 * d.c_forward::<Libm>())
    };
    let params = |uz0: f64, kz: f64, kx: f64| {
        let w0 = 0.3 * kz / kx * uz0;
        SceneParams {
            mu0: 0.3,
            kz,
            kx,
            uz0,
            duz: 0.4 * uz0,
            dux: 0.3 * w0,
            omega: 2.0 * PI * 40e3,
            phi: 1.0,
        }
    };
    let mu_of = |s: &Scene<f64>| {
        let vc = model_core::analytic::CriticalVelocity::of(s).forward;
        exact::solve(s, 0.3 * vc).unwrap().mu_over_mu0().unwrap()
    };
    // µm and GPa/m, and extremes that f64 still represents.
    for (uz0, kz) in [(1e-6, 1e9), (1e-12, 1e15), (1e-200, 1e200), (1e150, 1e-100)] {
        let s = Scene::new(params(uz0, kz, 1e9)).unwrap();
        assert!((mu_of(&s) - reference).abs() <= 2e-9, "uz0={uz0} kz={kz}");
    }
    let to32 = |p: SceneParams<f64>| SceneParams {
        mu0: p.mu0 as f32,
        kz: p.kz as f32,
        kx: p.kx as f32,
        uz0: p.uz0 as f32,
        duz: p.duz as f32,
        dux: p.dux as f32,
        omega: p.omega as f32,
        phi: p.phi as f32,
    };
    // f32, in range: within the f32 bound.
    let s = Scene::new(to32(params(1e-6, 1e9, 1e9))).unwrap();
    let vc = model_core::analytic::CriticalVelocity::of(&s).forward;
    let m = exact::solve(&s, 0.3 * vc).unwrap().mu_over_mu0().unwrap();
    assert!((f64::from(m) - reference).abs() <= 2e-6);
    // f32 subnormal u_z0 (1e-41 m): refused, not silently wrong.
    assert_eq!(
        Scene::new(to32(params(1e-41, 1e9, 1e9))).err(),
        Some(SceneError::OutOfRange(Param::Uz0))
    );
    // k_z/k_x = 1e-43 is subnormal in f32, but W₀ = 3e-34 m is not: accepted
    // (the ordering keeps the intermediates normal) and correct.
    let s = Scene::new(to32(params(1e10, 1e-34, 1e9))).unwrap();
    let vc = model_core::analytic::CriticalVelocity::of(&s).forward;
    let m = exact::solve(&s, 0.3 * vc).unwrap().mu_over_mu0().unwrap();
    assert!(
        (f64::from(m) - reference).abs() <= 2e-6,
        "{m} vs {reference}"
    );
    // W₀ itself below the f32 range: refused.
    assert!(matches!(
        Scene::new(to32(params(1e-30, 1e-12, 1e9))),
        Err(SceneError::OutOfRange(_))
    ));
}

/// The micromath backend: a number within its (large) stated bound, or an
/// explicit failure; never outside.
#[test]
fn micromath_within_its_bound_or_explicit() {
    let mut rng = integration_tests::Rng::new(11);
    let mut failures = 0;
    for _ in 0..2000 {
        let (a, b, phi) = (
            rng.range(0.0, 0.99),
            rng.range(0.0, 5.0),
            rng.range(0.0, std::f64::consts::TAU),
        );
        let x = rng.range(0.001, 0.999);
        let d = d64(a, b, phi);
        let v = x * d.c_forward::<Libm>();
        let dm = Drive::new::<Micromath>(a as f32, b as f32, phi as f32);
        match exact::mu_over_mu0::<f32, Micromath>(&dm, v as f32) {
            Ok(m) => {
                let allowed = f64::from(exact::error_bound::<f32, Micromath>(&dm))
                    + exact::error_bound::<f64, Libm>(&d);
                let e = exact64(&d, v);
                assert!((f64::from(m) - e).abs() <= allowed, "a={a} b={b} x={x}");
            }
            Err(ExactError::Inconsistent) => failures += 1,
            Err(e) => panic!("{e:?}"),
        }
    }
    assert!(failures < 100, "{failures} Inconsistent");
}

// ------------------------------------------------------------ randomised

fn wide_drive() -> impl Strategy<Value = (f64, f64, f64)> {
    (
        prop_oneof![
            0.0f64..0.99,
            (-12.0f64..-2.0).prop_map(|g| 1.0 - 10f64.powf(g))
        ],
        prop_oneof![Just(0.0), (-6.0f64..4.0).prop_map(|e| 10f64.powf(e))],
        -10.0f64..10.0,
    )
}

fn wide_velocity() -> impl Strategy<Value = f64> {
    prop_oneof![
        (-8.0f64..0.0).prop_map(|e| 10f64.powf(e)),
        (-12.0f64..-1.0).prop_map(|e| 1.0 - 10f64.powf(e)),
        0.0f64..1.5,
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(400))]

    /// Exact f64 against a fine fixed-step run, wherever both claim success:
    /// within the sum of their stated bounds.
    #[test]
    fn exact_agrees_with_fine_fixed_step((a, b, phi) in wide_drive(), x in wide_velocity(), back in any::<bool>()) {
        let d = d64(a, b, phi);
        let c = if back { d.c_backward::<Libm>() } else { d.c_forward::<Libm>() };
        let v = if back { -x * c } else { x * c };
        prop_assume!(v != 0.0 && v.is_finite());
        let n = fixed_step::min_steps_per_period(&d).saturating_mul(16).clamp(4096, 65_536);
        let (Ok(e), Ok((m, bound))) = (exact::mu_over_mu0::<f64, Libm>(&d, v), fixed_run(&d, v, n)) else {
            // Explicit failures are allowed; which ones is the business of the class tests.
            return Ok(());
        };
        let allowed = bound + exact::error_bound::<f64, Libm>(&d);
        prop_assert!((m - e).abs() <= allowed, "a={} b={} phi={} v={} N={}: {} vs {} (allowed {:e})", a, b, phi, v, n, m, e, allowed);
    }

    /// Exact f32 against exact f64: within the f32 bound, or an explicit failure.
    #[test]
    fn exact_f32_within_bound((a, b, phi) in wide_drive(), x in wide_velocity()) {
        let Ok(s32) = Scene::dimensionless(Groups { duz_rel: a as f32, dux_rel: b as f32, phi: phi as f32 }) else {
            return Ok(());
        };
        let d32 = s32.drive();
        // The f64 reference for the very drive the f32 scene holds.
        let d = d64(f64::from(d32.a), f64::from(d32.b), f64::from(phi as f32));
        let v = x * d.c_forward::<Libm>();
        prop_assume!(v != 0.0);
        match exact::mu_over_mu0::<f32, Libm>(&d32, v as f32) {
            Ok(m) => {
                let e = exact64(&d, f64::from(v as f32));
                let allowed = f64::from(exact::error_bound::<f32, Libm>(&d32)) + exact::error_bound::<f64, Libm>(&d);
                prop_assert!((f64::from(m) - e).abs() <= allowed, "a={} b={} x={}: {} vs {}", a, b, x, m, e);
            }
            Err(e) => prop_assert!(matches!(e, ExactError::IllConditioned), "{:?}", e),
        }
    }

    /// Fixed-step f32 at any accepted N: within its bound of the exact f64 value.
    #[test]
    fn fixed_f32_within_bound(a in 0.0f64..0.99, b in 0.0f64..20.0, phi in -10.0f64..10.0, x in 0.01f64..0.99, k in 0.0f64..1.0) {
        let d32 = Drive::new::<Libm>(a as f32, b as f32, phi as f32);
        let d = d64(f64::from(d32.a), f64::from(d32.b), f64::from(phi as f32));
        let (lo, hi) = (fixed_step::min_steps_per_period(&d32), fixed_step::max_steps_per_period::<f32>());
        let n = lo + ((hi - lo) as f64 * k) as u32;
        let v = (x * d.c_forward::<Libm>()) as f32;
        match fixed_run(&d32, v, n) {
            Ok((m, bound)) => {
                let e = exact64(&d, f64::from(v));
                prop_assert!((m - e).abs() <= bound + 1e-9, "a={} b={} N={}: {} vs {} (bound {:e})", a, b, n, m, e, bound);
            }
            Err(e) => prop_assert!(matches!(e, FixedStepError::IllConditioned), "{:?}", e),
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    /// The fixed-step bound where it is most at risk: coarse grids, from the
    /// fewest accepted steps to 4× that (measured worst error/bound 0.43 over
    /// 20 000 random scenes).
    #[test]
    fn fixed_step_bound_holds_on_coarse_grids((a, b, phi) in wide_drive(), x in wide_velocity(), k in 0.0f64..3.0, back in any::<bool>()) {
        prop_assume!(b <= 1e3);
        let d = d64(a, b, phi);
        let c = if back { d.c_backward::<Libm>() } else { d.c_forward::<Libm>() };
        let v = if back { -x * c } else { x * c };
        prop_assume!(v != 0.0);
        let nmin = fixed_step::min_steps_per_period(&d);
        let n = nmin + (k * f64::from(nmin)) as u32;
        let Ok((m, bound)) = fixed_run(&d, v, n) else { return Ok(()); };
        let e = exact64(&d, v);
        prop_assert!((m - e).abs() <= bound + exact::error_bound::<f64, Libm>(&d), "a={} b={} phi={} v={} N={}: {} vs {} (bound {:e})", a, b, phi, v, n, m, e, bound);
    }
}
