"""Compare the wheel solver of two revisions, interleaved, on this machine.

    python benchmarks/compare.py 2280f0c            # that revision vs the working tree
    python benchmarks/compare.py 2280f0c --new HEAD --rounds 5 --out compare.md
    python benchmarks/compare.py 2280f0c --only "Wong–Reece,slip angle"   # some rows

Shared 2-core virtual machines drift by tens of percent between runs minutes apart, so
two separate `benchmarks/run.py` tables cannot show a 10 % change, and neither can two
processes run one after the other (two revisions of the same compiled programs measured
that way moved by 0.80-1.43 both ways between sessions).  This script checks out the old
revision into a temporary git worktree and, for each of `--rounds` rounds, starts one
measuring process per tree, both pinned to the same core, which compile every row first
(the first call of a fresh process is itself a row) and then time the rows on request,
one row of one tree at a time, alternating the trees row by row (old first where the
row's and the round's indices sum to an even number, new first otherwise): the two
measurements of a row are seconds apart, so the machine's drift moves both.  Each row
keeps each tree's best time over the rounds (per request: best of 10 calls, 3 at batch
100,000).  Rows: `solve_wheel` throughput at batch 1 to 100,000 (thesis tyre on the
thesis snow, classic shear, loads 1-9 kN, slips 0-0.9, float64), the in-step latency (4
wheels in a jitted `lax.scan`, warm-started) and the cost of one `simulate_longitudinal`
step per wheel (4 driven wheels, 400 N m, 200 steps of 10 ms); the first call of a fresh
process (compile, batch 1); and the general quadrature: every terrain law (Wong snow,
Bekker's Snow (U.S.), a Reece test sand, the layered snow) on the front region and with
Wong–Reece, the rim at a slip angle of 0.1 rad, and a deflecting tyre (100 kPa) on Wong
snow, on Bekker's snow (front region and Wong–Reece) and on the Reece sand, batches 1
and 1,000 (loads 300-900 N, slips -0.3 to 0.9).  The table is
printed (`--out FILE`: also written there): it compares revisions, so it belongs in a
commit message or the CHANGELOG, not on the documentation's pages.
"""

from __future__ import annotations

import argparse
import inspect
import json
import os
import pathlib
import subprocess
import sys
import tempfile
import time

ROOT = pathlib.Path(__file__).resolve().parents[1]
SIZES = (1, 10, 100, 1_000, 10_000, 100_000)
FIRST_CALL = "first call (compile), batch 1"


def _rows() -> dict:
    """Compile every row (the first call of this fresh process timed as its own row) and
    return {row: (callable, calls per request, divisor)}: seconds per row = best of the
    calls / divisor.  Runs in the measuring process, whose `snowjax` is the tree under
    test, on one core (the last one it may use; Linux): unpinned, XLA's and the other
    tree's threads share the cores, and rows of unchanged code moved by 0.85-1.26 between
    runs on a shared 2-core machine.
    """
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {max(os.sched_getaffinity(0))})
    import jax  # noqa: PLC0415

    jax.config.update("jax_enable_x64", True)
    import jax.numpy as jnp  # noqa: PLC0415
    import numpy as np  # noqa: PLC0415

    import snowjax as sj  # noqa: PLC0415

    wheel, snow = sj.RigidWheel.thesis_tire(), sj.WongSnow.thesis_fresh_snow()
    rng = np.random.default_rng(0)

    t0 = time.perf_counter()  # a fresh process: the first call compiles
    sj.solve_wheel(wheel, snow, 5000.0, 0.3).entry_angle.block_until_ready()
    first = time.perf_counter() - t0
    rows: dict = {FIRST_CALL: (lambda: None, 0, first)}

    for n in SIZES:
        load, slip = rng.uniform(1e3, 9e3, n), rng.uniform(0.0, 0.9, n)

        def run(load=load, slip=slip):
            sj.solve_wheel(wheel, snow, load, slip).entry_angle.block_until_ready()

        rows[f"batch {n:,}"] = (run, 10 if n <= 10_000 else 3, 1)

    loads, offsets = jnp.full(4, 5000.0), jnp.arange(4, dtype=float)

    def step(theta, t):
        slip = 0.25 + 0.2 * jnp.sin(0.01 * t + offsets)
        st = sj.solve_wheel(wheel, snow, loads, slip, initial_entry_angle=theta)
        return st.entry_angle, st.drawbar_pull

    scan = jax.jit(lambda ts: jax.lax.scan(step, jnp.full(4, 0.5), ts))
    ts = jnp.arange(500, dtype=float)
    rows["in-step, per wheel"] = (lambda: jax.block_until_ready(scan(ts)), 10, 500 * 4)

    vehicle = sj.Vehicle(mass=2000.0, wheel_inertia=1.5, wheel=wheel, num_wheels=4)
    sim = lambda: sj.simulate_longitudinal(vehicle, snow, 400.0, 2.0, 0.01)  # noqa: E731
    rows["simulate_longitudinal, per wheel-step"] = (lambda: jax.block_until_ready(sim()), 5, 800)
    # Other terrains, the Wong–Reece distribution, a slip angle and a deflecting tyre (the
    # general quadrature).
    tire = sj.DeflectingTire(wheel.diameter, wheel.width, 0.176, 100e3, 0.0)
    bekker, rear = sj.BekkerSoil.snow_us(), sj.WongReece(0.43, 0.32)
    reece = sj.ReeceSoil(0.8, 10.0, 800.0, 15e3, 1e3, 0.6, shear_modulus=0.02)  # test sand
    others = {
        "Bekker snow (U.S.), Wong–Reece": (wheel, bekker, rear, None),
        "layered snow, front region": (wheel, sj.LayeredSnow.ice_layer_example(), None, None),
        "slip angle 0.1 rad": (wheel, snow, None, 0.1),
        "deflecting tyre (100 kPa)": (tire, snow, None, None),
        "deflecting tyre, Bekker snow (U.S.), Wong–Reece": (tire, bekker, rear, None),
        "deflecting tyre, Bekker snow (U.S.), front region": (tire, bekker, None, None),
        "deflecting tyre, Reece sand, front region": (tire, reece, None, None),
        "Wong snow, Wong–Reece": (wheel, snow, rear, None),
        "Bekker snow (U.S.), front region": (wheel, bekker, None, None),
        "Reece sand, front region": (wheel, reece, None, None),
        "Reece sand, Wong–Reece": (wheel, reece, rear, None),
        "layered snow, Wong–Reece": (wheel, sj.LayeredSnow.ice_layer_example(), rear, None),
        "slip angle 0.1 rad, Wong–Reece": (wheel, snow, rear, 0.1),
        "slip angle 0.1 rad, Bekker snow (U.S.)": (wheel, bekker, None, 0.1),
    }
    if hasattr(sj, "Rut"):  # a rut 8 cm deep, left by the same wheel, in Wong snow
        rut = sj.Rut(snow, 0.08, wheel.width, 1e6, 5e6)
        others["rut in Wong snow, front region"] = (wheel, rut, None, None)
    for label, (this_wheel, terrain, dist, angle) in others.items():
        solve = _solver(this_wheel, terrain, dist, angle)
        for n in (1, 1_000):
            load, slip = rng.uniform(300.0, 900.0, n), rng.uniform(-0.3, 0.9, n)

            def run(solve=solve, load=load, slip=slip):
                solve(load, slip).entry_angle.block_until_ready()

            rows[f"{label}, batch {n:,}"] = (run, 10 if n == 1 else 5, 1)
    only = [w for w in os.environ.get("SNOWJAX_COMPARE_ONLY", "").split(",") if w]
    if only:
        rows = {k: v for k, v in rows.items() if k == FIRST_CALL or any(w in k for w in only)}
    for fn, calls, _ in rows.values():
        if calls:
            fn()  # compile before the first request
    return rows


def serve() -> None:
    """The measuring process: compile the rows, print their names (JSON, one line), then
    answer each row name read from stdin with its seconds (JSON, one line)."""
    import snowjax  # noqa: PLC0415

    rows = _rows()
    print(json.dumps({"snowjax": snowjax.__file__, "rows": list(rows)}), flush=True)
    for line in sys.stdin:
        fn, calls, divisor = rows[line.strip()]
        if not calls:  # measured once, at start-up
            print(json.dumps(divisor), flush=True)
            continue
        times = []
        for _ in range(calls):
            t = time.perf_counter()
            fn()
            times.append(time.perf_counter() - t)
        print(json.dumps(min(times) / divisor), flush=True)


def _solver(wheel, terrain, distribution, slip_angle):
    """`(load, slip) -> solve_wheel(...)` with a distribution, in the spelling of the tree
    measured (revisions before the contact model took a `distribution=` keyword); the
    contact model built once, outside the timed calls, as a user builds it (built on every
    call, the new tree's batch-1 rows measured 1.06-1.39 the old tree's keywords)."""
    import snowjax as sj  # noqa: PLC0415

    if "distribution" in inspect.signature(sj.solve_wheel).parameters:
        options = dict(distribution=distribution, slip_angle=slip_angle)
        return lambda load, slip: sj.solve_wheel(wheel, terrain, load, slip, **options)
    model = sj.ContactModel(terrain, distribution)
    return lambda load, slip: sj.solve_wheel(wheel, model, load, slip, slip_angle=slip_angle)


class _Worker:
    """A measuring process (`serve`) of one tree."""

    def __init__(self, tree: pathlib.Path):
        env = dict(os.environ, PYTHONPATH=str(tree), JAX_PLATFORMS="cpu")
        env.pop("JAX_COMPILATION_CACHE_DIR", None)  # the first call must compile
        code = (
            f"import sys; sys.path.insert(0, {str(ROOT / 'benchmarks')!r}); "
            "import compare; compare.serve()"
        )
        self.process = subprocess.Popen(
            [sys.executable, "-c", code],
            env=env,
            cwd=tempfile.gettempdir(),
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            text=True,
        )
        hello = json.loads(self._read())
        assert hello["snowjax"].startswith(str(tree)), "measured the wrong snowjax"
        self.rows = hello["rows"]

    def _read(self) -> str:
        line = self.process.stdout.readline()  # type: ignore[union-attr]
        if not line:
            raise RuntimeError(f"the measuring process exited ({self.process.wait()})")
        return line

    def time(self, row: str) -> float:
        self.process.stdin.write(row + "\n")  # type: ignore[union-attr]
        self.process.stdin.flush()  # type: ignore[union-attr]
        return json.loads(self._read())

    def close(self) -> None:
        self.process.stdin.close()  # type: ignore[union-attr]
        self.process.wait()


def _fmt(name: str, seconds: float) -> str:
    if "batch" in name and not name.startswith("first"):
        n = int(name.rsplit("batch ", 1)[1].replace(",", ""))
        return f"{n / seconds:,.0f} /s"
    if seconds >= 0.1:
        return f"{seconds:.2f} s"
    return f"{seconds * 1e6:.1f} us"


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("revision", help="the old git revision (e.g. a commit hash)")
    parser.add_argument("--new", help="measure this revision instead of the working tree")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--out", type=pathlib.Path, default=None, help="also write the table here")
    parser.add_argument(
        "--only",
        default="",
        help="comma-separated parts of row names: time only the rows that contain one "
        "(and the first call)",
    )
    args = parser.parse_args(argv)
    os.environ["SNOWJAX_COMPARE_ONLY"] = args.only  # read by the measuring processes

    def rev(name):
        return subprocess.run(
            ["git", "rev-parse", "--short", name],
            cwd=ROOT,
            capture_output=True,
            text=True,
            check=True,
        ).stdout.strip()

    old_rev = rev(args.revision)
    new_rev = rev(args.new) if args.new else f"working tree at {rev('HEAD')}"
    with tempfile.TemporaryDirectory() as tmp:
        trees = {"old": pathlib.Path(tmp) / "old", "new": ROOT}
        revs = {"old": old_rev}
        if args.new:
            trees["new"], revs["new"] = pathlib.Path(tmp) / "new", new_rev
        for label, rev_ in revs.items():
            subprocess.run(
                ["git", "worktree", "add", "--detach", str(trees[label]), rev_],
                cwd=ROOT,
                capture_output=True,
                check=True,
            )
        try:
            best: dict[str, dict[str, float]] = {"old": {}, "new": {}}
            for r in range(args.rounds):
                # One after the other: each compiles alone (the first-call row).
                workers = {label: _Worker(tree) for label, tree in trees.items()}
                try:
                    for k, row in enumerate(workers["old"].rows):
                        order = ("old", "new") if (k + r) % 2 == 0 else ("new", "old")
                        for label in order:
                            t = workers[label].time(row)
                            best[label][row] = min(t, best[label].get(row, float("inf")))
                finally:
                    for worker in workers.values():
                        worker.close()
                print(f"round {r + 1}/{args.rounds} done", file=sys.stderr)
        finally:
            for label in revs:
                subprocess.run(
                    ["git", "worktree", "remove", "--force", str(trees[label])],
                    cwd=ROOT,
                    capture_output=True,
                )

    lines = [
        f"Old: {old_rev}; new: {new_rev}. Best of {args.rounds} rounds, the trees "
        f"alternating row by row ({time.strftime('%Y-%m-%d')}).",
        "",
        f"| row (Wong snow, front region unless named) | {old_rev} | {new_rev} | new / old time |",
        "|---|---|---|---|",
    ]
    for name in best["old"]:
        o, n = best["old"][name], best["new"][name]
        lines.append(f"| {name} | {_fmt(name, o)} | {_fmt(name, n)} | {n / o:.2f} |")
    table = "\n".join(lines)
    print(table)
    if args.out is not None:
        args.out.write_text(table + "\n", encoding="utf-8")


if __name__ == "__main__":
    main()
