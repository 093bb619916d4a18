//! Abaqus input decks (`.inp`): reading shell meshes (tools and flow meshes) and writing the
//! fibre orientations of a layup on a flow mesh.
//!
//! # Reading
//! `*NODE` and `*ELEMENT` of three- and four-node shell,
//! membrane, surface and rigid types (S3, S3R, S3RS, STRI3, DS3, M3D3, R3D3, SFM3D3 -> Tria3;
//! S4, S4R, S4RS, S4R5, DS4, M3D4, M3D4R, R3D4, SFM3D4, SFM3D4R -> Quad4); other element types
//! are skipped.
//!
//! Keywords and parameter names are case-insensitive and blanks in them are ignored; `**`
//! starts a comment; a data line ending in a comma continues on the next data line.
//! `*INCLUDE, INPUT=file` is followed (path relative to the including deck). Parts and
//! assemblies: the contents of each `*PART` are placed once per `*INSTANCE, PART=...`, moved by
//! the instance's optional data lines (translation `dx, dy, dz`; then rotation `ax, ay, az,
//! bx, by, bz, angle` in degrees, right-handed about the axis from a to b; as in Abaqus the
//! translation is applied first). A deck with parts but no instance places each part once,
//! unmoved. Node and element ids must be unique over the whole placed mesh: a part instanced
//! twice needs a flattened deck. `*NODE, SYSTEM=C` (cylindrical R, theta in degrees, Z) is
//! converted; node generators (`*NGEN`, `*NCOPY`, `*ELGEN`, ...) and `*SYSTEM` are refused
//! rather than silently ignored.
//!
//! An element's property is a number per `ELSET` name given on its `*ELEMENT` line, 1, 2, ...
//! in the order the names first appear (names compared case-insensitively), 0 without ELSET.
//!
//! # Writing
//! The flow mesh as shell elements and, per ply, a local material
//! orientation per element (Abaqus Keywords Reference: *DISTRIBUTION TABLE, *DISTRIBUTION,
//! *ORIENTATION).
//!
//! Layout:
//! ```text
//! *NODE, NSET=DRAPE_NODES                        id, x, y, z
//! *ELEMENT, TYPE=S3, ELSET=DRAPE_S3              id, n1, n2, n3
//! *ELEMENT, TYPE=S4, ELSET=DRAPE_S4              id, n1, n2, n3, n4
//! *DISTRIBUTION TABLE, NAME=DRAPE_DIRECTIONS     COORD3D, COORD3D
//! per ply P (TAG = "P<k>_" + the ply name with characters other than A-Z, a-z, 0-9, _ as _):
//! *ELSET, ELSET=<TAG>                            the elements the ply covers (16 per line)
//! *ELSET, ELSET=<TAG>_UNCOVERED                  the others (only if any)
//! *DISTRIBUTION, NAME=<TAG>_DIR, LOCATION=ELEMENT, TABLE=DRAPE_DIRECTIONS
//! , 1., 0., 0., 0., 1., 0.                       default line (required; used by no element)
//! id, a1, a2, a3, b1, b2, b3                     a = warp, b = weft (covered elements only)
//! *ORIENTATION, NAME=<TAG>_ORI, SYSTEM=RECTANGULAR, DEFINITION=COORDINATES
//! <TAG>_DIR
//! 3, 0.
//! ```
//! Numbers have 13 significant digits in at most 20 characters, so that readers with fixed
//! fields (CalculiX) read them whole. CalculiX does not apply distributions to shell sections:
//! for it, write [`super::calculix`] decks.
//! Abaqus takes local 1 = a projected onto the shell and local 2 in the plane of a and b, so
//! local 1 is the warp; b = weft keeps the sheared weft in the file (angle a-b = 90 - shear).
//! Reference the orientation from your *SHELL SECTION / *SHELL SECTION, COMPOSITE on ELSET `<TAG>`.
use super::calculix::{elset, short};
use super::shell_mesh::{read_bytes, Builder, FlowMeshError, Loc};
use super::{write_atomic, ExportError};
use crate::mapping::{FlowMesh, LayupMap};
use nalgebra::Vector3;
use std::collections::HashMap;
use std::io::{self, Write};
use std::path::{Path, PathBuf};

/// Abaqus as a shell-mesh format.
pub const FORMAT: super::MeshFormat = super::MeshFormat { name: "Abaqus", extensions: &["inp"], read };
/// How deep `*INCLUDE` may nest before we assume a cycle.
const MAX_INCLUDE_DEPTH: usize = 32;

/// Read an Abaqus input deck (see the module documentation).
pub fn read(path: &Path, scale: f64) -> Result<FlowMesh, FlowMeshError> {
    let mut b = Builder::new(path, scale)?;
    let mut lines = Vec::new();
    load(&mut b, 0, 0, &mut lines)?;
    let deck = parse(&mut b, &lines)?;
    place(&mut b, deck)?;
    b.finish("S3/S4/S3R/S4R/M3D3/M3D4/R3D3/R3D4/SFM3D3/SFM3D4 and variants")
}

/// One line of the deck with where it came from.
struct Line {
    loc: Loc,
    text: String,
}

/// Shape of a keyword line: its name (upper case, blanks removed) and parameters (names upper
/// case, values as written, unquoted).
struct Keyword {
    name: String,
    params: Vec<(String, String)>,
}

impl Keyword {
    fn parse(text: &str) -> Keyword {
        let mut parts = text[1..].split(',');
        let name =
            parts.next().unwrap_or("").chars().filter(|c| !c.is_whitespace()).collect::<String>().to_ascii_uppercase();
        let params = parts
            .filter(|p| !p.trim().is_empty())
            .map(|p| {
                let (k, v) = p.split_once('=').unwrap_or((p, ""));
                let k: String = k.chars().filter(|c| !c.is_whitespace()).collect::<String>().to_ascii_uppercase();
                (k, v.trim().trim_matches('"').to_string())
            })
            .collect();
        Keyword { name, params }
    }

    fn param(&self, key: &str) -> Option<&str> {
        self.params.iter().find(|(k, _)| k == key).map(|(_, v)| v.as_str())
    }
}

/// Whether a trimmed line is a keyword line (`*` but not the `**` comment).
fn is_keyword(t: &str) -> bool {
    t.starts_with('*') && !t.starts_with("**")
}

/// Read `b.files[file]` into `out`, following `*INCLUDE` in place.
fn load(b: &mut Builder, file: usize, depth: usize, out: &mut Vec<Line>) -> Result<(), FlowMeshError> {
    let path = b.files[file].clone();
    let bytes = read_bytes(&path)?;
    let text = String::from_utf8_lossy(&bytes);
    for (k, l) in text.lines().enumerate() {
        let loc = Loc { file, line: k + 1 };
        let t = l.trim();
        if t.is_empty() || t.starts_with("**") {
            continue;
        }
        if is_keyword(t) {
            let kw = Keyword::parse(t);
            if kw.name == "INCLUDE" {
                let Some(input) = kw.param("INPUT").filter(|s| !s.is_empty()) else {
                    return Err(b.syntax(loc, "*INCLUDE needs INPUT=file"));
                };
                if depth >= MAX_INCLUDE_DEPTH {
                    return Err(b.syntax(
                        loc,
                        format!("*INCLUDE nested more than {MAX_INCLUDE_DEPTH} deep: is a file including itself?"),
                    ));
                }
                let target: PathBuf = path.parent().map(Path::to_path_buf).unwrap_or_default().join(input);
                if !target.is_file() {
                    return Err(b.syntax(
                        loc,
                        format!(
                            "*INCLUDE file {} does not exist (paths are relative to the including deck)",
                            target.display()
                        ),
                    ));
                }
                b.files.push(target);
                let f = b.files.len() - 1;
                load(b, f, depth + 1, out)?;
                continue;
            }
        }
        out.push(Line { loc, text: t.to_string() });
    }
    Ok(())
}

/// Nodes and elements of the model level, a part or an instance with its own contents.
#[derive(Default)]
struct Container {
    nodes: Vec<(u64, [f64; 3], Loc)>,
    elements: Vec<(u64, Vec<u64>, u64, Loc)>,
}

/// A placed part.
struct Instance {
    name: String,
    /// Upper-case part name; `None` for an instance that holds its own contents.
    part: Option<String>,
    own: Container,
    translation: Option<[f64; 3]>,
    rotation: Option<[f64; 7]>,
    loc: Loc,
}

#[derive(Default)]
struct Deck {
    top: Container,
    parts: HashMap<String, Container>,
    part_order: Vec<String>,
    instances: Vec<Instance>,
}

/// Where data lines go.
enum Mode {
    Ignore,
    Node { cylindrical: bool },
    Element { corners: Option<usize>, kind: String, property: u64 },
    InstanceData { seen: usize },
}

/// Corner count of a shell element type, `None` when the type is not a 3/4-node shell.
fn shell_corners(kind: &str) -> Option<usize> {
    match kind {
        "S3" | "S3R" | "S3RS" | "STRI3" | "DS3" | "M3D3" | "R3D3" | "SFM3D3" => Some(3),
        "S4" | "S4R" | "S4RS" | "S4R5" | "DS4" | "M3D4" | "M3D4R" | "R3D4" | "SFM3D4" | "SFM3D4R" => Some(4),
        _ => None,
    }
}

/// Keywords that create or move nodes or elements in ways this reader does not follow.
const REFUSED: [&str; 7] = ["NGEN", "NCOPY", "NFILL", "NMAP", "ELGEN", "ELCOPY", "SYSTEM"];

fn parse(b: &mut Builder, lines: &[Line]) -> Result<Deck, FlowMeshError> {
    let mut deck = Deck::default();
    let mut part: Option<String> = None;
    let mut instance: Option<usize> = None;
    let mut mode = Mode::Ignore;
    let mut elsets: HashMap<String, u64> = HashMap::new();
    let mut k = 0;
    while k < lines.len() {
        let start = &lines[k];
        k += 1;
        if is_keyword(&start.text) {
            // A keyword line ending in a comma continues on the next line.
            let mut text = start.text.clone();
            while text.ends_with(',') && k < lines.len() && !is_keyword(&lines[k].text) {
                text.push_str(&lines[k].text);
                k += 1;
            }
            let kw = Keyword::parse(&text);
            let loc = start.loc;
            mode = Mode::Ignore;
            match kw.name.as_str() {
                "PART" => {
                    let name = kw.param("NAME").ok_or_else(|| b.syntax(loc, "*PART needs NAME="))?.to_ascii_uppercase();
                    if deck.parts.contains_key(&name) {
                        return Err(b.syntax(loc, format!("part {name} is defined twice")));
                    }
                    deck.parts.insert(name.clone(), Container::default());
                    deck.part_order.push(name.clone());
                    part = Some(name);
                }
                "ENDPART" => part = None,
                "INSTANCE" => {
                    let name = kw.param("NAME").unwrap_or("").to_string();
                    let p = kw.param("PART").map(str::to_ascii_uppercase);
                    deck.instances.push(Instance {
                        name,
                        part: p,
                        own: Container::default(),
                        translation: None,
                        rotation: None,
                        loc,
                    });
                    instance = Some(deck.instances.len() - 1);
                    mode = Mode::InstanceData { seen: 0 };
                }
                "ENDINSTANCE" => instance = None,
                "NODE" => {
                    if kw.param("INPUT").is_some() {
                        return Err(
                            b.syntax(loc, "*NODE, INPUT= is not supported: put the nodes in the deck or use *INCLUDE")
                        );
                    }
                    let cylindrical = match kw.param("SYSTEM").map(str::to_ascii_uppercase).as_deref() {
                        None | Some("R") => false,
                        Some("C") => true,
                        Some(s) => return Err(b.syntax(loc, format!("*NODE, SYSTEM={s} is not supported (only R and C): export the nodes in rectangular coordinates"))),
                    };
                    mode = Mode::Node { cylindrical };
                }
                "ELEMENT" => {
                    if kw.param("INPUT").is_some() {
                        return Err(b.syntax(
                            loc,
                            "*ELEMENT, INPUT= is not supported: put the elements in the deck or use *INCLUDE",
                        ));
                    }
                    let kind =
                        kw.param("TYPE").ok_or_else(|| b.syntax(loc, "*ELEMENT needs TYPE="))?.to_ascii_uppercase();
                    let property = match kw.param("ELSET") {
                        Some(s) if !s.is_empty() => {
                            let n = elsets.len() as u64 + 1;
                            *elsets.entry(s.to_ascii_uppercase()).or_insert(n)
                        }
                        _ => 0,
                    };
                    mode = Mode::Element { corners: shell_corners(&kind), kind, property };
                }
                n if REFUSED.contains(&n) => {
                    return Err(b.syntax(loc, format!("*{n} is not supported: it generates or moves nodes/elements; export the mesh with every node and element written out")));
                }
                _ => {}
            }
            continue;
        }
        // A data line, joined with its continuations (trailing comma).
        let loc = start.loc;
        let mut text = start.text.clone();
        let kind_corners = if let Mode::Element { corners: Some(c), .. } = mode { Some(c) } else { None };
        loop {
            let enough = kind_corners.is_some_and(|c| entries(&text).len() > c);
            if !text.ends_with(',') || enough || k >= lines.len() || is_keyword(&lines[k].text) {
                break;
            }
            text.push_str(&lines[k].text);
            k += 1;
        }
        let target: &mut Container = match (instance, &part) {
            (Some(i), _) => &mut deck.instances[i].own,
            (None, Some(p)) => deck.parts.get_mut(p).expect("part registered at *PART"),
            (None, None) => &mut deck.top,
        };
        match &mut mode {
            Mode::Ignore => {}
            Mode::Node { cylindrical } => {
                let e = entries(&text);
                let id = int(b, e[0], loc, "node id")?;
                let mut x = [0.0; 3];
                for (i, xi) in x.iter_mut().enumerate() {
                    if let Some(s) = e.get(i + 1).filter(|s| !s.is_empty()) {
                        *xi = real(b, s, loc, "node coordinate")?;
                    }
                }
                if *cylindrical {
                    let t = x[1].to_radians();
                    x = [x[0] * t.cos(), x[0] * t.sin(), x[2]];
                }
                target.nodes.push((id, x, loc));
            }
            Mode::Element { corners, kind, property } => match corners {
                Some(c) => {
                    let e = entries(&text);
                    if e.len() < *c + 1 {
                        return Err(b.syntax(loc, format!("{kind} element needs an id and {c} nodes, found '{text}'")));
                    }
                    let id = int(b, e[0], loc, "element id")?;
                    let mut nodes = Vec::with_capacity(*c);
                    for s in &e[1..=*c] {
                        nodes.push(int(b, s, loc, "element node")?);
                    }
                    target.elements.push((id, nodes, *property, loc));
                }
                None => b.skip(kind),
            },
            Mode::InstanceData { seen } => {
                let e = entries(&text);
                let v: Vec<f64> = e
                    .iter()
                    .map(|s| if s.is_empty() { Ok(0.0) } else { real(b, s, loc, "instance placement") })
                    .collect::<Result<_, _>>()?;
                let inst = &mut deck.instances[instance.expect("instance data only inside *INSTANCE")];
                match (*seen, v.len()) {
                    (0, 3) => inst.translation = Some([v[0], v[1], v[2]]),
                    (1, 7) => inst.rotation = Some([v[0], v[1], v[2], v[3], v[4], v[5], v[6]]),
                    _ => {
                        return Err(b.syntax(
                            loc,
                            "*INSTANCE data: expected a translation line 'dx, dy, dz' then a rotation line 'ax, ay, az, bx, by, bz, angle'",
                        ))
                    }
                }
                *seen += 1;
            }
        }
    }
    Ok(deck)
}

/// Comma-separated entries of a data line, trimmed, without the empty one after a trailing comma.
fn entries(text: &str) -> Vec<&str> {
    let mut e: Vec<&str> = text.split(',').map(str::trim).collect();
    while e.last().is_some_and(|s| s.is_empty()) && e.len() > 1 {
        e.pop();
    }
    e
}

fn int(b: &Builder, s: &str, loc: Loc, what: &str) -> Result<u64, FlowMeshError> {
    s.parse().map_err(|_| b.syntax(loc, format!("{what}: '{s}' is not a positive integer")))
}

fn real(b: &Builder, s: &str, loc: Loc, what: &str) -> Result<f64, FlowMeshError> {
    // Abaqus also accepts Fortran's D exponent.
    s.replace(['d', 'D'], "E").parse().map_err(|_| b.syntax(loc, format!("{what}: '{s}' is not a number")))
}

/// Put the model-level contents and every instance into the builder.
fn place(b: &mut Builder, deck: Deck) -> Result<(), FlowMeshError> {
    let Deck { top, parts, part_order, instances } = deck;
    add(b, &top, None, "the model level")?;
    if instances.is_empty() {
        for name in &part_order {
            add(b, &parts[name], None, &format!("part {name}"))?;
        }
        return Ok(());
    }
    for inst in &instances {
        let contents = match &inst.part {
            Some(p) => parts.get(p).ok_or_else(|| {
                b.syntax(
                    inst.loc,
                    format!("*INSTANCE {} refers to part {p}, which the deck does not define", inst.name),
                )
            })?,
            None => &inst.own,
        };
        let axis = match inst.rotation {
            Some(r) => {
                let a = Vector3::new(r[0], r[1], r[2]);
                let d = Vector3::new(r[3], r[4], r[5]) - a;
                if d.norm() == 0.0 {
                    return Err(
                        b.syntax(inst.loc, format!("*INSTANCE {}: rotation axis points a and b coincide", inst.name))
                    );
                }
                Some((a, d.normalize(), r[6].to_radians()))
            }
            None => None,
        };
        let t = inst.translation.map_or(Vector3::zeros(), |t| Vector3::new(t[0], t[1], t[2]));
        let f = move |x: [f64; 3]| -> [f64; 3] {
            let mut p = Vector3::new(x[0], x[1], x[2]) + t;
            if let Some((a, k, th)) = axis {
                // Rodrigues' rotation of p about the axis through a along k.
                let v = p - a;
                p = a + v * th.cos() + k.cross(&v) * th.sin() + k * k.dot(&v) * (1.0 - th.cos());
            }
            [p.x, p.y, p.z]
        };
        add(b, contents, Some(&f), &format!("instance {}", inst.name))?;
    }
    Ok(())
}

/// Add a container's nodes (moved by `f`) and elements; ids repeated across parts or instances
/// are reported with what to do.
fn add(
    b: &mut Builder,
    c: &Container,
    f: Option<&dyn Fn([f64; 3]) -> [f64; 3]>,
    what: &str,
) -> Result<(), FlowMeshError> {
    const HINT: &str = "node and element ids must be unique over the placed parts; a part instanced more than once (or parts numbered from 1 each) repeats ids: write a flattened deck (Abaqus/CAE: Model > Edit Attributes > check 'Do not use parts and assemblies in input files')";
    for &(id, x, loc) in &c.nodes {
        if let Some(&(_, first)) = b.node_index.get(&id) {
            let at = format!("{} line {}", b.files[first.file].display(), first.line);
            return Err(b.syntax(loc, format!("node id {id} of {what} is already defined ({at}): {HINT}")));
        }
        b.add_node(id, f.map_or(x, |f| f(x)), loc)?;
    }
    for (id, nodes, prop, loc) in &c.elements {
        if let Some(first) = b.element_loc.get(id).copied() {
            let at = format!("{} line {}", b.files[first.file].display(), first.line);
            return Err(b.syntax(*loc, format!("element id {id} of {what} is already defined ({at}): {HINT}")));
        }
        b.add_element(*id, nodes, *prop, *loc)?;
    }
    Ok(())
}

// ---- writing -------------------------------------------------------------------------------

/// Name of the shared distribution table.
pub const TABLE: &str = "DRAPE_DIRECTIONS";

pub(crate) fn write_flow(mesh: &FlowMesh, map: &LayupMap, out: &Path) -> Result<(), ExportError> {
    write_atomic(out, |w| write_flow_to(mesh, map, w))
}

/// The Abaqus name of ply `k` (0-based): unique, starts with a letter, at most 80 characters.
pub fn ply_tag(k: usize, ply: &str) -> String {
    let clean: String = ply.chars().map(|c| if c.is_ascii_alphanumeric() || c == '_' { c } else { '_' }).collect();
    let mut tag = format!("P{}_{clean}", k + 1);
    tag.truncate(64); // room for the _UNCOVERED / _DIR / _ORI suffixes
    tag
}

fn write_flow_to<W: Write>(mesh: &FlowMesh, map: &LayupMap, w: &mut W) -> io::Result<()> {
    writeln!(w, "** drape: fibre orientations on flow mesh {}", mesh.path.display())?;
    writeln!(w, "*HEADING")?;
    writeln!(w, "drape fibre orientations, {} ply(s)", map.plies.len())?;
    for (k, ply) in map.plies.iter().enumerate() {
        writeln!(w, "** ply {} '{}' -> {}", k + 1, ply.ply.replace(['\n', '\r'], " "), ply_tag(k, &ply.ply))?;
    }
    super::calculix::write_mesh(mesh, w)?;
    writeln!(w, "*DISTRIBUTION TABLE, NAME={TABLE}")?;
    writeln!(w, "COORD3D, COORD3D")?;
    for (k, ply) in map.plies.iter().enumerate() {
        let tag = ply_tag(k, &ply.ply);
        let ids = |covered: bool| -> Vec<u64> {
            mesh.elements.iter().zip(&ply.elements).filter(|(_, f)| f.is_some() == covered).map(|(e, _)| e.id).collect()
        };
        let (cov, unc) = (ids(true), ids(false));
        elset(w, &tag, &cov)?;
        if !unc.is_empty() {
            writeln!(
                w,
                "** {} element(s) not covered by ply '{}': no orientation",
                unc.len(),
                ply.ply.replace(['\n', '\r'], " ")
            )?;
            elset(w, &format!("{tag}_UNCOVERED"), &unc)?;
        }
        writeln!(w, "*DISTRIBUTION, NAME={tag}_DIR, LOCATION=ELEMENT, TABLE={TABLE}")?;
        writeln!(w, ", 1., 0., 0., 0., 1., 0.")?;
        for (el, f) in mesh.elements.iter().zip(&ply.elements) {
            if let Some(f) = f {
                let (a, b) = (f.warp, f.weft);
                writeln!(w, "{}, {}", el.id, [a.x, a.y, a.z, b.x, b.y, b.z].map(short).join(", "))?;
            }
        }
        writeln!(w, "*ORIENTATION, NAME={tag}_ORI, SYSTEM=RECTANGULAR, DEFINITION=COORDINATES")?;
        writeln!(w, "{tag}_DIR")?;
        writeln!(w, "3, 0.")?;
    }
    Ok(())
}

