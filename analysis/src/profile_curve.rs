//! μ(v) of a curved profile along a curve (`fricctl curve --profile …`,
//! issue 39): between neighbouring velocities μ(v) is smooth, so a run of
//! curve points is answered by a Chebyshev interpolant through MDR answers
//! at 17 velocities of the run, checked against two more MDR answers at the
//! run's own points, instead of one MDR quadrature per point.
//!
//! **The interpolant.** On a run `[v_lo, v_hi]` of velocities (same sign,
//! strictly monotone, `0 < |V| < V_c` in that direction) the MDR quadrature
//! gives `f_k ± b_k` at the Chebyshev extrema `v_k = m + h·cos(kπ/16)`,
//! `k = 0…16` (`m`, `h` the run's centre and half-width), each with
//! `b_k ≤ tol/8`; the interpolant `p` through them is evaluated in
//! barycentric form (weights `(−1)^k`, halved at both ends: Berrut &
//! Trefethen 2004, eq. 5.2). Its error at any `v` of the run is at most
//!
//! ```text
//! |p(v) − μ(v)| ≤ Λ₁₆·max b_k + 2·Σ_{j>16} |a_j|                          (C1)
//! ```
//!
//! — the node errors carried by the interpolation (Lebesgue constant of the
//! 17 Chebyshev extrema, `Λ₁₆ ≤ (2/π) ln 16 + 1 = 2.77`) and the
//! truncation of μ's Chebyshev series `Σ a_j T_j` on the run (Trefethen,
//! *Approximation Theory and Approximation Practice*, Thm 4.2). The tail is
//! not known; it is **estimated** from the interpolant's own coefficients
//! (their size at degrees 12–16 and their decay since degrees 6–10:
//! `truncation`; a run whose coefficients decay more slowly than by 0.8
//! per degree is not taken), and that estimate is **checked**: μ is computed by the quadrature
//! at the run's points one third and two thirds along it, and the run is
//! taken only if both lie within (C1) plus their own bound of `p`. A run whose
//! bound (C1) exceeds `tol`, or that fails a check or a node, is halved; a
//! run of fewer than [`MIN_RUN`] points is left to the quadrature point by
//! point. So each interpolated point carries the bound (C1), like the
//! quadrature's own an estimate (the quadrature's error estimate is one
//! too: [`model_core::mdr`]); `tests/profile_curve.rs` compares every
//! interpolated point of 16 curves with the quadrature at that point.
//!
//! Cost: 19 quadratures per run taken, at `tol/8` (≈ 1.2× a quadrature at
//! `tol`), for runs of hundreds to thousands of points where μ(v) is smooth;
//! near `v = 0` and `±v_c` (where μ(v) is not) the runs halve down to
//! [`MIN_RUN`] points. docs/guide/speed.md has the time per point.

use model_core::mdr::{self, Profile};
use model_core::{Libm, Scene};
use rayon::prelude::*;

/// Degree of the interpolant (17 nodes).
const DEGREE: usize = 16;

/// The Lebesgue constant's bound for the 17 Chebyshev extrema,
/// `(2/π) ln 16 + 1 = 2.765…`, rounded up (eq. C1).
pub const LEBESGUE: f64 = 2.77;

/// The share of the tolerance the nodes' own bounds may take: each node is
/// computed to `tol/8`, so that `Λ₁₆·tol/8 ≤ 0.35·tol` leaves the rest
/// to the truncation (eq. C1).
const NODE_SHARE: f64 = 0.125;

/// The fewest curve points a run must hold to be interpolated: below it,
/// the 19 quadratures of a run cost about as much as its points'.
pub const MIN_RUN: usize = 48;

/// One point of a curve answered by [`profile_curve`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CurvePoint {
    /// μ/μ0.
    pub mu_over_mu0: f64,
    /// Its bound, units of μ0: eq. C1 for an interpolated point, else the
    /// quadrature's own.
    pub bound: f64,
    /// From the interpolant (else the quadrature at this very point, one of
    /// a run's two checks).
    pub interpolated: bool,
}

/// μ/μ0 of the curved profile `p` at the velocities `vs` (m/s, or units of
/// ωW0 for a dimensionless scene) within `tol` (units of μ0), by the
/// interpolant of the module docs: `Some` for each point it answers, `None`
/// for the points left to the quadrature one by one (at rest, beyond the
/// critical velocities, in runs too short or where μ(v) is not smooth
/// enough, or where a node's quadrature failed). The result has `vs`'s
/// length and order. A flat profile, or a `tol` the nodes cannot reach,
/// leaves every point to the caller.
pub fn profile_curve(
    scene: &Scene<f64>,
    p: &Profile<f64>,
    vs: &[f64],
    tol: f64,
) -> Vec<Option<CurvePoint>> {
    let mut out = vec![None; vs.len()];
    let Some(n) = p.exponent() else {
        return out;
    };
    if !(tol.is_finite() && tol > 0.0) {
        return out;
    }
    let d = scene.drive();
    let Ok((cf, cb)) = mdr::critical_velocities::<f64, Libm>(&d, p) else {
        return out;
    };
    let node_tol = tol * NODE_SHARE;
    if mdr::solver_bound::<f64, Libm>(&d, n) >= node_tol {
        return out;
    }
    // Dimensionless velocities; NaN where the scene refuses one.
    let big_v: Vec<f64> = vs
        .iter()
        .map(|&v| scene.dimensionless_velocity(v).unwrap_or(f64::NAN))
        .collect();
    let inside = |x: f64| x.is_finite() && ((x > 0.0 && x < cf) || (x < 0.0 && -x < cb));
    let ctx = Context {
        d,
        p: *p,
        node_tol,
        tol,
    };
    // Runs: consecutive points inside, of one sign, strictly monotone.
    let mut runs: Vec<(usize, usize)> = Vec::new();
    let mut i = 0;
    while i < vs.len() {
        if !inside(big_v[i]) {
            i += 1;
            continue;
        }
        let start = i;
        let mut dir = 0.0f64;
        i += 1;
        while i < vs.len() && inside(big_v[i]) && big_v[i].signum() == big_v[start].signum() {
            let step = big_v[i] - big_v[i - 1];
            if step == 0.0 || (dir != 0.0 && step.signum() != dir) {
                break;
            }
            dir = step.signum();
            i += 1;
        }
        runs.push((start, i));
    }
    let mut rest: &mut [Option<CurvePoint>] = &mut out;
    let mut offset = 0;
    let mut jobs = Vec::with_capacity(runs.len());
    for (s, e) in runs {
        let tail = std::mem::take(&mut rest);
        let (_, tail) = tail.split_at_mut(s - offset);
        let (mine, tail) = tail.split_at_mut(e - s);
        rest = tail;
        offset = e;
        jobs.push((&big_v[s..e], mine));
    }
    jobs.into_par_iter().for_each(|(v, slot)| ctx.run(v, slot));
    out
}

/// What every run shares.
struct Context {
    d: model_core::Drive<f64>,
    p: Profile<f64>,
    node_tol: f64,
    tol: f64,
}

impl Context {
    /// The quadrature at dimensionless `v`: `(μ/μ0, bound)`.
    fn mdr(&self, v: f64) -> Option<(f64, f64)> {
        mdr::mu_over_mu0::<f64, Libm>(&self.d, &self.p, v, self.node_tol)
            .ok()
            .map(|r| (r.mu_over_mu0, r.bound))
    }

    /// Answers the run `v` (dimensionless, monotone, one sign) into `out`,
    /// halving it where the interpolant is not taken.
    fn run(&self, v: &[f64], out: &mut [Option<CurvePoint>]) {
        if v.len() < MIN_RUN {
            return;
        }
        if let Some(answers) = self.interpolate(v) {
            for (o, a) in out.iter_mut().zip(answers) {
                *o = Some(a);
            }
            return;
        }
        let mid = v.len() / 2;
        let (vl, vr) = v.split_at(mid);
        let (ol, or) = out.split_at_mut(mid);
        rayon::join(|| self.run(vl, ol), || self.run(vr, or));
    }

    /// The run's answers by the interpolant, if it is taken (module docs).
    fn interpolate(&self, v: &[f64]) -> Option<Vec<CurvePoint>> {
        let (lo, hi) = (v[0], v[v.len() - 1]);
        let (m, h) = ((lo + hi) * 0.5, (hi - lo) * 0.5);
        let nodes: Vec<f64> = (0..=DEGREE)
            .map(|k| (k as f64 * core::f64::consts::PI / DEGREE as f64).cos())
            .collect();
        let checks = [v.len() / 3, 2 * v.len() / 3];
        let at: Vec<f64> = nodes
            .iter()
            .map(|x| m + h * x)
            .chain(checks.iter().map(|&i| v[i]))
            .collect();
        let answers: Vec<Option<(f64, f64)>> = at.par_iter().map(|&x| self.mdr(x)).collect();
        let mut f = [0.0; DEGREE + 1];
        let mut node_bound = 0.0f64;
        for (k, a) in answers[..=DEGREE].iter().enumerate() {
            let (mu, b) = (*a)?;
            f[k] = mu;
            node_bound = node_bound.max(b);
        }
        let cc = coefficients(&f);
        let bound = LEBESGUE * node_bound + truncation(&cc, node_bound)?;
        // (NaN refused too.)
        if bound.is_nan() || bound > self.tol {
            return None;
        }
        let x_of = |vv: f64| if h != 0.0 { (vv - m) / h } else { 0.0 };
        let mut checked = [(0.0, 0.0); 2];
        for (j, &i) in checks.iter().enumerate() {
            let (mu, b) = answers[DEGREE + 1 + j]?;
            let gap = (barycentric(&nodes, &f, x_of(v[i])) - mu).abs();
            if gap.is_nan() || gap > bound + b {
                return None;
            }
            checked[j] = (mu, b);
        }
        Some(
            v.iter()
                .enumerate()
                .map(|(i, &vv)| match checks.iter().position(|&c| c == i) {
                    Some(j) => CurvePoint {
                        mu_over_mu0: checked[j].0,
                        bound: checked[j].1,
                        interpolated: false,
                    },
                    None => CurvePoint {
                        mu_over_mu0: barycentric(&nodes, &f, x_of(vv)),
                        bound,
                        interpolated: true,
                    },
                })
                .collect(),
        )
    }
}

/// The truncation term of eq. C1, `2·Σ_{j>16}|a_j|`, estimated from the
/// interpolant's coefficients (module docs): with `t = max |c₁₂…c₁₆|` and
/// `t₈ = max |c₆…c₁₀|` (five each: next to a weak singularity the
/// coefficients oscillate, and three in a row can all be small — measured:
/// a cone's run whose `c₁₄…c₁₆` were 6–8·10⁻¹¹ beside `c₁₂ = 5·10⁻¹⁰` was
/// off by 1.5× the bound the last three gave), the decay per degree `r =
/// (t/t₈)^{1/6}`; the tail of a series decaying so from `t` is `t·r/(1 −
/// r)`, taken twice (C1) and twice again for the estimate: `4t·max(1, r/(1
/// − r))`. `None` (the run is halved) where the coefficients decay more
/// slowly than `r = 0.8`: μ(v) not smooth on the run. A `t` at or below the
/// nodes' bound is their noise, not a truncation: `4t`.
fn truncation(c: &[f64; DEGREE + 1], node_bound: f64) -> Option<f64> {
    let top = |r: core::ops::Range<usize>| c[r].iter().fold(0.0f64, |t, x| t.max(x.abs()));
    let (t, t8) = (top(DEGREE - 4..DEGREE + 1), top(6..11));
    if t <= node_bound {
        return Some(4.0 * t);
    }
    let r = if t8 > 0.0 {
        (t / t8).powf(1.0 / 6.0)
    } else {
        1.0
    };
    if r.is_nan() || r >= 0.8 {
        return None;
    }
    Some(4.0 * t * (r / (1.0 - r)).max(1.0))
}

/// Chebyshev coefficients `c_j` of the interpolant through `f` at the
/// extrema `x_k = cos(kπ/n)` (a DCT-I: `c_j = (2/n) Σ″ f_k cos(jkπ/n)`,
/// the end terms halved, and `c₀`, `c_n` halved once more).
fn coefficients(f: &[f64; DEGREE + 1]) -> [f64; DEGREE + 1] {
    let n = DEGREE;
    let mut c = [0.0; DEGREE + 1];
    for (j, cj) in c.iter_mut().enumerate() {
        let mut s = 0.0;
        for (k, &fk) in f.iter().enumerate() {
            let w = if k == 0 || k == n { 0.5 } else { 1.0 };
            s += w * fk * ((j * k) as f64 * core::f64::consts::PI / n as f64).cos();
        }
        *cj = s * 2.0 / n as f64 * if j == 0 || j == n { 0.5 } else { 1.0 };
    }
    c
}

/// The interpolant through `f` at the extrema `nodes` at `x ∈ [−1, 1]`,
/// barycentric (weights `(−1)^k`, halved at the ends); a node's own value
/// at a node.
fn barycentric(nodes: &[f64], f: &[f64; DEGREE + 1], x: f64) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    for (k, (&xk, &fk)) in nodes.iter().zip(f).enumerate() {
        let dx = x - xk;
        if dx == 0.0 {
            return fk;
        }
        let mut w = if k % 2 == 0 { 1.0 } else { -1.0 };
        if k == 0 || k == DEGREE {
            w *= 0.5;
        }
        num += w / dx * fk;
        den += w / dx;
    }
    num / den
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_interpolant_reproduces_a_polynomial_and_its_coefficients() {
        // T_3(x) = 4x³ − 3x and a degree-16 polynomial: exact through 17
        // nodes; the coefficients of T_3 are (0, 0, 0, 1, 0, …).
        let nodes: Vec<f64> = (0..=DEGREE)
            .map(|k| (k as f64 * core::f64::consts::PI / DEGREE as f64).cos())
            .collect();
        let t3 = |x: f64| 4.0 * x * x * x - 3.0 * x;
        let f: [f64; DEGREE + 1] = core::array::from_fn(|k| t3(nodes[k]));
        let c = coefficients(&f);
        for (j, cj) in c.iter().enumerate() {
            let want = if j == 3 { 1.0 } else { 0.0 };
            assert!((cj - want).abs() < 1e-14, "c_{j} = {cj}");
        }
        let q = |x: f64| (0..=DEGREE).fold(0.0, |s, j| s * x + (j as f64 - 7.5) / 8.0);
        let f: [f64; DEGREE + 1] = core::array::from_fn(|k| q(nodes[k]));
        for i in 0..=100 {
            let x = -1.0 + 2.0 * i as f64 / 100.0;
            assert!((barycentric(&nodes, &f, x) - q(x)).abs() < 1e-13, "x = {x}");
        }
        // T_16's coefficient is halved in a DCT-I: the interpolant of T_16
        // has c_16 = 1.
        let f: [f64; DEGREE + 1] = core::array::from_fn(|k| (16.0 * nodes[k].acos()).cos());
        assert!((coefficients(&f)[DEGREE] - 1.0).abs() < 1e-13);
    }
}
