//! The draw-in picture (`<ply>-draw-in.png/.svg`): the blank as cut, flat, and the ply as
//! draped, both seen in the plan its draw-in is measured in ([`crate::kinematic::draw_in`]),
//! every k-th fibre of each, with the edge points of the fibre and diagonal lines through the
//! seed and how far each moved in; for a blank formed with a binder, the binder's opening.
use super::render::{de, DrawResult, FONT};
use crate::geometry::Vector;
use crate::kinematic::draw_in::origin_tangents;
use crate::kinematic::provenance::DrawIn;
use crate::kinematic::{DrapeNet, NodeStatus};
use plotters::coord::Shift;
use plotters::prelude::*;

/// Fibres drawn across the larger side of the grid, about.
const FIBRES_DRAWN: usize = 24;
const FLAT_COLOUR: RGBColor = RGBColor(175, 175, 175);
const DRAPED_COLOUR: RGBColor = RGBColor(49, 130, 189);
const EDGE_COLOUR: RGBColor = RGBColor(215, 48, 39);
const BINDER_COLOUR: RGBColor = RGBColor(35, 139, 69);

/// The plan's axes: the warp at the seed in plan, and the normal across it turned so the weft at
/// the seed points along the second. None where the net has no fibres through its origin node.
fn plan_axes(net: &DrapeNet, normal: &Vector) -> Option<(Vector, Vector)> {
    let (warp, weft) = origin_tangents(net)?;
    let e1 = (warp - normal * normal.dot(&warp)).try_normalize(1e-12)?;
    let e2 = normal.cross(&e1);
    Some((e1, if weft.dot(&e2) < 0.0 { -e2 } else { e2 }))
}

/// Draw the picture of `net`'s draw-in `d`.
pub fn draw_plan<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    net: &DrapeNet,
    d: &DrawIn,
    stem: &str,
) -> DrawResult {
    root.fill(&WHITE).map_err(de)?;
    let normal = Vector::from(d.plan_normal);
    let (e1, e2) =
        plan_axes(net, &normal).ok_or("the net has no fibres through its origin node to draw the plan by")?;
    let (i0, j0) = net.origin_node;
    let o = net.positions[net.index(i0, j0)];
    let placed = |i: usize, j: usize| net.status[net.index(i, j)] == NodeStatus::Placed;
    // Millimetres in plan: the flat blank at its fabric coordinates, the draped ply projected.
    let flat =
        |i: usize, j: usize| ((i as f64 - i0 as f64) * net.spacing * 1e3, (j as f64 - j0 as f64) * net.spacing * 1e3);
    let draped = |i: usize, j: usize| {
        let v = net.positions[net.index(i, j)] - o;
        (v.dot(&e1) * 1e3, v.dot(&e2) * 1e3)
    };
    // The binder's opening (given in the plan across the stroke), seen in this plan.
    let opening: Option<Vec<(f64, f64)>> = net.meta.forming.as_ref().and_then(|f| {
        let [a0, a1] = f.plan_axes.map(Vector::from);
        let (o0, o1) = (a0.dot(&o.coords), a1.dot(&o.coords));
        f.binder.as_ref().map(|b| {
            let mut ring: Vec<(f64, f64)> = b
                .outline_m
                .iter()
                .map(|q| {
                    let r = a0 * (q[0] - o0) + a1 * (q[1] - o1);
                    (r.dot(&e1) * 1e3, r.dot(&e2) * 1e3)
                })
                .collect();
            ring.extend(ring.first().copied());
            ring
        })
    });
    let mut lo = (f64::INFINITY, f64::INFINITY);
    let mut hi = (f64::NEG_INFINITY, f64::NEG_INFINITY);
    for i in 0..net.nu {
        for j in 0..net.nv {
            if placed(i, j) {
                for (x, y) in [flat(i, j), draped(i, j)] {
                    lo = (lo.0.min(x), lo.1.min(y));
                    hi = (hi.0.max(x), hi.1.max(y));
                }
            }
        }
    }
    for &(x, y) in opening.iter().flatten() {
        lo = (lo.0.min(x), lo.1.min(y));
        hi = (hi.0.max(x), hi.1.max(y));
    }
    let binder = if opening.is_some() { ", the binder's opening (green)" } else { "" };
    let title = format!("Ply {stem}: draw-in, the blank flat (grey) and draped (blue) in plan{binder}");
    let root = root.titled(&title, (FONT, 22)).map_err(de)?;
    let (w, h) = root.dim_in_pixel();
    // Equal scales on both axes: widen the narrower range to the picture's proportions.
    let (cx, cy) = (0.5 * (lo.0 + hi.0), 0.5 * (lo.1 + hi.1));
    let (mut sx, mut sy) = (1.05 * (hi.0 - lo.0).max(1e-9), 1.05 * (hi.1 - lo.1).max(1e-9));
    let aspect = (w.saturating_sub(90)) as f64 / (h.saturating_sub(110)).max(1) as f64;
    if sx / sy < aspect {
        sx = sy * aspect;
    } else {
        sy = sx / aspect;
    }
    let mut chart = ChartBuilder::on(&root)
        .caption(d.describe(), (FONT, 15))
        .margin(15)
        .x_label_area_size(40)
        .y_label_area_size(55)
        .build_cartesian_2d((cx - 0.5 * sx)..(cx + 0.5 * sx), (cy - 0.5 * sy)..(cy + 0.5 * sy))
        .map_err(de)?;
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc("along the warp at the seed, mm")
        .y_desc("along the weft, mm")
        .label_style((FONT, 13))
        .draw()
        .map_err(de)?;
    let step = (net.nu.max(net.nv) / FIBRES_DRAWN).max(1);
    // Every step-th fibre through the origin node, in runs of placed nodes.
    let fibres = |at: &dyn Fn(usize, usize) -> (f64, f64)| -> Vec<Vec<(f64, f64)>> {
        let mut lines = Vec::new();
        let mut run = |nodes: &mut dyn Iterator<Item = (usize, usize)>| {
            let mut line = Vec::new();
            for (i, j) in nodes {
                if placed(i, j) {
                    line.push(at(i, j));
                } else if line.len() > 1 {
                    lines.push(std::mem::take(&mut line));
                } else {
                    line.clear();
                }
            }
            if line.len() > 1 {
                lines.push(line);
            }
        };
        for i in (0..net.nu).filter(|i| i.abs_diff(i0) % step == 0) {
            run(&mut (0..net.nv).map(|j| (i, j)));
        }
        for j in (0..net.nv).filter(|j| j.abs_diff(j0) % step == 0) {
            run(&mut (0..net.nu).map(|i| (i, j)));
        }
        lines
    };
    for line in fibres(&flat) {
        chart.draw_series(LineSeries::new(line, FLAT_COLOUR.stroke_width(1))).map_err(de)?;
    }
    for line in fibres(&draped) {
        chart.draw_series(LineSeries::new(line, DRAPED_COLOUR.stroke_width(1))).map_err(de)?;
    }
    if let Some(ring) = opening {
        chart.draw_series(LineSeries::new(ring, BINDER_COLOUR.stroke_width(2))).map_err(de)?;
    }
    for e in &d.edges {
        let [i, j] = e.node;
        let (f, p) = (flat(i, j), draped(i, j));
        chart.draw_series(LineSeries::new([f, p], EDGE_COLOUR.stroke_width(2))).map_err(de)?;
        chart.draw_series([Circle::new(p, 4, EDGE_COLOUR.filled())]).map_err(de)?;
        // The label beside the point, clear of its marker.
        let label = format!("{} {:.1} mm", e.line.name(), e.draw_in_m * 1e3);
        chart
            .draw_series([EmptyElement::at(p) + Text::new(label, (7, 4), (FONT, 13).into_font().color(&BLACK))])
            .map_err(de)?;
    }
    Ok(())
}
