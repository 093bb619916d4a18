//! Fibre stretching [000 eqs. 14-17]: per fibre segment between neighbours along i (warp) or j
//! (weft), Green strain `e = (|xb - xa|^2 - d^2) / (2 d^2)` and energy `d * (f d) * W(e)` (reference
//! length d times tributary width f d, f = 1 inside the fabric and 1/2 along its edges; see
//! [`Grid::warp_segment_width`]), `(W, W', W'') = tension(fibre, e)`.
//!
//! With `r = xb - xa`: `grad_b e = r / d^2 = -grad_a e`, `hess e = [I, -I; -I, I] / d^2` (PSD).
//! Exact Hessian block `K = W'' r r^T / d^2 + W' I`, placed as `[K, -K; -K, K]`;
//! Convex: `max(W'', 0) r r^T / d^2 + max(W', 0) I` (PSD).
use super::{EnergyTerm, Grid, HessianKind, Laws, Sink};
use crate::geometry::{Point, Vector};
use crate::material::Fibre;
use nalgebra::Matrix3;
use std::ops::Range;

/// The stretch term.
pub struct Stretch<'a, L: Laws + ?Sized> {
    /// The material whose tension law the term uses.
    pub material: &'a L,
}

impl<'a, L: Laws + ?Sized> Stretch<'a, L> {
    /// The term for `material`.
    pub fn new(material: &'a L) -> Self {
        Stretch { material }
    }

    #[inline]
    #[allow(clippy::too_many_arguments)]
    fn segment(&self, fibre: Fibre, d2: f64, width: f64, a: usize, b: usize, x: &[Point], sink: &mut Sink<'_>) {
        let r = x[b] - x[a];
        let e = (r.norm_squared() - d2) / (2.0 * d2);
        let (w, w1, w2) = self.material.tension(fibre, e);
        let (w, w1, w2) = (w * width, w1 * width, w2 * width);
        sink.add_energy(a.min(b), d2 * w);
        if sink.wants_gradient() {
            let g: Vector = r * w1;
            sink.add_gradient(b, &g);
            sink.add_gradient(a, &-g);
        }
        if let Some(kind) = sink.hessian_kind() {
            let (c2, c1) = match kind {
                HessianKind::Exact => (w2, w1),
                HessianKind::Convex => (w2.max(0.0), w1.max(0.0)),
            };
            let k: Matrix3<f64> = r * r.transpose() * (c2 / d2) + Matrix3::from_diagonal_element(c1);
            sink.add_block(a, a, &k);
            sink.add_block(b, b, &k);
            sink.add_block(a, b, &-k);
        }
    }
}

impl<'a, L: Laws + ?Sized> Stretch<'a, L> {
    /// The second-order force of one segment between `x` and `trial` (see
    /// [`EnergyTerm::add_second_order`]): Green strain is quadratic in the positions, so its
    /// second-order change is exactly `|dy_b - dy_a|^2 / (2 d^2)`.
    #[allow(clippy::too_many_arguments)]
    fn segment_second_order(
        &self,
        fibre: Fibre,
        d2: f64,
        width: f64,
        a: usize,
        b: usize,
        x: &[Point],
        trial: &[Point],
        out: &mut [Vector],
    ) {
        let r = x[b] - x[a];
        let e = (r.norm_squared() - d2) / (2.0 * d2);
        let (_, _, w2) = self.material.tension(fibre, e);
        let dy = (trial[b] - x[b]) - (trial[a] - x[a]);
        let de = dy.norm_squared() / (2.0 * d2);
        // d(energy d^2 w W)/dx = w W' r (grad e = r / d^2 on b): the force of the extra strain.
        let f = r * (width * w2 * de);
        out[b] += f;
        out[a] -= f;
    }
}

impl<'a, L: Laws + ?Sized> EnergyTerm for Stretch<'a, L> {
    fn add_second_order(&self, grid: &Grid, x: &[Point], trial: &[Point], out: &mut [Vector]) {
        let (nu, nv) = (grid.nu, grid.nv);
        let d2 = grid.spacing * grid.spacing;
        let act = &grid.active;
        for i in 0..nu {
            for j in 0..nv {
                let a = i * nv + j;
                if i + 1 < nu {
                    let width = grid.warp_segment_width(i, j);
                    if act[a] && act[a + nv] && width > 0.0 {
                        self.segment_second_order(Fibre::Warp, d2, width, a, a + nv, x, trial, out);
                    }
                }
                if j + 1 < nv {
                    let width = grid.weft_segment_width(i, j);
                    if act[a] && act[a + 1] && width > 0.0 {
                        self.segment_second_order(Fibre::Weft, d2, width, a, a + 1, x, trial, out);
                    }
                }
            }
        }
    }

    fn name(&self) -> &'static str {
        "stretch"
    }

    fn row_span(&self) -> usize {
        1
    }

    fn add(&self, grid: &Grid, x: &[Point], base: Range<usize>, sink: &mut Sink<'_>) {
        let (nu, nv) = (grid.nu, grid.nv);
        let d2 = grid.spacing * grid.spacing;
        let act = &grid.active;
        // Warp segments (i, j)-(i + 1, j).
        for i in sink.element_rows(&base, 1, nu) {
            for j in 0..nv {
                let a = i * nv + j;
                let b = a + nv;
                let width = grid.warp_segment_width(i, j);
                if act[a] && act[b] && width > 0.0 {
                    self.segment(Fibre::Warp, d2, width, a, b, x, sink);
                }
            }
        }
        // Weft segments (i, j)-(i, j + 1).
        for i in sink.element_rows(&base, 0, nu) {
            for j in 0..nv.saturating_sub(1) {
                let a = i * nv + j;
                let width = grid.weft_segment_width(i, j);
                if act[a] && act[a + 1] && width > 0.0 {
                    self.segment(Fibre::Weft, d2, width, a, a + 1, x, sink);
                }
            }
        }
    }
}
