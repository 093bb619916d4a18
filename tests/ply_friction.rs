//! Ply on ply (issue 33 item 6): in a layup each ply lies on the plies below it, and where they
//! cover the tool it meets them with `ply_friction`, the tool's `friction` elsewhere. Known
//! answers: on an incline the lower ply holds on the tool while the upper one slides on it
//! exactly when tan a exceeds `ply_friction`; a formed ply over a formed ply draws in and slips
//! less the more the plies grip each other, and `ply_friction = friction` is the run without it.
use drape::geometry::{shapes, Point, TriangleMesh};
use std::path::{Path, PathBuf};

use crate::common::read_json;

fn card() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("materials/glass-plain-weave.toml")
}

/// Write the tools and `scene` into `dir` and run it, whatever its exit code (a ply that slides
/// ends the run with 1 after writing what it has): the code, the output folder, the CLI's output.
fn run_any(dir: &Path, tools: &[(&str, &TriangleMesh)], scene: &str) -> (i32, PathBuf, String) {
    crate::common::write_scene(dir, tools, scene);
    let out = dir.join("out");
    let run = crate::common::drape_run(dir).output().unwrap();
    let text = format!("{}{}", String::from_utf8_lossy(&run.stdout), String::from_utf8_lossy(&run.stderr));
    (run.status.code().unwrap_or(-1), out, text)
}

/// The nodes of a net JSON.
fn nodes(net: &serde_json::Value) -> Vec<Point> {
    crate::common::all_nodes(net).into_iter().map(Point::from).collect()
}

/// A plate tilted by `a` about the x axis (downhill along -y), in facets of 5 mm: the surface
/// the upper ply lies on is flat only a facet or two inside the lower ply's edge (the smooth
/// patches round off the ramp there), so the facets are kept small against the margin by which
/// the lower ply is wider than the upper.
fn incline(a: f64) -> TriangleMesh {
    let TriangleMesh { vertices, triangles } = shapes::plate(0.5, 0.6, 100, 120);
    let (s, c) = a.sin_cos();
    let vertices = vertices.into_iter().map(|p| Point::new(p.x, p.y * c, p.y * s)).collect();
    TriangleMesh { vertices, triangles }
}

/// How far the nodes of an n x n net with spacing `d`, seeded at its middle node with its warp
/// along x on the plate tilted by `a`, lie from where the drape laid them (m, the largest): in
/// the plate's own coordinates the grid is square, centred on the seed.
fn moved_on_incline(net: &serde_json::Value, n: usize, d: f64, a: f64) -> f64 {
    let x = nodes(net);
    let (s, c) = a.sin_cos();
    let plan = |p: &Point| (p.x, p.y * c + p.z * s);
    let mid = n / 2;
    // The weft's sense on the plate (from two neighbours: a rigid slide does not change it).
    let (_, a0) = plan(&x[mid * n + mid]);
    let (_, a1) = plan(&x[mid * n + mid + 1]);
    let sense = if a1 > a0 { 1.0 } else { -1.0 };
    let mut worst: f64 = 0.0;
    for i in 0..n {
        for j in 0..n {
            let (u, v) = plan(&x[i * n + j]);
            let (eu, ev) = ((i as f64 - mid as f64) * d, sense * (j as f64 - mid as f64) * d);
            worst = worst.max(((u - eu).powi(2) + (v - ev).powi(2)).sqrt());
        }
    }
    worst
}

/// Within this share of tan a the coefficient needed to hold a sliding ply must be (the
/// issue's 5%).
const NEEDED_SHARE: f64 = 0.05;
/// A ply that holds moves no node further than this (m).
const HOLD_MOVE: f64 = 1e-3;

/// Two pressed plies on a plate tilted by a, the tool's friction above tan a: with
/// `ply_friction` below tan a the lower ply holds on the tool and the upper one slides on it
/// (the outcome `slides`, and the least `ply_friction` that would hold it is tan a); above,
/// both hold. At two angles.
#[test]
fn on_an_incline_the_upper_ply_slides_on_the_lower_exactly_when_tan_a_exceeds_ply_friction() {
    let (d, lower, upper) = (0.005, 41, 17);
    for a_deg in [12.0f64, 20.0] {
        let a = a_deg.to_radians();
        let critical = a.tan();
        let tool_mu = 1.3 * critical;
        for ply_mu in [0.8 * critical, 1.2 * critical] {
            let tmp = tempfile::tempdir().unwrap();
            let ply = |name: &str, n: usize| {
                format!(
                    "[[ply]]\nname = \"{name}\"\norigin = [0.0, 0.0, 0.0]\nwarp = [1.0, 0.0, 0.0]\n\
                     material = \"{}\"\nspacing = {d}\ngrid = [{n}, {n}]\nmethod = \"mechanical\"\n\
                     max_iterations = 300\n",
                    card().display()
                )
            };
            let scene = format!(
                "units = \"m\"\ntool = \"plate.obj\"\nfriction = {tool_mu}\nply_friction = {ply_mu}\n{}{}",
                ply("lower", lower),
                ply("upper", upper)
            );
            let (code, out, text) = run_any(tmp.path(), &[("plate.obj", &incline(a))], &scene);
            let below = read_json(&out.join("lower.drape.json"));
            let above = read_json(&out.join("upper.drape.json"));
            let plies = read_json(&out.join("layup.json"))["plies"].clone();
            let what = format!("{a_deg} deg, friction {tool_mu:.4}, ply_friction {ply_mu:.4}");
            // The lower ply holds on the tool either way, and meets no ply below.
            assert_eq!(below["meta"]["solver"]["converged"], true, "{what}: {text}");
            let moved = moved_on_incline(&below, lower, d, a);
            assert!(moved < HOLD_MOVE, "{what}: a node of the lower ply moved {moved} m\n{text}");
            assert!(below["meta"]["contact"].get("ply_friction").is_none(), "{what}");
            // The upper ply carries the coefficient it met the lower one with.
            assert_eq!(above["meta"]["contact"]["ply_friction"].as_f64(), Some(ply_mu), "{what}");
            assert_eq!(plies[1]["contact"]["ply_friction"].as_f64(), Some(ply_mu), "{what}");
            assert!(text.contains(&format!("ply_friction {ply_mu}")), "{what}: {text}");
            if ply_mu < critical {
                assert_eq!(code, 1, "{what}: {text}");
                assert_eq!(above["meta"]["solver"]["outcome"], "slides", "{what}: {text}");
                let needed = above["meta"]["contact"]["friction_needed"].as_f64().unwrap();
                assert_eq!(above["meta"]["contact"]["friction_needed_between"], "plies", "{what}");
                assert!(
                    (needed - critical).abs() < NEEDED_SHARE * critical,
                    "{what}: ply_friction {needed} needed, tan a = {critical}"
                );
                eprintln!("{what}: slides, ply_friction {needed:.4} needed (tan a {critical:.4})");
            } else {
                assert_eq!(code, 0, "{what}: {text}");
                assert_eq!(above["meta"]["solver"]["converged"], true, "{what}: {text}");
                let moved = moved_on_incline(&above, upper, d, a);
                assert!(moved < HOLD_MOVE, "{what}: a node of the upper ply moved {moved} m\n{text}");
                eprintln!("{what}: both hold, the upper ply's nodes moved at most {moved:.2e} m");
            }
        }
    }
}

/// A bad `ply_friction`, on the scene or on a ply, is refused by name before anything runs.
#[test]
fn a_bad_ply_friction_exits_2_naming_the_field() {
    let tmp = tempfile::tempdir().unwrap();
    std::fs::write(tmp.path().join("plate.obj"), shapes::plate(0.5, 0.5, 10, 10).to_obj_string()).unwrap();
    let ply = |extra: &str| {
        format!(
            "[[ply]]\nname = \"p\"\norigin = [0.0, 0.0, 0.0]\nmaterial = \"{}\"\nspacing = 0.01\ngrid = [11, 11]\n\
             method = \"mechanical\"\n{extra}",
            card().display()
        )
    };
    for scene in [
        format!("tool = \"plate.obj\"\nply_friction = -0.1\n{}", ply("")),
        format!("tool = \"plate.obj\"\n{}", ply("ply_friction = -1.0\n")),
        format!("tool = \"plate.obj\"\n{}", ply("ply_friction = inf\n")),
        format!("tool = \"plate.obj\"\n{}", ply("ply_friction = nan\n")),
    ] {
        let err = crate::common::refused_scene(tmp.path(), &scene);
        assert!(err.contains("field `ply_friction`") && err.contains(">= 0"), "{scene}: {err}");
        assert!(!tmp.path().join("out").exists(), "{scene}: nothing is written");
    }
}

/// The mean draw-in of the blank's two edges across the warp (m), from a layup.json row.
fn warp_draw_in(row: &serde_json::Value) -> f64 {
    let draw_in: drape::kinematic::provenance::DrawIn = serde_json::from_value(row["draw_in"].clone()).unwrap();
    let along: Vec<f64> =
        draw_in.edges.iter().filter(|e| e.line.is_fibre() && e.flat_m > 0.05).map(|e| e.draw_in_m).collect();
    assert_eq!(along.len(), 2, "{draw_in:?}");
    along.iter().sum::<f64>() / 2.0
}

/// Two blanks formed one over the other by a cylindrical punch rising into them, a binder
/// clamping them outside a slot: the upper one meets the lower with `ply_friction` on the punch
/// and under the binder. The more the plies grip each other, the less the upper blank slips over
/// the lower one and the less it draws in (the binder's lower face and the punch hold it back
/// harder); `ply_friction = friction` is the run without the key, node for node.
#[test]
fn a_blank_formed_over_a_blank_slips_and_draws_in_less_the_more_the_plies_grip() {
    let (r, h, a, spacing, friction) = (0.04, 0.02, 0.06, 0.005, 0.2);
    let punch = shapes::cylinder(r, 0.2, std::f64::consts::PI, 96, 40);
    let ply = |name: &str| {
        format!(
            "[[ply]]\nname = \"{name}\"\norigin = [0.0, 0.0, {r}]\nwarp = [1.0, 0.0, 0.0]\n\
             material = \"{}\"\nspacing = {spacing}\ngrid = [41, 13]\nmethod = \"mechanical\"\n\
             mode = \"pressed\"\nstart = \"flat\"\nstroke = [0.0, 0.0, {h}]\nmax_iterations = 2000\n\
             [ply.binder]\npressure = 2.0e4\noutline = [[-{a}, -1.0], [{a}, -1.0], [{a}, 1.0], [-{a}, 1.0]]\n",
            card().display()
        )
    };
    // The upper blank: its draw-in, its mean slip over what it lies on, its nodes.
    let form = |key: &str| {
        let tmp = tempfile::tempdir().unwrap();
        let scene = format!(
            "units = \"m\"\ntool = \"punch.obj\"\nfriction = {friction}\n{key}{}{}",
            ply("lower"),
            ply("upper")
        );
        let (code, out, text) = run_any(tmp.path(), &[("punch.obj", &punch)], &scene);
        assert_eq!(code, 0, "{key}: {text}");
        let net = read_json(&out.join("upper.drape.json"));
        assert_eq!(net["meta"]["solver"]["converged"], true, "{key}: {text}");
        let row = read_json(&out.join("layup.json"))["plies"][1].clone();
        let slips: Vec<f64> =
            net["meta"]["contact"]["slip_m"].as_array().unwrap().iter().filter_map(|s| s.as_f64()).collect();
        let mean_slip = slips.iter().sum::<f64>() / slips.len() as f64;
        (warp_draw_in(&row), mean_slip, nodes(&net))
    };
    let (_, _, without) = form("");
    let (same_draw, same_slip, same) = form(&format!("ply_friction = {friction}\n"));
    assert!(same == without, "ply_friction = friction changed the upper blank");
    let mut last = (same_draw, same_slip);
    eprintln!("ply_friction {friction}: draw-in {same_draw:.6} m, mean slip {same_slip:.6} m");
    for mu in [0.4, 0.8] {
        let (draw, slip, _) = form(&format!("ply_friction = {mu}\n"));
        eprintln!("ply_friction {mu}: draw-in {draw:.6} m, mean slip {slip:.6} m");
        assert!(draw < last.0 && slip < last.1, "ply_friction {mu}: draw-in {draw} m, slip {slip} m after {last:?}");
        last = (draw, slip);
    }
    let (draw, slip, _) = form("ply_friction = 0.05\n");
    eprintln!("ply_friction 0.05: draw-in {draw:.6} m, mean slip {slip:.6} m");
    assert!(draw > same_draw && slip > same_slip, "ply_friction 0.05: draw-in {draw} m, slip {slip} m");
}
