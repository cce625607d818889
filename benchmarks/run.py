"""snowjax benchmarks: throughput, gradient cost, compile time, in-step latency, SciPy reference.

    python benchmarks/run.py            # full run (about 3-5 minutes on 2 CPU cores)
    python benchmarks/run.py --quick    # smaller sizes (about 1-2 minutes)
    python benchmarks/run.py --no-readme

Prints a table and writes it (with the machine it ran on) into README.md between the
markers `<!-- benchmarks:start -->` and `<!-- benchmarks:end -->`.  Float64 unless a row
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

import jax  # noqa: E402

jax.config.update("jax_enable_x64", True)
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402
from readme_block import write_block  # noqa: E402
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
    st = sj.solve_wheel(wheel, snow, load, slip, shear)
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
t = time.perf_counter(); sj.solve_wheel(w, s, load, slip, {shear!r}).entry_angle.block_until_ready()
first = time.perf_counter() - t
t = time.perf_counter(); sj.solve_wheel(w, s, load, slip, {shear!r}).entry_angle.block_until_ready()
print(first - (time.perf_counter() - t))
"""
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    return float(out.stdout.strip().splitlines()[-1])


def two_cores(n, repeats=3):
    """Throughput [1/s] of a batch of n on one of two host CPU devices and split over both
    (one program per device, as `sweep` does), in a fresh process with
    `XLA_FLAGS=--xla_force_host_platform_device_count=2`; best of `repeats` (one device
    timed before and after)."""
    code = f"""
import time, jax, numpy as np
jax.config.update("jax_enable_x64", True)
import snowjax as sj
w, s = sj.RigidWheel.thesis_tire(), sj.WongSnow.thesis_fresh_snow()
rng = np.random.default_rng(0)
load, slip = rng.uniform(1e3, 9e3, {n}), rng.uniform(0.0, 0.9, {n})
devices, h = jax.devices()[:2], {n} // 2
parts = [[jax.device_put(x[k * h:(k + 1) * h], d) for x in (load, slip)]
         for k, d in enumerate(devices)]
solve = lambda ps: [sj.solve_wheel(w, s, *p).entry_angle for p in ps]
jax.block_until_ready(solve(parts))
def timed(ps):
    t = time.perf_counter()
    jax.block_until_ready(solve(ps))
    return time.perf_counter() - t
one = min(timed(parts[:1]) for _ in range({repeats}))
both = min(timed(parts) for _ in range({repeats}))
one = min(one, *(timed(parts[:1]) for _ in range({repeats})))
print(h / one, 2 * h / both)
"""
    env = dict(os.environ, XLA_FLAGS="--xla_force_host_platform_device_count=2")
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, env=env
    )
    one, both = (float(x) for x in out.stdout.strip().splitlines()[-1].split())
    return one, both


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
    times = {}
    for name, fn in (("forward", fwd), ("jacfwd", jac), ("grad", grad)):
        fn(params).block_until_ready()
        times[name] = best_time(lambda fn=fn: fn(params).block_until_ready(), repeats)
    return times


def in_step_latency(n_steps, n_wheels=4):
    """Per-wheel cost of solve_wheel inside a jitted lax.scan step, warm-started."""
    loads = jnp.full(n_wheels, 5000.0)
    offsets = jnp.arange(n_wheels, dtype=float)

    def step(theta, t):
        slip = 0.25 + 0.2 * jnp.sin(0.01 * t + offsets)  # slips change every step
        st = sj.solve_wheel(WHEEL, SNOW, loads, slip, initial_entry_angle=theta)
        return st.entry_angle, st.drawbar_pull

    run = jax.jit(lambda ts: jax.lax.scan(step, jnp.full(n_wheels, 0.5), ts))
    ts = jnp.arange(n_steps, dtype=float)
    jax.block_until_ready(run(ts))
    t = best_time(lambda: jax.block_until_ready(run(ts)), 3)
    return t / n_steps / n_wheels


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
    parser.add_argument("--no-readme", action="store_true", help="do not update README.md")
    parser.add_argument("--json", type=pathlib.Path, help="also write the numbers as JSON")
    args = parser.parse_args(argv)
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
        one, both = two_cores(sizes[-1], repeats=2 if args.quick else 3)
        numbers.update(two_core_ratio=both / one)
        add(
            f"2 host CPU devices / 1, batch {sizes[-1]:,}",
            f"{both / one:.2f}x",
            f"one device {one:,.0f} /s, both {both:,.0f} /s (target >= 1.7x; a slice per"
            " device, fresh process with --xla_force_host_platform_device_count=2)",
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
        terrains = {  # name: (terrain, distribution, load divisor, slip angle, lateral)
            "WongSnow + Wong-Reece": (SNOW, wong_reece, 1, 0.0, None),
            "BekkerSoil.snow_us, front region": (sj.BekkerSoil.snow_us(), None, 9, 0.0, None),
            "BekkerSoil.snow_us + Wong-Reece": (sj.BekkerSoil.snow_us(), wong_reece, 9, 0.0, None),
            "ReeceSoil (test sand), front region": (reece, None, 4, 0.0, None),
            "ReeceSoil (test sand) + Wong-Reece": (reece, wong_reece, 4, 0.0, None),
            "LayeredSnow.ice_layer_example, front region": (
                sj.LayeredSnow.ice_layer_example(), None, 4, 0.0, None,
            ),
            "WongSnow, slip angle 10 deg, front region": (SNOW, None, 1, beta, None),
            "WongSnow, slip angle 10 deg + Wong-Reece + bulldozing": (
                SNOW, wong_reece, 1, beta, bulldozing,
            ),
        }  # fmt: skip
        for name, (terrain, dist, divisor, angle, lateral) in terrains.items():

            def run(terrain=terrain, dist=dist, ld=load / divisor, angle=angle, lateral=lateral):
                st = sj.solve_wheel(
                    WHEEL, terrain, ld, slip, distribution=dist, slip_angle=angle, lateral=lateral
                )
                st.entry_angle.block_until_ready()
                return st

            codes, counts = np.unique(np.asarray(run().status), return_counts=True)
            statuses = ", ".join(
                f"{sj.Status(int(c)).name} {k / n_ref:.2f}" for c, k in zip(codes, counts)
            )
            t = best_time(run, 2)
            numbers[f"throughput_{name}"] = n_ref / t
            add(
                f"solve_wheel {name}, batch {n_ref:,}",
                f"{n_ref / t:,.0f} /s",
                f"{numbers[f'throughput_{n_ref}'] / (n_ref / t):.1f}x the Wong front-region cost; "
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
        lat = in_step_latency(200 if args.quick else 1000)
        numbers["in_step_us_per_wheel"] = lat * 1e6
        add("in-step latency (4 wheels, lax.scan, warm start)", f"{lat * 1e6:.1f} us per wheel", "")
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

    table = Table(title="snowjax benchmarks")
    for col in ("what", "result", "notes"):
        table.add_column(col)
    for r in rows:
        table.add_row(*r)
    console.print(table)
    where = machine()
    console.print(f"machine: {where}")
    markdown = "\n".join(
        [
            f"Measured on: {where} ({time.strftime('%Y-%m-%d')}).",
            "",
            "| what | result | notes |",
            "|---|---|---|",
        ]
        + [f"| {a} | {b} | {c} |" for a, b, c in rows]
    )
    if args.json:
        args.json.write_text(json.dumps(dict(numbers, machine=where), indent=2))
    if not args.no_readme:
        write_block("benchmarks", markdown)
        console.print("updated README.md")
    return 0


if __name__ == "__main__":
    sys.exit(main())
