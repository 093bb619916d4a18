//! The picture of a shear fit (`drape calibrate`, `NEW.fit.png`): on the left each sample's
//! force against displacement with the law's force, on the right each sample's normalised
//! shear force against the shear angle (the energy normalisation that puts samples of every size
//! on one curve) with the law's, the fitted range marked; below, each point's relative force
//! error against its angle, where a misfit at small angles shows as plainly as one at large.
use super::render::{de, register_fonts, to_png, DrawResult, FONT};
use crate::material::calibrate::{normalised_shear_force, rig_force, ShearFit, ShearSample};
use plotters::coord::Shift;
use plotters::prelude::*;

/// One colour per sample.
const PALETTE: [RGBColor; 6] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
];
/// Points of each drawn law curve.
const CURVE_POINTS: usize = 200;

/// The fit's picture as PNG bytes.
pub fn fit_png(fit: &ShearFit, samples: &[ShearSample]) -> Result<Vec<u8>, String> {
    register_fonts();
    to_png(|root| draw_fit(root, fit, samples))
}

/// A range padded by 5 %, never empty.
fn padded(lo: f64, hi: f64) -> std::ops::Range<f64> {
    let span = if hi > lo { hi - lo } else { hi.abs().max(1.0) };
    (lo - 0.05 * span)..(hi + 0.05 * span)
}

/// Draw the two panels.
pub fn draw_fit<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    fit: &ShearFit,
    samples: &[ShearSample],
) -> DrawResult {
    root.fill(&WHITE).map_err(de)?;
    let title = format!(
        "{} fit from {} to {:.1} deg: R^2 {:.5}, rms relative error {:.2}% over {} points",
        fit.law.law_name(),
        fit.range.min_deg,
        fit.calibrated_max_deg,
        fit.r_squared,
        100.0 * fit.rms_relative,
        fit.points
    );
    let root = root.titled(&title, (FONT, 20)).map_err(de)?;
    let (top_area, bottom) = root.split_vertically(root.dim_in_pixel().1 as i32 * 62 / 100);
    let (left, right) = top_area.split_horizontally(top_area.dim_in_pixel().0 as i32 / 2);
    let cal = fit.calibrated_max_deg.to_radians();
    draw_relative_errors(&bottom, fit, samples)?;

    // Left: force against displacement (mm).
    let mut dmax: f64 = 0.0;
    let mut fmin: f64 = 0.0;
    let mut fmax: f64 = 0.0;
    for s in samples {
        for &(d, f) in s.data.iter().filter(|p| s.rig.shear(p.0).is_some()) {
            dmax = dmax.max(d);
            fmin = fmin.min(f);
            fmax = fmax.max(f);
        }
    }
    let mut chart = ChartBuilder::on(&left)
        .caption("force against displacement (filled: fitted)", (FONT, 16))
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(65)
        .build_cartesian_2d(padded(0.0, dmax * 1e3), padded(fmin, fmax))
        .map_err(de)?;
    chart.configure_mesh().x_desc("displacement, mm").y_desc("force, N").label_style((FONT, 13)).draw().map_err(de)?;
    for (k, s) in samples.iter().enumerate() {
        let c = PALETTE[k % PALETTE.len()];
        let fitted = |d: f64| s.rig.shear(d).is_some_and(|(g, _)| fit.range.holds(g));
        let pts: Vec<(f64, f64, bool)> =
            s.data.iter().filter(|p| s.rig.shear(p.0).is_some()).map(|&(d, f)| (d * 1e3, f, fitted(d))).collect();
        chart
            .draw_series(
                pts.iter()
                    .map(|&(x, y, inside)| Circle::new((x, y), 3, if inside { c.filled() } else { c.stroke_width(1) })),
            )
            .map_err(de)?
            .label(s.name.clone())
            .legend(move |(x, y)| Circle::new((x + 10, y), 4, c.filled()));
        let d_end = s.data.iter().map(|p| p.0).filter(|d| s.rig.shear(*d).is_some()).fold(0.0, f64::max);
        let curve: Vec<(f64, f64)> = (0..=CURVE_POINTS)
            .filter_map(|i| {
                let d = d_end * i as f64 / CURVE_POINTS as f64;
                Some((d * 1e3, rig_force(&fit.law, &s.rig, d)?))
            })
            .filter(|p| p.1 <= fmax * 1.5)
            .collect();
        chart.draw_series(LineSeries::new(curve, c.stroke_width(2))).map_err(de)?;
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font((FONT, 13))
        .position(SeriesLabelPosition::UpperLeft)
        .draw()
        .map_err(de)?;

    // Right: normalised shear force against the angle.
    let curves: Vec<Vec<(f64, f64)>> = samples
        .iter()
        .map(|s| {
            let mut c: Vec<(f64, f64)> = s.rig.normalise(&s.data).into_iter().flatten().collect();
            c.sort_by(|a, b| a.0.total_cmp(&b.0));
            c
        })
        .collect();
    // The data a little past the fitted range: where the law goes on and the data leave it.
    let reach = (cal + 20f64.to_radians()).max(1.5 * cal).min(89f64.to_radians());
    let gmax = curves.iter().flatten().map(|p| p.0).fold(cal, f64::max).min(reach);
    let law_at = |g: f64| normalised_shear_force(&fit.law, g);
    let in_range: Vec<f64> = curves.iter().flatten().filter(|p| p.0 <= cal).map(|p| p.1).collect();
    let top = in_range.iter().copied().fold(law_at(cal), f64::max) * 1.3;
    let bottom = in_range.iter().copied().fold(0.0, f64::min);
    let mut chart = ChartBuilder::on(&right)
        .caption("normalised shear force against shear angle", (FONT, 16))
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(65)
        .build_cartesian_2d(padded(0.0, gmax.to_degrees()), padded(bottom, top))
        .map_err(de)?;
    chart
        .configure_mesh()
        .x_desc("shear angle, deg")
        .y_desc("normalised shear force Fsh = M / cos g, N/m")
        .label_style((FONT, 13))
        .draw()
        .map_err(de)?;
    for (k, (s, c)) in samples.iter().zip(&curves).enumerate() {
        let col = PALETTE[k % PALETTE.len()];
        chart
            .draw_series(c.iter().filter(|p| p.0 <= gmax && p.1 <= top && p.1 >= bottom).map(|&(g, f)| {
                Circle::new((g.to_degrees(), f), 3, if fit.range.holds(g) { col.filled() } else { col.stroke_width(1) })
            }))
            .map_err(de)?
            .label(format!("{} ({})", s.name, s.rig.name()))
            .legend(move |(x, y)| Circle::new((x + 10, y), 4, col.filled()));
    }
    let law_curve = |from: f64, to: f64| -> Vec<(f64, f64)> {
        (0..=CURVE_POINTS)
            .map(|i| from + (to - from) * i as f64 / CURVE_POINTS as f64)
            .map(|g| (g.to_degrees(), law_at(g)))
            .filter(|p| p.1 <= top)
            .collect()
    };
    chart
        .draw_series(LineSeries::new(law_curve(0.0, cal), BLACK.stroke_width(3)))
        .map_err(de)?
        .label(format!("fitted {} law", fit.law.law_name()))
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK.stroke_width(3)));
    if gmax > cal {
        chart
            .draw_series(LineSeries::new(law_curve(cal, gmax), BLACK.mix(0.4).stroke_width(1)))
            .map_err(de)?
            .label("the law extrapolated")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK.mix(0.4)));
    }
    let cal_deg = fit.calibrated_max_deg;
    chart
        .draw_series(std::iter::once(PathElement::new(
            vec![(cal_deg, bottom), (cal_deg, top)],
            RGBColor(200, 0, 0).stroke_width(1),
        )))
        .map_err(de)?
        .label(format!("calibrated to {cal_deg:.1} deg"))
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], RGBColor(200, 0, 0)));
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font((FONT, 13))
        .position(SeriesLabelPosition::UpperLeft)
        .draw()
        .map_err(de)
}

/// Relative errors shown up to this (a point past it is drawn at the edge).
const ERROR_CLIP: f64 = 0.5;

/// Each point's F_law / F - 1 (%) against its angle, the fitted range shaded.
fn draw_relative_errors<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    fit: &ShearFit,
    samples: &[ShearSample],
) -> DrawResult {
    let pts: Vec<Vec<(f64, f64)>> = samples
        .iter()
        .map(|s| {
            s.data
                .iter()
                .filter_map(|&(d, f)| {
                    let (g, _) = s.rig.shear(d)?;
                    let law = rig_force(&fit.law, &s.rig, d)?;
                    (g > 0.0 && f != 0.0)
                        .then(|| (g.to_degrees(), (law / f - 1.0).clamp(-ERROR_CLIP, ERROR_CLIP) * 100.0))
                })
                .collect()
        })
        .collect();
    let gmax = pts.iter().flatten().map(|p| p.0).fold(fit.calibrated_max_deg, f64::max);
    let reach = (fit.calibrated_max_deg + 20.0).max(1.5 * fit.calibrated_max_deg).min(89.0);
    let xmax = gmax.min(reach);
    let lim = 100.0 * ERROR_CLIP;
    let mut chart = ChartBuilder::on(area)
        .caption("relative force error of the law at each point, F_law / F - 1 (filled: fitted)", (FONT, 16))
        .margin(15)
        .x_label_area_size(40)
        .y_label_area_size(65)
        .build_cartesian_2d(padded(0.0, xmax), -lim * 1.05..lim * 1.05)
        .map_err(de)?;
    chart.configure_mesh().x_desc("shear angle, deg").y_desc("error, %").label_style((FONT, 13)).draw().map_err(de)?;
    chart
        .draw_series(std::iter::once(Rectangle::new(
            [(fit.range.min_deg, -lim), (fit.calibrated_max_deg, lim)],
            RGBColor(230, 240, 255).filled(),
        )))
        .map_err(de)?;
    chart.draw_series(std::iter::once(PathElement::new(vec![(0.0, 0.0), (xmax, 0.0)], BLACK))).map_err(de)?;
    for (k, p) in pts.iter().enumerate() {
        let c = PALETTE[k % PALETTE.len()];
        chart
            .draw_series(p.iter().filter(|q| q.0 <= xmax).map(|&(g, e)| {
                let inside = fit.range.holds(g.to_radians());
                Circle::new((g, e), 3, if inside { c.filled() } else { c.stroke_width(1) })
            }))
            .map_err(de)?;
    }
    Ok(())
}
