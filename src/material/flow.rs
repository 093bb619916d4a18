//! What resin-flow simulations need of a fabric beyond its mechanics: how a sheared ply's
//! thickness and fibre volume fraction change (the cavity), the fibre packing limit and Gebart's
//! permeability (REFERENCES.md §5).
use crate::geometry::Vector;
use nalgebra::Matrix3;

/// What happens to a sheared ply's thickness (REFERENCES.md §5).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Cavity {
    /// Closed mould, cavity thickness fixed: t = t0, Vf = Vf0 / cos(gamma).
    Fixed,
    /// Free thickness: t = t0 / cos(gamma), Vf = Vf0.
    Free,
}

impl Cavity {
    /// Thickness and fibre volume fraction of a ply laid flat at `t0`, `vf0` and sheared by
    /// `shear` (radians); the volume fraction is capped at [`VF_CAP`].
    pub fn sheared(self, t0: f64, vf0: f64, shear: f64) -> (f64, f64) {
        match self {
            Cavity::Fixed => (t0, (vf0 / shear_cos(shear)).min(VF_CAP)),
            Cavity::Free => (sheared_thickness(t0, shear), vf0),
        }
    }
}

/// Thickness of a ply laid flat at `t0` and sheared by `shear` (radians) where nothing presses
/// it: a sheared cell keeps its fibre lengths, so its area shrinks by cos(shear) and the ply
/// thickens to t0 / cos(shear).
pub fn sheared_thickness(t0: f64, shear: f64) -> f64 {
    t0 / shear_cos(shear)
}

/// cos(shear), kept above zero so that a fully sheared cell gives a huge but finite value.
fn shear_cos(shear: f64) -> f64 {
    shear.cos().max(f64::MIN_POSITIVE)
}

/// Gebart's constant c for the axial permeability of a hexagonal fibre packing (Gebart 1992).
const GEBART_C_HEX: f64 = 57.0;
/// Largest fibre volume fraction of a hexagonal packing, pi / (2 sqrt 3): fibres touch.
pub const VF_MAX_HEX: f64 = 0.906_899_682_117_108_9;
/// Fibre volume fractions are capped just below the packing limit (the fabric would have locked
/// long before; the cap keeps the permeability model finite); the commands count the elements
/// that reach it.
pub const VF_CAP: f64 = VF_MAX_HEX - 1e-6;

/// Permeability model asked for with the mapping (REFERENCES.md §5): Gebart's (1992) axial and
/// transverse permeabilities of a hexagonal fibre packing, K_par = 8 r^2 / c (1 - Vf)^3 / Vf^2 and
/// K_perp = 16 / (9 pi sqrt 6) (sqrt(Vf_max / Vf) - 1)^(5/2) r^2, mixed over the ply's two fibre
/// directions: K = K_par A + K_perp (P - A) + K_perp n n^T with A = (w w^T + f f^T) / 2 and
/// P = I - n n^T. An unsheared balanced ply is isotropic in its plane; a sheared one has its
/// principal directions on the bisectors of warp and weft, the larger along the acute bisector.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PermeabilityModel {
    /// Fibre radius, metres (carbon about 3.5e-6, glass about 8e-6).
    pub fibre_radius: f64,
}

impl PermeabilityModel {
    /// Axial and transverse permeabilities (m^2) at fibre volume fraction `vf`.
    pub fn principal(&self, vf: f64) -> (f64, f64) {
        let r2 = self.fibre_radius * self.fibre_radius;
        let vf = vf.clamp(1e-6, VF_CAP);
        let k_par = 8.0 * r2 / GEBART_C_HEX * (1.0 - vf).powi(3) / (vf * vf);
        let c1 = 16.0 / (9.0 * std::f64::consts::PI * 6f64.sqrt());
        let k_perp = c1 * ((VF_MAX_HEX / vf).sqrt() - 1.0).powf(2.5) * r2;
        (k_par, k_perp)
    }

    /// The tensor of a ply with in-plane unit fibre directions `warp`, `weft` and normal `normal`.
    pub fn tensor(&self, vf: f64, warp: &Vector, weft: &Vector, normal: &Vector) -> Matrix3<f64> {
        let (k_par, k_perp) = self.principal(vf);
        let a = (warp * warp.transpose() + weft * weft.transpose()) * 0.5;
        let nn = normal * normal.transpose();
        let p = Matrix3::identity() - nn;
        a * k_par + (p - a) * k_perp + nn * k_perp
    }
}
