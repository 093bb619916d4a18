//! The generated hemisphere: the tool `drape bench` measures the engine on, and one of the test
//! shapes (`geometry::shapes`, behind the `shapes` feature).
use super::{Point, TriangleMesh, Vector};

/// Upper half (`z >= 0`) of the sphere of `radius` centred at the origin.
///
/// Built from the 4 upper faces of an octahedron, each split into `subdivisions^2` triangles
/// (a triangular lattice) and projected radially onto the sphere, so it has
/// `4 subdivisions^2` triangles and `2 subdivisions^2 + 2 subdivisions + 1` vertices. The rim
/// lies exactly on `z = 0`, the pole `(0, 0, radius)` and the four rim points on the axes are
/// vertices, and every vertex is at distance `radius` from the origin (up to rounding). Normals
/// point outward.
///
/// # Panics
/// If `radius <= 0` or `subdivisions == 0`.
pub fn hemisphere(radius: f64, subdivisions: usize) -> TriangleMesh {
    assert!(radius > 0.0, "hemisphere radius must be positive, got {radius}");
    assert!(subdivisions > 0, "hemisphere needs at least one subdivision");
    let n = subdivisions as i64;
    // Lattice points of the octahedron |x| + |y| + |z| = n, z >= 0, numbered in a fixed order:
    // by z (rim first), then around. Integer coordinates make the welding exact.
    let mut index = std::collections::HashMap::new();
    let mut vertices = Vec::new();
    for z in 0..=n {
        let r = n - z; // |x| + |y| = r on this level
        let ring: Vec<(i64, i64)> = if r == 0 {
            vec![(0, 0)]
        } else {
            // Counter-clockwise from (r, 0), 4r points.
            (0..4 * r)
                .map(|k| {
                    let (q, m) = (k / r, k % r);
                    match q {
                        0 => (r - m, m),
                        1 => (-m, r - m),
                        2 => (-(r - m), -m),
                        _ => (m, -(r - m)),
                    }
                })
                .collect()
        };
        for (x, y) in ring {
            index.insert((x, y, z), vertices.len() as u32);
            let v = Vector::new(x as f64, y as f64, z as f64);
            vertices.push(Point::from(v * (radius / v.norm())));
        }
    }
    // Faces (A, B, pole) with A -> B counter-clockwise seen from above: outward winding.
    let corners = [(1, 0), (0, 1), (-1, 0), (0, -1)];
    let mut triangles = Vec::with_capacity(4 * subdivisions * subdivisions);
    for q in 0..4 {
        let (ax, ay) = corners[q];
        let (bx, by) = corners[(q + 1) % 4];
        // Lattice point with weights (n - a - b, a, b) on (A, B, pole).
        let at = |a: i64, b: i64| -> u32 {
            let w = n - a - b;
            index[&(w * ax + a * bx, w * ay + a * by, b)]
        };
        for b in 0..n {
            for a in 0..n - b {
                triangles.push([at(a, b), at(a + 1, b), at(a, b + 1)]);
                if a + b + 2 <= n {
                    triangles.push([at(a + 1, b), at(a + 1, b + 1), at(a, b + 1)]);
                }
            }
        }
    }
    TriangleMesh { vertices, triangles }
}

/// The smallest `subdivisions` for which [`hemisphere`] has at least `min_triangles` triangles.
pub fn hemisphere_subdivisions_for(min_triangles: usize) -> usize {
    let mut s = ((min_triangles as f64 / 4.0).sqrt() as usize).max(1);
    while 4 * s * s < min_triangles {
        s += 1;
    }
    while s > 1 && 4 * (s - 1) * (s - 1) >= min_triangles {
        s -= 1;
    }
    s
}

/// [`hemisphere`] with the smallest subdivision giving at least `min_triangles` triangles.
pub fn hemisphere_with_triangles(radius: f64, min_triangles: usize) -> TriangleMesh {
    hemisphere(radius, hemisphere_subdivisions_for(min_triangles))
}
