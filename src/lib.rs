//! `drape`: plans how composite plies lie on a part.
//!
//! A [`geometry::ToolSurface`] (a checked mesh with a BVH and its topology) is draped by the
//! kinematic fishnet mapper ([`kinematic::drape`]) into a [`kinematic::DrapeNet`], the one grid
//! type every later stage reads: [`mechanics`] refines it, [`layup`] drapes plies on plies and
//! flattens them, [`mapping`] puts them onto a resin-flow mesh, [`io`] reads and writes every
//! file, [`pipeline`] does what `drape run` does, [`report`] draws a run.
//!
//! The modules are layers, each using only those listed before it: [`numeric`], [`geometry`],
//! [`kinematic`], [`material`], [`mechanics`], [`layup`], [`mapping`], [`io`], [`pipeline`],
//! [`report`], then the command line (docs/ARCHITECTURE.md; tests/module_layers.rs keeps it so).
#![warn(missing_docs)]
// The command line, for src/main.rs: not part of the library's API.
#[doc(hidden)]
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
pub mod study;

pub use geometry::ToolSurface;
pub use kinematic::{drape, DrapeNet, KinematicSettings};
