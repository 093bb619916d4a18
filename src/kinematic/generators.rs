//! Generators: the two fibre paths through the origin node that seed the fishnet. Geodesic
//! (straightest geodesics), steered (a user curve for the warp), or minimum-shear (each generator
//! segment turned to minimise the shear of the two cells beside it).
use super::fishnet::{cell_shear_of, circle_root, place_node, DrapeError, Placed};
use super::net::NodeStatus;
use super::surface::DrapeSurface;
use super::{GeneratorKind, KinematicSettings};
use crate::geometry::surface::Circle;
use crate::geometry::{Point, SurfacePoint, Vector};
use crate::numeric::golden_section_min;
use std::f64::consts::{FRAC_PI_2, PI};

/// Largest turn of one minimum-shear generator segment away from the geodesic (radians).
pub const MAX_STEER_TURN: f64 = 0.5;
/// Golden-section iterations of the minimum-shear search (interval shrinks by 0.618 each).
const GOLDEN_ITERATIONS: usize = 60;
/// The steering curve is refined to pieces of at most this fraction of the spacing.
const STEER_REFINE: f64 = 0.125;

/// The origin node and the four half-generators (nodes 1, 2, ... away from the origin).
#[derive(Debug, Clone)]
pub struct Generators {
    /// The seed on the tool.
    pub origin: Placed,
    /// Unit warp direction at the origin, in the tool's tangent plane.
    pub warp_dir: Vector,
    /// How they were laid: `geodesic`, `min-shear` or `steer`.
    pub kind: String,
    /// Nodes along +warp from the seed (or why the generator stopped there).
    pub warp_pos: Vec<Result<Placed, NodeStatus>>,
    /// Nodes along -warp.
    pub warp_neg: Vec<Result<Placed, NodeStatus>>,
    /// Nodes along +weft.
    pub weft_pos: Vec<Result<Placed, NodeStatus>>,
    /// Nodes along -weft.
    pub weft_neg: Vec<Result<Placed, NodeStatus>>,
}

/// Lay the generators for a grid of `grid` nodes with the origin at `origin_node`.
pub fn lay_generators<S: DrapeSurface>(
    surface: &S,
    settings: &KinematicSettings,
    seed: &SurfacePoint,
    grid: (usize, usize),
    origin_node: (usize, usize),
) -> Result<Generators, DrapeError> {
    let (nu, nv) = grid;
    let (i0, j0) = origin_node;
    let counts = [nu - 1 - i0, i0, nv - 1 - j0, j0]; // warp+, warp-, weft+, weft-
    let d = settings.spacing;
    let omega = FRAC_PI_2 - settings.pre_shear;
    let warp_err = || DrapeError::WarpNormal([settings.warp.x, settings.warp.y, settings.warp.z]);
    if !settings.warp.iter().all(|c| c.is_finite()) {
        return Err(warp_err());
    }

    match &settings.generators {
        GeneratorKind::Geodesic | GeneratorKind::MinShear => {
            let origin = Placed { point: seed.point, triangle: seed.triangle };
            let start = surface.start_trace(&origin, &settings.warp).ok_or_else(warp_err)?;
            let states = [
                Some(start),
                surface.turned(&start, PI),
                surface.turned(&start, omega),
                surface.turned(&start, PI + omega),
            ];
            let min_shear = settings.generators == GeneratorKind::MinShear;
            let mut halves: Vec<Vec<Result<Placed, NodeStatus>>> = Vec::with_capacity(4);
            if !min_shear {
                for (state, n) in states.iter().zip(counts) {
                    halves.push(match state {
                        Some(s) => trace_half(surface, *s, origin.point, n, d),
                        None => vec![Err(NodeStatus::OffTool); n],
                    });
                }
            } else {
                // First nodes of every half along the initial directions; they border the cells
                // that steer the following segments.
                let first: Vec<Option<Placed>> = states
                    .iter()
                    .map(|s| s.and_then(|s| trace_half(surface, s, origin.point, 1, d).pop()?.ok()))
                    .collect();
                // (is_warp, sign, the two neighbouring halves' first nodes with their side signs)
                let specs = [
                    (true, 1.0, [(first[2], 1.0), (first[3], -1.0)]),
                    (true, -1.0, [(first[2], 1.0), (first[3], -1.0)]),
                    (false, 1.0, [(first[0], 1.0), (first[1], -1.0)]),
                    (false, -1.0, [(first[0], 1.0), (first[1], -1.0)]),
                ];
                for ((state, n), (is_warp, sign, sides)) in states.iter().zip(counts).zip(specs) {
                    halves.push(match state {
                        Some(s) => min_shear_half(surface, settings, *s, origin, n, is_warp, sign, sides),
                        None => vec![Err(NodeStatus::OffTool); n],
                    });
                }
            }
            let mut it = halves.into_iter();
            Ok(Generators {
                origin,
                warp_dir: surface.trace_dir(&start),
                kind: if min_shear { "min-shear".into() } else { "geodesic".into() },
                warp_pos: it.next().unwrap_or_default(),
                warp_neg: it.next().unwrap_or_default(),
                weft_pos: it.next().unwrap_or_default(),
                weft_neg: it.next().unwrap_or_default(),
            })
        }
        GeneratorKind::Steer(curve) => steered(surface, settings, seed, curve, counts, omega),
    }
}

/// Follow a geodesic from `from`, placing `n` nodes at straight-line distance d from each other.
fn trace_half<S: DrapeSurface>(
    surface: &S,
    mut state: S::Trace,
    from: Point,
    n: usize,
    d: f64,
) -> Vec<Result<Placed, NodeStatus>> {
    let mut out = Vec::with_capacity(n);
    let mut prev = from;
    while out.len() < n {
        match surface.advance_chord(&mut state, &prev, d) {
            Some(p) => {
                out.push(Ok(p));
                prev = p.point;
            }
            None => break,
        }
    }
    out.resize(n, Err(NodeStatus::OffTool));
    out
}

/// A minimum-shear half-generator: each segment after the first leaves the previous node along
/// the geodesic continuation turned by the angle (within +-MAX_STEER_TURN) that minimises the
/// summed squared shear of the two cells beside it.
#[allow(clippy::too_many_arguments)]
fn min_shear_half<S: DrapeSurface>(
    surface: &S,
    settings: &KinematicSettings,
    start: S::Trace,
    origin: Placed,
    n: usize,
    is_warp: bool,
    sign: f64,
    sides: [(Option<Placed>, f64); 2],
) -> Vec<Result<Placed, NodeStatus>> {
    let d = settings.spacing;
    let mut out = Vec::with_capacity(n);
    let mut strip: [Option<Placed>; 2] = [sides[0].0, sides[1].0];
    let mut prev = origin;
    let mut state = start;
    // Shear of the cells beside a candidate node x, and the strip nodes they create.
    let evaluate = |prev: &Placed, x: &Placed, strip: &[Option<Placed>; 2]| -> (f64, [Option<Placed>; 2]) {
        let mut cost = 0.0;
        let mut used = 0;
        let mut next = [None, None];
        for (k, (_, side)) in sides.iter().enumerate() {
            let Some(s) = strip[k] else { continue };
            // Roles: the warp parent differs from the new strip node in i, the weft parent in j.
            let (a, b, si, sj) = if is_warp { (s, *x, sign, *side) } else { (*x, s, *side, sign) };
            if let Ok(p) = place_node(surface, d, settings.max_shear, &a, &b, &prev.point, si, sj) {
                let g = cell_shear_of(&a.point, &b.point, &prev.point, &p.point, si, sj);
                cost += g * g;
                used += 1;
                next[k] = Some(p);
            }
        }
        (if used == 0 { f64::NAN } else { cost }, next)
    };
    while out.len() < n {
        let shoot = |turn: f64| -> Option<(S::Trace, Placed)> {
            let mut s = if turn == 0.0 { state } else { surface.turned(&state, turn)? };
            let p = surface.advance_chord(&mut s, &prev.point, d)?;
            Some((s, p))
        };
        let cost = |turn: f64| -> f64 {
            match shoot(turn) {
                Some((_, x)) => {
                    let (c, _) = evaluate(&prev, &x, &strip);
                    if c.is_nan() {
                        turn * turn
                    } else {
                        c
                    }
                }
                None => f64::INFINITY,
            }
        };
        let turn = if out.is_empty() {
            0.0
        } else {
            golden_section_min(cost, -MAX_STEER_TURN, MAX_STEER_TURN, GOLDEN_ITERATIONS, 0.0).0
        };
        let turn = if cost(turn) <= cost(0.0) { turn } else { 0.0 };
        let Some((s, x)) = shoot(turn) else { break };
        let (_, next) = evaluate(&prev, &x, &strip);
        strip = next;
        out.push(Ok(x));
        prev = x;
        state = s;
    }
    out.resize(n, Err(NodeStatus::OffTool));
    out
}

/// Warp generator along a user curve; weft generator geodesic.
fn steered<S: DrapeSurface>(
    surface: &S,
    settings: &KinematicSettings,
    seed: &SurfacePoint,
    curve: &[Point],
    counts: [usize; 4],
    omega: f64,
) -> Result<Generators, DrapeError> {
    let d = settings.spacing;
    if curve.len() < 2 {
        return Err(DrapeError::Steering(format!(
            "the steering curve has {} point(s); give at least two points (x,y,z per line)",
            curve.len()
        )));
    }
    // Project the curve's points and refine it so each piece hugs the tool.
    let mut refined: Vec<Point> = Vec::new();
    for (k, w) in curve.windows(2).enumerate() {
        let pieces = (((w[1] - w[0]).norm() / (STEER_REFINE * d)).ceil() as usize).max(1);
        for m in 0..pieces + usize::from(k + 2 == curve.len()) {
            let q = w[0] + (w[1] - w[0]) * (m as f64 / pieces as f64);
            let sp = surface.seed(&q);
            if sp.distance > d {
                return Err(DrapeError::Steering(format!(
                    "steering curve point near ({:.6}, {:.6}, {:.6}) (segment {}) is {:.4} from the tool, more than one spacing: give a curve that lies on the tool",
                    q.x, q.y, q.z, k + 1, sp.distance
                )));
            }
            refined.push(sp.point);
        }
    }
    refined.dedup_by(|a, b| (*a - *b).norm() <= 1e-12 * d);
    if refined.len() < 2 {
        return Err(DrapeError::Steering("the steering curve has no length on the tool".into()));
    }
    // Where the curve passes the seed: the origin node.
    let (seg, t, dist) = closest_on_polyline(&refined, &seed.point);
    if dist > d {
        return Err(DrapeError::Steering(format!(
            "the steering curve passes {dist:.4} from the origin, more than one spacing ({d}): make the curve pass through the seed point"
        )));
    }
    let on_curve = refined[seg] + (refined[seg + 1] - refined[seg]) * t;
    let origin_sp = surface.seed(&on_curve);
    let origin = Placed { point: origin_sp.point, triangle: origin_sp.triangle };
    let tangent = refined[seg + 1] - refined[seg];
    let forward = tangent.dot(&settings.warp) >= 0.0;
    let warp_dir = if forward { tangent } else { -tangent };
    let start =
        surface.start_trace(&origin, &warp_dir).ok_or(DrapeError::WarpNormal([warp_dir.x, warp_dir.y, warp_dir.z]))?;
    // Walk the refined curve both ways from the origin.
    let ahead: Vec<Point> = std::iter::once(on_curve).chain(refined[seg + 1..].iter().copied()).collect();
    let behind: Vec<Point> = std::iter::once(on_curve).chain(refined[..=seg].iter().rev().copied()).collect();
    let (pos_path, neg_path) = if forward { (ahead, behind) } else { (behind, ahead) };
    let warp_pos = follow_curve(surface, &pos_path, origin, counts[0], d);
    let warp_neg = follow_curve(surface, &neg_path, origin, counts[1], d);
    let weft_pos = match surface.turned(&start, omega) {
        Some(s) => trace_half(surface, s, origin.point, counts[2], d),
        None => vec![Err(NodeStatus::OffTool); counts[2]],
    };
    let weft_neg = match surface.turned(&start, PI + omega) {
        Some(s) => trace_half(surface, s, origin.point, counts[3], d),
        None => vec![Err(NodeStatus::OffTool); counts[3]],
    };
    let warp_dir = surface.trace_dir(&start);
    Ok(Generators { origin, warp_dir, kind: "steer".into(), warp_pos, warp_neg, weft_pos, weft_neg })
}

/// Closest point of a polyline to `p`: (segment, parameter in [0, 1], distance).
fn closest_on_polyline(line: &[Point], p: &Point) -> (usize, f64, f64) {
    let mut best = (0, 0.0, f64::INFINITY);
    for k in 0..line.len() - 1 {
        let (a, b) = (line[k], line[k + 1]);
        let ab = b - a;
        let t = ((p - a).dot(&ab) / ab.norm_squared()).clamp(0.0, 1.0);
        let dist = (a + ab * t - p).norm();
        if dist < best.2 {
            best = (k, t, dist);
        }
    }
    best
}

/// Nodes at straight-line distance d along a path on the tool, each the point of the tool at
/// distance d from the previous node nearest to where the path crosses that distance.
fn follow_curve<S: DrapeSurface>(
    surface: &S,
    path: &[Point],
    origin: Placed,
    n: usize,
    d: f64,
) -> Vec<Result<Placed, NodeStatus>> {
    let mut out = Vec::with_capacity(n);
    let mut prev = origin;
    let mut seg = 0usize;
    'nodes: while out.len() < n {
        // First crossing of the sphere (prev, d) along the path, from segment `seg` on.
        while seg + 1 < path.len() {
            let (a, b) = (path[seg], path[seg + 1]);
            let ab = b - a;
            let len = ab.norm();
            if len == 0.0 {
                seg += 1;
                continue;
            }
            let dir = ab / len;
            let w = a - prev.point;
            let (bq, c) = (dir.dot(&w), w.norm_squared() - d * d);
            let disc = bq * bq - c;
            if disc >= 0.0 {
                let s = -bq + disc.sqrt();
                if s >= 0.0 && s <= len {
                    let target = a + dir * s;
                    match node_towards(surface, &prev, &target, d) {
                        Some(p) => {
                            out.push(Ok(p));
                            prev = p;
                            continue 'nodes;
                        }
                        None => break 'nodes,
                    }
                }
            }
            seg += 1;
        }
        break;
    }
    out.resize(n, Err(NodeStatus::OffTool));
    out
}

/// The point of the tool at distance d from `from` closest to `target`: the tool crossed by the
/// circle of radius d about `from` in the plane of `target - from` and the tool normal.
fn node_towards<S: DrapeSurface>(surface: &S, from: &Placed, target: &Point, d: f64) -> Option<Placed> {
    let n = surface.normal(from);
    let e1 = (target - from.point).try_normalize(1e-14 * d)?;
    let e2 = (n - e1 * e1.dot(&n)).try_normalize(1e-12)?;
    let circle = Circle { center: from.point, e1, e2, radius: d };
    let near = surface.tool().closest_point(target);
    circle_root(surface, &circle, d, [from.triangle, near.triangle])
        .ok()
        .map(|r| Placed { point: r.point, triangle: r.triangle })
}
