//! Equilibrium of a net: Newton steps on the energy over each node's free directions,
//! regularised by pseudo-transient continuation and kept on the curved valley of stiff fibres by
//! second-order corrections. Every subproblem is a quadratic model solved by Clarabel
//! ([`super::qp::QpEngine`]).
//!
//! One iteration at the state x with forces g = F - P:
//! 1. Each node's basis of motion B (fixed, a line, the tool's tangent plane, free) from its
//!    freedom and contact; the residual is B^T g (the tool's and the held nodes' reactions are
//!    not residual). Converged when |B^T g| <= tolerance |P| (seed 000 eq. 20).
//! 2. The model uses the exact Hessian H of the energy plus a shift `sigma M` (M the lumped
//!    nodal masses): an implicit pseudo-time step of the fabric's own dynamics with
//!    `sigma = 1/dt^2`. Far from equilibrium the shift keeps the model convex and the step
//!    physical (a hanging sheet falls as it would, a wrinkle picks a stable side); as the
//!    residual falls the step grows (sigma -> 0) and the iteration becomes Newton's, with its
//!    quadratic convergence. A step that is not a descent direction of a convex model (negative
//!    curvature) raises the shift.
//! 3. The trial state moves pressed nodes back onto the tool and free nodes that would enter it
//!    onto its surface. On a moving tool (on one standing still: a node the tool keeps letting
//!    go), a free node touching it that the step moves into it is first held on the tool and the
//!    step solved again ([`block_entering`]: its pull was outward where the model was built, so
//!    the model knew nothing of the tool there). It is accepted
//!    when the energy falls by a fair part of the model's prediction. If not, a second-order
//!    correction (a Newton step from the trial state with the same model) is tried first:
//!    stiff, nearly inextensible fibres make the energy a narrow
//!    curved valley, a straight step leaves it to second order and the fibres' stiffness
//!    multiplies that error; the correction steps back into the valley. Only then is the shift
//!    raised (a shorter, more cautious step). After a refusal the other core solves the rung
//!    after the next meanwhile ([`QpEngine::solve_ahead`]); the path is the same either way.
//! 4. At convergence, a second-order check ([`super::stability`]): the least eigenvalue of the
//!    exact Hessian over the free directions against a positive definite reference. A saddle
//!    (an unstable equilibrium) is reported; with [`SolverSettings::escape_saddles`] the state
//!    is moved along its negative curvature and the iterations go on from there.
use super::contact::{ContactMode, ContactSurface, Foot, Freedom, NodeBasis};
pub use super::qp::HessianBlocks;
use super::qp::{dot, norm, QpEngine, QpFailure, Reduction};
use super::stability::{
    least_mode, positive_definite, spread, CheckMethod, Escape, LeastEigenvalue, LeastMode, Stability, StabilityCheck,
    LANCZOS_ITERATIONS,
};
use crate::geometry::{Point, Vector};
use rayon::prelude::*;
use serde::Serialize;

/// The energy of a net and its derivatives, as the solver needs them.
pub trait Objective: Sync {
    /// Energy, internal forces, external loads P, and (if asked) the exact Hessian.
    fn evaluate(&self, x: &[Point], hessian: bool) -> Evaluation;
    /// A positive semidefinite approximation of the Hessian at `x` (each element's curvature
    /// with its negative parts dropped), for steps where the exact one curves down; None: the
    /// objective has none (the shift alone then handles negative curvature).
    fn convex_hessian(&self, _x: &[Point]) -> Option<Box<dyn HessianBlocks>> {
        None
    }
    /// The total energy only (line searches).
    fn energy(&self, x: &[Point]) -> f64 {
        self.evaluate(x, false).energy
    }
    /// Node pairs (a <= b) that may couple in the Hessian, (k, k) included.
    fn coupled_pairs(&self) -> Vec<(usize, usize)>;
    /// Lumped mass of each node (kg): the metric of the pseudo-time steps.
    fn masses(&self) -> Vec<f64>;
    /// The forces that the stiff, constraint-like terms (fibre stretch) gain to second order
    /// between `x` and `trial`: what a second-order correction must undo (None: no correction).
    fn second_order_forces(&self, _x: &[Point], _trial: &[Point]) -> Option<Vec<Vector>> {
        None
    }
    /// The internal forces split by energy term, for naming what dominates where a solve
    /// fails (empty if the objective cannot split them).
    fn term_forces(&self, _x: &[Point]) -> Vec<(&'static str, Vec<Vector>)> {
        Vec::new()
    }
    /// How far any node may move in one step from `x` (m), where the objective's data hold only
    /// so far (a lagged friction's normal forces, for what is left of the slide they were
    /// taken for); None: no bound but the solver's own reach.
    fn step_bound(&self, _x: &[Point]) -> Option<f64> {
        None
    }
    /// Whether the state `x` has run away from any equilibrium (a ply sliding off over the
    /// tool, [`super::friction::Frictional`]): the solve then stops with [`Outcome::Slides`].
    fn runaway(&self, _x: &[Point]) -> bool {
        false
    }
}

/// One evaluation of the objective.
pub struct Evaluation {
    /// Total energy (internal minus the work of the loads).
    pub energy: f64,
    /// Gradient of the internal energy per node (the internal forces F).
    pub internal: Vec<Vector>,
    /// External loads per node (P).
    pub external: Vec<Vector>,
    /// The exact Hessian of the energy, when asked for.
    pub hessian: Option<Box<dyn HessianBlocks>>,
}

/// Settings of the solver (builder style: `SolverSettings::default().max_iterations(80)`).
#[derive(Debug, Clone)]
pub struct SolverSettings {
    /// Most iterations of one solve.
    pub max_iterations: usize,
    /// Converged when |F - P| <= tolerance |P| over the free directions (seed 000 eq. 20).
    pub tolerance: f64,
    /// The force |F - P| is measured against when there are no loads (|P| = 0), in N; default:
    /// the internal forces over the free directions at the start.
    pub force_scale: Option<f64>,
    /// The forces the tools exert on the ply (N, their norm over the nodes), where they dwarf its
    /// weight (a punch, a binder): |F - P| is measured against the larger of them and |P|.
    pub reaction_scale: Option<f64>,
    /// Initial pseudo-transient shift, relative to the model's mean stiffness over the mean
    /// nodal mass (0 starts with Newton's step).
    pub initial_shift: f64,
    /// Try a second-order correction before shortening a rejected step.
    pub second_order_correction: bool,
    /// At convergence, check that the state is a minimum (no direction of negative curvature,
    /// [`super::stability`]); the report says what it found.
    pub stability_check: bool,
    /// With the check: compute the least eigenvalue (Lanczos) also where one Cholesky
    /// factorisation proves a minimum. Off by default: the verdict is the same, and the figure
    /// costs a factorisation and a few tens of solves (1.7 s of the 301 x 301 bench).
    pub stability_eigenvalue: bool,
    /// With the check: move off a saddle along its negative curvature and iterate on to a state
    /// of lower energy. Off by default: on pressed plies the states below the saddles found so
    /// far slide fabric past the tool's open edges onto the smooth surface's continuation (see
    /// docs/ARCHITECTURE.md, "picks a stable equilibrium"), at tens of times the solve's time.
    pub escape_saddles: bool,
    /// Stop early, with [`Outcome::Settled`], once an accepted iteration moves the nodes by at
    /// most this share of the largest move of one iteration so far (from the second iteration
    /// on): a probe of how far equilibrium lies, not a solve (`method = "auto"`).
    pub settle_share: Option<f64>,
}

impl Default for SolverSettings {
    fn default() -> Self {
        SolverSettings {
            max_iterations: 100,
            tolerance: 1e-4,
            force_scale: None,
            reaction_scale: None,
            initial_shift: 1e-6,
            second_order_correction: true,
            stability_check: true,
            stability_eigenvalue: false,
            escape_saddles: false,
            settle_share: None,
        }
    }
}

impl SolverSettings {
    /// Sets the iteration limit.
    pub fn max_iterations(mut self, n: usize) -> Self {
        self.max_iterations = n;
        self
    }
    /// Sets the relative residual tolerance.
    pub fn tolerance(mut self, t: f64) -> Self {
        self.tolerance = t;
        self
    }
    /// Switches the stability check at convergence on or off.
    pub fn stability_check(mut self, on: bool) -> Self {
        self.stability_check = on;
        self
    }
    /// Asks the check for the least eigenvalue even of a minimum (see
    /// [`SolverSettings::stability_eigenvalue`]).
    pub fn stability_eigenvalue(mut self, on: bool) -> Self {
        self.stability_eigenvalue = on;
        self
    }
    /// Switches escapes from saddles on or off (with the check).
    pub fn escape_saddles(mut self, on: bool) -> Self {
        self.escape_saddles = on;
        self
    }
}

/// One solver iteration, for the log.
#[derive(Debug, Clone, Serialize)]
pub struct IterationLog {
    /// Iteration number, from 1.
    pub iteration: usize,
    /// Energy after the iteration (J).
    pub energy: f64,
    /// |F - P| / |P| after the iteration.
    pub residual: f64,
    /// Largest node displacement of the accepted step, in spacings.
    pub step: f64,
    /// The pseudo-transient shift used, relative (see [`SolverSettings::initial_shift`]).
    pub shift: f64,
    /// Nodes held against the tool by free contact.
    pub active_contacts: usize,
    /// Whether a step was taken.
    pub accepted: bool,
    /// Whether the accepted step needed a second-order correction.
    pub corrected: bool,
    /// Clarabel subproblems solved in the iteration.
    pub subproblems: u32,
    /// Of them: solved by conjugate gradients on an earlier factorisation (no new one).
    pub lagged: u32,
    /// Of them: solved on the other core while the one before was solved
    /// ([`QpEngine::solve_ahead`]: a refused step's next rung that cost no wait).
    pub ahead: u32,
    /// Of the iteration's time: assembling the quadratic models (energy, gradient and Hessian
    /// at the new state, reduced onto the free directions), ms.
    pub model_ms: f64,
    /// ... solving them (Clarabel), ms.
    pub solve_ms: f64,
    /// ... trying steps (moving nodes onto the tool, energies), ms.
    pub trial_ms: f64,
    /// Wall-clock time of the iteration.
    pub time_ms: f64,
}

/// How a solve ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Outcome {
    /// |F - P| / |P| below the tolerance.
    Converged,
    /// The energy stopped falling (at rounding) with the residual above the tolerance.
    Stalled,
    /// Iteration limit reached.
    IterationLimit,
    /// No step lowered the energy, however short.
    LineSearchFailed,
    /// Clarabel could not solve a subproblem.
    SubproblemFailed,
    /// Stopped as asked once the nodes settled ([`SolverSettings::settle_share`]): a probe.
    Settled,
    /// The ply slid away over the tool ([`Objective::runaway`]): nothing holds it there, or
    /// friction is too weak to (no equilibrium).
    Slides,
    /// Every solve of an increment balanced its forces, but the friction's normal forces kept
    /// changing from one solve to the next ([`super::friction::MAX_LAGS`]).
    FrictionUnsettled,
}

impl Outcome {
    /// Its name in files (`converged`, `slides`, ...).
    pub fn name(self) -> &'static str {
        match self {
            Outcome::Converged => "converged",
            Outcome::Stalled => "stalled",
            Outcome::IterationLimit => "iteration_limit",
            Outcome::LineSearchFailed => "line_search_failed",
            Outcome::SubproblemFailed => "subproblem_failed",
            Outcome::Settled => "settled",
            Outcome::Slides => "slides",
            Outcome::FrictionUnsettled => "friction_unsettled",
        }
    }

    /// What the outcome means, for people.
    pub fn describe(self) -> &'static str {
        match self {
            Outcome::Converged => "converged",
            Outcome::Stalled => "stalled: the energy stopped falling before the forces balanced",
            Outcome::IterationLimit => "iteration limit reached before the forces balanced",
            Outcome::LineSearchFailed => "no step lowered the energy, however short",
            Outcome::SubproblemFailed => "a quadratic subproblem could not be solved",
            Outcome::Settled => "stopped once the nodes settled (a probe, not an equilibrium)",
            Outcome::Slides => "slides: nothing holds the ply where it is on the tool (no equilibrium)",
            Outcome::FrictionUnsettled => "the friction's normal forces did not settle",
        }
    }
}

/// A node where the forces do not balance, for the failure report.
#[derive(Debug, Clone, Serialize)]
pub struct UnbalancedNode {
    /// Node index (`i * nv + j` on a grid).
    pub node: usize,
    /// |F - P| over the node's free directions (N).
    pub force: f64,
    /// The energy term with the largest force over the node's free directions there.
    pub dominant_term: Option<&'static str>,
}

/// What a solve did.
#[derive(Debug, Clone, Serialize)]
pub struct SolveReport {
    /// How it ended.
    pub outcome: Outcome,
    /// Energy at the start (J).
    pub energy_start: f64,
    /// Energy at the end (J).
    pub energy_end: f64,
    /// |F - P| / |P| at the end.
    pub residual: f64,
    /// The force the residual is measured against (N): |P|, or the force scale without loads.
    pub force_scale: f64,
    /// One entry per iteration.
    pub iterations: Vec<IterationLog>,
    /// Wall-clock time of the solve.
    pub time_ms: f64,
    /// Where the forces are furthest from balance, largest first (empty when converged).
    pub unbalanced: Vec<UnbalancedNode>,
    /// What Clarabel said of the last subproblem that failed, if the solve ended on one.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub subproblem_status: Option<String>,
    /// The second-order check of the converged state (absent when switched off or not
    /// converged). A converged state it finds a saddle it could not escape stays `Converged`
    /// (the forces balance) with the verdict `saddle` here.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stability: Option<StabilityCheck>,
}

impl SolveReport {
    /// Whether the final state is an equilibrium to the tolerance.
    pub fn ok(&self) -> bool {
        self.outcome == Outcome::Converged
    }
    /// Whether the final state was checked and found a saddle (an unstable equilibrium).
    pub fn saddle(&self) -> bool {
        self.stability.as_ref().is_some_and(|c| c.verdict == Stability::Saddle)
    }
}

/// What the solver moves and how: each node's freedom, the tool for contact.
pub struct Constraints<'a> {
    /// How each node may move.
    pub freedom: Vec<Freedom>,
    /// How the net meets the tool.
    pub mode: ContactMode,
    /// Pressed nodes slide on it; free nodes stay out of it.
    pub tool: Option<&'a dyn ContactSurface>,
    /// Length scale for contact search and step sizes (the net's spacing).
    pub spacing: f64,
    /// Per node, the node whose freedoms it shares (stitched seams); None: each its own.
    pub stitched: Option<Vec<usize>>,
    /// Free contact only: a node the tool holds up stays where it touches (no sliding; seed
    /// 000's tables restrain the nodes on them) until the fabric pulls it off again by more
    /// than [`STICK_RELEASE`] of its own load.
    pub stick: bool,
}

/// After an exact-model step that moved no node further than this (spacings), the next model is
/// solved on the last factorisation first ([`QpEngine::solve_near`]).
const LAGGED_STEP_SPACINGS: f64 = 0.01;
/// Below this residual the exact model is tried first even if the last step needed the convex
/// one: near equilibrium Newton's step converges quadratically.
const EXACT_FIRST_RESIDUAL: f64 = 1e-2;
/// The convex model takes over from an indefinite exact one and stays while the residual is
/// above [`EXACT_FIRST_RESIDUAL`]. Where it creeps (its steps are tiny at the smallest shift: the
/// elements' convex parts are far stiffer than the energy along the way down) the exact model
/// is tested: when H - s C is positive definite, s this fraction (C the convex model with the
/// stability check's small mass shift), the exact model is tried first again.
const STIFF_EXACT: f64 = 1e-2;
/// The convex model is creeping, not held back by the shift, only when the shift is below
/// this (relative).
const EXACT_TEST_SHIFT: f64 = 1e-6;
/// Exact-model steps taken on that test's word must cut the residual by this factor every
/// [`EXACT_TRIAL_ITERATIONS`] iterations, else the convex model takes over again (on the
/// double dome's +90 deg ply a row of nodes at the tool's open edge takes turns being held and
/// the exact model creeps as well).
const EXACT_TRIAL_FALL: f64 = 0.5;
/// See [`EXACT_TRIAL_FALL`].
const EXACT_TRIAL_ITERATIONS: usize = 10;
/// Convex steps to wait after a failed stiffness test or exact trial at most (the wait doubles
/// each time).
const MAX_EXACT_TEST_WAIT: usize = 64;
/// A tiny step (under [`LAGGED_STEP_SPACINGS`]) whose energy falls by at least this share of
/// the predicted fall but below [`GOOD_RATIO`] is middling: the shift neither falls nor rises
/// after it ...
const MIDDLING_RATIO: f64 = 0.2;
/// ... unless this many come in a row: the shift alone then holds the steps back along a soft
/// mode and it halves. (The double dome's +45 ply formed coarse to fine crept 80 iterations at
/// its 5 mm level, each moving the free corners of its blank 0.005 spacings at a fixed shift;
/// with this, 179 iterations -> 118, the same net to 0.01 deg.)
const MIDDLING_RUN: usize = 3;
/// A step is accepted when the energy falls by at least this fraction of the predicted fall.
const ACCEPT_RATIO: f64 = 1e-4;
/// Steps whose energy change agrees with the model this well let the shift fall.
const GOOD_RATIO: f64 = 0.5;
/// Relative size of rounding in energies.
const ENERGY_ROUNDING: f64 = 1e-13;
/// Energy changes within this many times the rounding are not told from it: there steps are
/// judged by the forces instead.
const ROUNDING_BAND: f64 = 100.0;
/// A contact is active (the tool takes the node's push into it) when its gap is below this
/// fraction of the spacing.
const ACTIVE_GAP: f64 = 1e-9;
/// With `stick`, a node held where it touches the tool is let go only when pulled off by more
/// than this share of its own load. Let go at any pull, the nodes just inside the square
/// table's rim, whose small pull changes sign with every step, were let go and caught again
/// each iteration: the 4 mm table crept 856 iterations; with 0.1, 327, to an energy 0.03%
/// lower (0.01: 806).
pub const STICK_RELEASE: f64 = 0.1;
/// Steps whose gain is lost in rounding are shortened at most this many times, each time
/// without balancing the forces better, before the solve is called stalled.
const ROUNDING_RETRIES: usize = 4;
/// Curvature along a step below this fraction of the shifted model's (negative beyond rounding:
/// a positive semidefinite Hessian along a direction it barely stiffens sums to about zero).
const CURVATURE_ROUNDING: f64 = 1e-9;
/// Free nodes within this many spacings of the tool are checked for contact.
pub const CONTACT_RANGE: f64 = 2.0;
/// No node moves further than this many spacings in a step at first: the reach of a step (a cap,
/// not a line search). It doubles after every step it capped that went as the model said, up to
/// [`MAX_REACH_SPACINGS`] (a falling sheet moves many spacings at a time), and starts again from
/// this after a step is refused.
pub const MAX_STEP_SPACINGS: f64 = 1.0;
/// The largest reach of a step, spacings.
pub const MAX_REACH_SPACINGS: f64 = 32.0;
/// A shift below this share of a refused step's Rayleigh quotient (y^T H y / y^T M y, the
/// curvature along it per unit mass) changes the step by about as much: too little for it to be
/// accepted where it was refused. On the 91 x 91 sphere drape 0.01 skips 10 rungs (20 of 319
/// subproblems) and leaves the path as it was; 0.1 changes it (170 iterations, another fold).
const NEGLIGIBLE_SHIFT_SHARE: f64 = 0.01;
/// The shift never falls below this (relative): Newton's step to rounding.
const MIN_SHIFT: f64 = 1e-14;
/// A shift above this (relative) makes steps too short to matter: give up.
const MAX_SHIFT: f64 = 1e12;
/// Nodes listed in a failure report.
const UNBALANCED_REPORTED: usize = 5;
/// A converged state is a saddle when the least eigenvalue of its Hessian relative to the
/// check's positive definite reference (which bounds it from above) is below minus this: the
/// Hessian curves down by this fraction of the reference's curvature along some direction.
/// Rounding in the Hessian is about 1e-16 of its largest entries (1e3 of the mean diagonal),
/// at most 1e-3 of the reference's smallest curvature (its mass shift, [`REFERENCE_SHIFT`]);
/// the saddles met so far are at -0.07 (hemisphere) and -0.35 (double dome).
const NEGATIVE_CURVATURE: f64 = 1e-2;
/// Most moves off saddles in one solve.
const MAX_ESCAPES: usize = 3;
/// The largest node move of an escape, spacings (before halving).
const ESCAPE_STEP_SPACINGS: f64 = 0.5;
/// An escape move is halved at most this many times while neither sign lowers the energy.
const ESCAPE_HALVINGS: usize = 10;
/// The mass shift of the stability check's reference model, relative (as the solver's shift):
/// small, so that the reference stays close to the elements' convex parts and H's negative
/// directions stand out. On the double dome's first ply and the hemisphere: 1e-10 finds their
/// saddles in 11 and 19 Lanczos iterations, 1e-8 in 13 and 26, 1e-7 in 31 and 40+, and 1e-6
/// misses them (least reference eigenvalue +2e-4 after 40 iterations).
const REFERENCE_SHIFT: f64 = 1e-10;
/// Shifts beyond this (relative) are not tried for the reference: the check is given up.
const MAX_REFERENCE_SHIFT: f64 = 1e2;

/// Per node, where it touches the tool (on-tool nodes always; free nodes near the tool).
type Feet = Vec<Option<Foot>>;

/// The state of the solve at one configuration.
struct State {
    eval: Evaluation,
    feet: Feet,
    bases: Vec<NodeBasis>,
    /// Nodes that slide on the tool (pressed, or held against it in free contact).
    sliding: Vec<bool>,
}

/// Minimise the objective from `x` (modified in place to the last accepted state).
pub fn solve(objective: &dyn Objective, x: &mut [Point], cons: &Constraints, settings: &SolverSettings) -> SolveReport {
    let start = std::time::Instant::now();
    let n = x.len();
    let rep: Vec<usize> = cons.stitched.clone().unwrap_or_else(|| (0..n).collect());
    let pairs = objective.coupled_pairs();
    let masses = {
        let m = objective.masses();
        // Nodes without fabric area of their own (a lone segment at the net's edge) still move
        // with some inertia: a quarter of the mean.
        let movable: Vec<f64> = m.iter().zip(&cons.freedom).filter(|(_, f)| f.dofs() > 0).map(|(m, _)| *m).collect();
        let mean = movable.iter().sum::<f64>() / movable.len().max(1) as f64;
        let floor = if mean > 0.0 { 0.25 * mean } else { 1.0 };
        m.iter().map(|&mk| mk.max(floor)).collect::<Vec<f64>>()
    };
    let mean_mass = masses.iter().sum::<f64>() / n.max(1) as f64;
    if cons.mode == ContactMode::Free {
        // Start outside the tool: nodes given inside it (a net draped on the facets is inside
        // the smooth surface wherever that bulges out) are put on its surface.
        let zero = vec![Vector::zeros(); n];
        let (outside, _) = moved(cons, x, &zero, &vec![false; n], &vec![None; n]);
        x.copy_from_slice(&outside);
    }
    let mut state = state_at(objective, cons, &rep, x, None);
    let movable = |k: usize| cons.freedom[rep[k]].dofs() > 0;
    let load = (0..n).filter(|&k| movable(k)).map(|k| state.eval.external[k].norm_squared()).sum::<f64>().sqrt();
    // The pattern's slots: every freedom of the nodes that can move now (a node losing some to
    // the tool keeps its slots, pinned), none for those held now (a node stuck on a table
    // gains its slots only when it comes off: a new pattern).
    let full: Vec<u8> = (0..n).map(|k| if rep[k] == k { cons.freedom[k].dofs() as u8 } else { 0 }).collect();
    let dofs0 = dofs_of(&state.bases, &rep);
    let cap0 = full.iter().zip(&dofs0).map(|(&f, &d)| if d > 0 { f.max(d) } else { 0 }).collect();
    let mut red = Reduction::new(cap0, dofs0, rep.clone(), &pairs);
    let force_scale = if load > 0.0 || settings.reaction_scale.is_some() {
        load.max(settings.reaction_scale.unwrap_or(0.0))
    } else {
        settings
            .force_scale
            .unwrap_or_else(|| norm(&red.reduce(&state.eval.internal, &state.bases)))
            .max(f64::MIN_POSITIVE)
    };
    let energy_start = state.eval.energy;
    let mut engine = QpEngine::new();
    let mut shift = settings.initial_shift;
    let mut iterations = Vec::new();
    let mut outcome = Outcome::IterationLimit;
    let mut residual = residual_of(&red, &state, force_scale);
    let mut last_failure: Option<QpFailure> = None;
    // The reach of a step (spacings) and whether the last step needed the convex model.
    let mut reach = MAX_STEP_SPACINGS;
    let mut prefer_convex = false;
    // Convex steps to wait before the exact model's stiffness is tested again, that wait after
    // the next failure, and the exact trial under way (its first iteration and residual).
    let mut exact_test_wait = 0usize;
    let mut exact_test_interval = 1usize;
    let mut exact_trial: Option<(usize, f64)> = None;
    let mut stability: Option<StabilityCheck> = None;
    // The last saddle escaped from and its check, restored if the iterations from there fail.
    let mut saddle: Option<(Vec<Point>, StabilityCheck)> = None;
    // The largest move of one iteration so far, spacings (for `settle_share`).
    let mut largest_step = 0.0f64;
    // Whether the last accepted step was the exact model's and under `LAGGED_STEP_SPACINGS`.
    let mut newton_tail = false;
    // Accepted steps in a row that were tiny and only middlingly predicted (`MIDDLING_RUN`).
    let mut middling_run = 0usize;
    // Per node: how often the tool let it go (it slid on the tool at one state and not at the
    // next), and whether it was let go again at this state after earlier ones
    // ([`RELEASES_BEFORE_BLOCKING`]).
    let mut releases = vec![0u32; n];
    let mut cycling = vec![false; n];
    let mut it = 0;
    loop {
        if residual <= settings.tolerance || red.is_empty() {
            if settings.stability_check && !red.is_empty() {
                let t_check = std::time::Instant::now();
                let found = least_curvature(
                    objective,
                    cons,
                    &rep,
                    &red,
                    &state,
                    x,
                    (&masses, mean_mass),
                    &mut engine,
                    settings.stability_eigenvalue,
                );
                let check = stability.get_or_insert_with(|| StabilityCheck {
                    verdict: Stability::Unresolved,
                    method: None,
                    found: None,
                    checks: 0,
                    escapes: Vec::new(),
                    time_ms: 0.0,
                });
                check.checks += 1;
                let escape = match &found {
                    Some(Found::PositiveDefinite) => {
                        check.verdict = Stability::Minimum;
                        check.method = Some(CheckMethod::Cholesky);
                        check.found = None;
                        None
                    }
                    Some(Found::Mode(c)) => {
                        check.method = Some(CheckMethod::Lanczos);
                        check.found = Some(LeastEigenvalue {
                            least_eigenvalue: c.lumped,
                            relative_eigenvalue: c.relative,
                            reference_eigenvalue: c.mode.value,
                            lanczos_iterations: c.mode.iterations,
                            lanczos_converged: c.mode.converged,
                        });
                        check.verdict =
                            if c.mode.value < -NEGATIVE_CURVATURE { Stability::Saddle } else { Stability::Minimum };
                        let may_escape = settings.escape_saddles && check.escapes.len() < MAX_ESCAPES;
                        if check.verdict == Stability::Saddle && may_escape {
                            escape_move(objective, cons, x, &state, &red, &c.mode.vector)
                        } else {
                            None
                        }
                    }
                    None => {
                        check.verdict = Stability::Unresolved;
                        check.method = None;
                        check.found = None;
                        None
                    }
                };
                if let (Some((trial, feet, energy_moved, move_spacings)), Some(found)) = (escape, check.found) {
                    check.escapes.push(Escape {
                        after_iteration: it,
                        least_eigenvalue: found.least_eigenvalue,
                        reference_eigenvalue: found.reference_eigenvalue,
                        energy_saddle: state.eval.energy,
                        energy_moved,
                        move_spacings,
                        kept: true,
                        abandoned: None,
                    });
                    check.time_ms += t_check.elapsed().as_secs_f64() * 1e3;
                    saddle = Some((x.to_vec(), check.clone()));
                    x.copy_from_slice(&trial);
                    state = adopt(objective, cons, &rep, &full, &pairs, x, Some(feet), &mut red);
                    // Iterate from there as from a new start.
                    shift = settings.initial_shift;
                    reach = MAX_STEP_SPACINGS;
                    prefer_convex = false;
                    newton_tail = false;
                    middling_run = 0;
                    residual = residual_of(&red, &state, force_scale);
                    continue;
                }
                check.time_ms += t_check.elapsed().as_secs_f64() * 1e3;
            }
            outcome = Outcome::Converged;
            break;
        }
        if it >= settings.max_iterations {
            break;
        }
        it += 1;
        let t_it = std::time::Instant::now();
        let solve_ms_before = engine.time_ms;
        let lagged_before = engine.lagged_solves;
        let ahead_before = engine.solved_ahead;
        let mut trial_ms = 0.0;
        let mut g = red.reduce(&unbalanced(&state.eval), &state.bases);
        let mut base_values =
            exact_model(cons, &rep, &red, &state).expect("the Hessian is evaluated with every accepted state");
        let mut exact_values = base_values.clone();
        // Re-solves of this iteration with nodes its steps pushed into the tool held on it.
        let mut blocked_solves = 0;
        let mut convex = false;
        let stiffness = red.mean_diagonal(&base_values).max(f64::MIN_POSITIVE);
        let unit_shift = stiffness / mean_mass.max(f64::MIN_POSITIVE);
        let noise = ENERGY_ROUNDING * state.eval.energy.abs().max(f64::MIN_POSITIVE);
        // What to do when the model turns out indefinite: take the elements' convex parts, which
        // still descend along a saddle; then only a larger shift helps.
        let fallback = |shift: &mut f64, values: &mut Vec<f64>, convex: &mut bool, red: &Reduction, state: &State| {
            if !*convex {
                if let Some(v) = convex_model(objective, cons, &rep, red, state, x) {
                    *values = v;
                    *convex = true;
                    return;
                }
            }
            *shift = (*shift * 10.0).max(1e-8);
        };
        if prefer_convex && residual > EXACT_FIRST_RESIDUAL {
            // The exact model was indefinite last time: start where that ended.
            fallback(&mut shift, &mut base_values, &mut convex, &red, &state);
        }
        let mut values = vec![0.0; base_values.len()];
        // How far a node may move in this iteration's steps (m): the reach; once nodes are held
        // on the tool (below), no farther than the objective's data hold.
        let mut reach_m = reach * cons.spacing;
        // The lumped masses as a matrix of the pattern (for the Rayleigh quotients of refused steps).
        let mut mass_diagonal: Option<Vec<f64>> = None;
        let mut step_capped = false;
        let mut refused = false;
        let mut subproblems = 0;
        let mut rounding_tries = 0;
        let mut accepted = None;
        let mut failure = None;
        while shift <= MAX_SHIFT {
            values.copy_from_slice(&base_values);
            red.add_diagonal(&mut values, &masses, shift * unit_shift);
            subproblems += 1;
            // After a tiny Newton step the exact model has hardly changed: its factorisation
            // from the last iteration preconditions conjugate gradients that solve this one.
            let near = newton_tail && !convex && subproblems == 1;
            // Once a step of this iteration was refused, more refusals are likely (the shift
            // climbs rung by rung): the next rung is solved on the other core meanwhile, and a
            // refusal then costs no factorisation of its own. Not before: a first rung, mostly
            // accepted, runs alone (a factorisation beside it runs 20% slower).
            let ahead = !near && refused;
            let solved = if near {
                engine.solve_near(&red, &values, &g)
            } else if ahead {
                let mut next = base_values.clone();
                red.add_diagonal(&mut next, &masses, next_rung(shift) * unit_shift);
                engine.solve_ahead(&red, &values, &g, &next)
            } else {
                engine.solve(&red, &values, &g)
            };
            let y = match solved {
                Ok(y) => y,
                Err(e) => {
                    // Clarabel finds no minimum of an indefinite model: as below.
                    failure = Some(e);
                    fallback(&mut shift, &mut base_values, &mut convex, &red, &state);
                    continue;
                }
            };
            failure = None;
            if blocked_solves < MAX_BLOCKED_SOLVES {
                // Free nodes on the tool that the step moves into it: the model knew nothing of
                // the tool there (their pull was outward at this state), and the trial would put
                // them back on its face, a jump the model did not predict that refuses the step
                // rung after rung. Instead they slide on the tool, and the step is solved again.
                let delta = red.expand(&y, &state.bases);
                if block_entering(cons, &rep, &mut state, &delta, &cycling) {
                    blocked_solves += 1;
                    // Nodes that were free now slide on the tool, which the step before did not
                    // let them: the re-solved step may carry the ply farther over the tool than
                    // the lagged friction was taken for (with blocking on every tool, a strip
                    // over a rod at 1.05 times the capstan's friction ran off it so).
                    reach_m = objective.step_bound(x).map_or(reach_m, |b| b.min(reach_m));
                    let dofs = dofs_of(&state.bases, &rep);
                    red.set_dofs(dofs);
                    g = red.reduce(&unbalanced(&state.eval), &state.bases);
                    exact_values = exact_model(cons, &rep, &red, &state).expect("the state has its Hessian");
                    base_values = if convex {
                        convex_model(objective, cons, &rep, &red, &state, x).expect("the convex model was built before")
                    } else {
                        exact_values.clone()
                    };
                    mass_diagonal = None;
                    continue;
                }
            }
            let gy = dot(&g, &y);
            let y_model = red.quad(&values, &y);
            let y_hess = red.quad(&base_values, &y);
            if gy >= 0.0 || y_model <= 0.0 || y_hess < -CURVATURE_ROUNDING * y_model {
                // Not a descent direction of a convex model, or the Hessian curves down along
                // the step (a saddle's direction).
                fallback(&mut shift, &mut base_values, &mut convex, &red, &state);
                continue;
            }
            let (y, capped) = cap_step(&red, y, &state.bases, reach_m);
            let gy = dot(&g, &y);
            // The decrease the unshifted model predicts (the shifted one's if that is not
            // positive: the Hessian alone is indefinite along y).
            let y_hess = red.quad(&base_values, &y);
            let predicted = {
                let p = -(gy + 0.5 * y_hess);
                if p > 0.0 {
                    p
                } else {
                    -(gy + 0.5 * red.quad(&values, &y))
                }
            };
            let delta = red.expand(&y, &state.bases);
            let t_trial = std::time::Instant::now();
            let (trial, trial_feet) = moved(cons, x, &delta, &state.sliding, &state.feet);
            let e1 = objective.energy(&trial);
            trial_ms += t_trial.elapsed().as_secs_f64() * 1e3;
            let fall = state.eval.energy - e1;
            let (trial, trial_feet, fall) = if settings.second_order_correction
                && !convex
                && acceptable(fall, predicted, noise)
            {
                // A Newton step (the exact model) leaves the stiff fibres' curved valley to
                // second order as well: correct it once more on the factorisation at hand and
                // keep whichever state is lower. Near equilibrium this keeps the convergence
                // quadratic where the straight step alone stretches the fibres (the 301 x 301
                // bench: 7 iterations -> 5; the square table at 2.5 mm: 230 -> 42).
                subproblems += 1;
                match second_order_correction(objective, cons, &red, &mut engine, &values, &state, x, &trial, reach_m) {
                    Some((trial2, feet2, e2)) if state.eval.energy - e2 > fall => {
                        (trial2, feet2, state.eval.energy - e2)
                    }
                    _ => (trial, trial_feet, fall),
                }
            } else {
                (trial, trial_feet, fall)
            };
            if acceptable(fall, predicted, noise) {
                // Where the model is stiffer along the step than the energy (the shift, or the
                // convex parts standing in for an indefinite Hessian, limited it: a slow drift
                // down a nearly flat direction, such as a symmetric ply twisting off a saddle),
                // the energy may keep falling further along it: go on while it does.
                let y_exact = if convex { red.quad(&exact_values, &y) } else { y_hess };
                let (trial, trial_feet, fall) = if y_exact < EXTEND_CURVATURE * y_model && fall > ROUNDING_BAND * noise
                {
                    extend_step(objective, cons, x, &state, &red, &y, reach_m, (trial, trial_feet, fall))
                } else {
                    (trial, trial_feet, fall)
                };
                accepted = Some((trial, trial_feet, fall / predicted, false));
                step_capped = capped;
                break;
            }
            if predicted <= ROUNDING_BAND * noise {
                // The energy cannot tell this step from rounding: take it if the forces balance
                // better (stiff fibres hold forces far above what their energy shows); else try
                // shorter steps a few times before calling it a stall.
                if fall >= -ROUNDING_BAND * noise {
                    let e_trial = objective.evaluate(&trial, false);
                    let (bases, _) = bases_at(cons, &rep, &e_trial, &trial_feet);
                    if residual_at(&red, &e_trial, &bases, force_scale) < residual {
                        accepted = Some((trial, trial_feet, 1.0, false));
                        break;
                    }
                }
                rounding_tries += 1;
                if rounding_tries > ROUNDING_RETRIES {
                    break;
                }
            }
            if settings.second_order_correction && predicted > ROUNDING_BAND * noise {
                // Back into the curved valley of the stiff fibres: undo the strain the straight
                // step added to second order, with the same model.
                subproblems += 1;
                if let Some((trial2, feet2, e2)) =
                    second_order_correction(objective, cons, &red, &mut engine, &values, &state, x, &trial, reach_m)
                {
                    let fall2 = state.eval.energy - e2;
                    if acceptable(fall2, predicted, noise) {
                        accepted = Some((trial2, feet2, fall2 / predicted, true));
                        break;
                    }
                }
            }
            refused = true;
            shift = next_rung(shift);
            // A rung whose shift is far below the step's own curvature along it (its Rayleigh
            // quotient y^T H y / y^T M y) gives nearly the same step, refused again: climb past
            // such rungs at once. The rung then accepted is the one the climb would reach.
            let y_mass = red.quad(mass_diagonal.get_or_insert_with(|| red.diagonal_of(&masses)), &y);
            if y_hess > 0.0 && y_mass > 0.0 {
                let bites = NEGLIGIBLE_SHIFT_SHARE * y_hess / (y_mass * unit_shift);
                while shift < bites && shift <= MAX_SHIFT {
                    shift = next_rung(shift);
                }
            }
        }
        let (accepted_flag, corrected, step) = match accepted {
            Some((trial, feet, ratio, corrected)) => {
                let step = x.iter().zip(&trial).map(|(a, b)| (a - b).norm()).fold(0.0, f64::max) / cons.spacing;
                x.copy_from_slice(&trial);
                let slid = std::mem::take(&mut state.sliding);
                state = adopt(objective, cons, &rep, &full, &pairs, x, Some(feet), &mut red);
                for (k, (&was, &is)) in slid.iter().zip(&state.sliding).enumerate() {
                    let let_go = was && !is;
                    releases[k] += u32::from(let_go);
                    cycling[k] = let_go && releases[k] >= RELEASES_BEFORE_BLOCKING;
                }
                let middling =
                    (MIDDLING_RATIO..GOOD_RATIO).contains(&ratio) && step <= LAGGED_STEP_SPACINGS && !corrected;
                middling_run = if middling { middling_run + 1 } else { 0 };
                if ratio >= GOOD_RATIO && !corrected {
                    shift = (shift / 8.0).max(MIN_SHIFT);
                } else if middling_run >= MIDDLING_RUN {
                    // Tiny steps, one after another, that the model predicts only middlingly:
                    // the shift holds them back along a soft mode, and neither rule here would
                    // ever move it (see MIDDLING_RUN).
                    shift = (shift / 2.0).max(MIN_SHIFT);
                } else if ratio < 0.1 {
                    shift *= 2.0;
                }
                reach = if step_capped && ratio >= GOOD_RATIO { (2.0 * reach).min(MAX_REACH_SPACINGS) } else { reach };
                prefer_convex = convex;
                let creeping = convex && shift <= EXACT_TEST_SHIFT && step <= LAGGED_STEP_SPACINGS;
                if creeping && residual > EXACT_FIRST_RESIDUAL {
                    if exact_test_wait > 0 {
                        exact_test_wait -= 1;
                    } else if exact_is_stiff(&red, &exact_values, &base_values, &masses, unit_shift) {
                        prefer_convex = false;
                        exact_trial = Some((it, residual));
                    } else {
                        exact_test_interval = (2 * exact_test_interval).min(MAX_EXACT_TEST_WAIT);
                        exact_test_wait = exact_test_interval;
                    }
                }
                newton_tail = !convex && step <= LAGGED_STEP_SPACINGS;
                (true, corrected, step)
            }
            None => {
                newton_tail = false;
                (false, false, 0.0)
            }
        };
        if refused {
            // A step was refused on the way: start small again.
            reach = MAX_STEP_SPACINGS;
        }
        residual = residual_of(&red, &state, force_scale);
        if let Some((since, r0)) = exact_trial {
            if prefer_convex || residual <= EXACT_FIRST_RESIDUAL {
                exact_trial = None;
            } else if it - since >= EXACT_TRIAL_ITERATIONS {
                if residual > EXACT_TRIAL_FALL * r0 {
                    prefer_convex = true;
                    exact_trial = None;
                    exact_test_interval = (2 * exact_test_interval).min(MAX_EXACT_TEST_WAIT);
                    exact_test_wait = exact_test_interval;
                } else {
                    exact_trial = Some((it, residual));
                }
            }
        }
        iterations.push(IterationLog {
            iteration: it,
            energy: state.eval.energy,
            residual,
            step,
            shift,
            active_contacts: active_contacts(cons, &state),
            accepted: accepted_flag,
            corrected,
            subproblems,
            lagged: engine.lagged_solves - lagged_before,
            ahead: engine.solved_ahead - ahead_before,
            time_ms: t_it.elapsed().as_secs_f64() * 1e3,
            model_ms: t_it.elapsed().as_secs_f64() * 1e3 - (engine.time_ms - solve_ms_before) - trial_ms,
            solve_ms: engine.time_ms - solve_ms_before,
            trial_ms,
        });
        if residual <= settings.tolerance {
            // Converged: checked at the top of the loop.
            continue;
        }
        if accepted_flag && objective.runaway(x) {
            outcome = Outcome::Slides;
            break;
        }
        if let (Some(share), true) = (settings.settle_share, accepted_flag) {
            largest_step = largest_step.max(step);
            if it > 1 && step <= share * largest_step {
                outcome = Outcome::Settled;
                break;
            }
        }
        if !accepted_flag {
            outcome = match &failure {
                Some(_) => Outcome::SubproblemFailed,
                None if shift > MAX_SHIFT => Outcome::LineSearchFailed,
                None => Outcome::Stalled,
            };
            last_failure = failure;
            break;
        }
    }
    if outcome != Outcome::Converged {
        if let Some((at_saddle, check)) = saddle {
            // The iterations from the escape did not reach equilibrium: the saddle is an
            // equilibrium at least, and the report says what it is.
            let abandoned = (state.eval.energy, residual);
            x.copy_from_slice(&at_saddle);
            state = adopt(objective, cons, &rep, &full, &pairs, x, None, &mut red);
            residual = residual_of(&red, &state, force_scale);
            let time_ms = stability.as_ref().map_or(check.time_ms, |s| s.time_ms);
            let mut check = check;
            check.time_ms = time_ms;
            if let Some(e) = check.escapes.last_mut() {
                e.kept = false;
                e.abandoned = Some(abandoned);
            }
            stability = Some(check);
            outcome = Outcome::Converged;
            last_failure = None;
        }
    }
    let unbalanced =
        if outcome == Outcome::Converged { Vec::new() } else { unbalanced_nodes(objective, x, &red, &state) };
    let subproblem_status = match (&outcome, last_failure) {
        (Outcome::SubproblemFailed, Some(QpFailure::NotSolved(status))) => Some(status),
        (Outcome::SubproblemFailed, Some(QpFailure::Setup)) => Some("Clarabel could not be set up".into()),
        _ => None,
    };
    SolveReport {
        outcome,
        energy_start,
        energy_end: state.eval.energy,
        residual,
        force_scale,
        iterations,
        time_ms: start.elapsed().as_secs_f64() * 1e3,
        unbalanced,
        subproblem_status,
        stability: if outcome == Outcome::Converged { stability } else { None },
    }
}

/// Most re-solves of one iteration with the nodes its step pushed into the tool held on it
/// ([`block_entering`]).
const MAX_BLOCKED_SOLVES: usize = 3;
/// A free node on a tool that stands still is blocked ([`block_entering`]) once the tool lets it
/// go for the second time: let go, caught again and let go once more, it is cycling. Its push on
/// the tool changes sign from one state to the next while the rest of the ply moves (a stiff
/// sheet balanced on a sphere's pole bending down round it), and each time it is free the step
/// carries it into the tool, whose face puts it back: a jump the model did not predict, refused
/// rung after rung (carbon twill on a sphere of R = 0.1 m: 3,000 iterations, unconverged; now
/// 448). The first release is left alone: a node lifting off for good (the ply leaving a rod
/// where it hangs) is let go once, and blocking it changed the path a strip runs off a rod.
const RELEASES_BEFORE_BLOCKING: u32 = 2;

/// Free contact: the free nodes that touch the tool and that `delta` moves into it slide on it
/// from now on in this iteration (their basis loses the tool's normal). Whether any did. On a
/// tool that moves ([`ContactSurface::moving`]) every such node: a punch advancing pushes into
/// nodes that touch it in every increment of the stroke (forming's iterations fell by 15 to
/// 40%). On a tool that stands still only the nodes `cycling` marks, let go by the tool again at
/// this state ([`RELEASES_BEFORE_BLOCKING`]): blocking every node there was neutral on free
/// drapes of a sphere and changed the path a strip running off a rod takes, and with it the
/// friction it was estimated to need (docs/ARCHITECTURE.md).
fn block_entering(cons: &Constraints, rep: &[usize], s: &mut State, delta: &[Vector], cycling: &[bool]) -> bool {
    let Some(tool) = cons.tool.filter(|_| cons.mode == ContactMode::Free && !cons.stick) else {
        return false;
    };
    let moving = tool.moving();
    let mut any = false;
    for k in 0..rep.len() {
        if rep[k] != k || s.sliding[k] || s.bases[k].dofs == 0 || !(moving || cycling[k]) {
            continue;
        }
        let Some(foot) = s.feet[k].as_mut() else { continue };
        if foot.gap > ACTIVE_GAP * cons.spacing || delta[k].dot(&foot.normal) >= 0.0 {
            continue;
        }
        s.bases[k] = s.bases[k].without(&foot.normal);
        s.sliding[k] = true;
        tool.curve(foot);
        any = true;
    }
    any
}

/// The shift after a refused step.
fn next_rung(shift: f64) -> f64 {
    (shift * 4.0).max(1e-8)
}

/// The exact model at `s`: its reduced Hessian with the tool's curvature term (None when the
/// state was evaluated without its Hessian).
fn exact_model(cons: &Constraints, rep: &[usize], red: &Reduction, s: &State) -> Option<Vec<f64>> {
    let mut values = red.values(s.eval.hessian.as_deref()?, &s.bases);
    add_contact_curvature(cons, rep, red, s, &mut values, false);
    Some(values)
}

/// Whether the exact model `h` is at least [`STIFF_EXACT`] as stiff as the convex one `c` along
/// every direction (`c` with the stability check's mass shift, [`REFERENCE_SHIFT`]): H - s C
/// positive definite, proved by one Cholesky factorisation.
fn exact_is_stiff(red: &Reduction, h: &[f64], c: &[f64], masses: &[f64], unit_shift: f64) -> bool {
    let mut reference = c.to_vec();
    red.add_diagonal(&mut reference, masses, REFERENCE_SHIFT * unit_shift);
    let test: Vec<f64> = h.iter().zip(&reference).map(|(h, r)| h - STIFF_EXACT * r).collect();
    positive_definite(red, &test) == Some(true)
}

/// The convex model at `s` (positions `x`): the elements' convex parts, reduced, with the tool's
/// curvature term kept positive; None for an objective without convex parts.
fn convex_model(
    objective: &dyn Objective,
    cons: &Constraints,
    rep: &[usize],
    red: &Reduction,
    s: &State,
    x: &[Point],
) -> Option<Vec<f64>> {
    let h = objective.convex_hessian(x)?;
    let mut values = red.values(h.as_ref(), &s.bases);
    add_contact_curvature(cons, rep, red, s, &mut values, true);
    Some(values)
}

/// Makes `x` (already moved) the solve's state: its evaluation, feet (those found by the move
/// when given), bases, and the reduction's freedoms (a new pattern when a node outgrew its
/// slots).
#[allow(clippy::too_many_arguments)] // the solve's own locals, passed as they are
fn adopt(
    objective: &dyn Objective,
    cons: &Constraints,
    rep: &[usize],
    full: &[u8],
    pairs: &[(usize, usize)],
    x: &[Point],
    feet: Option<Feet>,
    red: &mut Reduction,
) -> State {
    let state = state_at(objective, cons, rep, x, feet);
    let dofs = dofs_of(&state.bases, rep);
    if dofs.as_slice() != red.dofs() {
        if red.fits(&dofs) {
            red.set_dofs(dofs);
        } else {
            // Slots for the nodes that outgrew theirs: all their freedoms.
            let cap = (red.capacity().iter().zip(&dofs).zip(full))
                .map(|((&c, &d), &f)| if d > c { f.max(d) } else { c })
                .collect();
            *red = Reduction::new(cap, dofs, rep.to_vec(), pairs);
        }
    }
    state
}

/// What a stability check found.
enum Found {
    /// H + c M is positive definite (c = [`NEGATIVE_CURVATURE`]): a minimum, proved by one
    /// factorisation.
    PositiveDefinite,
    /// The least eigenpair, from Lanczos.
    Mode(Curvature),
}

/// A converged state's least curvature (see [`super::stability`]).
struct Curvature {
    /// The least eigenpair of the pencil (exact Hessian, positive definite reference).
    mode: LeastMode,
    /// Its Rayleigh quotient over the lumped masses, 1/s^2.
    lumped: f64,
    /// `lumped` over the mean stiffness per mean mass.
    relative: f64,
}

/// The least eigenvalue of the exact reduced Hessian at `s` (the tool's curvature included, no
/// shift) relative to a positive definite reference: the elements' convex parts plus a small
/// mass shift (or, for an objective without convex parts, the Hessian shifted past its
/// Gershgorin bound). Unless `eigenvalue` asks for the figure, a minimum is proved by one
/// Cholesky factorisation of H + c M instead (the verdict the eigenvalue would give, see
/// [`positive_definite`]); Lanczos runs only where that fails. None where no reference could be
/// factorised.
#[allow(clippy::too_many_arguments)] // the solve's own locals, passed as they are
fn least_curvature(
    objective: &dyn Objective,
    cons: &Constraints,
    rep: &[usize],
    red: &Reduction,
    s: &State,
    x: &[Point],
    (masses, mean_mass): (&[f64], f64),
    engine: &mut QpEngine,
    eigenvalue: bool,
) -> Option<Found> {
    let h = exact_model(cons, rep, red, s)?;
    let unit = red.mean_diagonal(&h).max(f64::MIN_POSITIVE) / mean_mass.max(f64::MIN_POSITIVE);
    let mut lumped = vec![0.0; h.len()];
    red.add_diagonal(&mut lumped, masses, 1.0);
    let reference = match convex_model(objective, cons, rep, red, s, x) {
        Some(v) => v,
        None => {
            // |H| row sums over the live variables bound its least eigenvalue (Gershgorin):
            // twice that in masses makes H + shift diagonally dominant.
            let mut live = vec![0.0; h.len()];
            for k in (0..x.len()).filter(|&k| red.rep(k) == k) {
                let (o, m) = red.vars(k);
                live[o..o + m].fill(1.0);
            }
            let rows = red.mul(&h.iter().map(|v| v.abs()).collect::<Vec<_>>(), &live);
            let diag = red.mul(&lumped, &live);
            let bound = rows.iter().zip(&diag).filter(|(_, &d)| d > 0.0).map(|(r, d)| r / d).fold(0.0, f64::max);
            let mut v = h.clone();
            red.add_diagonal(&mut v, masses, 2.0 * bound);
            v
        }
    };
    // The reference with a mass shift (relative, as the solver's).
    let shifted = |shift: f64| {
        let mut m = reference.clone();
        red.add_diagonal(&mut m, masses, shift * unit);
        m
    };
    if !eigenvalue {
        // The verdict is a saddle when the pencil (H, M) has an eigenvalue below -c, M the
        // reference at its first shift: exactly when H + c M is not positive definite.
        let m = shifted(REFERENCE_SHIFT);
        let test: Vec<f64> = h.iter().zip(&m).map(|(h, m)| h + NEGATIVE_CURVATURE * m).collect();
        if positive_definite(red, &test) == Some(true) {
            return Some(Found::PositiveDefinite);
        }
    }
    let per_node: Vec<Vector> =
        (0..x.len()).map(|k| Vector::new(spread(3 * k), spread(3 * k + 1), spread(3 * k + 2))).collect();
    let start = red.reduce(&per_node, &s.bases);
    let mut shift = REFERENCE_SHIFT;
    while shift <= MAX_REFERENCE_SHIFT {
        let m = shifted(shift);
        match least_mode(red, engine, &h, &m, &lumped, &start, LANCZOS_ITERATIONS) {
            Ok(Some(mode)) => {
                return Some(Found::Mode(Curvature { relative: mode.least / unit, lumped: mode.least, mode }));
            }
            Ok(None) => return None,
            // Too near singular to factorise: a larger shift.
            Err(_) => shift *= 100.0,
        }
    }
    None
}

/// The state moved off a saddle along `v` (reduced, a direction of negative curvature): the
/// largest node move [`ESCAPE_STEP_SPACINGS`], halved while neither sign lowers the energy
/// beyond rounding (the straight move meets the stiff fibres' higher-order terms), with the
/// nodes kept on or off the tool as in a step. Returns the lower state (state, feet, energy,
/// largest move in spacings), None if no move lowered the energy.
fn escape_move(
    objective: &dyn Objective,
    cons: &Constraints,
    x: &[Point],
    s: &State,
    red: &Reduction,
    v: &[f64],
) -> Option<(Vec<Point>, Feet, f64, f64)> {
    let delta = red.expand(v, &s.bases);
    let largest = delta.iter().map(|d| d.norm()).fold(0.0, f64::max);
    if !(largest > 0.0) || !largest.is_finite() {
        return None;
    }
    let noise = ENERGY_ROUNDING * s.eval.energy.abs().max(f64::MIN_POSITIVE);
    let mut size = ESCAPE_STEP_SPACINGS * cons.spacing;
    for _ in 0..=ESCAPE_HALVINGS {
        let best = [1.0, -1.0]
            .into_iter()
            .map(|sign| {
                let d: Vec<Vector> = delta.iter().map(|d| d * (sign * size / largest)).collect();
                let (trial, feet) = moved(cons, x, &d, &s.sliding, &s.feet);
                let e = objective.energy(&trial);
                (trial, feet, e)
            })
            .min_by(|a, b| a.2.total_cmp(&b.2))
            .expect("two signs");
        if best.2 < s.eval.energy - ROUNDING_BAND * noise {
            return Some((best.0, best.1, best.2, size / cons.spacing));
        }
        size /= 2.0;
    }
    None
}

/// The accepted step `y` doubled while the energy keeps falling and no node moves further than
/// `cap` (m); returns the best trial (state, feet, fall).
#[allow(clippy::too_many_arguments)] // the solve's own locals, passed as they are
fn extend_step(
    objective: &dyn Objective,
    cons: &Constraints,
    x: &[Point],
    s: &State,
    red: &Reduction,
    y: &[f64],
    cap: f64,
    mut best: (Vec<Point>, Feet, f64),
) -> (Vec<Point>, Feet, f64) {
    let largest = red.expand(y, &s.bases).iter().map(|d| d.norm()).fold(0.0, f64::max);
    let mut factor = 1.0;
    while largest * factor * 2.0 <= cap {
        factor *= 2.0;
        let step: Vec<f64> = y.iter().map(|v| v * factor).collect();
        let (trial, feet) = moved(cons, x, &red.expand(&step, &s.bases), &s.sliding, &s.feet);
        let fall = s.eval.energy - objective.energy(&trial);
        if fall <= best.2 {
            break;
        }
        best = (trial, feet, fall);
    }
    best
}

/// The second-order correction of the step from `x` to `trial` (see the module doc): the model
/// `values` (already factorised: only triangular solves) solved against the forces the stiff
/// terms gained to second order along the step, capped at `reach` (m), and applied from
/// `trial` with the nodes kept on or off the tool. Returns the state, its feet and its energy;
/// None where the objective has no such forces or the solve failed.
#[allow(clippy::too_many_arguments)] // the solve's own locals, passed as they are
fn second_order_correction(
    objective: &dyn Objective,
    cons: &Constraints,
    red: &Reduction,
    engine: &mut QpEngine,
    values: &[f64],
    s: &State,
    x: &[Point],
    trial: &[Point],
    reach: f64,
) -> Option<(Vec<Point>, Feet, f64)> {
    let f2 = objective.second_order_forces(x, trial)?;
    let g2 = red.reduce(&f2, &s.bases);
    let z = engine.solve(red, values, &g2).ok()?;
    let (z, _) = cap_step(red, z, &s.bases, reach);
    let dz = red.expand(&z, &s.bases);
    let (trial2, feet2) = moved(cons, trial, &dz, &s.sliding, &s.feet);
    let e2 = objective.energy(&trial2);
    Some((trial2, feet2, e2))
}

/// A step whose curvature under the exact Hessian is below this fraction of the model's (shift
/// or convex parts included) was limited by the model, not the energy: it is extended while the
/// energy keeps falling.
const EXTEND_CURVATURE: f64 = 0.5;

/// Whether a step that lowered the energy by `fall` where the model predicted `predicted` is
/// good enough. Where the prediction is lost in rounding, any step that does not raise the
/// energy is.
fn acceptable(fall: f64, predicted: f64, noise: f64) -> bool {
    if predicted <= ROUNDING_BAND * noise {
        fall >= 0.0
    } else {
        fall >= ACCEPT_RATIO * predicted
    }
}

/// Scales `y` so that no node moves further than `cap` (m); whether it had to.
fn cap_step(red: &Reduction, y: Vec<f64>, bases: &[NodeBasis], cap: f64) -> (Vec<f64>, bool) {
    let delta = red.expand(&y, bases);
    let largest = delta.iter().map(|d| d.norm()).fold(0.0, f64::max);
    if largest > cap {
        let s = cap / largest;
        (y.into_iter().map(|v| v * s).collect(), true)
    } else {
        (y, false)
    }
}

/// F - P per node.
fn unbalanced(e: &Evaluation) -> Vec<Vector> {
    e.internal.iter().zip(&e.external).map(|(f, p)| f - p).collect()
}

/// |B^T (F - P)| / scale.
fn residual_of(red: &Reduction, s: &State, scale: f64) -> f64 {
    residual_at(red, &s.eval, &s.bases, scale)
}

fn residual_at(red: &Reduction, e: &Evaluation, bases: &[NodeBasis], scale: f64) -> f64 {
    norm(&red.reduce(&unbalanced(e), bases)) / scale
}

fn dofs_of(bases: &[NodeBasis], rep: &[usize]) -> Vec<u8> {
    bases.iter().enumerate().map(|(k, b)| if rep[k] == k { b.dofs as u8 } else { 0 }).collect()
}

/// The state at `x`: its evaluation, feet (those `known` from the move that found `x`, the rest
/// located), bases of motion, and the tool's curvature at the feet of the nodes that slide on
/// it (the model's contact term needs it there and nowhere else: a free node near the tool but
/// not on it would pay for a curvature nobody reads).
fn state_at(objective: &dyn Objective, cons: &Constraints, rep: &[usize], x: &[Point], known: Option<Feet>) -> State {
    let eval = objective.evaluate(x, true);
    let mut feet = feet_at(cons, x, known);
    let (bases, sliding) = bases_at(cons, rep, &eval, &feet);
    if let Some(tool) = cons.tool {
        feet.par_iter_mut().zip(&sliding).filter(|(_, &s)| s).for_each(|(foot, _)| {
            if let Some(foot) = foot.as_mut() {
                tool.curve(foot);
            }
        });
    }
    State { eval, feet, bases, sliding }
}

/// Where each node meets the tool at `x`: on-tool nodes always (their feet `known` from the
/// move that found `x` when given, the rest located), free nodes in free contact when within
/// [`CONTACT_RANGE`] spacings of it; without the tool's curvature, which [`state_at`] adds where
/// it is needed.
fn feet_at(cons: &Constraints, x: &[Point], known: Option<Feet>) -> Feet {
    let Some(tool) = cons.tool else { return vec![None; x.len()] };
    let range = CONTACT_RANGE * cons.spacing;
    let known = known.unwrap_or_else(|| vec![None; x.len()]);
    cons.freedom
        .par_iter()
        .zip(known)
        .enumerate()
        .map(|(k, (f, known))| match (cons.mode, f) {
            (ContactMode::Pressed, f) if f.on_tool() => known.or_else(|| Some(tool.locate(&x[k], false, None))),
            (ContactMode::Free, f) if f.meets_tool_free() => {
                known.or_else(|| tool.locate_near(&x[k], range, false, None))
            }
            _ => None,
        })
        .collect()
}

/// Each node's basis of motion for the pushes of the evaluation `e`, and whether it slides on
/// the tool: from its freedom, and in free contact without the tool's normal where a node
/// touches the tool and is pushed into it.
fn bases_at(cons: &Constraints, rep: &[usize], e: &Evaluation, feet: &Feet) -> (Vec<NodeBasis>, Vec<bool>) {
    // Pushes (and loads) summed over stitched nodes onto their representative.
    let mut descent: Vec<Vector> = vec![Vector::zeros(); rep.len()];
    let mut load: Vec<Vector> = vec![Vector::zeros(); rep.len()];
    for (k, r) in rep.iter().enumerate() {
        descent[*r] += e.external[k] - e.internal[k];
        load[*r] += e.external[k];
    }
    cons.freedom
        .par_iter()
        .enumerate()
        .map(|(k, f)| {
            if rep[k] != k {
                return (NodeBasis::FIXED, false);
            }
            let foot = feet[k].as_ref();
            match (cons.mode, foot) {
                (ContactMode::Free, Some(foot)) if f.dofs() > 0 => {
                    let own = f.basis(None, &descent[k]);
                    let push = descent[k].dot(&foot.normal);
                    let touching = foot.gap <= ACTIVE_GAP * cons.spacing;
                    if cons.stick && touching && push < STICK_RELEASE * load[k].norm() {
                        // Stuck where it touches until pulled off by more than a share of its own
                        // weight: a node at the rim whose small pull changes sign from one
                        // iteration to the next would otherwise be let go and caught again.
                        (NodeBasis::FIXED, false)
                    } else if !cons.stick && touching && push < 0.0 {
                        (own.without(&foot.normal), true)
                    } else {
                        (own, false)
                    }
                }
                (ContactMode::Pressed, foot) => (f.basis(foot, &descent[k]), f.on_tool()),
                (_, foot) => (f.basis(foot, &descent[k]), false),
            }
        })
        .unzip()
}

/// Adds the tool's curvature to the model of every node that slides on it: moving a node by a
/// tangent vector t keeps it on the tool only if it also moves by `-1/2 t^T C t` along the normal
/// n, so the energy's second derivative along the tool gains `-(g . n) B^T C B` (g the node's
/// force F - P, B its basis). With `convex`, only the block's non-negative part is kept.
fn add_contact_curvature(
    cons: &Constraints,
    rep: &[usize],
    red: &Reduction,
    s: &State,
    values: &mut [f64],
    convex: bool,
) {
    if cons.tool.is_none() {
        return;
    }
    let mut g: Vec<Vector> = vec![Vector::zeros(); rep.len()];
    for (k, r) in rep.iter().enumerate() {
        g[*r] += s.eval.internal[k] - s.eval.external[k];
    }
    for k in 0..rep.len() {
        let (basis, Some(foot)) = (&s.bases[k], s.feet[k].as_ref()) else { continue };
        if !s.sliding[k] || basis.dofs == 0 || rep[k] != k {
            continue;
        }
        let b = basis.basis;
        let mut m = b.transpose() * foot.curvature() * b * (-g[k].dot(&foot.normal));
        if convex {
            m = clamp_to_psd(&m, basis.dofs);
        }
        red.add_node_block(values, k, &m);
    }
}

/// The non-negative part of the leading `dofs x dofs` block of a symmetric matrix.
fn clamp_to_psd(m: &nalgebra::Matrix3<f64>, dofs: usize) -> nalgebra::Matrix3<f64> {
    let mut out = nalgebra::Matrix3::zeros();
    match dofs {
        1 => out[(0, 0)] = m[(0, 0)].max(0.0),
        2 => {
            let eig = nalgebra::Matrix2::new(m[(0, 0)], m[(0, 1)], m[(1, 0)], m[(1, 1)]).symmetric_eigen();
            let clamped = eig.eigenvectors
                * nalgebra::Matrix2::from_diagonal(&eig.eigenvalues.map(|l| l.max(0.0)))
                * eig.eigenvectors.transpose();
            out.fixed_view_mut::<2, 2>(0, 0).copy_from(&clamped);
        }
        _ => {
            let eig = m.symmetric_eigen();
            out = eig.eigenvectors
                * nalgebra::Matrix3::from_diagonal(&eig.eigenvalues.map(|l| l.max(0.0)))
                * eig.eigenvectors.transpose();
        }
    }
    out
}

/// Nodes held against the tool by free contact.
fn active_contacts(cons: &Constraints, s: &State) -> usize {
    if cons.mode != ContactMode::Free {
        return 0;
    }
    if cons.stick {
        let touching = |k: usize| {
            s.bases[k].dofs == 0
                && cons.freedom[k].dofs() > 0
                && s.feet[k].is_some_and(|f| f.gap <= ACTIVE_GAP * cons.spacing)
        };
        return (0..s.bases.len()).filter(|&k| touching(k)).count();
    }
    s.sliding.iter().filter(|&&sl| sl).count()
}

/// The state `x + delta` with the nodes that slide on the tool moved back onto it and free
/// nodes that would enter it put on its surface; returns the feet found.
fn moved(cons: &Constraints, x: &[Point], delta: &[Vector], sliding: &[bool], feet: &Feet) -> (Vec<Point>, Feet) {
    let range = CONTACT_RANGE * cons.spacing;
    let mut out: Vec<Point> = x.iter().zip(delta).map(|(p, d)| p + d).collect();
    let Some(tool) = cons.tool else { return (out, vec![None; x.len()]) };
    let new_feet: Feet = out
        .par_iter_mut()
        .zip(&cons.freedom)
        .zip(sliding)
        .zip(feet)
        .map(|(((p, f), &sliding), last)| match cons.mode {
            ContactMode::Pressed if f.on_tool() => {
                let foot = tool.locate(p, false, last.map(|l| l.facet));
                *p = foot.point;
                Some(Foot { gap: 0.0, ..foot })
            }
            ContactMode::Free if f.meets_tool_free() => {
                let foot = tool.locate_near(p, range, false, last.map(|l| l.facet))?;
                if sliding || foot.gap < 0.0 {
                    *p = foot.point;
                    Some(Foot { gap: 0.0, ..foot })
                } else {
                    Some(foot)
                }
            }
            _ => None,
        })
        .collect();
    (out, new_feet)
}

/// The nodes with the largest unbalanced force over their free directions, and the energy term
/// that dominates there.
fn unbalanced_nodes(objective: &dyn Objective, x: &[Point], red: &Reduction, s: &State) -> Vec<UnbalancedNode> {
    let r = red.reduce(&unbalanced(&s.eval), &s.bases);
    let mut per: Vec<(f64, usize)> = (0..x.len())
        .filter(|&k| red.rep(k) == k)
        .map(|k| {
            let (o, m) = red.vars(k);
            (r[o..o + m].iter().map(|v| v * v).sum::<f64>().sqrt(), k)
        })
        .filter(|(f, _)| *f > 0.0)
        .collect();
    per.sort_by(|a, b| b.0.total_cmp(&a.0));
    per.truncate(UNBALANCED_REPORTED);
    let terms = objective.term_forces(x);
    per.into_iter()
        .map(|(force, node)| {
            let basis = &s.bases[node];
            let along = |f: &Vector| (0..basis.dofs).map(|p| basis.dir(p).dot(f).powi(2)).sum::<f64>().sqrt();
            let dominant_term = terms
                .iter()
                .map(|(name, f)| (*name, along(&f[node])))
                .max_by(|a, b| a.1.total_cmp(&b.1))
                .map(|(name, _)| name);
            UnbalancedNode { node, force, dominant_term }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::shapes;
    use nalgebra::Matrix3;

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
        fn masses(&self) -> Vec<f64> {
            vec![1.0; self.targets.len()]
        }
    }

    fn cons<'a>(
        freedom: Vec<Freedom>,
        mode: ContactMode,
        tool: Option<&'a dyn ContactSurface>,
        spacing: f64,
    ) -> Constraints<'a> {
        Constraints { freedom, mode, tool, spacing, stitched: None, stick: false }
    }

    #[test]
    fn unconstrained_springs_reach_their_targets_and_fixed_nodes_stay() {
        let targets = vec![Point::new(1.0, 2.0, 3.0), Point::new(-1.0, 0.5, 0.0), Point::new(0.0, 0.0, 1.0)];
        let obj = Springs { targets: targets.clone(), k: 100.0 };
        let mut x = vec![Point::origin(); 3];
        let freedom = vec![Freedom::Free, Freedom::Fixed, Freedom::Line(Vector::z())];
        let report = solve(
            &obj,
            &mut x,
            &cons(freedom, ContactMode::None, None, 1.0),
            &SolverSettings::default().tolerance(1e-10),
        );
        assert!(report.ok(), "{report:?}");
        assert!((x[0] - targets[0]).norm() < 1e-6);
        assert_eq!(x[1], Point::origin());
        assert!((x[2] - Point::new(0.0, 0.0, 1.0)).norm() < 1e-6);
        assert!(report.energy_end <= report.energy_start);
    }

    #[test]
    fn stitched_nodes_move_together() {
        // Two nodes sharing their freedoms, pulled to two targets: they meet at the midpoint.
        let obj = Springs { targets: vec![Point::new(1.0, 0.0, 0.0), Point::new(3.0, 2.0, 0.0)], k: 1.0 };
        let mut x = vec![Point::origin(); 2];
        let c =
            Constraints { stitched: Some(vec![0, 0]), ..cons(vec![Freedom::Free; 2], ContactMode::None, None, 1.0) };
        let report = solve(&obj, &mut x, &c, &SolverSettings::default().tolerance(1e-10));
        assert!(report.ok(), "{report:?}");
        assert!((x[0] - Point::new(2.0, 1.0, 0.0)).norm() < 1e-8, "{}", x[0]);
        assert_eq!(x[0], x[1]);
    }

    #[test]
    fn free_contact_keeps_nodes_out_of_the_tool() {
        let tool = shapes::plate(4.0, 4.0, 4, 4).into_surface().unwrap();
        // Springs pull the nodes 1 m below the plate; contact must stop them on it.
        let targets = vec![Point::new(0.2, 0.1, -1.0), Point::new(-0.5, 0.3, -0.5), Point::new(0.1, 0.1, 2.0)];
        let obj = Springs { targets, k: 10.0 };
        let mut x = vec![Point::new(0.0, 0.0, 0.5), Point::new(0.0, 0.0, 0.3), Point::new(0.0, 0.0, 0.1)];
        let c = cons(vec![Freedom::Free; 3], ContactMode::Free, Some(&tool), 1.0);
        let report = solve(&obj, &mut x, &c, &SolverSettings::default().tolerance(1e-10));
        assert!(report.ok(), "{report:?}");
        assert!(x[0].z.abs() < 1e-9 && (x[0].x - 0.2).abs() < 1e-6, "{}", x[0]);
        assert!(x[1].z.abs() < 1e-9);
        assert!((x[2].z - 2.0).abs() < 1e-6);
    }

    #[test]
    fn pressed_nodes_slide_on_the_facets() {
        let tool = shapes::hemisphere(1.0, 20).into_surface().unwrap();
        // A target off the sphere: the pressed node ends at the closest point of the tool to it.
        let target = Point::new(0.6, 0.0, 1.2);
        let obj = Springs { targets: vec![target], k: 1.0 };
        let start = tool.closest_point(&Point::new(0.0, 0.0, 1.0));
        let mut x = vec![start.point];
        let c = cons(vec![Freedom::OnTool], ContactMode::Pressed, Some(&tool), 0.1);
        let report = solve(&obj, &mut x, &c, &SolverSettings::default().tolerance(1e-8));
        assert!(tool.closest_point(&x[0]).distance < 1e-12);
        // The closest point of the (faceted) sphere to the target: along the target's direction.
        // It lies on a facet edge, where the facets' tangent planes do not hold the spring's pull
        // (a kink has a cone of normals): the solve stops there without calling it equilibrium,
        // because no step, however short, lowers the energy.
        let expected = tool.closest_point(&target).point;
        assert!((x[0] - expected).norm() < 1e-4, "{} vs {}", x[0], expected);
        assert!(report.energy_end < report.energy_start);
        assert!(matches!(report.outcome, Outcome::LineSearchFailed | Outcome::Stalled), "{:?}", report.outcome);
    }

    #[test]
    fn pressed_nodes_slide_on_the_smooth_patches() {
        let tool = shapes::hemisphere(1.0, 20).into_surface().unwrap();
        let smooth = crate::geometry::SmoothSurface::new(&tool);
        let target = Point::new(0.6, 0.0, 1.2);
        let obj = Springs { targets: vec![target], k: 1.0 };
        let mut x = vec![smooth.project(&Point::new(0.0, 0.0, 1.0)).point];
        let c = cons(vec![Freedom::OnTool], ContactMode::Pressed, Some(&smooth), 0.1);
        let report = solve(&obj, &mut x, &c, &SolverSettings::default().tolerance(1e-10));
        assert!(report.ok(), "{report:?}");
        let s = smooth.project(&x[0]);
        assert!((s.point - x[0]).norm() < 1e-12);
        // At the constrained minimum the spring pulls along the surface normal...
        let misalignment = (target - x[0]).normalize().cross(&s.normal).norm();
        assert!(misalignment < 1e-6, "{misalignment:e}");
        // ... which, on patches following the sphere, is near the sphere's answer: closer than
        // the facets get.
        let sphere = Point::from(target.coords.normalize());
        let facets = tool.closest_point(&target).point;
        assert!((x[0] - sphere).norm() < (facets - sphere).norm() / 5.0, "{} vs {}", x[0], sphere);
    }

    /// Springs of one stiffness between node pairs, of given rest lengths, on nodes of one
    /// mass under gravity (-z).
    struct SpringNet {
        springs: Vec<(usize, usize, f64)>,
        k: f64,
        mass: f64,
        gravity: f64,
        nodes: usize,
    }
    /// 3x3 blocks by node pair (a <= b).
    struct Blocks(std::collections::HashMap<(usize, usize), Matrix3<f64>>);
    impl HessianBlocks for Blocks {
        fn block(&self, a: usize, b: usize) -> Matrix3<f64> {
            match (self.0.get(&(a, b)), self.0.get(&(b, a))) {
                (Some(m), _) => *m,
                (None, Some(m)) => m.transpose(),
                _ => Matrix3::zeros(),
            }
        }
    }
    impl SpringNet {
        /// Per spring (a, b, stiffness block along and across it: k n n^T + T/r (I - n n^T)),
        /// with only the non-negative part when `convex`.
        fn hessian(&self, x: &[Point], convex: bool) -> Blocks {
            let mut blocks = std::collections::HashMap::new();
            for &(a, b, rest) in &self.springs {
                let d = x[b] - x[a];
                let r = d.norm();
                let n = d / r;
                let nn = n * n.transpose();
                let across = self.k * (r - rest) / r;
                let across = if convex { across.max(0.0) } else { across };
                let kb = nn * self.k + (Matrix3::identity() - nn) * across;
                for (p, q, sign) in [(a, a, 1.0), (b, b, 1.0), (a.min(b), a.max(b), -1.0)] {
                    *blocks.entry((p, q)).or_insert_with(Matrix3::zeros) += kb * sign;
                }
            }
            Blocks(blocks)
        }
    }
    impl Objective for SpringNet {
        fn evaluate(&self, x: &[Point], hessian: bool) -> Evaluation {
            let mut internal = vec![Vector::zeros(); x.len()];
            let mut energy = 0.0;
            for &(a, b, rest) in &self.springs {
                let d = x[b] - x[a];
                let r = d.norm();
                let f = d / r * (self.k * (r - rest));
                internal[b] += f;
                internal[a] -= f;
                energy += 0.5 * self.k * (r - rest).powi(2);
            }
            energy += x.iter().map(|p| self.mass * self.gravity * p.z).sum::<f64>();
            Evaluation {
                energy,
                internal,
                external: vec![Vector::new(0.0, 0.0, -self.mass * self.gravity); x.len()],
                hessian: hessian.then(|| Box::new(self.hessian(x, false)) as Box<dyn HessianBlocks>),
            }
        }
        fn convex_hessian(&self, x: &[Point]) -> Option<Box<dyn HessianBlocks>> {
            Some(Box::new(self.hessian(x, true)))
        }
        fn coupled_pairs(&self) -> Vec<(usize, usize)> {
            let mut pairs: Vec<(usize, usize)> = (0..self.nodes).map(|k| (k, k)).collect();
            pairs.extend(self.springs.iter().map(|&(a, b, _)| (a.min(b), a.max(b))));
            pairs
        }
        fn masses(&self) -> Vec<f64> {
            vec![self.mass; self.nodes]
        }
    }

    /// A bob of 2 kg on a stiff spring of rest length 1 m from a fixed node at the origin.
    const PENDULUM: (f64, f64, f64) = (1.0, 2.0, 9.81);

    fn pendulum() -> SpringNet {
        let (length, mass, gravity) = PENDULUM;
        SpringNet { springs: vec![(0, 1, length)], k: 1e3 * mass * gravity / length, mass, gravity, nodes: 2 }
    }

    #[test]
    fn an_upright_pendulum_is_found_unstable_and_falls_to_hang_below() {
        let (length, mass, gravity) = PENDULUM;
        let obj = pendulum();
        // Upright, the spring shortened by the weight: the forces balance exactly.
        let sag = mass * gravity / obj.k;
        let mut x = vec![Point::origin(), Point::new(0.0, 0.0, length - sag)];
        let c = cons(vec![Freedom::Fixed, Freedom::Free], ContactMode::None, None, 0.25);
        // Without escapes the check only reports the saddle.
        let report = solve(&obj, &mut x.clone(), &c, &SolverSettings::default().tolerance(1e-10));
        assert!(report.ok() && report.saddle() && report.stability.as_ref().unwrap().escapes.is_empty());
        let settings = SolverSettings::default().tolerance(1e-10).escape_saddles(true).stability_eigenvalue(true);
        let report = solve(&obj, &mut x, &c, &settings);
        assert!(report.ok(), "{report:?}");
        let check = report.stability.as_ref().expect("checked");
        assert_eq!(check.escapes.len(), 1, "{check:?}");
        let escape = &check.escapes[0];
        assert_eq!(escape.after_iteration, 0);
        assert!(escape.kept && escape.energy_moved < escape.energy_saddle);
        // Across the compressed spring the stiffness is its force over its length, -m g / r;
        // over the mass, -g / r.
        let upright = -gravity / (length - sag);
        assert!((escape.least_eigenvalue - upright).abs() < 1e-6 * upright.abs(), "{}", escape.least_eigenvalue);
        // It ends hanging below, stretched by the weight, 2 m g L lower.
        let below = Point::new(0.0, 0.0, -(length + sag));
        assert!((x[1] - below).norm() < 1e-6, "{}", x[1]);
        let fall = report.energy_start - report.energy_end;
        assert!((fall - 2.0 * mass * gravity * length).abs() < 1e-9, "{fall}");
        assert_eq!(check.verdict, Stability::Minimum);
        let hanging = gravity / (length + sag);
        assert!(
            (check.found.unwrap().least_eigenvalue - hanging).abs() < 1e-6 * hanging,
            "{}",
            check.found.unwrap().least_eigenvalue
        );
        assert_eq!(check.checks, 2);
    }

    #[test]
    fn a_hanging_pendulum_is_stable() {
        let (length, mass, gravity) = PENDULUM;
        let obj = pendulum();
        let sag = mass * gravity / obj.k;
        let below = Point::new(0.0, 0.0, -(length + sag));
        let mut x = vec![Point::origin(), below];
        let c = cons(vec![Freedom::Fixed, Freedom::Free], ContactMode::None, None, 0.25);
        // By default one Cholesky factorisation proves the minimum, with no eigenvalue.
        let report = solve(&obj, &mut x, &c, &SolverSettings::default().tolerance(1e-10));
        assert!(report.ok() && report.iterations.is_empty(), "{report:?}");
        let check = report.stability.as_ref().expect("checked");
        assert_eq!((check.verdict, check.method), (Stability::Minimum, Some(CheckMethod::Cholesky)));
        assert!(check.found.is_none() && check.describe().contains("positive definite"), "{}", check.describe());
        // Asked for the figure, Lanczos finds the pendulum's g / L.
        let settings = SolverSettings::default().tolerance(1e-10).stability_eigenvalue(true);
        let report = solve(&obj, &mut x, &c, &settings);
        assert!(report.ok() && report.iterations.is_empty(), "{report:?}");
        let check = report.stability.as_ref().expect("checked");
        assert_eq!((check.verdict, check.method), (Stability::Minimum, Some(CheckMethod::Lanczos)));
        assert!(check.escapes.is_empty() && check.found.unwrap().lanczos_converged);
        let hanging = gravity / (length + sag);
        assert!(
            (check.found.unwrap().least_eigenvalue - hanging).abs() < 1e-6 * hanging,
            "{}",
            check.found.unwrap().least_eigenvalue
        );
        assert_eq!(x[1], below);
        // Switched off, there is no check.
        let report = solve(&obj, &mut x, &c, &SolverSettings::default().tolerance(1e-10).stability_check(false));
        assert!(report.ok() && report.stability.is_none());
    }

    #[test]
    fn a_saddle_left_without_reaching_equilibrium_is_restored_and_reported() {
        // Two iterations are too few to swing the pendulum down from upright.
        let (length, mass, gravity) = PENDULUM;
        let obj = pendulum();
        let upright = Point::new(0.0, 0.0, length - mass * gravity / obj.k);
        let mut x = vec![Point::origin(), upright];
        let c = cons(vec![Freedom::Fixed, Freedom::Free], ContactMode::None, None, 0.25);
        let report =
            solve(&obj, &mut x, &c, &SolverSettings::default().tolerance(1e-10).max_iterations(2).escape_saddles(true));
        assert!(report.ok() && report.saddle(), "{report:?}");
        assert_eq!(x[1], upright);
        assert_eq!(report.energy_end, report.energy_start);
        let check = report.stability.as_ref().expect("checked");
        assert_eq!(check.escapes.len(), 1);
        let (energy, _) = check.escapes[0].abandoned.expect("the lower state it gave up");
        assert!(!check.escapes[0].kept && energy < report.energy_end);
        assert!(check.describe().starts_with("UNSTABLE"), "{}", check.describe());
    }

    /// A node between two fixed nodes 2 a apart, on springs of rest length `rest` (no gravity).
    fn in_line(a: f64, rest: f64) -> (SpringNet, Vec<Point>, SolverSettings) {
        let obj = SpringNet { springs: vec![(0, 1, rest), (1, 2, rest)], k: 100.0, mass: 0.5, gravity: 0.0, nodes: 3 };
        let x = vec![Point::new(-a, 0.0, 0.0), Point::origin(), Point::new(a, 0.0, 0.0)];
        let settings = SolverSettings {
            force_scale: Some(obj.k * a),
            ..SolverSettings::default().tolerance(1e-10).escape_saddles(true).stability_eigenvalue(true)
        };
        (obj, x, settings)
    }

    #[test]
    fn a_node_between_stretched_springs_is_stable_and_between_compressed_ones_buckles() {
        let a = 1.0;
        let c = cons(vec![Freedom::Fixed, Freedom::Free, Freedom::Fixed], ContactMode::None, None, 0.2);
        // Stretched: across the line each spring stiffens by its tension over its length.
        let (obj, mut x, settings) = in_line(a, 0.8 * a);
        let report = solve(&obj, &mut x, &c, &settings);
        let check = report.stability.as_ref().expect("checked");
        assert!(report.ok() && check.is_minimum() && check.escapes.is_empty(), "{report:?}");
        let across = 2.0 * obj.k * (a - 0.8 * a) / a / obj.mass;
        assert!(
            (check.found.unwrap().least_eigenvalue - across).abs() < 1e-6 * across,
            "{}",
            check.found.unwrap().least_eigenvalue
        );
        // Compressed: the straight line is a saddle; the node buckles aside until both springs
        // are at rest (energy 0), sqrt(rest^2 - a^2) off the line.
        let rest = 1.25 * a;
        let (obj, mut x, settings) = in_line(a, rest);
        let report = solve(&obj, &mut x, &c, &settings);
        let check = report.stability.as_ref().expect("checked");
        assert!(report.ok() && check.is_minimum(), "{report:?}");
        assert_eq!(check.escapes.len(), 1);
        let across = 2.0 * obj.k * (a - rest) / a / obj.mass;
        let found = check.escapes[0].least_eigenvalue;
        assert!((found - across).abs() < 1e-6 * across.abs(), "{found} vs {across}");
        assert!(report.energy_end.abs() < 1e-12, "{}", report.energy_end);
        let off = (x[1].y.powi(2) + x[1].z.powi(2)).sqrt();
        assert!((off - (rest * rest - a * a).sqrt()).abs() < 1e-6 && x[1].x.abs() < 1e-6, "{}", x[1]);
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
        let c = cons(vec![Freedom::OnTool; 2], ContactMode::Pressed, Some(&tool), 0.1);
        let report = solve(&obj, &mut x, &c, &SolverSettings::default().tolerance(1e-10));
        assert_eq!(report.outcome, Outcome::Converged, "{report:?}");
        assert!((x[0] - Point::new(1.0, 0.3, 0.0)).norm() < 1e-9, "{}", x[0]);
        assert!((x[1] - Point::new(1.0, 1.0, 0.0)).norm() < 1e-9, "{}", x[1]);
    }
}
