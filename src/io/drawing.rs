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
/// Largest label height (m): a big piece does not get a poster.
const LABEL_MAX_M: f64 = 0.025;
/// Share of the largest free box inside the piece the label's box fills, so that a font a little
/// wider than [`LABEL_CHAR_WIDTH`] still stays inside.
const LABEL_FILL: f64 = 0.9;
/// Candidate label centres along each side of the piece's bounding box, before the best is
/// refined by a pattern search of [`LABEL_REFINE_STEPS`] halvings.
const LABEL_GRID: usize = 24;
/// Label height, as a share of the piece's smaller extent, when no free box was found.
const LABEL_TINY: f64 = 0.01;
const LABEL_REFINE_STEPS: usize = 24;
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
    let loops: Vec<Vec<[f64; 2]>> = p.loops().map(|l| l.iter().map(|&q| at.to_roll(q)).collect()).collect();
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
    let label = format!("{}  area {:.6} m2  bbox {:.1} x {:.1} mm  warp ->", p.ply, p.area, sx * MM, sy * MM);
    let (label_at, label_height) = place_label(&loops, &arrow, a, label.chars().count());
    Piece { ply: p.ply.clone(), loops, arrow, label_at, label_height, label }
}

/// Where a horizontal label of `chars` characters goes inside a piece (`loops`: its closed
/// loops, outer and holes, roll frame) and how tall it is: the largest box of the label's
/// proportions (estimated width [`LABEL_CHAR_WIDTH`] a character, height with
/// [`LABEL_DESCENT`]) that lies inside the piece clear of its edges and of the warp arrow, filled
/// to [`LABEL_FILL`], at most [`LABEL_MAX_M`] tall. Returns the baseline's centre and the height.
/// `anchor` (a point inside the piece) is the first candidate centre; a piece with no room at all
/// (none of the candidates inside it) gets a label [`LABEL_TINY`] of its smaller extent tall there.
fn place_label(loops: &[Vec<[f64; 2]>], arrow: &[[[f64; 2]; 2]], anchor: [f64; 2], chars: usize) -> ([f64; 2], f64) {
    // The box is `aspect` times wider than tall; measured in units of its half height, the
    // distance to an obstacle is an L-infinity distance with x scaled by 1 / aspect.
    let aspect = LABEL_CHAR_WIDTH * chars.max(1) as f64 / (1.0 + LABEL_DESCENT);
    let segments: Vec<[[f64; 2]; 2]> = loops
        .iter()
        .flat_map(|l| (0..l.len()).map(move |k| [l[k], l[(k + 1) % l.len()]]))
        .chain(arrow.iter().copied())
        .collect();
    let inside = |c: [f64; 2]| {
        let mut odd = false;
        for l in loops {
            for k in 0..l.len() {
                let (a, b) = (l[k], l[(k + 1) % l.len()]);
                if (a[1] > c[1]) != (b[1] > c[1]) && c[0] < a[0] + (c[1] - a[1]) * (b[0] - a[0]) / (b[1] - a[1]) {
                    odd = !odd;
                }
            }
        }
        odd
    };
    // Half height of the largest free box centred at c (0 outside the piece).
    let room = |c: [f64; 2]| {
        if !inside(c) {
            return 0.0;
        }
        segments.iter().map(|s| linf_to_segment(c, s, aspect)).fold(f64::INFINITY, f64::min)
    };
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    for p in loops.iter().flatten() {
        for k in 0..2 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let cell = [(hi[0] - lo[0]) / LABEL_GRID as f64, (hi[1] - lo[1]) / LABEL_GRID as f64];
    let mut best = (anchor, room(anchor));
    for i in 0..LABEL_GRID {
        for j in 0..LABEL_GRID {
            let c = [lo[0] + (i as f64 + 0.5) * cell[0], lo[1] + (j as f64 + 0.5) * cell[1]];
            let r = room(c);
            if r > best.1 {
                best = (c, r);
            }
        }
    }
    // Pattern search round the best candidate: move to a better neighbour, else halve the step.
    let mut step = [0.5 * cell[0], 0.5 * cell[1]];
    for _ in 0..LABEL_REFINE_STEPS {
        let (c, _) = best;
        let moves =
            [[1.0, 0.0], [-1.0, 0.0], [0.0, 1.0], [0.0, -1.0], [1.0, 1.0], [-1.0, -1.0], [1.0, -1.0], [-1.0, 1.0]];
        let mut moved = false;
        for m in moves {
            let q = [c[0] + m[0] * step[0], c[1] + m[1] * step[1]];
            let r = room(q);
            if r > best.1 {
                best = (q, r);
                moved = true;
            }
        }
        if !moved {
            step = [0.5 * step[0], 0.5 * step[1]];
        }
    }
    let (c, r) = best;
    if !(r > 0.0) {
        return (anchor, LABEL_TINY * (hi[0] - lo[0]).min(hi[1] - lo[1]));
    }
    let h = (LABEL_FILL * 2.0 * r / (1.0 + LABEL_DESCENT)).min(LABEL_MAX_M);
    // The box runs from DESCENT h below the baseline to h above it, centred on c.
    (c_baseline(c, h), h)
}

/// The baseline centre of a label of height `h` whose box is centred on `c`.
fn c_baseline(c: [f64; 2], h: f64) -> [f64; 2] {
    [c[0], c[1] - 0.5 * (1.0 + LABEL_DESCENT) * h + LABEL_DESCENT * h]
}

/// Distance from `c` to the segment `s` in the norm max(|dx| / aspect, |dy|): the half height of
/// the largest box `aspect` times wider than tall centred on `c` that the segment does not enter.
fn linf_to_segment(c: [f64; 2], s: &[[f64; 2]; 2], aspect: f64) -> f64 {
    let (x0, y0) = ((s[0][0] - c[0]) / aspect, s[0][1] - c[1]);
    let (dx, dy) = ((s[1][0] - s[0][0]) / aspect, s[1][1] - s[0][1]);
    let f = |t: f64| (x0 + t * dx).abs().max((y0 + t * dy).abs());
    // f is convex and piecewise linear in t: its least value is at an end or where |x| meets
    // |y| or either is zero.
    let mut ts = vec![0.0, 1.0];
    for (num, den) in [(-x0, dx), (-y0, dy), (y0 - x0, dx - dy), (-(x0 + y0), dx + dy)] {
        if den != 0.0 {
            let t = num / den;
            if (0.0..=1.0).contains(&t) {
                ts.push(t);
            }
        }
    }
    ts.into_iter().map(f).fold(f64::INFINITY, f64::min)
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
