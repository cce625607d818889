"""Write notebooks/quick_start.ipynb and notebooks/sensitivity_study.ipynb (no outputs).

Run `python notebooks/build_quick_start_and_sensitivity.py` after editing the cells below.
Both notebooks read SNOWJAX_NOTEBOOK_SMALL ("1" in the test suite) to shrink their grids.
"""

from __future__ import annotations

import pathlib

import nbformat
from nbformat.v4 import new_code_cell, new_markdown_cell, new_notebook

HERE = pathlib.Path(__file__).resolve().parent

SETUP = """\
import os

import jax

jax.config.update("jax_enable_x64", True)  # float64: accurate gradients and comparisons
import matplotlib.pyplot as plt
import numpy as np

import snowjax as sj

SMALL = os.environ.get("SNOWJAX_NOTEBOOK_SMALL") == "1"  # the test suite sets this
"""

QUICK_START = [
    new_markdown_cell("""\
# snowjax quick start

A rigid wheel on shallow snow (Sankapalli 2004, chapter 4): define the wheel and the snow,
solve the vertical equilibrium (4.14) for the entry angle, read sinkage, motion
resistance, thrust, drawbar pull and torque, batch over loads and slips in one call, and
differentiate through the solver. Units are SI throughout (N, Pa, m, rad)."""),
    new_code_cell(SETUP),
    new_markdown_cell("""\
## Wheel and snow

`RigidWheel.thesis_tire()` is the thesis's 0.736 m tyre (width 0.235 m, assumed).
`WongSnow.thesis_fresh_snow()` is the fresh shallow snow of Table 4.1: Wong's
pressure–sinkage law (4.1) with p_w, z_w, Mohr–Coulomb strength c + σ tan φ and the
shear modulus K of Janosi–Hanamoto (4.11). Every field is an array leaf: give it an array
to batch over parameter sets."""),
    new_code_cell("""\
wheel = sj.RigidWheel.thesis_tire()
snow = sj.WongSnow.thesis_fresh_snow()
print(f"D = {float(wheel.diameter)} m, b = {float(wheel.width)} m")
print(f"p_w = {float(snow.p_w) / 1e3:.2f} kPa, z_w = {float(snow.z_w):.3f} m, "
      f"c = {float(snow.cohesion) / 1e3:.2f} kPa, tan phi = {float(snow.tan_phi)}, "
      f"K = {float(snow.shear_modulus) * 1e3:.1f} mm")"""),
    new_markdown_cell("""\
## One operating point

`solve_wheel(wheel, snow, load, slip)` returns a `WheelState`. The
`status` field says whether the equilibrium converged (`Status.CONVERGED`), or e.g. the
wheel bottomed out on the base of the layer — never a silent NaN."""),
    new_code_cell("""\
st = sj.solve_wheel(wheel, snow, load=5000.0, slip=0.3)
print(f"entry angle  {np.degrees(float(st.entry_angle)):.2f} deg")
print(f"sinkage      {100 * float(st.sinkage):.2f} cm")
print(f"motion res.  {float(st.motion_resistance):.1f} N")
print(f"thrust       {float(st.thrust):.1f} N")
print(f"drawbar pull {float(st.drawbar_pull):.1f} N")
print(f"torque       {float(st.torque):.1f} N m")
print("status      ", sj.Status(int(st.status)).name)
assert sj.Status(int(st.status)) == sj.Status.CONVERGED"""),
    new_markdown_cell("""\
## Loads × slips in one call

`load` and `slip` broadcast with NumPy rules: a column of loads against a row of slips
gives a (loads, slips) grid, solved in one compiled, vectorised call."""),
    new_code_cell("""\
loads = np.array([3500.0, 5000.0, 7500.0])
slips = np.linspace(0.0, 1.0, 5 if SMALL else 21)
grid = sj.solve_wheel(wheel, snow, loads[:, None], slips[None, :])
print("shape:", grid.sinkage.shape, "statuses:",
      {sj.Status(int(s)).name for s in np.asarray(grid.status).ravel()})

fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10, 3.8))
for k, load in enumerate(loads):
    ax1.plot(slips, 100 * np.asarray(grid.sinkage[k]), label=f"{load / 1e3:g} kN")
    ax2.plot(slips, np.asarray(grid.drawbar_pull[k]), label=f"{load / 1e3:g} kN")
ax1.set_xlabel("slip i [-]"); ax1.set_ylabel("sinkage z0 [cm]")
ax2.set_xlabel("slip i [-]"); ax2.set_ylabel("drawbar pull [N]")
for ax in (ax1, ax2):
    ax.grid(alpha=0.3); ax.legend()
fig.suptitle("Thesis tyre on fresh snow, classic shear (4.11)")
fig.tight_layout()
plt.show()"""),
    new_markdown_cell("""\
## Gradients through the equilibrium

The solver is differentiable: `jax.grad` gives exact derivatives through the root solve
(implicit function theorem). Here dz0/dp_w, checked against a central finite difference."""),
    new_code_cell("""\
def sinkage_at(p_w):
    s = sj.WongSnow(p_w, snow.z_w, snow.cohesion, snow.tan_phi, snow.shear_modulus)
    return sj.solve_wheel(wheel, s, 5000.0, 0.3).sinkage

p_w = snow.p_w
dz_dpw = jax.grad(sinkage_at)(p_w)
h = 1e-4 * p_w
fd = (sinkage_at(p_w + h) - sinkage_at(p_w - h)) / (2 * h)
print(f"dz0/dp_w = {float(dz_dpw):.6e} m/Pa (autodiff), {float(fd):.6e} m/Pa (central FD)")
assert abs(float(dz_dpw) / float(fd) - 1) < 1e-5"""),
    new_markdown_cell("""\
## Next

* `sj.ContactModel(snow, shear="simplified")` in place of `snow` uses the thesis's
  simplified shear model (4.13); `shear="none"` ignores shear (the straight line of
  Fig. 4.7).
* `notebooks/sensitivity_study.ipynb`: sensitivities to every snow parameter.
* `snowjax reproduce`: every figure of the thesis, with a report."""),
]

SENSITIVITY = [
    new_markdown_cell("""\
# Sensitivity of sinkage and drawbar pull to the snow parameters

How much do the outputs of the wheel model depend on each of the five snow parameters
p_w, z_w, c, tan φ, K (Table 4.1)? `jax.jacfwd` differentiates `solve_wheel` with respect
to the whole `WongSnow` parameter set at once (forward mode, one pass per parameter,
through the implicit function theorem). We normalise the derivatives to **elasticities**
e = (θ / y) ∂y/∂θ: the percentage change of the output per percent change of the
parameter, comparable across parameters with different units."""),
    new_code_cell(SETUP),
    new_code_cell("""\
wheel = sj.RigidWheel.thesis_tire()
snow = sj.WongSnow.thesis_fresh_snow()
LOAD = 5000.0  # N
slips = np.linspace(0.05, 0.95, 5 if SMALL else 19)
NAMES = ["p_w", "z_w", "cohesion", "tan_phi", "shear_modulus"]


def outputs(sn):
    st = sj.solve_wheel(wheel, sn, LOAD, slips)
    out = {"sinkage": st.sinkage, "drawbar_pull": st.drawbar_pull}
    return out, out  # (value to differentiate, aux = the values themselves)


# One compiled function gives both the Jacobian and the values.
jac_and_values = jax.jit(jax.jacfwd(outputs, has_aux=True))
jac, values = jac_and_values(snow)
print({k: v.shape for k, v in values.items()})"""),
    new_markdown_cell("""\
`jac["sinkage"]` is a `WongSnow` whose field `p_w` holds ∂z0/∂p_w at every slip, and so on.
Elasticities:"""),
    new_code_cell("""\
elasticity = {
    out: {name: np.asarray(getattr(snow, name) * getattr(jac[out], name) / values[out])
          for name in NAMES}
    for out in ("sinkage", "drawbar_pull")
}
header = "slip  " + "".join(f"{n:>15s}" for n in NAMES)
for out in ("sinkage", "drawbar_pull"):
    print(f"elasticity of {out}")
    print(header)
    for k in range(0, len(slips), max(1, len(slips) // 5)):
        print(f"{slips[k]:4.2f}  " + "".join(f"{elasticity[out][n][k]:15.4f}" for n in NAMES))"""),
    new_code_cell("""\
fig, axes = plt.subplots(1, 2, figsize=(11, 4))
for ax, out in zip(axes, ("sinkage", "drawbar_pull")):
    for name in NAMES:
        ax.plot(slips, elasticity[out][name], marker="o", ms=3, label=name)
    ax.axhline(0, color="k", lw=0.6)
    ax.set_xlabel("slip i [-]")
    ax.set_ylabel(f"elasticity of {out} [-]")
    ax.set_title(f"{out}, F_z = {LOAD / 1e3:g} kN")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
fig.tight_layout()
plt.show()"""),
    new_markdown_cell("""\
## Finite-difference spot check

Central differences of the *values* (the aux output of the same compiled function, so no
new compilation) at ±1e-5 relative steps of each parameter, against the autodiff
elasticities at every slip."""),
    new_code_cell("""\
import equinox as eqx

worst = 0.0
for name in NAMES:
    theta = getattr(snow, name)
    h = 1e-5 * theta
    plus = jac_and_values(eqx.tree_at(lambda s: getattr(s, name), snow, theta + h))[1]
    minus = jac_and_values(eqx.tree_at(lambda s: getattr(s, name), snow, theta - h))[1]
    for out in ("sinkage", "drawbar_pull"):
        fd = np.asarray(theta * (plus[out] - minus[out]) / (2 * h) / values[out])
        ad = elasticity[out][name]
        err = np.max(np.abs(fd - ad)) / max(np.max(np.abs(ad)), 1e-3)
        worst = max(worst, err)
        print(f"{out:13s} {name:14s} max |FD - AD| / max|AD| = {err:.1e}")
assert worst < 1e-4, worst"""),
    new_markdown_cell("""\
## Reading the result

* Sinkage is governed by the pressure–sinkage law: p_w (elasticity about −1: a 1 % stiffer
  snow sinks about 1 % less) and z_w dominate; the shear parameters enter only through the
  vertical component of the shear stress in (4.14).
* Drawbar pull = thrust − motion resistance is a small difference of two large forces, so
  its elasticities are large; the shear strength (c, tan φ) drives the thrust and the
  pressure parameters drive the motion resistance.
* K matters mainly at small slip, where the shear stress is still being mobilised."""),
]


def write(cells, name):
    nb = new_notebook(cells=cells)
    nb.metadata["kernelspec"] = {
        "name": "python3",
        "display_name": "Python 3",
        "language": "python",
    }
    nb.metadata["language_info"] = {"name": "python"}
    nbformat.validate(nb)
    nbformat.write(nb, HERE / name)


if __name__ == "__main__":
    write(QUICK_START, "quick_start.ipynb")
    write(SENSITIVITY, "sensitivity_study.ipynb")
