//! `fricctl motion` against independent computations: the
//! quasi-static drift by quadrature of μ⁻¹ (no time integrator), the
//! convergence of homogenised and resolved as ω/Ω grows (rate fitted and
//! asserted), zero drift of a symmetric law, mirror symmetry, the ratchet's
//! direction, and bad input.
//!
//! The scenes are dimensionless (`--duz-rel`, `--ratio`): velocities are in
//! units of ωW₀, the mass in k_x/ω², `--force-omega` is ν = Ω/ω; one SI
//! scene is checked against its dimensionless form, converted by hand.

use std::f64::consts::{PI, TAU};

use assert_cmd::Command;
use model_core::{exact, Groups, Libm, Scene};
use serde_json::Value;

mod common;

use common::normal;

/// The paper's Fig. 7 scene (ratio 0.5, Δu_z/u_z0 = 0.5) at phase `phi_deg`.
fn fig7(phi_deg: f64) -> Vec<String> {
    scene_args(0.5, 0.5, phi_deg)
}

fn scene_args(a: f64, ratio: f64, phi_deg: f64) -> Vec<String> {
    vec![
        "--duz-rel".into(),
        a.to_string(),
        "--ratio".into(),
        ratio.to_string(),
        "--phi-deg".into(),
        phi_deg.to_string(),
    ]
}

/// Runs `fricctl motion … --json`, asserts success, returns the JSON.
fn motion(scene: &[String], extra: &[&str]) -> Value {
    let out = Command::cargo_bin("fricctl")
        .unwrap()
        .arg("motion")
        .args(scene)
        .args(extra)
        // A --csv may exist from the probe run of `tol_that_succeeds`.
        .args(["--json", "--force"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "fricctl motion {scene:?} {extra:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

/// The `--tol` under which `fricctl motion SCENE EXTRA` succeeds: `tol`, or
/// where the run's own estimated error exceeds that (a homogenised run where
/// the model is known to be inaccurate, E_h large), twice the error it
/// reports at the loosest tolerance. Derivation: the reported error is
/// `E_h + numerical`, the numerical part controlled to `0.1·tol` (step
/// halving) plus the table's `2·0.02·tol·S + 5β·S` (S the law's mean inverse
/// slope, β the solver's bound), so at `tol' = 2e` (e the error at the
/// loosest tolerance, ≥ E_h) it is at most `e + 0.2e + 0.08eS + …` — below
/// `2e` wherever S < 8, which the success of the run then checks.
fn tol_that_succeeds(scene: &[String], extra: &[&str], tol: f64) -> String {
    let out = Command::cargo_bin("fricctl")
        .unwrap()
        .arg("motion")
        .args(scene)
        .args(extra)
        .args(["--tol", "0.5", "--json"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "fricctl motion {scene:?} {extra:?} --tol 0.5 failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let o: Value = serde_json::from_slice(&out.stdout).unwrap();
    let e = num(&o, "error_estimate_over_v_ref");
    format!("{:e}", tol.max(2.0 * e))
}

/// A homogenised run at `--tol tol` whose exit status must be the one its own
/// printed numbers demand: refused (exit 1, "exceeds --tol", the result still
/// printed) exactly when `E_h + numerical > tol·v_ref`, and then because of
/// the model's estimate (`E_h > numerical`: the convergence studies run the
/// model where it is known to be inaccurate), else a success. Returns the
/// JSON either way.
fn homogenised_at(scene: &[String], extra: &[&str], tol: f64) -> Value {
    let t = tol.to_string();
    let out = Command::cargo_bin("fricctl")
        .unwrap()
        .arg("motion")
        .args(scene)
        .args(extra)
        .args(["--method", "homogenised", "--tol", t.as_str(), "--json"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    let o: Value = serde_json::from_slice(&out.stdout)
        .unwrap_or_else(|_| panic!("fricctl motion {scene:?} {extra:?}: no result ({err})"));
    let v_ref = num(&o, "v_ref");
    let (e_h, numerical) = (
        num(&o, "homogenisation_error_estimate"),
        num(&o, "numerical_error"),
    );
    if e_h + numerical > tol * v_ref {
        assert!(
            out.status.code() == Some(1) && err.contains("exceeds --tol"),
            "{extra:?}: E_h + numerical = {:e} v_ref > tol {tol}, yet: {err}",
            (e_h + numerical) / v_ref
        );
        assert!(
            e_h > numerical,
            "{extra:?}: refused for its numerical error {numerical:e} (E_h {e_h:e})"
        );
    } else {
        assert!(out.status.success(), "{extra:?}: {err}");
    }
    o
}

/// [`motion`] with `--tol` [`tol_that_succeeds`] (the run must succeed);
/// returns the JSON and the tolerance used.
fn motion_at_a_tol_that_succeeds(scene: &[String], extra: &[&str], tol: f64) -> (Value, f64) {
    let t = tol_that_succeeds(scene, extra, tol);
    let o = motion(scene, &[extra, &["--tol", t.as_str()]].concat());
    (o, t.parse().unwrap())
}

fn num(v: &Value, k: &str) -> f64 {
    v[k].as_f64()
        .unwrap_or_else(|| panic!("{k} missing in {v}"))
}

/// The velocity where μ(V)/μ₀ = g, by bisection on the exact solver
/// (independent of the command's table and its inverse).
fn inverse_exact(d: &model_core::Drive<f64>, g: f64, hi: f64, lo: f64) -> f64 {
    if g <= hi && g >= lo {
        return 0.0;
    }
    bisect(
        |m| exact::mu_over_mu0::<f64, Libm>(d, m).unwrap(),
        g,
        (hi, lo),
        (d.c_forward::<Libm>(), d.c_backward::<Libm>()),
        80,
    )
}

/// The velocity where the law `mu` (μ/μ₀ of V) equals `g`, by `iters`
/// halvings of [0, cf] if g > hi = μ(0⁺), else of [−cb, 0]; at V = 0 the law
/// is read as `hi` or `lo` = μ(0⁻) on the side searched.
fn bisect(
    mu: impl Fn(f64) -> f64,
    g: f64,
    (hi, lo): (f64, f64),
    (cf, cb): (f64, f64),
    iters: u32,
) -> f64 {
    let (mut a, mut b) = if g > hi { (0.0, cf) } else { (-cb, 0.0) };
    for _ in 0..iters {
        let m = 0.5 * (a + b);
        let v = if m == 0.0 {
            if g > hi {
                hi
            } else {
                lo
            }
        } else {
            mu(m)
        };
        if v < g {
            a = m;
        } else {
            b = m;
        }
    }
    0.5 * (a + b)
}

/// Mean over a load period of `inverse(f0 + f sin T)` (μ⁻¹, zero inside the
/// static band [lo, hi]): the moving sets {g > hi} and {g < lo} in closed
/// form (arcsine), Gauss–Legendre `nodes` ((x, w) on [−1, 1]) on `cells`
/// equal cells of each.
fn mean_over_load_period(
    inverse: impl Fn(f64) -> f64,
    f0: f64,
    f: f64,
    (hi, lo): (f64, f64),
    nodes: &[(f64, f64)],
    cells: usize,
) -> f64 {
    let mut total = 0.0;
    let mut integrate = |t0: f64, t1: f64| {
        for c in 0..cells {
            let (a, b) = (
                t0 + (t1 - t0) * c as f64 / cells as f64,
                t0 + (t1 - t0) * (c + 1) as f64 / cells as f64,
            );
            for &(x, w) in nodes {
                let t = 0.5 * (a + b) + 0.5 * (b - a) * x;
                total += 0.5 * (b - a) * w * inverse(f0 + f * t.sin());
            }
        }
    };
    let up = (hi - f0) / f;
    if up < 1.0 {
        let s = up.max(-1.0).asin();
        integrate(s, PI - s);
    }
    let down = (f0 - lo) / f;
    if down < 1.0 {
        let s = down.max(-1.0).asin();
        integrate(PI + s, TAU - s);
    }
    total / TAU
}

/// Mean of V(T) = μ⁻¹(f0 + f sin T) over a load period: the moving sets
/// {g > μ(0⁺)} and {g < μ(0⁻)} in closed form (arcsine), 20-point
/// Gauss–Legendre on 40 cells of each.
fn quasi_static_drift(d: &model_core::Drive<f64>, f0: f64, f: f64) -> f64 {
    let (hi, lo) = exact::limits_at_zero::<f64, Libm>(d).unwrap();
    let nodes = gauss_legendre(20);
    mean_over_load_period(|g| inverse_exact(d, g, hi, lo), f0, f, (hi, lo), &nodes, 40)
}

/// Quasi-static drift (`--mass 0`) against the quadrature of μ⁻¹ over a load
/// period, on a ratchet (Fig. 7, φ = 0) and an actuator (Fig. 6 ratio 2,
/// φ = 40°) with an offset force. The command's stated numerical error (step
/// halving + its table's interpolation error over the law's mean slope) must
/// cover the difference; the quadrature's own error (bisection to 2⁻⁸⁰ of
/// v_c, 20-point Gauss on smooth pieces, solver 1e-9·(1 + b) μ₀ over a slope
/// ≥ 0.3) is below 1e-8 and is added.
#[test]
fn massless_drift_matches_quadrature() {
    for (a, ratio, phi, f0, f) in [
        (0.5f64, 0.5f64, 0.0f64, 0.0f64, 0.5f64),
        (0.5, 2.0, 40.0, 0.1, 0.6),
        (0.3, 1.0, 120.0, -0.05, 0.7),
    ] {
        let d = Scene::dimensionless(Groups::from_ratio(a, ratio, phi.to_radians()).unwrap())
            .unwrap()
            .drive();
        let want = quasi_static_drift(&d, f0, f);
        let o = motion(
            &scene_args(a, ratio, phi),
            &[
                "--mass",
                "0",
                "--force-amp-rel",
                &f.to_string(),
                "--force-offset-rel",
                &f0.to_string(),
                "--force-omega",
                "1e-5",
            ],
        );
        assert_eq!(o["method"], "homogenised");
        let got = num(&o, "mean_velocity");
        let bound = num(&o, "numerical_error") + 1e-8;
        assert!(
            (got - want).abs() <= bound,
            "a={a} ratio={ratio} φ={phi}: motion {got} vs quadrature {want} (bound {bound:e})"
        );
    }
}

/// A body that responds within a millionth of the load period (`m̃ν` =
/// 6e-6, stiff for RK4 at any affordable step) drifts as the massless one:
/// against the quadrature of μ⁻¹ ([`quasi_static_drift`], independent of the
/// integrator) within the stated numerical error (which includes the lag
/// `τ_r·max|dV/dT|` of the light body) + 1e-8 (the quadrature's error).
#[test]
fn light_body_under_a_slow_force_drifts_quasi_statically() {
    let d = Scene::dimensionless(Groups::from_ratio(0.5, 0.5, 0.0).unwrap())
        .unwrap()
        .drive();
    let want = quasi_static_drift(&d, 0.0, 0.5);
    let o = motion(
        &fig7(0.0),
        &[
            "--mass",
            "2e4",
            "--force-amp-rel",
            "0.5",
            "--force-omega",
            "3e-10",
        ],
    );
    let got = num(&o, "mean_velocity");
    let bound = num(&o, "numerical_error") + 1e-8;
    assert!(
        (got - want).abs() <= bound,
        "light body {got} vs quasi-static {want} (bound {bound:e})"
    );
}

/// A heavy actuator body under a small force (`Mω²/k_x` = 1e8, ω/Ω = 10³)
/// relaxes over thousands of load periods towards the massless drift (0.196
/// ωW₀): after the run's 2000 load periods it is not periodic, and the
/// command says so (exit 1, `periodic` false) instead of reporting the
/// second period's drift as the answer.
#[test]
fn slowly_relaxing_body_is_not_called_periodic() {
    let out = Command::cargo_bin("fricctl")
        .unwrap()
        .arg("motion")
        .args(scene_args(0.5, 2.0, 30.0))
        .args([
            "--mass",
            "1e8",
            "--force-amp-rel",
            "0.01",
            "--force-omega",
            "1e-3",
            "--json",
        ])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("no periodic regime"));
    let o: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(o["periodic"], false);
    // The massless drift it relaxes towards: 0.196 ωW₀ to the three digits
    // quoted (±5e-4) plus the massless run's stated numerical error.
    let m0 = motion(
        &scene_args(0.5, 2.0, 30.0),
        &[
            "--mass",
            "0",
            "--force-amp-rel",
            "0.01",
            "--force-omega",
            "1e-3",
        ],
    );
    let v0 = num(&m0, "mean_velocity");
    assert!(
        (v0 - 0.196).abs() <= 5e-4 + num(&m0, "numerical_error"),
        "massless drift {v0}"
    );
}

/// A body ringing on a ground spring (the resolved model, chosen by auto)
/// has drift exactly 0 in its periodic regime (its position is bounded): the
/// reported drift is within the stated error of 0, i.e. the periodicity test
/// waits for the body's state, not only for two similar period means.
#[test]
fn spring_held_resolved_body_reports_zero_drift_within_its_error() {
    let o = motion(
        &fig7(0.0),
        &[
            "--mass",
            "1000",
            "--spring",
            "1e-3",
            "--force-offset-rel",
            "2",
            "--force-amp-rel",
            "0.5",
            "--force-omega",
            "1e-3",
        ],
    );
    assert_eq!(o["method"], "resolved");
    let (v, e) = (num(&o, "mean_velocity"), num(&o, "error_estimate"));
    assert!(v.abs() <= e, "drift {v:e} beyond its error {e:e} of 0");
}

/// Student's t, two-sided 95 %, for `dof` = 1…8 degrees of freedom.
const T95: [f64; 8] = [12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306];

/// Runs homogenised and resolved at `m̃ν = Mω Ω/k_x = 1` (so `m̃ = 1/ν`)
/// over `inv_nus` = ω/Ω, asserts `|H − R| ≤ E_h` (the derived estimate of
/// `motion::estimate`) at every point, and fits the rate `p` of
/// `ln|H − R|` against `ln ν` by least squares.
///
/// The acceptance band of `p` is derived, not chosen: the 95 % confidence
/// half-width of the least-squares slope, `t₀.₉₇₅(n − 2)·SE` with `SE` from
/// the fit's residuals (which carry the next-order term's curvature and any
/// scatter of the points), plus the largest slope shift the runs' stated
/// numerical errors can cause: each point's `ln|H − R|` may be off by
/// `δᵢ = −ln(1 − noiseᵢ/|H − R|ᵢ)`, which moves the slope by at most
/// `Σ|xᵢ − x̄|·δᵢ/Sxx`. Returns `(p, band)`.
fn converge(scene: &[String], f0: f64, f: f64, inv_nus: &[f64], tol: f64) -> (f64, f64) {
    let mut pts = Vec::new();
    let mut delta = Vec::new();
    for &inv_nu in inv_nus {
        let nu = 1.0 / inv_nu;
        let (mass, amp, offset, omega) = (
            inv_nu.to_string(),
            f.to_string(),
            f0.to_string(),
            nu.to_string(),
        );
        let extra = [
            "--mass",
            mass.as_str(),
            "--force-amp-rel",
            amp.as_str(),
            "--force-offset-rel",
            offset.as_str(),
            "--force-omega",
            omega.as_str(),
        ];
        // The homogenised run where its model may be inaccurate (its exit
        // status checked against its numbers); the resolved reference must
        // succeed at `tol`.
        let h = homogenised_at(scene, &extra, tol);
        let r = motion(
            scene,
            &[
                &extra[..],
                &["--method", "resolved", "--tol", &tol.to_string()],
            ]
            .concat(),
        );
        let err = (num(&h, "mean_velocity") - num(&r, "mean_velocity")).abs();
        let noise = num(&h, "numerical_error") + num(&r, "numerical_error");
        assert!(
            noise < 0.5 * err,
            "ν = {nu}: numerical error {noise:e} too large against |H − R| = {err:e}"
        );
        // The derived estimate of the homogenised model covers the difference.
        let e_h = num(&h, "homogenisation_error_estimate");
        assert!(
            err <= e_h + noise,
            "ν = {nu}: |H − R| = {err:e} above the derived estimate {e_h:e}"
        );
        delta.push(-(1.0 - noise / err).ln());
        pts.push((nu.ln(), err.ln(), e_h));
    }
    let n = pts.len() as f64;
    let (mx, my) = pts
        .iter()
        .fold((0.0, 0.0), |(a, b), p| (a + p.0 / n, b + p.1 / n));
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx) * (p.0 - mx)).sum();
    let rate = sxy / sxx;
    let c = my - rate * mx;
    let ss: f64 = pts.iter().map(|p| (p.1 - c - rate * p.0).powi(2)).sum();
    let se = (ss / (n - 2.0) / sxx).sqrt();
    let noise_shift: f64 = pts
        .iter()
        .zip(&delta)
        .map(|(p, d)| (p.0 - mx).abs() * d)
        .sum::<f64>()
        / sxx;
    let band = T95[pts.len() - 3] * se + noise_shift;
    eprintln!(
        "fitted rate {rate:.4}, band {band:.4} (t·SE {:.4} + noise {noise_shift:.4}); (ln ν, ln |H − R|, E_h): {pts:?}",
        T95[pts.len() - 3] * se
    );
    (rate, band)
}

/// [`converge`] on Fig. 7's ratchet scene at φ = 0 with the force
/// `f0 + f sin Ωt`, asserting the fitted rate is 1 within the derived band.
fn assert_first_order(f0: f64, f: f64, inv_nus: &[f64], tol: f64) {
    let (rate, band) = converge(&fig7(0.0), f0, f, inv_nus, tol);
    assert!(
        (rate - 1.0).abs() <= band,
        "fitted rate {rate} (expected 1 ± {band})"
    );
}

/// Homogenised and resolved converge at first order as ω/Ω grows at a fixed
/// body response in load periods (m̃ν = 1), on a scene where the body slides
/// forward all the time (Fig. 7 ratchet, force 0.6 + 0.2 sin Ωt > μ(0⁺) =
/// 0.25): expected rate 1, since the body's ultrasonic ripple that the
/// homogenised model drops is ∝ 1/m̃ = ν (`motion::estimate`). Band: derived
/// in [`converge`].
#[test]
fn homogenised_and_resolved_converge_at_first_order() {
    assert_first_order(0.6, 0.2, &[10.0, 20.0, 50.0, 100.0, 200.0, 500.0], 1e-5);
}

/// The same with stick–slip of the body (force 0.5 sin Ωt crosses the
/// static band's edge μ(0⁺) = 0.25 twice a period): the difference scatters
/// around the first-order line (the stick onsets' timing and the resolved
/// body's ringing while stuck), which the derived band absorbs through the
/// fit's residuals; the estimate covers every point.
#[test]
fn stick_slip_converges_at_first_order() {
    assert_first_order(
        0.0,
        0.5,
        &[10.0, 20.0, 50.0, 100.0, 200.0, 500.0, 1000.0],
        1e-4,
    );
}

/// Heavy bodies that stick (Fig. 7 ratchet, force 0.5 sin Ωt, ω/Ω = 10³,
/// `Mω²/k_x` = 10³…10⁵): the resolved body, stuck on the contact's
/// tangential stiffness, rings with a period `2π√(M/k_x)` that approaches the
/// load period; the homogenised body stands rigidly. Every run's |H − R| is
/// within the estimate `E_h` (plus both runs' numerical errors), and at
/// `Mω²/k_x = 10⁵` it is the sticking term `E_s = N(1 + a)ν/π`
/// (`motion::estimate`, N the arrivals at rest the homogenised run counts)
/// that covers it: the sliding term alone, `E_h − E_s`, does not.
#[test]
fn heavy_stuck_body_within_the_sticking_term() {
    let (a, nu) = (0.5, 1e-3);
    for mass in ["1e3", "1e4", "1e5"] {
        let nus = nu.to_string();
        let extra = [
            "--mass",
            mass,
            "--force-amp-rel",
            "0.5",
            "--force-omega",
            nus.as_str(),
        ];
        let h = homogenised_at(&fig7(0.0), &extra, 1e-4);
        let r = motion(
            &fig7(0.0),
            &[&extra[..], &["--method", "resolved", "--tol", "1e-4"]].concat(),
        );
        let diff = (num(&h, "mean_velocity") - num(&r, "mean_velocity")).abs();
        let noise = num(&h, "numerical_error") + num(&r, "numerical_error");
        let e_h = num(&h, "homogenisation_error_estimate");
        let n = num(&h, "stick_onsets");
        let e_s = n * (1.0 + a) * nu / std::f64::consts::PI;
        eprintln!(
            "M {mass}: |H − R| {diff:.3e} noise {noise:.3e} E_h {e_h:.3e} E_s {e_s:.3e} N {n}"
        );
        assert!(n >= 1.0, "M {mass}: the body never comes to rest");
        assert!(
            diff <= e_h + noise,
            "M {mass}: |H − R| = {diff:e} above E_h = {e_h:e} + {noise:e}"
        );
        if mass == "1e5" {
            assert!(
                diff > e_h - e_s + noise,
                "the sliding term alone should miss the ringing body: {diff:e} vs {:e}",
                e_h - e_s
            );
        }
    }
}

/// A single-mode drive (Δu_x = 0) gives a law odd in V; under a symmetric
/// sine force the drift vanishes: the mirror x → −x maps the motion onto
/// itself shifted by half a load period (500 whole ultrasonic periods at
/// ν = 1/1000, so even the resolved motion is exactly symmetric). Bound: the
/// stated numerical error. The body moves: the static band is
/// [−(1 − a), 1 − a] = [−0.5, 0.5] and the force 0.8 sin T leaves it; the
/// massless body is stuck exactly while |0.8 sin T| ≤ 0.5, a fraction
/// (2/π)·asin(0.5/0.8) = 0.4298 of the period (to the homogenised step's
/// Simpson weight, 1/512 of a period); a body with mass starts moving at the
/// same instants and stops later (it must decelerate), so it is stuck for
/// less, and for a positive fraction (the force stays inside the band for
/// 0.43 of the period and the body cannot be moving throughout: its
/// position is periodic in the periodic regime, so its velocity vanishes
/// somewhere).
#[test]
fn symmetric_law_gives_zero_drift() {
    let scene: Vec<String> = ["--duz-rel", "0.5", "--dux-rel", "0"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    for (mass, method) in [
        ("0", "homogenised"),
        ("1000", "homogenised"),
        ("1000", "resolved"),
    ] {
        let o = motion(
            &scene,
            &[
                "--mass",
                mass,
                "--force-amp-rel",
                "0.8",
                "--force-omega",
                "1e-3",
                "--method",
                method,
                "--tol",
                "5e-2",
            ],
        );
        let v = num(&o, "mean_velocity");
        assert!(
            v.abs() <= num(&o, "numerical_error") + 1e-12,
            "{method} M={mass}: drift {v:e}"
        );
        let stuck = num(&o, "stick_fraction");
        let closed = 2.0 / PI * (0.5f64 / 0.8).asin();
        assert!((closed - 0.4298).abs() < 5e-5);
        if mass == "0" {
            assert!(
                (stuck - closed).abs() <= 1.0 / 512.0,
                "massless stick fraction {stuck} vs (2/π)asin(0.5/0.8) = {closed}"
            );
        } else {
            assert!(
                stuck > 0.0 && stuck <= closed + 1.0 / 512.0,
                "{method} M={mass}: stick fraction {stuck} outside (0, {closed}]"
            );
        }
    }
}

/// Mirror symmetry: φ → φ + π with f0 → −f0 reverses the drift exactly
/// (μ(V, φ + π) = −μ(−V, φ) and −(f0 + f sin T) = −f0 + f sin(T + π), a
/// time shift by 500 whole ultrasonic periods at ν = 1/1000). Bound: the sum
/// of both runs' numerical errors.
#[test]
fn mirror_reverses_drift() {
    for method in ["homogenised", "resolved"] {
        let run = |phi: f64, f0: &str| {
            motion(
                &scene_args(0.5, 2.0, phi),
                &[
                    "--mass",
                    "1000",
                    "--force-amp-rel",
                    "0.4",
                    "--force-offset-rel",
                    f0,
                    "--force-omega",
                    "1e-3",
                    "--method",
                    method,
                    "--tol",
                    "5e-2",
                ],
            )
        };
        let p = run(40.0, "0.1");
        let m = run(220.0, "-0.1");
        let (vp, vm) = (num(&p, "mean_velocity"), num(&m, "mean_velocity"));
        let bound = num(&p, "numerical_error") + num(&m, "numerical_error") + 1e-12;
        assert!(
            vp.abs() > 10.0 * bound,
            "{method}: drift {vp:e} too small to test"
        );
        assert!(
            (vp + vm).abs() <= bound,
            "{method}: {vp:e} and {vm:e} are not opposite (bound {bound:e})"
        );
    }
}

/// The ratchet of Fig. 7 at φ = 0 (ratio 0.5 < 1): static band
/// [μ(0⁻), μ(0⁺)] = [−(1 − |a − b|), 1 − (a + b)] = [−0.75, 0.25] (eqs. 18, 19
/// with a = 0.5, b = 0.25). A symmetric force 0.5·sin Ωt exceeds the upper
/// edge and never the lower one, so the body moves forward only: positive
/// drift for every model, and the massless body is stuck exactly where
/// 0.5 sin T ≤ 0.25, i.e. 2/3 of the period (to the step's Simpson weight,
/// 1/512 of a period); its drift is the quadrature's of μ⁻¹.
#[test]
fn ratchet_drifts_forward() {
    let scene = fig7(0.0);
    let m0 = motion(
        &scene,
        &[
            "--mass",
            "0",
            "--force-amp-rel",
            "0.5",
            "--force-omega",
            "1e-5",
        ],
    );
    assert!((num(&m0, "mu_0plus_over_mu0") - 0.25).abs() < 1e-9);
    assert!((num(&m0, "mu_0minus_over_mu0") + 0.75).abs() < 1e-9);
    assert!((num(&m0, "stick_fraction") - 2.0 / 3.0).abs() < 1.0 / 512.0);
    // The massless drift against the quadrature of μ⁻¹ (independent of the
    // command: bisection on the exact solver, Gauss–Legendre over the moving
    // arcs), within the stated numerical error plus the quadrature's 1e-8
    // (`massless_drift_matches_quadrature`); it is forward.
    let d = Scene::dimensionless(Groups::from_ratio(0.5, 0.5, 0.0).unwrap())
        .unwrap()
        .drive();
    let want = quasi_static_drift(&d, 0.0, 0.5);
    assert!(want > 0.0);
    let v0 = num(&m0, "mean_velocity");
    assert!(
        (v0 - want).abs() <= num(&m0, "numerical_error") + 1e-8,
        "massless drift {v0} vs quadrature {want}"
    );
    // With mass (Mω²/k_x = 1000, ω/Ω = 1000: the body responds within about a
    // load period): forward, and the two models agree within the
    // homogenised run's stated error (E_h + numerical) plus the resolved
    // run's numerical error.
    let run = |method: &str| {
        motion(
            &scene,
            &[
                "--mass",
                "1000",
                "--force-amp-rel",
                "0.5",
                "--force-omega",
                "1e-3",
                "--method",
                method,
                "--tol",
                "5e-2",
            ],
        )
    };
    let (h, r) = (run("homogenised"), run("resolved"));
    let (vh, vr) = (num(&h, "mean_velocity"), num(&r, "mean_velocity"));
    let bound = num(&h, "error_estimate") + num(&r, "numerical_error");
    assert!(
        vr > num(&r, "error_estimate"),
        "resolved drift {vr:e} not forward beyond its error"
    );
    assert!(
        (vh - vr).abs() <= bound,
        "homogenised {vh} vs resolved {vr} (bound {bound:e})"
    );
}

/// A ground spring stops the drift: in the periodic regime the position is
/// bounded, so the mean velocity is 0 within the stated numerical error
/// (a body with mass, Mω²/k_x = 1000, and a massless one).
///
/// The massless body's swing, derived: it moves only while `F − κx` is
/// outside the static band `[μ(0⁻), μ(0⁺)]` (Fig. 7 ratchet: [−0.75, 0.25],
/// width 1.0), so at its forward turning point `κx_max = F − μ(0⁺) ≤ f − μ(0⁺)`
/// and at the backward one `κx_min ≥ −f − μ(0⁻)`: the spread is at most
/// `(2f − (μ(0⁺) − μ(0⁻)))/κ` = (1.6 − 1.0)/10⁻³ = 600 W₀. And at T = π/2
/// (F = f) `κx = f − μ(v) ≥ f − μ(v̄)`, `v̄` the largest speed: where the speed
/// peaks `dv/dT = 0`, so `κ dx/dT = dF/dT ≤ f` and `v = ν dx/dT ≤ νf/κ`; the
/// same at T = 3π/2. So the spread is at least `(2f − μ(v̄) + μ(−v̄))/κ`
/// (exact solver at ±v̄, ± its bound), 595 at ν = 10⁻⁶. Both plus the
/// table's stated error over κ at each end (the law the body feels).
#[test]
fn spring_stops_drift() {
    let dir = std::env::temp_dir().join(format!("fricctl-motion-spring-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let o = motion(
        &fig7(0.0),
        &[
            "--mass",
            "1000",
            "--force-amp-rel",
            "0.8",
            "--force-omega",
            "1e-3",
            "--spring",
            "1e-3",
            "--method",
            "homogenised",
            "--tol",
            "5e-2",
        ],
    );
    let width = num(&o, "mu_0plus_over_mu0") - num(&o, "mu_0minus_over_mu0");
    assert!((width - 1.0).abs() < 1e-9, "band width {width}");
    assert!(num(&o, "mean_velocity").abs() <= num(&o, "numerical_error") + 1e-12);
    // The massless body on the spring, slow force.
    let (f, kappa, nu) = (0.8, 1e-3, 1e-6);
    let csv = dir.join("x.csv");
    let o = motion(
        &fig7(0.0),
        &[
            "--mass",
            "0",
            "--force-amp-rel",
            "0.8",
            "--force-omega",
            &nu.to_string(),
            "--spring",
            &kappa.to_string(),
            "--tol",
            "1e-3",
            "--csv",
            csv.to_str().unwrap(),
        ],
    );
    assert!(num(&o, "mean_velocity").abs() <= num(&o, "numerical_error") + 1e-12);
    let xs = last_period_x(&csv, TAU / nu);
    let spread =
        xs.iter().cloned().fold(f64::MIN, f64::max) - xs.iter().cloned().fold(f64::MAX, f64::min);
    let d = Scene::dimensionless(Groups::from_ratio(0.5, 0.5, 0.0).unwrap())
        .unwrap()
        .drive();
    let eb = exact::error_bound::<f64, Libm>(&d);
    let vbar = nu * f / kappa;
    let (up, down) = (
        exact::mu_over_mu0::<f64, Libm>(&d, vbar).unwrap(),
        exact::mu_over_mu0::<f64, Libm>(&d, -vbar).unwrap(),
    );
    let slack = 2.0 * num(&o, "table_error_over_mu0") / kappa;
    let hi = (2.0 * f - width) / kappa + slack;
    let lo = (2.0 * f - up + down - 2.0 * eb) / kappa - slack;
    eprintln!("massless spring-held body: x spread {spread} W0, derived [{lo}, {hi}]");
    assert!(
        spread >= lo && spread <= hi,
        "spread {spread} outside [{lo}, {hi}]"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Bad input: exit 2 and one line naming the flag.
#[test]
fn bad_input_names_the_flag() {
    let base = fig7(0.0);
    for (extra, flag) in [
        (
            vec![
                "--mass",
                "-1",
                "--force-amp-rel",
                "0.5",
                "--force-omega",
                "1e-3",
            ],
            "--mass",
        ),
        (
            vec![
                "--mass",
                "1",
                "--force-amp-rel",
                "0.5",
                "--force-omega",
                "0",
            ],
            "--force-omega",
        ),
        (
            vec![
                "--mass",
                "1",
                "--force-amp-rel",
                "0.5",
                "--force-omega",
                "0.6",
            ],
            "--force-omega",
        ),
        (
            vec![
                "--mass",
                "1",
                "--force-amp-rel",
                "nan",
                "--force-omega",
                "1e-3",
            ],
            "--force-amp-rel",
        ),
        (
            vec![
                "--mass",
                "1",
                "--force-amp-rel",
                "0.5",
                "--force-omega",
                "1e-3",
                "--tol",
                "0",
            ],
            "--tol",
        ),
        (
            vec![
                "--mass",
                "0",
                "--force-amp-rel",
                "0.5",
                "--force-omega",
                "1e-3",
                "--method",
                "resolved",
            ],
            "--mass",
        ),
        (
            vec![
                "--mass",
                "0",
                "--force-amp-rel",
                "1.2",
                "--force-omega",
                "1e-3",
            ],
            "--force-amp-rel",
        ),
        (
            vec![
                "--mass",
                "1",
                "--force-amp-rel",
                "0.5",
                "--force-offset-rel",
                "1.5",
                "--force-omega",
                "1e-3",
            ],
            "--force-offset-rel",
        ),
        (
            vec![
                "--mass",
                "1",
                "--force-amp-rel",
                "0.5",
                "--force-omega",
                "1e-3",
                "--duration",
                "1",
            ],
            "--duration",
        ),
        (
            vec![
                "--mass",
                "1",
                "--force-amp-rel",
                "0.5",
                "--force-omega",
                "1e-3",
                "--spring",
                "-2",
            ],
            "--spring",
        ),
    ] {
        let out = Command::cargo_bin("fricctl")
            .unwrap()
            .arg("motion")
            .args(&base)
            .args(&extra)
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(2), "{extra:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(err.lines().count(), 1, "{extra:?}: {err}");
        assert!(err.contains(flag), "{extra:?}: {err}");
    }
}

/// Lift-off (Δu_z/u_z0 = 1.5): both models run through the same law
/// interface. μ at rest is unique (the band is a point), and it is the
/// lift-off window solver's μ(0) within its bound; the homogenised body is
/// therefore never stuck (the band has measure zero: stick fraction 0); the
/// two models agree within the derived estimate plus both numerical errors.
#[test]
fn lift_off_scene_in_both_models() {
    use model_core::model::liftoff;
    let scene = scene_args(1.5, 0.5, 34.4);
    let run = |m: &str| {
        motion(
            &scene,
            &[
                "--mass",
                "1000",
                "--force-amp-rel",
                "0.5",
                "--force-omega",
                "1e-3",
                "--method",
                m,
                "--tol",
                "5e-2",
            ],
        )
    };
    let h = run("homogenised");
    let r = run("resolved");
    assert_eq!(h["contact"], "lift-off");
    assert_eq!(num(&h, "mu_0plus_over_mu0"), num(&h, "mu_0minus_over_mu0"));
    let d = model_core::Drive::new::<Libm>(1.5, 0.75, 34.4f64.to_radians());
    let want = liftoff::mu_over_mu0::<f64, Libm>(&d, 0.0).unwrap();
    assert!(
        (num(&h, "mu_0plus_over_mu0") - want).abs()
            <= liftoff::error_bound::<f64, Libm>(&d) + 1e-15
    );
    assert_eq!(num(&h, "stick_fraction"), 0.0);
    let diff = (num(&h, "mean_velocity") - num(&r, "mean_velocity")).abs();
    let bound = num(&h, "error_estimate") + num(&r, "numerical_error");
    assert!(diff <= bound, "|H − R| = {diff:e} > {bound:e}");
    assert!(num(&h, "fz_mean_over_kz_uz0") > 1.0);
}

/// Gauss–Legendre nodes and weights on [−1, 1], `n` points (Newton on Pₙ).
fn gauss_legendre(n: usize) -> Vec<(f64, f64)> {
    let mut nodes = Vec::new();
    for i in 0..n {
        let mut x = (PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        for _ in 0..100 {
            let (mut p0, mut p1) = (1.0, x);
            for k in 2..=n {
                let p2 = ((2 * k - 1) as f64 * x * p1 - (k - 1) as f64 * p0) / k as f64;
                p0 = p1;
                p1 = p2;
            }
            let dp = n as f64 * (x * p1 - p0) / (x * x - 1.0);
            x -= p1 / dp;
            if (p1 / dp).abs() < 1e-16 {
                nodes.push((x, 2.0 / ((1.0 - x * x) * dp * dp)));
                break;
            }
        }
    }
    assert_eq!(nodes.len(), n);
    nodes
}

/// A curved profile (sphere) through the same interface: the massless drift
/// against the brute force over springs (`integration_tests::springs`, no
/// model-core solver), with no inversion of the law. Layer-cake: the body's
/// velocity exceeds `u > 0` exactly where the force exceeds `μ(u)` (μ
/// increasing), so with `f0 = 0`
///
/// `⟨V⟩ = (1/2π)[∫₀^{V₊} (π − 2 asin(μ(u)/f)) du − ∫₀^{V₋} (π − 2 asin(−μ(−u)/f)) du]`,
///
/// `V±` the velocities where `μ = ±f` (secant on the brute force). With
/// `u = V±(1 − τ²)` the square-root end becomes smooth; Gauss–Legendre at 12
/// and 24 nodes, the change taken as the quadrature's error. The brute
/// force's errors `δμ` enter through `|∂/∂μ| = 2/√(f² − μ²)` (summed with the
/// same weights, as the integrand's change over `μ ± δμ`, finite where the
/// asin is steep) and through `V±` (`δV = δμ/μ'`, moving the integral by at
/// most `π·δV`). Tolerance: the command's numerical error plus these.
#[test]
fn sphere_massless_drift() {
    use integration_tests::springs;
    let (a, ratio, phi, f) = (0.5f64, 2.0f64, 40.0f64, 0.5f64);
    let b = a * ratio;
    let phi_r = phi.to_radians();
    let tol = 1e-8;
    let mu = |v: f64| springs::mu(2.0, a, b, phi_r, v, tol, 1 << 13);
    // V± by the secant method on μ(V) = ±f (μ/μ0 increasing, 1 at the
    // critical velocities ≈ |b e^{iφ} ± a| for a < 1).
    let root = |target: f64, sign: f64| -> (f64, f64) {
        let g = |v: f64| mu(sign * v).mu * sign - target;
        if g(1e-9) >= 0.0 {
            // The force never leaves the static band on this side.
            return (0.0, 0.0);
        }
        let (mut x0, mut x1) = (0.05, 0.5);
        let (mut g0, mut g1) = (g(x0), g(x1));
        for _ in 0..30 {
            let x2 = x1 - g1 * (x1 - x0) / (g1 - g0);
            (x0, g0) = (x1, g1);
            x1 = x2;
            g1 = g(x1);
            if (x1 - x0).abs() < 1e-10 {
                break;
            }
        }
        // The law's slope there by a ±1 % difference (the secant's last step
        // is too short to give it above the brute force's noise).
        let slope = (g(1.01 * x1) - g(0.99 * x1)).abs() / (0.02 * x1);
        let bf = mu(sign * x1);
        (x1, (bf.err + g1.abs()) / slope)
    };
    let side = |sign: f64, nodes: &[(f64, f64)]| -> (f64, f64, f64) {
        let (vmax, dv) = root(f, sign);
        if vmax == 0.0 {
            return (0.0, 0.0, 0.0);
        }
        let (mut sum, mut err) = (0.0, 0.0);
        for &(x, w) in nodes {
            let tau = 0.5 * (x + 1.0);
            let u = vmax * (1.0 - tau * tau);
            let jac = 2.0 * vmax * tau * 0.5 * w;
            let r = mu(sign * u);
            let g = |y: f64| PI - 2.0 * y.clamp(-1.0, 1.0).asin();
            let (y, dy) = (sign * r.mu / f, r.err / f);
            sum += g(y) * jac;
            err += (g(y) - g(y + dy)).abs().max((g(y - dy) - g(y)).abs()) * jac;
        }
        (sum, err + PI * dv, vmax)
    };
    let (n12, n24) = (gauss_legendre(12), gauss_legendre(24));
    let (p12, _, _) = side(1.0, &n12);
    let (p24, pe, vp) = side(1.0, &n24);
    let (m12, _, _) = side(-1.0, &n12);
    let (m24, me, vm) = side(-1.0, &n24);
    let want = (p24 - m24) / TAU;
    let quad = ((p24 - p12).abs() + (m24 - m12).abs()) / TAU;
    let brute = (pe + me) / TAU;
    let args = |extra: &[&str]| {
        let mut v = scene_args(a, ratio, phi);
        v.extend(["--profile", "sphere"].iter().map(|s| s.to_string()));
        v.extend(extra.iter().map(|s| s.to_string()));
        v
    };
    let o = motion(
        &args(&[]),
        &[
            "--mass",
            "0",
            "--force-amp-rel",
            "0.5",
            "--force-omega",
            "1e-5",
            "--tol",
            "1e-3",
        ],
    );
    assert_eq!(o["contact"], "sphere");
    let got = num(&o, "mean_velocity");
    let bound = num(&o, "numerical_error") + quad + brute;
    eprintln!(
        "sphere: motion {got} brute-force layer-cake {want} (V+ {vp}, V− {vm}; quadrature ±{quad:.1e}, brute force ±{brute:.1e}, numerical {:.1e})",
        num(&o, "numerical_error")
    );
    assert!(
        (got - want).abs() <= bound,
        "sphere drift {got} vs brute force {want} (bound {bound:e})"
    );
}

/// The positions `x` (column 2) of the last load period of a `--csv` file
/// (`t` in column 1; `period` in the same unit).
fn last_period_x(path: &std::path::Path, period: f64) -> Vec<f64> {
    last_period_col(path, period, 1)
}

/// Column `col` (0 = t, 1 = x, 2 = v) of the last load period of a `--csv` file.
fn last_period_col(path: &std::path::Path, period: f64, col: usize) -> Vec<f64> {
    let text = std::fs::read_to_string(path).unwrap();
    let rows: Vec<Vec<f64>> = text
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|x| x.parse::<f64>().unwrap()).collect())
        .collect();
    let t_end = rows.last().unwrap()[0];
    rows.iter()
        .filter(|r| r[0] >= t_end - period)
        .map(|r| r[col])
        .collect()
}

/// A sphere body with mass tied to ground by a spring under a constant force
/// f0: it comes to rest where the applied force balances the contact's force
/// at rest and the spring, `κX = n̄(f0 − μ(0)/μ₀)` (units k_x W₀; μ(0) one
/// of μ(0±) — the equilibrium lies between the two positions). `n̄ = D` is
/// what this checks: the brute force over springs written here, not the
/// command's quadrature. Both models: the homogenised one (the law and n̄),
/// and the resolved one (a bed of springs at the ultrasonic scale, whose
/// contact force does not use D at all; `n̄` enters only the applied force's
/// unit). Both runs last 20 load periods (`--duration`), at a `--tol` under
/// which they succeed ([`tol_that_succeeds`]: the homogenised model's drift
/// estimate E_h is large here, and irrelevant to where the body rests). The
/// homogenised body is then at rest: its x does not move over the last load
/// period (spread exactly 0). The resolved body rings on the springs'
/// tangential stiffness while stuck; its spread is bounded by that of a
/// linear oscillator whose stiffness is at least the ground spring's κ:
/// amplitude ≤ v_max·√(M/κ), v_max the largest speed over the period.
/// Tolerance: for the resolved run the spread (the sampled mean and the
/// rest position both lie in the swing), plus the brute force's error of D
/// and the MDR's bound of μ(0±), each times its factor in X; for the resolved run also its contact
/// force error over κ (its step halving watches the drift, which is 0 here,
/// so it stays at its first N = `steps` per period): springs that lift off
/// (ξ > ξ_a = (1 − a)^{1/2}) land on the first grid point after the true
/// landing, a stretch offset ≤ b·h (h = 2π/N; stick and clamp are
/// 1-Lipschitz), weight ∫ dξ = ξ_max − ξ_a; permanent springs (ξ < ξ_a)
/// are the flat punch scaled by d, the fixed-step bound 10(d + a + b)/N²,
/// ≤ 10ξ_a(1 + a + b)/N² over them; and the bed's quadrature error,
/// estimated by its Σq⟨w⁺⟩ against D (|⟨s⟩| ≤ ⟨w⁺⟩).
#[test]
fn sphere_with_mass_and_spring_rests_at_the_force_balance() {
    use model_core::mdr::{self, Profile};
    let (a, ratio, phi, f0, kappa, nu) = (0.5f64, 2.0f64, 40.0f64, 0.2f64, 0.1f64, 1e-2f64);
    let d = Scene::dimensionless(Groups::from_ratio(a, ratio, phi.to_radians()).unwrap())
        .unwrap()
        .drive();
    let (plus, minus) = mdr::limits_at_zero::<f64, Libm>(&d, &Profile::Sphere, 1e-8).unwrap();
    let (nbar, e_nbar) = normal::reference(2.0, a);
    let x_of = |mu: f64| nbar * (f0 - mu) / kappa;
    let (x_lo, x_hi) = (x_of(plus.mu_over_mu0), x_of(minus.mu_over_mu0));
    let slack = e_nbar * (f0 + 1.0) / kappa + nbar * plus.bound.max(minus.bound) / kappa;
    let dir = std::env::temp_dir().join(format!("fricctl-motion-sphere-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for method in ["homogenised", "resolved"] {
        let csv = dir.join(format!("{method}.csv"));
        let mut args = scene_args(a, ratio, phi);
        args.extend(["--profile", "sphere"].iter().map(|s| s.to_string()));
        let duration = (20.0 * TAU / nu).to_string();
        let extra = [
            "--mass",
            "100",
            "--spring",
            "0.1",
            "--force-amp-rel",
            "0",
            "--force-offset-rel",
            "0.2",
            "--force-omega",
            "1e-2",
            "--method",
            method,
            "--duration",
            duration.as_str(),
            "--csv",
            csv.to_str().unwrap(),
        ];
        let (o, _) = motion_at_a_tol_that_succeeds(&args, &extra, 1e-3);
        assert_eq!(o["contact"], "sphere");
        assert!((num(&o, "fz_mean_over_kz_uz0") - nbar).abs() <= e_nbar + 1e-10 * nbar);
        let xs = last_period_x(&csv, TAU / nu);
        let mean = xs.iter().sum::<f64>() / xs.len() as f64;
        let spread = xs.iter().cloned().fold(f64::MIN, f64::max)
            - xs.iter().cloned().fold(f64::MAX, f64::min);
        let mut allow = slack;
        if method == "homogenised" {
            assert_eq!(spread, 0.0, "the homogenised body is not at rest");
        } else {
            let vmax = last_period_col(&csv, TAU / nu, 2)
                .into_iter()
                .fold(0.0f64, |m, v| m.max(v.abs()));
            let swing = 2.0 * vmax * (100.0f64 / kappa).sqrt();
            assert!(
                spread <= swing,
                "resolved spread {spread} beyond the oscillator bound {swing}"
            );
            allow += spread;
            let n = num(&o, "steps");
            let springs = num(&o, "springs") as usize;
            let h = TAU / n;
            let b = a * ratio;
            let (xi_a, xi_max) = ((1.0 - a).sqrt(), (1.0 + a).sqrt());
            let scheme = (xi_max - xi_a) * b * h + 10.0 * xi_a * (1.0 + a + b) / (n * n);
            // The bed of `springs` (resolved::Bed::profile): midpoints in t of
            // ξ = ξ_max(1 − cos t)/2, weights (ξ_max/2) sin t · π/J.
            let ht = PI / springs as f64;
            let bed: f64 = (0..springs)
                .map(|j| {
                    let t = (j as f64 + 0.5) * ht;
                    let dd = 1.0 - (0.5 * xi_max * (1.0 - t.cos())).powi(2);
                    let m = 4000;
                    let band = (0..m)
                        .map(|i| {
                            (dd - a * ((f64::from(i) + 0.5) * PI / f64::from(m)).cos()).max(0.0)
                        })
                        .sum::<f64>()
                        / f64::from(m);
                    band * 0.5 * xi_max * t.sin() * ht
                })
                .sum();
            allow += (scheme + (bed - nbar).abs()) / kappa;
        }
        eprintln!("sphere {method}: rests at {mean} (balance [{x_lo}, {x_hi}], allow {allow:e})");
        assert!(
            mean >= x_lo.min(x_hi) - allow && mean <= x_lo.max(x_hi) + allow,
            "{method}: rests at {mean}, balance [{x_lo}, {x_hi}] ± {allow:e}"
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// A sliding sphere body with mass: the homogenised model (MDR law, n̄ = D)
/// against the resolved one (bed of springs, refined by doubling, no law);
/// they agree within the homogenised run's stated error (E_h + numerical +
/// table) plus the resolved one's numerical error — the same criterion as
/// the flat and lift-off scenes. Run where that error is small against the
/// drift (Mω²/k_x = 1000, ω/Ω = 1000: E_h ≈ 0.015 on a drift of 0.22; at
/// ω/Ω = 100 it was 0.15), so the comparison could see a drift off by 10 %. An SI scene with a sphere (resolved) drifts
/// at its dimensionless scene's drift, converted here by hand, times ωW₀,
/// within the two runs' stated errors plus rounding; its mass and ω/Ω
/// are the converted ones, and its F̄z/(k_z u_z0) is the brute force's D
/// at its a = Δu_z/u_z0 (`common::normal`).
#[test]
fn sphere_with_mass_in_both_models_and_si() {
    let mut args = scene_args(0.5, 2.0, 40.0);
    args.extend(["--profile", "sphere"].iter().map(|s| s.to_string()));
    let run = |m: &str| {
        motion(
            &args,
            &[
                "--mass",
                "1000",
                "--force-amp-rel",
                "0.5",
                "--force-omega",
                "1e-3",
                "--method",
                m,
                "--tol",
                "5e-2",
            ],
        )
    };
    let h = run("homogenised");
    let r = run("resolved");
    assert_eq!(r["method"], "resolved");
    assert!(num(&r, "springs") >= 64.0);
    let diff = (num(&h, "mean_velocity") - num(&r, "mean_velocity")).abs();
    let bound = num(&h, "error_estimate") + num(&r, "numerical_error");
    eprintln!("sphere with mass: |H − R| = {diff:e}, bound {bound:e}");
    assert!(
        bound <= 0.15 * num(&r, "mean_velocity").abs(),
        "the comparison's bound {bound:e} is not small against the drift"
    );
    assert!(diff <= bound, "|H − R| = {diff:e} > {bound:e}");
    // SI: μ0 0.3, kz 2e6 N/m, kx 1.5e6 N/m, uz0 5 µm, Δuz 2.5 µm, Δux 2 µm,
    // 40 kHz, φ 40°, M 0.05 kg, f 0.6, Ω 62.83 rad/s; its dimensionless
    // scene converted here by hand (README "A body on the contact", eq. 25):
    // W₀ = μ0 (kz/kx) uz0, a = Δuz/uz0, b = Δux/W₀ (`--dux-rel`), mass in
    // kx/ω², `--force-omega` in ω, velocities in ωW₀; the force stays in
    // units of μ0·F̄z. The model is pinned (resolved, what `auto` picks
    // here) so both runs compute the same thing.
    let (mu0, kz, kx, uz0, duz, dux) = (0.3f64, 2e6f64, 1.5e6, 5e-6, 2.5e-6, 2e-6);
    let (freq, phi_deg, mass, force_omega) = (40e3f64, 40.0f64, 0.05f64, 62.83f64);
    let omega = TAU * freq;
    let w0 = mu0 * (kz / kx) * uz0;
    let (a, b) = (duz / uz0, dux / w0);
    let (mass_rel, nu) = (mass * omega * omega / kx, force_omega / omega);
    let unit = omega * w0;
    let flags = |pairs: &[(&str, f64)]| -> Vec<String> {
        pairs
            .iter()
            .flat_map(|(k, v)| [k.to_string(), v.to_string()])
            .collect()
    };
    let si_args = flags(&[
        ("--mu0", mu0),
        ("--kz", kz),
        ("--kx", kx),
        ("--uz0", uz0),
        ("--duz", duz),
        ("--dux", dux),
        ("--freq", freq),
        ("--phi-deg", phi_deg),
        ("--mass", mass),
        ("--force-omega", force_omega),
    ]);
    let dl_args = flags(&[
        ("--duz-rel", a),
        ("--dux-rel", b),
        ("--phi-deg", phi_deg),
        ("--mass", mass_rel),
        ("--force-omega", nu),
    ]);
    let load = [
        "--profile",
        "sphere",
        "--force-amp-rel",
        "0.6",
        "--method",
        "resolved",
    ];
    let si = motion(&si_args, &load);
    let dl = motion(&dl_args, &load);
    assert_eq!(si["method"], "resolved");
    assert_eq!(dl["method"], "resolved");
    // Rounding: a, b, m̃, ν and ωW₀ are each formed here in ≤ 4 roundings
    // (≤ 4ε relative, ε = 2.2e-16) and by the command in as many. Discrete
    // choices a perturbation could flip (steps, springs, periods) are inside
    // each run's stated error; what is left is the exact drift's response to
    // its inputs' rounding and the product v·ωW₀: 1e-12 relative (≈ 4500ε)
    // allows a sensitivity |d ln v/d ln p| of ~1000; measured by 1e-3
    // relative changes of a, b, m̃, ν on the dimensionless run: ≤ 0.9.
    let rounding = 1e-12;
    let close = |x: f64, y: f64| (x - y).abs() <= rounding * x.abs().max(y.abs());
    assert!(close(num(&si, "mass_rel"), mass_rel), "mass_rel: {si}");
    assert!(close(num(&si, "scale_separation"), 1.0 / nu), "ω/Ω: {si}");
    assert!(close(num(&si, "v_ref"), unit * num(&dl, "v_ref")), "v_ref");
    let (v_si, v_dl) = (num(&si, "mean_velocity"), num(&dl, "mean_velocity"));
    let bound =
        num(&si, "error_estimate") + unit * num(&dl, "error_estimate") + rounding * v_si.abs();
    let diff = (v_si - v_dl * unit).abs();
    eprintln!(
        "sphere SI: {v_si} m/s, {v_dl} ωW₀ × ωW₀ = {} m/s, |Δ| = {diff:e}, bound {bound:e}",
        v_dl * unit
    );
    // The comparison can fail: the stated errors are below 1 % of the
    // drift, so a wrong unit (a factor off by ≥ 1 %) would be caught.
    assert!(
        bound <= 1e-2 * v_si.abs(),
        "bound {bound:e} vs drift {v_si}"
    );
    assert!(
        diff <= bound,
        "SI drift {v_si} m/s vs {v_dl} ωW₀ × {unit} m/s: |Δ| = {diff:e} > {bound:e}"
    );
    let (nbar, e_nbar) = normal::reference(2.0, 0.5);
    assert!((num(&si, "fz_mean_over_kz_uz0") - nbar).abs() <= e_nbar + 1e-10 * nbar);
}
