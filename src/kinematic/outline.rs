//! Ply outlines: a closed polyline on the tool that trims the net.
//!
//! Inside/outside is decided in the outline's best-fit plane (principal axes of its points), which
//! suits plies that do not wrap around the tool by more than a half turn; an outline that does is
//! refused when its projection crosses itself.
use super::fishnet::DrapeError;
use super::net::{DrapeNet, NodeStatus};
use crate::geometry::{Point, ToolSurface, Vector};

/// How far beyond the straight distance from the origin to the outline the grid is sized, to
/// cover fibre paths that bend over the tool (pi/2 would reach the rim of a hemisphere).
pub const REACH_FACTOR: f64 = 1.6;

/// A closed outline on the tool and its projection onto its best-fit plane.
#[derive(Debug, Clone)]
pub struct Outline {
    points: Vec<Point>,
    centroid: Point,
    u: Vector,
    v: Vector,
    polygon: Vec<(f64, f64)>,
}

impl Outline {
    /// Check and project an outline; its points must lie within one spacing of the tool.
    pub fn new(tool: &ToolSurface, points: &[Point], spacing: f64) -> Result<Self, DrapeError> {
        let mut pts: Vec<Point> = points.to_vec();
        if pts.len() > 1 && (pts[0] - pts[pts.len() - 1]).norm() <= 1e-12 * spacing {
            pts.pop(); // closing point repeated
        }
        if pts.len() < 3 {
            return Err(DrapeError::Outline(format!(
                "the ply outline has {} distinct point(s); give a closed polyline of at least 3 points",
                pts.len()
            )));
        }
        for (k, p) in pts.iter().enumerate() {
            if !p.coords.iter().all(|c| c.is_finite()) {
                return Err(DrapeError::Outline(format!("outline point {} is not a finite number", k + 1)));
            }
            let sp = tool.closest_point(p);
            if sp.distance > spacing {
                return Err(DrapeError::Outline(format!(
                    "outline point {} ({}, {}, {}) is {:.4} from the tool, more than one spacing: give an outline on the tool surface",
                    k + 1, p.x, p.y, p.z, sp.distance
                )));
            }
        }
        let n = pts.len() as f64;
        let centroid = Point::from(pts.iter().fold(Vector::zeros(), |s, p| s + p.coords) / n);
        let mut cov = nalgebra::Matrix3::<f64>::zeros();
        for p in &pts {
            let w = p - centroid;
            cov += w * w.transpose();
        }
        let eig = cov.symmetric_eigen();
        let mut order = [0usize, 1, 2];
        order.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]));
        let u: Vector = eig.eigenvectors.column(order[0]).into();
        let v: Vector = eig.eigenvectors.column(order[1]).into();
        let polygon: Vec<(f64, f64)> = pts.iter().map(|p| ((p - centroid).dot(&u), (p - centroid).dot(&v))).collect();
        if self_intersects(&polygon) {
            return Err(DrapeError::Outline(
                "the ply outline crosses itself (seen in its best-fit plane): give a simple closed polyline, in order around the ply".into(),
            ));
        }
        Ok(Outline { points: pts, centroid, u, v, polygon })
    }

    /// The outline's points as given (a repeated closing point dropped).
    pub fn points(&self) -> &[Point] {
        &self.points
    }

    /// Nodes from the origin to the grid's edge so that the grid covers the outline.
    pub fn half_size(&self, origin: &Point, spacing: f64) -> usize {
        let reach = self.points.iter().map(|p| (p - origin).norm()).fold(0.0, f64::max);
        (REACH_FACTOR * reach / spacing).ceil() as usize + 2
    }

    /// Whether a point (near the tool) lies inside the outline.
    pub fn contains(&self, p: &Point) -> bool {
        let w = p - self.centroid;
        point_in_polygon((w.dot(&self.u), w.dot(&self.v)), &self.polygon)
    }

    /// Drop the placed nodes outside the outline, and relabel failures that lie outside it
    /// (no placed node inside the outline among their eight neighbours).
    pub fn drop_outside(&self, net: &mut DrapeNet) {
        let inside: Vec<bool> = (0..net.positions.len())
            .map(|k| net.status[k] == NodeStatus::Placed && self.contains(&net.positions[k]))
            .collect();
        for i in 0..net.nu {
            for j in 0..net.nv {
                let k = net.index(i, j);
                if inside[k] {
                    continue;
                }
                let near_inside = (i.saturating_sub(1)..=(i + 1).min(net.nu - 1))
                    .any(|a| (j.saturating_sub(1)..=(j + 1).min(net.nv - 1)).any(|b| inside[net.index(a, b)]));
                if net.status[k] == NodeStatus::Placed || !near_inside {
                    net.status[k] = NodeStatus::OutsideOutline;
                }
            }
        }
    }
}

/// Even-odd rule.
fn point_in_polygon(p: (f64, f64), poly: &[(f64, f64)]) -> bool {
    let mut inside = false;
    let mut j = poly.len() - 1;
    for i in 0..poly.len() {
        let (xi, yi) = poly[i];
        let (xj, yj) = poly[j];
        if (yi > p.1) != (yj > p.1) && p.0 < (xj - xi) * (p.1 - yi) / (yj - yi) + xi {
            inside = !inside;
        }
        j = i;
    }
    inside
}

/// Whether two non-adjacent edges of a closed polygon cross.
fn self_intersects(poly: &[(f64, f64)]) -> bool {
    let n = poly.len();
    let cross = |o: (f64, f64), a: (f64, f64), b: (f64, f64)| (a.0 - o.0) * (b.1 - o.1) - (a.1 - o.1) * (b.0 - o.0);
    for i in 0..n {
        let (a, b) = (poly[i], poly[(i + 1) % n]);
        for j in i + 2..n {
            if i == 0 && j == n - 1 {
                continue;
            }
            let (c, d) = (poly[j], poly[(j + 1) % n]);
            let (d1, d2) = (cross(a, b, c), cross(a, b, d));
            let (d3, d4) = (cross(c, d, a), cross(c, d, b));
            if d1 * d2 < 0.0 && d3 * d4 < 0.0 {
                return true;
            }
        }
    }
    false
}
