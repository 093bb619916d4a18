"""The Python package against the command line: the same numbers from the same input, the same
refusals, nets from numpy arrays equal to nets from files, and the JSON contract round trip."""
import json
import sys
import threading
import time
import warnings

import numpy as np
import pytest

import drape
from conftest import GLASS, HEMISPHERE, REPO


def cli_arrays(path):
    """Positions, cell shears and statuses of a net file read with Python's json alone (not
    through drape), NaN where the file has null."""
    f = json.loads(path.read_text())
    nu, nv = f["grid"]
    nodes = np.array([p if p is not None else [np.nan] * 3 for p in f["nodes"]], dtype=float)
    shear = np.array([np.nan if s is None else s for s in f["cell_shear_deg"]], dtype=float)
    legend = f["status"]["legend"]
    status = np.array([legend[str(c)] for c in f["status"]["node_codes"]])
    return nodes.reshape(nu, nv, 3), shear.reshape(nu - 1, nv - 1), status.reshape(nu, nv), f


def without_times(value):
    """A meta dict without its wall-clock times (keys ending in `_ms`), which differ from run to
    run."""
    if isinstance(value, dict):
        return {k: without_times(v) for k, v in value.items() if not k.endswith("_ms")}
    if isinstance(value, list):
        return [without_times(v) for v in value]
    return value


def assert_same_net(net, path):
    """The net equals the command line's file bit for bit (positions, shears, statuses)."""
    nodes, shear, status, f = cli_arrays(path)
    assert net.grid == tuple(f["grid"]) and net.origin_node == tuple(f["origin_node"])
    assert net.spacing == f["spacing"] and net.method == f["method"]
    assert np.array_equal(net.positions, nodes, equal_nan=True)
    assert np.array_equal(net.shear_deg, shear, equal_nan=True)
    assert np.array_equal(net.status, status)


# Option sets of `drape kinematic`, as (command-line arguments, the same as Python keywords).
KINEMATIC_CASES = {
    "geodesic": ([], {}),
    "min-shear-smooth-preshear": (
        ["--generators", "min-shear", "--surface", "smooth", "--pre-shear", "5", "--origin-node", "4,6",
         "--max-shear", "60"],
        {"generators": "min-shear", "surface": "smooth", "pre_shear_deg": 5.0, "origin_node": (4, 6),
         "max_shear_deg": 60.0},
    ),
    "auto": (
        ["--method", "auto", "--material", GLASS, "--tolerance", "0.5"],
        {"method": "auto", "material": GLASS, "tolerance_deg": 0.5},
    ),
}


@pytest.mark.parametrize("case", sorted(KINEMATIC_CASES))
def test_kinematic_matches_cli(cli, tmp_path, case):
    args, options = KINEMATIC_CASES[case]
    cli("kinematic", "--tool", HEMISPHERE, "--origin", "0.01,0.02,0.1", "--warp", "1,0.3,0", "--spacing", "0.008",
        "--grid", "15,17", "--name", "p", *args, "--out", tmp_path)
    net = drape.kinematic(HEMISPHERE, (0.01, 0.02, 0.1), (1, 0.3, 0), 0.008, (15, 17), name="p", **options)
    assert_same_net(net, tmp_path / "p.drape.json")
    cli_meta = json.loads((tmp_path / "p.drape.json").read_text())["meta"]
    assert without_times(net.meta) == without_times(cli_meta)
    if case == "auto":
        assert net.meta["method_choice"]["reason"]


def test_warp_weft_are_the_cells_fibres():
    net = drape.kinematic(HEMISPHERE, (0, 0, 0.1), (1, 0, 0), 0.01, (9, 9))
    p = net.positions
    warp = (p[1:, :-1] - p[:-1, :-1]) + (p[1:, 1:] - p[:-1, 1:])
    warp /= np.linalg.norm(warp, axis=2, keepdims=True)
    assert np.allclose(net.warp, warp, atol=1e-12)
    assert np.allclose(np.linalg.norm(net.weft, axis=2), 1.0)
    # The seed lies on the pole and its cells barely shear there.
    assert np.allclose(p[4, 4], [0, 0, 0.1], atol=1e-9)
    assert np.nanmax(np.abs(net.shear_deg)) < 15


def test_status_and_nan_where_not_placed(cli, tmp_path):
    # A grid wider than the hemisphere: nodes run off the rim.
    net = drape.kinematic(HEMISPHERE, (0, 0, 0.1), (1, 0, 0), 0.02, (21, 21))
    status, p = net.status, net.positions
    placed = status == "placed"
    assert 0 < placed.sum() < placed.size
    assert set(np.unique(status[~placed])) <= {"off_tool", "no_root", "parent_missing", "fold", "shear_limit"}
    assert np.isnan(p[~placed]).all() and np.isfinite(p[placed]).all()
    assert np.isnan(net.shear_deg).any()


def paraboloid(n=24, size=0.2, curvature=2.0):
    """A saddle-free dome z = -c (x^2 + y^2) as numpy arrays: (vertices, triangles)."""
    xs = np.linspace(-size / 2, size / 2, n + 1)
    x, y = np.meshgrid(xs, xs, indexing="ij")
    vertices = np.stack([x, y, -curvature * (x**2 + y**2)], axis=-1).reshape(-1, 3)
    k = np.arange(n + 1) * (n + 1)
    triangles = []
    for i in range(n):
        for j in range(n):
            a, b, c, d = k[i] + j, k[i + 1] + j, k[i] + j + 1, k[i + 1] + j + 1
            triangles += [(a, b, d), (a, d, c)]
    return vertices, np.array(triangles)


def write_obj(path, vertices, triangles):
    """An OBJ with every coordinate written exactly (repr of the double)."""
    lines = [f"v {x!r} {y!r} {z!r}" for x, y, z in vertices.tolist()]
    lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in triangles.tolist()]
    path.write_text("\n".join(lines) + "\n")


@pytest.mark.parametrize("surface", ["facets", "smooth"])
def test_ply_from_arrays_equals_ply_from_obj(cli, tmp_path, surface):
    vertices, triangles = paraboloid()
    obj = tmp_path / "dome.obj"
    write_obj(obj, vertices, triangles)
    settings = dict(origin=(0.01, 0, 0), warp=(1, 1, 0), spacing=0.01, grid=(17, 17), surface=surface)
    from_arrays = drape.kinematic((vertices, triangles.astype(np.int32)), **settings)
    from_obj = drape.kinematic(obj, **settings)
    assert np.array_equal(from_arrays.positions, from_obj.positions, equal_nan=True)
    assert np.array_equal(from_arrays.shear_deg, from_obj.shear_deg, equal_nan=True)
    assert np.array_equal(from_arrays.status, from_obj.status)
    assert (from_arrays.status == "placed").sum() > 200
    # And both equal the command line on the OBJ.
    cli("kinematic", "--tool", obj, "--origin", "0.01,0,0", "--warp", "1,1,0", "--spacing", "0.01", "--grid", "17,17",
        "--surface", surface, "--out", tmp_path)
    assert_same_net(from_arrays, tmp_path / "ply.drape.json")


def test_arrays_in_millimetres():
    vertices, triangles = paraboloid()
    in_m = drape.kinematic((vertices, triangles), (0, 0, 0), (1, 0, 0), 0.01, (9, 9))
    in_mm = drape.kinematic((vertices * 1e3, triangles), (0, 0, 0), (1, 0, 0), 10, (9, 9), units="mm")
    assert np.allclose(in_mm.positions, in_m.positions, rtol=0, atol=1e-12)


# Bad input: the command-line arguments and the same as Python keywords.
BAD_INPUT = {
    "units": (["--units", "cm"], {"units": "cm"}),
    "generators": (["--generators", "spiral"], {"generators": "spiral"}),
    "surface": (["--surface", "bumpy"], {"surface": "bumpy"}),
    "method": (["--method", "best"], {"method": "best"}),
    "auto-without-card": (["--method", "auto"], {"method": "auto"}),
    "tolerance-without-auto": (["--tolerance", "1"], {"tolerance_deg": 1.0}),
    "missing-card": (["--material", "no-such-card.toml"], {"material": "no-such-card.toml"}),
    "seed-off-tool": (["--origin", "0,0,0.5"], {"origin": (0, 0, 0.5)}),
    "spacing": (["--spacing", "-1"], {"spacing": -1.0}),
    "tool-missing": (["--tool", "no-such-tool.obj"], {"tool": "no-such-tool.obj"}),
}


@pytest.mark.parametrize("case", sorted(BAD_INPUT))
def test_errors_carry_the_cli_message(cli, tmp_path, case):
    args, options = BAD_INPUT[case]
    base = {"--tool": HEMISPHERE, "--origin": "0,0,0.1", "--warp": "1,0,0", "--spacing": "0.01", "--grid": "5,5"}
    flags = dict(zip(args[::2], args[1::2]))
    command = [x for k, v in {**base, **flags}.items() for x in (k, v)]
    done = cli("kinematic", *command, "--out", tmp_path, check=False)
    assert done.returncode == 2, done.stderr
    cli_message = done.stderr.strip().removeprefix("error: ")
    call = {"tool": HEMISPHERE, "origin": (0, 0, 0.1), "warp": (1, 0, 0), "spacing": 0.01, "grid": (5, 5), **options}
    with pytest.raises(drape.InputError) as raised:
        drape.kinematic(**call)
    assert str(raised.value) == cli_message
    assert isinstance(raised.value, drape.DrapeError)


def test_bad_arrays_are_refused():
    vertices, triangles = paraboloid(4)
    with pytest.raises(drape.InputError, match="shaped"):
        drape.kinematic((vertices[:, :2], triangles), (0, 0, 0), (1, 0, 0), 0.01, (5, 5))
    with pytest.raises(drape.InputError, match="index"):
        drape.kinematic((vertices, triangles - 1), (0, 0, 0), (1, 0, 0), 0.01, (5, 5))
    with pytest.raises(drape.InputError, match="pair"):
        drape.kinematic(42, (0, 0, 0), (1, 0, 0), 0.01, (5, 5))


def test_save_load_round_trip(tmp_path):
    net = drape.kinematic(HEMISPHERE, (0, 0, 0.1), (1, 1, 0), 0.01, (25, 25), surface="smooth", name="q")
    first = tmp_path / "q.drape.json"
    net.save(first)
    back = drape.Net.load(first)
    assert (back.name, back.grid, back.origin_node, back.spacing) == ("q", (25, 25), (12, 12), 0.01)
    for field in ("positions", "shear_deg", "warp", "weft"):
        assert np.array_equal(getattr(back, field), getattr(net, field), equal_nan=True), field
    assert np.array_equal(back.status, net.status)
    assert back.meta == net.meta
    again = tmp_path / "again" / "q.drape.json"
    again.parent.mkdir()
    back.save(again)
    assert again.read_bytes() == first.read_bytes()


def test_load_refuses_a_broken_file(cli, tmp_path):
    broken = tmp_path / "broken.drape.json"
    broken.write_text('{"ply": "x", "grid": [2, 2]')
    done = cli("refine", "--net", broken, "--tool", HEMISPHERE, "--material", GLASS, "--mode", "pressed", "--out",
               tmp_path, check=False)
    with pytest.raises(drape.InputError) as raised:
        drape.Net.load(broken)
    assert done.returncode == 2 and str(raised.value) == done.stderr.strip().removeprefix("error: ")


def test_refine_matches_cli(cli, tmp_path):
    cli("kinematic", "--tool", HEMISPHERE, "--origin", "0,0,0.1", "--warp", "1,0,0", "--spacing", "0.01", "--grid",
        "13,13", "--name", "k", "--out", tmp_path)
    cli("refine", "--net", tmp_path / "k.drape.json", "--tool", HEMISPHERE, "--material", GLASS, "--mode", "pressed",
        "--friction", "0.3", "--hold", "6,6", "--load-steps", "2", "--out", tmp_path / "refined")
    kinematic = drape.Net.load(tmp_path / "k.drape.json")
    refined = drape.refine(kinematic, HEMISPHERE, GLASS, friction=0.3, holds=[(6, 6)], load_steps=2)
    assert refined.method == "mechanical"
    assert_same_net(refined, tmp_path / "refined" / "k.drape.json")
    cli_meta = json.loads((tmp_path / "refined" / "k.drape.json").read_text())["meta"]
    assert refined.meta["solver"]["converged"] and without_times(refined.meta) == without_times(cli_meta)


def test_refine_refuses_like_the_cli(cli, tmp_path):
    cli("kinematic", "--tool", HEMISPHERE, "--origin", "0,0,0.1", "--warp", "1,0,0", "--spacing", "0.01", "--grid",
        "5,5", "--out", tmp_path)
    net = drape.Net.load(tmp_path / "ply.drape.json")
    for args, options in [(["--friction=-1"], {"friction": -1.0}), (["--load-steps", "0"], {"load_steps": 0}),
                          (["--stack-side", "under"], {"stack_side": "under"})]:
        done = cli("refine", "--net", tmp_path / "ply.drape.json", "--tool", HEMISPHERE, "--material", GLASS,
                   "--mode", "pressed", *args, "--out", tmp_path / "r", check=False)
        with pytest.raises(drape.InputError) as raised:
            drape.refine(net, HEMISPHERE, GLASS, **options)
        assert done.returncode == 2 and str(raised.value) == done.stderr.strip().removeprefix("error: ")
    with pytest.raises(drape.InputError, match="unknown mode"):
        drape.refine(net, HEMISPHERE, GLASS, mode="hanging")


SCENE = """
tool = "{tool}"
[materials]
glass = "{card}"
[[ply]]
name = "a"
origin = [0.0, 0.0, 0.1]
angle_deg = 0.0
material = "glass"
spacing = 0.01
grid = [21, 21]
[[ply]]
name = "b"
origin = [0.0, 0.0, 0.1]
angle_deg = 45.0
material = "glass"
spacing = 0.01
grid = [21, 21]
"""


def test_run_returns_the_layup_table(cli, tmp_path):
    scene = tmp_path / "scene.toml"
    scene.write_text(SCENE.format(tool=HEMISPHERE, card=GLASS))
    cli("run", scene, "--out", tmp_path / "cli")
    layup = drape.run(scene, tmp_path / "py")
    assert [p["name"] for p in layup.plies] == ["a", "b"] and len(layup) == 2
    cli_table = json.loads((tmp_path / "cli" / "layup.json").read_text())
    assert layup.plies == cli_table["plies"]
    assert layup.table["files"] == cli_table["files"]
    assert_same_net(layup.net("b"), tmp_path / "cli" / "b.drape.json")


def test_run_refuses_a_bad_scene(cli, tmp_path):
    scene = tmp_path / "scene.toml"
    scene.write_text(SCENE.format(tool=HEMISPHERE, card=GLASS).replace("spacing = 0.01\ngrid = [21, 21]\n[[ply]]",
                                                                        "spacing = 0.01\n[[ply]]"))
    done = cli("run", scene, "--out", tmp_path / "cli", check=False)
    with pytest.raises(drape.InputError) as raised:
        drape.run(scene, tmp_path / "py")
    assert done.returncode == 2 and str(raised.value) == done.stderr.strip().removeprefix("error: ")


def test_export_matches_cli(cli, tmp_path):
    cli("kinematic", "--tool", HEMISPHERE, "--origin", "0,0,0.1", "--warp", "1,0,0", "--spacing", "0.005", "--grid",
        "61,61", "--material", GLASS, "--out", tmp_path)
    net = drape.Net.load(tmp_path / "ply.drape.json")
    cli("export", "--net", tmp_path / "ply.drape.json", "--mesh", HEMISPHERE, "--format", "csv", "--material", GLASS,
        "--permeability", "--out", tmp_path / "cli.csv")
    done = drape.export(net, HEMISPHERE, "csv", tmp_path / "py.csv", material=GLASS, permeability=True)
    assert (tmp_path / "py.csv").read_bytes() == (tmp_path / "cli.csv").read_bytes()
    assert done["files"] == [tmp_path / "py.csv"]
    assert done["elements"] == 2116 and 0 < done["covered"] <= done["elements"]
    with pytest.raises(drape.InputError, match="--format"):
        drape.export(net, HEMISPHERE, "stl", tmp_path / "x.stl")


# An optimisation small enough for a test: 13 seeds x 3 angles of the hemisphere scene's p45 at
# 8 mm, the best 2 refined at its 4 mm; as command-line arguments and the same as Python keywords.
OPTIMISE_ARGS = ["--ply", "p45", "--seed-radius", "0.02", "--seed-step", "0.01", "--angle-range=-30,30",
                 "--angle-step", "30", "--objective", "max-shear:1,coverage:2", "--refine", "2", "--jobs", "2"]
OPTIMISE_KEYWORDS = dict(ply="p45", seed_radius=0.02, seed_step=0.01, angle_range=(-30, 30), angle_step=30,
                         objective="max-shear:1,coverage:2", refine=2, jobs=2)
OPTIMISE_SCENE = REPO / "geometries" / "hemisphere" / "scene.toml"


def without_run_times(result):
    """optimise.json without the wall-clock times, which differ from run to run."""
    return {k: v for k, v in result.items() if k not in ("search_drape_s", "refine_s")}


def test_optimise_matches_cli(cli, tmp_path):
    cli("optimise", OPTIMISE_SCENE, "--out", tmp_path / "cli", *OPTIMISE_ARGS)
    o = drape.optimise(OPTIMISE_SCENE, tmp_path / "py", **OPTIMISE_KEYWORDS)
    cli_result = json.loads((tmp_path / "cli" / "optimise.json").read_text())
    # The same best placement and objective, runners-up and landscape, to the last bit.
    assert o.best == cli_result["best"] and o.objective == cli_result["best"]["objective"]
    assert o.runners_up == cli_result["runners_up"] and len(o.landscape) == 39
    assert without_run_times(o.result) == without_run_times(cli_result)
    names = ["optimise.json", "optimal.toml", "optimise.png", "optimise.svg"]
    assert o.files == [tmp_path / "py" / n for n in names] and all(f.is_file() for f in o.files)
    assert o.scene == tmp_path / "py" / "optimal.toml"
    # The scene with the optimal ply is the command line's, but for the folder it names.
    py_scene = o.scene.read_text().replace(str(tmp_path / "py"), "OUT")
    assert py_scene == (tmp_path / "cli" / "optimal.toml").read_text().replace(str(tmp_path / "cli"), "OUT")
    # The same options as a polygon of corners and text where the command line takes text.
    again = drape.optimise(OPTIMISE_SCENE, tmp_path / "py", **{**OPTIMISE_KEYWORDS, "angle_range": "-30,30",
                                                               "vary": ["seed", "angle"]})
    assert again.best == o.best


def test_optimise_in_shards(tmp_path):
    keywords = {**OPTIMISE_KEYWORDS, "vary": "seed", "refine": 1}
    assert drape.optimise(OPTIMISE_SCENE, tmp_path, shard="1/2", **keywords) is None
    assert not (tmp_path / "optimise.json").exists()
    done = drape.optimise(OPTIMISE_SCENE, tmp_path, shard=(2, 2), **keywords)
    whole = drape.optimise(OPTIMISE_SCENE, tmp_path / "whole", **keywords)
    assert done.best == whole.best and done.best["angle_deg"] is None


# Bad optimisations: the command-line arguments and the same as Python keywords.
BAD_OPTIMISATIONS = {
    "objective": (["--seed-radius", "0.02", "--objective", "wrinkles"], {"seed_radius": 0.02, "objective": "wrinkles"}),
    "no-region": ([], {}),
    "vary": (["--seed-radius", "0.02", "--vary", "tilt"], {"seed_radius": 0.02, "vary": "tilt"}),
    "ply": (["--seed-radius", "0.02", "--ply", "nope"], {"seed_radius": 0.02, "ply": "nope"}),
    "angle-range": (["--seed-radius", "0.02", "--angle-range", "30,-30"], {"seed_radius": 0.02, "angle_range": (30, -30)}),
    "too-many": (["--seed-radius", "0.02", "--seed-step", "0.001", "--angle-step", "1"],
                 {"seed_radius": 0.02, "seed_step": 0.001, "angle_step": 1}),
    "polygon": (["--seed-polygon", "0,0,0.1;0.01,0,0.1", "--vary", "seed"],
                {"seed_polygon": [(0, 0, 0.1), (0.01, 0, 0.1)], "vary": "seed"}),
    "shard": (["--seed-radius", "0.02", "--shard", "3/2"], {"seed_radius": 0.02, "shard": "3/2"}),
}


@pytest.mark.parametrize("case", sorted(BAD_OPTIMISATIONS))
def test_optimise_refuses_like_the_cli(cli, tmp_path, case):
    args, keywords = BAD_OPTIMISATIONS[case]
    done = cli("optimise", OPTIMISE_SCENE, "--out", tmp_path / "cli", *args, check=False)
    assert done.returncode == 2, done.stderr
    with pytest.raises(drape.InputError) as raised:
        drape.optimise(OPTIMISE_SCENE, tmp_path / "py", **keywords)
    assert str(raised.value) == done.stderr.strip().removeprefix("error: ")
    assert not (tmp_path / "py").exists()


# Long calls, each given a folder to write into.
LONG_CALLS = {
    "kinematic": lambda out: drape.kinematic(HEMISPHERE, (0, 0, 0.1), (1, 0, 0), 0.0008, (301, 301), surface="smooth"),
    "optimise": lambda out: drape.optimise(OPTIMISE_SCENE, out, **OPTIMISE_KEYWORDS),
}


@pytest.mark.parametrize("call", sorted(LONG_CALLS))
def test_the_gil_is_released_while_draping(tmp_path, call):
    # With a switch interval far longer than the test, a thread gives the GIL up only when it
    # waits (the main thread's sleep(0)) or when the extension releases it. The main thread
    # counts while another drapes: released, the count goes on during the drape; held, it
    # stands still from the call to its return.
    count = [0]
    seen = {}
    done = threading.Event()

    def work():
        try:
            seen["before"] = count[0]
            LONG_CALLS[call](tmp_path)
            seen["after"] = count[0]
        finally:
            done.set()

    interval = sys.getswitchinterval()
    sys.setswitchinterval(100.0)
    try:
        thread = threading.Thread(target=work)
        thread.start()
        while not done.is_set():
            count[0] += 1
            time.sleep(0)
        thread.join()
    finally:
        sys.setswitchinterval(interval)
    assert seen["after"] - seen["before"] >= 10, seen


def test_example_script_runs(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    example = REPO / "examples" / "drape_from_python.py"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        namespace = {"__name__": "__main__", "__file__": str(example)}
        exec(compile(example.read_text(), str(example), "exec"), namespace)
