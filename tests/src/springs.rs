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
//! **Its error**: the quadrature's, the sum of the accepted panels'
//! `|K₁₅ − G₇|` (an over-estimate on smooth panels, where the Kronrod rule
//! is far more accurate than the Gauss rule it is compared with), and the
//! time step's, from the same nodes at `n`, `n/2` and `n/4` steps: the
//! scheme is second order, so the error at `n` would be a third of the last
//! change `|B(n) − B(n/2)|`; but the changes jitter with where the events
//! fall on the grid (a single spring's mean can move by the same amount over
//! three doublings), so twice a third of the larger of the last two changes
//! is allowed. `μ`'s error is `(δN + |μ|δD)/D`.

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
}

/// One spring's means with `n` steps per period; `(bc, bs) = (b cos φ, b sin φ)`.
pub fn spring(d: f64, a: f64, (bc, bs): (f64, f64), v: f64, n: u32) -> SpringMeans {
    let h = TAU / f64::from(n);
    let x = |t: f64| bc * t.cos() - bs * t.sin();
    let xp = |t: f64| -bc * t.sin() - bs * t.cos();
    let w = |t: f64| d - a * t.cos();
    if d <= -a {
        return SpringMeans::default();
    }
    if d > a {
        // Start on the band edge where a clamp in the direction of motion is
        // certain: where the stick rate V − Im((b e^{iφ} ± a)e^{iθ}) is
        // smallest against the edge (V ≥ 0; mirrored for V < 0).
        let (t0, sign) = if v >= 0.0 {
            (-FRAC_PI_2 - bs.atan2(bc + a), 1.0)
        } else {
            (FRAC_PI_2 - bs.atan2(bc - a), -1.0)
        };
        let mut s = sign * w(t0) * (1.0 - 4.0 * f64::EPSILON);
        let mut x_prev = x(t0);
        let mut last = (f64::NAN, f64::NAN);
        for p in 0..1000u32 {
            let (mut sum_s, mut sum_sx) = (0.0, 0.0);
            let (mut s_prev, mut sx_prev) = (s, s * xp(t0));
            for j in 1..=n {
                let t = t0 + h * f64::from(j);
                let xt = x(t);
                s = (s + v * h + (xt - x_prev)).clamp(-w(t), w(t));
                x_prev = xt;
                let sx = s * xp(t);
                sum_s += 0.5 * (s_prev + s);
                sum_sx += 0.5 * (sx_prev + sx);
                s_prev = s;
                sx_prev = sx;
            }
            let means = (sum_s / f64::from(n), sum_sx / f64::from(n));
            if p >= 2 && means == last {
                return SpringMeans {
                    s: means.0,
                    sx: means.1,
                    w: d,
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
    let (mut s, mut t_prev) = (0.0f64, t_start);
    let (mut int_s, mut int_sx, mut int_w) = (0.0, 0.0, 0.0);
    let mut x_prev = x(t_start);
    let (mut sx_prev, mut w_prev) = (0.0, 0.0);
    for j in 1..=whole + 1 {
        let t = if j > whole {
            t_end
        } else {
            t_start + h * f64::from(j)
        };
        if t <= t_prev {
            continue;
        }
        let wt = if j > whole { 0.0 } else { w(t).max(0.0) };
        let xt = x(t);
        let s_new = (s + v * (t - t_prev) + (xt - x_prev)).clamp(-wt, wt);
        let sx = s_new * xp(t);
        int_s += 0.5 * (t - t_prev) * (s + s_new);
        int_sx += 0.5 * (t - t_prev) * (sx_prev + sx);
        int_w += 0.5 * (t - t_prev) * (w_prev + wt);
        w_prev = wt;
        s = s_new;
        sx_prev = sx;
        x_prev = xt;
        t_prev = t;
    }
    SpringMeans {
        s: int_s / TAU,
        sx: int_sx / TAU,
        w: int_w / TAU,
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

/// Kronrod and Gauss sums of `f` on `[l, r]`, and the nodes' values
/// (so the same nodes can be re-evaluated at another step count).
fn gk(l: f64, r: f64, f: &mut impl FnMut(f64) -> Bed) -> (Bed, Bed) {
    let (c, h) = (0.5 * (l + r), 0.5 * (r - l));
    let (mut k, mut g) = (Bed::default(), Bed::default());
    for i in 0..8 {
        let pts: &[f64] = if i == 7 {
            &[c]
        } else {
            &[c - h * GK_X[i], c + h * GK_X[i]]
        };
        for &t in pts {
            let y = f(t);
            k = k.add(y, h * GK_WK[i]);
            if i % 2 == 1 {
                g = g.add(y, h * G_W[i / 2]);
            }
        }
    }
    (k, g)
}

/// The bed over `t ∈ [0, π]` of one piece: adaptive panels until each
/// panel's `|K − G|` on `N` and on `P` is within `tol·(width/π)`; returns
/// the accepted panels with their Kronrod and Gauss sums.
fn panels(tol: f64, f: &mut impl FnMut(f64) -> Bed) -> Vec<(f64, f64, Bed, Bed)> {
    let mut todo = vec![(0.0, PI)];
    let mut done = Vec::new();
    while let Some((l, r)) = todo.pop() {
        let (k, g) = gk(l, r, f);
        let e = (k.num - g.num).abs().max((k.input - g.input).abs());
        if e <= tol * (r - l) / PI || r - l < 1e-9 {
            done.push((l, r, k, g));
        } else {
            let m = 0.5 * (l + r);
            todo.push((l, m));
            todo.push((m, r));
        }
    }
    done
}

/// `μ/μ₀` of the profile `d = 1 − ξⁿ` (exponent `n_exp`) by the brute force
/// with quadrature tolerance `tol` (absolute, on `N` and `P` per piece) and
/// `n` steps per period (checked against `n/2` and `n/4`).
pub fn mu(n_exp: f64, a: f64, b: f64, phi: f64, v: f64, tol: f64, n: u32) -> BruteForce {
    let (bc, bs) = (b * phi.cos(), b * phi.sin());
    let xi_max = (1.0 + a).powf(1.0 / n_exp);
    let xi_a = if a < 1.0 {
        (1.0 - a).powf(1.0 / n_exp)
    } else {
        0.0
    };
    let mut total = [Bed::default(); 3];
    let mut quad = Bed::default();
    let mut springs = 0;
    for (l, r) in [(0.0, xi_a), (xi_a, xi_max)] {
        if r <= l {
            continue;
        }
        let at = |t: f64, steps: u32| {
            let xi = l + 0.5 * (r - l) * (1.0 - t.cos());
            let jac = 0.5 * (r - l) * t.sin();
            let m = spring(1.0 - xi.powf(n_exp), a, (bc, bs), v, steps);
            Bed {
                num: m.s * jac,
                den: m.w * jac,
                input: m.sx * jac,
            }
        };
        for (pl, pr, k, g) in panels(tol, &mut |t| at(t, n)) {
            let (k_half, _) = gk(pl, pr, &mut |t| at(t, n / 2));
            let (k_quarter, _) = gk(pl, pr, &mut |t| at(t, n / 4));
            total[0] = total[0].add(k, 1.0);
            total[1] = total[1].add(k_half, 1.0);
            total[2] = total[2].add(k_quarter, 1.0);
            quad = quad.add(
                Bed {
                    num: (k.num - g.num).abs(),
                    den: (k.den - g.den).abs(),
                    input: (k.input - g.input).abs(),
                },
                1.0,
            );
            springs += 15;
        }
    }
    let [fine, half, quarter] = total;
    let step = |x: f64, y: f64, z: f64| 2.0 * (x - y).abs().max((y - z).abs()) / 3.0;
    let bed_err = Bed {
        num: quad.num + step(fine.num, half.num, quarter.num),
        den: quad.den + step(fine.den, half.den, quarter.den),
        input: quad.input + step(fine.input, half.input, quarter.input),
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
