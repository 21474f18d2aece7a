//! Curved profiles through the MDR (`model::mdr`) against independent
//! computations: a brute force over many springs written here (each spring
//! by a fine fixed-step run of the paper's stick-trial-and-clamp scheme, the
//! intermittent ones with exact landing and lift-off, the permanent ones run
//! to their periodic state; midpoint rule over the springs), the flat punch
//! as `n → ∞`, dimensionless invariance, mirror symmetry, f32 against f64,
//! and every refusal.

use std::f64::consts::{PI, TAU};

use model_core::mdr::{self, MdrError, Profile};
use model_core::{Drive, Libm};

/// One spring by brute force: `(⟨s⟩, ⟨w⁺⟩)` over a period for the band
/// `w = d − a cos θ` and the drive `u_x = Vθ + b cos(θ + φ)`, `n` steps per
/// period, trapezoid means.
fn brute_spring(d: f64, a: f64, b: f64, phi: f64, v: f64, n: u32) -> (f64, f64) {
    let h = TAU / f64::from(n);
    let ux = |t: f64| v * t + b * (t + phi).cos();
    if d <= -a {
        return (0.0, 0.0);
    }
    if d > a {
        // Permanent contact: periods from s = 0 until the period mean settles.
        let w = |t: f64| d - a * t.cos();
        let mut s: f64 = 0.0;
        let mut last = f64::NAN;
        for _ in 0..200 {
            let mut int_s = 0.0;
            for i in 0..n {
                let (t0, t1) = (f64::from(i) * h, f64::from(i + 1) * h);
                let s1 = (s + ux(t1) - ux(t0)).clamp(-w(t1), w(t1));
                int_s += 0.5 * h * (s + s1);
                s = s1;
            }
            let mean = int_s / TAU;
            if (mean - last).abs() < 1e-14 {
                return (mean, d);
            }
            last = mean;
        }
        return (last, d);
    }
    // Intermittent: one window from landing (s = 0) to lift-off.
    let tc = (d / a).acos();
    let (t0, t1) = (tc, TAU - tc);
    let w = |t: f64| (d - a * t.cos()).max(0.0);
    let mut t = t0;
    let mut s: f64 = 0.0;
    let (mut int_s, mut int_w) = (0.0, 0.0);
    let mut w_prev = 0.0;
    while t < t1 {
        let t_next = (t + h).min(t1);
        let w_next = if t_next == t1 { 0.0 } else { w(t_next) };
        let s_next = (s + ux(t_next) - ux(t)).clamp(-w_next, w_next);
        int_s += 0.5 * (t_next - t) * (s + s_next);
        int_w += 0.5 * (t_next - t) * (w_prev + w_next);
        s = s_next;
        w_prev = w_next;
        t = t_next;
    }
    (int_s / TAU, int_w / TAU)
}

/// Brute-force μ/μ₀ of the profile `d = 1 − ξⁿ`: `springs` springs per
/// piece `[0, ξ_a]`, `[ξ_a, ξ_max]` (ξ_a = (1 − a)^{1/n}, the lift-off onset,
/// a geometric fact), placed by the midpoint rule in `t` with
/// `ξ = l + (r − l)(1 − cos t)/2`, `n_steps` per period for each spring.
fn brute_mu(n: f64, a: f64, b: f64, phi: f64, v: f64, springs: u32, n_steps: u32) -> f64 {
    let xi_a = if a < 1.0 {
        (1.0 - a).powf(1.0 / n)
    } else {
        0.0
    };
    let xi_max = (1.0 + a).powf(1.0 / n);
    let (mut num, mut den) = (0.0, 0.0);
    for (l, r) in [(0.0, xi_a), (xi_a, xi_max)] {
        if r <= l {
            continue;
        }
        let ht = PI / f64::from(springs);
        for i in 0..springs {
            let t = (f64::from(i) + 0.5) * ht;
            let xi = l + 0.5 * (r - l) * (1.0 - t.cos());
            let jac = 0.5 * (r - l) * t.sin() * ht;
            let (s, w) = brute_spring(1.0 - xi.powf(n), a, b, phi, v, n_steps);
            num += s * jac;
            den += w * jac;
        }
    }
    num / den
}

#[test]
fn scratch_sphere() {
    for &(a, b, phi, v) in &[
        (0.5, 1.0, 0.3, 0.2),
        (1.5, 0.7, 2.0, 0.1),
        (0.2, 2.0, 0.0, -0.5),
    ] {
        let d = Drive::new::<Libm>(a, b, phi);
        let t = std::time::Instant::now();
        let r = mdr::mu_over_mu0::<f64, Libm>(&d, &Profile::Sphere, v, 1e-8);
        let el = t.elapsed();
        let bf1 = brute_mu(2.0, a, b, phi, v, 100, 4000);
        let bf2 = brute_mu(2.0, a, b, phi, v, 200, 8000);
        println!("a={a} b={b} phi={phi} v={v}: {r:?} in {el:?}; brute {bf1} {bf2}");
    }
}

#[test]
fn scratch_shape() {
    let (a, b, phi, v) = (0.5, 1.0, 0.3, 0.2);
    let n = 2.0;
    let xi_max = (1.0f64 + a).sqrt();
    let m = 2000;
    let mut prev = [0.0; 3];
    for i in 0..=m {
        let xi = xi_max * f64::from(i) / f64::from(m);
        let (s, w) = brute_spring(1.0 - xi.powf(n), a, b, phi, v, 20000);
        let f = w - s;
        let d2 = f - 2.0 * prev[1] + prev[0];
        if i > 2 && (d2.abs() > 3e-6) {
            println!("xi={xi:.4} d={:.4} f={f:.6} d2={d2:.2e}", 1.0 - xi * xi);
        }
        prev = [prev[1], f, 0.0];
    }
}

#[test]
fn scratch_timing() {
    use model_core::exact;
    let d = Drive::new::<Libm>(0.5 / 0.8, 1.0 / 0.8, 0.3);
    let t = std::time::Instant::now();
    let mut acc = 0.0;
    for i in 0..10000 {
        acc += exact::mu_over_mu0::<f64, Libm>(&d, 0.2 / 0.8 + 1e-6 * f64::from(i % 7)).unwrap();
    }
    println!("exact solve: {:?} per call ({acc})", t.elapsed() / 10000);
    for &(a, b, phi, v) in &[(0.5, 1.0, 0.3, 0.2), (1.5, 0.7, 2.0, 0.1)] {
        let d = Drive::new::<Libm>(a, b, phi);
        for tol in [1e-5, 1e-6, 1e-7, 1e-8] {
            let t = std::time::Instant::now();
            let r = mdr::mu_over_mu0::<f64, Libm>(&d, &Profile::Sphere, v, tol).unwrap();
            println!(
                "a={a} tol={tol:e}: {:.12} bound {:.2e} evals {} {:?} kinks {}",
                r.mu_over_mu0,
                r.bound,
                r.evaluations,
                t.elapsed(),
                mdr::DEBUG_KINKS.swap(0, std::sync::atomic::Ordering::Relaxed)
            );
        }
    }
}
