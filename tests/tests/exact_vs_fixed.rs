//! The exact solver against the paper's fixed-step scheme (an independent
//! computation: no events, no root finding), the N⁻² convergence of the scheme,
//! the symmetries of the model and f32 against f64.

use std::f64::consts::{FRAC_PI_2, PI, TAU};

use integration_tests::{fixed, fixed_bounded, scene, Rng};
use model_core::analytic::CriticalVelocity;
use model_core::exact::{self, solve, ExactError};
use model_core::fixed_step::{
    run, run_dimensionless, FixedStepConfig, FixedStepError, Start, State, ROUNDING_K,
};
use model_core::{Drive, Groups, Libm, Scene, SceneParams};

/// Scenes covering the regimes (a, b, φ) and velocities as fractions of v_c.
const CASES: &[(f64, f64, f64)] = &[
    (0.5, 0.0, 0.0),       // normal only
    (0.0, 0.7, 0.4),       // tangential only, small
    (0.0, 3.0, 0.4),       // tangential only, large (back slip every period)
    (0.5, 0.25, 1.0),      // ratchet
    (0.5, 1.0, 0.3),       // actuator
    (0.9, 0.63, 0.0),      // actuator at ratio 0.7
    (0.5, 1.0, FRAC_PI_2), // no static equilibrium
    (0.95, 0.2, 2.8),      // near lift-off
];
const FRACTIONS: &[f64] = &[-0.95, -0.6, -0.2, 0.05, 0.3, 0.7, 0.97];

fn v_of(d: &Drive<f64>, x: f64) -> f64 {
    x * if x > 0.0 {
        d.c_forward::<Libm>()
    } else {
        d.c_backward::<Libm>()
    }
}

#[test]
fn exact_agrees_with_fine_fixed_step() {
    const N: u32 = 1 << 16;
    let mut worst = 0.0f64;
    for &(a, b, phi) in CASES {
        let d = scene(a, b, phi).drive();
        for &x in FRACTIONS {
            let v = v_of(&d, x);
            if v == 0.0 {
                continue;
            }
            let e = exact::mu_over_mu0::<f64, Libm>(&d, v).unwrap();
            // The scheme at N = 65 536 against the exact value. Tolerance: the
            // two stated bounds. The scheme's, (1 + b)(K_D/N² + K_R·N·ε) =
            // 2.34e-9·(1 + b), has constants calibrated on the scheme alone
            // (tests/fixed_step_bound.rs), so this is an independent check;
            // the exact solver's is 1e-9·(1 + b). (Richardson extrapolation
            // from N/2 does not tighten this: the error jitters with where the
            // events fall on the grid.)
            let (f2, fb) = fixed_bounded(&d, v, N);
            let tol = fb + exact::error_bound::<f64, Libm>(&d);
            let err = (f2 - e).abs();
            worst = worst.max(err);
            assert!(
                err <= tol,
                "a={a} b={b} φ={phi} x={x}: exact {e} fixed {f2} (tol {tol:e})"
            );
        }
    }
    println!("worst |exact − fixed(65536)| = {worst:.2e}");
    // The README's figure, "8.8e-10 worst of 56 points", to its two digits.
    assert!((worst - 8.8e-10).abs() <= 0.05e-10, "{worst:e}");
}

#[test]
fn fixed_step_error_falls_like_n_squared() {
    // Least-squares slope of log|error| against log N over N = 2⁶ … 2¹⁴
    // (several N per octave, because the error jitters with where the events
    // fall on the grid), for three scenes.
    // The README quotes the fitted orders: 2.01, 2.02, 2.00.
    for &(a, b, phi, x, readme) in &[
        (0.5, 0.0, 0.0, 0.3, 2.01),
        (0.5, 0.25, 1.0, 0.4, 2.02),
        (0.0, 3.0, 0.4, -0.5, 2.00),
    ] {
        let d = scene(a, b, phi).drive();
        let v = v_of(&d, x);
        let e = exact::mu_over_mu0::<f64, Libm>(&d, v).unwrap();
        let mut pts = Vec::new();
        let mut n = 64.0f64;
        while n <= 16384.0 {
            let err = (fixed(&d, v, n as u32) - e).abs();
            pts.push((n.ln(), err.max(1e-300).ln()));
            n *= 2f64.powf(0.25);
        }
        let m = pts.len() as f64;
        let (sx, sy) = pts
            .iter()
            .fold((0.0, 0.0), |(sx, sy), p| (sx + p.0, sy + p.1));
        let (mx, my) = (sx / m, sy / m);
        let sxx = pts.iter().map(|p| (p.0 - mx) * (p.0 - mx)).sum::<f64>();
        let slope = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum::<f64>() / sxx;
        // The slope's standard error from the residuals (which carry the
        // error's jitter with where the events fall on the grid), and the
        // two-sided 95 % Student quantile for the 33 − 2 = 31 degrees of
        // freedom of the 33 points (2⁶ … 2¹⁴, four per octave).
        let c = my - slope * mx;
        let ss = pts
            .iter()
            .map(|p| (p.1 - c - slope * p.0).powi(2))
            .sum::<f64>();
        assert_eq!(pts.len(), 33);
        let se = (ss / (m - 2.0) / sxx).sqrt();
        let band = 2.040 * se;
        println!(
            "a={a} b={b} φ={phi} v/vc={x}: fitted order {:.3} ± {band:.3} (95 %)",
            -slope
        );
        assert!(
            (-slope - readme).abs() < 0.005,
            "order {} (README: {readme})",
            -slope
        );
        assert!(
            (-slope - 2.0).abs() <= band,
            "order {} (expected 2 ± {band})",
            -slope
        );
    }
}

#[test]
fn mirror_symmetry() {
    // μ(v, φ) = −μ(−v, φ+π): the exact solver uses the mirror for v < 0, so check
    // it against the fixed-step scheme run directly at −v, and the exact values
    // of the two scenes against each other (φ+π rounded independently).
    let mut rng = Rng::new(3);
    for _ in 0..40 {
        let (a, b, phi) = (
            rng.range(0.0, 0.95),
            rng.range(0.0, 2.0),
            rng.range(-PI, PI),
        );
        let d1 = scene(a, b, phi).drive();
        let d2 = scene(a, b, phi + PI).drive();
        let v = v_of(&d1, rng.range(0.05, 0.95));
        let m1 = exact::mu_over_mu0::<f64, Libm>(&d1, v).unwrap();
        let m2 = exact::mu_over_mu0::<f64, Libm>(&d2, -v).unwrap();
        assert!((m1 + m2).abs() <= 1e-12, "{m1} vs {m2}");
        // Tolerance: the two stated bounds, the scheme's at N = 16 384
        // ((1 + b)(K_D/N² + K_R·N·ε) = 3.7e-8·(1 + b)) and the exact solver's.
        let (f2, fb) = fixed_bounded(&d2, -v, 1 << 14);
        let tol = fb + exact::error_bound::<f64, Libm>(&d1);
        assert!(
            (m1 + f2).abs() <= tol,
            "exact {m1} vs fixed(−v, φ+π) {f2} (tol {tol:e})"
        );
    }
}

#[test]
fn mu_over_mu0_depends_only_on_the_dimensionless_groups() {
    // Eq. 25: scale ω, k_z, k_x, u_z0 (and the amplitudes with them) — same μ/μ₀.
    let base = SceneParams {
        mu0: 0.4,
        kz: 3e6,
        kx: 1e6,
        uz0: 4e-6,
        duz: 1.6e-6,
        dux: 2.1e-6,
        omega: TAU * 30e3,
        phi: 0.8,
    };
    let s0 = Scene::new(base).unwrap();
    let vc0 = CriticalVelocity::of(&s0);
    for &(kw, kk, kzr, ku) in &[
        (10.0, 1.0, 1.0, 1.0),
        (0.01, 7.0, 0.3, 1e3),
        (1e5, 1e-3, 5.0, 1e-4),
    ] {
        let p = SceneParams {
            omega: base.omega * kw,
            kz: base.kz * kk * kzr,
            kx: base.kx * kk,
            uz0: base.uz0 * ku,
            duz: base.duz * ku,
            // Keep k_xΔu_x/(μ₀k_z u_z0) fixed.
            dux: base.dux * kzr * ku,
            ..base
        };
        let s = Scene::new(p).unwrap();
        let vc = CriticalVelocity::of(&s);
        for x in [-0.7, -0.1, 0.2, 0.6, 0.95] {
            let m0 = solve(&s0, x * if x > 0.0 { vc0.forward } else { vc0.backward })
                .unwrap()
                .mu_over_mu0()
                .unwrap();
            let m = solve(&s, x * if x > 0.0 { vc.forward } else { vc.backward })
                .unwrap()
                .mu_over_mu0()
                .unwrap();
            assert!(
                (m - m0).abs() <= 1e-12,
                "scaling {kw},{kk},{kzr},{ku} x={x}: {m} vs {m0}"
            );
        }
    }
}

#[test]
fn phi_half_pi_is_symmetric_while_static_equilibrium_exists() {
    for &(a, b) in &[(0.5, 0.5), (0.5, 0.25), (0.2, 0.3), (0.8, 0.3), (0.3, 0.9)] {
        let d = scene(a, b, FRAC_PI_2).drive();
        assert!(d.c_forward::<Libm>() <= 1.0); // static equilibrium exists (c = c' ≤ 1)
        for i in 1..50 {
            let v = d.c_forward::<Libm>() * i as f64 / 50.0;
            let f = exact::mu_over_mu0::<f64, Libm>(&d, v).unwrap();
            let g = exact::mu_over_mu0::<f64, Libm>(&d, -v).unwrap();
            assert!((f + g).abs() <= 1e-13, "a={a} b={b} v={v}: {f} vs {g}");
        }
    }
    // Without a static equilibrium (c = c' > 1) the law is not symmetric: a net
    // force at rest, checked against the fixed-step scheme at small |v|.
    let d = scene(0.5, 1.0, FRAC_PI_2).drive();
    let (p, m) = exact::limits_at_zero::<f64, Libm>(&d).unwrap();
    assert!((p - m).abs() <= 1e-12 && p.abs() > 0.01, "{p} {m}");
    // The README's figure for Fig. 6 at φ = π/2: μ(0±)/μ₀ = 0.0348.
    assert!((p - 0.0348).abs() < 5e-5, "{p}");
    // μ(V) = μ(0⁺) + sV + O(V²) near 0 (measured s = 1.115, the V² term
    // −1.1·V²): the two-point extrapolation 2μ(V) − μ(2V) removes the linear
    // term. Tolerance: the three runs' stated bounds (N = 16 384:
    // 10(1 + b)/N² = 7.5e-8 each, μ(V) counted twice) plus the remainder,
    // 2|C|V² = 2.3e-8 measured, allowed 10·V² = 1e-7: 3.2e-7.
    let v = 1e-4;
    let (near, fb1) = fixed_bounded(&d, v, 1 << 14);
    let (near2, fb2) = fixed_bounded(&d, 2.0 * v, 1 << 14);
    let extrapolated = 2.0 * near - near2;
    let tol = 2.0 * fb1 + fb2 + 10.0 * v * v;
    println!(
        "μ(1e-4) − μ(0+) = {:.3e}; 2μ(V) − μ(2V) − μ(0+) = {:.2e} (tol {tol:.1e})",
        near - p,
        extrapolated - p
    );
    assert!(
        (extrapolated - p).abs() <= tol,
        "2μ(V) − μ(2V) = {extrapolated}, μ(0+) = {p}"
    );
    // And μ is non-decreasing: μ(V) ≥ μ(0⁺) within the scheme's bound.
    assert!(near >= p - fb1, "μ(1e-4) = {near} < μ(0+) = {p}");
}

#[test]
fn f32_agrees_with_f64() {
    let mut rng = Rng::new(5);
    let mut worst = 0.0f64;
    let mut worst_rel = 0.0f64;
    for _ in 0..2000 {
        let (a, b, phi) = (
            rng.range(0.0, 0.95),
            rng.range(0.0, 3.0),
            rng.range(-PI, PI),
        );
        let x = rng.range(-0.99, 0.99);
        let d64 = scene(a, b, phi).drive();
        let v = v_of(&d64, x);
        if v == 0.0 {
            continue;
        }
        let s32 = Scene::<f32>::dimensionless(Groups {
            duz_rel: a as f32,
            dux_rel: b as f32,
            phi: phi as f32,
        })
        .unwrap();
        let m64 = exact::mu_over_mu0::<f64, Libm>(&d64, v).unwrap();
        let m32 = exact::mu_over_mu0::<f32, Libm>(&s32.drive(), v as f32).unwrap();
        // Reference: the f64 solver on the f32-rounded inputs, so only the
        // arithmetic differs.
        let d_r = scene(
            f64::from(a as f32),
            f64::from(b as f32),
            f64::from(phi as f32),
        )
        .drive();
        let m_r = exact::mu_over_mu0::<f64, Libm>(&d_r, f64::from(v as f32)).unwrap();
        let err = (f64::from(m32) - m_r).abs();
        worst = worst.max(err);
        worst_rel = worst_rel.max(err / (1.0 + b) / f64::from(f32::EPSILON));
        // Only the arithmetic differs: f32 rounding of a stretch of size up to
        // 1 + b, measured worst 1.46·(1 + b)·ε₃₂ over these scenes (1.40 before
        // the root finder's rotations, `exact::period::root`); tolerance
        // 2(1 + b)ε₃₂ (≤ 9.5e-7), well inside the solver's stated f32 bound 1e-6·(1 + b).
        let tol = 2.0 * (1.0 + b) * f64::from(f32::EPSILON);
        assert!(
            err <= tol,
            "a={a} b={b} φ={phi} x={x}: f32 {m32} vs f64 {m_r} (unrounded {m64}, tol {tol:e})"
        );
    }
    println!("worst |μ_f32 − μ_f64| = {worst:.2e}, worst err/((1+b)ε) = {worst_rel:.2}");
    // The guide's figure (docs/guide/f32-accuracy.md: 7.0e-7, printed above;
    // measured 6.97e-7).
    assert!(worst <= 7.0e-7, "{worst:e}");
}

/// The scheme in f32 against the same scheme in f64 on the f32-rounded
/// drive and velocity, at the same N = 2048 (≤ the f32 limit 2 204) and from
/// rest: the same discrete map, so only the arithmetic differs. Tolerance:
/// the rounding part of the two stated bounds, `(1 + b)·K_R·N·ε` in each
/// precision (the libm backends' set-up error is 0): 2.4e-4·(1 + b) for f32.
#[test]
fn fixed_step_f32_agrees_with_f64() {
    const N: u32 = 2048;
    let mut worst: f64 = 0.0;
    for &(a, b, phi) in CASES {
        let d32 = Drive::new::<Libm>(a as f32, b as f32, phi as f32);
        let d = Drive::new::<Libm>(f64::from(d32.a), f64::from(d32.b), f64::from(phi as f32));
        let v32 = v_of(&d, 0.3) as f32;
        let cfg = FixedStepConfig::<f32>::new(N);
        let m32 = run_dimensionless::<f32, Libm>(&d32, v32, &cfg, Start::Rest)
            .unwrap()
            .mu_over_mu0;
        let m64 = fixed(&d, f64::from(v32), N);
        let n = f64::from(N);
        let tol = (1.0 + d.b) * ROUNDING_K * n * (f64::from(f32::EPSILON) + f64::EPSILON);
        let gap = (f64::from(m32) - m64).abs();
        worst = worst.max(gap / ((1.0 + d.b) * n * f64::from(f32::EPSILON)));
        assert!(gap <= tol, "{m32} vs {m64} (tol {tol:e})");
    }
    println!("worst |f32 − f64|/((1 + b)·N·ε₃₂) = {worst:.3}");
}

#[test]
fn fixed_step_refusals() {
    let s = scene(0.5, 0.2, 0.3);
    let cfg = FixedStepConfig::<f64>::new(1024);
    assert_eq!(
        run(&s, 0.0, &cfg, Start::Rest),
        Err(FixedStepError::ZeroVelocity)
    );
    assert_eq!(
        run(&s, 0.1, &FixedStepConfig::new(10), Start::Rest),
        // ⌈√(K_D(1 + b)/0.1)⌉ = ⌈√120⌉ = 11 for b = 0.2.
        Err(FixedStepError::TooFewSteps { min_steps: 11 })
    );
    assert!(matches!(
        run(&s, f64::NAN, &cfg, Start::Rest),
        Err(FixedStepError::BadVelocity(_))
    ));
    let bad = Start::State(State {
        phase: 0.0,
        stretch: 0.9,
    }); // w(0) = 0.5
    assert_eq!(run(&s, 0.1, &cfg, bad), Err(FixedStepError::BadStart));
    let mut c2 = cfg;
    c2.tol = -1.0;
    assert_eq!(
        run(&s, 0.1, &c2, Start::Rest),
        Err(FixedStepError::BadConfig)
    );
    // Low velocity from rest: the transient (≈ 1/(2πV) periods) exceeds the limit,
    // and the last value is returned only inside the error — even though the
    // change per period (≈ 2πV ≈ 6e-9) would pass a naive tolerance test.
    let mut c3 = FixedStepConfig::<f64>::new(256);
    c3.max_periods = 1000;
    c3.tol = 1e-6;
    match run(&s, 1e-9, &c3, Start::Rest) {
        Err(FixedStepError::NotConverged {
            periods,
            last_change,
            ..
        }) => {
            assert_eq!(periods, 1000);
            assert!(last_change < c3.tol);
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn fixed_step_warm_start_at_the_window_end() {
    // Start at the steady state's forward-window end (s = +w): the first
    // periods are already steady, and μ is the same as from rest.
    let s = scene(0.5, 0.25, 1.0);
    let d = s.drive();
    let v = v_of(&d, 0.4);
    let (_, arcs) = exact::steady_state::<f64, Libm>(&d, v).unwrap();
    let end = arcs.last().unwrap().end; // end of forward slip = window end θ_e (+2π)
    let w = 1.0 - 0.5 * end.cos();
    let cfg = FixedStepConfig::<f64>::new(8192);
    let warm = run_dimensionless::<f64, Libm>(
        &d,
        v,
        &cfg,
        Start::State(State {
            phase: end,
            stretch: w,
        }),
    )
    .unwrap();
    let rest = run_dimensionless::<f64, Libm>(&d, v, &cfg, Start::Rest).unwrap();
    let e = exact::mu_over_mu0::<f64, Libm>(&d, v).unwrap();
    // Each within its stated bound ((1 + b)(K_D/N² + K_R·N·ε) = 1.9e-7 at
    // N = 8192, b = 0.25) plus the exact solver's; the warm run is steady at
    // once (it needs no more than the 3 periods of the proof).
    let eb = exact::error_bound::<f64, Libm>(&d);
    assert!(warm.periods <= 3, "{} periods", warm.periods);
    for (what, r) in [("warm", warm), ("rest", rest)] {
        assert!(
            (r.mu_over_mu0 - e).abs() <= r.error_bound + eb,
            "{what}: {} vs exact {e} (bound {:e})",
            r.mu_over_mu0,
            r.error_bound
        );
    }
}

#[test]
fn exact_rejects_bad_velocity() {
    let s = scene(0.5, 0.2, 0.3);
    assert!(matches!(
        solve(&s, f64::NAN),
        Err(ExactError::BadVelocity(_))
    ));
    assert!(matches!(
        solve(&s, f64::INFINITY),
        Err(ExactError::BadVelocity(_))
    ));
    assert!(exact::mu_over_mu0::<f64, Libm>(&s.drive(), 0.0).is_err());
    // Hand-built drives that no scene produces are refused, never looped on.
    let good = s.drive();
    for bad in [
        Drive {
            a: f64::NAN,
            ..good
        },
        Drive { a: 1.0, ..good },
        Drive { b: -0.1, ..good },
        Drive {
            bc: f64::INFINITY,
            ..good
        },
        Drive { bc: 5.0, ..good }, // not b·cos φ
    ] {
        assert_eq!(
            exact::mu_over_mu0::<f64, Libm>(&bad, 0.1),
            Err(ExactError::BadDrive),
            "{bad:?}"
        );
        assert_eq!(
            exact::limits_at_zero::<f64, Libm>(&bad),
            Err(ExactError::BadDrive)
        );
        assert!(exact::steady_state::<f64, Libm>(&bad, 0.1).is_err());
        let cfg = FixedStepConfig::<f64>::new(64);
        assert_eq!(
            run_dimensionless::<f64, Libm>(&bad, 0.1, &cfg, Start::Rest),
            Err(FixedStepError::BadDrive)
        );
    }
}

#[test]
fn the_prediction_shares_the_critical_velocities_without_changing_a_bit() {
    // `exact::solve_with_critical` (the board's prediction) takes c and c'
    // from the scene (formed once, with libm) and hands them to the solver,
    // which mirrors them for v0 < 0: its μ
    // must be the bits of `solve_with`'s, and its critical velocities those of
    // eq. 8, c = |b e^{iφ} ± a| = √(a² ± 2ab cos φ + b²) (times ωW₀ = 1 in
    // these dimensionless scenes), to the rounding of the two forms (a few ε
    // of a + b). Both directions, every regime of CASES, f64 with libm and
    // f32 with the board's FastF32.
    use model_core::float::FastF32;
    for &(a, b, phi) in CASES {
        let s = scene(a, b, phi);
        let sf = Scene::<f32>::dimensionless(Groups {
            duz_rel: a as f32,
            dux_rel: b as f32,
            phi: phi as f32,
        });
        let eq8 = |sgn: f64| (a * a + sgn * 2.0 * a * b * phi.cos() + b * b).sqrt();
        for &x in FRACTIONS {
            let vc = CriticalVelocity::of(&s);
            let v = x * vc.for_velocity(x);
            let (got, got_vc) = exact::solve_with_critical::<f64, Libm>(&s, v).unwrap();
            assert_eq!(got, solve(&s, v).unwrap(), "a={a} b={b} φ={phi} x={x}");
            for (c, want) in [(got_vc.forward, eq8(1.0)), (got_vc.backward, eq8(-1.0))] {
                assert!(
                    (c - want).abs() <= 8.0 * f64::EPSILON * (a + b),
                    "a={a} b={b} φ={phi}: {c} vs eq. 8 {want}"
                );
            }
            let Ok(sf) = &sf else { continue };
            let vf = (x as f32) * CriticalVelocity::of_with::<FastF32>(sf).for_velocity(x as f32);
            let (got, got_vc) = exact::solve_with_critical::<f32, FastF32>(sf, vf).unwrap();
            let want = exact::solve_with::<f32, FastF32>(sf, vf).unwrap();
            assert_eq!(got, want, "f32: a={a} b={b} φ={phi} x={x}");
            // The scene's own c, c' (formed once with libm's f32 hypot):
            // eq. 8 in f64 on the f32-rounded groups, within the f32
            // roundings of b·(cos φ, sin φ), the sum and hypot (a few ε₃₂ of
            // a + b), or of 0 where the value is counted as exactly 0
            // (`is_zero_critical_velocity`: up to 32 ε₃₂ of a + b): 32 ε₃₂·(a + b).
            let (af, bf, pf) = (
                f64::from(a as f32),
                f64::from(b as f32),
                f64::from(phi as f32),
            );
            let eq8f = |sgn: f64| (af * af + sgn * 2.0 * af * bf * pf.cos() + bf * bf).sqrt();
            let tol = 32.0 * f64::from(f32::EPSILON) * (af + bf);
            for (c, want) in [(got_vc.forward, eq8f(1.0)), (got_vc.backward, eq8f(-1.0))] {
                assert!(
                    (f64::from(c) - want).abs() <= tol,
                    "f32: a={a} b={b} φ={phi}: {c} vs eq. 8 {want}"
                );
            }
        }
    }
}
