//! Offset surfaces against Abaqus's: the BladeLike mould of ../shared/data/bladelike (KinDrapeMAX,
//! MIT) with the decks Abaqus offset by the thickness of 1..4 plies. Skipped, saying so, when the
//! data are absent (a user's fresh clone has no ../shared).
use drape::geometry::offset::offset_surface;
use drape::geometry::ToolSurface;
use drape::io::read_tool as load_tool;
use std::path::PathBuf;

fn data_dir() -> Option<PathBuf> {
    let dir = std::env::var("DRAPE_BLADELIKE_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|_| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/data/bladelike"));
    if dir.join("BladeLikeMoldExt.inp").is_file() {
        Some(dir)
    } else {
        eprintln!("offset_bladelike: skipped: no BladeLike decks at {}", dir.display());
        None
    }
}

/// Distances from the vertices of `a` to the surface `b`: (mean, 95th percentile, max).
fn distances(a: &ToolSurface, b: &ToolSurface) -> (f64, f64, f64) {
    let mut d: Vec<f64> = a.vertices().iter().map(|p| b.closest_point(p).distance).collect();
    d.sort_by(f64::total_cmp);
    (d.iter().sum::<f64>() / d.len() as f64, d[d.len() * 95 / 100], d[d.len() - 1])
}

/// Abaqus offset each deck by this much (20 mm a layer: the distance of its nodes to the mould).
const LAYER: f64 = 0.02;

#[test]
fn offsets_of_the_bladelike_mould_match_abaqus() {
    let Some(dir) = data_dir() else { return };
    let base = load_tool(&dir.join("BladeLikeMoldExt.inp"), 1.0).unwrap();
    assert_eq!(base.num_triangles(), 6764);
    for k in 1..=4 {
        let abaqus = load_tool(&dir.join(format!("BladeLikeMoldExt-Offset{k}.inp")), 1.0).unwrap();
        let h = LAYER * k as f64;
        let (mean, _, max) = distances(&abaqus, &base);
        assert!(mean > 0.98 * h && max < 1.15 * h, "Offset{k} is not {h} m from the mould (mean {mean}, max {max})");
        // The deck's facet normals point away from the side Abaqus offset to: plies on this
        // mould stack on the "opposite" side.
        let (ours, report) = offset_surface(&base, &vec![-h; base.vertices().len()]).unwrap();
        let (mean, p95, max) = distances(&abaqus, &ours);
        eprintln!(
            "Offset{k} ({h} m): Abaqus's vertices to our offset surface: mean {mean:.6} m ({:.2}% of h), 95th percentile {p95:.6} m, max {max:.6} m; {} of our triangles folded ({} vertices bridged)",
            100.0 * mean / h,
            report.folded,
            report.relaxed
        );
        assert_eq!(report.folded, 0, "Offset{k}: the offset surface folds");
        // Both follow the normals; they differ where they treat the mesh edges and the tightest
        // concave curvature differently (Abaqus trims there: decks 2-4 have fewer triangles).
        assert!(mean < 0.02 * h, "Offset{k}: mean deviation {mean} m");
        assert!(p95 < 0.07 * h, "Offset{k}: 95th percentile {p95} m");
    }
}

/// A ply draped on the mould deck itself (an Abaqus R3D3 deck as the tool), seeded at the middle.
#[test]
fn a_ply_drapes_on_the_bladelike_mould() {
    let Some(dir) = data_dir() else { return };
    let tool = load_tool(&dir.join("BladeLikeMoldExt.inp"), 1.0).unwrap();
    let v = tool.vertices();
    let lo = v.iter().fold(v[0].coords, |a, p| a.inf(&p.coords));
    let hi = v.iter().fold(v[0].coords, |a, p| a.sup(&p.coords));
    let centre = tool.closest_point(&drape::geometry::Point::from((lo + hi) / 2.0)).point;
    let size = hi - lo;
    let long = size.imax();
    let mut warp = drape::geometry::Vector::zeros();
    warp[long] = 1.0;
    let settings = drape::KinematicSettings::grid("blade", centre, warp, 0.02, 61, 41);
    let net = drape::drape(&tool, &settings).unwrap();
    let stats = net.shear_stats(45f64.to_radians());
    eprintln!(
        "BladeLike: {} of {} cells draped, |shear| max {:.2} deg, mean {:.2} deg",
        stats.cells,
        net.num_cells(),
        stats.max_abs.to_degrees(),
        stats.mean_abs.to_degrees()
    );
    assert!(stats.cells > net.num_cells() / 4, "only {} cells", stats.cells);
    assert!(net
        .positions
        .iter()
        .zip(&net.status)
        .all(|(p, s)| *s != drape::kinematic::NodeStatus::Placed || p.coords.iter().all(|x| x.is_finite())));
}
