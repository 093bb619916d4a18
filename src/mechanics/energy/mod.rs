//! Energy terms on the grid, with analytic gradients and sparse Hessians.
//!
//! The unknowns are the node positions `x` of the warp/weft grid (node (i, j) at `i * nv + j`,
//! i along the warp). The reference (unstressed) state is the flat square grid of spacing d:
//! fibre segments of length d, warp and weft at 90 degrees, straight fibres. The terms:
//! - [`Stretch`]: per fibre segment, Green strain `e = (|xb - xa|^2 - d^2) / (2 d^2)`, energy
//!   `d^2 W(e)` with `W` the tension law of its fibre family [000 eqs. 14-17];
//! - [`Shear`]: per cell, at each corner the shear angle `gamma = pi/2 - angle(warp, weft)` with
//!   edges along +i and +j (as [`crate::kinematic::net::corner_shear`]), energy `d^2/4 W(gamma)`;
//! - [`Bending`]: per node O with both neighbours A, B along a fibre, `w = xO - (xA + xB)/2`,
//!   energy `2 D_k |w|^2 / d^2` [000 eqs. 7-12] (no rotational DOFs);
//! - [`Gravity`]: `-sum_i m_i g . x_i`, `m_i` the areal mass times the node's area (a quarter of
//!   each complete cell around it).
//!
//! Elements (segments, cells, bending triples) count only when all their nodes are active.
//!
//! **Determinism.** [`Model::evaluate`] splits the grid into strips of whole node rows whose
//! height depends only on the grid (never on the thread count); strips run in parallel. Each
//! strip writes the gradient of its own nodes and the Hessian columns of its own nodes (a
//! contiguous slice of the CSC values), visiting every element that touches it (elements that
//! straddle two strips are computed by both; each keeps only its part). Elements are visited by
//! groups of two base rows (an element's base row is its lowest node row) aligned on the whole
//! grid, every term per group, so each node receives its contributions in one global order:
//! gradients and Hessians are bit-identical for any thread count and any strip height. An
//! element's energy goes to the strip of its lowest node; the strips' partial sums are added in
//! strip order, so energies are bit-identical for any thread count too.
use crate::geometry::{Point, Vector};
use crate::kinematic::net::{DrapeNet, NodeStatus};
use crate::material::{Fibre, MaterialCard};
use crate::mechanics::sheet::{Factors, SheetError, SheetFeatures, SheetLayout};
use crate::mechanics::sparse::{SymmetricMatrix, SymmetricPattern};
use nalgebra::Matrix3;
use rayon::prelude::*;
use std::ops::Range;
use std::sync::Arc;

mod bending;
mod gravity;
mod shear;
mod springs;
mod stretch;

pub use bending::Bending;
pub use gravity::Gravity;
pub use shear::{atan2_right, Shear};
pub use springs::Springs;
pub use stretch::Stretch;

/// The constitutive laws the energy needs (implemented by [`MaterialCard`]; tests use their
/// own analytic laws).
pub trait Laws: Sync {
    /// Stretch energy per unit reference length and width at Green strain `e`: (W, W', W'').
    fn tension(&self, fibre: Fibre, e: f64) -> (f64, f64, f64);
    /// Shear energy per unit area at shear angle `g` (rad): (W, M = W', M').
    fn shear(&self, g: f64) -> (f64, f64, f64);
    /// Flexural rigidity per unit width D_k (N m).
    fn bending(&self, fibre: Fibre) -> f64;
    /// Mass per unit area (kg/m^2).
    fn areal_mass(&self) -> f64;
}

impl Laws for MaterialCard {
    fn tension(&self, fibre: Fibre, e: f64) -> (f64, f64, f64) {
        MaterialCard::tension(self, fibre, e)
    }
    fn shear(&self, g: f64) -> (f64, f64, f64) {
        MaterialCard::shear(self, g)
    }
    fn bending(&self, fibre: Fibre) -> f64 {
        MaterialCard::bending(self, fibre)
    }
    fn areal_mass(&self) -> f64 {
        self.areal_mass
    }
}

/// Which Hessian to assemble.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HessianKind {
    /// The true second derivative (may be indefinite).
    Exact,
    /// A positive semidefinite approximation: Gauss-Newton-like, keeping only the curvature
    /// terms with non-negative coefficients (see each term).
    Convex,
}

/// The grid the energy lives on: its size, fibre spacing and which nodes are active.
#[derive(Debug, Clone)]
pub struct Grid {
    /// Nodes along the warp (i).
    pub nu: usize,
    /// Nodes along the weft (j).
    pub nv: usize,
    /// Reference fibre segment length d (m).
    pub spacing: f64,
    /// Per node (`i * nv + j`): does it take part (placed)?
    pub active: Vec<bool>,
    /// The sheet's features (cuts, seams, folds, reinforcements), if any.
    pub sheet: Option<Arc<SheetLayout>>,
}

impl Grid {
    /// A grid with every node active.
    pub fn full(nu: usize, nv: usize, spacing: f64) -> Self {
        Self::with_active(nu, nv, spacing, vec![true; nu * nv])
    }
    /// A grid with the given active flags.
    pub fn with_active(nu: usize, nv: usize, spacing: f64, active: Vec<bool>) -> Self {
        assert!(nu >= 1 && nv >= 1, "empty grid");
        assert_eq!(active.len(), nu * nv, "one active flag per node");
        assert!(spacing > 0.0 && spacing.is_finite(), "spacing must be positive");
        Grid { nu, nv, spacing, active, sheet: None }
    }
    /// This grid with the sheet's features laid out on it.
    pub fn with_sheet(mut self, sheet: SheetLayout) -> Self {
        assert_eq!(sheet.size(), (self.nu, self.nv), "the sheet layout is for another grid");
        self.sheet = Some(Arc::new(sheet));
        self
    }
    /// The grid of a drape net: the placed nodes are active.
    pub fn from_net(net: &DrapeNet) -> Self {
        let active = net.status.iter().map(|s| *s == NodeStatus::Placed).collect();
        Self::with_active(net.nu, net.nv, net.spacing, active)
    }
    #[inline]
    /// Nodes of the grid, `nu * nv`.
    pub fn num_nodes(&self) -> usize {
        self.nu * self.nv
    }
    #[inline]
    /// Linear index of node (i, j): `i * nv + j`.
    pub fn index(&self, i: usize, j: usize) -> usize {
        i * self.nv + j
    }
    /// Is cell (i, j) complete (all four corners active, not cut open)?
    #[inline]
    pub fn cell_active(&self, i: usize, j: usize) -> bool {
        let k = self.index(i, j);
        let nv = self.nv;
        self.active[k]
            && self.active[k + 1]
            && self.active[k + nv]
            && self.active[k + nv + 1]
            && !self.sheet.as_ref().is_some_and(|s| s.cell_cut(i, j))
    }
    /// Is the warp link (i, j)-(i+1, j) there (both nodes active, not cut)?
    #[inline]
    pub fn warp_link(&self, i: usize, j: usize) -> bool {
        let k = self.index(i, j);
        self.active[k] && self.active[k + self.nv] && !self.sheet.as_ref().is_some_and(|s| s.warp_cut(i, j))
    }
    /// Is the weft link (i, j)-(i, j+1) there?
    #[inline]
    pub fn weft_link(&self, i: usize, j: usize) -> bool {
        let k = self.index(i, j);
        self.active[k] && self.active[k + 1] && !self.sheet.as_ref().is_some_and(|s| s.weft_cut(i, j))
    }
    /// Is the warp bending triple (i, j), (i+1, j), (i+2, j) there (both links, no hinge)?
    #[inline]
    pub fn warp_triple(&self, i: usize, j: usize) -> bool {
        self.warp_link(i, j) && self.warp_link(i + 1, j) && !self.sheet.as_ref().is_some_and(|s| s.warp_hinge(i + 1, j))
    }
    /// Is the weft bending triple (i, j), (i, j+1), (i, j+2) there?
    #[inline]
    pub fn weft_triple(&self, i: usize, j: usize) -> bool {
        self.weft_link(i, j) && self.weft_link(i, j + 1)
    }
    /// Reinforcement factors of the warp link (i, j)-(i+1, j).
    #[inline]
    pub fn warp_link_factors(&self, i: usize, j: usize) -> Factors {
        self.sheet.as_ref().map_or(Factors::ONE, |s| *s.warp_link(i, j))
    }
    /// Reinforcement factors of the weft link (i, j)-(i, j+1).
    #[inline]
    pub fn weft_link_factors(&self, i: usize, j: usize) -> Factors {
        self.sheet.as_ref().map_or(Factors::ONE, |s| *s.weft_link(i, j))
    }
    /// Reinforcement factors of cell (i, j).
    #[inline]
    pub fn cell_factors(&self, i: usize, j: usize) -> Factors {
        self.sheet.as_ref().map_or(Factors::ONE, |s| *s.cell(i, j))
    }
    /// Reinforcement factors of node (i, j).
    #[inline]
    pub fn node_factors(&self, i: usize, j: usize) -> Factors {
        self.sheet.as_ref().map_or(Factors::ONE, |s| *s.node(i, j))
    }
    /// Whether cell (i, j) exists and is complete (out-of-range indices: false).
    fn cell_on(&self, i: isize, j: isize) -> f64 {
        let inside = i >= 0 && j >= 0 && (i as usize) + 1 < self.nu && (j as usize) + 1 < self.nv;
        if inside && self.cell_active(i as usize, j as usize) {
            1.0
        } else {
            0.0
        }
    }
    /// Share of the tributary width d carried by the warp segment (i, j)-(i+1, j): half for each
    /// complete cell beside it, so edge fibres of the fabric carry d/2 and the widths of all
    /// segments add up to the fabric's area.
    pub fn warp_segment_width(&self, i: usize, j: usize) -> f64 {
        let (i, j) = (i as isize, j as isize);
        0.5 * (self.cell_on(i, j - 1) + self.cell_on(i, j))
    }
    /// As [`Grid::warp_segment_width`] for the weft segment (i, j)-(i, j+1).
    pub fn weft_segment_width(&self, i: usize, j: usize) -> f64 {
        let (i, j) = (i as isize, j as isize);
        0.5 * (self.cell_on(i - 1, j) + self.cell_on(i, j))
    }
    /// Share of the width d carried by the warp bending triple (i, j), (i+1, j), (i+2, j): a
    /// quarter for each complete cell around its middle node along that line.
    pub fn warp_triple_width(&self, i: usize, j: usize) -> f64 {
        let (i, j) = (i as isize, j as isize);
        0.25 * (self.cell_on(i, j - 1) + self.cell_on(i, j) + self.cell_on(i + 1, j - 1) + self.cell_on(i + 1, j))
    }
    /// As [`Grid::warp_triple_width`] for the weft triple (i, j), (i, j+1), (i, j+2).
    pub fn weft_triple_width(&self, i: usize, j: usize) -> f64 {
        let (i, j) = (i as isize, j as isize);
        0.25 * (self.cell_on(i - 1, j) + self.cell_on(i, j) + self.cell_on(i - 1, j + 1) + self.cell_on(i, j + 1))
    }
    /// Area attributed to each node: a quarter of each complete cell it is a corner of (d^2 for
    /// interior nodes of a full grid, d^2/2 on edges, d^2/4 at corners, 0 for nodes without a
    /// complete cell). Sums to the area of the complete cells.
    pub fn nodal_areas(&self) -> Vec<f64> {
        self.quarter_cells(|_, _| 1.0)
    }
    /// Mass of each node (kg) for the fabric's `areal_mass` (kg/m^2): a quarter of each complete
    /// cell it is a corner of, times the cell's weight factor.
    pub fn nodal_masses(&self, areal_mass: f64) -> Vec<f64> {
        self.quarter_cells(|i, j| areal_mass * self.cell_factors(i, j).weight)
    }
    /// Per node, the sum over the complete cells it is a corner of of `weight(cell) d^2 / 4`.
    fn quarter_cells(&self, weight: impl Fn(usize, usize) -> f64) -> Vec<f64> {
        let mut out = vec![0.0; self.num_nodes()];
        let q = 0.25 * self.spacing * self.spacing;
        for i in 0..self.nu.saturating_sub(1) {
            for j in 0..self.nv.saturating_sub(1) {
                if self.cell_active(i, j) {
                    let k = self.index(i, j);
                    let w = q * weight(i, j);
                    for n in [k, k + 1, k + self.nv, k + self.nv + 1] {
                        out[n] += w;
                    }
                }
            }
        }
        out
    }
    /// The reference state laid flat: node (i, j) at (i d, j d, 0).
    pub fn flat_positions(&self) -> Vec<Point> {
        let d = self.spacing;
        (0..self.num_nodes()).map(|k| Point::new((k / self.nv) as f64 * d, (k % self.nv) as f64 * d, 0.0)).collect()
    }
}

/// Each cell's bending energy per unit of its reference area d^2 (J/m^2) as the net lies: the
/// bending term's share of each complete cell ([`Bending::cell_energies`], the term the
/// mechanics minimises, on the placed nodes, with the sheet's features when it has any: its
/// reinforcements' bending factors, hinges and cuts), over d^2. `None` for a cell that is not
/// complete. A cell the blank cuts counts per unit of the whole cell. Fails only when `sheet`
/// does not fit the net's grid.
pub fn bending_energy_density<L: Laws + ?Sized>(
    net: &DrapeNet,
    laws: &L,
    sheet: Option<&SheetFeatures>,
) -> Result<Vec<Option<f64>>, SheetError> {
    let mut grid = Grid::from_net(net);
    if let Some(s) = sheet.filter(|s| !s.is_empty()) {
        grid = grid.with_sheet(s.layout(net.nu, net.nv, net.spacing, net.origin_node)?);
    }
    let area = net.spacing * net.spacing;
    let energies = Bending::new(laws).cell_energies(&grid, &net.positions);
    Ok(energies.into_iter().map(|e| e.map(|e| e / area)).collect())
}

/// Where a term puts its contributions: one strip of node rows of the grid. A term reports the
/// energy, gradient and Hessian blocks of the elements it is asked for; the sink keeps the parts
/// that belong to the strip (the gradient of its nodes, the Hessian columns of its nodes, the
/// energy of elements whose lowest node is in it).
pub struct Sink<'s> {
    rows: Range<usize>,
    nodes: Range<usize>,
    energy: f64,
    grad: Option<&'s mut [Vector]>,
    hess: Option<HessSink<'s>>,
}

struct HessSink<'s> {
    pattern: &'s SymmetricPattern,
    values: &'s mut [f64],
    offset: usize,
    kind: HessianKind,
}

impl<'s> Sink<'s> {
    /// The node rows i of this strip.
    #[inline]
    pub fn rows(&self) -> Range<usize> {
        self.rows.clone()
    }
    /// Of the base rows `base`, those whose elements (spanning rows `i..=i + span`) lie inside a
    /// grid of `nu` rows and touch this strip: the elements worth visiting.
    #[inline]
    pub fn element_rows(&self, base: &Range<usize>, span: usize, nu: usize) -> Range<usize> {
        let lo = base.start.max(self.rows.start.saturating_sub(span));
        let hi = base.end.min(self.rows.end).min(nu.saturating_sub(span));
        lo..hi.max(lo)
    }
    /// Is the gradient wanted?
    #[inline]
    pub fn wants_gradient(&self) -> bool {
        self.grad.is_some()
    }
    /// Which Hessian is wanted, if any.
    #[inline]
    pub fn hessian_kind(&self) -> Option<HessianKind> {
        self.hess.as_ref().map(|h| h.kind)
    }
    /// Adds the energy `e` of an element whose lowest node index is `owner`.
    #[inline]
    pub fn add_energy(&mut self, owner: usize, e: f64) {
        if self.nodes.contains(&owner) {
            self.energy += e;
        }
    }
    /// Adds `g` to the gradient at `node`.
    #[inline]
    pub fn add_gradient(&mut self, node: usize, g: &Vector) {
        if let Some(grad) = self.grad.as_deref_mut() {
            if self.nodes.contains(&node) {
                grad[node - self.nodes.start] += g;
            }
        }
    }
    /// Adds `m` to the Hessian block (a, b) and `m^T` to (b, a); once per unordered pair of an
    /// element, `m` symmetric when `a == b`.
    #[inline(always)]
    pub fn add_block(&mut self, a: usize, b: usize, m: &Matrix3<f64>) {
        if let Some(h) = self.hess.as_mut() {
            if self.nodes.contains(&a.max(b)) {
                h.pattern.add_block_into(h.values, h.offset, a, b, m);
            }
        }
    }
    /// Adds `s I` to the Hessian block (a, b) and (b, a).
    #[inline(always)]
    pub fn add_scaled_identity(&mut self, a: usize, b: usize, s: f64) {
        if let Some(h) = self.hess.as_mut() {
            if self.nodes.contains(&a.max(b)) {
                h.pattern.add_identity_into(h.values, h.offset, a, b, s);
            }
        }
    }
}

/// One term of the energy.
pub trait EnergyTerm: Sync {
    /// The term's name in energy listings.
    fn name(&self) -> &'static str;
    /// How many rows beyond its base row (its lowest node row) an element reaches: 0 for nodal
    /// terms, 1 for segments and cells, 2 for bending triples.
    fn row_span(&self) -> usize;
    /// Reports every active element whose base row is in `base` to the sink (energy with
    /// [`Sink::add_energy`], gradient with [`Sink::add_gradient`], Hessian blocks with
    /// [`Sink::add_block`] when [`Sink::hessian_kind`] is set), in increasing base row, in an
    /// order that depends only on the grid. Elements that do not touch the sink's strip may be
    /// skipped ([`Sink::element_rows`]). `x` has one position per node (inactive nodes'
    /// positions are ignored).
    fn add(&self, grid: &Grid, x: &[Point], base: Range<usize>, sink: &mut Sink<'_>);
    /// For terms that act as stiff constraints (fibre stretch): adds to `out` the forces
    /// `sum_e W''(e) (e(trial) - e(x) - grad e(x) . (trial - x)) grad e(x)` that the term's
    /// measures gain to second order between `x` and `trial`, so that a correction step can
    /// return a trial state to the term's curved valley. Other terms add nothing.
    fn add_second_order(&self, _grid: &Grid, _x: &[Point], _trial: &[Point], _out: &mut [Vector]) {}
}

/// Energy, gradient and (optionally) Hessian at one configuration.
#[derive(Debug, Clone)]
pub struct Evaluation {
    /// Total energy (J).
    pub energy: f64,
    /// Energy of each term, in the model's order.
    pub terms: Vec<(&'static str, f64)>,
    /// dE/dx per node (N); zero at inactive nodes.
    pub gradient: Vec<Vector>,
    /// d2E/dx2 (upper triangle, DOF `3 * node + c`); rows/columns of inactive nodes are zero.
    pub hessian: Option<SymmetricMatrix>,
}

impl Evaluation {
    /// The gradient as a flat DOF vector.
    pub fn gradient_flat(&self) -> Vec<f64> {
        self.gradient.iter().flat_map(|g| [g.x, g.y, g.z]).collect()
    }
}

/// The energy of a ply on its grid: a list of terms evaluated together.
pub struct Model<'a> {
    /// The grid the terms live on.
    pub grid: Grid,
    terms: Vec<Box<dyn EnergyTerm + 'a>>,
    pattern: Arc<SymmetricPattern>,
    strip_nodes: usize,
}

/// Default number of nodes per strip of the parallel evaluation.
pub const STRIP_NODES: usize = 4096;
/// Base rows of elements visited together by all terms.
const GROUP: usize = 2;

impl<'a> Model<'a> {
    /// Stretch, shear, bending and gravity (`gravity` in m/s^2, e.g. (0, 0, -9.81)).
    pub fn new<L: Laws + ?Sized>(grid: Grid, material: &'a L, gravity: Vector) -> Self {
        let g = Gravity::new(&grid, material.areal_mass(), gravity);
        let mut model = Self::internal(grid, material);
        model.push_term(Box::new(g));
        model
    }
    /// The fabric's internal energy only: stretch, shear and bending, and the springs of the
    /// grid's sheet features (a fold) if it has any; loads are added by the caller.
    pub fn internal<L: Laws + ?Sized>(grid: Grid, material: &'a L) -> Self {
        let mut terms: Vec<Box<dyn EnergyTerm + 'a>> =
            vec![Box::new(Stretch::new(material)), Box::new(Shear::new(material)), Box::new(Bending::new(material))];
        if let Some(sheet) = grid.sheet.as_ref().filter(|s| !s.springs.is_empty()) {
            terms.push(Box::new(Springs::new(&grid, &sheet.springs)));
        }
        Self::with_terms(grid, terms)
    }
    /// A model with the given terms (e.g. a subset, or extra penalty terms).
    pub fn with_terms(grid: Grid, terms: Vec<Box<dyn EnergyTerm + 'a>>) -> Self {
        let pattern = Arc::new(SymmetricPattern::grid(grid.nu, grid.nv));
        Model { grid, terms, pattern, strip_nodes: STRIP_NODES }
    }
    /// Sets the (approximate) number of nodes per strip of the parallel evaluation. Gradients and
    /// Hessians do not depend on it at all; energies only through the order of summation.
    pub fn with_strip_nodes(mut self, nodes: usize) -> Self {
        self.strip_nodes = nodes.max(1);
        self
    }
    /// Rows of nodes per strip (a function of the grid only, never of the thread count).
    fn strip_rows(&self) -> usize {
        self.strip_nodes.div_ceil(self.grid.nv).max(1)
    }
    /// Adds a term at the end.
    pub fn push_term(&mut self, term: Box<dyn EnergyTerm + 'a>) {
        self.terms.push(term);
    }
    /// Names of the terms, in order.
    pub fn term_names(&self) -> Vec<&'static str> {
        self.terms.iter().map(|t| t.name()).collect()
    }
    /// The Hessian sparsity pattern (built once with the model).
    pub fn pattern(&self) -> &Arc<SymmetricPattern> {
        &self.pattern
    }

    /// Energy, gradient and, if `want` is set, the Hessian at positions `x` (one per node).
    pub fn evaluate(&self, x: &[Point], want: Option<HessianKind>) -> Evaluation {
        let mut out = Evaluation { energy: 0.0, terms: Vec::new(), gradient: Vec::new(), hessian: None };
        self.evaluate_into(x, want, &mut out);
        out
    }

    /// As [`Model::evaluate`], reusing the buffers of `out` (no allocation after the first call
    /// with the same grid; a Hessian in `out` is reused if it is on this model's pattern).
    pub fn evaluate_into(&self, x: &[Point], want: Option<HessianKind>, out: &mut Evaluation) {
        let n = self.grid.num_nodes();
        assert_eq!(x.len(), n, "one position per node");
        out.gradient.resize(n, Vector::zeros());
        match (want, &out.hessian) {
            (None, _) => out.hessian = None,
            (Some(_), Some(h)) if Arc::ptr_eq(&h.pattern, &self.pattern) => {}
            (Some(_), _) => out.hessian = Some(SymmetricMatrix::zeros(self.pattern.clone())),
        }
        let values: Option<&mut [f64]> = out.hessian.as_mut().map(|h| &mut h.values[..]);
        let per_term = self.run(x, Some(&mut out.gradient), values, want, None);
        out.terms = self.terms.iter().zip(&per_term).map(|(t, e)| (t.name(), *e)).collect();
        out.energy = per_term.iter().sum();
    }

    /// The total energy only (for line searches).
    pub fn energy(&self, x: &[Point]) -> f64 {
        assert_eq!(x.len(), self.grid.num_nodes(), "one position per node");
        self.run(x, None, None, None, None).iter().sum()
    }

    /// The second-order forces of the terms that act as stiff constraints between `x` and
    /// `trial` (see [`EnergyTerm::add_second_order`]).
    pub fn second_order_forces(&self, x: &[Point], trial: &[Point]) -> Vec<Vector> {
        let mut out = vec![Vector::zeros(); x.len()];
        for t in &self.terms {
            t.add_second_order(&self.grid, x, trial, &mut out);
        }
        out
    }

    /// The gradient of each term on its own, by name (for reports of where a solve fails).
    pub fn term_gradients(&self, x: &[Point]) -> Vec<(&'static str, Vec<Vector>)> {
        assert_eq!(x.len(), self.grid.num_nodes(), "one position per node");
        (0..self.terms.len())
            .map(|t| {
                let mut g = vec![Vector::zeros(); x.len()];
                self.run(x, Some(&mut g), None, None, Some(t));
                (self.terms[t].name(), g)
            })
            .collect()
    }

    /// Runs every term (or only term `only`) over every strip; returns the energy per term.
    fn run(
        &self,
        x: &[Point],
        grad: Option<&mut [Vector]>,
        values: Option<&mut [f64]>,
        want: Option<HessianKind>,
        only: Option<usize>,
    ) -> Vec<f64> {
        let grid = &self.grid;
        let (nu, nv) = (grid.nu, grid.nv);
        let h = self.strip_rows();
        let strips: Vec<Range<usize>> = (0..nu).step_by(h).map(|i0| i0..(i0 + h).min(nu)).collect();
        // Split the output buffers into one disjoint window per strip.
        type Job<'b> = (Range<usize>, Option<&'b mut [Vector]>, Option<(&'b mut [f64], usize)>);
        let mut jobs: Vec<Job> = Vec::with_capacity(strips.len());
        let mut grad_rest = grad;
        let mut val_rest = values.map(|v| (v, 0usize));
        for rows in strips {
            let nodes = rows.start * nv..rows.end * nv;
            let g = grad_rest.take().map(|g| {
                let (a, b) = g.split_at_mut(nodes.len());
                grad_rest = Some(b);
                a
            });
            let v = val_rest.take().map(|(v, off)| {
                let nz = self.pattern.nz_range(nodes.clone());
                let (a, b) = v.split_at_mut(nz.len());
                val_rest = Some((b, off + nz.len()));
                (a, off)
            });
            jobs.push((rows, g, v));
        }
        let nterms = self.terms.len();
        let span = self.terms.iter().map(|t| t.row_span()).max().unwrap_or(0);
        let pattern = &self.pattern;
        let energies: Vec<Vec<f64>> = jobs
            .into_par_iter()
            .map(|(rows, g, v)| {
                let nodes = rows.start * nv..rows.end * nv;
                let mut g = g;
                if let Some(g) = g.as_deref_mut() {
                    g.fill(Vector::zeros());
                }
                let hess = v.map(|(values, offset)| HessSink {
                    pattern,
                    values,
                    offset,
                    kind: want.expect("Hessian buffer without a kind"),
                });
                let mut sink = Sink { rows: rows.clone(), nodes, energy: 0.0, grad: g, hess };
                let mut e = vec![0.0; nterms];
                // Elements by groups of GROUP base rows (aligned on the whole grid, so that each
                // node receives its contributions in the same order whatever the strips), every
                // term per group: the Hessian columns being written stay in cache.
                let mut zeroed = rows.start; // Hessian columns zeroed for rows < zeroed
                let mut g0 = rows.start.saturating_sub(span);
                while g0 < rows.end {
                    let g1 = ((g0 / GROUP + 1) * GROUP).min(rows.end);
                    if let Some(h) = sink.hess.as_mut() {
                        let upto = (g1 + span).min(rows.end);
                        if upto > zeroed {
                            let nz = pattern.nz_range(zeroed * nv..upto * nv);
                            h.values[nz.start - h.offset..nz.end - h.offset].fill(0.0);
                            zeroed = upto;
                        }
                    }
                    for (index, (t, et)) in self.terms.iter().zip(e.iter_mut()).enumerate() {
                        if only.is_some_and(|o| o != index) {
                            continue;
                        }
                        sink.energy = 0.0;
                        t.add(grid, x, g0..g1, &mut sink);
                        *et += sink.energy;
                    }
                    g0 = g1;
                }
                e
            })
            .collect();
        let mut total = vec![0.0; nterms];
        for e in &energies {
            for (t, v) in total.iter_mut().zip(e) {
                *t += v;
            }
        }
        total
    }
}
