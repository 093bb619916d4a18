//! Writers of a [`LayupMap`] on its [`FlowMesh`]: the formats resin-flow and FE tools read.
//!
//! | format | files (beside `out`, `STEM` = file stem of `out`) |
//! |---|---|
//! | [`FlowFormat::Vtu`] | `out` (VTK XML unstructured grid, cell data per ply) |
//! | [`FlowFormat::Nastran`] | `out` for one net; for a layup one deck per ply, `STEM_<ply>.<ext>` |
//! | [`FlowFormat::Abaqus`] | `out` (`*NODE`, `*ELEMENT`, one `*ORIENTATION` + `*DISTRIBUTION` per ply) |
//! | [`FlowFormat::OptiStruct`] | `out` (GRID, elements, SET, PLY and DRAPE bulk entries) |
//! | [`FlowFormat::Rtmsim`] | `STEM.bdf` (mesh + sets) and `STEM_input.txt` (parameter file) |
//! | [`FlowFormat::Csv`] | `out` (one row per element and ply) |
//!
//! Everything is checked before the first file is opened (map sizes against the mesh, finite
//! values), so a bad map writes nothing; each file is written with [`write_atomic`].
mod abaqus;
mod csv;
mod nastran;
mod optistruct;
mod rtmsim;
mod vtu;

pub use abaqus::ply_tag as abaqus_ply_tag;
pub use csv::FLOW_CSV_HEADER;
pub use rtmsim::{
    RtmsimRegion, DIRECTION_BIN_DEG, MAX_RTMSIM_SETS, PERM_LOG10_BIN, POROSITY_BIN, RATIO_BIN, THICKNESS_BIN_REL,
};

use super::flowmesh::FlowMesh;
use super::map::{ElementFibres, LayupMap};
use super::ExportError;
use std::path::{Path, PathBuf};

pub(crate) use super::write_atomic;

/// A format of fibre data on a flow mesh.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum FlowFormat {
    Vtu,
    Nastran,
    Abaqus,
    OptiStruct,
    Rtmsim,
    Csv,
}

impl FlowFormat {
    /// All formats.
    pub const ALL: [FlowFormat; 6] = [
        FlowFormat::Vtu,
        FlowFormat::Nastran,
        FlowFormat::Abaqus,
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

/// Write `map` on `mesh` in `format` to `out` (and, for formats that need more than one file,
/// beside it, see the module table). Returns the files written, in a fixed order.
pub fn write_flow(
    mesh: &FlowMesh,
    map: &LayupMap,
    format: FlowFormat,
    out: &Path,
) -> Result<Vec<PathBuf>, ExportError> {
    check(mesh, map, format.name())?;
    match format {
        FlowFormat::Vtu => vtu::write(mesh, map, out).map(|()| vec![out.to_path_buf()]),
        FlowFormat::Nastran => nastran::write(mesh, map, out),
        FlowFormat::Abaqus => abaqus::write(mesh, map, out).map(|()| vec![out.to_path_buf()]),
        FlowFormat::OptiStruct => optistruct::write(mesh, map, out).map(|()| vec![out.to_path_buf()]),
        FlowFormat::Rtmsim => rtmsim::write(mesh, map, out).map(|r| r.files),
        FlowFormat::Csv => csv::write(mesh, map, out).map(|()| vec![out.to_path_buf()]),
    }
}

/// What [`write_rtmsim`] wrote and how it grouped the elements.
#[derive(Debug, Clone)]
pub struct RtmsimReport {
    /// Mesh file, then parameter file.
    pub files: Vec<PathBuf>,
    /// Groups of similar laminate found before RTMsim's limit of 1 + [`MAX_RTMSIM_SETS`] regions.
    pub groups_found: usize,
    /// Regions written: the main preform first, then SET 1..4.
    pub regions: Vec<RtmsimRegion>,
    /// Elements whose group was merged into a written region because of RTMsim's limit.
    pub merged_elements: usize,
    /// Ids of elements no ply covers: left out of the RTMsim mesh.
    pub uncovered: Vec<u64>,
    /// Largest angle (degrees) between an element's own first principal permeability direction
    /// and its region's reference direction projected into the element.
    pub max_direction_error_deg: f64,
}

/// [`write_flow`] for RTMsim, returning the grouping report as well.
pub fn write_rtmsim(mesh: &FlowMesh, map: &LayupMap, out: &Path) -> Result<RtmsimReport, ExportError> {
    check(mesh, map, FlowFormat::Rtmsim.name())?;
    rtmsim::write(mesh, map, out)
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
fn sibling(out: &Path, suffix: &str) -> PathBuf {
    let stem = out.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    out.with_file_name(format!("{stem}{suffix}"))
}

/// A ply name as part of a file name: refused if it could leave the directory.
fn file_tag(format: &'static str, ply: &str) -> Result<String, ExportError> {
    if ply == "." || ply == ".." || ply.chars().any(|c| matches!(c, '/' | '\\' | '\0') || c.is_control()) {
        return Err(ExportError::FlowInvalid {
            format,
            reason: format!("ply name '{ply}' cannot be part of a file name; rename the ply"),
        });
    }
    Ok(ply.to_string())
}

/// Degrees in (-180, 180] of an angle in radians (the map gives (-pi, pi]).
fn deg(rad: f64) -> f64 {
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
fn wrap(a: f64) -> f64 {
    let two_pi = std::f64::consts::TAU;
    let mut r = a.rem_euclid(two_pi);
    if r > std::f64::consts::PI {
        r -= two_pi;
    }
    r
}

/// The text of `x` that fits in `width` characters and reads back closest to `x`: plain
/// decimals (leading zero dropped, ".0123") or the Nastran exponent form without `E`
/// ("1.2345-7", "-2.5+12"), which Nastran, OptiStruct, pyNastran and RTMsim all accept.
/// `{:?}` (exact) is used whenever it fits. Always contains a decimal point, so it is never
/// read as an integer. `None` only for a non-finite `x` (checked earlier).
pub(crate) fn fit_real(x: f64, width: usize) -> Option<String> {
    if !x.is_finite() {
        return None;
    }
    if x == 0.0 {
        return Some("0.0".into());
    }
    let exact = nastran_style(&format!("{x:?}"));
    if exact.len() <= width {
        return Some(exact);
    }
    let mut best: Option<(f64, String)> = None;
    let mut consider = |s: String| {
        if s.len() <= width {
            if let Some(v) = read_nastran_real(&s) {
                let err = (v - x).abs();
                if best.as_ref().is_none_or(|(e, _)| err < *e) {
                    best = Some((err, s));
                }
            }
        }
    };
    for p in (0..=17).rev() {
        let s = format!("{x:.p$}");
        let s = if p == 0 { format!("{s}.") } else { s };
        let s = s.replacen("0.", ".", if s.starts_with("0.") || s.starts_with("-0.") { 1 } else { 0 });
        if s.len() <= width {
            consider(s);
            break;
        }
    }
    for p in (0..=16).rev() {
        let s = nastran_style(&format!("{x:.p$e}"));
        let compact = s.replacen('e', "", 1);
        if compact.len() <= width {
            consider(compact);
            break;
        }
    }
    best.map(|(_, s)| s)
}

/// Rust float text to a Nastran-readable one: a decimal point in the mantissa and a signed
/// exponent ("1e-7" -> "1.e-7", "1e16" -> "1.e+16").
fn nastran_style(s: &str) -> String {
    let (mant, exp) = match s.split_once('e') {
        Some((m, e)) => (m, Some(e)),
        None => (s, None),
    };
    let mant = if mant.contains('.') { mant.to_string() } else { format!("{mant}.") };
    match exp {
        None => mant,
        Some(e) if e.starts_with('-') || e.starts_with('+') => format!("{mant}e{e}"),
        Some(e) => format!("{mant}e+{e}"),
    }
}

/// Parse a Nastran real ("1.5", ".5", "1.5e-3", "1.5E+3", "1.5-3", "-.5+2").
pub(crate) fn read_nastran_real(s: &str) -> Option<f64> {
    let t = s.trim().to_ascii_lowercase().replace('d', "e");
    if let Ok(v) = t.parse::<f64>() {
        return Some(v);
    }
    // Implicit exponent: the last sign that is not the first character.
    let k = t.rfind(['+', '-']).filter(|&k| k > 0 && !t[..k].ends_with('e'))?;
    format!("{}e{}", &t[..k], &t[k..]).parse().ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fit_real_fits_and_reads_back() {
        for &x in &[0.1, -0.1234567891234, 1.0e-7, -3.0e-12, 123456.789, 1.0e20, 0.0, 179.99999999999997, -2.5e-300] {
            for width in [8, 16] {
                let s = fit_real(x, width).unwrap();
                assert!(s.len() <= width && s.contains('.'), "{x} -> {s}");
                let back = read_nastran_real(&s).unwrap();
                let rel = if x == 0.0 { back.abs() } else { ((back - x) / x).abs() };
                let tol = if width == 8 { 1e-3 } else { 1e-9 };
                assert!(rel <= tol, "{x} -> {s} -> {back}");
            }
        }
        assert_eq!(fit_real(0.5, 8).unwrap(), "0.5");
        assert_eq!(fit_real(-1.0e-7, 8).unwrap(), "-1.e-7");
        assert_eq!(read_nastran_real("1.5-3"), Some(1.5e-3));
        assert_eq!(read_nastran_real("-.5+2"), Some(-50.0));
        assert!(fit_real(f64::NAN, 8).is_none());
    }

    #[test]
    fn angles() {
        assert!((deg(std::f64::consts::PI) - 180.0).abs() < 1e-12);
        assert!((wrap(3.0 * std::f64::consts::PI) - std::f64::consts::PI).abs() < 1e-12);
    }
}
