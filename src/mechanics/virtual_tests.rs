//! Virtual material tests on the mechanical model: the cantilever strip under its own weight
//! (seed 000 Fig. 7). Each test builds a small flat grid, holds or moves some nodes, and
//! minimises the energy in load steps.
//!
//! The in-plane shear tests ([`picture_frame`], [`bias_extension`]; REFERENCES.md section 3)
//! move the rig's clamped nodes by a crosshead displacement d in equal load steps, leave the
//! other nodes free in the plane z = 0, and report the crosshead force by virtual work (the
//! internal forces at the clamped nodes times their velocity dx/dd). Remarks on what the
//! discrete net gives (measured in tests/mechanics_shear_tests.rs, stiff fibres):
//! - Picture frame: the uniformly sheared net is an exact equilibrium; shear angle and force
//!   follow the frame formulas to solver precision.
//! - Bias extension: the long free edges are zigzags of whole cells with tips on the sample's
//!   edge, so zones B and C hold less fabric than the formula's W^2 and W (L - 3W/2) (by a
//!   triangle of a^2 per 2a of edge, a = h / sqrt 2): the nominal force is high by about
//!   1/(3k) for L = 2W, k = width / (sqrt 2 h) lattice steps per half width. For L = 2W the
//!   net takes the three zones exactly; for L > 2W the hexagonal central zone shears
//!   non-uniformly (more near the A apexes, less mid-length, +-4.5 deg at 40 deg nominal), which
//!   lowers the energy below the ideal three-zone state's: the pin-jointed net's minimum, not a
//!   mesh effect.
//! - The bending term measures each node's deviation from its neighbours' chord in 3D, so in
//!   the plane too: the kinks of the fibres at the bias-extension zone boundaries cost bending
//!   energy that grows as the spacing shrinks (a kink is a curvature concentrated on one node).
//!   With a realistic bending rigidity (e.g. 2e-4 N m) this adds to the force; with a negligible
//!   one the kinematics above hold.
use super::contact::{ContactMode, Freedom};
use super::energy::{Grid, Laws};
use super::refine::{NetObjective, STANDARD_GRAVITY};
use super::solver::{solve, Constraints, SolveReport, SolverSettings};
use crate::geometry::{Point, Vector};
use crate::material::test_kinematics::{BiasExtensionKinematics, PictureFrameKinematics};
use crate::material::Fibre;

/// Load steps of the cantilever: its weight is applied gradually (large deflection).
pub const CANTILEVER_LOAD_STEPS: usize = 20;

/// The result of a cantilever test: the strip's centre line from the clamp to the tip.
#[derive(Debug, Clone)]
pub struct Cantilever {
    /// Centre line of the strip from the clamp to the tip.
    pub nodes: Vec<Point>,
    /// One report per load step.
    pub steps: Vec<SolveReport>,
}

impl Cantilever {
    /// Whether every load step reached equilibrium.
    pub fn ok(&self) -> bool {
        self.steps.iter().all(SolveReport::ok)
    }
}

/// A strip with free length `length` and `nodes` nodes along `fibre`, one cell wide, clamped
/// horizontally at x = 0 (its first two node columns, at x = -d/2 and d/2, held level), hanging
/// under gravity along -z. The strip lies along +x; the returned centre line runs from the clamp
/// (first node, inside the clamp at x = -d/2) to the tip.
pub fn cantilever<L: Laws + ?Sized>(laws: &L, fibre: Fibre, length: f64, nodes: usize) -> Result<Cantilever, String> {
    if nodes < 3 {
        return Err(format!("a cantilever needs at least 3 nodes, got {nodes}"));
    }
    if !(length.is_finite() && length > 0.0) {
        return Err(format!("the strip length must be positive, got {length}"));
    }
    // The clamp holds the first two node columns level; its edge (where the free length
    // starts, x = 0) is midway between them, which keeps the discrete clamp second-order
    // accurate. The nodes sit at x = (k - 1/2) d, k = 0..nodes-1, the last at the tip x = L.
    let d = length / (nodes as f64 - 1.5);
    // The strip runs along the grid's i (warp) or j (weft) direction.
    let (nu, nv) = match fibre {
        Fibre::Warp => (nodes, 2),
        Fibre::Weft => (2, nodes),
    };
    let along = |i: usize, j: usize| match fibre {
        Fibre::Warp => (i, j),
        Fibre::Weft => (j, i),
    };
    let mut x = vec![Point::origin(); nu * nv];
    let mut freedom = vec![Freedom::Free; nu * nv];
    for i in 0..nu {
        for j in 0..nv {
            let (s, w) = along(i, j);
            let k = i * nv + j;
            // Warp strip: i along +x, j across (+y). Weft strip: j along +x, i across (-y), so
            // that warp x weft stays +z.
            x[k] = match fibre {
                Fibre::Warp => Point::new((s as f64 - 0.5) * d, w as f64 * d, 0.0),
                Fibre::Weft => Point::new((s as f64 - 0.5) * d, -(w as f64) * d, 0.0),
            };
            if s < 2 {
                freedom[k] = Freedom::Fixed;
            }
        }
    }
    let grid = Grid::full(nu, nv, d);
    let gravity = Vector::new(0.0, 0.0, -STANDARD_GRAVITY);
    let mut objective = NetObjective::new(grid, laws, gravity / CANTILEVER_LOAD_STEPS as f64);
    let cons = Constraints { freedom, mode: ContactMode::None, tool: None, spacing: d, stitched: None, stick: false };
    let settings = SolverSettings::default().max_iterations(200);
    let mut steps = Vec::new();
    for step in 1..=CANTILEVER_LOAD_STEPS {
        if step > 1 {
            objective.scale_loads(step as f64 / (step - 1) as f64);
        }
        let report = solve(&objective, &mut x, &cons, &settings);
        let ok = report.ok();
        steps.push(report);
        if !ok {
            break;
        }
    }
    let centre = (0..nodes)
        .map(|s| {
            let (a, b) = match fibre {
                Fibre::Warp => (s * nv, s * nv + 1),
                Fibre::Weft => (s, nv + s),
            };
            Point::from((x[a].coords + x[b].coords) * 0.5)
        })
        .collect();
    Ok(Cantilever { nodes: centre, steps })
}

// ---------------------------------------------------------------------------------------------
// In-plane shear tests: picture frame and bias extension (REFERENCES.md section 3)
// ---------------------------------------------------------------------------------------------

/// Largest net the shear tests build (nodes, active or not).
pub const SHEAR_TEST_MAX_NODES: usize = 1_000_000;
/// A load step whose solve fails is retried as two half steps, down to this many halvings.
pub const SHEAR_TEST_MAX_HALVINGS: usize = 4;
/// Each load step is solved in equal sub-steps of at most this nominal shear increment (rad,
/// from the test's kinematics): far from the previous equilibrium a solve can end in another
/// equilibrium (fibres folded in the plane) instead of following the loading path.
pub const SHEAR_TEST_MAX_SHEAR_INCREMENT: f64 = 5.0 * std::f64::consts::PI / 180.0;
/// Relative residual the shear-test solves aim for, against the shear force scale of the sample
/// (its length times the card's shear stiffness, the force a sheared radian would take): the
/// forces balance to a hundred-millionth of it, far finer than the force curves are read.
pub const SHEAR_TEST_TOLERANCE: f64 = 1e-8;

/// The shear force scale of a sample `length` long (N): the length times the card's shear
/// stiffness (the initial slope of its shear moment, or its secant slope to half a radian for a
/// law that starts flat).
fn shear_force_scale<L: Laws + ?Sized>(laws: &L, length: f64) -> f64 {
    let (_, _, slope) = laws.shear(0.0);
    let (_, half, _) = laws.shear(0.5);
    slope.max(half / 0.5).max(f64::MIN_POSITIVE) * length
}

/// A picture-frame test: a square sample of side `side` in the plane z = 0 with warp and weft
/// along the frame's arms, `steps` equal crosshead steps up to `displacement` (all in m).
#[derive(Debug, Clone, Copy)]
pub struct PictureFrame {
    /// Frame side L, hinge to hinge, m.
    pub side: f64,
    /// Requested fibre spacing of the net: the side is cut into `round(side / spacing)` cells
    /// (at least 2) and the spacing adjusted to fit exactly.
    pub spacing: f64,
    /// Final crosshead displacement, m.
    pub displacement: f64,
    /// Equal load steps up to it.
    pub steps: usize,
}

/// A bias-extension test: a `length` x `width` sample (free length between the clamps along x,
/// `length >= 2 width`) with its fibres at -45 deg (warp) and +45 deg (weft) to the load,
/// `steps` equal clamp displacements up to `displacement` (all in m).
#[derive(Debug, Clone, Copy)]
pub struct BiasExtension {
    /// Free length between the clamps, m.
    pub length: f64,
    /// Width, m.
    pub width: f64,
    /// Requested fibre spacing; adjusted so that the clamp corners are nodes (see
    /// [`bias_extension`]).
    pub spacing: f64,
    /// Final clamp displacement, m.
    pub displacement: f64,
    /// Equal load steps up to it.
    pub steps: usize,
}

/// The state after one completed load step, as passed to an observer.
pub struct ShearState<'s> {
    /// Load step (1..=steps).
    pub step: usize,
    /// Crosshead displacement, m.
    pub displacement: f64,
    /// Crosshead force (N).
    pub force: f64,
    /// The net's grid.
    pub grid: &'s Grid,
    /// Node positions at d = 0.
    pub reference: &'s [Point],
    /// Node positions (inactive nodes keep their reference position).
    pub nodes: &'s [Point],
}

/// What a shear test did: the force-displacement curve and the net.
#[derive(Debug, Clone)]
pub struct ShearTest {
    /// The net's grid: size, the fibre spacing actually used, active nodes.
    pub grid: Grid,
    /// Node positions at d = 0.
    pub reference: Vec<Point>,
    /// Node positions after the last completed load step (the last consistent state).
    pub nodes: Vec<Point>,
    /// Crosshead displacement: 0 first, then one entry per completed load step.
    pub displacement: Vec<f64>,
    /// Crosshead force (N) at each entry of `displacement` (0 at d = 0).
    pub force: Vec<f64>,
    /// Load steps requested and completed.
    pub requested: usize,
    /// Load steps completed.
    pub completed: usize,
    /// One report per solve, in order (sub-steps included; a failed solve is the last one).
    pub solves: Vec<SolveReport>,
    /// The sample's dimensions as the net realises them: (length or side, width or side, spacing).
    pub sample: (f64, f64, f64),
    /// Adjustments made to the request, in words.
    pub notes: Vec<String>,
}

impl ShearTest {
    /// Whether every load step reached equilibrium.
    pub fn ok(&self) -> bool {
        self.completed == self.requested
    }

    /// Shear angle (rad) of each cell (i, j) at index `i * (nv - 1) + j` in the final state, the
    /// mean of its four corners (as [`crate::kinematic::DrapeNet::cell_shear`]); None for cells
    /// that are not complete.
    pub fn cell_shears(&self) -> Vec<Option<f64>> {
        cell_shears(&self.grid, &self.nodes)
    }

    /// Total solver iterations.
    pub fn iterations(&self) -> usize {
        self.solves.iter().map(|s| s.iterations.len()).sum()
    }
}

/// Shear angle (rad) of each complete cell of `grid` at positions `x` (cell (i, j) at
/// `i * (nv - 1) + j`): the mean over its corners of pi/2 - angle(warp edge, weft edge).
pub fn cell_shears(grid: &Grid, x: &[Point]) -> Vec<Option<f64>> {
    use crate::kinematic::net::corner_shear;
    let (nu, nv) = (grid.nu, grid.nv);
    let mut out = Vec::with_capacity(nu.saturating_sub(1) * nv.saturating_sub(1));
    for i in 0..nu.saturating_sub(1) {
        for j in 0..nv.saturating_sub(1) {
            if !grid.cell_active(i, j) {
                out.push(None);
                continue;
            }
            let k = grid.index(i, j);
            let (p00, p10, p01, p11) = (x[k], x[k + nv], x[k + 1], x[k + nv + 1]);
            let (w0, w1) = (p10 - p00, p11 - p01);
            let (f0, f1) = (p01 - p00, p11 - p10);
            let g = corner_shear(&w0, &f0) + corner_shear(&w0, &f1) + corner_shear(&w1, &f0) + corner_shear(&w1, &f1);
            out.push(Some(0.25 * g));
        }
    }
    out
}

/// A test rig: the net, which nodes the rig holds, where it puts them at crosshead
/// displacement d and how fast they move with d.
struct Rig<'r> {
    grid: Grid,
    reference: Vec<Point>,
    freedom: Vec<Freedom>,
    /// The nodes the rig holds (clamped; moved between solves).
    held: Vec<usize>,
    place: Box<dyn Fn(usize, f64) -> Point + 'r>,
    rate: Box<dyn Fn(usize, f64) -> Vector + 'r>,
    /// The kinematic (nominal) rate of shear d gamma / d d (rad/m) at displacement d: sets the
    /// sub-steps.
    shear_rate: Box<dyn Fn(f64) -> f64 + 'r>,
}

fn positive(what: &str, v: f64, unit: &str) -> Result<f64, String> {
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(format!("the {what} must be a positive number ({unit}), got {v}"))
    }
}

fn check_steps(steps: usize) -> Result<(), String> {
    if steps == 0 {
        return Err("the number of load steps must be at least 1".into());
    }
    if steps > 100_000 {
        return Err(format!("{steps} load steps is too many (at most 100000)"));
    }
    Ok(())
}

fn check_size(nu: usize, nv: usize) -> Result<(), String> {
    match nu.checked_mul(nv) {
        Some(n) if n <= SHEAR_TEST_MAX_NODES => Ok(()),
        _ => {
            Err(format!("a {nu} x {nv} net is too large for memory and time (at most {SHEAR_TEST_MAX_NODES} nodes): use a larger spacing"))
        }
    }
}

/// Picture frame. The frame is four rigid arms of length `side`, pin-jointed at the corners; the
/// corner at the origin is fixed and the opposite corner is pulled along +x (the diagonal) by
/// the crosshead displacement d. With the angle phi between the arms, `cos(phi/2) = 1/sqrt(2) +
/// d / (2 side)` and the frame shear is `gamma = pi/2 - phi` (REFERENCES.md section 3). Node
/// (i, j) of the (n+1) x (n+1) net (n = round(side / spacing) cells per side, at least 2; the
/// spacing is adjusted to side / n) sits at `h (i e_w + j e_f)` with the arm directions
/// `e_w = (cos phi/2, -sin phi/2, 0)` (warp, along i) and `e_f = (cos phi/2, sin phi/2, 0)` (weft,
/// along j). The edge nodes are clamped to the arms (placed by the frame kinematics), the
/// interior nodes are free in the plane z = 0. The force is the crosshead force by virtual work,
/// `F = sum over edge nodes of f_k . dx_k/dd` with f_k the internal force at node k and
/// dx_k/dd from the frame kinematics (analytic).
pub fn picture_frame<L: Laws + ?Sized>(laws: &L, spec: &PictureFrame) -> Result<ShearTest, String> {
    picture_frame_observed(laws, spec, &mut |_| {})
}

/// As [`picture_frame`], calling `observe` after every completed load step.
pub fn picture_frame_observed<L: Laws + ?Sized>(
    laws: &L,
    spec: &PictureFrame,
    observe: &mut dyn FnMut(&ShearState),
) -> Result<ShearTest, String> {
    let side = positive("frame side", spec.side, "m")?;
    let spacing = positive("spacing", spec.spacing, "m")?;
    let frame = PictureFrameKinematics { side };
    let travel = frame.travel();
    let dmax = positive("displacement", spec.displacement, "m")?;
    if dmax >= travel {
        return Err(format!(
            "a displacement of {dmax} m is beyond the travel of a frame of side {side} m: the frame closes (90 deg shear) at \
             d = (2 - sqrt 2) side = {travel:.6} m"
        ));
    }
    check_steps(spec.steps)?;
    let ratio = side / spacing;
    if ratio.round() < 2.0 {
        return Err(format!(
            "the spacing ({spacing} m) must be at most half the frame side ({side} m): the net needs at least 2 cells per side"
        ));
    }
    if ratio > SHEAR_TEST_MAX_NODES as f64 {
        check_size(usize::MAX, 1)?;
    }
    let n = ratio.round() as usize;
    check_size(n + 1, n + 1)?;
    let h = side / n as f64;
    let mut notes = Vec::new();
    if (h - spacing).abs() > 1e-9 * spacing {
        notes.push(format!("spacing adjusted from {spacing} m to {h} m: {n} whole cells per side of {side} m"));
    }
    let nv = n + 1;
    let grid = Grid::full(nv, nv, h);
    // Frame kinematics: c = cos(phi/2), s = sin(phi/2) at displacement d.
    let cs = move |d: f64| frame.half_angle(d);
    let ij = move |k: usize| ((k / nv) as f64, (k % nv) as f64);
    let place = move |k: usize, d: f64| {
        let (c, s) = cs(d);
        let (i, j) = ij(k);
        Point::new(h * (i + j) * c, h * (j - i) * s, 0.0)
    };
    let rate = move |k: usize, d: f64| {
        let (c, s) = cs(d);
        let dc = 1.0 / (2.0 * side);
        let ds = -c / s * dc;
        let (i, j) = ij(k);
        Vector::new(h * (i + j) * dc, h * (j - i) * ds, 0.0)
    };
    let reference: Vec<Point> = (0..nv * nv).map(|k| place(k, 0.0)).collect();
    let mut freedom = vec![Freedom::InPlane(Vector::z()); nv * nv];
    let mut held = Vec::new();
    for (k, f) in freedom.iter_mut().enumerate() {
        let (i, j) = (k / nv, k % nv);
        if i == 0 || j == 0 || i == n || j == n {
            *f = Freedom::Fixed;
            held.push(k);
        }
    }
    // d gamma / d d = 1 / (side sin(phi/2)).
    let shear_rate = move |d: f64| frame.shear(d).map_or(f64::INFINITY, |(_, rate)| rate);
    let rig = Rig {
        grid,
        reference,
        freedom,
        held,
        place: Box::new(place),
        rate: Box::new(rate),
        shear_rate: Box::new(shear_rate),
    };
    Ok(run_rig(laws, rig, dmax, spec.steps, (side, side, h), notes, observe))
}

/// Bias extension. The net's fibres run at -45 deg (warp, along i) and +45 deg (weft, along j)
/// to the load direction x; its nodes lie on the lattice `x = (i + j - k) a`, `y = (j - i) a`,
/// `a = h / sqrt 2` (h the fibre spacing). The sample spans x in [0, length] between the clamps
/// and y in [-width/2, width/2]. The spacing is adjusted so that the clamp corners
/// (0, +-width/2) and (length, +-width/2) are nodes: width = 2 k a and length = 2 p a with whole
/// k, p (k as near the requested spacing as the ratio length/width allows; if no spacing within
/// a factor 1.5 fits, the request is refused with the nearest length that fits). The zone
/// boundaries of REFERENCES.md section 3 (the fibres through the clamp corners) are then grid
/// lines, and the discrete net can take the three-zone state exactly.
///
/// Active nodes: those inside the sample, plus one lattice column beyond each clamp line
/// (x = -a and x = length + a, inside the clamps; it fills the notches of the diamond cells
/// along the clamp lines). Cells count only with all four corners active, so the long free
/// edges are zigzags of whole cells with their tips on y = +-width/2: the net's fabric lacks a
/// triangle of area a^2 per 2a of edge, i.e. its mean edge is a/2 inside the sample's edge.
/// Nodes with x <= 0 are held (fixed clamp), nodes with x >= length are held and moved by d
/// along +x (moving clamp), all others are free in the plane z = 0. The force is the sum of the
/// internal forces' x components on the moving clamp's nodes (virtual work of the clamp).
pub fn bias_extension<L: Laws + ?Sized>(laws: &L, spec: &BiasExtension) -> Result<ShearTest, String> {
    bias_extension_observed(laws, spec, &mut |_| {})
}

/// As [`bias_extension`], calling `observe` after every completed load step.
pub fn bias_extension_observed<L: Laws + ?Sized>(
    laws: &L,
    spec: &BiasExtension,
    observe: &mut dyn FnMut(&ShearState),
) -> Result<ShearTest, String> {
    let length = positive("length", spec.length, "m")?;
    let width = positive("width", spec.width, "m")?;
    let spacing = positive("spacing", spec.spacing, "m")?;
    if length < 2.0 * width * (1.0 - 1e-12) {
        return Err(format!(
            "a bias-extension sample needs length >= 2 x width (three shear zones), got length {length} m, width {width} m"
        ));
    }
    let dmax = positive("displacement", spec.displacement, "m")?;
    let travel = BiasExtensionKinematics { length, width }.travel();
    if dmax >= travel {
        return Err(format!(
            "a displacement of {dmax} m takes the central zone of a {length} x {width} m sample past 90 deg shear \
             (at d = (sqrt 2 - 1)(length - width) = {travel:.6} m)"
        ));
    }
    check_steps(spec.steps)?;
    let sqrt2 = std::f64::consts::SQRT_2;
    // Half-width in lattice steps a: k = width / (2a) = width / (sqrt 2 h).
    let k0 = width / (sqrt2 * spacing);
    if k0 > SHEAR_TEST_MAX_NODES as f64 {
        check_size(usize::MAX, 1)?;
    }
    if k0 < 0.5 {
        return Err(format!(
            "the spacing ({spacing} m) is too coarse for a sample {width} m wide: it must be at most width / sqrt 2 = {:.6} m",
            width / sqrt2
        ));
    }
    let ratio = length / width;
    let fits = |k: usize| {
        let p = ratio * k as f64;
        ((p - p.round()).abs() <= 1e-6 * p.max(1.0)).then(|| p.round() as usize)
    };
    let kr = (k0.round() as usize).max(1);
    let lo = ((k0 / 1.5).floor() as usize).max(1);
    let hi = ((k0 * 1.5).ceil() as usize).max(kr);
    let mut candidates: Vec<usize> = (lo..=hi).collect();
    candidates.sort_by(|a, b| (*a as f64 - k0).abs().total_cmp(&(*b as f64 - k0).abs()));
    let Some((k, p)) = candidates.iter().find_map(|&k| fits(k).map(|p| (k, p))) else {
        let a = width / (2.0 * kr as f64);
        let p = (length / (2.0 * a)).round().max(2.0 * kr as f64);
        return Err(format!(
            "cannot lay the +-45 deg net on a {length} x {width} m sample with a spacing near {spacing} m: the clamp corners must \
             be nodes, so length / width must be a ratio p / k of whole numbers with k near width / (sqrt 2 spacing) = {k0:.2}; \
             with k = {kr} (spacing {:.6} m) give a length of {:.6} m, or choose another spacing",
            sqrt2 * a,
            2.0 * p * a
        ));
    };
    let a = width / (2.0 * k as f64);
    let h = sqrt2 * a;
    let mut notes = Vec::new();
    if (h - spacing).abs() > 1e-9 * spacing {
        notes.push(format!(
            "spacing adjusted from {spacing} m to {h} m so that the clamp corners are nodes ({} lattice steps across, {} along)",
            2 * k,
            2 * p
        ));
    }
    let n = k + p + 1;
    check_size(n, n)?;
    let nv = n;
    let tol = 1e-9 * a;
    let pos = |i: usize, j: usize| Point::new((i as f64 + j as f64 - k as f64) * a, (j as f64 - i as f64) * a, 0.0);
    let reference: Vec<Point> = (0..n * n).map(|q| pos(q / nv, q % nv)).collect();
    let x_end = 2.0 * p as f64 * a;
    let half = k as f64 * a;
    let mut active: Vec<bool> =
        reference.iter().map(|q| q.x >= -a - tol && q.x <= x_end + a + tol && q.y.abs() <= half + tol).collect();
    // Nodes that are a corner of no complete cell take no part (no energy would hold them).
    let mut used = vec![false; n * n];
    for i in 0..n - 1 {
        for j in 0..n - 1 {
            let q = i * nv + j;
            let corners = [q, q + 1, q + nv, q + nv + 1];
            if corners.iter().all(|&c| active[c]) {
                corners.iter().for_each(|&c| used[c] = true);
            }
        }
    }
    for (act, u) in active.iter_mut().zip(&used) {
        *act &= *u;
    }
    let grid = Grid::with_active(n, n, h, active.clone());
    let mut freedom = vec![Freedom::Fixed; n * n];
    let mut held = Vec::new();
    let mut moving = vec![false; n * n];
    for q in 0..n * n {
        if !active[q] {
            continue;
        }
        let x = reference[q].x;
        if x <= tol {
            held.push(q);
        } else if x >= x_end - tol {
            held.push(q);
            moving[q] = true;
        } else {
            freedom[q] = Freedom::InPlane(Vector::z());
        }
    }
    let reference_c = reference.clone();
    let moving_c = moving.clone();
    let place = move |q: usize, d: f64| if moving_c[q] { reference_c[q] + Vector::x() * d } else { reference_c[q] };
    let rate = move |q: usize, _d: f64| if moving[q] { Vector::x() } else { Vector::zeros() };
    // Zone C of the sample the net realises.
    let zone = BiasExtensionKinematics { length: x_end, width: 2.0 * half };
    let shear_rate = move |d: f64| zone.shear(d).map_or(f64::INFINITY, |(_, rate)| rate);
    let rig = Rig {
        grid,
        reference,
        freedom,
        held,
        place: Box::new(place),
        rate: Box::new(rate),
        shear_rate: Box::new(shear_rate),
    };
    Ok(run_rig(laws, rig, dmax, spec.steps, (x_end, 2.0 * half, h), notes, observe))
}

/// Equal displacement steps up to `dmax`, each in sub-steps of at most
/// [`SHEAR_TEST_MAX_SHEAR_INCREMENT`] of nominal shear: move the held nodes, extrapolate the
/// free ones from the last increment, solve; a failed solve is retried in halves (up to
/// [`SHEAR_TEST_MAX_HALVINGS`]), after which the test stops at the last equilibrium.
fn run_rig<L: Laws + ?Sized>(
    laws: &L,
    rig: Rig,
    dmax: f64,
    steps: usize,
    sample: (f64, f64, f64),
    notes: Vec<String>,
    observe: &mut dyn FnMut(&ShearState),
) -> ShearTest {
    let objective = NetObjective::new(rig.grid.clone(), laws, Vector::zeros());
    let cons = Constraints {
        freedom: rig.freedom.clone(),
        mode: ContactMode::None,
        tool: None,
        spacing: rig.grid.spacing,
        stitched: None,
        stick: false,
    };
    let mut settings = SolverSettings::default().max_iterations(300).tolerance(SHEAR_TEST_TOLERANCE);
    settings.force_scale = Some(shear_force_scale(laws, sample.0));
    let free: Vec<usize> = (0..rig.freedom.len()).filter(|&q| rig.freedom[q].dofs() > 0).collect();
    let mut x = rig.reference.clone();
    let mut displacement = vec![0.0];
    let mut force = vec![0.0];
    let mut solves = Vec::new();
    // The last accepted increment of the free nodes and the displacement change it came with.
    let mut last: Option<(Vec<Vector>, f64)> = None;
    let mut completed = 0;
    let mut d = 0.0;
    // The state after the last completed load step.
    let mut at_step = x.clone();
    'steps: for step in 1..=steps {
        let target = dmax * step as f64 / steps as f64;
        // Sub-steps still to do (a stack of targets, the next one last), halved on failure.
        let nominal = (target - d) * (rig.shear_rate)(target);
        let parts = (nominal / SHEAR_TEST_MAX_SHEAR_INCREMENT).ceil().clamp(1.0, 10_000.0) as usize;
        let start = d;
        let mut pending: Vec<(f64, usize)> = (1..=parts)
            .rev()
            .map(|p| (if p == parts { target } else { start + (target - start) * p as f64 / parts as f64 }, 0))
            .collect();
        while let Some((to, depth)) = pending.pop() {
            let before = x.clone();
            if let Some((inc, dd)) = &last {
                let f = (to - d) / dd;
                for (q, v) in free.iter().zip(inc) {
                    x[*q] += v * f;
                }
            }
            for &q in &rig.held {
                x[q] = (rig.place)(q, to);
            }
            let report = solve(&objective, &mut x, &cons, &settings);
            let ok = report.ok();
            solves.push(report);
            if ok {
                last = Some((free.iter().map(|&q| x[q] - before[q]).collect(), to - d));
                d = to;
            } else {
                x = before;
                if depth >= SHEAR_TEST_MAX_HALVINGS {
                    // Back to the equilibrium of the last completed load step, which the
                    // displacement and force lists end with.
                    x = at_step;
                    break 'steps;
                }
                // Retry as two halves: the first half next, then the rest.
                pending.push((to, depth + 1));
                pending.push((0.5 * (d + to), depth + 1));
            }
        }
        let f = objective.internal_forces(&x);
        let fx: f64 = rig.held.iter().map(|&q| f[q].dot(&(rig.rate)(q, d))).sum();
        displacement.push(d);
        force.push(fx);
        completed = step;
        at_step.copy_from_slice(&x);
        observe(&ShearState {
            step,
            displacement: d,
            force: fx,
            grid: &rig.grid,
            reference: &rig.reference,
            nodes: &x,
        });
    }
    ShearTest {
        grid: rig.grid,
        reference: rig.reference,
        nodes: x,
        displacement,
        force,
        requested: steps,
        completed,
        solves,
        sample,
        notes,
    }
}
