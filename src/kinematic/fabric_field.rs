//! A net's cell shear as a field over fabric coordinates: the fibre arc lengths (u along the warp,
//! v along the weft) from the origin node. Nets of one ply drawn at different spacings, by
//! different methods, agree on what fabric point (u, v) is, so this is where they are compared.
use super::DrapeNet;

/// Cell shear of a net (degrees) over fabric coordinates.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ShearField {
    /// Fibre segment length d, m.
    pub spacing: f64,
    /// Cells along the warp.
    pub cu: usize,
    /// Cells along the weft.
    pub cv: usize,
    /// The origin node's grid indices.
    pub origin_node: (usize, usize),
    /// Shear of cell (i, j) at index `i * cv + j`, degrees; `None` where the cell is incomplete.
    pub shear_deg: Vec<Option<f64>>,
}

/// A map of fabric coordinates onto themselves that a mirror-symmetric drape problem respects:
/// the mirror image of a drape, its fibre families kept, is the same ply's drape seen through
/// this map ([`ShearField::image`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum FabricImage {
    /// The identity.
    AsIs,
    /// The mirror in the plane of the warp and the normal at the seed: (u, v) -> (u, -v).
    WarpMirror,
    /// The mirror in the plane of the weft and the normal at the seed: (u, v) -> (-u, v).
    WeftMirror,
    /// Both mirrors, a half turn about the normal at the seed: (u, v) -> (-u, -v).
    Rotated,
}

impl FabricImage {
    /// The two mirrors.
    pub const MIRRORS: [FabricImage; 2] = [FabricImage::WarpMirror, FabricImage::WeftMirror];

    /// Its name in files and tables: `as-is`, `warp-mirror`, `weft-mirror` or `rotated`.
    pub fn name(self) -> &'static str {
        match self {
            FabricImage::AsIs => "as-is",
            FabricImage::WarpMirror => "warp-mirror",
            FabricImage::WeftMirror => "weft-mirror",
            FabricImage::Rotated => "rotated",
        }
    }

    /// Whether the map reverses u, whether it reverses v.
    fn flips(self) -> (bool, bool) {
        match self {
            FabricImage::AsIs => (false, false),
            FabricImage::WarpMirror => (false, true),
            FabricImage::WeftMirror => (true, false),
            FabricImage::Rotated => (true, true),
        }
    }

    /// The group a set of mirrors generates, the identity left out: each mirror, and the half
    /// turn when both hold.
    pub fn group_of(mirrors: &[FabricImage]) -> Vec<FabricImage> {
        let mut g: Vec<FabricImage> = FabricImage::MIRRORS.into_iter().filter(|m| mirrors.contains(m)).collect();
        if g.len() == 2 {
            g.push(FabricImage::Rotated);
        }
        g
    }
}

/// Bilinear weights below this are rounding: the point sits on a cell centre or the line
/// between two.
const ZERO_WEIGHT: f64 = 1e-9;

impl ShearField {
    /// The cell shear field of `net`.
    pub fn of(net: &DrapeNet) -> ShearField {
        let (cu, cv) = (net.nu.saturating_sub(1), net.nv.saturating_sub(1));
        let mut shear_deg = Vec::with_capacity(cu * cv);
        for i in 0..cu {
            for j in 0..cv {
                shear_deg.push(net.cell_shear(i, j).map(f64::to_degrees));
            }
        }
        ShearField { spacing: net.spacing, cu, cv, origin_node: net.origin_node, shear_deg }
    }

    fn cell(&self, i: isize, j: isize) -> Option<f64> {
        if i < 0 || j < 0 || i as usize >= self.cu || j as usize >= self.cv {
            return None;
        }
        self.shear_deg[i as usize * self.cv + j as usize]
    }

    /// Shear at fabric coordinates (u, v), metres, degrees: bilinear between the four cell
    /// centres around the point (second order, as the cell values are). `None` where a centre
    /// it needs is missing: beyond the outermost cell centres the net has no second-order value,
    /// and a constant one would be a first-order error.
    pub fn at(&self, u: f64, v: f64) -> Option<f64> {
        // Cell-centre coordinates: the centre of cell i sits at i.
        let xc = u / self.spacing + self.origin_node.0 as f64 - 0.5;
        let yc = v / self.spacing + self.origin_node.1 as f64 - 0.5;
        if !xc.is_finite() || !yc.is_finite() {
            return None;
        }
        let (i, j) = (xc.floor() as isize, yc.floor() as isize);
        let (fx, fy) = (xc - i as f64, yc - j as f64);
        let mut sum = 0.0;
        for (di, wx) in [(0, 1.0 - fx), (1, fx)] {
            for (dj, wy) in [(0, 1.0 - fy), (1, fy)] {
                let w = wx * wy;
                // A centre the point sits on (to rounding) needs no neighbours.
                if w > ZERO_WEIGHT {
                    sum += w * self.cell(i + di, j + dj)?;
                }
            }
        }
        Some(sum)
    }

    /// Fabric coordinates of the centre of cell (i, j), metres.
    pub fn cell_centre(&self, i: usize, j: usize) -> (f64, f64) {
        (
            (i as f64 + 0.5 - self.origin_node.0 as f64) * self.spacing,
            (j as f64 + 0.5 - self.origin_node.1 as f64) * self.spacing,
        )
    }

    /// The field of the drape's mirror image under `image` (fibre families kept):
    /// `s'(u, v) = -s(u, -v)` for the warp mirror, `-s(-u, v)` for the weft mirror and
    /// `s(-u, -v)` for the half turn. A mirror reverses one fibre family's direction against the
    /// other's, so the angle between them becomes its supplement and the shear changes sign.
    /// Exact: the cells are relabelled, nothing is interpolated.
    pub fn image(&self, image: FabricImage) -> ShearField {
        let (fu, fv) = image.flips();
        let sign = if fu != fv { -1.0 } else { 1.0 };
        let (cu, cv) = (self.cu, self.cv);
        let mut shear_deg = vec![None; cu * cv];
        for i in 0..cu {
            for j in 0..cv {
                let (a, b) = (if fu { cu - 1 - i } else { i }, if fv { cv - 1 - j } else { j });
                shear_deg[a * cv + b] = self.shear_deg[i * cv + j].map(|s| sign * s);
            }
        }
        // Node n goes to node (cells - n): the origin node with it.
        let (o0, o1) = self.origin_node;
        let origin_node = (if fu { cu - o0 } else { o0 }, if fv { cv - o1 } else { o1 });
        ShearField { spacing: self.spacing, cu, cv, origin_node, shear_deg }
    }

    /// The fabric coordinates of every complete cell's centre.
    pub fn complete_cell_centres(&self) -> Vec<(f64, f64)> {
        let mut out = Vec::new();
        for i in 0..self.cu {
            for j in 0..self.cv {
                if self.shear_deg[i * self.cv + j].is_some() {
                    out.push(self.cell_centre(i, j));
                }
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn field(values: impl Fn(usize, usize) -> Option<f64>) -> ShearField {
        let (cu, cv) = (4, 3);
        let shear_deg = (0..cu).flat_map(|i| (0..cv).map(move |j| (i, j))).map(|(i, j)| values(i, j)).collect();
        ShearField { spacing: 0.5, cu, cv, origin_node: (2, 1), shear_deg }
    }

    #[test]
    fn linear_fields_are_reproduced_between_cell_centres() {
        // s = 3 u + 2 v over fabric coordinates, sampled at the cell centres.
        let f = field(|i, j| Some(3.0 * (i as f64 - 1.5) * 0.5 + 2.0 * (j as f64 - 0.5) * 0.5));
        for (u, v) in [(0.0, 0.0), (0.1, -0.2), (-0.6, 0.3)] {
            let s = f.at(u, v).unwrap();
            assert!((s - (3.0 * u + 2.0 * v)).abs() < 1e-12, "at ({u},{v}): {s}");
        }
    }

    #[test]
    fn images_map_fabric_points_and_change_the_sign_under_one_mirror() {
        let f = field(|i, j| if (i, j) == (0, 2) { None } else { Some((i * 10 + j) as f64 + 1.0) });
        for (u, v) in f.complete_cell_centres() {
            let s = f.at(u, v).unwrap();
            assert_eq!(f.image(FabricImage::AsIs).at(u, v), Some(s));
            assert_eq!(f.image(FabricImage::WarpMirror).at(u, -v), Some(-s));
            assert_eq!(f.image(FabricImage::WeftMirror).at(-u, v), Some(-s));
            assert_eq!(f.image(FabricImage::Rotated).at(-u, -v), Some(s));
        }
        // The missing cell goes with its point.
        let (u, v) = f.cell_centre(0, 2);
        assert_eq!(f.image(FabricImage::Rotated).at(-u, -v), None);
        // Each image undoes itself.
        for m in [FabricImage::WarpMirror, FabricImage::WeftMirror, FabricImage::Rotated] {
            assert_eq!(f.image(m).image(m), f);
        }
    }

    #[test]
    fn points_needing_a_missing_centre_have_no_value_and_centres_need_no_neighbours() {
        let f = field(|i, j| if (i, j) == (3, 2) { None } else { Some((i * 10 + j) as f64) });
        // (u, v) between the centres of cells (2, 1) and (3, 2), which is missing.
        assert_eq!(f.at(0.45, 0.45), None);
        // The centre of the last cell (3, 1) and of cell (2, 2), next to the missing one.
        assert_eq!(f.at(0.75, 0.25), Some(31.0));
        assert_eq!(f.at(0.25, 0.75), Some(22.0));
        assert_eq!(f.at(5.0, 0.0), None);
        assert_eq!(f.at(f64::NAN, 0.0), None);
    }
}
