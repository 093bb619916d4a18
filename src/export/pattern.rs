//! Cutting patterns as drawings: DXF (for cutters and CAD) and SVG (for eyes and browsers).
//!
//! Both show the same picture of a [`Nesting`]: each ply's flat pattern at its place on the roll
//! (closed loops: outer boundaries and holes), a warp arrow, a label with the ply name, area and
//! bounding box, and the roll (its two edges and the used length). Lengths are written in
//! millimetres (the library works in metres): the DXF says so with `$INSUNITS = 4`, the SVG with
//! `mm` width and height over a viewBox in millimetres.
//!
//! The DXF is ASCII release 12 (AC1009), the simplest release every reader takes: each loop is a
//! closed `POLYLINE` (flag 1) of `VERTEX`es, arrows are `LINE`s, labels `TEXT`; one layer per ply
//! (its name made DXF-safe, see [`dxf_layer_names`]) holds that ply's loops, arrow and label, and
//! layer `ROLL` the roll edges. SVG has y pointing down, so SVG y is minus the roll's y: the
//! picture is not mirrored (a cutting pattern must keep its face side).
use super::{write_atomic, ExportError};
use crate::layup::flat::FlatPattern;
use crate::layup::nest::{Nesting, Placement};
use std::io::{self, Write};
use std::path::{Path, PathBuf};

/// Why a pattern drawing could not be written.
#[derive(Debug, thiserror::Error)]
pub enum PatternError {
    /// The nesting was not made from these patterns.
    #[error("cannot draw {path}: the nesting places {placed} piece(s) ({placed_names}) but {given} pattern(s) were given ({given_names}). Nest exactly the patterns you draw, in the same order.")]
    Mismatch { path: std::path::PathBuf, placed: usize, placed_names: String, given: usize, given_names: String },
    /// A coordinate is not a finite number.
    #[error("cannot draw {path}: ply '{ply}' has a coordinate that is not a finite number ({what}). Nothing was written; this is a bug in the stage that made the pattern or nesting, please report it.")]
    NonFinite { path: std::path::PathBuf, ply: String, what: &'static str },
    /// Writing the file failed.
    #[error(transparent)]
    Export(#[from] ExportError),
}

/// Metres to millimetres.
const MM: f64 = 1000.0;
/// Blank border around an SVG drawing (mm).
const SVG_MARGIN_MM: f64 = 10.0;
/// Warp arrow length as a fraction of the piece's extent along the warp.
const ARROW_FRACTION: f64 = 0.3;
/// Arrow head: length as a fraction of the arrow, and half-angle (degrees).
const HEAD_FRACTION: f64 = 0.25;
const HEAD_HALF_ANGLE_DEG: f64 = 25.0;
/// Label height: a fraction of the piece's smaller extent, kept between these (m).
const LABEL_FRACTION: f64 = 0.05;
const LABEL_MIN_M: f64 = 0.002;
const LABEL_MAX_M: f64 = 0.025;
/// Longest layer name release 12 accepts.
const DXF_LAYER_MAX: usize = 31;

/// One piece as drawn: roll-frame (m) loops, arrow segments and label.
struct Piece {
    ply: String,
    loops: Vec<Vec<[f64; 2]>>,
    arrow: Vec<[[f64; 2]; 2]>,
    label_at: [f64; 2],
    label_height: f64,
    label: String,
}

fn piece(p: &FlatPattern, at: &Placement) -> Piece {
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

/// The pieces of a nesting, checked against the patterns and for finite numbers.
fn pieces(patterns: &[FlatPattern], nesting: &Nesting, path: &Path) -> Result<Vec<Piece>, PatternError> {
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
    let out: Vec<Piece> = patterns.iter().zip(&nesting.placements).map(|(p, q)| piece(p, q)).collect();
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

fn check_finite(pc: &Piece, path: &Path) -> Result<(), PatternError> {
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
fn mm(v: f64) -> String {
    let s = format!("{:.*}", MM_DECIMALS, v * MM);
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" {
        "0".to_string()
    } else {
        s.to_string()
    }
}

/// DXF layer names of the plies, in order: each name with characters other than ASCII letters,
/// digits, `_`, `-` and `$` replaced by `_`, cut to 31 characters, and made unique (and distinct
/// from `ROLL`) with a `_2`, `_3`... suffix.
pub fn dxf_layer_names(patterns: &[FlatPattern]) -> Vec<String> {
    let mut taken = vec!["ROLL".to_string()];
    let mut out = Vec::with_capacity(patterns.len());
    for p in patterns {
        let base: String = p
            .ply
            .chars()
            .map(|c| if c.is_ascii_alphanumeric() || "_-$".contains(c) { c } else { '_' })
            .take(DXF_LAYER_MAX)
            .collect();
        let base = if base.is_empty() { "PLY".to_string() } else { base };
        let mut name = base.clone();
        let mut k = 2;
        // Layer names compare without case in DXF.
        while taken.iter().any(|t| t.eq_ignore_ascii_case(&name)) {
            let suffix = format!("_{k}");
            let keep: String = base.chars().take(DXF_LAYER_MAX - suffix.len()).collect();
            name = format!("{keep}{suffix}");
            k += 1;
        }
        taken.push(name.clone());
        out.push(name);
    }
    out
}

/// Write the nesting of `patterns` as an ASCII DXF (release 12, millimetres) at `path`,
/// atomically. `nesting` must have been made from `patterns` (same plies, same order).
pub fn write_dxf(patterns: &[FlatPattern], nesting: &Nesting, path: &Path) -> Result<(), PatternError> {
    let pcs = pieces(patterns, nesting, path)?;
    let layers = dxf_layer_names(patterns);
    let (w, len) = (nesting.roll_width, nesting.length);
    write_atomic(path, |f| {
        let mut g = |code: u16, value: &str| writeln!(f, "{code:>3}\n{value}");
        g(0, "SECTION")?;
        g(2, "HEADER")?;
        g(9, "$ACADVER")?;
        g(1, "AC1009")?;
        g(9, "$INSUNITS")?; // 4 = millimetres
        g(70, "4")?;
        g(9, "$MEASUREMENT")?; // metric
        g(70, "1")?;
        g(9, "$EXTMIN")?;
        for (c, v) in [(10, 0.0), (20, 0.0), (30, 0.0)] {
            g(c, &mm(v))?;
        }
        g(9, "$EXTMAX")?;
        for (c, v) in [(10, len), (20, w), (30, 0.0)] {
            g(c, &mm(v))?;
        }
        g(0, "ENDSEC")?;
        g(0, "SECTION")?;
        g(2, "TABLES")?;
        g(0, "TABLE")?;
        g(2, "LTYPE")?;
        g(70, "1")?;
        for (c, v) in
            [(0, "LTYPE"), (2, "CONTINUOUS"), (70, "0"), (3, "Solid line"), (72, "65"), (73, "0"), (40, "0.0")]
        {
            g(c, v)?;
        }
        g(0, "ENDTAB")?;
        g(0, "TABLE")?;
        g(2, "LAYER")?;
        g(70, &(layers.len() + 1).to_string())?;
        // ROLL in grey (8), plies in colours 1..6 in turn.
        let colours = std::iter::once(8).chain((0..layers.len()).map(|k| 1 + k % 6));
        for (name, colour) in std::iter::once("ROLL").chain(layers.iter().map(String::as_str)).zip(colours) {
            for (c, v) in [(0, "LAYER"), (2, name), (70, "0"), (62, &colour.to_string()), (6, "CONTINUOUS")] {
                g(c, v)?;
            }
        }
        g(0, "ENDTAB")?;
        g(0, "ENDSEC")?;
        g(0, "SECTION")?;
        g(2, "ENTITIES")?;
        let line = |g: &mut dyn FnMut(u16, &str) -> io::Result<()>, layer: &str, a: [f64; 2], b: [f64; 2]| {
            g(0, "LINE")?;
            g(8, layer)?;
            for (c, v) in [(10, a[0]), (20, a[1]), (30, 0.0), (11, b[0]), (21, b[1]), (31, 0.0)] {
                g(c, &mm(v))?;
            }
            Ok::<(), io::Error>(())
        };
        // Roll: both edges over the used length and the two ends.
        for (a, b) in [([0.0, 0.0], [len, 0.0]), ([0.0, w], [len, w]), ([0.0, 0.0], [0.0, w]), ([len, 0.0], [len, w])] {
            line(&mut g, "ROLL", a, b)?;
        }
        for (pc, layer) in pcs.iter().zip(&layers) {
            for l in &pc.loops {
                for (c, v) in [(0, "POLYLINE"), (8, layer), (66, "1"), (10, "0"), (20, "0"), (30, "0"), (70, "1")] {
                    g(c, v)?;
                }
                for q in l {
                    g(0, "VERTEX")?;
                    g(8, layer)?;
                    g(10, &mm(q[0]))?;
                    g(20, &mm(q[1]))?;
                    g(30, "0")?;
                }
                g(0, "SEQEND")?;
                g(8, layer)?;
            }
            for s in &pc.arrow {
                line(&mut g, layer, s[0], s[1])?;
            }
            g(0, "TEXT")?;
            g(8, layer)?;
            g(10, &mm(pc.label_at[0]))?;
            g(20, &mm(pc.label_at[1]))?;
            g(30, "0")?;
            g(40, &mm(pc.label_height))?;
            g(1, &dxf_text(&pc.label))?;
            // Centred on the alignment point (72 = 1), like the SVG's text-anchor middle.
            g(72, "1")?;
            g(11, &mm(pc.label_at[0]))?;
            g(21, &mm(pc.label_at[1]))?;
            g(31, "0")?;
        }
        g(0, "ENDSEC")?;
        g(0, "EOF")
    })?;
    Ok(())
}

/// Text safe in a release-12 DXF value: ASCII printable only, one line.
fn dxf_text(s: &str) -> String {
    s.chars().map(|c| if c.is_ascii() && !c.is_ascii_control() { c } else { '?' }).collect()
}

/// Text escaped for XML content and attribute values.
fn xml(s: &str) -> String {
    super::xml_escape(s)
}

/// SVG ids of the plies, in order: `ply-` and the name with characters other than ASCII
/// letters, digits, `-`, `_` and `.` replaced by `_`, made unique with a `_2`, `_3`... suffix.
pub fn svg_ids(patterns: &[FlatPattern]) -> Vec<String> {
    let mut out: Vec<String> = Vec::with_capacity(patterns.len());
    for p in patterns {
        let base: String = format!(
            "ply-{}",
            p.ply
                .chars()
                .map(|c| if c.is_ascii_alphanumeric() || "-_.".contains(c) { c } else { '_' })
                .collect::<String>()
        );
        let mut id = base.clone();
        let mut k = 2;
        while out.contains(&id) || id == "roll" {
            id = format!("{base}_{k}");
            k += 1;
        }
        out.push(id);
    }
    out
}

/// A point as SVG user units: millimetres, y flipped.
fn svg_xy(p: [f64; 2]) -> String {
    format!("{},{}", mm(p[0]), mm(-p[1]))
}

/// Write an SVG of `pieces` over the box `lo..hi` (m, roll frame), with the roll if given.
fn write_svg_pieces(
    path: &Path,
    pcs: &[Piece],
    ids: &[String],
    lo: [f64; 2],
    hi: [f64; 2],
    roll: Option<(f64, f64)>,
    title: &str,
) -> Result<(), PatternError> {
    let (x0, y0) = (lo[0] * MM - SVG_MARGIN_MM, -hi[1] * MM - SVG_MARGIN_MM);
    let (width, height) = ((hi[0] - lo[0]) * MM + 2.0 * SVG_MARGIN_MM, (hi[1] - lo[1]) * MM + 2.0 * SVG_MARGIN_MM);
    write_atomic(path, |f| {
        writeln!(f, r#"<?xml version="1.0" encoding="UTF-8"?>"#)?;
        let u = |v: f64| mm(v / MM);
        writeln!(
            f,
            r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}mm" height="{h}mm" viewBox="{x0} {y0} {w} {h}">"#,
            w = u(width),
            h = u(height),
            x0 = u(x0),
            y0 = u(y0)
        )?;
        writeln!(f, "<title>{}</title>", xml(title))?;
        writeln!(f, "<desc>Units: millimetres; y up on the roll is up on the page. Warp arrows show the warp of each piece.</desc>")?;
        if let Some((w, len)) = roll {
            writeln!(f, r#"<g id="roll" data-width-m="{w}" data-length-m="{len}">"#)?;
            writeln!(
                f,
                r##"<rect x="0" y="{}" width="{}" height="{}" fill="none" stroke="#888" stroke-width="0.5" stroke-dasharray="4 2"/>"##,
                mm(-w),
                mm(len),
                mm(w)
            )?;
            writeln!(f, "</g>")?;
        }
        let stroke = 0.4;
        for (pc, id) in pcs.iter().zip(ids) {
            writeln!(f, r#"<g id="{}" data-ply="{}">"#, xml(id), xml(&pc.ply))?;
            let mut d = String::new();
            for l in &pc.loops {
                for (k, q) in l.iter().enumerate() {
                    d.push_str(if k == 0 { "M " } else { " L " });
                    d.push_str(&svg_xy(*q));
                }
                d.push_str(" Z ");
            }
            writeln!(
                f,
                r##"<path class="cut" d="{}" fill="#cde" fill-rule="evenodd" stroke="#000" stroke-width="{stroke}"/>"##,
                d.trim_end()
            )?;
            let a: Vec<String> = pc.arrow.iter().map(|s| format!("M {} L {}", svg_xy(s[0]), svg_xy(s[1]))).collect();
            writeln!(
                f,
                r##"<path class="warp" d="{}" fill="none" stroke="#c00" stroke-width="{stroke}"/>"##,
                a.join(" ")
            )?;
            let [tx, ty] = [mm(pc.label_at[0]), mm(-pc.label_at[1])];
            writeln!(
                f,
                r#"<text x="{tx}" y="{ty}" font-size="{}" font-family="sans-serif" text-anchor="middle">{}</text>"#,
                mm(pc.label_height),
                xml(&pc.label)
            )?;
            writeln!(f, "</g>")?;
        }
        writeln!(f, "</svg>")
    })?;
    Ok(())
}

/// Write the nesting of `patterns` as an SVG (millimetres) at `path`, atomically: the roll, then
/// one `<g id="ply-NAME">` per piece (see [`svg_ids`]) with its loops as one `<path class="cut">`
/// (fill-rule evenodd, so holes show), its warp arrow (`<path class="warp">`) and label.
pub fn write_svg(patterns: &[FlatPattern], nesting: &Nesting, path: &Path) -> Result<(), PatternError> {
    let pcs = pieces(patterns, nesting, path)?;
    let (w, len) = (nesting.roll_width, nesting.length);
    let title = format!(
        "{} piece(s) on a {} mm roll, {} mm used, {:.1} % waste",
        pcs.len(),
        mm(w),
        mm(len),
        100.0 * nesting.waste_fraction
    );
    write_svg_pieces(path, &pcs, &svg_ids(patterns), [0.0, 0.0], [len, w], Some((w, len)), &title)
}

/// Write one flat pattern as an SVG (millimetres) in its own frame (warp along +x, the seed node
/// at the origin), atomically; same layout as [`write_svg`] without the roll.
pub fn write_pattern_svg(pattern: &FlatPattern, path: &Path) -> Result<(), PatternError> {
    let at =
        Placement { ply: pattern.ply.clone(), rotated: false, offset: [0.0, 0.0], min: pattern.min, max: pattern.max };
    let pc = piece(pattern, &at);
    check_finite(&pc, path)?;
    let title = format!("ply {}: flat pattern, area {:.6} m2", pattern.ply, pattern.area);
    write_svg_pieces(path, &[pc], &svg_ids(std::slice::from_ref(pattern)), pattern.min, pattern.max, None, &title)
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
