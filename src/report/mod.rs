//! `drape report DIR`: pictures of every ply in a run's output folder and one HTML page that
//! shows them with the layup table and an interactive 3D view.
//!
//! For each `<ply>.drape.json` in DIR it writes, into DIR/report (or another folder):
//! - `<ply>-shear.png`: the ply on its tool, lit and shaded, in the views that together show
//!   every cell (an isometric view first), painted by signed shear on one diverging colour scale
//!   shared by all plies of the report; warp and weft fibres every k-th fibre, the ply's edge,
//!   the seed and the warp direction there, an axis triad; cells past locking hatched, folded
//!   cells in their own colour, the placed nodes where the net stopped ringed in the colour of
//!   why; a colour bar with the locking angle and a legend;
//! - `<ply>-histogram.png/.svg`: the distribution of signed shear with the locking angle marked;
//! - for a mechanical ply, `<ply>-change.png` (the change of shear from the kinematic net, on
//!   the same views) and `<ply>-change-histogram.png/.svg`, with the largest and mean change;
//!   and when the run kept the kinematic net it started from (`<ply>.kinematic.json`),
//!   `<ply>-kinematic.png`: that net from the same views and window on the same colour scale,
//!   shown beside `<ply>-shear.png`; and, when the net records how it meets the tool
//!   (`meta.contact`), `<ply>-contact.png`: the stick/slip map (cells that stick, that slid and
//!   how far, that hang off the tool, that the user held) with the friction and the largest slip;
//!   and, when the net records its draw-in (`meta.draw_in`), `<ply>-draw-in.png/.svg`: the blank
//!   flat and the ply draped, in plan, with how far the edge moved in along the fibres and the
//!   diagonals through the seed;
//! - when the net records its wrinkles (`meta.wrinkles`, every ply of `drape run`),
//!   `<ply>-wrinkles.png`: the wrinkle map, each cell by its waviness about the ply's smoothed
//!   surface on the shear map's views, the cells past the ply's threshold hatched, shown beside
//!   the shear map;
//! - `index.html`: the layup table (from `layup.json` when present, else computed from the
//!   nets), laminate totals, the flow-mesh export as `layup.json` records it, what each node status means, the interactive 3D view (the
//!   project's own script, data embedded: nothing is fetched), every picture, the flat patterns
//!   (`*.svg` in DIR) and notes on whatever could not be drawn.
//!
//! Text is rendered with the DejaVu Sans font compiled into the program (crate `dejavu`,
//! Bitstream Vera licence, which allows embedding), so no system fonts are needed.
pub mod calibration;
pub mod change;
mod draw_in;
mod html;
pub mod optimise;
mod raster;
mod render;
pub mod shade;
pub mod study;
mod view;
pub mod viewer;
mod wrinkle;

pub use render::{bin_shares, bin_width, register_fonts, HEIGHT, WIDTH};
pub use view::{change_limit, colour_limit, shear_colour, View};

use crate::geometry::Point;
use crate::io::layup_json::{self, LAYUP_FILE};
use crate::io::read_tool_mesh;
use crate::io::{kinematic_net_path, read_net, write_atomic, ExportError};
use crate::kinematic::coverage::surface_coverage;
use crate::kinematic::provenance::{ContactRecord, ContactState};
use crate::kinematic::{DrapeNet, Method};
use crate::layup::table::{CoverageOf, LayupRow, LayupTable};
use crate::layup::{locking_angle_deg, LockingSource, DEFAULT_LOCKING_ANGLE_DEG};
use crate::material::MaterialCard;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use rayon::prelude::*;
use render::{LegendItem, Mark, ShadedPicture, Swatch};
use shade::{CellPaint, PlyScene, ToolMesh};
use std::collections::BTreeMap;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Why a report could not be written.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    /// The run folder cannot be listed.
    #[error("cannot list {path}: {source}. Give the folder `drape run --out` wrote.")]
    ReadDir {
        /// The folder.
        path: PathBuf,
        /// What the system said.
        source: std::io::Error,
    },
    /// The run folder holds no net.
    #[error("{path} holds no drape net (*.drape.json). Give the folder `drape run --out` wrote, and run with the json format.")]
    NoNets {
        /// The folder.
        path: PathBuf,
    },
    /// A net could not be read, or a file written.
    #[error(transparent)]
    Net(#[from] ExportError),
    /// `layup.json` could not be read.
    #[error("{path}: {message}. Re-create it with `drape run`, or delete it to build the table from the nets.")]
    Layup {
        /// The file.
        path: PathBuf,
        /// Where and why.
        message: String,
    },
    /// The report folder could not be created.
    #[error("cannot create report folder {path}: {source}. Check the --out path and that its parent is writable.")]
    CreateDir {
        /// The folder.
        path: PathBuf,
        /// What the system said.
        source: std::io::Error,
    },
    /// A picture could not be drawn.
    #[error("cannot draw {path}: {message}. This is a bug; please report it with the run folder.")]
    Draw {
        /// The picture.
        path: PathBuf,
        /// What the renderer said.
        message: String,
    },
}

/// What a report wrote.
#[derive(Debug, Clone)]
pub struct ReportSummary {
    /// The report folder.
    pub out: PathBuf,
    /// Every file written, pictures in ply order then `index.html`.
    pub files: Vec<PathBuf>,
    /// One entry per ply drawn, in table order.
    pub plies: Vec<PlyReport>,
    /// What could not be drawn or read, in words (also shown on the page).
    pub notes: Vec<String>,
}

/// What the report drew for one ply.
#[derive(Debug, Clone)]
pub struct PlyReport {
    /// Ply name (the file stem of its net).
    pub name: String,
    /// How the net was computed.
    pub method: Method,
    /// Complete cells drawn.
    pub cells: usize,
    /// Locking angle used for the marks (degrees).
    pub locking_angle_deg: f64,
    /// Largest |shear| over the complete cells, degrees.
    pub max_abs_shear_deg: f64,
    /// Mean |shear|, degrees.
    pub mean_abs_shear_deg: f64,
    /// Colour limit of the shear map (degrees, symmetric).
    pub colour_limit_deg: f64,
    /// Whether the tool was drawn underneath.
    pub tool_drawn: bool,
    /// For a mechanical ply: the noise floor of its change from the kinematic net (no change
    /// map is drawn when every change lies within it).
    pub change_noise: Option<change::ChangeNoise>,
    /// For a mechanical ply: the change of shear from the kinematic net, summed up.
    pub change: Option<ChangeSummary>,
    /// For a mechanical ply whose kinematic net the run kept: that net in figures (its picture,
    /// `<ply>-kinematic.png`, is drawn beside `<ply>-shear.png` from the same views).
    pub kinematic: Option<KinematicSummary>,
    /// Names of the views drawn (the first is isometric).
    pub views: Vec<String>,
    /// Share of the drawn cells that some view shows (facing it, not hidden).
    pub seen_share: f64,
    /// Fibre lines are drawn every `fibre_step`-th fibre (in the first view).
    pub fibre_step: usize,
    /// Cells sheared past the locking angle (hatched).
    pub over_locking_cells: usize,
    /// Cells folded over against their neighbours or lying on another part of the net (wrinkle
    /// risk).
    pub folded_cells: usize,
    /// Where the net stopped: failure status and how many placed nodes border it.
    pub stops: Vec<(crate::kinematic::NodeStatus, usize)>,
    /// Pictures written for this ply.
    pub files: Vec<PathBuf>,
    /// What could not be drawn for this ply.
    pub notes: Vec<String>,
}

/// Suffix of net files.
const NET_SUFFIX: &str = ".drape.json";
/// Flat-pattern SVGs larger than this are linked from the page instead of inlined.
const PATTERN_INLINE_LIMIT: u64 = 8 << 20;
/// The kinds of picture, as file-name suffixes after `<ply>-`.
const PICTURES: [&str; 5] = ["shear", "kinematic", "histogram", "change", "change-histogram"];
/// Candidate scales (metres per OBJ unit) tried when the tool's units are not recorded.
const TOOL_SCALES: [f64; 2] = [1.0, 1e-3];

/// Read `layup.json` from `dir` if present.
pub fn read_layup(dir: &Path) -> Result<Option<LayupTable>, ReportError> {
    layup_json::read(dir).map_err(|e| ReportError::Layup { path: dir.join(LAYUP_FILE), message: e.message })
}

/// Signed shear (degrees) per cell index `i * (nv - 1) + j`, `None` where a cell is incomplete.
fn shear_values(net: &DrapeNet) -> Vec<Option<f64>> {
    let mut values = vec![None; net.num_cells()];
    for i in 0..net.nu.saturating_sub(1) {
        for j in 0..net.nv.saturating_sub(1) {
            values[i * (net.nv - 1) + j] = net.cell_shear(i, j).map(f64::to_degrees).filter(|g| g.is_finite());
        }
    }
    values
}

/// A tool's triangles as read from its file (file units).
struct RawTool {
    vertices: Vec<Point>,
    triangles: Vec<[u32; 3]>,
    lo: Point,
    hi: Point,
    /// Its facets' sagitta (file units), computed when a change map first needs it.
    sagitta: std::sync::OnceLock<Option<f64>>,
    /// Its smooth corner normals (for the shading), computed once for all plies.
    normals: std::sync::OnceLock<Vec<[crate::geometry::Vector; 3]>>,
}

impl RawTool {
    /// The median sagitta of its curved facets, file units ([`change::facet_sagitta`]).
    fn sagitta(&self) -> Option<f64> {
        *self.sagitta.get_or_init(|| change::facet_sagitta(&self.vertices, &self.triangles))
    }

    /// Its corner normals ([`shade::corner_normals`]; a uniform scale does not change them).
    fn normals(&self) -> &[[crate::geometry::Vector; 3]] {
        self.normals.get_or_init(|| shade::corner_normals(&self.vertices, &self.triangles))
    }
}

/// Where a net's tool (or material card) file is: as recorded (relative to the run's working folder), else
/// relative to the run folder, else its file name in the run folder.
fn locate_tool(recorded: &str, dir: &Path) -> Option<PathBuf> {
    let p = PathBuf::from(recorded);
    let mut candidates = vec![p.clone(), dir.join(&p)];
    if let Some(f) = p.file_name() {
        candidates.push(dir.join(f));
    }
    candidates.into_iter().find(|c| c.is_file())
}

fn load_tool(path: &Path) -> Result<RawTool, String> {
    let raw = read_tool_mesh(path, 1.0).map_err(|e| e.to_string())?.into_mesh();
    let mut lo = Point::from([f64::INFINITY; 3]);
    let mut hi = Point::from([f64::NEG_INFINITY; 3]);
    for v in &raw.vertices {
        lo = lo.inf(v);
        hi = hi.sup(v);
    }
    Ok(RawTool {
        vertices: raw.vertices,
        triangles: raw.triangles,
        lo,
        hi,
        sagitta: Default::default(),
        normals: Default::default(),
    })
}

/// The scale (metres per file unit) the run read the tool with, for a net that does not record
/// it (written by an older drape or another tool): among [`TOOL_SCALES`], those under which the most nodes lie inside the scaled tool's bounding
/// box (grown by 5% of its diagonal), the one whose box size is closest to the net's.
fn guess_scale(tool: &RawTool, net: &DrapeNet) -> f64 {
    let placed: Vec<&Point> = net
        .positions
        .iter()
        .zip(&net.status)
        .filter(|(_, s)| **s == crate::kinematic::NodeStatus::Placed)
        .map(|(p, _)| p)
        .collect();
    let tool_diag = (tool.hi - tool.lo).norm();
    let net_diag = crate::geometry::surface::bounding_diagonal(&placed.iter().map(|p| **p).collect::<Vec<_>>());
    let inside = |s: f64| {
        let grow = 0.05 * s * tool_diag;
        placed.iter().filter(|p| (0..3).all(|k| p[k] >= s * tool.lo[k] - grow && p[k] <= s * tool.hi[k] + grow)).count()
    };
    let counts: Vec<usize> = TOOL_SCALES.iter().map(|&s| inside(s)).collect();
    let most = counts.iter().copied().max().unwrap_or(0);
    let misfit = |s: f64| if net_diag > 0.0 && tool_diag > 0.0 { (s * tool_diag / net_diag).ln().abs() } else { 0.0 };
    TOOL_SCALES
        .iter()
        .zip(&counts)
        .filter(|(_, &c)| c == most)
        .map(|(&s, _)| s)
        .min_by(|a, b| misfit(*a).total_cmp(&misfit(*b)))
        .unwrap_or(1.0)
}

/// One ply's inputs.
struct PlyInput {
    stem: String,
    net: DrapeNet,
    locking_deg: f64,
    locking_source: LockingSource,
    given: Option<LayupRow>,
    tool: Option<PathBuf>,
    tool_note: Option<String>,
    /// The material card the net records, when it can be read.
    card: Option<MaterialCard>,
    /// For a mechanical ply: the kinematic net it started from (`<ply>.kinematic.json`).
    kinematic: Option<DrapeNet>,
}

/// The kinematic net a mechanical ply started from, when the run wrote it beside the ply's net
/// (`drape run` does; a net refined by `drape refine` has none, and the page says so).
fn read_kinematic(dir: &Path, stem: &str, notes: &mut Vec<String>) -> Option<DrapeNet> {
    let path = kinematic_net_path(dir, stem);
    if !path.is_file() {
        notes.push(format!(
            "ply '{stem}': no {} beside its net (`drape run` writes it): the kinematic and mechanical pictures are not shown side by side",
            path.file_name().map_or(String::new(), |n| n.to_string_lossy().into_owned())
        ));
        return None;
    }
    match read_net(&path) {
        Ok(k) => Some(k),
        Err(e) => {
            notes.push(format!("ply '{stem}': the kinematic net cannot be read ({e}): not shown side by side"));
            None
        }
    }
}

/// Everything the page shows, gathered by [`write_report`].
pub(crate) struct Page {
    pub title: String,
    pub layup: Option<LayupTable>,
    pub rows: Vec<LayupRow>,
    pub plies: Vec<PlyReport>,
    pub patterns: Vec<(String, Result<String, String>)>,
    pub notes: Vec<String>,
    pub extra: BTreeMap<String, Vec<(String, String)>>,
    /// The interactive 3D view's HTML.
    pub viewer: String,
    /// The laminate's totals, as (what, value) lines.
    pub laminate: Vec<(String, String)>,
    /// Node statuses other than placed: the status and its count in each ply (table order).
    pub statuses: Vec<(crate::kinematic::NodeStatus, Vec<usize>)>,
    /// Studies found in the folder: (heading, picture file in the report folder, summary).
    pub studies: Vec<study::StudyFigure>,
}

/// Draw every ply of the run folder `dir` into `out` (created if missing) and write
/// `out/index.html`. With `progress`, a progress bar runs on stderr (hidden when stderr is not
/// a terminal). Plies are drawn in parallel; the files do not depend on the thread count.
pub fn write_report(dir: &Path, out: &Path, progress: bool) -> Result<ReportSummary, ReportError> {
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(|source| ReportError::ReadDir { path: dir.to_path_buf(), source })?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .collect();
    entries.sort();
    let net_files: Vec<(String, PathBuf)> = entries
        .iter()
        .filter_map(|p| {
            let name = p.file_name()?.to_str()?;
            let stem = name.strip_suffix(NET_SUFFIX)?;
            (!stem.is_empty() && p.is_file()).then(|| (stem.to_string(), p.clone()))
        })
        .collect();
    if net_files.is_empty() {
        return Err(ReportError::NoNets { path: dir.to_path_buf() });
    }
    let layup = read_layup(dir)?;
    let mut notes = Vec::new();

    // With a layup.json, its plies in its order (nets it does not list belong to another run or
    // command and are left out, with a note); without one, every net by name.
    let listed = |stem: &str| layup.as_ref().is_none_or(|l| l.plies.iter().any(|r| r.name == stem));
    let unlisted: Vec<&str> = net_files.iter().map(|(s, _)| s.as_str()).filter(|s| !listed(s)).collect();
    if !unlisted.is_empty() {
        notes.push(format!(
            "{} also holds {} that {LAYUP_FILE} does not list (another run's or command's): not drawn.",
            dir.display(),
            unlisted.iter().map(|s| format!("{s}{NET_SUFFIX}")).collect::<Vec<_>>().join(", ")
        ));
    }
    let mut nets: BTreeMap<String, DrapeNet> = BTreeMap::new();
    for (stem, path) in net_files.iter().filter(|(s, _)| listed(s)) {
        nets.insert(stem.clone(), read_net(path)?);
    }
    let mut order: Vec<String> = Vec::new();
    if let Some(l) = &layup {
        for r in &l.plies {
            if nets.contains_key(&r.name) {
                if !order.contains(&r.name) {
                    order.push(r.name.clone());
                }
            } else {
                notes.push(format!(
                    "{LAYUP_FILE} lists ply '{}' but {} has no {}{NET_SUFFIX}: not drawn.",
                    r.name,
                    dir.display(),
                    r.name
                ));
            }
        }
    }
    for stem in nets.keys() {
        if !order.contains(stem) {
            order.push(stem.clone());
        }
    }

    let mut inputs = Vec::new();
    for stem in order {
        let net = nets.remove(&stem).expect("ordered from the map's keys");
        let given = layup.as_ref().and_then(|l| l.plies.iter().find(|r| r.name == stem)).cloned();
        let recorded_locking = given.as_ref().and_then(|r| r.locking_angle_deg).filter(|a| a.is_finite() && *a > 0.0);
        // The card the net records, found as the tool is.
        let card =
            net.meta.material.as_deref().and_then(|m| locate_tool(m, dir)).and_then(|p| MaterialCard::load(&p).ok());
        let (locking_deg, locking_source) = match recorded_locking {
            Some(a) => (a, given.as_ref().and_then(|r| r.locking_angle_source).unwrap_or(LockingSource::Ply)),
            None => locking_angle_deg(None, card.as_ref()),
        };
        if locking_source == LockingSource::Default {
            notes.push(format!(
                "ply '{stem}': neither {LAYUP_FILE} nor a material card gives a locking angle: judged against the default {DEFAULT_LOCKING_ANGLE_DEG}°"
            ));
        }
        let recorded = net.meta.tool.clone().or_else(|| layup.as_ref().and_then(|l| l.tool.clone()));
        let (tool, tool_note) = match recorded {
            None => (None, Some("the net records no tool file: drawn without the tool".to_string())),
            Some(t) => match locate_tool(&t, dir) {
                Some(p) => (Some(p), None),
                None => (
                    None,
                    Some(format!(
                        "tool {t} not found (looked relative to the current folder and to {}): drawn without the tool",
                        dir.display()
                    )),
                ),
            },
        };
        let kinematic = if net.method == Method::Mechanical { read_kinematic(dir, &stem, &mut notes) } else { None };
        inputs.push(PlyInput { stem, net, locking_deg, locking_source, given, tool, tool_note, card, kinematic });
    }

    std::fs::create_dir_all(out).map_err(|source| ReportError::CreateDir { path: out.to_path_buf(), source })?;

    // Each distinct tool is read once.
    let mut tools: BTreeMap<PathBuf, Result<RawTool, String>> = BTreeMap::new();
    for p in inputs.iter().filter_map(|i| i.tool.clone()) {
        tools.entry(p.clone()).or_insert_with(|| load_tool(&p));
    }
    // The table rows: layup.json's, else computed from the net (its coverage of the tool).
    let rows: Vec<LayupRow> = inputs
        .iter()
        .map(|i| match &i.given {
            Some(row) => row.clone(),
            None => {
                let tool = i.tool.as_ref().and_then(|p| tools.get(p)).and_then(|t| t.as_ref().ok());
                row_of_net(i, tool)
            }
        })
        .collect();

    let pictures: u64 = inputs
        .iter()
        .map(|i| if i.net.method == Method::Mechanical { 3 } else { 2 } + u64::from(i.kinematic.is_some()))
        .sum();
    let bar = if progress {
        ProgressBar::with_draw_target(Some(pictures + 1), ProgressDrawTarget::stderr())
    } else {
        ProgressBar::hidden()
    };
    if let Ok(style) = ProgressStyle::with_template("{msg:>20} [{bar:40}] {pos}/{len} ({elapsed})") {
        bar.set_style(style.progress_chars("=> "));
    }
    bar.set_message("drawing");

    let limit = shared_limit(&inputs);
    let reports: Vec<Result<PlyReport, ReportError>> = inputs
        .par_iter()
        .map(|input| draw_ply(input, tools.get(input.tool.as_deref().unwrap_or(Path::new(""))), limit, out, &bar))
        .collect();
    let mut plies = Vec::new();
    for r in reports {
        plies.push(r?);
    }
    let mut files: Vec<PathBuf> = plies.iter().flat_map(|p| p.files.iter().cloned()).collect();
    for p in &plies {
        notes.extend(p.notes.iter().map(|n| format!("ply '{}': {n}", p.name)));
    }

    // Flat patterns: every *.svg of the run folder.
    let mut patterns = Vec::new();
    // A report written into DIR itself leaves its own pictures there: those are not patterns.
    let own_picture =
        |name: &str| PICTURES.iter().any(|kind| inputs.iter().any(|i| name == format!("{}-{kind}.svg", i.stem)));
    for p in entries.iter().filter(|p| p.extension().is_some_and(|e| e.eq_ignore_ascii_case("svg")) && p.is_file()) {
        let name = p.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        if own_picture(&name) {
            continue;
        }
        let size = std::fs::metadata(p).map(|m| m.len()).unwrap_or(0);
        let body = if size > PATTERN_INLINE_LIMIT {
            Err(link_to(p, dir, out))
        } else {
            match std::fs::read_to_string(p) {
                Ok(s) => Ok(html::strip_prolog(&s).to_string()),
                Err(e) => {
                    notes.push(format!("flat pattern {}: cannot read it ({e})", p.display()));
                    continue;
                }
            }
        };
        patterns.push((name, body));
    }

    let viewer = viewer_section(&inputs, &tools, limit);
    let mut extra = BTreeMap::new();
    for i in &inputs {
        extra.insert(i.stem.clone(), html::net_facts(&i.net));
    }
    let title = layup
        .as_ref()
        .and_then(|l| l.scene.clone())
        .map(|s| format!("Drape report: {s}"))
        .unwrap_or_else(|| format!("Drape report: {}", dir.display()));
    let unconverged: Vec<&str> = rows.iter().filter(|r| r.converged == Some(false)).map(|r| r.name.as_str()).collect();
    let title = match unconverged.as_slice() {
        [] => title,
        names => format!("NOT CONVERGED ({}): {title}", names.join(", ")),
    };
    let laminate = laminate_totals(&inputs, &rows, layup.as_ref());
    let mut statuses: Vec<(crate::kinematic::NodeStatus, Vec<usize>)> = Vec::new();
    for s in crate::kinematic::NodeStatus::ALL.into_iter().filter(|s| *s != crate::kinematic::NodeStatus::Placed) {
        let counts: Vec<usize> = inputs.iter().map(|i| i.net.status.iter().filter(|x| **x == s).count()).collect();
        if counts.iter().any(|c| *c > 0) {
            statuses.push((s, counts));
        }
    }
    let studies = study::collect_figures(dir, out)?;
    files.extend(studies.iter().map(|f| out.join(&f.picture)));
    let page = Page { title, layup, rows, plies, patterns, notes, extra, viewer, laminate, statuses, studies };
    bar.set_message("writing index.html");
    let index = out.join("index.html");
    let text = html::page(&page);
    write_atomic(&index, |w| w.write_all(text.as_bytes()))?;
    bar.inc(1);
    bar.finish_and_clear();
    files.push(index);
    let Page { plies, notes, .. } = page;
    Ok(ReportSummary { out: out.to_path_buf(), files, plies, notes })
}

/// The laminate's totals: its thickness (nominal, and the range its plies' sheared thickness
/// spans), areas, mass and the nesting's waste; only what the run recorded.
fn laminate_totals(inputs: &[PlyInput], rows: &[LayupRow], layup: Option<&LayupTable>) -> Vec<(String, String)> {
    let mut out = Vec::new();
    let (mut nominal, mut thin, mut thick, mut known) = (0.0, 0.0, 0.0, 0);
    for (i, r) in inputs.iter().zip(rows) {
        let Some(t0) = r.thickness_m.or(i.net.meta.thickness_m).filter(|t| *t > 0.0) else { continue };
        let shears: Vec<f64> = (0..i.net.num_cells())
            .filter_map(|k| i.net.cell_shear(k / (i.net.nv - 1), k % (i.net.nv - 1)))
            .filter(|g| g.is_finite())
            .map(f64::abs)
            .collect();
        let lo = shears.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = shears.iter().copied().fold(0.0, f64::max);
        nominal += t0;
        thin += crate::material::flow::sheared_thickness(t0, if lo.is_finite() { lo } else { 0.0 });
        thick += crate::material::flow::sheared_thickness(t0, hi);
        known += 1;
    }
    if known > 0 {
        out.push((
            "laminate thickness".into(),
            format!(
                "{:.2} mm laid flat ({known} of {} plies give a thickness); sheared cells thicken (t0 / cos γ): from {:.2} mm (every ply at its least shear) to {:.2} mm (every ply at its most)",
                nominal * 1e3,
                inputs.len(),
                thin * 1e3,
                thick * 1e3
            ),
        ));
    }
    let sum = |f: fn(&LayupRow) -> Option<f64>| {
        let v: Vec<f64> = rows.iter().filter_map(f).filter(|x| x.is_finite()).collect();
        (!v.is_empty()).then(|| (v.iter().sum::<f64>(), v.len()))
    };
    if let Some((a, n)) = sum(|r| r.draped_area_m2) {
        out.push(("draped area".into(), format!("{a:.4} m² ({n} plies)")));
    }
    if let Some((a, n)) = sum(|r| r.fabric_area_m2) {
        out.push(("fabric area".into(), format!("{a:.4} m² ({n} plies)")));
    }
    if let Some((m, n)) = sum(|r| r.fabric_mass_kg) {
        out.push(("fabric mass".into(), format!("{:.1} g ({n} plies)", m * 1e3)));
    }
    if let Some(n) = layup.and_then(|l| l.nesting.as_ref()) {
        if let (Some(w), Some(f)) = (n.waste_area_m2, n.waste_fraction) {
            out.push(("waste in nesting".into(), format!("{w:.4} m² ({:.1}% of the roll used)", 100.0 * f)));
        }
    }
    out
}

/// The tool's vertices in metres, at the scale the run read it (recorded, else guessed).
fn scaled_vertices(t: &RawTool, net: &DrapeNet) -> Vec<Point> {
    let s = net.meta.tool_scale.filter(|s| s.is_finite() && *s > 0.0).unwrap_or_else(|| guess_scale(t, net));
    t.vertices.iter().map(|v| Point::from(v.coords * s)).collect()
}

/// The interactive 3D view of every ply on the first ply's tool.
fn viewer_section(inputs: &[PlyInput], tools: &BTreeMap<PathBuf, Result<RawTool, String>>, limit: f64) -> String {
    let tool_of = |i: &PlyInput| i.tool.as_ref().and_then(|p| tools.get(p)).and_then(|t| t.as_ref().ok());
    let scaled: Vec<Option<Vec<Point>>> =
        inputs.iter().map(|i| tool_of(i).map(|t| scaled_vertices(t, &i.net))).collect();
    let plies: Vec<viewer::ViewerPly> = inputs
        .iter()
        .zip(&scaled)
        .map(|(i, v)| viewer::ViewerPly {
            net: &i.net,
            thickness: i.net.meta.thickness_m.or(i.given.as_ref().and_then(|r| r.thickness_m)).filter(|t| *t > 0.0),
            vf: i.card.as_ref().and_then(|c| c.flow.as_ref()).map(|f| f.fibre_volume_fraction),
            tool_vertices: v.as_deref(),
        })
        .collect();
    let tool = inputs
        .iter()
        .zip(&scaled)
        .find_map(|(i, v)| Some((v.as_deref()?, tool_of(i)?.triangles.as_slice())))
        .map(|(v, t)| viewer::ViewTool::new(v, t, viewer::TOOL_TRIANGLE_LIMIT));
    viewer::section(&viewer::data_json(tool.as_ref(), &plies, limit), tool.as_ref())
}

/// The table row of a net that `layup.json` does not list: its shear statistics and, when its
/// tool could be read, its coverage of the tool.
fn row_of_net(input: &PlyInput, tool: Option<&RawTool>) -> LayupRow {
    let (net, locking_deg) = (&input.net, input.locking_deg);
    let st = net.shear_stats(locking_deg.to_radians());
    let coverage = tool.map(|t| {
        let s = net.meta.tool_scale.filter(|s| s.is_finite() && *s > 0.0).unwrap_or_else(|| guess_scale(t, net));
        let triangles: Vec<[Point; 3]> =
            t.triangles.iter().map(|tri| tri.map(|v| Point::from(t.vertices[v as usize].coords * s))).collect();
        surface_coverage(net, &triangles, None)
    });
    LayupRow {
        name: input.stem.clone(),
        material: net.meta.material.clone(),
        angle_deg: net.meta.angle_deg,
        method: Some(method_name(net.method).into()),
        locking_angle_deg: Some(locking_deg),
        locking_angle_source: Some(input.locking_source),
        max_abs_shear_deg: Some(st.max_abs.to_degrees()),
        mean_abs_shear_deg: Some(st.mean_abs.to_degrees()),
        area_over_locking_m2: Some(st.area_over_locking),
        coverage: coverage.map(|c| c.share()),
        coverage_of: coverage.as_ref().map(CoverageOf::of),
        covered_area_m2: coverage.map(|c| c.covered_area),
        draped_area_m2: Some(st.area),
        offset_m: net.meta.stack_offset_max_m,
        converged: net.meta.solver.as_ref().map(|s| s.converged),
        solver_failure: net.meta.solver.as_ref().and_then(|s| s.reason.clone()),
        outcome: net.meta.solver.as_ref().map(|s| s.outcome.clone()),
        contact: net.meta.contact.as_ref().map(|c| c.summary()),
        method_choice: net.meta.method_choice.clone(),
        wrinkles: net.meta.wrinkles.as_ref().map(|w| w.summary.clone()),
        ..LayupRow::default()
    }
}

/// A link from the page in `out` to `file` in `dir`: relative when `out` is inside `dir`.
fn link_to(file: &Path, dir: &Path, out: &Path) -> String {
    let name = file.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    if out.parent() == Some(dir) {
        format!("../{name}")
    } else {
        std::fs::canonicalize(file).unwrap_or(file.to_path_buf()).display().to_string()
    }
}

pub(crate) fn method_name(m: Method) -> &'static str {
    match m {
        Method::Kinematic => "kinematic",
        Method::Mechanical => "mechanical",
    }
}

/// The colour limit (degrees, symmetric) shared by every ply of a report: one scale for the
/// whole layup, so equal colours mean equal shear on every ply.
fn shared_limit(inputs: &[PlyInput]) -> f64 {
    // The kinematic nets drawn beside mechanical plies are on the same scale.
    let max = inputs
        .iter()
        .flat_map(|i| std::iter::once(&i.net).chain(&i.kinematic).map(|n| (n, i.locking_deg)))
        .map(|(n, lock)| n.shear_stats(lock.to_radians()).max_abs.to_degrees())
        .fold(0.0, f64::max);
    let lock = inputs.iter().map(|i| i.locking_deg).fold(0.0, f64::max);
    colour_limit(max, lock)
}

/// What each failure status means, for legends and the page.
pub fn status_meaning(s: crate::kinematic::NodeStatus) -> &'static str {
    use crate::kinematic::NodeStatus as S;
    match s {
        S::Placed => "placed on the tool",
        S::Pending => "not computed (never left in a finished net)",
        S::OffTool => "the fibre ran off the tool's edge",
        S::NoRoot => "no point of the tool at one fibre length from both neighbours",
        S::ShearLimit => "the cell would shear past the limit",
        S::Fold => "the only place would fold the fabric over itself",
        S::SheetJump => "the only place is on another sheet of the tool",
        S::ParentMissing => "a node it depends on was not placed",
        S::OutsideOutline => "outside the ply outline: trimmed",
        S::Detached => "hung on by a corner only: left out of the mechanical result",
    }
}

/// Short legend text of a failure status.
fn status_short(s: crate::kinematic::NodeStatus) -> &'static str {
    use crate::kinematic::NodeStatus as S;
    match s {
        S::Placed | S::Pending => "",
        S::OffTool => "off the tool",
        S::NoRoot => "no root",
        S::ShearLimit => "shear limit",
        S::Fold => "would fold",
        S::SheetJump => "sheet jump",
        S::ParentMissing => "parent missing",
        S::OutsideOutline => "outside outline",
        S::Detached => "detached",
    }
}

/// "1st", "2nd", "3rd", "4th"...
fn ordinal(k: usize) -> String {
    let suffix = match (k % 10, k % 100) {
        (_, 11..=13) => "th",
        (1, _) => "st",
        (2, _) => "nd",
        (3, _) => "rd",
        _ => "th",
    };
    format!("{k}{suffix}")
}

/// Draw one ply's pictures into `out`, on the colour scale `limit` shared by all plies.
fn draw_ply(
    input: &PlyInput,
    tool: Option<&Result<RawTool, String>>,
    limit: f64,
    out: &Path,
    bar: &ProgressBar,
) -> Result<PlyReport, ReportError> {
    let net = &input.net;
    let values = shear_values(net);
    let st = net.shear_stats(input.locking_deg.to_radians());
    let (max_abs_deg, mean_abs_deg) = (st.max_abs.to_degrees(), st.mean_abs.to_degrees());
    let mut notes: Vec<String> = input.tool_note.iter().cloned().collect();
    let mut sagitta = None;
    let scaled: Option<(Vec<Point>, &RawTool)> = match tool {
        Some(Ok(t)) => {
            // The scale the run read the tool with, when the net records it.
            let recorded = net.meta.tool_scale.filter(|s| s.is_finite() && *s > 0.0);
            let s = recorded.unwrap_or_else(|| guess_scale(t, net));
            if net.method == Method::Mechanical {
                sagitta = t.sagitta().map(|v| v * s);
            }
            Some((t.vertices.iter().map(|v| Point::from(v.coords * s)).collect(), t))
        }
        Some(Err(e)) => {
            notes.push(format!("tool not drawn: {e}"));
            None
        }
        None => None,
    };
    let tool_mesh =
        || scaled.as_ref().map(|(v, t)| ToolMesh { vertices: v, triangles: &t.triangles, normals: t.normals() });
    let tool_text = match (&input.tool, &scaled) {
        (Some(p), Some((_, t))) => format!("tool {} ({} triangles)", p.display(), t.triangles.len()),
        _ => "tool not drawn (see the report page)".to_string(),
    };
    if st.cells == 0 {
        notes.push("the net has no complete cell: the map is empty".into());
    }
    let kind = method_name(net.method);
    let lock = input.locking_deg;
    let lock_marks = vec![
        Mark { value: lock, label: format!("+{lock:.0}° locking") },
        Mark { value: -lock, label: format!("−{lock:.0}° locking") },
    ];
    let (paint, folded_count) = shear_paint(net, &values, limit, lock);
    let mut scene = PlyScene::new(net, tool_mesh(), paint, true);
    // A mechanical ply's kinematic start, on the same views, window and colour scale.
    let kinematic = input.kinematic.as_ref().map(|k| {
        let values = shear_values(k);
        let (paint, folded) = shear_paint(k, &values, limit, lock);
        let mut scene = PlyScene::new(k, tool_mesh(), paint, true);
        scene.frame = placed_points(net);
        (k, values, folded, scene)
    });
    if let Some((k, ..)) = &kinematic {
        scene.frame = placed_points(k);
    }
    let (views, seen_share) = if st.cells > 0 { shade::choose_views(&scene) } else { (Vec::new(), 1.0) };
    if seen_share < 1.0 {
        notes.push(format!(
            "the {} views show {:.1}% of the cells; the rest are hidden or seen edge-on from every direction tried (use the interactive view)",
            views.len(),
            100.0 * seen_share
        ));
    }
    let subtitle = format!(
        "{} cells; {} view{} showing {:.1}% of them; colour scale ±{limit:.0}° for the whole layup; {tool_text}",
        st.cells,
        views.len(),
        if views.len() == 1 { "" } else { "s" },
        100.0 * seen_share
    );
    let mut files = Vec::new();
    let name = |suffix: &str| out.join(format!("{}-{suffix}", input.stem));
    let draw_err = |p: &Path| {
        let p = p.to_path_buf();
        move |message: String| ReportError::Draw { path: p.clone(), message }
    };
    let shear_png = name("shear.png");
    let title = format!("Ply {}: shear angle ({kind})", input.stem);
    let shot = ShearShot {
        scene: &scene,
        views: &views,
        title,
        subtitle,
        limit,
        lock,
        over_locking: st.over_locking,
        folded: folded_count,
    };
    let (bytes, fibre_step, stops) = shear_picture(&shot).map_err(draw_err(&shear_png))?;
    write_atomic(&shear_png, |w| w.write_all(&bytes))?;
    files.push(shear_png);
    bar.inc(1);
    let mut kinematic_stats = None;
    if let Some((k, _, folded, kscene)) = &kinematic {
        let kst = k.shear_stats(lock.to_radians());
        let p = name("kinematic.png");
        let shot = ShearShot {
            scene: kscene,
            views: &views,
            title: format!("Ply {}: shear angle (kinematic, where the mechanics started)", input.stem),
            subtitle: format!(
                "{} cells; the mechanical net's views and window; colour scale ±{limit:.0}° for the whole layup; {tool_text}",
                kst.cells
            ),
            limit,
            lock,
            over_locking: kst.over_locking,
            folded: *folded,
        };
        let (bytes, _, _) = shear_picture(&shot).map_err(draw_err(&p))?;
        write_atomic(&p, |w| w.write_all(&bytes))?;
        files.push(p);
        kinematic_stats = Some(KinematicSummary {
            cells: kst.cells,
            max_abs_shear_deg: kst.max_abs.to_degrees(),
            mean_abs_shear_deg: kst.mean_abs.to_degrees(),
            over_locking_cells: kst.over_locking,
        });
        bar.inc(1);
    }

    let hist = render::HistogramPicture {
        title: format!("Ply {}: shear distribution ({kind})", input.stem),
        note: format!(
            "{} cells · mean |γ| {:.1}° · max |γ| {:.1}° · {:.1}% of area over locking",
            st.cells,
            mean_abs_deg,
            max_abs_deg,
            if st.area > 0.0 { 100.0 * st.area_over_locking / st.area } else { 0.0 }
        ),
        values: values.iter().flatten().copied().collect(),
        limit,
        x_label: "shear angle γ (deg)".into(),
        marks: lock_marks,
    };
    write_pair(
        &name("histogram"),
        |r| render::draw_histogram(r, &hist),
        |r| render::draw_histogram(r, &hist),
        &mut files,
    )?;
    bar.inc(1);

    let mut change_noise = None;
    let mut change_summary = None;
    if net.method == Method::Mechanical {
        match change_values(net) {
            Ok(change) => {
                change_summary = summarise_change(net, &change);
                let max = change.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
                let noise = change::change_noise(&change, net.nu, net.nv, net.spacing, sagitta);
                let floor = noise.floor_deg;
                if max <= floor {
                    notes.push(format!(
                        "the change from the kinematic net is within the solver's noise (largest |change| {max:.3}° against a noise floor of {floor:.3}°: {}): no change map drawn",
                        noise_parts(&noise)
                    ));
                } else {
                    // Changes within the noise are drawn as no change; the scale starts above it.
                    let climit = change_limit(max);
                    let paint: Vec<Option<CellPaint>> = change
                        .iter()
                        .map(|v| {
                            v.map(|x| CellPaint {
                                colour: shear_colour(if x.abs() <= floor { 0.0 } else { x }, climit),
                                hatch: false,
                            })
                        })
                        .collect();
                    let scene = PlyScene::new(net, tool_mesh(), paint, false);
                    let pic = ShadedPicture {
                        title: format!("Ply {}: change of shear, mechanical − kinematic", input.stem),
                        subtitle: format!(
                            "largest change {max:.2}°; within ±{floor:.2}° (the solver's noise) drawn as none; {tool_text}"
                        ),
                        limit: climit,
                        from_zero: false,
                        bar_label: "shear change (deg)".into(),
                        marks: vec![
                            Mark { value: floor, label: format!("+{floor:.2}° noise") },
                            Mark { value: -floor, label: format!("−{floor:.2}° noise") },
                        ],
                        legend: vec![
                            LegendItem { swatch: Swatch::Line(shade::EDGE_LINE), text: "ply edge".into() },
                            LegendItem { swatch: Swatch::Fill(shade::TOOL_BASE), text: "tool".into() },
                        ],
                    };
                    let p = name("change.png");
                    let (bytes, _) = render::shaded_png(&scene, &views, &pic).map_err(draw_err(&p))?;
                    write_atomic(&p, |w| w.write_all(&bytes))?;
                    files.push(p);
                    // The distribution of the change, beside the map.
                    let hist = render::HistogramPicture {
                        title: format!("Ply {}: change of shear, mechanical − kinematic", input.stem),
                        note: change_summary.as_ref().map_or(String::new(), |c| {
                            format!(
                                "{} cells · mean |change| {:.2}° · largest {:+.2}°",
                                c.cells, c.mean_abs_deg, c.largest_deg
                            )
                        }),
                        values: change.iter().flatten().copied().collect(),
                        limit: climit,
                        x_label: "shear change (deg)".into(),
                        marks: pic.marks.clone(),
                    };
                    write_pair(
                        &name("change-histogram"),
                        |r| render::draw_histogram(r, &hist),
                        |r| render::draw_histogram(r, &hist),
                        &mut files,
                    )?;
                }
                change_noise = Some(noise);
            }
            Err(why) => notes.push(format!("no change picture: {why}")),
        }
        bar.inc(1);
    }
    if let Some(d) = &net.meta.draw_in {
        write_pair(
            &name("draw-in"),
            |r| draw_in::draw_plan(r, net, d, &input.stem),
            |r| draw_in::draw_plan(r, net, d, &input.stem),
            &mut files,
        )?;
    }
    if let Some(record) = &net.meta.wrinkles {
        let p = name("wrinkles.png");
        let (scene, pic) = wrinkle::wrinkle_picture(net, record, tool_mesh(), &input.stem);
        let (bytes, _) = render::shaded_png(&scene, &views, &pic).map_err(draw_err(&p))?;
        write_atomic(&p, |w| w.write_all(&bytes))?;
        files.push(p);
    }
    if let Some(contact) = &net.meta.contact {
        let p = name("contact.png");
        let (scene, pic) = contact_picture(net, contact, tool_mesh(), &input.stem, &tool_text);
        let (bytes, _) = render::shaded_png(&scene, &views, &pic).map_err(draw_err(&p))?;
        write_atomic(&p, |w| w.write_all(&bytes))?;
        files.push(p);
    }
    Ok(PlyReport {
        name: input.stem.clone(),
        method: net.method,
        cells: st.cells,
        locking_angle_deg: lock,
        max_abs_shear_deg: max_abs_deg,
        mean_abs_shear_deg: mean_abs_deg,
        colour_limit_deg: limit,
        tool_drawn: scaled.is_some(),
        change_noise,
        change: change_summary,
        kinematic: kinematic_stats,
        views: views.into_iter().map(|(_, n)| n).collect(),
        seen_share,
        fibre_step,
        over_locking_cells: st.over_locking,
        folded_cells: folded_count,
        stops: stops.into_iter().collect(),
        files,
        notes,
    })
}

/// Colours of the stick/slip map: cells whose nodes bear on the tool and stick, cells that do
/// not bear on it, cells with a node held by the user (cells that slipped take the colour of
/// how far they slid).
const STICK_COLOUR: [u8; 3] = [69, 117, 180];
const FREE_COLOUR: [u8; 3] = [205, 205, 215];
const HELD_COLOUR: [u8; 3] = [40, 40, 40];

/// The stick/slip map of a refined ply: each cell by its corners (held if one is held, free if
/// none bears on the tool, else by the largest slip of a corner that slipped, or stick).
fn contact_picture<'a>(
    net: &'a DrapeNet,
    contact: &ContactRecord,
    tool: Option<ToolMesh<'a>>,
    stem: &str,
    tool_text: &str,
) -> (PlyScene<'a>, ShadedPicture) {
    let summary = contact.summary();
    let limit_mm = view::nice_ceil((summary.max_slip_m * 1e3).max(1e-3));
    let cv = net.nv - 1;
    let paint: Vec<Option<CellPaint>> = (0..net.num_cells())
        .map(|c| {
            let (i, j) = (c / cv, c % cv);
            net.cell_corners(i, j)?;
            let corners = [(i, j), (i + 1, j), (i, j + 1), (i + 1, j + 1)].map(|(a, b)| net.index(a, b));
            let state = |k: usize| contact.state.get(k).copied().flatten();
            let colour = if corners.iter().any(|&k| state(k) == Some(ContactState::Held)) {
                HELD_COLOUR
            } else if corners.iter().all(|&k| matches!(state(k), Some(ContactState::Free) | None)) {
                FREE_COLOUR
            } else if corners.iter().any(|&k| state(k) == Some(ContactState::Slip)) {
                let slip = corners.iter().filter_map(|&k| contact.slip_m.get(k).copied().flatten()).fold(0.0, f64::max);
                shear_colour(slip * 1e3, limit_mm)
            } else {
                STICK_COLOUR
            };
            Some(CellPaint { colour, hatch: false })
        })
        .collect();
    let scene = PlyScene::new(net, tool, paint, false);
    let mut subtitle = format!("{}; {tool_text}", summary.describe());
    if let Some(mu) = summary.friction_needed {
        let which = if summary.friction_needed_between.is_some() { "ply_friction" } else { "friction" };
        subtitle = format!("SLIDES ({which} {mu:.3} would hold it); {subtitle}");
    }
    let pic = ShadedPicture {
        title: format!("Ply {stem}: stick and slip on the tool"),
        subtitle,
        limit: limit_mm,
        from_zero: true,
        bar_label: "slip over the tool (mm)".into(),
        marks: Vec::new(),
        legend: vec![
            LegendItem { swatch: Swatch::Fill(STICK_COLOUR), text: "sticks".into() },
            LegendItem { swatch: Swatch::Fill(FREE_COLOUR), text: "off the tool".into() },
            LegendItem { swatch: Swatch::Fill(HELD_COLOUR), text: "held (hold)".into() },
            LegendItem { swatch: Swatch::Fill(shade::TOOL_BASE), text: "tool".into() },
        ],
    };
    (scene, pic)
}

/// The placed nodes of a net.
fn placed_points(net: &DrapeNet) -> Vec<Point> {
    net.positions
        .iter()
        .zip(&net.status)
        .filter(|(_, s)| **s == crate::kinematic::NodeStatus::Placed)
        .map(|(p, _)| *p)
        .collect()
}

/// A net painted by signed shear on the colour scale `limit` (degrees), folded cells in their
/// own colour, cells past `lock` hatched: the paint and the count of folded cells.
fn shear_paint(net: &DrapeNet, values: &[Option<f64>], limit: f64, lock: f64) -> (Vec<Option<CellPaint>>, usize) {
    let folded = shade::folded_cells(net);
    let paint = values
        .iter()
        .zip(&folded)
        .map(|(v, f)| {
            v.map(|g| CellPaint {
                colour: if *f { shade::FOLD_FILL } else { shear_colour(g, limit) },
                hatch: g.abs() > lock,
            })
        })
        .collect();
    (paint, folded.iter().filter(|f| **f).count())
}

/// What a shear picture shows.
struct ShearShot<'a> {
    scene: &'a PlyScene<'a>,
    views: &'a [(View, String)],
    title: String,
    subtitle: String,
    /// Colour limit, degrees.
    limit: f64,
    /// Locking angle, degrees.
    lock: f64,
    over_locking: usize,
    folded: usize,
}

/// Draw a shear picture with its legend: the PNG, the fibre step of its first view and where
/// the net stopped (status and placed nodes bordering it). Drawn twice: the first pass learns
/// the fibre step the legend names.
type ShearPng = (Vec<u8>, usize, BTreeMap<crate::kinematic::NodeStatus, usize>);
fn shear_picture(shot: &ShearShot) -> Result<ShearPng, String> {
    let (limit, lock) = (shot.limit, shot.lock);
    let mut legend = vec![
        LegendItem { swatch: Swatch::Line(shade::WARP_LINE), text: "warp fibres".into() },
        LegendItem { swatch: Swatch::Line(shade::WEFT_LINE), text: "weft fibres".into() },
        LegendItem { swatch: Swatch::Seed, text: "seed, arrow: warp direction".into() },
        LegendItem { swatch: Swatch::Line(shade::EDGE_LINE), text: "ply edge".into() },
        LegendItem { swatch: Swatch::Fill(shade::TOOL_BASE), text: "tool".into() },
        LegendItem {
            swatch: Swatch::Hatch(shear_colour(limit, limit)),
            text: format!("past locking: {} cells", shot.over_locking),
        },
        LegendItem {
            swatch: Swatch::Fill(shade::FOLD_FILL),
            text: format!("folded or overlapping (wrinkle): {}", shot.folded),
        },
    ];
    let mut stops: BTreeMap<crate::kinematic::NodeStatus, usize> = BTreeMap::new();
    for (_, s) in &shot.scene.frontier {
        *stops.entry(*s).or_default() += 1;
    }
    for (s, n) in &stops {
        legend.push(LegendItem {
            swatch: Swatch::Dot(shade::status_colour(*s)),
            text: format!("stopped, {}: {n}", status_short(*s)),
        });
    }
    let mut pic = ShadedPicture {
        title: shot.title.clone(),
        subtitle: shot.subtitle.clone(),
        limit,
        from_zero: false,
        bar_label: "shear angle (deg)".into(),
        marks: vec![
            Mark { value: lock, label: format!("+{lock:.0}° locking") },
            Mark { value: -lock, label: format!("−{lock:.0}° locking") },
        ],
        legend,
    };
    let (_, outs) = render::shaded_png(shot.scene, shot.views, &pic)?;
    let fibre_step = outs.first().map_or(0, |o| o.fibre_step);
    let every =
        if fibre_step <= 1 { "every fibre".to_string() } else { format!("every {} fibre", ordinal(fibre_step)) };
    pic.legend[0].text = format!("warp fibres ({every})");
    let (bytes, _) = render::shaded_png(shot.scene, shot.views, &pic)?;
    Ok((bytes, fibre_step, stops))
}

/// The kinematic net a mechanical ply started from, in figures.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KinematicSummary {
    /// Complete cells.
    pub cells: usize,
    /// Largest |shear|, degrees.
    pub max_abs_shear_deg: f64,
    /// Mean |shear|, degrees.
    pub mean_abs_shear_deg: f64,
    /// Cells sheared past the locking angle.
    pub over_locking_cells: usize,
}

/// The change of shear from the kinematic to the mechanical net, in figures.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ChangeSummary {
    /// Cells with a change.
    pub cells: usize,
    /// Mean |change|, degrees.
    pub mean_abs_deg: f64,
    /// The change of largest magnitude (signed), degrees.
    pub largest_deg: f64,
    /// Where it is: the cell (i, j) and its centre (m).
    pub largest_cell: (usize, usize),
    /// The centre of that cell, metres.
    pub largest_at: [f64; 3],
}

/// Sum up a per-cell change (degrees by cell index); `None` when no cell has one.
fn summarise_change(net: &DrapeNet, change: &[Option<f64>]) -> Option<ChangeSummary> {
    let cv = net.nv.saturating_sub(1).max(1);
    let values: Vec<(usize, f64)> = change.iter().enumerate().filter_map(|(k, v)| Some((k, (*v)?))).collect();
    let (k, largest) = values.iter().copied().reduce(|a, b| if b.1.abs() > a.1.abs() { b } else { a })?;
    let (i, j) = (k / cv, k % cv);
    let at = net.cell_frame(i, j).map_or([f64::NAN; 3], |f| [f.centre.x, f.centre.y, f.centre.z]);
    Some(ChangeSummary {
        cells: values.len(),
        mean_abs_deg: values.iter().map(|(_, v)| v.abs()).sum::<f64>() / values.len() as f64,
        largest_deg: largest,
        largest_cell: (i, j),
        largest_at: at,
    })
}

/// What a noise floor is made of, in words.
fn noise_parts(n: &change::ChangeNoise) -> String {
    let facets = n.facets_deg.map_or("tool not read".to_string(), |f| format!("{f:.3}°"));
    format!("the tool's facet sagitta over the spacing {facets}, the cell-to-cell scatter {:.3}°", n.scatter_deg)
}

/// The per-cell shear change (degrees) a mechanical net records in meta
/// "change_from_kinematic"."shear_deg".
fn change_values(net: &DrapeNet) -> Result<Vec<Option<f64>>, String> {
    let arr =
        net.meta.change_from_kinematic.as_ref().map(|c| &c.shear_deg).ok_or(
            "the net has no \"change_from_kinematic\".\"shear_deg\" (written by `drape refine` and `drape run`)",
        )?;
    if arr.len() != net.num_cells() {
        return Err(format!(
            "\"change_from_kinematic\".\"shear_deg\" has {} entries but the net has {} cells",
            arr.len(),
            net.num_cells()
        ));
    }
    Ok(arr.iter().map(|v| v.filter(|x| x.is_finite())).collect())
}

/// Render a picture to `<base>.png` and `<base>.svg`, atomically, and record the paths.
fn write_pair(
    base: &Path,
    png: impl Fn(
        &plotters::drawing::DrawingArea<plotters::prelude::BitMapBackend, plotters::coord::Shift>,
    ) -> render::DrawResult,
    svg: impl Fn(
        &plotters::drawing::DrawingArea<plotters::prelude::SVGBackend, plotters::coord::Shift>,
    ) -> render::DrawResult,
    files: &mut Vec<PathBuf>,
) -> Result<(), ReportError> {
    let with_ext = |ext: &str| {
        let mut name = base.file_name().unwrap_or_default().to_os_string();
        name.push(ext);
        base.with_file_name(name)
    };
    let p = with_ext(".png");
    let bytes = render::to_png(png).map_err(|message| ReportError::Draw { path: p.clone(), message })?;
    write_atomic(&p, |w| w.write_all(&bytes))?;
    files.push(p);
    let p = with_ext(".svg");
    let text = render::to_svg(svg).map_err(|message| ReportError::Draw { path: p.clone(), message })?;
    write_atomic(&p, |w| w.write_all(text.as_bytes()))?;
    files.push(p);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tool_scale_is_the_one_that_fits_the_net() {
        let tool = |k: f64| RawTool {
            vertices: vec![],
            triangles: vec![],
            lo: Point::new(-k, -k, 0.0),
            hi: Point::new(k, k, k),
            sagitta: Default::default(),
            normals: Default::default(),
        };
        let mut net = DrapeNet::new("n", 0.01, 2, 2, (0, 0));
        for (k, p) in [(0.0, 0.0), (0.05, 0.0), (0.0, 0.05), (0.05, 0.05)].iter().enumerate() {
            net.positions[k] = Point::new(p.0, p.1, 0.09);
            net.status[k] = crate::kinematic::NodeStatus::Placed;
        }
        assert_eq!(guess_scale(&tool(0.1), &net), 1.0, "metres");
        assert_eq!(guess_scale(&tool(100.0), &net), 1e-3, "millimetres: both boxes hold the net, the mm one fits");
    }
}
