//! [`TriangleBvh`]: the bounding-volume hierarchy of a tool's triangles, built in parallel, and
//! the three queries [`super::ToolSurface`] asks of it (closest triangle, first ray hit,
//! triangles whose box meets a box).
//!
//! The answers do not depend on the shape of the tree, so neither on the thread count nor on
//! how the tree is built: the closest triangle is the one of smallest squared distance (as the
//! caller computes it) and, among equal distances, of lowest index; the ray hit is the smallest
//! distance over all triangles; the box query's triangles come sorted by index. Pruning keeps
//! a slack far above rounding, so a box is only skipped when none of its triangles can tie.
//!
//! The tree: triangles ordered by recursive median splits of their centroids (rounded to `f32`
//! after the lowest centroid is taken off) along the longest axis (ties by index), the two
//! halves of each split ordered in parallel; node `k` covers a range of that order, its
//! children are nodes `2k + 1` and `2k + 2` (the two halves), a range of at most [`LEAF`]
//! triangles is a leaf, and the boxes are computed a depth at a time from the leaves up.
use super::{Point, Vector};

/// Most triangles in a leaf.
const LEAF: usize = 4;
/// Ranges at least this long are split in parallel.
const PARALLEL: usize = 1 << 12;
/// Deeper than any tree this builds (2^64 triangles): the traversal stacks' size.
const STACK: usize = 64;

/// An axis-aligned box.
#[derive(Debug, Clone, Copy)]
struct Box3 {
    min: [f64; 3],
    max: [f64; 3],
}

impl Box3 {
    const EMPTY: Box3 = Box3 { min: [f64::INFINITY; 3], max: [f64::NEG_INFINITY; 3] };

    fn of(points: &[Point]) -> Box3 {
        let mut b = Box3::EMPTY;
        for p in points {
            for a in 0..3 {
                b.min[a] = b.min[a].min(p[a]);
                b.max[a] = b.max[a].max(p[a]);
            }
        }
        b
    }

    fn union(&self, o: &Box3) -> Box3 {
        Box3 {
            min: std::array::from_fn(|a| self.min[a].min(o.min[a])),
            max: std::array::from_fn(|a| self.max[a].max(o.max[a])),
        }
    }

    /// Whether the boxes meet (touching counts).
    fn meets(&self, o: &Box3) -> bool {
        (0..3).all(|a| self.min[a] <= o.max[a] && o.min[a] <= self.max[a])
    }

    /// Squared distance from `p` to the box (0 inside).
    fn distance2(&self, p: &Point) -> f64 {
        (0..3)
            .map(|a| {
                let d = (self.min[a] - p[a]).max(p[a] - self.max[a]).max(0.0);
                d * d
            })
            .sum()
    }

    /// Distance along the ray to where it enters the box grown by `slack` on every side, if it
    /// meets it within `max`.
    fn ray_entry(&self, origin: &Point, dir: &Vector, slack: f64, max: f64) -> Option<f64> {
        let (mut t0, mut t1) = (0.0f64, max);
        for a in 0..3 {
            let (lo, hi) = (self.min[a] - slack, self.max[a] + slack);
            if dir[a] == 0.0 {
                if origin[a] < lo || origin[a] > hi {
                    return None;
                }
                continue;
            }
            let inv = 1.0 / dir[a];
            let (mut ta, mut tb) = ((lo - origin[a]) * inv, (hi - origin[a]) * inv);
            if ta > tb {
                std::mem::swap(&mut ta, &mut tb);
            }
            t0 = t0.max(ta);
            t1 = t1.min(tb);
            if !(t0 <= t1) {
                return None;
            }
        }
        Some(t0)
    }
}

/// A node: the box of its triangles and their range in [`TriangleBvh::order`]; `used` is false
/// for the slots of the heap layout below a leaf.
#[derive(Debug, Clone, Copy)]
struct Node {
    bounds: Box3,
    lo: u32,
    hi: u32,
}

/// The boxes of a tool's triangles ([`TriangleBvh::boxes`]).
pub(crate) struct TriangleBoxes(Vec<Box3>);

/// The hierarchy (see the module documentation).
#[derive(Debug, Clone)]
pub(crate) struct TriangleBvh {
    nodes: Vec<Node>,
    order: Vec<u32>,
    boxes: Vec<Box3>,
    /// Pruning slack, far above rounding: 1e-9 of the boxes' diagonal.
    slack: f64,
}

impl TriangleBvh {
    /// The hierarchy of `triangles` (corner indices into `vertices`, all valid).
    pub(crate) fn new(vertices: &[Point], triangles: &[[u32; 3]]) -> TriangleBvh {
        TriangleBvh::from_boxes(TriangleBvh::boxes(vertices, triangles))
    }

    /// The boxes of `triangles`, for [`TriangleBvh::from_boxes`]: all that the hierarchy needs of
    /// the triangles (so it is the same for triangles turned over).
    pub(crate) fn boxes(vertices: &[Point], triangles: &[[u32; 3]]) -> TriangleBoxes {
        use rayon::prelude::*;
        TriangleBoxes(
            triangles.par_iter().with_min_len(PARALLEL).map(|t| Box3::of(&t.map(|i| vertices[i as usize]))).collect(),
        )
    }

    /// The hierarchy of the triangles of `boxes`.
    pub(crate) fn from_boxes(boxes: TriangleBoxes) -> TriangleBvh {
        use rayon::prelude::*;
        let TriangleBoxes(boxes) = boxes;
        // Each triangle's centroid beside its index, so that the splits compare and move them
        // without looking anything up elsewhere in memory: as the bits of an `f32` of the
        // centroid less the lowest centroid (not negative, so the bits are in the same order as
        // the numbers), which halves what the splits move and makes their comparisons integer
        // ones. Rounding makes a few ties more, broken by index like the others; the answers do
        // not depend on the tree.
        let centroid = |b: &Box3| -> [f64; 3] { std::array::from_fn(|a| 0.5 * (b.min[a] + b.max[a])) };
        let lowest = boxes
            .par_iter()
            .with_min_len(PARALLEL)
            .map(centroid)
            .reduce(|| [f64::INFINITY; 3], |p, q| std::array::from_fn(|a| p[a].min(q[a])));
        let mut centroids: Vec<([u32; 3], u32)> = boxes
            .par_iter()
            .with_min_len(PARALLEL)
            .enumerate()
            .map(|(t, b)| {
                let c = centroid(b);
                (std::array::from_fn(|a| ((c[a] - lowest[a]) as f32).to_bits()), t as u32)
            })
            .collect();
        split(&mut centroids);
        let order: Vec<u32> = centroids.par_iter().with_min_len(PARALLEL).map(|&(_, t)| t).collect();
        drop(centroids);

        // Heap layout: node k has children 2k + 1 and 2k + 2, the nodes of one depth side by side
        // (depth d from 2^d - 1); each node's range from its place, then the boxes depth by depth
        // from the leaves up, each depth in parallel.
        let n = order.len();
        let mut depths = 1;
        let mut longest = n;
        while longest > LEAF {
            longest = longest.div_ceil(2);
            depths += 1;
        }
        let size = (1usize << depths) - 1;
        let mut nodes: Vec<Node> = (0..size)
            .into_par_iter()
            .with_min_len(PARALLEL)
            .map(|k| {
                let (lo, hi) = node_range(k, n);
                Node { bounds: Box3::EMPTY, lo, hi }
            })
            .collect();
        for d in (0..depths).rev() {
            let (upper, lower) = nodes.split_at_mut((1 << (d + 1)) - 1);
            let first = (1usize << d) - 1;
            upper[first..].par_iter_mut().with_min_len(PARALLEL).enumerate().for_each(|(i, node)| {
                let Node { lo, hi, .. } = *node;
                node.bounds = if hi == lo {
                    Box3::EMPTY
                } else if (hi - lo) as usize <= LEAF {
                    order[lo as usize..hi as usize].iter().fold(Box3::EMPTY, |b, &t| b.union(&boxes[t as usize]))
                } else {
                    // Children 2k + 1 and 2k + 2 of node k = first + i, at 2i and 2i + 1 of the
                    // next depth.
                    lower[2 * i].bounds.union(&lower[2 * i + 1].bounds)
                };
            });
        }
        let root = nodes[0].bounds;
        let diagonal = (0..3).map(|a| (root.max[a] - root.min[a]).powi(2)).sum::<f64>().sqrt();
        let slack = if diagonal.is_finite() { 1e-9 * diagonal } else { 0.0 };
        TriangleBvh { nodes, order, boxes, slack }
    }

    fn is_leaf(&self, node: &Node) -> bool {
        ((node.hi - node.lo) as usize) <= LEAF
    }

    fn leaf(&self, node: &Node) -> &[u32] {
        &self.order[node.lo as usize..node.hi as usize]
    }

    /// The triangle of smallest `distance2(t)` (a squared distance from `p`, at least the
    /// squared distance from `p` to the triangle's box up to rounding), the lowest index among
    /// equal ones, and that value. `None` only for a tree without triangles.
    /// `hint`, if given, is taken as the best so far (the nearest triangle before a small move of
    /// the point: most boxes are then pruned at once); the answer does not depend on it, since
    /// the bound only ever prunes boxes farther than a triangle already found.
    pub(crate) fn closest_from(
        &self,
        p: &Point,
        hint: Option<u32>,
        distance2: impl Fn(u32) -> f64,
    ) -> Option<(u32, f64)> {
        let mut best: Option<(u32, f64)> = None;
        // Boxes farther than this squared distance cannot hold a triangle as close as the best.
        let mut bound = f64::INFINITY;
        // The bound for a best triangle at squared distance d (the slack keeps rounding out).
        let bound_of = |d: f64| {
            let r = d.sqrt() + self.slack;
            if r.is_nan() {
                f64::INFINITY
            } else {
                r * r
            }
        };
        if let Some(t) = hint.filter(|&t| (t as usize) < self.boxes.len()) {
            let d = distance2(t);
            best = Some((t, d));
            bound = bound_of(d);
        }
        let mut stack = [0u32; STACK];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let node = &self.nodes[stack[top] as usize];
            if node.hi == node.lo || node.bounds.distance2(p) > bound {
                continue;
            }
            if self.is_leaf(node) {
                for &t in self.leaf(node) {
                    let d = distance2(t);
                    let better = match best {
                        None => true,
                        Some((bt, bd)) => d < bd || (d == bd && t < bt),
                    };
                    if better {
                        best = Some((t, d));
                        bound = bound_of(d);
                    }
                }
            } else {
                let k = stack[top] as usize;
                let (l, r) = (2 * k + 1, 2 * k + 2);
                // The nearer child on top, visited first.
                let (near, far) = if self.nodes[l].bounds.distance2(p) <= self.nodes[r].bounds.distance2(p) {
                    (l, r)
                } else {
                    (r, l)
                };
                stack[top] = far as u32;
                stack[top + 1] = near as u32;
                top += 2;
            }
        }
        best
    }

    /// The smallest `hit(t)` over the triangles (a distance along the unit ray from `origin`
    /// along `dir`, at least the distance to where the ray enters the triangle's box), if any.
    pub(crate) fn first_hit(&self, origin: &Point, dir: &Vector, hit: impl Fn(u32) -> Option<f64>) -> Option<f64> {
        let mut best: Option<f64> = None;
        let mut stack = [0u32; STACK];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let k = stack[top] as usize;
            let node = &self.nodes[k];
            let reach = best.map_or(f64::MAX, |b| b + self.slack);
            if node.hi == node.lo || node.bounds.ray_entry(origin, dir, self.slack, reach).is_none() {
                continue;
            }
            if self.is_leaf(node) {
                for &t in self.leaf(node) {
                    if let Some(d) = hit(t) {
                        if best.is_none_or(|b| d < b) {
                            best = Some(d);
                        }
                    }
                }
            } else {
                stack[top] = (2 * k + 2) as u32;
                stack[top + 1] = (2 * k + 1) as u32;
                top += 2;
            }
        }
        best
    }

    /// Visit the triangles whose box meets the box `min`..`max`, until `visit` returns false.
    fn each_meeting(&self, min: &Point, max: &Point, mut visit: impl FnMut(u32) -> bool) {
        let query = Box3 { min: [min.x, min.y, min.z], max: [max.x, max.y, max.z] };
        let mut stack = [0u32; STACK];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let k = stack[top] as usize;
            let node = &self.nodes[k];
            if node.hi == node.lo || !node.bounds.meets(&query) {
                continue;
            }
            if self.is_leaf(node) {
                for &t in self.leaf(node) {
                    if self.boxes[t as usize].meets(&query) && !visit(t) {
                        return;
                    }
                }
            } else {
                stack[top] = (2 * k + 2) as u32;
                stack[top + 1] = (2 * k + 1) as u32;
                top += 2;
            }
        }
    }

    /// The triangles whose box meets the box `min`..`max`, by increasing index.
    pub(crate) fn meeting(&self, min: &Point, max: &Point) -> Vec<u32> {
        let mut out = Vec::new();
        self.each_meeting(min, max, |t| {
            out.push(t);
            true
        });
        out.sort_unstable();
        out
    }

    /// Whether any triangle's box meets the box `min`..`max`.
    pub(crate) fn any_meeting(&self, min: &Point, max: &Point) -> bool {
        let mut any = false;
        self.each_meeting(min, max, |_| {
            any = true;
            false
        });
        any
    }
}

/// The range of [`TriangleBvh::order`] that node `k` of a tree of `n` triangles covers: the
/// root all, each child one half of its parent's (the first half the smaller), and (0, 0) below
/// a leaf (at most [`LEAF`] triangles).
fn node_range(k: usize, n: usize) -> (u32, u32) {
    let (mut lo, mut hi) = (0, n as u32);
    // The bits of k + 1 after its leading one: the way down from the root (0 left, 1 right).
    let path = k + 1;
    for bit in (0..path.ilog2()).rev() {
        if (hi - lo) as usize <= LEAF {
            return (0, 0);
        }
        let mid = lo + (hi - lo) / 2;
        if (path >> bit) & 1 == 0 {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    (lo, hi)
}

/// Order triangles (centroid keys, index) by recursive median splits of the centroids (see the
/// module documentation).
fn split(order: &mut [([u32; 3], u32)]) {
    if order.len() <= LEAF {
        return;
    }
    let (mut lo, mut hi) = ([u32::MAX; 3], [0u32; 3]);
    for (c, _) in order.iter() {
        for a in 0..3 {
            lo[a] = lo[a].min(c[a]);
            hi[a] = hi[a].max(c[a]);
        }
    }
    let extent = |a: usize| f32::from_bits(hi[a]) - f32::from_bits(lo[a]);
    let mut axis = 0;
    for a in 1..3 {
        if extent(a) > extent(axis) {
            axis = a;
        }
    }
    let mid = order.len() / 2;
    order.select_nth_unstable_by_key(mid, |&(c, t)| (u64::from(c[axis]) << 32) | u64::from(t));
    let (left, right) = order.split_at_mut(mid);
    if left.len() + right.len() >= PARALLEL {
        rayon::join(|| split(left), || split(right));
    } else {
        split(left);
        split(right);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A wavy grid of triangles with many exact ties (a flat part) and some far ones.
    fn mesh(n: usize) -> (Vec<Point>, Vec<[u32; 3]>) {
        let mut v = Vec::new();
        for i in 0..=n {
            for j in 0..=n {
                let (x, y) = (i as f64 / n as f64, j as f64 / n as f64);
                let z = if x < 0.5 { 0.0 } else { (7.0 * x).sin() * (5.0 * y).cos() * 0.1 };
                v.push(Point::new(x, y, z));
            }
        }
        let id = |i: usize, j: usize| (i * (n + 1) + j) as u32;
        let mut t = Vec::new();
        for i in 0..n {
            for j in 0..n {
                t.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                t.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        (v, t)
    }

    #[test]
    fn node_ranges_are_the_halvings_from_the_root() {
        // The ranges the tree was built with top down, node by node, before they were computed
        // from each node's place.
        for n in [0, 1, 4, 5, 8, 9, 17, 100, 1000, 4097] {
            let mut size = 1;
            let mut longest = n;
            while longest > LEAF {
                longest = longest.div_ceil(2);
                size = 2 * size + 1;
            }
            let mut ranges = vec![(0u32, 0u32); size];
            ranges[0] = (0, n as u32);
            for k in 0..size {
                let (lo, hi) = ranges[k];
                if (hi - lo) as usize > LEAF {
                    let mid = lo + (hi - lo) / 2;
                    ranges[2 * k + 1] = (lo, mid);
                    ranges[2 * k + 2] = (mid, hi);
                }
            }
            assert_eq!((0..size).map(|k| node_range(k, n)).collect::<Vec<_>>(), ranges, "{n} triangles");
        }
    }

    #[test]
    fn queries_equal_brute_force_whatever_the_thread_count() {
        let (v, tris) = mesh(60);
        let d2 = |t: u32, p: &Point| {
            let [a, b, c] = tris[t as usize].map(|i| v[i as usize]);
            (super::super::surface::closest_point_on_triangle(p, &a, &b, &c) - p).norm_squared()
        };
        let trees: Vec<TriangleBvh> = [1, 2, 3]
            .into_iter()
            .map(|threads| {
                let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
                pool.install(|| TriangleBvh::new(&v, &tris))
            })
            .collect();
        for q in 0..400 {
            let f = q as f64;
            // Points above the flat half tie between facets sharing the foot; others do not.
            let p =
                Point::new((f * 0.618).fract() * 1.2 - 0.1, (f * 0.377).fract() * 1.2 - 0.1, (f * 0.29).fract() - 0.3);
            let brute = (0..tris.len() as u32)
                .map(|t| (t, d2(t, &p)))
                .fold(None, |b: Option<(u32, f64)>, (t, d)| match b {
                    Some((bt, bd)) if bd < d || (bd == d && bt < t) => Some((bt, bd)),
                    _ => Some((t, d)),
                })
                .unwrap();
            let r = 0.05;
            let (lo, hi) = (p - Vector::repeat(r), p + Vector::repeat(r));
            let near: Vec<u32> = (0..tris.len() as u32)
                .filter(|&t| {
                    let b = Box3::of(&tris[t as usize].map(|i| v[i as usize]));
                    b.meets(&Box3 { min: [lo.x, lo.y, lo.z], max: [hi.x, hi.y, hi.z] })
                })
                .collect();
            for tree in &trees {
                assert_eq!(tree.closest_from(&p, None, |t| d2(t, &p)), Some(brute), "point {p:?}");
                // Whatever facet the search starts from, the same answer.
                for hint in [0, q % tris.len() as u32, brute.0, tris.len() as u32 - 1] {
                    assert_eq!(tree.closest_from(&p, Some(hint), |t| d2(t, &p)), Some(brute), "point {p:?}");
                }
                assert_eq!(tree.meeting(&lo, &hi), near);
                assert_eq!(tree.any_meeting(&lo, &hi), !near.is_empty());
            }
        }
        // A point exactly above a vertex of the flat half: six facets at distance 0.25, the
        // lowest index wins.
        let p = Point::new(0.25, 0.5, 0.25);
        let ties: Vec<u32> = (0..tris.len() as u32).filter(|&t| d2(t, &p) == 0.0625).collect();
        assert!(ties.len() > 1, "{ties:?}");
        for tree in &trees {
            assert_eq!(tree.closest_from(&p, None, |t| d2(t, &p)).unwrap().0, ties[0]);
            for &hint in &ties {
                assert_eq!(tree.closest_from(&p, Some(hint), |t| d2(t, &p)).unwrap().0, ties[0]);
            }
        }
    }

    #[test]
    fn ray_hit_is_the_nearest_over_all_triangles() {
        let (v, tris) = mesh(30);
        let tree = TriangleBvh::new(&v, &tris);
        use parry3d_f64::query::{Ray, RayCast};
        let hit = |t: u32, o: &Point, d: &Vector| {
            let [a, b, c] = tris[t as usize].map(|i| v[i as usize]);
            parry3d_f64::shape::Triangle::new(a, b, c).cast_local_ray(&Ray::new(*o, *d), f64::MAX, false)
        };
        for q in 0..200 {
            let f = q as f64;
            let o = Point::new((f * 0.618).fract(), (f * 0.377).fract(), 1.0);
            let d = Vector::new((f * 0.11).fract() - 0.5, (f * 0.23).fract() - 0.5, -1.0).normalize();
            let brute = (0..tris.len() as u32).filter_map(|t| hit(t, &o, &d)).reduce(f64::min);
            assert_eq!(tree.first_hit(&o, &d, |t| hit(t, &o, &d)), brute);
        }
        // Straight down onto the flat half, along an axis (zero direction components).
        let (o, d) = (Point::new(0.2, 0.3, 1.0), -Vector::z());
        assert_eq!(tree.first_hit(&o, &d, |t| hit(t, &o, &d)), Some(1.0));
    }
}
