"""Throughput of the snowjax rover inside MuJoCo MJX: environment steps per second with and
without the snow's wheel forces.

    python benchmarks/mjx.py            # 1, 1,024 and 4,096 environments (minutes on 2 cores)
    python benchmarks/mjx.py --device gpu  # also 16,384 and 65,536 environments, float32
    python benchmarks/mjx.py --quick    # fewer steps
    python benchmarks/mjx.py --no-docs

Needs the `mjx` extra.  The shipped rover (`snowjax.mjx.load_rover`: free-floating
chassis, sprung wheels, Ackermann steering, 4 thesis tyres; 16 dofs) starts at 2 m/s with
its wheels at slip 0.2, steered at 0.1 rad and driven by 540 N m per wheel, on the thesis
fresh snow (classic shear, `Lateral()`, float64 on the CPU).  Jitted `lax.scan`
rollouts from that state:

- `mjx.step`: MuJoCo MJX alone (no snow forces: the wheels spin on a frictionless floor;
  joint damping explicit, see `rollouts`);
- `snowjax.mjx.step`: the same MJX pipeline plus the four wheels' snow forces (warm-started
  equilibria with slip angle, their forward-mode slopes, the wheel Jacobians and the
  implicit update), at the reference accuracy and at the simulator accuracy
  (`ContactModel(accuracy="simulator")`);
- `snowjax.mjx.step` on a rut map (`rollout(..., ruts=RutMap.empty(...))`, reference
  accuracy): each wheel reads the rut ahead of it, solves on that `Rut` and marks its
  track, on a 10 m x 10 m map of 10 cm cells per environment (`MAP_EXTENT`, `MAP_CELL`).

The snowjax cost is the difference.  1,024 and 4,096 environments vmap the rollout, each
environment on its own snow (p_w 60-200 kPa).  `--device gpu` runs on the GPU in float32
(where one is present).  Timings are the best of three runs after the compile.  Prints
the table and writes it between `<!-- mjx-benchmarks:start -->` and
`<!-- mjx-benchmarks:end -->` in docs/guide/performance.md.
"""

from __future__ import annotations

import argparse
import pathlib
import sys
import time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))

import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402
from doc_block import add_no_docs, write_block  # noqa: E402
from mujoco import mjx  # noqa: E402
from rich.console import Console  # noqa: E402
from rich.progress import track  # noqa: E402
from rich.table import Table  # noqa: E402
from run import best_time, machine  # noqa: E402

# float32 on a GPU (see --device); set after importing run.py, which turns float64 on.
jax.config.update("jax_enable_x64", not {"gpu", "--device=gpu"} & set(sys.argv[1:]))

import snowjax as sj  # noqa: E402
from snowjax import mjx as smjx  # noqa: E402

TORQUE = 540.0  # [N m] per wheel
SPEED = 2.0  # [m/s]
SLIP = 0.2
STEER = 0.1  # [rad]
# The rut map of each environment: 10 m x 10 m about the start, 10 cm cells (100 x 100);
# k_0 [Pa/m] and A_u [Pa/m^2] as in docs/guide/ruts.md (illustrative).
MAP_EXTENT, MAP_CELL, MAP_K_0, MAP_A_U = (-4.0, 6.0, -5.0, 5.0), 0.1, 1e6, 5e6


def rut_map(dtype):
    """The empty rut map every environment starts on."""
    return sj.RutMap.empty(MAP_EXTENT, MAP_CELL, MAP_K_0, MAP_A_U, dtype=dtype)


def start(m, wheels):
    """MJX state at 2 m/s, every wheel spinning at slip 0.2, steered and driven."""
    d = mjx.make_data(m)
    radius = float(wheels.wheel.diameter) / 2
    omega = SPEED / (radius * (1 - SLIP))
    qvel = d.qvel.at[0].set(SPEED)
    qvel = qvel.at[np.asarray(wheels.dof_ids)].set(omega)
    return d.replace(qvel=qvel, ctrl=smjx.rover_controls(STEER, jnp.full(4, TORQUE)))


def rollouts(m, wheels, d0, steps):
    """(plain MJX, MJX + snowjax, at the simulator accuracy, on a rut map) rollouts of
    `steps` steps, functions of p_w [Pa]."""
    base = sj.WongSnow.thesis_fresh_snow()

    # MJX alone integrates the joints' damping explicitly: with MuJoCo's implicit damping,
    # MJX's Euler update (a batched Cholesky of M + dt D) hung on this CPU when vmapped over
    # 256 or more environments (jaxlib 0.10.2: no CPU use, never returned; 128 ran).
    # snowjax.mjx.step does its own implicit solve (an LU) and ran at 1,024 and 4,096.
    explicit = m.replace(
        opt=m.opt.replace(disableflags=m.opt.disableflags | mjx.DisableBit.EULERDAMP)
    )

    def plain(p_w):
        def body(d, _):
            d = mjx.step(explicit, d)
            return d, d.qvel[0]

        d = d0.replace(qpos=d0.qpos + 0.0 * p_w)  # same signature as `snow`
        return jax.lax.scan(body, d, None, length=steps)[1]

    def snow(p_w, accuracy="reference", on_map=False):
        terrain = sj.WongSnow(p_w, base.z_w, base.cohesion, base.tan_phi, base.shear_modulus)
        model = sj.ContactModel(terrain, accuracy=accuracy)
        grid = rut_map(d0.qpos.dtype) if on_map else None
        return smjx.rollout(m, d0, wheels, model, d0.ctrl, steps, ruts=grid).qvel[:, 0]

    return plain, snow, lambda p_w: snow(p_w, "simulator"), lambda p_w: snow(p_w, on_map=True)


def measure(batch, steps, m, wheels, d0):
    """Seconds per step of the rollouts (MJX alone, with snow at the reference and at the
    simulator accuracy, with snow on a rut map) for `batch` environments; the compile
    times [s]."""
    plain, snow, snow_simulator, snow_map = rollouts(m, wheels, d0, steps)
    fns = {"plain": plain, "snow": snow, "simulator": snow_simulator, "map": snow_map}
    if batch == 1:
        p_w = jnp.asarray(85.55e3, d0.qpos.dtype)
        runs = {name: jax.jit(fn) for name, fn in fns.items()}
    else:
        rng = np.random.default_rng(0)
        p_w = jnp.asarray(np.exp(rng.uniform(np.log(60e3), np.log(200e3), batch)), d0.qpos.dtype)
        runs = {name: jax.jit(jax.vmap(fn)) for name, fn in fns.items()}
    out = {}
    for name, fn in runs.items():
        t = time.perf_counter()
        compiled = fn.lower(p_w).compile()
        compile_s = time.perf_counter() - t
        v = jax.block_until_ready(compiled(p_w))
        if not np.all(np.isfinite(np.asarray(v))):
            raise SystemExit(f"non-finite speed in the {name} rollout (batch {batch})")
        best = best_time(lambda c=compiled: jax.block_until_ready(c(p_w)), 3)
        out[name] = (best / steps, compile_s)
    return out


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true", help="fewer steps per rollout")
    add_no_docs(parser)
    parser.add_argument("--device", choices=("cpu", "gpu"), default="cpu",
                        help="cpu (float64, default) or gpu (float32)")  # fmt: skip
    args = parser.parse_args(argv)
    device = jax.devices(args.device)[0]
    jax.config.update("jax_default_device", device)
    model, wheels = smjx.load_rover()
    m = mjx.put_model(model)
    d0 = start(m, wheels)
    n = wheels.num_wheels
    quick = args.quick
    cases = ((1, 100 if quick else 400), (1024, 3 if quick else 10), (4096, 2 if quick else 5))
    if args.device == "gpu":  # a GPU fills at larger batches
        cases += ((16384, 2 if quick else 5), (65536, 2 if quick else 5))
    rows, map_rows = [], []
    for batch, steps in track(cases, description="MJX rollouts", transient=True):
        r = measure(batch, steps, m, wheels, d0)
        t_mjx, t_all = r["plain"][0], r["snow"][0]
        t_wheels = t_all - t_mjx
        t_simulator = r["simulator"][0] - t_mjx
        row = (batch, steps, t_mjx, t_all, t_wheels, t_wheels / n, r["snow"][1], t_simulator)
        rows.append(row)
        map_rows.append((batch, steps, t_all, r["map"][0]))

    head = (
        "| environments | steps timed | MJX env-steps/s | MJX + snowjax env-steps/s |"
        " MJX step | MJX + snowjax step | snowjax wheel forces per step (per wheel) |"
        " wheel forces / MJX step | the same at the simulator accuracy |"
        " first-call compile (MJX + snowjax) |"
    )
    lines = [head, "|---|---|---|---|---|---|---|---|---|---|"]
    platform = jax.default_backend().upper()
    precision = "float64" if jax.config.jax_enable_x64 else "float32"
    table = Table(title=f"snowjax rover in MJX ({precision}, 4 wheels, {platform})")
    for col in (
        "envs",
        "steps",
        "MJX steps/s",
        "+snow steps/s",
        "MJX step",
        "MJX+snowjax",
        "wheels (per wheel)",
        "ratio",
        "ratio (simulator)",
        "compile",
    ):
        table.add_column(col)

    def us(seconds, batch):
        per_env = seconds / batch * 1e6
        return (
            f"{seconds * 1e3:.2f} ms ({per_env:.1f} µs/env)" if batch > 1 else f"{per_env:.0f} µs"
        )

    for batch, steps, t_mjx, t_all, t_wheels, t_wheel, compile_s, t_simulator in rows:
        cells = (
            f"{batch:,}",
            str(steps),
            f"{batch / t_mjx:,.0f}",
            f"{batch / t_all:,.0f}",
            us(t_mjx, batch),
            us(t_all, batch),
            f"{us(t_wheels, batch)} ({t_wheel / batch * 1e6:.1f} µs/wheel)",
            f"{t_wheels / t_mjx:.2f}",
            f"{t_simulator / t_mjx:.2f}",
            f"{compile_s:.1f} s",
        )
        lines.append("| " + " | ".join(cells) + " |")
        table.add_row(*cells)
    console = Console()
    console.print(table)
    map_lines = _map_table(map_rows, rut_map(d0.qpos.dtype), us, console)
    where = machine()
    console.print(f"machine: {where}")
    text = "\n".join(
        [
            *lines,
            "",
            f"* Machine: {where}.  Measured with"
            f" `python benchmarks/mjx.py{' --quick' if args.quick else ''}`.",
            f"* {precision}; the shipped rover (16 dofs, 4 wheels); env-steps/s = environments"
            " x MJX steps (5 ms) per second.  Wheel forces = (MJX + snowjax step) - (MJX step):"
            " the four equilibria with their slip angles, their forward-mode slopes, the wheel"
            " Jacobians and the implicit update; at the simulator accuracy"
            ' (`ContactModel(terrain, accuracy="simulator")`) with fewer quadrature nodes.',
            "",
            *map_lines,
        ]
    )
    if not args.no_docs:
        write_block("mjx-benchmarks", text)


def _map_table(map_rows, grid, us, console):
    """The rut map's rows (Markdown lines; printed too): the rover's step with and
    without a map, their difference, and the map's memory per environment."""
    nx, ny = grid.depth.shape
    memory = f"{grid.nbytes / 1024:,.0f} KiB ({nx} x {ny} cells)"
    head = (
        "| environments | steps timed | MJX + snowjax step | the same on a rut map |"
        " rut map per step (read, `Rut`, mark; 4 wheels) | on a map / without |"
        " map memory per environment |"
    )
    lines = [head, "|---|---|---|---|---|---|---|"]
    table = Table(title="the rover on a rut map")
    for col in ("envs", "steps", "MJX+snowjax", "on a map", "map per step", "ratio", "memory"):
        table.add_column(col)
    for batch, steps, t_all, t_map in map_rows:
        cells = (
            f"{batch:,}",
            str(steps),
            us(t_all, batch),
            us(t_map, batch),
            us(t_map - t_all, batch),
            f"{t_map / t_all:.2f}",
            memory,
        )
        lines.append("| " + " | ".join(cells) + " |")
        table.add_row(*cells)
    console.print(table)
    x0, x1, y0, y1 = MAP_EXTENT
    return [
        *lines,
        "",
        f"* The rut map (`snowjax.mjx.rollout(..., ruts=RutMap)`): {x1 - x0:g} m x"
        f" {y1 - y0:g} m in {MAP_CELL * 100:g} cm cells per environment, {grid.depth.dtype}"
        " (the cost per step does not grow with the map: each wheel's mark updates a"
        f" window of {grid.window} x {grid.window} cells; the memory grows with its area)."
        " Rut map per step = (step on a rut map) - (step without): reading the map ahead"
        " of the four wheels, their equilibria on a `Rut` instead of the virgin snow, the"
        " depths they leave and the marks.",
    ]


if __name__ == "__main__":
    main()
