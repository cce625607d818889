"""Cost and memory of ruts: the rut map (`snowjax.RutMap`, `snowjax.drive_path`) and the
vehicles in their own ruts (`snowjax.Ruts` in `simulate_longitudinal`).

    python benchmarks/ruts.py            # about 3 minutes on 2 cores
    python benchmarks/ruts.py --quick    # fewer steps
    python benchmarks/ruts.py --no-docs

Float64, thesis tyre on the thesis's fresh snow, slip 0.2, 3.5 kN per wheel, four wheels
(two axles 2.5 m apart, tracks 1.5 m apart) driving straight at 0.1 m per step over a
10 m x 10 m map of 5 cm cells (200 x 200), one map per environment:

- map alone: every step reads the rut ahead of the four wheels and marks their footprints
  (`RutMap.read` + `RutMap.mark`, depths given), in a `lax.scan`;
- `drive_path`: the same with each wheel's equilibrium on its `Rut` (warm-started);
- the same scan of `solve_wheel` on the virgin snow, without any map (the wheels alone);
- `simulate_longitudinal` with and without `Ruts` (four wheels, 400 N m each,
  dt = 10 ms).

Batch 1,024 vmaps the scan over 1,024 environments.  Best of three runs after the
compile.  Prints the table and writes it between `<!-- rut-benchmarks:start -->` and
`<!-- rut-benchmarks:end -->` in docs/guide/performance.md.
"""

from __future__ import annotations

import argparse
import pathlib
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))

import jax  # noqa: E402

jax.config.update("jax_enable_x64", True)
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402
from doc_block import add_no_docs, write_block  # noqa: E402
from rich.console import Console  # noqa: E402
from rich.progress import track  # noqa: E402
from rich.table import Table  # noqa: E402
from run import best_time, machine  # noqa: E402

import snowjax as sj  # noqa: E402

WHEEL = sj.RigidWheel.thesis_tire()
SNOW = sj.WongSnow.thesis_fresh_snow()
LOAD, SLIP, K_0, A_U = 3500.0, 0.2, 1e6, 5e6
CELL, EXTENT = 0.05, (-1.0, 9.0, -5.0, 5.0)


def paths(steps):
    """Wheel centres (steps, 4, 2): front left/right, rear left/right, along x."""
    x = 0.1 * jnp.arange(steps)
    corners = jnp.array([[2.5, 0.75], [2.5, -0.75], [0.0, 0.75], [0.0, -0.75]])
    return corners[None] + jnp.stack([x, 0 * x], -1)[:, None, :]


def kernels(steps):
    """Functions of p_w [Pa] -> a number, for the three scans."""
    positions = paths(steps)
    width, ahead = WHEEL.width, float(WHEEL.diameter) / 2

    def snow(p_w):
        return sj.WongSnow(p_w, SNOW.z_w, SNOW.cohesion, SNOW.tan_phi, SNOW.shear_modulus)

    def map_alone(p_w):
        grid = sj.RutMap.empty(EXTENT, CELL, K_0, A_U)
        depth = jnp.full(4, 0.1) * p_w / 85.55e3  # given depths [m]

        def body(carry, position):
            grid, previous = carry
            seen = grid.read(position, 0.0, width, ahead)
            grid = grid.mark(previous, position, width, jnp.maximum(depth, seen))
            return (grid, position), seen

        return jnp.sum(jax.lax.scan(body, (grid, positions[0]), positions)[1])

    def on_map(p_w):
        grid = sj.RutMap.empty(EXTENT, CELL, K_0, A_U)
        out = sj.drive_path(WHEEL, snow(p_w), grid, positions, 0.0, LOAD, SLIP)
        return jnp.sum(out.motion_resistance)

    def virgin(p_w):
        def body(hint, _):
            st = sj.solve_wheel(WHEEL, snow(p_w), jnp.full(4, LOAD), SLIP, initial_entry_angle=hint)
            return jax.lax.stop_gradient(st.entry_angle), st.motion_resistance

        hint = jnp.full(4, jnp.nan)
        return jnp.sum(jax.lax.scan(body, hint, None, length=steps)[1])

    return {"map alone": map_alone, "drive_path": on_map, "virgin": virgin}


def measure(batch, steps):
    """Seconds per step of each scan for `batch` environments."""
    if batch == 1:
        p_w = jnp.asarray(85.55e3)
    else:
        rng = np.random.default_rng(0)
        p_w = jnp.asarray(np.exp(rng.uniform(np.log(60e3), np.log(200e3), batch)))
    out = {}
    for name, fn in kernels(steps).items():
        run = jax.jit(fn if batch == 1 else jax.vmap(fn))
        compiled = run.lower(p_w).compile()
        v = jax.block_until_ready(compiled(p_w))
        if not np.all(np.isfinite(np.asarray(v))):
            raise SystemExit(f"non-finite result in {name} (batch {batch})")
        out[name] = best_time(lambda c=compiled: jax.block_until_ready(c(p_w)), 3) / steps
    return out


def simulation(steps, ruts):
    """Seconds per step of simulate_longitudinal (4 wheels, 400 N m, dt 10 ms)."""
    vehicle = sj.Vehicle(mass=4 * LOAD / 9.80665, wheel_inertia=1.5, wheel=WHEEL, num_wheels=4)

    def run():
        return sj.simulate_longitudinal(
            vehicle,
            SNOW,
            400.0,
            steps * 0.01,
            0.01,
            ruts=ruts,
            initial=sj.InitialState(speed=2.0),
            stepping=sj.Stepping(save_every=steps),
        )

    jax.block_until_ready(run())
    return best_time(lambda: jax.block_until_ready(run()), 3) / steps


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true", help="fewer steps")
    add_no_docs(parser)
    args = parser.parse_args(argv)
    cases = ((1, 50 if args.quick else 200), (1024, 5 if args.quick else 20))
    results = {}
    for batch, steps in track(cases, description="rut scans", transient=True):
        results[batch] = (steps, measure(batch, steps))
    sim_steps = 100 if args.quick else 400
    sim = {
        name: simulation(sim_steps, ruts)
        for name, ruts in (("off", None), ("on", sj.Ruts(K_0, A_U)))
    }

    def us(seconds, batch):
        return f"{seconds / batch * 1e6:.1f} µs/env" + (
            f" ({seconds * 1e3:.2f} ms)" if batch > 1 else ""
        )

    grid = sj.RutMap.empty(EXTENT, CELL, K_0, A_U)
    lines = [
        "| environments | steps timed | map alone (read + mark, 4 wheels) | drive_path"
        " (map + 4 equilibria on ruts) | 4 equilibria on virgin snow, no map |",
        "|---|---|---|---|---|",
    ]
    table = Table(title="rut map per step (float64, 4 wheels, CPU)")
    for col in ("envs", "steps", "map alone", "drive_path", "virgin, no map"):
        table.add_column(col)
    for batch, (steps, t) in results.items():
        cells = (
            f"{batch:,}",
            str(steps),
            us(t["map alone"], batch),
            us(t["drive_path"], batch),
            us(t["virgin"], batch),
        )
        lines.append("| " + " | ".join(cells) + " |")
        table.add_row(*cells)
    console = Console()
    console.print(table)
    where = machine()
    big = 1000 * 1000
    notes = [
        f"* Memory per environment: {grid.depth.shape[0]} x {grid.depth.shape[1]} cells,"
        f" {grid.nbytes / 1024:.0f} KiB in float64 ({grid.nbytes / 2048:.0f} KiB in float32);"
        f" a 100 m x 100 m map of 10 cm cells: {big * 8 / 2**20:.1f} MiB (float64). The cost"
        f" per step does not grow with the map: each wheel's mark updates a window of"
        f" {grid.window} x {grid.window} cells.",
        f"* `simulate_longitudinal` (4 wheels, 400 N m, dt = 10 ms, {sim_steps} steps):"
        f" {sim['off'] * 1e6 / 4:.1f} µs per wheel-step without ruts,"
        f" {sim['on'] * 1e6 / 4:.1f} µs with `Ruts` (rear axle in the front axle's ruts:"
        f" two solves in sequence per Newton evaluation), {sim['on'] / sim['off']:.2f}x.",
        f"* Machine: {where}.  Measured with"
        f" `python benchmarks/ruts.py{' --quick' if args.quick else ''}`.",
    ]
    for line in notes:
        console.print(line)
    if not args.no_docs:
        write_block("rut-benchmarks", "\n".join([*lines, "", *notes]))


if __name__ == "__main__":
    main()
