//! Triangle meshes as they come (from a file, or generated) and what the checks of a tool mesh
//! report ([`MeshReport`]) or refuse ([`ToolError`]).
use super::{Point, ToolSurface, Vector};
use std::path::PathBuf;

/// An indexed triangle mesh (0-based indices): a tool as read from a file, before the checks of
/// [`ToolSurface::from_mesh`], or a generated shape.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TriangleMesh {
    /// Vertex positions.
    pub vertices: Vec<Point>,
    /// Corner indices into `vertices`, counter-clockwise seen from the side the plies lie on.
    pub triangles: Vec<[u32; 3]>,
}

impl TriangleMesh {
    /// Check the mesh and build the queryable tool surface ([`ToolSurface::from_triangles`]).
    pub fn into_surface(self) -> Result<ToolSurface, ToolError> {
        ToolSurface::from_triangles(self.vertices, self.triangles)
    }

    /// Corner positions of triangle `t`.
    pub fn corners(&self, t: usize) -> [Point; 3] {
        self.triangles[t].map(|i| self.vertices[i as usize])
    }

    /// Unit normal of triangle `t` (`(b - a) x (c - a)`, normalised).
    pub fn normal(&self, t: usize) -> Vector {
        let [a, b, c] = self.corners(t);
        (b - a).cross(&(c - a)).normalize()
    }

    /// Total area of the triangles.
    pub fn area(&self) -> f64 {
        (0..self.triangles.len())
            .map(|t| {
                let [a, b, c] = self.corners(t);
                0.5 * (b - a).cross(&(c - a)).norm()
            })
            .sum()
    }
}

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

/// Why a mesh (a file, or triangles in memory) could not become a tool surface. Every message
/// names the file (`<memory>` for triangles in memory) and what to do.
#[derive(Debug, thiserror::Error)]
pub enum ToolError {
    /// The file could not be read.
    #[error("cannot read tool mesh {path}: {source}. Check the path and that the file is readable.")]
    Io {
        /// The file.
        path: PathBuf,
        /// What the system said.
        source: std::io::Error,
    },
    /// The file is not a valid OBJ.
    #[error("tool mesh {path} is not a valid OBJ file: {reason}. Export the surface again as a Wavefront OBJ with triangles or polygons.")]
    Parse {
        /// The file.
        path: PathBuf,
        /// Where and why.
        reason: String,
    },
    /// The file is not a valid STL.
    #[error(
        "tool mesh {path} is not a valid STL file: {reason}. Export the surface again as an STL (ASCII or binary)."
    )]
    ParseStl {
        /// The file.
        path: PathBuf,
        /// Where and why.
        reason: String,
    },
    /// The mesh has no faces.
    #[error(
        "tool mesh {path} has no faces. Export the surface (not only its points or curves) as triangles or polygons."
    )]
    Empty {
        /// The file.
        path: PathBuf,
    },
    /// `index` is the vertex number: 1-based in file order (as OBJ counts) for a file, 0-based
    /// for an in-memory mesh.
    #[error("tool mesh {path}: vertex {index} has a non-finite coordinate ({value}). Fix or remove that vertex.")]
    NonFinite {
        /// The file.
        path: PathBuf,
        /// The vertex.
        index: usize,
        /// The coordinate.
        value: f64,
    },
    /// For a file, `face` is the 1-based number of the `f` statement and `index` the vertex
    /// number as written (1-based); for an in-memory mesh both are 0-based.
    #[error("tool mesh {path}: face {face} refers to vertex {index}, but the file has only {count} vertices. Re-export the mesh.")]
    BadIndex {
        /// The file.
        path: PathBuf,
        /// The face.
        face: usize,
        /// The vertex it names.
        index: usize,
        /// How many vertices there are.
        count: usize,
    },
    /// Every face has zero area.
    #[error("tool mesh {path}: every face is degenerate (zero area). Check the file's units and export settings.")]
    AllDegenerate {
        /// The file.
        path: PathBuf,
    },
}
