//! [`SmoothSurface`]: the tool's facets replaced by curved quadratic patches (Phong tessellation
//! with shape factor 1/2) for pressed contact.
//!
//! A faceted tool is a tessellation of a smooth part. Nodes pressed onto the facets themselves see
//! a kink of about h/R at every edge (h the facet size, R the radius of curvature), and a net
//! finer than the facets then crawls from crease to crease instead of settling (each node can
//! lower the energy a little by sliding over an edge). The patches here interpolate the vertices
//! and their normals, agree along shared edges (so the surface has no cracks) and leave a kink of
//! only about (h/R)^2 between neighbouring patches. Edges sharper than [`CREASE_ANGLE_DEG`] stay
//! straight and sharp, and vertex normals are averaged only within the smooth sector of each
//! corner, so flat faces stay flat and sharp tool edges stay sharp.
use super::surface::ToolSurface;
use super::{Point, Vector, NO_NEIGHBOUR};

/// Edges whose facets meet at more than this angle (between normals) are sharp tool edges: they
/// stay straight and the patches on either side do not share vertex normals across them.
pub const CREASE_ANGLE_DEG: f64 = 35.0;

/// Phong shape factor: 1/2 reproduces a circular arc's sagitta and end tangents to leading order
/// (1 would bulge twice as far; 0 is the flat facet).
pub const PATCH_SHAPE_FACTOR: f64 = 0.5;

/// The projection's fixed-point iteration stops when the patch offset changes by less than this
/// fraction of the tool's bounding-box diagonal.
const PROJECTION_TOLERANCE_REL: f64 = 1e-13;
/// At most this many fixed-point iterations (the contraction rate is about h/R, so 3-4 suffice).
const PROJECTION_MAX_ITERATIONS: usize = 12;

/// A point on the smooth surface: where it is, over which facet (and where on it), and the
/// surface's unit normal there (on the tool's outer side, like the facet normals).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SmoothPoint {
    /// The point on the patches.
    pub point: Point,
    /// The facet it lies over.
    pub triangle: u32,
    /// Barycentric coordinates on the facet.
    pub barycentric: [f64; 3],
    /// Unit normal of the patch there.
    pub normal: Vector,
}

/// The tool with curved patches over its facets.
pub struct SmoothSurface<'a> {
    tool: &'a ToolSurface,
    /// Per facet, the offset vector of each edge (edge k runs between corners k+1 and k+2),
    /// already multiplied by the shape factor; zero on sharp edges.
    edge_offsets: Vec<[Vector; 3]>,
    /// Number of sharp (crease) edges, each counted once.
    creases: usize,
}

impl<'a> SmoothSurface<'a> {
    /// Patches over every facet of `tool`.
    pub fn new(tool: &'a ToolSurface) -> Self {
        let tris = tool.triangles();
        let verts = tool.vertices();
        let cos_crease = CREASE_ANGLE_DEG.to_radians().cos();
        let smooth_edge = |t: usize, k: usize| -> Option<usize> {
            let n = tool.neighbours(t as u32)[k];
            (n != NO_NEIGHBOUR && tool.normal(t as u32).dot(&tool.normal(n)) >= cos_crease).then_some(n as usize)
        };
        // Corners (3 t + k) joined across smooth edges share one vertex normal: union-find.
        let mut parent: Vec<usize> = (0..3 * tris.len()).collect();
        fn root(parent: &mut [usize], mut a: usize) -> usize {
            while parent[a] != a {
                parent[a] = parent[parent[a]];
                a = parent[a];
            }
            a
        }
        let mut creases = 0;
        for t in 0..tris.len() {
            for k in 0..3 {
                let Some(n) = smooth_edge(t, k) else {
                    let n = tool.neighbours(t as u32)[k];
                    if n != NO_NEIGHBOUR && (n as usize) > t {
                        creases += 1;
                    }
                    continue;
                };
                for c in [(k + 1) % 3, (k + 2) % 3] {
                    let v = tris[t][c];
                    if let Some(cn) = tris[n].iter().position(|&w| w == v) {
                        let (a, b) = (root(&mut parent, 3 * t + c), root(&mut parent, 3 * n + cn));
                        parent[a] = b;
                    }
                }
            }
        }
        // Angle-weighted sums of facet normals per smooth sector.
        let mut sums = vec![Vector::zeros(); 3 * tris.len()];
        for (t, tri) in tris.iter().enumerate() {
            let n = tool.normal(t as u32);
            for c in 0..3 {
                let p = verts[tri[c] as usize];
                let (u, v) = (verts[tri[(c + 1) % 3] as usize] - p, verts[tri[(c + 2) % 3] as usize] - p);
                let angle = u.cross(&v).norm().atan2(u.dot(&v));
                let r = root(&mut parent, 3 * t + c);
                sums[r] += n * angle;
            }
        }
        let corner_normal = |parent: &mut [usize], t: usize, c: usize| -> Vector {
            let r = root(parent, 3 * t + c);
            sums[r].try_normalize(0.0).unwrap_or_else(|| tool.normal(t as u32))
        };
        let mut edge_offsets = Vec::with_capacity(tris.len());
        for (t, tri) in tris.iter().enumerate() {
            let normals = [0, 1, 2].map(|c| corner_normal(&mut parent, t, c));
            let mut offsets = [Vector::zeros(); 3];
            for (k, offset) in offsets.iter_mut().enumerate() {
                let n = tool.neighbours(t as u32)[k];
                if n != NO_NEIGHBOUR && smooth_edge(t, k).is_none() {
                    continue; // sharp edge: straight
                }
                let (i, j) = ((k + 1) % 3, (k + 2) % 3);
                let e = verts[tri[j] as usize] - verts[tri[i] as usize];
                // Phong: the two ends' tangent-plane projections of the other end, minus the chord.
                // Symmetric in i and j, so both facets of an edge compute the same curve.
                *offset = (normals[j] * e.dot(&normals[j]) - normals[i] * e.dot(&normals[i])) * PATCH_SHAPE_FACTOR;
            }
            edge_offsets.push(offsets);
        }
        SmoothSurface { tool, edge_offsets, creases }
    }

    /// The faceted tool underneath.
    pub fn tool(&self) -> &ToolSurface {
        self.tool
    }

    /// Number of sharp edges kept straight.
    pub fn creases(&self) -> usize {
        self.creases
    }

    /// Offset of the patch over facet `t` from the facet at barycentric `l`.
    pub fn offset(&self, t: u32, l: &[f64; 3]) -> Vector {
        let d = &self.edge_offsets[t as usize];
        d[0] * (l[1] * l[2]) + d[1] * (l[2] * l[0]) + d[2] * (l[0] * l[1])
    }

    /// The patch point over facet `t` at barycentric `l`.
    pub fn point(&self, t: u32, l: &[f64; 3]) -> Point {
        let c = self.tool.corners(t);
        Point::from(c[0].coords * l[0] + c[1].coords * l[1] + c[2].coords * l[2]) + self.offset(t, l)
    }

    /// Unit normal of the patch over facet `t` at barycentric `l` (on the facet normal's side).
    pub fn normal(&self, t: u32, l: &[f64; 3]) -> Vector {
        let c = self.tool.corners(t);
        let d = &self.edge_offsets[t as usize];
        // Derivatives along l1 and l2 (l0 = 1 - l1 - l2).
        let ds = (c[1] - c[0]) + d[0] * l[2] - d[1] * l[2] + d[2] * (l[0] - l[1]);
        let dt = (c[2] - c[0]) + d[0] * l[1] + d[1] * (l[0] - l[2]) - d[2] * l[1];
        let facet = self.tool.normal(t);
        match ds.cross(&dt).try_normalize(0.0) {
            Some(n) if n.dot(&facet) > 0.0 => n,
            _ => facet,
        }
    }

    /// The point of the smooth surface over `q`: the patch point p over facet point f such that
    /// q - p is along the facet's normal (for q on the surface, q itself). A retraction onto the
    /// surface, exact to first order, which is what sliding contact needs.
    pub fn project(&self, q: &Point) -> SmoothPoint {
        let tol = PROJECTION_TOLERANCE_REL * self.tool.diagonal();
        let mut foot = self.tool.closest_point(q);
        let mut l = self.tool.barycentric(foot.triangle, &foot.point);
        let mut offset = self.offset(foot.triangle, &l);
        // Fixed point: the facet point under q minus the patch offset there.
        for _ in 0..PROJECTION_MAX_ITERATIONS {
            foot = self.tool.closest_point(&(q - offset));
            l = self.tool.barycentric(foot.triangle, &foot.point);
            let next = self.offset(foot.triangle, &l);
            let settled = (next - offset).norm() <= tol;
            offset = next;
            if settled {
                break;
            }
        }
        let t = foot.triangle;
        // Clamp rounding so the point is on the patch over the facet.
        let l = clamp_barycentric(l);
        SmoothPoint { point: self.point(t, &l), triangle: t, barycentric: l, normal: self.normal(t, &l) }
    }
}

/// Barycentric coordinates made non-negative and summing to one.
fn clamp_barycentric(l: [f64; 3]) -> [f64; 3] {
    let l = l.map(|x| x.max(0.0));
    let s = l[0] + l[1] + l[2];
    if s > 0.0 {
        l.map(|x| x / s)
    } else {
        [1.0 / 3.0; 3]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::shapes;

    #[test]
    fn a_flat_plate_stays_flat() {
        let tool = shapes::plate(2.0, 1.0, 6, 3).into_surface().unwrap();
        let smooth = SmoothSurface::new(&tool);
        for q in [Point::new(0.3, 0.2, 0.5), Point::new(-0.7, 0.1, -0.2)] {
            let s = smooth.project(&q);
            assert!((s.point - Point::new(q.x, q.y, 0.0)).norm() < 1e-14, "{}", s.point);
            assert!((s.normal - tool.normal(s.triangle)).norm() < 1e-14);
        }
    }

    #[test]
    fn hemisphere_patches_follow_the_sphere_far_closer_than_the_facets() {
        let r = 1.0;
        let tool = shapes::hemisphere(r, 12).into_surface().unwrap();
        let smooth = SmoothSurface::new(&tool);
        let (mut facet_err, mut patch_err, mut facet_angle, mut patch_angle) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
        for i in 0..40 {
            for j in 0..40 {
                let (theta, phi) = (1.4 * i as f64 / 39.0, std::f64::consts::TAU * j as f64 / 40.0);
                let q = Point::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos()) * r;
                let f = tool.closest_point(&q);
                let s = smooth.project(&q);
                facet_err = facet_err.max(r - f.point.coords.norm());
                patch_err = patch_err.max((s.point.coords.norm() - r).abs());
                facet_angle = facet_angle.max(f.normal.angle(&f.point.coords));
                patch_angle = patch_angle.max(s.normal.angle(&s.point.coords));
                // Points on the surface project onto themselves.
                let again = smooth.project(&s.point);
                assert!((again.point - s.point).norm() < 1e-12, "{} vs {}", again.point, s.point);
            }
        }
        assert!(patch_err < facet_err / 8.0, "patch {patch_err:e} facet {facet_err:e}");
        assert!(patch_angle < facet_angle / 4.0, "patch {patch_angle:e} facet {facet_angle:e}");
    }

    /// Points at parameters along every shared edge, seen from both of its facets.
    fn assert_no_cracks(tool: &ToolSurface, smooth: &SmoothSurface) {
        let tris = tool.triangles();
        for t in 0..tris.len() as u32 {
            for k in 0..3 {
                let Some(n) = tool.neighbour(t, k) else { continue };
                let (a, b) = (tris[t as usize][(k + 1) % 3], tris[t as usize][(k + 2) % 3]);
                for s in [0.25, 0.5, 0.8] {
                    let bary = |tri: [u32; 3]| {
                        tri.map(|v| {
                            if v == a {
                                1.0 - s
                            } else if v == b {
                                s
                            } else {
                                0.0
                            }
                        })
                    };
                    let p = smooth.point(t, &bary(tris[t as usize]));
                    let q = smooth.point(n, &bary(tris[n as usize]));
                    assert!((p - q).norm() < 1e-12 * tool.diagonal(), "crack between {t} and {n}");
                }
            }
        }
    }

    #[test]
    fn patches_meet_without_cracks() {
        let tool = crate::io::read_tool(
            std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/geometries/double-dome/double-dome.obj")),
            1.0,
        )
        .unwrap();
        let smooth = SmoothSurface::new(&tool);
        assert_eq!(smooth.creases(), 0, "no edge of the double dome is sharper than the crease angle");
        assert_no_cracks(&tool, &smooth);
    }

    #[test]
    fn sharp_edges_stay_straight_and_their_faces_flat() {
        // A plate folded by 90 degrees along y = 0 (an L in the x-z plane), 4 x 4 facets a side.
        let n = 4;
        let mut vertices = Vec::new();
        for i in 0..=2 * n {
            for j in 0..=n {
                let (u, y) = (i as f64 / n as f64 - 1.0, j as f64 / n as f64);
                vertices.push(if u <= 0.0 { Point::new(u, y, 0.0) } else { Point::new(0.0, y, u) });
            }
        }
        let id = |i: usize, j: usize| (i * (n + 1) + j) as u32;
        let mut triangles = Vec::new();
        for i in 0..2 * n {
            for j in 0..n {
                triangles.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                triangles.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        let tool = ToolSurface::from_triangles(vertices, triangles).unwrap();
        let smooth = SmoothSurface::new(&tool);
        assert_eq!(smooth.creases(), n, "the fold's edges are sharp");
        assert_no_cracks(&tool, &smooth);
        for q in [Point::new(-0.01, 0.37, 0.3), Point::new(-0.6, 0.5, 0.1), Point::new(0.2, 0.3, 0.5)] {
            let s = smooth.project(&q);
            let f = tool.closest_point(&q);
            assert!((s.point - f.point).norm() < 1e-14, "{} vs {}", s.point, f.point);
            assert!((s.normal - f.normal).norm() < 1e-14);
        }
    }
}
