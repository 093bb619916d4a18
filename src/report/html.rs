//! The report page: one self-contained HTML file (inline CSS; pictures linked by file name from
//! the same folder, flat patterns inlined).
use super::{method_name, LayupRow, Page, PlyReport};
use crate::kinematic::provenance::Stability;
use crate::kinematic::DrapeNet;
use crate::layup::flat::CutWarning;
use std::fmt::Write;

/// Escape text for HTML element content and attribute values (the crate's one XML escape).
pub use crate::io::xml::xml_escape as escape;

/// An SVG document without its XML declaration and DOCTYPE, ready to inline in HTML.
pub fn strip_prolog(svg: &str) -> &str {
    svg.find("<svg").map_or(svg, |k| &svg[k..])
}

/// A number with `digits` decimals, or a dash when missing or not finite (never "NaN").
fn num(x: Option<f64>, digits: usize) -> String {
    match x {
        Some(v) if v.is_finite() => format!("{v:.digits$}"),
        _ => "—".into(),
    }
}

/// Facts about a net worth showing next to its pictures.
pub fn net_facts(net: &DrapeNet) -> Vec<(String, String)> {
    let mut f = vec![
        (
            "grid".to_string(),
            format!("{} × {} nodes, origin node ({}, {})", net.nu, net.nv, net.origin_node.0, net.origin_node.1),
        ),
        ("fibre spacing".to_string(), format!("{:.2} mm", net.spacing * 1e3)),
    ];
    let placed = net.status.iter().filter(|s| **s == crate::kinematic::NodeStatus::Placed).count();
    let failed: Vec<String> = net
        .status_counts()
        .into_iter()
        .filter(|(s, _)| s.name() != "placed")
        .map(|(s, n)| format!("{n} {}", s.name()))
        .collect();
    let mut nodes = format!("{placed} of {} placed", net.status.len());
    if !failed.is_empty() {
        nodes += &format!(" ({})", failed.join(", "));
    }
    f.push(("nodes".to_string(), nodes));
    let m = &net.meta;
    for (key, value) in [("generators", &m.generators), ("tool", &m.tool), ("material", &m.material)] {
        if let Some(v) = value {
            f.push((key.to_string(), v.clone()));
        }
    }
    if let Some(s) = &m.solver {
        f.push(("solver outcome".to_string(), s.outcome.clone()));
        if !s.converged {
            let why = s.reason.clone().unwrap_or_else(|| s.outcome.clone());
            f.push(("NOT CONVERGED".to_string(), format!("the last accepted state, not an equilibrium: {why}")));
        }
        match s.stability {
            Some(Stability::Saddle) => f.push((
                "stability".to_string(),
                "UNSTABLE: a saddle, an equilibrium the energy falls away from along some direction (the second-order check at convergence; the figures are in the net's meta.solver)".to_string(),
            )),
            Some(Stability::Minimum) => {
                f.push(("stability".to_string(), "a minimum of the energy (second-order check)".to_string()))
            }
            Some(Stability::Unresolved) => f.push((
                "stability".to_string(),
                "not checked: the second-order check's reference model could not be factorised".to_string(),
            )),
            None => {}
        }
    }
    if let Some(fm) = &m.forming {
        let stroke = fm.stroke_m;
        let mut process = format!(
            "stroke ({:.1}, {:.1}, {:.1}) mm in {} increments",
            stroke[0] * 1e3,
            stroke[1] * 1e3,
            stroke[2] * 1e3,
            fm.increments
        );
        if fm.die {
            process += ", with a die";
        }
        if let Some(b) = &fm.binder {
            process += &format!(", binder at {:.1} kPa outside its opening", b.pressure_pa * 1e-3);
        }
        if let Some(levels) = fm.levels_summary() {
            process += &format!("; {levels}");
        }
        f.push(("formed".to_string(), process));
    }
    if let Some(c) = &m.change_from_kinematic {
        let max = c
            .warp_angle_deg
            .iter()
            .flatten()
            .copied()
            .filter(|v| v.is_finite())
            .fold(None, |m: Option<f64>, v| Some(m.map_or(v.abs(), |m| m.max(v.abs()))));
        if let Some(m) = max {
            f.push(("largest warp direction change".to_string(), format!("{m:.2}°")));
        }
    }
    f
}

const STYLE: &str = "body{font-family:system-ui,-apple-system,'Segoe UI',sans-serif;margin:2em auto;max-width:1100px;color:#222;padding:0 1em}\
h1{font-size:1.6em}h2{margin-top:2em;border-bottom:1px solid #ccc;padding-bottom:.2em}\
table{border-collapse:collapse;margin:1em 0}th,td{border:1px solid #ccc;padding:.3em .6em;text-align:right}\
th{background:#f3f3f3}td.t,th.t{text-align:left}img{max-width:100%;height:auto;border:1px solid #ddd;margin:.5em 0}\
.notes{background:#fff6e0;border-left:4px solid #e0a000;padding:.5em 1em}.small{color:#666;font-size:.9em}\
dl{display:grid;grid-template-columns:max-content auto;gap:.2em 1em}dt{color:#666}dd{margin:0}\
.pattern svg{max-width:100%;max-height:300px;height:auto;border:1px solid #ddd}\
figure{margin:.5em 0}.pair{display:flex;gap:1em;flex-wrap:wrap}.pair figure{flex:1 1 45%;min-width:300px;max-width:calc(50% - .5em)}\
figcaption{margin-top:-.3em}dl.summary{grid-template-columns:max-content auto max-content auto}details{margin:.5em 0}summary{cursor:pointer;color:#345}\
.compare{border-left:4px solid #9ab;padding-left:1em;margin:1em 0}.compare h3{margin:.3em 0}\
.patterns{display:grid;grid-template-columns:repeat(auto-fill,minmax(340px,1fr));gap:.5em 1em}.patterns h3{font-size:1em;margin:.3em 0}\
#drape-view{width:100%;height:auto;border:1px solid #ddd;cursor:grab}.viewer-controls label{margin-right:1em}";

/// The whole page.
pub(crate) fn page(p: &Page) -> String {
    let mut h = String::new();
    let _ = write!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>{}</title>\n<style>{STYLE}</style>\n</head>\n<body>\n<h1>{}</h1>\n",
        escape(&p.title),
        escape(&p.title)
    );
    if let Some(t) = p.layup.as_ref().and_then(|l| l.tool.as_ref()) {
        let _ = writeln!(h, "<p class=\"small\">Tool: {}</p>", escape(t));
    }
    let source = if p.layup.is_some() { "from layup.json" } else { "computed from the nets (no layup.json)" };
    let _ = writeln!(h, "<h2 id=\"layup\">Layup</h2>\n<p class=\"small\">Table {source}. Shear angles in degrees; the locking angle is where the fabric stops shearing freely.</p>");
    layup_table(&mut h, &p.rows);
    // Plies sheared past the range their card's shear law was calibrated over.
    let range_warnings: Vec<(&str, &str)> =
        p.rows.iter().filter_map(|r| Some((r.name.as_str(), r.shear_range_warning.as_deref()?))).collect();
    if !range_warnings.is_empty() {
        let _ = writeln!(h, "<ul id=\"shear-range-warnings\" class=\"warning\">");
        for (ply, w) in &range_warnings {
            let _ = writeln!(h, "<li>warning: ply {}: {}</li>", escape(ply), escape(w));
        }
        let _ = writeln!(h, "</ul>");
    }
    if let Some(n) = p.layup.as_ref().and_then(|l| l.nesting.as_ref()) {
        let _ = writeln!(
            h,
            "<h3>Nesting</h3>\n<table id=\"nesting\"><tr><th>roll width (m)</th><th>length (m)</th><th>used area (m²)</th><th>pattern area (m²)</th><th>waste</th></tr>\n<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr></table>",
            num(n.roll_width_m, 3),
            num(n.length_m, 3),
            num(n.used_area_m2, 4),
            num(n.pattern_area_m2, 4),
            n.waste_fraction.filter(|w| w.is_finite()).map_or("—".into(), |w| format!("{:.1}%", 100.0 * w))
        );
    }
    if !p.laminate.is_empty() {
        let _ = writeln!(h, "<h3>Laminate</h3>\n<dl id=\"laminate\">");
        for (k, v) in &p.laminate {
            let _ = writeln!(h, "<dt>{}</dt><dd>{}</dd>", escape(k), escape(v));
        }
        let _ = writeln!(h, "</dl>");
    }
    if let Some(e) = p.layup.as_ref().and_then(|l| l.export.as_ref()) {
        export_section(&mut h, e);
    }
    if !p.statuses.is_empty() {
        let _ = writeln!(
            h,
            "<h3>Where the nets stopped</h3>\n<p class=\"small\">Nodes of each ply's grid that were not placed, and why. In the pictures a ringed dot of the status's colour marks the placed nodes next to them.</p>\n<table id=\"statuses\"><tr><th class=\"t\">status</th><th class=\"t\">meaning</th>"
        );
        for ply in &p.plies {
            let _ = write!(h, "<th>{}</th>", escape(&ply.name));
        }
        let _ = writeln!(h, "</tr>");
        for (s, counts) in &p.statuses {
            let c = super::shade::status_colour(*s);
            let _ = write!(
                h,
                "<tr><td class=\"t\"><span style=\"color:rgb({},{},{})\">●</span> {}</td><td class=\"t\">{}</td>",
                c[0],
                c[1],
                c[2],
                s.name(),
                escape(super::status_meaning(*s))
            );
            for n in counts {
                let _ = write!(h, "<td>{n}</td>");
            }
            let _ = writeln!(h, "</tr>");
        }
        let _ = writeln!(h, "</table>");
    }
    if !p.notes.is_empty() {
        let _ = writeln!(h, "<div class=\"notes\"><strong>Not everything could be drawn:</strong><ul>");
        for n in &p.notes {
            let _ = writeln!(h, "<li>{}</li>", escape(n));
        }
        let _ = writeln!(h, "</ul></div>");
    }
    h.push_str(&p.viewer);
    for ply in &p.plies {
        ply_section(&mut h, ply, p.extra.get(&ply.name).map(Vec::as_slice).unwrap_or(&[]));
    }
    if !p.studies.is_empty() {
        let _ = writeln!(h, "<h2 id=\"studies\">Studies</h2>");
        for f in &p.studies {
            let _ = writeln!(
                h,
                "<h3>{}</h3>\n<p class=\"small\">{}</p>\n<img src=\"{}\" alt=\"{}\">",
                escape(&f.heading),
                escape(&f.summary),
                escape(&f.picture),
                escape(&f.heading)
            );
        }
    }
    // Patterns not cut along the line their ply asks for, from layup.json.
    let cut_warnings: Vec<(&str, &CutWarning)> = p
        .layup
        .iter()
        .flat_map(|l| l.plies.iter())
        .flat_map(|r| r.pattern_warnings.iter().map(move |w| (r.name.as_str(), w)))
        .collect();
    if !p.patterns.is_empty() || !cut_warnings.is_empty() {
        let _ = writeln!(h, "<h2 id=\"patterns\">Flat patterns</h2>");
        if !cut_warnings.is_empty() {
            let _ = writeln!(h, "<ul id=\"pattern-warnings\" class=\"warning\">");
            for (ply, w) in &cut_warnings {
                let _ = writeln!(h, "<li>warning: ply {}: {}</li>", escape(ply), escape(&w.to_string()));
            }
            let _ = writeln!(h, "</ul>");
        }
        // In a grid of small drawings: each opens full size from its link.
        let _ = writeln!(h, "<div class=\"patterns\">");
        for (name, body) in &p.patterns {
            match body {
                Ok(svg) => {
                    let _ = writeln!(h, "<div><h3>{}</h3>\n<div class=\"pattern\">{svg}</div></div>", escape(name));
                }
                Err(link) => {
                    let _ = writeln!(
                        h,
                        "<div><h3>{0}</h3>\n<p><a href=\"{1}\">{0}</a> (too large to show inline)</p></div>",
                        escape(name),
                        escape(link)
                    );
                }
            }
        }
        let _ = writeln!(h, "</div>");
    }
    let _ = writeln!(h, "<p class=\"small\">Written by drape {}.</p>\n</body>\n</html>", env!("CARGO_PKG_VERSION"));
    h
}

/// The plies on the flow or FE mesh, as the run recorded them in `layup.json`.
fn export_section(h: &mut String, e: &crate::layup::table::ExportRow) {
    let _ = writeln!(
        h,
        "<h3 id=\"flow-export\">Flow-mesh export</h3>\n<p class=\"small\">The run mapped every ply onto the mesh <code>{}</code> ({} elements, {} nodes) and wrote {} ({}).</p>",
        escape(&e.mesh),
        e.elements,
        e.nodes,
        if e.formats.is_empty() { "no format".to_string() } else { escape(&e.formats.join(", ")) },
        if e.files.is_empty() { "no file".to_string() } else { escape(&e.files.join(", ")) }
    );
    let _ = writeln!(
        h,
        "<table id=\"export-table\"><tr><th class=\"t\">ply</th><th>elements covered</th><th>share of the mesh</th><th>max |γ| on the mesh (°)</th><th>mean |γ| on the mesh (°)</th></tr>"
    );
    for r in &e.plies {
        let share = if r.share.is_finite() { format!("{:.1}%", 100.0 * r.share) } else { "—".into() };
        let _ = writeln!(
            h,
            "<tr class=\"export-ply\"><td class=\"t\">{}</td><td>{} of {}</td><td>{share}</td><td>{}</td><td>{}</td></tr>",
            escape(&r.name),
            r.covered,
            e.elements,
            num(r.max_abs_shear_deg, 1),
            num(r.mean_abs_shear_deg, 1)
        );
    }
    let _ = writeln!(h, "</table>");
}

fn layup_table(h: &mut String, rows: &[LayupRow]) {
    let _ = writeln!(
        h,
        "<table id=\"layup-table\">\n<tr><th class=\"t\">ply</th><th class=\"t\">material</th><th>angle (°)</th><th class=\"t\">method</th><th>locking (°)</th><th>max |γ| (°)</th><th>mean |γ| (°)</th><th>area over locking (m²)</th><th>coverage (share of the tool or outline covered)</th><th>draped area (m²)</th><th>offset (mm)</th><th>draw-in (mm, fibres / diagonals)</th><th>wrinkled area (m², waviness over the threshold)</th></tr>"
    );
    for r in rows {
        let material = r
            .material
            .as_deref()
            .map(|m| std::path::Path::new(m).file_stem().map_or(m.to_string(), |s| s.to_string_lossy().into_owned()));
        let _ = writeln!(
            h,
            "<tr class=\"ply\"><td class=\"t\"><a href=\"#ply-{0}\">{0}</a></td><td class=\"t\">{1}</td><td>{2}</td><td class=\"t\">{3}</td><td>{4}</td><td>{5}</td><td>{6}</td><td>{7}</td><td>{8}</td><td>{9}</td><td>{10}</td><td>{11}</td><td>{12}</td></tr>",
            escape(&r.name),
            escape(material.as_deref().unwrap_or("—")),
            num(r.angle_deg, 1),
            method_cell(r),
            match r.locking_angle_source {
                Some(source) if source != crate::layup::LockingSource::Ply =>
                    format!("{} <span class=\"small\">({})</span>", num(r.locking_angle_deg, 1), source.tag()),
                _ => num(r.locking_angle_deg, 1),
            },
            num(r.max_abs_shear_deg, 1),
            num(r.mean_abs_shear_deg, 1),
            num(r.area_over_locking_m2, 4),
            match (r.coverage.filter(|c| c.is_finite()), r.coverage_of) {
                (Some(c), Some(of)) => format!("{:.1}% of {}", 100.0 * c, of.name()),
                _ => "—".into(),
            },
            num(r.draped_area_m2, 4),
            num(r.offset_m.map(|o| o * 1e3), 2),
            r.draw_in.as_ref().map_or("—".to_string(), |d| {
                let largest = |fibres: bool| num(d.largest(fibres).map(|e| e.draw_in_m * 1e3), 1);
                format!("{} / {}", largest(true), largest(false))
            }),
            r.wrinkles.as_ref().map_or("—".to_string(), |w| {
                format!(
                    "{} <span class=\"small\">(over {} mm)</span>",
                    num(Some(w.wrinkled_area_m2), 4),
                    num(Some(w.threshold_m * 1e3), 2)
                )
            }),
        );
    }
    let _ = writeln!(h, "</table>");
    // Why each ply with method = "auto" ran what it ran, in words under the table.
    for r in rows {
        if let Some(c) = &r.method_choice {
            let _ = writeln!(
                h,
                "<p class=\"choice\">Ply {}: <code>method = \"auto\"</code> (±{}°) ran <strong>{}</strong>: {}.</p>",
                escape(&r.name),
                c.tolerance_deg,
                escape(&c.headline()),
                escape(&c.reason)
            );
        }
    }
}

fn ply_section(h: &mut String, ply: &PlyReport, facts: &[(String, String)]) {
    let name = escape(&ply.name);
    let _ =
        writeln!(h, "<h2 id=\"ply-{name}\">Ply {name} <span class=\"small\">({})</span></h2>", method_name(ply.method));
    let mut summary = vec![
        ("complete cells".to_string(), ply.cells.to_string()),
        ("max |shear|".to_string(), format!("{}°", num(Some(ply.max_abs_shear_deg), 1))),
        ("mean |shear|".to_string(), format!("{}°", num(Some(ply.mean_abs_shear_deg), 1))),
        ("locking angle".to_string(), format!("{}°", num(Some(ply.locking_angle_deg), 1))),
        ("colour scale".to_string(), format!("±{}°", num(Some(ply.colour_limit_deg), 0))),
    ];
    let change = ply.change.as_ref().map(|c| {
        let at = c.largest_at;
        let place = if at.iter().all(|x| x.is_finite()) {
            format!(
                " at cell ({}, {}), ({:.1}, {:.1}, {:.1}) mm",
                c.largest_cell.0,
                c.largest_cell.1,
                at[0] * 1e3,
                at[1] * 1e3,
                at[2] * 1e3
            )
        } else {
            String::new()
        };
        format!(
            "largest change {:+.2}°{place}; mean |change| {:.2}° over {} cells",
            c.largest_deg, c.mean_abs_deg, c.cells
        )
    });
    if let Some(c) = &change {
        summary.push(("mechanical − kinematic".to_string(), c.clone()));
    }
    let _ = writeln!(h, "<dl class=\"summary\">");
    for (k, v) in &summary {
        let _ = writeln!(h, "<dt>{}</dt><dd>{}</dd>", escape(k), escape(v));
    }
    let _ = writeln!(h, "</dl>");
    // The net's particulars are secondary: folded away.
    if !facts.is_empty() {
        let _ = writeln!(h, "<details class=\"facts\"><summary>Net details</summary><dl>");
        for (k, v) in facts {
            let _ = writeln!(h, "<dt>{}</dt><dd>{}</dd>", escape(k), escape(v));
        }
        let _ = writeln!(h, "</dl></details>");
    }
    if !ply.notes.is_empty() {
        let _ = writeln!(h, "<div class=\"notes\"><ul>");
        for n in &ply.notes {
            let _ = writeln!(h, "<li>{}</li>", escape(n));
        }
        let _ = writeln!(h, "</ul></div>");
    }
    let names: Vec<String> =
        ply.files.iter().filter_map(|f| Some(f.file_name()?.to_string_lossy().into_owned())).collect();
    let png = |suffix: &str| names.iter().find(|n| n.ends_with(&format!("-{suffix}.png"))).cloned();
    let figure = |h: &mut String, png: &str, caption: &str| {
        let svg = png.trim_end_matches(".png").to_string() + ".svg";
        let svg_link =
            if names.contains(&svg) { format!(" · <a href=\"{}\">SVG</a>", escape(&svg)) } else { String::new() };
        let _ = writeln!(
            h,
            "<figure><img src=\"{0}\" alt=\"{0}\" width=\"{1}\" height=\"{2}\"><figcaption class=\"small\">{3}<a href=\"{0}\">PNG</a>{svg_link}</figcaption></figure>",
            escape(png),
            super::WIDTH,
            super::HEIGHT,
            caption
        );
    };
    // Pictures two to a row: a mechanical ply with its kinematic start shows the two side by
    // side, then the change map and its histogram, then the shear histogram.
    let mut rows: Vec<Vec<(String, &str)>> = Vec::new();
    match (png("kinematic"), png("shear")) {
        (Some(k), Some(m)) => {
            let _ = writeln!(
                h,
                "<section class=\"compare\" id=\"compare-{name}\"><h3>Kinematic against mechanical</h3>\n<p class=\"small\">The kinematic net the mechanics started from and the mechanical result, from the same views on the layup's colour scale (±{}°). {}</p>",
                num(Some(ply.colour_limit_deg), 0),
                escape(&compare_text(ply, change.as_deref()))
            );
            let _ = writeln!(h, "<div class=\"pair\">");
            figure(h, &k, "kinematic · ");
            figure(h, &m, "mechanical · ");
            let _ = writeln!(h, "</div>");
            let change: Vec<(String, &str)> =
                ["change", "change-histogram"].iter().filter_map(|s| png(s)).map(|p| (p, "")).collect();
            if change.is_empty() {
                let _ = writeln!(
                    h,
                    "<p class=\"small\">No difference map: every change lies within the solver's noise (see the note above).</p>"
                );
            } else {
                let _ = writeln!(h, "<div class=\"pair\">");
                for (p, c) in &change {
                    figure(h, p, c);
                }
                let _ = writeln!(h, "</div>");
            }
            let _ = writeln!(h, "</section>");
            // The wrinkle map beside the mechanical net's shear histogram.
            rows.push(png("wrinkles").into_iter().chain(png("histogram")).map(|p| (p, "")).collect());
        }
        (_, shear) => {
            // The wrinkle map beside the shear map, then the histogram.
            match png("wrinkles") {
                Some(w) => {
                    rows.push(shear.into_iter().map(|p| (p, "")).chain([(w, "wrinkles · ")]).collect());
                    rows.push(png("histogram").into_iter().map(|p| (p, "")).collect());
                }
                None => rows.push(shear.into_iter().chain(png("histogram")).map(|p| (p, "")).collect()),
            }
            rows.push(["change", "change-histogram"].iter().filter_map(|s| png(s)).map(|p| (p, "")).collect());
        }
    }
    rows.push(png("contact").into_iter().map(|p| (p, "stick and slip · ")).collect());
    // The draw-in in plan is linked, not shown: a page of every ply's pictures stays a page.
    if let Some(p) = png("draw-in") {
        let svg = p.trim_end_matches(".png").to_string() + ".svg";
        let _ = writeln!(
            h,
            "<p class=\"small\">Draw-in, the blank flat and the ply draped in plan: <a href=\"{0}\">PNG</a> · <a href=\"{1}\">SVG</a></p>",
            escape(&p),
            escape(&svg)
        );
    }
    for row in rows.iter().filter(|r| !r.is_empty()) {
        let _ = writeln!(h, "<div class=\"pair\">");
        for (p, c) in row {
            figure(h, p, c);
        }
        let _ = writeln!(h, "</div>");
    }
}

/// The side-by-side section's figures in words: each net's shear and the change between them.
fn compare_text(ply: &PlyReport, change: Option<&str>) -> String {
    let mut t = String::new();
    if let Some(k) = &ply.kinematic {
        t += &format!(
            "Kinematic: max |γ| {}°, mean {}°, {} cells past locking. ",
            num(Some(k.max_abs_shear_deg), 1),
            num(Some(k.mean_abs_shear_deg), 1),
            k.over_locking_cells
        );
    }
    t += &format!(
        "Mechanical: max |γ| {}°, mean {}°, {} cells past locking.",
        num(Some(ply.max_abs_shear_deg), 1),
        num(Some(ply.mean_abs_shear_deg), 1),
        ply.over_locking_cells
    );
    if let Some(c) = change {
        t += &format!(" Mechanical − kinematic: {c}.");
    }
    if let Some(n) = &ply.change_noise {
        t += &format!(" Changes within ±{:.2}° are the solver's noise and drawn as none.", n.floor_deg);
    }
    t
}

/// The layup table's method cell: what ran, marked when it did not converge or ended on a
/// saddle, with auto's choice in a tooltip.
fn method_cell(r: &LayupRow) -> String {
    if r.outcome.as_deref() == Some("slides") {
        let title = r.solver_failure.as_deref().unwrap_or("nothing holds the ply where it is on the tool");
        return format!(
            "<strong>SLIDES</strong> <span class=\"small\" title=\"{}\">{}</span>",
            escape(title),
            escape(r.method.as_deref().unwrap_or(""))
        );
    }
    if r.converged == Some(false) {
        return format!("<strong>NOT CONVERGED</strong> {}", escape(r.method.as_deref().unwrap_or("")));
    }
    let mut cell = match &r.method_choice {
        Some(c) => format!(
            "{} <span class=\"small\" title=\"{}\">(auto, ±{}°)</span>{}",
            escape(r.method.as_deref().unwrap_or(&c.chosen)),
            escape(&c.reason),
            c.tolerance_deg,
            if c.not_assured() { " <strong>NOT ASSURED</strong>" } else { "" }
        ),
        None => escape(r.method.as_deref().unwrap_or("—")),
    };
    if r.stability == Some(Stability::Saddle) {
        cell.push_str(
            " <span class=\"small\" title=\"the converged state is a saddle of the energy, not a minimum\">(unstable: a saddle)</span>",
        );
    }
    cell
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn escapes_and_strips() {
        assert_eq!(escape("<a & \"b\">"), "&lt;a &amp; &quot;b&quot;&gt;");
        assert_eq!(strip_prolog("<?xml version=\"1.0\"?>\n<svg x=\"1\"/>"), "<svg x=\"1\"/>");
        assert_eq!(num(Some(f64::NAN), 2), "—");
        assert_eq!(num(Some(1.234), 1), "1.2");
    }

    #[test]
    fn the_method_cell_marks_an_auto_choice_that_is_not_assured() {
        let choice = |assured| crate::kinematic::MethodChoice {
            requested: "auto".into(),
            chosen: "mechanical".into(),
            surface: "facets".into(),
            tolerance_deg: 1.0,
            spacing_m: 0.002,
            assured,
            reason: "why".into(),
            indicators: Default::default(),
        };
        let row = |assured| LayupRow {
            name: "p0".into(),
            method: Some("mechanical".into()),
            method_choice: Some(choice(assured)),
            converged: Some(true),
            ..Default::default()
        };
        assert!(method_cell(&row(Some(false))).contains("<strong>NOT ASSURED</strong>"));
        assert!(!method_cell(&row(Some(true))).contains("NOT ASSURED"));
        // Files written before the verdict was recorded claim nothing either way.
        assert!(!method_cell(&row(None)).contains("NOT ASSURED"));
        // A saddle and a ply that slides are marked too.
        let saddle = LayupRow { stability: Some(Stability::Saddle), ..row(Some(true)) };
        assert!(method_cell(&saddle).contains("(unstable: a saddle)"));
        let slides = LayupRow {
            converged: Some(false),
            outcome: Some("slides".into()),
            solver_failure: Some("slides: frictionless and held by nothing".into()),
            ..row(Some(true))
        };
        let cell = method_cell(&slides);
        assert!(
            cell.starts_with("<strong>SLIDES</strong>") && cell.contains("frictionless and held by nothing"),
            "{cell}"
        );
        assert_eq!(choice(Some(false)).headline(), "mechanical (NOT ASSURED within 1 deg)");
        assert_eq!(choice(None).headline(), "mechanical");
    }
}
