//! The resolved body: body and spring contact integrated together at the
//! ultrasonic scale, no separation of scales assumed (module docs of
//! [`crate::motion`]).
//!
//! Per step `h` (in `τ = ωt`), symplectic Euler for the body and the paper's
//! scheme (§3) for the contact:
//! `V ← V + h(n̄g − s)/m̃`, `X ← X + hV`, then the stick trial
//! `s ← s + ΔX + Δ(b cos(τ + φ))` and the clamp `|s| ≤ max(0, 1 − a cos τ)`
//! (the contact point slips so that `|f_x| = μ₀f_z`; in the air, lift-off,
//! the massless spring relaxes to `s = 0` and lands with it). The body's velocity enters the
//! contact as its sliding velocity through `ΔX`. The run starts at rest with
//! the contact point at the origin (`s = b cos φ`, clamped), like the paper's.
//!
//! **Curved profiles** (MDR, [`Bed::profile`]): the same step for every
//! spring of the bed, each with its band `max(0, d_j − a cos τ)`, the body
//! feeling `Σ q_j s_j`; the bed is refined by doubling ([`run`]).
//!
//! `(cos τ, sin τ)` and `sin T` advance by rotation and are recomputed
//! exactly every 1024 steps. Steps per ultrasonic period start at
//! `max(64, 2·min_steps_per_period)` (`fixed_step`'s, or with lift-off
//! `liftoff::stepping`'s) and double (up to 1024)
//! until two runs agree on the mean velocity within the tolerance; their
//! difference plus the last period-to-period change (with the tail of a
//! geometric relaxation, [`super::remaining`]) is the numerical error.
//! When ω/Ω is not a whole number the state is only quasi-periodic in the
//! load period; the drift is then the average over the last 10 load periods,
//! accepted when it agrees with the average of the 10 before.

use std::f64::consts::TAU;

use model_core::{fixed_step, Drive};

use super::{Problem, Recorder, Run, Sample, SAMPLES_PER_PERIOD};

/// Settings of a resolved run.
#[derive(Debug, Clone, Copy)]
pub struct Settings {
    /// Tolerance on the mean velocity (units ωW₀).
    pub tol: f64,
    /// Load periods: `Some(n)` runs exactly `n`; `None` runs until periodic.
    pub periods: Option<u32>,
    /// Most load periods when running until periodic.
    pub max_periods: u32,
    /// The body's relaxation over one load period
    /// ([`super::relaxation_per_period`]), the least ratio the periodicity
    /// test assumes for the changes still to come.
    pub relaxation: f64,
    /// Most spring steps (steps × springs) of all runs together
    /// (`u64::MAX`: no bound): the step and bed doublings stop before a run
    /// that would exceed it ([`Run::stopped_at_work_bound`]).
    pub budget: u64,
}

/// Load periods averaged when ω/Ω is not a whole number.
const QUASI: usize = 10;

/// Most steps per ultrasonic period.
pub const MAX_STEPS: u64 = 1024;

/// The first step count per ultrasonic period.
pub fn start_steps(d: &Drive<f64>) -> u64 {
    let min = if d.a >= 1.0 {
        model_core::model::liftoff::stepping::min_steps_per_period(d)
    } else {
        fixed_step::min_steps_per_period(d)
    };
    u64::from(min).saturating_mul(2).max(64)
}

/// The cost of a run in steps per load period at `n` steps per ultrasonic period.
pub fn steps_per_load_period(p: &Problem, n: u64) -> u64 {
    ((n as f64) / p.nu).round().max(1.0) as u64
}

fn run_n(
    p: &Problem,
    d: &Drive<f64>,
    bed: &Bed,
    s: &Settings,
    n: u64,
    mut rec: Option<&mut Recorder>,
    tick: &mut dyn FnMut(),
) -> Run {
    let per_load = steps_per_load_period(p, n);
    let h = TAU / p.nu / per_load as f64;
    // Steps of one ultrasonic period (for the stick fraction).
    let per_us = ((TAU / h).round() as u64).max(1);
    let every = (per_load / SAMPLES_PER_PERIOD as u64).max(1);
    let (a, bc, bs) = (d.a, d.bc, d.bs);
    let inv_m = 1.0 / p.mass;
    let (sh, ch) = h.sin_cos();
    let (snh, cnh) = (p.nu * h).sin_cos();
    let (mut x, mut v) = (0.0f64, 0.0f64);
    // Each spring starts with the contact point at the origin, clamped.
    let mut stretch: Vec<f64> = bed
        .springs
        .iter()
        .map(|&(off, _)| {
            let w0 = (off - a).max(0.0);
            bc.clamp(-w0, w0)
        })
        .collect();
    let force_of = |st: &[f64]| -> f64 { st.iter().zip(&bed.springs).map(|(s, q)| s * q.1).sum() };
    let mut s_ = force_of(&stretch);
    let normal = p.normal;
    let (mut c, mut sn) = (1.0f64, 0.0f64); // cos τ, sin τ
    let (mut cl, mut sl) = (1.0f64, 0.0f64); // cos T, sin T
    let mut drive = bc;
    let limit = s.periods.unwrap_or(s.max_periods);
    let mut step_no: u64 = 0;
    let (mut mean, mut prev_mean, mut change) = (0.0, f64::NAN, f64::INFINITY);
    let (mut prev_v, mut prev_x_end) = (f64::NAN, f64::NAN);
    let mut prev_change = f64::INFINITY;
    let mut stick_fraction = 0.0;
    let (mut periods, mut periodic) = (0, false);
    let mut last_block_stuck = false;
    let mut means: Vec<f64> = Vec::new();
    for k in 1..=limit {
        periods = k;
        if let Some(r) = rec.as_deref_mut() {
            r.new_period();
        }
        let x0 = x;
        let (mut blocks, mut stuck_blocks) = (0u64, 0u64);
        let mut slipped = false;
        let mut sample_x = x;
        for i in 0..per_load {
            // Body: symplectic Euler with the spring force of the step start.
            let g = normal * (p.f0 + p.f * sl) - p.kappa * x;
            v += h * (g - s_) * inv_m;
            let dx = h * v;
            x += dx;
            step_no += 1;
            if step_no % 1024 == 0 {
                let tau = step_no as f64 * h;
                (sn, c) = tau.sin_cos();
                (sl, cl) = (p.nu * tau).sin_cos();
            } else {
                (c, sn) = (c * ch - sn * sh, sn * ch + c * sh);
                (cl, sl) = (cl * cnh - sl * snh, sl * cnh + cl * snh);
            }
            // Contact: stick trial and clamp, spring by spring.
            let dn = bc * c - bs * sn;
            let inc = dx + (dn - drive);
            drive = dn;
            let mut force = 0.0;
            for (st, &(off, q)) in stretch.iter_mut().zip(&bed.springs) {
                // In the air (lift-off) the band is empty: s = 0.
                let w = (off - a * c).max(0.0);
                let trial = *st + inc;
                if trial > w {
                    *st = w;
                    slipped = true;
                } else if trial < -w {
                    *st = -w;
                    slipped = true;
                } else {
                    *st = trial;
                }
                force += *st * q;
            }
            s_ = force;
            if (i + 1) % per_us == 0 {
                blocks += 1;
                if !slipped {
                    stuck_blocks += 1;
                }
                last_block_stuck = !slipped;
                slipped = false;
            }
            if let Some(r) = rec.as_deref_mut() {
                if (i + 1) % every == 0 {
                    let t = p.nu * h * step_no as f64;
                    r.push(Sample {
                        t,
                        x,
                        v: (x - sample_x) / (every as f64 * h),
                        force: p.applied(t),
                        stuck: last_block_stuck,
                    });
                    sample_x = x;
                }
            }
        }
        tick();
        mean = (x - x0) * p.nu / TAU;
        stick_fraction = if blocks > 0 {
            stuck_blocks as f64 / blocks as f64
        } else {
            0.0
        };
        if k > 1 {
            // The period's mean, the state it ends in (velocity; with a
            // ground spring the position, as the drift Δx·ν/(2π) it implies).
            let dx = if p.kappa > 0.0 {
                (x - prev_x_end).abs() * p.nu / TAU
            } else {
                0.0
            };
            let now = (mean - prev_mean).abs().max((v - prev_v).abs()).max(dx);
            // The change plus the tail of a geometric relaxation.
            change = super::remaining(now, prev_change, s.relaxation);
            prev_change = now;
        }
        prev_mean = mean;
        prev_v = v;
        prev_x_end = x;
        means.push(mean);
        // Judged afresh every period: a fixed `--duration` reports the last.
        periodic = k > 2 && change <= s.tol;
        if periodic {
            if s.periods.is_none() {
                break;
            }
        } else if s.periods.is_none() && means.len() >= 2 * QUASI {
            // ω/Ω not a whole number: the ultrasonic phase at the period start
            // beats, so single periods differ; the drift is the average over
            // QUASI periods, accepted when two successive averages agree.
            let n = means.len();
            let last: f64 = means[n - QUASI..].iter().sum::<f64>() / QUASI as f64;
            let before: f64 = means[n - 2 * QUASI..n - QUASI].iter().sum::<f64>() / QUASI as f64;
            // The averages relax like the periods, by ρ^QUASI per average.
            let tail = 1.0 - s.relaxation.powi(QUASI as i32).min(0.999);
            if (last - before).abs() <= s.tol * tail {
                mean = last;
                change = (last - before).abs() / tail;
                periodic = true;
                break;
            }
        }
    }
    let _ = cl;
    Run {
        mean_velocity: mean,
        stick_fraction,
        stick_onsets: 0,
        numerical_error: if change.is_finite() { change } else { 0.0 },
        periods,
        periodic,
        steps: n,
        springs: bed.springs.len(),
        trajectory: Vec::new(),
        stopped_at_work_bound: false,
    }
}

/// The contact's springs: `(band offset d_j, weight q_j)`, the force on the
/// body `Σ q_j s_j` in units of `k_x W₀`, each spring's band
/// `max(0, d_j − a cos τ)`.
#[derive(Debug, Clone, PartialEq)]
pub struct Bed {
    /// `(d_j, q_j)` per spring.
    pub springs: Vec<(f64, f64)>,
}

impl Bed {
    /// The flat punch: one spring, `d = 1`, weight 1.
    pub fn flat() -> Self {
        Bed {
            springs: vec![(1.0, 1.0)],
        }
    }

    /// The MDR bed of a profile `ξⁿ` (`model_core::mdr`): `count` springs
    /// over the springs that ever touch, `ξ ∈ [0, ξ_max]`, `ξ_max = (1 +
    /// a)^{1/n}`, at the midpoints `t_j = (j + ½)π/count` of the map
    /// `ξ = ξ_max(1 − cos t)/2` (dense at the rim, where the springs' mean
    /// force has its `(ξ_max − ξ)^{3/2}` onset), offset `d_j = 1 − ξ_jⁿ` and
    /// weight `q_j = (ξ_max/2) sin t_j · π/count`. With `k_x = 2G*a₀` the
    /// force of both sides `2G*a₀W₀∫₀^{ξ_max} s dξ` is `Σ q_j s_j` in units
    /// of `k_x W₀` (`mdr::normal::mean_normal_force`'s reading of the scene).
    pub fn profile(n: f64, a: f64, count: usize) -> Self {
        let xi_max = (1.0 + a).powf(1.0 / n);
        let h = std::f64::consts::PI / count as f64;
        let springs = (0..count)
            .map(|j| {
                let t = (j as f64 + 0.5) * h;
                let xi = 0.5 * xi_max * (1.0 - t.cos());
                (1.0 - xi.powf(n), 0.5 * xi_max * t.sin() * h)
            })
            .collect();
        Bed { springs }
    }
}

/// Springs of a curved profile's first bed; doubled (up to
/// [`MAX_SPRINGS`]) until the drift changes by at most the tolerance.
pub const START_SPRINGS: usize = 32;
/// Most springs of a curved profile's bed.
pub const MAX_SPRINGS: usize = 512;

/// Integrates with step halving (module docs); for a curved profile
/// (`exponent = Some(n)`) then with the bed of springs doubled at the final
/// step count until two beds agree, the difference added to the numerical
/// error. `tick` is called once per load period integrated.
pub fn run(
    p: &Problem,
    d: &Drive<f64>,
    exponent: Option<f64>,
    s: &Settings,
    tick: &mut dyn FnMut(),
) -> Run {
    let Some(ne) = exponent else {
        return run_bed(p, d, &Bed::flat(), s, s.budget, tick).0;
    };
    let mut count = START_SPRINGS;
    let (mut prev, mut spent) = run_bed(p, d, &Bed::profile(ne, d.a, count), s, s.budget, tick);
    loop {
        count *= 2;
        let left = s.budget.saturating_sub(spent);
        let (mut cur, work) = run_bed(p, d, &Bed::profile(ne, d.a, count), s, left, tick);
        spent = spent.saturating_add(work);
        let diff = (cur.mean_velocity - prev.mean_velocity).abs();
        // The next bed, twice the springs, would cost about twice this one.
        let over = spent.saturating_add(work.saturating_mul(2)) > s.budget;
        if diff <= s.tol || count >= MAX_SPRINGS || over {
            cur.stopped_at_work_bound |= diff > s.tol && count < MAX_SPRINGS;
            cur.numerical_error += diff;
            cur.springs = count;
            return cur;
        }
        prev = cur;
    }
}

/// Step halving on one bed, within `budget` spring steps (steps × springs;
/// the first two runs always run); returns the run and the spring steps spent.
fn run_bed(
    p: &Problem,
    d: &Drive<f64>,
    bed: &Bed,
    s: &Settings,
    budget: u64,
    tick: &mut dyn FnMut(),
) -> (Run, u64) {
    let cost = |n: u64, r: &Run| {
        steps_per_load_period(p, n)
            .saturating_mul(u64::from(r.periods))
            .saturating_mul(bed.springs.len() as u64)
    };
    let mut n = start_steps(d);
    let mut prev = run_n(p, d, bed, s, n, None, tick);
    let mut spent = cost(n, &prev);
    loop {
        n *= 2;
        let last = n >= MAX_STEPS;
        let mut rec = Recorder::default();
        let mut cur = run_n(p, d, bed, s, n, Some(&mut rec), tick);
        let work = cost(n, &cur);
        spent = spent.saturating_add(work);
        let halving = (cur.mean_velocity - prev.mean_velocity).abs();
        let over = spent.saturating_add(work.saturating_mul(2)) > budget;
        if halving <= s.tol || last || over {
            cur.stopped_at_work_bound = halving > s.tol && !last;
            cur.numerical_error += halving;
            cur.trajectory = rec.finish();
            return (cur, spent);
        }
        prev = cur;
    }
}
