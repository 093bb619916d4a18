//! Forming a flat blank by tools in motion (issue 33): a punch with a stroke, a binder, a die.
use drape::geometry::{shapes, TriangleMesh};
use drape::kinematic::provenance::DrawIn;
use std::path::Path;

use crate::common::read_json;

/// Write the tools and `scene` into `dir` and run it: the CLI's output, layup.json's first row
/// and that ply's net JSON.
fn run(dir: &Path, tools: &[(&str, &TriangleMesh)], scene: &str) -> (String, serde_json::Value, serde_json::Value) {
    let (out, stdout) = crate::common::run_scene(dir, tools, scene);
    let row = read_json(&out.join("layup.json"))["plies"][0].clone();
    let name = row["name"].as_str().unwrap().to_string();
    (stdout, row, read_json(&out.join(format!("{name}.drape.json"))))
}

/// The fabric's path over a cylindrical punch of radius `r` raised `h` above the binder's plane,
/// from one edge of the binder's opening (half-width `a`) to the top: a straight span tangent
/// to the punch, then the arc over it (the fibres keep their length, so the blank's edge draws
/// in by this less `a`).
fn half_path(r: f64, h: f64, a: f64) -> f64 {
    // The edge seen from the punch's axis, which lies r - h below the plane.
    let d = (a * a + (r - h) * (r - h)).sqrt();
    let tangent = (d * d - r * r).sqrt();
    let edge_elevation = (r - h).atan2(a);
    let touch_elevation = edge_elevation + (r / d).acos();
    tangent + r * (std::f64::consts::FRAC_PI_2 - touch_elevation)
}

/// A cylindrical punch rises into a blank clamped by a binder outside a slot across it: the
/// fibres across the punch are developable and keep their length, so the blank's edges draw in
/// by the path over the punch less the opening's half-width, on both sides alike, for other
/// radii, strokes and openings; every node of the blank is present at the end, none inside the
/// punch, and those the binder still grips lie in its plane.
#[test]
fn a_punch_rising_into_a_clamped_blank_draws_in_its_path_over_the_punch() {
    // Allowed error against the exact draw-in, relative: the fabric's stretch under the binder's
    // friction (40 N/m against 8e6 N/m), the bend at the binder's edge rounded by bending over
    // about sqrt(B/T) = 2 mm, and the net's chords on the punch.
    const DRAW_IN_SHARE: f64 = 0.02;
    for (r, h, a) in [(0.05, 0.03, 0.1), (0.04, 0.025, 0.07)] {
        let tmp = tempfile::tempdir().unwrap();
        let punch = shapes::cylinder(r, 0.2, std::f64::consts::PI, 96, 40);
        let spacing = 0.005;
        let scene = format!(
            "units = \"m\"\ntool = \"punch.obj\"\nfriction = 0.2\n\
             [[ply]]\nname = \"p\"\norigin = [0.0, 0.0, {r}]\nwarp = [1.0, 0.0, 0.0]\n\
             material = \"{card}\"\nspacing = {spacing}\ngrid = [61, 21]\nmethod = \"mechanical\"\n\
             mode = \"pressed\"\nstart = \"flat\"\nstroke = [0.0, 0.0, {h}]\nmax_iterations = 2000\n\
             [ply.binder]\npressure = 2.0e3\noutline = [[-{a}, -1.0], [{a}, -1.0], [{a}, 1.0], [-{a}, 1.0]]\n",
            card = Path::new(env!("CARGO_MANIFEST_DIR")).join("materials/glass-plain-weave.toml").display()
        );
        let (stdout, row, net) = run(tmp.path(), &[("punch.obj", &punch)], &scene);
        assert_eq!(net["meta"]["solver"]["converged"], true, "{stdout}");
        let draw_in: DrawIn = serde_json::from_value(row["draw_in"].clone()).unwrap();
        let exact = half_path(r, h, a) - a;
        let along_warp: Vec<f64> =
            draw_in.edges.iter().filter(|e| e.line.is_fibre() && e.flat_m > 0.1).map(|e| e.draw_in_m).collect();
        assert_eq!(along_warp.len(), 2, "{draw_in:?}");
        for d in &along_warp {
            assert!(
                (d - exact).abs() < DRAW_IN_SHARE * exact,
                "R {r}, stroke {h}, opening {a}: the edge drew in {d} m, exactly {exact} m\n{stdout}"
            );
        }
        // The whole blank is formed: every node placed, none inside the punch where it ends.
        assert_eq!(net["status"]["placed"], 61 * 21, "{}", net["status"]);
        for p in net["nodes"].as_array().unwrap() {
            let p: Vec<f64> = p.as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect();
            let inside = r - (p[0] * p[0] + p[2] * p[2]).sqrt();
            assert!(p[2] < 0.0 || inside < 1e-6 * r, "node {p:?} is inside the punch by {inside} m");
            // Outside the opening the binder holds the blank in its plane (where the punch's top
            // stood at the start).
            if p[0].abs() > a + spacing {
                assert!((p[2] - (r - h)).abs() < 1e-9, "node {p:?} left the binder's plane");
            }
        }
    }
}

/// What a formed blank needs, and what only a formed blank takes, are refused by name.
#[test]
fn forming_keys_are_checked_before_anything_runs() {
    let tmp = tempfile::tempdir().unwrap();
    std::fs::write(tmp.path().join("punch.obj"), shapes::hemisphere(0.075, 12).to_obj_string()).unwrap();
    let card = Path::new(env!("CARGO_MANIFEST_DIR")).join("materials/glass-plain-weave.toml");
    let head = format!(
        "units = \"m\"\ntool = \"punch.obj\"\n[[ply]]\nname = \"p\"\norigin = [0.0, 0.0, 0.075]\n\
         material = \"{}\"\nspacing = 0.01\ngrid = [21, 21]\nmethod = \"mechanical\"\n",
        card.display()
    );
    for (tail, field, says) in [
        ("mode = \"pressed\"\nstart = \"flat\"\n", "stroke", "formed by the tool's stroke"),
        ("mode = \"free\"\nstart = \"flat\"\nstroke = [0.0, 0.0, 0.05]\n", "stroke", "only a flat blank formed"),
        ("stroke = [0.0, 0.0, 0.05]\n", "stroke", "only a flat blank formed"),
        ("mode = \"pressed\"\nstart = \"flat\"\nstroke = [0.0, 0.0, 0.0]\n", "stroke", "non-zero"),
        (
            "mode = \"pressed\"\nstart = \"flat\"\nstroke = [0.0, 0.0, 0.05]\n[ply.binder]\npressure = 1e4\noutline = [[0.1, 0.1], [0.2, 0.1], [0.2, 0.2]]\n",
            "binder",
            "outside its opening",
        ),
        (
            "mode = \"pressed\"\nstart = \"flat\"\nstroke = [0.0, 0.0, 0.05]\n[ply.binder]\npressure = -1.0\noutline = [[-0.1, -0.1], [0.1, -0.1], [0.1, 0.1]]\n",
            "binder",
            "pressure",
        ),
        ("mode = \"pressed\"\nstart = \"flat\"\nstroke = [0.0, 0.0, 0.05]\ndie = \"nothing.obj\"\n", "die", "nothing.obj"),
    ] {
        std::fs::write(tmp.path().join("scene.toml"), format!("{head}{tail}")).unwrap();
        let run = assert_cmd::Command::cargo_bin("drape")
            .unwrap()
            .arg("run")
            .arg(tmp.path().join("scene.toml"))
            .arg("--out")
            .arg(tmp.path().join("out"))
            .assert()
            .code(2);
        let err = String::from_utf8_lossy(&run.get_output().stderr).to_string();
        assert!(err.contains(&format!("field `{field}`")) && err.contains(says), "{tail}: {err}");
    }
}

/// A hemispherical punch rising into a square blank of a balanced fabric clamped outside a round
/// opening: the set-up is symmetric about the x and y planes and about the diagonal (warp and
/// weft swap), so is the formed blank, within a share of the spacing; the whole blank is
/// present, none of it inside the punch, and its edge draws in most along the fibres.
#[test]
fn a_hemisphere_formed_from_a_clamped_blank_keeps_the_set_ups_symmetries() {
    // The mirror images agree to this share of the spacing: the tools and the grid are
    // symmetric, so mirror nodes see the same arithmetic up to rounding (1.7e-12 spacings
    // measured).
    const MIRROR_SPACINGS: f64 = 1e-6;
    let (r, stroke, n, spacing) = (0.06, 0.035, 25, 0.01);
    let tmp = tempfile::tempdir().unwrap();
    let punch = shapes::hemisphere(r, 24);
    let opening: Vec<String> = (0..24)
        .map(|k| {
            let t = std::f64::consts::TAU * k as f64 / 24.0;
            format!("[{:.6}, {:.6}]", 0.085 * t.cos(), 0.085 * t.sin())
        })
        .collect();
    let scene = format!(
        "units = \"m\"\ntool = \"punch.obj\"\nfriction = 0.2\n\
         [[ply]]\nname = \"p\"\norigin = [0.0, 0.0, {r}]\nwarp = [1.0, 0.0, 0.0]\n\
         material = \"{card}\"\nspacing = {spacing}\ngrid = [{n}, {n}]\nmethod = \"mechanical\"\n\
         mode = \"pressed\"\nstart = \"flat\"\nstroke = [0.0, 0.0, {stroke}]\nmax_iterations = 2000\n\
         [ply.binder]\npressure = 1.0e4\noutline = [{}]\n",
        opening.join(", "),
        card = Path::new(env!("CARGO_MANIFEST_DIR")).join("materials/glass-plain-weave.toml").display()
    );
    let (stdout, row, net) = run(tmp.path(), &[("punch.obj", &punch)], &scene);
    assert_eq!(net["meta"]["solver"]["converged"], true, "{stdout}");
    assert_eq!(net["status"]["placed"], n * n, "{}", net["status"]);
    let x: Vec<[f64; 3]> = net["nodes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| {
            let p = p.as_array().unwrap();
            [0, 1, 2].map(|c| p[c].as_f64().unwrap())
        })
        .collect();
    // The nodes meet the punch's smooth surface, which lies within this share of the radius of
    // the sphere its facets stand for (their sagitta is 5e-4 R at 24 subdivisions).
    const SMOOTH_SHARE: f64 = 1e-4;
    for p in &x {
        let inside = r - (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
        assert!(p[2] < 0.0 || inside < SMOOTH_SHARE * r, "node {p:?} is inside the punch by {inside} m");
    }
    let at = |i: usize, j: usize| x[i * n + j];
    let mut worst: f64 = 0.0;
    for i in 0..n {
        for j in 0..n {
            let p = at(i, j);
            for (q, image) in [
                (at(n - 1 - i, j), [-p[0], p[1], p[2]]),
                (at(i, n - 1 - j), [p[0], -p[1], p[2]]),
                (at(j, i), [p[1], p[0], p[2]]),
            ] {
                let d = ((q[0] - image[0]).powi(2) + (q[1] - image[1]).powi(2) + (q[2] - image[2]).powi(2)).sqrt();
                worst = worst.max(d);
            }
        }
    }
    assert!(worst < MIRROR_SPACINGS * spacing, "mirror images differ by {worst} m\n{stdout}");
    let draw_in: DrawIn = serde_json::from_value(row["draw_in"].clone()).unwrap();
    let most = |fibre: bool| {
        draw_in.edges.iter().filter(|e| e.line.is_fibre() == fibre).map(|e| e.draw_in_m).fold(0.0, f64::max)
    };
    assert!(most(true) > 2.0 * most(false), "{draw_in:?}");
}

/// A hemispherical punch drawn through a die's opening with an entry fillet (R 60 mm into R 66 mm,
/// a 6 mm fillet, eight facets over its quarter turn) from a blank clamped on the die's face: it
/// converges, no node is inside the punch or the die, those the binder grips lie in the die's
/// plane, and the set-up's mirror symmetries hold as far as the die's facets allow. On the die's
/// facets (each turning by 11 deg round the fillet) it stopped at the iteration limit in its
/// seventh increment; on its smooth surface it converges in 320 iterations.
#[test]
fn a_hemisphere_drawn_through_a_die_with_an_entry_fillet_stays_out_of_both_tools() {
    let (r, opening, fillet, stroke, n, spacing) = (0.06, 0.066, 0.006, 0.04, 29, 0.01);
    let face = r - stroke;
    let tmp = tempfile::tempdir().unwrap();
    let punch = shapes::hemisphere(r, 24);
    let mut die = shapes::die_ring(opening, fillet, 0.2, 0.06, 192, [8, 8, 10]);
    die.vertices.iter_mut().for_each(|v| v.z += face);
    let binder = 0.08;
    let outline: Vec<String> = (0..24)
        .map(|k| {
            let t = std::f64::consts::TAU * k as f64 / 24.0;
            format!("[{:.6}, {:.6}]", binder * t.cos(), binder * t.sin())
        })
        .collect();
    let scene = format!(
        "units = \"m\"\ntool = \"punch.obj\"\nfriction = 0.2\n\
         [[ply]]\nname = \"p\"\norigin = [0.0, 0.0, {r}]\nwarp = [1.0, 0.0, 0.0]\n\
         material = \"{card}\"\nspacing = {spacing}\ngrid = [{n}, {n}]\nmethod = \"mechanical\"\n\
         mode = \"pressed\"\nstart = \"flat\"\nstroke = [0.0, 0.0, {stroke}]\ndie = \"die.obj\"\n\
         max_iterations = 2000\n[ply.binder]\npressure = 1.0e4\noutline = [{}]\n",
        outline.join(", "),
        card = Path::new(env!("CARGO_MANIFEST_DIR")).join("materials/glass-plain-weave.toml").display()
    );
    let (stdout, _, net) = run(tmp.path(), &[("punch.obj", &punch), ("die.obj", &die)], &scene);
    assert_eq!(net["meta"]["solver"]["converged"], true, "{stdout}");
    assert_eq!(net["status"]["placed"], n * n, "{}", net["status"]);
    let x: Vec<[f64; 3]> = net["nodes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| {
            let p = p.as_array().unwrap();
            [0, 1, 2].map(|c| p[c].as_f64().unwrap())
        })
        .collect();
    // Out of the punch (its smooth surface lies within 1e-4 R of the sphere) and the die (within
    // its fillet's torus and its wall, its smooth surface within a sagitta of the facets).
    let sagitta = {
        let chord = fillet * std::f64::consts::FRAC_PI_2 / 7.0;
        chord * chord / (8.0 * fillet)
    };
    for p in &x {
        let inside = r - (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
        assert!(p[2] < 0.0 || inside < 1e-4 * r, "node {p:?} is inside the punch by {inside} m");
        let rho = p[0].hypot(p[1]);
        // How far into the die's solid (above the face, outside the wall, inside the fillet's
        // quarter torus round the opening's edge).
        let into_die = if rho > opening + fillet {
            p[2] - face
        } else if p[2] > face + fillet {
            rho - opening
        } else if rho >= opening && p[2] >= face {
            fillet - (rho - opening - fillet).hypot(p[2] - face - fillet)
        } else {
            (rho - opening).min(p[2] - face)
        };
        assert!(into_die < sagitta, "node {p:?} is inside the die by {into_die} m");
        if rho > binder + spacing {
            assert!((p[2] - face).abs() < 1e-9, "node {p:?} left the binder's plane");
        }
    }
    let at = |i: usize, j: usize| x[i * n + j];
    let mut worst: f64 = 0.0;
    for i in 0..n {
        for j in 0..n {
            let p = at(i, j);
            for (q, image) in [
                (at(n - 1 - i, j), [-p[0], p[1], p[2]]),
                (at(i, n - 1 - j), [p[0], -p[1], p[2]]),
                (at(j, i), [p[1], p[0], p[2]]),
            ] {
                let d = ((q[0] - image[0]).powi(2) + (q[1] - image[1]).powi(2) + (q[2] - image[2]).powi(2)).sqrt();
                worst = worst.max(d);
            }
        }
    }
    // The die's quads are split along one diagonal each, so mirror facets are not images of each
    // other and neither are their smooth surfaces (0.02 spacings measured; 1.7e-12 with the
    // punch alone, above).
    const DIE_MIRROR_SPACINGS: f64 = 0.05;
    assert!(worst < DIE_MIRROR_SPACINGS * spacing, "mirror images differ by {worst} m\n{stdout}");
}
