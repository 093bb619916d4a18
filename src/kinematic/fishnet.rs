//! Fishnet cell completion: every node off the generators is the point of the tool at distance d
//! from its two placed neighbours (the intersection of the tool with a circle), on the side away
//! from the diagonal node. Quadrants are filled in parallel, each in its own part of the net (in
//! place), one anti-diagonal at a time (every node of an anti-diagonal depends only on the one
//! before), so the result does not depend on the number of threads.
use super::generators::{lay_generators, Generators};
use super::net::{corner_shear, DrapeNet, Method, NodeStatus};
use super::surface::DrapeSurface;
use super::{Extent, KinematicSettings, SurfaceKind};
use crate::geometry::surface::{Circle, CircleRoot};
use crate::geometry::{Point, SmoothSurface, ToolSurface, Vector};
use rayon::prelude::*;
use std::cell::RefCell;
use std::time::Instant;

/// A root whose circle parameter is past this cosine (about 120 deg from straight ahead) would
/// fold the cell back towards its diagonal node: it is never taken.
pub const COS_FOLD: f64 = -0.5;
/// Roots this close to the diagonal node's side of the circle are the diagonal node itself
/// (cos of about 162 deg): their presence alone is not a fold.
const COS_DIAGONAL: f64 = -0.95;
/// Parents farther apart than this fraction of 2 d leave no usable circle (cell collapsed).
const MAX_PARENT_GAP: f64 = 1.0 - 1e-12;
/// Anti-diagonals shorter than this are filled on one thread (parallel overhead dominates).
const PARALLEL_DIAGONAL: usize = 256;
/// The smallest spacing, as a fraction of the tool's bounding-box diagonal. Points closer than
/// [`crate::geometry::surface::WELD_TOLERANCE_REL`] of the diagonal are one point of the tool, so a spacing
/// within a hundred of those is below what the tool resolves: such a net is a dot, and refining
/// it mechanically runs for hours (every node in contact with the same triangles).
pub const MIN_SPACING_REL: f64 = 1e-7;
/// The largest coordinate of an origin or net node, m: a thousand kilometres, beyond any part,
/// and far below where squared distances overflow (`io::net_json::MAX_NET_COORDINATE` is this).
pub const MAX_COORDINATE: f64 = 1e6;

/// Bytes of memory per node while a net is built and written: its position, triangle and status
/// (29), each cell's shear as the writer keeps it (16), and room for the rest (the quadrants fill
/// the net in place; they once kept a copy of it).
pub const BYTES_PER_NODE: usize = 2 * (24 + 4 + 1) + 8;

/// Why a drape could not start. Per-node failures are not errors: they are recorded in the net.
#[derive(Debug, thiserror::Error)]
pub enum DrapeError {
    /// The spacing is not a positive length.
    #[error("spacing must be a positive length, got {0}. Give the fibre segment length d, e.g. --spacing 0.005")]
    Spacing(f64),
    /// The spacing is far below the tool's precision.
    #[error("spacing {spacing} is below what the tool resolves: at least {min:.3e}, {rel:e} of the tool's bounding-box diagonal ({diagonal:.6}). Give the spacing in the tool's units: a fibre segment of a few mm is usual, e.g. 0.005 for a tool in m")]
    SpacingBelowTool {
        /// The spacing given.
        spacing: f64,
        /// The smallest spacing for this tool.
        min: f64,
        /// [`MIN_SPACING_REL`].
        rel: f64,
        /// The tool's bounding-box diagonal.
        diagonal: f64,
    },
    /// The origin lies beyond any part ([`MAX_COORDINATE`] from the coordinate origin).
    #[error("the origin ({x}, {y}, {z}) lies beyond {max:e} from the coordinate origin: no part is that large. Give the seed point on the tool, in the tool's units")]
    OriginFar {
        /// The seed: x,
        x: f64,
        /// y
        y: f64,
        /// and z.
        z: f64,
        /// [`MAX_COORDINATE`].
        max: f64,
    },
    /// The grid is smaller than 2 x 2.
    #[error("grid must be at least 2 x 2 nodes, got {0} x {1}")]
    GridTooSmall(usize, usize),
    /// The origin node lies outside the grid.
    #[error("origin node ({0}, {1}) is outside the {2} x {3} grid: use 0..{2} and 0..{3}")]
    OriginNode(usize, usize, usize, usize),
    /// The net would not fit in memory.
    #[error("a {nu} x {nv} net needs about {need_mb} MB but only {have_mb} MB of memory are available: use a larger spacing or a smaller grid")]
    TooLarge {
        /// Nodes along the warp.
        nu: usize,
        /// Nodes along the weft.
        nv: usize,
        /// Memory the net needs, MB.
        need_mb: u64,
        /// Memory available, MB.
        have_mb: u64,
    },
    /// The seed is farther than one spacing from the tool.
    #[error("the origin ({x}, {y}, {z}) is {distance:.4} from the tool, more than one spacing ({spacing}): give a seed point on (or within one spacing of) the tool surface, in the tool's units")]
    OriginOffTool {
        /// The seed: x,
        x: f64,
        /// y
        y: f64,
        /// and z.
        z: f64,
        /// Its distance from the tool.
        distance: f64,
        /// The spacing.
        spacing: f64,
    },
    /// The warp has no direction along the tool at the seed.
    #[error(
        "the warp direction {0:?} is normal to the tool at the origin (or zero): give a direction along the surface"
    )]
    WarpNormal([f64; 3]),
    /// The pre-shear is not between -90 and 90 degrees.
    #[error("pre-shear must lie strictly between -90 and 90 degrees, got {0} deg")]
    PreShear(f64),
    /// The shear limit is not between 0 and 90 degrees.
    #[error("the shear limit must lie strictly between 0 and 90 degrees, got {0} deg")]
    MaxShear(f64),
    /// The outline is unusable (the message says why).
    #[error("{0}")]
    Outline(String),
    /// The steering curve is unusable (the message says why).
    #[error("{0}")]
    Steering(String),
}

/// A node placed on the tool.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Placed {
    /// Where it lies.
    pub point: Point,
    /// The tool triangle it lies in.
    pub triangle: u32,
}

/// Per-thread scratch for the local root search (triangle visit stamps, stack, roots).
#[derive(Default)]
struct Scratch {
    stamps: Vec<u32>,
    stamp: u32,
    stack: Vec<u32>,
    roots: Vec<CircleRoot>,
}

impl Scratch {
    fn next_stamp(&mut self, n: usize) -> u32 {
        if self.stamps.len() < n {
            self.stamps.resize(n, 0);
        }
        self.stamp = self.stamp.wrapping_add(1);
        if self.stamp == 0 {
            self.stamps.iter_mut().for_each(|s| *s = 0);
            self.stamp = 1;
        }
        self.stamp
    }
}

thread_local! {
    static SCRATCH: RefCell<Scratch> = RefCell::new(Scratch::default());
}

/// The fishnet step. `a` is the warp parent (differs from the new node in i), `b` the weft parent
/// (differs in j), `c` the diagonal node; `si`, `sj` (+1 or -1) say in which direction i and j
/// grow from the parents to the new node. Returns the new node or why it cannot be placed.
// The step's inputs, as the fill and the min-shear generators have them: no struct to build per
// node in the hot loop.
#[allow(clippy::too_many_arguments)]
pub fn place_node<S: DrapeSurface>(
    surface: &S,
    d: f64,
    max_shear: f64,
    a: &Placed,
    b: &Placed,
    c: &Point,
    si: f64,
    sj: f64,
) -> Result<Placed, NodeStatus> {
    let ab = a.point - b.point;
    let gap = ab.norm();
    if gap >= 2.0 * d * MAX_PARENT_GAP {
        return Err(NodeStatus::ShearLimit);
    }
    let axis = ab / gap;
    let center = Point::from((a.point.coords + b.point.coords) * 0.5);
    let radius = (d * d - 0.25 * gap * gap).sqrt();
    let mc = center - c;
    let e1 = (mc - axis * axis.dot(&mc)).try_normalize(1e-14 * d).ok_or(NodeStatus::ShearLimit)?;
    let e2 = axis.cross(&e1);
    let circle = Circle { center, e1, e2, radius };
    let reach = radius.max(0.5 * gap);

    let root = circle_root(surface, &circle, reach, [a.triangle, b.triangle])?;
    let x = root.point;
    // Fold: the new cell must keep the net's orientation (warp x weft along the tool normal; the
    // facet's normal on either surface: a sign test, and the same test on both).
    let warp_x = (x - a.point) * si;
    let weft_x = (x - b.point) * sj;
    if warp_x.cross(&weft_x).dot(&surface.tool().normal(root.triangle)) <= 0.0 {
        return Err(NodeStatus::Fold);
    }
    let warp_c = (b.point - c) * si;
    let weft_c = (a.point - c) * sj;
    // |shear| > limit  <=>  |cos(angle between the fibres)| > sin(limit): no trigonometry here.
    let limit = max_shear.sin();
    let over = |w: &Vector, f: &Vector| w.dot(f).abs() > limit * (w.norm_squared() * f.norm_squared()).sqrt();
    if over(&warp_x, &weft_x) || over(&warp_c, &weft_c) {
        return Err(NodeStatus::ShearLimit);
    }
    Ok(Placed { point: x, triangle: root.triangle })
}

/// The acceptable crossing of `circle` with the surface farthest along `e1` (largest cos of the
/// circle parameter): first on the patch of facets connected to `seeds` within `reach` of the
/// circle's centre, then, if that patch has none, among all facets near the circle (BVH). A root
/// found only by the BVH whose facet faces away from the first seed's is on another sheet. The
/// crossings are found on the facets and moved onto `surface` ([`DrapeSurface::on_surface`]).
pub fn circle_root<S: DrapeSurface>(
    surface: &S,
    circle: &Circle,
    reach: f64,
    seeds: [u32; 2],
) -> Result<CircleRoot, NodeStatus> {
    let tool = surface.tool();
    SCRATCH.with(|s| {
        let s = &mut *s.borrow_mut();
        local_roots(tool, circle, reach, seeds, s);
        if let Some(r) = best_on_surface(surface, circle, &mut s.roots) {
            return Ok(r);
        }
        all_roots_near(tool, circle, reach, s);
        if let Some(r) = best_on_surface(surface, circle, &mut s.roots.clone()) {
            if tool.normal(r.triangle).dot(&tool.normal(seeds[0])) < 0.0 {
                return Err(NodeStatus::SheetJump);
            }
            return Ok(r);
        }
        // Roots between "ahead" and "back at the diagonal node" mean the fabric would fold back
        // (roots ahead that the smooth surface does not cross are no roots).
        if s.roots.iter().any(|r| r.cos_t > COS_DIAGONAL && r.cos_t < COS_FOLD) {
            Err(NodeStatus::Fold)
        } else {
            Err(NodeStatus::NoRoot)
        }
    })
}

/// The best acceptable facet root moved onto `surface`; roots the surface has no crossing near
/// are dropped and the next best tried (on the facets the first is taken as it is).
#[inline]
fn best_on_surface<S: DrapeSurface>(surface: &S, circle: &Circle, roots: &mut Vec<CircleRoot>) -> Option<CircleRoot> {
    loop {
        let k = best_root(roots)?;
        match surface.on_surface(circle, &roots[k]) {
            Some(r) if r.cos_t >= COS_FOLD => return Some(r),
            _ => {
                roots.swap_remove(k);
            }
        }
    }
}

/// The roots of `circle` on the facets connected to `seeds` that may meet the ball around the
/// circle, by flood fill over edge neighbours, into `s.roots`.
fn local_roots(tool: &ToolSurface, circle: &Circle, reach: f64, seeds: [u32; 2], s: &mut Scratch) {
    let stamp = s.next_stamp(tool.num_triangles());
    s.stack.clear();
    s.roots.clear();
    for t in seeds {
        if s.stamps[t as usize] != stamp {
            s.stamps[t as usize] = stamp;
            s.stack.push(t);
        }
    }
    while let Some(t) = s.stack.pop() {
        tool.circle_roots(t, circle, &mut s.roots);
        for n in tool.neighbours(t) {
            if n != crate::geometry::NO_NEIGHBOUR
                && s.stamps[n as usize] != stamp
                && tool.triangle_may_meet_ball(n, &circle.center, reach)
            {
                s.stamps[n as usize] = stamp;
                s.stack.push(n);
            }
        }
    }
}

/// All roots of `circle` on the facets near it (BVH query), into `s.roots`.
fn all_roots_near(tool: &ToolSurface, circle: &Circle, reach: f64, s: &mut Scratch) {
    s.roots.clear();
    for t in tool.triangles_near(&circle.center, reach) {
        tool.circle_roots(t, circle, &mut s.roots);
    }
}

/// Index of the root farthest from the diagonal node (largest cos of the circle parameter), if it
/// is ahead enough not to fold the cell. Ties are broken by triangle index so results are
/// deterministic whatever the order of the roots.
fn best_root(roots: &[CircleRoot]) -> Option<usize> {
    roots
        .iter()
        .enumerate()
        .filter(|(_, r)| r.cos_t >= COS_FOLD)
        .max_by(|(_, p), (_, q)| p.cos_t.total_cmp(&q.cos_t).then(q.triangle.cmp(&p.triangle)))
        .map(|(k, _)| k)
}

/// One quadrant of the grid seen from the origin node: i = i0 + si * a, j = j0 + sj * b.
struct Quadrant {
    si: i64,
    sj: i64,
    /// Nodes along a (warp) and b (weft), including the generator row/column at 0.
    na: usize,
    nb: usize,
}

/// One quadrant's part of the net, written in place: its rows `a = 1..na` (row `a` at index
/// `a - 1`), each the half-row of columns `b = 1..nb` (at `b - 1` when `sj > 0`, else at
/// `j0 - b`), of positions, triangles and statuses; and its generator row (`a = 0`) and column
/// (`b = 0`), copied, since neighbouring quadrants read them too.
struct QuadrantRows<'n> {
    positions: Vec<&'n mut [Point]>,
    triangles: Vec<&'n mut [u32]>,
    status: Vec<&'n mut [NodeStatus]>,
    /// Nodes (a, 0), a = 0..na.
    column0: Vec<Option<Placed>>,
    /// Nodes (0, b), b = 0..nb.
    row0: Vec<Option<Placed>>,
}

impl QuadrantRows<'_> {
    /// Index of node (a >= 1, b >= 1) in its half-row `a - 1`.
    #[inline]
    fn column(&self, q: &Quadrant, j0: usize, b: usize) -> usize {
        if q.sj > 0 {
            b - 1
        } else {
            j0 - b
        }
    }
}

/// The rows of `values` (the net's `nu x nv` node array) off the origin's row and column, cut
/// into the four quadrants' half-rows in the order of [`QUADRANTS`], rows in order of growing
/// distance from the origin's row. Disjoint borrows: the quadrants fill in parallel, in place.
fn split_quadrants<T>(values: &mut [T], nv: usize, (i0, j0): (usize, usize)) -> [Vec<&mut [T]>; 4] {
    let (above, rest) = values.split_at_mut(i0 * nv);
    let below = &mut rest[nv..];
    let mut out: [Vec<&mut [T]>; 4] = Default::default();
    // QUADRANTS: (1, 1), (-1, 1), (-1, -1), (1, -1).
    for (rows, (right, left)) in
        [(below.chunks_mut(nv).collect::<Vec<_>>(), (0, 3)), (above.chunks_mut(nv).rev().collect(), (1, 2))]
    {
        for row in rows {
            let (l, r) = row.split_at_mut(j0);
            out[right].push(&mut r[1..]);
            out[left].push(l);
        }
    }
    out
}

/// The quadrants' directions (si, sj), in the order the fill takes them.
const QUADRANTS: [(i64, i64); 4] = [(1, 1), (-1, 1), (-1, -1), (1, -1)];

/// Drape one ply on the tool with the kinematic (fishnet) method, on the surface the settings
/// name: the facets as given or the smooth surface over them ([`SurfaceKind`]).
pub fn drape(tool: &ToolSurface, settings: &KinematicSettings) -> Result<DrapeNet, DrapeError> {
    match settings.surface {
        SurfaceKind::Facets => drape_on(tool, settings),
        SurfaceKind::Smooth => {
            check_settings(settings)?;
            check_spacing_on_tool(tool, settings.spacing)?;
            let start = Instant::now();
            let smooth = SmoothSurface::new(tool);
            let build_ms = ms(start);
            let mut net = drape_smooth(&smooth, settings)?;
            net.timing.total_ms += build_ms;
            Ok(net)
        }
    }
}

/// Drape one ply on a smooth surface already built (for callers that drape several nets on
/// it), with the checks [`drape`] makes.
pub fn drape_smooth(smooth: &SmoothSurface, settings: &KinematicSettings) -> Result<DrapeNet, DrapeError> {
    check_settings(settings)?;
    check_spacing_on_tool(smooth.tool(), settings.spacing)?;
    drape_on(smooth, settings)
}

/// Drape one ply on `surface` (whatever `settings.surface` says; the net's provenance records
/// the surface used).
pub fn drape_on<S: DrapeSurface>(surface: &S, settings: &KinematicSettings) -> Result<DrapeNet, DrapeError> {
    let start = Instant::now();
    let tool = surface.tool();
    check_settings(settings)?;
    let d = settings.spacing;
    check_spacing_on_tool(tool, settings.spacing)?;
    let seed = surface.seed(&settings.origin);
    if !(seed.distance <= d) {
        let o = settings.origin;
        return Err(DrapeError::OriginOffTool { x: o.x, y: o.y, z: o.z, distance: seed.distance, spacing: d });
    }
    let outline = match &settings.extent {
        Extent::Outline(points) => Some(super::outline::Outline::new(tool, points, d)?),
        Extent::Grid { .. } => None,
    };
    let (nu, nv, (i0, j0)) = match (&settings.extent, &outline) {
        (Extent::Grid { nu, nv, origin_node }, _) => (*nu, *nv, origin_node.unwrap_or((nu / 2, nv / 2))),
        (_, Some(o)) => {
            let half = o.half_size(&seed.point, d);
            (2 * half + 1, 2 * half + 1, (half, half))
        }
        _ => unreachable!("an outline extent always builds an outline"),
    };
    if outline.is_some() {
        check_memory(nu, nv)?; // a grid was checked with the other settings
    }

    let t_gen = Instant::now();
    let generators = lay_generators(surface, settings, &seed, (nu, nv), (i0, j0))?;
    let generators_ms = ms(t_gen);

    let t_fill = Instant::now();
    let mut net = DrapeNet::new(&settings.name, d, nu, nv, (i0, j0));
    net.method = Method::Kinematic;
    write_generators(&mut net, &generators);
    let quadrants: Vec<Quadrant> = QUADRANTS
        .into_iter()
        .map(|(si, sj)| Quadrant {
            si,
            sj,
            na: if si > 0 { nu - i0 } else { i0 + 1 },
            nb: if sj > 0 { nv - j0 } else { j0 + 1 },
        })
        .collect();
    // The generator row and column of each quadrant, copied before the net is cut up.
    let axes: Vec<_> = quadrants
        .iter()
        .map(|q| -> (Vec<Option<Placed>>, Vec<Option<Placed>>) {
            let node = |a: usize, b: usize| {
                let i = (i0 as i64 + q.si * a as i64) as usize;
                let j = (j0 as i64 + q.sj * b as i64) as usize;
                let k = net.index(i, j);
                (net.status[k] == NodeStatus::Placed)
                    .then(|| Placed { point: net.positions[k], triangle: net.triangles[k] })
            };
            ((0..q.na).map(|a| node(a, 0)).collect(), (0..q.nb).map(|b| node(0, b)).collect())
        })
        .collect();
    // Each quadrant fills its own nodes of the net in place (no copy to merge afterwards).
    let [p0, p1, p2, p3] = split_quadrants(&mut net.positions, nv, (i0, j0));
    let [t0, t1, t2, t3] = split_quadrants(&mut net.triangles, nv, (i0, j0));
    let [s0, s1, s2, s3] = split_quadrants(&mut net.status, nv, (i0, j0));
    let parts: Vec<QuadrantRows> = [(p0, t0, s0), (p1, t1, s1), (p2, t2, s2), (p3, t3, s3)]
        .into_iter()
        .zip(axes)
        .map(|((positions, triangles, status), (column0, row0))| QuadrantRows {
            positions,
            triangles,
            status,
            column0,
            row0,
        })
        .collect();
    quadrants.par_iter().zip(parts).for_each(|(q, mut rows)| fill_quadrant(surface, settings, j0, q, &mut rows));
    if let Some(o) = &outline {
        o.drop_outside(&mut net);
    }
    net.timing.generators_ms = generators_ms;
    net.timing.fill_ms = ms(t_fill);
    net.timing.total_ms = ms(start);
    let (w, p) = (generators.warp_dir, seed.point);
    net.meta.warp_direction = Some([w.x, w.y, w.z]);
    net.meta.origin = Some([p.x, p.y, p.z]);
    net.meta.pre_shear_deg = Some(settings.pre_shear.to_degrees());
    net.meta.generators = Some(generators.kind.clone());
    net.meta.max_shear_deg = Some(settings.max_shear.to_degrees());
    net.meta.surface = surface.kind();
    Ok(net)
}

/// Checks of the settings that need no tool (spacing, angles, warp, grid size and memory), so a
/// caller can refuse bad input before loading a tool; [`drape`] runs them too.
pub fn check_settings(s: &KinematicSettings) -> Result<(), DrapeError> {
    if !(s.spacing.is_finite() && s.spacing > 0.0) {
        return Err(DrapeError::Spacing(s.spacing));
    }
    if !(s.pre_shear.abs() < std::f64::consts::FRAC_PI_2) {
        return Err(DrapeError::PreShear(s.pre_shear.to_degrees()));
    }
    if !(s.max_shear > 0.0 && s.max_shear < std::f64::consts::FRAC_PI_2) {
        return Err(DrapeError::MaxShear(s.max_shear.to_degrees()));
    }
    // A warp of 1e308 has an infinite norm and normalizes to zero.
    if !(s.warp.norm() > 0.0 && s.warp.norm().is_finite()) {
        return Err(DrapeError::WarpNormal([s.warp.x, s.warp.y, s.warp.z]));
    }
    // Distances to a point at 1e308 overflow: the closest-point search finds nothing (a panic
    // in parry, found by the mutation harness).
    if !s.origin.iter().all(|c| c.abs() <= MAX_COORDINATE) {
        let o = s.origin;
        return Err(DrapeError::OriginFar { x: o.x, y: o.y, z: o.z, max: MAX_COORDINATE });
    }
    if let Extent::Grid { nu, nv, origin_node } = s.extent {
        if nu < 2 || nv < 2 {
            return Err(DrapeError::GridTooSmall(nu, nv));
        }
        if let Some((i, j)) = origin_node {
            if i >= nu || j >= nv {
                return Err(DrapeError::OriginNode(i, j, nu, nv));
            }
        }
        check_memory(nu, nv)?;
    }
    Ok(())
}

/// The check of the settings against the tool: a spacing of at least [`MIN_SPACING_REL`] of the
/// tool's size. [`drape`] runs it; a run checks every ply with it before draping any, and
/// `drape refine` the net it reads.
pub fn check_spacing_on_tool(tool: &ToolSurface, spacing: f64) -> Result<(), DrapeError> {
    let (d, diagonal) = (spacing, tool.diagonal());
    let min = MIN_SPACING_REL * diagonal;
    if !(d >= min) {
        return Err(DrapeError::SpacingBelowTool { spacing: d, min, rel: MIN_SPACING_REL, diagonal });
    }
    Ok(())
}

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

/// Refuse nets that cannot fit in the memory this machine has free.
pub fn check_memory(nu: usize, nv: usize) -> Result<(), DrapeError> {
    let need = (nu as u128 * nv as u128 * BYTES_PER_NODE as u128) as f64;
    let have = available_memory_bytes().unwrap_or(u64::MAX) as f64;
    if need > 0.8 * have || nu.checked_mul(nv).is_none() {
        return Err(DrapeError::TooLarge { nu, nv, need_mb: (need / 1e6).ceil() as u64, have_mb: (have / 1e6) as u64 });
    }
    Ok(())
}

/// Memory available to new allocations (Linux /proc/meminfo), if known.
pub fn available_memory_bytes() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// Put the origin and generator nodes into the net.
fn write_generators(net: &mut DrapeNet, g: &Generators) {
    let (i0, j0) = net.origin_node;
    let k0 = net.index(i0, j0);
    net.positions[k0] = g.origin.point;
    net.triangles[k0] = g.origin.triangle;
    net.status[k0] = NodeStatus::Placed;
    let halves = [(&g.warp_pos, 1i64, 0i64), (&g.warp_neg, -1, 0), (&g.weft_pos, 0, 1), (&g.weft_neg, 0, -1)];
    for (nodes, di, dj) in halves {
        for (k, node) in nodes.iter().enumerate() {
            let step = k as i64 + 1;
            let i = (i0 as i64 + di * step) as usize;
            let j = (j0 as i64 + dj * step) as usize;
            let idx = net.index(i, j);
            match node {
                Ok(p) => {
                    net.positions[idx] = p.point;
                    net.triangles[idx] = p.triangle;
                    net.status[idx] = NodeStatus::Placed;
                }
                Err(s) => net.status[idx] = *s,
            }
        }
    }
}

/// Fill one quadrant of the net in place, anti-diagonal by anti-diagonal. A node's parents lie
/// on the two anti-diagonals before its own, so those two are kept as compact arrays (node
/// (a, k - a) of anti-diagonal k at index a): the parents are read from memory side by side,
/// not from three of the net's rows each.
fn fill_quadrant<S: DrapeSurface>(
    surface: &S,
    settings: &KinematicSettings,
    j0: usize,
    q: &Quadrant,
    rows: &mut QuadrantRows,
) {
    let (na, nb) = (q.na, q.nb);
    let (si, sj) = (q.si as f64, q.sj as f64);
    let d = settings.spacing;
    let max_shear = settings.max_shear;
    // Anti-diagonals k - 2, k - 1 and k; 0 and 1 hold generator nodes only.
    let mut before: Vec<Option<Placed>> = vec![None; na];
    let mut last: Vec<Option<Placed>> = vec![None; na];
    let mut this: Vec<Option<Placed>> = vec![None; na];
    before[0] = rows.row0[0];
    if nb > 1 {
        last[0] = rows.row0[1];
    }
    if na > 1 {
        last[1] = rows.column0[1];
    }
    let mut results: Vec<Result<Placed, NodeStatus>> = Vec::new();
    for k in 2..(na + nb - 1) {
        if k < nb {
            this[0] = rows.row0[k];
        }
        if k < na {
            this[k] = rows.column0[k];
        }
        // Nodes with a + b = k, 1 <= a < na, 1 <= b < nb: parents (a - 1, b) and (a, b - 1) on
        // anti-diagonal k - 1 at a - 1 and a, the diagonal node (a - 1, b - 1) on k - 2 at a - 1.
        let a_lo = k.saturating_sub(nb - 1).max(1);
        let a_hi = (k - 1).min(na - 1);
        if a_lo <= a_hi {
            let (last, before) = (&last, &before);
            let solve = |a: usize| -> Result<Placed, NodeStatus> {
                match (last[a - 1], last[a], before[a - 1]) {
                    (Some(pa), Some(pb), Some(pc)) => place_node(surface, d, max_shear, &pa, &pb, &pc.point, si, sj),
                    _ => Err(NodeStatus::ParentMissing),
                }
            };
            if a_hi - a_lo + 1 >= PARALLEL_DIAGONAL {
                (a_lo..a_hi + 1).into_par_iter().map(solve).collect_into_vec(&mut results);
            } else {
                results.clear();
                results.extend((a_lo..=a_hi).map(solve));
            }
            for (off, r) in results.iter().enumerate() {
                let a = a_lo + off;
                let (row, c) = (a - 1, rows.column(q, j0, k - a));
                match r {
                    Ok(p) => {
                        rows.positions[row][c] = p.point;
                        rows.triangles[row][c] = p.triangle;
                        rows.status[row][c] = NodeStatus::Placed;
                    }
                    Err(s) => rows.status[row][c] = *s,
                }
                this[a] = r.ok();
            }
        }
        // k - 1 becomes k - 2, k becomes k - 1; `this` is overwritten where anti-diagonal k + 1
        // has nodes before it is read.
        std::mem::swap(&mut before, &mut last);
        std::mem::swap(&mut last, &mut this);
    }
}

/// Mean shear (radians) of the cell with warp parent `a`, weft parent `b`, diagonal `c` and new
/// node `x`, for a quadrant growing along (`si`, `sj`).
pub fn cell_shear_of(a: &Point, b: &Point, c: &Point, x: &Point, si: f64, sj: f64) -> f64 {
    let w0: Vector = (b - c) * si; // warp edges
    let w1: Vector = (x - a) * si;
    let f0: Vector = (a - c) * sj; // weft edges
    let f1: Vector = (x - b) * sj;
    0.25 * (corner_shear(&w0, &f0) + corner_shear(&w0, &f1) + corner_shear(&w1, &f0) + corner_shear(&w1, &f1))
}
