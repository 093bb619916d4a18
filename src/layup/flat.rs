//! Flat patterns: the cutting outline of a ply, the draped net unfolded onto its flat grid.
//!
//! A woven ply is cut unsheared, so node (i, j) of a [`DrapeNet`] lies flat at
//! `((i - i0) d, (j - j0) d)`: warp along +x, weft along +y, `d` the net spacing and `(i0, j0)`
//! the origin (seed) node, which sits at (0, 0). A cell belongs to the pattern when its four
//! corners were placed; the pattern is the union of those unit squares and its outline is the
//! exact boundary of that union, traced on the integer grid.
//!
//! Trimming: a ply draped with an outline (`Extent::Outline`) has every node outside the outline
//! already refused (`outside_outline`), so the union of complete cells *is* the ply trimmed to its
//! outline, at the resolution of the net (a staircase within one spacing d of the true outline).
//! Nodes lost for other reasons (off the tool, shear limit, folds) are trimmed the same way: the
//! pattern is the fabric that actually lies on the tool. A cutting allowance can be added all
//! round with [`flat_pattern_with_margin`].
use crate::kinematic::DrapeNet;
use std::collections::HashMap;

/// Why a flat pattern or a nesting could not be made.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FlatError {
    /// The net has no cell with four placed corners.
    #[error("ply '{ply}' has no complete cell (no cell with all four corners placed), so it has no flat pattern. Check the drape of this ply: its seed, size and the node statuses in its .drape.json.")]
    NoCells {
        /// The ply.
        ply: String,
    },
    /// A cutting allowance that is not a length.
    #[error("ply '{ply}': the cutting margin {margin} is not zero or a positive length in metres. Fix it in the scene file.")]
    BadMargin {
        /// The ply.
        ply: String,
        /// The margin, m.
        margin: f64,
    },
    /// The net's spacing cannot scale a pattern.
    #[error("ply '{ply}': the net spacing {spacing} is not a positive finite length, so the pattern cannot be unfolded. Re-create the net with `drape run`.")]
    BadSpacing {
        /// The ply.
        ply: String,
        /// The spacing, m.
        spacing: f64,
    },
    /// A nesting parameter is out of range.
    #[error("nesting: {field} = {value} {reason}. Fix it in the scene file.")]
    BadNestParameter {
        /// The parameter.
        field: &'static str,
        /// Its value.
        value: f64,
        /// What it must be.
        reason: &'static str,
    },
    /// A pattern does not fit across the roll in any allowed orientation.
    #[error("ply '{ply}' is {across:.6} m across the roll ({orientation}) but the roll is only {roll_width:.6} m wide: {excess:.6} m too wide. Use a wider roll, allow a 90 degree turn if the material permits it, or split the ply.")]
    TooWide {
        /// The ply.
        ply: String,
        /// Its extent across the roll, m.
        across: f64,
        /// The roll width, m.
        roll_width: f64,
        /// How much too wide, m.
        excess: f64,
        /// How it was turned.
        orientation: &'static str,
    },
}

/// One connected piece of a pattern (cells joined through edges; cells that only touch at a
/// corner are separate pieces).
#[derive(Debug, Clone, PartialEq)]
pub struct Region {
    /// Closed loops (last vertex joins the first, not repeated), in metres in the pattern frame:
    /// the outer boundary first, counter-clockwise, then the holes, clockwise. No loop visits a
    /// point twice; loops of one pattern may touch at a corner (a pinch point) but never cross.
    /// Collinear vertices are merged, so every vertex is a corner.
    pub loops: Vec<Vec<[f64; 2]>>,
    /// Number of the ply's cells in the region.
    pub cells: usize,
    /// Area inside the loops (m^2), their signed shoelace area: `cells * d^2` exactly when there
    /// is no cutting margin.
    pub area: f64,
}

/// The flat cutting pattern of one ply, in its own frame: metres, warp along +x, weft along +y,
/// the origin (seed) node at (0, 0).
#[derive(Debug, Clone, PartialEq)]
pub struct FlatPattern {
    /// Ply name.
    pub ply: String,
    /// Fibre spacing d of the net (m).
    pub spacing: f64,
    /// Grid indices of the seed node, which lies at (0, 0).
    pub origin_node: (usize, usize),
    /// The connected pieces, largest first (ties in grid order).
    pub regions: Vec<Region>,
    /// Total number of complete cells; `cells * d^2` is the ply's area.
    pub cells: usize,
    /// Area to cut (m^2), inside the loops: `cells * d^2` exactly when there is no margin.
    pub area: f64,
    /// Lower-left corner of the bounding box (m).
    pub min: [f64; 2],
    /// Upper-right corner of the bounding box (m).
    pub max: [f64; 2],
    /// A point inside the pattern to hang the warp arrow and label on: the centre of the cell
    /// of the largest region nearest to that region's centroid.
    pub anchor: [f64; 2],
}

impl FlatPattern {
    /// All loops of all regions (outer boundaries counter-clockwise, holes clockwise).
    pub fn loops(&self) -> impl Iterator<Item = &Vec<[f64; 2]>> {
        self.regions.iter().flat_map(|r| r.loops.iter())
    }

    /// Size of the bounding box: [along the warp, along the weft] (m).
    pub fn size(&self) -> [f64; 2] {
        [self.max[0] - self.min[0], self.max[1] - self.min[1]]
    }
}

/// The flat pattern of a draped net: its complete cells unfolded onto the unsheared grid and the
/// outline of their union (see the module comment for the frame and the trimming).
/// Error when the net has no complete cell, or a spacing that is not a positive length.
pub fn flat_pattern(net: &DrapeNet) -> Result<FlatPattern, FlatError> {
    flat_pattern_with_margin(net, 0.0)
}

/// Grid coordinates closer than this (in spacings) are one coordinate when cells are grown by a
/// margin: `i - u` and `k + 1 + u` can meet up to rounding.
const SNAP: f64 = 1e-9;

/// The flat pattern with a cutting allowance: the outline of the union of the complete cells,
/// each grown by `margin` (m) on every side. Corners stay square (the allowance of a staircase
/// is a staircase); pieces closer than `2 margin` merge into one piece and narrower holes close.
/// Then `area` is the area to cut (inside the grown outline), while `cells` still counts the
/// ply's cells; each region's `cells` counts the cells it contains. `margin = 0` is
/// [`flat_pattern`]. Errors as [`flat_pattern`], and for a negative or non-finite margin.
pub fn flat_pattern_with_margin(net: &DrapeNet, margin: f64) -> Result<FlatPattern, FlatError> {
    let d = net.spacing;
    if !(d.is_finite() && d > 0.0) {
        return Err(FlatError::BadSpacing { ply: net.name.clone(), spacing: d });
    }
    if !(margin.is_finite() && margin >= 0.0) {
        return Err(FlatError::BadMargin { ply: net.name.clone(), margin });
    }
    let (ncx, ncy) = (net.nu.saturating_sub(1), net.nv.saturating_sub(1));
    let mut mask = CellMask::new(ncx, ncy);
    for i in 0..ncx {
        for j in 0..ncy {
            if net.cell_corners(i, j).is_some() {
                mask.set(i, j);
            }
        }
    }
    let traced = trace(&mask);
    if traced.is_empty() {
        return Err(FlatError::NoCells { ply: net.name.clone() });
    }
    let (i0, j0) = (net.origin_node.0 as f64, net.origin_node.1 as f64);
    let to_flat = |[x, y]: [f64; 2]| [(x - i0) * d, (y - j0) * d];
    let regions: Vec<Region> = if margin == 0.0 {
        traced
            .iter()
            .map(|r| Region {
                loops: r
                    .loops
                    .iter()
                    .map(|l| l.iter().map(|&[i, j]| to_flat([i as f64, j as f64])).collect())
                    .collect(),
                cells: r.cells,
                area: r.cells as f64 * d * d,
            })
            .collect()
    } else {
        grown(&mask, margin / d)
            .into_iter()
            .map(|(loops, cells)| {
                let loops: Vec<Vec<[f64; 2]>> = loops.iter().map(|l| l.iter().map(|&p| to_flat(p)).collect()).collect();
                let area = loops.iter().map(|l| shoelace_area(l)).sum();
                Region { loops, cells, area }
            })
            .collect()
    };
    let mut min = [f64::INFINITY; 2];
    let mut max = [f64::NEG_INFINITY; 2];
    for p in regions.iter().flat_map(|r| r.loops.iter()).flatten() {
        for k in 0..2 {
            min[k] = min[k].min(p[k]);
            max[k] = max[k].max(p[k]);
        }
    }
    let cells: usize = traced.iter().map(|r| r.cells).sum();
    // The arrow hangs on a cell of the ply itself, not on the allowance.
    let a = traced[0].anchor;
    let anchor = to_flat([a[0] as f64 + 0.5, a[1] as f64 + 0.5]);
    let area = if margin == 0.0 { cells as f64 * d * d } else { regions.iter().map(|r| r.area).sum() };
    Ok(FlatPattern {
        ply: net.name.clone(),
        spacing: d,
        origin_node: net.origin_node,
        regions,
        cells,
        area,
        min,
        max,
        anchor,
    })
}

/// Sorted distinct coordinates, those within [`SNAP`] of a kept one dropped.
fn snapped(mut v: Vec<f64>) -> Vec<f64> {
    v.sort_by(f64::total_cmp);
    let mut out: Vec<f64> = Vec::with_capacity(v.len());
    for x in v {
        if out.last().is_none_or(|&l| x - l >= SNAP) {
            out.push(x);
        }
    }
    out
}

/// Index in `axis` (from [`snapped`]) of a coordinate that was snapped into it.
fn snap_index(axis: &[f64], x: f64) -> usize {
    axis.partition_point(|&a| a < x - SNAP)
}

/// Loops (grid units) and cell counts of the union of the filled cells each grown by `u` on
/// every side: the rectangles' edges make a compressed grid, whose covered cells (by a 2-D
/// difference array) are traced like the cells of the net.
fn grown(mask: &CellMask, u: f64) -> Vec<(Vec<Vec<[f64; 2]>>, usize)> {
    let filled: Vec<[usize; 2]> = (0..mask.nx)
        .flat_map(|i| (0..mask.ny).map(move |j| [i, j]))
        .filter(|&[i, j]| mask.get(i as i64, j as i64))
        .collect();
    let grow = |k: usize| [k as f64 - u, k as f64 + 1.0 + u];
    let xs = snapped(filled.iter().flat_map(|c| grow(c[0])).collect());
    let ys = snapped(filled.iter().flat_map(|c| grow(c[1])).collect());
    let (nx, ny) = (xs.len(), ys.len());
    let mut cover = vec![0i64; nx * ny];
    for &[i, j] in &filled {
        let ([x0, x1], [y0, y1]) = (grow(i), grow(j));
        let (a0, a1, b0, b1) = (snap_index(&xs, x0), snap_index(&xs, x1), snap_index(&ys, y0), snap_index(&ys, y1));
        cover[a0 * ny + b0] += 1;
        cover[a1 * ny + b0] -= 1;
        cover[a0 * ny + b1] -= 1;
        cover[a1 * ny + b1] += 1;
    }
    for a in 0..nx {
        for b in 0..ny {
            let left = if a > 0 { cover[(a - 1) * ny + b] } else { 0 };
            let below = if b > 0 { cover[a * ny + b - 1] } else { 0 };
            let diag = if a > 0 && b > 0 { cover[(a - 1) * ny + b - 1] } else { 0 };
            cover[a * ny + b] += left + below - diag;
        }
    }
    let mut big = CellMask::new(nx - 1, ny - 1);
    for a in 0..nx - 1 {
        for b in 0..ny - 1 {
            if cover[a * ny + b] > 0 {
                big.set(a, b);
            }
        }
    }
    let regions = trace(&big);
    // Which grown region holds each cell: look up the compressed cell under the cell's centre.
    let mut region_of = vec![usize::MAX; (nx - 1) * (ny - 1)];
    for (k, r) in regions.iter().enumerate() {
        for c in &r.members {
            region_of[c[0] as usize * (ny - 1) + c[1] as usize] = k;
        }
    }
    let mut counts = vec![0usize; regions.len()];
    for &[i, j] in &filled {
        let a = xs.partition_point(|&x| x <= i as f64 + 0.5) - 1;
        let b = ys.partition_point(|&y| y <= j as f64 + 0.5) - 1;
        counts[region_of[a * (ny - 1) + b]] += 1;
    }
    regions
        .into_iter()
        .zip(counts)
        .map(|(r, n)| {
            (r.loops.iter().map(|l| l.iter().map(|&[a, b]| [xs[a as usize], ys[b as usize]]).collect()).collect(), n)
        })
        .collect()
}

/// Signed shoelace area of a closed loop (positive when counter-clockwise).
pub fn shoelace_area(loop_: &[[f64; 2]]) -> f64 {
    let n = loop_.len();
    let mut twice = 0.0;
    for k in 0..n {
        let (a, b) = (loop_[k], loop_[(k + 1) % n]);
        twice += a[0] * b[1] - b[0] * a[1];
    }
    0.5 * twice
}

/// Which cells of an `nx x ny` grid are filled; cell (i, j) is the unit square
/// `[i, i+1] x [j, j+1]` of grid (node index) coordinates.
#[derive(Debug, Clone)]
pub struct CellMask {
    nx: usize,
    ny: usize,
    filled: Vec<bool>,
}

impl CellMask {
    /// An empty mask.
    pub fn new(nx: usize, ny: usize) -> Self {
        CellMask { nx, ny, filled: vec![false; nx * ny] }
    }
    /// Fill cell (i, j).
    pub fn set(&mut self, i: usize, j: usize) {
        self.filled[i * self.ny + j] = true;
    }
    /// Whether cell (i, j) is filled; cells outside the grid are empty.
    pub fn get(&self, i: i64, j: i64) -> bool {
        i >= 0
            && j >= 0
            && (i as usize) < self.nx
            && (j as usize) < self.ny
            && self.filled[i as usize * self.ny + j as usize]
    }
}

/// A traced region on the integer grid (see [`trace`]).
#[derive(Debug, Clone, PartialEq)]
pub struct GridRegion {
    /// Loops of grid vertices, outer (counter-clockwise) first, then holes (clockwise).
    pub loops: Vec<Vec<[i64; 2]>>,
    /// Number of cells.
    pub cells: usize,
    /// The cell of the region nearest to its centroid (lowest grid order on ties).
    pub anchor: [i64; 2],
    /// The region's cells.
    pub members: Vec<[i64; 2]>,
}

/// Directions of boundary edges, counter-clockwise order: +x, +y, -x, -y.
const DIRS: [[i64; 2]; 4] = [[1, 0], [0, 1], [-1, 0], [0, -1]];

/// The cell on the left of the unit edge leaving vertex `v` in direction `dir` (the edge's cell).
fn left_cell(v: [i64; 2], dir: usize) -> [i64; 2] {
    match dir {
        0 => [v[0], v[1]],
        1 => [v[0] - 1, v[1]],
        2 => [v[0] - 1, v[1] - 1],
        _ => [v[0], v[1] - 1],
    }
}

/// Exact outline of the filled cells of `mask`: one [`GridRegion`] per edge-connected set of
/// cells, largest first (ties by the region's first cell in grid order).
///
/// Every boundary edge is directed with its cell on the left, so outer boundaries run
/// counter-clockwise and holes clockwise. Edges are chained preferring a left turn, which keeps
/// two cells touching only at a corner apart; a chain that still returns to a vertex it already
/// visited (a hole pinched against the outer boundary) is split there into separate loops, so no
/// loop visits a vertex twice.
pub fn trace(mask: &CellMask) -> Vec<GridRegion> {
    // Edge-connected components (breadth-first, in grid order: deterministic).
    let (nx, ny) = (mask.nx, mask.ny);
    let mut label = vec![usize::MAX; nx * ny];
    let mut members: Vec<Vec<[i64; 2]>> = Vec::new();
    for start in 0..nx * ny {
        if !mask.filled[start] || label[start] != usize::MAX {
            continue;
        }
        let id = members.len();
        let mut cells = vec![[(start / ny) as i64, (start % ny) as i64]];
        label[start] = id;
        let mut k = 0;
        while k < cells.len() {
            let c = cells[k];
            k += 1;
            for d in DIRS {
                let (a, b) = (c[0] + d[0], c[1] + d[1]);
                if mask.get(a, b) && label[a as usize * ny + b as usize] == usize::MAX {
                    label[a as usize * ny + b as usize] = id;
                    cells.push([a, b]);
                }
            }
        }
        members.push(cells);
    }

    // Directed boundary edges, keyed by their start vertex: out[v] has bit `dir` set.
    let mut out: HashMap<[i64; 2], u8> = HashMap::new();
    let mut starts: Vec<([i64; 2], usize)> = Vec::new();
    for i in 0..nx as i64 {
        for j in 0..ny as i64 {
            if !mask.get(i, j) {
                continue;
            }
            // (start vertex, direction, neighbour across the edge)
            let edges = [
                ([i, j], 0, [i, j - 1]),
                ([i + 1, j], 1, [i + 1, j]),
                ([i + 1, j + 1], 2, [i, j + 1]),
                ([i, j + 1], 3, [i - 1, j]),
            ];
            for (v, dir, nb) in edges {
                if !mask.get(nb[0], nb[1]) {
                    *out.entry(v).or_insert(0) |= 1 << dir;
                    starts.push((v, dir));
                }
            }
        }
    }

    let mut loops_of: Vec<Vec<Vec<[i64; 2]>>> = vec![Vec::new(); members.len()];
    for (v0, d0) in starts {
        if out[&v0] & (1 << d0) == 0 {
            continue; // already chained
        }
        let cell = left_cell(v0, d0);
        let id = label[cell[0] as usize * ny + cell[1] as usize];
        let mut chain = Vec::new();
        let (mut v, mut dir) = (v0, d0);
        loop {
            chain.push(v);
            *out.get_mut(&v).expect("edge start is a key") &= !(1 << dir);
            v = [v[0] + DIRS[dir][0], v[1] + DIRS[dir][1]];
            let bits = out.get(&v).copied().unwrap_or(0);
            // Left turn, then straight on, then right turn (a U-turn cannot be a boundary).
            match [(dir + 1) % 4, dir, (dir + 3) % 4].into_iter().find(|&d| bits & (1 << d) != 0) {
                Some(d) => dir = d,
                None => break,
            }
        }
        debug_assert_eq!(v, v0, "boundary chains close on their start");
        for l in split_at_repeats(chain) {
            loops_of[id].push(merge_collinear(l));
        }
    }

    let mut regions: Vec<GridRegion> = members
        .into_iter()
        .zip(loops_of)
        .map(|(cells, mut loops)| {
            // Outer boundary (the one loop with positive area) first; holes keep trace order.
            loops.sort_by_key(|l| std::cmp::Reverse(twice_area(l) > 0));
            let n = cells.len() as f64;
            let (sx, sy) = cells.iter().fold((0.0, 0.0), |(x, y), c| (x + c[0] as f64, y + c[1] as f64));
            let (cx, cy) = (sx / n, sy / n);
            let dist = |c: &[i64; 2]| (c[0] as f64 - cx).powi(2) + (c[1] as f64 - cy).powi(2);
            let anchor =
                *cells.iter().min_by(|a, b| dist(a).total_cmp(&dist(b)).then(a.cmp(b))).expect("regions are not empty");
            GridRegion { loops, cells: cells.len(), anchor, members: cells }
        })
        .collect();
    // Stable: equal sizes keep grid order.
    regions.sort_by_key(|r| std::cmp::Reverse(r.cells));
    regions
}

/// Twice the signed area of an integer loop (exact).
pub fn twice_area(l: &[[i64; 2]]) -> i64 {
    let n = l.len();
    (0..n).map(|k| l[k][0] * l[(k + 1) % n][1] - l[(k + 1) % n][0] * l[k][1]).sum()
}

/// Split a closed chain of vertices into loops that visit no vertex twice: whenever the walk
/// comes back to a vertex still on the stack, the stretch since then is a closed loop of its own.
fn split_at_repeats(chain: Vec<[i64; 2]>) -> Vec<Vec<[i64; 2]>> {
    let mut loops = Vec::new();
    let mut stack: Vec<[i64; 2]> = Vec::with_capacity(chain.len());
    let mut at: HashMap<[i64; 2], usize> = HashMap::new();
    for v in chain {
        if let Some(&p) = at.get(&v) {
            let piece: Vec<[i64; 2]> = stack.drain(p..).collect();
            for u in &piece {
                at.remove(u);
            }
            loops.push(piece);
        }
        at.insert(v, stack.len());
        stack.push(v);
    }
    loops.push(stack);
    loops
}

/// Drop vertices where the loop goes straight on.
fn merge_collinear(l: Vec<[i64; 2]>) -> Vec<[i64; 2]> {
    let n = l.len();
    let dir = |a: [i64; 2], b: [i64; 2]| [(b[0] - a[0]).signum(), (b[1] - a[1]).signum()];
    (0..n).filter(|&k| dir(l[(k + n - 1) % n], l[k]) != dir(l[k], l[(k + 1) % n])).map(|k| l[k]).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn mask_of(nx: usize, ny: usize, cells: &[(usize, usize)]) -> CellMask {
        let mut m = CellMask::new(nx, ny);
        for &(i, j) in cells {
            m.set(i, j);
        }
        m
    }

    /// Loops are closed axis-aligned polylines whose vertices are all corners and distinct.
    fn check_loop(l: &[[i64; 2]]) {
        let n = l.len();
        assert!(n >= 4, "{l:?}");
        let mut seen = std::collections::HashSet::new();
        for k in 0..n {
            assert!(seen.insert(l[k]), "vertex {:?} repeated in {l:?}", l[k]);
            let (a, b, c) = (l[(k + n - 1) % n], l[k], l[(k + 1) % n]);
            assert!(a[0] == b[0] || a[1] == b[1], "not axis aligned");
            let (u, w) = ([b[0] - a[0], b[1] - a[1]], [c[0] - b[0], c[1] - b[1]]);
            assert_ne!(u[0] * w[1] - u[1] * w[0], 0, "vertex {b:?} is not a corner of {l:?}");
        }
    }

    #[test]
    fn square_ring_and_pinch() {
        let r = trace(&mask_of(3, 3, &[(0, 0), (0, 1), (0, 2), (1, 0), (1, 2), (2, 0), (2, 1), (2, 2)]));
        assert_eq!(r.len(), 1);
        assert_eq!(r[0].loops, vec![vec![[0, 0], [3, 0], [3, 3], [0, 3]], vec![[1, 1], [1, 2], [2, 2], [2, 1]]]);
        // Two cells touching at a corner: two regions, two squares.
        let r = trace(&mask_of(2, 2, &[(0, 0), (1, 1)]));
        assert_eq!(r.len(), 2);
        assert_eq!(r[0].loops, vec![vec![[0, 0], [1, 0], [1, 1], [0, 1]]]);
        assert_eq!(r[1].loops, vec![vec![[1, 1], [2, 1], [2, 2], [1, 2]]]);
        // A hole pinched against the outside at a corner: outer and hole split apart.
        let r = trace(&mask_of(3, 3, &[(0, 0), (0, 1), (0, 2), (1, 0), (1, 2), (2, 0), (2, 1)]));
        assert_eq!(r.len(), 1);
        assert_eq!(r[0].loops.len(), 2);
        assert_eq!(twice_area(&r[0].loops[0]), 2 * 8);
        assert_eq!(twice_area(&r[0].loops[1]), -2);
        r[0].loops.iter().for_each(|l| check_loop(l));
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(200))]
        /// Random masks: loops simple, one counter-clockwise outer per region, signed areas sum to
        /// the cell count, and every boundary edge of the mask is used exactly once.
        #[test]
        fn random_masks(nx in 1usize..9, ny in 1usize..9, bits in proptest::collection::vec(any::<bool>(), 64)) {
            let mut m = CellMask::new(nx, ny);
            let mut count = 0;
            for i in 0..nx { for j in 0..ny { if bits[i * 8 + j] { m.set(i, j); count += 1; } } }
            let regions = trace(&m);
            prop_assert_eq!(regions.iter().map(|r| r.cells).sum::<usize>(), count);
            let mut edges = 0;
            for r in &regions {
                let areas: Vec<i64> = r.loops.iter().map(|l| twice_area(l)).collect();
                prop_assert_eq!(areas.iter().sum::<i64>(), 2 * r.cells as i64);
                prop_assert!(areas[0] > 0);
                prop_assert!(areas[1..].iter().all(|&a| a < 0), "{:?}", areas);
                for l in &r.loops {
                    check_loop(l);
                    edges += (0..l.len()).map(|k| (l[k][0] - l[(k + 1) % l.len()][0]).abs() + (l[k][1] - l[(k + 1) % l.len()][1]).abs()).sum::<i64>();
                }
            }
            let mut expect = 0;
            for i in 0..nx as i64 { for j in 0..ny as i64 { if m.get(i, j) {
                expect += DIRS.iter().filter(|d| !m.get(i + d[0], j + d[1])).count() as i64;
            } } }
            prop_assert_eq!(edges, expect);
        }
    }
}
