//! Contact with the tool and fixed nodes, as per-node bases of allowed motion (pressed contact
//! and fixed directions) and linearised one-sided constraints (free contact).
use crate::geometry::{Point, SmoothSurface, ToolSurface, Vector};
use nalgebra::Matrix3;

/// Where a point meets a contact surface.
#[derive(Debug, Clone, Copy)]
pub struct Foot {
    /// The surface point for the query (its closest point, or a retraction onto the surface
    /// exact to first order).
    pub point: Point,
    /// The surface's unit outward normal there.
    pub normal: Vector,
    /// Outward directions of the tool's open (boundary) edges the point lies on.
    pub open_edges: [Option<Vector>; 2],
}

/// A surface the nodes are held against (pressed) or kept out of (free).
pub trait ContactSurface: Sync {
    /// Where `p` meets the surface.
    fn locate(&self, p: &Point) -> Foot;
}

impl ContactSurface for ToolSurface {
    fn locate(&self, p: &Point) -> Foot {
        let s = self.closest_point(p);
        let l = self.barycentric(s.triangle, &s.point);
        Foot { point: s.point, normal: s.normal, open_edges: self.open_edges_at(s.triangle, &l) }
    }
}

impl ContactSurface for SmoothSurface<'_> {
    fn locate(&self, p: &Point) -> Foot {
        let s = self.project(p);
        Foot { point: s.point, normal: s.normal, open_edges: self.tool().open_edges_at(s.triangle, &s.barycentric) }
    }
}

/// How the ply meets the tool.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ContactMode {
    /// Held against the tool (hand lay-up, vacuum): nodes stay on the surface and slide on it.
    Pressed,
    /// Gravity drape with one-sided contact: no node inside the tool.
    Free,
    /// No tool (virtual material tests).
    None,
}

/// How one node may move in a step: `dofs` orthonormal directions (the first `dofs` columns of
/// `basis`); 0 = fixed, 2 = sliding on the tool, 3 = free.
#[derive(Debug, Clone, Copy)]
pub struct NodeBasis {
    /// How many directions: 0 fixed, 2 sliding, 3 free.
    pub dofs: usize,
    /// The directions, as columns.
    pub basis: Matrix3<f64>,
}

impl NodeBasis {
    /// No direction: the node stays.
    pub const FIXED: NodeBasis =
        NodeBasis { dofs: 0, basis: Matrix3::new(0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0) };

    /// Free in all three directions.
    pub fn free() -> Self {
        NodeBasis { dofs: 3, basis: Matrix3::identity() }
    }

    /// Free to slide in the plane normal to `n`.
    pub fn tangent(n: &Vector) -> Self {
        let (t1, t2) = tangent_pair(n);
        NodeBasis { dofs: 2, basis: Matrix3::from_columns(&[t1, t2, *n]) }
    }

    /// Free to move along `t` only.
    pub fn line(t: &Vector) -> Self {
        let t = t.normalize();
        let (a, b) = tangent_pair(&t);
        NodeBasis { dofs: 1, basis: Matrix3::from_columns(&[t, a, b]) }
    }

    /// Column k of the basis.
    #[inline]
    pub fn dir(&self, k: usize) -> Vector {
        self.basis.column(k).into()
    }
}

/// How a node may move.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Freedom {
    /// Held where it is.
    Fixed,
    /// Free in space.
    Free,
    /// Along a fixed direction only.
    Line(Vector),
    /// Within the plane with this normal.
    InPlane(Vector),
    /// Sliding on the tool (pressed contact).
    OnTool,
    /// Sliding on the tool within the plane with this normal (keeps a direction fixed).
    OnToolInPlane(Vector),
}

impl Freedom {
    /// Number of free directions.
    pub fn dofs(&self) -> usize {
        match self {
            Freedom::Fixed => 0,
            Freedom::Line(_) | Freedom::OnToolInPlane(_) => 1,
            Freedom::OnTool | Freedom::InPlane(_) => 2,
            Freedom::Free => 3,
        }
    }

    /// Whether the node slides on the tool (its basis needs the node's [`Foot`]).
    pub fn on_tool(&self) -> bool {
        matches!(self, Freedom::OnTool | Freedom::OnToolInPlane(_))
    }

    /// The basis of allowed motion for a node the energy pushes along `descent`; the on-tool
    /// kinds use the node's `foot` on the tool (its normal is +z without one). An on-tool node on
    /// the tool's open boundary that is pushed out over it is held there by the edge (it slides
    /// along the edge, or stays put at a corner): the tool ends, and a pressed ply does not
    /// leave it.
    pub fn basis(&self, foot: Option<&Foot>, descent: &Vector) -> NodeBasis {
        let foot =
            || foot.copied().unwrap_or(Foot { point: Point::origin(), normal: Vector::z(), open_edges: [None; 2] });
        // The open edges the node is pushed over, as outward directions in the tangent plane.
        let held = |f: &Foot| -> Vec<Vector> {
            f.open_edges
                .iter()
                .flatten()
                .filter_map(|m| (m - f.normal * f.normal.dot(m)).try_normalize(1e-9))
                .filter(|m| m.dot(descent) > 0.0)
                .collect()
        };
        match self {
            Freedom::Fixed => NodeBasis::FIXED,
            Freedom::Free => NodeBasis::free(),
            Freedom::Line(t) => NodeBasis::line(t),
            Freedom::InPlane(m) => NodeBasis::tangent(&m.normalize()),
            Freedom::OnTool => {
                let f = foot();
                match held(&f).as_slice() {
                    [] => NodeBasis::tangent(&f.normal),
                    [m] => NodeBasis::line(&f.normal.cross(m)),
                    _ => NodeBasis::FIXED,
                }
            }
            Freedom::OnToolInPlane(m) => {
                let f = foot();
                match f.normal.cross(m).try_normalize(1e-9) {
                    Some(t) if held(&f).is_empty() => NodeBasis::line(&t),
                    _ => NodeBasis::FIXED,
                }
            }
        }
    }
}

/// Two unit vectors completing `n` (unit) to an orthonormal frame.
pub fn tangent_pair(n: &Vector) -> (Vector, Vector) {
    let helper = if n.x.abs() < 0.6 { Vector::x() } else { Vector::y() };
    let t1 = n.cross(&helper).normalize();
    let t2 = n.cross(&t1);
    (t1, t2)
}

/// A linearised one-sided contact constraint: `normal . (x + delta - point) >= 0`.
#[derive(Debug, Clone, Copy)]
pub struct ContactRow {
    /// The node.
    pub node: usize,
    /// Unit normal of the tool at the contact point.
    pub normal: Vector,
    /// Signed gap `normal . (x - point)` at the current state (>= 0 when outside the tool).
    pub gap: f64,
}

/// Nodes within this many spacings of the tool get a contact row in free drape.
pub const CONTACT_RANGE: f64 = 2.0;

/// Linearised contact rows for the free-drape nodes near the tool.
pub fn contact_rows(tool: &dyn ContactSurface, x: &[Point], movable: &[bool], spacing: f64) -> Vec<ContactRow> {
    use rayon::prelude::*;
    x.par_iter()
        .enumerate()
        .filter(|(k, _)| movable[*k])
        .filter_map(|(k, p)| {
            let Foot { point: foot, normal, .. } = tool.locate(p);
            // On the tool or outside: the tool's outward normal; a node found inside gets a row
            // that pushes it back out.
            ((p - foot).norm() <= CONTACT_RANGE * spacing).then(|| ContactRow {
                node: k,
                normal,
                gap: normal.dot(&(p - foot)),
            })
        })
        .collect()
}
