//! Offset surfaces: the tool moved along its normals by the thickness of the plies below, so
//! each ply of a layup is draped where it will lie.
//!
//! Each vertex moves along the direction `m` that moves every adjacent facet's plane by the same
//! distance: the least-squares solution of `n_f . m = 1` over the facets around the vertex,
//! weighted by their corner angles. On a smooth surface `m` is the vertex normal; on a sharp
//! edge or corner (convex or concave) it is longer and points along the bisector, so both faces
//! move by the full thickness instead of the corner thinning the stack. The distance per vertex
//! comes from the caller (it varies where the plies below shear and thicken, and steps down at
//! their edges).
use super::{Point, ToolError, ToolSurface, Vector};
use nalgebra::{Matrix3, SymmetricEigen};

/// Eigenvalues of the normal scatter below this fraction of the largest are dropped: the
/// facets around the vertex do not constrain the offset in that direction.
const SCATTER_CUTOFF_REL: f64 = 1e-9;
/// Longest offset direction relative to the distance: a vertex on a 150 deg concave edge moves
/// 1 / cos(75 deg) = 3.9 times the thickness; sharper spikes are clipped to this.
pub const MAX_OFFSET_STRETCH: f64 = 4.0;

/// What an offset did.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct OffsetReport {
    /// Vertices moved (distance > 0).
    pub moved: usize,
    /// Largest distance over the moved vertices, metres.
    pub max_distance: f64,
    /// Mean distance over the moved vertices, metres.
    pub mean_distance: f64,
    /// Vertices whose direction was clipped at [`MAX_OFFSET_STRETCH`].
    pub clipped: usize,
    /// Triangles still turned over (offset normal against the original) after relaxation: a
    /// concave region whose radius is below the offset distance folds the offset surface there.
    pub folded: usize,
    /// Vertices moved off their normal offset to unfold such a region (the plies bridge it).
    pub relaxed: usize,
}

/// Unit-distance offset direction of every vertex (see the module doc), pointing to the side the
/// facet normals point to.
pub fn offset_directions(tool: &ToolSurface) -> (Vec<Vector>, usize) {
    let vertices = tool.vertices();
    let mut scatter = vec![Matrix3::<f64>::zeros(); vertices.len()];
    let mut rhs = vec![Vector::zeros(); vertices.len()];
    for (t, tri) in tool.triangles().iter().enumerate() {
        let n = tool.normal(t as u32);
        for k in 0..3 {
            let (a, b, c) = (tri[k] as usize, tri[(k + 1) % 3] as usize, tri[(k + 2) % 3] as usize);
            let (u, v) = (vertices[b] - vertices[a], vertices[c] - vertices[a]);
            let angle = u.cross(&v).norm().atan2(u.dot(&v));
            scatter[a] += n * n.transpose() * angle;
            rhs[a] += n * angle;
        }
    }
    let mut clipped = 0;
    let dirs = scatter
        .iter()
        .zip(&rhs)
        .map(|(s, r)| {
            if r.norm() == 0.0 {
                return Vector::zeros(); // a vertex no triangle uses
            }
            let eig = SymmetricEigen::new(*s);
            let top = eig.eigenvalues.iter().cloned().fold(0.0, f64::max);
            let mut m = Vector::zeros();
            for k in 0..3 {
                let lambda = eig.eigenvalues[k];
                if lambda > SCATTER_CUTOFF_REL * top {
                    let e = eig.eigenvectors.column(k);
                    m += e * (e.dot(r) / lambda);
                }
            }
            let mean = r.normalize();
            if !(m.dot(&mean) > 0.0) || !m.iter().all(|x| x.is_finite()) {
                m = mean;
            }
            if m.norm() > MAX_OFFSET_STRETCH {
                clipped += 1;
                m *= MAX_OFFSET_STRETCH / m.norm();
            }
            m
        })
        .collect();
    (dirs, clipped)
}

/// The tool offset by `distance[v]` metres at vertex `v` (to the side its normals point to; a
/// negative distance moves the other way). The result is a new, checked [`ToolSurface`].
pub fn offset_surface(tool: &ToolSurface, distance: &[f64]) -> Result<(ToolSurface, OffsetReport), ToolError> {
    let (dirs, clipped) = offset_directions(tool);
    offset_along(tool, &dirs, clipped, distance)
}

/// The tool offset by `distance[v]` along precomputed directions `dirs` (from
/// [`offset_directions`], of which `clipped` were clipped): for several offsets of one tool.
pub fn offset_along(
    tool: &ToolSurface,
    dirs: &[Vector],
    clipped: usize,
    distance: &[f64],
) -> Result<(ToolSurface, OffsetReport), ToolError> {
    assert_eq!(distance.len(), tool.vertices().len(), "one offset distance per tool vertex");
    let mut report = OffsetReport { clipped, ..Default::default() };
    let moved = offset_vertices(tool, dirs, distance);
    for &h in distance.iter().filter(|h| **h != 0.0) {
        report.moved += 1;
        report.max_distance = report.max_distance.max(h.abs());
        report.mean_distance += h.abs();
    }
    if report.moved > 0 {
        report.mean_distance /= report.moved as f64;
    }
    let mut moved = moved;
    (report.relaxed, report.folded) = unfold(tool, &mut moved, distance);
    let surface = ToolSurface::from_triangles(moved, tool.triangles().to_vec())?;
    Ok((surface, report))
}

/// Triangles of the offset whose normal turned against the tool's.
fn folded_triangles(tool: &ToolSurface, moved: &[Point]) -> Vec<usize> {
    (0..tool.triangles().len())
        .filter(|&t| {
            let [a, b, c] = tool.triangles()[t].map(|i| moved[i as usize]);
            (b - a).cross(&(c - a)).dot(&tool.normal(t as u32)) <= 0.0
        })
        .collect()
}

/// The vertices joined to each vertex by an edge of the tool, in index order.
fn vertex_rings(tool: &ToolSurface) -> Vec<Vec<u32>> {
    let mut ring: Vec<Vec<u32>> = vec![Vec::new(); tool.vertices().len()];
    for tri in tool.triangles() {
        for k in 0..3 {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            ring[a as usize].push(b);
            ring[b as usize].push(a);
        }
    }
    for r in &mut ring {
        r.sort_unstable();
        r.dedup();
    }
    ring
}

/// Sweeps of fold relaxation at most.
const MAX_UNFOLD_SWEEPS: usize = 200;

/// Where the offset folds (a concave radius smaller than the stack: the offsets of the two sides
/// cross), the plies bridge the corner instead: the corners of folded triangles are moved to the
/// mean of their neighbours, sweep after sweep (widening to the neighbours when a sweep does not
/// help), and pushed back out to their offset distance from the tool where the mean sank below
/// it, until nothing is folded. Returns the number of vertices moved and of triangles still
/// folded.
fn unfold(tool: &ToolSurface, moved: &mut [Point], distance: &[f64]) -> (usize, usize) {
    let mut folded = folded_triangles(tool, moved);
    if folded.is_empty() {
        return (0, 0);
    }
    let n = moved.len();
    let ring = vertex_rings(tool);
    let mut touched = vec![false; n];
    let mut widen = 0;
    let mut last = usize::MAX;
    for _ in 0..MAX_UNFOLD_SWEEPS {
        if folded.is_empty() {
            break;
        }
        if folded.len() >= last {
            widen += 1; // no progress: relax a wider patch
        }
        last = folded.len();
        let mut active = vec![false; n];
        for &t in &folded {
            for v in tool.triangles()[t] {
                active[v as usize] = true;
            }
        }
        for _ in 0..widen {
            let grown: Vec<usize> = (0..n).filter(|&v| active[v]).collect();
            for v in grown {
                for &w in &ring[v] {
                    active[w as usize] = true;
                }
            }
        }
        // Jacobi sweep: every active vertex from the old positions (order-free, deterministic).
        let updates: Vec<(usize, Point)> = (0..n)
            .filter(|&v| active[v] && !ring[v].is_empty())
            .map(|v| {
                let sum = ring[v].iter().fold(Vector::zeros(), |s, &w| s + moved[w as usize].coords);
                (v, Point::from(sum / ring[v].len() as f64))
            })
            .collect();
        for (v, p) in updates {
            let q = tool.closest_point(&p).point;
            let (gap, clearance) = ((p - q).norm(), distance[v].abs());
            moved[v] = if gap < clearance && gap > 0.0 { q + (p - q) * (clearance / gap) } else { p };
            touched[v] = true;
        }
        folded = folded_triangles(tool, moved);
    }
    (touched.iter().filter(|&&t| t).count(), folded.len())
}

/// Steepest rise, across the tool, of the surface a ply lies on where the plies below it end: a
/// ply bridges the drop at the edge of the plies under it (1 in 4: a 2 mm stack over 8 mm)
/// instead of following a cliff one facet wide. Why: a step of a stack thickness over one facet
/// is a kink the smooth surface of the pressed contact cannot follow; the upper plies'
/// mechanical drape stopped on it (the hemisphere's third and fourth plies, `LineSearchFailed`
/// and `Stalled`). A gentler 1 in 10 also cured those, but widened the ramps over the double
/// dome's corners enough that its third ply (pushed past the tool's open edge there) ran out of
/// iterations: the shortest ramp that spans a few facets changes the least.
pub const PLY_DROP_SLOPE: f64 = 0.25;

/// The least field at or above `distance` that rises by at most `slope` per metre along the tool's
/// edges: every fall steeper than `slope` (a ply drop) becomes a ramp of that slope outward from
/// the higher side, and gentler variations (thickening with shear) stay as they are. A max-plus
/// Dijkstra from the highest vertices; ties are taken by vertex index, so the result does not
/// depend on the order of equal values.
pub fn ramp_drops(tool: &ToolSurface, distance: &[f64], slope: f64) -> Vec<f64> {
    use std::cmp::Ordering;
    use std::collections::BinaryHeap;
    #[derive(PartialEq)]
    struct Entry(f64, u32);
    impl Eq for Entry {}
    impl PartialOrd for Entry {
        fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
            Some(self.cmp(other))
        }
    }
    impl Ord for Entry {
        fn cmp(&self, other: &Self) -> Ordering {
            self.0.total_cmp(&other.0).then_with(|| other.1.cmp(&self.1))
        }
    }
    let vertices = tool.vertices();
    let ring = vertex_rings(tool);
    let mut value = distance.to_vec();
    let mut heap: BinaryHeap<Entry> =
        value.iter().enumerate().filter(|(_, h)| **h > 0.0).map(|(v, &h)| Entry(h, v as u32)).collect();
    while let Some(Entry(h, v)) = heap.pop() {
        if h < value[v as usize] {
            continue; // a stale entry: the vertex was raised again since
        }
        for &w in &ring[v as usize] {
            let reach = h - slope * (vertices[w as usize] - vertices[v as usize]).norm();
            if reach > value[w as usize] {
                value[w as usize] = reach;
                heap.push(Entry(reach, w));
            }
        }
    }
    value
}

/// The tool's vertices moved by `distance[v]` along `dirs[v]`.
pub fn offset_vertices(tool: &ToolSurface, dirs: &[Vector], distance: &[f64]) -> Vec<Point> {
    tool.vertices().iter().zip(dirs).zip(distance).map(|((p, m), &h)| p + m * h).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::shapes;

    /// Offsets agree with the analytic ones to this (metres), rounding only.
    const TOL: f64 = 1e-12;

    #[test]
    fn a_ply_drop_becomes_a_ramp_and_gentle_variations_stay() {
        // A flat 1 x 1 plate of 20 x 20 squares; the stack is 2 mm (rising gently with x) on
        // x < 0.5 and nothing beyond: a cliff one facet wide.
        let n = 21;
        let h = 1.0 / (n - 1) as f64;
        let vertices: Vec<Point> =
            (0..n * n).map(|k| Point::new((k % n) as f64 * h, (k / n) as f64 * h, 0.0)).collect();
        let mut tris = Vec::new();
        for j in 0..n - 1 {
            for i in 0..n - 1 {
                let a = (j * n + i) as u32;
                tris.push([a, a + 1, a + n as u32 + 1]);
                tris.push([a, a + n as u32 + 1, a + n as u32]);
            }
        }
        let tool = ToolSurface::from_triangles(vertices.clone(), tris).unwrap();
        let given: Vec<f64> = vertices.iter().map(|p| if p.x < 0.5 { 0.002 + 0.0001 * p.x } else { 0.0 }).collect();
        let slope = 0.001;
        let ramped = ramp_drops(&tool, &given, slope);
        for (v, p) in vertices.iter().enumerate() {
            assert!(ramped[v] >= given[v], "never below the stack");
            if p.x < 0.5 {
                assert_eq!(ramped[v], given[v], "a gentle rise is kept at {p:?}");
            } else {
                // Outward from the last covered column (x = 0.45) at the given slope, to zero.
                let top = 0.002 + 0.0001 * 0.45;
                let expect = (top - slope * (p.x - 0.45)).max(0.0);
                assert!((ramped[v] - expect).abs() < TOL, "ramp at {p:?}: {} against {expect}", ramped[v]);
            }
        }
        // No edge rises faster than the slope.
        for tri in tool.triangles() {
            for k in 0..3 {
                let (a, b) = (tri[k] as usize, tri[(k + 1) % 3] as usize);
                let length = (vertices[a] - vertices[b]).norm();
                assert!((ramped[a] - ramped[b]).abs() <= slope * length + TOL);
            }
        }
    }

    #[test]
    fn a_sphere_offset_is_a_larger_sphere_over_the_facet_planes() {
        let tool = shapes::hemisphere(0.1, 12).into_surface().unwrap();
        let h = 0.002;
        let (off, report) = offset_surface(&tool, &vec![h; tool.vertices().len()]).unwrap();
        assert_eq!(report.folded, 0);
        assert_eq!(report.clipped, 0);
        // Vertex on the sphere: moves radially; each adjacent facet plane moves by ~h.
        for (p, q) in tool.vertices().iter().zip(off.vertices()) {
            let d = q - p;
            let radial = p.coords.normalize();
            assert!((d.normalize() - radial).norm() < 0.05, "offset leaves the radial direction at {p:?}");
            assert!(d.norm() >= h - TOL && d.norm() < 1.05 * h, "offset {}", d.norm());
        }
    }

    #[test]
    fn a_sharp_inside_corner_moves_both_walls_by_the_thickness() {
        // An L-shaped channel: floor z = 0 for x < 0, wall x = 0 for z > 0, normals towards (-x, +z)
        // (the ply lies inside the corner).
        let v = vec![
            Point::new(-1.0, 0.0, 0.0),
            Point::new(0.0, 0.0, 0.0),
            Point::new(0.0, 1.0, 0.0),
            Point::new(-1.0, 1.0, 0.0),
            Point::new(0.0, 0.0, 1.0),
            Point::new(0.0, 1.0, 1.0),
        ];
        let tris = vec![[0, 1, 2], [0, 2, 3], [1, 4, 5], [1, 5, 2]];
        let tool = ToolSurface::from_triangles(v, tris).unwrap();
        assert!(tool.normal(0).z > 0.0 && tool.normal(2).x < 0.0, "test mesh winding");
        let h = 0.01;
        let (off, report) = offset_surface(&tool, &[h; 6]).unwrap();
        assert_eq!(report.folded, 0);
        for (k, p) in off.vertices().iter().enumerate() {
            let on_floor = tool.vertices()[k].z == 0.0;
            let on_wall = tool.vertices()[k].x == 0.0;
            if on_floor {
                assert!((p.z - h).abs() < TOL, "vertex {k} floor offset {}", p.z);
            }
            if on_wall {
                assert!((p.x + h).abs() < TOL, "vertex {k} wall offset {}", p.x);
            }
        }
    }

    /// An L-shaped channel with a concave fillet of radius `r` (floor z = 0 for x < -r, wall
    /// x = 0 for z > r), extruded along y; normals into the channel.
    fn channel(r: f64, n_arc: usize) -> ToolSurface {
        let mut profile = vec![Point::new(-1.0, 0.0, 0.0), Point::new(-0.5, 0.0, 0.0)];
        for k in 0..=n_arc {
            let a = std::f64::consts::FRAC_PI_2 * k as f64 / n_arc as f64;
            profile.push(Point::new(-r + r * a.sin(), 0.0, r - r * a.cos()));
        }
        profile.extend([Point::new(0.0, 0.0, 0.5), Point::new(0.0, 0.0, 1.0)]);
        let m = profile.len();
        let mut v = Vec::new();
        for y in [0.0, 0.2, 0.4] {
            v.extend(profile.iter().map(|p| Point::new(p.x, y, p.z)));
        }
        let mut tris = Vec::new();
        for row in 0..2u32 {
            for k in 0..(m as u32 - 1) {
                let (a, b) = (row * m as u32 + k, (row + 1) * m as u32 + k);
                tris.push([a, a + 1, b + 1]);
                tris.push([a, b + 1, b]);
            }
        }
        let tool = ToolSurface::from_triangles(v, tris).unwrap();
        assert!(tool.normal(0).z > 0.0, "channel winding: normals into the channel");
        tool
    }

    #[test]
    fn a_stack_thicker_than_a_concave_fillet_bridges_it_without_folding() {
        let (r, h) = (0.01, 0.03);
        let tool = channel(r, 8);
        let (dirs, clipped) = offset_directions(&tool);
        let plain = offset_vertices(&tool, &dirs, &vec![h; tool.vertices().len()]);
        assert!(!folded_triangles(&tool, &plain).is_empty(), "the plain offset folds in the fillet");
        let (off, report) = offset_along(&tool, &dirs, clipped, &vec![h; tool.vertices().len()]).unwrap();
        assert_eq!(report.folded, 0);
        assert!(report.relaxed > 0);
        // The bridge keeps clear of the tool: no vertex comes closer to it than the stack.
        for (k, p) in off.vertices().iter().enumerate() {
            let d = tool.closest_point(p).distance;
            assert!(d > 0.95 * h, "vertex {k} at {p:?} is {d} from the tool");
        }
    }

    #[test]
    fn a_zero_distance_leaves_the_tool_where_it_is() {
        let tool = shapes::saddle(0.2, 0.3, 10).into_surface().unwrap();
        let (off, report) = offset_surface(&tool, &vec![0.0; tool.vertices().len()]).unwrap();
        assert_eq!(report.moved, 0);
        assert_eq!(off.vertices(), tool.vertices());
    }
}
