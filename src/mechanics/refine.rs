//! Mechanical refinement of a draped net: the energy model on its grid, minimised from the
//! kinematic state with the tool as contact, under load steps of gravity.
use super::contact::{ContactMode, ContactSurface, Freedom};
use super::energy::{Grid, HessianKind, Laws, Model};
use super::solver::{solve, Constraints, Evaluation, HessianBlocks, Objective, Outcome, SolveReport, SolverSettings};
use crate::geometry::{Point, SmoothSurface, ToolSurface, Vector};
use crate::kinematic::{DrapeNet, Method, NodeStatus};

/// Which Hessian the quadratic models use.
const HESSIAN: HessianKind = HessianKind::Convex;

/// Standard gravity, m/s^2.
pub const STANDARD_GRAVITY: f64 = 9.80665;

/// The energy of a net's grid as the solver sees it: internal energy from the model, and
/// gravity as constant nodal loads P = m g.
pub struct NetObjective<'a> {
    model: Model<'a>,
    loads: Vec<Vector>,
    pairs: Vec<(usize, usize)>,
}

impl<'a> NetObjective<'a> {
    /// Stretch, shear and bending of `laws` on `grid`, loaded by `gravity` (m/s^2) times
    /// `load_factor`.
    pub fn new<L: Laws + ?Sized>(grid: Grid, laws: &'a L, gravity: Vector) -> Self {
        let areas = grid.nodal_areas();
        let loads = areas.iter().map(|a| gravity * (a * laws.areal_mass())).collect();
        let model = Model::new(grid, laws, Vector::zeros());
        let pairs = model.pattern().coupled_pairs();
        NetObjective { model, loads, pairs }
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
    fn coupled_pairs(&self) -> Vec<(usize, usize)> {
        self.pairs.clone()
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
    /// How the term moves: pressed, free or none.
    pub mode: ContactMode,
    /// What pressed nodes slide on.
    pub pressed_surface: PressedSurface,
    /// Gravity, m/s^2.
    pub gravity: Vector,
    /// Gravity is applied in this many equal steps.
    pub load_steps: usize,
    /// The solver's settings.
    pub solver: SolverSettings,
}

impl Default for RefineSettings {
    fn default() -> Self {
        RefineSettings {
            mode: ContactMode::Pressed,
            pressed_surface: PressedSurface::Smooth,
            gravity: Vector::new(0.0, 0.0, -STANDARD_GRAVITY),
            load_steps: 1,
            solver: SolverSettings::default(),
        }
    }
}

/// A refined net and what the solver did.
#[derive(Debug, Clone)]
pub struct Refined {
    /// The refined net.
    pub net: DrapeNet,
    /// One report per load step.
    pub steps: Vec<SolveReport>,
    /// Energy (full load) of the kinematic net as given.
    pub energy_kinematic: f64,
    /// Energy (full load) of the state the solver started from: the kinematic net moved onto the
    /// smooth tool in pressed contact on [`PressedSurface::Smooth`], else the kinematic net. Moving
    /// nodes from the facets onto the patches stretches the fibres, and a smooth tool can need a
    /// little more shear than its facets, so the refined energy is bounded by this one, and by
    /// `energy_kinematic` only on the facets.
    pub energy_start: f64,
    /// Energy (full load) of the refined net.
    pub energy_final: f64,
}

impl Refined {
    /// Whether every load step reached equilibrium.
    pub fn ok(&self) -> bool {
        self.steps.iter().all(SolveReport::ok)
    }
    /// How the last load step ended.
    pub fn outcome(&self) -> Outcome {
        self.steps.last().map_or(Outcome::Converged, |s| s.outcome)
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
    if settings.load_steps == 0 {
        return Err(RefineError::LoadSteps);
    }
    let active: Vec<bool> = kinematic.status.iter().map(|s| *s == NodeStatus::Placed).collect();
    if !active.iter().any(|a| *a) {
        return Err(RefineError::Empty);
    }
    let grid = Grid::with_active(kinematic.nu, kinematic.nv, kinematic.spacing, active.clone());
    // Pressed nodes slide on the smooth patches: on the facets themselves a net finer than them
    // crawls from edge to edge (see the module doc of `geometry::smooth`). Free contact keeps the
    // nodes out of the facets as given.
    let on_patches = settings.mode == ContactMode::Pressed && settings.pressed_surface == PressedSurface::Smooth;
    let smooth = on_patches.then(|| SmoothSurface::new(tool));
    let surface: &dyn ContactSurface = match &smooth {
        Some(s) => s,
        None => tool,
    };
    let mut x = kinematic.positions.clone();
    if let Some(smooth) = &smooth {
        use rayon::prelude::*;
        x.par_iter_mut().zip(&active).filter(|(_, a)| **a).for_each(|(p, _)| *p = smooth.project(p).point);
    }
    let (i0, j0) = kinematic.origin_node;
    let origin = kinematic.index(i0, j0);
    let warp_neighbour = if i0 + 1 < kinematic.nu { Some(kinematic.index(i0 + 1, j0)) } else { None };
    let n0 = surface.locate(&x[origin]).normal;
    let plane_normal =
        warp_neighbour.filter(|&k| active[k]).and_then(|k| (x[k] - x[origin]).cross(&n0).try_normalize(1e-12));
    let freedom: Vec<Freedom> = (0..active.len())
        .map(|k| {
            if !active[k] || k == origin {
                Freedom::Fixed
            } else if Some(k) == warp_neighbour && plane_normal.is_some() {
                match settings.mode {
                    ContactMode::Pressed => Freedom::OnToolInPlane(plane_normal.unwrap()),
                    _ => Freedom::InPlane(plane_normal.unwrap()),
                }
            } else {
                match settings.mode {
                    ContactMode::Pressed => Freedom::OnTool,
                    _ => Freedom::Free,
                }
            }
        })
        .collect();
    // The residual is measured against the kinematic net's forces as given (on the facets).
    let facet_cons =
        Constraints { freedom: freedom.clone(), mode: settings.mode, tool: Some(tool), spacing: kinematic.spacing };
    let cons = Constraints { freedom, mode: settings.mode, tool: Some(surface), spacing: kinematic.spacing };
    let mut steps = Vec::new();
    let mut objective = NetObjective::new(grid, laws, settings.gravity / settings.load_steps as f64);
    let mut solver_settings = settings.solver.clone();
    if solver_settings.force_scale.is_none() {
        // At the full load: the one the last step must balance.
        let full = NetObjective::new(objective.grid().clone(), laws, settings.gravity);
        solver_settings.force_scale = Some(super::solver::force_scale(&full, &kinematic.positions, &facet_cons));
    }
    // Energies under the full load, for comparison with the result. The first step carries 1/S
    // of the load, so the full load does (S - 1) times more work.
    let full_load = |objective: &NetObjective, x: &[Point]| {
        objective.evaluate(x, false).energy - (settings.load_steps - 1) as f64 * objective.work(x)
    };
    let energy_kinematic = full_load(&objective, &kinematic.positions);
    let energy_start = full_load(&objective, &x);
    for step in 1..=settings.load_steps {
        if step > 1 {
            objective.scale_loads(step as f64 / (step - 1) as f64);
        }
        let report = solve(&objective, &mut x, &cons, &solver_settings);
        let ok = report.ok();
        steps.push(report);
        if !ok {
            break;
        }
    }
    let energy_final = objective.evaluate(&x, false).energy;
    let mut net = kinematic.clone();
    net.method = Method::Mechanical;
    for (k, p) in x.iter().enumerate() {
        if active[k] {
            net.positions[k] = *p;
            net.triangles[k] = tool.closest_point(p).triangle;
        }
    }
    Ok(Refined { net, steps, energy_kinematic, energy_start, energy_final })
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
    let shear: Vec<Option<f64>> = changes.iter().map(|c| c.map(|(g, _)| g.to_degrees())).collect();
    let angle: Vec<Option<f64>> = changes.iter().map(|c| c.map(|(_, a)| a.to_degrees())).collect();
    out.meta.insert("change_from_kinematic".into(), serde_json::json!({"shear_deg": shear, "warp_angle_deg": angle}));
    out.meta.insert("material".into(), serde_json::json!(material.display().to_string()));
    out.meta.insert(
        "solver".into(),
        serde_json::json!({
            "outcome": refined.outcome(),
            "energy_kinematic": refined.energy_kinematic,
            "energy_start": refined.energy_start,
            "energy_final": refined.energy_final,
            "load_steps": refined.steps,
        }),
    );
}
