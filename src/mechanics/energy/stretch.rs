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

/// Calls `f(fibre, weight, a, b)` for every fibre link of the grid: warp links (i, j)-(i+1, j)
/// with i in `warp_rows`, weft links (i, j)-(i, j+1) with i in `weft_rows`, whose `weight` is
/// the link's tributary width times its tension factor (links with no width are skipped).
fn for_each_link(
    grid: &Grid,
    warp_rows: Range<usize>,
    weft_rows: Range<usize>,
    mut f: impl FnMut(Fibre, f64, usize, usize),
) {
    let nv = grid.nv;
    for i in warp_rows {
        for j in 0..nv {
            let width = grid.warp_segment_width(i, j);
            if width > 0.0 && grid.warp_link(i, j) {
                let a = i * nv + j;
                f(Fibre::Warp, width * grid.warp_link_factors(i, j).tension, a, a + nv);
            }
        }
    }
    for i in weft_rows {
        for j in 0..nv.saturating_sub(1) {
            let width = grid.weft_segment_width(i, j);
            if width > 0.0 && grid.weft_link(i, j) {
                let a = i * nv + j;
                f(Fibre::Weft, width * grid.weft_link_factors(i, j).tension, a, a + 1);
            }
        }
    }
}

impl<'a, L: Laws + ?Sized> EnergyTerm for Stretch<'a, L> {
    fn add_second_order(&self, grid: &Grid, x: &[Point], trial: &[Point], out: &mut [Vector]) {
        let d2 = grid.spacing * grid.spacing;
        for_each_link(grid, 0..grid.nu.saturating_sub(1), 0..grid.nu, |fibre, weight, a, b| {
            self.segment_second_order(fibre, d2, weight, a, b, x, trial, out)
        });
    }

    fn name(&self) -> &'static str {
        "stretch"
    }

    fn row_span(&self) -> usize {
        1
    }

    fn add(&self, grid: &Grid, x: &[Point], base: Range<usize>, sink: &mut Sink<'_>) {
        let d2 = grid.spacing * grid.spacing;
        let warp_rows = sink.element_rows(&base, 1, grid.nu);
        let weft_rows = sink.element_rows(&base, 0, grid.nu);
        for_each_link(grid, warp_rows, weft_rows, |fibre, weight, a, b| self.segment(fibre, d2, weight, a, b, x, sink));
    }
}
