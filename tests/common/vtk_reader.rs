//! A .vtu read by VTK's own reader (tools/vtu_vtk_readback.py, `vtk.vtkXMLUnstructuredGridReader`):
//! every array as f64 (integers converted exactly, NaN kept).
use serde_json::Value;
use std::collections::BTreeMap;
use std::path::Path;
use std::process::Command;

/// What VTK read from a .vtu.
pub struct VtkRead {
    /// The readback summary (points, cells, arrays, encoding).
    pub summary: Value,
    /// Arrays by `<kind>.<name>` (kind: points, cells, cell, point): values tuple by tuple.
    pub arrays: BTreeMap<String, Vec<f64>>,
}

/// Read `vtu` with VTK (the arrays go through a temporary folder as raw little-endian f64).
pub fn read_with_vtk(vtu: &Path) -> VtkRead {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tools/vtu_vtk_readback.py");
    let dir = tempfile::tempdir().unwrap();
    let out = Command::new("python3").arg(&script).arg(vtu).arg(dir.path()).output().unwrap();
    assert!(out.status.success(), "{} failed:\n{}", script.display(), String::from_utf8_lossy(&out.stderr));
    let summary: Value = serde_json::from_slice(&out.stdout).unwrap();
    let mut arrays = BTreeMap::new();
    for key in summary["arrays"].as_object().unwrap().keys() {
        let bytes = std::fs::read(dir.path().join(format!("{key}.f64"))).unwrap();
        let values = bytes.chunks_exact(8).map(|b| f64::from_le_bytes(b.try_into().unwrap())).collect();
        arrays.insert(key.clone(), values);
    }
    VtkRead { summary, arrays }
}

/// Whether python3 with vtk and numpy is there; panics saying what to install if not, unless
/// DRAPE_SKIP_PYTHON=1.
pub fn vtk_ready() -> bool {
    if std::env::var("DRAPE_SKIP_PYTHON").is_ok_and(|v| v == "1") {
        eprintln!("DRAPE_SKIP_PYTHON=1: skipped the read-back with VTK");
        return false;
    }
    match Command::new("python3").args(["-c", "import vtk, numpy"]).output() {
        Ok(o) if o.status.success() => true,
        Ok(o) => panic!(
            "python3 cannot import vtk/numpy ({}). Run `python3 -m pip install -r tools/requirements.txt`, or set DRAPE_SKIP_PYTHON=1.",
            String::from_utf8_lossy(&o.stderr).trim()
        ),
        Err(e) => panic!("cannot run python3 ({e}); install it or set DRAPE_SKIP_PYTHON=1"),
    }
}
