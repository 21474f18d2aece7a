//! Bad input, generatively: every command × every numeric flag ×
//! hostile values (NaN, ±inf, ±0, ±1e-320, ±1e308, 1e9, −1, −2e-6; the
//! negative ones both as `--flag -x` and `--flag=-x`), each run as a process
//! of the built `fricctl` with a time bound. Every run must
//!
//! * answer within the bound: exit, or (a stream: `watch`, `sim-device`)
//!   have printed on stdout and end within a few seconds of Ctrl-C;
//! * exit 0 with finite output (no `NaN` or `inf` token on stdout), or exit 2
//!   with exactly one line on stderr that starts with a flag that was given;
//! * write no line longer than 200 characters.
//!
//! Exit 1 is the status of a computation that ran and reports that its
//! result failed a stated check (`motion`'s error estimate above `--tol` or
//! no periodic regime, a device's invalid estimate, the control bench's
//! verdict). Valid extreme values reach these legitimately (a 1e9 m
//! indentation ends with `motion`'s estimate far above its tolerance); such
//! a run passes only with one of these [`VERDICTS`] as its one stderr line,
//! so that bad input answered with exit 1 still fails the test.
//!
//! The numeric flags are read from each command's `--help` (every option that
//! takes a value, except the known file, enum and address options), so a new
//! flag is tested without being listed here. Commands that are expensive at
//! valid values (`figures`, `bench …`) run with `--out` naming a regular
//! file: a value the flag accepts then ends in the `--out` refusal (exit 2,
//! naming `--out`) instead of a long run.
//!
//! The regression tests below pin each case found before (NaN and infinite
//! values, unbounded runs, numbers printed in full) by its message.

mod common;

use std::collections::BTreeSet;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use common::cli::{fricctl, PHYS};

/// Values written as `--flag v` only.
const PLAIN: &[&str] = &["nan", "inf", "0", "1e-320", "1e308", "1e9"];
/// Values written both as `--flag -x` and `--flag=-x`.
const NEGATIVE: &[&str] = &["-inf", "-0", "-1e-320", "-1e308", "-1", "-2e-6"];

/// Options that take a value that is not a number (files, enums, addresses).
const NOT_NUMERIC: &[&str] = &[
    "scene",
    "csv",
    "plot",
    "out",
    "method",
    "profile",
    "param",
    "adjust",
    "maximize",
    "tcp",
    "port",
    "data",
    "params",
    "from-fit",
    "v0-profile",
    "track",
    "fault-listen",
    "listen",
    "record",
];

/// The one-line messages of exit 1 that are a computation's stated verdict
/// on a valid input (module docs); any other exit 1 fails the test.
const VERDICTS: &[&str] = &[
    "error: estimated error ",
    "error: no periodic regime after ",
    "error: the fixed-step method did not reach a steady state",
    "error: doubtful: ",
    "error: invalid estimate ",
    "error: the loop did not settle",
    "error: the run ended at ",
];

/// Longest line allowed on stdout or stderr.
const MAX_LINE: usize = 200;

/// Time bound of one run (generous: the machine is shared and noisy).
const BOUND: Duration = Duration::from_secs(40);

/// A run still going after this long that has printed on stdout has
/// answered (a stream, or rows as they are computed): it gets Ctrl-C.
const STREAM_AFTER: Duration = Duration::from_secs(10);

/// The dimensionless scene of the issue (`M`).
const M: &[&str] = &["--duz-rel", "0.5", "--ratio", "0.5", "--phi-deg", "0"];

/// One command (its `--help` path) and the base invocations its flags are
/// varied in: a flag is replaced in the first base that has it, or added to
/// the first base (after `insert_after`, if set, else at the end).
struct Entry {
    help: Vec<&'static str>,
    bases: Vec<Vec<String>>,
    /// Flags the help does not list (`device tune`'s trailing `tune` flags).
    extra: Vec<&'static str>,
    /// Where a flag the bases lack goes: after this argument.
    insert_after: Option<&'static str>,
}

fn v(parts: &[&[&str]]) -> Vec<String> {
    parts
        .iter()
        .flat_map(|p| p.iter().map(|s| s.to_string()))
        .collect()
}

/// `PHYS` with `--omega` in place of `--freq`.
fn phys_omega() -> Vec<String> {
    let mut p = v(&[PHYS]);
    let i = p.iter().position(|a| a == "--freq").unwrap();
    p[i] = "--omega".into();
    p[i + 1] = "2.5e5".into();
    p
}

/// A cheap `motion`: a massless body (the homogenised model only; periodic
/// at once), a tolerance its estimate meets.
const MOTION: &[&str] = &[
    "--mass",
    "0",
    "--force-amp-rel",
    "0.5",
    "--force-omega",
    "1e-3",
    "--tol",
    "1e-2",
];

/// [`MOTION`] for the SI scene (Ω = 1e3 rad/s against ω = 2.5e5 rad/s).
const MOTION_SI: &[&str] = &[
    "--mass",
    "0",
    "--force-amp-rel",
    "0.5",
    "--force-omega",
    "1e3",
    "--tol",
    "1e-2",
];

/// The dimensionless scene with `--dux-rel` and `--phi-rad`.
const M2: &[&str] = &["--duz-rel", "0.5", "--dux-rel", "0.3", "--phi-rad", "0.5"];

/// Every command with cheap base invocations (`{dir}` is a fresh directory
/// per run, `{file}` a regular file in it).
fn entries() -> Vec<Entry> {
    let scene_bases = |cmd: &str, tail: &[&str]| -> Vec<Vec<String>> {
        vec![
            v(&[&[cmd], PHYS, tail]),
            v(&[&[cmd], M, tail]),
            v(&[&[cmd], M2, tail]),
            [vec![cmd.to_string()], phys_omega(), v(&[tail])].concat(),
            v(&[&[cmd], M, &["--profile", "power", "--exponent", "3"], tail]),
        ]
    };
    let e = |help: &[&'static str], bases: Vec<Vec<String>>| Entry {
        help: help.to_vec(),
        bases,
        extra: Vec::new(),
        insert_after: None,
    };
    let device = |sub: &[&str]| v(&[&["device", "--sim"], sub]);
    vec![
        e(
            &["mu"],
            [
                scene_bases("mu", &["--v0", "0.01"]),
                vec![
                    v(&[&["mu"], M, &["--v-rel", "0.5"]]),
                    v(&[
                        &["mu"],
                        M,
                        &[
                            "--v0",
                            "0.1",
                            "--method",
                            "fixed",
                            "--steps-per-period",
                            "1000",
                        ],
                    ]),
                    v(&[&["mu"], PHYS, &["--v0", "0.01", "--tol", "1e-3"]]),
                ],
            ]
            .concat(),
        ),
        e(
            &["curve"],
            [
                scene_bases(
                    "curve",
                    &["--v-min", "-0.01", "--v-max", "0.01", "--points", "5"],
                ),
                vec![
                    v(&[
                        &["curve"],
                        M,
                        &["--v-rel-min", "-1", "--v-rel-max", "1", "--points", "5"],
                    ]),
                    v(&[
                        &["curve"],
                        M,
                        &["--v-min", "0.1", "--v-max", "0.2", "--points", "3"],
                        &["--method", "fixed", "--steps-per-period", "1000"],
                    ]),
                    v(&[
                        &["curve"],
                        M,
                        &[
                            "--v-min", "0.1", "--v-max", "0.2", "--points", "3", "--tol", "1e-3",
                        ],
                    ]),
                ],
            ]
            .concat(),
        ),
        e(&["static"], scene_bases("static", &[])[..4].to_vec()),
        e(&["classify"], scene_bases("classify", &[])),
        e(
            &["map"],
            vec![
                v(&[&[
                    "map",
                    "--duz-rel",
                    "0.5",
                    "--res",
                    "3",
                    "--csv",
                    "{dir}/m.csv",
                ]]),
                v(&[&[
                    "map",
                    "--duz-rel",
                    "0.5",
                    "--res",
                    "2",
                    "--v-rel",
                    "0.5",
                    "--csv",
                    "{dir}/m.csv",
                ]]),
                v(&[&[
                    "map",
                    "--duz-rel",
                    "0.5",
                    "--res",
                    "2",
                    "--v-rel",
                    "0.5",
                    "--method",
                    "fixed",
                    "--steps-per-period",
                    "1000",
                    "--csv",
                    "{dir}/m.csv",
                ]]),
                v(&[&[
                    "map",
                    "--duz-rel",
                    "0.5",
                    "--res",
                    "2",
                    "--v-rel",
                    "0.5",
                    "--tol",
                    "1e-3",
                    "--csv",
                    "{dir}/m.csv",
                ]]),
                v(&[&[
                    "map",
                    "--duz-rel",
                    "0.5",
                    "--res",
                    "2",
                    "--profile",
                    "power",
                    "--exponent",
                    "3",
                    "--csv",
                    "{dir}/m.csv",
                ]]),
            ],
        ),
        e(
            &["tune"],
            [
                scene_bases(
                    "tune",
                    &["--v0", "0.01", "--target-mu-rel", "0.5", "--adjust", "duz"],
                )[..4]
                    .to_vec(),
                vec![
                    v(&[
                        &["tune"],
                        PHYS,
                        &["--v0", "0.01", "--target-mu-rel", "0.5", "--adjust", "duz"],
                        &["--max-duz", "3e-6"],
                    ]),
                    v(&[
                        &["tune"],
                        PHYS,
                        &["--v0", "0.01", "--target-mu", "0.1", "--adjust", "dux"],
                        &["--max-dux", "1e-6"],
                    ]),
                    v(&[
                        &["tune"],
                        PHYS,
                        &["--maximize", "asymmetry", "--adjust", "phase"],
                        &["--liftoff-margin", "0.1"],
                    ]),
                ],
            ]
            .concat(),
        ),
        e(&["fit"], Vec::new()),
        e(
            &["load-line"],
            [
                scene_bases("load-line", &[]),
                vec![v(&[&["load-line"], PHYS, &["--points", "10"]])],
            ]
            .concat(),
        ),
        e(
            &["motion"],
            [
                scene_bases("motion", MOTION)[1..3].to_vec(),
                vec![
                    v(&[&["motion"], PHYS, MOTION_SI]),
                    [vec!["motion".to_string()], phys_omega(), v(&[MOTION_SI])].concat(),
                    v(&[&["motion"], M, &["--profile", "sphere"], MOTION]),
                    v(&[
                        &["motion"],
                        M,
                        MOTION,
                        &["--mass", "1", "--method", "homogenised"],
                    ]),
                ],
            ]
            .concat(),
        ),
        e(&["figures"], vec![v(&[&["figures", "--out", "{file}"]])]),
        e(
            &["bench", "work-precision"],
            vec![v(&[&["bench", "work-precision", "--out", "{file}"]])],
        ),
        e(
            &["bench", "methods"],
            vec![v(&[&["bench", "methods", "--out", "{file}"]])],
        ),
        e(
            &["bench", "stability"],
            vec![v(&[&["bench", "stability", "--out", "{file}"]])],
        ),
        e(
            &["bench", "dac"],
            vec![v(&[&["bench", "dac", "--out", "{file}"]])],
        ),
        e(
            &["bench", "motion"],
            vec![v(&[&["bench", "motion", "--out", "{file}"]])],
        ),
        e(
            &["sim-device"],
            vec![v(&[&[
                "sim-device",
                "--tcp",
                "127.0.0.1:0",
                "--seconds",
                "0.05",
            ]])],
        ),
        Entry {
            help: vec!["device"],
            bases: vec![device(&["info"])],
            extra: Vec::new(),
            insert_after: Some("--sim"),
        },
        e(
            &["device", "drive", "set"],
            vec![device(&[
                "drive",
                "set",
                "--open-loop",
                "--freq",
                "20000",
                "--amp-z",
                "2e-6",
                "--amp-x",
                "3e-7",
                "--offset-z",
                "4e-6",
                "--phase-deg",
                "40",
            ])],
        ),
        e(
            &["device", "scene", "set"],
            vec![device(&[
                "scene", "set", "--mu0", "0.3", "--kz", "1e7", "--kx", "1e7",
            ])],
        ),
        e(
            &["device", "predict"],
            vec![device(&["predict", "--v0", "0.004"])],
        ),
        e(
            &["device", "measure"],
            vec![device(&["measure", "--periods", "100"])],
        ),
        e(
            &["device", "watch"],
            vec![device(&["watch", "--periods", "100", "--count", "2"])],
        ),
        e(
            &["device", "sweep"],
            vec![device(&[
                "sweep",
                "--param",
                "phase-deg",
                "--from",
                "0",
                "--to",
                "90",
                "--points",
                "2",
                "--periods",
                "100",
                "--v0",
                "0.004",
                "--csv",
                "{dir}/sw.csv",
            ])],
        ),
        e(
            &["device", "control"],
            vec![device(&["control", "--target-mu", "0.1", "--v0", "0.004"])],
        ),
        e(
            &["device", "control-bench"],
            vec![device(&["control-bench"])],
        ),
        Entry {
            help: vec!["device", "tune"],
            bases: vec![
                device(&[
                    "tune",
                    "--v0",
                    "0.004",
                    "--target-mu",
                    "0.1",
                    "--adjust",
                    "duz",
                ]),
                device(&[
                    "tune",
                    "--v0",
                    "0.004",
                    "--target-mu-rel",
                    "0.3",
                    "--adjust",
                    "duz",
                    "--max-duz",
                    "3e-6",
                ]),
                device(&[
                    "tune",
                    "--v0",
                    "0.004",
                    "--target-mu-rel",
                    "0.3",
                    "--adjust",
                    "dux",
                    "--max-dux",
                    "1e-6",
                ]),
            ],
            extra: vec!["v0", "target-mu", "target-mu-rel", "max-duz", "max-dux"],
            insert_after: None,
        },
    ]
}

/// The value-taking options of `fricctl <path> --help`, without the known
/// non-numeric ones.
fn numeric_flags(path: &[&str]) -> Vec<String> {
    let out = fricctl()
        .args(path)
        .arg("--help")
        .output()
        .expect("fricctl --help");
    assert!(out.status.success(), "{path:?} --help");
    let help = String::from_utf8(out.stdout).unwrap();
    let mut flags = Vec::new();
    for line in help.lines() {
        let t = line.trim_start();
        let t = t
            .strip_prefix('-')
            .filter(|r| r.len() > 2 && r.as_bytes()[1] == b',')
            .map_or(t, |r| r[2..].trim_start());
        let Some(rest) = t.strip_prefix("--") else {
            continue;
        };
        let mut words = rest.split_whitespace();
        let name = words.next().unwrap_or("");
        let takes_value = words.next().is_some_and(|w| w.starts_with('<'));
        if takes_value && !NOT_NUMERIC.contains(&name) {
            flags.push(name.to_string());
        }
    }
    flags
}

/// How a value is written.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Form {
    /// `--flag value`
    Separate,
    /// `--flag=value`
    Joined,
}

/// One run of the generative test.
#[derive(Clone, Debug)]
struct Case {
    args: Vec<String>,
    /// The flags given (`--name`), for the "names a flag that was given" check.
    given: BTreeSet<String>,
    label: String,
}

/// The invocation with `--flag` set to `value` in `form` (replacing its
/// value where the base has it).
fn with_value(e: &Entry, flag: &str, value: &str, form: Form) -> Vec<String> {
    let long = format!("--{flag}");
    let base = e
        .bases
        .iter()
        .find(|b| b.contains(&long))
        .unwrap_or(&e.bases[0]);
    let pair = match form {
        Form::Separate => vec![long.clone(), value.to_string()],
        Form::Joined => vec![format!("{long}={value}")],
    };
    let mut args = Vec::new();
    let mut i = 0;
    let mut placed = false;
    while i < base.len() {
        if base[i] == long {
            args.extend(pair.iter().cloned());
            placed = true;
            i += 2;
            continue;
        }
        args.push(base[i].clone());
        if !placed && e.insert_after.is_some_and(|a| base[i] == a) {
            args.extend(pair.iter().cloned());
            placed = true;
        }
        i += 1;
    }
    if !placed {
        args.extend(pair);
    }
    args
}

fn cases() -> Vec<Case> {
    let mut out = Vec::new();
    for e in entries() {
        if e.bases.is_empty() {
            // No base: the command has no numeric flag (asserted).
            assert!(numeric_flags(&e.help).is_empty(), "{:?}", e.help);
            continue;
        }
        let mut flags = numeric_flags(&e.help);
        flags.extend(e.extra.iter().map(|s| s.to_string()));
        for flag in flags {
            let values = PLAIN
                .iter()
                .map(|x| (*x, Form::Separate))
                .chain(NEGATIVE.iter().map(|x| (*x, Form::Separate)))
                .chain(NEGATIVE.iter().map(|x| (*x, Form::Joined)));
            for (x, form) in values {
                let args = with_value(&e, &flag, x, form);
                let given = args
                    .iter()
                    .filter_map(|a| a.strip_prefix("--"))
                    .map(|a| format!("--{}", a.split('=').next().unwrap_or(a)))
                    .collect();
                let label = format!("{} --{flag} {x} ({form:?})", e.help.join(" "));
                out.push(Case { args, given, label });
            }
        }
    }
    out
}

/// What a run printed and how it ended.
struct Outcome {
    code: Option<i32>,
    stdout: String,
    stderr: String,
    /// Still running at the bound (then interrupted).
    streamed: bool,
    elapsed: Duration,
}

/// Runs `fricctl args` in `dir` (with its own virtual-device state `state`)
/// within [`BOUND`]; a run still going after [`STREAM_AFTER`] that has
/// printed on stdout has answered (a stream) and gets Ctrl-C (SIGINT), and
/// must then end within 5 s.
fn run(args: &[String], dir: &Path, state: &Path) -> Result<Outcome, String> {
    let t0 = Instant::now();
    let mut child = Command::new(env!("CARGO_BIN_EXE_fricctl"))
        .args(args)
        .current_dir(dir)
        .env("FRICCTL_SIM_STATE", state)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|e| e.to_string())?;
    let pipe = |mut r: Box<dyn Read + Send>| {
        let buf = Arc::new(Mutex::new(Vec::new()));
        let b = buf.clone();
        let h = std::thread::spawn(move || {
            let mut chunk = [0u8; 4096];
            while let Ok(n) = r.read(&mut chunk) {
                if n == 0 {
                    break;
                }
                b.lock().unwrap().extend_from_slice(&chunk[..n]);
            }
        });
        (buf, h)
    };
    let (out, ho) = pipe(Box::new(child.stdout.take().unwrap()));
    let (err, he) = pipe(Box::new(child.stderr.take().unwrap()));
    let mut streamed = false;
    let status = loop {
        if let Some(s) = child.try_wait().map_err(|e| e.to_string())? {
            break s;
        }
        let printed = !out.lock().unwrap().is_empty();
        if t0.elapsed() > BOUND && !printed {
            let _ = child.kill();
            let _ = child.wait();
            return Err(format!("no answer within {} s (killed)", BOUND.as_secs()));
        }
        if t0.elapsed() > STREAM_AFTER && printed {
            streamed = true;
            let _ = Command::new("kill")
                .args(["-INT", &child.id().to_string()])
                .status();
            let t1 = Instant::now();
            loop {
                if child.try_wait().map_err(|e| e.to_string())?.is_some() {
                    break;
                }
                if t1.elapsed() > Duration::from_secs(5) {
                    let _ = child.kill();
                    let _ = child.wait();
                    return Err("a stream that did not end within 5 s of Ctrl-C".into());
                }
                std::thread::sleep(Duration::from_millis(10));
            }
            break child.wait().map_err(|e| e.to_string())?;
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    let _ = (ho.join(), he.join());
    let text = |b: &Arc<Mutex<Vec<u8>>>| String::from_utf8_lossy(&b.lock().unwrap()).into_owned();
    Ok(Outcome {
        code: status.code(),
        stdout: text(&out),
        stderr: text(&err),
        streamed,
        elapsed: t0.elapsed(),
    })
}

/// Whether `text` has a `NaN` or `inf` token (a number that is not finite).
fn non_finite_token(text: &str) -> Option<String> {
    text.split(|c: char| !(c.is_ascii_alphanumeric() || c == '.'))
        .find(|t| {
            let l = t.to_ascii_lowercase();
            l == "nan" || l == "inf" || l == "infinity"
        })
        .map(str::to_string)
}

/// Judges one run; `Err` says what is wrong.
fn judge(c: &Case, o: &Outcome) -> Result<(), String> {
    for line in o.stdout.lines().chain(o.stderr.lines()) {
        if line.chars().count() > MAX_LINE {
            return Err(format!(
                "a line of {} characters: {}…",
                line.chars().count(),
                line.chars().take(120).collect::<String>()
            ));
        }
    }
    if let Some(t) = non_finite_token(&o.stdout) {
        return Err(format!("'{t}' on stdout (exit {:?})", o.code));
    }
    if o.streamed {
        return Ok(());
    }
    match o.code {
        Some(0) => Ok(()),
        Some(1) => {
            let err = o.stderr.trim_end();
            if err.lines().count() == 1 && VERDICTS.iter().any(|v| err.starts_with(v)) {
                Ok(())
            } else {
                Err(format!("exit 1, not a stated verdict: {err}"))
            }
        }
        Some(2) => {
            let err = o.stderr.trim_end();
            if err.lines().count() != 1 {
                return Err(format!("exit 2 with {} lines: {err}", err.lines().count()));
            }
            let msg = err
                .strip_prefix("error: ")
                .ok_or_else(|| format!("exit 2 without 'error: ': {err}"))?;
            let msg = msg.strip_prefix("device tune: ").unwrap_or(msg);
            let flag: String = msg
                .chars()
                .take_while(|ch| ch.is_ascii_alphanumeric() || *ch == '-')
                .collect();
            if !c.given.contains(&flag) {
                return Err(format!("exit 2 naming '{flag}', not a flag given: {err}"));
            }
            Ok(())
        }
        other => Err(format!(
            "exit {other:?} (wanted 0 or 2): {}",
            o.stderr.trim_end()
        )),
    }
}

/// A virtual-device state with the drive set and started, for the device
/// commands (each run gets its own copy).
fn device_state(dir: &Path) -> PathBuf {
    let state = dir.join("state.json");
    for args in [
        &[
            "device",
            "--sim",
            "drive",
            "set",
            "--open-loop",
            "--freq",
            "20000",
            "--amp-z",
            "2e-6",
            "--amp-x",
            "3e-7",
            "--offset-z",
            "4e-6",
            "--phase-deg",
            "40",
        ][..],
        &["device", "--sim", "start"][..],
    ] {
        let out = fricctl()
            .args(args)
            .env("FRICCTL_SIM_STATE", &state)
            .output()
            .unwrap();
        assert!(out.status.success(), "{args:?}");
    }
    state
}

/// Every command × numeric flag × hostile value: answered within the bound,
/// exit 0 with finite output or exit 2 naming a flag that was given, no line
/// over 200 characters. Prints the number of combinations tried.
#[test]
fn every_numeric_flag_of_every_command_refuses_or_answers() {
    let t0 = Instant::now();
    let root = tempfile::tempdir().unwrap();
    let template = device_state(root.path());
    let all = cases();
    let total = all.len();
    let flags: BTreeSet<(String, String)> = all
        .iter()
        .map(|c| {
            let mut w = c.label.split(" --");
            (
                w.next().unwrap_or("").to_string(),
                w.next()
                    .unwrap_or("")
                    .split(' ')
                    .next()
                    .unwrap_or("")
                    .to_string(),
            )
        })
        .collect();
    let queue = Arc::new(Mutex::new(all.into_iter().enumerate().collect::<Vec<_>>()));
    let failures = Arc::new(Mutex::new(Vec::<String>::new()));
    let slowest = Arc::new(Mutex::new((Duration::ZERO, String::new())));
    let counts = Arc::new(Mutex::new(
        std::collections::BTreeMap::<String, usize>::new(),
    ));
    let workers = std::thread::available_parallelism()
        .map_or(2, |n| n.get())
        .clamp(2, 4);
    let handles: Vec<_> = (0..workers)
        .map(|_| {
            let (queue, failures, slowest, counts) = (
                queue.clone(),
                failures.clone(),
                slowest.clone(),
                counts.clone(),
            );
            let (root, template) = (root.path().to_path_buf(), template.clone());
            std::thread::spawn(move || loop {
                let Some((i, c)) = queue.lock().unwrap().pop() else {
                    break;
                };
                let dir = root.join(format!("run{i}"));
                std::fs::create_dir_all(&dir).unwrap();
                let file = dir.join("plain-file");
                std::fs::write(&file, "").unwrap();
                let state = dir.join("state.json");
                std::fs::copy(&template, &state).unwrap();
                let args: Vec<String> = c
                    .args
                    .iter()
                    .map(|a| {
                        a.replace("{file}", file.to_str().unwrap())
                            .replace("{dir}", dir.to_str().unwrap())
                    })
                    .collect();
                let verdict = run(&args, &dir, &state).and_then(|o| {
                    {
                        let mut s = slowest.lock().unwrap();
                        if o.elapsed > s.0 {
                            *s = (o.elapsed, c.label.clone());
                        }
                        let kind = match o.code {
                            _ if o.streamed => "a stream, ended by Ctrl-C".to_string(),
                            Some(1) => format!("exit 1 ({})", c.label),
                            Some(c) => format!("exit {c}"),
                            None => "killed".to_string(),
                        };
                        *counts.lock().unwrap().entry(kind).or_default() += 1;
                    }
                    judge(&c, &o)
                });
                if let Err(why) = verdict {
                    failures.lock().unwrap().push(format!(
                        "{}: {why}\n    fricctl {}",
                        c.label,
                        args.join(" ")
                    ));
                }
                let _ = std::fs::remove_dir_all(&dir);
            })
        })
        .collect();
    for h in handles {
        h.join().unwrap();
    }
    let failures = failures.lock().unwrap();
    let slow = slowest.lock().unwrap();
    let kinds: Vec<String> = counts
        .lock()
        .unwrap()
        .iter()
        .map(|(k, n)| format!("{n} {k}"))
        .collect();
    eprintln!(
        "bad input: {total} command × flag × value combinations ({} command/flag pairs, {} threads), {:.0} s; slowest run {:.1} s ({})\n  {}",
        flags.len(),
        workers,
        t0.elapsed().as_secs_f64(),
        slow.0.as_secs_f64(),
        slow.1,
        kinds.join("\n  ")
    );
    assert!(
        failures.is_empty(),
        "{} of {total} runs failed:\n{}",
        failures.len(),
        failures.join("\n")
    );
}

// ---------------------------------------------------------------------------
// Regressions: each case of issue 28 (and issue 24 §9), by its message.
// ---------------------------------------------------------------------------

/// The physical scene `P` of the issue.
fn p(extra: &[&str]) -> Vec<String> {
    v(&[PHYS, extra])
}

/// The dimensionless scene `M` of the issue.
fn m(extra: &[&str]) -> Vec<String> {
    v(&[M, extra])
}

/// Runs `fricctl cmd args`, bounded by `limit`.
fn bounded(cmd: &[&str], args: &[String], limit: Duration) -> Outcome {
    let dir = tempfile::tempdir().unwrap();
    let all: Vec<String> = cmd
        .iter()
        .map(|s| s.to_string())
        .chain(args.iter().cloned())
        .collect();
    let o = run(&all, dir.path(), &dir.path().join("state.json"))
        .unwrap_or_else(|e| panic!("fricctl {}: {e}", all.join(" ")));
    assert!(
        o.elapsed < limit,
        "fricctl {}: {:.1} s (bound {} s)",
        all.join(" "),
        o.elapsed.as_secs_f64(),
        limit.as_secs()
    );
    o
}

/// Bad input: exit 2, nothing on stdout, one stderr line `error: {flag}: …`
/// containing `text`, within 20 s. Returns the line.
fn refused(cmd: &[&str], args: &[String], flag: &str, text: &str) -> String {
    let o = bounded(cmd, args, Duration::from_secs(20));
    let err = o.stderr.trim_end().to_string();
    let shown = format!("fricctl {} {}: {err}", cmd.join(" "), args.join(" "));
    assert_eq!(o.code, Some(2), "{shown}");
    assert!(o.stdout.is_empty(), "{shown}");
    assert_eq!(err.lines().count(), 1, "{shown}");
    assert!(err.starts_with(&format!("error: {flag}: ")), "{shown}");
    assert!(err.contains(text), "{shown} (wanted {text})");
    assert!(err.chars().count() <= MAX_LINE, "{shown}");
    err
}

/// Issue 28 §1–3 and issue 24 §9: the inputs that made `motion` run for
/// minutes (or print NaN with exit 0) are refused at once, by name, with the
/// estimated cost where the cost is the reason.
#[test]
fn motion_hangs_are_refusals() {
    let base = |extra: &[&str]| m(&[&["--mass", "1", "--force-amp-rel", "0.5"], extra].concat());
    refused(
        &["motion"],
        &base(&["--force-omega", "1e-320"]),
        "--force-omega",
        "must be ≥ 1e-100 (got 1e-320)",
    );
    // Ω/ω = 1e-12: the resolved model that auto needs would take 5.8e14 steps.
    refused(
        &["motion"],
        &base(&["--force-omega", "1e-12"]),
        "--force-omega",
        "auto needs the resolved model (homogenised estimate 1.32e1 v_ref > --tol), which takes ≥ 5.76e14 steps (work bound 1e9)",
    );
    for k in ["1e308", "1e50"] {
        refused(
            &["motion"],
            &base(&["--force-omega", "1e-3", "--spring", k]),
            "--spring",
            if k == "1e308" {
                "must be ≤ 1e100 (got 1e308)"
            } else {
                "steps per load period"
            },
        );
    }
    for f in ["100", "1e3", "1e20", "1e308"] {
        let args = m(&["--mass", "1", "--force-amp-rel", f, "--force-omega", "1e-3"]);
        refused(
            &["motion"],
            &args,
            "--force-amp-rel",
            &format!("must be ≤ 10 (got {f}; ten times the contact's largest force μ0·F̄z)"),
        );
    }
    // Issue 24 §9: 1.6e8 load periods.
    refused(
        &["motion"],
        &m(&[
            "--mass",
            "1e4",
            "--force-amp-rel",
            "0.5",
            "--force-omega",
            "1e-3",
            "--duration",
            "1e12",
        ]),
        "--duration",
        "the homogenised model takes ≥ 1.22e11 steps (work bound 1e8); give a shorter --duration",
    );
}

/// A light body whose oscillation on the contact the resolved model cannot
/// resolve is refused by name, not integrated into NaN.
#[test]
fn motion_unresolvable_body_is_refused() {
    refused(
        &["motion"],
        &m(&[
            "--mass",
            "1e-9",
            "--force-amp-rel",
            "0.5",
            "--force-omega",
            "1e-3",
            "--method",
            "resolved",
        ]),
        "--mass",
        "the resolved model needs 9.93e4 steps per period for this body (Mω²/k_x = 1e-9, K/k_x = 0; max 1024)",
    );
}

/// Issue 28 §4: a phase range of 1e300° (and any span beyond ten turns) is
/// refused before the map is drawn.
#[test]
fn map_phase_range_is_bounded() {
    let dir = tempfile::tempdir().unwrap();
    let plot = dir.path().join("m.png");
    let map = |extra: &[&str]| {
        v(&[
            &["--duz-rel", "0.5", "--res", "5", "--phi-min-deg", "0"],
            extra,
            &["--plot", plot.to_str().unwrap()],
        ])
    };
    refused(
        &["map"],
        &map(&["--phi-max-deg", "1e300"]),
        "--phi-max-deg",
        "must be ≤ 572957 (got 1e300; ≈ 10⁴ rad; give the phase within a turn)",
    );
    refused(
        &["map"],
        &map(&["--phi-max-deg", "1e5"]),
        "--phi-max-deg",
        "exceeds ten turns",
    );
    assert!(!plot.exists());
}

/// Issue 28 §5: `--points 1e9` is refused before anything is allocated or
/// the device is asked.
#[test]
fn sweep_points_are_capped() {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("sw.csv");
    refused(
        &["device", "--sim", "sweep"],
        &v(&[&[
            "--param",
            "phase-deg",
            "--from",
            "0",
            "--to",
            "180",
            "--points",
            "1e9",
            "--periods",
            "10",
            "--v0",
            "0.004",
            "--csv",
            csv.to_str().unwrap(),
        ]]),
        "--points",
        "must be ≤ 10000 (got 1e9; sweep in several files for more)",
    );
    assert!(!csv.exists());
}

/// Issue 28 §6: negative values reach the flag's check in both forms.
#[test]
fn negative_values_are_values() {
    for tol in [&["--tol", "-1"][..], &["--tol=-1"][..]] {
        refused(
            &["mu"],
            &p(&[&["--v0", "0.01"], tol].concat()),
            "--tol",
            "must be > 0 (got -1)",
        );
    }
    let root = tempfile::tempdir().unwrap();
    let state = device_state(root.path());
    for amp in [&["--amp-z", "-2e-6"][..], &["--amp-z=-2e-6"][..]] {
        let args = v(&[
            &[
                "device",
                "--sim",
                "drive",
                "set",
                "--open-loop",
                "--freq",
                "20000",
            ],
            amp,
            &["--amp-x", "3e-7", "--offset-z", "4e-6"],
        ]);
        let o = run(&args, root.path(), &state).unwrap();
        assert_eq!(o.code, Some(2), "{args:?}: {}", o.stderr);
        assert!(
            o.stderr
                .starts_with("error: --amp-z: refused by the device: allowed range [0, "),
            "{}",
            o.stderr
        );
    }
}

/// Issue 28 §7: a flag given twice says so.
#[test]
fn a_flag_given_twice_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("s.toml");
    std::fs::write(&scene, "mu0 = 0.3\n").unwrap();
    let s = scene.to_str().unwrap();
    for (cmd, args, flag) in [
        (&["mu"][..], p(&["--v0", "0.01", "--v0", "0.02"]), "--v0"),
        (
            &["mu"][..],
            p(&["--v0", "0.01", "--json", "--json"]),
            "--json",
        ),
        (
            &["motion"][..],
            m(&[
                "--mass",
                "1",
                "--mass",
                "2",
                "--force-amp-rel",
                "0.5",
                "--force-omega",
                "1e-3",
            ]),
            "--mass",
        ),
        (
            &["static"][..],
            v(&[&["--scene", s, "--scene", s]]),
            "--scene",
        ),
        (&["static"][..], p(&["--freq", "1e3"]), "--freq"),
    ] {
        refused(cmd, &args, flag, "given twice (give it once)");
    }
}

/// Issue 28 §8–9 and issue 24 §9: finite values are refused by the limit
/// they exceed, echoed as typed, and every number in a message is short.
#[test]
fn limits_are_named_and_values_echoed_short() {
    refused(
        &["mu"],
        &p(&["--v0", "1e308"]),
        "--v0",
        "must be of magnitude ≤ 1e100 (got 1e308)",
    );
    refused(
        &["curve"],
        &p(&[
            "--v-rel-min",
            "-1e308",
            "--v-rel-max",
            "1e308",
            "--points",
            "3",
        ]),
        "--v-rel-min",
        "(got -1e308)",
    );
    let tune = |extra: &[&str]| p(&[&["--v0", "0.01", "--adjust", "duz"], extra].concat());
    refused(
        &["tune"],
        &tune(&["--target-mu", "1e308"]),
        "--target-mu",
        "(got 1e308)",
    );
    refused(
        &["tune"],
        &tune(&["--target-mu", "0.5"]),
        "--target-mu",
        "0.5 must lie strictly inside (−0.3, 0.3)",
    );
    refused(
        &["tune"],
        &tune(&["--target-mu-rel", "1e300"]),
        "--target-mu-rel",
        "must be < 1 (got 1e300; mu/mu0 lies strictly inside (−1, 1)",
    );
    refused(
        &["tune"],
        &tune(&["--target-mu-rel", "0.5", "--max-duz", "1e308"]),
        "--max-duz",
        "(got 1e308)",
    );
    refused(
        &["tune"],
        &tune(&["--target-mu-rel", "0.5", "--max-duz", "1e-5"]),
        "--max-duz",
        "1e-5 m is above the lift-off limit (1 − liftoff-margin)·uz0 = 4.75e-6 m",
    );
    let tp = |v0: &str| p(&["--v0", v0, "--target-mu-rel", "0.5", "--adjust", "duz"]);
    refused(&["tune"], &tp("1e-300"), "--v0", "(got 1e-300)");
    refused(&["tune"], &tp("1e300"), "--v0", "(got 1e300)");
    refused(&["mu"], &p(&["--v0", "1e-320"]), "--v0", "(got 1e-320)");
    refused(
        &["mu"],
        &v(&[&["--v0", "0.01", "--mu0", "1e308"], &PHYS[2..]]),
        "--mu0",
        "must be ≤ 1e100 (got 1e308)",
    );
    let dir = tempfile::tempdir().unwrap();
    let plot = dir.path().join("m.png");
    refused(
        &["map"],
        &v(&[&[
            "--duz-rel",
            "0.5",
            "--res",
            "3",
            "--ratio-max",
            "1e308",
            "--plot",
            plot.to_str().unwrap(),
        ]]),
        "--ratio-max",
        "(got 1e308)",
    );
    // A tiny valid velocity is written short in the text output too.
    let o = bounded(&["mu"], &m(&["--v0", "1e-90"]), Duration::from_secs(20));
    assert_eq!(o.code, Some(0), "{}", o.stderr);
    assert!(
        o.stdout.contains("v0           1e-90 ωW0\n"),
        "{}",
        o.stdout
    );
    assert!(o.stdout.lines().all(|l| l.len() <= 80), "{}", o.stdout);
}

/// Issue 28 §10–11: errors name the flag that was given, and a drive beyond
/// the solvers' reach is bad input (exit 2), not a leaked internal failure.
#[test]
fn errors_name_the_flag_given() {
    refused(
        &["static"],
        &v(&[&["--duz-rel", "1e-320", "--ratio", "2"]]),
        "--duz-rel",
        "(got 1e-320)",
    );
    refused(
        &["tune"],
        &v(&[&[
            "--duz-rel",
            "1.5",
            "--dux-rel",
            "0.5",
            "--v0",
            "0.1",
            "--target-mu-rel",
            "0.5",
            "--adjust",
            "phase",
        ]]),
        "--duz-rel",
        "must be < 1 for this command",
    );
    refused(
        &["static"],
        &v(&[&["--duz-rel", "0.5", "--ratio", "1e308"]]),
        "--ratio",
        "must be ≤ 1e100 (got 1e308)",
    );
    // b = 5e9: beyond 1 + b ≤ 1e7, where the exact solver's precision part
    // of its bound, 1e-9·(1 + b), exceeds 1 % of μ0.
    refused(
        &["static"],
        &v(&[&["--duz-rel", "0.5", "--ratio", "1e10"]]),
        "--ratio",
        "gives kx·dux/(mu0·kz·uz0) = 5.000e9; the solvers resolve",
    );
    for cmd in ["static", "classify"] {
        refused(
            &[cmd],
            &v(&[&["--duz-rel", "1e308", "--dux-rel", "0.5"]]),
            "--duz-rel",
            "must be ≤ 1e100 (got 1e308)",
        );
        refused(
            &[cmd],
            &v(&[&["--duz-rel", "1e50", "--dux-rel", "0.5"]]),
            "--duz-rel",
            "gives duz/uz0 = 1.000e50",
        );
    }
    // A scene file's value is named by --scene and its key.
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("s.toml");
    std::fs::write(
        &f,
        "mu0 = 0.3\nkz = 2e6\nkx = 1.5e6\nuz0 = 5e-6\nduz = 2e-6\ndux = 1e60\nfreq = 4e4\n",
    )
    .unwrap();
    refused(
        &["static"],
        &v(&[&["--scene", f.to_str().unwrap()]]),
        "--scene",
        "dux",
    );
}

/// Issue 28 §12: a directory and a meaningless model column are named.
#[test]
fn fit_names_what_is_wrong() {
    let dir = tempfile::tempdir().unwrap();
    refused(
        &["fit"],
        &v(&[&["--data", dir.path().to_str().unwrap()]]),
        "--data",
        "is a directory",
    );
    let header = "param,value,freq_hz,amp_z,amp_x,offset_z,phi_deg,v0,model_mu0,model_kz,model_kx,measured_mu,std_error,predicted_mu,valid,reasons";
    let row = |phi: &str| {
        format!("phase-deg,{phi},20000,2e-6,3e-7,4e-6,{phi},0.004,-0.3,1e7,1e7,0.1,1e-6,0.1,true,")
    };
    let f = dir.path().join("sw.csv");
    std::fs::write(
        &f,
        format!("{header}\n{}\n{}\n{}\n", row("0"), row("45"), row("90")),
    )
    .unwrap();
    refused(
        &["fit"],
        &v(&[&["--data", f.to_str().unwrap()]]),
        "--data",
        "line 2: model_mu0 must be > 0 (got -0.3)",
    );
}

/// A sweep file of `fricctl fit` on PHYS's drive at four phases whose
/// measured μ is the model's own (`fricctl mu`, exact), σ = 1e-3; `edit`
/// changes a row's fields before it is written.
fn model_sweep(path: &Path, edit: impl Fn(usize, &mut Vec<String>)) {
    let header = "param,value,freq_hz,amp_z,amp_x,offset_z,phi_deg,v0,model_mu0,model_kz,model_kx,measured_mu,std_error,predicted_mu,valid,reasons";
    let mut csv = format!("{header}\n");
    for (i, phi) in ["0", "60", "120", "180"].into_iter().enumerate() {
        let m = common::cli::json(
            &[
                &["mu"][..],
                &PHYS[..PHYS.len() - 2],
                &["--phi-deg", phi, "--v0", "0.01", "--method", "exact"],
            ]
            .concat(),
        );
        let mu = m["mu"].as_f64().unwrap().to_string();
        let mut row: Vec<String> = [
            "phase-deg",
            phi,
            "40000",
            "2e-6",
            "0.7e-6",
            "5e-6",
            phi,
            "0.01",
            "0.3",
            "2e6",
            "1.5e6",
            &mu,
            "0.001",
            &mu,
            "true",
            "",
        ]
        .iter()
        .map(|s| s.to_string())
        .collect();
        edit(i, &mut row);
        csv += &format!("{}\n", row.join(","));
    }
    std::fs::write(path, csv).unwrap();
}

/// Issue 41 §5: a row of absurd values is refused by its line and column
/// (v0 1e300 was fitted with exit 0 and χ²/ν 3.8e7; σ 1e-300 overflowed the
/// normal matrix and was called "not identifiable"); a fit whose χ² its
/// distribution does not reach prints its result and exits 1 with the
/// verdict (analysis::fit, "Goodness of fit"); one the model describes
/// exits 0 and prints p(χ²).
#[test]
fn fit_refuses_absurd_rows_and_flags_a_chi2_beyond_its_quantile() {
    const V0: usize = 7;
    const MEASURED: usize = 11;
    const STD_ERROR: usize = 12;
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("sw.csv");
    let data = |edit: &dyn Fn(usize, &mut Vec<String>)| {
        model_sweep(&f, edit);
        v(&[&["--params", "mu0", "--data", f.to_str().unwrap()]])
    };
    let at = |row: usize, col: usize, val: &'static str| {
        move |i: usize, r: &mut Vec<String>| {
            if i == row {
                r[col] = val.to_string();
            }
        }
    };
    refused(
        &["fit"],
        &data(&at(2, V0, "1e300")),
        "--data",
        "line 4: v0 must be of magnitude ≤ 1e100 (got 1e300)",
    );
    refused(
        &["fit"],
        &data(&at(1, STD_ERROR, "1e-300")),
        "--data",
        "line 3: std_error must be 0 or of magnitude ≥ 1e-100 (got 1e-300)",
    );
    refused(
        &["fit"],
        &data(&at(1, STD_ERROR, "1e-20")),
        "--data",
        "line 3: std_error 1e-20 is below what the model resolves (3e-13 = 1e-12·model_mu0; 0 = unknown)",
    );
    // The model's own μ: χ² ≈ 0, p ≈ 1, exit 0.
    let args = data(&|_, _| {});
    let o = bounded(&["fit"], &args, Duration::from_secs(60));
    assert_eq!(o.code, Some(0), "{}", o.stderr);
    assert!(o.stdout.contains("p(χ²)        1 "), "{}", o.stdout);
    // One row 0.05 off at σ = 1e-3: χ² ≈ 0.05²/σ²·(1 − 1/4) = 1875 on 3
    // degrees of freedom, whose 1 − 1e-6 quantile is 30.66: exit 1 after
    // the result (text, and JSON with the verdict in `doubtful`).
    let off = |i: usize, r: &mut Vec<String>| {
        if i == 1 {
            let m: f64 = r[MEASURED].parse().unwrap();
            r[MEASURED] = (m + 0.05).to_string();
        }
    };
    let args = data(&off);
    let o = bounded(&["fit"], &args, Duration::from_secs(60));
    assert_eq!(o.code, Some(1), "{}", o.stderr);
    assert!(o.stdout.starts_with("μ0 "), "{}", o.stdout);
    let err = o.stderr.trim_end();
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.starts_with("error: doubtful: chi2 ")
            && err.contains(" on 3 degrees of freedom ")
            && err.contains("exceeds its 0.999999 quantile 30.66: the model does not describe the data within their standard errors"),
        "{err}"
    );
    let mut json_args = args.clone();
    json_args.push("--json".into());
    let o = bounded(&["fit"], &json_args, Duration::from_secs(60));
    assert_eq!(o.code, Some(1), "{}", o.stderr);
    let j: serde_json::Value = serde_json::from_str(&o.stdout).unwrap();
    let chi2 = j["chi2"].as_f64().unwrap();
    // Between the outlier's share (0.05·3/4/σ)² and its whole (0.05/σ)².
    assert!((1406.0..2500.0).contains(&chi2), "{chi2}");
    assert!(j["chi2_p_value"].as_f64().unwrap() < 1e-6);
    assert_eq!(
        format!("error: {}", j["doubtful"].as_str().unwrap()),
        err,
        "the JSON's verdict is the stderr line"
    );
    // Unweighted (no standard errors): no scale to judge χ² by, exit 0.
    let args = data(&|i, r| {
        off(i, r);
        r[STD_ERROR] = "0".into();
    });
    let o = bounded(&["fit"], &args, Duration::from_secs(60));
    assert_eq!(o.code, Some(0), "{}", o.stderr);
    assert!(!o.stdout.contains("p(χ²)"), "{}", o.stdout);
}

/// Issue 28 §13: a flag that would be ignored is refused.
#[test]
fn stray_steps_per_period_is_refused() {
    refused(
        &["mu"],
        &p(&["--v0", "0.01", "--steps-per-period", "100"]),
        "--steps-per-period",
        "only with --method fixed",
    );
    // With --method fixed it is used.
    let o = bounded(
        &["mu"],
        &p(&[
            "--v0",
            "0.01",
            "--method",
            "fixed",
            "--steps-per-period",
            "2000",
            "--json",
        ]),
        Duration::from_secs(60),
    );
    assert_eq!(o.code, Some(0), "{}", o.stderr);
    assert!(
        o.stdout.contains("\"steps_per_period\": 2000"),
        "{}",
        o.stdout
    );
}

/// Issue 28 §14: `map --csv` alone is a map; values are checked before the
/// missing output.
#[test]
fn map_csv_alone_and_values_first() {
    refused(
        &["map"],
        &v(&[&["--duz-rel", "NaN", "--res", "5"]]),
        "--duz-rel",
        "'NaN' is not a number",
    );
    refused(
        &["map"],
        &v(&[&["--duz-rel", "0.5", "--res", "5"]]),
        "--plot",
        "missing (give --plot FILE, --csv FILE or both)",
    );
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("m.csv");
    let o = bounded(
        &["map"],
        &v(&[&[
            "--duz-rel",
            "0.5",
            "--res",
            "4",
            "--csv",
            csv.to_str().unwrap(),
        ]]),
        Duration::from_secs(60),
    );
    assert_eq!(o.code, Some(0), "{}", o.stderr);
    let text = std::fs::read_to_string(&csv).unwrap();
    // A header and 4 × 4 cells.
    assert_eq!(text.lines().count(), 17, "{text}");
}

/// Issue 28 §15: subnormal and absurd scene inputs are refused by the one
/// domain check, with the same words for a flag and for a scene file.
#[test]
fn scene_domain_is_one_check() {
    refused(
        &["mu"],
        &p(&["--v0", "0.01", "--phi-rad", "1e-320"])[..]
            .iter()
            .filter(|a| *a != "--phi-deg" && *a != "50")
            .cloned()
            .collect::<Vec<_>>(),
        "--phi-rad",
        "must be 0 or of magnitude ≥ 1e-100 (got 1e-320)",
    );
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("s.toml");
    for (key, x, flag_text) in [
        ("kz", "1e-320", "kz must be ≥ 1e-100 (got 1e-320)"),
        ("mu0", "1e308", "mu0 must be ≤ 1e100 (got 1e308)"),
    ] {
        let mut text = String::new();
        for (k, val) in [
            ("mu0", "0.3"),
            ("kz", "2e6"),
            ("kx", "1.5e6"),
            ("uz0", "5e-6"),
            ("duz", "2e-6"),
            ("dux", "7e-7"),
            ("freq", "4e4"),
        ] {
            text += &format!("{k} = {}\n", if k == key { x } else { val });
        }
        std::fs::write(&f, text).unwrap();
        refused(
            &["mu"],
            &v(&[&["--scene", f.to_str().unwrap(), "--v0", "0.01"]]),
            "--scene",
            flag_text,
        );
        // The flag says the same.
        let line = refused(
            &["mu"],
            &v(&[
                &["--scene", f.to_str().unwrap(), "--v0", "0.01"],
                &[&format!("--{key}"), x],
            ]),
            &format!("--{key}"),
            &flag_text[key.len() + 1..],
        );
        assert!(line.ends_with(&flag_text[key.len()..]), "{line}");
    }
}

/// Issue 28 §16: the virtual device's flags are checked before it serves.
#[test]
fn sim_device_flags_are_checked_before_serving() {
    for (args, flag, text) in [
        (&["--tcp", "notanaddr"][..], "--tcp", "is not HOST:PORT"),
        (
            &["--tcp", "127.0.0.1:0", "--plant-kz", "1e-320"][..],
            "--plant-kz",
            "must be ≥ 1.2e-38 (got 1e-320)",
        ),
        (
            &["--tcp", "127.0.0.1:0", "--v0", "1e308"][..],
            "--v0",
            "must be ≤ 1000 (got 1e308; the device's velocity limit)",
        ),
        (
            &["--tcp", "127.0.0.1:0", "--plant-mu0-drift", "1e308"][..],
            "--plant-mu0-drift",
            "(got 1e308)",
        ),
    ] {
        refused(&["sim-device"], &v(&[args]), flag, text);
    }
}

/// Issue 28 §17: no negative zero in `load-line`'s output.
#[test]
fn load_line_prints_no_negative_zero() {
    let o = bounded(
        &["load-line"],
        &v(&[&["--duz-rel", "1", "--dux-rel", "0"]]),
        Duration::from_secs(60),
    );
    assert_eq!(o.code, Some(0), "{}", o.stderr);
    assert!(
        o.stdout.contains("stall force, forward    0.000000 μ0·F̄z"),
        "{}",
        o.stdout
    );
    assert!(!o.stdout.contains("-0.0"), "{}", o.stdout);
}

/// Issue 24 §9: `tune`'s "infeasible" refusal (every drive an actuator:
/// exit 2, naming --maximize) — checked against `classify` at every 15° —
/// and the exit statuses in `--help`.
#[test]
fn tune_infeasible_and_exit_statuses() {
    // a = 0.5, b = 1: c + c' = |b e^{iφ} + a| + |b e^{iφ} − a| ≥ 2√(b² + a²)
    // ... > 2 for every φ, so the static interval is empty everywhere.
    for deg in (0..360).step_by(15) {
        let o = bounded(
            &["classify"],
            &v(&[&[
                "--duz-rel",
                "0.5",
                "--ratio",
                "2",
                "--phi-deg",
                &deg.to_string(),
                "--json",
            ]]),
            Duration::from_secs(20),
        );
        assert!(
            o.stdout.contains("\"regime\": \"actuator\""),
            "{deg}°: {}",
            o.stdout
        );
    }
    refused(
        &["tune"],
        &v(&[&[
            "--duz-rel",
            "0.5",
            "--ratio",
            "2",
            "--maximize",
            "asymmetry",
            "--adjust",
            "phase",
        ]]),
        "--maximize",
        "every drive with phase in its range is an actuator",
    );
    let help = bounded(&["tune"], &v(&[&["--help"]]), Duration::from_secs(20)).stdout;
    assert!(help.contains("Exit status: 0 a solution"), "{help}");
    assert!(
        help.contains("1 the result is printed but doubtful"),
        "{help}"
    );
    let top = bounded(&[], &v(&[&["--help"]]), Duration::from_secs(20)).stdout;
    assert!(
        top.contains("2 bad input (one line naming the flag)"),
        "{top}"
    );
}
