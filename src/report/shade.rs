//! Shaded 3D pictures of a ply on its tool: lit surfaces (ambient, diffuse from a point light
//! and a little specular, so a flat plate still shows a gradient and curvature reads), fibre
//! lines every k-th fibre, the ply's edge, the seed with its warp arrow, an axis triad, marks
//! where the net stopped and why; and the choice of views that together show every placed cell.
use super::raster::{Canvas, ScreenPoint, SUPERSAMPLE};
use super::view::{Fit, View};
use crate::geometry::{Point, Vector};
use crate::kinematic::{DrapeNet, NodeStatus};

/// The tool's base colour: a neutral slate grey, so the ply's colours (never grey) stand out.
pub const TOOL_BASE: [u8; 3] = [150, 154, 160];
/// Warp fibre lines.
pub const WARP_LINE: [u8; 3] = [25, 25, 70];
/// Weft fibre lines.
pub const WEFT_LINE: [u8; 3] = [95, 45, 15];
/// The ply's edge.
pub const EDGE_LINE: [u8; 3] = [20, 20, 20];
/// Cells whose normal is turned against their neighbours' (folded: wrinkle risk).
pub const FOLD_FILL: [u8; 3] = [0, 175, 175];
/// Fibre lines are drawn every k-th fibre so that neighbouring lines are about this far apart.
pub const FIBRE_GAP_PX: f64 = 12.0;
/// Cells seen this obliquely (|cos| of normal to view) or less do not count as seen.
const GRAZING_COS: f64 = 0.3;
/// At most this many views of one ply.
pub const MAX_VIEWS: usize = 4;
/// Resolution of the visibility test (samples across).
const VISIBILITY_RES: usize = 320;
/// Tool facets meeting at more than this (degrees) keep a sharp edge in the shading.
const SMOOTH_ANGLE_DEG: f64 = 35.0;
/// Lighting weights.
const AMBIENT: f64 = 0.38;
const DIFFUSE: f64 = 0.62;
const SHININESS: i32 = 24;

/// Colour of the frontier marks of each failure status.
pub fn status_colour(s: NodeStatus) -> [u8; 3] {
    match s {
        NodeStatus::Placed | NodeStatus::Pending => [255, 255, 255],
        NodeStatus::OffTool => [70, 70, 70],
        NodeStatus::NoRoot => [255, 140, 0],
        NodeStatus::ShearLimit => [190, 0, 190],
        NodeStatus::Fold => FOLD_FILL,
        NodeStatus::SheetJump => [140, 80, 0],
        NodeStatus::ParentMissing => [200, 200, 200],
        NodeStatus::OutsideOutline => [60, 150, 60],
        NodeStatus::Detached => [255, 215, 0],
    }
}

/// A tool ready to shade: scaled vertices, triangles and per-corner normals.
pub struct ToolMesh<'a> {
    /// Vertices, metres.
    pub vertices: &'a [Point],
    /// Triangles.
    pub triangles: &'a [[u32; 3]],
    /// Per triangle corner: the normal averaged over the facets at that vertex that meet this
    /// one at less than [`SMOOTH_ANGLE_DEG`] (so creases stay sharp), from [`corner_normals`].
    pub normals: &'a [[Vector; 3]],
}

/// Smooth per-corner normals of a triangle mesh (see [`ToolMesh::normals`]); facets may be
/// wound either way (lighting is two-sided).
pub fn corner_normals(vertices: &[Point], triangles: &[[u32; 3]]) -> Vec<[Vector; 3]> {
    let face: Vec<Vector> = triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|v| vertices[v as usize]);
            (b - a).cross(&(c - a))
        })
        .collect();
    let mut at: Vec<Vec<u32>> = vec![Vec::new(); vertices.len()];
    for (k, t) in triangles.iter().enumerate() {
        for &v in t {
            at[v as usize].push(k as u32);
        }
    }
    let cos = SMOOTH_ANGLE_DEG.to_radians().cos();
    triangles
        .iter()
        .enumerate()
        .map(|(k, t)| {
            let own = face[k].try_normalize(0.0).unwrap_or(Vector::z());
            t.map(|v| {
                let mut n = Vector::zeros();
                for &f in &at[v as usize] {
                    let Some(u) = face[f as usize].try_normalize(0.0) else { continue };
                    let d = u.dot(&own);
                    if d.abs() >= cos {
                        // Area-weighted, turned to agree with this facet.
                        n += face[f as usize] * d.signum();
                    }
                }
                n.try_normalize(0.0).unwrap_or(own)
            })
        })
        .collect()
}

/// How one cell is painted.
#[derive(Debug, Clone, Copy)]
pub struct CellPaint {
    /// Base colour (before lighting).
    pub colour: [u8; 3],
    /// Hatched (past the locking angle).
    pub hatch: bool,
}

/// One ply's picture contents, independent of the view.
pub struct PlyScene<'a> {
    /// The net.
    pub net: &'a DrapeNet,
    /// The tool, when it was read.
    pub tool: Option<ToolMesh<'a>>,
    /// Paint by cell index `i * (nv - 1) + j`; `None`: not drawn.
    pub cells: Vec<Option<CellPaint>>,
    /// Whether fibre lines, the seed and failure marks are drawn.
    pub fibres: bool,
    /// Placed nodes (by index) next to a node that failed, with that failure: where the net
    /// stopped (trimming at an outline is not marked).
    pub frontier: Vec<(usize, NodeStatus)>,
    /// More points each view frames besides the placed nodes (the other net of a side-by-side
    /// pair, so that both pictures show the same window).
    pub frame: Vec<Point>,
    node_normals: Vec<Vector>,
}

impl<'a> PlyScene<'a> {
    /// The scene of `net` with cell paint `cells`.
    pub fn new(net: &'a DrapeNet, tool: Option<ToolMesh<'a>>, cells: Vec<Option<CellPaint>>, fibres: bool) -> Self {
        let normals = outer_normals(net, tool.as_ref().map(|t| t.vertices));
        let frontier = frontier(net).into_iter().filter(|(_, s)| *s != NodeStatus::OutsideOutline).collect();
        PlyScene { net, tool, cells, fibres, frontier, frame: Vec::new(), node_normals: normals }
    }

    /// Node `k`'s position lifted off the tool along its outer normal by `lift` metres.
    fn lifted(&self, k: usize, lift: f64) -> Point {
        self.net.positions[k] + self.node_normals[k] * lift
    }

    /// Positions of the placed nodes.
    fn placed(&self) -> impl Iterator<Item = Point> + '_ {
        self.net.positions.iter().zip(&self.net.status).filter(|(_, s)| **s == NodeStatus::Placed).map(|(p, _)| *p)
    }

    /// Bounding-box diagonal of the placed nodes (of the tool when none is placed), metres.
    fn diagonal(&self) -> f64 {
        let pts: Vec<Point> = self.placed().collect();
        let pts =
            if pts.is_empty() { self.tool.as_ref().map(|t| t.vertices.to_vec()).unwrap_or_default() } else { pts };
        crate::geometry::surface::bounding_diagonal(&pts).max(1e-9)
    }
}

/// Unit node normals (zero where not placed) turned to the ply's outer side: away from the
/// centre of the tool's vertices, or upwards without a tool. The ply is drawn lifted off the
/// tool that way, so from the tool's far side the tool hides it.
pub fn outer_normals(net: &DrapeNet, tool_vertices: Option<&[Point]>) -> Vec<Vector> {
    let mut normals = node_normals(net);
    // The centre of the tool's vertices near the ply (a far-off part of the tool says nothing
    // about which side of the ply is outside).
    let placed_pts: Vec<Point> =
        net.positions.iter().zip(&net.status).filter(|(_, s)| **s == NodeStatus::Placed).map(|(p, _)| *p).collect();
    let (mut lo, mut hi) = (Point::from([f64::INFINITY; 3]), Point::from([f64::NEG_INFINITY; 3]));
    for p in &placed_pts {
        lo = lo.inf(p);
        hi = hi.sup(p);
    }
    let grow = 0.25 * (hi - lo).norm();
    let near = |p: &&Point| (0..3).all(|k| p[k] >= lo[k] - grow && p[k] <= hi[k] + grow);
    let centre = tool_vertices.and_then(|v| {
        let close: Vec<&Point> = v.iter().filter(near).collect();
        (!close.is_empty())
            .then(|| Point::from(close.iter().fold(Vector::zeros(), |s, p| s + p.coords) / close.len() as f64))
    });
    // Mean cosine between the normals and the directions away from the tool's centre; on a
    // flat tool that says nothing (all near zero) and up is taken as outside.
    let placed: Vec<(&Point, &Vector)> = net.positions.iter().zip(&normals).filter(|(_, n)| n.norm() > 0.0).collect();
    let away = |p: &Point, c: &Point| (p - c).try_normalize(0.0).unwrap_or(Vector::zeros());
    let mean_cos = centre
        .map_or(0.0, |c| placed.iter().map(|(p, n)| n.dot(&away(p, &c))).sum::<f64>() / placed.len().max(1) as f64);
    let outward = if mean_cos.abs() > 0.05 { mean_cos } else { placed.iter().map(|(_, n)| n.z).sum() };
    if outward < 0.0 {
        normals.iter_mut().for_each(|n| *n = -*n);
    }
    normals
}

/// A cell whose centre lies closer than this (spacings) to the centre of a cell more than one row
/// or column away lies on another part of the net: the fabric overlaps itself there. Cells of
/// one sound net come that close only past 85 deg of shear (two short diagonals of 2 d sin((90 -
/// g) / 2) each), far beyond any locking angle.
pub const OVERLAP_SPACINGS: f64 = 0.25;

/// Cells where the net folds or overlaps itself (a wrinkle risk), by cell index: a cell whose
/// normal points against the summed normals of its complete neighbours (folded back over
/// itself), or one lying on another part of the net without turning over (see
/// [`OVERLAP_SPACINGS`]: a layer doubled back twice, a net wrapped past a full turn).
pub fn folded_cells(net: &DrapeNet) -> Vec<bool> {
    let mut out = turned_cells(net);
    for (c, over) in overlapping_cells(net).into_iter().enumerate() {
        out[c] |= over;
    }
    out
}

/// Cells lying on a part of the net more than one row or column away (see
/// [`OVERLAP_SPACINGS`]), found through a hash of cell centres in buckets of the reach.
fn overlapping_cells(net: &DrapeNet) -> Vec<bool> {
    use std::collections::HashMap;
    let (cu, cv) = (net.nu.saturating_sub(1), net.nv.saturating_sub(1));
    let mut out = vec![false; cu * cv];
    let reach = OVERLAP_SPACINGS * net.spacing;
    if !(reach > 0.0) {
        return out;
    }
    let centres: Vec<Option<Point>> = (0..cu * cv)
        .map(|c| {
            net.cell_corners(c / cv, c % cv)
                .map(|q| Point::from(q.iter().fold(Vector::zeros(), |s, p| s + p.coords) / 4.0))
        })
        .collect();
    let key = |p: &Point| [(p.x / reach).floor() as i64, (p.y / reach).floor() as i64, (p.z / reach).floor() as i64];
    let mut buckets: HashMap<[i64; 3], Vec<usize>> = HashMap::new();
    for (c, p) in centres.iter().enumerate() {
        if let Some(p) = p {
            buckets.entry(key(p)).or_default().push(c);
        }
    }
    for (c, p) in centres.iter().enumerate() {
        let Some(p) = p else { continue };
        let k = key(p);
        let (i, j) = (c / cv, c % cv);
        'search: for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    let Some(list) = buckets.get(&[k[0] + dx, k[1] + dy, k[2] + dz]) else { continue };
                    for &o in list {
                        let (a, b) = (o / cv, o % cv);
                        let apart = i.abs_diff(a) > 1 || j.abs_diff(b) > 1;
                        if apart && centres[o].is_some_and(|q| (q - p).norm() < reach) {
                            out[c] = true;
                            break 'search;
                        }
                    }
                }
            }
        }
    }
    out
}

/// Cells whose normal points against the summed normals of their complete neighbours.
fn turned_cells(net: &DrapeNet) -> Vec<bool> {
    let (cu, cv) = (net.nu.saturating_sub(1), net.nv.saturating_sub(1));
    let normal =
        |i: usize, j: usize| net.cell_corners(i, j).map(|[p00, p10, p01, p11]| (p11 - p00).cross(&(p01 - p10)));
    let mut out = vec![false; cu * cv];
    for i in 0..cu {
        for j in 0..cv {
            let Some(n) = normal(i, j) else { continue };
            let mut around = Vector::zeros();
            let near = [(i.wrapping_sub(1), j), (i + 1, j), (i, j.wrapping_sub(1)), (i, j + 1)];
            for (a, b) in near.into_iter().filter(|(a, b)| *a < cu && *b < cv) {
                if let Some(m) = normal(a, b) {
                    around += m;
                }
            }
            out[i * cv + j] = around.norm() > 0.0 && n.dot(&around) < 0.0;
        }
    }
    out
}

/// Unit normal at every placed node from its grid neighbours (warp x weft), zero elsewhere.
fn node_normals(net: &DrapeNet) -> Vec<Vector> {
    let mut out = vec![Vector::zeros(); net.positions.len()];
    for i in 0..net.nu {
        for j in 0..net.nv {
            let Some(p) = net.node(i, j) else { continue };
            let at = |a: Option<usize>, b: Option<usize>| a.zip(b).and_then(|(a, b)| net.node(a, b));
            let (ip, im) = (at(Some(i + 1).filter(|x| *x < net.nu), Some(j)), at(i.checked_sub(1), Some(j)));
            let (jp, jm) = (at(Some(i), Some(j + 1).filter(|x| *x < net.nv)), at(Some(i), j.checked_sub(1)));
            let du = ip.unwrap_or(p) - im.unwrap_or(p);
            let dv = jp.unwrap_or(p) - jm.unwrap_or(p);
            out[net.index(i, j)] = du.cross(&dv).try_normalize(0.0).unwrap_or(Vector::zeros());
        }
    }
    out
}

/// The placed nodes next to a failed one (4-neighbours), with the failure; one mark per placed
/// node (the first failed neighbour in a fixed order).
fn frontier(net: &DrapeNet) -> Vec<(usize, NodeStatus)> {
    let mut out = Vec::new();
    for i in 0..net.nu {
        for j in 0..net.nv {
            if net.node(i, j).is_none() {
                continue;
            }
            let near = [(i.wrapping_sub(1), j), (i + 1, j), (i, j.wrapping_sub(1)), (i, j + 1)];
            let failed = near
                .into_iter()
                .filter(|(a, b)| *a < net.nu && *b < net.nv)
                .map(|(a, b)| net.status[net.index(a, b)])
                .find(|s| !matches!(s, NodeStatus::Placed | NodeStatus::Pending));
            if let Some(s) = failed {
                out.push((net.index(i, j), s));
            }
        }
    }
    out
}

/// Lit colour of a surface point: two-sided, ambient plus diffuse from a point light plus a
/// white specular highlight of weight `spec`.
fn lit(base: [u8; 3], n: Vector, p: Point, light: &Point, toward: &Vector, spec: f64) -> [u8; 3] {
    let mut n = n.try_normalize(0.0).unwrap_or(*toward);
    if n.dot(toward) < 0.0 {
        n = -n;
    }
    let l = (light - p).try_normalize(0.0).unwrap_or(*toward);
    let diffuse = n.dot(&l).max(0.0);
    let h = (l + toward).try_normalize(0.0).unwrap_or(n);
    let s = spec * n.dot(&h).max(0.0).powi(SHININESS) * 255.0;
    base.map(|c| (c as f64 * (AMBIENT + DIFFUSE * diffuse) + s).round().clamp(0.0, 255.0) as u8)
}

/// Text to draw over a panel, picture pixels.
#[derive(Debug, Clone)]
pub struct Label {
    /// Left.
    pub x: i32,
    /// Vertical centre.
    pub y: i32,
    /// The text.
    pub text: String,
    /// Its colour.
    pub colour: [u8; 3],
}

/// What [`render_panel`] drew besides pixels.
#[derive(Debug, Clone, Default)]
pub struct PanelOut {
    /// Labels to draw over the panel.
    pub labels: Vec<Label>,
    /// Fibre lines are every k-th fibre (0 when none are drawn).
    pub fibre_step: usize,
    /// Pixels per metre in the view plane.
    pub px_per_m: f64,
}

/// The view's screen box of the placed nodes (or the tool), padded.
fn view_bounds(scene: &PlyScene, view: &View) -> Option<[f64; 4]> {
    let mut pts: Vec<Point> = scene.placed().chain(scene.frame.iter().copied()).collect();
    if pts.is_empty() {
        pts = scene.tool.iter().flat_map(|t| t.vertices.iter().copied()).collect();
    }
    if pts.is_empty() {
        return None;
    }
    let mut b = [f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY];
    for p in &pts {
        let (x, y, _) = view.project(p);
        b = [b[0].min(x), b[1].max(x), b[2].min(y), b[3].max(y)];
    }
    let pad = 0.12 * (b[1] - b[0]).max(b[3] - b[2]).max(1e-9);
    Some([b[0] - pad, b[1] + pad, b[2] - pad, b[3] + pad])
}

/// Draw the tool and the ply's surface into `canvas` with `to_screen`; `colour` false draws depth
/// only (the visibility test).
fn draw_surfaces(
    canvas: &mut Canvas,
    scene: &PlyScene,
    view: &View,
    to_screen: &dyn Fn(&Point) -> ScreenPoint,
    light: &Point,
    lift: f64,
    colour: bool,
) {
    if let Some(t) = &scene.tool {
        for (tri, normals) in t.triangles.iter().zip(t.normals) {
            let c = tri.map(|v| t.vertices[v as usize]);
            let s = c.map(|p| to_screen(&p));
            canvas.triangle(s, |w, _, _| {
                if !colour {
                    return TOOL_BASE;
                }
                let n = normals[0] * w[0] + normals[1] * w[1] + normals[2] * w[2];
                let p = Point::from(c[0].coords * w[0] + c[1].coords * w[1] + c[2].coords * w[2]);
                lit(TOOL_BASE, n, p, light, &view.toward, 0.12)
            });
        }
    }
    let net = scene.net;
    let cv = net.nv.saturating_sub(1);
    for i in 0..net.nu.saturating_sub(1) {
        for j in 0..cv {
            let k = i * cv + j;
            let Some(paint) = scene.cells.get(k).copied().flatten() else { continue };
            if net.cell_corners(i, j).is_none() {
                continue;
            }
            let corner = |a: usize, b: usize| {
                let m = net.index(a, b);
                (scene.lifted(m, lift), scene.node_normals[m])
            };
            let corners = [corner(i, j), corner(i + 1, j), corner(i + 1, j + 1), corner(i, j + 1)];
            for tri in [[0, 1, 2], [0, 2, 3]] {
                let c = tri.map(|m| corners[m]);
                let s = c.map(|(p, _)| to_screen(&p));
                canvas.triangle(s, |w, x, y| {
                    if !colour {
                        return paint.colour;
                    }
                    let n = c[0].1 * w[0] + c[1].1 * w[1] + c[2].1 * w[2];
                    let p = Point::from(c[0].0.coords * w[0] + c[1].0.coords * w[1] + c[2].0.coords * w[2]);
                    let rgb = lit(paint.colour, n, p, light, &view.toward, 0.3);
                    // Diagonal stripes, fixed in screen space, mark cells past locking.
                    let stripe = ((x + y) / SUPERSAMPLE as f64 / 4.0).floor() as i64;
                    if paint.hatch && stripe.rem_euclid(3) == 0 {
                        rgb.map(|v| (v as f64 * 0.2) as u8)
                    } else {
                        rgb
                    }
                });
            }
        }
    }
}

/// Render `scene` as seen in `view` into the picture `img` (RGB, `stride` pixels wide) inside
/// `rect` = [left, top, width, height] pixels.
pub fn render_panel(scene: &PlyScene, view: &View, rect: [usize; 4], img: &mut [u8], stride: usize) -> PanelOut {
    let [left, top, w, h] = rect;
    let ss = SUPERSAMPLE as f64;
    let mut canvas = Canvas::new(w * SUPERSAMPLE, h * SUPERSAMPLE, [255, 255, 255]);
    let Some(bounds) = view_bounds(scene, view) else { return PanelOut::default() };
    let fit = Fit::new(bounds, 0.0, 0.0, (w * SUPERSAMPLE) as f64, (h * SUPERSAMPLE) as f64);
    let to_screen = |p: &Point| {
        let (x, y, z) = view.project(p);
        let (a, b) = fit.pixel(x, y);
        (a, b, z)
    };
    let diag = scene.diagonal();
    let centre = {
        let pts: Vec<Point> = scene.placed().collect();
        let n = pts.len().max(1) as f64;
        Point::from(pts.iter().fold(Vector::zeros(), |s, p| s + p.coords) / n)
    };
    // A point light above, left and in front of the viewer: gradients even on a flat ply.
    let light = centre + 1.1 * diag * (-0.45 * view.right + 0.65 * view.up + 0.6 * view.toward).normalize();
    // The ply is lifted off the tool, its lines off the ply; lines pass the depth test within
    // `line_bias` (they lie on the surface they are drawn on).
    let (surface_lift, line_lift, line_bias) = (0.002 * diag, 0.0035 * diag, 0.001 * diag);
    draw_surfaces(&mut canvas, scene, view, &to_screen, &light, surface_lift, true);
    let mut out = PanelOut { px_per_m: fit.scale / ss, ..Default::default() };
    let net = scene.net;
    let at = |i: usize, j: usize| {
        (i < net.nu && j < net.nv)
            .then(|| net.node(i, j))
            .flatten()
            .map(|_| to_screen(&scene.lifted(net.index(i, j), line_lift)))
    };
    let pixel_of = |q: ScreenPoint| ((left as f64 + q.0 / ss).round() as i32, (top as f64 + q.1 / ss).round() as i32);
    if scene.fibres && net.spacing > 0.0 {
        let k = (FIBRE_GAP_PX / (net.spacing * out.px_per_m)).ceil().max(1.0) as usize;
        out.fibre_step = k;
        let (i0, j0) = net.origin_node;
        let r = 0.6 * ss;
        // Warp fibres run along i (fixed j), weft fibres along j (fixed i); both through the seed.
        for j in (0..net.nv).filter(|j| (*j as i64 - j0 as i64).rem_euclid(k as i64) == 0) {
            for i in 0..net.nu.saturating_sub(1) {
                if let (Some(a), Some(b)) = (at(i, j), at(i + 1, j)) {
                    canvas.line(a, b, r, line_bias, WARP_LINE);
                }
            }
        }
        for i in (0..net.nu).filter(|i| (*i as i64 - i0 as i64).rem_euclid(k as i64) == 0) {
            for j in 0..net.nv.saturating_sub(1) {
                if let (Some(a), Some(b)) = (at(i, j), at(i, j + 1)) {
                    canvas.line(a, b, r, line_bias, WEFT_LINE);
                }
            }
        }
    }
    // The ply's edge: cell sides with no drawn cell across.
    let cv = net.nv.saturating_sub(1);
    let drawn = |i: usize, j: usize| i < net.nu.saturating_sub(1) && j < cv && scene.cells[i * cv + j].is_some();
    for i in 0..net.nu.saturating_sub(1) {
        for j in 0..cv {
            if !drawn(i, j) {
                continue;
            }
            let sides = [
                ((i, j), (i + 1, j), drawn(i, j.wrapping_sub(1))),
                ((i, j + 1), (i + 1, j + 1), drawn(i, j + 1)),
                ((i, j), (i, j + 1), drawn(i.wrapping_sub(1), j)),
                ((i + 1, j), (i + 1, j + 1), drawn(i + 1, j)),
            ];
            for (a, b, across) in sides {
                if let (false, Some(a), Some(b)) = (across, at(a.0, a.1), at(b.0, b.1)) {
                    canvas.line(a, b, 0.9 * ss, line_bias, EDGE_LINE);
                }
            }
        }
    }
    if scene.fibres {
        for (k, s) in &scene.frontier {
            let q = to_screen(&scene.lifted(*k, line_lift));
            canvas.disc(q, 3.0 * ss, line_bias, [0, 0, 0]);
            canvas.disc(q, 2.1 * ss, line_bias, status_colour(*s));
        }
        // The seed and the warp direction there: an arrow along the warp fibre through it.
        let (i0, j0) = net.origin_node;
        if let Some(s0) = at(i0, j0) {
            let mut path = vec![s0];
            let mut i = i0;
            while let Some(q) = at(i + 1, j0) {
                path.push(q);
                i += 1;
                if (q.0 - s0.0).hypot(q.1 - s0.1) > 70.0 * ss {
                    break;
                }
            }
            for w in path.windows(2) {
                canvas.line(w[0], w[1], 1.7 * ss, f64::INFINITY, [0, 0, 0]);
            }
            if let [.., a, b] = path.as_slice() {
                let (dx, dy) = (b.0 - a.0, b.1 - a.1);
                let len = dx.hypot(dy).max(1e-9);
                let (ux, uy) = (dx / len, dy / len);
                for turn in [2.6f64, -2.6] {
                    let (c, s) = (turn.cos(), turn.sin());
                    let tip = (b.0 + 12.0 * ss * (ux * c - uy * s), b.1 + 12.0 * ss * (ux * s + uy * c), b.2);
                    canvas.line(*b, tip, 1.7 * ss, f64::INFINITY, [0, 0, 0]);
                }
                let (x, y) = pixel_of(*b);
                let x = if ux >= 0.0 { x + 10 } else { x - 46 };
                out.labels.push(Label { x, y: y - 12, text: "warp".into(), colour: [0, 0, 0] });
            }
            canvas.disc(s0, 7.0 * ss, f64::INFINITY, [0, 0, 0]);
            canvas.disc(s0, 4.8 * ss, f64::INFINITY, [255, 255, 255]);
            let (x, y) = pixel_of(s0);
            out.labels.push(Label { x: x - 44, y: y - 12, text: "seed".into(), colour: [0, 0, 0] });
        }
    }
    // Axis triad in the lower-left corner.
    let origin = (42.0 * ss, (h as f64 - 42.0) * ss, 0.0);
    for (axis, colour, name) in
        [(Vector::x(), [200, 30, 30], "x"), (Vector::y(), [30, 150, 30], "y"), (Vector::z(), [30, 60, 220], "z")]
    {
        let (dx, dy) = (axis.dot(&view.right), -axis.dot(&view.up));
        let tip = (origin.0 + 28.0 * ss * dx, origin.1 + 28.0 * ss * dy, 0.0);
        canvas.line(origin, tip, 1.3 * ss, f64::INFINITY, colour);
        let lab = (origin.0 + 38.0 * ss * dx, origin.1 + 38.0 * ss * dy, 0.0);
        let (x, y) = pixel_of(lab);
        out.labels.push(Label { x: x - 4, y, text: name.into(), colour });
    }
    canvas.resolve_into(img, stride, left, top);
    out
}

/// Which complete cells `view` shows: facing it by more than a grazing angle and not hidden by
/// the tool or other cells. By cell index.
pub fn seen_cells(scene: &PlyScene, view: &View) -> Vec<bool> {
    let net = scene.net;
    let mut seen = vec![false; net.num_cells()];
    let Some(bounds) = view_bounds(scene, view) else { return seen };
    let res = VISIBILITY_RES;
    let fit = Fit::new(bounds, 0.0, 0.0, res as f64, res as f64);
    let to_screen = |p: &Point| {
        let (x, y, z) = view.project(p);
        let (a, b) = fit.pixel(x, y);
        (a, b, z)
    };
    let mut canvas = Canvas::new(res, res, [255; 3]);
    let diag = scene.diagonal();
    draw_surfaces(&mut canvas, scene, view, &to_screen, &Point::origin(), 0.002 * diag, false);
    // Within a pixel a tilted cell's depth varies by up to about a pixel times its slope.
    let eps = 0.006 * diag;
    let cv = net.nv.saturating_sub(1);
    for i in 0..net.nu.saturating_sub(1) {
        for j in 0..cv {
            let k = i * cv + j;
            if scene.cells[k].is_none() || net.cell_corners(i, j).is_none() {
                continue;
            }
            // The cell's outer side must face the view (from the far side the tool is seen).
            let ids = [net.index(i, j), net.index(i + 1, j), net.index(i, j + 1), net.index(i + 1, j + 1)];
            let n: Vector = ids.iter().map(|m| scene.node_normals[*m]).sum();
            let c: Vector = ids.iter().map(|m| scene.lifted(*m, 0.002 * diag).coords).sum::<Vector>() / 4.0;
            let (x, y, z) = to_screen(&Point::from(c));
            let facing = n.try_normalize(0.0).is_some_and(|n| n.dot(&view.toward) > GRAZING_COS);
            seen[k] = facing && z + eps >= canvas.depth_at(x, y);
        }
    }
    seen
}

/// A named candidate view direction (towards the viewer).
fn candidates() -> Vec<(Vector, String)> {
    let mut out = Vec::new();
    let side = |v: f64, pos: &str, neg: &str| if v > 0.0 { pos.to_string() } else { neg.to_string() };
    for z in [1.0, -1.0] {
        for (x, y) in [(1.0, -1.0), (-1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
            let name = format!(
                "isometric, {} {}, {}",
                side(y, "back", "front"),
                side(x, "right", "left"),
                side(z, "above", "below")
            );
            out.push((Vector::new(x, y, z), name));
        }
    }
    for (v, name) in [
        (Vector::new(0.0, -1.0, 0.0), "from the front (−y)"),
        (Vector::new(1.0, 0.0, 0.0), "from the right (+x)"),
        (Vector::new(0.0, 1.0, 0.0), "from the back (+y)"),
        (Vector::new(-1.0, 0.0, 0.0), "from the left (−x)"),
        (Vector::new(0.0, 0.0, 1.0), "from above (+z)"),
        (Vector::new(0.0, 0.0, -1.0), "from below (−z)"),
    ] {
        out.push((v, name.to_string()));
    }
    out
}

/// The views of a ply: the isometric view that shows the most cells, then (greedily) the views
/// that show the most cells not yet seen, up to [`MAX_VIEWS`]; with the share of the drawn
/// cells they show together.
pub fn choose_views(scene: &PlyScene) -> (Vec<(View, String)>, f64) {
    let all: Vec<(View, String, Vec<bool>)> = candidates()
        .into_iter()
        .map(|(v, name)| {
            let view = View::looking(v);
            let seen = seen_cells(scene, &view);
            (view, name, seen)
        })
        .collect();
    let total = scene.cells.iter().filter(|c| c.is_some()).count();
    let count = |s: &[bool], covered: &[bool]| s.iter().zip(covered).filter(|(a, b)| **a && !**b).count();
    let mut covered = vec![false; scene.cells.len()];
    let mut chosen: Vec<usize> = Vec::new();
    // The first view is an isometric one (the first eight candidates).
    let first =
        (0..8).fold(0, |best, k| if count(&all[k].2, &covered) > count(&all[best].2, &covered) { k } else { best });
    chosen.push(first);
    covered.iter_mut().zip(&all[first].2).for_each(|(c, s)| *c |= *s);
    while chosen.len() < MAX_VIEWS {
        let best = (0..all.len()).filter(|k| !chosen.contains(k)).fold(None, |best: Option<usize>, k| match best {
            Some(b) if count(&all[b].2, &covered) >= count(&all[k].2, &covered) => Some(b),
            _ => Some(k),
        });
        let Some(b) = best.filter(|b| count(&all[*b].2, &covered) > 0) else { break };
        chosen.push(b);
        covered.iter_mut().zip(&all[b].2).for_each(|(c, s)| *c |= *s);
    }
    let seen = covered.iter().filter(|c| **c).count();
    let share = if total > 0 { seen as f64 / total as f64 } else { 1.0 };
    (chosen.into_iter().map(|k| (all[k].0, all[k].1.clone())).collect(), share)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_fold_is_found_and_a_flat_net_has_none() {
        let mut net = DrapeNet::new("f", 1.0, 4, 4, (0, 0));
        for i in 0..4 {
            for j in 0..4 {
                let k = net.index(i, j);
                net.positions[k] = Point::new(i as f64, j as f64, 0.0);
                net.status[k] = NodeStatus::Placed;
            }
        }
        assert!(folded_cells(&net).iter().all(|f| !f));
        // Push node (2, 2) across the diagonal of cell (1, 1): that cell turns over.
        let k = net.index(2, 2);
        net.positions[k] = Point::new(0.6, 0.6, 0.0);
        let f = folded_cells(&net);
        assert!(f[3 + 1], "{f:?}");
    }

    #[test]
    fn a_net_lying_on_itself_without_turning_over_is_found() {
        // A 12 x 4 strip along x whose rows from i = 7 on are carried back over rows 1-4, 0.1 mm
        // above them, the same way up: no cell of those turns over, yet they overlap.
        let d = 0.01;
        let mut net = DrapeNet::new("o", d, 12, 4, (0, 0));
        for i in 0..12 {
            for j in 0..4 {
                let k = net.index(i, j);
                net.positions[k] = Point::new(i as f64 * d, j as f64 * d, 0.0);
                net.status[k] = NodeStatus::Placed;
            }
        }
        assert!(folded_cells(&net).iter().all(|f| !f), "a flat strip neither folds nor overlaps");
        for i in 7..12 {
            for j in 0..4 {
                let k = net.index(i, j);
                net.positions[k] = Point::new((i - 6) as f64 * d, j as f64 * d, 1e-4);
            }
        }
        let f = folded_cells(&net);
        let cv = 3;
        for j in 0..cv {
            for i in 7..11 {
                assert!(f[i * cv + j], "cell ({i}, {j}) lies on cell ({}, {j})", i - 6);
                assert!(f[(i - 6) * cv + j], "cell ({}, {j}) lies under cell ({i}, {j})", i - 6);
            }
            assert!(!f[j], "cell (0, {j}) lies alone");
        }
        // Away from the cell that turns back (6, next to which the turned-over test flags 5 and 7
        // too), the layer on top is found by the overlap alone.
        assert!(turned_cells(&net)[8 * cv..11 * cv].iter().all(|t| !t), "the layer on top is not turned over");
    }
}
