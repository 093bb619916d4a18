//! The mechanical stage: an energy model on the drape net's warp/weft grid (fibre tension, shear
//! with locking, bending, gravity) with tool contact, minimised by sequential convex subproblems
//! solved with Clarabel.
pub mod contact;
pub mod energy;
pub mod forming;
pub mod friction;
pub mod qp;
pub mod refine;
pub mod sheet;
pub mod solver;
pub mod sparse;
pub mod stability;
pub mod virtual_tests;

pub use contact::{ContactMode, ContactSurface, Foot, Freedom, NodeBasis};
pub use qp::HessianBlocks;
pub use solver::{solve, Constraints, Evaluation, Objective, Outcome, SolveReport, SolverSettings, UnbalancedNode};
pub use stability::{Escape, Stability, StabilityCheck};
