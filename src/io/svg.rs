//! SVG cutting plans (for eyes and browsers): the nesting on the roll and each flat pattern on its
//! own, in millimetres (`mm` width and height over a viewBox in millimetres). SVG has y pointing
//! down, so SVG y is minus the roll's y: the picture is not mirrored (a cutting pattern must keep
//! its face side). The picture is laid out by [`super::drawing`].
use super::drawing::{check_finite, mm, piece, pieces, PatternError, Piece, MM};
use super::write_atomic;
use super::xml::xml_escape;
use crate::layup::flat::FlatPattern;
use crate::layup::nest::{Nesting, Placement};
use std::io::Write;
use std::path::Path;

/// Blank border around an SVG drawing (mm).
const SVG_MARGIN_MM: f64 = 10.0;

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
        writeln!(f, "<title>{}</title>", xml_escape(title))?;
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
            writeln!(f, r#"<g id="{}" data-ply="{}">"#, xml_escape(id), xml_escape(&pc.ply))?;
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
                xml_escape(&pc.label)
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
