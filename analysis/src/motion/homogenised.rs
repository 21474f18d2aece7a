//! The homogenised body: the averaged law μ(V) as the friction force, in the
//! load phase `T = Ωt` (module docs of [`crate::motion`]).
//!
//! * `M > 0`: classical RK4 on `(X, V)` with a fixed step per load period.
//!   The law jumps at `V = 0`, so every stage evaluates it on the side the
//!   body moves to (`dir`); a step whose velocity changes sign is cut at the
//!   crossing, located by bisection on the step length to 1e-14 of a step.
//!   At rest the body stays while `μ(0⁻) ≤ g ≤ μ(0⁺)` (the static band,
//!   `exact::limits_at_zero`); leaving the band is located by bisection on
//!   `g(T)` too, and the body starts on the side of the violated edge. An
//!   actuator has `μ(0⁺) < μ(0⁻)`: no force holds it, and a body at rest
//!   with `μ(0⁺) < g < μ(0⁻)` could start either way; it starts forward
//!   (`g > μ(0⁺)` is tested first; the massless inverse takes the same
//!   branch). With lift-off `μ(0⁺) = μ(0⁻)`: the body is never stuck.
//! * `M = 0`: `V = μ⁻¹(g)` ([`MuTable::inverse`]) and RK4 on `dX/dT = V/ν`
//!   (Simpson's rule when `K = 0`).
//!
//! The step count doubles from 256 per load period until two successive runs
//! agree on the mean velocity within the requested integration tolerance;
//! their difference is the reported numerical error. The periodic regime is
//! accepted when the period-to-period change plus the tail of a geometric
//! relaxation ([`super::remaining`]) is within the tolerance — a heavy body
//! relaxes over many load periods, and a small change per period alone would
//! stop it early.

use std::f64::consts::TAU;

use super::table::MuTable;
use super::{Problem, Recorder, Run, Sample, SAMPLES_PER_PERIOD};

/// Settings of a homogenised run.
#[derive(Debug, Clone, Copy)]
pub struct Settings {
    /// Tolerance on the mean velocity (units ωW₀), for both step halving and periodicity.
    pub tol: f64,
    /// Load periods: `Some(n)` runs exactly `n`; `None` runs until periodic.
    pub periods: Option<u32>,
    /// Most load periods when running until periodic.
    pub max_periods: u32,
    /// The body's relaxation over one load period
    /// ([`super::relaxation_per_period`]), the least ratio the periodicity
    /// test assumes for the changes still to come.
    pub relaxation: f64,
    /// Fewest steps per load period the caller knows the problem needs
    /// (e.g. RK4's stability on a stiff ground spring); 0 for none.
    pub min_steps: u64,
    /// Most steps of all runs together (`u64::MAX`: no bound): the step
    /// doubling stops before a run that would exceed it
    /// ([`Run::stopped_at_work_bound`]).
    pub budget: u64,
}

/// Fewest steps per load period.
pub const MIN_STEPS: u64 = 256;
/// Most steps per load period.
pub const MAX_STEPS: u64 = 1 << 20;
/// Above this stiffness bound on the steps per load period (`2πλ`, [`run`])
/// the body is run in its quasi-static (massless) limit.
pub const STIFF_STEPS: u64 = 1 << 16;

#[derive(Debug, Clone, Copy, PartialEq)]
enum Mode {
    /// Moving (or about to) in direction +1 / −1.
    Moving(i8),
    Stuck,
}

struct Body<'a> {
    p: &'a Problem,
    law: &'a MuTable,
}

impl Body<'_> {
    #[inline]
    fn g(&self, t: f64, x: f64) -> f64 {
        self.p.applied(t) - self.p.kappa * x / self.p.normal
    }

    /// The law on side `dir` (stage values past 0 are clamped to 0).
    #[inline]
    fn mu(&self, v: f64, dir: i8) -> f64 {
        if dir > 0 {
            self.law.mu(v.max(0.0), 1)
        } else {
            self.law.mu(v.min(0.0), -1)
        }
    }

    /// `(dX/dT, dV/dT)` while moving on side `dir`.
    #[inline]
    fn rhs(&self, t: f64, x: f64, v: f64, dir: i8) -> (f64, f64) {
        let beta = self.p.mass * self.p.nu / self.p.normal;
        (v / self.p.nu, (self.g(t, x) - self.mu(v, dir)) / beta)
    }

    fn rk4(&self, t: f64, x: f64, v: f64, dir: i8, h: f64) -> (f64, f64) {
        let (k1x, k1v) = self.rhs(t, x, v, dir);
        let (k2x, k2v) = self.rhs(t + 0.5 * h, x + 0.5 * h * k1x, v + 0.5 * h * k1v, dir);
        let (k3x, k3v) = self.rhs(t + 0.5 * h, x + 0.5 * h * k2x, v + 0.5 * h * k2v, dir);
        let (k4x, k4v) = self.rhs(t + h, x + h * k3x, v + h * k3v, dir);
        (
            x + h / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x),
            v + h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v),
        )
    }

    /// The mode of a body at rest at `(t, x)`.
    fn at_rest(&self, t: f64, x: f64) -> Mode {
        let g = self.g(t, x);
        if g > self.law.mu_0plus {
            Mode::Moving(1)
        } else if g < self.law.mu_0minus {
            Mode::Moving(-1)
        } else {
            Mode::Stuck
        }
    }

    /// Advances `(x, v, mode)` from `t` by `h`; returns the time stuck in it
    /// and counts the body's arrivals at rest (stick onsets) in `onsets`.
    fn step(
        &self,
        t: f64,
        x: &mut f64,
        v: &mut f64,
        mode: &mut Mode,
        h: f64,
        onsets: &mut u32,
    ) -> f64 {
        let (mut t, end) = (t, t + h);
        let mut stuck = 0.0;
        // At most a few events per step (each bisection consumes part of it).
        for _ in 0..8 {
            let left = end - t;
            if left <= 0.0 {
                break;
            }
            match *mode {
                Mode::Stuck => {
                    let m = self.at_rest(end, *x);
                    if m == Mode::Stuck {
                        stuck += left;
                        return stuck;
                    }
                    // Leaves the band inside the step: bisect on g.
                    let (mut lo, mut hi) = (t, end);
                    for _ in 0..60 {
                        let mid = 0.5 * (lo + hi);
                        if self.at_rest(mid, *x) == Mode::Stuck {
                            lo = mid;
                        } else {
                            hi = mid;
                        }
                    }
                    stuck += hi - t;
                    t = hi;
                    *v = 0.0;
                    *mode = m;
                }
                Mode::Moving(dir) => {
                    let (xn, vn) = self.rk4(t, *x, *v, dir, left);
                    let reversed = (dir > 0 && vn < 0.0) || (dir < 0 && vn > 0.0);
                    if !reversed {
                        *x = xn;
                        *v = vn;
                        return stuck;
                    }
                    // Cut the step where V crosses 0.
                    let (mut lo, mut hi) = (0.0, left);
                    for _ in 0..60 {
                        let mid = 0.5 * (lo + hi);
                        let (_, vm) = self.rk4(t, *x, *v, dir, mid);
                        if (dir > 0 && vm > 0.0) || (dir < 0 && vm < 0.0) {
                            lo = mid;
                        } else {
                            hi = mid;
                        }
                    }
                    let (xc, _) = self.rk4(t, *x, *v, dir, hi);
                    *x = xc;
                    *v = 0.0;
                    t += hi;
                    // At rest: stick, or pass through into the other side.
                    *mode = match self.at_rest(t, *x) {
                        Mode::Moving(d) if d != dir => Mode::Moving(d),
                        _ => {
                            *onsets += 1;
                            Mode::Stuck
                        }
                    };
                }
            }
        }
        stuck
    }

    fn massless_v(&self, t: f64, x: f64) -> f64 {
        self.law.inverse(self.g(t, x))
    }
}

/// One run at `n` steps per load period.
fn run_n(
    p: &Problem,
    law: &MuTable,
    s: &Settings,
    n: u64,
    mut rec: Option<&mut Recorder>,
    tick: &mut dyn FnMut(),
) -> Run {
    let body = Body { p, law };
    let h = TAU / n as f64;
    let (mut x, mut v) = (0.0f64, 0.0f64);
    let mut mode = body.at_rest(0.0, 0.0);
    let every = (n / SAMPLES_PER_PERIOD as u64).max(1);
    let limit = s.periods.unwrap_or(s.max_periods);
    let (mut prev_mean, mut prev_v, mut prev_x_end) = (f64::NAN, f64::NAN, f64::NAN);
    let (mut mean, mut stick_fraction, mut change) = (0.0, 0.0, f64::INFINITY);
    let mut prev_change = f64::INFINITY;
    let mut periods = 0;
    let mut periodic = false;
    let mut onsets = 0u32;
    for k in 1..=limit {
        periods = k;
        if let Some(r) = rec.as_deref_mut() {
            r.new_period();
        }
        let t0 = TAU * f64::from(k - 1);
        let x0 = x;
        let mut stuck = 0.0;
        onsets = 0;
        for i in 0..n {
            let t = t0 + h * i as f64;
            if let Some(r) = rec.as_deref_mut() {
                if i % every == 0 {
                    let vv = if p.mass > 0.0 {
                        v
                    } else {
                        body.massless_v(t, x)
                    };
                    r.push(Sample {
                        t,
                        x,
                        v: vv,
                        force: p.applied(t),
                        stuck: if p.mass > 0.0 {
                            mode == Mode::Stuck
                        } else {
                            vv == 0.0
                        },
                    });
                }
            }
            if p.mass > 0.0 {
                stuck += body.step(t, &mut x, &mut v, &mut mode, h, &mut onsets);
            } else {
                // dX/dT = V(T, X)/ν, RK4; stick time by Simpson weights.
                let f = |tt: f64, xx: f64| body.massless_v(tt, xx) / p.nu;
                let k1 = f(t, x);
                let k2 = f(t + 0.5 * h, x + 0.5 * h * k1);
                let k3 = f(t + 0.5 * h, x + 0.5 * h * k2);
                let k4 = f(t + h, x + h * k3);
                let w = [k1 == 0.0, k2 == 0.0 && k3 == 0.0, k4 == 0.0];
                // A stick onset: moving at the step's start, at rest at its end.
                onsets += u32::from(k1 != 0.0 && k4 == 0.0);
                stuck += h
                    * (f64::from(u8::from(w[0]))
                        + 4.0 * f64::from(u8::from(w[1]))
                        + f64::from(u8::from(w[2])))
                    / 6.0;
                x += h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
            }
        }
        tick();
        mean = (x - x0) * p.nu / TAU;
        stick_fraction = stuck / TAU;
        if k > 1 {
            // Change of the period's mean and of the state it ends in.
            let dv = (v - prev_v).abs();
            // Held by a spring the body's position is periodic too: a change
            // of its end position is a drift of Δx·ν/(2π) (units ωW₀).
            let dx = if p.kappa > 0.0 {
                (x - prev_x_end).abs() * p.nu / TAU
            } else {
                0.0
            };
            let now = (mean - prev_mean).abs().max(dv).max(dx);
            // The change plus the tail of a geometric relaxation.
            change = super::remaining(now, prev_change, s.relaxation);
            prev_change = now;
        }
        prev_mean = mean;
        prev_v = v;
        prev_x_end = x;
        // Without a spring and mass the massless body is periodic at once.
        let exact_periodic = p.mass == 0.0 && p.kappa == 0.0;
        // Judged afresh every period: a fixed `--duration` reports the last.
        periodic = exact_periodic || (k > 1 && change <= s.tol);
        if periodic && s.periods.is_none() {
            if exact_periodic {
                change = 0.0;
            }
            break;
        }
    }
    Run {
        mean_velocity: mean,
        stick_fraction,
        stick_onsets: onsets,
        numerical_error: if change.is_finite() { change } else { 0.0 },
        periods,
        periodic,
        steps: n,
        springs: 0,
        trajectory: rec.map(|_| Vec::new()).unwrap_or_default(),
        stopped_at_work_bound: false,
    }
}

/// Integrates with step halving until the mean velocity is within `s.tol`.
/// The trajectory is that of the final run. `tick` is called once per load
/// period integrated (for progress).
///
/// A body that responds fast against the load period makes the equation
/// stiff: `λ = n̄·max(dμ/dV)/(m̃ν)` in `T`, and RK4 is stable only for
/// `hλ ≲ 2.8`. The first step count is therefore at least `2πλ` (hλ ≤ 1).
/// When that exceeds [`STIFF_STEPS`] the body follows the quasi-static law
/// within a response time `τ_r = m̃νS/n̄` (in T, `S` the law's mean inverse
/// slope): it is run massless ([`Problem::mass`] 0), and its lag
/// `τ_r·max|dV/dT|` (from the massless trajectory) is added to the
/// numerical error.
pub fn run(p: &Problem, law: &MuTable, s: &Settings, tick: &mut dyn FnMut()) -> Run {
    let stiff = if p.mass > 0.0 {
        TAU * p.normal * law.max_slope() / (p.mass * p.nu)
    } else {
        0.0
    };
    // The massless limit exists while the force stays inside ±μ₀F̄z.
    let bounded = p.f0.abs() + p.f.abs() < 1.0;
    if stiff > STIFF_STEPS as f64 && bounded {
        let q = Problem { mass: 0.0, ..*p };
        let mut r = run(&q, law, s, tick);
        let tau_r = p.mass * p.nu * super::estimate::inverse_slope(law) / p.normal;
        r.numerical_error += tau_r * super::estimate::max_dv_dt(&r);
        return r;
    }
    let mut n = MIN_STEPS
        .max((stiff.ceil() as u64).next_power_of_two().min(MAX_STEPS / 2))
        .max(s.min_steps.next_power_of_two().min(MAX_STEPS / 2));
    let mut prev = run_n(p, law, s, n, None, tick);
    let mut spent = n.saturating_mul(u64::from(prev.periods));
    loop {
        n *= 2;
        let last = n >= MAX_STEPS;
        let mut rec = Recorder::default();
        let mut cur = run_n(p, law, s, n, Some(&mut rec), tick);
        let work = n.saturating_mul(u64::from(cur.periods));
        spent = spent.saturating_add(work);
        let halving = (cur.mean_velocity - prev.mean_velocity).abs();
        // The next run, at twice the steps, would cost about twice this one.
        let over = spent.saturating_add(work.saturating_mul(2)) > s.budget;
        if halving <= s.tol || last || over {
            cur.stopped_at_work_bound = halving > s.tol && !last;
            cur.numerical_error += halving;
            if stiff > 2.5 * n as f64 {
                // hλ > 2.5, at RK4's stability edge (2.79): no error estimate holds.
                cur.numerical_error = f64::INFINITY;
                cur.periodic = false;
            }
            cur.trajectory = rec.finish();
            return cur;
        }
        prev = cur;
    }
}
