//! Reading a tool surface from a file: an OBJ or STL (read with the same checks), or any shell mesh of [`super::MESH_FORMATS`] (an
//! Abaqus mould deck, a Nastran or Gmsh mesh), its quads split into triangles. Every command and
//! the report read tools through [`read_tool`].
use super::obj::read_obj;
use super::stl::read_stl;
use super::{read_flow_mesh, FlowMeshError};
use crate::geometry::{MeshReport, ToolError, ToolSurface, TriangleMesh};
use std::path::{Path, PathBuf};

/// Why a tool file could not become a tool surface.
#[derive(Debug, thiserror::Error)]
pub enum ReadToolError {
    /// The OBJ or STL could not be read or checked.
    #[error(transparent)]
    Obj(#[from] ToolError),
    /// The shell mesh could not be read.
    #[error(transparent)]
    Mesh(#[from] FlowMeshError),
    /// The shell mesh was read but its triangles fail the tool checks.
    #[error("tool {path}: {error}")]
    Check {
        /// The tool file.
        path: PathBuf,
        /// What the checks found.
        error: ToolError,
    },
}

/// Read a tool surface from `path` (see the module documentation); lengths scaled by `scale`
/// (metres per file unit).
pub fn read_tool(path: &Path, scale: f64) -> Result<ToolSurface, ReadToolError> {
    match read_tool_mesh(path, scale)? {
        ToolMesh::Surface(mesh, report) => Ok(ToolSurface::from_mesh(mesh, report, path)?),
        ToolMesh::Shell(mesh) => mesh.into_surface().map_err(|error| ReadToolError::Check { path: path.into(), error }),
    }
}

/// A tool's triangles as its file gives them, before the checks (what the report draws).
pub enum ToolMesh {
    /// From an OBJ or STL, with what reading it found.
    Surface(TriangleMesh, MeshReport),
    /// From a shell mesh: its elements, quads split into two triangles.
    Shell(TriangleMesh),
}

impl ToolMesh {
    /// The triangles.
    pub fn into_mesh(self) -> TriangleMesh {
        match self {
            ToolMesh::Surface(m, _) | ToolMesh::Shell(m) => m,
        }
    }
}

/// Read the triangles of a tool file (see the module documentation), lengths scaled by `scale`,
/// without checking or mending them.
pub fn read_tool_mesh(path: &Path, scale: f64) -> Result<ToolMesh, ReadToolError> {
    let ext = path.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase()).unwrap_or_default();
    if ext == "obj" || ext == "stl" {
        let (mut mesh, report) = if ext == "obj" { read_obj(path)? } else { read_stl(path)? };
        if scale != 1.0 {
            mesh.vertices.iter_mut().for_each(|v| *v *= scale);
        }
        return Ok(ToolMesh::Surface(mesh, report));
    }
    let shell = read_flow_mesh(path, scale)?;
    // Only the nodes the elements use: decks carry reference nodes (rigid bodies) that are not
    // part of the surface.
    let mut index = vec![u32::MAX; shell.nodes.len()];
    let mut mesh = TriangleMesh::default();
    for el in &shell.elements {
        let ids: Vec<u32> = el
            .nodes
            .iter()
            .map(|&n| {
                if index[n] == u32::MAX {
                    index[n] = mesh.vertices.len() as u32;
                    mesh.vertices.push(shell.nodes[n]);
                }
                index[n]
            })
            .collect();
        mesh.triangles.push([ids[0], ids[1], ids[2]]);
        if ids.len() == 4 {
            mesh.triangles.push([ids[0], ids[2], ids[3]]);
        }
    }
    Ok(ToolMesh::Shell(mesh))
}
