//! A material card: areal mass, thickness, and the tension, shear and bending laws.

/// One of the two fibre families.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Fibre {
    Warp,
    Weft,
}

/// Why a material card could not be read or used.
#[derive(Debug, thiserror::Error)]
pub enum MaterialError {
    #[error("{0}")]
    Invalid(String),
}

/// A fabric material card (SI units).
#[derive(Debug, Clone)]
pub struct MaterialCard {
    pub name: String,
    /// kg/m^2
    pub areal_mass: f64,
    /// m
    pub thickness: f64,
}

impl MaterialCard {
    /// Read and check a card file.
    pub fn load(path: &std::path::Path) -> Result<Self, MaterialError> {
        let _ = path;
        todo!("material helper")
    }
    /// Stretch energy per unit reference length and unit width of a fibre family at Green strain
    /// `e`: (W, dW/de, d2W/de2), in N/m (dW/de is the fibre tension per unit width).
    pub fn tension(&self, fibre: Fibre, e: f64) -> (f64, f64, f64) {
        let _ = (fibre, e);
        todo!("material helper")
    }
    /// In-plane shear energy per unit area at shear angle `g` (radians, signed):
    /// (W, M = dW/dg, dM/dg), W in J/m^2 and M the shear moment per unit area in N/m.
    pub fn shear(&self, g: f64) -> (f64, f64, f64) {
        let _ = g;
        todo!("material helper")
    }
    /// Flexural rigidity per unit width of a fibre family, N m.
    pub fn bending(&self, fibre: Fibre) -> f64 {
        let _ = fibre;
        todo!("material helper")
    }
}
