//! Seed 000's drapes end to end: free drapes from a flat sheet over the bundled tables and sphere
//! (at sizes the suite can afford; the bundled scenes run the seed's sizes), the sheet variants,
//! pressed plies on the double dome, and how a ply that did not converge is shown.
use crate::mechanics_refine::max_strain;
use assert_cmd::Command;
use drape::geometry::{Point, ToolSurface};
use drape::io::read_tool;
use drape::kinematic::NodeStatus;
use drape::layup::stack::{drape_layup, PlyResult};
use drape::mechanics::energy::Grid;
use drape::pipeline::Scene;
use std::path::{Path, PathBuf};

fn repo(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)
}

/// Drapes the scene text (tool and cards given relative to the repository) and returns the tool
/// and the plies.
/// The text with `@/` standing for the repository's folder.
fn resolve(text: &str) -> String {
    text.replace("@/", &format!("{}/", env!("CARGO_MANIFEST_DIR")))
}

/// The bundled square-table scene's text with its tool and cards given from the repository
/// (`@/`, which [`drape_text`] resolves) and `replacements` applied.
fn square_table_text(replacements: &[(&str, &str)]) -> String {
    let text = std::fs::read_to_string(repo("geometries/square-table/scene.toml"))
        .unwrap()
        .replace("\"square-table.obj\"", "\"@/geometries/square-table/square-table.obj\"")
        .replace("../../materials", "@/materials");
    replacements.iter().fold(text, |t, (from, to)| t.replace(from, to))
}

fn drape_text(text: &str) -> (ToolSurface, Vec<PlyResult>) {
    let dir = tempfile::tempdir().unwrap();
    let text = resolve(text);
    let path = dir.path().join("scene.toml");
    std::fs::write(&path, text).unwrap();
    drape_file(&path)
}

fn drape_file(path: &Path) -> (ToolSurface, Vec<PlyResult>) {
    let scene = Scene::load(path).unwrap();
    let tool = read_tool(&scene.tool, scene.scale).unwrap();
    let results = drape_layup(&scene.layup, &tool, |_, _| {}).unwrap();
    (tool, results)
}

fn converged(r: &PlyResult) -> bool {
    let refined = r.refined.as_ref().expect("a mechanical ply");
    if !refined.ok() {
        eprintln!("{}", refined.describe_failure());
    }
    refined.ok()
}

/// The sphere scene's sheet (1.8 m, centre over the pole of the R = 0.4 m sphere at the origin)
/// at `n` x `n` nodes, with `extra` TOML lines for the ply. Friction 0.3 on the sphere, as the
/// bundled scene: a frictionless sheet balanced on the pole has no equilibrium (it slides off).
fn sphere_sheet(n: usize, extra: &str) -> String {
    format!(
        r#"tool = "@/geometries/sphere/sphere.obj"
friction = 0.3
[[ply]]
name = "sheet"
origin = [0.0, 0.0, 1.0]
warp = [1.0, 0.0, 0.0]
material = "@/materials/sze-liu-table1.toml"
spacing = {}
grid = [{n}, {n}]
method = "mechanical"
mode = "free"
start = "flat"
{extra}
"#,
        1.8 / (n - 1) as f64
    )
}

const SPHERE_RADIUS: f64 = 0.4;
/// The Kang & Yu fabric is stiff in tension (745-1097 N/m) but far softer in shear (41 N/m per
/// rad): where it wraps the sphere it stretches about 1% rather than shear, as a real fabric
/// does; its weight alone strains the fibres by 0.2% at most. A strain above this is a fault.
const FIBRE_STRAIN_LIMIT: f64 = 0.03;
/// The sphere's facets lie inside the sphere by up to their sagitta; nodes rest on the smooth
/// surface through the vertices, within this of the true sphere.
const SPHERE_FACET_SAGITTA: f64 = 2e-4;

/// Largest |p(i, j) - mirror(p(mirror i, j))| over the net, mirroring x (i along the warp).
fn mirror_gap(r: &PlyResult, along_warp: bool) -> f64 {
    let net = &r.net;
    let mut worst: f64 = 0.0;
    for i in 0..net.nu {
        for j in 0..net.nv {
            let (a, b) = if along_warp {
                (net.node(i, j), net.node(net.nu - 1 - i, j))
            } else {
                (net.node(i, j), net.node(i, net.nv - 1 - j))
            };
            if let (Some(a), Some(b)) = (a, b) {
                let m = if along_warp { Point::new(-b.x, b.y, b.z) } else { Point::new(b.x, -b.y, b.z) };
                worst = worst.max((a - m).norm());
            }
        }
    }
    worst
}

#[test]
fn the_square_table_scene_drapes_the_whole_sheet_and_converges_with_the_mesh() {
    // The bundled scene (41 x 41 at 5 mm) and the same sheet at 2.5 mm: both converge, no node
    // is inside the table, and the corners drop alike, within issue 10's 5 mm (the seed finds
    // its 21 x 21 and 51 x 51 quarter models indistinguishable). Spacings between fold the
    // corners into other equilibria of their own (at 4 mm a deeper fold, 41.5 mm, of lower
    // energy), so the pair is the issue's.
    let (_, coarse) = drape_file(&repo("geometries/square-table/scene.toml"));
    assert!(converged(&coarse[0]));
    // The seed's restraint (stick = true) is said as such, not as a friction of 0.
    let contact = coarse[0].refined.as_ref().unwrap().contact.summary();
    assert!(contact.sticky && contact.describe().starts_with("stick = true"), "{}", contact.describe());
    let text = square_table_text(&[("spacing = 0.005", "spacing = 0.0025"), ("grid = [41, 41]", "grid = [81, 81]")]);
    let (_, fine) = drape_text(&text);
    assert!(converged(&fine[0]));
    for r in [&fine[0], &coarse[0]] {
        assert!(max_strain(&r.net) < FIBRE_STRAIN_LIMIT, "fibre strain {}", max_strain(&r.net));
        for p in r.net.positions.iter() {
            let inside = p.x.abs() < 0.05 - 1e-9 && p.y.abs() < 0.05 - 1e-9 && p.z < -1e-9 && p.z > -0.1;
            assert!(!inside, "node {p} inside the table");
        }
    }
    // The corners fold to one side or the other (equilibria of equal standing: the seed's
    // experiment is "slightly nonsymmetric" too), so the mean drop of the four is compared.
    let drop = |r: &PlyResult| {
        let (nu, nv) = (r.net.nu, r.net.nv);
        let corners = [(0, 0), (0, nv - 1), (nu - 1, 0), (nu - 1, nv - 1)];
        -corners.iter().map(|&(i, j)| r.net.node(i, j).unwrap().z).sum::<f64>() / 4.0
    };
    let (d_fine, d_coarse) = (drop(&fine[0]), drop(&coarse[0]));
    assert!(d_fine > 0.02 && d_fine < 0.05, "the corners hang {d_fine} m below the top");
    assert!((d_fine - d_coarse).abs() < 5e-3, "corner drop {d_coarse} m at 5 mm, {d_fine} m at 2.5 mm");
}

#[test]
fn a_flat_sheet_over_the_sphere_drapes_symmetrically_outside_it() {
    let (_, r) = drape_text(&sphere_sheet(31, ""));
    let r = &r[0];
    assert!(converged(r));
    assert!(max_strain(&r.net) < FIBRE_STRAIN_LIMIT, "fibre strain {}", max_strain(&r.net));
    for p in &r.net.positions {
        assert!(p.coords.norm() > SPHERE_RADIUS - SPHERE_FACET_SAGITTA, "node {p} inside the sphere");
    }
    assert!(r.refined.as_ref().unwrap().steps[0].energy_end < r.refined.as_ref().unwrap().steps[0].energy_start);
    // The pole stays where the sheet touched it; the sheet hangs well below the equator.
    let centre = r.net.node(15, 15).unwrap();
    assert!((centre - Point::new(0.0, 0.0, SPHERE_RADIUS)).norm() < 1e-3, "centre at {centre}");
    assert!(r.net.node(0, 0).unwrap().z < -0.2);
    assert!(mirror_gap(r, true) < 5e-3 && mirror_gap(r, false) < 5e-3);
}

/// A square blank cut at 45 deg to the fibres (its corners on the fibre axes, 0.7 m out, so the
/// edge cuts cells across) dropped over the sphere: the nodes of the blank drape and no other,
/// the fabric weighs the blank's area (the cells the edge cuts carry their share), the drape
/// keeps the blank's mirror symmetries, and the flat pattern is the blank.
#[test]
fn a_blank_cut_at_45_degrees_over_the_sphere_drapes_what_was_cut() {
    let n = 31;
    let half = 0.7;
    let (_, r) = drape_text(&sphere_sheet(
        n,
        &format!("blank = [[{half}, 0.0], [0.0, {half}], [-{half}, 0.0], [0.0, -{half}]]"),
    ));
    let r = &r[0];
    assert!(converged(r));
    let d = r.net.spacing;
    let blank = [[half, 0.0], [0.0, half], [-half, 0.0], [0.0, -half]];
    let fractions = drape::mechanics::sheet::blank_fractions(&blank, n, n, d, (15, 15));
    let keep = drape::mechanics::sheet::blank_nodes(&fractions, n, n);
    for (k, (&status, keep)) in r.net.status.iter().zip(&keep).enumerate() {
        let expected = if *keep { NodeStatus::Placed } else { NodeStatus::OutsideOutline };
        assert_eq!(status, expected, "node {k}");
    }
    // The sheet's corners are cut away; the fibre axes reach the blank's corners, 0.7 m out, in
    // the cells 11 to 12 spacings (0.06 m) from the origin node.
    assert!(r.net.node(0, 0).is_none() && r.net.node(15, 2).is_none() && r.net.node(28, 15).is_none());
    assert!(r.net.node(15, 3).is_some() && r.net.node(27, 15).is_some());
    // Its weight: the areal mass over the blank's area, 2 half^2.
    let areal_mass = drape::material::MaterialCard::load(&repo("materials/sze-liu-table1.toml")).unwrap().areal_mass;
    let layout = drape::mechanics::sheet::SheetFeatures { blank: Some(blank.to_vec()), ..Default::default() }
        .layout(n, n, d, (15, 15))
        .unwrap();
    let mass: f64 = Grid::from_net(&r.net).with_sheet(layout).nodal_masses(areal_mass).iter().sum();
    let exact = areal_mass * 2.0 * half * half;
    assert!((mass - exact).abs() < 1e-9 * exact, "{mass} kg against {exact} kg");
    assert!((r.stats.fabric_area - 2.0 * half * half).abs() < 1e-9, "{}", r.stats.fabric_area);
    for p in &r.net.positions {
        assert!(p.coords.norm() > SPHERE_RADIUS - SPHERE_FACET_SAGITTA || !p.coords.norm().is_finite());
    }
    assert!(mirror_gap(r, true) < 5e-3 && mirror_gap(r, false) < 5e-3);
}

/// Stiff cards dropped free on a small sphere settle on it. An 11 x 11 sheet at 2 cm balances
/// on the pole node at first; that node's push on the sphere changes sign from one iteration to
/// the next while the sheet bends down, and (before) it was let go and caught again every other
/// iteration until the iteration limit (carbon twill and glass on R = 0.1 m: 3,000 iterations,
/// unconverged). Two cards, two spheres, two ply angles: each converges to a minimum, rests on
/// the pole where it was dropped, stays out of the sphere and hangs down over it.
#[test]
fn stiff_cards_dropped_free_on_a_small_sphere_settle_on_it() {
    use drape::geometry::shapes;
    use drape::mechanics::Stability;
    for (card, radius, angle) in
        [("carbon-twill", 0.1, 0.0), ("glass-plain-weave", 0.1, 0.0), ("carbon-twill", 0.13, 30.0)]
    {
        let dir = tempfile::tempdir().unwrap();
        let sphere = shapes::icosphere(radius, Point::origin(), 4);
        std::fs::write(dir.path().join("sphere.obj"), sphere.to_obj_string()).unwrap();
        let scene = format!(
            "units = \"m\"\ntool = \"sphere.obj\"\nfriction = 0.3\nreference = [1.0, 0.0, 0.0]\n[[ply]]\n\
             name = \"p\"\norigin = [0.0, 0.0, {radius}]\nangle_deg = {angle}\nmaterial = {:?}\n\
             spacing = 0.02\ngrid = [11, 11]\nmethod = \"mechanical\"\nmode = \"free\"\nstart = \"flat\"\n\
             max_iterations = 3000\n",
            repo(&format!("materials/{card}.toml")).display().to_string()
        );
        std::fs::write(dir.path().join("scene.toml"), scene).unwrap();
        let (_, results) = drape_file(&dir.path().join("scene.toml"));
        let r = &results[0];
        let what = format!("{card} on R = {radius} m at {angle} deg");
        assert!(converged(r), "{what}");
        assert_eq!(r.refined.as_ref().unwrap().stability_verdict(), Some(Stability::Minimum), "{what}");
        let top = Point::new(0.0, 0.0, radius);
        let centre = r.net.node(5, 5).unwrap();
        assert!((centre - top).norm() < 1e-3, "{what}: the centre rests at {centre}");
        // The facets lie inside the sphere by up to their sagitta (about 0.1 mm here).
        for p in &r.net.positions {
            assert!(p.coords.norm() > radius - 2e-4, "{what}: node {p} inside the sphere");
        }
        for (i, j) in [(0, 0), (0, 10), (10, 0), (10, 10)] {
            let corner = r.net.node(i, j).unwrap();
            assert!(corner.z < radius - 0.01, "{what}: corner ({i}, {j}) at {corner} does not hang down");
        }
    }
}

#[test]
fn sheet_variants_over_the_sphere_converge_and_do_what_they_say() {
    let n = 31;
    let (_, plain) = drape_text(&sphere_sheet(n, ""));
    // Reinforced edges: heavier and far stiffer in bending, the border hangs differently (the
    // seed's edges flare out instead of hanging straight down).
    let (_, edges) = drape_text(&sphere_sheet(
        n,
        "[[ply.reinforcement]]\nedges = 0.12\ntension = 5.0\nshear = 5.0\nbending = 20.0\nweight = 2.0",
    ));
    assert!(converged(&edges[0]));
    let mid = |r: &PlyResult| r.net.node(0, n / 2).unwrap();
    assert!((mid(&edges[0]) - mid(&plain[0])).norm() > 0.01, "the reinforced edge hangs as the plain one");
    // A cut across the weft links near an edge: the two lips part.
    let (_, cut) = drape_text(&sphere_sheet(n, "[[ply.cut]]\npoints = [[-0.45, 0.81], [0.45, 0.81]]"));
    assert!(converged(&cut[0]));
    let net = &cut[0].net;
    let lips: f64 = (8..23).map(|i| (net.node(i, 28).unwrap() - net.node(i, 29).unwrap()).norm()).fold(0.0, f64::max);
    assert!(lips > 1.5 * net.spacing, "the cut's lips are {lips} m apart");
    // A seam: two sheets stitched along a weft line; stitched nodes coincide.
    let (_, seam) = drape_text(
        &sphere_sheet(n, "[ply.seam]\nrows = [16, 16]\nallowance = 1")
            .replace(&format!("grid = [{n}, {n}]"), &format!("grid = [32, {n}]")),
    );
    assert!(converged(&seam[0]));
    // A fold along the weft through the middle, starting unfolded.
    let (_, fold) = drape_text(&sphere_sheet(n, "[ply.fold]\nrow = 15\nstiffness = 98.0"));
    assert!(converged(&fold[0]));
    // No fabric lies in the cells the sheet was cut through (the cut's, the seam's edge): the
    // net says which, they have no cell values, and the net is written (before: `drape run`
    // refused to write the bundled seam and cut scenes after solving them, a cut cell having a
    // shear but no bending energy).
    use drape::kinematic::provenance::SheetFeature;
    for (r, cut_cells, feature) in [
        (&cut[0], (8..22).map(|i| [i, 28]).collect::<Vec<_>>(), SheetFeature::Cut),
        (&seam[0], (0..n - 1).map(|j| [15, j]).collect(), SheetFeature::Seam),
        (&fold[0], Vec::new(), SheetFeature::Fold),
    ] {
        let net = &r.net;
        assert_eq!(net.meta.sheet_features, [feature]);
        for [i, j] in &cut_cells {
            assert!(net.meta.cut_cells.contains(&[*i, *j]), "cell ({i}, {j}) is not recorded as cut");
        }
        for &[i, j] in &net.meta.cut_cells {
            assert!(net.cell_shear(i, j).is_none() && net.cell_frame(i, j).is_none(), "cut cell ({i}, {j})");
        }
        let dir = tempfile::tempdir().unwrap();
        drape::io::write_net(net, dir.path(), &drape::io::Format::ALL).unwrap();
        let back = drape::io::read_net(&dir.path().join("sheet.drape.json")).unwrap();
        assert_eq!(back.meta.cut_cells, net.meta.cut_cells);
        assert_eq!(back.cell_shears(), net.cell_shears());
        // `drape refine` does not know the features themselves: it refuses to join the sheet
        // across its cuts and seams or to drop its fold, and says how to drape it again.
        let refine = Command::cargo_bin("drape")
            .unwrap()
            .arg("refine")
            .arg("--net")
            .arg(dir.path().join("sheet.drape.json"))
            .arg("--tool")
            .arg(repo("geometries/sphere/sphere.obj"))
            .arg("--material")
            .arg(repo("materials/sze-liu-table1.toml"))
            .args(["--mode", "free", "--friction", "0.3", "--out"])
            .arg(dir.path().join("again"))
            .assert()
            .code(2);
        let err = String::from_utf8_lossy(&refine.get_output().stderr).to_string();
        let feature = format!("scene's {}", feature.name());
        for says in [feature.as_str(), "meta.sheet_features", "drape run"] {
            assert!(err.contains(says), "the refusal does not say '{says}': {err}");
        }
    }
}

#[test]
fn the_double_dome_presses_to_equilibrium_at_0_and_45_degrees() {
    let scene = |angle: f64| {
        format!(
            r#"tool = "@/geometries/double-dome/double-dome.obj"
[[ply]]
name = "p"
origin = [0.0, 0.0, 0.06]
angle_deg = {angle}
material = "@/materials/carbon-twill.toml"
spacing = 0.01
grid = [51, 41]
method = "mechanical"
mode = "pressed"
"#
        )
    };
    for angle in [0.0, 45.0] {
        let (tool, r) = drape_text(&scene(angle));
        let r = &r[0];
        assert!(converged(r), "{angle} deg");
        let refined = r.refined.as_ref().unwrap();
        assert!(refined.steps[0].energy_end <= refined.steps[0].energy_start);
        // On the tool, or (a known limit: a node carried past the tool's open edge stays on the
        // smooth surface's continuation, and each of a load step's solves with friction may
        // carry it a little further) within two spacings of its edge.
        let placed = r.net.positions.iter().zip(&r.net.status);
        for p in placed.filter(|(_, s)| **s == drape::kinematic::NodeStatus::Placed).map(|(p, _)| p) {
            assert!(tool.closest_point(p).distance < 2.0 * r.net.spacing, "{angle} deg: node {p} off the tool");
        }
    }
}

/// Issue 10's +/-45 ply on the hat box (the bundled scene's tool and card, at 6 mm so the suite
/// can afford it): the convex model's tail used to creep there with the energy flat to ten
/// digits (stalled after 250 iterations at |F-P|/|P| 2.7e-4) until the solver learned to test
/// whether the exact model is stiff enough to take over (`solver::exact_is_stiff`).
#[test]
fn the_hat_box_presses_to_a_minimum_at_45_degrees() {
    // At 8 mm nodes slide past the flange's open edge by more than the smooth surface's own
    // continuation reached (its sectors' supports); it used to end there and the solve stalled
    // at |F-P|/|P| 1.27 with a node held against that border.
    for (spacing, grid) in [(0.006, [74, 66]), (0.008, [56, 50])] {
        let text = format!(
            r#"tool = "@/geometries/hat-box/hat-box.obj"
[[ply]]
name = "p45"
origin = [0.0, 0.0, 0.08]
warp = [0.7071, 0.7071, 0.0]
material = "@/materials/carbon-twill.toml"
spacing = {spacing}
grid = {grid:?}
locking_angle_deg = 45.0
method = "mechanical"
mode = "pressed"
"#
        );
        let (tool, r) = drape_text(&text);
        let r = &r[0];
        assert!(converged(r), "at {spacing} m");
        let refined = r.refined.as_ref().unwrap();
        let step = &refined.steps[0];
        assert!(step.energy_end <= step.energy_start, "{} > {}", step.energy_end, step.energy_start);
        assert!(!step.saddle(), "the pressed ply ends on a saddle at {spacing} m");
        // Pressed nodes lie on the smooth surface the facets stand for: within its standoff from
        // the facets (0.2 mm on the fillets), or past the flange's open edge (0.17 m and 0.145 m
        // from the centre) on that surface's continuation, the flange's plane: fabric that slides
        // off a tool's end goes on as the tool's last face does.
        let placed = r.net.positions.iter().zip(&r.net.status);
        for p in placed.filter(|(_, s)| **s == drape::kinematic::NodeStatus::Placed).map(|(p, _)| p) {
            let off = tool.closest_point(p).distance;
            let past_edge = (p.x.abs() > 0.17 || p.y.abs() > 0.145) && p.z.abs() < 1e-6;
            assert!(off < 0.05 * r.net.spacing || past_edge, "node {p} {off} m off the tool at {spacing} m");
        }
    }
}

#[test]
fn a_ply_that_did_not_converge_is_marked_everywhere_and_the_run_exits_1() {
    let dir = tempfile::tempdir().unwrap();
    let text = resolve(&square_table_text(&[("max_iterations = 2000", "max_iterations = 2")]));
    let scene = dir.path().join("scene.toml");
    std::fs::write(&scene, text).unwrap();
    let out = dir.path().join("out");
    let run = Command::cargo_bin("drape").unwrap().arg("run").arg(&scene).arg("--out").arg(&out).output().unwrap();
    assert_eq!(run.status.code(), Some(1));
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(stdout.contains("UNCONVERGED"), "{stdout}");
    assert!(stdout.contains("largest unbalanced force"), "{stdout}");
    let layup: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("layup.json")).unwrap()).unwrap();
    assert_eq!(layup["plies"][0]["converged"], serde_json::json!(false));
    assert!(layup["plies"][0]["solver_failure"].as_str().unwrap().contains("iteration limit"));
    let net: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("sheet.drape.json")).unwrap()).unwrap();
    assert_eq!(net["meta"]["solver"]["converged"], serde_json::json!(false));
    assert!(!net["meta"]["solver"]["unbalanced"].as_array().unwrap().is_empty());
    // The ply's whole time counts its solve (the fill of a refined net).
    let time = |k: &str| net["timing_ms"][k].as_f64().unwrap();
    assert!(time("fill") > 0.0 && time("total") >= time("fill"), "{}", net["timing_ms"]);
    let report = Command::cargo_bin("drape").unwrap().arg("report").arg(&out).output().unwrap();
    assert!(report.status.success(), "{}", String::from_utf8_lossy(&report.stderr));
    let html = std::fs::read_to_string(out.join("report/index.html")).unwrap();
    assert!(html.contains("<title>NOT CONVERGED (sheet)"));
    assert!(html.contains("<strong>NOT CONVERGED</strong>"));
}

#[test]
fn a_free_drape_is_the_same_on_one_thread_and_on_two() {
    let text = square_table_text(&[("spacing = 0.005", "spacing = 0.01"), ("grid = [41, 41]", "grid = [21, 21]")]);
    let on = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| drape_text(&text).1.remove(0))
    };
    let (one, two) = (on(1), on(2));
    assert!(converged(&one));
    assert_eq!(one.net.positions, two.net.positions, "bit for bit");
}

#[test]
fn refining_a_converged_free_drape_again_moves_no_node() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let scene = repo("geometries/square-table/scene.toml");
    let run = Command::cargo_bin("drape").unwrap().arg("run").arg(&scene).arg("--out").arg(&out).output().unwrap();
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    let again = dir.path().join("again");
    let refine = Command::cargo_bin("drape")
        .unwrap()
        .args(["refine", "--mode", "free", "--stick", "--net"])
        .arg(out.join("sheet.drape.json"))
        .arg("--tool")
        .arg(repo("geometries/square-table/square-table.obj"))
        .arg("--material")
        .arg(repo("materials/sze-liu-table1.toml"))
        .arg("--out")
        .arg(&again)
        .output()
        .unwrap();
    assert!(refine.status.success(), "{}", String::from_utf8_lossy(&refine.stderr));
    let read =
        |p: PathBuf| -> serde_json::Value { serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap() };
    let (a, b) = (read(out.join("sheet.drape.json")), read(again.join("sheet.drape.json")));
    let spacing = a["spacing"].as_f64().unwrap();
    let nodes = |v: &serde_json::Value| -> Vec<[f64; 3]> { serde_json::from_value(v["nodes"].clone()).unwrap() };
    let moved = nodes(&a)
        .iter()
        .zip(nodes(&b))
        .map(|(p, q)| ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt())
        .fold(0.0, f64::max);
    assert!(moved <= 1e-3 * spacing, "a node moved {moved} m");
    assert_eq!(b["meta"]["solver"]["converged"], serde_json::json!(true));
}

#[test]
fn every_ply_of_the_hemisphere_layup_presses_to_equilibrium_on_the_stack_below_it() {
    // The bundled four-ply layup with every ply mechanical. Before the plies below ended in a
    // ramp (geometry::offset::PLY_DROP_SLOPE), the third and fourth plies stopped on the cliff
    // one facet wide at the edge of the stack (`LineSearchFailed`, `Stalled`).
    let text = std::fs::read_to_string(repo("geometries/hemisphere/scene.toml"))
        .unwrap()
        .replace("\"hemisphere-20k.obj\"", "\"@/geometries/hemisphere/hemisphere-20k.obj\"")
        .replace("\"hemisphere-2k.obj\"", "\"@/geometries/hemisphere/hemisphere-2k.obj\"")
        .replace("../../materials", "@/materials")
        .replace("method = \"mechanical\"", "")
        .replace("grid = [79, 79]", "grid = [79, 79]\nmethod = \"mechanical\"");
    let (tool, plies) = drape_text(&text);
    assert_eq!(plies.len(), 4);
    for r in &plies {
        assert!(converged(r), "ply {}", r.net.name);
        let refined = r.refined.as_ref().unwrap();
        assert!(refined.steps[0].energy_end <= refined.steps[0].energy_start, "ply {}", r.net.name);
        // Every placed node lies on or above the tool (the stack below lifts the upper plies),
        // or (a known limit: a node carried past the rim, the tool's open edge, rides on the
        // smooth surface's continuation, and each of a load step's solves may carry it a little
        // further; with friction the fourth ply takes four) hangs within two spacings below it.
        let placed = r.net.positions.iter().zip(&r.net.status);
        for p in placed.filter(|(_, s)| **s == drape::kinematic::NodeStatus::Placed).map(|(p, _)| p) {
            let foot = tool.closest_point(p);
            let past_rim = p.z < 0.0 && p.z > -2.0 * r.net.spacing;
            assert!(
                (p - foot.point).dot(&tool.normal(foot.triangle)) > -1e-4 || past_rim,
                "ply {}: node {p} under the tool",
                r.net.name
            );
        }
    }
}

/// A sheet dropped on a tool whose file faces into the part (its facets wound the other way)
/// would come down on the back of the facets, where contact pushes it through the tool: the run
/// is refused before anything is computed (exit 2), naming `stack_side` and `sheet_normal`.
/// With `stack_side = "opposite"` the sheet drapes there exactly as on the file facing out.
/// (Before: the bundled sphere's sheet at 3 cm on its file turned over stopped without
/// equilibrium after 16 s with its fibres stretched, energy 0.6 J -> 2,800 J.) Two generated
/// spheres and a plate, other sizes and ply angles, the seed's soft fabric (stiff cards on such
/// spheres: `stiff_cards_dropped_free_on_a_small_sphere_settle_on_it`).
#[test]
fn a_sheet_dropped_on_the_back_of_the_tool_is_refused_and_drapes_as_on_the_front_on_the_other_side() {
    use crate::common::{read_json, refused_scene, run_scene, write_scene};
    use drape::geometry::{shapes, TriangleMesh};
    let turned = |m: &TriangleMesh| TriangleMesh {
        vertices: m.vertices.clone(),
        triangles: m.triangles.iter().map(|&[p, q, s]| [p, s, q]).collect(),
    };
    let sphere = |r: f64| shapes::icosphere(r, Point::origin(), 4);
    for (front, top, angle, first) in [
        (sphere(0.1), 0.1, 0.0, "node (5, 5)"),
        (sphere(0.13), 0.13, 30.0, "node (5, 5)"),
        (shapes::plate(0.3, 0.3, 12, 12), 0.0, 45.0, "node (0, 0)"),
    ] {
        let back = turned(&front);
        let scene = |tool: &str, side: &str| {
            format!(
                "units = \"m\"\ntool = \"{tool}\"\nfriction = 0.3\nreference = [1.0, 0.0, 0.0]\n{side}\
                 [[ply]]\nname = \"p\"\norigin = [0.0, 0.0, {top}]\nangle_deg = {angle}\n\
                 material = \"{}\"\nspacing = 0.02\ngrid = [11, 11]\nmethod = \"mechanical\"\n\
                 mode = \"free\"\nstart = \"flat\"\nmax_iterations = 2000\n",
                repo("materials/sze-liu-table1.toml").display()
            )
        };
        let tools = [("front.obj", &front), ("back.obj", &back)];
        let dir = tempfile::tempdir().unwrap();
        write_scene(dir.path(), &tools, "");
        let err = refused_scene(dir.path(), &scene("back.obj", ""));
        for says in ["back of the tool", "stack_side = \"opposite\"", "sheet_normal", first] {
            assert!(err.contains(says), "top {top}: the refusal does not say '{says}': {err}");
        }
        assert!(!dir.path().join("out").exists(), "a refused run wrote its folder");
        let mut nets = Vec::new();
        for (tool, side) in [("front.obj", ""), ("back.obj", "stack_side = \"opposite\"\n")] {
            let dir = tempfile::tempdir().unwrap();
            let (out, stdout) = run_scene(dir.path(), &tools, &scene(tool, side));
            let net = read_json(&out.join("p.drape.json"));
            assert_eq!(net["meta"]["solver"]["converged"], true, "{tool}: {stdout}");
            nets.push(net);
        }
        assert_eq!(nets[0]["nodes"], nets[1]["nodes"], "top {top}: the sheet on the turned file lies elsewhere");
    }
}
