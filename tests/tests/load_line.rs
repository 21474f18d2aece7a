//! The load line and power balance (model-core `load_line`) against an
//! independent fixed-step simulation written here (not model-core's scheme):
//! the paper's explicit update with the work of each force summed step by step.

use std::f64::consts::TAU;

use integration_tests::scene_ratio;
use model_core::exact;
use model_core::model::load_line::{best, best_forward, load_line, powers, Objective, Powers};
use model_core::Libm;

/// Steady-state period of the paper's scheme (stick trial, clamp to ±w) with
/// `n` steps per period at velocity `v`: `(⟨s⟩, P_in, P_fric)` over the last
/// period, after the period-to-period change of ⟨s⟩ falls below 1e-15.
///
/// Work per step (exact for the discrete scheme's energy): the drive's
/// oscillation does ½(s_k + s_trial)·ΔX, the slip dissipates
/// ½(s_trial + s_clamped)·Δx_c. Both converge to the continuous integrals at
/// first order in 1/n (the clamp lags by one step).
fn simulate(a: f64, bc: f64, bs: f64, v: f64, n: u32) -> (f64, f64, f64) {
    let h = TAU / n as f64;
    let x = |t: f64| bc * t.cos() - bs * t.sin();
    let mut s = 1.0 - a; // any start in the band
    let mut last = f64::NAN;
    for _period in 0..200_000 {
        let (mut sum_s, mut p_in, mut p_f) = (0.0, 0.0, 0.0);
        for k in 0..n {
            let t0 = k as f64 * h;
            let t1 = t0 + h;
            let dx = x(t1) - x(t0);
            let trial = s + v * h + dx;
            p_in += 0.5 * (s + trial) * dx;
            let w = 1.0 - a * t1.cos();
            let clamped = trial.clamp(-w, w);
            let slip = trial - clamped;
            p_f += 0.5 * (trial + clamped) * slip;
            s = clamped;
            sum_s += s;
        }
        let mean = sum_s / n as f64;
        if (mean - last).abs() < 1e-15 {
            return (mean, p_in / TAU, p_f / TAU);
        }
        last = mean;
    }
    panic!("no steady state");
}

/// The scenes: the paper's Fig. 4–7 groups (a = 0.5; ratio 0.5, 1, 2) at
/// several phases, plus a large-b single-mode case.
fn scenes() -> Vec<(f64, f64, f64)> {
    let mut v = Vec::new();
    for ratio in [0.5, 1.0, 2.0] {
        for phi_deg in [0.0, 45.0, 90.0, 160.0, 250.0] {
            v.push((0.5, ratio, phi_deg));
        }
    }
    v.push((0.0001, 20000.0, 0.0)); // tangential only, b = 2
    v
}

#[test]
fn energy_balance_holds_to_rounding() {
    // P_in = P_out + P_fric is an identity of the exact steady state; the
    // three are integrated by separate closed forms, so rounding (a few ulps
    // of the O(1 + b) terms times a few arcs) is all that may separate them.
    let mut worst: f64 = 0.0;
    for (a, r, p) in scenes() {
        let s = scene_ratio(a, r, p.to_radians());
        let d = s.drive();
        let c = d.c_forward::<Libm>().max(d.c_backward::<Libm>());
        for i in 1..40 {
            let v = c * (-1.0 + 2.0 * i as f64 / 40.0) * 1.05;
            if v == 0.0 {
                continue;
            }
            let pw = powers::<f64, Libm>(&d, v).unwrap();
            let gap = (pw.input - pw.output - pw.friction).abs() / (1.0 + d.b) / (1.0 + v.abs());
            worst = worst.max(gap);
            assert!(pw.friction >= -1e-12, "friction power {} < 0", pw.friction);
        }
    }
    assert!(worst < 1e-12, "energy balance off by {worst:e}");
}

#[test]
fn powers_match_an_independent_simulation() {
    // Error of the simulation at 2N: the asymptotic part is estimated from N
    // and 2N (first order: err(2N) ≈ |P(N) − P(2N)|, second order: a third of
    // it), allowed 1.5×; the part that does not shrink smoothly (where events
    // fall between grid points) is bounded as model-core's fixed-step bound
    // states it for the same scheme, 10(1+b)/N² in μ/μ₀, and (1+b)² times
    // that for the powers (a force times a velocity, each O(1+b)).
    let n = 20_000;
    let mut checked = 0;
    for (a, r, p) in scenes() {
        let s = scene_ratio(a, r, p.to_radians());
        let d = s.drive();
        for frac in [0.15, 0.5, 0.85, -0.3, -0.7] {
            let c = if frac > 0.0 {
                d.c_forward::<Libm>()
            } else {
                d.c_backward::<Libm>()
            };
            let v = frac * c;
            if v == 0.0 {
                continue;
            }
            let pw = powers::<f64, Libm>(&d, v).unwrap();
            let (m1, i1, f1) = simulate(d.a, d.bc, d.bs, v, n);
            let (m2, i2, f2) = simulate(d.a, d.bc, d.bs, v, 2 * n);
            for (name, exact, coarse, fine) in [
                ("mu", pw.mu_over_mu0, m1, m2),
                ("input", pw.input, i1, i2),
                ("friction", pw.friction, f1, f2),
            ] {
                let grid = 10.0 * (1.0 + d.b) / (2.0 * n as f64).powi(2);
                let grid = if name == "mu" {
                    grid
                } else {
                    grid * (1.0 + d.b)
                };
                let allow = 1.5 * (coarse - fine).abs() + grid + 1e-12;
                assert!(
                    (exact - fine).abs() <= allow,
                    "{name} at a={a} ratio={r} φ={p}° v={v}: exact {exact} sim {fine} (allow {allow:e})"
                );
            }
            checked += 1;
        }
    }
    // 16 scenes × 5 velocities, less the two where c' = 0 (ratio 1, φ = 0:
    // the paper's v_c = 0 case, no stick–slip backward).
    assert_eq!(checked, 78);
}

/// `Powers::efficiency` where the contact brakes the body: documented as
/// `η = P_out/P_in` where the contact delivers power (`P_out > 0`), **else 0**.
/// At Fig. 6's a = 0.5, ratio 2, φ = 0 and V = c/2 (above the no-load
/// velocity) friction opposes the motion, μ > 0, so `P_out = −μV < 0`, while
/// the tangential transducer still puts power in, `P_in > 0`. Both signs are
/// taken from the simulation written here (not from `powers`), each clear of
/// zero by more than its allowance (the one of
/// `powers_match_an_independent_simulation`: 1.5|f_N − f_2N| + 10(1 + b)/(2N)²,
/// times (1 + b) for a power); `powers` must match the simulation within the
/// same allowance, and η must be exactly 0 — the documented value, not the
/// negative ratio `P_out/P_in` (≈ −3.5 here).
#[test]
fn efficiency_is_zero_where_the_contact_brakes() {
    let d = scene_ratio(0.5, 2.0, 0.0).drive();
    let v = 0.5 * d.c_forward::<Libm>();
    let n = 20_000;
    let (m1, i1, _) = simulate(d.a, d.bc, d.bs, v, n);
    let (m2, i2, _) = simulate(d.a, d.bc, d.bs, v, 2 * n);
    let grid = 10.0 * (1.0 + d.b) / (2.0 * f64::from(n)).powi(2);
    let allow_mu = 1.5 * (m1 - m2).abs() + grid + 1e-12;
    let allow_in = 1.5 * (i1 - i2).abs() + grid * (1.0 + d.b) + 1e-12;
    // The state: braking (μ > 0 at V > 0) with power going in.
    assert!(m2 > allow_mu, "μ = {m2} ± {allow_mu:e}: not braking");
    assert!(i2 > allow_in, "P_in = {i2} ± {allow_in:e}: no input");
    let pw = powers::<f64, Libm>(&d, v).unwrap();
    assert!(
        (pw.mu_over_mu0 - m2).abs() <= allow_mu,
        "μ {} vs {m2}",
        pw.mu_over_mu0
    );
    assert!(
        (pw.input - i2).abs() <= allow_in,
        "P_in {} vs {i2}",
        pw.input
    );
    assert!(
        (pw.output + m2 * v).abs() <= allow_mu * v,
        "P_out {} vs {}",
        pw.output,
        -m2 * v
    );
    assert_eq!(pw.efficiency(), 0.0, "η where P_out < 0 < P_in: {pw:?}");
}

#[test]
fn stall_forces_and_no_load_velocities() {
    // Fig. 6's scenes (ratio 2) push; ratio 0.5 at φ = 0 does not (a ratchet).
    let mut pushing = 0;
    for (a, r, p) in scenes() {
        let s = scene_ratio(a, r, p.to_radians());
        let d = s.drive();
        let line = load_line::<f64, Libm>(&d).unwrap();
        let (plus, minus) = exact::limits_at_zero::<f64, Libm>(&d).unwrap();
        assert_eq!(line.stall_forward, (-plus).max(0.0));
        assert_eq!(line.stall_backward, minus.max(0.0));
        if line.stall_forward > 0.0 {
            pushing += 1;
            let v = line.no_load_forward;
            assert!(v > 0.0 && v < d.c_forward::<Libm>());
            // A root of μ: an independent simulation at the returned velocity
            // gives μ ≈ 0 within its discretisation error (estimated from
            // N and 2N as above), and the sign changes 1e-6·v_c either side.
            let (m1, _, _) = simulate(d.a, d.bc, d.bs, v, 20_000);
            let (m2, _, _) = simulate(d.a, d.bc, d.bs, v, 40_000);
            let grid = 10.0 * (1.0 + d.b) / 40_000f64.powi(2);
            assert!(m2.abs() <= 1.5 * (m1 - m2).abs() + grid, "μ(v_nl) = {m2}");
            let c = d.c_forward::<Libm>();
            assert!(exact::mu_over_mu0::<f64, Libm>(&d, v - 1e-6 * c).unwrap() < 0.0);
            assert!(exact::mu_over_mu0::<f64, Libm>(&d, v + 1e-6 * c).unwrap() > 0.0);
        } else {
            assert_eq!(line.no_load_forward, 0.0);
        }
        if line.stall_backward > 0.0 {
            let v = -line.no_load_backward;
            let c = d.c_backward::<Libm>();
            assert!(exact::mu_over_mu0::<f64, Libm>(&d, v + 1e-6 * c).unwrap() > 0.0);
            assert!(exact::mu_over_mu0::<f64, Libm>(&d, v - 1e-6 * c).unwrap() < 0.0);
        }
    }
    // Forward pushers here: ratio 2 at φ = 0° and 45° (Fig. 6), and the
    // nearly single-mode b = 2 scene whose tiny a = 1e-4 breaks the symmetry.
    assert_eq!(pushing, 3);
}

#[test]
fn mirror_symmetry_and_symmetric_law() {
    // φ → φ + π mirrors the law: the forward line of one is the backward line
    // of the other.
    for (a, r, p) in scenes() {
        let d = scene_ratio(a, r, p.to_radians()).drive();
        let m = scene_ratio(a, r, (p + 180.0).to_radians()).drive();
        let l = load_line::<f64, Libm>(&d).unwrap();
        let lm = load_line::<f64, Libm>(&m).unwrap();
        assert!((l.stall_forward - lm.stall_backward).abs() < 1e-12);
        assert!(
            (l.no_load_forward - lm.no_load_backward).abs() <= 1e-9 * (1.0 + l.no_load_forward)
        );
    }
    // Normal-only oscillation: a symmetric law (class I), nothing pushes.
    let d = scene_ratio(0.5, 0.0, 0.0).drive();
    let l = load_line::<f64, Libm>(&d).unwrap();
    assert_eq!((l.stall_forward, l.stall_backward), (0.0, 0.0));
    assert!(best_forward::<f64, Libm>(&d, &l, Objective::Power)
        .unwrap()
        .is_none());
}

/// φ → φ + π (`Drive::mirrored`, an exact sign change of the tangential
/// drive) maps μ(v) to −μ(−v), so the powers at `−v` of the mirror equal
/// those at `v`, and the backward line's operating points of the mirror are
/// the forward line's at `−v`.
///
/// Tolerances: the powers are closed-form sums over a few arcs of O(1 + b)
/// terms, so two evaluations on mirrored arcs differ by rounding, bounded by
/// `δ = 1e-12·(1 + b)(1 + |v|)` (the bound of
/// `energy_balance_holds_to_rounding`). The maximum's *value* is then known
/// to `2δ` (plus the golden section's last bracket, 1e-9·v_nl, times the
/// curvature squared: < 1e-17 here). Its *location* is ill-conditioned: a
/// point whose value is within `ε = 4δ` of the maximum lies within
/// `√(2ε/κ)` of it, `κ = |P''|` there (a second difference with step
/// 1e-3·v_nl; its own error ≤ `4δ/h²`, taken off κ), so the two velocities
/// agree to `2√(2ε/κ)`, and a power `Q` at the points to `|Q'|·Δv + 2δ` (`Q'`
/// by a difference quotient, doubled for its variation over `Δv`).
#[test]
fn mirror_symmetry_of_powers_and_operating_points() {
    let mut points = 0;
    let mut worst_v: f64 = 0.0;
    for (a, r, p) in scenes() {
        let d = scene_ratio(a, r, p.to_radians()).drive();
        let m = d.mirrored();
        let c = d.c_forward::<Libm>().max(d.c_backward::<Libm>());
        for i in 1..20 {
            let v = c * (-1.0 + 2.0 * i as f64 / 20.0) * 1.05;
            if v == 0.0 {
                continue;
            }
            let (x, y) = (
                powers::<f64, Libm>(&d, v).unwrap(),
                powers::<f64, Libm>(&m, -v).unwrap(),
            );
            let delta = 1e-12 * (1.0 + d.b) * (1.0 + v.abs());
            assert!((x.mu_over_mu0 + y.mu_over_mu0).abs() <= delta);
            for (name, p, q) in [
                ("input", x.input, y.input),
                ("output", x.output, y.output),
                ("friction", x.friction, y.friction),
            ] {
                assert!(
                    (p - q).abs() <= delta,
                    "{name} at a={a} ratio={r} φ={p}° v={v}: {p} vs mirror {q}"
                );
            }
        }
        let l = load_line::<f64, Libm>(&d).unwrap();
        let lm = load_line::<f64, Libm>(&m).unwrap();
        for obj in [Objective::Power, Objective::Efficiency] {
            let (o, om) = (
                best::<f64, Libm>(&d, &l, obj).unwrap(),
                best::<f64, Libm>(&m, &lm, obj).unwrap(),
            );
            let (o, om) = match (o, om) {
                (None, None) => continue,
                (Some(o), Some(om)) => (o, om),
                _ => panic!("a={a} ratio={r} φ={p}°: one side has an operating point"),
            };
            assert!(o.v * om.v < 0.0, "the mirror's point is on the other line");
            let vnl = if o.v > 0.0 {
                l.no_load_forward
            } else {
                l.no_load_backward
            };
            let delta = 1e-12 * (1.0 + d.b) * (1.0 + vnl);
            let val = |v: f64| obj.of(&powers::<f64, Libm>(&d, v).unwrap());
            assert!((obj.of(&o.powers) - obj.of(&om.powers)).abs() <= 2.0 * delta + 1e-17);
            // Curvature at the maximum (interior: both neighbours inside the line).
            let h = 1e-3 * vnl;
            let v = o.v;
            let inside = |x: f64| x * v.signum() > 0.0 && x.abs() < vnl;
            let dv = if inside(v - h) && inside(v + h) {
                let kappa = ((val(v + h) - 2.0 * val(v) + val(v - h)) / (h * h)).abs()
                    - 4.0 * delta / (h * h);
                if kappa > 0.0 {
                    2.0 * (2.0 * 4.0 * delta / kappa).sqrt() + 2e-9 * vnl
                } else {
                    // The curvature is not resolved against δ at this step:
                    // both points lie in the optimiser's refined cell, two
                    // scan steps of v_nl/64 wide.
                    2.0 * vnl / 64.0
                }
            } else {
                // A maximum at the line's end (η as v → 0): the optimiser's
                // first scan cell bounds it from both sides.
                vnl / 64.0
            };
            worst_v = worst_v.max((o.v + om.v).abs() / dv);
            assert!(
                (o.v + om.v).abs() <= dv,
                "{obj:?} at a={a} ratio={r} φ={p}°: v {} vs mirror {} (allow {dv:e})",
                o.v,
                om.v
            );
            let slope = |f: fn(&Powers<f64>) -> f64| {
                let hh = (dv).max(1e-6 * vnl).min(0.5 * (vnl - v.abs()).max(1e-12));
                let (lo, hi) = (v - hh, v + hh);
                if inside(lo) && inside(hi) {
                    let q = |x: f64| f(&powers::<f64, Libm>(&d, x).unwrap());
                    2.0 * ((q(hi) - q(lo)) / (2.0 * hh)).abs()
                } else {
                    10.0 * (1.0 + d.b)
                }
            };
            for (name, f) in [
                ("input", (|p| p.input) as fn(&Powers<f64>) -> f64),
                ("friction", |p| p.friction),
                ("force", |p| p.mu_over_mu0),
            ] {
                let gap = if name == "force" {
                    (f(&o.powers) + f(&om.powers)).abs()
                } else {
                    (f(&o.powers) - f(&om.powers)).abs()
                };
                let allow = slope(f) * (o.v + om.v).abs() + 2.0 * delta;
                assert!(
                    gap <= allow,
                    "{obj:?} {name} at a={a} ratio={r} φ={p}°: gap {gap:e} > {allow:e}"
                );
            }
            points += 1;
        }
    }
    println!("mirror: {points} operating points, worst |v + v_mirror| / allowed = {worst_v:.3e}");
    // Pushing scenes here (ratio 2 at 0°, 45°, 160°, 250°; b = 2), two
    // objectives each.
    assert!(points >= 8, "only {points} operating points compared");
}

#[test]
fn best_operating_points_beat_a_dense_scan() {
    for (a, r, p) in [(0.5, 2.0, 0.0), (0.5, 2.0, 45.0), (0.5, 1.0, 160.0)] {
        let d = scene_ratio(a, r, f64::to_radians(p)).drive();
        let l = load_line::<f64, Libm>(&d).unwrap();
        if l.no_load_forward == 0.0 {
            continue;
        }
        for obj in [Objective::Power, Objective::Efficiency] {
            let best = best_forward::<f64, Libm>(&d, &l, obj).unwrap().unwrap();
            let f = |pw: model_core::model::load_line::Powers<f64>| match obj {
                Objective::Power => pw.output,
                Objective::Efficiency => pw.efficiency(),
            };
            // Two-sided: the maximiser is no worse than the scan (less its
            // rounding, 1e-12), and no better than the scan can miss: between
            // grid points h apart the maximum exceeds the best node by at most
            // κh²/8, κ the largest |second difference|/h² over the scan (a kink
            // shows there too). A maximiser in the first cell (a supremum as
            // V → 0⁺, where the slope need not be bounded) is compared with
            // the objective at its own velocity instead (f is evaluated there
            // by the same powers, so only their rounding separates them), and
            // the scan must fall from there: f(h) ≤ got.
            let h = l.no_load_forward / 2000.0;
            let ys: Vec<f64> = (1..2000)
                .map(|i| f(powers::<f64, Libm>(&d, h * i as f64).unwrap()))
                .collect();
            let scan_best = ys.iter().copied().fold(0.0, f64::max);
            let kappa = ys
                .windows(3)
                .map(|w| (w[0] - 2.0 * w[1] + w[2]).abs() / (h * h))
                .fold(0.0, f64::max);
            let got = f(best.powers);
            assert!(got >= scan_best - 1e-12, "{obj:?} {got} < scan {scan_best}");
            if best.v > h {
                let above = kappa * h * h / 8.0 + 1e-12;
                assert!(
                    got <= scan_best + above,
                    "{obj:?} {got} above the scan {scan_best} (+{above:e})"
                );
            } else {
                let at = f(powers::<f64, Libm>(&d, best.v).unwrap());
                assert!((got - at).abs() <= 1e-12, "{obj:?} {got} vs f(v*) {at}");
            }
        }
    }
}

/// The load line of any contact model (`load_line_of`) on the lift-off
/// solver (a ≥ 1): μ at rest is unique, so exactly one stall force is
/// positive (the other side's band edge is the same value with the opposite
/// sign convention) and the no-load velocity is a root of the lift-off law.
/// Tolerance: the root finder brackets to 8ε·c, so |μ(v_nl)| is within the
/// solver's bound (`liftoff::error_bound`) plus the law's slope (≤ 10 per ωW₀
/// on these scenes, checked by a difference quotient) times 8ε·c.
/// The flat law through the same function reproduces `load_line` exactly.
#[test]
fn load_line_of_any_contact() {
    use model_core::model::liftoff;
    use model_core::model::load_line::load_line_of;
    use model_core::Drive;
    let mut checked = 0;
    for &(a, b, phi) in &[(1.5, 0.75, 0.6), (2.0, 1.0, 2.5), (1.2, 3.0, 4.0)] {
        let d = Drive::new::<Libm>(a, b, phi);
        let mu = |v: f64| liftoff::mu_over_mu0::<f64, Libm>(&d, v);
        let m0 = mu(0.0).unwrap();
        let (cf, cb) = liftoff::critical_velocities::<f64, Libm>(&d).unwrap();
        let line = load_line_of(m0, m0, cf, cb, mu).unwrap();
        assert!(
            (line.stall_forward > 0.0) != (line.stall_backward > 0.0) || m0 == 0.0,
            "a={a}: both stall forces positive with a unique μ(0) = {m0}"
        );
        assert_eq!(line.stall_forward, (-m0).max(0.0));
        assert_eq!(line.stall_backward, m0.max(0.0));
        let bound = liftoff::error_bound::<f64, Libm>(&d);
        for (v, c) in [(line.no_load_forward, cf), (-line.no_load_backward, cb)] {
            if v == 0.0 {
                continue;
            }
            let slope = (mu(v + 1e-7).unwrap() - mu(v - 1e-7).unwrap()) / 2e-7;
            assert!(slope.abs() <= 10.0, "slope {slope}");
            let r = mu(v).unwrap();
            assert!(
                r.abs() <= bound + 10.0 * 8.0 * f64::EPSILON * c,
                "a={a}: μ({v}) = {r:e}"
            );
            checked += 1;
        }
    }
    assert!(checked >= 3, "only {checked} no-load roots checked");
    // The flat law through the same function gives the flat load line.
    for (a, ratio, phi_deg) in scenes() {
        let d = Drive::new::<Libm>(a, a * ratio, phi_deg.to_radians());
        let (p, m) = exact::limits_at_zero::<f64, Libm>(&d).unwrap();
        let any = load_line_of(p, m, d.c_forward::<Libm>(), d.c_backward::<Libm>(), |v| {
            exact::mu_over_mu0::<f64, Libm>(&d, v)
        })
        .unwrap();
        assert_eq!(any, load_line::<f64, Libm>(&d).unwrap());
    }
}

/// Independent fixed-step run of a lift-off scene (a ≥ 1) over one period
/// of `n` equal steps from θ = 0 (in the air: w(0) = 1 − a ≤ 0, so s = 0 is
/// the exact state there and one period is the steady state): the paper's
/// stick trial and clamp to the band `[−w⁺, w⁺]`, no contact window, no
/// solver code. Returns `(⟨s⟩/⟨w⁺⟩, P_x, P_fric, P_z/r)` in units of
/// `μ₀F̄z ωW₀` (`F̄z = k_z u_z0⟨w⁺⟩`, `⟨w⁺⟩` by the same trapezoid rule):
/// `P_x = ⟨f_x u̇_x,osc⟩` the drive's work on the trial step, `P_fric` the
/// clamp's, and `⟨w⁺ w'⟩/⟨w⁺⟩`, which times `r = u_z0/(μ₀W₀)` is the normal
/// transducer's `⟨f_z u̇_z⟩` in the same unit.
fn simulate_liftoff(a: f64, bc: f64, bs: f64, v: f64, n: u32) -> (f64, f64, f64, f64) {
    let h = TAU / f64::from(n);
    let x = |t: f64| bc * t.cos() - bs * t.sin();
    let w = |t: f64| 1.0 - a * t.cos();
    let (mut s, mut sum_s, mut sum_w) = (0.0f64, 0.0, 0.0);
    let (mut p_in, mut p_f, mut p_z) = (0.0, 0.0, 0.0);
    for k in 0..n {
        let t0 = f64::from(k) * h;
        let t1 = t0 + h;
        let dx = x(t1) - x(t0);
        let trial = s + v * h + dx;
        p_in += 0.5 * (s + trial) * dx;
        let (w0, w1) = (w(t0), w(t1));
        let band = w1.max(0.0);
        let clamped = trial.clamp(-band, band);
        p_f += 0.5 * (trial + clamped) * (trial - clamped);
        p_z += 0.5 * (w0.max(0.0) + band) * (w1 - w0);
        sum_s += 0.5 * (s + clamped);
        sum_w += 0.5 * (w0.max(0.0) + band);
        s = clamped;
    }
    (
        sum_s / sum_w,
        p_in / (sum_w * h),
        p_f / (sum_w * h),
        p_z / (sum_w * h),
    )
}

/// Lift-off scenes `(a, b, φ)` and velocities as fractions of the window's
/// critical velocities (0 included: μ at rest is unique; ±1.2 slides through).
fn liftoff_cases() -> Vec<(f64, f64, f64, f64)> {
    use model_core::model::liftoff;
    use model_core::Drive;
    let mut out = Vec::new();
    for &(a, b, phi) in &[
        (1.0, 0.8, 0.5),
        (1.5, 0.75, 0.3),
        (2.0, 1.0, 2.5),
        (1.2, 3.0, 4.0),
        (3.5, 0.2, 1.0),
        (1.5, 0.8, std::f64::consts::FRAC_PI_2),
    ] {
        let d = Drive::new::<Libm>(a, b, phi);
        let (cf, cb) = liftoff::critical_velocities::<f64, Libm>(&d).unwrap();
        for frac in [0.0, 0.1, 0.4, 0.8, 1.2, -0.3, -0.7, -1.2] {
            let v = if frac >= 0.0 { frac * cf } else { frac * cb };
            out.push((a, b, phi, v));
        }
    }
    out
}

/// P_in = P_out + P_fric with lift-off: an identity of the window's steady
/// state (`[s²/2]` over the window is 0 because `s = 0` at landing and at
/// lift-off); the three powers come from separate closed forms, so only
/// rounding of the O((1 + a + b)(1 + 2π|V|)) terms over ≤ 9 arcs separates them.
/// Checked to 1e-9 (and reported: the worst gap is ~1e-15).
#[test]
fn liftoff_energy_balance() {
    use model_core::model::load_line::liftoff_powers;
    use model_core::Drive;
    let mut worst: f64 = 0.0;
    for (a, b, phi, v) in liftoff_cases() {
        let d = Drive::new::<Libm>(a, b, phi);
        let pw = liftoff_powers::<f64, Libm>(&d, v).unwrap();
        let gap = (pw.input - pw.output - pw.friction).abs();
        assert!(gap <= 1e-9, "a={a} b={b} φ={phi} v={v}: gap {gap:e}");
        worst = worst.max(gap);
        assert!(pw.friction >= -1e-12, "friction {} < 0", pw.friction);
    }
    println!("lift-off energy balance: worst |P_in − P_out − P_fric| = {worst:e}");
}

/// Each lift-off power against the independent fixed-step run: the
/// transducers' total input `⟨f_x u̇_x⟩ + ⟨f_z u̇_z⟩` (the normal part must
/// vanish), the friction loss and μ. Tolerance, at 2N steps:
/// * the smooth first-order part (the clamp lags one step; measured: the
///   power errors fall by 4.00 per 4× N from 2¹² to 2²⁰), estimated from N
///   and 2N as `|P(N) − P(2N)|`, allowed 1.5×;
/// * the part that does not shrink smoothly: the run lands on the first grid
///   point after the true landing with the drive's motion of that whole step
///   in `s`, an offset `≤ (|V| + b)h` that stick and clamp never enlarge
///   (both 1-Lipschitz), so `≤ (|V| + b)h` in μ (the window's `∫1 ≤ 2π` over
///   `∫w = 2π⟨w⁺⟩ ≥ 2π`) and `(1 + a + b + |V|)` times that in a power (the
///   velocities `V + X' − s'` are ≤ that); plus the trapezoid rule's
///   `10(1 + a + b)/N²` as the lift-off stepping states it;
/// * rounding of the N-term sums, `N·ε·(1 + a + b)²`.
#[test]
fn liftoff_powers_match_an_independent_simulation() {
    use model_core::model::load_line::liftoff_powers;
    use model_core::Drive;
    // r = u_z0/(μ0 W0) = k_x/(μ0² k_z) of the physical scene (8.33): the
    // normal transducer's input in units of μ0 F̄z ωW0 per ⟨w⁺ w'⟩/⟨w⁺⟩.
    let ps = integration_tests::physical_scene();
    let p = ps.params();
    let r = p.kx / (p.mu0 * p.mu0 * p.kz);
    let n = 1u32 << 18;
    let mut worst: [f64; 3] = [0.0; 3];
    let mut worst_richardson: f64 = 0.0;
    for (a, b, phi, v) in liftoff_cases() {
        let d = Drive::new::<Libm>(a, b, phi);
        let pw = liftoff_powers::<f64, Libm>(&d, v).unwrap();
        let (m1, i1, f1, z1) = simulate_liftoff(d.a, d.bc, d.bs, v, n);
        let (m2, i2, f2, z2) = simulate_liftoff(d.a, d.bc, d.bs, v, 2 * n);
        let scale = 1.0 + a + b;
        let nn = 2.0 * f64::from(n);
        let round = nn * f64::EPSILON * scale * scale;
        let h = TAU / nn;
        // The normal transducer's input: 0 exactly; the trapezoid sum of a
        // derivative telescopes except on the two steps that cross w = 0,
        // each off by at most h·max|w'|·max w⁺ over the step, i.e. ≤ 2(a h)²/⟨w⁺⟩.
        assert!(
            (r * z2).abs() <= r * 2.0 * (a * h).powi(2) + r * round,
            "normal input {z2:e} at a={a}"
        );
        let extrapolated = 2.0 * (i2 + r * z2) - (i1 + r * z1);
        worst_richardson = worst_richardson.max((extrapolated - pw.input).abs());
        for (k, (name, exact, coarse, fine)) in [
            ("mu", pw.mu_over_mu0, m1, m2),
            ("input", pw.input, i1 + r * z1, i2 + r * z2),
            ("friction", pw.friction, f1, f2),
        ]
        .into_iter()
        .enumerate()
        {
            let landing = (v.abs() + b) * h * if k == 0 { 1.0 } else { scale + v.abs() };
            let grid = 10.0 * scale / (nn * nn) * if k == 0 { 1.0 } else { scale * scale };
            let grid = grid + landing;
            let allow = 1.5 * (coarse - fine).abs() + grid + round;
            let gap = (exact - fine).abs();
            worst[k] = worst[k].max(gap);
            assert!(
                gap <= allow,
                "{name} at a={a} b={b} φ={phi} v={v}: closed form {exact} sim {fine} (gap {gap:e}, allow {allow:e})"
            );
        }
    }
    println!(
        "lift-off powers vs fixed step at N = 2^19: worst gap μ {:e}, P_in {:e}, P_fric {:e}",
        worst[0], worst[1], worst[2]
    );
    println!("  P_in Richardson-extrapolated from 2^18, 2^19: worst gap {worst_richardson:e}");
}

/// One MDR spring of band offset `dd`, fixed-step, the paper's clamp to
/// `[−w⁺, w⁺]`: `(∫s X'dθ, ∫s u̇_c dθ, ∫s dθ)/2π` (per unit phase;
/// trapezoid work sums as `simulate_liftoff`). With lift-off (`|dd| ≤ a`)
/// one period from θ = 0, in the air (`w(0) = dd − a ≤ 0`); in permanent
/// contact periods until ⟨s⟩ settles.
fn simulate_spring(dd: f64, a: f64, bc: f64, bs: f64, v: f64, n: u32) -> [f64; 3] {
    if dd > a {
        // Permanent contact: periods until ⟨s⟩ settles (as `simulate`).
        let (mut s, mut last) = (0.0f64, f64::NAN);
        for _ in 0..100_000 {
            let (out, s_end) = spring_period(dd, a, bc, bs, v, n, s);
            s = s_end;
            if (out[2] - last).abs() < 1e-15 {
                return out;
            }
            last = out[2];
        }
        panic!("no steady state");
    }
    spring_period(dd, a, bc, bs, v, n, 0.0).0
}

/// One period of [`simulate_spring`] from the stretch `s0` at θ = 0.
fn spring_period(dd: f64, a: f64, bc: f64, bs: f64, v: f64, n: u32, s0: f64) -> ([f64; 3], f64) {
    let h = TAU / f64::from(n);
    let x = |t: f64| bc * t.cos() - bs * t.sin();
    let mut s = s0;
    let (mut p_in, mut p_f, mut sum_s) = (0.0, 0.0, 0.0);
    for k in 0..n {
        let t0 = f64::from(k) * h;
        let t1 = t0 + h;
        let dx = x(t1) - x(t0);
        let trial = s + v * h + dx;
        p_in += 0.5 * (s + trial) * dx;
        let band = (dd - a * t1.cos()).max(0.0);
        let clamped = trial.clamp(-band, band);
        p_f += 0.5 * (trial + clamped) * (trial - clamped);
        sum_s += 0.5 * (s + clamped) * h;
        s = clamped;
    }
    ([p_in / TAU, p_f / TAU, sum_s / TAU], s)
}

/// A bed of `m` springs of the profile ξⁿ at a ≥ 1 (all lift off), each
/// simulated with `steps` per period; midpoints in ξ over [0, ξ_max]; D by
/// the same midpoints with each spring's ⟨w⁺⟩ on the same grid.
/// Returns `(μ, P_in, P_fric)` in units of μ₀F̄z ωW₀.
fn bed_brute_force(n: f64, a: f64, bc: f64, bs: f64, v: f64, m: u32, steps: u32) -> [f64; 3] {
    let xi_max = (1.0 + a).powf(1.0 / n);
    let hx = xi_max / f64::from(m);
    let (mut tot, mut den) = ([0.0; 3], 0.0);
    for i in 0..m {
        let dd = 1.0 - ((f64::from(i) + 0.5) * hx).powf(n);
        let w = simulate_spring(dd, a, bc, bs, v, steps);
        for k in 0..3 {
            tot[k] += w[k] * hx;
        }
        let ht = TAU / f64::from(steps);
        let band: f64 = (0..steps)
            .map(|j| (dd - a * ((f64::from(j) + 0.5) * ht).cos()).max(0.0))
            .sum::<f64>()
            / f64::from(steps);
        den += band * hx;
    }
    [tot[2] / den, tot[0] / den, tot[1] / den]
}

/// Curved profiles (`mdr::powers::profile_powers`): the bed's balance
/// P_in = P_out + P_fric (each spring balances exactly; the three totals
/// come from one quadrature, so they may differ by the stated bound of each,
/// and P_out = −μV by |V| times μ's), μ against the MDR's own μ quadrature
/// (`mdr::mu_over_mu0`, which also searches the kinks) within both bounds;
/// and against a brute force over springs written here (springs that lift
/// off: one period each from the air; permanent ones: periods until
/// steady): 200 springs × 2¹² steps and 400 × 2¹³, accepted within 1.5×
/// that change (both the ξ midpoints and the per-spring runs converge at
/// order ≥ 1) plus each spring's landing offset bound `(|V| + b)h` times
/// `(1 + a + b + |V|)` (as `liftoff_powers_match_an_independent_simulation`),
/// weighted `ξ_max/D`, plus the fixed-step bound `10(1 + a + b)/N²` times
/// `(1 + a + b + |V|)` for the permanent springs, and the profile's bound.
#[test]
fn profile_powers_balance_and_brute_force() {
    use model_core::mdr::powers::profile_powers;
    use model_core::mdr::{self, Profile};
    use model_core::Drive;
    let mut worst: f64 = 0.0;
    for p in [Profile::Sphere, Profile::Cone] {
        for &(a, b, phi) in &[(0.5, 1.0, 0.7), (1.5, 0.75, 0.35)] {
            let d = Drive::new::<Libm>(a, b, phi);
            let (cf, cb) = mdr::critical_velocities::<f64, Libm>(&d, &p).unwrap();
            for frac in [0.1, 0.5, -0.4, 1.1] {
                let v = if frac > 0.0 { frac * cf } else { frac * cb };
                let r = profile_powers::<f64, Libm>(&d, &p, v, 1e-6).unwrap();
                let pw = r.powers;
                let gap = (pw.input - pw.output - pw.friction).abs();
                worst = worst.max(gap);
                assert!(
                    gap <= (2.0 + v.abs()) * r.bound,
                    "{p:?} a={a} v={v}: balance gap {gap:e}, bound {:e}",
                    r.bound
                );
                // Balance to 1e-9: the three totals share one subdivision
                // and nodes, and each spring balances in closed form, so the
                // sums balance to rounding whatever the quadrature's error.
                assert!(gap <= 1e-9, "{p:?} a={a} v={v}: balance gap {gap:e}");
                assert!(pw.friction >= -r.bound);
                let m = mdr::mu_over_mu0::<f64, Libm>(&d, &p, v, 1e-6).unwrap();
                assert!(
                    (m.mu_over_mu0 - pw.mu_over_mu0).abs() <= m.bound + r.bound,
                    "{p:?} a={a} v={v}: μ {} vs MDR {}",
                    pw.mu_over_mu0,
                    m.mu_over_mu0
                );
                if frac.abs() < 1.0 {
                    let nexp = p.exponent().unwrap();
                    let c = bed_brute_force(nexp, a, d.bc, d.bs, v, 200, 1 << 12);
                    let f = bed_brute_force(nexp, a, d.bc, d.bs, v, 400, 1 << 13);
                    let h = TAU / f64::from(1u32 << 13);
                    let xi_max = (1.0 + a).powf(1.0 / nexp);
                    let nn = f64::from(1u32 << 13);
                    let landing = ((v.abs() + b) * h + 10.0 * (1.0 + a + b) / (nn * nn))
                        * (1.0 + a + b + v.abs())
                        * xi_max
                        / r.mean_normal;
                    for (k, exact) in [pw.mu_over_mu0, pw.input, pw.friction].iter().enumerate() {
                        let allow = 1.5 * (c[k] - f[k]).abs() + landing + r.bound;
                        assert!(
                            (exact - f[k]).abs() <= allow,
                            "{p:?} a={a} v={v} [{k}]: {exact} vs brute force {} (allow {allow:e})",
                            f[k]
                        );
                    }
                    println!(
                        "{p:?} a={a} v={v:.3}: gaps μ {:.1e} P_in {:.1e} P_fric {:.1e}",
                        (pw.mu_over_mu0 - f[0]).abs(),
                        (pw.input - f[1]).abs(),
                        (pw.friction - f[2]).abs()
                    );
                }
            }
        }
    }
    println!("profile powers: worst balance gap {worst:e}");
}

/// `best_of` over a law that pushes both ways (a synthetic contact, as
/// `best_of` takes any law's powers): `μ = −s_f(1 − V/v_f)` on
/// `(0, v_f)` and `μ = s_b(1 + V/v_b)` on `(−v_b, 0)`, so
/// `P_out = −μV` peaks in closed form at `V = v_f/2`, `s_f·v_f/4` forward
/// and at `V = −v_b/2`, `s_b·v_b/4` backward; friction 1 makes
/// `η = P/(P + 1)`, with the same maximiser. The better side's peak is
/// returned (velocity within 1e-6 of the closed form: the maximiser's
/// bracket of a smooth peak is ~√ε wide; power within 1e-12), and with
/// both sides equal (the same law mirrored: bit-identical searches) the
/// forward one, as documented.
#[test]
fn the_best_of_both_lines_is_the_better_sides_peak() {
    use model_core::model::load_line::{best_of, LoadLine};
    let law = |(sf, vf, sb, vb): (f64, f64, f64, f64)| {
        move |v: f64| -> Result<Powers<f64>, ()> {
            let mu = if v > 0.0 {
                -sf * (1.0 - v / vf)
            } else {
                sb * (1.0 + v / vb)
            };
            let output = -mu * v;
            Ok(Powers {
                mu_over_mu0: mu,
                input: output + 1.0,
                output,
                friction: 1.0,
            })
        }
    };
    // (s_f, v_f, s_b, v_b) and the expected peak's velocity and power.
    for (c, want_v, want_p) in [
        ((1.0, 1.0, 2.0, 1.0), -0.5, 0.5),
        ((2.0, 1.5, 1.0, 2.0), 0.75, 0.75),
        ((1.0, 0.8, 3.0, 0.2), 0.4, 0.2),
        ((1.0, 1.0, 1.0, 1.0), 0.5, 0.25),
    ] {
        let line = LoadLine {
            stall_forward: c.0,
            stall_backward: c.2,
            no_load_forward: c.1,
            no_load_backward: c.3,
        };
        for obj in [Objective::Power, Objective::Efficiency] {
            let got = best_of(&line, obj, law(c)).unwrap().unwrap();
            assert!(
                (got.v - want_v).abs() <= 1e-6,
                "{c:?} {obj:?}: V = {} (want {want_v})",
                got.v
            );
            assert!(
                (got.powers.output - want_p).abs() <= 1e-12,
                "{c:?} {obj:?}: P = {} (want {want_p})",
                got.powers.output
            );
        }
    }
}
