//! Where a point lands on a net: [`NetSampler`] finds the closest point of a net's cells (two
//! triangles a cell) and the fibre tangents of the bilinear cell patch there. The flow-mesh
//! mapping samples the net at element centroids; the layup samples it at tool vertices to add a
//! ply's thickness to the stack.
use crate::geometry::surface::closest_point_on_triangle;
use crate::geometry::{Point, Vector};
use crate::kinematic::DrapeNet;
use std::collections::HashMap;

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

/// A net as triangles (two per complete cell) in a uniform hash grid of cell size 2d, for
/// closest-point queries near the net. (Our own grid rather than a BVH: nets are regular, their
/// triangles all about d in size, and collapsed or coincident cells of a locked net must not
/// upset the search structure.)
pub struct NetSampler<'a> {
    net: &'a DrapeNet,
    /// Triangle corners by node index, and the cell (i, j) and half (0: corners 00-10-11,
    /// 1: corners 00-11-01) of each triangle.
    triangles: Vec<([usize; 3], (usize, usize, u8))>,
    grid: HashMap<[i64; 3], Vec<u32>>,
    bin: f64,
}

impl<'a> NetSampler<'a> {
    /// `None` when the net has no complete cell.
    pub fn new(net: &'a DrapeNet) -> Option<Self> {
        let bin = 2.0 * net.spacing;
        let key = |p: &Point| [(p.x / bin).floor() as i64, (p.y / bin).floor() as i64, (p.z / bin).floor() as i64];
        let min_area = MIN_TRIANGLE_AREA_REL * net.spacing * net.spacing;
        let mut triangles = Vec::new();
        let mut grid: HashMap<[i64; 3], Vec<u32>> = HashMap::new();
        for i in 0..net.nu.saturating_sub(1) {
            for j in 0..net.nv.saturating_sub(1) {
                if net.cell_corners(i, j).is_none() {
                    continue;
                }
                let c = [net.index(i, j), net.index(i + 1, j), net.index(i + 1, j + 1), net.index(i, j + 1)];
                for (half, tri) in [(0u8, [c[0], c[1], c[2]]), (1, [c[0], c[2], c[3]])] {
                    let [a, b, d] = tri.map(|k| net.positions[k]);
                    // Collapsed halves (a folded or locked cell) carry no area to find.
                    if (b - a).cross(&(d - a)).norm() <= min_area {
                        continue;
                    }
                    let lo = key(&Point::from(a.coords.inf(&b.coords).inf(&d.coords)));
                    let hi = key(&Point::from(a.coords.sup(&b.coords).sup(&d.coords)));
                    for x in lo[0]..=hi[0] {
                        for y in lo[1]..=hi[1] {
                            for z in lo[2]..=hi[2] {
                                grid.entry([x, y, z]).or_default().push(triangles.len() as u32);
                            }
                        }
                    }
                    triangles.push((tri, (i, j, half)));
                }
            }
        }
        (!triangles.is_empty()).then_some(NetSampler { net, triangles, grid, bin })
    }

    /// The net at its closest point to `p`, if the net comes within `radius` of `p`.
    pub fn nearest_within(&self, p: &Point, radius: f64) -> Option<NetSample> {
        let net = self.net;
        let lo = ((p.coords - Vector::repeat(radius)) / self.bin).map(f64::floor);
        let hi = ((p.coords + Vector::repeat(radius)) / self.bin).map(f64::floor);
        let mut best: Option<(f64, u32, Point)> = None;
        for x in lo.x as i64..=hi.x as i64 {
            for y in lo.y as i64..=hi.y as i64 {
                for z in lo.z as i64..=hi.z as i64 {
                    for &t in self.grid.get(&[x, y, z]).map_or(&[][..], Vec::as_slice) {
                        let [a, b, c] = self.triangles[t as usize].0.map(|k| net.positions[k]);
                        let q = closest_point_on_triangle(p, &a, &b, &c);
                        let d2 = (q - p).norm_squared();
                        // Ties go to the lower triangle number, so the answer does not depend on
                        // the order the grid lists them in.
                        if best.is_none_or(|(bd, bt, _)| d2 < bd || (d2 == bd && t < bt)) {
                            best = Some((d2, t, q));
                        }
                    }
                }
            }
        }
        let (d2, t, x) = best?;
        if d2 > radius * radius {
            return None;
        }
        let ([k0, k1, k2], (i, j, half)) = self.triangles[t as usize];
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
