//! A command that fails, is refused, is interrupted or only queries leaves
//! the device and every file as it found them: the device's drive, mode,
//! options and running state are put back on every way out (SIGINT and
//! SIGTERM sent mid-run over a pty included), outputs are checked before any
//! work, and no header-only file is left behind.

mod common;

use std::path::Path;
use std::process::{Command as StdCommand, Stdio};
use std::time::{Duration, Instant};

use assert_cmd::cargo::CommandCargoExt;
use common::cli::fricctl;
use common::signal_and_wait;
use common::sim::{dev, ok_json, sim, sim_with, Sim};
use serde_json::Value;

/// The resonant plant of the identification tests (both modes ring in the
/// ±5 % span around 20 kHz).
const RESONANT: &[&str] = &[
    "--plant-resonance-z",
    "20300",
    "--plant-q-z",
    "300",
    "--plant-resonance-x",
    "19700",
    "--plant-q-x",
    "200",
];

/// The drive, mode, options and running state as `drive get` and `status`
/// report them.
fn state(s: &Sim) -> (Value, Value, Value, Value) {
    let d = ok_json(s, &["drive", "get"]);
    let st = ok_json(s, &["status"]);
    (
        d,
        st["drive_mode"].clone(),
        serde_json::json!([st["track"], st["headroom"]]),
        st["running"].clone(),
    )
}

/// `fricctl device --port PTY ARGS`, spawned with its output piped.
fn spawn_dev(s: &Sim, args: &[&str]) -> std::process::Child {
    StdCommand::cargo_bin("fricctl")
        .unwrap()
        .args(["device", "--port", &s.path])
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
}

fn stderr_of(child: &mut std::process::Child) -> String {
    let mut err = String::new();
    std::io::Read::read_to_string(&mut child.stderr.take().unwrap(), &mut err).unwrap();
    err
}

/// The transducers are not identified: `drive set` without `--open-loop`
/// is refused, naming `identify`.
fn assert_not_identified(s: &Sim) {
    let plain: Vec<&str> = common::drive_set("20000", "1e-6", "2e-7", "4e-6", Some("30"))
        .into_iter()
        .filter(|a| *a != "--open-loop")
        .collect();
    let o = dev(s, &plain);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("run `fricctl device identify`"));
}

#[test]
fn identify_interrupted_by_a_signal_puts_the_device_back() {
    for signal in ["-INT", "-TERM"] {
        let s = sim_with(RESONANT, 600);
        // A drive of the user's own (identify sweeps with its own), stopped.
        ok_json(
            &s,
            &common::drive_set("20000", "1e-6", "2e-7", "4e-6", Some("30")),
        );
        let before = state(&s);
        assert_eq!(before.3, false);
        let mut child = spawn_dev(&s, &["identify"]);
        // The sweep runs for ≈ 10 s; 2 s in, it drives the normal transducer.
        std::thread::sleep(Duration::from_millis(2000));
        assert!(child.try_wait().unwrap().is_none(), "identify ended early");
        let st = signal_and_wait(&mut child, signal, 10, "identify");
        let err = stderr_of(&mut child);
        assert_eq!(st.code(), Some(130), "{signal}: {err}");
        assert!(err.contains("interrupted"), "{err}");
        assert_eq!(err.trim().lines().count(), 1, "{err}");
        // The user's drive, voltage mode, options and the stopped drive.
        assert_eq!(state(&s), before, "{signal}");
        // Nothing stored.
        assert_not_identified(&s);
    }
}

#[test]
fn identify_refuses_an_out_it_cannot_write_before_it_sweeps() {
    let s = sim_with(RESONANT, 600);
    ok_json(&s, &common::drive_set("20000", "0", "0", "4e-6", None));
    let before = state(&s);
    for (flag, path) in [
        ("--out", "/nonexistent/x.json"),
        ("--plot", "/nonexistent/x.png"),
        ("--plot", "/tmp/bode.txt"),
    ] {
        let t = Instant::now();
        let o = dev(&s, &["identify", flag, path]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{flag} {path}: {err}");
        assert!(err.contains(flag), "{err}");
        assert_eq!(err.trim().lines().count(), 1, "{err}");
        // Refused before the sweep (which takes ≈ 10 s).
        assert!(t.elapsed() < Duration::from_secs(5), "{:?}", t.elapsed());
    }
    assert_eq!(state(&s), before);
    assert_not_identified(&s);
}

/// A sweep of amp-z from 1e-6 m to `to` over 2 points, 200 periods each.
fn sweep_args<'a>(to: &'a str, csv: &'a Path) -> Vec<&'a str> {
    vec![
        "sweep",
        "--param",
        "amp-z",
        "--from",
        "1e-6",
        "--to",
        to,
        "--points",
        "2",
        "--periods",
        "200",
        "--v0",
        "0.004",
        "--csv",
        csv.to_str().unwrap(),
    ]
}

#[test]
fn a_sweep_refused_midway_puts_the_drive_back_and_keeps_its_rows() {
    let s = sim();
    ok_json(
        &s,
        &common::drive_set("20000", "2e-6", "3e-7", "4e-6", Some("40")),
    );
    ok_json(&s, &["start"]);
    std::thread::sleep(Duration::from_millis(300));
    let before = state(&s);
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("sw.csv");
    // The second point (1 m) would lift the contact off: refused, named by --to.
    let o = dev(&s, &sweep_args("1", &csv));
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.starts_with("error: --to:"), "{err}");
    // The drive as it was, still running.
    assert_eq!(state(&s), before);
    // The measured row is kept whole (the file policy), resumable.
    let text = std::fs::read_to_string(&csv).unwrap();
    assert_eq!(text.lines().count(), 2, "{text}");
    assert!(
        text.lines().nth(1).unwrap().starts_with("amp-z,1e-6,"),
        "{text}"
    );
}

#[test]
fn a_sweep_refused_at_its_first_point_leaves_no_file() {
    let s = sim();
    ok_json(
        &s,
        &common::drive_set("20000", "2e-6", "3e-7", "4e-6", Some("40")),
    );
    ok_json(&s, &["start"]);
    let before = state(&s);
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("sw.csv");
    let mut args = sweep_args("2", &csv);
    args[4] = "1"; // --from 1 m: refused at once.
    let o = dev(&s, &args);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).starts_with("error: --from:"));
    assert!(!csv.exists(), "a header-only file was left behind");
    assert_eq!(state(&s), before);
}

#[test]
fn a_sweep_interrupted_by_a_signal_puts_the_drive_back() {
    let s = sim();
    ok_json(
        &s,
        &common::drive_set("20000", "2e-6", "3e-7", "4e-6", Some("40")),
    );
    ok_json(&s, &["start"]);
    std::thread::sleep(Duration::from_millis(300));
    let before = state(&s);
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("sw.csv");
    // 20 points of 4000 periods (0.2 s each at 20 kHz, the sim in real time).
    let mut args = sweep_args("3e-6", &csv);
    args[8] = "20";
    args[10] = "4000";
    let mut child = spawn_dev(&s, &args);
    std::thread::sleep(Duration::from_millis(1500));
    assert!(child.try_wait().unwrap().is_none(), "sweep ended early");
    let st = signal_and_wait(&mut child, "-INT", 10, "sweep");
    let err = stderr_of(&mut child);
    assert_eq!(st.code(), Some(130), "{err}");
    assert!(err.contains("interrupted"), "{err}");
    assert_eq!(state(&s), before);
    // Whole rows only, each a point of this sweep.
    let text = std::fs::read_to_string(&csv).unwrap();
    assert!(text.ends_with('\n'), "{text}");
    let rows = text.lines().count() - 1;
    assert!((1..20).contains(&rows), "{rows} rows: {text}");
}

/// `fricctl ARGS` in `dir`.
fn run_in(dir: &Path, args: &[&str]) -> std::process::Output {
    fricctl().current_dir(dir).args(args).output().unwrap()
}

const LOAD_LINE: &[&str] = &[
    "load-line",
    "--duz-rel",
    "0.5",
    "--ratio",
    "2",
    "--phi-deg",
    "0",
    "--points",
    "3",
];

#[test]
fn outputs_are_checked_before_any_work_and_never_name_one_file_twice() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    for (extra, flag, why) in [
        (
            &["--csv", "p.png", "--plot", "p.png"][..],
            "--csv",
            "same file",
        ),
        (
            &["--csv", "ll.csv", "--plot", "x.txt"][..],
            "--plot",
            ".svg or .png",
        ),
        (
            &["--csv", "ll.csv", "--plot", "missing/x.png"][..],
            "--plot",
            "does not exist",
        ),
        (&["--csv", "missing/ll.csv"][..], "--csv", "does not exist"),
        (&["--csv", "."][..], "--csv", "is a directory"),
    ] {
        let o = run_in(d, &[LOAD_LINE, extra].concat());
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{extra:?}: {err}");
        assert!(err.starts_with(&format!("error: {flag}:")), "{err}");
        assert!(err.contains(why), "{extra:?}: {err}");
        assert!(!err.contains("os error"), "{err}");
        // Nothing written.
        let left: Vec<_> = std::fs::read_dir(d).unwrap().collect();
        assert!(left.is_empty(), "{extra:?} left {left:?}");
    }
    // `./p.png` and `p.png` are one file too.
    let o = run_in(
        d,
        &[LOAD_LINE, &["--csv", "./p.png", "--plot", "p.png"]].concat(),
    );
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("same file"));
}

#[test]
fn control_bench_refuses_a_plot_it_cannot_write_before_it_runs() {
    let o = fricctl()
        .args(["device", "control-bench", "--plot", "/nonexistent/cb.png"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.starts_with("error: --plot:"), "{err}");
    assert!(o.stdout.is_empty());
}

#[test]
fn a_flag_a_subcommand_would_ignore_is_refused_by_name() {
    let s = sim();
    ok_json(
        &s,
        &common::drive_set("20000", "2e-6", "3e-7", "4e-6", Some("40")),
    );
    let before = state(&s);
    for (args, flag) in [
        (&["control", "status", "--headroom", "4"][..], "--headroom"),
        (
            &["control", "off", "--v0", "5", "--gain", "0.5"][..],
            "--v0",
        ),
        (&["control", "off", "--gain", "0.5"][..], "--gain"),
        (&["control", "status", "--periods", "auto"][..], "--periods"),
        (&["control", "off", "--rate", "1e-4"][..], "--rate"),
        (
            &common::drive_set("20000", "2e-6", "3e-7", "4e-6", Some("40"))
                .into_iter()
                .chain(["--headroom", "3"])
                .collect::<Vec<_>>()[..],
            "--headroom",
        ),
    ] {
        let o = dev(&s, args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(
            err.starts_with(&format!("error: {flag}:")),
            "{args:?}: {err}"
        );
        assert_eq!(err.trim().lines().count(), 1, "{err}");
    }
    // A query and a refusal change nothing.
    assert_eq!(state(&s), before);
}

/// `drive set --track` below the amplitude the tracking needs (0.2 µm of
/// the tracked mode, `TRACK_MIN_AMP_M`; an undriven one, 0, included) is
/// refused by the flag of that amplitude with the least value, before the
/// mode, the options or the drive reach the device: nothing changes.
#[test]
fn tracking_below_the_amplitude_it_needs_is_refused_by_name() {
    let s = sim();
    ok_json(
        &s,
        &common::drive_set("20000", "2e-6", "3e-7", "4e-6", Some("40")),
    );
    let before = state(&s);
    for (amp_z, amp_x, track, flag, got) in [
        ("2e-6", "1e-7", "x", "--amp-x", "1e-7"),
        ("2e-6", "0", "x", "--amp-x", "0"),
        ("1.5e-7", "3e-7", "z", "--amp-z", "1.5e-7"),
    ] {
        let args: Vec<&str> = common::drive_set("20000", amp_z, amp_x, "4e-6", Some("40"))
            .into_iter()
            .filter(|a| *a != "--open-loop")
            .chain(["--track", track])
            .collect();
        let o = dev(&s, &args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.starts_with(&format!("error: {flag}:")), "{err}");
        assert!(
            err.contains("at least 2e-7 m") && err.contains(&format!("(got {got})")),
            "{err}"
        );
        assert_eq!(err.trim().lines().count(), 1, "{err}");
    }
    assert_eq!(state(&s), before);
}

/// Issue 41 §3: a message names the flag the user typed, in the user's
/// units, and nothing is clamped silently — the device's phase limit
/// (±1000 rad) comes back in degrees, truncated inside it (±57 295°);
/// `identify --from`/`--to` outside the device's range (1 … 100 kHz) are
/// refused by name, not clamped, and an empty span names both; the device
/// is as it was.
#[test]
fn refusals_name_the_flag_in_its_units_and_clamp_nothing() {
    let s = sim();
    ok_json(
        &s,
        &common::drive_set("20000", "0", "0", "4e-6", Some("40")),
    );
    let before = state(&s);
    let phase = common::drive_set("20000", "1e-6", "1e-7", "4e-6", Some("60000"));
    let cases: [(Vec<&str>, &str); 4] = [
        (
            phase,
            "error: --phase-deg: refused by the device: allowed range [-57295, 57295] degrees",
        ),
        (
            vec!["identify", "--from", "500", "--to", "30000"],
            "error: --from: 500 Hz is outside the device's range 1000 … 100000 Hz",
        ),
        (
            vec!["identify", "--from", "19000", "--to", "2e5"],
            "error: --to: 200000 Hz is outside the device's range 1000 … 100000 Hz",
        ),
        (
            vec!["identify", "--from", "30000", "--to", "20000"],
            "error: --from/--to: --from (30000 Hz) must be below --to (20000 Hz)",
        ),
    ];
    for (args, want) in cases {
        let o = dev(&s, &args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert_eq!(err.trim(), want, "{args:?}");
    }
    // −1000 rad is −57 295.78°: the range printed lies inside it.
    assert!(1000f64.to_degrees() >= 57_295.0 && 1000f64.to_degrees() < 57_296.0);
    assert_eq!(state(&s), before);
    assert_not_identified(&s);
}

/// `scene set` takes the stiffnesses the device's f32 model takes
/// (`STIFFNESS_RANGE_N_PER_M`, 1 … 1e12 N/m) and names the flag, or the
/// fit file's key, of one outside it (k_x 1e-30 was accepted and then made
/// every prediction fail; k_z 1e-30 blamed `--offset-z`); the contact stays.
#[test]
fn scene_set_names_a_stiffness_the_model_cannot_take() {
    let s = sim();
    let before = ok_json(&s, &["scene", "get"]);
    let dir = tempfile::tempdir().unwrap();
    let fit = dir.path().join("fit.json");
    std::fs::write(&fit, r#"{"mu0": 0.3, "kz": 1e7, "kx": 0.5}"#).unwrap();
    let fit_arg = fit.to_str().unwrap();
    for (args, want) in [
        (
            vec!["scene", "set", "--mu0", "0.3", "--kz", "1e-30", "--kx", "1e7"],
            "error: --kz: must be ≥ 1 (got 1e-30; the contact stiffness the device's f32 model takes, N/m)",
        ),
        (
            vec!["scene", "set", "--mu0", "0.3", "--kz", "1e7", "--kx", "1e13"],
            "error: --kx: must be ≤ 1e12 (got 1e13; the contact stiffness the device's f32 model takes, N/m)",
        ),
        (vec!["scene", "set", "--from-fit", fit_arg], "kx: must be ≥ 1 (got 0.5"),
    ] {
        let o = dev(&s, &args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.trim().starts_with(want) || err.contains(want), "{args:?}: {err}");
        assert_eq!(err.trim().lines().count(), 1, "{err}");
    }
    assert_eq!(ok_json(&s, &["scene", "get"]), before);
}

#[test]
fn the_plant_refuses_what_it_cannot_be_by_the_flag_given() {
    let dir = tempfile::tempdir().unwrap();
    let prof = dir.path().join("v.csv");
    std::fs::write(&prof, "t_s,v0_m_s\n0,0.004\n1,1e300\n").unwrap();
    let p = prof.to_str().unwrap();
    for (flags, named, why) in [
        (&["--sim-v0", "1e30"][..], "--sim-v0", "1000"),
        (&["--plant-load-q", "0.45"][..], "--plant-load-q", "> 0.5"),
        (&["--plant-load-q", "1e-100"][..], "--plant-load-q", "> 0.5"),
        (
            &["--plant-resonance-z", "1e-100"][..],
            "--plant-resonance-z",
            "",
        ),
        (
            &["--plant-resonance-z", "2e7"][..],
            "--plant-resonance-z",
            "10 MHz",
        ),
        (&["--plant-q-x", "1e7"][..], "--plant-q-x", "1e6"),
        (&["--v0-profile", p][..], "--v0-profile", "line 3"),
    ] {
        let o = fricctl()
            .env("FRICCTL_SIM_STATE", dir.path().join("state.json"))
            .args(["device", "--sim"])
            .args(flags)
            .arg("status")
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{flags:?}: {err}");
        assert!(
            err.starts_with(&format!("error: {named}:")),
            "{flags:?}: {err}"
        );
        assert!(err.contains(why), "{flags:?}: {err}");
        assert_eq!(err.trim().lines().count(), 1, "{err}");
    }
}

/// Issue 41 §1: `drive set` sends the mode, the options, then the drive; a
/// drive the device refuses puts the mode and the options back as they
/// were (all or nothing). Identified transducers (a short identification),
/// the device in voltage mode with headroom 2: `drive set` (displacement,
/// `--headroom 3`) with a Δu_z the DAC cannot give in displacement mode
/// (check 8) is refused naming `--amp-z`, and the mode, options, drive and
/// running state are as before.
#[test]
fn a_refused_drive_puts_the_mode_and_options_back() {
    // A normal transducer a quarter as strong as the bench's: in
    // displacement mode the DAC's room around u_z0 = 4 µm reaches about
    // 1.1 µm at 20 kHz, below the lift-off limit 3.8 µm.
    let s = sim_with(&[RESONANT, &["--plant-gain-z", "2e-8"]].concat(), 600);
    ok_json(
        &s,
        &common::drive_set("20000", "0", "0", "4e-6", Some("40")),
    );
    ok_json(
        &s,
        &[
            "identify",
            "--points",
            "11",
            "--fine-points",
            "11",
            "--settle-ms",
            "20",
        ],
    );
    ok_json(
        &s,
        &common::drive_set("20000", "1e-6", "2e-7", "4e-6", Some("40")),
    );
    let before = state(&s);
    assert_eq!(before.1, "open_loop", "{before:?}");
    let args: Vec<&str> = common::drive_set("20000", "2e-6", "2e-7", "4e-6", Some("40"))
        .into_iter()
        .filter(|a| *a != "--open-loop")
        .chain(["--headroom", "3"])
        .collect();
    let o = dev(&s, &args);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.starts_with("error: --amp-z:"), "{err}");
    assert_eq!(state(&s), before);
}

/// Issue 41 §3: `control-bench` has no drive flags; a plant that cannot
/// give its fixed drive (Δu_z 2 µm, Δu_x 0.3 µm at the normal resonance)
/// is refused naming the plant's flags given that shape that channel (the
/// normal resonance sets the drive frequency), with what the DAC reaches,
/// not `--amp-z`/`--amp-x` (flags the bench does not have), before any run
/// and exit 2.
#[test]
fn control_bench_names_the_plant_flags_that_cannot_give_its_drive() {
    for (flags, names) in [
        (&["--plant-gain-z", "1e-9"][..], "--plant-gain-z:"),
        (
            &["--plant-resonance-z", "30000"][..],
            "--plant-resonance-z:",
        ),
        (
            &["--plant-resonance-x", "25000", "--plant-q-x", "50"][..],
            "--plant-resonance-x, --plant-q-x:",
        ),
    ] {
        let o = fricctl()
            .args(["device", "control-bench"])
            .args(flags)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{flags:?}: {err}");
        assert!(err.starts_with(&format!("error: {names}")), "{err}");
        assert!(err.contains("m at most there"), "{err}");
        assert!(!err.contains("--amp-"), "{err}");
        assert_eq!(err.trim().lines().count(), 1, "{err}");
    }
}
