//! The scene file: a tool and the layup to drape on it, plies in stacking order (the first
//! lies on the tool, each next one on the plies below it).
//!
//! ```toml
//! units = "m"                 # "m" (default) or "mm": lengths here and in the OBJ
//! tool = "hemisphere-20k.obj" # relative to this file: OBJ, STL, or a shell mesh (.inp .bdf .msh)
//! reference = [1.0, 0.0, 0.0] # optional: the 0 deg direction of ply angles (default +x)
//! surface = "facets"          # optional: what the fishnet lies on, for every ply without its
//!                             # own: "facets" (the tool's facets, default) or "smooth" (the
//!                             # smooth surface over them: a coarse tool drapes like a fine one)
//! stack_side = "normal"       # optional: plies stack on the side the tool normals point to
//!                             # ("normal", default) or the other ("opposite")
//! roll_width = 1.27           # optional: fabric roll width, for nesting the flat patterns
//! nesting_gap = 0.01          # optional: gap between nested pieces (default 10 mm)
//! cutting_margin = 0.0        # optional: allowance around each flat pattern
//! rotate_patterns = false     # optional: pieces may turn 90 deg on the roll (warp across)
//! friction = 0.25             # optional: Coulomb's coefficient between mechanical plies and the
//!                             # tool, for every ply without its own (default: each card's)
//! ply_friction = 0.15         # optional: Coulomb's coefficient between a mechanical ply and the
//!                             # plies below it, for every ply without its own (default: each
//!                             # ply's `friction`); the tool's where the ply bears on bare tool
//! [materials]                 # optional: names for material cards, relative to this file
//! glass = "../../materials/glass-plain-weave.toml"
//! [export]                    # optional: map every ply onto a resin-flow mesh
//! mesh = "part.bdf"           # Nastran, Abaqus .inp, OBJ or Gmsh 4 .msh, in the scene's units
//! formats = ["vtu", "csv"]    # vtu, nastran, abaqus, calculix, optistruct, rtmsim, csv
//! cavity = "fixed"            # "fixed" (Vf = Vf0 / cos g) or "free" (t = t0 / cos g)
//! permeability = true         # permeability tensors (needs [flow] in the material cards)
//! vtu = "auto"                # flow.vtu: "auto" (binary from 50k elements), "ascii" or "binary"
//! [[ply]]
//! name = "p0"
//! origin = [0.0, 0.0, 0.1]
//! angle_deg = 0.0             # warp = reference turned by this about the tool normal at the
//!                             # seed (counter-clockwise seen from the normal side);
//! # warp = [1.0, 0.0, 0.0]    # or the warp direction itself (not both)
//! material = "glass"          # a name from [materials] or a card file; gives the thickness
//! # thickness = 5.0e-4        # optional: overrides the card's thickness (scene units)
//! spacing = 0.004
//! grid = [61, 61]             # or outline = [[x,y,z], ...] or outline_file = "outline.csv"
//! origin_node = [30, 30]      # optional (default: the centre)
//! pre_shear_deg = 0.0         # optional
//! generators = "geodesic"     # or "min-shear" or "steer:curve.csv"
//! locking_angle_deg = 45.0    # optional, for reporting (default: the card's two-slope
//!                             # locking angle, else 45)
//! max_shear_deg = 75.0        # optional: nodes shearing past this are not placed
//! surface = "smooth"          # optional: this ply's surface (default: the scene's)
//! method = "kinematic"       # or "mechanical": kinematic, then refinement with the
//!                             # ply's material card; or "auto": mechanics only where the
//!                             # kinematic net is not within the tolerance (layup::auto)
//! # tolerance_deg = 1.0       # method = "auto": the cell-shear error accepted (default 1)
//! # mode = "pressed"          # or "free" (gravity drape with one-sided contact)
//! # start = "kinematic"       # mechanical plies: start from the kinematic drape (default) or
//!                             # "flat": a flat sheet laid over the tool, its origin node over
//!                             # `origin`, just touching the tool (free drape; grid only)
//! # sheet_normal = [0, 0, 1]  # with start = "flat": the sheet plane's normal (default +z)
//! # load_steps = 1            # gravity applied in this many steps (default 1)
//! # max_iterations = 500      # solver iterations per load step (default 500)
//! # friction = 0.25          # Coulomb's coefficient between the ply and the tool (default: the
//!                             # scene's `friction`, else the card's [contact] friction, else 0)
//! # ply_friction = 0.15      # Coulomb's coefficient between the ply and the plies below it where
//!                             # they cover the tool under it (default: the scene's
//!                             # `ply_friction`, else the ply's `friction`); a formed ply's binder
//!                             # grips with `friction` above and this below where plies lie under it
//! # hold = [[30, 30]]         # grid nodes [i, j] held in place (nothing else holds a ply but
//!                             # the tool and friction; a ply that slides says so)
//! # stick = false             # free drape: nodes the tool holds up stay where they touch (until pulled off by over a tenth of their weight)
//!                             # (seed 000's tables restrain the nodes on them: friction without
//!                             # limit; default: friction as given)
//! # escape_saddles = false    # move off an equilibrium the stability check finds a saddle
//!                             # and iterate on to a lower one (default: only report it)
//! # [[ply.reinforcement]]     # regions with multiplied properties (seed 000's bands):
//! # edges = 0.03              #   a band this wide along the edges; or axes = W (bands along
//! #                           #   the fibres through the origin node); or u = [u0, u1],
//! #                           #   v = [v0, v1] (fabric coordinates from the origin node)
//! # tension = 5.0             #   factors (default 1): tension, shear, bending, weight
//! # shear = 5.0
//! # bending = 20.0
//! # weight = 2.0
//! # [ply.seam]                # two sheets side by side, stitched along a weft line
//! # rows = [47, 47]           #   node rows of each (adding up to grid[0])
//! # allowance = 1             #   seam allowance in cells; the allowances hang as flaps
//! # [ply.fold]                # a fold along a weft line, the sheet starting unfolded
//! # row = 45                  #   its node row (default: the middle)
//! # stiffness = 98.0          #   restoring stiffness, N/m per metre of fold (SI)
//! # [[ply.cut]]               # fibre links removed along a polyline
//! # points = [[-0.45, 0.82], [0.45, 0.82]]   # fabric coordinates (u, v) from the origin node
//! # blank = [[0.3, 0.0], [0.0, 0.3], [-0.3, 0.0], [0.0, -0.3]]  # with start = "flat": the
//! #                           # shape the sheet is cut to, corners in fabric coordinates (u, v)
//! #                           # from the origin node (here a square at 45 deg to the fibres);
//! #                           # cells the edge cuts keep their share of the blank's fabric
//! # stroke = [0.0, 0.0, 0.05] # with start = "flat" and mode = "pressed": the blank is formed by
//! #                           # the tool (the punch) moving this far over the increments (at most
//! #                           # half a spacing each); the tool file has it where the stroke ends,
//! #                           # the blank lies flat on it where the stroke begins
//! # die = "die.obj"           # optional: the female tool, still; the ply stays on the side of it
//! #                           # that faces the punch
//! # coarse_levels = 1         # optional (default 0): form the blank on the grid of 2^L times the
//! #                           # spacing first, then hold it by the tools where the stroke ended
//! #                           # on each grid of half the spacing down to the ply's (faster: the
//! #                           # stroke's increments are the coarse grid's); the grid's cells each
//! #                           # side of the origin node must be a multiple of 2^L
//! # [ply.binder]              # optional: a blank holder clamping the blank in its plane outside
//! # outline = [[-0.1, -0.1], [0.1, -0.1], [0.1, 0.1], [-0.1, 0.1]]  # its opening in plan view
//! #                           # across the stroke ([x, y] for a stroke along z)
//! # pressure = 1.0e4          # Pa; friction (the ply's) on both faces
//! ```
use super::{parse_generators, unit_scale};
use crate::geometry::{Point, Vector};
use crate::io::flow::FlowFormat;
use crate::io::points::read_points;
use crate::io::read_tool;
use crate::io::vtk::VtuEncoding;
use crate::kinematic::fishnet::check_memory;
use crate::kinematic::{Extent, KinematicSettings, SurfaceKind, DEFAULT_MAX_SHEAR_DEG};
use crate::layup::auto::DEFAULT_TOLERANCE_DEG;
use crate::layup::coarse::{coarser_grid, MAX_COARSE_LEVELS};
use crate::layup::{
    locking_angle_deg, AutoModel, Layup, Orientation, Ply, PlyMaterial, Refinement, StackSide, Start,
    DEFAULT_SOLVER_ITERATIONS, MAX_LOAD_STEPS, MAX_SOLVER_ITERATIONS,
};
use crate::material::flow::Cavity;
use crate::material::MaterialCard;
use crate::mechanics::forming::{die_facing, Binder, Forming};
use crate::mechanics::sheet::{
    blank_fractions, check_blank, default_origin_node, Cut, Factors, Fold, Region, Reinforcement, Seam, SheetFeatures,
};
use crate::mechanics::ContactMode;
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Why a scene could not be read.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The scene file could not be read.
    #[error("cannot read scene {path}: {source}. Check the path.")]
    Io {
        /// The file.
        path: PathBuf,
        /// What the system said.
        source: std::io::Error,
    },
    /// The scene is wrong; the message names the field and line.
    #[error("scene {path}: {message}")]
    Invalid {
        /// The file.
        path: PathBuf,
        /// What is wrong and what to do.
        message: String,
    },
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneFile {
    #[serde(default = "default_units")]
    units: String,
    tool: String,
    reference: Option<[f64; 3]>,
    surface: Option<toml::Spanned<String>>,
    stack_side: Option<String>,
    roll_width: Option<f64>,
    nesting_gap: Option<f64>,
    cutting_margin: Option<f64>,
    #[serde(default)]
    rotate_patterns: bool,
    friction: Option<f64>,
    ply_friction: Option<f64>,
    #[serde(default)]
    materials: BTreeMap<String, String>,
    export: Option<toml::Spanned<ExportFile>>,
    #[serde(default)]
    ply: Vec<toml::Spanned<PlyFile>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ExportFile {
    mesh: String,
    #[serde(default = "default_export_formats")]
    formats: Vec<String>,
    #[serde(default = "default_cavity")]
    cavity: String,
    #[serde(default)]
    permeability: bool,
    #[serde(default = "default_vtu")]
    vtu: String,
}

fn default_vtu() -> String {
    "auto".into()
}

fn default_units() -> String {
    "m".into()
}
fn default_export_formats() -> Vec<String> {
    vec!["vtu".into()]
}
fn default_cavity() -> String {
    "fixed".into()
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PlyFile {
    name: String,
    origin: [f64; 3],
    warp: Option<[f64; 3]>,
    angle_deg: Option<f64>,
    spacing: f64,
    grid: Option<[usize; 2]>,
    outline: Option<Vec<[f64; 3]>>,
    outline_file: Option<String>,
    origin_node: Option<[usize; 2]>,
    #[serde(default)]
    pre_shear_deg: f64,
    #[serde(default = "default_generators")]
    generators: String,
    locking_angle_deg: Option<f64>,
    max_shear_deg: Option<f64>,
    surface: Option<toml::Spanned<String>>,
    #[serde(default = "default_method")]
    method: String,
    tolerance_deg: Option<f64>,
    material: Option<String>,
    thickness: Option<f64>,
    mode: Option<String>,
    start: Option<String>,
    sheet_normal: Option<[f64; 3]>,
    load_steps: Option<usize>,
    max_iterations: Option<usize>,
    stick: Option<bool>,
    friction: Option<f64>,
    ply_friction: Option<f64>,
    hold: Option<Vec<[usize; 2]>>,
    escape_saddles: Option<bool>,
    #[serde(default)]
    reinforcement: Vec<ReinforcementFile>,
    seam: Option<SeamFile>,
    fold: Option<FoldFile>,
    #[serde(default)]
    cut: Vec<CutFile>,
    blank: Option<Vec<[f64; 2]>>,
    stroke: Option<[f64; 3]>,
    die: Option<String>,
    binder: Option<BinderFile>,
    coarse_levels: Option<usize>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct BinderFile {
    outline: Vec<[f64; 2]>,
    pressure: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ReinforcementFile {
    edges: Option<f64>,
    axes: Option<f64>,
    u: Option<[f64; 2]>,
    v: Option<[f64; 2]>,
    #[serde(default = "one")]
    tension: f64,
    #[serde(default = "one")]
    shear: f64,
    #[serde(default = "one")]
    bending: f64,
    #[serde(default = "one")]
    weight: f64,
}

fn one() -> f64 {
    1.0
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SeamFile {
    rows: [usize; 2],
    #[serde(default = "default_allowance")]
    allowance: usize,
}

fn default_allowance() -> usize {
    1
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FoldFile {
    row: Option<usize>,
    stiffness: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CutFile {
    points: Vec<[f64; 2]>,
}

fn default_generators() -> String {
    "geodesic".into()
}
fn default_method() -> String {
    "kinematic".into()
}

/// The scene's `[export]` table: map every ply onto a resin-flow mesh.
#[derive(Debug, Clone)]
pub struct SceneExport {
    /// The flow mesh file.
    pub mesh: PathBuf,
    /// The formats to write.
    pub formats: Vec<FlowFormat>,
    /// What shear does to thickness and Vf.
    pub cavity: Cavity,
    /// Whether to write permeability tensors.
    pub permeability: bool,
    /// How `flow.vtu` stores its arrays.
    pub vtu: VtuEncoding,
}

/// The mechanical refinement a ply asks for; errors name the field.
fn refinement(
    p: &PlyFile,
    material: Option<&PlyMaterial>,
    extent: &Extent,
    scale: f64,
    scene_friction: Option<f64>,
    scene_ply_friction: Option<f64>,
    base: &Path,
) -> Result<Refinement, (&'static str, String)> {
    let m = material.ok_or((
        "material",
        "a mechanical ply needs a material card: material = \"card.toml\" or a name from [materials]".to_string(),
    ))?;
    let mode = match p.mode.as_deref().unwrap_or("pressed") {
        "pressed" => ContactMode::Pressed,
        "free" => ContactMode::Free,
        other => return Err(("mode", format!("unknown mode '{other}': use \"pressed\" or \"free\""))),
    };
    let start = match (p.start.as_deref().unwrap_or("kinematic"), p.sheet_normal) {
        ("kinematic", None) => Start::Kinematic,
        ("kinematic", Some(_)) => return Err(("sheet_normal", "only a ply with start = \"flat\" uses it".into())),
        ("flat", normal) => {
            let n = normal.unwrap_or([0.0, 0.0, 1.0]);
            let n = Vector::new(n[0], n[1], n[2]);
            if !(n.iter().all(|x| x.is_finite()) && n.norm() > 0.0) {
                return Err((
                    "sheet_normal",
                    format!("must be a non-zero vector of three finite numbers, got {:?}", p.sheet_normal),
                ));
            }
            if !matches!(extent, Extent::Grid { .. }) {
                return Err(("start", "a flat sheet needs a grid (not an outline)".into()));
            }
            if mode == ContactMode::Pressed && p.stroke.is_none() {
                return Err((
                    "stroke",
                    "a flat blank pressed onto the tool is formed by the tool's stroke: give stroke = [dx, dy, dz], the punch's travel (the tool file has it where the stroke ends), or mode = \"free\" to let the sheet hang under gravity".into(),
                ));
            }
            Start::Flat { normal: n.normalize() }
        }
        (other, _) => return Err(("start", format!("unknown start '{other}': use \"kinematic\" or \"flat\""))),
    };
    let load_steps = match p.load_steps {
        Some(0) => return Err(("load_steps", "must be at least 1".into())),
        Some(n) if n > MAX_LOAD_STEPS => return Err(("load_steps", format!("at most {MAX_LOAD_STEPS}, got {n}"))),
        Some(n) => n,
        None => 1,
    };
    let max_iterations = match p.max_iterations {
        Some(0) => return Err(("max_iterations", "must be at least 1".into())),
        Some(n) if n > MAX_SOLVER_ITERATIONS => {
            return Err(("max_iterations", format!("at most {MAX_SOLVER_ITERATIONS}, got {n}")))
        }
        Some(n) => n,
        None => DEFAULT_SOLVER_ITERATIONS,
    };
    let mut sheet = SheetFeatures::default();
    let length = |field: &'static str, x: f64| -> Result<f64, (&'static str, String)> {
        if x.is_finite() {
            Ok(x * scale)
        } else {
            Err((field, format!("must be a finite length, got {x}")))
        }
    };
    for r in &p.reinforcement {
        let region = match (r.edges, r.axes, r.u, r.v) {
            (Some(w), None, None, None) if w > 0.0 => Region::Edges(length("reinforcement", w)?),
            (None, Some(w), None, None) if w > 0.0 => Region::Axes(length("reinforcement", w)?),
            (None, None, Some(u), Some(v)) if u[0] <= u[1] && v[0] <= v[1] => Region::Rectangle {
                u: [length("reinforcement", u[0])?, length("reinforcement", u[1])?],
                v: [length("reinforcement", v[0])?, length("reinforcement", v[1])?],
            },
            _ => {
                return Err((
                    "reinforcement",
                    "give one region: edges = W (a band W wide along the sheet's edges), axes = W (bands along the fibres through the origin node) or u = [u0, u1] and v = [v0, v1] (from the origin node, u0 <= u1, v0 <= v1); widths positive".into(),
                ))
            }
        };
        let factors = Factors { tension: r.tension, shear: r.shear, bending: r.bending, weight: r.weight };
        if [factors.tension, factors.shear, factors.bending, factors.weight]
            .iter()
            .any(|f| !(f.is_finite() && *f > 0.0))
        {
            return Err((
                "reinforcement",
                "the factors tension, shear, bending and weight must be positive numbers".into(),
            ));
        }
        sheet.reinforcements.push(Reinforcement { region, factors });
    }
    let nu = match extent {
        Extent::Grid { nu, .. } => Some(*nu),
        Extent::Outline(_) => None,
    };
    if let Some(seam) = &p.seam {
        if nu.is_none() {
            return Err(("seam", "a seam needs a grid (not an outline)".into()));
        }
        sheet.seam = Some(Seam { rows: seam.rows, allowance: seam.allowance });
    }
    if let Some(fold) = &p.fold {
        let Some(nu) = nu else { return Err(("fold", "a fold needs a grid (not an outline)".into())) };
        sheet.fold = Some(Fold { row: fold.row.unwrap_or(nu / 2), stiffness: fold.stiffness });
    }
    for c in &p.cut {
        let points =
            c.points.iter().map(|q| Ok([length("cut", q[0])?, length("cut", q[1])?])).collect::<Result<Vec<_>, _>>()?;
        sheet.cuts.push(Cut { points });
    }
    if let Some(blank) = &p.blank {
        if !matches!(start, Start::Flat { .. }) {
            return Err((
                "blank",
                "the blank is the shape the flat sheet is cut to: give start = \"flat\" (a ply draped from its kinematic net is trimmed on the tool by outline = ...)".into(),
            ));
        }
        let corners = blank
            .iter()
            .map(|q| Ok([length("blank", q[0])?, length("blank", q[1])?]))
            .collect::<Result<Vec<_>, _>>()?;
        check_blank(&corners).map_err(|e| ("blank", e.0))?;
        sheet.blank = Some(corners);
    }
    if let (Extent::Grid { nu, nv, origin_node }, false) = (extent, sheet.is_empty()) {
        // The features must fit the grid now, not after the drape.
        let origin = origin_node.unwrap_or_else(|| default_origin_node(*nu, *nv, sheet.seam));
        let field = if p.blank.is_some() && sheet.seam.is_none() { "blank" } else { "seam" };
        sheet.layout(*nu, *nv, p.spacing * scale, origin).map_err(|e| (field, e.0))?;
        if let Some(blank) = &sheet.blank {
            let fractions = blank_fractions(blank, *nu, *nv, p.spacing * scale, origin);
            if !fractions.iter().any(|f| *f > 0.0) {
                return Err(("blank", "the blank covers no cell of the grid: make the grid reach it".into()));
            }
        }
    }
    let forming = forming(p, start, mode, base, scale)?;
    let seam = sheet.seam;
    let coarse_levels = match (p.coarse_levels, &forming, extent) {
        (None | Some(0), ..) => 0,
        (Some(_), None, _) => {
            return Err((
                "coarse_levels",
                "only a blank formed by the tools is formed coarse to fine: give start = \"flat\", mode = \"pressed\" and a stroke".into(),
            ))
        }
        (Some(n), ..) if n > MAX_COARSE_LEVELS => {
            return Err(("coarse_levels", format!("at most {MAX_COARSE_LEVELS} (a grid {} times coarser), got {n}", 1 << MAX_COARSE_LEVELS)))
        }
        (Some(_), Some(_), _) if seam.is_some() => {
            return Err(("coarse_levels", "a sheet with a seam is formed at its own spacing: leave coarse_levels out".into()))
        }
        (Some(n), Some(_), Extent::Grid { nu, nv, origin_node }) => {
            let origin = origin_node.unwrap_or_else(|| default_origin_node(*nu, *nv, None));
            coarser_grid(*nu, *nv, origin, 1 << n).map_err(|e| ("coarse_levels", e))?;
            n
        }
        (Some(_), Some(_), Extent::Outline(_)) => {
            return Err(("coarse_levels", "a flat blank is a grid: give grid = [nu, nv]".into()))
        }
    };
    Ok(Refinement {
        material: m.card.clone(),
        material_path: m.path.clone(),
        mode,
        start,
        load_steps,
        max_iterations,
        sheet,
        stick: match (p.stick, mode) {
            (Some(true), m) if m != ContactMode::Free => {
                return Err(("stick", "only a free drape sticks to the tool: give mode = \"free\"".into()))
            }
            (s, _) => s.unwrap_or(false),
        },
        friction: match p.friction.or(scene_friction).or(m.card.friction) {
            Some(mu) if !(mu.is_finite() && mu >= 0.0) => {
                return Err(("friction", format!("must be a finite number >= 0 (Coulomb's coefficient), got {mu}")))
            }
            mu => mu.unwrap_or(0.0),
        },
        ply_friction: match p.ply_friction.or(scene_ply_friction) {
            Some(mu) if !(mu.is_finite() && mu >= 0.0) => {
                return Err((
                    "ply_friction",
                    format!("must be a finite number >= 0 (Coulomb's coefficient between plies), got {mu}"),
                ))
            }
            mu => mu,
        },
        plies_below: None,
        holds: match (extent, &p.hold) {
            (_, None) => Vec::new(),
            (Extent::Grid { nu, nv, origin_node }, Some(hold)) => {
                let (i0, j0) = origin_node.unwrap_or_else(|| default_origin_node(*nu, *nv, seam));
                let d = p.spacing * scale;
                let mut holds = Vec::new();
                for &[i, j] in hold {
                    if i >= *nu || j >= *nv {
                        return Err((
                            "hold",
                            format!(
                                "node [{i}, {j}] is outside the {nu} x {nv} grid: give [i, j] with i < {nu}, j < {nv}"
                            ),
                        ));
                    }
                    holds.push([(i as f64 - i0 as f64) * d, (j as f64 - j0 as f64) * d]);
                }
                holds
            }
            (Extent::Outline(_), Some(_)) => {
                return Err(("hold", "held nodes are grid nodes [i, j]: the ply needs a grid (not an outline)".into()))
            }
        },
        escape_saddles: p.escape_saddles.unwrap_or(false),
        forming,
        coarse_levels,
    })
}

/// The forming process of a flat blank pressed onto the tool: the punch's stroke, the die, the
/// binder (errors name the field).
fn forming(
    p: &PlyFile,
    start: Start,
    mode: ContactMode,
    base: &Path,
    scale: f64,
) -> Result<Option<Forming>, (&'static str, String)> {
    let formed = matches!(start, Start::Flat { .. }) && mode == ContactMode::Pressed;
    if !formed {
        for (field, given) in [("stroke", p.stroke.is_some()), ("die", p.die.is_some()), ("binder", p.binder.is_some())]
        {
            if given {
                return Err((
                    field,
                    "only a flat blank formed by the tools uses it: give start = \"flat\" and mode = \"pressed\""
                        .into(),
                ));
            }
        }
        return Ok(None);
    }
    let stroke = p.stroke.expect("a formed blank has its stroke (checked with start)");
    let stroke = Vector::new(stroke[0], stroke[1], stroke[2]) * scale;
    let origin = Point::new(p.origin[0], p.origin[1], p.origin[2]) * scale;
    let die_file = p.die.as_ref().map(|file| base.join(file));
    let die = match &die_file {
        None => None,
        Some(path) => {
            let die = read_tool(path, scale).map_err(|e| ("die", format!("{e}")))?;
            let die = die_facing(die, &origin, &stroke).map_err(|e| ("die", format!("{e}")))?;
            Some(Arc::new(die))
        }
    };
    let binder = p.binder.as_ref().map(|b| Binder {
        outline: b.outline.iter().map(|q| [q[0] * scale, q[1] * scale]).collect(),
        pressure: b.pressure,
        gripping: None,
    });
    let forming = Forming {
        stroke,
        die,
        // Named as the tool is (`meta.tool`): joined to the scene's folder.
        die_file: die_file.map(|f| f.display().to_string()),
        binder,
        blank_plane: None,
        at_stroke_end: false,
    };
    forming.check(&origin).map_err(|e| (e.field, e.message))?;
    Ok(Some(forming))
}

/// Gap between nested flat patterns when the scene gives none, metres.
pub const DEFAULT_NESTING_GAP: f64 = 0.01;

/// A scene: the tool and its plies in stacking order.
#[derive(Debug, Clone)]
pub struct Scene {
    /// The scene file.
    pub path: PathBuf,
    /// Metres per unit of the scene and OBJ.
    pub scale: f64,
    /// The tool file.
    pub tool: PathBuf,
    /// The plies, their reference direction and stacking side.
    pub layup: Layup,
    /// Fabric roll width for nesting, metres.
    pub roll_width: Option<f64>,
    /// Gap between nested pieces, metres.
    pub nesting_gap: f64,
    /// Allowance added around each flat pattern, metres.
    pub cutting_margin: f64,
    /// Whether pieces may be turned 90 degrees on the roll (warp across the roll).
    pub rotate_patterns: bool,
    /// The flow export, if the scene has an `[export]` table.
    pub export: Option<SceneExport>,
}

impl Scene {
    /// Read and check a scene file.
    pub fn load(path: &Path) -> Result<Scene, SceneError> {
        let text = std::fs::read_to_string(path).map_err(|source| SceneError::Io { path: path.into(), source })?;
        let invalid = |message: String| SceneError::Invalid { path: path.into(), message };
        let file: SceneFile = toml::from_str(&text).map_err(|e| invalid(e.to_string().trim_end().to_string()))?;
        let line_of = |offset: usize| 1 + text[..offset].matches('\n').count();
        let scale = unit_scale(&file.units).map_err(|m| invalid(format!("field `units`: {m}")))?;
        let base = path.parent().unwrap_or(Path::new("."));
        if file.ply.is_empty() {
            return Err(invalid(
                "no [[ply]] table: add at least one ply (name, origin, angle_deg or warp, spacing, grid)".into(),
            ));
        }
        let v = |a: [f64; 3]| Vector::new(a[0], a[1], a[2]);
        let reference = match file.reference {
            None => Vector::x(),
            Some(r) if v(r).norm().is_finite() && v(r).norm() > 0.0 => v(r).normalize(),
            Some(r) => {
                return Err(invalid(format!(
                    "field `reference`: must be a non-zero vector of three finite numbers, got {r:?}"
                )))
            }
        };
        let scene_surface = match &file.surface {
            None => SurfaceKind::Facets,
            Some(spanned) => spanned
                .get_ref()
                .parse::<SurfaceKind>()
                .map_err(|m| invalid(format!("field `surface` (line {}): {m}", line_of(spanned.span().start))))?,
        };
        let stack_side = match file.stack_side.as_deref().unwrap_or("normal") {
            "normal" => StackSide::Normal,
            "opposite" => StackSide::Opposite,
            other => {
                return Err(invalid(format!(
                    "field `stack_side`: unknown side '{other}': use \"normal\" or \"opposite\""
                )))
            }
        };
        let positive_length = |field: &str, x: Option<f64>| -> Result<Option<f64>, SceneError> {
            match x {
                None => Ok(None),
                Some(x) if x.is_finite() && x > 0.0 => Ok(Some(x * scale)),
                Some(x) => Err(invalid(format!("field `{field}`: must be a positive length, got {x}"))),
            }
        };
        let roll_width = positive_length("roll_width", file.roll_width)?;
        let length_or = |field: &str, x: Option<f64>, default: f64| match x {
            None => Ok(default),
            Some(g) if g.is_finite() && g >= 0.0 => Ok(g * scale),
            Some(g) => Err(invalid(format!("field `{field}`: must be a length >= 0, got {g}"))),
        };
        let nesting_gap = length_or("nesting_gap", file.nesting_gap, DEFAULT_NESTING_GAP)?;
        let cutting_margin = length_or("cutting_margin", file.cutting_margin, 0.0)?;
        let mut materials: BTreeMap<String, PlyMaterial> = BTreeMap::new();
        for (name, file) in &file.materials {
            let path = base.join(file);
            let card = MaterialCard::load(&path).map_err(|e| invalid(format!("[materials] `{name}`: {e}")))?;
            materials.insert(name.clone(), PlyMaterial { name: name.clone(), card, path });
        }
        let export = match &file.export {
            None => None,
            Some(spanned) => {
                let e = spanned.get_ref();
                let line = line_of(spanned.span().start);
                let at = |field: &str, m: String| invalid(format!("[export] (line {line}), field `{field}`: {m}"));
                let mut formats = Vec::new();
                for f in &e.formats {
                    let f: FlowFormat = f.parse().map_err(|m| at("formats", m))?;
                    if !formats.contains(&f) {
                        formats.push(f);
                    }
                }
                if formats.is_empty() {
                    return Err(at("formats", "is empty: name at least one format".into()));
                }
                let cavity = match e.cavity.as_str() {
                    "fixed" => Cavity::Fixed,
                    "free" => Cavity::Free,
                    other => return Err(at("cavity", format!("unknown cavity '{other}': use \"fixed\" or \"free\""))),
                };
                let vtu: VtuEncoding = e.vtu.parse().map_err(|m| at("vtu", m))?;
                let mesh = base.join(&e.mesh);
                if !mesh.is_file() {
                    return Err(at(
                        "mesh",
                        format!("no flow mesh at {}: check the path (relative to the scene file)", mesh.display()),
                    ));
                }
                Some(SceneExport { mesh, formats, cavity, permeability: e.permeability, vtu })
            }
        };
        let mut plies = Vec::new();
        for spanned in &file.ply {
            let line = line_of(spanned.span().start);
            let p = spanned.get_ref();
            let at = |field: &str, m: String| invalid(format!("ply '{}' (line {line}), field `{field}`: {m}", p.name));
            if plies.iter().any(|q: &Ply| q.settings.name == p.name) {
                return Err(at("name", "two plies have this name; give each ply its own name".into()));
            }
            if !p.origin.iter().all(|x| x.is_finite()) {
                return Err(at("origin", "must be three finite numbers".into()));
            }
            if !(p.spacing.is_finite() && p.spacing > 0.0) {
                return Err(at("spacing", format!("must be a positive length, got {}", p.spacing)));
            }
            let orientation = match (p.warp, p.angle_deg) {
                (Some(_), Some(_)) => return Err(at("warp", "give either warp or angle_deg, not both".into())),
                (Some(w), None) => {
                    if !w.iter().all(|x| x.is_finite()) {
                        return Err(at("warp", "must be three finite numbers".into()));
                    }
                    if v(w).norm() == 0.0 {
                        return Err(at("warp", "must not be the zero vector".into()));
                    }
                    Orientation::Warp(v(w))
                }
                (None, Some(a)) if a.is_finite() => Orientation::Angle(a.to_radians()),
                (None, Some(a)) => return Err(at("angle_deg", format!("must be a finite angle, got {a}"))),
                (None, None) => Orientation::Angle(0.0),
            };
            let extent = match (p.grid, &p.outline, &p.outline_file) {
                (Some([nu, nv]), None, None) => {
                    if nu < 2 || nv < 2 {
                        return Err(at("grid", format!("needs at least 2 x 2 nodes, got {nu} x {nv}")));
                    }
                    // Before anything is sized by the grid (sheet features lay out per node).
                    check_memory(nu, nv).map_err(|e| at("grid", e.to_string()))?;
                    Extent::Grid { nu, nv, origin_node: p.origin_node.map(|[i, j]| (i, j)) }
                }
                (None, Some(points), None) => {
                    Extent::Outline(points.iter().map(|a| Point::new(a[0], a[1], a[2]) * scale).collect())
                }
                (None, None, Some(f)) => {
                    Extent::Outline(read_points(&base.join(f), scale).map_err(|m| at("outline_file", m))?)
                }
                _ => return Err(at("grid", "give exactly one of grid, outline or outline_file".into())),
            };
            let generators = parse_generators(&p.generators, base, scale).map_err(|m| at("generators", m))?;
            let material = match &p.material {
                None => None,
                Some(m) => Some(match materials.get(m) {
                    Some(known) => known.clone(),
                    None => {
                        let path = base.join(m);
                        if !path.is_file() {
                            let names: Vec<&str> = materials.keys().map(String::as_str).collect();
                            return Err(at(
                                "material",
                                format!(
                                    "'{m}' is neither a name in [materials] ({}) nor a card file {}",
                                    if names.is_empty() { "none given".to_string() } else { names.join(", ") },
                                    path.display()
                                ),
                            ));
                        }
                        let card = MaterialCard::load(&path).map_err(|e| at("material", e.to_string()))?;
                        PlyMaterial { name: card.name.clone(), card, path }
                    }
                }),
            };
            let thickness = match p.thickness {
                Some(t) if t.is_finite() && t > 0.0 => Some(t * scale),
                Some(t) => return Err(at("thickness", format!("must be a positive length, got {t}"))),
                None => material.as_ref().map(|m| m.card.thickness),
            };
            let refinement = match p.method.as_str() {
                "kinematic" => {
                    let mechanical_only = [
                        ("mode", p.mode.is_some()),
                        ("start", p.start.is_some()),
                        ("sheet_normal", p.sheet_normal.is_some()),
                        ("load_steps", p.load_steps.is_some()),
                        ("max_iterations", p.max_iterations.is_some()),
                        ("stick", p.stick.is_some()),
                        ("friction", p.friction.is_some()),
                        ("ply_friction", p.ply_friction.is_some()),
                        ("hold", p.hold.is_some()),
                        ("escape_saddles", p.escape_saddles.is_some()),
                        ("reinforcement", !p.reinforcement.is_empty()),
                        ("seam", p.seam.is_some()),
                        ("fold", p.fold.is_some()),
                        ("cut", !p.cut.is_empty()),
                        ("blank", p.blank.is_some()),
                        ("stroke", p.stroke.is_some()),
                        ("die", p.die.is_some()),
                        ("binder", p.binder.is_some()),
                        ("coarse_levels", p.coarse_levels.is_some()),
                    ];
                    if let Some((field, _)) = mechanical_only.iter().find(|(_, given)| *given) {
                        return Err(at(field, "only a ply with method = \"mechanical\" uses it".into()));
                    }
                    None
                }
                "mechanical" => Some(
                    refinement(p, material.as_ref(), &extent, scale, file.friction, file.ply_friction, base)
                        .map_err(|(f, m)| at(f, m))?,
                ),
                "auto" => {
                    if material.is_none() {
                        return Err(at(
                            "material",
                            "method = \"auto\" weighs the kinematic net under the ply's material card: give material = \"card.toml\" or a name from [materials]".into(),
                        ));
                    }
                    let r = refinement(p, material.as_ref(), &extent, scale, file.friction, file.ply_friction, base)
                        .map_err(|(f, m)| at(f, m))?;
                    if r.mode != ContactMode::Pressed {
                        return Err(at(
                            "mode",
                            "method = \"auto\" chooses between the kinematic net and the pressed drape; a free (hanging) drape has no kinematic counterpart: use method = \"mechanical\"".into(),
                        ));
                    }
                    Some(r)
                }
                other => {
                    return Err(at(
                        "method",
                        format!("unknown method '{other}': use \"kinematic\", \"mechanical\" or \"auto\""),
                    ))
                }
            };
            let auto = match (p.method.as_str(), p.tolerance_deg) {
                ("auto", None) => Some(AutoModel { tolerance_deg: DEFAULT_TOLERANCE_DEG }),
                ("auto", Some(t)) if t.is_finite() && t > 0.0 => Some(AutoModel { tolerance_deg: t }),
                ("auto", Some(t)) => {
                    return Err(at("tolerance_deg", format!("must be a positive angle in degrees, got {t}")))
                }
                (_, None) => None,
                (_, Some(_)) => return Err(at("tolerance_deg", "only a ply with method = \"auto\" uses it".into())),
            };
            // A seamed sheet is held on its stitch line unless told otherwise.
            let extent = match (extent, refinement.as_ref().and_then(|r| r.sheet.seam)) {
                (Extent::Grid { nu, nv, origin_node: None }, Some(seam)) => {
                    Extent::Grid { nu, nv, origin_node: Some(default_origin_node(nu, nv, Some(seam))) }
                }
                (extent, _) => extent,
            };
            let max_shear = p.max_shear_deg.unwrap_or(DEFAULT_MAX_SHEAR_DEG);
            if !(max_shear > 0.0 && max_shear < 90.0) {
                return Err(at("max_shear_deg", format!("must lie strictly between 0 and 90, got {max_shear}")));
            }
            if !(p.pre_shear_deg.abs() < 90.0) {
                return Err(at(
                    "pre_shear_deg",
                    format!("must lie strictly between -90 and 90, got {}", p.pre_shear_deg),
                ));
            }
            let (locking, locking_source) = locking_angle_deg(p.locking_angle_deg, material.as_ref().map(|m| &m.card));
            if !(locking > 0.0 && locking < 90.0) {
                return Err(at("locking_angle_deg", format!("must lie strictly between 0 and 90, got {locking}")));
            }
            let surface = match &p.surface {
                None => scene_surface,
                Some(spanned) => spanned.get_ref().parse::<SurfaceKind>().map_err(|m| at("surface", m))?,
            };
            let settings = KinematicSettings {
                name: p.name.clone(),
                origin: Point::from(v(p.origin) * scale),
                warp: match orientation {
                    Orientation::Warp(w) => w,
                    Orientation::Angle(_) => reference,
                },
                spacing: p.spacing * scale,
                extent,
                pre_shear: p.pre_shear_deg.to_radians(),
                generators,
                max_shear: max_shear.to_radians(),
                surface,
            };
            plies.push(Ply {
                settings,
                orientation,
                material,
                thickness,
                refinement,
                auto,
                locking_angle: locking.to_radians(),
                locking_source,
                line,
            });
        }
        // A ply above another needs the thickness of the one below to know where it lies.
        if plies.len() > 1 {
            if let Some(p) = plies[..plies.len() - 1].iter().find(|p| p.thickness.is_none()) {
                return Err(invalid(format!(
                    "ply '{}' (line {}), field `thickness`: a ply with plies above it needs a thickness: give `material` (a card with its thickness) or `thickness`",
                    p.settings.name, p.line
                )));
            }
        }
        Ok(Scene {
            path: path.into(),
            scale,
            tool: base.join(&file.tool),
            layup: Layup { reference, stack_side, plies, wrinkles: true },
            roll_width,
            nesting_gap,
            cutting_margin,
            rotate_patterns: file.rotate_patterns,
            export,
        })
    }
}
