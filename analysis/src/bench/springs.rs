//! A brute force over the springs of the MDR foundation (eqs. M1–M8 of
//! `model_core::mdr`), sharing no code with the quadrature or with the
//! per-spring solvers: the reference of the curved-profile stability plane.
//!
//! Each spring (band `w = d − a cos θ`, drive `u_x = Vθ + b cos(θ + φ)`, units
//! of `W₀`) runs the paper's stick-trial-and-clamp scheme with `n` steps per
//! period: the intermittent ones (`|d| < a`) over one contact window from the
//! landing (`s = 0`, exact phase `acos(d/a)`) to the lift-off, the last step
//! shortened to end there (order 2, as `liftoff::stepping`); the permanent
//! ones (`d > a`) from the forward (or, for `V < 0`, backward) band edge at
//! the phase where a clamp is certain, period after period until the period
//! mean settles. `⟨s⟩` is the trapezoid mean; `⟨w⁺⟩` the closed form (eq. M4).
//! The springs are placed by the midpoint rule in `t` on each of
//! `[0, ξ_a]`, `[ξ_a, ξ_max]` with `ξ = l + (r − l)(1 − cos t)/2`
//! (`ξ_a = (1 − a)^{1/n}`, `ξ_max = (1 + a)^{1/n}`), and
//! `μ/μ₀ = Σ⟨s⟩ J / Σ⟨w⁺⟩ J` (eq. M8).

use std::f64::consts::{FRAC_PI_2, PI, TAU};

use model_core::mdr::normal::mean_band;
use model_core::Libm;

/// `⟨s⟩` of one spring over a period by the scheme with `n` steps per
/// period; `(a, bc, bs) = (a, b cos φ, b sin φ)`.
fn spring_stretch(d: f64, a: f64, bc: f64, bs: f64, v: f64, n: u32) -> f64 {
    let h = TAU / f64::from(n);
    let swing = |t: f64| bc * t.cos() - bs * t.sin();
    let w = |t: f64| d - a * t.cos();
    let clamp = |s: f64, w: f64| s.clamp(-w, w);
    if d <= -a {
        return 0.0;
    }
    if d > a {
        // Start on the band edge where a clamp in the direction of motion is
        // certain: the minimum (V ≥ 0) or maximum (V < 0) of the stick rate
        // against the edge's rate (as `integration_tests::fixed_warm`).
        let (t0, sign) = if v >= 0.0 {
            (-FRAC_PI_2 - bs.atan2(bc + a), 1.0)
        } else {
            (FRAC_PI_2 - bs.atan2(bc - a), -1.0)
        };
        let mut s = sign * w(t0) * (1.0 - 4.0 * f64::EPSILON);
        let mut x_prev = swing(t0);
        let mut last = f64::NAN;
        let scale = 1.0 + a + bc.hypot(bs);
        for p in 0..400u32 {
            let mut sum = 0.0;
            for j in 1..=n {
                let t = t0 + h * f64::from(p * n + j);
                let x = swing(t);
                s = clamp(s + v * h + (x - x_prev), w(t));
                x_prev = x;
                sum += s;
            }
            let mean = sum / f64::from(n);
            if (mean - last).abs() <= 1e-13 * scale {
                return mean;
            }
            last = mean;
        }
        return last;
    }
    // One window from the landing to the lift-off.
    let tl = (d / a).acos();
    let tr = TAU - tl;
    let whole = ((tr - tl) / h).floor() as u32;
    let (mut s, mut x_prev, mut t_prev) = (0.0, swing(tl), tl);
    let mut integral = 0.0;
    for j in 1..=whole {
        let t = tl + h * f64::from(j);
        let x = swing(t);
        let s_new = clamp(s + v * (t - t_prev) + (x - x_prev), w(t).max(0.0));
        integral += 0.5 * (t - t_prev) * (s + s_new);
        (s, x_prev, t_prev) = (s_new, x, t);
    }
    let x = swing(tr);
    let s_end = clamp(s + v * (tr - t_prev) + (x - x_prev), 0.0);
    integral += 0.5 * (tr - t_prev) * (s + s_end);
    integral / TAU
}

/// Brute-force `μ/μ₀` of the profile `d = 1 − ξⁿ` (exponent `n_exp`) with
/// `springs` springs per segment and `n` steps per period.
pub fn mu(n_exp: f64, a: f64, b: f64, phi: f64, v: f64, springs: u32, n: u32) -> f64 {
    let (bc, bs) = (b * phi.cos(), b * phi.sin());
    let xi_a = if a < 1.0 {
        (1.0 - a).powf(1.0 / n_exp)
    } else {
        0.0
    };
    let xi_max = (1.0 + a).powf(1.0 / n_exp);
    let (mut num, mut den) = (0.0, 0.0);
    for (l, r) in [(0.0, xi_a), (xi_a, xi_max)] {
        if r <= l {
            continue;
        }
        let ht = PI / f64::from(springs);
        for i in 0..springs {
            let t = (f64::from(i) + 0.5) * ht;
            let xi = l + 0.5 * (r - l) * (1.0 - t.cos());
            let jac = 0.5 * (r - l) * t.sin();
            let d = 1.0 - xi.powf(n_exp);
            num += spring_stretch(d, a, bc, bs, v, n) * jac;
            den += mean_band::<f64, Libm>(d, a) * jac;
        }
    }
    num / den
}

/// The brute force with its error estimate, `(B(4M, N), allowance)` (the
/// tests' reference, `integration_tests::springs`, is refined further: events
/// sub-stepped, Richardson in N, adaptive panels): over the springs the midpoint rule converges
/// like `h²` with an erratic constant (a kink of `⟨s⟩(ξ)` inside a cell), so
/// no Richardson step is taken; `B(4M, N)`'s spring error is taken as the
/// larger of the last two changes `|B(M) − B(2M)|`, `|B(2M) − B(4M)|` (true
/// whenever the error at least halves per doubling over two doublings), and
/// its time-step error as `2|B(M, N) − B(M, 2N)|` (order 2 in N: the change
/// is 3/4 of the error at N). An estimate, not a proof.
pub fn mu_with_error(n_exp: f64, a: f64, b: f64, phi: f64, v: f64, m: u32, n: u32) -> (f64, f64) {
    let b_m = mu(n_exp, a, b, phi, v, m, n);
    let b_2m = mu(n_exp, a, b, phi, v, 2 * m, n);
    let b_4m = mu(n_exp, a, b, phi, v, 4 * m, n);
    let b_m_2n = mu(n_exp, a, b, phi, v, m, 2 * n);
    let springs = (b_m - b_2m).abs().max((b_2m - b_4m).abs());
    (b_4m, springs + 2.0 * (b_m - b_m_2n).abs())
}

#[cfg(test)]
mod tests {
    use super::*;
    use model_core::{exact, Drive};

    /// A flat band (`a = 0`) makes every spring the flat punch scaled by its
    /// `d`; with `b` small against the band the springs all stick or all
    /// slide alike. Independent check of the permanent branch: one spring
    /// at `d = 1` against the exact flat solver, within the scheme's stated
    /// `10(1 + b)/N²` (fixed_step::DISCRETISATION_K).
    #[test]
    fn permanent_spring_matches_the_exact_flat_solver() {
        for &(a, b, phi, x) in &[(0.5, 0.25, 1.0, 0.3), (0.3, 1.0, -2.0, -0.4)] {
            let d = Drive::new::<Libm>(a, b, phi);
            let v = x * if x > 0.0 {
                d.c_forward::<Libm>()
            } else {
                d.c_backward::<Libm>()
            };
            let e = exact::mu_over_mu0::<f64, Libm>(&d, v).unwrap();
            let n = 2048;
            let s = spring_stretch(1.0, a, d.bc, d.bs, v, n);
            let tol = 10.0 * (1.0 + b) / f64::from(n * n);
            assert!((s - e).abs() <= tol, "{s} vs {e} (tol {tol:e})");
        }
    }

    /// The intermittent branch at `d = 1`, `a ≥ 1` is the lift-off punch:
    /// against the lift-off solver within `10(1 + a + b)/N²`
    /// (liftoff::stepping::DISCRETISATION_K), both signs of V.
    #[test]
    fn intermittent_spring_matches_the_lift_off_solver() {
        use model_core::model::liftoff;
        for &(a, b, phi, v) in &[(1.5, 0.7, 2.0, 0.1), (2.5, 0.3, 1.0, -0.05)] {
            let d = Drive::new::<Libm>(a, b, phi);
            let m = liftoff::mu_over_mu0::<f64, Libm>(&d, v).unwrap();
            let n = 2048;
            let s = spring_stretch(1.0, a, d.bc, d.bs, v, n);
            let mean_w = mean_band::<f64, Libm>(1.0, a);
            let tol = 10.0 * (1.0 + a + b) / f64::from(n * n) * mean_w;
            assert!(
                (s - m * mean_w).abs() <= tol,
                "{s} vs {} (tol {tol:e})",
                m * mean_w
            );
        }
    }
}
