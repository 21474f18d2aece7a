//! Figure files: the type from the extension, the output folder, and one
//! chart drawn once as SVG and, for `.png`, rasterised by resvg at
//! [`PNG_SCALE`].

use std::path::Path;
use std::sync::Arc;

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::error::{CliError, CliResult};

use super::*;

/// The file type from the extension (`svg` or `png`).
pub fn ext(path: &Path) -> CliResult<String> {
    let e = path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase())
        .unwrap_or_default();
    if e == "svg" || e == "png" {
        Ok(e)
    } else {
        Err(CliError::usage(format!(
            "--plot: {}: the file name must end in .svg or .png",
            path.display()
        )))
    }
}

/// Checks an output directory before any work: it is created if missing, must
/// be a directory, and must accept a new file.
///
/// # Errors
/// Exit status 2 with a one-line message naming `--out`.
pub fn prepare_out_dir(out: &Path) -> CliResult {
    let bad = |what: String| CliError::usage(format!("--out: {}: {what}", out.display()));
    if out.exists() && !out.is_dir() {
        return Err(bad("exists and is not a directory".into()));
    }
    std::fs::create_dir_all(out).map_err(|e| bad(format!("cannot create the directory: {e}")))?;
    let probe = out.join(format!(".fricctl-write-test-{}", std::process::id()));
    std::fs::write(&probe, b"")
        .map_err(|e| bad(format!("cannot write into the directory: {e}")))?;
    // The probe is ours and empty; failing to remove it leaves a harmless file.
    let _ = std::fs::remove_file(&probe);
    Ok(())
}

/// Draws a chart of `size` nominal pixels with `draw` and writes it to `path`
/// (`.svg` as drawn, `.png` rasterised, anti-aliased, at [`PNG_SCALE`]).
///
/// # Errors
/// A bad extension (exit 2); a drawing, rasterising or file error as one line
/// naming the file (exit 1).
pub fn write_chart<F>(path: &Path, size: (u32, u32), draw: F) -> CliResult
where
    F: FnOnce(
        &DrawingArea<SVGBackend<'_>, Shift>,
    ) -> Result<(), DrawingAreaErrorKind<std::io::Error>>,
{
    init_font();
    let kind = ext(path)?;
    let fail = |what: &str, e: &dyn std::fmt::Display| {
        CliError::failure(format!("{}: {what}: {e}", path.display()))
    };
    let mut svg = String::new();
    FINE.with(|f| f.borrow_mut().clear());
    {
        let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
        draw(&root).map_err(|e| fail("cannot draw", &e))?;
        root.present().map_err(|e| fail("cannot draw", &e))?;
    }
    let fine = FINE.with(|f| std::mem::take(&mut *f.borrow_mut()));
    let svg = typeset(&refine(&svg, &fine));
    let svg = svg.replace("<rect ", "<rect shape-rendering=\"crispEdges\" ");
    let bytes = if kind == "svg" {
        svg.into_bytes()
    } else {
        rasterise(&svg, size).map_err(|e| fail("cannot rasterise", &e))?
    };
    std::fs::write(path, bytes).map_err(|e| fail("cannot write", &e))
}

/// SVG text to PNG bytes at [`PNG_SCALE`], with only the embedded font.
pub(super) fn rasterise(svg: &str, size: (u32, u32)) -> Result<Vec<u8>, String> {
    use resvg::{tiny_skia, usvg};
    let mut opt = usvg::Options::default();
    let mut db = usvg::fontdb::Database::new();
    db.load_font_data(FONT_BYTES.to_vec());
    db.set_sans_serif_family("DejaVu Sans");
    opt.fontdb = Arc::new(db);
    let tree = usvg::Tree::from_str(svg, &opt).map_err(|e| e.to_string())?;
    let (w, h) = (
        (size.0 as f32 * PNG_SCALE).round() as u32,
        (size.1 as f32 * PNG_SCALE).round() as u32,
    );
    let mut pixmap =
        tiny_skia::Pixmap::new(w, h).ok_or_else(|| format!("bad image size {w} × {h}"))?;
    pixmap.fill(tiny_skia::Color::WHITE);
    resvg::render(
        &tree,
        tiny_skia::Transform::from_scale(PNG_SCALE, PNG_SCALE),
        &mut pixmap.as_mut(),
    );
    pixmap.encode_png().map_err(|e| e.to_string())
}
