//! Forming a flat blank by tools in motion (issue 33): a punch with a stroke, a binder, a die.
use drape::geometry::{shapes, TriangleMesh};
use drape::kinematic::provenance::DrawIn;
use drape::mechanics::forming::STROKE_STEP_SPACINGS;
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

/// Allowed error against the exact draw-in over a cylindrical punch, relative: the fabric's
/// stretch under the binder's friction (40 N/m against 8e6 N/m), the bend at the binder's edge
/// rounded by bending over about sqrt(B/T) = 2 mm, and the net's chords on the punch.
const SLOT_DRAW_IN_SHARE: f64 = 0.02;

/// A scene: a glass blank of `grid` nodes at `spacing` lies flat on a cylindrical punch of radius
/// `r` (`punch.obj`) that rises `h` into it, clamped by a binder outside a slot of half-width
/// `a` across it; `extra` are more keys of the ply.
fn slot_scene(r: f64, h: f64, a: f64, spacing: f64, [nu, nv]: [usize; 2], extra: &str) -> String {
    format!(
        "units = \"m\"\ntool = \"punch.obj\"\nfriction = 0.2\n\
         [[ply]]\nname = \"p\"\norigin = [0.0, 0.0, {r}]\nwarp = [1.0, 0.0, 0.0]\n\
         material = \"{card}\"\nspacing = {spacing}\ngrid = [{nu}, {nv}]\nmethod = \"mechanical\"\n\
         mode = \"pressed\"\nstart = \"flat\"\nstroke = [0.0, 0.0, {h}]\nmax_iterations = 2000\n{extra}\
         [ply.binder]\npressure = 2.0e3\noutline = [[-{a}, -1.0], [{a}, -1.0], [{a}, 1.0], [-{a}, 1.0]]\n",
        card = Path::new(env!("CARGO_MANIFEST_DIR")).join("materials/glass-plain-weave.toml").display()
    )
}

/// The blank of a [`slot_scene`] (layup.json's `row`, its `net`, the run's `stdout`; `what`
/// names the set-up in messages) drew both edges across the punch in by the exact path over it
/// less the slot's half-width, within [`SLOT_DRAW_IN_SHARE`]; no node lies inside the punch,
/// and those farther than `gripped_beyond` outside the slot lie in the binder's plane.
fn assert_drawn_in_over_the_slot(
    row: &serde_json::Value,
    net: &serde_json::Value,
    stdout: &str,
    (r, h, a): (f64, f64, f64),
    gripped_beyond: f64,
    what: &str,
) {
    let draw_in: DrawIn = serde_json::from_value(row["draw_in"].clone()).unwrap();
    let exact = half_path(r, h, a) - a;
    let along_warp: Vec<f64> =
        draw_in.edges.iter().filter(|e| e.line.is_fibre() && e.flat_m > 0.1).map(|e| e.draw_in_m).collect();
    assert_eq!(along_warp.len(), 2, "{draw_in:?}");
    for d in &along_warp {
        assert!(
            (d - exact).abs() < SLOT_DRAW_IN_SHARE * exact,
            "R {r}, stroke {h}, opening {a}{what}: the edge drew in {d} m, exactly {exact} m\n{stdout}"
        );
    }
    for p in net["nodes"].as_array().unwrap() {
        let p: Vec<f64> = p.as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect();
        let inside = r - (p[0] * p[0] + p[2] * p[2]).sqrt();
        assert!(p[2] < 0.0 || inside < 1e-6 * r, "node {p:?} is inside the punch by {inside} m");
        // Outside the opening the binder holds the blank in its plane (where the punch's top
        // stood at the start).
        if p[0].abs() > a + gripped_beyond {
            assert!((p[2] - (r - h)).abs() < 1e-9, "node {p:?} left the binder's plane");
        }
    }
}

/// A cylindrical punch rises into a blank clamped by a binder outside a slot across it: the
/// fibres across the punch are developable and keep their length, so the blank's edges draw in
/// by the path over the punch less the opening's half-width, on both sides alike, for other
/// radii, strokes and openings; every node of the blank is present at the end, none inside the
/// punch, and those the binder still grips lie in its plane.
#[test]
fn a_punch_rising_into_a_clamped_blank_draws_in_its_path_over_the_punch() {
    for (r, h, a) in [(0.05, 0.03, 0.1), (0.04, 0.025, 0.07)] {
        let tmp = tempfile::tempdir().unwrap();
        let punch = shapes::cylinder(r, 0.2, std::f64::consts::PI, 96, 40);
        let spacing = 0.005;
        let scene = slot_scene(r, h, a, spacing, [61, 21], "");
        let (stdout, row, net) = run(tmp.path(), &[("punch.obj", &punch)], &scene);
        assert_eq!(net["meta"]["solver"]["converged"], true, "{stdout}");
        // The whole blank is formed: every node placed, none inside the punch where it ends.
        assert_eq!(net["status"]["placed"], 61 * 21, "{}", net["status"]);
        assert_drawn_in_over_the_slot(&row, &net, &stdout, (r, h, a), spacing, "");
    }
}

/// Formed coarse to fine (`coarse_levels`), the same punch and binder give the same known
/// answer: the blank formed on the grid of 2 or 4 times the spacing, then held by its tools on
/// each finer grid, draws its edges in by the path over the punch less the opening's half-width
/// (within the same 2%), the whole blank present on the ply's own grid; every level converged,
/// the stroke's increments are the coarsest grid's and each finer one is held in one. Other
/// radii, strokes, openings, grids and level counts than the test above.
#[test]
fn a_blank_formed_coarse_to_fine_draws_in_its_path_over_the_punch() {
    for (r, h, a, levels, [nu, nv]) in [(0.045, 0.03, 0.09, 1, [61, 21]), (0.06, 0.035, 0.1, 2, [81, 25])] {
        let tmp = tempfile::tempdir().unwrap();
        let punch = shapes::cylinder(r, 0.2, std::f64::consts::PI, 96, 40);
        let spacing = 0.004;
        let scene = slot_scene(r, h, a, spacing, [nu, nv], &format!("coarse_levels = {levels}\n"));
        let (stdout, row, net) = run(tmp.path(), &[("punch.obj", &punch)], &scene);
        assert_eq!(net["meta"]["solver"]["converged"], true, "{stdout}");
        assert_eq!(net["spacing"], spacing);
        assert_eq!(net["status"]["placed"], nu * nv, "{}", net["status"]);
        let record = &net["meta"]["forming"];
        let steps = record["levels"].as_array().unwrap();
        assert_eq!(steps.len(), levels + 1, "{record}");
        for (k, level) in steps.iter().enumerate() {
            let expected = spacing * (1 << (levels - k)) as f64;
            assert!((level["spacing_m"].as_f64().unwrap() - expected).abs() < 1e-12, "{level}");
            assert_eq!(level["converged"], true, "{level}");
            assert_eq!(level["increments"].as_u64().unwrap() == 1, k > 0, "{level}");
        }
        assert_eq!(record["increments"], steps[0]["increments"]);
        let beyond = 2.0 * spacing * (1 << levels) as f64;
        assert_drawn_in_over_the_slot(&row, &net, &stdout, (r, h, a), beyond, &format!(", {levels} levels"));
        assert!(stdout.contains("formed coarse to fine"), "{stdout}");
        // Held again by its tools (`drape refine`), the formed net stays where it is.
        let card = Path::new(env!("CARGO_MANIFEST_DIR")).join("materials/glass-plain-weave.toml");
        let again = tmp.path().join("again");
        let held = refine_again(
            &tmp.path().join("out/p.drape.json"),
            &tmp.path().join("punch.obj"),
            card.to_str().unwrap(),
            0.2,
            &[],
            &again,
        )
        .success();
        let refined = read_json(&again.join("p.drape.json"));
        held_where_it_was(&net, &refined, &String::from_utf8_lossy(&held.get_output().stdout), 1.0);
    }
}

/// Mean |shear| difference, degrees, between a net at spacing d (`fine`, cells 2 x 2 to a cell
/// of `coarse`) and a net of the same blank at 2d (`coarse`), the fine cells averaged onto the
/// coarse ones; or between two nets of the same grid (`coarse` at d too: `k` = 1).
fn mean_shear_difference(fine: &serde_json::Value, coarse: &serde_json::Value, k: usize) -> f64 {
    let cells = |n: &serde_json::Value| -> (usize, Vec<Option<f64>>) {
        let nv = n["grid"][1].as_u64().unwrap() as usize;
        (nv - 1, n["cell_shear_deg"].as_array().unwrap().iter().map(|g| g.as_f64()).collect())
    };
    let ((fw, f), (cw, c)) = (cells(fine), cells(coarse));
    let mut sum = 0.0;
    let mut count = 0;
    for (index, g) in c.iter().enumerate() {
        let (ci, cj) = (index / cw, index % cw);
        let parts: Option<Vec<f64>> =
            (0..k * k).map(|q| f[(k * ci + q / k) * fw + k * cj + q % k]).collect::<Option<Vec<f64>>>();
        if let (Some(g), Some(parts)) = (g, parts) {
            sum += (parts.iter().sum::<f64>() / parts.len() as f64 - g).abs();
            count += 1;
        }
    }
    assert!(count > 0, "no cell to compare");
    sum / count as f64
}

/// A hemisphere formed coarse to fine from a clamped blank (another punch and opening than the
/// test above): the set-up's three mirror symmetries hold through the levels (the finer grid
/// starts from the coarse one's symmetric shape), the whole blank is present and none of it
/// inside the punch; and it has the finer grid's accuracy: its shear is nearer the blank formed
/// directly at its spacing than the blank formed at the coarse spacing is.
#[test]
fn a_hemisphere_formed_coarse_to_fine_keeps_its_symmetries_and_gains_the_finer_grids_accuracy() {
    const MIRROR_SPACINGS: f64 = 1e-6;
    const SMOOTH_SHARE: f64 = 1e-4;
    let (r, stroke, n, spacing) = (0.07, 0.04, 29, 0.008);
    let punch = shapes::hemisphere(r, 24);
    let form = |n: usize, spacing: f64, levels: usize| {
        let tmp = tempfile::tempdir().unwrap();
        let scene = hemisphere_in_binder(r, stroke, n, spacing, 0.095, &format!("coarse_levels = {levels}\n"));
        let (stdout, _, net) = run(tmp.path(), &[("punch.obj", &punch)], &scene);
        assert_eq!(net["meta"]["solver"]["converged"], true, "{stdout}");
        assert_eq!(net["status"]["placed"], n * n, "{}", net["status"]);
        (stdout, net)
    };
    let (stdout, stepped) = form(n, spacing, 1);
    let x = crate::common::all_nodes(&stepped);
    for p in &x {
        let inside = r - (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
        assert!(p[2] < 0.0 || inside < SMOOTH_SHARE * r, "node {p:?} is inside the punch by {inside} m");
    }
    let worst = mirror_error(&x, n);
    assert!(worst < MIRROR_SPACINGS * spacing, "mirror images differ by {worst} m\n{stdout}");
    let (_, direct) = form(n, spacing, 0);
    let (_, coarse) = form((n - 1) / 2 + 1, 2.0 * spacing, 0);
    let off_direct = mean_shear_difference(&stepped, &direct, 1);
    let coarse_off = mean_shear_difference(&direct, &coarse, 2);
    println!("coarse to fine against direct: {off_direct:.4} deg; direct at 2d against d: {coarse_off:.4} deg");
    assert!(off_direct < coarse_off, "{off_direct} deg from the direct forming, the coarse grid {coarse_off}");
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
        ("mode = \"pressed\"\ncoarse_levels = 1\n", "coarse_levels", "only a blank formed by the tools"),
        (
            "mode = \"pressed\"\nstart = \"flat\"\nstroke = [0.0, 0.0, 0.05]\ncoarse_levels = 2\n",
            "coarse_levels",
            "multiple of 4",
        ),
        ("mode = \"pressed\"\nstart = \"flat\"\nstroke = [0.0, 0.0, 0.05]\ncoarse_levels = 4\n", "coarse_levels", "at most 3"),
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
    let scene = hemisphere_in_binder(r, stroke, n, spacing, 0.085, "");
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

/// A scene: a hemispherical punch (`punch.obj`, radius `r`) rising `stroke` through a binder's
/// round opening of radius `opening` (24 sides) that clamps a flat glass blank of `n` x `n`
/// nodes at `spacing` at 10 kPa, friction 0.2; `extra` lines join the ply's keys.
fn hemisphere_in_binder(r: f64, stroke: f64, n: usize, spacing: f64, opening: f64, extra: &str) -> String {
    let outline: Vec<String> = (0..24)
        .map(|k| {
            let t = std::f64::consts::TAU * k as f64 / 24.0;
            format!("[{:.6}, {:.6}]", opening * t.cos(), opening * t.sin())
        })
        .collect();
    format!(
        "units = \"m\"\ntool = \"punch.obj\"\nfriction = 0.2\n\
         [[ply]]\nname = \"p\"\norigin = [0.0, 0.0, {r}]\nwarp = [1.0, 0.0, 0.0]\n\
         material = \"{card}\"\nspacing = {spacing}\ngrid = [{n}, {n}]\nmethod = \"mechanical\"\n\
         mode = \"pressed\"\nstart = \"flat\"\nstroke = [0.0, 0.0, {stroke}]\nmax_iterations = 2000\n\
         {extra}[ply.binder]\npressure = 1.0e4\noutline = [{}]\n",
        outline.join(", "),
        card = Path::new(env!("CARGO_MANIFEST_DIR")).join("materials/glass-plain-weave.toml").display()
    )
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

/// A hemispherical punch of radius `r` drawn `stroke` through a die's opening of radius
/// `opening` with an entry fillet `fillet` (eight facets over its quarter turn), from a square
/// blank of n x n nodes clamped on the die's face outside a round binder opening of radius
/// `binder` at `pressure`, with `friction` on every tool.
#[derive(Debug, Clone, Copy)]
struct DieSetUp {
    r: f64,
    opening: f64,
    fillet: f64,
    stroke: f64,
    n: usize,
    spacing: f64,
    binder: f64,
    pressure: f64,
    friction: f64,
}

/// R 60 mm into R 66 mm with a 6 mm fillet, 40 mm stroke, at 10 mm: the die set-up the tests
/// share.
const FILLETED_DIE: DieSetUp = DieSetUp {
    r: 0.06,
    opening: 0.066,
    fillet: 0.006,
    stroke: 0.04,
    n: 29,
    spacing: 0.01,
    binder: 0.08,
    pressure: 1.0e4,
    friction: 0.2,
};

/// R 50 mm into R 56 mm with a 5 mm fillet, 30 mm stroke, at 10 mm, friction 0.3: the second
/// die set-up the tests share.
const SMALL_DIE: DieSetUp = DieSetUp {
    r: 0.05,
    opening: 0.056,
    fillet: 0.005,
    stroke: 0.03,
    n: 25,
    spacing: 0.01,
    binder: 0.07,
    pressure: 5.0e3,
    friction: 0.3,
};

impl DieSetUp {
    /// Form the blank in `dir` (`punch.obj`, `die.obj`, the scene, `out/`): the command's output
    /// and the net.
    fn form(&self, dir: &Path) -> (String, serde_json::Value) {
        let (stdout, mut nets) = self.form_layup(dir, &[0.0]);
        (stdout, nets.remove(0))
    }

    /// Form a blank for each of `angles` (deg, from x), each on the plies formed before it (`p`,
    /// then `p2`, `p3`, ...) in `dir`: the command's output and the nets, in stacking order.
    fn form_layup(&self, dir: &Path, angles: &[f64]) -> (String, Vec<serde_json::Value>) {
        let DieSetUp { r, opening, fillet, stroke, n, spacing, binder, pressure, friction } = *self;
        let punch = shapes::hemisphere(r, 24);
        let mut die = shapes::die_ring(opening, fillet, 0.2, 0.06, 192, [8, 8, 10]);
        die.vertices.iter_mut().for_each(|v| v.z += r - stroke);
        let outline: Vec<String> = (0..24)
            .map(|k| {
                let t = std::f64::consts::TAU * k as f64 / 24.0;
                format!("[{:.6}, {:.6}]", binder * t.cos(), binder * t.sin())
            })
            .collect();
        let card = Path::new(env!("CARGO_MANIFEST_DIR")).join("materials/glass-plain-weave.toml");
        let names: Vec<String> =
            (0..angles.len()).map(|k| if k == 0 { "p".to_string() } else { format!("p{}", k + 1) }).collect();
        let plies: String = (names.iter().zip(angles))
            .map(|(name, angle)| {
                format!(
                    "[[ply]]\nname = \"{name}\"\norigin = [0.0, 0.0, {r}]\nangle_deg = {angle}\n\
                     material = \"{card}\"\nspacing = {spacing}\ngrid = [{n}, {n}]\nmethod = \"mechanical\"\n\
                     mode = \"pressed\"\nstart = \"flat\"\nstroke = [0.0, 0.0, {stroke}]\ndie = \"die.obj\"\n\
                     max_iterations = 2000\n[ply.binder]\npressure = {pressure}\noutline = [{}]\n",
                    outline.join(", "),
                    card = card.display()
                )
            })
            .collect();
        let scene =
            format!("units = \"m\"\ntool = \"punch.obj\"\nreference = [1.0, 0.0, 0.0]\nfriction = {friction}\n{plies}");
        let (out, stdout) = crate::common::run_scene(dir, &[("punch.obj", &punch), ("die.obj", &die)], &scene);
        let nets = names.iter().map(|name| read_json(&out.join(format!("{name}.drape.json")))).collect();
        (stdout, nets)
    }
}

/// A hemispherical punch drawn through a die's opening with an entry fillet (R 60 mm into R 66 mm,
/// a 6 mm fillet, eight facets over its quarter turn) from a blank clamped on the die's face: it
/// converges, no node is inside the punch or the die, those the binder grips lie in the die's
/// plane, and the set-up's mirror symmetries hold as far as the die's facets allow. On the die's
/// facets (each turning by 11 deg round the fillet) it stopped at the iteration limit in its
/// seventh increment; on its smooth surface it converges in 320 iterations.
#[test]
fn a_hemisphere_drawn_through_a_die_with_an_entry_fillet_stays_out_of_both_tools() {
    let set_up = FILLETED_DIE;
    let DieSetUp { r, opening, fillet, stroke, n, spacing, binder, .. } = set_up;
    let face = r - stroke;
    let tmp = tempfile::tempdir().unwrap();
    let (stdout, net) = set_up.form(tmp.path());
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

/// A second ply formed through a die on the first: the binder grips it in its own plane, a ply's
/// thickness above the die's face on the first ply (not on the face: contact once put the
/// gripped nodes there, undoing the grip, and the blank fell through the die's opening, 100 mm
/// below its face), it stays out of the die, and it draws in as the first ply does (it lies
/// on a punch thicker by the first ply: a little more). Two set-ups, the second ply at 0 and
/// at 45 deg to the first.
#[test]
fn a_second_ply_formed_through_a_die_is_gripped_in_its_own_plane() {
    // The second ply's largest draw-in along the fibres against the first's (2.4% more
    // measured on the bundled punch-and-die's two plies at 10 mm).
    const DRAW_IN_SHARE: f64 = 0.1;
    for (set_up, angle) in [(SMALL_DIE, 0.0), (FILLETED_DIE, 45.0)] {
        let DieSetUp { r, stroke, spacing, binder, .. } = set_up;
        let face = r - stroke;
        let tmp = tempfile::tempdir().unwrap();
        let (stdout, nets) = set_up.form_layup(tmp.path(), &[0.0, angle]);
        let largest_draw_in = |net: &serde_json::Value| {
            let edges = net["meta"]["draw_in"]["edges"].as_array().unwrap().clone();
            edges.iter().map(|e| e["draw_in_m"].as_f64().unwrap()).fold(0.0, f64::max)
        };
        for net in &nets {
            assert_eq!(net["meta"]["solver"]["converged"], true, "{angle} deg: {stdout}");
        }
        let second = &nets[1];
        let plane = second["meta"]["forming"]["blank_plane"]["point_m"][2].as_f64().unwrap();
        assert!(
            plane > face + 1e-4 && plane < face + 2e-3,
            "{angle} deg: the second blank's plane at {plane}, the face at {face}"
        );
        let gripped = second["meta"]["forming"]["binder"]["gripped"].as_array().unwrap().len();
        assert!(gripped > 0, "{angle} deg: the binder grips none of the second ply\n{stdout}");
        for p in crate::common::all_nodes(second) {
            assert!(
                p[2] > face - 1e-3,
                "{angle} deg: node {p:?} of the second ply fell below the die's face\n{stdout}"
            );
            if p[0].hypot(p[1]) > binder + spacing {
                assert!((p[2] - plane).abs() < 1e-9, "{angle} deg: node {p:?} left the second blank's plane");
            }
        }
        let (first, again) = (largest_draw_in(&nets[0]), largest_draw_in(second));
        println!("{angle} deg: draw-in {first:.5} m, on it {again:.5} m; {gripped} nodes gripped");
        assert!(
            (again - first).abs() < DRAW_IN_SHARE * first,
            "{angle} deg: draw-in {again} m on a first ply's {first} m"
        );
    }
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

/// How far (in spacings) a node of a formed ply may move when it is refined again where its
/// stroke ended, `share` the smallest share of a cell its blank keeps (1: whole cells). The
/// formed state balances its forces to the solver's tolerance, |F - P| <= 1e-4 of the tools'
/// forces; the ply's stiffness against those forces is about their size over half a spacing,
/// the most the punch moves the ply in one increment ([`STROKE_STEP_SPACINGS`]): so what is left
/// unbalanced moves the nodes by about 1e-4 x 0.5 spacings, and a node of cells the blank cuts
/// to a share s, s times as stiff, 1/s times that. The bound is twice that: 1e-4 spacings for
/// whole cells (measured at most 4.4e-6 over four set-ups), 4e-4 for the blank that keeps a
/// quarter of its corner cells (measured 3.6e-5). Restarted from zero friction force the nodes
/// crept by up to the stick distance and a taut span sagged: 0.012 spacings; with the binder
/// letting go of the nodes drawn past its edge in the last increment, 0.0022.
fn held_again_spacings(share: f64) -> f64 {
    2.0 * drape::mechanics::SolverSettings::default().tolerance * STROKE_STEP_SPACINGS / share
}

/// `drape refine` on the formed net `net` (a file), held by its tools: the punch `punch`, the
/// card, `friction`, and `extra` arguments, into `out`; the command's run.
fn refine_again(
    net: &Path,
    punch: &Path,
    card: &str,
    friction: f64,
    extra: &[&str],
    out: &Path,
) -> assert_cmd::assert::Assert {
    let friction = friction.to_string();
    assert_cmd::Command::cargo_bin("drape")
        .unwrap()
        .arg("refine")
        .arg("--net")
        .arg(net)
        .arg("--tool")
        .arg(punch)
        .args(["--material", card, "--mode", "pressed", "--friction", &friction])
        .args(extra)
        .arg("--out")
        .arg(out)
        .assert()
}

/// The refined net that `refine_again` wrote from the formed `net`: it converged in one
/// increment, keeps the process's record and every node's status, and no node moved more than
/// [`held_again_spacings`] (`share`: the smallest share of a cell the blank keeps); the largest
/// move in spacings.
fn held_where_it_was(formed: &serde_json::Value, refined: &serde_json::Value, stdout: &str, share: f64) -> f64 {
    assert_eq!(refined["meta"]["solver"]["converged"], true, "{stdout}");
    assert_eq!(refined["meta"]["solver"]["increments"].as_array().unwrap().len(), 1, "{stdout}");
    assert_eq!(refined["meta"]["forming"], formed["meta"]["forming"], "the formed ply's record is kept");
    assert_eq!(refined["status"], formed["status"], "{stdout}");
    let spacing = formed["spacing"].as_f64().unwrap();
    let (before, after) = (formed["nodes"].as_array().unwrap(), refined["nodes"].as_array().unwrap());
    let mut worst: f64 = 0.0;
    for (p, q) in before.iter().zip(after) {
        if let (Some(p), Some(q)) = (p.as_array(), q.as_array()) {
            let d = (0..3).map(|c| (p[c].as_f64().unwrap() - q[c].as_f64().unwrap()).powi(2)).sum::<f64>().sqrt();
            worst = worst.max(d / spacing);
        }
    }
    println!("refined again: largest node move {worst:.3e} spacings\n{stdout}");
    assert!(worst < held_again_spacings(share), "a node moved {worst} spacings\n{stdout}");
    worst
}

/// A blank formed by a cylindrical punch rising through a binder's slot, refined again with
/// `drape refine` from the command line where the stroke ended: the punch still, the binder
/// gripping the flange in the blank's plane with its recorded opening and pressure, the fabric
/// cut to the blank it records. It is an equilibrium, so no node moves, for other radii,
/// strokes, openings, pressures and coefficients, and a blank that cuts cells.
#[test]
fn a_blank_formed_through_a_binder_refined_again_moves_no_node() {
    let card = Path::new(env!("CARGO_MANIFEST_DIR")).join("materials/glass-plain-weave.toml");
    let card = card.to_str().unwrap();
    // A blank inside the 0.3 x 0.1 m grid whose edges run through the middle of the cells they
    // cut: half of each along its edges, a quarter at its corners.
    let halves = "[[-0.1375, -0.0475], [0.1425, -0.0475], [0.1425, 0.0475], [-0.1375, 0.0475]]";
    for (r, h, a, pressure, friction, blank) in
        [(0.05, 0.03, 0.1, 2.0e3, 0.2, None), (0.04, 0.02, 0.08, 8.0e3, 0.35, Some(halves))]
    {
        let tmp = tempfile::tempdir().unwrap();
        let punch = shapes::cylinder(r, 0.2, std::f64::consts::PI, 96, 40);
        let scene = format!(
            "units = \"m\"\ntool = \"punch.obj\"\nfriction = {friction}\n\
             [[ply]]\nname = \"p\"\norigin = [0.0, 0.0, {r}]\nwarp = [1.0, 0.0, 0.0]\n\
             material = \"{card}\"\nspacing = 0.005\ngrid = [61, 21]\nmethod = \"mechanical\"\n\
             mode = \"pressed\"\nstart = \"flat\"\nstroke = [0.0, 0.0, {h}]\nmax_iterations = 2000\n{}\
             [ply.binder]\npressure = {pressure}\noutline = [[-{a}, -1.0], [{a}, -1.0], [{a}, 1.0], [-{a}, 1.0]]\n",
            blank.map_or(String::new(), |b| format!("blank = {b}\n"))
        );
        let (stdout, _, formed) = run(tmp.path(), &[("punch.obj", &punch)], &scene);
        assert_eq!(formed["meta"]["solver"]["converged"], true, "{stdout}");
        let recorded = &formed["meta"]["forming"]["blank_m"];
        // The smallest share of a cell the blank keeps.
        let share = match blank {
            Some(b) => {
                assert_eq!(*recorded, serde_json::from_str::<serde_json::Value>(b).unwrap());
                let corners: Vec<[f64; 2]> = serde_json::from_str(b).unwrap();
                let shares = drape::mechanics::sheet::blank_fractions(&corners, 61, 21, 0.005, (30, 10));
                shares.into_iter().filter(|s| *s > 0.0).fold(1.0, f64::min)
            }
            None => {
                assert!(recorded.is_null(), "{recorded}");
                1.0
            }
        };
        // The net records the plane the binder gripped in: where the punch's top stood at the start.
        let plane = &formed["meta"]["forming"]["blank_plane"];
        assert_eq!(plane["normal"], serde_json::json!([0.0, 0.0, 1.0]), "{plane}");
        assert!((plane["point_m"][2].as_f64().unwrap() - (r - h)).abs() < 1e-12, "{plane}");
        let net = tmp.path().join("out/p.drape.json");
        let again = tmp.path().join("again");
        let run = refine_again(&net, &tmp.path().join("punch.obj"), card, friction, &[], &again).success();
        let stdout = String::from_utf8_lossy(&run.get_output().stdout).to_string();
        held_where_it_was(&formed, &read_json(&again.join("p.drape.json")), &stdout, share);
    }
}

/// A blank drawn through a die with an entry fillet, refined again with `drape refine` from the
/// command line where the stroke ended: the punch still, the die it records (found by the file
/// the net names, or given with `--die` once that file is gone), the binder gripping the flange
/// on the die's face. It is an equilibrium, so no node moves (beyond friction's creep), for
/// other radii, strokes, fillets, pressures and coefficients; a die that cannot be found is
/// refused with exit code 2, nothing written.
#[test]
fn a_blank_drawn_through_a_die_refined_again_moves_no_node() {
    let card = Path::new(env!("CARGO_MANIFEST_DIR")).join("materials/glass-plain-weave.toml");
    let card = card.to_str().unwrap();
    let set_ups = [SMALL_DIE, FILLETED_DIE];
    for (k, set_up) in set_ups.into_iter().enumerate() {
        let tmp = tempfile::tempdir().unwrap();
        let (stdout, formed) = set_up.form(tmp.path());
        assert_eq!(formed["meta"]["solver"]["converged"], true, "{set_up:?}\n{stdout}");
        // The net names the die's file as the scene did (joined to its folder).
        let die = tmp.path().join("die.obj");
        assert_eq!(formed["meta"]["forming"]["die_file"], die.display().to_string());
        let net = tmp.path().join("out/p.drape.json");
        let punch = tmp.path().join("punch.obj");
        let again = tmp.path().join("again");
        let run = if k == 0 {
            refine_again(&net, &punch, card, set_up.friction, &[], &again).success()
        } else {
            // The die moved: the net's record no longer finds it, and saying where it is does.
            let moved = tmp.path().join("moved-die.obj");
            std::fs::rename(&die, &moved).unwrap();
            let refused = refine_again(&net, &punch, card, set_up.friction, &[], &again).code(2);
            let err = String::from_utf8_lossy(&refused.get_output().stderr).to_string();
            assert!(
                err.contains("formed by a punch's stroke")
                    && err.contains(&format!("{} is not found", die.display()))
                    && err.contains("--die FILE"),
                "{err}"
            );
            assert!(!again.exists(), "a refused refinement wrote {}", again.display());
            refine_again(&net, &punch, card, set_up.friction, &["--die", moved.to_str().unwrap()], &again).success()
        };
        let stdout = String::from_utf8_lossy(&run.get_output().stdout).to_string();
        held_where_it_was(&formed, &read_json(&again.join("p.drape.json")), &stdout, 1.0);
    }
}

/// What does not fit a formed net is refused with exit code 2, naming what to give, before
/// anything is written: a free drape or load steps (it is held by its tools, its load already
/// on), a die it was not formed with, a die given for a net no process formed, a record without
/// the binder's plane (a net formed before drape recorded it), gripping a node off the grid, or
/// with a blank of two corners.
#[test]
fn a_formed_net_refined_again_with_what_does_not_fit_it_is_refused() {
    let card = Path::new(env!("CARGO_MANIFEST_DIR")).join("materials/glass-plain-weave.toml");
    let card = card.to_str().unwrap();
    let tmp = tempfile::tempdir().unwrap();
    let punch = shapes::cylinder(0.05, 0.2, std::f64::consts::PI, 48, 20);
    let scene = format!(
        "units = \"m\"\ntool = \"punch.obj\"\nfriction = 0.2\n\
         [[ply]]\nname = \"p\"\norigin = [0.0, 0.0, 0.05]\nwarp = [1.0, 0.0, 0.0]\n\
         material = \"{card}\"\nspacing = 0.01\ngrid = [31, 5]\nmethod = \"mechanical\"\n\
         mode = \"pressed\"\nstart = \"flat\"\nstroke = [0.0, 0.0, 0.02]\nmax_iterations = 2000\n\
         [ply.binder]\npressure = 2.0e3\noutline = [[-0.08, -1.0], [0.08, -1.0], [0.08, 1.0], [-0.08, 1.0]]\n"
    );
    let (stdout, _, formed) = run(tmp.path(), &[("punch.obj", &punch)], &scene);
    assert_eq!(formed["meta"]["solver"]["converged"], true, "{stdout}");
    let punch = tmp.path().join("punch.obj");
    let net = tmp.path().join("out/p.drape.json");
    let out = tmp.path().join("again");
    // A net changed by `edit`, written beside the formed one.
    let edited = |name: &str, edit: &dyn Fn(&mut serde_json::Value)| {
        let mut json = formed.clone();
        edit(&mut json);
        let path = tmp.path().join(name);
        std::fs::write(&path, serde_json::to_string(&json).unwrap()).unwrap();
        path
    };
    let unformed = edited("unformed.drape.json", &|j| {
        j["meta"].as_object_mut().unwrap().remove("forming");
    });
    let planeless = edited("planeless.drape.json", &|j| {
        j["meta"]["forming"].as_object_mut().unwrap().remove("blank_plane");
    });
    let off_grid = edited("off-grid.drape.json", &|j| {
        j["meta"]["forming"]["binder"]["gripped"].as_array_mut().unwrap().push(serde_json::json!([31, 0]));
    });
    let no_area = edited("no-area.drape.json", &|j| {
        j["meta"]["forming"]["blank_m"] = serde_json::json!([[0.0, 0.0], [0.1, 0.0]]);
    });
    let die = tmp.path().join("die.obj");
    std::fs::write(&die, shapes::hemisphere(0.1, 4).to_obj_string()).unwrap();
    let die = die.to_str().unwrap();
    let pressed = ["--mode", "pressed"];
    for (net, extra, says) in [
        (&net, vec!["--mode", "free"], "give --mode pressed"),
        (&net, [&pressed[..], &["--load-steps", "3"]].concat(), "leave --load-steps out"),
        (&net, [&pressed[..], &["--die", die]].concat(), "without a die (meta.forming.die is false): leave --die out"),
        (&unformed, [&pressed[..], &["--die", die]].concat(), "the net records no forming process (meta.forming)"),
        (&planeless, pressed.to_vec(), "meta.forming.blank_plane: the net records a binder but not the plane"),
        (&off_grid, pressed.to_vec(), "meta.forming.binder: gripped: node [31, 0] is outside the net's 31 x 5 grid"),
        (&no_area, pressed.to_vec(), "meta.forming.blank_m: a blank needs at least three corners"),
    ] {
        let mut command = assert_cmd::Command::cargo_bin("drape").unwrap();
        command.arg("refine").arg("--net").arg(net).arg("--tool").arg(&punch);
        command.args(["--material", card]).args(&extra).arg("--out").arg(&out);
        let refused = command.assert().code(2);
        let err = String::from_utf8_lossy(&refused.get_output().stderr).to_string();
        assert!(err.contains(says), "{extra:?}: {err}");
        assert!(!out.exists(), "{extra:?}: a refused refinement wrote {}", out.display());
    }
}

/// A punch whose file faces into the part (its facets wound the other way) forms the same blank
/// once the scene says the plies lie on the other side (`stack_side = "opposite"`), to the last
/// digit; without it, and with the stroke reversed, the punch would move away from the blank and
/// the run is refused before anything is computed, naming the stroke and both ways out. (Before:
/// a hat box wound inward "converged" on 16% of the tool after 7,356 iterations, and a reversed
/// stroke left the blank flat 80 mm above the part, exit 0.) Two hat boxes (vertical walls on a
/// flange the blank lies on, clamped by a binder round the box), other sizes and ply angles.
#[test]
fn a_punch_facing_into_the_part_forms_alike_on_the_other_side_and_a_stroke_away_is_refused() {
    let smaller = shapes::HatBox {
        length: 0.16,
        width: 0.12,
        height: 0.05,
        corner_radius: 0.025,
        base_fillet: 0.008,
        top_fillet: 0.008,
        flange: 0.06,
    };
    for (b, angle, card) in [(shapes::HatBox::standard(), 30.0, "glass-plain-weave"), (smaller, 0.0, "carbon-twill")] {
        let tmp = tempfile::tempdir().unwrap();
        let punch = shapes::hat_box(&b, 0.01, 3);
        let inward = TriangleMesh {
            vertices: punch.vertices.clone(),
            triangles: punch.triangles.iter().map(|&[p, q, s]| [p, s, q]).collect(),
        };
        let h = b.height;
        let (x, y) = (b.length / 2.0 + 0.025, b.width / 2.0 + 0.025);
        let scene = |tool: &str, side: &str, stroke: f64| {
            format!(
                "units = \"m\"\ntool = \"{tool}\"\nfriction = 0.2\nreference = [1.0, 0.0, 0.0]\n{side}\
                 [[ply]]\nname = \"p\"\norigin = [0.0, 0.0, {h}]\nangle_deg = {angle}\n\
                 material = \"{card}\"\nspacing = 0.02\ngrid = [21, 19]\nmethod = \"mechanical\"\n\
                 mode = \"pressed\"\nstart = \"flat\"\nstroke = [0.0, 0.0, {stroke}]\nmax_iterations = 2000\n\
                 [ply.binder]\npressure = 1.0e4\noutline = [[{x}, -{y}], [{x}, {y}], [-{x}, {y}], [-{x}, -{y}]]\n",
                card = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("materials/{card}.toml")).display()
            )
        };
        let tools = [("punch.obj", &punch), ("inward.obj", &inward)];
        let (stdout, _, net) = run(tmp.path(), &tools, &scene("punch.obj", "", h));
        assert_eq!(net["meta"]["solver"]["converged"], true, "{stdout}");
        let tmp2 = tempfile::tempdir().unwrap();
        let (stdout2, _, turned) = run(tmp2.path(), &tools, &scene("inward.obj", "stack_side = \"opposite\"\n", h));
        assert_eq!(turned["meta"]["solver"]["converged"], true, "{stdout2}");
        assert_eq!(net["nodes"], turned["nodes"], "{b:?}, angle {angle}: the turned punch formed another blank");
        assert_eq!(net["cell_shear_deg"], turned["cell_shear_deg"]);
        // The turned net records its side, and `drape refine` holds it on the inward file as it
        // holds the outward net on the outward file; told the other side, it lets go of it.
        assert_eq!(turned["meta"]["stack_side"], "opposite");
        assert!(net["meta"].get("stack_side").is_none());
        let card_path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("materials/{card}.toml"));
        let card_path = card_path.to_str().unwrap();
        let formed = tmp2.path().join("out/p.drape.json");
        let inward_file = tmp2.path().join("inward.obj");
        let again = tmp2.path().join("again");
        refine_again(&formed, &inward_file, card_path, 0.2, &[], &again).success();
        let refined = read_json(&again.join("p.drape.json"));
        assert_eq!(refined["meta"]["stack_side"], "opposite");
        let outward_again = tmp.path().join("again");
        refine_again(
            &tmp.path().join("out/p.drape.json"),
            &tmp.path().join("punch.obj"),
            card_path,
            0.2,
            &[],
            &outward_again,
        )
        .success();
        let refined_outward = read_json(&outward_again.join("p.drape.json"));
        assert_eq!(
            refined["nodes"], refined_outward["nodes"],
            "held again on the inward file, the ply moved otherwise"
        );
        let wrong = tmp.path().join("wrong");
        let other = refine_again(&formed, &inward_file, card_path, 0.2, &["--stack-side", "normal"], &wrong);
        let refined = read_json(&wrong.join("p.drape.json"));
        let moved = refined["nodes"]
            .as_array()
            .unwrap()
            .iter()
            .zip(turned["nodes"].as_array().unwrap())
            .filter_map(|(p, q)| Some((p.as_array()?, q.as_array()?)))
            .map(|(p, q)| (0..3).map(|c| (p[c].as_f64().unwrap() - q[c].as_f64().unwrap()).powi(2)).sum::<f64>().sqrt())
            .fold(0.0, f64::max);
        assert!(moved > 0.02, "met from the wrong side the ply stayed within {moved} m\n{:?}", other.get_output());
        for (tool, side, stroke) in
            [("inward.obj", "", h), ("punch.obj", "", -h), ("inward.obj", "stack_side = \"opposite\"\n", -h)]
        {
            let fresh = tempfile::tempdir().unwrap();
            let out = fresh.path().join("out");
            crate::common::write_scene(fresh.path(), &tools, &scene(tool, side, stroke));
            let refused = crate::common::drape_run(fresh.path()).assert().code(2);
            let stderr = String::from_utf8_lossy(&refused.get_output().stderr).to_string();
            assert!(
                stderr.contains("field `stroke`: the stroke")
                    && stderr.contains("moves the punch away from the blank")
                    && stderr.contains("Reverse the stroke")
                    && stderr.contains("stack_side = \"opposite\""),
                "{tool} {side} {stroke}: {stderr}"
            );
            assert!(!out.exists());
            // The library refuses it too, before any ply is draped (a study, an optimisation
            // and Python drape layups without the CLI's run).
            let loaded = drape::pipeline::scene::Scene::load(&fresh.path().join("scene.toml")).unwrap();
            let surface = drape::io::read_tool(&loaded.tool, loaded.scale).unwrap();
            let mut draped = 0;
            let refused = drape::layup::stack::drape_layup(&loaded.layup, &surface, |_, _| draped += 1);
            assert!(
                matches!(refused, Err(drape::layup::stack::LayupError::Forming { field: "stroke", .. })),
                "{tool:?} {side} {stroke}: {:?}",
                refused.map(|r| r.len())
            );
            assert_eq!(draped, 0, "a ply was draped before the stroke was refused");
        }
    }
}
