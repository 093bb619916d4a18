//! The mechanical stage: an energy model on the drape net's warp/weft grid (fibre tension, shear
//! with locking, bending, gravity) with tool contact, minimised by sequential convex subproblems
//! solved with Clarabel.
pub mod contact;
pub mod energy;
pub mod refine;
// The solver is being rewritten on another branch; its two lint findings (a spelled-out column
// type, an index loop over a sparse column) are left to that rewrite.
#[allow(clippy::type_complexity, clippy::needless_range_loop)]
pub mod solver;
pub mod sparse;
pub mod virtual_tests;

pub use contact::{ContactMode, ContactSurface, Foot, Freedom, NodeBasis};
pub use solver::{solve, Constraints, Evaluation, HessianBlocks, Objective, Outcome, SolveReport, SolverSettings};
