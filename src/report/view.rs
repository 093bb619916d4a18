//! Colour map, orthographic views and the fit of a view into a pixel rectangle.
use crate::geometry::{Point, Vector};

/// Control points of the diverging colour map (ColorBrewer's RdYlBu), from -1 (blue) through a
/// pale yellow (0) to +1 (red). The centre is a colour, not a grey, so that an unsheared ply
/// stands out from the grey tool and the white page.
pub(crate) const DIVERGING: [(f64, [u8; 3]); 5] = [
    (-1.0, [49, 54, 149]),
    (-0.5, [116, 173, 209]),
    (0.0, [255, 250, 180]),
    (0.5, [244, 109, 67]),
    (1.0, [165, 0, 38]),
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
    /// An orthographic view looking along `-toward` (towards the viewer is `toward`), with world
    /// +z up on the screen (world +y when looking straight down or up).
    pub fn looking(toward: Vector) -> View {
        let toward = toward.try_normalize(1e-300).unwrap_or(Vector::z());
        let reference = if toward.cross(&Vector::z()).norm() > 0.1 { Vector::z() } else { Vector::y() };
        let right = reference.cross(&toward).try_normalize(0.0).unwrap_or(Vector::x());
        View { right, up: toward.cross(&right), toward }
    }

    /// Screen coordinates (right, up) and depth (larger = nearer the viewer) of `p`.
    pub fn project(&self, p: &Point) -> (f64, f64, f64) {
        (p.coords.dot(&self.right), p.coords.dot(&self.up), p.coords.dot(&self.toward))
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
        assert_eq!(shear_colour(0.0, 10.0), [255, 250, 180]);
        assert_eq!(shear_colour(10.0, 10.0), [165, 0, 38]);
        assert_eq!(shear_colour(50.0, 10.0), [165, 0, 38]);
        assert_eq!(shear_colour(-10.0, 10.0), [49, 54, 149]);
        assert_eq!(shear_colour(f64::NAN, 10.0), [255, 250, 180]);
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
}
