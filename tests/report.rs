//! `drape report`: pictures are looked at, not only written. A real kinematic drape on a
//! hemisphere plus a mechanical copy carrying a known per-cell change, a flat ply on a plate and
//! a ply on a hat box; the PNGs are decoded and must show shading (many levels across a ply of
//! one colour), fibre lines, the tool, both signs of a change, text; one colour scale for all
//! plies; views that see the hat box's walls; the page must show every picture.
use drape::geometry::{shapes, Point, Vector};
use drape::io::{write_net, Format};
use drape::kinematic::provenance::Stability;
use drape::kinematic::{drape, DrapeNet, KinematicSettings, Method};
use drape::report::{bin_shares, bin_width, colour_limit, shear_colour, write_report, ReportError, HEIGHT, WIDTH};
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
/// Pixels of the tool's slate grey when the tool is drawn (the visible rim of the hemisphere).
const MIN_TOOL_PIXELS: usize = 5000;
/// Width of the legend column on the right of a shaded picture.
const LEGEND_COLUMN: u32 = 240;
/// Height of a shaded picture's title and subtitle band, pixels.
const TITLE_BAND: u32 = 66;

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
    // The kinematic net the mechanical copy "started from", as `drape run` keeps it.
    drape::io::write_json(&net, &drape::io::kinematic_net_path(dir, "p0mech")).unwrap();
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

/// Whether a pixel is the tool's slate grey (150, 154, 160), lit: bluer than red by a little,
/// green 0.4 of the way (text, frames and the page are pure greys, the ply is coloured).
fn is_tool(p: &[u8; 3]) -> bool {
    let (r, g, b) = (p[0] as i32, p[1] as i32, p[2] as i32);
    (3..=11).contains(&(b - r)) && (2 * (g - r) - (b - r)).abs() <= 2 && (70..=245).contains(&r)
}

/// Pixels painted in the tool's shaded grey.
fn tool_pixels(hist: &HashMap<[u8; 3], usize>) -> usize {
    hist.iter().filter(|(c, _)| is_tool(c)).map(|(_, n)| n).sum()
}

/// Pixels of the map area (left of the legend column) of a decoded picture, row by row.
fn map_rows(path: &Path) -> Vec<Vec<[u8; 3]>> {
    let (w, _, px) = decode(path);
    px.chunks(w as usize).map(|row| row[..(w - LEGEND_COLUMN) as usize].to_vec()).collect()
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
            "p0-histogram.png",
            "p0-histogram.svg",
            "p0mech-shear.png",
            "p0mech-kinematic.png",
            "p0mech-histogram.png",
            "p0mech-histogram.svg",
            "p0mech-change.png",
            "p0mech-change-histogram.png",
            "p0mech-change-histogram.svg",
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
    // One colour scale for the layup: the larger locking angle of the two plies and the shear.
    let lock = summary.plies.iter().map(|p| p.locking_angle_deg).fold(0.0, f64::max);
    let limit = colour_limit(max, lock);
    assert!(summary.plies.iter().all(|p| p.colour_limit_deg == limit), "{:?}", summary.plies);
    assert_eq!(p.seen_share, 1.0, "the views show every cell of a hemisphere cap: {:?}", p.views);
    assert!(p.views[0].starts_with("isometric"), "{:?}", p.views);

    // Shear map: the tool, and both ends of the colour bar.
    let hist = check_picture(&out.join("p0-shear.png"));
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

    // Change map of the mechanical ply: the known change runs from -CHANGE_STEP * 29 to
    // +CHANGE_STEP * 29 across the diagonal, well above the noise floor (the facets of this
    // 2304-triangle hemisphere against 7 mm cells; a smooth change has no scatter): both its
    // blue and its red half show.
    check_picture(&out.join("p0mech-change.png"));
    let noise = summary.plies[1].change_noise.unwrap();
    let facets = noise.facets_deg.unwrap();
    assert!(noise.scatter_deg < 1e-9 && noise.floor_deg == facets, "{noise:?}");
    // Facets about 8 mm across on R = 0.1 m: a sagitta of about 1e-4 m, 0.9 deg over 7 mm cells.
    assert!(facets > 0.6 && facets < 1.2, "{noise:?}");
    let rows = map_rows(&out.join("p0mech-change.png"));
    let count = |f: &dyn Fn(i32, i32, i32) -> bool| {
        rows.iter().flatten().filter(|p| f(p[0] as i32, p[1] as i32, p[2] as i32)).count()
    };
    let (red, blue) = (count(&|r, g, _| r > g + 60), count(&|r, _, b| b > r + 30));
    assert!(red > 5000 && blue > 5000, "change map: {red} red and {blue} blue pixels");
    // Its figures: the known change is CHANGE_STEP (i - j), largest at a corner of the grid.
    let c = summary.plies[1].change.unwrap();
    let (i, j) = c.largest_cell;
    assert!((c.largest_deg - CHANGE_STEP * (i as f64 - j as f64)).abs() < 1e-9, "{c:?}");
    assert!(c.largest_deg.abs() > 4.0 && c.mean_abs_deg > 1.0, "{c:?}");
    check_picture(&out.join("p0mech-change-histogram.png"));

    // Kinematic against mechanical: the kinematic start is drawn from the mechanical ply's views
    // and window on the layup's scale. The mechanical copy has the kinematic net's nodes, so the
    // two pictures are the same below the title band (the titles differ); its figures are p0's.
    let k = summary.plies[1].kinematic.expect("p0mech's kinematic net is beside it");
    assert_eq!((k.cells, k.max_abs_shear_deg), (p.cells, p.max_abs_shear_deg));
    assert_eq!(summary.plies[1].views, p.views);
    assert!(summary.plies[0].kinematic.is_none(), "a kinematic ply has no side by side");
    let (_, _, a) = decode(&out.join("p0mech-shear.png"));
    let (_, _, b) = decode(&out.join("p0mech-kinematic.png"));
    let below_title = TITLE_BAND as usize * WIDTH as usize;
    let differ = a[below_title..].iter().zip(&b[below_title..]).filter(|(x, y)| x != y).count();
    assert!(
        differ * 1000 < a.len(),
        "p0mech-kinematic.png differs from p0mech-shear.png in {differ} pixels below the title"
    );
    let differ_all = a.iter().zip(&b).filter(|(x, y)| x != y).count();
    assert!(differ_all > 500, "the titles differ: {differ_all} pixels");

    check_svg(&out.join("p0-histogram.svg"), 10);

    // The page: every picture, one table row per ply, in order.
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    for f in summary.files.iter().filter(|f| f.extension().unwrap() != "html") {
        let n = f.file_name().unwrap().to_str().unwrap();
        let needle = if n.ends_with(".png") { format!("src=\"{n}\"") } else { format!("href=\"{n}\"") };
        assert!(html.contains(&needle), "index.html does not show {n}");
    }
    let rows: Vec<&str> = html.split("<tr class=\"ply\">").skip(1).collect();
    assert_eq!(rows.len(), 2);
    assert!(rows[0].contains(">p0<") && rows[1].contains(">p0mech<"));
    assert!(rows[1].contains("mechanical") && rows[1].contains("glass-plain-weave"));
    assert!(html.contains("computed from the nets"));
    assert!(!html.contains("NaN"));
    // The side-by-side section: two pictures, then the difference map and its histogram.
    let compare =
        html.split("<section class=\"compare\" id=\"compare-p0mech\">").nth(1).expect("side by side of p0mech");
    let compare = &compare[..compare.find("</section>").unwrap()];
    let pictures: Vec<&str> = compare.split("<img src=\"").skip(1).map(|s| &s[..s.find('"').unwrap()]).collect();
    assert_eq!(
        pictures,
        ["p0mech-kinematic.png", "p0mech-shear.png", "p0mech-change.png", "p0mech-change-histogram.png"]
    );
    assert!(compare.contains(&format!("{:+.2}°", c.largest_deg)), "the largest change is named: {compare}");
    assert_eq!(html.matches("class=\"compare\"").count(), 1, "p0 is kinematic: no side by side");

    // Deterministic: a second report is byte-identical.
    let again = dir.join("again");
    write_report(dir, &again, false).unwrap();
    for f in ["p0-shear.png", "p0mech-change.png", "index.html"] {
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
    // 8100 triangles.
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

    // The tool shows; the lost ply still has its cells, without a tool.
    let hist = check_picture(&out.join("p0-shear.png"));
    let tool_greys = tool_pixels(&hist);
    assert!(tool_greys > MIN_TOOL_PIXELS, "tool missing: {tool_greys} pixels in its greys");
    let lost_hist = check_picture(&out.join("lost-shear.png"));
    let coloured: usize = lost_hist.iter().filter(|(c, _)| c[0] as i32 - c[2] as i32 > 40).map(|(_, n)| n).sum();
    assert!(coloured > 20_000, "lost-shear.png: only {coloured} pixels of the ply's warm colours");
    let greys = tool_pixels(&lost_hist);
    assert!(greys * 10 < tool_greys, "no tool should be drawn for 'lost', yet {greys} pixels are in its greys");

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
    let tool = tool_pixels(&hist);
    assert!(tool > MIN_TOOL_PIXELS, "the plate is drawn around the ply: {tool} pixels");
}

/// A flat ply on a plate (no shear: one colour everywhere) next to a sheared ply on a
/// hemisphere, in one run folder. Returns the flat net.
fn make_flat_and_curved(dir: &Path) -> DrapeNet {
    make_run(dir, 16);
    std::fs::remove_file(dir.join("p0mech.drape.json")).unwrap();
    let mesh = shapes::plate(0.3, 0.24, 30, 24);
    let obj = dir.join("plate.obj");
    std::fs::write(&obj, mesh.to_obj_string()).unwrap();
    let tool = mesh.into_surface().unwrap();
    let mut flat =
        drape(&tool, &KinematicSettings::grid("flat", Point::new(0.0, 0.0, 0.0), Vector::x(), 0.005, 41, 33)).unwrap();
    flat.meta.tool = Some(obj.display().to_string());
    write_net(&flat, dir, &[Format::Json]).unwrap();
    flat
}

/// Pixels of the flat ply's one colour (the zero of the map), lit: warm, yellow, never grey.
fn is_ply_cream(p: &[u8; 3]) -> bool {
    let (r, g, b) = (p[0] as i32, p[1] as i32, p[2] as i32);
    r > b + 20 && g > b + 15 && (r - g).abs() < 25
}

/// A ply of one colour is shaded (its pixels take many brightness levels across it, where a
/// flat fill has one), stands out from the tool, carries fibre lines, and shares the colour
/// scale of the sheared ply beside it.
#[test]
fn report_shades_a_flat_ply_draws_its_fibres_and_shares_one_scale() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let flat = make_flat_and_curved(dir);
    let out = dir.join("r");
    let s = write_report(dir, &out, false).unwrap();
    let [flat_ply, curved] = [&s.plies[0], &s.plies[1]];
    assert_eq!((flat_ply.name.as_str(), curved.name.as_str()), ("flat", "p0"));
    assert!(flat_ply.max_abs_shear_deg < 1e-6 && curved.max_abs_shear_deg > 10.0);
    assert_eq!(flat_ply.colour_limit_deg, curved.colour_limit_deg, "one colour scale for the layup");
    assert_eq!(flat_ply.views.len(), 1, "one isometric view shows a flat ply: {:?}", flat_ply.views);

    let rows = map_rows(&out.join("flat-shear.png"));
    let cream: Vec<&[u8; 3]> = rows.iter().flatten().filter(|p| is_ply_cream(p)).collect();
    assert!(cream.len() > 60_000, "the flat ply covers the view: {} pixels", cream.len());
    // Shading: brightness spreads across the ply (a flat fill would sit at one level).
    let mut lum: Vec<i32> = cream.iter().map(|p| p[0] as i32 + p[1] as i32 + p[2] as i32).collect();
    lum.sort();
    let (p10, p90) = (lum[lum.len() / 10], lum[lum.len() * 9 / 10]);
    let levels: HashSet<i32> = lum.iter().copied().collect();
    eprintln!("flat ply: {} levels, 10-90% brightness {p10}..{p90}", levels.len());
    assert!(levels.len() > 60 && p90 - p10 > 25, "{} levels, 10-90% {p10}..{p90}: not shaded", levels.len());
    // Stands out: the ply's colour is far from the tool's grey, and the tool shows around it.
    let tool: usize = rows.iter().flatten().filter(|p| is_tool(p)).count();
    assert!(tool > 3000, "the plate around the ply: {tool} pixels");
    // Fibre lines: along the middle row of the ply, dark lines cross it again and again, at the
    // drawn step (every k-th fibre of 41 x 33).
    let dark = |p: &[u8; 3]| p.iter().all(|&c| c < 120);
    let (mut best, mut best_row) = (0, 0);
    for (y, row) in rows.iter().enumerate() {
        let crossings = row.windows(2).filter(|w| is_ply_cream(&w[0]) && dark(&w[1])).count();
        if crossings > best {
            (best, best_row) = (crossings, y);
        }
    }
    let k = flat_ply.fibre_step;
    assert!(k >= 1, "fibre lines drawn");
    let lines = (flat.nu + flat.nv) / k;
    eprintln!("flat ply: every {k}th fibre, {best} line crossings on row {best_row}");
    assert!(best >= lines / 3, "only {best} fibre-line crossings on any row, expected about {lines} lines");
}

/// On a hat box, the isometric view sees the top and two walls edge-on or not at all; the
/// report adds views until every cell is seen from in front.
#[test]
fn report_views_see_every_wall_of_a_hat_box() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let mesh = shapes::hat_box(&shapes::HatBox::standard(), 0.008, 3);
    let obj = dir.join("hat.obj");
    std::fs::write(&obj, mesh.to_obj_string()).unwrap();
    let tool = mesh.into_surface().unwrap();
    let top = Point::new(0.0, 0.0, shapes::HatBox::standard().height);
    let mut net = drape(&tool, &KinematicSettings::grid("hat", top, Vector::x(), 0.008, 41, 41)).unwrap();
    net.meta.tool = Some(obj.display().to_string());
    write_net(&net, dir, &[Format::Json]).unwrap();
    let s = write_report(dir, &dir.join("r"), false).unwrap();
    let p = &s.plies[0];
    eprintln!("hat box views: {:?}, {:.4} seen", p.views, p.seen_share);
    assert!(p.views.len() >= 2, "the walls the first view hides need more views: {:?}", p.views);
    assert!(p.seen_share > 0.995, "{:.4} of the cells seen in {:?}", p.seen_share, p.views);
    // The net stops at the corners: the report says where and why.
    let stopped: usize = p.stops.iter().map(|(_, n)| n).sum();
    assert!(stopped > 0, "{:?}", p.stops);
    check_picture(&dir.join("r/hat-shear.png"));
    // The page says what each status means.
    let html = std::fs::read_to_string(dir.join("r/index.html")).unwrap();
    let (status, _) = p.stops[0];
    assert!(html.contains("id=\"statuses\"") && html.contains(drape::report::status_meaning(status)), "status table");
}

/// What headless Chromium saw of a report page (tools/report_browser.py).
fn browse(index: &Path, shot: &Path) -> serde_json::Value {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tools/report_browser.py");
    let run = std::process::Command::new("python3")
        .arg(&script)
        .arg(index)
        .arg(shot)
        .output()
        .expect("python3 must run tools/report_browser.py (tools/run-tests installs its requirements)");
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(
        run.status.success(),
        "tools/report_browser.py failed ({}): {stdout}\n{}\nChromium and the Python requirements are installed by tools/run-tests.",
        run.status,
        String::from_utf8_lossy(&run.stderr)
    );
    serde_json::from_str(stdout.trim()).unwrap()
}

/// The page as a person sees it: headless Chromium (installed by tools/run-tests) opens
/// index.html with every host name unresolvable; the page must load with no console error and
/// no request beyond local files, every picture must load, the 3D view must draw the part (a
/// screenshot with the part over a sizable area, in many colours), turn when dragged, and name
/// the cell under the pointer; the page must stay a readable length.
#[test]
fn report_page_in_chromium() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    make_flat_and_curved(dir);
    let out = dir.join("r");
    write_report(dir, &out, false).unwrap();
    let seen = browse(&out.join("index.html"), &dir.join("view.png"));
    eprintln!("chromium saw: {seen}");
    assert_eq!(seen["loaded"], true);
    assert_eq!(seen["errors"], serde_json::json!([]), "console errors");
    assert_eq!(seen["external_requests"], serde_json::json!([]), "requests beyond local files");
    let images = seen["images"].as_array().unwrap();
    assert!(images.len() >= 4 && images.iter().all(|i| i["loaded"] == true), "{images:?}");
    assert_eq!(seen["plies"], 2);
    assert!(seen["faces"].as_u64().unwrap() > 1000, "the 3D view drew {} faces", seen["faces"]);
    assert!(seen["faces_by_thickness"].as_u64().unwrap() > 0);
    let pick = seen["pick"].as_str().unwrap_or("");
    assert!(pick.starts_with("ply ") && pick.contains("shear"), "under the centre: {pick:?}");
    let shot = &seen["shots"]["initial"];
    assert!(shot["part_share"].as_f64().unwrap() > 0.1, "the part is missing from the 3D view: {shot}");
    assert!(shot["distinct_colours"].as_u64().unwrap() > 100, "a flat or blank 3D view: {shot}");
    assert!(seen["shots"]["changed_share"].as_f64().unwrap() > 0.05, "dragging did not turn the view");
    // Two plies with their pictures, the table, the 3D view: a page, not a scroll of 15,000 px.
    let height = seen["height"].as_u64().unwrap();
    assert!(height < 6000, "the page is {height} px long");
}

/// `drape run` of the bundled four-ply hemisphere scene (the first ply pressed mechanically,
/// the plies mapped onto a 2,116-element flow mesh) and `drape report` of it: the run keeps the
/// mechanical ply's kinematic net beside it and lists it; the page shows the two side by side
/// (its change lies within the solver's noise, so no difference map, said so), no side by side
/// for the kinematic plies, the flow-mesh export from the run's record (the covered counts are
/// those of flow.csv), and in Chromium the four-ply page loads every picture and stays under
/// 7,000 px.
#[test]
fn a_four_ply_run_reports_side_by_side_and_the_flow_mesh() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("run");
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("geometries/hemisphere/scene.toml");
    let run = assert_cmd::Command::cargo_bin("drape")
        .unwrap()
        .args(["run", scene.to_str().unwrap(), "--out", out.to_str().unwrap(), "--format", "json"])
        .assert()
        .success();
    let stdout = String::from_utf8_lossy(&run.get_output().stdout).to_string();
    assert!(out.join("p0.kinematic.json").is_file(), "the mechanical ply's kinematic net is kept");
    for k in ["p45", "p90", "m45"] {
        assert!(!out.join(format!("{k}.kinematic.json")).exists(), "{k} is kinematic");
    }
    let kinematic = drape::io::read_net(&out.join("p0.kinematic.json")).unwrap();
    let refined = drape::io::read_net(&out.join("p0.drape.json")).unwrap();
    assert_eq!((kinematic.method, refined.method), (Method::Kinematic, Method::Mechanical));
    assert_eq!((kinematic.nu, kinematic.nv), (refined.nu, refined.nv));
    // The refined net records its change from this very net: mechanical − kinematic, per cell.
    let change = &refined.meta.change_from_kinematic.as_ref().unwrap().shear_deg;
    for (k, c) in change.iter().enumerate() {
        let (i, j) = (k / (refined.nv - 1), k % (refined.nv - 1));
        if let (Some(c), Some(a), Some(b)) = (c, refined.cell_shear(i, j), kinematic.cell_shear(i, j)) {
            assert!((c - (a - b).to_degrees()).abs() < 1e-4, "cell ({i}, {j}): {c} vs {}", (a - b).to_degrees());
        }
    }
    let layup = drape::report::read_layup(&out).unwrap().unwrap();
    assert!(layup.files.contains(&"p0.kinematic.json".to_string()), "{:?}", layup.files);
    // The pressed p0, held on the tool by the glass card's friction (0.25), converges to a
    // minimum (frictionless and pinned at its seed it was a shallow saddle: the ply could twist
    // about the pin): said in the row, the net and the report, with how it meets the tool.
    assert_eq!(layup.plies[0].stability, Some(Stability::Minimum), "{:?}", layup.plies[0]);
    assert_eq!(refined.meta.solver.as_ref().unwrap().stability, Some(Stability::Minimum));
    let row = stdout.lines().find(|l| l.starts_with("p0 ")).expect("the layup table's p0 row");
    assert!(row.contains("mechanical") && !row.contains("saddle"), "{row}");
    assert!(!stdout.contains("UNSTABLE:"), "{stdout}");
    let contact = layup.plies[0].contact.as_ref().expect("the mechanical ply's contact in layup.json");
    assert_eq!(contact.friction, 0.25);
    assert!(contact.stick > 1000 && contact.held == 0, "{contact:?}");
    assert!(stdout.contains("contact: ply 'p0': friction 0.25: "), "{stdout}");
    assert!(layup.plies[1..].iter().all(|p| p.contact.is_none()), "kinematic plies have no contact record");
    assert!(layup.plies[1..].iter().all(|p| p.stability.is_none()), "kinematic plies are not checked");
    // The export record: the mesh, its size, the formats and each ply's covered elements, as
    // flow.csv (one row an element and ply) has them.
    let e = layup.export.as_ref().expect("the scene exports onto a flow mesh");
    assert!(e.mesh.ends_with("hemisphere-2k.obj"), "{}", e.mesh);
    assert_eq!((e.elements, e.formats.clone()), (2116, vec!["vtu".to_string(), "csv".to_string()]));
    assert_eq!(e.files, ["flow.vtu", "flow.csv"]);
    let csv = std::fs::read_to_string(out.join("flow.csv")).unwrap();
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let (ply_col, covered_col) =
        (header.iter().position(|h| *h == "ply").unwrap(), header.iter().position(|h| *h == "covered").unwrap());
    let names: Vec<&str> = e.plies.iter().map(|p| p.name.as_str()).collect();
    assert_eq!(names, ["p0", "p45", "p90", "m45"]);
    for p in &e.plies {
        let covered = csv
            .lines()
            .skip(1)
            .map(|l| l.split(',').collect::<Vec<_>>())
            .filter(|f| f[ply_col] == p.name && matches!(f[covered_col], "1" | "true"))
            .count();
        assert_eq!(p.covered, covered, "ply {}", p.name);
        assert!(covered > 1900 && p.share == covered as f64 / 2116.0, "{p:?}");
    }

    let report = out.join("report");
    let s = write_report(&out, &report, false).unwrap();
    assert!(s.plies[0].kinematic.is_some() && s.plies[1..].iter().all(|p| p.kinematic.is_none()));
    assert!(report.join("p0-kinematic.png").is_file());
    check_picture(&report.join("p0-kinematic.png"));
    let html = std::fs::read_to_string(report.join("index.html")).unwrap();
    assert_eq!(html.matches("<section class=\"compare\"").count(), 1, "only the mechanical ply");
    assert_eq!(html.matches("(unstable: a saddle)").count(), 0);
    // The stick/slip map of the mechanical ply, and only of it.
    assert!(report.join("p0-contact.png").is_file());
    check_picture(&report.join("p0-contact.png"));
    assert!(html.contains("src=\"p0-contact.png\""), "the page shows the stick/slip map");
    assert!(!report.join("p45-contact.png").exists());
    let compare = html.split("id=\"compare-p0\">").nth(1).unwrap();
    let compare = &compare[..compare.find("</section>").unwrap()];
    assert_eq!(compare.matches("<img ").count(), 2, "kinematic and mechanical side by side: {compare}");
    assert!(compare.contains("src=\"p0-kinematic.png\"") && compare.contains("src=\"p0-shear.png\""));
    assert!(compare.contains("within the solver's noise"), "{compare}");
    let export = html.split("id=\"flow-export\"").nth(1).expect("flow-mesh export section");
    let export = &export[..export.find("</table>").unwrap()];
    assert!(export.contains("hemisphere-2k.obj") && export.contains("2116 elements") && export.contains("vtu, csv"));
    for p in &e.plies {
        assert!(export.contains(&format!("{} of 2116", p.covered)), "ply {}: {export}", p.name);
    }

    // The run owns its folder: run again with every ply kinematic and the kept net goes.
    let scenes = tmp.path().join("scene");
    std::fs::create_dir(&scenes).unwrap();
    for f in ["hemisphere-20k.obj", "hemisphere-2k.obj"] {
        std::fs::copy(scene.with_file_name(f), scenes.join(f)).unwrap();
    }
    let text = std::fs::read_to_string(&scene).unwrap();
    assert!(text.contains("method = \"mechanical\""));
    let text = text
        .replace("method = \"mechanical\"", "method = \"kinematic\"")
        .replace("../../materials/", &format!("{}/materials/", env!("CARGO_MANIFEST_DIR")));
    std::fs::write(scenes.join("scene.toml"), text).unwrap();
    let rerun = tmp.path().join("rerun");
    copy_dir(&out, &rerun);
    assert!(rerun.join("p0.kinematic.json").is_file());
    assert_cmd::Command::cargo_bin("drape")
        .unwrap()
        .args([
            "run",
            scenes.join("scene.toml").to_str().unwrap(),
            "--out",
            rerun.to_str().unwrap(),
            "--format",
            "json",
        ])
        .assert()
        .success();
    assert!(!rerun.join("p0.kinematic.json").exists(), "a later run removes the kinematic net it does not write");

    let seen = browse(&report.join("index.html"), &tmp.path().join("view.png"));
    assert_eq!(seen["errors"], serde_json::json!([]), "console errors");
    assert_eq!(seen["plies"], 4);
    let images = seen["images"].as_array().unwrap();
    assert!(images.len() >= 9 && images.iter().all(|i| i["loaded"] == true), "{images:?}");
    // Four plies with their pictures, the side by side, the flow mesh, the patterns and the 3D
    // view: a page, not a scroll of 13,000 px (6,250 px when this was written; each kinematic
    // ply's wrinkle map beside its shear map moves its histogram to a row of its own: 8,184 px).
    let height = seen["height"].as_u64().unwrap();
    eprintln!("four-ply page: {height} px");
    assert!(height < 9000, "the four-ply page is {height} px long");
}

/// Copy the files of folder `from` into a new folder `to`.
fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let p = e.unwrap().path();
        if p.is_file() {
            std::fs::copy(&p, to.join(p.file_name().unwrap())).unwrap();
        }
    }
}
