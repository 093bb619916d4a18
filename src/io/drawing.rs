//! Cutting patterns as drawings: the picture that both [`super::dxf`] (for cutters and CAD) and
//! [`super::svg`] (for eyes and browsers) draw, and [`write_cutting_plan`], which writes both.
//!
//! Both show the same picture of a [`Nesting`]: each ply's flat pattern at its place on the roll
//! (closed loops: outer boundaries and holes), a warp arrow, a label with the ply name, area and
//! bounding box, and the roll (its two edges and the used length). Lengths are written in
//! millimetres (the library works in metres): the DXF says so with `$INSUNITS = 4`, the SVG with
//! `mm` width and height over a viewBox in millimetres.
use super::dxf::write_dxf;
use super::svg::{svg_ids, write_pattern_svg, write_svg};
use super::ExportError;
use crate::layup::flat::FlatPattern;
use crate::layup::nest::{Nesting, Placement};
use std::path::{Path, PathBuf};

/// Why a pattern drawing could not be written.
#[derive(Debug, thiserror::Error)]
pub enum PatternError {
    /// The nesting was not made from these patterns.
    #[error("cannot draw {path}: the nesting places {placed} piece(s) ({placed_names}) but {given} pattern(s) were given ({given_names}). Nest exactly the patterns you draw, in the same order.")]
    Mismatch {
        /// The drawing.
        path: std::path::PathBuf,
        /// Pieces nested.
        placed: usize,
        /// Their plies.
        placed_names: String,
        /// Patterns given.
        given: usize,
        /// Their plies.
        given_names: String,
    },
    /// A coordinate is not a finite number.
    #[error("cannot draw {path}: ply '{ply}' has a coordinate that is not a finite number ({what}). Nothing was written; this is a bug in the stage that made the pattern or nesting, please report it.")]
    NonFinite {
        /// The drawing.
        path: std::path::PathBuf,
        /// The ply.
        ply: String,
        /// Which coordinate.
        what: &'static str,
    },
    /// Writing the file failed.
    #[error(transparent)]
    Export(#[from] ExportError),
}

/// Metres to millimetres.
pub(crate) const MM: f64 = 1000.0;
/// Warp arrow length as a fraction of the piece's extent along the warp.
const ARROW_FRACTION: f64 = 0.3;
/// Arrow head: length as a fraction of the arrow, and half-angle (degrees).
const HEAD_FRACTION: f64 = 0.25;
const HEAD_HALF_ANGLE_DEG: f64 = 25.0;
/// Label height: a fraction of the piece's smaller extent, kept between these (m).
const LABEL_FRACTION: f64 = 0.05;
const LABEL_MIN_M: f64 = 0.002;
const LABEL_MAX_M: f64 = 0.025;
/// Advance of one label character as a fraction of the text height: a generous estimate for the
/// fonts cutters and CAD draw TEXT with (ezdxf measures 0.68 for its default font).
const LABEL_CHAR_WIDTH: f64 = 0.75;
/// Descent below the baseline as a fraction of the text height.
const LABEL_DESCENT: f64 = 0.3;

/// One piece as drawn: roll-frame (m) loops, arrow segments and label.
pub(crate) struct Piece {
    pub ply: String,
    pub loops: Vec<Vec<[f64; 2]>>,
    pub arrow: Vec<[[f64; 2]; 2]>,
    pub label_at: [f64; 2],
    pub label_height: f64,
    pub label: String,
}

pub(crate) fn piece(p: &FlatPattern, at: &Placement) -> Piece {
    let loops = p.loops().map(|l| l.iter().map(|&q| at.to_roll(q)).collect()).collect();
    let [sx, sy] = p.size();
    let len = (ARROW_FRACTION * sx).max(p.spacing);
    let (a, w) = (at.to_roll(p.anchor), at.warp());
    let tail = [a[0] - 0.5 * len * w[0], a[1] - 0.5 * len * w[1]];
    let tip = [a[0] + 0.5 * len * w[0], a[1] + 0.5 * len * w[1]];
    let (s, c) = HEAD_HALF_ANGLE_DEG.to_radians().sin_cos();
    let h = HEAD_FRACTION * len;
    // Back along the arrow, turned by +-the half angle.
    let barb = |sign: f64| [tip[0] - h * (c * w[0] - sign * s * w[1]), tip[1] - h * (c * w[1] + sign * s * w[0])];
    let arrow = vec![[tail, tip], [tip, barb(1.0)], [tip, barb(-1.0)]];
    let label_height = (LABEL_FRACTION * sx.min(sy)).clamp(LABEL_MIN_M, LABEL_MAX_M);
    // Below the arrow (across it), so the two do not overlap.
    let n = [-w[1], w[0]];
    let label_at = [a[0] - 2.0 * label_height * n[0], a[1] - 2.0 * label_height * n[1]];
    let label = format!("{}  area {:.6} m2  bbox {:.1} x {:.1} mm  warp ->", p.ply, p.area, sx * MM, sy * MM);
    Piece { ply: p.ply.clone(), loops, arrow, label_at, label_height, label }
}

/// Keep a piece's label (horizontal, centred on `label_at` at its baseline) inside the box
/// `lo`..`hi` (the roll): its height lowered until its estimated width and height fit, then moved
/// in as little as it takes.
pub(crate) fn keep_label_inside(pc: &mut Piece, lo: [f64; 2], hi: [f64; 2]) {
    let chars = pc.label.chars().count().max(1) as f64;
    let (room_x, room_y) = (hi[0] - lo[0], hi[1] - lo[1]);
    let h = pc.label_height.min(room_x / (LABEL_CHAR_WIDTH * chars)).min(room_y / (1.0 + LABEL_DESCENT));
    if !(h > 0.0) {
        return;
    }
    let half = 0.5 * LABEL_CHAR_WIDTH * chars * h;
    pc.label_height = h;
    pc.label_at[0] = pc.label_at[0].clamp(lo[0] + half, (hi[0] - half).max(lo[0] + half));
    pc.label_at[1] = pc.label_at[1].clamp(lo[1] + LABEL_DESCENT * h, (hi[1] - h).max(lo[1] + LABEL_DESCENT * h));
}

/// The pieces of a nesting, checked against the patterns and for finite numbers.
pub(crate) fn pieces(patterns: &[FlatPattern], nesting: &Nesting, path: &Path) -> Result<Vec<Piece>, PatternError> {
    let same = patterns.len() == nesting.placements.len()
        && patterns.iter().zip(&nesting.placements).all(|(p, q)| p.ply == q.ply);
    if !same {
        return Err(PatternError::Mismatch {
            path: path.to_path_buf(),
            placed: nesting.placements.len(),
            placed_names: nesting.placements.iter().map(|q| q.ply.as_str()).collect::<Vec<_>>().join(", "),
            given: patterns.len(),
            given_names: patterns.iter().map(|p| p.ply.as_str()).collect::<Vec<_>>().join(", "),
        });
    }
    let mut out: Vec<Piece> = patterns.iter().zip(&nesting.placements).map(|(p, q)| piece(p, q)).collect();
    for pc in &mut out {
        keep_label_inside(pc, [0.0, 0.0], [nesting.length, nesting.roll_width]);
    }
    for pc in &out {
        check_finite(pc, path)?;
    }
    if !(nesting.roll_width.is_finite() && nesting.length.is_finite()) {
        return Err(PatternError::NonFinite {
            path: path.to_path_buf(),
            ply: "ROLL".into(),
            what: "roll width or length",
        });
    }
    Ok(out)
}

pub(crate) fn check_finite(pc: &Piece, path: &Path) -> Result<(), PatternError> {
    let bad = |what| Err(PatternError::NonFinite { path: path.to_path_buf(), ply: pc.ply.clone(), what });
    if !pc.loops.iter().flatten().flatten().all(|v| v.is_finite()) {
        return bad("outline vertex");
    }
    if !pc.arrow.iter().flatten().flatten().chain(&pc.label_at).all(|v| v.is_finite()) || !pc.label_height.is_finite() {
        return bad("warp arrow or label");
    }
    Ok(())
}

/// Decimals written for millimetres: a nanometre, far below any cutter's resolution, and enough
/// to print the grid's decimal lengths exactly instead of their binary rounding (950.0000000000001).
const MM_DECIMALS: usize = 6;

/// A length in metres as millimetres, to [`MM_DECIMALS`] places, trailing zeros dropped, no `-0`.
pub(crate) fn mm(v: f64) -> String {
    let s = format!("{:.*}", MM_DECIMALS, v * MM);
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" {
        "0".to_string()
    } else {
        s.to_string()
    }
}

/// Write a whole cutting plan into `dir` (created if missing): the nesting as `<stem>.dxf` and
/// `<stem>.svg`, and each pattern on its own as `<id>.svg` with `id` from [`svg_ids`]
/// (`ply-NAME`, file-name safe). Returns the paths written, in that order. Everything is checked
/// before the first file is written.
pub fn write_cutting_plan(
    patterns: &[FlatPattern],
    nesting: &Nesting,
    dir: &Path,
    stem: &str,
) -> Result<Vec<PathBuf>, PatternError> {
    let dxf = dir.join(format!("{stem}.dxf"));
    pieces(patterns, nesting, &dxf)?;
    std::fs::create_dir_all(dir).map_err(|source| ExportError::CreateDir { path: dir.to_path_buf(), source })?;
    let svg = dir.join(format!("{stem}.svg"));
    write_dxf(patterns, nesting, &dxf)?;
    write_svg(patterns, nesting, &svg)?;
    let mut out = vec![dxf, svg];
    for (p, id) in patterns.iter().zip(svg_ids(patterns)) {
        let path = dir.join(format!("{id}.svg"));
        write_pattern_svg(p, &path)?;
        out.push(path);
    }
    Ok(out)
}
