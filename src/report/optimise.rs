//! The picture of an optimisation (`optimise.svg/png`): the objective's landscape over the seed
//! region (at each seed the best over the angles tried) and against the ply angle (the best
//! over the seeds, and at the best candidate's seed), the optimum and the runners-up marked.
//! Colours are the report's diverging map, blue for the best and red for the worst.
use super::render::{de, draw_colour_bar, DrawResult, Mark, BAR_COLUMN_PX, FONT, HEIGHT, TITLE_PX, WIDTH};
use super::view::shear_colour;
use crate::study::optimise::{Candidate, Optimisation};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::collections::BTreeMap;

/// Cells drawn for seeds without a complete cell at any angle.
const NO_DRAPE: RGBColor = RGBColor(200, 200, 200);
/// The angle chart's two lines.
const BEST_OVER_SEEDS: RGBColor = RGBColor(31, 119, 180);
const AT_BEST_SEED: RGBColor = RGBColor(255, 127, 14);

/// The landscape's colour of objective `f` between the best `lo` and the worst `hi` found.
fn landscape_colour(f: f64, lo: f64, hi: f64) -> [u8; 3] {
    let t = if hi > lo { 2.0 * (f - lo) / (hi - lo) - 1.0 } else { -1.0 };
    shear_colour(t, 1.0)
}

/// The best objective at each seed (over the angles), in plan order of the seeds.
fn best_per_seed(landscape: &[Candidate]) -> Vec<([f64; 2], Option<f64>)> {
    let mut seeds: Vec<([f64; 2], Option<f64>)> = Vec::new();
    for c in landscape {
        match seeds.iter_mut().find(|s| s.0 == c.seed_ab) {
            Some(s) => s.1 = min_option(s.1, c.objective),
            None => seeds.push((c.seed_ab, c.objective)),
        }
    }
    seeds
}

fn min_option(a: Option<f64>, b: Option<f64>) -> Option<f64> {
    match (a, b) {
        (Some(x), Some(y)) => Some(x.min(y)),
        (x, None) => x,
        (None, y) => y,
    }
}

/// Draw the landscape of `o`.
pub fn draw_landscape<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, o: &Optimisation) -> DrawResult {
    root.fill(&WHITE).map_err(de)?;
    let values: Vec<f64> = o.landscape.iter().filter_map(|c| c.objective).collect();
    let (lo, hi) = values.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(*v), b.max(*v)));
    let (lo, hi) = (lo.min(o.best.objective), hi.max(o.best.objective));
    let (top, body) = root.split_vertically(TITLE_PX);
    top.draw(&Text::new(
        format!("Ply {}: the objective over the seed region and the ply angle", o.ply),
        (20, 10),
        (FONT, 20).into_font(),
    ))
    .map_err(de)?;
    let angle = o.best.angle_deg.map_or("as in the scene".to_string(), |a| format!("{a:.2} deg"));
    top.draw(&Text::new(
        format!(
            "minimised: {}; best {:.4} at seed ({:.4}, {:.4}, {:.4}) m, angle {angle} (d = {} m; search at {} m)",
            o.objective_text,
            o.best.objective,
            o.best.origin[0],
            o.best.origin[1],
            o.best.origin[2],
            o.best.spacing,
            o.search_spacing
        ),
        (20, 40),
        (FONT, 13).into_font(),
    ))
    .map_err(de)?;
    let (plots, _) = body.split_horizontally(WIDTH - BAR_COLUMN_PX);
    let seeds_varied = o.search.region.is_some();
    let angles_varied = o.search.angles.is_some();
    match (seeds_varied, angles_varied) {
        (true, true) => {
            let (left, right) = plots.split_horizontally((WIDTH - BAR_COLUMN_PX) / 2);
            draw_seed_map(&left, o, lo, hi)?;
            draw_angle_chart(&right, o)?;
        }
        (true, false) => draw_seed_map(&plots, o, lo, hi)?,
        _ => draw_angle_chart(&plots, o)?,
    }
    let marks = [Mark { value: o.best.objective, label: "optimum".into() }];
    let (bar_lo, bar_hi) = if hi > lo { (lo, hi) } else { (lo - 0.5, lo + 0.5) };
    draw_colour_bar(root, (bar_lo, bar_hi), &|f| landscape_colour(f, lo, hi), "objective", &marks, HEIGHT / 3)
}

/// The seeds in the plane, each coloured by its best objective over the angles.
fn draw_seed_map<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, o: &Optimisation, lo: f64, hi: f64) -> DrawResult {
    let seeds = best_per_seed(&o.landscape);
    let h = o.search.seed_step;
    let (mut a0, mut a1, mut b0, mut b1) = (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY);
    for (ab, _) in &seeds {
        (a0, a1, b0, b1) = (a0.min(ab[0]), a1.max(ab[0]), b0.min(ab[1]), b1.max(ab[1]));
    }
    // Square axes about the seeds (the plane is not stretched).
    let half = 0.5 * (a1 - a0).max(b1 - b0) + h;
    let (ca, cb) = (0.5 * (a0 + a1), 0.5 * (b0 + b1));
    let mut chart = ChartBuilder::on(area)
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(70)
        .build_cartesian_2d(ca - half..ca + half, cb - half..cb + half)
        .map_err(de)?;
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc("seed along the 0 deg direction, m")
        .y_desc("seed across it, m")
        .x_label_formatter(&|x| format!("{x:.3}"))
        .y_label_formatter(&|y| format!("{y:.3}"))
        .label_style((FONT, 13))
        .draw()
        .map_err(de)?;
    chart
        .draw_series(seeds.iter().map(|(ab, f)| {
            let c = f.map_or(NO_DRAPE, |f| {
                let [r, g, b] = landscape_colour(f, lo, hi);
                RGBColor(r, g, b)
            });
            Rectangle::new([(ab[0] - 0.48 * h, ab[1] - 0.48 * h), (ab[0] + 0.48 * h, ab[1] + 0.48 * h)], c.filled())
        }))
        .map_err(de)?;
    let at = |p: &crate::study::optimise::Placement| (p.seed_ab[0], p.seed_ab[1]);
    chart.draw_series(o.runners_up.iter().map(|p| Circle::new(at(p), 7, BLACK.stroke_width(2)))).map_err(de)?;
    chart
        .draw_series([Circle::new(at(&o.best), 9, BLACK.filled()), Circle::new(at(&o.best), 4, WHITE.filled())])
        .map_err(de)?;
    area.draw(&Text::new(
        "each seed: its best angle; filled ring: optimum, rings: runners-up, grey: no drape",
        (80, 2),
        (FONT, 12).into_font(),
    ))
    .map_err(de)
}

/// The objective against the angle: the best over the seeds, and at the best candidate's seed.
fn draw_angle_chart<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, o: &Optimisation) -> DrawResult {
    let key = |a: f64| (a * 1e9).round() as i64;
    let mut best_over_seeds: BTreeMap<i64, (f64, f64)> = BTreeMap::new();
    for c in &o.landscape {
        let (Some(a), Some(f)) = (c.angle_deg, c.objective) else { continue };
        let e = best_over_seeds.entry(key(a)).or_insert((a, f));
        e.1 = e.1.min(f);
    }
    let seed = o.landscape.get(o.best.start.candidate).map(|c| c.seed_ab);
    let at_seed: Vec<(f64, f64)> = o
        .landscape
        .iter()
        .filter(|c| Some(c.seed_ab) == seed)
        .filter_map(|c| Some((c.angle_deg?, c.objective?)))
        .collect();
    let over: Vec<(f64, f64)> = best_over_seeds.values().copied().collect();
    if over.is_empty() {
        return area.draw(&Text::new("no angle gave a drape", (20, 20), (FONT, 16).into_font())).map_err(de);
    }
    let range = o.search.angles.map_or((-90.0, 90.0), |r| (r.lo, r.hi));
    let pad = o.search.angles.map_or(1.0, |r| 0.5 * r.step);
    let fs: Vec<f64> = over.iter().chain(&at_seed).map(|p| p.1).chain([o.best.objective]).collect();
    let (f0, f1) = fs.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(*v), b.max(*v)));
    let margin = 0.05 * (f1 - f0).max(1e-9);
    let mut chart = ChartBuilder::on(area)
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(70)
        .build_cartesian_2d(range.0 - pad..range.1 + pad, f0 - margin..f1 + margin)
        .map_err(de)?;
    chart
        .configure_mesh()
        .x_desc("ply angle, deg")
        .y_desc("objective")
        .y_label_formatter(&|y| format!("{y:.3}"))
        .label_style((FONT, 13))
        .draw()
        .map_err(de)?;
    chart
        .draw_series(LineSeries::new(over.clone(), BEST_OVER_SEEDS.stroke_width(2)))
        .map_err(de)?
        .label("best over the seeds")
        .legend(|(x, y)| PathElement::new([(x, y), (x + 20, y)], BEST_OVER_SEEDS.stroke_width(2)));
    chart
        .draw_series(LineSeries::new(at_seed, AT_BEST_SEED.stroke_width(2)))
        .map_err(de)?
        .label("at the best candidate's seed")
        .legend(|(x, y)| PathElement::new([(x, y), (x + 20, y)], AT_BEST_SEED.stroke_width(2)));
    if let Some(a) = o.best.angle_deg {
        chart
            .draw_series([Circle::new((a, o.best.objective), 6, BLACK.filled())])
            .map_err(de)?
            .label("optimum (refined at the ply's spacing)")
            .legend(|(x, y)| Circle::new((x + 10, y), 5, BLACK.filled()));
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font((FONT, 12))
        .position(SeriesLabelPosition::UpperRight)
        .draw()
        .map_err(de)
}
