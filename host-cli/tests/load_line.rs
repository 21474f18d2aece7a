//! `fricctl load-line` and `fricctl fit` from the command line: JSON keys, SI
//! units against values converted by hand, refusals.

use serde_json::Value;

mod common;

use common::cli::{fricctl, json, PHYS};

/// `load-line` on the dimensionless scene a = `duz_rel`, b/a = `ratio`,
/// φ = `phi_deg` (degrees).
fn dimensionless<'a>(duz_rel: &'a str, ratio: &'a str, phi_deg: &'a str) -> [&'a str; 7] {
    [
        "load-line",
        "--duz-rel",
        duz_rel,
        "--ratio",
        ratio,
        "--phi-deg",
        phi_deg,
    ]
}

/// The SI scene of these tests at φ = `phi_deg`: [`PHYS`] (μ0 = 0.3,
/// kz = 2e6 N/m, kx = 1.5e6 N/m, uz0 = 5 µm, 40 kHz) with Δuz = 2.5 µm
/// (a = 0.5) and Δux = 2 µm.
fn si_scene(phi_deg: &str) -> Vec<&str> {
    [
        &PHYS[..8],
        &[
            "--duz",
            "2.5e-6",
            "--dux",
            "2e-6",
            "--freq",
            "40e3",
            "--phi-deg",
            phi_deg,
        ],
    ]
    .concat()
}

#[test]
fn load_line_units_and_keys() {
    // Fig. 6's scene at φ = 0 (a = 0.5, ratio 2): it pushes forward.
    let d = json(&dimensionless("0.5", "2", "0"));
    for key in [
        "stall_force_over_mu0_fz",
        "no_load_velocity",
        "stall_force_backward_over_mu0_fz",
        "no_load_velocity_backward",
        "max_power",
        "max_efficiency",
    ] {
        assert!(d[key].is_f64(), "{key} missing");
    }
    // Here c + c' = 2 exactly: the static interval is the single point
    // [c' − 1, 1 − c] = [−0.5, −0.5], so −μ(0⁺)/μ0 = 0.5 (closed form).
    let stall = d["stall_force_over_mu0_fz"].as_f64().unwrap();
    assert!((stall - 0.5).abs() < 1e-12, "stall {stall}");
    assert_eq!(d["stall_force_backward_over_mu0_fz"].as_f64(), Some(0.0));
    // SI: the same groups with μ0 = 0.3, kz = 2e6, kx = 1.5e6, uz0 = 5 µm,
    // Δuz = 2.5 µm (a = 0.5) and Δux = ratio·μ0 kz Δuz/kx = 2 µm, 40 kHz.
    let si = json(&[&["load-line"][..], &si_scene("0")].concat());
    let fz = 2e6 * 5e-6; // N
    let w0 = 0.3 * 2e6 * 5e-6 / 1.5e6; // m
    let omega = std::f64::consts::TAU * 40e3;
    let rel = |a: f64, b: f64| (a - b).abs() <= 1e-9 * b.abs().max(1e-300);
    assert!(rel(si["stall_force"].as_f64().unwrap(), 0.5 * 0.3 * fz));
    assert!(rel(
        si["no_load_velocity"].as_f64().unwrap(),
        d["no_load_velocity"].as_f64().unwrap() * omega * w0
    ));
    assert!(rel(
        si["max_power"].as_f64().unwrap(),
        d["max_power"].as_f64().unwrap() * 0.3 * fz * omega * w0
    ));
}

#[test]
fn load_line_plot_refused_when_nothing_pushes() {
    let out = fricctl()
        .args(dimensionless("0.5", "0.5", "90"))
        .args(["--plot", "/tmp/never-written.png"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert_eq!(
        String::from_utf8_lossy(&out.stderr).trim(),
        "error: --plot: this scene does not push forward (μ(0⁺) ≥ 0): there is no forward load line to plot"
    );
}

#[test]
fn fit_reads_a_sweep_file_and_refuses_bad_ones() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("sweep.csv");
    // A header-only file: no rows.
    std::fs::write(
        &data,
        "param,value,freq_hz,amp_z,amp_x,offset_z,phi_deg,v0,model_mu0,model_kz,model_kx,measured_mu,std_error,predicted_mu,valid,reasons\n",
    )
    .unwrap();
    let out = fricctl()
        .args(["fit", "--data"])
        .arg(&data)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert_eq!(
        String::from_utf8_lossy(&out.stderr).trim(),
        "error: --data: the sweep file has no rows"
    );
    let out = fricctl()
        .args(["fit", "--params", "mu0,kz", "--data"])
        .arg(&data)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    // Rows measured on the model itself (μ = predicted, from `fricctl mu`):
    // the fit returns the model's μ0 with a zero-width scatter.
    let mut csv = String::from(
        "param,value,freq_hz,amp_z,amp_x,offset_z,phi_deg,v0,model_mu0,model_kz,model_kx,measured_mu,std_error,predicted_mu,valid,reasons\n",
    );
    for phi in [0.0, 60.0, 120.0, 180.0] {
        // PHYS (φ its last flag) at this φ.
        let phi_flag = format!("{phi}");
        let m = json(
            &[
                &["mu"][..],
                &PHYS[..PHYS.len() - 2],
                &["--phi-deg", &phi_flag, "--v0", "0.01", "--method", "exact"],
            ]
            .concat(),
        );
        let mu = m["mu"].as_f64().unwrap();
        csv += &format!(
            "phase-deg,{phi},40000,2e-6,0.7e-6,5e-6,{phi},0.01,0.3,2e6,1.5e6,{mu},0.001,{mu},true,\n"
        );
    }
    std::fs::write(&data, csv).unwrap();
    let fit_out = dir.path().join("fit.json");
    let f = json(&[
        "fit",
        "--params",
        "mu0",
        "--data",
        data.to_str().unwrap(),
        "--out",
        fit_out.to_str().unwrap(),
    ]);
    assert!((f["mu0"].as_f64().unwrap() - 0.3).abs() < 1e-9);
    assert_eq!(f["rows_used"].as_u64(), Some(4));
    assert_eq!(f["dof"].as_u64(), Some(3));
    let saved: Value = serde_json::from_slice(&std::fs::read(&fit_out).unwrap()).unwrap();
    assert_eq!(saved["kx"], f["kx"]);
}

/// Every contact model through the one law: lift-off (μ at rest unique, so
/// one stall force is −μ(0) or μ(0) of the window solver, within its bound)
/// and a sphere (stall force −μ(0⁺) of the MDR, no-load velocity a root of
/// its law: |μ(v_nl)| within the MDR's bound plus the law's slope (≤ 5 per
/// ωW₀ here, checked by a difference quotient) times the root's bracket
/// 8ε·v_c). Both have a derived input power and so an efficiency.
#[test]
fn load_line_of_every_contact() {
    use model_core::mdr::{self, Profile};
    use model_core::model::liftoff;
    use model_core::{Drive, Libm};
    // Lift-off, a = 1.5, b = 0.75, φ = 200°: pushes backward only.
    let o = json(&dimensionless("1.5", "0.5", "200"));
    assert_eq!(o["contact"], "lift-off");
    let d = Drive::new::<Libm>(1.5, 0.75, 200f64.to_radians());
    let m0 = liftoff::mu_over_mu0::<f64, Libm>(&d, 0.0).unwrap();
    let bound = liftoff::error_bound::<f64, Libm>(&d);
    let fwd = o["stall_force_over_mu0_fz"].as_f64().unwrap();
    let bwd = o["stall_force_backward_over_mu0_fz"].as_f64().unwrap();
    assert!((fwd - (-m0).max(0.0)).abs() <= bound && (bwd - m0.max(0.0)).abs() <= bound);
    assert!(fwd == 0.0 || bwd == 0.0, "unique μ(0): one side only");
    // Lift-off at φ = 20° pushes forward: the efficiency is now derived
    // (`load_line::liftoff_powers`, checked against an independent
    // simulation in the integration tests). The reported maximum must be at
    // least every value of a dense scan of η over (0, v_nl) (the optimiser's
    // golden-section refinement only improves on its 64-point scan; 1e-12
    // allows rounding), and η ≤ 1 (P_fric ≥ 0).
    let out = fricctl()
        .args(dimensionless("1.5", "0.5", "20"))
        .arg("--json")
        .output()
        .unwrap();
    assert!(out.status.success());
    assert!(
        out.stderr.is_empty(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let o: Value = serde_json::from_slice(&out.stdout).unwrap();
    let eta = o["max_efficiency"].as_f64().unwrap();
    let vnl = o["no_load_velocity"].as_f64().unwrap();
    let d = Drive::new::<Libm>(1.5, 0.75, 20f64.to_radians());
    let mut scan: f64 = 0.0;
    for i in 1..1000 {
        let v = vnl * f64::from(i) / 1000.0;
        let pw = model_core::model::load_line::liftoff_powers::<f64, Libm>(&d, v).unwrap();
        scan = scan.max(pw.efficiency());
    }
    assert!(
        eta >= scan - 1e-12 && eta <= 1.0 && eta > 0.0,
        "η {eta} scan {scan}"
    );
    // Sphere, Fig. 6 scene at φ = 40°.
    let o = json(
        &[
            &dimensionless("0.5", "2", "40")[..],
            &["--profile", "sphere"],
        ]
        .concat(),
    );
    assert_eq!(o["contact"], "sphere");
    // Its efficiency is the bed's (mdr::powers::profile_powers): at least
    // every value of a dense scan over (0, v_nl), and in (0, 1].
    {
        let eta = o["max_efficiency"].as_f64().unwrap();
        let vnl = o["no_load_velocity"].as_f64().unwrap();
        let d = Drive::new::<Libm>(0.5, 1.0, 40f64.to_radians());
        let mut scan: f64 = 0.0;
        for i in 1..200 {
            let v = vnl * f64::from(i) / 200.0;
            let r =
                mdr::powers::profile_powers::<f64, Libm>(&d, &Profile::Sphere, v, 1e-6).unwrap();
            scan = scan.max(r.powers.efficiency());
        }
        assert!(
            eta >= scan - 1e-12 && eta <= 1.0 && eta > 0.0,
            "η {eta} scan {scan}"
        );
    }
    let d = Drive::new::<Libm>(0.5, 1.0, 40f64.to_radians());
    let p = Profile::Sphere;
    let (plus, _) = mdr::limits_at_zero::<f64, Libm>(&d, &p, 1e-8).unwrap();
    let stall = o["stall_force_over_mu0_fz"].as_f64().unwrap();
    assert!(
        (stall + plus.mu_over_mu0).abs() <= 2.0 * plus.bound.max(1e-9),
        "{stall}"
    );
    let v = o["no_load_velocity"].as_f64().unwrap();
    let mu = |x: f64| {
        mdr::mu_over_mu0::<f64, Libm>(&d, &p, x, 1e-8)
            .unwrap()
            .mu_over_mu0
    };
    let slope = (mu(v + 1e-6) - mu(v - 1e-6)) / 2e-6;
    assert!(slope.abs() <= 5.0, "slope {slope}");
    let at = mdr::mu_over_mu0::<f64, Libm>(&d, &p, v, 1e-8).unwrap();
    let (cf, _) = mdr::critical_velocities::<f64, Libm>(&d, &p).unwrap();
    assert!(
        at.mu_over_mu0.abs() <= 2.0 * at.bound + 5.0 * 8.0 * f64::EPSILON * cf,
        "μ(v_nl) = {:e}",
        at.mu_over_mu0
    );
    // An SI scene with a curved profile: F̄z = kz·uz0·D (eq. M5, kz read as
    // the incremental stiffness 2E*a0), D here by a brute force over springs
    // and phases (midpoint rules, m = k = 1000 and 2000; the finer one's
    // error is below twice their change for methods of order ≥ 1), and the
    // stall force in newtons is μ0·F̄z times the one in units of μ0·F̄z.
    let o = json(
        &[
            &["load-line"][..],
            &si_scene("30"),
            &["--profile", "sphere"],
        ]
        .concat(),
    );
    let brute = |m: u32| {
        let (a, n) = (0.5f64, 2.0f64);
        let xi_max = (1.0 + a).powf(1.0 / n);
        let (hx, ht) = (xi_max / f64::from(m), std::f64::consts::PI / f64::from(m));
        let mut sum = 0.0;
        for i in 0..m {
            let d = 1.0 - ((f64::from(i) + 0.5) * hx).powf(n);
            for j in 0..m {
                sum += (d - a * ((f64::from(j) + 0.5) * ht).cos()).max(0.0);
            }
        }
        sum * hx / f64::from(m)
    };
    let (coarse, fine) = (brute(1000), brute(2000));
    let kz_uz0 = 2e6 * 5e-6;
    let fz = o["fz_mean"].as_f64().unwrap();
    assert!(
        (fz / kz_uz0 - fine).abs() <= 2.0 * (coarse - fine).abs() + 1e-10,
        "F̄z/(kz uz0) = {} vs brute force {fine}",
        fz / kz_uz0
    );
    let rel = o["stall_force_over_mu0_fz"].as_f64().unwrap();
    let newton = o["stall_force"].as_f64().unwrap();
    assert!((newton - rel * 0.3 * fz).abs() <= 1e-12 * newton.abs().max(1e-300));
    assert!(o["max_efficiency"].as_f64().unwrap() > 0.0);
}
