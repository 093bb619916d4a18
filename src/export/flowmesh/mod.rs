//! Resin-flow meshes: the user's own shell mesh of the part (not the drape grid), read from
//! Nastran bulk data (GRID/CTRIA3/CQUAD4 in fixed, large and free fields), Abaqus input decks
//! (*NODE/*ELEMENT, S3/S4/S3R/S4R/M3D3/M3D4/R3D3/R3D4, parts and instances), OBJ and Gmsh 4.1
//! `.msh` (ASCII and binary).
//!
//! Every reader returns a [`FlowMesh`]: nodes in metres (scaled by the caller's unit factor),
//! the ids the file gave them, and three- and four-node shell elements with their own ids, so
//! that writers can give results back under the user's numbering.
use crate::geometry::{Point, Vector};
use std::collections::{BTreeMap, HashMap};
use std::hash::{BuildHasherDefault, Hasher};
use std::path::{Path, PathBuf};

mod abaqus;
mod gmsh;
mod nastran;
mod obj;

pub use abaqus::read_abaqus;
pub use gmsh::read_gmsh;
pub use nastran::{parse_nastran_real, read_nastran};
pub use obj::read_obj;

/// Why a flow mesh could not be read. Messages name the file, the line and what to do.
#[derive(Debug, thiserror::Error)]
pub enum FlowMeshError {
    #[error("cannot read flow mesh {path}: {source}. Check the path.")]
    Io { path: PathBuf, source: std::io::Error },
    #[error(
        "flow mesh {path}: unknown file type: use .bdf/.nas/.dat/.fem (Nastran), .inp (Abaqus), .obj or .msh (Gmsh 4)"
    )]
    UnknownFormat { path: PathBuf },
    #[error("flow mesh {path} line {line}: {message}")]
    Syntax { path: PathBuf, line: usize, message: String },
    #[error("flow mesh {path}: {message}")]
    Invalid { path: PathBuf, message: String },
}

/// Shape of a shell element of a flow mesh.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ElementShape {
    /// Three-node triangle (CTRIA3, S3, M3D3, ...).
    Tria3,
    /// Four-node quadrilateral (CQUAD4, S4, M3D4, ...).
    Quad4,
}

impl ElementShape {
    /// Number of corner nodes.
    pub fn corners(self) -> usize {
        match self {
            ElementShape::Tria3 => 3,
            ElementShape::Quad4 => 4,
        }
    }
}

/// One shell element of a flow mesh.
#[derive(Debug, Clone, PartialEq)]
pub struct FlowElement {
    /// Element id in the source file (for OBJ: the face number, from 1).
    pub id: u64,
    pub shape: ElementShape,
    /// Corner node indices into [`FlowMesh::nodes`], in the file's order (G1, G2, G3[, G4]).
    pub nodes: Vec<usize>,
    /// Property / section / physical-group id from the source file, 0 when it has none.
    pub property: u64,
}

/// A shell mesh of the part, in metres.
#[derive(Debug, Clone, Default)]
pub struct FlowMesh {
    /// The file it was read from.
    pub path: PathBuf,
    /// Node coordinates in metres.
    pub nodes: Vec<Point>,
    /// Node ids in the source file, one per node (for OBJ: the vertex number, from 1).
    pub node_ids: Vec<u64>,
    pub elements: Vec<FlowElement>,
}

impl FlowMesh {
    /// Corner points of element `e`.
    pub fn corners(&self, e: usize) -> Vec<Point> {
        self.elements[e].nodes.iter().map(|&n| self.nodes[n]).collect()
    }

    /// Centroid (mean of the corners) of element `e`.
    pub fn centroid(&self, e: usize) -> Point {
        let c = self.corners(e);
        let sum = c.iter().fold(Vector::zeros(), |s, p| s + p.coords);
        Point::from(sum / c.len() as f64)
    }

    /// Area-weighted normal of element `e` (Newell's method; for a warped quad the normal of its
    /// mean plane), of length twice the area for a triangle and the projected area x 2 for a
    /// quad. Zero for a degenerate element.
    pub fn area_normal(&self, e: usize) -> Vector {
        let c = self.corners(e);
        let mut n = Vector::zeros();
        for k in 0..c.len() {
            n += c[k].coords.cross(&c[(k + 1) % c.len()].coords);
        }
        n
    }

    /// Unit normal of element `e` (right-handed over G1, G2, G3...), or `None` if degenerate.
    pub fn normal(&self, e: usize) -> Option<Vector> {
        let n = self.area_normal(e);
        let len = n.norm();
        (len > 0.0 && len.is_finite()).then(|| n / len)
    }

    /// Area of element `e` (of its mean plane for a warped quad).
    pub fn area(&self, e: usize) -> f64 {
        0.5 * self.area_normal(e).norm()
    }

    /// Unit direction of the element's first edge G1 -> G2 projected into its plane: the
    /// reference of Nastran's material angle THETA.
    pub fn first_edge(&self, e: usize) -> Option<Vector> {
        let n = self.normal(e)?;
        let el = &self.elements[e];
        let d = self.nodes[el.nodes[1]] - self.nodes[el.nodes[0]];
        let d = d - n * n.dot(&d);
        let len = d.norm();
        (len > 0.0).then(|| d / len)
    }
}

/// Read a flow mesh, choosing the reader by the file extension (case ignored): `.bdf`, `.nas`,
/// `.dat`, `.fem`, `.blk` Nastran; `.inp` Abaqus; `.obj`; `.msh` Gmsh 4. Lengths are multiplied by
/// `scale` (metres per file unit).
///
/// Every reader refuses a mesh with no three- or four-node shell element, a non-finite
/// coordinate, a repeated node or element id, or an element naming a node that is not defined.
/// Elements that are not three- or four-node shells (CTRIA6, CHEXA, C3D8, lines, points...)
/// are skipped; how many of each were skipped is only reported when nothing usable is left.
pub fn read_flow_mesh(path: &Path, scale: f64) -> Result<FlowMesh, FlowMeshError> {
    let ext = path.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase()).unwrap_or_default();
    match ext.as_str() {
        "bdf" | "nas" | "dat" | "fem" | "blk" => read_nastran(path, scale),
        "inp" => read_abaqus(path, scale),
        "obj" => read_obj(path, scale),
        "msh" => read_gmsh(path, scale),
        _ => Err(FlowMeshError::UnknownFormat { path: path.into() }),
    }
}

impl FlowMesh {
    /// Index in [`FlowMesh::nodes`] of the node with file id `id` (a linear search: build a map
    /// for many look-ups).
    pub fn node_by_id(&self, id: u64) -> Option<usize> {
        self.node_ids.iter().position(|&n| n == id)
    }

    /// The file ids of the corners of element `e`.
    pub fn element_node_ids(&self, e: usize) -> Vec<u64> {
        self.elements[e].nodes.iter().map(|&n| self.node_ids[n]).collect()
    }
}

/// Read the whole file, naming it in the error.
fn read_bytes(path: &Path) -> Result<Vec<u8>, FlowMeshError> {
    std::fs::read(path).map_err(|source| FlowMeshError::Io { path: path.into(), source })
}

/// Hash map keyed by file ids: ids are trusted integers, so a multiplicative hash is enough and
/// several times faster than the default SipHash on million-element meshes.
type IdMap<V> = HashMap<u64, V, BuildHasherDefault<IdHasher>>;

/// Fibonacci (multiplicative) hashing of a `u64` id.
#[derive(Default)]
struct IdHasher(u64);

impl Hasher for IdHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(u64::from(b));
        }
    }
    fn write_u64(&mut self, x: u64) {
        // Fold the high half in so ids differing only in high bits still spread.
        self.0 = (self.0 ^ x ^ (x >> 32)).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    }
}

/// Where a card or line came from, for error messages: index into [`Builder::files`] and the
/// 1-based line number.
#[derive(Debug, Clone, Copy)]
struct Loc {
    file: usize,
    line: usize,
}

/// An element whose node ids are resolved once every node is known (Nastran allows elements
/// before their GRIDs).
struct Pending {
    id: u64,
    shape: ElementShape,
    nodes: [u64; 4],
    property: u64,
    loc: Loc,
}

/// Shared assembly of a [`FlowMesh`] by the readers: scaling, the id checks and the final
/// "is there anything usable" check, so every format reports the same problems the same way.
struct Builder {
    /// Files read (the deck and its includes); `Loc::file` indexes this.
    files: Vec<PathBuf>,
    scale: f64,
    mesh: FlowMesh,
    /// Node id -> index in `mesh.nodes`, and where it was defined.
    node_index: IdMap<(usize, Loc)>,
    element_loc: IdMap<Loc>,
    pending: Vec<Pending>,
    /// Skipped element kinds and how many of each, for the "no shell elements" message.
    skipped: BTreeMap<String, usize>,
}

impl Builder {
    /// A builder for `path`; refuses a scale that is not a positive finite number.
    fn new(path: &Path, scale: f64) -> Result<Builder, FlowMeshError> {
        if !(scale.is_finite() && scale > 0.0) {
            return Err(FlowMeshError::Invalid {
                path: path.into(),
                message: format!("length scale {scale} must be a positive finite number (metres per file unit)"),
            });
        }
        Ok(Builder {
            files: vec![path.to_path_buf()],
            scale,
            mesh: FlowMesh { path: path.to_path_buf(), ..FlowMesh::default() },
            node_index: IdMap::default(),
            element_loc: IdMap::default(),
            pending: Vec::new(),
            skipped: BTreeMap::new(),
        })
    }

    /// A syntax error at `loc`.
    fn syntax(&self, loc: Loc, message: impl Into<String>) -> FlowMeshError {
        FlowMeshError::Syntax { path: self.files[loc.file].clone(), line: loc.line, message: message.into() }
    }

    /// Add node `id` at `xyz` (file units); returns its index.
    fn add_node(&mut self, id: u64, xyz: [f64; 3], loc: Loc) -> Result<usize, FlowMeshError> {
        let p = Point::new(xyz[0] * self.scale, xyz[1] * self.scale, xyz[2] * self.scale);
        if !(p.x.is_finite() && p.y.is_finite() && p.z.is_finite()) {
            return Err(self.syntax(
                loc,
                format!(
                    "node {id} has a non-finite coordinate ({}, {}, {}) (after scaling by {}): fix the coordinate",
                    xyz[0], xyz[1], xyz[2], self.scale
                ),
            ));
        }
        let k = self.mesh.nodes.len();
        if let Some(&(_, first)) = self.node_index.get(&id) {
            return Err(self.syntax(
                loc,
                format!(
                    "node id {id} is defined twice (first in {} line {}): node ids must be unique",
                    self.files[first.file].display(),
                    first.line
                ),
            ));
        }
        self.node_index.insert(id, (k, loc));
        self.mesh.nodes.push(p);
        self.mesh.node_ids.push(id);
        Ok(k)
    }

    /// Add element `id` over the node ids `nodes` (3 or 4 of them); they are resolved in
    /// [`Builder::finish`].
    fn add_element(&mut self, id: u64, nodes: &[u64], property: u64, loc: Loc) -> Result<(), FlowMeshError> {
        let shape = match nodes.len() {
            3 => ElementShape::Tria3,
            4 => ElementShape::Quad4,
            n => return Err(self.syntax(loc, format!("element {id} has {n} corners; only 3 or 4 are shell elements"))),
        };
        if let Some(first) = self.element_loc.insert(id, loc) {
            return Err(self.syntax(
                loc,
                format!(
                    "element id {id} is used twice (first in {} line {}): element ids must be unique",
                    self.files[first.file].display(),
                    first.line
                ),
            ));
        }
        let mut n = [0u64; 4];
        n[..nodes.len()].copy_from_slice(nodes);
        self.pending.push(Pending { id, shape, nodes: n, property, loc });
        Ok(())
    }

    /// Count an element that is not a three- or four-node shell.
    fn skip(&mut self, kind: &str) {
        *self.skipped.entry(kind.to_string()).or_insert(0) += 1;
    }

    /// Resolve the elements' node ids and check the mesh has shell elements. `what` names the
    /// element kinds the format's reader keeps, for the message when there are none.
    fn finish(mut self, what: &str) -> Result<FlowMesh, FlowMeshError> {
        let pending = std::mem::take(&mut self.pending);
        let mut elements = Vec::with_capacity(pending.len());
        for p in pending {
            let corners = &p.nodes[..p.shape.corners()];
            let mut nodes = Vec::with_capacity(corners.len());
            for &g in corners {
                match self.node_index.get(&g) {
                    Some(&(k, _)) => nodes.push(k),
                    None => {
                        return Err(self.syntax(
                            p.loc,
                            format!("element {} refers to node {g}, which the file does not define", p.id),
                        ))
                    }
                }
            }
            elements.push(FlowElement { id: p.id, shape: p.shape, nodes, property: p.property });
        }
        if elements.is_empty() {
            let skipped = if self.skipped.is_empty() {
                "no other elements".to_string()
            } else {
                let list: Vec<String> = self.skipped.iter().map(|(k, n)| format!("{n} {k}")).collect();
                format!("skipped {}", list.join(", "))
            };
            return Err(FlowMeshError::Invalid {
                path: self.files[0].clone(),
                message: format!(
                    "no three- or four-node shell elements ({what}) found: {} nodes, {skipped}. A flow mesh must be a shell (surface) mesh of the part",
                    self.mesh.nodes.len()
                ),
            });
        }
        self.mesh.elements = elements;
        Ok(self.mesh)
    }
}
