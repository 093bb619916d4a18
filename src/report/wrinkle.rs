//! The wrinkle map of a ply (`<ply>-wrinkles.png`): each cell by its waviness (the amplitude of
//! its undulation about the ply's own smoothed surface and about the tool, the smaller,
//! `meta.wrinkles`, see `kinematic::wrinkle`), on the shear map's views and colours from zero,
//! the wrinkled cells hatched (wavier than the ply's threshold where the ply undulates) and the
//! threshold marked on the bar.
use super::render::{LegendItem, Mark, ShadedPicture, Swatch};
use super::shade::{self, CellPaint, PlyScene, ToolMesh};
use super::view::{nice_ceil, shear_colour};
use crate::kinematic::provenance::{WrinkleRecord, WrinkleThresholdFrom};
use crate::kinematic::DrapeNet;

/// Head room of the colour bar above the larger of the largest waviness and the threshold, so
/// the threshold's mark sits inside the bar.
const BAR_MARGIN: f64 = 1.05;

/// The wrinkle map of `net` from its `record`: the scene to draw on the shear map's views and
/// the picture's title, bar and legend.
pub(super) fn wrinkle_picture<'a>(
    net: &'a DrapeNet,
    record: &WrinkleRecord,
    tool: Option<ToolMesh<'a>>,
    stem: &str,
) -> (PlyScene<'a>, ShadedPicture) {
    let s = &record.summary;
    let threshold_mm = s.threshold_m * 1e3;
    let largest_mm = s.max_waviness_m.unwrap_or(0.0) * 1e3;
    let limit = nice_ceil((largest_mm.max(threshold_mm) * BAR_MARGIN).max(1e-3));
    let paint: Vec<Option<CellPaint>> = (0..net.num_cells())
        .map(|c| {
            let w = record.waviness_m.get(c).copied().flatten()?;
            Some(CellPaint { colour: shear_colour(w * 1e3, limit), hatch: record.wrinkled(c) == Some(true) })
        })
        .collect();
    let scene = PlyScene::new(net, tool, paint, false);
    let gap = s.max_tool_gap_m.map_or("-".to_string(), |g| format!("{:.2} mm", g * 1e3));
    let from = match s.threshold_from {
        WrinkleThresholdFrom::Thickness => "ply thickness",
        WrinkleThresholdFrom::Default => "default, no thickness",
    };
    let subtitle = format!(
        "about the ply's own surface and the tool (the smaller), σ = {} spacings: largest {largest_mm:.3} mm, threshold {threshold_mm:.3} mm ({from}); largest tool gap {gap}",
        s.smoothing_spacings
    );
    let pic = ShadedPicture {
        title: format!("Ply {stem}: wrinkles (waviness)"),
        subtitle,
        limit,
        from_zero: true,
        bar_label: "waviness (mm)".into(),
        marks: vec![Mark { value: threshold_mm, label: format!("{threshold_mm:.2} mm") }],
        legend: vec![
            LegendItem {
                swatch: Swatch::Hatch(shear_colour(limit, limit)),
                text: format!("wrinkled: {} cells, {:.4} m²", s.wrinkled_cells, s.wrinkled_area_m2),
            },
            LegendItem { swatch: Swatch::Line(shade::EDGE_LINE), text: "ply edge".into() },
            LegendItem { swatch: Swatch::Fill(shade::TOOL_BASE), text: "tool".into() },
        ],
    };
    (scene, pic)
}
