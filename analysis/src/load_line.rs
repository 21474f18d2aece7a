//! The contact read as an actuator — stall forces, no-load velocities, the
//! force–velocity line(s), powers and efficiency (model-core
//! [`model_core::model::load_line`], whose doc states the sign conventions
//! and the power balance); the computation of `fricctl load-line` and
//! `fricctl.load_line`.
//!
//! μ(v) comes through [`crate::motion::law::Law`], the one interface for
//! every contact model: stall forces, no-load velocities and the output
//! power `−μ(v)F̄z·v` exist for all of them, and so do the transducers' input
//! power and the efficiency: the flat punch in permanent contact
//! ([`load_line::powers`]) and with lift-off ([`load_line::liftoff_powers`]),
//! closed form; a curved profile as the bed's sum
//! ([`model_core::mdr::powers::profile_powers`], bound 1e-6).
//!
//! A scene may push forward (`μ(0⁺) < 0`: the line `0 < v < v_nl`),
//! backward (`μ(0⁻) > 0`: `−v_nl' < v < 0`), or neither. The operating
//! points of maximum power and maximum efficiency are sought over every line
//! the scene has ([`load_line::best_of`]) and reported with a signed
//! velocity, the direction, and the contact's force on the body
//! `−μ(v)F̄z` along `+x` (the external load it holds is `F = μ(v)F̄z`, the
//! opposite), so that `P_out = force·v ≥ 0` on either line.

use model_core::model::load_line::{self, best_of, load_line_of, Objective, OperatingPoint};
use serde::Serialize;

use crate::error::{Error, Result};
use crate::motion::law::{Law, LawError};
use crate::scene::ResolvedScene;

/// The load line's summary, the JSON document of `fricctl load-line` (flat; SI units for an SI scene,
/// units of μ0·F̄z, ωW0 and μ0·F̄z·ωW0 for a dimensionless one). Velocities
/// of operating points are signed (negative on the backward line); forces
/// are the contact's force on the body `−μ(v)F̄z` along `+x`.
#[derive(Serialize, Debug, Clone)]
pub struct LoadLineOut {
    /// Contact model: flat | lift-off | sphere | cone | power.
    pub contact: &'static str,
    /// Which load lines the scene has: forward | backward | both | neither.
    pub pushes: &'static str,
    /// Forward stall force −μ(0⁺)/μ0 when positive, else 0 (units μ0·F̄z).
    pub stall_force_over_mu0_fz: f64,
    /// The same in newtons (μ0·F̄z·…).
    pub stall_force: f64,
    /// Forward no-load velocity (0 when the scene does not push forward).
    pub no_load_velocity: f64,
    /// Backward stall force μ(0⁻)/μ0 when positive, else 0.
    pub stall_force_backward_over_mu0_fz: f64,
    /// The same in newtons.
    pub stall_force_backward: f64,
    /// |velocity| of the backward no-load point (0 when it does not push backward).
    pub no_load_velocity_backward: f64,
    /// Largest output power −μ(v)·F̄z·v over both lines (0 when it pushes neither way).
    pub max_power: f64,
    /// forward | backward | none.
    pub direction_at_max_power: &'static str,
    /// Signed velocity of the maximum power point.
    pub velocity_at_max_power: f64,
    /// Contact's force on the body there, −μ/μ0 (units μ0·F̄z, signed).
    pub force_at_max_power_over_mu0_fz: f64,
    /// The same in newtons.
    pub force_at_max_power: f64,
    /// Input power of the two transducers there.
    pub input_power_at_max_power: f64,
    /// Friction loss there.
    pub friction_power_at_max_power: f64,
    /// Efficiency P_out/P_in there.
    pub efficiency_at_max_power: f64,
    /// Largest efficiency P_out/P_in over both lines (0 when it pushes neither way);
    /// with `max_efficiency_at_stall` its limit as v → 0 (the supremum, not attained).
    pub max_efficiency: f64,
    /// Whether the efficiency has no interior maximum: it is largest in the
    /// limit v → 0 at stall, where no power is delivered (the point's velocity
    /// and powers are then 0, its force the stall force). E.g. the flat punch
    /// at φ = 0, a = 0.5, b/a = 2: η → 0.5 as v → 0, decreasing along the line.
    pub max_efficiency_at_stall: bool,
    /// forward | backward | none.
    pub direction_at_max_efficiency: &'static str,
    /// Signed velocity of the maximum efficiency point.
    pub velocity_at_max_efficiency: f64,
    /// Contact's force on the body there, −μ/μ0 (units μ0·F̄z, signed).
    pub force_at_max_efficiency_over_mu0_fz: f64,
    /// The same in newtons.
    pub force_at_max_efficiency: f64,
    /// Output power there.
    pub output_power_at_max_efficiency: f64,
    /// Input power of the two transducers there.
    pub input_power_at_max_efficiency: f64,
    /// Friction loss there.
    pub friction_power_at_max_efficiency: f64,
    /// Mean normal force F̄z (N; kz·uz0 in permanent contact, kz·uz0·⟨w⁺⟩ with lift-off, kz·uz0·D (eq. M5) for a curved profile whose kz is its incremental stiffness 2E*a0; in units of kz·uz0 for a dimensionless scene, whose forces and powers are in units of μ0·F̄z and μ0·F̄z·ωW0).
    pub fz_mean: f64,
    /// Force unit μ0·F̄z (N; 1 for a dimensionless scene).
    pub force_scale: f64,
    /// Velocity unit ωW0 (m/s; 1 for a dimensionless scene).
    pub velocity_scale: f64,
    /// Power unit μ0·F̄z·ωW0 (W; 1 for a dimensionless scene).
    pub power_scale: f64,
    /// Whether values are dimensionless.
    pub dimensionless: bool,
}

/// An operating point in output units (SI or dimensionless).
#[derive(Debug, Clone, Copy, Default, Serialize)]
pub struct Point {
    /// `forward`, `backward` or `none`.
    pub direction: &'static str,
    /// Signed velocity.
    pub v: f64,
    /// The contact's force on the body, −μ/μ0 (units μ0·F̄z).
    pub force_rel: f64,
    /// The same in output units.
    pub force: f64,
    /// Output power.
    pub p_out: f64,
    /// Input power of the two transducers.
    pub p_in: f64,
    /// Friction loss.
    pub p_friction: f64,
    /// Efficiency P_out/P_in.
    pub efficiency: f64,
}

/// The output units: `μ0·F̄z` (N), `ωW0` (m/s), `μ0·F̄z·ωW0` (W); all 1
/// for a dimensionless scene.
#[derive(Debug, Clone, Copy)]
pub struct Units {
    /// Force unit μ0·F̄z.
    pub force: f64,
    /// Velocity unit ωW0.
    pub velocity: f64,
    /// Power unit μ0·F̄z·ωW0.
    pub power: f64,
    /// Whether the scene is dimensionless (all units 1).
    pub dimensionless: bool,
}

impl Units {
    /// An operating point (dimensionless) in these units.
    pub fn point(&self, o: Option<OperatingPoint<f64>>) -> Point {
        o.map_or(
            Point {
                direction: "none",
                ..Point::default()
            },
            |o| Point {
                direction: if o.v > 0.0 { "forward" } else { "backward" },
                v: o.v * self.velocity,
                force_rel: o.force,
                force: o.force * self.force,
                p_out: o.powers.output * self.power,
                p_in: o.powers.input * self.power,
                p_friction: o.powers.friction * self.power,
                efficiency: o.powers.efficiency(),
            },
        )
    }

    /// Unit names of force, velocity and power.
    pub fn names(&self) -> (&'static str, &'static str, &'static str) {
        if self.dimensionless {
            ("μ0·F̄z", "ωW0", "μ0·F̄z·ωW0")
        } else {
            ("N", "m/s", "W")
        }
    }
}

/// One sample of a load line: dimensionless velocity (signed) and powers.
pub type Sample = (f64, load_line::Powers<f64>);

/// A maximum-efficiency point closer to stall than this fraction of its
/// line's no-load velocity is the stall limit: [`best_of`]'s search brackets
/// a maximum in the first of its 64 cells down to 1e-6 of the cell
/// (1.6e-8·v_nl) and converges there only when the efficiency keeps rising
/// towards v → 0; an interior maximum this close to stall would be at no
/// plotted or printed resolution anyway.
pub const STALL_LIMIT: f64 = 1e-6;

/// A computed load line: the summary, and what plotting and sampling need.
pub struct Analysis {
    /// The summary.
    pub out: LoadLineOut,
    /// The contact's law μ(v).
    pub law: Law,
    /// The line(s), dimensionless.
    pub line: load_line::LoadLine<f64>,
    /// The maximum-power point (None when the scene pushes neither way).
    pub best_power: Option<OperatingPoint<f64>>,
    /// The maximum-efficiency point (as found, at a velocity ≤ [`STALL_LIMIT`]·v_nl
    /// when `out.max_efficiency_at_stall`).
    pub best_efficiency: Option<OperatingPoint<f64>>,
    /// The maximum-power point in output units.
    pub power_point: Point,
    /// The maximum-efficiency point in output units (the stall limit when
    /// `out.max_efficiency_at_stall`).
    pub efficiency_point: Point,
    /// The output units.
    pub units: Units,
    /// Mean normal force F̄z (N, or units of kz·uz0).
    pub fz: f64,
}

/// The load line of a scene (any contact: resolve it with
/// `ContactMode::Intermittent` to admit lift-off).
///
/// # Errors
/// A solver failure (one line).
pub fn analyse(rs: &ResolvedScene) -> Result<Analysis> {
    let s = &rs.scene;
    let p = s.params();
    let law = Law::with_profile(s, rs.profile);
    let normal = law
        .mean_normal()
        .map_err(|e| Error::failure(e.to_string()))?;
    let fz = p.kz * p.uz0 * normal;
    // Dimensionless scenes report forces in units of μ0·F̄z (F̄z = 1 unit).
    let force_scale = if rs.dimensionless { 1.0 } else { s.mu0() * fz };
    let vs = s.velocity_scale();
    let units = Units {
        force: force_scale,
        velocity: vs,
        power: force_scale * vs,
        dimensionless: rs.dimensionless,
    };
    let fail = |e: LawError| Error::failure(e.to_string());
    // The solver's own tolerance: its best bound (the law retries with it).
    let tol = 1e-12;
    let zero = law.at(0.0, tol).map_err(fail)?;
    let (cf, cb) = law.critical().map_err(fail)?;
    let line = load_line_of(zero.upper, zero.lower, cf, cb, |v| {
        law.mu(v, tol).map(|m| m.0)
    })
    .map_err(fail)?;
    let best_p = best_of(&line, Objective::Power, |v| law.powers(v)).map_err(fail)?;
    let best_e = best_of(&line, Objective::Efficiency, |v| law.powers(v)).map_err(fail)?;
    let (mp, mut me) = (units.point(best_p), units.point(best_e));
    // No interior maximum: report the stall limit (velocity and powers 0, the
    // stall force; η its limit, to the search's O(1e-8·v_nl) in velocity).
    let at_stall = best_e.is_some_and(|o| {
        let vnl = if o.v > 0.0 {
            line.no_load_forward
        } else {
            line.no_load_backward
        };
        o.v.abs() <= STALL_LIMIT * vnl
    });
    if at_stall {
        let stall = if me.v > 0.0 {
            line.stall_forward
        } else {
            -line.stall_backward
        };
        me = Point {
            v: 0.0,
            force_rel: stall,
            force: stall * force_scale,
            p_out: 0.0,
            p_in: 0.0,
            p_friction: 0.0,
            ..me
        };
    }
    let pushes = match (line.no_load_forward > 0.0, line.no_load_backward > 0.0) {
        (true, true) => "both",
        (true, false) => "forward",
        (false, true) => "backward",
        (false, false) => "neither",
    };
    let o = LoadLineOut {
        contact: law.name(),
        pushes,
        stall_force_over_mu0_fz: line.stall_forward,
        stall_force: line.stall_forward * force_scale,
        no_load_velocity: line.no_load_forward * vs,
        stall_force_backward_over_mu0_fz: line.stall_backward,
        stall_force_backward: line.stall_backward * force_scale,
        no_load_velocity_backward: line.no_load_backward * vs,
        max_power: mp.p_out,
        direction_at_max_power: mp.direction,
        velocity_at_max_power: mp.v,
        force_at_max_power_over_mu0_fz: mp.force_rel,
        force_at_max_power: mp.force,
        input_power_at_max_power: mp.p_in,
        friction_power_at_max_power: mp.p_friction,
        efficiency_at_max_power: mp.efficiency,
        max_efficiency: me.efficiency,
        max_efficiency_at_stall: at_stall,
        direction_at_max_efficiency: me.direction,
        velocity_at_max_efficiency: me.v,
        force_at_max_efficiency_over_mu0_fz: me.force_rel,
        force_at_max_efficiency: me.force,
        output_power_at_max_efficiency: me.p_out,
        input_power_at_max_efficiency: me.p_in,
        friction_power_at_max_efficiency: me.p_friction,
        fz_mean: fz,
        force_scale,
        velocity_scale: vs,
        power_scale: units.power,
        dimensionless: rs.dimensionless,
    };
    Ok(Analysis {
        out: o,
        law,
        line,
        best_power: best_p,
        best_efficiency: best_e,
        power_point: mp,
        efficiency_point: me,
        units,
        fz,
    })
}

/// Samples of every load line the scene has: `n` velocities each, at
/// `±v_nl·i/n` (`i = 1…n`, the no-load point included, `v = 0` left out:
/// the stall is the limit there), backward line first, in increasing `v`.
pub fn sample_lines(
    law: &Law,
    line: &load_line::LoadLine<f64>,
    n: usize,
) -> Result<Vec<Vec<Sample>>, LawError> {
    let mut lines = Vec::new();
    for (vnl, sign) in [(line.no_load_backward, -1.0), (line.no_load_forward, 1.0)] {
        if vnl <= 0.0 {
            continue;
        }
        let mut l = Vec::with_capacity(n);
        for i in 1..=n {
            let v = sign * vnl * i as f64 / n as f64;
            l.push((v, law.powers(v)?));
        }
        if sign < 0.0 {
            l.reverse();
        }
        lines.push(l);
    }
    Ok(lines)
}
