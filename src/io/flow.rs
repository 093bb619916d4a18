//! Writers of a [`LayupMap`] on its [`FlowMesh`]: the formats resin-flow and FE tools read.
//!
//! | format | files (beside `out`, `STEM` = file stem of `out`) |
//! |---|---|
//! | [`FlowFormat::Vtu`] | `out` (VTK XML unstructured grid, cell data per ply) |
//! | [`FlowFormat::Nastran`] | `out` for one net; for a layup one deck per ply, `STEM_<ply>.<ext>` |
//! | [`FlowFormat::Abaqus`] | `out` (`*NODE`, `*ELEMENT`, one `*ORIENTATION` + `*DISTRIBUTION` per ply) |
//! | [`FlowFormat::Calculix`] | `out` for one net, `STEM_<ply>.<ext>` a ply for a layup (orientation, set and shell section per orientation) |
//! | [`FlowFormat::OptiStruct`] | `out` (GRID, elements, SET, PLY and DRAPE bulk entries) |
//! | [`FlowFormat::Rtmsim`] | `STEM.bdf` (mesh + sets) and `STEM_input.txt` (parameter file) |
//! | [`FlowFormat::Csv`] | `out` (one row per element and ply) |
//!
//! Everything is checked before the first file is opened (map sizes against the mesh, finite
//! values), so a bad map writes nothing; each file is written with [`crate::io::write_atomic`].
use super::rtmsim::RtmsimRegion;
use super::{abaqus, calculix, csv, nastran, optistruct, rtmsim, vtk, ExportError};
use crate::mapping::{ElementFibres, FlowMesh, LayupMap, PlyMap};
use std::path::{Path, PathBuf};

/// A format of fibre data on a flow mesh.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum FlowFormat {
    /// VTK XML unstructured grid (`flow.vtu`).
    Vtu,
    /// Nastran bulk data with THETA (`flow.bdf`, one deck a ply).
    Nastran,
    /// Abaqus orientations and distributions (`flow.inp`).
    Abaqus,
    /// CalculiX shell sections with an orientation each (`flow-ccx.inp`, a deck a ply).
    Calculix,
    /// OptiStruct PLY and DRAPE entries (`flow.fem`).
    OptiStruct,
    /// RTMsim mesh and parameter file (`flow-rtmsim.bdf`).
    Rtmsim,
    /// CSV, one row an element and ply (`flow.csv`).
    Csv,
}

impl FlowFormat {
    /// All formats.
    pub const ALL: [FlowFormat; 7] = [
        FlowFormat::Vtu,
        FlowFormat::Nastran,
        FlowFormat::Abaqus,
        FlowFormat::Calculix,
        FlowFormat::OptiStruct,
        FlowFormat::Rtmsim,
        FlowFormat::Csv,
    ];

    /// Name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            FlowFormat::Vtu => "vtu",
            FlowFormat::Nastran => "nastran",
            FlowFormat::Abaqus => "abaqus",
            FlowFormat::Calculix => "calculix",
            FlowFormat::OptiStruct => "optistruct",
            FlowFormat::Rtmsim => "rtmsim",
            FlowFormat::Csv => "csv",
        }
    }
}

impl FlowFormat {
    /// File a scene writes this format to, in its output directory.
    pub fn scene_file(self) -> &'static str {
        match self {
            FlowFormat::Vtu => "flow.vtu",
            FlowFormat::Nastran => "flow.bdf",
            FlowFormat::Abaqus => "flow.inp",
            FlowFormat::Calculix => "flow-ccx.inp",
            FlowFormat::OptiStruct => "flow.fem",
            FlowFormat::Rtmsim => "flow-rtmsim.bdf",
            FlowFormat::Csv => "flow.csv",
        }
    }
}

impl std::str::FromStr for FlowFormat {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        FlowFormat::ALL.into_iter().find(|f| f.name().eq_ignore_ascii_case(s.trim())).ok_or_else(|| {
            format!("unknown format '{s}': use one of {}", FlowFormat::ALL.map(FlowFormat::name).join(", "))
        })
    }
}

/// Choices of the flow writers beyond the format.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FlowOptions {
    /// The material name CalculiX sections refer to (the user defines the material).
    pub material_name: String,
    /// ASCII or binary VTU (by default by size).
    pub vtu: vtk::VtuEncoding,
}

impl Default for FlowOptions {
    fn default() -> Self {
        FlowOptions { material_name: calculix::DEFAULT_MATERIAL.to_string(), vtu: vtk::VtuEncoding::Auto }
    }
}

/// Write `map` on `mesh` in `format` to `out` (and, for formats that need more than one file,
/// beside it, see the module table). Returns the files written, in a fixed order.
pub fn write_flow(
    mesh: &FlowMesh,
    map: &LayupMap,
    format: FlowFormat,
    out: &Path,
) -> Result<Vec<PathBuf>, ExportError> {
    write_flow_with(mesh, map, format, out, &FlowOptions::default())
}

/// [`write_flow`] with `options`.
pub fn write_flow_with(
    mesh: &FlowMesh,
    map: &LayupMap,
    format: FlowFormat,
    out: &Path,
    options: &FlowOptions,
) -> Result<Vec<PathBuf>, ExportError> {
    check_flow(mesh, map, format, out, options)?;
    match format {
        FlowFormat::Vtu => vtk::write_flow(mesh, map, out, options.vtu).map(|()| vec![out.to_path_buf()]),
        FlowFormat::Nastran => nastran::write_flow(mesh, map, out),
        FlowFormat::Abaqus => abaqus::write_flow(mesh, map, out).map(|()| vec![out.to_path_buf()]),
        FlowFormat::Calculix => calculix::write_flow(mesh, map, out, &options.material_name),
        FlowFormat::OptiStruct => optistruct::write_flow(mesh, map, out).map(|()| vec![out.to_path_buf()]),
        FlowFormat::Rtmsim => rtmsim::write_flow(mesh, map, out).map(|r| r.files),
        FlowFormat::Csv => csv::write_flow(mesh, map, out).map(|()| vec![out.to_path_buf()]),
    }
}

/// Everything [`write_flow_with`] checks before it opens a file, for `format` written to `out`:
/// the map against the mesh (sizes, finite values) and what the format itself needs (ply names
/// that become file names, the CalculiX material name, RTMsim's permeability and field widths,
/// the property and material of every PID of a Nastran or OptiStruct deck).
/// Returns notes on what the files will carry that the flow mesh or the plies did not give. A
/// run checks every format of its export with this before it writes any file, so a map that a
/// format cannot write stops it with nothing written.
pub fn check_flow(
    mesh: &FlowMesh,
    map: &LayupMap,
    format: FlowFormat,
    out: &Path,
    options: &FlowOptions,
) -> Result<Vec<String>, ExportError> {
    check(mesh, map, format.name())?;
    Ok(match format {
        FlowFormat::Vtu | FlowFormat::Abaqus | FlowFormat::Csv => Vec::new(),
        FlowFormat::Nastran => nastran::write::check(mesh, map, out)?,
        FlowFormat::Calculix => calculix::check(map, out, &options.material_name).map(|_| Vec::new())?,
        FlowFormat::OptiStruct => optistruct::check(mesh, map)?,
        FlowFormat::Rtmsim => rtmsim::check(mesh, map, out).map(|()| Vec::new())?,
    })
}

/// What [`write_rtmsim`] wrote and how it grouped the elements.
#[derive(Debug, Clone)]
pub struct RtmsimReport {
    /// Mesh file, then parameter file.
    pub files: Vec<PathBuf>,
    /// Groups of similar laminate found before RTMsim's limit of 1 + [`crate::io::rtmsim::MAX_RTMSIM_SETS`] regions.
    pub groups_found: usize,
    /// Regions written: the main preform first, then SET 1..4.
    pub regions: Vec<RtmsimRegion>,
    /// Elements whose group was merged into a written region because of RTMsim's limit.
    pub merged_elements: usize,
    /// Ids of elements no ply covers: in the RTMsim mesh as SET `uncovered_set` of their own.
    pub uncovered: Vec<u64>,
    /// The SET (1..=4) of the elements no ply covers, `None` when every element is covered.
    pub uncovered_set: Option<usize>,
    /// Largest angle (degrees) between an element's own first principal permeability direction
    /// and its region's reference direction projected into the element.
    pub max_direction_error_deg: f64,
}

/// [`write_flow`] for RTMsim, returning the grouping report as well.
pub fn write_rtmsim(mesh: &FlowMesh, map: &LayupMap, out: &Path) -> Result<RtmsimReport, ExportError> {
    check(mesh, map, FlowFormat::Rtmsim.name())?;
    rtmsim::write_flow(mesh, map, out)
}

/// Sizes, names and finiteness of everything the writers read.
fn check(mesh: &FlowMesh, map: &LayupMap, format: &'static str) -> Result<(), ExportError> {
    let invalid = |reason: String| Err(ExportError::FlowInvalid { format, reason });
    let n = mesh.elements.len();
    if mesh.node_ids.len() != mesh.nodes.len() {
        return invalid(format!("the flow mesh has {} node ids for {} nodes", mesh.node_ids.len(), mesh.nodes.len()));
    }
    for (k, p) in mesh.nodes.iter().enumerate() {
        if !(p.x.is_finite() && p.y.is_finite() && p.z.is_finite()) {
            return invalid(format!("flow mesh node {} has a non-finite coordinate", mesh.node_ids[k]));
        }
    }
    for el in &mesh.elements {
        if el.nodes.len() != el.shape.corners() || el.nodes.iter().any(|&k| k >= mesh.nodes.len()) {
            return invalid(format!("flow mesh element {} has bad corner nodes {:?}", el.id, el.nodes));
        }
    }
    if map.plies.is_empty() {
        return invalid("the map has no plies".into());
    }
    for (what, len) in [
        ("laminate thicknesses", map.thickness.len()),
        ("mean fibre volume fractions", map.mean_vf.len()),
        ("laminate permeabilities", map.permeability.len()),
    ] {
        if len != n {
            return invalid(format!("the map has {len} {what} for {n} flow elements"));
        }
    }
    let mut names = std::collections::BTreeSet::new();
    for ply in &map.plies {
        if ply.ply.is_empty() || ply.ply.chars().any(|c| c.is_control()) {
            return invalid(format!("ply name {:?} is empty or has control characters", ply.ply));
        }
        if !names.insert(ply.ply.as_str()) {
            return invalid(format!("ply name '{}' appears twice", ply.ply));
        }
        if ply.elements.len() != n {
            return invalid(format!("ply '{}' has {} entries for {n} flow elements", ply.ply, ply.elements.len()));
        }
        for (e, f) in ply.elements.iter().enumerate() {
            if let Some(f) = f {
                check_fibres(f, format, &ply.ply, mesh.elements[e].id)?;
            }
        }
    }
    let lam = "laminate";
    for e in 0..n {
        let id = mesh.elements[e].id;
        finite(map.thickness[e], format, lam, id, "laminate thickness")?;
        if let Some(v) = map.mean_vf[e] {
            finite(v, format, lam, id, "mean fibre volume fraction")?;
        }
        if let Some(k) = &map.permeability[e] {
            for v in k.iter() {
                finite(*v, format, lam, id, "laminate permeability")?;
            }
        }
    }
    Ok(())
}

fn finite(v: f64, format: &'static str, ply: &str, element: u64, field: &'static str) -> Result<(), ExportError> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(ExportError::FlowNonFinite { format, ply: ply.to_string(), element, field, value: v })
    }
}

fn check_fibres(f: &ElementFibres, format: &'static str, ply: &str, id: u64) -> Result<(), ExportError> {
    for (field, v) in [("warp", f.warp), ("weft", f.weft), ("normal", f.normal)] {
        for c in v.iter() {
            finite(*c, format, ply, id, field)?;
        }
    }
    for (field, v) in [
        ("shear", f.shear),
        ("theta", f.theta),
        ("angle_change", f.angle_change),
        ("thickness", f.thickness),
        ("nominal_thickness", f.nominal_thickness),
        ("vf", f.vf),
    ] {
        finite(v, format, ply, id, field)?;
    }
    if let Some(k) = &f.permeability {
        for v in k.iter() {
            finite(*v, format, ply, id, "permeability")?;
        }
    }
    Ok(())
}

/// `DIR/STEM<suffix>` beside `out`.
pub(crate) fn sibling(out: &Path, suffix: &str) -> PathBuf {
    let stem = out.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    out.with_file_name(format!("{stem}{suffix}"))
}

/// The file of each ply for the formats that write one deck a ply: `out` for one net, and for a
/// layup `STEM_<ply>.<ext>` beside `out`, in stacking order.
pub(crate) fn ply_files<'a>(
    format: &'static str,
    map: &'a LayupMap,
    out: &Path,
) -> Result<Vec<(PathBuf, &'a PlyMap)>, ExportError> {
    if !map.layup {
        return Ok(vec![(out.to_path_buf(), &map.plies[0])]);
    }
    let ext = out.extension().map(|e| format!(".{}", e.to_string_lossy())).unwrap_or_default();
    map.plies.iter().map(|ply| Ok((sibling(out, &format!("_{}{ext}", file_tag(format, &ply.ply)?)), ply))).collect()
}

/// A ply name as part of a file name: refused if it could leave the directory.
pub(crate) fn file_tag(format: &'static str, ply: &str) -> Result<String, ExportError> {
    if ply == "." || ply == ".." || ply.chars().any(|c| matches!(c, '/' | '\\' | '\0') || c.is_control()) {
        return Err(ExportError::FlowInvalid {
            format,
            reason: format!("ply name '{ply}' cannot be part of a file name; rename the ply"),
        });
    }
    Ok(ply.to_string())
}

/// Degrees in (-180, 180] of an angle in radians (the map gives (-pi, pi]).
pub(crate) fn deg(rad: f64) -> f64 {
    let d = rad.to_degrees();
    if d <= -180.0 {
        d + 360.0
    } else if d > 180.0 {
        d - 360.0
    } else {
        d
    }
}

/// Angle (radians, in (-pi, pi]) wrapped.
pub(crate) fn wrap(a: f64) -> f64 {
    let two_pi = std::f64::consts::TAU;
    let mut r = a.rem_euclid(two_pi);
    if r > std::f64::consts::PI {
        r -= two_pi;
    }
    r
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn angles() {
        assert!((deg(std::f64::consts::PI) - 180.0).abs() < 1e-12);
        assert!((wrap(3.0 * std::f64::consts::PI) - std::f64::consts::PI).abs() < 1e-12);
    }
}
