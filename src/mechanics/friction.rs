//! Coulomb friction between the ply and the tool (REFERENCES section 8), as a potential whose
//! data are lagged from the last state.
//!
//! Friction dissipates `mu f_n |slip|`: what it does depends on the path, so the load comes in
//! increments (`load_steps`) and, within each, friction is a potential of the positions whose
//! data come from the state before it (the lagged friction of incremental-potential contact,
//! Li et al., ACM ToG 39(4) 2020). Every node the tool pushed at the lag carries
//!
//! ```text
//! D_k(x) = mu lambda_k f0(|T_k (x_k - o_k)|)
//! ```
//!
//! with `o_k` where its slip is measured from (its place when the increment began, or where it
//! touched down during it), `T_k = I - n_k n_k^T` the tool's tangent plane there, and `lambda_k`
//! the normal force the tool gave it at the lag. `f0` is |s| smoothed below the stick distance
//! eps: `f0(s) = -s^3 / (3 eps^2) + s^2 / eps + eps / 3` below it, `s` beyond, so its slope `f1`
//! rises from 0 to 1 over `[0, eps]`. A node whose tangential push is below `mu lambda` creeps
//! less than eps against it (it sticks); beyond, it slides against the force `mu lambda` (it
//! slips). After each solve the normal forces and bases are taken again from the solution and
//! the increment is solved again, until the normal forces agree ([`LAG_TOLERANCE`]).
//!
//! The solver sees [`Frictional`]: the net's energy plus this potential, with friction among
//! the internal forces. With `mu = 0` the potential is zero, but the lag still records where the
//! ply bears on the tool: [`Frictional::runaway`] stops a solve whose ply slides away over the
//! tool, whatever the friction.
use super::contact::{ContactMode, ContactSurface, Foot};
use super::qp::HessianBlocks;
use super::solver::{Constraints, Evaluation, Objective};
use crate::geometry::{Point, Vector};
use nalgebra::{Matrix3, Matrix6, Vector6};
use rayon::prelude::*;

/// The stick distance eps, in spacings: a node held by friction creeps less than this (the
/// smoothing of |s| at zero slip). Small against the 1 mm by which an engineer would call a node
/// moved, and large enough that the friction well (stiffness about `2 mu lambda / eps`) stays
/// below the fibres' stiffness.
pub const STICK_SPACINGS: f64 = 1e-3;
/// The normal forces of an increment agree with its solution when they changed by less than
/// this share of their sum since the last lag.
pub const LAG_TOLERANCE: f64 = 1e-2;
/// Most solves of one increment (each with the normal forces of the last).
pub const MAX_LAGS: usize = 24;
/// A ply slides (no equilibrium holds it) once its nodes in contact have slipped, weighted by
/// their normal forces, by more than this share of the contact region's size within one
/// increment ...
pub const SLIDE_SHARE: f64 = 0.1;
/// ... and by more than this many spacings.
pub const SLIDE_MIN_SPACINGS: f64 = 2.0;
/// A solve whose ply slides by this share of that limit further stops, and the increment goes
/// on from there with the normal forces where the ply has got to: a slide is followed in steps
/// short enough that the normal forces of its start still hold (a strip over a rod gains the
/// normal forces of its tension only once it bears on the rod).
pub const RELAG_SHARE: f64 = 0.125;
/// With friction, a solve also stops once a node has travelled this many spacings, and the
/// increment goes on from there with the normal forces where the ply has got to: a sheet
/// dropped onto a tool bears on it only as it lands, and friction grips only what bears.
/// Without friction too while nothing bears: [`Frictional::runaway`] measures the slide of the
/// nodes that bear, and a frictionless sheet dropped on a sphere's pole from a hair above it
/// would otherwise slide off and fall to the iteration limit (the bundled sphere at mu = 0:
/// 2,000 iterations, 11 minutes, no named outcome).
pub const RELAG_TRAVEL_SPACINGS: f64 = 4.0;
/// A free node bears on the tool when it lies within this many spacings of it (and the forces
/// push it in): the solver puts touching nodes on the surface, and locating them again finds
/// them there to rounding (its own active-set test, the solver's `ACTIVE_GAP`, is for the feet it keeps).
pub const BEARING_GAP: f64 = 1e-6;
/// A rigid motion of the ply is tangent to the tool (the tool does not stop it) when the normal
/// speeds it gives the nodes in contact are below this share of their speeds, rms. Any small
/// patch of a curved tool nearly lets a ply turn and slide over it (to second order in its size
/// over the radius of curvature: 0.5% on a saddle curved as much as the ply is wide); a sphere,
/// a cylinder or a plane lets it exactly, to the accuracy of the smooth surface's normals
/// (about 1e-4 on the bundled tools).
pub const RIGID_TANGENT: f64 = 1e-3;

/// Where each node bears on the tool at a state, with the force the tool gives it and the
/// friction coefficient of what it bears on.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bearing {
    /// The tool's outward unit normal at the node's foot.
    pub normal: Vector,
    /// The normal force, N (positive: the tool pushes the node out).
    pub force: f64,
    /// Coulomb's coefficient there: the tool's, or where a ply of a layup lies on the plies
    /// below it, theirs ([`Coulomb`]); a binder's grip, the mean of its two faces'.
    pub mu: f64,
    /// Whether it bears on the plies below (their coefficient, `ply_friction`) rather than on a
    /// tool: what [`friction_needed`] asks about.
    pub on_plies: bool,
    /// How far what it bears on moved over the increment (a punch's step; zero on a still
    /// tool): a node that sticks moves with it, so its slip is measured from where the tool
    /// carried its place ([`FrictionLag::new`]).
    pub carried: Vector,
}

/// Coulomb's coefficients a ply meets: the tool's, and in a layup, where the ply lies on the
/// plies below it, theirs.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Coulomb {
    /// Between the ply and a tool (the tool, the punch, the die, the binder's upper face).
    pub tool: f64,
    /// Between the ply and the plies below it, when a layup gives its own (`ply_friction`).
    pub plies: Option<PliesBelow>,
}

/// Where the plies below a ply of a layup lie, and the friction between them and it.
#[derive(Debug, Clone, PartialEq)]
pub struct PliesBelow {
    /// Coulomb's coefficient between plies.
    pub mu: f64,
    /// Per facet of the tool (the surface the ply lies on has the same facets, offset): whether
    /// the plies below cover it (a node whose foot is on it bears on fabric). Facets numbered
    /// past these (a die's) are bare tool.
    pub facets: Vec<bool>,
    /// Whether the plies below reach under the binder: its lower face then grips them.
    pub under_binder: bool,
}

impl Coulomb {
    /// Just the tool's coefficient.
    pub fn tool(mu: f64) -> Self {
        Coulomb { tool: mu, plies: None }
    }

    /// The coefficient, and whether it is the plies', where a node's foot is on `facet`.
    pub fn on_facet(&self, facet: u32) -> (f64, bool) {
        match &self.plies {
            Some(p) if p.facets.get(facet as usize).copied().unwrap_or(false) => (p.mu, true),
            _ => (self.tool, false),
        }
    }

    /// The coefficient of a binder's grip per unit of its normal force on both faces: the
    /// mean of the upper face's (on the binder, the tool's) and the lower face's (on the plies
    /// below where they reach under it, else on the tool's flange, the tool's). With one
    /// coefficient it is that one exactly.
    pub fn binder(&self) -> f64 {
        match &self.plies {
            Some(p) if p.under_binder => (self.tool + p.mu) / 2.0,
            _ => self.tool,
        }
    }

    /// The largest coefficient any contact has (0: frictionless everywhere).
    pub fn largest(&self) -> f64 {
        self.plies.as_ref().map_or(self.tool, |p| p.mu.max(self.tool))
    }
}

/// The friction of one increment: its data lagged from the last state.
#[derive(Debug, Clone)]
pub struct FrictionLag {
    /// The largest of Coulomb's coefficients the bearings may carry ([`Coulomb::largest`]):
    /// 0, frictionless, and the potential is left out.
    pub mu: f64,
    /// The stick distance eps (m).
    pub stick: f64,
    /// Per node, where its slip is measured from.
    pub origin: Vec<Point>,
    /// Per node, where it bears on the tool at the lag (None: it does not).
    pub bearing: Vec<Option<Bearing>>,
}

/// |s| smoothed below `eps` ([module doc](self)), its slope and curvature.
fn smoothed(s: f64, eps: f64) -> (f64, f64, f64) {
    if s >= eps {
        (s, 1.0, 0.0)
    } else {
        let r = s / eps;
        (eps * (-r * r * r / 3.0 + r * r + 1.0 / 3.0), 2.0 * r - r * r, 2.0 * (1.0 - r) / eps)
    }
}

impl FrictionLag {
    /// A lag at the state `x` with its bearings, whose coefficients are at most `mu`: each
    /// node slips from where it is, carried on by what it bears on ([`Bearing::carried`]: a
    /// node on a punch that moved sticks to it where the punch took its place).
    pub fn new(mu: f64, stick: f64, x: &[Point], bearing: Vec<Option<Bearing>>) -> Self {
        let origin = x.iter().zip(&bearing).map(|(p, b)| b.map_or(*p, |b| p + b.carried)).collect();
        FrictionLag { mu, stick, origin, bearing }
    }

    /// The next lag of the same increment, at `x`, with the normal forces `bearing`: slips stay
    /// measured from where the increment began, but a node that did not bear on the tool then
    /// slips from where it is now (where it touched down).
    pub fn relag(&mut self, x: &[Point], bearing: Vec<Option<Bearing>>) {
        for (k, p) in x.iter().enumerate() {
            if self.bearing[k].is_none() {
                self.origin[k] = *p;
            }
        }
        self.bearing = bearing;
    }

    /// Every node slips from where it is at `x` from now on (what it slid so far is the
    /// caller's to bank).
    pub fn anchor(&mut self, x: &[Point]) {
        self.origin.copy_from_slice(x);
    }

    /// Start each node that bears where the potential's gradient balances the tangential part
    /// of its push at `x` (`eval`'s forces less loads, friction excluded, as [`bearings`] takes
    /// them), up to its capacity: a state already in equilibrium with friction (a formed ply
    /// held again by its tools) starts with the friction forces that hold it. From zero slip,
    /// where the potential's slope is zero, every node would creep up to a stick distance to
    /// take them up again, and a taut span between two gripped ends sag by far more.
    pub fn preload(&mut self, cons: &Constraints, x: &[Point], eval: &Evaluation) {
        let push = pushes(cons, eval);
        for (k, p) in x.iter().enumerate() {
            let (c, Some(b)) = (self.capacity(k), self.bearing[k]) else { continue };
            let t = push[k] - b.normal * b.normal.dot(&push[k]);
            let pull = t.norm();
            if c == 0.0 || pull == 0.0 {
                continue;
            }
            // The slip s whose slope f1(s) = 2 r - r^2 (r = s / eps) is the share of the
            // capacity the push takes: r = 1 - sqrt(1 - share), the full stick distance at it.
            let share = (pull / c).min(1.0);
            let slip = self.stick * (1.0 - (1.0 - share).sqrt());
            // The gradient c f1(s) u / s, u = T (x - o), is -t when u = -s t / |t|: o = x + s t / |t|
            // (carried on with what it bears on, as [`FrictionLag::new`] carries it).
            self.origin[k] = p + b.carried + t * (slip / pull);
        }
    }

    /// The slip of node k at `x` in the lagged tangent plane (zero where it does not bear).
    pub fn slip(&self, k: usize, x: &Point) -> Vector {
        match &self.bearing[k] {
            Some(b) => {
                let d = x - self.origin[k];
                d - b.normal * b.normal.dot(&d)
            }
            None => Vector::zeros(),
        }
    }

    /// The friction force capacity mu lambda of node k (N), with the coefficient of what it
    /// bears on.
    fn capacity(&self, k: usize) -> f64 {
        self.bearing[k].map_or(0.0, |b| b.mu * b.force.max(0.0))
    }

    /// The potential at `x`.
    pub fn energy(&self, x: &[Point]) -> f64 {
        (0..x.len())
            .filter(|&k| self.capacity(k) > 0.0)
            .map(|k| self.capacity(k) * smoothed(self.slip(k, &x[k]).norm(), self.stick).0)
            .sum()
    }

    /// Its gradient per node: the friction force each node feels is minus this.
    pub fn gradient(&self, x: &[Point]) -> Vec<Vector> {
        (0..x.len())
            .into_par_iter()
            .map(|k| {
                let c = self.capacity(k);
                let u = self.slip(k, &x[k]);
                let s = u.norm();
                if c == 0.0 || s == 0.0 {
                    return Vector::zeros();
                }
                u * (c * smoothed(s, self.stick).1 / s)
            })
            .collect()
    }

    /// Its Hessian's diagonal blocks (the potential couples no two nodes). Below the stick
    /// distance `c (f1/s (T - u u^T) + f1' u u^T)`, beyond `c/s (T - u u^T)`: positive
    /// semidefinite either way, and `2 c / eps T` at zero slip.
    pub fn hessian(&self, x: &[Point]) -> Vec<Matrix3<f64>> {
        (0..x.len())
            .into_par_iter()
            .map(|k| {
                let c = self.capacity(k);
                let Some(b) = self.bearing[k].filter(|_| c > 0.0) else { return Matrix3::zeros() };
                let tangent = Matrix3::identity() - b.normal * b.normal.transpose();
                let u = self.slip(k, &x[k]);
                let s = u.norm();
                let (_, f1, f2) = smoothed(s, self.stick);
                if s <= 1e-12 * self.stick {
                    return tangent * (c * 2.0 / self.stick);
                }
                let uu = (u / s) * (u / s).transpose();
                (tangent - uu) * (c * f1 / s) + uu * (c * f2)
            })
            .collect()
    }

    /// The normal forces' sum (N).
    pub fn total_force(&self) -> f64 {
        self.bearing.iter().flatten().map(|b| b.force.max(0.0)).sum()
    }

    /// How far the ply has slid over the tool at `x`: the slips of the nodes that bear on it,
    /// weighted by their normal forces (m).
    pub fn mean_slip(&self, x: &[Point]) -> f64 {
        let total = self.total_force();
        if total <= 0.0 {
            return 0.0;
        }
        (0..x.len()).filter_map(|k| Some(self.bearing[k]?.force.max(0.0) * self.slip(k, &x[k]).norm())).sum::<f64>()
            / total
    }

    /// The size of the region that bears on the tool: the diagonal of its nodes' bounding box.
    pub fn extent(&self) -> f64 {
        let mut lo = Vector::repeat(f64::INFINITY);
        let mut hi = Vector::repeat(f64::NEG_INFINITY);
        for (p, _) in self.origin.iter().zip(&self.bearing).filter(|(_, b)| b.is_some_and(|b| b.force > 0.0)) {
            lo = lo.inf(&p.coords);
            hi = hi.sup(&p.coords);
        }
        if lo.x.is_finite() {
            (hi - lo).norm()
        } else {
            0.0
        }
    }
}

/// The net's energy with the lagged friction potential: what the solver minimises within an
/// increment.
pub struct Frictional<'a> {
    /// The net's own energy and loads.
    pub inner: &'a dyn Objective,
    /// The increment's friction.
    pub lag: &'a FrictionLag,
    /// The slide (the normal-force weighted mean slip, [`FrictionLag::mean_slip`]) beyond which
    /// the solve stops ([`Objective::runaway`]), m.
    pub slide_limit: f64,
    /// Where the solve began, and how far a node may travel from there before the solve stops
    /// (m): normal forces taken where a falling sheet has not landed yet hold only while it
    /// falls a few spacings; and, frictionless, while nothing bears (the slide, measured on
    /// the nodes that bear, would not see a ply that lands and slides off). None: no limit.
    pub travel: Option<(&'a [Point], f64)>,
}

/// A Hessian plus diagonal blocks.
struct PlusDiagonal {
    inner: Box<dyn HessianBlocks>,
    diagonal: Vec<Matrix3<f64>>,
}

impl HessianBlocks for PlusDiagonal {
    fn block(&self, a: usize, b: usize) -> Matrix3<f64> {
        let h = self.inner.block(a, b);
        if a == b {
            h + self.diagonal[a]
        } else {
            h
        }
    }
}

impl Frictional<'_> {
    fn with_friction(&self, x: &[Point], h: Option<Box<dyn HessianBlocks>>) -> Option<Box<dyn HessianBlocks>> {
        let h = h?;
        if self.lag.mu == 0.0 {
            return Some(h);
        }
        Some(Box::new(PlusDiagonal { inner: h, diagonal: self.lag.hessian(x) }))
    }
}

impl Objective for Frictional<'_> {
    fn evaluate(&self, x: &[Point], hessian: bool) -> Evaluation {
        let mut e = self.inner.evaluate(x, hessian);
        if self.lag.mu > 0.0 {
            e.energy += self.lag.energy(x);
            for (f, g) in e.internal.iter_mut().zip(self.lag.gradient(x)) {
                *f += g;
            }
            e.hessian = self.with_friction(x, e.hessian.take());
        }
        e
    }
    fn energy(&self, x: &[Point]) -> f64 {
        self.inner.energy(x) + if self.lag.mu > 0.0 { self.lag.energy(x) } else { 0.0 }
    }
    fn convex_hessian(&self, x: &[Point]) -> Option<Box<dyn HessianBlocks>> {
        self.with_friction(x, self.inner.convex_hessian(x))
    }
    fn coupled_pairs(&self) -> Vec<(usize, usize)> {
        self.inner.coupled_pairs()
    }
    fn masses(&self) -> Vec<f64> {
        self.inner.masses()
    }
    fn second_order_forces(&self, x: &[Point], trial: &[Point]) -> Option<Vec<Vector>> {
        self.inner.second_order_forces(x, trial)
    }
    fn term_forces(&self, x: &[Point]) -> Vec<(&'static str, Vec<Vector>)> {
        let mut terms = self.inner.term_forces(x);
        if self.lag.mu > 0.0 {
            terms.push(("friction", self.lag.gradient(x)));
        }
        terms
    }
    fn step_bound(&self, x: &[Point]) -> Option<f64> {
        if self.lag.mu == 0.0 {
            return None;
        }
        // What is left of the slide the lagged normal forces were taken for, and of the travel
        // (a rigid slide moves the force-weighted mean slip as far as its nodes): a step ends at
        // most a stick distance past either, and the solve then stops for the lag to be renewed.
        // A step far past it would slide on forces the ply no longer bears.
        let slide = (self.slide_limit - self.lag.mean_slip(x)).max(0.0);
        let travel = self.travel.map_or(f64::INFINITY, |(start, limit)| {
            let gone = x.iter().zip(start).map(|(p, s)| (p - s).norm()).fold(0.0, f64::max);
            (limit - gone).max(0.0)
        });
        Some(slide.min(travel) + self.lag.stick)
    }
    fn runaway(&self, x: &[Point]) -> bool {
        let travelled = |(start, limit): (&[Point], f64)| x.iter().zip(start).any(|(p, s)| (p - s).norm() > limit);
        self.lag.mean_slip(x) > self.slide_limit || self.travel.is_some_and(travelled)
    }
}

/// Where each node bears on the tool at `x` under the net's own forces (`eval`: internal
/// forces F without friction, loads P): the tool's reaction `n . (F - P)` at every node that
/// slides on it (pressed) or touches it (free contact), where it pushes the node out, with the
/// coefficient `coulomb` has on its foot's facet; stitched nodes bear through their
/// representative. None: no contact, or the tool pulls (a pressed node over a hollow).
pub fn bearings(cons: &Constraints, x: &[Point], eval: &Evaluation, coulomb: &Coulomb) -> Vec<Option<Bearing>> {
    let n = x.len();
    let Some(tool) = cons.tool else { return vec![None; n] };
    let rep: Vec<usize> = cons.stitched.clone().unwrap_or_else(|| (0..n).collect());
    let push = pushes(cons, eval);
    (0..n)
        .into_par_iter()
        .map(|k| {
            if rep[k] != k {
                return None;
            }
            let foot = foot_of(tool, cons, k, &x[k])?;
            let force = foot.normal.dot(&push[k]);
            let (mu, on_plies) = coulomb.on_facet(foot.facet);
            let carried = tool.motion(&foot);
            (force > 0.0).then_some(Bearing { normal: foot.normal, force, mu, on_plies, carried })
        })
        .collect()
}

/// Each node's push on the tool, the fabric's forces less the loads (friction excluded), a
/// stitched node's on the node that stands for it.
fn pushes(cons: &Constraints, eval: &Evaluation) -> Vec<Vector> {
    let n = eval.internal.len();
    let rep: Vec<usize> = cons.stitched.clone().unwrap_or_else(|| (0..n).collect());
    let mut push = vec![Vector::zeros(); n];
    for (k, &r) in rep.iter().enumerate() {
        push[r] += eval.internal[k] - eval.external[k];
    }
    push
}

/// The foot of node k where it meets the tool: pressed nodes that slide on it always, free
/// nodes where they touch it.
fn foot_of(tool: &dyn ContactSurface, cons: &Constraints, k: usize, p: &Point) -> Option<Foot> {
    let f = cons.freedom[k];
    match cons.mode {
        ContactMode::Pressed if f.on_tool() => Some(tool.locate(p, false, None)),
        ContactMode::Free if f.meets_tool_free() => {
            tool.locate_near(p, cons.spacing, false, None).filter(|foot| foot.gap <= BEARING_GAP * cons.spacing)
        }
        _ => None,
    }
}

/// The rigid motions of the ply that the tool does not stop: those whose normal speeds at the
/// bearing nodes are below [`RIGID_TANGENT`] of their speeds (rms). Each is a unit per-node
/// velocity field `a + w x (p - c)`, one per independent motion (a plane has three, a cylinder
/// two, a sphere three, a generic part none). With no friction and no hold, a ply on such a tool
/// is free to move along them.
pub fn tangent_rigid_motions(x: &[Point], bearing: &[Option<Bearing>]) -> Vec<Vec<Vector>> {
    let nodes: Vec<(Point, Vector)> = x.iter().zip(bearing).filter_map(|(p, b)| b.map(|b| (*p, b.normal))).collect();
    if nodes.len() < 3 {
        return Vec::new();
    }
    let c = nodes.iter().fold(Vector::zeros(), |s, (p, _)| s + p.coords) / nodes.len() as f64;
    let scale = nodes.iter().map(|(p, _)| (p.coords - c).norm()).fold(0.0, f64::max).max(f64::MIN_POSITIVE);
    // Normal speed of node k under (a, w scaled by 1/scale): n . a + (r x n) . w / scale.
    let row = |p: &Point, n: &Vector| {
        let r = (p.coords - c) / scale;
        let m = r.cross(n);
        Vector6::new(n.x, n.y, n.z, m.x, m.y, m.z)
    };
    // Speeds of a motion: |a + w x r|^2 summed, the metric the normal speeds are weighed against.
    let mut normal = Matrix6::zeros();
    let mut speed = Matrix6::zeros();
    for (p, n) in &nodes {
        let j = row(p, n);
        normal += j * j.transpose();
        let r = (p.coords - c) / scale;
        // Velocity = a + w x r = [I, -[r]x] [a; w].
        let mut v = nalgebra::Matrix3x6::zeros();
        v.fixed_view_mut::<3, 3>(0, 0).copy_from(&Matrix3::identity());
        v.fixed_view_mut::<3, 3>(0, 3).copy_from(&(-r.cross_matrix()));
        speed += v.transpose() * v;
    }
    // Generalised eigenproblem normal v = l speed v, through speed = L L^T.
    let Some(chol) = speed.cholesky() else { return Vec::new() };
    let l_inv = chol.l().try_inverse().unwrap_or_else(Matrix6::zeros);
    let reduced = l_inv * normal * l_inv.transpose();
    let eig = reduced.symmetric_eigen();
    let mut motions = Vec::new();
    for (i, &value) in eig.eigenvalues.iter().enumerate() {
        if value.max(0.0).sqrt() > RIGID_TANGENT {
            continue;
        }
        let q = l_inv.transpose() * eig.eigenvectors.column(i);
        let (a, w) = (Vector::new(q[0], q[1], q[2]), Vector::new(q[3], q[4], q[5]) / scale);
        let field: Vec<Vector> = x.iter().map(|p| a + w.cross(&(p.coords - c))).collect();
        let size = (field.iter().map(|v| v.norm_squared()).sum::<f64>() / field.len() as f64).sqrt();
        if size > 0.0 {
            motions.push(field.into_iter().map(|v| v / size).collect());
        }
    }
    motions
}

/// What a coefficient [`friction_needed`] reports is about.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Needed {
    /// One coefficient for every contact: the tool's `friction`.
    Friction,
    /// The coefficient between the ply and the plies below it (`ply_friction`), the tool's as
    /// given where the ply bears on bare tool.
    PlyFriction,
}

/// The least friction coefficient that would hold the ply against a motion `v` (per node) that
/// keeps its fibres at their lengths (a slide, a rigid motion), under the loads `drive`: the
/// work the loads do along it over the work friction of coefficient 1 would take from it (the
/// fabric's own forces do no work along such a motion). None where nothing bears on the tool
/// along it.
///
/// Where some nodes bear on the plies below with a coefficient of their own
/// ([`Bearing::on_plies`]), it is about that one: the least `ply_friction` that would hold the
/// ply, with the friction the other nodes bear with (their own coefficients) taken off the work
/// first (0 when they alone hold it). A ply sliding on the plies below needs that coefficient;
/// one coefficient for all would mix the tool's into it.
pub fn friction_needed(v: &[Vector], drive: &[Vector], bearing: &[Option<Bearing>]) -> Option<(f64, Needed)> {
    let work: f64 = v.iter().zip(drive).map(|(v, d)| v.dot(d)).sum();
    // The work friction of coefficient 1 takes along v from the nodes on the plies below and
    // from the others, and what the others' own coefficients take.
    let (mut plies, mut others, mut others_own) = (0.0, 0.0, 0.0);
    for (v, b) in v.iter().zip(bearing) {
        let Some(b) = b else { continue };
        let w = b.force.max(0.0) * (v - b.normal * b.normal.dot(v)).norm();
        if b.on_plies {
            plies += w;
        } else {
            others += w;
            others_own += b.mu * w;
        }
    }
    if plies > 0.0 {
        return Some((((work.abs() - others_own) / plies).max(0.0), Needed::PlyFriction));
    }
    (others > 0.0).then(|| (work.abs() / others, Needed::Friction))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_smoothed_norm_is_c1_and_its_slope_rises_from_zero_to_one() {
        let eps = 0.3;
        let (f, d, c) = smoothed(0.0, eps);
        assert!((f - eps / 3.0).abs() < 1e-15 && d == 0.0 && (c - 2.0 / eps).abs() < 1e-12);
        let below = smoothed(eps * (1.0 - 1e-9), eps);
        let above = smoothed(eps, eps);
        assert!((below.0 - above.0).abs() < 1e-9 && (below.1 - above.1).abs() < 1e-8 && below.2 < 1e-8);
        for s in [0.01, 0.1, 0.2, 0.29] {
            let h = 1e-7;
            let fd = (smoothed(s + h, eps).0 - smoothed(s - h, eps).0) / (2.0 * h);
            let fd2 = (smoothed(s + h, eps).1 - smoothed(s - h, eps).1) / (2.0 * h);
            assert!((fd - smoothed(s, eps).1).abs() < 1e-6, "slope at {s}");
            assert!((fd2 - smoothed(s, eps).2).abs() < 1e-5, "curvature at {s}");
        }
    }

    #[test]
    fn the_potential_gradient_and_hessian_agree_with_finite_differences() {
        let x0 = vec![Point::new(0.0, 0.0, 0.0), Point::new(1.0, 0.0, 0.0)];
        let n = Vector::new(0.0, 0.3, 1.0).normalize();
        let bearing = vec![
            Some(Bearing { normal: n, force: 2.0, mu: 0.4, on_plies: false, carried: Vector::zeros() }),
            Some(Bearing { normal: Vector::z(), force: 0.5, mu: 0.3, on_plies: true, carried: Vector::zeros() }),
        ];
        let lag = FrictionLag::new(0.4, 0.01, &x0, bearing);
        for x in [
            vec![Point::new(0.003, -0.002, 0.001), Point::new(1.02, 0.01, 0.0)],
            vec![Point::new(0.03, 0.02, -0.01), Point::new(1.0004, -0.0002, 0.3)],
        ] {
            let g = lag.gradient(&x);
            let h = lag.hessian(&x);
            for k in 0..2 {
                for a in 0..3 {
                    let step = 1e-7;
                    let mut xp = x.clone();
                    xp[k][a] += step;
                    let mut xm = x.clone();
                    xm[k][a] -= step;
                    let fd = (lag.energy(&xp) - lag.energy(&xm)) / (2.0 * step);
                    assert!((fd - g[k][a]).abs() < 1e-6, "gradient {k} {a}: {fd} against {}", g[k][a]);
                    let dg = (lag.gradient(&xp)[k] - lag.gradient(&xm)[k]) / (2.0 * step);
                    for b in 0..3 {
                        assert!((dg[b] - h[k][(b, a)]).abs() < 1e-4 * (1.0 + h[k].norm()), "hessian {k} {a} {b}");
                    }
                }
            }
        }
    }

    #[test]
    fn a_plane_admits_three_rigid_motions_a_sphere_three_a_cylinder_two_and_a_saddle_none() {
        let grid = |f: &dyn Fn(f64, f64) -> (Point, Vector)| {
            let mut x = Vec::new();
            let mut b = Vec::new();
            for i in 0..9 {
                for j in 0..9 {
                    let (p, n) = f(-0.4 + 0.1 * i as f64, -0.4 + 0.1 * j as f64);
                    x.push(p);
                    b.push(Some(Bearing { normal: n, force: 1.0, mu: 0.0, on_plies: false, carried: Vector::zeros() }));
                }
            }
            (x, b)
        };
        let plane = grid(&|u, v| (Point::new(u, v, 0.0), Vector::z()));
        let sphere = grid(&|u, v| {
            let n = Vector::new(u, v, 1.0).normalize();
            (Point::from(n * 2.0), n)
        });
        let cylinder = grid(&|u, v| {
            let n = Vector::new(u.sin(), 0.0, u.cos());
            (Point::new(n.x, v, n.z), n)
        });
        // Curved as much as the patch is wide (over a much flatter patch a saddle is nearly a
        // plane, and nearly lets the ply move).
        let rho = 0.3;
        let saddle = grid(&|u, v| {
            let n = Vector::new(-u / rho, v / rho, 1.0).normalize();
            (Point::new(u, v, (u * u - v * v) / (2.0 * rho)), n)
        });
        assert_eq!(tangent_rigid_motions(&plane.0, &plane.1).len(), 3);
        assert_eq!(tangent_rigid_motions(&sphere.0, &sphere.1).len(), 3);
        assert_eq!(tangent_rigid_motions(&cylinder.0, &cylinder.1).len(), 2);
        assert_eq!(tangent_rigid_motions(&saddle.0, &saddle.1).len(), 0);
    }

    #[test]
    fn the_friction_needed_on_an_incline_is_the_tangent_of_its_angle() {
        let a: f64 = 0.35;
        let n = Vector::new(0.0, -a.sin(), a.cos());
        let down = Vector::new(0.0, -a.cos(), -a.sin());
        let weight = Vector::new(0.0, 0.0, -2.0);
        let drive = vec![weight; 4];
        let bearing =
            vec![
                Some(Bearing { normal: n, force: 2.0 * a.cos(), mu: 0.0, on_plies: false, carried: Vector::zeros() });
                4
            ];
        let v = vec![down; 4];
        let (mu, of) = friction_needed(&v, &drive, &bearing).unwrap();
        assert!((mu - a.tan()).abs() < 1e-12 && of == Needed::Friction);
    }

    /// Half of a ply on an incline bears on the tool with tan a / 2, half on a ply below: the
    /// ply friction that holds it is 3/2 tan a (the two halves' friction adds up to its pull).
    #[test]
    fn the_ply_friction_needed_takes_the_tools_share_off_first() {
        let a: f64 = 0.35;
        let n = Vector::new(0.0, -a.sin(), a.cos());
        let down = Vector::new(0.0, -a.cos(), -a.sin());
        let drive = vec![Vector::new(0.0, 0.0, -2.0); 4];
        let on =
            |mu, on_plies| Some(Bearing { normal: n, force: 2.0 * a.cos(), mu, on_plies, carried: Vector::zeros() });
        let tool = 0.5 * a.tan();
        let bearing = vec![on(tool, false), on(tool, false), on(0.1, true), on(0.1, true)];
        let (mu, of) = friction_needed(&[down; 4], &drive, &bearing).unwrap();
        assert!((mu - 1.5 * a.tan()).abs() < 1e-12 && of == Needed::PlyFriction, "{mu}");
        // Held by the tool's share alone, it needs none.
        let bearing = vec![on(5.0, false), on(5.0, false), on(0.1, true), on(0.1, true)];
        assert_eq!(friction_needed(&[down; 4], &drive, &bearing), Some((0.0, Needed::PlyFriction)));
    }

    #[test]
    fn a_foot_on_a_facet_the_plies_below_cover_meets_them_and_a_die_facet_the_tool() {
        let plies = PliesBelow { mu: 0.1, facets: vec![true, false, true], under_binder: false };
        let c = Coulomb { tool: 0.3, plies: Some(plies) };
        assert_eq!(c.on_facet(0), (0.1, true));
        assert_eq!(c.on_facet(1), (0.3, false));
        // A die's facets are numbered after the punch's.
        assert_eq!(c.on_facet(3), (0.3, false));
        // The plies below do not reach under the binder: both its faces grip the tool's way.
        assert_eq!(c.binder(), 0.3);
        assert_eq!(c.largest(), 0.3);
        assert_eq!(Coulomb::tool(0.2).on_facet(0), (0.2, false));
    }

    #[test]
    fn a_binders_grip_with_one_coefficient_is_that_coefficient_exactly() {
        for mu in [0.0, 0.1, 0.2, 0.3, 1.0 / 3.0] {
            let plies = PliesBelow { mu, facets: Vec::new(), under_binder: true };
            assert_eq!(Coulomb { tool: mu, plies: Some(plies) }.binder(), mu);
        }
    }
}
