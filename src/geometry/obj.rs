//! Loading a tool surface from an OBJ file, and the checks every tool mesh goes through.
use super::Point;
use std::path::{Path, PathBuf};

/// What was found (and mended) while loading and checking a tool mesh.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct MeshReport {
    /// Vertices as read from the file.
    pub vertices_read: usize,
    /// Faces as read (polygons counted once).
    pub faces_read: usize,
    /// Polygons with more than three corners that were split into triangles.
    pub polygons_triangulated: usize,
    /// Vertices merged into another one at the same position.
    pub vertices_welded: usize,
    /// Faces with (near) zero area that were dropped.
    pub degenerate_faces_dropped: usize,
    /// Faces that repeated another face and were dropped.
    pub duplicate_faces_dropped: usize,
    /// Edges shared by more than two triangles (treated as tool edges when walking).
    pub non_manifold_edges: usize,
    /// Edges used by a single triangle (the open boundary of the tool).
    pub boundary_edges: usize,
    /// Triangles whose winding disagreed with their neighbours' and were turned over.
    pub flipped_faces: usize,
    /// Connected pieces of the mesh.
    pub components: usize,
    /// Triangles in the checked mesh.
    pub triangles: usize,
    /// Vertices in the checked mesh.
    pub vertices: usize,
}

/// Why an OBJ file could not become a tool surface.
#[derive(Debug, thiserror::Error)]
pub enum ObjError {
    #[error("cannot read tool mesh {path}: {source}. Check the path and that the file is readable.")]
    Io { path: PathBuf, source: std::io::Error },
    #[error("tool mesh {path} is not a valid OBJ file: {reason}. Export the surface again as a Wavefront OBJ with triangles or polygons.")]
    Parse { path: PathBuf, reason: String },
    #[error(
        "tool mesh {path} has no faces. Export the surface (not only its points or curves) as triangles or polygons."
    )]
    Empty { path: PathBuf },
    /// `index` is the vertex number: 1-based in file order (as OBJ counts) for a file, 0-based
    /// for an in-memory mesh.
    #[error("tool mesh {path}: vertex {index} has a non-finite coordinate ({value}). Fix or remove that vertex.")]
    NonFinite { path: PathBuf, index: usize, value: f64 },
    /// For a file, `face` is the 1-based number of the `f` statement and `index` the vertex
    /// number as written (1-based); for an in-memory mesh both are 0-based.
    #[error("tool mesh {path}: face {face} refers to vertex {index}, but the file has only {count} vertices. Re-export the mesh.")]
    BadIndex { path: PathBuf, face: usize, index: usize, count: usize },
    #[error("tool mesh {path}: every face is degenerate (zero area). Check the file's units and export settings.")]
    AllDegenerate { path: PathBuf },
}

/// A triangle soup with checked coordinates, before welding and topology.
#[derive(Debug, Clone, Default)]
pub struct RawMesh {
    pub vertices: Vec<Point>,
    pub triangles: Vec<[u32; 3]>,
}

/// Read an OBJ file into a raw triangle mesh (polygons fan-triangulated), refusing empty files,
/// non-finite coordinates and bad indices.
///
/// All objects and groups of the file are merged into one mesh that keeps the file's vertex
/// numbering (a vertex shared by two groups stays one vertex). Only `v` and `f` statements
/// matter: normals, texture coordinates, vertex colours, materials, groups, polylines (`l`) and
/// comments are ignored. Faces with fewer than three corners are dropped and counted as
/// degenerate. Vertices no face uses are left out.
pub fn read_obj(path: &Path) -> Result<(RawMesh, MeshReport), ObjError> {
    let mut bytes = std::fs::read(path).map_err(|source| ObjError::Io { path: path.into(), source })?;
    let parse_error = |reason: String| ObjError::Parse { path: path.into(), reason };
    if bytes.contains(&0) {
        return Err(parse_error(
            "it is a binary file, not a text (Wavefront) OBJ; binary STL, zipped or native CAD \
             files cannot be read"
                .into(),
        ));
    }
    let vertices_read = sanitize(&mut bytes);

    // One index per position (normal and texture indices are separate and unused), no
    // triangulation by tobj (we fan-triangulate and count polygons), points and lines kept so
    // that faces with fewer than three corners can be counted.
    // (`..Default::default()` covers the fields tobj's optional features add.)
    #[allow(clippy::needless_update)]
    let options = tobj::LoadOptions {
        single_index: false,
        triangulate: false,
        ignore_points: false,
        ignore_lines: false,
        ..Default::default()
    };
    // `sanitize` removed the statements on which tobj can panic (arithmetic overflow on
    // out-of-range texture or normal indices); the guard is a last line of defence.
    let loaded = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        tobj::load_obj_buf(&mut &bytes[..], &options, |_| Err(tobj::LoadError::OpenFileFailed))
    }));
    let models = match loaded {
        Err(_) => return Err(parse_error("the OBJ reader (tobj) failed on this file".into())),
        Ok(Err(e)) => return Err(explain_load_error(e, &bytes, path)),
        Ok(Ok((models, _materials))) => models,
    };

    let mut report = MeshReport { vertices_read, ..Default::default() };
    let mut raw = RawMesh::default();
    for model in &models {
        let mesh = &model.mesh;
        let base = raw.vertices.len();
        for c in mesh.positions.chunks_exact(3) {
            let p = Point::new(f64::from(c[0]), f64::from(c[1]), f64::from(c[2]));
            if let Some(&value) = p.coords.iter().find(|x| !x.is_finite()) {
                // tobj renumbers vertices; look the offending one up in the file.
                let (index, value) =
                    first_non_finite_vertex(&bytes, &mesh.positions).unwrap_or((raw.vertices.len() + 1, value));
                return Err(ObjError::NonFinite { path: path.into(), index, value });
            }
            raw.vertices.push(p);
        }
        let count = raw.vertices.len();
        // tobj leaves `face_arities` empty when every face is a triangle.
        let faces = if mesh.face_arities.is_empty() { mesh.indices.len() / 3 } else { mesh.face_arities.len() };
        let mut start = 0;
        for f in 0..faces {
            let n = mesh.face_arities.get(f).map_or(3, |&n| n as usize);
            let corners = mesh
                .indices
                .get(start..start + n)
                .ok_or_else(|| parse_error("the OBJ reader returned inconsistent faces".into()))?;
            start += n;
            report.faces_read += 1;
            if n < 3 {
                report.degenerate_faces_dropped += 1;
                continue;
            }
            if n > 3 {
                report.polygons_triangulated += 1;
            }
            let global = |i: u32| {
                let g = base + i as usize;
                if g < count {
                    Ok(g as u32)
                } else {
                    Err(parse_error("the OBJ reader returned a vertex index out of range".into()))
                }
            };
            let first = global(corners[0])?;
            for pair in corners[1..].windows(2) {
                raw.triangles.push([first, global(pair[0])?, global(pair[1])?]);
            }
        }
    }
    if report.faces_read == 0 {
        return Err(ObjError::Empty { path: path.into() });
    }
    if raw.triangles.is_empty() {
        return Err(ObjError::AllDegenerate { path: path.into() });
    }
    Ok((raw, report))
}

/// OBJ whitespace as `str::split_whitespace` sees it in ASCII (tobj splits words with it).
fn is_space(b: u8) -> bool {
    b.is_ascii_whitespace() || b == 0x0b
}

/// Byte ranges of the first `N` words of `line`, and how many words it has, counted up to
/// `N + 1` (so `N + 1` means "more than `N`").
fn words<const N: usize>(line: &[u8]) -> ([(usize, usize); N], usize) {
    let mut out = [(0, 0); N];
    let mut count = 0;
    let mut i = 0;
    while i < line.len() && count <= N {
        if is_space(line[i]) {
            i += 1;
            continue;
        }
        let s = i;
        while i < line.len() && !is_space(line[i]) {
            i += 1;
        }
        if count < N {
            out[count] = (s, i);
        }
        count += 1;
    }
    (out, count)
}

/// The first word of `line`.
fn keyword(line: &[u8]) -> &[u8] {
    let (w, n) = words::<1>(line);
    if n == 0 {
        &[]
    } else {
        &line[w[0].0..w[0].1]
    }
}

/// Prepare the file text for tobj, in place and without changing line numbers: turn lone `\r`
/// line ends into `\n`, blank comments, every statement other than `v` and `f` (tobj would
/// split the mesh into one model per group, read `l` polylines as faces, try to open material
/// libraries, and can overflow on out-of-range texture or normal indices) and vertex colours
/// (tobj refuses a file where only some vertices have colours). Returns the number of `v`
/// statements.
fn sanitize(bytes: &mut [u8]) -> usize {
    // (`contains` on bytes is memchr-fast; most files have neither `\r` nor comments.)
    if bytes.contains(&b'\r') {
        for i in 0..bytes.len() {
            if bytes[i] == b'\r' {
                bytes[i] = if bytes.get(i + 1) == Some(&b'\n') { b' ' } else { b'\n' };
            }
        }
    }
    let mut vertices = 0;
    for line in bytes.split_mut(|&b| b == b'\n') {
        if line.contains(&b'#') {
            if let Some(hash) = line.iter().position(|&b| b == b'#') {
                line[hash..].fill(b' ');
            }
        }
        match keyword(line) {
            b"" | b"f" => {}
            b"v" => {
                vertices += 1;
                // `v x y z [w]` or `v x y z r g b`: drop the colour.
                let (w, n) = words::<7>(line);
                if n == 7 {
                    line[w[4].0..].fill(b' ');
                }
            }
            _ => line.fill(b' '),
        }
    }
    vertices
}

/// Lines of the (sanitized) text with their 1-based numbers.
fn numbered_lines(bytes: &[u8]) -> impl Iterator<Item = (usize, &[u8])> {
    bytes.split(|&b| b == b'\n').enumerate().map(|(i, l)| (i + 1, l))
}

/// A line, shortened for an error message.
fn quote(line: &[u8]) -> String {
    let text = String::from_utf8_lossy(line);
    let text = text.trim();
    match text.char_indices().nth(60) {
        Some((cut, _)) => format!("`{}...`", &text[..cut]),
        None => format!("`{text}`"),
    }
}

/// Turn a tobj error into an [`ObjError`] that says where the problem is.
fn explain_load_error(e: tobj::LoadError, bytes: &[u8], path: &Path) -> ObjError {
    use tobj::LoadError as L;
    let parse = |reason: String| ObjError::Parse { path: path.into(), reason };
    let at = |found: Option<(usize, &[u8])>, hint: &str| match found {
        Some((n, line)) => parse(format!("{e} on line {n}: {} ({hint})", quote(line))),
        None => parse(format!("{e} ({hint})")),
    };
    match e {
        L::PositionParseError | L::ScalingByZeroError | L::ColorParseError => at(
            numbered_lines(bytes).find(|(_, l)| keyword(l) == b"v" && !vertex_line_ok(l)),
            "a vertex is `v x y z` with three numbers, optionally followed by a weight w other \
             than 0",
        ),
        L::FaceParseError => at(
            numbered_lines(bytes).find(|(_, l)| keyword(l) == b"f" && !face_line_ok(l)),
            "a face is `f` followed by vertex numbers, such as `f 1 2 3` or `f 1/1/1 2/2/2 3/3/3`",
        ),
        L::ReadError => {
            at(numbered_lines(bytes).find(|(_, l)| std::str::from_utf8(l).is_err()), "the file must be plain text")
        }
        L::FaceVertexOutOfBounds => bad_index(bytes, path)
            .unwrap_or_else(|| parse(format!("{e} (a face refers to a vertex that does not exist)"))),
        _ => parse(e.to_string()),
    }
}

/// Whether a `v` line is one tobj accepts.
fn vertex_line_ok(line: &[u8]) -> bool {
    let (w, n) = words::<7>(line);
    let num = |k: usize| std::str::from_utf8(&line[w[k].0..w[k].1]).ok().and_then(|s| s.parse::<f64>().ok());
    n >= 4
        && (1..4).all(|k| num(k).is_some())
        && match n {
            4 | 7 => true,
            5 => num(4).is_some_and(|x| x != 0.0),
            _ => false,
        }
}

/// Whether an `f` line is one tobj accepts (syntax only).
fn face_line_ok(line: &[u8]) -> bool {
    let Ok(text) = std::str::from_utf8(line) else {
        return false;
    };
    text.split_whitespace().skip(1).all(|word| {
        let parts: Vec<&str> = word.split('/').collect();
        parts.len() <= 3 && parts.iter().all(|p| p.is_empty() || p.parse::<isize>().is_ok())
    })
}

/// The vertex references of the `f` lines, in file order: (face number, line number, index as
/// written, vertices defined before the line).
fn face_references(bytes: &[u8]) -> impl Iterator<Item = (usize, usize, isize, usize)> + '_ {
    let mut before = 0;
    let mut face = 0;
    numbered_lines(bytes).flat_map(move |(n, line)| {
        let mut refs = Vec::new();
        match keyword(line) {
            b"v" => before += 1,
            b"f" => {
                face += 1;
                if let Ok(text) = std::str::from_utf8(line) {
                    for word in text.split_whitespace().skip(1) {
                        let v = word.split('/').next().unwrap_or("");
                        if let Ok(i) = v.parse::<isize>() {
                            refs.push((face, n, i, before));
                        }
                    }
                }
            }
            _ => {}
        }
        refs
    })
}

/// Find the first face whose vertex reference does not resolve (what tobj reports as
/// `FaceVertexOutOfBounds`). Indices in the error are 1-based, as written in the file.
fn bad_index(bytes: &[u8], path: &Path) -> Option<ObjError> {
    let count = numbered_lines(bytes).filter(|(_, l)| keyword(l) == b"v").count();
    let parse = |reason: String| ObjError::Parse { path: path.into(), reason };
    face_references(bytes).find_map(|(face, line, index, before)| {
        if index > 0 && index as usize > count {
            Some(ObjError::BadIndex { path: path.into(), face, index: index as usize, count })
        } else if index == 0 {
            Some(parse(format!("face {face} (line {line}) refers to vertex 0, but OBJ vertex numbers start at 1")))
        } else if index < 0 && index.unsigned_abs() > before {
            Some(parse(format!(
                "face {face} (line {line}) refers to relative vertex {index}, but only {before} \
                 vertices are defined before it"
            )))
        } else {
            None
        }
    })
}

/// The first `v` line (1-based vertex number) whose coordinates are not finite once read the
/// way tobj reads them (same float type `T`, divided by the optional weight).
fn first_non_finite_vertex<T>(bytes: &[u8], _like: &[T]) -> Option<(usize, f64)>
where
    T: std::str::FromStr + Copy + Into<f64> + std::ops::Div<Output = T>,
{
    numbered_lines(bytes).filter(|(_, l)| keyword(l) == b"v").enumerate().find_map(|(i, (_, line))| {
        let (w, n) = words::<5>(line);
        let num = |k: usize| -> Option<T> { std::str::from_utf8(&line[w[k].0..w[k].1]).ok()?.parse::<T>().ok() };
        let weight = if n == 5 { num(4) } else { None };
        (1..4).find_map(|k| {
            let mut x = num(k)?;
            if let Some(w) = weight {
                x = x / w;
            }
            let x: f64 = x.into();
            (!x.is_finite()).then_some((i + 1, x))
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    fn write(dir: &tempfile::TempDir, name: &str, contents: impl AsRef<[u8]>) -> PathBuf {
        let path = dir.path().join(name);
        std::fs::write(&path, contents).unwrap();
        path
    }

    fn read_text(text: &str) -> Result<(RawMesh, MeshReport), ObjError> {
        let dir = tempfile::tempdir().unwrap();
        read_obj(&write(&dir, "mesh.obj", text))
    }

    const SQUARE: &str = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n";

    #[test]
    fn triangles_quads_and_polygons_are_fan_triangulated() {
        let text = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0.5 1.5 0\n\
                    f 1 2 3\nf 1 2 3 4\nf 1 2 3 5 4\n";
        let (raw, report) = read_text(text).unwrap();
        assert_eq!(report.vertices_read, 5);
        assert_eq!(report.faces_read, 3);
        assert_eq!(report.polygons_triangulated, 2);
        assert_eq!(report.degenerate_faces_dropped, 0);
        assert_eq!(raw.vertices.len(), 5);
        assert_eq!(raw.vertices[4], Point::new(0.5, 1.5, 0.0));
        assert_eq!(raw.triangles, vec![[0, 1, 2], [0, 1, 2], [0, 2, 3], [0, 1, 2], [0, 2, 4], [0, 4, 3]]);
    }

    #[test]
    fn quad_only_file_becomes_two_triangles() {
        let (raw, report) = read_text(&format!("{SQUARE}f 1 2 3 4\n")).unwrap();
        assert_eq!(raw.triangles, vec![[0, 1, 2], [0, 2, 3]]);
        assert_eq!((report.faces_read, report.polygons_triangulated), (1, 1));
    }

    #[test]
    fn faces_with_fewer_than_three_corners_are_dropped_as_degenerate() {
        let (raw, report) = read_text(&format!("{SQUARE}f 1\nf 1 2\nf\nf 1 2 3\n")).unwrap();
        assert_eq!(raw.triangles, vec![[0, 1, 2]]);
        assert_eq!(report.faces_read, 4);
        assert_eq!(report.degenerate_faces_dropped, 3);
        let err = read_text(&format!("{SQUARE}f 1 2\n")).unwrap_err();
        assert!(matches!(err, ObjError::AllDegenerate { .. }), "{err}");
    }

    #[test]
    fn relative_indices_and_slashed_indices_are_read() {
        let text = "v 0 0 0\nv 1 0 0\nv 1 1 0\nf -3 -2 -1\nvt 0 0\nvn 0 0 1\n\
                    v 0 1 0\nf 1/1/1 3/1/1 4/1/1\nf 1//1 2//1 4//1\n";
        let (raw, report) = read_text(text).unwrap();
        assert_eq!(raw.triangles.len(), 3);
        assert_eq!(raw.vertices.len(), 4);
        assert_eq!(report.vertices_read, 4);
        let tri: Vec<[Point; 3]> = raw.triangles.iter().map(|t| t.map(|i| raw.vertices[i as usize])).collect();
        assert_eq!(tri[0], [Point::new(0., 0., 0.), Point::new(1., 0., 0.), Point::new(1., 1., 0.)]);
        assert_eq!(tri[1][2], Point::new(0., 1., 0.));

        // Raw tobj overflows (panics in debug builds) on this out-of-range texture index.
        let (raw, _) = read_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/-5 2/-5 3/-5\n").unwrap();
        assert_eq!(raw.triangles.len(), 1);
    }

    #[test]
    fn objects_groups_and_other_statements_do_not_split_or_break_the_mesh() {
        // Groups sharing vertices, materials (library missing), polylines, texture and normal
        // indices out of range, inline comments, a weight, vertex colours on some vertices only,
        // Windows line ends and a non-UTF-8 group name.
        let mut text = b"mtllib missing.mtl\r\no part\r\n".to_vec();
        text.extend_from_slice(b"g caf\xe9\r\n");
        text.extend_from_slice(
            b"v 0 0 0 # origin\r\nv 2 0 0 2\r\nv 1 1 0 1 0 0\r\nv 0 1 0\r\nvt 0 0\r\nvn 0 0 1\r\n\
              usemtl steel\r\nf 1/7/9 2/7/9 3/7/9\r\ng other\r\nl 1 2 3 4\r\ns off\r\n\
              f 1/0 3/0 4/0 # second\r\np 1\r\n",
        );
        let dir = tempfile::tempdir().unwrap();
        let (raw, report) = read_obj(&write(&dir, "mixed.obj", &text)).unwrap();
        assert_eq!(report.vertices_read, 4);
        assert_eq!(report.faces_read, 2);
        assert_eq!(raw.vertices.len(), 4, "shared vertices stay shared across groups");
        assert_eq!(raw.triangles, vec![[0, 1, 2], [0, 2, 3]]);
        assert_eq!(raw.vertices[1], Point::new(1.0, 0.0, 0.0), "weight w divides");
        assert_eq!(raw.vertices[2], Point::new(1.0, 1.0, 0.0), "colour is not a weight");

        // Old Mac line ends.
        let (raw, _) = read_text(&format!("{SQUARE}f 1 2 3 4\n").replace('\n', "\r")).unwrap();
        assert_eq!(raw.triangles.len(), 2);
    }

    #[test]
    fn non_finite_coordinate_is_refused_with_its_vertex_number() {
        let err = read_text("v 0 0 0\nv 1 0 0\nv 1 nan 0\nf 1 2 3\n").unwrap_err();
        match err {
            ObjError::NonFinite { index, value, .. } => {
                assert_eq!(index, 3);
                assert!(value.is_nan());
            }
            e => panic!("expected NonFinite, got {e}"),
        }
        let err = read_text("v 0 0 0\nv 1 0 -inf\nv 1 1 0\nf 1 2 3\n").unwrap_err();
        assert!(matches!(err, ObjError::NonFinite { index: 2, value, .. } if value == f64::NEG_INFINITY), "{err}");
        // Unused non-finite vertices are harmless.
        assert!(read_text("v 0 0 0\nv 1 0 0\nv 1 1 0\nv nan 0 0\nf 1 2 3\n").is_ok());
    }

    #[test]
    fn out_of_range_index_is_refused() {
        let err = read_text(&format!("{SQUARE}f 1 2 3\nf 1 3 7\n")).unwrap_err();
        assert!(matches!(err, ObjError::BadIndex { face: 2, index: 7, count: 4, .. }), "{err}");
        assert!(err.to_string().contains("face 2 refers to vertex 7"), "{err}");

        let err = read_text(&format!("{SQUARE}f 0 1 2\n")).unwrap_err();
        assert!(matches!(err, ObjError::Parse { .. }), "{err}");
        assert!(err.to_string().contains("start at 1"), "{err}");

        let err = read_text("v 0 0 0\nv 1 0 0\nf -1 -2 -3\nv 1 1 0\n").unwrap_err();
        assert!(matches!(err, ObjError::Parse { .. }), "{err}");
        assert!(err.to_string().contains("relative vertex -3"), "{err}");
    }

    #[test]
    fn unparsable_lines_are_refused_with_their_line_number() {
        let err = read_text("v 0 0 0\nv 1 zero 0\n").unwrap_err();
        assert!(matches!(err, ObjError::Parse { .. }), "{err}");
        assert!(err.to_string().contains("line 2"), "{err}");
        let err = read_text(&format!("{SQUARE}f 1 2 3\nf 1 2 x\n")).unwrap_err();
        assert!(err.to_string().contains("line 6"), "{err}");
        let err = read_text("v 0 0 0 0\n").unwrap_err();
        assert!(err.to_string().contains("line 1"), "{err}");
    }

    #[test]
    fn file_without_faces_is_refused() {
        for text in ["", "# only a comment\n", SQUARE, "l 1 2\n", "hello\nworld\n"] {
            let err = read_text(text).unwrap_err();
            assert!(matches!(err, ObjError::Empty { .. }), "{text:?}: {err}");
        }
    }

    #[test]
    fn missing_file_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let err = read_obj(&dir.path().join("nope.obj")).unwrap_err();
        assert!(matches!(err, ObjError::Io { .. }), "{err}");
        assert!(err.to_string().contains("nope.obj"), "{err}");
        let err = read_obj(dir.path()).unwrap_err();
        assert!(matches!(err, ObjError::Io { .. }), "{err}");
    }

    #[test]
    fn binary_and_garbage_files_are_refused_without_panic() {
        let dir = tempfile::tempdir().unwrap();
        // Binary STL-like header with NUL bytes.
        let mut stl = b"solid part".to_vec();
        stl.resize(84, 0);
        stl.extend_from_slice(&[0x3f; 50]);
        let err = read_obj(&write(&dir, "part.stl", &stl)).unwrap_err();
        assert!(matches!(err, ObjError::Parse { .. }), "{err}");
        assert!(err.to_string().contains("binary"), "{err}");

        // Not UTF-8 where it matters.
        let err = read_obj(&write(&dir, "latin.obj", b"v 0 0 0\nv 1\xff 0 0\n")).unwrap_err();
        assert!(matches!(err, ObjError::Parse { .. }), "{err}");

        // Random bytes and random OBJ-like words: refused (or, by chance, read), never a panic.
        let mut state = 0x2545_f491_4f6c_dd1d_u64;
        let mut rnd = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        let tokens = ["v", "f", "vt", "l", "1", "-1", "0", "2/3", "//", "/", "1e40", "nan", "\n"];
        for round in 0..240 {
            let bytes: Vec<u8> = match round % 3 {
                0 => (0..200).map(|_| (rnd() % 256) as u8).collect(),
                1 => (0..200).map(|_| (rnd() % 255 + 1) as u8).collect(),
                _ => {
                    let words: Vec<&str> = (0..60).map(|_| tokens[(rnd() % tokens.len() as u64) as usize]).collect();
                    words.join(" ").into_bytes()
                }
            };
            let path = write(&dir, &format!("garbage{round}.obj"), &bytes);
            match read_obj(&path) {
                Ok(_)
                | Err(ObjError::Parse { .. })
                | Err(ObjError::Empty { .. })
                | Err(ObjError::BadIndex { .. })
                | Err(ObjError::NonFinite { .. })
                | Err(ObjError::AllDegenerate { .. }) => {}
                Err(e) => panic!("unexpected error {e}"),
            }
        }
    }

    #[test]
    fn tool_surface_from_obj_answers_closest_point_queries() {
        let dir = tempfile::tempdir().unwrap();
        let path = write(&dir, "square.obj", format!("{SQUARE}f 1 2 3\nf 1 3 4\n"));
        let surface = crate::geometry::ToolSurface::from_obj(&path).unwrap();
        assert_eq!(surface.num_triangles(), 2);
        assert_eq!(surface.report().boundary_edges, 4);
        let cases = [
            (Point::new(0.8, 0.2, 0.5), Point::new(0.8, 0.2, 0.0), 0),
            (Point::new(0.2, 0.7, -0.3), Point::new(0.2, 0.7, 0.0), 1),
            (Point::new(2.0, 0.5, 0.0), Point::new(1.0, 0.5, 0.0), 0),
            (Point::new(-1.0, 0.5, 1.0), Point::new(0.0, 0.5, 0.0), 1),
        ];
        for (query, expected, triangle) in cases {
            let sp = surface.closest_point(&query);
            assert!((sp.point - expected).norm() < 1e-12, "{query}: {sp:?}");
            assert_eq!(sp.triangle, triangle, "{query}");
            assert!((sp.distance - (query - expected).norm()).abs() < 1e-12);
            assert!((sp.normal.z.abs() - 1.0).abs() < 1e-12);
        }
    }
}
