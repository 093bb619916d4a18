//! [`SmoothSurface`]: the smooth part a faceted tool stands for, as an implicit surface whose
//! normal turns continuously (G1, in fact C2) across the facets' edges, with the tool's sharp
//! edges kept sharp.
//!
//! Why: a faceted tool is a tessellation of a smooth part. Nodes sliding on the facets see a kink
//! of about h/R at every edge (h the facet size, R the radius of curvature), and curved patches
//! through the vertices (Phong, PN, Nagata) still leave a kink of about (h/R)^2 between
//! neighbours. A stiff fibre stretched over such a kink turns each step a node takes across it
//! into an error of first order in the step, multiplied by the fibre's rigidity: the net crawls
//! instead of settling (measured on the double dome, whose 70-degree walls are tessellated in
//! steps of 27 degrees). A surface whose normal is continuous has no such kinks.
//!
//! The construction: every vertex has one *sector* per smooth fan of facets around it (facets
//! joined across edges sharper than [`CREASE_ANGLE_DEG`] belong to different sectors), with the
//! angle-weighted normal of its facets and a curvature tensor fitted to the normals of its
//! neighbouring sectors (Weingarten: dn = K dx in the tangent plane). Each sector s carries the
//! local quadric `q_s(p) = n_s . (p - x_s) + 1/2 (p - x_s)^T K_s (p - x_s)` (the signed distance to
//! the surface to second order) and a compactly supported weight `w_s(p) = phi(|p - x_s| / h_s)`
//! (Wendland's C2 function, h_s one and a half times the longest edge of its facets, so every
//! point of a facet is inside the support of its three corners). The surface is the zero set of
//! the partition of unity `f(p) = sum w_s q_s / sum w_s` over the sectors of one *region*: the
//! facets joined by smooth edges. Flat regions are reproduced exactly (all quadrics are the same
//! plane), a sphere to third order in h; a sharp edge is where two regions meet, each point
//! taking the region of its closest facet.
//!
//! Flat faces stay flat where a fillet meets them tangentially ([`FaceEdge`]): a sector on the
//! edge of a face takes the face's normal, and its curvature acts only across the edge, away
//! from the face, over the fillet facets' reach. (Averaged over both sides the edge's normal
//! tilted by half a facet's turn, and with the face's large facets' support its quadric bulged
//! out of a die's face by 0.4 mm, into the blank a binder holds in that plane.) And a point
//! reached by Newton's steps further from the facets than the surface ever lies
//! ([`SURFACE_BAND_OVER_EDGE`]) is found again from the query's facet point: queries a few
//! millimetres off a die's fillet, where few sectors reach, were taken to a zero set of the
//! blend running on into the die's opening, or to the fillet a centimetre away.
use super::surface::{SurfacePoint, ToolSurface};
use super::{Point, Vector, NO_NEIGHBOUR};
use crate::numeric::union_find_root;
use nalgebra::{Matrix2, Matrix3, Vector2};
use parry3d_f64::bounding_volume::Aabb;
use parry3d_f64::partitioning::{Bvh, BvhBuildStrategy};
use std::sync::OnceLock;

/// Edges whose facets meet at more than this angle (between normals) are sharp tool edges: the
/// smooth surface keeps them sharp (the facets on either side belong to different regions).
pub const CREASE_ANGLE_DEG: f64 = 35.0;

/// A sector's support radius over the longest edge of its facets (at least 1, so every point of
/// a facet is inside the support of its corners; more overlap makes the blend smoother).
const SUPPORT_OVER_EDGE: f64 = 1.5;
/// The projection stops when |f| falls below this fraction of the tool's bounding-box diagonal.
const PROJECTION_TOLERANCE_REL: f64 = 1e-14;
/// At most this many Newton steps of the projection (it converges quadratically: 2-4 suffice).
const PROJECTION_MAX_ITERATIONS: usize = 20;
/// A query counts as beyond an open edge when it is off it outwards by more than this fraction
/// of the tool's bounding-box diagonal.
const BOUNDARY_TOLERANCE_REL: f64 = 1e-12;
/// A projected point lies across a facet's sharp edge when its barycentric coordinate is below
/// minus this (rounding on the edge itself stays within it).
const CREASE_OVERSHOOT_BARYCENTRIC: f64 = 1e-9;
/// Relative ridge added to the curvature fit (sectors with too few neighbours fit flat).
const CURVATURE_FIT_RIDGE: f64 = 1e-6;
/// Facets whose normals agree to within this (1 - cos of the angle between them) across an edge
/// lie in one plane: a flat face (rounding in a generated or exported plane is far below it).
const COPLANAR_COS_SLACK: f64 = 1e-12;
/// The smooth surface over a facet lies within this fraction of the facet's longest edge of it:
/// its sagitta is at most an eighth of the edge times the turn across it (under 0.08 below the
/// crease angle).
const SURFACE_BAND_OVER_EDGE: f64 = 0.25;
/// A plane of facets is a flat face when it spans at least this angle round one of its
/// vertices (an interior vertex 2 pi, one on a straight edge pi): a quad of a cylinder, cone or
/// fillet split into two coplanar triangles spans its corner's angle, about pi / 2.
const FACE_SPAN: f64 = 2.0 * std::f64::consts::FRAC_PI_3;
/// A facet's sector list ([`SmoothSurface::near_facet`]) serves points within its bounding box
/// grown by this fraction of its longest edge: the projections of nodes on or next to it.
const FACET_REACH_OVER_EDGE: f64 = 0.25;

/// A point on the smooth surface: where it is, the facet nearest to it (and where on it), and the
/// surface's unit normal there (on the tool's outer side, like the facet normals).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SmoothPoint {
    /// The point on the smooth surface.
    pub point: Point,
    /// The facet closest to the query (a retraction moves a point by a second-order amount, so
    /// for a query on or next to the surface this is the facet under the point).
    pub triangle: u32,
    /// Barycentric coordinates of the query's foot on that facet.
    pub barycentric: [f64; 3],
    /// Unit normal of the surface there.
    pub normal: Vector,
    /// The region (facets joined by smooth edges) whose surface the point is on.
    pub region: u32,
    /// The query point lay beyond the tool's open boundary: its closest facet point is on an
    /// open edge and it is off that edge outwards (the surface runs on past the edge as its
    /// tangent plane there, see [`SmoothSurface::project`]; pressed nodes are held back by the
    /// edge, free contact ends there).
    pub beyond_boundary: bool,
    /// The query point lay beyond a sharp edge or corner of its region: the region's surface
    /// would carry it across the edge (a table's top runs on as a plane past its rim), so the
    /// nearest tool is the edge itself.
    pub beyond_region: bool,
}

/// One smooth fan of facets around a vertex, with its local quadric.
#[derive(Debug, Clone)]
struct Sector {
    x: Point,
    n: Vector,
    /// Curvature tensor in the tangent plane, lifted to 3-D (K n = 0).
    k: Matrix3<f64>,
    /// Support radius.
    h: f64,
    region: u32,
    /// On the edge of a flat face ([`FaceEdge`]): the quadric's curvature acts only on the side
    /// away from the face, where the support reaches less far.
    edge: Option<FaceEdge>,
}

/// A sector on the edge of a flat face (a plane of facets round at least one vertex) whose other
/// facets curve away from it: a fillet tangent to the face. The surface is tangent to the face
/// along its edge, so the sector's normal is the face's; its curvature is zero along the edge
/// (the edge lies in the plane, and the normal along it is the face's) and jumps there from
/// zero on the face to the fillet's across it: `K = kappa m m^T` on the side `m . d > 0` only.
/// Averaged over both sides as other sectors are, the normal tilts by half a facet's turn and
/// the quadric bulges out of the face by a fraction of a millimetre (a die's face next to its
/// entry fillet, where a binder holds the blank in that plane).
#[derive(Debug, Clone, Copy)]
struct FaceEdge {
    /// Unit direction in the face's plane, across its edge, away from the face.
    m: Vector,
    /// The support radius on that side (over the edge's facets there: the face's facets are
    /// often far larger than the fillet's, and the quadric fits the fillet only near the edge).
    h_off: f64,
}

/// The tool's smooth surface (see the module docs).
pub struct SmoothSurface<'a> {
    tool: &'a ToolSurface,
    sectors: Vec<Sector>,
    /// Region of each facet.
    regions: Vec<u32>,
    /// Bounding boxes of the sectors' supports.
    bvh: Bvh,
    creases: usize,
    /// Per facet, gathered when first asked: the sectors whose supports meet its box
    /// ([`SmoothSurface::facet_box`]), in the BVH's order (a projection's points then need no
    /// search: the BVH query costs more than the sums). 24 bytes a facet until asked.
    near_facet: Vec<OnceLock<Box<[u32]>>>,
}

/// Wendland's C2 function on [0, 1] and its derivative: (1 - r)^4 (4 r + 1).
#[inline]
fn wendland(r: f64) -> (f64, f64) {
    if r >= 1.0 {
        return (0.0, 0.0);
    }
    let s = 1.0 - r;
    let s3 = s * s * s;
    (s3 * s * (4.0 * r + 1.0), -20.0 * r * s3)
}

impl<'a> SmoothSurface<'a> {
    /// The smooth surface of `tool`.
    pub fn new(tool: &'a ToolSurface) -> Self {
        let tris = tool.triangles();
        let verts = tool.vertices();
        let cos_crease = CREASE_ANGLE_DEG.to_radians().cos();
        let smooth_edge = |t: usize, k: usize| -> Option<usize> {
            let n = tool.neighbours(t as u32)[k];
            (n != NO_NEIGHBOUR && tool.normal(t as u32).dot(&tool.normal(n)) >= cos_crease).then_some(n as usize)
        };
        // Corners (3 t + c) joined across smooth edges form a sector; facets joined across smooth
        // edges form a region.
        let mut corner_parent: Vec<usize> = (0..3 * tris.len()).collect();
        let mut facet_parent: Vec<usize> = (0..tris.len()).collect();
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
                let (a, b) = (union_find_root(&mut facet_parent, t), union_find_root(&mut facet_parent, n));
                facet_parent[a] = b;
                for c in [(k + 1) % 3, (k + 2) % 3] {
                    let v = tris[t][c];
                    if let Some(cn) = tris[n].iter().position(|&w| w == v) {
                        let (a, b) = (
                            union_find_root(&mut corner_parent, 3 * t + c),
                            union_find_root(&mut corner_parent, 3 * n + cn),
                        );
                        corner_parent[a] = b;
                    }
                }
            }
        }
        let mut region_id = vec![u32::MAX; tris.len()];
        let mut regions = vec![0u32; tris.len()];
        let mut next_region = 0;
        for (t, region) in regions.iter_mut().enumerate() {
            let r = union_find_root(&mut facet_parent, t);
            if region_id[r] == u32::MAX {
                region_id[r] = next_region;
                next_region += 1;
            }
            *region = region_id[r];
        }
        // Sector ids, positions, angle-weighted normals and supports.
        let mut sector_of_corner = vec![0usize; 3 * tris.len()];
        let mut id_of_root = vec![usize::MAX; 3 * tris.len()];
        let mut sum_normal: Vec<Vector> = Vec::new();
        let mut sectors: Vec<Sector> = Vec::new();
        for (t, tri) in tris.iter().enumerate() {
            let n = tool.normal(t as u32);
            let longest =
                (0..3).map(|c| (verts[tri[(c + 1) % 3] as usize] - verts[tri[c] as usize]).norm()).fold(0.0, f64::max);
            for c in 0..3 {
                let r = union_find_root(&mut corner_parent, 3 * t + c);
                if id_of_root[r] == usize::MAX {
                    id_of_root[r] = sectors.len();
                    sectors.push(Sector {
                        x: verts[tri[c] as usize],
                        n: Vector::zeros(),
                        k: Matrix3::zeros(),
                        h: 0.0,
                        region: regions[t],
                        edge: None,
                    });
                    sum_normal.push(Vector::zeros());
                }
                let s = id_of_root[r];
                sector_of_corner[3 * t + c] = s;
                let p = verts[tri[c] as usize];
                let (u, v) = (verts[tri[(c + 1) % 3] as usize] - p, verts[tri[(c + 2) % 3] as usize] - p);
                sum_normal[s] += n * u.cross(&v).norm().atan2(u.dot(&v));
                sectors[s].h = sectors[s].h.max(SUPPORT_OVER_EDGE * longest);
            }
        }
        for (s, sum) in sectors.iter_mut().zip(&sum_normal) {
            s.n = sum.try_normalize(0.0).unwrap_or_else(Vector::z);
        }
        // Neighbouring sectors: the other corners of each sector's facets.
        let mut neighbours: Vec<Vec<usize>> = vec![Vec::new(); sectors.len()];
        for t in 0..tris.len() {
            for c in 0..3 {
                let s = sector_of_corner[3 * t + c];
                for o in [(c + 1) % 3, (c + 2) % 3] {
                    let j = sector_of_corner[3 * t + o];
                    if !neighbours[s].contains(&j) {
                        neighbours[s].push(j);
                    }
                }
            }
        }
        face_edges(tool, &mut sectors, &sector_of_corner, &regions);
        let ks: Vec<Matrix3<f64>> = (0..sectors.len())
            .map(|s| match sectors[s].edge {
                Some(edge) => fit_edge_curvature(&sectors, s, &edge, &neighbours[s]),
                None => fit_curvature(&sectors, s, &neighbours[s]),
            })
            .collect();
        for (s, k) in sectors.iter_mut().zip(ks) {
            s.k = k;
        }
        let boxes: Vec<Aabb> =
            sectors.iter().map(|s| Aabb::new(s.x - Vector::repeat(s.h), s.x + Vector::repeat(s.h))).collect();
        let bvh = Bvh::from_leaves(BvhBuildStrategy::Binned, &boxes);
        let near_facet = (0..tris.len()).map(|_| OnceLock::new()).collect();
        SmoothSurface { tool, sectors, regions, bvh, creases, near_facet }
    }

    /// The sectors whose supports may hold `p`, found next to facet `t`: the facet's own list
    /// when `p` lies in its box (a superset of what a search at `p` finds, in the same order, so
    /// sums agree to the bit), None when `p` is further off.
    fn near_facet(&self, t: u32, p: &Point) -> Option<&[u32]> {
        let bounds = self.facet_box(t);
        if !bounds.contains_local_point(p) {
            return None;
        }
        Some(self.near_facet[t as usize].get_or_init(|| self.bvh.intersect_aabb(&bounds).collect()))
    }

    /// The longest edge of facet `t`.
    fn longest_edge(&self, t: u32) -> f64 {
        longest_edge(&self.tool.corners(t))
    }

    /// Facet `t`'s bounding box grown by [`FACET_REACH_OVER_EDGE`] of its longest edge
    /// (computed again at each query rather than kept: 48 bytes a facet on large tools).
    fn facet_box(&self, t: u32) -> Aabb {
        let c = self.tool.corners(t);
        let grow = Vector::repeat(FACET_REACH_OVER_EDGE * longest_edge(&c));
        Aabb::new(c[0].inf(&c[1]).inf(&c[2]) - grow, c[0].sup(&c[1]).sup(&c[2]) + grow)
    }

    /// [`SmoothSurface::curvature`] at `p` next to facet `t` (see [`SmoothSurface::near_facet`]).
    pub fn curvature_near(&self, region: u32, t: u32, p: &Point) -> Matrix3<f64> {
        match self.near_facet(t, p) {
            Some(candidates) => curvature_of(self.evaluate_among(candidates.iter().copied(), region, p, true)),
            None => self.curvature(region, p),
        }
    }

    /// The faceted tool underneath.
    pub fn tool(&self) -> &ToolSurface {
        self.tool
    }

    /// Number of sharp edges kept sharp.
    pub fn creases(&self) -> usize {
        self.creases
    }

    /// The region (set of facets joined by smooth edges) of facet `t`.
    pub fn region_of(&self, t: u32) -> u32 {
        self.regions[t as usize]
    }

    /// The implicit function of region `region` at `p` and its gradient, or None where no
    /// sector of the region reaches `p`.
    pub fn value_and_gradient(&self, region: u32, p: &Point) -> Option<(f64, Vector)> {
        self.evaluate(region, p, false).map(|(f, g, _)| (f, g))
    }

    /// The implicit function of region `region` at `p`, its gradient and its Hessian.
    pub fn value_gradient_hessian(&self, region: u32, p: &Point) -> Option<(f64, Vector, Matrix3<f64>)> {
        self.evaluate(region, p, true)
    }

    /// f = A / W with A = sum w_s q_s and W = sum w_s; derivatives by the quotient rule.
    fn evaluate(&self, region: u32, p: &Point, hessian: bool) -> Option<(f64, Vector, Matrix3<f64>)> {
        self.evaluate_among(self.bvh.intersect_aabb(&Aabb::new(*p, *p)), region, p, hessian)
    }

    /// [`SmoothSurface::evaluate`] over the sectors `candidates`, which must include every sector
    /// whose support holds `p` (in the order the BVH gives them, so sums agree to the bit).
    fn evaluate_among(
        &self,
        candidates: impl IntoIterator<Item = u32>,
        region: u32,
        p: &Point,
        hessian: bool,
    ) -> Option<(f64, Vector, Matrix3<f64>)> {
        let (mut w_sum, mut a_sum) = (0.0, 0.0);
        let (mut dw_sum, mut da_sum) = (Vector::zeros(), Vector::zeros());
        let (mut hw_sum, mut ha_sum) = (Matrix3::zeros(), Matrix3::zeros());
        for s in candidates {
            let sec = &self.sectors[s as usize];
            if sec.region != region {
                continue;
            }
            let d = p - sec.x;
            // Off a flat face's edge, across it (`a` > 0): the curvature acts and the support
            // reaches `h_off` along `m` (an ellipsoid, r^2 = d^T A d, meeting the face's sphere
            // where a = 0 with r and its gradient continuous).
            let off = sec.edge.and_then(|e| {
                let a = e.m.dot(&d);
                (a > 0.0).then_some((e, a))
            });
            let inv_h2 = 1.0 / (sec.h * sec.h);
            let (r, ad) = match off {
                None => (d.norm() / sec.h, d * inv_h2),
                Some((e, a)) => {
                    let extra = 1.0 / (e.h_off * e.h_off) - inv_h2;
                    ((d.norm_squared() * inv_h2 + a * a * extra).sqrt(), d * inv_h2 + e.m * (a * extra))
                }
            };
            if r >= 1.0 {
                continue;
            }
            let (w, _) = wendland(r);
            let k = if sec.edge.is_none() || off.is_some() { sec.k } else { Matrix3::zeros() };
            let kd = k * d;
            let q = sec.n.dot(&d) + 0.5 * d.dot(&kd);
            let dq = sec.n + kd;
            // w = phi(r): grad w = -20 (1 - r)^3 A d (finite at d = 0).
            let one = 1.0 - r;
            let dw = match off {
                None => d * (-20.0 * one * one * one / (sec.h * sec.h)),
                Some(_) => ad * (-20.0 * one * one * one),
            };
            w_sum += w;
            a_sum += w * q;
            dw_sum += dw;
            da_sum += dw * q + dq * w;
            if hessian {
                // hess w = -20 (1 - r)^3 A + 60 (1 - r)^2 / r (A d) (A d)^T.
                let mut hw = match off {
                    None => {
                        let mut hw = Matrix3::identity() * (-20.0 * one * one * one / (sec.h * sec.h));
                        let dist = d.norm();
                        if dist > 0.0 {
                            hw += d * d.transpose() * (60.0 * one * one / (sec.h * sec.h * sec.h * dist));
                        }
                        hw
                    }
                    Some((e, _)) => {
                        let a_matrix =
                            Matrix3::identity() * inv_h2 + e.m * e.m.transpose() * (1.0 / (e.h_off * e.h_off) - inv_h2);
                        a_matrix * (-20.0 * one * one * one)
                    }
                };
                if let (Some(_), true) = (off, r > 0.0) {
                    hw += ad * ad.transpose() * (60.0 * one * one / r);
                }
                hw_sum += hw;
                ha_sum += hw * q + dw * dq.transpose() + dq * dw.transpose() + k * w;
            }
        }
        if w_sum <= 0.0 {
            return None;
        }
        let f = a_sum / w_sum;
        let grad = (da_sum - dw_sum * f) / w_sum;
        let hess = if hessian {
            (ha_sum - hw_sum * f - grad * dw_sum.transpose() - dw_sum * grad.transpose()) / w_sum
        } else {
            Matrix3::zeros()
        };
        Some((f, grad, hess))
    }

    /// The curvature of the surface at `p` (on it, in region `region`): `C = hess f / |grad f|`,
    /// so that a point moved by the tangent vector t stays on the surface by moving
    /// `-1/2 t^T C t` along the normal.
    pub fn curvature(&self, region: u32, p: &Point) -> Matrix3<f64> {
        curvature_of(self.value_gradient_hessian(region, p))
    }

    /// The point of the smooth surface over `q`: reached from `q` (or, far from the surface,
    /// from its closest facet point) by Newton steps along the implicit function's gradient. For
    /// `q` on the surface, `q` itself. A retraction onto the surface, exact to first order, which
    /// is what sliding contact needs. Beyond an open edge of the tool, onto the surface's
    /// continuation: the tangent plane of the surface over the query's closest point on the edge.
    pub fn project(&self, q: &Point) -> SmoothPoint {
        self.project_from(q, &self.tool.closest_point(q))
    }

    /// As [`SmoothSurface::project`], given the closest facet point `foot` of `q`.
    pub fn project_from(&self, q: &Point, foot: &SurfacePoint) -> SmoothPoint {
        self.project_inner(q, foot, false).0
    }

    /// [`SmoothSurface::project`] and the surface's [`SmoothSurface::curvature`] at the point
    /// found (from the sectors the projection already gathered).
    pub fn project_curved(&self, q: &Point) -> (SmoothPoint, Matrix3<f64>) {
        self.project_inner(q, &self.tool.closest_point(q), true)
    }

    /// [`SmoothSurface::project_from`], and the curvature there if `curved`.
    pub fn project_from_curved_if(
        &self,
        q: &Point,
        foot: &SurfacePoint,
        curved: bool,
    ) -> (SmoothPoint, Option<Matrix3<f64>>) {
        let (point, curvature) = self.project_inner(q, foot, curved);
        (point, curved.then_some(curvature))
    }

    fn project_inner(&self, q: &Point, foot: &SurfacePoint, curved: bool) -> (SmoothPoint, Matrix3<f64>) {
        let region = self.regions[foot.triangle as usize];
        let l = self.tool.barycentric(foot.triangle, &foot.point);
        let off = q - foot.point;
        let beyond_boundary = self.beyond_open_edge(q, foot, &l);
        let (p, normal, curvature) = if beyond_boundary {
            self.past_open_edge(q, foot, curved)
        } else {
            let found = self.onto_region(q, foot, region, curved);
            // The surface lies within a sagitta of the facets. A point found further from the
            // query's facet point than [`SURFACE_BAND_OVER_EDGE`] of the facet's size was reached
            // from a query too far off for Newton's steps (where few sectors reach, the blend's
            // gradient turns with their weights, and its zero set may even run on away from the
            // facets): it is found again from the facet point, on the surface over the facet.
            if (found.0 - foot.point).norm() > SURFACE_BAND_OVER_EDGE * self.longest_edge(foot.triangle) {
                self.onto_region(&foot.point, foot, region, curved)
            } else {
                found
            }
        };
        // A region's implicit surface runs on past its sharp edges (a table's top continues as a
        // plane beyond the rim): where the point found lies across such an edge of the facet under
        // the query, the query is beyond the region and the nearest tool is that edge.
        // Only a query on the outer side of its facet: one inside the tool next to a convex edge
        // is off both faces inwards and goes back out through the surface.
        let (off_n, off_t) = (foot.normal.dot(&off), (off - foot.normal * foot.normal.dot(&off)).norm());
        let outside = off_n >= -BOUNDARY_TOLERANCE_REL * self.tool.diagonal();
        let lp = self.tool.barycentric(foot.triangle, &p);
        let beyond_crease = outside
            && (0..3).any(|k| {
                lp[k] < -CREASE_OVERSHOOT_BARYCENTRIC
                    && self.tool.neighbour(foot.triangle, k).is_some_and(|n| self.regions[n as usize] != region)
            });
        // Off a region's smooth part the query lies within the normals of its facets (which
        // differ by less than the crease angle): a query off its facet at a steeper angle is
        // beyond a sharp edge or corner (a sheet's node beside a table's corner).
        let beyond_edge_or_corner = outside
            && off.norm() > BOUNDARY_TOLERANCE_REL * self.tool.diagonal()
            && off_t > off_n.abs() * CREASE_ANGLE_DEG.to_radians().tan();
        let point = SmoothPoint {
            point: p,
            triangle: foot.triangle,
            barycentric: clamp_barycentric(l),
            normal,
            region,
            beyond_boundary,
            beyond_region: beyond_crease || beyond_edge_or_corner,
        };
        (point, curvature)
    }

    /// Whether `q` lies beyond an open edge of the tool: its closest facet point `foot`
    /// (barycentric `l` on its facet) is on an open edge and `q` is off it outwards.
    fn beyond_open_edge(&self, q: &Point, foot: &SurfacePoint, l: &[f64; 3]) -> bool {
        let off = q - foot.point;
        self.tool.open_edges_at(foot.triangle, l).iter().flatten().any(|m| {
            let tangential = off - foot.normal * foot.normal.dot(&off);
            tangential.dot(m) > BOUNDARY_TOLERANCE_REL * self.tool.diagonal()
        })
    }

    /// `q` taken onto the implicit surface of `region` by Newton steps along its gradient (from
    /// the facet point `foot` where no sector of the region reaches `q`): the point, its normal
    /// and, if `curved`, its curvature.
    fn onto_region(&self, q: &Point, foot: &SurfacePoint, region: u32, curved: bool) -> (Point, Vector, Matrix3<f64>) {
        let tol = PROJECTION_TOLERANCE_REL * self.tool.diagonal();
        let mut p = *q;
        let mut normal = foot.normal;
        let mut restarted = false;
        // The sectors near the Newton iterates, gathered for a box around an iterate and kept
        // while the next ones stay in it: Newton's steps at least halve near the surface, so a box
        // of half the last step holds the rest (a far query's box stays small: a large box
        // gathers sectors that all have to be tried).
        let mut reach = tol;
        let mut near = NearSectors::default();
        for _ in 0..PROJECTION_MAX_ITERATIONS {
            let candidates = match self.near_facet(foot.triangle, &p) {
                Some(c) => c,
                None => near.around(self, &p, reach),
            };
            let Some((f, g, _)) = self.evaluate_among(candidates.iter().copied(), region, &p, false) else {
                if restarted {
                    break;
                }
                restarted = true;
                p = foot.point;
                continue;
            };
            let g2 = g.norm_squared();
            if g2 <= 0.0 {
                break;
            }
            normal = g / g2.sqrt();
            if f.abs() <= tol {
                break;
            }
            p -= g * (f / g2);
            reach = 0.5 * f.abs() / g2.sqrt() + tol;
        }
        let curvature = if curved {
            let candidates = match self.near_facet(foot.triangle, &p) {
                Some(c) => c,
                None => near.around(self, &p, reach),
            };
            curvature_of(self.evaluate_among(candidates.iter().copied(), region, &p, true))
        } else {
            Matrix3::zeros()
        };
        (p, normal, curvature)
    }

    /// `q`, beyond an open edge of the tool, taken onto the surface's continuation there: the
    /// tangent plane of the smooth surface over the query's closest point on the edge (the
    /// surface runs on as it leaves the tool, with its normal continuous across the edge). The
    /// point, its normal and, if `curved`, the continuation's curvature.
    ///
    /// Why not the region's implicit surface, which runs on past the edge too: it runs on only
    /// as far as its sectors' supports reach, a ragged band whose width follows the facets along
    /// the edge, and beyond it the Newton steps fell back to the edge itself. A pressed node
    /// sliding along the edge at a few millimetres out met that band's border as a cliff: the
    /// least move on past it put the node back on the edge, stretching its fibres by millimetres,
    /// and no step that moved it that way lowered the energy (the hat box at 8 mm and +45 deg
    /// stalled there at |F-P|/|P| 1.27).
    fn past_open_edge(&self, q: &Point, foot: &SurfacePoint, curved: bool) -> (Point, Vector, Matrix3<f64>) {
        let tol = PROJECTION_TOLERANCE_REL * self.tool.diagonal();
        let mut foot = *foot;
        let mut p = *q;
        for _ in 0..PROJECTION_MAX_ITERATIONS {
            let region = self.regions[foot.triangle as usize];
            let (edge, normal, _) = self.onto_region(&foot.point, &foot, region, false);
            let lift = normal.dot(&(p - edge));
            if lift.abs() <= tol {
                let curvature = if curved {
                    // The continuation is ruled by straight lines out of the edge: no curvature
                    // along them; across them it curves as the surface at the edge does.
                    let c = self.curvature_near(region, foot.triangle, &edge);
                    let out = p - edge;
                    match (out - normal * normal.dot(&out)).try_normalize(tol) {
                        Some(u) => c - u * u.transpose() * u.dot(&(c * u)),
                        None => c,
                    }
                } else {
                    Matrix3::zeros()
                };
                return (p, normal, curvature);
            }
            // Along the edge's normal, which on a curved tool is not the facet's: the point's
            // closest facet point may move, and with it the edge point the plane is taken at.
            p -= normal * lift;
            foot = self.tool.closest_point_from(&p, Some(foot.triangle));
            let l = self.tool.barycentric(foot.triangle, &foot.point);
            if !self.beyond_open_edge(&p, &foot, &l) {
                // Back over the tool (a point barely beyond an edge that curves inwards).
                return self.onto_region(&p, &foot, self.regions[foot.triangle as usize], curved);
            }
        }
        let region = self.regions[foot.triangle as usize];
        let (edge, normal, _) = self.onto_region(&foot.point, &foot, region, false);
        let curvature = if curved { self.curvature_near(region, foot.triangle, &edge) } else { Matrix3::zeros() };
        (p - normal * normal.dot(&(p - edge)), normal, curvature)
    }
}

/// `C = hess f / |grad f|` from an evaluation of the implicit function (zero where there is none).
fn curvature_of(evaluation: Option<(f64, Vector, Matrix3<f64>)>) -> Matrix3<f64> {
    match evaluation {
        Some((_, g, h)) if g.norm() > 0.0 => h / g.norm(),
        _ => Matrix3::zeros(),
    }
}

/// The sectors whose supports meet a box, kept while the points asked about stay in it.
#[derive(Default)]
struct NearSectors {
    bounds: Option<Aabb>,
    sectors: Vec<u32>,
}

impl NearSectors {
    /// The sectors that may hold `p`: the kept ones if `p` is in the box, else those meeting a
    /// new box of half-width `reach` around `p`.
    fn around(&mut self, surface: &SmoothSurface, p: &Point, reach: f64) -> &[u32] {
        if !self.bounds.is_some_and(|b| b.contains_local_point(p)) {
            let half = Vector::repeat(reach);
            let bounds = Aabb::new(p - half, p + half);
            self.sectors.clear();
            self.sectors.extend(surface.bvh.intersect_aabb(&bounds));
            self.bounds = Some(bounds);
        }
        &self.sectors
    }
}

/// The longest edge of a facet with corners `c`.
fn longest_edge(c: &[Point; 3]) -> f64 {
    (0..3).map(|k| (c[(k + 1) % 3] - c[k]).norm()).fold(0.0, f64::max)
}

/// Marks the sectors on the edge of a flat face ([`FaceEdge`]): a face is a set of facets in one
/// plane joined across edges that spans [`FACE_SPAN`] or more round one of its vertices (two
/// coplanar facets of a quad on a cylinder are not a face). A sector with facets in exactly
/// one face and others, of its region, off it gets the face's normal, the direction across the
/// edge and the support of its facets off the face. (A sector between two faces, a kink
/// softer than a crease, stays as it is: no side is the flat one.)
fn face_edges(tool: &ToolSurface, sectors: &mut [Sector], sector_of_corner: &[usize], regions: &[u32]) {
    let tris = tool.triangles();
    let verts = tool.vertices();
    // Facets in one plane, joined across their edges.
    let mut parent: Vec<usize> = (0..tris.len()).collect();
    for t in 0..tris.len() {
        for k in 0..3 {
            let n = tool.neighbours(t as u32)[k];
            if n == NO_NEIGHBOUR || regions[n as usize] != regions[t] {
                continue;
            }
            if tool.normal(t as u32).dot(&tool.normal(n)) >= 1.0 - COPLANAR_COS_SLACK {
                let (a, b) = (union_find_root(&mut parent, t), union_find_root(&mut parent, n as usize));
                parent[a] = b;
            }
        }
    }
    let plane: Vec<usize> = (0..tris.len()).map(|t| union_find_root(&mut parent, t)).collect();
    // Each sector's facets, and the angle each plane spans at each sector.
    let mut facets: Vec<Vec<usize>> = vec![Vec::new(); sectors.len()];
    let mut spans: Vec<Vec<(usize, f64)>> = vec![Vec::new(); sectors.len()];
    for (corner, &s) in sector_of_corner.iter().enumerate() {
        let (t, c) = (corner / 3, corner % 3);
        facets[s].push(t);
        let p = verts[tris[t][c] as usize];
        let (u, v) = (verts[tris[t][(c + 1) % 3] as usize] - p, verts[tris[t][(c + 2) % 3] as usize] - p);
        let angle = u.cross(&v).norm().atan2(u.dot(&v));
        match spans[s].iter_mut().find(|(q, _)| *q == plane[t]) {
            Some((_, a)) => *a += angle,
            None => spans[s].push((plane[t], angle)),
        }
    }
    // The planes that are faces: spanning FACE_SPAN at some vertex.
    let mut is_face = vec![false; tris.len()];
    for &(q, angle) in spans.iter().flatten() {
        if angle >= FACE_SPAN {
            is_face[q] = true;
        }
    }
    for (s, f) in facets.iter().enumerate() {
        let mut faces: Vec<usize> = f.iter().map(|&t| plane[t]).filter(|&p| is_face[p]).collect();
        faces.sort_unstable();
        faces.dedup();
        let [face] = faces[..] else { continue };
        let off: Vec<usize> = f.iter().copied().filter(|&t| plane[t] != face).collect();
        if off.is_empty() {
            continue;
        }
        let on = f.iter().copied().find(|&t| plane[t] == face).expect("a facet in the face");
        let n = tool.normal(on as u32);
        let x = sectors[s].x;
        // Across the edge: towards the off-face facets' centroids, in the face's plane.
        let towards: Vector = off
            .iter()
            .map(|&t| {
                let c = tris[t].iter().map(|&v| verts[v as usize].coords).sum::<Vector>() / 3.0 - x.coords;
                (c - n * n.dot(&c)).try_normalize(0.0).unwrap_or_else(Vector::zeros)
            })
            .sum();
        let Some(m) = towards.try_normalize(1e-9) else { continue };
        let longest = off.iter().map(|&t| longest_edge(&tool.corners(t as u32))).fold(0.0, f64::max);
        let sec = &mut sectors[s];
        sec.n = n;
        sec.edge = Some(FaceEdge { m, h_off: (SUPPORT_OVER_EDGE * longest).min(sec.h) });
    }
}

/// The curvature of a sector on a face's edge: `kappa m m^T`, kappa fitted to the normals of
/// its neighbours across the edge (Weingarten along m, weighted least squares as
/// [`fit_curvature`]); zero where none lies across it.
fn fit_edge_curvature(sectors: &[Sector], s: usize, edge: &FaceEdge, neighbours: &[usize]) -> Matrix3<f64> {
    let sec = &sectors[s];
    let (mut num, mut den) = (0.0, 0.0);
    for &j in neighbours {
        let o = &sectors[j];
        let d = o.x - sec.x;
        let a = edge.m.dot(&d);
        let len2 = (d - sec.n * sec.n.dot(&d)).norm_squared();
        if a <= 0.0 || len2 <= 0.0 {
            continue;
        }
        let w = 1.0 / len2;
        num += w * a * edge.m.dot(&(o.n - sec.n));
        den += w * a * a;
    }
    if den <= 0.0 {
        return Matrix3::zeros();
    }
    edge.m * edge.m.transpose() * (num / den)
}

/// The curvature tensor of sector `s` fitted to its neighbours' normals: in the tangent frame
/// (t1, t2) of n_s, the tangential change of the normal to each neighbour j is K times the
/// tangential offset (Weingarten), weighted least squares over the neighbours; lifted to 3-D.
fn fit_curvature(sectors: &[Sector], s: usize, neighbours: &[usize]) -> Matrix3<f64> {
    let sec = &sectors[s];
    let n = sec.n;
    let helper = if n.x.abs() < 0.6 { Vector::x() } else { Vector::y() };
    let t1 = n.cross(&helper).normalize();
    let t2 = n.cross(&t1);
    // Unknowns (a, b, c) of K = [[a, b], [b, c]]: rows (u1, u2, 0) . = dn1 and (0, u1, u2) . = dn2.
    let mut ata = Matrix3::<f64>::zeros();
    let mut atb = nalgebra::Vector3::<f64>::zeros();
    for &j in neighbours {
        let o = &sectors[j];
        let d = o.x - sec.x;
        let u = Vector2::new(t1.dot(&d), t2.dot(&d));
        let len2 = u.norm_squared();
        if len2 <= 0.0 {
            continue;
        }
        let dn = o.n - n;
        let w = 1.0 / len2; // each neighbour counts as a direction, whatever its distance
        for (row, rhs) in
            [(nalgebra::Vector3::new(u.x, u.y, 0.0), t1.dot(&dn)), (nalgebra::Vector3::new(0.0, u.x, u.y), t2.dot(&dn))]
        {
            ata += row * row.transpose() * w;
            atb += row * (rhs * w);
        }
    }
    let ridge = CURVATURE_FIT_RIDGE * ata.trace().max(f64::MIN_POSITIVE);
    let Some(abc) = (ata + Matrix3::identity() * ridge).lu().solve(&atb) else { return Matrix3::zeros() };
    let k2 = Matrix2::new(abc.x, abc.y, abc.y, abc.z);
    let frame = nalgebra::Matrix3x2::from_columns(&[t1, t2]);
    frame * k2 * frame.transpose()
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
        for q in [Point::new(0.3, 0.2, 0.5), Point::new(-0.7, 0.1, -0.2), Point::new(0.31, -0.17, 0.0)] {
            let s = smooth.project(&q);
            assert!((s.point - Point::new(q.x, q.y, 0.0)).norm() < 1e-13, "{}", s.point);
            assert!((s.normal - tool.normal(s.triangle)).norm() < 1e-13);
        }
    }

    #[test]
    fn a_dies_face_stays_flat_up_to_its_fillet_and_the_fillet_stays_round() {
        // A die's flat face meets its entry fillet tangentially (opening R 80 mm, fillet 10 mm,
        // eight facets over its quarter turn): the face's smooth surface is the face's plane
        // (averaged over both sides, the edge's sectors tilted by half a facet's turn, 0.08 rad
        // on the face, and bulged out of it by 0.4 mm), and the fillet is followed about as
        // closely as by its facets: 1.5e-5 m from the face to 50 deg round it, 6e-5 m next to the
        // wall (a cylinder, not a face: its sectors average over the junction as before),
        // against the facets' 4.7e-5 m.
        let (opening, fillet) = (0.08, 0.01);
        let tool = shapes::die_ring(opening, fillet, 0.22, 0.07, 192, [8, 8, 12]).into_surface().unwrap();
        let smooth = SmoothSurface::new(&tool);
        // Beyond the reach of the fillet's own sectors (1.5 times its facets' longest edge) the
        // face is its plane; nearer, the fillet's quadrics run on into the face and it recedes
        // into the die by micrometres (4.4e-6 m at the edge), never out of it.
        let reach = 1.5 * (fillet * std::f64::consts::FRAC_PI_2 / 7.0).hypot(std::f64::consts::TAU * 0.09 / 192.0);
        let (mut face, mut recess, mut out) = (0.0f64, 0.0f64, 0.0f64);
        for i in 0..400 {
            let (r, t) = (opening + fillet + 1e-6 + 0.12 * (i as f64 / 399.0).powi(2), 0.37 * i as f64);
            let s = smooth.project(&Point::new(r * t.cos(), r * t.sin(), -0.003));
            // The die's solid lies at z > 0, the blank's side at z < 0.
            out = out.max(-s.point.z);
            if r > opening + fillet + reach {
                face = face.max(s.point.z.abs()).max(s.normal.xy().norm());
            } else {
                recess = recess.max(s.point.z);
            }
        }
        assert!(face < 1e-12, "past the fillet's reach the face leaves its plane by {face:e}");
        assert!(out < 1e-15 && recess < 1e-5, "the face bulges out by {out:e} and in by {recess:e}");
        let (mut smooth_err, mut facet_err) = (0.0f64, 0.0f64);
        for i in 0..200 {
            let (a, t) = (std::f64::consts::FRAC_PI_2 * i as f64 / 199.0, 0.61 * i as f64);
            let (r, z) = (opening + fillet * (1.0 - a.sin()), fillet * (1.0 - a.cos()));
            let q = Point::new(r * t.cos(), r * t.sin(), z);
            let off = |p: &Point| ((p.x.hypot(p.y) - opening - fillet).hypot(p.z - fillet) - fillet).abs();
            smooth_err = smooth_err.max(off(&smooth.project(&q).point));
            facet_err = facet_err.max(off(&tool.closest_point(&q).point));
        }
        println!("die fillet: smooth {smooth_err:e} facets {facet_err:e}");
        assert!(smooth_err < 2.0 * facet_err, "smooth {smooth_err:e} facets {facet_err:e}");
    }

    #[test]
    fn a_projection_with_its_curvature_agrees_with_the_separate_queries_to_the_bit() {
        // The sectors a projection gathers once must give what a BVH query a step gives: the
        // same point, normal and curvature, for queries near the surface and far from it.
        let tool = shapes::hemisphere(1.0, 12).into_surface().unwrap();
        let smooth = SmoothSurface::new(&tool);
        for i in 0..30 {
            for (k, lift) in [1e-9, 1e-4, 0.02, 0.3].into_iter().enumerate() {
                let (theta, phi) = (1.4 * i as f64 / 29.0, 0.7 * i as f64 + k as f64);
                let dir = Vector::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos());
                let q = Point::from(dir * (1.0 + lift));
                let (s, curvature) = smooth.project_curved(&q);
                let plain = smooth.project(&q);
                assert_eq!(s, plain);
                assert_eq!(curvature, smooth.curvature(s.region, &s.point), "at {q}");
                // The same from the sectors kept beside the facet (a foot's curvature computed
                // after its projection, `mechanics::contact`).
                assert_eq!(curvature, smooth.curvature_near(s.region, s.triangle, &s.point), "at {q}");
            }
        }
    }

    #[test]
    fn past_an_open_edge_the_surface_runs_on_as_its_tangent_plane_without_a_jump() {
        // The hemisphere's rim is open and its wall about vertical there: beyond the rim the
        // surface runs on downwards. Walked out from the rim, the projections move steadily,
        // project onto themselves and stay by the query: the region's implicit surface ran on
        // only as far as its sectors reached (about 0.2 here) and past that the projection
        // jumped back onto the rim.
        let tool = shapes::hemisphere(1.0, 12).into_surface().unwrap();
        let smooth = SmoothSurface::new(&tool);
        let step = 0.005;
        for phi in [0.1f64, 0.7, 2.0, 4.4] {
            let mut last = smooth.project(&Point::new(phi.cos(), phi.sin(), 0.0));
            for k in 1..=100 {
                let q = Point::new(phi.cos(), phi.sin(), -step * k as f64);
                let s = smooth.project(&q);
                assert!(s.beyond_boundary, "{q} is past the rim");
                assert!((s.point - last.point).norm() < 2.0 * step, "at {q}: {} after {}", s.point, last.point);
                assert!((s.point - q).norm() < 0.1 * (q.z.abs() + step), "at {q}: {}", s.point);
                assert!(s.normal.angle(&last.normal) < 1e-2, "the normal turns at {q}");
                let again = smooth.project(&s.point);
                assert!((again.point - s.point).norm() < 1e-12, "{} vs {}", again.point, s.point);
                last = s;
            }
        }
    }

    #[test]
    fn hemisphere_surface_follows_the_sphere_far_closer_than_the_facets() {
        let r = 1.0;
        let tool = shapes::hemisphere(r, 12).into_surface().unwrap();
        let smooth = SmoothSurface::new(&tool);
        let (mut facet_err, mut smooth_err, mut facet_angle, mut smooth_angle) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
        for i in 0..40 {
            for j in 0..40 {
                let (theta, phi) = (1.3 * i as f64 / 39.0, std::f64::consts::TAU * j as f64 / 40.0);
                let q = Point::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos()) * r;
                let f = tool.closest_point(&q);
                let s = smooth.project(&q);
                facet_err = facet_err.max(r - f.point.coords.norm());
                smooth_err = smooth_err.max((s.point.coords.norm() - r).abs());
                facet_angle = facet_angle.max(f.normal.angle(&f.point.coords));
                smooth_angle = smooth_angle.max(s.normal.angle(&s.point.coords));
                // Points on the surface project onto themselves.
                let again = smooth.project(&s.point);
                assert!((again.point - s.point).norm() < 1e-12, "{} vs {}", again.point, s.point);
            }
        }
        println!("sphere: smooth {smooth_err:e} facet {facet_err:e} angles {smooth_angle:e} {facet_angle:e}");
        assert!(smooth_err < facet_err / 8.0, "smooth {smooth_err:e} facet {facet_err:e}");
        assert!(smooth_angle < facet_angle / 4.0, "smooth {smooth_angle:e} facet {facet_angle:e}");
    }

    #[test]
    fn the_normal_turns_continuously_across_facet_edges() {
        // Along a line crossing many edges of the double dome's coarse walls, the normal of the
        // smooth surface changes by a small angle per small step: no kinks.
        let tool = crate::io::read_tool(
            std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/geometries/double-dome/double-dome.obj")),
            1.0,
        )
        .unwrap();
        let smooth = SmoothSurface::new(&tool);
        assert_eq!(smooth.creases(), 0, "no edge of the double dome is sharper than the crease angle");
        let steps = 4000;
        let mut worst_rate = 0.0f64;
        let mut previous: Option<SmoothPoint> = None;
        for k in 0..=steps {
            // Across the wall and both fillets at the body's side (y from 0 to 0.12 m).
            let y = 0.12 * k as f64 / steps as f64;
            let q = Point::new(0.013, y, 0.1);
            let s = smooth.project(&tool.closest_point(&q).point);
            if let Some(p) = previous {
                let ds = (s.point - p.point).norm();
                if ds > 0.0 {
                    worst_rate = worst_rate.max(s.normal.angle(&p.normal) / ds);
                }
            }
            previous = Some(s);
        }
        // The fillets' radius is 0.015 m: the normal turns at about 1/0.015 = 67 rad/m there. A
        // kink would show as a rate of (kink angle) / (step of 3e-5 m), thousands of rad/m.
        println!("worst rate {worst_rate}");
        assert!(worst_rate < 300.0, "the normal turns at up to {worst_rate} rad/m");
    }

    #[test]
    fn sharp_edges_stay_sharp_and_their_faces_flat() {
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
        for q in [
            Point::new(-0.01, 0.37, 0.3),
            Point::new(-0.6, 0.5, 0.1),
            Point::new(0.2, 0.3, 0.5),
            Point::new(-0.001, 0.5, 0.002),
        ] {
            let s = smooth.project(&q);
            let f = tool.closest_point(&q);
            assert!((s.point - f.point).norm() < 1e-13, "{} vs {}", s.point, f.point);
            assert!((s.normal - f.normal).norm() < 1e-13);
        }
    }

    #[cfg(feature = "shapes")]
    #[test]
    fn beside_a_sharp_rim_or_corner_the_nearest_tool_is_the_edge_itself() {
        // A square table 0.1 m wide, its top at z = 0: the top's plane runs on past the rim, but
        // a point beside the rim or beside a corner is off the table, at its distance from the
        // edge; points over the top and beside the walls are on the faces.
        let mesh = crate::geometry::shapes::table_box(0.1, 0.1, 0.1, 10);
        let tool = ToolSurface::from_triangles(mesh.vertices, mesh.triangles).unwrap();
        let smooth = SmoothSurface::new(&tool);
        for q in [Point::new(0.06, 0.01, 0.0), Point::new(-0.05, 0.065, 0.0), Point::new(0.07, 0.08, 0.003)] {
            let s = smooth.project(&q);
            assert!(s.beyond_region, "{q} is beyond the rim");
        }
        for q in [
            Point::new(0.01, 0.02, 0.004),
            Point::new(0.058, 0.01, -0.03),
            Point::new(0.049, 0.0, 1e-12),
            Point::new(0.0495, 0.01, -0.0005),
        ] {
            let s = smooth.project(&q);
            assert!(!s.beyond_region, "{q} is over a face");
            let f = tool.closest_point(&q);
            assert!((s.point - f.point).norm() < 1e-12, "flat faces stay flat: {} vs {}", s.point, f.point);
        }
    }
}
