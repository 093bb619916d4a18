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
    write_scene(dir, tools, scene);
    let run = drape_run(dir).assert().success();
    (dir.join("out"), String::from_utf8_lossy(&run.get_output().stdout).to_string())
}

/// `drape run dir/scene.toml --out dir/out`, to be run.
pub fn drape_run(dir: &std::path::Path) -> assert_cmd::Command {
    let mut command = assert_cmd::Command::cargo_bin("drape").unwrap();
    command.arg("run").arg(dir.join("scene.toml")).arg("--out").arg(dir.join("out"));
    command
}

/// Write `tools` (file name, mesh) and `scene` (as `scene.toml`) into `dir`.
pub fn write_scene(dir: &std::path::Path, tools: &[(&str, &drape::geometry::TriangleMesh)], scene: &str) {
    for (name, mesh) in tools {
        std::fs::write(dir.join(name), mesh.to_obj_string()).unwrap();
    }
    std::fs::write(dir.join("scene.toml"), scene).unwrap();
}

/// Write `scene` into `dir` (its tools already there), run `drape run` on it into `dir/out` and
/// expect it refused as bad input (exit 2): its standard error.
pub fn refused_scene(dir: &std::path::Path, scene: &str) -> String {
    write_scene(dir, &[], scene);
    let run = drape_run(dir).assert().code(2);
    String::from_utf8_lossy(&run.get_output().stderr).to_string()
}

/// A JSON file the run wrote (a panic naming the file when it is missing or not JSON).
pub fn read_json(p: &std::path::Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))).unwrap()
}

/// The nodes of a net JSON whose nodes are all placed (a panic names the first that is not).
pub fn all_nodes(net: &serde_json::Value) -> Vec<[f64; 3]> {
    net["nodes"]
        .as_array()
        .unwrap()
        .iter()
        .enumerate()
        .map(|(k, p)| {
            let p = p.as_array().unwrap_or_else(|| panic!("node {k} is not placed"));
            [0, 1, 2].map(|c| p[c].as_f64().unwrap())
        })
        .collect()
}
