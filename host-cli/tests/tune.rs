//! `fricctl tune`: JSON keys and values checked by an independent computation
//! (the fixed-step scheme at fine N, or a dense brute-force scan), the text
//! layout, and every refusal (exit 2, one line naming the flag).

use integration_tests::fixed_warm;
use model_core::exact;
use model_core::{Drive, Libm, Scene, SceneParams};
use serde_json::Value;

mod common;

use common::cli::{fricctl, PHYS};

fn run(args: &[&str]) -> std::process::Output {
    fricctl()
        .args(["tune"])
        .args(args)
        .args(PHYS)
        .output()
        .unwrap()
}

/// `fricctl tune ARGS PHYS --json`, asserted to succeed.
fn json(args: &[&str]) -> Value {
    common::cli::json(&[&["tune"], args, PHYS].concat())
}

/// Runs a refused command: exit 2, nothing on stdout, one stderr line starting
/// with `error: --{flag}`; returns that line.
fn refused(args: &[&str], flag: &str) -> String {
    let out = run(args);
    assert_eq!(out.status.code(), Some(2), "{args:?}");
    assert!(out.stdout.is_empty(), "{args:?}: stdout not empty");
    let err = String::from_utf8(out.stderr).unwrap();
    assert_eq!(err.lines().count(), 1, "{args:?}: {err}");
    assert!(
        err.starts_with(&format!("error: --{flag}")),
        "{args:?}: {err}"
    );
    err
}

/// The physical scene with Δuz, Δux, φ replaced.
fn scene_with(duz: f64, dux: f64, phi_deg: f64) -> Scene<f64> {
    Scene::new(SceneParams {
        mu0: 0.3,
        kz: 2e6,
        kx: 1.5e6,
        uz0: 5e-6,
        duz,
        dux,
        omega: std::f64::consts::TAU * 40e3,
        phi: phi_deg.to_radians(),
    })
    .unwrap()
}

fn f(v: &Value, key: &str) -> f64 {
    v[key]
        .as_f64()
        .unwrap_or_else(|| panic!("{key} missing in {v}"))
}

/// Round trip through the CLI: the reported drive, rebuilt from the JSON's
/// own `duz`, `dux`, `phi_deg`, gives the target under the fixed-step scheme
/// at N = 65 536 within that scheme's stated bound plus the exact bound and
/// the reported residual (tests/tests/inverse.rs explains the sum).
#[test]
fn target_json_round_trips() {
    for adjust in ["duz", "dux", "phase"] {
        let v = json(&[
            "--v0",
            "0.05",
            "--target-mu-rel",
            "0.6",
            "--adjust",
            adjust,
            "--json",
        ]);
        for key in [
            "adjust",
            "duz",
            "dux",
            "phi_deg",
            "duz_rel",
            "dux_rel",
            "range_lo",
            "range_hi",
            "scan_cells",
            "v0",
            "target_mu",
            "target_mu_over_mu0",
            "mu",
            "mu_over_mu0",
            "residual_over_mu0",
            "method",
            "error_bound_over_mu0",
            "solutions",
            "solutions_found",
            "start",
            "reachable_min_over_mu0",
            "reachable_max_over_mu0",
        ] {
            assert!(v.get(key).is_some(), "{adjust}: {key} missing in {v}");
        }
        assert_eq!(v["adjust"], adjust);
        assert_eq!(v["method"], "exact");
        assert_eq!(f(&v, "target_mu"), 0.6 * 0.3);
        let s = scene_with(f(&v, "duz"), f(&v, "dux"), f(&v, "phi_deg"));
        let d = s.drive();
        let vv = s.dimensionless_velocity(0.05).unwrap();
        let (mu_ref, ref_bound) = fixed_warm(&d, vv, 65_536);
        let bound = f(&v, "error_bound_over_mu0");
        // The bound (1e-9·(1 + b)) of the drive rebuilt from the printed values:
        // equal up to the rounding of b through dux → W0.
        let rebuilt = exact::error_bound::<f64, Libm>(&d);
        assert!((bound - rebuilt).abs() <= 1e-12 * rebuilt);
        let residual = f(&v, "residual_over_mu0");
        assert!(residual.abs() <= bound);
        assert!(
            (mu_ref - 0.6).abs() <= ref_bound + bound + residual.abs(),
            "{adjust}: fixed-step {mu_ref}"
        );
        // The reported solution is among the listed ones, and the nearest to the scene's value.
        let sols: Vec<f64> = v["solutions"]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect();
        let shown = match adjust {
            "duz" => f(&v, "duz"),
            "dux" => f(&v, "dux"),
            _ => f(&v, "phi_deg"),
        };
        assert!(sols.contains(&shown), "{adjust}: {shown} not in {sols:?}");
        let start = f(&v, "start");
        let dist = |x: f64| {
            let d = (x - start).abs();
            if adjust == "phase" {
                d.min(360.0 - d)
            } else {
                d
            }
        };
        assert!(sols.iter().all(|&x| dist(shown) <= dist(x)));
    }
}

/// The amplitude limits: defaults (1 − 0.05)·uz0 = 4.75 µm and 10·W0 = 20 µm.
#[test]
fn default_limits() {
    let v = json(&[
        "--v0",
        "0.05",
        "--target-mu-rel",
        "0.6",
        "--adjust",
        "duz",
        "--json",
    ]);
    assert!((f(&v, "range_hi") - 4.75e-6).abs() <= 1e-20);
    let v = json(&[
        "--v0",
        "0.05",
        "--target-mu-rel",
        "0.6",
        "--adjust",
        "dux",
        "--json",
    ]);
    assert!((f(&v, "range_hi") - 20e-6).abs() <= 1e-18);
    let v = json(&[
        "--v0",
        "0.05",
        "--target-mu-rel",
        "0.6",
        "--adjust",
        "duz",
        "--liftoff-margin",
        "0.2",
        "--json",
    ]);
    assert!((f(&v, "range_hi") - 4e-6).abs() <= 1e-20);
    assert!(f(&v, "duz") <= 4e-6);
}

#[test]
fn target_text_layout() {
    let out = run(&["--v0", "0.05", "--target-mu-rel", "0.6", "--adjust", "duz"]);
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    let heads: Vec<&str> = text
        .lines()
        .map(|l| l.split_whitespace().next().unwrap_or(""))
        .collect();
    assert_eq!(
        heads,
        [
            "adjust",
            "v0",
            "target",
            "duz",
            "dux",
            "phi",
            "mu",
            "residual",
            "error",
            "solutions",
            "reachable",
            "search"
        ]
    );
    // Values start in one column (16), units are named.
    for l in text.lines() {
        let b = l.as_bytes();
        assert!(b.len() > 16 && b[15] == b' ' && b[16] != b' ', "{l:?}");
    }
    assert!(text.contains(" m/s"));
    assert!(text.contains("duz             ") && text.contains(" m "));
    assert!(text.contains("(units of mu0, method exact)"));
}

/// Half a unit in the last printed digit of the decimal number `s` (as
/// printed in a message: the reading's rounding).
fn half_ulp_of_printed(s: &str) -> f64 {
    let (mantissa, exp) = match s.find(['e', 'E']) {
        Some(i) => (&s[..i], s[i + 1..].parse::<i32>().unwrap()),
        None => (s, 0),
    };
    let decimals = mantissa.split_once('.').map_or(0, |(_, d)| d.len()) as i32;
    0.5 * 10f64.powi(exp - decimals)
}

/// Out of reach: the message gives the reachable range, whose ends are
/// checked against a dense brute-force scan of the exact law over the
/// default range a = Δuz/uz0 ∈ [0, 0.95] (4 097 points, 16× the search's
/// scan): the reported ends are attained values, so no wider than the law's
/// range — the dense range widened by the scan's Lipschitz bound (largest
/// secant slope × half the spacing: an extremum between two dense points)
/// — and no narrower than the dense scan's by more than the solver's bound;
/// both plus the rounding of the printed numbers.
#[test]
fn out_of_reach_is_refused_with_the_range() {
    let err = refused(
        &["--v0", "0.05", "--target-mu-rel", "0.02", "--adjust", "duz"],
        "target-mu-rel",
    );
    assert!(
        err.contains("0.02 is out of reach by adjusting duz at v0 = 0.05 m/s: reachable "),
        "{err}"
    );
    assert!(err.contains("(duz from 0 to 4.75e-6 m)"), "{err}");
    let range = err.split("reachable ").nth(1).unwrap();
    let range = range.split(" (").next().unwrap();
    let (lo_s, hi_s) = range.split_once('…').unwrap();
    let (lo, hi): (f64, f64) = (lo_s.parse().unwrap(), hi_s.parse().unwrap());
    let s = integration_tests::physical_scene();
    let g = s.groups();
    let vv = s.dimensionless_velocity(0.05).unwrap();
    let (mut dmin, mut dmax) = (f64::INFINITY, f64::NEG_INFINITY);
    let (mut prev, mut slope) = (f64::NAN, 0.0f64);
    let h = 0.95 / 4096.0;
    for i in 0..4097 {
        let a = 0.95 * i as f64 / 4096.0;
        let d = model_core::Drive::new::<Libm>(a, g.dux_rel, g.phi);
        let m = exact::mu_over_mu0::<f64, Libm>(&d, vv).unwrap();
        dmin = dmin.min(m);
        dmax = dmax.max(m);
        if i > 0 {
            slope = slope.max((m - prev).abs() / h);
        }
        prev = m;
    }
    let bound = exact::error_bound::<f64, Libm>(&s.drive());
    let (plo, phi_) = (half_ulp_of_printed(lo_s), half_ulp_of_printed(hi_s));
    assert!(
        lo <= dmin + bound + plo && hi >= dmax - bound - phi_,
        "{lo}..{hi} vs dense {dmin}..{dmax}"
    );
    let over = slope * h / 2.0 + bound;
    assert!(
        lo >= dmin - over - plo && hi <= dmax + over + phi_,
        "{lo}..{hi} beyond dense {dmin}..{dmax} ± {over:e}"
    );
    assert!(0.02 < lo);
    // In units of μ with --target-mu.
    let err = refused(
        &["--v0", "0.05", "--target-mu", "0.006", "--adjust", "duz"],
        "target-mu",
    );
    assert!(err.contains("0.006 is out of reach"), "{err}");
}

/// `--maximize asymmetry` over the phase: JSON keys and the closed form.
/// With a static equilibrium at every phase (a + b = 0.75 < 1 for the
/// README's scene, a = 0.4, b = 0.35), μ(0±) at φ ∈ {0, π} are
/// ±(1 − |a − b|), ∓(1 − (a + b)) (the static interval `[c' − 1, 1 − c]`),
/// |μ(0⁺) + μ(0⁻)| = 2·min(a, b) = 0.70 there, and |c − c'| ≤ 2·min(a, b)
/// at every φ (triangle inequality): the optimum is 0.70 at φ* ∈ {0°, 180°}
/// (tests/inverse.rs checks the closed form on random scenes). Tolerances:
/// the value, the reported bound (two exact bounds); μ(0±), one exact bound
/// each; the phase from the curvature at the maximum, asym ≈ 0.70 − κφ²/2,
/// κ = ab/|a − b| + ab/(a + b) = 2.99: |φ − φ*| ≤ √(2·bound/κ).
#[test]
fn maximize_asymmetry_json() {
    let v = json(&["--maximize", "asymmetry", "--adjust", "phase", "--json"]);
    for key in [
        "adjust",
        "objective",
        "value",
        "error_bound_over_mu0",
        "regime",
        "asymmetry",
        "stall_force_forward",
        "mu_0plus_over_mu0",
        "mu_0minus_over_mu0",
        "duz",
        "dux",
        "phi_deg",
        "scan_cells",
    ] {
        assert!(v.get(key).is_some(), "{key} missing in {v}");
    }
    assert_eq!(v["objective"], "asymmetry");
    assert_eq!(v["regime"], "dynamic_ratchet");
    let g = integration_tests::physical_scene().groups();
    let (a, b) = (g.duz_rel, g.dux_rel);
    let bound = f(&v, "error_bound_over_mu0");
    let want = 2.0 * a.min(b);
    assert!((want - 0.70).abs() < 1e-12);
    for key in ["value", "asymmetry"] {
        assert!(
            (f(&v, key) - want).abs() <= bound,
            "{key} {} vs 2·min(a, b) = {want}",
            f(&v, key)
        );
    }
    let kappa = a * b / (a - b).abs() + a * b / (a + b);
    let dphi = (2.0 * bound / kappa).sqrt().to_degrees();
    let phi = f(&v, "phi_deg");
    let (plus, minus) = (f(&v, "mu_0plus_over_mu0"), f(&v, "mu_0minus_over_mu0"));
    let one = bound / 2.0;
    if (phi - 180.0).abs() <= dphi {
        assert!((plus - (1.0 - (a - b).abs())).abs() <= one, "μ(0+) {plus}");
        assert!((minus + (1.0 - (a + b))).abs() <= one, "μ(0−) {minus}");
    } else {
        assert!(
            phi.min(360.0 - phi) <= dphi,
            "φ* = {phi}° (allowed ±{dphi:e}° of 0 or 180)"
        );
        assert!((plus - (1.0 - (a + b))).abs() <= one, "μ(0+) {plus}");
        assert!(
            (minus + (1.0 - (a - b).abs())).abs() <= one,
            "μ(0−) {minus}"
        );
    }
    assert_eq!(f(&v, "stall_force_forward"), 0.0);
}

/// `--maximize stall-force` over Δux: text layout and the closed form. With
/// a static equilibrium μ(0⁺) = 1 − c, c = |a + b e^{iφ}|, falling with b
/// while the static interval `[c' − 1, 1 − c]` is non-empty (c + c' ≤ 2); at
/// its end μ(0⁺) = μ(0⁻) and c − c' = (c² − c'²)/2 = 2ab cos φ, so the stall
/// force is `ab* cos φ` at `b* = √((1 − a²)/(1 − a² cos² φ))`, the maximum
/// over Δux (tests/inverse.rs). README scene: a = 0.4, φ = 50°: b* = 0.94840,
/// 0.24385. Tolerance: the printed bound plus the golden section's bracket at
/// the kink (8ε relative in b at a slope ≤ 1: 16ε(1 + b*)) plus the printing.
#[test]
fn maximize_stall_force_text() {
    let out = run(&["--maximize", "stall-force", "--adjust", "dux"]);
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(text.starts_with("adjust          dux\nmaximize        stall_force\nvalue           "));
    assert!(text.contains("regime          actuator"));
    let word = |line: usize, k: usize| -> String {
        text.lines()
            .nth(line)
            .unwrap()
            .split_whitespace()
            .nth(k)
            .unwrap()
            .trim_start_matches('(')
            .trim_end_matches(',')
            .to_string()
    };
    let value_s = word(2, 1);
    let value: f64 = value_s.parse().unwrap();
    let bound: f64 = word(2, 3).parse().unwrap();
    let g = integration_tests::physical_scene().groups();
    let (a, phi) = (g.duz_rel, g.phi);
    let b_star = ((1.0 - a * a) / (1.0 - (a * phi.cos()).powi(2))).sqrt();
    let want = a * b_star * phi.cos();
    let tol = bound + 16.0 * f64::EPSILON * (1.0 + b_star) + half_ulp_of_printed(&value_s);
    assert!(
        (value - want).abs() <= tol,
        "{value} vs closed form {want} (tol {tol:e})"
    );
}

#[test]
fn refusals_name_the_flag() {
    refused(
        &[
            "--v0",
            "0.05",
            "--target-mu-rel",
            "0.5",
            "--target-mu",
            "0.1",
            "--adjust",
            "duz",
        ],
        "target-mu",
    );
    refused(&["--v0", "0.05", "--adjust", "duz"], "target-mu-rel");
    let e = refused(&["--target-mu-rel", "0.5", "--adjust", "duz"], "v0");
    assert!(e.contains("missing"));
    let e = refused(
        &["--v0", "0", "--target-mu-rel", "0.5", "--adjust", "duz"],
        "v0",
    );
    assert!(e.contains("!= 0"));
    let e = refused(
        &["--v0", "0.05", "--target-mu-rel", "1", "--adjust", "duz"],
        "target-mu-rel",
    );
    assert!(e.contains("strictly inside (−1, 1)"), "{e}");
    refused(
        &["--v0", "0.05", "--target-mu-rel", "nan", "--adjust", "duz"],
        "target-mu-rel",
    );
    let e = refused(
        &[
            "--v0",
            "0.05",
            "--target-mu-rel",
            "0.5",
            "--adjust",
            "duz",
            "--max-duz",
            "4.9e-6",
        ],
        "max-duz",
    );
    assert!(e.contains("lift-off limit"), "{e}");
    refused(
        &[
            "--v0",
            "0.05",
            "--target-mu-rel",
            "0.5",
            "--adjust",
            "duz",
            "--max-duz",
            "-1",
        ],
        "max-duz",
    );
    refused(
        &[
            "--v0",
            "0.05",
            "--target-mu-rel",
            "0.5",
            "--adjust",
            "phase",
            "--max-dux",
            "1e-6",
        ],
        "max-dux",
    );
    refused(
        &[
            "--v0",
            "0.05",
            "--target-mu-rel",
            "0.5",
            "--adjust",
            "duz",
            "--liftoff-margin",
            "0",
        ],
        "liftoff-margin",
    );
    refused(
        &["--v0", "0.05", "--maximize", "asymmetry", "--adjust", "duz"],
        "v0",
    );
    refused(
        &["--v0", "0.05", "--target-mu-rel", "0.5", "--adjust", "amp"],
        "adjust",
    );
}

/// A scene that never pushes forward however Δuz is set (Δux = 0: single
/// mode, μ(0⁺) = 1 − a > 0): the stall-force objective is refused.
#[test]
fn stall_force_without_push_is_refused() {
    let out = fricctl()
        .args([
            "tune",
            "--maximize",
            "stall-force",
            "--adjust",
            "duz",
            "--duz-rel",
            "0.3",
            "--dux-rel",
            "0",
        ])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8(out.stderr).unwrap();
    assert_eq!(err.lines().count(), 1);
    assert!(
        err.starts_with("error: --maximize: the contact never pushes forward"),
        "{err}"
    );
}

/// Issue 41 §5: a dimensionless scene's result is in the groups' units
/// (lengths in uz0 and W0, velocities in ωW0), never in m or m/s; the
/// numbers are the JSON's (where uz0 = W0 = 1).
#[test]
fn dimensionless_scene_prints_no_si_units() {
    let scene = ["--duz-rel", "0.5", "--ratio", "1", "--phi-deg", "45"];
    let text = |args: &[&str]| {
        let o = fricctl()
            .args(["tune"])
            .args(scene)
            .args(args)
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(0), "{o:?}");
        String::from_utf8(o.stdout).unwrap()
    };
    let j = |args: &[&str]| common::cli::json(&[&["tune"][..], &scene, args, &["--json"]].concat());
    for (adjust, unit) in [("duz", "uz0"), ("dux", "W0")] {
        let args = ["--adjust", adjust, "--target-mu-rel", "0.2", "--v0", "0.1"];
        let t = text(&args);
        // No SI unit anywhere (" m" as a word, m/s, N).
        for line in t.lines() {
            let words: Vec<&str> = line.split_whitespace().collect();
            assert!(
                !words
                    .iter()
                    .any(|w| matches!(*w, "m" | "m/s" | "N" | "m," | "m)")),
                "{line}"
            );
        }
        assert!(
            t.contains("v0              0.1 ωW0 (dimensionless scene)\n"),
            "{t}"
        );
        let out = j(&args);
        // The reported knob: its JSON value (the scene's uz0 = W0 = 1) and unit.
        let x = out[adjust].as_f64().unwrap();
        let line = t
            .lines()
            .find(|l| l.starts_with(&format!("{adjust:<16}")))
            .unwrap();
        let shown: f64 = line.split_whitespace().nth(1).unwrap().parse().unwrap();
        // Rounded prints 12 significant digits.
        assert!((shown - x).abs() <= 1e-11 * x.abs(), "{line} vs {x}");
        assert_eq!(line.split_whitespace().nth(2), Some(unit), "{line}");
        let search = t.lines().find(|l| l.starts_with("search")).unwrap();
        assert!(search.contains(&format!("] {unit}, ")), "{search}");
    }
    // The refusal of a --max-duz beyond the lift-off limit, in uz0 too.
    let o = fricctl()
        .args(["tune"])
        .args(scene)
        .args([
            "--adjust",
            "duz",
            "--target-mu-rel",
            "0.2",
            "--v0",
            "0.1",
            "--max-duz",
            "2",
        ])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert_eq!(
        String::from_utf8(o.stderr).unwrap(),
        "error: --max-duz: 2 uz0 is above the lift-off limit (1 − liftoff-margin)·uz0 = 0.95 uz0\n"
    );
    // The physical scene keeps its SI units.
    let o = run(&["--adjust", "duz", "--target-mu-rel", "0.2", "--v0", "0.01"]);
    let t = String::from_utf8(o.stdout).unwrap();
    assert!(t.contains("v0              0.01 m/s\n"), "{t}");
    assert!(
        t.lines()
            .any(|l| l.starts_with("duz") && l.contains(" m   (duz/uz0 = ")),
        "{t}"
    );
}

/// Issue 39: `tune --profile` runs the search on the profile's MDR
/// quadrature. The reported drive, rebuilt from the JSON's own `duz_rel`,
/// `dux_rel` and `phi_deg` (a dimensionless scene: V is `--v0`), gives the
/// target under the brute force over springs (`integration_tests::springs`,
/// each spring a fixed-step run; refined to an estimated error `e ≤ 4·bound`)
/// within `e + bound + |residual|`; the residual is within the bound, the
/// method is `mdr`, and the profile is named in JSON and text.
#[test]
fn profile_target_meets_the_target_by_the_brute_force_over_springs() {
    use integration_tests::springs;
    let scene = ["--duz-rel", "0.5", "--dux-rel", "1", "--phi-deg", "17.2"];
    for (profile, n, adjust, target) in [
        ("sphere", 2.0, "dux", "0.4"),
        ("cone", 1.0, "phase", "-0.3"),
    ] {
        let args = [
            &scene[..],
            &["--profile", profile, "--adjust", adjust],
            &[
                "--v0",
                if target.starts_with('-') {
                    "-0.1"
                } else {
                    "0.2"
                },
            ],
            &["--target-mu-rel", target],
        ]
        .concat();
        let v = common::cli::json(&[&["tune"][..], &args, &["--json"]].concat());
        assert_eq!(v["profile"], profile);
        assert_eq!(f(&v, "exponent"), n);
        assert_eq!(v["method"], "mdr");
        let t: f64 = target.parse().unwrap();
        let (bound, residual) = (f(&v, "error_bound_over_mu0"), f(&v, "residual_over_mu0"));
        // The tolerance asked of the quadrature: 1e-9 unless the springs' part is larger.
        assert!((1e-9..=1e-8).contains(&bound), "{v}");
        assert!(residual.abs() <= bound, "{v}");
        // The reported μ is the target plus the residual, to rounding.
        assert!(
            (f(&v, "mu_over_mu0") - (t + residual)).abs() <= 1e-15,
            "{v}"
        );
        let scene = (
            f(&v, "duz_rel"),
            f(&v, "dux_rel"),
            f(&v, "phi_deg").to_radians(),
            f(&v, "v0"),
        );
        let mut steps = 1 << 12;
        let bf = loop {
            let bf = springs::mu_extrapolated(n, scene, bound, steps, 64);
            if bf.err <= 4.0 * bound || steps >= 1 << 15 {
                break bf;
            }
            steps *= 2;
        };
        assert!(
            bf.err <= 4.0 * bound,
            "brute force not refined: {:e}",
            bf.err
        );
        let allowed = bf.err + bound + residual.abs();
        assert!(
            (bf.mu - t).abs() <= allowed,
            "{profile}: brute force {} vs target {t} (allowed {allowed:e})",
            bf.mu
        );
        // A result off by 10× its bound would fail.
        assert!((bf.mu - (t + 10.0 * bound)).abs() > allowed);
        let o = fricctl().args(["tune"]).args(&args).output().unwrap();
        assert_eq!(o.status.code(), Some(0), "{o:?}");
        let text = String::from_utf8(o.stdout).unwrap();
        assert!(
            text.contains(&format!("profile         {profile} (MDR quadrature over the springs; uz0 = mean indentation d0)\n")),
            "{text}"
        );
        assert!(text.contains("(units of mu0, method mdr)"), "{text}");
    }
}

/// Issue 39: `tune --profile cone --maximize stall-force` is no worse than
/// a dense scan (4× the search's cells) of the profile's μ(0⁺) over the
/// phase, within the limits' bound, and what it reports at the maximum is
/// what `fricctl static --profile` says of that drive.
#[test]
fn profile_stall_force_is_no_worse_than_a_dense_scan() {
    use model_core::mdr::{self, Profile};
    let scene = ["--duz-rel", "0.5", "--dux-rel", "1", "--phi-deg", "0"];
    let v = common::cli::json(
        &[
            &["tune"][..],
            &scene,
            &[
                "--profile",
                "cone",
                "--adjust",
                "phase",
                "--maximize",
                "stall-force",
                "--json",
            ],
        ]
        .concat(),
    );
    assert_eq!(v["profile"], "cone");
    let (best, bound) = (f(&v, "value"), f(&v, "error_bound_over_mu0"));
    assert!(bound > 0.0 && bound <= 1e-8, "{v}");
    let mut dense = f64::MIN;
    for k in 0..1024 {
        let phi = std::f64::consts::TAU * f64::from(k) / 1024.0;
        let d = Drive::new::<Libm>(0.5, 1.0, phi);
        let (plus, _) = mdr::limits_at_zero::<f64, Libm>(&d, &Profile::Cone, 1e-8).unwrap();
        dense = dense.max(-plus.mu_over_mu0);
    }
    assert!(
        best >= dense - 2.0 * 1e-8,
        "search {best} below dense {dense}"
    );
    // At the maximum: the statics of the same drive.
    let phi = format!("{}", f(&v, "phi_deg"));
    let st = common::cli::json(&[
        "static",
        "--duz-rel",
        "0.5",
        "--dux-rel",
        "1",
        "--phi-deg",
        &phi,
        "--profile",
        "cone",
        "--json",
    ]);
    assert!(
        (f(&st, "mu_0plus_over_mu0") + best).abs() <= 2.0 * bound,
        "{st}"
    );
    assert_eq!(f(&v, "stall_force_forward"), best);
}
