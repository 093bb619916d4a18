//! Reading a tool surface from a file: an OBJ, or any shell mesh of [`super::MESH_FORMATS`] (an
//! Abaqus mould deck, a Nastran or Gmsh mesh), its quads split into triangles. Every command and
//! the report read tools through [`read_tool`].
use super::{read_flow_mesh, FlowMeshError};
use crate::geometry::{ObjError, ToolSurface};
use std::path::{Path, PathBuf};

/// Why a tool file could not become a tool surface.
#[derive(Debug, thiserror::Error)]
pub enum ReadToolError {
    /// The OBJ could not be read or checked.
    #[error(transparent)]
    Obj(#[from] ObjError),
    /// The shell mesh could not be read.
    #[error(transparent)]
    Mesh(#[from] FlowMeshError),
    /// The shell mesh was read but its triangles fail the tool checks.
    #[error("tool {path}: {error}")]
    Check {
        /// The tool file.
        path: PathBuf,
        /// What the checks found.
        error: ObjError,
    },
}

/// Read a tool surface from `path` (see the module documentation); lengths scaled by `scale`
/// (metres per file unit).
pub fn read_tool(path: &Path, scale: f64) -> Result<ToolSurface, ReadToolError> {
    let is_obj = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("obj"));
    if is_obj {
        return Ok(ToolSurface::from_obj_scaled(path, scale)?);
    }
    let mesh = read_flow_mesh(path, scale)?;
    // Only the nodes the elements use: decks carry reference nodes (rigid bodies) that are not
    // part of the surface.
    let mut index = vec![u32::MAX; mesh.nodes.len()];
    let mut vertices = Vec::new();
    let mut triangles = Vec::new();
    for el in &mesh.elements {
        let ids: Vec<u32> = el
            .nodes
            .iter()
            .map(|&n| {
                if index[n] == u32::MAX {
                    index[n] = vertices.len() as u32;
                    vertices.push(mesh.nodes[n]);
                }
                index[n]
            })
            .collect();
        triangles.push([ids[0], ids[1], ids[2]]);
        if ids.len() == 4 {
            triangles.push([ids[0], ids[2], ids[3]]);
        }
    }
    ToolSurface::from_triangles(vertices, triangles).map_err(|error| ReadToolError::Check { path: path.into(), error })
}
