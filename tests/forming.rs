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
        let err = crate::common::refused_scene(tmp.path(), &format!("{head}{tail}"));
        assert!(err.contains(&format!("field `{field}`")) && err.contains(says), "{tail}: {err}");
    }
}

/// The largest distance (m) of a square n x n net's nodes `x` from the images of their mirror
/// nodes in the x and y planes and in the diagonal (warp and weft swapped).
fn mirror_error(x: &[[f64; 3]], n: usize) -> f64 {
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
    worst
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
    let x = crate::common::all_nodes(&net);
    // The nodes meet the punch's smooth surface, which lies within this share of the radius of
    // the sphere its facets stand for (their sagitta is 5e-4 R at 24 subdivisions).
    const SMOOTH_SHARE: f64 = 1e-4;
    for p in &x {
        let inside = r - (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
        assert!(p[2] < 0.0 || inside < SMOOTH_SHARE * r, "node {p:?} is inside the punch by {inside} m");
    }
    let worst = mirror_error(&x, n);
    assert!(worst < MIRROR_SPACINGS * spacing, "mirror images differ by {worst} m\n{stdout}");
    let draw_in: DrawIn = serde_json::from_value(row["draw_in"].clone()).unwrap();
    let most = |fibre: bool| {
        draw_in.edges.iter().filter(|e| e.line.is_fibre() == fibre).map(|e| e.draw_in_m).fold(0.0, f64::max)
    };
    assert!(most(true) > 2.0 * most(false), "{draw_in:?}");
    // The net records how it was formed, and the report says so and draws the binder's opening
    // beside the draw-in.
    let formed = &net["meta"]["forming"];
    assert_eq!(formed["stroke_m"], serde_json::json!([0.0, 0.0, stroke]), "{formed}");
    let increments = net["meta"]["solver"]["increments"].as_array().unwrap();
    assert_eq!(formed["increments"], increments.len(), "{formed}");
    // Each increment says how many of the solver's iterations it took.
    let per_increment: u64 = increments.iter().map(|i| i["iterations"].as_u64().unwrap()).sum();
    assert_eq!(per_increment, net["meta"]["solver"]["iterations"].as_u64().unwrap());
    assert_eq!(formed["die"], false);
    assert_eq!(formed["binder"]["pressure_pa"], 1.0e4);
    assert_eq!(formed["binder"]["outline_m"].as_array().unwrap().len(), 24);
    let out = tmp.path().join("out");
    assert_cmd::Command::cargo_bin("drape").unwrap().arg("report").arg(&out).assert().success();
    let page = std::fs::read_to_string(out.join("report/index.html")).unwrap();
    assert!(page.contains("stroke (0.0, 0.0, 35.0) mm in"), "the report does not say how the ply was formed");
    assert!(page.contains("binder at 10.0 kPa"), "the report does not name the binder");
    let svg = std::fs::read_to_string(out.join("report/p-draw-in.svg")).unwrap();
    assert!(
        svg.contains("the binder&apos;s opening") || svg.contains("the binder's opening"),
        "no binder in the draw-in picture"
    );
}

/// The binder's opening round a double dome's body: a stadium `clearance` outside its foot, in
/// `segments` straight pieces per rounded end, as the scene's `outline` value.
fn stadium_opening(p: &shapes::DoubleDome, clearance: f64, segments: usize) -> String {
    let r = p.body_width / 2.0 + clearance;
    let a = p.body_length / 2.0 - p.body_width / 2.0;
    let mut corners = Vec::new();
    for (centre, start) in [(a, -std::f64::consts::FRAC_PI_2), (-a, std::f64::consts::FRAC_PI_2)] {
        for k in 0..=segments {
            let t = start + std::f64::consts::PI * k as f64 / segments as f64;
            corners.push(format!("[{:.6}, {:.6}]", centre + r * t.cos(), r * t.sin()));
        }
    }
    format!("[{}]", corners.join(", "))
}

/// The +/-45 plies of a double dome (not the bundled one: other proportions) formed from flat
/// blanks cut square to the part, the part rising through a binder's opening: each converges
/// to a minimum with its whole blank present, none of it inside the part, the blank under the
/// binder still in its plane; each is symmetric under the half turn about the part's axis, and
/// the -45 ply is the +45 ply's mirror image (the set-up's mirror maps one onto the other).
#[test]
fn a_double_domes_plus_minus_45_plies_formed_with_a_binder_mirror_each_other() {
    // Mirror and half-turn images agree to this share of the spacing: the tool, the blank and
    // the binder are symmetric, so image nodes see the same arithmetic up to rounding.
    const IMAGE_SPACINGS: f64 = 1e-6;
    // The nodes meet the part's smooth surface, within this of its height field (the facets'
    // sagitta on the fillets; the smooth surface lies between them and the exact part).
    const SURFACE_TOLERANCE: f64 = 2e-4;
    let dome = shapes::DoubleDome {
        flange_length: 0.3,
        flange_width: 0.24,
        body_length: 0.17,
        body_width: 0.09,
        height: 0.035,
        wall_angle: 60f64.to_radians(),
        base_fillet: 0.01,
        top_fillet: 0.012,
    };
    let tool = shapes::double_dome(&dome, 36);
    let (spacing, n) = (0.01, 37);
    // The blank: 0.26 x 0.2 m square to the part, in each ply's fabric coordinates.
    let (hx, hy) = (0.13, 0.1);
    let s = std::f64::consts::FRAC_1_SQRT_2;
    let corners = [(hx, hy), (-hx, hy), (-hx, -hy), (hx, -hy)];
    let blank = |angle: f64| {
        let c: Vec<String> = corners
            .iter()
            .map(|&(x, y)| {
                // u along the warp (x turned by the angle), v along the weft (90 deg further).
                let (u, v) = if angle > 0.0 { ((x + y) * s, (y - x) * s) } else { ((x - y) * s, (x + y) * s) };
                format!("[{u:.6}, {v:.6}]")
            })
            .collect();
        format!("[{}]", c.join(", "))
    };
    let opening = stadium_opening(&dome, 0.015, 8);
    let form = |angle: f64| {
        let tmp = tempfile::tempdir().unwrap();
        let scene = format!(
            "units = \"m\"\ntool = \"part.obj\"\nreference = [1.0, 0.0, 0.0]\nfriction = 0.2\n\
             [[ply]]\nname = \"p\"\norigin = [0.0, 0.0, {h}]\nangle_deg = {angle}\n\
             material = \"{card}\"\nspacing = {spacing}\ngrid = [{n}, {n}]\nmethod = \"mechanical\"\n\
             mode = \"pressed\"\nstart = \"flat\"\nstroke = [0.0, 0.0, {h}]\nblank = {b}\nmax_iterations = 2000\n\
             [ply.binder]\npressure = 2.0e4\noutline = {opening}\n",
            h = dome.height,
            b = blank(angle),
            card = Path::new(env!("CARGO_MANIFEST_DIR")).join("materials/carbon-twill.toml").display()
        );
        let (stdout, _, net) = run(tmp.path(), &[("part.obj", &tool)], &scene);
        assert_eq!(net["meta"]["solver"]["converged"], true, "{angle} deg: {stdout}");
        assert_eq!(net["meta"]["solver"]["stability"], "minimum", "{angle} deg: {stdout}");
        // The whole blank is formed: every node of the grid is placed or cut away by the blank.
        let status = &net["status"];
        let cut = status["failed"]["outside_outline"].as_u64().unwrap_or(0);
        assert_eq!(status["placed"].as_u64().unwrap() + cut, (n * n) as u64, "{status}");
        let x: Vec<Option<[f64; 3]>> = net["nodes"]
            .as_array()
            .unwrap()
            .iter()
            .map(|p| p.as_array().map(|p| [0, 1, 2].map(|c| p[c].as_f64().unwrap())))
            .collect();
        for p in x.iter().flatten() {
            let below = dome.height_at(p[0], p[1]) - p[2];
            assert!(below < SURFACE_TOLERANCE, "{angle} deg: node {p:?} is inside the part by {below} m");
            // The binder holds the blank in its plane outside the opening (z = 0 at the end).
            if dome.outline_distance(p[0], p[1]) > 0.015 + spacing {
                assert!(p[2].abs() < 1e-9, "{angle} deg: node {p:?} left the binder's plane");
            }
        }
        (x, stdout)
    };
    let (plus, out_plus) = form(45.0);
    let (minus, out_minus) = form(-45.0);
    let at = |x: &[Option<[f64; 3]>], i: usize, j: usize| x[i * n + j];
    let distance =
        |p: [f64; 3], q: [f64; 3]| ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt();
    let (mut half_turn, mut mirror): (f64, f64) = (0.0, 0.0);
    for i in 0..n {
        for j in 0..n {
            // The half turn about z maps the +45 ply onto itself: (u, v) -> (-u, -v).
            match (at(&plus, i, j), at(&plus, n - 1 - i, n - 1 - j)) {
                (Some(p), Some(q)) => half_turn = half_turn.max(distance([-p[0], -p[1], p[2]], q)),
                (p, q) => assert_eq!(p.is_some(), q.is_some(), "node ({i}, {j}) and its half-turn image"),
            }
            // The mirror y -> -y maps the +45 ply's warp onto the -45 ply's and its weft onto
            // the -45 ply's weft reversed: (u, v) -> (u, -v).
            match (at(&plus, i, j), at(&minus, i, n - 1 - j)) {
                (Some(p), Some(q)) => mirror = mirror.max(distance([p[0], -p[1], p[2]], q)),
                (p, q) => assert_eq!(p.is_some(), q.is_some(), "node ({i}, {j}) and its mirror image"),
            }
        }
    }
    assert!(half_turn < IMAGE_SPACINGS * spacing, "half-turn images differ by {half_turn} m\n{out_plus}");
    assert!(mirror < IMAGE_SPACINGS * spacing, "mirror images differ by {mirror} m\n{out_plus}\n{out_minus}");
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
    let x = crate::common::all_nodes(&net);
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
    let worst = mirror_error(&x, n);
    // The die's quads are split along one diagonal each, so mirror facets are not images of each
    // other and neither are their smooth surfaces (0.02 spacings measured; 1.7e-12 with the
    // punch alone, above).
    const DIE_MIRROR_SPACINGS: f64 = 0.05;
    assert!(worst < DIE_MIRROR_SPACINGS * spacing, "mirror images differ by {worst} m\n{stdout}");
}

/// A plate tilted by `a` about the y axis (rising along +x), `size` square.
fn tilted_plate(a: f64, size: f64) -> TriangleMesh {
    let TriangleMesh { vertices, triangles } = shapes::plate(size, size, 24, 24);
    let (s, c) = a.sin_cos();
    let vertices = vertices.into_iter().map(|p| drape::geometry::Point::new(p.x * c, p.y, p.x * s)).collect();
    TriangleMesh { vertices, triangles }
}

/// A punch that moves along its own face carries the blank lying on it as friction allows
/// (Coulomb acts on the slip between the two, not on the blank's motion in space): a blank on a
/// plate tilted by a, carried up the slope and across it, rides along with the plate (every node
/// moves by the stroke, within the 1 mm of a ply that sticks) while tan a is within mu,
/// and slides down off it (the named outcome) once mu falls short of tan a. On a level plate
/// pushed sideways nothing but friction moves the blank either.
#[test]
fn a_punch_moving_along_its_face_carries_the_blank_friction_holds() {
    // A ply that sticks moves no node further than this from where the plate carried it (m).
    const STICK_MOVE: f64 = 1e-3;
    let card = Path::new(env!("CARGO_MANIFEST_DIR")).join("materials/glass-plain-weave.toml");
    for (a_deg, stroke, mu) in
        [(0.0f64, [0.03, 0.0, 0.0], 0.2), (15.0, [0.03, 0.02, 0.0], 0.35), (20.0, [0.04, 0.0, 0.0], 0.5)]
    {
        let a = a_deg.to_radians();
        // The stroke runs in the plate's plane: x up the slope, y across it.
        let stroke = [stroke[0] * a.cos(), stroke[1], stroke[0] * a.sin()];
        for (mu, holds) in [(mu, true), (0.9 * a.tan(), false)] {
            if !holds && a_deg == 0.0 {
                continue;
            }
            let tmp = tempfile::tempdir().unwrap();
            let plate = tilted_plate(a, 0.4);
            let scene = format!(
                "units = \"m\"\ntool = \"plate.obj\"\nfriction = {mu}\n\
                 [[ply]]\nname = \"p\"\norigin = [0.0, 0.0, 0.0]\nwarp = [1.0, 0.0, 0.0]\n\
                 material = \"{}\"\nspacing = 0.01\ngrid = [11, 11]\nmethod = \"mechanical\"\n\
                 mode = \"pressed\"\nstart = \"flat\"\nsheet_normal = [{}, 0.0, {}]\n\
                 stroke = [{}, {}, {}]\nmax_iterations = 400\n",
                card.display(),
                -a.sin(),
                a.cos(),
                stroke[0],
                stroke[1],
                stroke[2]
            );
            crate::common::write_scene(tmp.path(), &[("plate.obj", &plate)], &scene);
            let out = tmp.path().join("out");
            let run = crate::common::drape_run(tmp.path()).output().unwrap();
            let stdout = String::from_utf8_lossy(&run.stdout).to_string() + &String::from_utf8_lossy(&run.stderr);
            let net = read_json(&out.join("p.drape.json"));
            if !holds {
                assert_eq!(net["meta"]["solver"]["outcome"], "slides", "tilt {a_deg} deg, mu {mu}: {stdout}");
                continue;
            }
            assert_eq!(net["meta"]["solver"]["converged"], true, "tilt {a_deg} deg, mu {mu}: {stdout}");
            // Where the plate carried each node of the flat blank laid on it: the blank is laid
            // where the plate begins its stroke (the scene's origin moved back by the stroke), so
            // carried all the way it lies where the origin puts it on the plate's final place.
            let (s, c) = a.sin_cos();
            for (k, p) in crate::common::all_nodes(&net).iter().enumerate() {
                let (i, j) = (k / 11, k % 11);
                let (u, v) = ((i as f64 - 5.0) * 0.01, (j as f64 - 5.0) * 0.01);
                let carried = [u * c, v, u * s];
                let off = (0..3).map(|m| (p[m] - carried[m]).powi(2)).sum::<f64>().sqrt();
                assert!(
                    off < STICK_MOVE,
                    "tilt {a_deg} deg, mu {mu}: node ({i}, {j}) is {off} m from where the plate carried it\n{stdout}"
                );
            }
        }
    }
}
