//! `fricctl static`: critical velocities, the exact static interval and
//! static friction beside the paper's eqs. 18/19.

use std::io::Write;

use clap::Args;
use model_core::analytic::{CriticalVelocity, StaticFriction};
use model_core::{exact, Libm};
use serde::Serialize;

use crate::error::CliResult;
use crate::eval::exact_failure;
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
}

impl StaticCmd {
    /// Runs the command.
    pub fn run(self, out: &mut impl Write) -> CliResult {
        let rs = self.scene.resolve()?;
        let s = &rs.scene;
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
        };
        if self.json {
            return write_json(out, &o);
        }
        write_text(out, &o, iv, &st).map_err(stdout_error)
    }
}

fn write_text(
    out: &mut impl Write,
    o: &StaticOut,
    iv: Option<(f64, f64)>,
    st: &StaticFriction<f64>,
) -> std::io::Result<()> {
    writeln!(out, "v_c forward            {}", o.vc_forward)?;
    writeln!(out, "v_c backward           {}", o.vc_backward)?;
    writeln!(
        out,
        "static equilibrium     {}",
        if o.static_exists {
            "exists"
        } else {
            "none (the contact cannot rest)"
        }
    )?;
    match iv {
        Some((lo, hi)) => writeln!(out, "static interval u_x0   [{lo}, {hi}] m")?,
        None => writeln!(
            out,
            "static interval u_x0   empty (lo = {} W0 > hi = {} W0)",
            st.lo, st.hi
        )?,
    }
    let opt = |x: Option<f64>| x.map_or("-".to_string(), |v| v.to_string());
    writeln!(
        out,
        "mu_s+/mu0 (exact)      {}",
        opt(o.mu_s_forward_over_mu0)
    )?;
    writeln!(
        out,
        "mu_s-/mu0 (exact)      {}",
        opt(o.mu_s_backward_over_mu0)
    )?;
    writeln!(
        out,
        "paper eq. 18 (forward) {}",
        o.paper_eq18_forward_over_mu0
    )?;
    writeln!(
        out,
        "paper eq. 19 (backward) {}",
        o.paper_eq19_backward_over_mu0
    )?;
    writeln!(out, "mu(0+)/mu0             {}", o.mu_0plus_over_mu0)?;
    writeln!(out, "mu(0-)/mu0             {}", o.mu_0minus_over_mu0)
}
