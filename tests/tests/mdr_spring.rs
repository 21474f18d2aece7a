//! The per-spring solvers of the MDR foundation (`mdr::spring_means`: the
//! exact flat-punch solver scaled by `d` for permanent springs, the lift-off
//! walk for intermittent ones) against an independent brute force written
//! here at 2²¹ steps per period: the measurement behind
//! `mdr::SPRING_PRECISION`, the per-spring part of the quadrature's bound.
//!
//! The brute force is the paper's stick-trial-and-clamp scheme, written so
//! that rounding does not accumulate: while the spring sticks, its stretch
//! is `s_a + u_x(θ) − u_x(θ_a)` from the last clamp `(θ_a, s_a)` (in exact
//! arithmetic the same as adding the increments step by step, so the same
//! discretisation error), and the period mean is a compensated (Neumaier)
//! sum. So its error is the scheme's `O(N⁻²)` and a few ulps — not the
//! `N·ε ≈ 5·10⁻¹⁰` of a plain run at this N.

use std::f64::consts::{FRAC_PI_2, PI, TAU};

use integration_tests::Rng;
use model_core::mdr::{self, Profile};
use model_core::{Drive, Libm};

/// Neumaier's compensated sum.
#[derive(Default)]
struct Sum {
    s: f64,
    c: f64,
}

impl Sum {
    fn add(&mut self, x: f64) {
        let t = self.s + x;
        if self.s.abs() >= x.abs() {
            self.c += (self.s - t) + x;
        } else {
            self.c += (x - t) + self.s;
        }
        self.s = t;
    }
    fn value(&self) -> f64 {
        self.s + self.c
    }
}

/// The clamp state of the anchored scheme.
struct Anchor {
    theta: f64,
    stretch: f64,
    cos_phase: f64,
}

/// One step to phase `t` with band `w`: the stick trial from the anchor,
/// clamped to `[−w, w]` (a clamp re-anchors). Returns the stretch.
fn step(an: &mut Anchor, t: f64, w: f64, b: f64, phi: f64, v: f64) -> f64 {
    let c = (t + phi).cos();
    let trial = an.stretch + v * (t - an.theta) + b * (c - an.cos_phase);
    if trial > w || trial < -w {
        let s = if trial > w { w } else { -w };
        *an = Anchor {
            theta: t,
            stretch: s,
            cos_phase: c,
        };
        s
    } else {
        trial
    }
}

/// `⟨s⟩` over a period of the spring with band `w = d − a cos θ` and drive
/// `u_x = Vθ + b cos(θ + φ)`, `V ≥ 0`, by the anchored scheme with `n` steps
/// per period. Permanent springs (`d > a`) start on the forward band edge at
/// the phase where a forward clamp is certain (the minimum of
/// `Im((b e^{iφ} + a) e^{iθ})`, as `integration_tests::fixed_warm`), so the
/// state is the scheme's steady one after that clamp; the third period is
/// returned and checked against the second. Intermittent springs run one
/// window from the landing (`s = 0`, exact) to the lift-off.
fn anchored(d: f64, a: f64, b: f64, phi: f64, v: f64, n: u32) -> f64 {
    let h = TAU / f64::from(n);
    let w = |t: f64| d - a * t.cos();
    if d > a {
        let t0 = -FRAC_PI_2 - (b * phi.sin()).atan2(b * phi.cos() + a);
        let s0 = w(t0) * (1.0 - 4.0 * f64::EPSILON);
        let mut an = Anchor {
            theta: t0,
            stretch: s0,
            cos_phase: (t0 + phi).cos(),
        };
        let mut means = [0.0; 3];
        for (p, mean) in means.iter_mut().enumerate() {
            let mut sum = Sum::default();
            for j in 1..=n {
                let t = t0 + h * f64::from(p as u32 * n + j);
                sum.add(step(&mut an, t, w(t), b, phi, v));
            }
            *mean = sum.value() / f64::from(n);
        }
        assert!(
            (means[2] - means[1]).abs() <= 1e-13 * (1.0 + a + b),
            "brute force not periodic: {means:?}"
        );
        return means[2];
    }
    // Intermittent: landing θ_L = acos(d/a) to lift-off 2π − θ_L.
    let tl = (d / a).acos();
    let tr = TAU - tl;
    let whole = ((tr - tl) / h).floor() as u32;
    let mut an = Anchor {
        theta: tl,
        stretch: 0.0,
        cos_phase: (tl + phi).cos(),
    };
    let mut sum = Sum::default();
    let mut s_last = 0.0;
    for j in 1..=whole {
        let t = tl + h * f64::from(j);
        s_last = step(&mut an, t, w(t).max(0.0), b, phi, v);
        // Trapezoid: interior points weight h, the last whole one h/2.
        sum.add(if j < whole {
            h * s_last
        } else {
            0.5 * h * s_last
        });
    }
    let last = tr - (tl + h * f64::from(whole));
    let s_end = step(&mut an, tr, 0.0, b, phi, v);
    sum.add(0.5 * last * (s_last + s_end));
    sum.value() / TAU
}

/// The allowance of the brute force at `n` steps: `K(1 + a + b)/n²` with
/// `K = 20`, twice the stated discretisation constant of the flat schemes
/// (`fixed_step::DISCRETISATION_K`, `liftoff::stepping::DISCRETISATION_K`,
/// both 10 for `μ/μ₀` with measured worsts 4.75 and 2.16 by self-convergence): a permanent spring
/// is the flat punch scaled by `d`, so its `⟨s⟩` errs by at most
/// `d·K(1 + b/d)/n² ≤ K(1 + a + b)/n²`; an intermittent spring's band
/// `d − a cos θ` is the lift-off punch's scaled by `d` (`d > 0`) or its
/// mirror image in time, and the factor 2 covers `⟨w⁺⟩ ≤ 2a`. The test
/// also checks that the brute force itself converges at that rate
/// (`|B(n/2) − B(n)| ≤ K(1 + a + b)/(n/2)²`), so the constant is not taken on
/// trust for these springs.
fn allowance(a: f64, b: f64, n: u32) -> f64 {
    20.0 * (1.0 + a + b) / (f64::from(n) * f64::from(n))
}

/// One spring against the brute force: checks `B(N/2) − B(N)` within its
/// allowance (the brute force converges as stated) and `|solver − B(N)| +
/// allowance ≤ SPRING_PRECISION·(1 + a + b)`; returns the gap over `1 + a + b`.
fn check_spring(got: f64, d: f64, (a, b, phi): (f64, f64, f64), v: f64, n: u32) -> f64 {
    let bn = anchored(d, a, b, phi, v, n);
    let bh = anchored(d, a, b, phi, v, n / 2);
    let scale = 1.0 + a + b;
    assert!(
        (bh - bn).abs() <= allowance(a, b, n / 2),
        "brute force converges slower than its allowance: a={a} b={b} phi={phi} d={d} v={v}: B(N/2) − B(N) = {:e}",
        bh - bn
    );
    let gap = (got - bn).abs();
    assert!(
        gap + allowance(a, b, n) <= mdr::SPRING_PRECISION * scale,
        "a={a} b={b} phi={phi} d={d} v={v}: solver {got:.15e} brute {bn:.15e} gap {gap:e}"
    );
    gap / scale
}

/// The per-spring solvers against the brute force over random springs:
/// `|solver − B(2²¹)| + allowance ≤ SPRING_PRECISION·(1 + a + b)` for every
/// one (printed: the worst measured gap in units of `1 + a + b`).
#[test]
fn per_spring_solvers_within_spring_precision() {
    const N: u32 = 1 << 21;
    let mut rng = Rng::new(2112);
    let mut worst: f64 = 0.0;
    let mut checked = 0;
    for i in 0..48 {
        let a = if i % 3 == 0 {
            rng.range(0.05, 0.95)
        } else {
            rng.range(0.3, 3.0)
        };
        let b = 10f64.powf(rng.range(-1.0, 0.7));
        let phi = rng.range(-PI, PI);
        let drive = Drive::new::<Libm>(a, b, phi);
        // Offsets: a permanent spring (d in (a, 1]) where there is one, else
        // an intermittent one; near the rim and near the onset too.
        let d = match i % 4 {
            0 if a < 1.0 => rng.range(a, 1.0),
            1 => rng.range(-a, a),
            2 => a * (1.0 - 10f64.powf(rng.range(-6.0, -1.0))),
            _ => -a * (1.0 - 10f64.powf(rng.range(-3.0, -0.5))),
        };
        let (vc, _) = mdr::critical_velocities::<f64, Libm>(&drive, &Profile::Sphere).unwrap();
        let v = rng.range(0.0, 1.0) * vc;
        let got = match mdr::spring_means::<f64, Libm>(&drive, d, v) {
            Ok((s, _)) => s,
            Err(mdr::MdrError::IllConditioned) => continue, // a sliver: counted in U
            Err(e) => panic!("a={a} b={b} phi={phi} d={d} v={v}: {e}"),
        };
        worst = worst.max(check_spring(got, d, (a, b, phi), v, N));
        checked += 1;
    }
    println!(
        "{checked} springs: worst |solver − brute(2^21)|/(1 + a + b) = {worst:.2e}, allowance {:.2e}·(1 + a + b), SPRING_PRECISION {:e}",
        allowance(0.0, 0.0, N),
        mdr::SPRING_PRECISION
    );
    assert!(checked >= 40, "only {checked} springs resolved");
}

/// The springs at rest, `V → 0⁺` (`mdr::spring_means_at_rest`, what
/// `mdr::limits_at_zero` integrates), against the same brute force at
/// `V = 0`. A permanent spring's μ(0⁺) is the limit of the steady states as
/// `V → 0⁺`, each of which has a forward clamp; at `V = 0` the scheme's
/// orbits are not unique, and the brute force picks the one through the
/// forward clamp at the phase where one is certain — the limit orbit (the
/// scheme is 1-Lipschitz in its state and continuous in `V`, so the limit of
/// the clamped orbits is the clamped orbit). It checks its own periodicity
/// (third period against the second, 10⁻¹³) and its convergence in `n`.
/// Required, as for `V > 0`: `|solver − B(2²¹)| + allowance ≤
/// SPRING_PRECISION·(1 + a + b)` — the measurement behind using
/// `SPRING_PRECISION` for the limits at rest too. Springs: permanent (most;
/// `a < 1`), next to the lift-off onset, and intermittent; μ(0⁻) is the same
/// computation on the mirrored drive (`φ → φ + π`), covered by the random `φ`.
#[test]
fn springs_at_rest_within_spring_precision() {
    const N: u32 = 1 << 21;
    let mut rng = Rng::new(2113);
    let mut worst: f64 = 0.0;
    let mut checked = 0;
    for i in 0..32 {
        let a = rng.range(0.05, 0.95);
        let b = 10f64.powf(rng.range(-1.0, 0.7));
        let phi = rng.range(-PI, PI);
        let drive = Drive::new::<Libm>(a, b, phi);
        let d = match i % 4 {
            0 | 1 => rng.range(a, 1.0),
            2 => a * (1.0 + 10f64.powf(rng.range(-6.0, -1.0))),
            _ => rng.range(-a, a),
        };
        let got = match mdr::spring_means_at_rest::<f64, Libm>(&drive, d) {
            Ok((s, _)) => s,
            Err(mdr::MdrError::IllConditioned) => continue,
            Err(e) => panic!("a={a} b={b} phi={phi} d={d}: {e}"),
        };
        worst = worst.max(check_spring(got, d, (a, b, phi), 0.0, N));
        checked += 1;
    }
    println!(
        "{checked} springs at rest: worst |solver − brute(2^21)|/(1 + a + b) = {worst:.2e}, SPRING_PRECISION {:e}",
        mdr::SPRING_PRECISION
    );
    assert!(checked >= 28, "only {checked} springs resolved");
}
