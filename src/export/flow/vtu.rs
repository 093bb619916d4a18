//! VTK XML unstructured grid (ASCII) of the flow mesh with the fibres as cell data.
//!
//! Points are the mesh nodes in mesh order; cells are VTK_TRIANGLE (5) and VTK_QUAD (9) in
//! element order with the element's corner order. Cell data for one net (`map.layup == false`):
//! `element_id` (Int64, the mesh's id), `covered` (Int32 0/1), `warp`, `weft` (Float64 x 3),
//! `shear_deg`, `thickness`, `vf` (Float64) and `permeability` (Float64 x 9, row-major, only if
//! some element has one). For a layup the per-ply fields get the prefix `<ply>_` (`covered`
//! too) and the laminate fields `laminate_thickness`, `mean_vf` and `laminate_permeability`
//! (only if present) follow. Where a ply does not cover an element: covered = 0 and zeros in
//! its other fields (never NaN); likewise zeros where a laminate value is missing.
use super::{write_atomic, ExportError, FlowMesh, LayupMap};
use crate::export::flowmesh::ElementShape;
use std::io::{self, Write};
use std::path::Path;

const VTK_TRIANGLE: u8 = 5;
const VTK_QUAD: u8 = 9;

pub(super) fn write(mesh: &FlowMesh, map: &LayupMap, out: &Path) -> Result<(), ExportError> {
    write_atomic(out, |w| write_to(mesh, map, w))
}

/// Attribute-safe text of a ply name.
fn xml_escape(s: &str) -> String {
    s.replace('&', "&amp;").replace('"', "&quot;").replace('<', "&lt;").replace('>', "&gt;")
}

fn write_to<W: Write>(mesh: &FlowMesh, map: &LayupMap, w: &mut W) -> io::Result<()> {
    let n = mesh.elements.len();
    w.write_all(b"<?xml version=\"1.0\"?>\n")?;
    w.write_all(
        b"<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\">\n<UnstructuredGrid>\n",
    )?;
    writeln!(w, "<Piece NumberOfPoints=\"{}\" NumberOfCells=\"{n}\">", mesh.nodes.len())?;
    w.write_all(b"<CellData>\n")?;
    data_array(w, "Int64", "element_id", 1, mesh.elements.iter().map(|e| e.id))?;
    for ply in &map.plies {
        let p = if map.layup { format!("{}_", xml_escape(&ply.ply)) } else { String::new() };
        let els = &ply.elements;
        data_array(w, "Int32", &format!("{p}covered"), 1, els.iter().map(|f| i32::from(f.is_some())))?;
        let vec3 = |pick: fn(&crate::export::map::ElementFibres) -> [f64; 3]| {
            els.iter().flat_map(move |f| f.as_ref().map_or([0.0; 3], pick))
        };
        data_array(w, "Float64", &format!("{p}warp"), 3, vec3(|f| [f.warp.x, f.warp.y, f.warp.z]))?;
        data_array(w, "Float64", &format!("{p}weft"), 3, vec3(|f| [f.weft.x, f.weft.y, f.weft.z]))?;
        let scalar =
            |pick: fn(&crate::export::map::ElementFibres) -> f64| els.iter().map(move |f| f.as_ref().map_or(0.0, pick));
        data_array(w, "Float64", &format!("{p}shear_deg"), 1, scalar(|f| f.shear.to_degrees()))?;
        data_array(w, "Float64", &format!("{p}thickness"), 1, scalar(|f| f.thickness))?;
        data_array(w, "Float64", &format!("{p}vf"), 1, scalar(|f| f.vf))?;
        if els.iter().flatten().any(|f| f.permeability.is_some()) {
            let k = els.iter().flat_map(|f| row_major(f.as_ref().and_then(|f| f.permeability.as_ref())));
            data_array(w, "Float64", &format!("{p}permeability"), 9, k)?;
        }
    }
    if map.layup {
        data_array(w, "Float64", "laminate_thickness", 1, map.thickness.iter().copied())?;
        data_array(w, "Float64", "mean_vf", 1, map.mean_vf.iter().map(|v| v.unwrap_or(0.0)))?;
        if map.permeability.iter().any(Option::is_some) {
            let k = map.permeability.iter().flat_map(|k| row_major(k.as_ref()));
            data_array(w, "Float64", "laminate_permeability", 9, k)?;
        }
    }
    w.write_all(b"</CellData>\n<Points>\n")?;
    data_array(w, "Float64", "Points", 3, mesh.nodes.iter().flat_map(|p| [p.x, p.y, p.z]))?;
    w.write_all(b"</Points>\n<Cells>\n")?;
    data_array(w, "Int64", "connectivity", 1, mesh.elements.iter().flat_map(|e| e.nodes.iter().copied()))?;
    let offsets = mesh.elements.iter().scan(0usize, |acc, e| {
        *acc += e.nodes.len();
        Some(*acc)
    });
    data_array(w, "Int64", "offsets", 1, offsets)?;
    let types = mesh.elements.iter().map(|e| match e.shape {
        ElementShape::Tria3 => VTK_TRIANGLE,
        ElementShape::Quad4 => VTK_QUAD,
    });
    data_array(w, "UInt8", "types", 1, types)?;
    w.write_all(b"</Cells>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n")
}

/// The 9 entries of `k` row by row, zeros for `None`.
fn row_major(k: Option<&nalgebra::Matrix3<f64>>) -> [f64; 9] {
    let mut out = [0.0; 9];
    if let Some(k) = k {
        for r in 0..3 {
            for c in 0..3 {
                out[3 * r + c] = k[(r, c)];
            }
        }
    }
    out
}

/// One ASCII `<DataArray>` (the net writer's, a whole tuple a group).
fn data_array<W: Write, T: std::fmt::Debug>(
    w: &mut W,
    ty: &str,
    name: &str,
    components: usize,
    values: impl Iterator<Item = T>,
) -> io::Result<()> {
    crate::export::vtu::data_array(w, ty, name, components, components, values)
}
