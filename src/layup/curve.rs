//! Plane curves for cutting lines: the smooth closed curve through a loop of points
//! ([`smooth_loop`]), the outward offset of closed loops by a cutting margin ([`offset_loops`]),
//! and the crossing tests both need.
//!
//! - **Smooth curve**: cubic Hermite segments through the loop's points. The tangent at a point
//!   runs along the chord across it (from the point before to the point after, Catmull-Rom's
//!   direction) and is as long as the segment's own chord, so a long straight run beside a short
//!   step is bent only by the direction across both, not by the short step's; with turns up to
//!   [`CORNER_TURN_DEG`] both end tangents lie within that angle of the chord, which rules out
//!   loops and cusps. Where the loop turns by more, the point stays a corner and both edges at it
//!   stay straight (the fabric's rows end there). Each segment is sampled by halving its
//!   parameter interval until the curve lies within [`SMOOTH_CHORD_TOL`] of the polyline.
//! - **Offset**: each loop moved to the right of its direction of travel (outward for the
//!   counter-clockwise outer loops, into the holes for the clockwise holes) by the margin: edges
//!   moved along their normals, round arcs at the convex turns (sampled within
//!   [`OFFSET_ARC_TOL`] of the circle), the offset lines' intersection at the concave ones. A
//!   concavity tighter than the margin makes the raw curve cross itself; it is split at its
//!   crossings and the pieces that run the wrong way round or come closer to the cut than the
//!   margin (less [`OFFSET_KEEP_TOL`]) are dropped; an outer loop keeps its largest piece, a hole
//!   its pieces of at least [`OFFSET_MIN_AREA`]. A result whose loops still cross is refused (`None`).
/// A loop turning by more than this (degrees) at a point keeps that point as a corner. The
/// boundary through a net's nodes turns by 45 degrees where it follows a curve (a fibre to a
/// diagonal) and by 90 or more where the fabric's rows end at a corner.
pub const CORNER_TURN_DEG: f64 = 60.0;

/// Largest distance (m) between the smooth curve and the polyline written for it: 0.05 mm, below
/// a cutter's resolution.
pub const SMOOTH_CHORD_TOL: f64 = 5e-5;

/// Largest distance (m) between an offset's round arc and its sampled chords.
pub const OFFSET_ARC_TOL: f64 = 5e-5;

/// Pieces of an offset with a point closer to the cut than the margin less this (m) are
/// dropped: twice [`OFFSET_ARC_TOL`], as a crossing on a round join's chord lies up to that
/// inside the arc, and the tails cut off at concavities come closer by far more.
const OFFSET_KEEP_TOL: f64 = 2.0 * OFFSET_ARC_TOL;

/// Pieces of a hole's offset smaller than this (m^2, 1 mm^2) are dropped: no cutter cuts them,
/// and the slivers a split leaves at tight concavities are far smaller.
const OFFSET_MIN_AREA: f64 = 1e-6;

/// Deepest halving of a segment's parameter interval (2^12 pieces at most).
const MAX_DEPTH: u32 = 12;

/// Most splits of one raw offset loop at its crossings.
const MAX_SPLITS: usize = 10_000;

type P = [f64; 2];

fn sub(a: P, b: P) -> P {
    [a[0] - b[0], a[1] - b[1]]
}
fn cross(a: P, b: P) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}
fn dot(a: P, b: P) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}
fn norm(a: P) -> f64 {
    a[0].hypot(a[1])
}

/// Turn (radians, positive to the left) of the path a -> b -> c at b.
pub fn turn(a: P, b: P, c: P) -> f64 {
    let (u, w) = (sub(b, a), sub(c, b));
    cross(u, w).atan2(dot(u, w))
}

/// The smooth closed curve through the points of a closed loop (last point joins the first, not
/// repeated), as a polyline starting at `points[0]`, every given point kept (see the module
/// comment). Loops of fewer than three points come back as they are.
pub fn smooth_loop(points: &[P]) -> Vec<P> {
    let n = points.len();
    if n < 3 {
        return points.to_vec();
    }
    let corner_turn = CORNER_TURN_DEG.to_radians();
    let corner: Vec<bool> =
        (0..n).map(|k| turn(points[(k + n - 1) % n], points[k], points[(k + 1) % n]).abs() > corner_turn).collect();
    // Unit tangent at each point: along the chord across it (Catmull-Rom's direction).
    let tangent: Vec<Option<P>> = (0..n)
        .map(|k| {
            let c = sub(points[(k + 1) % n], points[(k + n - 1) % n]);
            let len = norm(c);
            (len > 0.0).then(|| [c[0] / len, c[1] / len])
        })
        .collect();
    let mut out = Vec::with_capacity(4 * n);
    for k in 0..n {
        let k2 = (k + 1) % n;
        let (p1, p2) = (points[k], points[k2]);
        out.push(p1);
        // An edge that ends at a corner stays straight: the fabric's rows end there.
        if corner[k] || corner[k2] {
            continue;
        }
        let (Some(u1), Some(u2)) = (tangent[k], tangent[k2]) else { continue };
        let len = norm(sub(p2, p1));
        if !(len > 0.0) {
            continue;
        }
        let seg = Hermite { p1, p2, t1: [len * u1[0], len * u1[1]], t2: [len * u2[0], len * u2[1]] };
        seg.sample(0.0, 1.0, p1, p2, 0, &mut out);
    }
    out
}

/// One cubic Hermite segment from p1 (tangent t1) to p2 (tangent t2), parameter 0 to 1.
struct Hermite {
    p1: P,
    p2: P,
    t1: P,
    t2: P,
}

impl Hermite {
    fn at(&self, u: f64) -> P {
        let (u2, u3) = (u * u, u * u * u);
        let (h00, h10, h01, h11) = (2.0 * u3 - 3.0 * u2 + 1.0, u3 - 2.0 * u2 + u, -2.0 * u3 + 3.0 * u2, u3 - u2);
        [0, 1].map(|c| h00 * self.p1[c] + h10 * self.t1[c] + h01 * self.p2[c] + h11 * self.t2[c])
    }

    /// Push the points strictly between `ua` and `ub` (whose points are `a` and `b`), halving
    /// the interval until the curve's midpoint is within [`SMOOTH_CHORD_TOL`] of the chord. The
    /// first halving is always made: a segment may bulge symmetrically about its chord ends.
    fn sample(&self, ua: f64, ub: f64, a: P, b: P, depth: u32, out: &mut Vec<P>) {
        let um = 0.5 * (ua + ub);
        let m = self.at(um);
        let flat = distance_to_segment(m, a, b) <= SMOOTH_CHORD_TOL;
        if depth >= MAX_DEPTH || (depth > 0 && flat) {
            return;
        }
        self.sample(ua, um, a, m, depth + 1, out);
        out.push(m);
        self.sample(um, ub, m, b, depth + 1, out);
    }
}

/// Distance from `p` to the segment a-b.
pub fn distance_to_segment(p: P, a: P, b: P) -> f64 {
    let ab = sub(b, a);
    let l2 = dot(ab, ab);
    let s = if l2 > 0.0 { (dot(sub(p, a), ab) / l2).clamp(0.0, 1.0) } else { 0.0 };
    norm(sub(p, [a[0] + s * ab[0], a[1] + s * ab[1]]))
}

/// Distance from `p` to the nearest edge of the closed loops.
pub fn distance_to_loops(p: P, loops: &[Vec<P>]) -> f64 {
    loops
        .iter()
        .flat_map(|l| (0..l.len()).map(move |k| distance_to_segment(p, l[k], l[(k + 1) % l.len()])))
        .fold(f64::INFINITY, f64::min)
}

/// Signed shoelace area of a closed loop (positive counter-clockwise).
fn signed_area(l: &[P]) -> f64 {
    let n = l.len();
    0.5 * (0..n).map(|k| cross(l[k], l[(k + 1) % n])).sum::<f64>()
}

/// A crossing of two edges: (loop, edge) of each and the point where they meet.
#[derive(Debug, Clone, Copy)]
pub struct Crossing {
    /// Loop and edge (edge k runs from vertex k to vertex k + 1) of the first edge.
    pub a: (usize, usize),
    /// Loop and edge of the second edge (after the first in loop and edge order).
    pub b: (usize, usize),
    /// A point both edges share.
    pub at: P,
}

/// The first (in loop and edge order of the first edge, then of the second) pair of edges of
/// the closed loops that share a point, apart from an edge and its neighbours in the same loop.
pub fn first_crossing(loops: &[Vec<P>]) -> Option<Crossing> {
    // Edges sorted by their lowest x: only edges whose x ranges overlap are compared.
    let mut edges: Vec<(f64, f64, usize, usize)> = Vec::new();
    for (li, l) in loops.iter().enumerate() {
        let n = l.len();
        for k in 0..n {
            let (a, b) = (l[k], l[(k + 1) % n]);
            edges.push((a[0].min(b[0]), a[0].max(b[0]), li, k));
        }
    }
    edges.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.2.cmp(&b.2)).then(a.3.cmp(&b.3)));
    let mut best: Option<Crossing> = None;
    for (x, &(_, hi, la, ea)) in edges.iter().enumerate() {
        for &(lo, _, lb, eb) in &edges[x + 1..] {
            if lo > hi {
                break;
            }
            let (first, second) = if (la, ea) < (lb, eb) { ((la, ea), (lb, eb)) } else { ((lb, eb), (la, ea)) };
            if first.0 == second.0 {
                let n = loops[first.0].len();
                let (i, j) = (first.1, second.1);
                if j == i + 1 || (i == 0 && j == n - 1) || n < 4 {
                    continue;
                }
            }
            let edge = |(l, k): (usize, usize)| {
                let lp = &loops[l];
                (lp[k], lp[(k + 1) % lp.len()])
            };
            let (p, q) = edge(first);
            let (r, s) = edge(second);
            if let Some(at) = segments_meet(p, q, r, s) {
                let c = Crossing { a: first, b: second, at };
                if best.is_none_or(|b| (c.a, c.b) < (b.a, b.b)) {
                    best = Some(c);
                }
            }
        }
    }
    best
}

/// A point the closed segments p-q and r-s share, if any.
fn segments_meet(p: P, q: P, r: P, s: P) -> Option<P> {
    let orient = |a: P, b: P, c: P| {
        let v = cross(sub(b, a), sub(c, a));
        (v > 0.0) as i8 - (v < 0.0) as i8
    };
    let on = |a: P, b: P, c: P| {
        a[0].min(b[0]) <= c[0] && c[0] <= a[0].max(b[0]) && a[1].min(b[1]) <= c[1] && c[1] <= a[1].max(b[1])
    };
    let (o1, o2, o3, o4) = (orient(p, q, r), orient(p, q, s), orient(r, s, p), orient(r, s, q));
    if o1 != o2 && o3 != o4 {
        let (d1, d2) = (sub(q, p), sub(s, r));
        let den = cross(d1, d2);
        if den != 0.0 {
            let t = (cross(sub(r, p), d2) / den).clamp(0.0, 1.0);
            return Some([p[0] + t * d1[0], p[1] + t * d1[1]]);
        }
    }
    for (cond, pt) in [(o1 == 0 && on(p, q, r), r), (o2 == 0 && on(p, q, s), s), (o3 == 0 && on(r, s, p), p)] {
        if cond {
            return Some(pt);
        }
    }
    (o4 == 0 && on(r, s, q)).then_some(q)
}

/// The raw offset of one closed loop to the right of its direction of travel by `m` (see the
/// module comment), before its crossings are removed.
fn raw_offset(l: &[P], m: f64) -> Vec<P> {
    let n = l.len();
    // Largest angle step of a round join whose chords stay within OFFSET_ARC_TOL of the arc.
    let step = 2.0 * (1.0 - (OFFSET_ARC_TOL / m).min(1.0)).acos();
    let unit = |v: P| {
        let len = norm(v);
        [v[0] / len, v[1] / len]
    };
    let mut out = Vec::with_capacity(2 * n);
    for k in 0..n {
        let (a, b, c) = (l[(k + n - 1) % n], l[k], l[(k + 1) % n]);
        let (u, w) = (unit(sub(b, a)), unit(sub(c, b)));
        let (ni, no) = ([u[1], -u[0]], [w[1], -w[0]]);
        let th = cross(u, w).atan2(dot(u, w));
        let at = |nv: P| [b[0] + m * nv[0], b[1] + m * nv[1]];
        if th > 0.0 {
            // Convex for the offset: a round join through the turn.
            let (phi0, steps) = (ni[1].atan2(ni[0]), (th / step).ceil().max(1.0) as usize);
            for s in 0..=steps {
                let phi = phi0 + th * s as f64 / steps as f64;
                out.push(at([phi.cos(), phi.sin()]));
            }
        } else if th == 0.0 {
            out.push(at(ni));
        } else {
            // Concave: where the two offset lines meet, unless they are nearly parallel (a
            // turn back), where both ends are kept and the crossing they make is removed after.
            let den = 1.0 + dot(ni, no);
            if den > 0.05 {
                out.push([b[0] + m * (ni[0] + no[0]) / den, b[1] + m * (ni[1] + no[1]) / den]);
            } else {
                out.push(at(ni));
                out.push(at(no));
            }
        }
    }
    out
}

/// The closed loops `loops` (outer loops counter-clockwise, holes clockwise; no loop crossing
/// itself or another) offset outward by `margin` > 0 (see the module comment): one list of loops
/// per given loop (empty when a hole closes). `None` when the result's loops cross (pieces or a
/// hole and its outer loop closer than twice the margin) or a loop is degenerate.
pub fn offset_loops(loops: &[Vec<P>], margin: f64) -> Option<Vec<Vec<Vec<P>>>> {
    if !(margin > 0.0 && margin.is_finite()) {
        return None;
    }
    let mut out = Vec::with_capacity(loops.len());
    for l in loops {
        // Repeated consecutive points have no direction: drop them.
        let mut l: Vec<P> = l.clone();
        l.dedup();
        while l.len() > 1 && l.first() == l.last() {
            l.pop();
        }
        if l.len() < 3 {
            return None;
        }
        let sign = signed_area(&l).signum();
        let raw = raw_offset(&l, margin);
        let mut todo = vec![raw];
        let mut pieces = Vec::new();
        let mut splits = 0;
        while let Some(r) = todo.pop() {
            match first_crossing(std::slice::from_ref(&r)) {
                Some(c) => {
                    splits += 1;
                    if splits > MAX_SPLITS {
                        return None;
                    }
                    let (i, j) = (c.a.1, c.b.1);
                    let mut one = vec![c.at];
                    one.extend_from_slice(&r[i + 1..=j]);
                    let mut two = vec![c.at];
                    two.extend_from_slice(&r[j + 1..]);
                    two.extend_from_slice(&r[..=i]);
                    for mut piece in [one, two] {
                        piece.dedup();
                        while piece.len() > 1 && piece.first() == piece.last() {
                            piece.pop();
                        }
                        if piece.len() >= 3 {
                            todo.push(piece);
                        }
                    }
                }
                None => pieces.push(r),
            }
        }
        // Crossings on a round join's chords lie up to OFFSET_ARC_TOL inside its arc.
        let keep_at = margin - OFFSET_KEEP_TOL;
        let mut kept: Vec<Vec<P>> = pieces
            .into_iter()
            .filter(|r| signed_area(r).signum() == sign)
            // Also without a crossing: a hole offset past half its width turns inside out.
            .filter(|r| r.iter().all(|&p| distance_to_loops(p, loops) >= keep_at))
            .collect();
        if sign > 0.0 {
            // An outer loop grown outward is one loop: the rest are slivers of its tails.
            let Some(big) = kept.iter().max_by(|a, b| signed_area(a).total_cmp(&signed_area(b))).cloned() else {
                return None; // an outer loop must stay
            };
            kept = vec![big];
        } else {
            kept.retain(|r| signed_area(r).abs() >= OFFSET_MIN_AREA);
        }
        out.push(kept);
    }
    let all: Vec<Vec<P>> = out.iter().flatten().cloned().collect();
    if first_crossing(&all).is_some() {
        return None;
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square(a: f64) -> Vec<P> {
        vec![[0.0, 0.0], [a, 0.0], [a, a], [0.0, a]]
    }

    #[test]
    fn square_offset_is_the_rounded_square() {
        let (a, m) = (0.2, 0.01);
        let o = offset_loops(&[square(a)], m).unwrap();
        assert_eq!((o.len(), o[0].len()), (1, 1));
        let want = a * a + 4.0 * a * m + std::f64::consts::PI * m * m;
        let area = signed_area(&o[0][0]);
        // The arcs' chords lie inside the circle by at most OFFSET_ARC_TOL.
        assert!(area <= want && want - area < 2.0 * std::f64::consts::PI * m * OFFSET_ARC_TOL, "{area} vs {want}");
        for &p in &o[0][0] {
            assert!((distance_to_loops(p, &[square(a)]) - m).abs() < 1e-12);
        }
    }

    #[test]
    fn a_hole_closes_and_a_notch_fills() {
        // A clockwise hole 0.02 wide closes under a margin of 0.011.
        let hole: Vec<P> = square(0.02).into_iter().rev().collect();
        let o = offset_loops(&[square(1.0), hole.clone()], 0.011).unwrap();
        assert!(o[1].is_empty());
        // A 0.1 deep notch 0.01 wide: the margin 0.02 bridges it, no crossing remains.
        let notch = vec![
            [0.0, 0.0],
            [0.5, 0.0],
            [0.5, 0.3],
            [0.255, 0.3],
            [0.255, 0.2],
            [0.245, 0.2],
            [0.245, 0.3],
            [0.0, 0.3],
        ];
        let o = offset_loops(std::slice::from_ref(&notch), 0.02).unwrap();
        assert_eq!(o[0].len(), 1);
        let area = signed_area(&o[0][0]);
        let want = 0.5 * 0.3 + 2.0 * 0.8 * 0.02 + std::f64::consts::PI * 0.02 * 0.02;
        assert!((area - want).abs() < 1e-3 * want, "{area} vs {want}");
        for &p in &o[0][0] {
            assert!(distance_to_loops(p, std::slice::from_ref(&notch)) > 0.02 - OFFSET_KEEP_TOL);
        }
    }

    #[test]
    fn smooth_keeps_corners_and_points() {
        let s = smooth_loop(&square(1.0));
        assert_eq!(s, square(1.0), "corners only: the square itself");
        // An octagon (45 degree turns) becomes a smooth curve through its points.
        let oct: Vec<P> = (0..8)
            .map(|k| {
                let t = k as f64 * std::f64::consts::FRAC_PI_4;
                [t.cos(), t.sin()]
            })
            .collect();
        let s = smooth_loop(&oct);
        assert!(s.len() > 8 * 8);
        assert!(oct.iter().all(|p| s.contains(p)));
        let worst = s.iter().map(|p| (norm(*p) - 1.0).abs()).fold(0.0, f64::max);
        assert!(worst < 0.02, "{worst}");
        assert!(first_crossing(&[s]).is_none());
    }
}
