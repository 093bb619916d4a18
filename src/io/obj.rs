//! Wavefront OBJ: one parser ([`parse`]) for tools ([`read_obj`]) and flow meshes ([`read`]),
//! and the writer of a triangle mesh ([`TriangleMesh::to_obj_string`]).
//!
//! Only `v` and `f` statements matter: `v x y z`, optionally followed by a weight w that
//! divides the coordinates (not 0) or by a colour r g b; `f` with vertex numbers (`a`, `a/t`,
//! `a//n`, `a/t/n`; negative numbers count back from the last vertex read, positive ones may
//! refer to vertices further down the file). Normals, texture coordinates, groups, objects,
//! materials, smoothing and comments (`#`) are ignored, so every group and object of a file is
//! one mesh keeping the file's vertex numbering. A line ending in `\` continues on the next.
//! Lines end at `\n`, `\r\n` or a lone `\r`.
//!
//! A tool ([`read_obj`]): every polygon is fanned into triangles from its first corner, faces of
//! fewer than three corners are dropped and counted as degenerate, and vertices no face uses
//! are left out (numbered in the order faces first use them), so a stray non-finite vertex that
//! no face uses is harmless. A flow mesh ([`read`]): every vertex is a node whose id is its
//! number (from 1), triangles and quads are kept as they are, larger polygons are fanned into
//! triangles, a face of fewer than three corners is an error; element ids number the elements
//! from 1 in output order (the face number as long as no polygon was split), every property 0.
use super::shell_mesh::{read_bytes, Builder, FlowMeshError, Loc};
use crate::geometry::{MeshReport, Point, ToolError, TriangleMesh};
use crate::mapping::FlowMesh;
use std::fmt::Write as _;
use std::path::Path;

/// OBJ as a shell-mesh format.
pub const FORMAT: super::MeshFormat = super::MeshFormat { name: "OBJ", extensions: &["obj"], read };

/// The `v` and `f` statements of an OBJ text.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ObjText {
    /// Vertices in file order, divided by their weight, with the line of each.
    pub vertices: Vec<([f64; 3], usize)>,
    /// Faces in file order.
    pub faces: Vec<ObjFace>,
    /// The corners of all faces, face after face (see [`ObjFace::corners`]): vertex numbers
    /// from 1, relative numbers resolved; not checked against the vertex count (a face may
    /// refer to a vertex further down the file). One array instead of one per face, so a
    /// large file is read without an allocation per face.
    pub corners: Vec<u64>,
    /// `l` (polyline) statements, which are not surfaces.
    pub lines: usize,
    /// `p` (point) statements, which are not surfaces.
    pub points: usize,
}

impl ObjText {
    /// The vertex numbers of `face`, in order.
    pub fn face_corners(&self, face: &ObjFace) -> &[u64] {
        &self.corners[face.corners.clone()]
    }
}

/// One `f` statement.
#[derive(Debug, Clone, PartialEq)]
pub struct ObjFace {
    /// Where its vertex numbers are in [`ObjText::corners`].
    pub corners: std::ops::Range<usize>,
    /// Its line in the file.
    pub line: usize,
}

/// Why an OBJ text could not be parsed: the line (0 for the whole file) and what is wrong.
#[derive(Debug, Clone, PartialEq)]
pub struct ObjSyntaxError {
    /// 1-based line, 0 when the whole file is at fault.
    pub line: usize,
    /// What is wrong and what a valid statement looks like.
    pub message: String,
}

/// Parse the statements of an OBJ file's bytes (see the module documentation).
///
/// Lines of ASCII text that do not continue on the next one (nearly all lines of nearly all
/// files) are read from the bytes as they are, with no allocation; a line with other bytes
/// (read as UTF-8, invalid sequences replaced) or a continued line goes through the same
/// statement reading as text. Both give the same statements and the same errors (tested).
/// A large text is read in pieces in parallel ([`parse_pieces`]), with the same result.
pub fn parse(bytes: &[u8]) -> Result<ObjText, ObjSyntaxError> {
    Ok(parse_pieces(bytes, PIECE)?.into_text())
}

/// Texts longer than this are read in pieces of about this many bytes, in parallel.
const PIECE: usize = 1 << 19;

/// [`parse`], with the byte path for ASCII lines or (`fast` false) every line read as text, all
/// in one piece.
fn parse_with(bytes: &[u8], fast: bool) -> Result<ObjText, ObjSyntaxError> {
    refuse_binary(bytes)?;
    let mut text = ObjText::default();
    read_statements(bytes, fast, &mut text, &mut None)?;
    Ok(text)
}

/// A NUL byte means a binary file.
fn refuse_binary(bytes: &[u8]) -> Result<(), ObjSyntaxError> {
    match memchr::memchr(0, bytes) {
        Some(_) => Err(ObjSyntaxError {
            line: 0,
            message: "it is a binary file, not a text (Wavefront) OBJ; binary STL, zipped or native CAD files cannot be read"
                .into(),
        }),
        None => Ok(()),
    }
}

/// Add the statements of `bytes` to `text`, lines numbered from 1; the number of lines.
/// `back`: see [`resolve`].
fn read_statements(
    bytes: &[u8],
    fast: bool,
    text: &mut ObjText,
    back: &mut Option<Vec<CountBack>>,
) -> Result<usize, ObjSyntaxError> {
    let mut joined: Option<(usize, String)> = None;
    let mut count = 0;
    for (number, raw) in lines(bytes) {
        count = number;
        // Everything from the first `#` on is a comment. (`#` is ASCII, so cutting the bytes
        // there and then reading them as UTF-8 gives the text before the `#` of the line read
        // as UTF-8.)
        let content = &raw[..memchr::memchr(b'#', raw).unwrap_or(raw.len())];
        if fast && joined.is_none() && content.is_ascii() {
            // ASCII bytes are valid UTF-8, and every word boundary below is an ASCII byte.
            let line = std::str::from_utf8(content).unwrap_or_default();
            if !line.trim_end_matches(is_space).ends_with('\\') {
                statement(line, ascii_words(line), number, text, back)?;
                continue;
            }
        }
        let raw = String::from_utf8_lossy(content);
        let (start, mut line) = joined.take().unwrap_or((number, String::new()));
        if let Some(head) = raw.trim_end().strip_suffix('\\') {
            line.push_str(head);
            line.push(' ');
            joined = Some((start, line));
            continue;
        }
        line.push_str(&raw);
        statement(&line, line.split_whitespace(), start, text, back)?;
    }
    if let Some((start, line)) = joined {
        statement(&line, line.split_whitespace(), start, text, back)?;
    }
    Ok(count)
}

/// A corner that counts back from the last vertex read, in a piece read on its own: where it is
/// in the piece's corners, how far back it counts and how many vertices the piece had read.
#[derive(Debug, Clone, Copy)]
struct CountBack {
    corner: usize,
    back: u64,
    read: u64,
}

/// An OBJ text read in pieces ([`parse_pieces`]): each piece's statements as [`ObjText`]s, with
/// line and vertex numbers those of the whole text, each face's corners in its own piece.
struct Pieces {
    texts: Vec<ObjText>,
    /// How many vertices the pieces before each piece have.
    vertices_before: Vec<usize>,
}

impl Pieces {
    /// One text.
    fn whole(text: ObjText) -> Pieces {
        Pieces { texts: vec![text], vertices_before: vec![0] }
    }

    /// The pieces put together.
    fn into_text(self) -> ObjText {
        let mut texts = self.texts.into_iter();
        let mut all = texts.next().unwrap_or_default();
        for text in texts {
            let shift = all.corners.len();
            all.vertices.extend_from_slice(&text.vertices);
            all.faces.extend(text.faces.into_iter().map(|f| ObjFace { corners: f.corners.start + shift..f.corners.end + shift, ..f }));
            all.corners.extend_from_slice(&text.corners);
            all.lines += text.lines;
            all.points += text.points;
        }
        all
    }

    /// The number of vertices read.
    fn vertex_count(&self) -> usize {
        self.vertices_before.last().copied().unwrap_or(0) + self.texts.last().map_or(0, |t| t.vertices.len())
    }

    /// Vertex `k` (from 0; less than [`Self::vertex_count`]) and its line.
    fn vertex(&self, k: usize) -> ([f64; 3], usize) {
        let piece = self.vertices_before.partition_point(|&before| before <= k) - 1;
        self.texts[piece].vertices[k - self.vertices_before[piece]]
    }
}

/// [`parse`] in pieces of about `piece` bytes (cut after a line end, never inside a continued
/// line), each read on its own in parallel and then numbered as in the whole text: its lines
/// counted on from the pieces before it, corners that count back resolved against all
/// vertices before them. Any error in any piece, or a corner counting back past the first
/// vertex, and the whole text is read again in one piece, so errors are those of one reading.
fn parse_pieces(bytes: &[u8], piece: usize) -> Result<Pieces, ObjSyntaxError> {
    use rayon::prelude::*;
    refuse_binary(bytes)?;
    let bounds = piece_bounds(bytes, piece);
    let whole = || parse_with(bytes, true).map(Pieces::whole);
    if bounds.len() <= 2 {
        return whole();
    }
    let read: Vec<Option<(ObjText, usize, Vec<CountBack>)>> = bounds
        .par_windows(2)
        .map(|w| {
            // Room for as many statements as the piece can hold (`v 0 0 0` and `f 1 2 3` lines
            // of 8 bytes): memory is only taken where written, and the arrays never move.
            let n = (w[1] - w[0]) / 8 + 1;
            let mut text = ObjText {
                vertices: Vec::with_capacity(n),
                faces: Vec::with_capacity(n),
                corners: Vec::with_capacity(3 * n),
                ..Default::default()
            };
            let mut back = Some(Vec::new());
            let lines = read_statements(&bytes[w[0]..w[1]], true, &mut text, &mut back).ok()?;
            Some((text, lines, back.unwrap_or_default()))
        })
        .collect();
    let Some(read) = read.into_iter().collect::<Option<Vec<_>>>() else {
        return whole();
    };
    // Lines and vertices before each piece.
    let mut before = Vec::with_capacity(read.len());
    let (mut lines, mut vertices) = (0, 0);
    for (text, count, back) in &read {
        if back.iter().any(|b| b.back > (vertices + b.read as usize) as u64) {
            return whole();
        }
        before.push((lines, vertices));
        lines += count;
        vertices += text.vertices.len();
    }
    let texts: Vec<ObjText> = read
        .into_par_iter()
        .zip(&before)
        .map(|((mut text, _, back), &(lines, vertices))| {
            text.vertices.iter_mut().for_each(|v| v.1 += lines);
            text.faces.iter_mut().for_each(|f| f.line += lines);
            for b in back {
                text.corners[b.corner] = vertices as u64 + b.read + 1 - b.back;
            }
            text
        })
        .collect();
    Ok(Pieces { texts, vertices_before: before.into_iter().map(|(_, v)| v).collect() })
}

/// Where the pieces of [`parse_pieces`] begin, and the end: each after the first line end
/// (`\n`) at least `piece` bytes after the start of the piece before it, whose line does not
/// continue on the next.
fn piece_bounds(bytes: &[u8], piece: usize) -> Vec<usize> {
    let mut bounds = vec![0];
    let mut at = piece.max(1);
    while at < bytes.len() {
        let Some(end) = memchr::memchr(b'\n', &bytes[at..]).map(|i| at + i) else { break };
        // The line this `\n` ends (with the `\r` of `\r\n`: a `\r` before a `\n` is always one).
        let stop = if end > 0 && bytes[end - 1] == b'\r' { end - 1 } else { end };
        let start = memchr::memrchr2(b'\n', b'\r', &bytes[..stop]).map_or(0, |i| i + 1);
        let line = &bytes[start..stop];
        // The text path's test of a continued line (which the byte path agrees with, tested).
        let content = &line[..memchr::memchr(b'#', line).unwrap_or(line.len())];
        if String::from_utf8_lossy(content).trim_end().ends_with('\\') {
            at = end + 1;
            continue;
        }
        if end + 1 < bytes.len() {
            bounds.push(end + 1);
        }
        at = end + 1 + piece;
    }
    bounds.push(bytes.len());
    bounds
}

/// The lines of `bytes` with their 1-based numbers; `\n`, `\r\n` and a lone `\r` end a line.
fn lines(bytes: &[u8]) -> impl Iterator<Item = (usize, &[u8])> {
    let mut rest = bytes;
    let mut number = 0;
    std::iter::from_fn(move || {
        if rest.is_empty() {
            return None;
        }
        number += 1;
        let end = memchr::memchr2(b'\n', b'\r', rest).unwrap_or(rest.len());
        let line = &rest[..end];
        let skip = match (rest.get(end), rest.get(end + 1)) {
            (Some(b'\r'), Some(b'\n')) => 2,
            (Some(_), _) => 1,
            (None, _) => 0,
        };
        rest = &rest[end + skip..];
        Some((number, line))
    })
}

/// The ASCII characters that are white space to [`char::is_whitespace`] and can occur inside
/// a line (line ends cannot).
#[inline]
fn is_space(c: char) -> bool {
    matches!(c, ' ' | '\t' | '\x0b' | '\x0c')
}

/// The words of an ASCII line, split at white space as [`str::split_whitespace`] splits it.
#[inline]
fn ascii_words(line: &str) -> impl Iterator<Item = &str> {
    line.split([' ', '\t', '\x0b', '\x0c']).filter(|w| !w.is_empty())
}

/// Add one statement to `text`: `line` (a whole line, continuations joined) split into `words`,
/// either at ASCII white space ([`ascii_words`], a line of ASCII text read from the bytes) or at
/// any white space (`str::split_whitespace`, the text path), which split an ASCII line alike:
/// one reading of the statements for both paths, without allocating.
fn statement<'a>(
    line: &str,
    mut words: impl Iterator<Item = &'a str>,
    number: usize,
    text: &mut ObjText,
    back: &mut Option<Vec<CountBack>>,
) -> Result<(), ObjSyntaxError> {
    match words.next() {
        Some("v") => {
            let mut numbers = [0.0; 6];
            let mut count = 0;
            let mut valid = true;
            for w in words {
                match w.parse::<f64>() {
                    Ok(x) if count < 6 => numbers[count] = x,
                    Ok(_) => {}
                    Err(_) => valid = false,
                }
                count += 1;
            }
            let xyz = match (valid, count) {
                (true, 3 | 6) => [numbers[0], numbers[1], numbers[2]],
                (true, 4) if numbers[3] != 0.0 => {
                    let w = numbers[3];
                    [numbers[0] / w, numbers[1] / w, numbers[2] / w]
                }
                _ => return Err(vertex_error(line, number)),
            };
            text.vertices.push((xyz, number));
        }
        Some("f") => {
            let start = text.corners.len();
            for word in words {
                // Most words are plain vertex numbers.
                if let Some(i) = small_number(word) {
                    let vertex = resolve(i, text, number, back)?;
                    text.corners.push(vertex);
                    continue;
                }
                let mut parts = word.split('/');
                let first = parts.next().unwrap_or_default();
                let mut count = 1;
                let mut well_formed = true;
                for part in parts {
                    count += 1;
                    well_formed &= part.is_empty() || part.parse::<i64>().is_ok();
                }
                let Some(i) = first.parse::<i64>().ok().filter(|_| well_formed && count <= 3) else {
                    return Err(face_error(line, number));
                };
                let vertex = resolve(i, text, number, back)?;
                text.corners.push(vertex);
            }
            text.faces.push(ObjFace { corners: start..text.corners.len(), line: number });
        }
        Some("l") => text.lines += 1,
        Some("p") => text.points += 1,
        _ => {}
    }
    Ok(())
}

/// A word of 1 to 18 ASCII digits as a number (what `i64` parsing gives it), else `None`.
#[inline]
fn small_number(word: &str) -> Option<i64> {
    if word.is_empty() || word.len() > 18 {
        return None;
    }
    let mut n = 0i64;
    for &c in word.as_bytes() {
        let d = c.wrapping_sub(b'0');
        if d > 9 {
            return None;
        }
        n = n * 10 + i64::from(d);
    }
    Some(n)
}

/// The error of a `v` statement that is not three numbers, optionally with a weight or colour.
fn vertex_error(line: &str, number: usize) -> ObjSyntaxError {
    ObjSyntaxError {
        line: number,
        message: format!(
            "{}: a vertex is `v x y z` with three numbers, optionally followed by a weight w other than 0 or by a colour r g b",
            quote(line)
        ),
    }
}

/// The error of an `f` statement with a word that is not a vertex reference.
fn face_error(line: &str, number: usize) -> ObjSyntaxError {
    ObjSyntaxError {
        line: number,
        message: format!(
            "{}: a face is `f` followed by vertex numbers, such as `f 1 2 3` or `f 1/1/1 2/2/2 3/3/3`",
            quote(line)
        ),
    }
}

/// The vertex number (from 1) that the face reference `i` of the face being read (the next
/// one of `text`) on line `number` means: positive numbers as they are, negative ones counted
/// back from the last vertex read. In a piece read on its own (`back` given), a negative one is
/// noted in `back` and stands as 0 until the vertices before the piece are counted.
#[inline]
fn resolve(i: i64, text: &ObjText, number: usize, back: &mut Option<Vec<CountBack>>) -> Result<u64, ObjSyntaxError> {
    let read_so_far = text.vertices.len() as u64;
    match i {
        i if i > 0 => Ok(i as u64),
        i if i < 0 && back.is_some() => {
            let b = CountBack { corner: text.corners.len(), back: i.unsigned_abs(), read: read_so_far };
            back.iter_mut().for_each(|v| v.push(b));
            Ok(0)
        }
        0 => Err(ObjSyntaxError {
            line: number,
            message: format!("face {} refers to vertex 0, but OBJ vertex numbers start at 1", text.faces.len() + 1),
        }),
        i if i.unsigned_abs() <= read_so_far => Ok(read_so_far + 1 - i.unsigned_abs()),
        i => Err(ObjSyntaxError {
            line: number,
            message: format!(
                "face {} refers to relative vertex {i}, but only {read_so_far} vertices are defined before it",
                text.faces.len() + 1
            ),
        }),
    }
}

/// A line, shortened for an error message.
fn quote(line: &str) -> String {
    let text = line.trim();
    match text.char_indices().nth(60) {
        Some((cut, _)) => format!("`{}...`", &text[..cut]),
        None => format!("`{text}`"),
    }
}

/// Read an OBJ file as a tool: its triangles (see the module documentation) and what was found
/// on the way. Refuses an unreadable or unparsable file, one without faces or with only
/// degenerate ones, a face referring to a vertex the file does not have, and a used vertex
/// with a non-finite coordinate.
pub fn read_obj(path: &Path) -> Result<(TriangleMesh, MeshReport), ToolError> {
    let bytes = super::read::read_file(path).map_err(|source| ToolError::Io { path: path.into(), source })?;
    // The pieces as they are: putting them together would copy every statement once more.
    let text = parse_pieces(&bytes, PIECE).map_err(|e| ToolError::Parse {
        path: path.into(),
        reason: if e.line == 0 { e.message } else { format!("line {}: {}", e.line, e.message) },
    })?;
    drop(bytes);
    let mut report = MeshReport { vertices_read: text.vertex_count(), ..Default::default() };
    let mesh = tool_mesh(&text, path, &mut report)?;
    Ok((mesh, report))
}

/// What [`tool_mesh`] finds in one piece's faces: the vertices its faces use first (before any
/// other face of the piece), with where in the piece's corners, and its first corner naming a
/// vertex the file does not have (face in the piece, vertex number, where in the corners).
struct PieceUse {
    first_use: Vec<(u32, usize)>,
    bad: Option<(usize, u64, usize)>,
    triangles: usize,
}

/// The tool's triangles from the faces of `text` (see the module documentation): polygons
/// fanned, faces of fewer than three corners dropped, vertices in the order the faces first
/// use them; the counts go into `report`. Each piece's faces are read in parallel (the
/// vertices they use first, their first bad corner), then the pieces' first uses are taken in
/// order (the numbering, and the first error of the faces read in order: a corner naming a
/// vertex the file does not have, or a non-finite vertex used), then the triangles written in
/// parallel: the mesh and errors of one reading in order ([`tool_mesh_serial`], tested).
fn tool_mesh(text: &Pieces, path: &Path, report: &mut MeshReport) -> Result<TriangleMesh, ToolError> {
    use rayon::prelude::*;
    let count = text.vertex_count();
    let faces: usize = text.texts.iter().map(|t| t.faces.len()).sum();
    report.faces_read = faces;
    if faces == 0 {
        return Err(ToolError::Empty { path: path.into() });
    }
    let uses: Vec<PieceUse> = text
        .texts
        .par_iter()
        .map(|t| {
            let mut seen = vec![0u64; count.div_ceil(64)];
            let mut first_use = Vec::new();
            let mut bad = None;
            let mut triangles = 0;
            'faces: for (f, face) in t.faces.iter().enumerate() {
                for (c, &v) in t.face_corners(face).iter().enumerate() {
                    let at = face.corners.start + c;
                    let k = match (v as usize).checked_sub(1).filter(|&k| k < count) {
                        Some(k) => k,
                        None => {
                            bad = Some((f, v, at));
                            break 'faces;
                        }
                    };
                    if seen[k / 64] & (1 << (k % 64)) == 0 {
                        seen[k / 64] |= 1 << (k % 64);
                        first_use.push((k as u32, at));
                    }
                }
                triangles += face.corners.len().saturating_sub(2);
            }
            PieceUse { first_use, bad, triangles }
        })
        .collect();
    // The vertices in the order of first use, and the first error in the order of reading.
    let mut index = vec![u32::MAX; count];
    let mut order: Vec<u32> = Vec::with_capacity(count);
    let mut faces_before = 0;
    for (t, u) in text.texts.iter().zip(&uses) {
        let bad_at = u.bad.map_or(usize::MAX, |(_, _, at)| at);
        for &(k, _) in u.first_use.iter().take_while(|&&(_, at)| at < bad_at) {
            if index[k as usize] == u32::MAX {
                let ([x, y, z], _) = text.vertex(k as usize);
                if let Some(&value) = [x, y, z].iter().find(|c| !c.is_finite()) {
                    return Err(ToolError::NonFinite { path: path.into(), index: k as usize + 1, value });
                }
                index[k as usize] = order.len() as u32;
                order.push(k);
            }
        }
        if let Some((f, v, _)) = u.bad {
            return Err(ToolError::BadIndex { path: path.into(), face: faces_before + f + 1, index: v as usize, count });
        }
        faces_before += t.faces.len();
    }
    let vertices: Vec<Point> = order
        .par_iter()
        .with_min_len(1 << 12)
        .map(|&k| {
            let ([x, y, z], _) = text.vertex(k as usize);
            Point::new(x, y, z)
        })
        .collect();
    drop(order);
    // Each piece's triangles in its own part of the array.
    let mut triangles = vec![[0u32; 3]; uses.iter().map(|u| u.triangles).sum()];
    let mut parts = Vec::with_capacity(uses.len());
    let mut rest = triangles.as_mut_slice();
    for u in &uses {
        let (part, tail) = rest.split_at_mut(u.triangles);
        parts.push(part);
        rest = tail;
    }
    let counts: Vec<(usize, usize)> = text
        .texts
        .par_iter()
        .zip(parts)
        .map(|(t, part)| {
            let (mut degenerate, mut polygons, mut next) = (0, 0, 0);
            for face in &t.faces {
                let corners = t.face_corners(face);
                match corners.len() {
                    0..=2 => degenerate += 1,
                    n => {
                        polygons += usize::from(n > 3);
                        let a = index[corners[0] as usize - 1];
                        for pair in corners[1..].windows(2) {
                            part[next] = [a, index[pair[0] as usize - 1], index[pair[1] as usize - 1]];
                            next += 1;
                        }
                    }
                }
            }
            (degenerate, polygons)
        })
        .collect();
    report.degenerate_faces_dropped = counts.iter().map(|c| c.0).sum();
    report.polygons_triangulated = counts.iter().map(|c| c.1).sum();
    if triangles.is_empty() {
        return Err(ToolError::AllDegenerate { path: path.into() });
    }
    Ok(TriangleMesh { vertices, triangles })
}

/// [`tool_mesh`] in one pass over the faces in order: what it must give.
#[cfg(test)]
fn tool_mesh_serial(text: &Pieces, path: &Path, report: &mut MeshReport) -> Result<TriangleMesh, ToolError> {
    let count = text.vertex_count();
    let faces = text.texts.iter().map(|t| t.faces.len()).sum();
    report.faces_read = faces;
    if faces == 0 {
        return Err(ToolError::Empty { path: path.into() });
    }
    // Vertices in the order the faces first use them.
    let mut index = vec![u32::MAX; count];
    let mut mesh = TriangleMesh { vertices: Vec::with_capacity(count), triangles: Vec::with_capacity(faces) };
    let mut corners = Vec::with_capacity(8);
    let all_faces = text.texts.iter().flat_map(|t| t.faces.iter().map(move |face| t.face_corners(face)));
    for (f, face) in all_faces.enumerate() {
        corners.clear();
        for &v in face {
            let k = (v as usize).checked_sub(1).filter(|&k| k < count).ok_or(ToolError::BadIndex {
                path: path.into(),
                face: f + 1,
                index: v as usize,
                count,
            })?;
            if index[k] == u32::MAX {
                let ([x, y, z], _) = text.vertex(k);
                if let Some(&value) = [x, y, z].iter().find(|c| !c.is_finite()) {
                    return Err(ToolError::NonFinite { path: path.into(), index: k + 1, value });
                }
                index[k] = mesh.vertices.len() as u32;
                mesh.vertices.push(Point::new(x, y, z));
            }
            corners.push(index[k]);
        }
        match corners.len() {
            0..=2 => report.degenerate_faces_dropped += 1,
            n => {
                if n > 3 {
                    report.polygons_triangulated += 1;
                }
                for pair in corners[1..].windows(2) {
                    mesh.triangles.push([corners[0], pair[0], pair[1]]);
                }
            }
        }
    }
    if mesh.triangles.is_empty() {
        return Err(ToolError::AllDegenerate { path: path.into() });
    }
    Ok(mesh)
}

/// Read an OBJ file as a flow mesh (see the module documentation); lengths multiplied by `scale`.
pub fn read(path: &Path, scale: f64) -> Result<FlowMesh, FlowMeshError> {
    let mut b = Builder::new(path, scale)?;
    let bytes = read_bytes(path)?;
    let text = parse(&bytes).map_err(|e| match e.line {
        0 => FlowMeshError::Invalid { path: path.into(), message: e.message },
        line => FlowMeshError::Syntax { path: path.into(), line, message: e.message },
    })?;
    for (k, &(xyz, line)) in text.vertices.iter().enumerate() {
        b.add_node(k as u64 + 1, xyz, Loc { file: 0, line })?;
    }
    let mut next_element: u64 = 1;
    for face in &text.faces {
        let loc = Loc { file: 0, line: face.line };
        let c = text.face_corners(face);
        match c.len() {
            3 | 4 => {
                b.add_element(next_element, c, 0, loc)?;
                next_element += 1;
            }
            n if n > 4 => {
                for k in 1..n - 1 {
                    b.add_element(next_element, &[c[0], c[k], c[k + 1]], 0, loc)?;
                    next_element += 1;
                }
            }
            n => return Err(b.syntax(loc, format!("face with {n} corners: a face needs at least 3"))),
        }
    }
    for _ in 0..text.lines {
        b.skip("line (l)");
    }
    for _ in 0..text.points {
        b.skip("point (p)");
    }
    b.finish("f faces with 3 or more corners")
}

impl TriangleMesh {
    /// Wavefront OBJ text: a comment line with the counts, one `v x y z` line per vertex (`{}`
    /// formatting of `f64`, the shortest text that reads back to the same number) and one
    /// `f i j k` line per triangle (1-based indices, as OBJ requires).
    pub fn to_obj_string(&self) -> String {
        let mut s = String::with_capacity(self.vertices.len() * 60 + self.triangles.len() * 24);
        let _ = writeln!(s, "# {} vertices, {} triangles", self.vertices.len(), self.triangles.len());
        for v in &self.vertices {
            let _ = writeln!(s, "v {} {} {}", v.x, v.y, v.z);
        }
        for t in &self.triangles {
            let _ = writeln!(s, "f {} {} {}", t[0] + 1, t[1] + 1, t[2] + 1);
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Point;
    use std::path::PathBuf;

    fn write(dir: &tempfile::TempDir, name: &str, contents: impl AsRef<[u8]>) -> PathBuf {
        let path = dir.path().join(name);
        std::fs::write(&path, contents).unwrap();
        path
    }

    fn read_text(text: &str) -> Result<(TriangleMesh, MeshReport), ToolError> {
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
        assert!(matches!(err, ToolError::AllDegenerate { .. }), "{err}");
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

        // An out-of-range texture index is not read (tobj, the reader before, overflowed on it).
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
            ToolError::NonFinite { index, value, .. } => {
                assert_eq!(index, 3);
                assert!(value.is_nan());
            }
            e => panic!("expected NonFinite, got {e}"),
        }
        let err = read_text("v 0 0 0\nv 1 0 -inf\nv 1 1 0\nf 1 2 3\n").unwrap_err();
        assert!(matches!(err, ToolError::NonFinite { index: 2, value, .. } if value == f64::NEG_INFINITY), "{err}");
        // Unused non-finite vertices are harmless.
        assert!(read_text("v 0 0 0\nv 1 0 0\nv 1 1 0\nv nan 0 0\nf 1 2 3\n").is_ok());
    }

    #[test]
    fn out_of_range_index_is_refused() {
        let err = read_text(&format!("{SQUARE}f 1 2 3\nf 1 3 7\n")).unwrap_err();
        assert!(matches!(err, ToolError::BadIndex { face: 2, index: 7, count: 4, .. }), "{err}");
        assert!(err.to_string().contains("face 2 refers to vertex 7"), "{err}");

        let err = read_text(&format!("{SQUARE}f 0 1 2\n")).unwrap_err();
        assert!(matches!(err, ToolError::Parse { .. }), "{err}");
        assert!(err.to_string().contains("start at 1"), "{err}");

        let err = read_text("v 0 0 0\nv 1 0 0\nf -1 -2 -3\nv 1 1 0\n").unwrap_err();
        assert!(matches!(err, ToolError::Parse { .. }), "{err}");
        assert!(err.to_string().contains("relative vertex -3"), "{err}");
    }

    #[test]
    fn unparsable_lines_are_refused_with_their_line_number() {
        let err = read_text("v 0 0 0\nv 1 zero 0\n").unwrap_err();
        assert!(matches!(err, ToolError::Parse { .. }), "{err}");
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
            assert!(matches!(err, ToolError::Empty { .. }), "{text:?}: {err}");
        }
    }

    #[test]
    fn missing_file_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let err = read_obj(&dir.path().join("nope.obj")).unwrap_err();
        assert!(matches!(err, ToolError::Io { .. }), "{err}");
        assert!(err.to_string().contains("nope.obj"), "{err}");
        let err = read_obj(dir.path()).unwrap_err();
        assert!(matches!(err, ToolError::Io { .. }), "{err}");
    }

    #[test]
    fn binary_and_garbage_files_are_refused_without_panic() {
        let dir = tempfile::tempdir().unwrap();
        // Binary STL-like header with NUL bytes.
        let mut stl = b"solid part".to_vec();
        stl.resize(84, 0);
        stl.extend_from_slice(&[0x3f; 50]);
        let err = read_obj(&write(&dir, "part.stl", &stl)).unwrap_err();
        assert!(matches!(err, ToolError::Parse { .. }), "{err}");
        assert!(err.to_string().contains("binary"), "{err}");

        // Not UTF-8 where it matters.
        let err = read_obj(&write(&dir, "latin.obj", b"v 0 0 0\nv 1\xff 0 0\n")).unwrap_err();
        assert!(matches!(err, ToolError::Parse { .. }), "{err}");

        // Random bytes and random OBJ-like words: refused (or, by chance, read), never a panic.
        let mut rnd = xorshift(0x2545_f491_4f6c_dd1d);
        let tokens = ["v", "f", "vt", "l", "1", "-1", "0", "2/3", "//", "/", "1e40", "nan", "\n"];
        for round in 0..240 {
            let bytes: Vec<u8> = match round % 3 {
                0 => (0..200).map(|_| rnd(256) as u8).collect(),
                1 => (0..200).map(|_| (rnd(255) + 1) as u8).collect(),
                _ => {
                    let words: Vec<&str> = (0..60).map(|_| tokens[rnd(tokens.len())]).collect();
                    words.join(" ").into_bytes()
                }
            };
            let path = write(&dir, &format!("garbage{round}.obj"), &bytes);
            match read_obj(&path) {
                Ok(_)
                | Err(ToolError::Parse { .. })
                | Err(ToolError::Empty { .. })
                | Err(ToolError::BadIndex { .. })
                | Err(ToolError::NonFinite { .. })
                | Err(ToolError::AllDegenerate { .. }) => {}
                Err(e) => panic!("unexpected error {e}"),
            }
        }
    }

    #[test]
    fn tool_surface_from_obj_answers_closest_point_queries() {
        let dir = tempfile::tempdir().unwrap();
        let path = write(&dir, "square.obj", format!("{SQUARE}f 1 2 3\nf 1 3 4\n"));
        let surface = crate::io::read_tool(&path, 1.0).unwrap();
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

    use crate::mapping::ElementShape;

    /// The flow-mesh reading of one text: every vertex a node (numbered from 1), faces of three
    /// and four corners kept, larger polygons fanned.
    fn read_flow(text: &str) -> Result<FlowMesh, FlowMeshError> {
        let dir = tempfile::tempdir().unwrap();
        read(&write(&dir, "mesh.obj", text), 1.0)
    }

    /// A deterministic pseudo-random index below `n` (xorshift64 from `seed`), for the random
    /// texts of the tests.
    fn xorshift(seed: u64) -> impl FnMut(usize) -> usize {
        let mut state = seed;
        move |n: usize| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state % n as u64) as usize
        }
    }

    #[test]
    fn the_flow_reading_keeps_quads_and_continues_lines() {
        let m = read_flow("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 \\\n 3 4\nf 1 2 3\n").unwrap();
        let shapes: Vec<ElementShape> = m.elements.iter().map(|e| e.shape).collect();
        assert_eq!(shapes, [ElementShape::Quad4, ElementShape::Tria3]);
        assert_eq!(m.node_ids, [1, 2, 3, 4]);
        let e = read_flow("v 0 0 0\nv 1 0 0\nf 1 2\n").unwrap_err().to_string();
        assert!(e.contains("line 3") && e.contains("at least 3"), "{e}");
    }

    #[test]
    fn the_byte_path_reads_what_the_text_path_reads() {
        // Random lines of OBJ-like words, white space of every ASCII kind, comments, continued
        // lines, non-ASCII bytes and all three line ends: parsed with the byte path for ASCII
        // lines and with every line read as text, the same statements or the same error.
        let mut rnd = xorshift(0x9e37_79b9_7f4a_7c15);
        let words = [
            "v", "f", "vt", "l", "p", "1", "-1", "2", "-3", "0", "+4", "7/1", "2//5", "3/1/2", "1/2/3/4", "/", "//",
            "1e40", "nan", "inf", "-0.5", "2.5e-3", ".5", "1.", "x", "#", "#c", "\\", "caf\u{e9}", "\u{a0}", "9999999999999999999999",
        ];
        let spaces = [" ", "  ", "\t", "\x0b", "\x0c", " \t"];
        let ends = ["\n", "\r\n", "\r"];
        for round in 0..3000 {
            let mut text = String::new();
            for _ in 0..1 + rnd(6) {
                let kind = ["v", "f", "f", "l", "#", "g"][rnd(6)];
                text += kind;
                for _ in 0..rnd(7) {
                    text += spaces[rnd(spaces.len())];
                    text += if rnd(3) == 0 { words[rnd(words.len())] } else { ["1", "2", "3", "-1", "0.25"][rnd(5)] };
                }
                if rnd(4) == 0 {
                    text += spaces[rnd(spaces.len())];
                }
                text += ends[rnd(ends.len())];
            }
            let bytes = if round % 7 == 0 { [text.as_bytes(), b"v 1 \xff 2\n"].concat() } else { text.into_bytes() };
            // Compared as Debug text: NaN coordinates are not equal to themselves.
            let (fast, text) = (parse_with(&bytes, true), parse_with(&bytes, false));
            assert_eq!(format!("{fast:?}"), format!("{text:?}"), "{:?}", String::from_utf8_lossy(&bytes));
        }
    }

    #[test]
    fn a_text_read_in_pieces_is_the_text_read_whole() {
        // Random OBJ-like texts of many lines (vertices, faces with plain, slashed and negative
        // numbers, comments, continued lines, non-ASCII bytes, all three line ends, errors of
        // every kind), read in pieces of 1 to 60 bytes with 1, 2 and 3 threads and read whole
        // as text: the same statements or the same error.
        let mut rnd = xorshift(0x2545_f491_4f6c_dd1d);
        let words = ["1", "2", "3", "-1", "-2", "-4", "4/1", "2//5", "0", "x", "0.5", "1e3", "nan", "#c", "\\", "caf\u{e9}"];
        let ends = ["\n", "\r\n", "\r", "\\\n", " \\\r\n", "\n\n"];
        let mut texts = Vec::new();
        for round in 0..400 {
            let mut text = String::new();
            for _ in 0..5 + rnd(30) {
                match rnd(20) {
                    0..=7 => text += &format!("v {} {} {}", rnd(9), rnd(9), 0.5 * rnd(9) as f64),
                    8..=15 => {
                        text += "f";
                        for _ in 0..rnd(6) {
                            text += " ";
                            // Mostly valid numbers, so that most texts read to the end.
                            text += if rnd(40) == 0 { words[rnd(words.len())] } else { ["1", "2", "-1", "-2", "3/3"][rnd(5)] };
                        }
                    }
                    16..=18 => text += ["# comment", "g part", "vn 0 0 1", "l 1 2", "p 1", "f 1 2 3 # \\"][rnd(6)],
                    _ => text += ["v 1 2 2", "v 1 \u{e9} 2"][rnd(2)],
                }
                text += if rnd(6) == 0 { ends[rnd(ends.len())] } else { "\n" };
            }
            let bytes = if round % 11 == 0 { [text.as_bytes(), b"v 1 \xff 2\n"].concat() } else { text.into_bytes() };
            texts.push(bytes);
        }
        let (mut read, mut refused) = (0, 0);
        for threads in [1, 2, 3] {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| {
                for (round, bytes) in texts.iter().enumerate() {
                    let whole = format!("{:?}", parse_with(bytes, false));
                    let piece = 1 + round % 60;
                    let pieces = format!("{:?}", parse_pieces(bytes, piece).map(Pieces::into_text));
                    assert_eq!(pieces, whole, "pieces of {piece} bytes: {:?}", String::from_utf8_lossy(bytes));
                    if whole.starts_with("Ok") {
                        read += 1;
                    } else {
                        refused += 1;
                    }
                }
            });
        }
        // Both outcomes are exercised.
        assert!(read > 100 && refused > 100, "{read} read, {refused} refused");
    }

    #[test]
    fn the_tool_mesh_built_in_parallel_is_the_one_built_in_order() {
        // Random texts of vertices (some not finite) and faces (of 0 to 6 corners, some naming
        // vertices the file does not have, some counting back), read in pieces of 1 to 80 bytes:
        // the parallel build gives the mesh, counts and error of the build in order, with 1, 2
        // and 3 threads.
        let mut rnd = xorshift(0x9e37_79b9_7f4a_7c15);
        let mut texts = Vec::new();
        for _ in 0..300 {
            let vertices = 3 + rnd(40);
            let mut text = String::new();
            for v in 0..vertices {
                let x = match rnd(150) {
                    0 => "nan".to_string(),
                    1 => "1e999".to_string(),
                    _ => format!("{}", v as f64 * 0.5),
                };
                text += &format!("v {x} {} {}\n", rnd(9), rnd(9));
                if rnd(3) == 0 {
                    text += "f";
                    for _ in 0..rnd(7) {
                        text += &match rnd(60) {
                            0 => format!(" {}", vertices + 1 + rnd(3)),
                            1..=5 => format!(" -{}", 1 + rnd(v + 1)),
                            _ => format!(" {}", 1 + rnd(vertices)),
                        };
                    }
                    text += "\n";
                }
            }
            texts.push(text);
        }
        let path = Path::new("t.obj");
        let (mut built, mut refused) = (0, 0);
        for threads in [1, 2, 3] {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| {
                for (round, text) in texts.iter().enumerate() {
                    let pieces = parse_pieces(text.as_bytes(), 1 + round % 80).unwrap();
                    let (mut a, mut b) = (MeshReport::default(), MeshReport::default());
                    let (parallel, serial) = (tool_mesh(&pieces, path, &mut a), tool_mesh_serial(&pieces, path, &mut b));
                    // As Debug text: NaN coordinates are not equal to themselves. (After an
                    // error the counts are not used.)
                    let text_of = |r: Result<TriangleMesh, ToolError>, m: MeshReport| match r {
                        Ok(mesh) => format!("Ok({mesh:?}) {m:?}"),
                        Err(e) => format!("{e:?}"),
                    };
                    let (parallel, serial) = (text_of(parallel, a), text_of(serial, b));
                    assert_eq!(parallel, serial, "{text}");
                    if serial.starts_with("Ok") {
                        built += 1;
                    } else {
                        refused += 1;
                    }
                }
            });
        }
        assert!(built > 200 && refused > 200, "{built} built, {refused} refused");
    }

    #[test]
    fn pieces_begin_after_a_line_end_that_does_not_continue() {
        let text = b"v 0 0 0\nf 1 \\\n 2 3\r\nf 1 2 3 # \\\r\nv 1 1 1\rv 2 2 2\n";
        let bounds = piece_bounds(text, 1);
        // After `v 0 0 0`, not after the continued `f 1 \`, after the `\r\n` of ` 2 3` and of
        // the comment; the lone `\r` is not a piece boundary.
        assert_eq!(bounds, [0, 8, 20, 33, text.len()]);
        let pieces = parse_pieces(text, 1).unwrap();
        assert_eq!(pieces.texts.len(), 4);
        assert_eq!((pieces.vertex(1), pieces.vertex(2)), (([1.0, 1.0, 1.0], 5), ([2.0, 2.0, 2.0], 6)));
        assert_eq!(format!("{:?}", pieces.into_text()), format!("{:?}", parse_with(text, false).unwrap()));
    }

    #[test]
    fn obj_text_round_trips() {
        let mesh = TriangleMesh {
            vertices: vec![Point::new(0.1, -0.2, 1.0 / 3.0), Point::new(1e-17, 2.0, 0.0), Point::new(3.0, 0.5, -1e300)],
            triangles: vec![[0, 1, 2]],
        };
        let dir = tempfile::tempdir().unwrap();
        let (back, _) = read_obj(&write(&dir, "m.obj", mesh.to_obj_string())).unwrap();
        assert_eq!(back, mesh);
    }
}
