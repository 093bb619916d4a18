//! `drape report`: pictures are looked at, not only written. A real kinematic drape on a
//! hemisphere plus a mechanical copy carrying a known per-cell change; the PNGs are decoded and
//! must hold the colours of the cells' shear (and of the change), the tool's greys, text; the
//! SVGs must hold the cells; the page must show every picture and one table row per ply.
use drape::geometry::{shapes, Point, Vector};
use drape::io::{write_net, Format};
use drape::kinematic::{drape, DrapeNet, KinematicSettings, Method};
use drape::report::{
    bin_shares, bin_width, change_limit, colour_limit, shear_colour, tool_greys, write_report, ReportError, HEIGHT,
    WIDTH,
};
use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};

/// Hemisphere radius (m) and ply grid.
const R: f64 = 0.1;
const N: usize = 31;
const D: f64 = 0.007;
/// Share of the distinct expected colours that must appear in a picture.
const MIN_COLOURS_FOUND: f64 = 0.85;
const WHITE: [u8; 3] = [255, 255, 255];
/// The known change of p0mech per cell across the diagonal, degrees.
const CHANGE_STEP: f64 = 0.2;
/// Pixels in the tool's greys when the tool is drawn (the visible rim of the hemisphere).
const MIN_TOOL_PIXELS: usize = 5000;

/// Write a hemisphere tool with `subdivisions` and drape ply `p0` on it; plus `p0mech`, a
/// mechanical copy with change_from_kinematic = CHANGE_STEP deg * (i - j) per cell (null where
/// the cell is incomplete): a smooth change, well above the tool's facet noise.
fn make_run(dir: &Path, subdivisions: usize) -> (DrapeNet, DrapeNet) {
    let mesh = shapes::hemisphere(R, subdivisions);
    let obj = dir.join("tool.obj");
    std::fs::write(&obj, mesh.to_obj_string()).unwrap();
    let tool = mesh.into_surface().unwrap();
    let mut net = drape(&tool, &KinematicSettings::grid("p0", Point::new(0.0, 0.0, R), Vector::x(), D, N, N)).unwrap();
    net.meta.tool = Some(obj.display().to_string());
    let mut mech = net.clone();
    mech.name = "p0mech".into();
    mech.method = Method::Mechanical;
    let change: Vec<Option<f64>> = (0..net.num_cells())
        .map(|k| {
            let (i, j) = (k / (N - 1), k % (N - 1));
            net.cell_shear(i, j).map(|_| CHANGE_STEP * (i as f64 - j as f64))
        })
        .collect();
    mech.meta.change_from_kinematic =
        Some(drape::kinematic::CellChanges { shear_deg: change.clone(), warp_angle_deg: change });
    mech.meta.material = Some("materials/glass-plain-weave.toml".into());
    write_net(&net, dir, &[Format::Json]).unwrap();
    write_net(&mech, dir, &[Format::Json]).unwrap();
    (net, mech)
}

/// Decode a PNG: (width, height, RGB pixels).
fn decode(path: &Path) -> (u32, u32, Vec<[u8; 3]>) {
    let dec = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let mut r = dec.read_info().unwrap_or_else(|e| panic!("{} is not a PNG: {e}", path.display()));
    let mut buf = vec![0; r.output_buffer_size()];
    let info = r.next_frame(&mut buf).unwrap();
    assert_eq!(info.color_type, png::ColorType::Rgb, "{}", path.display());
    let px = buf[..info.buffer_size()].chunks(3).map(|c| [c[0], c[1], c[2]]).collect();
    (info.width, info.height, px)
}

/// A decoded picture must have the report's size, not be blank, and contain dark text pixels.
fn check_picture(path: &Path) -> HashMap<[u8; 3], usize> {
    let (w, h, px) = decode(path);
    assert_eq!((w, h), (WIDTH, HEIGHT), "{}", path.display());
    let mut hist: HashMap<[u8; 3], usize> = HashMap::new();
    for p in &px {
        *hist.entry(*p).or_default() += 1;
    }
    let white = hist.get(&WHITE).copied().unwrap_or(0);
    assert!(white < px.len() * 9 / 10, "{}: {white} of {} pixels are background", path.display(), px.len());
    assert!(hist.len() > 30, "{}: only {} distinct colours", path.display(), hist.len());
    // Text (titles, ticks) is drawn in black with anti-aliasing.
    let dark = px.iter().filter(|p| p.iter().all(|&c| c < 60)).count();
    assert!(dark > 1000, "{}: only {dark} near-black pixels: no text or axes", path.display());
    hist
}

/// At least MIN_COLOURS_FOUND of the distinct colours in `expected` occur in the picture.
fn assert_colours(hist: &HashMap<[u8; 3], usize>, expected: &HashSet<[u8; 3]>, what: &str) {
    assert!(expected.len() > 5, "{what}: too few expected colours ({})", expected.len());
    let found = expected.iter().filter(|c| hist.contains_key(*c)).count();
    eprintln!("{what}: {found} of {} expected colours found", expected.len());
    assert!(
        found as f64 >= MIN_COLOURS_FOUND * expected.len() as f64,
        "{what}: only {found} of {} expected colours are in the picture",
        expected.len()
    );
}

/// Pixels painted in the tool's greys (anti-aliased text adds a few).
fn tool_pixels(hist: &HashMap<[u8; 3], usize>) -> usize {
    tool_greys().iter().map(|&g| hist.get(&[g, g, g]).copied().unwrap_or(0)).sum()
}

fn cell_shears_deg(net: &DrapeNet) -> Vec<f64> {
    let mut v = Vec::new();
    for i in 0..net.nu - 1 {
        for j in 0..net.nv - 1 {
            if let Some(g) = net.cell_shear(i, j) {
                v.push(g.to_degrees());
            }
        }
    }
    v
}

fn check_svg(path: &Path, min_polygons: usize) {
    let s = std::fs::read_to_string(path).unwrap();
    let t = s.trim();
    assert!(t.starts_with("<svg") && t.ends_with("</svg>"), "{}: not an SVG document", path.display());
    assert_eq!(
        s.matches("<text").count(),
        s.matches("</text>").count(),
        "{}: unbalanced text elements",
        path.display()
    );
    let shapes = s.matches("<polygon").count() + s.matches("<rect").count();
    assert!(shapes >= min_polygons, "{}: {shapes} shapes, expected at least {min_polygons}", path.display());
    assert!(!s.contains("NaN"), "{}", path.display());
}

fn names(files: &[PathBuf]) -> Vec<String> {
    files.iter().map(|f| f.file_name().unwrap().to_string_lossy().into_owned()).collect()
}

#[test]
fn report_draws_every_ply_and_the_page_shows_them() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    // 2304 triangles: the tool is drawn triangle by triangle.
    let (net, _mech) = make_run(dir, 24);
    let out = dir.join("report");
    let summary = write_report(dir, &out, false).unwrap();
    assert_eq!(
        names(&summary.files),
        [
            "p0-shear.png",
            "p0-shear.svg",
            "p0-histogram.png",
            "p0-histogram.svg",
            "p0mech-shear.png",
            "p0mech-shear.svg",
            "p0mech-histogram.png",
            "p0mech-histogram.svg",
            "p0mech-change.png",
            "p0mech-change.svg",
            "index.html"
        ]
    );
    assert!(summary.files.iter().all(|f| f.is_file() && f.starts_with(&out)));
    // Without layup.json or a card the kinematic ply is judged against the default, and the
    // report says so.
    assert_eq!(
        summary.notes,
        ["ply 'p0': neither layup.json nor a material card gives a locking angle: judged against the default 45°"]
    );

    let shears = cell_shears_deg(&net);
    let max = shears.iter().fold(0.0f64, |m, g| m.max(g.abs()));
    assert!(max > 10.0, "the hemisphere must shear the ply, max {max}");
    let p = &summary.plies[0];
    assert_eq!((p.name.as_str(), p.cells, p.locking_angle_deg), ("p0", shears.len(), 45.0));
    assert!(p.tool_drawn);
    assert!((p.max_abs_shear_deg - max).abs() < 1e-9);
    let limit = colour_limit(max, 45.0);
    assert_eq!(p.colour_limit_deg, limit);

    // Shear map: the cells' colours, the tool's greys, and both ends of the colour bar.
    let hist = check_picture(&out.join("p0-shear.png"));
    let expected: HashSet<[u8; 3]> = shears.iter().map(|g| shear_colour(*g, limit)).collect();
    assert_colours(&hist, &expected, "p0-shear.png cells");
    let greys = tool_pixels(&hist);
    assert!(greys > MIN_TOOL_PIXELS, "the tool is missing: {greys} pixels in its greys");
    // The colour bar reaches both ends of the map (within a few levels: it is drawn in steps).
    for end in [limit, -limit] {
        let c = shear_colour(end, limit);
        let near = |p: &[u8; 3]| (0..3).all(|k| (p[k] as i32 - c[k] as i32).abs() <= 4);
        assert!(hist.keys().any(near), "colour bar end {end} ({c:?}) missing");
    }
    // Signed: both signs of shear are present on a hemisphere and must show.
    assert!(shears.iter().any(|g| *g > 5.0) && shears.iter().any(|g| *g < -5.0));

    // Histogram: the colours of the fuller bins.
    let hist = check_picture(&out.join("p0-histogram.png"));
    let bin = bin_width(limit);
    let shares = bin_shares(&shears, limit, bin);
    let expected: HashSet<[u8; 3]> = shares
        .iter()
        .enumerate()
        .filter(|(_, s)| **s > 0.5)
        .map(|(k, _)| shear_colour(-limit + (k as f64 + 0.5) * bin, limit))
        .collect();
    assert_colours(&hist, &expected, "p0-histogram.png bars");

    // Change map of the mechanical ply: the known change pattern's colours, changes within the
    // noise floor (the facets of this 2304-triangle hemisphere against 7 mm cells; a smooth
    // change has no scatter) drawn as none.
    let hist = check_picture(&out.join("p0mech-change.png"));
    let noise = summary.plies[1].change_noise.unwrap();
    let facets = noise.facets_deg.unwrap();
    assert!(noise.scatter_deg < 1e-9 && noise.floor_deg == facets, "{noise:?}");
    // Facets about 8 mm across on R = 0.1 m: a sagitta of about 1e-4 m, 0.9 deg over 7 mm cells.
    assert!(facets > 0.6 && facets < 1.2, "{noise:?}");
    let changes: Vec<f64> = (0..net.num_cells())
        .filter(|k| net.cell_shear(k / (N - 1), k % (N - 1)).is_some())
        .map(|k| CHANGE_STEP * ((k / (N - 1)) as f64 - (k % (N - 1)) as f64))
        .collect();
    let climit = change_limit(changes.iter().fold(0.0f64, |m, g| m.max(g.abs())));
    let shown = |g: f64| if g.abs() <= noise.floor_deg { 0.0 } else { g };
    let expected: HashSet<[u8; 3]> = changes.iter().map(|g| shear_colour(shown(*g), climit)).collect();
    assert_colours(&hist, &expected, "p0mech-change.png cells");

    for f in ["p0-shear.svg", "p0mech-shear.svg", "p0mech-change.svg"] {
        check_svg(&out.join(f), shears.len() / 2);
    }
    check_svg(&out.join("p0-histogram.svg"), 10);

    // The page: every picture, one table row per ply, in order.
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    for f in summary.files.iter().filter(|f| f.extension().unwrap() != "html") {
        let n = f.file_name().unwrap().to_str().unwrap();
        let needle = if n.ends_with(".png") { format!("<img src=\"{n}\"") } else { format!("href=\"{n}\"") };
        assert!(html.contains(&needle), "index.html does not show {n}");
    }
    let rows: Vec<&str> = html.split("<tr class=\"ply\">").skip(1).collect();
    assert_eq!(rows.len(), 2);
    assert!(rows[0].contains(">p0<") && rows[1].contains(">p0mech<"));
    assert!(rows[1].contains("mechanical") && rows[1].contains("glass-plain-weave"));
    assert!(html.contains("computed from the nets"));
    assert!(!html.contains("NaN"));

    // Deterministic: a second report is byte-identical.
    let again = dir.join("again");
    write_report(dir, &again, false).unwrap();
    for f in ["p0-shear.png", "p0mech-change.svg", "index.html"] {
        assert_eq!(
            std::fs::read(out.join(f)).unwrap(),
            std::fs::read(again.join(f)).unwrap(),
            "{f} differs between runs"
        );
    }
}

#[test]
fn layup_file_patterns_large_tool_and_missing_tool() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    // 8100 triangles: above the limit, the tool is rasterised.
    const { assert!(4 * 45 * 45 > drape::report::TOOL_TRIANGLE_LIMIT) };
    let (net, _) = make_run(dir, 45);
    // A third ply whose tool cannot be found.
    let mut lost = net.clone();
    lost.name = "lost".into();
    lost.meta.tool = Some("nowhere/missing.obj".into());
    write_net(&lost, dir, &[Format::Json]).unwrap();
    // A net of another run or command that layup.json does not list: left out.
    let mut stray = net.clone();
    stray.name = "stray".into();
    write_net(&stray, dir, &[Format::Json]).unwrap();
    let layup = serde_json::json!({
        "scene": "hemi.toml", "tool": "tool.obj",
        "plies": [
            {"name": "p0mech", "material": "glass.toml", "angle_deg": 45.0, "method": "mechanical", "locking_angle_deg": 40.0,
             "max_abs_shear_deg": 30.0, "mean_abs_shear_deg": 10.0, "area_over_locking_m2": 0.0, "coverage": 0.9,
             "draped_area_m2": 0.04, "offset_m": 0.0005},
            {"name": "p0", "material": null, "angle_deg": 0.0, "method": "kinematic", "locking_angle_deg": 50.0,
             "max_abs_shear_deg": 30.0, "mean_abs_shear_deg": 10.0, "area_over_locking_m2": 0.0, "coverage": 1.0,
             "draped_area_m2": 0.04, "offset_m": 0.0},
            {"name": "ghost", "material": null, "angle_deg": 90.0, "method": "kinematic", "locking_angle_deg": 45.0,
             "max_abs_shear_deg": null, "mean_abs_shear_deg": null, "area_over_locking_m2": null, "coverage": null,
             "draped_area_m2": null, "offset_m": null},
            {"name": "lost", "method": "kinematic"}
        ],
        "nesting": {"roll_width_m": 1.2, "length_m": 0.5, "used_area_m2": 0.6, "pattern_area_m2": 0.45, "waste_fraction": 0.25}
    });
    std::fs::write(dir.join("layup.json"), serde_json::to_string_pretty(&layup).unwrap()).unwrap();
    std::fs::write(dir.join("patterns.svg"), "<?xml version=\"1.0\"?>\n<svg xmlns=\"http://www.w3.org/2000/svg\" id=\"pattern-marker\"><path d=\"M0 0 L1 1\"/></svg>\n").unwrap();

    let out = dir.join("pictures");
    let s = write_report(dir, &out, false).unwrap();
    let order: Vec<&str> = s.plies.iter().map(|p| p.name.as_str()).collect();
    assert_eq!(order, ["p0mech", "p0", "lost"], "the layup's plies in its order, the unlisted net left out");
    assert!(s.notes.iter().any(|n| n.contains("stray.drape.json") && n.contains("not drawn")), "{:?}", s.notes);
    assert!(!out.join("stray-shear.png").exists());
    assert_eq!(s.plies[0].locking_angle_deg, 40.0);
    assert_eq!(s.plies[1].locking_angle_deg, 50.0);
    assert_eq!(s.plies[2].locking_angle_deg, 45.0, "default for a ply the layup gives no locking angle");
    assert!(s.plies[0].tool_drawn && s.plies[1].tool_drawn && !s.plies[2].tool_drawn);
    assert!(s.notes.iter().any(|n| n.contains("ghost")), "{:?}", s.notes);
    assert!(s.notes.iter().any(|n| n.contains("lost") && n.contains("missing.obj")), "{:?}", s.notes);

    // The rasterised tool still shows its greys; the lost ply still has its cells.
    let hist = check_picture(&out.join("p0-shear.png"));
    let greys = tool_pixels(&hist);
    assert!(greys > MIN_TOOL_PIXELS, "rasterised tool missing: {greys} pixels in its greys");
    let shears = cell_shears_deg(&net);
    let max = shears.iter().fold(0.0f64, |m, g| m.max(g.abs()));
    let expected: HashSet<[u8; 3]> = shears.iter().map(|g| shear_colour(*g, colour_limit(max, 45.0))).collect();
    let lost_hist = check_picture(&out.join("lost-shear.png"));
    assert_colours(&lost_hist, &expected, "lost-shear.png cells");
    let greys = tool_pixels(&lost_hist);
    assert!(greys < MIN_TOOL_PIXELS / 10, "no tool should be drawn for 'lost', yet {greys} pixels are in its greys");

    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    let rows: Vec<&str> = html.split("<tr class=\"ply\">").skip(1).collect();
    assert_eq!(rows.len(), 3, "one row per drawn ply");
    assert!(rows[0].contains(">p0mech<") && rows[0].contains(">45.0<") && rows[0].contains(">0.50<"), "{}", rows[0]);
    assert!(rows[1].contains(">p0<") && rows[2].contains(">lost<"));
    assert!(html.contains("from layup.json") && html.contains("Drape report: hemi.toml"));
    assert!(html.contains("id=\"pattern-marker\"") && !html.contains("<?xml"), "patterns.svg is shown inline");
    assert!(html.contains("25.0%"), "nesting waste shown");
    assert!(html.contains("missing.obj"), "the page says the tool could not be drawn");

    // A report written into the run folder itself, twice: its own SVGs are not flat patterns.
    write_report(dir, dir, false).unwrap();
    write_report(dir, dir, false).unwrap();
    let html = std::fs::read_to_string(dir.join("index.html")).unwrap();
    assert_eq!(html.matches("<div class=\"pattern\">").count(), 1, "only patterns.svg is a pattern");
}

#[test]
fn errors_name_the_folder() {
    let tmp = tempfile::tempdir().unwrap();
    let e = write_report(tmp.path(), &tmp.path().join("r"), false).unwrap_err();
    assert!(matches!(e, ReportError::NoNets { .. }), "{e}");
    assert!(e.to_string().contains(&tmp.path().display().to_string()));
    assert!(!tmp.path().join("r").exists(), "nothing written");
    make_run(tmp.path(), 8);
    std::fs::write(tmp.path().join("layup.json"), "{\"plies\": [").unwrap();
    let e = write_report(tmp.path(), &tmp.path().join("r"), false).unwrap_err().to_string();
    assert!(e.contains("layup.json") && e.contains("line"), "{e}");
}

#[test]
fn cli_report() {
    let tmp = tempfile::tempdir().unwrap();
    make_run(tmp.path(), 16);
    let out = tmp.path().join("cli-out");
    let a = assert_cmd::Command::cargo_bin("drape")
        .unwrap()
        .args(["report", tmp.path().to_str().unwrap(), "--out", out.to_str().unwrap()])
        .assert()
        .success();
    let stdout = String::from_utf8_lossy(&a.get_output().stdout).to_string();
    assert!(stdout.contains("ply p0:") && stdout.contains("wrote 11 files"), "{stdout}");
    assert!(out.join("index.html").is_file() && out.join("p0mech-change.png").is_file());
    // Bad input: exit code 2 and a message naming the folder.
    let empty = tmp.path().join("empty");
    std::fs::create_dir(&empty).unwrap();
    let a = assert_cmd::Command::cargo_bin("drape").unwrap().args(["report", empty.to_str().unwrap()]).assert().code(2);
    let err = String::from_utf8_lossy(&a.get_output().stderr).to_string();
    assert!(err.contains("no drape net") && err.contains("empty"), "{err}");
}

/// A run whose tool is an Abaqus deck (or any shell mesh a tool may be) draws its tool: the
/// report reads tools as the drape does, not only from OBJ. The plate deck is in millimetres
/// and the net records that scale.
#[test]
fn a_tool_given_as_a_shell_mesh_is_drawn_at_the_scale_the_run_read_it() {
    let tmp = tempfile::tempdir().unwrap();
    let deck = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/flowmesh/plate.inp");
    let scale = 1e-3;
    let tool = drape::io::read_tool(&deck, scale).unwrap();
    let origin = Point::new(50.0, 75.0, 0.0) * scale;
    let mut net = drape(&tool, &KinematicSettings::grid("deck", origin, Vector::x(), 5.0 * scale, 11, 11)).unwrap();
    net.meta.tool = Some(deck.display().to_string());
    net.meta.tool_scale = Some(scale);
    write_net(&net, tmp.path(), &[Format::Json]).unwrap();
    let s = write_report(tmp.path(), &tmp.path().join("r"), false).unwrap();
    assert!(s.plies[0].tool_drawn, "{:?}", s.notes);
    let hist = check_picture(&tmp.path().join("r/deck-shear.png"));
    assert!(tool_pixels(&hist) > MIN_TOOL_PIXELS, "the plate is drawn around the ply");
}
