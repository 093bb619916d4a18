//! Drawing the pictures: the shaded views of a ply on its tool (pixels from [`super::shade`])
//! with titles, a colour bar and a legend; and the histogram (PNG and SVG).
use super::shade::{render_panel, PanelOut, PlyScene};
use super::view::{nice_ceil, nice_floor, shear_colour, View};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::sync::Once;

/// Picture size in pixels (PNG) and user units (SVG).
pub const WIDTH: u32 = 1200;
/// Picture height, see [`WIDTH`].
pub const HEIGHT: u32 = 800;

/// Font family every text of the pictures uses; registered from the embedded DejaVu Sans (the
/// other pictures' modules name it through this, so their text is drawn in the font registered).
pub(super) const FONT: &str = "sans-serif";

/// Width of the colour-bar column (kept on the right of the pictures that have one), pixels.
pub(super) const BAR_COLUMN_PX: u32 = 240;
/// Height of the title band, pixels.
pub(super) const TITLE_PX: u32 = 64;

static FONTS: Once = Once::new();

/// Register the embedded DejaVu Sans (regular and bold) with plotters' `ab_glyph` text renderer,
/// so pictures need no system fonts (fontconfig). Idempotent.
pub fn register_fonts() {
    FONTS.call_once(|| {
        // The font files are compiled in from the `dejavu` crate; they always parse.
        let ok = plotters::style::register_font(FONT, FontStyle::Normal, dejavu::sans::regular()).is_ok()
            && plotters::style::register_font(FONT, FontStyle::Bold, dejavu::sans::bold()).is_ok();
        debug_assert!(ok, "embedded DejaVu fonts did not parse");
    });
}

/// One picture error: what plotters said.
pub type DrawResult = Result<(), String>;

/// A plotters error as the picture's error text.
pub(super) fn de<E: std::fmt::Display>(e: E) -> String {
    e.to_string()
}

fn rgb(c: [u8; 3]) -> RGBColor {
    RGBColor(c[0], c[1], c[2])
}

/// A labelled line on a colour bar or histogram (value in degrees).
#[derive(Debug, Clone)]
pub struct Mark {
    pub value: f64,
    pub label: String,
}

fn fmt_len(x: f64) -> String {
    if x >= 1.0 {
        format!("{x:.0}")
    } else {
        format!("{x}")
    }
}

fn font(size: f64) -> FontDesc<'static> {
    (FONT, size).into_font()
}

fn bold(size: f64) -> FontDesc<'static> {
    (FONT, size, FontStyle::Bold).into_font()
}

/// The colour bar in the right column: `colour` from `low` to `limit` (the diverging map of a
/// shear picture, or of an optimisation's landscape) with ticks, a label and marked lines (the
/// locking angle, the optimum).
pub(crate) fn draw_colour_bar<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    (low, limit): (f64, f64),
    colour: &dyn Fn(f64) -> [u8; 3],
    label: &str,
    marks: &[Mark],
    bottom: u32,
) -> DrawResult {
    let (_, column) = root.split_horizontally(WIDTH - BAR_COLUMN_PX);
    let mut chart = ChartBuilder::on(&column)
        .margin_top(TITLE_PX + 10)
        .margin_bottom(bottom)
        .margin_right(85)
        .y_label_area_size(58)
        .build_cartesian_2d(0f64..1f64, low..limit)
        .map_err(de)?;
    let step_label = |v: &f64| if limit - low >= 10.0 { format!("{v:.0}") } else { format!("{v:.2}") };
    chart
        .configure_mesh()
        .disable_x_mesh()
        .disable_y_mesh()
        .x_labels(0)
        .y_labels(9)
        .y_label_formatter(&step_label)
        .y_desc(label)
        .label_style(font(14.0))
        .axis_desc_style(font(15.0))
        .draw()
        .map_err(de)?;
    const STEPS: usize = 128;
    let h = (limit - low) / STEPS as f64;
    chart
        .draw_series((0..STEPS).map(|k| {
            let a = low + k as f64 * h;
            Rectangle::new([(0.0, a), (1.0, a + h)], rgb(colour(a + 0.5 * h)).filled())
        }))
        .map_err(de)?;
    for m in marks {
        chart
            .draw_series(std::iter::once(PathElement::new(vec![(0.0, m.value), (1.0, m.value)], BLACK.stroke_width(2))))
            .map_err(de)?;
        let (x, y) = chart.backend_coord(&(1.0, m.value));
        let style = font(13.0).color(&BLACK).pos(Pos::new(HPos::Left, VPos::Center));
        root.draw(&Text::new(m.label.clone(), (x + 6, y), style)).map_err(de)?;
    }
    Ok(())
}

/// A histogram of signed values (degrees) between -limit and +limit.
#[derive(Debug, Clone)]
pub struct HistogramPicture {
    pub title: String,
    /// Summary line drawn in the top-right corner of the plot.
    pub note: String,
    pub values: Vec<f64>,
    pub limit: f64,
    pub x_label: String,
    pub marks: Vec<Mark>,
}

/// Bin width (degrees) giving about `HISTOGRAM_BINS` bins over [-limit, limit].
pub fn bin_width(limit: f64) -> f64 {
    nice_ceil(2.0 * limit / HISTOGRAM_BINS)
}

/// Target number of histogram bins.
const HISTOGRAM_BINS: f64 = 60.0;

/// Share of values (percent) in each bin of width `bin` starting at `-limit`.
pub fn bin_shares(values: &[f64], limit: f64, bin: f64) -> Vec<f64> {
    let n = (2.0 * limit / bin).round().max(1.0) as usize;
    let mut counts = vec![0usize; n];
    for v in values.iter().filter(|v| v.is_finite()) {
        let k = ((v + limit) / bin).floor().clamp(0.0, (n - 1) as f64) as usize;
        counts[k] += 1;
    }
    let total = values.len().max(1) as f64;
    counts.into_iter().map(|c| 100.0 * c as f64 / total).collect()
}

/// Draw a histogram picture on `root`.
pub fn draw_histogram<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, pic: &HistogramPicture) -> DrawResult {
    register_fonts();
    root.fill(&WHITE).map_err(de)?;
    let bin = bin_width(pic.limit);
    let shares = bin_shares(&pic.values, pic.limit, bin);
    let top = shares.iter().copied().fold(0.0, f64::max);
    let ymax = if top > 0.0 { nice_ceil(top * 1.15) } else { 1.0 };
    let mut chart = ChartBuilder::on(root)
        .caption(pic.title.clone(), bold(24.0))
        .margin(20)
        .x_label_area_size(55)
        .y_label_area_size(75)
        .build_cartesian_2d(-pic.limit..pic.limit, 0f64..ymax)
        .map_err(de)?;
    chart
        .configure_mesh()
        .disable_x_mesh()
        .light_line_style(RGBColor(235, 235, 235))
        .x_desc(pic.x_label.clone())
        .y_desc("share of cells (%)")
        .label_style(font(15.0))
        .axis_desc_style(font(17.0))
        .x_label_formatter(&|v| format!("{v:.0}"))
        .y_label_formatter(&|v| if ymax >= 5.0 { format!("{v:.0}") } else { format!("{v:.1}") })
        .draw()
        .map_err(de)?;
    chart
        .draw_series(shares.iter().enumerate().filter(|(_, s)| **s > 0.0).map(|(k, s)| {
            let a = -pic.limit + k as f64 * bin;
            Rectangle::new([(a, 0.0), (a + bin, *s)], rgb(shear_colour(a + 0.5 * bin, pic.limit)).filled())
        }))
        .map_err(de)?;
    chart
        .draw_series(shares.iter().enumerate().filter(|(_, s)| **s > 0.0).map(|(k, s)| {
            let a = -pic.limit + k as f64 * bin;
            Rectangle::new([(a, 0.0), (a + bin, *s)], RGBColor(60, 60, 60).stroke_width(1))
        }))
        .map_err(de)?;
    for m in &pic.marks {
        chart
            .draw_series(std::iter::once(PathElement::new(
                vec![(m.value, 0.0), (m.value, ymax)],
                BLACK.stroke_width(2),
            )))
            .map_err(de)?;
        // Labels sit inside the band between the marks, next to their line.
        let (hpos, dx) = if m.value < 0.0 { (HPos::Left, 6) } else { (HPos::Right, -6) };
        let (x, y) = chart.backend_coord(&(m.value, ymax));
        root.draw(&Text::new(
            m.label.clone(),
            (x + dx, y + 12),
            font(14.0).color(&BLACK).pos(Pos::new(hpos, VPos::Center)),
        ))
        .map_err(de)?;
    }
    let (x0, y) = chart.backend_coord(&(-pic.limit, ymax));
    let (x1, _) = chart.backend_coord(&(pic.limit, ymax));
    let style = font(14.0).color(&RGBColor(60, 60, 60)).pos(Pos::new(HPos::Center, VPos::Center));
    root.draw(&Text::new(pic.note.clone(), ((x0 + x1) / 2, y + 40), style)).map_err(de)?;
    Ok(())
}

/// Render with `draw` to a PNG (RGB, [`WIDTH`] x [`HEIGHT`]) in memory.
pub fn to_png(draw: impl Fn(&DrawingArea<BitMapBackend, Shift>) -> DrawResult) -> Result<Vec<u8>, String> {
    let mut buf = vec![0u8; (WIDTH * HEIGHT * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (WIDTH, HEIGHT)).into_drawing_area();
        draw(&root)?;
        root.present().map_err(de)?;
    }
    encode_png(&buf)
}

/// Encode an RGB buffer of [`WIDTH`] x [`HEIGHT`] pixels as PNG.
fn encode_png(buf: &[u8]) -> Result<Vec<u8>, String> {
    let mut out = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut out, WIDTH, HEIGHT);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let mut w = enc.write_header().map_err(de)?;
        w.write_image_data(buf).map_err(de)?;
    }
    Ok(out)
}

/// Render with `draw` to an SVG document in memory.
pub fn to_svg(draw: impl Fn(&DrawingArea<SVGBackend, Shift>) -> DrawResult) -> Result<String, String> {
    let mut s = String::new();
    {
        let root = SVGBackend::with_string(&mut s, (WIDTH, HEIGHT)).into_drawing_area();
        draw(&root)?;
        root.present().map_err(de)?;
    }
    Ok(s)
}

/// The sample drawn beside a legend entry.
#[derive(Debug, Clone, Copy)]
pub enum Swatch {
    /// A line in this colour.
    Line([u8; 3]),
    /// A filled box.
    Fill([u8; 3]),
    /// A box with dark diagonal stripes over this colour.
    Hatch([u8; 3]),
    /// A ringed dot (the frontier marks).
    Dot([u8; 3]),
    /// The seed's ringed white disc.
    Seed,
}

/// One line of a picture's legend.
#[derive(Debug, Clone)]
pub struct LegendItem {
    /// Its sample.
    pub swatch: Swatch,
    /// What it means (short: the column is narrow).
    pub text: String,
}

/// A shaded picture's texts: title, colour bar, legend.
#[derive(Debug, Clone, Default)]
pub struct ShadedPicture {
    /// Title.
    pub title: String,
    /// Small text under the title.
    pub subtitle: String,
    /// Colour bar limit (symmetric) and label, marks on it.
    pub limit: f64,
    /// The bar runs from 0 to the limit only (a quantity that is never negative).
    pub from_zero: bool,
    /// Colour bar label.
    pub bar_label: String,
    /// Marked values on the bar.
    pub marks: Vec<Mark>,
    /// Legend below the colour bar.
    pub legend: Vec<LegendItem>,
}

/// Where the views go: the first large on the left, the others stacked on the right.
pub fn panel_rects(views: usize) -> Vec<[usize; 4]> {
    let (left, top) = (10usize, TITLE_PX as usize + 6);
    let w = (WIDTH - BAR_COLUMN_PX) as usize - 20;
    let h = HEIGHT as usize - top - 10;
    match views {
        0 => vec![],
        1 => vec![[left, top, w, h]],
        n => {
            let main = w * 62 / 100;
            let side = w - main - 8;
            let each = (h - 6 * (n - 2)) / (n - 1);
            let mut out = vec![[left, top, main, h]];
            for k in 0..n - 1 {
                out.push([left + main + 8, top + k * (each + 6), side, each]);
            }
            out
        }
    }
}

/// Top of the legend, pixels.
const LEGEND_TOP: i32 = 440;

/// Render `scene` in `views` with `pic`'s texts to a PNG; also what each panel drew.
pub fn shaded_png(
    scene: &PlyScene,
    views: &[(View, String)],
    pic: &ShadedPicture,
) -> Result<(Vec<u8>, Vec<PanelOut>), String> {
    register_fonts();
    let mut buf = vec![255u8; (WIDTH * HEIGHT * 3) as usize];
    let rects = panel_rects(views.len());
    let outs: Vec<PanelOut> =
        views.iter().zip(&rects).map(|((v, _), r)| render_panel(scene, v, *r, &mut buf, WIDTH as usize)).collect();
    {
        let root = BitMapBackend::with_buffer(&mut buf, (WIDTH, HEIGHT)).into_drawing_area();
        for ((_, name), (r, out)) in views.iter().zip(rects.iter().zip(&outs)) {
            let [x, y, w, h] = r.map(|v| v as i32);
            root.draw(&Rectangle::new([(x, y), (x + w, y + h)], RGBColor(200, 200, 200).stroke_width(1)))
                .map_err(de)?;
            root.draw(&Text::new(name.clone(), (x + 8, y + 6), font(14.0).color(&RGBColor(60, 60, 60)))).map_err(de)?;
            for l in &out.labels {
                let style = bold(14.0).color(&rgb(l.colour)).pos(Pos::new(HPos::Left, VPos::Center));
                root.draw(&Text::new(l.text.clone(), (l.x, l.y), style)).map_err(de)?;
            }
        }
        // A scale bar in the first panel's lower-right corner (lengths across the view).
        if let (Some(r), Some(out)) = (rects.first(), outs.first()) {
            if out.px_per_m > 0.0 {
                let len_m = nice_floor(0.2 * r[2] as f64 / out.px_per_m);
                let len = (len_m * out.px_per_m).round() as i32;
                let label =
                    if len_m < 1.0 { format!("{} mm", fmt_len(len_m * 1e3)) } else { format!("{} m", fmt_len(len_m)) };
                let (x1, y) = ((r[0] + r[2]) as i32 - 70, (r[1] + r[3]) as i32 - 18);
                root.draw(&Rectangle::new([(x1 - len, y - 3), (x1, y + 3)], BLACK.filled())).map_err(de)?;
                let style = font(14.0).color(&BLACK).pos(Pos::new(HPos::Left, VPos::Center));
                root.draw(&Text::new(label, (x1 + 6, y), style)).map_err(de)?;
            }
        }
        root.draw(&Text::new(pic.title.clone(), (20, 12), bold(24.0).color(&BLACK))).map_err(de)?;
        root.draw(&Text::new(pic.subtitle.clone(), (20, 44), font(14.0).color(&RGBColor(90, 90, 90)))).map_err(de)?;
        if views.is_empty() {
            let style = font(20.0).color(&BLACK).pos(Pos::new(HPos::Center, VPos::Center));
            let at = (((WIDTH - BAR_COLUMN_PX) / 2) as i32, (HEIGHT / 2) as i32);
            root.draw(&Text::new("no complete cells to draw", at, style)).map_err(de)?;
        }
        draw_colour_bar(
            &root,
            (if pic.from_zero { 0.0 } else { -pic.limit }, pic.limit),
            &|v| shear_colour(v, pic.limit),
            &pic.bar_label,
            &pic.marks,
            HEIGHT - LEGEND_TOP as u32 + 20,
        )?;
        draw_legend(&root, &pic.legend)?;
        root.present().map_err(de)?;
    }
    Ok((encode_png(&buf)?, outs))
}

/// The legend in the right column, below the colour bar.
fn draw_legend<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, items: &[LegendItem]) -> DrawResult {
    let x = (WIDTH - BAR_COLUMN_PX) as i32 + 8;
    for (k, item) in items.iter().enumerate() {
        let y = LEGEND_TOP + 22 * k as i32;
        match item.swatch {
            Swatch::Line(c) => {
                root.draw(&PathElement::new(vec![(x, y), (x + 26, y)], rgb(c).stroke_width(3))).map_err(de)?;
            }
            Swatch::Fill(c) | Swatch::Hatch(c) => {
                root.draw(&Rectangle::new([(x, y - 7), (x + 26, y + 7)], rgb(c).filled())).map_err(de)?;
                if matches!(item.swatch, Swatch::Hatch(_)) {
                    for d in (0..40).step_by(6) {
                        let (a, b) = ((x + d - 14).max(x), (x + d).min(x + 26));
                        if a < b {
                            let line = vec![(a, y + 7 - (a - (x + d - 14))), (b, y + 7 - (b - (x + d - 14)))];
                            root.draw(&PathElement::new(line, BLACK.stroke_width(2))).map_err(de)?;
                        }
                    }
                }
                root.draw(&Rectangle::new([(x, y - 7), (x + 26, y + 7)], RGBColor(60, 60, 60).stroke_width(1)))
                    .map_err(de)?;
            }
            Swatch::Dot(c) => {
                root.draw(&Circle::new((x + 13, y), 5, BLACK.filled())).map_err(de)?;
                root.draw(&Circle::new((x + 13, y), 4, rgb(c).filled())).map_err(de)?;
            }
            Swatch::Seed => {
                root.draw(&Circle::new((x + 13, y), 7, BLACK.filled())).map_err(de)?;
                root.draw(&Circle::new((x + 13, y), 4, WHITE.filled())).map_err(de)?;
            }
        }
        let style = font(13.0).color(&BLACK).pos(Pos::new(HPos::Left, VPos::Center));
        root.draw(&Text::new(item.text.clone(), (x + 34, y), style)).map_err(de)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shares_sum_to_100_and_land_in_the_right_bin() {
        let v = [-44.0, -1.0, 0.5, 0.5, 44.9, 80.0];
        let s = bin_shares(&v, 45.0, 1.0);
        assert_eq!(s.len(), 90);
        assert!((s.iter().sum::<f64>() - 100.0).abs() < 1e-9);
        assert!((s[45] - 200.0 / 6.0).abs() < 1e-9);
        assert!((s[89] - 200.0 / 6.0).abs() < 1e-9, "44.9 and the clamped 80");
        assert_eq!(bin_width(45.0), 2.0);
    }

    #[test]
    fn text_renders_without_system_fonts() {
        // A text-only picture must put dark pixels on the page: the embedded font works.
        let png = to_png(|root| {
            register_fonts();
            root.fill(&WHITE).map_err(de)?;
            root.draw(&Text::new("Shear 45°", (10, 10), font(40.0).color(&BLACK))).map_err(de)
        })
        .unwrap();
        let dec = png::Decoder::new(std::io::Cursor::new(png));
        let mut r = dec.read_info().unwrap();
        let mut buf = vec![0; r.output_buffer_size()];
        r.next_frame(&mut buf).unwrap();
        let dark = buf.chunks(3).filter(|p| p[0] < 100).count();
        assert!(dark > 200, "only {dark} dark pixels: text was not drawn");
    }
}
