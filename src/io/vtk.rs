//! VTK XML files (UnstructuredGrid, ASCII, version 0.1, little endian) for ParaView and meshio:
//! a draped net and the flow mesh with the fibres mapped onto it.
//!
//! `<ply>.vtu`: VTK XML UnstructuredGrid (ASCII, version 0.1, little endian) for ParaView and
//! meshio. Points are the placed nodes only, renumbered compactly in node order; cells are
//! VTK_QUAD (type 9), one for every cell whose four corners are placed, with connectivity
//! (i, j), (i+1, j), (i+1, j+1), (i, j+1) (counter-clockwise seen from the normal warp x weft).
//!
//! CellData: `shear_deg` (Float64), `warp`, `weft`, `normal` (Float64 x 3, unit), `cell_i`,
//! `cell_j` (Int32); for a net that records its wrinkles (`meta.wrinkles`, a ply of `drape
//! run`) also `waviness_m` (Float64, m), `wrinkled` (Int32: 1 where the waviness exceeds the
//! ply's threshold and the ply undulates, `WrinkleRecord::wrinkled`), `tool_gap_m` (Float64, m) and, for a ply with a material card,
//! `bending_energy_density_j_m2` (Float64, J/m^2). PointData: `node_i`, `node_j` (Int32); for a
//! refined net also how each node meets the tool (`meta.contact`): `contact_state` (Int32: 0
//! free, 1 stick, 2 slip, 3 held; [`ContactState::code`]), `slip` (Float64, m, over all load
//! steps) and `contact_pressure` (Float64, Pa). Floats are written with `{:?}`, the shortest
//! text that parses back to the same f64.
//!
//! The flow mesh with the fibres of a mapped layup as cell data (`drape export --format vtu`,
//! `flow.vtu`): points are the mesh nodes in mesh order; cells are VTK_TRIANGLE (5) and VTK_QUAD (9) in
//! element order with the element's corner order. Cell data for one net (`map.layup == false`):
//! `element_id` (Int64, the mesh's id), `covered` (Int32 0/1), `warp`, `weft` (Float64 x 3),
//! `shear_deg`, `thickness`, `vf` (Float64) and `permeability` (Float64 x 9, row-major, only if
//! some element has one). For a layup the per-ply fields get the prefix `<ply>_` (`covered`
//! too) and the laminate fields `laminate_thickness`, `mean_vf` and `laminate_permeability`
//! (only if present) follow. Where a ply does not cover an element: covered = 0 and NaN in its
//! other fields (not zeros, which a flow solver would read as an impermeable, zero-thickness
//! wall); likewise NaN where no ply covers an element in the laminate fields. VTK reads `NaN`.
//!
//! Large files are binary ([`VtuEncoding`]): the same arrays, appended raw after the XML
//! (`<AppendedData encoding="raw">`, `format="appended"` with each array's byte offset), each
//! compressed by zlib in blocks of [`BLOCK_BYTES`] (`compressor="vtkZLibDataCompressor"`,
//! `header_type="UInt64"`, so `version="1.0"`): an array is the header `[blocks, block size,
//! size of the last block if partial (else 0), compressed size of each block]` (UInt64, little
//! endian) followed by the compressed blocks. Floats are their exact IEEE bits (NaN stays NaN).
use super::check::{cells, check_net};
use super::xml::xml_escape;
use super::{write_atomic, ExportError};
use crate::geometry::Vector;
use crate::kinematic::provenance::ContactState;
use crate::kinematic::{DrapeNet, NodeStatus};
use crate::mapping::{ElementShape, FlowMesh, LayupMap};
use std::io::{self, Write};
use std::path::Path;
/// VTK cell type of a linear quadrilateral.
const VTK_QUAD: u8 = 9;
/// Values per line in the data arrays (keeps lines short; any layout is valid VTK).
const PER_LINE: usize = 8;
/// Uncompressed bytes per zlib block of a binary array (VTK's own default).
pub const BLOCK_BYTES: usize = 1 << 15;
/// [`VtuEncoding::Auto`] writes binary from this many cells on (a net of 224 x 224 nodes, a flow
/// mesh of 50k elements): about 11 MB of ASCII (a 301 x 301 net is 20 MB).
pub const BINARY_FROM_CELLS: usize = 50_000;

/// How a VTU's data arrays are stored.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum VtuEncoding {
    /// ASCII below [`BINARY_FROM_CELLS`] cells, binary from there on.
    #[default]
    Auto,
    /// Text in the XML: the shortest decimal of each value that reads back to it.
    Ascii,
    /// zlib-compressed raw binary appended after the XML.
    Binary,
}

impl VtuEncoding {
    /// Ascii or Binary for a file of `cells` cells.
    pub fn resolve(self, cells: usize) -> VtuEncoding {
        match self {
            VtuEncoding::Auto if cells >= BINARY_FROM_CELLS => VtuEncoding::Binary,
            VtuEncoding::Auto => VtuEncoding::Ascii,
            e => e,
        }
    }
}

impl std::str::FromStr for VtuEncoding {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "auto" => Ok(VtuEncoding::Auto),
            "ascii" => Ok(VtuEncoding::Ascii),
            "binary" => Ok(VtuEncoding::Binary),
            _ => Err(format!("unknown VTU encoding '{s}': use auto, ascii or binary")),
        }
    }
}

/// A value of a VTK data array as its little-endian bytes in the array's type.
pub(crate) trait VtkValue: std::fmt::Debug {
    /// Append the value as a `ty` (`Float64`, `Int64`, `Int32` or `UInt8`).
    fn put(&self, ty: &str, out: &mut Vec<u8>);
}

macro_rules! vtk_value {
    ($($t:ty),*) => {$(
        impl VtkValue for $t {
            fn put(&self, ty: &str, out: &mut Vec<u8>) {
                match ty {
                    "Float64" => out.extend_from_slice(&(*self as f64).to_le_bytes()),
                    "Int64" => out.extend_from_slice(&(*self as i64).to_le_bytes()),
                    "Int32" => out.extend_from_slice(&(*self as i32).to_le_bytes()),
                    "UInt8" => out.push(*self as u8),
                    _ => unreachable!("VTK type {ty} is not written"),
                }
            }
        }
    )*};
}
vtk_value!(f64, usize, u64, u32, i32, u8);

/// The data arrays of one file as they are written: inline ASCII, or appended binary (the
/// compressed bytes collected here and written after the XML by [`Arrays::finish`]).
pub(crate) struct Arrays {
    encoding: VtuEncoding,
    appended: Vec<u8>,
}

impl Arrays {
    /// Arrays in `encoding` (Ascii or Binary, resolved), after writing the `<VTKFile>` line.
    pub(crate) fn start<W: Write>(w: &mut W, encoding: VtuEncoding) -> io::Result<Arrays> {
        w.write_all(b"<?xml version=\"1.0\"?>\n")?;
        match encoding {
            VtuEncoding::Binary => w.write_all(
                b"<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\" compressor=\"vtkZLibDataCompressor\">\n",
            )?,
            _ => w.write_all(b"<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\">\n")?,
        }
        Ok(Arrays { encoding, appended: Vec::new() })
    }

    /// One `<DataArray>` of `components` per tuple; ASCII puts a whole number of `group`s a line.
    pub(crate) fn array<W: Write, T: VtkValue>(
        &mut self,
        w: &mut W,
        ty: &str,
        name: &str,
        components: usize,
        group: usize,
        values: impl Iterator<Item = T>,
    ) -> io::Result<()> {
        if self.encoding != VtuEncoding::Binary {
            return data_array(w, ty, name, components, group, values);
        }
        write!(w, "<DataArray type=\"{ty}\" Name=\"{name}\"")?;
        if components > 1 {
            write!(w, " NumberOfComponents=\"{components}\"")?;
        }
        writeln!(w, " format=\"appended\" offset=\"{}\"/>", self.appended.len())?;
        let mut raw = Vec::new();
        for v in values {
            v.put(ty, &mut raw);
        }
        compress_into(&raw, &mut self.appended)
    }

    /// Close the file: the appended data (binary) and `</VTKFile>`.
    pub(crate) fn finish<W: Write>(self, w: &mut W) -> io::Result<()> {
        if self.encoding == VtuEncoding::Binary {
            w.write_all(b"<AppendedData encoding=\"raw\">\n_")?;
            w.write_all(&self.appended)?;
            w.write_all(b"\n</AppendedData>\n")?;
        }
        w.write_all(b"</VTKFile>\n")
    }
}

/// `raw` as a vtkZLibDataCompressor array with a UInt64 header, appended to `out`.
fn compress_into(raw: &[u8], out: &mut Vec<u8>) -> io::Result<()> {
    use flate2::{write::ZlibEncoder, Compression};
    let blocks: Vec<Vec<u8>> = raw
        .chunks(BLOCK_BYTES)
        .map(|b| {
            let mut z = ZlibEncoder::new(Vec::new(), Compression::default());
            z.write_all(b)?;
            z.finish()
        })
        .collect::<io::Result<_>>()?;
    let last = raw.len() % BLOCK_BYTES;
    let header = [blocks.len(), BLOCK_BYTES, last].into_iter().chain(blocks.iter().map(Vec::len));
    for h in header {
        out.extend_from_slice(&(h as u64).to_le_bytes());
    }
    for b in &blocks {
        out.extend_from_slice(b);
    }
    Ok(())
}

/// Write `net` to `path` (normally `DIR/<ply>.vtu`) atomically, ASCII or binary by its size
/// ([`VtuEncoding::Auto`]). Fails, writing nothing, if a placed node, a cell shear or a cell
/// frame is not finite or a complete cell is degenerate.
pub fn write_vtu(net: &DrapeNet, path: &Path) -> Result<(), ExportError> {
    write_vtu_as(net, path, VtuEncoding::Auto)
}

/// [`write_vtu`] in a given encoding.
pub fn write_vtu_as(net: &DrapeNet, path: &Path, encoding: VtuEncoding) -> Result<(), ExportError> {
    check_net(net, true)?;
    let n_cells = cells(net).filter(|&(i, j)| net.cell_corners(i, j).is_some()).count();
    write_atomic(path, |w| write_vtu_to(net, w, encoding.resolve(n_cells)))
}

fn write_vtu_to<W: Write>(net: &DrapeNet, w: &mut W, encoding: VtuEncoding) -> io::Result<()> {
    // Compact point numbers: point_id[k] for placed node k.
    let mut point_id = vec![u32::MAX; net.status.len()];
    let mut n_points = 0u32;
    for (k, s) in net.status.iter().enumerate() {
        if *s == NodeStatus::Placed {
            point_id[k] = n_points;
            n_points += 1;
        }
    }
    let complete = || cells(net).filter(|&(i, j)| net.cell_corners(i, j).is_some());
    let n_cells = complete().count();
    let placed = || (0..net.status.len()).filter(|&k| net.status[k] == NodeStatus::Placed);

    let mut arrays = Arrays::start(w, encoding)?;
    w.write_all(b"<UnstructuredGrid>\n")?;
    writeln!(w, "<Piece NumberOfPoints=\"{n_points}\" NumberOfCells=\"{n_cells}\">")?;

    w.write_all(b"<PointData Scalars=\"node_i\">\n")?;
    arrays.array(w, "Int32", "node_i", 1, 1, placed().map(|k| k / net.nv))?;
    arrays.array(w, "Int32", "node_j", 1, 1, placed().map(|k| k % net.nv))?;
    if let Some(c) = &net.meta.contact {
        // Every placed node of a refined net is in its mechanical body; the net check made sure
        // the lists fit the grid.
        let state = |k: usize| c.state[k].map_or(ContactState::Free.code(), ContactState::code);
        arrays.array(w, "Int32", "contact_state", 1, 1, placed().map(state))?;
        arrays.array(w, "Float64", "slip", 1, 1, placed().map(|k| c.slip_m[k].unwrap_or(0.0)))?;
        arrays.array(w, "Float64", "contact_pressure", 1, 1, placed().map(|k| c.pressure_pa[k].unwrap_or(0.0)))?;
    }
    w.write_all(b"</PointData>\n")?;

    w.write_all(b"<CellData Scalars=\"shear_deg\" Vectors=\"warp\">\n")?;
    let shear = complete().map(|(i, j)| net.cell_shear(i, j).expect("complete cell").to_degrees());
    arrays.array(w, "Float64", "shear_deg", 1, 1, shear)?;
    type Pick = fn(&crate::kinematic::net::CellFrame) -> Vector;
    let picks: [(&str, Pick); 3] = [("warp", |f| f.warp), ("weft", |f| f.weft), ("normal", |f| f.normal)];
    for (name, pick) in picks {
        let values = complete().flat_map(|(i, j)| {
            let v = pick(&net.cell_frame(i, j).expect("checked: complete cells have a frame"));
            [v.x, v.y, v.z]
        });
        arrays.array(w, "Float64", name, 3, 3, values)?;
    }
    arrays.array(w, "Int32", "cell_i", 1, 1, complete().map(|(i, _)| i))?;
    arrays.array(w, "Int32", "cell_j", 1, 1, complete().map(|(_, j)| j))?;
    if let Some(wr) = &net.meta.wrinkles {
        // The net check made sure every complete cell has each measure the record holds.
        let cv = net.nv - 1;
        let at = |list: &[Option<f64>], (i, j): (usize, usize)| list[i * cv + j].expect("checked: complete cell");
        arrays.array(w, "Float64", "waviness_m", 1, 1, complete().map(|c| at(&wr.waviness_m, c)))?;
        let wrinkled = |(i, j): (usize, usize)| wr.wrinkled(i * cv + j).expect("checked: complete cell") as i32;
        arrays.array(w, "Int32", "wrinkled", 1, 1, complete().map(wrinkled))?;
        arrays.array(w, "Float64", "tool_gap_m", 1, 1, complete().map(|c| at(&wr.tool_gap_m, c)))?;
        if !wr.bending_energy_density_j_m2.is_empty() {
            let values = complete().map(|c| at(&wr.bending_energy_density_j_m2, c));
            arrays.array(w, "Float64", "bending_energy_density_j_m2", 1, 1, values)?;
        }
    }
    w.write_all(b"</CellData>\n")?;

    w.write_all(b"<Points>\n")?;
    let points = placed().flat_map(|k| {
        let p = net.positions[k];
        [p.x, p.y, p.z]
    });
    arrays.array(w, "Float64", "Points", 3, 3, points)?;
    w.write_all(b"</Points>\n")?;

    w.write_all(b"<Cells>\n")?;
    let corners =
        |i: usize, j: usize| [(i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)].map(|(a, b)| point_id[net.index(a, b)]);
    arrays.array(w, "Int64", "connectivity", 1, 4, complete().flat_map(|(i, j)| corners(i, j)))?;
    arrays.array(w, "Int64", "offsets", 1, 1, (1..=n_cells).map(|c| 4 * c))?;
    arrays.array(w, "UInt8", "types", 1, 1, (0..n_cells).map(|_| VTK_QUAD))?;
    w.write_all(b"</Cells>\n")?;

    w.write_all(b"</Piece>\n</UnstructuredGrid>\n")?;
    arrays.finish(w)
}

/// One ASCII `<DataArray>` of `components` per tuple; `values` are written with `{}` (exact for
/// f64), a whole number of `group`s per line.
pub(crate) fn data_array<W: Write, T: std::fmt::Debug>(
    w: &mut W,
    ty: &str,
    name: &str,
    components: usize,
    group: usize,
    values: impl Iterator<Item = T>,
) -> io::Result<()> {
    write!(w, "<DataArray type=\"{ty}\" Name=\"{name}\"")?;
    if components > 1 {
        write!(w, " NumberOfComponents=\"{components}\"")?;
    }
    w.write_all(b" format=\"ascii\">")?;
    let per_line = PER_LINE.max(group) / group * group;
    for (k, v) in values.enumerate() {
        let sep = if k % per_line == 0 { "\n" } else { " " };
        write!(w, "{sep}{v:?}")?;
    }
    w.write_all(b"\n</DataArray>\n")
}

// ---- the flow mesh with the fibres -------------------------------------------------------------

const VTK_TRIANGLE: u8 = 5;

pub(crate) fn write_flow(
    mesh: &FlowMesh,
    map: &LayupMap,
    out: &Path,
    encoding: VtuEncoding,
) -> Result<(), ExportError> {
    let encoding = encoding.resolve(mesh.elements.len());
    write_atomic(out, |w| write_flow_to(mesh, map, w, encoding))
}

fn write_flow_to<W: Write>(mesh: &FlowMesh, map: &LayupMap, w: &mut W, encoding: VtuEncoding) -> io::Result<()> {
    let n = mesh.elements.len();
    let mut a = Arrays::start(w, encoding)?;
    w.write_all(b"<UnstructuredGrid>\n")?;
    writeln!(w, "<Piece NumberOfPoints=\"{}\" NumberOfCells=\"{n}\">", mesh.nodes.len())?;
    w.write_all(b"<CellData>\n")?;
    a.tuple(w, "Int64", "element_id", 1, mesh.elements.iter().map(|e| e.id))?;
    for ply in &map.plies {
        let p = if map.layup { format!("{}_", xml_escape(&ply.ply)) } else { String::new() };
        let els = &ply.elements;
        a.tuple(w, "Int32", &format!("{p}covered"), 1, els.iter().map(|f| i32::from(f.is_some())))?;
        let vec3 = |pick: fn(&crate::mapping::ElementFibres) -> [f64; 3]| {
            els.iter().flat_map(move |f| f.as_ref().map_or([f64::NAN; 3], pick))
        };
        a.tuple(w, "Float64", &format!("{p}warp"), 3, vec3(|f| [f.warp.x, f.warp.y, f.warp.z]))?;
        a.tuple(w, "Float64", &format!("{p}weft"), 3, vec3(|f| [f.weft.x, f.weft.y, f.weft.z]))?;
        let scalar = |pick: fn(&crate::mapping::ElementFibres) -> f64| {
            els.iter().map(move |f| f.as_ref().map_or(f64::NAN, pick))
        };
        a.tuple(w, "Float64", &format!("{p}shear_deg"), 1, scalar(|f| f.shear.to_degrees()))?;
        a.tuple(w, "Float64", &format!("{p}thickness"), 1, scalar(|f| f.thickness))?;
        a.tuple(w, "Float64", &format!("{p}vf"), 1, scalar(|f| f.vf))?;
        if els.iter().flatten().any(|f| f.permeability.is_some()) {
            let k = els.iter().flat_map(|f| row_major(f.as_ref().and_then(|f| f.permeability.as_ref())));
            a.tuple(w, "Float64", &format!("{p}permeability"), 9, k)?;
        }
    }
    if map.layup {
        let laminate = map.thickness.iter().zip(&map.mean_vf).map(|(t, vf)| if vf.is_some() { *t } else { f64::NAN });
        a.tuple(w, "Float64", "laminate_thickness", 1, laminate)?;
        a.tuple(w, "Float64", "mean_vf", 1, map.mean_vf.iter().map(|v| v.unwrap_or(f64::NAN)))?;
        if map.permeability.iter().any(Option::is_some) {
            let k = map.permeability.iter().flat_map(|k| row_major(k.as_ref()));
            a.tuple(w, "Float64", "laminate_permeability", 9, k)?;
        }
    }
    w.write_all(b"</CellData>\n<Points>\n")?;
    a.tuple(w, "Float64", "Points", 3, mesh.nodes.iter().flat_map(|p| [p.x, p.y, p.z]))?;
    w.write_all(b"</Points>\n<Cells>\n")?;
    a.tuple(w, "Int64", "connectivity", 1, mesh.elements.iter().flat_map(|e| e.nodes.iter().copied()))?;
    let offsets = mesh.elements.iter().scan(0usize, |acc, e| {
        *acc += e.nodes.len();
        Some(*acc)
    });
    a.tuple(w, "Int64", "offsets", 1, offsets)?;
    let types = mesh.elements.iter().map(|e| match e.shape {
        ElementShape::Tria3 => VTK_TRIANGLE,
        ElementShape::Quad4 => VTK_QUAD,
    });
    a.tuple(w, "UInt8", "types", 1, types)?;
    w.write_all(b"</Cells>\n</Piece>\n</UnstructuredGrid>\n")?;
    a.finish(w)
}

/// The 9 entries of `k` row by row, zeros for `None`.
/// A tensor's nine components row by row; NaN for none (an element no ply covers).
fn row_major(k: Option<&nalgebra::Matrix3<f64>>) -> [f64; 9] {
    let mut out = [f64::NAN; 9];
    if let Some(k) = k {
        for r in 0..3 {
            for c in 0..3 {
                out[3 * r + c] = k[(r, c)];
            }
        }
    }
    out
}

impl Arrays {
    /// One `<DataArray>` with a whole tuple a group.
    fn tuple<W: Write, T: VtkValue>(
        &mut self,
        w: &mut W,
        ty: &str,
        name: &str,
        components: usize,
        values: impl Iterator<Item = T>,
    ) -> io::Result<()> {
        self.array(w, ty, name, components, components, values)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Point;

    #[test]
    fn small_net_layout() {
        // 3 x 3 unit grid with the corner node (2, 2) missing: 8 points, 3 quads.
        let mut net = DrapeNet::new("p", 1.0, 3, 3, (0, 0));
        for i in 0..3 {
            for j in 0..3 {
                let k = net.index(i, j);
                net.positions[k] = Point::new(i as f64, j as f64, 0.0);
                net.status[k] = NodeStatus::Placed;
            }
        }
        net.status[8] = NodeStatus::NoRoot;
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("p.vtu");
        write_vtu(&net, &path).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(text.contains("<Piece NumberOfPoints=\"8\" NumberOfCells=\"3\">"), "{text}");
        // Cell (0, 0): nodes 0, 3, 4, 1 (points renumbered, but all before node 8 keep their id).
        assert!(text.contains("Name=\"connectivity\" format=\"ascii\">\n0 3 4 1 1 4 5 2\n3 6 7 4\n"), "{text}");
        assert!(text.contains("Name=\"offsets\" format=\"ascii\">\n4 8 12\n"), "{text}");
        assert!(text.contains("Name=\"types\" format=\"ascii\">\n9 9 9\n"), "{text}");
        assert!(
            text.contains(
                "Name=\"normal\" NumberOfComponents=\"3\" format=\"ascii\">\n0.0 0.0 1.0 0.0 0.0 1.0\n0.0 0.0 1.0\n"
            ),
            "{text}"
        );
    }
}
