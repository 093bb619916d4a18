//! Fishnet cell completion, quadrant by quadrant, one anti-diagonal wavefront at a time.
use super::{DrapeNet, KinematicSettings};
use crate::geometry::ToolSurface;

/// Why a drape could not start (bad settings or seed); per-node failures are recorded in the net.
#[derive(Debug, thiserror::Error)]
pub enum DrapeError {
    #[error("{0}")]
    Settings(String),
}

/// Drape one ply on the tool.
pub fn drape(tool: &ToolSurface, settings: &KinematicSettings) -> Result<DrapeNet, DrapeError> {
    let _ = (tool, settings);
    todo!()
}
