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
