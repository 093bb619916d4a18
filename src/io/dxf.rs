//! DXF cutting plans (ASCII release 12, AC1009, the simplest release every reader takes): each
//! loop of a flat pattern is a closed `POLYLINE` (flag 1) of `VERTEX`es, arrows are `LINE`s,
//! labels `TEXT`; one layer per ply (its name made DXF-safe, see [`dxf_layer_names`]) holds that
//! ply's cut loops and nothing else, so a cutter cuts a layer as it is; the warp arrows are on
//! layer `ARROWS`, the labels on `LABELS` and the roll edges on `ROLL`. Millimetres, said with
//! `$INSUNITS = 4`. The picture is laid out by [`super::drawing`].
use super::drawing::{mm, pieces, PatternError};
use super::write_atomic;
use crate::layup::flat::FlatPattern;
use crate::layup::nest::Nesting;
use std::io::{self, Write};
use std::path::Path;

/// The layers that are not plies' cut loops.
const DXF_OTHER_LAYERS: [&str; 3] = ["ROLL", "ARROWS", "LABELS"];

/// Longest layer name release 12 accepts.
const DXF_LAYER_MAX: usize = 31;

/// DXF layer names of the plies, in order: each name with characters other than ASCII letters,
/// digits, `_`, `-` and `$` replaced by `_`, cut to 31 characters, and made unique (and distinct
/// from `ROLL`, `ARROWS` and `LABELS`) with a `_2`, `_3`... suffix.
pub fn dxf_layer_names(patterns: &[FlatPattern]) -> Vec<String> {
    let mut taken: Vec<String> = DXF_OTHER_LAYERS.iter().map(|l| l.to_string()).collect();
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
        g(70, &(layers.len() + DXF_OTHER_LAYERS.len()).to_string())?;
        // ROLL in grey (8), arrows and labels in white/black (7), plies in colours 1..6 in turn.
        let colours = [8, 7, 7].into_iter().chain((0..layers.len()).map(|k| 1 + k % 6));
        for (name, colour) in DXF_OTHER_LAYERS.into_iter().chain(layers.iter().map(String::as_str)).zip(colours) {
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
                line(&mut g, "ARROWS", s[0], s[1])?;
            }
            g(0, "TEXT")?;
            g(8, "LABELS")?;
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
