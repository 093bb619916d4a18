//! Shared helpers for the integration tests.
#![allow(dead_code)]

pub mod chebyshev;
pub mod elastica;
pub mod shear_frames;
pub mod vtk_reader;

/// Write `tools` (file name, mesh) and `scene` into `dir`, run `drape run` on the scene into
/// `dir/out` and expect success: the output folder and the command's standard output.
pub fn run_scene(
    dir: &std::path::Path,
    tools: &[(&str, &drape::geometry::TriangleMesh)],
    scene: &str,
) -> (std::path::PathBuf, String) {
    for (name, mesh) in tools {
        std::fs::write(dir.join(name), mesh.to_obj_string()).unwrap();
    }
    std::fs::write(dir.join("scene.toml"), scene).unwrap();
    let out = dir.join("out");
    let run = assert_cmd::Command::cargo_bin("drape")
        .unwrap()
        .arg("run")
        .arg(dir.join("scene.toml"))
        .arg("--out")
        .arg(&out)
        .assert()
        .success();
    (out, String::from_utf8_lossy(&run.get_output().stdout).to_string())
}

/// A JSON file the run wrote (a panic naming the file when it is missing or not JSON).
pub fn read_json(p: &std::path::Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))).unwrap()
}
