//! STL (stereolithography), ASCII and binary: one parser ([`parse`]) for tools ([`read_stl`])
//! and flow meshes ([`read`]), and the writers of a triangle mesh
//! ([`TriangleMesh::to_stl_ascii`], [`TriangleMesh::to_stl_binary`]).
//!
//! A binary STL is an 80-byte header, a little-endian `u32` triangle count and 50 bytes per
//! triangle (normal and three corners as `f32`, two attribute bytes); a file is read as binary
//! when its size is exactly what its count says, whatever its header holds (several CAD systems
//! begin binary headers with `solid`). Otherwise it must be ASCII: `solid [name]`, then facets
//! `facet normal ni nj nk` / `outer loop` / `vertex x y z` (three or more) / `endloop` /
//! `endfacet`, then `endsolid [name]`; several solids may follow one another, keywords may be in
//! any case, and numbers are read as `f64`. Normals are read but not used (the tool's sides come
//! from the corners' order and the checks).
//!
//! STL repeats every corner in every facet that uses it: corners at exactly the same position
//! are one vertex (numbered in the order facets first use them), so an STL and an OBJ of the same
//! triangles give the same mesh. A facet of more than three corners is fanned from its first.
//! A truncated file (a binary one shorter or longer than its count says, an ASCII one ending
//! inside a facet or without `endsolid`), a non-finite corner or a file with no facet is refused,
//! saying where.
use super::shell_mesh::{read_bytes, Builder, FlowMeshError, Loc};
use crate::geometry::{MeshReport, Point, ToolError, TriangleMesh};
use crate::mapping::FlowMesh;
use std::collections::HashMap;
use std::fmt::Write as _;
use std::path::Path;

/// STL as a shell-mesh format.
pub const FORMAT: super::MeshFormat = super::MeshFormat { name: "STL", extensions: &["stl"], read };

/// One facet: its corners and where it is (its 1-based line in an ASCII file, its 1-based
/// number in a binary one).
#[derive(Debug, Clone, PartialEq)]
pub struct StlFacet {
    /// Corners in file order.
    pub corners: Vec<[f64; 3]>,
    /// Line of `facet` (ASCII) or facet number (binary).
    pub at: usize,
}

/// The facets of an STL file.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct StlText {
    /// Whether the file is binary.
    pub binary: bool,
    /// Facets in file order.
    pub facets: Vec<StlFacet>,
}

impl StlFacet {
    /// Where the facet is, for messages.
    fn place(&self, binary: bool) -> String {
        if binary {
            format!("facet {}", self.at)
        } else {
            format!("the facet at line {}", self.at)
        }
    }
}

/// Size of a binary STL's header and count.
const BINARY_HEAD: usize = 84;
/// Size of one binary facet.
const BINARY_FACET: usize = 50;

/// Parse an STL file's bytes (see the module documentation); the error says where and what is
/// wrong.
pub fn parse(bytes: &[u8]) -> Result<StlText, String> {
    let declared = (bytes.len() >= BINARY_HEAD).then(|| u32::from_le_bytes(bytes[80..84].try_into().unwrap()) as u64);
    let needed = declared.map(|n| BINARY_HEAD as u64 + BINARY_FACET as u64 * n);
    if needed == Some(bytes.len() as u64) {
        return Ok(parse_binary(bytes));
    }
    let looks_ascii = bytes.trim_ascii_start().get(..5).is_some_and(|w| w.eq_ignore_ascii_case(b"solid"));
    let is_text = !bytes.contains(&0);
    match (looks_ascii && is_text, declared, needed) {
        (true, _, _) => parse_ascii(bytes),
        (false, Some(n), Some(needed)) => Err(format!(
            "as a binary STL it declares {n} triangles, which take {needed} bytes, but the file has {} bytes: it is truncated or damaged{}",
            bytes.len(),
            if looks_ascii { " (it begins with `solid` but holds binary data, so it is not an ASCII STL either)" } else { "" }
        )),
        _ if looks_ascii => Err("it begins with `solid` but holds binary data, and it is too short to be a binary STL".into()),
        _ => Err(format!(
            "it has {} bytes: too short for a binary STL (an 84-byte header and count) and it does not begin with `solid` as an ASCII STL does",
            bytes.len()
        )),
    }
}

fn parse_binary(bytes: &[u8]) -> StlText {
    let facets = bytes[BINARY_HEAD..]
        .chunks_exact(BINARY_FACET)
        .enumerate()
        .map(|(k, chunk)| {
            let f = |i: usize| f32::from_le_bytes(chunk[i..i + 4].try_into().unwrap()) as f64;
            let corner = |c: usize| [f(12 + 12 * c), f(16 + 12 * c), f(20 + 12 * c)];
            StlFacet { corners: vec![corner(0), corner(1), corner(2)], at: k + 1 }
        })
        .collect();
    StlText { binary: true, facets }
}

/// The words of an ASCII STL with their 1-based line numbers.
struct Words<'a> {
    lines: std::vec::IntoIter<(usize, Vec<&'a str>)>,
}

impl<'a> Words<'a> {
    fn new(text: &'a str) -> Self {
        let lines: Vec<(usize, Vec<&str>)> = text
            .split(['\n', '\r'])
            .enumerate()
            .map(|(k, l)| (k + 1, l.split_whitespace().collect::<Vec<_>>()))
            .filter(|(_, w)| !w.is_empty())
            .collect();
        Words { lines: lines.into_iter() }
    }

    /// The next non-empty line.
    fn line(&mut self) -> Option<(usize, Vec<&'a str>)> {
        self.lines.next()
    }
}

fn parse_ascii(bytes: &[u8]) -> Result<StlText, String> {
    // `\r\n` counts as one line end for the line numbers.
    let text = String::from_utf8_lossy(bytes).replace("\r\n", "\n");
    let mut words = Words::new(&text);
    let mut facets = Vec::new();
    let keyword = |w: &[&str], k: usize, expected: &str| w.get(k).is_some_and(|x| x.eq_ignore_ascii_case(expected));
    let shown = |w: &[&str]| {
        let s = w.join(" ");
        if s.chars().count() > 60 {
            format!("`{}...`", s.chars().take(60).collect::<String>())
        } else {
            format!("`{s}`")
        }
    };
    let numbers = |w: &[&str], line: usize, what: &str| -> Result<[f64; 3], String> {
        let parsed: Option<Vec<f64>> = w.iter().map(|x| x.parse::<f64>().ok()).collect();
        match parsed.as_deref() {
            Some(&[x, y, z]) => Ok([x, y, z]),
            _ => Err(format!("line {line}: {what} needs three numbers, found {}", shown(w))),
        }
    };
    let truncated = |inside: &str| format!("the file ends {inside}: it is truncated");
    // Solids until the end of the file (there is at least one: the file begins with `solid`).
    while let Some((line, w)) = words.line() {
        if !keyword(&w, 0, "solid") {
            return Err(format!("line {line}: expected `solid` (or the end of the file), found {}", shown(&w)));
        }
        loop {
            let Some((line, w)) = words.line() else { return Err(truncated("without `endsolid`")) };
            if keyword(&w, 0, "endsolid") {
                break;
            }
            if !(keyword(&w, 0, "facet") && keyword(&w, 1, "normal")) {
                return Err(format!(
                    "line {line}: expected `facet normal ni nj nk` or `endsolid`, found {}",
                    shown(&w)
                ));
            }
            numbers(&w[2..], line, "`facet normal`")?;
            let at = line;
            let inside = format!("inside the facet at line {at}");
            let (l, w) = words.line().ok_or_else(|| truncated(&inside))?;
            if !(keyword(&w, 0, "outer") && keyword(&w, 1, "loop") && w.len() == 2) {
                return Err(format!("line {l}: expected `outer loop`, found {}", shown(&w)));
            }
            let mut corners = Vec::with_capacity(3);
            loop {
                let (l, w) = words.line().ok_or_else(|| truncated(&inside))?;
                if keyword(&w, 0, "endloop") && w.len() == 1 {
                    break;
                }
                if !keyword(&w, 0, "vertex") {
                    return Err(format!("line {l}: expected `vertex x y z` or `endloop`, found {}", shown(&w)));
                }
                corners.push(numbers(&w[1..], l, "`vertex`")?);
            }
            if corners.len() < 3 {
                return Err(format!(
                    "the facet at line {at} has {} corners: a facet needs three `vertex` lines",
                    corners.len()
                ));
            }
            let (l, w) = words.line().ok_or_else(|| truncated(&inside))?;
            if !(keyword(&w, 0, "endfacet") && w.len() == 1) {
                return Err(format!("line {l}: expected `endfacet`, found {}", shown(&w)));
            }
            facets.push(StlFacet { corners, at });
        }
    }
    Ok(StlText { binary: false, facets })
}

/// The key of a position for welding: its bits, with -0 as 0.
fn key(p: [f64; 3]) -> [u64; 3] {
    p.map(|c| (c + 0.0).to_bits())
}

/// Read an STL file as a tool: its triangles (see the module documentation) and what was found
/// on the way. Refuses an unreadable or unparsable file, one without facets, and a non-finite
/// corner.
pub fn read_stl(path: &Path) -> Result<(TriangleMesh, MeshReport), ToolError> {
    let bytes = super::read::read_file(path).map_err(|source| ToolError::Io { path: path.into(), source })?;
    let bad = |reason: String| ToolError::ParseStl { path: path.into(), reason };
    let text = parse(&bytes).map_err(bad)?;
    if text.facets.is_empty() {
        return Err(ToolError::Empty { path: path.into() });
    }
    let mut report = MeshReport { faces_read: text.facets.len(), ..Default::default() };
    let mut index: HashMap<[u64; 3], u32> = HashMap::new();
    let mut mesh = TriangleMesh::default();
    for facet in &text.facets {
        let mut corners = Vec::with_capacity(facet.corners.len());
        for (c, &p) in facet.corners.iter().enumerate() {
            if let Some(value) = p.iter().find(|v| !v.is_finite()) {
                return Err(bad(format!(
                    "{}, corner {}, has a non-finite coordinate ({value}); fix or remove that facet",
                    facet.place(text.binary),
                    c + 1
                )));
            }
            let next = mesh.vertices.len() as u32;
            let k = *index.entry(key(p)).or_insert_with(|| {
                mesh.vertices.push(Point::new(p[0], p[1], p[2]));
                next
            });
            corners.push(k);
        }
        if corners.len() > 3 {
            report.polygons_triangulated += 1;
        }
        for pair in corners[1..].windows(2) {
            mesh.triangles.push([corners[0], pair[0], pair[1]]);
        }
    }
    report.vertices_read = mesh.vertices.len();
    Ok((mesh, report))
}

/// Read an STL file as a flow mesh: node ids number the distinct corner positions from 1 in
/// the order facets first use them, element ids the triangles from 1 (facets of more than
/// three corners fanned), every property 0; lengths multiplied by `scale`.
pub fn read(path: &Path, scale: f64) -> Result<FlowMesh, FlowMeshError> {
    let mut b = Builder::new(path, scale)?;
    let bytes = read_bytes(path)?;
    let text = parse(&bytes).map_err(|message| FlowMeshError::Invalid { path: path.into(), message })?;
    let mut ids: HashMap<[u64; 3], u64> = HashMap::new();
    let mut element = 0;
    for facet in &text.facets {
        // ASCII: the facet's line; binary: no lines, so 0 and the facet number in the message.
        let loc = Loc { file: 0, line: if text.binary { 0 } else { facet.at } };
        let mut corners = Vec::with_capacity(facet.corners.len());
        for &p in &facet.corners {
            let id = match ids.get(&key(p)) {
                Some(&id) => id,
                None => {
                    let id = ids.len() as u64 + 1;
                    b.add_node(id, p, loc).map_err(|e| match (text.binary, e) {
                        (true, FlowMeshError::Syntax { path, message, .. }) => {
                            FlowMeshError::Invalid { path, message: format!("facet {}: {message}", facet.at) }
                        }
                        (_, e) => e,
                    })?;
                    ids.insert(key(p), id);
                    id
                }
            };
            corners.push(id);
        }
        for k in 1..corners.len() - 1 {
            element += 1;
            b.add_element(element, &[corners[0], corners[k], corners[k + 1]], 0, loc)?;
        }
    }
    b.finish("facets")
}

impl TriangleMesh {
    /// ASCII STL of the triangles, the solid named `name`: `{}` formatting of `f64` (the
    /// shortest text that reads back to the same number), each facet's unit normal from its
    /// corners' order (0 0 0 for a degenerate one).
    pub fn to_stl_ascii(&self, name: &str) -> String {
        let mut s = String::with_capacity(self.triangles.len() * 200);
        let _ = writeln!(s, "solid {name}");
        for t in &self.triangles {
            let [a, b, c] = t.map(|i| self.vertices[i as usize]);
            let n = self.facet_normal(t);
            let _ = writeln!(s, "  facet normal {} {} {}\n    outer loop", n[0], n[1], n[2]);
            for p in [a, b, c] {
                let _ = writeln!(s, "      vertex {} {} {}", p.x, p.y, p.z);
            }
            let _ = writeln!(s, "    endloop\n  endfacet");
        }
        let _ = writeln!(s, "endsolid {name}");
        s
    }

    /// Binary STL of the triangles: coordinates rounded to `f32` as the format requires, a
    /// header that does not begin with `solid`.
    pub fn to_stl_binary(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(BINARY_HEAD + BINARY_FACET * self.triangles.len());
        let mut header = [b' '; 80];
        let title = b"binary STL written by drape";
        header[..title.len()].copy_from_slice(title);
        out.extend_from_slice(&header);
        out.extend_from_slice(&(self.triangles.len() as u32).to_le_bytes());
        for t in &self.triangles {
            let n = self.facet_normal(t);
            let corners = t.map(|i| self.vertices[i as usize]).map(|p| [p.x, p.y, p.z]);
            for v in std::iter::once(n).chain(corners) {
                for c in v {
                    out.extend_from_slice(&(c as f32).to_le_bytes());
                }
            }
            out.extend_from_slice(&[0, 0]);
        }
        out
    }

    fn facet_normal(&self, t: &[u32; 3]) -> [f64; 3] {
        let [a, b, c] = t.map(|i| self.vertices[i as usize]);
        let n = (b - a).cross(&(c - a));
        let len = n.norm();
        if len > 0.0 && len.is_finite() {
            [n.x / len, n.y / len, n.z / len]
        } else {
            [0.0; 3]
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square() -> TriangleMesh {
        TriangleMesh {
            vertices: vec![
                Point::new(0.0, 0.0, 0.0),
                Point::new(1.0, 0.0, 0.0),
                Point::new(1.0, 1.0, 0.25),
                Point::new(0.0, 1.0, 0.0),
            ],
            triangles: vec![[0, 1, 2], [0, 2, 3]],
        }
    }

    fn read_bytes_as_tool(bytes: &[u8]) -> Result<(TriangleMesh, MeshReport), ToolError> {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("tool.stl");
        std::fs::write(&path, bytes).unwrap();
        read_stl(&path)
    }

    #[test]
    fn ascii_and_binary_read_back_the_same_welded_mesh() {
        let mesh = square();
        for bytes in [mesh.to_stl_ascii("sq").into_bytes(), mesh.to_stl_binary()] {
            let (read, report) = read_bytes_as_tool(&bytes).unwrap();
            assert_eq!(read, mesh);
            assert_eq!(report.vertices_read, 4);
            assert_eq!(report.faces_read, 2);
        }
    }

    #[test]
    fn a_binary_header_beginning_with_solid_is_still_binary() {
        let mut bytes = square().to_stl_binary();
        bytes[..6].copy_from_slice(b"solid ");
        assert_eq!(read_bytes_as_tool(&bytes).unwrap().0, square());
    }

    #[test]
    fn ascii_variants_are_read() {
        // Upper case, no name, CRLF, two solids, a quad facet fanned.
        let text = "SOLID\r\nFACET NORMAL 0 0 1\r\nOUTER LOOP\r\nVERTEX 0 0 0\r\nVERTEX 1 0 0\r\nVERTEX 1 1 0\r\nVERTEX 0 1 0\r\nENDLOOP\r\nENDFACET\r\nENDSOLID\r\n\
                    solid b\nfacet normal 0 0 0\nouter loop\nvertex 0 0 0\nvertex 1 1 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid b";
        let (mesh, report) = read_bytes_as_tool(text.as_bytes()).unwrap();
        assert_eq!(mesh.vertices.len(), 4);
        assert_eq!(mesh.triangles, vec![[0, 1, 2], [0, 2, 3], [0, 2, 3]]);
        assert_eq!(report.polygons_triangulated, 1);
    }

    #[test]
    fn malformed_and_truncated_files_say_where() {
        let ascii = square().to_stl_ascii("sq");
        let err = |bytes: &[u8]| read_bytes_as_tool(bytes).unwrap_err().to_string();
        let cut = &ascii[..ascii.find("endloop").unwrap()];
        assert!(err(cut.as_bytes()).contains("ends inside the facet at line 2: it is truncated"), "{}", err(cut.as_bytes()));
        let no_end = &ascii[..ascii.rfind("endsolid").unwrap()];
        assert!(err(no_end.as_bytes()).contains("without `endsolid`"));
        let bad_number = ascii.replacen("vertex 1 0 0", "vertex 1 zero 0", 1);
        assert!(err(bad_number.as_bytes()).contains("line 5: `vertex` needs three numbers, found `1 zero 0`"));
        let nan = ascii.replacen("vertex 1 0 0", "vertex 1 nan 0", 1);
        assert!(err(nan.as_bytes()).contains("the facet at line 2, corner 2, has a non-finite coordinate"));
        let binary = square().to_stl_binary();
        let e = err(&binary[..binary.len() - 7]);
        assert!(e.contains("declares 2 triangles, which take 184 bytes, but the file has 177 bytes: it is truncated"), "{e}");
        assert!(e.contains("not a valid STL file"), "{e}");
        assert!(err(b"hello").contains("too short for a binary STL"));
        assert!(matches!(read_bytes_as_tool(b"solid x\nendsolid x\n"), Err(ToolError::Empty { .. })));
        let mut nan = binary.clone();
        nan[84 + 12..84 + 16].copy_from_slice(&f32::NAN.to_le_bytes());
        assert!(err(&nan).contains("facet 1, corner 1, has a non-finite coordinate"));
    }

    #[test]
    fn flow_mesh_nodes_are_the_distinct_corners() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("mesh.stl");
        std::fs::write(&path, square().to_stl_binary()).unwrap();
        let mesh = read(&path, 0.001).unwrap();
        assert_eq!(mesh.nodes.len(), 4);
        assert_eq!(mesh.elements.len(), 2);
        assert_eq!(mesh.nodes[2], Point::new(0.001, 0.001, 0.00025));
    }
}
