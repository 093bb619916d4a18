//! [`ExportError`]: why a file could not be written, or a net read back.
use std::io;
use std::path::PathBuf;

impl ExportError {
    /// Whether the input is at fault: the user's output path (a folder that cannot be created,
    /// a file where a folder should be, no permission to write), a ply name, or a flow export
    /// that the mesh, the plies or the options do not allow (nothing written): bad input, exit
    /// code 2.
    pub fn is_bad_input(&self) -> bool {
        use io::ErrorKind::*;
        match self {
            ExportError::CreateDir { .. } | ExportError::BadName { .. } | ExportError::FlowInvalid { .. } => true,
            ExportError::Write { source, .. } => {
                matches!(source.kind(), PermissionDenied | NotADirectory | IsADirectory | ReadOnlyFilesystem | NotFound)
            }
            _ => false,
        }
    }
}

/// Why a file could not be written (or a written net read back). Every message names the file,
/// node or cell at fault and what to do about it.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    /// The output folder could not be created.
    #[error("cannot create output directory {path}: {source}. Check the --out path and that its parent is writable.")]
    CreateDir {
        /// The folder.
        path: PathBuf,
        /// What the system said.
        source: io::Error,
    },
    /// A file could not be written (the previous version, if any, is untouched).
    #[error("cannot write {path}: {source}. Check that the directory is writable and the disk is not full; any previous version of the file was left untouched.")]
    Write {
        /// The file.
        path: PathBuf,
        /// What the system said.
        source: io::Error,
    },
    /// A net file could not be read.
    #[error("cannot read drape net {path}: {source}. Check the path and that the file is readable.")]
    Read {
        /// The file.
        path: PathBuf,
        /// What the system said.
        source: io::Error,
    },
    /// A net file is not JSON of the net's layout.
    #[error("drape net {path} is not valid JSON or does not have the drape-net layout (line {line}, column {column}): {message}. Re-create it with `drape run` instead of editing it by hand.")]
    Parse {
        /// The file.
        path: PathBuf,
        /// Where the parser stopped: line,
        line: usize,
        /// and column.
        column: usize,
        /// What the parser said.
        message: String,
    },
    /// A net file's fields do not fit together.
    #[error("drape net {path}: \"{field}\" {reason}. The file is truncated, was edited, or was not written by drape; re-create it with `drape run`.")]
    Invalid {
        /// The file.
        path: PathBuf,
        /// The field at fault.
        field: String,
        /// What is wrong with it.
        reason: String,
    },
    /// A net would need NaN or infinity in a file (a bug upstream; nothing is written).
    #[error("cannot export ply '{ply}': {reason}. This is a bug in the stage that computed the net (nothing was written); please report it together with the scene file.")]
    BadNet {
        /// The ply.
        ply: String,
        /// What is wrong with its net.
        reason: String,
    },
    /// A ply name that cannot be a file name.
    #[error("ply name '{ply}' cannot be used as an output file name ({reason}). Rename the ply in the scene file.")]
    BadName {
        /// The ply.
        ply: String,
        /// Why not.
        reason: String,
    },
    /// A mapped value is not finite (a bug in the mapping; nothing is written).
    #[error("cannot write the {format} flow export: ply '{ply}', element {element}: {field} is {value} (must be finite). This is a bug in the mapping stage (nothing was written); please report it together with the scene and flow mesh.")]
    FlowNonFinite {
        /// The flow format.
        format: &'static str,
        /// The ply.
        ply: String,
        /// The flow element's id.
        element: u64,
        /// The field.
        field: &'static str,
        /// Its value.
        value: f64,
    },
    /// A map that a flow format cannot write (nothing is written).
    #[error("cannot write the {format} flow export: {reason}. Nothing was written.")]
    FlowInvalid {
        /// The flow format.
        format: &'static str,
        /// Why not.
        reason: String,
    },
}
