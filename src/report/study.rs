//! The pictures of a study: error against time on log-log axes with the Pareto front
//! (`speed_accuracy.svg/png`), and the outcome map over two swept parameters
//! (`stability.svg/png`).
use super::render::{register_fonts, to_png, to_svg, DrawResult};
use crate::kinematic::fabric_field::FabricImage;
use crate::study::speed_accuracy::SpeedAccuracy;
use crate::study::stability::Stability;
use crate::study::Finished;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

const FONT: &str = "sans-serif";
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

fn de<E: std::fmt::Display>(e: E) -> String {
    e.to_string()
}

/// Draw a finished study's pictures into `dir`; returns the files written.
pub fn draw(dir: &Path, finished: &Finished) -> Result<Vec<PathBuf>, String> {
    register_fonts();
    let (stem, png, svg) = match finished {
        Finished::SpeedAccuracy(s) => {
            ("speed_accuracy", to_png(|r| draw_speed_accuracy(r, s))?, to_svg(|r| draw_speed_accuracy(r, s))?)
        }
        Finished::Stability(s) => ("stability", to_png(|r| draw_stability(r, s))?, to_svg(|r| draw_stability(r, s))?),
    };
    let mut files = Vec::new();
    for (ext, bytes) in [("png", png), ("svg", svg.into_bytes())] {
        let path = dir.join(format!("{stem}.{ext}"));
        crate::io::write_atomic(&path, |w| std::io::Write::write_all(w, &bytes)).map_err(de)?;
        files.push(path);
    }
    Ok(files)
}

/// A number in at most three significant figures, for axis labels.
fn short(x: f64) -> String {
    format!("{}", format!("{x:.2e}").parse::<f64>().unwrap_or(x))
}

fn series_name(method: &str, surface: &str) -> String {
    if surface == "facets" {
        method.to_string()
    } else {
        format!("{method} ({surface})")
    }
}

/// Error (max over the compared points) against time, one series per method, on log axes.
pub fn draw_speed_accuracy<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, s: &SpeedAccuracy) -> DrawResult {
    root.fill(&WHITE).map_err(de)?;
    let pts: Vec<(&str, String, f64, f64, bool)> = s
        .points
        .iter()
        .filter_map(|p| {
            // The reference itself has no error to put on a log axis; the title names it.
            let e = p.error_max_deg.filter(|e| *e > 0.0)?.max(ERROR_FLOOR_DEG);
            (p.time_s > 0.0).then(|| (p.method.as_str(), series_name(&p.method, &p.surface), p.time_s, e, p.pareto))
        })
        .collect();
    let reference = match s.reference.kind.as_str() {
        "mechanical" => format!("{} at d = {:.4} m", s.reference.method, s.reference.spacing),
        _ => "each method's Richardson limit".to_string(),
    };
    let title = format!("Ply {}: largest shear error against time (reference: {reference})", s.ply);
    if pts.is_empty() {
        return root
            .draw(&Text::new(format!("{title}: no run gave an error to chart"), (20, 20), (FONT, 20).into_font()))
            .map_err(de);
    }
    let (tmin, tmax) = pts.iter().fold((f64::INFINITY, 0.0f64), |(a, b), p| (a.min(p.2), b.max(p.2)));
    let (emin, emax) = pts.iter().fold((f64::INFINITY, 0.0f64), |(a, b), p| (a.min(p.3), b.max(p.3)));
    let mut chart = ChartBuilder::on(root)
        .caption(title, (FONT, 18))
        .margin(20)
        .x_label_area_size(50)
        .y_label_area_size(70)
        .build_cartesian_2d((tmin / 2.0..tmax * 2.0).log_scale(), (emin / 2.0..emax * 2.0).log_scale())
        .map_err(de)?;
    chart
        .configure_mesh()
        .x_desc("time per ply, s")
        .y_desc("largest cell-shear error, deg")
        .x_label_formatter(&|x| short(*x))
        .y_label_formatter(&|y| short(*y))
        .label_style((FONT, 14))
        .draw()
        .map_err(de)?;
    let mut series: BTreeMap<String, Vec<(f64, f64)>> = BTreeMap::new();
    for p in &pts {
        series.entry(p.1.clone()).or_default().push((p.2, p.3));
    }
    for (k, (name, mut xy)) in series.into_iter().enumerate() {
        let c = PALETTE[k % PALETTE.len()];
        xy.sort_by(|a, b| a.0.total_cmp(&b.0));
        chart.draw_series(LineSeries::new(xy.clone(), c.stroke_width(2))).map_err(de)?;
        chart
            .draw_series(xy.iter().map(|&(x, y)| Circle::new((x, y), 5, c.filled())))
            .map_err(de)?
            .label(name)
            .legend(move |(x, y)| Circle::new((x + 10, y), 5, c.filled()));
    }
    let mut front: Vec<(f64, f64)> = pts.iter().filter(|p| p.4).map(|p| (p.2, p.3)).collect();
    front.sort_by(|a, b| a.0.total_cmp(&b.0));
    chart
        .draw_series(LineSeries::new(front.clone(), BLACK.stroke_width(1)))
        .map_err(de)?
        .label("Pareto front")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK));
    chart.draw_series(front.iter().map(|&(x, y)| Circle::new((x, y), 9, BLACK.stroke_width(2)))).map_err(de)?;
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font((FONT, 14))
        .position(SeriesLabelPosition::UpperRight)
        .draw()
        .map_err(de)
}

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
                "Ply {}: {} runs ({ok} compared) against {} ({}); circled points are the Pareto front: no other run is both faster and more accurate.",
                s.ply,
                s.points.len(),
                if s.reference.kind == "mechanical" { format!("{} at d = {:.4} m", s.reference.method, s.reference.spacing) } else { "each method's Richardson limit".into() },
                s.reference.kind
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
                        Some(format!("{} ({}, d = {:.4} m): {}", p.method, p.surface, p.spacing, m.name()))
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
        for (stem, heading, summary) in found {
            let Ok(bytes) = std::fs::read(place.join(format!("{stem}.png"))) else { continue };
            let picture = format!("{tag}-{stem}.png");
            crate::io::write_atomic(&out.join(&picture), |w| std::io::Write::write_all(w, &bytes))?;
            figures.push(StudyFigure { heading, picture, summary });
        }
    }
    Ok(figures)
}
