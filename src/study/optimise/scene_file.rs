//! The scene with the optimal placement: the user's scene file with the optimised ply's
//! `origin` and `angle_deg` set, ready for `drape run`. Written into the optimisation's folder,
//! so every file the scene names relative to itself is made absolute.
use std::path::Path;

/// Keys of a scene (top level, `[materials]`, `[export]`, `[[ply]]`) that name files relative to
/// the scene.
const TOP_FILES: [&str; 1] = ["tool"];
const PLY_FILES: [&str; 1] = ["outline_file"];
const STEER_PREFIX: &str = "steer:";

/// The text of the scene at `scene` with ply `ply` seeded at `origin` (scene units) and, when
/// given, laid at `angle_deg` (its `warp` dropped); `note` becomes the file's opening comment.
pub fn optimal_scene(
    scene: &Path,
    ply: &str,
    origin: [f64; 3],
    angle_deg: Option<f64>,
    note: &str,
) -> Result<String, String> {
    let text = std::fs::read_to_string(scene).map_err(|e| format!("cannot read scene {}: {e}", scene.display()))?;
    let mut table: toml::Table = text.parse().map_err(|e| format!("scene {}: {e}", scene.display()))?;
    let base = std::path::absolute(scene.parent().unwrap_or(Path::new(".")))
        .map_err(|e| format!("scene {}: {e}", scene.display()))?;
    let absolute = |v: &mut toml::Value, prefix: &str| {
        if let Some(s) = v.as_str().and_then(|s| s.strip_prefix(prefix)) {
            *v = toml::Value::String(format!("{prefix}{}", base.join(s.trim()).display()));
        }
    };
    for key in TOP_FILES {
        if let Some(v) = table.get_mut(key) {
            absolute(v, "");
        }
    }
    let materials: Vec<String> = match table.get_mut("materials").and_then(toml::Value::as_table_mut) {
        Some(m) => {
            m.iter_mut().for_each(|(_, v)| absolute(v, ""));
            m.keys().cloned().collect()
        }
        None => Vec::new(),
    };
    if let Some(mesh) = table.get_mut("export").and_then(|e| e.get_mut("mesh")) {
        absolute(mesh, "");
    }
    let mut found = false;
    for p in table.get_mut("ply").and_then(toml::Value::as_array_mut).into_iter().flatten() {
        let Some(p) = p.as_table_mut() else { continue };
        for key in PLY_FILES {
            if let Some(v) = p.get_mut(key) {
                absolute(v, "");
            }
        }
        if let Some(v) = p.get_mut("generators") {
            absolute(v, STEER_PREFIX);
        }
        // A material that is not a name from [materials] is a card file.
        if let Some(v) = p.get_mut("material") {
            if v.as_str().is_some_and(|m| !materials.iter().any(|k| k == m)) {
                absolute(v, "");
            }
        }
        if p.get("name").and_then(toml::Value::as_str) == Some(ply) {
            found = true;
            p.insert("origin".into(), toml::Value::Array(origin.iter().map(|x| toml::Value::Float(*x)).collect()));
            if let Some(a) = angle_deg {
                p.remove("warp");
                p.insert("angle_deg".into(), toml::Value::Float(a));
            }
        }
    }
    if !found {
        return Err(format!("scene {} has no ply '{ply}'", scene.display()));
    }
    let body = toml::to_string(&table).map_err(|e| e.to_string())?;
    let comment: String = note.lines().map(|l| format!("# {l}\n")).collect();
    Ok(format!("{comment}{body}"))
}
