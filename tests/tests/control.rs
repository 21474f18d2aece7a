//! The closed loop (`board::control`) on a plant that is not its model:
//! the exact law with the true μ₀ 20 % off the model's, sampled once per
//! update with a one-update dead time (the update at `k` sees the command of
//! update `k − 1`), as the device runs it.
//!
//! **The bound the settling is checked against.** With the command
//! `u_{k+1} = u_k + κ·e_k/(ρ̂_k·s)` (eq. C1 with the learned gain, no rate or
//! bound active) and the plant `μ_k = μ_p(u_k)`, the mean value theorem gives
//! exactly `e_{k+1} = (1 − κ·ρ(ξ_k)/ρ̂_k)·e_k` with `ρ = s_p(ξ)/s`, the
//! plant's slope at some `ξ_k` between `u_k` and `u_{k+1}` over the model's
//! `s`. ρ̂ (C6) is a weighted mean of its start, 1, and of secants of the
//! plant, each (mean value theorem again, before the clamp of C5) a value
//! of ρ on the interval the iterates visit: ρ̂ lies between
//! `min(1, ρ_lo)` and `max(1, ρ_hi)`. If `κ·ρ_hi/min(1, ρ_lo) ≤ 1` the
//! iterates stay in the interval between the start and the solution and
//! `|e_k| ≤ q^k·|e_0|`, `q = 1 − κ·ρ_lo/max(1, ρ_hi)`. `ρ` is bounded here
//! by the plant's finite differences on a fine grid of that interval
//! (independent of the controller), widened by 5 % for the grid.

use board::control::{self, Controller, Gains, Plan};
use model_core::exact;
use model_core::{Libm, Scene, SceneParams};

/// The bench's drive: 40 kHz, u_z0 = 4 µm, Δu_x = 0.3 µm, φ = 40°, k = 10⁷ N/m.
fn scene<T: model_core::Float>(mu0: f64, duz: f64) -> Scene<T> {
    let f = T::from_f64;
    Scene::new(SceneParams {
        mu0: f(mu0),
        kz: f(1e7),
        kx: f(1e7),
        uz0: f(4e-6),
        duz: f(duz),
        dux: f(0.3e-6),
        omega: f(std::f64::consts::TAU * 40e3),
        phi: f(40f64.to_radians()),
    })
    .expect("valid scene")
}

const V0: f64 = 0.004;
const MODEL_MU0: f64 = 0.3;
const LIMIT: f64 = 0.95 * 4e-6;

/// The plant's μ at Δu_z = `u` (exact law, f64).
fn plant(mu0: f64, u: f64) -> f64 {
    let s = scene::<f64>(mu0, u);
    let v = s.dimensionless_velocity(V0).unwrap();
    mu0 * exact::mu_over_mu0::<f64, Libm>(&s.drive(), v).unwrap()
}

fn plan(target: f64, near: f64) -> Plan {
    control::plan(
        &scene::<f32>(MODEL_MU0, 0.0),
        target as f32,
        V0 as f32,
        near as f32,
        LIMIT as f32,
    )
    .expect("reachable")
}

/// Runs `n` updates from command `u0`; returns (commands, measured μ).
fn run(ctl: &mut Controller, mu0: f64, n: usize, dt: f32) -> (Vec<f64>, Vec<f64>) {
    let (mut us, mut mus) = (Vec::new(), Vec::new());
    let mut u = f64::from(ctl.output().command_m);
    for _ in 0..n {
        let mu = plant(mu0, u);
        u = f64::from(ctl.update(mu as f32, dt).command_m);
        us.push(u);
        mus.push(mu);
    }
    (us, mus)
}

/// Bounds of ρ = s_p/s on [a, b] from 200 finite differences, widened 5 %.
fn rho_range(mu0: f64, a: f64, b: f64, s: f64) -> (f64, f64) {
    let (lo, hi) = (a.min(b), a.max(b));
    let n = 200;
    let (mut rmin, mut rmax) = (f64::MAX, f64::MIN);
    for i in 0..n {
        let x0 = lo + (hi - lo) * i as f64 / n as f64;
        let x1 = lo + (hi - lo) * (i + 1) as f64 / n as f64;
        let r = (plant(mu0, x1) - plant(mu0, x0)) / (x1 - x0) / s;
        rmin = rmin.min(r);
        rmax = rmax.max(r);
    }
    (rmin / 1.05, rmax * 1.05)
}

#[test]
fn settles_within_the_derived_bound_with_20_percent_mismatch() {
    for (mu0_plant, target, u_start) in [(0.24, 0.10, 2.0e-6), (0.36, 0.13, 1.0e-6)] {
        let p = plan(target, u_start);
        let kappa = 0.7f32;
        let gains = Gains {
            kappa,
            rate_m_per_s: 1.0, // no rate limit in this test
        };
        let mut ctl = Controller::new(p, gains, u_start as f32);
        let (us, mus) = run(&mut ctl, mu0_plant, 40, 1e-3);
        // The plant's solution, by bisection on the monotone law (independent of the loop).
        let (mut a, mut b) = (0.0, LIMIT);
        for _ in 0..60 {
            let m = 0.5 * (a + b);
            if plant(mu0_plant, m) > target {
                a = m;
            } else {
                b = m;
            }
        }
        let u_star = 0.5 * (a + b);
        let (rlo, rhi) = rho_range(mu0_plant, u_start, u_star, f64::from(p.slope_per_m));
        let k = f64::from(kappa);
        assert!(
            rlo > 0.0 && k * rhi / rlo.min(1.0) <= 1.0,
            "monotone regime: ρ in [{rlo}, {rhi}]"
        );
        let q = 1.0 - k * rlo / rhi.max(1.0);
        let learned = f64::from(ctl.plant_gain());
        assert!(
            (rlo.min(1.0)..=rhi.max(1.0)).contains(&learned),
            "ρ̂ {learned} outside [min(1, {rlo}), max(1, {rhi})]"
        );
        let e0 = (mus[0] - target).abs();
        // Updates until q^k·e0 ≤ 2 % of the target; +1 for the dead time (the
        // first measurement is of the starting command), +1 for f32 rounding.
        let bound = ((0.02 * target / e0).ln() / q.ln()).ceil() as usize + 2;
        let settled = mus
            .iter()
            .position(|m| (m - target).abs() <= 0.02 * target)
            .expect("settles");
        assert!(
            settled <= bound,
            "mu0 {mu0_plant}: settled after {settled} updates, bound {bound} (ρ in [{rlo:.3}, {rhi:.3}])"
        );
        // And it stays: monotone contraction, no overshoot past the target
        // (κρ ≤ 1 ⇒ every error has the sign of the first), up to the f32
        // resolution of the command (1e-13 m · |s_p| ≪ 1e-6).
        let sign = (mus[0] - target).signum();
        for m in &mus {
            assert!((m - target) * sign >= -1e-6, "overshoot: {m} vs {target}");
        }
        // Steady state: the f32 command's resolution (ulp of 2 µm ≈ 2.3e-13 m)
        // times |s_p| ≲ 1e5 /m: below 1e-6 after 40 updates (q^40 ≈ 0).
        assert!(
            (mus[39] - target).abs() < 1e-6,
            "steady error {}",
            mus[39] - target
        );
        assert!(us.iter().all(|&u| (0.0..=LIMIT).contains(&u)));
    }
}

#[test]
fn never_commands_above_the_liftoff_limit_and_does_not_wind_up() {
    // A plant with μ0 20 % above the model reaches only μ = −0.0308 at the
    // lift-off limit (the model −0.0343; `fricctl mu … --duz 3.8e-6`): the
    // target −0.033 needs more Δu_z than allowed, the command saturates.
    let (mu0_plant, target) = (0.36, -0.033);
    let reach = plant(mu0_plant, LIMIT);
    assert!(reach > target, "unreachable for the plant: {reach}");
    let p = plan(target, 3e-6);
    let gains = Gains {
        kappa: 0.7,
        rate_m_per_s: 1.0,
    };
    let mut ctl = Controller::new(p, gains, 3e-6);
    let (us, _) = run(&mut ctl, mu0_plant, 50, 1e-3);
    let limit = f64::from(p.limit_m);
    for u in &us {
        assert!(*u <= limit, "command {u} above the limit {limit}");
    }
    let o = ctl.output();
    assert_eq!(f64::from(o.command_m), limit, "held at the limit");
    assert!(o.saturated);
    // Back-calculation: the trim holds exactly the bound, nothing beyond
    // (C4), however long the saturation lasted.
    assert_eq!(o.integral_m, p.limit_m - p.feedforward_m);
    // Recovery: a reachable target afterwards settles as fast as from a fresh
    // start at the limit (no wound-up trim to unwind first).
    let p2 = plan(0.10, 3e-6);
    ctl.retarget(p2, gains, 1.0);
    let mut fresh = Controller::new(p2, gains, 0.0);
    fresh.retarget(p2, gains, 1.0); // same trim-free start: command = u_ff
    let (_, a) = run(&mut ctl, mu0_plant, 30, 1e-3);
    let (_, b) = run(&mut fresh, mu0_plant, 30, 1e-3);
    let within = |m: &[f64]| m.iter().position(|x| (x - 0.10).abs() <= 0.002).unwrap();
    assert!(
        within(&a) <= within(&b) + 1,
        "after saturation {} updates, fresh {}",
        within(&a),
        within(&b)
    );
}

#[test]
fn rate_limit_bounds_every_step() {
    let p = plan(0.13, 2e-6);
    let (rate, dt) = (1e-3f32, 0.512e-3f32);
    let gains = Gains {
        kappa: 0.7,
        rate_m_per_s: rate,
    };
    let mut ctl = Controller::new(p, gains, 3.0e-6);
    let mut prev = 3.0e-6f64;
    for _ in 0..20 {
        let u = f64::from(ctl.output().command_m);
        let mu = plant(0.24, u);
        let out = ctl.update(mu as f32, dt);
        let step = (f64::from(out.command_m) - prev).abs();
        // r·dt = 5.12e-7 m, plus the f32 rounding of the clamp (ulp(3e-6) ≈ 4e-13).
        assert!(step <= f64::from(rate * dt) + 1e-12, "step {step}");
        prev = f64::from(out.command_m);
    }
}

#[test]
fn switching_is_bumpless() {
    let p = plan(0.10, 2e-6);
    let gains = Gains {
        kappa: 0.7,
        rate_m_per_s: 1e-3,
    };
    // On: the first command is exactly the amplitude applied now.
    for now in [0.0f32, 1.234e-6, 2e-6, 3.7e-6] {
        let ctl = Controller::new(p, gains, now);
        assert_eq!(ctl.output().command_m, now);
        assert_eq!(ctl.output().integral_m, now - p.feedforward_m);
    }
    // A setpoint change keeps the learned trim and gain: the command moves
    // from u_ff + I by the model's step over ρ̂ (C7).
    let mut ctl = Controller::new(p, gains, 2e-6);
    let _ = run(&mut ctl, 0.24, 30, 0.5e-3);
    let (trim, rho) = (ctl.output().integral_m, ctl.plant_gain());
    let before = ctl.output().command_m;
    assert_eq!(before, p.feedforward_m + trim);
    let p2 = plan(0.12, 1.2e-6);
    let out = ctl.retarget(p2, gains, 1.0);
    let want = f64::from(before) + f64::from(p2.feedforward_m - p.feedforward_m) / f64::from(rho);
    // f32 arithmetic of C7: a few ulps of 2 µm.
    assert!(
        (f64::from(out.command_m) - want).abs() <= 1e-12,
        "{} vs {want}",
        out.command_m
    );
    assert_eq!(ctl.plant_gain(), rho, "a retarget learns nothing");
}

/// The plant's μ0 20 % below the model's: ρ ≈ 0.6…0.8 on the way. A large
/// step teaches the loop the plant's gain (C5–C6).
///
/// **What ρ̂ may be.** Within one plan a secant is `Δμ_p/(s·Δu)`, by the mean
/// value theorem a value of ρ = s_p/s on the interval visited, in
/// `[ρ_lo, ρ_hi]` (the plant's finite differences, as above). C5's cap keeps a
/// secant between ρ̂ and itself, and C6 moves ρ̂ towards it, so ρ̂ stays in the
/// hull of its start and the secants. While the cap is not active (checked:
/// `ρ_lo ≥ max(1, ρ_hi)/2`, `ρ_hi ≤ 2·min(1, ρ_lo)`) C6 is exactly the weighted
/// mean of the prior 1 (weight λᵏP₀, `P₀ = (0.01·μ₀)²`) and the secants (their
/// Δ²): the prior's share is at most `P₀/Δ₁²` with Δ₁ the first secant's.
/// So ρ̂ is within `[ρ_lo, ρ_hi]` widened by `P₀/Δ₁²·max|1 − ρ|`.
///
/// **The next setpoint.** The pair across the retarget has its ends on the
/// two plans (C5: `m = μ* + s·(u − u_ff)` on each), its secant `r_x` computed
/// here from the plant; the later pairs lie on the new plan, in `[ρ'_lo, ρ'_hi]`
/// over the commands visited. ρ̂ stays in the hull of its value at the
/// retarget, `r_x` and that range, and the error falls by at least
/// `q = max |1 − κρ/ρ̂|` per update over ρ and ρ̂ in those ranges.
#[test]
fn learns_the_plant_gain_and_then_settles_at_its_rate() {
    let mu0_plant = 0.24;
    let gains = Gains {
        kappa: 0.95,
        rate_m_per_s: 1.0,
    };
    let k = f64::from(gains.kappa);
    // From 3 µm (μ ≈ 0.03) to μ* = 0.10: a step of ≈ 0.07.
    let p = plan(0.10, 3e-6);
    let mut ctl = Controller::new(p, gains, 3e-6);
    let (us, _) = run(&mut ctl, mu0_plant, 20, 1e-3);
    let s = f64::from(p.slope_per_m);
    let (umin, umax) = (
        us.iter().copied().fold(3e-6, f64::min),
        us.iter().copied().fold(3e-6, f64::max),
    );
    let (rlo, rhi) = rho_range(mu0_plant, umin, umax, s);
    assert!(rlo >= rhi.max(1.0) / 2.0 && rhi <= 2.0 * rlo.min(1.0));
    let d1 = (s * (us[0] - 3e-6)).abs();
    let p0 = (0.01 * MODEL_MU0).powi(2);
    assert!(d1 * d1 > p0, "first secant Δ {d1}");
    let slack = p0 / (d1 * d1) * (1.0 - rlo).abs().max((1.0 - rhi).abs());
    let rho = f64::from(ctl.plant_gain());
    assert!(
        rho >= rlo - slack && rho <= rhi + slack,
        "ρ̂ {rho} outside [{rlo}, {rhi}] ± {slack}"
    );
    // It learned: the whole allowed range is below 0.9 (ρ̂ started at 1).
    assert!(rhi + slack < 0.9, "[{rlo}, {rhi}] ± {slack}");
    // The next step, 0.10 → 0.12, with the learned gain. The last pair of
    // the first plan: the command measured last (us[18]) and its μ.
    let u_last = us[18];
    let m_last = f64::from(p.target_mu) + s * (u_last - f64::from(p.feedforward_m));
    let p2 = plan(0.12, 1.5e-6);
    let s2 = f64::from(p2.slope_per_m);
    let u_r = f64::from(ctl.retarget(p2, gains, 1.0).command_m);
    let rho = f64::from(ctl.plant_gain());
    let m_r = f64::from(p2.target_mu) + s2 * (u_r - f64::from(p2.feedforward_m));
    let r_x = (plant(mu0_plant, u_r) - plant(mu0_plant, u_last)) / (m_r - m_last);
    let (us2, mus) = run(&mut ctl, mu0_plant, 12, 1e-3);
    let (a, b) = (
        us2.iter().copied().fold(u_r, f64::min),
        us2.iter().copied().fold(u_r, f64::max),
    );
    let (rlo, rhi) = rho_range(mu0_plant, a, b, s2);
    let (hlo, hhi) = (rho.min(rlo).min(r_x), rho.max(rhi).max(r_x));
    let learned = f64::from(ctl.plant_gain());
    assert!(
        (hlo..=hhi).contains(&learned),
        "ρ̂ {learned} outside [{hlo}, {hhi}]"
    );
    let q = (1.0 - k * rlo / hhi).abs().max((1.0 - k * rhi / hlo).abs());
    // The bound below is only worth checking if it is a real contraction.
    assert!(q < 0.5, "q {q} (ρ in [{rlo}, {rhi}], ρ̂ in [{hlo}, {hhi}])");
    let e0 = (mus[0] - 0.12).abs();
    let settled = mus
        .iter()
        .position(|m| (m - 0.12).abs() <= 0.02 * 0.02)
        .expect("settles");
    // Updates until q^k·e0 ≤ 2 % of the step (0.02), +1 for the first
    // measurement (of the retarget's command), +1 for f32 rounding.
    let bound = if e0 <= 0.0004 {
        1
    } else {
        ((0.0004 / e0).ln() / q.ln()).ceil() as usize + 2
    };
    assert!(
        settled <= bound,
        "settled after {settled} updates, bound {bound} (q {q:.3}, e0 {e0:.2e})"
    );
}

/// A step of the plant's μ0 caught half-way by a window is not taken for
/// gain (C5): the pair from the last steady estimate to the half-way one has
/// no command change but a change of μ̂ beyond the learned response, so the
/// pair after it is not learned from. Taken, its secant would be
/// `ρ − (1 − f)·d/Δ` with `f` the share of the step the first window saw, `d`
/// the step and Δ the model's change of μ over the correction: far from the
/// plant's ρ. So ρ̂ is exactly (bitwise) unchanged over both pairs, and after
/// them stays within the hull of the two plants' slopes over the commands
/// visited.
#[test]
fn a_disturbance_is_not_learned_as_gain() {
    let gains = Gains {
        kappa: 0.95,
        rate_m_per_s: 1.0,
    };
    let p = plan(0.10, 2e-6);
    let mut ctl = Controller::new(p, gains, 2e-6);
    let (us, _) = run(&mut ctl, 0.24, 30, 1e-3);
    let s = f64::from(p.slope_per_m);
    // μ0 0.24 → 0.216 (× 0.9); the first window after it sees half.
    let mut u = *us.last().unwrap();
    let before = ctl.plant_gain();
    let half = 0.5 * (plant(0.24, u) + plant(0.216, u));
    u = f64::from(ctl.update(half as f32, 1e-3).command_m);
    assert_eq!(ctl.plant_gain(), before, "learned from the half-way pair");
    // The next estimate sees the whole step and the correction: not learned.
    u = f64::from(ctl.update(plant(0.216, u) as f32, 1e-3).command_m);
    assert_eq!(ctl.plant_gain(), before, "learned from the disturbed pair");
    let (us2, _) = run(&mut ctl, 0.216, 20, 1e-3);
    let lo = us2.iter().chain(&us).copied().fold(u.min(2e-6), f64::min);
    let hi = us2.iter().chain(&us).copied().fold(u.max(2e-6), f64::max);
    let (a_lo, a_hi) = rho_range(0.24, lo, hi, s);
    let (b_lo, b_hi) = rho_range(0.216, lo, hi, s);
    let rho = f64::from(ctl.plant_gain());
    let (hlo, hhi) = (a_lo.min(b_lo).min(1.0), a_hi.max(b_hi).max(1.0));
    assert!((hlo..=hhi).contains(&rho), "ρ̂ {rho} outside [{hlo}, {hhi}]");
    // And the loop is back at the target within 2 %.
    let m = plant(0.216, f64::from(ctl.output().command_m));
    assert!((m - 0.10).abs() <= 0.002, "μ {m}");
}

/// C5's cap on a secant, `clamp(r, max(RHO_MIN, ρ̂/2), min(RHO_MAX, 2ρ̂))`,
/// and C6's update, on a hand-made plan (s = −2.5·10⁴ /m, u_ff = 2 µm,
/// μ* = 0.1, μ₀ = 0.3) fed measurements chosen so that each secant lies
/// beyond a cap: r = 3 from ρ̂ = 1 (cut to 2ρ̂ = 2), then r = 10 from
/// ρ̂ ≈ 2 (cut to 2ρ̂ ≈ 4, inside RHO_MAX), then r = 0.1 (cut to ρ̂/2, above
/// RHO_MIN). ρ̂ after each pair against C5–C6 written out in f64 from the
/// commands in force (C5's `m = μ* + s·(u − u_ff)`); f32 arithmetic: 1e-5
/// relative.
#[test]
fn each_secant_is_capped_at_twice_and_half_the_learned_gain() {
    let p = Plan {
        target_mu: 0.1,
        feedforward_m: 2e-6,
        slope_per_m: -2.5e4,
        limit_m: LIMIT as f32,
        mu0: 0.3,
    };
    let gains = Gains {
        kappa: 0.5,
        rate_m_per_s: 1.0,
    };
    let mut ctl = Controller::new(p, gains, 1e-6);
    let s = f64::from(p.slope_per_m);
    let model = |u: f64| f64::from(p.target_mu) + s * (u - f64::from(p.feedforward_m));
    let p0 = (f64::from(control::LEARN_MIN_REL) * 0.3).powi(2);
    let forget = f64::from(control::FORGET);
    // The first update only records its pair.
    let mut last = (model(f64::from(ctl.output().command_m)), f64::from(0.15f32));
    ctl.update(0.15, 1e-3);
    assert_eq!(ctl.plant_gain(), 1.0);
    let (mut rho, mut weight) = (1.0f64, p0);
    // Each secant r, and which cap must cut it (true: the upper one).
    for (r, upper) in [(3.0, true), (10.0, true), (0.1, false)] {
        let m = model(f64::from(ctl.output().command_m));
        let d = m - last.0;
        assert!(d.abs() >= 0.003, "Δ {d} too small to learn from");
        let mu = f64::from((last.1 + r * d) as f32);
        let r = (mu - last.1) / d;
        let (lo, hi) = (
            f64::from(control::RHO_MIN).max(0.5 * rho),
            f64::from(control::RHO_MAX).min(2.0 * rho),
        );
        if upper {
            assert!(
                r > hi && hi < f64::from(control::RHO_MAX),
                "r {r}, cap {hi}"
            );
        } else {
            assert!(
                r < lo && lo > f64::from(control::RHO_MIN),
                "r {r}, cap {lo}"
            );
        }
        let rk = r.clamp(lo, hi);
        weight = forget * weight + d * d;
        rho += d * d / weight * (rk - rho);
        ctl.update(mu as f32, 1e-3);
        let got = f64::from(ctl.plant_gain());
        assert!(
            (got - rho).abs() <= 1e-5 * rho,
            "secant {r}: ρ̂ {got}, C5–C6 give {rho}"
        );
        last = (m, mu);
    }
}

/// The least gain (C5's `|s| ≥ S_MIN_REL·μ₀/u_z0`) where the law is flat:
/// sliding at v₀ = 1 m/s against a tangential vibration of 0.01 µm at
/// 40 kHz (2.5 mm/s) never reverses, so μ = μ₀ at every Δu_z (the exact law
/// in f64 says so to 1e-12 on the range; the plan's reach is `[μ₀, μ₀]`).
/// The central difference is then 0, and the plan must carry the floor
/// 0.05·0.3/4 µm = 3 750 /m (positive: the sign of a zero slope), never 0.
#[test]
fn a_flat_law_gets_the_least_gain_not_zero() {
    let params = |duz: f64| SceneParams {
        mu0: 0.3,
        kz: 1e7,
        kx: 1e7,
        uz0: 4e-6,
        duz,
        dux: 0.01e-6,
        omega: std::f64::consts::TAU * 40e3,
        phi: 40f64.to_radians(),
    };
    for j in 0..=19 {
        let s = Scene::<f64>::new(params(j as f64 * 0.2e-6)).expect("valid scene");
        let v = s.dimensionless_velocity(1.0).unwrap();
        let mu = 0.3 * exact::mu_over_mu0::<f64, Libm>(&s.drive(), v).unwrap();
        assert!((mu - 0.3).abs() <= 1e-12, "μ {mu} at Δu_z {j}·0.2 µm");
    }
    let p0 = params(0.0);
    let sc = Scene::<f32>::new(SceneParams {
        mu0: p0.mu0 as f32,
        kz: p0.kz as f32,
        kx: p0.kx as f32,
        uz0: p0.uz0 as f32,
        duz: 0.0,
        dux: p0.dux as f32,
        omega: p0.omega as f32,
        phi: p0.phi as f32,
    })
    .expect("valid scene");
    let below = control::plan(&sc, 0.2999, 1.0, 2e-6, LIMIT as f32);
    assert_eq!(
        below,
        Err(control::ControlError::OutOfReach { min: 0.3, max: 0.3 })
    );
    let p = control::plan(&sc, 0.3, 1.0, 2e-6, LIMIT as f32).expect("μ₀ is reached");
    let floor = f64::from(control::S_MIN_REL) * 0.3 / 4e-6;
    assert!(
        (f64::from(p.slope_per_m) - floor).abs() <= 1e-6 * floor,
        "slope {} /m, the floor {floor} /m",
        p.slope_per_m
    );
}

/// μ* beyond ±μ₀ is no target (`BadTarget`), not a target out of this
/// drive's reach (`OutOfReach`): |μ| ≤ μ₀ holds for every drive (eq. 7).
#[test]
fn a_target_beyond_mu0_is_refused_as_a_bad_target() {
    let sc = scene::<f32>(MODEL_MU0, 0.0);
    for t in [0.3001f32, -0.31, 0.5, f32::INFINITY, f32::NAN] {
        assert_eq!(
            control::plan(&sc, t, V0 as f32, 2e-6, LIMIT as f32),
            Err(control::ControlError::BadTarget),
            "target {t}"
        );
    }
}

/// A law that falls and rises again (φ = 90°, Δu_x = 1 µm, v₀ = 4 mm/s:
/// μ falls from 0.061 to ≈ 0.009 near Δu_z = 2.4 µm and rises to 0.048 at
/// the limit, the exact law in f64) crosses μ* = 0.03 twice; the plan
/// takes the crossing nearer the present command `near_m`. Each crossing
/// is found here by bisection of the f64 law on its side of the minimum
/// (independent of the plan's f32 scan); the plan's f32 law is within
/// 10⁻⁵·μ₀ of it (tests/device.rs) and its slope here is ≥ 2·10⁴ /m, so
/// its root is within 1.5·10⁻¹⁰ m: allowed 1 nm.
#[test]
fn a_law_with_two_crossings_takes_the_one_nearest_the_present_command() {
    let params = |duz: f64| SceneParams {
        mu0: 0.3,
        kz: 1e7,
        kx: 1e7,
        uz0: 4e-6,
        duz,
        dux: 1e-6,
        omega: std::f64::consts::TAU * 40e3,
        phi: 90f64.to_radians(),
    };
    let (v0, target) = (0.004, 0.03);
    let law = |duz: f64| {
        let s = Scene::<f64>::new(params(duz)).expect("valid scene");
        let v = s.dimensionless_velocity(v0).unwrap();
        0.3 * exact::mu_over_mu0::<f64, Libm>(&s.drive(), v).unwrap()
    };
    // The minimum on a fine grid, then each side's root by bisection.
    let grid: Vec<f64> = (0..=380).map(|i| LIMIT * f64::from(i) / 380.0).collect();
    let x_min = *grid
        .iter()
        .min_by(|a, b| law(**a).total_cmp(&law(**b)))
        .unwrap();
    assert!(law(0.0) > target && law(x_min) < target && law(LIMIT) > target);
    let root = |(mut a, mut b): (f64, f64)| {
        let falling_at_a = law(a) > target;
        for _ in 0..60 {
            let m = 0.5 * (a + b);
            if (law(m) > target) == falling_at_a {
                a = m;
            } else {
                b = m;
            }
        }
        0.5 * (a + b)
    };
    let (lower, upper) = (root((0.0, x_min)), root((x_min, LIMIT)));
    let p0 = params(0.0);
    let sc = Scene::<f32>::new(SceneParams {
        mu0: p0.mu0 as f32,
        kz: p0.kz as f32,
        kx: p0.kx as f32,
        uz0: p0.uz0 as f32,
        duz: 0.0,
        dux: p0.dux as f32,
        omega: p0.omega as f32,
        phi: p0.phi as f32,
    })
    .expect("valid scene");
    for (near, want) in [
        (0.5e-6, lower),
        (3.7e-6, upper),
        (lower + 0.1e-6, lower),
        (upper - 0.1e-6, upper),
    ] {
        let p = control::plan(&sc, target as f32, v0 as f32, near as f32, LIMIT as f32)
            .expect("reachable");
        let got = f64::from(p.feedforward_m);
        assert!(
            (got - want).abs() <= 1e-9,
            "near {near:e}: feedforward {got:e}, the crossing {want:e} (the other: {:e})",
            if want == lower { upper } else { lower }
        );
    }
}

/// The least gain keeps the law's sign: where μ falls gently (φ = 90°,
/// Δu_x = 1 µm, v₀ = 1 mm/s: μ = 0.0530 at Δu_z = 0 and 0.0526 at 0.17 µm,
/// the exact law in f64), the central difference at the plan's
/// feedforward is negative and below the floor S_MIN_REL·μ₀/u_z0 in size
/// (checked here on the f64 law over the plan's own ±1 % of the range,
/// −2 250 /m at Δu_z = 0.1 µm, within the f32 law's slack of 80 /m),
/// so the plan must carry −3 750 /m, not +3 750.
#[test]
fn a_gently_falling_law_gets_the_least_gain_with_its_sign() {
    let params = |duz: f64| SceneParams {
        mu0: 0.3,
        kz: 1e7,
        kx: 1e7,
        uz0: 4e-6,
        duz,
        dux: 1e-6,
        omega: std::f64::consts::TAU * 40e3,
        phi: 90f64.to_radians(),
    };
    let v0 = 0.001;
    let law = |duz: f64| {
        let s = Scene::<f64>::new(params(duz)).expect("valid scene");
        let v = s.dimensionless_velocity(v0).unwrap();
        0.3 * exact::mu_over_mu0::<f64, Libm>(&s.drive(), v).unwrap()
    };
    let target = law(0.1e-6) as f32;
    let p0 = params(0.0);
    let sc = Scene::<f32>::new(SceneParams {
        mu0: p0.mu0 as f32,
        kz: p0.kz as f32,
        kx: p0.kx as f32,
        uz0: p0.uz0 as f32,
        duz: 0.0,
        dux: p0.dux as f32,
        omega: p0.omega as f32,
        phi: p0.phi as f32,
    })
    .expect("valid scene");
    let p = control::plan(&sc, target, v0 as f32, 0.0, LIMIT as f32).expect("reachable");
    let floor = f64::from(control::S_MIN_REL) * 0.3 / 4e-6;
    let x = f64::from(p.feedforward_m);
    let h = 0.01 * LIMIT;
    let (a, b) = ((x - h).max(0.0), (x + h).min(LIMIT));
    let s = (law(b) - law(a)) / (b - a);
    // The plan's f32 law is within 10⁻⁵·μ₀ of this one at each end
    // (tests/device.rs): its difference quotient within 2·10⁻⁵·μ₀/(b − a).
    let slack = 2.0 * 1e-5 * 0.3 / (b - a);
    assert!(
        s + slack < 0.0 && s.abs() + slack < floor,
        "the premise: f64 slope {s} /m (± {slack}) at {x:e} m"
    );
    assert!(
        (f64::from(p.slope_per_m) + floor).abs() <= 1e-6 * floor,
        "slope {} /m, the floor −{floor} /m",
        p.slope_per_m
    );
}
