//! Sheet features of seed 000 on the warp/weft grid: reinforced bands, a seam (two sheets
//! stitched along a weft line), a fold (a weft line with a restoring stiffness), cuts (fibre
//! links removed along a polyline) and the blank's shape (a polygon the sheet is cut to).
//!
//! [`SheetFeatures`] describes them in the sheet's own terms (fabric coordinates: u along the
//! warp and v along the weft, metres from the origin node); [`SheetFeatures::layout`] turns them
//! into a [`SheetLayout`] on a grid: which fibre links, cells and bending triples are gone, which
//! nodes are stitched to which, the zero-length springs of a fold, and the factor each element's
//! tension, shear, bending and weight is multiplied by. The energy terms read the layout through
//! [`super::energy::Grid`].
use crate::geometry::{Point, ToolSurface, Vector};
use crate::kinematic::provenance::SheetFeature;
use crate::kinematic::{DrapeNet, NodeStatus};
use std::fmt;

/// Multipliers of a reinforced region's properties.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Factors {
    /// Tensile rigidity.
    pub tension: f64,
    /// Shear rigidity.
    pub shear: f64,
    /// Flexural rigidity.
    pub bending: f64,
    /// Weight (areal mass).
    pub weight: f64,
}

impl Factors {
    /// No change.
    pub const ONE: Factors = Factors { tension: 1.0, shear: 1.0, bending: 1.0, weight: 1.0 };
}

/// A region of the sheet, in fabric coordinates (u along the warp, v along the weft, metres from
/// the origin node).
#[derive(Debug, Clone, PartialEq)]
pub enum Region {
    /// A band this wide along every edge of the sheet.
    Edges(f64),
    /// Bands this wide centred on the two fibre lines through the origin node (u = 0, v = 0).
    Axes(f64),
    /// The rectangle u in [u0, u1], v in [v0, v1].
    Rectangle {
        /// u range.
        u: [f64; 2],
        /// v range.
        v: [f64; 2],
    },
}

/// A reinforced region: its properties multiplied by `factors`.
#[derive(Debug, Clone, PartialEq)]
pub struct Reinforcement {
    /// Where.
    pub region: Region,
    /// By how much.
    pub factors: Factors,
}

/// Two sheets of `rows[0]` and `rows[1]` node rows (along the warp) side by side in one grid,
/// stitched along a weft line `allowance` cells in from their facing edges; the allowances hang
/// as flaps on one side of the sheet.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Seam {
    /// Node rows of the first and second sheet (their sum is the grid's).
    pub rows: [usize; 2],
    /// Seam allowance, cells (at least 1).
    pub allowance: usize,
}

/// A fold along the weft line `row`: no bending across it, and zero-length springs of
/// `stiffness` (N/m per metre of fold) between the rows on either side, which the sheet stretches
/// when it starts unfolded [000 eq. 28].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fold {
    /// The fold's node row (along the warp).
    pub row: usize,
    /// Restoring stiffness, N/m per metre of fold line.
    pub stiffness: f64,
}

/// Fibre links removed where a polyline (fabric coordinates) crosses them.
#[derive(Debug, Clone, PartialEq)]
pub struct Cut {
    /// The polyline's points (u, v), metres from the origin node.
    pub points: Vec<[f64; 2]>,
}

/// A sheet's features.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SheetFeatures {
    /// Reinforced regions (where several apply, the last one given wins).
    pub reinforcements: Vec<Reinforcement>,
    /// Two sheets stitched together.
    pub seam: Option<Seam>,
    /// A fold.
    pub fold: Option<Fold>,
    /// Cuts.
    pub cuts: Vec<Cut>,
    /// The blank's outline in fabric coordinates (u, v), metres from the origin node: the sheet
    /// is cut to it ([`blank_fractions`]).
    pub blank: Option<Vec<[f64; 2]>>,
}

/// A cell with less of its area inside the blank than this share is left out (a sliver the
/// blank's edge grazes carries no fabric to speak of, and its nodes would hang by nothing).
pub const BLANK_SLIVER: f64 = 1e-6;

/// The area of the polygon `p` (either orientation), m^2.
fn polygon_area(p: &[[f64; 2]]) -> f64 {
    let n = p.len();
    0.5 * (0..n).map(|k| p[k][0] * p[(k + 1) % n][1] - p[(k + 1) % n][0] * p[k][1]).sum::<f64>().abs()
}

/// What is wrong with a polygon that must enclose an area round a point.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum PolygonFault {
    /// Fewer than three corners.
    TooFew,
    /// A corner that is not a finite number.
    NonFinite,
    /// Its corners enclose no area.
    NoArea,
    /// The point lies outside it.
    Outside,
}

/// Check a polygon that must enclose an area with `inside` in it: its area, m^2, or what is wrong
/// (the caller words it for its field).
pub(crate) fn polygon_round(p: &[[f64; 2]], inside: (f64, f64)) -> Result<f64, PolygonFault> {
    if p.len() < 3 {
        return Err(PolygonFault::TooFew);
    }
    if p.iter().flatten().any(|x| !x.is_finite()) {
        return Err(PolygonFault::NonFinite);
    }
    let area = polygon_area(p);
    if !(area > 0.0) {
        return Err(PolygonFault::NoArea);
    }
    if !point_in_polygon(inside, p) {
        return Err(PolygonFault::Outside);
    }
    Ok(area)
}

/// Check a blank outline: three points or more, finite, enclosing an area, with the origin node
/// (0, 0) inside. Its area, m^2.
pub fn check_blank(blank: &[[f64; 2]]) -> Result<f64, SheetError> {
    polygon_round(blank, (0.0, 0.0)).map_err(|fault| {
        SheetError(match fault {
            PolygonFault::TooFew => format!("a blank needs at least three corners (u, v), got {}", blank.len()),
            PolygonFault::NonFinite => "the blank's corners must be finite numbers".into(),
            PolygonFault::NoArea => "the blank encloses no area: give its corners in order round it".into(),
            PolygonFault::Outside => "the blank must contain the origin node (0, 0): give its corners in fabric coordinates from the origin node".into(),
        })
    })
}

/// Whether `q` lies inside the polygon `p` (even-odd rule).
pub(crate) fn point_in_polygon(q: (f64, f64), p: &[[f64; 2]]) -> bool {
    let mut inside = false;
    let n = p.len();
    for k in 0..n {
        let (a, b) = (p[k], p[(k + 1) % n]);
        if (a[1] > q.1) != (b[1] > q.1) && q.0 < a[0] + (q.1 - a[1]) / (b[1] - a[1]) * (b[0] - a[0]) {
            inside = !inside;
        }
    }
    inside
}

/// The share of the square [u0, u0 + d] x [v0, v0 + d] inside the polygon `blank`: the polygon
/// clipped by the square (Sutherland-Hodgman against the square's four sides, which holds for
/// any simple polygon clipped by a convex window), its area over d^2.
fn square_share(blank: &[[f64; 2]], u0: f64, v0: f64, d: f64) -> f64 {
    let mut poly: Vec<[f64; 2]> = blank.to_vec();
    // Each side as (axis, bound, keep the side above the bound).
    for (axis, bound, above) in [(0, u0, true), (0, u0 + d, false), (1, v0, true), (1, v0 + d, false)] {
        if poly.is_empty() {
            break;
        }
        let inside = |p: &[f64; 2]| if above { p[axis] >= bound } else { p[axis] <= bound };
        let mut out = Vec::with_capacity(poly.len() + 4);
        for k in 0..poly.len() {
            let (a, b) = (poly[k], poly[(k + 1) % poly.len()]);
            if inside(&a) {
                out.push(a);
            }
            if inside(&a) != inside(&b) {
                let t = (bound - a[axis]) / (b[axis] - a[axis]);
                out.push([a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])]);
            }
        }
        poly = out;
    }
    if poly.len() < 3 {
        return 0.0;
    }
    let share = polygon_area(&poly) / (d * d);
    // A cell inside the blank is whole, not whole to rounding.
    if share > 1.0 - BLANK_ROUNDING {
        1.0
    } else {
        share.max(0.0)
    }
}

/// Shares within this of 1 are a whole cell (the clipped area's rounding).
const BLANK_ROUNDING: f64 = 1e-9;

/// Per cell of an `nu x nv` grid of spacing `d` with its origin node at `origin` (at
/// `i * (nv - 1) + j`): the share of its area inside the blank, 0 for a sliver below
/// [`BLANK_SLIVER`].
pub fn blank_fractions(blank: &[[f64; 2]], nu: usize, nv: usize, d: f64, origin: (usize, usize)) -> Vec<f64> {
    let (i0, j0) = (origin.0 as f64, origin.1 as f64);
    let mut f = Vec::with_capacity(nu.saturating_sub(1) * nv.saturating_sub(1));
    for i in 0..nu.saturating_sub(1) {
        for j in 0..nv.saturating_sub(1) {
            let share = square_share(blank, (i as f64 - i0) * d, (j as f64 - j0) * d, d);
            f.push(if share < BLANK_SLIVER { 0.0 } else { share });
        }
    }
    f
}

/// Per node of the grid: whether a cell with fabric of the blank has it as a corner (the nodes
/// of the blank; the others are cut away).
pub fn blank_nodes(fractions: &[f64], nu: usize, nv: usize) -> Vec<bool> {
    let mut keep = vec![false; nu * nv];
    for i in 0..nu.saturating_sub(1) {
        for j in 0..nv.saturating_sub(1) {
            if fractions[i * (nv - 1) + j] > 0.0 {
                for k in [i * nv + j, i * nv + j + 1, (i + 1) * nv + j, (i + 1) * nv + j + 1] {
                    keep[k] = true;
                }
            }
        }
    }
    keep
}

/// Why features do not fit a grid.
#[derive(Debug, Clone, PartialEq)]
pub struct SheetError(pub String);

impl fmt::Display for SheetError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for SheetError {}

/// The features on a grid: what the energy terms skip, share or multiply.
#[derive(Debug, Clone, PartialEq)]
pub struct SheetLayout {
    nu: usize,
    nv: usize,
    /// Warp link (i, j)-(i+1, j) removed, at `i * nv + j`.
    warp_cut: Vec<bool>,
    /// Weft link (i, j)-(i, j+1) removed, at `i * nv + j`.
    weft_cut: Vec<bool>,
    /// Cell (i, j) removed, at `i * (nv - 1) + j`.
    cell_cut: Vec<bool>,
    /// No warp bending triple centred on node `i * nv + j` (a fold or seam line).
    warp_hinge: Vec<bool>,
    /// Per node, the node whose freedoms it shares (itself unless stitched).
    pub stitched: Vec<usize>,
    /// Zero-length springs (node a, node b, stiffness N/m), a < b.
    pub springs: Vec<(usize, usize, f64)>,
    /// Factors per node (weight and bending of the triples centred there) ...
    node_factors: Vec<Factors>,
    /// ... and per cell (shear, and the weight of its area) and link midpoint (tension).
    cell_factors: Vec<Factors>,
    warp_link_factors: Vec<Factors>,
    weft_link_factors: Vec<Factors>,
}

impl SheetFeatures {
    /// The kinds of feature the sheet has (what [`crate::kinematic::Provenance::sheet_features`]
    /// records).
    pub fn kinds(&self) -> Vec<SheetFeature> {
        [
            (!self.reinforcements.is_empty(), SheetFeature::Reinforcement),
            (self.seam.is_some(), SheetFeature::Seam),
            (self.fold.is_some(), SheetFeature::Fold),
            (!self.cuts.is_empty(), SheetFeature::Cut),
            (self.blank.is_some(), SheetFeature::Blank),
        ]
        .into_iter()
        .filter_map(|(there, kind)| there.then_some(kind))
        .collect()
    }

    /// Whether there is anything to lay out.
    pub fn is_empty(&self) -> bool {
        self.kinds().is_empty()
    }

    /// The features on an `nu x nv` grid of spacing `d` with its origin node at `origin`.
    pub fn layout(&self, nu: usize, nv: usize, d: f64, origin: (usize, usize)) -> Result<SheetLayout, SheetError> {
        let mut l = SheetLayout {
            nu,
            nv,
            warp_cut: vec![false; nu * nv],
            weft_cut: vec![false; nu * nv],
            cell_cut: vec![false; nu.saturating_sub(1) * nv.saturating_sub(1)],
            warp_hinge: vec![false; nu * nv],
            stitched: (0..nu * nv).collect(),
            springs: Vec::new(),
            node_factors: vec![Factors::ONE; nu * nv],
            cell_factors: vec![Factors::ONE; nu.saturating_sub(1) * nv.saturating_sub(1)],
            warp_link_factors: vec![Factors::ONE; nu * nv],
            weft_link_factors: vec![Factors::ONE; nu * nv],
        };
        let (i0, j0) = (origin.0 as f64, origin.1 as f64);
        let uv = |i: f64, j: f64| ((i - i0) * d, (j - j0) * d);
        // Reinforcements, by the element's centre in fabric coordinates.
        let extent = (uv(0.0, 0.0), uv((nu - 1) as f64, (nv - 1) as f64));
        let factors_at = |u: f64, v: f64| -> Factors {
            let mut f = Factors::ONE;
            for r in &self.reinforcements {
                if r.region.contains(u, v, extent) {
                    f = r.factors;
                }
            }
            f
        };
        if !self.reinforcements.is_empty() {
            for i in 0..nu {
                for j in 0..nv {
                    let k = i * nv + j;
                    let (u, v) = uv(i as f64, j as f64);
                    l.node_factors[k] = factors_at(u, v);
                    let (u, v) = uv(i as f64 + 0.5, j as f64);
                    l.warp_link_factors[k] = factors_at(u, v);
                    let (u, v) = uv(i as f64, j as f64 + 0.5);
                    l.weft_link_factors[k] = factors_at(u, v);
                    if i + 1 < nu && j + 1 < nv {
                        let (u, v) = uv(i as f64 + 0.5, j as f64 + 0.5);
                        l.cell_factors[i * (nv - 1) + j] = factors_at(u, v);
                    }
                }
            }
        }
        if let Some(seam) = self.seam {
            let [a, b] = seam.rows;
            if a + b != nu {
                return Err(SheetError(format!(
                    "the seam's sheets have {a} + {b} = {} node rows but the grid has {nu}: make them add up",
                    a + b
                )));
            }
            if seam.allowance == 0 || seam.allowance + 1 >= a.min(b) {
                return Err(SheetError(format!(
                    "a seam allowance of {} cells does not fit sheets of {a} and {b} rows: give at least 1 and fewer than the smaller sheet's cells",
                    seam.allowance
                )));
            }
            // No link, cell or bending triple crosses from one sheet to the other.
            for j in 0..nv {
                l.warp_cut[(a - 1) * nv + j] = true;
            }
            if nv > 1 {
                for j in 0..nv - 1 {
                    l.cell_cut[(a - 1) * (nv - 1) + j] = true;
                }
            }
            // The stitch line: row a-1-allowance of the first sheet and row a+allowance of the
            // second share their freedoms.
            let (ra, rb) = (a - 1 - seam.allowance, a + seam.allowance);
            for j in 0..nv {
                l.stitched[rb * nv + j] = ra * nv + j;
            }
        }
        if let Some(fold) = self.fold {
            if fold.row == 0 || fold.row >= nu.saturating_sub(1) {
                return Err(SheetError(format!(
                    "a fold at row {} has no row on one side of it: give a row between 1 and {}",
                    fold.row,
                    nu.saturating_sub(2)
                )));
            }
            if !(fold.stiffness.is_finite() && fold.stiffness >= 0.0) {
                return Err(SheetError(format!(
                    "fold stiffness {} must be a non-negative number (N/m per metre)",
                    fold.stiffness
                )));
            }
            for j in 0..nv {
                l.warp_hinge[fold.row * nv + j] = true;
                // Each spring stands for the fold's length beside its node column (half at the
                // sheet's edges).
                let share = if j == 0 || j + 1 == nv { 0.5 } else { 1.0 };
                let k = fold.stiffness * d * share;
                l.springs.push(((fold.row - 1) * nv + j, (fold.row + 1) * nv + j, k));
            }
        }
        for cut in &self.cuts {
            if cut.points.len() < 2 {
                return Err(SheetError("a cut needs at least two points".into()));
            }
            let pts: Vec<(f64, f64)> = cut.points.iter().map(|p| (p[0], p[1])).collect();
            let crosses = |a: (f64, f64), b: (f64, f64)| pts.windows(2).any(|w| segments_cross(a, b, w[0], w[1]));
            for i in 0..nu {
                for j in 0..nv {
                    let k = i * nv + j;
                    let p = uv(i as f64, j as f64);
                    if i + 1 < nu && crosses(p, uv(i as f64 + 1.0, j as f64)) {
                        l.warp_cut[k] = true;
                    }
                    if j + 1 < nv && crosses(p, uv(i as f64, j as f64 + 1.0)) {
                        l.weft_cut[k] = true;
                    }
                }
            }
            // A cell whose links are cut is cut open: it holds no shear.
            // (The blank's cells are laid out after the cuts, below.)
            for i in 0..nu.saturating_sub(1) {
                for j in 0..nv.saturating_sub(1) {
                    let k = i * nv + j;
                    if l.warp_cut[k] || l.warp_cut[k + 1] || l.weft_cut[k] || l.weft_cut[k + nv] {
                        l.cell_cut[i * (nv - 1) + j] = true;
                    }
                }
            }
        }
        if let Some(blank) = &self.blank {
            check_blank(blank)?;
            let fractions = blank_fractions(blank, nu, nv, d, origin);
            let cv = nv.saturating_sub(1);
            let share = |i: isize, j: isize| -> Option<f64> {
                (i >= 0 && j >= 0 && (i as usize) + 1 < nu && (j as usize) + 1 < nv)
                    .then(|| fractions[i as usize * cv + j as usize])
            };
            // An element's tributary width counts the cells about it that are there (a cut
            // cell is not); of those, the blank holds the mean share.
            let mean = |cells: &[(isize, isize)]| {
                let s: Vec<f64> = cells.iter().filter_map(|&(i, j)| share(i, j)).filter(|f| *f > 0.0).collect();
                // No cell about it: no width either, whatever its factor.
                if s.is_empty() {
                    1.0
                } else {
                    s.iter().sum::<f64>() / s.len() as f64
                }
            };
            for i in 0..nu {
                for j in 0..nv {
                    let (a, b) = (i as isize, j as isize);
                    let k = i * nv + j;
                    let node = mean(&[(a - 1, b - 1), (a - 1, b), (a, b - 1), (a, b)]);
                    l.node_factors[k].bending *= node;
                    l.warp_link_factors[k].tension *= mean(&[(a, b - 1), (a, b)]);
                    l.weft_link_factors[k].tension *= mean(&[(a - 1, b), (a, b)]);
                    if let Some(f) = share(a, b) {
                        let c = &mut l.cell_factors[i * cv + j];
                        c.shear *= f;
                        c.weight *= f;
                        if f == 0.0 {
                            l.cell_cut[i * cv + j] = true;
                        }
                    }
                }
            }
        }
        Ok(l)
    }
}

impl Region {
    /// Whether (u, v) lies in the region of a sheet spanning `extent` ((u_min, v_min), (u_max,
    /// v_max)).
    fn contains(&self, u: f64, v: f64, extent: ((f64, f64), (f64, f64))) -> bool {
        let ((u0, v0), (u1, v1)) = extent;
        match *self {
            Region::Edges(w) => u - u0 < w || u1 - u < w || v - v0 < w || v1 - v < w,
            Region::Axes(w) => u.abs() < 0.5 * w || v.abs() < 0.5 * w,
            Region::Rectangle { u: [a, b], v: [c, e] } => u >= a && u <= b && v >= c && v <= e,
        }
    }
}

/// Whether the segments a-b and c-e cross (touching counts).
fn segments_cross(a: (f64, f64), b: (f64, f64), c: (f64, f64), e: (f64, f64)) -> bool {
    let orient = |p: (f64, f64), q: (f64, f64), r: (f64, f64)| (q.0 - p.0) * (r.1 - p.1) - (q.1 - p.1) * (r.0 - p.0);
    let (d1, d2) = (orient(c, e, a), orient(c, e, b));
    let (d3, d4) = (orient(a, b, c), orient(a, b, e));
    d1 * d2 <= 0.0 && d3 * d4 <= 0.0 && !(d1 == 0.0 && d2 == 0.0)
}

impl SheetLayout {
    /// Whether the warp link (i, j)-(i+1, j) is removed.
    #[inline]
    pub fn warp_cut(&self, i: usize, j: usize) -> bool {
        self.warp_cut[i * self.nv + j]
    }
    /// Whether the weft link (i, j)-(i, j+1) is removed.
    #[inline]
    pub fn weft_cut(&self, i: usize, j: usize) -> bool {
        self.weft_cut[i * self.nv + j]
    }
    /// Whether cell (i, j) is removed.
    #[inline]
    pub fn cell_cut(&self, i: usize, j: usize) -> bool {
        self.cell_cut[i * (self.nv - 1) + j]
    }
    /// The cells removed, as `[i, j]`, sorted (what [`crate::kinematic::Provenance::cut_cells`] records).
    pub fn cut_cells(&self) -> Vec<[usize; 2]> {
        let cv = self.nv.saturating_sub(1);
        self.cell_cut.iter().enumerate().filter(|(_, c)| **c).map(|(k, _)| [k / cv, k % cv]).collect()
    }
    /// Whether no warp bending triple is centred on node (i, j).
    #[inline]
    pub fn warp_hinge(&self, i: usize, j: usize) -> bool {
        self.warp_hinge[i * self.nv + j]
    }
    /// Factors of node (i, j) (bending of the triples centred there).
    #[inline]
    pub fn node(&self, i: usize, j: usize) -> &Factors {
        &self.node_factors[i * self.nv + j]
    }
    /// Factors of cell (i, j) (shear, weight).
    #[inline]
    pub fn cell(&self, i: usize, j: usize) -> &Factors {
        &self.cell_factors[i * (self.nv - 1) + j]
    }
    /// Factors of the warp link (i, j)-(i+1, j) (tension).
    #[inline]
    pub fn warp_link(&self, i: usize, j: usize) -> &Factors {
        &self.warp_link_factors[i * self.nv + j]
    }
    /// Factors of the weft link (i, j)-(i, j+1) (tension).
    #[inline]
    pub fn weft_link(&self, i: usize, j: usize) -> &Factors {
        &self.weft_link_factors[i * self.nv + j]
    }
    /// Grid size the layout is for.
    pub fn size(&self) -> (usize, usize) {
        (self.nu, self.nv)
    }
}

/// A sheet that first touches the tool where the tool's unit normal makes a cosine below minus
/// this with the sheet's normal comes down on the back of its facets (refused). Any facet the
/// first touch of a sheet from outside meets faces it (cosine >= 0) on a tool whose normals point
/// out of the part; the margin lets a touch on an edge between facets pass.
pub const BACK_FACING: f64 = 0.1;

/// A flat sheet laid over `tool` as seed 000 starts its drapes: an `nu x nv` grid of spacing
/// `d` in the plane with unit normal `normal`, its origin node over `centre` and its warp along
/// `warp` (projected into the plane), moved along the normal until it just touches the tool
/// (the first node whose drop along `-normal` meets the tool comes to rest on it). With a seam,
/// the two sheets meet at the stitch line and their allowances hang from it along `-normal`,
/// the origin node is on the stitch line. A sheet that would come down on the back of the
/// tool's facets is refused ([`BACK_FACING`]).
#[allow(clippy::too_many_arguments)]
pub fn flat_sheet(
    name: &str,
    nu: usize,
    nv: usize,
    d: f64,
    origin_node: (usize, usize),
    centre: &Point,
    warp: &Vector,
    normal: &Vector,
    seam: Option<Seam>,
    tool: &ToolSurface,
) -> Result<DrapeNet, SheetError> {
    let n = normal.try_normalize(0.0).ok_or_else(|| SheetError("the sheet's normal must not be zero".into()))?;
    let w = (warp - n * n.dot(warp)).try_normalize(1e-9 * warp.norm()).ok_or_else(|| {
        SheetError("the warp direction is normal to the sheet: give a direction in the sheet's plane".into())
    })?;
    let f = n.cross(&w);
    let (i0, j0) = origin_node;
    // Each row's distance along the warp from the origin row, and how far it hangs below.
    let row = |r: usize| -> (f64, f64) {
        match seam {
            Some(Seam { rows: [a, _], allowance }) => {
                let (ra, rb) = (a - 1 - allowance, a + allowance);
                if r <= ra {
                    (r as f64 - ra as f64, 0.0)
                } else if r >= rb {
                    (r as f64 - rb as f64, 0.0)
                } else if r < a {
                    (0.0, (r - ra) as f64)
                } else {
                    (0.0, (rb - r) as f64)
                }
            }
            None => (r as f64 - i0 as f64, 0.0),
        }
    };
    let mut positions: Vec<Point> = (0..nu * nv)
        .map(|k| {
            let (u, depth) = row(k / nv);
            let v = (k % nv) as f64 - j0 as f64;
            centre + w * (u * d) + f * (v * d) - n * (depth * d)
        })
        .collect();
    // Lift the sheet clear of the tool, then drop it until its first node touches.
    let top = tool.vertices().iter().map(|v| n.dot(&(v - centre))).fold(f64::NEG_INFINITY, f64::max);
    let lowest = positions.iter().map(|p| n.dot(&(p - centre))).fold(f64::INFINITY, f64::min);
    let lift = top - lowest + d;
    positions.iter_mut().for_each(|p| *p += n * lift);
    let (first, drop) = positions
        .iter()
        .enumerate()
        .filter_map(|(k, p)| tool.cast_ray(p, &-n).map(|t| (k, t)))
        .fold((0, f64::INFINITY), |best, hit| if hit.1 < best.1 { hit } else { best });
    if !drop.is_finite() {
        return Err(SheetError(
            "the sheet does not lie over the tool: no node drops onto it along the sheet's normal; move its centre over the tool".into(),
        ));
    }
    positions.iter_mut().for_each(|p| *p -= n * drop);
    // Contact keeps the ply on the side the tool's normals point to: a sheet coming down on the
    // back of the facets would be pushed through the tool (a sphere wound inward took the whole
    // sheet for inside it and stopped without equilibrium, its energy 0.6 J -> 2,800 J).
    let touched = tool.closest_point(&positions[first]);
    let facing = touched.normal.dot(&n);
    if facing < -BACK_FACING {
        let (i, j) = (first / nv, first % nv);
        let at = touched.point;
        return Err(SheetError(format!(
            "the sheet comes down on the back of the tool: where it first touches it (node ({i}, {j}), at \
             ({:.4}, {:.4}, {:.4})) the tool's facets face away from the sheet (their normal makes {:.0} deg with \
             the sheet's normal), and the ply is kept on the side the normals point to. If the tool's file \
             faces into the part, give stack_side = \"opposite\" (or turn its triangles over); if the sheet \
             belongs on the other side of the tool, turn sheet_normal round",
            at.x,
            at.y,
            at.z,
            facing.clamp(-1.0, 1.0).acos().to_degrees()
        )));
    }
    let mut net = DrapeNet::new(name, d, nu, nv, origin_node);
    net.positions = positions;
    net.status = vec![NodeStatus::Placed; nu * nv];
    for (k, p) in net.positions.iter().enumerate() {
        net.triangles[k] = tool.closest_point(p).triangle;
    }
    net.meta.origin = Some(net.positions[net.index(i0, j0)].coords.into());
    net.meta.warp_direction = Some(w.into());
    Ok(net)
}

/// The default origin node of a sheet with `seam` on an `nu x nv` grid: on the stitch line
/// (the first sheet's stitched row), else the grid's centre.
pub fn default_origin_node(nu: usize, nv: usize, seam: Option<Seam>) -> (usize, usize) {
    match seam {
        Some(Seam { rows: [a, _], allowance }) if a > allowance => (a - 1 - allowance, nv / 2),
        _ => (nu / 2, nv / 2),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The cells' shares of blanks of every kind add up to the blank's area: a square at
    /// 45 deg, a triangle off the grid's lines, an L (not convex), at other spacings and origins.
    #[test]
    fn the_cells_share_the_blank_s_area_exactly() {
        let blanks: [Vec<[f64; 2]>; 3] = [
            vec![[0.31, 0.0], [0.0, 0.31], [-0.31, 0.0], [0.0, -0.31]],
            vec![[-0.17, -0.2], [0.33, -0.05], [-0.02, 0.27]],
            vec![[-0.2, -0.2], [0.25, -0.2], [0.25, -0.05], [0.05, -0.05], [0.05, 0.3], [-0.2, 0.3]],
        ];
        for blank in &blanks {
            let area = check_blank(blank).unwrap();
            for (n, d, origin) in [(41, 0.02, (20, 20)), (30, 0.027, (13, 16)), (61, 0.0113, (29, 31))] {
                let f = blank_fractions(blank, n, n, d, origin);
                let sum: f64 = f.iter().sum::<f64>() * d * d;
                assert!(
                    (sum - area).abs() < 1e-12 * area.max(1.0) + BLANK_SLIVER * d * d * f.len() as f64,
                    "{sum} against {area}"
                );
                assert!(f.iter().all(|x| (0.0..=1.0).contains(x)));
                // The origin node is in the blank.
                let keep = blank_nodes(&f, n, n);
                assert!(keep[origin.0 * n + origin.1]);
            }
        }
    }

    #[test]
    fn a_blank_as_large_as_the_grid_changes_nothing_and_a_bad_one_is_refused() {
        let (n, d, o) = (11, 0.1, (5, 5));
        let whole = vec![[-0.5, -0.5], [0.5, -0.5], [0.5, 0.5], [-0.5, 0.5]];
        let with = SheetFeatures { blank: Some(whole), ..Default::default() }.layout(n, n, d, o).unwrap();
        let without = SheetFeatures::default().layout(n, n, d, o).unwrap();
        assert_eq!(with, without);
        // Half the grid: the cells beyond it are cut, the cells it halves carry half.
        let half = vec![[-0.5, -0.5], [0.05, -0.5], [0.05, 0.5], [-0.5, 0.5]];
        let l = SheetFeatures { blank: Some(half), ..Default::default() }.layout(n, n, d, o).unwrap();
        assert!((l.cell(5, 3).shear - 0.5).abs() < 1e-12 && (l.cell(5, 3).weight - 0.5).abs() < 1e-12);
        assert!(l.cell_cut(6, 3) && !l.cell_cut(5, 3) && !l.cell_cut(4, 3));
        assert_eq!(l.cell(4, 3).weight, 1.0);
        // The weft link on the cut's side of the halved cells carries their half.
        assert!((l.weft_link(6, 3).tension - 0.5).abs() < 1e-12);
        for bad in [
            vec![[0.1, 0.1], [0.2, 0.1]],
            vec![[0.1, 0.1], [0.3, 0.1], [0.2, 0.3]],
            vec![[0.0, 0.0], [0.1, 0.0], [0.2, 0.0]],
        ] {
            assert!(check_blank(&bad).is_err(), "{bad:?}");
        }
    }

    #[test]
    fn a_cut_along_the_warp_opens_the_weft_links_and_cells_it_crosses() {
        // 9 x 9 nodes, d = 1, origin (4, 4): a cut at v = 1.5 from u = -2 to u = 2 crosses the
        // weft links (i, 5)-(i, 6) for i = 2..=6 (u = -2..2).
        let f = SheetFeatures { cuts: vec![Cut { points: vec![[-2.0, 1.5], [2.0, 1.5]] }], ..Default::default() };
        let l = f.layout(9, 9, 1.0, (4, 4)).unwrap();
        for i in 0..9 {
            assert_eq!(l.weft_cut(i, 5), (2..=6).contains(&i), "link ({i}, 5)");
            assert!(!l.weft_cut(i, 4) && !l.weft_cut(i, 6));
        }
        for i in 0..8 {
            assert_eq!(l.cell_cut(i, 5), (1..=6).contains(&i), "cell ({i}, 5)");
        }
        assert!((0..8).all(|i| (0..9).all(|j| !l.warp_cut(i, j))));
    }

    #[test]
    fn a_seam_cuts_between_the_sheets_and_stitches_their_allowances() {
        let f = SheetFeatures { seam: Some(Seam { rows: [5, 6], allowance: 1 }), ..Default::default() };
        let l = f.layout(11, 4, 0.1, (5, 2)).unwrap();
        for j in 0..4 {
            assert!(l.warp_cut(4, j));
            assert_eq!(l.stitched[6 * 4 + j], 3 * 4 + j);
        }
        assert!((0..3).all(|j| l.cell_cut(4, j)));
        assert!(f.layout(12, 4, 0.1, (5, 2)).is_err(), "rows must add up");
    }

    #[test]
    fn a_fold_drops_bending_across_it_and_springs_its_neighbour_rows() {
        let f = SheetFeatures { fold: Some(Fold { row: 3, stiffness: 100.0 }), ..Default::default() };
        let l = f.layout(7, 5, 0.02, (3, 2)).unwrap();
        assert!((0..5).all(|j| l.warp_hinge(3, j)));
        assert_eq!(l.springs.len(), 5);
        assert_eq!(l.springs[2], (2 * 5 + 2, 4 * 5 + 2, 100.0 * 0.02));
        assert_eq!(l.springs[0].2, 100.0 * 0.02 * 0.5, "edge springs carry half");
    }

    #[test]
    fn a_flat_sheet_comes_to_rest_touching_the_tool() {
        // A 1 m sphere centred at the origin (a faceted hemisphere cap): the sheet's centre node
        // touches its pole, every other node is above the tool.
        let tool = crate::geometry::shapes::hemisphere(1.0, 16).into_surface().unwrap();
        let net =
            flat_sheet("s", 9, 9, 0.1, (4, 4), &Point::new(0.0, 0.0, 5.0), &Vector::x(), &Vector::z(), None, &tool)
                .unwrap();
        let c = net.positions[4 * 9 + 4];
        assert!((c - Point::new(0.0, 0.0, 1.0)).norm() < 1e-12, "{c}");
        assert!(net.positions.iter().all(|p| (p.z - 1.0).abs() < 1e-12));
        // A seam's flaps hang below the stitch line: they touch first.
        let seam = Seam { rows: [5, 5], allowance: 1 };
        let net = flat_sheet(
            "s",
            10,
            5,
            0.1,
            default_origin_node(10, 5, Some(seam)),
            &Point::new(0.0, 0.0, 5.0),
            &Vector::x(),
            &Vector::z(),
            Some(seam),
            &tool,
        )
        .unwrap();
        let (stitch_a, stitch_b) = (3 * 5 + 2, 6 * 5 + 2);
        assert_eq!(net.positions[stitch_a], net.positions[stitch_b]);
        assert!((net.positions[4 * 5 + 2].z - (net.positions[stitch_a].z - 0.1)).abs() < 1e-12);
        assert!(
            (net.positions[4 * 5 + 2] - Point::new(0.0, 0.0, 1.0)).norm() < 1e-12,
            "the flap tip rests on the pole"
        );
    }

    #[test]
    fn edge_bands_reinforce_the_border_only() {
        let factors = Factors { tension: 5.0, shear: 5.0, bending: 20.0, weight: 2.0 };
        let f = SheetFeatures {
            reinforcements: vec![Reinforcement { region: Region::Edges(0.25), factors }],
            ..Default::default()
        };
        // 11 x 11 nodes at d = 0.1: the band covers u or v within 0.25 of the edge.
        let l = f.layout(11, 11, 0.1, (5, 5)).unwrap();
        assert_eq!(*l.node(0, 5), factors);
        assert_eq!(*l.node(2, 5), factors);
        assert_eq!(*l.node(3, 5), Factors::ONE);
        assert_eq!(*l.cell(5, 5), Factors::ONE);
        assert_eq!(*l.cell(1, 5), factors);
    }
}
