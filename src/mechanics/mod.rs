//! The mechanical stage: an energy model on the drape net's warp/weft grid (fibre tension, shear
//! with locking, bending, gravity) with tool contact, minimised by sequential convex subproblems
//! solved with Clarabel.
pub mod energy;
