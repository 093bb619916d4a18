//! Fibre bending without rotational DOFs [000 eqs. 7-12]: for every node O whose two neighbours
//! A, B along a fibre are active, the deviation of O from the chord midpoint
//! `w = xO - (xA + xB) / 2` gives the curvature `k = 2 |w| / (a b)`; with a = b = d, l = 2 d and
//! width L = f d (f = 1 inside the fabric, 1/2 along its edges; see [`Grid::warp_triple_width`]) the energy `(D_k / 2) k^2 l L = l L D_k |w|^2 / (a^2 b^2) = 2 D_k |w|^2 / d^2`,
//! D_k the flexural rigidity of that fibre family. Quadratic: the exact Hessian is constant and
//! PSD (`2 c N^T N`, `N = [-1/2, 1, -1/2]` over (A, O, B), `c = 2 D_k / d^2`), Convex = Exact.
//!
//! The same triples, each with its energy, give each cell its share of the bending energy
//! ([`Bending::cell_energies`]): a triple's width counts a quarter for each complete cell around
//! its middle node, and each of those cells takes that quarter of the triple's energy.
use super::{EnergyTerm, Grid, Laws, Sink};
use crate::geometry::{Point, Vector};
use crate::material::Fibre;
use std::ops::Range;

/// The bending term.
pub struct Bending<'a, L: Laws + ?Sized> {
    /// The material whose bending rigidities the term uses.
    pub material: &'a L,
}

/// The bow of the triple A-O-B: O's deviation from the midpoint of A and B.
#[inline]
fn bow(a: usize, o: usize, b: usize, x: &[Point]) -> Vector {
    x[o].coords - 0.5 * (x[a].coords + x[b].coords)
}

/// The energy of a triple of stiffness `c` and bow `w`: `c |w|^2`.
#[inline]
fn triple_energy(c: f64, w: &Vector) -> f64 {
    c * w.norm_squared()
}

impl<'a, L: Laws + ?Sized> Bending<'a, L> {
    /// The term for `material`.
    pub fn new(material: &'a L) -> Self {
        Bending { material }
    }

    /// Calls `f(c, a, o, b, o_ij)` for every warp triple A = (i, j), O = (i + 1, j), B = (i + 2,
    /// j) of base row i in `rows`: `c` its stiffness over its whole width (energy `c |w|^2`),
    /// `o_ij` its middle node (i + 1, j).
    #[inline]
    fn warp_triples(
        &self,
        grid: &Grid,
        rows: Range<usize>,
        mut f: impl FnMut(f64, usize, usize, usize, (usize, usize)),
    ) {
        let nv = grid.nv;
        let cw = 2.0 * self.material.bending(Fibre::Warp) / (grid.spacing * grid.spacing);
        if cw == 0.0 {
            return;
        }
        for i in rows {
            for j in 0..nv {
                let a = i * nv + j;
                let (o, b) = (a + nv, a + 2 * nv);
                let width = grid.warp_triple_width(i, j);
                if width > 0.0 && grid.warp_triple(i, j) {
                    f(cw * width * grid.node_factors(i + 1, j).bending, a, o, b, (i + 1, j));
                }
            }
        }
    }

    /// As [`Bending::warp_triples`] for the weft triples A = (i, j), O = (i, j + 1), B = (i, j +
    /// 2) of row i in `rows`.
    #[inline]
    fn weft_triples(
        &self,
        grid: &Grid,
        rows: Range<usize>,
        mut f: impl FnMut(f64, usize, usize, usize, (usize, usize)),
    ) {
        let nv = grid.nv;
        let cf = 2.0 * self.material.bending(Fibre::Weft) / (grid.spacing * grid.spacing);
        if cf == 0.0 {
            return;
        }
        for i in rows {
            for j in 0..nv.saturating_sub(2) {
                let a = i * nv + j;
                let width = grid.weft_triple_width(i, j);
                if width > 0.0 && grid.weft_triple(i, j) {
                    f(cf * width * grid.node_factors(i, j + 1).bending, a, a + 1, a + 2, (i, j + 1));
                }
            }
        }
    }

    /// Each cell's share of the bending energy at positions `x` (J), in cell order (index
    /// `i * (nv - 1) + j`), `None` for a cell that is not complete ([`Grid::cell_active`]). Every
    /// triple's energy (the one [`EnergyTerm::add`] reports) is split evenly among the complete
    /// cells around its middle node, the cells its width counts, so the shares add up to the
    /// term's energy.
    pub fn cell_energies(&self, grid: &Grid, x: &[Point]) -> Vec<Option<f64>> {
        assert_eq!(x.len(), grid.num_nodes(), "one position per node");
        let (nu, nv) = (grid.nu, grid.nv);
        let cv = nv.saturating_sub(1);
        let mut out: Vec<Option<f64>> =
            (0..nu.saturating_sub(1) * cv).map(|c| grid.cell_active(c / cv, c % cv).then_some(0.0)).collect();
        let mut share = |c: f64, a: usize, o: usize, b: usize, (i, j): (usize, usize)| {
            let e = triple_energy(c, &bow(a, o, b, x));
            // The complete cells around the middle node (i, j): those its width counts.
            let around =
                [(i.wrapping_sub(1), j.wrapping_sub(1)), (i.wrapping_sub(1), j), (i, j.wrapping_sub(1)), (i, j)];
            let on = |&(ci, cj): &(usize, usize)| ci < nu - 1 && cj < cv && grid.cell_active(ci, cj);
            let n = around.iter().filter(|c| on(c)).count() as f64;
            for (ci, cj) in around.iter().filter(|c| on(c)) {
                if let Some(v) = out[ci * cv + cj].as_mut() {
                    *v += e / n;
                }
            }
        };
        self.warp_triples(grid, 0..nu.saturating_sub(2), &mut share);
        self.weft_triples(grid, 0..nu, &mut share);
        out
    }
}

/// One triple A-O-B with stiffness `c` (energy `c |w|^2`).
#[inline]
fn triple(c: f64, a: usize, o: usize, b: usize, x: &[Point], sink: &mut Sink<'_>) {
    let w = bow(a, o, b, x);
    sink.add_energy(a.min(b), triple_energy(c, &w));
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
        let nu = grid.nu;
        // Warp lines: A = (i, j), O = (i + 1, j), B = (i + 2, j).
        let rows = sink.element_rows(&base, 2, nu);
        self.warp_triples(grid, rows, |c, a, o, b, _| triple(c, a, o, b, x, sink));
        // Weft lines: A = (i, j), O = (i, j + 1), B = (i, j + 2).
        let rows = sink.element_rows(&base, 0, nu);
        self.weft_triples(grid, rows, |c, a, o, b, _| triple(c, a, o, b, x, sink));
    }
}
