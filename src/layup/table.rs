//! The layup table: one row per ply (angle, material, shear, coverage, fabric used, offset) and
//! the nesting of the flat patterns. `drape run` prints it and writes it as `layup.json`
//! ([`crate::io::layup_json`]); `drape report` reads that file into the same type.
use super::flat::{CutLine, CutWarning};
use super::nest::Nesting;
use super::stack::PlyResult;
use super::{LockingSource, Ply};
use crate::kinematic::coverage::SurfaceCoverage;
use crate::kinematic::provenance::{ContactSummary, DrawIn, Stability, WrinkleSummary};
use crate::kinematic::MethodChoice;
use serde::{Deserialize, Serialize};

/// `layup.json`: the layup table of a run. Every field but a row's name may be missing in a file
/// (other tools write it too); `drape run` writes them all.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct LayupTable {
    /// The scene file.
    #[serde(default)]
    pub scene: Option<String>,
    /// The tool file.
    #[serde(default)]
    pub tool: Option<String>,
    /// One row per ply, in stacking order.
    #[serde(default)]
    pub plies: Vec<LayupRow>,
    /// Where the flat patterns lie on the roll, when there is a pattern.
    #[serde(default)]
    pub nesting: Option<NestingRow>,
    /// Every file the run wrote into its folder (names in the folder, sorted, `layup.json`
    /// included): the next run into the folder removes those it does not write again.
    #[serde(default)]
    pub files: Vec<String>,
    /// What the run mapped onto the scene's flow or FE mesh (`[export]`), when it did.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub export: Option<ExportRow>,
}

/// The plies on the scene's flow or FE mesh (`[export]`), in the layup table: which mesh, what
/// was written and how much of it each ply covers. `drape report` shows it as it is.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct ExportRow {
    /// The mesh file, as the scene names it.
    pub mesh: String,
    /// Its elements.
    pub elements: usize,
    /// Its nodes.
    #[serde(default)]
    pub nodes: usize,
    /// The formats written, as the scene names them (`vtu`, `csv`, `nastran`, ...).
    #[serde(default)]
    pub formats: Vec<String>,
    /// The files written (names in the run folder), in the order of the formats.
    #[serde(default)]
    pub files: Vec<String>,
    /// One entry per ply, in stacking order.
    #[serde(default)]
    pub plies: Vec<ExportPlyRow>,
}

/// How much of the flow mesh one ply covers.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct ExportPlyRow {
    /// Ply name.
    pub name: String,
    /// Elements the ply covers.
    pub covered: usize,
    /// Covered over all elements (0 for a mesh without elements).
    pub share: f64,
    /// Largest |shear| over the covered elements, degrees.
    #[serde(default)]
    pub max_abs_shear_deg: Option<f64>,
    /// Mean |shear| over the covered elements, degrees.
    #[serde(default)]
    pub mean_abs_shear_deg: Option<f64>,
    /// Covered elements on cells sheared past the collapse (`material::flow::COLLAPSED_SHEAR_DEG`),
    /// whose thickness and Vf were written at that shear.
    #[serde(default)]
    pub collapsed_elements: usize,
}

/// One ply of the layup table.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct LayupRow {
    /// Ply name.
    pub name: String,
    /// The material's name in the scene.
    #[serde(default)]
    pub material: Option<String>,
    /// The material card file.
    #[serde(default)]
    pub material_card: Option<String>,
    /// Ply angle, degrees (`None` when the warp was given as a vector).
    #[serde(default)]
    pub angle_deg: Option<f64>,
    /// Unit warp direction at the seed.
    #[serde(default)]
    pub warp: Option<[f64; 3]>,
    /// What ran: `kinematic` or `mechanical`.
    #[serde(default)]
    pub method: Option<String>,
    /// For a ply with `method = "auto"`: what was asked for, why `method` was chosen, and the
    /// measurements it was chosen from.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub method_choice: Option<MethodChoice>,
    /// For a mechanical ply: whether the solver reached equilibrium (|F - P| / |P| within its
    /// tolerance in every load step). A ply with `false` here is the last accepted state, not
    /// a drape.
    #[serde(default)]
    pub converged: Option<bool>,
    /// For a mechanical ply that did not converge: why, and where the forces are furthest from
    /// balance.
    #[serde(default)]
    pub solver_failure: Option<String>,
    /// For a mechanical ply: how it ended (`converged`, `slides`, `iteration_limit`, ...; the
    /// solver's outcomes).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub outcome: Option<String>,
    /// For a mechanical ply: how it meets the tool (friction, stick and slip).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub contact: Option<ContactSummary>,
    /// For a mechanical ply that converged: the second-order check of its state, `minimum` or
    /// `saddle` (an equilibrium the energy falls away from: an unstable one), or `unresolved`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stability: Option<Stability>,
    /// Thickness as laid flat, m.
    #[serde(default)]
    pub thickness_m: Option<f64>,
    /// Locking angle, degrees.
    #[serde(default)]
    pub locking_angle_deg: Option<f64>,
    /// Where the locking angle comes from: `ply`, `card` or `default`.
    #[serde(default)]
    pub locking_angle_source: Option<LockingSource>,
    /// Largest |shear| over the complete cells, degrees.
    #[serde(default)]
    pub max_abs_shear_deg: Option<f64>,
    /// Mean |shear| over the complete cells, degrees.
    #[serde(default)]
    pub mean_abs_shear_deg: Option<f64>,
    /// Draped area of the cells sheared past the locking angle, m^2.
    #[serde(default)]
    pub area_over_locking_m2: Option<f64>,
    /// Share of the surface the ply covers: of the tool it lies on (offset by the plies below),
    /// or of the part of it inside the ply's outline (see `coverage_of`).
    #[serde(default)]
    pub coverage: Option<f64>,
    /// What `coverage` is a share of: `tool` or `outline`.
    #[serde(default)]
    pub coverage_of: Option<CoverageOf>,
    /// Area of the tool (or the outline) the ply covers, m^2.
    #[serde(default)]
    pub covered_area_m2: Option<f64>,
    /// Complete cells.
    #[serde(default)]
    pub cells: Option<usize>,
    /// Draped area of the complete cells, m^2.
    #[serde(default)]
    pub draped_area_m2: Option<f64>,
    /// Fabric used (the flat pattern's area), m^2.
    #[serde(default)]
    pub fabric_area_m2: Option<f64>,
    /// The line the ply's flat pattern is cut along (`outline`, `smooth_nodes`, `nodes`, or
    /// `grown_cells` when the margin could not be offset), when it has a pattern.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pattern_cut: Option<CutLine>,
    /// The cutting margin outside that line, m, when the ply has a pattern.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pattern_margin_m: Option<f64>,
    /// Why the ply's flat pattern is not cut along the line the ply asks for (empty when it is).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub pattern_warnings: Vec<CutWarning>,
    /// Mass of that fabric, kg.
    #[serde(default)]
    pub fabric_mass_kg: Option<f64>,
    /// Largest offset of the tool by the plies below, m.
    #[serde(default)]
    pub offset_m: Option<f64>,
    /// Triangles of that offset surface that folded over.
    #[serde(default)]
    pub offset_folded_triangles: Option<usize>,
    /// Offset vertices moved off their normals to bridge tight concave corners.
    #[serde(default)]
    pub offset_bridged_vertices: Option<usize>,
    /// Tool vertices under cells of the plies below sheared past their collapse
    /// (`material::flow::COLLAPSED_SHEAR_DEG`), counted in the offset at that shear's thickness.
    #[serde(default)]
    pub offset_collapsed_vertices: Option<usize>,
    /// How far the blank's edge moved in towards the seed, in plan, along the fibres and the
    /// diagonals through the origin node.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub draw_in: Option<DrawIn>,
    /// When the ply shears past the angle its material card's shear law was calibrated to:
    /// the warning ([`shear_range_warning`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shear_range_warning: Option<String>,
    /// Its wrinkles: the wrinkled area (cells wavier than the threshold), the threshold and
    /// where it comes from, the largest waviness, tool gap and bending energy density
    /// ([`crate::kinematic::wrinkle`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub wrinkles: Option<WrinkleSummary>,
}

/// A warning when a ply's largest shear is past the angle its material card's shear law was
/// calibrated to (the card it is refined with, else its own); `None` within it, without a card,
/// or for a card that records no range.
pub fn shear_range_warning(ply: &Ply, result: &PlyResult) -> Option<String> {
    let card = ply.card()?;
    card.shear_range_warning(result.stats.max_abs_shear.to_degrees())
}

/// What a ply's coverage is a share of.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum CoverageOf {
    /// The surface the ply lies on (the tool offset by the plies below).
    Tool,
    /// The part of that surface inside the ply's outline.
    Outline,
}

impl CoverageOf {
    /// What `coverage` measures.
    pub fn of(c: &SurfaceCoverage) -> CoverageOf {
        if c.of_outline {
            CoverageOf::Outline
        } else {
            CoverageOf::Tool
        }
    }

    /// The word in tables: `tool` or `outline`.
    pub fn name(self) -> &'static str {
        match self {
            CoverageOf::Tool => "tool",
            CoverageOf::Outline => "outline",
        }
    }
}

/// The nesting of the flat patterns in the layup table.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct NestingRow {
    /// Roll width, m.
    #[serde(default)]
    pub roll_width_m: Option<f64>,
    /// Gap kept between pieces, m.
    #[serde(default)]
    pub gap_m: Option<f64>,
    /// Length of roll used, m.
    #[serde(default)]
    pub length_m: Option<f64>,
    /// Material used, m^2.
    #[serde(default)]
    pub used_area_m2: Option<f64>,
    /// Area of the patterns, m^2.
    #[serde(default)]
    pub pattern_area_m2: Option<f64>,
    /// Material wasted, m^2.
    #[serde(default)]
    pub waste_area_m2: Option<f64>,
    /// Waste over material used.
    #[serde(default)]
    pub waste_fraction: Option<f64>,
}

impl LayupRow {
    /// The row of a draped ply.
    pub fn of(ply: &Ply, result: &PlyResult) -> LayupRow {
        let (s, w) = (&result.stats, result.warp);
        LayupRow {
            name: ply.settings.name.clone(),
            material: ply.material.as_ref().map(|m| m.name.clone()),
            material_card: ply.material.as_ref().map(|m| m.path.display().to_string()),
            angle_deg: ply.angle_deg(),
            warp: Some([w.x, w.y, w.z]),
            method: Some(if result.refined.is_some() { "mechanical" } else { "kinematic" }.into()),
            method_choice: result.choice.clone(),
            converged: result.refined.as_ref().map(|r| r.ok()),
            solver_failure: result.refined.as_ref().filter(|r| !r.ok()).map(|r| r.describe_failure()),
            outcome: result.refined.as_ref().map(|r| r.outcome().name().to_string()),
            contact: result.refined.as_ref().map(|r| r.contact.summary()),
            stability: result.refined.as_ref().and_then(|r| r.stability_verdict()),
            thickness_m: ply.thickness,
            locking_angle_deg: Some(ply.locking_angle.to_degrees()),
            locking_angle_source: Some(ply.locking_source),
            max_abs_shear_deg: Some(s.max_abs_shear.to_degrees()),
            mean_abs_shear_deg: Some(s.mean_abs_shear.to_degrees()),
            area_over_locking_m2: Some(s.area_over_locking),
            coverage: Some(s.coverage.share()),
            coverage_of: Some(CoverageOf::of(&s.coverage)),
            covered_area_m2: Some(s.coverage.covered_area),
            cells: Some(s.cells),
            draped_area_m2: Some(s.draped_area),
            fabric_area_m2: Some(s.fabric_area),
            fabric_mass_kg: s.fabric_mass,
            offset_m: Some(result.offset.max_distance),
            offset_folded_triangles: Some(result.offset.folded),
            offset_bridged_vertices: Some(result.offset.relaxed),
            offset_collapsed_vertices: Some(result.collapsed_below),
            shear_range_warning: shear_range_warning(ply, result),
            draw_in: result.net.meta.draw_in.clone(),
            wrinkles: result.net.meta.wrinkles.as_ref().map(|w| w.summary.clone()),
            // Filled in by the run from the ply's pattern.
            pattern_cut: None,
            pattern_margin_m: None,
            pattern_warnings: Vec::new(),
        }
    }
}

impl From<&Nesting> for NestingRow {
    fn from(n: &Nesting) -> NestingRow {
        NestingRow {
            roll_width_m: Some(n.roll_width),
            gap_m: Some(n.gap),
            length_m: Some(n.length),
            used_area_m2: Some(n.used_area),
            pattern_area_m2: Some(n.pattern_area),
            waste_area_m2: Some(n.waste_area),
            waste_fraction: Some(n.waste_fraction),
        }
    }
}
