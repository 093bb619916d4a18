//! Sequential convex subproblems: at each iterate a quadratic model of the energy (convexified
//! Hessian plus Levenberg-Marquardt damping) with the linearised contact constraints is solved by
//! Clarabel; the step is accepted if the energy falls as predicted, else the damping grows.
use super::contact::{contact_rows, ContactMode, ContactRow, ContactSurface, Foot, Freedom, NodeBasis};
use crate::geometry::{Point, Vector};
use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettingsBuilder, DefaultSolver, IPSolver, NonnegativeConeT, SolverStatus, SupportedConeT,
};
use nalgebra::Matrix3;
use rayon::prelude::*;
use serde::Serialize;

/// The energy of a net and its derivatives, as the solver needs them.
pub trait Objective: Sync {
    /// Energy, gradient of the internal energy, external loads P, and (if asked) the convexified
    /// Hessian of the total energy.
    fn evaluate(&self, x: &[Point], hessian: bool) -> Evaluation;
    /// Node pairs (a <= b) that may couple in the Hessian.
    fn coupled_pairs(&self) -> Vec<(usize, usize)>;
}

/// Hessian storage the solver reads block by block.
pub trait HessianBlocks {
    /// The 3x3 block coupling nodes `a` and `b` (a <= b).
    fn block(&self, a: usize, b: usize) -> Matrix3<f64>;
}

/// One evaluation of the objective.
pub struct Evaluation {
    /// Total energy (internal minus the work of the loads).
    pub energy: f64,
    /// Gradient of the internal energy per node (the internal forces F).
    pub internal: Vec<Vector>,
    /// External loads per node (P).
    pub external: Vec<Vector>,
    /// Hessian blocks of the internal energy, when asked for.
    pub hessian: Option<Box<dyn HessianBlocks>>,
}

/// Settings of the solver (builder style: `SolverSettings::default().max_iterations(80)`).
#[derive(Debug, Clone)]
pub struct SolverSettings {
    /// Iteration limit per solve.
    pub max_iterations: usize,
    /// Converged when |F - P| / max(|P|, |F|, |F at the start|) <= tolerance (seed 000 eq. 20:
    /// |F - P| / |P| <= 1e-4).
    pub tolerance: f64,
    /// Converged too when the energy changes by less than this (relative) over `stall_window`
    /// accepted steps.
    pub stall_tolerance: f64,
    /// Accepted steps over which the energy must stall.
    pub stall_window: usize,
    /// Initial Levenberg-Marquardt damping, relative to the Hessian's mean diagonal.
    pub initial_damping: f64,
    /// Largest damping before the solver gives up (stalled line search).
    pub max_damping: f64,
    /// The force the residual is measured against (N); default: the larger of the loads and the
    /// internal forces at the start. Refinement passes the kinematic net's, as given, so that
    /// moving its nodes onto a smooth tool (which stretches the fibres a little) does not
    /// loosen the test.
    pub force_scale: Option<f64>,
}

impl Default for SolverSettings {
    fn default() -> Self {
        SolverSettings {
            max_iterations: 100,
            tolerance: 1e-4,
            stall_tolerance: 1e-13,
            stall_window: 3,
            initial_damping: 1e-6,
            max_damping: 1e12,
            force_scale: None,
        }
    }
}

impl SolverSettings {
    /// Set the iteration limit.
    pub fn max_iterations(mut self, n: usize) -> Self {
        self.max_iterations = n;
        self
    }
    /// Set the residual tolerance.
    pub fn tolerance(mut self, t: f64) -> Self {
        self.tolerance = t;
        self
    }
}

/// One solver iteration, for the log.
#[derive(Debug, Clone, Serialize)]
pub struct IterationLog {
    /// Iteration number, from 1.
    pub iteration: usize,
    /// Energy after the iteration.
    pub energy: f64,
    /// Relative residual |F - P| after it.
    pub residual: f64,
    /// Length of the step taken.
    pub step: f64,
    /// Levenberg-Marquardt damping used.
    pub damping: f64,
    /// Nodes in contact.
    pub active_contacts: usize,
    /// Whether the step was accepted.
    pub accepted: bool,
    /// Interior-point iterations of the subproblem.
    pub qp_iterations: u32,
    /// Wall-clock time, ms.
    pub time_ms: f64,
}

/// How a solve ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Outcome {
    /// |F - P| / |P| below the tolerance.
    Converged,
    /// The energy stopped changing.
    Stalled,
    /// Iteration limit reached.
    IterationLimit,
    /// The damping grew past its limit without an acceptable step.
    LineSearchFailed,
    /// Clarabel could not solve a subproblem (infeasible constraints).
    SubproblemFailed,
}

/// What a solve did.
#[derive(Debug, Clone, Serialize)]
pub struct SolveReport {
    /// How the solve ended.
    pub outcome: Outcome,
    /// Energy at the start.
    pub energy_start: f64,
    /// Energy at the end.
    pub energy_end: f64,
    /// Relative residual at the end.
    pub residual: f64,
    /// One entry per iteration.
    pub iterations: Vec<IterationLog>,
    /// Wall-clock time, ms.
    pub time_ms: f64,
}

impl SolveReport {
    /// Whether the final state is an equilibrium (converged or stalled at a minimum).
    pub fn ok(&self) -> bool {
        matches!(self.outcome, Outcome::Converged | Outcome::Stalled)
    }
}

/// What the solver moves and how: each node's freedom, the tool for contact.
pub struct Constraints<'a> {
    /// How each node may move.
    pub freedom: Vec<Freedom>,
    /// Pressed, free or no contact.
    pub mode: ContactMode,
    /// Pressed nodes slide on it; free nodes stay out of it.
    pub tool: Option<&'a dyn ContactSurface>,
    /// Length scale for contact search (the net's spacing).
    pub spacing: f64,
}

/// Reduced (free) variables: node k's components start at `offset[k]` and number `bases[k].dofs`.
struct Reduction {
    offset: Vec<usize>,
    n: usize,
    /// Upper-triangular CSC pattern over the reduced variables.
    colptr: Vec<usize>,
    rowval: Vec<usize>,
    /// For each stored entry: (node a, node b, component p of a, component q of b).
    source: Vec<(u32, u32, u8, u8)>,
    /// Position of each column's diagonal entry.
    diag: Vec<usize>,
}

impl Reduction {
    fn new(freedom: &[Freedom], pairs: &[(usize, usize)]) -> Self {
        let mut offset = Vec::with_capacity(freedom.len());
        let mut n = 0;
        for f in freedom {
            offset.push(n);
            n += f.dofs();
        }
        let dofs: Vec<usize> = freedom.iter().map(Freedom::dofs).collect();
        // Column-wise lists of (row variable, source).
        let mut columns: Vec<Vec<(usize, (u32, u32, u8, u8))>> = vec![Vec::new(); n];
        for &(a, b) in pairs {
            let (a, b) = if a <= b { (a, b) } else { (b, a) };
            for p in 0..dofs[a] {
                for q in 0..dofs[b] {
                    let (r, c) = (offset[a] + p, offset[b] + q);
                    if a == b && p > q {
                        continue;
                    }
                    // Upper triangle: row <= column.
                    let (r, c, src) = if r <= c {
                        (r, c, (a as u32, b as u32, p as u8, q as u8))
                    } else {
                        (c, r, (a as u32, b as u32, p as u8, q as u8))
                    };
                    columns[c].push((r, src));
                }
            }
        }
        let mut colptr = vec![0];
        let mut rowval = Vec::new();
        let mut source = Vec::new();
        let mut diag = vec![usize::MAX; n];
        for (c, mut col) in columns.into_iter().enumerate() {
            col.sort_by_key(|e| e.0);
            col.dedup_by_key(|e| e.0);
            for (r, src) in col {
                if r == c {
                    diag[c] = rowval.len();
                }
                rowval.push(r);
                source.push(src);
            }
            colptr.push(rowval.len());
        }
        Reduction { offset, n, colptr, rowval, source, diag }
    }

    /// Reduced Hessian values B^T H B.
    fn values(&self, h: &dyn HessianBlocks, bases: &[NodeBasis]) -> Vec<f64> {
        let mut cache: Option<((u32, u32), Matrix3<f64>)> = None;
        self.source
            .iter()
            .map(|&(a, b, p, q)| {
                let blk = match cache {
                    Some((key, m)) if key == (a, b) => m,
                    _ => {
                        let m = bases[a as usize].basis.transpose()
                            * h.block(a as usize, b as usize)
                            * bases[b as usize].basis;
                        cache = Some(((a, b), m));
                        m
                    }
                };
                blk[(p as usize, q as usize)]
            })
            .collect()
    }

    fn reduce(&self, v: &[Vector], bases: &[NodeBasis]) -> Vec<f64> {
        let mut out = vec![0.0; self.n];
        for (k, b) in bases.iter().enumerate() {
            for p in 0..b.dofs {
                out[self.offset[k] + p] = b.dir(p).dot(&v[k]);
            }
        }
        out
    }

    fn expand(&self, y: &[f64], bases: &[NodeBasis]) -> Vec<Vector> {
        bases
            .iter()
            .enumerate()
            .map(|(k, b)| (0..b.dofs).fold(Vector::zeros(), |s, p| s + b.dir(p) * y[self.offset[k] + p]))
            .collect()
    }
}

/// The larger of the internal forces and the loads over the free directions.
fn start_forces(r: &Reduction, e: &Evaluation, bases: &[NodeBasis]) -> f64 {
    norm(&r.reduce(&e.internal, bases)).max(norm(&r.reduce(&e.external, bases)))
}

/// The force scale [`solve`] would use at `x` by default: the larger of the internal forces and
/// the loads over the free directions of `cons` there.
pub fn force_scale(objective: &dyn Objective, x: &[Point], cons: &Constraints) -> f64 {
    let e = objective.evaluate(x, false);
    start_forces(&Reduction::new(&cons.freedom, &[]), &e, &bases_at(cons, x, &e, None))
}

/// Each node's basis of motion at `x`, for the pushes of the evaluation there (on-tool nodes
/// pushed over the tool's open edge are held by it). `feet`: the on-tool nodes' feet when the
/// caller has just found them, else they are located here.
fn bases_at(cons: &Constraints, x: &[Point], e: &Evaluation, feet: Option<&[Option<Foot>]>) -> Vec<NodeBasis> {
    let (internal, external) = (&e.internal, &e.external);
    cons.freedom
        .par_iter()
        .enumerate()
        .map(|(k, f)| {
            let foot = match (f.on_tool(), feet.and_then(|feet| feet[k]), cons.tool) {
                (false, _, _) => None,
                (true, Some(known), _) => Some(known),
                (true, None, tool) => tool.map(|t| t.locate(&x[k])),
            };
            f.basis(foot.as_ref(), &(external[k] - internal[k]))
        })
        .collect()
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

/// Minimise the objective from `x` (modified in place to the last accepted state).
pub fn solve(objective: &dyn Objective, x: &mut [Point], cons: &Constraints, settings: &SolverSettings) -> SolveReport {
    let start = std::time::Instant::now();
    let reduction = Reduction::new(&cons.freedom, &objective.coupled_pairs());
    let movable: Vec<bool> = cons.freedom.iter().map(|f| f.dofs() > 0).collect();
    let rows_at = |x: &[Point]| -> Vec<ContactRow> {
        match (cons.mode, cons.tool) {
            (ContactMode::Free, Some(tool)) => contact_rows(tool, x, &movable, cons.spacing),
            _ => Vec::new(),
        }
    };
    let mut eval = objective.evaluate(x, true);
    let mut bases = bases_at(cons, x, &eval, None);
    let mut rows = rows_at(x);
    let energy_start = eval.energy;
    let mut iterations = Vec::new();
    let mut damping = settings.initial_damping;
    let mut history = vec![eval.energy];
    // Force scale: the larger of the loads and the internal forces at the start, so that a net
    // relaxing towards zero force with no load (P = 0) still measures its progress.
    // ... and never below the rounding noise of the forces: what would move the nodes by a
    // FORCE_NOISE fraction of the spacing through the model's mean stiffness.
    let mean_stiffness = {
        let h = reduction.values(eval.hessian.as_deref().expect("hessian requested"), &bases);
        reduction.diag.iter().filter(|&&k| k != usize::MAX).map(|&k| h[k].abs()).sum::<f64>()
            / reduction.n.max(1) as f64
    };
    let noise = FORCE_NOISE * mean_stiffness * cons.spacing * (reduction.n as f64).sqrt();
    let force_scale = settings.force_scale.unwrap_or_else(|| start_forces(&reduction, &eval, &bases)).max(noise);
    let energy_noise = FORCE_NOISE * mean_stiffness * cons.spacing * cons.spacing * reduction.n as f64;
    let mut residual = residual(&reduction, &eval, &bases, &rows, cons.spacing, force_scale);
    let mut outcome = Outcome::IterationLimit;
    for it in 0..settings.max_iterations {
        if residual <= settings.tolerance || reduction.n == 0 {
            outcome = Outcome::Converged;
            break;
        }
        let t_it = std::time::Instant::now();
        let grad: Vec<Vector> = eval.internal.iter().zip(&eval.external).map(|(f, p)| f - p).collect();
        let g = reduction.reduce(&grad, &bases);
        let mut pvals = reduction.values(eval.hessian.as_deref().expect("hessian requested"), &bases);
        let mean_diag = reduction.diag.iter().filter(|&&k| k != usize::MAX).map(|&k| pvals[k].abs()).sum::<f64>()
            / reduction.n.max(1) as f64;
        let scale = mean_diag.max(f64::MIN_POSITIVE);
        // Try steps with growing damping until one lowers the energy.
        let mut accepted = false;
        let mut stationary = false;
        let mut qp_iterations = 0;
        let mut step_norm = 0.0;
        let mut qp_failed = false;
        while damping <= settings.max_damping {
            for &k in reduction.diag.iter() {
                if k != usize::MAX {
                    pvals[k] += damping * scale;
                }
            }
            let qp = solve_qp(&reduction, &pvals, &g, &rows, &bases);
            let predicted = qp.as_ref().map(|(y, _)| -(dot(&g, y) + 0.5 * quad(&reduction, &pvals, y)));
            for &k in reduction.diag.iter() {
                if k != usize::MAX {
                    pvals[k] -= damping * scale;
                }
            }
            let (Some((y, iters)), Some(predicted)) = (qp, predicted) else {
                // A failed subproblem: more damping conditions it better.
                qp_failed = true;
                damping *= 10.0;
                continue;
            };
            qp_failed = false;
            qp_iterations += iters;
            let floor = ENERGY_ROUNDING * eval.energy.abs().max(energy_noise).max(f64::MIN_POSITIVE);
            if predicted <= floor {
                stationary = true; // the model sees nothing left to gain
                break;
            }
            let delta = reduction.expand(&y, &bases);
            let mut trial: Vec<Point> = x.iter().zip(&delta).map(|(p, d)| p + d).collect();
            // Pressed nodes back onto the tool; their feet also give the next bases.
            let feet: Option<Vec<Option<Foot>>> = match (cons.mode, cons.tool) {
                (ContactMode::Pressed, Some(tool)) => Some(
                    trial
                        .par_iter_mut()
                        .zip(&cons.freedom)
                        .map(|(p, f)| {
                            f.on_tool().then(|| {
                                let foot = tool.locate(p);
                                *p = foot.point;
                                foot
                            })
                        })
                        .collect(),
                ),
                _ => None,
            };
            let trial_eval = objective.evaluate(&trial, true);
            let actual = eval.energy - trial_eval.energy;
            if actual >= ACCEPT_RATIO * predicted || (actual >= 0.0 && predicted <= 100.0 * floor) {
                step_norm = norm(&y);
                x.copy_from_slice(&trial);
                eval = trial_eval;
                bases = bases_at(cons, x, &eval, feet.as_deref());
                rows = rows_at(x);
                if actual >= 0.75 * predicted {
                    damping = (damping / 4.0).max(1e-12);
                }
                accepted = true;
                break;
            }
            damping *= 5.0;
        }
        residual = self::residual(&reduction, &eval, &bases, &rows, cons.spacing, force_scale);
        iterations.push(IterationLog {
            iteration: it + 1,
            energy: eval.energy,
            residual,
            step: step_norm,
            damping,
            active_contacts: rows.iter().filter(|r| r.gap <= ACTIVE_GAP * cons.spacing).count(),
            accepted,
            qp_iterations,
            time_ms: t_it.elapsed().as_secs_f64() * 1e3,
        });
        if stationary {
            outcome = if residual <= settings.tolerance { Outcome::Converged } else { Outcome::Stalled };
            break;
        }
        if !accepted {
            outcome = if qp_failed { Outcome::SubproblemFailed } else { Outcome::LineSearchFailed };
            break;
        }
        history.push(eval.energy);
        if residual <= settings.tolerance {
            outcome = Outcome::Converged;
            break;
        }
        if history.len() > settings.stall_window {
            let old = history[history.len() - 1 - settings.stall_window];
            if (old - eval.energy).abs() <= settings.stall_tolerance * old.abs().max(eval.energy.abs()) {
                outcome = Outcome::Stalled;
                break;
            }
        }
    }
    SolveReport {
        outcome,
        energy_start,
        energy_end: eval.energy,
        residual,
        iterations,
        time_ms: start.elapsed().as_secs_f64() * 1e3,
    }
}

/// A step is accepted when the energy falls by at least this fraction of the predicted fall.
const ACCEPT_RATIO: f64 = 0.1;
/// Relative energy changes below this are rounding.
const ENERGY_ROUNDING: f64 = 1e-14;
/// Relative size of the rounding noise in forces and energies (see `solve`).
const FORCE_NOISE: f64 = 1e-10;
/// Subproblems with at least this many variables are factorised on all threads.
const PARALLEL_FACTORISATION_MIN: usize = 20_000;
/// A contact is active (the tool takes the node's push into it) when its gap is below this
/// fraction of the spacing: the interior-point subproblems leave touching nodes 1e-7..1e-5
/// spacings off the tool (measured on a free drape of a 21 x 21 net), and a node a ten-thousandth
/// of a cell off the tool touches it for any purpose of drape.
const ACTIVE_GAP: f64 = 1e-4;

/// |F - P - R| / max(|F|, |P|, `floor`) over the free directions, where R are the contact
/// reactions (the part of F - P pushing active contact nodes into the tool, which the tool takes)
/// and `floor` the force scale at the start of the solve.
fn residual(r: &Reduction, e: &Evaluation, bases: &[NodeBasis], rows: &[ContactRow], spacing: f64, floor: f64) -> f64 {
    let mut unbalanced: Vec<Vector> = e.internal.iter().zip(&e.external).map(|(f, p)| f - p).collect();
    for row in rows.iter().filter(|row| row.gap <= ACTIVE_GAP * spacing) {
        let g = &mut unbalanced[row.node];
        let push = row.normal.dot(g);
        if push > 0.0 {
            *g -= row.normal * push;
        }
    }
    let num = norm(&r.reduce(&unbalanced, bases));
    let den = norm(&r.reduce(&e.internal, bases)).max(norm(&r.reduce(&e.external, bases))).max(floor);
    num / den.max(f64::MIN_POSITIVE)
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// y^T P y for the upper-triangular CSC P.
fn quad(r: &Reduction, p: &[f64], y: &[f64]) -> f64 {
    let mut s = 0.0;
    for c in 0..r.n {
        for k in r.colptr[c]..r.colptr[c + 1] {
            let row = r.rowval[k];
            let v = p[k] * y[row] * y[c];
            s += if row == c { v } else { 2.0 * v };
        }
    }
    s
}

/// Solve min 1/2 y^T P y + g^T y subject to the linearised contact rows, with Clarabel.
/// Returns the step and Clarabel's iteration count, or None if it failed.
fn solve_qp(
    r: &Reduction,
    pvals: &[f64],
    g: &[f64],
    rows: &[ContactRow],
    bases: &[NodeBasis],
) -> Option<(Vec<f64>, u32)> {
    let p = CscMatrix::new(r.n, r.n, r.colptr.clone(), r.rowval.clone(), pvals.to_vec());
    // Contact: normal . (B_k y_k) + gap >= 0  ->  -normal^T B_k y_k + s = gap, s >= 0.
    let mut cols: Vec<Vec<(usize, f64)>> = vec![Vec::new(); r.n];
    let mut b = Vec::with_capacity(rows.len());
    for (m, row) in rows.iter().enumerate() {
        let basis = &bases[row.node];
        for q in 0..basis.dofs {
            let a = -row.normal.dot(&basis.dir(q));
            if a != 0.0 {
                cols[r.offset[row.node] + q].push((m, a));
            }
        }
        b.push(row.gap);
    }
    let mut colptr = vec![0];
    let mut rowval = Vec::new();
    let mut nzval = Vec::new();
    for col in cols {
        for (m, a) in col {
            rowval.push(m);
            nzval.push(a);
        }
        colptr.push(rowval.len());
    }
    let a = CscMatrix::new(rows.len(), r.n, colptr, rowval, nzval);
    let cones: Vec<SupportedConeT<f64>> = if rows.is_empty() { vec![] } else { vec![NonnegativeConeT(rows.len())] };
    let settings = DefaultSettingsBuilder::default()
        .verbose(false)
        .max_iter(100)
        // Ruiz equilibration makes these subproblems (stiff fibres beside soft shear, a few
        // directions per node) far harder: 10-30 interior-point iterations instead of one
        // factorisation for a pressed net (measured with `drape bench --refine`).
        .equilibrate_enable(false)
        .direct_solve_method("faer".to_string())
        // Threads only pay for large factorisations; on small ones they cost more in switching
        // than they save (`perf` on a 21 x 21 free drape: a quarter of the time in the kernel).
        .max_threads(if r.n >= PARALLEL_FACTORISATION_MIN { 0 } else { 1 })
        .build()
        .ok()?;
    let mut solver = DefaultSolver::new(&p, g, &a, &b, &cones, settings).ok()?;
    solver.solve();
    match solver.solution.status {
        SolverStatus::Solved | SolverStatus::AlmostSolved => {
            Some((solver.solution.x.clone(), solver.solution.iterations))
        }
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::shapes;

    /// 1/2 sum k |x - target|^2: each node pulled to its target by a spring.
    struct Springs {
        targets: Vec<Point>,
        k: f64,
    }
    struct Diagonal(f64);
    impl HessianBlocks for Diagonal {
        fn block(&self, a: usize, b: usize) -> Matrix3<f64> {
            if a == b {
                Matrix3::identity() * self.0
            } else {
                Matrix3::zeros()
            }
        }
    }
    impl Objective for Springs {
        fn evaluate(&self, x: &[Point], hessian: bool) -> Evaluation {
            let internal: Vec<Vector> = x.iter().zip(&self.targets).map(|(p, t)| (p - t) * self.k).collect();
            let energy = x.iter().zip(&self.targets).map(|(p, t)| 0.5 * self.k * (p - t).norm_squared()).sum();
            Evaluation {
                energy,
                internal,
                external: vec![Vector::zeros(); x.len()],
                hessian: hessian.then(|| Box::new(Diagonal(self.k)) as Box<dyn HessianBlocks>),
            }
        }
        fn coupled_pairs(&self) -> Vec<(usize, usize)> {
            (0..self.targets.len()).map(|k| (k, k)).collect()
        }
    }

    #[test]
    fn unconstrained_springs_reach_their_targets_and_fixed_nodes_stay() {
        let targets = vec![Point::new(1.0, 2.0, 3.0), Point::new(-1.0, 0.5, 0.0), Point::new(0.0, 0.0, 1.0)];
        let obj = Springs { targets: targets.clone(), k: 100.0 };
        let mut x = vec![Point::origin(); 3];
        let freedom = vec![Freedom::Free, Freedom::Fixed, Freedom::Line(Vector::z())];
        let cons = Constraints { freedom, mode: ContactMode::None, tool: None, spacing: 1.0 };
        let report = solve(&obj, &mut x, &cons, &SolverSettings::default().tolerance(1e-10));
        assert!(report.ok(), "{report:?}");
        assert!((x[0] - targets[0]).norm() < 1e-6);
        assert_eq!(x[1], Point::origin());
        assert!((x[2] - Point::new(0.0, 0.0, 1.0)).norm() < 1e-6);
        assert!(report.energy_end <= report.energy_start);
    }

    #[test]
    fn free_contact_keeps_nodes_out_of_the_tool() {
        let tool = shapes::plate(4.0, 4.0, 4, 4).into_surface().unwrap();
        // Springs pull the nodes 1 m below the plate; contact must stop them on it.
        let targets = vec![Point::new(0.2, 0.1, -1.0), Point::new(-0.5, 0.3, -0.5), Point::new(0.1, 0.1, 2.0)];
        let obj = Springs { targets, k: 10.0 };
        let mut x = vec![Point::new(0.0, 0.0, 0.5), Point::new(0.0, 0.0, 0.3), Point::new(0.0, 0.0, 0.1)];
        let cons =
            Constraints { freedom: vec![Freedom::Free; 3], mode: ContactMode::Free, tool: Some(&tool), spacing: 1.0 };
        let report = solve(&obj, &mut x, &cons, &SolverSettings::default().tolerance(1e-10));
        assert!(report.ok(), "{report:?}");
        assert!(x[0].z.abs() < 1e-6 && (x[0].x - 0.2).abs() < 1e-6, "{}", x[0]);
        assert!(x[1].z.abs() < 1e-6);
        assert!((x[2].z - 2.0).abs() < 1e-6);
    }

    #[test]
    fn pressed_nodes_slide_on_the_tool() {
        let tool = shapes::hemisphere(1.0, 20).into_surface().unwrap();
        // A target off the sphere: the pressed node ends at the closest point of the tool to it.
        let target = Point::new(0.6, 0.0, 1.2);
        let obj = Springs { targets: vec![target], k: 1.0 };
        let start = tool.closest_point(&Point::new(0.0, 0.0, 1.0));
        let mut x = vec![start.point];
        let cons =
            Constraints { freedom: vec![Freedom::OnTool], mode: ContactMode::Pressed, tool: Some(&tool), spacing: 0.1 };
        let report = solve(&obj, &mut x, &cons, &SolverSettings::default());
        assert!(report.ok(), "{report:?}");
        assert!(tool.closest_point(&x[0]).distance < 1e-12);
        // The closest point of the (faceted) sphere to the target: along the target's direction.
        let expected = tool.closest_point(&target).point;
        assert!((x[0] - expected).norm() < 1e-4, "{} vs {}", x[0], expected);
    }

    #[test]
    fn pressed_nodes_slide_on_the_smooth_patches() {
        let tool = shapes::hemisphere(1.0, 20).into_surface().unwrap();
        let smooth = crate::geometry::SmoothSurface::new(&tool);
        let target = Point::new(0.6, 0.0, 1.2);
        let obj = Springs { targets: vec![target], k: 1.0 };
        let mut x = vec![smooth.project(&Point::new(0.0, 0.0, 1.0)).point];
        let cons = Constraints {
            freedom: vec![Freedom::OnTool],
            mode: ContactMode::Pressed,
            tool: Some(&smooth),
            spacing: 0.1,
        };
        let report = solve(&obj, &mut x, &cons, &SolverSettings::default().tolerance(1e-10));
        assert!(report.ok(), "{report:?}");
        let s = smooth.project(&x[0]);
        assert!((s.point - x[0]).norm() < 1e-12);
        // At the constrained minimum the spring pulls along the surface normal...
        // (to the energy's rounding: the solve stalls at |F - P| / |P| ~ 5e-8).
        let misalignment = (target - x[0]).normalize().cross(&s.normal).norm();
        assert!(misalignment < 1e-6, "{misalignment:e}");
        // ... which, on patches following the sphere, is near the sphere's answer: closer than
        // the facets get.
        let sphere = Point::from(target.coords.normalize());
        let facets = tool.closest_point(&target).point;
        assert!((x[0] - sphere).norm() < (facets - sphere).norm() / 5.0, "{} vs {}", x[0], sphere);
    }

    #[test]
    fn pressed_nodes_pulled_over_the_tool_edge_are_held_by_it() {
        // A 2 m x 2 m plate (|x|, |y| <= 1): springs pull one node beyond the edge x = 1 and
        // another beyond the corner (1, 1); the edge holds the first (it slides along the edge to
        // y = 0.3), the corner holds the second.
        let tool = shapes::plate(2.0, 2.0, 4, 4).into_surface().unwrap();
        let targets = vec![Point::new(1.5, 0.3, 0.0), Point::new(1.4, 1.6, 0.0)];
        let obj = Springs { targets, k: 1.0 };
        let mut x = vec![Point::new(0.2, 0.0, 0.0), Point::new(0.5, 0.5, 0.0)];
        let cons = Constraints {
            freedom: vec![Freedom::OnTool; 2],
            mode: ContactMode::Pressed,
            tool: Some(&tool),
            spacing: 0.1,
        };
        let report = solve(&obj, &mut x, &cons, &SolverSettings::default().tolerance(1e-10));
        assert_eq!(report.outcome, Outcome::Converged, "{report:?}");
        assert!((x[0] - Point::new(1.0, 0.3, 0.0)).norm() < 1e-9, "{}", x[0]);
        assert!((x[1] - Point::new(1.0, 1.0, 0.0)).norm() < 1e-9, "{}", x[1]);
    }
}
