//! [`Provenance`]: where a net came from and what later stages need to know about it (`"meta"`
//! in `<ply>.drape.json`). Each stage sets the typed fields it knows and the later stages read
//! them, so a key one stage writes is the key the next one reads.
use serde::{Deserialize, Serialize};
use serde_json::{Map, Value};

/// Where a net came from (`"meta"` in `<ply>.drape.json`, keys as the field names). Every field
/// is optional: a net read from a file has what the stages that made it recorded.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Provenance {
    /// Unit warp direction at the seed, as the drape resolved it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub warp_direction: Option<[f64; 3]>,
    /// The seed on the tool, m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub origin: Option<[f64; 3]>,
    /// Pre-shear between the generators, degrees.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pre_shear_deg: Option<f64>,
    /// How the generators were laid: `geodesic`, `min-shear` or `steer`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub generators: Option<String>,
    /// The surface the fishnet lay on: `facets` or `smooth` (files written before it was
    /// recorded were draped on the facets, and read so).
    #[serde(default)]
    pub surface: super::SurfaceKind,
    /// Shear past which nodes were refused, degrees.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_shear_deg: Option<f64>,
    /// The ply angle of a layup ply, degrees (absent when its warp was given as a vector).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub angle_deg: Option<f64>,
    /// The material card file.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub material: Option<String>,
    /// Ply thickness as laid flat, m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub thickness_m: Option<f64>,
    /// Largest distance the tool was offset by the plies below, m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stack_offset_max_m: Option<f64>,
    /// The side of the tool a layup's plies lie on, where it is the other side than the one its
    /// facets' normals point to (absent: that side). `drape refine` meets the tool turned over
    /// for such a net, as the layup's mechanics did.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stack_side: Option<StackSide>,
    /// The tool file, as given to the command.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tool: Option<String>,
    /// Metres per unit of the tool file: the scale the tool was read with.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tool_scale: Option<f64>,
    /// The scene file of a layup ply.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scene: Option<String>,
    /// For a refined net: the change of each cell from the kinematic net.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub change_from_kinematic: Option<CellChanges>,
    /// For a refined net: what the solver did.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub solver: Option<SolverRecord>,
    /// For a refined net: how each node meets the tool (friction, stick and slip, pressure).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub contact: Option<ContactRecord>,
    /// How far the blank's edge moved in towards the seed, in plan ([`super::draw_in`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub draw_in: Option<DrawIn>,
    /// For a ply draped with `method = "auto"`: what was chosen and why.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub method_choice: Option<MethodChoice>,
    /// Per cell, how far the ply stands off the surface it was draped on, how much it undulates
    /// about its own smoothed surface and the bending energy there; the wrinkled area
    /// ([`super::wrinkle`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub wrinkles: Option<WrinkleRecord>,
    /// Cells the sheet was cut through (a `[[ply.cut]]`, the edge between a seam's two sheets, a
    /// cell the blank leaves out), as `[i, j]`, sorted: no fabric lies there, so they have no
    /// shear, frame or any other cell value, whatever their corners ([`super::DrapeNet::cell_corners`]).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub cut_cells: Vec<[usize; 2]>,
    /// The features of the flat sheet a mechanical ply was draped as (seed 000's sheets, a
    /// blank): the net records that they were there, not the features themselves, which its
    /// scene gives (`drape refine` refuses a net it could not draw them from).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub sheet_features: Vec<SheetFeature>,
    /// For a blank formed by tools in motion: the stroke, the die and the binder it was formed
    /// with.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub forming: Option<FormingRecord>,
    /// Keys other tools wrote, kept on a round trip.
    #[serde(flatten)]
    pub other: Map<String, Value>,
}

/// Which side of the tool the plies stack on (`"normal"` or `"opposite"`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum StackSide {
    /// The side the tool's facet normals point to.
    Normal,
    /// The other side.
    Opposite,
}

/// What `method = "auto"` chose for a ply, and why (`"method_choice"` in the net's meta and in
/// `layup.json`; the method that ran is `"method"`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MethodChoice {
    /// What the ply asked for: `auto`.
    pub requested: String,
    /// What ran: `kinematic` or `mechanical`.
    pub chosen: String,
    /// The surface the kinematic net lay on: `facets` or `smooth` (the ply's own, or the
    /// smooth surface when that net was within the tolerance and the one on the facets not).
    #[serde(default)]
    pub surface: String,
    /// The largest cell-shear error the ply accepts, degrees.
    pub tolerance_deg: f64,
    /// The fibre spacing that ran, m (finer than the ply's when the discretisation needed it).
    pub spacing_m: f64,
    /// Whether the choice's estimates say the ply is within the tolerance: `false` where an
    /// estimate is above it or could not be made, or mechanics did not converge (the reason
    /// says which); absent in files written before it was recorded.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub assured: Option<bool>,
    /// Why, in words.
    pub reason: String,
    /// What the choice was made from.
    pub indicators: ChoiceIndicators,
}

impl MethodChoice {
    /// Whether the estimates said the tolerance is not met (false for files that predate the
    /// verdict: they claim nothing either way).
    pub fn not_assured(&self) -> bool {
        self.assured == Some(false)
    }

    /// What ran, and that the tolerance is not assured where the estimates say so: the words
    /// every place that shows the choice leads with (`mechanical`, `kinematic (NOT ASSURED
    /// within 1 deg)`).
    pub fn headline(&self) -> String {
        if self.not_assured() {
            format!("{} (NOT ASSURED within {} deg)", self.chosen, self.tolerance_deg)
        } else {
            self.chosen.clone()
        }
    }
}

/// The cheap measurements on the kinematic net that `method = "auto"` decides from.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct ChoiceIndicators {
    /// The ply's own spacing, m.
    pub spacing_m: f64,
    /// Estimated largest cell-shear error of the kinematic net from its spacing, degrees: the
    /// difference from a net at twice the spacing, at the same fabric points, over 2^p - 1 with
    /// the fishnet's order p = 2 (absent when the coarser net has no cell to compare).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub discretisation_deg: Option<f64>,
    /// The spacing that error estimate asks for to stay within its share of the tolerance, m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub spacing_needed_m: Option<f64>,
    /// Where mechanics ran: the pressed drape's own estimated largest cell-shear error from its
    /// spacing, degrees, by the same estimate from the pressed drape at twice the spacing
    /// (absent when mechanics did not run or that drape did not converge).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mechanical_discretisation_deg: Option<f64>,
    /// The same estimate over the cells below the locking angle in both drapes, degrees (past
    /// it the fabric wrinkles and the shear there need not converge with the spacing).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mechanical_discretisation_unlocked_deg: Option<f64>,
    /// The spacing that estimate asks for to keep the pressed drape within the tolerance, m
    /// (present only when the ply's spacing is too coarse; auto then presses the ply again at
    /// the spacing it asks for, within its node budget).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mechanical_spacing_needed_m: Option<f64>,
    /// Where auto pressed the ply again finer: the order of convergence in the spacing its
    /// three pressed drapes (2d, d, d / k) show at their largest cell-shear differences (absent
    /// when the difference does not fall with the spacing).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mechanical_observed_order: Option<f64>,
    /// The same over the cells below the locking angle.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mechanical_observed_order_unlocked: Option<f64>,
    /// Where auto pressed the ply again finer: that drape's own estimated largest cell-shear
    /// error, degrees, against the drape at the ply's spacing (Richardson with their ratio, at
    /// the observed order, at most 2; absent when no order is observed).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub refined_mechanical_discretisation_deg: Option<f64>,
    /// The same over the cells below the locking angle, degrees (at their own observed order).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub refined_mechanical_discretisation_unlocked_deg: Option<f64>,
    /// Largest cell-shear change of the steps of the mechanical model from the kinematic net
    /// until the nodes settle, degrees: how far the kinematic net lies from equilibrium under
    /// the ply's card (absent when no step could be taken).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub equilibrium_step_deg: Option<f64>,
    /// The same step from the kinematic net on the smooth surface, degrees, when the ply lies
    /// on the facets and the step from that net was above the model's share of the tolerance.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub smooth_equilibrium_step_deg: Option<f64>,
    /// |F - P| / |P| of the mechanical model where that probe stopped.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub residual_after_step: Option<f64>,
    /// Iterations of the mechanical model that probe took (it goes on until the nodes settle,
    /// see `layup::auto`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub probe_iterations: Option<usize>,
    /// Share of the draped area sheared at or past the locking angle.
    pub locking_share: f64,
    /// Time spent measuring these, ms.
    pub time_ms: f64,
}

/// The change of every cell (index `i * (nv - 1) + j`) of a refined net from its kinematic net,
/// `None` where a cell is missing in either.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct CellChanges {
    /// Shear, refined minus kinematic, degrees.
    pub shear_deg: Vec<Option<f64>>,
    /// Angle between the kinematic and refined warp directions, degrees.
    pub warp_angle_deg: Vec<Option<f64>>,
}

/// What the mechanical solver did to a net.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SolverRecord {
    /// How the last load step ended (`converged`, `stalled`, `iteration_limit`, ...).
    pub outcome: String,
    /// Whether every load step ended in equilibrium: |F - P| <= tolerance |P| over the free
    /// directions. A net that did not converge is the last accepted state, not an equilibrium.
    #[serde(default)]
    pub converged: bool,
    /// Why it did not converge, in words (absent when it did).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reason: Option<String>,
    /// |F - P| / |P| at the end of the last load step.
    #[serde(default)]
    pub residual: f64,
    /// Solver iterations over all load steps.
    #[serde(default)]
    pub iterations: usize,
    /// Where the forces are furthest from balance when it did not converge, largest first.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub unbalanced: Vec<UnbalancedRecord>,
    /// Energy of the kinematic net under the full load, J.
    pub energy_kinematic: f64,
    /// Energy of the state the solver started from, J.
    pub energy_start: f64,
    /// Energy of the refined net, J.
    pub energy_final: f64,
    /// The second-order check of the final state: `minimum`, `saddle` (an equilibrium, but an
    /// unstable one) or `unresolved`; absent when not checked (switched off, not converged).
    /// The figures are in the last load step's `stability`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stability: Option<Stability>,
    /// The solver's log, one entry per solve (a load step's friction may take several).
    #[serde(default)]
    pub load_steps: Value,
    /// Per load step: its share of the load, its solves and how far its friction's normal
    /// forces changed over the last one.
    #[serde(default, skip_serializing_if = "Value::is_null")]
    pub increments: Value,
}

/// How a node of a refined net meets the tool at the end.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ContactState {
    /// Bears on the tool and friction holds it: it crept less than the stick distance in the
    /// last increment.
    Stick,
    /// Bears on the tool and slid over it in the last increment.
    Slip,
    /// Does not bear on the tool (hangs free, or a pressed node the tool pulls).
    Free,
    /// Held in place at the user's request (`hold`).
    Held,
}

impl ContactState {
    /// The state's number in VTU point data: 0 free, 1 stick, 2 slip, 3 held.
    pub fn code(self) -> i32 {
        match self {
            ContactState::Free => 0,
            ContactState::Stick => 1,
            ContactState::Slip => 2,
            ContactState::Held => 3,
        }
    }

    /// The state's name in files.
    pub fn name(self) -> &'static str {
        match self {
            ContactState::Stick => "stick",
            ContactState::Slip => "slip",
            ContactState::Free => "free",
            ContactState::Held => "held",
        }
    }
}

/// How each node of a refined net meets the tool (`"contact"` in the net's meta); per-node
/// lists are indexed `i * nv + j`, null where a node is not in the mechanical body.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct ContactRecord {
    /// Coulomb's coefficient between the ply and the tool.
    pub friction: f64,
    /// Coulomb's coefficient between the ply and the plies below it, where a layup gives one
    /// (`ply_friction`) and plies lie below.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ply_friction: Option<f64>,
    /// Seed 000's restraint (`stick = true`, free drape): the nodes the tool holds up stay where
    /// they touch until pulled off, friction without limit.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub sticky: bool,
    /// Per node: `stick`, `slip`, `free` or `held`.
    pub state: Vec<Option<ContactState>>,
    /// Per node: how far it slid over the tool over all load steps, m.
    pub slip_m: Vec<Option<f64>>,
    /// Per node: the tool's normal force on it over the node's share of the fabric, Pa.
    pub pressure_pa: Vec<Option<f64>>,
    /// The nodes the user held in place, [i, j].
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub held: Vec<[usize; 2]>,
    /// Where the ply slides: the least friction coefficient that would hold it, as far as the
    /// forces at the end tell (0: it rests in neutral balance, any friction holds it).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub friction_needed: Option<f64>,
    /// [`BETWEEN_PLIES`] when `friction_needed` is the least `ply_friction` (the ply slides on
    /// the plies below; the tool's friction as given where it bears on bare tool); absent when
    /// it is the tool's `friction`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub friction_needed_between: Option<String>,
}

/// What [`ContactRecord::friction_needed_between`] says when the coefficient needed is the one
/// between the ply and the plies below it.
pub const BETWEEN_PLIES: &str = "plies";

/// How a refined ply meets the tool, in a few numbers (the layup table's and the report's).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct ContactSummary {
    /// Coulomb's coefficient between the ply and the tool.
    pub friction: f64,
    /// Coulomb's coefficient between the ply and the plies below it ([`ContactRecord::ply_friction`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ply_friction: Option<f64>,
    /// Seed 000's restraint instead of friction ([`ContactRecord::sticky`]).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub sticky: bool,
    /// Nodes that bear on the tool and stick.
    pub stick: usize,
    /// Nodes that bear on the tool and slipped in the last load step.
    pub slip: usize,
    /// Nodes that do not bear on the tool.
    pub free: usize,
    /// Nodes held at the user's request.
    pub held: usize,
    /// The farthest any node slid over the tool, m.
    pub max_slip_m: f64,
    /// The largest contact pressure, Pa.
    pub max_pressure_pa: f64,
    /// Where the ply slides: the least friction coefficient that would hold it, where the
    /// forces tell.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub friction_needed: Option<f64>,
    /// Which coefficient that is ([`ContactRecord::friction_needed_between`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub friction_needed_between: Option<String>,
}

impl ContactRecord {
    /// The largest coefficient the ply met (0: frictionless everywhere).
    pub fn largest_friction(&self) -> f64 {
        self.ply_friction.map_or(self.friction, |p| p.max(self.friction))
    }

    /// The record in a few numbers.
    pub fn summary(&self) -> ContactSummary {
        let count = |s: ContactState| self.state.iter().flatten().filter(|&&x| x == s).count();
        let largest = |v: &[Option<f64>]| v.iter().flatten().copied().fold(0.0, f64::max);
        ContactSummary {
            friction: self.friction,
            ply_friction: self.ply_friction,
            sticky: self.sticky,
            stick: count(ContactState::Stick),
            slip: count(ContactState::Slip),
            free: count(ContactState::Free),
            held: count(ContactState::Held),
            max_slip_m: largest(&self.slip_m),
            max_pressure_pa: largest(&self.pressure_pa),
            friction_needed: self.friction_needed,
            friction_needed_between: self.friction_needed_between.clone(),
        }
    }
}

impl ContactSummary {
    /// One line for people: friction, how many nodes stick and slip, the largest slip.
    pub fn describe(&self) -> String {
        let grip = if self.sticky {
            "stick = true (nodes the tool holds up stay where they touch)".to_string()
        } else {
            match self.ply_friction {
                Some(p) => format!("friction {}, ply_friction {p} on the plies below", self.friction),
                None => format!("friction {}", self.friction),
            }
        };
        let nodes = if self.stick == 1 { "node sticks" } else { "nodes stick" };
        let mut s = format!("{grip}: {} {nodes}, {} slip, {} free", self.stick, self.slip, self.free);
        if self.held > 0 {
            s += &format!(", {} held", self.held);
        }
        s +=
            &format!("; largest slip {:.2} mm, largest pressure {:.3} Pa", self.max_slip_m * 1e3, self.max_pressure_pa);
        s
    }
}

/// A feature of the flat sheet a mechanical ply was draped as ([`Provenance::sheet_features`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SheetFeature {
    /// Reinforced bands (`[[ply.reinforcement]]`).
    Reinforcement,
    /// Two sheets stitched together (`[ply.seam]`).
    Seam,
    /// A fold (`[ply.fold]`).
    Fold,
    /// Cuts (`[[ply.cut]]`).
    Cut,
    /// The sheet cut to a blank (`blank`).
    Blank,
}

impl SheetFeature {
    /// Its name, as the JSON writes it.
    pub fn name(self) -> &'static str {
        match self {
            SheetFeature::Reinforcement => "reinforcement",
            SheetFeature::Seam => "seam",
            SheetFeature::Fold => "fold",
            SheetFeature::Cut => "cut",
            SheetFeature::Blank => "blank",
        }
    }
}

/// What the second-order check found of a converged mechanical state (`mechanics::stability`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Stability {
    /// No direction of negative curvature beyond the tolerance: a (local) minimum.
    Minimum,
    /// A direction of negative curvature: the state is an unstable equilibrium.
    Saddle,
    /// The check could not run (the reference model could not be factorised).
    Unresolved,
}

/// A node whose forces do not balance, in a [`SolverRecord`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct UnbalancedRecord {
    /// Grid indices (i, j).
    pub node: [usize; 2],
    /// Its position, m.
    pub position: [f64; 3],
    /// |F - P| over its free directions, N.
    pub force_n: f64,
    /// The energy term with the largest force there.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub term: Option<String>,
}

impl Provenance {
    /// The provenance as the JSON object written to a file: keys in sorted order.
    pub fn to_json(&self) -> Map<String, Value> {
        match serde_json::to_value(self) {
            Ok(Value::Object(map)) => map,
            _ => unreachable!("provenance serialises to a JSON object"),
        }
    }
}

/// A line through the origin node of the grid: a fibre or a diagonal, and which way.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum DrawInLine {
    /// Along the warp, away from the origin row (i increasing).
    #[serde(rename = "+warp")]
    WarpPlus,
    /// Along the weft (j increasing).
    #[serde(rename = "+weft")]
    WeftPlus,
    /// Along the warp, i decreasing.
    #[serde(rename = "-warp")]
    WarpMinus,
    /// Along the weft, j decreasing.
    #[serde(rename = "-weft")]
    WeftMinus,
    /// The diagonal of i and j increasing.
    #[serde(rename = "+warp+weft")]
    PlusPlus,
    /// The diagonal of i decreasing, j increasing.
    #[serde(rename = "-warp+weft")]
    MinusPlus,
    /// The diagonal of i and j decreasing.
    #[serde(rename = "-warp-weft")]
    MinusMinus,
    /// The diagonal of i increasing, j decreasing.
    #[serde(rename = "+warp-weft")]
    PlusMinus,
}

impl DrawInLine {
    /// The eight lines: the fibres first, then the diagonals.
    pub const ALL: [DrawInLine; 8] = [
        DrawInLine::WarpPlus,
        DrawInLine::WeftPlus,
        DrawInLine::WarpMinus,
        DrawInLine::WeftMinus,
        DrawInLine::PlusPlus,
        DrawInLine::MinusPlus,
        DrawInLine::MinusMinus,
        DrawInLine::PlusMinus,
    ];

    /// One step along it on the grid, (di, dj).
    pub fn step(self) -> (isize, isize) {
        match self {
            DrawInLine::WarpPlus => (1, 0),
            DrawInLine::WeftPlus => (0, 1),
            DrawInLine::WarpMinus => (-1, 0),
            DrawInLine::WeftMinus => (0, -1),
            DrawInLine::PlusPlus => (1, 1),
            DrawInLine::MinusPlus => (-1, 1),
            DrawInLine::MinusMinus => (-1, -1),
            DrawInLine::PlusMinus => (1, -1),
        }
    }

    /// Whether it runs along a fibre (else a diagonal).
    pub fn is_fibre(self) -> bool {
        let (di, dj) = self.step();
        di == 0 || dj == 0
    }

    /// Its name in files and tables (`+warp`, `-warp+weft`, ...).
    pub fn name(self) -> &'static str {
        match self {
            DrawInLine::WarpPlus => "+warp",
            DrawInLine::WeftPlus => "+weft",
            DrawInLine::WarpMinus => "-warp",
            DrawInLine::WeftMinus => "-weft",
            DrawInLine::PlusPlus => "+warp+weft",
            DrawInLine::MinusPlus => "-warp+weft",
            DrawInLine::MinusMinus => "-warp-weft",
            DrawInLine::PlusMinus => "+warp-weft",
        }
    }
}

/// The blank's edge on one line through the origin node.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct EdgeDrawIn {
    /// Which line.
    pub line: DrawInLine,
    /// The edge node (i, j): the last node the net reaches along the line.
    pub node: [usize; 2],
    /// Its distance from the origin node in the flat blank, m.
    pub flat_m: f64,
    /// Its distance from the origin node in plan, as draped, m.
    pub plan_m: f64,
    /// `flat_m - plan_m`, m: how far the edge moved in towards the seed (negative: out).
    pub draw_in_m: f64,
}

/// How a blank was formed (`meta.forming` in the net's JSON): what the report draws the draw-in
/// against.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FormingRecord {
    /// The punch's travel over the whole process, m.
    pub stroke_m: [f64; 3],
    /// The increments the stroke was taken in.
    pub increments: usize,
    /// Whether a die stood opposite the punch.
    pub die: bool,
    /// The die's file, as the scene named it (absent in files written before it was recorded).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub die_file: Option<String>,
    /// The axes of the plan across the stroke that the binder's outline is given in (unit
    /// vectors).
    pub plan_axes: [[f64; 3]; 2],
    /// The binder, if one held the blank.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub binder: Option<BinderRecord>,
    /// The plane the blank was laid flat in, where the binder grips it (absent in files written
    /// before it was recorded).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub blank_plane: Option<BlankPlaneRecord>,
    /// The outline the sheet was cut to, corners (u, v) in fabric coordinates from the origin
    /// node, m (absent: the whole grid, or a file written before it was recorded).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub blank_m: Option<Vec<[f64; 2]>>,
    /// A blank formed coarse to fine (`coarse_levels`): the grids it was solved on, coarsest
    /// first; the stroke's increments are the coarsest's, each finer one held by the tools
    /// where the stroke ended (empty: formed at the ply's spacing alone).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub levels: Vec<FormedLevel>,
}

impl FormingRecord {
    /// How a blank formed coarse to fine was solved, level by level (`formed coarse to fine:
    /// 10.0 mm, 12 increments, 266 iterations, 13.6 s; 5.0 mm held by the tools, 179
    /// iterations, 27.4 s`); None for a blank formed at its own spacing.
    pub fn levels_summary(&self) -> Option<String> {
        let (first, rest) = self.levels.split_first()?;
        let describe = |l: &FormedLevel, what: String| {
            format!(
                "{:.1} mm{what}, {} iterations, {:.1} s{}",
                l.spacing_m * 1e3,
                l.iterations,
                l.solve_ms * 1e-3,
                if l.converged { "" } else { " (NOT CONVERGED: the sequence ended there)" }
            )
        };
        let mut parts = vec![describe(first, format!(", {} increments", first.increments))];
        parts.extend(rest.iter().map(|l| describe(l, " held by the tools".into())));
        Some(format!("formed coarse to fine: {}", parts.join("; ")))
    }
}

/// One grid of a blank formed coarse to fine.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FormedLevel {
    /// The grid's fibre spacing, m.
    pub spacing_m: f64,
    /// The increments solved on it.
    pub increments: usize,
    /// The solver's iterations on it.
    pub iterations: usize,
    /// Whether it reached equilibrium (a level that did not ends the sequence: its net stands).
    pub converged: bool,
    /// Its solve time, ms.
    pub solve_ms: f64,
}

/// The plane a flat blank was laid in.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BlankPlaneRecord {
    /// A point of it (the blank's origin node where it was laid), m.
    pub point_m: [f64; 3],
    /// Its unit normal.
    pub normal: [f64; 3],
}

/// A binder as the blank was formed with it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BinderRecord {
    /// Its opening's inner boundary in the plan across the stroke, m.
    pub outline_m: Vec<[f64; 2]>,
    /// Its clamping pressure, Pa.
    pub pressure_pa: f64,
    /// The nodes [i, j] it gripped in the last increment (absent in files written before it was
    /// recorded).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gripped: Option<Vec<[usize; 2]>>,
}

/// A ply's draw-in (`meta.draw_in` in the net's JSON; its largest in the layup table).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DrawIn {
    /// The unit normal of the plan the distances are measured in.
    pub plan_normal: [f64; 3],
    /// Where the plan normal comes from: `sheet` (a flat start's normal) or `seed` (the ply's
    /// normal at its origin node).
    pub plan_from: String,
    /// One per line the net reaches beyond its origin node, fibres first.
    pub edges: Vec<EdgeDrawIn>,
}

impl DrawIn {
    /// The edge of the largest draw-in along the fibres, or along the diagonals.
    pub fn largest(&self, fibres: bool) -> Option<&EdgeDrawIn> {
        self.edges.iter().filter(|e| e.line.is_fibre() == fibres).max_by(|a, b| a.draw_in_m.total_cmp(&b.draw_in_m))
    }

    /// The edge of the largest draw-in on any line.
    pub fn largest_overall(&self) -> Option<&EdgeDrawIn> {
        self.edges.iter().max_by(|a, b| a.draw_in_m.total_cmp(&b.draw_in_m))
    }

    /// The draw-in in a few words, millimetres.
    pub fn describe(&self) -> String {
        let part = |fibres: bool, what: &str| {
            self.largest(fibres).map(|e| format!("{what} up to {:.2} mm ({})", e.draw_in_m * 1e3, e.line.name()))
        };
        let parts: Vec<String> =
            [part(true, "along the fibres"), part(false, "along the diagonals")].into_iter().flatten().collect();
        if parts.is_empty() {
            "no draw-in measured (the net reaches no node beyond its origin)".into()
        } else {
            format!("draw-in {} in the plan normal to {}", parts.join(", "), self.plan_from_words())
        }
    }

    fn plan_from_words(&self) -> &'static str {
        if self.plan_from == "sheet" {
            "the flat sheet"
        } else {
            "the ply at its seed"
        }
    }
}

/// Where the waviness threshold of a ply comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum WrinkleThresholdFrom {
    /// The ply's thickness as laid flat.
    Thickness,
    /// No thickness given: the default, 0.5 mm.
    Default,
}

impl WrinkleThresholdFrom {
    /// Its name in files and tables: `thickness` or `default`.
    pub fn name(self) -> &'static str {
        match self {
            WrinkleThresholdFrom::Thickness => "thickness",
            WrinkleThresholdFrom::Default => "default",
        }
    }
}

/// A ply's wrinkles in a few numbers (`layup.json`'s `wrinkles`, and the head of the net's
/// `meta.wrinkles`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct WrinkleSummary {
    /// A cell whose waviness exceeds this is wrinkled, m.
    pub threshold_m: f64,
    /// Where the threshold comes from: `thickness` or `default`.
    pub threshold_from: WrinkleThresholdFrom,
    /// The standard deviation of the Gaussian weights of the smoothed surface and of the
    /// waviness, in fibre spacings.
    pub smoothing_spacings: f64,
    /// A crest or a trough of the wave test bends the ply by more than this, m (the bend:
    /// the second difference of the positions along a fibre, along the normal): the
    /// threshold times `kinematic::wrinkle::WAVE_BEND_FRACTION`. Absent from a record written
    /// before the wave test (its cells are wrinkled on their waviness alone).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub wave_bend_m: Option<f64>,
    /// Cells whose waviness exceeds the threshold where the ply undulates (the wave test).
    pub wrinkled_cells: usize,
    /// Their draped area, m^2.
    pub wrinkled_area_m2: f64,
    /// The largest waviness of a cell, m (absent without a complete cell).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_waviness_m: Option<f64>,
    /// The largest distance of a cell's corner from the surface the ply was draped on, m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_tool_gap_m: Option<f64>,
    /// The largest bending energy density of a cell, J/m^2 (absent without a material card).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_bending_energy_density_j_m2: Option<f64>,
}

impl WrinkleSummary {
    /// The wrinkles in a few words, millimetres.
    pub fn describe(&self) -> String {
        let mm = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{:.3} mm", v * 1e3));
        let mut s = format!(
            "{} cells ({:.4} m^2) wavier than {:.3} mm (the {}) where the ply undulates; largest waviness {}, largest gap to the tool {}",
            self.wrinkled_cells,
            self.wrinkled_area_m2,
            self.threshold_m * 1e3,
            match self.threshold_from {
                WrinkleThresholdFrom::Thickness => "ply's thickness",
                WrinkleThresholdFrom::Default => "default, no thickness given",
            },
            mm(self.max_waviness_m),
            mm(self.max_tool_gap_m)
        );
        if let Some(b) = self.max_bending_energy_density_j_m2 {
            s += &format!(", largest bending energy {b:.4e} J/m^2");
        }
        s
    }
}

/// Per cell (index `i * (nv - 1) + j`, `None` where a cell is not complete): the wrinkle
/// measures of [`super::wrinkle`] (`"wrinkles"` in the net's meta).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct WrinkleRecord {
    /// The figures of the whole ply.
    #[serde(flatten)]
    pub summary: WrinkleSummary,
    /// Waviness: the amplitude of the ply's undulation about its own smoothed surface and about
    /// the tool, the smaller of the two, m.
    pub waviness_m: Vec<Option<f64>>,
    /// The wave test: whether the ply undulates about the cell (a crest between two troughs or
    /// a trough between two crests along a fibre through it, `kinematic::wrinkle`). Empty in a
    /// record written before the wave test.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub undulating: Vec<Option<bool>>,
    /// The largest distance of the cell's corners from the surface the ply was draped on (the
    /// tool, or the tool offset by the plies below), m: large by design where a ply hangs off
    /// the tool.
    pub tool_gap_m: Vec<Option<f64>>,
    /// Bending energy per unit area, J/m^2 (empty when the ply has no material card).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub bending_energy_density_j_m2: Vec<Option<f64>>,
}

impl WrinkleRecord {
    /// Whether cell `c` is wrinkled: its waviness exceeds the threshold and the ply undulates
    /// there (without the wave test, in a record written before it: on its waviness alone);
    /// `None` for a cell that is not complete. The one rule the VTU, the cells CSV and the
    /// report's map use, and the summary's count.
    pub fn wrinkled(&self, c: usize) -> Option<bool> {
        let wavy = self.waviness_m.get(c).copied().flatten()? > self.summary.threshold_m;
        let undulating = if self.undulating.is_empty() { true } else { self.undulating.get(c).copied().flatten()? };
        Some(wavy && undulating)
    }
}
