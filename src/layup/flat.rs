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
//! pattern is the fabric that actually lies on the tool.
use crate::kinematic::DrapeNet;
use std::collections::HashMap;

/// Why a flat pattern or a nesting could not be made.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FlatError {
    /// The net has no cell with four placed corners.
    #[error("ply '{ply}' has no complete cell (no cell with all four corners placed), so it has no flat pattern. Check the drape of this ply: its seed, size and the node statuses in its .drape.json.")]
    NoCells { ply: String },
    /// The net's spacing cannot scale a pattern.
    #[error("ply '{ply}': the net spacing {spacing} is not a positive finite length, so the pattern cannot be unfolded. Re-create the net with `drape run`.")]
    BadSpacing { ply: String, spacing: f64 },
    /// A nesting parameter is out of range.
    #[error("nesting: {field} = {value} {reason}. Fix it in the scene file.")]
    BadNestParameter { field: &'static str, value: f64, reason: &'static str },
    /// A pattern does not fit across the roll in any allowed orientation.
    #[error("ply '{ply}' is {across:.6} m across the roll ({orientation}) but the roll is only {roll_width:.6} m wide: {excess:.6} m too wide. Use a wider roll, allow a 90 degree turn if the material permits it, or split the ply.")]
    TooWide { ply: String, across: f64, roll_width: f64, excess: f64, orientation: &'static str },
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
    /// Number of cells in the region.
    pub cells: usize,
    /// Area (m^2): `cells * d^2`, equal to the signed shoelace area of the loops.
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
    /// Total number of complete cells.
    pub cells: usize,
    /// Total area (m^2), `cells * d^2`.
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
    let d = net.spacing;
    if !(d.is_finite() && d > 0.0) {
        return Err(FlatError::BadSpacing { ply: net.name.clone(), spacing: d });
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
    let to_flat = |[i, j]: [i64; 2]| [(i as f64 - i0) * d, (j as f64 - j0) * d];
    let mut regions = Vec::with_capacity(traced.len());
    let mut min = [f64::INFINITY; 2];
    let mut max = [f64::NEG_INFINITY; 2];
    for r in &traced {
        let loops: Vec<Vec<[f64; 2]>> = r.loops.iter().map(|l| l.iter().map(|&p| to_flat(p)).collect()).collect();
        for p in loops.iter().flatten() {
            for k in 0..2 {
                min[k] = min[k].min(p[k]);
                max[k] = max[k].max(p[k]);
            }
        }
        regions.push(Region { loops, cells: r.cells, area: r.cells as f64 * d * d });
    }
    let cells: usize = traced.iter().map(|r| r.cells).sum();
    let big = &traced[0];
    let anchor = to_flat([0, 0]);
    let anchor = [anchor[0] + (big.anchor[0] as f64 + 0.5) * d, anchor[1] + (big.anchor[1] as f64 + 0.5) * d];
    Ok(FlatPattern {
        ply: net.name.clone(),
        spacing: d,
        origin_node: net.origin_node,
        regions,
        cells,
        area: cells as f64 * d * d,
        min,
        max,
        anchor,
    })
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
        i >= 0 && j >= 0 && (i as usize) < self.nx && (j as usize) < self.ny && self.filled[i as usize * self.ny + j as usize]
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
            let edges = [([i, j], 0, [i, j - 1]), ([i + 1, j], 1, [i + 1, j]), ([i + 1, j + 1], 2, [i, j + 1]), ([i, j + 1], 3, [i - 1, j])];
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
            let anchor = *cells.iter().min_by(|a, b| dist(a).total_cmp(&dist(b)).then(a.cmp(b))).expect("regions are not empty");
            GridRegion { loops, cells: cells.len(), anchor }
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
    (0..n)
        .filter(|&k| dir(l[(k + n - 1) % n], l[k]) != dir(l[k], l[(k + 1) % n]))
        .map(|k| l[k])
        .collect()
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
