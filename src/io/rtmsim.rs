//! RTMsim (github.com/obertscheiderfhwn/RTMsim) mesh and parameter files.
//!
//! RTMsim reads (src/pre.jl `read_nastran_mesh`, docs "Input parameters"):
//! * a mesh file ending in `.bdf`, small fixed fields of 8 characters: `GRID` (id in columns
//!   9-16, x y z in 25-32, 33-40, 41-48), `CTRIA3` (id in 9-16, `0` in 17-24, nodes in 25-48),
//!   and up to four cell sets `SET N = id,id,...` (at most 6 ids a line, continuation lines
//!   starting with 8 blanks); sets are numbered by their order in the file. Only triangles are
//!   read, so each quad is split along its shorter diagonal into two CTRIA3: the first keeps the
//!   quad's id, the second gets a new id above every element id of the mesh (comment lines
//!   `$$ SPLIT quad tri1 tri2` record this);
//! * a 14-line parameter file (`readdlm(..., ' ')`, one blank between values): line 6 holds the
//!   main preform `t porosity K alpha refdir1 refdir2 refdir3`, lines 7-10 the same for SET
//!   1-4, line 11 the patch types (2 = preform region, 0 = unused). K is the permeability along
//!   the reference direction projected onto each cell, alpha * K the one across it.
//!
//! drape groups the covered elements by laminate thickness, porosity 1 - mean_vf, the larger
//! in-plane principal value K1 of the laminate permeability, the ratio K2 / K1 and the
//! direction of K1 (bin widths below). RTMsim takes one main preform and at most four sets, so
//! the groups with the largest area become those regions and the elements of any further group
//! go to the region nearest to their group (counted in the report). Region values are
//! area-weighted means of their elements; the reference direction is the mean K1 axis.
//! Elements no ply covers stay in the mesh as a SET of their own, the last one written (so the
//! covered elements then get the main preform and at most three SETs): its parameter line
//! repeats the main preform's values, marked for the user to replace with what fills that part
//! of the cavity (a resin channel, a core, an insert); comment lines `$$ UNCOVERED id ...` list
//! them. Inlets are left to RTMsim's interactive selection (`i_interactive` 2, or 1 when
//! there is no set); the process values (pressures, viscosity, tmax) are RTMsim's documented
//! example values: edit them. Run RTMsim in the output directory (the mesh name is relative).
use super::flow::{sibling, RtmsimReport};
use super::nastran::fit_real;
use super::{write_atomic, ExportError};
use crate::geometry::Vector;
use crate::mapping::{ElementShape, FlowMesh, LayupMap};
use std::io::{self, Write};
use std::path::Path;

/// Thickness bin: relative width (5 %).
pub const THICKNESS_BIN_REL: f64 = 0.05;
/// Porosity bin width.
pub const POROSITY_BIN: f64 = 0.02;
/// Permeability bin width in log10(K1) (0.1 decade, about 26 %).
pub const PERM_LOG10_BIN: f64 = 0.1;
/// Anisotropy ratio K2 / K1 bin width.
pub const RATIO_BIN: f64 = 0.05;
/// Largest angle between the K1 axes of elements in one group, degrees.
pub const DIRECTION_BIN_DEG: f64 = 10.0;
/// RTMsim reads at most this many SETs (besides the main preform).
pub const MAX_RTMSIM_SETS: usize = 4;
/// Largest id that fits an 8-character field.
const MAX_ID: u64 = 99_999_999;
const FORMAT: &str = "rtmsim";

/// One preform region written to RTMsim: the main preform (`set == None`) or a SET.
#[derive(Debug, Clone, PartialEq)]
pub struct RtmsimRegion {
    /// SET number 1..=4, `None` for the main preform (cells in no set).
    pub set: Option<usize>,
    /// Flow elements in the region.
    pub elements: Vec<u64>,
    /// Area, m^2.
    pub area: f64,
    /// Laminate thickness, m.
    pub thickness: f64,
    /// Porosity 1 - Vf.
    pub porosity: f64,
    /// Permeability along the reference direction, m^2.
    pub permeability: f64,
    /// Anisotropy ratio (RTMsim's alpha): permeability across / along.
    pub ratio: f64,
    /// Reference direction (unit, global), projected onto each cell by RTMsim.
    pub refdir: Vector,
}

/// The laminate of one covered element as RTMsim sees it.
#[derive(Debug, Clone, Copy)]
struct Cell {
    e: usize,
    area: f64,
    thickness: f64,
    porosity: f64,
    k1: f64,
    ratio: f64,
    /// K1 axis, unit, in the element plane.
    dir: Vector,
    normal: Vector,
}

impl Cell {
    fn key(&self) -> [i64; 4] {
        [
            (self.thickness.ln() / THICKNESS_BIN_REL.ln_1p()).round() as i64,
            (self.porosity / POROSITY_BIN).round() as i64,
            (self.k1.log10() / PERM_LOG10_BIN).round() as i64,
            (self.ratio / RATIO_BIN).round() as i64,
        ]
    }
}

fn invalid(reason: String) -> ExportError {
    ExportError::FlowInvalid { format: FORMAT, reason }
}

/// In-plane principal values and K1 axis of `k` on the plane with unit normal `n` and first
/// in-plane axis `u`.
fn principal(k: &nalgebra::Matrix3<f64>, n: Vector, u: Vector) -> (f64, f64, Vector) {
    let v = n.cross(&u);
    let (a11, a22, a12) = (u.dot(&(k * u)), v.dot(&(k * v)), 0.5 * (u.dot(&(k * v)) + v.dot(&(k * u))));
    let mean = 0.5 * (a11 + a22);
    let r = (0.25 * (a11 - a22).powi(2) + a12 * a12).sqrt();
    let phi = 0.5 * (2.0 * a12).atan2(a11 - a22);
    (mean + r, mean - r, u * phi.cos() + v * phi.sin())
}

fn cells(mesh: &FlowMesh, map: &LayupMap) -> Result<(Vec<Cell>, Vec<u64>), ExportError> {
    let mut cells = Vec::new();
    let mut uncovered = Vec::new();
    for (e, el) in mesh.elements.iter().enumerate() {
        if !map.plies.iter().any(|p| p.elements[e].is_some()) {
            uncovered.push(el.id);
            continue;
        }
        let (Some(n), Some(u)) = (mesh.normal(e), mesh.first_edge(e)) else {
            return Err(invalid(format!("flow element {} is degenerate (no normal)", el.id)));
        };
        let Some(k) = map.permeability[e] else {
            return Err(invalid(format!(
                "element {} has no laminate permeability: RTMsim needs one per element; ask the mapping for permeability",
                el.id
            )));
        };
        let vf = map.mean_vf[e]
            .ok_or_else(|| invalid(format!("element {} is covered but has no mean fibre volume fraction", el.id)))?;
        let thickness = map.thickness[e];
        let (k1, k2, dir) = principal(&k, n, u);
        if !(thickness > 0.0 && k1 > 0.0 && k2 > 0.0 && (0.0..1.0).contains(&vf)) {
            return Err(invalid(format!(
                "element {}: laminate thickness {thickness}, fibre volume fraction {vf}, in-plane permeabilities {k1}, {k2}: RTMsim needs positive thickness and permeability and 0 <= Vf < 1",
                el.id
            )));
        }
        cells.push(Cell { e, area: mesh.area(e), thickness, porosity: 1.0 - vf, k1, ratio: k2 / k1, dir, normal: n });
    }
    Ok((cells, uncovered))
}

/// Group statistics (area-weighted means; axis signs aligned with the first member).
fn region(members: &[Cell], mesh: &FlowMesh) -> RtmsimRegion {
    let seed = members[0].dir;
    let mut r = RtmsimRegion {
        set: None,
        elements: members.iter().map(|c| mesh.elements[c.e].id).collect(),
        area: 0.0,
        thickness: 0.0,
        porosity: 0.0,
        permeability: 0.0,
        ratio: 0.0,
        refdir: Vector::zeros(),
    };
    // Degenerate (zero-area) members still count: weight by area plus a tiny floor.
    let total: f64 = members.iter().map(|c| c.area).sum();
    for c in members {
        let w = if total > 0.0 { c.area / total } else { 1.0 / members.len() as f64 };
        r.area += c.area;
        r.thickness += w * c.thickness;
        r.porosity += w * c.porosity;
        r.permeability += w * c.k1;
        r.ratio += w * c.ratio;
        r.refdir += w * c.dir * c.dir.dot(&seed).signum();
    }
    let len = r.refdir.norm();
    r.refdir = if len > 0.0 { r.refdir / len } else { seed };
    r
}

/// Distance between a cell-like group mean and a region, in bins.
fn distance(a: &RtmsimRegion, b: &RtmsimRegion) -> f64 {
    (a.thickness / b.thickness).ln().abs() / THICKNESS_BIN_REL.ln_1p()
        + (a.porosity - b.porosity).abs() / POROSITY_BIN
        + (a.permeability / b.permeability).log10().abs() / PERM_LOG10_BIN
        + (a.ratio - b.ratio).abs() / RATIO_BIN
        + a.refdir.dot(&b.refdir).abs().min(1.0).acos().to_degrees() / DIRECTION_BIN_DEG
}

/// Write the RTMsim mesh and parameter file beside `out` (see the module documentation).
pub(crate) fn write_flow(mesh: &FlowMesh, map: &LayupMap, out: &Path) -> Result<RtmsimReport, ExportError> {
    let (report, region_of) = plan(mesh, map, out)?;
    let mesh_name = report.files[0].file_name().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    write_atomic(&report.files[0], |w| {
        write_mesh(mesh, &report.regions, &region_of, &report.uncovered, report.uncovered_set, w)
    })?;
    write_atomic(&report.files[1], |w| write_input(&mesh_name, &report.regions, report.uncovered_set, w))?;
    Ok(report)
}

/// Everything [`write_flow`] checks and computes before it writes: the regions and each
/// element's region (`usize::MAX` where no ply covers it). An error here means nothing is written.
pub(crate) fn check(mesh: &FlowMesh, map: &LayupMap, out: &Path) -> Result<(), ExportError> {
    plan(mesh, map, out).map(drop)
}

/// The report [`write_flow`] returns and each element's region, or why the map cannot be written.
fn plan(mesh: &FlowMesh, map: &LayupMap, out: &Path) -> Result<(RtmsimReport, Vec<usize>), ExportError> {
    let mesh_path = sibling(out, ".bdf");
    let input_path = sibling(out, "_input.txt");
    let (cells, uncovered) = cells(mesh, map)?;
    if cells.is_empty() {
        return Err(invalid("no ply covers any element of the flow mesh: nothing to simulate".into()));
    }
    if let Some(el) = mesh.elements.iter().find(|e| e.id > MAX_ID) {
        return Err(invalid(format!(
            "element id {} does not fit RTMsim's 8-character fields; renumber the mesh",
            el.id
        )));
    }
    if let Some(id) = mesh.node_ids.iter().find(|&&id| id > MAX_ID) {
        return Err(invalid(format!("node id {id} does not fit RTMsim's 8-character fields; renumber the mesh")));
    }

    // Group: same bins and K1 axes within DIRECTION_BIN_DEG of the group's first member.
    let cos_tol = DIRECTION_BIN_DEG.to_radians().cos();
    let mut groups: Vec<([i64; 4], Vector, Vec<Cell>)> = Vec::new();
    for c in &cells {
        let key = c.key();
        match groups.iter_mut().find(|(k, seed, _)| *k == key && c.dir.dot(seed).abs() >= cos_tol) {
            Some(g) => g.2.push(*c),
            None => groups.push((key, c.dir, vec![*c])),
        }
    }
    let groups_found = groups.len();
    let mut stats: Vec<(RtmsimRegion, Vec<Cell>)> = groups.into_iter().map(|(_, _, m)| (region(&m, mesh), m)).collect();
    // Largest area first (stable: ties keep mesh order).
    stats.sort_by(|a, b| b.0.area.total_cmp(&a.0.area));
    // One SET is kept for the elements no ply covers, if there are any.
    let keep = stats.len().min(MAX_RTMSIM_SETS + usize::from(uncovered.is_empty()));
    let dropped = stats.split_off(keep);
    let mut merged_elements = 0;
    for (g, members) in dropped {
        let best = (0..stats.len())
            .min_by(|&a, &b| distance(&g, &stats[a].0).total_cmp(&distance(&g, &stats[b].0)))
            .expect("at least one region kept");
        merged_elements += members.len();
        stats[best].1.extend(members);
    }
    let mut regions = Vec::with_capacity(stats.len());
    let mut region_of = vec![usize::MAX; mesh.elements.len()];
    for (r, (_, members)) in stats.iter_mut().enumerate() {
        members.sort_by_key(|c| c.e);
        for c in members.iter() {
            region_of[c.e] = r;
        }
        let mut reg = region(members, mesh);
        reg.set = (r > 0).then_some(r);
        regions.push(reg);
    }
    let mut max_direction_error_deg: f64 = 0.0;
    for c in &cells {
        let rd = regions[region_of[c.e]].refdir;
        let p = rd - c.normal * c.normal.dot(&rd);
        let err = if p.norm() > 0.0 { (p.normalize().dot(&c.dir)).abs().min(1.0).acos().to_degrees() } else { 90.0 };
        max_direction_error_deg = max_direction_error_deg.max(err);
    }
    for reg in &regions {
        for v in [reg.thickness, reg.porosity, reg.permeability, reg.ratio, reg.refdir.x, reg.refdir.y, reg.refdir.z] {
            if !v.is_finite() {
                return Err(invalid(format!("a region value is {v} (region of element {})", reg.elements[0])));
            }
        }
    }

    let mesh_name = mesh_path.file_name().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    if mesh_name.contains(char::is_whitespace) {
        return Err(invalid(format!("RTMsim reads the mesh file name up to the first blank: '{mesh_name}' has one; choose an output name without blanks")));
    }
    // The elements no ply covers: a SET after the covered regions' SETs.
    let uncovered_set = (!uncovered.is_empty()).then_some(regions.len());
    let report = RtmsimReport {
        files: vec![mesh_path, input_path],
        groups_found,
        regions,
        merged_elements,
        uncovered,
        uncovered_set,
        max_direction_error_deg,
    };
    Ok((report, region_of))
}

fn short(x: f64) -> String {
    fit_real(x, 8).expect("coordinates are checked finite")
}

/// The RTMsim mesh: every element of the flow mesh, covered ones in their region's SET (none for
/// the main preform), the uncovered ones (`region_of` is `usize::MAX`) in `uncovered_set`.
fn write_mesh<W: Write>(
    mesh: &FlowMesh,
    regions: &[RtmsimRegion],
    region_of: &[usize],
    uncovered: &[u64],
    uncovered_set: Option<usize>,
    w: &mut W,
) -> io::Result<()> {
    writeln!(w, "$$ drape: RTMsim mesh of flow mesh {}", mesh.path.display())?;
    writeln!(
        w,
        "$$ {} region(s): main preform + {} SET(s); quads split in two CTRIA3",
        regions.len(),
        regions.len() - 1
    )?;
    if let Some(set) = uncovered_set {
        writeln!(w, "$$ SET {set}: the {} element(s) no ply covers (give them their own values)", uncovered.len())?;
    }
    for id in uncovered.chunks(10) {
        let s: Vec<String> = id.iter().map(u64::to_string).collect();
        writeln!(w, "$$ UNCOVERED {}", s.join(" "))?;
    }
    // Triangles: (id, SET (0: the main preform), [node index; 3]).
    let mut next_id = mesh.elements.iter().map(|e| e.id).max().unwrap_or(0);
    let mut tris: Vec<(u64, usize, [usize; 3])> = Vec::new();
    let mut splits = Vec::new();
    for (e, el) in mesh.elements.iter().enumerate() {
        let set = match region_of[e] {
            usize::MAX => uncovered_set.expect("an uncovered element has its SET"),
            r => r,
        };
        let g = &el.nodes;
        match el.shape {
            ElementShape::Tria3 => tris.push((el.id, set, [g[0], g[1], g[2]])),
            ElementShape::Quad4 => {
                let d13 = (mesh.nodes[g[2]] - mesh.nodes[g[0]]).norm();
                let d24 = (mesh.nodes[g[3]] - mesh.nodes[g[1]]).norm();
                let (a, b) = if d13 <= d24 {
                    ([g[0], g[1], g[2]], [g[0], g[2], g[3]])
                } else {
                    ([g[0], g[1], g[3]], [g[1], g[2], g[3]])
                };
                next_id += 1;
                tris.push((el.id, set, a));
                tris.push((next_id, set, b));
                splits.push((el.id, next_id));
            }
        }
    }
    for (q, t) in &splits {
        writeln!(w, "$$ SPLIT {q} {q} {t}")?;
    }
    writeln!(w, "CEND")?;
    for r in 1..regions.len() + usize::from(uncovered_set.is_some()) {
        let ids: Vec<String> = tris.iter().filter(|t| t.1 == r).map(|t| t.0.to_string()).collect();
        let lines: Vec<String> = ids.chunks(6).map(|c| c.join(",")).collect();
        for (k, line) in lines.iter().enumerate() {
            let head = if k == 0 { format!("SET {r} = ") } else { " ".repeat(8) };
            let tail = if k + 1 < lines.len() { "," } else { "" };
            writeln!(w, "{head}{line}{tail}")?;
        }
    }
    writeln!(w, "BEGIN BULK")?;
    let mut used = vec![false; mesh.nodes.len()];
    for t in &tris {
        for &k in &t.2 {
            used[k] = true;
        }
    }
    for (k, p) in mesh.nodes.iter().enumerate().filter(|(k, _)| used[*k]) {
        writeln!(w, "GRID    {:>8}{:8}{:>8}{:>8}{:>8}", mesh.node_ids[k], "", short(p.x), short(p.y), short(p.z))?;
    }
    for (id, _, g) in &tris {
        let [a, b, c] = g.map(|k| mesh.node_ids[k]);
        writeln!(w, "CTRIA3  {id:>8}{:>8}{a:>8}{b:>8}{c:>8}", 0)?;
    }
    writeln!(w, "ENDDATA")
}

fn write_input<W: Write>(
    mesh_name: &str,
    regions: &[RtmsimRegion],
    uncovered_set: Option<usize>,
    w: &mut W,
) -> io::Result<()> {
    let line = |r: &RtmsimRegion| {
        format!(
            "{:?} {:?} {:?} {:?} {:?} {:?} {:?}",
            r.thickness, r.porosity, r.permeability, r.ratio, r.refdir.x, r.refdir.y, r.refdir.z
        )
    };
    let main = line(&regions[0]);
    writeln!(w, "1    #i_model")?;
    writeln!(w, "{mesh_name}    #meshfilename")?;
    writeln!(w, "200    #tmax (RTMsim example value: edit)")?;
    writeln!(w, "1.01325e5 1.225 1.4 0.06    #p_ref rho_ref gamma mu_resin_val (RTMsim example values: edit)")?;
    writeln!(w, "1.35e5 1.0e5    #p_a_val p_init_val (RTMsim example values: edit)")?;
    writeln!(w, "{main}    #t_val porosity_val K_val alpha_val refdir1_val refdir2_val refdir3_val (main preform)")?;
    for s in 1..=MAX_RTMSIM_SETS {
        match regions.get(s) {
            Some(r) => writeln!(w, "{}    #t{s}_val porosity{s}_val K{s}_val alpha{s}_val refdir1{s}_val refdir2{s}_val refdir3{s}_val (SET {s})", line(r))?,
            None if uncovered_set == Some(s) => writeln!(w, "{main}    #t{s}_val porosity{s}_val K{s}_val alpha{s}_val refdir1{s}_val refdir2{s}_val refdir3{s}_val (SET {s}: elements no ply covers; the main preform's values: EDIT)")?,
            None => writeln!(w, "{main}    #t{s}_val porosity{s}_val K{s}_val alpha{s}_val refdir1{s}_val refdir2{s}_val refdir3{s}_val (no SET {s}: unused)")?,
        }
    }
    let sets = regions.len() - 1 + usize::from(uncovered_set.is_some());
    let types: Vec<&str> = (1..=MAX_RTMSIM_SETS).map(|s| if s <= sets { "2" } else { "0" }).collect();
    writeln!(w, "{}    #patchtype1val patchtype2val patchtype3val patchtype4val", types.join(" "))?;
    writeln!(w, "0 results.jld2    #i_restart restartfilename")?;
    let interactive = if sets > 0 { 2 } else { 1 };
    writeln!(w, "{interactive} 0.01    #i_interactive r_p (select the inlet ports in RTMsim)")?;
    writeln!(w, "16    #n_pics")
}
