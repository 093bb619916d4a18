//! Drawing the pictures: a shaded map of a ply on its tool with a colour bar, and a histogram.
//! Everything is laid out in pixels once and drawn the same way on the PNG and the SVG backend.
use super::view::{for_each_cell, nice_ceil, nice_floor, shear_colour, Fit, View};
use crate::geometry::Point;
use crate::kinematic::DrapeNet;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::sync::Once;

/// Picture size in pixels (PNG) and user units (SVG).
pub const WIDTH: u32 = 1000;
/// Picture height, see [`WIDTH`].
pub const HEIGHT: u32 = 720;

/// Font family every text of the pictures uses; registered from the embedded DejaVu Sans.
const FONT: &str = "sans-serif";

/// Above this many triangles the tool is drawn as a depth-buffered raster of
/// `TOOL_BIN_PX`-pixel bins (merged into runs) instead of one polygon per triangle, so a
/// 200k-triangle tool stays fast and its SVG small.
pub const TOOL_TRIANGLE_LIMIT: usize = 6000;
/// Bin size of the rasterised tool, pixels.
const TOOL_BIN_PX: usize = 2;
/// Grey levels of the tool shading (lit faces light, grazing faces darker).
const TOOL_GREY_LEVELS: f64 = 8.0;
/// Cells whose mean projected edge is longer than this (pixels) get an outline.
const OUTLINE_MIN_EDGE_PX: f64 = 7.0;
/// Colour of cell outlines.
const OUTLINE: RGBColor = RGBColor(95, 95, 95);
/// Width of the colour-bar column, pixels.
const BAR_COLUMN_PX: u32 = 190;
/// Height of the title band, pixels.
const TITLE_PX: u32 = 64;
/// Margin around the ply in the map, as a fraction of its extent.
const MAP_PAD: f64 = 0.08;

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

fn de<E: std::fmt::Display>(e: E) -> String {
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

/// A tool triangle in pixels and its grey.
pub type ToolTriangle = ([(i32, i32); 3], u8);
/// A cell in pixels and its colour.
pub type PaintedCell = ([(i32, i32); 4], [u8; 3]);

/// A map picture laid out in pixels: the tool underneath, the cells on top, a colour bar.
#[derive(Debug, Clone, Default)]
pub struct MapPicture {
    pub title: String,
    /// Small text under the title (view, tool).
    pub subtitle: String,
    /// Tool raster runs: ([x0, y0, x1, y1], grey), drawn first.
    pub tool_runs: Vec<([i32; 4], u8)>,
    /// Tool triangles in paint order (far to near), with their grey.
    pub tool_triangles: Vec<ToolTriangle>,
    /// Cells in paint order (far to near) with their colour.
    pub cells: Vec<PaintedCell>,
    /// Whether cells get outlines.
    pub outlines: bool,
    /// Scale bar: left pixel, baseline pixel, length in pixels, label.
    pub scale_bar: Option<(i32, i32, i32, String)>,
    /// Colour bar limit (degrees, symmetric) and label.
    pub limit: f64,
    pub bar_label: String,
    pub marks: Vec<Mark>,
    /// The map's pixel rectangle [x0, y0, x1, y1]: anything drawn outside it is painted over.
    pub frame: [i32; 4],
}

/// What the tool layer of a map is made from.
pub struct ToolLayer<'a> {
    pub vertices: &'a [Point],
    pub triangles: &'a [[u32; 3]],
}

/// Lay out the map of `net` with cell values `values` (degrees, by cell index
/// `i * (nv - 1) + j`; cells without a value are left out), on `tool` if given.
pub fn layout_map(net: &DrapeNet, values: &[Option<f64>], tool: Option<&ToolLayer>, limit: f64) -> MapPicture {
    let view = View::for_net(net);
    // Project cells; the fit is the ply's extent plus a margin.
    let mut cells3 = Vec::new();
    let mut b = [f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY];
    for_each_cell(net, |k, c| {
        let Some(v) = values.get(k).copied().flatten().filter(|v| v.is_finite()) else { return };
        let p = c.map(|p| view.project(&p));
        for q in &p {
            b = [b[0].min(q.0), b[1].max(q.0), b[2].min(q.1), b[3].max(q.1)];
        }
        let depth = p.iter().map(|q| q.2).sum::<f64>() / 4.0;
        cells3.push((depth, p, v));
    });
    let (left, top) = (10.0, TITLE_PX as f64);
    let (w, h) = ((WIDTH - BAR_COLUMN_PX) as f64 - 20.0, HEIGHT as f64 - top - 40.0);
    let frame = [left as i32, top as i32, (left + w) as i32, (top + h) as i32];
    let mut pic = MapPicture { limit, frame, ..Default::default() };
    if cells3.is_empty() {
        return pic;
    }
    let pad = MAP_PAD * (b[1] - b[0]).max(b[3] - b[2]);
    let bounds = [b[0] - pad, b[1] + pad, b[2] - pad, b[3] + pad];
    let fit = Fit::new(bounds, left, top, w, h);
    let px = |x: f64, y: f64| {
        let (a, b) = fit.pixel(x, y);
        (a.round() as i32, b.round() as i32)
    };
    if let Some(t) = tool {
        let clip = [left, top, left + w, top + h];
        if t.triangles.len() > TOOL_TRIANGLE_LIMIT {
            pic.tool_runs = raster_tool(t, &view, &fit, clip);
        } else {
            let mut tris: Vec<(f64, ToolTriangle)> = t
                .triangles
                .iter()
                .filter_map(|tri| {
                    let c = tri.map(|k| t.vertices[k as usize]);
                    let p = c.map(|p| view.project(&p));
                    let pix = p.map(|q| px(q.0, q.1));
                    let out = |k: usize, lo: f64, hi: f64| {
                        let v: Vec<f64> = pix.iter().map(|q| if k == 0 { q.0 as f64 } else { q.1 as f64 }).collect();
                        v.iter().all(|&x| x < lo) || v.iter().all(|&x| x > hi)
                    };
                    if out(0, clip[0], clip[2]) || out(1, clip[1], clip[3]) {
                        return None;
                    }
                    Some(((p[0].2 + p[1].2 + p[2].2) / 3.0, (pix, tool_grey(&c, &view))))
                })
                .collect();
            tris.sort_by(|a, b| a.0.total_cmp(&b.0));
            pic.tool_triangles = tris.into_iter().map(|(_, t)| t).collect();
        }
    }
    cells3.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut edge_sum = 0.0;
    for (_, p, v) in &cells3 {
        let pix = p.map(|q| px(q.0, q.1));
        edge_sum += ((pix[1].0 - pix[0].0) as f64).hypot((pix[1].1 - pix[0].1) as f64);
        pic.cells.push((pix, shear_colour(*v, limit)));
    }
    pic.outlines = edge_sum / cells3.len() as f64 > OUTLINE_MIN_EDGE_PX;
    // Scale bar of a round length near a fifth of the map width.
    let len_m = nice_floor(0.2 * w / fit.scale);
    let label = if len_m < 1.0 { format!("{} mm", fmt_len(len_m * 1e3)) } else { format!("{} m", fmt_len(len_m)) };
    pic.scale_bar = Some((left as i32 + 20, (top + h) as i32 + 22, (len_m * fit.scale).round() as i32, label));
    pic
}

fn fmt_len(x: f64) -> String {
    if x >= 1.0 {
        format!("{x:.0}")
    } else {
        format!("{x}")
    }
}

/// Grey level of a tool triangle: lighter where it faces the viewer.
fn tool_grey(c: &[Point; 3], view: &View) -> u8 {
    let n = (c[1] - c[0]).cross(&(c[2] - c[0]));
    let cos = n.try_normalize(0.0).map_or(0.0, |n| n.dot(&view.toward).abs());
    grey_of_level((cos * TOOL_GREY_LEVELS).floor().min(TOOL_GREY_LEVELS - 1.0))
}

fn grey_of_level(level: f64) -> u8 {
    (178.0 + level * (52.0 / (TOOL_GREY_LEVELS - 1.0))).round() as u8
}

/// The greys (r = g = b) the tool can be painted in.
pub fn tool_greys() -> Vec<u8> {
    (0..TOOL_GREY_LEVELS as usize).map(|k| grey_of_level(k as f64)).collect()
}

/// Rasterise the tool into bins with a depth buffer, then merge each row's equal greys into runs.
fn raster_tool(t: &ToolLayer, view: &View, fit: &Fit, clip: [f64; 4]) -> Vec<([i32; 4], u8)> {
    let bin = TOOL_BIN_PX as f64;
    let nx = ((clip[2] - clip[0]) / bin).ceil() as usize;
    let ny = ((clip[3] - clip[1]) / bin).ceil() as usize;
    let mut depth = vec![f64::NEG_INFINITY; nx * ny];
    let mut grey = vec![0u8; nx * ny];
    for tri in t.triangles {
        let c = tri.map(|k| t.vertices[k as usize]);
        let p = c.map(|p| {
            let (x, y, z) = view.project(&p);
            let (a, b) = fit.pixel(x, y);
            ((a - clip[0]) / bin, (b - clip[1]) / bin, z)
        });
        let area = (p[1].0 - p[0].0) * (p[2].1 - p[0].1) - (p[2].0 - p[0].0) * (p[1].1 - p[0].1);
        if area.abs() < 1e-12 {
            continue;
        }
        let lo = |k: fn(&(f64, f64, f64)) -> f64| p.iter().map(k).fold(f64::INFINITY, f64::min);
        let hi = |k: fn(&(f64, f64, f64)) -> f64| p.iter().map(k).fold(f64::NEG_INFINITY, f64::max);
        let (x0, x1) = (lo(|q| q.0).floor().max(0.0), hi(|q| q.0).ceil().min(nx as f64));
        let (y0, y1) = (lo(|q| q.1).floor().max(0.0), hi(|q| q.1).ceil().min(ny as f64));
        if x0 >= x1 || y0 >= y1 {
            continue;
        }
        let g = tool_grey(&c, view);
        for iy in y0 as usize..y1 as usize {
            for ix in x0 as usize..x1 as usize {
                let (x, y) = (ix as f64 + 0.5, iy as f64 + 0.5);
                // Barycentric weights of the bin centre.
                let w1 = ((x - p[0].0) * (p[2].1 - p[0].1) - (p[2].0 - p[0].0) * (y - p[0].1)) / area;
                let w2 = ((p[1].0 - p[0].0) * (y - p[0].1) - (x - p[0].0) * (p[1].1 - p[0].1)) / area;
                let w0 = 1.0 - w1 - w2;
                if w0 < 0.0 || w1 < 0.0 || w2 < 0.0 {
                    continue;
                }
                let z = w0 * p[0].2 + w1 * p[1].2 + w2 * p[2].2;
                let k = iy * nx + ix;
                if z > depth[k] {
                    depth[k] = z;
                    grey[k] = g;
                }
            }
        }
    }
    let mut runs = Vec::new();
    for iy in 0..ny {
        let mut ix = 0;
        while ix < nx {
            let g = grey[iy * nx + ix];
            let start = ix;
            while ix < nx && grey[iy * nx + ix] == g {
                ix += 1;
            }
            if g != 0 {
                let px = |i: usize| (clip[0] + i as f64 * bin).round() as i32;
                let py = |i: usize| (clip[1] + i as f64 * bin).round() as i32;
                runs.push(([px(start), py(iy), px(ix), py(iy + 1)], g));
            }
        }
    }
    runs
}

fn font(size: f64) -> FontDesc<'static> {
    (FONT, size).into_font()
}

fn bold(size: f64) -> FontDesc<'static> {
    (FONT, size, FontStyle::Bold).into_font()
}

/// Draw a laid-out map on `root` (the whole picture).
pub fn draw_map<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, pic: &MapPicture) -> DrawResult {
    register_fonts();
    root.fill(&WHITE).map_err(de)?;
    for (r, g) in &pic.tool_runs {
        let c = RGBColor(*g, *g, *g);
        root.draw(&Rectangle::new([(r[0], r[1]), (r[2], r[3])], c.filled())).map_err(de)?;
    }
    for (p, g) in &pic.tool_triangles {
        let c = RGBColor(*g, *g, *g);
        root.draw(&Polygon::new(p.to_vec(), c.filled())).map_err(de)?;
    }
    for (p, c) in &pic.cells {
        root.draw(&Polygon::new(p.to_vec(), rgb(*c).filled())).map_err(de)?;
        if pic.outlines {
            let mut ring = p.to_vec();
            ring.push(p[0]);
            root.draw(&PathElement::new(ring, OUTLINE.stroke_width(1))).map_err(de)?;
        }
    }
    // Tool triangles and cells may reach past the map: paint the margins white again.
    let [x0, y0, x1, y1] = pic.frame;
    let (w, h) = (WIDTH as i32, HEIGHT as i32);
    for r in [[0, 0, w, y0], [0, y1, w, h], [0, 0, x0, h], [x1, 0, w, h]] {
        root.draw(&Rectangle::new([(r[0], r[1]), (r[2], r[3])], WHITE.filled())).map_err(de)?;
    }
    root.draw(&Text::new(pic.title.clone(), (20, 14), bold(24.0).color(&BLACK))).map_err(de)?;
    root.draw(&Text::new(pic.subtitle.clone(), (20, 44), font(14.0).color(&RGBColor(90, 90, 90)))).map_err(de)?;
    if pic.cells.is_empty() {
        let style = font(20.0).color(&BLACK).pos(Pos::new(HPos::Center, VPos::Center));
        root.draw(&Text::new(
            "no complete cells to draw",
            (((WIDTH - BAR_COLUMN_PX) / 2) as i32, (HEIGHT / 2) as i32),
            style,
        ))
        .map_err(de)?;
    }
    if let Some((x, y, len, label)) = &pic.scale_bar {
        root.draw(&Rectangle::new([(*x, *y - 3), (*x + *len, *y + 3)], BLACK.filled())).map_err(de)?;
        let style = font(14.0).color(&BLACK).pos(Pos::new(HPos::Left, VPos::Center));
        root.draw(&Text::new(label.clone(), (*x + *len + 8, *y), style)).map_err(de)?;
    }
    draw_colour_bar(root, pic.limit, &pic.bar_label, &pic.marks)
}

/// The colour bar in the right column: the diverging map from -limit to +limit with ticks, a
/// label and marked lines (the locking angle).
fn draw_colour_bar<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    limit: f64,
    label: &str,
    marks: &[Mark],
) -> DrawResult {
    let (_, column) = root.split_horizontally(WIDTH - BAR_COLUMN_PX);
    let mut chart = ChartBuilder::on(&column)
        .margin_top(TITLE_PX + 10)
        .margin_bottom(40)
        .margin_right(85)
        .y_label_area_size(58)
        .build_cartesian_2d(0f64..1f64, -limit..limit)
        .map_err(de)?;
    let step_label = |v: &f64| if limit >= 5.0 { format!("{v:.0}") } else { format!("{v:.2}") };
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
    let h = 2.0 * limit / STEPS as f64;
    chart
        .draw_series((0..STEPS).map(|k| {
            let a = -limit + k as f64 * h;
            Rectangle::new([(0.0, a), (1.0, a + h)], rgb(shear_colour(a + 0.5 * h, limit)).filled())
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
    let mut out = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut out, WIDTH, HEIGHT);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let mut w = enc.write_header().map_err(de)?;
        w.write_image_data(&buf).map_err(de)?;
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
