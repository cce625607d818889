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
    fwd(params).block_until_ready()
    jac(params).block_until_ready()
    t_fwd = best_time(lambda: fwd(params).block_until_ready(), repeats)
    t_jac = best_time(lambda: jac(params).block_until_ready(), repeats)
    return t_jac / t_fwd, t_fwd, t_jac


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
        # Every terrain law and the Wong-Reece distribution, same loads and slips, wheel
        # 1.0 m x 0.4 m where the thesis snow's tyre would exceed 85 degrees on Bekker snow.
        load, slip = inputs(n_ref)
        terrains = {
            "WongSnow + Wong-Reece": (SNOW, sj.WongReece(0.43, 0.32), WHEEL, load),
            "BekkerSoil.snow_us, front region": (sj.BekkerSoil.snow_us(), None, WHEEL, load / 9),
            "BekkerSoil.snow_us + Wong-Reece": (
                sj.BekkerSoil.snow_us(),
                sj.WongReece(0.43, 0.32),
                WHEEL,
                load / 9,
            ),
            "LayeredSnow.ice_layer_example, front region": (
                sj.LayeredSnow.ice_layer_example(),
                None,
                WHEEL,
                load / 4,
            ),
        }
        for name, (terrain, dist, wheel, ld) in terrains.items():

            def run(wheel=wheel, terrain=terrain, ld=ld, dist=dist):
                st = sj.solve_wheel(wheel, terrain, ld, slip, distribution=dist)
                st.entry_angle.block_until_ready()

            run()
            t = best_time(run, 2)
            numbers[f"throughput_{name}"] = n_ref / t
            add(
                f"solve_wheel {name}, batch {n_ref:,}",
                f"{n_ref / t:,.0f} /s",
                f"{numbers[f'throughput_{n_ref}'] / (n_ref / t):.1f}x the Wong front-region cost; "
                + "loads "
                + ("1-9 kN" if ld is load else f"1-9 kN / {9 if 'Bekker' in name else 4}"),
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
        ratio, t_fwd, t_jac = gradient_ratio(n_ref)
        numbers.update(gradient_ratio=ratio)
        add(
            f"jacfwd of 3 outputs w.r.t. (p_w, z_w, tan phi), batch {n_ref:,}",
            f"{ratio:.2f} x forward",
            f"forward {t_fwd * 1e3:.0f} ms, Jacobian {t_jac * 1e3:.0f} ms",
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
