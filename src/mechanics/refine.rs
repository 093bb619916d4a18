//! Mechanical refinement of a draped net: the energy model on its grid, minimised from the
//! kinematic state with the tool as contact, under load steps of gravity.
use super::contact::{ContactMode, ContactSurface, Freedom};
use super::energy::{Gravity, Grid, HessianKind, Laws, Model};
use super::forming::{BlankPlane, Forming, Grip, PlanView, ToolsAt};
use super::friction::{
    bearings, friction_needed, tangent_rigid_motions, Bearing, Coulomb, FrictionLag, Frictional, Needed, PliesBelow,
    LAG_TOLERANCE, MAX_LAGS, RELAG_SHARE, RELAG_TRAVEL_SPACINGS, SLIDE_MIN_SPACINGS, SLIDE_SHARE, STICK_SPACINGS,
};
use super::qp::HessianBlocks;
use super::sheet::{SheetError, SheetFeatures, SheetLayout};
use super::solver::{solve, Constraints, Evaluation, Objective, Outcome, SolveReport, SolverSettings};
use crate::geometry::{Point, SmoothSurface, ToolSurface, Vector};
use crate::kinematic::provenance::{
    CellChanges, ContactRecord, ContactState, SolverRecord, Stability, UnbalancedRecord, BETWEEN_PLIES,
};
use crate::kinematic::{drape_smooth, DrapeNet, KinematicSettings, Method, NodeStatus, SurfaceKind};
use crate::numeric::union_find_root;

/// Which Hessian the quadratic models use: the exact one (the solver's shift handles its
/// negative curvature).
const HESSIAN: HessianKind = HessianKind::Exact;

/// Standard gravity, m/s^2.
pub const STANDARD_GRAVITY: f64 = 9.80665;

/// The energy of a net's grid as the solver sees it: internal energy from the model, and
/// gravity as constant nodal loads P = m g (the masses of [`Gravity`]).
pub struct NetObjective<'a> {
    model: Model<'a>,
    loads: Vec<Vector>,
    masses: Vec<f64>,
    pairs: Vec<(usize, usize)>,
}

impl<'a> NetObjective<'a> {
    /// Stretch, shear and bending of `laws` on `grid`, loaded by `gravity` (m/s^2) times
    /// `load_factor`.
    pub fn new<L: Laws + ?Sized>(grid: Grid, laws: &'a L, gravity: Vector) -> Self {
        let weight = Gravity::new(&grid, laws.areal_mass(), gravity);
        let loads = weight.loads();
        let model = Model::internal(grid, laws);
        let pairs = model.pattern().coupled_pairs();
        NetObjective { model, loads, masses: weight.mass, pairs }
    }

    /// Scale the loads (load stepping).
    pub fn scale_loads(&mut self, factor: f64) {
        self.loads.iter_mut().for_each(|l| *l *= factor);
    }

    /// Work of the current loads on the displacement to `x`: sum of P . x.
    pub fn work(&self, x: &[Point]) -> f64 {
        self.loads.iter().zip(x).map(|(l, p)| l.dot(&p.coords)).sum()
    }

    /// The grid.
    pub fn grid(&self) -> &Grid {
        &self.model.grid
    }

    /// Internal forces (energy gradient without loads) at `x`.
    pub fn internal_forces(&self, x: &[Point]) -> Vec<Vector> {
        self.model.evaluate(x, None).gradient
    }

    /// The energy terms at `x`, by name.
    pub fn energy_terms(&self, x: &[Point]) -> Vec<(&'static str, f64)> {
        self.model.evaluate(x, None).terms
    }
}

impl Objective for NetObjective<'_> {
    fn evaluate(&self, x: &[Point], hessian: bool) -> Evaluation {
        let ev = self.model.evaluate(x, hessian.then_some(HESSIAN));
        let work = self.work(x);
        Evaluation {
            energy: ev.energy - work,
            internal: ev.gradient,
            external: self.loads.clone(),
            hessian: ev.hessian.map(|h| Box::new(h) as Box<dyn HessianBlocks>),
        }
    }
    fn energy(&self, x: &[Point]) -> f64 {
        self.model.energy(x) - self.work(x)
    }
    fn convex_hessian(&self, x: &[Point]) -> Option<Box<dyn HessianBlocks>> {
        let h = self.model.evaluate(x, Some(HessianKind::Convex)).hessian?;
        Some(Box::new(h))
    }
    fn coupled_pairs(&self) -> Vec<(usize, usize)> {
        self.pairs.clone()
    }
    fn masses(&self) -> Vec<f64> {
        self.masses.clone()
    }
    fn second_order_forces(&self, x: &[Point], trial: &[Point]) -> Option<Vec<Vector>> {
        Some(self.model.second_order_forces(x, trial))
    }
    fn term_forces(&self, x: &[Point]) -> Vec<(&'static str, Vec<Vector>)> {
        let mut terms = self.model.term_gradients(x);
        terms.push(("gravity", self.loads.iter().map(|l| -l).collect()));
        terms
    }
}

/// What pressed nodes slide on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum PressedSurface {
    /// Smooth patches over the facets ([`SmoothSurface`]): the part the tessellation stands for.
    #[default]
    Smooth,
    /// The facets exactly as given (a net finer than them converges slowly: it crawls from edge
    /// to edge).
    Facets,
}

/// How to refine.
#[derive(Debug, Clone)]
pub struct RefineSettings {
    /// How the ply meets the tool: pressed or free.
    pub mode: ContactMode,
    /// What pressed nodes slide on.
    pub pressed_surface: PressedSurface,
    /// Gravity, m/s^2.
    pub gravity: Vector,
    /// Gravity is applied in this many equal steps.
    pub load_steps: usize,
    /// The solver's settings (per load step).
    pub solver: SolverSettings,
    /// The sheet's features (reinforcements, seam, fold, cuts), laid out on the net's grid.
    pub sheet: SheetFeatures,
    /// Free drape: nodes the tool holds up stay where they touch (see [`Constraints::stick`]):
    /// friction without limit.
    pub stick: bool,
    /// Coulomb's coefficient of friction between the ply and the tool (0: frictionless).
    pub friction: f64,
    /// A ply of a layup with a coefficient of its own against the plies below it
    /// (`ply_friction`): where they lie. None: the tool's `friction` everywhere.
    pub plies_below: Option<PliesBelow>,
    /// Nodes held in place at the user's request, as fabric coordinates from the origin node
    /// (u along the warp, v along the weft, m): the node there is held, on a grid of any
    /// spacing (a ply draped again at another spacing holds the same fabric points). Nothing
    /// else holds a ply but the tool and friction.
    pub holds: Vec<[f64; 2]>,
    /// A forming process: the tool is a punch moving along its stroke over the increments
    /// (`load_steps` at least as many as [`Forming::increments`] asks), a die and a binder
    /// beside it; the ply meets them with one-sided contact (the mode is then free).
    pub forming: Option<Forming>,
}

impl Default for RefineSettings {
    fn default() -> Self {
        RefineSettings {
            mode: ContactMode::Pressed,
            pressed_surface: PressedSurface::Smooth,
            gravity: Vector::new(0.0, 0.0, -STANDARD_GRAVITY),
            load_steps: 1,
            solver: SolverSettings::default(),
            sheet: SheetFeatures::default(),
            stick: false,
            friction: 0.0,
            plies_below: None,
            holds: Vec::new(),
            forming: None,
        }
    }
}

impl RefineSettings {
    /// The coefficients the ply meets: the tool's, and the plies' below it where they lie.
    pub fn coulomb(&self) -> Coulomb {
        Coulomb { tool: self.friction, plies: self.plies_below.clone() }
    }
}

/// One load increment: how many solves its friction took to agree with its solution.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Increment {
    /// The share of the full load it carries.
    pub load_factor: f64,
    /// Solves: the first with the normal forces of the state before it, each next one with
    /// those of the last solution.
    pub solves: usize,
    /// Solver iterations over its solves (where a forming stroke or a load path spends them).
    pub iterations: usize,
    /// How much the normal forces changed over the last solve, relative to their sum
    /// ([`LAG_TOLERANCE`]: settled below it).
    pub lag_change: f64,
}

impl Increment {
    /// Whether its friction agrees with its solution.
    pub fn settled(&self, friction: f64) -> bool {
        friction == 0.0 || self.lag_change <= LAG_TOLERANCE
    }
}

/// Why a ply has no equilibrium where it is.
#[derive(Debug, Clone, PartialEq)]
pub enum Slide {
    /// It slid away over the tool while the load came on: friction cannot hold it.
    Away {
        /// How far it slid before the solve stopped (normal-force weighted mean, m).
        distance: f64,
        /// The least friction coefficient that would hold it, as the forces there tell.
        friction_needed: Option<f64>,
        /// Which coefficient that is ([`friction_needed`]): the tool's `friction`, or on a ply
        /// of a layup bearing on the plies below, `ply_friction`.
        about: Needed,
    },
    /// Frictionless and held by nothing, on a tool that lets it move rigidly (a plane, a
    /// cylinder, a sphere): its place is not determined.
    Free {
        /// How many independent rigid motions the tool leaves it.
        motions: usize,
        /// The least friction coefficient that would hold it against the loads along them
        /// (0: it rests in neutral balance).
        friction_needed: Option<f64>,
    },
}

impl Slide {
    /// The least friction coefficient that would hold the ply, where the forces tell it.
    pub fn friction_needed(&self) -> Option<f64> {
        match self {
            Slide::Away { friction_needed, .. } | Slide::Free { friction_needed, .. } => *friction_needed,
        }
    }

    /// Which coefficient [`Slide::friction_needed`] is about.
    pub fn about(&self) -> Needed {
        match self {
            Slide::Away { about, .. } => *about,
            Slide::Free { .. } => Needed::Friction,
        }
    }

    /// What happened and what would hold the ply, in words.
    pub fn describe(&self) -> String {
        let hold = match self.friction_needed() {
            Some(mu) if mu < 1e-6 => {
                "; it rests in neutral balance: any friction, or a hold, keeps it in place".to_string()
            }
            Some(mu) if self.about() == Needed::PlyFriction => format!(
                "; ply_friction >= {mu:.3} between it and the plies below would hold it (or hold nodes with `hold`)"
            ),
            Some(mu) => format!("; friction mu >= {mu:.3} would hold it (or hold nodes with `hold`)"),
            None => "; hold nodes with `hold`, or give friction".to_string(),
        };
        match self {
            Slide::Away { distance, about, .. } => {
                let over = if *about == Needed::PlyFriction { "the plies below" } else { "the tool" };
                format!("slides: the ply slid {:.1} mm over {over} and friction cannot stop it{hold}", distance * 1e3)
            }
            Slide::Free { motions, .. } => format!(
                "slides: frictionless and held by nothing, the ply is free to move rigidly over the tool \
                 ({motions} independent motion{}){hold}",
                if *motions == 1 { "" } else { "s" }
            ),
        }
    }
}

/// A refined net and what the solver did.
#[derive(Debug, Clone)]
pub struct Refined {
    /// The refined net.
    pub net: DrapeNet,
    /// One report per solve: each load step's solves in order ([`Refined::increments`] says
    /// how many each took).
    pub steps: Vec<SolveReport>,
    /// One record per load step begun.
    pub increments: Vec<Increment>,
    /// How each node meets the tool at the end.
    pub contact: ContactRecord,
    /// Where the ply has no equilibrium: why.
    pub slide: Option<Slide>,
    /// Energy (full load) of the kinematic net as given.
    pub energy_kinematic: f64,
    /// Energy (full load) of the state the solver started from: the kinematic net moved onto the
    /// smooth tool in pressed contact on [`PressedSurface::Smooth`] (or the ply draped on the
    /// smooth surface, [`refine_draped`]), else the kinematic net. Moving
    /// nodes from the facets onto the patches stretches the fibres, and a smooth tool can need a
    /// little more shear than its facets, so the refined energy is bounded by this one, and by
    /// `energy_kinematic` only on the facets.
    pub energy_start: f64,
    /// Energy (full load) of the refined net.
    pub energy_final: f64,
    /// A forming process: how its binder held the blank at the end (the plane, the nodes).
    pub grip: Option<Grip>,
}

impl Refined {
    /// The stability check's verdict on the final state (`minimum`, `saddle`, `unresolved`),
    /// when it ran (the last load step converged and the check was on).
    pub fn stability_verdict(&self) -> Option<Stability> {
        Some(self.steps.last()?.stability.as_ref()?.verdict)
    }

    /// Whether every load step reached equilibrium, with friction that agrees with it, and
    /// the ply is held there.
    pub fn ok(&self) -> bool {
        self.outcome() == Outcome::Converged
    }
    /// How the refinement ended: how the last solve ended, unless the ply slides or its
    /// friction never agreed with a solution.
    pub fn outcome(&self) -> Outcome {
        let last = self.steps.last().map_or(Outcome::Converged, |s| s.outcome);
        let unsettled = self.increments.iter().any(|i| !i.settled(self.contact.largest_friction()));
        if self.slide.is_some() {
            Outcome::Slides
        } else if last == Outcome::Slides || (last == Outcome::Converged && unsettled) {
            // A solve stopped to take the normal forces again, and no more were allowed.
            Outcome::FrictionUnsettled
        } else {
            last
        }
    }

    /// Why the refinement did not reach equilibrium, in words: the outcome, the load step, and
    /// where the forces are furthest from balance and which energy term dominates there.
    pub fn describe_failure(&self) -> String {
        if self.ok() {
            return "converged".into();
        }
        if let Some(slide) = &self.slide {
            return slide.describe();
        }
        if self.outcome() == Outcome::FrictionUnsettled {
            let friction = self.contact.largest_friction();
            if let Some((k, i)) = self.increments.iter().enumerate().find(|(_, i)| !i.settled(friction)) {
                let how = if i.lag_change.is_finite() {
                    format!("the normal forces still changed by {:.1}% over the last", 100.0 * i.lag_change)
                } else {
                    "the ply was still moving (each solve stopped after it travelled or slid a little)".into()
                };
                return format!(
                    "{} in load step {} after {} solves: {how}",
                    Outcome::FrictionUnsettled.describe(),
                    k + 1,
                    i.solves
                );
            }
        }
        // The solve that ended the refinement (the solves before it in its load step stopped
        // only to take the friction's normal forces again).
        let Some((k, step)) = self.steps.iter().enumerate().next_back() else {
            return "converged".into();
        };
        // The load step of the k-th solve.
        let mut first = 0;
        let load_step = self
            .increments
            .iter()
            .position(|i| {
                first += i.solves;
                k < first
            })
            .unwrap_or(k);
        let mut s = format!(
            "{} in load step {} after {} iterations, |F-P|/|P| = {:.2e}",
            step.outcome.describe(),
            load_step + 1,
            step.iterations.len(),
            step.residual
        );
        if let Some(status) = &step.subproblem_status {
            s.push_str(&format!(" (Clarabel: {status})"));
        }
        if let Some(u) = step.unbalanced.first() {
            let (i, j) = (u.node / self.net.nv, u.node % self.net.nv);
            s.push_str(&format!("; largest unbalanced force {:.2e} N at node ({i}, {j})", u.force));
            if let Some(t) = u.dominant_term {
                s.push_str(&format!(", mostly {t}"));
            }
        }
        s
    }
}

/// Why a refinement could not start.
#[derive(Debug, thiserror::Error)]
pub enum RefineError {
    /// The net has no placed node.
    #[error("the net has no placed nodes to refine")]
    Empty,
    /// No load step was asked for.
    #[error("load steps must be at least 1")]
    LoadSteps,
    /// The sheet's features do not fit the net.
    #[error("{0}")]
    Sheet(#[from] SheetError),
    /// A node to hold is not in the net's body.
    #[error(
        "cannot hold the fabric point {:.4} m along the warp, {:.4} m along the weft from the origin node: it is node ({}, {}) of the {nu} x {nv} grid, which the mechanical model does not drape (off the grid, not placed, or not in a complete cell joined to the body). Hold a node of the draped ply.",
        at[0], at[1], node[0], node[1]
    )]
    Hold {
        /// The fabric point asked for (u, v from the origin node, m).
        at: [f64; 2],
        /// The grid node there (may lie off the grid).
        node: [f64; 2],
        /// The grid's size.
        nu: usize,
        /// ...
        nv: usize,
    },
}

/// Refine a kinematic net on its tool. Pressed: every node slides on the tool (by default on its
/// smooth patches, [`SmoothSurface`], onto which the kinematic nodes are first moved; see
/// [`PressedSurface`]), the origin node is held and its warp neighbour stays in the plane of the
/// initial warp direction and normal. Free: nodes move freely with one-sided contact with the
/// facets as given, the origin node held likewise.
pub fn refine<L: Laws + ?Sized>(
    kinematic: &DrapeNet,
    tool: &ToolSurface,
    laws: &L,
    settings: &RefineSettings,
) -> Result<Refined, RefineError> {
    refine_on(kinematic, tool, None, laws, settings)
}

/// [`refine`] with the tool's smooth surface already built (`smooth`, of `tool`), for callers
/// that use it before (a kinematic drape on it, or a first step): built once, not per call.
pub fn refine_on<L: Laws + ?Sized>(
    kinematic: &DrapeNet,
    tool: &ToolSurface,
    smooth: Option<&SmoothSurface>,
    laws: &L,
    settings: &RefineSettings,
) -> Result<Refined, RefineError> {
    refine_from(kinematic, &kinematic.positions, tool, smooth, laws, settings)
}

/// [`refine_on`] for a kinematic net draped with `draped`: a pressed refinement on the smooth
/// patches of a net draped on the facets starts from the same ply draped on the smooth surface
/// ([`smooth_start`]); the net stays the kinematic reference. The one way a scene's ply, the
/// automatic choice and the bench refine a net they draped.
pub fn refine_draped<L: Laws + ?Sized>(
    kinematic: &DrapeNet,
    draped: &KinematicSettings,
    tool: &ToolSurface,
    smooth: Option<&SmoothSurface>,
    laws: &L,
    settings: &RefineSettings,
) -> Result<Refined, RefineError> {
    let pressed_on_patches =
        settings.mode == ContactMode::Pressed && settings.pressed_surface == PressedSurface::Smooth;
    if !pressed_on_patches || draped.surface != SurfaceKind::Facets {
        return refine_on(kinematic, tool, smooth, laws, settings);
    }
    let built = smooth.is_none().then(|| SmoothSurface::new(tool));
    let smooth = smooth.or(built.as_ref()).expect("the smooth surface is given or built");
    match smooth_start(kinematic, smooth, draped) {
        // The lower of the two starts: where the smooth drape took another root somewhere (a
        // fold, a sheet jump on a stack of plies) a start mixing it with the facet net tears the
        // fabric (the hemisphere layup's fourth ply once started at 0.14 J against 0.08 J).
        Some(start) => refine_among(kinematic, &[&start, &kinematic.positions], tool, Some(smooth), laws, settings),
        None => refine_on(kinematic, tool, Some(smooth), laws, settings),
    }
}

/// Where a pressed refinement on the smooth patches starts: the same ply draped kinematically
/// on the smooth surface (`settings` as the net `kinematic` was draped with, on `smooth`), so
/// the fibres start at their lengths on the surface the pressed nodes meet. Moving a net draped
/// on the facets onto the patches stretches its fibres where the patches bulge out of the
/// facets, and Newton's first iterations only undo that (the 301 x 301 bench: |F-P|/|P| 1.3e3
/// at the start and 5 iterations, against 7.5e-2 and 3). Nodes the smooth drape did not place
/// start where the kinematic net has them. None when the smooth drape fails or lays out
/// another grid.
fn smooth_start(kinematic: &DrapeNet, smooth: &SmoothSurface, settings: &KinematicSettings) -> Option<Vec<Point>> {
    let settings = KinematicSettings { surface: SurfaceKind::Smooth, ..settings.clone() };
    let on_smooth = drape_smooth(smooth, &settings).ok()?;
    let same_grid =
        (on_smooth.nu, on_smooth.nv, on_smooth.origin_node) == (kinematic.nu, kinematic.nv, kinematic.origin_node);
    same_grid.then(|| {
        (kinematic.positions.iter().zip(&on_smooth.positions))
            .zip(&on_smooth.status)
            .map(|((&own, &there), &status)| if status == NodeStatus::Placed { there } else { own })
            .collect()
    })
}

/// [`refine_on`] with the solver starting from `start` (one position per node of `kinematic`,
/// e.g. a state part of the way to equilibrium) instead of the kinematic net's positions; the
/// kinematic net stays the reference (`energy_kinematic`, the grid and its statuses).
pub fn refine_from<L: Laws + ?Sized>(
    kinematic: &DrapeNet,
    start: &[Point],
    tool: &ToolSurface,
    smooth: Option<&SmoothSurface>,
    laws: &L,
    settings: &RefineSettings,
) -> Result<Refined, RefineError> {
    refine_among(kinematic, &[start], tool, smooth, laws, settings)
}

/// [`refine_from`] from the lowest in energy of `starts` (each one position per node).
fn refine_among<L: Laws + ?Sized>(
    kinematic: &DrapeNet,
    starts: &[&[Point]],
    tool: &ToolSurface,
    smooth: Option<&SmoothSurface>,
    laws: &L,
    settings: &RefineSettings,
) -> Result<Refined, RefineError> {
    assert!(starts.iter().all(|s| s.len() == kinematic.positions.len()), "one start position per node");
    if settings.load_steps == 0 {
        return Err(RefineError::LoadSteps);
    }
    let layout = (!settings.sheet.is_empty())
        .then(|| settings.sheet.layout(kinematic.nu, kinematic.nv, kinematic.spacing, kinematic.origin_node))
        .transpose()?;
    let active = connected_body(kinematic, layout.as_ref());
    if !active.iter().any(|a| *a) {
        return Err(RefineError::Empty);
    }
    let stitched = layout.as_ref().map(|l| l.stitched.clone());
    let cut_cells = layout.as_ref().map(|l| l.cut_cells()).unwrap_or_default();
    let mut grid = Grid::with_active(kinematic.nu, kinematic.nv, kinematic.spacing, active.clone());
    if let Some(layout) = layout {
        grid = grid.with_sheet(layout);
    }
    // Nodes meet the smooth patches: on the facets themselves a net finer than them crawls from
    // edge to edge (see the module doc of `geometry::smooth`).
    let on_patches = settings.pressed_surface == PressedSurface::Smooth;
    let built = (on_patches && smooth.is_none()).then(|| SmoothSurface::new(tool));
    let smooth = if on_patches { smooth.or(built.as_ref()) } else { None };
    let surface: &dyn ContactSurface = match smooth {
        Some(s) => s,
        None => tool,
    };
    let placed = |start: &[Point]| {
        let mut x = start.to_vec();
        // (A blank to be formed starts as it was laid.)
        if let (Some(smooth), ContactMode::Pressed, None) = (smooth, settings.mode, &settings.forming) {
            use rayon::prelude::*;
            x.par_iter_mut().zip(&active).filter(|(_, a)| **a).for_each(|(p, _)| *p = smooth.project(p).point);
        }
        x
    };
    // Nothing holds the ply but the tool, friction and the nodes the user holds.
    let mut held = vec![false; active.len()];
    let mut held_nodes = Vec::new();
    for &[u, v] in &settings.holds {
        let (i0, j0) = kinematic.origin_node;
        let at = |o: usize, w: f64| (o as f64 + w / kinematic.spacing).round();
        let (i, j) = (at(i0, u), at(j0, v));
        let inside = i >= 0.0 && j >= 0.0 && (i as usize) < kinematic.nu && (j as usize) < kinematic.nv;
        match inside.then(|| kinematic.index(i as usize, j as usize)) {
            Some(k) if active[k] => {
                held[k] = true;
                held_nodes.push([i as usize, j as usize]);
            }
            _ => return Err(RefineError::Hold { at: [u, v], node: [i, j], nu: kinematic.nu, nv: kinematic.nv }),
        }
    }
    // A forming process meets its tools with one-sided contact, in as many increments as its
    // stroke needs.
    let forming = settings.forming.as_ref();
    // A formed ply held again by its tools where the stroke ended starts from equilibrium.
    let held_again = forming.is_some_and(|f| f.at_stroke_end);
    let mode = if forming.is_some() { ContactMode::Free } else { settings.mode };
    let load_steps = forming.map_or(settings.load_steps, |f| f.increments(kinematic.spacing, settings.load_steps));
    let freedom: Vec<Freedom> = (0..active.len())
        .map(|k| match (active[k] && !held[k], mode) {
            (false, _) => Freedom::Fixed,
            (true, ContactMode::Pressed) => Freedom::OnTool,
            (true, _) => Freedom::Free,
        })
        .collect();
    // The blank's plane (the binder grips in it): the set-up's, else where the flat blank was
    // laid.
    let origin_index = kinematic.index(kinematic.origin_node.0, kinematic.origin_node.1);
    let plane = forming.map(|f| {
        f.blank_plane.unwrap_or_else(|| BlankPlane {
            point: starts[0][origin_index],
            normal: crate::kinematic::draw_in::seed_normal(kinematic).unwrap_or_else(Vector::z),
        })
    });
    let blank_plane = plane.map(|p| (p.point, p.normal));
    // The die is met as the punch is: on its smooth surface (on its facets a node at the entry
    // fillet, whose facets turn by a tenth of a right angle each, crawls from one to the next).
    let die_tool = forming.and_then(|f| f.die.as_deref());
    let die_smooth = die_tool.filter(|_| on_patches).map(SmoothSurface::new);
    let die: Option<&dyn ContactSurface> = match (&die_smooth, die_tool) {
        (Some(s), _) => Some(s),
        (None, d) => d.map(|d| d as &dyn ContactSurface),
    };
    let plan_view = forming.map(|f| PlanView::across(&f.stroke));
    // The nodes that may move at all (the binder grips only these).
    let body: Vec<bool> = freedom.iter().map(|f| f.dofs() > 0).collect();
    let mut steps = Vec::new();
    let mut increments = Vec::new();
    let mut objective = NetObjective::new(grid, laws, settings.gravity / load_steps as f64);
    // Each node's share of the fabric, m^2: what the binder's pressure acts on.
    let areas = objective.grid().nodal_masses(1.0);
    let solver_settings = settings.solver.clone();
    // Energies under the full load, for comparison with the result. The first step carries 1/S
    // of the load, so the full load does (S - 1) times more work.
    let full_load = |objective: &NetObjective, x: &[Point]| {
        objective.evaluate(x, false).energy - (load_steps - 1) as f64 * objective.work(x)
    };
    let energy_kinematic = full_load(&objective, &kinematic.positions);
    let (mut x, energy_start) = starts
        .iter()
        .map(|s| {
            let x = placed(s);
            let e = full_load(&objective, &x);
            (x, e)
        })
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .expect("at least one start");
    let stick_distance = STICK_SPACINGS * kinematic.spacing;
    // How far each node slid over the tool, over all increments.
    let mut slid = vec![0.0; x.len()];
    // The coefficients the ply meets, and the largest: 0, frictionless everywhere.
    let coulomb = settings.coulomb();
    let friction = coulomb.largest();
    let mut lag = FrictionLag::new(friction, stick_distance, &x, vec![None; x.len()]);
    let mut slide = None;
    let mut grip = None;
    // Forming: the equilibrium the increment before this one began from (the predictor's).
    let mut previous_equilibrium: Option<Vec<Point>> = None;
    for step in 1..=load_steps {
        if step > 1 {
            objective.scale_loads(step as f64 / (step - 1) as f64);
        }
        // The tools where this increment leaves them, and the nodes the binder grips as it
        // begins: they slide in the blank's plane, friction on both faces.
        let tools_at = forming.map(|f| ToolsAt {
            punch: surface,
            punch_facets: tool.num_triangles() as u32,
            offset: f.punch_offset(step, load_steps),
            step: f.punch_step(step, load_steps),
            die,
        });
        let binder = forming.and_then(|f| f.binder.as_ref());
        let gripped = match (binder, plan_view, blank_plane) {
            (Some(b), Some(view), Some((point, normal))) => {
                b.gripped(&view, &x, &body, &point, &normal, kinematic.spacing)
            }
            _ => vec![false; x.len()],
        };
        grip = plane.map(|plane| Grip { plane, nodes: gripped.clone() });
        let cons = Constraints {
            freedom: (freedom.iter().zip(&gripped))
                .map(|(&f, &g)| match (g, blank_plane) {
                    (true, Some((_, normal))) => Freedom::InPlane(normal),
                    _ => f,
                })
                .collect(),
            mode,
            tool: Some(tools_at.as_ref().map_or(surface, |t| t as &dyn ContactSurface)),
            spacing: kinematic.spacing,
            stitched: stitched.clone(),
            stick: settings.stick,
        };
        // Where the nodes bear: on the tools, and the gripped ones on the binder.
        let bear = |x: &[Point], eval: &Evaluation| {
            let mut b = bearings(&cons, x, eval, &coulomb);
            if let (Some(binder), Some((_, normal))) = (binder, blank_plane) {
                for (k, _) in gripped.iter().enumerate().filter(|(_, g)| **g) {
                    b[k] = Some(binder.bearing(&normal, areas[k], coulomb.binder()));
                }
            }
            b
        };
        // The increment's friction: normal forces of this state under this increment's load,
        // slips from here; then the normal forces of each solution, until they agree, slips
        // still from here (a node slid under the first normal forces, too weak, is pulled back by
        // the next ones if they hold it). The first increment starts where the ply was laid: its
        // normal forces are the load's (the fabric's own forces there are those of a start off
        // equilibrium, such as a net draped on the facets moved onto the smooth tool, and would
        // grip with friction that no laid ply has); every later one starts from an equilibrium,
        // and so does a formed ply held again where its stroke ended: the tools' reactions to
        // its forces are what its friction bears on (with the load's alone it grips too weakly
        // and creeps: 0.012 spacings on a cylindrical punch through a binder's slot).
        let mut eval = objective.evaluate(&x, false);
        if step == 1 && !held_again {
            eval.internal.iter_mut().for_each(|f| *f = Vector::zeros());
        }
        lag = FrictionLag::new(friction, stick_distance, &x, bear(&x, &eval));
        // ... and with the friction forces that hold it there.
        if held_again {
            lag.preload(&cons, &x, &eval);
        }
        if forming.is_some() {
            // The solve starts where the last increment's motion, repeated, takes the ply (a
            // secant predictor along the stroke's path: the fabric goes on drawing in and
            // wrapping the punch as it did), each node by at most a spacing; friction's slips
            // still count from the equilibrium. From the equilibrium itself the first
            // iterations would only redo that motion (the double dome's +45 ply at 10 mm: 333
            // iterations -> 266).
            let equilibrium = x.clone();
            if let Some(earlier) = &previous_equilibrium {
                for ((p, e), _) in x.iter_mut().zip(earlier).zip(&body).filter(|(_, b)| **b) {
                    let motion = *p - e;
                    *p += motion * (kinematic.spacing / motion.norm()).min(1.0);
                }
            }
            previous_equilibrium = Some(equilibrium);
        }
        let limit = slide_limit(&lag, kinematic.spacing);
        let mut increment =
            Increment { load_factor: step as f64 / load_steps as f64, solves: 0, iterations: 0, lag_change: 0.0 };
        // The iterations of a load step, shared by its solves.
        let mut budget = solver_settings.max_iterations;
        let ok = loop {
            increment.solves += 1;
            let before = x.clone();
            // With friction, and while nothing bears on the tool (a ply dropped onto it: its
            // lag, bearing nothing, would not see it slide away after it lands).
            let travel = (friction > 0.0 || lag.total_force() <= 0.0)
                .then_some((before.as_slice(), RELAG_TRAVEL_SPACINGS * kinematic.spacing));
            let step_limit = lag.mean_slip(&x) + RELAG_SHARE * limit;
            let frictional = Frictional { inner: &objective, lag: &lag, slide_limit: step_limit, travel };
            let mut this_solve = solver_settings.clone().max_iterations(budget);
            if forming.is_some() {
                // Forming is driven by the tools: their forces set the scale of balance.
                this_solve.reaction_scale = Some(reaction_scale(&lag, &gripped));
            }
            let report = solve(&frictional, &mut x, &cons, &this_solve);
            budget = budget.saturating_sub(report.iterations.len());
            increment.iterations += report.iterations.len();
            let outcome = report.outcome;
            steps.push(report);
            let now = bear(&x, &objective.evaluate(&x, false));
            increment.lag_change = lag_change(&lag.bearing, &now);
            // How far the ply slid over the tool in this increment (normal-force weighted mean).
            let sliding = lag.mean_slip(&x);
            let last_try = increment.solves >= MAX_LAGS || budget == 0;
            match outcome {
                Outcome::Slides if sliding > limit => {
                    // The last solve's move is the slide itself (the first may settle the ply too).
                    let moved: Vec<Vector> = x.iter().zip(&before).map(|(p, o)| p - o).collect();
                    let needed = friction_needed(&moved, &objective.loads, &now);
                    slide = Some(Slide::Away {
                        distance: sliding,
                        friction_needed: needed.map(|(mu, _)| mu),
                        about: needed.map_or(Needed::Friction, |(_, about)| about),
                    });
                    lag.bearing = now;
                    break false;
                }
                // Still moving after every solve an increment may take.
                Outcome::Slides if last_try => {
                    lag.bearing = now;
                    increment.lag_change = f64::INFINITY;
                    break true;
                }
                // It slid a little, or travelled a few spacings, with the normal forces of where
                // it began: on from here, with those where it is now.
                Outcome::Slides => {}
                Outcome::Converged if friction == 0.0 || increment.lag_change <= LAG_TOLERANCE || last_try => {
                    lag.bearing = now;
                    break true;
                }
                Outcome::Converged => {}
                // A solve that stopped short with normal forces far from those where it stopped
                // may have been held back by them (a start whose forces were the load's alone):
                // once more with the forces where it is.
                _ if friction > 0.0 && increment.lag_change > LAG_TOLERANCE && !last_try => {}
                // A solve that stalled, or found no step lowering the energy, with nodes sliding
                // at the edge of their stick distance (where friction's slope turns from the stiff
                // stick to the constant slide and Newton's model of it is poor: the 61 x 61
                // punch-and-die blank stopped at |F-P|/|P| = 1.5e-4, a node on the die's face
                // mostly friction): what they slid is banked, and they stick again where they are.
                Outcome::Stalled | Outcome::LineSearchFailed if friction > 0.0 && !last_try => {
                    for (k, s) in slid.iter_mut().enumerate() {
                        *s += lag.slip(k, &x[k]).norm();
                    }
                    lag.anchor(&x);
                }
                _ => {
                    lag.bearing = now;
                    break false;
                }
            }
            lag.relag(&x, now);
        };
        for (k, s) in slid.iter_mut().enumerate() {
            *s += lag.slip(k, &x[k]).norm();
        }
        let settled = increment.settled(friction);
        increments.push(increment);
        if !ok || !settled {
            break;
        }
    }
    // A frictionless ply that nothing holds, on a tool that lets it move rigidly (a plane, a
    // cylinder, a sphere): its place is not determined, however well its forces balance.
    // (Converged or not: a solve chasing such a motion may not settle at all.)
    let free_to_move = friction == 0.0 && !settings.stick && settings.holds.is_empty();
    if slide.is_none() && free_to_move {
        let motions = tangent_rigid_motions(&x, &lag.bearing);
        if !motions.is_empty() {
            let needed = motions
                .iter()
                .filter_map(|v| friction_needed(v, &objective.loads, &lag.bearing).map(|(mu, _)| mu))
                .fold(None, |m: Option<f64>, f| Some(m.map_or(f, |m| m.max(f))));
            slide = Some(Slide::Free { motions: motions.len(), friction_needed: needed });
        }
    }
    let energy_final = objective.evaluate(&x, false).energy;
    let contact = contact_record(&objective, &lag, &x, &slid, (&active, &held, held_nodes), settings, &slide);
    let mut net = kinematic.clone();
    net.method = Method::Mechanical;
    net.meta.cut_cells = cut_cells;
    net.meta.sheet_features = settings.sheet.kinds();
    for (k, p) in x.iter().enumerate() {
        if active[k] {
            net.positions[k] = *p;
            net.triangles[k] = tool.closest_point(p).triangle;
        } else if net.status[k] == NodeStatus::Placed {
            net.status[k] = NodeStatus::Detached;
        }
    }
    Ok(Refined { net, steps, increments, contact, slide, energy_kinematic, energy_start, energy_final, grip })
}

/// The slide beyond which a ply has no equilibrium: [`SLIDE_SHARE`] of the region bearing on
/// the tool, and at least [`SLIDE_MIN_SPACINGS`] spacings.
fn slide_limit(lag: &FrictionLag, spacing: f64) -> f64 {
    (SLIDE_SHARE * lag.extent()).max(SLIDE_MIN_SPACINGS * spacing)
}

/// The forces the tools exert on a formed ply, as the lag has them (N, their norm over the
/// nodes): the punch's and the die's normal forces, and the binder's grip in its plane (its
/// friction capacity: the binder's normal force only clamps).
fn reaction_scale(lag: &FrictionLag, gripped: &[bool]) -> f64 {
    (lag.bearing.iter().zip(gripped))
        .filter_map(|(b, &g)| {
            let b = b.as_ref()?;
            let f = b.force.max(0.0);
            Some(if g { b.mu * f } else { f })
        })
        .map(|f| f * f)
        .sum::<f64>()
        .sqrt()
}

/// How much the normal forces changed from `before` to `after`: the sum of the changes over the
/// sum of the forces.
fn lag_change(before: &[Option<Bearing>], after: &[Option<Bearing>]) -> f64 {
    let force = |b: &Option<Bearing>| b.map_or(0.0, |b| b.force);
    let total: f64 = after.iter().map(force).sum::<f64>().max(before.iter().map(force).sum());
    if total <= 0.0 {
        return 0.0;
    }
    before.iter().zip(after).map(|(a, b)| (force(a) - force(b)).abs()).sum::<f64>() / total
}

/// Each node's contact at the end: its state, how far it slid, its pressure.
#[allow(clippy::too_many_arguments)] // the refinement's own locals
fn contact_record(
    objective: &NetObjective,
    lag: &FrictionLag,
    x: &[Point],
    slid: &[f64],
    (active, held, held_nodes): (&[bool], &[bool], Vec<[usize; 2]>),
    settings: &RefineSettings,
    slide: &Option<Slide>,
) -> ContactRecord {
    let areas = objective.grid().nodal_areas();
    let n = x.len();
    let mut state = vec![None; n];
    let mut slip_m = vec![None; n];
    let mut pressure_pa = vec![None; n];
    for k in (0..n).filter(|&k| active[k]) {
        let bearing = lag.bearing[k];
        state[k] = Some(match bearing {
            _ if held[k] => ContactState::Held,
            None => ContactState::Free,
            Some(_) if lag.slip(k, &x[k]).norm() < lag.stick => ContactState::Stick,
            Some(_) => ContactState::Slip,
        });
        slip_m[k] = Some(slid[k]);
        let force = bearing.map_or(0.0, |b| b.force);
        pressure_pa[k] = Some(if areas[k] > 0.0 { force / areas[k] } else { 0.0 });
    }
    ContactRecord {
        friction: settings.friction,
        ply_friction: settings.plies_below.as_ref().map(|p| p.mu),
        sticky: settings.stick,
        state,
        slip_m,
        pressure_pa,
        held: held_nodes,
        friction_needed: slide.as_ref().and_then(Slide::friction_needed),
        friction_needed_between: slide
            .as_ref()
            .filter(|s| s.friction_needed().is_some() && s.about() == Needed::PlyFriction)
            .map(|_| BETWEEN_PLIES.to_string()),
    }
}

/// The nodes of the net's body: the corners of the complete cells joined by shared fibre links
/// (not cut) or by stitched nodes to the cell at the origin node (or, without one, to the
/// largest such group). Cells that hang on the rest by a single corner, and placed nodes in no
/// complete cell, are mechanisms the energy does not hold (they would swing about their
/// corner): the mechanical model leaves them out.
pub fn connected_body(net: &DrapeNet, layout: Option<&SheetLayout>) -> Vec<bool> {
    let (nu, nv) = (net.nu, net.nv);
    let mut body = vec![false; nu * nv];
    if nu < 2 || nv < 2 {
        return body;
    }
    let (cu, cv) = (nu - 1, nv - 1);
    let placed = |i: usize, j: usize| net.status[net.index(i, j)] == NodeStatus::Placed;
    let complete = |i: usize, j: usize| {
        placed(i, j)
            && placed(i + 1, j)
            && placed(i, j + 1)
            && placed(i + 1, j + 1)
            && !layout.is_some_and(|l| l.cell_cut(i, j))
    };
    let cells: Vec<bool> = (0..cu * cv).map(|c| complete(c / cv, c % cv)).collect();
    let mut parent: Vec<usize> = (0..cells.len()).collect();
    fn join(parent: &mut [usize], a: usize, b: usize) {
        let (ra, rb) = (union_find_root(parent, a), union_find_root(parent, b));
        parent[ra] = rb;
    }
    for i in 0..cu {
        for j in 0..cv {
            let c = i * cv + j;
            if !cells[c] {
                continue;
            }
            // Across the weft link (i+1, j)-(i+1, j+1) to the next cell along the warp, across the
            // warp link (i, j+1)-(i+1, j+1) to the next along the weft.
            if i + 1 < cu && cells[c + cv] && !layout.is_some_and(|l| l.weft_cut(i + 1, j)) {
                join(&mut parent, c, c + cv);
            }
            if j + 1 < cv && cells[c + 1] && !layout.is_some_and(|l| l.warp_cut(i, j + 1)) {
                join(&mut parent, c, c + 1);
            }
        }
    }
    // Stitched nodes join the cells around them.
    if let Some(layout) = layout {
        let cell_at = |k: usize| -> Option<usize> {
            let (i, j) = (k / nv, k % nv);
            [(i, j), (i.wrapping_sub(1), j), (i, j.wrapping_sub(1)), (i.wrapping_sub(1), j.wrapping_sub(1))]
                .into_iter()
                .filter(|&(a, b)| a < cu && b < cv)
                .map(|(a, b)| a * cv + b)
                .find(|&c| cells[c])
        };
        for (k, &r) in layout.stitched.iter().enumerate() {
            if r != k {
                if let (Some(a), Some(b)) = (cell_at(k), cell_at(r)) {
                    join(&mut parent, a, b);
                }
            }
        }
    }
    let mut size = vec![0usize; cells.len()];
    for (c, _) in cells.iter().enumerate().filter(|(_, &complete)| complete) {
        size[union_find_root(&mut parent, c)] += 1;
    }
    // The group at the origin node, else the largest.
    let (i0, j0) = net.origin_node;
    let at_origin =
        [(i0, j0), (i0.wrapping_sub(1), j0), (i0, j0.wrapping_sub(1)), (i0.wrapping_sub(1), j0.wrapping_sub(1))]
            .into_iter()
            .filter(|&(i, j)| i < cu && j < cv && cells[i * cv + j])
            .map(|(i, j)| union_find_root(&mut parent, i * cv + j))
            .max_by_key(|&r| size[r]);
    let Some(chosen) = at_origin.or_else(|| {
        (0..cells.len()).filter(|&c| cells[c]).map(|c| union_find_root(&mut parent, c)).max_by_key(|&r| size[r])
    }) else {
        return body;
    };
    for (c, _) in cells.iter().enumerate().filter(|(_, &complete)| complete) {
        if union_find_root(&mut parent, c) == chosen {
            let (i, j) = (c / cv, c % cv);
            for (a, b) in [(i, j), (i + 1, j), (i, j + 1), (i + 1, j + 1)] {
                body[net.index(a, b)] = true;
            }
        }
    }
    body
}

/// Per-cell change from `before` to `after` (same grid): (shear difference, angle between the
/// warp directions), radians; None where a cell is missing in either.
pub fn cell_changes(before: &DrapeNet, after: &DrapeNet) -> Vec<Option<(f64, f64)>> {
    let mut out = Vec::with_capacity(before.num_cells());
    for i in 0..before.nu - 1 {
        for j in 0..before.nv - 1 {
            let c = match (
                before.cell_shear(i, j),
                after.cell_shear(i, j),
                before.cell_frame(i, j),
                after.cell_frame(i, j),
            ) {
                (Some(g0), Some(g1), Some(f0), Some(f1)) => Some((g1 - g0, f0.warp.angle(&f1.warp))),
                _ => None,
            };
            out.push(c);
        }
    }
    out
}

/// Record the solver's work and the per-cell change from the kinematic net in the net's meta.
pub fn annotate(out: &mut DrapeNet, kinematic: &DrapeNet, refined: &Refined, material: &std::path::Path) {
    let changes = cell_changes(kinematic, &refined.net);
    out.meta.change_from_kinematic = Some(CellChanges {
        shear_deg: changes.iter().map(|c| c.map(|(g, _)| g.to_degrees())).collect(),
        warp_angle_deg: changes.iter().map(|c| c.map(|(_, a)| a.to_degrees())).collect(),
    });
    out.meta.material = Some(material.display().to_string());
    out.meta.contact = Some(refined.contact.clone());
    let last = refined.steps.last();
    let unbalanced = last
        .map(|s| {
            s.unbalanced
                .iter()
                .map(|u| UnbalancedRecord {
                    node: [u.node / out.nv, u.node % out.nv],
                    position: out.positions[u.node].coords.into(),
                    force_n: u.force,
                    term: u.dominant_term.map(str::to_string),
                })
                .collect()
        })
        .unwrap_or_default();
    out.meta.solver = Some(SolverRecord {
        outcome: refined.outcome().name().to_string(),
        converged: refined.ok(),
        reason: (!refined.ok()).then(|| refined.describe_failure()),
        residual: last.map_or(0.0, |s| s.residual),
        iterations: refined.steps.iter().map(|s| s.iterations.len()).sum(),
        unbalanced,
        energy_kinematic: refined.energy_kinematic,
        energy_start: refined.energy_start,
        energy_final: refined.energy_final,
        stability: refined.stability_verdict(),
        load_steps: serde_json::to_value(&refined.steps).unwrap_or_default(),
        increments: serde_json::to_value(&refined.increments).unwrap_or_default(),
    });
}
