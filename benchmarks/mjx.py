"""Cost of the snowjax wheel forces inside MuJoCo MJX, per wheel per step, vs the MJX step.

    python benchmarks/mjx.py            # batch 1 and 1,024 environments (about 2-3 minutes)
    python benchmarks/mjx.py --quick    # fewer steps
    python benchmarks/mjx.py --no-readme

Needs the `mjx` extra.  The shipped vehicle (`snowjax.mjx.load_vehicle`: 4 thesis tyres,
thesis fresh snow, classic shear, float64) starts at 2 m/s with its wheels at slip 0.2 and
is driven by 540 N m per wheel.  Two jitted `lax.scan` rollouts from that state:

- `mjx.step`: MuJoCo MJX alone (no snow forces);
- `snowjax.mjx.step`: the same MJX pipeline plus the four wheels' snow forces
  (warm-started equilibria, the forward-mode slope for the implicit spin damping, the
  wheel Jacobians and the implicit update).

The snowjax cost is the difference, reported per step and per wheel.  Batch 1,024 vmaps
the rollout over 1,024 environments, each on its own snow (p_w 60-200 kPa).  Timings are
the best of three runs after the compile.  Prints the table and writes it between
`<!-- mjx-benchmarks:start -->` and `<!-- mjx-benchmarks:end -->` in README.md.
"""

from __future__ import annotations

import argparse
import pathlib
import sys
import time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))

import jax  # noqa: E402

jax.config.update("jax_enable_x64", True)
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402
from readme_block import write_block  # noqa: E402
from rich.console import Console  # noqa: E402
from rich.progress import track  # noqa: E402
from rich.table import Table  # noqa: E402
from run import best_time, machine  # noqa: E402

import snowjax as sj  # noqa: E402
from snowjax import mjx as smjx  # noqa: E402

mjx = smjx.mjx
TORQUE = 540.0  # [N m] per wheel
SPEED = 2.0  # [m/s]
SLIP = 0.2


def start(m, wheels):
    """MJX state at 2 m/s, every wheel spinning at slip 0.2."""
    d = mjx.make_data(m)
    radius = float(wheels.wheel.diameter) / 2
    omega = SPEED / (radius * (1 - SLIP))
    qvel = d.qvel.at[0].set(SPEED)
    qvel = qvel.at[np.asarray(wheels.dof_ids)].set(omega)
    return d.replace(qvel=qvel, ctrl=jnp.full(m.nu, TORQUE))


def rollouts(m, wheels, d0, steps):
    """(plain MJX, MJX + snowjax) rollouts of `steps` steps, functions of p_w [Pa]."""
    base = sj.WongSnow.thesis_fresh_snow()

    def plain(p_w):
        def body(d, _):
            d = mjx.step(m, d)
            return d, d.qvel[0]

        d = d0.replace(qpos=d0.qpos + 0.0 * p_w)  # same signature as `snow`
        return jax.lax.scan(body, d, None, length=steps)[1]

    def snow(p_w):
        terrain = sj.WongSnow(p_w, base.z_w, base.cohesion, base.tan_phi, base.shear_modulus)
        ctrl = jnp.full(m.nu, TORQUE)
        return smjx.rollout(m, d0, wheels, terrain, ctrl, steps).qvel[:, 0]

    return plain, snow


def measure(batch, steps, m, wheels, d0):
    """Seconds per step of both rollouts for `batch` environments; the compile times [s]."""
    plain, snow = rollouts(m, wheels, d0, steps)
    if batch == 1:
        p_w = jnp.asarray(85.55e3)
        runs = {"plain": jax.jit(plain), "snow": jax.jit(snow)}
    else:
        rng = np.random.default_rng(0)
        p_w = jnp.asarray(np.exp(rng.uniform(np.log(60e3), np.log(200e3), batch)))
        runs = {"plain": jax.jit(jax.vmap(plain)), "snow": jax.jit(jax.vmap(snow))}
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
    parser.add_argument("--no-readme", action="store_true", help="do not rewrite README.md")
    args = parser.parse_args(argv)
    model, wheels = smjx.load_vehicle()
    m = mjx.put_model(model)
    d0 = start(m, wheels)
    n = wheels.num_wheels
    cases = ((1, 100 if args.quick else 400), (1024, 5 if args.quick else 20))
    rows = []
    for batch, steps in track(cases, description="MJX rollouts", transient=True):
        r = measure(batch, steps, m, wheels, d0)
        t_mjx, t_all = r["plain"][0], r["snow"][0]
        t_wheels = t_all - t_mjx
        rows.append((batch, steps, t_mjx, t_all, t_wheels, t_wheels / n, r["snow"][1]))

    head = (
        "| environments | steps timed | MJX step | MJX + snowjax step | snowjax wheel forces"
        " per step (per wheel) | wheel forces / MJX step | first-call compile (MJX + snowjax) |"
    )
    lines = [head, "|---|---|---|---|---|---|---|"]
    platform = jax.default_backend().upper()
    table = Table(title=f"snowjax wheel forces inside MJX (float64, 4 wheels, {platform})")
    for col in (
        "envs",
        "steps",
        "MJX step",
        "MJX+snowjax",
        "wheels (per wheel)",
        "ratio",
        "compile",
    ):
        table.add_column(col)

    def us(seconds, batch):
        per_env = seconds / batch * 1e6
        return (
            f"{seconds * 1e3:.2f} ms ({per_env:.1f} µs/env)" if batch > 1 else f"{per_env:.0f} µs"
        )

    for batch, steps, t_mjx, t_all, t_wheels, t_wheel, compile_s in rows:
        cells = (
            f"{batch:,}",
            str(steps),
            us(t_mjx, batch),
            us(t_all, batch),
            f"{us(t_wheels, batch)} ({t_wheel / batch * 1e6:.1f} µs/wheel)",
            f"{t_wheels / t_mjx:.2f}",
            f"{compile_s:.1f} s",
        )
        lines.append("| " + " | ".join(cells) + " |")
        table.add_row(*cells)
    console = Console()
    console.print(table)
    where = machine()
    console.print(f"machine: {where}")
    text = "\n".join(
        [
            *lines,
            "",
            f"* Machine: {where}.  Measured {time.strftime('%Y-%m-%d')} with"
            f" `python benchmarks/mjx.py{' --quick' if args.quick else ''}`.",
            "* Wheel forces = (MJX + snowjax step) - (MJX step): the four equilibria with their"
            " forward-mode slopes, the wheel Jacobians and the implicit spin update.",
        ]
    )
    if not args.no_readme:
        write_block("mjx-benchmarks", text)


if __name__ == "__main__":
    main()
