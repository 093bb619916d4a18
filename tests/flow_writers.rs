//! Flow-mesh writers read back by independent code (tools/flow_readback.py: meshio, pyNastran,
//! Python's csv and parsers written from the Abaqus, OptiStruct and RTMsim documentation).
//!
//! A small curved mesh with triangles, warped and oblique quads and non-consecutive node and
//! element ids; fibres built in the test from a known angle THETA (from edge G1 -> G2), shear
//! and thinning, for one net and for a 3-ply layup in which some plies miss some elements.
//!
//! Needs `python3` with meshio, numpy and pyNastran (tools/requirements.txt). Set
//! DRAPE_SKIP_PYTHON=1 to skip the Python part (the Rust-side checks still run).
use drape::geometry::{Point, Vector};
use drape::io::csv::FLOW_CSV_HEADER;
use drape::io::flow::{write_flow, write_rtmsim, FlowFormat};
use drape::io::rtmsim::MAX_RTMSIM_SETS;
use drape::io::ExportError;
use drape::mapping::{ElementFibres, LayupMap, MeshCard, MeshCards, PlyFabric, PlyMap};
use drape::mapping::{ElementShape, FlowElement, FlowMesh};
use nalgebra::Matrix3;
use serde_json::Value;
use std::f64::consts::{FRAC_PI_2, PI};
use std::path::{Path, PathBuf};
use std::process::Command;

/// Directions read back from text written with `{:?}` (exact) and recomputed geometry.
const EXACT_TOL: f64 = 1e-12;
/// Angles (degrees) read back from 16-character Nastran fields.
const LARGE_FIELD_DEG_TOL: f64 = 1e-8;
/// Directions rebuilt from a THETA in a 16-character field.
const LARGE_FIELD_DIR_TOL: f64 = 1e-9;
/// Coordinates in RTMsim's 8-character fields (metres, part of size 0.3 m).
const SHORT_FIELD_TOL: f64 = 1e-6;

const NOMINAL_T: f64 = 3.0e-4;
const VF0: f64 = 0.5;

fn rotate(v: Vector, n: Vector, angle: f64) -> Vector {
    let (s, c) = angle.sin_cos();
    v * c + n.cross(&v) * s + n * n.dot(&v) * (1.0 - c)
}

/// Signed angle from `a` to `b` about `n`.
fn angle_about(a: Vector, b: Vector, n: Vector) -> f64 {
    n.dot(&a.cross(&b)).atan2(a.dot(&b))
}

fn wrap_deg(d: f64) -> f64 {
    let r = d.rem_euclid(360.0);
    if r > 180.0 {
        r - 360.0
    } else {
        r
    }
}

/// Curved, warped mesh: nodes (i, j) at (0.1 i, 0.1 j, 0.02 i j) with ids 10 i + j + 11, and an
/// extra node 40 off the surface for an oblique triangle.
fn mesh() -> FlowMesh {
    let mut nodes = Vec::new();
    let mut node_ids = Vec::new();
    for i in 0..3 {
        for j in 0..3 {
            nodes.push(Point::new(0.1 * i as f64, 0.1 * j as f64, 0.02 * (i * j) as f64));
            node_ids.push(10 * i as u64 + j as u64 + 11);
        }
    }
    nodes.push(Point::new(0.25, 0.1, 0.05));
    node_ids.push(40);
    let idx = |id: u64| node_ids.iter().position(|&x| x == id).unwrap();
    let el = |id: u64, ns: &[u64]| FlowElement {
        id,
        shape: if ns.len() == 3 { ElementShape::Tria3 } else { ElementShape::Quad4 },
        nodes: ns.iter().map(|&n| idx(n)).collect(),
        property: user_pid(id),
    };
    let elements = vec![
        el(7, &[11, 21, 22, 12]),
        el(3, &[12, 22, 23, 13]),
        el(42, &[21, 31, 32]),
        el(1000, &[21, 32, 22]),
        el(15, &[22, 32, 33, 23]),
        el(16, &[31, 40, 32]),
    ];
    FlowMesh { path: PathBuf::from("test-mesh.bdf"), nodes, node_ids, elements, scale: 1.0, cards: user_cards() }
}

/// The user's cards of [`mesh`]: PSHELL 5 on MAT8 100, PCOMP 6 of MAT1 101 and MAT8 100; none
/// for the elements without a PID (1 in the decks); a MATT8 drape does not carry.
fn user_cards() -> MeshCards {
    let card = |name: &str, fields: &[&str]| MeshCard {
        name: name.into(),
        id: fields[0].parse().unwrap(),
        fields: fields.iter().map(|f| f.to_string()).collect(),
        origin: format!("test-mesh.bdf line {}", fields[0]),
    };
    MeshCards {
        properties: vec![
            card("PSHELL", &["5", "100", ".002", "100"]),
            card("PCOMP", &["6", "", "", "", "", "", "", "", "101", ".0005", "0.", "", "100", ".0005", "90."]),
        ],
        materials: vec![
            card("MAT8", &["100", "140.+9", "10.+9", ".3", "5.+9", "", "", "1600."]),
            card("MAT1", &["101", "70.+9", "", ".33", "2700."]),
        ],
        not_carried: vec!["MATT8 100 (test-mesh.bdf line 9)".into()],
    }
}

/// The fabric of the plies of [`layup_map`].
fn fabric() -> PlyFabric {
    PlyFabric {
        card: "test-fabric".into(),
        tension_warp: 8.0e6,
        tension_weft: 6.0e6,
        shear: 5.0,
        areal_mass: 0.6,
        thickness: NOMINAL_T,
    }
}

/// The user's property of each element of [`mesh`]: 0 (none) for elements 15 and 16.
fn user_pid(id: u64) -> u64 {
    match id {
        7 | 3 => 5,
        42 | 1000 => 6,
        _ => 0,
    }
}

/// The PID an element keeps in a Nastran deck: the user's, else 1.
fn kept_pid(id: u64) -> u64 {
    match user_pid(id) {
        0 => 1,
        p => p,
    }
}

/// Ply angles (rad) and which elements (by index) each ply misses.
const PLIES: [(&str, f64, &[usize]); 3] = [("base", 0.0, &[5]), ("p45", PI / 4.0, &[1]), ("p-45", -PI / 4.0, &[4, 5])];

fn shear_of(e: usize, k: usize) -> f64 {
    0.05 + 0.07 * e as f64 + 0.02 * k as f64
}

fn change_of(e: usize, k: usize) -> f64 {
    0.03 * (e as f64 + 1.0) * if k.is_multiple_of(2) { 1.0 } else { -1.0 }
}

fn fibres(mesh: &FlowMesh, e: usize, k: usize, ply_angle: f64) -> ElementFibres {
    let n = mesh.normal(e).unwrap();
    let u = mesh.first_edge(e).unwrap();
    let r = Vector::new(1.0, 0.2, 0.0).normalize();
    let nominal = angle_about(u, r - n * n.dot(&r), n) + ply_angle;
    let change = change_of(e, k);
    let theta = nominal + change;
    let shear = shear_of(e, k);
    let warp = rotate(u, n, theta);
    let weft = rotate(warp, n, FRAC_PI_2 - shear);
    let b1 = (warp + weft).normalize();
    let b2 = n.cross(&b1);
    let (k1, k2, k3) = (2.0e-10 * (1.0 - shear), 0.5e-10, 1.0e-12);
    let perm = b1 * b1.transpose() * k1 + b2 * b2.transpose() * k2 + n * n.transpose() * k3;
    let wrap = |a: f64| (a + PI).rem_euclid(2.0 * PI) - PI;
    ElementFibres {
        warp,
        weft,
        normal: n,
        shear,
        theta: wrap(theta),
        angle_change: change,
        thickness: NOMINAL_T / shear.cos(),
        nominal_thickness: NOMINAL_T,
        vf: VF0,
        permeability: Some(perm),
    }
}

fn layup_map(mesh: &FlowMesh, layup: bool) -> LayupMap {
    let n = mesh.elements.len();
    let plies: Vec<PlyMap> = PLIES
        .iter()
        .take(if layup { 3 } else { 1 })
        .enumerate()
        .map(|(k, (name, angle, missing))| PlyMap {
            ply: name.to_string(),
            elements: (0..n).map(|e| (!missing.contains(&e)).then(|| fibres(mesh, e, k, *angle))).collect(),
            fabric: Some(fabric()),
        })
        .collect();
    let mut thickness = vec![0.0; n];
    let mut mean_vf = vec![None; n];
    let mut permeability = vec![None; n];
    for e in 0..n {
        let cov: Vec<&ElementFibres> = plies.iter().filter_map(|p| p.elements[e].as_ref()).collect();
        if cov.is_empty() {
            continue;
        }
        let t: f64 = cov.iter().map(|f| f.thickness).sum();
        thickness[e] = t;
        mean_vf[e] = Some(cov.iter().map(|f| f.vf * f.thickness).sum::<f64>() / t);
        permeability[e] = Some(cov.iter().fold(Matrix3::zeros(), |s, f| s + f.permeability.unwrap() * f.thickness) / t);
    }
    LayupMap { plies, layup, thickness, mean_vf, permeability }
}

fn python_ready() -> bool {
    if std::env::var("DRAPE_SKIP_PYTHON").is_ok_and(|v| v == "1") {
        eprintln!("flow_writers: DRAPE_SKIP_PYTHON=1: skipped the independent Python read-back");
        return false;
    }
    let probe = Command::new("python3").args(["-c", "import meshio, numpy, pyNastran, vtk"]).output();
    match probe {
        Ok(o) if o.status.success() => true,
        Ok(o) => panic!(
            "python3 cannot import meshio/numpy/pyNastran/vtk ({}). Run `python3 -m pip install -r tools/requirements.txt`, \
             or set DRAPE_SKIP_PYTHON=1 to skip this check.",
            String::from_utf8_lossy(&o.stderr).trim()
        ),
        Err(e) => panic!("cannot run python3 ({e}); install it or set DRAPE_SKIP_PYTHON=1"),
    }
}

fn readback(format: &str, files: &[PathBuf]) -> Value {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tools/flow_readback.py");
    let out = Command::new("python3").arg(&script).arg(format).args(files).output().unwrap();
    assert!(out.status.success(), "{} {format} failed:\n{}", script.display(), String::from_utf8_lossy(&out.stderr));
    serde_json::from_slice(&out.stdout).unwrap_or_else(|e| panic!("readback output is not JSON ({e})"))
}

fn f64s(v: &Value) -> Vec<f64> {
    // Non-finite numbers come as text ("nan") from the read-back.
    let number = |x: &Value| x.as_f64().or_else(|| x.as_str().and_then(|s| s.parse().ok())).unwrap();
    v.as_array().unwrap_or_else(|| panic!("not an array: {v}")).iter().map(number).collect()
}

fn vec3(v: &[f64]) -> Vector {
    Vector::new(v[0], v[1], v[2])
}

/// Unit, in the element plane, at 90 deg - shear from each other.
fn assert_frame(mesh: &FlowMesh, e: usize, warp: Vector, weft: Vector, shear_deg: f64, tol: f64, what: &str) {
    let n = mesh.normal(e).unwrap();
    assert!((warp.norm() - 1.0).abs() < tol && (weft.norm() - 1.0).abs() < tol, "{what}: not unit");
    assert!(warp.dot(&n).abs() < tol && weft.dot(&n).abs() < tol, "{what}: not in the element plane");
    let between = warp.dot(&weft).clamp(-1.0, 1.0).acos().to_degrees();
    assert!((between - (90.0 - shear_deg)).abs() < 1e-9, "{what}: warp-weft {between} vs 90 - {shear_deg}");
}

fn write(mesh: &FlowMesh, map: &LayupMap, format: FlowFormat, out: &Path) -> Vec<PathBuf> {
    let files = write_flow(mesh, map, format, out).unwrap();
    for f in &files {
        assert!(f.is_file(), "{} missing", f.display());
    }
    files
}

#[test]
fn vtu_fields_and_frames() {
    let mesh = mesh();
    for layup in [false, true] {
        let map = layup_map(&mesh, layup);
        let dir = tempfile::tempdir().unwrap();
        let files = write(&mesh, &map, FlowFormat::Vtu, &dir.path().join("flow.vtu"));
        let text = std::fs::read_to_string(&files[0]).unwrap();
        // Uncovered elements carry NaN (every map here leaves some element uncovered), never inf.
        assert!(text.contains("NaN") && !text.contains("inf"));
        if !python_ready() {
            continue;
        }
        // Cells through meshio, the fields through VTK's own reader.
        let s = readback("vtu", &files);
        let vtk = readback("vtu-vtk", &files);
        assert_eq!(vtk["cells"], mesh.elements.len());
        assert_eq!(vtk["points"], mesh.nodes.len());
        let data = vtk["cell_data"].as_object().unwrap();
        let mut names: Vec<&str> = data.keys().map(String::as_str).collect();
        names.sort();
        let per_ply = ["covered", "warp", "weft", "shear_deg", "thickness", "vf", "permeability"];
        let mut expected: Vec<String> = vec!["element_id".into()];
        for p in &map.plies {
            let prefix = if layup { format!("{}_", p.ply) } else { String::new() };
            expected.extend(per_ply.iter().map(|f| format!("{prefix}{f}")));
        }
        if layup {
            expected.extend(["laminate_thickness", "mean_vf", "laminate_permeability"].map(String::from));
        }
        expected.sort();
        assert_eq!(names, expected, "field names");
        let cells = s["cells"].as_array().unwrap();
        assert_eq!(cells.len(), mesh.elements.len());
        for (e, el) in mesh.elements.iter().enumerate() {
            let ty = if el.shape == ElementShape::Tria3 { "triangle" } else { "quad" };
            assert_eq!(cells[e]["type"], ty);
            let nodes: Vec<usize> =
                cells[e]["nodes"].as_array().unwrap().iter().map(|v| v.as_u64().unwrap() as usize).collect();
            assert_eq!(nodes, el.nodes);
            assert_eq!(data["element_id"][e][0].as_f64().unwrap(), el.id as f64);
            for p in &map.plies {
                let prefix = if layup { format!("{}_", p.ply) } else { String::new() };
                let get = |f: &str| f64s(&data[&format!("{prefix}{f}")][e]);
                let covered = get("covered")[0];
                match &p.elements[e] {
                    None => {
                        assert_eq!(covered, 0.0);
                        for f in ["warp", "weft", "shear_deg", "thickness", "vf", "permeability"] {
                            assert!(get(f).iter().all(|v| v.is_nan()), "{f} of uncovered element {}", el.id);
                        }
                    }
                    Some(fib) => {
                        assert_eq!(covered, 1.0);
                        let (warp, weft) = (vec3(&get("warp")), vec3(&get("weft")));
                        assert_eq!(warp, fib.warp);
                        assert_frame(&mesh, e, warp, weft, get("shear_deg")[0], EXACT_TOL, "vtu");
                        let theta = angle_about(mesh.first_edge(e).unwrap(), warp, mesh.normal(e).unwrap());
                        assert!((theta - fib.theta).abs() < 1e-12);
                        let k = get("permeability");
                        let want = fib.permeability.unwrap();
                        for r in 0..3 {
                            for c in 0..3 {
                                assert_eq!(k[3 * r + c], want[(r, c)], "row-major permeability");
                            }
                        }
                    }
                }
            }
            if layup {
                let (t, vf) = (f64s(&data["laminate_thickness"][e])[0], f64s(&data["mean_vf"][e])[0]);
                match map.mean_vf[e] {
                    Some(want) => assert!(t == map.thickness[e] && vf == want),
                    None => assert!(t.is_nan() && vf.is_nan(), "element {} no ply covers", el.id),
                }
            }
        }
    }
}

#[test]
fn nastran_theta_reproduces_warp() {
    let mesh = mesh();
    for layup in [false, true] {
        let map = layup_map(&mesh, layup);
        let dir = tempfile::tempdir().unwrap();
        let files = write(&mesh, &map, FlowFormat::Nastran, &dir.path().join("flow.bdf"));
        let names: Vec<String> = files.iter().map(|f| f.file_name().unwrap().to_string_lossy().into_owned()).collect();
        if layup {
            assert_eq!(names, ["flow_base.bdf", "flow_p45.bdf", "flow_p-45.bdf"]);
        } else {
            assert_eq!(names, ["flow.bdf"]);
        }
        if !python_ready() {
            continue;
        }
        let s = readback("nastran", &files);
        for (deck, ply) in s["decks"].as_array().unwrap().iter().zip(&map.plies) {
            // Grids: same ids, coordinates to 16-character precision; meshio agrees.
            let grids = deck["grids"].as_object().unwrap();
            assert_eq!(grids.len(), mesh.nodes.len());
            let mio = deck["meshio_points"].as_array().unwrap();
            assert_eq!(mio.len(), mesh.nodes.len());
            let mut read_nodes = Vec::new();
            for (k, id) in mesh.node_ids.iter().enumerate() {
                let p = vec3(&f64s(&grids[&id.to_string()]));
                assert!((p - mesh.nodes[k].coords).norm() < 1e-13, "grid {id}");
                assert!((vec3(&f64s(&mio[k])) - mesh.nodes[k].coords).norm() < 1e-13, "meshio grid {id}");
                read_nodes.push(Point::from(p));
            }
            let back = FlowMesh { nodes: read_nodes, ..mesh.clone() };
            let els = deck["elements"].as_object().unwrap();
            assert_eq!(els.len(), mesh.elements.len());
            for (e, el) in mesh.elements.iter().enumerate() {
                let r = &els[&el.id.to_string()];
                assert_eq!(r["type"], if el.shape == ElementShape::Tria3 { "CTRIA3" } else { "CQUAD4" });
                let nodes: Vec<u64> = r["nodes"].as_array().unwrap().iter().map(|v| v.as_u64().unwrap()).collect();
                assert_eq!(nodes, el.nodes.iter().map(|&k| mesh.node_ids[k]).collect::<Vec<_>>());
                assert!(r["mcid"].is_null(), "THETA must be read as a real angle, not a coordinate system");
                match &ply.elements[e] {
                    None => {
                        assert_eq!(r["pid"], kept_pid(el.id), "uncovered element {} keeps the user's PID", el.id);
                        assert_eq!(r["theta_blank"], true, "uncovered element {}: no THETA", el.id);
                    }
                    Some(fib) => {
                        assert_eq!(r["pid"], kept_pid(el.id), "element {} keeps the user's PID", el.id);
                        assert_eq!(r["theta_blank"], false);
                        let theta = r["theta"].as_f64().unwrap();
                        assert!((theta - fib.theta.to_degrees()).abs() < LARGE_FIELD_DEG_TOL, "{theta}");
                        let n = back.normal(e).unwrap();
                        let warp = rotate(back.first_edge(e).unwrap(), n, theta.to_radians());
                        assert!(
                            (warp - fib.warp).norm() < LARGE_FIELD_DIR_TOL,
                            "element {}: THETA does not give the warp",
                            el.id
                        );
                    }
                }
            }
        }
    }
}

#[test]
fn abaqus_distributions() {
    let mesh = mesh();
    let map = layup_map(&mesh, true);
    let dir = tempfile::tempdir().unwrap();
    let files = write(&mesh, &map, FlowFormat::Abaqus, &dir.path().join("flow.inp"));
    if !python_ready() {
        return;
    }
    let s = readback("abaqus", &files);
    assert_eq!(s["meshio_points"].as_array().unwrap().len(), mesh.nodes.len());
    assert_eq!(s["meshio_cells"].as_array().unwrap().len(), mesh.elements.len());
    let ids: Vec<u64> = s["node_ids"].as_array().unwrap().iter().map(|v| v.as_u64().unwrap()).collect();
    assert_eq!(ids, mesh.node_ids);
    let mut eids: Vec<u64> = s["element_ids"].as_array().unwrap().iter().map(|v| v.as_u64().unwrap()).collect();
    let mut want: Vec<u64> = mesh.elements.iter().map(|e| e.id).collect();
    eids.sort();
    want.sort();
    assert_eq!(eids, want);
    assert_eq!(s["tables"]["DRAPE_DIRECTIONS"], serde_json::json!(["COORD3D", "COORD3D"]));
    for (k, ply) in map.plies.iter().enumerate() {
        let tag = drape::io::abaqus::ply_tag(k, &ply.ply);
        let d = &s["distributions"][&format!("{tag}_DIR")];
        assert_eq!(d["location"], "ELEMENT");
        assert_eq!(d["table"], "DRAPE_DIRECTIONS");
        assert_eq!(f64s(&d["default"]).len(), 6);
        let ori = &s["orientations"][&format!("{tag}_ORI")];
        assert_eq!(ori["lines"][0][0], format!("{tag}_DIR"));
        let covered: Vec<u64> = s["elsets"][&tag].as_array().unwrap().iter().map(|v| v.as_u64().unwrap()).collect();
        let rows = d["rows"].as_object().unwrap();
        for (e, el) in mesh.elements.iter().enumerate() {
            match &ply.elements[e] {
                None => {
                    assert!(!rows.contains_key(&el.id.to_string()) && !covered.contains(&el.id));
                    let unc = s["elsets"][&format!("{tag}_UNCOVERED")].as_array().unwrap();
                    assert!(unc.iter().any(|v| v.as_u64() == Some(el.id)));
                }
                Some(fib) => {
                    assert!(covered.contains(&el.id));
                    let r = f64s(&rows[&el.id.to_string()]);
                    let (a, b) = (vec3(&r[0..3]), vec3(&r[3..6]));
                    assert_frame(&mesh, e, a, b, fib.shear.to_degrees(), EXACT_TOL, "abaqus");
                    let theta = angle_about(mesh.first_edge(e).unwrap(), a, mesh.normal(e).unwrap());
                    assert!((theta - fib.theta).abs() < 1e-12);
                }
            }
        }
    }
}

#[test]
fn optistruct_ply_drape() {
    let mesh = mesh();
    let map = layup_map(&mesh, true);
    let dir = tempfile::tempdir().unwrap();
    let files = write(&mesh, &map, FlowFormat::OptiStruct, &dir.path().join("flow.fem"));
    // The deck structure OptiStruct reads: control section, CEND, BEGIN BULK, bulk, ENDDATA.
    let text = std::fs::read_to_string(&files[0]).unwrap();
    let keys: Vec<&str> =
        text.lines().filter(|l| !l.starts_with('$') && !l.starts_with(' ') && !l.contains('*')).collect();
    assert_eq!(keys, ["CEND", "BEGIN BULK", "ENDDATA"], "{text}");
    if !python_ready() {
        return;
    }
    let s = readback("optistruct", &files);
    let els = &s["elements"];
    for (k, ply) in map.plies.iter().enumerate() {
        let id = (k + 1).to_string();
        let p = &s["plies"][&id];
        assert_eq!(p["did"].as_u64().unwrap(), (k + 1) as u64);
        assert_eq!(p["esids"], serde_json::json!([k + 1]));
        assert!((p["t"].as_f64().unwrap() - NOMINAL_T).abs() < 1e-15);
        let set: Vec<u64> = s["sets"][&id].as_array().unwrap().iter().map(|v| v.as_u64().unwrap()).collect();
        let covered: Vec<u64> =
            mesh.elements.iter().zip(&ply.elements).filter(|(_, f)| f.is_some()).map(|(e, _)| e.id).collect();
        assert_eq!(set, covered);
        let drape = s["drapes"][&id].as_object().unwrap();
        assert_eq!(drape.len(), covered.len());
        for (e, el) in mesh.elements.iter().enumerate() {
            let Some(fib) = &ply.elements[e] else { continue };
            let row = f64s(&drape[&el.id.to_string()]);
            assert!((row[0] - fib.thickness / fib.nominal_thickness).abs() < 1e-12, "thinning");
            // Nominal angles are consistent across plies here, so DRAPE THETA = angle change.
            assert!((row[1] - fib.angle_change.to_degrees()).abs() < LARGE_FIELD_DEG_TOL, "drape angle {}", row[1]);
            let el_theta = els[&el.id.to_string()]["theta"].as_f64().unwrap();
            let total = el_theta + p["theta"].as_f64().unwrap() + row[1];
            let warp = rotate(mesh.first_edge(e).unwrap(), mesh.normal(e).unwrap(), total.to_radians());
            assert!((warp - fib.warp).norm() < LARGE_FIELD_DIR_TOL, "element {}: angles do not give the warp", el.id);
        }
        assert!(
            (wrap_deg(p["theta"].as_f64().unwrap()) - wrap_deg((PLIES[k].1 - PLIES[0].1).to_degrees())).abs() < 1e-8
        );
    }
    // Every element keeps the user's PID (1 where the mesh has none).
    for el in &mesh.elements {
        assert_eq!(els[&el.id.to_string()]["pid"], kept_pid(el.id));
    }
    // pyNastran, taught PCOMPP, cross-references the deck alone; PLY, STACK, SET and DRAPE
    // resolve. Every element here lies under some ply: all on PCOMPPs of their PIDs, each ply on
    // a MAT8 of its fabric, the plies in one STACK in stacking order.
    let x = readback("optistruct-xref", &files);
    assert_eq!(x["dangling"], serde_json::json!([]));
    for el in &mesh.elements {
        let r = &x["elements"][&el.id.to_string()];
        assert_eq!((r["pid"].as_u64(), r["property"].as_str()), (Some(kept_pid(el.id)), Some("PCOMPP")));
    }
    assert_eq!(x["stacks"]["1"]["plies"], serde_json::json!([1, 2, 3]));
    let f = fabric();
    for k in 1..=3 {
        let m = &x["plies"][&k.to_string()]["material"];
        assert_eq!(m["type"], "MAT8");
        assert!((m["e1"].as_f64().unwrap() - f.tension_warp / NOMINAL_T).abs() < 1e-6 * f.tension_warp / NOMINAL_T);
    }
    assert!(comments(&text).contains("it replaces the flow mesh's PSHELL 5"), "{text}");

    // Elements no ply covers: off the PCOMPPs. Element 3 (PID 5, beside covered element 7) takes
    // a fresh PID 7 with the user's PSHELL 5 renumbered; element 16 (no PID, beside covered 15)
    // a fresh PID 8 with a PSHELL of the bottom ply's fabric, named in a note.
    let mut part = map.clone();
    for ply in &mut part.plies {
        ply.elements[1] = None;
        ply.elements[5] = None;
    }
    let notes = drape::io::flow::check_flow(
        &mesh,
        &part,
        FlowFormat::OptiStruct,
        &dir.path().join("part.fem"),
        &Default::default(),
    )
    .unwrap();
    assert!(
        notes.len() == 1 && notes[0].contains("PID 8 (PID 1 in the flow mesh): 1 element(s) no ply covers"),
        "{notes:?}"
    );
    let files = write(&mesh, &part, FlowFormat::OptiStruct, &dir.path().join("part.fem"));
    let x = readback("optistruct-xref", &files);
    assert_eq!(x["dangling"], serde_json::json!([]));
    let pid_of = |id: u64| {
        (
            x["elements"][&id.to_string()]["pid"].as_u64().unwrap(),
            x["elements"][&id.to_string()]["property"].as_str().unwrap().to_string(),
        )
    };
    assert_eq!(pid_of(3), (7, "PSHELL".into()));
    assert_eq!(pid_of(16), (8, "PSHELL".into()));
    assert_eq!(pid_of(7), (5, "PCOMPP".into()));
    assert_eq!(pid_of(15), (1, "PCOMPP".into()));
    assert_eq!(x["properties"]["7"]["t"].as_f64(), Some(0.002));
    assert_eq!(x["properties"]["8"]["t"].as_f64(), Some(NOMINAL_T));
    assert_eq!(x["properties"]["8"]["materials"], serde_json::json!(["MAT8"]));
}

#[test]
fn rtmsim_mesh_sets_and_parameters() {
    let mesh = mesh();
    for layup in [false, true] {
        let map = layup_map(&mesh, layup);
        let dir = tempfile::tempdir().unwrap();
        let report = write_rtmsim(&mesh, &map, &dir.path().join("flow.bdf")).unwrap();
        let names: Vec<String> =
            report.files.iter().map(|f| f.file_name().unwrap().to_string_lossy().into_owned()).collect();
        assert_eq!(names, ["flow.bdf", "flow_input.txt"]);
        eprintln!(
            "rtmsim layup={layup}: {} group(s) found, {} region(s), {} merged, max direction error {:.3} deg",
            report.groups_found,
            report.regions.len(),
            report.merged_elements,
            report.max_direction_error_deg
        );
        assert!(report.regions.len() <= MAX_RTMSIM_SETS + 1 && report.regions.len() <= report.groups_found);
        let uncovered: Vec<u64> = if layup { vec![] } else { vec![16] };
        assert_eq!(report.uncovered, uncovered);
        // The uncovered elements get the SET after the covered regions' SETs.
        let uncovered_set = (!layup).then_some(report.regions.len());
        assert_eq!(report.uncovered_set, uncovered_set);
        let sets_used = report.regions.len() - 1 + usize::from(uncovered_set.is_some());
        assert!(sets_used <= MAX_RTMSIM_SETS);
        if !python_ready() {
            continue;
        }
        let s = readback("rtmsim", &report.files);
        assert_eq!(s["meshfilename"], "flow.bdf");
        let ids_of = |v: &Value| -> Vec<u64> { v.as_array().unwrap().iter().map(|x| x.as_u64().unwrap()).collect() };
        assert_eq!(ids_of(&s["uncovered"]), uncovered);
        // Triangles: each covered tri by its id, each covered quad as two (SPLIT lines).
        let tris = s["tris"].as_object().unwrap();
        let splits: Vec<Vec<u64>> = s["splits"].as_array().unwrap().iter().map(ids_of).collect();
        let mut tri_of = std::collections::BTreeMap::new(); // tri id -> element index
        for (e, el) in mesh.elements.iter().enumerate() {
            let mine: Vec<u64> = match el.shape {
                ElementShape::Tria3 => vec![el.id],
                ElementShape::Quad4 => {
                    let sp = splits.iter().find(|s| s[0] == el.id).expect("quad split recorded");
                    vec![sp[1], sp[2]]
                }
            };
            let mut corners = std::collections::BTreeSet::new();
            for t in &mine {
                for n in ids_of(&tris[&t.to_string()]) {
                    corners.insert(n);
                }
                tri_of.insert(*t, e);
            }
            let want: std::collections::BTreeSet<u64> = el.nodes.iter().map(|&k| mesh.node_ids[k]).collect();
            assert_eq!(corners, want, "element {} triangles", el.id);
        }
        assert_eq!(tris.len(), tri_of.len());
        assert_eq!(s["meshio_triangles"].as_u64().unwrap() as usize, tri_of.len());
        // Element count in = element count out: every element (covered or not) is written.
        let written: std::collections::BTreeSet<usize> = tri_of.values().copied().collect();
        assert_eq!(written.len(), mesh.elements.len());
        for (id, p) in s["grids"].as_object().unwrap() {
            let k = mesh.node_ids.iter().position(|n| n.to_string() == *id).unwrap();
            assert!((vec3(&f64s(p)) - mesh.nodes[k].coords).norm() < SHORT_FIELD_TOL, "grid {id}");
        }
        // Regions: main = cells in no set; set s = region s; values as reported.
        let params: Vec<Vec<f64>> = s["params"].as_array().unwrap().iter().map(f64s).collect();
        let sets: Vec<Vec<u64>> = s["sets"].as_array().unwrap().iter().map(ids_of).collect();
        let types: Vec<u64> = ids_of(&s["patchtypes"]);
        let mut region_of_tri = std::collections::BTreeMap::new();
        for (r, reg) in report.regions.iter().enumerate() {
            let p = &params[r];
            let want =
                [reg.thickness, reg.porosity, reg.permeability, reg.ratio, reg.refdir.x, reg.refdir.y, reg.refdir.z];
            assert_eq!(p[..], want[..], "region {r} parameters");
            if r > 0 {
                assert_eq!(types[r - 1], 2);
                for t in &sets[r - 1] {
                    region_of_tri.insert(*t, r);
                }
            }
        }
        if let Some(u) = uncovered_set {
            // Their own preform region: the main preform's values, for the user to edit.
            assert_eq!(types[u - 1], 2);
            assert_eq!(params[u], params[0]);
            for t in &sets[u - 1] {
                region_of_tri.insert(*t, usize::MAX);
            }
        }
        for s_unused in sets_used + 1..=MAX_RTMSIM_SETS {
            assert_eq!(types[s_unused - 1], 0);
            assert!(sets[s_unused - 1].is_empty());
        }
        assert_eq!(s["i_interactive"].as_u64().unwrap(), if sets_used > 0 { 2 } else { 1 });
        let mut max_err: f64 = 0.0;
        for (t, &e) in &tri_of {
            let r = *region_of_tri.get(t).unwrap_or(&0);
            let id = mesh.elements[e].id;
            assert_eq!(
                r == usize::MAX,
                uncovered.contains(&id),
                "tri {t} of element {id}: in the uncovered SET or not"
            );
            if r == usize::MAX {
                continue;
            }
            assert!(report.regions[r].elements.contains(&mesh.elements[e].id), "tri {t} in the wrong region");
            // The reference direction projected onto the element vs the element's own K1 axis.
            let n = mesh.normal(e).unwrap();
            let k = map.permeability[e].unwrap();
            let eig = k.symmetric_eigen();
            let (mut best, mut dir) = (f64::MIN, Vector::zeros());
            for c in 0..3 {
                let v: Vector = eig.eigenvectors.column(c).into();
                if v.dot(&n).abs() < 0.5 && eig.eigenvalues[c] > best {
                    best = eig.eigenvalues[c];
                    dir = v;
                }
            }
            let rd = vec3(&params[r][4..7]);
            let p = (rd - n * n.dot(&rd)).normalize();
            max_err = max_err.max(p.dot(&dir).abs().min(1.0).acos().to_degrees());
            // Porosity of the element within the region's bin unless its group was merged.
            if report.merged_elements == 0 {
                let por = 1.0 - map.mean_vf[e].unwrap();
                assert!((por - params[r][1]).abs() <= drape::io::rtmsim::POROSITY_BIN, "porosity");
            }
        }
        assert!(
            (max_err - report.max_direction_error_deg).abs() < 1e-6,
            "{max_err} vs {}",
            report.max_direction_error_deg
        );
    }
}

#[test]
fn csv_rows() {
    let mesh = mesh();
    let map = layup_map(&mesh, true);
    let dir = tempfile::tempdir().unwrap();
    let files = write(&mesh, &map, FlowFormat::Csv, &dir.path().join("flow.csv"));
    let text = std::fs::read_to_string(&files[0]).unwrap();
    assert_eq!(text.lines().next(), Some(FLOW_CSV_HEADER));
    if !python_ready() {
        return;
    }
    let s = readback("csv", &files);
    assert_eq!(s["widths"], serde_json::json!([23]));
    let rows = s["rows"].as_array().unwrap();
    assert_eq!(rows.len(), mesh.elements.len() * map.plies.len());
    let num = |r: &Value, c: &str| r[c].as_str().unwrap().parse::<f64>().unwrap();
    for (e, el) in mesh.elements.iter().enumerate() {
        for (k, ply) in map.plies.iter().enumerate() {
            let r = &rows[e * map.plies.len() + k];
            assert_eq!(r["element_id"], el.id.to_string());
            assert_eq!(r["ply"], ply.ply.as_str());
            match &ply.elements[e] {
                None => {
                    assert_eq!(r["covered"], "0");
                    assert_eq!(r["warp_x"], "");
                    assert_eq!(r["k33"], "");
                }
                Some(fib) => {
                    assert_eq!(r["covered"], "1");
                    let warp = Vector::new(num(r, "warp_x"), num(r, "warp_y"), num(r, "warp_z"));
                    let weft = Vector::new(num(r, "weft_x"), num(r, "weft_y"), num(r, "weft_z"));
                    assert_frame(&mesh, e, warp, weft, num(r, "shear_deg"), EXACT_TOL, "csv");
                    let theta = num(r, "theta_deg").to_radians();
                    let from_theta = rotate(mesh.first_edge(e).unwrap(), mesh.normal(e).unwrap(), theta);
                    assert!((from_theta - warp).norm() < 1e-12);
                    assert!((num(r, "angle_change_deg") - fib.angle_change.to_degrees()).abs() < 1e-12);
                    assert_eq!(num(r, "k12"), fib.permeability.unwrap()[(0, 1)]);
                }
            }
        }
    }
}

#[test]
fn non_finite_is_refused_and_nothing_written() {
    let mesh = mesh();
    let mut map = layup_map(&mesh, true);
    map.plies[1].elements[2].as_mut().unwrap().theta = f64::NAN;
    let dir = tempfile::tempdir().unwrap();
    for format in FlowFormat::ALL {
        let out = dir.path().join(format!("flow.{}", format.name()));
        let e = write_flow(&mesh, &map, format, &out).unwrap_err();
        assert!(matches!(e, ExportError::FlowNonFinite { .. }), "{e}");
        let msg = e.to_string();
        assert!(msg.contains("'p45'") && msg.contains("element 42") && msg.contains("theta"), "{msg}");
    }
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    // A map that does not fit the mesh is refused too.
    let mut short = layup_map(&mesh, false);
    short.plies[0].elements.pop();
    let e = write_flow(&mesh, &short, FlowFormat::Csv, &dir.path().join("x.csv")).unwrap_err().to_string();
    assert!(e.contains("5 entries for 6 flow elements"), "{e}");
    // RTMsim needs permeability.
    let mut noperm = layup_map(&mesh, false);
    noperm.permeability.iter_mut().for_each(|k| *k = None);
    let e = write_flow(&mesh, &noperm, FlowFormat::Rtmsim, &dir.path().join("r.bdf")).unwrap_err().to_string();
    assert!(e.contains("permeability"), "{e}");
}

/// More groups than RTMsim's 1 + 4 regions: the smallest groups are merged into the nearest
/// written region, every covered element still lands in exactly one region.
#[test]
fn rtmsim_merges_excess_groups() {
    let mesh = mesh();
    let mut map = layup_map(&mesh, false);
    // Element 16 covered too, and every element in its own thickness bin (x 1.3 each).
    map.plies[0].elements[5] = Some(fibres(&mesh, 5, 0, 0.0));
    for e in 0..mesh.elements.len() {
        let f = map.plies[0].elements[e].as_mut().unwrap();
        f.thickness = NOMINAL_T * 1.3f64.powi(e as i32);
        map.thickness[e] = f.thickness;
        map.mean_vf[e] = Some(f.vf);
        map.permeability[e] = f.permeability;
    }
    let dir = tempfile::tempdir().unwrap();
    let report = write_rtmsim(&mesh, &map, &dir.path().join("merged.bdf")).unwrap();
    let input = std::fs::read_to_string(&report.files[1]).unwrap();
    eprintln!("{input}");
    assert_eq!(report.groups_found, 6);
    assert_eq!(report.regions.len(), MAX_RTMSIM_SETS + 1);
    assert_eq!(report.merged_elements, 1);
    let mut all: Vec<u64> = report.regions.iter().flat_map(|r| r.elements.clone()).collect();
    all.sort();
    let mut want: Vec<u64> = mesh.elements.iter().map(|e| e.id).collect();
    want.sort();
    assert_eq!(all, want);
    assert_eq!(report.regions[0].set, None);
    assert_eq!(report.regions.iter().skip(1).map(|r| r.set.unwrap()).collect::<Vec<_>>(), [1, 2, 3, 4]);
    if !python_ready() {
        return;
    }
    let s = readback("rtmsim", &report.files);
    let sets = s["sets"].as_array().unwrap();
    assert!(sets.iter().all(|v| !v.as_array().unwrap().is_empty()), "all four sets used");
    assert_eq!(s["patchtypes"], serde_json::json!([2, 2, 2, 2]));
}

/// pyNastran reads drape's Nastran deck alone, and a solver's deck that INCLUDEs it, with
/// cross-referencing on: every element keeps its PID and finds its property and material, the
/// user's cards carried as they were, a PSHELL and MAT8 from the ply's fabric for the PID the
/// mesh gives none (E = rigidity / t0, G12 = shear stiffness / t0, RHO = areal mass / t0).
#[test]
fn nastran_deck_reads_alone_and_included_with_cross_references() {
    if !python_ready() {
        return;
    }
    let mesh = mesh();
    let map = layup_map(&mesh, false);
    let dir = tempfile::tempdir().unwrap();
    let deck = write(&mesh, &map, FlowFormat::Nastran, &dir.path().join("flow.bdf")).remove(0);
    let master = dir.path().join("job.bdf");
    std::fs::write(&master, "SOL 101\nCEND\nSUBCASE 1\n  DISP = ALL\nBEGIN BULK\nINCLUDE 'flow.bdf'\nENDDATA\n")
        .unwrap();
    let alone = readback("nastran-xref", &[deck]);
    let included = readback("nastran-xref", &[master]);
    assert_eq!(alone["elements"], included["elements"]);
    assert_eq!(alone["rejected"], serde_json::json!([]), "pyNastran rejected cards of the deck");
    let els = alone["elements"].as_object().unwrap();
    assert_eq!(els.len(), mesh.elements.len());
    for (e, el) in mesh.elements.iter().enumerate() {
        let r = &els[&el.id.to_string()];
        assert_eq!(r["pid"], kept_pid(el.id));
        let (property, material) = match kept_pid(el.id) {
            5 => ("PSHELL", "MAT8"),
            6 => ("PCOMP", "MAT1"),
            _ => ("PSHELL", "MAT8"),
        };
        assert_eq!((r["property"].as_str().unwrap(), r["material"].as_str().unwrap()), (property, material));
        match &map.plies[0].elements[e] {
            Some(fib) => {
                assert!((r["theta"].as_f64().unwrap() - fib.theta.to_degrees()).abs() < LARGE_FIELD_DEG_TOL)
            }
            None => assert!(r["theta"].is_null() || r["theta"].as_f64() == Some(0.0), "{r}"),
        }
    }
    // The user's cards as they were.
    let props = &alone["properties"];
    assert_eq!(props["5"]["t"].as_f64(), Some(0.002));
    assert_eq!(props["5"]["mids"], serde_json::json!([100, 100]));
    assert_eq!(props["6"]["mids"], serde_json::json!([101, 100]));
    assert_eq!(props["6"]["materials"], serde_json::json!(["MAT1", "MAT8"]));
    let mats = &alone["materials"];
    assert_eq!(mats["100"]["e1"].as_f64(), Some(140.0e9));
    assert_eq!(mats["101"]["e"].as_f64(), Some(70.0e9));
    // PID 1: drape's PSHELL (membrane, t0) and MAT8 of the fabric, above the user's MIDs.
    assert_eq!(props["1"]["t"].as_f64(), Some(NOMINAL_T));
    assert_eq!(props["1"]["mids"], serde_json::json!([102]));
    let m = &mats["102"];
    let f = fabric();
    let close = |v: &Value, want: f64| (v.as_f64().unwrap() - want).abs() <= 1e-9 * want.abs();
    assert!(close(&m["e1"], f.tension_warp / NOMINAL_T) && close(&m["e2"], f.tension_weft / NOMINAL_T), "{m}");
    assert!(close(&m["g12"], f.shear / NOMINAL_T) && close(&m["rho"], f.areal_mass / NOMINAL_T), "{m}");
    assert_eq!(m["nu12"].as_f64(), Some(0.0));
    let text = std::fs::read_to_string(dir.path().join("flow.bdf")).unwrap();
    assert!(comments(&text).contains("not carried from the flow mesh: MATT8 100"), "{text}");
    // Without a fabric for the PID the mesh gives no card, the deck is refused, saying what to give.
    let mut bare = map.clone();
    bare.plies[0].fabric = None;
    let e = write_flow(&mesh, &bare, FlowFormat::Nastran, &dir.path().join("bare.bdf")).unwrap_err();
    assert!(e.is_bad_input(), "{e}");
    let e = e.to_string();
    assert!(e.contains("PID 1") && e.contains("elements 15, 16") && e.contains("--material"), "{e}");
    // A user's card that refers to a material the mesh does not give is refused, naming both.
    let mut lost = mesh.clone();
    lost.cards.materials.retain(|c| c.id != 101);
    let e = write_flow(&lost, &map, FlowFormat::Nastran, &dir.path().join("lost.bdf")).unwrap_err().to_string();
    assert!(e.contains("PCOMP 6 (test-mesh.bdf line 6) refers to material 101") && e.contains("MATT8 100"), "{e}");
    assert!(!dir.path().join("bare.bdf").exists() && !dir.path().join("lost.bdf").exists());
}

/// The flow VTU as compressed binary: VTK's own reader gets the same arrays as from the ASCII
/// file, bit for bit, NaN where a ply does not cover an element included (and NaN stays NaN).
#[test]
fn flow_vtu_binary_reads_in_vtk_as_the_ascii_does() {
    use crate::common::vtk_reader::{read_with_vtk, vtk_ready};
    use drape::io::flow::{write_flow_with, FlowOptions};
    use drape::io::vtk::VtuEncoding;
    let mesh = mesh();
    let map = layup_map(&mesh, true);
    let dir = tempfile::tempdir().unwrap();
    let (bin, ascii) = (dir.path().join("flow.vtu"), dir.path().join("flow-ascii.vtu"));
    let opts = |vtu| FlowOptions { vtu, ..FlowOptions::default() };
    write_flow_with(&mesh, &map, FlowFormat::Vtu, &bin, &opts(VtuEncoding::Binary)).unwrap();
    write_flow_with(&mesh, &map, FlowFormat::Vtu, &ascii, &opts(VtuEncoding::Ascii)).unwrap();
    // The default for a small mesh is ASCII.
    let auto = dir.path().join("flow-auto.vtu");
    write_flow(&mesh, &map, FlowFormat::Vtu, &auto).unwrap();
    assert_eq!(std::fs::read(&auto).unwrap(), std::fs::read(&ascii).unwrap());
    assert!(!std::fs::read(&bin).unwrap().windows(14).any(|w| w == b"format=\"ascii\""));
    if !vtk_ready() {
        return;
    }
    let (b, a) = (read_with_vtk(&bin), read_with_vtk(&ascii));
    assert_eq!(b.summary["encoding"]["compressor"], "vtkZLibDataCompressor");
    assert_eq!(b.summary["cells"].as_u64().unwrap() as usize, mesh.elements.len());
    assert_eq!(b.arrays.keys().collect::<Vec<_>>(), a.arrays.keys().collect::<Vec<_>>());
    for (key, values) in &b.arrays {
        let same = values.len() == a.arrays[key].len()
            && values.iter().zip(&a.arrays[key]).all(|(x, y)| x.to_bits() == y.to_bits() || (x.is_nan() && y.is_nan()));
        assert!(same, "{key} differs between the binary and the ASCII file");
    }
    // Against the map itself: ids, and NaN exactly where a ply does not cover an element.
    let ids: Vec<f64> = mesh.elements.iter().map(|e| e.id as f64).collect();
    assert_eq!(b.arrays["cell.element_id"], ids);
    let mut uncovered = 0;
    for ply in &map.plies {
        let warp = &b.arrays[&format!("cell.{}_warp", ply.ply)];
        let covered = &b.arrays[&format!("cell.{}_covered", ply.ply)];
        for (e, f) in ply.elements.iter().enumerate() {
            match f {
                Some(f) => {
                    assert_eq!(covered[e], 1.0);
                    assert_eq!(warp[3 * e..3 * e + 3], [f.warp.x, f.warp.y, f.warp.z]);
                }
                None => {
                    uncovered += 1;
                    assert_eq!(covered[e], 0.0);
                    assert!(
                        warp[3 * e..3 * e + 3].iter().all(|v| v.is_nan()),
                        "element {e}: {:?}",
                        &warp[3 * e..3 * e + 3]
                    );
                }
            }
        }
    }
    assert!(uncovered > 0, "the layup leaves elements uncovered");
}

/// A Nastran card in one of the layouts a flow mesh may use.
#[derive(Clone, Copy, Debug)]
enum Layout {
    Small,
    Large,
    Free,
}

fn nastran_card(layout: Layout, name: &str, fields: &[String]) -> String {
    let mut out = String::new();
    match layout {
        Layout::Free => {
            // Eight fields a line, continuation lines starting with a comma.
            for (k, chunk) in fields.chunks(8).enumerate() {
                out += &format!("{},{}\n", if k == 0 { name } else { "" }, chunk.join(","));
            }
        }
        Layout::Small => {
            for (k, chunk) in fields.chunks(8).enumerate() {
                out += &format!("{:<8}", if k == 0 { name } else { "" });
                for f in chunk {
                    assert!(f.len() <= 8, "{f}");
                    out += &format!("{f:>8}");
                }
                out += "\n";
            }
        }
        Layout::Large => {
            for (k, chunk) in fields.chunks(4).enumerate() {
                out += &if k == 0 { format!("{:<8}", format!("{name}*")) } else { format!("{:<8}", "*") };
                for f in chunk {
                    out += &format!("{f:<16}");
                }
                out += "\n";
            }
        }
    }
    out
}

/// Decks that read alone, on Nastran flow meshes generated here with several PIDs (stripes
/// across the part), each with its own property layout: PSHELL on a MAT1, PCOMP (a blank MID
/// taking the ply above's) on a MAT8, PCOMPG on a MAT8 and the first stripe's MAT1, the last
/// stripe without a card; small, large or free fields; metres or millimetres. Two plies draped
/// on the plate, one short of the part's end, one over half of it. pyNastran cross-references
/// every Nastran deck alone and the OptiStruct deck (taught PCOMPP): every element keeps its PID
/// (OptiStruct: a PCOMPP where a ply covers it, else its card, a fresh PID beside a PCOMPP), the
/// user's cards read as written, drape's PSHELL and MAT8 carry the card's fabric in the mesh's
/// units.
#[test]
fn decks_read_alone_on_generated_nastran_meshes_with_several_pids() {
    use drape::geometry::shapes;
    use drape::kinematic::{drape, KinematicSettings};
    use drape::mapping::{map_plies, Cavity, PlyToMap};
    use drape::material::MaterialCard;
    if !python_ready() {
        return;
    }
    let card =
        MaterialCard::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("materials/glass-plain-weave.toml")).unwrap();
    let tool = shapes::plate(0.4, 0.3, 8, 6).into_surface().unwrap();
    let ply = |name: &str, x0: f64, nu: usize| {
        let s = KinematicSettings::grid(name, Point::new(x0, 0.0, 0.0), Vector::new(1.0, 0.2, 0.0), 0.01, nu, 31);
        drape(&tool, &s).unwrap()
    };
    // Seeds at the grid's middle node: a covers x < 0.12 m, b x < 0.0 m.
    let nets = [ply("a", -0.04, 33), ply("b", -0.1, 21)];
    for (stripes, layout, scale, nx, ny) in
        [(3, Layout::Small, 1.0, 12, 5), (5, Layout::Large, 1e-3, 15, 4), (4, Layout::Free, 1e-3, 16, 6)]
    {
        let what = format!("{stripes} PIDs, {layout:?} fields, {scale} m a unit");
        let unit = |metres: f64| metres / scale;
        // Three significant digits, as short as a small field needs ("2.00E5").
        let real = |x: f64| format!("{x:.2e}").replace('e', "E");
        let short = |x: f64| drape_short(x);
        let mut text = String::from("$ generated flow mesh\nBEGIN BULK\n");
        let node = |i: usize, j: usize| (1000 + 100 * i + j) as u64;
        for i in 0..=nx {
            for j in 0..=ny {
                let (x, y) = (-0.2 + 0.4 * i as f64 / nx as f64, -0.15 + 0.3 * j as f64 / ny as f64);
                let f = vec![node(i, j).to_string(), String::new(), short(unit(x)), short(unit(y)), short(0.0)];
                text += &nastran_card(layout, "GRID", &f);
            }
        }
        let pid_of = |i: usize| 10 * (1 + i * stripes / nx) as u64;
        let mut expected_pid = std::collections::BTreeMap::new();
        let mut eid = 500;
        for i in 0..nx {
            for j in 0..ny {
                let p = pid_of(i).to_string();
                let (a, b, c, d) = (node(i, j), node(i + 1, j), node(i + 1, j + 1), node(i, j + 1));
                if (i + j) % 3 == 0 {
                    for tri in [[a, b, c], [a, c, d]] {
                        eid += 1;
                        let mut f = vec![eid.to_string(), p.clone()];
                        f.extend(tri.iter().map(u64::to_string));
                        text += &nastran_card(layout, "CTRIA3", &f);
                        expected_pid.insert(eid, pid_of(i));
                    }
                } else {
                    eid += 1;
                    let mut f = vec![eid.to_string(), p.clone()];
                    f.extend([a, b, c, d].iter().map(u64::to_string));
                    text += &nastran_card(layout, "CQUAD4", &f);
                    expected_pid.insert(eid, pid_of(i));
                }
            }
        }
        // Cards: stripe k's MID is 7 + k (so drape's first MID is 7 + stripes - 1).
        let t_user = |k: usize| unit(0.001 * (1.0 + k as f64));
        let (e_steel, rho) = (2.0e11 * scale * scale, 7800.0 * scale.powi(4));
        let mut user = std::collections::BTreeMap::new(); // PID -> (type, t, mids)
        for k in 0..stripes - 1 {
            let (pid, mid) = (10 * (k + 1) as u64, 7 + k as u64);
            let mut f: Vec<String> = vec![pid.to_string()];
            let b = String::new;
            match k % 3 {
                0 => {
                    f.extend([mid.to_string(), short(t_user(k)), mid.to_string()]);
                    text += &nastran_card(layout, "PSHELL", &f);
                    text +=
                        &nastran_card(layout, "MAT1", &[mid.to_string(), real(e_steel), b(), ".3".into(), real(rho)]);
                    user.insert(pid, ("PSHELL", vec![t_user(k)], vec![mid, mid]));
                }
                1 => {
                    f.extend((0..7).map(|_| b()));
                    f.extend([
                        mid.to_string(),
                        short(t_user(k) / 2.0),
                        "0.".into(),
                        b(),
                        b(),
                        short(t_user(k) / 2.0),
                        "90.".into(),
                    ]);
                    text += &nastran_card(layout, "PCOMP", &f);
                    user.insert(pid, ("PCOMP", vec![t_user(k) / 2.0; 2], vec![mid, mid]));
                }
                _ => {
                    f.extend((0..7).map(|_| b()));
                    f.extend(["1".into(), mid.to_string(), short(t_user(k) / 2.0), "45.".into(), b(), b(), b(), b()]);
                    f.extend(["2".into(), "7".into(), short(t_user(k) / 2.0), "-45.".into()]);
                    text += &nastran_card(layout, "PCOMPG", &f);
                    user.insert(pid, ("PCOMPG", vec![t_user(k) / 2.0; 2], vec![mid, 7]));
                }
            }
            if k % 3 != 0 {
                let f = [
                    mid.to_string(),
                    real(1.4e11 * scale * scale),
                    real(1.0e10 * scale * scale),
                    ".3".into(),
                    real(5e9 * scale * scale),
                ];
                text += &nastran_card(layout, "MAT8", &f);
            }
        }
        if stripes > 3 {
            // Stripe 1's PCOMP is on MAT8 8; its temperature dependence is not carried.
            text += "MATT8,8,1\n";
        }
        text += "ENDDATA\n";
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("part.bdf");
        std::fs::write(&path, &text).unwrap();
        let mesh = drape::io::read_flow_mesh(&path, scale).unwrap_or_else(|e| panic!("{what}: {e}\n{text}"));
        assert_eq!(mesh.cards.properties.len(), stripes - 1, "{what}");
        let plies: Vec<PlyToMap> =
            nets.iter().map(|net| PlyToMap { net, card: Some(&card), thickness: None, permeability: None }).collect();
        let map = map_plies(&mesh, &plies, Cavity::Fixed, true, &mut |_| {}).unwrap();
        let covered = |e: usize| map.plies.iter().any(|p| p.elements[e].is_some());
        assert!((0..mesh.elements.len()).any(|e| !covered(e)), "{what}: some element no ply covers");
        let t0 = card.thickness;
        let moduli = PlyFabric::new(&card, t0).moduli();
        let close = |v: &Value, want: f64| (v.as_f64().unwrap() - want).abs() <= 1e-9 * want.abs();
        let drape_mid = 7 + stripes as u64 - 1;
        let last = 10 * stripes as u64;

        let decks = write(&mesh, &map, FlowFormat::Nastran, &dir.path().join("flow.bdf"));
        assert_eq!(decks.len(), 2);
        for (k, deck) in decks.iter().enumerate() {
            let x = readback("nastran-xref", std::slice::from_ref(deck));
            assert_eq!(x["rejected"], serde_json::json!([]), "{what}");
            for (e, el) in mesh.elements.iter().enumerate() {
                let r = &x["elements"][&el.id.to_string()];
                assert_eq!(r["pid"].as_u64(), Some(expected_pid[&el.id]), "{what}: element {}", el.id);
                match &map.plies[k].elements[e] {
                    Some(f) => {
                        assert!((r["theta"].as_f64().unwrap() - f.theta.to_degrees()).abs() < LARGE_FIELD_DEG_TOL)
                    }
                    None => assert!(r["theta"].is_null() || r["theta"].as_f64() == Some(0.0), "{what}: {r}"),
                }
            }
            for (pid, (kind, ts, mids)) in &user {
                let p = &x["properties"][&pid.to_string()];
                assert_eq!(p["type"].as_str(), Some(*kind), "{what}: PID {pid}");
                let t: Vec<f64> =
                    if *kind == "PSHELL" { vec![p["t"].as_f64().unwrap()] } else { f64s(&p["thicknesses"]) };
                assert!(t.iter().zip(ts).all(|(a, b)| (a - b).abs() <= 1e-6 * b), "{what}: PID {pid} thickness {t:?}");
                assert_eq!(p["mids"], serde_json::json!(mids), "{what}: PID {pid}");
            }
            assert!(close(&x["materials"]["7"]["e"], e_steel), "{what}");
            let p = &x["properties"][&last.to_string()];
            assert_eq!(
                (p["type"].as_str(), p["mids"].clone()),
                (Some("PSHELL"), serde_json::json!([drape_mid])),
                "{what}"
            );
            assert!(close(&p["t"], t0 / scale), "{what}: {p}");
            let m = &x["materials"][&drape_mid.to_string()];
            assert!(
                close(&m["e1"], moduli.e1 * scale * scale) && close(&m["e2"], moduli.e2 * scale * scale),
                "{what}: {m}"
            );
            assert!(
                close(&m["g12"], moduli.g12 * scale * scale) && close(&m["rho"], moduli.density * scale.powi(4)),
                "{what}: {m}"
            );
        }

        let files = write(&mesh, &map, FlowFormat::OptiStruct, &dir.path().join("flow.fem"));
        let x = readback("optistruct-xref", &files);
        assert_eq!(x["dangling"], serde_json::json!([]), "{what}");
        let mut fresh = std::collections::BTreeMap::new();
        for (e, el) in mesh.elements.iter().enumerate() {
            let r = &x["elements"][&el.id.to_string()];
            let (pid, property) = (r["pid"].as_u64().unwrap(), r["property"].as_str().unwrap());
            let own = expected_pid[&el.id];
            if covered(e) {
                assert_eq!((pid, property), (own, "PCOMPP"), "{what}: element {}", el.id);
                continue;
            }
            let beside = (0..mesh.elements.len()).any(|f| covered(f) && expected_pid[&mesh.elements[f].id] == own);
            if beside {
                assert!(pid > last, "{what}: element {} keeps PID {pid} beside a PCOMPP", el.id);
                assert_eq!(*fresh.entry(own).or_insert(pid), pid, "{what}: one fresh PID a PID");
            } else {
                assert_eq!(pid, own, "{what}: element {}", el.id);
            }
            let want = user.get(&own).map_or("PSHELL", |u| u.0);
            assert_eq!(property, want, "{what}: element {}", el.id);
        }
        assert!(!fresh.is_empty(), "{what}: a PID with elements on both sides of the plies' edge");
        assert_eq!(x["stacks"]["1"]["plies"], serde_json::json!([1, 2]), "{what}");
        for k in ["1", "2"] {
            let p = &x["plies"][k];
            assert!(close(&p["t"], t0 / scale), "{what}: PLY {k} {p}");
            assert!(close(&p["material"]["e1"], moduli.e1 * scale * scale), "{what}: PLY {k} {p}");
        }
        let text = std::fs::read_to_string(&files[0]).unwrap();
        assert_eq!(comments(&text).contains("not carried from the flow mesh: MATT8 8"), stripes > 3, "{what}");
    }
}

/// `x` in at most 8 characters (a Nastran small field), as a pre-processor writes it.
fn drape_short(x: f64) -> String {
    if x == 0.0 {
        return "0.".into();
    }
    for p in (0..=6).rev() {
        let s = format!("{x:.p$}");
        let s = if s.contains('.') { s } else { format!("{s}.") };
        if s.len() <= 8 {
            return s;
        }
    }
    panic!("{x} does not fit 8 characters")
}

/// The comment lines of a deck as one text (lines broken at blanks joined again).
fn comments(deck: &str) -> String {
    let words: Vec<&str> = deck.lines().filter_map(|l| l.strip_prefix('$')).flat_map(str::split_whitespace).collect();
    words.join(" ")
}
