//! Wrinkles (issue 33 item 7): a ply's waviness about its own smoothed surface, its gap to the
//! tool, its bending energy density and its wrinkled area, against known answers on generated
//! shapes (spheres, cylinders, planes with imposed ripples) of several sizes and spacings, and
//! end to end through `drape run` (layup table, `layup.json`, the net, the VTU read by VTK's own
//! reader) and `drape report`.
//!
//! The answers, derived in `kinematic::wrinkle`'s notes with σ = `SMOOTHING_SPACINGS` d:
//! - a ripple `A sin(k u)` reads `A T(k)`, `T = 1 - (1 + q) e^(-q)`, `q = (k σ)² / 2`;
//! - a smooth surface's nodes lie off their smoothed positions by its fourth-order terms in the
//!   fabric coordinates, σ⁴(3 c40 + c22 + 3 c04) for a height `Σ c_ij u^i v^j`: σ⁴/(8R³) on a
//!   cylinder of radius R with a fibre round it, σ⁴/(3R³) on a sphere in geodesic polar
//!   coordinates; the waviness, √2 times a weighted standard deviation of those, is at most √2
//!   times their largest.
use crate::common::vtk_reader::{read_with_vtk, vtk_ready};
use crate::energy_common::{Rng, TestLaws};
use drape::geometry::{shapes, Point, TriangleMesh, Vector};
use drape::kinematic::provenance::WrinkleThresholdFrom;
use drape::kinematic::wrinkle::{
    cell_undulating, cell_waviness, gap_deviations, measure, node_bends, node_deviations, node_gaps,
    SMOOTHING_SPACINGS, WAVE_BEND_FRACTION, WINDOW_SIGMAS,
};
use drape::kinematic::{DrapeNet, NodeStatus};
use drape::material::Fibre;
use drape::mechanics::energy::{bending_energy_density, Bending, EnergyTerm, Grid, Laws, Model};
use std::f64::consts::{PI, SQRT_2};
use std::path::Path;

/// A net of `nu x nv` nodes at spacing `d`, all placed, node (i, j) at `at(u, v)` with (u, v)
/// its fabric coordinates from the centre node, m.
fn net_of(nu: usize, nv: usize, d: f64, at: impl Fn(f64, f64) -> Point) -> DrapeNet {
    let (i0, j0) = (nu / 2, nv / 2);
    let mut net = DrapeNet::new("w", d, nu, nv, (i0, j0));
    for i in 0..nu {
        for j in 0..nv {
            let k = net.index(i, j);
            net.positions[k] = at((i as f64 - i0 as f64) * d, (j as f64 - j0 as f64) * d);
            net.status[k] = NodeStatus::Placed;
        }
    }
    net
}

/// A net on the sphere of radius `r` about the origin, centred at its top: fabric point (u, v)
/// at the geodesic distance |(u, v)| from the top in the direction (u, v) (a smooth map; the
/// measure is geometric, so the net need not be a fabric's).
fn sphere_net(r: f64, d: f64, n: usize) -> DrapeNet {
    net_of(n, n, d, |u, v| {
        let (t, p) = ((u * u + v * v).sqrt() / r, v.atan2(u));
        Point::new(r * t.sin() * p.cos(), r * t.sin() * p.sin(), r * t.cos())
    })
}

/// A net on the cylinder of radius `r` about the y axis with the fibre `around` round it at
/// chord `d` (its nodes exactly on the circle) and the other along the axis.
fn cylinder_net(r: f64, d: f64, nu: usize, nv: usize, around: Fibre) -> DrapeNet {
    let step = 2.0 * (d / (2.0 * r)).asin();
    net_of(nu, nv, d, |u, v| {
        let (s, y) = match around {
            Fibre::Warp => (u, v),
            Fibre::Weft => (v, u),
        };
        let a = s / d * step;
        Point::new(r * a.sin(), y, r * a.cos())
    })
}

/// Every complete cell's waviness, each present.
fn waviness(net: &DrapeNet) -> Vec<f64> {
    let w = cell_waviness(net, &node_deviations(net));
    let cv = net.nv - 1;
    (0..w.len())
        .filter(|&c| net.cell_corners(c / cv, c % cv).is_some())
        .map(|c| w[c].expect("every complete cell has a waviness"))
        .collect()
}

/// The ripple transfer of the smoothed surface: `1 - (1 + q) e^(-q)`, `q = (k σ)² / 2`, for a
/// wavelength of `lambda` spacings.
fn transfer(lambda: f64) -> f64 {
    let q = (2.0 * PI / lambda * SMOOTHING_SPACINGS).powi(2) / 2.0;
    1.0 - (1.0 + q) * (-q).exp()
}

/// The standard normal distribution function (Abramowitz and Stegun 7.1.26 for erf, absolute
/// error below 1.5e-7: far below the margins it is compared with).
fn normal_cdf(x: f64) -> f64 {
    let z = x.abs() / SQRT_2;
    let t = 1.0 / (1.0 + 0.3275911 * z);
    let poly = t * (0.254829592 + t * (-0.284496736 + t * (1.421413741 + t * (-1.453152027 + t * 1.061405429))));
    let erf = 1.0 - poly * (-z * z).exp();
    0.5 * (1.0 + erf.copysign(x))
}

/// A flat tool under the nets of the ripple tests (z = 0, wide enough for them).
fn flat_tool(size: f64) -> drape::geometry::ToolSurface {
    shapes::plate(size, size, 8, 8).into_surface().unwrap()
}

/// A smooth sphere and cylinder read (near) zero waviness: on spheres and cylinders of several
/// radii and spacings (the radius from 5 to 40 spacings, so σ up to 0.4 R) every cell stays
/// below √2 times the fit's fourth-order error, √2 σ⁴/(3R³) (sphere, geodesic polar fabric
/// coordinates) and √2 σ⁴/(8R³) (cylinder); and nothing is wrinkled against a thickness of a
/// tenth of a spacing.
#[test]
fn smooth_spheres_and_cylinders_read_no_waviness() {
    let tool = flat_tool(10.0);
    for (r_over_d, d, n) in [(10.0, 0.004, 17), (20.0, 0.005, 31), (40.0, 0.002, 41), (13.0, 0.003, 21)] {
        let r = r_over_d * d;
        let sigma = SMOOTHING_SPACINGS * d;
        let bound = SQRT_2 * sigma.powi(4) / (3.0 * r.powi(3));
        let net = sphere_net(r, d, n);
        let w = waviness(&net);
        assert_eq!(w.len(), (n - 1) * (n - 1));
        let max = w.iter().copied().fold(0.0, f64::max);
        eprintln!("sphere R = {r_over_d} d, d = {d}: largest waviness {max:.3e} m, bound {bound:.3e} m");
        assert!(max <= bound, "sphere R = {r} m, d = {d} m: waviness {max} m over the fit's error {bound} m");
        let record = measure(&net, &tool, Some(0.1 * d), None);
        assert_eq!(record.summary.wrinkled_cells, 0);
    }
    for (r_over_d, d, nu, nv, around) in [
        (5.0, 0.004, 21, 15, Fibre::Warp),
        (10.0, 0.005, 31, 21, Fibre::Weft),
        (30.0, 0.002, 41, 31, Fibre::Warp),
        (7.0, 0.003, 25, 25, Fibre::Weft),
    ] {
        let r = r_over_d * d;
        let sigma = SMOOTHING_SPACINGS * d;
        let bound = SQRT_2 * sigma.powi(4) / (8.0 * r.powi(3));
        let net = cylinder_net(r, d, nu, nv, around);
        let max = waviness(&net).into_iter().fold(0.0, f64::max);
        eprintln!("cylinder R = {r_over_d} d, d = {d}: largest waviness {max:.3e} m, bound {bound:.3e} m");
        assert!(max <= bound, "cylinder R = {r} m, d = {d} m: waviness {max} m over the fit's error {bound} m");
    }
}

/// How far a ripple's reading may stray from `A T(k)` (relative): the weighted mean the spread
/// removes and the window's `sin²` change it by `e^(-(kσ)²)` and `e^(-2(kσ)²)` (below 1e-4 for
/// wavelengths up to 4 spacings), the window's cut at 3.5 σ leaves out 0.2 % of the weight (it
/// shifts the fit's fourth moment by some tenths of a percent), the grid's sums differ from the
/// integrals by e^(-2π²σ²/d²): 1 % holds all of it with room.
const RIPPLE_TOL: f64 = 0.01;

/// Cells this many spacings from the net's edge see whole windows: a node's fit reaches
/// `WINDOW_SIGMAS` σ and a cell's spread as far again.
fn whole_window_margin() -> usize {
    (2.0 * WINDOW_SIGMAS * SMOOTHING_SPACINGS).ceil() as usize
}

/// A ripple `A sin(k (u cos t + v sin t) + phase)` along the normal of a plane or of a cylinder
/// (radius 30 spacings) reads `A T(k)` in every cell whose windows are whole, about the ply's own
/// surface and about the tool (the plane, or the cylinder's facets) and so in the smaller of the
/// two: wavelengths of 3, 3.5 and 4 spacings, along the warp, the weft and at 30, 45 and 60 deg,
/// amplitudes from a tenth of a spacing down to 1e-4 of it. Within `RIPPLE_TOL`; about its own
/// surface on the cylinder also within the cylinder's own fit error and `A / R` (the normals the
/// ripple follows spread over the window); about the cylinder's facets also within their
/// sagitta s (the gaps hold the facets' pattern besides the ripple, a spread of at most s / 2).
#[test]
fn ripples_read_their_amplitude_times_the_smoothing_transfer() {
    let n = 45;
    let m = whole_window_margin();
    let mut rng = Rng(0x5eed_0007);
    for (lambda, angle_deg, a_over_d, d) in [
        (3.0, 0.0f64, 0.1, 0.005),
        (4.0, 90.0, 0.05, 0.004),
        (3.5, 30.0, 1e-4, 0.005),
        (4.0, 45.0, 0.02, 0.003),
        (3.0, 60.0, 0.08, 0.002),
    ] {
        let (k, t) = (2.0 * PI / (lambda * d), angle_deg.to_radians());
        let a = a_over_d * d;
        let phase = PI * rng.next();
        let ripple = |u: f64, v: f64| a * (k * (u * t.cos() + v * t.sin()) + phase).sin();
        let expected = a * transfer(lambda);
        let r = 30.0 * d;
        let (sweep, n_around) = (1.8, 2000);
        let h = r * sweep / n_around as f64;
        let sagitta = h * h / (8.0 * r);
        for base in ["plane", "cylinder"] {
            let (net, tool) = match base {
                "plane" => (net_of(n, n, d, |u, v| Point::new(u, v, ripple(u, v))), flat_tool(10.0)),
                _ => (
                    net_of(n, n, d, |u, v| {
                        let (s, rho) = (u / r, r + ripple(u, v));
                        Point::new(rho * s.sin(), v, rho * s.cos())
                    }),
                    shapes::cylinder(r, 2.0 * n as f64 * d, sweep, n_around, 4).into_surface().unwrap(),
                ),
            };
            let (tol_own, tol_tool) = match base {
                "plane" => (RIPPLE_TOL * expected, RIPPLE_TOL * expected),
                _ => {
                    let sigma = SMOOTHING_SPACINGS * d;
                    (
                        (RIPPLE_TOL + a / r) * expected + SQRT_2 * sigma.powi(4) / (8.0 * r.powi(3)),
                        RIPPLE_TOL * expected + sagitta,
                    )
                }
            };
            let own = cell_waviness(&net, &node_deviations(&net));
            let about_tool = cell_waviness(&net, &gap_deviations(&net, &node_gaps(&net, &tool)));
            let both = measure(&net, &tool, None, None).waviness_m;
            let cv = n - 1;
            let inner = |w: &[Option<f64>]| -> (f64, f64) {
                (0..w.len())
                    .filter(|c| (m..cv - m).contains(&(c / cv)) && (m..cv - m).contains(&(c % cv)))
                    .map(|c| w[c].unwrap())
                    .fold((f64::MAX, 0.0f64), |(lo, hi), v| (lo.min(v), hi.max(v)))
            };
            for (what, w, tol) in [
                ("about its own surface", &own, tol_own),
                ("about the tool", &about_tool, tol_tool),
                ("the smaller reading", &both, tol_own.max(tol_tool)),
            ] {
                let (lo, hi) = inner(w);
                eprintln!(
                    "{base}, {what}: wavelength {lambda} d, {angle_deg} deg, A {a:.2e} m: waviness / A in [{:.5}, {:.5}], T = {:.5}",
                    lo / a,
                    hi / a,
                    transfer(lambda)
                );
                assert!(
                    (lo - expected).abs() <= tol && (hi - expected).abs() <= tol,
                    "{base}, {what}, wavelength {lambda} d at {angle_deg} deg: waviness in [{lo}, {hi}] m, expected {expected} m within {tol} m"
                );
            }
        }
    }
}

/// A band of whole half-waves of a ripple across a flat net is wrinkled exactly where the
/// derivation says: a cell at signed distance s from the band's edge (s > 0 inside) sees the
/// share Φ(s/σ) of its Gaussian weight on the ripple, so it reads `A T √Φ(s/σ)` and is
/// wrinkled when that exceeds the threshold t, i.e. when `Φ(s/σ) > (t / (A T))²`. With
/// `A = √2 t / T` that is s > 0: the wrinkled cells are the band's and its wrinkled area is the
/// band's area. Larger amplitudes reach rows outside it, as many as have Φ(-s/σ) above the
/// target. The targets are chosen between the values at the cell rows (Φ at s = ∓d/2, ∓3d/2, ...:
/// 0.599 / 0.401, 0.227, 0.106), at least 0.08 from each, against an error of the half-window's
/// `sin²` of at most φ(0)/(2kσ) / 2 ≈ 0.03 (and the cells' draped area: the ripple lengthens
/// a cell by its slope's square, which the expected area takes from the net). Also the tool gap
/// of every cell is the largest |ripple| at its corners above the flat tool.
#[test]
fn a_rippled_band_is_wrinkled_over_exactly_its_predicted_area() {
    // Nodes along the rippled fibre and across it.
    let (along, across) = (61, 21);
    let tool = flat_tool(10.0);
    for (lambda, half_waves, start, d, thickness, along_weft) in [
        (4.0, 8usize, 22usize, 0.005, 0.5e-3, false),
        (3.0, 10, 17, 0.004, 0.3e-3, true),
        (4.0, 9, 21, 0.003, 0.2e-3, false),
    ] {
        let k = 2.0 * PI / (lambda * d);
        let band = (half_waves as f64 * lambda / 2.0).round() as usize; // cell rows
        for (target, extra_rows) in [(0.5, 0usize), (0.31, 1), (0.16, 2)] {
            // The rows the derivation puts past each edge: Φ(-(r + 1/2) d / σ) > target.
            let predicted = (0..5).filter(|r| normal_cdf(-(*r as f64 + 0.5) / SMOOTHING_SPACINGS) > target).count();
            assert_eq!(predicted, extra_rows);
            let a = thickness / (transfer(lambda) * f64::sqrt(target));
            let (lo, hi) = (start as f64 * d, (start + band) as f64 * d);
            let z = |s: f64| if (lo..=hi).contains(&s) { a * (k * (s - lo)).sin() } else { 0.0 };
            // s: the fabric coordinate from the net's first node along the rippled fibre.
            let offset = (along / 2) as f64 * d;
            let net = if along_weft {
                net_of(across, along, d, |u, v| Point::new(u, v, z(v + offset)))
            } else {
                net_of(along, across, d, |u, v| Point::new(u, v, z(u + offset)))
            };
            let record = measure(&net, &tool, Some(thickness), None);
            assert_eq!(record.summary.threshold_from, WrinkleThresholdFrom::Thickness);
            assert_eq!(record.summary.threshold_m, thickness);
            let cv = net.nv - 1;
            let row_of = |c: usize| if along_weft { c % cv } else { c / cv };
            let wrinkled = |c: usize| record.waviness_m[c].unwrap() > thickness;
            let rows = (start - extra_rows)..(start + band + extra_rows);
            let mut expected_area = 0.0;
            for c in 0..net.num_cells() {
                assert_eq!(
                    wrinkled(c),
                    rows.contains(&row_of(c)),
                    "wavelength {lambda} d, target {target}: cell {c} (row {}) reads {} m against {thickness} m",
                    row_of(c),
                    record.waviness_m[c].unwrap()
                );
                if rows.contains(&row_of(c)) {
                    expected_area += net.cell_area(c / cv, c % cv).unwrap();
                }
                // Tool gap: the largest |z| of the corners above the plane z = 0.
                let (i, j) = (c / cv, c % cv);
                let gap = net.cell_corners(i, j).unwrap().iter().map(|p| p.z.abs()).fold(0.0, f64::max);
                assert!((record.tool_gap_m[c].unwrap() - gap).abs() <= 1e-12, "cell {c}");
            }
            let band_cells = (band + 2 * extra_rows) * (across - 1);
            assert_eq!(record.summary.wrinkled_cells, band_cells);
            assert!((record.summary.wrinkled_area_m2 - expected_area).abs() <= 1e-12 * expected_area);
            // The draped area is the fabric's band lengthened by the ripple's slope, within
            // (k A)² / 4 on average.
            let flat = band_cells as f64 * d * d;
            assert!(
                record.summary.wrinkled_area_m2 >= flat * (1.0 - 1e-12)
                    && record.summary.wrinkled_area_m2 <= flat * (1.0 + (k * a).powi(2) / 2.0),
                "{} m^2 against the band's {flat} m^2",
                record.summary.wrinkled_area_m2
            );
        }
    }
}

/// A cylinder of radius R bent along one fibre has the bending law's energy density
/// `D / 2 · (1/R)²` of that fibre's rigidity D in every cell whose corners all have a triple
/// along it (each node on the circle at chord d bows by exactly d²/(2R), so the discrete
/// curvature 2|w|/d² is exactly 1/R): to rounding, on several radii and spacings, bent along the
/// warp and along the weft; the straight fibre adds nothing. The cells' energies add up to the
/// bending term's energy, also on perturbed nets with holes.
#[test]
fn a_cylinder_bent_along_a_fibre_has_the_bending_laws_energy_density() {
    let laws = TestLaws::default();
    for (r, d, around) in [(0.05, 0.002, Fibre::Warp), (0.2, 0.005, Fibre::Weft), (0.013, 0.001, Fibre::Warp)] {
        let (nu, nv) = (15, 11);
        let net = cylinder_net(r, d, nu, nv, around);
        let density = bending_energy_density(&net, &laws, None).unwrap();
        let expected = laws.bending(around) / (2.0 * r * r);
        let cv = nv - 1;
        let mut checked = 0;
        for (c, e) in density.iter().enumerate() {
            let (i, j) = (c / cv, c % cv);
            // The bent line's index and length across the net.
            let (s, len) = match around {
                Fibre::Warp => (i, nu),
                Fibre::Weft => (j, nv),
            };
            // Both its corners along the bent line have a triple: 1 <= s and s + 1 <= len - 2.
            if (1..len - 2).contains(&s) {
                let e = e.expect("complete cell");
                assert!(
                    (e - expected).abs() <= 1e-9 * expected,
                    "R {r}, d {d}: cell ({i}, {j}) {e} J/m^2, expected {expected}"
                );
                checked += 1;
            }
        }
        assert!(checked > 0);
    }
    // The shares add up to the term's energy: perturbed nets, some nodes not placed.
    let mut rng = Rng(0xbe2d);
    for (nu, nv, holes) in [(9, 7, 0usize), (12, 10, 6), (7, 13, 3)] {
        let d = 0.004;
        let mut net = net_of(nu, nv, d, |u, v| Point::new(u, v, 0.0));
        for p in net.positions.iter_mut() {
            *p += Vector::new(rng.next(), rng.next(), rng.next()) * 0.3 * d;
        }
        for _ in 0..holes {
            let k = ((rng.next() + 1.0) / 2.0 * (nu * nv) as f64) as usize % (nu * nv);
            net.status[k] = NodeStatus::NoRoot;
        }
        let density = bending_energy_density(&net, &laws, None).unwrap();
        let total: f64 = density.iter().flatten().sum::<f64>() * d * d;
        let grid = Grid::from_net(&net);
        let term: Vec<Box<dyn EnergyTerm>> = vec![Box::new(Bending::new(&laws))];
        let energy = Model::with_terms(grid.clone(), term).energy(&net.positions);
        assert!((total - energy).abs() <= 1e-12 * energy, "{total} against the term's {energy}");
        let cv = nv - 1;
        for (c, e) in density.iter().enumerate() {
            assert_eq!(e.is_some(), grid.cell_active(c / cv, c % cv), "cell {c}");
        }
    }
}

use crate::common::read_json;

fn repo(rel: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)
}

/// Run `scene` with `tool` written beside it as `tool.obj`; the output folder and the command's
/// output.
fn drape_run(dir: &Path, tool: &TriangleMesh, scene: &str) -> (std::path::PathBuf, String) {
    crate::common::run_scene(dir, &[("tool.obj", tool)], scene)
}

/// The largest distance of a facet's centroid inside the sphere of radius `r` about the origin:
/// how far the facets lie inside the sphere.
fn facet_sagitta(mesh: &TriangleMesh, r: f64) -> f64 {
    mesh.triangles
        .iter()
        .map(|t| r - (t.iter().fold(Vector::zeros(), |acc, v| acc + mesh.vertices[*v as usize].coords) / 3.0).norm())
        .fold(0.0, f64::max)
}

/// The placed nodes of a `.drape.json`.
fn nodes(net: &serde_json::Value) -> Vec<Point> {
    net["nodes"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|p| !p.is_null())
        .map(|p| Point::new(p[0].as_f64().unwrap(), p[1].as_f64().unwrap(), p[2].as_f64().unwrap()))
        .collect()
}

/// A per-cell list of the net's `meta.wrinkles`.
fn cell_list(net: &serde_json::Value, key: &str) -> Vec<Option<f64>> {
    net["meta"]["wrinkles"][key].as_array().unwrap().iter().map(|v| v.as_f64()).collect()
}

/// The glass card's bending rigidity (N m, both fibres) and thickness (m).
const GLASS_BENDING: f64 = 2.0e-4;
const GLASS_THICKNESS: f64 = 5.5e-4;

/// How far a node's bow may be from the exact d²/(2R) when the nodes lie up to `e` off the exact
/// shape (the bow is a second difference: off by up to 2e), as a share of the energy density
/// (the square of the bow: twice the share of the bow, and its square).
fn bow_share(e: f64, d: f64, r: f64) -> f64 {
    let s = 2.0 * e / (d * d / (2.0 * r));
    2.0 * s + s * s
}

/// `drape run` on generated hemispheres (a smooth doubly curved ply, on the smooth surface over
/// the facets): no wrinkled cell, every waviness below √2 σ⁴/R³ plus twice the largest distance
/// e of a node from the exact sphere (the spread of offsets within ±e; the fabric coordinates of
/// a Chebyshev net are not geodesic polar ones, whose σ⁴/(3R³) its fourth-order terms change by
/// its shear's growth, ω ≈ -u v / R² (Hazzidakis): the bound allows three times that), no gap to
/// the tool but
/// the facets' sagitta (the gap is measured to the facets, which the smooth surface bulges
/// past); the bending energy density at the pole is the two fibres' D/(2R²) within the share of
/// the bow e moves ([`bow_share`]) and the fibres' geodesic curvature there (of order d/R²
/// against the normal curvature 1/R: (d/R)² of the density). The table, the printed run table
/// and the net agree.
#[test]
fn drape_run_on_hemispheres_finds_no_wrinkles() {
    let card = repo("materials/glass-plain-weave.toml");
    for (r, d, n, triangles) in [(0.1, 0.005, 31, 20_000), (0.06, 0.003, 29, 8_000)] {
        let tmp = tempfile::tempdir().unwrap();
        let mesh = shapes::hemisphere_with_triangles(r, triangles);
        let scene = format!(
            "units = \"m\"\ntool = \"tool.obj\"\n[materials]\nglass = \"{}\"\n[[ply]]\nname = \"p\"\norigin = [0.0, 0.0, {r}]\nwarp = [1.0, 0.0, 0.0]\nmaterial = \"glass\"\nspacing = {d}\ngrid = [{n}, {n}]\nsurface = \"smooth\"\n",
            card.display()
        );
        let (out, stdout) = drape_run(tmp.path(), &mesh, &scene);
        assert!(stdout.contains("wrinkled") && stdout.contains("wrinkles: ply 'p': 0 cells"), "{stdout}");
        let w = &read_json(&out.join("layup.json"))["plies"][0]["wrinkles"];
        assert_eq!(w["wrinkled_cells"], 0, "{w}");
        assert_eq!(w["wrinkled_area_m2"], 0.0);
        assert_eq!(w["threshold_from"], "thickness");
        assert_eq!(w["threshold_m"], GLASS_THICKNESS);
        let net = read_json(&out.join("p.drape.json"));
        let e = nodes(&net).iter().map(|p| (p.coords.norm() - r).abs()).fold(0.0, f64::max);
        let sigma = SMOOTHING_SPACINGS * d;
        let bound = SQRT_2 * sigma.powi(4) / r.powi(3) + 2.0 * e;
        let max = w["max_waviness_m"].as_f64().unwrap();
        eprintln!("hemisphere R {r}, d {d}: largest waviness {max:.3e} m, bound {bound:.3e} m (nodes within {e:.2e} m of the sphere)");
        assert!(max <= bound, "R {r}: waviness {max} m over {bound} m");
        // The gap is measured to the facets, which the smooth surface bulges past by up to their
        // sagitta (and the nodes lie within e of the sphere).
        let gap = w["max_tool_gap_m"].as_f64().unwrap();
        assert!(gap <= facet_sagitta(&mesh, r) + e, "{w}");
        for key in ["wrinkled_cells", "wrinkled_area_m2", "max_waviness_m", "threshold_m"] {
            assert_eq!(net["meta"]["wrinkles"][key], w[key], "{key}");
        }
        // The origin node's cell: both fibres bent at 1/R.
        let expected = 2.0 * GLASS_BENDING / (2.0 * r * r);
        let tol = (bow_share(e, d, r) + (d / r).powi(2)) * expected;
        let cv = n - 1;
        let density = cell_list(&net, "bending_energy_density_j_m2")[(n / 2) * cv + n / 2].unwrap();
        eprintln!(
            "  bending energy density at the pole {density:.6e} J/m^2, D/R^2 = {expected:.6e} (within {tol:.1e})"
        );
        assert!(
            (density - expected).abs() <= tol,
            "R {r}: {density} J/m^2 at the pole, expected {expected} within {tol}"
        );
    }
}

/// End to end on a generated cylinder with a ply bent along its warp (on the smooth surface):
/// `layup.json`, the net, the VTU (read back by VTK's own reader: the cell arrays, value for
/// value in the order of the complete cells) and the report (the wrinkle map beside the shear
/// map, the table's column). The bending density of the cells away from the warp's ends is
/// D_warp/(2R²) within the share of the bow the nodes' distance e from the exact cylinder moves
/// ([`bow_share`]); the weft runs straight along the axis and adds nothing; no cell is wrinkled.
#[test]
fn drape_run_writes_wrinkles_to_the_table_the_net_the_vtu_and_the_report() {
    let tmp = tempfile::tempdir().unwrap();
    let (r, d, n) = (0.08, 0.004, 25);
    let mesh = shapes::cylinder(r, 0.2, 2.4, 120, 40);
    let card = repo("materials/glass-plain-weave.toml");
    let scene = format!(
        "units = \"m\"\ntool = \"tool.obj\"\n[materials]\nglass = \"{}\"\n[[ply]]\nname = \"c\"\norigin = [0.0, 0.0, {r}]\nwarp = [1.0, 0.0, 0.0]\nmaterial = \"glass\"\nspacing = {d}\ngrid = [{n}, {n}]\nsurface = \"smooth\"\n",
        card.display()
    );
    let (out, _) = drape_run(tmp.path(), &mesh, &scene);
    let net = read_json(&out.join("c.drape.json"));
    assert_eq!(net["meta"]["wrinkles"]["wrinkled_cells"], 0);
    let (waviness, gap, bending) =
        (cell_list(&net, "waviness_m"), cell_list(&net, "tool_gap_m"), cell_list(&net, "bending_energy_density_j_m2"));
    let cv = n - 1;
    assert_eq!(waviness.len(), cv * cv);
    let e = nodes(&net).iter().map(|p| (p.x.hypot(p.z) - r).abs()).fold(0.0, f64::max);
    let expected = GLASS_BENDING / (2.0 * r * r);
    let tol = bow_share(e, d, r) * expected;
    let mut checked = 0;
    for i in 1..cv - 1 {
        for j in 0..cv {
            if let Some(density) = bending[i * cv + j] {
                assert!(
                    (density - expected).abs() <= tol,
                    "cell ({i}, {j}): {density} J/m^2, expected {expected} within {tol} (nodes within {e:.2e} m of the cylinder)"
                );
                checked += 1;
            }
        }
    }
    assert!(checked > 100, "{checked} cells");
    let table = read_json(&out.join("layup.json"));
    assert_eq!(table["plies"][0]["wrinkles"]["wrinkled_area_m2"], 0.0);
    if vtk_ready() {
        let vtk = read_with_vtk(&out.join("c.vtu"));
        let complete: Vec<usize> = (0..cv * cv).filter(|&c| waviness[c].is_some()).collect();
        assert_eq!(vtk.summary["cells"], complete.len());
        for (name, values) in
            [("waviness_m", &waviness), ("tool_gap_m", &gap), ("bending_energy_density_j_m2", &bending)]
        {
            let read = &vtk.arrays[&format!("cell.{name}")];
            let want: Vec<f64> = complete.iter().map(|&c| values[c].unwrap()).collect();
            assert_eq!(read, &want, "{name}");
        }
        assert!(vtk.arrays["cell.wrinkled"].iter().all(|v| *v == 0.0));
    }
    assert_cmd::Command::cargo_bin("drape").unwrap().arg("report").arg(&out).assert().success();
    let page = std::fs::read_to_string(out.join("report/index.html")).unwrap();
    assert!(out.join("report/c-wrinkles.png").is_file());
    assert!(page.contains("c-wrinkles.png") && page.contains("wrinkled area"), "the page shows the map and the column");
    // The map sits in the row of the shear map, the histogram in the next.
    let shear = page.find("c-shear.png").unwrap();
    let wrinkles = page.find("c-wrinkles.png").unwrap();
    let histogram = page.find("c-histogram.png").unwrap();
    assert!(shear < wrinkles && wrinkles < histogram);
    assert!(!page[shear..wrinkles].contains("class=\"pair\""), "the wrinkle map is beside the shear map");
}

/// A ply lying on a tool whose curvature the fit cannot follow is not wrinkled: `drape run`
/// drapes the double dome of the benchmark (15 mm fillets, 70 deg walls) at 5 mm, where the
/// ply's own smoothed surface cannot follow the fillets (its own reading exceeds the ply's
/// thickness there), but the kinematic ply lies on the facets, so its gaps to them are nil up to
/// rounding and so is the reading about the tool: no cell is wrinkled, every waviness is below
/// a nanometre. Also with its card's bending energy, from a net the pipeline wrote.
#[test]
fn a_ply_on_tight_fillets_reads_the_tools_shape_as_no_wrinkle() {
    let tmp = tempfile::tempdir().unwrap();
    let mesh = shapes::double_dome(&shapes::DoubleDome::benchmark(), 40);
    let card = repo("materials/glass-plain-weave.toml");
    let scene = format!(
        "units = \"m\"\ntool = \"tool.obj\"\n[materials]\nglass = \"{}\"\n[[ply]]\nname = \"f\"\norigin = [0.0, 0.0, 0.06]\nwarp = [1.0, 0.0, 0.0]\nmaterial = \"glass\"\nspacing = 0.005\ngrid = [61, 41]\n",
        card.display()
    );
    let (out, _) = drape_run(tmp.path(), &mesh, &scene);
    let net = drape::io::read_net(&out.join("f.drape.json")).unwrap();
    let record = net.meta.wrinkles.as_ref().unwrap();
    let own = cell_waviness(&net, &node_deviations(&net));
    let own_max = own.iter().flatten().copied().fold(0.0, f64::max);
    eprintln!(
        "double dome: own reading up to {own_max:.3e} m, the record's waviness up to {:?} m",
        record.summary.max_waviness_m
    );
    assert!(own_max > GLASS_THICKNESS, "the ply's own reading should not follow the fillets: {own_max} m");
    assert_eq!(record.summary.wrinkled_cells, 0);
    assert!(record.summary.max_waviness_m.unwrap() < 1e-9, "{:?}", record.summary);
}

/// A net with a wrinkle record that lacks a complete cell's value is refused before any file is
/// written: no NaN, no made-up value in the VTU.
#[test]
fn a_wrinkle_record_missing_a_complete_cell_is_refused() {
    let d = 0.005;
    let mut net = net_of(6, 5, d, |u, v| Point::new(u, v, 0.0));
    let mut record = measure(&net, &flat_tool(1.0), None, None);
    assert_eq!(record.summary.threshold_from, WrinkleThresholdFrom::Default);
    record.waviness_m[3] = None;
    net.meta.wrinkles = Some(record);
    let tmp = tempfile::tempdir().unwrap();
    let e = drape::io::write_net(&net, tmp.path(), &[drape::io::Format::Vtu]).unwrap_err();
    assert!(e.to_string().contains("meta.wrinkles.waviness_m"), "{e}");
    assert_eq!(std::fs::read_dir(tmp.path()).unwrap().count(), 0);
}

/// Bends of a net that lies exactly on planes are zero up to the rounding of its positions
/// (of order 1e-17 m for positions of order 0.1 m): a bend this small is taken as zero.
const BEND_ROUNDING_M: f64 = 1e-12;

/// A net folded along a straight hinge, isometrically (the fabric unstretched): flat for
/// s <= 0, turned by `theta` (towards its normal, a valley, or away, a ridge) for s > 0, s the
/// fabric distance across the hinge, which runs at `phi` to the warp `s0` past the centre node.
fn kink_net(theta: f64, valley: bool, phi: f64, s0: f64, d: f64, n: usize) -> DrapeNet {
    let up = if valley { 1.0 } else { -1.0 };
    net_of(n, n, d, |u, v| {
        let (s, t) = (u * phi.cos() + v * phi.sin() - s0, -u * phi.sin() + v * phi.cos());
        let (x, z) = if s <= 0.0 { (s, 0.0) } else { (s * theta.cos(), up * s * theta.sin()) };
        // Back to the frame of the fabric's directions.
        Point::new(x * phi.cos() - t * phi.sin(), x * phi.sin() + t * phi.cos(), z)
    })
}

/// A single kink is no wrinkle, whatever its angle and the spacing: folded at 5 to 150 deg,
/// as a valley and as a ridge, the hinge along the warp, across it and at 20 and 45 deg to it,
/// off the nodes, at 2, 5 and 10 mm. The waviness reads the kink (the fit rounds it: a trough
/// at the kink between the fit's overshoots, `0.098 tan(theta) σ` at most for a small angle,
/// see `kinematic::wrinkle`), above a threshold of half its largest reading, so the waviness
/// alone would call it wrinkled; but every bend has the kink's sign (each is a non-negative
/// multiple of the slope's jump across the hinge), so no node is both a crest and a trough in
/// turn and no cell undulates: none is wrinkled.
#[test]
fn a_single_kink_is_not_wrinkled_at_any_angle_or_spacing() {
    let n = 41;
    let tool = flat_tool(10.0);
    for (theta_deg, valley, phi_deg, d) in [
        (5.0f64, true, 0.0f64, 0.005),
        (20.0, false, 90.0, 0.002),
        (45.0, true, 20.0, 0.010),
        (45.0, false, 45.0, 0.005),
        (90.0, true, 45.0, 0.002),
        (120.0, false, 20.0, 0.010),
        (150.0, true, 70.0, 0.005),
        (10.0, false, 33.0, 0.010),
    ] {
        let (theta, phi) = (theta_deg.to_radians(), phi_deg.to_radians());
        let net = kink_net(theta, valley, phi, 0.37 * d, d, n);
        let bends = node_bends(&net);
        let sign = if valley { 1.0 } else { -1.0 };
        let (mut turned, mut against) = (0, 0);
        for b in bends.iter().flat_map(|b| b.iter().flatten()) {
            if b * sign > BEND_ROUNDING_M {
                turned += 1;
            }
            if b * sign < -BEND_ROUNDING_M {
                against += 1;
            }
        }
        assert!(turned > 0 && against == 0, "{theta_deg} deg: {turned} bends with the kink, {against} against it");
        // The record's waviness (the smaller of the readings about the ply and about the tool).
        let largest = measure(&net, &tool, None, None).summary.max_waviness_m.unwrap();
        let thickness = largest / 2.0;
        let record = measure(&net, &tool, Some(thickness), None);
        let wavy = record.waviness_m.iter().flatten().filter(|w| **w > thickness).count();
        eprintln!(
            "kink {theta_deg} deg ({}), hinge at {phi_deg} deg, d {d}: largest waviness {largest:.3e} m ({:.3} tan(theta) sigma), {wavy} cells wavier than {thickness:.3e} m, {} wrinkled",
            if valley { "valley" } else { "ridge" },
            largest / (theta.tan().abs() * SMOOTHING_SPACINGS * d),
            record.summary.wrinkled_cells
        );
        assert!(wavy > 0);
        assert!(record.undulating.iter().all(|u| *u == Some(false)), "{theta_deg} deg: a cell undulates");
        assert_eq!(record.summary.wrinkled_cells, 0);
        assert_eq!(record.summary.wrinkled_area_m2, 0.0);
    }
}

/// A ripple `A sin(k u + phase)` on a plane undulates wherever its waviness reaches the
/// threshold, so it is wrinkled exactly where it reads above it, as without the wave test:
/// wavelengths of 2.5 to 8 spacings, along the warp, the weft and at 30 deg. With the threshold
/// at the smallest reading of the cells whose windows are whole (the largest bend the wave test
/// then asks for, `WAVE_BEND_FRACTION` of it), each of those cells undulates: every half-wave
/// has a node whose bend `4 A sin²(π d/λ) |sin(k u + phase)|` (the second difference of the
/// ripple) exceeds it, as the module's notes derive (a node within π d/λ of the half-wave's
/// peak, |sin| >= cos(π d/λ), against a reading `A T`). With the threshold just above the
/// largest reading no cell is wrinkled.
#[test]
fn a_ripple_undulates_wherever_it_reads_the_threshold() {
    let n = 45;
    let m = whole_window_margin();
    let cv = n - 1;
    let tool = flat_tool(10.0);
    let mut rng = Rng(0x5eed_0033);
    for (lambda, angle_deg, d) in
        [(2.5, 0.0f64, 0.005), (3.0, 90.0, 0.004), (4.0, 30.0, 0.005), (6.0, 0.0, 0.003), (8.0, 90.0, 0.010)]
    {
        let (k, t) = (2.0 * PI / (lambda * d), angle_deg.to_radians());
        let a = 0.05 * d;
        let phase = PI * rng.next();
        let net = net_of(n, n, d, |u, v| Point::new(u, v, a * (k * (u * t.cos() + v * t.sin()) + phase).sin()));
        let inner: Vec<usize> =
            (0..cv * cv).filter(|c| (m..cv - m).contains(&(c / cv)) && (m..cv - m).contains(&(c % cv))).collect();
        let readings = cell_waviness(&net, &node_deviations(&net));
        let (lo, hi) =
            inner.iter().map(|&c| readings[c].unwrap()).fold((f64::MAX, 0.0f64), |(l, h), w| (l.min(w), h.max(w)));
        // Just below the smallest reading: every inner cell is wavier.
        let thickness = lo * (1.0 - 1e-9);
        let record = measure(&net, &tool, Some(thickness), None);
        assert_eq!(record.summary.wave_bend_m, Some(WAVE_BEND_FRACTION * thickness));
        let undulating = inner.iter().filter(|&&c| record.undulating[c] == Some(true)).count();
        let wrinkled = inner.iter().filter(|&&c| record.wrinkled(c) == Some(true)).count();
        eprintln!(
            "ripple {lambda} d at {angle_deg} deg, d {d}: readings in [{:.4}, {:.4}] A (T = {:.4}), {undulating} of {} inner cells undulate, {wrinkled} wrinkled",
            lo / a,
            hi / a,
            transfer(lambda),
            inner.len()
        );
        assert_eq!(undulating, inner.len(), "ripple {lambda} d: every inner cell undulates");
        assert_eq!(wrinkled, inner.len(), "ripple {lambda} d: every inner cell is wrinkled");
        // Every cell is wrinkled exactly where its waviness exceeds the threshold and it undulates.
        let count = (0..cv * cv)
            .filter(|&c| record.waviness_m[c].unwrap() > thickness && record.undulating[c] == Some(true))
            .count();
        assert_eq!(record.summary.wrinkled_cells, count);
        // Above the largest reading: nothing is wrinkled, though the ply still undulates.
        let above = measure(&net, &tool, Some(hi * (1.0 + 1e-9)), None);
        assert!(inner.iter().all(|&c| above.undulating[c] == Some(true)));
        let wavier = above.waviness_m.iter().flatten().filter(|w| **w > hi * (1.0 + 1e-9)).count();
        assert_eq!(
            above.summary.wrinkled_cells, wavier,
            "cells outside the inner ones may read more (their windows are cut)"
        );
        assert!(inner.iter().all(|&c| above.wrinkled(c) == Some(false)));
    }
}

/// Spheres and cylinders bend one way: every bend has one sign (the straight fibre of a
/// cylinder's zero up to rounding), so no cell undulates and none is wrinkled, even against a
/// threshold of half their largest waviness (the fit's error, largest near the edges), which the
/// waviness alone would exceed.
#[test]
fn spheres_and_cylinders_do_not_undulate() {
    let tool = flat_tool(10.0);
    let nets = [
        ("sphere", sphere_net(0.04, 0.004, 21)),
        ("sphere", sphere_net(0.1, 0.005, 31)),
        ("cylinder", cylinder_net(0.02, 0.004, 21, 15, Fibre::Warp)),
        ("cylinder", cylinder_net(0.05, 0.005, 31, 21, Fibre::Weft)),
    ];
    for (what, net) in nets {
        // One sign (which one depends on which side the net's normal, warp x weft, points to).
        let bends: Vec<f64> = node_bends(&net).iter().flat_map(|b| b.iter().flatten()).copied().collect();
        let (least, most) = bends.iter().fold((f64::MAX, f64::MIN), |(l, m), b| (l.min(*b), m.max(*b)));
        assert!(
            most <= BEND_ROUNDING_M || least >= -BEND_ROUNDING_M,
            "{what}: bends from {least} m to {most} m, both ways"
        );
        let largest = measure(&net, &tool, None, None).summary.max_waviness_m.unwrap();
        let thickness = largest / 2.0;
        let record = measure(&net, &tool, Some(thickness), None);
        let wavy = record.waviness_m.iter().flatten().filter(|w| **w > thickness).count();
        eprintln!(
            "{what}: largest waviness {largest:.3e} m, {wavy} cells over half of it, {} wrinkled",
            record.summary.wrinkled_cells
        );
        assert!(wavy > 0);
        assert!(record.undulating.iter().flatten().all(|u| !u));
        assert_eq!(record.summary.wrinkled_cells, 0);
    }
}

/// A record written before the wave test (no `undulating`) keeps its meaning: a cell is
/// wrinkled on its waviness alone, as its summary counted; with the test, only where both hold.
#[test]
fn a_record_without_the_wave_test_is_wrinkled_on_its_waviness_alone() {
    let d = 0.005;
    let net = kink_net(30f64.to_radians(), true, 0.0, 0.37 * d, d, 31);
    let thickness = waviness(&net).into_iter().fold(0.0, f64::max) / 2.0;
    let mut record = measure(&net, &flat_tool(1.0), Some(thickness), None);
    let cv = net.nv - 1;
    let cells = (0..net.num_cells()).filter(|&c| net.cell_corners(c / cv, c % cv).is_some());
    assert!(cells.clone().all(|c| record.wrinkled(c) == Some(false)));
    record.undulating.clear();
    let wavy = cells.clone().filter(|&c| record.waviness_m[c].unwrap() > thickness).count();
    assert!(wavy > 0);
    assert_eq!(cells.filter(|&c| record.wrinkled(c) == Some(true)).count(), wavy);
    // And cell_undulating is what measure records.
    let again = cell_undulating(&net, &node_deviations(&net), &node_bends(&net), WAVE_BEND_FRACTION * thickness);
    assert!(again.iter().flatten().all(|u| !u));
}
