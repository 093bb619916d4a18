//! Where a point lands on a net: [`NetSampler`] finds the closest point of a net's cells (four
//! triangles a cell, about its centre) and the fibre tangents of the bilinear cell patch there. The flow-mesh
//! mapping samples the net at element centroids; the layup samples it at tool vertices to add a
//! ply's thickness to the stack.
use crate::geometry::surface::closest_point_on_triangle;
use crate::geometry::{Point, Vector};
use crate::kinematic::DrapeNet;
use rstar::{PointDistance, RTree, RTreeObject, AABB};

/// A centroid whose closest point on the net lies further than this (times the net spacing) from
/// it along the net's tangent plane is off the net's edge: the element is not covered.
const EDGE_TOLERANCE_REL: f64 = 1e-6;
/// Cell pieces with less area than this (times d^2) are left out of the net's search mesh.
const MIN_TRIANGLE_AREA_REL: f64 = 1e-12;

/// Where a point lands on a net: the cell, the bilinear parameters in it, the closest point and
/// the fibre tangents there.
#[derive(Debug, Clone, Copy)]
pub struct NetSample {
    /// Cell (i, j) of the net.
    pub cell: (usize, usize),
    /// Bilinear parameters of the closest point in the cell, along the warp (`s`) and the weft
    /// (`t`), in [0, 1].
    pub s: f64,
    /// Bilinear parameter along the weft, in [0, 1].
    pub t: f64,
    /// The closest point of the net.
    pub point: Point,
    /// Warp and weft tangents of the bilinear cell patch there (not normalised).
    pub warp: Vector,
    /// Weft tangent there (not normalised).
    pub weft: Vector,
    /// Unit normal warp x weft.
    pub normal: Vector,
    /// Signed distance from the net to the query point along `normal`.
    pub normal_distance: f64,
    /// How far (metres, in the cell's parameters times d) the query point lies beyond the net's
    /// edge: 0 over the net.
    pub beyond_edge: f64,
}

impl NetSample {
    /// Shear of the patch here, radians.
    pub fn shear(&self) -> f64 {
        super::net::corner_shear(&self.warp, &self.weft)
    }
}

/// A net as triangles (four per complete cell) in an R-tree (`rstar`), for closest-point queries
/// near the net. Collapsed pieces of folded or locked cells are left out (they carry no area to
/// find); the tree takes the flat boxes of coincident cells as they are.
///
/// A cell is cut into four triangles, each of its sides with its centre, not into two along a
/// diagonal: the pieces are then the same whichever way the net's warp and weft run (a diagonal
/// would be the other one for a net with its warp reversed, and where the cell is not flat the
/// two halves lie differently), so a net and its mirror image cover the same share of a
/// symmetric tool and map alike onto a symmetric mesh.
pub struct NetSampler<'a> {
    net: &'a DrapeNet,
    tree: RTree<CellPiece>,
}

/// One triangle of the net: a side of cell (i, j) and the cell's centre.
struct CellPiece {
    /// Its number: ties between triangles at the same distance go to the lowest, so the answer
    /// does not depend on how the tree is built.
    number: u32,
    /// Corner positions: the side's two nodes, then the cell's centre.
    corners: [Point; 3],
    /// The bilinear parameters (s, t) of the corners in the cell.
    params: [[f64; 2]; 3],
    /// Cell (i, j).
    cell: (usize, usize),
}

/// A cell's corners in order round it, with their bilinear parameters: 00, 10, 11, 01.
const CELL_CORNERS: [((usize, usize), [f64; 2]); 4] =
    [((0, 0), [0.0, 0.0]), ((1, 0), [1.0, 0.0]), ((1, 1), [1.0, 1.0]), ((0, 1), [0.0, 1.0])];

impl CellPiece {
    fn closest_point(&self, p: &Point) -> Point {
        let [a, b, c] = &self.corners;
        closest_point_on_triangle(p, a, b, c)
    }
}

impl RTreeObject for CellPiece {
    type Envelope = AABB<[f64; 3]>;
    fn envelope(&self) -> Self::Envelope {
        let [a, b, c] = &self.corners;
        let (lo, hi) = (a.coords.inf(&b.coords).inf(&c.coords), a.coords.sup(&b.coords).sup(&c.coords));
        AABB::from_corners([lo.x, lo.y, lo.z], [hi.x, hi.y, hi.z])
    }
}

impl PointDistance for CellPiece {
    fn distance_2(&self, p: &[f64; 3]) -> f64 {
        let p = Point::from(*p);
        (self.closest_point(&p) - p).norm_squared()
    }
}

impl<'a> NetSampler<'a> {
    /// `None` when the net has no complete cell.
    pub fn new(net: &'a DrapeNet) -> Option<Self> {
        let min_area = MIN_TRIANGLE_AREA_REL * net.spacing * net.spacing;
        let mut triangles = Vec::new();
        for i in 0..net.nu.saturating_sub(1) {
            for j in 0..net.nv.saturating_sub(1) {
                if net.cell_corners(i, j).is_none() {
                    continue;
                }
                let p = CELL_CORNERS.map(|((di, dj), _)| net.positions[net.index(i + di, j + dj)]);
                // Summed diagonal by diagonal, so that the centre is the same to the last bit
                // whichever corner the cell is numbered from and whichever way round.
                let centre = Point::from(((p[0].coords + p[2].coords) + (p[1].coords + p[3].coords)) * 0.25);
                for k in 0..4 {
                    let next = (k + 1) % 4;
                    let corners = [p[k], p[next], centre];
                    let [a, b, c] = corners;
                    // Collapsed pieces (a folded or locked cell) carry no area to find.
                    if (b - a).cross(&(c - a)).norm() <= min_area {
                        continue;
                    }
                    let number = triangles.len() as u32;
                    let params = [CELL_CORNERS[k].1, CELL_CORNERS[next].1, [0.5, 0.5]];
                    triangles.push(CellPiece { number, corners, params, cell: (i, j) });
                }
            }
        }
        (!triangles.is_empty()).then(|| NetSampler { net, tree: RTree::bulk_load(triangles) })
    }

    /// The net at its closest point to `p`, if the net comes within `radius` of `p`.
    pub fn nearest_within(&self, p: &Point, radius: f64) -> Option<NetSample> {
        let net = self.net;
        // The nearest triangles come first; of those at the same distance, the lowest number.
        let mut best: Option<(f64, &CellPiece)> = None;
        for (t, d2) in self.tree.nearest_neighbor_iter_with_distance_2(&[p.x, p.y, p.z]) {
            match best {
                Some((bd, _)) if d2 > bd => break,
                Some((_, bt)) if t.number > bt.number => {}
                _ => best = Some((d2, t)),
            }
        }
        let (d2, piece) = best?;
        let x = piece.closest_point(p);
        let (i, j) = piece.cell;
        if d2 > radius * radius {
            return None;
        }
        // Parameters of p's projection onto the triangle's plane, not clamped: a point over the
        // net lies inside its cell up to the kink between neighbouring facets; one beyond the
        // net's edge lies outside a cell that has no neighbour on that side.
        let [a, b, c] = &piece.corners;
        let params = |l: [f64; 3]| {
            let param = |k: usize| l[0] * piece.params[0][k] + l[1] * piece.params[1][k] + l[2] * piece.params[2][k];
            (param(0), param(1))
        };
        let (s, t) = params(barycentric(p, a, b, c));
        let complete = |a: isize, b: isize| {
            a >= 0
                && b >= 0
                && (a as usize) + 1 < net.nu
                && (b as usize) + 1 < net.nv
                && net.cell_corners(a as usize, b as usize).is_some()
        };
        let (ci, cj) = (i as isize, j as isize);
        let di = if s < 0.0 {
            -1
        } else if s > 1.0 {
            1
        } else {
            0
        };
        let dj = if t < 0.0 {
            -1
        } else if t > 1.0 {
            1
        } else {
            0
        };
        let over_s = if s < 0.0 { -s } else { (s - 1.0).max(0.0) };
        let over_t = if t < 0.0 { -t } else { (t - 1.0).max(0.0) };
        let mut beyond = 0.0f64;
        if di != 0 && !complete(ci + di, cj) {
            beyond = beyond.max(over_s);
        }
        if dj != 0 && !complete(ci, cj + dj) {
            beyond = beyond.max(over_t);
        }
        if di != 0 && dj != 0 && !complete(ci + di, cj + dj) {
            beyond = beyond.max(over_s.min(over_t));
        }
        let beyond_edge = beyond * net.spacing;
        // Where p lands: the parameters of its closest point, not of its projection, which
        // differ where the closest point lies on an edge between two pieces (over a kink) and
        // would then depend on which of the two equally near pieces was found first.
        let (s, t) = params(barycentric(&x, a, b, c));
        let (s, t) = (s.clamp(0.0, 1.0), t.clamp(0.0, 1.0));
        let q = |a: usize, b: usize| net.positions[net.index(a, b)];
        let (p00, p10, p11, p01) = (q(i, j), q(i + 1, j), q(i + 1, j + 1), q(i, j + 1));
        let warp = (p10 - p00) * (1.0 - t) + (p11 - p01) * t;
        let weft = (p01 - p00) * (1.0 - s) + (p11 - p10) * s;
        let normal = warp.cross(&weft).normalize();
        let normal_distance = (p - x).dot(&normal);
        Some(NetSample { cell: (i, j), s, t, point: x, warp, weft, normal, normal_distance, beyond_edge })
    }

    /// The net under `p`, or `None` when `p` lies beyond the net's edge or further than
    /// `max_distance` from it along the normal.
    pub fn cover(&self, p: &Point, max_distance: f64) -> Option<NetSample> {
        let edge = EDGE_TOLERANCE_REL * self.net.spacing;
        let h = self.nearest_within(p, max_distance + edge)?;
        (h.beyond_edge <= edge && h.normal_distance.abs() <= max_distance).then_some(h)
    }
}

fn barycentric(p: &Point, a: &Point, b: &Point, c: &Point) -> [f64; 3] {
    let (e1, e2, w) = (b - a, c - a, p - a);
    let (d11, d12, d22) = (e1.dot(&e1), e1.dot(&e2), e2.dot(&e2));
    let den = d11 * d22 - d12 * d12;
    if den <= 0.0 {
        return [1.0, 0.0, 0.0];
    }
    let (x, y) = (w.dot(&e1), w.dot(&e2));
    let l1 = (d22 * x - d12 * y) / den;
    let l2 = (d11 * y - d12 * x) / den;
    [1.0 - l1 - l2, l1, l2]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kinematic::NodeStatus;

    /// A net of one twisted cell (three corners in z = 0, the fourth raised) and the same net
    /// numbered with its warp reversed, its weft reversed, or warp and weft swapped.
    fn twisted(number: impl Fn(usize, usize) -> (usize, usize)) -> DrapeNet {
        let corner = |i: usize, j: usize| Point::new(i as f64, j as f64, if (i, j) == (0, 1) { 0.4 } else { 0.0 });
        let mut net = DrapeNet::new("cell", 1.0, 2, 2, (0, 0));
        for i in 0..2 {
            for j in 0..2 {
                let (a, b) = number(i, j);
                let k = net.index(i, j);
                net.positions[k] = corner(a, b);
                net.status[k] = NodeStatus::Placed;
            }
        }
        net
    }

    /// Where a point lands on a net does not depend on how the net is numbered: the same
    /// parameters (mapped with the numbering), distance along the normal (its sign with the
    /// normal's) and distance beyond the edge, above a twisted cell and beyond its edges. Cut
    /// along the diagonal 00-11 (before), the halves were other triangles with the warp
    /// reversed: a point above the middle landed at s = 0.41 one way and 0.50 the other, one
    /// 0.2 beyond an edge was 0.155 beyond it.
    #[test]
    fn a_sample_does_not_depend_on_the_nets_numbering() {
        let net = twisted(|i, j| (i, j));
        let sampler = NetSampler::new(&net).unwrap();
        // Each numbering of the nodes and its map of the parameters (s, t); every one turns the
        // normal (warp x weft) over.
        type Numbering = (fn(usize, usize) -> (usize, usize), fn(f64, f64) -> (f64, f64));
        let numberings: [Numbering; 3] = [
            (|i, j| (1 - i, j), |s, t| (1.0 - s, t)),
            (|i, j| (i, 1 - j), |s, t| (s, 1.0 - t)),
            (|i, j| (j, i), |s, t| (t, s)),
        ];
        let points = [
            [0.5, 0.5, 0.3],
            [0.3, 0.6, 0.25],
            [0.75, 0.15, -0.1],
            [0.5, -0.2, 0.05],
            [1.3, 0.6, 0.1],
            [-0.1, 0.9, 0.5],
        ];
        for (k, (number, map)) in numberings.iter().enumerate() {
            let other = twisted(number);
            let other_sampler = NetSampler::new(&other).unwrap();
            for p in points.map(Point::from) {
                let a = sampler.nearest_within(&p, 10.0).unwrap();
                let b = other_sampler.nearest_within(&p, 10.0).unwrap();
                let (s, t) = map(b.s, b.t);
                assert!((a.s - s).abs() < 1e-12 && (a.t - t).abs() < 1e-12, "numbering {k}, {p:?}: {a:?} {b:?}");
                assert!((a.normal_distance + b.normal_distance).abs() < 1e-12, "numbering {k}, {p:?}");
                assert!((a.beyond_edge - b.beyond_edge).abs() < 1e-12, "numbering {k}, {p:?}");
                assert!((a.point - b.point).norm() < 1e-12, "numbering {k}, {p:?}");
            }
        }
    }
}
