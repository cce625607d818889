"""Generate notebooks/parameter_sweep.ipynb (no stored outputs)."""

import sys

import nbformat
from nbformat.v4 import new_code_cell, new_markdown_cell, new_notebook

cells = [
    new_markdown_cell("""# Parameter sweep: loads × slips × snow parameter sets

`snowjax.sweep` solves the rigid-wheel equilibrium of the thesis (Sankapalli 2004, eq. 4.14)
on a grid of wheel loads × slips × parameter sets, in fixed-size chunks written to disk.
It needs the memory of one chunk whatever the number of points, shows a progress bar,
spreads each chunk over all local JAX devices, and resumes an interrupted sweep when it is
run again with the same arguments.

Here: the thesis tyre (D = 0.736 m, b = 0.235 m) on the thesis's fresh shallow snow
(Table 4.1 ratios) with three values of Wong's pressure parameter p_w (the cohesion follows
the thesis ratio c = 0.2165 p_w). SI units: N, Pa, m, rad."""),
    new_code_cell("""import os

import jax

jax.config.update("jax_enable_x64", True)
import matplotlib.pyplot as plt
import numpy as np

import snowjax as sj

SMALL = os.environ.get("SNOWJAX_NOTEBOOK_SMALL") == "1"  # the test suite runs a tiny version
n_loads, n_slips = (4, 6) if SMALL else (25, 40)
p_ws = np.array([40e3, 85.55e3]) if SMALL else np.array([40e3, 60e3, 85.55e3])  # [Pa]
chunk_size = 8 if SMALL else 1024"""),
    new_markdown_cell("""A *parameter set* is one element of a leading batch of the parameter leaves: giving
`p_w` (and with it the cohesion) as arrays of length P makes P snow parameter sets; the
leaves that stay scalars are shared. The grid is parameter set × load × slip, slip fastest."""),
    new_code_cell("""wheel = sj.RigidWheel.thesis_tire()
snow = sj.WongSnow.thesis_fresh_snow(p_w=p_ws)  # p_w and cohesion vary, z_w, tan_phi, K shared
loads = np.linspace(2000.0, 8000.0, n_loads)  # [N]
slips = np.linspace(0.0, 0.9, n_slips)  # driving slip [-]

# progress=True (the default) shows a rich progress bar on a terminal; in Jupyter it
# needs ipywidgets.
result = sj.sweep(wheel, snow, loads, slips, out="sweep-output", progress=False,
                  run=sj.SweepRun(chunk_size))
result"""),
    new_markdown_cell("""Running the same call again finds every chunk on disk (the manifest records a hash of
the sweep definition) and computes nothing. After an interruption it would compute only the
missing chunks; with different inputs in the same directory it refuses with a `ValueError`."""),
    new_code_cell("""again = sj.sweep(wheel, snow, loads, slips, out="sweep-output", progress=False,
                 run=sj.SweepRun(chunk_size))
print(again)"""),
    new_markdown_cell("""## Load the results

`load_sweep` returns one array per column, in flat-index order; the grid shape
(parameter sets, loads, slips) restores the axes."""),
    new_code_cell("""rows = sj.load_sweep("sweep-output")
print(list(rows))
shape = (p_ws.size, loads.size, slips.size)
assert np.array_equal(rows["index"], np.arange(np.prod(shape)))
grid = {name: column.reshape(shape) for name, column in rows.items()}
for code in np.unique(rows["status"]):
    print(f"{sj.Status(code).name}: {np.sum(rows['status'] == code)} points")"""),
    new_code_cell("""fig, axes = plt.subplots(2, p_ws.size, figsize=(4.2 * p_ws.size, 7), sharex=True, sharey=True,
                         squeeze=False)
for p, p_w in enumerate(p_ws):
    for row, (name, scale, label) in enumerate(
        [("drawbar_pull", 1e-3, "drawbar pull [kN]"), ("sinkage", 1e2, "sinkage [cm]")]
    ):
        ax = axes[row, p]
        mesh = ax.pcolormesh(slips, loads / 1e3, grid[name][p] * scale, shading="nearest")
        fig.colorbar(mesh, ax=ax, label=label)
        ax.set_title(f"p_w = {p_w / 1e3:g} kPa")
        if row == 1:
            ax.set_xlabel("slip [-]")
        if p == 0:
            ax.set_ylabel("load [kN]")
fig.tight_layout()"""),
    new_code_cell("""mid = loads.size // 2
fig, ax = plt.subplots(figsize=(6, 4))
for p, p_w in enumerate(p_ws):
    ax.plot(slips, grid["drawbar_pull"][p, mid] / 1e3, label=f"p_w = {p_w / 1e3:g} kPa")
ax.set_xlabel("slip [-]")
ax.set_ylabel("drawbar pull [kN]")
ax.set_title(f"load {loads[mid] / 1e3:.1f} kN")
ax.legend();"""),
    new_markdown_cell("""## Large sweeps

The chunk files `sweep-output/chunk_*.npz` are the dataset; `iter_sweep_chunks` reads them
one at a time, so a summary of 10⁸ points needs the memory of one chunk. For such sweeps
pass `formats=()` (no consolidated copy) and read the chunks.

The same sweep from the command line (full sizes; it has the same definition, so run in
this directory it finds every chunk done; after an interruption, rerun it to resume):

    snowjax sweep --loads 2000:8000:25 --slips 0:0.9:40 --p-w 40e3,60e3,85.55e3 \\
        --chunk-size 1024 --out sweep-output

Lists given to parameter options are zipped into parameter sets; `--param-grid` takes every
combination instead (`snowjax sweep --help`)."""),
    new_code_cell("""best = None
for chunk in sj.iter_sweep_chunks("sweep-output", columns=["index", "load", "slip", "p_w",
                                                           "drawbar_pull"]):
    k = int(np.argmax(chunk["drawbar_pull"]))
    if best is None or chunk["drawbar_pull"][k] > best["drawbar_pull"]:
        best = {name: column[k] for name, column in chunk.items()}
print("largest drawbar pull:", {k: v.item() for k, v in best.items()})"""),
    new_code_cell("""import csv

with open("sweep-output/sweep.csv") as f:
    reader = csv.DictReader(f)
    first = next(reader)
print(first)"""),
]
nb = new_notebook(
    cells=cells,
    metadata={
        "kernelspec": {"display_name": "Python 3", "language": "python", "name": "python3"},
        "language_info": {"name": "python"},
    },
)
nbformat.write(nb, sys.argv[1])
