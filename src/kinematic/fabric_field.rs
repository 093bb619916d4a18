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

/// Along one axis of `n` cell centres, the first centre and the weights of the point at centre
/// coordinate `x`: the centre itself where the point is on one (to rounding), else the cubic
/// through four consecutive centres, the ones around the point where the axis has them.
/// `None` beyond half a cell past the outermost centres, or with fewer than four.
fn cubic_stencil(x: f64, n: usize) -> Option<(isize, Vec<f64>)> {
    if !(x >= -0.5 - ZERO_WEIGHT && x <= n as f64 - 0.5 + ZERO_WEIGHT) {
        return None;
    }
    let k = x.round();
    if (x - k).abs() <= ZERO_WEIGHT && k >= 0.0 && (k as usize) < n {
        return Some((k as isize, vec![1.0]));
    }
    if n < 4 {
        return None;
    }
    let i0 = (x.floor() as isize - 1).clamp(0, n as isize - 4);
    let t = x - i0 as f64;
    // Lagrange weights of the centres at 0, 1, 2, 3.
    let w = vec![
        -(t - 1.0) * (t - 2.0) * (t - 3.0) / 6.0,
        t * (t - 2.0) * (t - 3.0) / 2.0,
        -t * (t - 1.0) * (t - 3.0) / 2.0,
        t * (t - 1.0) * (t - 2.0) / 6.0,
    ];
    Some((i0, w))
}

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
        let (xc, yc) = self.centre_coordinates(u, v)?;
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

    /// Shear at fabric coordinates (u, v), metres, degrees, read off a smooth field: the cubic
    /// through the 4 x 4 cell centres around the point (fourth order: between its centres a
    /// reference keeps the accuracy it has at them, where [`ShearField::at`]'s bilinear value
    /// would add an error of the order of a fine net's own), the stencil shifted inward at the
    /// edges; up to half a cell beyond the outermost centres (the cells' own area). A point on a
    /// centre (to rounding) takes that centre's value. Where the stencil lacks a cell, the
    /// bilinear value; `None` where that has none either.
    pub fn interpolate(&self, u: f64, v: f64) -> Option<f64> {
        let (xc, yc) = self.centre_coordinates(u, v)?;
        let cubic = || {
            let (i0, wx) = cubic_stencil(xc, self.cu)?;
            let (j0, wy) = cubic_stencil(yc, self.cv)?;
            let mut sum = 0.0;
            for (a, wa) in wx.iter().enumerate() {
                for (b, wb) in wy.iter().enumerate() {
                    sum += wa * wb * self.cell(i0 + a as isize, j0 + b as isize)?;
                }
            }
            Some(sum)
        };
        cubic().or_else(|| self.at(u, v))
    }

    /// Cell-centre coordinates of fabric point (u, v): the centre of cell i sits at i.
    fn centre_coordinates(&self, u: f64, v: f64) -> Option<(f64, f64)> {
        let xc = u / self.spacing + self.origin_node.0 as f64 - 0.5;
        let yc = v / self.spacing + self.origin_node.1 as f64 - 0.5;
        (xc.is_finite() && yc.is_finite()).then_some((xc, yc))
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
    fn cubic_fields_are_reproduced_up_to_the_cells_edges() {
        // s = u^3 - 2 u v^2 + v over fabric coordinates on a 6 x 5 grid of 0.5 m cells.
        let exact = |u: f64, v: f64| u * u * u - 2.0 * u * v * v + v;
        let (cu, cv) = (6, 5);
        let mut f = ShearField { spacing: 0.5, cu, cv, origin_node: (3, 2), shear_deg: vec![None; cu * cv] };
        for i in 0..cu {
            for j in 0..cv {
                let (u, v) = f.cell_centre(i, j);
                f.shear_deg[i * cv + j] = Some(exact(u, v));
            }
        }
        // Inside, near the edges (stencil shifted) and half a cell beyond the outer centres.
        for (u, v) in [(0.1, -0.2), (-1.3, 0.9), (1.45, -0.95), (-1.5, 1.25), (1.5, -1.0)] {
            let s = f.interpolate(u, v).unwrap();
            assert!((s - exact(u, v)).abs() < 1e-12, "at ({u},{v}): {s} against {}", exact(u, v));
        }
        assert_eq!(f.interpolate(1.6, 0.0), None, "beyond the cells");
        // A missing cell in the stencil: the bilinear value where it has one.
        f.shear_deg[2 * cv + 2] = None;
        assert!(f.at(0.45, 0.4).is_some());
        assert_eq!(f.interpolate(0.45, 0.4), f.at(0.45, 0.4));
        // On a centre: that centre's value, whatever is missing around it.
        let (u, v) = f.cell_centre(2, 3);
        assert_eq!(f.interpolate(u, v), f.shear_deg[2 * cv + 3]);
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
