"""Throughput of the snowjax rover inside MuJoCo MJX: environment steps per second with and
without the snow's wheel forces.

    python benchmarks/mjx.py            # 1, 1,024 and 4,096 environments (minutes on 2 cores)
    python benchmarks/mjx.py --device gpu  # also 16,384 and 65,536 environments, float32
    python benchmarks/mjx.py --quick    # fewer steps
    python benchmarks/mjx.py --no-docs

Needs the `mjx` extra.  The shipped rover (`snowjax.mjx.load_rover`: free-floating
chassis, sprung wheels, Ackermann steering, 4 thesis tyres; 16 dofs) starts at 2 m/s with
its wheels at slip 0.2, steered at 0.1 rad and driven by 540 N m per wheel, on the thesis
fresh snow (classic shear, `Lateral()`, float64 on the CPU).  Two jitted `lax.scan`
rollouts from that state:

- `mjx.step`: MuJoCo MJX alone (no snow forces: the wheels spin on a frictionless floor;
  joint damping explicit, see `rollouts`);
- `snowjax.mjx.step`: the same MJX pipeline plus the four wheels' snow forces (warm-started
  equilibria with slip angle, their forward-mode slopes, the wheel Jacobians and the
  implicit update), at the reference accuracy and at the simulator accuracy
  (`ContactModel(accuracy="simulator")`).

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


def start(m, wheels):
    """MJX state at 2 m/s, every wheel spinning at slip 0.2, steered and driven."""
    d = mjx.make_data(m)
    radius = float(wheels.wheel.diameter) / 2
    omega = SPEED / (radius * (1 - SLIP))
    qvel = d.qvel.at[0].set(SPEED)
    qvel = qvel.at[np.asarray(wheels.dof_ids)].set(omega)
    return d.replace(qvel=qvel, ctrl=smjx.rover_controls(STEER, jnp.full(4, TORQUE)))


def rollouts(m, wheels, d0, steps):
    """(plain MJX, MJX + snowjax) rollouts of `steps` steps, functions of p_w [Pa]."""
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

    def snow(p_w, accuracy="reference"):
        terrain = sj.WongSnow(p_w, base.z_w, base.cohesion, base.tan_phi, base.shear_modulus)
        model = sj.ContactModel(terrain, accuracy=accuracy)
        return smjx.rollout(m, d0, wheels, model, d0.ctrl, steps).qvel[:, 0]

    return plain, snow, lambda p_w: snow(p_w, "simulator")


def measure(batch, steps, m, wheels, d0):
    """Seconds per step of the rollouts (MJX alone, with snow at the reference and at the
    simulator accuracy) for `batch` environments; the compile times [s]."""
    plain, snow, snow_simulator = rollouts(m, wheels, d0, steps)
    fns = {"plain": plain, "snow": snow, "simulator": snow_simulator}
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
    rows = []
    for batch, steps in track(cases, description="MJX rollouts", transient=True):
        r = measure(batch, steps, m, wheels, d0)
        t_mjx, t_all = r["plain"][0], r["snow"][0]
        t_wheels = t_all - t_mjx
        t_simulator = r["simulator"][0] - t_mjx
        row = (batch, steps, t_mjx, t_all, t_wheels, t_wheels / n, r["snow"][1], t_simulator)
        rows.append(row)

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
        ]
    )
    if not args.no_docs:
        write_block("mjx-benchmarks", text)


if __name__ == "__main__":
    main()
