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

/// Tools with more triangles than this are left out of the 3D view (the page would grow by
/// megabytes and the canvas slow down); the plies are still shown.
pub const TOOL_TRIANGLE_LIMIT: usize = 60_000;

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

/// The page's data: the tool (mm; `None` when not read or too large), the plies, the shear
/// colour map's stops and the shared colour limit (degrees).
pub fn data_json(tool: Option<(&[Point], &[[u32; 3]])>, plies: &[ViewerPly], shear_limit: f64) -> String {
    let tool = tool.filter(|(_, t)| t.len() <= TOOL_TRIANGLE_LIMIT).map(|(v, t)| {
        json!({
            "v": v.iter().flat_map(|p| [mm(p.x), mm(p.y), mm(p.z)]).collect::<Vec<f64>>(),
            "t": t.iter().flatten().copied().collect::<Vec<u32>>(),
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

/// The viewer's HTML: controls, the canvas, the data and the script.
pub fn section(data: &str) -> String {
    format!(
        r#"<h2 id="view3d">3D view</h2>
<p class="small">Drag to rotate, shift-drag (or right-drag) to pan, wheel to zoom; point at a cell to read its values.</p>
<div class="viewer-controls"><span id="drape-plies"></span>
<label><input type="checkbox" id="drape-tool" checked> tool</label>
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
