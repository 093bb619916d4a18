//! The interactive 3D view of `index.html`: the tool and every ply as JSON embedded in the page,
//! drawn by the project's own small script (`viewer.js`, canvas 2D with depth sorting), so the
//! page works offline and fetches nothing.
use super::shade;
use crate::geometry::{Point, Vector};
use crate::kinematic::DrapeNet;
use crate::material::flow::{sheared_thickness, Cavity};
use serde_json::{json, Value};

/// The viewer's script, embedded in the page.
pub const SCRIPT: &str = include_str!("viewer.js");

/// Tools with more triangles than this are shown decimated in the 3D view ([`decimate`]): the
/// page would grow by megabytes and the canvas slow down.
pub const TOOL_TRIANGLE_LIMIT: usize = 60_000;
/// Finest clustering grid tried (cells along the tool's longest side).
const MAX_CLUSTER_GRID: usize = 1 << 12;

/// The tool as the 3D view shows it.
pub struct ViewTool {
    /// Vertices, metres.
    pub vertices: Vec<Point>,
    /// Triangles.
    pub triangles: Vec<[u32; 3]>,
    /// Triangles of the tool as read (more than `triangles` when decimated).
    pub original_triangles: usize,
}

impl ViewTool {
    /// The tool for the view: as read when it has at most `limit` triangles, else decimated.
    pub fn new(vertices: &[Point], triangles: &[[u32; 3]], limit: usize) -> ViewTool {
        let (vertices, kept) = if triangles.len() <= limit {
            (vertices.to_vec(), triangles.to_vec())
        } else {
            decimate(vertices, triangles, limit)
        };
        ViewTool { vertices, triangles: kept, original_triangles: triangles.len() }
    }

    /// Whether the view shows fewer triangles than the tool has.
    pub fn decimated(&self) -> bool {
        self.triangles.len() < self.original_triangles
    }
}

/// Vertex clustering on a grid of cubes with `n` cells along the longest side of the bounding
/// box: each vertex moves to the mean of its cube's vertices (summed in vertex order), triangles
/// whose corners fall into fewer than three cubes vanish, repeats are kept once (the first).
fn cluster(vertices: &[Point], triangles: &[[u32; 3]], lo: &Point, size: f64, n: usize) -> (Vec<Point>, Vec<[u32; 3]>) {
    let h = size / n as f64;
    let mut ids: std::collections::HashMap<[i64; 3], u32> = std::collections::HashMap::new();
    let mut sums: Vec<(Vector, usize)> = Vec::new();
    let of: Vec<u32> = vertices
        .iter()
        .map(|p| {
            let key = [0, 1, 2].map(|k| (((p[k] - lo[k]) / h).floor() as i64).clamp(0, n as i64));
            let id = *ids.entry(key).or_insert_with(|| {
                sums.push((Vector::zeros(), 0));
                (sums.len() - 1) as u32
            });
            sums[id as usize].0 += p.coords;
            sums[id as usize].1 += 1;
            id
        })
        .collect();
    let mut seen = std::collections::HashSet::new();
    let kept: Vec<[u32; 3]> = triangles
        .iter()
        .map(|t| t.map(|v| of[v as usize]))
        .filter(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2])
        .filter(|t| {
            let mut key = *t;
            key.sort_unstable();
            seen.insert(key)
        })
        .collect();
    let points = sums.iter().map(|(s, c)| Point::from(s / *c as f64)).collect();
    (points, kept)
}

/// The tool decimated to at most `limit` triangles by vertex clustering ([`cluster`]) on the
/// finest grid that keeps within the limit (bisection on the grid size); deterministic.
pub fn decimate(vertices: &[Point], triangles: &[[u32; 3]], limit: usize) -> (Vec<Point>, Vec<[u32; 3]>) {
    let mut lo = Point::from([f64::INFINITY; 3]);
    let mut hi = Point::from([f64::NEG_INFINITY; 3]);
    for v in vertices {
        lo = lo.inf(v);
        hi = hi.sup(v);
    }
    let size = (hi - lo).max();
    if !(size.is_finite() && size > 0.0) {
        return (Vec::new(), Vec::new());
    }
    // The triangle count grows with the grid (roughly as its square on a surface): bisect for
    // the finest grid within the limit.
    let (mut good, mut bad) = (1usize, MAX_CLUSTER_GRID);
    let mut best = cluster(vertices, triangles, &lo, size, good);
    while bad - good > 1 {
        let mid = (good + bad) / 2;
        let c = cluster(vertices, triangles, &lo, size, mid);
        if c.1.len() <= limit {
            (good, best) = (mid, c);
        } else {
            bad = mid;
        }
    }
    best
}

/// One ply for the viewer.
pub struct ViewerPly<'a> {
    /// Its net.
    pub net: &'a DrapeNet,
    /// Flat thickness (m), when known.
    pub thickness: Option<f64>,
    /// Flat fibre volume fraction (0-1), when the material card gives one.
    pub vf: Option<f64>,
    /// The tool's vertices (m) the ply was draped on, to tell the ply's outer side.
    pub tool_vertices: Option<&'a [Point]>,
}

/// Millimetres with 3 decimals (the page's numbers stay short).
fn mm(x: f64) -> f64 {
    (x * 1e6).round() / 1e3
}

fn rounded(x: f64, digits: i32) -> f64 {
    let k = 10f64.powi(digits);
    (x * k).round() / k
}

/// A ply's JSON: placed nodes (mm), its complete cells as quads wound so that their normal
/// points to the ply's outer side, the cells' grid indices, shear (deg), and where known the
/// sheared thickness (mm, free cavity: t0 / cos) and Vf (%, closed cavity: Vf0 / cos).
fn ply_json(p: &ViewerPly) -> Value {
    let net = p.net;
    let normals = shade::outer_normals(net, p.tool_vertices);
    let mut index = vec![u32::MAX; net.positions.len()];
    let mut v = Vec::new();
    for (k, (pos, s)) in net.positions.iter().zip(&net.status).enumerate() {
        if *s == crate::kinematic::NodeStatus::Placed {
            index[k] = (v.len() / 3) as u32;
            v.extend([mm(pos.x), mm(pos.y), mm(pos.z)]);
        }
    }
    let (mut q, mut ij, mut shear, mut t, mut vf) = (Vec::new(), Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for i in 0..net.nu.saturating_sub(1) {
        for j in 0..net.nv.saturating_sub(1) {
            let Some(g) = net.cell_shear(i, j).filter(|g| g.is_finite()) else { continue };
            let Some([p00, p10, p01, p11]) = net.cell_corners(i, j) else { continue };
            let ids = [net.index(i, j), net.index(i + 1, j), net.index(i + 1, j + 1), net.index(i, j + 1)];
            let outer: Vector = ids.iter().map(|k| normals[*k]).sum();
            let mut ring = ids.map(|k| index[k]);
            // The ring turns about warp x weft (the diagonals' cross product); outward or not.
            if (p11 - p00).cross(&(p01 - p10)).dot(&outer) < 0.0 {
                ring.reverse();
            }
            q.extend(ring);
            ij.extend([i as u32, j as u32]);
            shear.push(rounded(g.to_degrees(), 3));
            if let Some(t0) = p.thickness {
                t.push(rounded(sheared_thickness(t0, g) * 1e3, 5));
            }
            if let Some(v0) = p.vf {
                vf.push(rounded(100.0 * Cavity::Fixed.sheared(1.0, v0, g).1, 3));
            }
        }
    }
    json!({
        "name": net.name, "v": v, "q": q, "ij": ij, "shear": shear,
        "t": if p.thickness.is_some() { json!(t) } else { Value::Null },
        "vf": if p.vf.is_some() { json!(vf) } else { Value::Null },
    })
}

/// The page's data: the tool (mm; `None` when not read), the plies, the shear colour map's
/// stops and the shared colour limit (degrees).
pub fn data_json(tool: Option<&ViewTool>, plies: &[ViewerPly], shear_limit: f64) -> String {
    let tool = tool.map(|t| {
        json!({
            "v": t.vertices.iter().flat_map(|p| [mm(p.x), mm(p.y), mm(p.z)]).collect::<Vec<f64>>(),
            "t": t.triangles.iter().flatten().copied().collect::<Vec<u32>>(),
        })
    });
    let stops: Vec<Value> = super::view::DIVERGING.iter().map(|(t, c)| json!([t, c])).collect();
    let data = json!({
        "tool": tool,
        "plies": plies.iter().map(ply_json).collect::<Vec<Value>>(),
        "shearLimit": shear_limit,
        "shearStops": stops,
    });
    // Inside a <script> element "</" must not occur.
    data.to_string().replace("</", "<\\/")
}

/// The viewer's HTML: controls (with what the tool shown is, when `tool` says), the canvas, the
/// data and the script.
pub fn section(data: &str, tool: Option<&ViewTool>) -> String {
    let note = match tool {
        Some(t) if t.decimated() => format!(
            r#" <span class="small" id="drape-tool-note">(decimated for the view: {} of its {} triangles)</span>"#,
            t.triangles.len(),
            t.original_triangles
        ),
        _ => String::new(),
    };
    format!(
        r#"<h2 id="view3d">3D view</h2>
<p class="small">Drag to rotate, shift-drag (or right-drag) to pan, wheel to zoom; point at a cell to read its values.</p>
<div class="viewer-controls"><span id="drape-plies"></span>
<label><input type="checkbox" id="drape-tool" checked> tool</label>{note}
<label>colour by <select id="drape-colour"><option value="shear">shear</option><option value="thickness">thickness</option><option value="vf">Vf</option></select></label>
<button type="button" id="drape-reset">reset view</button></div>
<canvas id="drape-view" width="1000" height="620"></canvas>
<div><canvas id="drape-scale" width="420" height="34"></canvas></div>
<p id="drape-tip" class="small">Point at a cell to read its values.</p>
<script type="application/json" id="drape-data">{data}</script>
<script>
{SCRIPT}</script>
"#
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_large_tool_is_decimated_within_the_limit_and_keeps_its_shape() {
        // A 193,600-triangle hemisphere of radius 1.
        let mesh = crate::geometry::shapes::hemisphere(1.0, 220);
        assert!(mesh.triangles.len() > 3 * TOOL_TRIANGLE_LIMIT, "{}", mesh.triangles.len());
        let clock = std::time::Instant::now();
        let t = ViewTool::new(&mesh.vertices, &mesh.triangles, TOOL_TRIANGLE_LIMIT);
        eprintln!(
            "decimated {} triangles to {} in {:.0} ms",
            mesh.triangles.len(),
            t.triangles.len(),
            clock.elapsed().as_secs_f64() * 1e3
        );
        assert!(t.decimated() && t.original_triangles == mesh.triangles.len());
        // Within the limit, yet not needlessly coarse: the finest grid that fits.
        let n = t.triangles.len();
        assert!(n <= TOOL_TRIANGLE_LIMIT && n > TOOL_TRIANGLE_LIMIT / 3, "{n} triangles");
        // Every vertex is a mean of points on the sphere, within a grid cell of it.
        for p in &t.vertices {
            let r = p.coords.norm();
            assert!(r <= 1.0 + 1e-12 && r > 0.99, "radius {r}");
        }
        assert!(t.triangles.iter().flatten().all(|&v| (v as usize) < t.vertices.len()));
        // The viewer's legend says so.
        let html = section("{}", Some(&t));
        assert!(html.contains(&format!("decimated for the view: {n} of its 193600 triangles")), "{html}");
        assert!(!section("{}", None).contains("decimated"));
        // Deterministic, and a small tool is shown as read.
        let again = ViewTool::new(&mesh.vertices, &mesh.triangles, TOOL_TRIANGLE_LIMIT);
        assert_eq!((again.vertices, again.triangles), (t.vertices, t.triangles));
        let small = crate::geometry::shapes::hemisphere(1.0, 8);
        let s = ViewTool::new(&small.vertices, &small.triangles, TOOL_TRIANGLE_LIMIT);
        assert!(!s.decimated() && s.triangles == small.triangles);
    }
}
