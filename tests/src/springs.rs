//! A brute force over the springs of a curved profile's MDR bed, written
//! from the model's statement and sharing no code with model-core's
//! quadrature (`model_core::mdr`) or its per-spring solvers: the reference
//! for curved profiles in `tests/mdr.rs` and in the command-line tests.
//!
//! **One spring** (band offset `d`, band `w = d − a cos θ`, drive
//! `u_x = Vθ + X(θ)`, `X = b cos(θ + φ)`, units of `W₀`) runs the paper's
//! stick-trial-and-clamp scheme with `n` steps per period: an intermittent
//! spring (`|d| < a`) over its contact window from the landing (`s = 0` at
//! the exact phase `acos(d/a)`) to the lift-off, the last step shortened to
//! end there; a permanent one (`d > a`) from the band edge at the phase where
//! a clamp in the direction of motion is certain, period after period until
//! the period's means repeat. The means `⟨s⟩`, `⟨s X'⟩` (the tangential
//! transducer's input) and `⟨w⁺⟩` are trapezoid sums on the same grid (so a
//! spring that slips throughout gives `⟨s⟩ = ⟨w⁺⟩` exactly; over a whole
//! period the trapezoid rule integrates `w = d − a cos θ` exactly).
//!
//! **The bed**: `N = ∫⟨s⟩dξ`, `D = ∫⟨w⁺⟩dξ`, `P = ∫⟨sX'⟩dξ` over the springs
//! `d = 1 − ξⁿ`, `0 ≤ ξ ≤ ξ_max = (1 + a)^{1/n}`, split at the lift-off onset
//! `ξ_a = (1 − a)^{1/n}` (`a < 1`) and integrated in `t` with
//! `ξ = l + (r − l)(1 − cos t)/2` (which removes the square-root ends) by
//! adaptive Gauss–Kronrod (7/15 points): a panel is halved until its
//! `|K₁₅ − G₇|` on `N` is within its share of the tolerance, so kinks of
//! `⟨s⟩(ξ)` (where a spring's stick–slip pattern changes) are bisected down
//! instead of costing an erratic `Δh²` as on a fixed grid. `μ/μ₀ = N/D`.
//!
//! **Its error** ([`mu`]): the quadrature's, the sum of the accepted panels'
//! `|K₁₅ − G₇|` (an over-estimate on smooth panels, where the Kronrod rule
//! is far more accurate than the Gauss rule it is compared with), and the
//! time step's, from the same nodes at `n`, `n/2` and `n/4` steps: the
//! scheme is second order, so the error at `n` would be a third of the last
//! change `|B(n) − B(n/2)|`; but the changes jitter with where the events
//! fall on the grid (a single spring's mean can move by the same amount over
//! three doublings), so twice a third of the larger of the last two changes
//! is allowed. `μ`'s error is `(δN + |μ|δD)/D`.
//!
//! **Refined** ([`mu_extrapolated`], for checks at the MDR's `10⁻⁹`): the
//! cells around each change of a spring's clamp state are re-run in finer
//! sub-steps ([`spring_refined`]), which removes the jitter, so that
//! Richardson extrapolation in `n` applies; a panel is accepted only when the
//! springs at its ends have the stick–slip pattern of its outermost nodes.

use std::f64::consts::{FRAC_PI_2, PI, TAU};

/// Per-period means of one spring.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SpringMeans {
    /// `⟨s⟩`.
    pub s: f64,
    /// `⟨s X'⟩`, `X' = −b sin(θ + φ)`.
    pub sx: f64,
    /// `⟨w⁺⟩`.
    pub w: f64,
    /// Changes of the clamp state (stick, slip either way) over the period
    /// on the grid of `n` steps: the spring's stick–slip pattern, which
    /// changes where `⟨s⟩(ξ)` has a kink.
    pub changes: u32,
}

/// One spring's means with `n` steps per period; `(bc, bs) = (b cos φ, b sin φ)`.
pub fn spring(d: f64, a: f64, bcs: (f64, f64), v: f64, n: u32) -> SpringMeans {
    spring_refined(d, a, bcs, v, n, 1)
}

/// The drive and band of one spring at a phase: `(w, X, X')`.
fn at(t: f64, d: f64, a: f64, (bc, bs): (f64, f64)) -> (f64, f64, f64) {
    let (sn, cs) = t.sin_cos();
    (d - a * cs, bc * cs - bs * sn, -bc * sn - bs * cs)
}

/// One cell `[t0, t1]` of the scheme from `s` in `k` equal sub-steps: the
/// end value, the trapezoid sums `(∫s, ∫sX', ∫w⁺)` over the cell, and the
/// clamp state of the last sub-step (`−1`, `0` sticking, `+1`). `end` is the
/// lift-off phase, where the band is taken as exactly 0.
#[allow(clippy::too_many_arguments)]
fn cell(
    mut s: f64,
    (t0, t1): (f64, f64),
    k: u32,
    d: f64,
    a: f64,
    bcs: (f64, f64),
    v: f64,
    end: f64,
) -> (f64, [f64; 3], i8) {
    let band = |w: f64, t: f64| if t >= end { 0.0 } else { w.max(0.0) };
    let (w0, mut x_prev, xp0) = at(t0, d, a, bcs);
    let (mut w_prev, mut sx_prev) = (band(w0, t0), s * xp0);
    let mut t_prev = t0;
    let mut sums = [0.0; 3];
    let mut state = 0;
    for j in 1..=k {
        let t = if j == k {
            t1
        } else {
            t0 + (t1 - t0) * f64::from(j) / f64::from(k)
        };
        let (w, x, xp) = at(t, d, a, bcs);
        let w = band(w, t);
        let trial = s + v * (t - t_prev) + (x - x_prev);
        let s_new = trial.clamp(-w, w);
        state = if trial > w {
            1
        } else if trial < -w {
            -1
        } else {
            0
        };
        let sx = s_new * xp;
        let h = 0.5 * (t - t_prev);
        sums[0] += h * (s + s_new);
        sums[1] += h * (sx_prev + sx);
        sums[2] += h * (w_prev + w);
        (s, x_prev, sx_prev, w_prev, t_prev) = (s_new, x, sx, w, t);
    }
    (s, sums, state)
}

/// [`spring`] with the two cells around every change of the clamp state
/// (stick to slip, slip to stick) re-run in `sub` sub-steps each.
///
/// The scheme is exact inside a stick phase (`s` follows the drive) and on a
/// slip phase (`s = ±w` at the grid points); its error comes from the cells
/// where the state changes: the slip-to-stick phase lands up to a cell late
/// or early (an `O(h²)` offset carried through the stick phase) and the
/// trapezoid cuts the kink of `s(θ)`. Both depend on where the event falls
/// in its cell, so at `sub = 1` the error is `O(h²)` with a coefficient that
/// jitters with `n`. With the two cells around each change sub-stepped, that
/// part is `O((h/sub)²)`, and what is left is the trapezoid's `−h²/12·[f']`
/// at the ends of the smooth pieces (a smooth function of `h`) plus `O(h³)`:
/// Richardson extrapolation in `n` then applies ([`mu_extrapolated`]).
pub fn spring_refined(d: f64, a: f64, bcs: (f64, f64), v: f64, n: u32, sub: u32) -> SpringMeans {
    let (bc, bs) = bcs;
    let h = TAU / f64::from(n);
    if d <= -a {
        return SpringMeans::default();
    }
    // Runs cells `j_from..=j_to` of the grid `t(j)`, refining around state
    // changes; returns the end value and the sums.
    let run = |s0: f64, state0: i8, cells: u32, t: &dyn Fn(u32) -> f64, end: f64| {
        let mut s = s0;
        let mut state = state0;
        let mut sums = [0.0; 3];
        let mut changes = 0;
        // The previous cell: its start value and its sums (uncommitted).
        let mut prev: Option<(f64, [f64; 3])> = None;
        for j in 1..=cells {
            let span = (t(j - 1), t(j));
            if span.1 <= span.0 {
                continue;
            }
            let (mut s1, mut c, st) = cell(s, span, 1, d, a, bcs, v, end);
            changes += u32::from(st != state);
            if sub > 1 && st != state {
                let mut start = s;
                if let Some((s_before, c_prev)) = prev.take() {
                    // Re-run the previous cell too: the event may lie in it.
                    let back = (t(j - 2), span.0);
                    let (s_mid, c_mid, _) = cell(s_before, back, sub, d, a, bcs, v, end);
                    for i in 0..3 {
                        sums[i] += c_mid[i] - c_prev[i];
                    }
                    start = s_mid;
                }
                let st2;
                (s1, c, st2) = cell(start, span, sub, d, a, bcs, v, end);
                state = st2;
                prev = None;
                for i in 0..3 {
                    sums[i] += c[i];
                }
                s = s1;
                continue;
            }
            state = st;
            prev = Some((s, c));
            for i in 0..3 {
                sums[i] += c[i];
            }
            s = s1;
        }
        (s, sums, changes)
    };
    if d > a {
        // Start on the band edge where a clamp in the direction of motion is
        // certain: where the stick rate V − Im((b e^{iφ} ± a)e^{iθ}) is
        // smallest against the edge (V ≥ 0; mirrored for V < 0).
        let (t0, sign) = if v >= 0.0 {
            (-FRAC_PI_2 - bs.atan2(bc + a), 1.0)
        } else {
            (FRAC_PI_2 - bs.atan2(bc - a), -1.0)
        };
        let w0 = d - a * t0.cos();
        let mut s = sign * w0 * (1.0 - 4.0 * f64::EPSILON);
        let state0 = if sign > 0.0 { 1 } else { -1 };
        let grid = |j: u32| t0 + h * f64::from(j);
        let mut last = (f64::NAN, f64::NAN);
        for p in 0..1000u32 {
            let (s_end, sums, changes) = run(s, state0, n, &grid, f64::INFINITY);
            s = s_end;
            let means = (sums[0] / TAU, sums[1] / TAU);
            if p >= 2 && means == last {
                return SpringMeans {
                    s: means.0,
                    sx: means.1,
                    w: d,
                    changes,
                };
            }
            last = means;
        }
        panic!("a permanent spring did not repeat its period (d = {d}, a = {a}, V = {v})");
    }
    // Intermittent: one window from the landing (s = 0) to the lift-off.
    let tc = (d / a).acos();
    let (t_start, t_end) = (tc, TAU - tc);
    let whole = ((t_end - t_start) / h).floor() as u32;
    let grid = |j: u32| {
        if j > whole {
            t_end
        } else {
            t_start + h * f64::from(j)
        }
    };
    let (_, sums, changes) = run(0.0, 0, whole + 1, &grid, t_end);
    SpringMeans {
        s: sums[0] / TAU,
        sx: sums[1] / TAU,
        w: sums[2] / TAU,
        changes,
    }
}

/// The bed's integrals `(N, D, P) = ∫(⟨s⟩, ⟨w⁺⟩, ⟨sX'⟩) dξ`.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Bed {
    /// `∫⟨s⟩ dξ`.
    pub num: f64,
    /// `∫⟨w⁺⟩ dξ` (the mean normal force `D`).
    pub den: f64,
    /// `∫⟨s X'⟩ dξ` (the tangential transducer's input).
    pub input: f64,
}

impl Bed {
    fn add(self, o: Bed, k: f64) -> Bed {
        Bed {
            num: self.num + k * o.num,
            den: self.den + k * o.den,
            input: self.input + k * o.input,
        }
    }
}

/// The brute force's answer with its error estimate.
#[derive(Debug, Clone, Copy)]
pub struct BruteForce {
    /// `μ/μ₀ = N/D`.
    pub mu: f64,
    /// Estimated error of `mu` (quadrature + time step, module docs).
    pub err: f64,
    /// The bed's integrals at `n` steps per period.
    pub bed: Bed,
    /// Their estimated errors (each component separately).
    pub bed_err: Bed,
    /// Springs evaluated (at each of the two step counts).
    pub springs: usize,
}

const GK_X: [f64; 8] = [
    0.991_455_371_120_812_6,
    0.949_107_912_342_758_5,
    0.864_864_423_359_769_1,
    0.741_531_185_599_394_4,
    0.586_087_235_467_691_1,
    0.405_845_151_377_397_2,
    0.207_784_955_007_898_5,
    0.0,
];
const GK_WK: [f64; 8] = [
    0.022_935_322_010_529_22,
    0.063_092_092_629_978_55,
    0.104_790_010_322_250_2,
    0.140_653_259_715_525_9,
    0.169_004_726_639_267_9,
    0.190_350_578_064_785_4,
    0.204_432_940_075_298_9,
    0.209_482_141_084_728,
];
/// Gauss weights on the odd Kronrod nodes (1, 3, 5, 7 of `GK_X`).
const G_W: [f64; 4] = [
    0.129_484_966_168_869_7,
    0.279_705_391_489_276_7,
    0.381_830_050_505_118_9,
    0.417_959_183_673_469_4,
];

/// A node's beds and its spring's stick–slip pattern ([`SpringMeans::changes`]).
type Node<const K: usize> = ([Bed; K], u32);

/// Kronrod and Gauss sums of `f` on `[l, r]` (each of its `K` beds), and the
/// patterns at the outermost nodes (left, right).
fn gk<const K: usize>(
    l: f64,
    r: f64,
    f: &mut impl FnMut(f64) -> Node<K>,
) -> ([Bed; K], [Bed; K], [u32; 2]) {
    let (c, h) = (0.5 * (l + r), 0.5 * (r - l));
    let (mut k, mut g) = ([Bed::default(); K], [Bed::default(); K]);
    let mut outer = [0; 2];
    for i in 0..8 {
        let pts: &[f64] = if i == 7 {
            &[c]
        } else {
            &[c - h * GK_X[i], c + h * GK_X[i]]
        };
        for (side, &t) in pts.iter().enumerate() {
            let (y, pattern) = f(t);
            if i == 0 {
                outer[side] = pattern;
            }
            for j in 0..K {
                k[j] = k[j].add(y[j], h * GK_WK[i]);
                if i % 2 == 1 {
                    g[j] = g[j].add(y[j], h * G_W[i / 2]);
                }
            }
        }
    }
    (k, g, outer)
}

/// The bed over `t ∈ [0, π]` of one piece: adaptive panels until each
/// panel's `|K − G|` on `N` and on `P` of the first bed is within
/// `tol·(width/π)` and the springs at its interior ends have the pattern of
/// the outermost nodes (a kink of `⟨s⟩(ξ)` between the outermost node and
/// the panel's end — 0.4 % of its width — is invisible to both rules: one
/// such kink cost `1.1·10⁻⁹` on a sphere at a = 1 before this check);
/// returns the accepted panels' Kronrod and Gauss sums.
fn panels<const K: usize>(
    tol: f64,
    f: &mut impl FnMut(f64) -> Node<K>,
) -> Vec<([Bed; K], [Bed; K])> {
    let mut todo = vec![(0.0, PI)];
    let mut done = Vec::new();
    while let Some((l, r)) = todo.pop() {
        let (k, g, outer) = gk(l, r, f);
        let e = (k[0].num - g[0].num)
            .abs()
            .max((k[0].input - g[0].input).abs());
        let mut same = |t: f64, pattern: u32| t <= 0.0 || t >= PI || f(t).1 == pattern;
        let smooth = e <= tol * (r - l) / PI && same(l, outer[0]) && same(r, outer[1]);
        if smooth || r - l < 1e-9 {
            done.push((k, g));
        } else {
            let m = 0.5 * (l + r);
            todo.push((l, m));
            todo.push((m, r));
        }
    }
    done
}

/// The bed's sums over the pieces `[0, ξ_a]`, `[ξ_a, ξ_max]` of the profile
/// `d = 1 − ξⁿ` (exponent `n_exp`) with the springs' means `f(d, steps)` at
/// `n`, `n/2`, `n/4` steps per period, mixed per node by `mix` into the
/// beds the panels adapt on (the first) and report: returns their Kronrod
/// sums, the first bed's summed `|K − G|`, and the springs evaluated.
fn bed<const K: usize>(
    n_exp: f64,
    a: f64,
    tol: f64,
    n: u32,
    f: &impl Fn(f64, u32) -> SpringMeans,
    mix: impl Fn([SpringMeans; 3]) -> [SpringMeans; K],
) -> ([Bed; K], Bed, usize) {
    let xi_max = (1.0 + a).powf(1.0 / n_exp);
    let xi_a = if a < 1.0 {
        (1.0 - a).powf(1.0 / n_exp)
    } else {
        0.0
    };
    let mut total = [Bed::default(); K];
    let mut quad = Bed::default();
    let mut springs = 0;
    for (l, r) in [(0.0, xi_a), (xi_a, xi_max)] {
        if r <= l {
            continue;
        }
        let mut node = |t: f64| {
            let xi = l + 0.5 * (r - l) * (1.0 - t.cos());
            let jac = 0.5 * (r - l) * t.sin();
            let d = 1.0 - xi.powf(n_exp);
            let fine = f(d, n);
            let means = mix([fine, f(d, n / 2), f(d, n / 4)]);
            let beds = means.map(|m| Bed {
                num: m.s * jac,
                den: m.w * jac,
                input: m.sx * jac,
            });
            (beds, fine.changes)
        };
        for (k, g) in panels(tol, &mut node) {
            for j in 0..K {
                total[j] = total[j].add(k[j], 1.0);
            }
            quad = quad.add(
                Bed {
                    num: (k[0].num - g[0].num).abs(),
                    den: (k[0].den - g[0].den).abs(),
                    input: (k[0].input - g[0].input).abs(),
                },
                1.0,
            );
            springs += 15;
        }
    }
    (total, quad, springs)
}

/// `bed`'s answer with the bed's error `quad + step`, per component.
fn answer(
    fine: Bed,
    quad: Bed,
    step: impl Fn(fn(&Bed) -> f64) -> f64,
    springs: usize,
) -> BruteForce {
    let bed_err = Bed {
        num: quad.num + step(|b| b.num),
        den: quad.den + step(|b| b.den),
        input: quad.input + step(|b| b.input),
    };
    let mu = fine.num / fine.den;
    BruteForce {
        mu,
        err: (bed_err.num + mu.abs() * bed_err.den) / fine.den,
        bed: fine,
        bed_err,
        springs,
    }
}

/// `μ/μ₀` of the profile `d = 1 − ξⁿ` (exponent `n_exp`) by the brute force
/// with quadrature tolerance `tol` (absolute, on `N` and `P` per piece) and
/// `n` steps per period (checked against `n/2` and `n/4`).
pub fn mu(n_exp: f64, a: f64, b: f64, phi: f64, v: f64, tol: f64, n: u32) -> BruteForce {
    let bcs = (b * phi.cos(), b * phi.sin());
    let f = |d: f64, steps: u32| spring(d, a, bcs, v, steps);
    let ([fine, half, quarter], quad, springs) = bed(n_exp, a, tol, n, &f, |m| m);
    let step = |c: fn(&Bed) -> f64| {
        let (x, y, z) = (c(&fine), c(&half), c(&quarter));
        2.0 * (x - y).abs().max((y - z).abs()) / 3.0
    };
    answer(fine, quad, step, springs)
}

/// `μ/μ₀` by the brute force refined for accuracy: each spring by
/// [`spring_refined`] (the cells around its events in `sub` sub-steps) at
/// `n`, `n/2` and `n/4` steps per period, extrapolated per node by Richardson
/// (`R(n) = (4B(n) − B(n/2))/3`, which removes the trapezoid's `h²` term),
/// the bed integrated by the adaptive panels on `R(n)`.
///
/// Its error: the panels' summed `|K − G|` on `R(n)`, plus the whole change
/// `|R(n) − R(n/2)|` for the time step (for an `O(h³)` remainder the error
/// of `R(n)` is a seventh of that change; the rest covers the remainder's
/// jitter with where the events fall on the grid).
pub fn mu_extrapolated(
    n_exp: f64,
    (a, b, phi, v): (f64, f64, f64, f64),
    tol: f64,
    n: u32,
    sub: u32,
) -> BruteForce {
    let bcs = (b * phi.cos(), b * phi.sin());
    let f = |d: f64, steps: u32| spring_refined(d, a, bcs, v, steps, sub);
    let rich = |x: SpringMeans, y: SpringMeans| SpringMeans {
        s: (4.0 * x.s - y.s) / 3.0,
        sx: (4.0 * x.sx - y.sx) / 3.0,
        w: (4.0 * x.w - y.w) / 3.0,
        changes: x.changes,
    };
    let ([fine, coarse], quad, springs) =
        bed(n_exp, a, tol, n, &f, |[x, y, z]| [rich(x, y), rich(y, z)]);
    let step = |c: fn(&Bed) -> f64| (c(&fine) - c(&coarse)).abs();
    answer(fine, quad, step, springs)
}
