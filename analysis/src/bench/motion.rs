//! The slow-dynamics bench: homogenised against resolved, the quasi-static
//! drift map and the load lines of the paper's Fig. 6 (`fricctl bench
//! motion` writes the CSV files and charts).
//!
//! * [`ErrorCost`]: homogenised against resolved on the paper's Fig. 7
//!   ratchet (Δu_z/u_z0 = 0.5, ratio 0.5, φ = 0) and on a lift-off scene
//!   (Δu_z/u_z0 = 1.5, Δu_x k_x/(μ0 k_z u_z0) = 0.75, φ = 34.4°), both under
//!   `F = 0.5 μ0F̄z sin Ωt`: the relative difference `|H − R|/|R|` over the
//!   scale separation ω/Ω = 10…3·10⁴ (to 10⁶ with `full`) at three body
//!   responses `Mω Ω/k_x` (lift-off: to 10⁴), over the body's response time
//!   in ultrasonic periods at ω/Ω = 10³, and the wall time of each model.
//!   The resolved model is the reference; where `|H − R|` is below the
//!   runs' stated numerical error the difference is not resolved
//!   ([`Comparison::below_floor`]).
//! * [`drift_map`]: the quasi-static drift (`M = 0`, homogenised, μ⁻¹ of the
//!   force) over (φ, ratio) at Δu_z/u_z0 = 0.5 under `F = 0.5 μ0F̄z sin Ωt`,
//!   in units of ωW₀.
//! * [`fig6_load_line`]: the load lines of the paper's Fig. 6 scenes
//!   (Δu_z/u_z0 = 0.5, ratio 2, φ = [`FIG6_PHIS_DEG`]; 90° is not symmetric at
//!   this ratio and pushes backward weakly, stall force 0.0348 μ0F̄z):
//!   force–velocity, output power and efficiency, each in the direction the
//!   scene pushes.
//!
//! Everything is dimensionless (velocities in ωW₀, forces in μ0F̄z, masses in
//! k_x/ω²).

use std::f64::consts::TAU;
use std::time::Instant;

use model_core::model::load_line::{best_forward, load_line, powers, Objective};
use model_core::scene::ContactMode;
use model_core::{Groups, Libm, Scene};

use crate::error::{Error, Result};
use crate::eval::exact_failure;
use crate::grid::centres;
use crate::motion::law::Law;
use crate::motion::table::{MuTable, TableError};
use crate::motion::{estimate, homogenised, relaxation_per_period, resolved, Problem};

/// Force amplitude of every chart, units μ0F̄z.
pub const FORCE: f64 = 0.5;
/// Tolerance of the runs, relative to the larger critical velocity.
pub const TOL: f64 = 1e-4;
/// Relative error above which homogenisation counts as failed.
pub const FAIL: f64 = 0.1;

/// The lift-off scene's resolved runs stop at ω/Ω = 10⁴: beyond, |H − R| is
/// below the resolved model's numerical error (its grid does not land
/// exactly, a first-order error) and each run costs seconds.
pub const LIFT_OFF_MAX_INV_NU: f64 = 1e4;

fn scene_err(e: model_core::SceneError) -> Error {
    Error::failure(format!("bench scene: {e}"))
}

/// A scene with its law and table.
struct Case {
    name: &'static str,
    law: Law,
    table: MuTable,
    table_time: f64,
}

impl Case {
    fn new(name: &'static str, scene: Scene<f64>) -> Result<Self> {
        let law = Law::of(&scene);
        let t0 = Instant::now();
        let table =
            MuTable::new(&law, 0.02 * TOL).map_err(|e| Error::failure(format!("{name}: {e}")))?;
        Ok(Case {
            name,
            law,
            table,
            table_time: t0.elapsed().as_secs_f64(),
        })
    }

    fn v_ref(&self) -> f64 {
        self.table.c_forward.max(self.table.c_backward)
    }
}

/// One comparison of the two models at a scale separation and a mass.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Comparison {
    /// Scale separation ω/Ω.
    pub inv_nu: f64,
    /// Body mass, units k_x/ω².
    pub mass: f64,
    /// Body response time in ultrasonic periods, `m̃S/(2πn̄)`.
    pub response: f64,
    /// Homogenised mean velocity H, units ωW₀.
    pub h: f64,
    /// The homogenised run's numerical error (integration and table
    /// interpolation), units ωW₀.
    pub h_numerical: f64,
    /// The derived estimate of the homogenisation error E_h, units ωW₀.
    pub e_h: f64,
    /// Wall time of the homogenised model (table and run), s.
    pub h_time: f64,
    /// Resolved mean velocity R (the reference), units ωW₀.
    pub r: f64,
    /// The resolved run's numerical error, units ωW₀.
    pub r_numerical: f64,
    /// Wall time of the resolved model, s.
    pub r_time: f64,
    /// Steps per period of the resolved run.
    pub r_steps: u64,
    /// Whether both runs reached a periodic state.
    pub periodic: bool,
}

impl Comparison {
    /// `|H − R|/|R|`.
    pub fn rel(&self) -> f64 {
        (self.h - self.r).abs() / self.r.abs()
    }
    /// The difference is not resolved: below the reference's numerical error.
    pub fn below_floor(&self) -> bool {
        (self.h - self.r).abs() <= self.r_numerical + self.h_numerical
    }
    /// E_h with both runs' numerical errors covers `|H − R|`.
    pub fn covered(&self) -> bool {
        (self.h - self.r).abs() <= self.e_h + self.h_numerical + self.r_numerical
    }
}

/// One comparison still to run ([`ErrorCost::runs`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Run {
    /// `flat` or `lift-off`.
    pub case: &'static str,
    /// `mnu=<MωΩ/k_x>` (the sweep over ω/Ω) or `mass` (the sweep over M).
    pub sweep: String,
    /// Scale separation ω/Ω.
    pub inv_nu: f64,
    /// Body mass, units k_x/ω².
    pub mass: f64,
    /// What runs, for a progress line.
    pub message: String,
}

/// One row of the error–cost CSV: a run and its comparison.
#[derive(Debug, Clone, PartialEq)]
pub struct Row {
    /// `flat` or `lift-off`.
    pub case: &'static str,
    /// As [`Run::sweep`].
    pub sweep: String,
    /// The comparison.
    pub point: Comparison,
}

/// The error–cost comparison: its two scenes (with their μ tables) and grids.
pub struct ErrorCost {
    flat: Case,
    lift: Case,
    /// Scale separations ω/Ω.
    pub inv: Vec<f64>,
    /// Body responses `Mω Ω/k_x`.
    pub responses: [f64; 3],
    /// Masses of the mass sweep (at ω/Ω = 10³), units k_x/ω².
    pub masses: Vec<f64>,
}

impl ErrorCost {
    /// The scenes and grids; `full` adds ω/Ω = 10⁵ … 10⁶.
    pub fn new(full: bool) -> Result<Self> {
        let flat = Case::new(
            "flat",
            Scene::dimensionless(Groups::from_ratio(0.5, 0.5, 0.0).map_err(scene_err)?)
                .map_err(scene_err)?,
        )?;
        let lift = Case::new(
            "lift-off",
            Scene::dimensionless_with_contact(
                Groups {
                    duz_rel: 1.5,
                    dux_rel: 0.75,
                    phi: 0.6,
                },
                ContactMode::Intermittent,
            )
            .map_err(scene_err)?,
        )?;
        let mut inv = vec![10.0, 30.0, 100.0, 300.0, 1e3, 3e3, 1e4, 3e4];
        if full {
            inv.extend([1e5, 3e5, 1e6]);
        }
        let masses = vec![3.0, 10.0, 30.0, 100.0, 300.0, 1e3, 3e3, 1e4, 1e5];
        Ok(ErrorCost {
            flat,
            lift,
            inv,
            responses: [0.1, 1.0, 10.0],
            masses,
        })
    }

    /// Every comparison in the CSV's order: flat over ω/Ω at each response,
    /// lift-off over ω/Ω to [`LIFT_OFF_MAX_INV_NU`], then both over the mass.
    pub fn runs(&self) -> Vec<Run> {
        let mut runs = Vec::new();
        for &mn in &self.responses {
            for &i in &self.inv {
                runs.push(Run {
                    case: self.flat.name,
                    sweep: format!("mnu={mn}"),
                    inv_nu: i,
                    mass: mn * i,
                    message: format!("flat, ω/Ω = {i:.0e}, MωΩ/k_x = {mn}"),
                });
            }
        }
        for &i in self.inv.iter().filter(|&&i| i <= LIFT_OFF_MAX_INV_NU) {
            runs.push(Run {
                case: self.lift.name,
                sweep: "mnu=1".into(),
                inv_nu: i,
                mass: i,
                message: format!("lift-off, ω/Ω = {i:.0e}"),
            });
        }
        for c in [&self.flat, &self.lift] {
            for &m in &self.masses {
                runs.push(Run {
                    case: c.name,
                    sweep: "mass".into(),
                    inv_nu: 1e3,
                    mass: m,
                    message: format!("{}, Mω²/k_x = {m:.0e}", c.name),
                });
            }
        }
        runs
    }

    /// Runs one comparison.
    pub fn measure(&self, run: &Run) -> Result<Row> {
        let c = if run.case == self.flat.name {
            &self.flat
        } else {
            &self.lift
        };
        Ok(Row {
            case: c.name,
            sweep: run.sweep.clone(),
            point: compare(c, run.inv_nu, run.mass)?,
        })
    }
}

/// The homogenised and the resolved model under `F = FORCE sin Ωt`, no spring.
fn compare(c: &Case, inv_nu: f64, mass: f64) -> Result<Comparison> {
    let tick: &mut dyn FnMut() = &mut || {};
    let p = Problem {
        f0: 0.0,
        f: FORCE,
        nu: 1.0 / inv_nu,
        mass,
        kappa: 0.0,
        normal: c
            .law
            .mean_normal()
            .map_err(|e| Error::failure(format!("{}: {e}", c.name)))?,
    };
    let tol = 0.1 * TOL * c.v_ref();
    let relaxation = relaxation_per_period(&p, estimate::inverse_slope(&c.table));
    let t0 = Instant::now();
    let h = homogenised::run(
        &p,
        &c.table,
        &homogenised::Settings {
            tol,
            periods: None,
            max_periods: 2000,
            relaxation,
            min_steps: 0,
            budget: u64::MAX,
        },
        tick,
    );
    let h_time = t0.elapsed().as_secs_f64() + c.table_time;
    let e_h = estimate::homogenisation_error(&p, c.law.spring_bounds(), &c.table, &h);
    let t0 = Instant::now();
    let r = resolved::run(
        &p,
        &c.law.scene().drive(),
        c.law.exponent(),
        &resolved::Settings {
            tol,
            periods: None,
            max_periods: 2000,
            relaxation,
            budget: u64::MAX,
        },
        tick,
    );
    Ok(Comparison {
        inv_nu,
        mass,
        response: mass * estimate::inverse_slope(&c.table) / (TAU * p.normal),
        h: h.mean_velocity,
        h_numerical: h.numerical_error
            + c.table.interpolation_error * estimate::inverse_slope(&c.table),
        e_h,
        h_time,
        r: r.mean_velocity,
        r_numerical: r.numerical_error,
        r_time: t0.elapsed().as_secs_f64(),
        r_steps: r.steps,
        periodic: h.periodic && r.periodic,
    })
}

/// What one cell of the drift map gave.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Drift {
    /// The drift.
    Ok {
        /// Mean velocity, units ωW₀ (signed).
        mean_velocity: f64,
        /// Fraction of the time the contact sticks.
        stick_fraction: f64,
    },
    /// The μ(v) law is not monotone: no homogenised table.
    NotMonotone,
    /// The table could not be built otherwise.
    Failed,
}

/// One cell of the drift map.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DriftCell {
    /// φ, degrees.
    pub phi_deg: f64,
    /// k_xΔu_x/(μ0k_zΔu_z).
    pub ratio: f64,
    /// What the cell gave.
    pub drift: Drift,
}

/// The drift map: cell centres of φ (degrees, 0 … 360) and of
/// log10(ratio) (−1 … 1), and the cells row-major (ratio rows, φ columns).
#[derive(Debug, Clone, PartialEq)]
pub struct DriftMap {
    /// φ of the columns, degrees.
    pub phis_deg: Vec<f64>,
    /// log10 of the ratio of the rows.
    pub log_ratios: Vec<f64>,
    /// The cells.
    pub cells: Vec<DriftCell>,
}

impl DriftMap {
    /// The smallest and largest mean velocity (0 included), units ωW₀.
    pub fn range(&self) -> (f64, f64) {
        self.cells
            .iter()
            .filter_map(|c| match c.drift {
                Drift::Ok { mean_velocity, .. } => Some(mean_velocity),
                _ => None,
            })
            .fold((0.0f64, 0.0f64), |(lo, hi), v| (lo.min(v), hi.max(v)))
    }
}

/// The quasi-static drift over (φ, ratio), `res` cells per axis, at
/// Δu_z/u_z0 = 0.5 under `F = FORCE sin Ωt` (f0 = 0, M = 0); `tick` after
/// each cell.
pub fn drift_map(res: usize, tick: &mut dyn FnMut()) -> Result<DriftMap> {
    let phis_deg = centres(0.0, 360.0, res);
    let log_ratios = centres(-1.0, 1.0, res);
    let mut cells = Vec::with_capacity(res * res);
    for &l in &log_ratios {
        let ratio = 10f64.powf(l);
        for &phi_deg in &phis_deg {
            cells.push(DriftCell {
                phi_deg,
                ratio,
                drift: drift_cell(phi_deg, ratio)?,
            });
            tick();
        }
    }
    Ok(DriftMap {
        phis_deg,
        log_ratios,
        cells,
    })
}

/// The drift at one (φ, ratio): the homogenised model on a 10⁻⁶ table.
fn drift_cell(phi_deg: f64, ratio: f64) -> Result<Drift> {
    let g = Groups::from_ratio(0.5, ratio, phi_deg.to_radians()).map_err(scene_err)?;
    let law = Law::of(&Scene::dimensionless(g).map_err(scene_err)?);
    Ok(match MuTable::new(&law, 1e-6) {
        Ok(t) => {
            let p = Problem {
                f0: 0.0,
                f: FORCE,
                nu: 1e-3,
                mass: 0.0,
                kappa: 0.0,
                normal: 1.0,
            };
            let r = homogenised::run(
                &p,
                &t,
                &homogenised::Settings {
                    tol: 1e-6,
                    periods: None,
                    max_periods: 10,
                    relaxation: 0.0,
                    min_steps: 0,
                    budget: u64::MAX,
                },
                &mut || {},
            );
            Drift::Ok {
                mean_velocity: r.mean_velocity,
                stick_fraction: r.stick_fraction,
            }
        }
        Err(TableError::NotMonotone { .. }) => Drift::NotMonotone,
        Err(_) => Drift::Failed,
    })
}

/// The phases of the Fig. 6 scenes, degrees.
pub const FIG6_PHIS_DEG: [f64; 5] = [0.0, 45.0, 90.0, 135.0, 180.0];

/// Points of a load line between stall and no load (exclusive).
pub const LOAD_LINE_POINTS: usize = 200;

/// One point of a load line, in the direction the scene pushes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LoadPoint {
    /// |v|, units ωW₀.
    pub v: f64,
    /// The load held, −μ(v)/μ0 (units μ0F̄z).
    pub load: f64,
    /// Output power, units μ0F̄zωW₀.
    pub p_out: f64,
    /// Input power of the tangential transducer, units μ0F̄zωW₀.
    pub p_in: f64,
    /// P_out/P_in.
    pub efficiency: f64,
}

/// The load line of one Fig. 6 scene (the exact steady state).
#[derive(Debug, Clone, PartialEq)]
pub struct Fig6Line {
    /// φ, degrees.
    pub phi_deg: f64,
    /// `forward` or `backward`: the direction the scene pushes.
    pub dir: &'static str,
    /// +1 forward, −1 backward (the sign of the CSV's v).
    pub sign: f64,
    /// Stall force, units μ0F̄z.
    pub stall: f64,
    /// No-load velocity, units ωW₀.
    pub no_load: f64,
    /// Largest output power, units μ0F̄zωW₀.
    pub best_power: f64,
    /// Largest efficiency.
    pub best_efficiency: f64,
    /// [`LOAD_LINE_POINTS`] − 1 points at `v = no_load·i/200`, i = 1 … 199.
    pub points: Vec<LoadPoint>,
}

/// The load line of the Fig. 6 scene at `phi_deg` (Δu_z/u_z0 = 0.5, ratio 2):
/// a backward pusher is computed as the mirrored drive's forward line
/// (μ(−v; φ) = −μ(v; φ + π)).
pub fn fig6_load_line(phi_deg: f64) -> Result<Fig6Line> {
    let d0 = Scene::dimensionless(
        Groups::from_ratio(0.5, 2.0, phi_deg.to_radians()).map_err(scene_err)?,
    )
    .map_err(scene_err)?
    .drive();
    let line0 = load_line::<f64, Libm>(&d0).map_err(exact_failure)?;
    let (d, dir, sign) = if line0.no_load_forward > 0.0 {
        (d0, "forward", 1.0)
    } else {
        (d0.mirrored(), "backward", -1.0)
    };
    let line = load_line::<f64, Libm>(&d).map_err(exact_failure)?;
    let best_power = best_forward::<f64, Libm>(&d, &line, Objective::Power)
        .map_err(exact_failure)?
        .map_or(0.0, |o| o.powers.output);
    let best_efficiency = best_forward::<f64, Libm>(&d, &line, Objective::Efficiency)
        .map_err(exact_failure)?
        .map_or(0.0, |o| o.powers.efficiency());
    let nl = line.no_load_forward;
    let mut points = Vec::with_capacity(LOAD_LINE_POINTS);
    for i in 1..LOAD_LINE_POINTS {
        let v = nl * i as f64 / LOAD_LINE_POINTS as f64;
        let pw = powers::<f64, Libm>(&d, v).map_err(exact_failure)?;
        points.push(LoadPoint {
            v,
            load: -pw.mu_over_mu0,
            p_out: pw.output,
            p_in: pw.input,
            efficiency: pw.efficiency(),
        });
    }
    Ok(Fig6Line {
        phi_deg,
        dir,
        sign,
        stall: line.stall_forward,
        no_load: nl,
        best_power,
        best_efficiency,
        points,
    })
}
