//! Zero-length springs between pairs of nodes, `E = 1/2 k |x_a - x_b|^2` [000 eqs. 28-30]: the
//! restoring stiffness of a fold, tying the rows on either side of it. Quadratic: gradient
//! `k (x_a - x_b)` on a, the opposite on b; Hessian `k [I, -I; -I, I]` (positive semidefinite, so
//! Convex = Exact).
use super::{EnergyTerm, Grid, Sink};
use crate::geometry::Point;
use std::ops::Range;

/// The springs term.
pub struct Springs {
    /// (node a, node b, stiffness N/m), sorted by the lower node's row.
    pairs: Vec<(usize, usize, f64)>,
    /// How many rows apart the two nodes of a pair are at most.
    span: usize,
}

impl Springs {
    /// Springs between the given node pairs of `grid` (each (a, b, k), stiffness k in N/m).
    pub fn new(grid: &Grid, pairs: &[(usize, usize, f64)]) -> Self {
        let mut pairs: Vec<(usize, usize, f64)> = pairs.iter().map(|&(a, b, k)| (a.min(b), a.max(b), k)).collect();
        pairs.sort_by_key(|p| (p.0, p.1));
        let span = pairs.iter().map(|p| p.1 / grid.nv - p.0 / grid.nv).max().unwrap_or(0);
        Springs { pairs, span }
    }
}

impl EnergyTerm for Springs {
    fn name(&self) -> &'static str {
        "springs"
    }

    fn row_span(&self) -> usize {
        self.span
    }

    fn add(&self, grid: &Grid, x: &[Point], base: Range<usize>, sink: &mut Sink<'_>) {
        let rows = sink.element_rows(&base, self.span, grid.nu);
        let (lo, hi) = (rows.start * grid.nv, rows.end * grid.nv);
        let first = self.pairs.partition_point(|p| p.0 < lo);
        for &(a, b, k) in self.pairs[first..].iter().take_while(|p| p.0 < hi) {
            if !(grid.active[a] && grid.active[b]) {
                continue;
            }
            let r = x[a] - x[b];
            sink.add_energy(a, 0.5 * k * r.norm_squared());
            if sink.wants_gradient() {
                sink.add_gradient(a, &(r * k));
                sink.add_gradient(b, &(-r * k));
            }
            if sink.hessian_kind().is_some() {
                sink.add_scaled_identity(a, a, k);
                sink.add_scaled_identity(b, b, k);
                sink.add_scaled_identity(a, b, -k);
            }
        }
    }
}
