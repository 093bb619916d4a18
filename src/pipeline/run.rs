//! `drape run` as a library call: [`run`] drapes every ply of a [`Scene`] and writes everything
//! the run produces into one folder, telling its caller what it did through [`Event`]s (the
//! command line prints them).
//!
//! Order, so that bad input costs nothing computed: the plies' settings are checked, the flow
//! export's mesh is read and the plies' cards checked for what it asks, the tool is read, the
//! output folder is checked ([`super::folder`]), every ply is draped (a bad ply stops
//! the run before any file is written), the flat patterns are made and nested (a ply too wide
//! for the roll stops the run before any file is written), the plies are mapped onto the scene's
//! flow mesh and the map checked against every format the export asks for (a ply that covers no
//! element, or a map a format cannot write, stops the run before any file is written), then each
//! net is written, the flat patterns are drawn, the flow files are written, `layup.json` is written
//! listing every file, and last the files of an earlier run into the folder that this one did
//! not write are removed.
use super::folder::{prepare, FolderError};
use super::scene::{Scene, SceneExport};
use crate::geometry::ToolSurface;
use crate::io::drawing::{write_cutting_plan, PatternError};
use crate::io::flow::{check_flow, write_flow_with, FlowOptions};
use crate::io::layup_json::{self, LAYUP_FILE};
use crate::io::{
    kinematic_net_path, read_flow_mesh, read_tool, write_json, write_net, ExportError, Format, ReadToolError,
};
use crate::kinematic::fishnet::{check_settings, check_spacing_on_tool, DrapeError};
use crate::kinematic::Extent;
use crate::layup::flat::{blank_pattern, ply_pattern, CutWarning, FlatError, FlatPattern};
use crate::layup::nest::{nest, Nesting, Rotation};
use crate::layup::stack::{drape_layup, LayupError, PlyResult};
use crate::layup::table::{ExportPlyRow, ExportRow, LayupRow, LayupTable, NestingRow};
use crate::layup::Ply;
use crate::mapping::{map_plies, FlowMesh, LayupMap, MapError, PlyToMap};
use crate::material::flow::PermeabilityModel;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// What [`run`] reports, in the order it happens.
pub enum Event<'a> {
    /// The tool was read and checked.
    ToolRead {
        /// The tool file.
        path: &'a Path,
        /// The checked surface (its report says what was mended).
        tool: &'a ToolSurface,
    },
    /// Ply `index` (from 0) of `count` starts draping.
    Draping {
        /// Position in the stack.
        index: usize,
        /// Plies in the stack.
        count: usize,
        /// The ply's name.
        name: &'a str,
    },
    /// Every ply is draped.
    Draped,
    /// A ply's net was written.
    PlyWritten {
        /// The ply as the scene gives it.
        ply: &'a Ply,
        /// Its drape.
        result: &'a PlyResult,
        /// The files written, in the order of the formats, then the kinematic net a mechanical
        /// ply started from (`<ply>.kinematic.json`, with the json format).
        files: &'a [PathBuf],
        /// Time to read the tool, ms.
        load_ms: f64,
        /// Time to write the files, ms.
        write_ms: f64,
    },
    /// Every net is written: the layup table can be shown.
    Layup {
        /// The scene.
        scene: &'a Scene,
        /// Every ply's drape, in stacking order.
        results: &'a [PlyResult],
    },
    /// A ply has no complete cell, so it has no flat pattern.
    NoPattern {
        /// The ply's name.
        ply: &'a str,
    },
    /// A ply's flat pattern is not cut along the line the ply asks for (its outline, its margin
    /// offset from the cut line): why, and what it is cut along instead.
    PatternWarning {
        /// The ply's name.
        ply: &'a str,
        /// Why.
        warning: &'a CutWarning,
    },
    /// The scene gives no roll width: the pieces were nested on a roll as wide as the widest.
    RollWidthAssumed {
        /// That width, m.
        width: f64,
    },
    /// The flat patterns were nested and drawn.
    CuttingPlan {
        /// Pieces nested.
        pieces: usize,
        /// Where they lie on the roll.
        nesting: &'a Nesting,
        /// The drawings written.
        files: &'a [PathBuf],
    },
    /// The layup table was written.
    TableWritten {
        /// `DIR/layup.json`.
        path: &'a Path,
    },
    /// A value the flow mapping assumed for a ply.
    FlowNote(&'a str),
    /// Every ply was mapped onto the flow mesh.
    FlowMapped {
        /// The flow mesh file.
        path: &'a Path,
        /// The flow mesh.
        mesh: &'a FlowMesh,
        /// The plies on it.
        map: &'a LayupMap,
        /// Time to read and map, ms.
        ms: f64,
    },
    /// One flow format was written.
    FlowWritten {
        /// Its files.
        files: &'a [PathBuf],
    },
    /// Files an earlier run into the folder wrote and this one did not were removed.
    Removed {
        /// Those files.
        files: &'a [PathBuf],
    },
}

/// Why a run stopped. [`RunError::is_bad_input`] tells bad input (exit code 2) from a failed
/// computation (exit code 1).
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// A ply's kinematic settings are unusable.
    #[error("scene {scene}: ply '{ply}' (line {line}): {error}")]
    Settings {
        /// The scene file.
        scene: PathBuf,
        /// The ply.
        ply: String,
        /// Its line in the scene.
        line: usize,
        /// What is wrong.
        error: DrapeError,
    },
    /// The tool could not be read.
    #[error("{0}")]
    Tool(ReadToolError),
    /// A ply could not be draped.
    #[error("scene {scene}: {error}")]
    Layup {
        /// The scene file.
        scene: PathBuf,
        /// What went wrong.
        error: LayupError,
    },
    /// A flat pattern or the nesting could not be made.
    #[error(transparent)]
    Flat(FlatError),
    /// The flow mesh could not be read.
    #[error("scene {scene}: [export] mesh: {error}")]
    FlowMesh {
        /// The scene file.
        scene: PathBuf,
        /// What went wrong.
        error: crate::io::FlowMeshError,
    },
    /// Permeability was asked for but a ply's card has no fibre radius.
    #[error("scene {scene}: ply '{ply}' (line {line}): [export] permeability = true needs a material card with a [flow] section (fibre_radius)")]
    NoFibreRadius {
        /// The scene file.
        scene: PathBuf,
        /// The ply.
        ply: String,
        /// Its line in the scene.
        line: usize,
    },
    /// A ply could not be mapped onto the flow mesh.
    #[error(transparent)]
    Map(MapError),
    /// A file could not be written.
    #[error(transparent)]
    Write(#[from] ExportError),
    /// A drawing could not be written.
    #[error(transparent)]
    Pattern(PatternError),
    /// The output folder cannot be used.
    #[error(transparent)]
    Folder(#[from] FolderError),
    /// Every file was written but a mechanical ply did not reach equilibrium.
    #[error("the mechanical solver stopped without equilibrium for {plies}; the last accepted states were written")]
    Unconverged {
        /// The plies and how their solves ended.
        plies: String,
    },
}

impl RunError {
    /// Whether the input (scene, tool, flow mesh) is at fault rather than the computation.
    pub fn is_bad_input(&self) -> bool {
        matches!(
            self,
            RunError::Settings { .. }
                | RunError::Tool(_)
                | RunError::Layup { .. }
                | RunError::Flat(_)
                | RunError::FlowMesh { .. }
                | RunError::NoFibreRadius { .. }
                | RunError::Map(_)
                | RunError::Folder(_)
        ) || matches!(self, RunError::Write(e) if e.is_bad_input())
    }
}

/// Drape every ply of `scene` and write into `out`: each net in `formats`, the flat patterns
/// nested on the roll, `layup.json` and, with the scene's `[export]`, the plies on its flow mesh.
/// `on` hears what happens (see [`Event`]). Nets of mechanical plies that did not reach
/// equilibrium are written, and the run ends with [`RunError::Unconverged`].
///
/// The run owns `out` ([`super::folder`]): files an earlier run into it wrote that this one does
/// not are removed at the end, and nets of another run or command in it refuse the run unless
/// `replace`.
pub fn run(
    scene: &Scene,
    out: &Path,
    formats: &[Format],
    replace: bool,
    on: &mut dyn FnMut(Event),
) -> Result<(), RunError> {
    for ply in &scene.layup.plies {
        check_settings(&ply.settings).map_err(|error| RunError::Settings {
            scene: scene.path.clone(),
            ply: ply.settings.name.clone(),
            line: ply.line,
            error,
        })?;
    }
    // Everything that can be checked before computing: the flow export's cards and mesh, the
    // tool, the output folder.
    let flow = scene.export.as_ref().map(|e| flow_input(scene, e)).transpose()?;
    let t_load = Instant::now();
    let tool = read_tool(&scene.tool, scene.scale).map_err(RunError::Tool)?;
    let load_ms = t_load.elapsed().as_secs_f64() * 1e3;
    on(Event::ToolRead { path: &scene.tool, tool: &tool });
    for ply in &scene.layup.plies {
        check_spacing_on_tool(&tool, ply.settings.spacing).map_err(|error| RunError::Settings {
            scene: scene.path.clone(),
            ply: ply.settings.name.clone(),
            line: ply.line,
            error,
        })?;
    }
    let folder = prepare(out, replace)?;
    let mut written: Vec<PathBuf> = Vec::new();
    // Drape every ply first, so a bad ply is reported before any file is written.
    let count = scene.layup.plies.len();
    let mut results = drape_layup(&scene.layup, &tool, |index, name| on(Event::Draping { index, count, name }))
        .map_err(|error| RunError::Layup { scene: scene.path.clone(), error })?;
    on(Event::Draped);
    // The flat patterns are nested and the flow export is mapped and checked before the first
    // file is written.
    let cutting = plan_cutting(scene, &results)?;
    let mapped = match (&scene.export, &flow) {
        (Some(export), Some(flow)) => Some(map_flow(scene, export, flow, &results, out)?),
        _ => None,
    };
    folder.create()?;
    let mut unconverged = Vec::new();
    for (ply, r) in scene.layup.plies.iter().zip(results.iter_mut()) {
        r.net.timing.load_ms = load_ms;
        r.net.meta.tool = Some(scene.tool.display().to_string());
        r.net.meta.tool_scale = Some(scene.scale);
        r.net.meta.scene = Some(scene.path.display().to_string());
        if let Some(k) = &mut r.kinematic {
            k.timing.load_ms = load_ms;
            k.meta.tool = r.net.meta.tool.clone();
            k.meta.tool_scale = r.net.meta.tool_scale;
            k.meta.scene = r.net.meta.scene.clone();
            k.meta.material = r.net.meta.material.clone();
            k.meta.angle_deg = r.net.meta.angle_deg;
            k.meta.thickness_m = r.net.meta.thickness_m;
        }
        if let Some(refined) = &r.refined {
            if !refined.ok() {
                unconverged.push(format!("ply '{}' ({:?})", ply.settings.name, refined.outcome()));
            }
        }
    }
    for (ply, result) in scene.layup.plies.iter().zip(&results) {
        let t_write = Instant::now();
        let mut files = write_net(&result.net, out, formats)?;
        // The kinematic net a mechanical ply started from, beside its JSON net (the report's).
        if let Some(k) = result.kinematic.as_ref().filter(|_| formats.contains(&Format::Json)) {
            let path = kinematic_net_path(out, &ply.settings.name);
            write_json(k, &path)?;
            files.push(path);
        }
        let write_ms = t_write.elapsed().as_secs_f64() * 1e3;
        on(Event::PlyWritten { ply, result, files: &files, load_ms, write_ms });
        written.extend(files);
    }
    on(Event::Layup { scene, results: &results });
    let (nesting, patterns) = write_cutting(cutting, out, &mut written, on)?;
    // The flow export before the table, so that the table lists its files.
    let export_row = match (&scene.export, &flow, &mapped) {
        (Some(export), Some(flow), Some(mapped)) => Some(export_flow(export, flow, mapped, out, &mut written, on)?),
        _ => None,
    };
    let files = folder.names(&written);
    let table = LayupTable {
        scene: Some(scene.path.display().to_string()),
        tool: Some(scene.tool.display().to_string()),
        plies: scene
            .layup
            .plies
            .iter()
            .zip(&results)
            .map(|(ply, r)| {
                let mut row = LayupRow::of(ply, r);
                if let Some(p) = patterns.iter().find(|p| p.ply == ply.settings.name) {
                    row.pattern_cut = Some(p.cut);
                    row.pattern_margin_m = Some(p.margin);
                    row.pattern_warnings = p.warnings.clone();
                }
                row
            })
            .collect(),
        nesting: nesting.as_ref().map(NestingRow::from),
        files: files.clone(),
        export: export_row,
    };
    let path = out.join(LAYUP_FILE);
    layup_json::write(&table, &path)?;
    on(Event::TableWritten { path: &path });
    let removed = folder.tidy(&files)?;
    if !removed.is_empty() {
        on(Event::Removed { files: &removed });
    }
    if !unconverged.is_empty() {
        return Err(RunError::Unconverged { plies: unconverged.join(", ") });
    }
    Ok(())
}

/// Flat patterns of every ply, nested on the roll, before anything is written (a ply too wide
/// for the roll stops the run with nothing written).
struct Cutting {
    patterns: Vec<FlatPattern>,
    /// Per ply in stacking order: its pattern's index, or its name when it has no complete cell
    /// (so no pattern).
    plies: Vec<Result<usize, String>>,
    /// The roll width assumed when the scene gives none.
    assumed_width: Option<f64>,
    nesting: Option<Nesting>,
}

/// Flat patterns of every ply, nested on the roll. Plies without a complete cell have no pattern
/// and are named; a pattern not cut along the line its ply asks for says why ([`write_cutting`]
/// reports both).
fn plan_cutting(scene: &Scene, results: &[PlyResult]) -> Result<Cutting, RunError> {
    let mut cutting = Cutting { patterns: Vec::new(), plies: Vec::new(), assumed_width: None, nesting: None };
    for (ply, r) in scene.layup.plies.iter().zip(results) {
        // A ply draped with an outline is cut along it (without a margin).
        let outline = match &ply.settings.extent {
            Extent::Outline(points) => Some(points.as_slice()),
            Extent::Grid { .. } => None,
        };
        // A flat sheet cut to a blank is cut along the blank.
        let blank = ply.refinement.as_ref().and_then(|f| f.sheet.blank.as_deref());
        let pattern = match blank {
            Some(blank) => blank_pattern(&r.net, blank, scene.cutting_margin),
            None => ply_pattern(&r.net, outline, scene.cutting_margin),
        };
        match pattern {
            Ok(p) => {
                cutting.plies.push(Ok(cutting.patterns.len()));
                cutting.patterns.push(p);
            }
            Err(FlatError::NoCells { ply }) => cutting.plies.push(Err(ply)),
            Err(e) => return Err(RunError::Flat(e)),
        }
    }
    if cutting.patterns.is_empty() {
        return Ok(cutting);
    }
    let rotation = if scene.rotate_patterns { Rotation::AllowQuarterTurn } else { Rotation::WarpAlongRoll };
    let roll_width = scene.roll_width.unwrap_or_else(|| {
        // Without a roll width the pieces go on a roll as wide as the widest of them.
        let width = cutting.patterns.iter().map(|p| p.size()[1]).fold(0.0, f64::max);
        cutting.assumed_width = Some(width);
        width
    });
    cutting.nesting = Some(nest(&cutting.patterns, roll_width, scene.nesting_gap, rotation).map_err(RunError::Flat)?);
    Ok(cutting)
}

/// Report the cutting plan and draw it: `patterns.dxf`, `patterns.svg` and one SVG a ply.
/// Returns the nesting (when there is a pattern) and the patterns.
fn write_cutting(
    cutting: Cutting,
    out: &Path,
    written: &mut Vec<PathBuf>,
    on: &mut dyn FnMut(Event),
) -> Result<(Option<Nesting>, Vec<FlatPattern>), RunError> {
    for ply in &cutting.plies {
        match ply {
            Ok(k) => {
                let p = &cutting.patterns[*k];
                for warning in &p.warnings {
                    on(Event::PatternWarning { ply: &p.ply, warning });
                }
            }
            Err(ply) => on(Event::NoPattern { ply }),
        }
    }
    let Some(nesting) = cutting.nesting else { return Ok((None, cutting.patterns)) };
    if let Some(width) = cutting.assumed_width {
        on(Event::RollWidthAssumed { width });
    }
    let files = write_cutting_plan(&cutting.patterns, &nesting, out, "patterns").map_err(RunError::Pattern)?;
    on(Event::CuttingPlan { pieces: cutting.patterns.len(), nesting: &nesting, files: &files });
    written.extend(files);
    Ok((Some(nesting), cutting.patterns))
}

/// Every ply on the flow mesh, checked against the export's formats, before anything is written.
struct MappedFlow {
    map: LayupMap,
    /// What the mapping assumed and the formats will write in the mesh's stead, for the events.
    notes: Vec<String>,
    /// Time to map and check, ms.
    ms: f64,
}

/// Map every ply onto the scene's resin-flow mesh and check the map against every format the
/// export asks for (`io::flow::check_flow`), so that a ply that covers no element, or a map a
/// format cannot write, stops the run before any file is written.
fn map_flow(
    scene: &Scene,
    export: &SceneExport,
    flow: &FlowInput,
    results: &[PlyResult],
    out: &Path,
) -> Result<MappedFlow, RunError> {
    let t = Instant::now();
    let mesh = &flow.mesh;
    let plies: Vec<PlyToMap> = scene
        .layup
        .plies
        .iter()
        .zip(results)
        .zip(&flow.permeability)
        .map(|((ply, r), permeability)| PlyToMap {
            net: &r.net,
            card: ply.material.as_ref().map(|m| &m.card),
            thickness: ply.thickness,
            permeability: *permeability,
        })
        .collect();
    let mut notes = Vec::new();
    let map =
        map_plies(mesh, &plies, export.cavity, true, &mut |n| notes.push(n.to_string())).map_err(RunError::Map)?;
    for &format in &export.formats {
        let path = out.join(format.scene_file());
        notes.extend(check_flow(mesh, &map, format, &path, &flow_options(export))?);
    }
    Ok(MappedFlow { map, notes, ms: t.elapsed().as_secs_f64() * 1e3 })
}

/// The writers' options a scene's export asks for.
fn flow_options(export: &SceneExport) -> FlowOptions {
    FlowOptions { vtu: export.vtu, ..FlowOptions::default() }
}

/// Write the formats the scene's export asks for as `DIR/flow.<ext>` (`FlowFormat::scene_file`;
/// field names prefixed by the ply) from the map [`map_flow`] checked; returns the layup table's
/// record of it.
fn export_flow(
    export: &SceneExport,
    flow: &FlowInput,
    mapped: &MappedFlow,
    out: &Path,
    written: &mut Vec<PathBuf>,
    on: &mut dyn FnMut(Event),
) -> Result<ExportRow, RunError> {
    let (mesh, map) = (&flow.mesh, &mapped.map);
    for n in &mapped.notes {
        on(Event::FlowNote(n));
    }
    let ms = flow.read_ms + mapped.ms;
    on(Event::FlowMapped { path: &export.mesh, mesh, map, ms });
    let mut row = ExportRow {
        mesh: export.mesh.display().to_string(),
        elements: mesh.elements.len(),
        nodes: mesh.nodes.len(),
        formats: export.formats.iter().map(|f| f.name().to_string()).collect(),
        files: Vec::new(),
        plies: map
            .plies
            .iter()
            .map(|p| {
                let c = p.coverage();
                let any = c.covered > 0;
                ExportPlyRow {
                    name: p.ply.clone(),
                    covered: c.covered,
                    share: if c.elements > 0 { c.covered as f64 / c.elements as f64 } else { 0.0 },
                    max_abs_shear_deg: any.then_some(c.max_abs_shear_deg),
                    mean_abs_shear_deg: any.then_some(c.mean_abs_shear_deg),
                    collapsed_elements: c.collapsed,
                }
            })
            .collect(),
    };
    for &format in &export.formats {
        let files = write_flow_with(mesh, map, format, &out.join(format.scene_file()), &flow_options(export))?;
        on(Event::FlowWritten { files: &files });
        row.files.extend(files.iter().filter_map(|p| p.file_name()).map(|n| n.to_string_lossy().into_owned()));
        written.extend(files);
    }
    Ok(row)
}

/// What the flow export needs that can be checked before anything is draped.
struct FlowInput {
    /// The flow mesh, read.
    mesh: FlowMesh,
    /// Time to read it, ms.
    read_ms: f64,
    /// Each ply's permeability model, when the export asks for permeability.
    permeability: Vec<Option<PermeabilityModel>>,
}

/// Read the scene's flow mesh and check that every ply's card gives what the export asks for,
/// before anything is computed.
fn flow_input(scene: &Scene, export: &SceneExport) -> Result<FlowInput, RunError> {
    let mut permeability = Vec::with_capacity(scene.layup.plies.len());
    for ply in &scene.layup.plies {
        permeability.push(if export.permeability {
            let card = ply.material.as_ref().map(|m| &m.card);
            let radius = card.and_then(|c| c.flow).map(|f| f.fibre_radius).ok_or_else(|| RunError::NoFibreRadius {
                scene: scene.path.clone(),
                ply: ply.settings.name.clone(),
                line: ply.line,
            })?;
            Some(PermeabilityModel { fibre_radius: radius })
        } else {
            None
        });
    }
    let t = Instant::now();
    let mesh = read_flow_mesh(&export.mesh, scene.scale)
        .map_err(|error| RunError::FlowMesh { scene: scene.path.clone(), error })?;
    Ok(FlowInput { mesh, read_ms: t.elapsed().as_secs_f64() * 1e3, permeability })
}
