//! Output files: every file named by a flag (`--csv`, `--out FILE`,
//! `--plot`) follows one overwrite policy — an existing file is refused
//! before any work unless `--force`, which replaces it and says so — and a
//! file written by temp-and-rename gets the mode `File::create` would give
//! (0666 less the umask), or keeps the mode of the file it replaces.

use std::os::unix::fs::PermissionsExt;
use std::path::Path;
use std::process::Output;

mod common;

use common::cli::{json, PHYS};

/// Runs `fricctl args` under `umask` (a shell sets it, then `exec`s).
fn under_umask(umask: &str, args: &[String]) -> Output {
    let bin = assert_cmd::cargo::cargo_bin("fricctl");
    let mut cmd = std::process::Command::new("sh");
    cmd.arg("-c")
        .arg(format!("umask {umask}; exec \"$0\" \"$@\""))
        .arg(bin)
        .args(args);
    cmd.output().unwrap()
}

fn mode(p: &Path) -> u32 {
    std::fs::metadata(p).unwrap().permissions().mode() & 0o777
}

/// A sweep file for `fit` whose rows are the model's own μ (from `fricctl mu`).
fn sweep_file(p: &Path) {
    let mut csv = String::from(
        "param,value,freq_hz,amp_z,amp_x,offset_z,phi_deg,v0,model_mu0,model_kz,model_kx,measured_mu,std_error,predicted_mu,valid,reasons\n",
    );
    for phi in [0.0, 90.0, 180.0] {
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
    std::fs::write(p, csv).unwrap();
}

/// Each command that writes a file, with `FILE` where the file goes.
fn writers(dir: &Path) -> Vec<(&'static str, Vec<String>)> {
    let data = dir.join("sweep-data.csv");
    sweep_file(&data);
    let s = |v: &[&str]| v.iter().map(|x| x.to_string()).collect::<Vec<_>>();
    let mut fit = s(&["fit", "--params", "mu0", "--data"]);
    fit.push(data.display().to_string());
    fit.extend(s(&["--out", "FILE"]));
    vec![
        (
            "--csv",
            s(&[
                "curve",
                "--duz-rel",
                "0.5",
                "--ratio",
                "2",
                "--phi-deg",
                "45",
                "--v-rel-min",
                "0.1",
                "--v-rel-max",
                "2",
                "--points",
                "5",
                "--csv",
                "FILE",
            ]),
        ),
        (
            "--csv",
            s(&["map", "--duz-rel", "0.5", "--res", "4", "--csv", "FILE"]),
        ),
        (
            "--csv",
            s(&[
                "load-line",
                "--duz-rel",
                "0.5",
                "--ratio",
                "2",
                "--phi-deg",
                "0",
                "--points",
                "3",
                "--csv",
                "FILE",
            ]),
        ),
        (
            "--csv",
            s(&[
                "motion",
                "--duz-rel",
                "0.5",
                "--ratio",
                "0.5",
                "--phi-deg",
                "0",
                "--mass",
                "0",
                "--force-amp-rel",
                "0.8",
                "--force-omega",
                "1e-3",
                "--spring",
                "1e-3",
                "--tol",
                "5e-2",
                "--csv",
                "FILE",
            ]),
        ),
        ("--out", fit),
        (
            "--plot",
            s(&[
                "map",
                "--duz-rel",
                "0.5",
                "--res",
                "4",
                "--plot",
                "FILE.svg",
            ]),
        ),
    ]
}

fn with_file(args: &[String], file: &Path) -> (Vec<String>, std::path::PathBuf) {
    let mut path = file.to_path_buf();
    let args = args
        .iter()
        .map(|a| match a.as_str() {
            "FILE" => file.display().to_string(),
            "FILE.svg" => {
                path = file.with_extension("svg");
                path.display().to_string()
            }
            _ => a.clone(),
        })
        .collect();
    (args, path)
}

/// New files get 0666 less the umask (as `File::create`), not tempfile's
/// 0600; a replaced file keeps its mode.
#[test]
fn files_get_the_umask_mode_and_replacing_keeps_the_mode() {
    let dir = tempfile::tempdir().unwrap();
    for (i, (flag, args)) in writers(dir.path()).into_iter().enumerate() {
        for (umask, want) in [("022", 0o644), ("027", 0o640)] {
            let (a, p) = with_file(&args, &dir.path().join(format!("m{i}-{umask}")));
            let o = under_umask(umask, &a);
            assert!(
                o.status.success(),
                "{a:?}: {}",
                String::from_utf8_lossy(&o.stderr)
            );
            assert_eq!(mode(&p), want, "{flag} of {} under umask {umask}", a[0]);
        }
        // Replacing (--force) a file of mode 0604 keeps 0604.
        let (mut a, p) = with_file(&args, &dir.path().join(format!("m{i}-022")));
        std::fs::set_permissions(&p, std::fs::Permissions::from_mode(0o604)).unwrap();
        a.push("--force".into());
        let o = under_umask("022", &a);
        assert!(
            o.status.success(),
            "{a:?}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        assert_eq!(mode(&p), 0o604, "{flag} of {} replacing", a[0]);
    }
}

/// One policy: an existing file is refused (exit 2, one line naming the
/// flag, the file untouched) unless `--force`, which replaces it and says so.
#[test]
fn every_output_file_is_refused_if_it_exists_unless_forced() {
    let dir = tempfile::tempdir().unwrap();
    for (i, (flag, args)) in writers(dir.path()).into_iter().enumerate() {
        let (a, p) = with_file(&args, &dir.path().join(format!("o{i}")));
        std::fs::write(&p, "keep me\n").unwrap();
        let o = under_umask("022", &a);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{a:?}: {err}");
        assert_eq!(
            err.trim(),
            format!(
                "error: {flag}: {} exists (give --force to replace it, or choose another file)",
                p.display()
            )
        );
        assert_eq!(std::fs::read_to_string(&p).unwrap(), "keep me\n");
        let mut forced = a.clone();
        forced.push("--force".into());
        let o = under_umask("022", &forced);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(o.status.success(), "{forced:?}: {err}");
        assert!(
            err.contains(&format!(
                "{flag}: {} exists; replacing it (--force)",
                p.display()
            )),
            "{err}"
        );
        assert_ne!(std::fs::read_to_string(&p).unwrap(), "keep me\n");
    }
}

/// `tune --v-rel X` is `tune --v0 X·v_c` with v_c of the scene as given
/// (`fricctl static` reports v_c); the same solution to the solver's bound.
#[test]
fn tune_takes_the_velocity_relative_to_v_c() {
    let st = json(&[&["static"][..], PHYS].concat());
    let vc = st["vc_forward"].as_f64().unwrap();
    let x = 0.5;
    let v0 = format!("{:e}", x * vc);
    let base: Vec<&str> = [
        &["tune"][..],
        PHYS,
        &["--adjust", "duz", "--target-mu-rel", "0.6"],
    ]
    .concat();
    let a = json(&[&base[..], &["--v-rel", "0.5"]].concat());
    let b = json(&[&base[..], &["--v0", &v0]].concat());
    assert!((a["v0"].as_f64().unwrap() - x * vc).abs() <= 1e-15 * vc);
    let bound = a["error_bound_over_mu0"].as_f64().unwrap();
    assert!(
        (a["duz"].as_f64().unwrap() - b["duz"].as_f64().unwrap()).abs() <= 1e-9 * 5e-6,
        "{a} {b}"
    );
    assert!((a["mu_over_mu0"].as_f64().unwrap() - 0.6).abs() <= bound);
    // Both velocities at once: refused by name.
    let o = common::cli::fricctl()
        .args([&base[..], &["--v-rel", "0.5", "--v0", "0.01"]].concat())
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(
        String::from_utf8_lossy(&o.stderr).starts_with("error: --v"),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
}

/// A device is written to, not replaced: `--csv /dev/null` (the speed
/// benchmark's) succeeds without `--force`, and `/dev/null` is still the
/// character device afterwards. (Renaming the temporary file over it used
/// to turn `/dev/null` into a regular file when run as root.)
#[test]
fn a_device_is_written_to_not_replaced() {
    use std::os::unix::fs::FileTypeExt;
    let o = assert_cmd::Command::cargo_bin("fricctl")
        .unwrap()
        .args([
            "curve",
            "--duz-rel",
            "0.5",
            "--ratio",
            "2",
            "--phi-deg",
            "45",
            "--v-rel-min",
            "-1",
            "--v-rel-max",
            "1",
            "--points",
            "11",
            "--csv",
            "/dev/null",
        ])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let m = std::fs::metadata("/dev/null").unwrap();
    assert!(
        m.file_type().is_char_device(),
        "/dev/null is no longer a device"
    );
}
