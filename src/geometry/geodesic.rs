//! Straightest geodesics on a triangle mesh (Polthier & Schmies): straight within a triangle,
//! unfolded across edges (the angle to the edge is kept), and leaving a vertex with half the total
//! angle around that vertex on either side. On a developable strip this is the straight line of
//! the unfolded strip, exactly.
use super::surface::ToolSurface;
use super::{Point, Vector};

/// A barycentric coordinate below this (relative) means "on the edge/vertex".
pub const VERTEX_TOLERANCE: f64 = 1e-9;
/// Most triangles one trace may cross before it is stopped (guards against broken topology).
pub const MAX_CROSSINGS: usize = 10_000_000;
/// Most zero-length crossings in a row before a trace is declared stuck.
const MAX_STALLED: usize = 64;
/// Most triangles walked around one vertex fan.
const MAX_FAN: usize = 1024;

/// Where a geodesic is: a point in a triangle and a unit direction in that triangle's plane.
#[derive(Debug, Clone, Copy)]
pub struct TraceState {
    /// The point.
    pub point: Point,
    /// The triangle it lies in.
    pub triangle: u32,
    /// Unit direction in the triangle's plane.
    pub dir: Vector,
    /// Edge (by opposite corner) through which the trace entered `triangle`, if any.
    entry_edge: Option<usize>,
    /// Corner of `triangle` the trace sits on (after passing a vertex), if any.
    at_corner: Option<usize>,
}

/// Why a geodesic stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TraceStop {
    /// It reached an open boundary edge or a non-manifold edge of the tool.
    Boundary,
    /// It reached a vertex on the tool boundary.
    BoundaryVertex,
    /// Too many triangle crossings, or a direction that is not tangent to the tool.
    Degenerate,
}

/// Barycentric coordinates of point `p` and the barycentric rate of direction `dir` in `t`.
fn bary_point_and_rate(tool: &ToolSurface, t: u32, p: &Point, dir: &Vector) -> ([f64; 3], [f64; 3]) {
    let l = tool.barycentric(t, p);
    let q = tool.barycentric(t, &(p + dir));
    (l, [q[0] - l[0], q[1] - l[1], q[2] - l[2]])
}

/// Corner index of global vertex `v` in triangle `t`.
fn corner_of(tool: &ToolSurface, t: u32, v: u32) -> Option<usize> {
    tool.triangle(t).iter().position(|&x| x == v)
}

/// Angle between two vectors, robust for small and large angles.
fn angle_between(a: &Vector, b: &Vector) -> f64 {
    a.cross(b).norm().atan2(a.dot(b))
}

/// Rotate the unit vector `u` towards `toward` (both in one plane) by `angle`.
fn rotate_towards(u: &Vector, toward: &Vector, angle: f64) -> Vector {
    let perp = toward - u * u.dot(toward);
    let perp = perp.try_normalize(1e-300).unwrap_or_else(|| u.cross(&Vector::z()).normalize());
    (u * angle.cos() + perp * angle.sin()).normalize()
}

/// The one-ring fan of vertex `v`, walked counter-clockwise (about the oriented normals) from
/// triangle `t`: each entry is (triangle, unit edge direction where the sector starts, unit edge
/// direction where it ends). Returns the fan and whether it closed (interior vertex).
fn vertex_fan(tool: &ToolSurface, t: u32, v: u32) -> (Vec<(u32, Vector, Vector)>, bool) {
    let vp = tool.vertices()[v as usize];
    let mut fan = Vec::new();
    let mut cur = t;
    for _ in 0..MAX_FAN {
        let Some(c) = corner_of(tool, cur, v) else { return (fan, false) };
        let tri = tool.triangle(cur);
        let a = tool.vertices()[tri[(c + 1) % 3] as usize];
        let b = tool.vertices()[tri[(c + 2) % 3] as usize];
        fan.push((cur, (a - vp).normalize(), (b - vp).normalize()));
        // Counter-clockwise: leave through edge (v, b), the edge opposite corner c+1.
        match tool.neighbour(cur, (c + 1) % 3) {
            Some(n) if n == t => return (fan, true),
            Some(n) => cur = n,
            None => return (fan, false),
        }
    }
    (fan, false)
}

/// Turn `angle` counter-clockwise around vertex `v` starting from the unit direction `u` (which
/// lies in the sector of triangle `t` at `v`). Returns the triangle and unit direction reached.
fn turn_about_vertex(tool: &ToolSurface, t: u32, v: u32, u: &Vector, angle: f64) -> Option<(u32, Vector)> {
    let (fan, closed) = vertex_fan(tool, t, v);
    let total: f64 = fan.iter().map(|(_, a, b)| angle_between(a, b)).sum();
    let mut remaining = angle;
    if closed {
        remaining = remaining.rem_euclid(total);
    }
    // First sector: from u to the sector's end edge.
    let (t0, _, end0) = fan[0];
    let avail = angle_between(u, &end0);
    if remaining <= avail {
        return Some((t0, rotate_towards(u, &end0, remaining)));
    }
    remaining -= avail;
    for &(ti, start, end) in fan.iter().skip(1).chain(fan.first()) {
        let avail = angle_between(&start, &end);
        if remaining <= avail {
            return Some((ti, rotate_towards(&start, &end, remaining)));
        }
        remaining -= avail;
    }
    None
}

/// Total angle around vertex `v` (sum of corner angles), and whether the vertex is interior.
pub fn vertex_angle(tool: &ToolSurface, t: u32, v: u32) -> (f64, bool) {
    let (fan, closed) = vertex_fan(tool, t, v);
    (fan.iter().map(|(_, a, b)| angle_between(a, b)).sum(), closed)
}

impl TraceState {
    /// Start a geodesic at surface point `point` in triangle `t` heading along `dir` (projected
    /// onto the triangle's plane). Returns `None` when `dir` is normal to the tool.
    pub fn new(tool: &ToolSurface, point: Point, t: u32, dir: &Vector) -> Option<Self> {
        let n = tool.normal(t);
        let d = (dir - n * n.dot(dir)).try_normalize(1e-12 * dir.norm())?;
        let mut s = TraceState { point, triangle: t, dir: d, entry_edge: None, at_corner: None };
        let l = tool.barycentric(t, &point);
        if let Some(c) = (0..3).find(|&c| l[c] > 1.0 - VERTEX_TOLERANCE) {
            // On a vertex: find the fan sector that holds the direction.
            s = Self::at_vertex_towards(tool, t, tool.triangle(t)[c], dir)?;
        }
        Some(s)
    }

    /// A trace leaving vertex `v` along direction `dir`. The direction is projected onto the
    /// vertex's tangent plane (angle-weighted normal) and located among the projected fan edges;
    /// it then leaves at the same fraction of that sector's true angle. A direction along a
    /// projected mesh edge thus leaves exactly along that edge, whatever the facets' tilt.
    fn at_vertex_towards(tool: &ToolSurface, t: u32, v: u32, dir: &Vector) -> Option<Self> {
        let (fan, _) = vertex_fan(tool, t, v);
        let normal = fan
            .iter()
            .fold(Vector::zeros(), |s, (ti, a, b)| s + tool.normal(*ti) * angle_between(a, b))
            .try_normalize(1e-300)?;
        let flat = |w: &Vector| w - normal * normal.dot(w);
        let target = flat(dir).try_normalize(1e-12 * dir.norm())?;
        // Counter-clockwise angle from x to y in the tangent plane, in [0, 2 pi).
        let ccw = |x: &Vector, y: &Vector| x.cross(y).dot(&normal).atan2(x.dot(y)).rem_euclid(std::f64::consts::TAU);
        let vp = tool.vertices()[v as usize];
        for &(ti, a, b) in &fan {
            let (fa, fb) = (flat(&a), flat(&b));
            let (sector, to_dir) = (ccw(&fa, &fb), ccw(&fa, &target));
            if to_dir <= sector && sector > 0.0 {
                let d = rotate_towards(&a, &b, angle_between(&a, &b) * (to_dir / sector));
                let c = corner_of(tool, ti, v)?;
                return Some(TraceState { point: vp, triangle: ti, dir: d, entry_edge: None, at_corner: Some(c) });
            }
        }
        // An open fan that does not hold the direction: leave along the nearer end edge.
        let (t_first, a_first, _) = *fan.first()?;
        let (t_last, _, b_last) = *fan.last()?;
        let (ti, d) = if angle_between(&a_first, &target) <= angle_between(&b_last, &target) {
            (t_first, a_first)
        } else {
            (t_last, b_last)
        };
        Some(TraceState { point: vp, triangle: ti, dir: d, entry_edge: None, at_corner: Some(corner_of(tool, ti, v)?) })
    }

    /// The same point, heading in the direction turned counter-clockwise (about the tool normal)
    /// by `angle` from this state's direction. At a vertex the angle is scaled by the vertex's
    /// total angle over 2 pi (Polthier's polar angle), so opposite directions stay straightest.
    pub fn turned(&self, tool: &ToolSurface, angle: f64) -> Option<Self> {
        if let Some(c) = self.at_corner {
            let v = tool.triangle(self.triangle)[c];
            let (total, closed) = vertex_angle(tool, self.triangle, v);
            let scaled =
                if closed { angle.rem_euclid(std::f64::consts::TAU) * total / std::f64::consts::TAU } else { angle };
            let (t2, d2) = turn_about_vertex(tool, self.triangle, v, &self.dir, scaled)?;
            let c2 = corner_of(tool, t2, v)?;
            return Some(TraceState {
                point: self.point,
                triangle: t2,
                dir: d2,
                entry_edge: None,
                at_corner: Some(c2),
            });
        }
        let n = tool.normal(self.triangle);
        let d = (self.dir * angle.cos() + n.cross(&self.dir) * angle.sin()).normalize();
        Some(TraceState { dir: d, entry_edge: None, ..*self })
    }

    /// Follow the geodesic until the first point at straight-line distance `d` from `from`
    /// (which should be where the walk started), and stop there.
    pub fn advance_chord(&mut self, tool: &ToolSurface, from: &Point, d: f64) -> Result<Point, TraceStop> {
        let mut stalled = 0;
        for _ in 0..MAX_CROSSINGS {
            let t = self.triangle;
            let (l, rate) = bary_point_and_rate(tool, t, &self.point, &self.dir);
            // Exit parameter: the first edge whose barycentric coordinate reaches zero.
            let mut exit: Option<(f64, usize)> = None;
            for k in 0..3 {
                if Some(k) == self.entry_edge {
                    continue;
                }
                if let Some(c) = self.at_corner {
                    if k != c {
                        continue; // from a vertex, only the opposite edge can be crossed
                    }
                }
                if rate[k] < 0.0 {
                    let s = (-l[k] / rate[k]).max(0.0);
                    if exit.is_none_or(|(se, _)| s < se) {
                        exit = Some((s, k));
                    }
                }
            }
            let Some((s_exit, k)) = exit else { return Err(TraceStop::Degenerate) };
            // Does the segment leave the ball of radius d around `from`?
            let w = self.point - from;
            let b = self.dir.dot(&w);
            let c = w.norm_squared() - d * d;
            let s_node = if c >= 0.0 { 0.0 } else { -b + (b * b - c).sqrt() };
            if s_node <= s_exit {
                self.point += self.dir * s_node;
                self.entry_edge = None;
                if s_node > 0.0 {
                    self.at_corner = None;
                }
                return Ok(self.point);
            }
            // A trace that keeps crossing at zero length runs along an edge or circles a vertex.
            stalled = if s_exit == 0.0 { stalled + 1 } else { 0 };
            if stalled > MAX_STALLED {
                return Err(TraceStop::Degenerate);
            }
            let q = self.point + self.dir * s_exit;
            let (k1, k2) = ((k + 1) % 3, (k + 2) % 3);
            let lq = [l[0] + s_exit * rate[0], l[1] + s_exit * rate[1], l[2] + s_exit * rate[2]];
            let vertex_corner = if lq[k1] < VERTEX_TOLERANCE {
                Some(k2)
            } else if lq[k2] < VERTEX_TOLERANCE {
                Some(k1)
            } else {
                None
            };
            if let Some(vc) = vertex_corner {
                self.pass_vertex(tool, vc)?;
            } else {
                self.cross_edge(tool, k, q)?;
            }
        }
        Err(TraceStop::Degenerate)
    }

    /// Cross the edge of the current triangle opposite corner `k` at point `q`.
    fn cross_edge(&mut self, tool: &ToolSurface, k: usize, q: Point) -> Result<(), TraceStop> {
        let t = self.triangle;
        let n = tool.neighbour(t, k).ok_or(TraceStop::Boundary)?;
        let tri = tool.triangle(t);
        let (va, vb) = (tri[(k + 1) % 3], tri[(k + 2) % 3]);
        let pa = tool.vertices()[va as usize];
        let pb = tool.vertices()[vb as usize];
        let e = (pb - pa).normalize();
        // In-plane unit normals of the edge: out of t, and into n.
        let opp_t = tool.vertices()[tri[k] as usize];
        let out_t = {
            let w = pa - opp_t;
            (w - e * e.dot(&w)).normalize()
        };
        let ntri = tool.triangle(n);
        let kn = (0..3).find(|&i| ntri[i] != va && ntri[i] != vb).ok_or(TraceStop::Degenerate)?;
        let opp_n = tool.vertices()[ntri[kn] as usize];
        let in_n = {
            let w = opp_n - pa;
            (w - e * e.dot(&w)).normalize()
        };
        let along = self.dir.dot(&e);
        let across = self.dir.dot(&out_t).max(0.0);
        self.dir = (e * along + in_n * across).normalize();
        self.point = q;
        self.triangle = n;
        self.entry_edge = Some(kn);
        self.at_corner = None;
        Ok(())
    }

    /// Pass through corner `c` of the current triangle, leaving with half the vertex's total
    /// angle on each side.
    fn pass_vertex(&mut self, tool: &ToolSurface, c: usize) -> Result<(), TraceStop> {
        let t = self.triangle;
        let v = tool.triangle(t)[c];
        let (total, closed) = vertex_angle(tool, t, v);
        if !closed {
            return Err(TraceStop::BoundaryVertex);
        }
        let back = -self.dir;
        let (t2, d2) = turn_about_vertex(tool, t, v, &back, 0.5 * total).ok_or(TraceStop::Degenerate)?;
        self.point = tool.vertices()[v as usize];
        self.triangle = t2;
        self.dir = d2;
        self.entry_edge = None;
        self.at_corner = corner_of(tool, t2, v);
        Ok(())
    }
}
