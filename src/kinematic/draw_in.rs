//! Draw-in: how far the blank's edge moved in towards the seed, seen in plan, as the ply was
//! draped or formed. The blank is the fabric grid laid flat (node (i, j) at fabric coordinates
//! ((i - i0) d, (j - j0) d) from the origin node (i0, j0)); the plan is the plane normal to the
//! direction the ply was formed along (a flat sheet's normal, else the ply's own normal at the
//! seed). Along each of the eight fibre and diagonal lines through the origin node, the last
//! node the net reaches is the blank's edge there: its draw-in is its distance from the origin
//! node in the flat blank less its distance from it in plan. A fibre that stays inextensible
//! over a spherical cap from its pole, s along a meridian of radius R, draws in s - R sin(s/R).
use super::net::{DrapeNet, NodeStatus};
pub use super::provenance::{DrawIn, DrawInLine, EdgeDrawIn};
use crate::geometry::Vector;

/// The warp and weft tangents of `net` at its origin node (central differences where both
/// neighbours are placed, else one-sided); None where the origin node or a fibre through it is
/// missing.
pub fn origin_tangents(net: &DrapeNet) -> Option<(Vector, Vector)> {
    let (i0, j0) = net.origin_node;
    let placed = |i: usize, j: usize| net.status[net.index(i, j)] == NodeStatus::Placed;
    if !placed(i0, j0) {
        return None;
    }
    let tangent = |di: usize, dj: usize| -> Option<Vector> {
        let fwd = (i0 + di < net.nu && j0 + dj < net.nv && placed(i0 + di, j0 + dj))
            .then(|| net.positions[net.index(i0 + di, j0 + dj)]);
        let back =
            (i0 >= di && j0 >= dj && placed(i0 - di, j0 - dj)).then(|| net.positions[net.index(i0 - di, j0 - dj)]);
        let here = net.positions[net.index(i0, j0)];
        match (fwd, back) {
            (Some(f), Some(b)) => Some(f - b),
            (Some(f), None) => Some(f - here),
            (None, Some(b)) => Some(here - b),
            (None, None) => None,
        }
    };
    Some((tangent(1, 0)?, tangent(0, 1)?))
}

/// The ply's unit normal at the origin node of `net`, from the fibres through it
/// ([`origin_tangents`]).
pub fn seed_normal(net: &DrapeNet) -> Option<Vector> {
    let (warp, weft) = origin_tangents(net)?;
    warp.cross(&weft).try_normalize(0.0)
}

/// The draw-in of `net` in the plan normal to `plan_normal` (`plan_from`: `sheet` or `seed`);
/// None where the origin node is not placed or the normal is zero.
pub fn draw_in(net: &DrapeNet, plan_normal: &Vector, plan_from: &str) -> Option<DrawIn> {
    let n = plan_normal.try_normalize(0.0)?;
    let (i0, j0) = net.origin_node;
    let origin = net.index(i0, j0);
    if net.status[origin] != NodeStatus::Placed {
        return None;
    }
    let plan = |v: Vector| v - n * n.dot(&v);
    let mut edges = Vec::new();
    for line in DrawInLine::ALL {
        let (di, dj) = line.step();
        // Walk out from the origin node while the next node is placed.
        let mut k = 0usize;
        loop {
            let (i, j) = (i0 as isize + (k as isize + 1) * di, j0 as isize + (k as isize + 1) * dj);
            if i < 0 || j < 0 || i >= net.nu as isize || j >= net.nv as isize {
                break;
            }
            if net.status[net.index(i as usize, j as usize)] != NodeStatus::Placed {
                break;
            }
            k += 1;
        }
        if k == 0 {
            continue;
        }
        let (i, j) = ((i0 as isize + k as isize * di) as usize, (j0 as isize + k as isize * dj) as usize);
        let flat_m = k as f64 * net.spacing * ((di * di + dj * dj) as f64).sqrt();
        let plan_m = plan(net.positions[net.index(i, j)] - net.positions[origin]).norm();
        edges.push(EdgeDrawIn { line, node: [i, j], flat_m, plan_m, draw_in_m: flat_m - plan_m });
    }
    Some(DrawIn { plan_normal: [n.x, n.y, n.z], plan_from: plan_from.into(), edges })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Point;

    /// A net laid on the plane z = 0 with its grid scaled by `stretch` (1: as cut).
    fn plane_net(nu: usize, nv: usize, d: f64, stretch: f64) -> DrapeNet {
        let mut net = DrapeNet::new("p", d, nu, nv, (nu / 2, nv / 2));
        for i in 0..nu {
            for j in 0..nv {
                let k = net.index(i, j);
                net.positions[k] = Point::new(
                    stretch * d * (i as f64 - (nu / 2) as f64),
                    stretch * d * (j as f64 - (nv / 2) as f64),
                    0.0,
                );
                net.status[k] = NodeStatus::Placed;
            }
        }
        net
    }

    #[test]
    fn a_blank_lying_flat_draws_in_nothing_and_a_shrunk_one_by_its_shrinkage() {
        let net = plane_net(11, 7, 0.01, 1.0);
        let n = seed_normal(&net).unwrap();
        assert!((n.z.abs() - 1.0).abs() < 1e-12);
        let d = draw_in(&net, &n, "seed").unwrap();
        assert_eq!(d.edges.len(), 8);
        assert!(d.edges.iter().all(|e| e.draw_in_m.abs() < 1e-12), "{d:?}");
        // The weft reaches 3 nodes each way, the warp 5, the diagonals 3.
        let e = d.edges.iter().find(|e| e.line == DrawInLine::WarpPlus).unwrap();
        assert_eq!(e.node, [10, 3]);
        assert!((e.flat_m - 0.05).abs() < 1e-12);
        let e = d.edges.iter().find(|e| e.line == DrawInLine::MinusMinus).unwrap();
        assert_eq!(e.node, [2, 0]);
        let shrunk = draw_in(&plane_net(11, 7, 0.01, 0.9), &n, "seed").unwrap();
        for e in &shrunk.edges {
            assert!((e.draw_in_m - 0.1 * e.flat_m).abs() < 1e-12, "{e:?}");
        }
    }

    #[test]
    fn the_edge_is_where_the_net_stops_and_tilted_plans_foreshorten() {
        let mut net = plane_net(9, 9, 0.01, 1.0);
        // The warp line stops two nodes out: its third node was not placed.
        let k = net.index(7, 4);
        net.status[k] = NodeStatus::ShearLimit;
        let d = draw_in(&net, &Vector::z(), "sheet").unwrap();
        let e = d.edges.iter().find(|e| e.line == DrawInLine::WarpPlus).unwrap();
        assert_eq!(e.node, [6, 4]);
        // Seen in a plan tilted by 60 deg about the weft, the warp shows half its length.
        let tilted = Vector::new(60f64.to_radians().sin(), 0.0, 60f64.to_radians().cos());
        let d = draw_in(&net, &tilted, "sheet").unwrap();
        let e = d.edges.iter().find(|e| e.line == DrawInLine::WarpMinus).unwrap();
        assert!((e.plan_m - 0.5 * e.flat_m).abs() < 1e-12, "{e:?}");
        let e = d.edges.iter().find(|e| e.line == DrawInLine::WeftPlus).unwrap();
        assert!(e.draw_in_m.abs() < 1e-12, "{e:?}");
        // Without its origin node there is nothing to measure from.
        let k = net.index(4, 4);
        net.status[k] = NodeStatus::OffTool;
        assert!(draw_in(&net, &Vector::z(), "sheet").is_none());
    }
}
