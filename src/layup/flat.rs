//! Flat patterns: the cutting outline of a ply, the draped net unfolded onto its flat grid.
//!
//! A woven ply is cut unsheared, so node (i, j) of a [`DrapeNet`] lies flat at
//! `((i - i0) d, (j - j0) d)`: warp along +x, weft along +y, `d` the net spacing and `(i0, j0)`
//! the origin (seed) node, which sits at (0, 0). A point of the draped net with fabric
//! coordinates (i + s, j + t) in cell (i, j) lies flat at `((i + s - i0) d, (j + t - j0) d)`: the
//! bilinear interpolation of the cell's flat corners.
//!
//! The cut line ([`CutLine`]):
//! - **the ply's outline** ([`flat_pattern_in_outline`]): a ply draped with an outline is cut
//!   along that outline, each of its points located on the draped net (its cell and the
//!   bilinear parameters there, extended up to [`OUTLINE_REACH`] cells beyond the placed cells,
//!   where the nodes outside the outline were refused) and carried into the flat frame;
//! - **the smooth curve through the boundary nodes** ([`flat_pattern_smooth`]): otherwise a
//!   smooth closed curve ([`super::curve::smooth_loop`]: cubic Hermite, corners kept)
//!   through the points of the boundary polygon ([`flat_pattern`]: the polygon through the net's
//!   placed boundary nodes, the boundary of the cells with four placed corners and of the half
//!   cells (triangles) whose three corners were placed; its edges run along a fibre or across one
//!   cell's diagonal);
//! - **with a cutting margin** ([`with_margin`]): that cut line offset outward by the margin in
//!   the flat plane ([`super::curve::offset_loops`]: round joins); when the offset loops would
//!   overlap (pieces or a hole closer than twice the margin), the complete cells each grown by
//!   the margin ([`flat_pattern_with_margin`], a staircase with square corners) instead.
//!
//! A pattern not cut along the line its ply asks for (an outline the net does not carry, a
//! margin that cannot be offset) says why in [`FlatPattern::warnings`].
//!
//! Nodes lost for other reasons than an outline (off the tool, shear limit, folds) are trimmed
//! the same way: the pattern is the fabric that actually lies on the tool.
use super::curve::{first_crossing, offset_loops, smooth_loop};
use crate::geometry::Point;
use crate::kinematic::sampler::NetSampler;
use crate::kinematic::DrapeNet;
use crate::numeric::union_find_root;
use serde::{Deserialize, Serialize};
use std::collections::HashMap;

/// Why a flat pattern or a nesting could not be made.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FlatError {
    /// The net has no cell with four placed corners.
    #[error("ply '{ply}' has no complete cell (no cell with all four corners placed), so it has no flat pattern. Check the drape of this ply: its seed, size and the node statuses in its .drape.json.")]
    NoCells {
        /// The ply.
        ply: String,
    },
    /// A cutting allowance that is not a length.
    #[error("ply '{ply}': the cutting margin {margin} is not zero or a positive length in metres. Fix it in the scene file.")]
    BadMargin {
        /// The ply.
        ply: String,
        /// The margin, m.
        margin: f64,
    },
    /// The net's spacing cannot scale a pattern.
    #[error("ply '{ply}': the net spacing {spacing} is not a positive finite length, so the pattern cannot be unfolded. Re-create the net with `drape run`.")]
    BadSpacing {
        /// The ply.
        ply: String,
        /// The spacing, m.
        spacing: f64,
    },
    /// A nesting parameter is out of range.
    #[error("nesting: {field} = {value} {reason}. Fix it in the scene file.")]
    BadNestParameter {
        /// The parameter.
        field: &'static str,
        /// Its value.
        value: f64,
        /// What it must be.
        reason: &'static str,
    },
    /// A pattern does not fit across the roll in any allowed orientation.
    #[error("ply '{ply}' is {across:.6} m across the roll ({orientation}) but the roll is only {roll_width:.6} m wide: {excess:.6} m too wide. Use a wider roll, allow a 90 degree turn if the material permits it, or split the ply.")]
    TooWide {
        /// The ply.
        ply: String,
        /// Its extent across the roll, m.
        across: f64,
        /// The roll width, m.
        roll_width: f64,
        /// How much too wide, m.
        excess: f64,
        /// How it was turned.
        orientation: &'static str,
    },
}

/// One connected piece of a pattern (cells joined through edges; cells that only touch at a
/// corner are separate pieces).
#[derive(Debug, Clone, PartialEq)]
pub struct Region {
    /// Closed loops (last vertex joins the first, not repeated), in metres in the pattern frame:
    /// the outer boundary first, counter-clockwise, then the holes, clockwise. No loop visits a
    /// point twice; loops of one pattern may touch at a corner (a pinch point) but never cross.
    /// On the grid lines (boundary nodes, cells), collinear vertices are merged.
    pub loops: Vec<Vec<[f64; 2]>>,
    /// Number of the ply's complete cells in the region.
    pub cells: usize,
    /// Area inside the loops (m^2), their signed shoelace area. Cut through the boundary nodes it
    /// is `(cells + half_cells / 2) d^2` exactly.
    pub area: f64,
}

/// The line a pattern is cut along (see the module comment). With a cutting margin, the line
/// the margin was offset from ([`FlatPattern::margin`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CutLine {
    /// The ply's outline, carried through the draped net into the flat frame.
    Outline,
    /// The polygon through the net's placed boundary nodes (complete cells and half cells).
    Nodes,
    /// The smooth curve through the points of that polygon (corners kept).
    SmoothNodes,
    /// The complete cells, each grown by the cutting margin.
    GrownCells,
    /// The blank a flat sheet was cut to (`blank = ...`), as given in fabric coordinates.
    Blank,
}

/// Why a pattern is not cut along the line its ply asks for. Recorded in the pattern, printed by
/// `drape run`, written in `layup.json` and shown in the report.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, thiserror::Error)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum CutWarning {
    /// A point of the ply's outline does not land on the draped net.
    #[error("outline point {point} (of {of}) is not on the draped net within {reach} cells of its placed cells (the ply did not reach it), so the pattern is cut along the smooth curve through the boundary nodes, not along the outline", reach = OUTLINE_REACH)]
    OutlineOffNet {
        /// Index of the first such point in the outline.
        point: usize,
        /// Number of outline points.
        of: usize,
    },
    /// The outline carried into the flat frame crosses itself or encloses no area.
    #[error("the outline carried into the flat frame crosses itself or encloses no area (the net folds or shears too much along it), so the pattern is cut along the smooth curve through the boundary nodes, not along the outline")]
    OutlineNotSimple,
    /// The cut line offset by the margin overlaps itself.
    #[error("the cutting margin of {margin} m around the cut line makes pieces or holes overlap (closer than twice the margin), so the margin is grown around the complete cells instead (square steps of whole cells)")]
    MarginOverlaps {
        /// The margin, m.
        margin: f64,
    },
}

/// The flat cutting pattern of one ply, in its own frame: metres, warp along +x, weft along +y,
/// the origin (seed) node at (0, 0).
#[derive(Debug, Clone, PartialEq)]
pub struct FlatPattern {
    /// Ply name.
    pub ply: String,
    /// Fibre spacing d of the net (m).
    pub spacing: f64,
    /// Grid indices of the seed node, which lies at (0, 0).
    pub origin_node: (usize, usize),
    /// The connected pieces, largest first (ties in grid order).
    pub regions: Vec<Region>,
    /// Total number of complete cells.
    pub cells: usize,
    /// Number of half cells: cells with exactly three placed corners, whose triangle is part of
    /// the pattern cut through the boundary nodes.
    pub half_cells: usize,
    /// Area to cut (m^2), inside the loops: `(cells + half_cells / 2) d^2` cut through the
    /// boundary nodes.
    pub area: f64,
    /// The line the pattern is cut along.
    pub cut: CutLine,
    /// The cutting margin included outside that line (m; 0 without one).
    pub margin: f64,
    /// Why the pattern is not cut along the line its ply asks for (empty when it is).
    pub warnings: Vec<CutWarning>,
    /// Lower-left corner of the bounding box (m).
    pub min: [f64; 2],
    /// Upper-right corner of the bounding box (m).
    pub max: [f64; 2],
    /// A point inside the pattern to hang the warp arrow and label on: the centroid of the
    /// triangle (half of a complete cell, or a half cell) of the largest region nearest to that
    /// region's centroid.
    pub anchor: [f64; 2],
}

impl FlatPattern {
    /// All loops of all regions (outer boundaries counter-clockwise, holes clockwise).
    pub fn loops(&self) -> impl Iterator<Item = &Vec<[f64; 2]>> {
        self.regions.iter().flat_map(|r| r.loops.iter())
    }

    /// Size of the bounding box: [along the warp, along the weft] (m).
    pub fn size(&self) -> [f64; 2] {
        [self.max[0] - self.min[0], self.max[1] - self.min[1]]
    }
}

/// The flat pattern of a draped net cut through its boundary nodes (see the module comment).
/// Error when the net has no complete cell, or a spacing that is not a positive length.
pub fn flat_pattern(net: &DrapeNet) -> Result<FlatPattern, FlatError> {
    check_spacing(net)?;
    let tri = triangles_of(net);
    if tri.cells == 0 {
        return Err(FlatError::NoCells { ply: net.name.clone() });
    }
    let d = net.spacing;
    let (i0, j0) = (net.origin_node.0 as f64, net.origin_node.1 as f64);
    let to_flat = |[x, y]: [f64; 2]| [(x - i0) * d, (y - j0) * d];
    let traced = trace_triangles(&tri);
    let regions: Vec<Region> = traced
        .iter()
        .map(|r| Region {
            loops: r.loops.iter().map(|l| l.iter().map(|&[i, j]| to_flat([i as f64, j as f64])).collect()).collect(),
            cells: r.cells,
            area: r.triangles as f64 * 0.5 * d * d,
        })
        .collect();
    let anchor = to_flat(traced[0].anchor);
    let area = (2 * tri.cells + tri.half_cells) as f64 * 0.5 * d * d;
    Ok(pattern_of(net, regions, tri.cells, tri.half_cells, area, CutLine::Nodes, anchor))
}

/// How far (in cells, along the warp or the weft) beyond the cell it lands in an outline point
/// may lie and still be carried into the flat frame by that cell's bilinear patch: the nodes
/// just outside an outline are refused, so the outline runs through the band of cells with
/// refused corners, within one cell (along its diagonal, up to sqrt 2 of one fibre) of the
/// complete cells.
pub const OUTLINE_REACH: f64 = 1.5;

/// Gauss-Newton steps that locate a point on a cell's bilinear patch (it converges in two or
/// three on the cells of a net; the step size is checked after).
const PATCH_STEPS: usize = 12;
/// A located point whose last Gauss-Newton step moved its parameters by more than this did not
/// converge.
const PATCH_CONVERGED: f64 = 1e-9;

/// The flat pattern of a draped net cut along the smooth curve through its boundary nodes: each
/// loop of [`flat_pattern`] replaced by [`smooth_loop`] through its points (the boundary nodes
/// where it turns; an edge ending at a corner stays straight). A loop whose curve would cross
/// itself keeps its chords; if the curves of two loops cross, the whole pattern keeps its chords
/// and says [`CutLine::Nodes`]. The area is the curves' shoelace area. Errors as
/// [`flat_pattern`].
pub fn flat_pattern_smooth(net: &DrapeNet) -> Result<FlatPattern, FlatError> {
    let nodes = flat_pattern(net)?;
    let regions: Vec<Region> = nodes
        .regions
        .iter()
        .map(|r| {
            let loops: Vec<Vec<[f64; 2]>> = r
                .loops
                .iter()
                .map(|l| {
                    let s = smooth_loop(l);
                    if first_crossing(std::slice::from_ref(&s)).is_some() {
                        l.clone()
                    } else {
                        s
                    }
                })
                .collect();
            let area = loops.iter().map(|l| shoelace_area(l)).sum();
            Region { loops, cells: r.cells, area }
        })
        .collect();
    let all: Vec<Vec<[f64; 2]>> = regions.iter().flat_map(|r| r.loops.iter().cloned()).collect();
    if first_crossing(&all).is_some() {
        return Ok(nodes);
    }
    let area = regions.iter().map(|r| r.area).sum();
    Ok(pattern_of(net, regions, nodes.cells, nodes.half_cells, area, CutLine::SmoothNodes, nodes.anchor))
}

/// The flat pattern of a ply draped with an outline (`outline`: the points as the drape was
/// given them, on the tool): cut along the outline carried through the net into the flat frame
/// (see the module comment). When some outline point does not land on the net within
/// [`OUTLINE_REACH`] cells of a complete cell (the ply did not reach it: off the tool, a
/// failure), or the carried outline crosses itself, the pattern is cut along the smooth curve
/// through the boundary nodes instead ([`flat_pattern_smooth`]); `cut` says which and `warnings`
/// why. Errors as [`flat_pattern`].
pub fn flat_pattern_in_outline(net: &DrapeNet, outline: &[Point]) -> Result<FlatPattern, FlatError> {
    let fallback = |why: CutWarning| {
        flat_pattern_smooth(net).map(|mut p| {
            p.warnings.push(why);
            p
        })
    };
    let nodes = flat_pattern(net)?;
    let mut poly = match flat_outline(net, outline) {
        Ok(poly) => poly,
        Err(point) => return fallback(CutWarning::OutlineOffNet { point, of: outline.len() }),
    };
    // Consecutive points that land on one flat point are one vertex.
    poly.dedup_by(|a, b| a == b);
    while poly.len() > 1 && poly.first() == poly.last() {
        poly.pop();
    }
    if poly.len() < 3 || polygon_crosses_itself(&poly) {
        return fallback(CutWarning::OutlineNotSimple);
    }
    let mut area = shoelace_area(&poly);
    if area < 0.0 {
        poly.reverse();
        area = -area;
    }
    if !(area > 0.0) {
        return fallback(CutWarning::OutlineNotSimple);
    }
    let regions = vec![Region { loops: vec![poly], cells: nodes.cells, area }];
    Ok(pattern_of(net, regions, nodes.cells, nodes.half_cells, area, CutLine::Outline, nodes.anchor))
}

/// The pattern of a flat sheet cut to `blank` (fabric coordinates from the origin node, m): the
/// blank itself, which is what was cut, with a cutting margin offset from it as
/// [`with_margin`] does. Errors as [`flat_pattern`] (a net without a complete cell).
pub fn blank_pattern(net: &DrapeNet, blank: &[[f64; 2]], margin: f64) -> Result<FlatPattern, FlatError> {
    check_margin(net, margin)?;
    let nodes = flat_pattern(net)?;
    let n = blank.len();
    let area =
        0.5 * (0..n).map(|k| blank[k][0] * blank[(k + 1) % n][1] - blank[(k + 1) % n][0] * blank[k][1]).sum::<f64>();
    // Loops run counter-clockwise, as the other cut lines give them.
    let mut poly = blank.to_vec();
    if area < 0.0 {
        poly.reverse();
    }
    let regions = vec![Region { loops: vec![poly], cells: nodes.cells, area: area.abs() }];
    let base = pattern_of(net, regions, nodes.cells, nodes.half_cells, area.abs(), CutLine::Blank, nodes.anchor);
    with_margin(net, base, margin)
}

/// The pattern of a ply as the run cuts it: along the ply's outline when it has one
/// ([`flat_pattern_in_outline`]), else along the smooth curve through its boundary nodes
/// ([`flat_pattern_smooth`]); with a cutting margin that line offset by it ([`with_margin`]).
/// Errors as [`flat_pattern`], and for a negative or non-finite margin.
pub fn ply_pattern(net: &DrapeNet, outline: Option<&[Point]>, margin: f64) -> Result<FlatPattern, FlatError> {
    check_margin(net, margin)?;
    let base = match outline {
        Some(points) => flat_pattern_in_outline(net, points)?,
        None => flat_pattern_smooth(net)?,
    };
    with_margin(net, base, margin)
}

/// `pattern` (a pattern of `net`, cut along its line without a margin) with a cutting margin:
/// every loop offset outward by `margin` (m) in the flat plane
/// ([`offset_loops`]: round joins; a hole narrower than twice the margin closes). When the offset
/// loops would overlap, the complete cells grown by the margin instead
/// ([`flat_pattern_with_margin`]), with a [`CutWarning::MarginOverlaps`]. `margin = 0` gives the
/// pattern back. Errors for a negative or non-finite margin.
pub fn with_margin(net: &DrapeNet, pattern: FlatPattern, margin: f64) -> Result<FlatPattern, FlatError> {
    check_margin(net, margin)?;
    if margin == 0.0 {
        return Ok(pattern);
    }
    let loops: Vec<Vec<[f64; 2]>> = pattern.loops().cloned().collect();
    let Some(mut offset) = offset_loops(&loops, margin) else {
        let mut grown = flat_pattern_with_margin(net, margin)?;
        grown.warnings = pattern.warnings;
        grown.warnings.push(CutWarning::MarginOverlaps { margin });
        return Ok(grown);
    };
    let mut regions = Vec::with_capacity(pattern.regions.len());
    let mut next = offset.drain(..);
    for r in &pattern.regions {
        let mut loops: Vec<Vec<[f64; 2]>> = Vec::new();
        for _ in &r.loops {
            loops.extend(next.next().expect("one offset a loop"));
        }
        // Outer loops (counter-clockwise) first; holes keep their order.
        loops.sort_by_key(|l| std::cmp::Reverse(shoelace_area(l) > 0.0));
        let area = loops.iter().map(|l| shoelace_area(l)).sum();
        regions.push(Region { loops, cells: r.cells, area });
    }
    let area = regions.iter().map(|r| r.area).sum();
    let mut out = pattern_of(net, regions, pattern.cells, pattern.half_cells, area, pattern.cut, pattern.anchor);
    out.margin = margin;
    out.warnings = pattern.warnings;
    Ok(out)
}

fn check_margin(net: &DrapeNet, margin: f64) -> Result<(), FlatError> {
    if !(margin.is_finite() && margin >= 0.0) {
        return Err(FlatError::BadMargin { ply: net.name.clone(), margin });
    }
    Ok(())
}

/// The outline's points carried into the flat frame, or the index of the first point that does
/// not land on the net within [`OUTLINE_REACH`] cells.
fn flat_outline(net: &DrapeNet, outline: &[Point]) -> Result<Vec<[f64; 2]>, usize> {
    let d = net.spacing;
    let sampler = NetSampler::new(net).ok_or(0usize)?;
    let (i0, j0) = (net.origin_node.0 as f64, net.origin_node.1 as f64);
    let mut out = Vec::with_capacity(outline.len());
    for (k, p) in outline.iter().enumerate() {
        let h = sampler.nearest_within(p, (OUTLINE_REACH + 1.0) * std::f64::consts::SQRT_2 * d).ok_or(k)?;
        let (i, j) = h.cell;
        let [s, t] = locate_on_patch(net, i, j, p, [h.s, h.t]).ok_or(k)?;
        let beyond = (-s).max(s - 1.0).max(-t).max(t - 1.0);
        if beyond > OUTLINE_REACH {
            return Err(k);
        }
        out.push([(i as f64 + s - i0) * d, (j as f64 + t - j0) * d]);
    }
    Ok(out)
}

/// Bilinear parameters (s, t) of the point of cell (i, j)'s patch, extended beyond the cell,
/// nearest to `p`: Gauss-Newton from `start`. `None` if it does not converge.
fn locate_on_patch(net: &DrapeNet, i: usize, j: usize, p: &Point, start: [f64; 2]) -> Option<[f64; 2]> {
    let [p00, p10, p01, p11] = net.cell_corners(i, j)?;
    let [mut s, mut t] = start;
    for _ in 0..PATCH_STEPS {
        let b = p00.coords * ((1.0 - s) * (1.0 - t))
            + p10.coords * (s * (1.0 - t))
            + p11.coords * (s * t)
            + p01.coords * ((1.0 - s) * t);
        let r = p.coords - b;
        let warp = (p10 - p00) * (1.0 - t) + (p11 - p01) * t;
        let weft = (p01 - p00) * (1.0 - s) + (p11 - p10) * s;
        let (a11, a12, a22) = (warp.dot(&warp), warp.dot(&weft), weft.dot(&weft));
        let (b1, b2) = (warp.dot(&r), weft.dot(&r));
        let det = a11 * a22 - a12 * a12;
        if !(det > 0.0) {
            return None;
        }
        let ds = (a22 * b1 - a12 * b2) / det;
        let dt = (a11 * b2 - a12 * b1) / det;
        s += ds;
        t += dt;
        if ds.abs().max(dt.abs()) <= PATCH_CONVERGED {
            return Some([s, t]);
        }
    }
    None
}

/// Whether two edges of a closed polygon that are not neighbours share a point.
fn polygon_crosses_itself(poly: &[[f64; 2]]) -> bool {
    let n = poly.len();
    let orient = |p: [f64; 2], q: [f64; 2], r: [f64; 2]| {
        let v = (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0]);
        (v > 0.0) as i8 - (v < 0.0) as i8
    };
    let on = |p: [f64; 2], q: [f64; 2], r: [f64; 2]| {
        p[0].min(q[0]) <= r[0] && r[0] <= p[0].max(q[0]) && p[1].min(q[1]) <= r[1] && r[1] <= p[1].max(q[1])
    };
    // Edges sorted by their lowest x: only edges whose x ranges overlap are compared.
    let mut edges: Vec<(f64, f64, usize)> =
        (0..n).map(|k| (poly[k][0].min(poly[(k + 1) % n][0]), poly[k][0].max(poly[(k + 1) % n][0]), k)).collect();
    edges.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.2.cmp(&b.2)));
    for (x, &(_, hi, a)) in edges.iter().enumerate() {
        for &(lo, _, b) in &edges[x + 1..] {
            if lo > hi {
                break;
            }
            let (a, b) = (a.min(b), a.max(b));
            if b == a + 1 || (a == 0 && b == n - 1) {
                continue;
            }
            let (p, q, r, u) = (poly[a], poly[(a + 1) % n], poly[b], poly[(b + 1) % n]);
            let (o1, o2, o3, o4) = (orient(p, q, r), orient(p, q, u), orient(r, u, p), orient(r, u, q));
            if (o1 != o2 && o3 != o4)
                || (o1 == 0 && on(p, q, r))
                || (o2 == 0 && on(p, q, u))
                || (o3 == 0 && on(r, u, p))
                || (o4 == 0 && on(r, u, q))
            {
                return true;
            }
        }
    }
    false
}

fn check_spacing(net: &DrapeNet) -> Result<(), FlatError> {
    let d = net.spacing;
    if !(d.is_finite() && d > 0.0) {
        return Err(FlatError::BadSpacing { ply: net.name.clone(), spacing: d });
    }
    Ok(())
}

/// A pattern from its regions: the bounding box from the loops.
fn pattern_of(
    net: &DrapeNet,
    regions: Vec<Region>,
    cells: usize,
    half_cells: usize,
    area: f64,
    cut: CutLine,
    anchor: [f64; 2],
) -> FlatPattern {
    let mut min = [f64::INFINITY; 2];
    let mut max = [f64::NEG_INFINITY; 2];
    for p in regions.iter().flat_map(|r| r.loops.iter()).flatten() {
        for k in 0..2 {
            min[k] = min[k].min(p[k]);
            max[k] = max[k].max(p[k]);
        }
    }
    FlatPattern {
        ply: net.name.clone(),
        spacing: net.spacing,
        origin_node: net.origin_node,
        regions,
        cells,
        half_cells,
        area,
        cut,
        margin: 0.0,
        warnings: Vec::new(),
        min,
        max,
        anchor,
    }
}

/// The triangles of a net's pattern, in grid (node index) coordinates.
struct Triangles {
    /// Corners, counter-clockwise.
    corners: Vec<[[i64; 2]; 3]>,
    /// Whether each is half of a complete cell (else it is a half cell).
    complete: Vec<bool>,
    /// Complete cells.
    cells: usize,
    /// Cells with exactly three placed corners.
    half_cells: usize,
}

/// Two triangles (split along the 00-11 diagonal) per complete cell and one per cell with
/// exactly three placed corners, in cell order.
fn triangles_of(net: &DrapeNet) -> Triangles {
    let mut t = Triangles { corners: Vec::new(), complete: Vec::new(), cells: 0, half_cells: 0 };
    for i in 0..net.nu.saturating_sub(1) {
        for j in 0..net.nv.saturating_sub(1) {
            // Counter-clockwise round the cell.
            let ring = [(i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)];
            let placed = ring.map(|(a, b)| net.node(a, b).is_some());
            let v = ring.map(|(a, b)| [a as i64, b as i64]);
            match placed.iter().filter(|&&p| p).count() {
                4 => {
                    t.corners.push([v[0], v[1], v[2]]);
                    t.corners.push([v[0], v[2], v[3]]);
                    t.complete.extend([true, true]);
                    t.cells += 1;
                }
                3 => {
                    let missing = placed.iter().position(|&p| !p).expect("one corner is missing");
                    t.corners.push([v[(missing + 1) % 4], v[(missing + 2) % 4], v[(missing + 3) % 4]]);
                    t.complete.push(false);
                    t.half_cells += 1;
                }
                _ => {}
            }
        }
    }
    t
}

/// A region of triangles traced on the integer grid (see [`trace_triangles`]).
struct TriangleRegion {
    /// Loops of grid nodes, outer (counter-clockwise) first, then holes (clockwise).
    loops: Vec<Vec<[i64; 2]>>,
    /// Complete cells.
    cells: usize,
    /// Triangles (each half a cell).
    triangles: usize,
    /// Grid coordinates of the centroid of the region's triangle nearest to the region's
    /// centroid (lowest triangle on ties).
    anchor: [f64; 2],
}

/// The boundary of the union of the triangles: one region per set of triangles joined through
/// edges, most triangles first (ties in cell order). Boundary edges are the triangles' edges
/// that no other triangle has reversed, directed with their triangle on the left (outer loops
/// counter-clockwise, holes clockwise); chained as [`trace`] chains cell edges, taking at each
/// node the sharpest left turn (which keeps pieces touching at a node apart) and splitting a
/// chain that returns to a node into loops that visit no node twice.
fn trace_triangles(tri: &Triangles) -> Vec<TriangleRegion> {
    let n = tri.corners.len();
    // Every directed edge and its triangle.
    let mut edge_of: HashMap<([i64; 2], [i64; 2]), usize> = HashMap::with_capacity(3 * n);
    for (k, c) in tri.corners.iter().enumerate() {
        for e in 0..3 {
            edge_of.insert((c[e], c[(e + 1) % 3]), k);
        }
    }
    // Regions: union-find over edges shared (reversed) by two triangles.
    let mut parent: Vec<usize> = (0..n).collect();
    let mut boundary: Vec<([i64; 2], [i64; 2], usize)> = Vec::new();
    for (k, c) in tri.corners.iter().enumerate() {
        for e in 0..3 {
            let (a, b) = (c[e], c[(e + 1) % 3]);
            match edge_of.get(&(b, a)) {
                Some(&other) => {
                    let (ra, rb) = (union_find_root(&mut parent, k), union_find_root(&mut parent, other));
                    // The lower root wins: labels do not depend on the order of the unions.
                    parent[ra.max(rb)] = ra.min(rb);
                }
                None => boundary.push((a, b, k)),
            }
        }
    }
    let roots: Vec<usize> = (0..n).map(|k| union_find_root(&mut parent, k)).collect();
    let mut region_of_root: HashMap<usize, usize> = HashMap::new();
    let mut members: Vec<Vec<usize>> = Vec::new();
    for (k, &r) in roots.iter().enumerate() {
        let id = *region_of_root.entry(r).or_insert_with(|| {
            members.push(Vec::new());
            members.len() - 1
        });
        members[id].push(k);
    }

    // Boundary edges out of each node, and which are still to chain.
    let mut out: HashMap<[i64; 2], Vec<([i64; 2], bool)>> = HashMap::new();
    for &(a, b, _) in &boundary {
        out.entry(a).or_default().push((b, true));
    }
    let mut loops_of: Vec<Vec<Vec<[i64; 2]>>> = vec![Vec::new(); members.len()];
    for &(a0, b0, k0) in &boundary {
        let fresh = out[&a0].iter().any(|&(b, f)| b == b0 && f);
        if !fresh {
            continue;
        }
        let id = region_of_root[&roots[k0]];
        let mut chain = Vec::new();
        let (mut a, mut b) = (a0, b0);
        loop {
            chain.push(a);
            let e = out.get_mut(&a).expect("edge start is a key");
            e.iter_mut().find(|x| x.0 == b && x.1).expect("the edge is still to chain").1 = false;
            // The sharpest left turn among the edges still to chain out of b.
            let din = [b[0] - a[0], b[1] - a[1]];
            let turn = |c: [i64; 2]| {
                let dout = [c[0] - b[0], c[1] - b[1]];
                let cross = (din[0] * dout[1] - din[1] * dout[0]) as f64;
                let dot = (din[0] * dout[0] + din[1] * dout[1]) as f64;
                cross.atan2(dot)
            };
            let next = out
                .get(&b)
                .and_then(|v| v.iter().filter(|x| x.1).map(|x| x.0).max_by(|&p, &q| turn(p).total_cmp(&turn(q))));
            match next {
                Some(c) => {
                    a = b;
                    b = c;
                }
                None => break,
            }
        }
        debug_assert_eq!(b, a0, "boundary chains close on their start");
        for l in split_at_repeats(chain) {
            loops_of[id].push(merge_collinear(l));
        }
    }

    let mut regions: Vec<TriangleRegion> = members
        .into_iter()
        .zip(loops_of)
        .map(|(tris, mut loops)| {
            loops.sort_by_key(|l| std::cmp::Reverse(twice_area(l) > 0));
            let centroid = |k: usize| {
                let c = tri.corners[k];
                [(c[0][0] + c[1][0] + c[2][0]) as f64 / 3.0, (c[0][1] + c[1][1] + c[2][1]) as f64 / 3.0]
            };
            let m = tris.len() as f64;
            let (sx, sy) = tris.iter().fold((0.0, 0.0), |(x, y), &k| (x + centroid(k)[0], y + centroid(k)[1]));
            let (cx, cy) = (sx / m, sy / m);
            let dist = |k: usize| (centroid(k)[0] - cx).powi(2) + (centroid(k)[1] - cy).powi(2);
            let best = *tris
                .iter()
                .min_by(|&&a, &&b| dist(a).total_cmp(&dist(b)).then(a.cmp(&b)))
                .expect("regions are not empty");
            let cells = tris.iter().filter(|&&k| tri.complete[k]).count() / 2;
            TriangleRegion { loops, cells, triangles: tris.len(), anchor: centroid(best) }
        })
        .collect();
    // Stable: equal sizes keep cell order.
    regions.sort_by_key(|r| std::cmp::Reverse(r.triangles));
    regions
}

/// Grid coordinates closer than this (in spacings) are one coordinate when cells are grown by a
/// margin: `i - u` and `k + 1 + u` can meet up to rounding.
const SNAP: f64 = 1e-9;

/// The flat pattern with a cutting allowance: the outline of the union of the complete cells,
/// each grown by `margin` (m) on every side. Corners stay square (the allowance of a staircase
/// is a staircase); pieces closer than `2 margin` merge into one piece and narrower holes close.
/// Then `area` is the area to cut (inside the grown outline), while `cells` still counts the
/// ply's cells; each region's `cells` counts the cells it contains. `margin = 0` is
/// [`flat_pattern`] (cut through the boundary nodes). Errors as [`flat_pattern`], and for a
/// negative or non-finite margin.
pub fn flat_pattern_with_margin(net: &DrapeNet, margin: f64) -> Result<FlatPattern, FlatError> {
    check_spacing(net)?;
    check_margin(net, margin)?;
    if margin == 0.0 {
        return flat_pattern(net);
    }
    let d = net.spacing;
    let (ncx, ncy) = (net.nu.saturating_sub(1), net.nv.saturating_sub(1));
    let mut mask = CellMask::new(ncx, ncy);
    for i in 0..ncx {
        for j in 0..ncy {
            if net.cell_corners(i, j).is_some() {
                mask.set(i, j);
            }
        }
    }
    let traced = trace(&mask);
    if traced.is_empty() {
        return Err(FlatError::NoCells { ply: net.name.clone() });
    }
    let (i0, j0) = (net.origin_node.0 as f64, net.origin_node.1 as f64);
    let to_flat = |[x, y]: [f64; 2]| [(x - i0) * d, (y - j0) * d];
    let regions: Vec<Region> = grown(&mask, margin / d)
        .into_iter()
        .map(|(loops, cells)| {
            let loops: Vec<Vec<[f64; 2]>> = loops.iter().map(|l| l.iter().map(|&p| to_flat(p)).collect()).collect();
            let area = loops.iter().map(|l| shoelace_area(l)).sum();
            Region { loops, cells, area }
        })
        .collect();
    let cells: usize = traced.iter().map(|r| r.cells).sum();
    // The arrow hangs on a cell of the ply itself, not on the allowance.
    let a = traced[0].anchor;
    let anchor = to_flat([a[0] as f64 + 0.5, a[1] as f64 + 0.5]);
    let area = regions.iter().map(|r| r.area).sum();
    let half_cells = triangles_of(net).half_cells;
    let mut p = pattern_of(net, regions, cells, half_cells, area, CutLine::GrownCells, anchor);
    p.margin = margin;
    Ok(p)
}

/// Sorted distinct coordinates, those within [`SNAP`] of a kept one dropped.
fn snapped(mut v: Vec<f64>) -> Vec<f64> {
    v.sort_by(f64::total_cmp);
    let mut out: Vec<f64> = Vec::with_capacity(v.len());
    for x in v {
        if out.last().is_none_or(|&l| x - l >= SNAP) {
            out.push(x);
        }
    }
    out
}

/// Index in `axis` (from [`snapped`]) of a coordinate that was snapped into it.
fn snap_index(axis: &[f64], x: f64) -> usize {
    axis.partition_point(|&a| a < x - SNAP)
}

/// Loops (grid units) and cell counts of the union of the filled cells each grown by `u` on
/// every side: the rectangles' edges make a compressed grid, whose covered cells (by a 2-D
/// difference array) are traced like the cells of the net.
fn grown(mask: &CellMask, u: f64) -> Vec<(Vec<Vec<[f64; 2]>>, usize)> {
    let filled: Vec<[usize; 2]> = (0..mask.nx)
        .flat_map(|i| (0..mask.ny).map(move |j| [i, j]))
        .filter(|&[i, j]| mask.get(i as i64, j as i64))
        .collect();
    let grow = |k: usize| [k as f64 - u, k as f64 + 1.0 + u];
    let xs = snapped(filled.iter().flat_map(|c| grow(c[0])).collect());
    let ys = snapped(filled.iter().flat_map(|c| grow(c[1])).collect());
    let (nx, ny) = (xs.len(), ys.len());
    let mut cover = vec![0i64; nx * ny];
    for &[i, j] in &filled {
        let ([x0, x1], [y0, y1]) = (grow(i), grow(j));
        let (a0, a1, b0, b1) = (snap_index(&xs, x0), snap_index(&xs, x1), snap_index(&ys, y0), snap_index(&ys, y1));
        cover[a0 * ny + b0] += 1;
        cover[a1 * ny + b0] -= 1;
        cover[a0 * ny + b1] -= 1;
        cover[a1 * ny + b1] += 1;
    }
    for a in 0..nx {
        for b in 0..ny {
            let left = if a > 0 { cover[(a - 1) * ny + b] } else { 0 };
            let below = if b > 0 { cover[a * ny + b - 1] } else { 0 };
            let diag = if a > 0 && b > 0 { cover[(a - 1) * ny + b - 1] } else { 0 };
            cover[a * ny + b] += left + below - diag;
        }
    }
    let mut big = CellMask::new(nx - 1, ny - 1);
    for a in 0..nx - 1 {
        for b in 0..ny - 1 {
            if cover[a * ny + b] > 0 {
                big.set(a, b);
            }
        }
    }
    let regions = trace(&big);
    // Which grown region holds each cell: look up the compressed cell under the cell's centre.
    let mut region_of = vec![usize::MAX; (nx - 1) * (ny - 1)];
    for (k, r) in regions.iter().enumerate() {
        for c in &r.members {
            region_of[c[0] as usize * (ny - 1) + c[1] as usize] = k;
        }
    }
    let mut counts = vec![0usize; regions.len()];
    for &[i, j] in &filled {
        let a = xs.partition_point(|&x| x <= i as f64 + 0.5) - 1;
        let b = ys.partition_point(|&y| y <= j as f64 + 0.5) - 1;
        counts[region_of[a * (ny - 1) + b]] += 1;
    }
    regions
        .into_iter()
        .zip(counts)
        .map(|(r, n)| {
            (r.loops.iter().map(|l| l.iter().map(|&[a, b]| [xs[a as usize], ys[b as usize]]).collect()).collect(), n)
        })
        .collect()
}

/// Signed shoelace area of a closed loop (positive when counter-clockwise).
pub fn shoelace_area(loop_: &[[f64; 2]]) -> f64 {
    let n = loop_.len();
    let mut twice = 0.0;
    for k in 0..n {
        let (a, b) = (loop_[k], loop_[(k + 1) % n]);
        twice += a[0] * b[1] - b[0] * a[1];
    }
    0.5 * twice
}

/// Which cells of an `nx x ny` grid are filled; cell (i, j) is the unit square
/// `[i, i+1] x [j, j+1]` of grid (node index) coordinates.
#[derive(Debug, Clone)]
pub struct CellMask {
    nx: usize,
    ny: usize,
    filled: Vec<bool>,
}

impl CellMask {
    /// An empty mask.
    pub fn new(nx: usize, ny: usize) -> Self {
        CellMask { nx, ny, filled: vec![false; nx * ny] }
    }
    /// Fill cell (i, j).
    pub fn set(&mut self, i: usize, j: usize) {
        self.filled[i * self.ny + j] = true;
    }
    /// Whether cell (i, j) is filled; cells outside the grid are empty.
    pub fn get(&self, i: i64, j: i64) -> bool {
        i >= 0
            && j >= 0
            && (i as usize) < self.nx
            && (j as usize) < self.ny
            && self.filled[i as usize * self.ny + j as usize]
    }
}

/// A traced region on the integer grid (see [`trace`]).
#[derive(Debug, Clone, PartialEq)]
pub struct GridRegion {
    /// Loops of grid vertices, outer (counter-clockwise) first, then holes (clockwise).
    pub loops: Vec<Vec<[i64; 2]>>,
    /// Number of cells.
    pub cells: usize,
    /// The cell of the region nearest to its centroid (lowest grid order on ties).
    pub anchor: [i64; 2],
    /// The region's cells.
    pub members: Vec<[i64; 2]>,
}

/// Directions of boundary edges, counter-clockwise order: +x, +y, -x, -y.
const DIRS: [[i64; 2]; 4] = [[1, 0], [0, 1], [-1, 0], [0, -1]];

/// The cell on the left of the unit edge leaving vertex `v` in direction `dir` (the edge's cell).
fn left_cell(v: [i64; 2], dir: usize) -> [i64; 2] {
    match dir {
        0 => [v[0], v[1]],
        1 => [v[0] - 1, v[1]],
        2 => [v[0] - 1, v[1] - 1],
        _ => [v[0], v[1] - 1],
    }
}

/// Exact outline of the filled cells of `mask`: one [`GridRegion`] per edge-connected set of
/// cells, largest first (ties by the region's first cell in grid order).
///
/// Every boundary edge is directed with its cell on the left, so outer boundaries run
/// counter-clockwise and holes clockwise. Edges are chained preferring a left turn, which keeps
/// two cells touching only at a corner apart; a chain that still returns to a vertex it already
/// visited (a hole pinched against the outer boundary) is split there into separate loops, so no
/// loop visits a vertex twice.
pub fn trace(mask: &CellMask) -> Vec<GridRegion> {
    // Edge-connected components (breadth-first, in grid order: deterministic).
    let (nx, ny) = (mask.nx, mask.ny);
    let mut label = vec![usize::MAX; nx * ny];
    let mut members: Vec<Vec<[i64; 2]>> = Vec::new();
    for start in 0..nx * ny {
        if !mask.filled[start] || label[start] != usize::MAX {
            continue;
        }
        let id = members.len();
        let mut cells = vec![[(start / ny) as i64, (start % ny) as i64]];
        label[start] = id;
        let mut k = 0;
        while k < cells.len() {
            let c = cells[k];
            k += 1;
            for d in DIRS {
                let (a, b) = (c[0] + d[0], c[1] + d[1]);
                if mask.get(a, b) && label[a as usize * ny + b as usize] == usize::MAX {
                    label[a as usize * ny + b as usize] = id;
                    cells.push([a, b]);
                }
            }
        }
        members.push(cells);
    }

    // Directed boundary edges, keyed by their start vertex: out[v] has bit `dir` set.
    let mut out: HashMap<[i64; 2], u8> = HashMap::new();
    let mut starts: Vec<([i64; 2], usize)> = Vec::new();
    for i in 0..nx as i64 {
        for j in 0..ny as i64 {
            if !mask.get(i, j) {
                continue;
            }
            // (start vertex, direction, neighbour across the edge)
            let edges = [
                ([i, j], 0, [i, j - 1]),
                ([i + 1, j], 1, [i + 1, j]),
                ([i + 1, j + 1], 2, [i, j + 1]),
                ([i, j + 1], 3, [i - 1, j]),
            ];
            for (v, dir, nb) in edges {
                if !mask.get(nb[0], nb[1]) {
                    *out.entry(v).or_insert(0) |= 1 << dir;
                    starts.push((v, dir));
                }
            }
        }
    }

    let mut loops_of: Vec<Vec<Vec<[i64; 2]>>> = vec![Vec::new(); members.len()];
    for (v0, d0) in starts {
        if out[&v0] & (1 << d0) == 0 {
            continue; // already chained
        }
        let cell = left_cell(v0, d0);
        let id = label[cell[0] as usize * ny + cell[1] as usize];
        let mut chain = Vec::new();
        let (mut v, mut dir) = (v0, d0);
        loop {
            chain.push(v);
            *out.get_mut(&v).expect("edge start is a key") &= !(1 << dir);
            v = [v[0] + DIRS[dir][0], v[1] + DIRS[dir][1]];
            let bits = out.get(&v).copied().unwrap_or(0);
            // Left turn, then straight on, then right turn (a U-turn cannot be a boundary).
            match [(dir + 1) % 4, dir, (dir + 3) % 4].into_iter().find(|&d| bits & (1 << d) != 0) {
                Some(d) => dir = d,
                None => break,
            }
        }
        debug_assert_eq!(v, v0, "boundary chains close on their start");
        for l in split_at_repeats(chain) {
            loops_of[id].push(merge_collinear(l));
        }
    }

    let mut regions: Vec<GridRegion> = members
        .into_iter()
        .zip(loops_of)
        .map(|(cells, mut loops)| {
            // Outer boundary (the one loop with positive area) first; holes keep trace order.
            loops.sort_by_key(|l| std::cmp::Reverse(twice_area(l) > 0));
            let n = cells.len() as f64;
            let (sx, sy) = cells.iter().fold((0.0, 0.0), |(x, y), c| (x + c[0] as f64, y + c[1] as f64));
            let (cx, cy) = (sx / n, sy / n);
            let dist = |c: &[i64; 2]| (c[0] as f64 - cx).powi(2) + (c[1] as f64 - cy).powi(2);
            let anchor =
                *cells.iter().min_by(|a, b| dist(a).total_cmp(&dist(b)).then(a.cmp(b))).expect("regions are not empty");
            GridRegion { loops, cells: cells.len(), anchor, members: cells }
        })
        .collect();
    // Stable: equal sizes keep grid order.
    regions.sort_by_key(|r| std::cmp::Reverse(r.cells));
    regions
}

/// Twice the signed area of an integer loop (exact).
pub fn twice_area(l: &[[i64; 2]]) -> i64 {
    let n = l.len();
    (0..n).map(|k| l[k][0] * l[(k + 1) % n][1] - l[(k + 1) % n][0] * l[k][1]).sum()
}

/// Split a closed chain of vertices into loops that visit no vertex twice: whenever the walk
/// comes back to a vertex still on the stack, the stretch since then is a closed loop of its own.
fn split_at_repeats(chain: Vec<[i64; 2]>) -> Vec<Vec<[i64; 2]>> {
    let mut loops = Vec::new();
    let mut stack: Vec<[i64; 2]> = Vec::with_capacity(chain.len());
    let mut at: HashMap<[i64; 2], usize> = HashMap::new();
    for v in chain {
        if let Some(&p) = at.get(&v) {
            let piece: Vec<[i64; 2]> = stack.drain(p..).collect();
            for u in &piece {
                at.remove(u);
            }
            loops.push(piece);
        }
        at.insert(v, stack.len());
        stack.push(v);
    }
    loops.push(stack);
    loops
}

/// Drop vertices where the loop goes straight on.
fn merge_collinear(l: Vec<[i64; 2]>) -> Vec<[i64; 2]> {
    let n = l.len();
    let dir = |a: [i64; 2], b: [i64; 2]| [(b[0] - a[0]).signum(), (b[1] - a[1]).signum()];
    (0..n).filter(|&k| dir(l[(k + n - 1) % n], l[k]) != dir(l[k], l[(k + 1) % n])).map(|k| l[k]).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn mask_of(nx: usize, ny: usize, cells: &[(usize, usize)]) -> CellMask {
        let mut m = CellMask::new(nx, ny);
        for &(i, j) in cells {
            m.set(i, j);
        }
        m
    }

    /// Loops are closed axis-aligned polylines whose vertices are all corners and distinct.
    fn check_loop(l: &[[i64; 2]]) {
        let n = l.len();
        assert!(n >= 4, "{l:?}");
        let mut seen = std::collections::HashSet::new();
        for k in 0..n {
            assert!(seen.insert(l[k]), "vertex {:?} repeated in {l:?}", l[k]);
            let (a, b, c) = (l[(k + n - 1) % n], l[k], l[(k + 1) % n]);
            assert!(a[0] == b[0] || a[1] == b[1], "not axis aligned");
            let (u, w) = ([b[0] - a[0], b[1] - a[1]], [c[0] - b[0], c[1] - b[1]]);
            assert_ne!(u[0] * w[1] - u[1] * w[0], 0, "vertex {b:?} is not a corner of {l:?}");
        }
    }

    #[test]
    fn square_ring_and_pinch() {
        let r = trace(&mask_of(3, 3, &[(0, 0), (0, 1), (0, 2), (1, 0), (1, 2), (2, 0), (2, 1), (2, 2)]));
        assert_eq!(r.len(), 1);
        assert_eq!(r[0].loops, vec![vec![[0, 0], [3, 0], [3, 3], [0, 3]], vec![[1, 1], [1, 2], [2, 2], [2, 1]]]);
        // Two cells touching at a corner: two regions, two squares.
        let r = trace(&mask_of(2, 2, &[(0, 0), (1, 1)]));
        assert_eq!(r.len(), 2);
        assert_eq!(r[0].loops, vec![vec![[0, 0], [1, 0], [1, 1], [0, 1]]]);
        assert_eq!(r[1].loops, vec![vec![[1, 1], [2, 1], [2, 2], [1, 2]]]);
        // A hole pinched against the outside at a corner: outer and hole split apart.
        let r = trace(&mask_of(3, 3, &[(0, 0), (0, 1), (0, 2), (1, 0), (1, 2), (2, 0), (2, 1)]));
        assert_eq!(r.len(), 1);
        assert_eq!(r[0].loops.len(), 2);
        assert_eq!(twice_area(&r[0].loops[0]), 2 * 8);
        assert_eq!(twice_area(&r[0].loops[1]), -2);
        r[0].loops.iter().for_each(|l| check_loop(l));
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(200))]
        /// Random masks: loops simple, one counter-clockwise outer per region, signed areas sum to
        /// the cell count, and every boundary edge of the mask is used exactly once.
        #[test]
        fn random_masks(nx in 1usize..9, ny in 1usize..9, bits in proptest::collection::vec(any::<bool>(), 64)) {
            let mut m = CellMask::new(nx, ny);
            let mut count = 0;
            for i in 0..nx { for j in 0..ny { if bits[i * 8 + j] { m.set(i, j); count += 1; } } }
            let regions = trace(&m);
            prop_assert_eq!(regions.iter().map(|r| r.cells).sum::<usize>(), count);
            let mut edges = 0;
            for r in &regions {
                let areas: Vec<i64> = r.loops.iter().map(|l| twice_area(l)).collect();
                prop_assert_eq!(areas.iter().sum::<i64>(), 2 * r.cells as i64);
                prop_assert!(areas[0] > 0);
                prop_assert!(areas[1..].iter().all(|&a| a < 0), "{:?}", areas);
                for l in &r.loops {
                    check_loop(l);
                    edges += (0..l.len()).map(|k| (l[k][0] - l[(k + 1) % l.len()][0]).abs() + (l[k][1] - l[(k + 1) % l.len()][1]).abs()).sum::<i64>();
                }
            }
            let mut expect = 0;
            for i in 0..nx as i64 { for j in 0..ny as i64 { if m.get(i, j) {
                expect += DIRS.iter().filter(|d| !m.get(i + d[0], j + d[1])).count() as i64;
            } } }
            prop_assert_eq!(edges, expect);
        }
    }
}
