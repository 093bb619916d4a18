//! `drape`: plans how composite plies lie on a part.
//!
//! The pipeline: a [`geometry::ToolSurface`] (checked OBJ mesh + BVH + topology) is draped by the
//! kinematic fishnet mapper ([`kinematic::drape`]) into a [`kinematic::DrapeNet`], the one grid
//! type that every later stage reads; [`export`] writes it out.
pub mod cli;
pub mod geometry;
pub mod io;
pub mod kinematic;
pub mod layup;
pub mod mapping;
pub mod material;
pub mod mechanics;
pub mod numeric;
pub mod pipeline;
pub mod report;

pub use geometry::ToolSurface;
pub use kinematic::{drape, DrapeNet, KinematicSettings};
