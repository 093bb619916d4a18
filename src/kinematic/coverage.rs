//! How much of a surface a draped net covers: the share of the tool's area (or of the part of it
//! inside the ply's outline) that lies under the net, which is what an engineer means by a ply's
//! coverage. Each triangle of the surface is split into sub-triangles about one net spacing
//! across and counted as covered where the net lies over its sub-triangles' centroids
//! ([`NetSampler::cover`]).
use super::outline::Outline;
use super::sampler::NetSampler;
use super::DrapeNet;
use crate::geometry::Point;
use rayon::prelude::*;

/// At most this many sample points over a whole surface: a surface that is large against the
/// net's spacing is sampled more coarsely (the share is still exact to about a sample's size
/// along the ply's boundary).
const MAX_SAMPLES: usize = 2_000_000;
/// A sample counts as covered when the net passes within this many spacings of it along the
/// net's normal (the net follows the facets up to their sagitta; a refined net lies on the
/// smooth surface through them).
const COVER_DISTANCE_SPACINGS: f64 = 1.0;

/// What a net covers of a surface.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfaceCoverage {
    /// Area of the surface the share is taken of (the whole tool, or the part of it inside the
    /// ply's outline), m^2.
    pub area: f64,
    /// The part of that area under the net, m^2.
    pub covered_area: f64,
    /// Whether `area` is the part inside the ply's outline (else the whole surface).
    pub of_outline: bool,
}

impl SurfaceCoverage {
    /// `covered_area / area`, 0 for an empty surface.
    pub fn share(&self) -> f64 {
        if self.area > 0.0 {
            (self.covered_area / self.area).min(1.0)
        } else {
            0.0
        }
    }
}

/// The share of the surface made of `triangles` (corner points, m) that `net` covers; with an
/// outline, only the surface inside it counts. The result does not depend on the number of
/// threads (per-triangle sums are added in triangle order).
pub fn surface_coverage(net: &DrapeNet, triangles: &[[Point; 3]], outline: Option<&Outline>) -> SurfaceCoverage {
    let sampler = NetSampler::new(net);
    let step = sample_step(triangles, net.spacing);
    let reach = COVER_DISTANCE_SPACINGS * net.spacing;
    let per_triangle: Vec<(f64, f64)> = triangles
        .par_iter()
        .map(|t| {
            let n = subdivisions(t, step);
            let piece = triangle_area(t) / (n * n) as f64;
            let (mut area, mut covered) = (0.0, 0.0);
            for p in sample_points(t, n) {
                if outline.is_some_and(|o| !o.contains(&p)) {
                    continue;
                }
                area += piece;
                if sampler.as_ref().is_some_and(|s| s.cover(&p, reach).is_some()) {
                    covered += piece;
                }
            }
            (area, covered)
        })
        .collect();
    let (area, covered_area) = per_triangle.iter().fold((0.0, 0.0), |(a, c), (ta, tc)| (a + ta, c + tc));
    SurfaceCoverage { area, covered_area, of_outline: outline.is_some() }
}

fn triangle_area(t: &[Point; 3]) -> f64 {
    0.5 * (t[1] - t[0]).cross(&(t[2] - t[0])).norm()
}

fn longest_edge(t: &[Point; 3]) -> f64 {
    (t[1] - t[0]).norm().max((t[2] - t[1]).norm()).max((t[0] - t[2]).norm())
}

/// Sub-triangles along each edge of triangle `t` for samples about `step` apart.
fn subdivisions(t: &[Point; 3], step: f64) -> usize {
    let n = (longest_edge(t) / step).ceil();
    if n.is_finite() && n >= 1.0 {
        n.min(1e4) as usize
    } else {
        1
    }
}

/// The sample spacing: one net spacing, coarser if the surface would need more than
/// [`MAX_SAMPLES`] points.
fn sample_step(triangles: &[[Point; 3]], spacing: f64) -> f64 {
    let mut step = spacing;
    for _ in 0..40 {
        let count: f64 = triangles.iter().map(|t| (subdivisions(t, step) as f64).powi(2)).sum();
        if count <= MAX_SAMPLES as f64 {
            break;
        }
        step *= (count / MAX_SAMPLES as f64).sqrt().max(1.1);
    }
    step
}

/// Centroids of the n^2 sub-triangles of the regular subdivision of `t`.
fn sample_points(t: &[Point; 3], n: usize) -> Vec<Point> {
    let (a, e1, e2) = (t[0], t[1] - t[0], t[2] - t[0]);
    let at = |u: f64, v: f64| -> Point { a + e1 * (u / n as f64) + e2 * (v / n as f64) };
    let mut out = Vec::with_capacity(n * n);
    for i in 0..n {
        for j in 0..n - i {
            out.push(at(i as f64 + 1.0 / 3.0, j as f64 + 1.0 / 3.0));
            if i + j + 1 < n {
                out.push(at(i as f64 + 2.0 / 3.0, j as f64 + 2.0 / 3.0));
            }
        }
    }
    debug_assert_eq!(out.len(), n * n);
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Vector;
    use crate::kinematic::NodeStatus;

    /// A flat net of `n x n` nodes, spacing `d`, from (0, 0).
    fn flat_net(n: usize, d: f64) -> DrapeNet {
        let mut net = DrapeNet::new("flat", d, n, n, (0, 0));
        for i in 0..n {
            for j in 0..n {
                let k = net.index(i, j);
                net.positions[k] = Point::new(i as f64 * d, j as f64 * d, 0.0);
                net.status[k] = NodeStatus::Placed;
            }
        }
        net
    }

    fn square(side: f64) -> Vec<[Point; 3]> {
        let p = |x: f64, y: f64| Point::new(x, y, 0.0);
        vec![[p(0.0, 0.0), p(side, 0.0), p(side, side)], [p(0.0, 0.0), p(side, side), p(0.0, side)]]
    }

    #[test]
    fn a_net_over_a_quarter_of_a_plate_covers_a_quarter() {
        // 0.5 x 0.5 m of net on a 1 x 1 m plate of two triangles.
        let c = surface_coverage(&flat_net(51, 0.01), &square(1.0), None);
        assert!((c.area - 1.0).abs() < 1e-12, "{c:?}");
        assert!((c.share() - 0.25).abs() < 0.01, "{c:?}");
        // A net larger than the plate covers all of it.
        let c = surface_coverage(&flat_net(201, 0.01), &square(1.0), None);
        assert!((c.share() - 1.0).abs() < 1e-12, "{c:?}");
    }

    #[test]
    fn subdivision_centroids_fill_the_triangle() {
        let t = [Point::new(0.0, 0.0, 0.0), Point::new(1.0, 0.0, 0.0), Point::new(0.0, 1.0, 0.0)];
        for n in 1..6 {
            let pts = sample_points(&t, n);
            assert_eq!(pts.len(), n * n);
            let mean = pts.iter().fold(Vector::zeros(), |s, p| s + p.coords) / pts.len() as f64;
            assert!((mean - Vector::new(1.0 / 3.0, 1.0 / 3.0, 0.0)).norm() < 1e-12, "n = {n}");
        }
    }
}
