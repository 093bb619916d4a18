//! Virtual material tests on the mechanical model: the cantilever strip under its own weight
//! (seed 000 Fig. 7). Each test builds a small flat grid, holds or moves some nodes, and
//! minimises the energy in load steps.
use super::contact::{ContactMode, Freedom};
use super::energy::{Grid, Laws};
use super::refine::{NetObjective, STANDARD_GRAVITY};
use super::solver::{solve, Constraints, SolveReport, SolverSettings};
use crate::geometry::{Point, Vector};
use crate::material::Fibre;

/// Load steps of the cantilever: its weight is applied gradually (large deflection).
pub const CANTILEVER_LOAD_STEPS: usize = 20;

/// The result of a cantilever test: the strip's centre line from the clamp to the tip.
#[derive(Debug, Clone)]
pub struct Cantilever {
    pub nodes: Vec<Point>,
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
    let cons = Constraints { freedom, mode: ContactMode::None, tool: None, spacing: d };
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
