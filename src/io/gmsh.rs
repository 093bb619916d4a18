//! Gmsh `.msh` version 4.1, ASCII: `$MeshFormat`, `$Entities` (for physical tags), `$Nodes`
//! entity blocks (parametric coordinates skipped) and `$Elements` blocks. Triangles (type 2)
//! and quadrangles (type 3) are kept; every other type (points, lines, volumes, second-order
//! elements) is skipped. An element's property is the first physical tag of its entity when
//! `$Entities` gives one, else the entity tag. Other sections are skipped. Binary 4.1 files
//! (little-endian, 8-byte size_t, as Gmsh writes them on every common machine) are read the
//! same way. Older versions (2.x, 4.0) are refused with a message saying how to re-save.
use super::shell_mesh::{read_bytes, Builder, FlowMeshError, Loc};
use crate::mapping::FlowMesh;
use std::collections::HashMap;
use std::path::Path;

/// Gmsh 4 as a shell-mesh format.
pub const FORMAT: super::MeshFormat = super::MeshFormat { name: "Gmsh 4", extensions: &["msh"], read };

/// Read a Gmsh 4.1 ASCII mesh (see the module documentation).
pub fn read(path: &Path, scale: f64) -> Result<FlowMesh, FlowMeshError> {
    let mut b = Builder::new(path, scale)?;
    let bytes = read_bytes(path)?;
    // Binary files hold raw bytes after the header; only the header needs to be text.
    let text = String::from_utf8_lossy(&bytes);
    let mut c = Lines { lines: text.lines().collect(), next: 0 };
    let mut physical: HashMap<(i64, i64), u64> = HashMap::new();
    let mut format_seen = false;
    while let Some((no, line)) = c.next_line() {
        let loc = Loc { file: 0, line: no };
        let Some(section) = line.strip_prefix('$') else {
            return Err(b.syntax(loc, format!("expected a section such as $Nodes, found '{line}'")));
        };
        let end = format!("$End{section}");
        match section {
            "MeshFormat" => {
                let (no, l) = c.need(&b, "the format line")?;
                let t: Vec<&str> = l.split_whitespace().collect();
                let loc = Loc { file: 0, line: no };
                if t.first() != Some(&"4.1") {
                    return Err(b.syntax(
                        loc,
                        format!("Gmsh format version {}: only 4.1 is read; re-save as 4.1 ASCII (File > Export, Version 4 ASCII, or -format msh41)", t.first().unwrap_or(&"?")),
                    ));
                }
                if t.get(1) == Some(&"1") {
                    if t.get(2) != Some(&"8") {
                        return Err(b.syntax(loc, "binary .msh with a size_t that is not 8 bytes: re-save as ASCII"));
                    }
                    // The binary part starts after the format line.
                    let start = byte_offset_of_line(&bytes, no);
                    return read_binary(b, &bytes, start);
                }
                if t.get(1) != Some(&"0") {
                    return Err(b.syntax(loc, "the file type on the $MeshFormat line must be 0 (ASCII) or 1 (binary)"));
                }
                format_seen = true;
                c.skip_to(&b, &end, loc)?;
            }
            _ if !format_seen => {
                return Err(b.syntax(loc, "the file must start with $MeshFormat: is this a Gmsh .msh file?"))
            }
            "Entities" => {
                let (no, l) = c.need(&b, "the entity counts")?;
                let counts = ints(&b, l, no, 4)?;
                for (dim, &n) in counts.iter().enumerate() {
                    for _ in 0..n {
                        let (no, l) = c.need(&b, "an entity line")?;
                        let t: Vec<&str> = l.split_whitespace().collect();
                        // Points: tag x y z nphys ...; others: tag 6-number box nphys ...
                        let at = if dim == 0 { 4 } else { 7 };
                        let get = |k: usize| -> Result<i64, FlowMeshError> {
                            t.get(k).and_then(|s| s.parse().ok()).ok_or_else(|| {
                                b.syntax(
                                    Loc { file: 0, line: no },
                                    format!("entity line: field {} is missing or not an integer", k + 1),
                                )
                            })
                        };
                        let tag = get(0)?;
                        if get(at)? > 0 {
                            physical.insert((dim as i64, tag), get(at + 1)?.unsigned_abs());
                        }
                    }
                }
                c.skip_to(&b, &end, loc)?;
            }
            "Nodes" => {
                let (no, l) = c.need(&b, "the node counts")?;
                let blocks = ints(&b, l, no, 4)?[0];
                for _ in 0..blocks {
                    let (no, l) = c.need(&b, "a node block header")?;
                    let h = ints(&b, l, no, 4)?;
                    let (dim, parametric) = (h[0], h[2]);
                    // Each node takes two lines: a count beyond the file is refused before it
                    // sizes anything (a mutated count of 2^63 asked for the memory).
                    let n = usize::try_from(h[3]).ok().filter(|&n| n <= c.remaining()).ok_or_else(|| {
                        b.syntax(
                            Loc { file: 0, line: no },
                            format!("node block of {} nodes: the file has {} lines left", h[3], c.remaining()),
                        )
                    })?;
                    let mut tags = Vec::with_capacity(n);
                    for _ in 0..n {
                        let (no, l) = c.need(&b, "a node tag")?;
                        tags.push((ints(&b, l, no, 1)?[0] as u64, no));
                    }
                    for &(tag, _) in &tags {
                        let (no, l) = c.need(&b, "node coordinates")?;
                        let loc = Loc { file: 0, line: no };
                        let mut x = [0.0; 3];
                        let mut t = l.split_whitespace();
                        for (i, xi) in x.iter_mut().enumerate() {
                            let s = t.next().ok_or_else(|| b.syntax(loc, format!("node {tag}: needs x y z")))?;
                            *xi = s.parse().map_err(|_| {
                                b.syntax(loc, format!("node {tag}: coordinate {}: '{s}' is not a number", i + 1))
                            })?;
                        }
                        let extra = if parametric != 0 { dim.max(0) as usize } else { 0 };
                        if t.count() != extra {
                            return Err(
                                b.syntax(loc, format!("node {tag}: expected {} numbers on the line", 3 + extra))
                            );
                        }
                        b.add_node(tag, x, loc)?;
                    }
                }
                c.skip_to(&b, &end, loc)?;
            }
            "Elements" => {
                let (no, l) = c.need(&b, "the element counts")?;
                let blocks = ints(&b, l, no, 4)?[0];
                for _ in 0..blocks {
                    let (no, l) = c.need(&b, "an element block header")?;
                    let h = ints(&b, l, no, 4)?;
                    let (dim, tag, kind) = (h[0], h[1], h[2]);
                    let n = usize::try_from(h[3]).ok().filter(|&n| n <= c.remaining()).ok_or_else(|| {
                        b.syntax(
                            Loc { file: 0, line: no },
                            format!("element block of {} elements: the file has {} lines left", h[3], c.remaining()),
                        )
                    })?;
                    let corners = match kind {
                        2 => Some(3),
                        3 => Some(4),
                        _ => None,
                    };
                    let property = physical.get(&(dim, tag)).copied().unwrap_or(tag.unsigned_abs());
                    for _ in 0..n {
                        let (no, l) = c.need(&b, "an element line")?;
                        let Some(k) = corners else {
                            b.skip(&format!("Gmsh type {kind}"));
                            continue;
                        };
                        let v = ints(&b, l, no, 1 + k)?;
                        if v.len() != 1 + k {
                            return Err(b.syntax(
                                Loc { file: 0, line: no },
                                format!("element {}: expected {} node tags", v[0], k),
                            ));
                        }
                        let nodes: Vec<u64> = v[1..].iter().map(|&x| x as u64).collect();
                        b.add_element(v[0] as u64, &nodes, property, Loc { file: 0, line: no })?;
                    }
                }
                c.skip_to(&b, &end, loc)?;
            }
            _ => c.skip_to(&b, &end, loc)?,
        }
    }
    if !format_seen {
        return Err(FlowMeshError::Invalid {
            path: path.into(),
            message: "no $MeshFormat section: is this a Gmsh .msh file?".into(),
        });
    }
    b.finish("Gmsh types 2 (triangle) and 3 (quadrangle)")
}

/// The file's lines with a cursor; blank lines are skipped.
struct Lines<'a> {
    lines: Vec<&'a str>,
    next: usize,
}

impl<'a> Lines<'a> {
    /// How many lines (blank ones too) are left.
    fn remaining(&self) -> usize {
        self.lines.len() - self.next
    }

    /// Next non-blank line, trimmed, with its 1-based number.
    fn next_line(&mut self) -> Option<(usize, &'a str)> {
        while self.next < self.lines.len() {
            self.next += 1;
            let l = self.lines[self.next - 1].trim();
            if !l.is_empty() {
                return Some((self.next, l));
            }
        }
        None
    }

    /// Next line, or an error saying the file ended while reading `what`.
    fn need(&mut self, b: &Builder, what: &str) -> Result<(usize, &'a str), FlowMeshError> {
        let n = self.lines.len();
        self.next_line().ok_or_else(|| {
            b.syntax(Loc { file: 0, line: n }, format!("file ends while reading {what}: is it truncated?"))
        })
    }

    /// Skip to the line `end` (e.g. `$EndNodes`).
    fn skip_to(&mut self, b: &Builder, end: &str, start: Loc) -> Result<(), FlowMeshError> {
        while let Some((_, l)) = self.next_line() {
            if l == end {
                return Ok(());
            }
        }
        Err(b.syntax(start, format!("section has no {end}: is the file truncated?")))
    }
}

/// At least `min` integers from a line.
fn ints(b: &Builder, l: &str, no: usize, min: usize) -> Result<Vec<i64>, FlowMeshError> {
    let v: Result<Vec<i64>, _> = l.split_whitespace().map(str::parse).collect();
    match v {
        Ok(v) if v.len() >= min => Ok(v),
        _ => Err(b.syntax(Loc { file: 0, line: no }, format!("expected {min} or more integers, found '{l}'"))),
    }
}

/// Byte offset of the start of line `no + 1` (1-based `no`): where a binary part begins.
fn byte_offset_of_line(bytes: &[u8], no: usize) -> usize {
    let mut seen = 0;
    for (k, &c) in bytes.iter().enumerate() {
        if c == b'\n' {
            seen += 1;
            if seen == no {
                return k + 1;
            }
        }
    }
    bytes.len()
}

/// Node count of the Gmsh element types, to step over the types we skip in binary files
/// (ASCII files are skipped line by line and need no table).
fn nodes_of_type(kind: i32) -> Option<usize> {
    Some(match kind {
        1 => 2,
        2 => 3,
        3 => 4,
        4 => 4,
        5 => 8,
        6 => 6,
        7 => 5,
        8 => 3,
        9 => 6,
        10 => 9,
        11 => 10,
        12 => 27,
        13 => 18,
        14 => 14,
        15 => 1,
        16 => 8,
        17 => 20,
        18 => 15,
        19 => 13,
        20 => 9,
        21 => 10,
        22 => 12,
        23 => 15,
        24 => 15,
        25 => 21,
        26 => 4,
        27 => 5,
        28 => 6,
        29 => 20,
        30 => 35,
        31 => 56,
        _ => return None,
    })
}

/// Little-endian reader of the binary sections.
struct Bin<'a> {
    bytes: &'a [u8],
    pos: usize,
}

impl<'a> Bin<'a> {
    fn take(&mut self, n: usize) -> Option<&'a [u8]> {
        let s = self.bytes.get(self.pos..self.pos.checked_add(n)?)?;
        self.pos += n;
        Some(s)
    }
    fn i32(&mut self) -> Option<i32> {
        Some(i32::from_le_bytes(self.take(4)?.try_into().ok()?))
    }
    fn u64(&mut self) -> Option<u64> {
        Some(u64::from_le_bytes(self.take(8)?.try_into().ok()?))
    }
    fn f64(&mut self) -> Option<f64> {
        Some(f64::from_le_bytes(self.take(8)?.try_into().ok()?))
    }
    /// A count that must fit what is left of the file (`each` bytes an item), so a corrupt
    /// count cannot make us allocate wildly.
    fn count(&mut self, each: usize) -> Option<usize> {
        let n = usize::try_from(self.u64()?).ok()?;
        (n.checked_mul(each)? <= self.bytes.len() - self.pos).then_some(n)
    }
    /// The next text line (a section header), skipping the newline left after binary data.
    fn line(&mut self) -> Option<&'a str> {
        while self.pos < self.bytes.len() && matches!(self.bytes[self.pos], b'\n' | b'\r' | b' ') {
            self.pos += 1;
        }
        if self.pos >= self.bytes.len() {
            return None;
        }
        let end = self.bytes[self.pos..].iter().position(|&c| c == b'\n').map_or(self.bytes.len(), |k| self.pos + k);
        let l = std::str::from_utf8(&self.bytes[self.pos..end]).ok()?.trim();
        // Binary data starts right after the header's newline.
        self.pos = (end + 1).min(self.bytes.len());
        Some(l)
    }
    /// Skip to just after the text `end` (e.g. `$EndNodes`).
    fn skip_to(&mut self, end: &str) -> Option<()> {
        let e = end.as_bytes();
        let k = self.bytes[self.pos..].windows(e.len()).position(|w| w == e)?;
        self.pos += k + e.len();
        Some(())
    }
}

/// Read the binary part of a 4.1 file, from `start` (just after the `$MeshFormat` line).
fn read_binary(mut b: Builder, bytes: &[u8], start: usize) -> Result<FlowMesh, FlowMeshError> {
    let path = b.files[0].clone();
    let bad = |pos: usize, what: &str| FlowMeshError::Invalid {
        path: path.clone(),
        message: format!(
            "binary .msh at byte {pos}: {what}; the file may be truncated or not little-endian: re-save as 4.1 ASCII"
        ),
    };
    let mut r = Bin { bytes, pos: start };
    if r.i32() != Some(1) {
        return Err(bad(start, "the endianness check is not 1 (big-endian files are not read)"));
    }
    r.skip_to("$EndMeshFormat").ok_or_else(|| bad(r.pos, "no $EndMeshFormat"))?;
    let mut physical: HashMap<(i64, i64), u64> = HashMap::new();
    while let Some(l) = r.line() {
        let pos = r.pos;
        let Some(section) = l.strip_prefix('$') else {
            return Err(bad(pos, &format!("expected a section, found '{l}'")));
        };
        let end = format!("$End{section}");
        let e = |what: &str| bad(pos, &format!("${section}: {what}"));
        match section {
            "Entities" => {
                let mut counts = [0usize; 4];
                for c in &mut counts {
                    *c = r.count(4).ok_or_else(|| e("entity counts"))?;
                }
                for (dim, &n) in counts.iter().enumerate() {
                    for _ in 0..n {
                        let tag = r.i32().ok_or_else(|| e("entity tag"))?;
                        r.take(if dim == 0 { 24 } else { 48 }).ok_or_else(|| e("entity box"))?;
                        let np = r.count(4).ok_or_else(|| e("physical count"))?;
                        let mut first = None;
                        for _ in 0..np {
                            let p = r.i32().ok_or_else(|| e("physical tag"))?;
                            first.get_or_insert(p);
                        }
                        if let Some(p) = first {
                            physical.insert((dim as i64, i64::from(tag)), u64::from(p.unsigned_abs()));
                        }
                        if dim > 0 {
                            let nb = r.count(4).ok_or_else(|| e("bounding count"))?;
                            r.take(4 * nb).ok_or_else(|| e("bounding tags"))?;
                        }
                    }
                }
            }
            "Nodes" => {
                let blocks = r.count(1).ok_or_else(|| e("counts"))?;
                r.take(24).ok_or_else(|| e("counts"))?;
                for _ in 0..blocks {
                    let (dim, _tag, parametric) = (r.i32(), r.i32(), r.i32());
                    let (Some(dim), Some(parametric)) = (dim, parametric) else { return Err(e("block header")) };
                    let n = r.count(8).ok_or_else(|| e("block size"))?;
                    let mut tags = Vec::with_capacity(n);
                    for _ in 0..n {
                        tags.push(r.u64().ok_or_else(|| e("node tags"))?);
                    }
                    let extra = if parametric != 0 { dim.max(0) as usize } else { 0 };
                    for tag in tags {
                        let mut x = [0.0; 3];
                        for xi in &mut x {
                            *xi = r.f64().ok_or_else(|| e("coordinates"))?;
                        }
                        r.take(8 * extra).ok_or_else(|| e("parametric coordinates"))?;
                        // Binary data has no lines: report the section's line (the header's).
                        b.add_node(tag, x, Loc { file: 0, line: 0 }).map_err(no_line)?;
                    }
                }
            }
            "Elements" => {
                let blocks = r.count(1).ok_or_else(|| e("counts"))?;
                r.take(24).ok_or_else(|| e("counts"))?;
                for _ in 0..blocks {
                    let (dim, tag, kind) = (r.i32(), r.i32(), r.i32());
                    let (Some(dim), Some(tag), Some(kind)) = (dim, tag, kind) else { return Err(e("block header")) };
                    let k = nodes_of_type(kind)
                        .ok_or_else(|| e(&format!("element type {kind} is not known: re-save as 4.1 ASCII")))?;
                    let n = r.count(8 * (k + 1)).ok_or_else(|| e("block size"))?;
                    let property = physical
                        .get(&(i64::from(dim), i64::from(tag)))
                        .copied()
                        .unwrap_or(u64::from(tag.unsigned_abs()));
                    let mut v = [0u64; 4];
                    for _ in 0..n {
                        let id = r.u64().ok_or_else(|| e("element"))?;
                        if kind == 2 || kind == 3 {
                            for x in v.iter_mut().take(k) {
                                *x = r.u64().ok_or_else(|| e("element nodes"))?;
                            }
                            b.add_element(id, &v[..k], property, Loc { file: 0, line: 0 }).map_err(no_line)?;
                        } else {
                            r.take(8 * k).ok_or_else(|| e("element nodes"))?;
                            b.skip(&format!("Gmsh type {kind}"));
                        }
                    }
                }
            }
            _ => {}
        }
        r.skip_to(&end).ok_or_else(|| e(&format!("no {end}")))?;
    }
    b.finish("Gmsh types 2 (triangle) and 3 (quadrangle)").map_err(no_line)
}

/// Binary data has no line numbers (the builder's errors carry line 0): drop the line.
fn no_line(e: FlowMeshError) -> FlowMeshError {
    match e {
        FlowMeshError::Syntax { path, line: 0, message } => {
            FlowMeshError::Invalid { path, message: format!("binary data: {message}") }
        }
        e => e,
    }
}
