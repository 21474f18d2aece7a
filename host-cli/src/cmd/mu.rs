//! `fricctl mu`: μ at one sliding velocity.

use std::io::Write;

use clap::Args;
use model_core::scene::ContactMode;

use crate::args::{round_up_sig, Real, Rounded, Short};
use crate::error::{CliError, CliResult};
use crate::eval::{
    critical_velocity, from_rel, mean_normal_force_over_kz_uz0, mu_at, MethodArgs, MuOutcome,
};
use crate::output::{stdout_error, write_json};
use crate::scene_args::{profile_text, ResolvedScene, SceneArgs};
use model_core::mdr::Profile;

/// Flags of `fricctl mu`.
#[derive(Args, Debug, Clone)]
pub struct MuCmd {
    #[command(flatten)]
    scene: SceneArgs,
    /// Sliding velocity v0, m/s (units of ωW0 for a dimensionless scene)
    #[arg(
        long,
        value_parser = Real::ANY,
        conflicts_with = "v_rel",
        required_unless_present = "v_rel"
    )]
    v0: Option<f64>,
    /// Velocity relative to v_c: v0 = X·v_c (forward v_c for X > 0, backward for X < 0)
    #[arg(long, value_parser = Real::ANY, value_name = "X")]
    v_rel: Option<f64>,
    #[command(flatten)]
    how: MethodArgs,
    /// JSON output
    #[arg(long)]
    json: bool,
}

impl MuCmd {
    /// Runs the command.
    pub fn run(mut self, out: &mut impl Write) -> CliResult {
        self.how.validate()?;
        let rs = self.scene.resolve_with(ContactMode::Intermittent)?;
        self.how.profile = rs.profile;
        let v = self.velocity(&rs)?;
        let flag = if self.v_rel.is_some() {
            "--v-rel"
        } else {
            "--v0"
        };
        let o = mu_at(&rs.scene, v, &self.how).map_err(|e| e.renamed("--v0", flag))?;
        if self.json {
            write_json(out, &o)?;
        } else {
            write_text(out, &o, &rs).map_err(stdout_error)?;
        }
        o.not_converged().map_or(Ok(()), Err)
    }

    /// The velocity (m/s, or ωW0) from `--v0` or `--v-rel`, checked against
    /// the scene's velocity scale.
    fn velocity(&self, rs: &ResolvedScene) -> CliResult<f64> {
        let (v, flag) = match (self.v0, self.v_rel) {
            (Some(v), None) => (v, "--v0"),
            (None, Some(x)) => (
                from_rel(&critical_velocity(&rs.scene)?, x, "v-rel")?,
                "--v-rel",
            ),
            _ => return Err(CliError::usage("--v0: give either --v0 or --v-rel")),
        };
        rs.velocity(v, flag)?;
        Ok(v)
    }
}

fn write_text(out: &mut impl Write, o: &MuOutcome, rs: &ResolvedScene) -> std::io::Result<()> {
    // Velocities in the scene's unit: m/s, or ωW0 for a dimensionless scene.
    let v = if rs.dimensionless { "ωW0" } else { "m/s" };
    writeln!(out, "v0           {} {v}", Rounded(o.v0))?;
    match o.v_rel {
        Some(x) => writeln!(out, "v0/v_c       {}", Rounded(x))?,
        None => writeln!(out, "v0/v_c       (v_c = 0 in this direction)")?,
    }
    if let Some(m) = o.mu {
        writeln!(out, "mu           {}", Rounded(m))?;
        if let Some(r) = o.mu_over_mu0 {
            writeln!(out, "mu/mu0       {}", Rounded(r))?;
        }
    }
    if let (Some(p), Some(m)) = (o.mu_0plus_over_mu0, o.mu_0minus_over_mu0) {
        writeln!(out, "mu(0+)/mu0   {}", Rounded(p))?;
        writeln!(out, "mu(0-)/mu0   {}", Rounded(m))?;
    }
    writeln!(out, "method       {}", o.method)?;
    if let Some(b) = o.error_bound_over_mu0 {
        writeln!(out, "error bound  {} mu0", Short(round_up_sig(b, 3)))?;
    }
    if let Some(n) = o.steps_per_period {
        writeln!(out, "steps/period {n}")?;
        writeln!(out, "periods      {}", o.periods.unwrap_or(0))?;
        writeln!(out, "converged    {}", o.converged.unwrap_or(false))?;
    }
    writeln!(out, "v_c forward  {} {v}", Rounded(o.vc_forward))?;
    writeln!(out, "v_c backward {} {v}", Rounded(o.vc_backward))?;
    if rs.profile != Profile::Flat {
        write_profile_notes(out, rs)?;
    } else if o.lifts_off {
        write_lift_off_notes(out, rs, o.method == "fixed")?;
    }
    Ok(())
}

/// What a curved profile changes (`model_core::mdr`).
fn write_profile_notes(out: &mut impl Write, rs: &ResolvedScene) -> std::io::Result<()> {
    let a = rs.scene.drive().a;
    writeln!(
        out,
        "profile      {} through MDR: uz0 is the mean indentation d0, kz/kx is E*/G*",
        profile_text(&rs.profile)
    )?;
    writeln!(
        out,
        "normal force mu = (sum of fx)/(sum of fz) over the springs (eq. M8); the rim springs lift off every period{}",
        if a >= 1.0 {
            ", and with duz >= d0 all of them (mu(0) is unique)"
        } else {
            ""
        }
    )?;
    writeln!(
        out,
        "v_c          the flat punch's with the same drive (the central spring decides)"
    )
}

/// What changes meaning when the contact lifts off (`model_core::model::liftoff`).
fn write_lift_off_notes(
    out: &mut impl Write,
    rs: &ResolvedScene,
    fixed: bool,
) -> std::io::Result<()> {
    let a = rs.scene.drive().a;
    let w = mean_normal_force_over_kz_uz0(&rs.scene);
    writeln!(
        out,
        "contact      lifts off once per period (duz/uz0 = {} >= 1)",
        Short(a)
    )?;
    writeln!(
        out,
        "normal force mean kz<uz+> = {} kz uz0: mu = <fx>/<fz> is normalised by it, not by kz uz0",
        Rounded(w)
    )?;
    writeln!(
        out,
        "at rest      mu(0) is unique (the state resets at every landing; no static interval)"
    )?;
    writeln!(
        out,
        "v_c          of the contact window (eq. L5), not eq. 8"
    )?;
    if fixed {
        writeln!(
            out,
            "scheme       lift-off stepping: one contact window from the landing (exact), order 2; bound (1 + a + b)(10/N^2 + N eps)"
        )?;
    }
    Ok(())
}
