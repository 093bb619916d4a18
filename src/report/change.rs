//! The noise floor of a kinematic-to-mechanical change map: how large a change of shear the
//! refinement produces without the mechanics having changed anything, so that the map's colour
//! scale starts above it and a ply whose whole change lies below it says so instead of drawing
//! noise as a pattern.
//!
//! Two sources, the larger wins (and never less than [`MIN_CHANGE_FLOOR_DEG`]):
//! - the facets: the solver slides pressed nodes on a smooth surface through the tool's facets,
//!   which lies up to a facet's sagitta s off them, so cells of size d turn by up to about s / d
//!   (radians) with no change in the mechanics. s is the median over the tool's curved edges
//!   (dihedral angle theta between 0 and [`SHARP_EDGE_DEG`]) of rho^2 kappa / 2: the sagitta of
//!   a cap of curvature kappa = theta / (distance between the two facets' centres) over a
//!   facet's circumcircle (radius rho, the two facets' mean). On a tessellated sphere this is
//!   the facets' true sagitta to within 30 %.
//! - the scatter: [`NOISE_SIGMAS`] times the cell-to-cell scatter of the change (a robust standard
//!   deviation of each cell's change less the mean of its neighbours): what varies from one
//!   cell to the next is the solver's tolerance and the tool's facets, not the fabric.
use crate::geometry::Point;
use std::collections::HashMap;

/// Edges whose facets meet at more than this (degrees) are creases the smooth surface keeps.
pub const SHARP_EDGE_DEG: f64 = 30.0;
/// The scatter part of the floor, in robust standard deviations.
pub const NOISE_SIGMAS: f64 = 3.0;
/// The floor is never below this (degrees).
pub const MIN_CHANGE_FLOOR_DEG: f64 = 0.01;
/// A cell's scatter is measured against at least this many complete neighbours.
const MIN_NEIGHBOURS: usize = 3;
/// Median absolute deviation to standard deviation for a normal distribution.
const MAD_TO_SIGMA: f64 = 1.4826;

/// The noise floor of one ply's change map and what it is made of (degrees).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ChangeNoise {
    /// Changes of at most this are noise.
    pub floor_deg: f64,
    /// The facets' part, when the tool was read.
    pub facets_deg: Option<f64>,
    /// The cell-to-cell scatter's part.
    pub scatter_deg: f64,
}

/// The median sagitta of the curved edges of a triangle mesh (in the mesh's units; see the
/// module documentation), `None` when no edge is curved (a flat or creased tool).
pub fn facet_sagitta(vertices: &[Point], triangles: &[[u32; 3]]) -> Option<f64> {
    let corners = |t: &[u32; 3]| t.map(|v| vertices[v as usize]);
    let normal = |t: &[u32; 3]| {
        let [a, b, c] = corners(t);
        (b - a).cross(&(c - a)).try_normalize(0.0)
    };
    let centroid = |t: &[u32; 3]| {
        let [a, b, c] = corners(t);
        Point::from((a.coords + b.coords + c.coords) / 3.0)
    };
    let circumradius = |t: &[u32; 3]| {
        let [a, b, c] = corners(t);
        let twice_area = (b - a).cross(&(c - a)).norm();
        (b - a).norm() * (c - b).norm() * (a - c).norm() / (2.0 * twice_area)
    };
    let mut edges: HashMap<(u32, u32), Vec<usize>> = HashMap::new();
    for (k, t) in triangles.iter().enumerate() {
        for e in 0..3 {
            let (a, b) = (t[e], t[(e + 1) % 3]);
            edges.entry((a.min(b), a.max(b))).or_default().push(k);
        }
    }
    let sharp = SHARP_EDGE_DEG.to_radians();
    let mut sagittas: Vec<f64> = edges
        .values()
        .filter(|faces| faces.len() == 2)
        .filter_map(|faces| {
            let (t1, t2) = (&triangles[faces[0]], &triangles[faces[1]]);
            let (n1, n2) = (normal(t1)?, normal(t2)?);
            let theta = n1.cross(&n2).norm().atan2(n1.dot(&n2).abs());
            // Curvature theta / (distance between the facets' centres), over the facets'
            // circumcircles: the sagitta rho^2 kappa / 2 of a cap of that curvature.
            let kappa = theta / (centroid(t1) - centroid(t2)).norm();
            let rho = 0.5 * (circumradius(t1) + circumradius(t2));
            let s = 0.5 * rho * rho * kappa;
            (theta > 0.0 && theta < sharp && s.is_finite()).then_some(s)
        })
        .collect();
    if sagittas.is_empty() {
        return None;
    }
    sagittas.sort_by(f64::total_cmp);
    Some(sagittas[sagittas.len() / 2])
}

/// The noise floor of a change map: `values` per cell (index `i * (nv - 1) + j`, degrees),
/// `spacing` of the net (m), `sagitta` of the tool's facets (m) when known.
pub fn change_noise(values: &[Option<f64>], nu: usize, nv: usize, spacing: f64, sagitta: Option<f64>) -> ChangeNoise {
    let facets_deg =
        sagitta.filter(|s| s.is_finite() && *s >= 0.0 && spacing > 0.0).map(|s| (s / spacing).to_degrees());
    let (cu, cv) = (nu.saturating_sub(1), nv.saturating_sub(1));
    let at = |i: isize, j: isize| -> Option<f64> {
        (i >= 0 && j >= 0 && (i as usize) < cu && (j as usize) < cv).then(|| values[i as usize * cv + j as usize])?
    };
    let mut residuals = Vec::new();
    for i in 0..cu as isize {
        for j in 0..cv as isize {
            let Some(v) = at(i, j) else { continue };
            let around: Vec<f64> = [(-1, -1), (-1, 0), (-1, 1), (0, -1), (0, 1), (1, -1), (1, 0), (1, 1)]
                .iter()
                .filter_map(|(di, dj)| at(i + di, j + dj))
                .collect();
            if around.len() >= MIN_NEIGHBOURS {
                let mean = around.iter().sum::<f64>() / around.len() as f64;
                // The neighbours' mean carries noise of its own: scale back to one cell's.
                residuals.push((v - mean).abs() / (1.0 + 1.0 / around.len() as f64).sqrt());
            }
        }
    }
    let scatter_deg = if residuals.is_empty() {
        0.0
    } else {
        residuals.sort_by(f64::total_cmp);
        NOISE_SIGMAS * MAD_TO_SIGMA * residuals[residuals.len() / 2]
    };
    let floor_deg = facets_deg.unwrap_or(0.0).max(scatter_deg).max(MIN_CHANGE_FLOOR_DEG);
    ChangeNoise { floor_deg, facets_deg, scatter_deg }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_smooth_change_has_no_scatter_and_noise_is_measured() {
        let (nu, nv) = (21, 21);
        let smooth: Vec<Option<f64>> = (0..400).map(|k| Some(0.1 * (k / 20) as f64 - 0.05 * (k % 20) as f64)).collect();
        let n = change_noise(&smooth, nu, nv, 0.004, None);
        assert!(n.scatter_deg < 1e-12 && n.floor_deg == MIN_CHANGE_FLOOR_DEG, "{n:?}");
        // A checkerboard of +-0.05: scatter of about 3 x 0.05 x (8/9 ... ) well above the floor.
        let noisy: Vec<Option<f64>> =
            (0..400).map(|k| Some(if (k / 20 + k % 20) % 2 == 0 { 0.05 } else { -0.05 })).collect();
        let n = change_noise(&noisy, nu, nv, 0.004, None);
        assert!(n.scatter_deg > 0.1 && n.scatter_deg < 0.3, "{n:?}");
    }

    #[test]
    fn facets_of_a_sphere_have_its_sagitta() {
        // The typical facet of a tessellated unit hemisphere lies its sagitta inside the sphere
        // (1 less the distance of its plane from the centre); the estimate from the facets'
        // turning is within 30 % of the median.
        for n in [8, 24] {
            let mesh = crate::geometry::shapes::hemisphere(1.0, n);
            let mut true_sagitta: Vec<f64> = mesh
                .triangles
                .iter()
                .map(|t| {
                    let [a, b, c] = t.map(|v| mesh.vertices[v as usize]);
                    let normal = (b - a).cross(&(c - a)).normalize();
                    1.0 - normal.dot(&a.coords).abs()
                })
                .collect();
            true_sagitta.sort_by(f64::total_cmp);
            let median = true_sagitta[true_sagitta.len() / 2];
            let s = facet_sagitta(&mesh.vertices, &mesh.triangles).unwrap();
            assert!((s / median - 1.0).abs() < 0.3, "n = {n}: {s} vs {median}");
        }
        // A flat plate has none.
        let plate = crate::geometry::shapes::plate(1.0, 1.0, 4, 4);
        assert_eq!(facet_sagitta(&plate.vertices, &plate.triangles), None);
    }
}
