//! Colour map and the projection of a ply (and its tool) onto the picture plane.
use crate::geometry::{Point, Vector};
use crate::kinematic::DrapeNet;

/// Control points of the diverging colour map, from -1 (blue) through a light grey (0) to +1
/// (red). The centre is not pure white so that unsheared cells still stand out from the page.
const DIVERGING: [(f64, [u8; 3]); 5] = [
    (-1.0, [33, 102, 172]),
    (-0.5, [103, 169, 207]),
    (0.0, [236, 236, 236]),
    (0.5, [239, 138, 98]),
    (1.0, [178, 24, 43]),
];

/// Colour of `value` on the diverging map with symmetric limits `[-limit, limit]` (values outside
/// are clamped). This is the colour every cell with that value gets in the PNG pictures.
pub fn shear_colour(value: f64, limit: f64) -> [u8; 3] {
    let t = if limit > 0.0 { (value / limit).clamp(-1.0, 1.0) } else { 0.0 };
    let t = if t.is_finite() { t } else { 0.0 };
    for w in DIVERGING.windows(2) {
        let ((a, ca), (b, cb)) = (w[0], w[1]);
        if t <= b {
            let s = (t - a) / (b - a);
            let mix = |k: usize| (ca[k] as f64 + s * (cb[k] as f64 - ca[k] as f64)).round() as u8;
            return [mix(0), mix(1), mix(2)];
        }
    }
    DIVERGING[DIVERGING.len() - 1].1
}

/// Symmetric colour limit (degrees) for a shear map: the larger of the largest |shear| and the
/// locking angle, plus a margin so the locking lines sit inside the bar, rounded up to 5 degrees.
pub fn colour_limit(max_abs_deg: f64, locking_deg: f64) -> f64 {
    let m = max_abs_deg.max(locking_deg).max(0.0) * COLOUR_LIMIT_MARGIN;
    ((m / 5.0).ceil() * 5.0).max(5.0)
}

/// Head room above the largest value on a colour bar.
const COLOUR_LIMIT_MARGIN: f64 = 1.05;

/// Symmetric limit for a map of small differences (degrees): the largest |value| rounded up to
/// a 1-2-5 step, at least `MIN_CHANGE_LIMIT_DEG`.
pub fn change_limit(max_abs_deg: f64) -> f64 {
    nice_ceil(max_abs_deg.max(MIN_CHANGE_LIMIT_DEG))
}

/// Smallest colour limit of a change map: below this the differences are noise.
pub const MIN_CHANGE_LIMIT_DEG: f64 = 0.1;

/// Smallest 1, 2 or 5 times a power of ten that is >= x (x > 0).
pub(crate) fn nice_ceil(x: f64) -> f64 {
    let p = 10f64.powf(x.log10().floor());
    for m in [1.0, 2.0, 5.0, 10.0] {
        if m * p >= x * (1.0 - 1e-12) {
            return m * p;
        }
    }
    10.0 * p
}

/// Largest 1, 2 or 5 times a power of ten that is <= x (x > 0).
pub(crate) fn nice_floor(x: f64) -> f64 {
    let p = 10f64.powf(x.log10().floor());
    for m in [5.0, 2.0, 1.0] {
        if m * p <= x * (1.0 + 1e-12) {
            return m * p;
        }
    }
    p
}

/// Angle by which the view is tilted from the ply's mean normal, so curvature reads as depth.
pub const VIEW_TILT_DEG: f64 = 30.0;

/// An orthographic view: screen right, screen up, and towards the viewer.
#[derive(Debug, Clone, Copy)]
pub struct View {
    /// Screen right.
    pub right: Vector,
    /// Screen up.
    pub up: Vector,
    /// Towards the viewer.
    pub toward: Vector,
}

impl View {
    /// Look at `net` along its area-weighted mean normal, oriented to face world +z when the
    /// ply is not on a vertical wall (plies are laid from above by convention), then tilted by
    /// [`VIEW_TILT_DEG`] so the viewer looks from the front (-y side) and above.
    pub fn for_net(net: &DrapeNet) -> View {
        let mut n = Vector::zeros();
        for_each_cell(net, |_, c| n += (c[2] - c[0]).cross(&(c[3] - c[1])));
        let z = Vector::z();
        let mut toward = n.try_normalize(1e-300).unwrap_or(z);
        // A ply on a vertical wall keeps its own orientation; otherwise face upwards.
        if toward.dot(&z) < -VERTICAL_WALL_COS {
            toward = -toward;
        }
        let reference = if toward.cross(&z).norm() > 0.1 { z } else { Vector::y() };
        let right = reference.cross(&toward).try_normalize(0.0).unwrap_or(Vector::x());
        let up = toward.cross(&right);
        let t = VIEW_TILT_DEG.to_radians();
        // Rotate about `right`: the viewer moves towards -up (the front) and keeps looking at it.
        let up2 = t.cos() * up + t.sin() * toward;
        let toward2 = -t.sin() * up + t.cos() * toward;
        View { right, up: up2, toward: toward2 }
    }

    /// Screen coordinates (right, up) and depth (larger = nearer the viewer) of `p`.
    pub fn project(&self, p: &Point) -> (f64, f64, f64) {
        (p.coords.dot(&self.right), p.coords.dot(&self.up), p.coords.dot(&self.toward))
    }
}

/// |cos| of the angle to world z below which a ply counts as on a vertical wall.
const VERTICAL_WALL_COS: f64 = 0.1;

/// Call `f(cell_index, corners)` for every complete cell, with cell index `i * (nv - 1) + j` and
/// corners in ring order [(i,j), (i+1,j), (i+1,j+1), (i,j+1)].
pub fn for_each_cell(net: &DrapeNet, mut f: impl FnMut(usize, [Point; 4])) {
    for i in 0..net.nu.saturating_sub(1) {
        for j in 0..net.nv.saturating_sub(1) {
            if let Some([p00, p10, p01, p11]) = net.cell_corners(i, j) {
                f(i * (net.nv - 1) + j, [p00, p10, p11, p01]);
            }
        }
    }
}

/// Maps screen coordinates (metres) into a pixel rectangle with one scale on both axes.
#[derive(Debug, Clone, Copy)]
pub struct Fit {
    /// Pixels per metre.
    pub scale: f64,
    cx: f64,
    cy: f64,
    px: f64,
    py: f64,
}

impl Fit {
    /// Fit the box `[x0, x1] x [y0, y1]` (metres) into the pixel rectangle with top-left
    /// `(left, top)` and size `w x h`, centred, keeping the aspect ratio.
    pub fn new(bounds: [f64; 4], left: f64, top: f64, w: f64, h: f64) -> Fit {
        let [x0, x1, y0, y1] = bounds;
        let (bw, bh) = ((x1 - x0).max(1e-12), (y1 - y0).max(1e-12));
        let scale = (w / bw).min(h / bh);
        Fit { scale, cx: 0.5 * (x0 + x1), cy: 0.5 * (y0 + y1), px: left + 0.5 * w, py: top + 0.5 * h }
    }

    /// Pixel position (screen y grows downwards) of screen coordinates (x, y).
    pub fn pixel(&self, x: f64, y: f64) -> (f64, f64) {
        (self.px + (x - self.cx) * self.scale, self.py - (y - self.cy) * self.scale)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn colours_are_symmetric_and_clamped() {
        assert_eq!(shear_colour(0.0, 10.0), [236, 236, 236]);
        assert_eq!(shear_colour(10.0, 10.0), [178, 24, 43]);
        assert_eq!(shear_colour(50.0, 10.0), [178, 24, 43]);
        assert_eq!(shear_colour(-10.0, 10.0), [33, 102, 172]);
        assert_eq!(shear_colour(f64::NAN, 10.0), [236, 236, 236]);
        assert_ne!(shear_colour(2.0, 10.0), shear_colour(-2.0, 10.0));
    }

    #[test]
    fn limits() {
        assert_eq!(colour_limit(30.0, 45.0), 50.0);
        assert_eq!(colour_limit(61.0, 45.0), 65.0);
        assert_eq!(colour_limit(0.0, 0.0), 5.0);
        assert_eq!(change_limit(0.3), 0.5);
        assert_eq!(change_limit(0.0), 0.1);
        assert_eq!(nice_floor(0.37), 0.2);
        assert_eq!(nice_ceil(3.0), 5.0);
    }

    #[test]
    fn view_of_a_flat_ply_faces_up_whatever_its_winding() {
        let mut net = DrapeNet::new("f", 1.0, 2, 2, (0, 0));
        // Weft along -y: warp x weft points down.
        for (k, p) in [(0.0, 0.0), (0.0, -1.0), (1.0, 0.0), (1.0, -1.0)].iter().enumerate() {
            net.positions[k] = Point::new(p.0, p.1, 0.0);
            net.status[k] = crate::kinematic::NodeStatus::Placed;
        }
        let v = View::for_net(&net);
        assert!(v.toward.z > 0.8, "{v:?}");
        assert!((v.right.cross(&v.up) - v.toward).norm() < 1e-12);
    }
}
