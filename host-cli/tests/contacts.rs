//! `fricctl` with contacts the paper sets aside: a flat punch that
//! lifts off once per period (Δu_z ≥ u_z0).
//!
//! Reference numbers are independent of the solver under test: the lift-off
//! fixed-step scheme (`liftoff::stepping`, landing exactly on the grid, order
//! 2, stated bound `(1 + a + b)(10/N² + Nε + …)`) at fine N, brute-force
//! maxima and integrals on fine grids, and the permanent-contact solver on
//! the other side of a = 1.

use model_core::model::liftoff::stepping;
use model_core::{Drive, Libm};
use serde_json::Value;
use std::f64::consts::{PI, TAU};

mod common;

use common::cli::{csv_rows, fricctl, json, run_ok};

fn text(args: &[&str]) -> String {
    String::from_utf8(run_ok(args).stdout).unwrap()
}

/// Runs fricctl, expects exit status 2 and exactly the one stderr line `want`.
fn refused(args: &[&str], want: &str) {
    let out = fricctl().args(args).output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
    assert!(out.stdout.is_empty(), "{args:?}");
    assert_eq!(err.trim_end(), format!("error: {want}"), "{args:?}");
}

fn f(v: &Value, k: &str) -> f64 {
    v[k].as_f64()
        .unwrap_or_else(|| panic!("{k} missing or not a number in {v}"))
}

/// Steps of the reference run: 2¹⁶ per period.
const N_REF: u32 = 1 << 16;

/// μ/μ0 of the lift-off stepping at `N_REF` and its stated bound.
fn reference(a: f64, b: f64, phi_deg: f64, v: f64) -> (f64, f64) {
    let d = Drive::new::<Libm>(a, b, phi_deg.to_radians());
    let r = stepping::mu_over_mu0::<f64, Libm>(&d, v, N_REF).unwrap();
    (r.mu_over_mu0, r.error_bound)
}

/// `max_{θ ∈ window} (a + b cos φ) sin θ + b sin φ cos θ` (eq. L5 written
/// out: `c sin(θ + ψ) = Im((a + b e^{iφ}) e^{iθ})`) on a grid of 2·10⁶
/// points over the contact window `[θ_c, 2π − θ_c]`, `cos θ_c = 1/a`. A grid
/// misses the maximum of a sinusoid of amplitude ≤ a + b by at most
/// `(a + b)·h²/8` (h < 3.2·10⁻⁶: < 1.3·10⁻¹²·(a + b)); the window's ends are
/// grid points.
fn brute_critical(a: f64, b: f64, phi: f64) -> f64 {
    let tc = (1.0 / a).acos();
    let n = 2_000_000;
    let (re, im) = (a + b * phi.cos(), b * phi.sin());
    (0..=n)
        .map(|i| {
            let t = tc + (TAU - 2.0 * tc) * i as f64 / n as f64;
            re * t.sin() + im * t.cos()
        })
        .fold(f64::NEG_INFINITY, f64::max)
}

/// `⟨(1 − a cos θ)⁺⟩` by the midpoint rule on 10⁶ cells (second order: the
/// integrand is Lipschitz with kinks at ±θ_c, error ≤ a·h²·(…)/24 per cell
/// away from the kinks and ≤ a·h² at the two kink cells: < 10⁻¹⁰ in all).
fn brute_mean_band(a: f64) -> f64 {
    let n = 1_000_000;
    let h = TAU / n as f64;
    (0..n)
        .map(|i| (1.0 - a * ((i as f64 + 0.5) * h).cos()).max(0.0))
        .sum::<f64>()
        * h
        / TAU
}

/// Lift-off scenes `(a, b, φ°)`: near a = 1, moderate, large amplitudes.
const SCENES: [(f64, f64, f64); 4] = [
    (1.5, 0.8, 30.0),
    (2.0, 0.3, 200.0),
    (1.0001, 1.2, 75.0),
    (3.0, 2.0, 10.0),
];

fn dimless(a: f64, b: f64, phi: f64) -> Vec<String> {
    vec![
        "--duz-rel".into(),
        a.to_string(),
        "--dux-rel".into(),
        b.to_string(),
        "--phi-deg".into(),
        phi.to_string(),
    ]
}

fn with<'a>(head: &[&'a str], tail: &'a [String]) -> Vec<&'a str> {
    let mut v = head.to_vec();
    v.extend(tail.iter().map(String::as_str));
    v
}

#[test]
fn lift_off_mu_matches_the_fine_stepping_and_brute_critical_velocities() {
    for (a, b, phi) in SCENES {
        let s = dimless(a, b, phi);
        // Critical velocities against the brute-force maximum over the window
        // (backward: the mirrored drive φ + π). Tolerance: the grid's miss
        // (< 1.3e-12 (a + b)) plus rounding of a few ulps of a + b.
        let v = json(&with(&["mu", "--v0", "0", "--json"], &s));
        assert_eq!(v["lifts_off"], true);
        let (cf, cb) = (f(&v, "vc_forward"), f(&v, "vc_backward"));
        let bf = brute_critical(a, b, phi.to_radians());
        let bb = brute_critical(a, b, phi.to_radians() + PI);
        let tol = 1e-11 * (a + b);
        assert!((cf - bf).abs() <= tol, "{a} {b} {phi}: v_c+ {cf} vs {bf}");
        assert!((cb - bb).abs() <= tol, "{a} {b} {phi}: v_c- {cb} vs {bb}");
        for x in [0.0, 0.3, -0.3, 0.8, -0.95, 1.2] {
            let vc = if x >= 0.0 { cf } else { cb };
            let v0 = x * vc;
            let v0s = v0.to_string();
            let (want, ref_bound) = reference(a, b, phi, v0);
            for method in ["auto", "exact"] {
                let o = json(&with(
                    &["mu", "--v0", &v0s, "--method", method, "--json"],
                    &s,
                ));
                let got = f(&o, "mu_over_mu0");
                let bound = f(&o, "error_bound_over_mu0");
                // Beyond the window's critical velocity the contact slides:
                // ±1 exactly, bound 0.
                if x.abs() >= 1.0 {
                    assert_eq!(got, x.signum(), "{a} {b} {phi} {x} {method}");
                    assert_eq!(bound, 0.0);
                    assert_eq!(
                        o["method"],
                        if method == "auto" { "sliding" } else { "exact" }
                    );
                    continue;
                }
                assert_eq!(o["method"], "exact", "{a} {b} {phi} {x} {method}");
                // The two stated bounds together (the reference's is its
                // order-2 discretisation bound at N = 2^16).
                assert!(
                    (got - want).abs() <= bound + ref_bound,
                    "{a} {b} {phi} x={x} {method}: {got} vs stepping {want} (bounds {bound:e} + {ref_bound:e})"
                );
                assert!(bound <= 1e-8, "{bound}");
            }
            // --method fixed: its own stated bound holds against the reference.
            let o = json(&with(
                &[
                    "mu",
                    "--v0",
                    &v0s,
                    "--method",
                    "fixed",
                    "--steps-per-period",
                    "2000",
                    "--json",
                ],
                &s,
            ));
            assert_eq!(o["method"], "fixed");
            assert_eq!(o["converged"], true);
            assert_eq!(o["periods"], 1);
            let (got, bound) = (f(&o, "mu_over_mu0"), f(&o, "error_bound_over_mu0"));
            assert!(
                (got - want).abs() <= bound + ref_bound,
                "{a} {b} {phi} x={x} fixed: {got} vs {want} (bound {bound:e})"
            );
        }
    }
}

#[test]
fn lift_off_text_says_what_changes_meaning() {
    // A physical scene with Δu_z = 2 u_z0: a = 2, W0 = μ0 k_z u_z0/k_x = 0.3 µm.
    let args = [
        "mu", "--mu0", "0.3", "--kz", "1e6", "--kx", "1e6", "--uz0", "1e-6", "--duz", "2e-6",
        "--dux", "1e-7", "--freq", "1000", "--v0", "0",
    ];
    let t = text(&args);
    let w = brute_mean_band(2.0);
    // ⟨w⁺⟩ of eq. L4 against the midpoint rule (error < 1e-10).
    let line = t
        .lines()
        .find(|l| l.starts_with("normal force mean kz<uz+> = "))
        .unwrap_or_else(|| panic!("{t}"));
    let shown: f64 = line["normal force mean kz<uz+> = ".len()..]
        .split_whitespace()
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert!((shown - w).abs() < 1e-9, "{shown} vs {w}");
    for want in [
        "contact      lifts off once per period (duz/uz0 = 2 >= 1)",
        "at rest      mu(0) is unique (the state resets at every landing; no static interval)",
        "v_c          of the contact window (eq. L5), not eq. 8",
    ] {
        assert!(t.lines().any(|l| l == want), "missing {want:?} in\n{t}");
    }
    // μ at rest against the reference (b = k_xΔu_x/(μ0 k_z u_z0) = 1/3).
    let mu_line = t.lines().find(|l| l.starts_with("mu/mu0")).unwrap();
    let mu: f64 = mu_line.split_whitespace().nth(1).unwrap().parse().unwrap();
    let (want, rb) = reference(2.0, 1.0 / 3.0, 0.0, 0.0);
    assert!((mu - want).abs() <= rb + 1e-8, "{mu} vs {want}");

    // The same scene from a file (Δu_z ≥ u_z0 accepted there too).
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("s.toml");
    std::fs::write(
        &p,
        "mu0 = 0.3\nkz = 1e6\nkx = 1e6\nuz0 = 1e-6\nduz = 2e-6\ndux = 1e-7\nfreq = 1000\n",
    )
    .unwrap();
    let ps = p.to_str().unwrap();
    let v = json(&["mu", "--scene", ps, "--v0", "0", "--json"]);
    assert_eq!(v["lifts_off"], true);
    assert!((f(&v, "mu_over_mu0") - want).abs() <= rb + 1e-8);

    // The fixed-step text states the scheme's order and bound.
    let t = text(&[&args[..], &["--method", "fixed"]].concat());
    assert!(
        t.contains(
            "scheme       lift-off stepping: one contact window from the landing (exact), order 2"
        ),
        "{t}"
    );
}

#[test]
fn lift_off_refusals_are_one_line() {
    let s = dimless(1.5, 0.8, 30.0);
    refused(
        &with(&["mu", "--v0", "0.1", "--method", "approx"], &s),
        "--method: approx (eqs. 21/24) assumes permanent contact; this scene lifts off (duz >= uz0): use auto, exact or fixed",
    );
    // min steps = ⌈√(10(1 + a + b)/0.1)⌉ = ⌈√330⌉ = 19 (liftoff::stepping).
    refused(
        &with(&["mu", "--v0", "0.1", "--method", "fixed", "--steps-per-period", "18"], &s),
        "--steps-per-period: this lift-off drive needs at least 19 steps per period (fewer: the stepping's bound 10(1 + a + b)/N^2 would exceed 10 % of mu0)",
    );
    refused(
        &with(
            &["mu", "--v0", "0.1", "--method", "exact", "--tol", "1e-3"],
            &s,
        ),
        "--tol: only --method auto chooses by tolerance (the other methods report their bound)",
    );
    // The permanent-contact refusal still applies to commands that need it.
    refused(
        &["mu", "--duz-rel", "1.5", "--ratio", "-1", "--v0", "0"],
        "--ratio: must be ≥ 0 (got -1)",
    );
}

#[test]
fn mu_is_continuous_across_a_equals_one() {
    // For a = 1 ∓ ε the stretches of the permanent contact and of the
    // lift-off model stay within 2ε of each other (the clamp to a band is
    // 1-Lipschitz and the bands differ by ε·|cos θ| ≤ ε on each side of 1;
    // liftoff module docs), ∫s/∫w then moves by ≤ 2ε plus the airborne arc's
    // O(ε^{3/2}) in both ∫s and ⟨w⁺⟩; so |μ(1 − ε) − μ(1 + ε)| ≤ 4ε + ε^{3/2}·(1 + b)·10
    // plus the two solvers' bounds.
    let eps = 1e-6;
    let mut worst = 0.0f64;
    for (b, phi) in [(0.0, 0.0), (0.5, 30.0), (1.2, 120.0), (3.0, 250.0)] {
        for v in [0.05, 0.4, -0.3, -1.1] {
            let vs = v.to_string();
            let below = json(&with(
                &["mu", "--v0", &vs, "--json"],
                &dimless(1.0 - eps, b, phi),
            ));
            let above = json(&with(
                &["mu", "--v0", &vs, "--json"],
                &dimless(1.0 + eps, b, phi),
            ));
            assert_eq!(below["lifts_off"], false);
            assert_eq!(above["lifts_off"], true);
            let d = (f(&below, "mu_over_mu0") - f(&above, "mu_over_mu0")).abs();
            let tol = 4.0 * eps
                + 10.0 * (1.0 + b) * eps.powf(1.5)
                + f(&below, "error_bound_over_mu0")
                + f(&above, "error_bound_over_mu0");
            assert!(d <= tol, "b {b} φ {phi} v {v}: jump {d:e} > {tol:e}");
            worst = worst.max(d);
            // The critical velocities are continuous too: the window fills
            // the period as a → 1⁺ and eq. L5 becomes eq. 8 (|Δ| ≤ (2 + b)·√(2ε)
            // from the window's ends moving by θ_c ≈ √(2ε) plus Δa = 2ε).
            for k in ["vc_forward", "vc_backward"] {
                let dv = (f(&below, k) - f(&above, k)).abs();
                assert!(dv <= (2.0 + b) * (2.0 * eps).sqrt(), "{k}: {dv:e}");
            }
        }
    }
    eprintln!("largest |mu(1-eps) - mu(1+eps)| = {worst:e} at eps = {eps:e}");
}

#[test]
fn static_and_classify_with_lift_off() {
    let s = dimless(1.5, 0.8, 30.0);
    let (want, rb) = reference(1.5, 0.8, 30.0, 0.0);
    let v = json(&with(&["static", "--json"], &s));
    assert_eq!(v["lifts_off"], true);
    assert_eq!(v["static_exists"], false);
    let got = f(&v, "mu_at_rest_over_mu0");
    assert!(
        (got - want).abs() <= rb + f(&v, "error_bound_over_mu0"),
        "{got} vs {want}"
    );
    assert!((f(&v, "mean_normal_force_over_kz_uz0") - brute_mean_band(1.5)).abs() < 1e-9);
    let t = text(&with(&["static"], &s));
    assert!(
        t.lines().any(|l| l
            == "static interval        none in the permanent-contact sense: the stretch resets at every landing"),
        "{t}"
    );
    assert!(!t.contains("static interval u_x0"), "{t}");
    assert!(!t.contains("paper eq. 18"), "{t}");

    // μ(0) ≠ 0 beyond its bound: an actuator; μ(0±) are the unique μ(0).
    let c = json(&with(&["classify", "--json"], &s));
    assert_eq!(c["regime"], "actuator");
    assert_eq!(c["lifts_off"], true);
    assert_eq!(c["mu_0plus_over_mu0"], c["mu_0minus_over_mu0"]);
    assert!((f(&c, "mu_0plus_over_mu0") - want).abs() <= rb + 1e-8);
    assert!(c["rule_of_thumb"].is_null());
    // Normal oscillation only (b = 0): the drive is its own mirror image, so
    // μ(−v) = −μ(v) exactly and μ(0) = 0: active control.
    let c = json(&with(&["classify", "--json"], &dimless(2.0, 0.0, 0.0)));
    assert_eq!(c["regime"], "active_control");
    assert!(f(&c, "mu_0plus_over_mu0").abs() <= 1e-9);
}

#[test]
fn curve_and_map_across_lift_off() {
    let dir = tempfile::tempdir().unwrap();
    // A curve through v0 = 0: one row there (μ at rest is unique).
    let csv = dir.path().join("c.csv");
    let cs = csv.to_str().unwrap();
    run_ok(&with(
        &[
            "curve",
            "--v-rel-min",
            "-0.5",
            "--v-rel-max",
            "0.5",
            "--points",
            "5",
            "--csv",
            cs,
        ],
        &dimless(1.5, 0.8, 30.0),
    ));
    let body = std::fs::read_to_string(&csv).unwrap();
    let rows: Vec<&str> = body.lines().skip(1).collect();
    assert_eq!(rows.len(), 5, "{body}");
    for r in rows {
        let c: Vec<&str> = r.split(',').collect();
        let (v0, mu, bound): (f64, f64, f64) = (
            c[0].parse().unwrap(),
            c[3].parse().unwrap(),
            c[5].parse().unwrap(),
        );
        let (want, rb) = reference(1.5, 0.8, 30.0, v0);
        assert!((mu - want).abs() <= bound + rb, "{r}: {want}");
    }
    // A μ map at a = 1.5, cells against the reference.
    let png = dir.path().join("m.png");
    let mcsv = dir.path().join("m.csv");
    run_ok(&[
        "map",
        "--duz-rel",
        "1.5",
        "--res",
        "3",
        "--v-rel",
        "0.5",
        "--plot",
        png.to_str().unwrap(),
        "--csv",
        mcsv.to_str().unwrap(),
    ]);
    let rows = csv_rows(&mcsv);
    assert_eq!(rows.len(), 9);
    for r in rows {
        let g = |k: &str| r.num(k);
        let (phi, ratio, v0) = (g("phi_deg"), g("ratio"), g("v0"));
        let (want, rb) = reference(1.5, ratio * 1.5, phi, v0);
        let mu = g("mu_over_mu0");
        assert!(
            (mu - want).abs() <= g("error_bound_over_mu0") + rb,
            "{r}: {want}"
        );
    }
    // A regime map at a = 1.5: written, every cell classified.
    let out = run_ok(&[
        "map",
        "--duz-rel",
        "1.5",
        "--res",
        "4",
        "--plot",
        // A file of its own: the μ map's plot exists (output-files policy).
        dir.path().join("regimes.png").to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.starts_with("16 cells: "), "{err}");
}

/// `∫s dθ` and `∫w⁺ dθ` over one period of one MDR spring with band offset
/// `d` (`w = d − a cos θ`, `−a < d ≤ a`: it touches in the window
/// `[θ_c, 2π − θ_c]`, `cos θ_c = d/a`, and lands with s = 0), by the plain
/// fixed-step scheme of the paper (add the drive increment, clamp to ±w)
/// started exactly at the landing with `n` steps per period and the
/// trapezoid rule — written here from the model's statement (a spring of the
/// MDR bed that lifts off and lands, as the README states it), independent of
/// model-core's code. ∫w⁺ is closed form.
fn spring_brute(d: f64, a: f64, b: f64, phi: f64, v: f64, n: usize) -> (f64, f64) {
    let tc = (d / a).clamp(-1.0, 1.0).acos();
    let (tl, tr) = (tc, TAU - tc);
    let band = |t: f64| d - a * t.cos();
    let ux = |t: f64| v * t + b * (t + phi).cos();
    let h = TAU / n as f64;
    let mut t = tl;
    let mut s = 0.0f64;
    let mut integral = 0.0;
    while t < tr {
        let t1 = (t + h).min(tr);
        let w = band(t1).max(0.0);
        let s1 = (s + ux(t1) - ux(t)).clamp(-w, w);
        integral += 0.5 * (s + s1) * (t1 - t);
        s = s1;
        t = t1;
    }
    let wint = d * (tr - tl) + a * (tl.sin() - tr.sin());
    (integral, wint)
}

/// μ/μ0 of a power-law profile `d(ξ) = 1 − ξⁿ` with `a ≥ 1` (every spring
/// lifts off) over `m` springs: ξ = ξ_max(1 − cos t)/2, midpoint rule in t
/// (smooth at the rim where ∫w⁺ ∝ (a + d)^{3/2}), ξ_max = (1 + a)^{1/n}.
fn profile_brute(nexp: f64, a: f64, b: f64, phi: f64, v: f64, m: usize, n: usize) -> f64 {
    let xi_max = (1.0 + a).powf(1.0 / nexp);
    let (mut num, mut den) = (0.0, 0.0);
    for j in 0..m {
        let t = PI * (j as f64 + 0.5) / m as f64;
        let xi = 0.5 * xi_max * (1.0 - t.cos());
        let jac = 0.5 * xi_max * t.sin();
        let (si, wi) = spring_brute(1.0 - xi.powf(nexp), a, b, phi, v, n);
        num += si * jac;
        den += wi * jac;
    }
    num / den
}

#[test]
fn curved_profiles_with_lift_off_match_a_brute_force_over_springs() {
    // a = 1.5: every spring lifts off, so each is one window from its
    // landing (no transient). Tolerance: the CLI's bound plus the brute
    // force's two errors, each estimated from the brute force itself: the
    // time stepping (order 2 with the exact landing) by the change from N/2
    // to N steps, the ξ-quadrature (midpoint rule, order 2) by the change
    // from m/2 to m springs — for an order-2 method the error at the finer
    // level is about a third of the change; the whole change is used.
    let (a, b, phi_deg) = (1.5, 0.5, 45.0);
    let phi = f64::to_radians(phi_deg);
    let s = dimless(a, b, phi_deg);
    for (profile, nexp) in [("sphere", 2.0), ("cone", 1.0)] {
        for v in [0.0, 0.4, -0.6] {
            let vs = v.to_string();
            let o = json(&with(
                &["mu", "--v0", &vs, "--profile", profile, "--json"],
                &s,
            ));
            assert_eq!(o["profile"], profile);
            assert_eq!(f(&o, "exponent"), nexp);
            assert_eq!(o["method"], "mdr", "{o}");
            let got = f(&o, "mu_over_mu0");
            let fine = profile_brute(nexp, a, b, phi, v, 400, 4096);
            let coarse = profile_brute(nexp, a, b, phi, v, 200, 4096);
            let half_n = profile_brute(nexp, a, b, phi, v, 400, 2048);
            let tol = f(&o, "error_bound_over_mu0") + (fine - coarse).abs() + (fine - half_n).abs();
            assert!(
                (got - fine).abs() <= tol,
                "{profile} v {v}: {got} vs brute force {fine} (m/2: {coarse}), tol {tol:e}"
            );
            eprintln!(
                "{profile} v = {v}: fricctl {got}, brute force {fine}, |Δ| = {:e}",
                (got - fine).abs()
            );
        }
    }
}

#[test]
fn profile_flags_and_refusals() {
    let s = dimless(0.5, 0.8, 30.0);
    // --profile flat is the flat punch exactly (same JSON as no flag).
    let plain = json(&with(&["mu", "--v0", "0.2", "--json"], &s));
    let flat = json(&with(
        &["mu", "--v0", "0.2", "--profile", "flat", "--json"],
        &s,
    ));
    assert_eq!(plain, flat);
    assert_eq!(plain["profile"], "flat");
    assert!(plain["exponent"].is_null());
    // A sphere given in SI units is the same scene as its groups (uz0 read
    // as d0, kz/kx as E*/G*): μ/μ0 agrees to the two bounds.
    // W0 = 0.3·1e6·1e-6/1e6 = 3e-7 m; a = 0.5, b = 0.8 → dux = 2.4e-7 m;
    // ω = 2π·1000, v0 = 0.2 ωW0.
    let w = TAU * 1000.0 * 3e-7;
    let si = json(&[
        "mu",
        "--mu0",
        "0.3",
        "--kz",
        "1e6",
        "--kx",
        "1e6",
        "--uz0",
        "1e-6",
        "--duz",
        "0.5e-6",
        "--dux",
        "2.4e-7",
        "--freq",
        "1000",
        "--phi-deg",
        "30",
        "--v0",
        &(0.2 * w).to_string(),
        "--profile",
        "sphere",
        "--json",
    ]);
    let gr = json(&with(
        &["mu", "--v0", "0.2", "--profile", "sphere", "--json"],
        &s,
    ));
    let tol = f(&si, "error_bound_over_mu0") + f(&gr, "error_bound_over_mu0");
    assert!((f(&si, "mu_over_mu0") - f(&gr, "mu_over_mu0")).abs() <= tol);
    // The scene file carries the profile too.
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("s.toml");
    std::fs::write(
        &p,
        "mu0 = 0.3\nkz = 1e6\nkx = 1e6\nuz0 = 1e-6\nduz = 0.5e-6\ndux = 2.4e-7\nfreq = 1000\nphi_deg = 30\nprofile = \"sphere\"\n",
    )
    .unwrap();
    let file = json(&[
        "mu",
        "--scene",
        p.to_str().unwrap(),
        "--v0",
        &(0.2 * w).to_string(),
        "--json",
    ]);
    assert_eq!(file["profile"], "sphere");
    assert_eq!(file["mu_over_mu0"], si["mu_over_mu0"]);

    // `mu --v0 0.2` on the scene with each refused profile flag combination.
    let v = ["mu", "--v0", "0.2"];
    for (extra, want) in [
        (
            &["--profile", "power"][..],
            "--exponent: missing (--profile power needs --exponent n > 0)",
        ),
        (
            &["--profile", "sphere", "--exponent", "2"][..],
            "--exponent: only with --profile power (the sphere profile has n = 2)",
        ),
        (
            &["--exponent", "3"][..],
            "--exponent: only with --profile power (the flat profile has no exponent)",
        ),
        (
            &["--profile", "power", "--exponent", "0"][..],
            "--exponent: must be > 0 (got 0)",
        ),
        (
            // (1.5)^(1/n) overflows 1e100 below n = ln 1.5/ln 1e100 = 1.761e-3.
            &["--profile", "power", "--exponent", "1e-5"][..],
            "--exponent: n = 1e-5 is too small for Δu_z/u_z0 = 0.5: the springs' reach (1 + a)^(1/n) overflows (use n ≥ 1.761e-3)",
        ),
        (
            &["--profile", "sphere", "--method", "fixed"][..],
            "--profile: --method fixed is for the flat punch; a sphere profile is computed by the MDR quadrature (--method auto or exact)",
        ),
        (
            &["--profile", "cone", "--method", "approx"][..],
            "--profile: --method approx is for the flat punch; a cone profile is computed by the MDR quadrature (--method auto or exact)",
        ),
    ] {
        refused(&with(&[&v[..], extra].concat(), &s), want);
    }
    // `static` on a curved profile (docs/guide/lift-off-and-profiles.md,
    // eqs. S1–S3): a = 0.5, b = 0.8, φ = 30°: c = 1.25810, c' = 0.44405
    // (eq. 8), σ = c + c' = 1.70215 < 2, so the interval exists (S2), and
    // its width μ(0+) − μ(0−) is eq. S3 by hand: ξ_m = (1 − σ/2)^{1/2},
    // ((2 − σ)ξ_m − 2ξ_m³/3)/D with D = (2/3)⟨(1 − a cos θ)^{3/2}⟩ (M5, by
    // the trapezoid rule, spectrally exact here).
    let st = json(&with(&["static", "--profile", "sphere", "--json"], &s));
    assert_eq!(st["profile"], "sphere");
    assert_eq!(st["static_exists"], true);
    assert_eq!(st["lifts_off"], false);
    let (lo, hi) = (f(&st, "static_lo_over_mu0"), f(&st, "static_hi_over_mu0"));
    assert_eq!(
        (lo, hi),
        (f(&st, "mu_0minus_over_mu0"), f(&st, "mu_0plus_over_mu0"))
    );
    let (a, b, phi) = (0.5f64, 0.8f64, 30f64.to_radians());
    let c = ((a + b * phi.cos()).powi(2) + (b * phi.sin()).powi(2)).sqrt();
    let cb = ((b * phi.cos() - a).powi(2) + (b * phi.sin()).powi(2)).sqrt();
    assert!((f(&st, "vc_forward") - c).abs() < 1e-12 && (f(&st, "vc_backward") - cb).abs() < 1e-12);
    let sigma = c + cb;
    let xm = (1.0 - sigma / 2.0).sqrt();
    let k = 4096;
    let d = (0..k)
        .map(|j| (1.0 - a * (TAU * j as f64 / k as f64).cos()).powf(1.5))
        .sum::<f64>()
        / k as f64
        * (2.0 / 3.0);
    let width = ((2.0 - sigma) * xm - 2.0 * xm.powi(3) / 3.0) / d;
    let bound = f(&st, "error_bound_over_mu0");
    assert!(
        ((hi - lo) - width).abs() <= 2.0 * bound + 1e-12,
        "width {} vs eq. S3 {width} (bound {bound:e})",
        hi - lo
    );
    // `classify` reports the same interval under the same keys.
    let cl = json(&with(&["classify", "--profile", "sphere", "--json"], &s));
    assert_eq!(cl["static_exists"], true);
    assert_eq!(
        (f(&cl, "static_lo_over_mu0"), f(&cl, "static_hi_over_mu0")),
        (lo, hi)
    );
    let mut file_bad = std::fs::read_to_string(&p).unwrap();
    file_bad = file_bad.replace("sphere", "cube");
    std::fs::write(&p, file_bad).unwrap();
    refused(
        &["mu", "--scene", p.to_str().unwrap(), "--v0", "0"],
        "--scene: profile = \"cube\" is not one of flat, sphere, cone, power",
    );
}

#[test]
fn classify_and_curve_with_a_profile() {
    // Normal oscillation only (b = 0): the drive is its own mirror image, so
    // μ(−v) = −μ(v) for every profile and μ(0−) = −μ(0+) exactly (the
    // quadrature mirrors spring by spring): active control.
    let c = json(&[
        "classify",
        "--duz-rel",
        "0.5",
        "--dux-rel",
        "0",
        "--profile",
        "sphere",
        "--json",
    ]);
    assert_eq!(c["regime"], "active_control", "{c}");
    assert_eq!(c["profile"], "sphere");
    // c = c' = a = 0.5, σ = 1 < 2: a static interval (eq. S2), [μ(0−), μ(0+)].
    assert_eq!(c["static_exists"], true);
    assert!(c["rule_of_thumb"].is_null());
    let (p, m) = (f(&c, "mu_0plus_over_mu0"), f(&c, "mu_0minus_over_mu0"));
    assert_eq!(
        (f(&c, "static_lo_over_mu0"), f(&c, "static_hi_over_mu0")),
        (m, p)
    );
    // Closed form at b = 0, V → 0⁺: a permanent spring (d > a) is the flat
    // punch scaled by d with b/d = 0, so ⟨s⟩ = d·(1 − a/d) = d − a; an
    // intermittent one lands at s = 0 and the drive does not move it, ⟨s⟩ = 0.
    // N = ∫₀^{ξ_a} (1 − ξ² − a) dξ = (2/3)(1 − a)^{3/2}; D = ∫⟨w⁺⟩ dξ with each
    // spring's ⟨w⁺⟩ = (d(π − θ_c) + a sin θ_c)/π (cos θ_c = d/a) by the
    // midpoint rule (2·10⁵ cells: error below 10⁻¹¹). Allowed: the command's
    // tolerance (`eval::PROFILE_TOL`) plus that.
    let a = 0.5f64;
    let xi_max = (1.0 + a).sqrt();
    let cells = 200_000;
    let den: f64 = (0..cells)
        .map(|i| {
            let xi = (f64::from(i) + 0.5) * xi_max / f64::from(cells);
            let d = 1.0 - xi * xi;
            let band = if d >= a {
                d
            } else {
                let tc = (d / a).acos();
                (d * (PI - tc) + a * tc.sin()) / PI
            };
            band * xi_max / f64::from(cells)
        })
        .sum();
    let closed = 2.0 / 3.0 * (1.0 - a).powf(1.5) / den;
    assert!(
        (p - closed).abs() <= fric_analysis::eval::PROFILE_TOL + 1e-11,
        "mu(0+) {p} vs closed form {closed}"
    );
    assert!((p + m).abs() <= 1e-9, "{p} {m}");
    assert!(f(&c, "asymmetry") <= 1e-9);
    // A curve through v0 = 0 with a < 1: two rows there, μ(0−) then μ(0+).
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("c.csv");
    run_ok(&[
        "curve",
        "--duz-rel",
        "0.5",
        "--dux-rel",
        "0",
        "--profile",
        "cone",
        "--v-rel-min",
        "-0.5",
        "--v-rel-max",
        "0.5",
        "--points",
        "3",
        "--csv",
        csv.to_str().unwrap(),
    ]);
    let body = std::fs::read_to_string(&csv).unwrap();
    let rows: Vec<Vec<&str>> = body
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    assert_eq!(rows.len(), 4, "{body}");
    assert_eq!((rows[1][0], rows[2][0]), ("0.0", "0.0"), "{body}");
    assert!(rows.iter().all(|r| r[4] == "mdr"), "{body}");
    let mu = |i: usize| rows[i][3].parse::<f64>().unwrap();
    // Odd law (b = 0): the rows mirror each other.
    assert!(
        (mu(0) + mu(3)).abs() <= 1e-8 && (mu(1) + mu(2)).abs() <= 1e-8,
        "{body}"
    );
}

#[test]
fn profile_mu_map_cells_match_the_brute_force() {
    // map --profile cone --v-rel 0.5 at a = 1.5: each cell against the brute
    // force over springs, tolerance as in the test above.
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("m.png");
    let csv = dir.path().join("m.csv");
    run_ok(&[
        "map",
        "--duz-rel",
        "1.5",
        "--res",
        "2",
        "--v-rel",
        "0.5",
        "--profile",
        "cone",
        "--plot",
        png.to_str().unwrap(),
        "--csv",
        csv.to_str().unwrap(),
    ]);
    let rows = csv_rows(&csv);
    assert_eq!(rows.len(), 4);
    for r in rows {
        let g = |k: &str| r.num(k);
        assert_eq!(r.get("method"), "mdr", "{r}");
        let (phi, b, v) = (g("phi_deg").to_radians(), g("ratio") * 1.5, g("v0"));
        let fine = profile_brute(1.0, 1.5, b, phi, v, 400, 4096);
        let coarse = profile_brute(1.0, 1.5, b, phi, v, 200, 4096);
        let half_n = profile_brute(1.0, 1.5, b, phi, v, 400, 2048);
        let tol = g("error_bound_over_mu0") + (fine - coarse).abs() + (fine - half_n).abs();
        let mu = g("mu_over_mu0");
        assert!(
            (mu - fine).abs() <= tol,
            "{r}: brute force {fine}, tol {tol:e}"
        );
    }
}

/// `curve --profile`: runs where μ(v) is smooth come from the interpolant
/// (`mdr-interpolated`, bound eq. C1 ≤ the tolerance), `--per-point` gives
/// each velocity its own quadrature (`mdr`), and the two agree within
/// their bounds except where the quadrature's own estimate fails
/// (docs/guide/speed.md: 0.1–0.35 % of velocities on dense curves; here
/// at most 2 of 601, counted). `--per-point` on a flat punch is refused,
/// naming the flag, before any output.
#[test]
fn a_profile_curve_interpolates_and_per_point_does_not() {
    let dir = tempfile::tempdir().unwrap();
    let csv = |name: &str, extra: &[&str]| {
        let path = dir.path().join(name);
        let p = path.to_str().unwrap().to_string();
        let base = [
            "curve",
            "--profile",
            "sphere",
            "--duz-rel",
            "0.5",
            "--dux-rel",
            "0.7",
            "--phi-deg",
            "60",
            "--v-rel-min",
            "0.01",
            "--v-rel-max",
            "0.99",
            "--points",
            "601",
            "--csv",
            &p,
        ];
        run_ok(&[&base[..], extra].concat());
        csv_rows(&path)
    };
    let interp = csv("i.csv", &[]);
    let each = csv("p.csv", &["--per-point"]);
    assert_eq!(interp.len(), 601);
    assert_eq!(each.len(), 601);
    let n_interp = interp
        .iter()
        .filter(|r| r.get("method") == "mdr-interpolated")
        .count();
    // 441 here: the runs next to the ends, where μ(v) is not smooth, go to
    // the quadrature.
    assert!(n_interp >= 400, "{n_interp} of 601 interpolated");
    assert!(each.iter().all(|r| r.get("method") == "mdr"));
    let mut disagree = 0;
    for (i, p) in interp.iter().zip(&each) {
        assert_eq!(i.get("v0"), p.get("v0"));
        assert!(i.num("error_bound_over_mu0") <= 1e-9, "{i}");
        let gap = (i.num("mu_over_mu0") - p.num("mu_over_mu0")).abs();
        if gap > i.num("error_bound_over_mu0") + p.num("error_bound_over_mu0") {
            disagree += 1;
        }
    }
    assert!(disagree <= 2, "{disagree} of 601 disagree");
    let out = fricctl()
        .args([
            "curve",
            "--duz-rel",
            "0.5",
            "--dux-rel",
            "0.7",
            "--v-rel-min",
            "0",
            "--v-rel-max",
            "0.5",
            "--points",
            "3",
            "--per-point",
        ])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.starts_with("error: --per-point: only for a curved --profile"),
        "{err}"
    );
    assert!(out.stdout.is_empty());
}
