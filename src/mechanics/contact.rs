//! Contact with the tool and fixed nodes, as per-node bases of allowed motion: pressed nodes slide
//! on the tool, free nodes touching it and pushed into it slide on it for a step (one-sided
//! contact as an active set), held nodes keep some directions fixed.
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
    /// Signed distance of the query point from the surface along `normal` (negative inside).
    pub gap: f64,
    /// The surface's curvature there: a point moved by a tangent vector t stays on the surface
    /// by moving `-1/2 t^T curvature t` along the normal (zero on flat facets). None when not
    /// asked for ([`ContactSurface::curve`] fills it in).
    pub curvature: Option<Matrix3<f64>>,
    /// The part of the surface the point is on (a [`SmoothSurface`] region; 0 on facets).
    pub region: u32,
    /// The tool's facet nearest to the query.
    pub facet: u32,
}

impl Foot {
    /// The curvature, which must have been computed.
    pub fn curvature(&self) -> &Matrix3<f64> {
        self.curvature.as_ref().expect("the feet of a state have their curvature")
    }
}

/// A surface the nodes are held against (pressed) or kept out of (free).
pub trait ContactSurface: Sync {
    /// Where `p` meets the surface; with its curvature if `curved` (trial states, which only
    /// need their energy, skip it: on a smooth tool it costs as much as the rest). `hint`: the
    /// facet of the point's last foot, where the search for the nearest facet starts (the same
    /// answer, found faster after a small move).
    fn locate(&self, p: &Point, curved: bool, hint: Option<u32>) -> Foot;
    /// Where `p` meets the surface if it is within `range` of it (a cheap test first).
    fn locate_near(&self, p: &Point, range: f64, curved: bool, hint: Option<u32>) -> Option<Foot>;
    /// Computes the curvature of a foot found without it.
    fn curve(&self, foot: &mut Foot);
    /// How far the surface at `foot` moved over the current increment (a punch on its stroke;
    /// zero for a tool that stays still): friction measures a node's slip against it.
    fn motion(&self, _foot: &Foot) -> Vector {
        Vector::zeros()
    }
    /// Whether any part of the surface moves over the current increment (a punch on its
    /// stroke): it then pushes into the ply's nodes that touch it.
    fn moving(&self) -> bool {
        false
    }
}

impl ContactSurface for ToolSurface {
    fn curve(&self, foot: &mut Foot) {
        foot.curvature.get_or_insert_with(Matrix3::zeros);
    }
    fn locate(&self, p: &Point, _curved: bool, hint: Option<u32>) -> Foot {
        let s = self.closest_point_from(p, hint);
        let l = self.barycentric(s.triangle, &s.point);
        Foot {
            point: s.point,
            normal: s.normal,
            open_edges: self.open_edges_at(s.triangle, &l),
            gap: s.normal.dot(&(p - s.point)),
            curvature: Some(Matrix3::zeros()),
            region: 0,
            facet: s.triangle,
        }
    }
    fn locate_near(&self, p: &Point, range: f64, curved: bool, hint: Option<u32>) -> Option<Foot> {
        let foot = self.locate(p, curved, hint);
        ((p - foot.point).norm() <= range).then_some(foot)
    }
}

impl ContactSurface for SmoothSurface<'_> {
    fn curve(&self, foot: &mut Foot) {
        if foot.curvature.is_none() {
            foot.curvature = Some(self.curvature_near(foot.region, foot.facet, &foot.point));
        }
    }
    fn locate(&self, p: &Point, curved: bool, hint: Option<u32>) -> Foot {
        let facet = self.tool().closest_point_from(p, hint);
        let (s, curvature) = self.project_from_curved_if(p, &facet, curved);
        Foot {
            point: s.point,
            normal: s.normal,
            open_edges: self.tool().open_edges_at(s.triangle, &s.barycentric),
            gap: s.normal.dot(&(p - s.point)),
            curvature,
            region: s.region,
            facet: s.triangle,
        }
    }
    fn locate_near(&self, p: &Point, range: f64, curved: bool, hint: Option<u32>) -> Option<Foot> {
        // The surface stays within a sagitta of the facets: test against the facets first, by
        // bounding boxes, then by distance.
        if !self.tool().any_triangle_near(p, 2.0 * range) {
            return None;
        }
        let facet = self.tool().closest_point_from(p, hint);
        if facet.distance > 2.0 * range {
            return None;
        }
        let (s, curvature) = self.project_from_curved_if(p, &facet, curved);
        let open_edges = self.tool().open_edges_at(s.triangle, &s.barycentric);
        if s.beyond_boundary || s.beyond_region {
            // Past the tool's open edge, or past a sharp edge of the region the nearest tool is the edge itself: the point is
            // outside, at its distance from the edge.
            let normal = (p - facet.point).try_normalize(0.0).unwrap_or(facet.normal);
            return Some(Foot {
                point: facet.point,
                normal,
                open_edges,
                gap: facet.distance,
                curvature: Some(Matrix3::zeros()),
                region: s.region,
                facet: s.triangle,
            });
        }
        Some(Foot {
            point: s.point,
            normal: s.normal,
            open_edges,
            gap: s.normal.dot(&(p - s.point)),
            curvature,
            region: s.region,
            facet: s.triangle,
        })
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
    /// How many directions: 0 fixed, 1 a line, 2 a plane, 3 free.
    pub dofs: usize,
    /// The directions, as columns (the first `dofs` are free).
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

    /// The directions of this basis that do not move along `n` (unit): the basis with `n`
    /// projected out (a free node on the tool's tangent plane, a node in a plane on the line
    /// where that plane meets the tangent plane, a line along the normal: fixed).
    pub fn without(&self, n: &Vector) -> NodeBasis {
        let mut kept: Vec<Vector> = Vec::with_capacity(3);
        for k in 0..self.dofs {
            let mut v = self.dir(k) - n * n.dot(&self.dir(k));
            for u in &kept {
                v -= u * u.dot(&v);
            }
            if let Some(v) = v.try_normalize(1e-9) {
                kept.push(v);
            }
        }
        match kept.as_slice() {
            [] => NodeBasis::FIXED,
            [t] => NodeBasis::line(t),
            [a, b, ..] => {
                let c = a.cross(b);
                NodeBasis { dofs: 2, basis: Matrix3::from_columns(&[*a, *b, c]) }
            }
        }
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

    /// Whether the node meets the tool in free contact: it moves, and no plane holds it (a
    /// node the binder grips is held in the blank's plane by the binder, whatever tool lies
    /// under it: a ply laid on another in a punch-and-die lies a ply's thickness above the
    /// die's face, and its grip was undone when contact put its nodes on the face).
    pub fn meets_tool_free(&self) -> bool {
        self.dofs() > 0 && !matches!(self, Freedom::InPlane(_))
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
        let foot = || {
            foot.copied().unwrap_or(Foot {
                point: Point::origin(),
                normal: Vector::z(),
                open_edges: [None; 2],
                gap: 0.0,
                curvature: Some(Matrix3::zeros()),
                region: 0,
                facet: 0,
            })
        };
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
