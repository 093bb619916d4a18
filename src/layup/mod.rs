//! Layups: plies draped in stacking order, each on the tool offset by the plies below it
//! ([`stack`]); their flat patterns ([`flat`]) and the nesting of those on the roll ([`nest`]).
pub mod auto;
pub mod coarse;
pub mod curve;
pub mod flat;
pub mod nest;
pub mod ply;
pub mod stack;
pub mod table;

pub use ply::{
    locking_angle_deg, AutoModel, Layup, LockingSource, Orientation, Ply, PlyMaterial, Refinement, StackSide, Start,
    DEFAULT_LOCKING_ANGLE_DEG, DEFAULT_SOLVER_ITERATIONS, MAX_LOAD_STEPS, MAX_SOLVER_ITERATIONS,
};
