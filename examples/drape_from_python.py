# %% [markdown]
# # Draping from Python
# Install the package from the checkout once: `pip install ./python`. Each `# %%` cell runs in
# Jupyter or VS Code as a notebook cell; `python examples/drape_from_python.py` runs them all
# (writing into `out/python-example` in the working folder).

# %%
from pathlib import Path

import numpy as np

import drape

repo = Path(__file__).resolve().parents[1]
tool = repo / "geometries" / "hemisphere" / "hemisphere-2k.obj"
card = repo / "materials" / "glass-plain-weave.toml"
out = Path("out") / "python-example"

# %% [markdown]
# ## One ply from a file: seed at the pole, warp along x, 4 mm spacing

# %%
net = drape.kinematic(tool, origin=(0, 0, 0.1), warp=(1, 0, 0), spacing=0.004, grid=(79, 79), surface="smooth")
print(net)
shear = net.shear_deg
print(f"max |shear| {np.nanmax(np.abs(shear)):.2f} deg, mean {np.nanmean(np.abs(shear)):.2f} deg")
print("why nodes were not placed:", dict(zip(*np.unique(net.status[net.status != "placed"], return_counts=True))))
net.save(out / "p0.drape.json")

# %% [markdown]
# ## The same ply on a tool made in numpy (a paraboloid dome), no file needed

# %%
xs = np.linspace(-0.1, 0.1, 41)
x, y = np.meshgrid(xs, xs, indexing="ij")
vertices = np.stack([x, y, -2.0 * (x**2 + y**2)], axis=-1).reshape(-1, 3)
k = np.arange(41 * 41).reshape(41, 41)
quads = np.stack([k[:-1, :-1], k[1:, :-1], k[1:, 1:], k[:-1, 1:]], axis=-1).reshape(-1, 4)
triangles = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
dome = drape.kinematic((vertices, triangles), origin=(0, 0, 0), warp=(1, 1, 0), spacing=0.005, grid=(41, 41))
print(dome, f"max |shear| {np.nanmax(np.abs(dome.shear_deg)):.2f} deg")

# %% [markdown]
# ## Let `auto` decide whether mechanics is needed, then refine mechanically ourselves

# %%
auto = drape.kinematic(tool, (0, 0, 0.1), (1, 0, 0), 0.008, (39, 39), method="auto", material=card)
print("auto:", auto.meta["method_choice"]["reason"])
pressed = drape.refine(net, tool, card, friction=0.25, holds=[net.origin_node])
moved = np.linalg.norm(pressed.positions - net.positions, axis=-1)
print(f"pressed refinement moved the nodes by up to {np.nanmax(moved) * 1e3:.2f} mm")

# %% [markdown]
# ## A whole layup from a scene file, and its fibres on a flow mesh

# %%
layup = drape.run(repo / "geometries" / "plate" / "scene.toml", out / "plate", replace=True)
for row in layup.plies:
    print(row["name"], row["method"], f"max |shear| {row['max_abs_shear_deg']:.2f} deg")
mapped = drape.export(net, tool, "vtu", out / "flow.vtu", material=card, permeability=True)
print(f"flow mesh: {mapped['covered']} of {mapped['elements']} elements covered -> {mapped['files']}")

# %% [markdown]
# ## The best seed and angle of the +45 ply: a global search of candidate drapes, refined

# %%
best = drape.optimise(repo / "geometries" / "hemisphere" / "scene.toml", out / "optimise", ply="p45",
                      seed_radius=0.02, angle_range=(-30, 30), angle_step=15, refine=2)
print(f"{best.result['objective_text']}: {best.objective:.3f} at seed {np.round(best.best['origin'], 4)} m, "
      f"angle {best.best['angle_deg']:.2f} deg ({len(best.landscape)} candidates) -> {best.scene}")
