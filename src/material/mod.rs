//! Fabric material cards (TOML, SI units) and their constitutive laws; fitting laws to test data.
//!
//! [`MaterialCard`] reads a card (schema in [`card`]) and evaluates its laws with exact
//! derivatives: `tension(fibre, e)`, `shear(g)`, `bending(fibre)`. [`calibrate`] fits the shear
//! law to picture-frame or bias-extension data and the knit tension law to uniaxial data.
//! Bundled cards live in `materials/` at the crate root.
pub mod calibrate;
pub mod card;
pub mod card_toml;
pub mod flow;
pub mod laws;
pub mod test_kinematics;

pub use card::{FlowProperties, MaterialCard, MaterialError};
pub use laws::{Bending, Fibre, KnitParams, ShearLaw, ShearTable, Tension, TensionLaw};
