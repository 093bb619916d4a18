//! Wavefront OBJ: `v x y z [w]` vertices and `f` faces (`a`, `a/t`, `a//n`, `a/t/n`; negative
//! indices count back from the last vertex read). Triangles and quads are kept as they are; a
//! polygon with more than four corners is split into a fan of triangles from its first corner.
//! Node ids are the vertex numbers (from 1); element ids are the elements' numbers in output
//! order (from 1), which is the face number as long as no polygon was split. Groups, objects,
//! materials and smoothing (`g`, `o`, `usemtl`, `s`) are ignored: every property is 0. A line
//! ending in `\` continues on the next.
use super::shell_mesh::{read_bytes, Builder, FlowMeshError, Loc};
use crate::mapping::FlowMesh;
use std::path::Path;

/// OBJ as a shell-mesh format.
pub const FORMAT: super::MeshFormat = super::MeshFormat { name: "OBJ", extensions: &["obj"], read };

/// Read an OBJ file (see the module documentation).
pub fn read(path: &Path, scale: f64) -> Result<FlowMesh, FlowMeshError> {
    let mut b = Builder::new(path, scale)?;
    let bytes = read_bytes(path)?;
    let text = String::from_utf8_lossy(&bytes);
    let mut nverts: u64 = 0;
    let mut next_element: u64 = 1;
    let mut joined = String::new();
    let mut start = 0usize;
    for (k, raw) in text.lines().enumerate() {
        let raw = raw.split('#').next().unwrap_or("");
        if joined.is_empty() {
            start = k + 1;
        }
        if let Some(head) = raw.trim_end().strip_suffix('\\') {
            joined.push_str(head);
            joined.push(' ');
            continue;
        }
        joined.push_str(raw);
        let line = std::mem::take(&mut joined);
        let loc = Loc { file: 0, line: start };
        let mut tok = line.split_whitespace();
        match tok.next() {
            Some("v") => {
                let mut x = [0.0; 3];
                for (i, xi) in x.iter_mut().enumerate() {
                    let t = tok.next().ok_or_else(|| b.syntax(loc, "vertex line needs three coordinates: v x y z"))?;
                    *xi = t
                        .parse()
                        .map_err(|_| b.syntax(loc, format!("vertex coordinate {}: '{t}' is not a number", i + 1)))?;
                }
                nverts += 1;
                b.add_node(nverts, x, loc)?;
            }
            Some("f") => {
                let mut corners: Vec<u64> = Vec::with_capacity(4);
                for t in tok {
                    let v = t.split('/').next().unwrap_or("");
                    let i: i64 = v
                        .parse()
                        .map_err(|_| b.syntax(loc, format!("face corner '{t}' does not start with a vertex number")))?;
                    let n = if i > 0 {
                        i as u64
                    } else if i < 0 && i.unsigned_abs() <= nverts {
                        nverts + 1 - i.unsigned_abs()
                    } else {
                        return Err(b.syntax(
                            loc,
                            format!("face corner {i} does not name a vertex read so far ({nverts} vertices)"),
                        ));
                    };
                    corners.push(n);
                }
                match corners.len() {
                    3 | 4 => {
                        b.add_element(next_element, &corners, 0, loc)?;
                        next_element += 1;
                    }
                    n if n > 4 => {
                        for k in 1..n - 1 {
                            b.add_element(next_element, &[corners[0], corners[k], corners[k + 1]], 0, loc)?;
                            next_element += 1;
                        }
                    }
                    n => return Err(b.syntax(loc, format!("face with {n} corners: a face needs at least 3"))),
                }
            }
            Some("l") => b.skip("line (l)"),
            Some("p") => b.skip("point (p)"),
            _ => {}
        }
    }
    b.finish("f faces with 3 or more corners")
}
