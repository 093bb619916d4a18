//! A small depth-buffered software rasteriser for the report's shaded pictures: triangles whose
//! colour is computed per pixel by a closure (so lighting and hatching are per pixel), thick
//! lines and discs with a depth test. Rendered at [`SUPERSAMPLE`] times the picture's size and
//! box-filtered down, so edges are smooth. Everything is sequential and deterministic.

/// Samples per pixel along each axis.
pub const SUPERSAMPLE: usize = 2;

/// An RGB image with a depth buffer, at the supersampled size. Larger depth is nearer.
pub struct Canvas {
    /// Width in samples.
    pub w: usize,
    /// Height in samples.
    pub h: usize,
    rgb: Vec<[u8; 3]>,
    depth: Vec<f64>,
}

/// A vertex on the canvas: sample coordinates (x right, y down) and depth (larger = nearer).
pub type ScreenPoint = (f64, f64, f64);

impl Canvas {
    /// A canvas of `w x h` samples filled with `background`.
    pub fn new(w: usize, h: usize, background: [u8; 3]) -> Canvas {
        Canvas { w, h, rgb: vec![background; w * h], depth: vec![f64::NEG_INFINITY; w * h] }
    }

    /// Fill triangle `p` (depth-tested, nearer wins). `shade(w, x, y)` gets the barycentric weights
    /// of the sample and its position and returns its colour.
    pub fn triangle(&mut self, p: [ScreenPoint; 3], mut shade: impl FnMut([f64; 3], f64, f64) -> [u8; 3]) {
        let area = (p[1].0 - p[0].0) * (p[2].1 - p[0].1) - (p[2].0 - p[0].0) * (p[1].1 - p[0].1);
        if !(area.abs() > 1e-12) {
            return;
        }
        let x0 = p.iter().map(|q| q.0).fold(f64::INFINITY, f64::min).floor().max(0.0) as usize;
        let x1 = p.iter().map(|q| q.0).fold(f64::NEG_INFINITY, f64::max).ceil().min(self.w as f64).max(0.0) as usize;
        let y0 = p.iter().map(|q| q.1).fold(f64::INFINITY, f64::min).floor().max(0.0) as usize;
        let y1 = p.iter().map(|q| q.1).fold(f64::NEG_INFINITY, f64::max).ceil().min(self.h as f64).max(0.0) as usize;
        for iy in y0..y1 {
            let y = iy as f64 + 0.5;
            for ix in x0..x1 {
                let x = ix as f64 + 0.5;
                let w1 = ((x - p[0].0) * (p[2].1 - p[0].1) - (p[2].0 - p[0].0) * (y - p[0].1)) / area;
                let w2 = ((p[1].0 - p[0].0) * (y - p[0].1) - (x - p[0].0) * (p[1].1 - p[0].1)) / area;
                let w0 = 1.0 - w1 - w2;
                if w0 < 0.0 || w1 < 0.0 || w2 < 0.0 {
                    continue;
                }
                let z = w0 * p[0].2 + w1 * p[1].2 + w2 * p[2].2;
                let k = iy * self.w + ix;
                if z > self.depth[k] {
                    self.depth[k] = z;
                    self.rgb[k] = shade([w0, w1, w2], x, y);
                }
            }
        }
    }

    /// A disc of radius `r` samples at `c`, drawn where it is not behind what is there by more
    /// than `bias` (depth units); it does not write depth (lines stay on their surface).
    pub fn disc(&mut self, c: ScreenPoint, r: f64, bias: f64, colour: [u8; 3]) {
        let (x0, x1) = ((c.0 - r).floor().max(0.0) as usize, (c.0 + r).ceil().min(self.w as f64).max(0.0) as usize);
        let (y0, y1) = ((c.1 - r).floor().max(0.0) as usize, (c.1 + r).ceil().min(self.h as f64).max(0.0) as usize);
        for iy in y0..y1 {
            for ix in x0..x1 {
                let (dx, dy) = (ix as f64 + 0.5 - c.0, iy as f64 + 0.5 - c.1);
                let k = iy * self.w + ix;
                if dx * dx + dy * dy <= r * r && c.2 + bias >= self.depth[k] {
                    self.rgb[k] = colour;
                }
            }
        }
    }

    /// A line of width `2 r` samples from `a` to `b`, depth-tested as [`Canvas::disc`].
    pub fn line(&mut self, a: ScreenPoint, b: ScreenPoint, r: f64, bias: f64, colour: [u8; 3]) {
        let len = (b.0 - a.0).hypot(b.1 - a.1);
        let steps = (len / (0.5 * r.max(0.5))).ceil().max(1.0) as usize;
        for s in 0..=steps {
            let t = s as f64 / steps as f64;
            let p = (a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1), a.2 + t * (b.2 - a.2));
            self.disc(p, r, bias, colour);
        }
    }

    /// Depth at sample (x, y) (negative infinity where nothing is drawn or outside).
    pub fn depth_at(&self, x: f64, y: f64) -> f64 {
        if x >= 0.0 && y >= 0.0 && (x as usize) < self.w && (y as usize) < self.h {
            self.depth[y as usize * self.w + x as usize]
        } else {
            f64::NEG_INFINITY
        }
    }

    /// Box-filter down by [`SUPERSAMPLE`] into `out` (RGB bytes of an image `stride` pixels wide)
    /// with the top-left corner at pixel (`left`, `top`).
    pub fn resolve_into(&self, out: &mut [u8], stride: usize, left: usize, top: usize) {
        let s = SUPERSAMPLE;
        let n = (s * s) as u32;
        for py in 0..self.h / s {
            for px in 0..self.w / s {
                let mut sum = [0u32; 3];
                for dy in 0..s {
                    for dx in 0..s {
                        let c = self.rgb[(py * s + dy) * self.w + px * s + dx];
                        for k in 0..3 {
                            sum[k] += c[k] as u32;
                        }
                    }
                }
                let o = ((top + py) * stride + left + px) * 3;
                if o + 3 <= out.len() {
                    for k in 0..3 {
                        out[o + k] = ((sum[k] + n / 2) / n) as u8;
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nearer_triangle_wins_and_lines_respect_depth() {
        let mut c = Canvas::new(20, 20, [255; 3]);
        c.triangle([(0.0, 0.0, 1.0), (20.0, 0.0, 1.0), (0.0, 20.0, 1.0)], |_, _, _| [10, 10, 10]);
        c.triangle([(0.0, 0.0, 0.0), (20.0, 0.0, 0.0), (0.0, 20.0, 0.0)], |_, _, _| [200, 0, 0]);
        assert_eq!(c.rgb[2 * 20 + 2], [10, 10, 10], "the far triangle is hidden");
        assert_eq!(c.rgb[18 * 20 + 18], [255; 3]);
        // A line behind the surface is hidden, one on it is drawn.
        c.line((1.0, 5.0, 0.0), (8.0, 5.0, 0.0), 1.0, 0.01, [0, 0, 255]);
        assert_eq!(c.rgb[5 * 20 + 4], [10, 10, 10]);
        c.line((1.0, 5.0, 1.0), (8.0, 5.0, 1.0), 1.0, 0.01, [0, 0, 255]);
        assert_eq!(c.rgb[5 * 20 + 4], [0, 0, 255]);
        let mut out = vec![0u8; 10 * 10 * 3];
        c.resolve_into(&mut out, 10, 0, 0);
        assert_eq!(&out[(9 * 10 + 9) * 3..], &[255, 255, 255]);
    }
}
