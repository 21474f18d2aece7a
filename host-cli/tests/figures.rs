//! Chart output of the real `fricctl` binary: output-directory and file
//! errors are one line naming what is wrong, checked before any long
//! computation, and PNGs are anti-aliased.

use assert_cmd::Command;

fn fricctl() -> Command {
    Command::cargo_bin("fricctl").unwrap()
}

/// Runs fricctl, expects exit status `code`, and returns its error line: the
/// last stderr line, the only one starting with `error: `, with no Rust
/// Debug dump anywhere in stderr.
fn error_line(args: &[&str], code: i32) -> (String, usize) {
    let out = fricctl().args(args).output().unwrap();
    let err = String::from_utf8(out.stderr).unwrap();
    assert_eq!(out.status.code(), Some(code), "{args:?}: {err}");
    let lines: Vec<&str> = err.trim_end().lines().collect();
    assert_eq!(
        lines.iter().filter(|l| l.starts_with("error: ")).count(),
        1,
        "{args:?}: {err}"
    );
    let last = lines.last().copied().unwrap_or_default();
    assert!(last.starts_with("error: "), "{args:?}: {err}");
    for debug in ["Os {", "Error(", "kind:", "BackendError"] {
        assert!(!err.contains(debug), "{args:?}: {err}");
    }
    (last.to_string(), lines.len())
}

/// `--out` naming an existing regular file: exit 2, naming `--out`, for the
/// figures and for every bench, before anything is computed (no progress
/// line, the file untouched).
#[test]
fn out_onto_a_regular_file_is_refused_naming_out() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("a-file");
    std::fs::write(&file, "keep").unwrap();
    let f = file.to_str().unwrap();
    for args in [
        vec!["figures", "--out", f],
        vec!["bench", "work-precision", "--out", f],
        vec!["bench", "methods", "--out", f],
        vec!["bench", "stability", "--out", f],
        vec!["bench", "dac", "--out", f],
    ] {
        // One line in all: the refusal comes before any progress output.
        let (err, lines) = error_line(&args, 2);
        assert_eq!(lines, 1, "{args:?}: {err}");
        assert!(err.starts_with("error: --out: "), "{args:?}: {err}");
        assert!(err.contains("not a directory"), "{args:?}: {err}");
    }
    assert_eq!(std::fs::read_to_string(&file).unwrap(), "keep");
}

/// A directory that cannot be created (its parent is a regular file): exit 2
/// naming `--out`, before the bench computes.
#[test]
fn out_that_cannot_be_created_is_refused_naming_out() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("a-file");
    std::fs::write(&file, "").unwrap();
    let sub = file.join("sub");
    let s = sub.to_str().unwrap();
    for args in [
        vec!["figures", "--out", s],
        vec!["bench", "stability", "--out", s],
        vec!["bench", "work-precision", "--out", s],
    ] {
        let (err, lines) = error_line(&args, 2);
        assert_eq!(lines, 1, "{args:?}: {err}");
        assert!(
            err.starts_with("error: --out: ") && err.contains("cannot create"),
            "{args:?}: {err}"
        );
    }
}

/// A plot file that cannot be written (a directory of that name): exit 1
/// with one line naming the file, not a plotters error dump.
#[test]
fn unwritable_plot_file_is_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let target = dir.path().join("c.png");
    std::fs::create_dir(&target).unwrap();
    let (err, _) = error_line(
        &[
            "curve",
            "--duz-rel",
            "0.5",
            "--ratio",
            "2",
            "--v-rel-min",
            "-1",
            "--v-rel-max",
            "1",
            "--points",
            "20",
            "--plot",
            target.to_str().unwrap(),
            // Past the overwrite policy (the name exists, as a directory):
            // refused before the computation, as bad input.
            "--force",
        ],
        2,
    );
    assert!(err.contains("--plot: "), "{err}");
    assert!(err.contains("c.png is a directory"), "{err}");
}

/// The blend weight `α` of a pixel that is colour `c` drawn with coverage
/// `α` over white (`p = α·c + (1 − α)·255` per channel), if all three
/// channels agree on one `α` within 0.03 (≈ 2–8 levels of 255 per channel,
/// rounding included), else `None`.
fn blend_weight(p: [u8; 3], c: [u8; 3]) -> Option<f64> {
    let mut alphas = Vec::new();
    for k in 0..3 {
        let span = 255.0 - f64::from(c[k]);
        if span > 60.0 {
            alphas.push((255.0 - f64::from(p[k])) / span);
        } else if p[k] < c[k].saturating_sub(2) {
            // A channel the colour barely changes must stay near white … c.
            return None;
        }
    }
    let (lo, hi) = alphas
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &a| {
            (l.min(a), h.max(a))
        });
    (hi - lo <= 0.03).then_some((lo + hi) / 2.0)
}

/// A curve drawn to PNG is anti-aliased. The curve is the only thing drawn
/// in palette colour 0 = RGB(0, 114, 178); everything else is white, grey
/// (r = g = b) or black text. An aliased renderer gives each pixel of the
/// curve full coverage or none, so no pixel lies strictly between the curve
/// colour and white: 0 intermediate levels. Anti-aliasing blends the curve's
/// edges with the background at many coverages; we require ≥ 200 such
/// pixels at ≥ 10 distinct coverages (quantised to 1/20) in (0.1, 0.9). A
/// 200-point curve spans ≈ 900 px of edges at 2× scale, so both counts are
/// far below what a smooth rendering gives and far above the aliased 0.
#[test]
fn png_lines_are_anti_aliased() {
    let dir = tempfile::tempdir().unwrap();
    let png_path = dir.path().join("c.png");
    let out = fricctl()
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
            "--points",
            "200",
            "--plot",
            png_path.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let decoder = png::Decoder::new(std::io::BufReader::new(
        std::fs::File::open(&png_path).unwrap(),
    ));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    let channels = match info.color_type {
        png::ColorType::Rgb => 3,
        png::ColorType::Rgba => 4,
        other => panic!("unexpected PNG colour type {other:?}"),
    };
    assert_eq!(info.bit_depth, png::BitDepth::Eight);
    let curve = [0u8, 114, 178];
    let mut levels = std::collections::BTreeSet::new();
    let mut blended = 0usize;
    for px in buf[..info.buffer_size()].chunks_exact(channels) {
        if let Some(a) = blend_weight([px[0], px[1], px[2]], curve) {
            if a > 0.1 && a < 0.9 {
                blended += 1;
                levels.insert((a * 20.0).round() as i32);
            }
        }
    }
    assert!(blended >= 200, "{blended} blended pixels");
    assert!(levels.len() >= 10, "{} coverage levels", levels.len());
}
