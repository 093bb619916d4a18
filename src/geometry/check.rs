//! Mesh checks and repairs: welding, degenerate and duplicate faces, topology, orientation.
use super::mesh::{MeshReport, ToolError, TriangleMesh};
use super::surface::bounding_diagonal;
use super::{Point, Vector};
use std::path::Path;

/// Sentinel in [`MendedMesh::neighbours`]: no (or no unique) triangle across that edge.
pub const NO_NEIGHBOUR: u32 = u32::MAX;

/// A face is degenerate (and dropped) when its area is at most `(DEGENERATE_AREA_REL * d)^2`,
/// `d` the bounding-box diagonal of the mesh.
pub const DEGENERATE_AREA_REL: f64 = 1e-12;
/// A face is degenerate (and dropped) when twice its area is at most this fraction of its
/// longest edge squared, i.e. its smallest angle's sine is below about this: three
/// (numerically) collinear corners, whose normal would be rounding noise.
pub const DEGENERATE_SINE: f64 = 1e-10;

/// A welded, consistently oriented triangle mesh with edge adjacency.
#[derive(Debug, Clone)]
pub struct MendedMesh {
    /// Welded vertices, in input order.
    pub vertices: Vec<Point>,
    /// Triangles (indices into `vertices`), consistently wound per piece.
    pub triangles: Vec<[u32; 3]>,
    /// `neighbours[t][k]`: the triangle across the edge of `t` opposite its corner `k`
    /// (the edge from corner `(k+1)%3` to corner `(k+2)%3`), or [`NO_NEIGHBOUR`] on an open
    /// boundary or a non-manifold edge.
    pub neighbours: Vec<[u32; 3]>,
}

/// Weld vertices closer than `weld_tolerance`, drop degenerate and duplicate faces, build edge
/// adjacency, count boundary and non-manifold edges, and turn triangles over so that each
/// connected piece is consistently wound. Counts go into `report`.
///
/// Welding keeps the first vertex (in input order) of each cluster, and vertices no kept face
/// uses are dropped; the kept vertices and faces stay in input order. A face is degenerate when
/// two corners weld together or its area is negligible ([`DEGENERATE_AREA_REL`],
/// [`DEGENERATE_SINE`]); a face is a duplicate when an earlier face has the same three vertices
/// (in any order). Pieces are the sets of triangles connected through manifold edges; each is
/// wound like the majority of its triangles (ties: like its first triangle). A non-orientable
/// piece (a Moebius strip) keeps the winding a breadth-first walk gives it.
pub fn mend(
    raw: TriangleMesh,
    weld_tolerance: f64,
    path: &Path,
    report: &mut MeshReport,
) -> Result<MendedMesh, ToolError> {
    let TriangleMesh { vertices, triangles } = mend_faces(raw, weld_tolerance, path, report)?;
    let (triangles, neighbours, _) = mend_edges(triangles, vertices.len(), report);
    Ok(MendedMesh { vertices, triangles, neighbours })
}

/// The first stage of [`mend`]: weld the vertices, drop the degenerate faces and the vertices no
/// kept face uses (kept vertices and faces in input order). The triangles' corners are the
/// final ones up to the order [`mend_edges`] may turn them over in, and its dropping of
/// duplicate faces. Done in place: the file's arrays become the mended ones.
pub(crate) fn mend_faces(
    raw: TriangleMesh,
    weld_tolerance: f64,
    path: &Path,
    report: &mut MeshReport,
) -> Result<TriangleMesh, ToolError> {
    let TriangleMesh { mut vertices, mut triangles } = raw;
    let count = vertices.len();
    for (face, tri) in triangles.iter().enumerate() {
        if let Some(&index) = tri.iter().find(|&&i| i as usize >= count) {
            return Err(ToolError::BadIndex { path: path.into(), face, index: index as usize, count });
        }
    }

    let weld = weld_map(&vertices, weld_tolerance);
    report.vertices_welded = weld.iter().enumerate().filter(|&(i, &r)| r as usize != i).count();

    // Faces: weld, drop degenerate ones (duplicates are found with the edges, below); the kept
    // ones moved to the front.
    let diagonal = bounding_diagonal(&vertices);
    let min_double_area = 2.0 * (DEGENERATE_AREA_REL * diagonal).powi(2);
    let mut kept = 0;
    for k in 0..triangles.len() {
        let t = triangles[k].map(|i| weld[i as usize]);
        if t[0] == t[1] || t[1] == t[2] || t[2] == t[0] {
            continue;
        }
        let [a, b, c] = t.map(|i| vertices[i as usize]);
        let (ab, ac, bc) = (b - a, c - a, c - b);
        let double_area2 = ab.cross(&ac).norm_squared();
        let longest = ab.norm_squared().max(ac.norm_squared()).max(bc.norm_squared());
        if !(double_area2 > min_double_area * min_double_area && double_area2 > (DEGENERATE_SINE * longest).powi(2)) {
            continue;
        }
        triangles[kept] = t;
        kept += 1;
    }
    report.degenerate_faces_dropped += triangles.len() - kept;
    triangles.truncate(kept);
    drop(weld);
    if triangles.is_empty() {
        return Err(ToolError::AllDegenerate { path: path.into() });
    }

    // Keep used vertices only, in input order (moved to the front: a vertex's new index is
    // never above its old one).
    let mut new_index = vec![u32::MAX; count];
    for t in &triangles {
        for &v in t {
            new_index[v as usize] = 0;
        }
    }
    let mut used = 0;
    for i in 0..count {
        if new_index[i] == 0 {
            new_index[i] = used as u32;
            vertices[used] = vertices[i];
            used += 1;
        }
    }
    vertices.truncate(used);
    for t in &mut triangles {
        *t = t.map(|v| new_index[v as usize]);
    }
    Ok(TriangleMesh { vertices, triangles })
}

/// The second stage of [`mend`], on the triangles of [`mend_faces`] over `num_vertices`
/// vertices: drop duplicate faces, build the edge adjacency, count boundary and non-manifold
/// edges and orient the pieces. The triangles, their neighbours, and whether any duplicate was
/// dropped (otherwise the triangles are those given, some turned over).
pub(crate) fn mend_edges(
    mut tris: Vec<[u32; 3]>,
    num_vertices: usize,
    report: &mut MeshReport,
) -> (Vec<[u32; 3]>, Vec<[u32; 3]>, bool) {
    let mut edges = adjacency(&tris, num_vertices);
    // Duplicate faces share all three edges, so the edge grouping finds them. Drop them (the
    // first in input order stays) and group the edges again.
    report.duplicate_faces_dropped = edges.duplicates.iter().filter(|&&d| d).count();
    if report.duplicate_faces_dropped > 0 {
        let mut t = 0;
        tris.retain(|_| {
            t += 1;
            !edges.duplicates[t - 1]
        });
        edges = adjacency(&tris, num_vertices);
    }
    let Edges { mut neighbours, boundary, non_manifold, .. } = edges;
    report.boundary_edges = boundary;
    report.non_manifold_edges = non_manifold;

    let (components, flipped) = orient(&mut tris, &mut neighbours);
    report.components = components;
    report.flipped_faces = flipped;
    report.triangles = tris.len();
    report.vertices = num_vertices;
    (tris, neighbours, report.duplicate_faces_dropped > 0)
}

const NONE: u32 = u32::MAX;

/// Weld grid cell width, in weld tolerances. Wider cells mean fewer cells to search per vertex
/// (a vertex searches a neighbouring cell only within one tolerance of the border) but more
/// vertices per cell when vertices are packed about one tolerance apart.
const WELD_CELL: f64 = 8.0;

/// Mix integer words into a well-spread 64-bit hash (FxHash steps, MurmurHash3 finaliser).
#[inline]
fn mix(words: [u64; 3]) -> u64 {
    let mut h = 0u64;
    for w in words {
        h = (h.rotate_left(5) ^ w).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
    h ^= h >> 33;
    h = h.wrapping_mul(0xff51_afd7_ed55_8ccd);
    h ^= h >> 33;
    h = h.wrapping_mul(0xc4ce_b9fe_1a85_ec53);
    h ^ (h >> 33)
}

/// A hash table of chains without keys: items (numbered `0..capacity`) are pushed onto the
/// chain of their key's slot, and a search walks the chain and checks each item itself, so keys
/// that share a slot merely share a chain. Two `u32` per slot and per item, no allocation per
/// key.
struct Chains {
    heads: Vec<u32>,
    next: Vec<u32>,
    mask: u64,
}

impl Chains {
    fn new(capacity: usize) -> Self {
        let slots = (2 * capacity).next_power_of_two().max(2);
        Chains { heads: vec![NONE; slots], next: vec![NONE; capacity], mask: slots as u64 - 1 }
    }
    #[inline]
    fn slot(&self, hash: u64) -> usize {
        (hash & self.mask) as usize
    }
    /// Items on the chain of `hash`, most recent first.
    #[inline]
    fn chain(&self, hash: u64) -> impl Iterator<Item = u32> + '_ {
        let mut h = self.heads[self.slot(hash)];
        std::iter::from_fn(move || {
            let item = h;
            if item == NONE {
                return None;
            }
            h = self.next[item as usize];
            Some(item)
        })
    }
    #[inline]
    fn push(&mut self, hash: u64, item: u32) {
        let slot = self.slot(hash);
        self.next[item as usize] = self.heads[slot];
        self.heads[slot] = item;
    }
}

/// For each vertex, the vertex it welds to (itself if it is the first of its cluster). A vertex
/// welds to the earliest earlier cluster head within `tolerance` (distance `<= tolerance`);
/// heads are found through a hash grid of cells [`WELD_CELL`] tolerances wide. A tolerance that
/// is not positive and finite welds exactly coincident vertices only.
fn weld_map(vertices: &[Point], tolerance: f64) -> Vec<u32> {
    let mut rep = Vec::with_capacity(vertices.len());
    let mut heads = Chains::new(vertices.len());
    if !(tolerance > 0.0 && tolerance.is_finite()) {
        for (i, p) in vertices.iter().enumerate() {
            // `+ 0.0` turns -0.0 into 0.0.
            let hash = mix([p.x, p.y, p.z].map(|c| (c + 0.0).to_bits()));
            let found = heads.chain(hash).filter(|&h| vertices[h as usize] == *p).min();
            rep.push(found.unwrap_or_else(|| {
                heads.push(hash, i as u32);
                i as u32
            }));
        }
        return rep;
    }
    // Cells are counted from the lowest corner so that cell numbers stay small.
    let lo =
        vertices.iter().fold(Point::from(Vector::repeat(f64::INFINITY)), |m, p| Point::from(m.coords.inf(&p.coords)));
    let inv_cell = 1.0 / (WELD_CELL * tolerance);
    let reach = 1.0 / WELD_CELL; // the tolerance in cell units
    let tol2 = tolerance * tolerance;
    let cell_hash = |x: i64, y: i64, z: i64| mix([x as u64, y as u64, z as u64]);
    for (i, p) in vertices.iter().enumerate() {
        let u = (p - lo) * inv_cell;
        // Cells that may hold a point within the tolerance: the vertex's own, and on each axis
        // the next one down or up if the vertex is that close to the border.
        let mut cell = [0i64; 3];
        let mut range = [(0i64, 0i64); 3];
        for axis in 0..3 {
            let c = u[axis].floor();
            let f = u[axis] - c;
            cell[axis] = c as i64;
            range[axis] = (
                if f < reach { cell[axis].saturating_sub(1) } else { cell[axis] },
                if f + reach >= 1.0 { cell[axis].saturating_add(1) } else { cell[axis] },
            );
        }
        let mut best = NONE;
        for x in range[0].0..=range[0].1 {
            for y in range[1].0..=range[1].1 {
                for z in range[2].0..=range[2].1 {
                    for h in heads.chain(cell_hash(x, y, z)) {
                        if h < best && (vertices[h as usize] - p).norm_squared() <= tol2 {
                            best = h;
                        }
                    }
                }
            }
        }
        if best == NONE {
            heads.push(cell_hash(cell[0], cell[1], cell[2]), i as u32);
            best = i as u32;
        }
        rep.push(best);
    }
    rep
}

/// Edge adjacency of a triangle list.
struct Edges {
    /// See [`MendedMesh::neighbours`].
    neighbours: Vec<[u32; 3]>,
    /// Edges with one triangle.
    boundary: usize,
    /// Edges with more than two triangles.
    non_manifold: usize,
    /// Triangles with the same three vertices as an earlier triangle.
    duplicates: Vec<bool>,
}

/// Edge adjacency of `tris` (over `num_vertices` vertices). Half-edges are bucketed by their
/// lower vertex (counting sort) and sorted by their upper vertex within each bucket: O(n) plus
/// small sorts, no hashing. Triangles on one edge with the same opposite vertex are duplicates.
fn adjacency(tris: &[[u32; 3]], num_vertices: usize) -> Edges {
    let edge = |h: usize| {
        let t = &tris[h / 3];
        let k = h % 3;
        let (a, b) = (t[(k + 1) % 3], t[(k + 2) % 3]);
        (a.min(b), a.max(b))
    };
    let opposite = |h: u64| tris[h as usize / 3][h as usize % 3];
    let half_edges = 3 * tris.len();
    let mut start = vec![0u32; num_vertices + 1];
    for h in 0..half_edges {
        start[edge(h).0 as usize + 1] += 1;
    }
    for v in 0..num_vertices {
        start[v + 1] += start[v];
    }
    let mut fill = start.clone();
    // (upper vertex, half-edge) packed so that sorting groups an edge's half-edges in order.
    let mut slots = vec![0u64; half_edges];
    for h in 0..half_edges {
        let (lower, upper) = edge(h);
        let f = &mut fill[lower as usize];
        slots[*f as usize] = (u64::from(upper) << 32) | h as u64;
        *f += 1;
    }
    drop(fill);
    let mut edges = Edges {
        neighbours: vec![[NO_NEIGHBOUR; 3]; tris.len()],
        boundary: 0,
        non_manifold: 0,
        duplicates: vec![false; tris.len()],
    };
    const HALF: u64 = 0xffff_ffff;
    let mut scratch: Vec<(u32, u64)> = Vec::new();
    for v in 0..num_vertices {
        let bucket = &mut slots[start[v] as usize..start[v + 1] as usize];
        bucket.sort_unstable();
        for run in bucket.chunk_by(|x, y| x >> 32 == y >> 32) {
            if run.len() == 1 {
                edges.boundary += 1;
                continue;
            }
            // Half-edges of a run are in triangle order: a triangle is a duplicate when an
            // earlier one on the same edge has the same opposite vertex.
            if run.len() <= 8 {
                for (i, &h) in run.iter().enumerate() {
                    let o = opposite(h & HALF);
                    if run[..i].iter().any(|&g| opposite(g & HALF) == o) {
                        edges.duplicates[(h & HALF) as usize / 3] = true;
                    }
                }
            } else {
                scratch.clear();
                scratch.extend(run.iter().map(|&h| (opposite(h & HALF), h & HALF)));
                scratch.sort_unstable();
                for pair in scratch.windows(2) {
                    if pair[0].0 == pair[1].0 {
                        edges.duplicates[pair[1].1 as usize / 3] = true;
                    }
                }
            }
            if run.len() == 2 {
                let (h0, h1) = ((run[0] & HALF) as usize, (run[1] & HALF) as usize);
                edges.neighbours[h0 / 3][h0 % 3] = (h1 / 3) as u32;
                edges.neighbours[h1 / 3][h1 % 3] = (h0 / 3) as u32;
            } else {
                edges.non_manifold += 1;
            }
        }
    }
    edges
}

/// Turn triangle `t` over (swap corners 1 and 2, and the neighbours opposite them).
fn flip(tris: &mut [[u32; 3]], neighbours: &mut [[u32; 3]], t: usize) {
    tris[t].swap(1, 2);
    neighbours[t].swap(1, 2);
}

/// Orient each piece consistently: breadth-first from its lowest-index triangle through
/// manifold edges, turning over each newly reached triangle that traverses the shared edge in
/// the same direction as the triangle it was reached from; then, if more than half of the
/// piece was turned over, turn the whole piece over instead. Returns (pieces, faces turned).
fn orient(tris: &mut [[u32; 3]], neighbours: &mut [[u32; 3]]) -> (usize, usize) {
    let mut visited = vec![false; tris.len()];
    let mut piece: Vec<u32> = Vec::new();
    let (mut components, mut flipped) = (0, 0);
    for seed in 0..tris.len() {
        if visited[seed] {
            continue;
        }
        components += 1;
        visited[seed] = true;
        piece.clear();
        piece.push(seed as u32);
        let mut turned = 0;
        let mut head = 0;
        while head < piece.len() {
            let t = piece[head] as usize;
            head += 1;
            for k in 0..3 {
                let n = neighbours[t][k];
                if n == NO_NEIGHBOUR || visited[n as usize] {
                    // A visited neighbour that disagrees means a non-orientable piece: keep it.
                    continue;
                }
                let n = n as usize;
                // t runs a -> b along the shared edge; n agrees if it runs b -> a.
                let (a, b) = (tris[t][(k + 1) % 3], tris[t][(k + 2) % 3]);
                let j = tris[n].iter().position(|&v| v == b).unwrap_or(0);
                if tris[n][(j + 1) % 3] != a {
                    flip(tris, neighbours, n);
                    turned += 1;
                }
                visited[n] = true;
                piece.push(n as u32);
            }
        }
        if 2 * turned > piece.len() {
            for &t in &piece {
                flip(tris, neighbours, t as usize);
            }
            turned = piece.len() - turned;
        }
        flipped += turned;
    }
    (components, flipped)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::surface::WELD_TOLERANCE_REL;
    use crate::geometry::Vector;
    use crate::io::obj::read_obj;

    /// Read an OBJ text and mend it the way a tool read from a file is.
    fn load(text: &str) -> Result<(MendedMesh, MeshReport), ToolError> {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("mesh.obj");
        std::fs::write(&path, text).unwrap();
        let (raw, mut report) = read_obj(&path)?;
        let tolerance = WELD_TOLERANCE_REL * bounding_diagonal(&raw.vertices);
        let mesh = mend(raw, tolerance, &path, &mut report)?;
        check_adjacency(&mesh);
        Ok((mesh, report))
    }

    fn mend_raw(vertices: Vec<Point>, triangles: Vec<[u32; 3]>) -> (MendedMesh, MeshReport) {
        let tolerance = WELD_TOLERANCE_REL * bounding_diagonal(&vertices);
        let mut report = MeshReport::default();
        let mesh = mend(TriangleMesh { vertices, triangles }, tolerance, Path::new("t"), &mut report).unwrap();
        check_adjacency(&mesh);
        (mesh, report)
    }

    /// Every neighbour link is mutual and crosses exactly the edge it names.
    fn check_adjacency(mesh: &MendedMesh) {
        assert_eq!(mesh.neighbours.len(), mesh.triangles.len());
        for (t, tri) in mesh.triangles.iter().enumerate() {
            assert!(tri.iter().all(|&v| (v as usize) < mesh.vertices.len()));
            assert!(tri[0] != tri[1] && tri[1] != tri[2] && tri[2] != tri[0]);
            for k in 0..3 {
                let n = mesh.neighbours[t][k];
                if n == NO_NEIGHBOUR {
                    continue;
                }
                assert_ne!(n as usize, t);
                let other = mesh.triangles[n as usize];
                let back: Vec<usize> = (0..3).filter(|&j| mesh.neighbours[n as usize][j] == t as u32).collect();
                assert_eq!(back.len(), 1, "triangle {n} must link back to {t} exactly once");
                let edge = |tri: [u32; 3], k: usize| {
                    let (a, b) = (tri[(k + 1) % 3], tri[(k + 2) % 3]);
                    (a.min(b), a.max(b))
                };
                assert_eq!(edge(*tri, k), edge(other, back[0]), "{t}/{k} and {n}/{}", back[0]);
                let shared = tri.iter().filter(|v| other.contains(v)).count();
                assert_eq!(shared, 2);
            }
        }
    }

    fn normal(mesh: &MendedMesh, t: usize) -> Vector {
        let [a, b, c] = mesh.triangles[t].map(|i| mesh.vertices[i as usize]);
        (b - a).cross(&(c - a)).normalize()
    }

    /// Whether neighbours across every manifold edge traverse it in opposite directions.
    fn consistently_wound(mesh: &MendedMesh) -> bool {
        (0..mesh.triangles.len()).all(|t| {
            (0..3).all(|k| {
                let n = mesh.neighbours[t][k];
                if n == NO_NEIGHBOUR {
                    return true;
                }
                let tri = mesh.triangles[t];
                let (a, b) = (tri[(k + 1) % 3], tri[(k + 2) % 3]);
                let other = mesh.triangles[n as usize];
                let j = other.iter().position(|&v| v == b).unwrap();
                other[(j + 1) % 3] == a
            })
        })
    }

    /// An `n` x `n` grid of unit squares in the plane z = 0, two triangles per square, wound
    /// counter-clockwise seen from +z.
    fn grid(n: u32) -> (Vec<Point>, Vec<[u32; 3]>) {
        let mut vertices = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                vertices.push(Point::new(f64::from(i), f64::from(j), 0.0));
            }
        }
        let id = |i: u32, j: u32| j * (n + 1) + i;
        let mut triangles = Vec::new();
        for j in 0..n {
            for i in 0..n {
                triangles.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                triangles.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        (vertices, triangles)
    }

    /// Deterministic pseudo-random numbers (xorshift).
    struct Rng(u64);
    impl Rng {
        fn next(&mut self) -> u64 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            self.0
        }
        fn below(&mut self, n: usize) -> usize {
            (self.next() % n as u64) as usize
        }
    }

    #[test]
    fn duplicated_vertices_are_welded_and_triangles_become_neighbours() {
        // Two triangles exported separately, sharing the edge (1,0,0)-(0,1,0) by position only.
        let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 4 5 6\n";
        let (mesh, report) = load(text).unwrap();
        assert_eq!(report.vertices_welded, 2);
        assert_eq!(report.vertices, 4);
        assert_eq!(mesh.vertices.len(), 4);
        assert_eq!(mesh.neighbours[0][0], 1);
        assert_eq!(mesh.neighbours[1][1], 0);
        assert_eq!(report.boundary_edges, 4);
        assert_eq!(report.components, 1);
        assert_eq!(report.flipped_faces, 0);
        assert!(consistently_wound(&mesh));
    }

    #[test]
    fn welding_keeps_the_first_vertex_and_respects_the_tolerance() {
        let vertices = vec![
            Point::new(0.0, 0.0, 0.0),
            Point::new(1.0, 0.0, 0.0),
            Point::new(0.0, 1.0, 0.0),
            Point::new(1.0 + 4e-4, 0.0, 0.0), // within 1e-3 of vertex 1
            Point::new(1.0, 1.0, 0.0),
            Point::new(0.0, 1.0 + 3e-3, 0.0), // not within 1e-3 of vertex 2
        ];
        let triangles = vec![[0, 1, 2], [3, 4, 5]];
        let mut report = MeshReport::default();
        let mesh = mend(TriangleMesh { vertices, triangles }, 1e-3, Path::new("t"), &mut report).unwrap();
        assert_eq!(report.vertices_welded, 1);
        assert_eq!(mesh.vertices.len(), 5);
        assert_eq!(mesh.vertices[1], Point::new(1.0, 0.0, 0.0), "first vertex wins");
        assert_eq!(mesh.triangles[1][0], 1);

        // A zero tolerance welds coincident vertices only (and -0.0 equals 0.0).
        let vertices = vec![
            Point::new(0.0, 0.0, 0.0),
            Point::new(1.0, 0.0, 0.0),
            Point::new(0.0, 1.0, 0.0),
            Point::new(-0.0, 0.0, 0.0),
            Point::new(1.0, 1e-300, 0.0),
            Point::new(1.0, 1.0, 0.0),
        ];
        let mut report = MeshReport::default();
        let raw = TriangleMesh { vertices, triangles: vec![[0, 1, 2], [3, 4, 5]] };
        let mesh = mend(raw, 0.0, Path::new("t"), &mut report).unwrap();
        assert_eq!(report.vertices_welded, 1);
        assert_eq!(mesh.vertices.len(), 5);
    }

    #[test]
    fn welding_matches_a_brute_force_search() {
        // Clusters of points jittered by up to about two tolerances, so some pairs weld and
        // some do not, scattered over many grid cells and their borders.
        let tol = 0.01;
        let mut rng = Rng(0x1234_5678_9abc_def1);
        let mut coord = |scale: f64| (rng.below(1 << 20) as f64 / f64::from(1 << 20) - 0.5) * scale;
        let mut vertices = Vec::new();
        for _ in 0..400 {
            let centre = Point::new(coord(1.0), coord(1.0), coord(1.0));
            for _ in 0..4 {
                vertices.push(centre + Vector::new(coord(2.4 * tol), coord(2.4 * tol), coord(2.4 * tol)));
            }
        }
        for i in (1..vertices.len()).rev() {
            let j = rng.below(i + 1);
            vertices.swap(i, j);
        }
        let mut expected: Vec<u32> = Vec::new();
        let mut heads: Vec<u32> = Vec::new();
        for (i, p) in vertices.iter().enumerate() {
            let near = heads.iter().copied().filter(|&h| (vertices[h as usize] - p).norm() <= tol).min();
            expected.push(near.unwrap_or_else(|| {
                heads.push(i as u32);
                i as u32
            }));
        }
        let welded = expected.iter().enumerate().filter(|&(i, &r)| r as usize != i).count();
        assert!(welded > 200 && heads.len() > 400, "{welded} welded, {} heads", heads.len());
        assert_eq!(weld_map(&vertices, tol), expected);

        // Exact welding (zero tolerance).
        let mut exact = vertices.clone();
        exact.extend_from_slice(&vertices[..100]);
        let map = weld_map(&exact, 0.0);
        assert!((0..vertices.len()).all(|i| map[i] as usize == i || exact[map[i] as usize] == exact[i]));
        assert!((0..100).all(|i| exact[map[vertices.len() + i] as usize] == vertices[i]));
    }

    #[test]
    fn many_triangles_on_one_edge_with_duplicates() {
        // Twelve fins on the edge (0,0,0)-(0,0,1); fins 4 and 9 repeat fins 1 and 2.
        let mut vertices = vec![Point::new(0.0, 0.0, 0.0), Point::new(0.0, 0.0, 1.0)];
        let mut triangles = Vec::new();
        for i in 0..10 {
            let a = f64::from(i) * 0.6;
            vertices.push(Point::new(a.cos(), a.sin(), 0.5));
            triangles.push([0, 1, i + 2]);
        }
        triangles.insert(4, [1, 3, 0]);
        triangles.insert(9, [4, 0, 1]);
        let (mesh, report) = mend_raw(vertices, triangles);
        assert_eq!(report.duplicate_faces_dropped, 2);
        assert_eq!(mesh.triangles.len(), 10);
        assert_eq!(report.non_manifold_edges, 1);
        assert_eq!(report.boundary_edges, 20);
        assert_eq!(report.components, 10);
        assert!(mesh.neighbours.iter().all(|n| n.iter().all(|&x| x == NO_NEIGHBOUR)));
    }

    #[test]
    fn degenerate_faces_are_dropped_and_counted() {
        // A collinear face, a face with a repeated corner, and a face that collapses by welding.
        let text = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 2 0 0\nv 0 1e-12 0\n\
                    f 1 2 3\nf 1 2 4\nf 1 1 3\nf 1 5 3\n";
        let (mesh, report) = load(text).unwrap();
        assert_eq!(mesh.triangles.len(), 1);
        assert_eq!(report.degenerate_faces_dropped, 3);
        assert_eq!(report.faces_read, 4);
        assert_eq!(report.vertices, 3);

        let err = load("v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\nf 3 2 1\n").unwrap_err();
        assert!(matches!(err, ToolError::AllDegenerate { .. }), "{err}");
    }

    #[test]
    fn duplicate_faces_are_dropped_and_counted() {
        let text = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n\
                    f 1 2 3\nf 1 3 4\nf 2 3 1\nf 1 3 2\n";
        let (mesh, report) = load(text).unwrap();
        assert_eq!(mesh.triangles, vec![[0, 1, 2], [0, 2, 3]]);
        assert_eq!(report.duplicate_faces_dropped, 2);
        assert_eq!(report.boundary_edges, 4);
        assert_eq!(report.non_manifold_edges, 0);
    }

    #[test]
    fn single_quad_has_four_boundary_edges() {
        let (mesh, report) = load("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n").unwrap();
        assert_eq!(mesh.triangles.len(), 2);
        assert_eq!(report.polygons_triangulated, 1);
        assert_eq!(report.boundary_edges, 4);
        assert_eq!(report.non_manifold_edges, 0);
        assert_eq!(report.components, 1);
        // The diagonal links the two triangles.
        assert_eq!(mesh.neighbours[0], [NO_NEIGHBOUR, 1, NO_NEIGHBOUR]);
        assert_eq!(mesh.neighbours[1], [NO_NEIGHBOUR, NO_NEIGHBOUR, 0]);
    }

    #[test]
    fn non_manifold_edge_is_counted_and_not_linked() {
        // Three fins on the edge 1-2, plus a fourth triangle properly attached to the first fin.
        let text = "v 0 0 0\nv 0 0 1\nv 1 0 0\nv -1 0 0\nv 0 1 0\nv 1 0 1\n\
                    f 1 2 3\nf 2 1 4\nf 1 2 5\nf 3 2 6\n";
        let (mesh, report) = load(text).unwrap();
        assert_eq!(report.non_manifold_edges, 1);
        assert_eq!(report.boundary_edges, 2 + 2 + 2 + 2 - 1);
        assert_eq!(mesh.neighbours[0][2], NO_NEIGHBOUR);
        assert_eq!(mesh.neighbours[1][2], NO_NEIGHBOUR);
        assert_eq!(mesh.neighbours[2][2], NO_NEIGHBOUR);
        assert_eq!(mesh.neighbours[0][0], 3);
        // Pieces are connected through manifold edges only.
        assert_eq!(report.components, 3);
    }

    #[test]
    fn one_flipped_triangle_in_a_grid_is_turned_over() {
        for wrong in [0, 5] {
            let (vertices, mut triangles) = grid(2);
            triangles[wrong].swap(0, 1);
            let (mesh, report) = mend_raw(vertices, triangles);
            assert_eq!(report.flipped_faces, 1, "wrong triangle {wrong}");
            assert_eq!(report.components, 1);
            assert_eq!(report.boundary_edges, 8);
            assert!(consistently_wound(&mesh));
            for t in 0..mesh.triangles.len() {
                assert!((normal(&mesh, t) - Vector::z()).norm() < 1e-12, "triangle {t}");
            }
        }
    }

    #[test]
    fn same_orientation_through_obj_file() {
        // 2x2 grid of quads, the third one wound the other way.
        let text = "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 0 1 0\nv 1 1 0\nv 2 1 0\nv 0 2 0\nv 1 2 0\nv 2 2 0\n\
                    f 1 2 5 4\nf 2 3 6 5\nf 4 7 8 5\nf 5 6 9 8\n";
        let (mesh, report) = load(text).unwrap();
        assert_eq!(report.flipped_faces, 2, "both triangles of the third quad");
        for t in 0..mesh.triangles.len() {
            assert!((normal(&mesh, t) - Vector::z()).norm() < 1e-12, "triangle {t}");
        }
    }

    #[test]
    fn moebius_strip_terminates_and_keeps_valid_adjacency() {
        let n = 12;
        let mut vertices = Vec::new();
        for i in 0..n {
            let a = std::f64::consts::TAU * f64::from(i) / f64::from(n);
            for s in [-0.3, 0.3] {
                let (h, r) = (a / 2.0, 1.0 + s * (a / 2.0).cos());
                vertices.push(Point::new(r * a.cos(), r * a.sin(), s * h.sin()));
            }
        }
        let mut triangles = Vec::new();
        for i in 0..n {
            let (a0, a1) = (2 * i, 2 * i + 1);
            // The last strip is glued back with a half twist.
            let (b0, b1) = if i + 1 == n { (1, 0) } else { (2 * i + 2, 2 * i + 3) };
            triangles.push([a0, b0, b1]);
            triangles.push([a0, b1, a1]);
        }
        let (mesh, report) = mend_raw(vertices, triangles);
        assert_eq!(mesh.triangles.len(), 24);
        assert_eq!(report.components, 1);
        assert_eq!(report.boundary_edges, 24);
        assert_eq!(report.non_manifold_edges, 0);
        assert!(!consistently_wound(&mesh), "a Moebius strip cannot be oriented");
    }

    #[test]
    fn random_mesh_has_mutual_adjacency_and_one_orientation() {
        let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
        for round in 0..5 {
            let (vertices, triangles) = grid(12 + round);
            // Split some vertices (duplicate their position), flip and shuffle triangles, add
            // duplicates and fins (non-manifold edges).
            let mut vertices = vertices;
            let mut triangles: Vec<[u32; 3]> = triangles
                .into_iter()
                .map(|mut t| {
                    for v in &mut t {
                        if rng.below(4) == 0 {
                            vertices.push(vertices[*v as usize]);
                            *v = vertices.len() as u32 - 1;
                        }
                    }
                    if rng.below(3) == 0 {
                        t.swap(1, 2);
                    }
                    t
                })
                .collect();
            for _ in 0..triangles.len() / 10 {
                let t = triangles[rng.below(triangles.len())];
                triangles.push([t[1], t[2], t[0]]);
            }
            let planar = triangles.len();
            for _ in 0..5 {
                let t = triangles[rng.below(planar)];
                vertices.push(Point::new(rng.below(10) as f64, rng.below(10) as f64, 5.0));
                triangles.push([t[0], t[1], vertices.len() as u32 - 1]);
            }
            for i in (1..triangles.len()).rev() {
                triangles.swap(i, rng.below(i + 1));
            }
            let (mesh, report) = mend_raw(vertices, triangles);
            assert!(report.duplicate_faces_dropped > 0);
            assert!(report.non_manifold_edges > 0);
            assert!(report.vertices_welded > 0);
            assert!(report.flipped_faces > 0);
            // The planar grid part is one consistently wound piece: all normals agree.
            let planar_normals: Vec<Vector> = (0..mesh.triangles.len())
                .filter(|&t| mesh.triangles[t].iter().all(|&v| mesh.vertices[v as usize].z == 0.0))
                .map(|t| normal(&mesh, t))
                .collect();
            let up = planar_normals.iter().filter(|n| n.z > 0.0).count();
            assert!(up == 0 || up == planar_normals.len(), "round {round}: {up} up");
            assert!(consistently_wound(&mesh));
        }
    }

    #[test]
    fn large_mesh_is_mended_quickly() {
        // 200k triangles, every vertex duplicated per triangle (a triangle soup).
        let (vertices, triangles) = grid(316);
        let mut soup = Vec::with_capacity(3 * triangles.len());
        let triangles: Vec<[u32; 3]> = triangles
            .iter()
            .map(|t| {
                t.map(|v| {
                    soup.push(vertices[v as usize]);
                    soup.len() as u32 - 1
                })
            })
            .collect();
        let start = std::time::Instant::now();
        let (mesh, report) = mend_raw(soup, triangles);
        let elapsed = start.elapsed();
        eprintln!("mend of {} triangles: {elapsed:?}", mesh.triangles.len());
        assert_eq!(report.components, 1);
        assert_eq!(report.boundary_edges, 4 * 316);
        assert_eq!(mesh.vertices.len(), 317 * 317);
        // Generous bound: catches quadratic behaviour, not noise.
        assert!(elapsed.as_secs_f64() < 2.0, "{elapsed:?}");
    }
}
