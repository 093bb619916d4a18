//! Flat patterns, nesting and their drawings, on real drapes of generated tools.
//!
//! Known answers: on a plate the pattern is the plate (to within one spacing), on a cylinder
//! the unrolled patch (axis length by arc length); cut through the boundary nodes the pattern
//! area is exactly (complete cells + half cells / 2) d^2; a ply with an outline is cut along the
//! outline carried into the flat frame (on a plate: the outline itself). The DXF and SVG are read back by
//! tools/pattern_readback.py (ezdxf and xml.etree; `python3 -m pip install -r
//! tools/requirements.txt`); DRAPE_SKIP_PYTHON=1 skips that part.
use drape::geometry::{shapes, Point, ToolSurface, Vector};
use drape::io::drawing::{write_cutting_plan, PatternError};
use drape::io::dxf::{dxf_layer_names, write_dxf};
use drape::io::svg::{svg_ids, write_pattern_svg, write_svg};
use drape::kinematic::{drape, DrapeNet, Extent, KinematicSettings, NodeStatus};
use drape::layup::flat::{
    flat_pattern, flat_pattern_in_outline, flat_pattern_smooth, flat_pattern_with_margin, ply_pattern, shoelace_area,
    CutLine, CutWarning, FlatError, FlatPattern, Region,
};
use drape::layup::nest::{nest, Nesting, Rotation};
use proptest::prelude::*;
use serde_json::Value;
use std::path::Path;
use std::process::Command;
use std::sync::OnceLock;

/// Relative tolerance between areas computed two ways in floating point.
const AREA_REL: f64 = 1e-12;
/// Relative tolerance of areas read back from a file (coordinates printed in mm).
pub(crate) const FILE_AREA_REL: f64 = 1e-9;
/// Rounding-level length tolerance (m).
const LEN_EPS: f64 = 1e-9;

pub(crate) fn hemisphere() -> &'static ToolSurface {
    static TOOL: OnceLock<ToolSurface> = OnceLock::new();
    TOOL.get_or_init(|| shapes::hemisphere_with_triangles(1.0, 20_000).into_surface().unwrap())
}

/// Complete cells of a net, counted directly.
fn complete_cells(net: &DrapeNet) -> usize {
    (0..net.nu - 1)
        .flat_map(|i| (0..net.nv - 1).map(move |j| (i, j)))
        .filter(|&(i, j)| net.cell_corners(i, j).is_some())
        .count()
}

/// Cells of a net with exactly three placed corners, counted directly.
fn half_cells(net: &DrapeNet) -> usize {
    (0..net.nu - 1)
        .flat_map(|i| (0..net.nv - 1).map(move |j| (i, j)))
        .filter(|&(i, j)| {
            [(i, j), (i + 1, j), (i, j + 1), (i + 1, j + 1)].iter().filter(|&&(a, b)| net.node(a, b).is_some()).count()
                == 3
        })
        .count()
}

/// Largest turn between consecutive edges of the loops of a pattern, degrees.
fn max_turn_deg(p: &FlatPattern) -> f64 {
    let mut worst = 0.0f64;
    for l in p.loops() {
        let n = l.len();
        for k in 0..n {
            let (a, b, c) = (l[(k + n - 1) % n], l[k], l[(k + 1) % n]);
            let (u, w) = ([b[0] - a[0], b[1] - a[1]], [c[0] - b[0], c[1] - b[1]]);
            worst = worst.max((u[0] * w[1] - u[1] * w[0]).atan2(u[0] * w[0] + u[1] * w[1]).abs().to_degrees());
        }
    }
    worst
}

/// Loops of a pattern cut through the boundary nodes are closed polygons through nodes (on the
/// grid of spacing d), each edge along a fibre or along cell diagonals, simple (no repeated
/// vertex, no collinear vertex), outer counter-clockwise first then holes clockwise, and the
/// signed areas add up to the pattern area, (cells + half cells / 2) d^2.
fn check_pattern(p: &FlatPattern) {
    let d = p.spacing;
    assert_eq!(p.cut, CutLine::Nodes, "{}", p.ply);
    let mut total = 0.0;
    for r in &p.regions {
        let areas: Vec<f64> = r.loops.iter().map(|l| shoelace_area(l)).collect();
        assert!(areas[0] > 0.0, "{}: the outer loop must be counter-clockwise: {areas:?}", p.ply);
        assert!(areas[1..].iter().all(|&a| a < 0.0), "{}: holes must be clockwise: {areas:?}", p.ply);
        let sum: f64 = areas.iter().sum();
        assert!((sum - r.area).abs() <= AREA_REL * r.area, "{}: loops {sum} vs triangles {}", p.ply, r.area);
        // Whole cells and half cells: a multiple of d^2 / 2.
        let halves = r.area / (0.5 * d * d);
        assert!((halves - halves.round()).abs() < 1e-9 && halves.round() >= 2.0 * r.cells as f64, "{}", p.ply);
        total += sum;
        for l in &r.loops {
            let n = l.len();
            let mut seen = std::collections::HashSet::new();
            for k in 0..n {
                let (a, b, c) = (l[(k + n - 1) % n], l[k], l[(k + 1) % n]);
                // On the grid: multiples of d from the seed.
                for v in b {
                    assert!((v / d - (v / d).round()).abs() < 1e-9, "{}: vertex {b:?} off the grid", p.ply);
                }
                assert!(
                    seen.insert([(b[0] / d).round() as i64, (b[1] / d).round() as i64]),
                    "{}: vertex {b:?} repeated",
                    p.ply
                );
                let (u, w) = ([b[0] - a[0], b[1] - a[1]], [c[0] - b[0], c[1] - b[1]]);
                assert!(
                    u[0].abs() < LEN_EPS || u[1].abs() < LEN_EPS || (u[0].abs() - u[1].abs()).abs() < LEN_EPS,
                    "{}: edge {a:?} -> {b:?} neither along a fibre nor along cell diagonals",
                    p.ply
                );
                assert!((u[0] * w[1] - u[1] * w[0]).abs() > 0.25 * d * d, "{}: vertex {b:?} is not a corner", p.ply);
            }
        }
    }
    assert!((total - p.area).abs() <= AREA_REL * p.area);
    assert_eq!(p.cells, p.regions.iter().map(|r| r.cells).sum::<usize>());
    let want = (2 * p.cells + p.half_cells) as f64 * 0.5 * d * d;
    assert!((p.area - want).abs() <= AREA_REL * want, "{}: area {} vs {want}", p.ply, p.area);
}

/// `check_pattern`, and the cell counts are the net's own.
fn check_net_pattern(p: &FlatPattern, net: &DrapeNet) {
    check_pattern(p);
    assert_eq!((p.cells, p.half_cells), (complete_cells(net), half_cells(net)), "{}", p.ply);
}

#[test]
fn plate_ply_fully_on_the_tool_is_one_rectangle() {
    let tool = shapes::plate(1.0, 1.0, 13, 17).into_surface().unwrap();
    let d = 0.02;
    let (nu, nv) = (31, 25);
    let net =
        drape(&tool, &KinematicSettings::grid("rect", Point::new(0.05, -0.03, 0.01), Vector::x(), d, nu, nv)).unwrap();
    let p = flat_pattern(&net).unwrap();
    check_net_pattern(&p, &net);
    assert_eq!(p.regions.len(), 1);
    assert_eq!(p.regions[0].loops.len(), 1);
    assert_eq!(p.regions[0].loops[0].len(), 4, "a rectangle: {:?}", p.regions[0].loops[0]);
    let (i0, j0) = net.origin_node;
    assert_eq!(p.min, [-(i0 as f64) * d, -(j0 as f64) * d]);
    assert_eq!(p.max, [(nu - 1 - i0) as f64 * d, (nv - 1 - j0) as f64 * d]);
    let [sx, sy] = p.size();
    assert!((sx - (nu - 1) as f64 * d).abs() < LEN_EPS && (sy - (nv - 1) as f64 * d).abs() < LEN_EPS, "{sx} x {sy}");
    assert_eq!(p.cells, (nu - 1) * (nv - 1));
    // The anchor (arrow and label) is inside the pattern.
    assert!((0..2).all(|k| p.min[k] < p.anchor[k] && p.anchor[k] < p.max[k]));
}

#[test]
fn plate_ply_larger_than_the_plate_is_the_plate_outline_to_within_d() {
    let (w, l) = (0.5, 0.3);
    let tool = shapes::plate(w, l, 10, 6).into_surface().unwrap();
    let d = 0.02;
    let seed = Point::new(0.013, -0.007, 0.0);
    let net = drape(&tool, &KinematicSettings::grid("big", seed, Vector::x(), d, 41, 31)).unwrap();
    assert!(net.status.iter().any(|s| *s != NodeStatus::Placed), "the ply must overhang the plate");
    let p = flat_pattern(&net).unwrap();
    check_net_pattern(&p, &net);
    assert_eq!((p.regions.len(), p.regions[0].loops.len(), p.regions[0].loops[0].len()), (1, 1, 4));
    // On a plane the flat pattern is the drape itself: flat point + seed = draped node.
    let (i0, j0) = net.origin_node;
    for i in 0..net.nu {
        for j in 0..net.nv {
            if let Some(q) = net.node(i, j) {
                let flat = [(i as f64 - i0 as f64) * d, (j as f64 - j0 as f64) * d];
                assert!(
                    (q.x - seed.x - flat[0]).abs() < 1e-9 && (q.y - seed.y - flat[1]).abs() < 1e-9,
                    "node ({i}, {j})"
                );
            }
        }
    }
    // Plate edges in the pattern frame; the pattern lies inside and reaches within d of each.
    let lo = [-w / 2.0 - seed.x, -l / 2.0 - seed.y];
    let hi = [w / 2.0 - seed.x, l / 2.0 - seed.y];
    for k in 0..2 {
        assert!(p.min[k] >= lo[k] - LEN_EPS && p.min[k] < lo[k] + d, "min[{k}] {} vs plate edge {}", p.min[k], lo[k]);
        assert!(p.max[k] <= hi[k] + LEN_EPS && p.max[k] > hi[k] - d, "max[{k}] {} vs plate edge {}", p.max[k], hi[k]);
    }
    assert!(p.area <= w * l && p.area > (w - 2.0 * d) * (l - 2.0 * d), "area {}", p.area);
}

#[test]
fn ply_trimmed_to_a_circular_outline() {
    let tool = shapes::plate(1.0, 1.0, 20, 20).into_surface().unwrap();
    let (r, d) = (0.2, 0.01);
    let outline: Vec<Point> = (0..180)
        .map(|k| {
            let t = k as f64 * std::f64::consts::TAU / 180.0;
            Point::new(r * t.cos(), r * t.sin(), 0.0)
        })
        .collect();
    let mut s = KinematicSettings::grid("disc", Point::new(0.0, 0.0, 0.0), Vector::x(), d, 3, 3);
    s.extent = Extent::Outline(outline);
    let net = drape(&tool, &s).unwrap();
    let p = flat_pattern(&net).unwrap();
    check_net_pattern(&p, &net);
    assert_eq!(p.regions.len(), 1);
    // The nodes inside the polygon span a convex region inside the circle; every point of the
    // disc of radius r - sqrt(2) d (less the polygon's sagitta) is in a complete cell.
    let sagitta = r * (1.0 - (std::f64::consts::PI / 180.0).cos());
    let inner = r - sagitta - std::f64::consts::SQRT_2 * d;
    let pi = std::f64::consts::PI;
    assert!(
        p.area <= pi * r * r && p.area >= pi * inner * inner,
        "area {} not in [{}, {}]",
        p.area,
        pi * inner * inner,
        pi * r * r
    );
    for k in 0..2 {
        assert!(
            p.min[k] >= -r && p.max[k] <= r && p.min[k] < -r + 2.0 * d && p.max[k] > r - 2.0 * d,
            "bbox {:?} {:?}",
            p.min,
            p.max
        );
    }
}

#[test]
fn cylinder_pattern_is_the_unrolled_patch() {
    // Half a cylinder, radius 0.5, length 1: the unrolled tool is 1 (axis) x arc length.
    let (radius, length, n_around) = (0.5, 1.0, 720);
    let tool = shapes::cylinder(radius, length, std::f64::consts::PI, n_around, 40).into_surface().unwrap();
    let d = 0.02;
    // Warp along the axis (y), weft around; the grid overhangs the tool both ways. The seed is
    // off the grid of the tool's ends so that no node falls exactly on an end.
    let net =
        drape(&tool, &KinematicSettings::grid("cyl", Point::new(0.0, 0.007, radius), Vector::y(), d, 61, 91)).unwrap();
    let p = flat_pattern(&net).unwrap();
    check_net_pattern(&p, &net);
    // Arc length of the faceted section: the sum of its chords. Nodes d apart fit in a length L
    // over at least L - d (the staircase).
    let arc = n_around as f64 * 2.0 * radius * (std::f64::consts::PI / (2.0 * n_around as f64)).sin();
    let [along_axis, around] = p.size();
    println!("cylinder: pattern {along_axis} x {around} m, tool {length} x {arc} m, {} cells", p.cells);
    assert!(
        along_axis <= length + LEN_EPS && along_axis >= length - d - LEN_EPS,
        "along the axis {along_axis} vs {length}"
    );
    assert!(around <= arc + LEN_EPS && around >= arc - d - LEN_EPS, "around {around} vs arc {arc}");
    assert_eq!(p.regions.len(), 1);
}

#[test]
fn hemisphere_pattern_area_is_the_cell_and_half_cell_count_exactly() {
    for (name, warp, n) in [("h0", Vector::x(), 61), ("h45", Vector::new(1.0, 1.0, 0.0), 71)] {
        let net =
            drape(hemisphere(), &KinematicSettings::grid(name, Point::new(0.0, 0.0, 1.0), warp, 0.05, n, n)).unwrap();
        let p = flat_pattern(&net).unwrap();
        // A woven cell keeps its fibre lengths: each draped cell is d x d undeformed, each half
        // cell (three corners on the tool) half of that.
        check_net_pattern(&p, &net);
        assert!(p.half_cells > 0, "{name}: the rim of a hemisphere drape has half cells");
        let holes: usize = p.regions.iter().map(|r| r.loops.len() - 1).sum();
        println!(
            "{name}: {} cells, {} region(s), {holes} hole(s), area {:.4} m2, bbox {:?}",
            p.cells,
            p.regions.len(),
            p.area,
            p.size()
        );
        // Deterministic.
        assert_eq!(flat_pattern(&net).unwrap(), p);
    }
}

#[test]
fn no_complete_cell_is_an_error_naming_the_ply() {
    let mut net = DrapeNet::new("lonely", 0.01, 3, 3, (1, 1));
    net.status[4] = NodeStatus::Placed;
    let e = flat_pattern(&net).unwrap_err();
    assert_eq!(e, FlatError::NoCells { ply: "lonely".into() });
    assert!(e.to_string().contains("'lonely'"), "{e}");
}

/// The flat pattern of a hand-made net (see [`shape_net`]).
fn shape(name: &str, d: f64, nu: usize, nv: usize, cells: impl Fn(usize, usize) -> bool) -> FlatPattern {
    flat_pattern(&shape_net(name, d, nu, nv, cells)).unwrap()
}

/// A square ring (a hole in the middle) and two squares touching at a corner.
fn ring() -> FlatPattern {
    shape("ring", 0.01, 21, 21, |i, j| !(5..15).contains(&i) || !(5..15).contains(&j))
}
fn pinch() -> FlatPattern {
    shape("pinch", 0.01, 21, 21, |i, j| (i < 10) == (j < 10))
}

/// A flat net of `cells` (i, j) on an nu x nv grid, spacing d: a hand-made pattern shape.
pub(crate) fn shape_net(name: &str, d: f64, nu: usize, nv: usize, cells: impl Fn(usize, usize) -> bool) -> DrapeNet {
    let mut net = DrapeNet::new(name, d, nu, nv, (nu / 2, nv / 2));
    for i in 0..nu - 1 {
        for j in 0..nv - 1 {
            if cells(i, j) {
                for (a, b) in [(i, j), (i + 1, j), (i, j + 1), (i + 1, j + 1)] {
                    let k = net.index(a, b);
                    net.positions[k] = Point::new(a as f64 * d, b as f64 * d, 0.0);
                    net.status[k] = NodeStatus::Placed;
                }
            }
        }
    }
    net
}

/// The box of a net's complete cells in the flat frame: [min, max].
fn cell_box(net: &DrapeNet) -> [[f64; 2]; 2] {
    let (d, (i0, j0)) = (net.spacing, net.origin_node);
    let mut b = [[f64::INFINITY; 2], [f64::NEG_INFINITY; 2]];
    for i in 0..net.nu - 1 {
        for j in 0..net.nv - 1 {
            if net.cell_corners(i, j).is_some() {
                let lo = [(i as f64 - i0 as f64) * d, (j as f64 - j0 as f64) * d];
                for k in 0..2 {
                    b[0][k] = b[0][k].min(lo[k]);
                    b[1][k] = b[1][k].max(lo[k] + d);
                }
            }
        }
    }
    b
}

/// Loops of a pattern with a margin: outer counter-clockwise first, holes clockwise, region
/// areas are their shoelace sums, and the box is the complete cells' box grown by the margin.
fn check_margin(p: &FlatPattern, net: &DrapeNet, margin: f64) {
    let plain = flat_pattern(net).unwrap();
    let [lo, hi] = cell_box(net);
    assert_eq!(p.cut, CutLine::GrownCells);
    let mut total = 0.0;
    for r in &p.regions {
        let areas: Vec<f64> = r.loops.iter().map(|l| shoelace_area(l)).collect();
        assert!(areas[0] > 0.0 && areas[1..].iter().all(|&a| a < 0.0), "{}: {areas:?}", p.ply);
        assert!((areas.iter().sum::<f64>() - r.area).abs() <= AREA_REL * r.area);
        total += r.area;
    }
    assert!((total - p.area).abs() <= AREA_REL * p.area);
    assert_eq!(p.cells, plain.cells);
    assert_eq!(p.regions.iter().map(|r| r.cells).sum::<usize>(), p.cells);
    for k in 0..2 {
        assert!((p.min[k] - (lo[k] - margin)).abs() < LEN_EPS && (p.max[k] - (hi[k] + margin)).abs() < LEN_EPS);
    }
    assert!(p.area > p.cells as f64 * net.spacing * net.spacing);
}

#[test]
fn cutting_margin_grows_the_outline_with_square_corners() {
    let d = 0.01;
    // A 0.2 x 0.1 rectangle grown by m: (0.2 + 2m) x (0.1 + 2m).
    let rect = shape_net("rect", d, 21, 11, |_, _| true);
    let m = 0.003;
    let p = flat_pattern_with_margin(&rect, m).unwrap();
    check_margin(&p, &rect, m);
    assert_eq!((p.regions.len(), p.regions[0].loops.len(), p.regions[0].loops[0].len()), (1, 1, 4));
    assert!((p.area - (0.2 + 2.0 * m) * (0.1 + 2.0 * m)).abs() < 1e-15, "{}", p.area);
    // Two squares touching at a corner merge into one piece: the grown squares overlap by (2m)^2.
    let pinch = shape_net("pinch", d, 21, 21, |i, j| (i < 10) == (j < 10));
    let p = flat_pattern_with_margin(&pinch, m).unwrap();
    check_margin(&p, &pinch, m);
    assert_eq!((p.regions.len(), p.regions[0].cells), (1, 200));
    let want = 2.0 * (0.1 + 2.0 * m) * (0.1 + 2.0 * m) - 4.0 * m * m;
    assert!((p.area - want).abs() < 1e-15, "{} vs {want}", p.area);
    // A ring keeps a smaller hole, until the margin closes it (hole 0.1 wide).
    let ring = shape_net("ring", d, 21, 21, |i, j| !(5..15).contains(&i) || !(5..15).contains(&j));
    for (m, holes) in [(0.004, 1), (0.03, 1), (0.05, 0), (0.07, 0)] {
        let p = flat_pattern_with_margin(&ring, m).unwrap();
        check_margin(&p, &ring, m);
        assert_eq!(p.regions[0].loops.len() - 1, holes, "margin {m}");
        let hole = (0.1 - 2.0 * m).max(0.0);
        let want = (0.2 + 2.0 * m).powi(2) - hole * hole;
        assert!((p.area - want).abs() < 1e-14, "margin {m}: {} vs {want}", p.area);
    }
    // A margin that is not a whole number of spacings, on a hemisphere drape (pinches, stairs).
    let net = drape(
        hemisphere(),
        &KinematicSettings::grid("hm", Point::new(0.1, 0.0, 1.0), Vector::new(1.0, 0.3, 0.0), 0.05, 61, 61),
    )
    .unwrap();
    let plain = flat_pattern(&net).unwrap();
    for m in [0.0123, 0.025, 0.075] {
        check_margin(&flat_pattern_with_margin(&net, m).unwrap(), &net, m);
    }
    assert_eq!(flat_pattern_with_margin(&net, 0.0).unwrap(), plain);
    assert!(matches!(flat_pattern_with_margin(&net, -0.01), Err(FlatError::BadMargin { .. })));
}

fn check_nesting(patterns: &[FlatPattern], n: &Nesting) {
    assert_eq!(n.placements.len(), patterns.len());
    for (p, q) in patterns.iter().zip(&n.placements) {
        assert_eq!(p.ply, q.ply);
        // The placed box is the transformed pattern box, inside the roll.
        let corners = [p.min, [p.max[0], p.min[1]], p.max, [p.min[0], p.max[1]]].map(|c| q.to_roll(c));
        for k in 0..2 {
            let lo = corners.iter().map(|c| c[k]).fold(f64::INFINITY, f64::min);
            let hi = corners.iter().map(|c| c[k]).fold(f64::NEG_INFINITY, f64::max);
            assert!((lo - q.min[k]).abs() < LEN_EPS && (hi - q.max[k]).abs() < LEN_EPS, "{}: box", p.ply);
        }
        assert!(
            q.min[1] >= -LEN_EPS && q.max[1] <= n.roll_width + LEN_EPS,
            "{}: across {:?}..{:?}",
            p.ply,
            q.min,
            q.max
        );
        assert!(q.min[0] >= -LEN_EPS && q.max[0] <= n.length + LEN_EPS);
    }
    // Boxes apart by at least the gap in x or in y.
    for a in 0..n.placements.len() {
        for b in a + 1..n.placements.len() {
            let (p, q) = (&n.placements[a], &n.placements[b]);
            let sep_x = (q.min[0] - p.max[0]).max(p.min[0] - q.max[0]);
            let sep_y = (q.min[1] - p.max[1]).max(p.min[1] - q.max[1]);
            assert!(
                sep_x >= n.gap - LEN_EPS || sep_y >= n.gap - LEN_EPS,
                "{} and {} overlap: {p:?} {q:?}",
                p.ply,
                q.ply
            );
        }
    }
    let area: f64 = patterns.iter().map(|p| p.area).sum();
    assert!((n.pattern_area - area).abs() <= AREA_REL * area);
    assert_eq!(n.used_area, n.roll_width * n.length);
    assert!((n.waste_area - (n.used_area - n.pattern_area)).abs() < LEN_EPS);
    assert!(n.waste_area >= 0.0 && (0.0..1.0).contains(&n.waste_fraction));
    assert_eq!(n.length, n.placements.iter().map(|q| q.max[0]).fold(0.0, f64::max));
}

fn some_patterns() -> Vec<FlatPattern> {
    let h = drape(hemisphere(), &KinematicSettings::grid("hemi", Point::new(0.0, 0.0, 1.0), Vector::x(), 0.05, 31, 31))
        .unwrap();
    let mut v = vec![flat_pattern(&h).unwrap(), ring(), pinch()];
    for (k, (a, b)) in [(12, 5), (5, 30), (9, 9), (20, 3), (3, 3), (16, 11)].into_iter().enumerate() {
        v.push(shape(&format!("r{k}"), 0.02, a + 1, b + 1, |_, _| true));
    }
    v
}

#[test]
fn nesting_places_every_piece_inside_the_roll_without_overlap() {
    let patterns = some_patterns();
    for (width, gap, rot) in [
        (1.6, 0.01, Rotation::WarpAlongRoll),
        (3.0, 0.0, Rotation::WarpAlongRoll),
        (1.55, 0.005, Rotation::AllowQuarterTurn),
    ] {
        let n = nest(&patterns, width, gap, rot).unwrap();
        check_nesting(&patterns, &n);
        if rot == Rotation::WarpAlongRoll {
            assert!(n.placements.iter().all(|q| !q.rotated && q.warp() == [1.0, 0.0]));
        }
        println!(
            "roll {width} m, gap {gap}: length {:.3} m, used {:.3} m2, patterns {:.3} m2, waste {:.1} %",
            n.length,
            n.used_area,
            n.pattern_area,
            100.0 * n.waste_fraction
        );
        assert_eq!(nest(&patterns, width, gap, rot).unwrap(), n, "deterministic");
    }
}

/// A rectangular pattern `a x b` (m) with its lower-left corner at `at`, built field by field.
fn rect_pattern(name: &str, a: f64, b: f64, at: [f64; 2]) -> FlatPattern {
    let (x0, y0, x1, y1) = (at[0], at[1], at[0] + a, at[1] + b);
    FlatPattern {
        ply: name.into(),
        spacing: a.min(b),
        origin_node: (0, 0),
        regions: vec![Region { loops: vec![vec![[x0, y0], [x1, y0], [x1, y1], [x0, y1]]], cells: 1, area: a * b }],
        cells: 1,
        half_cells: 0,
        area: a * b,
        cut: CutLine::Nodes,
        margin: 0.0,
        warnings: Vec::new(),
        min: [x0, y0],
        max: [x1, y1],
        anchor: [x0 + a / 2.0, y0 + b / 2.0],
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]
    /// Random boxes on random rolls: inside the roll, apart by the gap, areas add up.
    #[test]
    fn nesting_random_boxes(sizes in proptest::collection::vec((0.01f64..0.9, 0.01f64..0.9, -1.0f64..1.0, -1.0f64..1.0), 1..25),
                            width in 0.9f64..2.5, gap in 0.0f64..0.05, turn in any::<bool>()) {
        let patterns: Vec<FlatPattern> = sizes.iter().enumerate().map(|(k, &(a, b, x, y))| rect_pattern(&format!("p{k}"), a, b, [x, y])).collect();
        let rot = if turn { Rotation::AllowQuarterTurn } else { Rotation::WarpAlongRoll };
        let n = nest(&patterns, width, gap, rot).unwrap();
        check_nesting(&patterns, &n);
        // No piece reaches past the roll length and the roll is not longer than laying them end to end.
        let end_to_end: f64 = patterns.iter().map(|p| p.size()[0].max(if turn { p.size()[1] } else { 0.0 }) + gap).sum();
        prop_assert!(n.length <= end_to_end + LEN_EPS);
    }
}

#[test]
fn nesting_refuses_a_piece_wider_than_the_roll() {
    let wide = shape("wide", 0.1, 4, 13, |_, _| true); // 0.3 along x, 1.2 across
    let e = nest(std::slice::from_ref(&wide), 1.0, 0.0, Rotation::WarpAlongRoll).unwrap_err();
    match &e {
        FlatError::TooWide { ply, excess, .. } => {
            assert_eq!(ply, "wide");
            assert!((excess - 0.2).abs() < LEN_EPS, "{e}");
        }
        other => panic!("{other}"),
    }
    assert!(e.to_string().contains("'wide'") && e.to_string().contains("0.200000 m too wide"), "{e}");
    // Turned, it fits.
    let n = nest(std::slice::from_ref(&wide), 1.0, 0.0, Rotation::AllowQuarterTurn).unwrap();
    assert!(n.placements[0].rotated && n.placements[0].warp() == [0.0, 1.0]);
    check_nesting(std::slice::from_ref(&wide), &n);
    assert!(matches!(
        nest(&[], 0.0, 0.0, Rotation::WarpAlongRoll),
        Err(FlatError::BadNestParameter { field: "roll_width", .. })
    ));
    assert!(matches!(
        nest(&[], 1.0, -1.0, Rotation::WarpAlongRoll),
        Err(FlatError::BadNestParameter { field: "gap", .. })
    ));
}

/// Whether the Python part should run; fails the test (with what to do) if ezdxf is missing.
pub(crate) fn python_ready() -> bool {
    if std::env::var("DRAPE_SKIP_PYTHON").is_ok_and(|v| v == "1") {
        eprintln!("flat_patterns: DRAPE_SKIP_PYTHON=1: skipped the independent Python read-back");
        return false;
    }
    match Command::new("python3").args(["-c", "import ezdxf"]).output() {
        Ok(o) if o.status.success() => true,
        Ok(o) => panic!(
            "python3 cannot import ezdxf ({}). Run `python3 -m pip install -r tools/requirements.txt`, or set DRAPE_SKIP_PYTHON=1 to skip this check.",
            String::from_utf8_lossy(&o.stderr).trim()
        ),
        Err(e) => panic!("cannot run python3 ({e}). Install Python 3 and the packages in tools/requirements.txt, or set DRAPE_SKIP_PYTHON=1."),
    }
}

pub(crate) fn readback(files: &[&Path]) -> Value {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tools/pattern_readback.py");
    let out = Command::new("python3").arg(&script).args(files).output().unwrap();
    assert!(
        out.status.success(),
        "{} failed ({}):\n{}",
        script.display(),
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout)
        .unwrap_or_else(|e| panic!("readback output is not JSON ({e}):\n{}", String::from_utf8_lossy(&out.stdout)))
}

pub(crate) fn num(v: &Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("not a number: {v}"))
}

pub(crate) fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * b.abs().max(1e-300)
}

#[test]
fn drawings_read_back_independently() {
    let mut patterns = some_patterns();
    patterns.truncate(5);
    patterns[4].ply = "odd name/<&>".into(); // must become a valid layer name and id
    patterns.push(
        flat_pattern_with_margin(&shape_net("ring-margin", 0.01, 21, 21, |i, j| i < 5 || j < 5 || i >= 15), 0.0037)
            .unwrap(),
    );
    let n = nest(&patterns, 1.6, 0.01, Rotation::AllowQuarterTurn).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let (dxf, svg, one) = (dir.path().join("nest.dxf"), dir.path().join("nest.svg"), dir.path().join("ring.svg"));
    write_dxf(&patterns, &n, &dxf).unwrap();
    write_svg(&patterns, &n, &svg).unwrap();
    write_pattern_svg(&patterns[1], &one).unwrap();
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 3, "no temporary files left");
    let text = std::fs::read_to_string(&dxf).unwrap();
    assert!(!text.contains("NaN") && !text.contains("inf"));
    let layers = dxf_layer_names(&patterns);
    assert_eq!(layers[4], "odd_name____");
    let ids = svg_ids(&patterns);
    assert_eq!(ids[4], "ply-odd_name____");

    // A nesting of other patterns is refused, and nothing is written.
    let bad = dir.path().join("bad.dxf");
    assert!(matches!(write_dxf(&patterns[..2], &n, &bad), Err(PatternError::Mismatch { .. })));
    assert!(!bad.exists());

    if !python_ready() {
        return;
    }
    let r = readback(&[&dxf, &svg, &one]);
    let d = &r[dxf.to_str().unwrap()];
    assert_eq!(d["dxfversion"], "AC1009");
    assert_eq!(d["insunits"], 4);
    let mut want: Vec<String> = layers.iter().cloned().chain(["ROLL", "ARROWS", "LABELS"].map(String::from)).collect();
    want.sort();
    let got: Vec<String> = d["layers"].as_array().unwrap().iter().map(|v| v.as_str().unwrap().to_string()).collect();
    assert!(want.iter().all(|l| got.contains(l)), "layers {got:?}, want {want:?}");
    assert_eq!(d["by_layer"]["ROLL"]["lines"], 4);
    for ((p, q), layer) in patterns.iter().zip(&n.placements).zip(&layers) {
        let s = &d["by_layer"][layer.as_str()];
        let holes: usize = p.regions.iter().map(|r| r.loops.len() - 1).sum();
        assert_eq!(s["closed_polylines"], p.loops().count(), "{layer}");
        assert_eq!((s["open_polylines"].as_u64(), s["self_intersecting"].as_u64()), (Some(0), Some(0)), "{layer}");
        assert_eq!(
            (s["loops_ccw"].as_u64(), s["loops_cw"].as_u64()),
            (Some(p.regions.len() as u64), Some(holes as u64)),
            "{layer}"
        );
        let area = num(&s["signed_area_mm2"]) * 1e-6;
        assert!(close(area, p.area, FILE_AREA_REL), "{layer}: DXF area {area} vs {}", p.area);
        let bb: Vec<f64> = s["bbox_mm"].as_array().unwrap().iter().map(num).collect();
        for (k, v) in [q.min[0], q.min[1], q.max[0], q.max[1]].into_iter().enumerate() {
            assert!((bb[k] * 1e-3 - v).abs() < 1e-9, "{layer}: bbox {bb:?} vs {q:?}");
        }
        // The ply's layer holds its cut loops alone: a cutter cuts the layer as it is.
        assert_eq!(s["lines"].as_u64().unwrap_or(0) + s["texts"].as_u64().unwrap_or(0), 0, "{layer}: loops only");
    }
    // Arrows (three lines a ply) and labels on their own layers.
    assert_eq!(d["by_layer"]["ARROWS"]["lines"], 3 * patterns.len());
    assert_eq!(d["by_layer"]["ARROWS"]["closed_polylines"], 0);
    assert_eq!(d["by_layer"]["LABELS"]["texts"], patterns.len());
    // Every label inside the roll, as ezdxf measures its text.
    let tb: Vec<f64> = d["by_layer"]["LABELS"]["text_bbox_mm"].as_array().unwrap().iter().map(num).collect();
    let (len_mm, w_mm) = (n.length * 1e3, n.roll_width * 1e3);
    assert!(
        tb[0] >= 0.0 && tb[1] >= 0.0 && tb[2] <= len_mm && tb[3] <= w_mm,
        "labels {tb:?} off the {len_mm} x {w_mm} mm roll"
    );
    let texts = d["by_layer"]["LABELS"]["text"].as_array().unwrap();
    for p in &patterns {
        let area = format!("area {:.6} m2", p.area);
        assert!(texts.iter().any(|t| t.as_str().unwrap().contains(&area)), "{area} in {texts:?}");
    }

    let s = &r[svg.to_str().unwrap()];
    assert_eq!(
        (s["width"].as_str().unwrap().ends_with("mm"), s["height"].as_str().unwrap().ends_with("mm")),
        (true, true)
    );
    let vb: Vec<f64> = s["viewbox"].as_array().unwrap().iter().map(num).collect();
    assert!(
        close(vb[2], n.length * 1e3 + 20.0, 1e-12) && close(vb[3], n.roll_width * 1e3 + 20.0, 1e-12),
        "viewBox {vb:?}"
    );
    assert!(s["groups"]["roll"].is_object());
    for (p, id) in patterns.iter().zip(&ids) {
        let g = &s["groups"][id.as_str()];
        assert_eq!(g["data_ply"], p.ply.as_str(), "{id}");
        assert_eq!(
            (g["cut_paths"].as_u64(), g["subpaths"].as_u64()),
            (Some(1), Some(p.loops().count() as u64)),
            "{id}"
        );
        assert_eq!((g["open_subpaths"].as_u64(), g["self_intersecting"].as_u64()), (Some(0), Some(0)), "{id}");
        assert_eq!(g["fill_rule"], "evenodd");
        assert_eq!(g["warp_segments"], 3);
        let area = num(&g["signed_area_mm2"]) * 1e-6;
        assert!(close(area, p.area, FILE_AREA_REL), "{id}: SVG area {area} vs {}", p.area);
    }

    let s = &r[one.to_str().unwrap()];
    let g = &s["groups"]["ply-ring"];
    let bb: Vec<f64> = g["bbox_mm"].as_array().unwrap().iter().map(num).collect();
    let p = &patterns[1];
    for (k, v) in [p.min[0], p.min[1], p.max[0], p.max[1]].into_iter().enumerate() {
        assert!((bb[k] * 1e-3 - v).abs() < 1e-9, "single-piece bbox {bb:?} vs {:?} {:?}", p.min, p.max);
    }
    assert!(close(num(&g["signed_area_mm2"]) * 1e-6, p.area, FILE_AREA_REL));
    assert!(s["groups"].get("roll").is_none());

    // The whole plan: nesting drawings and one SVG per ply, all readable.
    let plan = dir.path().join("plan");
    let paths = write_cutting_plan(&patterns, &n, &plan, "nest").unwrap();
    let names: Vec<String> = paths.iter().map(|p| p.file_name().unwrap().to_string_lossy().into_owned()).collect();
    assert_eq!(names[..3], ["nest.dxf", "nest.svg", "ply-hemi.svg"]);
    assert_eq!(names.len(), 2 + patterns.len());
    assert_eq!(std::fs::read(&paths[0]).unwrap(), std::fs::read(&dxf).unwrap(), "deterministic");
    let r = readback(&paths.iter().map(|p| p.as_path()).collect::<Vec<_>>());
    for (p, (path, id)) in patterns.iter().zip(paths[2..].iter().zip(&ids)) {
        let g = &r[path.to_str().unwrap()]["groups"][id.as_str()];
        assert!(close(num(&g["signed_area_mm2"]) * 1e-6, p.area, FILE_AREA_REL), "{id}");
    }
}

/// Largest turn (degrees) between consecutive edges of a pattern cut along a smooth outline of
/// N points: a polygon of N points round a convex curve turns by 360/N on average; the flat
/// image of a circle on the hemisphere is not a circle (the fabric shears), so some vertices
/// turn several times that, but nowhere near the 90 degree steps of a staircase of cells.
const MAX_OUTLINE_TURN_DEG: f64 = 10.0;

/// A circle of `n` points round the z axis at `z`, radius `r`, counter-clockwise seen from +z.
pub(crate) fn circle(r: f64, z: f64, n: usize) -> Vec<Point> {
    (0..n)
        .map(|k| {
            let t = k as f64 * std::f64::consts::TAU / n as f64;
            Point::new(r * t.cos(), r * t.sin(), z)
        })
        .collect()
}

#[test]
fn outline_ply_on_a_plate_is_cut_along_the_outline_itself() {
    let tool = shapes::plate(1.0, 1.0, 20, 20).into_surface().unwrap();
    let (r, d, n) = (0.2, 0.01, 180);
    let outline = circle(r, 0.0, n);
    let mut s = KinematicSettings::grid("disc", Point::origin(), Vector::x(), d, 3, 3);
    s.extent = Extent::Outline(outline.clone());
    let net = drape(&tool, &s).unwrap();
    let q = flat_pattern_in_outline(&net, &outline).unwrap();
    assert_eq!(q.cut, CutLine::Outline);
    assert_eq!((q.regions.len(), q.regions[0].loops.len(), q.regions[0].loops[0].len()), (1, 1, n));
    // On a plane the flat frame is the tool moved by the seed (here the origin): every vertex is
    // its outline point, in order.
    for (v, o) in q.regions[0].loops[0].iter().zip(&outline) {
        assert!((v[0] - o.x).abs() < LEN_EPS && (v[1] - o.y).abs() < LEN_EPS, "{v:?} vs {o:?}");
    }
    let want = shoelace_area(&outline.iter().map(|p| [p.x, p.y]).collect::<Vec<_>>());
    assert!((q.area - want).abs() <= 1e-9 * want, "area {} vs the outline's {want}", q.area);
    assert!((max_turn_deg(&q) - 360.0 / n as f64).abs() < 1e-6, "turn {}", max_turn_deg(&q));
    // Through the boundary nodes instead: chords inside the outline, less area.
    let p = flat_pattern(&net).unwrap();
    check_net_pattern(&p, &net);
    assert!(p.area < q.area && q.area - p.area < 2.0 * std::f64::consts::PI * r * d, "{} vs {}", p.area, q.area);
    // What the run cuts: the outline, also with a margin (offset from it); without an outline,
    // the smooth curve through the boundary nodes.
    assert_eq!(ply_pattern(&net, Some(&outline), 0.0).unwrap(), q);
    let smooth = flat_pattern_smooth(&net).unwrap();
    assert_eq!(ply_pattern(&net, None, 0.0).unwrap(), smooth);
    let m = ply_pattern(&net, Some(&outline), 0.003).unwrap();
    assert_eq!((m.cut, m.margin, m.warnings.len()), (CutLine::Outline, 0.003, 0));
    // An outline the net does not reach (twice as large) falls back to the smooth curve through
    // the boundary nodes, and says so.
    let far = flat_pattern_in_outline(&net, &circle(2.0 * r, 0.0, n)).unwrap();
    assert_eq!((far.cut, far.area), (CutLine::SmoothNodes, smooth.area));
    assert_eq!(far.warnings, vec![CutWarning::OutlineOffNet { point: 0, of: n }]);
}

/// The chords through the boundary nodes follow a circle without the staircase of whole cells:
/// the cut turns by at most 45 degrees at a node (the staircase by 90 at every step), and leaves
/// out of the disc exactly the half cells' area less than the staircase does.
#[test]
fn boundary_nodes_cut_chords_not_a_staircase() {
    let tool = shapes::plate(1.0, 1.0, 20, 20).into_surface().unwrap();
    let (r, d) = (0.2, 0.01);
    let mut s = KinematicSettings::grid("disc", Point::origin(), Vector::x(), d, 3, 3);
    s.extent = Extent::Outline(circle(r, 0.0, 360));
    let net = drape(&tool, &s).unwrap();
    let p = flat_pattern(&net).unwrap();
    check_net_pattern(&p, &net);
    let disc = shoelace_area(&circle(r, 0.0, 360).iter().map(|p| [p.x, p.y]).collect::<Vec<_>>());
    let staircase = complete_cells(&net) as f64 * d * d;
    let (left_out, stairs_left_out) = (disc - p.area, disc - staircase);
    println!(
        "disc {disc}: chords leave out {left_out}, the staircase {stairs_left_out}, max turn {}",
        max_turn_deg(&p)
    );
    assert!(p.half_cells > 0);
    let halves = p.half_cells as f64 * 0.5 * d * d;
    assert!(left_out > 0.0 && (stairs_left_out - left_out - halves).abs() < 1e-12, "{left_out} vs {stairs_left_out}");
    assert!(max_turn_deg(&p) <= 45.0 + 1e-9, "turns by {} deg", max_turn_deg(&p));
    // Every vertex is a node inside the outline.
    assert!(p.loops().flatten().all(|v| v[0].hypot(v[1]) < r), "a vertex outside the disc");
}

#[test]
fn hemisphere_disc_outline_is_cut_along_its_flattened_outline() {
    let (theta, d, n) = (0.5f64, 0.02, 240);
    let outline = circle(theta.sin(), theta.cos(), n);
    let mut s = KinematicSettings::grid("cap", Point::new(0.0, 0.0, 1.0), Vector::x(), d, 3, 3);
    s.extent = Extent::Outline(outline.clone());
    let net = drape(hemisphere(), &s).unwrap();
    let q = flat_pattern_in_outline(&net, &outline).unwrap();
    assert_eq!(q.cut, CutLine::Outline);
    assert_eq!((q.regions.len(), q.regions[0].loops.len(), q.regions[0].loops[0].len()), (1, 1, n));
    let turn = max_turn_deg(&q);
    let l = &q.regions[0].loops[0];
    let perimeter: f64 = (0..n).map(|k| (l[(k + 1) % n][0] - l[k][0]).hypot(l[(k + 1) % n][1] - l[k][1])).sum();
    let p = flat_pattern(&net).unwrap();
    check_net_pattern(&p, &net);
    println!("cap: outline cut {} m2 (max turn {turn} deg, perimeter {perimeter}), nodes {} m2", q.area, p.area);
    assert!(turn < MAX_OUTLINE_TURN_DEG, "largest turn {turn} deg");
    // The outline runs through the band of cells whose outer corners were refused: it encloses
    // the cut through the boundary nodes and lies within a cell's diagonal of it.
    assert!(q.area > p.area && q.area - p.area < perimeter * std::f64::consts::SQRT_2 * d, "{} vs {}", q.area, p.area);
    // The fabric the layup table counts is this cut.
    let tool_outline = drape::kinematic::outline::Outline::new(hemisphere(), &outline, d).unwrap();
    let stats = drape::layup::stack::ply_stats(&net, hemisphere(), Some(&tool_outline), 0.5, None);
    assert_eq!(stats.fabric_area, q.area);
    assert!(!q.loops().flatten().flatten().any(|v| v.is_nan()));

    // The drawing: the ply's layer holds one closed loop, of that area, turning smoothly.
    let nesting = nest(std::slice::from_ref(&q), 2.0, 0.01, Rotation::WarpAlongRoll).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let dxf = dir.path().join("cap.dxf");
    write_dxf(std::slice::from_ref(&q), &nesting, &dxf).unwrap();
    if !python_ready() {
        return;
    }
    let r = readback(&[&dxf]);
    let layer = &r[dxf.to_str().unwrap()]["by_layer"]["cap"];
    assert_eq!((layer["closed_polylines"].as_u64(), layer["open_polylines"].as_u64()), (Some(1), Some(0)));
    assert_eq!((layer["vertices"].as_u64(), layer["self_intersecting"].as_u64()), (Some(n as u64), Some(0)));
    let area = num(&layer["signed_area_mm2"]) * 1e-6;
    assert!(close(area, q.area, FILE_AREA_REL), "DXF area {area} vs {}", q.area);
    let dxf_turn = num(&layer["max_turn_deg"]);
    assert!(dxf_turn < MAX_OUTLINE_TURN_DEG, "DXF turns by {dxf_turn} deg");
}
