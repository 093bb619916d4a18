//! Draw-in: how far the blank's edge moves in towards the seed, in plan, against known answers.
use drape::geometry::shapes;
use drape::kinematic::provenance::{DrawIn, DrawInLine};
use std::path::Path;

use crate::common::read_json;

/// Run `scene` (TOML text, the tool written beside it as `tool.obj`) and return the first ply's
/// draw-in from layup.json, the same from its net, and the CLI's output.
fn run(dir: &Path, tool: &drape::geometry::TriangleMesh, scene: &str) -> (DrawIn, DrawIn, String) {
    let (out, stdout) = crate::common::run_scene(dir, &[("tool.obj", tool)], scene);
    let row = &read_json(&out.join("layup.json"))["plies"][0];
    let table: DrawIn = serde_json::from_value(row["draw_in"].clone()).unwrap();
    let name = row["name"].as_str().unwrap();
    let net: DrawIn =
        serde_json::from_value(read_json(&out.join(format!("{name}.drape.json")))["meta"]["draw_in"].clone()).unwrap();
    (table, net, stdout)
}

/// A ply seeded at the pole of a hemisphere of radius R: its fibres through the seed are
/// meridians (geodesics, and the Chebyshev net keeps their length), so a fibre end s out along
/// one lies R sin(s / R) from the axis in plan and draws in s - R sin(s / R). The four fibre ends
/// agree, and so do the four diagonal ends (the net's symmetry), on other radii, reaches and
/// spacings; the facets' error is a small share of the draw-in.
#[test]
fn fibres_over_a_hemisphere_draw_in_by_the_arc_less_its_chord_in_plan() {
    // Relative error allowed against the exact draw-in: the fibre runs on the facets.
    const FACET_SHARE: f64 = 0.01;
    for (r, reach, n) in [(0.1, 0.6, 31), (0.25, 1.2, 41), (0.18, 1.0, 25)] {
        let tmp = tempfile::tempdir().unwrap();
        let s = reach * r;
        let d = s / ((n - 1) / 2) as f64;
        let scene = format!(
            "units = \"m\"\ntool = \"tool.obj\"\n[[ply]]\nname = \"p\"\norigin = [0.0, 0.0, {r}]\nwarp = [1.0, 0.0, 0.0]\nspacing = {d}\ngrid = [{n}, {n}]\nsurface = \"smooth\"\nmax_shear_deg = 89.0\n"
        );
        let (table, net, stdout) = run(tmp.path(), &shapes::hemisphere_with_triangles(r, 20_000), &scene);
        assert_eq!(table, net, "layup.json and the net record one draw-in");
        assert_eq!(table.plan_from, "seed");
        assert!(table.plan_normal[2].abs() > 1.0 - 1e-6, "{:?}", table.plan_normal);
        let exact = s - r * (s / r).sin();
        let fibres: Vec<_> = table.edges.iter().filter(|e| e.line.is_fibre()).collect();
        assert_eq!(fibres.len(), 4, "{table:?}");
        for e in &fibres {
            assert!((e.flat_m - s).abs() < 1e-9 * s, "{e:?}");
            assert!(
                (e.draw_in_m - exact).abs() < FACET_SHARE * exact,
                "R {r}, s {s}: {} draws in {} m, exactly {exact} m",
                e.line.name(),
                e.draw_in_m
            );
        }
        let diagonals: Vec<f64> = table.edges.iter().filter(|e| !e.line.is_fibre()).map(|e| e.draw_in_m).collect();
        assert_eq!(diagonals.len(), 4, "{table:?}");
        let (lo, hi) = diagonals.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), &x| (lo.min(x), hi.max(x)));
        assert!(lo > 0.0 && hi - lo < FACET_SHARE * hi, "R {r}: diagonals {diagonals:?}");
        let largest = table.largest_overall().unwrap();
        assert!(stdout.contains(&format!("{:.2}", largest.draw_in_m * 1e3)), "{stdout}");
        assert!(stdout.contains("draw-in: ply 'p': draw-in along the fibres up to"), "{stdout}");
    }
}

/// A flat sheet dropped onto a plate larger than itself lies where it fell: no draw-in, in the
/// plan of the sheet.
#[test]
fn a_sheet_lying_flat_on_a_plate_draws_in_nothing() {
    // The sheet settles under its weight by its fibres' strain: far below a micrometre here.
    const FLAT_DRAW_IN: f64 = 1e-6;
    let tmp = tempfile::tempdir().unwrap();
    let card = Path::new(env!("CARGO_MANIFEST_DIR")).join("materials/sze-liu-table1.toml");
    let scene = format!(
        "units = \"m\"\ntool = \"tool.obj\"\nfriction = 0.3\n[[ply]]\nname = \"sheet\"\norigin = [0.0, 0.0, 0.0]\nwarp = [1.0, 0.0, 0.0]\nmaterial = {:?}\nspacing = 0.01\ngrid = [21, 15]\nmethod = \"mechanical\"\nmode = \"free\"\nstart = \"flat\"\n",
        card.display().to_string()
    );
    let (table, _, _) = run(tmp.path(), &shapes::plate(0.5, 0.5, 10, 10), &scene);
    assert_eq!(table.plan_from, "sheet");
    assert_eq!(table.edges.len(), 8);
    assert!(table.edges.iter().any(|e| e.line == DrawInLine::MinusPlus));
    for e in &table.edges {
        assert!(e.draw_in_m.abs() < FLAT_DRAW_IN, "{e:?}");
    }
}
