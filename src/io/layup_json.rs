//! `layup.json`: the [`LayupTable`] of a run, written by `drape run` and read by `drape report`.
//! Keys in sorted order, two-space indents, a newline at the end.
use super::{write_atomic, ExportError};
use crate::layup::table::LayupTable;
use std::path::Path;

/// Name of the layup table in a run's folder.
pub const LAYUP_FILE: &str = "layup.json";

/// Why `layup.json` could not be read: the message says where.
#[derive(Debug, thiserror::Error)]
#[error("{message}")]
pub struct ReadLayupError {
    /// What went wrong, with the line and column for a parse error.
    pub message: String,
}

/// Write `table` to `path` atomically.
pub fn write(table: &LayupTable, path: &Path) -> Result<(), ExportError> {
    // Through a JSON value, whose maps keep their keys sorted.
    let value = serde_json::to_value(table).expect("a layup table is plain data");
    write_atomic(path, |w| {
        serde_json::to_writer_pretty(&mut *w, &value)?;
        std::io::Write::write_all(w, b"\n")
    })
}

/// Read `dir/layup.json` if it is there.
pub fn read(dir: &Path) -> Result<Option<LayupTable>, ReadLayupError> {
    let bytes = match std::fs::read(dir.join(LAYUP_FILE)) {
        Ok(b) => b,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(ReadLayupError { message: format!("cannot read it: {e}") }),
    };
    serde_json::from_slice(&bytes)
        .map(Some)
        .map_err(|e| ReadLayupError { message: format!("line {}, column {}: {e}", e.line(), e.column()) })
}
