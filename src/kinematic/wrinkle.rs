//! Wrinkles: per cell of a draped net, how far the ply stands off the surface it was draped on
//! (the tool gap) and how much it undulates about its own smoothed surface (the waviness); a
//! cell wavier than a threshold is wrinkled where the ply undulates (the wave test: a single
//! bend is no wrinkle), and the wrinkled cells' draped area is the ply's wrinkled area. (The bending energy density beside them comes from the mechanics' bending
//! term, `mechanics::energy::bending_energy_density`, which this layer cannot call: the caller
//! hands it in.)
//!
//! **The smoothed surface.** The net's positions, smoothed over its fabric coordinates: at each
//! node, each coordinate of the placed nodes about it, weighted by a Gaussian of their distance
//! in the fabric (standard deviation σ = [`SMOOTHING_SPACINGS`] fibre spacings, cut at
//! [`WINDOW_SIGMAS`] σ), is fitted by weighted least squares with a quadric
//! `a0 + a1 a + a2 b + a3 a² + a4 a b + a5 b²` of the fabric coordinates (a, b), and `a0` is the
//! smoothed position. The node's *deviation* is its offset from its smoothed position along the
//! normal smoothed by the same Gaussian (the weighted sum of the cells' unit normals)
//! ([`node_deviations`]). The fit's weights depend only on which nodes about a node are placed,
//! so a node whose whole window is placed takes weights computed once. Being a function of the
//! fabric coordinates, the smoothed surface needs no height over a plane: a ply folded over
//! itself is smoothed as well.
//!
//! **Waviness** of a cell: √2 times the standard deviation of the nodes' deviations, weighted by
//! the same Gaussian about the cell's centre: the amplitude of the sinusoid of that spread, in
//! metres ([`cell_waviness`]). A spread, not a mean, so a deviation that is the same at every
//! node (the fit's own error on a sphere, below) is no waviness. It is read twice, and the
//! smaller reading counts:
//! - about the ply's own smoothed surface, as above;
//! - about the tool: the same smoothing and spread of the nodes' signed gaps to the surface they
//!   were draped on ([`gap_deviations`]).
//!
//! Either alone mistakes a shape for a wrinkle, the other not: the fit cannot follow a tool
//! radius of the order of σ (the double dome's 15 mm fillets at 5 mm spacing read 0.7 mm about
//! the ply's own surface), but a ply lying on its tool has no gap to undulate; and a ply that
//! hangs or bridges smoothly off the tool has gaps whose curvature jumps where the closest
//! feature of the tool changes (a table's top to its edge), but a smooth own surface. A wrinkle
//! undulates about both, and reads its amplitude in each.
//!
//! What it reads, derived for the continuous fit (the grid's weighted sums are those integrals
//! up to the window's cut, whose weight is e^(-3.5²/2) = 0.2 % of the whole):
//! - A ripple `A sin(k u)` of the ply along its normal, of wavelength λ = 2π/k, reads `A T(k)`
//!   with `T = 1 - (1 + q) e^(-q)`, `q = (k σ)² / 2`: the weighted local quadratic fit is a
//!   smoothing whose equivalent kernel has the Fourier transform `(1 + q) e^(-q)`; the weighted
//!   mean the spread removes and the sampled `sin²` change it by factors `1 ± e^(-2q)`. With
//!   σ = 2 spacings: T = 0.9985, 0.957, 0.823, 0.644, 0.350 for λ = 3, 4, 5, 6, 8 spacings: an
//!   undulation up to 4 spacings long is read in full, longer ones increasingly as the ply's
//!   shape. (The net cannot show one shorter than 2 spacings.) The same holds of a ripple of
//!   the gap to a tool.
//! - A smooth surface is fitted up to its fourth-order terms: the fit leaves `8 c σ⁴` of a term
//!   `c (a² + b²)²` and `3 c σ⁴` of `c a⁴` (the Gaussian's moments E a⁴ = 3σ⁴, E a⁶ = 15σ⁶). A
//!   fibre of arc length u round a circle of radius R falls `u²/(2R) - u⁴/(24R³)` below its
//!   tangent, so on a cylinder each node lies σ⁴/(8R³) off its smoothed position along the
//!   normal, and on a sphere (geodesic polar coordinates) σ⁴/(3R³). That is the same at every
//!   node whose window is whole, so there the own reading is ~0; where the window is cut by the
//!   ply's edge the deviations differ and it stays below √2 times the largest of them: of order
//!   √2 σ⁴/R³ near the ply's edges, 0.11 mm for R = 50 mm at 5 mm spacing. A tool whose
//!   curvature jumps (a fillet meeting a flat) within a few σ reads more there; the reading about
//!   the tool does not, where the ply lies on it.
//!
//! **The wave test** ([`cell_undulating`]). The waviness reads a single bend as wavy too: the
//! fit rounds a kink, so a ply folded by a slope jump Δ (tan θ for a fold by θ) deviates
//! `Δ σ ρ(u/σ)` at a distance u across the kink, ρ = (|s| - E|s - X|)/2 with X drawn from
//! the fit's equivalent kernel `φ(x)(3 - x²)/2`: a trough of -0.199 Δ σ at the kink, zero at
//! ±0.61 σ, overshoots of +0.041 Δ σ at ±1.19 σ, read as a waviness of up to 0.098 Δ σ
//! (continuous fit; the grid's cells, whose centres miss the kink's line, read 0.83-0.87 of it
//! at 5 and 20 deg): a 45 deg fold at 5 mm reads 1 mm, above a 0.35 mm ply. And its deviation
//! changes sign twice, as a wave's does: the fit's overshoot, not the ply's. So the test reads
//! the ply's own bends, which nothing smooths: at each node along each fibre the second
//! difference `p(-1) - 2 p + p(+1)` along the node's normal ([`node_bends`]). A **crest** is a
//! node above the smoothed surface (deviation > 0) that bends convexly by more than b (bend <
//! -b), a **trough** one below it that bends concavely by more than b; the ply **undulates**
//! about a cell when along one of the four fibres through its corners, within its window, a
//! crest lies between two troughs or a trough between two crests. A cell is wrinkled when its
//! waviness exceeds the threshold and the ply undulates there; b = [`WAVE_BEND_FRACTION`] times
//! the threshold. What it finds:
//! - **A single kink, whatever θ and the spacing: never.** A net folded along a straight line,
//!   `F(u) = A u + w max(0, u·ν)`, has the second differences `w (g(m-1) - 2 g(m) + g(m+1))`,
//!   g = max(0, s) at equally spaced s: non-negative multiples of the one vector w (the slope's
//!   jump), zero on the planes; along the node normals (which lie between the two planes') all
//!   of one sign. No node bends the other way, so there is no crest next to the kink's trough
//!   (the overshoots lie on the planes and do not bend), however wavy the cells read.
//! - **A ripple `A sin(k u)`: wherever its waviness exceeds the threshold.** Its node bends
//!   are `-4 A sin²(π d/λ) sin(k u)` (times the cosine of its slope) and its deviations
//!   `A T sin(k u)`: each node is a crest or a trough by sign. In every half-wave a node lies
//!   within π d/λ of the peak, |sin| >= cos(π d/λ), so with a reading `A T >= t` its bend
//!   exceeds b = t when `4 sin²(π d/λ) cos(π d/λ) > T`: 1.50, 1.48, 1.36, 1.34, 1.42, 1.55 times
//!   over at λ = 3, 4, 5, 6, 7, 8 spacings, growing past that, 1.12 at 2.5 spacings (it fails
//!   under 2.45 spacings, by the worst phase, where the net can hardly show a wave). Every
//!   half-wave has its crest or trough and a window holds three (a cell up to two rows past a
//!   band of ripple still sees them within its window, as the band test in `tests/wrinkles.rs`
//!   checks): the wrinkled cells are those whose reading exceeds the threshold, as before.
//! - **Spheres, cylinders, fillets: never.** Their bends along a fibre have one sign (about
//!   `-d²/R`; a cylinder's straight fibre zero up to rounding).
//! - Not counted, by design or as a limit: an S (a step from one level to another: two bends
//!   of opposite signs, one alternation); a ripple on a ply curved more than the ripple bends
//!   (its bends `4 A sin²(π d/λ)` below the base's `d²/R` plus b never change sign: the test
//!   reads the ply's own bends, not bends about a curved base). Counted: an undulation of the
//!   computed net however it arose, e.g. the staircase a clamp edge oblique to the fibres
//!   leaves on a coarse net (docs/ARCHITECTURE.md, "the wave test").
//!
//! **The threshold** ([`threshold`]): the ply's thickness ([`THICKNESS_FRACTION`] of it), else
//! [`DEFAULT_THRESHOLD_M`]. A ply that undulates about its own smoothed surface by more than its
//! thickness no longer lies within the layer it takes up when the laminate is consolidated: the
//! undulation cannot be pressed out within the ply's own thickness, so its fibres stay wavy
//! (out-of-plane fibre waviness, the wrinkle defect whose amplitude against the ply thickness
//! governs the loss of compressive strength). Without a thickness, 0.5 mm: the thickness of a
//! heavy woven or non-crimp ply, so a thinner ply is judged leniently rather than flagged
//! everywhere.
//!
//! **Tool gap** of a cell: the largest distance of its four corners from the surface the ply
//! was draped on (the tool, or the tool offset by the plies below), measured to its facets. On
//! a kinematic drape on the facets it is zero up to rounding; a ply on the smooth surface over
//! them (`surface = "smooth"`, or pressed by the mechanics) lies up to their sagitta off them; a
//! free drape that hangs off the tool has large gaps there by design.
//!
//! Cells that are not complete get no value (`None`), as their shear. Each value is a function
//! of the net alone (and of the surface), computed in parallel: the same for any thread count.
use super::net::{DrapeNet, NodeStatus};
use super::provenance::{WrinkleRecord, WrinkleSummary, WrinkleThresholdFrom};
use crate::geometry::{ToolSurface, Vector};
use nalgebra::{Matrix6, Vector6};
use rayon::prelude::*;

/// The standard deviation of the Gaussian weights of the smoothed surface and of the waviness,
/// in fibre spacings: ripples up to 4 spacings long are read in full (see the module's notes),
/// tool radii above about 10 σ read as smooth.
pub const SMOOTHING_SPACINGS: f64 = 2.0;

/// The windows end this many σ from their centre: the weight beyond is e^(-3.5²/2) = 0.2 % of
/// the whole (a Gaussian in the plane), and a window holds about 150 nodes.
pub const WINDOW_SIGMAS: f64 = 3.5;

/// The waviness threshold of a ply without a thickness, m: a heavy woven or non-crimp ply's
/// thickness (see the module's notes).
pub const DEFAULT_THRESHOLD_M: f64 = 0.5e-3;

/// The waviness threshold of a ply with a thickness, as a share of it: a ply undulating by more
/// than its thickness cannot be consolidated flat within its own layer.
pub const THICKNESS_FRACTION: f64 = 1.0;

/// A crest or a trough of the wave test bends the ply by more than this share of the waviness
/// threshold (the bend: the second difference of the positions along a fibre, along the node's
/// normal). Every half-wave of a ripple from 2.5 spacings long whose reading reaches the
/// threshold has a node bending by more (see the module's notes), and a bend this large is far
/// above rounding.
pub const WAVE_BEND_FRACTION: f64 = 1.0;

/// A weighted fit's normal equations are solved by Cholesky unless a pivot falls below this
/// share of their largest diagonal entry (nodes nearly on a line or a conic: too few to fix a
/// quadric); then by the pseudo-inverse, whose singular values below this share count as zero.
/// The fit's coordinates are in units of σ, so a well-spread window has pivots of order 1.
const SINGULAR: f64 = 1e-12;

/// The waviness above which a ply's cell is wrinkled, m, for a ply of `thickness` (m), and where
/// it comes from.
pub fn threshold(thickness: Option<f64>) -> (f64, WrinkleThresholdFrom) {
    match thickness.filter(|t| t.is_finite() && *t > 0.0) {
        Some(t) => (THICKNESS_FRACTION * t, WrinkleThresholdFrom::Thickness),
        None => (DEFAULT_THRESHOLD_M, WrinkleThresholdFrom::Default),
    }
}

/// Grid offsets (a, b) and Gaussian weights of a window about a point `shift` spacings past a
/// node in both directions: the offsets whose distance `|(a + shift, b + shift)|` is within
/// [`WINDOW_SIGMAS`] σ. Nodes about a node: shift 0; nodes about a cell's centre: -0.5.
fn window(shift: f64) -> Vec<(isize, isize, f64)> {
    let s = SMOOTHING_SPACINGS;
    let reach = s * WINDOW_SIGMAS;
    let n = reach.ceil() as isize + 1;
    let mut out = Vec::new();
    for a in -n..=n {
        for b in -n..=n {
            let r2 = (a as f64 + shift).powi(2) + (b as f64 + shift).powi(2);
            if r2 <= reach * reach {
                out.push((a, b, (-r2 / (2.0 * s * s)).exp()));
            }
        }
    }
    out
}

/// Node (i + a, j + b) of an `nu x nv` grid, if inside it.
#[inline]
fn offset(i: usize, j: usize, a: isize, b: isize, nu: usize, nv: usize) -> Option<(usize, usize)> {
    let (p, q) = (i as isize + a, j as isize + b);
    (p >= 0 && q >= 0 && (p as usize) < nu && (q as usize) < nv).then_some((p as usize, q as usize))
}

/// Each node's deviation from the ply's smoothed surface there (m, signed along the smoothed
/// normal), in node order; `None` for a node that is not a corner of a complete cell.
pub fn node_deviations(net: &DrapeNet) -> Vec<Option<f64>> {
    deviations(net, None).0
}

/// Each placed node's signed distance from `surface` (m): its distance from the closest point,
/// negative where it lies behind the facet there (against the facet's normal); `None` for a
/// node that is not placed.
pub fn node_gaps(net: &DrapeNet, surface: &ToolSurface) -> Vec<Option<f64>> {
    let triangles = surface.triangles().len();
    (0..net.positions.len())
        .into_par_iter()
        .with_min_len(1 << 8)
        .map(|k| {
            (net.status[k] == NodeStatus::Placed).then(|| {
                let p = net.positions[k];
                let hint = Some(net.triangles[k]).filter(|t| (*t as usize) < triangles);
                let foot = surface.closest_point_from(&p, hint);
                foot.distance.copysign((p - foot.point).dot(&foot.normal))
            })
        })
        .collect()
}

/// Each node's deviation of its gap to the tool (`gaps`, [`node_gaps`]) from the gaps smoothed
/// about it (m): the same smoothing as [`node_deviations`], in node order; `None` for a node
/// that is not a corner of a complete cell. Where the ply lies on its tool the gaps are nil and
/// so are these, whatever the tool's shape.
pub fn gap_deviations(net: &DrapeNet, gaps: &[Option<f64>]) -> Vec<Option<f64>> {
    deviations(net, Some(gaps)).1
}

/// The node's smoothing weights over the window `nodes_about` (its offsets and Gaussian
/// weights), for the nodes `present` there: the smoothed value at the node is the sum of the
/// weights times the nodes' values, the value at the origin of the quadric
/// `a0 + a1 a + a2 b + a3 a² + a4 a b + a5 b²` fitted to them by weighted least squares over
/// their fabric coordinates (a, b, in units of σ). From the weighted moments of the monomials up
/// to degree four (the normal equations' 15 distinct entries): weight `w φ · c`, `M c = e0`.
fn smoothing_weights(nodes_about: &[(isize, isize, f64)], present: impl Fn(usize) -> bool) -> Vec<f64> {
    let s = SMOOTHING_SPACINGS;
    let phi = |a: isize, b: isize| {
        let (x, y) = (a as f64 / s, b as f64 / s);
        [1.0, x, y, x * x, x * y, y * y]
    };
    let mut mo = [0.0f64; 15];
    for (n, &(a, b, w)) in nodes_about.iter().enumerate() {
        if !present(n) {
            continue;
        }
        let (x, y) = (a as f64 / s, b as f64 / s);
        let (wx, wy) = (w * x, w * y);
        let (wxx, wxy, wyy) = (wx * x, wx * y, wy * y);
        let terms = [
            w,
            wx,
            wy,
            wxx,
            wxy,
            wyy,
            wxx * x,
            wxx * y,
            wxy * y,
            wyy * y,
            wxx * x * x,
            wxx * x * y,
            wxx * y * y,
            wxy * y * y,
            wyy * y * y,
        ];
        for (acc, v) in mo.iter_mut().zip(terms) {
            *acc += v;
        }
    }
    // Moments by (power of a, power of b).
    let [m00, m10, m01, m20, m11, m02, m30, m21, m12, m03, m40, m31, m22, m13, m04] = mo;
    #[rustfmt::skip]
    let m = Matrix6::new(
        m00, m10, m01, m20, m11, m02,
        m10, m20, m11, m30, m21, m12,
        m01, m11, m02, m21, m12, m03,
        m20, m30, m21, m40, m31, m22,
        m11, m21, m12, m31, m22, m13,
        m02, m12, m03, m22, m13, m04,
    );
    let c = solve(m, Vector6::x());
    nodes_about
        .iter()
        .enumerate()
        .map(|(n, &(a, b, w))| if present(n) { w * Vector6::from(phi(a, b)).dot(&c) } else { 0.0 })
        .collect()
}

/// Each node's deviation from the ply's smoothed surface (m, along the smoothed normal) and,
/// with `gaps`, of its gap from the gaps smoothed alike; `None` for a node that is not a corner
/// of a complete cell (and, for the gaps, without `gaps`).
///
/// The smoothed surface: the net's positions smoothed over its fabric coordinates by the
/// Gaussian-weighted local quadratic fit ([`smoothing_weights`]); a node's deviation is its
/// offset from its smoothed position along the normal smoothed by the same Gaussian. A node
/// whose whole window is placed takes the weights of the whole window, computed once.
fn deviations(net: &DrapeNet, gaps: Option<&[Option<f64>]>) -> (Vec<Option<f64>>, Vec<Option<f64>>) {
    let (nu, nv) = (net.nu, net.nv);
    if nu < 2 || nv < 2 {
        return (vec![None; nu * nv], vec![None; nu * nv]);
    }
    if let Some(g) = gaps {
        assert_eq!(g.len(), nu * nv, "one gap per node");
    }
    let cv = nv - 1;
    let normals: Vec<Option<Vector>> = (0..net.num_cells())
        .into_par_iter()
        .with_min_len(1 << 12)
        .map(|c| net.cell_frame(c / cv, c % cv).map(|f| f.normal))
        .collect();
    let smoothed = smoothed_normals(&normals, nu, nv);
    let nodes_about = window(0.0);
    let whole = smoothing_weights(&nodes_about, |_| true);
    (0..nu * nv)
        .into_par_iter()
        .with_min_len(1 << 8)
        .map(|k| {
            let (i, j) = (k / nv, k % nv);
            let Some(c) = net.node(i, j) else { return (None, None) };
            // The node's own cells: it must be a corner of one; their normal is the fallback.
            let own = [(-1, -1), (-1, 0), (0, -1), (0, 0)]
                .into_iter()
                .filter_map(|(a, b)| offset(i, j, a, b, nu - 1, nv - 1))
                .filter_map(|(p, q)| normals[p * cv + q])
                .fold(None, |acc: Option<Vector>, n| Some(acc.unwrap_or_else(Vector::zeros) + n));
            let Some(n) = own.and_then(|own| smoothed[k].try_normalize(0.0).or_else(|| own.try_normalize(0.0))) else {
                return (None, None);
            };
            let at = |n: usize| {
                let (a, b, _) = nodes_about[n];
                offset(i, j, a, b, nu, nv).map(|(p, q)| p * nv + q).filter(|&m| net.status[m] == NodeStatus::Placed)
            };
            let partial;
            let weights = if (0..nodes_about.len()).all(|n| at(n).is_some()) {
                &whole
            } else {
                partial = smoothing_weights(&nodes_about, |n| at(n).is_some());
                &partial
            };
            let (mut position, mut gap) = (Vector::zeros(), 0.0);
            for (n, w) in weights.iter().enumerate() {
                if let Some(m) = at(n).filter(|_| *w != 0.0) {
                    position += (net.positions[m] - c) * *w;
                    if let Some(g) = gaps {
                        gap += w * g[m].unwrap_or(0.0);
                    }
                }
            }
            // The node's offset from its smoothed position: minus the smoothed offset from it.
            let own = -position.dot(&n);
            let about_tool = gaps.and_then(|g| g[k]).map(|g| g - gap);
            (Some(own), about_tool)
        })
        .unzip()
}

/// At each node, the sum of the complete cells' unit normals (`normals`, `None` where a cell is
/// not complete) weighted by the Gaussian of their centres' fabric distance from the node, out
/// to [`WINDOW_SIGMAS`] σ along each fibre: the Gaussian factors, so the sum is taken along the
/// weft and then along the warp.
fn smoothed_normals(normals: &[Option<Vector>], nu: usize, nv: usize) -> Vec<Vector> {
    let (cu, cv) = (nu - 1, nv - 1);
    let s = SMOOTHING_SPACINGS;
    let reach = s * WINDOW_SIGMAS;
    // Cells (by their lower corner) at offsets b from a node: centres at b + 1/2.
    let n = reach.ceil() as isize;
    let taps: Vec<(isize, f64)> = (-n - 1..=n)
        .map(|b| (b, (b as f64 + 0.5)))
        .filter(|(_, x)| x.abs() <= reach)
        .map(|(b, x)| (b, (-x * x / (2.0 * s * s)).exp()))
        .collect();
    let tap = |len: usize, at: usize, value: &dyn Fn(usize) -> Vector| {
        taps.iter()
            .filter_map(|&(b, w)| {
                let q = at as isize + b;
                (q >= 0 && (q as usize) < len).then(|| value(q as usize) * w)
            })
            .fold(Vector::zeros(), |acc, v| acc + v)
    };
    // Along the weft: per cell row, at each node column.
    let rows: Vec<Vector> = (0..cu * nv)
        .into_par_iter()
        .with_min_len(1 << 10)
        .map(|k| {
            let (i, j) = (k / nv, k % nv);
            tap(cv, j, &|q| normals[i * cv + q].unwrap_or_else(Vector::zeros))
        })
        .collect();
    // Along the warp: at each node.
    (0..nu * nv)
        .into_par_iter()
        .with_min_len(1 << 10)
        .map(|k| {
            let (i, j) = (k / nv, k % nv);
            tap(cu, i, &|p| rows[p * nv + j])
        })
        .collect()
}

/// The weighted least-squares coefficients from the normal equations `m a = r` (see
/// [`SINGULAR`]).
fn solve(m: Matrix6<f64>, r: Vector6<f64>) -> Vector6<f64> {
    let scale = m.diagonal().max();
    if !(scale > 0.0) {
        return Vector6::zeros();
    }
    if let Some(ch) = m.cholesky() {
        let l = ch.l_dirty();
        if (0..6).all(|k| l[(k, k)] * l[(k, k)] > SINGULAR * scale) {
            return ch.solve(&r);
        }
    }
    let svd = m.svd(true, true);
    let eps = SINGULAR * svd.singular_values.max();
    svd.solve(&r, eps).unwrap_or_else(|_| Vector6::zeros())
}

/// Each cell's waviness (m) from the nodes' deviations ([`node_deviations`]), in cell order;
/// `None` for a cell that is not complete.
pub fn cell_waviness(net: &DrapeNet, deviations: &[Option<f64>]) -> Vec<Option<f64>> {
    let (nu, nv) = (net.nu, net.nv);
    assert_eq!(deviations.len(), nu * nv, "one deviation per node");
    let cv = nv.saturating_sub(1);
    let nodes_about = window(-0.5);
    (0..net.num_cells())
        .into_par_iter()
        .with_min_len(1 << 10)
        .map(|c| {
            let (i, j) = (c / cv, c % cv);
            net.cell_corners(i, j)?;
            // One pass, the deviations taken from the cell's first corner's (a value among them,
            // so the sums do not cancel when the deviations share a large common part).
            let shift = deviations[i * nv + j]?;
            let (mut total, mut sum, mut squares) = (0.0, 0.0, 0.0);
            for &(a, b, w) in &nodes_about {
                let Some((p, q)) = offset(i, j, a, b, nu, nv) else { continue };
                if let Some(d) = deviations[p * nv + q] {
                    let e = d - shift;
                    total += w;
                    sum += w * e;
                    squares += w * e * e;
                }
            }
            let mean = sum / total;
            let var = (squares / total - mean * mean).max(0.0);
            Some((2.0 * var).sqrt())
        })
        .collect()
}

/// Each node's bend along the warp and along the weft (m): the second difference of the
/// positions along the fibre, `p(-1) - 2 p + p(+1)`, along the node's normal (the sum of its
/// complete cells' unit normals), negative where the ply turns away from its normal (convex,
/// a crest's bend), positive where it turns towards it; `None` where the node or a neighbour
/// along that fibre is not placed, or the node is not a corner of a complete cell. Of the net
/// alone: no smoothing, so a kink's bends stay at the kink.
pub fn node_bends(net: &DrapeNet) -> Vec<[Option<f64>; 2]> {
    let (nu, nv) = (net.nu, net.nv);
    if nu < 2 || nv < 2 {
        return vec![[None, None]; nu * nv];
    }
    (0..nu * nv)
        .into_par_iter()
        .with_min_len(1 << 8)
        .map(|k| {
            let (i, j) = (k / nv, k % nv);
            let Some(p) = net.node(i, j) else { return [None, None] };
            let normal = [(-1, -1), (-1, 0), (0, -1), (0, 0)]
                .into_iter()
                .filter_map(|(a, b)| offset(i, j, a, b, nu - 1, nv - 1))
                .filter_map(|(p, q)| net.cell_frame(p, q).map(|f| f.normal))
                .fold(None, |acc: Option<Vector>, n| Some(acc.unwrap_or_else(Vector::zeros) + n))
                .and_then(|n| n.try_normalize(0.0));
            let Some(n) = normal else { return [None, None] };
            let bend = |(a, b): (isize, isize)| {
                let before = offset(i, j, -a, -b, nu, nv).and_then(|(p, q)| net.node(p, q))?;
                let after = offset(i, j, a, b, nu, nv).and_then(|(p, q)| net.node(p, q))?;
                Some((before.coords - 2.0 * p.coords + after.coords).dot(&n))
            };
            [bend((1, 0)), bend((0, 1))]
        })
        .collect()
}

/// A node's part in a wave along a fibre: a crest stands above the ply's smoothed surface and
/// bends convexly, a trough stands below it and bends concavely, each by more than `bend`.
fn lobe(deviation: Option<f64>, bend: Option<f64>, least: f64) -> i8 {
    match (deviation, bend) {
        (Some(d), Some(b)) if d > 0.0 && b < -least => 1,
        (Some(d), Some(b)) if d < 0.0 && b > least => -1,
        _ => 0,
    }
}

/// The wave test of each cell, in cell order: whether the ply undulates about it, i.e. whether
/// along one of the four fibres through its corners (the warp at its two columns, the weft at
/// its two rows), within its window ([`WINDOW_SIGMAS`] σ of its centre), the nodes show a crest
/// between two troughs or a trough between two crests (a crest: deviation above the smoothed
/// surface, `deviations` ([`node_deviations`]), and a bend ([`node_bends`]) below `-least`; a
/// trough: the opposite). `None` for a cell that is not complete. See the module's notes.
pub fn cell_undulating(
    net: &DrapeNet,
    deviations: &[Option<f64>],
    bends: &[[Option<f64>; 2]],
    least: f64,
) -> Vec<Option<bool>> {
    let (nu, nv) = (net.nu, net.nv);
    assert_eq!(deviations.len(), nu * nv, "one deviation per node");
    assert_eq!(bends.len(), nu * nv, "one pair of bends per node");
    let cv = nv.saturating_sub(1);
    // The window's nodes on the four fibres through the cell's corners, in order along each:
    // the warp at the cell's columns (offsets (a, 0), (a, 1)), the weft at its rows.
    let about = window(-0.5);
    let along = |fibre: usize, at: isize| -> Vec<(isize, isize)> {
        about
            .iter()
            .filter(|&&(a, b, _)| if fibre == 0 { b == at } else { a == at })
            .map(|&(a, b, _)| (a, b))
            .collect::<Vec<_>>()
    };
    let lines: Vec<(usize, Vec<(isize, isize)>)> = [(0, 0), (0, 1), (1, 0), (1, 1)]
        .into_iter()
        .map(|(fibre, at)| {
            let mut line = along(fibre, at);
            line.sort_by_key(|&(a, b)| if fibre == 0 { a } else { b });
            (fibre, line)
        })
        .collect();
    (0..net.num_cells())
        .into_par_iter()
        .with_min_len(1 << 10)
        .map(|c| {
            let (i, j) = (c / cv, c % cv);
            net.cell_corners(i, j)?;
            let waves = lines.iter().any(|(fibre, line)| {
                // The alternations of the lobes met along the line: two make a wave.
                let (mut last, mut lobes) = (0i8, 0usize);
                for &(a, b) in line {
                    let Some((p, q)) = offset(i, j, a, b, nu, nv) else { continue };
                    let k = p * nv + q;
                    let s = lobe(deviations[k], bends[k][*fibre], least);
                    if s != 0 && s != last {
                        (last, lobes) = (s, lobes + 1);
                    }
                }
                lobes >= 3
            });
            Some(waves)
        })
        .collect()
}

/// Each cell's tool gap (m): the largest distance of its corners from the surface (`gaps`,
/// [`node_gaps`]), in cell order; `None` for a cell that is not complete.
pub fn cell_tool_gaps(net: &DrapeNet, gaps: &[Option<f64>]) -> Vec<Option<f64>> {
    assert_eq!(gaps.len(), net.nu * net.nv, "one gap per node");
    let (nv, cv) = (net.nv, net.nv.saturating_sub(1));
    (0..net.num_cells())
        .map(|c| {
            let k = (c / cv) * nv + c % cv;
            net.cell_corners(c / cv, c % cv)?;
            [k, k + 1, k + nv, k + nv + 1].into_iter().try_fold(0.0f64, |m, n| Some(m.max(gaps[n]?.abs())))
        })
        .collect()
}

/// The wrinkles of `net`, draped on `surface`, for a ply of `thickness` (m; the threshold, see
/// [`threshold`]), with each cell's bending energy density (J/m^2, in cell order) when the ply
/// has a material card.
///
/// # Panics
/// If `bending` is given with other than one entry per cell.
pub fn measure(
    net: &DrapeNet,
    surface: &ToolSurface,
    thickness: Option<f64>,
    bending: Option<Vec<Option<f64>>>,
) -> WrinkleRecord {
    let gaps = node_gaps(net, surface);
    let (own_deviations, about_tool) = deviations(net, Some(&gaps));
    let (own, about_tool) = (cell_waviness(net, &own_deviations), cell_waviness(net, &about_tool));
    // The smaller reading: an undulation the tool has, or a smooth ply's gap that the tool's
    // shape bends, is no wrinkle (see the module's notes).
    let waviness: Vec<Option<f64>> = own
        .into_iter()
        .zip(about_tool)
        .map(|(a, b)| match (a, b) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        })
        .collect();
    let tool_gap = cell_tool_gaps(net, &gaps);
    let bending = bending.unwrap_or_default();
    assert!(bending.is_empty() || bending.len() == net.num_cells(), "one bending energy density per cell");
    let (threshold_m, threshold_from) = threshold(thickness);
    // The wave test: a single bend (a kink, a fillet, a sphere) is no wrinkle however wavy it
    // reads; the ply must undulate (see the module's notes).
    let wave_bend_m = WAVE_BEND_FRACTION * threshold_m;
    let undulating = cell_undulating(net, &own_deviations, &node_bends(net), wave_bend_m);
    let largest = |v: &[Option<f64>]| v.iter().flatten().copied().reduce(f64::max);
    let mut record = WrinkleRecord {
        summary: WrinkleSummary {
            threshold_m,
            threshold_from,
            smoothing_spacings: SMOOTHING_SPACINGS,
            wave_bend_m: Some(wave_bend_m),
            wrinkled_cells: 0,
            wrinkled_area_m2: 0.0,
            max_waviness_m: largest(&waviness),
            max_tool_gap_m: largest(&tool_gap),
            max_bending_energy_density_j_m2: largest(&bending),
        },
        waviness_m: waviness,
        undulating,
        tool_gap_m: tool_gap,
        bending_energy_density_j_m2: bending,
    };
    let cv = net.nv.saturating_sub(1);
    let (mut wrinkled_cells, mut wrinkled_area_m2) = (0, 0.0);
    for c in 0..net.num_cells() {
        if record.wrinkled(c) == Some(true) {
            wrinkled_cells += 1;
            wrinkled_area_m2 += net.cell_area(c / cv, c % cv).unwrap_or(0.0);
        }
    }
    (record.summary.wrinkled_cells, record.summary.wrinkled_area_m2) = (wrinkled_cells, wrinkled_area_m2);
    record
}
