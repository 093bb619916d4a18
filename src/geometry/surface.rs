//! [`ToolSurface`]: a checked triangle mesh with a BVH ([`super::bvh`]), edge adjacency and
//! per-triangle frames, answering the geometric queries the drape engine needs.
use super::bvh::TriangleBvh;
use super::check::{mend_edges, mend_faces, NO_NEIGHBOUR};
use super::mesh::{MeshReport, ToolError, TriangleMesh};
use super::{Point, Vector};
use std::path::Path;

/// Vertices closer than this fraction of the mesh's bounding-box diagonal are welded.
pub const WELD_TOLERANCE_REL: f64 = 1e-9;
/// Barycentric slack when deciding whether a point lies in a triangle: points this close
/// (relative) outside an edge still count, so roots on shared edges are never lost.
pub const INSIDE_TOLERANCE: f64 = 1e-10;

/// A point counts as on a facet's edge when its barycentric coordinate opposite the edge is at
/// most this (points moved back onto the tool are clamped to exactly 0).
pub const ON_EDGE_BARYCENTRIC: f64 = 1e-9;
/// Walks around a vertex give up after this many facets (a non-manifold fan).
const MAX_VALENCE: usize = 256;

/// Precomputed per-triangle data for fast plane and barycentric tests.
#[derive(Debug, Clone, Copy)]
struct TriangleFrame {
    v0: Point,
    e1: Vector,
    e2: Vector,
    normal: Vector,
    d11: f64,
    d12: f64,
    d22: f64,
    inv_den: f64,
}

/// A point on the tool: where it is, in which triangle, and the triangle's unit normal.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfacePoint {
    /// The point.
    pub point: Point,
    /// The triangle it lies in.
    pub triangle: u32,
    /// The triangle's unit normal.
    pub normal: Vector,
    /// Distance from the query point (zero for points built on the surface).
    pub distance: f64,
}

/// A circle in space: `center + radius (cos t e1 + sin t e2)`.
#[derive(Debug, Clone, Copy)]
pub struct Circle {
    /// Centre.
    pub center: Point,
    /// First unit axis in the circle's plane.
    pub e1: Vector,
    /// Second unit axis, perpendicular to the first.
    pub e2: Vector,
    /// Radius.
    pub radius: f64,
}

/// A point where a circle crosses the tool surface.
#[derive(Debug, Clone, Copy)]
pub struct CircleRoot {
    /// Where it crosses.
    pub point: Point,
    /// The triangle it crosses.
    pub triangle: u32,
    /// cos of the circle parameter: 1 at `center + radius e1`, decreasing away from it.
    pub cos_t: f64,
}

/// The tool surface: a checked, consistently oriented triangle mesh with a BVH.
pub struct ToolSurface {
    vertices: Vec<Point>,
    triangles: Vec<[u32; 3]>,
    neighbours: Vec<[u32; 3]>,
    frames: Vec<TriangleFrame>,
    /// Bounding sphere of each triangle (centre, radius), for cheap ball tests.
    spheres: Vec<(Point, f64)>,
    bvh: TriangleBvh,
    report: MeshReport,
    diagonal: f64,
}

impl std::fmt::Debug for ToolSurface {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ToolSurface").field("report", &self.report).finish()
    }
}

impl ToolSurface {
    /// Build from in-memory triangles (analytic shapes, tests); goes through the same checks.
    pub fn from_triangles(vertices: Vec<Point>, triangles: Vec<[u32; 3]>) -> Result<Self, ToolError> {
        let report = MeshReport { vertices_read: vertices.len(), faces_read: triangles.len(), ..Default::default() };
        let path = Path::new("<memory>");
        if triangles.is_empty() {
            return Err(ToolError::Empty { path: path.into() });
        }
        for (f, tri) in triangles.iter().enumerate() {
            for &i in tri {
                if i as usize >= vertices.len() {
                    return Err(ToolError::BadIndex {
                        path: path.into(),
                        face: f,
                        index: i as usize,
                        count: vertices.len(),
                    });
                }
            }
        }
        for (i, v) in vertices.iter().enumerate() {
            if let Some(&value) = v.coords.iter().find(|c| !c.is_finite()) {
                return Err(ToolError::NonFinite { path: path.into(), index: i, value });
            }
        }
        Self::from_mesh(TriangleMesh { vertices, triangles }, report, path)
    }

    /// Check and mend `mesh` (read from `path`, with what reading it found in `report`) and build
    /// the surface: welding, degenerate and duplicate faces, adjacency, orientation
    /// ([`super::check::mend`]), then the BVH.
    pub fn from_mesh(mut raw: TriangleMesh, mut report: MeshReport, path: &Path) -> Result<Self, ToolError> {
        use rayon::prelude::*;
        let diagonal = bounding_diagonal(&raw.vertices);
        snap_coordinates(&mut raw.vertices, diagonal);
        let TriangleMesh { vertices, triangles } = mend_faces(raw, WELD_TOLERANCE_REL * diagonal, path, &mut report)?;
        // The BVH (built in parallel; its answers do not depend on its shape, see
        // `geometry::bvh`) needs only the triangles' boxes, which turning triangles over does not
        // change: it is built while the edges are grouped and the pieces oriented, and then
        // beside the per-triangle frames and spheres (each a pure function of its triangle, so
        // the same whatever the thread count). Only if duplicate faces were dropped (so the
        // triangles are numbered anew) is it built again.
        let boxes = TriangleBvh::boxes(&vertices, &triangles);
        let (bvh, (triangles, neighbours, renumbered, frames, spheres)) = rayon::join(
            || TriangleBvh::from_boxes(boxes),
            || {
                let (triangles, neighbours, renumbered) = mend_edges(triangles, vertices.len(), &mut report);
                let frames: Vec<TriangleFrame> = triangles
                    .par_iter()
                    .with_min_len(4096)
                    .map(|t| {
                        let v0 = vertices[t[0] as usize];
                        let e1 = vertices[t[1] as usize] - v0;
                        let e2 = vertices[t[2] as usize] - v0;
                        let normal = e1.cross(&e2).normalize();
                        let (d11, d12, d22) = (e1.dot(&e1), e1.dot(&e2), e2.dot(&e2));
                        let inv_den = 1.0 / (d11 * d22 - d12 * d12);
                        TriangleFrame { v0, e1, e2, normal, d11, d12, d22, inv_den }
                    })
                    .collect();
                let spheres: Vec<(Point, f64)> = triangles
                    .par_iter()
                    .with_min_len(4096)
                    .map(|t| {
                        let p = t.map(|i| vertices[i as usize]);
                        let c = Point::from((p[0].coords + p[1].coords + p[2].coords) / 3.0);
                        let r = p.iter().map(|q| (q - c).norm()).fold(0.0, f64::max);
                        (c, r)
                    })
                    .collect();
                (triangles, neighbours, renumbered, frames, spheres)
            },
        );
        let bvh = if renumbered { TriangleBvh::new(&vertices, &triangles) } else { bvh };
        report.triangles = triangles.len();
        report.vertices = vertices.len();
        Ok(ToolSurface { vertices, triangles, neighbours, frames, spheres, bvh, report, diagonal })
    }

    /// What the checks found and mended.
    pub fn report(&self) -> &MeshReport {
        &self.report
    }
    /// Number of triangles.
    pub fn num_triangles(&self) -> usize {
        self.triangles.len()
    }
    /// Welded vertex positions.
    pub fn vertices(&self) -> &[Point] {
        &self.vertices
    }
    /// Triangles (consistently wound within each connected piece).
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }
    /// Length of the bounding-box diagonal: the mesh's length scale.
    pub fn diagonal(&self) -> f64 {
        self.diagonal
    }
    /// Corner positions of triangle `t`.
    pub fn corners(&self, t: u32) -> [Point; 3] {
        self.triangles[t as usize].map(|i| self.vertices[i as usize])
    }
    /// Vertex indices of triangle `t`.
    pub fn triangle(&self, t: u32) -> [u32; 3] {
        self.triangles[t as usize]
    }
    /// Unit normal of triangle `t`.
    pub fn normal(&self, t: u32) -> Vector {
        self.frames[t as usize].normal
    }
    /// Triangle across the edge of `t` opposite corner `k`, if there is exactly one.
    pub fn neighbour(&self, t: u32, k: usize) -> Option<u32> {
        let n = self.neighbours[t as usize][k];
        (n != NO_NEIGHBOUR).then_some(n)
    }
    /// All three neighbours of `t` ([`NO_NEIGHBOUR`] where there is none).
    pub fn neighbours(&self, t: u32) -> [u32; 3] {
        self.neighbours[t as usize]
    }

    /// The closest point of the tool to `p`: on the facet nearest to `p`, and among facets at
    /// exactly the same distance the one of lowest index (whatever the BVH's shape).
    pub fn closest_point(&self, p: &Point) -> SurfacePoint {
        self.closest_point_from(p, None)
    }

    /// [`ToolSurface::closest_point`], the search starting from facet `hint` (the facet nearest
    /// to where the point was before a small move: faster, the same answer).
    pub fn closest_point_from(&self, p: &Point, hint: Option<u32>) -> SurfacePoint {
        let (triangle, _) = self
            .bvh
            .closest_from(p, hint, |t| (self.project_to_triangle(t, p) - p).norm_squared())
            .expect("a tool surface has triangles");
        let point = self.project_to_triangle(triangle, p);
        SurfacePoint { point, triangle, normal: self.normal(triangle), distance: (point - p).norm() }
    }

    /// Distance along the unit direction `dir` from `origin` to the first facet it meets, if
    /// any. A ray through an edge or a vertex that facets share meets them (see
    /// [`ray_triangle`]), so a ray is never lost between two facets.
    pub fn cast_ray(&self, origin: &Point, dir: &Vector) -> Option<f64> {
        self.bvh.first_hit(origin, dir, |t| ray_triangle(&self.corners(t), origin, dir))
    }

    /// Closest point of triangle `t` to `p`.
    pub fn project_to_triangle(&self, t: u32, p: &Point) -> Point {
        let c = self.corners(t);
        closest_point_on_triangle(p, &c[0], &c[1], &c[2])
    }

    /// The tool's open (boundary) edges that the point at barycentric `l` on facet `t` lies on:
    /// none inside the tool, one on an edge, two at a boundary corner (found by walking around
    /// the vertex). Each as the edge's outward direction in its facet's plane.
    pub fn open_edges_at(&self, t: u32, l: &[f64; 3]) -> [Option<Vector>; 2] {
        let mut out = [None; 2];
        let on: Vec<usize> = (0..3).filter(|&k| l[k] <= ON_EDGE_BARYCENTRIC).collect();
        match on.as_slice() {
            [k] if self.neighbours[t as usize][*k] == NO_NEIGHBOUR => out[0] = Some(self.outward(t, *k)),
            [k1, k2] => {
                // At the corner opposite both: walk around it both ways to the open edges.
                let corner = 3 - k1 - k2;
                let v = self.triangles[t as usize][corner];
                for (slot, start) in [*k1, *k2].into_iter().enumerate() {
                    out[slot] = self.walk_to_open_edge(t, start, v);
                }
            }
            _ => {}
        }
        out
    }

    /// From facet `t` across its edge `k` (which has vertex `v`), around `v` until an open edge.
    fn walk_to_open_edge(&self, t: u32, k: usize, v: u32) -> Option<Vector> {
        let (mut cur, mut edge) = (t, k);
        for _ in 0..MAX_VALENCE {
            let n = self.neighbours[cur as usize][edge];
            if n == NO_NEIGHBOUR {
                return Some(self.outward(cur, edge));
            }
            if n == t {
                return None; // all the way round: an inner vertex
            }
            // In n, the other edge at v: opposite the corner that is neither v nor across from cur.
            let tri = self.triangles[n as usize];
            let cv = tri.iter().position(|&w| w == v)?;
            let (e1, e2) = ((cv + 1) % 3, (cv + 2) % 3);
            edge = if self.neighbours[n as usize][e1] == cur { e2 } else { e1 };
            cur = n;
        }
        None
    }

    /// Unit outward direction of edge `k` of facet `t`, in the facet's plane.
    fn outward(&self, t: u32, k: usize) -> Vector {
        let c = self.corners(t);
        let (a, b, opposite) = (c[(k + 1) % 3], c[(k + 2) % 3], c[k]);
        let m = (b - a).cross(&self.normal(t)).normalize();
        if m.dot(&(opposite - a)) > 0.0 {
            -m
        } else {
            m
        }
    }

    /// Barycentric coordinates of `p` (assumed in the plane of `t`) with respect to `t`.
    pub fn barycentric(&self, t: u32, p: &Point) -> [f64; 3] {
        let f = &self.frames[t as usize];
        let w = p - f.v0;
        let (a, b) = (w.dot(&f.e1), w.dot(&f.e2));
        let l1 = (f.d22 * a - f.d12 * b) * f.inv_den;
        let l2 = (f.d11 * b - f.d12 * a) * f.inv_den;
        [1.0 - l1 - l2, l1, l2]
    }

    /// Triangles whose bounding box meets the box around the ball (`center`, `radius`), from
    /// the BVH, by increasing index.
    pub fn triangles_near(&self, center: &Point, radius: f64) -> Vec<u32> {
        let r = Vector::repeat(radius);
        self.bvh.meeting(&(center - r), &(center + r))
    }

    /// Whether any facet's bounding box comes within `radius` of `center` (a cheap test before a
    /// closest-point search).
    pub fn any_triangle_near(&self, center: &Point, radius: f64) -> bool {
        let r = Vector::repeat(radius);
        self.bvh.any_meeting(&(center - r), &(center + r))
    }

    /// Whether triangle `t` may come within `radius` of `center` (bounding-sphere test).
    #[inline]
    pub fn triangle_may_meet_ball(&self, t: u32, center: &Point, radius: f64) -> bool {
        let (c, r) = self.spheres[t as usize];
        (c - center).norm_squared() <= (r + radius) * (r + radius)
    }

    /// Points where `circle` crosses triangle `t` (zero, one or two), exactly up to rounding.
    #[inline]
    pub fn circle_roots(&self, t: u32, circle: &Circle, out: &mut Vec<CircleRoot>) {
        let f = &self.frames[t as usize];
        // Plane: n.(x - v0) = 0 with x = c + r (cos e1 + sin e2):  p cos + q sin = -h / r.
        let p = f.normal.dot(&circle.e1);
        let q = f.normal.dot(&circle.e2);
        let h = f.normal.dot(&(circle.center - f.v0));
        let rho = (p * p + q * q).sqrt();
        if rho * circle.radius <= f64::EPSILON * (h.abs() + circle.radius) {
            return; // the circle's plane is parallel to the triangle's: no isolated crossing
        }
        let cos_d = -h / (rho * circle.radius);
        if !(-1.0..=1.0).contains(&cos_d) {
            return;
        }
        let sin_d = (1.0 - cos_d * cos_d).sqrt();
        let (ux, uy) = (p / rho, q / rho);
        for s in [1.0, -1.0] {
            // Unit vector (cos t, sin t) = cos_d u + s sin_d u_perp, u_perp = (-uy, ux).
            let ct = cos_d * ux - s * sin_d * uy;
            let st = cos_d * uy + s * sin_d * ux;
            let x = circle.center + circle.radius * (ct * circle.e1 + st * circle.e2);
            let l = self.barycentric(t, &x);
            if l.iter().all(|&li| li >= -INSIDE_TOLERANCE) {
                out.push(CircleRoot { point: x, triangle: t, cos_t: ct });
            }
            if sin_d == 0.0 {
                break;
            }
        }
    }
}

/// Round every coordinate to a multiple of a power of two 2^-80 of the bounding-box diagonal
/// (about 1e-24 of it, far below the weld tolerance): coordinates beyond 2^-28 of the diagonal
/// are exact multiples already and do not change. Without it two triangles whose centres
/// differed by a subnormal number (a corner at 1e-320 beside one at 0) made parry's BVH build
/// divide by that difference and index a bin at infinity (a panic found by the mutation harness).
/// A mesh smaller than the smallest step (2^-1000 m) collapses and is refused as degenerate.
fn snap_coordinates(points: &mut [Point], diagonal: f64) {
    if !(diagonal.is_finite() && diagonal > 0.0) {
        return;
    }
    let step = 2f64.powi(diagonal.log2().floor() as i32 - 80).max(2f64.powi(-1000));
    // Beyond 2^52 steps a coordinate is a multiple of the step already (and dividing might overflow).
    let exact = step * 2f64.powi(52);
    for c in points.iter_mut().flat_map(|p| p.coords.iter_mut()).filter(|c| c.abs() < exact) {
        *c = (*c / step).round() * step;
    }
}

/// Length of the bounding-box diagonal of a point set (0 for fewer than two points).
pub fn bounding_diagonal(points: &[Point]) -> f64 {
    let mut lo = Vector::repeat(f64::INFINITY);
    let mut hi = Vector::repeat(f64::NEG_INFINITY);
    for p in points {
        lo = lo.inf(&p.coords);
        hi = hi.sup(&p.coords);
    }
    if points.is_empty() {
        0.0
    } else {
        (hi - lo).norm()
    }
}

/// Closest point on triangle (a, b, c) to p (Ericson, Real-Time Collision Detection §5.1.5).
pub fn closest_point_on_triangle(p: &Point, a: &Point, b: &Point, c: &Point) -> Point {
    let ab = b - a;
    let ac = c - a;
    let ap = p - a;
    let d1 = ab.dot(&ap);
    let d2 = ac.dot(&ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return *a;
    }
    let bp = p - b;
    let d3 = ab.dot(&bp);
    let d4 = ac.dot(&bp);
    if d3 >= 0.0 && d4 <= d3 {
        return *b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let d5 = ab.dot(&cp);
    let d6 = ac.dot(&cp);
    if d6 >= 0.0 && d5 <= d6 {
        return *c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = 1.0 / (va + vb + vc);
    a + ab * (vb * denom) + ac * (vc * denom)
}

/// Distance along `dir` (a unit vector) from `origin` to triangle `t`, if the ray meets it at
/// or ahead of its origin, from either side. Points within [`INSIDE_TOLERANCE`] (barycentric)
/// outside an edge count as on it: with exact tests (parry's, which this replaced) a ray through
/// an edge two facets share may be refused by both, each computing its barycentric coordinates
/// from its own corners and rounding them to just below zero. That lost the seeds on a mirror
/// plane of a symmetric mesh, where the plane runs along the facets' edges.
fn ray_triangle(t: &[Point; 3], origin: &Point, dir: &Vector) -> Option<f64> {
    let (ab, ac) = (t[1] - t[0], t[2] - t[0]);
    let n = ab.cross(&ac);
    let d = n.dot(dir);
    if d == 0.0 {
        return None;
    }
    let ap = origin - t[0];
    let h = ap.dot(&n);
    // The origin on the side the ray moves away from: no hit ahead.
    if (h < 0.0 && d < 0.0) || (h > 0.0 && d > 0.0) {
        return None;
    }
    // The hit's barycentric coordinates along ab and ac, times |d| (Cramer's rule).
    let e = dir.cross(&ap);
    let sign = d.signum();
    let (v, w) = (sign * ac.dot(&e), -sign * ab.dot(&e));
    let d = d.abs();
    let slack = INSIDE_TOLERANCE * d;
    if v < -slack || w < -slack || v + w > d + slack {
        return None;
    }
    Some(h.abs() / d)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::shapes;

    #[test]
    fn open_edges_are_found_on_edges_and_at_corners_only() {
        let tool = shapes::plate(2.0, 2.0, 4, 4).into_surface().unwrap();
        let at = |p: Point| {
            let s = tool.closest_point(&p);
            let l = tool.barycentric(s.triangle, &s.point);
            let mut e: Vec<Vector> = tool.open_edges_at(s.triangle, &l).into_iter().flatten().collect();
            e.sort_by(|a, b| a.x.partial_cmp(&b.x).unwrap().then(a.y.partial_cmp(&b.y).unwrap()));
            e
        };
        assert!(at(Point::new(0.3, 0.2, 0.0)).is_empty(), "inside");
        assert!(at(Point::new(0.5, 0.5, 0.0)).is_empty(), "an inner vertex");
        let edge = at(Point::new(1.3, 0.2, 0.0));
        assert_eq!(edge.len(), 1);
        assert!((edge[0] - Vector::x()).norm() < 1e-12, "{:?}", edge);
        let corner = at(Point::new(1.3, -1.2, 0.0));
        assert_eq!(corner.len(), 2, "{corner:?}");
        assert!((corner[0] + Vector::y()).norm() < 1e-12 && (corner[1] - Vector::x()).norm() < 1e-12, "{corner:?}");
        // A boundary vertex in the middle of a side: both open edges point the same way.
        let side = at(Point::new(1.2, 0.0, 0.0));
        assert_eq!(side.len(), 2);
        assert!(side.iter().all(|m| (m - Vector::x()).norm() < 1e-12), "{side:?}");
    }

    /// The BVH is built from the triangles before duplicates are dropped and pieces oriented:
    /// its answers must be those of the final triangles (brute force), with and without
    /// duplicate faces (which number the triangles anew) and on 1 and 3 threads.
    #[test]
    fn the_bvh_answers_for_the_mended_triangles() {
        let n = 24;
        let mut vertices = Vec::new();
        for i in 0..=n {
            for j in 0..=n {
                let (x, y) = (i as f64 / n as f64, j as f64 / n as f64);
                vertices.push(Point::new(x, y, 0.1 * (5.0 * x).sin() * (3.0 * y).cos()));
            }
        }
        let at = |i: usize, j: usize| (i * (n + 1) + j) as u32;
        let mut triangles = Vec::new();
        for i in 0..n {
            for j in 0..n {
                let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
                // Every third triangle turned over, so that orienting the pieces flips some.
                triangles.push(if (i + j) % 3 == 0 { [a, c, b] } else { [a, b, c] });
                triangles.push([a, c, d]);
            }
        }
        for duplicates in [false, true] {
            let mut tris = triangles.clone();
            // A degenerate face (dropped before the BVH is built).
            tris.insert(7, [0, 0, 1]);
            if duplicates {
                tris.insert(100, tris[40]);
                tris.push([tris[3][1], tris[3][2], tris[3][0]]);
            }
            for threads in [1, 3] {
                let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
                let tool = pool.install(|| ToolSurface::from_triangles(vertices.clone(), tris.clone()).unwrap());
                assert_eq!(tool.report().duplicate_faces_dropped, if duplicates { 2 } else { 0 });
                assert_eq!(tool.report().degenerate_faces_dropped, 1);
                assert!(tool.report().flipped_faces > 0);
                assert_eq!(tool.num_triangles(), 2 * n * n);
                for k in 0..300 {
                    let f = k as f64;
                    let p = Point::new(
                        (f * 0.618).fract() * 1.2 - 0.1,
                        (f * 0.382).fract() * 1.2 - 0.1,
                        0.3 * (f * 0.7).sin(),
                    );
                    let brute = (0..tool.num_triangles() as u32)
                        .map(|t| ((tool.project_to_triangle(t, &p) - p).norm_squared(), t))
                        .min_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)))
                        .unwrap();
                    assert_eq!(tool.closest_point(&p).triangle, brute.1, "point {k}");
                    let r = 0.05;
                    let near: Vec<u32> = (0..tool.num_triangles() as u32)
                        .filter(|&t| {
                            let c = tool.corners(t);
                            (0..3).all(|a| {
                                let lo = c.iter().map(|q| q[a]).fold(f64::INFINITY, f64::min);
                                let hi = c.iter().map(|q| q[a]).fold(f64::NEG_INFINITY, f64::max);
                                lo <= p[a] + r && p[a] - r <= hi
                            })
                        })
                        .collect();
                    assert_eq!(tool.triangles_near(&p, r), near, "point {k}");
                }
            }
        }
    }

    /// Rays through the edges and vertices that facets share meet the tool: along the mirror
    /// plane of the two-bump part, where mirrored facets meet in a line of edges and rounding
    /// puts a ray a hair to either side (parry's exact ray cast, used before, lost 6 of these
    /// 2,000 slanted rays: both facets refused them); vertical rays onto the plane's vertices; a
    /// ray away from the tool or beside it meets nothing.
    #[test]
    fn a_ray_through_a_shared_edge_or_vertex_meets_the_tool() {
        let tool = shapes::two_bumps(0.3, 40).into_surface().unwrap();
        let on_tool = |q: &Point, n: &Vector, x: f64| {
            let t = tool.cast_ray(q, n).unwrap_or_else(|| panic!("the ray from {q:?} along {n:?} missed"));
            let hit = q + n * t;
            assert!((hit.x - x).abs() < 1e-15 && tool.closest_point(&hit).distance < 1e-12, "{hit:?}");
            t
        };
        let slanted = Vector::new(0.0, -0.03, 1.0).normalize();
        for k in 0..2000 {
            let y = -0.6 + 1.2 * (k as f64 + 0.37) / 2000.0;
            let q = Point::new(-3.5e-18, y, 1.0);
            let down = on_tool(&q, &-slanted, -3.5e-18);
            // From below, the same point of the tool.
            let below = q - slanted * 2.0;
            let up = on_tool(&below, &slanted, -3.5e-18);
            assert!((up + down - 2.0).abs() < 1e-12, "{up} + {down}");
            assert!(tool.cast_ray(&q, &slanted).is_none(), "away from the tool");
        }
        for j in 1..40 {
            let q = Point::new(0.0, -0.8 + 1.6 * j as f64 / 40.0, 1.0);
            on_tool(&q, &-Vector::z(), 0.0);
        }
        assert!(tool.cast_ray(&Point::new(1.2, 0.0, 1.0), &-Vector::z()).is_none(), "beside the tool");
    }
}
