//! Mutation harness for every reader (issue 12, item 15): the bundled inputs (tools, flow meshes,
//! scenes, material cards, a net) mutated by byte flips, truncations, duplicated and deleted lines
//! and numbers replaced by extremes (1e308, -0, NaN, inf, 4e-12, huge integers). Every case must
//! read or be refused with an error: a panic fails the test, and a reader that does not finish
//! hangs it (the readers run in-process, one case after another; a case still running after 30 s
//! is named on stderr).
//!
//! Deterministic (a fixed seed, splitmix64) and bounded: `CASES` mutants per reader by default,
//! `DRAPE_FUZZ_CASES=n` for a longer run (`DRAPE_FUZZ_SEED` changes the seed). A mutant that
//! panicked is kept under the test target's tmp folder (`fuzz-failures/`) to reproduce it.
//!
//! Flow meshes that read are mapped onto a net and exported in every flow format (the path of
//! `drape export`), so a mutant that reads but breaks the mapping or a writer is caught too;
//! an export may refuse a mutant with an error, never with a panic or an error that calls itself
//! a bug. The `fuzz_element_nodes_*` runs mutate node ids inside elements (a number of a line
//! copied over another of the same line: repeated nodes, swapped corners) of the Nastran,
//! Abaqus, Gmsh and OBJ meshes.
//!
//! The pipeline is checked too: a few mutated scenes with a flow export run by `drape run` end
//! with exit code 0, 1 or 2 and never a panic (101), and a run that ends with 2 ("bad input,
//! nothing written") wrote nothing.
use assert_cmd::Command;
use drape::geometry::Point;
use drape::io::flow::{write_flow, FlowFormat};
use drape::io::{read_flow_mesh, read_net, read_tool, write_json};
use drape::kinematic::{DrapeNet, NodeStatus};
use drape::mapping::{map_plies, Cavity, PermeabilityModel, PlyToMap};
use drape::material::MaterialCard;
use drape::pipeline::Scene;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// Mutants per reader in the normal test run (a few seconds in all on two cores).
const CASES: usize = 150;
const SEED: u64 = 0x0d5a_9e12_f00d_0015;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn env_usize(name: &str) -> Option<u64> {
    std::env::var(name).ok().and_then(|s| s.trim().parse().ok())
}

/// splitmix64: small, fast, and the same on every platform.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    /// Uniform in 0..n (n > 0).
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
}

/// What replaces a number.
const EXTREMES: &[&str] = &[
    "1e308",
    "-1e308",
    "1e309",
    "-0",
    "-0.0",
    "NaN",
    "nan",
    "inf",
    "-inf",
    "4e-12",
    "-4e-12",
    "0",
    "-1",
    "2147483648",
    "4294967296",
    "18446744073709551615",
    "99999999999999999999999",
    "-9223372036854775808",
    "1e-320",
];

/// Byte ranges of the numbers in `b`: a digit, or a sign or point before one, and the run of
/// digits, points, exponents and signs that follows.
fn numbers(b: &[u8]) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut k = 0;
    while k < b.len() {
        let starts = b[k].is_ascii_digit()
            || ((b[k] == b'-' || b[k] == b'+' || b[k] == b'.') && b.get(k + 1).is_some_and(|c| c.is_ascii_digit()));
        if starts && (k == 0 || !(b[k - 1].is_ascii_alphanumeric() || b[k - 1] == b'_')) {
            let mut e = k + 1;
            while e < b.len() && (b[e].is_ascii_digit() || b"+-.eE".contains(&b[e])) {
                e += 1;
            }
            out.push((k, e));
            k = e;
        } else {
            k += 1;
        }
    }
    out
}

/// Byte ranges of the lines of `b`, each with its newline.
fn lines(b: &[u8]) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut s = 0;
    for (k, &c) in b.iter().enumerate() {
        if c == b'\n' {
            out.push((s, k + 1));
            s = k + 1;
        }
    }
    if s < b.len() {
        out.push((s, b.len()));
    }
    out
}

/// One to three mutations of `input`, described for the failure message.
fn mutate(rng: &mut Rng, input: &[u8]) -> (Vec<u8>, String) {
    let mut b = input.to_vec();
    let mut what = Vec::new();
    for _ in 0..1 + rng.below(3) {
        if b.is_empty() {
            break;
        }
        match rng.below(8) {
            0 => {
                let k = rng.below(b.len());
                let bit = 1u8 << rng.below(8);
                b[k] ^= bit;
                what.push(format!("flip bit {bit:#x} of byte {k}"));
            }
            1 => {
                let k = rng.below(b.len());
                b[k] = rng.next() as u8;
                what.push(format!("byte {k} set to {:#x}", b[k]));
            }
            2 => {
                let k = rng.below(b.len());
                b.truncate(k);
                what.push(format!("truncated at {k}"));
            }
            3 | 4 => {
                let ls = lines(&b);
                let (s, e) = ls[rng.below(ls.len())];
                if rng.below(2) == 0 {
                    let line = b[s..e].to_vec();
                    b.splice(s..s, line);
                    what.push(format!("line at byte {s} duplicated"));
                } else {
                    b.drain(s..e);
                    what.push(format!("line at byte {s} deleted"));
                }
            }
            _ => {
                let ns = numbers(&b);
                if ns.is_empty() {
                    continue;
                }
                let (s, e) = ns[rng.below(ns.len())];
                let x = EXTREMES[rng.below(EXTREMES.len())];
                b.splice(s..e, x.bytes());
                what.push(format!("number at byte {s} replaced by {x}"));
            }
        }
    }
    (b, what.join(", "))
}

/// Byte ranges of the integers (digits only, not part of a real) in `b`.
fn integers(b: &[u8]) -> Vec<(usize, usize)> {
    numbers(b).into_iter().filter(|&(s, e)| b[s..e].iter().all(u8::is_ascii_digit)).collect()
}

/// One or two node ids inside elements changed: on a line with three or more integers (an
/// element's id and corners in every format here), one integer copied over another, padded with
/// blanks on the left to its width so fixed columns stay in place. Gives repeated nodes, swapped
/// or unknown corners.
fn mutate_ids(rng: &mut Rng, input: &[u8]) -> (Vec<u8>, String) {
    let mut b = input.to_vec();
    let mut what = Vec::new();
    for _ in 0..1 + rng.below(2) {
        let candidates: Vec<(usize, usize)> =
            lines(&b).into_iter().filter(|&(s, e)| integers(&b[s..e]).len() >= 3).collect();
        if candidates.is_empty() {
            break;
        }
        let (s, e) = candidates[rng.below(candidates.len())];
        let ints: Vec<(usize, usize)> = integers(&b[s..e]).into_iter().map(|(a, z)| (s + a, s + z)).collect();
        let (from, to) = (ints[rng.below(ints.len())], ints[rng.below(ints.len())]);
        let mut text = b[from.0..from.1].to_vec();
        while text.len() < to.1 - to.0 {
            text.insert(0, b' ');
        }
        what.push(format!(
            "integer at byte {} ({}) copied over the one at byte {} ({})",
            from.0,
            String::from_utf8_lossy(&b[from.0..from.1]),
            to.0,
            String::from_utf8_lossy(&b[to.0..to.1])
        ));
        b.splice(to.0..to.1, text);
    }
    (b, what.join(", "))
}

/// A reader under test: reads the file at the path (a mutant of input number `usize`), Ok or a
/// message.
type Read<'a> = &'a dyn Fn(&Path, usize) -> Result<(), String>;

/// How a case's input is mutated.
type Mutate = fn(&mut Rng, &[u8]) -> (Vec<u8>, String);

/// The generator of `reader`'s mutants.
fn reader_rng(reader: &str, seed: u64) -> Rng {
    Rng(seed ^ reader.bytes().fold(0u64, |h, c| h.wrapping_mul(31).wrapping_add(c as u64)))
}

/// Mutant number `case` of a run of `reader` with `seed`, as [`fuzz`] makes it.
fn mutant(reader: &str, inputs: &[(String, Vec<u8>)], seed: u64, case: usize) -> Vec<u8> {
    let mut rng = reader_rng(reader, seed);
    for k in 0..case {
        mutate(&mut rng, &inputs[k % inputs.len()].1);
    }
    mutate(&mut rng, &inputs[case % inputs.len()].1).0
}

/// The case running now, for the watchdog: its number (u64::MAX when none) and its description.
struct Running {
    case: AtomicU64,
    what: Mutex<String>,
}

/// Read `cases` mutants of each input with `read`, writing each to `file` first. Returns the
/// number of cases tried; panics (after all cases) if any reader panicked.
fn fuzz(
    reader: &str,
    inputs: &[(String, Vec<u8>)],
    file: &Path,
    read: Read,
    mutator: Mutate,
    cases: usize,
    seed: u64,
) -> usize {
    let running = Arc::new(Running { case: AtomicU64::new(u64::MAX), what: Mutex::new(String::new()) });
    let done = Arc::new(AtomicU64::new(0));
    let watchdog = {
        let (running, done) = (running.clone(), done.clone());
        std::thread::spawn(move || {
            let (mut last, mut since, mut told) = (u64::MAX, Instant::now(), false);
            while done.load(Ordering::Relaxed) == 0 {
                std::thread::sleep(Duration::from_millis(200));
                let now = running.case.load(Ordering::Relaxed);
                if now != last {
                    (last, since, told) = (now, Instant::now(), false);
                } else if now != u64::MAX && !told && since.elapsed() > Duration::from_secs(30) {
                    eprintln!("fuzz: case {now} still running after 30 s: {}", running.what.lock().unwrap());
                    told = true;
                }
            }
        })
    };
    let mut rng = reader_rng(reader, seed);
    let mut failures = Vec::new();
    for case in 0..cases {
        let (name, input) = &inputs[case % inputs.len()];
        let (bytes, what) = mutator(&mut rng, input);
        let what = format!("{reader} case {case}, {name}: {what}");
        std::fs::write(file, &bytes).unwrap();
        *running.what.lock().unwrap() = what.clone();
        running.case.store(case as u64, Ordering::Relaxed);
        if let Err(p) = catch_unwind(AssertUnwindSafe(|| read(file, case % inputs.len()))) {
            let msg = p
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_default();
            let keep = Path::new(env!("CARGO_TARGET_TMPDIR")).join("fuzz-failures");
            std::fs::create_dir_all(&keep).unwrap();
            let ext = file.extension().and_then(|e| e.to_str()).unwrap_or("bin");
            let kept = keep.join(format!("{reader}-{case}.{ext}"));
            std::fs::write(&kept, &bytes).unwrap();
            failures.push(format!("{what}: panicked: {msg} (input kept at {})", kept.display()));
        }
    }
    done.store(1, Ordering::Relaxed);
    watchdog.join().unwrap();
    assert!(failures.is_empty(), "{} of {cases} mutants panicked:\n{}", failures.len(), failures.join("\n"));
    cases
}

fn cases() -> usize {
    env_usize("DRAPE_FUZZ_CASES").map_or(CASES, |n| n as usize)
}

fn seed() -> u64 {
    env_usize("DRAPE_FUZZ_SEED").unwrap_or(SEED)
}

fn load(paths: &[&str]) -> Vec<(String, Vec<u8>)> {
    paths.iter().map(|p| (p.to_string(), std::fs::read(root().join(p)).unwrap())).collect()
}

/// A shell-mesh reader: the flow-mesh reader and the tool reader (with the tool's checks).
fn shell_mesh(path: &Path) -> Result<(), String> {
    let flow = read_flow_mesh(path, 1.0).map(drop).map_err(|e| e.to_string());
    let tool = read_tool(path, 1.0).map(drop).map_err(|e| e.to_string());
    flow.and(tool)
}

/// The export path of the mesh mutants: per input, a flat net over the input's own mesh (as
/// read before mutation), a material card and a folder to write into.
struct Export {
    nets: Vec<DrapeNet>,
    card: MaterialCard,
    dir: tempfile::TempDir,
    /// Mutants read as flow meshes, mapped (some element covered), and written in every format.
    counts: [AtomicU64; 3],
}

/// Nodes of the export nets along each side.
const EXPORT_NET_NODES: usize = 24;

impl Export {
    fn new(inputs: &[(String, Vec<u8>)], ext: &str) -> Export {
        let dir = tempfile::tempdir().unwrap();
        let nets: Vec<Option<DrapeNet>> = inputs
            .iter()
            .map(|(name, bytes)| {
                // The bundled file where there is one (its INCLUDEs beside it), else the bytes.
                let mut p = root().join(name);
                if !p.is_file() {
                    p = dir.path().join(format!("input.{ext}"));
                    std::fs::write(&p, bytes).unwrap();
                }
                // A file that is not a mesh alone (grids to INCLUDE) takes another input's net.
                let mesh = read_flow_mesh(&p, 1.0).ok()?;
                let (lo, hi) =
                    mesh.nodes.iter().fold((mesh.nodes[0], mesh.nodes[0]), |(lo, hi), p| (lo.inf(p), hi.sup(p)));
                // A plane at the median height of the nodes, a little wider than the mesh's box.
                let mut z: Vec<f64> = mesh.nodes.iter().map(|p| p.z).collect();
                z.sort_by(f64::total_cmp);
                let size = (hi.x - lo.x).max(hi.y - lo.y);
                let spacing = 1.2 * size / (EXPORT_NET_NODES - 1) as f64;
                let n = EXPORT_NET_NODES;
                let mut net = DrapeNet::new("fuzz", spacing, n, n, (n / 2, n / 2));
                let (cx, cy, cz) = (0.5 * (lo.x + hi.x), 0.5 * (lo.y + hi.y), z[z.len() / 2]);
                for i in 0..n {
                    for j in 0..n {
                        let k = net.index(i, j);
                        let (u, v) = ((i as f64 - (n / 2) as f64) * spacing, (j as f64 - (n / 2) as f64) * spacing);
                        net.positions[k] = Point::new(cx + u, cy + v, cz);
                        net.status[k] = NodeStatus::Placed;
                        net.triangles[k] = 0;
                    }
                }
                net.meta.warp_direction = Some([1.0, 0.0, 0.0]);
                Some(net)
            })
            .collect();
        let any = nets.iter().flatten().next().expect("an input reads as a flow mesh").clone();
        let nets = nets.into_iter().map(|n| n.unwrap_or_else(|| any.clone())).collect();
        let card = MaterialCard::load(&root().join("materials/glass-plain-weave.toml")).unwrap();
        Export { nets, card, dir, counts: Default::default() }
    }

    /// Read `path` as a shell mesh; if it reads as a flow mesh, map input `input`'s net onto it
    /// and write every flow format. Errors are fine; an error that calls itself a bug is not.
    fn check(&self, path: &Path, input: usize) -> Result<(), String> {
        let read = shell_mesh(path);
        let Ok(mesh) = read_flow_mesh(path, 1.0) else { return read };
        self.counts[0].fetch_add(1, Ordering::Relaxed);
        let net = &self.nets[input];
        let ply = PlyToMap {
            net,
            card: Some(&self.card),
            thickness: Some(net.spacing / 20.0),
            permeability: Some(PermeabilityModel { fibre_radius: 8e-6 }),
        };
        let map = match map_plies(&mesh, &[ply], Cavity::Fixed, false, &mut |_| {}) {
            Ok(map) => map,
            Err(e) => return Err(e.to_string()),
        };
        self.counts[1].fetch_add(1, Ordering::Relaxed);
        let mut all = true;
        for format in FlowFormat::ALL {
            let out = self.dir.path().join(format!("flow-{}.out", format.name()));
            if let Err(e) = write_flow(&mesh, &map, format, &out) {
                let e = e.to_string();
                assert!(!e.contains("bug"), "{} export: {e}", format.name());
                all = false;
            }
        }
        if all {
            self.counts[2].fetch_add(1, Ordering::Relaxed);
        }
        read
    }
}

fn fuzz_files(reader: &str, ext: &str, inputs: &[(String, Vec<u8>)], read: Read) {
    fuzz_files_with(reader, ext, inputs, read, mutate);
}

fn fuzz_files_with(reader: &str, ext: &str, inputs: &[(String, Vec<u8>)], read: Read, mutator: Mutate) {
    let dir = tempfile::tempdir().unwrap();
    let n = fuzz(reader, inputs, &dir.path().join(format!("case.{ext}")), read, mutator, cases(), seed());
    eprintln!("fuzz {reader}: {n} mutants, no panic");
}

/// The mutants of a shell-mesh format, read, mapped and exported.
fn fuzz_meshes(reader: &str, ext: &str, inputs: &[(String, Vec<u8>)], mutator: Mutate) {
    let export = Export::new(inputs, ext);
    fuzz_files_with(reader, ext, inputs, &|p, k| export.check(p, k), mutator);
    let [read, mapped, written] = export.counts.map(|c| c.into_inner());
    eprintln!("fuzz {reader}: {read} read as flow meshes, {mapped} mapped, {written} written in every format");
}

fn nastran_inputs() -> Vec<(String, Vec<u8>)> {
    load(&[
        "tests/data/flowmesh/plate_free.bdf",
        "tests/data/flowmesh/plate_large.bdf",
        "tests/data/flowmesh/plate_quirks.bdf",
        "tests/data/flowmesh/plate_quirks_grids.bdf",
        "tests/data/flowmesh/plate_small.bdf",
    ])
}

fn abaqus_inputs() -> Vec<(String, Vec<u8>)> {
    load(&[
        "tests/data/flowmesh/plate.inp",
        "tests/data/flowmesh/plate_parts.inp",
        "tests/data/flowmesh/plate_parts_nodes.inp",
    ])
}

fn gmsh_inputs() -> Vec<(String, Vec<u8>)> {
    load(&["tests/data/flowmesh/plate.msh", "tests/data/flowmesh/plate_bin.msh"])
}

fn obj_inputs() -> Vec<(String, Vec<u8>)> {
    load(&[
        "tests/data/flowmesh/plate.obj",
        "tests/data/flowmesh/pentagon.obj",
        "geometries/square-table/square-table.obj",
    ])
}

#[test]
fn fuzz_element_nodes_nastran() {
    fuzz_meshes("nastran-nodes", "bdf", &nastran_inputs(), mutate_ids);
}

#[test]
fn fuzz_element_nodes_abaqus() {
    fuzz_meshes("abaqus-nodes", "inp", &abaqus_inputs(), mutate_ids);
}

#[test]
fn fuzz_element_nodes_gmsh() {
    // The ASCII file only: ids inside the binary one are not text.
    fuzz_meshes("gmsh-nodes", "msh", &gmsh_inputs()[..1], mutate_ids);
}

#[test]
fn fuzz_element_nodes_obj() {
    fuzz_meshes("obj-nodes", "obj", &obj_inputs(), mutate_ids);
}

#[test]
fn fuzz_obj() {
    fuzz_meshes("obj", "obj", &obj_inputs(), mutate);
}

fn stl_inputs() -> Vec<(String, Vec<u8>)> {
    let mut inputs = Vec::new();
    for p in ["tests/data/flowmesh/plate.obj", "geometries/square-table/square-table.obj"] {
        let (mesh, _) = drape::io::obj::read_obj(&root().join(p)).unwrap();
        inputs.push((format!("{p} as ASCII STL"), mesh.to_stl_ascii("part").into_bytes()));
        inputs.push((format!("{p} as binary STL"), mesh.to_stl_binary()));
    }
    inputs
}

#[test]
fn fuzz_stl() {
    fuzz_meshes("stl", "stl", &stl_inputs(), mutate);
}

#[test]
fn fuzz_nastran() {
    fuzz_meshes("nastran", "bdf", &nastran_inputs(), mutate);
}

#[test]
fn fuzz_abaqus() {
    fuzz_meshes("abaqus", "inp", &abaqus_inputs(), mutate);
}

#[test]
fn fuzz_gmsh() {
    fuzz_meshes("gmsh", "msh", &gmsh_inputs(), mutate);
}

#[test]
fn fuzz_material_card() {
    let inputs =
        load(&["materials/glass-plain-weave.toml", "materials/carbon-twill.toml", "materials/sze-liu-table1.toml"]);
    fuzz_files("card", "toml", &inputs, &|p, _| MaterialCard::load(p).map(drop).map_err(|e| e.to_string()));
}

/// A 7 x 6 net on a tilted plane, two nodes not placed.
fn small_net_json(dir: &Path) -> Vec<u8> {
    let mut net = DrapeNet::new("fuzz", 0.01, 7, 6, (3, 2));
    for i in 0..7 {
        for j in 0..6 {
            let k = net.index(i, j);
            net.positions[k] = Point::new(0.01 * i as f64, 0.01 * j as f64, 0.003 * i as f64 + 0.5);
            net.status[k] = NodeStatus::Placed;
            net.triangles[k] = k as u32;
        }
    }
    for (i, j) in [(0, 5), (6, 0)] {
        let k = net.index(i, j);
        net.status[k] = NodeStatus::OffTool;
    }
    let p = dir.join("net.drape.json");
    write_json(&net, &p).unwrap();
    std::fs::read(p).unwrap()
}

#[test]
fn fuzz_net_json() {
    let dir = tempfile::tempdir().unwrap();
    let inputs = vec![("a 7 x 6 net".to_string(), small_net_json(dir.path()))];
    fuzz_files("net", "json", &inputs, &|p, _| read_net(p).map(drop).map_err(|e| e.to_string()));
}

/// The bundled scenes, read from a copy of `geometries/<dir>/` beside a copy of `materials/`, so
/// the cards they name are found (and read, mutated scene or not).
#[test]
fn fuzz_scene() {
    let dir = tempfile::tempdir().unwrap();
    let materials = dir.path().join("materials");
    std::fs::create_dir_all(&materials).unwrap();
    for e in std::fs::read_dir(root().join("materials")).unwrap() {
        let e = e.unwrap();
        std::fs::copy(e.path(), materials.join(e.file_name())).unwrap();
    }
    let mut inputs = Vec::new();
    let mut scenes: Vec<PathBuf> = std::fs::read_dir(root().join("geometries"))
        .unwrap()
        .flat_map(|d| std::fs::read_dir(d.unwrap().path()).into_iter().flatten())
        .map(|f| f.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    scenes.sort();
    for p in &scenes {
        inputs.push((p.strip_prefix(root()).unwrap().display().to_string(), std::fs::read(p).unwrap()));
    }
    assert!(inputs.len() >= 10, "{} scenes", inputs.len());
    let scene_dir = dir.path().join("geometries").join("case");
    std::fs::create_dir_all(&scene_dir).unwrap();
    let n = fuzz(
        "scene",
        &inputs,
        &scene_dir.join("scene.toml"),
        &|p, _| Scene::load(p).map(drop).map_err(|e| e.to_string()),
        mutate,
        cases(),
        seed(),
    );
    eprintln!("fuzz scene: {n} mutants, no panic");
}

/// A two-ply scene on a 10 x 10 plate with a flow export onto the plate in every format,
/// mutated, run end to end by `drape run`: exit 0, 1 or 2, never a panic; a run that fails leaves
/// no file half written, and one that ends with 2 (bad input) wrote nothing at all.
#[test]
fn fuzz_scene_through_the_pipeline() {
    let dir = tempfile::tempdir().unwrap();
    let mut obj = String::new();
    for i in 0..=10 {
        for j in 0..=10 {
            obj += &format!("v {} {} 0\n", i as f64 / 10.0 - 0.5, j as f64 / 10.0 - 0.5);
        }
    }
    for i in 0..10 {
        for j in 0..10 {
            let a = i * 11 + j + 1;
            obj += &format!("f {a} {} {}\nf {a} {} {}\n", a + 11, a + 12, a + 12, a + 1);
        }
    }
    std::fs::write(dir.path().join("plate.obj"), obj).unwrap();
    let card = root().join("materials/glass-plain-weave.toml");
    let scene = format!(
        "units = \"m\"\ntool = \"plate.obj\"\nreference = [1.0, 0.0, 0.0]\nroll_width = 1.0\n\n[materials]\nglass = {card:?}\n\n\
         [export]\nmesh = \"plate.obj\"\nformats = [\"vtu\", \"nastran\", \"abaqus\", \"calculix\", \"optistruct\", \"rtmsim\", \"csv\"]\npermeability = true\n\n\
         [[ply]]\nname = \"p0\"\norigin = [0.0, 0.0, 0.0]\nangle_deg = 30.0\nmaterial = \"glass\"\nspacing = 0.05\ngrid = [11, 11]\n\n\
         [[ply]]\nname = \"p1\"\norigin = [0.1, 0.0, 0.0]\nangle_deg = -45.0\nmaterial = \"glass\"\nspacing = 0.04\ngrid = [9, 9]\n"
    );
    let cases = env_usize("DRAPE_FUZZ_PIPELINE_CASES").unwrap_or(8) as usize;
    let mut rng = Rng(seed());
    let mut codes = [0usize; 3];
    for case in 0..cases {
        // Numbers only, and the mutated scene must still parse as TOML now and then: one or two
        // numbers replaced by extremes.
        let mut b = scene.clone().into_bytes();
        let mut what = Vec::new();
        for _ in 0..1 + rng.below(2) {
            let ns = numbers(&b);
            let (s, e) = ns[rng.below(ns.len())];
            let x = EXTREMES[rng.below(EXTREMES.len())];
            what.push(format!("{} -> {x}", String::from_utf8_lossy(&b[s..e])));
            b.splice(s..e, x.bytes());
        }
        let path = dir.path().join(format!("scene{case}.toml"));
        std::fs::write(&path, &b).unwrap();
        let out = dir.path().join(format!("run{case}"));
        let o = Command::cargo_bin("drape").unwrap().args(["run"]).arg(&path).arg("--out").arg(&out).output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        let code = o.status.code();
        assert!(
            matches!(code, Some(0..=2)) && !err.contains("panicked"),
            "case {case} ({}): exit {code:?}\n{err}",
            what.join(", ")
        );
        codes[code.unwrap() as usize] += 1;
        if code == Some(2) && out.exists() {
            let files: Vec<_> = std::fs::read_dir(&out).unwrap().map(|f| f.unwrap().file_name()).collect();
            assert!(
                files.is_empty(),
                "case {case} ({}): exit 2 (nothing written) but wrote {files:?}\n{err}",
                what.join(", ")
            );
        }
        if code != Some(0) && out.exists() {
            // Nothing half written: every file there is whole (the atomic writer leaves no temporaries).
            for f in std::fs::read_dir(&out).unwrap() {
                let name = f.unwrap().file_name().to_string_lossy().to_string();
                assert!(!name.contains(".tmp-"), "case {case}: {name} left in {}", out.display());
            }
        }
    }
    eprintln!("fuzz pipeline: {cases} mutated scenes, exit codes 0/1/2: {codes:?}");
}

/// Found by the harness: a Gmsh block whose node or element count is negative or beyond the file
/// sized a vector by it (capacity overflow, or an allocation of 32 GB that aborted the process).
#[test]
fn gmsh_block_counts_beyond_the_file_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(root().join("tests/data/flowmesh/plate.msh")).unwrap();
    for (from, to) in [("2 1 0 6\n", "2 1 0 -1\n"), ("2 1 0 6\n", "2 1 0 4294967296000\n")] {
        let p = dir.path().join("bad.msh");
        std::fs::write(&p, text.replacen(from, to, 1)).unwrap();
        let Err(e) = read_flow_mesh(&p, 1.0) else { panic!("read: {to}") };
        let e = e.to_string();
        assert!(e.contains("node block of") && e.contains("lines left"), "{e}");
    }
}

/// Found by the harness: a scene whose grid is far too large for memory, on a ply with sheet
/// features (a seam), laid the features out per node while loading (an allocation of 200 GB that
/// aborted the process); the grid is refused when it is read.
#[test]
fn a_scene_grid_beyond_memory_is_refused_when_read() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(root().join("geometries/sphere/seam.toml")).unwrap();
    let card = root().join("materials/sze-liu-table1.toml");
    let text = text
        .replace("grid = [94, 91]", "grid = [94, 4294967296]")
        .replace("\"../../materials/sze-liu-table1.toml\"", &format!("{card:?}"));
    let p = dir.path().join("scene.toml");
    std::fs::write(&p, text).unwrap();
    let Err(e) = Scene::load(&p) else { panic!("read") };
    let e = e.to_string();
    assert!(e.contains("field `grid`") && e.contains("MB of memory"), "{e}");
}

/// Found by the harness: corners at 1e-320 beside corners at 0 (triangles whose centres differ by
/// a subnormal number) made parry's BVH build index a bin at infinity; and a fold row of
/// 2^64 - 1 wrapped past the check that it lies inside the grid.
#[test]
fn subnormal_corners_and_a_fold_row_beyond_the_grid_are_read_without_panic() {
    let dir = tempfile::tempdir().unwrap();
    // Seed 7, case 9030: a line duplicated, a coordinate set to 1e-320 and one to -4e-12.
    let p = dir.path().join("case.stl");
    std::fs::write(&p, mutant("stl", &stl_inputs(), 7, 9030)).unwrap();
    assert!(shell_mesh(&p).is_ok());
    let text = std::fs::read_to_string(root().join("geometries/sphere/fold.toml")).unwrap();
    let card = root().join("materials/sze-liu-table1.toml");
    let text = text.replace("\"../../materials/sze-liu-table1.toml\"", &format!("{card:?}")).replacen(
        "row = ",
        "row = 18446744073709551615 # ",
        1,
    );
    let p = dir.path().join("scene.toml");
    std::fs::write(&p, text).unwrap();
    let Err(e) = Scene::load(&p) else { panic!("read") };
    assert!(e.to_string().contains("fold at row 18446744073709551615"), "{e}");
}
