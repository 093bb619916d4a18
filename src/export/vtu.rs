//! `<ply>.vtu`: VTK XML UnstructuredGrid (ASCII, version 0.1, little endian) for ParaView and
//! meshio. Points are the placed nodes only, renumbered compactly in node order; cells are
//! VTK_QUAD (type 9), one for every cell whose four corners are placed, with connectivity
//! (i, j), (i+1, j), (i+1, j+1), (i, j+1) (counter-clockwise seen from the normal warp x weft).
//!
//! CellData: `shear_deg` (Float64), `warp`, `weft`, `normal` (Float64 x 3, unit), `cell_i`,
//! `cell_j` (Int32). PointData: `node_i`, `node_j` (Int32). Floats are written with `{:?}`, the
//! shortest text that parses back to the same f64.
use super::check::{cells, check_net};
use super::{write_atomic, ExportError};
use crate::geometry::Vector;
use crate::kinematic::{DrapeNet, NodeStatus};
use std::io::{self, Write};
use std::path::Path;

/// VTK cell type of a linear quadrilateral.
const VTK_QUAD: u8 = 9;
/// Values per line in the data arrays (keeps lines short; any layout is valid VTK).
const PER_LINE: usize = 8;

/// Write `net` to `path` (normally `DIR/<ply>.vtu`) atomically. Fails, writing nothing, if a
/// placed node, a cell shear or a cell frame is not finite or a complete cell is degenerate.
pub fn write_vtu(net: &DrapeNet, path: &Path) -> Result<(), ExportError> {
    check_net(net, true)?;
    write_atomic(path, |w| write_vtu_to(net, w))
}

fn write_vtu_to<W: Write>(net: &DrapeNet, w: &mut W) -> io::Result<()> {
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

    w.write_all(b"<?xml version=\"1.0\"?>\n")?;
    w.write_all(b"<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\">\n")?;
    w.write_all(b"<UnstructuredGrid>\n")?;
    writeln!(w, "<Piece NumberOfPoints=\"{n_points}\" NumberOfCells=\"{n_cells}\">")?;

    w.write_all(b"<PointData Scalars=\"node_i\">\n")?;
    data_array(w, "Int32", "node_i", 1, 1, placed().map(|k| k / net.nv))?;
    data_array(w, "Int32", "node_j", 1, 1, placed().map(|k| k % net.nv))?;
    w.write_all(b"</PointData>\n")?;

    w.write_all(b"<CellData Scalars=\"shear_deg\" Vectors=\"warp\">\n")?;
    let shear = complete().map(|(i, j)| net.cell_shear(i, j).expect("complete cell").to_degrees());
    data_array(w, "Float64", "shear_deg", 1, 1, shear)?;
    type Pick = fn(&crate::kinematic::net::CellFrame) -> Vector;
    let picks: [(&str, Pick); 3] = [("warp", |f| f.warp), ("weft", |f| f.weft), ("normal", |f| f.normal)];
    for (name, pick) in picks {
        let values = complete().flat_map(|(i, j)| {
            let v = pick(&net.cell_frame(i, j).expect("checked: complete cells have a frame"));
            [v.x, v.y, v.z]
        });
        data_array(w, "Float64", name, 3, 3, values)?;
    }
    data_array(w, "Int32", "cell_i", 1, 1, complete().map(|(i, _)| i))?;
    data_array(w, "Int32", "cell_j", 1, 1, complete().map(|(_, j)| j))?;
    w.write_all(b"</CellData>\n")?;

    w.write_all(b"<Points>\n")?;
    let points = placed().flat_map(|k| {
        let p = net.positions[k];
        [p.x, p.y, p.z]
    });
    data_array(w, "Float64", "Points", 3, 3, points)?;
    w.write_all(b"</Points>\n")?;

    w.write_all(b"<Cells>\n")?;
    let corners =
        |i: usize, j: usize| [(i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)].map(|(a, b)| point_id[net.index(a, b)]);
    data_array(w, "Int64", "connectivity", 1, 4, complete().flat_map(|(i, j)| corners(i, j)))?;
    data_array(w, "Int64", "offsets", 1, 1, (1..=n_cells).map(|c| 4 * c))?;
    data_array(w, "UInt8", "types", 1, 1, (0..n_cells).map(|_| VTK_QUAD))?;
    w.write_all(b"</Cells>\n")?;

    w.write_all(b"</Piece>\n</UnstructuredGrid>\n</VTKFile>\n")
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
