//! What resin-flow simulations need of a fabric beyond its mechanics: how a sheared ply's
//! thickness and fibre volume fraction change (the cavity), the fibre packing limit and Gebart's
//! permeability (REFERENCES.md §5).
use crate::geometry::Vector;
use nalgebra::Matrix3;

/// What happens to a sheared ply's thickness (REFERENCES.md §5).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Cavity {
    /// Closed mould, cavity thickness fixed: t = t0, Vf = Vf0 / cos(gamma) (gamma at most
    /// [`COLLAPSED_SHEAR_DEG`], Vf at most [`VF_CAP`]).
    Fixed,
    /// Free thickness: t = t0 / cos(gamma) (gamma at most [`COLLAPSED_SHEAR_DEG`]), Vf = Vf0.
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
/// thickens to t0 / cos(shear), up to [`COLLAPSED_SHEAR_DEG`].
pub fn sheared_thickness(t0: f64, shear: f64) -> f64 {
    t0 / shear_cos(shear)
}

/// Shear (degrees) past which a cell of a drape has collapsed: it has lost three quarters of its
/// area (the kinematic stage refuses a node there by default, `DEFAULT_MAX_SHEAR_DEG`), and a
/// mechanical result sheared further has a folded or crushed cell, its fabric bunched into a
/// wrinkle rather than thickened in the plane. Thickness and Vf are not carried past it: at the
/// fold itself cos(shear) -> 0, and a formed hat box's 0.35 mm ply read 254 mm thick in the flow
/// export and raised the next ply's tool by 285 mm (every vertex moved, 9,842 facets folded).
/// Past it they stay at its values (t0 / cos 75 deg = 3.9 t0); the exports and the layup count
/// where ([`collapsed`]).
pub const COLLAPSED_SHEAR_DEG: f64 = 75.0;

/// Whether a cell sheared by `shear` (radians) has collapsed ([`COLLAPSED_SHEAR_DEG`]).
pub fn collapsed(shear: f64) -> bool {
    shear.abs() > COLLAPSED_SHEAR_DEG.to_radians()
}

/// cos(shear), with the shear taken at most [`COLLAPSED_SHEAR_DEG`] (NaN stays NaN).
fn shear_cos(shear: f64) -> f64 {
    let limit = COLLAPSED_SHEAR_DEG.to_radians();
    if shear.abs() > limit {
        limit.cos()
    } else {
        shear.cos()
    }
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_sheared_ply_thickens_as_its_cells_shrink_until_they_collapse() {
        let t0 = 3.5e-4;
        for deg in [0.0, 10.0, 45.0, 60.0, 74.9] {
            let g = f64::to_radians(deg);
            for shear in [g, -g] {
                let t = sheared_thickness(t0, shear);
                assert!((t - t0 / g.cos()).abs() <= 1e-15 * t, "{deg} deg: {t}");
                assert!(!collapsed(shear));
            }
        }
        // Past the collapse, and at the fold itself, the thickness stays that of 75 deg.
        let at_collapse = t0 / COLLAPSED_SHEAR_DEG.to_radians().cos();
        assert!((at_collapse / t0 - 3.8637).abs() < 1e-4);
        for deg in [75.1, 80.0, 89.92, 90.0] {
            let shear = f64::to_radians(deg);
            assert!(collapsed(shear) && collapsed(-shear), "{deg} deg");
            assert_eq!(sheared_thickness(t0, shear), at_collapse, "{deg} deg");
            assert_eq!(sheared_thickness(t0, -shear), at_collapse, "{deg} deg");
            assert_eq!(Cavity::Free.sheared(t0, 0.45, shear), (at_collapse, 0.45));
            assert_eq!(Cavity::Fixed.sheared(t0, 0.2, shear), (t0, 0.2 / COLLAPSED_SHEAR_DEG.to_radians().cos()));
        }
        assert!(sheared_thickness(t0, f64::NAN).is_nan());
    }
}
