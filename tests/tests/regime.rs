//! Regime classification: the paper's Figs. 5–7 scenes, the counter-
//! examples to the rule of thumb, and a brute-force scan on random scenes.

use std::f64::consts::{FRAC_PI_2, PI};

use integration_tests::{scene, scene_ratio, Rng};
use model_core::exact;
use model_core::regime::{classify, ClassifyOptions, Regime};
use model_core::{Drive, Libm};

fn regime(a: f64, ratio: f64, phi: f64) -> Regime {
    classify(&scene_ratio(a, ratio, phi), &ClassifyOptions::default())
        .unwrap()
        .regime
}

const PHASES: &[f64] = &[
    0.0,
    PI / 4.0,
    FRAC_PI_2,
    3.0 * PI / 4.0,
    PI,
    5.0 * PI / 4.0,
    3.0 * FRAC_PI_2,
];

/// At Δu_z/u_z0 = 0.5 and this amplitude ratio: active control (symmetric)
/// at φ = π/2 and 3π/2, a dynamic ratchet at every other phase of [`PHASES`].
fn ratchet_except_half_pi(ratio: f64) {
    for &phi in PHASES {
        let r = regime(0.5, ratio, phi);
        let want = if (phi - FRAC_PI_2).abs() < 1e-12 || (phi - 3.0 * FRAC_PI_2).abs() < 1e-12 {
            Regime::ActiveControl
        } else {
            Regime::DynamicRatchet
        };
        assert_eq!(r, want, "ratio {ratio}, φ = {phi}");
    }
}

#[test]
fn fig5_ratio_1_ratchets_and_symmetric_at_half_pi() {
    // Paper §3.2: Fig. 5 (ratio 1, Δu_z/u_z0 = 0.5) is symmetric at φ = π/2,
    // asymmetric otherwise, the extremes φ = 0, π being ratchets.
    ratchet_except_half_pi(1.0);
}

#[test]
fn fig6_ratio_2_actuator_except_half_pi() {
    // Paper: "The same situation [actuator] can be found in Fig. 6 for φ ≠ π/2."
    for &phi in PHASES {
        if (phi - FRAC_PI_2).abs() < 1e-12 || (phi - 3.0 * FRAC_PI_2).abs() < 1e-12 {
            continue;
        }
        assert_eq!(regime(0.5, 2.0, phi), Regime::Actuator, "φ = {phi}");
    }
    // At φ = π/2 the paper calls the law symmetric. Exactly, c = c' = √1.25 > 1:
    // no static equilibrium, and a net force at rest — the symmetry the paper
    // sees in Fig. 6 is only approximate (the scene is an actuator).
    let c = classify(
        &scene_ratio(0.5, 2.0, FRAC_PI_2),
        &ClassifyOptions::default(),
    )
    .unwrap();
    assert!(!c.statics.exists());
    assert_eq!(c.regime, Regime::Actuator);
    assert!((c.mu_0plus - c.mu_0minus).abs() < 1e-12 && c.mu_0plus.abs() > 0.01);
}

#[test]
fn fig7_ratio_half_ratchets_and_symmetric_at_half_pi() {
    // "Dynamic ratchets are realized for values of the governing parameter smaller than 1."
    ratchet_except_half_pi(0.5);
}

#[test]
fn fig4_dual_mode_at_phi_0_is_actuator() {
    // Fig. 4a, b (b = 1 and 2, φ = 0): every dual-mode curve (Δu_z > 0) is an actuator.
    for b in [1.0, 2.0] {
        for a in [0.1, 0.3, 0.5, 0.9] {
            let c = classify(&scene(a, b, 0.0), &ClassifyOptions::default()).unwrap();
            assert_eq!(c.regime, Regime::Actuator, "a={a} b={b}");
        }
        // ... except the purely tangential one (the upper-most curve).
        let c = classify(&scene(0.0, b, 0.0), &ClassifyOptions::default()).unwrap();
        assert_eq!(c.regime, Regime::ActiveControl, "a=0 b={b}");
    }
}

#[test]
fn single_mode_is_always_active_control() {
    for &(a, b) in &[(0.5, 0.0), (0.99, 0.0), (0.0, 0.3), (0.0, 1.0), (0.0, 5.0)] {
        for phi in [0.0, 1.0, 2.0, 3.0] {
            assert_eq!(
                classify(&scene(a, b, phi), &ClassifyOptions::default())
                    .unwrap()
                    .regime,
                Regime::ActiveControl,
                "a={a} b={b} φ={phi}"
            );
        }
    }
}

#[test]
fn where_the_rule_of_thumb_fails() {
    // Ratio 0.7 < 1 at Δu_z/u_z0 = 0.9, φ = 0: an actuator, not a ratchet.
    assert_eq!(regime(0.9, 0.7, 0.0), Regime::Actuator);
    // Ratio 3 > 1 at Δu_z/u_z0 = 0.2, φ = 0: a ratchet, not a drive.
    assert_eq!(regime(0.2, 3.0, 0.0), Regime::DynamicRatchet);
    // φ = π/2 with no static equilibrium: a net force at rest.
    assert_eq!(regime(0.3, 10.0, FRAC_PI_2), Regime::Actuator);
    // The exact actuator boundary with a static equilibrium: a²(1 + 2r|cos φ| + r²) = 1.
    for a in [0.2, 0.5, 0.9] {
        for phi in [0.0f64, 0.6, 2.0] {
            let k = f64::cos(phi).abs();
            let r_star = -k + (k * k - 1.0 + 1.0 / (a * a)).sqrt();
            assert_ne!(
                regime(a, r_star * 0.99, phi),
                Regime::Actuator,
                "a={a} φ={phi} r*={r_star}"
            );
            assert_eq!(
                regime(a, r_star * 1.01, phi),
                Regime::Actuator,
                "a={a} φ={phi} r*={r_star}"
            );
        }
    }
}

#[test]
fn classification_agrees_with_brute_force_scan() {
    // Brute force: μ(v)·v over a velocity grid (including |v| = 1e-7 v_c for the
    // force at rest) and μ(v) + μ(−v) for symmetry, with the exact solver at
    // individual velocities only.
    let mut rng = Rng::new(2024);
    let mut counts = [0usize; 3];
    let mut skipped = 0;
    for _ in 0..400 {
        let (a, b, phi) = (
            rng.range(0.0, 0.98),
            rng.range(0.0, 3.0),
            rng.range(-PI, PI),
        );
        let s = scene(a, b, phi);
        let d: Drive<f64> = s.drive();
        let cl = classify(&s, &ClassifyOptions::default()).unwrap();
        // Skip scenes within 1e-4 of the actuator boundary, where a grid cannot decide.
        if cl.mu_0plus.abs() < 1e-4 || cl.mu_0minus.abs() < 1e-4 {
            skipped += 1;
            continue;
        }
        let (c, cb) = (d.c_forward::<Libm>(), d.c_backward::<Libm>());
        let vmax = c.max(cb) * 1.05;
        let mut against_motion = false;
        let mut asym = 0.0f64;
        let mut grid: Vec<f64> = (1..=300).map(|i| vmax * i as f64 / 300.0).collect();
        grid.push(vmax * 1e-7);
        for v in grid {
            let f = exact::mu_over_mu0::<f64, Libm>(&d, v).unwrap();
            let g = exact::mu_over_mu0::<f64, Libm>(&d, -v).unwrap();
            against_motion |= f < -1e-9 || g > 1e-9;
            asym = asym.max((f + g).abs());
        }
        let brute = if against_motion {
            Regime::Actuator
        } else if asym <= 1e-9 {
            Regime::ActiveControl
        } else {
            Regime::DynamicRatchet
        };
        assert_eq!(cl.regime, brute, "a={a} b={b} φ={phi}: {cl:?}");
        counts[cl.regime as usize] += 1;
    }
    println!("active/ratchet/actuator = {counts:?}, skipped {skipped}");
    // The random set must exercise the two asymmetric classes.
    assert!(counts[1] > 20 && counts[2] > 20, "{counts:?}");
}

#[test]
fn velocity_law_is_monotone() {
    // The reason μ(0±) decide the actuator class: μ(v) is non-decreasing.
    let mut rng = Rng::new(99);
    for _ in 0..300 {
        let (a, b, phi) = (
            rng.range(0.0, 0.98),
            rng.range(0.0, 4.0),
            rng.range(-PI, PI),
        );
        let d = scene(a, b, phi).drive();
        let (c, cb) = (d.c_forward::<Libm>(), d.c_backward::<Libm>());
        let mut prev = -1.0;
        for i in 0..=400 {
            let v = -cb * 1.01 + (c + cb) * 1.02 * i as f64 / 400.0;
            if v == 0.0 {
                continue;
            }
            let m = exact::mu_over_mu0::<f64, Libm>(&d, v).unwrap();
            assert!(m >= prev - 1e-12, "a={a} b={b} φ={phi} v={v}: {m} < {prev}");
            prev = m;
        }
    }
}
