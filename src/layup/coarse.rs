//! Forming a blank coarse to fine (`coarse_levels`): the grids a blank is solved on, coarsest
//! first, and how a formed grid's shape carries to the grid of half its spacing. Node (i, j) of
//! a grid is node (2 i, 2 j) of the next finer one: the origin node and the blank's corners keep
//! their fabric coordinates, so the finer grid's sheet and blank are the ply's own at that
//! spacing.
//!
//! Why: the stroke's increments, and the wrinkles the flange buckles into step by step, are most
//! of a formed ply's iterations (see ARCHITECTURE, "Forming coarse to fine"); on a grid of twice
//! the spacing there are half the increments and a quarter of the nodes; the finer grids follow
//! the path the coarse one took.
use crate::geometry::Point;
use crate::kinematic::DrapeNet;

/// Most coarse levels a ply may ask for (a grid 8 times coarser: at 5 mm that is 40 mm, 8 or 9
/// cells across the double dome's 0.34 m wide blank).
pub const MAX_COARSE_LEVELS: usize = 3;

/// The grid of `nu` x `nv` nodes with its origin node at `origin`, at `factor` times its
/// spacing (its nodes every `factor`-th node of the grid): `(nu, nv, origin)`, or why there is
/// none (the grid's cells each side of the origin node are not a multiple of `factor`).
pub fn coarser_grid(
    nu: usize,
    nv: usize,
    origin: (usize, usize),
    factor: usize,
) -> Result<(usize, usize, (usize, usize)), String> {
    let fits = |n: usize, o: usize| o < n && o.is_multiple_of(factor) && (n - 1 - o).is_multiple_of(factor);
    if !(fits(nu, origin.0) && fits(nv, origin.1)) {
        // The least grid with the origin node in the middle that covers this one and fits.
        let fitting = |n: usize, o: usize| 2 * o.max(n.saturating_sub(1 + o)).div_ceil(factor) * factor + 1;
        return Err(format!(
            "a grid of {nu} x {nv} nodes with its origin node at [{}, {}] has no grid at {factor} times its spacing: the cells each side of the origin node must be a multiple of {factor} (for example grid = [{}, {}] with the origin node in the middle)",
            origin.0,
            origin.1,
            fitting(nu, origin.0),
            fitting(nv, origin.1),
        ));
    }
    Ok(((nu - 1) / factor + 1, (nv - 1) / factor + 1, (origin.0 / factor, origin.1 / factor)))
}

/// The positions of `fine`'s nodes (a grid of half `coarse`'s spacing, [`coarser_grid`] of it
/// with factor 2) where the formed `coarse` net puts them: bilinear between the coarse cell's
/// placed corners (their mean where some corner is not placed); `fine`'s own position where
/// none is.
pub fn prolong(coarse: &DrapeNet, fine: &DrapeNet) -> Vec<Point> {
    debug_assert_eq!((fine.nu, fine.nv), (2 * coarse.nu - 1, 2 * coarse.nv - 1));
    let mut out = fine.positions.clone();
    for i in 0..fine.nu {
        for j in 0..fine.nv {
            let (i0, j0) = (i / 2, j / 2);
            let (i1, j1) = ((i0 + i % 2).min(coarse.nu - 1), (j0 + j % 2).min(coarse.nv - 1));
            let corners = [(i0, j0), (i1, j0), (i0, j1), (i1, j1)];
            let placed: Vec<Point> = corners.iter().filter_map(|&(a, b)| coarse.node(a, b)).collect();
            if !placed.is_empty() {
                // A fine node lies on a coarse node, an edge's midpoint or a cell's centre: the
                // corners' mean is the bilinear value there.
                let sum = placed.iter().fold(nalgebra::Vector3::zeros(), |acc, p| acc + p.coords);
                out[fine.index(i, j)] = Point::from(sum / placed.len() as f64);
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_grid_has_a_coarser_one_where_its_cells_each_side_of_the_origin_divide() {
        assert_eq!(coarser_grid(113, 113, (56, 56), 2), Ok((57, 57, (28, 28))));
        assert_eq!(coarser_grid(113, 113, (56, 56), 4), Ok((29, 29, (14, 14))));
        assert_eq!(coarser_grid(21, 17, (4, 8), 4), Ok((6, 5, (1, 2))));
        let e = coarser_grid(112, 113, (56, 56), 2).unwrap_err();
        assert!(e.contains("multiple of 2") && e.contains("grid = [113, 113]"), "{e}");
        assert!(coarser_grid(113, 113, (55, 56), 2).is_err());
    }
}
