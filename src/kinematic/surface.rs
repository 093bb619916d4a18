//! [`DrapeSurface`]: what the fishnet and its generators ask of the surface they drape on, so one
//! fishnet implementation runs on the faceted tool ([`ToolSurface`], the default) and on the
//! smooth surface the facets stand for ([`SmoothSurface`], the one the pressed contact slides
//! on). The fill is generic over the trait (monomorphised): the facet path compiles to what it was.
//!
//! Both surfaces search the circle's crossings on the facets (the exact closed form, a flood fill
//! from the parents' facets, the BVH beyond); the smooth surface then moves the chosen crossing
//! along the circle onto its own surface by Newton steps on the circle parameter. Its crossing
//! lies within the facets' sagitta of the facet crossing, so the choice of root, the fold and
//! sheet-jump tests and the node statuses keep their meaning.
use super::fishnet::{circle_root, Placed};
use super::SurfaceKind;
use crate::geometry::geodesic::TraceState;
use crate::geometry::surface::{Circle, CircleRoot};
use crate::geometry::{Point, SmoothSurface, SurfacePoint, ToolSurface, Vector, NO_NEIGHBOUR};

/// Newton steps on the circle parameter that move a facet crossing onto the smooth surface (it
/// converges quadratically from within the facets' sagitta: 2-3 steps).
const CIRCLE_NEWTON_MAX_ITERATIONS: usize = 12;
/// The Newton iteration stops when |f| (about the distance to the surface) or the step along the
/// circle falls below this fraction of the tool's bounding-box diagonal.
const CIRCLE_NEWTON_TOLERANCE_REL: f64 = 1e-13;
/// Once |f| is below this fraction of the diagonal, one more Newton step brings it (quadratic
/// convergence) far below [`CIRCLE_NEWTON_TOLERANCE_REL`]: that step is taken without checking.
const CIRCLE_NEWTON_LAST_STEP_REL: f64 = 1e-9;
/// A Newton step along the circle longer than this (radians) means the smooth surface has no
/// crossing near the facet one (the circle grazes it): the root is dropped.
const CIRCLE_NEWTON_MAX_STEP: f64 = 0.5;
/// Facets walked from a crossing's facet to the one under the moved point, at most (the point
/// moves by a second-order amount, so one step is usual).
const MAX_WALK: usize = 16;
/// A point is over a facet when its barycentric coordinates are above minus this.
const WALK_TOLERANCE: f64 = 1e-12;

/// The surface a kinematic drape lies on: the queries the fishnet step and the generators make.
pub trait DrapeSurface: Sync {
    /// A geodesic being followed (position, facet, direction).
    type Trace: Copy + Send + Sync;

    /// The faceted tool underneath (the crossings are searched on its facets).
    fn tool(&self) -> &ToolSurface;
    /// Which surface this is (recorded in the net's provenance).
    fn kind(&self) -> SurfaceKind;
    /// The point of the surface nearest to `p` (the seed), with its facet and normal; `distance`
    /// is from `p`.
    fn seed(&self, p: &Point) -> SurfacePoint;
    /// Unit normal of the surface at a placed point (on the tool's outer side).
    fn normal(&self, at: &Placed) -> Vector;
    /// The crossing of `circle` with this surface that corresponds to the facet crossing `root`,
    /// or None when there is none near it (the circle grazes the surface there).
    fn on_surface(&self, circle: &Circle, root: &CircleRoot) -> Option<CircleRoot>;
    /// A geodesic leaving `at` along `dir` (projected onto the tangent plane), or None when
    /// `dir` is normal to the surface.
    fn start_trace(&self, at: &Placed, dir: &Vector) -> Option<Self::Trace>;
    /// The unit direction of a trace.
    fn trace_dir(&self, trace: &Self::Trace) -> Vector;
    /// The same point, heading turned counter-clockwise about the normal by `angle`.
    fn turned(&self, trace: &Self::Trace, angle: f64) -> Option<Self::Trace>;
    /// Follow the geodesic to the first point at straight-line distance `d` from `from` (where
    /// the trace stands), or None where it leaves the tool.
    fn advance_chord(&self, trace: &mut Self::Trace, from: &Point, d: f64) -> Option<Placed>;
}

impl DrapeSurface for ToolSurface {
    type Trace = TraceState;

    #[inline]
    fn tool(&self) -> &ToolSurface {
        self
    }
    fn kind(&self) -> SurfaceKind {
        SurfaceKind::Facets
    }
    fn seed(&self, p: &Point) -> SurfacePoint {
        self.closest_point(p)
    }
    #[inline]
    fn normal(&self, at: &Placed) -> Vector {
        ToolSurface::normal(self, at.triangle)
    }
    #[inline]
    fn on_surface(&self, _circle: &Circle, root: &CircleRoot) -> Option<CircleRoot> {
        Some(*root)
    }
    fn start_trace(&self, at: &Placed, dir: &Vector) -> Option<TraceState> {
        TraceState::new(self, at.point, at.triangle, dir)
    }
    fn trace_dir(&self, trace: &TraceState) -> Vector {
        trace.dir
    }
    fn turned(&self, trace: &TraceState, angle: f64) -> Option<TraceState> {
        trace.turned(self, angle)
    }
    fn advance_chord(&self, trace: &mut TraceState, from: &Point, d: f64) -> Option<Placed> {
        let p = trace.advance_chord(self, from, d).ok()?;
        Some(Placed { point: p, triangle: trace.triangle })
    }
}

/// A geodesic on the smooth surface: where it stands and its unit tangent direction.
#[derive(Debug, Clone, Copy)]
pub struct SmoothTrace {
    /// The point on the surface.
    pub at: Placed,
    /// Unit direction in the tangent plane there.
    pub dir: Vector,
}

impl SmoothSurface<'_> {
    /// The surface's unit normal at `p` in the region of facet `t` (the facet's normal where no
    /// sector reaches `p`).
    fn normal_near(&self, t: u32, p: &Point) -> Vector {
        self.value_and_gradient(self.region_of(t), p)
            .and_then(|(_, g)| g.try_normalize(0.0))
            .unwrap_or_else(|| self.tool().normal(t))
    }

    /// Newton on the circle parameter from the facet crossing `root`, on region `region`.
    fn circle_newton(&self, circle: &Circle, root: &CircleRoot, region: u32) -> Option<Point> {
        let tol = CIRCLE_NEWTON_TOLERANCE_REL * self.tool().diagonal();
        let last = CIRCLE_NEWTON_LAST_STEP_REL * self.tool().diagonal();
        let rel = root.point - circle.center;
        let mut theta = rel.dot(&circle.e2).atan2(rel.dot(&circle.e1));
        for _ in 0..CIRCLE_NEWTON_MAX_ITERATIONS {
            let (s, c) = theta.sin_cos();
            let x = circle.center + (circle.e1 * c + circle.e2 * s) * circle.radius;
            let (f, g) = self.value_and_gradient(region, &x)?;
            if f.abs() <= tol {
                return Some(x);
            }
            let df = g.dot(&((circle.e2 * c - circle.e1 * s) * circle.radius));
            if !(df.abs() > 0.0) {
                return None;
            }
            let step = f / df;
            if !(step.abs() <= CIRCLE_NEWTON_MAX_STEP) {
                return None;
            }
            theta -= step;
            if f.abs() <= last || step.abs() * circle.radius <= tol {
                let (s, c) = theta.sin_cos();
                return Some(circle.center + (circle.e1 * c + circle.e2 * s) * circle.radius);
            }
        }
        None
    }

    /// The facet under `p`, walked to from facet `t`: stops at the tool's open boundary (the
    /// point stays with the last facet) and at a sharp edge, returning the facet beyond it.
    fn walk(&self, t: u32, p: &Point) -> (u32, Option<u32>) {
        let tool = self.tool();
        let mut cur = t;
        for _ in 0..MAX_WALK {
            let l = tool.barycentric(cur, p);
            let k = (0..3).min_by(|&a, &b| l[a].total_cmp(&l[b])).unwrap_or(0);
            if l[k] >= -WALK_TOLERANCE {
                return (cur, None);
            }
            let n = tool.neighbours(cur)[k];
            if n == NO_NEIGHBOUR {
                return (cur, None);
            }
            if self.region_of(n) != self.region_of(cur) {
                return (cur, Some(n));
            }
            cur = n;
        }
        (cur, None)
    }
}

impl DrapeSurface for SmoothSurface<'_> {
    type Trace = SmoothTrace;

    fn tool(&self) -> &ToolSurface {
        SmoothSurface::tool(self)
    }
    fn kind(&self) -> SurfaceKind {
        SurfaceKind::Smooth
    }
    fn seed(&self, p: &Point) -> SurfacePoint {
        let s = self.project(p);
        let (triangle, _) = self.walk(s.triangle, &s.point);
        SurfacePoint { point: s.point, triangle, normal: s.normal, distance: (s.point - p).norm() }
    }
    fn normal(&self, at: &Placed) -> Vector {
        self.normal_near(at.triangle, &at.point)
    }
    fn on_surface(&self, circle: &Circle, root: &CircleRoot) -> Option<CircleRoot> {
        let region = self.region_of(root.triangle);
        let x = self.circle_newton(circle, root, region)?;
        let (t, beyond) = self.walk(root.triangle, &x);
        let (x, t) = match beyond {
            None => (x, t),
            // Carried across a sharp edge on this region's continuation: the crossing belongs
            // to the region beyond it.
            Some(n) => {
                let x = self.circle_newton(circle, root, self.region_of(n))?;
                (x, self.walk(n, &x).0)
            }
        };
        let rel = x - circle.center;
        let cos_t = rel.dot(&circle.e1) / rel.norm();
        Some(CircleRoot { point: x, triangle: t, cos_t })
    }
    fn start_trace(&self, at: &Placed, dir: &Vector) -> Option<SmoothTrace> {
        let n = self.normal_near(at.triangle, &at.point);
        let d = (dir - n * n.dot(dir)).try_normalize(1e-12 * dir.norm())?;
        Some(SmoothTrace { at: *at, dir: d })
    }
    fn trace_dir(&self, trace: &SmoothTrace) -> Vector {
        trace.dir
    }
    fn turned(&self, trace: &SmoothTrace, angle: f64) -> Option<SmoothTrace> {
        let n = self.normal_near(trace.at.triangle, &trace.at.point);
        let (s, c) = angle.sin_cos();
        let d = (trace.dir * c + n.cross(&trace.dir) * s).try_normalize(0.0)?;
        Some(SmoothTrace { at: trace.at, dir: d })
    }
    /// The discrete geodesic of chords d: the next node lies in the plane of the direction and
    /// the surface normal at the current one (the chords' second difference is along the normal,
    /// the discrete form of a geodesic's curvature being normal to the surface), and the next
    /// direction is the chord's projection onto the tangent plane at the new node.
    fn advance_chord(&self, trace: &mut SmoothTrace, from: &Point, d: f64) -> Option<Placed> {
        let n = self.normal_near(trace.at.triangle, from);
        let e2 = (n - trace.dir * trace.dir.dot(&n)).try_normalize(1e-12)?;
        let circle = Circle { center: *from, e1: trace.dir, e2, radius: d };
        let root = circle_root(self, &circle, d, [trace.at.triangle, trace.at.triangle]).ok()?;
        // Only ahead: a geodesic does not turn back.
        if root.cos_t <= 0.0 {
            return None;
        }
        let at = Placed { point: root.point, triangle: root.triangle };
        let m = self.normal_near(at.triangle, &at.point);
        let chord = at.point - from;
        let dir = (chord - m * m.dot(&chord)).try_normalize(1e-12 * d)?;
        *trace = SmoothTrace { at, dir };
        Some(at)
    }
}
