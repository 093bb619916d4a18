//! Forming a flat blank by tools in motion (issue 33): the tool (the punch) moves along its
//! stroke over the increments and ends where the tool file has it; a die (the female half, met
//! by the ply's other face) and a binder (a blank holder clamping the blank outside its opening)
//! stay where they are. The ply meets every tool with one-sided contact and Coulomb friction,
//! so where it spans from punch to die it hangs where the mechanics puts it.
//!
//! The tools are one [`ContactSurface`] per increment ([`ToolsAt`]): a node meets whichever tool
//! it is nearest to, the punch moved back by what of the stroke is still to come. A punch step
//! of less than a spacing ([`STROKE_STEP_SPACINGS`]) lets the solver's contact search find the
//! nodes the punch has passed and put them back on its face before each solve.
//!
//! The binder clamps the blank in its plane: a node outside the binder's opening in plan view
//! (across the stroke) and still in the blank's plane slides in that plane only, and friction
//! on both faces holds it with a normal force of the binder's pressure over the node's share of
//! the fabric ([`Binder::bearing`]). Drawn in past the opening's edge it is let go. A ply of a
//! layup formed over the plies below grips them with its lower face: the two faces' coefficients
//! differ then (`ply_friction`, [`super::friction::Coulomb::binder`]).
use super::contact::{ContactSurface, Foot};
use super::friction::Bearing;
use super::sheet::{point_in_polygon, polygon_round, PolygonFault};
use crate::geometry::{Point, ToolError, ToolSurface, Vector};
use crate::kinematic::provenance::{BinderRecord, BlankPlaneRecord, FormingRecord};
use std::sync::Arc;

/// The punch moves at most this many spacings per increment: the solver's contact search
/// ([`super::solver::CONTACT_RANGE`], 2 spacings) finds every node the punch passed in a step,
/// with room for the punch's slope.
pub const STROKE_STEP_SPACINGS: f64 = 0.5;
/// A stroke whose component against the side the blank lies on is more than this share of its
/// length moves the punch away from the blank ([`Forming::check_pushes`]). A punch moving along
/// its own face (no component) still carries the blank by friction.
pub const STROKE_AWAY: f64 = 1e-2;
/// Most increments a stroke may be divided into (a bound on the run's time whatever the stroke
/// and spacing).
pub const MAX_STROKE_STEPS: usize = 400;
/// A node is still in the binder's grip while it lies within this many spacings of the blank's
/// plane (nodes the binder holds stay in it exactly; one drawn into the opening and lifted by
/// the punch is not gripped again).
pub const BINDER_PLANE_SPACINGS: f64 = 1e-3;

/// A forming process: what moves, what holds.
#[derive(Debug, Clone)]
pub struct Forming {
    /// The punch's motion over the whole process (m): the tool is `-stroke` from where the tool
    /// file has it when the blank is laid, and ends there.
    pub stroke: Vector,
    /// The die: the ply stays out of it (on the side its face turns to the punch), still.
    pub die: Option<Arc<ToolSurface>>,
    /// The die's file as the scene names it (recorded, so that the formed ply can be held by
    /// it again: [`Forming::at_stroke_end`]).
    pub die_file: Option<String>,
    /// The blank holder.
    pub binder: Option<Binder>,
    /// The plane the blank was laid flat in, where the binder grips it. None: through the
    /// origin node of the flat blank the stroke starts from, normal to it there.
    pub blank_plane: Option<BlankPlane>,
    /// The ply is formed already (a formed net refined again): the tools stand where the stroke
    /// left them, and the ply is solved in one increment without motion, starting from the
    /// equilibrium it was formed to (its friction starts with the normal forces and the
    /// friction forces that hold it there). With a binder, `blank_plane` must then be given.
    pub at_stroke_end: bool,
}

/// The plane a flat blank was laid in (the binder grips the blank in it).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BlankPlane {
    /// A point of the plane, m.
    pub point: Point,
    /// Its unit normal.
    pub normal: Vector,
}

/// A blank holder: it clamps the blank outside its opening with a pressure, friction on both
/// faces.
#[derive(Debug, Clone)]
pub struct Binder {
    /// The opening's inner boundary in plan view across the stroke ([`PlanView`]), m.
    pub outline: Vec<[f64; 2]>,
    /// The clamping pressure, Pa.
    pub pressure: f64,
    /// Per node, whether it grips it, given: a formed ply held again grips the nodes its last
    /// increment gripped (those outside the opening as that increment began: a node drawn past
    /// the opening's edge during it is let go only at the next). None: the nodes outside its
    /// opening in the blank's plane ([`Binder::gripped`]).
    pub gripping: Option<Vec<bool>>,
}

/// How the binder held a formed blank at the end of its stroke: the plane it gripped in and
/// the nodes it gripped in the last increment (what a formed ply held again is held by).
#[derive(Debug, Clone, PartialEq)]
pub struct Grip {
    /// The blank's plane.
    pub plane: BlankPlane,
    /// Per node, whether the binder gripped it (none without a binder).
    pub nodes: Vec<bool>,
}

/// Why a forming set-up cannot run.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{field}: {message}")]
pub struct FormingError {
    /// The scene field at fault (`stroke` or `binder`).
    pub field: &'static str,
    /// What is wrong and what to do.
    pub message: String,
}

fn stroke_error(message: String) -> FormingError {
    FormingError { field: "stroke", message }
}

fn binder_error(message: String) -> FormingError {
    FormingError { field: "binder", message }
}

/// Plan view across a stroke: coordinates in the plane normal to it. For a stroke along z (up or
/// down) they are x and y; otherwise the first axis is x (y if the stroke runs along x) with its
/// part along the stroke taken out, the second the stroke's axis (its largest component
/// positive) crossed with it.
#[derive(Debug, Clone, Copy)]
pub struct PlanView {
    axes: [Vector; 2],
}

impl PlanView {
    /// The plan view across `stroke` (non-zero).
    pub fn across(stroke: &Vector) -> Self {
        // The axis's sense does not depend on the stroke's (a punch rising or a die falling
        // along z both see x and y): its largest component is positive.
        let d = stroke.normalize();
        let d = if d[d.iamax()] < 0.0 { -d } else { d };
        let first = if d.x.abs() < 0.9 { Vector::x() } else { Vector::y() };
        let e1 = (first - d * d.dot(&first)).normalize();
        let e2 = d.cross(&e1);
        PlanView { axes: [e1, e2] }
    }

    /// The plan's two axes (unit vectors normal to the stroke).
    pub fn axes(&self) -> [Vector; 2] {
        self.axes
    }

    /// Where `p` appears in plan.
    pub fn at(&self, p: &Point) -> [f64; 2] {
        [self.axes[0].dot(&p.coords), self.axes[1].dot(&p.coords)]
    }
}

impl Forming {
    /// Check the set-up: a stroke, a binder opening that encloses an area and the blank's centre
    /// `origin` (m), a pressure that is a finite number >= 0.
    pub fn check(&self, origin: &Point) -> Result<(), FormingError> {
        if !(self.stroke.iter().all(|x| x.is_finite()) && self.stroke.norm() > 0.0) {
            return Err(stroke_error(format!(
                "the stroke must be a non-zero vector of three finite numbers, got {:?}",
                self.stroke.as_slice()
            )));
        }
        if let Some(b) = &self.binder {
            let c = PlanView::across(&self.stroke).at(origin);
            // The outline's own faults first, then the pressure, then where the blank lies.
            let fault = polygon_round(&b.outline, (c[0], c[1])).err();
            match fault {
                Some(PolygonFault::TooFew | PolygonFault::NonFinite) => {
                    return Err(binder_error(
                        "the binder's outline needs three or more corners [x, y] of finite numbers".into(),
                    ))
                }
                Some(PolygonFault::NoArea) => {
                    return Err(binder_error(
                        "the binder's outline encloses no area: give its corners in order round the opening".into(),
                    ))
                }
                _ => {}
            }
            if !(b.pressure.is_finite() && b.pressure >= 0.0) {
                return Err(binder_error(format!(
                    "the binder's pressure must be a finite number >= 0 (Pa), got {}",
                    b.pressure
                )));
            }
            if fault == Some(PolygonFault::Outside) {
                return Err(binder_error(format!(
                    "the blank's centre (the ply's origin, at [{:.4}, {:.4}] m in plan) lies under the binder, outside its opening: give the opening's outline round the punch",
                    c[0], c[1]
                )));
            }
        }
        Ok(())
    }

    /// Whether the stroke pushes the punch into the blank: the blank lies on the side `blank_side`
    /// (unit) of the punch at its centre, and a stroke with a component against it larger than
    /// [`STROKE_AWAY`] of its length moves the punch away from the blank, which nothing then
    /// forms. (A punch whose file faces into the part looks the same from here: the run said it
    /// had converged, on 16% of the tool, after 20 times the iterations.)
    pub fn check_pushes(&self, blank_side: &Vector) -> Result<(), FormingError> {
        let along = self.stroke.dot(blank_side) / self.stroke.norm();
        if along >= -STROKE_AWAY {
            return Ok(());
        }
        let s = self.stroke;
        Err(stroke_error(format!(
            "the stroke [{:.4}, {:.4}, {:.4}] moves the punch away from the blank: at the blank's centre the plies lie on the \
             side [{:.3}, {:.3}, {:.3}] of the tool (the side its facets' normals point to, or the other with stack_side = \
             \"opposite\"), and the punch must move that way into the blank. Reverse the stroke; or, if the tool's file faces \
             into the part, give stack_side = \"opposite\"",
            s.x, s.y, s.z, blank_side.x, blank_side.y, blank_side.z
        )))
    }

    /// What the net records of the process, formed in `increments` increments and left gripped
    /// as `grip` says ([`super::refine::Refined::grip`]; nodes numbered on a grid `nv` nodes
    /// wide).
    pub fn record(&self, increments: usize, grip: Option<&Grip>, nv: usize) -> FormingRecord {
        let axes = PlanView::across(&self.stroke).axes().map(|a| [a.x, a.y, a.z]);
        FormingRecord {
            stroke_m: [self.stroke.x, self.stroke.y, self.stroke.z],
            increments,
            die: self.die.is_some(),
            die_file: self.die_file.clone(),
            plan_axes: axes,
            binder: self.binder.as_ref().map(|b| BinderRecord {
                outline_m: b.outline.clone(),
                pressure_pa: b.pressure,
                gripped: grip.map(|g| {
                    (g.nodes.iter().enumerate()).filter(|(_, &on)| on).map(|(k, _)| [k / nv, k % nv]).collect()
                }),
            }),
            blank_plane: grip
                .map(|g| g.plane)
                .or(self.blank_plane)
                .map(|p| BlankPlaneRecord { point_m: p.point.coords.into(), normal: p.normal.into() }),
            blank_m: None,
            levels: Vec::new(),
        }
    }

    /// The process a formed net of `nu` x `nv` nodes records (`record`), with the tools where
    /// its stroke left them ([`Forming::at_stroke_end`]) and `die` its die (read from the file it
    /// names, or another), checked as a scene's set-up is; the binder grips the nodes the
    /// record says it gripped. A record with a binder must give the blank's plane.
    pub fn at_end_of(
        record: &FormingRecord,
        die: Option<Arc<ToolSurface>>,
        (nu, nv): (usize, usize),
    ) -> Result<Forming, FormingError> {
        let stroke = Vector::from(record.stroke_m);
        let blank_plane = record
            .blank_plane
            .as_ref()
            .map(|p| BlankPlane { point: Point::from(p.point_m), normal: Vector::from(p.normal).normalize() });
        if record.binder.is_some() && blank_plane.is_none() {
            return Err(FormingError {
                field: "blank_plane",
                message: "the net records a binder but not the plane it gripped the blank in (a net formed before \
                          drape recorded it): form the ply again"
                    .into(),
            });
        }
        let binder = match &record.binder {
            None => None,
            Some(b) => {
                let gripping = match &b.gripped {
                    None => None,
                    Some(nodes) => {
                        let mut on = vec![false; nu * nv];
                        for &[i, j] in nodes {
                            if i >= nu || j >= nv {
                                return Err(binder_error(format!(
                                    "gripped: node [{i}, {j}] is outside the net's {nu} x {nv} grid: the net's record is damaged; form the ply again"
                                )));
                            }
                            on[i * nv + j] = true;
                        }
                        Some(on)
                    }
                };
                Some(Binder { outline: b.outline_m.clone(), pressure: b.pressure_pa, gripping })
            }
        };
        let forming =
            Forming { stroke, die, die_file: record.die_file.clone(), binder, blank_plane, at_stroke_end: true };
        // The blank's centre where the stroke ends: its origin node laid in the plane, carried
        // by the stroke (the binder's opening must hold it).
        if let Some(p) = &forming.blank_plane {
            forming.check(&(p.point + stroke))?;
        }
        Ok(forming)
    }

    /// Increments for a stroke at `spacing`: enough that the punch moves at most
    /// [`STROKE_STEP_SPACINGS`] per increment, at least `asked`; one, with no motion, at the
    /// stroke's end.
    pub fn increments(&self, spacing: f64, asked: usize) -> usize {
        if self.at_stroke_end {
            return 1;
        }
        let needed = (self.stroke.norm() / (STROKE_STEP_SPACINGS * spacing)).ceil() as usize;
        needed.max(asked).clamp(1, MAX_STROKE_STEPS)
    }

    /// Where the punch is at the end of increment `step` of `steps` (0: the start): moved back
    /// by the share of the stroke still to come.
    pub fn punch_offset(&self, step: usize, steps: usize) -> Vector {
        if self.at_stroke_end {
            return Vector::zeros();
        }
        -self.stroke * (1.0 - step as f64 / steps as f64)
    }

    /// How far the punch moves over increment `step` (from 1) of `steps`.
    pub fn punch_step(&self, step: usize, steps: usize) -> Vector {
        self.punch_offset(step, steps) - self.punch_offset(step - 1, steps)
    }
}

impl Binder {
    /// Which nodes the binder grips at `x`: those outside its opening in plan and in the blank's
    /// plane (through `plane_point`, unit normal `plane_normal`), or those it is given
    /// ([`Binder::gripping`]) of the ply's `body`.
    pub fn gripped(
        &self,
        view: &PlanView,
        x: &[Point],
        body: &[bool],
        plane_point: &Point,
        plane_normal: &Vector,
        spacing: f64,
    ) -> Vec<bool> {
        if let Some(given) = &self.gripping {
            return given.iter().zip(body).map(|(&g, &b)| g && b).collect();
        }
        x.iter()
            .zip(body)
            .map(|(p, &b)| {
                let q = view.at(p);
                b && !point_in_polygon((q[0], q[1]), &self.outline)
                    && plane_normal.dot(&(p - plane_point)).abs() <= BINDER_PLANE_SPACINGS * spacing
            })
            .collect()
    }

    /// Whether any of `points` lies under the binder: outside its opening in plan (`view`).
    pub fn reaches_under<'a>(&self, view: &PlanView, mut points: impl Iterator<Item = &'a Point>) -> bool {
        points.any(|p| {
            let q = view.at(p);
            !point_in_polygon((q[0], q[1]), &self.outline)
        })
    }

    /// Where a gripped node bears: on the blank's plane, with the binder's pressure over its
    /// share of the fabric `area` (m^2) on each of its two faces (friction acts on both), `mu`
    /// the mean of the two faces' coefficients ([`super::friction::Coulomb::binder`]).
    pub fn bearing(&self, plane_normal: &Vector, area: f64, mu: f64) -> Bearing {
        Bearing {
            normal: *plane_normal,
            force: 2.0 * self.pressure * area,
            mu,
            on_plies: false,
            carried: Vector::zeros(),
        }
    }
}

/// The tools at one increment as one contact surface: the punch moved by `offset`, the die
/// where it is; a point meets the tool it is nearest to. The die's facets are numbered after
/// the punch's (`punch_facets` of them), so a foot's facet says which tool it is on.
pub struct ToolsAt<'a> {
    /// The punch (the tool, or its smooth surface).
    pub punch: &'a dyn ContactSurface,
    /// How many facets the punch has.
    pub punch_facets: u32,
    /// Where the punch is, from where the tool file has it.
    pub offset: Vector,
    /// How far the punch moved over this increment.
    pub step: Vector,
    /// The die (its smooth surface, or its facets), its normals facing the ply ([`die_facing`]).
    /// Its flat face stays flat up to the entry fillet (the smooth surface's face edges,
    /// `geometry::smooth`): the binder holds the blank in that plane.
    pub die: Option<&'a dyn ContactSurface>,
}

impl ToolsAt<'_> {
    fn punch_foot(&self, mut foot: Foot) -> Foot {
        foot.point += self.offset;
        foot
    }

    fn die_foot(&self, mut foot: Foot) -> Foot {
        foot.facet += self.punch_facets;
        foot
    }

    fn hints(&self, hint: Option<u32>) -> (Option<u32>, Option<u32>) {
        match hint {
            Some(h) if h >= self.punch_facets => (None, Some(h - self.punch_facets)),
            h => (h, None),
        }
    }
}

/// The nearer of two feet (the smaller gap: a node inside a tool meets that one).
fn nearer(a: Option<Foot>, b: Option<Foot>) -> Option<Foot> {
    match (a, b) {
        (Some(a), Some(b)) => Some(if b.gap < a.gap { b } else { a }),
        (a, b) => a.or(b),
    }
}

impl ContactSurface for ToolsAt<'_> {
    fn locate(&self, p: &Point, curved: bool, hint: Option<u32>) -> Foot {
        let (hp, hd) = self.hints(hint);
        let punch = self.punch_foot(self.punch.locate(&(p - self.offset), curved, hp));
        let die = self.die.map(|d| self.die_foot(d.locate(p, curved, hd)));
        nearer(Some(punch), die).expect("the punch has a foot")
    }

    fn locate_near(&self, p: &Point, range: f64, curved: bool, hint: Option<u32>) -> Option<Foot> {
        let (hp, hd) = self.hints(hint);
        let punch = self.punch.locate_near(&(p - self.offset), range, curved, hp).map(|f| self.punch_foot(f));
        let die = self.die.and_then(|d| d.locate_near(p, range, curved, hd).map(|f| self.die_foot(f)));
        nearer(punch, die)
    }

    fn curve(&self, foot: &mut Foot) {
        match self.die {
            Some(die) if foot.facet >= self.punch_facets => {
                let mut own = Foot { facet: foot.facet - self.punch_facets, ..*foot };
                die.curve(&mut own);
                foot.curvature = own.curvature;
            }
            // Curvature does not change with a translation.
            _ => self.punch.curve(foot),
        }
    }

    fn motion(&self, foot: &Foot) -> Vector {
        if foot.facet < self.punch_facets {
            self.step
        } else {
            Vector::zeros()
        }
    }

    fn moving(&self) -> bool {
        self.step != Vector::zeros()
    }
}

/// The die with its normals facing the ply, which is what contact keeps the ply on the side
/// of: its face nearest the blank's centre `origin` faces against the stroke (the punch moves
/// into the die). A die whose file winds it the other way is turned over.
pub fn die_facing(die: ToolSurface, origin: &Point, stroke: &Vector) -> Result<ToolSurface, ToolError> {
    if die.closest_point(origin).normal.dot(stroke) <= 0.0 {
        return Ok(die);
    }
    turned_over(&die)
}

/// `tool` with every facet wound the other way: its normals point to the other side.
pub fn turned_over(tool: &ToolSurface) -> Result<ToolSurface, ToolError> {
    let turned = tool.triangles().iter().map(|&[a, b, c]| [a, c, b]).collect();
    ToolSurface::from_triangles(tool.vertices().to_vec(), turned)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_plan_view_across_z_is_x_and_y() {
        let v = PlanView::across(&Vector::new(0.0, 0.0, -0.05));
        let q = v.at(&Point::new(0.3, -0.2, 7.0));
        assert!((q[0] - 0.3).abs() < 1e-15 && (q[1] + 0.2).abs() < 1e-15, "{q:?}");
    }

    #[test]
    fn increments_keep_the_punch_step_below_half_a_spacing() {
        let f = Forming {
            stroke: Vector::new(0.0, 0.0, 0.05),
            die: None,
            die_file: None,
            binder: None,
            blank_plane: None,
            at_stroke_end: false,
        };
        assert_eq!(f.increments(0.005, 1), 20);
        assert_eq!(f.increments(0.005, 30), 30);
        assert!((f.punch_offset(0, 20) + f.stroke).norm() < 1e-15);
        assert!(f.punch_offset(20, 20).norm() < 1e-15);
    }

    #[test]
    fn a_binder_opening_must_hold_the_blanks_centre() {
        let square = vec![[-0.1, -0.1], [0.1, -0.1], [0.1, 0.1], [-0.1, 0.1]];
        let f = Forming {
            stroke: Vector::new(0.0, 0.0, 0.05),
            die: None,
            die_file: None,
            binder: Some(Binder { outline: square, pressure: 1e4, gripping: None }),
            blank_plane: None,
            at_stroke_end: false,
        };
        assert!(f.check(&Point::new(0.0, 0.0, 0.02)).is_ok());
        assert!(f.check(&Point::new(0.3, 0.0, 0.02)).is_err());
        let still = Forming { stroke: Vector::zeros(), ..f.clone() };
        assert!(still.check(&Point::origin()).is_err());
    }
}
