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
    #[error("tool mesh {path} has no faces. Export the surface (not only its points or curves) as triangles or polygons.")]
    Empty { path: PathBuf },
    #[error("tool mesh {path}: vertex {index} has a non-finite coordinate ({value}). Fix or remove that vertex.")]
    NonFinite { path: PathBuf, index: usize, value: f64 },
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
pub fn read_obj(path: &Path) -> Result<(RawMesh, MeshReport), ObjError> {
    let _ = path;
    todo!("helper: read_obj")
}
