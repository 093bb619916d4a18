//! The pictures of a study: error against time on log-log axes with the Pareto front
//! (`speed_accuracy.svg/png`), and the outcome map over two swept parameters
//! (`stability.svg/png`).
use super::optimise::draw_landscape;
use super::render::{de, register_fonts, to_png, to_svg, DrawResult, FONT, TITLE_PX};
use crate::kinematic::fabric_field::FabricImage;
use crate::study::optimise::Optimisation;
use crate::study::speed_accuracy::{mm, three_figures, SpeedAccuracy, SpeedPoint};
use crate::study::stability::Stability;
use crate::study::Finished;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Errors below this (degrees) are drawn at it (the estimate's rounding floor).
const ERROR_FLOOR_DEG: f64 = 1e-4;
/// Series colours, one per method.
const PALETTE: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
];

/// Draw a finished study's pictures into `dir`; returns the files written.
pub fn draw(dir: &Path, finished: &Finished) -> Result<Vec<PathBuf>, String> {
    register_fonts();
    let (stem, png, svg) = match finished {
        Finished::SpeedAccuracy(s) => {
            ("speed_accuracy", to_png(|r| draw_speed_accuracy(r, s))?, to_svg(|r| draw_speed_accuracy(r, s))?)
        }
        Finished::Stability(s) => ("stability", to_png(|r| draw_stability(r, s))?, to_svg(|r| draw_stability(r, s))?),
        Finished::Optimise(o) => ("optimise", to_png(|r| draw_landscape(r, o))?, to_svg(|r| draw_landscape(r, o))?),
    };
    let mut files = Vec::new();
    for (ext, bytes) in [("png", png), ("svg", svg.into_bytes())] {
        let path = dir.join(format!("{stem}.{ext}"));
        crate::io::write_atomic(&path, |w| std::io::Write::write_all(w, &bytes)).map_err(de)?;
        files.push(path);
    }
    Ok(files)
}

/// The labelled values of a log axis over `lo..hi`: each decade and 2 and 5 times it.
fn log_ticks(lo: f64, hi: f64) -> Vec<f64> {
    if !(lo > 0.0 && hi >= lo && hi.is_finite()) {
        return Vec::new();
    }
    let (a, b) = (lo.log10().floor() as i32, hi.log10().ceil() as i32);
    (a..=b)
        .flat_map(|k| [1.0, 2.0, 5.0].map(|m| m * 10f64.powi(k)))
        // Within the axis, to rounding of the powers of ten.
        .filter(|v| *v >= lo * (1.0 - 1e-12) && *v <= hi * (1.0 + 1e-12))
        .collect()
}

/// The series a run belongs to: its method and surface, and its tool where the study ran on
/// several.
fn series_name(p: &SpeedPoint, several_tools: bool) -> String {
    let mut name = format!("{} ({})", p.method_label(), p.surface);
    if several_tools {
        name += &format!(" [{} tri]", p.tool_triangles);
    }
    name
}

/// Error (max over the compared points, against the study's one reference) against time, one
/// series per method, on log axes labelled at each decade and at 2 and 5, each point marked
/// with its spacing.
pub fn draw_speed_accuracy<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, s: &SpeedAccuracy) -> DrawResult {
    root.fill(&WHITE).map_err(de)?;
    let mut triangles: Vec<usize> = s.points.iter().map(|p| p.tool_triangles).collect();
    triangles.sort_unstable();
    triangles.dedup();
    let several_tools = triangles.len() > 1;
    // (series, time, error, on the Pareto front, spacing)
    let pts: Vec<(String, f64, f64, bool, f64)> = s
        .points
        .iter()
        .filter_map(|p| {
            // The reference itself has no error to put on a log axis; the title names it.
            let e = p.error_max_deg.filter(|e| *e > 0.0)?.max(ERROR_FLOOR_DEG);
            (p.time_s > 0.0).then(|| (series_name(p, several_tools), p.time_s, e, p.pareto, p.spacing))
        })
        .collect();
    let (top, body) = root.split_vertically(TITLE_PX);
    top.draw(&Text::new(
        format!("Ply {}: largest cell-shear error against time, every run against one reference", s.ply),
        (20, 10),
        (FONT, 18).into_font(),
    ))
    .map_err(de)?;
    top.draw(&Text::new(format!("reference: {}", s.reference.label()), (20, 38), (FONT, 14).into_font()))
        .map_err(de)?;
    if pts.is_empty() {
        return body.draw(&Text::new("no run gave an error to chart", (20, 20), (FONT, 20).into_font())).map_err(de);
    }
    // The reference's own uncertainty, drawn as a line: errors below it cannot be told apart
    // from the reference's.
    let uncertainty = s.reference.convergence.uncertainty_max_deg.filter(|u| *u > 0.0).map(|u| u.max(ERROR_FLOOR_DEG));
    let (tmin, tmax) = pts.iter().fold((f64::INFINITY, 0.0f64), |(a, b), p| (a.min(p.1), b.max(p.1)));
    let (emin, emax) = pts.iter().fold((f64::INFINITY, 0.0f64), |(a, b), p| (a.min(p.2), b.max(p.2)));
    let (emin, emax) = uncertainty.map_or((emin, emax), |u| (emin.min(u), emax.max(u)));
    let (x0, x1, y0, y1) = (tmin / 2.0, tmax * 2.0, emin / 2.0, emax * 2.0);
    // The legend in a column of its own, clear of the points.
    let (plot, legend) = body.split_horizontally(body.dim_in_pixel().0.saturating_sub(LEGEND_COLUMN) as i32);
    let mut chart = ChartBuilder::on(&plot)
        .margin(20)
        .x_label_area_size(50)
        .y_label_area_size(70)
        .build_cartesian_2d(
            (x0..x1).log_scale().with_key_points(log_ticks(x0, x1)),
            (y0..y1).log_scale().with_key_points(log_ticks(y0, y1)),
        )
        .map_err(de)?;
    chart
        .configure_mesh()
        .x_desc("time per ply, s")
        .y_desc("largest cell-shear error against the reference, deg")
        .x_label_formatter(&|x| three_figures(*x))
        .y_label_formatter(&|y| three_figures(*y))
        .label_style((FONT, 14))
        .draw()
        .map_err(de)?;
    let mut series: BTreeMap<String, Vec<(f64, f64, f64)>> = BTreeMap::new();
    for p in &pts {
        series.entry(p.0.clone()).or_default().push((p.1, p.2, p.4));
    }
    let mut entries: Vec<(String, RGBColor)> = Vec::new();
    for (k, (name, mut xy)) in series.into_iter().enumerate() {
        let c = PALETTE[k % PALETTE.len()];
        xy.sort_by(|a, b| a.0.total_cmp(&b.0));
        chart.draw_series(LineSeries::new(xy.iter().map(|p| (p.0, p.1)), c.stroke_width(2))).map_err(de)?;
        chart.draw_series(xy.iter().map(|&(x, y, _)| Circle::new((x, y), 5, c.filled()))).map_err(de)?;
        // Each point says its spacing.
        chart
            .draw_series(xy.iter().map(|&(x, y, d)| {
                EmptyElement::at((x, y))
                    + Text::new(format!("{} mm", mm(d)), (7, -16), (FONT, 11).into_font().color(&c))
            }))
            .map_err(de)?;
        entries.push((name, c));
    }
    if let Some(u) = uncertainty {
        chart.draw_series(LineSeries::new([(x0, u), (x1, u)], GREY.stroke_width(1))).map_err(de)?;
    }
    let mut front: Vec<(f64, f64)> = pts.iter().filter(|p| p.3).map(|p| (p.1, p.2)).collect();
    front.sort_by(|a, b| a.0.total_cmp(&b.0));
    chart.draw_series(LineSeries::new(front.clone(), BLACK.stroke_width(1))).map_err(de)?;
    chart.draw_series(front.iter().map(|&(x, y)| Circle::new((x, y), 9, BLACK.stroke_width(2)))).map_err(de)?;
    // The legend: the series, the Pareto front, the reference's own error, what the labels say.
    let font = (FONT, 13).into_font();
    let mut y = 30;
    for (name, c) in &entries {
        legend.draw(&Circle::new((14, y + 7), 5, c.filled())).map_err(de)?;
        legend.draw(&Text::new(name.clone(), (28, y), font.clone())).map_err(de)?;
        y += 22;
    }
    y += 8;
    legend.draw(&Circle::new((14, y + 7), 9, BLACK.stroke_width(2))).map_err(de)?;
    legend.draw(&Text::new("Pareto front", (28, y), font.clone())).map_err(de)?;
    if uncertainty.is_some() {
        y += 22;
        legend.draw(&PathElement::new(vec![(4, y + 7), (24, y + 7)], GREY)).map_err(de)?;
        legend.draw(&Text::new("the reference's own spacing error", (28, y), font.clone())).map_err(de)?;
    }
    y += 30;
    legend.draw(&Text::new("each point: its spacing d", (4, y), font.clone())).map_err(de)?;
    Ok(())
}

/// Width of the chart's legend column, pixels.
const LEGEND_COLUMN: u32 = 300;
/// The reference's own-error line.
const GREY: RGBColor = RGBColor(120, 120, 120);

/// Colour of an outcome on the stability map: green for `ok`, a fixed colour per reason.
fn outcome_colour(outcome: &str, reasons: &[String]) -> RGBColor {
    if outcome == "ok" {
        return RGBColor(120, 200, 120);
    }
    let k = reasons.iter().position(|r| r == outcome).unwrap_or(0);
    PALETTE[(k + 1) % PALETTE.len()]
}

/// The outcome of every case over the two axes' values, one coloured cell each.
pub fn draw_stability<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, s: &Stability) -> DrawResult {
    root.fill(&WHITE).map_err(de)?;
    let [a, b] = &s.axes;
    let cells: Vec<(f64, f64, &str)> = s
        .cases
        .iter()
        .filter(|c| c.params.len() >= 2 && c.params.contains_key(a) && c.params.contains_key(b))
        .map(|c| (c.params[a], c.params[b], c.outcome.as_str()))
        .collect();
    let title = format!("Ply {}: outcome over {a} and {b}", s.ply);
    let mut xs: Vec<f64> = cells.iter().map(|c| c.0).collect();
    let mut ys: Vec<f64> = cells.iter().map(|c| c.1).collect();
    for v in [&mut xs, &mut ys] {
        v.sort_by(f64::total_cmp);
        v.dedup();
    }
    if xs.is_empty() || ys.is_empty() {
        return root
            .draw(&Text::new(format!("{title}: no case on both axes"), (20, 20), (FONT, 20).into_font()))
            .map_err(de);
    }
    let mut reasons: Vec<String> = cells.iter().filter(|c| c.2 != "ok").map(|c| c.2.to_string()).collect();
    reasons.sort();
    reasons.dedup();
    let (legend, plot) = root.split_horizontally(root.dim_in_pixel().0 as i32 - 260);
    let mut chart = ChartBuilder::on(&legend)
        .caption(title, (FONT, 18))
        .margin(20)
        .x_label_area_size(50)
        .y_label_area_size(70)
        .build_cartesian_2d(-0.5..xs.len() as f64 - 0.5, -0.5..ys.len() as f64 - 0.5)
        .map_err(de)?;
    let label = |vals: &[f64], x: &f64| {
        let k = x.round();
        if (x - k).abs() < 1e-9 && k >= 0.0 && (k as usize) < vals.len() {
            format!("{}", vals[k as usize])
        } else {
            String::new()
        }
    };
    chart
        .configure_mesh()
        .disable_mesh()
        .x_labels(xs.len())
        .y_labels(ys.len())
        .x_label_formatter(&|x| label(&xs, x))
        .y_label_formatter(&|y| label(&ys, y))
        .x_desc(if a == "spacing" { "spacing (times the ply's)" } else { a.as_str() })
        .y_desc(if b == "spacing" { "spacing (times the ply's)" } else { b.as_str() })
        .label_style((FONT, 14))
        .draw()
        .map_err(de)?;
    let index = |vals: &[f64], x: f64| vals.iter().position(|v| *v == x).unwrap_or(0) as f64;
    chart
        .draw_series(cells.iter().map(|&(x, y, o)| {
            let (i, j) = (index(&xs, x), index(&ys, y));
            Rectangle::new([(i - 0.45, j - 0.45), (i + 0.45, j + 0.45)], outcome_colour(o, &reasons).filled())
        }))
        .map_err(de)?;
    let mut y = 60;
    for o in std::iter::once("ok".to_string()).chain(reasons.iter().cloned()) {
        let c = outcome_colour(&o, &reasons);
        plot.draw(&Rectangle::new([(10, y), (30, y + 20)], c.filled())).map_err(de)?;
        plot.draw(&Text::new(o, (38, y + 3), (FONT, 14).into_font())).map_err(de)?;
        y += 30;
    }
    Ok(())
}

/// A study's chart on the report page.
#[derive(Debug, Clone, PartialEq)]
pub struct StudyFigure {
    /// The section's heading.
    pub heading: String,
    /// The chart, copied into the report folder (a file name there).
    pub picture: String,
    /// One line saying what the chart shows.
    pub summary: String,
}

/// The studies that ran in the run folder `dir` (into it, or into a folder inside it): their
/// charts, copied into the report folder `out`. A study whose file does not read is skipped.
pub fn collect_figures(dir: &Path, out: &Path) -> Result<Vec<StudyFigure>, crate::io::ExportError> {
    let mut places: Vec<PathBuf> = vec![dir.to_path_buf()];
    if let Ok(entries) = std::fs::read_dir(dir) {
        let mut subs: Vec<PathBuf> = entries.filter_map(|e| e.ok().map(|e| e.path())).filter(|p| p.is_dir()).collect();
        subs.sort();
        places.extend(subs);
    }
    let mut figures = Vec::new();
    for place in places {
        let tag = if place == dir {
            "study".to_string()
        } else {
            format!("study-{}", place.file_name().unwrap_or_default().to_string_lossy())
        };
        let read = |name: &str| std::fs::read_to_string(place.join(name)).ok();
        let mut found = Vec::new();
        if let Some(s) =
            read(crate::study::speed_accuracy::FILE).and_then(|t| serde_json::from_str::<SpeedAccuracy>(&t).ok())
        {
            let ok = s.points.iter().filter(|p| p.error_max_deg.is_some()).count();
            let summary = format!(
                "Ply {}: {} runs ({ok} compared), every one against one reference: {}. A run's error is its distance from it, whatever its source (its spacing, the tool's facets, its model); each point is labelled with its spacing; circled points are the Pareto front: no other run is both faster and more accurate.",
                s.ply,
                s.points.len(),
                s.reference.describe()
            );
            // On a symmetric scene: the symmetries, and the runs measured in an image of the
            // reference rather than in the reference as it fell.
            let summary = if s.reference.symmetries.is_empty() {
                summary
            } else {
                let names: Vec<&str> = s.reference.symmetries.iter().map(|m| m.name()).collect();
                let imaged: Vec<String> = s
                    .points
                    .iter()
                    .filter_map(|p| {
                        let m = p.reference_image.filter(|m| *m != FabricImage::AsIs)?;
                        Some(format!("{} ({}, d = {:.4} m): {}", p.method_label(), p.surface, p.spacing, m.name()))
                    })
                    .collect();
                format!(
                    "{summary} The ply's drape problem is symmetric ({}), so a mechanical drape may break the symmetry either way: each run is measured against the reference or its image nearest to it; {}.",
                    names.join(", "),
                    if imaged.is_empty() { "every run against the reference as it fell".to_string() } else { format!("against an image: {}", imaged.join("; ")) }
                )
            };
            // What method = "auto" kept and saved, in words under the chart.
            let auto: String = s
                .auto
                .iter()
                .map(|a| {
                    format!(
                        " auto at d = {:.4} m ran {}: largest error {} (tolerance {} deg), {:.2} s{}{}.",
                        a.spacing,
                        a.chosen,
                        a.error_max_deg.map_or("not compared".to_string(), |e| format!("{e:.3} deg")),
                        a.tolerance_deg,
                        a.time_s,
                        a.cost_ratio.map_or(String::new(), |r| format!(
                            " against {:.2} s for mechanics ({:.0}% of its cost)",
                            a.mechanical_time_s.unwrap_or_default(),
                            100.0 * r
                        )),
                        a.verdict(&s.reference).map_or(String::new(), |v| format!("; {v}"))
                    )
                })
                .collect();
            let auto = match &s.auto_not_run {
                Some(why) => format!("{auto} Auto was not run: {why}."),
                None => auto,
            };
            let summary = summary + &auto;
            found.push((
                "speed_accuracy",
                format!("Speed against accuracy, ply {} ({})", s.ply, place.display()),
                summary,
            ));
        }
        if let Some(s) = read(crate::study::stability::FILE).and_then(|t| serde_json::from_str::<Stability>(&t).ok()) {
            let failed = s.cases.iter().filter(|c| c.outcome != "ok").count();
            let summary = format!(
                "Ply {}: {} cases, {failed} ended in a named failure; the map shows the outcome over {} and {}.",
                s.ply,
                s.cases.len(),
                s.axes[0],
                s.axes[1]
            );
            found.push(("stability", format!("Where the methods fail, ply {} ({})", s.ply, place.display()), summary));
        }
        if let Some(o) = read(crate::study::optimise::FILE).and_then(|t| serde_json::from_str::<Optimisation>(&t).ok())
        {
            let summary = format!(
                "Ply {}: {} candidate placements ({} draped) searched at d = {} m, the best {} refined at the ply's d = {} m. Minimised: {}. Best {:.4} at seed ({:.4}, {:.4}, {:.4}) m, angle {}; {} ready for drape run.",
                o.ply,
                o.landscape.len(),
                o.feasible,
                o.search_spacing,
                o.search.refine_starts,
                o.best.spacing,
                o.objective_text,
                o.best.objective,
                o.best.origin[0],
                o.best.origin[1],
                o.best.origin[2],
                o.best.angle_deg.map_or("as in the scene".to_string(), |a| format!("{a:.2} deg")),
                place.join(&o.scene).display()
            );
            found.push(("optimise", format!("Best placement, ply {} ({})", o.ply, place.display()), summary));
        }
        for (stem, heading, summary) in found {
            let Ok(bytes) = std::fs::read(place.join(format!("{stem}.png"))) else { continue };
            let picture = format!("{tag}-{stem}.png");
            crate::io::write_atomic(&out.join(&picture), |w| std::io::Write::write_all(w, &bytes))?;
            figures.push(StudyFigure { heading, picture, summary });
        }
    }
    Ok(figures)
}

#[cfg(test)]
mod tests {
    use super::log_ticks;

    #[test]
    fn log_axes_are_labelled_at_each_decade_and_at_2_and_5() {
        let close =
            |a: &[f64], b: &[f64]| a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() <= 1e-12 * y);
        let t = log_ticks(3e-4, 0.3);
        assert!(close(&t, &[5e-4, 1e-3, 2e-3, 5e-3, 0.01, 0.02, 0.05, 0.1, 0.2]), "{t:?}");
        // The ends themselves when they fall on a label; a narrow range still has one.
        assert!(close(&log_ticks(1e-3, 1.0), &[1e-3, 2e-3, 5e-3, 0.01, 0.02, 0.05, 0.1, 0.2, 0.5, 1.0]));
        assert!(close(&log_ticks(2.1, 8.4), &[5.0]));
        assert!(log_ticks(0.0, 1.0).is_empty() && log_ticks(1.0, f64::INFINITY).is_empty());
    }
}
