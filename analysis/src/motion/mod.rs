//! A body moved by the vibrated contact: the slow dynamics of
//! the paper's "substrate subjected to a low-frequency tangential force".
//!
//! # Conventions
//! The friction force on the body is `−μ(v)·F̄z` along `+x` (`F̄z` the mean
//! normal force: `k_z u_z0` in permanent contact, `k_z u_z0⟨w⁺⟩` with
//! lift-off, `k_z u_z0·D` (eq. M5) for a curved profile, [`law::Law::mean_normal`]); the external force is
//! `F(t) = μ₀F̄z·(f0 + f sin Ωt)`, a ground spring adds `−K x`. The body's
//! slow coordinate `x` carries the transducers: the upper spring point is at
//! `u_x = x + Δu_x cos(ωt + φ)` (eq. 2 with `v₀t → x(t)`).
//!
//! # Dimensionless form
//! Lengths in `W₀ = μ₀k_z u_z0/k_x`, forces in `μ₀F̄z = k_x W₀`, velocities
//! `V = v/(ωW₀)`, the ultrasonic phase `τ = ωt` and the load phase `T = Ωt`.
//! With `m̃ = Mω²/k_x`, `κ = K/k_x`, `ν = Ω/ω`, `g = f0 + f sin T − κX/n̄`
//! (units μ₀F̄z) and `n̄ = F̄z/(k_z u_z0)` (1 for permanent contact, `⟨w⁺⟩`
//! of eq. L4 with lift-off, `D` of eq. M5 for a curved profile):
//!
//! * **homogenised** (`μ` replaced by its steady-state law, [`table`], taken
//!   through [`law`] for every contact model):
//!   `m̃ν dV/dT = n̄(g − μ(V)/μ₀)`, `dX/dT = V/ν`; stuck (`V = 0`) while
//!   `μ(0⁻) ≤ g·μ₀ ≤ μ(0⁺)` (with lift-off μ(0) is unique: the band is a
//!   point); with `M = 0`, `V = μ⁻¹(g)` ([`homogenised`]);
//! * **resolved** (no separation of scales): `m̃ d²X/dτ² = n̄g − s` with the
//!   spring stretch `s = X + b cos(τ + φ) − X_c` kept in the band
//!   `|s| ≤ max(0, 1 − a cos τ)` by the paper's clamp (`s = 0` in the air,
//!   lift-off) ([`resolved`]); for a curved profile `s` is the bed's
//!   `Σ q_j s_j`, each MDR spring with its own band `max(0, d_j − a cos τ)`.

pub mod estimate;
pub mod homogenised;
pub mod law;
pub mod resolved;
pub mod simulate;
pub mod table;

/// The dimensionless problem.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Problem {
    /// Mean force `f0` (units μ₀F̄z).
    pub f0: f64,
    /// Force amplitude `f` (units μ₀F̄z).
    pub f: f64,
    /// `ν = Ω/ω`.
    pub nu: f64,
    /// `m̃ = Mω²/k_x` (0: massless).
    pub mass: f64,
    /// `κ = K/k_x`.
    pub kappa: f64,
    /// `n̄ = F̄z/(k_z u_z0)`: 1 for permanent contact, `⟨w⁺⟩` with lift-off,
    /// `D` (eq. M5) for a curved profile
    /// ([`law::Law::mean_normal`]); forces in `μ₀F̄z` are `n̄` times forces in
    /// `μ₀k_z u_z0 = k_x W₀`, the unit of the contact's stretch.
    pub normal: f64,
}

impl Problem {
    /// The applied force `f0 + f sin T` (units μ₀F̄z) at load phase `T`.
    #[inline]
    pub fn applied(&self, t: f64) -> f64 {
        self.f0 + self.f * t.sin()
    }
}

/// One trajectory sample (dimensionless).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// Load phase `T = Ωt`, rad.
    pub t: f64,
    /// Position `X = x/W₀`.
    pub x: f64,
    /// Velocity `V = v/(ωW₀)` (resolved: averaged over the sample's ultrasonic periods).
    pub v: f64,
    /// Applied force `f0 + f sin T` (units μ₀F̄z).
    pub force: f64,
    /// The body is at rest on the contact (resolved: no slip of the contact
    /// point during the sample's ultrasonic periods).
    pub stuck: bool,
}

/// The result of a run (dimensionless).
#[derive(Debug, Clone, PartialEq)]
pub struct Run {
    /// Mean velocity over the last load period (units ωW₀).
    pub mean_velocity: f64,
    /// Fraction of the last load period the body was stuck.
    pub stick_fraction: f64,
    /// Arrivals at rest (stick onsets) in the last load period (homogenised
    /// runs; 0 for resolved runs, which do not count them).
    pub stick_onsets: u32,
    /// Estimated numerical error of `mean_velocity` (units ωW₀): the step
    /// halving difference plus the last period-to-period change.
    pub numerical_error: f64,
    /// Load periods integrated (of the final, finest run).
    pub periods: u32,
    /// Whether the periodic regime was reached (the last two periods agree
    /// within the requested tolerance).
    pub periodic: bool,
    /// Steps per load period (homogenised) or per ultrasonic period (resolved)
    /// of the final run.
    pub steps: u64,
    /// Springs of the contact in the final run (resolved: 1 for the flat
    /// punch, the bed's size for a curved profile; homogenised: 0, the law
    /// stands for them).
    pub springs: usize,
    /// The recorded trajectory (the last periods).
    pub trajectory: Vec<Sample>,
    /// The refinement (step doubling, or doubling a curved profile's bed)
    /// stopped at the settings' work budget before the tolerance was met:
    /// `numerical_error` is the last refinement's change, above the tolerance.
    pub stopped_at_work_bound: bool,
}

/// How far the last load period's state may still be from the periodic
/// regime, from the last two period-to-period changes `change` and `prev`
/// (same units): a body relaxing geometrically with ratio `ρ` per load period
/// is still `change·ρ/(1 − ρ)` away, so the change plus that tail,
/// `change/(1 − ρ)`, is returned. `ρ` is the larger of the measured ratio
/// `change/prev` and `floor`, the body's own relaxation over a load period
/// ([`relaxation_per_period`]; the measured ratio alone is blind at the second
/// period and where the changes happen to shrink), capped at 0.999: a
/// sequence that does not contract yet counts 1000 changes.
pub fn remaining(change: f64, prev: f64, floor: f64) -> f64 {
    let measured = if prev.is_finite() && prev > 0.0 {
        change / prev
    } else {
        0.0
    };
    let rho = measured.max(floor).clamp(0.0, 0.999);
    change / (1.0 - rho)
}

/// The body's relaxation over one load period, `ρ = exp(−2π n̄/(m̃ν S))`:
/// linearised about a sliding state, `m̃ν dV/dT = n̄(g − μ(V)/μ₀)` relaxes at
/// the rate `n̄/(m̃ν S)` in `T`, `S` the law's mean inverse slope
/// (`estimate::inverse_slope`, units ωW₀ per μ₀). 0 for the massless body.
pub fn relaxation_per_period(p: &Problem, inverse_slope: f64) -> f64 {
    if p.mass > 0.0 && inverse_slope > 0.0 {
        (-std::f64::consts::TAU * p.normal / (p.mass * p.nu * inverse_slope)).exp()
    } else {
        0.0
    }
}

/// Samples kept per load period of the trajectory.
pub const SAMPLES_PER_PERIOD: usize = 400;
/// Load periods kept in the trajectory (the last ones).
pub const KEPT_PERIODS: usize = 50;

/// Keeps the samples of the last [`KEPT_PERIODS`] load periods.
#[derive(Debug, Default)]
pub struct Recorder {
    periods: std::collections::VecDeque<Vec<Sample>>,
}

impl Recorder {
    /// Starts a new load period.
    pub fn new_period(&mut self) {
        if self.periods.len() == KEPT_PERIODS {
            self.periods.pop_front();
        }
        self.periods
            .push_back(Vec::with_capacity(SAMPLES_PER_PERIOD + 1));
    }

    /// Adds a sample to the current period.
    pub fn push(&mut self, s: Sample) {
        if let Some(p) = self.periods.back_mut() {
            p.push(s);
        }
    }

    /// All kept samples in time order.
    pub fn finish(self) -> Vec<Sample> {
        self.periods.into_iter().flatten().collect()
    }
}

#[cfg(test)]
mod tests {
    use super::law::Law;
    use super::table::MuTable;
    use super::*;
    use model_core::scene::ContactMode;
    use model_core::{Groups, Scene};

    /// A lift-off scene (a = 1.5) runs through the same law interface in both
    /// models. The homogenised body's band at rest is a point (μ(0) unique),
    /// and homogenised and resolved agree within the derived estimate
    /// `E_h` ([`estimate`]) plus both runs' numerical errors.
    #[test]
    fn lift_off_body_homogenised_matches_resolved() {
        let g = Groups {
            duz_rel: 1.5,
            dux_rel: 0.75,
            phi: 0.6,
        };
        let scene = Scene::dimensionless_with_contact(g, ContactMode::Intermittent).unwrap();
        let law = Law::of(&scene);
        let table = MuTable::new(&law, 1e-7).unwrap();
        assert_eq!(table.mu_0plus, table.mu_0minus);
        let nu = 1e-3;
        let p = Problem {
            f0: 0.0,
            f: 0.5,
            nu,
            mass: 1.0 / nu,
            kappa: 0.0,
            normal: law.mean_normal().unwrap(),
        };
        let tol = 1e-5;
        let h = homogenised::run(
            &p,
            &table,
            &homogenised::Settings {
                tol,
                periods: None,
                max_periods: 500,
                relaxation: relaxation_per_period(&p, estimate::inverse_slope(&table)),
                min_steps: 0,
                budget: u64::MAX,
            },
            &mut || {},
        );
        let r = resolved::run(
            &p,
            &scene.drive(),
            None,
            &resolved::Settings {
                tol,
                periods: None,
                max_periods: 500,
                relaxation: relaxation_per_period(&p, estimate::inverse_slope(&table)),
                budget: u64::MAX,
            },
            &mut || {},
        );
        let e_h = estimate::homogenisation_error(&p, law.spring_bounds(), &table, &h);
        let diff = (h.mean_velocity - r.mean_velocity).abs();
        eprintln!(
            "lift-off: H {:e} R {:e} |H-R| {diff:e} E_h {e_h:e}",
            h.mean_velocity, r.mean_velocity
        );
        assert!(h.periodic && r.periodic);
        assert!(
            h.mean_velocity.abs() > 10.0 * diff,
            "drift too small to test"
        );
        assert!(diff <= e_h + h.numerical_error + r.numerical_error);
    }
}
