//! The Python module `drape`: the library's pipeline (`drape::pipeline`) and placement
//! optimisation (`drape::study::optimise`) called from Python, a draped net as numpy arrays. Every function here converts arguments, calls the same library
//! functions as the command line (with the GIL released while they work) and converts the
//! result; a refusal is raised with the command line's message.
use drape::geometry::{Point, ToolSurface};
use drape::io::{read_net, write_json, Format};
use drape::kinematic::{DrapeNet, NodeStatus};
use drape::layup::DEFAULT_LOCKING_ANGLE_DEG;
use drape::material::MaterialCard;
use drape::pipeline::export::{export_net, parse_cavity, ExportOptions};
use drape::pipeline::failure::{compute, input, write_failure, Failure};
use drape::pipeline::ply::{check_converged, read_tool, PlyOptions};
use drape::pipeline::refine::{check_refined, parse_mode, parse_stack_side, refine_net, RefineOptions};
use drape::pipeline::run::{run as run_scene, RunError};
use drape::pipeline::Scene;
use drape::study::optimise::run::{
    parse_angle_range, DEFAULT_ANGLE_RANGE, DEFAULT_ANGLE_STEP, DEFAULT_OBJECTIVE, DEFAULT_VARY,
};
use drape::study::optimise::{self as opt, PolygonArg, Request, DEFAULT_MAX_CANDIDATES, DEFAULT_REFINE_STARTS};
use drape::study::runner::jobs_or_cores;
use drape::study::{Finished, Shard};
use numpy::ndarray::{Array2, Array3};
use numpy::{IntoPyArray, PyArray2, PyArray3, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::create_exception;
use pyo3::exceptions::PyException;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyTuple};
use std::path::{Path, PathBuf};
use std::time::Instant;

create_exception!(drape, DrapeError, PyException, "A drape command failed; the message says why.");
create_exception!(
    drape,
    InputError,
    DrapeError,
    "The input is wrong (the command line's exit code 2); the message says how to fix it."
);
create_exception!(
    drape,
    ComputeError,
    DrapeError,
    "The computation failed (the command line's exit code 1), e.g. a solver that stopped short; \
     what was computed is attached (`net` or `layup`) where there is one."
);

/// The Python exception of a library failure, with the command line's message.
fn to_py(failure: Failure) -> PyErr {
    match failure {
        Failure::Input(_) => InputError::new_err(failure.message()),
        Failure::Compute(_) => ComputeError::new_err(failure.message()),
    }
}

/// A [`ComputeError`] that carries what was computed as attribute `name`.
fn compute_error_with<'py>(py: Python<'py>, failure: Failure, name: &str, value: Bound<'py, PyAny>) -> PyErr {
    let err = to_py(failure);
    // Attaching can only fail on an exception object that refuses attributes, which ours do not.
    let _ = err.value(py).setattr(name, value);
    err
}

/// Warn in Python (a `UserWarning`), as the command line prints `warning: ...`.
fn warn(py: Python<'_>, message: &str) -> PyResult<()> {
    py.import("warnings")?.call_method1("warn", (message,))?;
    Ok(())
}

/// A JSON text as Python objects (dicts, lists, numbers, strings).
fn json_to_py<'py>(py: Python<'py>, text: &str) -> PyResult<Bound<'py, PyAny>> {
    py.import("json")?.call_method1("loads", (text,))
}

/// A tool as Python gives it: a file, or vertices and triangles in memory.
enum ToolArg {
    File(PathBuf),
    Arrays { vertices: Vec<Point>, triangles: Vec<[u32; 3]> },
}

impl ToolArg {
    /// A path (`str` or `os.PathLike`), or a pair `(vertices (n, 3), triangles (m, 3))` of
    /// array-likes.
    fn extract<'py>(tool: &Bound<'py, PyAny>) -> PyResult<ToolArg> {
        if let Ok(path) = tool.extract::<PathBuf>() {
            return Ok(ToolArg::File(path));
        }
        let bad = || {
            InputError::new_err(
                "tool: give a file (OBJ, STL, or a shell mesh) or a pair (vertices, triangles) of arrays shaped (n, 3) and (m, 3)",
            )
        };
        let pair = tool.cast::<PyTuple>().map_err(|_| bad())?;
        if pair.len() != 2 {
            return Err(bad());
        }
        let np = tool.py().import("numpy")?;
        let as_array = |item: Bound<'py, PyAny>, dtype: &str| np.call_method1("ascontiguousarray", (item, dtype));
        let vertices = as_array(pair.get_item(0)?, "float64")?;
        let vertices: PyReadonlyArray2<f64> = vertices.extract().map_err(|_| bad())?;
        let triangles = as_array(pair.get_item(1)?, "int64")?;
        let triangles: PyReadonlyArray2<i64> = triangles.extract().map_err(|_| bad())?;
        if vertices.shape()[1] != 3 || triangles.shape()[1] != 3 {
            return Err(InputError::new_err(format!(
                "tool: vertices are shaped {:?} and triangles {:?}; both must be (n, 3)",
                vertices.shape(),
                triangles.shape()
            )));
        }
        let vertices = vertices.as_array().rows().into_iter().map(|r| Point::new(r[0], r[1], r[2])).collect();
        let mut corners = Vec::with_capacity(triangles.shape()[0]);
        for (t, row) in triangles.as_array().rows().into_iter().enumerate() {
            let mut tri = [0u32; 3];
            for (c, &index) in tri.iter_mut().zip(row) {
                *c = u32::try_from(index).map_err(|_| {
                    InputError::new_err(format!(
                        "tool: triangle {t} has the vertex index {index}; indices are 0-based and at least 0"
                    ))
                })?;
            }
            corners.push(tri);
        }
        Ok(ToolArg::Arrays { vertices, triangles: corners })
    }

    /// The checked tool surface, lengths times `scale` (metres per unit); runs without the GIL.
    fn load(self, scale: f64) -> Result<(ToolSurface, Option<String>), Failure> {
        match self {
            ToolArg::File(path) => Ok((read_tool(&path, scale)?, Some(path.display().to_string()))),
            ToolArg::Arrays { mut vertices, triangles } => {
                vertices.iter_mut().for_each(|v| *v *= scale);
                let tool =
                    ToolSurface::from_triangles(vertices, triangles).map_err(|e| input(anyhow::anyhow!("{e}")))?;
                Ok((tool, None))
            }
        }
    }
}

/// A draped net: the warp/weft grid of one ply, node (i, j) with i along the warp.
///
/// The arrays are new copies at each access. `positions` (nu, nv, 3), metres, NaN where a node
/// was not placed; `status` (nu, nv) says why (`placed`, `off_tool`, `no_root`, `shear_limit`,
/// `fold`, `sheet_jump`, `parent_missing`, `outside_outline`, ...); `shear_deg` (nu-1, nv-1)
/// and the unit fibre directions `warp`, `weft` (nu-1, nv-1, 3) per cell, NaN where a cell
/// lacks a corner; `meta` the provenance (the JSON file's `"meta"`) as a dict.
#[pyclass(module = "drape", name = "Net", frozen)]
struct Net {
    net: DrapeNet,
}

#[pymethods]
impl Net {
    /// Read a net from a `<ply>.drape.json` file (the JSON contract).
    #[staticmethod]
    fn load(py: Python<'_>, path: PathBuf) -> PyResult<Net> {
        let net = py.detach(|| read_net(&path)).map_err(|e| to_py(input(e)))?;
        Ok(Net { net })
    }

    /// Write the net as JSON to `path` (the JSON contract, as `drape kinematic` writes
    /// `<ply>.drape.json`), atomically, creating its folder. Returns the path.
    fn save(&self, py: Python<'_>, path: PathBuf) -> PyResult<PathBuf> {
        // The folder is created, as the command line creates its --out folder.
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir)
                .map_err(|e| InputError::new_err(format!("cannot create the folder {} ({e})", dir.display())))?;
        }
        py.detach(|| write_json(&self.net, &path)).map_err(|e| to_py(write_failure(e)))?;
        Ok(path)
    }

    /// The ply's name.
    #[getter]
    fn name(&self) -> &str {
        &self.net.name
    }

    /// `"kinematic"` or `"mechanical"`.
    #[getter]
    fn method(&self) -> PyResult<String> {
        serde_json::to_value(self.net.method)
            .ok()
            .and_then(|v| v.as_str().map(str::to_string))
            .ok_or_else(|| DrapeError::new_err("the net's method has no name"))
    }

    /// Fibre segment length d, metres.
    #[getter]
    fn spacing(&self) -> f64 {
        self.net.spacing
    }

    /// Grid size (nu, nv).
    #[getter]
    fn grid(&self) -> (usize, usize) {
        (self.net.nu, self.net.nv)
    }

    /// Grid indices (i, j) of the seed node.
    #[getter]
    fn origin_node(&self) -> (usize, usize) {
        self.net.origin_node
    }

    /// Node positions (nu, nv, 3), metres; NaN where not placed.
    #[getter]
    fn positions<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray3<f64>> {
        let n = &self.net;
        Array3::from_shape_fn((n.nu, n.nv, 3), |(i, j, c)| n.node(i, j).map_or(f64::NAN, |p| p[c])).into_pyarray(py)
    }

    /// Cell shear (nu-1, nv-1), degrees; NaN where a cell lacks a placed corner.
    #[getter]
    fn shear_deg<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        let n = &self.net;
        let cv = n.nv.saturating_sub(1);
        let shears = n.cell_shears();
        Array2::from_shape_fn((n.nu.saturating_sub(1), cv), |(i, j)| {
            shears[i * cv + j].map_or(f64::NAN, f64::to_degrees)
        })
        .into_pyarray(py)
    }

    /// Unit warp direction of each cell (nu-1, nv-1, 3); NaN where a cell lacks a corner.
    #[getter]
    fn warp<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray3<f64>> {
        self.cell_directions(py, |f| f.warp)
    }

    /// Unit weft direction of each cell (nu-1, nv-1, 3); NaN where a cell lacks a corner.
    #[getter]
    fn weft<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray3<f64>> {
        self.cell_directions(py, |f| f.weft)
    }

    /// Each node's status (nu, nv) as a string: `placed`, or why it was not placed.
    #[getter]
    fn status<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let names = PyList::new(py, self.net.status.iter().map(|s| s.name()))?;
        py.import("numpy")?.call_method1("array", (names,))?.call_method1("reshape", ((self.net.nu, self.net.nv),))
    }

    /// The net's provenance (`"meta"` of the JSON file) as a dict.
    #[getter]
    fn meta<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let text = serde_json::to_string(&self.net.meta).map_err(|e| DrapeError::new_err(e.to_string()))?;
        json_to_py(py, &text)
    }

    fn __repr__(&self) -> String {
        let placed = self.net.status.iter().filter(|s| **s == NodeStatus::Placed).count();
        format!(
            "<drape.Net '{}' {} x {} nodes, {} placed, spacing {} m>",
            self.net.name, self.net.nu, self.net.nv, placed, self.net.spacing
        )
    }
}

impl Net {
    /// One direction of each cell's frame, NaN where the cell has none.
    fn cell_directions<'py>(
        &self,
        py: Python<'py>,
        pick: impl Fn(&drape::kinematic::net::CellFrame) -> drape::geometry::Vector,
    ) -> Bound<'py, PyArray3<f64>> {
        let n = &self.net;
        let (cu, cv) = (n.nu.saturating_sub(1), n.nv.saturating_sub(1));
        let mut out = Array3::from_elem((cu, cv, 3), f64::NAN);
        for i in 0..cu {
            for j in 0..cv {
                if let Some(frame) = n.cell_frame(i, j) {
                    let d = pick(&frame);
                    (0..3).for_each(|c| out[[i, j, c]] = d[c]);
                }
            }
        }
        out.into_pyarray(py)
    }
}

/// Drape one ply on a tool with the kinematic (fishnet) method, as `drape kinematic` does.
#[pyfunction]
#[pyo3(signature = (
    tool, origin, warp, spacing, grid=None, *, outline=None, origin_node=None, generators=None,
    surface=None, max_shear_deg=None, pre_shear_deg=None, method=None, material=None,
    tolerance_deg=None, locking_angle_deg=None, units=None, name=None
))]
#[allow(clippy::too_many_arguments)]
fn kinematic(
    py: Python<'_>,
    tool: &Bound<'_, PyAny>,
    origin: [f64; 3],
    warp: [f64; 3],
    spacing: f64,
    grid: Option<[usize; 2]>,
    outline: Option<PathBuf>,
    origin_node: Option<[usize; 2]>,
    generators: Option<String>,
    surface: Option<String>,
    max_shear_deg: Option<f64>,
    pre_shear_deg: Option<f64>,
    method: Option<String>,
    material: Option<PathBuf>,
    tolerance_deg: Option<f64>,
    locking_angle_deg: Option<f64>,
    units: Option<String>,
    name: Option<String>,
) -> PyResult<Net> {
    let tool = ToolArg::extract(tool)?;
    let defaults = PlyOptions::default();
    let options = PlyOptions {
        origin,
        warp,
        spacing,
        grid,
        outline,
        origin_node,
        pre_shear_deg: pre_shear_deg.unwrap_or(defaults.pre_shear_deg),
        generators: generators.unwrap_or(defaults.generators),
        max_shear_deg: max_shear_deg.unwrap_or(defaults.max_shear_deg),
        surface: surface.unwrap_or(defaults.surface),
        locking_angle_deg,
        method: method.unwrap_or(defaults.method),
        material,
        tolerance_deg,
        units: units.unwrap_or(defaults.units),
        name: name.unwrap_or(defaults.name),
    };
    let (net, warning) = py
        .detach(|| -> Result<_, Failure> {
            let ply = options.prepare()?;
            let t_load = Instant::now();
            let (tool, path) = tool.load(ply.scale)?;
            let load_ms = t_load.elapsed().as_secs_f64() * 1e3;
            let mut net = ply.drape(&tool)?;
            net.timing.load_ms = load_ms;
            net.meta.tool = path;
            net.meta.tool_scale = Some(ply.scale);
            let max_shear = net.shear_stats(ply.locking_angle_deg.to_radians()).max_abs.to_degrees();
            Ok((net, ply.shear_range_warning(max_shear)))
        })
        .map_err(to_py)?;
    if let Some(w) = warning {
        warn(py, &format!("ply '{}': {w}", net.name))?;
    }
    if let Err(failure) = check_converged(&net) {
        let net = Bound::new(py, Net { net })?.into_any();
        return Err(compute_error_with(py, failure, "net", net));
    }
    Ok(Net { net })
}

/// Refine a net mechanically on a tool under a material card, as `drape refine` does.
#[pyfunction]
#[pyo3(signature = (
    net, tool, material, mode="pressed", *, units=None, facets=false, gravity=None, load_steps=None,
    stick=false, friction=None, holds=None, escape_saddles=false, max_iterations=None, die=None,
    stack_side=None
))]
#[allow(clippy::too_many_arguments)]
fn refine(
    py: Python<'_>,
    net: &Net,
    tool: &Bound<'_, PyAny>,
    material: PathBuf,
    mode: &str,
    units: Option<String>,
    facets: bool,
    gravity: Option<[f64; 3]>,
    load_steps: Option<usize>,
    stick: bool,
    friction: Option<f64>,
    holds: Option<Vec<[usize; 2]>>,
    escape_saddles: bool,
    max_iterations: Option<usize>,
    die: Option<PathBuf>,
    stack_side: Option<String>,
) -> PyResult<Net> {
    let tool = ToolArg::extract(tool)?;
    let defaults = RefineOptions::default();
    let options = RefineOptions {
        mode: parse_mode(mode).map_err(to_py)?,
        units,
        facets,
        gravity: gravity.unwrap_or(defaults.gravity),
        load_steps: load_steps.unwrap_or(defaults.load_steps),
        stick,
        friction,
        holds: holds.unwrap_or_default(),
        escape_saddles,
        max_iterations: max_iterations.unwrap_or(defaults.max_iterations),
        die,
        stack_side: stack_side.as_deref().map(parse_stack_side).transpose().map_err(to_py)?,
    };
    let kinematic = &net.net;
    let (refined_net, refined, warning) = py
        .detach(|| -> Result<_, Failure> {
            options.check()?;
            let card = MaterialCard::load(&material).map_err(input)?;
            let settings = options.settings(kinematic, &card)?;
            let scale = options.tool_scale(kinematic)?;
            let t_load = Instant::now();
            let (tool, _) = tool.load(scale)?;
            let load_ms = t_load.elapsed().as_secs_f64() * 1e3;
            let label = format!("'{}'", kinematic.name);
            let (mut out, refined) =
                refine_net(kinematic, &label, &tool, options.stack_side(kinematic), &card, &material, &settings)?;
            out.timing.load_ms = load_ms;
            out.timing.total_ms += load_ms;
            let max_shear = out.shear_stats(DEFAULT_LOCKING_ANGLE_DEG.to_radians()).max_abs.to_degrees();
            let warning = card.shear_range_warning(max_shear);
            Ok((out, refined, warning))
        })
        .map_err(to_py)?;
    if let Some(w) = warning {
        warn(py, &format!("ply '{}': {w}", refined_net.name))?;
    }
    if let Err(failure) = check_refined(&refined) {
        let net = Bound::new(py, Net { net: refined_net })?.into_any();
        return Err(compute_error_with(py, failure, "net", net));
    }
    Ok(Net { net: refined_net })
}

/// The layup a `drape run` wrote: its table (`layup.json`) and where its files are.
#[pyclass(module = "drape", name = "Layup", frozen)]
struct Layup {
    table: Py<PyAny>,
    out: PathBuf,
}

#[pymethods]
impl Layup {
    /// One dict per ply, in stacking order: the layup table's rows (angle, method, locking
    /// angle, shear, coverage, fabric area and mass, offset, ...).
    #[getter]
    fn plies<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.table.bind(py).get_item("plies")
    }

    /// The whole `layup.json` as a dict (rows, nesting, files written, flow export).
    #[getter]
    fn table<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        self.table.bind(py).clone()
    }

    /// The run folder.
    #[getter]
    fn out(&self) -> PathBuf {
        self.out.clone()
    }

    /// The net of ply `name`, read from the run folder (written with the `json` format).
    fn net(&self, py: Python<'_>, name: &str) -> PyResult<Net> {
        Net::load(py, Format::Json.path(&self.out, name))
    }

    fn __len__(&self, py: Python<'_>) -> PyResult<usize> {
        self.plies(py)?.len()
    }

    fn __repr__(&self, py: Python<'_>) -> PyResult<String> {
        Ok(format!("<drape.Layup of {} plies in {}>", self.__len__(py)?, self.out.display()))
    }
}

/// The layup table a run wrote into `out`, as a [`Layup`].
fn read_layup(py: Python<'_>, out: &Path) -> PyResult<Layup> {
    let table = py
        .detach(|| drape::io::layup_json::read(out))
        .map_err(|e| DrapeError::new_err(e.to_string()))?
        .ok_or_else(|| DrapeError::new_err(format!("{}: the run wrote no layup.json", out.display())))?;
    let text = serde_json::to_string(&table).map_err(|e| DrapeError::new_err(e.to_string()))?;
    Ok(Layup { table: json_to_py(py, &text)?.unbind(), out: out.to_path_buf() })
}

/// Drape every ply of a scene file into the folder `out`, as `drape run` does.
#[pyfunction]
#[pyo3(signature = (scene, out, *, formats="json,vtu,csv", replace=false))]
fn run(py: Python<'_>, scene: PathBuf, out: PathBuf, formats: &str, replace: bool) -> PyResult<Layup> {
    let formats = Format::parse_list(formats).map_err(|m| to_py(input(anyhow::anyhow!("--format: {m}"))))?;
    let result = py.detach(|| -> Result<(), Failure> {
        let scene = Scene::load(&scene).map_err(input)?;
        run_scene(&scene, &out, &formats, replace, &mut |_| {}).map_err(|e: RunError| {
            if e.is_bad_input() {
                input(e)
            } else {
                compute(e)
            }
        })
    });
    match result {
        Ok(()) => read_layup(py, &out),
        Err(failure @ Failure::Compute(_)) => match read_layup(py, &out) {
            Ok(layup) => Err(compute_error_with(py, failure, "layup", Bound::new(py, layup)?.into_any())),
            Err(_) => Err(to_py(failure)),
        },
        Err(failure) => Err(to_py(failure)),
    }
}

/// Map a net onto a resin-flow shell mesh and write it in `format` to `out`, as `drape export`
/// does. Returns a dict: the files written, the mesh's size, the elements covered and their
/// shear, and the notes on the mesh and the map.
#[pyfunction]
#[pyo3(signature = (
    net, mesh, format, out, *, mesh_units=None, material=None, thickness=None, cavity="fixed",
    permeability=false, fibre_radius=None, material_name=None, vtu=None
))]
#[allow(clippy::too_many_arguments)]
fn export<'py>(
    py: Python<'py>,
    net: &Net,
    mesh: PathBuf,
    format: &str,
    out: PathBuf,
    mesh_units: Option<String>,
    material: Option<PathBuf>,
    thickness: Option<f64>,
    cavity: &str,
    permeability: bool,
    fibre_radius: Option<f64>,
    material_name: Option<String>,
    vtu: Option<String>,
) -> PyResult<Bound<'py, PyDict>> {
    let defaults = ExportOptions::default();
    let options = ExportOptions {
        mesh_units: mesh_units.unwrap_or(defaults.mesh_units),
        material,
        thickness,
        cavity: parse_cavity(cavity).map_err(to_py)?,
        permeability,
        fibre_radius,
        material_name: material_name.unwrap_or(defaults.material_name),
        vtu: vtu.unwrap_or(defaults.vtu),
    };
    let mut notes = Vec::new();
    let done = py
        .detach(|| {
            let plan = options.check(format, &out)?;
            export_net(&net.net, &mesh, &out, &plan, &options, &mut |n| notes.push(n.to_string()))
        })
        .map_err(to_py)?;
    let coverage = done.map.coverage();
    let result = PyDict::new(py);
    result.set_item("files", done.files)?;
    result.set_item("nodes", done.mesh.nodes.len())?;
    result.set_item("elements", coverage.elements)?;
    result.set_item("covered", coverage.covered)?;
    result.set_item("max_abs_shear_deg", coverage.max_abs_shear_deg)?;
    result.set_item("mean_abs_shear_deg", coverage.mean_abs_shear_deg)?;
    result.set_item("vf_capped", coverage.capped)?;
    result.set_item("collapsed", coverage.collapsed)?;
    result.set_item("notes", notes)?;
    Ok(result)
}

/// An optimisation's result (`optimise.json` in its folder) and the files it wrote.
#[pyclass(module = "drape", name = "Optimisation", frozen)]
struct Optimisation {
    result: Py<PyAny>,
    files: Vec<PathBuf>,
    scene: PathBuf,
    out: PathBuf,
}

#[pymethods]
impl Optimisation {
    /// The best placement at the ply's spacing, a dict: `origin` (the seed on the tool, m),
    /// `angle_deg`, `objective`, `stats` (the figures it is made of), `seed_ab`, `spacing`,
    /// `outcome` and `start` (the global search's candidate it was refined from).
    #[getter]
    fn best<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.result.bind(py).get_item("best")
    }

    /// The best placement's objective (smaller is better).
    #[getter]
    fn objective(&self, py: Python<'_>) -> PyResult<f64> {
        self.best(py)?.get_item("objective")?.extract()
    }

    /// The other refined placements, best first, as dicts like `best`.
    #[getter]
    fn runners_up<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.result.bind(py).get_item("runners_up")
    }

    /// Every candidate of the global search in plan order (the objective's landscape), dicts:
    /// `index`, `seed_ab`, `origin`, `angle_deg`, `objective` (None where it gave no complete
    /// cell), `outcome`.
    #[getter]
    fn landscape<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.result.bind(py).get_item("landscape")
    }

    /// The whole `optimise.json` as a dict.
    #[getter]
    fn result<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        self.result.bind(py).clone()
    }

    /// The files written: `optimise.json`, the scene with the optimal ply, the landscape
    /// pictures (PNG, SVG).
    #[getter]
    fn files(&self) -> Vec<PathBuf> {
        self.files.clone()
    }

    /// The scene with the optimal ply (`optimal.toml`), ready for `drape.run`.
    #[getter]
    fn scene(&self) -> PathBuf {
        self.scene.clone()
    }

    /// The optimisation's folder.
    #[getter]
    fn out(&self) -> PathBuf {
        self.out.clone()
    }

    fn __repr__(&self, py: Python<'_>) -> PyResult<String> {
        let best = self.best(py)?;
        Ok(format!(
            "<drape.Optimisation of ply {}: {} = {} at {} deg, seed {} in {}>",
            self.result.bind(py).get_item("ply")?,
            self.result.bind(py).get_item("objective_text")?,
            best.get_item("objective")?,
            best.get_item("angle_deg")?,
            best.get_item("origin")?,
            self.out.display()
        ))
    }
}

/// `vary` as Python gives it: `"seed,angle"` or a sequence like `["seed", "angle"]`.
fn vary_arg(vary: &Bound<'_, PyAny>) -> PyResult<String> {
    if let Ok(text) = vary.extract::<String>() {
        return Ok(text);
    }
    let names: Vec<String> = vary
        .extract()
        .map_err(|_| InputError::new_err("vary: give \"seed\", \"angle\", \"seed,angle\" or a list of them"))?;
    Ok(names.join(","))
}

/// `seed_polygon` as Python gives it: a points file, the corners as text (`x,y,z;x,y,z;...`), or
/// an array-like of corners shaped (n, 3).
fn polygon_arg(polygon: &Bound<'_, PyAny>) -> PyResult<PolygonArg> {
    if let Ok(path) = polygon.extract::<PathBuf>() {
        return Ok(PolygonArg::Text(path.to_string_lossy().into_owned()));
    }
    let bad = || {
        InputError::new_err(
            "seed_polygon: give a points file, the corners as x,y,z;x,y,z;... or an array shaped (n, 3)",
        )
    };
    let array =
        polygon.py().import("numpy")?.call_method1("ascontiguousarray", (polygon, "float64")).map_err(|_| bad())?;
    let array: PyReadonlyArray2<f64> = array.extract().map_err(|_| bad())?;
    if array.shape()[1] != 3 {
        return Err(bad());
    }
    Ok(PolygonArg::Points(array.as_array().rows().into_iter().map(|r| [r[0], r[1], r[2]]).collect()))
}

/// `angle_range` as Python gives it: `"LO,HI"` or a pair of degrees.
fn angle_range_arg(range: &Bound<'_, PyAny>) -> PyResult<[f64; 2]> {
    if let Ok(text) = range.extract::<String>() {
        return parse_angle_range(&text).map_err(|e| to_py(e.into()));
    }
    range
        .extract::<[f64; 2]>()
        .map_err(|_| InputError::new_err("angle_range: give (LO, HI) in degrees, like (-45, 45)"))
}

/// `shard` as Python gives it: `"K/N"` or a pair `(K, N)`.
fn shard_arg(shard: &Bound<'_, PyAny>) -> PyResult<Shard> {
    let text = match shard.extract::<String>() {
        Ok(text) => text,
        Err(_) => {
            let (k, n): (usize, usize) =
                shard.extract().map_err(|_| InputError::new_err("shard: give \"K/N\" or (K, N), like \"2/8\""))?;
            format!("{k}/{n}")
        }
    };
    Shard::parse(&text).map_err(|m| InputError::new_err(format!("--shard: {m}")))
}

/// Find the best seed and angle of a ply of a scene file, into the folder `out`, as `drape
/// optimise` does.
#[pyfunction]
#[pyo3(signature = (
    scene, out, *, ply=None, vary=None, seed_radius=None, seed_polygon=None, seed_step=None,
    angle_range=None, angle_step=None, objective=None, spacing=None, refine=None,
    max_candidates=None, jobs=None, shard=None
))]
#[allow(clippy::too_many_arguments)]
fn optimise(
    py: Python<'_>,
    scene: PathBuf,
    out: PathBuf,
    ply: Option<String>,
    vary: Option<&Bound<'_, PyAny>>,
    seed_radius: Option<f64>,
    seed_polygon: Option<&Bound<'_, PyAny>>,
    seed_step: Option<f64>,
    angle_range: Option<&Bound<'_, PyAny>>,
    angle_step: Option<f64>,
    objective: Option<String>,
    spacing: Option<f64>,
    refine: Option<usize>,
    max_candidates: Option<usize>,
    jobs: Option<usize>,
    shard: Option<&Bound<'_, PyAny>>,
) -> PyResult<Option<Optimisation>> {
    let request = Request {
        ply,
        vary: vary.map(vary_arg).transpose()?.unwrap_or_else(|| DEFAULT_VARY.into()),
        seed_radius,
        seed_polygon: seed_polygon.map(polygon_arg).transpose()?,
        seed_step,
        angle_range: angle_range.map(angle_range_arg).transpose()?.unwrap_or(DEFAULT_ANGLE_RANGE),
        angle_step: angle_step.unwrap_or(DEFAULT_ANGLE_STEP),
        objective: objective.unwrap_or_else(|| DEFAULT_OBJECTIVE.into()),
        spacing,
        refine: refine.unwrap_or(DEFAULT_REFINE_STARTS),
        max_candidates: max_candidates.unwrap_or(DEFAULT_MAX_CANDIDATES),
    };
    let shard = shard.map(shard_arg).transpose()?.unwrap_or(Shard::ALL);
    let done = py
        .detach(|| -> Result<_, Failure> {
            let scene = Scene::load(&scene).map_err(input)?;
            let done = opt::optimise(&scene, &request, &out, shard, jobs_or_cores(jobs), |_| {}, |_, _| {})?;
            let Some((o, path)) = done.result else { return Ok(None) };
            let text = serde_json::to_string(&o).map_err(compute)?;
            let scene_file = out.join(&o.scene);
            // The landscape pictures, as the command line draws them.
            let pictures = drape::report::study::draw(&out, &Finished::Optimise(Box::new(o)))
                .map_err(|m| compute(anyhow::anyhow!(m)))?;
            let files = [vec![path, scene_file.clone()], pictures].concat();
            Ok(Some((text, files, scene_file, drape::study::shear_range_warning(&out))))
        })
        .map_err(to_py)?;
    let Some((text, files, scene_file, warning)) = done else { return Ok(None) };
    if let Some(w) = warning {
        warn(py, &w)?;
    }
    Ok(Some(Optimisation { result: json_to_py(py, &text)?.unbind(), files, scene: scene_file, out }))
}

/// Plans how woven composite plies lie on a part: the drape library from Python.
#[pymodule]
#[pyo3(name = "drape")]
fn drape_module(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add_class::<Net>()?;
    m.add_class::<Layup>()?;
    m.add_class::<Optimisation>()?;
    m.add_function(wrap_pyfunction!(kinematic, m)?)?;
    m.add_function(wrap_pyfunction!(refine, m)?)?;
    m.add_function(wrap_pyfunction!(run, m)?)?;
    m.add_function(wrap_pyfunction!(export, m)?)?;
    m.add_function(wrap_pyfunction!(optimise, m)?)?;
    m.add("DrapeError", py.get_type::<DrapeError>())?;
    m.add("InputError", py.get_type::<InputError>())?;
    m.add("ComputeError", py.get_type::<ComputeError>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
