//! Fibre bending without rotational DOFs [000 eqs. 7-12]: for every node O whose two neighbours
//! A, B along a fibre are active, the deviation of O from the chord midpoint
//! `w = xO - (xA + xB) / 2` gives the curvature `k = 2 |w| / (a b)`; with a = b = d, l = 2 d and
//! width L = f d (f = 1 inside the fabric, 1/2 along its edges; see [`Grid::warp_triple_width`]) the energy `(D_k / 2) k^2 l L = l L D_k |w|^2 / (a^2 b^2) = 2 D_k |w|^2 / d^2`,
//! D_k the flexural rigidity of that fibre family. Quadratic: the exact Hessian is constant and
//! PSD (`2 c N^T N`, `N = [-1/2, 1, -1/2]` over (A, O, B), `c = 2 D_k / d^2`), Convex = Exact.
use super::{EnergyTerm, Grid, Laws, Sink};
use crate::geometry::Point;
use crate::material::Fibre;
use std::ops::Range;

/// The bending term.
pub struct Bending<'a, L: Laws + ?Sized> {
    /// The material whose bending rigidities the term uses.
    pub material: &'a L,
}

impl<'a, L: Laws + ?Sized> Bending<'a, L> {
    /// The term for `material`.
    pub fn new(material: &'a L) -> Self {
        Bending { material }
    }
}

/// One triple A-O-B with stiffness `c` (energy `c |w|^2`).
#[inline]
fn triple(c: f64, a: usize, o: usize, b: usize, x: &[Point], sink: &mut Sink<'_>) {
    let w = x[o].coords - 0.5 * (x[a].coords + x[b].coords);
    sink.add_energy(a.min(b), c * w.norm_squared());
    if sink.wants_gradient() {
        sink.add_gradient(o, &(w * (2.0 * c)));
        let g = w * (-c);
        sink.add_gradient(a, &g);
        sink.add_gradient(b, &g);
    }
    if sink.hessian_kind().is_some() {
        sink.add_scaled_identity(o, o, 2.0 * c);
        sink.add_scaled_identity(a, a, 0.5 * c);
        sink.add_scaled_identity(b, b, 0.5 * c);
        sink.add_scaled_identity(a, o, -c);
        sink.add_scaled_identity(o, b, -c);
        sink.add_scaled_identity(a, b, 0.5 * c);
    }
}

impl<'a, L: Laws + ?Sized> EnergyTerm for Bending<'a, L> {
    fn name(&self) -> &'static str {
        "bending"
    }

    fn row_span(&self) -> usize {
        2
    }

    fn add(&self, grid: &Grid, x: &[Point], base: Range<usize>, sink: &mut Sink<'_>) {
        let (nu, nv) = (grid.nu, grid.nv);
        let d2 = grid.spacing * grid.spacing;
        // Warp lines: A = (i, j), O = (i + 1, j), B = (i + 2, j).
        let cw = 2.0 * self.material.bending(Fibre::Warp) / d2;
        if cw != 0.0 {
            for i in sink.element_rows(&base, 2, nu) {
                for j in 0..nv {
                    let a = i * nv + j;
                    let (o, b) = (a + nv, a + 2 * nv);
                    let width = grid.warp_triple_width(i, j);
                    if width > 0.0 && grid.warp_triple(i, j) {
                        triple(cw * width * grid.node_factors(i + 1, j).bending, a, o, b, x, sink);
                    }
                }
            }
        }
        // Weft lines: A = (i, j), O = (i, j + 1), B = (i, j + 2).
        let cf = 2.0 * self.material.bending(Fibre::Weft) / d2;
        if cf != 0.0 {
            for i in sink.element_rows(&base, 0, nu) {
                for j in 0..nv.saturating_sub(2) {
                    let a = i * nv + j;
                    let width = grid.weft_triple_width(i, j);
                    if width > 0.0 && grid.weft_triple(i, j) {
                        triple(cf * width * grid.node_factors(i, j + 1).bending, a, a + 1, a + 2, x, sink);
                    }
                }
            }
        }
    }
}
