//! Shared helpers for the integration tests.
#![allow(dead_code)]

pub mod chebyshev;
pub mod elastica;
pub mod shear_frames;
pub mod vtk_reader;
