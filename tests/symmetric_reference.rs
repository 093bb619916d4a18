//! Symmetric scenes in the speed-accuracy study: which mirrors of a ply's drape problem are found
//! (`study::symmetry`), the sign rule of a mirrored drape's shear field checked on real nets
//! (`ShearField::image`), and the study measuring each run against the reference or its image.
use drape::geometry::{Point, ToolSurface};
use drape::io::read_tool;
use drape::kinematic::fabric_field::{FabricImage, ShearField};
use drape::kinematic::DrapeNet;
use drape::layup::stack::drape_layup;
use drape::layup::{Layup, Orientation, Ply};
use drape::pipeline::Scene;
use drape::study::runner::collect;
use drape::study::speed_accuracy::{self, ReferenceImages};
use drape::study::symmetry::{check_mirror, mirror_plane, symmetries, MirrorPlane};
use drape::study::{run_plan, Finished, Shard, StudyMethod};
use std::path::{Path, PathBuf};

use FabricImage::{AsIs, Rotated, WarpMirror, WeftMirror};

fn repo(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)
}

/// A bundled scene, its tool, and its ply `name`.
fn scene_ply(scene: &str, name: &str) -> (Scene, ToolSurface, Ply) {
    let scene = Scene::load(&repo(scene)).unwrap();
    let tool = read_tool(&scene.tool, scene.scale).unwrap();
    let ply = scene.layup.plies.iter().find(|p| p.settings.name == name).unwrap().clone();
    (scene, tool, ply)
}

/// The kinematic net of `ply` alone on `tool`, at `spacing` with a `n x n` grid.
fn kinematic_net(layup: &Layup, tool: &ToolSurface, ply: &Ply, spacing: f64, n: usize) -> DrapeNet {
    let mut ply = ply.clone();
    ply.settings = ply.settings.at_spacing(spacing);
    ply.settings.extent = drape::kinematic::Extent::Grid { nu: n, nv: n, origin_node: None };
    ply.refinement = None;
    ply.auto = None;
    let one = Layup { reference: layup.reference, stack_side: layup.stack_side, plies: vec![ply], wrinkles: false };
    drape_layup(&one, tool, |_, _| {}).unwrap().pop().unwrap().net
}

/// `net` mirrored in `plane`, its fibre families kept: node (i, j) of the image is the mirror
/// image of node (i', j'), with i' = nu - 1 - i where `flip_u` (and likewise j).
fn mirrored_net(net: &DrapeNet, planes: &[MirrorPlane], flip_u: bool, flip_v: bool) -> DrapeNet {
    let mut out = net.clone();
    for i in 0..net.nu {
        for j in 0..net.nv {
            let a = if flip_u { net.nu - 1 - i } else { i };
            let b = if flip_v { net.nv - 1 - j } else { j };
            let (k, from) = (net.index(i, j), net.index(a, b));
            out.positions[k] = planes.iter().fold(net.positions[from], |p, m| m.reflect(&p));
            out.status[k] = net.status[from];
        }
    }
    let (o0, o1) = net.origin_node;
    out.origin_node = (if flip_u { net.nu - 1 - o0 } else { o0 }, if flip_v { net.nv - 1 - o1 } else { o1 });
    out
}

/// Largest |a - b| over a's complete cells, and how many.
fn largest_difference(a: &ShearField, b: &ShearField) -> (f64, usize) {
    let c = ReferenceImages::new(a, &[]).compare(b);
    (c.error_max_deg.unwrap(), c.compared)
}

fn negated(f: &ShearField) -> ShearField {
    ShearField { shear_deg: f.shear_deg.iter().map(|s| s.map(|x| -x)).collect(), ..f.clone() }
}

/// Which mirrors are found: both on the hemisphere seeded at its pole, whatever the ply angle
/// (its mesh is symmetric about the axes and the diagonals), but none at 30 deg (the mesh is
/// not symmetric about those planes); only the warp's on the cone (the
/// plane through its axis and the seed), not the weft's; none for a ply turned 30 deg on the
/// cone, a pre-sheared ply, or a grid whose origin is off its middle.
#[test]
fn symmetry_detection_finds_the_mirrors_that_hold_and_names_what_breaks_the_others() {
    let (scene, tool, _) = scene_ply("geometries/hemisphere/scene.toml", "p0");
    for ply in &scene.layup.plies {
        assert_eq!(
            symmetries(ply, &scene.layup, &tool),
            vec![WarpMirror, WeftMirror, Rotated],
            "hemisphere {}",
            ply.settings.name
        );
    }
    // Turned 30 deg at the pole, gravity stays in the planes but the mesh is not symmetric.
    let mut turned = scene.layup.plies[0].clone();
    turned.orientation = Orientation::Angle(30f64.to_radians());
    assert_eq!(symmetries(&turned, &scene.layup, &tool), vec![]);
    let why = check_mirror(&turned, &scene.layup, &tool, WarpMirror).unwrap_err();
    assert!(why.contains("off the tool"), "{why}");

    let (cone, cone_tool, p0) = scene_ply("geometries/cone/scene.toml", "p0");
    assert_eq!(symmetries(&p0, &cone.layup, &cone_tool), vec![WarpMirror]);
    // The weft's plane is normal to the slant: gravity leaves it, and so does the tool.
    let weft = check_mirror(&p0, &cone.layup, &cone_tool, WeftMirror).unwrap_err();
    assert!(weft.contains("gravity"), "{weft}");
    // The warp mirror is the plane y = 0 through the cone's axis.
    let plane = check_mirror(&p0, &cone.layup, &cone_tool, WarpMirror).unwrap();
    assert!(plane.normal.y.abs() > 1.0 - 1e-12 && plane.point.y.abs() < 1e-12, "{plane:?}");

    let mut turned = p0.clone();
    let up = drape::geometry::Vector::new(0.0, 0.0, 1.0);
    let layup = Layup { reference: up, ..cone.layup.clone() };
    turned.orientation = Orientation::Angle(30f64.to_radians());
    assert_eq!(symmetries(&turned, &layup, &cone_tool), vec![]);
    // Its warp's plane leaves the axis: gravity is not in it.
    let why = check_mirror(&turned, &layup, &cone_tool, WarpMirror).unwrap_err();
    assert!(why.contains("gravity"), "{why}");
    // The same ply at 0 deg from the same reference is the bundled one.
    turned.orientation = Orientation::Angle(0.0);
    assert_eq!(symmetries(&turned, &layup, &cone_tool), vec![WarpMirror]);

    let mut sheared = p0.clone();
    sheared.settings.pre_shear = 5f64.to_radians();
    assert_eq!(symmetries(&sheared, &cone.layup, &cone_tool), vec![]);
    let why = check_mirror(&sheared, &cone.layup, &cone_tool, WarpMirror).unwrap_err();
    assert!(why.contains("pre-shear"), "{why}");

    let mut off_centre = p0.clone();
    off_centre.settings.extent = drape::kinematic::Extent::Grid { nu: 41, nv: 100, origin_node: None };
    let why = check_mirror(&off_centre, &cone.layup, &cone_tool, WarpMirror).unwrap_err();
    assert!(why.contains("origin node"), "{why}");
}

/// The sign rule on real nets. A net mirrored in a plane, its fibre families kept (relabelled),
/// has the shear field `ShearField::image` gives: -s(u, -v) under the warp mirror, -s(-u, v)
/// under the weft mirror, s(-u, -v) under both; the hemisphere ply seeded off its pole has shear
/// of several degrees that the other sign would not reproduce. And on the hemisphere seeded at
/// its pole, where both mirrors hold, the kinematic net is its own image under each.
#[test]
fn mirrored_nets_have_the_imaged_shear_field_and_symmetric_nets_are_their_own_images() {
    let (scene, tool, p0) = scene_ply("geometries/hemisphere/scene.toml", "p0");
    let mut off_pole = p0.clone();
    off_pole.settings.origin = Point::new(0.03, 0.02, (0.01f64 - 0.03 * 0.03 - 0.02 * 0.02).sqrt());
    let net = kinematic_net(&scene.layup, &tool, &off_pole, 0.006, 31);
    let field = ShearField::of(&net);
    let largest = field.shear_deg.iter().flatten().fold(0.0f64, |m, s| m.max(s.abs()));
    assert!(largest > 3.0, "the net shears {largest} deg");
    let warp = mirror_plane(&off_pole, &scene.layup, &tool, WarpMirror).unwrap();
    let weft = mirror_plane(&off_pole, &scene.layup, &tool, WeftMirror).unwrap();
    for (image, planes, fu, fv) in [
        (WarpMirror, vec![warp], false, true),
        (WeftMirror, vec![weft], true, false),
        (Rotated, vec![warp, weft], true, true),
    ] {
        let mirrored = ShearField::of(&mirrored_net(&net, &planes, fu, fv));
        let (e, n) = largest_difference(&field.image(image), &mirrored);
        assert!(n > 500 && e < 1e-9, "{image:?}: {e} deg over {n} cells");
        if image != Rotated {
            // Without the sign change the mirror's field is not reproduced.
            let (wrong, _) = largest_difference(&negated(&field.image(image)), &mirrored);
            assert!(wrong > 1.0, "{image:?}: {wrong}");
        }
    }

    let at_pole = kinematic_net(&scene.layup, &tool, &p0, 0.006, 31);
    let field = ShearField::of(&at_pole);
    let largest = field.shear_deg.iter().flatten().fold(0.0f64, |m, s| m.max(s.abs()));
    assert!(largest > 3.0, "the net shears {largest} deg");
    for image in symmetries(&p0, &scene.layup, &tool) {
        let (e, n) = largest_difference(&field.image(image), &field);
        assert!(n > 500 && e < 1e-6, "{image:?}: {e} deg over {n} cells");
    }
    let (wrong, _) = largest_difference(&negated(&field.image(WarpMirror)), &field);
    assert!(wrong > 1.0, "{wrong}");
}

/// A net measured against its own mirror image: 0 to rounding when the study may use the
/// mirror, about twice the pre-shear (10 deg) when it may not. The pre-sheared net on the
/// hemisphere is not symmetric, so its image is another drape.
#[test]
fn a_net_against_its_mirror_image_differs_only_when_the_symmetry_is_not_used() {
    let (scene, tool, mut ply) = scene_ply("geometries/hemisphere/scene.toml", "p0");
    ply.settings.pre_shear = 10f64.to_radians();
    let field = ShearField::of(&kinematic_net(&scene.layup, &tool, &ply, 0.008, 21));
    let image = field.image(WarpMirror);
    let used = ReferenceImages::new(&field, &[WarpMirror]).compare(&image);
    assert_eq!(used.image, WarpMirror);
    assert!(used.error_max_deg.unwrap() < 1e-9 && used.compared > 200, "{used:?}");
    let not_used = ReferenceImages::new(&field, &[]).compare(&image);
    assert_eq!(not_used.image, AsIs);
    assert!(not_used.error_max_deg.unwrap() > 15.0, "{not_used:?}");
    // With the whole group the mirror is still the nearest image.
    let all = ReferenceImages::new(&field, &[WarpMirror, WeftMirror, Rotated]).compare(&image);
    assert_eq!(all.image, WarpMirror);
}

/// The study of the bundled cone at 6 and 3 mm: the warp mirror is found and recorded, every
/// compared run names the image it was measured in, and the mechanical run at 6 mm is reported
/// with the least of its errors against the reference as it fell and against its mirror image
/// (computed here from the cases' fields). On the cone both pressed drapes keep the symmetry
/// (each is its own mirror image to rounding), so the two errors are the same and the
/// reference as it fell is used: the drapes' difference is their spacing's, not a mirror's.
#[test]
fn the_study_measures_the_cone_up_to_its_mirror() {
    let scene = Scene::load(&repo("geometries/cone/scene.toml")).unwrap();
    let opts = speed_accuracy::Options {
        spacings: Some(vec![0.006]),
        mechanical_spacings: Some(vec![0.006, 0.003]),
        repeats: 1,
        ..Default::default()
    };
    let plan = speed_accuracy::plan(&scene, &opts).unwrap();
    assert_eq!(plan.symmetries, vec![WarpMirror]);
    let dir = tempfile::tempdir().unwrap();
    let (_, finished) = run_plan(&plan, dir.path(), Shard::ALL, 1, |_, _| {}).unwrap();
    let Some((Finished::SpeedAccuracy(sa), path)) = finished else { panic!("the study finished") };
    assert_eq!(sa.reference.symmetries, vec![WarpMirror]);
    assert!(std::fs::read_to_string(path).unwrap().contains("\"reference_image\": \"as-is\""));
    for p in sa.points.iter().filter(|p| p.error_max_deg.is_some()) {
        assert!(p.reference_image.is_some(), "{} at {}: no image named", p.method, p.spacing);
    }
    let records = collect(&plan, dir.path()).unwrap();
    let mech = |d: f64| {
        records
            .iter()
            .find(|r| r.case.variant.method == StudyMethod::MechanicalPressed && r.case.variant.spacing == d)
            .and_then(|r| r.result.field.clone())
            .unwrap()
    };
    let (reference, coarse) = (mech(0.003), mech(0.006));
    for f in [&reference, &coarse] {
        let (e, _) = largest_difference(&f.image(WarpMirror), f);
        // To rounding, and to friction's lag loop: it stops once the normal forces agree to
        // 1% between solves, so the two halves agree to the solves' tolerance (2.4e-6 deg
        // measured at 3 mm), not to the last digit.
        assert!(e < 1e-5, "a pressed drape on the cone broke its mirror by {e} deg");
    }
    let as_fell = ReferenceImages::new(&reference, &[]).compare(&coarse).error_max_deg.unwrap();
    let mirrored = ReferenceImages::new(&reference.image(WarpMirror), &[]).compare(&coarse).error_max_deg.unwrap();
    let p = sa.points.iter().find(|p| p.method == "mechanical-pressed" && p.spacing == 0.006).unwrap();
    let reported = p.error_max_deg.unwrap();
    // The image with the least largest error, the reference as it fell on a tie (1e-9 deg).
    let (expected, error) = if mirrored < as_fell - 1e-9 { (WarpMirror, mirrored) } else { (AsIs, as_fell) };
    assert_eq!(p.reference_image, Some(expected), "{as_fell} / {mirrored}");
    assert_eq!(reported, error, "{as_fell} / {mirrored}");
    assert!(reported > 0.1, "the 6 mm drape is {reported} deg from the 3 mm one: its spacing error");
}

/// A scene with no symmetry gives the study's file as before: no `symmetries`, no
/// `reference_image` (the cone's ply turned 30 deg from its warp).
#[test]
fn a_study_without_symmetry_writes_no_images() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(repo("geometries/cone/scene.toml"))
        .unwrap()
        .replace("tool = \"cone.obj\"", &format!("tool = \"{}\"", repo("geometries/cone/cone.obj").display()))
        .replace("../../materials", &repo("materials").display().to_string())
        .replace("warp = [0.0, 0.0, 1.0]", "warp = [0.0, 0.5, 0.866]")
        .replace("grid = [41, 101]", "grid = [21, 41]");
    let path = dir.path().join("scene.toml");
    std::fs::write(&path, text).unwrap();
    let scene = Scene::load(&path).unwrap();
    let opts = speed_accuracy::Options {
        spacings: Some(vec![0.006]),
        mechanical_spacings: Some(vec![0.006]),
        repeats: 1,
        ..Default::default()
    };
    let plan = speed_accuracy::plan(&scene, &opts).unwrap();
    assert!(plan.symmetries.is_empty());
    let out = dir.path().join("study");
    let (_, finished) = run_plan(&plan, &out, Shard::ALL, 1, |_, _| {}).unwrap();
    let (_, path) = finished.unwrap();
    let json = std::fs::read_to_string(path).unwrap();
    assert!(json.contains("error_max_deg") && !json.contains("symmetries") && !json.contains("reference_image"));
    assert!(!std::fs::read_to_string(out.join("study.json")).unwrap().contains("symmetries"));
}
