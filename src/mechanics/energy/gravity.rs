//! Gravity: `E = -sum_i m_i g . x_i`, with `m_i` the node's mass ([`Grid::nodal_masses`]: a
//! quarter of each complete cell it is a corner of, times the areal mass and the cell's weight
//! factor — d^2 inside a full grid, d^2/2 on its edges, d^2/4 at its corners; nodes without a
//! complete cell carry no mass). Linear: gradient `-m_i g`, zero Hessian. The same masses are
//! the solver's loads `P = m g` ([`Gravity::loads`]).
use super::{EnergyTerm, Grid, Sink};
use crate::geometry::{Point, Vector};
use std::ops::Range;

/// The gravity term.
pub struct Gravity {
    /// Acceleration of gravity (m/s^2).
    pub g: Vector,
    /// Mass per node (kg).
    pub mass: Vec<f64>,
}

impl Gravity {
    /// Nodal masses from `grid` (see the module docs) and the areal mass (kg/m^2).
    pub fn new(grid: &Grid, areal_mass: f64, g: Vector) -> Self {
        Gravity { g, mass: grid.nodal_masses(areal_mass) }
    }

    /// The weight of every node as a load, `m_i g` (N).
    pub fn loads(&self) -> Vec<Vector> {
        self.mass.iter().map(|m| self.g * *m).collect()
    }
}

impl EnergyTerm for Gravity {
    fn name(&self) -> &'static str {
        "gravity"
    }

    fn row_span(&self) -> usize {
        0
    }

    fn add(&self, grid: &Grid, x: &[Point], base: Range<usize>, sink: &mut Sink<'_>) {
        let nv = grid.nv;
        let rows = sink.element_rows(&base, 0, grid.nu);
        let nodes = rows.start * nv..rows.end * nv;
        for (k, &m) in nodes.clone().zip(&self.mass[nodes]) {
            if m != 0.0 && grid.active[k] {
                let f = self.g * m;
                sink.add_energy(k, -f.dot(&x[k].coords));
                sink.add_gradient(k, &-f);
            }
        }
    }
}
