//! Kinematics of the in-plane shear tests (REFERENCES.md section 3, seed 002 eqs. 1-4; fibres
//! inextensible): how far the fabric shears for a crosshead displacement d. The calibration fits
//! ([`super::calibrate`]) turn measured forces into shear moments with them; the virtual tests
//! (`mechanics::virtual_tests`) move their rigs by them.
use std::f64::consts::{FRAC_1_SQRT_2, FRAC_PI_2, SQRT_2};

/// A picture frame: four rigid arms of length `side`, pin-jointed at the corners, one corner
/// fixed and the opposite one pulled along the diagonal.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PictureFrameKinematics {
    /// Frame side L, hinge to hinge, m.
    pub side: f64,
}

impl PictureFrameKinematics {
    /// cos and sin of half the angle phi between the arms at displacement `d`:
    /// cos(phi/2) = 1/sqrt 2 + d / (2 L).
    pub fn half_angle(&self, d: f64) -> (f64, f64) {
        let c = FRAC_1_SQRT_2 + d / (2.0 * self.side);
        (c, (1.0 - c * c).max(0.0).sqrt())
    }

    /// The displacement at which the frame closes (90 deg shear): (2 - sqrt 2) L.
    pub fn travel(&self) -> f64 {
        (2.0 - SQRT_2) * self.side
    }

    /// Shear angle gamma = pi/2 - phi and its rate d gamma / d d = 1 / (L sin(phi/2)) at `d`, or
    /// `None` past the frame's travel (-sqrt 2 L < d < (2 - sqrt 2) L).
    pub fn shear(&self, d: f64) -> Option<(f64, f64)> {
        let (c, s) = self.half_angle(d);
        (c > 0.0 && c < 1.0).then(|| (FRAC_PI_2 - 2.0 * c.acos(), 1.0 / (self.side * s)))
    }
}

/// A bias-extension specimen: free length `length` between the clamps (>= 2 `width`), fibres at
/// +-45 deg to the load. Its central zone shears by gamma, the zones beside the clamps by half.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BiasExtensionKinematics {
    /// Free length L between the clamps, m.
    pub length: f64,
    /// Width W, m.
    pub width: f64,
}

impl BiasExtensionKinematics {
    /// D = L - W, the length of the central zone's diagonal along the load.
    pub fn zone_length(&self) -> f64 {
        self.length - self.width
    }

    /// cos and sin of half the fibre angle in the central zone at elongation `d`:
    /// cos(phi/2) = (D + d) / (sqrt 2 D).
    pub fn half_angle(&self, d: f64) -> (f64, f64) {
        let dd = self.zone_length();
        let c = (dd + d) / (SQRT_2 * dd);
        (c, (1.0 - c * c).max(0.0).sqrt())
    }

    /// The elongation at which the central zone reaches 90 deg shear: (sqrt 2 - 1) D.
    pub fn travel(&self) -> f64 {
        (SQRT_2 - 1.0) * self.zone_length()
    }

    /// Shear angle of the central zone and its rate d gamma / d d = sqrt 2 / (D sin(phi/2)) at
    /// `d`, or `None` past 90 deg.
    pub fn shear(&self, d: f64) -> Option<(f64, f64)> {
        let (c, s) = self.half_angle(d);
        (c > 0.0 && c < 1.0).then(|| (FRAC_PI_2 - 2.0 * c.acos(), SQRT_2 / (self.zone_length() * s)))
    }
}

/// The rig a shear test was run in, with its kinematics and the energy normalisation of its
/// force (REFERENCES.md section 9; Harrison et al. 2004, Cao et al. 2008 eq. 18).
///
/// The normalised shear force Fsh(g) is the shear force per unit length of fibre of the
/// sheared fabric, Fsh = M / cos g with M the law's shear moment per unit area: the same
/// function of the angle for every size of sample of one fabric, so tests of different sizes
/// (and both rigs) fall on one curve.
/// - Picture frame, side L: Fsh = F / (2 L cos(phi/2)) (the force along the arms per unit of
///   their length); with F = L^2 M dg/dd this is M / cos g exactly.
/// - Bias extension, length H, width W: Fsh(g) = (H/W - 1) F (cos(g/2) - sin(g/2)) /
///   ((2H - 3W) cos g) - W cos(g/2) Fsh(g/2) / ((2H - 3W) cos g), the central zone's share of
///   the power once the zones B (at g/2) have taken theirs: a recursion from small angles.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ShearRig {
    /// A picture frame.
    PictureFrame(PictureFrameKinematics),
    /// A bias-extension specimen.
    BiasExtension(BiasExtensionKinematics),
}

/// How a rig's force at one displacement turns into normalised shear force:
/// Fsh(gamma) = `force_factor` F - `half_factor` Fsh(gamma / 2).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Normalisation {
    /// Shear angle of the (central) sheared zone, rad.
    pub gamma: f64,
    /// N/m per N.
    pub force_factor: f64,
    /// The weight of the zones sheared by half as much (0 for a picture frame).
    pub half_factor: f64,
}

impl ShearRig {
    /// The rig's name in words: `picture frame` or `bias extension`.
    pub fn name(&self) -> &'static str {
        match self {
            ShearRig::PictureFrame(_) => "picture frame",
            ShearRig::BiasExtension(_) => "bias extension",
        }
    }

    /// The displacement at which the rig reaches 90 deg (its travel).
    pub fn travel(&self) -> f64 {
        match self {
            ShearRig::PictureFrame(k) => k.travel(),
            ShearRig::BiasExtension(k) => k.travel(),
        }
    }

    /// Shear of the (central) zone and its rate d gamma / d d at `d`, or `None` past 90 deg.
    pub fn shear(&self, d: f64) -> Option<(f64, f64)> {
        match self {
            ShearRig::PictureFrame(k) => k.shear(d),
            ShearRig::BiasExtension(k) => k.shear(d),
        }
    }

    /// The displacement at which the (central) zone reaches `gamma` (rad, 0 <= gamma < pi/2).
    pub fn displacement_at(&self, gamma: f64) -> f64 {
        let c = (FRAC_PI_2 - gamma) * 0.5; // half the fibre angle phi
        match self {
            ShearRig::PictureFrame(k) => 2.0 * k.side * (c.cos() - FRAC_1_SQRT_2),
            ShearRig::BiasExtension(k) => (SQRT_2 * c.cos() - 1.0) * k.zone_length(),
        }
    }

    /// The force as a combination of shear moments, F = sum weight * M(angle), at `d` (by
    /// virtual work: F dd = the shear power of every zone), or `None` past 90 deg.
    /// - Picture frame: the whole L x L sample at gamma: F = L^2 M(gamma) dgamma/dd.
    /// - Bias extension: the central zone C of area A_C = W (H - 3W/2) at gamma and the zones B
    ///   of total area A_B = W^2 at gamma / 2 (REFERENCES.md section 3):
    ///   F = A_C M(gamma) dgamma/dd + A_B M(gamma/2) dgamma/dd / 2.
    pub fn force_terms(&self, d: f64) -> Option<[(f64, f64); 2]> {
        let (g, rate) = self.shear(d)?;
        Some(match self {
            ShearRig::PictureFrame(k) => [(g, rate * k.side * k.side), (0.0, 0.0)],
            ShearRig::BiasExtension(k) => {
                let (h, w) = (k.length, k.width);
                [(g, rate * w * (h - 1.5 * w)), (0.5 * g, rate * w * w * 0.5)]
            }
        })
    }

    /// The energy normalisation at `d`, or `None` past 90 deg.
    pub fn normalisation(&self, d: f64) -> Option<Normalisation> {
        let (g, _) = self.shear(d)?;
        Some(match self {
            ShearRig::PictureFrame(k) => {
                let (c, _) = k.half_angle(d);
                Normalisation { gamma: g, force_factor: 1.0 / (2.0 * k.side * c), half_factor: 0.0 }
            }
            ShearRig::BiasExtension(k) => {
                let (h, w) = (k.length, k.width);
                let den = (2.0 * h - 3.0 * w) * g.cos();
                Normalisation {
                    gamma: g,
                    force_factor: (h / w - 1.0) * ((0.5 * g).cos() - (0.5 * g).sin()) / den,
                    half_factor: w * (0.5 * g).cos() / den,
                }
            }
        })
    }

    /// The normalised shear force of measured (displacement, force) points, in their order:
    /// (gamma rad, Fsh N/m) for each point at a positive angle before the rig's travel, `None`
    /// for the others. The bias extension's recursion runs in order of angle and takes
    /// Fsh(gamma / 2) from the points already normalised, interpolated linearly between them and
    /// through (0, 0) below the first; the first point itself takes Fsh(gamma/2) = Fsh(gamma)/2
    /// (the curve is straight at small angles).
    pub fn normalise(&self, data: &[(f64, f64)]) -> Vec<Option<(f64, f64)>> {
        let norms: Vec<Option<Normalisation>> =
            data.iter().map(|&(d, _)| self.normalisation(d).filter(|n| n.gamma > 0.0)).collect();
        let mut order: Vec<usize> = (0..data.len()).filter(|&i| norms[i].is_some()).collect();
        order.sort_by(|&a, &b| data[a].0.total_cmp(&data[b].0));
        let mut curve: Vec<(f64, f64)> = Vec::with_capacity(order.len());
        let mut out = vec![None; data.len()];
        for i in order {
            let (Some(n), f) = (norms[i], data[i].1) else { continue };
            let fsh = if curve.is_empty() {
                // Fsh(g/2) = Fsh(g)/2: Fsh (1 + h/2) = k F.
                n.force_factor * f / (1.0 + 0.5 * n.half_factor)
            } else {
                n.force_factor * f - n.half_factor * interpolate(&curve, 0.5 * n.gamma)
            };
            curve.push((n.gamma, fsh));
            out[i] = Some((n.gamma, fsh));
        }
        out
    }
}

/// Linear interpolation in increasing (x, y) points at `x` (>= 0), through (0, 0) before the
/// first point and held flat after the last.
fn interpolate(pts: &[(f64, f64)], x: f64) -> f64 {
    let k = pts.partition_point(|p| p.0 <= x);
    let (x0, y0) = if k == 0 { (0.0, 0.0) } else { pts[k - 1] };
    match pts.get(k) {
        Some(&(x1, y1)) if x1 > x0 => y0 + (y1 - y0) * (x - x0) / (x1 - x0),
        _ => y0,
    }
}
