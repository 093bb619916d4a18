//! The resin-flow mesh: the user's own shell mesh of the part (not the drape grid), as the readers
//! in [`crate::io`] return it: nodes in metres with the ids the file gave them, and three- and
//! four-node shell elements with their own ids, so that writers can give results back under the
//! user's numbering.
use crate::geometry::{Point, Vector};
use std::path::PathBuf;

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
    /// Triangle or quad.
    pub shape: ElementShape,
    /// Corner node indices into [`FlowMesh::nodes`], in the file's order (G1, G2, G3[, G4]).
    pub nodes: Vec<usize>,
    /// Property / section / physical-group id from the source file, 0 when it has none.
    pub property: u64,
}

/// A shell mesh of the part, in metres.
#[derive(Debug, Clone)]
pub struct FlowMesh {
    /// The file it was read from.
    pub path: PathBuf,
    /// Node coordinates in metres.
    pub nodes: Vec<Point>,
    /// Node ids in the source file, one per node (for OBJ: the vertex number, from 1).
    pub node_ids: Vec<u64>,
    /// The elements, in file order.
    pub elements: Vec<FlowElement>,
    /// Metres per length unit of the file (1 for metres, 0.001 for millimetres): writers that
    /// carry the file's own cards through write lengths back in its unit.
    pub scale: f64,
    /// The property and material cards of the file, for the writers of its family to carry
    /// through (Nastran: PSHELL, PCOMP, PCOMPG, MAT1, MAT2, MAT8); empty for other formats.
    pub cards: MeshCards,
}

impl Default for FlowMesh {
    fn default() -> Self {
        FlowMesh {
            path: PathBuf::new(),
            nodes: Vec::new(),
            node_ids: Vec::new(),
            elements: Vec::new(),
            scale: 1.0,
            cards: MeshCards::default(),
        }
    }
}

/// One property or material card of a flow mesh's file, kept as read (in the file's units).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MeshCard {
    /// The card's name, upper case (`PSHELL`, `MAT8`, ...).
    pub name: String,
    /// Its id (the PID of a property, the MID of a material): its first data field.
    pub id: u64,
    /// Its data fields as text, the id first, in small-field numbering (eight a line, blanks
    /// kept as empty strings), each at most 15 characters.
    pub fields: Vec<String>,
    /// Where it was read: `file line n`.
    pub origin: String,
}

/// The property and material cards a flow mesh's file gives (see [`FlowMesh::cards`]).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct MeshCards {
    /// Property cards, in file order.
    pub properties: Vec<MeshCard>,
    /// Material cards, in file order.
    pub materials: Vec<MeshCard>,
    /// Cards of the same families that are not carried (temperature-dependent or nonlinear
    /// materials, say), named with where they are, for the writers to say so.
    pub not_carried: Vec<String>,
}

impl MeshCards {
    /// The property card with PID `id`.
    pub fn property(&self, id: u64) -> Option<&MeshCard> {
        self.properties.iter().find(|c| c.id == id)
    }

    /// The material card with MID `id`.
    pub fn material(&self, id: u64) -> Option<&MeshCard> {
        self.materials.iter().find(|c| c.id == id)
    }
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

/// An element with an area at most this times its longest edge squared, or with a G1 -> G2 edge
/// (in its plane) at most this times its longest edge, has no frame to map fibres into: its
/// corners are coincident or in a line, or G1 and G2 coincide. Far below any real element's
/// aspect ratio; only rounding separates such an element from an exactly degenerate one.
pub const DEGENERATE_RATIO: f64 = 1e-12;

/// Why an element has no frame (normal and first edge) to map fibres into.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Degeneracy {
    /// Its corners are coincident or in a line (a repeated node in a triangle, or opposite corners
    /// of a quad the same node, give this too).
    ZeroArea {
        /// Its area, in m^2.
        area: f64,
        /// Its longest edge, in m.
        longest_edge: f64,
    },
    /// G1 and G2 coincide (the same node, or two nodes at one place), so there is no first edge
    /// to measure the material angle THETA from.
    NoFirstEdge {
        /// The file id of G1.
        g1: u64,
        /// The file id of G2.
        g2: u64,
    },
}

impl std::fmt::Display for Degeneracy {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Degeneracy::ZeroArea { area, longest_edge } => write!(
                f,
                "zero area ({area:.3e} m^2 with a longest edge of {longest_edge:.3e} m): its corners are coincident or in a line"
            ),
            Degeneracy::NoFirstEdge { g1, g2 } if g1 == g2 => {
                write!(f, "G1 and G2 are the same node {g1}: it has no first edge to measure THETA from")
            }
            Degeneracy::NoFirstEdge { g1, g2 } => {
                write!(f, "G1 (node {g1}) and G2 (node {g2}) coincide: it has no first edge to measure THETA from")
            }
        }
    }
}

impl FlowMesh {
    /// Why element `e` has no frame to map fibres into, or `None` when it has one (see
    /// [`DEGENERATE_RATIO`]). A quad with one repeated corner away from G1-G2 is a triangle
    /// written as a quad (as Abaqus allows) and has a frame.
    pub fn degeneracy(&self, e: usize) -> Option<Degeneracy> {
        let c = self.corners(e);
        let longest_edge = (0..c.len()).map(|k| (c[(k + 1) % c.len()] - c[k]).norm()).fold(0.0, f64::max);
        let area = self.area(e);
        if !(area > DEGENERATE_RATIO * longest_edge * longest_edge) {
            return Some(Degeneracy::ZeroArea { area, longest_edge });
        }
        let n = self.area_normal(e) / (2.0 * area);
        let d = c[1] - c[0];
        let d = d - n * n.dot(&d);
        if !(d.norm() > DEGENERATE_RATIO * longest_edge) {
            let el = &self.elements[e];
            return Some(Degeneracy::NoFirstEdge { g1: self.node_ids[el.nodes[0]], g2: self.node_ids[el.nodes[1]] });
        }
        None
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
