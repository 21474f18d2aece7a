//! `fricctl static`: critical velocities, the exact static interval and
//! static friction beside the paper's eqs. 18/19.

use std::io::Write;

use clap::Args;
use model_core::analytic::{CriticalVelocity, StaticFriction};
use model_core::model::liftoff;
use model_core::scene::ContactMode;
use model_core::{exact, Libm, Scene};
use serde::Serialize;

use crate::args::{round_up_sig, Rounded, Short};
use crate::error::CliResult;
use crate::eval::{exact_failure, lift_off_failure, mean_normal_force_over_kz_uz0};
use crate::output::{stdout_error, write_json};
use crate::scene_args::SceneArgs;

/// Flags of `fricctl static`.
#[derive(Args, Debug, Clone)]
pub struct StaticCmd {
    #[command(flatten)]
    scene: SceneArgs,
    /// JSON output
    #[arg(long)]
    json: bool,
}

/// The JSON document of `fricctl static` (keys are part of the CLI contract).
#[derive(Serialize)]
struct StaticOut {
    vc_forward: f64,
    vc_backward: f64,
    static_exists: bool,
    /// Exact static interval of the equilibrium displacement u_x0, m (null when empty).
    interval_lo_m: Option<f64>,
    interval_hi_m: Option<f64>,
    /// The interval ends over W0 = μ0 k_z u_z0/k_x (lo = c' − 1, hi = 1 − c), also when lo > hi.
    lo_over_w0: f64,
    hi_over_w0: f64,
    mu_s_forward_over_mu0: Option<f64>,
    mu_s_backward_over_mu0: Option<f64>,
    paper_eq18_forward_over_mu0: f64,
    paper_eq19_backward_over_mu0: f64,
    mu_0plus_over_mu0: f64,
    mu_0minus_over_mu0: f64,
    w0_m: f64,
    lifts_off: bool,
}

/// The JSON document of `fricctl static` for a contact that lifts off: no
/// static interval exists; the force at rest is unique.
#[derive(Serialize)]
struct LiftOffStaticOut {
    /// Always true here.
    lifts_off: bool,
    /// Always false: the state resets at every landing.
    static_exists: bool,
    /// μ(0)/μ0, the unique force at rest over μ0⟨f_z⟩.
    mu_at_rest_over_mu0: f64,
    /// Its bound, units of μ0 (the lift-off solver's).
    error_bound_over_mu0: f64,
    /// ⟨f_z⟩/(k_z u_z0) = ⟨u_z⁺⟩/u_z0 (eq. L4).
    mean_normal_force_over_kz_uz0: f64,
    /// The contact window's critical velocities (eq. L5), m/s.
    vc_forward: f64,
    vc_backward: f64,
    w0_m: f64,
}

impl StaticCmd {
    /// Runs the command.
    pub fn run(self, out: &mut impl Write) -> CliResult {
        let rs = self.scene.resolve_with(ContactMode::Intermittent)?;
        let s = &rs.scene;
        if rs.profile != model_core::mdr::Profile::Flat {
            return self.curved(&rs, out);
        }
        if s.lifts_off() {
            return self.lift_off(s, out, Units::of(rs.dimensionless));
        }
        let vc = CriticalVelocity::of(s);
        let st = StaticFriction::of(s);
        let (p, m) = exact::limits_at_zero::<f64, Libm>(&s.drive()).map_err(exact_failure)?;
        let iv = st.interval_m(s);
        let o = StaticOut {
            vc_forward: vc.forward,
            vc_backward: vc.backward,
            static_exists: st.exists(),
            interval_lo_m: iv.map(|x| x.0),
            interval_hi_m: iv.map(|x| x.1),
            lo_over_w0: st.lo,
            hi_over_w0: st.hi,
            mu_s_forward_over_mu0: st.mu_s_forward_over_mu0(),
            mu_s_backward_over_mu0: st.mu_s_backward_over_mu0(),
            paper_eq18_forward_over_mu0: st.paper_eq18_forward,
            paper_eq19_backward_over_mu0: st.paper_eq19_backward,
            mu_0plus_over_mu0: p,
            mu_0minus_over_mu0: m,
            w0_m: s.w0(),
            lifts_off: false,
        };
        if self.json {
            return write_json(out, &o);
        }
        write_text(out, &o, iv, &st, Units::of(rs.dimensionless)).map_err(stdout_error)
    }

    /// With lift-off "static friction" has no permanent-contact meaning: the
    /// stretch resets at every landing, so a body held at rest feels one
    /// force, μ(0)·⟨f_z⟩, whatever its history (`model_core::model::liftoff`).
    fn lift_off(&self, s: &Scene<f64>, out: &mut impl Write, u: Units) -> CliResult {
        let d = s.drive();
        let mu = liftoff::mu_over_mu0::<f64, Libm>(&d, 0.0).map_err(lift_off_failure)?;
        let (c, cb) = liftoff::critical_velocities::<f64, Libm>(&d).map_err(lift_off_failure)?;
        let unit = s.velocity_scale();
        let o = LiftOffStaticOut {
            lifts_off: true,
            static_exists: false,
            mu_at_rest_over_mu0: mu,
            error_bound_over_mu0: liftoff::error_bound::<f64, Libm>(&d),
            mean_normal_force_over_kz_uz0: mean_normal_force_over_kz_uz0(s),
            vc_forward: c * unit,
            vc_backward: cb * unit,
            w0_m: s.w0(),
        };
        if self.json {
            return write_json(out, &o);
        }
        write_lift_off_text(out, &o, s, u).map_err(stdout_error)
    }
}

/// The JSON document of `fricctl static` for a curved profile (MDR): the
/// static interval as held forces over μ0 times the mean normal force.
#[derive(Serialize)]
struct ProfileStaticOut {
    /// `sphere`, `cone` or `power`.
    profile: &'static str,
    /// The profile's exponent n.
    exponent: Option<f64>,
    /// The central spring lifts off (duz ≥ uz0): every spring is
    /// intermittent and the force at rest is unique.
    lifts_off: bool,
    /// The static interval has a width (eq. S2).
    static_exists: bool,
    /// The interval's ends μ(0−)/μ0 and μ(0+)/μ0 (null without a width).
    static_lo_over_mu0: Option<f64>,
    static_hi_over_mu0: Option<f64>,
    /// The body held with zero force rests on average (0 in the interval).
    rests_free: bool,
    mu_0plus_over_mu0: f64,
    mu_0minus_over_mu0: f64,
    /// The larger bound of the two limits, units of μ0 (MDR quadrature).
    error_bound_over_mu0: f64,
    /// The critical velocities (the flat punch's with the same drive, eq. S1), m/s.
    vc_forward: f64,
    vc_backward: f64,
    w0_m: f64,
}

impl StaticCmd {
    /// A curved profile (docs/guide/lift-off-and-profiles.md, eqs. S1–S4).
    fn curved(&self, rs: &crate::scene_args::ResolvedScene, out: &mut impl Write) -> CliResult {
        let s = &rs.scene;
        let st = fric_analysis::eval::profile_statics(s, &rs.profile)?;
        let unit = s.velocity_scale();
        let exists = st.exists;
        let o = ProfileStaticOut {
            profile: rs.profile.name(),
            exponent: rs.profile.exponent(),
            lifts_off: s.lifts_off(),
            static_exists: exists,
            static_lo_over_mu0: exists.then_some(st.mu_0minus),
            static_hi_over_mu0: exists.then_some(st.mu_0plus),
            rests_free: st.mu_0minus <= 0.0 && 0.0 <= st.mu_0plus,
            mu_0plus_over_mu0: st.mu_0plus,
            mu_0minus_over_mu0: st.mu_0minus,
            error_bound_over_mu0: st.bound,
            vc_forward: st.c_forward * unit,
            vc_backward: st.c_backward * unit,
            w0_m: s.w0(),
        };
        if self.json {
            return write_json(out, &o);
        }
        write_profile_text(out, &o, &rs.profile, Units::of(rs.dimensionless)).map_err(stdout_error)
    }
}

fn write_profile_text(
    out: &mut impl Write,
    o: &ProfileStaticOut,
    p: &model_core::mdr::Profile<f64>,
    u: Units,
) -> std::io::Result<()> {
    let b = Short(round_up_sig(o.error_bound_over_mu0, 3));
    writeln!(
        out,
        "profile                {} (MDR quadrature over the springs; bound {b} mu0)",
        crate::scene_args::profile_text(p)
    )?;
    write_vc(
        out,
        (o.vc_forward, o.vc_backward),
        u.velocity,
        " (the flat punch's with the same drive, eq. S1)",
    )?;
    if o.lifts_off {
        writeln!(
            out,
            "static interval        none: the central spring lifts off too (duz >= uz0), every spring's stretch resets at its landing"
        )?;
        return writeln!(
            out,
            "force at rest          unique: mu(0)/mu0 = {} (± {b})",
            Rounded(o.mu_0plus_over_mu0)
        );
    }
    match (o.static_lo_over_mu0, o.static_hi_over_mu0) {
        (Some(lo), Some(hi)) => writeln!(
            out,
            "static interval        rests on average when held at mu/mu0 in [{}, {}] (± {b}); free (zero force), it {}",
            Rounded(lo),
            Rounded(hi),
            free_text(o.rests_free)
        )?,
        _ => writeln!(
            out,
            "static interval        none: it slips at every held force (c + c' > 2 at the central spring, eq. S2)"
        )?,
    }
    writeln!(
        out,
        "mu(0+)/mu0             {} (± {b}; mu: held force over the mean normal force)",
        Rounded(o.mu_0plus_over_mu0)
    )?;
    writeln!(
        out,
        "mu(0-)/mu0             {} (± {b})",
        Rounded(o.mu_0minus_over_mu0)
    )
}

/// Units of the text output: SI, or the scene's own for a dimensionless one.
#[derive(Clone, Copy)]
struct Units {
    length: &'static str,
    velocity: &'static str,
    force: &'static str,
    tangential: &'static str,
}

impl Units {
    fn of(dimensionless: bool) -> Self {
        if dimensionless {
            Units {
                length: "W0",
                velocity: "ωW0",
                force: "kz uz0",
                tangential: "μ0 kz uz0",
            }
        } else {
            Units {
                length: "m",
                velocity: "m/s",
                force: "N",
                tangential: "N",
            }
        }
    }
}

fn write_lift_off_text(
    out: &mut impl Write,
    o: &LiftOffStaticOut,
    s: &Scene<f64>,
    u: Units,
) -> std::io::Result<()> {
    let p = s.params();
    writeln!(
        out,
        "contact                lifts off once per period (duz/uz0 = {} >= 1)",
        Rounded(s.drive().a)
    )?;
    writeln!(
        out,
        "static interval        none in the permanent-contact sense: the stretch resets at every landing"
    )?;
    writeln!(
        out,
        "force at rest          unique: mu(0)/mu0 = {} (error bound {} mu0)",
        Rounded(o.mu_at_rest_over_mu0),
        Short(round_up_sig(o.error_bound_over_mu0, 3))
    )?;
    writeln!(
        out,
        "mean normal force      kz<uz+> = {} kz uz0 = {} {}",
        Rounded(o.mean_normal_force_over_kz_uz0),
        Rounded(o.mean_normal_force_over_kz_uz0 * p.kz * p.uz0),
        u.force
    )?;
    writeln!(
        out,
        "tangential at rest     mu(0)*<fz> = {} {}",
        Rounded(o.mu_at_rest_over_mu0 * s.mu0() * o.mean_normal_force_over_kz_uz0 * p.kz * p.uz0),
        u.tangential
    )?;
    write_vc(
        out,
        (o.vc_forward, o.vc_backward),
        u.velocity,
        " (contact window, eq. L5)",
    )
}

/// The two critical-velocity lines (`note` follows the forward one).
fn write_vc(
    out: &mut impl Write,
    (forward, backward): (f64, f64),
    unit: &str,
    note: &str,
) -> std::io::Result<()> {
    writeln!(
        out,
        "v_c forward            {} {unit}{note}",
        Rounded(forward)
    )?;
    writeln!(out, "v_c backward           {} {unit}", Rounded(backward))
}

/// What a body held with zero force does: it rests when 0 lies in the
/// static interval, otherwise it is an actuator.
fn free_text(rests: bool) -> &'static str {
    if rests {
        "rests"
    } else {
        "moves (an actuator)"
    }
}

fn write_text(
    out: &mut impl Write,
    o: &StaticOut,
    iv: Option<(f64, f64)>,
    st: &StaticFriction<f64>,
    u: Units,
) -> std::io::Result<()> {
    write_vc(out, (o.vc_forward, o.vc_backward), u.velocity, "")?;
    // The static interval (paper §2.2): the spring stretches u_x0, and so the
    // held forces k_x u_x0 = mu/mu0 · μ0 k_z u_z0, at which the contact
    // sticks. Its ends are μ(0−) and μ(0+); an actuator may have one (0
    // outside it) or none (c + c' > 2).
    match iv {
        Some((lo, hi)) => {
            writeln!(
                out,
                "static interval u_x0   [{}, {}] {} (sticks when held there)",
                Rounded(lo),
                Rounded(hi),
                u.length
            )?;
            writeln!(
                out,
                "held force mu/mu0      [{}, {}]: free (zero force), it {}",
                Rounded(st.lo),
                Rounded(st.hi),
                free_text(st.lo <= 0.0 && 0.0 <= st.hi)
            )?;
        }
        None => writeln!(
            out,
            "static interval u_x0   empty (lo = {} W0 > hi = {} W0): slips at every held force",
            Rounded(st.lo),
            Rounded(st.hi)
        )?,
    }
    // μ_s± as the paper writes them (eqs. 18/19): the largest force that
    // holds in each direction, each as a magnitude along its direction:
    // μ_s+ = μ(0+), μ_s− = −μ(0−); none without a static interval.
    match (o.mu_s_forward_over_mu0, o.mu_s_backward_over_mu0) {
        (Some(f), Some(b)) => {
            writeln!(
                out,
                "mu_s+/mu0 forward      {} (= mu(0+); paper eq. 18: {})",
                Rounded(f),
                Rounded(o.paper_eq18_forward_over_mu0)
            )?;
            writeln!(
                out,
                "mu_s-/mu0 backward     {} (= -mu(0-), along -x; paper eq. 19: {})",
                Rounded(b),
                Rounded(o.paper_eq19_backward_over_mu0)
            )?;
        }
        _ => writeln!(
            out,
            "mu_s+/mu0, mu_s-/mu0   none (no static interval; paper eqs. 18/19: {}, {})",
            Rounded(o.paper_eq18_forward_over_mu0),
            Rounded(o.paper_eq19_backward_over_mu0)
        )?,
    }
    writeln!(
        out,
        "mu(0+)/mu0             {}",
        Rounded(o.mu_0plus_over_mu0)
    )?;
    writeln!(
        out,
        "mu(0-)/mu0             {}",
        Rounded(o.mu_0minus_over_mu0)
    )
}
