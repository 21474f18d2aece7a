//! Curved profiles at rest and at their critical velocities
//! (docs/guide/lift-off-and-profiles.md, "Curved profiles at rest", eqs.
//! S1–S4) against the brute force over springs (`integration_tests::springs`,
//! written from the model's statement, sharing no code with model-core's
//! quadrature), on 15 scenes: sphere, cone and the power law n = 3.5; the
//! central spring permanent (`a < 1`) with and without a static interval,
//! and lifting off (`a ≥ 1`); both signs of sin φ.
//!
//! * **Critical velocities** (eq. S1: the flat punch's with the same drive).
//!   Just above (`1.001 v_c`) every spring of the brute force slides: μ/μ0 =
//!   ±1 up to the rounding of its trapezoid sums (each spring's `s = ±w` on
//!   every step: ~10⁻¹³); just below (`0.99 v_c`) some spring sticks: μ/μ0
//!   is inside (−1, 1) by more than ten times the brute force's error.
//! * **The limits at rest** μ(0±) (`mdr::limits_at_zero`) against the brute
//!   force's law extrapolated to `V → 0±` from `V`, `2V`, `4V`
//!   ([`limit_at_zero`]: its remainder is `O(V^{3/2})`, not `O(V²)`), plus
//!   the limit's bound; with `a ≥ 1` μ(0) is unique and is compared with the
//!   brute force at `V = 0`.
//! * **The static interval's width** μ(0⁺) − μ(0⁻) against the closed form
//!   of eq. S3, `[(2 − σ)ξ_m − 2ξ_m^{n+1}/(n + 1)]/D`, `σ = c + c'`,
//!   `ξ_m = (1 − max(a, σ/2))^{1/n}`, with `D` (eq. M5) by the trapezoid
//!   rule over θ (spectrally exact for the smooth periodic integrand of
//!   `a < 1`; 4 096 nodes: rounding only); and whether it exists (eq. S2).

use integration_tests::springs;
use model_core::mdr::{self, Profile};
use model_core::scene::Drive;
use model_core::Libm;
use std::f64::consts::TAU;

/// `(n, a, b, φ)`: per profile, an interval (a = 0.5, b = 0.3), none
/// (a = 0.7, b = 1.0: c + c' > 2), and lift-off of the centre (a = 1.5).
const SCENES: [(f64, f64, f64, f64); 15] = [
    (2.0, 0.5, 0.3, 0.7),
    (2.0, 0.5, 0.3, -0.7),
    (2.0, 0.7, 1.0, 2.0),
    (2.0, 1.5, 0.5, 0.7),
    (2.0, 1.5, 0.5, -0.7),
    (1.0, 0.5, 0.3, 0.7),
    (1.0, 0.5, 0.3, -0.7),
    (1.0, 0.7, 1.0, -2.0),
    (1.0, 1.5, 0.5, 0.7),
    (1.0, 1.5, 0.5, -0.7),
    (3.5, 0.5, 0.3, 0.7),
    (3.5, 0.5, 0.3, -0.7),
    (3.5, 0.7, 1.0, 2.0),
    (3.5, 1.5, 0.5, 0.7),
    (3.5, 1.5, 0.5, -0.7),
];

/// Steps per period and quadrature tolerance of the brute force.
const STEPS: u32 = 4096;
const BF_TOL: f64 = 1e-8;

fn profile(n: f64) -> Profile<f64> {
    match n {
        2.0 => Profile::Sphere,
        1.0 => Profile::Cone,
        _ => Profile::Power(n),
    }
}

fn brute(n: f64, a: f64, b: f64, phi: f64, v: f64) -> springs::BruteForce {
    springs::mu(n, a, b, phi, v, BF_TOL, STEPS)
}

#[test]
fn critical_velocities_are_where_every_spring_slides() {
    for &(n, a, b, phi) in &SCENES {
        let d = Drive::new::<Libm>(a, b, phi);
        let (cf, cb) = mdr::critical_velocities::<f64, Libm>(&d, &profile(n)).unwrap();
        for (vc, sign) in [(cf, 1.0), (cb, -1.0)] {
            let above = brute(n, a, b, phi, sign * 1.001 * vc);
            assert!(
                (above.mu - sign).abs() < 1e-12,
                "n={n} a={a} b={b} φ={phi}: μ(1.001 v_c) = {} (every spring should slide)",
                above.mu
            );
            let below = brute(n, a, b, phi, sign * 0.99 * vc);
            let inside = 1.0 - sign * below.mu;
            println!(
                "n={n} a={a} b={b} φ={phi} {}: 1 − |μ(0.99 v_c)| = {inside:.3e} (brute force ±{:.1e})",
                if sign > 0.0 { "forward" } else { "backward" },
                below.err
            );
            assert!(
                inside > 10.0 * below.err,
                "n={n} a={a} b={b} φ={phi}: μ(0.99 v_c) = {} ± {:e} is not below the sliding value",
                below.mu,
                below.err
            );
        }
    }
}

/// The law's one-sided limit at 0 from its values (with errors) at `V`,
/// `2V`, `4V`: `(E₁, allowance)`, `E₁ = 2μ(V) − μ(2V)` (removes the linear
/// term). Its remainder is `c·V^{3/2}`, not the `V²` of
/// `integration_tests::limit_by_extrapolation`: on the sphere, a = 0.5,
/// b = 0.3, φ = 0.7, `(μ(V) − μ(0⁺))/V` = 3.6748, 3.6639, 3.6485, 3.6264 at
/// V = 1, 2, 4, 8·10⁻⁴ — steps growing by √2 per doubling (brute force and
/// quadrature agree there to 1e-7). For that remainder `E₁ − μ(0) =
/// (E₂ − E₁)/(2^{3/2} − 1)`, `E₂ = 2μ(2V) − μ(4V)`; the allowance is twice
/// that (room for the next term) plus the values' errors with their weights.
fn limit_at_zero(at: [(f64, f64); 3]) -> (f64, f64) {
    let [(m1, e1), (m2, e2), (m4, e4)] = at;
    let (x1, x2) = (2.0 * m1 - m2, 2.0 * m2 - m4);
    let q = 2f64.powf(1.5) - 1.0;
    let allowance = 2.0 * (x1 - x2).abs() / q + (2.0 * e1 + e2) + (2.0 * e1 + 3.0 * e2 + e4) / q;
    (x1, allowance)
}

/// Eq. S3's width of the static interval over μ0 times the mean normal force.
fn width_s3(n: f64, d: &Drive<f64>) -> f64 {
    let a = d.a;
    let sigma = d.c_forward::<Libm>() + d.c_backward::<Libm>();
    let m = a.max(sigma / 2.0);
    if m >= 1.0 {
        return 0.0;
    }
    let xm = (1.0 - m).powf(1.0 / n);
    let num = (2.0 - sigma) * xm - 2.0 * xm.powf(n + 1.0) / (n + 1.0);
    // D = n/(n+1)·⟨(1 − a cos θ)₊^{1+1/n}⟩ (eq. M5).
    let k = 4096;
    let mean = (0..k)
        .map(|j| {
            let t = TAU * j as f64 / k as f64;
            (1.0 - a * t.cos()).max(0.0).powf(1.0 + 1.0 / n)
        })
        .sum::<f64>()
        / k as f64;
    num / (n / (n + 1.0) * mean)
}

#[test]
fn the_static_interval_against_the_brute_force_and_eq_s3() {
    let mut with_interval = 0;
    for &(n, a, b, phi) in &SCENES {
        let d = Drive::new::<Libm>(a, b, phi);
        let p = profile(n);
        let tol = (2.0 * mdr::solver_bound_at_rest::<f64, Libm>(&d, n)).max(1e-9);
        let (plus, minus) = mdr::limits_at_zero::<f64, Libm>(&d, &p, tol).unwrap();
        let exists = mdr::static_interval_exists::<f64, Libm>(&d);
        if a >= 1.0 {
            assert_eq!(plus.mu_over_mu0, minus.mu_over_mu0);
            assert!(!exists);
            let bf = brute(n, a, b, phi, 0.0);
            let gap = (bf.mu - plus.mu_over_mu0).abs();
            println!(
                "n={n} a={a} b={b} φ={phi}: μ(0) {} brute {} gap {gap:.1e} (allowed {:.1e})",
                plus.mu_over_mu0,
                bf.mu,
                bf.err + plus.bound
            );
            assert!(gap <= bf.err + plus.bound, "n={n} a={a}: μ(0) gap {gap:e}");
            continue;
        }
        // The width: eq. S3 against the quadrature's two limits.
        let w = width_s3(n, &d);
        let got = plus.mu_over_mu0 - minus.mu_over_mu0;
        let allowed = plus.bound + minus.bound + 1e-12;
        println!("n={n} a={a} b={b} φ={phi}: width {got:.12} eq. S3 {w:.12} (allowed {allowed:.1e}), exists {exists}");
        assert!(
            (got - w).abs() <= allowed,
            "n={n} a={a} b={b} φ={phi}: width {got} vs eq. S3 {w}"
        );
        assert_eq!(exists, w > 0.0, "n={n} a={a} b={b} φ={phi}: eq. S2 vs S3");
        if exists {
            with_interval += 1;
            assert!(w > 100.0 * allowed);
        }
        // Each limit against the brute force's law extrapolated to 0±.
        for (limit, sign) in [(plus, 1.0), (minus, -1.0)] {
            let v = sign * 2e-5;
            let at = |k: f64| {
                let bf = brute(n, a, b, phi, k * v);
                (bf.mu, bf.err)
            };
            let (e1, allowance) = limit_at_zero([at(1.0), at(2.0), at(4.0)]);
            let gap = (e1 - limit.mu_over_mu0).abs();
            println!(
                "   μ(0{}) {} extrapolated brute {e1} gap {gap:.1e} (allowed {:.1e})",
                if sign > 0.0 { "+" } else { "-" },
                limit.mu_over_mu0,
                allowance + limit.bound
            );
            assert!(
                gap <= allowance + limit.bound,
                "n={n} a={a} b={b} φ={phi} sign {sign}: gap {gap:e}"
            );
        }
    }
    assert_eq!(with_interval, 6);
}

/// Eq. S2's boundary: at `c + c' = 2` exactly the central spring's interval
/// is a point (S3's width is 0) and there is no static interval; just below
/// it there is one. (`a = 0.6, b = 0.8, φ = 90°`: `c = c' = |0.6 ± 0.8i|`
/// = 1 in f64 too, asserted.) And `c + c' ≥ 2a`, so `a ≥ 1` never has one.
#[test]
fn the_static_interval_begins_below_c_plus_c_prime_two() {
    let d = Drive::new::<Libm>(0.6, 0.8, std::f64::consts::FRAC_PI_2);
    assert_eq!(d.c_forward::<Libm>() + d.c_backward::<Libm>(), 2.0);
    assert!(!mdr::static_interval_exists::<f64, Libm>(&d));
    assert_eq!(width_s3(2.0, &d), 0.0);
    let below = Drive::new::<Libm>(0.6, 0.8 - 1e-9, std::f64::consts::FRAC_PI_2);
    assert!(below.c_forward::<Libm>() + below.c_backward::<Libm>() < 2.0);
    assert!(mdr::static_interval_exists::<f64, Libm>(&below));
    assert!(width_s3(2.0, &below) > 0.0);
    for (a, b, phi) in [(1.0, 0.0, 0.0), (1.0, 1e-3, 1.0), (1.2, 0.1, 2.0)] {
        assert!(!mdr::static_interval_exists::<f64, Libm>(
            &Drive::new::<Libm>(a, b, phi)
        ));
    }
}
