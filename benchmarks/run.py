"""snowjax benchmarks: throughput, gradient cost, compile time, in-step latency, SciPy reference.

    python benchmarks/run.py            # full run (about 3-5 minutes on 2 CPU cores)
    python benchmarks/run.py --quick    # smaller sizes (about 1-2 minutes)
    python benchmarks/run.py --no-docs

Prints a table and writes it (with the machine it ran on) into docs/guide/performance.md
between the markers `<!-- benchmarks:start -->` and `<!-- benchmarks:end -->`.  Float64 unless a row
says otherwise; thesis tyre (D = 0.736 m, b = 0.235 m) on the thesis's fresh snow
(`WongSnow.thesis_fresh_snow()`), loads uniform in 1-9 kN and slips uniform in [0, 0.9]
(classic shear) unless stated.  Every timing is the best of several runs after the
compile (the compile is reported on its own).
"""

from __future__ import annotations

import argparse
import json
import os
import pathlib
import platform
import subprocess
import sys
import time

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # for tests/reference.py (the independent SciPy reference)
sys.path.insert(0, str(ROOT / "benchmarks"))
# The CPU table runs on the CPU even where a GPU is installed; the GPU rows are measured
# by a child process of this script (`--gpu-child`), which keeps JAX's default platform.
GPU_CHILD = "--gpu-child" in sys.argv
if not GPU_CHILD:
    os.environ["JAX_PLATFORMS"] = "cpu"

import jax  # noqa: E402

jax.config.update("jax_enable_x64", True)
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402
from doc_block import add_no_docs, write_block  # noqa: E402
from rich.console import Console  # noqa: E402
from rich.progress import Progress  # noqa: E402
from rich.table import Table  # noqa: E402
from robustness import cost_ratio  # noqa: E402

import snowjax as sj  # noqa: E402

WHEEL = sj.RigidWheel.thesis_tire()
SNOW = sj.WongSnow.thesis_fresh_snow()


def inputs(n, seed=0, dtype=np.float64):
    rng = np.random.default_rng(seed)
    return rng.uniform(1e3, 9e3, n).astype(dtype), rng.uniform(0.0, 0.9, n).astype(dtype)


def best_time(fn, repeats):
    """Best wall time [s] of `fn()` (which must block) over `repeats` runs."""
    best = np.inf
    for _ in range(repeats):
        t = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t)
    return best


def solve(load, slip, shear="classic", snow=SNOW, wheel=WHEEL):
    st = sj.solve_wheel(wheel, sj.ContactModel(snow, shear=shear), load, slip)
    st.entry_angle.block_until_ready()
    return st


def throughput(n, shear="classic", dtype=np.float64, repeats=3):
    load, slip = inputs(n, dtype=dtype)
    snow, wheel = SNOW, WHEEL
    if dtype == np.float32:
        cast = lambda tree: jax.tree_util.tree_map(lambda x: jnp.asarray(x, jnp.float32), tree)  # noqa: E731
        snow, wheel = cast(SNOW), cast(WHEEL)
    st = solve(load, slip, shear, snow, wheel)  # compile
    t = best_time(lambda: solve(load, slip, shear, snow, wheel), repeats)
    return n / t, t, st


def compile_time(shear="classic"):
    """First call of solve_wheel in a fresh process, minus the same call once compiled."""
    code = f"""
import time, jax, numpy as np
jax.config.update("jax_enable_x64", True)
import snowjax as sj
w, s = sj.RigidWheel.thesis_tire(), sj.WongSnow.thesis_fresh_snow()
load, slip = np.linspace(1e3, 9e3, 1000), np.linspace(0, 0.9, 1000)
s = sj.ContactModel(s, shear={shear!r})
t = time.perf_counter(); sj.solve_wheel(w, s, load, slip).entry_angle.block_until_ready()
first = time.perf_counter() - t
t = time.perf_counter(); sj.solve_wheel(w, s, load, slip).entry_angle.block_until_ready()
print(first - (time.perf_counter() - t))
"""
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    return float(out.stdout.strip().splitlines()[-1])


_CORE_JOB = """
import os, sys, time
core, n, repeats, start_at = (int(sys.argv[1]), int(sys.argv[2]), int(sys.argv[3]),
                              float(sys.argv[4]))
if core >= 0:
    os.sched_setaffinity(0, {core})
import jax, numpy as np
jax.config.update("jax_enable_x64", True)
import snowjax as sj
w, s = sj.RigidWheel.thesis_tire(), sj.WongSnow.thesis_fresh_snow()
rng = np.random.default_rng(max(core, 0))
load, slip = rng.uniform(1e3, 9e3, n), rng.uniform(0.0, 0.9, n)
sj.solve_wheel(w, s, load, slip).entry_angle.block_until_ready()
time.sleep(max(0.0, start_at - time.time()))  # workers start timing together
best = 1e9
for _ in range(repeats):
    t = time.perf_counter()
    sj.solve_wheel(w, s, load, slip).entry_angle.block_until_ready()
    best = min(best, time.perf_counter() - t)
print(best)
"""


def _core_jobs(cores, n, repeats):
    """Seconds per solve of a batch of n in one fresh process per entry of `cores` (a core
    to pin it to, or -1 for none), all timing at the same moment."""
    start_at = time.time() + 25.0  # after every process's import and compile
    procs = [
        subprocess.Popen(
            [sys.executable, "-c", _CORE_JOB, str(c), str(n), str(repeats), str(start_at)],
            stdout=subprocess.PIPE,
            text=True,
        )
        for c in cores
    ]
    return [float(p.communicate()[0].strip().splitlines()[-1]) for p in procs]


def two_cores(n, repeats=3):
    """Throughput [1/s] of batches of n on the machine's first two cores: one process
    pinned to one core, one unpinned process (XLA:CPU's own threads), and two processes
    pinned to a core each with n/2 points each (what `sweep` does with `workers=2`)."""
    (one,) = _core_jobs([0], n, repeats)
    (plain,) = _core_jobs([-1], n, repeats)
    pair = _core_jobs([0, 1], n // 2, repeats)
    return n / one, n / plain, 2 * (n // 2) / max(pair)


def gradient_ratio(n, repeats=3):
    """Cost of d(sinkage, motion resistance, drawbar pull)/d(p_w, z_w, tan phi), vs forward."""
    load, slip = inputs(n)
    params = jnp.array([float(SNOW.p_w), float(SNOW.z_w), float(SNOW.tan_phi)])

    def outputs(p):
        snow = sj.WongSnow(p[0], p[1], SNOW.cohesion, p[2], SNOW.shear_modulus)
        st = sj.solve_wheel(WHEEL, snow, load, slip)
        return jnp.stack([st.sinkage, st.motion_resistance, st.drawbar_pull])

    fwd = jax.jit(outputs)
    jac = jax.jit(jax.jacfwd(outputs))  # (3, n, 3): every element's 3x3 Jacobian
    grad = jax.jit(jax.grad(lambda p: jnp.sum(outputs(p))))  # one scalar over the batch
    fns = {"forward": fwd, "jacfwd": jac, "grad": grad}
    for fn in fns.values():
        fn(params).block_until_ready()
    # Interleaved rounds, best of each: the first large run in a process is slower (the
    # allocator grows), which would otherwise favour whichever is timed last.
    times = dict.fromkeys(fns, np.inf)
    for _ in range(repeats):
        for name, fn in fns.items():
            t = best_time(lambda fn=fn: fn(params).block_until_ready(), 1)
            times[name] = min(times[name], t)
    return times


def in_step_latency(n_steps, n_wheels=4, n_vehicles=1, braking=False):
    """Per-wheel cost of solve_wheel inside a jitted lax.scan step, warm-started, for
    `n_vehicles` vehicles of `n_wheels` wheels solved together each step; driving slips
    0.05-0.45, or with `braking` -0.45 to -0.05 (the four-panel rule)."""
    shape = (n_vehicles, n_wheels)
    loads = jnp.full(shape, 5000.0)
    offsets = jnp.arange(n_vehicles * n_wheels, dtype=float).reshape(shape)

    def step(theta, t):
        slip = 0.25 + 0.2 * jnp.sin(0.01 * t + offsets)  # slips change every step
        slip = -slip if braking else slip
        st = sj.solve_wheel(WHEEL, SNOW, loads, slip, initial_entry_angle=theta)
        return st.entry_angle, st.drawbar_pull[0]

    run = jax.jit(lambda ts: jax.lax.scan(step, jnp.full(shape, 0.5), ts))
    ts = jnp.arange(n_steps, dtype=float)
    jax.block_until_ready(run(ts))
    t = best_time(lambda: jax.block_until_ready(run(ts)), 3)
    return t / n_steps / (n_vehicles * n_wheels)


def in_step_latency_pinned(n_steps, braking=False):
    """`in_step_latency` (4 wheels) in a fresh process pinned to one core: at this size
    the step is a few hundred small kernels, and an unpinned process's time varies by
    +-30 % with the core XLA's threads land on."""
    code = (
        "import os, sys; os.sched_setaffinity(0, {0}); sys.argv = ['run.py'];"
        f" sys.path.insert(0, {str(ROOT / 'benchmarks')!r}); import run;"
        f" print(run.in_step_latency({n_steps}, braking={braking}))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    return float(out.stdout.strip().splitlines()[-1])


def simulation_step_cost(n_steps):
    """Per-step, per-wheel cost of `simulate_longitudinal` (4 wheels, constant torque)."""
    vehicle = sj.Vehicle(mass=2000.0, wheel_inertia=1.5, wheel=WHEEL, num_wheels=4)
    dt = 0.01
    run = lambda: sj.simulate_longitudinal(vehicle, SNOW, 400.0, n_steps * dt, dt)  # noqa: E731
    jax.block_until_ready(run())
    return best_time(lambda: jax.block_until_ready(run()), 3) / n_steps / vehicle.num_wheels


def scipy_reference(n_points):
    """Per-point time of the independent SciPy reference (adaptive quad + brentq)."""
    from tests import reference as ref  # noqa: PLC0415

    load, slip = inputs(n_points, seed=1)
    p = dict(
        D=0.736,
        b=0.235,
        p_w=float(SNOW.p_w),
        z_w=float(SNOW.z_w),
        c=float(SNOW.cohesion),
        tan_phi=float(SNOW.tan_phi),
        K=float(SNOW.shear_modulus),
    )
    t = time.perf_counter()
    out = [
        ref.solve(
            load[k],
            slip[k],
            p["D"],
            p["b"],
            p["p_w"],
            p["z_w"],
            p["c"],
            p["tan_phi"],
            p["K"],
            "classic",
        )
        for k in range(n_points)
    ]
    per_point = (time.perf_counter() - t) / n_points
    st = solve(load, slip)
    err = max(
        abs(float(st.sinkage[k]) / (0.368 * (1 - np.cos(o[0]))) - 1)
        for k, o in enumerate(out)
        if o is not None
    )
    return per_point, err


def float32_error(n):
    load, slip = inputs(n)
    st64 = solve(load, slip)
    rate32, _, st32 = throughput(n, dtype=np.float32)
    ok = (np.asarray(st64.status) == 0) & (np.asarray(st32.status) == 0)
    err = np.max(np.abs(np.asarray(st32.sinkage, float)[ok] / np.asarray(st64.sinkage)[ok] - 1))
    return rate32, float(err), float(np.mean(np.isfinite(np.asarray(st32.drawbar_pull))))


def gpu_rows(quick):
    """Rows measured on the GPU (run in the `--gpu-child` process): float32 and float64
    throughput for batches up to 10^7, the gradient ratios and the in-step latency for
    10^4 vehicles of 4 wheels."""
    rows, numbers = [], {}

    def done(row):  # each row on stderr as it is measured (stdout carries the JSON)
        rows.append(row)
        print(" | ".join(row), file=sys.stderr, flush=True)

    sizes = [10_000, 100_000, 1_000_000] + ([] if quick else [10_000_000])
    for dtype, name in ((np.float32, "float32"), (np.float64, "float64")):
        for n in sizes:
            rate, t, st = throughput(n, dtype=dtype, repeats=3)
            ok = float(np.mean(np.asarray(st.status) == 0))
            numbers[f"gpu_throughput_{name}_{n}"] = rate
            done(
                (
                    f"GPU solve_wheel {name}, batch {n:,}",
                    f"{rate:,.0f} /s",
                    f"{t * 1e3:.2f} ms per call; converged {ok:.3f}"
                    + ("; target >= 1e8 /s (H100)" if name == "float32" else ""),
                )
            )
    n_grad = 100_000 if quick else 1_000_000
    times = gradient_ratio(n_grad)
    for name in ("jacfwd", "grad"):
        ratio = times[name] / times["forward"]
        numbers[f"gpu_gradient_ratio_{name}"] = ratio
        done(
            (
                f"GPU {name} w.r.t. (p_w, z_w, tan phi), batch {n_grad:,}",
                f"{ratio:.2f} x forward",
                f"forward {times['forward'] * 1e3:.1f} ms (target <= 1.5x)",
            )
        )
    lat = in_step_latency(100 if quick else 300, n_vehicles=10_000)
    numbers["gpu_in_step_ns_per_wheel"] = lat * 1e9
    done(
        (
            "GPU in-step latency, 10,000 vehicles x 4 wheels (lax.scan, warm start)",
            f"{lat * 1e9:.1f} ns per wheel",
            f"{lat * 4e4 * 1e6:.0f} us per step for all 40,000 wheels",
        )
    )
    return rows, numbers


def _gpu_visible() -> bool:
    """Whether JAX, with its default platform, finds a GPU (checked in a child process,
    since this one is restricted to the CPU)."""
    env = {k: v for k, v in os.environ.items() if k != "JAX_PLATFORMS"}
    code = "import jax; print(jax.default_backend())"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env)
    return out.returncode == 0 and out.stdout.strip().endswith(("gpu", "cuda", "rocm"))


def _run_gpu_child(quick):
    """The GPU rows and the GPU's name, from `run.py --gpu-child` (default platform)."""
    env = {k: v for k, v in os.environ.items() if k != "JAX_PLATFORMS"}
    cmd = [sys.executable, __file__, "--gpu-child"] + (["--quick"] if quick else [])
    # stderr passes through: the child prints each row as it is measured.
    out = subprocess.run(cmd, stdout=subprocess.PIPE, text=True, env=env, check=True)
    result = json.loads(out.stdout.strip().splitlines()[-1])
    return [tuple(r) for r in result["rows"]], result["numbers"], result["machine"]


def machine() -> str:
    cpu = platform.processor() or platform.machine()
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    dev = jax.devices()[0]
    return (
        f"{cpu}, {os.cpu_count()} cores, {dev.platform.upper()} ({dev.device_kind}), "
        f"jax {jax.__version__}, Python {platform.python_version()}"
    )


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="smaller sizes")
    add_no_docs(parser)
    parser.add_argument("--json", type=pathlib.Path, help="also write the numbers as JSON")
    parser.add_argument(
        "--device",
        choices=("auto", "cpu", "gpu"),
        default="auto",
        help="cpu: the CPU table only; gpu: also the GPU rows (an error without a GPU);"
        " auto (default): the GPU rows where JAX finds a GPU",
    )
    parser.add_argument("--gpu-child", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.gpu_child:  # the GPU rows, as one JSON line on stdout
        rows, numbers = gpu_rows(args.quick)
        print(json.dumps(dict(rows=rows, numbers=numbers, machine=machine())))
        return 0
    use_gpu = args.device == "gpu" or (args.device == "auto" and _gpu_visible())
    if args.device == "gpu" and not _gpu_visible():
        print("benchmarks/run.py: --device gpu: JAX finds no GPU here", file=sys.stderr)
        return 2
    console = Console()
    sizes = [1, 10, 100, 1_000, 10_000, 100_000] + ([] if args.quick else [1_000_000])
    rows, numbers = [], {}

    def add(name, value, note=""):
        rows.append((name, value, note))

    steps = [
        "throughput",
        "braking",
        "models",
        "terrains",
        "float32",
        "gradient",
        "compile",
        "in-step",
        "scipy",
    ]
    with Progress(console=console, transient=True) as progress:
        task = progress.add_task("benchmarks", total=len(steps) + len(sizes) - 1)
        for n in sizes:
            rate, t, st = throughput(n, repeats=2 if n >= 1e5 else 5)
            numbers[f"throughput_{n}"] = rate
            add(f"solve_wheel, batch {n:,}", f"{rate:,.0f} /s", f"{t * 1e3:.2f} ms per call")
            progress.advance(task)
        one, plain, pair = two_cores(sizes[-1], repeats=2 if args.quick else 3)
        numbers.update(two_core_ratio=pair / one, one_process_ratio=plain / one)
        add(
            f"2 cores / 1 core, batch {sizes[-1]:,}",
            f"{pair / one:.2f}x",
            f"one pinned core {one:,.0f} /s; two processes pinned to a core each (sweep's"
            f" workers) {pair:,.0f} /s (target >= 1.7x); one unpinned process"
            f" {plain:,.0f} /s = {plain / one:.2f}x",
        )
        balance = sj.contact_forces(WHEEL, SNOW, st.entry_angle, inputs(sizes[-1])[1]).vertical_load
        numbers["max_load_balance_error"] = float(
            np.max(np.abs(np.asarray(balance) / inputs(sizes[-1])[0] - 1))
        )
        n_ref = 10_000 if args.quick else 100_000
        # Braking against driving: random in-range cases (benchmarks/cases.py), slips in
        # [-0.5, 0) against [0, 0.99), same parameter sets; the target is <= 2x.
        for shear in ("classic", "simplified", "none"):
            for n in (10_000, n_ref) if n_ref > 10_000 else (n_ref,):
                ratio, times = cost_ratio(n, shear, repeats=2)
                numbers[f"braking_ratio_{shear}_{n}"] = ratio
                add(
                    f"braking / driving time, {shear}, batch {n:,}",
                    f"{ratio:.2f}x",
                    f"random in-range cases: {times['braking'] * 1e3:.0f} ms vs"
                    f" {times['driving'] * 1e3:.0f} ms",
                )
        progress.advance(task)
        for shear in ("simplified", "none"):
            rate, _, _ = throughput(n_ref, shear=shear, repeats=2)
            numbers[f"throughput_{shear}"] = rate
            add(
                f"solve_wheel {shear} shear, batch {n_ref:,}",
                f"{rate:,.0f} /s",
                f"classic: {numbers[f'throughput_{n_ref}']:,.0f} /s",
            )
        # Every terrain law, the Wong-Reece distribution and the slip-angle wheel: same
        # slips, loads scaled into each terrain's range (the thesis tyre would pass
        # 85 degrees on the softer soils at 9 kN).
        load, slip = inputs(n_ref)
        wong_reece = sj.WongReece(0.43, 0.32)
        reece = sj.ReeceSoil(0.8, 10.0, 800.0, 15e3, 1e3, 0.6, shear_modulus=0.02)
        beta = np.deg2rad(10.0)
        bulldozing = sj.Lateral(unit_weight=5e3, bulldozing=True)
        bekker, layered = sj.BekkerSoil.snow_us(), sj.LayeredSnow.ice_layer_example()
        laws = {  # name: (terrain, load divisor)
            "WongSnow": (SNOW, 1),
            "BekkerSoil.snow_us": (bekker, 9),
            "ReeceSoil (test sand)": (reece, 4),
            "LayeredSnow.ice_layer_example": (layered, 4),
        }
        # name: (terrain, distribution, load divisor, slip angle, lateral); every law with
        # each distribution, straight and at a slip angle of 10 degrees (the Wong front
        # region straight is the reference row above).
        terrains = {}
        for law, (terrain, divisor) in laws.items():
            for angle, running in ((0.0, ""), (beta, ", slip angle 10 deg")):
                for dist, region in ((None, ", front region"), (wong_reece, " + Wong-Reece")):
                    if law == "WongSnow" and dist is None and angle == 0.0:
                        continue
                    terrains[f"{law}{running}{region}"] = (terrain, dist, divisor, angle, None)
        terrains["WongSnow, slip angle 10 deg + Wong-Reece + bulldozing"] = (
            SNOW, wong_reece, 1, beta, bulldozing,
        )  # fmt: skip
        # The deflecting tyre (the thesis tyre's size, section height 0.176 m, 100 kPa:
        # both modes over these loads on Wong snow and Reece's sand; on Bekker's snow it
        # stays round, its switch to the elastic mode beyond the cap, and the solver
        # takes it as its rim), against the rigid rows of the same terrain and
        # distribution; the notes give the share of treads flattened at the root.
        tires = {
            "WongSnow, front region": (SNOW, None, 1),
            "WongSnow + Wong-Reece": (SNOW, wong_reece, 1),
            "BekkerSoil.snow_us, front region": (bekker, None, 9),
            "BekkerSoil.snow_us + Wong-Reece": (bekker, wong_reece, 9),
            "ReeceSoil (test sand), front region": (reece, None, 4),
        }
        rigid_rows = {}
        for rigid, (terrain, dist, divisor) in tires.items():
            name = f"DeflectingTire 100 kPa on {rigid}"
            terrains[name] = (terrain, dist, divisor, 0.0, None)
            reference = rigid == "WongSnow, front region"
            rigid_rows[name] = f"throughput_{n_ref}" if reference else f"throughput_{rigid}"
        # Ruts 2-12 cm deep left in the thesis snow by the same wheel (k_0 = 1 MPa/m,
        # A_u = 5 MPa/m^2, as benchmarks/ruts.py): against the Wong front-region row, the
        # same wheel, loads and slips on the virgin snow.
        terrains["Rut of WongSnow (2-12 cm), front region"] = (
            sj.Rut(SNOW, np.random.default_rng(1).uniform(0.02, 0.12, n_ref), WHEEL.width,
                   1e6, 5e6),
            None, 1, 0.0, None,
        )  # fmt: skip
        tire = sj.DeflectingTire(WHEEL.diameter, WHEEL.width, 0.176, 100e3)
        for name, (terrain, dist, divisor, angle, lateral) in terrains.items():
            wheel = tire if name in rigid_rows else WHEEL

            def run(
                terrain=terrain, dist=dist, ld=load / divisor, angle=angle, lateral=lateral,
                wheel=wheel,
            ):  # fmt: skip
                st = sj.solve_wheel(
                    wheel,
                    sj.ContactModel(terrain, distribution=dist, lateral=lateral),
                    ld,
                    slip,
                    slip_angle=angle,
                )
                st.entry_angle.block_until_ready()
                return st

            state = run()
            codes, counts = np.unique(np.asarray(state.status), return_counts=True)
            statuses = ", ".join(
                f"{sj.Status(int(c)).name} {k / n_ref:.2f}" for c, k in zip(codes, counts)
            )
            if name in rigid_rows:  # the share of treads that flatten at the root
                flat = 1 - np.mean(np.asarray(wheel.stays_round(state.entry_angle, terrain)))
                statuses += f"; treads flattened {flat:.2f}"

            t = best_time(run, 2)
            numbers[f"throughput_{name}"] = n_ref / t
            add(
                f"solve_wheel {name}, batch {n_ref:,}",
                f"{n_ref / t:,.0f} /s",
                f"{numbers[f'throughput_{n_ref}'] / (n_ref / t):.1f}x the Wong front-region cost; "
                + (
                    f"{numbers[rigid_rows[name]] / (n_ref / t):.1f}x the rigid wheel's on the "
                    "same terrain, this run; "
                    if name in rigid_rows
                    else ""
                )
                + ("loads 1-9 kN" if divisor == 1 else f"loads 1-9 kN / {divisor}")
                + f"; status {statuses}",
            )
        progress.advance(task)
        rate32, err32, finite32 = float32_error(n_ref)
        numbers.update(throughput_float32=rate32, float32_sinkage_error=err32)
        add(
            f"solve_wheel float32, batch {n_ref:,}",
            f"{rate32:,.0f} /s",
            f"max sinkage error vs float64 {err32:.1e}; finite fraction {finite32:.3f}",
        )
        progress.advance(task)
        times = gradient_ratio(n_ref)
        for name, what in (
            ("jacfwd", "jacfwd of 3 outputs"),
            ("grad", "jax.grad of their sum over the batch"),
        ):
            ratio = times[name] / times["forward"]
            numbers[f"gradient_ratio_{name}"] = ratio
            add(
                f"{what} w.r.t. (p_w, z_w, tan phi), batch {n_ref:,}",
                f"{ratio:.2f} x forward",
                f"forward {times['forward'] * 1e3:.0f} ms, {name} {times[name] * 1e3:.0f} ms"
                " (target <= 1.5x)",
            )
        progress.advance(task)
        for shear in ("classic",):
            c = compile_time(shear)
            numbers[f"compile_{shear}"] = c
            add(f"first-call compile, {shear}", f"{c:.2f} s", "fresh process, batch of 1,000")
        progress.advance(task)
        lat = in_step_latency_pinned(200 if args.quick else 1000)
        lat_braking = in_step_latency_pinned(200 if args.quick else 1000, braking=True)
        numbers["in_step_us_per_wheel"] = lat * 1e6
        numbers["in_step_us_per_wheel_braking"] = lat_braking * 1e6
        add(
            "in-step latency (4 wheels, lax.scan, warm start)",
            f"{lat * 1e6:.1f} us per wheel",
            "driving slips; fresh process pinned to one core (target <= 5 us); braking"
            f" slips (four-panel rule) {lat_braking * 1e6:.1f} us",
        )
        sim = simulation_step_cost(200 if args.quick else 1000)
        numbers["simulation_us_per_wheel_step"] = sim * 1e6
        add(
            "simulate_longitudinal, per step",
            f"{sim * 1e6:.1f} us per wheel",
            "4 driven wheels, 400 N m each, dt = 10 ms, diffrax",
        )
        progress.advance(task)
        n_scipy = 3 if args.quick else 10
        per_point, err = scipy_reference(n_scipy)
        numbers.update(scipy_per_point_s=per_point)
        speedup = numbers[f"throughput_{n_ref}"] * per_point
        add(
            "SciPy reference (quad + brentq), per point",
            f"{per_point * 1e3:.0f} ms",
            f"snowjax batch {n_ref:,} is {speedup:,.0f}x faster; sinkage agrees to {err:.1e}",
        )
        progress.advance(task)

    gpu_where = None
    if use_gpu:
        console.print("measuring the GPU rows (a child process) ...")
        gpu, gpu_numbers, gpu_where = _run_gpu_child(args.quick)
        rows += gpu
        numbers.update(gpu_numbers)
    table = Table(title="snowjax benchmarks")
    for col in ("what", "result", "notes"):
        table.add_column(col)
    for r in rows:
        table.add_row(*r)
    console.print(table)
    where = machine()
    console.print(f"machine: {where}")
    if gpu_where is not None:
        console.print(f"GPU rows: {gpu_where}")
    markdown = "\n".join(
        [
            f"Measured on: {where}, with `python benchmarks/run.py` (`make bench`).",
            "",
            *(
                ["GPU rows (`GPU ...`) measured on: " + gpu_where + ".", ""]
                if gpu_where is not None
                else [
                    "No GPU was available for this run (`--device gpu` measures the GPU rows"
                    " where JAX finds one).",
                    "",
                ]
            ),
            "| what | result | notes |",
            "|---|---|---|",
        ]
        + [f"| {a} | {b} | {c} |" for a, b, c in rows]
    )
    if args.json:
        args.json.write_text(json.dumps(dict(numbers, machine=where), indent=2))
    if not args.no_docs:
        console.print(f"updated {write_block('benchmarks', markdown)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
