//! `drape export` end to end: a ply draped on the 20k-triangle hemisphere, exported onto the
//! 2k-triangle hemisphere as the flow mesh in every format, read back by independent readers
//! (tools/flow_readback.py: meshio, pyNastran, parsers of the documented formats). For every
//! covered element the directions read back are unit, lie in the element's plane (from the
//! reader's own geometry), and their angle equals the ply's shear at that place (sampled on the
//! net by the test).
use assert_cmd::Command;
use drape::geometry::{Point, Vector};
use drape::io::read_net;
use drape::kinematic::sampler::NetSampler;
use drape::kinematic::DrapeNet;
use serde_json::Value;
use std::path::{Path, PathBuf};

/// Unit length and in-plane tolerances of directions read back (text round trips).
const UNIT_TOL: f64 = 1e-9;
/// The shear in a flow element (its plane) against the net's own shear at the element centroid
/// (the bilinear cell there, degrees): the 2k-triangle facets tilt by up to about 2 deg against
/// the net's cells, which changes projected angles by a fraction of a degree.
const SHEAR_AT_PLACE_TOL_DEG: f64 = 0.5;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn skip_python() -> bool {
    if std::env::var("DRAPE_SKIP_PYTHON").is_ok_and(|v| v == "1") {
        eprintln!("flow_export: DRAPE_SKIP_PYTHON=1: skipped the independent read-back");
        return true;
    }
    false
}

fn readback(format: &str, files: &[&Path]) -> Value {
    let out = std::process::Command::new("python3")
        .arg(root().join("tools/flow_readback.py"))
        .arg(format)
        .args(files)
        .output()
        .expect("python3 runs");
    assert!(out.status.success(), "flow_readback {format}: {}", String::from_utf8_lossy(&out.stderr));
    serde_json::from_slice(&out.stdout).unwrap()
}

/// A +45 ply on the hemisphere (drape kinematic) and its export in `format` onto the 2k mesh.
struct Case {
    _dir: tempfile::TempDir,
    dir: PathBuf,
    net: DrapeNet,
}

fn drape_ply() -> Case {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path().to_path_buf();
    let tool = root().join("geometries/hemisphere/hemisphere-20k.obj");
    Command::cargo_bin("drape")
        .unwrap()
        .args(["kinematic", "--tool", tool.to_str().unwrap(), "--origin", "0,0,0.1", "--warp", "1,1,0"])
        .args([
            "--spacing",
            "0.004",
            "--grid",
            "79,79",
            "--name",
            "p45",
            "--format",
            "json",
            "--out",
            d.to_str().unwrap(),
        ])
        .assert()
        .success();
    let net = read_net(&d.join("p45.drape.json")).unwrap();
    Case { _dir: dir, dir: d, net }
}

fn export(case: &Case, format: &str, out: &str, extra: &[&str]) -> PathBuf {
    let mesh = root().join("geometries/hemisphere/hemisphere-2k.obj");
    let card = root().join("materials/glass-plain-weave.toml");
    let out = case.dir.join(out);
    Command::cargo_bin("drape")
        .unwrap()
        .args(["export", "--net", case.dir.join("p45.drape.json").to_str().unwrap(), "--mesh", mesh.to_str().unwrap()])
        .args(["--format", format, "--out", out.to_str().unwrap(), "--material", card.to_str().unwrap()])
        .args(extra)
        .assert()
        .success();
    out
}

/// A number of the read-back (non-finite ones come as text, "nan").
fn num(v: &Value) -> f64 {
    v.as_f64().or_else(|| v.as_str().and_then(|s| s.parse().ok())).unwrap_or_else(|| panic!("not a number: {v}"))
}

fn v3(v: &Value) -> Vector {
    Vector::new(num(&v[0]), num(&v[1]), num(&v[2]))
}

/// Element geometry from a reader: centroid, unit normal (right-handed over the corners), unit
/// first edge projected into the plane.
struct Element {
    centroid: Point,
    normal: Vector,
    edge: Vector,
}

fn element(points: &[Point]) -> Element {
    let c = Point::from(points.iter().fold(Vector::zeros(), |s, p| s + p.coords) / points.len() as f64);
    let mut n = Vector::zeros();
    for k in 0..points.len() {
        n += points[k].coords.cross(&points[(k + 1) % points.len()].coords);
    }
    let n = n.normalize();
    let e = points[1] - points[0];
    Element { centroid: c, normal: n, edge: (e - n * n.dot(&e)).normalize() }
}

/// The ply's shear (degrees) and warp at an element, from the net itself; `None` off the net.
fn net_at(sampler: &NetSampler, e: &Element, reach: f64) -> Option<(f64, Vector)> {
    let s = sampler.cover(&e.centroid, reach)?;
    let w = s.warp - e.normal * e.normal.dot(&s.warp);
    Some((s.shear().to_degrees(), w.normalize()))
}

fn angle_deg(a: &Vector, b: &Vector) -> f64 {
    a.cross(b).norm().atan2(a.dot(b)).to_degrees()
}

/// Check a covered element's directions: unit, in plane, angle = 90 - shear, shear = the net's.
fn check_directions(
    e: &Element,
    warp: &Vector,
    weft: &Vector,
    shear_deg: f64,
    expected: (f64, Vector),
    worst: &mut f64,
    what: &str,
) {
    assert!((warp.norm() - 1.0).abs() < UNIT_TOL && (weft.norm() - 1.0).abs() < UNIT_TOL, "{what}: not unit");
    assert!(
        warp.dot(&e.normal).abs() < UNIT_TOL && weft.dot(&e.normal).abs() < UNIT_TOL,
        "{what}: not in the element plane"
    );
    assert!((angle_deg(warp, weft) - (90.0 - shear_deg)).abs() < 1e-7, "{what}: angle(warp, weft) != 90 - shear");
    let diff = (shear_deg - expected.0).abs();
    *worst = worst.max(diff);
    assert!(diff < SHEAR_AT_PLACE_TOL_DEG, "{what}: shear {shear_deg} deg, the net's {} deg", expected.0);
    assert!(angle_deg(warp, &expected.1) < 1e-6, "{what}: warp is not the net's warp projected into the element");
}

#[test]
fn every_format_reads_back_unit_in_plane_directions_at_the_plys_shear() {
    if skip_python() {
        return;
    }
    let case = drape_ply();
    let sampler = NetSampler::new(&case.net).unwrap();
    let reach = case.net.spacing + 5.5e-4;

    // VTU (meshio): the geometry of every element and its fields.
    let vtu = readback("vtu", &[&export(&case, "vtu", "flow.vtu", &["--permeability"])]);
    let points: Vec<Point> = vtu["points"].as_array().unwrap().iter().map(|p| Point::from(v3(p))).collect();
    let cells = vtu["cells"].as_array().unwrap();
    let data = &vtu["cell_data"];
    for name in ["element_id", "covered", "warp", "weft", "shear_deg", "thickness", "vf", "permeability"] {
        assert!(data.get(name).is_some(), "VTU has no cell data '{name}'");
    }
    let mut elements = std::collections::HashMap::new();
    let (mut covered, mut worst) = (0, 0.0f64);
    for (k, c) in cells.iter().enumerate() {
        let corners: Vec<Point> =
            c["nodes"].as_array().unwrap().iter().map(|n| points[n.as_u64().unwrap() as usize]).collect();
        let e = element(&corners);
        let scalar = |name: &str| num(&data[name][k][0]);
        let id = scalar("element_id") as u64;
        let at = net_at(&sampler, &e, reach);
        let is_covered = scalar("covered") == 1.0;
        assert_eq!(is_covered, at.is_some(), "element {id}: covered flag against the net");
        if let Some(expected) = at {
            covered += 1;
            let shear = scalar("shear_deg");
            check_directions(
                &e,
                &v3(&data["warp"][k]),
                &v3(&data["weft"][k]),
                shear,
                expected,
                &mut worst,
                &format!("VTU element {id}"),
            );
            // Fixed cavity: Vf = Vf0 / cos(shear) with the card's Vf0.
            let vf = scalar("vf");
            assert!((vf - 0.429 / shear.to_radians().cos()).abs() < 1e-9, "element {id}: vf {vf}");
            assert_eq!(scalar("thickness"), 5.5e-4);
        } else {
            // NaN, not a zero a flow solver would read as a value.
            for f in ["shear_deg", "thickness", "vf"] {
                assert!(scalar(f).is_nan(), "uncovered element {id} carries a {f}");
            }
        }
        elements.insert(id, (e, at));
    }
    eprintln!("VTU: {covered} of {} elements covered; largest |shear - net's shear| {worst:.4} deg", cells.len());
    assert!(covered > 1800, "{covered} covered");

    // CSV (python csv): one row per element; same checks.
    let csv = readback("csv", &[&export(&case, "csv", "flow.csv", &[])]);
    let f = |row: &Value, n: &str| row[n].as_str().unwrap().parse::<f64>().unwrap();
    let mut worst = 0.0f64;
    for row in csv["rows"].as_array().unwrap() {
        let id: u64 = row["element_id"].as_str().unwrap().parse().unwrap();
        let (e, at) = &elements[&id];
        assert_eq!(row["covered"].as_str().unwrap() == "1", at.is_some(), "CSV element {id}");
        if let Some(expected) = at {
            let warp = Vector::new(f(row, "warp_x"), f(row, "warp_y"), f(row, "warp_z"));
            let weft = Vector::new(f(row, "weft_x"), f(row, "weft_y"), f(row, "weft_z"));
            check_directions(e, &warp, &weft, f(row, "shear_deg"), *expected, &mut worst, &format!("CSV element {id}"));
        }
    }

    // Nastran (pyNastran): THETA from G1->G2 about the element normal gives the net's warp.
    let bdf_path = export(&case, "nastran", "flow.bdf", &[]);
    let bdf = readback("nastran", &[&bdf_path]);
    // The deck reads alone with cross-referencing: the OBJ mesh has no PIDs, so every element is
    // on PID 1, a PSHELL drape writes of the card's fabric (MAT8).
    let xref = readback("nastran-xref", &[&bdf_path]);
    assert_eq!(xref["rejected"], serde_json::json!([]));
    for el in xref["elements"].as_object().unwrap().values() {
        assert_eq!(
            (el["pid"].as_u64(), el["property"].as_str(), el["material"].as_str()),
            (Some(1), Some("PSHELL"), Some("MAT8"))
        );
    }
    let deck = &bdf["decks"][0];
    let grids = &deck["grids"];
    let mut thetas = 0;
    for (id, el) in deck["elements"].as_object().unwrap() {
        let id: u64 = id.parse().unwrap();
        let corners: Vec<Point> = el["nodes"]
            .as_array()
            .unwrap()
            .iter()
            .map(|n| Point::from(v3(&grids[n.as_u64().unwrap().to_string()])))
            .collect();
        let e = element(&corners);
        // Uncovered elements keep their PID with a blank THETA (which pyNastran reads as 0).
        let pid = el["pid"].as_u64().unwrap();
        let blank = el["theta_blank"].as_bool().unwrap();
        match (&elements[&id].1, el["theta"].as_f64().filter(|_| !blank)) {
            (Some((_, warp)), Some(theta)) => {
                let r =
                    nalgebra::Rotation3::from_axis_angle(&nalgebra::Unit::new_normalize(e.normal), theta.to_radians());
                assert!(
                    angle_deg(&(r * e.edge), warp) < 1e-6,
                    "Nastran element {id}: THETA {theta} does not give the warp"
                );
                thetas += 1;
            }
            (None, None) => assert_eq!(pid, 1, "Nastran element {id}: uncovered keeps the mesh's PID (1 for OBJ)"),
            (at, theta) => panic!("Nastran element {id}: covered {} but THETA {theta:?}", at.is_some()),
        }
    }
    assert_eq!(thetas, covered);

    // Abaqus (meshio + the documented *DISTRIBUTION layout): a = warp, b = weft per element.
    let inp = readback("abaqus", &[&export(&case, "abaqus", "flow.inp", &[])]);
    let dist = inp["distributions"].as_object().unwrap().values().next().expect("one distribution");
    let rows = dist["rows"].as_object().unwrap();
    assert_eq!(rows.len(), covered);
    let mut worst = 0.0f64;
    for (id, r) in rows {
        let id: u64 = id.parse().unwrap();
        let (e, at) = &elements[&id];
        let r: Vec<f64> = r.as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect();
        let (a, b) = (Vector::new(r[0], r[1], r[2]), Vector::new(r[3], r[4], r[5]));
        let expected = at.expect("only covered elements are distributed");
        let shear = 90.0 - angle_deg(&a, &b);
        check_directions(e, &a, &b, shear, expected, &mut worst, &format!("Abaqus element {id}"));
    }

    // OptiStruct (documented DRAPE/PLY layout), free cavity: thinning T = 1 / cos(shear) and
    // element THETA + PLY THETA + DRAPE THETA gives the warp.
    let fem_path = export(&case, "optistruct", "flow.fem", &["--cavity", "free"]);
    let fem = readback("optistruct", &[&fem_path]);
    // Cross-referenced (pyNastran taught PCOMPP, our parser for PLY, STACK, SET, DRAPE): nothing
    // dangles; covered elements on the PCOMPP, the others on a PSHELL of their own.
    let xref = readback("optistruct-xref", &[&fem_path]);
    assert_eq!(xref["dangling"], serde_json::json!([]));
    for (id, el) in xref["elements"].as_object().unwrap() {
        let covered = elements[&id.parse::<u64>().unwrap()].1.is_some();
        let want = if covered { (Some(1), Some("PCOMPP")) } else { (Some(2), Some("PSHELL")) };
        assert_eq!((el["pid"].as_u64(), el["property"].as_str()), want, "OptiStruct element {id}");
    }
    let ply = fem["plies"].as_object().unwrap().values().next().unwrap();
    let drape = &fem["drapes"][ply["did"].as_u64().unwrap().to_string()];
    let mut checked = 0;
    for (id, el) in fem["elements"].as_object().unwrap() {
        let Some((shear, warp)) = elements[&id.parse::<u64>().unwrap()].1 else { continue };
        let d = drape[id].as_array().expect("a covered element has a DRAPE row");
        let (t, dtheta) = (d[0].as_f64().unwrap(), d[1].as_f64().unwrap());
        assert!(
            (t - 1.0 / shear.to_radians().cos()).abs() < 0.02 * t,
            "OptiStruct element {id}: thinning {t}, shear {shear}"
        );
        let theta = el["theta"].as_f64().unwrap_or(0.0) + ply["theta"].as_f64().unwrap() + dtheta;
        let g = &fem["grids"];
        let corners: Vec<Point> = el["nodes"]
            .as_array()
            .unwrap()
            .iter()
            .map(|n| Point::from(v3(&g[n.as_u64().unwrap().to_string()])))
            .collect();
        let e = element(&corners);
        let r = nalgebra::Rotation3::from_axis_angle(&nalgebra::Unit::new_normalize(e.normal), theta.to_radians());
        assert!(angle_deg(&(r * e.edge), &warp) < 1e-6, "OptiStruct element {id}: angles do not give the warp");
        checked += 1;
    }
    assert_eq!(checked, covered);

    // RTMsim (its read_nastran_mesh layout and 14-line input file): every element, sets of the
    // laminate and one of the elements no ply covers, porosity 1 - Vf within what the ply's shear
    // makes of Vf0.
    let mesh = export(&case, "rtmsim", "flow-rtmsim.bdf", &["--permeability"]);
    let input = case.dir.join("flow-rtmsim_input.txt");
    let rtm = readback("rtmsim", &[&mesh, &input]);
    let uncovered = rtm["uncovered"].as_array().unwrap().len();
    assert_eq!(uncovered, elements.len() - covered, "RTMsim lists exactly the uncovered elements");
    assert!(uncovered > 0, "the case leaves elements uncovered");
    assert_eq!(rtm["tris"].as_object().unwrap().len(), elements.len(), "every element, none split (all triangles)");
    // The uncovered elements are the last SET used, alone, a preform region of their own.
    let sets: Vec<Vec<u64>> = rtm["sets"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s.as_array().unwrap().iter().map(|x| x.as_u64().unwrap()).collect())
        .collect();
    let last = sets.iter().rposition(|s| !s.is_empty()).expect("a SET is written");
    let mut want: Vec<u64> = rtm["uncovered"].as_array().unwrap().iter().map(|x| x.as_u64().unwrap()).collect();
    let mut got = sets[last].clone();
    want.sort();
    got.sort();
    assert_eq!(got, want, "SET {} holds the uncovered elements", last + 1);
    assert_eq!(rtm["patchtypes"][last], 2);
    for p in rtm["params"].as_array().unwrap() {
        let porosity = p[1].as_f64().unwrap();
        assert!(
            porosity > 1.0 - 0.429 / 50f64.to_radians().cos() && porosity <= 1.0 - 0.429 + 1e-9,
            "porosity {porosity}"
        );
    }
}

/// `drape export --vtu binary` writes the compressed binary VTU; VTK's reader finds in it the
/// arrays of the ASCII file bit for bit (NaN on the uncovered elements), and a bad `--vtu` is
/// refused.
#[test]
fn export_vtu_binary_option_reads_in_vtk_as_the_ascii() {
    use crate::common::vtk_reader::{read_with_vtk, vtk_ready};
    let case = drape_ply();
    let bin = export(&case, "vtu", "flow-bin.vtu", &["--vtu", "binary"]);
    let ascii = export(&case, "vtu", "flow-ascii.vtu", &["--vtu", "ascii"]);
    let auto = export(&case, "vtu", "flow-auto.vtu", &[]);
    assert_eq!(std::fs::read(&auto).unwrap(), std::fs::read(&ascii).unwrap(), "2k elements: ASCII by default");
    let text = String::from_utf8_lossy(&std::fs::read(&bin).unwrap()[..400]).into_owned();
    assert!(text.contains("compressor=\"vtkZLibDataCompressor\""), "{text}");
    let refused = Command::cargo_bin("drape")
        .unwrap()
        .args(["export", "--net", case.dir.join("p45.drape.json").to_str().unwrap()])
        .args(["--mesh", root().join("geometries/hemisphere/hemisphere-2k.obj").to_str().unwrap()])
        .args(["--format", "vtu", "--out", case.dir.join("x.vtu").to_str().unwrap(), "--vtu", "zip"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&refused.stderr);
    assert!(!refused.status.success() && stderr.contains("--vtu: unknown VTU encoding 'zip'"), "{stderr}");
    assert!(!case.dir.join("x.vtu").exists());
    if skip_python() || !vtk_ready() {
        return;
    }
    let (b, a) = (read_with_vtk(&bin), read_with_vtk(&ascii));
    assert_eq!(b.arrays.keys().collect::<Vec<_>>(), a.arrays.keys().collect::<Vec<_>>());
    for (key, values) in &b.arrays {
        let same = values.len() == a.arrays[key].len()
            && values.iter().zip(&a.arrays[key]).all(|(x, y)| x.to_bits() == y.to_bits() || (x.is_nan() && y.is_nan()));
        assert!(same, "{key} differs between the binary and the ASCII file");
    }
    let covered = &b.arrays["cell.covered"];
    let vf = &b.arrays["cell.vf"];
    assert!(covered.contains(&0.0), "some elements uncovered");
    for (c, v) in covered.iter().zip(vf) {
        assert_eq!(*c == 0.0, v.is_nan(), "NaN exactly on the uncovered elements");
    }
}

/// Lengths on the command line in millimetres (`--units mm`) export the same file as the same
/// lengths in metres; an unknown unit is refused before anything is written.
#[test]
fn export_lengths_in_millimetres_are_the_same_lengths_in_metres() {
    let case = drape_ply();
    let metres =
        export(&case, "csv", "m.csv", &["--permeability", "--thickness", "0.00031", "--fibre-radius", "3.5e-6"]);
    let mm = export(
        &case,
        "csv",
        "mm.csv",
        &["--permeability", "--units", "mm", "--thickness", "0.31", "--fibre-radius", "0.0035"],
    );
    let (a, b) = (std::fs::read_to_string(&metres).unwrap(), std::fs::read_to_string(&mm).unwrap());
    assert_eq!(a, b);
    // And the thickness is the one given, not the card's.
    let card = export(&case, "csv", "card.csv", &["--permeability", "--fibre-radius", "3.5e-6"]);
    assert_ne!(std::fs::read_to_string(&card).unwrap(), a);
    let refused = Command::cargo_bin("drape")
        .unwrap()
        .args(["export", "--net", case.dir.join("p45.drape.json").to_str().unwrap()])
        .args(["--mesh", root().join("geometries/hemisphere/hemisphere-2k.obj").to_str().unwrap()])
        .args(["--format", "csv", "--out", case.dir.join("x.csv").to_str().unwrap(), "--units", "inch"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&refused.stderr);
    assert_eq!(refused.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("--units"), "{stderr}");
    assert!(!case.dir.join("x.csv").exists());
}

/// A net sheared by `shear_deg` everywhere: warp along x, the weft turned to meet it at
/// 90 - shear_deg, the origin node at the origin of the xy plane.
fn uniformly_sheared_net(shear_deg: f64) -> DrapeNet {
    let (n, d) = (11, 0.01);
    let g = shear_deg.to_radians();
    let (warp, weft) = (Vector::x(), Vector::new(g.sin(), g.cos(), 0.0));
    let mut net = DrapeNet::new("s", d, n, n, (n / 2, n / 2));
    for i in 0..n {
        for j in 0..n {
            let k = net.index(i, j);
            let (u, v) = ((i as f64 - (n / 2) as f64) * d, (j as f64 - (n / 2) as f64) * d);
            net.positions[k] = Point::origin() + warp * u + weft * v;
            net.status[k] = drape::kinematic::NodeStatus::Placed;
        }
    }
    net
}

/// A ply sheared past the collapse of its cells (75 deg: a mechanical result crushed or folded
/// there) is exported at that shear's thickness and Vf, and the export says where; short of it
/// the thickness is t0 / cos(shear) as before. At a fold, cos(shear) -> 0 wrote a formed hat
/// box's 0.35 mm ply as 254 mm thick.
#[test]
fn a_ply_sheared_past_its_collapse_is_exported_at_the_collapse_not_as_a_spike() {
    let dir = tempfile::tempdir().unwrap();
    // One small element about the origin node: it lies on the net however thin its cells.
    let mesh = dir.path().join("element.obj");
    std::fs::write(&mesh, "v -0.002 -0.00005 0\nv 0.002 -0.00005 0\nv 0 0.0001 0\nf 1 2 3\n").unwrap();
    let t0 = 5e-4;
    let card = root().join("materials/glass-plain-weave.toml");
    let vf0 = drape::material::MaterialCard::load(&card).unwrap().flow.unwrap().fibre_volume_fraction;
    let collapse = drape::material::flow::COLLAPSED_SHEAR_DEG;
    for shear_deg in [0.0, 30.0, 60.0, 74.0, 76.0, 85.0, 89.9] {
        let net_path = dir.path().join(format!("s{shear_deg}.drape.json"));
        drape::io::write_json(&uniformly_sheared_net(shear_deg), &net_path).unwrap();
        for cavity in ["free", "fixed"] {
            let out = dir.path().join(format!("s{shear_deg}-{cavity}.csv"));
            let run = Command::cargo_bin("drape")
                .unwrap()
                .args(["export", "--net", net_path.to_str().unwrap(), "--mesh", mesh.to_str().unwrap()])
                .args(["--format", "csv", "--out", out.to_str().unwrap(), "--cavity", cavity])
                .args(["--material", card.to_str().unwrap(), "--thickness", &t0.to_string()])
                .output()
                .unwrap();
            let stdout = String::from_utf8_lossy(&run.stdout);
            assert!(run.status.success(), "{shear_deg} deg: {stdout} {}", String::from_utf8_lossy(&run.stderr));
            let text = std::fs::read_to_string(&out).unwrap();
            let header: Vec<&str> = text.lines().next().unwrap().split(',').collect();
            let row: Vec<&str> = text.lines().nth(1).unwrap().split(',').collect();
            let field = |name: &str| row[header.iter().position(|h| *h == name).unwrap()].parse::<f64>().unwrap();
            assert!((field("shear_deg") - shear_deg).abs() < 1e-6, "{shear_deg} deg: {text}");
            let taken = shear_deg.min(collapse).to_radians();
            let (t, vf) = match cavity {
                "free" => (t0 / taken.cos(), vf0),
                _ => (t0, (vf0 / taken.cos()).min(drape::material::flow::VF_CAP)),
            };
            assert!((field("thickness") - t).abs() < 1e-9 * t, "{shear_deg} deg {cavity}: {text}");
            assert!((field("vf") - vf).abs() < 1e-9, "{shear_deg} deg {cavity}: {text}");
            let said = stdout.contains(&format!("1 element lies on cells of the drape sheared past {collapse} deg"));
            assert_eq!(said, shear_deg > collapse, "{shear_deg} deg: {stdout}");
        }
    }
}
