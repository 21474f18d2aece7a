//! The fixed-step scheme's discretisation constant `K_D`
//! (`fixed_step::DISCRETISATION_K`) calibrated by **self-convergence of the
//! scheme alone**: no exact solver, no other model-core solver is called.
//!
//! For each scene the scheme runs at a reference `N_ref = 2¹⁸` steps per
//! period and at coarser `N`; the stated bound is `|μ_N − μ|/μ₀ ≤
//! (1 + b)(K_D/N² + K_R·N·ε + backend)`. Writing `μ_ref` for the run at
//! `N_ref`,
//!
//! `|μ_N − μ| ≤ |μ_N − μ_ref| + |μ_ref − μ| ≤ |μ_N − μ_ref| + (1 + b)(K/N_ref² + N_ref·ε)`,
//!
//! so with `K = sup_N |μ_N − μ|·N²/(1 + b)` (the discretisation constant the
//! bound needs) and `r = max (N/N_ref)²`,
//!
//! `K ≤ (K_obs + N_ref·ε·N_max²)/(1 − r)`,  `K_obs = max |μ_N − μ_ref|·N²/(1 + b)`:
//!
//! the doubling-difference estimate `|F(N) − F(2N)|·4/3` summed over every
//! doubling from `N` to `N_ref` (a telescoping sum), with the tail beyond
//! `N_ref` bounded by the constant itself. `N ≤ 4 096` keeps `r ≤ 2.4·10⁻⁴`;
//! the rounding of the reference, `N_ref·ε = 5.8·10⁻¹¹`, adds at most
//! `5.8·10⁻¹¹·4096² = 10⁻³` to the constant. Each run starts on the band
//! edge ([`integration_tests::fixed_warm`]): the bound holds for any start,
//! and the run is steady after ≈ 3 periods at any velocity.
//!
//! The exact solver is compared with the scheme *within this bound* in
//! `exact_vs_fixed.rs` and `stability.rs`; those comparisons are independent
//! only because the constant is calibrated here without it.

use std::f64::consts::PI;

use integration_tests::{fixed_warm, scene, Rng};
use model_core::fixed_step::{
    self, run_dimensionless, FixedStepConfig, Start, DISCRETISATION_K, ROUNDING_K,
};
use model_core::{Drive, Libm, Math};

/// Reference steps per period.
const N_REF: u32 = 1 << 18;
/// Largest calibrated N.
const N_MAX: u32 = 4096;

/// The worst constant measured here, as `fixed_step::DISCRETISATION_K`'s
/// documentation states it (three digits).
const DOCUMENTED_WORST: f64 = 4.75;

/// `v = x·c` with `c` the critical velocity on the side of `x`.
fn v_of(d: &Drive<f64>, x: f64) -> f64 {
    x * if x > 0.0 {
        d.c_forward::<Libm>()
    } else {
        d.c_backward::<Libm>()
    }
}

/// Steps per period to calibrate at for drive `d`: four per octave from
/// `N_min` to `N_MAX`, and every N of the coarsest octave `[N_min, 2N_min]`
/// sampled eight times (where the constant is largest: the steps barely
/// resolve the stick windows).
fn grid(d: &Drive<f64>) -> Vec<u32> {
    let nmin = fixed_step::min_steps_per_period(d);
    let mut ns = Vec::new();
    for k in 0..8 {
        ns.push(nmin + k * nmin / 8);
    }
    let mut x = f64::from(nmin);
    while x <= f64::from(N_MAX) {
        ns.push(x.round() as u32);
        x *= 2f64.powf(0.25);
    }
    ns.sort_unstable();
    ns.dedup();
    ns.retain(|&n| n <= N_MAX);
    ns
}

/// `(K_obs, worst N)` of one scene: `max |μ_N − μ_ref|·N²/(1 + b)`.
fn scene_constant(d: &Drive<f64>, v: f64) -> (f64, u32) {
    let (reference, _) = fixed_warm(d, v, N_REF);
    let mut worst = (0.0f64, 0u32);
    for n in grid(d) {
        let (m, _) = fixed_warm(d, v, n);
        let k = (m - reference).abs() * f64::from(n) * f64::from(n) / (1.0 + d.b);
        if k > worst.0 {
            worst = (k, n);
        }
    }
    worst
}

/// The scenes of the calibration: the work-precision bench's eight, the
/// `exact_vs_fixed` cases at seven velocities each, and 300 random scenes
/// with `a` up to `1 − 10⁻⁶`, `b` from 10⁻⁴ to 300 (log-uniform) and
/// `|v|/v_c` from 10⁻³ to `1 − 10⁻⁶`, both directions.
fn scenes() -> Vec<(f64, f64, f64, f64)> {
    let mut out = vec![
        (0.5, 0.0, 0.0, 0.3),
        (0.0, 0.5, 0.4, 0.3),
        (0.0, 3.0, 0.4, -0.5),
        (0.5, 0.25, 1.0, 0.4),
        (0.5, 1.0, 0.3, 0.2),
        (0.5, 0.25, 1.0, 0.98),
        (0.5, 0.25, 1.0, 0.02),
        (0.97, 0.3, 2.0, 0.4),
    ];
    for &(a, b, phi) in &[
        (0.5, 0.0, 0.0),
        (0.0, 0.7, 0.4),
        (0.0, 3.0, 0.4),
        (0.5, 0.25, 1.0),
        (0.5, 1.0, 0.3),
        (0.9, 0.63, 0.0),
        (0.5, 1.0, PI / 2.0),
        (0.95, 0.2, 2.8),
    ] {
        for x in [-0.95, -0.6, -0.2, 0.05, 0.3, 0.7, 0.97] {
            out.push((a, b, phi, x));
        }
    }
    let mut rng = Rng::new(0x6b5f_d15c);
    for _ in 0..1000 {
        let a = if rng.uniform() < 0.8 {
            rng.range(0.0, 0.99)
        } else {
            1.0 - 10f64.powf(rng.range(-6.0, -2.0))
        };
        let b = 10f64.powf(rng.range(-4.0, 300f64.log10()));
        let phi = rng.range(-PI, PI);
        let x = if rng.uniform() < 0.7 {
            10f64.powf(rng.range(-3.0, 0.0)).min(1.0 - 1e-6)
        } else {
            1.0 - 10f64.powf(rng.range(-6.0, -1.0))
        };
        let x = if rng.uniform() < 0.5 { x } else { -x };
        out.push((a, b, phi, x));
    }
    out
}

/// The calibration: every scene's constant, the worst against `K_D`.
///
/// Assertions (two-sided on the measured constant):
/// * the bound's constant holds with the reference's own error included,
///   `(K_obs + N_ref·ε·N_max²)/(1 − r) ≤ K_D`, with a factor of at least 2 to
///   spare for scenes not sampled here (`≤ K_D/2`);
/// * the measured worst is the documented one (`DOCUMENTED_WORST`, three
///   digits: ±0.01), so the documentation cannot drift from the calibration.
#[test]
fn discretisation_constant_by_self_convergence() {
    let mut worst = (0.0f64, (0.0, 0.0, 0.0, 0.0), 0u32);
    let all = scenes();
    for &(a, b, phi, x) in &all {
        let d = scene(a, b, phi).drive();
        let v = v_of(&d, x);
        if v == 0.0 {
            continue;
        }
        let (k, n) = scene_constant(&d, v);
        if k > worst.0 {
            worst = (k, (a, b, phi, x), n);
        }
    }
    let (k_obs, (a, b, phi, x), n) = worst;
    let r = (f64::from(N_MAX) / f64::from(N_REF)).powi(2);
    let nmax2 = f64::from(N_MAX) * f64::from(N_MAX);
    let k = (k_obs + f64::from(N_REF) * f64::EPSILON * nmax2) / (1.0 - r);
    println!(
        "K_D by self-convergence over {} scenes: worst measured {k_obs:.3} \
         (with the reference's error {k:.3}) at a={a} b={b} φ={phi} v/v_c={x} N={n}; \
         stated K_D = {DISCRETISATION_K}",
        all.len()
    );
    assert!(
        k <= DISCRETISATION_K / 2.0,
        "K = {k} leaves less than a factor 2 to K_D = {DISCRETISATION_K}"
    );
    assert!(
        (k_obs - DOCUMENTED_WORST).abs() <= 0.01,
        "measured worst {k_obs:.3}, documented {DOCUMENTED_WORST}"
    );
}

/// The reference runs are converged: on the calibration's first scenes the
/// doubling difference at the reference, `|F(N_ref/2) − F(N_ref)|·4/3`, is
/// within the bound's discretisation part at `N_ref/2` (`K_D(1 + b)/(N_ref/2)²`,
/// ≈ 1.5·10⁻¹⁰(1 + b)) plus both runs' rounding, `(N_ref/2 + N_ref)·ε(1 + b)`,
/// so the reference's error `K_D(1 + b)/N_ref²` is ≤ 4·10⁻¹¹(1 + b).
#[test]
fn reference_runs_are_converged() {
    for &(a, b, phi, x) in &scenes()[..8] {
        let d = scene(a, b, phi).drive();
        let v = v_of(&d, x);
        let (fine, _) = fixed_warm(&d, v, N_REF);
        let (half, _) = fixed_warm(&d, v, N_REF / 2);
        let est = (half - fine).abs() * 4.0 / 3.0;
        let nh = f64::from(N_REF / 2);
        let allowed = (1.0 + b)
            * (DISCRETISATION_K / (nh * nh) + (nh + f64::from(N_REF)) * f64::EPSILON)
            * 4.0
            / 3.0;
        assert!(
            est <= allowed,
            "a={a} b={b} φ={phi} x={x}: |F(N_ref/2) − F(N_ref)|·4/3 = {est:e} > {allowed:e}"
        );
    }
}

/// The rounding constant `K_R` (`fixed_step::ROUNDING_K`) by the same
/// scheme in two precisions: f32 against f64 on the f32-rounded drive and
/// velocity, at the same N and from the same start (rest), so the two runs
/// are the same discrete map and differ only by the f32 arithmetic. The
/// difference, over `(1 + b)·N·ε₃₂` (the f64 run's own rounding,
/// `N·ε₆₄(1 + b)`, is 2·10⁻⁹ of that and the f32 backend's set-up error
/// `Libm::MAX_REL_ERROR` is 0), is the constant the bound needs; over the
/// calibration's first 64 scenes and N from `N_min` to the f32 limit 4N*
/// (2 204) it must be within `K_R`, with a factor 2 to spare, and is printed.
#[test]
fn rounding_constant_by_f32_against_f64() {
    assert_eq!(<Libm as Math<f32>>::MAX_REL_ERROR, 0.0);
    let eps32 = f64::from(f32::EPSILON);
    let mut worst = (0.0f64, 0u32);
    for &(a, b, phi, x) in &scenes()[..64] {
        let d32 = Drive::new::<Libm>(a as f32, b as f32, phi as f32);
        let d = Drive::new::<Libm>(f64::from(d32.a), f64::from(d32.b), f64::from(phi as f32));
        let v32 = v_of(&d, x) as f32;
        if v32 == 0.0 {
            continue;
        }
        let nmin = fixed_step::min_steps_per_period(&d32);
        let nmax = fixed_step::max_steps_per_period::<f32>();
        let mut n = nmin;
        while n <= nmax {
            let mut c32 = FixedStepConfig::<f32>::new(n);
            c32.max_periods = 2_000_000;
            let mut c64 = FixedStepConfig::<f64>::new(n);
            c64.max_periods = 2_000_000;
            let (Ok(r32), Ok(r64)) = (
                run_dimensionless::<f32, Libm>(&d32, v32, &c32, Start::Rest),
                run_dimensionless::<f64, Libm>(&d, f64::from(v32), &c64, Start::Rest),
            ) else {
                panic!("a={a} b={b} φ={phi} x={x} N={n}: a run did not converge");
            };
            let k = (f64::from(r32.mu_over_mu0) - r64.mu_over_mu0).abs()
                / ((1.0 + f64::from(d32.b)) * f64::from(n) * eps32);
            if k > worst.0 {
                worst = (k, n);
            }
            n = (n * 2).min(if n == nmax { nmax + 1 } else { nmax });
        }
    }
    println!(
        "K_R by f32 against f64: worst {:.3} at N = {} (stated {ROUNDING_K})",
        worst.0, worst.1
    );
    assert!(worst.0 <= ROUNDING_K / 2.0, "K_R measured {}", worst.0);
}

/// The lift-off stepping's constant (`liftoff::stepping::DISCRETISATION_K`,
/// bound `(1 + a + b)(K/N² + N·ε)`) by the same self-convergence: the
/// stepping at N = 64 … 4 096 (four per octave, and `N_min`) against the
/// stepping at `N_ref` = 2¹⁸, over 400 random scenes with `a` from 1 to 4 (a
/// fifth within 10⁻³ of 1), `b` from 10⁻³ to 10 (log-uniform), `V` over
/// ±1.2 of the critical velocities (the window solver's closed form, used
/// only to place the velocities) and 0. The constant with the reference's
/// error, `(K_obs + N_ref·ε·N_max²)/(1 − r)`, must leave a factor 2 to the
/// stated 10, and is printed.
#[test]
fn liftoff_stepping_constant_by_self_convergence() {
    use model_core::model::liftoff::{self, stepping};
    let mut rng = Rng::new(0x11f7_0ff5);
    let mut worst = (0.0f64, 0u32);
    for i in 0..400 {
        let a = if i % 5 == 0 {
            1.0 + rng.range(0.0, 1e-3)
        } else {
            rng.range(1.0, 4.0)
        };
        let b = 10f64.powf(rng.range(-3.0, 1.0));
        let phi = rng.range(-PI, PI);
        let d = Drive::new::<Libm>(a, b, phi);
        let (cp, cm) = liftoff::critical_velocities::<f64, Libm>(&d).unwrap();
        let x = rng.range(-1.2, 1.2);
        let v = if i % 10 == 1 {
            0.0
        } else if x > 0.0 {
            x * cp
        } else {
            x * cm
        };
        let reference = stepping::mu_over_mu0::<f64, Libm>(&d, v, N_REF)
            .unwrap()
            .mu_over_mu0;
        let nmin = stepping::min_steps_per_period(&d);
        let mut ns = vec![nmin];
        let mut x = 64.0f64;
        while x <= f64::from(N_MAX) {
            ns.push(x.round() as u32);
            x *= 2f64.powf(0.25);
        }
        for n in ns.into_iter().filter(|&n| n >= nmin) {
            let m = stepping::mu_over_mu0::<f64, Libm>(&d, v, n)
                .unwrap()
                .mu_over_mu0;
            let k = (m - reference).abs() * f64::from(n) * f64::from(n) / (1.0 + a + b);
            if k > worst.0 {
                worst = (k, n);
            }
        }
    }
    let r = (f64::from(N_MAX) / f64::from(N_REF)).powi(2);
    let nmax2 = f64::from(N_MAX) * f64::from(N_MAX);
    let k = (worst.0 + f64::from(N_REF) * f64::EPSILON * nmax2) / (1.0 - r);
    println!(
        "lift-off stepping K by self-convergence: worst {:.3} at N = {} (with the reference's error {k:.3}; stated {})",
        worst.0,
        worst.1,
        stepping::DISCRETISATION_K
    );
    assert!(k <= stepping::DISCRETISATION_K / 2.0, "K = {k}");
}

/// `fixed_step::Stepper` (the simulated device's plant: the same scheme with an
/// arbitrary phase step δ, its `(cos θ, sin θ)` advanced by rotation and
/// renormalised every 1 024 steps) against the scheme written out here with
/// direct `cos`/`sin` of `θ_k = θ₀ + kδ` at every step: stick trial
/// `s + Vδ + ΔX` with `X = b cos φ cos θ − b sin φ sin θ`, clamp to `±w`,
/// `w = 1 − a cos θ` (§2). `K = 3 000` steps at a δ that divides no period, so
/// the renormalisation runs twice and both clamps and stick arcs occur.
///
/// Tolerance. One rotation adds at most ≈ 4ε to the error of `(cos θ, sin θ)`
/// (two products and a sum, and `cos δ`, `sin δ` correct to an ulp); a
/// rotation does not grow an error and the renormalisation only shrinks its
/// radial part, so after `k` steps the pair is within `4kε` of the direct
/// values (whose own error, `ε·θ_k` from the phase sum, is below `ε·θ_K`
/// ≈ 20ε). So `|cos θ − cos θ_k|` and `|w − w_k|/a ≤ (4K + 20)ε = 2.7·10⁻¹²`.
/// The clamp is 1-Lipschitz in the trial and the band, so the stretch error
/// grows per step by at most the two `X` errors and the band's,
/// `(2b + a)(4K + 20)ε`: after K steps `≤ K(2b + a)(4K + 20)ε = 1.7·10⁻⁸`
/// for `a = 0.5, b = 0.8`.
#[test]
fn stepper_matches_the_scheme_with_direct_trig() {
    use model_core::fixed_step::Stepper;
    let (a, b, phi): (f64, f64, f64) = (0.5, 0.8, 0.7);
    let d = Drive::new::<Libm>(a, b, phi);
    let (bc, bs) = (d.bc, d.bs);
    // A fifth of the forward critical velocity: stick–slip in each period.
    let v = 0.2 * d.c_forward::<Libm>();
    let delta = 2.0 * PI / 1000.37;
    let (theta0, s0) = (0.3, 0.1);
    let k_steps = 3000u32;
    let eps = f64::EPSILON;
    let trig_tol = f64::from(4 * k_steps + 20) * eps;
    let stretch_tol = f64::from(k_steps) * (2.0 * b + a) * trig_tol;

    let mut stepper = Stepper::<f64>::new::<Libm>(d, v, theta0, s0, delta);
    let x_of = |t: f64| bc * t.cos() - bs * t.sin();
    let mut x_prev = x_of(theta0);
    let mut s = s0.clamp(-(1.0 - a * theta0.cos()), 1.0 - a * theta0.cos());
    let (mut clamps, mut sticks) = (0u32, 0u32);
    let (mut worst_c, mut worst_s) = (0.0f64, 0.0f64);
    for k in 1..=k_steps {
        let t = theta0 + f64::from(k) * delta;
        let x = x_of(t);
        let w = 1.0 - a * t.cos();
        let trial = s + v * delta + (x - x_prev);
        s = trial.clamp(-w, w);
        if s == trial {
            sticks += 1;
        } else {
            clamps += 1;
        }
        x_prev = x;
        let (c_got, s_got, w_got) = stepper.step();
        worst_c = worst_c.max((c_got - t.cos()).abs());
        worst_s = worst_s.max((s_got - s).abs());
        assert!(
            (c_got - t.cos()).abs() <= trig_tol,
            "step {k}: cos θ {c_got} vs {} (tol {trig_tol:e})",
            t.cos()
        );
        assert!(
            (w_got - w).abs() <= a * trig_tol,
            "step {k}: w {w_got} vs {w} (tol {:e})",
            a * trig_tol
        );
        assert!(
            (s_got - s).abs() <= stretch_tol,
            "step {k}: stretch {s_got} vs {s} (tol {stretch_tol:e})"
        );
    }
    println!("Stepper vs direct trig: worst |Δcos θ| {worst_c:.1e} (tol {trig_tol:.1e}), worst |Δs| {worst_s:.1e} (tol {stretch_tol:.1e}); {clamps} clamped, {sticks} stuck");
    // The run exercised both the stick trial and the clamp.
    assert!(
        clamps > 100 && sticks > 100,
        "clamps {clamps}, sticks {sticks}"
    );
}
