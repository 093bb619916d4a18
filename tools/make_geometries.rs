//! Writes the bundled tool meshes in `geometries/` from the analytic shapes in
//! `drape::geometry::shapes`.
//!
//! ```text
//! cargo run --release --example make_geometries -- [--large] [--out DIR]
//! ```
//!
//! Without `--large` it (re)writes the small, committed meshes, one folder per tool:
//!
//! | file                                  | shape                                                   |
//! |---------------------------------------|---------------------------------------------------------|
//! | `hemisphere/hemisphere-2k.obj`        | hemisphere R = 0.1 m, 23 subdivisions (2 116 triangles) |
//! | `hemisphere/hemisphere-20k.obj`       | hemisphere R = 0.1 m, 71 subdivisions (20 164)          |
//! | `plate/plate.obj`                     | 0.4 x 0.3 m flat plate, 80 x 60 quads                   |
//! | `cylinder/cylinder.obj`               | half cylinder R = 0.1 m, 0.3 m long, axis y             |
//! | `cone/cone.obj`                       | closed frustum ring r 0.15 -> 0.075 m, 0.1 m high       |
//! | `saddle/saddle.obj`                   | z = (x^2 - y^2) / (2 * 0.3 m) over 0.3 x 0.3 m          |
//! | `double-dome/double-dome.obj`         | double-dome benchmark-style part on a 0.47 x 0.37 m flange |
//! | `hat-box/hat-box.obj`                 | 0.2 x 0.15 x 0.08 m box, vertical walls, 0.07 m flange  |
//! | `square-table/square-table.obj`       | closed 0.1 x 0.1 x 0.1 m box, top at z = 0 (seed 000)    |
//! | `round-table/round-table.obj`         | closed drum R = 0.8 m, 0.75 m high, top at z = 0 (seed 000) |
//! | `sphere/sphere.obj`                   | sphere R = 0.4 m at the origin, 20 480 triangles (seed 000) |
//! | `punch-and-die/punch.obj`             | hemispherical punch R = 75 mm, 48 subdivisions (9 216)  |
//! | `punch-and-die/die.obj`               | die face at z = 25 mm, opening R = 80 mm, 10 mm fillet, 70 mm deep |
//!
//! With `--large` it also writes `generated/hemisphere-200k.obj` (224 subdivisions, 200 704
//! triangles) and `generated/hemisphere-800k.obj` (448 subdivisions, 802 816 triangles) for
//! benchmarks; `geometries/generated/` is git-ignored. The `scene.toml` files and the README next
//! to the meshes are written by hand and are not touched.
//!
//! The output is deterministic: the same build writes byte-identical files. `--out DIR` writes
//! under `DIR` instead of the crate's `geometries/` folder.
use drape::geometry::shapes::*;
use drape::geometry::TriangleMesh;
use std::f64::consts::{PI, TAU};
use std::io::Write;
use std::path::{Path, PathBuf};

/// A committed mesh: its path under the output folder and how to build it.
type Committed = (&'static str, fn() -> TriangleMesh);

/// Hemisphere radius of the bundled hemisphere meshes (m).
const HEMISPHERE_RADIUS: f64 = 0.1;
/// The punch-and-die set-up (issue 33): a hemispherical punch of R 75 mm (its rim at z = 0 where
/// its 50 mm stroke ends) into a die opening of R 80 mm with a 10 mm entry fillet, the die's face
/// at z = 25 mm (the punch's top where its stroke begins), m.
const PUNCH_RADIUS: f64 = 0.075;
/// See [`PUNCH_RADIUS`].
const DIE_OPENING: f64 = 0.08;
/// See [`PUNCH_RADIUS`].
const DIE_FILLET: f64 = 0.01;
/// See [`PUNCH_RADIUS`].
const DIE_FACE_Z: f64 = 0.025;

fn main() -> anyhow::Result<()> {
    let mut large = false;
    let mut out = Path::new(env!("CARGO_MANIFEST_DIR")).join("geometries");
    let mut args = std::env::args().skip(1);
    while let Some(arg) = args.next() {
        match arg.as_str() {
            "--large" => large = true,
            "--out" => out = PathBuf::from(args.next().ok_or_else(|| anyhow::anyhow!("--out needs a directory"))?),
            "-h" | "--help" => {
                println!("usage: make_geometries [--large] [--out DIR]");
                return Ok(());
            }
            other => {
                anyhow::bail!("unknown argument {other:?}; usage: make_geometries [--large] [--out DIR]")
            }
        }
    }

    let small: [Committed; 13] = [
        ("hemisphere/hemisphere-2k.obj", || hemisphere(HEMISPHERE_RADIUS, 23)),
        ("hemisphere/hemisphere-20k.obj", || hemisphere(HEMISPHERE_RADIUS, 71)),
        ("plate/plate.obj", || plate(0.4, 0.3, 80, 60)),
        ("cylinder/cylinder.obj", || cylinder(0.1, 0.3, PI, 100, 96)),
        ("cone/cone.obj", || cone(0.15, 0.075, 0.1, TAU, 192, 40)),
        ("saddle/saddle.obj", || saddle(0.3, 0.3, 100)),
        ("double-dome/double-dome.obj", || double_dome(&DoubleDome::benchmark(), 60)),
        ("hat-box/hat-box.obj", || hat_box(&HatBox::standard(), 0.004, 8)),
        ("square-table/square-table.obj", || table_box(0.1, 0.1, 0.1, 10)),
        ("round-table/round-table.obj", || round_table(0.8, 0.75, 256, 8, 6)),
        ("sphere/sphere.obj", || icosphere(0.4, drape::geometry::Point::origin(), 5)),
        ("punch-and-die/punch.obj", || hemisphere(PUNCH_RADIUS, 48)),
        ("punch-and-die/die.obj", || {
            let mut die = die_ring(DIE_OPENING, DIE_FILLET, 0.22, 0.07, 192, [8, 8, 12]);
            die.vertices.iter_mut().for_each(|v| v.z += DIE_FACE_Z);
            die
        }),
    ];
    for (name, make) in &small {
        write(&out, name, &make())?;
    }
    if large {
        write(&out, "generated/hemisphere-200k.obj", &hemisphere_with_triangles(HEMISPHERE_RADIUS, 200_000))?;
        write(&out, "generated/hemisphere-800k.obj", &hemisphere_with_triangles(HEMISPHERE_RADIUS, 800_000))?;
    }
    Ok(())
}

/// Write `mesh` as OBJ to `root/name` (creating folders) and print a one-line summary.
fn write(root: &Path, name: &str, mesh: &TriangleMesh) -> anyhow::Result<()> {
    let path = root.join(name);
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir)?;
    }
    let text =
        format!("# {name}: written by `cargo run --release --example make_geometries`\n{}", mesh.to_obj_string());
    drape::io::write_atomic(&path, |w| w.write_all(text.as_bytes()))?;
    println!(
        "{:<36} {:>8} triangles {:>8} vertices {:>10} bytes",
        name,
        mesh.triangles.len(),
        mesh.vertices.len(),
        text.len()
    );
    Ok(())
}
