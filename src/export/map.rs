//! Mapping a draped net onto a resin-flow mesh: for every flow element, the warp and weft of each
//! ply projected into the element's plane, the shear angle, the thickness and fibre volume
//! fraction change and, on request, a permeability tensor (REFERENCES.md §5).
use super::flowmesh::FlowMesh;
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

/// The fibres of one ply in one flow element.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ElementFibres {
    /// Warp direction projected into the element plane, unit.
    pub warp: Vector,
    /// Weft direction projected into the element plane, unit.
    pub weft: Vector,
    /// Unit element normal (right-handed over G1, G2, G3).
    pub normal: Vector,
    /// Shear angle, radians: pi/2 minus the angle between `warp` and `weft`.
    pub shear: f64,
    /// Angle from the element's first edge G1 -> G2 (projected) to `warp`, about `normal`,
    /// radians in (-pi, pi]: Nastran's material angle THETA.
    pub theta: f64,
    /// Angle from the ply's nominal fibre direction (its reference direction turned by the ply
    /// angle, projected into the element plane) to `warp`, about `normal`, radians in (-pi, pi]:
    /// the "angle variation" of OptiStruct's DRAPE.
    pub angle_change: f64,
    /// Ply thickness here, metres.
    pub thickness: f64,
    /// Ply thickness as laid flat (t0), metres; `thickness / nominal_thickness` is the
    /// thinning factor of OptiStruct's DRAPE.
    pub nominal_thickness: f64,
    /// Fibre volume fraction here.
    pub vf: f64,
    /// Permeability tensor in global coordinates (m^2), symmetric, principal directions along
    /// the bisectors of warp and weft and the element normal; `None` unless asked for.
    pub permeability: Option<Matrix3<f64>>,
}

/// One ply mapped onto a flow mesh: one entry per flow element, `None` where the ply does not
/// cover the element (marked, not guessed).
#[derive(Debug, Clone)]
pub struct PlyMap {
    pub ply: String,
    pub elements: Vec<Option<ElementFibres>>,
}

/// Every ply of a layup mapped onto one flow mesh, with laminate-level fields.
#[derive(Debug, Clone)]
pub struct LayupMap {
    /// Plies in stacking order.
    pub plies: Vec<PlyMap>,
    /// True when the map comes from a layup (field names get a `<ply>_` prefix), false for the
    /// export of one net (plain field names).
    pub layup: bool,
    /// Laminate thickness per element: the sum over the plies covering it (0 where none does).
    pub thickness: Vec<f64>,
    /// Thickness-weighted mean fibre volume fraction per element, `None` where no ply covers it.
    pub mean_vf: Vec<Option<f64>>,
    /// Laminate permeability per element (thickness-weighted mean of the plies' tensors), `None`
    /// where no ply covers it or permeability was not asked for.
    pub permeability: Vec<Option<Matrix3<f64>>>,
}
