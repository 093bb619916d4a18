//! Checks run before any output file is opened: a net that would need NaN, infinity or a
//! made-up value in a file is refused with an error naming the node or cell.
use super::ExportError;
use crate::kinematic::{DrapeNet, NodeStatus};
use rayon::prelude::*;

/// Number of cells, `(nu - 1) * (nv - 1)`, zero for a degenerate grid (never underflows).
pub(crate) fn cell_count(net: &DrapeNet) -> usize {
    net.nu.saturating_sub(1) * net.nv.saturating_sub(1)
}

/// Cells (i, j) in file order (index i * (nv - 1) + j).
pub(crate) fn cells(net: &DrapeNet) -> impl Iterator<Item = (usize, usize)> + '_ {
    let (cu, cv) = (net.nu.saturating_sub(1), net.nv.saturating_sub(1));
    (0..cu).flat_map(move |i| (0..cv).map(move |j| (i, j)))
}

/// The ply name must be usable as a file name inside the output directory.
pub(crate) fn check_name(net: &DrapeNet) -> Result<(), ExportError> {
    let bad = |reason: &str| Err(ExportError::BadName { ply: net.name.clone(), reason: reason.to_string() });
    if net.name.is_empty() {
        return bad("it is empty");
    }
    if net.name == "." || net.name == ".." {
        return bad("it is a directory name");
    }
    if net.name.chars().any(|c| matches!(c, '/' | '\\' | '\0') || c.is_control()) {
        return bad("it contains a path separator or a control character");
    }
    Ok(())
}

/// Consistency and finiteness of everything a writer reads. `frames`: also check each complete
/// cell's fibre frame (VTU, CSV).
pub(crate) fn check_net(net: &DrapeNet, frames: bool) -> Result<(), ExportError> {
    check_net_shears(net, frames).map(|_| ())
}

/// [`check_net`], giving back each cell's shear ([`DrapeNet::cell_shears`]) that the check
/// computed, for the writers and the statistics to use instead of computing them again.
pub(crate) fn check_net_shears(net: &DrapeNet, frames: bool) -> Result<Vec<Option<f64>>, ExportError> {
    let bad = |reason: String| Err(ExportError::BadNet { ply: net.name.clone(), reason });
    if net.nu == 0 || net.nv == 0 {
        return bad(format!("the grid is empty ({} x {} nodes)", net.nu, net.nv));
    }
    let Some(n) = net.nu.checked_mul(net.nv) else {
        return bad(format!("the grid {} x {} is too large", net.nu, net.nv));
    };
    for (what, len) in
        [("positions", net.positions.len()), ("status", net.status.len()), ("triangles", net.triangles.len())]
    {
        if len != n {
            return bad(format!("it has {len} {what} for a {} x {} grid ({n} nodes)", net.nu, net.nv));
        }
    }
    if let Some(c) = &net.meta.contact {
        for (what, len) in [("state", c.state.len()), ("slip_m", c.slip_m.len()), ("pressure_pa", c.pressure_pa.len())]
        {
            if len != n {
                return bad(format!(
                    "meta.contact.{what} has {len} entries for a {} x {} grid ({n} nodes)",
                    net.nu, net.nv
                ));
            }
        }
        let odd = c.slip_m.iter().chain(&c.pressure_pa).flatten().find(|v| !v.is_finite());
        if let Some(v) = odd {
            return bad(format!("meta.contact holds a slip or pressure of {v}"));
        }
    }
    if let Some(w) = &net.meta.wrinkles {
        let cells = cell_count(net);
        let lists = [
            ("waviness_m", &w.waviness_m),
            ("tool_gap_m", &w.tool_gap_m),
            ("bending_energy_density_j_m2", &w.bending_energy_density_j_m2),
        ];
        for (what, list) in lists {
            // Without a material card the bending list is empty.
            if list.len() != cells && !(what.starts_with("bending") && list.is_empty()) {
                return bad(format!(
                    "meta.wrinkles.{what} has {} entries for a {} x {} grid ({cells} cells)",
                    list.len(),
                    net.nu,
                    net.nv
                ));
            }
            if let Some(v) = list.iter().flatten().find(|v| !v.is_finite()) {
                return bad(format!("meta.wrinkles.{what} holds {v}"));
            }
        }
        // Without the wave test (a record written before it) the list is empty.
        if !w.undulating.is_empty() && w.undulating.len() != cells {
            return bad(format!(
                "meta.wrinkles.undulating has {} entries for a {} x {} grid ({cells} cells)",
                w.undulating.len(),
                net.nu,
                net.nv
            ));
        }
        let s = &w.summary;
        let figures =
            [Some(s.threshold_m), Some(s.wrinkled_area_m2), s.max_waviness_m, s.max_tool_gap_m, s.wave_bend_m];
        if let Some(v) = figures.into_iter().flatten().chain(s.max_bending_energy_density_j_m2).find(|v| !v.is_finite())
        {
            return bad(format!("meta.wrinkles holds a figure of {v}"));
        }
    }
    let (i0, j0) = net.origin_node;
    if i0 >= net.nu || j0 >= net.nv {
        return bad(format!("the origin node ({i0}, {j0}) lies outside the {} x {} grid", net.nu, net.nv));
    }
    if !(net.spacing.is_finite() && net.spacing > 0.0) {
        return bad(format!("the spacing is {} (must be finite and positive)", net.spacing));
    }
    let t = &net.timing;
    for (what, v) in [("load", t.load_ms), ("generators", t.generators_ms), ("fill", t.fill_ms), ("total", t.total_ms)]
    {
        if !v.is_finite() {
            return bad(format!("the {what} time is {v} ms"));
        }
    }
    // Nodes and cells are checked in parallel; the error is the one of the first bad node, or
    // else of the first bad cell, in file order, as a serial check would find.
    let nv = net.nv;
    let bad_node = (0..n)
        .into_par_iter()
        .with_min_len(1 << 14)
        .find_first(|&k| net.status[k] == NodeStatus::Placed && !net.positions[k].coords.iter().all(|c| c.is_finite()));
    if let Some(k) = bad_node {
        let p = net.positions[k];
        return bad(format!("node ({}, {}) is placed but its position is ({}, {}, {})", k / nv, k % nv, p.x, p.y, p.z));
    }
    let cv = nv - 1;
    let shears = net.cell_shears();
    let bad_cell = (0..shears.len())
        .into_par_iter()
        .with_min_len(1 << 13)
        .find_first(|&k| cell_problem(net, k / cv, k % cv, shears[k], frames).is_some());
    if let Some(reason) = bad_cell.and_then(|k| cell_problem(net, k / cv, k % cv, shears[k], frames)) {
        return bad(reason);
    }
    Ok(shears)
}

/// What is wrong with cell (i, j) of shear `shear` (its [`DrapeNet::cell_shear`]), if anything:
/// a non-finite shear, or (`frames`) no finite fibre frame.
fn cell_problem(net: &DrapeNet, i: usize, j: usize, shear: Option<f64>, frames: bool) -> Option<String> {
    let g = shear?;
    if !g.to_degrees().is_finite() {
        return Some(format!("cell ({i}, {j}) has a shear angle of {g} rad"));
    }
    // A complete cell has every wrinkle measure the net records (the lengths were checked).
    if let Some(w) = &net.meta.wrinkles {
        let k = i * (net.nv - 1) + j;
        let missing = [("waviness_m", &w.waviness_m), ("tool_gap_m", &w.tool_gap_m)]
            .into_iter()
            .chain(
                (!w.bending_energy_density_j_m2.is_empty())
                    .then_some(("bending_energy_density_j_m2", &w.bending_energy_density_j_m2)),
            )
            .find(|(_, list)| list[k].is_none());
        if let Some((what, _)) = missing {
            return Some(format!("cell ({i}, {j}) is complete but meta.wrinkles.{what} has no value for it"));
        }
        if !w.undulating.is_empty() && w.undulating[k].is_none() {
            return Some(format!("cell ({i}, {j}) is complete but meta.wrinkles.undulating has no value for it"));
        }
    }
    if frames {
        match net.cell_frame(i, j) {
            None => {
                return Some(format!(
                    "cell ({i}, {j}) is degenerate: its warp, weft or normal direction has zero length"
                ))
            }
            Some(f) => {
                let all = f.centre.coords.iter().chain(&f.warp).chain(&f.weft).chain(&f.normal);
                if !all.into_iter().all(|c| c.is_finite()) {
                    return Some(format!("cell ({i}, {j}) has a non-finite centre or fibre direction"));
                }
            }
        }
    }
    None
}
