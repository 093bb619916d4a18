//! Draping a layup: each ply in stacking order on the tool offset by the plies below it, its warp
//! resolved from the ply angle on that surface, refined where the ply asks for it; and the
//! numbers of the layup table.
use super::auto::{drape_auto, AutoError};
use super::coarse::{coarser_grid, prolong};
use super::flat::{blank_pattern, ply_pattern};
use super::{Layup, Orientation, Ply, StackSide, Start};
use crate::geometry::offset::{
    offset_along, offset_directions, offset_vertices, ramp_drops, OffsetReport, PLY_DROP_SLOPE,
};
use crate::geometry::{Point, ToolError, ToolSurface, Vector};
use crate::kinematic::coverage::{surface_coverage, SurfaceCoverage};
use crate::kinematic::fishnet::DrapeError;
use crate::kinematic::outline::Outline;
use crate::kinematic::provenance::{FormedLevel, FormingRecord};
use crate::kinematic::sampler::NetSampler;
use crate::kinematic::{drape, DrapeNet, Extent, KinematicSettings, MethodChoice, NodeStatus};
use crate::material::flow::sheared_thickness;
use crate::mechanics::forming::{turned_over, Binder, Forming, PlanView};
use crate::mechanics::friction::PliesBelow;
use crate::mechanics::refine::{RefineError, Refined};
use crate::mechanics::sheet::{blank_fractions, blank_nodes, default_origin_node, flat_sheet, SheetError};
use std::time::Instant;

/// A reference direction closer than this (sine of the angle) to the tool normal at a seed has
/// no usable projection onto the tool there.
const MIN_REFERENCE_SINE: f64 = 1e-3;

/// Why a layup could not be draped. Every message names the ply and its line in the scene.
#[derive(Debug, thiserror::Error)]
pub enum LayupError {
    /// The ply could not be draped.
    #[error("ply '{ply}' (line {line}): {source}")]
    Drape {
        /// The ply.
        ply: String,
        /// Its line in the scene.
        line: usize,
        /// Why.
        source: DrapeError,
    },
    /// The tool offset by the plies below is unusable.
    #[error("ply '{ply}' (line {line}): the offset surface of the plies below is unusable: {source}")]
    Offset {
        /// The ply.
        ply: String,
        /// Its line in the scene.
        line: usize,
        /// Why.
        source: ToolError,
    },
    /// The mechanical refinement could not start.
    #[error("ply '{ply}' (line {line}): refinement: {source}")]
    Refine {
        /// The ply.
        ply: String,
        /// Its line in the scene.
        line: usize,
        /// Why.
        source: RefineError,
    },
    /// A formed ply's process does not fit the tool (its stroke moves the punch away from the
    /// blank).
    #[error("ply '{ply}' (line {line}), field `{field}`: {message}")]
    Forming {
        /// The ply.
        ply: String,
        /// Its line in the scene.
        line: usize,
        /// The scene field at fault.
        field: &'static str,
        /// What is wrong and what to do.
        message: String,
    },
    /// The ply's warp has no direction on the tool at its seed.
    #[error("ply '{ply}' (line {line}): {message}")]
    Orientation {
        /// The ply.
        ply: String,
        /// Its line in the scene.
        line: usize,
        /// Why, and what to do.
        message: String,
    },
}

/// One draped ply of a layup.
#[derive(Debug, Clone)]
pub struct PlyResult {
    /// The net: refined where the ply is mechanical, else kinematic.
    pub net: DrapeNet,
    /// The solver's record, for a mechanical ply.
    pub refined: Option<Refined>,
    /// For a mechanical ply started from a kinematic drape: that kinematic net (the report
    /// draws it beside the refined one).
    pub kinematic: Option<DrapeNet>,
    /// For a ply with `method = "auto"`: what ran and why.
    pub choice: Option<MethodChoice>,
    /// The warp direction at the seed, resolved on the ply's surface.
    pub warp: Vector,
    /// How the tool was offset for this ply (nothing moved for the first).
    pub offset: OffsetReport,
    /// Tool vertices under cells of the plies below sheared past their collapse
    /// ([`COLLAPSED_SHEAR_DEG`](crate::material::flow::COLLAPSED_SHEAR_DEG)): the stack counts
    /// them at that shear's thickness.
    pub collapsed_below: usize,
    /// Its row of the layup table.
    pub stats: PlyStats,
}

/// A ply's row of the layup table.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlyStats {
    /// Largest and mean |shear| over the complete cells, radians.
    pub max_abs_shear: f64,
    /// Mean |shear| over the complete cells, radians.
    pub mean_abs_shear: f64,
    /// Draped area (3D) of the cells sheared past the locking angle, m^2.
    pub area_over_locking: f64,
    /// What the ply covers of the surface it lies on (the tool offset by the plies below), or of
    /// the part of that surface inside its outline.
    pub coverage: SurfaceCoverage,
    /// Draped area (3D) of the complete cells, m^2.
    pub draped_area: f64,
    /// Fabric used, m^2: the area of the ply's flat pattern without a cutting margin (cut along
    /// its outline when it has one, else through its boundary nodes; see `layup::flat`).
    pub fabric_area: f64,
    /// Mass of that fabric, kg, when the ply has a material card.
    pub fabric_mass: Option<f64>,
    /// Complete cells.
    pub cells: usize,
}

/// The layup-table numbers of a draped net ([`DrapeNet::shear_stats`], and
/// [`surface_coverage`] of `surface`, the surface it was draped on, inside `outline` when it has
/// one); `areal_mass` in kg/m^2.
pub fn ply_stats(
    net: &DrapeNet,
    surface: &ToolSurface,
    outline: Option<&Outline>,
    locking_angle: f64,
    areal_mass: Option<f64>,
) -> PlyStats {
    let s = net.shear_stats(locking_angle);
    let triangles: Vec<[Point; 3]> =
        surface.triangles().iter().map(|t| t.map(|v| surface.vertices()[v as usize])).collect();
    // The fabric cut for the ply: its flat pattern without a margin (along its outline, or
    // through its boundary nodes).
    let fabric_area = ply_pattern(net, outline.map(Outline::points), 0.0).map_or(0.0, |p| p.area);
    PlyStats {
        max_abs_shear: s.max_abs,
        mean_abs_shear: s.mean_abs,
        area_over_locking: s.area_over_locking,
        coverage: surface_coverage(net, &triangles, outline),
        draped_area: s.area,
        fabric_area,
        fabric_mass: areal_mass.map(|m| m * fabric_area),
        cells: s.cells,
    }
}

/// The warp direction of `ply` with its seed at `origin` on `surface`: its warp or the scene's
/// reference, projected onto the tangent plane there and turned by the ply angle about the
/// normal on the stacking side.
pub fn resolve_warp(
    ply: &Ply,
    origin: &Point,
    reference: &Vector,
    surface: &ToolSurface,
    side: StackSide,
) -> Result<Vector, String> {
    let sp = surface.closest_point(origin);
    let n = stacking_normal(surface, origin, side);
    let (direction, angle) = match ply.orientation {
        Orientation::Warp(w) => (w, 0.0),
        Orientation::Angle(a) => (*reference, a),
    };
    let projected = direction - n * n.dot(&direction);
    if projected.norm() < MIN_REFERENCE_SINE * direction.norm() {
        let what = match ply.orientation {
            Orientation::Warp(_) => "the warp direction",
            Orientation::Angle(_) => "the scene's reference direction",
        };
        return Err(format!(
            "{what} is normal to the tool at the seed {:?} (normal {:?}): it has no direction on the surface there; choose another direction",
            sp.point, n
        ));
    }
    let rotation = nalgebra::Rotation3::from_axis_angle(&nalgebra::Unit::new_normalize(n), angle);
    Ok((rotation * projected).normalize())
}

/// Unit normal of `surface` at the seed `origin`, pointing to the side the plies stack on.
fn stacking_normal(surface: &ToolSurface, origin: &Point, side: StackSide) -> Vector {
    let n = seed_normal(surface, &surface.closest_point(origin).point);
    match side {
        StackSide::Normal => n,
        StackSide::Opposite => -n,
    }
}

/// Unit normal of `surface` at its point `p`: the facet's normal inside a facet, the mean of the
/// facets' normals when `p` lies on an edge or a vertex (a seed is often placed on a vertex, and
/// the angle of a ply should not depend on which facet the search happened to return).
pub(crate) fn seed_normal(surface: &ToolSurface, p: &Point) -> Vector {
    let eps = SEED_CONTACT_REL * surface.diagonal();
    let mut n = Vector::zeros();
    for t in surface.triangles_near(p, eps) {
        if (surface.project_to_triangle(t, p) - p).norm() <= eps {
            n += surface.normal(t);
        }
    }
    if n.norm() > 0.0 {
        n.normalize()
    } else {
        surface.closest_point(p).normal
    }
}

/// The warp of a ply laid as a flat sheet with unit normal `normal`: its warp or the scene's
/// reference, projected into the sheet's plane and turned by the ply angle about the normal.
fn sheet_warp(ply: &Ply, reference: &Vector, normal: &Vector) -> Result<Vector, String> {
    let (direction, angle) = match ply.orientation {
        Orientation::Warp(w) => (w, 0.0),
        Orientation::Angle(a) => (*reference, a),
    };
    let projected = direction - normal * normal.dot(&direction);
    if projected.norm() < MIN_REFERENCE_SINE * direction.norm() {
        return Err("the warp direction is normal to the sheet: give a direction in the sheet's plane".into());
    }
    let rotation = nalgebra::Rotation3::from_axis_angle(&nalgebra::Unit::new_normalize(*normal), angle);
    Ok((rotation * projected).normalize())
}

/// The flat sheet a ply with `start = "flat"` starts from (see [`flat_sheet`]).
fn flat_start(
    ply: &Ply,
    settings: &KinematicSettings,
    normal: &Vector,
    tool: &ToolSurface,
) -> Result<DrapeNet, SheetError> {
    let Extent::Grid { nu, nv, origin_node } = settings.extent else {
        return Err(SheetError("a flat sheet needs a grid".into()));
    };
    let sheet = ply.refinement.as_ref().map(|r| &r.sheet);
    let seam = sheet.and_then(|s| s.seam);
    let origin = origin_node.unwrap_or_else(|| default_origin_node(nu, nv, seam));
    let mut net = flat_sheet(
        &settings.name,
        nu,
        nv,
        settings.spacing,
        origin,
        &settings.origin,
        &settings.warp,
        normal,
        seam,
        tool,
    )?;
    // A blank formed by the tools is laid on the punch where its stroke begins.
    if let Some(forming) = ply.refinement.as_ref().and_then(|r| r.forming.as_ref()) {
        net.positions.iter_mut().for_each(|p| *p -= forming.stroke);
    }
    // The nodes the blank cuts away are not part of the ply.
    if let Some(blank) = sheet.and_then(|s| s.blank.as_ref()) {
        let keep = blank_nodes(&blank_fractions(blank, nu, nv, settings.spacing, origin), nu, nv);
        for (status, keep) in net.status.iter_mut().zip(keep) {
            if !keep {
                *status = NodeStatus::OutsideOutline;
            }
        }
    }
    Ok(net)
}

/// A blank formed coarse to fine (`coarse_levels` = L, [`super::coarse`]): formed by its tools
/// on the grid of 2^L times the ply's spacing; then on each grid of half the spacing, down to
/// the ply's, held by the tools where the stroke ended (one increment), starting from the
/// coarser grid's shape. A level that does not reach equilibrium ends the sequence: its net (on
/// its own grid) stands and says so. The net, the solver's record of the last level, and every
/// level's record.
fn form_coarse_to_fine(
    ply: &Ply,
    r: &super::Refinement,
    settings: &KinematicSettings,
    normal: &Vector,
    contact: &ToolSurface,
) -> Result<(DrapeNet, Refined, Vec<FormedLevel>), RefineError> {
    let Extent::Grid { nu, nv, origin_node } = settings.extent else {
        return Err(SheetError("a blank formed coarse to fine needs a grid".into()).into());
    };
    let forming =
        r.forming.as_ref().ok_or_else(|| SheetError("only a formed blank is formed coarse to fine".into()))?;
    let origin = origin_node.unwrap_or_else(|| default_origin_node(nu, nv, None));
    let at_level = |level: usize| -> Result<KinematicSettings, RefineError> {
        let factor = 1 << level;
        let (nu, nv, origin) = coarser_grid(nu, nv, origin, factor).map_err(SheetError)?;
        Ok(KinematicSettings {
            spacing: settings.spacing * factor as f64,
            extent: Extent::Grid { nu, nv, origin_node: Some(origin) },
            ..settings.clone()
        })
    };
    let record = |net: &DrapeNet, result: &Refined, t: Instant| FormedLevel {
        spacing_m: net.spacing,
        increments: result.increments.len(),
        iterations: result.steps.iter().map(|s| s.iterations.len()).sum(),
        converged: result.ok(),
        solve_ms: t.elapsed().as_secs_f64() * 1e3,
    };
    let t = Instant::now();
    let sheet = flat_start(ply, &at_level(r.coarse_levels)?, normal, contact)?;
    let (mut net, mut result) = r.run(&sheet, contact, None)?;
    let mut levels = vec![record(&net, &result, t)];
    for level in (0..r.coarse_levels).rev() {
        if !result.ok() {
            break;
        }
        let t = Instant::now();
        let sheet = flat_start(ply, &at_level(level)?, normal, contact)?;
        let mut start = prolong(&net, &sheet);
        let plane = result.grip.as_ref().map(|g| g.plane).or(forming.blank_plane);
        // The binder clamps what lies under it to the blank's plane: a finer node between a
        // gripped node and one past the opening's edge lies on the coarse chord above the
        // plane, and left there it keeps the coarse grid's corner cut at the edge (the edge then
        // drew in 6% short over a cylindrical punch, as at the coarse spacing, against 1.8%).
        if let (Some(binder), Some(plane)) = (&forming.binder, plane) {
            let view = PlanView::across(&forming.stroke);
            for p in start.iter_mut() {
                let off = plane.normal.dot(&(*p - plane.point));
                if off.abs() <= net.spacing && binder.reaches_under(&view, std::iter::once(&*p)) {
                    *p -= plane.normal * off;
                }
            }
        }
        // The binder grips the finer grid's nodes outside its opening in the blank's plane, as
        // the stroke's last increment would have (the coarse grid's grip carried over would let
        // go of the fabric up to half a coarse cell outside the opening).
        let held = Forming {
            at_stroke_end: true,
            blank_plane: plane,
            binder: forming.binder.as_ref().map(|b| Binder { gripping: None, ..b.clone() }),
            ..forming.clone()
        };
        let finer = super::Refinement { forming: Some(held), ..r.clone() };
        (net, result) = finer.run_from(&sheet, &start, contact, None)?;
        levels.push(record(&net, &result, t));
    }
    Ok((net, result, levels))
}

/// Facets within this distance (times the tool's diagonal) of a seed touch it.
const SEED_CONTACT_REL: f64 = 1e-9;

/// Drape every ply of `layup` on `tool` in stacking order. `on_ply(k, name)` is called before
/// ply `k` starts (for progress display).
pub fn drape_layup(
    layup: &Layup,
    tool: &ToolSurface,
    mut on_ply: impl FnMut(usize, &str),
) -> Result<Vec<PlyResult>, LayupError> {
    // A formed ply whose stroke moves the punch away from the blank is refused before any ply
    // is draped (the stack offsets the tool along the same side, so the tool's normal decides).
    for ply in &layup.plies {
        if let Some(forming) = ply.refinement.as_ref().and_then(|r| r.forming.as_ref()) {
            let blank_side = stacking_normal(tool, &ply.settings.origin, layup.stack_side);
            forming.check_pushes(&blank_side).map_err(|e| LayupError::Forming {
                ply: ply.settings.name.clone(),
                line: ply.line,
                field: e.field,
                message: e.message,
            })?;
        }
    }
    let (dirs, clipped) = offset_directions(tool);
    let sign = match layup.stack_side {
        StackSide::Normal => 1.0,
        StackSide::Opposite => -1.0,
    };
    // Thickness of the stack so far at every tool vertex, metres, and whether a ply below is
    // collapsed there.
    let mut stack = vec![0.0; tool.vertices().len()];
    let mut collapsed = vec![false; tool.vertices().len()];
    let mut results: Vec<PlyResult> = Vec::new();
    for (k, ply) in layup.plies.iter().enumerate() {
        on_ply(k, &ply.settings.name);
        let name = ply.settings.name.clone();
        let line = ply.line;
        // Where this ply lies: the tool offset by the stack below it (before bridging corners).
        // The plies below end in a ramp, not a cliff (see `PLY_DROP_SLOPE`).
        let signed: Vec<f64> = ramp_drops(tool, &stack, PLY_DROP_SLOPE).iter().map(|h| sign * h).collect();
        let collapsed_below = collapsed.iter().filter(|c| **c).count();
        let under = offset_vertices(tool, &dirs, &signed);
        let (offset_tool, offset) = if k == 0 {
            (None, OffsetReport::default())
        } else {
            let (s, r) = offset_along(tool, &dirs, clipped, &signed).map_err(|source| LayupError::Offset {
                ply: name.clone(),
                line,
                source,
            })?;
            (Some(s), r)
        };
        let surface = offset_tool.as_ref().unwrap_or(tool);
        let mut settings = ply.settings.clone();
        if k > 0 {
            // The seed rides up with the stack: the point of the offset surface over its foot on
            // the tool (not the offset surface's closest point, which is off to one side when the
            // seed lies below it).
            let foot = tool.closest_point(&ply.settings.origin);
            let l = tool.barycentric(foot.triangle, &foot.point);
            let tri = tool.triangle(foot.triangle);
            let riding = Point::from((0..3).fold(Vector::zeros(), |acc, c| acc + under[tri[c] as usize].coords * l[c]));
            // A seed given off the tool stays where it is, so the drape refuses it by name.
            if (riding - ply.settings.origin).norm() <= ply.settings.spacing + (riding - foot.point).norm() {
                settings.origin = riding;
            }
        }
        let start = ply.refinement.as_ref().map_or(Start::Kinematic, |r| r.start);
        let warp = match start {
            Start::Kinematic => resolve_warp(ply, &settings.origin, &layup.reference, surface, layup.stack_side),
            Start::Flat { normal } => sheet_warp(ply, &layup.reference, &normal),
        }
        .map_err(|message| LayupError::Orientation { ply: name.clone(), line, message })?;
        settings.warp = warp;
        let drape_error = |source| LayupError::Drape { ply: name.clone(), line, source };
        let refine_error = |source| LayupError::Refine { ply: name.clone(), line, source };
        // The net mechanics starts from (or the kinematic net that stands), the refined net and
        // the solver's record when mechanics ran, and an automatic ply's choice.
        // A ply on plies below with a coefficient of its own against them meets them with it.
        let refinement = match (&ply.refinement, k) {
            (Some(r), 1..) => Some(on_plies_below(r, &stack, tool, &results)),
            (r, _) => r.clone(),
        };
        // The mechanics keeps a ply on the side its tool's normals point to: with the plies on
        // the other side (stack_side = "opposite", a tool whose file faces into the part), it
        // meets the tool turned over.
        let turned = match (layup.stack_side, &refinement) {
            (StackSide::Opposite, Some(_)) => {
                Some(turned_over(surface).map_err(|source| LayupError::Offset { ply: name.clone(), line, source })?)
            }
            _ => None,
        };
        let contact = turned.as_ref().unwrap_or(surface);
        let (start_net, refined, choice) = match (start, &ply.auto, &refinement) {
            (Start::Kinematic, Some(auto), Some(r)) => {
                let a = drape_auto(surface, contact, &settings, r, ply.locking_angle, *auto).map_err(|e| match e {
                    AutoError::Drape(source) => drape_error(source),
                    AutoError::Refine(source) => refine_error(source),
                })?;
                (a.kinematic, a.refined.map(|(out, result)| (out, result, Vec::new())), Some(a.choice))
            }
            (start, _, r) => {
                let net = match start {
                    Start::Kinematic => drape(surface, &settings).map_err(drape_error)?,
                    Start::Flat { normal } => {
                        flat_start(ply, &settings, &normal, contact).map_err(|source| refine_error(source.into()))?
                    }
                };
                let refined = match (start, r) {
                    (Start::Kinematic, Some(r)) => Some(
                        r.run_draped(&net, contact, None, &settings).map(|(out, result)| (out, result, Vec::new())),
                    ),
                    (Start::Flat { normal }, Some(r)) if r.coarse_levels > 0 => {
                        Some(form_coarse_to_fine(ply, r, &settings, &normal, contact))
                    }
                    (Start::Flat { .. }, Some(r)) => {
                        Some(r.run(&net, contact, None).map(|(out, result)| (out, result, Vec::new())))
                    }
                    (_, None) => None,
                }
                .transpose()
                .map_err(refine_error)?;
                (net, refined, None)
            }
        };
        // A flat sheet is not a kinematic drape: only a kinematic start is kept beside the
        // refined net.
        let (mut net, refined, kinematic, levels) = match refined {
            Some((out, result, levels)) => {
                (out, Some(result), matches!(start, Start::Kinematic).then_some(start_net), levels)
            }
            None => (start_net, None, None, Vec::new()),
        };
        net.meta.method_choice = choice.clone();
        // The draw-in, in the plan of the flat sheet, else of the ply at its seed.
        let plan = match start {
            Start::Flat { normal } => Some((normal, "sheet")),
            Start::Kinematic => crate::kinematic::draw_in::seed_normal(&net).map(|n| (n, "seed")),
        };
        net.meta.draw_in = plan.and_then(|(n, from)| crate::kinematic::draw_in::draw_in(&net, &n, from));
        net.meta.wrinkles = layup.wrinkles.then(|| ply.wrinkles(&net, surface));
        net.meta.forming = match (ply.refinement.as_ref().and_then(|r| r.forming.as_ref()), &refined) {
            (Some(f), Some(r)) => Some(FormingRecord {
                // The shape the blank was cut to: what the fabric's cells weigh and resist.
                blank_m: ply.refinement.as_ref().and_then(|r| r.sheet.blank.clone()),
                // Formed coarse to fine: the stroke's increments are the coarsest grid's.
                levels: levels.clone(),
                ..f.record(levels.first().map_or(r.increments.len(), |l| l.increments), r.grip.as_ref(), net.nv)
            }),
            _ => None,
        };
        // What later stages (exports, reports) need to know about the ply.
        net.meta.stack_offset_max_m = Some(offset.max_distance);
        net.meta.stack_side = (layup.stack_side == StackSide::Opposite).then_some(StackSide::Opposite);
        net.meta.angle_deg = ply.angle_deg();
        if let Some(m) = &ply.material {
            net.meta.material = Some(m.path.display().to_string());
        }
        net.meta.thickness_m = ply.thickness;
        if let Some(t0) = ply.thickness {
            if k + 1 < layup.plies.len() {
                add_ply_thickness(&mut stack, &mut collapsed, &under, &net, t0);
            }
        }
        let areal_mass = ply.material.as_ref().map(|m| m.card.areal_mass);
        // The outline as the drape checked it (it cannot fail here: the drape used it).
        let outline = match &settings.extent {
            Extent::Outline(points) => Outline::new(surface, points, net.spacing).ok(),
            Extent::Grid { .. } => None,
        };
        let mut stats = ply_stats(&net, surface, outline.as_ref(), ply.locking_angle, areal_mass);
        // A flat sheet cut to a blank used the blank's fabric.
        if let Some(blank) = ply.refinement.as_ref().and_then(|r| r.sheet.blank.as_deref()) {
            if let Ok(p) = blank_pattern(&net, blank, 0.0) {
                stats.fabric_area = p.area;
                stats.fabric_mass = areal_mass.map(|m| m * p.area);
            }
        }
        results.push(PlyResult { net, refined, kinematic, choice, warp, offset, collapsed_below, stats });
    }
    Ok(results)
}

/// Where a ply's corners must be covered by the plies below for a facet to bear on them: two of
/// three (a facet across the edge of the plies below goes to the side most of it lies on).
const COVERED_CORNERS: usize = 2;

/// The refinement `r` of a ply (as it is when it gives no `ply_friction`), meeting the plies below it (`below`,
/// their results; `stack`, their thickness at every vertex of `tool`) with that coefficient:
/// on the facets they cover ([`COVERED_CORNERS`] of whose corners they lie over), and under
/// the binder when one of them reaches under it (outside its opening in plan). Elsewhere, and
/// on the die and the binder's upper face, the ply meets the tool with its `friction`.
fn on_plies_below(r: &super::Refinement, stack: &[f64], tool: &ToolSurface, below: &[PlyResult]) -> super::Refinement {
    let Some(mu) = r.ply_friction else { return r.clone() };
    let facets = (tool.triangles().iter())
        .map(|t| t.iter().filter(|&&v| stack[v as usize] > 0.0).count() >= COVERED_CORNERS)
        .collect();
    let under_binder = r.forming.as_ref().is_some_and(|f| {
        f.binder.as_ref().is_some_and(|b| {
            let view = PlanView::across(&f.stroke);
            below.iter().any(|p| {
                let placed = p.net.positions.iter().zip(&p.net.status).filter(|(_, s)| **s == NodeStatus::Placed);
                b.reaches_under(&view, placed.map(|(x, _)| x))
            })
        })
    });
    super::Refinement { plies_below: Some(PliesBelow { mu, facets, under_binder }), ..r.clone() }
}

/// Add a draped ply's thickness t0 / cos(gamma) (sheared cells keep their fibre lengths, so their
/// area shrinks by cos(gamma) and the ply thickens; gamma at most
/// [`COLLAPSED_SHEAR_DEG`](crate::material::flow::COLLAPSED_SHEAR_DEG)) to the stack at every
/// tool vertex it covers, marking in `collapsed` those it covers with a cell sheared past that;
/// `under[v]` is where vertex `v` lay for this ply (the tool offset by the stack below it).
fn add_ply_thickness(stack: &mut [f64], collapsed: &mut [bool], under: &[Point], net: &DrapeNet, t0: f64) {
    let Some(sampler) = NetSampler::new(net) else { return };
    // The net follows its surface up to the chord sagitta and, for a refined ply, what the
    // mechanics moved it: accept it within a ply thickness or a cell of the surface.
    let reach = t0.max(net.spacing);
    for (v, p) in under.iter().enumerate() {
        if let Some(hit) = sampler.cover(p, reach) {
            stack[v] += sheared_thickness(t0, hit.shear());
            collapsed[v] |= crate::material::flow::collapsed(hit.shear());
        }
    }
}
