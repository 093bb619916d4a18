//! File formats, one module per format with its reader and writer side by side, and the one
//! atomic writer every file goes through ([`write_atomic`]: a file appears whole or not at all).
//!
//! | module | reads | writes |
//! |---|---|---|
//! | [`net_json`] | `<ply>.drape.json` ([`read_net`]) | `<ply>.drape.json` |
//! | [`vtk`] | | `<ply>.vtu`, the flow mesh with fibres (`flow.vtu`) |
//! | [`csv`] | | `<ply>.cells.csv`, `flow.csv` |
//! | [`obj`] | tools and flow meshes | OBJ text of a triangle mesh |
//! | [`stl`] | tools and flow meshes (ASCII and binary) | ASCII and binary STL of a triangle mesh |
//! | [`nastran`] | flow meshes and tools (bulk data) | THETA decks |
//! | [`optistruct`], [`rtmsim`] | | ply-based decks, RTMsim mesh and parameters |
//! | [`abaqus`] | flow meshes and tools (input decks) | orientation decks |
//! | [`calculix`] | (as [`abaqus`]) | a shell section per orientation, for `ccx` |
//! | [`gmsh`] | flow meshes and tools (`.msh` 4.1) | |
//! | [`dxf`], [`svg`] | | cutting plans ([`drawing`] lays them out) |
//!
//! Nets are checked before any file is opened, so a net that would need NaN or infinity in a
//! file is refused and nothing partial is left behind. A new shell-mesh format is a new module
//! with a `FORMAT` and its name in the `mesh_formats!` list below.
mod atomic;
pub mod calculix;
mod check;
pub mod csv;
pub mod drawing;
pub mod dxf;
mod error;
pub mod flow;
pub mod layup_json;
pub mod net;
pub mod net_json;
pub mod optistruct;
pub mod points;
mod read;
pub mod rtmsim;
pub(crate) mod shell_mesh;
pub mod svg;
mod tool;
pub mod vtk;
pub mod xml;

pub use atomic::{write_atomic, SyncAheadFile};
pub use csv::{write_csv, CSV_HEADER};
pub use error::ExportError;
pub use net::{kinematic_net_path, write_net, write_net_shears, Format, KINEMATIC_NET_SUFFIX};
pub use net_json::{read_net, write_json};
pub use shell_mesh::FlowMeshError;
pub use tool::{read_tool, read_tool_mesh, ReadToolError, ToolMesh};
pub use vtk::write_vtu;

use crate::mapping::FlowMesh;
use std::path::Path;

/// A shell-mesh format that tools and flow meshes are read from.
pub struct MeshFormat {
    /// Name in messages.
    pub name: &'static str,
    /// File extensions it reads, lower case, without the dot.
    pub extensions: &'static [&'static str],
    /// The reader: lengths are multiplied by `scale` (metres per file unit).
    pub read: fn(&Path, f64) -> Result<FlowMesh, FlowMeshError>,
}

/// Declares each shell-mesh format module and lists its `FORMAT` in [`MESH_FORMATS`].
macro_rules! mesh_formats {
    ($($module:ident),* $(,)?) => {
        $(pub mod $module;)*
        /// Every shell-mesh format, one per module.
        pub const MESH_FORMATS: &[&MeshFormat] = &[$(&$module::FORMAT),*];
    };
}

mesh_formats!(nastran, abaqus, obj, stl, gmsh);

/// Read a shell mesh (a flow mesh, or a tool given as a mesh), choosing the reader by the file
/// extension (case ignored, see [`MESH_FORMATS`]). Lengths are multiplied by `scale` (metres per
/// file unit).
///
/// Every reader refuses a mesh with no three- or four-node shell element, a non-finite
/// coordinate, a repeated node or element id, or an element naming a node that is not defined.
/// Elements that are not three- or four-node shells (CTRIA6, CHEXA, C3D8, lines, points...)
/// are skipped; how many of each were skipped is only reported when nothing usable is left.
pub fn read_flow_mesh(path: &Path, scale: f64) -> Result<FlowMesh, FlowMeshError> {
    let ext = path.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase()).unwrap_or_default();
    match MESH_FORMATS.iter().find(|f| f.extensions.contains(&ext.as_str())) {
        Some(format) => (format.read)(path, scale),
        None => Err(FlowMeshError::UnknownFormat { path: path.into(), known: known_mesh_formats() }),
    }
}

/// The readable extensions, for messages: `.bdf/.nas (Nastran), .inp (Abaqus)`.
fn known_mesh_formats() -> String {
    let each: Vec<String> = MESH_FORMATS
        .iter()
        .map(|f| {
            let ext: Vec<String> = f.extensions.iter().map(|e| format!(".{e}")).collect();
            format!("{} ({})", ext.join("/"), f.name)
        })
        .collect();
    each.join(", ")
}
