//! Reading Nastran bulk data: GRID, CTRIA3/CTRIAR and CQUAD4/CQUADR, with CORD2R/CORD2C/CORD2S for
//! grids given in a local system (CP).
//!
//! Accepted layouts, mixed freely line by line:
//! - small fixed fields: 8 columns each, name in columns 1-8, eight data fields, columns 73-80
//!   the continuation field (ignored); tabs move to the next 8-column field;
//! - large fixed fields: a name ending in `*` (`GRID*`), four 16-column data fields a line,
//!   continuation lines starting with `*`;
//! - free fields: any line holding a comma; `GRID*,...` / `*,...` are large free fields (four
//!   data fields a line). A free line with more fields than fit is read as if the extra fields
//!   were on continuation lines (every 9th (small) or 5th (large) field after the name is a
//!   continuation marker and dropped).
//!
//! A line whose first field is blank or starts with `+` or `*` continues the card above it
//! (continuation labels are not matched: cards must be in order, as every pre-processor writes
//! them). `$` starts a comment. If the file has a `BEGIN BULK` line, everything before it
//! (executive and case control) is skipped; `ENDDATA` ends reading. `INCLUDE 'file'` (one line,
//! path relative to the including file) is followed.
//!
//! Reals take Nastran's forms: `1.-3` = 1e-3, `-.5+2` = -50, `1.5D-3`, `7.`; a blank coordinate
//! is 0. An element's blank PID is its EID (Nastran's default). Cards starting with `C` that are
//! not shells (CTRIA6, CQUAD8, CHEXA, CBAR, CONM2, ...) are counted and skipped. The shells'
//! property and material cards (PSHELL, PCOMP, PCOMPG, MAT1, MAT2, MAT8) are kept as read in
//! [`FlowMesh::cards`], for the Nastran and OptiStruct writers to carry through; other MAT cards
//! (MATT8, MATS1, MAT9, ...) are named there as not carried; other cards are ignored.
use super::parse_real;
use crate::io::shell_mesh::{read_bytes, Builder, FlowMeshError, Loc};
use crate::mapping::{FlowMesh, MeshCard};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// How deep `INCLUDE` may nest before we assume a cycle.
const MAX_INCLUDE_DEPTH: usize = 32;
/// How deep coordinate systems may reference each other (RID) before we assume a cycle.
const MAX_CORD_DEPTH: usize = 64;

/// Read a Nastran bulk data file (see the module documentation for what is accepted).
pub fn read(path: &Path, scale: f64) -> Result<FlowMesh, FlowMeshError> {
    let mut b = Builder::new(path, scale)?;
    let mut r = Reader { card: Card::default(), grids: Vec::new(), cords: HashMap::new(), other_cords: HashMap::new() };
    let bytes = read_bytes(path)?;
    r.read_file(&mut b, &bytes, 0, true, 0)?;
    r.flush(&mut b)?;
    r.place_grids(&mut b)?;
    b.finish("CTRIA3, CTRIAR, CQUAD4, CQUADR")
}

/// One logical card: its name and the data fields of all its lines, as byte ranges into `buf`.
#[derive(Default)]
struct Card {
    name: String,
    loc: Option<Loc>,
    buf: Vec<u8>,
    fields: Vec<(usize, usize)>,
}

impl Card {
    /// Data field `k` (0 = the field after the name), trimmed; empty when blank or absent.
    fn field(&self, k: usize) -> &str {
        match self.fields.get(k) {
            Some(&(a, b)) => std::str::from_utf8(&self.buf[a..b]).unwrap_or("\u{fffd}").trim(),
            None => "",
        }
    }

    fn push(&mut self, f: &[u8]) {
        let a = self.buf.len();
        self.buf.extend_from_slice(f);
        self.fields.push((a, self.buf.len()));
    }

    /// Push a line's data fields, padded with blanks to `width` (8 small, 4 large) so that a
    /// continuation starts at the right field.
    fn push_line(&mut self, data: &[&[u8]], width: usize) {
        for f in data {
            self.push(f);
        }
        for _ in data.len()..width {
            self.push(b"");
        }
    }
}

/// A local coordinate system defined by three points (CORD2R/C/S).
#[derive(Clone, Copy)]
struct Cord {
    kind: CordKind,
    rid: u64,
    a: [f64; 3],
    b: [f64; 3],
    c: [f64; 3],
    loc: Loc,
}

#[derive(Clone, Copy, PartialEq)]
enum CordKind {
    Rectangular,
    Cylindrical,
    Spherical,
}

/// A GRID card, placed once every coordinate system is known.
struct Grid {
    id: u64,
    cp: u64,
    x: [f64; 3],
    loc: Loc,
}

struct Reader {
    card: Card,
    grids: Vec<Grid>,
    cords: HashMap<u64, Cord>,
    /// Coordinate systems of kinds we do not support (CORD1R, CORD3G...): id -> card name.
    other_cords: HashMap<u64, String>,
}

/// Trim ASCII blanks of a byte field.
fn trim(f: &[u8]) -> &[u8] {
    let a = f.iter().position(|c| !c.is_ascii_whitespace()).unwrap_or(f.len());
    let b = f.iter().rposition(|c| !c.is_ascii_whitespace()).map_or(a, |b| b + 1);
    &f[a..b.max(a)]
}

/// Expand tabs to the next multiple of 8 columns (Nastran's fixed-field tab rule).
fn expand_tabs(line: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(line.len() + 32);
    for &c in line {
        if c == b'\t' {
            out.push(b' ');
            while out.len() % 8 != 0 {
                out.push(b' ');
            }
        } else {
            out.push(c);
        }
    }
    out
}

/// Column slice `a..b` of a fixed-format line, empty past its end.
fn cols(line: &[u8], a: usize, b: usize) -> &[u8] {
    if a >= line.len() {
        b""
    } else {
        &line[a..b.min(line.len())]
    }
}

impl Reader {
    /// Read the lines of one file (`file` indexes `b.files`). `top`: the main file, where
    /// `BEGIN BULK` is looked for. Returns `true` when ENDDATA was met.
    fn read_file(
        &mut self,
        b: &mut Builder,
        bytes: &[u8],
        file: usize,
        top: bool,
        depth: usize,
    ) -> Result<bool, FlowMeshError> {
        let mut lines: Vec<&[u8]> = bytes.split(|&c| c == b'\n').collect();
        let mut first_line = 0;
        if top {
            // Cheap byte test first: this runs on every line of the file.
            if let Some(k) = lines.iter().position(|l| {
                let t = trim(l);
                t.len() >= 5
                    && t[..5].eq_ignore_ascii_case(b"BEGIN")
                    && String::from_utf8_lossy(t).to_ascii_uppercase().contains("BULK")
            }) {
                first_line = k + 1;
            }
        }
        for (k, raw) in lines.drain(..).enumerate().skip(first_line) {
            let loc = Loc { file, line: k + 1 };
            let mut line = raw.strip_suffix(b"\r").unwrap_or(raw);
            if let Some(p) = line.iter().position(|&c| c == b'$') {
                line = &line[..p];
            }
            if trim(line).is_empty() {
                continue;
            }
            let expanded;
            if line.contains(&b'\t') && !line.contains(&b',') {
                expanded = expand_tabs(line);
                line = &expanded;
            }
            let free = line.contains(&b',');
            let first =
                if free { trim(line.split(|&c| c == b',').next().unwrap_or(b"")) } else { trim(cols(line, 0, 8)) };
            let is_cont = first.is_empty() || first[0] == b'+' || first[0] == b'*';
            if !is_cont {
                let starts = |w: &[u8]| first.len() >= w.len() && first[..w.len()].eq_ignore_ascii_case(w);
                if starts(b"ENDDATA") {
                    self.flush(b)?;
                    return Ok(true);
                }
                if starts(b"INCLUDE") {
                    self.flush(b)?;
                    if self.include(b, line, loc, depth)? {
                        return Ok(true);
                    }
                    continue;
                }
                self.flush(b)?;
                // Upper-case name without the large-field '*', reusing the buffer.
                let name = trim(first.strip_suffix(b"*").unwrap_or(first));
                self.card.name.clear();
                self.card.name.extend(name.iter().map(|c| c.to_ascii_uppercase() as char));
                self.card.loc = Some(loc);
            } else if self.card.loc.is_none() {
                return Err(b.syntax(
                    loc,
                    "continuation line with no card before it: start the card with its name (GRID, CQUAD4, ...)",
                ));
            }
            let large = first.ends_with(b"*") || first.starts_with(b"*");
            let width = if large { 4 } else { 8 };
            let mut data: [&[u8]; 8] = [b""; 8];
            if free {
                let mut n = 0;
                let mut after_marker = false;
                for (i, tok) in line.split(|&c| c == b',').skip(1).enumerate() {
                    // Every (width+1)th token after the name is a continuation marker.
                    if i % (width + 1) == width {
                        self.card.push_line(&data[..n], width);
                        n = 0;
                        after_marker = true;
                        continue;
                    }
                    data[n] = trim(tok);
                    n += 1;
                    after_marker = false;
                }
                if n > 0 || !after_marker {
                    self.card.push_line(&data[..n], width);
                }
            } else {
                let w = if large { 16 } else { 8 };
                for (i, d) in data.iter_mut().enumerate().take(width) {
                    *d = cols(line, 8 + i * w, 8 + (i + 1) * w);
                }
                self.card.push_line(&data[..width], width);
            }
        }
        Ok(false)
    }

    /// Follow `INCLUDE 'file'` (path relative to the including file).
    fn include(&mut self, b: &mut Builder, line: &[u8], loc: Loc, depth: usize) -> Result<bool, FlowMeshError> {
        let text = String::from_utf8_lossy(line);
        let name = match (text.find('\''), text.rfind('\'')) {
            (Some(a), Some(z)) if z > a + 1 => text[a + 1..z].trim().to_string(),
            _ => {
                return Err(
                    b.syntax(loc, "INCLUDE needs the file name in single quotes on the same line: INCLUDE 'file.bdf'")
                )
            }
        };
        if depth >= MAX_INCLUDE_DEPTH {
            return Err(b.syntax(
                loc,
                format!("INCLUDE nested more than {MAX_INCLUDE_DEPTH} deep: is a file including itself?"),
            ));
        }
        let base = b.files[loc.file].parent().map(Path::to_path_buf).unwrap_or_default();
        let target: PathBuf = base.join(&name);
        let bytes = std::fs::read(&target)
            .map_err(|e| b.syntax(loc, format!("cannot read INCLUDE file {}: {e}", target.display())))?;
        b.files.push(target);
        let file = b.files.len() - 1;
        let end = self.read_file(b, &bytes, file, false, depth + 1)?;
        self.flush(b)?;
        Ok(end)
    }

    /// Process the card being collected, if any.
    fn flush(&mut self, b: &mut Builder) -> Result<(), FlowMeshError> {
        let Some(loc) = self.card.loc.take() else { return Ok(()) };
        let mut card = std::mem::take(&mut self.card);
        self.card_fields(b, &card, loc)?;
        // Keep the buffers for the next card (no allocation per card).
        card.buf.clear();
        card.fields.clear();
        self.card = card;
        Ok(())
    }

    /// Act on one complete card.
    fn card_fields(&mut self, b: &mut Builder, card: &Card, loc: Loc) -> Result<(), FlowMeshError> {
        let name = card.name.as_str();
        let int = |k: usize, what: &str| -> Result<Option<u64>, FlowMeshError> {
            let f = card.field(k);
            if f.is_empty() {
                return Ok(None);
            }
            f.parse::<u64>()
                .map(Some)
                .map_err(|_| b.syntax(loc, format!("{name} field {what}: '{f}' is not a non-negative integer")))
        };
        let real = |k: usize, what: &str| -> Result<f64, FlowMeshError> {
            let f = card.field(k);
            if f.is_empty() {
                return Ok(0.0);
            }
            parse_real(f)
                .ok_or_else(|| b.syntax(loc, format!("{name} field {what}: '{f}' is not a Nastran real number")))
        };
        let id = |k: usize, what: &str| -> Result<u64, FlowMeshError> {
            int(k, what)?.ok_or_else(|| b.syntax(loc, format!("{name}: field {what} is blank; it is required")))
        };
        match name {
            "GRID" => {
                let gid = id(0, "ID")?;
                let cp = int(1, "CP")?.unwrap_or(0);
                let x = [real(2, "X1")?, real(3, "X2")?, real(4, "X3")?];
                self.grids.push(Grid { id: gid, cp, x, loc });
            }
            "CTRIA3" | "CTRIAR" | "CQUAD4" | "CQUADR" => {
                let eid = id(0, "EID")?;
                let pid = int(1, "PID")?.unwrap_or(eid);
                let n = if name.starts_with("CTRIA") { 3 } else { 4 };
                let mut g = [0u64; 4];
                for (k, gk) in g.iter_mut().enumerate().take(n) {
                    *gk = id(2 + k, ["G1", "G2", "G3", "G4"][k])?;
                }
                b.add_element(eid, &g[..n], pid, loc)?;
            }
            "CORD2R" | "CORD2C" | "CORD2S" => {
                let cid = id(0, "CID")?;
                let rid = int(1, "RID")?.unwrap_or(0);
                let p = |k: usize, w: &str| -> Result<[f64; 3], FlowMeshError> {
                    Ok([real(k, &format!("{w}1"))?, real(k + 1, &format!("{w}2"))?, real(k + 2, &format!("{w}3"))?])
                };
                let kind = match name {
                    "CORD2R" => CordKind::Rectangular,
                    "CORD2C" => CordKind::Cylindrical,
                    _ => CordKind::Spherical,
                };
                let cord = Cord { kind, rid, a: p(2, "A")?, b: p(5, "B")?, c: p(8, "C")?, loc };
                if cid == 0 {
                    return Err(
                        b.syntax(loc, format!("{name} defines CID 0, which is the basic system: use another id"))
                    );
                }
                if self.cords.insert(cid, cord).is_some() || self.other_cords.contains_key(&cid) {
                    return Err(b.syntax(loc, format!("coordinate system {cid} is defined twice: ids must be unique")));
                }
            }
            "PSHELL" | "PCOMP" | "PCOMPG" | "MAT1" | "MAT2" | "MAT8" => keep_card(b, card, loc)?,
            n if n.starts_with("MAT") => {
                let at = format!("{} line {}", b.files[loc.file].display(), loc.line);
                b.mesh.cards.not_carried.push(format!("{n} {} ({at})", card.field(0)));
            }
            n if n.starts_with("CORD") => {
                if let Some(cid) = int(0, "CID").ok().flatten() {
                    self.other_cords.insert(cid, n.to_string());
                }
            }
            n if n.starts_with('C') && n.len() > 1 => b.skip(n),
            _ => {}
        }
        Ok(())
    }

    /// Convert the grids to the basic system and add them to the mesh, in file order.
    fn place_grids(&mut self, b: &mut Builder) -> Result<(), FlowMeshError> {
        let grids = std::mem::take(&mut self.grids);
        // Each system's frame in basic, computed once.
        let mut frames: HashMap<u64, Frame> = HashMap::new();
        for g in grids {
            let x = if g.cp == 0 {
                g.x
            } else {
                let f = match frames.entry(g.cp) {
                    std::collections::hash_map::Entry::Occupied(o) => o.into_mut(),
                    std::collections::hash_map::Entry::Vacant(v) => v.insert(
                        self.frame(b, g.cp, 0)
                            .map_err(|why| b.syntax(g.loc, format!("GRID {} has CP={}: {why}", g.id, g.cp)))?,
                    ),
                };
                f.to_basic(g.x)
            };
            b.add_node(g.id, x, g.loc)?;
        }
        Ok(())
    }

    /// Frame of system `cid` in the basic system, or why it cannot be built.
    fn frame(&self, b: &Builder, cid: u64, depth: usize) -> Result<Frame, String> {
        if depth > MAX_CORD_DEPTH {
            return Err(format!("coordinate system {cid} references systems (RID) in a cycle"));
        }
        let Some(c) = self.cords.get(&cid) else {
            return Err(match self.other_cords.get(&cid) {
                Some(kind) => format!(
                    "coordinate system {cid} is a {kind}, which is not supported: define it with CORD2R, CORD2C or CORD2S, or export the grids in the basic system (CP blank)"
                ),
                None => format!(
                    "coordinate system {cid} is not defined in the file (no CORD2R/CORD2C/CORD2S with CID {cid}): add it, or export the grids in the basic system (CP blank)"
                ),
            });
        };
        let at = |l: Loc| format!("{} line {}", b.files[l.file].display(), l.line);
        let (a, pb, pc) = if c.rid == 0 {
            (c.a, c.b, c.c)
        } else {
            let r = self.frame(b, c.rid, depth + 1)?;
            (r.to_basic(c.a), r.to_basic(c.b), r.to_basic(c.c))
        };
        let v = |p: [f64; 3]| nalgebra::Vector3::new(p[0], p[1], p[2]);
        let (a, pb, pc) = (v(a), v(pb), v(pc));
        let ez = pb - a;
        let y = ez.cross(&(pc - a));
        // Relative tolerance: points A, B, C must span a plane at a scale set by |AB| |AC|.
        let tol = 1e-12 * ez.norm() * (pc - a).norm();
        // partial_cmp: a NaN span (from infinite points) is refused too.
        if ez.norm() == 0.0 || y.norm().partial_cmp(&tol) != Some(std::cmp::Ordering::Greater) {
            return Err(format!("coordinate system {cid} ({}) has coincident or collinear points A, B, C", at(c.loc)));
        }
        let ez = ez.normalize();
        let ey = y.normalize();
        let ex = ey.cross(&ez);
        Ok(Frame { kind: c.kind, origin: a, axes: [ex, ey, ez] })
    }
}

/// Keep a property (PSHELL, PCOMP, PCOMPG) or material (MAT1, MAT2, MAT8) card for the writers
/// to carry through: its fields as text, a real too long for a large field (a free field can be
/// any length) rewritten in 15 characters. A card whose id is not a number is listed as not
/// carried; an id defined twice is refused, as Nastran refuses it.
fn keep_card(b: &mut Builder, card: &Card, loc: Loc) -> Result<(), FlowMeshError> {
    let name = card.name.as_str();
    let at = format!("{} line {}", b.files[loc.file].display(), loc.line);
    let Ok(id) = card.field(0).parse::<u64>() else {
        b.mesh.cards.not_carried.push(format!("{name} '{}' ({at}: its id is not a number)", card.field(0)));
        return Ok(());
    };
    let mut fields: Vec<String> = Vec::with_capacity(card.fields.len());
    for k in 0..card.fields.len() {
        let f = card.field(k);
        if f.len() < super::LARGE {
            fields.push(f.to_string());
            continue;
        }
        match parse_real(f).and_then(|x| super::fit_real(x, super::LARGE - 1)) {
            Some(short) => fields.push(short),
            None => {
                b.mesh.cards.not_carried.push(format!("{name} {id} ({at}: field {} '{f}' is too long)", k + 2));
                return Ok(());
            }
        }
    }
    while fields.last().is_some_and(String::is_empty) {
        fields.pop();
    }
    let material = name.starts_with("MAT");
    let list = if material { &b.mesh.cards.materials } else { &b.mesh.cards.properties };
    if let Some(first) = list.iter().find(|c| c.id == id) {
        let what = if material { "material" } else { "property" };
        return Err(b.syntax(
            loc,
            format!("{what} id {id} is defined twice ({} first at {}): ids must be unique", first.name, first.origin),
        ));
    }
    let kept = MeshCard { name: name.to_string(), id, fields, origin: at };
    if material {
        b.mesh.cards.materials.push(kept);
    } else {
        b.mesh.cards.properties.push(kept);
    }
    Ok(())
}

/// A coordinate system resolved to the basic one.
struct Frame {
    kind: CordKind,
    origin: nalgebra::Vector3<f64>,
    axes: [nalgebra::Vector3<f64>; 3],
}

impl Frame {
    /// Basic coordinates of the point with local coordinates `x` (r, theta deg, z for
    /// cylindrical; r, theta deg, phi deg for spherical).
    fn to_basic(&self, x: [f64; 3]) -> [f64; 3] {
        let l = match self.kind {
            CordKind::Rectangular => x,
            CordKind::Cylindrical => {
                let t = x[1].to_radians();
                [x[0] * t.cos(), x[0] * t.sin(), x[2]]
            }
            CordKind::Spherical => {
                let (t, p) = (x[1].to_radians(), x[2].to_radians());
                [x[0] * t.sin() * p.cos(), x[0] * t.sin() * p.sin(), x[0] * t.cos()]
            }
        };
        let p = self.origin + self.axes[0] * l[0] + self.axes[1] * l[1] + self.axes[2] * l[2];
        [p.x, p.y, p.z]
    }
}
