//! `fricctl classify`: the regime, with the numbers it rests on and the
//! paper's rule of thumb beside it.

use std::io::Write;

use clap::Args;
use model_core::regime::rule_of_thumb;
use model_core::scene::ContactMode;
use serde::Serialize;

use crate::args::{Rounded, Short};
use crate::error::CliResult;
use crate::eval::{classify_scene_profile, critical_velocity};
use crate::output::{stdout_error, write_json};
use crate::scene_args::profile_text;
use crate::scene_args::SceneArgs;
use model_core::mdr::Profile;

/// Flags of `fricctl classify`.
#[derive(Args, Debug, Clone)]
pub struct ClassifyCmd {
    #[command(flatten)]
    scene: SceneArgs,
    /// JSON output
    #[arg(long)]
    json: bool,
}

/// The JSON document of `fricctl classify` (keys are part of the CLI contract).
#[derive(Serialize)]
struct ClassifyOut {
    regime: &'static str,
    mu_0plus_over_mu0: f64,
    mu_0minus_over_mu0: f64,
    /// Whether a static interval exists (false with lift-off; for a curved
    /// profile eq. S2 of docs/guide/lift-off-and-profiles.md).
    static_exists: Option<bool>,
    /// The flat punch's static interval's ends over W0 (null with lift-off
    /// and for a curved profile, whose springs hold different stretches).
    static_lo_over_w0: Option<f64>,
    static_hi_over_w0: Option<f64>,
    /// The static interval as held forces μ/μ0, [μ(0−), μ(0+)] (null
    /// when it does not exist), for every profile.
    static_lo_over_mu0: Option<f64>,
    static_hi_over_mu0: Option<f64>,
    vc_forward: f64,
    vc_backward: f64,
    vc_forward_over_omega_w0: f64,
    vc_backward_over_omega_w0: f64,
    asymmetry: f64,
    duz_rel: f64,
    dux_rel: f64,
    ratio: Option<f64>,
    phi_deg: f64,
    /// The paper's rule (permanent contact only; null with lift-off).
    rule_of_thumb: Option<&'static str>,
    rule_of_thumb_agrees: Option<bool>,
    /// The contact lifts off once per period: μ(0±) are the unique μ(0),
    /// v_c are the contact window's (eq. L5), classes by `liftoff::regime`.
    lifts_off: bool,
    /// The contact profile (`flat`, `sphere`, `cone`, `power`) and its exponent (null for flat).
    profile: &'static str,
    exponent: Option<f64>,
}

impl ClassifyCmd {
    /// Runs the command.
    pub fn run(self, out: &mut impl Write) -> CliResult {
        let rs = self.scene.resolve_with(ContactMode::Intermittent)?;
        let s = &rs.scene;
        let c = classify_scene_profile(s, &rs.profile)?;
        let vc = critical_velocity(s)?;
        let g = s.groups();
        let flat = rs.profile == Profile::Flat;
        let rot = (!s.lifts_off() && flat).then(|| rule_of_thumb(s));
        // The static interval as held forces μ/μ0: the flat punch's
        // [lo, hi], a curved profile's [μ(0−), μ(0+)] (eq. S2).
        let exists = match (c.statics, c.profile_statics) {
            (Some(st), _) => st.exists(),
            (None, Some(ps)) => ps.exists,
            (None, None) => false,
        };
        let held = exists.then_some((c.mu_0minus, c.mu_0plus));
        let o = ClassifyOut {
            regime: c.regime.name(),
            mu_0plus_over_mu0: c.mu_0plus,
            mu_0minus_over_mu0: c.mu_0minus,
            static_exists: Some(exists),
            static_lo_over_w0: c.statics.map(|x| x.lo),
            static_hi_over_w0: c.statics.map(|x| x.hi),
            static_lo_over_mu0: held.map(|h| h.0),
            static_hi_over_mu0: held.map(|h| h.1),
            vc_forward: vc.forward,
            vc_backward: vc.backward,
            vc_forward_over_omega_w0: c.c_forward,
            vc_backward_over_omega_w0: c.c_backward,
            asymmetry: c.asymmetry,
            duz_rel: g.duz_rel,
            dux_rel: g.dux_rel,
            ratio: s.ratio(),
            phi_deg: g.phi.to_degrees(),
            rule_of_thumb: rot.map(|r| r.name()),
            rule_of_thumb_agrees: rot.map(|r| r == c.regime),
            lifts_off: s.lifts_off(),
            profile: rs.profile.name(),
            exponent: rs.profile.exponent(),
        };
        if self.json {
            return write_json(out, &o);
        }
        write_text(out, &o, &rs.profile, rs.dimensionless).map_err(stdout_error)
    }
}

/// What each regime means, in the paper's words (§3.2, classes I–III).
fn regime_meaning(regime: &str) -> &'static str {
    match regime {
        "active_control" => "class I: symmetric, always against the motion",
        "dynamic_ratchet" => {
            "class II: asymmetric, always against the motion; at rest with no force"
        }
        "actuator" => "class III: pushes by itself, mu(0+) < 0 or mu(0-) > 0",
        _ => "",
    }
}

/// The text output; velocities in m/s, or in ωW0 for a `dimensionless` scene.
fn write_text(
    out: &mut impl Write,
    o: &ClassifyOut,
    p: &Profile<f64>,
    dimensionless: bool,
) -> std::io::Result<()> {
    writeln!(
        out,
        "regime                 {} ({})",
        o.regime,
        regime_meaning(o.regime)
    )?;
    if *p != Profile::Flat {
        writeln!(
            out,
            "profile                {} (MDR quadrature; static interval over the springs, eq. S2)",
            profile_text(p)
        )?;
    }
    if o.lifts_off {
        writeln!(
            out,
            "contact                lifts off once per period (duz/uz0 = {} >= 1)",
            Short(o.duz_rel)
        )?;
        writeln!(
            out,
            "mu(0)/mu0              {} (unique at rest: the state resets at every landing)",
            Rounded(o.mu_0plus_over_mu0)
        )?;
        writeln!(
            out,
            "static interval        none (no static interval with lift-off)"
        )?;
    } else {
        writeln!(
            out,
            "mu(0+)/mu0             {}",
            Rounded(o.mu_0plus_over_mu0)
        )?;
        writeln!(
            out,
            "mu(0-)/mu0             {}",
            Rounded(o.mu_0minus_over_mu0)
        )?;
        // The static interval (paper §2.2): the held forces at which the
        // contact sticks. An actuator may have one (0 outside it: held, it
        // sticks; free, it moves) or none (it slips at every force).
        let (what, why) = if *p == Profile::Flat {
            ("sticks when held", "c + c' > 2")
        } else {
            (
                "rests on average when held",
                "c + c' > 2 at the central spring, eq. S2",
            )
        };
        match (o.static_lo_over_mu0, o.static_hi_over_mu0) {
            (Some(lo), Some(hi)) => writeln!(
                out,
                "static interval        {what} at mu/mu0 in [{}, {}]; {}",
                Rounded(lo),
                Rounded(hi),
                if lo <= 0.0 && 0.0 <= hi {
                    "free (zero force), it rests"
                } else {
                    "free (zero force), it moves"
                }
            )?,
            _ => writeln!(
                out,
                "static interval        none: it slips at every held force ({why})"
            )?,
        }
    }
    writeln!(
        out,
        "asymmetry              {} (max |mu(v) + mu(-v)|/mu0)",
        Rounded(o.asymmetry)
    )?;
    let unit = if dimensionless { "ωW0" } else { "m/s" };
    writeln!(
        out,
        "v_c forward/backward   {} / {} {unit}",
        Rounded(o.vc_forward),
        Rounded(o.vc_backward)
    )?;
    match (o.rule_of_thumb, o.rule_of_thumb_agrees) {
        (Some(r), Some(agrees)) => writeln!(
            out,
            "paper's rule of thumb  {r} ({})",
            if agrees { "agrees" } else { "disagrees" }
        ),
        _ if o.lifts_off => writeln!(
            out,
            "paper's rule of thumb  n/a (derived for permanent contact); v_c of the contact window (eq. L5)"
        ),
        _ => writeln!(
            out,
            "paper's rule of thumb  n/a (derived for the flat punch)"
        ),
    }
}
