//! Closed-form kinematics and forces of the two standard in-plane shear tests: the picture
//! frame and the bias extension (REFERENCES.md §3, [002] eqs. 1-4). Used as test oracles.
//!
//! The shear law is a closure `m(γ)`: the shear moment per unit (initial) area, in N m / m² =
//! N/m, with `γ` in rad. Its integral `W(γ) = ∫_0^γ m` is the shear energy per unit area.
//! Forces are in N, displacements and lengths in m.
//!
//! # Picture frame (side `L`, crosshead displacement `d`)
//!
//! Four hinged bars of length `L` form a rhombus, pulled along a diagonal. Let `φ = π/2 − γ` be
//! the angle between the bars. The pulled diagonal is `2 L cos(φ/2)`, and it starts at `√2 L`.
//! So `cos(φ/2) = 1/√2 + d/(2L)`, i.e.
//!
//! ```text
//!     γ(d) = π/2 − 2 acos(1/√2 + d/(2L)),
//!     dγ/dd = 1 / (L sin(φ/2)) = √2 / (L (cos(γ/2) − sin(γ/2))),
//! ```
//!
//! using `sin(φ/2) = sin(π/4 − γ/2) = (cos(γ/2) − sin(γ/2)) / √2`. The whole `L × L` specimen
//! shears uniformly. Virtual work `F δd = L² m(γ) δγ` gives
//!
//! ```text
//!     F = L² m(γ) dγ/dd = √2 L m(γ) / (cos(γ/2) − sin(γ/2)),
//! ```
//!
//! which is the REFERENCES / [002] eq. 2 form `M = F (cos(γ/2) − sin(γ/2)) / (√2 L)` rearranged
//! (per unit area; multiply by the cell area `S_c` for the per-cell moment of [002]).
//!
//! # Bias extension (length `L`, width `W`, `L ≥ 2W`, fibres at ±45°, `D = L − W`)
//!
//! With inextensible fibres the specimen splits into zones. Zone C (centre) shears by `γ_C`,
//! zones B by `γ_C / 2`, and zones A (at the clamps) do not shear. The apexes of the two A
//! triangles lie on the axis, `D` apart, and are opposite corners of zone C: a rhombus of fibre
//! sides `D/√2` and fibre angle `φ = π/2 − γ_C`. Its axial diagonal is `√2 D cos(φ/2) = D + d`:
//!
//! ```text
//!     γ_C(d) = π/2 − 2 acos((D + d) / (√2 D)),
//!     dγ_C/dd = √2 / (D sin(φ/2)) = 2 / (D (cos(γ_C/2) − sin(γ_C/2))).
//! ```
//!
//! Zone areas (initial): `A_C = W (L − 3W/2)`, `A_B = W²` (all four B triangles),
//! `A_A = W²/2` (both A triangles); they sum to `L W`. The energy is
//! `E(d) = A_C W(γ_C) + A_B W(γ_C/2)`, and `F = dE/dd` gives
//!
//! ```text
//!     F = 2 / (D (cos(γ_C/2) − sin(γ_C/2))) · (A_C m(γ_C) + A_B m(γ_C/2) / 2).
//! ```
//!
//! Since `2 A_C = W (2D − W)` and `A_B / (2 A_C) = W / (2D − W)`, this is [002] eq. 4,
//! `M(γ) = F D (cos(γ/2) − sin(γ/2)) / (W (2D − W)) − W / (2D − W) · M(γ/2)`, rearranged.
//!
//! Both kinematic maps need `γ ∈ [0, π/2)` (the frame cannot close further); `dγ/dd` blows up
//! as `γ → π/2`.

use std::f64::consts::{FRAC_1_SQRT_2, FRAC_PI_2, FRAC_PI_4, SQRT_2};

/// Number of panels of the composite Gauss-Legendre rule in [`shear_energy_density`].
const ENERGY_PANELS: usize = 64;
/// Slack allowed on the acos argument before it is treated as out of range.
const ACOS_SLACK: f64 = 1e-12;

fn checked_acos(c: f64, what: &str) -> f64 {
    assert!(
        (-1.0 - ACOS_SLACK..=1.0 + ACOS_SLACK).contains(&c),
        "{what}: acos argument {c} out of range (displacement beyond full closure)"
    );
    c.clamp(-1.0, 1.0).acos()
}

/// `cos(γ/2) − sin(γ/2)` = `√2 sin(π/4 − γ/2)`, the factor shared by both tests.
pub fn half_angle_factor(gamma: f64) -> f64 {
    (0.5 * gamma).cos() - (0.5 * gamma).sin()
}

/// Shear energy per unit area `W(γ) = ∫_0^γ m(t) dt` (N/m · rad = J/m²), by composite 5-point
/// Gauss-Legendre quadrature (exact for polynomial laws up to degree 9).
pub fn shear_energy_density(gamma: f64, m: &dyn Fn(f64) -> f64) -> f64 {
    const X: [f64; 5] =
        [-0.906_179_845_938_664, -0.538_469_310_105_683, 0.0, 0.538_469_310_105_683, 0.906_179_845_938_664];
    const WT: [f64; 5] = [
        0.236_926_885_056_189_1,
        0.478_628_670_499_366_5,
        0.568_888_888_888_888_9,
        0.478_628_670_499_366_5,
        0.236_926_885_056_189_1,
    ];
    let h = gamma / ENERGY_PANELS as f64;
    let mut sum = 0.0;
    for p in 0..ENERGY_PANELS {
        let mid = (p as f64 + 0.5) * h;
        for (x, wt) in X.iter().zip(WT.iter()) {
            sum += wt * m(mid + 0.5 * h * x);
        }
    }
    0.5 * h * sum
}

// ------------------------------------------------------------------------------------------
// Picture frame
// ------------------------------------------------------------------------------------------

/// Picture-frame shear angle (rad) at crosshead displacement `d` for frame side `side`.
pub fn pf_shear(d: f64, side: f64) -> f64 {
    FRAC_PI_2 - 2.0 * checked_acos(FRAC_1_SQRT_2 + d / (2.0 * side), "pf_shear")
}

/// `dγ/dd` (rad/m) of the picture frame, analytic: `1 / (L sin(φ/2))`, `φ = π/2 − γ`.
pub fn pf_shear_rate(d: f64, side: f64) -> f64 {
    let c = FRAC_1_SQRT_2 + d / (2.0 * side);
    1.0 / (side * (1.0 - c * c).sqrt())
}

/// Inverse of [`pf_shear`]: the displacement at which the frame reaches shear `gamma`.
pub fn pf_displacement(gamma: f64, side: f64) -> f64 {
    2.0 * side * ((FRAC_PI_4 - 0.5 * gamma).cos() - FRAC_1_SQRT_2)
}

/// Picture-frame crosshead force (N), by virtual work: `F = L² m(γ) dγ/dd`.
pub fn pf_force(d: f64, side: f64, m: &dyn Fn(f64) -> f64) -> f64 {
    side * side * m(pf_shear(d, side)) * pf_shear_rate(d, side)
}

/// Total shear energy (J) of the picture-frame specimen: `L² W(γ)`.
pub fn pf_energy(d: f64, side: f64, m: &dyn Fn(f64) -> f64) -> f64 {
    side * side * shear_energy_density(pf_shear(d, side), m)
}

/// REFERENCES / [002] eq. 2 identification: shear moment per unit area from the measured force,
/// `M = F (cos(γ/2) − sin(γ/2)) / (√2 L)`.
pub fn pf_moment_from_force(force: f64, d: f64, side: f64) -> f64 {
    force * half_angle_factor(pf_shear(d, side)) / (SQRT_2 * side)
}

// ------------------------------------------------------------------------------------------
// Bias extension
// ------------------------------------------------------------------------------------------

fn be_d(length: f64, width: f64) -> f64 {
    assert!(length >= 2.0 * width && width > 0.0, "bias extension needs L >= 2W > 0 (L = {length}, W = {width})");
    length - width
}

/// Bias-extension shear angle (rad) of the central zone C at elongation `d`.
pub fn be_shear(d: f64, length: f64, width: f64) -> f64 {
    let dd = be_d(length, width);
    FRAC_PI_2 - 2.0 * checked_acos(FRAC_1_SQRT_2 * (1.0 + d / dd), "be_shear")
}

/// Shear angles of the zones `(A, B, C)` = `(0, γ_C/2, γ_C)`.
pub fn be_zone_shears(d: f64, length: f64, width: f64) -> (f64, f64, f64) {
    let gc = be_shear(d, length, width);
    (0.0, 0.5 * gc, gc)
}

/// Initial zone areas `(A_A, A_B, A_C)` = `(W²/2, W², W (L − 3W/2))` (m²), summing to `L W`.
pub fn be_zone_areas(length: f64, width: f64) -> (f64, f64, f64) {
    let _ = be_d(length, width);
    (0.5 * width * width, width * width, width * (length - 1.5 * width))
}

/// `dγ_C/dd` (rad/m), analytic: `2 / (D (cos(γ_C/2) − sin(γ_C/2)))`.
pub fn be_shear_rate(d: f64, length: f64, width: f64) -> f64 {
    let dd = be_d(length, width);
    2.0 / (dd * half_angle_factor(be_shear(d, length, width)))
}

/// Inverse of [`be_shear`]: the elongation at which zone C reaches shear `gamma`,
/// `d = D (√2 cos(π/4 − γ/2) − 1)`.
pub fn be_displacement(gamma: f64, length: f64, width: f64) -> f64 {
    let dd = be_d(length, width);
    dd * (SQRT_2 * (FRAC_PI_4 - 0.5 * gamma).cos() - 1.0)
}

/// Bias-extension force (N), REFERENCES §3 virtual-work form:
/// `F = 2 / (D (cos(γ_C/2) − sin(γ_C/2))) (A_C m(γ_C) + A_B m(γ_C/2) / 2)`.
pub fn be_force(d: f64, length: f64, width: f64, m: &dyn Fn(f64) -> f64) -> f64 {
    let dd = be_d(length, width);
    let gc = be_shear(d, length, width);
    let (_, a_b, a_c) = be_zone_areas(length, width);
    2.0 / (dd * half_angle_factor(gc)) * (a_c * m(gc) + 0.5 * a_b * m(0.5 * gc))
}

/// Total shear energy (J) of the bias-extension specimen: `A_C W(γ_C) + A_B W(γ_C/2)`.
pub fn be_energy(d: f64, length: f64, width: f64, m: &dyn Fn(f64) -> f64) -> f64 {
    let gc = be_shear(d, length, width);
    let (_, a_b, a_c) = be_zone_areas(length, width);
    a_c * shear_energy_density(gc, m) + a_b * shear_energy_density(0.5 * gc, m)
}

/// [002] eq. 4 identification (per unit area, `ℓ = W`): the moment at `γ_C` from the force and
/// the already-known moment at `γ_C / 2`,
/// `M(γ) = F D (cos(γ/2) − sin(γ/2)) / (W (2D − W)) − W / (2D − W) · M(γ/2)`.
pub fn be_moment_from_force(force: f64, d: f64, length: f64, width: f64, m_half: f64) -> f64 {
    let dd = be_d(length, width);
    let gc = be_shear(d, length, width);
    force * dd * half_angle_factor(gc) / (width * (2.0 * dd - width)) - width / (2.0 * dd - width) * m_half
}
