//! The real `fricctl` binary: each command's happy path against model-core,
//! every invalid-input class (exit 2, one line naming the parameter), and the
//! figures command producing valid SVG/PNG files.

use model_core::analytic::{CriticalVelocity, StaticFriction};
use model_core::exact;
use model_core::regime::{classify, ClassifyOptions};
use model_core::{Groups, Libm, Scene};

mod common;

use common::cli::{fricctl, json, run_ok, PHYS};

/// The scene of the `PHYS` flags.
fn phys_scene() -> Scene<f64> {
    integration_tests::physical_scene()
}

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol * (1.0 + b.abs())
}

#[test]
fn mu_exact_matches_model_core() {
    let s = phys_scene();
    let v = json(&[&["mu", "--v0", "0.01", "--json"], PHYS].concat());
    let want = exact::solve(&s, 0.01).unwrap().mu_over_mu0().unwrap();
    assert_eq!(v["method"], "exact");
    assert!(close(v["mu_over_mu0"].as_f64().unwrap(), want, 1e-15));
    assert!(close(v["mu"].as_f64().unwrap(), 0.3 * want, 1e-15));
    let vc = CriticalVelocity::of(&s);
    assert!(close(v["vc_forward"].as_f64().unwrap(), vc.forward, 1e-15));
    assert!(close(
        v["vc_backward"].as_f64().unwrap(),
        vc.backward,
        1e-15
    ));
}

#[test]
fn mu_v_rel_uses_the_direction_s_vc() {
    let s = phys_scene();
    let vc = CriticalVelocity::of(&s);
    let v = json(&[&["mu", "--v-rel", "-0.5", "--json"], PHYS].concat());
    assert!(close(v["v0"].as_f64().unwrap(), -0.5 * vc.backward, 1e-15));
    let want = exact::solve(&s, -0.5 * vc.backward)
        .unwrap()
        .mu_over_mu0()
        .unwrap();
    assert!(close(v["mu_over_mu0"].as_f64().unwrap(), want, 1e-15));
    // Beyond v_c: sliding, exactly μ0.
    let v = json(&[&["mu", "--v-rel", "1.5", "--json"], PHYS].concat());
    assert_eq!(v["mu_over_mu0"].as_f64().unwrap(), 1.0);
    assert_eq!(v["method"], "sliding");
}

#[test]
fn mu_fixed_reports_diagnostics() {
    let s = phys_scene();
    let v = json(
        &[
            &[
                "mu",
                "--v0",
                "0.01",
                "--method",
                "fixed",
                "--steps-per-period",
                "8192",
                "--json",
            ],
            PHYS,
        ]
        .concat(),
    );
    assert_eq!(v["method"], "fixed");
    assert_eq!(v["steps_per_period"], 8192);
    assert_eq!(v["converged"], true);
    assert!(v["periods"].as_u64().unwrap() >= 3);
    let want = exact::solve(&s, 0.01).unwrap().mu_over_mu0().unwrap();
    // The scheme's stated bound at N = 8192, written out:
    // (1 + b)(K_D/N² + N·ε), K_D = 10, b = k_xΔu_x/(μ₀k_z u_z0) = 0.35 here:
    // 2.0e-7; the exact value's own bound 1e-9·(1 + b) adds to it.
    let b = 1.5e6 * 0.7e-6 / (0.3 * 2e6 * 5e-6);
    let n = 8192.0f64;
    let bound = (1.0 + b) * (10.0 / (n * n) + n * f64::EPSILON);
    let reported = v["error_bound_over_mu0"].as_f64().unwrap();
    assert!(
        (reported - bound).abs() <= 1e-12 * bound,
        "{reported} vs {bound}"
    );
    let got = v["mu_over_mu0"].as_f64().unwrap();
    println!(
        "fixed N=8192: |Δμ|/μ0 = {:.2e}, bound {bound:.2e}",
        (got - want).abs()
    );
    assert!(
        (got - want).abs() <= bound + 1e-9 * (1.0 + b),
        "{got} vs {want}"
    );
}

#[test]
fn mu_dimensionless_and_approx() {
    let v = json(&[
        "mu",
        "--duz-rel",
        "0.5",
        "--dux-rel",
        "0",
        "--v-rel",
        "0.3",
        "--method",
        "approx",
        "--json",
    ]);
    assert_eq!(v["method"], "approx_eq21");
    let x: f64 = 0.3 - 1.0;
    let eq21 = 1.0 - 0.5 * (0.75 * x * x + 0.25 * x.powi(4));
    assert!(close(v["mu_over_mu0"].as_f64().unwrap(), eq21, 1e-14));
    // v0 = 0: the static analysis answers, with both limits.
    let v = json(&[
        "mu",
        "--duz-rel",
        "0.5",
        "--ratio",
        "0.5",
        "--phi-deg",
        "30",
        "--v0",
        "0",
        "--json",
    ]);
    assert_eq!(v["method"], "static");
    assert!(v["mu"].is_null());
    let s =
        Scene::dimensionless(Groups::from_ratio(0.5, 0.5, 30f64.to_radians()).unwrap()).unwrap();
    let st = StaticFriction::of(&s);
    assert!(close(
        v["mu_0plus_over_mu0"].as_f64().unwrap(),
        st.hi,
        1e-12
    ));
    assert!(close(
        v["mu_0minus_over_mu0"].as_f64().unwrap(),
        st.lo,
        1e-12
    ));
}

#[test]
fn curve_csv_matches_model_core() {
    let out = fricctl()
        .args(
            [
                &[
                    "curve", "--v-min", "-0.05", "--v-max", "0.05", "--points", "11",
                ],
                PHYS,
            ]
            .concat(),
        )
        .output()
        .unwrap();
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    let mut lines = text.lines();
    assert_eq!(
        lines.next().unwrap(),
        "v0,v_rel,mu,mu_over_mu0,method,error_bound_over_mu0"
    );
    let s = phys_scene();
    let lines: Vec<&str> = lines.collect();
    let rows: Vec<Vec<f64>> = lines
        .iter()
        .map(|l| {
            l.split(',')
                .filter_map(|x| x.parse().ok())
                .collect::<Vec<f64>>()
        })
        .collect();
    // Default tolerance: never an approximation; the bound is 0 while sliding
    // and the exact solver's otherwise.
    let bound = exact::error_bound::<f64, Libm>(&s.drive());
    for (l, r) in lines.iter().zip(&rows) {
        let method = l.split(',').nth(4).unwrap();
        match method {
            "sliding" => assert_eq!(r[4], 0.0),
            "exact" | "static" => assert_eq!(r[4], bound),
            other => panic!("unexpected method {other} in {l}"),
        }
    }
    // 11 velocities, v0 = 0 gives two rows (the limits from below and above).
    assert_eq!(rows.len(), 12);
    for r in &rows {
        if r[0] == 0.0 {
            continue;
        }
        let want = exact::solve(&s, r[0]).unwrap().mu_over_mu0().unwrap();
        assert!(close(r[3], want, 1e-15), "{r:?}");
        assert!(close(r[2], 0.3 * want, 1e-15));
    }
    let zero: Vec<&Vec<f64>> = rows.iter().filter(|r| r[0] == 0.0).collect();
    let (p, m) = exact::limits_at_zero::<f64, Libm>(&s.drive()).unwrap();
    assert!(close(zero[0][3], m, 1e-15) && close(zero[1][3], p, 1e-15));
}

#[test]
fn curve_writes_csv_and_plot_files() {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("c.csv");
    let svg = dir.path().join("c.svg");
    let png = dir.path().join("c.png");
    for plot in [&svg, &png] {
        fricctl()
            .args([
                "curve",
                "--duz-rel",
                "0.5",
                "--ratio",
                "2",
                "--phi-deg",
                "30",
                "--v-rel-min",
                "-1.2",
                "--v-rel-max",
                "1.2",
            ])
            .args([
                "--points",
                "200",
                "--csv",
                csv.to_str().unwrap(),
                "--plot",
                plot.to_str().unwrap(),
                // The second run replaces the first one's CSV (output-files policy).
                "--force",
            ])
            .assert()
            .success()
            .stdout("");
    }
    let text = std::fs::read_to_string(&csv).unwrap();
    assert_eq!(text.lines().count(), 201);
    check_svg(&svg);
    check_png(&png);
}

#[test]
fn static_json() {
    let v = json(&[
        "static",
        "--duz-rel",
        "0.5",
        "--ratio",
        "2",
        "--phi-deg",
        "90",
        "--json",
    ]);
    assert_eq!(v["static_exists"], false);
    assert!(v["mu_s_forward_over_mu0"].is_null());
    assert!(close(
        v["paper_eq18_forward_over_mu0"].as_f64().unwrap(),
        1.0 - 1.25f64.sqrt(),
        1e-15
    ));
    let v = json(&[&["static", "--json"], PHYS].concat());
    let st = StaticFriction::of(&phys_scene());
    assert_eq!(v["static_exists"], true);
    assert!(close(
        v["mu_s_forward_over_mu0"].as_f64().unwrap(),
        st.hi,
        1e-15
    ));
    assert!(close(
        v["mu_s_backward_over_mu0"].as_f64().unwrap(),
        -st.lo,
        1e-15
    ));
    assert!(close(
        v["paper_eq19_backward_over_mu0"].as_f64().unwrap(),
        st.paper_eq19_backward,
        1e-15
    ));
    // Eq. 8 from the scene's parameters: v_c = ωW₀|b e^{iφ} ± a|,
    // W₀ = μ₀(k_z/k_x)u_z0, a = Δu_z/u_z0, b = Δu_x/W₀ (a few roundings).
    let p = *phys_scene().params();
    let w0 = p.mu0 * p.kz / p.kx * p.uz0;
    let (a, b) = (p.duz / p.uz0, p.dux / w0);
    for (k, sign) in [("vc_forward", 1.0), ("vc_backward", -1.0)] {
        let c = (b * p.phi.cos() + sign * a).hypot(b * p.phi.sin());
        let want = p.omega * w0 * c;
        let got = v[k].as_f64().unwrap();
        assert!(close(got, want, 1e-14), "{k}: {got} vs eq. 8 {want}");
    }
}

#[test]
fn classify_json() {
    let v = json(&["classify", "--duz-rel", "0.9", "--ratio", "0.7", "--json"]);
    assert_eq!(v["regime"], "actuator");
    assert_eq!(v["rule_of_thumb"], "dynamic_ratchet");
    assert_eq!(v["rule_of_thumb_agrees"], false);
    let s = Scene::dimensionless(Groups::from_ratio(0.9, 0.7, 0.0).unwrap()).unwrap();
    let c = classify(&s, &ClassifyOptions::default()).unwrap();
    assert!(close(
        v["mu_0plus_over_mu0"].as_f64().unwrap(),
        c.mu_0plus,
        1e-15
    ));
    let v = json(&[
        "classify",
        "--duz-rel",
        "0.5",
        "--ratio",
        "1",
        "--phi-deg",
        "90",
        "--json",
    ]);
    assert_eq!(v["regime"], "active_control");
    let v = json(&[&["classify", "--json"], PHYS].concat());
    assert!(v["regime"].is_string());
}

#[test]
fn map_writes_plot_and_csv() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("m.png");
    let csv = dir.path().join("m.csv");
    fricctl()
        .args([
            "map",
            "--duz-rel",
            "0.5",
            "--res",
            "12",
            "--plot",
            png.to_str().unwrap(),
            "--csv",
            csv.to_str().unwrap(),
        ])
        .assert()
        .success()
        .stdout("");
    check_png(&png);
    let text = std::fs::read_to_string(&csv).unwrap();
    assert_eq!(text.lines().count(), 1 + 144);
    assert!(text.starts_with("phi_deg,ratio,regime,"));
    // Every cell agrees with model-core.
    for l in text.lines().skip(1) {
        let f: Vec<&str> = l.split(',').collect();
        let (phi, r): (f64, f64) = (f[0].parse().unwrap(), f[1].parse().unwrap());
        let s = Scene::dimensionless(Groups {
            duz_rel: 0.5,
            dux_rel: r * 0.5,
            phi: phi.to_radians(),
        })
        .unwrap();
        assert_eq!(
            f[2],
            classify(&s, &ClassifyOptions::default())
                .unwrap()
                .regime
                .name()
        );
    }
}

fn check_svg(p: &std::path::Path) {
    let s = std::fs::read_to_string(p).unwrap();
    assert!(s.len() > 1000, "{}", p.display());
    assert!(
        s.contains("<svg") && s.trim_end().ends_with("</svg>"),
        "{}",
        p.display()
    );
}

fn check_png(p: &std::path::Path) {
    let b = std::fs::read(p).unwrap();
    assert!(b.len() > 1000, "{}", p.display());
    assert_eq!(&b[..8], b"\x89PNG\r\n\x1a\n", "{}", p.display());
    assert_eq!(&b[b.len() - 8..b.len() - 4], b"IEND", "{}", p.display());
}

#[test]
fn figures_are_written() {
    let dir = tempfile::tempdir().unwrap();
    fricctl()
        .args([
            "figures",
            "--out",
            dir.path().to_str().unwrap(),
            "--map-res",
            "20",
        ])
        .assert()
        .success()
        .stdout("");
    for name in [
        "fig2",
        "fig3a",
        "fig3b",
        "fig4",
        "fig5",
        "fig6",
        "fig7",
        "liftoff_normal",
        "profiles",
        "regime_map",
    ] {
        let svg = dir.path().join(format!("{name}.svg"));
        check_svg(&svg);
        check_png(&dir.path().join(format!("{name}.png")));
        let text = std::fs::read_to_string(&svg).unwrap();
        curves_have_sub_pixel_coordinates(name, &text);
        frames_cover_no_data(name, &text);
    }
}

/// The value of attribute `key` in one SVG tag.
fn attr<'a>(tag: &'a str, key: &str) -> Option<&'a str> {
    let at = tag.find(&format!(" {key}=\""))? + key.len() + 3;
    tag[at..].split('"').next()
}

/// The tags `<name …>` of an SVG document.
fn tags<'a>(svg: &'a str, name: &str) -> Vec<&'a str> {
    svg.match_indices(&format!("<{name} "))
        .map(|(i, _)| &svg[i..i + svg[i..].find('>').unwrap()])
        .collect()
}

fn polyline_points(tag: &str) -> Vec<(f64, f64)> {
    attr(tag, "points")
        .unwrap_or("")
        .split_whitespace()
        .map(|p| {
            let (x, y) = p.split_once(',').unwrap();
            (x.parse().unwrap(), y.parse().unwrap())
        })
        .collect()
}

/// Issue 27: plotters writes whole pixels, so a smooth curve drawn through it
/// is a staircase. Every polyline of more than 5 points (a curve, not an
/// axis, a tick or a legend sample) has coordinates off the pixel grid.
fn curves_have_sub_pixel_coordinates(name: &str, svg: &str) {
    let curves: Vec<&str> = tags(svg, "polyline")
        .into_iter()
        .filter(|t| polyline_points(t).len() > 5)
        .collect();
    assert!(!curves.is_empty(), "{name}: no curve");
    for t in curves {
        let pts = polyline_points(t);
        let fractional = pts
            .iter()
            .filter(|(x, y)| x.fract() != 0.0 || y.fract() != 0.0)
            .count();
        assert!(
            fractional * 2 > pts.len(),
            "{name}: a curve of {} points with integer coordinates ({fractional} fractional)",
            pts.len()
        );
    }
}

/// Issue 27: legend and notes frames (grey, #A0A0A0) lie where no data is:
/// no curve point (sub-pixel polylines) and no marker centre strictly
/// inside a frame (1 px margin for the frame's own line).
fn frames_cover_no_data(name: &str, svg: &str) {
    let num = |t: &str, k: &str| attr(t, k).unwrap().parse::<f64>().unwrap();
    let frames: Vec<(f64, f64, f64, f64)> = tags(svg, "rect")
        .into_iter()
        .filter(|t| attr(t, "stroke") == Some("#A0A0A0"))
        .map(|t| (num(t, "x"), num(t, "y"), num(t, "width"), num(t, "height")))
        .collect();
    let mut data: Vec<(f64, f64)> = tags(svg, "polyline")
        .into_iter()
        .filter(|t| t.contains("clip-path"))
        .flat_map(polyline_points)
        .collect();
    data.extend(
        tags(svg, "circle")
            .into_iter()
            .map(|t| (num(t, "cx"), num(t, "cy"))),
    );
    for &(x, y, w, h) in &frames {
        for &(px, py) in &data {
            let inside = px > x + 1.0 && px < x + w - 1.0 && py > y + 1.0 && py < y + h - 1.0;
            // A legend's own samples sit inside its frame: those are circles
            // at the sample column (x + 8 + 14), not data.
            let sample = (px - (x + 8.0 + 14.0)).abs() < 1.0;
            assert!(
                !inside || sample,
                "{name}: point ({px}, {py}) under the frame at ({x}, {y}) {w}×{h}"
            );
        }
    }
}

/// Runs fricctl, expects exit status 2 and a single stderr line containing `needle`.
fn bad(args: &[&str], needle: &str) {
    let out = fricctl().args(args).output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
    assert!(out.stdout.is_empty(), "{args:?}");
    assert_eq!(err.trim_end().lines().count(), 1, "{args:?}: {err}");
    assert!(err.contains(needle), "{args:?}: {err} (wanted {needle})");
    assert!(!err.contains("panicked") && !err.contains("backtrace"));
}

fn with(replace: &str, value: &str) -> Vec<String> {
    let mut v: Vec<String> = vec!["mu".into(), "--v0".into(), "0.01".into()];
    let mut i = 0;
    while i < PHYS.len() {
        v.push(PHYS[i].into());
        v.push(if PHYS[i] == replace {
            value.into()
        } else {
            PHYS[i + 1].into()
        });
        i += 2;
    }
    v
}

fn without(drop: &str) -> Vec<String> {
    let mut v: Vec<String> = vec!["mu".into(), "--v0".into(), "0.01".into()];
    let mut i = 0;
    while i < PHYS.len() {
        if PHYS[i] != drop {
            v.push(PHYS[i].into());
            v.push(PHYS[i + 1].into());
        }
        i += 2;
    }
    v
}

fn refs(v: &[String]) -> Vec<&str> {
    v.iter().map(String::as_str).collect()
}

#[test]
fn invalid_input_classes() {
    // Missing parameters.
    for p in ["--mu0", "--kz", "--kx", "--uz0", "--duz", "--dux", "--freq"] {
        bad(&refs(&without(p)), p);
    }
    // Non-numeric.
    bad(&refs(&with("--kz", "abc")), "--kz");
    // NaN / infinite.
    bad(&refs(&with("--kx", "NaN")), "--kx");
    bad(&refs(&with("--uz0", "inf")), "--uz0");
    // Non-positive and negative.
    bad(&refs(&with("--kz", "-1e6")), "--kz");
    bad(&refs(&with("--mu0", "0")), "--mu0");
    bad(&refs(&with("--freq", "0")), "--freq");
    bad(&refs(&with("--dux", "-1e-7")), "--dux");
    // Lift-off (duz >= uz0) is accepted by the model commands: tests/contacts.rs.
    // Velocity.
    bad(&[&["mu", "--v0", "nan"], PHYS].concat(), "--v0");
    bad(&[&["mu"], PHYS].concat(), "--v0");
    // Conflicts and dimensionless misuse.
    bad(
        &[&["mu", "--v0", "0.1", "--omega", "1e5"], PHYS].concat(),
        "--omega",
    );
    bad(&["mu", "--duz-rel", "0.5", "--v-rel", "0.1"], "--dux-rel");
    bad(
        &[
            "mu",
            "--duz-rel",
            "0.5",
            "--ratio",
            "1",
            "--phi-deg",
            "1e7",
            "--v-rel",
            "0.1",
        ],
        "--phi-deg: |φ| = 1.745e5 rad is beyond 10⁴ rad",
    );
    bad(&refs(&with("--phi-deg", "1e7")), "--phi-deg");
    bad(
        &["mu", "--duz-rel", "0", "--ratio", "1", "--v-rel", "0.1"],
        "--ratio",
    );
    bad(
        &[
            "mu",
            "--duz-rel",
            "0.5",
            "--dux-rel",
            "0.1",
            "--kz",
            "1",
            "--v-rel",
            "0.1",
        ],
        "--kz",
    );
    // Method that does not apply.
    bad(
        &[
            "mu",
            "--duz-rel",
            "0.5",
            "--dux-rel",
            "0.1",
            "--v-rel",
            "0.1",
            "--method",
            "approx",
        ],
        "--method",
    );
    bad(
        &[
            "mu",
            "--duz-rel",
            "0.5",
            "--dux-rel",
            "0.1",
            "--v0",
            "0",
            "--method",
            "fixed",
        ],
        "--v0",
    );
    bad(
        &[
            "mu",
            "--duz-rel",
            "0.5",
            "--dux-rel",
            "0.1",
            "--v0",
            "0.1",
            "--method",
            "fixed",
            "--steps-per-period",
            "2",
        ],
        "--steps-per-period",
    );
    bad(
        &[
            "mu",
            "--duz-rel",
            "0.5",
            "--dux-rel",
            "0.1",
            "--v0",
            "0.1",
            "--method",
            "magic",
        ],
        "--method",
    );
    // Curve and map ranges.
    bad(
        &[
            &["curve", "--v-min", "1", "--v-max", "0", "--points", "10"],
            PHYS,
        ]
        .concat(),
        "--v-max",
    );
    bad(
        &[
            &["curve", "--v-min", "0", "--v-max", "1", "--points", "1"],
            PHYS,
        ]
        .concat(),
        "--points",
    );
    bad(
        &[
            &[
                "curve", "--v-min", "0", "--v-max", "1", "--points", "10", "--plot", "x.jpg",
            ],
            PHYS,
        ]
        .concat(),
        "--plot",
    );
    bad(
        &["map", "--duz-rel", "0", "--res", "4", "--plot", "m.png"],
        "--duz-rel",
    );
    bad(
        &["map", "--duz-rel", "0.5", "--res", "1", "--plot", "m.png"],
        "--res",
    );
    // Scene file: unknown key, unreadable.
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("s.toml");
    std::fs::write(&f, "mu0 = 0.3\nkz = 2e6\nkx = 1.5e6\nuz0 = 5e-6\nduz = 2e-6\ndux = 7e-7\nfreq = 4e4\nphi_deg = 50\nbogus = 1\n").unwrap();
    bad(
        &["mu", "--v0", "0.01", "--scene", f.to_str().unwrap()],
        "--scene",
    );
    bad(
        &["mu", "--v0", "0.01", "--scene", "/nonexistent/s.toml"],
        "--scene",
    );
}

#[test]
fn scene_file_with_flag_override() {
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("s.toml");
    std::fs::write(&f, "mu0 = 0.3\nkz = 2e6\nkx = 1.5e6\nuz0 = 5e-6\nduz = 2e-6\ndux = 7e-7\nfreq = 4e4\nphi_deg = 10\n").unwrap();
    // The file says φ = 10°, the flag 50°: the flag wins, so the result equals PHYS.
    let a = json(&[
        "mu",
        "--v0",
        "0.01",
        "--json",
        "--scene",
        f.to_str().unwrap(),
        "--phi-deg",
        "50",
    ]);
    let b = json(&[&["mu", "--v0", "0.01", "--json"], PHYS].concat());
    assert_eq!(a["mu"], b["mu"]);
    let c = json(&[
        "mu",
        "--v0",
        "0.01",
        "--json",
        "--scene",
        f.to_str().unwrap(),
    ]);
    assert_ne!(a["mu"], c["mu"]);
}

#[test]
fn bench_work_precision_writes_charts_and_csv() {
    let dir = tempfile::tempdir().unwrap();
    fricctl()
        .args([
            "bench",
            "work-precision",
            "--out",
            dir.path().to_str().unwrap(),
            "--max-steps",
            "128",
        ])
        .assert()
        .success();
    check_svg(&dir.path().join("work_precision.svg"));
    check_png(&dir.path().join("work_precision.png"));
    let csv = std::fs::read_to_string(dir.path().join("work_precision.csv")).unwrap();
    let rows: Vec<Vec<&str>> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    // Every scene has the exact solver and the fixed-step series from 8 to 128 steps.
    for scene in ["normal only", "dual actuator", "near lift-off"] {
        assert!(rows
            .iter()
            .any(|r| r[0] == scene && r[1] == "exact f64" && r[3] == "0"));
        let fixed: Vec<&Vec<&str>> = rows
            .iter()
            .filter(|r| r[0] == scene && r[1] == "fixed f64 from rest")
            .collect();
        assert_eq!(fixed.len(), 17, "{scene}");
        // The scheme's stated bound at N = 128, (1 + b)(10/N² + N·ε) with b
        // of the scene (work_precision::SCENES: 0, 1, 0.3): 6.1e-4·(1 + b).
        let b = match scene {
            "normal only" => 0.0,
            "dual actuator" => 1.0,
            _ => 0.3,
        };
        let bound = (1.0 + b) * (10.0 / (128.0f64 * 128.0) + 128.0 * f64::EPSILON);
        let e128: f64 = fixed.iter().find(|r| r[2] == "128").unwrap()[3]
            .parse()
            .unwrap();
        println!("{scene}: error at N = 128 {e128:.2e}, bound {bound:.2e}");
        assert!(e128 <= bound && e128 > 0.0, "{scene}: {e128} > {bound}");
    }
    // Across lift-off: every point within its stated bound against its
    // reference. Flat punch: the exact/lift-off solver in f64 is the
    // reference (error 0), the fixed-step / lift-off stepping errors are
    // within the schemes' stated bounds (column 5). Sphere: the MDR at
    // 1e-6, 1e-8, 1e-9 against the MDR at 2× its per-spring part, whose own
    // bound is ≤ 2·ε_s·ξ_max/D ≤ 2·1e-11·(1 + 3 + 0.6)·2/(2/3) < 3e-10
    // (`mdr::solver_bound`, a ≤ 3, b = 0.6, D ≥ n/(n + 1)): error ≤ bound +
    // 3e-10.
    let num = |s: &str| s.parse::<f64>().unwrap();
    for a in ["0.5", "0.9", "1.1", "1.5", "2", "3"] {
        let scene = format!("flat across lift-off a={a}");
        assert!(rows
            .iter()
            .any(|r| r[0] == scene && r[1] == "exact f64" && r[3] == "0"));
        let method = if num(a) < 1.0 {
            "fixed f64 from rest"
        } else {
            "lift-off stepping f64"
        };
        let series: Vec<&Vec<&str>> = rows
            .iter()
            .filter(|r| r[0] == scene && r[1] == method && r[6] == "ok")
            .collect();
        assert!(series.len() >= 3, "{scene}: {} points", series.len());
        for r in series {
            assert!(
                num(r[3]) <= num(r[5]),
                "{scene} N={}: {} > {}",
                r[2],
                r[3],
                r[5]
            );
        }
    }
    for a in ["0.5", "0.9", "1.1", "1.5", "3"] {
        let scene = format!("sphere across lift-off a={a}");
        let mdr: Vec<&Vec<&str>> = rows
            .iter()
            .filter(|r| r[0] == scene && r[1] == "MDR f64")
            .collect();
        assert_eq!(mdr.len(), 3, "{scene}");
        for r in mdr {
            assert_eq!(r[6], "ok", "{scene}");
            assert!(
                num(r[3]) <= num(r[5]) + 3e-10,
                "{scene}: {} > {}",
                r[3],
                r[5]
            );
        }
        assert_eq!(
            rows.iter()
                .filter(|r| r[0] == scene && r[1] == "brute force over springs")
                .count(),
            4
        );
    }
    let orders = std::fs::read_to_string(dir.path().join("convergence_orders.csv")).unwrap();
    assert!(orders.lines().count() > 8);
}

#[test]
fn extreme_inputs_end_with_a_clear_error_not_a_hang() {
    // A fixed-step run at a vanishing velocity has a transient of ≈ 1/(2πV)
    // periods: the step budget ends it with "not converged" (exit 1), quickly.
    let t = std::time::Instant::now();
    let out = fricctl()
        .args([
            "mu",
            "--duz-rel",
            "0.5",
            "--dux-rel",
            "0.2",
            "--v0",
            "1e-12",
            "--method",
            "fixed",
            "--steps-per-period",
            "1000",
        ])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("did not reach a steady state"));
    assert!(t.elapsed() < std::time::Duration::from_secs(30));
    bad(&["sim-device", "--pty", "--seconds", "inf"], "--seconds");
    bad(&["sim-device", "--pty", "--noise", "-1"], "--noise");
    bad(&["device", "--sim", "--sim-v0", "nan", "info"], "--sim-v0");
}

/// `--method auto --tol`: the approximation answers exactly when its bound
/// 0.0144·A is within the tolerance, and it is then within that bound of the
/// exact solver; below the exact solver's bound the request is refused.
#[test]
fn auto_picks_the_cheapest_method_within_tol() {
    let base = [
        "mu",
        "--duz-rel",
        "0.4",
        "--dux-rel",
        "0",
        "--phi-deg",
        "0",
        "--v-rel",
        "0.3",
        "--json",
    ];
    let exact_v = json(&[&base[..], &["--method", "exact"]].concat());
    let m_exact = exact_v["mu_over_mu0"].as_f64().unwrap();
    // 0.0144·0.4 = 0.00576.
    for (tol, want) in [
        ("1e-2", "approx_eq21"),
        ("0.00576", "approx_eq21"),
        ("0.0057", "exact"),
        ("1e-6", "exact"),
    ] {
        let v = json(&[&base[..], &["--tol", tol]].concat());
        assert_eq!(v["method"], want, "tol {tol}");
        let b = v["error_bound_over_mu0"].as_f64().unwrap();
        assert!(b <= tol.parse::<f64>().unwrap());
        let m = v["mu_over_mu0"].as_f64().unwrap();
        assert!((m - m_exact).abs() <= b, "{m} vs {m_exact} (bound {b})");
    }
    // Beyond v_c: sliding, bound 0, whatever the tolerance.
    let v = json(&[
        "mu",
        "--duz-rel",
        "0.4",
        "--dux-rel",
        "0.3",
        "--phi-deg",
        "20",
        "--v-rel",
        "1.5",
        "--json",
    ]);
    assert_eq!(v["method"], "sliding");
    assert_eq!(v["mu_over_mu0"], 1.0);
    assert_eq!(v["error_bound_over_mu0"], 0.0);
    // Tighter than any method: exit 2, one line naming --tol.
    let out = fricctl()
        .args([&base[..], &["--tol", "1e-12"]].concat())
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8(out.stderr).unwrap();
    assert!(
        err.starts_with("error: --tol:") && err.lines().count() == 1,
        "{err}"
    );
    for bad in ["0", "-1", "nan", "inf"] {
        let out = fricctl()
            .args([&base[..], &["--tol", bad]].concat())
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(2), "--tol {bad}");
    }
    // --tol with a method that does not choose.
    let out = fricctl()
        .args([&base[..], &["--method", "exact", "--tol", "1e-3"]].concat())
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
}

/// The fixed-step method's explicit refusals reach the user as one line.
#[test]
fn fixed_step_refusals_are_usage_errors() {
    let base = [
        "mu",
        "--duz-rel",
        "0.4",
        "--dux-rel",
        "3",
        "--phi-deg",
        "0",
        "--v-rel",
        "0.3",
        "--method",
        "fixed",
    ];
    // ⌈√(10·(1 + 3)/0.1)⌉ = 20.
    let out = fricctl()
        .args([&base[..], &["--steps-per-period", "19"]].concat())
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8(out.stderr).unwrap();
    assert!(err.contains("at least 20"), "{err}");
    let v = json(&[&base[..], &["--steps-per-period", "20", "--json"]].concat());
    // The stated bound (1 + b)(K_D/N² + N·ε) with K_D = 10.
    let want = 4.0 * (10.0 / 400.0 + 20.0 * f64::EPSILON);
    assert!(close(
        v["error_bound_over_mu0"].as_f64().unwrap(),
        want,
        1e-12
    ));
    let out = fricctl()
        .args([&base[..], &["--steps-per-period", "2000000"]].concat())
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8(out.stderr).unwrap().contains("at most"));
}

/// `map --v-rel`: every cell's μ equals an independent per-cell computation;
/// the cells are dual-mode (ratio > 0 at every cell centre), where no
/// approximation applies, so even a loose tolerance leaves all 16 exact.
#[test]
fn mu_map_cells_follow_the_method_choice() {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("m.csv");
    let png = dir.path().join("m.png");
    let out = run_ok(&[
        "map",
        "--duz-rel",
        "0.5",
        "--ratio-min",
        "0",
        "--ratio-max",
        "2",
        "--res",
        "4",
        "--v-rel",
        "0.5",
        "--tol",
        "1e-2",
        "--plot",
        png.to_str().unwrap(),
        "--csv",
        csv.to_str().unwrap(),
    ]);
    assert!(String::from_utf8(out.stderr).unwrap().contains("exact 16"));
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut n = 0;
    for l in text.lines().skip(1) {
        let f: Vec<&str> = l.split(',').collect();
        let (phi, ratio): (f64, f64) = (f[0].parse().unwrap(), f[1].parse().unwrap());
        let s = Scene::dimensionless(model_core::Groups {
            duz_rel: 0.5,
            dux_rel: 0.5 * ratio,
            phi: phi.to_radians(),
        })
        .unwrap();
        let v = 0.5 * model_core::analytic::CriticalVelocity::of(&s).forward;
        let want = exact::solve(&s, v).unwrap().mu_over_mu0().unwrap();
        let got: f64 = f[3].parse().unwrap();
        assert_eq!(f[4], "exact");
        assert!((got - want).abs() <= 1e-12, "{l}");
        n += 1;
    }
    assert_eq!(n, 16);
    assert!(std::fs::metadata(&png).unwrap().len() > 1000);
}

/// `bench stability` at a coarse resolution: every map is written, and no
/// cell returns a number outside its method's stated bound (the command
/// fails if one does).
#[test]
fn bench_stability_maps_have_no_silent_failures() {
    let dir = tempfile::tempdir().unwrap();
    let out = run_ok(&[
        "bench",
        "stability",
        "--out",
        dir.path().to_str().unwrap(),
        "--res",
        "8",
    ]);
    let text = String::from_utf8(out.stdout).unwrap();
    for name in [
        "fixed_f64",
        "fixed_f32",
        "exact_lift_off_f64",
        "exact_lift_off_f32",
        "exact_ratio_f64",
        "exact_ratio_f32",
        "si_f64",
        "si_f32",
    ] {
        check_png(&dir.path().join(format!("{name}.png")));
        let csv = std::fs::read_to_string(dir.path().join(format!("{name}.csv"))).unwrap();
        assert_eq!(csv.lines().count(), 65, "{name}");
        assert!(!csv.contains("exceeds"), "{name}");
        assert!(text.contains(&format!("{name} ")), "{text}");
    }
    // The failure classes the maps are for appear where expected.
    let f32_fixed = std::fs::read_to_string(dir.path().join("fixed_f32.csv")).unwrap();
    assert!(f32_fixed.contains("precision limit") && f32_fixed.contains("too few steps"));
    let ratio = std::fs::read_to_string(dir.path().join("exact_ratio_f32.csv")).unwrap();
    assert!(ratio.contains("ill-conditioned"));
    let si = std::fs::read_to_string(dir.path().join("si_f32.csv")).unwrap();
    assert!(si.contains("out of range"));
}

/// `bench methods` at small sizes: the CSV has every case × method, and the
/// mixes say what answered.
#[test]
fn bench_methods_reports_times_and_mix() {
    let dir = tempfile::tempdir().unwrap();
    run_ok(&[
        "bench",
        "methods",
        "--out",
        dir.path().to_str().unwrap(),
        "--points",
        "200",
        "--res",
        "6",
        "--fixed-points",
        "4",
        "--fixed-res",
        "2",
        "--steps-per-period",
        "512",
        "--repeats",
        "1",
        "--mdr-points",
        "20",
    ]);
    let csv = std::fs::read_to_string(dir.path().join("methods.csv")).unwrap();
    let lines: Vec<&str> = csv.lines().skip(1).collect();
    assert_eq!(lines.len(), 26);
    // Curved profiles, without (a = 0.5) and with lift-off (a = 1.5):
    // v/v_c = −1.5 + 3i/19 slides for |v/v_c| ≥ 1 (i ≤ 3 and i ≥ 16, the flat
    // punch's v_c for every profile — eq. 8, resp. eq. L5), the other 12
    // points go to the exact solver (flat: single spring, resp. lift-off) or
    // the MDR quadrature (sphere, cone).
    for first in [12, 19] {
        assert!(
            lines[first].contains("sliding 8 + exact 12"),
            "{}",
            lines[first]
        );
        for l in &lines[first + 1..first + 7] {
            assert!(l.contains("sliding 8 + mdr 12"), "{l}");
        }
    }
    assert!(lines[19].contains("lift-off solver"), "{}", lines[19]);
    // Normal-only curve at tol 1e-2: |v| ≥ v_c slides (v/v_c = −1.5 + 3i/199:
    // i·3/199 ≤ 0.5 for i ≤ 33, 34 points on each side), the other 132 are
    // eq. 21 (bound 0.0144·0.4 ≤ 1e-2), or the exact solver at the default tolerance.
    assert!(
        lines[0].contains("sliding 68 + approx_eq21 132"),
        "{}",
        lines[0]
    );
    assert!(lines[1].contains("sliding 68 + exact 132"), "{}", lines[1]);
    assert!(lines[3].contains("fixed 4"), "{}", lines[3]);
}

/// `bench dac`: the measured worst errors and SFDR follow the closed forms of
/// table look-up (amp = 2047 codes): nearest entry ≈ amp·sin(π/N) plus
/// rounding, linear ≤ amp·(2π/N)²/8 + 0.5; SFDR rises ≈ 6 dB per doubling of N
/// (nearest) and ≈ 12 dB (linear) until the 12-bit floor; micromath tables
/// are limited by its sine error (≤ 1.1e-3 ≈ 2.3 LSB); the codes formed
/// from the reference words (the board's) stay within eq. Q7.
#[test]
fn bench_dac_matches_table_lookup_theory() {
    let dir = tempfile::tempdir().unwrap();
    run_ok(&[
        "bench",
        "dac",
        "--out",
        dir.path().to_str().unwrap(),
        "--rounds",
        "1",
    ]);
    check_png(&dir.path().join("dac.png"));
    check_svg(&dir.path().join("dac.svg"));
    let csv = std::fs::read_to_string(dir.path().join("dac.csv")).unwrap();
    let rows: Vec<Vec<String>> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect();
    assert_eq!(rows.len(), 7 * 6 + 2);
    let get = |n: usize, interp: &str, backend: &str| -> (f64, f64) {
        let r = rows
            .iter()
            .find(|r| r[0] == n.to_string() && r[1] == interp && r[2] == backend)
            .unwrap_or_else(|| panic!("{n} {interp} {backend}"));
        (r[3].parse().unwrap(), r[4].parse().unwrap())
    };
    let amp = 2047.0f64;
    let sizes = [16usize, 64, 256, 1024, 4096, 16384, 65536];
    for &n in &sizes {
        let h = std::f64::consts::PI / n as f64;
        let (_, worst) = get(n, "nearest", "libm");
        let want = amp * h.sin();
        assert!(
            worst >= 0.97 * want && worst <= amp * h + 0.5 + 1e-3,
            "nearest {n}: {worst} vs {want}"
        );
        let (_, worst) = get(n, "linear", "libm");
        let bound = amp * (2.0 * h).powi(2) / 8.0 + 0.5 + 1e-3;
        assert!(worst <= bound, "linear {n}: {worst} > {bound}");
        if n <= 64 {
            assert!(worst >= bound - 1.0, "linear {n}: {worst} vs {bound}");
        }
        // A micromath table entry differs from libm's by ≤ its sine error,
        // 1.1e-3·amp = 2.25 LSB (tests/micromath_bounds.rs), so its worst
        // error is within 2.25 LSB of the libm table's on either side:
        // ≤ amp(2π/N)²/8 + 0.5 + 2.25 (2.76 LSB at N ≥ 1024; README: 2.73).
        let (_, worst_libm) = get(n, "linear", "libm");
        let (_, worst) = get(n, "linear", "micromath");
        let sine = amp * 1.1e-3;
        println!(
            "micromath linear {n}: {worst:.3} LSB (libm {worst_libm:.3}, bound {:.3})",
            bound + sine
        );
        assert!(
            worst <= bound + sine && worst >= worst_libm - sine,
            "micromath {n}: {worst} vs libm {worst_libm} ± {sine}"
        );
        if n == 1024 {
            // The README's table figure (micromath, N = 1024, linear: 2.73 LSB).
            assert!((worst - 2.73).abs() < 0.01, "micromath 1024: {worst}");
        }
    }
    for w in sizes.windows(2).take(4) {
        let (a, _) = get(w[0], "nearest", "libm");
        let (b, _) = get(w[1], "nearest", "libm");
        assert!((b - a - 12.04).abs() < 2.0, "nearest {w:?}: {a} → {b}");
    }
    for w in sizes.windows(2).take(2) {
        let (a, _) = get(w[0], "linear", "libm");
        let (b, _) = get(w[1], "linear", "libm");
        assert!((b - a - 24.08).abs() < 2.0, "linear {w:?}: {a} → {b}");
    }
    // 12-bit floor: a full-scale sine quantised to 4096 levels has SNR ≈ 74 dB;
    // the largest single spur of 2¹⁹ bins sits far below it.
    let (floor, worst) = get(1024, "linear", "libm");
    assert!(floor > 90.0 && worst <= 0.52, "{floor} {worst}");
    let (direct, worst) = get(0, "direct", "libm");
    assert!(direct > 90.0 && worst <= 0.5 + 1e-3, "{direct} {worst}");
    // From the reference words (the board's, eq. Q6): within eq. Q7,
    // 1/2 + √2·amp·(ε_r + ε_φ + 3·2⁻²⁴) + √2/16 + 2⁻¹⁹, with the table's
    // entries within ε_t (libm: π·2⁻²³ + 2⁻²⁴; micromath: its sine error
    // 1.1e-3), ε_φ = ε_t + (2π/N)²/8 + 2⁻²⁹ and ε_r (eq. R2: each run's
    // first phase times its step, both read within ε_φ) = max(2√2·ε_φ +
    // 2ε_φ² + 2⁻²⁷ + 2⁻¹⁶, 2⁻¹⁵).
    for (backend, eps_t) in [
        (
            "libm",
            std::f64::consts::PI * 2f64.powi(-23) + 2f64.powi(-24),
        ),
        ("micromath", 1.1e-3),
    ] {
        for &n in &sizes {
            let eps_phi =
                eps_t + (2.0 * std::f64::consts::PI / n as f64).powi(2) / 8.0 + 2f64.powi(-29);
            let eps_r = (2.0 * 2f64.sqrt() * eps_phi
                + 2.0 * eps_phi * eps_phi
                + 2f64.powi(-27)
                + 2f64.powi(-16))
            .max(2f64.powi(-15));
            let q7 = 0.5
                + 2f64.sqrt() * amp * (eps_r + eps_phi + 3.0 * 2f64.powi(-24))
                + 2f64.sqrt() / 16.0
                + 2f64.powi(-19);
            let (_, worst) = get(n, "reference", backend);
            assert!(worst <= q7, "reference {backend} {n}: {worst} > {q7}");
        }
    }
    // The board's setting: as clean as the linear table's (≤ 0.70 LSB by
    // Q7; the 12-bit floor's SFDR).
    let (floor, worst) = get(1024, "reference", "libm");
    assert!(floor > 90.0 && worst <= 0.81, "{floor} {worst}");
}

/// Runs fricctl expecting bad input: exit 2, nothing on stdout, and exactly
/// `want` (one line) on stderr.
fn refused_with(args: &[&str], want: &str) {
    let out = fricctl().args(args).output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
    assert!(out.stdout.is_empty(), "{args:?}");
    assert_eq!(err, format!("error: {want}\n"), "{args:?}");
}

const CURVE_0_1: &[&str] = &["curve", "--v-min", "0", "--v-max", "1"];

#[test]
fn negative_numbers_are_values() {
    refused_with(
        &[CURVE_0_1, &["--points", "-5"], PHYS].concat(),
        "--points: must be ≥ 2 (got -5)",
    );
    refused_with(
        &[
            "device", "--sim", "scene", "set", "--mu0", "-1", "--kz", "1e6", "--kx", "1e6",
        ],
        "--mu0: must be > 0 (got -1)",
    );
    refused_with(
        &["map", "--duz-rel", "0.5", "--res", "-3", "--plot", "m.png"],
        "--res: must be ≥ 2 (got -3)",
    );
}

#[test]
fn misspelt_enum_value_lists_the_allowed_ones() {
    refused_with(
        &[
            "mu",
            "--duz-rel",
            "0.5",
            "--dux-rel",
            "0.1",
            "--v0",
            "0.1",
            "--method",
            "exakt",
        ],
        "--method: invalid value 'exakt' (one of: auto, exact, fixed, approx)",
    );
}

#[test]
fn counts_are_read_like_numbers() {
    // `1e1` is 10: the same bytes as `--points 10`.
    let a = run_ok(&[CURVE_0_1, &["--points", "1e1"], PHYS].concat()).stdout;
    let b = run_ok(&[CURVE_0_1, &["--points", "10"], PHYS].concat()).stdout;
    assert_eq!(a, b);
    // Header, 10 velocities, and v0 = 0 written twice (μ(0⁻) then μ(0⁺)).
    assert_eq!(String::from_utf8(a).unwrap().lines().count(), 12);
    refused_with(
        &[CURVE_0_1, &["--points", "2.5"], PHYS].concat(),
        "--points: must be a whole number (got 2.5)",
    );
    refused_with(
        &[CURVE_0_1, &["--points", "2e7"], PHYS].concat(),
        "--points: must be ≤ 10000000 (got 2e7; write several curves for more)",
    );
    refused_with(
        &[CURVE_0_1, &["--points", "many"], PHYS].concat(),
        "--points: 'many' is not a number",
    );
    refused_with(
        &["device", "--sim", "--attempts", "0", "info"],
        "--attempts: must be ≥ 1 (got 0)",
    );
}

/// Fields of a curve CSV line (`v0,v_rel,mu,mu_over_mu0,method,error_bound_over_mu0`).
const CURVE_HEADER: &str = "v0,v_rel,mu,mu_over_mu0,method,error_bound_over_mu0";

#[test]
fn long_curve_streams_whole_rows_to_a_file() {
    // 70 001 points: more than one 65 536-velocity chunk, so the header must
    // appear once and the rows stay in order across the chunk boundary.
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("c.csv");
    let n = 70_001usize;
    let out = run_ok(&[
        "curve",
        "--duz-rel",
        "0.5",
        "--ratio",
        "2",
        "--phi-deg",
        "45",
        "--v-rel-min",
        "0.001",
        "--v-rel-max",
        "3",
        "--points",
        "70001",
        "--csv",
        f.to_str().unwrap(),
    ]);
    // stderr is not a terminal here: no progress bar, only the summary lines.
    let err = String::from_utf8(out.stderr).unwrap();
    assert_eq!(err.lines().count(), 2, "{err}");
    assert!(err.starts_with("methods: "), "{err}");
    assert!(err.ends_with(&format!("wrote {n} rows to {}\n", f.display())));
    let text = std::fs::read_to_string(&f).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some(CURVE_HEADER));
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), n);
    let s =
        Scene::dimensionless(Groups::from_ratio(0.5, 2.0, 45f64.to_radians()).unwrap()).unwrap();
    let vc = CriticalVelocity::of(&s);
    for i in [0, 65_535, 65_536, 65_537, n - 1] {
        let r = &rows[i];
        assert_eq!(r.len(), 6);
        // The i-th velocity is x_i·v_c with x_i evenly spaced from 0.001 to 3.
        let x = if i == n - 1 {
            3.0
        } else {
            0.001 + (3.0 - 0.001) * i as f64 / (n - 1) as f64
        };
        let v: f64 = r[0].parse().unwrap();
        assert_eq!(v, x * vc.forward, "row {i}");
        // μ/μ0 equals the exact solver's value at that velocity (±μ0 beyond
        // v_c): the auto method's default tolerance is the solver's bound.
        let want = exact::mu_over_mu0::<f64, Libm>(&s.drive(), v).unwrap();
        let bound = exact::error_bound::<f64, Libm>(&s.drive());
        let got: f64 = r[3].parse().unwrap();
        assert!((got - want).abs() <= bound, "row {i}: {got} vs {want}");
    }
    // Only the CSV in the directory: no temporary file left behind.
    let names: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
    assert_eq!(names.len(), 1);
}

/// Sends SIGINT to `child` once `delay` has passed, then collects it (with a
/// 120 s limit, after which it is killed and the test fails).
fn interrupt(child: std::process::Child, delay: std::time::Duration) -> std::process::Output {
    std::thread::sleep(delay);
    let pid = child.id().to_string();
    let st = std::process::Command::new("kill")
        .args(["-INT", &pid])
        .status()
        .unwrap();
    assert!(st.success());
    let watchdog = std::thread::spawn({
        let pid = pid.clone();
        move || {
            std::thread::sleep(std::time::Duration::from_secs(120));
            let _ = std::process::Command::new("kill")
                .args(["-KILL", &pid])
                .status();
        }
    });
    let out = child.wait_with_output().unwrap();
    drop(watchdog);
    out
}

const HUGE_CURVE: &[&str] = &[
    "curve",
    "--duz-rel",
    "0.5",
    "--ratio",
    "2",
    "--phi-deg",
    "45",
    "--v-rel-min",
    "-1.5",
    "--v-rel-max",
    "1.5",
    "--points",
    "1e7",
];

#[test]
fn ctrl_c_leaves_no_truncated_csv() {
    use std::process::Stdio;
    // To a file: nothing appears under its name, and no temporary is left.
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("c.csv");
    let child = std::process::Command::new(assert_cmd::cargo::cargo_bin("fricctl"))
        .args(HUGE_CURVE)
        .args(["--csv", f.to_str().unwrap()])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let out = interrupt(child, std::time::Duration::from_millis(1500));
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(130), "{err}");
    assert!(
        err.starts_with("error: interrupted after ")
            && err.ends_with(&format!(
                " of 10000000 velocities ({} not written)\n",
                f.display()
            )),
        "{err}"
    );
    assert!(!f.exists());
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    // To stdout: whatever was written is whole rows.
    let child = std::process::Command::new(assert_cmd::cargo::cargo_bin("fricctl"))
        .args(HUGE_CURVE)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let out = interrupt(child, std::time::Duration::from_millis(1500));
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(130), "{err}");
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(text.is_empty() || text.ends_with('\n'));
    let mut lines = text.lines();
    let rows = if text.is_empty() {
        0
    } else {
        assert_eq!(lines.next(), Some(CURVE_HEADER));
        lines
            .map(|l| assert_eq!(l.split(',').count(), 6, "{l}"))
            .count()
    };
    assert!(
        err.ends_with(&format!(" velocities ({rows} whole rows written)\n")),
        "{err} ({rows} rows)"
    );
}

#[test]
fn device_target_errors_name_the_flag() {
    refused_with(
        &["device", "--tcp", "localhost", "info"],
        "--tcp: 'localhost' is not HOST:PORT (e.g. 127.0.0.1:7777)",
    );
    refused_with(
        &["device", "--port", "/dev/null", "info"],
        "--port: /dev/null is not a serial device",
    );
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("plain");
    std::fs::write(&f, "").unwrap();
    refused_with(
        &["device", "--port", f.to_str().unwrap(), "info"],
        &format!("--port: {} is not a serial device", f.display()),
    );
    // Counts of the device commands are read like the model commands' ones.
    refused_with(
        &["device", "--sim", "measure", "--periods", "-5"],
        "--periods: must be ≥ 1 (got -5)",
    );
    refused_with(
        &["device", "--sim", "watch", "--count", "0"],
        "--count: must be ≥ 1 (got 0)",
    );
}

#[test]
fn zero_critical_velocity_at_phi_180_ratio_1() {
    // φ = 180°, b = a (ratio 1): eq. 8 gives v_c+ = |b e^{iπ} + a| ωW0 = 0
    // and v_c− = 2a ωW0 = 1 (ωW0 = 1 in the dimensionless scene). The
    // computed |b e^{iφ} + a| is 6e-17 (sin of the rounded π), which the
    // documented 32-ulp rule counts as 0.
    let g = ["--duz-rel", "0.5", "--ratio", "1", "--phi-deg", "180"];
    let v = json(&[&["static", "--json"], &g[..]].concat());
    assert_eq!(v["vc_forward"].as_f64(), Some(0.0));
    assert!((v["vc_backward"].as_f64().unwrap() - 1.0).abs() <= 2.0 * f64::EPSILON);
    let v = json(&[&["mu", "--v0", "0.1", "--json"], &g[..]].concat());
    assert_eq!(v["vc_forward"].as_f64(), Some(0.0));
    assert!(v["v_rel"].is_null());
    // Beyond v_c = 0 the contact slides: μ = μ0 exactly.
    assert_eq!(v["mu_over_mu0"].as_f64(), Some(1.0));
    let text =
        String::from_utf8(run_ok(&[&["mu", "--v0", "0.1"], &g[..]].concat()).stdout).unwrap();
    assert!(
        text.contains("v0/v_c       (v_c = 0 in this direction)\n"),
        "{text}"
    );
    assert!(text.contains("v_c forward  0 ωW0\n"), "{text}");
}

#[test]
fn help_texts_match_behaviour() {
    let help = |args: &[&str]| String::from_utf8(run_ok(args).stdout).unwrap();
    let top = help(&["--help"]);
    assert!(
        top.contains("CSV rows v0,v_rel,mu,mu_over_mu0,method,error_bound_over_mu0"),
        "{top}"
    );
    assert!(
        top.contains("work-precision, methods, stability, dac"),
        "{top}"
    );
    let mu = help(&["mu", "--help"]);
    assert!(!mu.contains("velocities are then relative to v_c"), "{mu}");
    assert!(mu.contains("--v0 is in units of ωW0"), "{mu}");
}

/// Issue 37: `bench --help`'s summary (also `fricctl --help`'s line for
/// `bench`) names every bench that the help lists under "Commands:".
#[test]
fn bench_help_summary_names_every_bench() {
    let text = String::from_utf8(run_ok(&["bench", "--help"]).stdout).unwrap();
    let summary = text.lines().next().unwrap();
    let benches: Vec<&str> = text
        .lines()
        .skip_while(|l| *l != "Commands:")
        .skip(1)
        .take_while(|l| l.starts_with("  "))
        .filter_map(|l| l.split_whitespace().next())
        .filter(|b| *b != "help")
        .collect();
    assert_eq!(benches.len(), 6, "{text}");
    for b in &benches {
        assert!(summary.contains(b), "{b} missing from {summary:?}");
    }
}

/// Issue 37, wall 5: the regime's words. At Δu_z/u_z0 = a = 0.9, ratio
/// r = 0.7, φ = 0, eq. 8 gives c = a(1 + r) = 1.53 and c′ = a|1 − r| = 0.27, so
/// the static interval (paper §2.2) is [c′ − 1, 1 − c] = [−0.73, −0.53]: the
/// contact sticks when held by such a force, and free (zero force, outside
/// the interval) it moves — an actuator (class III) with a static interval.
/// The text says both, prints no float noise (0.53, not 0.5300000000000002),
/// and keeps μ_s− a magnitude named as one. Every label fits the 23-column
/// field (no label pushes its value out of line).
#[test]
fn classify_and_static_explain_an_actuator_that_sticks_when_held() {
    let g = ["--duz-rel", "0.9", "--ratio", "0.7"];
    let c = String::from_utf8(run_ok(&[&["classify"], &g[..]].concat()).stdout).unwrap();
    let want = [
        "regime                 actuator (class III: pushes by itself, mu(0+) < 0 or mu(0-) > 0)",
        "mu(0+)/mu0             -0.53",
        "mu(0-)/mu0             -0.73",
        "static interval        sticks when held at mu/mu0 in [-0.73, -0.53]; free (zero force), it moves",
        "v_c forward/backward   1.53 / 0.27 ωW0",
    ];
    for w in want {
        assert!(c.lines().any(|l| l == w), "missing {w:?} in\n{c}");
    }
    let s = String::from_utf8(run_ok(&[&["static"], &g[..]].concat()).stdout).unwrap();
    let want = [
        "static interval u_x0   [-0.73, -0.53] W0 (sticks when held there)",
        "held force mu/mu0      [-0.73, -0.53]: free (zero force), it moves (an actuator)",
        "mu_s+/mu0 forward      -0.53 (= mu(0+); paper eq. 18: -0.53)",
        "mu_s-/mu0 backward     0.73 (= -mu(0-), along -x; paper eq. 19: 0.73)",
    ];
    for w in want {
        assert!(s.lines().any(|l| l == w), "missing {w:?} in\n{s}");
    }
    // A ratchet at the same a with a small ratio (r = 0.05: c = 0.945 ≤ 1,
    // c′ = 0.855): free, it rests.
    let r = ["--duz-rel", "0.9", "--ratio", "0.05"];
    let c = String::from_utf8(run_ok(&[&["classify"], &r[..]].concat()).stdout).unwrap();
    assert!(
        c.starts_with("regime                 dynamic_ratchet (class II"),
        "{c}"
    );
    assert!(c.contains("; free (zero force), it rests\n"), "{c}");
    for text in [&c, &s] {
        for l in text.lines() {
            assert_eq!(
                l.char_indices().nth(23).map(|(_, ch)| ch != ' '),
                Some(true),
                "value not at column 23: {l:?}"
            );
            assert_eq!(l.chars().nth(22), Some(' '), "label overflows: {l:?}");
        }
    }
}

/// Issue 41 §4: a map that may take long says so before it starts, on a
/// terminal (run under `script`, which gives the command a pty). A sphere
/// map of 100 × 100 cells (≈ 4 ms a cell in release) is timed on 16 cells
/// and announced in one line — at least the 5 s from which it speaks —
/// before the progress bar; the run is then stopped (the estimate is what
/// is tested, and it comes before any work on the whole).
#[test]
fn a_long_map_prints_its_estimate_up_front_on_a_terminal() {
    use std::io::{BufRead, BufReader};
    let bin = assert_cmd::cargo::cargo_bin("fricctl");
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("m.csv");
    let cmd = format!(
        "{} map --duz-rel 0.5 --res 100 --profile sphere --csv {}",
        bin.display(),
        csv.display()
    );
    let mut child = std::process::Command::new("script")
        .args(["-qec", &cmd, "/dev/null"])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::null())
        .spawn()
        .expect("script (util-linux) runs the command on a pty");
    let out = child.stdout.take().unwrap();
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        for line in BufReader::new(out).split(b'\n').map_while(Result::ok) {
            let _ = tx.send(String::from_utf8_lossy(&line).into_owned());
        }
    });
    let first = rx
        .recv_timeout(std::time::Duration::from_secs(120))
        .expect("a line within 120 s");
    let _ = child.kill();
    let _ = child.wait();
    let first = first.trim();
    let rest = first
        .strip_prefix("map: 10000 cells, about ")
        .unwrap_or_else(|| panic!("{first:?}"));
    let (v, unit) = rest
        .strip_suffix(" (timed on 16 of them)")
        .and_then(|r| r.split_once(' '))
        .unwrap_or_else(|| panic!("{first:?}"));
    let s = v.parse::<f64>().unwrap()
        * match unit {
            "s" => 1.0,
            "min" => 60.0,
            "h" => 3600.0,
            _ => panic!("{first:?}"),
        };
    assert!(s >= 5.0, "{first}");
    assert!(!csv.exists(), "nothing written before the map is done");
}
