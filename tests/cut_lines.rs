//! Cutting lines a cutter can use: the smooth curve through a net's boundary nodes, the cutting
//! margin offset from the true cut line, the warning when a ply's outline cannot be carried
//! through its net, and labels inside their pieces.
//!
//! Known answers: a disc outline with a margin m is a circle of radius r + m, and the margin
//! curve lies at distance m from the cut everywhere; the smooth curve through the boundary nodes
//! of a disc drape is closer to the disc than the chords through the same nodes.
use super::flat_patterns::{circle, close, hemisphere, num, python_ready, readback, shape_net, FILE_AREA_REL};
use assert_cmd::Command;
use drape::geometry::{shapes, Point, Vector};
use drape::io::dxf::write_dxf;
use drape::kinematic::{drape, DrapeNet, Extent, KinematicSettings};
use drape::layup::curve::{distance_to_loops, first_crossing, turn, CORNER_TURN_DEG, OFFSET_ARC_TOL};
use drape::layup::flat::{
    flat_pattern, flat_pattern_smooth, ply_pattern, shoelace_area, with_margin, CutLine, CutWarning, FlatPattern,
};
use drape::layup::nest::{nest, Rotation};
use std::f64::consts::PI;

/// Points sampled on each edge of the loops of a pattern (ends and `k - 1` between).
fn samples(p: &FlatPattern, k: usize) -> Vec<[f64; 2]> {
    let mut out = Vec::new();
    for l in p.loops() {
        for e in 0..l.len() {
            let (a, b) = (l[e], l[(e + 1) % l.len()]);
            for s in 0..k {
                let t = s as f64 / k as f64;
                out.push([a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])]);
            }
        }
    }
    out
}

fn loops_of(p: &FlatPattern) -> Vec<Vec<[f64; 2]>> {
    p.loops().cloned().collect()
}

/// A disc ply of radius `r` on a plate, spacing `d`, its outline of `n` points.
fn disc_net(r: f64, d: f64, n: usize) -> (DrapeNet, Vec<Point>) {
    let tool = shapes::plate(1.0, 1.0, 20, 20).into_surface().unwrap();
    let outline = circle(r, 0.0, n);
    let mut s = KinematicSettings::grid("disc", Point::origin(), Vector::x(), d, 3, 3);
    s.extent = Extent::Outline(outline.clone());
    (drape(&tool, &s).unwrap(), outline)
}

/// Every sampled point of the margin curve is at distance `m` from the cut (the straight parts
/// exactly, the round joins' chords within OFFSET_ARC_TOL inside their arcs).
fn check_offset(cut: &FlatPattern, grown: &FlatPattern, m: f64) {
    let loops = loops_of(cut);
    let (mut lo, mut hi) = (f64::INFINITY, 0.0f64);
    for q in samples(grown, 8) {
        let dist = distance_to_loops(q, &loops);
        lo = lo.min(dist);
        hi = hi.max(dist);
    }
    println!("{}: margin {m}: distance from the cut {lo} .. {hi}", cut.ply);
    assert!(lo >= m - OFFSET_ARC_TOL - 1e-12 && hi <= m + 1e-12, "{}: distance {lo} .. {hi} for a margin {m}", cut.ply);
    assert!(first_crossing(&loops_of(grown)).is_none(), "{}: the margin curve crosses itself", cut.ply);
    assert_eq!((grown.margin, grown.cut, &grown.warnings), (m, cut.cut, &cut.warnings));
    let area: f64 = grown.loops().map(|l| shoelace_area(l)).sum();
    assert!((area - grown.area).abs() <= 1e-12 * area && grown.area > cut.area);
}

#[test]
fn a_margin_round_a_disc_outline_is_a_circle_of_radius_r_plus_m() {
    let (r, d, n, m) = (0.2, 0.01, 360, 0.01);
    let (net, outline) = disc_net(r, d, n);
    let cut = ply_pattern(&net, Some(&outline), 0.0).unwrap();
    let grown = ply_pattern(&net, Some(&outline), m).unwrap();
    assert_eq!((cut.cut, grown.regions.len(), grown.regions[0].loops.len()), (CutLine::Outline, 1, 1));
    check_offset(&cut, &grown, m);
    // The circle of radius r + m: its area, and every vertex on it to within the outline's own
    // chord error r (1 - cos(pi / n)) and the round joins' tolerance.
    let want = PI * (r + m) * (r + m);
    let rel = (grown.area - want).abs() / want;
    println!("disc + margin: area {} vs pi (r + m)^2 = {want} (relative {rel:e})", grown.area);
    assert!(rel < 2e-4, "area {} vs {want}", grown.area);
    let chord = r * (1.0 - (PI / n as f64).cos());
    for v in grown.loops().flatten() {
        let rho = v[0].hypot(v[1]);
        assert!((rho - (r + m)).abs() <= chord + OFFSET_ARC_TOL + 1e-12, "vertex {v:?} at radius {rho}");
    }
    // Not the staircase of grown cells: the bounding box is the circle's.
    for k in 0..2 {
        assert!(
            (grown.max[k] - (r + m)).abs() < 1e-6 && (grown.min[k] + r + m).abs() < 1e-6,
            "{:?} {:?}",
            grown.min,
            grown.max
        );
    }
}

#[test]
fn a_margin_round_the_smooth_cut_of_drapes_and_shapes() {
    // A hemisphere drape (the smooth curve through its boundary nodes) and an L of cells (a
    // concave corner, which the margin turns at the offset lines' meeting point).
    let h = drape(
        hemisphere(),
        &KinematicSettings::grid("hemi", Point::new(0.1, 0.0, 1.0), Vector::new(1.0, 0.3, 0.0), 0.05, 61, 61),
    )
    .unwrap();
    let l = shape_net("ell", 0.01, 21, 21, |i, j| i < 8 || j < 8);
    for (net, m) in [(&h, 0.02), (&h, 0.0123), (&l, 0.005), (&l, 0.03)] {
        let cut = flat_pattern_smooth(net).unwrap();
        assert_eq!(cut.cut, CutLine::SmoothNodes, "{}", net.name);
        let grown = ply_pattern(net, None, m).unwrap();
        check_offset(&cut, &grown, m);
        assert_eq!(with_margin(net, cut.clone(), m).unwrap(), grown);
    }
    // A rectangle (corners only, straight sides): A + P m + pi m^2, the four corners' quarter
    // circles less what their chords cut off.
    let m = 0.005;
    let rect = shape_net("rect", 0.01, 21, 11, |_, _| true);
    let grown = ply_pattern(&rect, None, m).unwrap();
    let want = 0.2 * 0.1 + 0.6 * m + PI * m * m;
    println!("rectangle + margin: area {} vs {want}", grown.area);
    assert!(grown.area <= want && want - grown.area < 2.0 * PI * m * OFFSET_ARC_TOL, "{} vs {want}", grown.area);
    // Two squares touching at a corner: their margins overlap, so the run grows the cells
    // instead and says so.
    // Two pieces 0.02 apart: a margin of 0.005 keeps them apart, one of 0.015 would overlap
    // them, so the run grows the cells instead and says so.
    let two = shape_net("two", 0.01, 21, 11, |i, _| !(8..10).contains(&i));
    let cut = flat_pattern_smooth(&two).unwrap();
    let p = ply_pattern(&two, None, 0.005).unwrap();
    assert_eq!(p.regions.len(), 2);
    check_offset(&cut, &p, 0.005);
    let p = ply_pattern(&two, None, 0.015).unwrap();
    assert_eq!((p.cut, p.margin, p.regions.len()), (CutLine::GrownCells, 0.015, 1));
    assert_eq!(p.warnings, vec![CutWarning::MarginOverlaps { margin: 0.015 }]);
}

/// Radial distance from the circle of radius r of points sampled along a pattern's loops:
/// (mean, largest).
fn radial_error(p: &FlatPattern, r: f64) -> (f64, f64) {
    let s = samples(p, 16);
    let e: Vec<f64> = s.iter().map(|v| (v[0].hypot(v[1]) - r).abs()).collect();
    (e.iter().sum::<f64>() / e.len() as f64, e.iter().fold(0.0, |a: f64, &b| a.max(b)))
}

#[test]
fn smooth_cut_through_the_boundary_nodes_follows_the_disc_closer_than_the_chords() {
    let (r, d) = (0.2, 0.01);
    let (net, _) = disc_net(r, d, 360);
    let chords = flat_pattern(&net).unwrap();
    let smooth = flat_pattern_smooth(&net).unwrap();
    assert_eq!((smooth.cut, smooth.regions.len(), smooth.regions[0].loops.len()), (CutLine::SmoothNodes, 1, 1));
    let disc = PI * r * r;
    let (cm, cx) = radial_error(&chords, r);
    let (sm, sx) = radial_error(&smooth, r);
    println!(
        "disc r = {r}, d = {d}: chords {} vertices, area {} (off by {}), radial error mean {cm} max {cx}; smooth {} vertices, area {} (off by {}), radial error mean {sm} max {sx}",
        chords.loops().next().unwrap().len(),
        chords.area,
        disc - chords.area,
        smooth.loops().next().unwrap().len(),
        smooth.area,
        disc - smooth.area
    );
    // Through every node of the chord polygon, closer to the circle than the chords.
    let s = smooth.loops().next().unwrap();
    assert!(chords.loops().next().unwrap().iter().all(|v| s.contains(v)));
    assert!((disc - smooth.area).abs() < disc - chords.area, "area");
    // The nodes themselves lie up to a cell inside the circle: the curve through them gains
    // between them (measured: mean 4.6 mm vs 4.9, largest 8.0 mm vs 10.0, area error 13 % less).
    assert!(sm < 0.95 * cm && sx < 0.9 * cx, "radial error {sm} / {sx} vs chords {cm} / {cx}");
    // Within a cell's diagonal of the circle everywhere, no loop: simple, and turning smoothly
    // (a circle has no corner).
    assert!(sx < std::f64::consts::SQRT_2 * d);
    assert!(first_crossing(&loops_of(&smooth)).is_none());
    let n = s.len();
    let worst = (0..n).map(|k| turn(s[(k + n - 1) % n], s[k], s[(k + 1) % n]).abs().to_degrees()).fold(0.0, f64::max);
    println!("smooth disc cut: largest turn {worst} deg");
    assert!(worst < 20.0, "turns by {worst} deg");
    // The fabric the layup table counts is this cut.
    assert_eq!(ply_pattern(&net, None, 0.0).unwrap().area, smooth.area);

    // Corners stay corners: a rectangle of cells is its own smooth cut; an L keeps its five
    // corners and straight sides, only the half cell's chord across its inner corner is rounded.
    let rect = shape_net("rect", 0.01, 21, 11, |_, _| true);
    assert_eq!(loops_of(&flat_pattern_smooth(&rect).unwrap()), loops_of(&flat_pattern(&rect).unwrap()));
    let l = shape_net("ell", 0.01, 21, 21, |i, j| i < 8 || j < 8);
    let (ls, lc) = (flat_pattern_smooth(&l).unwrap(), flat_pattern(&l).unwrap());
    let (sl, cl) = (&loops_of(&ls)[0], &loops_of(&lc)[0]);
    assert!(cl.iter().all(|v| sl.contains(v)));
    // Off the chords only round the half cell at the inner corner (node (8, 8), the seed node
    // (10, 10) at the origin: (-0.02, -0.02)), by less than a cell.
    for v in sl {
        let off = distance_to_loops(*v, &loops_of(&lc));
        assert!(
            off < 1e-12 || ((v[0] + 0.015).abs() < 0.01 && (v[1] + 0.015).abs() < 0.01 && off < 0.01),
            "{v:?} {off}"
        );
    }
    const { assert!(CORNER_TURN_DEG < 90.0) };

    // The DXF: one closed polyline on the ply's layer, simple, of that area.
    let nesting = nest(std::slice::from_ref(&smooth), 1.0, 0.01, Rotation::WarpAlongRoll).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let dxf = dir.path().join("disc.dxf");
    write_dxf(std::slice::from_ref(&smooth), &nesting, &dxf).unwrap();
    if !python_ready() {
        return;
    }
    let rb = readback(&[&dxf]);
    let layer = &rb[dxf.to_str().unwrap()]["by_layer"]["disc"];
    assert_eq!((layer["closed_polylines"].as_u64(), layer["open_polylines"].as_u64()), (Some(1), Some(0)));
    assert_eq!((layer["vertices"].as_u64(), layer["self_intersecting"].as_u64()), (Some(n as u64), Some(0)));
    assert!(close(num(&layer["signed_area_mm2"]) * 1e-6, smooth.area, FILE_AREA_REL));
    assert_eq!(layer["lines"].as_u64().unwrap_or(0) + layer["texts"].as_u64().unwrap_or(0), 0);
}

use crate::common::read_json;

/// A ply whose outline the net does not reach (its nodes stop at a shear limit before the rim)
/// is cut along the smooth curve through its boundary nodes, and the run says so: on its output,
/// in layup.json and in the report.
#[test]
fn an_outline_the_net_does_not_carry_is_a_visible_warning() {
    let dir = tempfile::tempdir().unwrap();
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let tool = root.join("geometries/hemisphere/hemisphere-2k.obj");
    // A circle near the rim of the R = 0.1 hemisphere; nodes shearing past 20 deg are refused,
    // so the net stops short of it along the diagonals.
    let (rr, z) = (0.095f64, (0.1f64 * 0.1 - 0.095 * 0.095).sqrt());
    let outline: Vec<String> = (0..72)
        .map(|k| {
            let t = k as f64 * std::f64::consts::TAU / 72.0;
            format!("[{}, {}, {}]", rr * t.cos(), rr * t.sin(), z)
        })
        .collect();
    let scene = dir.path().join("scene.toml");
    std::fs::write(
        &scene,
        format!(
            "units = \"m\"\ntool = \"{}\"\nroll_width = 1.0\ncutting_margin = 0.005\n\n[[ply]]\nname = \"cap\"\norigin = [0.0, 0.0, 0.1]\nwarp = [1.0, 0.0, 0.0]\nspacing = 0.004\noutline = [{}]\nmax_shear_deg = 20.0\nmethod = \"kinematic\"\n",
            tool.display(),
            outline.join(", ")
        ),
    )
    .unwrap();
    let out = dir.path().join("out");
    let run = Command::cargo_bin("drape")
        .unwrap()
        .args(["run", scene.to_str().unwrap(), "--out", out.to_str().unwrap(), "--format", "json"])
        .assert()
        .success();
    let stdout = String::from_utf8_lossy(&run.get_output().stdout).to_string();
    println!("{stdout}");
    assert!(
        stdout.contains("warning: ply 'cap': flat pattern: outline point") && stdout.contains("not along the outline"),
        "{stdout}"
    );
    let layup = read_json(&out.join("layup.json"));
    let row = &layup["plies"][0];
    assert_eq!(row["pattern_cut"], "smooth_nodes");
    assert_eq!(row["pattern_margin_m"], 0.005);
    let w = &row["pattern_warnings"][0];
    assert_eq!((w["kind"].as_str(), w["of"].as_u64()), (Some("outline_off_net"), Some(72)), "{row}");
    assert!(w["point"].as_u64().unwrap() < 72);
    // The report's flat-pattern section shows it.
    let report = dir.path().join("report");
    Command::cargo_bin("drape")
        .unwrap()
        .args(["report", out.to_str().unwrap(), "--out", report.to_str().unwrap()])
        .assert()
        .success();
    let html = std::fs::read_to_string(report.join("index.html")).unwrap();
    let at = html.find("id=\"patterns\"").expect("a flat-pattern section");
    let section = &html[at..];
    assert!(
        section.contains("<ul id=\"pattern-warnings\"") && section.contains("warning: ply cap: outline point"),
        "{section}"
    );

    // A ply the net carries to its outline has no warning, and layup.json none either.
    let ok = dir.path().join("ok.toml");
    std::fs::write(&ok, std::fs::read_to_string(&scene).unwrap().replace("max_shear_deg = 20.0\n", "")).unwrap();
    let out2 = dir.path().join("out2");
    let run = Command::cargo_bin("drape")
        .unwrap()
        .args(["run", ok.to_str().unwrap(), "--out", out2.to_str().unwrap(), "--format", "json"])
        .assert()
        .success();
    let stdout = String::from_utf8_lossy(&run.get_output().stdout).to_string();
    assert!(!stdout.contains("flat pattern: "), "{stdout}");
    let row = &read_json(&out2.join("layup.json"))["plies"][0];
    assert_eq!((row["pattern_cut"].as_str(), row.get("pattern_warnings")), (Some("outline"), None), "{row}");
}
