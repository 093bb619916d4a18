//! Gmsh `.msh` version 4.1, ASCII: `$MeshFormat`, `$Entities` (for physical tags), `$Nodes`
//! entity blocks (parametric coordinates skipped) and `$Elements` blocks. Triangles (type 2)
//! and quadrangles (type 3) are kept; every other type (points, lines, volumes, second-order
//! elements) is skipped. An element's property is the first physical tag of its entity when
//! `$Entities` gives one, else the entity tag. Other sections are skipped. Older versions (2.x,
//! 4.0) and binary files are refused with a message saying how to re-save.
use super::{read_bytes, Builder, FlowMesh, FlowMeshError, Loc};
use std::collections::HashMap;
use std::path::Path;

/// Read a Gmsh 4.1 ASCII mesh (see the module documentation).
pub fn read_gmsh(path: &Path, scale: f64) -> Result<FlowMesh, FlowMeshError> {
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
                if t.get(1) != Some(&"0") {
                    return Err(b.syntax(loc, "binary .msh: re-save as ASCII (Gmsh: File > Export, uncheck binary, or -format msh41 without -bin)"));
                }
                format_seen = true;
                c.skip_to(&b, &end, loc)?;
            }
            _ if !format_seen => return Err(b.syntax(loc, "the file must start with $MeshFormat: is this a Gmsh .msh file?")),
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
                                b.syntax(Loc { file: 0, line: no }, format!("entity line: field {} is missing or not an integer", k + 1))
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
                    let (dim, parametric, n) = (h[0], h[2], h[3] as usize);
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
                            *xi = s.parse().map_err(|_| b.syntax(loc, format!("node {tag}: coordinate {}: '{s}' is not a number", i + 1)))?;
                        }
                        let extra = if parametric != 0 { dim.max(0) as usize } else { 0 };
                        if t.count() != extra {
                            return Err(b.syntax(loc, format!("node {tag}: expected {} numbers on the line", 3 + extra)));
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
                    let (dim, tag, kind, n) = (h[0], h[1], h[2], h[3] as usize);
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
                            return Err(b.syntax(Loc { file: 0, line: no }, format!("element {}: expected {} node tags", v[0], k)));
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
        return Err(FlowMeshError::Invalid { path: path.into(), message: "no $MeshFormat section: is this a Gmsh .msh file?".into() });
    }
    b.finish("Gmsh types 2 (triangle) and 3 (quadrangle)")
}

/// The file's lines with a cursor; blank lines are skipped.
struct Lines<'a> {
    lines: Vec<&'a str>,
    next: usize,
}

impl<'a> Lines<'a> {
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
        self.next_line().ok_or_else(|| b.syntax(Loc { file: 0, line: n }, format!("file ends while reading {what}: is it truncated?")))
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
