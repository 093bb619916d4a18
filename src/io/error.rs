//! [`ExportError`]: why a net could not be written or read back.
use std::io;
use std::path::PathBuf;

/// Why a net could not be written (or a written net read back). Every message names the file,
/// node or cell at fault and what to do about it.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    #[error("cannot create output directory {path}: {source}. Check the --out path and that its parent is writable.")]
    CreateDir { path: PathBuf, source: io::Error },
    #[error("cannot write {path}: {source}. Check that the directory is writable and the disk is not full; any previous version of the file was left untouched.")]
    Write { path: PathBuf, source: io::Error },
    #[error("cannot read drape net {path}: {source}. Check the path and that the file is readable.")]
    Read { path: PathBuf, source: io::Error },
    #[error("drape net {path} is not valid JSON or does not have the drape-net layout (line {line}, column {column}): {message}. Re-create it with `drape run` instead of editing it by hand.")]
    Parse { path: PathBuf, line: usize, column: usize, message: String },
    #[error("drape net {path}: \"{field}\" {reason}. The file is truncated, was edited, or was not written by drape; re-create it with `drape run`.")]
    Invalid { path: PathBuf, field: String, reason: String },
    #[error("cannot export ply '{ply}': {reason}. This is a bug in the stage that computed the net (nothing was written); please report it together with the scene file.")]
    BadNet { ply: String, reason: String },
    #[error("ply name '{ply}' cannot be used as an output file name ({reason}). Rename the ply in the scene file.")]
    BadName { ply: String, reason: String },
    #[error("cannot write the {format} flow export: ply '{ply}', element {element}: {field} is {value} (must be finite). This is a bug in the mapping stage (nothing was written); please report it together with the scene and flow mesh.")]
    FlowNonFinite { format: &'static str, ply: String, element: u64, field: &'static str, value: f64 },
    #[error("cannot write the {format} flow export: {reason}. Nothing was written.")]
    FlowInvalid { format: &'static str, reason: String },
}
