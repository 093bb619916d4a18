//! `<ply>.cells.csv`: one row per complete cell (all four corners placed), in cell order, with its
//! centre, shear (degrees) and unit fibre frame. Floats are written with `{:?}` (shortest exact round trip, exponent when needed).
use super::check::{cells, check_net};
use super::{write_atomic, ExportError};
use crate::kinematic::DrapeNet;
use std::io::{self, Write};
use std::path::Path;

/// The header line of the cell CSV.
pub const CSV_HEADER: &str =
    "i,j,cx,cy,cz,shear_deg,warp_x,warp_y,warp_z,weft_x,weft_y,weft_z,normal_x,normal_y,normal_z";

/// Write the complete cells of `net` to `path` (normally `DIR/<ply>.cells.csv`) atomically.
/// Fails, writing nothing, if a value would not be finite or a complete cell is degenerate.
pub fn write_csv(net: &DrapeNet, path: &Path) -> Result<(), ExportError> {
    check_net(net, true)?;
    write_atomic(path, |w| write_csv_to(net, w))
}

fn write_csv_to<W: Write>(net: &DrapeNet, w: &mut W) -> io::Result<()> {
    writeln!(w, "{CSV_HEADER}")?;
    for (i, j) in cells(net) {
        let (Some(g), Some(f)) = (net.cell_shear(i, j), net.cell_frame(i, j)) else { continue };
        let (c, a, b, n) = (f.centre, f.warp, f.weft, f.normal);
        writeln!(
            w,
            "{i},{j},{:?},{:?},{:?},{:?},{:?},{:?},{:?},{:?},{:?},{:?},{:?},{:?},{:?}",
            c.x,
            c.y,
            c.z,
            g.to_degrees(),
            a.x,
            a.y,
            a.z,
            b.x,
            b.y,
            b.z,
            n.x,
            n.y,
            n.z
        )?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Point;
    use crate::kinematic::NodeStatus;

    #[test]
    fn rows_for_complete_cells_only() {
        let mut net = DrapeNet::new("p", 0.5, 3, 2, (0, 0));
        for i in 0..3 {
            for j in 0..2 {
                let k = net.index(i, j);
                net.positions[k] = Point::new(0.5 * i as f64, 0.5 * j as f64, 1.0);
                net.status[k] = NodeStatus::Placed;
            }
        }
        let k = net.index(2, 1);
        net.status[k] = NodeStatus::OffTool;
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("p.cells.csv");
        write_csv(&net, &path).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        assert_eq!(text, format!("{CSV_HEADER}\n0,0,0.25,0.25,1.0,0.0,1.0,0.0,0.0,0.0,1.0,0.0,0.0,0.0,1.0\n"));
    }
}
