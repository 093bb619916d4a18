"""Plans how woven composite plies lie on a part: the drape library from Python.

Every function calls the same library code as the ``drape`` command line (with the GIL released
while it works) and refuses bad input with the command line's message. Lengths are metres unless
``units="mm"`` says the tool and the lengths given are in millimetres; nets are always in metres.
"""

import os
from pathlib import Path
from typing import Any, Literal, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

__version__: str

PathLike = Union[str, "os.PathLike[str]"]
#: A tool: a file (OBJ, STL, or a shell mesh: .inp, .bdf, .msh) or ``(vertices, triangles)``,
#: array-likes shaped (n, 3) (float) and (m, 3) (0-based vertex indices, counter-clockwise seen
#: from the side the plies lie on).
Tool = Union[PathLike, Tuple[npt.ArrayLike, npt.ArrayLike]]
Vec3 = Tuple[float, float, float]

class DrapeError(Exception):
    """A drape command failed; the message says why."""

class InputError(DrapeError):
    """The input is wrong (the command line's exit code 2); the message says how to fix it."""

class ComputeError(DrapeError):
    """The computation failed (the command line's exit code 1), e.g. a solver that stopped
    short. ``net`` (kinematic, refine) or ``layup`` (run) holds what was computed."""

    net: "Net"
    layup: "Layup"

class Net:
    """A draped net: the warp/weft grid of one ply, node (i, j) with i along the warp.

    Each array property returns a new copy.
    """

    @staticmethod
    def load(path: PathLike) -> "Net":
        """Read a ``<ply>.drape.json`` file (the JSON contract of ``drape kinematic``)."""
    def save(self, path: PathLike) -> Path:
        """Write the net as JSON (the same contract), atomically, creating its folder; returns
        the path."""
    @property
    def name(self) -> str:
        """The ply's name."""
    @property
    def method(self) -> Literal["kinematic", "mechanical"]:
        """How the net was computed."""
    @property
    def spacing(self) -> float:
        """Fibre segment length d, metres."""
    @property
    def grid(self) -> Tuple[int, int]:
        """Grid size (nu, nv)."""
    @property
    def origin_node(self) -> Tuple[int, int]:
        """Grid indices of the seed node."""
    @property
    def positions(self) -> npt.NDArray[np.float64]:
        """Node positions (nu, nv, 3), metres; NaN where a node was not placed."""
    @property
    def shear_deg(self) -> npt.NDArray[np.float64]:
        """Cell shear (nu-1, nv-1), degrees; NaN where a cell lacks a placed corner."""
    @property
    def warp(self) -> npt.NDArray[np.float64]:
        """Unit warp direction per cell (nu-1, nv-1, 3); NaN where a cell lacks a corner."""
    @property
    def weft(self) -> npt.NDArray[np.float64]:
        """Unit weft direction per cell (nu-1, nv-1, 3); NaN where a cell lacks a corner."""
    @property
    def status(self) -> npt.NDArray[np.str_]:
        """Each node's status (nu, nv): ``placed``, or why not (``off_tool``, ``no_root``,
        ``shear_limit``, ``fold``, ``sheet_jump``, ``parent_missing``, ``outside_outline``,
        ``detached``)."""
    @property
    def meta(self) -> dict[str, Any]:
        """Where the net came from (the JSON file's ``"meta"``): tool, material, surface,
        solver record, auto's choice..."""

class Layup:
    """The layup a ``drape.run`` wrote: its table (``layup.json``) and its folder."""

    @property
    def plies(self) -> list[dict[str, Any]]:
        """One dict per ply in stacking order: the layup table's rows."""
    @property
    def table(self) -> dict[str, Any]:
        """The whole ``layup.json``: rows, nesting, files written, flow export."""
    @property
    def out(self) -> Path:
        """The run folder."""
    def net(self, name: str) -> Net:
        """The net of ply ``name`` from the run folder (written with the json format)."""
    def __len__(self) -> int: ...

class Optimisation:
    """An optimisation's result (``optimise.json`` in its folder) and the files it wrote."""

    @property
    def best(self) -> dict[str, Any]:
        """The best placement at the ply's spacing: ``origin`` (the seed on the tool, m),
        ``angle_deg``, ``objective``, ``stats`` (``max_abs_shear_deg``, ``mean_abs_shear_deg``,
        ``area_over_locking_m2``, ``coverage``, ``cells``), ``seed_ab`` (the seed in the seed
        plane, m), ``spacing``, ``outcome`` and ``start`` (the global search's candidate it was
        refined from, its objective at both spacings, the drapes the refinement ran)."""
    @property
    def objective(self) -> float:
        """The best placement's objective (smaller is better)."""
    @property
    def runners_up(self) -> list[dict[str, Any]]:
        """The other refined placements, best first, as dicts like ``best``."""
    @property
    def landscape(self) -> list[dict[str, Any]]:
        """Every candidate of the global search in plan order: ``index``, ``seed_ab``, ``origin``,
        ``angle_deg``, ``objective`` (None where it gave no complete cell), ``outcome``."""
    @property
    def result(self) -> dict[str, Any]:
        """The whole ``optimise.json``."""
    @property
    def files(self) -> list[Path]:
        """The files written: ``optimise.json``, ``optimal.toml``, ``optimise.png``,
        ``optimise.svg``."""
    @property
    def scene(self) -> Path:
        """The scene with the optimal ply (``optimal.toml``), ready for ``drape.run``."""
    @property
    def out(self) -> Path:
        """The optimisation's folder."""

def kinematic(
    tool: Tool,
    origin: Vec3,
    warp: Vec3,
    spacing: float,
    grid: Optional[Tuple[int, int]] = None,
    *,
    outline: Optional[PathLike] = None,
    origin_node: Optional[Tuple[int, int]] = None,
    generators: str = "geodesic",
    surface: Literal["facets", "smooth"] = "facets",
    max_shear_deg: float = 75.0,
    pre_shear_deg: float = 0.0,
    method: Literal["kinematic", "auto"] = "kinematic",
    material: Optional[PathLike] = None,
    tolerance_deg: Optional[float] = None,
    locking_angle_deg: Optional[float] = None,
    units: Literal["m", "mm"] = "m",
    name: str = "ply",
) -> Net:
    """Drape one ply with the kinematic (fishnet) method, as ``drape kinematic`` does.

    ``origin`` is projected onto the tool, ``warp`` onto its tangent plane there; ``grid`` is
    (nu, nv) nodes, or give ``outline`` (a closed polyline file on the tool) instead.
    ``generators``: ``geodesic``, ``min-shear`` or ``steer:FILE``. ``method="auto"`` with a
    ``material`` card runs the pressed mechanical model only where the kinematic net is not within
    ``tolerance_deg`` (default 1) of it; its choice is in ``meta["method_choice"]``. A shear past
    the card's calibrated range is a ``UserWarning``.

    Raises InputError on bad input; ComputeError (with ``.net``) when auto's solver stopped
    without equilibrium.
    """

def refine(
    net: Net,
    tool: Tool,
    material: PathLike,
    mode: Literal["pressed", "free"] = "pressed",
    *,
    units: Optional[Literal["m", "mm"]] = None,
    facets: bool = False,
    gravity: Optional[Vec3] = None,
    load_steps: int = 1,
    stick: bool = False,
    friction: Optional[float] = None,
    holds: Optional[Sequence[Tuple[int, int]]] = None,
    escape_saddles: bool = False,
    max_iterations: int = 100,
    die: Optional[PathLike] = None,
    stack_side: Optional[Literal["normal", "opposite"]] = None,
) -> Net:
    """Refine a net mechanically (tension, shear, bending, gravity, tool contact, friction), as
    ``drape refine`` does. ``units``: the tool's (default: the unit the net records). ``gravity``
    defaults to (0, 0, -9.80665) m/s^2; ``friction`` to the card's ``[contact] friction``;
    ``holds`` are grid nodes (i, j) held in place. A formed net (``meta["forming"]``) is held by
    the tools that formed it where its stroke ended: ``tool`` is the punch, ``die`` its die (in
    the tool's units; default: the file the net records). ``stack_side``: the side of the tool
    the ply lies on (default: the side the net records, else the one its normals point to).

    Raises InputError on bad input; ComputeError (with ``.net``, the last state) when the ply
    slides or the solver stops without equilibrium.
    """

def run(scene: PathLike, out: PathLike, *, formats: str = "json,vtu,csv", replace: bool = False) -> Layup:
    """Drape every ply of a scene file into the folder ``out``, as ``drape run`` does (nets, flat
    patterns, ``layup.json``, the flow export), and return the layup table.

    Raises InputError on bad input; ComputeError (with ``.layup``) when a ply's solver stopped
    short, after everything was written.
    """

def export(
    net: Net,
    mesh: PathLike,
    format: Literal["vtu", "nastran", "abaqus", "calculix", "optistruct", "rtmsim", "csv"],
    out: PathLike,
    *,
    mesh_units: Literal["m", "mm"] = "m",
    material: Optional[PathLike] = None,
    thickness: Optional[float] = None,
    cavity: Literal["fixed", "free"] = "fixed",
    permeability: bool = False,
    fibre_radius: Optional[float] = None,
    material_name: str = "PLY_MATERIAL",
    vtu: Literal["auto", "ascii", "binary"] = "auto",
) -> dict[str, Any]:
    """Map a net onto a resin-flow shell mesh and write fibre directions, shear, thickness, Vf
    (and permeability) in ``format`` to the file ``out``, as ``drape export`` does.

    Returns a dict: ``files`` (the Paths written), ``nodes`` and ``elements`` of the mesh,
    ``covered`` (elements the ply covers), ``max_abs_shear_deg`` and ``mean_abs_shear_deg`` over
    them, ``vf_capped`` (elements at the fibre packing limit), ``collapsed`` (elements on cells
    sheared past 75 deg, written at that shear), ``notes`` (on the mesh and map).
    """


def optimise(
    scene: PathLike,
    out: PathLike,
    *,
    ply: Optional[str] = None,
    vary: Union[str, Sequence[str]] = "seed,angle",
    seed_radius: Optional[float] = None,
    seed_polygon: Optional[Union[PathLike, npt.ArrayLike]] = None,
    seed_step: Optional[float] = None,
    angle_range: Union[str, Tuple[float, float]] = (-45.0, 45.0),
    angle_step: float = 5.0,
    objective: str = "max-shear",
    spacing: Optional[float] = None,
    refine: int = 3,
    max_candidates: int = 10000,
    jobs: Optional[int] = None,
    shard: Optional[Union[str, Tuple[int, int]]] = None,
) -> Optional[Optimisation]:
    """Find the seed and angle of a ply of a scene file that minimise ``objective``, into the
    folder ``out``, as ``drape optimise`` does (the keywords are its options; lengths in the
    scene's units).

    A global search drapes every candidate (the seeds of a lattice of step ``seed_step`` over the
    seed region, ``seed_radius`` around the ply's origin or inside ``seed_polygon`` (a points
    file, ``"x,y,z;x,y,z;..."`` or corners shaped (n, 3)), at every angle of ``angle_range`` by
    ``angle_step``) kinematically at ``spacing`` (default: twice the ply's), ``jobs`` at a time
    (default: every core); the best ``refine`` are refined by a pattern search at the ply's own
    spacing. ``vary`` names what moves: ``seed``, ``angle`` or both. ``objective``:
    ``max-shear``, ``locked-area``, ``mean-shear``, ``coverage`` (maximised) or a weighted sum
    like ``"max-shear:1,coverage:0.5"``.

    Writes ``optimise.json``, ``optimal.toml`` (the scene with the optimal ply), the landscape
    pictures and the study's ``study.json`` and ``cases/`` (run again into ``out`` to resume).
    With ``shard="K/N"`` only that shard of the global search runs: the result is None until a
    folder holds every candidate (``drape study merge`` joins shard folders and finishes).

    Raises InputError on bad input, with the command line's message.
    """
