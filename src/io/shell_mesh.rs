//! What the shell-mesh readers ([`super::MESH_FORMATS`]) share: their error type and the
//! [`Builder`] that assembles a [`FlowMesh`] (scaling, id checks, the final "is there anything
//! usable" check), so every format reports the same problems the same way.
use crate::geometry::Point;
use crate::mapping::{ElementShape, FlowElement, FlowMesh};
use std::collections::{BTreeMap, HashMap};
use std::hash::{BuildHasherDefault, Hasher};
use std::path::{Path, PathBuf};

/// Why a flow mesh could not be read. Messages name the file, the line and what to do.
#[derive(Debug, thiserror::Error)]
pub enum FlowMeshError {
    /// The file could not be read.
    #[error("cannot read flow mesh {path}: {source}. Check the path.")]
    Io {
        /// The file.
        path: PathBuf,
        /// What the system said.
        source: std::io::Error,
    },
    /// No reader takes the file's extension.
    #[error("flow mesh {path}: unknown file type: use {known}")]
    UnknownFormat {
        /// The file.
        path: PathBuf,
        /// The extensions there are readers for.
        known: String,
    },
    /// A line of the file is wrong.
    #[error("flow mesh {path} line {line}: {message}")]
    Syntax {
        /// The file (the deck or an included one).
        path: PathBuf,
        /// The line.
        line: usize,
        /// What is wrong and what to do.
        message: String,
    },
    /// The file as a whole is unusable.
    #[error("flow mesh {path}: {message}")]
    Invalid {
        /// The file.
        path: PathBuf,
        /// What is wrong and what to do.
        message: String,
    },
}

/// Read the whole file, naming it in the error.
pub fn read_bytes(path: &Path) -> Result<Vec<u8>, FlowMeshError> {
    super::read::read_file(path).map_err(|source| FlowMeshError::Io { path: path.into(), source })
}

/// Hash map keyed by file ids: ids are trusted integers, so a multiplicative hash is enough and
/// several times faster than the default SipHash on million-element meshes.
pub type IdMap<V> = HashMap<u64, V, BuildHasherDefault<IdHasher>>;

/// Fibonacci (multiplicative) hashing of a `u64` id.
#[derive(Default)]
pub struct IdHasher(u64);

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
pub struct Loc {
    pub file: usize,
    pub line: usize,
}

/// An element whose node ids are resolved once every node is known (Nastran allows elements
/// before their GRIDs).
pub struct Pending {
    id: u64,
    shape: ElementShape,
    nodes: [u64; 4],
    property: u64,
    loc: Loc,
}

/// Shared assembly of a [`FlowMesh`] by the readers: scaling, the id checks and the final
/// "is there anything usable" check, so every format reports the same problems the same way.
pub struct Builder {
    /// Files read (the deck and its includes); `Loc::file` indexes this.
    pub files: Vec<PathBuf>,
    pub scale: f64,
    pub mesh: FlowMesh,
    /// Node id -> index in `mesh.nodes`, and where it was defined.
    pub node_index: IdMap<(usize, Loc)>,
    pub element_loc: IdMap<Loc>,
    pub pending: Vec<Pending>,
    /// Skipped element kinds and how many of each, for the "no shell elements" message.
    pub skipped: BTreeMap<String, usize>,
}

impl Builder {
    /// A builder for `path`; refuses a scale that is not a positive finite number.
    pub fn new(path: &Path, scale: f64) -> Result<Builder, FlowMeshError> {
        if !(scale.is_finite() && scale > 0.0) {
            return Err(FlowMeshError::Invalid {
                path: path.into(),
                message: format!("length scale {scale} must be a positive finite number (metres per file unit)"),
            });
        }
        Ok(Builder {
            files: vec![path.to_path_buf()],
            scale,
            mesh: FlowMesh { path: path.to_path_buf(), scale, ..FlowMesh::default() },
            node_index: IdMap::default(),
            element_loc: IdMap::default(),
            pending: Vec::new(),
            skipped: BTreeMap::new(),
        })
    }

    /// A syntax error at `loc`.
    pub fn syntax(&self, loc: Loc, message: impl Into<String>) -> FlowMeshError {
        FlowMeshError::Syntax { path: self.files[loc.file].clone(), line: loc.line, message: message.into() }
    }

    /// Add node `id` at `xyz` (file units); returns its index.
    pub fn add_node(&mut self, id: u64, xyz: [f64; 3], loc: Loc) -> Result<usize, FlowMeshError> {
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
    pub fn add_element(&mut self, id: u64, nodes: &[u64], property: u64, loc: Loc) -> Result<(), FlowMeshError> {
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
    pub fn skip(&mut self, kind: &str) {
        *self.skipped.entry(kind.to_string()).or_insert(0) += 1;
    }

    /// Resolve the elements' node ids and check the mesh has shell elements. `what` names the
    /// element kinds the format's reader keeps, for the message when there are none.
    pub fn finish(mut self, what: &str) -> Result<FlowMesh, FlowMeshError> {
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
