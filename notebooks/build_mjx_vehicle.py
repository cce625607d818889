"""Generate notebooks/mjx_vehicle.ipynb (no stored outputs)."""

import sys

import nbformat
from nbformat.v4 import new_code_cell, new_markdown_cell, new_notebook

cells = [
    new_markdown_cell("""# A vehicle on snow in MuJoCo MJX: two snows, 1,024 snows at once, gradients

`snowjax.mjx.step` is `mjx.step` with the snowjax rigid-wheel forces (drawbar pull, eq. 2.10,
and resisting torque M_w, eq. 2.12, at the quasi-static equilibrium 4.14 of Sankapalli 2004)
written into the wheel rows of `data.xfrc_applied`; `snowjax.mjx.rollout` scans it. Both are
pure JAX, so a rollout can be jitted, vmapped over snow parameter sets and differentiated.

The shipped model (`snowjax/data/mjx_rover.xml`) is a steerable 4-wheel rover of 1,427 kg
(free-floating chassis, sprung wheels, Ackermann steering) on four thesis tyres
(D = 0.736 m, b = 0.235 m, I = 1.5 kg m²), driven straight ahead by 540 N m per wheel from
rest for 3 s (600 MJX steps of 5 ms). MuJoCo's frictionless floor stands for the compacted
rut bottom and carries the load; the snow supplies the tangential forces and torques (see
the `snowjax.mjx` module documentation for the load model).

This notebook needs the optional extra: `pip install 'snowjax[mjx]'`. SI units throughout."""),
    new_code_cell("""import os
import time

import jax

jax.config.update("jax_enable_x64", True)
import jax.numpy as jnp
import matplotlib.pyplot as plt
import numpy as np
from mujoco import mjx

import snowjax as sj
from snowjax import mjx as smjx

SMALL = os.environ.get("SNOWJAX_NOTEBOOK_SMALL") == "1"  # the test suite runs a tiny version
STEPS = 600  # 3 s at 5 ms
TORQUE = 540.0  # [N m] per wheel
NUM_SNOWS = 8 if SMALL else 1024  # snow parameter sets in the one vmapped rollout

model, wheels = smjx.load_rover()
m = mjx.put_model(model)
d0 = mjx.make_data(m)
print(f"timestep {model.opt.timestep} s, static wheel loads {np.asarray(wheels.static_load).round(1)} N")"""),
    new_markdown_cell("""## One function for everything: distance, trajectory and its gradient

`drive(x)` runs the 3 s rollout on the snow with x = (p_w [Pa], tan φ) (the other Wong
parameters are the thesis's fresh snow, Table 4.1) and returns the distance travelled and
the trajectory of speed and slip. Forward-mode differentiation (a `jax.jvp` per parameter,
vmapped over the two directions) gives d distance / d(p_w, tan φ) in the same pass, and
`jax.vmap` over x runs every snow at once. JAX compiles this once, so the two snows, the
1,024 snows, the gradients and their finite-difference check below are one batch.

Forward mode because MJX's constraint solver is a `while_loop` (reverse mode needs
`opt.iterations = 1`, too inexact for this vehicle's floor contact; see the module
documentation), and for two parameters it is also the cheaper mode."""),
    new_code_cell("""base = sj.WongSnow.thesis_fresh_snow()


def snow_of(x):
    return sj.WongSnow(x[0], base.z_w, base.cohesion, x[1], base.shear_modulus)


def drive(x):
    ctrl = smjx.rover_controls(0.0, jnp.full(4, TORQUE))  # straight ahead
    r = smjx.rollout(m, d0, wheels, snow_of(x), ctrl, STEPS)
    slip = jnp.mean(r.wheels.slip, axis=-1)
    return r.qpos[-1, 0], (r.qvel[:, 0], slip, jnp.max(r.wheels.status, axis=-1))


def drive_with_gradient(x):
    def along(direction):
        return jax.jvp(drive, (x,), (direction,))

    (distance, traj), (d_distance, _) = jax.vmap(along, out_axes=(None, 0))(jnp.eye(2))
    return distance, d_distance, traj


batched = jax.jit(jax.vmap(drive_with_gradient))"""),
    new_markdown_cell("""## The batch

Rows 0 and 1 are the two named snows: the thesis's fresh snow (p_w = 85.55 kPa,
tan φ = 0.0787) and a firmer, more frictional snow (p_w = 150 kPa, tan φ = 0.3). Rows 2–5
perturb the fresh snow by ±0.1 % in p_w and in tan φ (central differences). The rest
are random snows, p_w log-uniform in 60–200 kPa and tan φ uniform in 0.05–0.4."""),
    new_code_cell("""fresh = jnp.array([base.p_w, base.tan_phi])
firm = jnp.array([150e3, 0.3])
h = jnp.array([1e-3 * fresh[0], 1e-3 * fresh[1]])
rng = np.random.default_rng(0)
n_random = NUM_SNOWS - 6
random = np.column_stack([np.exp(rng.uniform(np.log(60e3), np.log(200e3), n_random)),
                          rng.uniform(0.05, 0.4, n_random)])
xs = jnp.concatenate([jnp.stack([fresh, firm,
                                 fresh.at[0].add(h[0]), fresh.at[0].add(-h[0]),
                                 fresh.at[1].add(h[1]), fresh.at[1].add(-h[1])]),
                      jnp.asarray(random)])

t0 = time.perf_counter()
compiled = batched.lower(xs).compile()
t1 = time.perf_counter()
distance, gradient, (speed, slip, status) = jax.block_until_ready(compiled(xs))
t2 = time.perf_counter()
print(f"compile {t1 - t0:.1f} s; {NUM_SNOWS} snows x {STEPS} steps with 2 tangents: {t2 - t1:.1f} s")
worst = np.asarray(status).max(axis=-1)
print("status of the wheel equilibria:", {sj.Status(int(s)).name: int(np.sum(worst == s))
                                          for s in np.unique(worst)})
assert np.all(np.isfinite(np.asarray(distance))) and np.all(np.isfinite(np.asarray(gradient)))"""),
    new_markdown_cell("""## Two snows

On the firmer snow the same torque drives the rover at a lower slip and it gets further."""),
    new_code_cell("""time_s = model.opt.timestep * np.arange(1, STEPS + 1)
fig, axes = plt.subplots(1, 2, figsize=(10, 3.6))
for row, label in ((0, "fresh snow (thesis)"), (1, "firm snow")):
    axes[0].plot(time_s, speed[row], label=f"{label}: {float(distance[row]):.2f} m")
    axes[1].plot(time_s, slip[row], label=label)
axes[0].set(xlabel="time [s]", ylabel="speed [m/s]", title="Speed from rest, 540 N m per wheel")
axes[1].set(xlabel="time [s]", ylabel="slip [-]", title="Wheel slip", ylim=(-0.1, 1))
axes[0].legend()
axes[1].legend()
fig.tight_layout()
for row, label in ((0, "fresh"), (1, "firm")):
    print(f"{label}: distance {float(distance[row]):.3f} m, speed {float(speed[row, -1]):.3f} m/s,"
          f" slip {float(slip[row, -1]):.3f}")
assert float(distance[1]) > float(distance[0])"""),
    new_markdown_cell("""## Gradients against central differences

d distance / d p_w and d distance / d tan φ on the fresh snow, forward mode vs the
central differences of rows 2–5 (same compiled function)."""),
    new_code_cell("""central = np.array([(distance[2] - distance[3]) / (2 * h[0]),
                    (distance[4] - distance[5]) / (2 * h[1])])
for k, name, unit in ((0, "p_w", "m/Pa"), (1, "tan phi", "m")):
    g = float(gradient[0, k])
    print(f"d distance / d {name}: forward mode {g:.6e} {unit}, central differences "
          f"{central[k]:.6e} {unit}, relative difference {abs(g / central[k] - 1):.1e}")
np.testing.assert_allclose(np.asarray(gradient[0]), central, rtol=1e-3)"""),
    new_markdown_cell("""## Many snows

Distance after 3 s over the random snows, and its sensitivity to friction,
d distance / d tan φ, from the same batch."""),
    new_code_cell("""x_r = np.asarray(xs[6:])
d_r = np.asarray(distance[6:])
g_r = np.asarray(gradient[6:])
fig, axes = plt.subplots(1, 2, figsize=(11, 4), sharey=True)
for ax, value, label in ((axes[0], d_r, "distance in 3 s [m]"),
                         (axes[1], g_r[:, 1], "d distance / d tan φ [m]")):
    sc = ax.scatter(x_r[:, 0] / 1e3, x_r[:, 1], c=value, s=12, cmap="viridis")
    fig.colorbar(sc, ax=ax, label=label)
    ax.set_xscale("log")
    ax.set(xlabel="p_w [kPa]")
axes[0].set(ylabel="tan φ [-]", title=f"{len(x_r)} snows in one vmapped rollout")
fig.tight_layout()
print(f"distance over the random snows: {d_r.min():.2f}-{d_r.max():.2f} m")"""),
]

nb = new_notebook(cells=cells)
nb.metadata["kernelspec"] = {"display_name": "Python 3", "language": "python", "name": "python3"}
nbformat.write(nb, sys.argv[1] if len(sys.argv) > 1 else "notebooks/mjx_vehicle.ipynb")
