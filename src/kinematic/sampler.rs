//! Where a point lands on a net: [`NetSampler`] finds the closest point of a net's cells (two
//! triangles a cell) and the fibre tangents of the bilinear cell patch there. The flow-mesh
//! mapping samples the net at element centroids; the layup samples it at tool vertices to add a
//! ply's thickness to the stack.
use crate::geometry::surface::closest_point_on_triangle;
use crate::geometry::{Point, Vector};
use crate::kinematic::DrapeNet;
use rstar::{PointDistance, RTree, RTreeObject, AABB};

/// A centroid whose closest point on the net lies further than this (times the net spacing) from
/// it along the net's tangent plane is off the net's edge: the element is not covered.
const EDGE_TOLERANCE_REL: f64 = 1e-6;
/// Half-cells with less area than this (times d^2) are left out of the net's search mesh.
const MIN_TRIANGLE_AREA_REL: f64 = 1e-12;

/// Where a point lands on a net: the cell, the bilinear parameters in it, the closest point and
/// the fibre tangents there.
#[derive(Debug, Clone, Copy)]
pub struct NetSample {
    /// Cell (i, j) of the net.
    pub cell: (usize, usize),
    /// Bilinear parameters in the cell, along the warp (`s`) and the weft (`t`), in [0, 1].
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

/// A net as triangles (two per complete cell) in an R-tree (`rstar`), for closest-point queries
/// near the net. Collapsed halves of folded or locked cells are left out (they carry no area to
/// find); the tree takes the flat boxes of coincident cells as they are.
pub struct NetSampler<'a> {
    net: &'a DrapeNet,
    tree: RTree<HalfCell>,
}

/// One triangle of the net: half 0 of cell (i, j) has the corners 00-10-11, half 1 00-11-01.
struct HalfCell {
    /// Its number: ties between triangles at the same distance go to the lowest, so the answer
    /// does not depend on how the tree is built.
    number: u32,
    /// Corner node indices.
    nodes: [usize; 3],
    /// Corner positions.
    corners: [Point; 3],
    /// Cell (i, j) and half.
    cell: (usize, usize, u8),
}

impl HalfCell {
    fn closest_point(&self, p: &Point) -> Point {
        let [a, b, c] = &self.corners;
        closest_point_on_triangle(p, a, b, c)
    }
}

impl RTreeObject for HalfCell {
    type Envelope = AABB<[f64; 3]>;
    fn envelope(&self) -> Self::Envelope {
        let [a, b, c] = &self.corners;
        let (lo, hi) = (a.coords.inf(&b.coords).inf(&c.coords), a.coords.sup(&b.coords).sup(&c.coords));
        AABB::from_corners([lo.x, lo.y, lo.z], [hi.x, hi.y, hi.z])
    }
}

impl PointDistance for HalfCell {
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
                let c = [net.index(i, j), net.index(i + 1, j), net.index(i + 1, j + 1), net.index(i, j + 1)];
                for (half, nodes) in [(0u8, [c[0], c[1], c[2]]), (1, [c[0], c[2], c[3]])] {
                    let corners = nodes.map(|k| net.positions[k]);
                    let [a, b, d] = corners;
                    // Collapsed halves (a folded or locked cell) carry no area to find.
                    if (b - a).cross(&(d - a)).norm() <= min_area {
                        continue;
                    }
                    let number = triangles.len() as u32;
                    triangles.push(HalfCell { number, nodes, corners, cell: (i, j, half) });
                }
            }
        }
        (!triangles.is_empty()).then(|| NetSampler { net, tree: RTree::bulk_load(triangles) })
    }

    /// The net at its closest point to `p`, if the net comes within `radius` of `p`.
    pub fn nearest_within(&self, p: &Point, radius: f64) -> Option<NetSample> {
        let net = self.net;
        // The nearest triangles come first; of those at the same distance, the lowest number.
        let mut best: Option<(f64, &HalfCell)> = None;
        for (t, d2) in self.tree.nearest_neighbor_iter_with_distance_2(&[p.x, p.y, p.z]) {
            match best {
                Some((bd, _)) if d2 > bd => break,
                Some((_, bt)) if t.number > bt.number => {}
                _ => best = Some((d2, t)),
            }
        }
        let (d2, half) = best?;
        let x = half.closest_point(p);
        let ([k0, k1, k2], (i, j, half)) = (half.nodes, half.cell);
        if d2 > radius * radius {
            return None;
        }
        // Parameters of p's projection onto the triangle's plane, not clamped: a point over the
        // net lies inside its cell up to the kink between neighbouring facets; one beyond the
        // net's edge lies outside a cell that has no neighbour on that side.
        let l = barycentric(p, &net.positions[k0], &net.positions[k1], &net.positions[k2]);
        let (s, t) = if half == 0 { (l[1] + l[2], l[2]) } else { (l[1], l[1] + l[2]) };
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
