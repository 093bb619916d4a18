//! [`DrapeNet`]: the warp/weft grid of nodes that travels through the whole pipeline.
use super::provenance::Provenance;
use crate::geometry::{Point, Vector};
use serde::{Deserialize, Serialize};

/// How a net was computed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Method {
    /// By the kinematic (fishnet) drape.
    Kinematic,
    /// Refined by the mechanical stage.
    Mechanical,
}

/// What happened to one node of the net.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, PartialOrd, Ord)]
#[serde(rename_all = "snake_case")]
#[repr(u8)]
pub enum NodeStatus {
    /// Placed on the tool.
    Placed = 0,
    /// Not computed yet (never left in a finished net).
    Pending = 1,
    /// A generator ran off the tool (open boundary, non-manifold edge or boundary vertex).
    OffTool = 2,
    /// The circle of points at distance d from both parents misses the tool.
    NoRoot = 3,
    /// The cell would shear past the limit (or its parents are farther apart than 2 d).
    ShearLimit = 4,
    /// The only root folds the fabric back over itself (cell turned over).
    Fold = 5,
    /// The only root lies on another sheet of the tool (e.g. the far side of a thin wall).
    SheetJump = 6,
    /// A node it depends on was not placed.
    ParentMissing = 7,
    /// Outside the ply outline: dropped.
    OutsideOutline = 8,
    /// Placed by the kinematic drape, but joined to the body of the net by no more than a
    /// corner (a mechanism: it could swing about that corner at no cost): left out of the
    /// mechanical result.
    Detached = 9,
}

impl NodeStatus {
    /// All statuses, in code order.
    pub const ALL: [NodeStatus; 10] = [
        NodeStatus::Placed,
        NodeStatus::Pending,
        NodeStatus::OffTool,
        NodeStatus::NoRoot,
        NodeStatus::ShearLimit,
        NodeStatus::Fold,
        NodeStatus::SheetJump,
        NodeStatus::ParentMissing,
        NodeStatus::OutsideOutline,
        NodeStatus::Detached,
    ];
    /// Snake-case name used in files and summaries.
    pub fn name(self) -> &'static str {
        match self {
            NodeStatus::Placed => "placed",
            NodeStatus::Pending => "pending",
            NodeStatus::OffTool => "off_tool",
            NodeStatus::NoRoot => "no_root",
            NodeStatus::ShearLimit => "shear_limit",
            NodeStatus::Fold => "fold",
            NodeStatus::SheetJump => "sheet_jump",
            NodeStatus::ParentMissing => "parent_missing",
            NodeStatus::OutsideOutline => "outside_outline",
            NodeStatus::Detached => "detached",
        }
    }
    /// Status from its numeric code.
    pub fn from_code(code: u8) -> Option<Self> {
        Self::ALL.get(code as usize).copied()
    }
}

/// Wall-clock time per stage, in milliseconds.
#[derive(Debug, Clone, Default, Serialize, Deserialize, PartialEq)]
pub struct Timing {
    /// Reading the tool.
    pub load_ms: f64,
    /// Laying the generators.
    pub generators_ms: f64,
    /// Filling the net (the solve, for a refined net).
    pub fill_ms: f64,
    /// The whole drape.
    pub total_ms: f64,
}

/// A draped warp/weft grid. Node (i, j) is at index `i * nv + j`; i runs along the warp.
/// A node's position is meaningful only where its status is [`NodeStatus::Placed`].
#[derive(Debug, Clone)]
pub struct DrapeNet {
    /// Ply name.
    pub name: String,
    /// How the net was computed.
    pub method: Method,
    /// Fibre segment length d (m).
    pub spacing: f64,
    /// Nodes along the warp (i).
    pub nu: usize,
    /// Nodes along the weft (j).
    pub nv: usize,
    /// Grid indices of the origin node.
    pub origin_node: (usize, usize),
    /// Node positions, m (meaningful where placed).
    pub positions: Vec<Point>,
    /// Triangle of the tool each placed node lies in.
    pub triangles: Vec<u32>,
    /// What happened to each node.
    pub status: Vec<NodeStatus>,
    /// Time per stage.
    pub timing: Timing,
    /// Where the net came from (`"meta"` in the JSON file): tool, material, directions...
    pub meta: Provenance,
}

impl DrapeNet {
    /// An empty (all pending) net.
    pub fn new(name: &str, spacing: f64, nu: usize, nv: usize, origin_node: (usize, usize)) -> Self {
        let n = nu * nv;
        DrapeNet {
            name: name.to_string(),
            method: Method::Kinematic,
            spacing,
            nu,
            nv,
            origin_node,
            positions: vec![Point::origin(); n],
            triangles: vec![u32::MAX; n],
            status: vec![NodeStatus::Pending; n],
            timing: Timing::default(),
            meta: Default::default(),
        }
    }

    /// Linear index of node (i, j).
    #[inline]
    pub fn index(&self, i: usize, j: usize) -> usize {
        i * self.nv + j
    }

    /// Position of node (i, j) if it was placed.
    #[inline]
    pub fn node(&self, i: usize, j: usize) -> Option<Point> {
        let k = self.index(i, j);
        (self.status[k] == NodeStatus::Placed).then(|| self.positions[k])
    }

    /// Number of cells, `(nu - 1) * (nv - 1)`.
    pub fn num_cells(&self) -> usize {
        (self.nu - 1) * (self.nv - 1)
    }

    /// The four corners of cell (i, j) if all are placed and the sheet was not cut through it
    /// ([`Provenance::cut_cells`]): [(i,j), (i+1,j), (i,j+1), (i+1,j+1)].
    #[inline]
    pub fn cell_corners(&self, i: usize, j: usize) -> Option<[Point; 4]> {
        if self.cell_cut(i, j) {
            return None;
        }
        Some([self.node(i, j)?, self.node(i + 1, j)?, self.node(i, j + 1)?, self.node(i + 1, j + 1)?])
    }

    /// Whether the sheet was cut through cell (i, j) ([`Provenance::cut_cells`], kept sorted).
    #[inline]
    pub fn cell_cut(&self, i: usize, j: usize) -> bool {
        !self.meta.cut_cells.is_empty() && self.meta.cut_cells.binary_search(&[i, j]).is_ok()
    }

    /// Mean shear angle of cell (i, j) in radians: the mean over its four corners of
    /// pi/2 - angle(warp edge, weft edge), edges oriented along +i and +j.
    pub fn cell_shear(&self, i: usize, j: usize) -> Option<f64> {
        let [p00, p10, p01, p11] = self.cell_corners(i, j)?;
        let (w0, w1) = (p10 - p00, p11 - p01); // warp edges (bottom, top)
        let (f0, f1) = (p01 - p00, p11 - p10); // weft edges (left, right)
        let g = corner_shear(&w0, &f0) + corner_shear(&w0, &f1) + corner_shear(&w1, &f0) + corner_shear(&w1, &f1);
        Some(0.25 * g)
    }

    /// Unit warp and weft directions and unit normal (warp x weft) of cell (i, j).
    pub fn cell_frame(&self, i: usize, j: usize) -> Option<CellFrame> {
        let [p00, p10, p01, p11] = self.cell_corners(i, j)?;
        let warp = ((p10 - p00) + (p11 - p01)).try_normalize(0.0)?;
        let weft = ((p01 - p00) + (p11 - p10)).try_normalize(0.0)?;
        let normal = warp.cross(&weft).try_normalize(0.0)?;
        let centre = Point::from((p00.coords + p10.coords + p01.coords + p11.coords) * 0.25);
        Some(CellFrame { centre, warp, weft, normal })
    }

    /// Count of nodes by status.
    pub fn status_counts(&self) -> Vec<(NodeStatus, usize)> {
        let mut counts = [0usize; NodeStatus::ALL.len()];
        for s in &self.status {
            counts[*s as usize] += 1;
        }
        NodeStatus::ALL.iter().zip(counts).filter(|(_, c)| *c > 0).map(|(s, c)| (*s, c)).collect()
    }

    /// Draped area of cell (i, j) if all its corners are placed: half the norm of the cross
    /// product of its diagonals, the area of a planar quad of any shape (and of the best plane
    /// through a warped one), m^2.
    pub fn cell_area(&self, i: usize, j: usize) -> Option<f64> {
        let [p00, p10, p01, p11] = self.cell_corners(i, j)?;
        Some(0.5 * (p11 - p00).cross(&(p01 - p10)).norm())
    }

    /// Each cell's shear in radians ([`DrapeNet::cell_shear`]), in file order (index
    /// i * (nv - 1) + j), `None` for a cell lacking a placed corner: computed in parallel, each
    /// value a function of its cell alone, so the same whatever the thread count.
    pub fn cell_shears(&self) -> Vec<Option<f64>> {
        use rayon::prelude::*;
        let cv = self.nv.saturating_sub(1);
        let n = self.nu.saturating_sub(1) * cv;
        (0..n).into_par_iter().with_min_len(1 << 12).map(|k| self.cell_shear(k / cv, k % cv)).collect()
    }

    /// Shear and area statistics over the complete cells, `locking_angle` in radians: the one
    /// computation behind the run summary, the layup table and the report.
    pub fn shear_stats(&self, locking_angle: f64) -> ShearStats {
        self.stats_of(locking_angle, |i, j| self.cell_shear(i, j))
    }

    /// [`DrapeNet::shear_stats`] from the cells' shears as [`DrapeNet::cell_shears`] gives them
    /// (the same figures, without computing the shears again).
    pub fn shear_stats_from(&self, shears: &[Option<f64>], locking_angle: f64) -> ShearStats {
        let cv = self.nv.saturating_sub(1);
        assert_eq!(shears.len(), self.nu.saturating_sub(1) * cv, "one shear per cell");
        self.stats_of(locking_angle, |i, j| shears[i * cv + j])
    }

    fn stats_of(&self, locking_angle: f64, shear: impl Fn(usize, usize) -> Option<f64> + Sync) -> ShearStats {
        use rayon::prelude::*;
        /// Cells whose shear and area are computed in parallel before they are summed.
        const BATCH: usize = 1 << 16;
        let mut s = ShearStats::default();
        let mut sum = 0.0;
        let cv = self.nv.saturating_sub(1);
        let n = self.nu.saturating_sub(1) * cv;
        // Each cell's shear and area in parallel, summed in cell order as a serial loop sums
        // them: the same figures whatever the thread count.
        for start in (0..n).step_by(BATCH) {
            let values: Vec<Option<(f64, f64)>> = (start..n.min(start + BATCH))
                .into_par_iter()
                .with_min_len(1 << 12)
                .map(|k| Some((shear(k / cv, k % cv)?, self.cell_area(k / cv, k % cv)?)))
                .collect();
            for (g, area) in values.into_iter().flatten() {
                s.cells += 1;
                s.area += area;
                sum += g.abs();
                s.max_abs = s.max_abs.max(g.abs());
                if g.abs() > locking_angle {
                    s.over_locking += 1;
                    s.area_over_locking += area;
                }
            }
        }
        if s.cells > 0 {
            s.mean_abs = sum / s.cells as f64;
        }
        s
    }
}

/// Local fibre frame of one cell.
#[derive(Debug, Clone, Copy)]
pub struct CellFrame {
    /// Mean of the four corners.
    pub centre: Point,
    /// Unit warp direction.
    pub warp: Vector,
    /// Unit weft direction.
    pub weft: Vector,
    /// Unit normal, warp x weft.
    pub normal: Vector,
}

/// Shear and area statistics of a net's complete cells (radians, m^2), from
/// [`DrapeNet::shear_stats`].
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ShearStats {
    /// Complete cells (all four corners placed).
    pub cells: usize,
    /// Largest |shear|.
    pub max_abs: f64,
    /// Mean |shear|.
    pub mean_abs: f64,
    /// Cells sheared past the locking angle.
    pub over_locking: usize,
    /// Draped area of the complete cells ([`DrapeNet::cell_area`]).
    pub area: f64,
    /// Draped area of the cells sheared past the locking angle.
    pub area_over_locking: f64,
}

/// Shear of one corner: pi/2 minus the angle between the warp and weft edges, radians.
#[inline]
pub fn corner_shear(warp: &Vector, weft: &Vector) -> f64 {
    // atan2 form: accurate near 0 and near 90 deg, unlike acos of a dot product.
    let angle = warp.cross(weft).norm().atan2(warp.dot(weft));
    std::f64::consts::FRAC_PI_2 - angle
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 2 x 2 net whose one cell has the corners `c` ([(0,0), (1,0), (0,1), (1,1)] order).
    fn one_cell(c: [[f64; 3]; 4]) -> DrapeNet {
        let mut net = DrapeNet::new("c", 1.0, 2, 2, (0, 0));
        for (k, (i, j)) in [(0, 0), (1, 0), (0, 1), (1, 1)].into_iter().enumerate() {
            let n = net.index(i, j);
            net.positions[n] = Point::from(c[k]);
            net.status[n] = NodeStatus::Placed;
        }
        net
    }

    #[test]
    fn cell_area_is_exact_for_any_planar_quad() {
        // Not a parallelogram: the shoelace area of the ring (0,0), (1,0), (3,3), (0,1) is 3.
        // (Two triangles on the wrong diagonal, (00, 10, 01) + (00, 01, 11), gave 2.)
        let net = one_cell([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [3.0, 3.0, 0.0]]);
        assert!((net.cell_area(0, 0).unwrap() - 3.0).abs() < 1e-15);
        let s = net.shear_stats(0.0);
        assert_eq!((s.cells, s.over_locking), (1, 1));
        assert_eq!((s.area, s.area_over_locking), (3.0, 3.0));
    }
}
