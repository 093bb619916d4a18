//! Where an optimisation may put the seed: a disc about the ply's seed or a polygon, sampled on a
//! square lattice in the tool's tangent plane at the ply's seed and projected onto the tool along
//! that plane's normal, so every candidate seed lies on the tool.
use crate::geometry::{Point, ToolSurface, Vector};
use crate::kinematic::outline::Outline;
use serde::{Deserialize, Serialize};

/// Lattice points within this share of a step outside the region are still in it (the disc's
/// rim and the polygon's edges, against rounding).
const RIM_SLACK: f64 = 1e-9;
/// Most lattice points along a side of the region's box: a finer step is refused before any
/// lattice is built.
const MAX_LATTICE_SIDE: usize = 100_000;

/// The region the seed may lie in (m, on the tool).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum SeedRegion {
    /// Within `radius` of the ply's seed, measured in the tangent plane there.
    Disc {
        /// The radius, m.
        radius: f64,
    },
    /// Inside a closed polygon on the tool (seen in its best-fit plane, as ply outlines are).
    Polygon {
        /// Its corners, m.
        points: Vec<[f64; 3]>,
    },
}

/// The plane seeds are laid out in: the tangent plane of the tool at the ply's seed, its first
/// axis the scene's reference direction (0 deg) turned into it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Frame {
    /// The ply's seed on the tool, m.
    pub origin: [f64; 3],
    /// First axis (unit).
    pub u: [f64; 3],
    /// Second axis (unit): the normal times the first.
    pub v: [f64; 3],
}

impl Frame {
    /// The frame at `seed`'s foot on `tool`, its first axis along `reference` where that has a
    /// direction in the tangent plane.
    pub fn at(tool: &ToolSurface, seed: &Point, reference: &Vector) -> Frame {
        let foot = tool.closest_point(seed).point;
        let n = crate::layup::stack::seed_normal(tool, &foot);
        let mut u = reference - n * n.dot(reference);
        if u.norm() < 1e-6 * reference.norm().max(1.0) {
            // The reference is normal to the tool here: the world axis most across the normal.
            let axis = [Vector::x(), Vector::y(), Vector::z()]
                .into_iter()
                .min_by(|a, b| a.dot(&n).abs().total_cmp(&b.dot(&n).abs()))
                .unwrap_or_else(Vector::x);
            u = axis - n * n.dot(&axis);
        }
        let u = u.normalize();
        let v = n.cross(&u).normalize();
        Frame { origin: foot.coords.into(), u: u.into(), v: v.into() }
    }

    /// The point of the plane at coordinates (a, b), m.
    pub fn point(&self, ab: [f64; 2]) -> Point {
        Point::from(Vector::from(self.origin) + Vector::from(self.u) * ab[0] + Vector::from(self.v) * ab[1])
    }

    /// The plane's unit normal (the tool's normal at the ply's seed).
    pub fn normal(&self) -> Vector {
        Vector::from(self.u).cross(&Vector::from(self.v))
    }

    /// The plane coordinates of `p`'s projection onto the plane.
    pub fn coordinates(&self, p: &Point) -> [f64; 2] {
        let w = p.coords - Vector::from(self.origin);
        [w.dot(&Vector::from(self.u)), w.dot(&Vector::from(self.v))]
    }
}

/// A candidate seed: its plane coordinates and the point of the tool under them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Seed {
    /// Plane coordinates, m.
    pub ab: [f64; 2],
    /// The seed on the tool, m.
    pub point: Point,
}

/// The point of `tool` seen from `q` along the plane normal `n` (the nearer hit, ahead or
/// behind), or the closest point where the line misses the tool. Along the normal rather than
/// the closest point: over a hollow the closest point of a point above it may lie to either side
/// (two equally near points), which would break a symmetric lattice's symmetry and crowd seeds.
fn onto_tool(tool: &ToolSurface, q: &Point, n: &Vector) -> Point {
    let ahead = tool.cast_ray(q, n).map(|t| (t, q + n * t));
    let behind = tool.cast_ray(q, &-n).map(|t| (t, q - n * t));
    match (ahead, behind) {
        (Some(a), Some(b)) => {
            if b.0 < a.0 {
                b.1
            } else {
                a.1
            }
        }
        (Some((_, p)), None) | (None, Some((_, p))) => p,
        (None, None) => tool.closest_point(q).point,
    }
}

/// A seed region ready to answer whether a point is in it.
pub struct Region {
    region: SeedRegion,
    frame: Frame,
    outline: Option<Outline>,
}

impl Region {
    /// Check `region` on `tool`; `slack` is how far (m) polygon corners may lie off the tool.
    pub fn new(region: SeedRegion, frame: Frame, tool: &ToolSurface, slack: f64) -> Result<Region, String> {
        let outline =
            match &region {
                SeedRegion::Disc { radius } => {
                    if !(radius.is_finite() && *radius > 0.0) {
                        return Err(format!("--seed-radius must be a positive length, got {radius}"));
                    }
                    None
                }
                SeedRegion::Polygon { points } => {
                    let pts: Vec<Point> = points.iter().map(|p| Point::from(*p)).collect();
                    Some(Outline::new(tool, &pts, slack).map_err(|e| {
                        format!("--seed-polygon: {}", e.to_string().replace("ply outline", "seed polygon"))
                    })?)
                }
            };
        Ok(Region { region, frame, outline })
    }

    /// The seed at plane coordinates `ab`, if it is in the region: the tool's point under it.
    pub fn seed(&self, tool: &ToolSurface, ab: [f64; 2]) -> Option<Seed> {
        let point = onto_tool(tool, &self.frame.point(ab), &self.frame.normal());
        let inside = match (&self.region, &self.outline) {
            (SeedRegion::Disc { radius }, _) => ab[0].hypot(ab[1]) <= radius * (1.0 + RIM_SLACK),
            (_, Some(outline)) => outline.contains(&point),
            (SeedRegion::Polygon { .. }, None) => false,
        };
        inside.then_some(Seed { ab, point })
    }

    /// The seeds of the square lattice of `step` through the frame's origin that lie in the
    /// region, row by row (a seed on the frame's origin when it is in the region).
    pub fn lattice(&self, tool: &ToolSurface, step: f64) -> Result<Vec<Seed>, String> {
        if !(step.is_finite() && step > 0.0) {
            return Err(format!("--seed-step must be a positive length, got {step}"));
        }
        // The region's box in plane coordinates.
        let (lo, hi) = match &self.region {
            SeedRegion::Disc { radius } => ([-radius, -radius], [*radius, *radius]),
            SeedRegion::Polygon { points } => {
                points.iter().fold(([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]), |(lo, hi), p| {
                    let c = self.frame.coordinates(&Point::from(*p));
                    ([lo[0].min(c[0]), lo[1].min(c[1])], [hi[0].max(c[0]), hi[1].max(c[1])])
                })
            }
        };
        let index = |x: f64, up: bool| {
            let k = x / step;
            if up {
                (k - RIM_SLACK).ceil()
            } else {
                (k + RIM_SLACK).floor()
            }
        };
        let (i0, i1, j0, j1) = (index(lo[0], true), index(hi[0], false), index(lo[1], true), index(hi[1], false));
        if i1 - i0 > MAX_LATTICE_SIDE as f64 || j1 - j0 > MAX_LATTICE_SIDE as f64 {
            return Err(format!(
                "--seed-step {step} m is too fine for the seed region ({} by {} m): give a coarser step",
                hi[0] - lo[0],
                hi[1] - lo[1]
            ));
        }
        let mut seeds = Vec::new();
        for j in j0 as i64..=j1 as i64 {
            for i in i0 as i64..=i1 as i64 {
                seeds.extend(self.seed(tool, [i as f64 * step, j as f64 * step]));
            }
        }
        Ok(seeds)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::ToolSurface;

    /// A flat square of side 2 about the origin in z = 0.
    fn square() -> ToolSurface {
        let v = vec![
            Point::new(-1.0, -1.0, 0.0),
            Point::new(1.0, -1.0, 0.0),
            Point::new(1.0, 1.0, 0.0),
            Point::new(-1.0, 1.0, 0.0),
        ];
        ToolSurface::from_triangles(v, vec![[0, 1, 2], [0, 2, 3]]).unwrap()
    }

    #[test]
    fn a_disc_holds_the_lattice_points_within_its_radius() {
        let tool = square();
        let frame = Frame::at(&tool, &Point::new(0.0, 0.0, 0.3), &Vector::x());
        assert_eq!(frame.origin, [0.0, 0.0, 0.0]);
        assert_eq!((frame.u, frame.v), ([1.0, 0.0, 0.0], [0.0, 1.0, 0.0]));
        let r = Region::new(SeedRegion::Disc { radius: 0.5 }, frame, &tool, 0.0).unwrap();
        let seeds = r.lattice(&tool, 0.25).unwrap();
        // Points (i, j) / 4 with i^2 + j^2 <= 4: 13 of them, the centre among them.
        assert_eq!(seeds.len(), 13);
        assert!(seeds.iter().any(|s| s.ab == [0.0, 0.0]));
        assert!(seeds.iter().all(|s| s.point.z == 0.0 && s.ab[0].hypot(s.ab[1]) <= 0.5));
        assert!(r.seed(&tool, [0.4, 0.4]).is_none());
    }

    #[test]
    fn a_polygon_holds_the_lattice_points_inside_it() {
        let tool = square();
        let frame = Frame::at(&tool, &Point::new(0.0, 0.0, 0.0), &Vector::x());
        // A triangle with corners (0, 0), (0.6, 0), (0, 0.6): points with i + j <= 2 on a 0.3 lattice
        // inside or on it; those on the hypotenuse sit on the boundary, so count only the strict inside.
        let points = vec![[-0.01, -0.01, 0.0], [0.65, -0.01, 0.0], [-0.01, 0.65, 0.0]];
        let r = Region::new(SeedRegion::Polygon { points }, frame, &tool, 0.01).unwrap();
        let seeds = r.lattice(&tool, 0.3).unwrap();
        let ab: Vec<[f64; 2]> = seeds.iter().map(|s| s.ab).collect();
        assert_eq!(ab.len(), 6, "{ab:?}");
        assert!(ab.iter().all(|p| p[0] >= 0.0 && p[1] >= 0.0 && p[0] + p[1] <= 0.6 + 1e-12), "{ab:?}");
        let bad =
            Region::new(SeedRegion::Polygon { points: vec![[0.0, 0.0, 0.0], [0.5, 0.0, 0.0]] }, frame, &tool, 0.01);
        assert!(bad.err().unwrap().contains("seed polygon"));
        assert!(r.lattice(&tool, 0.0).is_err());
    }
}
