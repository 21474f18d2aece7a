//! `fricctl classify`: the regime, with the numbers it rests on and the
//! paper's rule of thumb beside it.

use std::io::Write;

use clap::Args;
use model_core::analytic::CriticalVelocity;
use model_core::regime::{self, rule_of_thumb, ClassifyOptions};
use serde::Serialize;

use crate::error::CliResult;
use crate::eval::exact_failure;
use crate::output::{stdout_error, write_json};
use crate::scene_args::SceneArgs;

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
    static_exists: bool,
    static_lo_over_w0: f64,
    static_hi_over_w0: f64,
    vc_forward: f64,
    vc_backward: f64,
    vc_forward_over_omega_w0: f64,
    vc_backward_over_omega_w0: f64,
    asymmetry: f64,
    duz_rel: f64,
    dux_rel: f64,
    ratio: Option<f64>,
    phi_deg: f64,
    rule_of_thumb: &'static str,
    rule_of_thumb_agrees: bool,
}

impl ClassifyCmd {
    /// Runs the command.
    pub fn run(self, out: &mut impl Write) -> CliResult {
        let rs = self.scene.resolve()?;
        let s = &rs.scene;
        let c = regime::classify(s, &ClassifyOptions::default()).map_err(exact_failure)?;
        let vc = CriticalVelocity::of(s);
        let g = s.groups();
        let rot = rule_of_thumb(s);
        let o = ClassifyOut {
            regime: c.regime.name(),
            mu_0plus_over_mu0: c.mu_0plus,
            mu_0minus_over_mu0: c.mu_0minus,
            static_exists: c.statics.exists(),
            static_lo_over_w0: c.statics.lo,
            static_hi_over_w0: c.statics.hi,
            vc_forward: vc.forward,
            vc_backward: vc.backward,
            vc_forward_over_omega_w0: c.c_forward,
            vc_backward_over_omega_w0: c.c_backward,
            asymmetry: c.asymmetry,
            duz_rel: g.duz_rel,
            dux_rel: g.dux_rel,
            ratio: s.ratio(),
            phi_deg: g.phi.to_degrees(),
            rule_of_thumb: rot.name(),
            rule_of_thumb_agrees: rot == c.regime,
        };
        if self.json {
            return write_json(out, &o);
        }
        write_text(out, &o).map_err(stdout_error)
    }
}

fn write_text(out: &mut impl Write, o: &ClassifyOut) -> std::io::Result<()> {
    writeln!(out, "regime                 {}", o.regime)?;
    writeln!(out, "mu(0+)/mu0             {}", o.mu_0plus_over_mu0)?;
    writeln!(out, "mu(0-)/mu0             {}", o.mu_0minus_over_mu0)?;
    writeln!(out, "static equilibrium     {}", o.static_exists)?;
    writeln!(out, "asymmetry max|mu(v)+mu(-v)|/mu0  {}", o.asymmetry)?;
    writeln!(
        out,
        "v_c forward/backward   {} / {}",
        o.vc_forward, o.vc_backward
    )?;
    writeln!(
        out,
        "paper's rule of thumb  {} ({})",
        o.rule_of_thumb,
        if o.rule_of_thumb_agrees {
            "agrees"
        } else {
            "disagrees"
        }
    )
}
