//! Running one case: the studied ply, changed as the case's [`Variant`] says, draped alone on its
//! tool, timed, and summed up in a [`CaseResult`].
use super::plan::{Case, StudyMethod, Variant};
use crate::geometry::{Point, ToolSurface};
use crate::kinematic::fabric_field::ShearField;
use crate::kinematic::MethodChoice;
use crate::kinematic::{DrapeNet, Extent, GeneratorKind, NodeStatus};
use crate::layup::auto::DEFAULT_TOLERANCE_DEG;
use crate::layup::stack::{drape_layup, resolve_warp, PlyStats};
use crate::layup::{AutoModel, Layup, Orientation, Ply, Refinement};
use crate::material::TensionLaw;
use crate::mechanics::ContactMode;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::time::Instant;

/// Most nodes a kinematic case may have (a finer spacing is refused with its reason).
pub const MAX_KINEMATIC_NODES: usize = 4_000_000;
/// Most nodes a mechanical case may have: larger nets take minutes per case.
pub const MAX_MECHANICAL_NODES: usize = 40_000;

/// What one case gave.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CaseResult {
    /// `ok`, or why not: a refused input, the dominant node failure, or the solver's outcome.
    pub outcome: String,
    /// Median time of the repeats, seconds: drape and refine of the ply, not reading the tool.
    pub time_s: f64,
    /// Every repeat's time, seconds.
    pub times_s: Vec<f64>,
    /// Triangles of the tool the case ran on.
    pub tool_triangles: usize,
    /// Nodes of the grid.
    pub nodes: usize,
    /// Placed nodes over the grid's nodes (nodes outside an outline left out of both).
    pub placed_fraction: f64,
    /// Largest |cell shear|, degrees (absent without a complete cell).
    pub max_shear_deg: Option<f64>,
    /// Nodes not placed, by reason.
    pub failures: BTreeMap<String, usize>,
    /// Where each failure begins: of the placed nodes next to the failed ones, the nearest to the
    /// seed (for the solver, the node furthest from balance), m.
    #[serde(rename = "where")]
    pub where_: BTreeMap<String, [f64; 3]>,
    /// For a mechanical case: whether it reached equilibrium, and in how many iterations.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub converged: Option<bool>,
    /// Solver iterations.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub iterations: Option<usize>,
    /// For an `auto` case: what it chose and why.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub choice: Option<MethodChoice>,
    /// The cell shear over fabric coordinates, when the case keeps it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub field: Option<ShearField>,
    /// The ply's row of the layup table, when it was draped.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stats: Option<CaseStats>,
}

/// A draped case's layup-table figures ([`crate::layup::stack::PlyStats`]): what an
/// optimisation's objectives are made of.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CaseStats {
    /// Largest |shear| over the complete cells, degrees.
    pub max_abs_shear_deg: f64,
    /// Mean |shear| over the complete cells, degrees.
    pub mean_abs_shear_deg: f64,
    /// Draped area of the cells sheared past the ply's locking angle, m^2.
    pub area_over_locking_m2: f64,
    /// The share of the tool (or of the ply's outline) the ply covers, 0 to 1.
    pub coverage: f64,
    /// Complete cells.
    pub cells: usize,
}

impl CaseStats {
    /// The figures of a ply's layup-table row.
    pub fn of(s: &PlyStats) -> CaseStats {
        CaseStats {
            max_abs_shear_deg: s.max_abs_shear.to_degrees(),
            mean_abs_shear_deg: s.mean_abs_shear.to_degrees(),
            area_over_locking_m2: s.area_over_locking,
            coverage: s.coverage.share(),
            cells: s.cells,
        }
    }
}

impl CaseResult {
    /// A case that gave no net, and why.
    pub fn refused(reason: String, tool_triangles: usize) -> CaseResult {
        CaseResult {
            outcome: reason,
            time_s: 0.0,
            times_s: Vec::new(),
            tool_triangles,
            nodes: 0,
            placed_fraction: 0.0,
            max_shear_deg: None,
            failures: BTreeMap::new(),
            where_: BTreeMap::new(),
            converged: None,
            iterations: None,
            choice: None,
            field: None,
            stats: None,
        }
    }
}

/// Node statuses that do not name a case's failure: a fabric larger than the tool runs off its
/// edge wherever it is draped (`off_tool`), and a node whose parent is missing failed because
/// of that parent, whose own status is counted.
const NOT_FAILURES: [&str; 5] = ["placed", "outside_outline", "off_tool", "parent_missing", OFF_PART];
/// A failed node whose parallelogram prediction lies further than this (times d) from the tool
/// would have been off the part.
const OFF_PART_DISTANCE: f64 = 0.5;
/// A predicted position closer than this (times d) to an open edge is on it, not beyond it.
const BEYOND_EDGE: f64 = 1e-6;

/// The ply a case drapes, or why it cannot: `base` is the ply as the scene gives it, `tool` the
/// case's tool.
pub fn case_ply(base: &Ply, layup: &Layup, v: &Variant, tool: &ToolSurface) -> Result<Ply, String> {
    let mut ply = base.clone();
    ply.settings = base.settings.at_spacing(v.spacing);
    let s = &mut ply.settings;
    if let Some(o) = v.origin {
        s.origin = Point::from(o);
    }
    if let Extent::Grid { nu, nv, .. } = s.extent {
        let cap = if v.method.may_run_mechanics() { MAX_MECHANICAL_NODES } else { MAX_KINEMATIC_NODES };
        if nu.saturating_mul(nv) > cap {
            return Err(format!("skipped: {nu} x {nv} nodes is more than the {cap} a study case may have"));
        }
    }
    if let Extent::Grid { nu, nv, .. } = base.settings.extent {
        if v.seed_shift != [0.0, 0.0] {
            let d0 = base.settings.spacing;
            let half = [0.5 * (nu - 1) as f64 * d0, 0.5 * (nv - 1) as f64 * d0];
            let foot = tool.closest_point(&s.origin);
            let warp = resolve_warp(base, &foot.point, &layup.reference, tool, layup.stack_side)?;
            let weft = foot.normal.cross(&warp).normalize();
            let moved =
                Point::from(foot.point.coords + warp * v.seed_shift[0] * half[0] + weft * v.seed_shift[1] * half[1]);
            s.origin = tool.closest_point(&moved).point;
        }
    } else if v.seed_shift != [0.0, 0.0] {
        return Err("refused: a seed shift needs a ply given by its grid".into());
    }
    s.surface = v.surface;
    if let Some(a) = v.angle_deg {
        ply.orientation = Orientation::Angle(a.to_radians());
    }
    if let Some(p) = v.pre_shear_deg {
        s.pre_shear = p.to_radians();
    }
    if let Some(m) = v.max_shear_deg {
        s.max_shear = m.to_radians();
    }
    match v.method {
        StudyMethod::KinematicGeodesic => s.generators = GeneratorKind::Geodesic,
        StudyMethod::KinematicMinShear => s.generators = GeneratorKind::MinShear,
        StudyMethod::KinematicSteered
        | StudyMethod::MechanicalPressed
        | StudyMethod::MechanicalFree
        | StudyMethod::Auto => {}
    }
    ply.refinement = match v.method {
        StudyMethod::MechanicalPressed | StudyMethod::Auto => Some(pressed_refinement(base)?),
        StudyMethod::MechanicalFree => match &base.refinement {
            Some(r) if r.mode == ContactMode::Free => Some(r.clone()),
            _ => return Err("refused: the ply is not a free drape".into()),
        },
        _ => None,
    };
    ply.auto = match v.method {
        StudyMethod::Auto => Some(base.auto.unwrap_or(AutoModel { tolerance_deg: DEFAULT_TOLERANCE_DEG })),
        _ => None,
    };
    if let Some(r) = &mut ply.refinement {
        scale_tension(&mut r.material.tension.law, v.tension_factor);
        if let Some(n) = v.load_steps {
            r.load_steps = n;
        }
        if let Some(mu) = v.friction {
            r.friction = mu;
        }
    }
    Ok(ply)
}

/// The ply's pressed refinement: its own when it is pressed, else one from its material card.
fn pressed_refinement(ply: &Ply) -> Result<Refinement, String> {
    if let Some(r) = &ply.refinement {
        if r.mode == ContactMode::Pressed {
            return Ok(r.clone());
        }
    }
    let m = ply.material.as_ref().ok_or("refused: the ply has no material card for the mechanical stage")?;
    Ok(Refinement::pressed(m.card.clone(), m.path.clone()))
}

fn scale_tension(law: &mut TensionLaw, f: f64) {
    match law {
        TensionLaw::Linear { warp, weft } => {
            *warp *= f;
            *weft *= f;
        }
        TensionLaw::Knit { warp, weft } => {
            for p in [warp, weft] {
                p.c *= f;
                p.beta *= f;
            }
        }
    }
}

/// Run `case` of the ply `base` of `layup` on `tool`.
pub fn run_case(base: &Ply, layup: &Layup, case: &Case, tool: &ToolSurface) -> CaseResult {
    let triangles = tool.num_triangles();
    let ply = match case_ply(base, layup, &case.variant, tool) {
        Ok(p) => p,
        Err(reason) => return CaseResult::refused(reason, triangles),
    };
    // A case's figures need no wrinkles, and its time is the drape's.
    let one = Layup { reference: layup.reference, stack_side: layup.stack_side, plies: vec![ply], wrinkles: false };
    let mut times = Vec::new();
    let mut last = None;
    for _ in 0..case.repeats.max(1) {
        let t = Instant::now();
        let r = drape_layup(&one, tool, |_, _| {});
        times.push(t.elapsed().as_secs_f64());
        match r {
            Ok(mut plies) => last = plies.pop(),
            Err(e) => {
                let mut out = CaseResult::refused(format!("refused: {e}"), triangles);
                out.time_s = median(&mut times.clone());
                out.times_s = times;
                return out;
            }
        }
    }
    let Some(result) = last else { unreachable!("at least one repeat ran") };
    let net = &result.net;
    let mut out = summarise(net, tool, case.keep_field);
    out.tool_triangles = triangles;
    out.time_s = median(&mut times.clone());
    out.times_s = times;
    out.choice = result.choice.clone();
    out.stats = Some(CaseStats::of(&result.stats));
    if let Some(rec) = &net.meta.solver {
        out.converged = Some(rec.converged);
        out.iterations = Some(rec.iterations);
        // A mechanical case is judged by its solver: the nodes it lacks are its kinematic
        // start's, which the kinematic cases report.
        out.outcome = "ok".into();
        if rec.outcome == "slides" {
            // Nothing holds the ply on the tool: a named outcome of its own on the map.
            out.outcome = "slides".into();
        } else if !rec.converged {
            out.outcome = format!("not_converged: {}", rec.outcome);
            if let Some(u) = rec.unbalanced.first() {
                out.where_.insert("unbalanced".into(), u.position);
            }
        }
    }
    out
}

fn median(t: &mut [f64]) -> f64 {
    t.sort_by(f64::total_cmp);
    match t.len() {
        0 => 0.0,
        n if n % 2 == 1 => t[n / 2],
        n => 0.5 * (t[n / 2 - 1] + t[n / 2]),
    }
}

/// Failures counted under this name are nodes the fabric would have put off the tool's surface
/// (past an open edge or a rim): the part ends there, the method did not fail.
pub const OFF_PART: &str = "off_part";

/// Where a failed node would be if the cell it closes were a parallelogram of placed nodes.
fn predicted(net: &DrapeNet, i: usize, j: usize) -> Option<Point> {
    let at = |a: isize, b: isize| {
        (a >= 0 && b >= 0 && (a as usize) < net.nu && (b as usize) < net.nv)
            .then(|| net.node(a as usize, b as usize))
            .flatten()
    };
    let (i, j) = (i as isize, j as isize);
    [(-1, -1), (1, -1), (-1, 1), (1, 1)].into_iter().find_map(|(di, dj)| {
        let (a, b, c) = (at(i + di, j)?, at(i, j + dj)?, at(i + di, j + dj)?);
        Some(Point::from(a.coords + b.coords - c.coords))
    })
}

/// Whether a predicted node position `p` lies on the part: near the tool, and not beyond one of
/// its open edges (its closest point on an open edge, with the point off the surface).
fn on_part(tool: &ToolSurface, p: &Point, d: f64) -> bool {
    let sp = tool.closest_point(p);
    if sp.distance > OFF_PART_DISTANCE * d {
        return false;
    }
    let l = tool.barycentric(sp.triangle, &sp.point);
    sp.distance <= BEYOND_EDGE * d || tool.open_edges_at(sp.triangle, &l)[0].is_none()
}

/// Outcome, placed share, largest shear, failures and where they are, of a finished net on
/// `tool`.
pub fn summarise(net: &DrapeNet, tool: &ToolSurface, keep_field: bool) -> CaseResult {
    let counted = net.status.iter().filter(|s| **s != NodeStatus::OutsideOutline).count();
    let placed = net.status.iter().filter(|s| **s == NodeStatus::Placed).count();
    let mut failures = BTreeMap::new();
    // Per reason, the failure front's point nearest the seed: where the failure begins.
    let seed = net.node(net.origin_node.0, net.origin_node.1);
    let mut first: BTreeMap<&'static str, (f64, Point)> = BTreeMap::new();
    for i in 0..net.nu {
        for j in 0..net.nv {
            let st = net.status[net.index(i, j)];
            if st == NodeStatus::Placed || st == NodeStatus::OutsideOutline {
                continue;
            }
            // A node that fails where the fabric would leave the tool has run off the part.
            let name = match st {
                NodeStatus::NoRoot | NodeStatus::ShearLimit | NodeStatus::Fold | NodeStatus::SheetJump => {
                    if predicted(net, i, j).is_some_and(|p| on_part(tool, &p, net.spacing)) {
                        st.name()
                    } else {
                        OFF_PART
                    }
                }
                _ => st.name(),
            };
            *failures.entry(name.to_string()).or_insert(0usize) += 1;
            // The failure front: placed neighbours of the failed node.
            let near = [(1, 0), (-1, 0), (0, 1), (0, -1)].into_iter().filter_map(|(di, dj): (isize, isize)| {
                let (a, b) = (i as isize + di, j as isize + dj);
                (a >= 0 && b >= 0 && (a as usize) < net.nu && (b as usize) < net.nv)
                    .then(|| net.node(a as usize, b as usize))
                    .flatten()
            });
            for p in near {
                let r = seed.map_or(0.0, |s| (p - s).norm());
                let e = first.entry(name).or_insert((r, p));
                // Ties go to the lower node (the scan's order), so the answer is reproducible.
                if r < e.0 {
                    *e = (r, p);
                }
            }
        }
    }
    let where_ = first.into_iter().map(|(k, (_, p))| (k.to_string(), [p.x, p.y, p.z])).collect();
    let field = ShearField::of(net);
    let max_shear_deg = field.shear_deg.iter().flatten().map(|s| s.abs()).reduce(f64::max);
    // The dominant real failure names the outcome; running off the tool's edge is not one.
    let outcome = failures
        .iter()
        .filter(|(k, _)| !NOT_FAILURES.contains(&k.as_str()))
        .max_by_key(|(_, n)| **n)
        .map_or_else(|| "ok".to_string(), |(k, _)| k.clone());
    CaseResult {
        outcome,
        time_s: 0.0,
        times_s: Vec::new(),
        tool_triangles: 0,
        nodes: counted,
        placed_fraction: if counted > 0 { placed as f64 / counted as f64 } else { 0.0 },
        max_shear_deg,
        failures,
        where_,
        converged: None,
        iterations: None,
        choice: None,
        field: keep_field.then_some(field),
        stats: None,
    }
}
