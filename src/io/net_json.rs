//! `<ply>.drape.json`: the net as the contract in DESIGN.md lays it out, streamed (no JSON tree of
//! the whole net is built in memory), and [`read_net`] to load it back.
//!
//! Layout (small keys first, so `head` shows them; arrays one node / cell / grid row per line):
//! `ply`, `method`, `spacing`, `grid` [nu, nv], `origin_node` [i0, j0], `timing_ms` {load,
//! generators, fill, total}, `status` {placed, failed {reason: count, nonzero only}, legend
//! {"code": name}, node_codes [u8; nu*nv]}, `meta`, `nodes` [[x, y, z] | null; nu*nv],
//! `cell_shear_deg` [f64 | null; (nu-1)*(nv-1)], `triangles` [u32 | null; nu*nv] (the tool
//! triangle of each placed node; an extension, optional when reading).
use super::check::{cell_count, cells, check_net_shears};
use super::{write_atomic, ExportError};
use crate::geometry::Point;
use crate::kinematic::net::{Method, NodeStatus, Timing};
use crate::kinematic::{DrapeNet, Provenance};
use rayon::prelude::*;
use serde::Deserialize;
use serde_json::ser::{CompactFormatter, Formatter};
use std::collections::BTreeMap;
use std::io::{self, Write};
use std::path::Path;

/// Write `net` to `path` (normally `DIR/<ply>.drape.json`) atomically. Fails, writing nothing,
/// if a placed node or a cell shear is not finite.
pub fn write_json(net: &DrapeNet, path: &Path) -> Result<(), ExportError> {
    let shears = check_net_shears(net, false)?;
    write_json_checked(net, &shears, path)
}

/// [`write_json`] of a net that `check_net` has passed, with the cell shears it computed
/// ([`DrapeNet::cell_shears`]).
pub(crate) fn write_json_checked(net: &DrapeNet, shears: &[Option<f64>], path: &Path) -> Result<(), ExportError> {
    write_atomic(path, |w| write_json_to(net, shears, w))
}

/// Items per piece of an array formatted on one thread.
const PIECE: usize = 1 << 12;
/// Pieces formatted in parallel before they are written, in order (bounds the memory held).
const PIECES_AT_ONCE: usize = 32;

/// The byte buffers of [`write_items`], kept from one array to the next so that their memory is
/// allocated (and faulted in) once: one set being written while the other is formatted.
struct Pieces {
    written: Vec<Vec<u8>>,
    formatted: Vec<Vec<u8>>,
}

impl Pieces {
    fn new() -> Self {
        Pieces { written: vec![Vec::new(); PIECES_AT_ONCE], formatted: vec![Vec::new(); PIECES_AT_ONCE] }
    }
}

/// Write items `0..n` of an array, each appended to a byte buffer by `item` (separator
/// included): pieces of [`PIECE`] items are formatted in parallel into their own buffers and
/// written in order (the next [`PIECES_AT_ONCE`] pieces formatted while the last are written),
/// so the bytes are those of a serial loop whatever the thread count.
fn write_items<W: Write + Send>(
    w: &mut W,
    bufs: &mut Pieces,
    n: usize,
    item: impl Fn(&mut Vec<u8>, usize) + Sync,
) -> io::Result<()> {
    let pieces = n.div_ceil(PIECE);
    // Format pieces first.. (at most PIECES_AT_ONCE of them) into `into`; how many.
    let format = |into: &mut [Vec<u8>], first: usize| -> usize {
        let count = pieces.saturating_sub(first).min(PIECES_AT_ONCE);
        into[..count].par_iter_mut().enumerate().for_each(|(q, buf)| {
            let p = first + q;
            buf.clear();
            (p * PIECE..n.min((p + 1) * PIECE)).for_each(|k| item(buf, k));
        });
        count
    };
    let mut ready = format(&mut bufs.formatted, 0);
    let mut first = 0;
    while ready > 0 {
        std::mem::swap(&mut bufs.written, &mut bufs.formatted);
        first += PIECES_AT_ONCE;
        let (to_write, to_format) = (&bufs.written[..ready], &mut bufs.formatted);
        let (written, next) =
            rayon::join(|| to_write.iter().try_for_each(|b| w.write_all(b)), || format(to_format, first));
        written?;
        ready = next;
    }
    Ok(())
}

/// The JSON document of a checked net (see the module doc for the layout).
fn write_json_to<W: Write + Send>(net: &DrapeNet, shears: &[Option<f64>], w: &mut W) -> io::Result<()> {
    let bufs = &mut Pieces::new();
    w.write_all(b"{\n\"ply\": ")?;
    write_value(w, &net.name)?;
    w.write_all(b",\n\"method\": ")?;
    write_value(w, &net.method)?;
    w.write_all(b",\n\"spacing\": ")?;
    write_f64(w, net.spacing)?;
    write!(
        w,
        ",\n\"grid\": [{}, {}],\n\"origin_node\": [{}, {}],\n",
        net.nu, net.nv, net.origin_node.0, net.origin_node.1
    )?;

    let t = &net.timing;
    w.write_all(b"\"timing_ms\": {")?;
    for (k, (name, v)) in
        [("load", t.load_ms), ("generators", t.generators_ms), ("fill", t.fill_ms), ("total", t.total_ms)]
            .into_iter()
            .enumerate()
    {
        write!(w, "{}\"{name}\": ", if k > 0 { ", " } else { "" })?;
        write_f64(w, v)?;
    }
    w.write_all(b"},\n")?;

    let counts = net.status_counts();
    let placed = counts.iter().find(|(s, _)| *s == NodeStatus::Placed).map_or(0, |c| c.1);
    write!(w, "\"status\": {{\"placed\": {placed}, \"failed\": {{")?;
    for (k, (s, c)) in counts.iter().filter(|(s, _)| *s != NodeStatus::Placed).enumerate() {
        write!(w, "{}\"{}\": {c}", if k > 0 { ", " } else { "" }, s.name())?;
    }
    w.write_all(b"},\n  \"legend\": {")?;
    for (k, s) in NodeStatus::ALL.iter().enumerate() {
        write!(w, "{}\"{}\": \"{}\"", if k > 0 { ", " } else { "" }, *s as u8, s.name())?;
    }
    w.write_all(b"},\n  \"node_codes\": [")?;
    let nv = net.nv;
    write_items(w, bufs, net.status.len(), |b, k| {
        b.extend_from_slice(separator(k, nv).as_bytes());
        push_u32(b, u32::from(net.status[k] as u8));
    })?;
    w.write_all(b"]},\n\"meta\": ")?;
    write_value(w, &net.meta.to_json())?;

    w.write_all(b",\n\"nodes\": [")?;
    write_items(w, bufs, net.positions.len(), |b, k| {
        b.extend_from_slice(if k > 0 { b",\n" } else { b"\n" });
        if net.status[k] == NodeStatus::Placed {
            let p = net.positions[k];
            b.push(b'[');
            push_f64(b, p.x);
            b.extend_from_slice(b", ");
            push_f64(b, p.y);
            b.extend_from_slice(b", ");
            push_f64(b, p.z);
            b.push(b']');
        } else {
            b.extend_from_slice(b"null");
        }
    })?;
    w.write_all(b"],\n\"cell_shear_deg\": [")?;
    debug_assert_eq!(shears.len(), cell_count(net));
    write_items(w, bufs, shears.len(), |b, k| {
        b.extend_from_slice(if k > 0 { b",\n" } else { b"\n" });
        match shears[k] {
            Some(g) => push_f64(b, g.to_degrees()),
            None => b.extend_from_slice(b"null"),
        }
    })?;
    w.write_all(b"],\n\"triangles\": [")?;
    write_items(w, bufs, net.triangles.len(), |b, k| {
        b.extend_from_slice(separator(k, nv).as_bytes());
        if net.status[k] == NodeStatus::Placed {
            push_u32(b, net.triangles[k]);
        } else {
            b.extend_from_slice(b"null");
        }
    })?;
    w.write_all(b"]\n}\n")
}

/// Array separator that starts a new line at each grid row.
fn separator(k: usize, row: usize) -> &'static str {
    match k {
        0 => "\n",
        _ if k.is_multiple_of(row) => ",\n",
        _ => ", ",
    }
}

/// A finite f64 in the shortest form that parses back to the same bits.
fn write_f64<W: Write>(w: &mut W, x: f64) -> io::Result<()> {
    debug_assert!(x.is_finite(), "checked before writing");
    CompactFormatter.write_f64(w, x)
}

/// Append a finite f64 in the shortest form that parses back to the same bits (the bytes of
/// [`write_f64`]).
#[inline]
fn push_f64(b: &mut Vec<u8>, x: f64) {
    debug_assert!(x.is_finite(), "checked before writing");
    // Writing to a Vec cannot fail.
    let _ = CompactFormatter.write_f64(b, x);
}

/// Append a u32 in decimal.
#[inline]
fn push_u32(b: &mut Vec<u8>, x: u32) {
    let _ = CompactFormatter.write_u32(b, x);
}

fn write_value<W: Write, T: serde::Serialize + ?Sized>(w: &mut W, v: &T) -> io::Result<()> {
    serde_json::to_writer(w, v).map_err(io::Error::from)
}

#[derive(Deserialize)]
struct NetFile {
    ply: String,
    method: Method,
    spacing: f64,
    grid: [usize; 2],
    origin_node: [usize; 2],
    nodes: Vec<Option<[f64; 3]>>,
    cell_shear_deg: Vec<Option<f64>>,
    status: StatusFile,
    #[serde(default)]
    timing_ms: TimingFile,
    #[serde(default)]
    meta: Provenance,
    #[serde(default)]
    triangles: Option<Vec<Option<u32>>>,
}

#[derive(Deserialize)]
struct StatusFile {
    placed: usize,
    #[serde(default)]
    failed: BTreeMap<String, usize>,
    node_codes: Vec<u8>,
}

#[derive(Deserialize, Default)]
#[serde(default)]
struct TimingFile {
    load: f64,
    generators: f64,
    fill: f64,
    total: f64,
}

/// The largest coordinate of a net node, m: a thousand kilometres, beyond any part, and far
/// below where squared distances overflow (a coordinate of 1e308 made every distance NaN or
/// infinite and the mapping of `drape export` fail or run on without end).
pub const MAX_NET_COORDINATE: f64 = crate::kinematic::fishnet::MAX_COORDINATE;

/// Read a net written by [`write_json`] back, checking that its arrays fit its grid and agree with
/// each other (node null exactly where its code is not "placed", counts, cell nulls). The cell
/// shears are checked for presence only: they are derived from the nodes, which are what is kept.
/// Nodes that were not placed get the position (0, 0, 0) and triangle `u32::MAX`.
///
/// Exact f64 round trip needs serde_json's `float_roundtrip` feature (its default float parser
/// may be one ulp off).
pub fn read_net(path: &Path) -> Result<DrapeNet, ExportError> {
    let bytes = std::fs::read(path).map_err(|source| ExportError::Read { path: path.to_path_buf(), source })?;
    let f: NetFile = serde_json::from_slice(&bytes).map_err(|e| ExportError::Parse {
        path: path.to_path_buf(),
        line: e.line(),
        column: e.column(),
        message: e.to_string(),
    })?;
    drop(bytes);
    let invalid = |field: &str, reason: String| ExportError::Invalid {
        path: path.to_path_buf(),
        field: field.to_string(),
        reason,
    };

    let [nu, nv] = f.grid;
    if nu == 0 || nv == 0 {
        return Err(invalid("grid", format!("is [{nu}, {nv}]; both sizes must be at least 1")));
    }
    let n = nu.checked_mul(nv).ok_or_else(|| invalid("grid", format!("[{nu}, {nv}] is too large")))?;
    let [i0, j0] = f.origin_node;
    if i0 >= nu || j0 >= nv {
        return Err(invalid("origin_node", format!("[{i0}, {j0}] lies outside the {nu} x {nv} grid")));
    }
    if !(f.spacing.is_finite() && f.spacing > 0.0) {
        return Err(invalid("spacing", format!("is {}; it must be positive", f.spacing)));
    }
    let len_check = |field: &str, len: usize, want: usize, what: &str| {
        if len == want {
            Ok(())
        } else {
            Err(invalid(field, format!("has {len} entries but the {nu} x {nv} grid has {want} {what}")))
        }
    };
    len_check("nodes", f.nodes.len(), n, "nodes")?;
    len_check("status.node_codes", f.status.node_codes.len(), n, "nodes")?;
    let cells_n = (nu - 1) * (nv - 1);
    len_check("cell_shear_deg", f.cell_shear_deg.len(), cells_n, "cells")?;
    if let Some(t) = &f.triangles {
        len_check("triangles", t.len(), n, "nodes")?;
    }

    let mut net = DrapeNet::new(&f.ply, f.spacing, nu, nv, (i0, j0));
    net.method = f.method;
    net.meta = f.meta;
    // Kept sorted, as `DrapeNet::cell_cut` searches them (a file edited by hand may not be).
    net.meta.cut_cells.sort_unstable();
    net.meta.cut_cells.dedup();
    net.timing = Timing {
        load_ms: f.timing_ms.load,
        generators_ms: f.timing_ms.generators,
        fill_ms: f.timing_ms.fill,
        total_ms: f.timing_ms.total,
    };
    for (k, (node, &code)) in f.nodes.iter().zip(&f.status.node_codes).enumerate() {
        let (i, j) = (k / nv, k % nv);
        let status = NodeStatus::from_code(code).ok_or_else(|| {
            invalid(
                "status.node_codes",
                format!(
                    "has the unknown code {code} for node ({i}, {j}); known codes are 0 to {}",
                    NodeStatus::ALL.len() - 1
                ),
            )
        })?;
        match (node, status) {
            (Some(p), NodeStatus::Placed) => {
                if let Some(c) = p.iter().find(|c| !(c.abs() <= MAX_NET_COORDINATE)) {
                    return Err(invalid(
                        "nodes",
                        format!(
                            "gives node ({i}, {j}) the coordinate {c:e} m, beyond {MAX_NET_COORDINATE:e} m from the origin: no part is that large"
                        ),
                    ));
                }
                net.positions[k] = Point::new(p[0], p[1], p[2])
            }
            (None, s) if s != NodeStatus::Placed => {}
            (Some(_), s) => {
                return Err(invalid(
                    "nodes",
                    format!("gives a position for node ({i}, {j}) whose status is {}", s.name()),
                ))
            }
            (None, _) => return Err(invalid("nodes", format!("is null for node ({i}, {j}) whose status is placed"))),
        }
        net.status[k] = status;
        if status == NodeStatus::Placed {
            if let Some(t) = &f.triangles {
                net.triangles[k] =
                    t[k].ok_or_else(|| invalid("triangles", format!("is null for placed node ({i}, {j})")))?;
            }
        }
    }

    let counts = net.status_counts();
    let placed = counts.iter().find(|(s, _)| *s == NodeStatus::Placed).map_or(0, |c| c.1);
    if placed != f.status.placed {
        return Err(invalid("status.placed", format!("is {} but {placed} nodes are placed", f.status.placed)));
    }
    let failed: BTreeMap<String, usize> =
        counts.iter().filter(|(s, _)| *s != NodeStatus::Placed).map(|(s, c)| (s.name().to_string(), *c)).collect();
    let nonzero: BTreeMap<String, usize> = f.status.failed.into_iter().filter(|(_, c)| *c > 0).collect();
    if nonzero != failed {
        return Err(invalid("status.failed", format!("is {nonzero:?} but the node codes count {failed:?}")));
    }
    for (k, (i, j)) in cells(&net).enumerate() {
        let complete = net.cell_corners(i, j).is_some();
        match (complete, f.cell_shear_deg[k]) {
            (true, None) => {
                return Err(invalid(
                    "cell_shear_deg",
                    format!("is null for cell ({i}, {j}) whose four corners are placed"),
                ))
            }
            (false, Some(_)) => {
                return Err(invalid(
                    "cell_shear_deg",
                    format!("has a value for cell ({i}, {j}), which lacks a placed corner"),
                ))
            }
            _ => {}
        }
    }
    debug_assert_eq!(cells_n, cell_count(&net));
    Ok(net)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Vector;

    /// A 7 x 5 doubly curved net with awkward coordinates and some failed nodes.
    fn sample() -> DrapeNet {
        let mut net = DrapeNet::new("ply \"A\"/é", 0.0123456789, 7, 5, (3, 2));
        net.method = Method::Mechanical;
        for i in 0..7 {
            for j in 0..5 {
                let k = net.index(i, j);
                let (x, y) = (i as f64 * 0.1 / 3.0, j as f64 * 0.7f64.sqrt() / 10.0);
                net.positions[k] = Point::new(x + 1e-17 * j as f64, y, (x * x - y * y).sin() * std::f64::consts::PI);
                net.status[k] = NodeStatus::Placed;
                net.triangles[k] = (k * 7) as u32;
            }
        }
        let k = net.index(0, 0);
        net.status[k] = NodeStatus::NoRoot;
        let k = net.index(4, 2);
        net.status[k] = NodeStatus::Fold;
        let k = net.index(6, 4);
        net.status[k] = NodeStatus::NoRoot;
        net.timing = Timing { load_ms: 1.5, generators_ms: 0.1 + 0.2, fill_ms: 1e-9, total_ms: 123456.789 };
        net.meta.tool = Some("geometries/dome.obj".into());
        net.meta.other.insert("warp".into(), serde_json::json!([1.0, 0.0, 0.0]));
        net
    }

    #[test]
    fn floats_parse_exactly() {
        // serde_json's default parser is best-effort and can be one ulp off; the crate must enable
        // its `float_roundtrip` feature for read_net to give back the exact positions.
        let x = 2.9168327507216497e-10_f64;
        let y: f64 = serde_json::from_str(&serde_json::to_string(&x).unwrap()).unwrap();
        assert_eq!(
            x.to_bits(),
            y.to_bits(),
            "serde_json parses floats inexactly: add `features = [\"float_roundtrip\"]` to serde_json in Cargo.toml"
        );
    }

    #[test]
    fn the_surface_is_recorded_and_older_files_without_it_read_as_facets() {
        let mut net = sample();
        net.meta.surface = crate::kinematic::SurfaceKind::Smooth;
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.drape.json");
        write_json(&net, &path).unwrap();
        let mut v: serde_json::Value = serde_json::from_slice(&std::fs::read(&path).unwrap()).unwrap();
        assert_eq!(v["meta"]["surface"], "smooth");
        assert_eq!(read_net(&path).unwrap().meta.surface, crate::kinematic::SurfaceKind::Smooth);
        // A file written before the surface was recorded: draped on the facets.
        v["meta"].as_object_mut().unwrap().remove("surface");
        std::fs::write(&path, serde_json::to_vec(&v).unwrap()).unwrap();
        assert_eq!(read_net(&path).unwrap().meta.surface, crate::kinematic::SurfaceKind::Facets);
    }

    #[test]
    fn round_trip() {
        let net = sample();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.drape.json");
        write_json(&net, &path).unwrap();
        let back = read_net(&path).unwrap();
        assert_eq!((back.nu, back.nv, back.origin_node), (net.nu, net.nv, net.origin_node));
        assert_eq!(back.name, net.name);
        assert_eq!(back.method, net.method);
        assert_eq!(back.spacing.to_bits(), net.spacing.to_bits());
        assert_eq!(back.status, net.status);
        assert_eq!(back.timing, net.timing);
        assert_eq!(back.meta, net.meta);
        for k in 0..net.positions.len() {
            if net.status[k] == NodeStatus::Placed {
                let (a, b) = (net.positions[k], back.positions[k]);
                for c in 0..3 {
                    assert_eq!(a[c].to_bits(), b[c].to_bits(), "node {k} coordinate {c}: {} vs {}", a[c], b[c]);
                }
                assert_eq!(net.triangles[k], back.triangles[k]);
            } else {
                assert_eq!(back.triangles[k], u32::MAX);
            }
        }
        // The shears in the file are the net's, in degrees.
        let v: serde_json::Value = serde_json::from_slice(&std::fs::read(&path).unwrap()).unwrap();
        let shears = v["cell_shear_deg"].as_array().unwrap();
        assert_eq!(shears.len(), 6 * 4);
        for (k, (i, j)) in cells(&net).enumerate() {
            match net.cell_shear(i, j) {
                Some(g) => assert!((shears[k].as_f64().unwrap() - g.to_degrees()).abs() < 1e-12),
                None => assert!(shears[k].is_null(), "cell ({i}, {j})"),
            }
        }
        assert_eq!(v["status"]["placed"], 32);
        assert_eq!(v["status"]["failed"], serde_json::json!({"no_root": 2, "fold": 1}));
        assert_eq!(v["status"]["legend"]["3"], "no_root");
        assert_eq!(v["grid"], serde_json::json!([7, 5]));
    }

    #[test]
    fn the_file_and_the_statistics_are_the_same_whatever_the_thread_count() {
        // More nodes and cells than one piece of the parallel writer, some not placed.
        let (nu, nv) = (123, 101);
        let mut net = DrapeNet::new("threads", 0.01, nu, nv, (60, 50));
        for i in 0..nu {
            for j in 0..nv {
                let k = net.index(i, j);
                let (x, y) = (i as f64 * 0.01, j as f64 * 0.0103);
                net.positions[k] = Point::new(x, y, (3.0 * x).sin() * (2.0 * y).cos() / 7.0);
                net.status[k] = if (i * 7 + j * 3) % 97 == 0 { NodeStatus::NoRoot } else { NodeStatus::Placed };
                net.triangles[k] = (k * 13 % 9973) as u32;
            }
        }
        let dir = tempfile::tempdir().unwrap();
        let run = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            let path = dir.path().join(format!("t{threads}.drape.json"));
            pool.install(|| write_json(&net, &path)).unwrap();
            let stats = pool.install(|| net.shear_stats(0.3));
            (std::fs::read(&path).unwrap(), format!("{stats:?}"))
        };
        let (one, stats) = run(1);
        for threads in [2, 3] {
            let (bytes, s) = run(threads);
            assert!(bytes == one, "{threads} threads wrote other bytes");
            assert_eq!(s, stats, "{threads} threads");
        }
        let back = read_net(&dir.path().join("t1.drape.json")).unwrap();
        assert_eq!(back.status, net.status);
        assert_eq!(format!("{:?}", back.shear_stats(0.3)), stats);
    }

    #[test]
    fn non_finite_node_is_refused_and_nothing_written() {
        let mut net = sample();
        let k = net.index(2, 3);
        net.positions[k] = Point::new(0.0, f64::NAN, 0.0);
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.drape.json");
        let msg = write_json(&net, &path).unwrap_err().to_string();
        assert!(msg.contains("node (2, 3)") && msg.contains("bug"), "{msg}");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
        // A non-finite position of a node that is not placed is never written: fine.
        net.status[k] = NodeStatus::ShearLimit;
        write_json(&net, &path).unwrap();
        read_net(&path).unwrap();
    }

    #[test]
    fn non_finite_shear_is_refused() {
        let mut net = sample();
        // Finite but huge coordinates: the edge between them overflows to infinity.
        let (a, b) = (net.index(1, 1), net.index(2, 1));
        net.positions[a] = Point::from(Vector::repeat(f64::MAX));
        net.positions[b] = Point::from(Vector::repeat(-f64::MAX));
        let msg = write_json(&net, &tempfile::tempdir().unwrap().path().join("a.json")).unwrap_err().to_string();
        assert!(msg.contains("cell (0, 1) has a shear angle of NaN"), "{msg}");
    }

    #[test]
    fn read_rejects_inconsistent_files() {
        let net = sample();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.drape.json");
        write_json(&net, &path).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
        let broken = dir.path().join("broken.drape.json");
        let check = |v: &serde_json::Value, want: &str| {
            std::fs::write(&broken, serde_json::to_string(v).unwrap()).unwrap();
            let msg = read_net(&broken).unwrap_err().to_string();
            assert!(msg.contains(want) && msg.contains("broken.drape.json"), "{msg}");
        };
        v["nodes"].as_array_mut().unwrap().pop();
        check(&v, "\"nodes\" has 34 entries but the 7 x 5 grid has 35 nodes");
        let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
        v["cell_shear_deg"].as_array_mut().unwrap().push(serde_json::Value::Null);
        check(&v, "\"cell_shear_deg\" has 25 entries");
        let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
        v["status"]["node_codes"][1] = 3.into();
        check(&v, "node (0, 1) whose status is no_root");
        let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
        v["status"]["node_codes"][0] = 42.into();
        check(&v, "unknown code 42");
        let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
        v["origin_node"] = serde_json::json!([7, 0]);
        check(&v, "origin_node");
        // Truncated file: a parse error with a line number.
        std::fs::write(&broken, &text[..text.len() / 2]).unwrap();
        let msg = read_net(&broken).unwrap_err().to_string();
        assert!(msg.contains("line") && msg.contains("broken.drape.json"), "{msg}");
    }
}
