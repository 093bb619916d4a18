//! Fabric material cards (TOML, SI units) and their constitutive laws; fitting laws to test data.
pub mod calibrate;
pub mod card;

pub use card::{Fibre, MaterialCard, MaterialError};
