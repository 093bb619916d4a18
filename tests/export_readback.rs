//! Exports read back by independent code: tools/readback.py reads the .vtu with meshio, the CSV with
//! Python's csv module and the JSON with Python's json module. Known answer: a planar grid sheared
//! by a known angle, with a few failed nodes whose cells must be absent.
//!
//! Needs `python3` with meshio (`python3 -m pip install meshio`; .ci/run installs it). Set
//! DRAPE_SKIP_PYTHON=1 to skip the Python part (the Rust-side checks still run).
use drape::geometry::{Point, Vector};
use drape::io::{read_net, write_net, Format, CSV_HEADER};
use drape::kinematic::{DrapeNet, NodeStatus};
use serde_json::Value;
use std::collections::BTreeSet;
use std::path::Path;
use std::process::Command;

const NU: usize = 6;
const NV: usize = 5;
const D: f64 = 0.01;
/// Angle between warp and weft (degrees); the shear is 90 - this.
const WEFT_ANGLE_DEG: f64 = 70.0;
/// Failed nodes: (i, j, status).
const FAILED: [(usize, usize, NodeStatus); 3] =
    [(2, 2, NodeStatus::NoRoot), (5, 4, NodeStatus::NoRoot), (0, 4, NodeStatus::OffTool)];

/// Orthonormal in-plane axes of the (tilted) plane and its origin.
fn axes() -> (Vector, Vector, Point) {
    let e1 = Vector::new(1.0, 2.0, 2.0) / 3.0;
    let e2 = Vector::new(2.0, 1.0, -2.0) / 3.0;
    (e1, e2, Point::new(0.3, -0.2, 1.5))
}

/// Node (i, j) at i d e1 + j d (cos w e1 + sin w e2): every cell has shear 90 deg - w exactly.
fn sheared_net() -> DrapeNet {
    let (e1, e2, o) = axes();
    let w = WEFT_ANGLE_DEG.to_radians();
    let weft = w.cos() * e1 + w.sin() * e2;
    let mut net = DrapeNet::new("sheared", D, NU, NV, (2, 1));
    for i in 0..NU {
        for j in 0..NV {
            let k = net.index(i, j);
            net.positions[k] = o + (i as f64 * D) * e1 + (j as f64 * D) * weft;
            net.status[k] = NodeStatus::Placed;
            net.triangles[k] = k as u32;
        }
    }
    for (i, j, s) in FAILED {
        let k = net.index(i, j);
        net.status[k] = s;
    }
    net.meta.other.insert("test".into(), Value::from("export_readback"));
    net
}

/// Cells with all four corners placed.
fn expected_cells() -> BTreeSet<(usize, usize)> {
    let failed = |i: usize, j: usize| FAILED.iter().any(|&(a, b, _)| (a, b) == (i, j));
    let mut s = BTreeSet::new();
    for i in 0..NU - 1 {
        for j in 0..NV - 1 {
            if ![(i, j), (i + 1, j), (i, j + 1), (i + 1, j + 1)].iter().any(|&(a, b)| failed(a, b)) {
                s.insert((i, j));
            }
        }
    }
    s
}

fn f(v: &Value, key: &str) -> f64 {
    v[key].as_f64().unwrap_or_else(|| panic!("readback summary has no number \"{key}\": {v:#}"))
}

fn u(v: &Value, key: &str) -> u64 {
    v[key].as_u64().unwrap_or_else(|| panic!("readback summary has no count \"{key}\": {v:#}"))
}

/// Whether the Python part should run; fails the test (with what to do) if meshio is missing.
fn python_ready() -> bool {
    if std::env::var("DRAPE_SKIP_PYTHON").is_ok_and(|v| v == "1") {
        eprintln!("export_readback: DRAPE_SKIP_PYTHON=1: skipped the independent Python read-back");
        return false;
    }
    let probe = Command::new("python3").args(["-c", "import meshio, numpy"]).output();
    match probe {
        Ok(o) if o.status.success() => true,
        Ok(o) => panic!(
            "python3 cannot import meshio/numpy ({}). Run `python3 -m pip install meshio numpy` \
             (CI installs it in .ci/run), or set DRAPE_SKIP_PYTHON=1 to skip this check.",
            String::from_utf8_lossy(&o.stderr).trim()
        ),
        Err(e) => panic!(
            "cannot run python3 ({e}). Install Python 3 and `python3 -m pip install meshio numpy`, \
             or set DRAPE_SKIP_PYTHON=1 to skip this check."
        ),
    }
}

fn readback(vtu: &Path, csv: &Path, json: &Path) -> Value {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tools/readback.py");
    let out = Command::new("python3").arg(&script).args([vtu, csv, json]).arg("--cells").output().unwrap();
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

#[test]
fn exports_read_back_independently() {
    let net = sheared_net();
    let shear_deg = 90.0 - WEFT_ANGLE_DEG;
    let cells = expected_cells();
    assert_eq!(cells.len(), 14, "test setup: 20 cells less the 6 touching a failed node");
    let points = NU * NV - FAILED.len();

    let dir = tempfile::tempdir().unwrap();
    let paths = write_net(&net, dir.path(), &Format::ALL).unwrap();
    let [json, vtu, csv] = [&paths[0], &paths[1], &paths[2]];
    assert_eq!(json.file_name().unwrap(), "sheared.drape.json");
    assert_eq!(vtu.file_name().unwrap(), "sheared.vtu");
    assert_eq!(csv.file_name().unwrap(), "sheared.cells.csv");

    // Rust-side: the JSON reads back to the same grid and statuses; the CSV has one row a cell.
    let back = read_net(json).unwrap();
    assert_eq!((back.nu, back.nv, back.origin_node), (NU, NV, (2, 1)));
    assert_eq!(back.status, net.status);
    for k in 0..NU * NV {
        if net.status[k] == NodeStatus::Placed {
            assert!((back.positions[k] - net.positions[k]).norm() < 1e-15, "node {k}");
        }
    }
    let text = std::fs::read_to_string(csv).unwrap();
    assert_eq!(text.lines().next(), Some(CSV_HEADER));
    assert_eq!(text.lines().count(), 1 + cells.len());
    let j: Value = serde_json::from_str(&std::fs::read_to_string(json).unwrap()).unwrap();
    assert_eq!(j["status"]["placed"], points);
    assert_eq!(j["status"]["failed"], serde_json::json!({"no_root": 2, "off_tool": 1}));

    if !python_ready() {
        return;
    }
    let s = readback(vtu, csv, json);
    eprintln!("readback summary: {s}");
    assert_eq!(u(&s, "points"), points as u64);
    assert_eq!(u(&s, "quads"), cells.len() as u64);
    assert_eq!(u(&s, "other_cells"), 0);
    let n = cells.len();
    assert_eq!(
        s["cell_data_shapes"],
        serde_json::json!({"shear_deg": [n], "warp": [n, 3], "weft": [n, 3], "normal": [n, 3], "cell_i": [n], "cell_j": [n]})
    );
    assert_eq!(s["point_data_shapes"], serde_json::json!({"node_i": [points], "node_j": [points]}));
    assert_eq!(u(&s, "connectivity_errors"), 0);
    let got: BTreeSet<(usize, usize)> = s["cells"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| (c[0].as_u64().unwrap() as usize, c[1].as_u64().unwrap() as usize))
        .collect();
    assert_eq!(got, cells, "the .vtu must hold exactly the complete cells");

    assert!((f(&s, "shear_deg_min") - shear_deg).abs() < 1e-9, "{s:#}");
    assert!((f(&s, "shear_deg_max") - shear_deg).abs() < 1e-9, "{s:#}");
    for key in
        ["max_warp_norm_err", "max_weft_norm_err", "max_normal_norm_err", "max_warp_dot_normal", "max_weft_dot_normal"]
    {
        assert!(f(&s, key) < 1e-12, "{key} = {}", f(&s, key));
    }

    assert_eq!(s["json_grid"], serde_json::json!([NU, NV]));
    assert_eq!(u(&s, "json_placed"), points as u64);
    assert_eq!(u(&s, "json_nodes_non_null"), points as u64);
    assert_eq!(f(&s, "max_point_vs_json_node"), 0.0, "VTU points and JSON nodes must be the same numbers");
    assert_eq!(u(&s, "json_cell_shear_non_null"), n as u64);
    assert_eq!((u(&s, "json_cells_not_in_vtu"), u(&s, "vtu_cells_not_in_json")), (0, 0));
    assert_eq!(f(&s, "max_json_vs_vtu_shear_deg"), 0.0, "JSON and VTU shears must be the same numbers");

    assert_eq!(u(&s, "csv_rows"), n as u64);
    assert_eq!((u(&s, "csv_cells_not_in_vtu"), u(&s, "vtu_cells_not_in_csv")), (0, 0));
    assert_eq!(f(&s, "max_csv_vs_vtu_shear_deg"), 0.0, "CSV and VTU shears must be the same numbers");
    assert_eq!(f(&s, "max_csv_vs_vtu_direction"), 0.0, "CSV and VTU directions must be the same numbers");
}

/// The fibre frame in the files is the expected one: warp along e1, weft at the weft angle,
/// normal e1 x e2 (checked on the CSV, which is plain text).
#[test]
fn csv_frame_matches_geometry() {
    let (e1, e2, _) = axes();
    let w = WEFT_ANGLE_DEG.to_radians();
    let weft = w.cos() * e1 + w.sin() * e2;
    let normal = e1.cross(&e2);
    let dir = tempfile::tempdir().unwrap();
    let paths = write_net(&sheared_net(), dir.path(), &[Format::Csv]).unwrap();
    let text = std::fs::read_to_string(&paths[0]).unwrap();
    for line in text.lines().skip(1) {
        let v: Vec<f64> = line.split(',').map(|x| x.parse().unwrap()).collect();
        let vec = |k: usize| Vector::new(v[k], v[k + 1], v[k + 2]);
        assert!((v[5] - (90.0 - WEFT_ANGLE_DEG)).abs() < 1e-9, "{line}");
        assert!((vec(6) - e1).norm() < 1e-12, "{line}");
        assert!((vec(9) - weft).norm() < 1e-12, "{line}");
        assert!((vec(12) - normal).norm() < 1e-12, "{line}");
    }
}

/// A net larger than `BINARY_FROM_CELLS` is written as compressed binary VTU, and VTK's own
/// reader gets every point and every cell value of the net back bit for bit.
#[test]
fn export_large_net_as_binary_vtu_read_by_vtk() {
    use crate::common::vtk_reader::{read_with_vtk, vtk_ready};
    use drape::io::vtk::{write_vtu_as, VtuEncoding, BINARY_FROM_CELLS};
    let n = 241;
    let d = 0.005;
    let mut net = DrapeNet::new("big", d, n, n, (n / 2, n / 2));
    for i in 0..n {
        for j in 0..n {
            let (x, y) = (i as f64 * d, j as f64 * d);
            let k = net.index(i, j);
            net.positions[k] = Point::new(x, y, 0.05 * (3.0 * x).sin() * (2.0 * y).cos());
            net.status[k] = NodeStatus::Placed;
        }
    }
    // Failed nodes: a corner block and a scattered few, so points are renumbered.
    for i in 0..n {
        for j in 0..n {
            if (i < 20 && j < 30) || (i * 7 + j * 13) % 997 == 0 {
                let k = net.index(i, j);
                net.status[k] = NodeStatus::NoRoot;
            }
        }
    }
    let complete: Vec<(usize, usize)> = (0..n - 1)
        .flat_map(|i| (0..n - 1).map(move |j| (i, j)))
        .filter(|&(i, j)| net.cell_corners(i, j).is_some())
        .collect();
    assert!(complete.len() >= BINARY_FROM_CELLS, "{} cells", complete.len());
    let dir = tempfile::tempdir().unwrap();
    let (bin, ascii) = (dir.path().join("big.vtu"), dir.path().join("big-ascii.vtu"));
    drape::io::write_vtu(&net, &bin).unwrap();
    write_vtu_as(&net, &ascii, VtuEncoding::Ascii).unwrap();
    let bytes = std::fs::read(&bin).unwrap();
    let head = String::from_utf8_lossy(&bytes[..bytes.len().min(4000)]).into_owned();
    assert!(head.contains("compressor=\"vtkZLibDataCompressor\"") && head.contains("header_type=\"UInt64\""));
    assert!(!head.contains("format=\"ascii\"") && head.contains("format=\"appended\""));
    let ascii_len = std::fs::metadata(&ascii).unwrap().len();
    println!("{} cells: binary {} bytes, ascii {ascii_len} bytes", complete.len(), bytes.len());
    assert!((bytes.len() as u64) < ascii_len / 2, "binary is not smaller");
    // A small net stays ASCII.
    let small = sheared_net();
    let small_path = dir.path().join("small.vtu");
    drape::io::write_vtu(&small, &small_path).unwrap();
    assert!(std::fs::read_to_string(&small_path).unwrap().contains("format=\"ascii\""));

    if !vtk_ready() {
        return;
    }
    let r = read_with_vtk(&bin);
    assert_eq!(r.summary["encoding"]["compressor"], "vtkZLibDataCompressor");
    let placed: Vec<usize> = (0..n * n).filter(|&k| net.status[k] == NodeStatus::Placed).collect();
    assert_eq!(r.summary["points"].as_u64().unwrap() as usize, placed.len());
    assert_eq!(r.summary["cells"].as_u64().unwrap() as usize, complete.len());
    let a = &r.arrays;
    for (p, &k) in placed.iter().enumerate() {
        let q = net.positions[k];
        assert_eq!(a["points.Points"][3 * p..3 * p + 3], [q.x, q.y, q.z], "point {p}");
        assert_eq!([a["point.node_i"][p], a["point.node_j"][p]], [(k / n) as f64, (k % n) as f64]);
    }
    assert!(a["cells.types"].iter().all(|&t| t == 9.0));
    for (c, &(i, j)) in complete.iter().enumerate() {
        assert_eq!([a["cell.cell_i"][c], a["cell.cell_j"][c]], [i as f64, j as f64]);
        assert_eq!(a["cell.shear_deg"][c], net.cell_shear(i, j).unwrap().to_degrees(), "cell ({i}, {j})");
        let f = net.cell_frame(i, j).unwrap();
        for (name, v) in [("warp", f.warp), ("weft", f.weft), ("normal", f.normal)] {
            assert_eq!(a[&format!("cell.{name}")][3 * c..3 * c + 3], [v.x, v.y, v.z], "{name} of ({i}, {j})");
        }
        // Corners (i, j), (i+1, j), (i+1, j+1), (i, j+1) by the points' node numbers.
        assert_eq!(a["cells.offsets"][c], 4.0 * (c + 1) as f64);
        let corners: Vec<(f64, f64)> = a["cells.connectivity"][4 * c..4 * c + 4]
            .iter()
            .map(|&p| (a["point.node_i"][p as usize], a["point.node_j"][p as usize]))
            .collect();
        let want: Vec<(f64, f64)> =
            [(i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)].iter().map(|&(x, y)| (x as f64, y as f64)).collect();
        assert_eq!(corners, want, "cell ({i}, {j})");
    }
}
