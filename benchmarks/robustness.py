"""Reliability of `solve_wheel` over its documented range: statuses, NaN, balance, float32.

    python benchmarks/robustness.py                 # 10^6 cases per shear model (~10 min)
    python benchmarks/robustness.py --cases 100000  # quicker
    python benchmarks/robustness.py --no-docs

Then the any-terrain families (`--terrain-cases`, default 100,000 each; also the tyre and
rut families below): every terrain law
(Wong snow on the general quadrature, Bekker, Reece, layered snow), the front region and
Wong–Reece, straight running and slip angles up to 60 degrees with and without sidewall
bulldozing (`tests/random_cases.py`, the ranges of the property tests; a tenth of the cases
rest on the base with the braking sign change of the shear displacement at the axle), in
float64 and float32: statuses, non-finite fields outside INVALID_INPUT, the load balance of
the straight families, and the float32 sinkage error.  Then deflecting tyres (soft with
flexing, and stiff ones against the rim) and ruts (zero depth, mid-depth, at the base) on
every law.

Random in-range cases (`benchmarks/cases.py`: WongSnow front region, slips -0.5 to 0.99,
so about a third brake), every shear model, float64 and float32.  Per shear model and
per family (driving: slip >= 0, braking: slip < 0) it reports the statuses, the number
of NaN fields outside INVALID_INPUT, the load balance |W(theta0) / load - 1| at
convergence (W re-evaluated by `contact_forces`), the float32-vs-float64 sinkage error
quantiles over cases converged in both, the cost of a braking batch relative to a
driving batch of the same size, non-finite gradients over converged cases, and an
independent check of a few hundred cases against SciPy (quad + brentq).  Writes the
table between `<!-- robustness:start -->` and `<!-- robustness:end -->` in
docs/guide/reliability.md.
"""

from __future__ import annotations

import argparse
import pathlib
import sys
import time

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # tests/reference.py: the independent SciPy reference
sys.path.insert(0, str(ROOT / "benchmarks"))

import jax  # noqa: E402

jax.config.update("jax_enable_x64", True)
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402
from cases import in_range  # noqa: E402
from doc_block import add_no_docs, write_block  # noqa: E402
from rich.console import Console  # noqa: E402
from rich.progress import track  # noqa: E402

import snowjax as sj  # noqa: E402
from snowjax import Status  # noqa: E402
from tests.random_cases import (  # noqa: E402
    KINDS,
    UNIT_ROWS,
    any_terrain_inputs,
    tire_and_rut_inputs,
)

SHEARS = ("classic", "simplified", "none")
FIELDS = ("entry_angle", "sinkage", "motion_resistance", "thrust", "drawbar_pull", "torque")
CHUNK = 100_000  # cases per solve_wheel call


def solve_in_chunks(wheel, snow, load, slip, shear):
    """solve_wheel on `CHUNK`-sized pieces (bounded memory); NumPy fields."""
    n = load.shape[0]
    parts = []
    for k in range(0, n, CHUNK):
        piece = slice(k, min(k + CHUNK, n))
        take = lambda tree: jax.tree_util.tree_map(lambda x: x[piece], tree)  # noqa: E731,B023
        st = sj.solve_wheel(
            take(wheel), sj.ContactModel(take(snow), shear=shear), load[piece], slip[piece]
        )
        parts.append({f: np.asarray(getattr(st, f)) for f in (*FIELDS, "status")})
    return {f: np.concatenate([p[f] for p in parts]) for f in parts[0]}


def balance(wheel, snow, load, slip, theta0, shear):
    """|W(theta0) / load - 1| with W from contact_forces (NaN where theta0 is NaN)."""
    out = np.empty_like(load, dtype=np.float64)
    for k in range(0, load.shape[0], CHUNK):
        piece = slice(k, min(k + CHUNK, load.shape[0]))
        take = lambda tree: jax.tree_util.tree_map(lambda x: x[piece], tree)  # noqa: E731,B023
        th = np.where(np.isfinite(theta0[piece]), theta0[piece], 0.1)
        w = sj.contact_forces(
            take(wheel), sj.ContactModel(take(snow), shear=shear), th, slip[piece]
        ).vertical_load
        out[piece] = np.abs(np.asarray(w) / load[piece] - 1)
    return out


def cost_ratio(n, shear, repeats=5):
    """Best time of a braking batch / best time of a driving batch (n random cases each).

    The two batches are timed alternately (driving, braking, driving, ...), so a change
    in the machine's load during the run affects both alike."""
    runs = {}
    for name, slips in (("driving", (0.0, 0.99)), ("braking", (-0.5, 0.0))):
        wheel, snow, load, slip = in_range(n, seed=7, slip=slips)

        def run(wheel=wheel, snow=snow, load=load, slip=slip):
            sj.solve_wheel(
                wheel, sj.ContactModel(snow, shear=shear), load, slip
            ).status.block_until_ready()

        run()  # compile
        runs[name] = run
    times = dict.fromkeys(runs, np.inf)
    for _ in range(repeats):
        for name, run in runs.items():
            t = time.perf_counter()
            run()
            times[name] = min(times[name], time.perf_counter() - t)
    return times["braking"] / times["driving"], times


def gradient_check(n, shear):
    """Non-finite entries of d(drawbar pull)/d(snow leaves, load, slip) over converged cases."""
    wheel, snow, load, slip = in_range(n, seed=3)

    def total(snow, load, slip):
        st = sj.solve_wheel(wheel, sj.ContactModel(snow, shear=shear), load, slip)
        return jnp.sum(st.drawbar_pull), st.status

    grads, status = jax.jit(jax.grad(total, argnums=(0, 1, 2), has_aux=True))(snow, load, slip)
    ok = np.asarray(status) == Status.CONVERGED
    leaves = [np.asarray(g)[ok] for g in jax.tree_util.tree_leaves(grads)]
    return int(sum(np.sum(~np.isfinite(g)) for g in leaves)), int(ok.sum()) * len(leaves)


def scipy_check(n, shear):
    """Max |W_scipy(theta0) / load - 1| and max sinkage difference to brentq [m]."""
    from tests import reference as ref  # noqa: PLC0415

    wheel, snow, load, slip = in_range(n, seed=5)
    st = sj.solve_wheel(wheel, sj.ContactModel(snow, shear=shear), load, slip)
    worst_w, worst_z = 0.0, 0.0
    for k in np.flatnonzero(np.asarray(st.status) == Status.CONVERGED):
        args = (
            float(wheel.diameter[k]), float(wheel.width[k]), float(snow.p_w[k]),
            float(snow.z_w[k]), float(snow.cohesion[k]), float(snow.tan_phi[k]),
            float(snow.shear_modulus[k]),
        )  # fmt: skip
        w = ref.contact_integrals(float(st.entry_angle[k]), float(slip[k]), *args, shear)[0]
        worst_w = max(worst_w, abs(w / float(load[k]) - 1))
        sol = ref.solve(float(load[k]), float(slip[k]), *args, shear)
        if sol is not None and slip[k] >= 0:  # braking W may have several roots
            z_ref = args[0] / 2 * (1 - np.cos(sol[0]))
            worst_z = max(worst_z, abs(z_ref - float(st.sinkage[k])))
    return worst_w, worst_z


# (label, distribution, slip angle, bulldozing) of the any-terrain families.
ANY_FAMILIES = (
    ("front region", False, False, False),
    ("Wong–Reece", True, False, False),
    ("front region, slip angle, bulldozing", False, True, True),
    ("Wong–Reece, slip angle", True, True, False),
)
ALL_FIELDS = (*FIELDS, "lateral_force", "aligning_torque")


def any_terrain_family(kind, family, n, seed=13):
    """Statuses and checks of one any-terrain family: a row of the second table."""
    label, wong_reece, steered, bulldozing = family
    rng = np.random.default_rng(seed)
    unit, corner = rng.uniform(size=(UNIT_ROWS, n)), rng.uniform(size=n) < 0.1
    states = {}
    for dtype in (np.float64, np.float32):
        wheel, terrain, dist, lateral, load, slip, beta = any_terrain_inputs(
            kind, unit, corner, dtype
        )
        lateral = sj.Lateral(lateral.shear_modulus, lateral.unit_weight, bulldozing=bulldozing)
        parts = []
        for k in range(0, n, CHUNK):
            take = lambda t, k=k: jax.tree_util.tree_map(lambda x: x[k : k + CHUNK], t)  # noqa: E731
            st = sj.solve_wheel(
                take(wheel),
                sj.ContactModel(
                    take(terrain),
                    distribution=take(dist) if wong_reece else None,
                    lateral=take(lateral),
                ),
                load[k : k + CHUNK],
                slip[k : k + CHUNK],
                slip_angle=beta[k : k + CHUNK] if steered else None,
            )
            parts.append({f: np.asarray(getattr(st, f)) for f in (*ALL_FIELDS, "status")})
        states[dtype] = {f: np.concatenate([p[f] for p in parts]) for f in parts[0]}
        if dtype == np.float64:
            inputs64 = (wheel, terrain, dist, load, slip)
    st64, st32 = states[np.float64], states[np.float32]
    counts = [int(np.sum(st64["status"] == s)) for s in (0, 1, 4, 3, 2)]

    def non_finite(st):
        bad = np.zeros(n, bool)
        for f in ALL_FIELDS:
            bad |= ~np.isfinite(st[f])
        return int(np.sum(bad & (st["status"] != Status.INVALID_INPUT)))

    conv = st64["status"] == Status.CONVERGED
    worst = "—"
    if not steered:  # W re-evaluated by contact_forces at the returned entry angle
        wheel, terrain, dist, load, slip = inputs64
        th = np.where(conv, st64["entry_angle"], 0.1)
        w = sj.contact_forces(
            wheel, sj.ContactModel(terrain, dist if wong_reece else None), th, slip
        ).vertical_load
        worst = f"{np.max(np.abs(np.asarray(w)[conv] / load[conv] - 1)):.1e}"
    both = conv & (st32["status"] == Status.CONVERGED)
    rel = np.abs(st32["sinkage"][both] / st64["sinkage"][both] - 1)
    q = np.quantile(rel, [0.5, 0.999]) if rel.size else [np.nan, np.nan]
    return (
        f"| {kind} | {label} | {n:,} | {counts[0]:,} | {counts[1]:,} | {counts[2]:,} |"
        f" {counts[3]:,} | {counts[4]:,} | {non_finite(st64)} / {non_finite(st32)} | {worst} |"
        f" {q[0]:.1e} / {q[1]:.1e} / {np.max(rel) if rel.size else np.nan:.1e} |"
    )


# (label, wheel, Wong–Reece) of the tyre and rut families.
TIRE_FAMILIES = (
    ("tyre, front region", "tire", False),
    ("tyre, Wong–Reece", "tire", True),
    ("rut, front region", "rut", False),
)


def _solve_chunks(wheel, terrain, dist, load, slip, n):
    """`solve_wheel` over `CHUNK`-sized pieces: NumPy fields and status."""
    parts = []
    for k in range(0, n, CHUNK):
        take = (
            lambda t, k=k: jax.tree_util.tree_map(  # noqa: E731
                lambda x: x[k : k + CHUNK] if np.ndim(x) else x, t
            )
        )
        st = sj.solve_wheel(
            take(wheel),
            sj.ContactModel(take(terrain), None if dist is None else take(dist)),
            load[k : k + CHUNK],
            slip[k : k + CHUNK],
        )
        parts.append({f: np.asarray(getattr(st, f)) for f in (*FIELDS, "status")})
    return {f: np.concatenate([p[f] for p in parts]) for f in parts[0]}


def tire_and_rut_family(kind, family, n, seed=17):
    """Statuses and checks of one tyre or rut family: a row of the third table.  The
    tyres are half soft (10 kPa-1 MPa, with flexing), half stiff (1e9 Pa), compared with
    the rim; the ruts a third each of zero depth, mid-depth and at the base."""
    label, what, wong_reece = family
    rng = np.random.default_rng(seed)
    unit, extra = rng.uniform(size=(UNIT_ROWS, n)), rng.uniform(size=(3, n))
    corner = rng.uniform(size=n) < 0.1
    states, rims = {}, {}
    for dtype in (np.float64, np.float32):
        rim, tires, terrain, dist, load, slip, ruts = tire_and_rut_inputs(
            kind, unit, extra, corner, dtype
        )
        dist = dist if wong_reece else None
        wheel, ground = (tires, terrain) if what == "tire" else (rim, ruts)
        states[dtype] = _solve_chunks(wheel, ground, dist, load, slip, n)
        if what == "tire":
            rims[dtype] = _solve_chunks(rim, terrain, dist, load, slip, n)
    st64, st32 = states[np.float64], states[np.float32]
    counts = [int(np.sum(st64["status"] == s)) for s in (0, 1, 4, 3, 2)]

    def non_finite(st):
        bad = np.zeros(n, bool)
        for f in FIELDS:
            bad |= ~np.isfinite(st[f])
        return int(np.sum(bad & (st["status"] != Status.INVALID_INPUT)))

    stiff = "—"
    if what == "tire":  # the stiff half against the rim: worst relative difference
        worst = []
        for dtype in (np.float64, np.float32):
            tire, rim = states[dtype], rims[dtype]
            half = slice(n // 2, None)
            same = tire["status"][half] == rim["status"][half]
            rel = [
                np.abs(tire[f][half] - rim[f][half])
                / np.maximum(np.abs(rim[f][half]), np.abs(rim["motion_resistance"][half]))
                for f in ("entry_angle", "sinkage", "motion_resistance", "thrust", "torque")
            ]
            worst.append(f"{np.nanmax(rel):.1e} ({int(np.sum(~same))} statuses differ)")
        stiff = " / ".join(worst)
    both = (st64["status"] == Status.CONVERGED) & (st32["status"] == Status.CONVERGED)
    rel = np.abs(st32["sinkage"][both] / st64["sinkage"][both] - 1)
    q = np.quantile(rel, [0.5, 0.999]) if rel.size else [np.nan, np.nan]
    return (
        f"| {kind} | {label} | {n:,} | {counts[0]:,} | {counts[1]:,} | {counts[2]:,} |"
        f" {counts[3]:,} | {counts[4]:,} | {non_finite(st64)} / {non_finite(st32)} | {stiff} |"
        f" {q[0]:.1e} / {q[1]:.1e} / {np.max(rel) if rel.size else np.nan:.1e} |"
    )


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", type=int, default=1_000_000, help="cases per shear model")
    parser.add_argument(
        "--terrain-cases", type=int, default=100_000, help="cases per any-terrain family"
    )
    add_no_docs(parser)
    args = parser.parse_args(argv)
    console = Console()
    n = args.cases
    lines = [
        f"{n:,} random in-range cases per shear model (slips -0.5 to 0.99), float64 and"
        " float32; balance = |W(theta0) / load - 1| at convergence.",
        "",
        "| shear | family | cases | converged | bottomed out | angle limit | not converged"
        " | NaN outside INVALID_INPUT (f64 / f32) | max balance | float32 sinkage error"
        " (median / 99.9 % / max) |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    costs, grads, refs = [], [], []
    for shear in track(SHEARS, description="robustness", console=console):
        wheel, snow, load, slip = in_range(n, seed=11)
        st64 = solve_in_chunks(wheel, snow, load, slip, shear)
        cast = lambda t: jax.tree_util.tree_map(lambda x: np.asarray(x, np.float32), t)  # noqa: E731
        st32 = solve_in_chunks(cast(wheel), cast(snow), cast(load), cast(slip), shear)
        bal = balance(wheel, snow, load, slip, st64["entry_angle"], shear)
        for family, mask in (("driving", slip >= 0), ("braking", slip < 0)):
            s64, s32 = st64["status"][mask], st32["status"][mask]
            counts = [int(np.sum(s64 == s)) for s in (0, 1, 2, 3)]

            def nan_outside(st, mask=mask):
                bad = np.zeros(mask.sum(), bool)
                for f in FIELDS:
                    bad |= ~np.isfinite(st[f][mask])
                return int(np.sum(bad & (st["status"][mask] != Status.INVALID_INPUT)))

            conv = s64 == Status.CONVERGED
            both = conv & (s32 == Status.CONVERGED)
            rel = np.abs(st32["sinkage"][mask][both] / st64["sinkage"][mask][both] - 1)
            q = np.quantile(rel, [0.5, 0.999]) if rel.size else [np.nan, np.nan]
            lines.append(
                f"| {shear} | {family} | {mask.sum():,} | {counts[0]:,} | {counts[1]:,} |"
                f" {counts[2]:,} | {counts[3]:,} | {nan_outside(st64)} / {nan_outside(st32)} |"
                f" {np.max(bal[mask][conv]):.1e} | {q[0]:.1e} / {q[1]:.1e} /"
                f" {np.max(rel) if rel.size else np.nan:.1e} |"
            )
        ratio, times = cost_ratio(min(n, 100_000), shear)
        costs.append(
            f"{shear}: {ratio:.2f} ({times['braking'] * 1e3:.0f} ms vs"
            f" {times['driving'] * 1e3:.0f} ms)"
        )
        if shear != "none":
            bad, total = gradient_check(10_000, shear)
            grads.append(f"{shear}: {bad} of {total:,}")
            worst_w, worst_z = scipy_check(100, shear)
            refs.append(f"{shear}: balance {worst_w:.1e}, sinkage {worst_z:.1e} m")
    lines += [
        "",
        f"* Braking / driving time per batch of {min(n, 100_000):,}: " + "; ".join(costs) + ".",
        "* Non-finite gradient entries (drawbar pull w.r.t. the five snow parameters, load"
        " and slip) over converged cases of 10,000: " + "; ".join(grads) + ".",
        "* Against SciPy (quad + brentq) on 100 cases: max |W_scipy(theta0) / load - 1| and"
        " max sinkage difference (driving; braking W can have several roots): "
        + "; ".join(refs)
        + ".",
    ]
    m = args.terrain_cases
    lines += [
        "",
        f"Any-terrain path: {m:,} random cases per family (`tests/random_cases.py`: slips"
        " -0.5 to 0.99, slip angles up to 60 degrees, a tenth resting on the base with the"
        " braking sign change at the axle), classic shear, float64 and float32 (Wong snow on"
        " the front region without a slip angle takes the first table's quadrature).",
        "",
        "| terrain | family | cases | converged | bottomed out | angle limit | not converged"
        " | invalid | non-finite outside INVALID_INPUT (f64 / f32) | max balance |"
        " float32 sinkage error (median / 99.9 % / max) |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    jobs = [(kind, family) for kind in KINDS for family in ANY_FAMILIES]
    for kind, family in track(jobs, description="any terrain", console=console):
        lines.append(any_terrain_family(kind, family, m))
    lines += [
        "",
        f"Deflecting tyres and ruts: {m:,} random cases per family (the any-terrain cases"
        " above; `tests/random_cases.py`): half the tyres soft (p_i 10 kPa-1 MPa, p_c and"
        " flexing), half stiff (1e9 Pa), the stiff ones compared with the rim; the ruts a"
        " third each of zero depth, of a random share of the base's depth and at the base"
        " (a leader that bottomed out), classic shear, float64 and float32.",
        "",
        "| terrain | family | cases | converged | bottomed out | angle limit | not converged"
        " | invalid | non-finite outside INVALID_INPUT (f64 / f32) | stiff tyre vs rim, worst"
        " relative difference (f64 / f32) | float32 sinkage error (median / 99.9 % / max) |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    jobs = [(kind, family) for kind in KINDS for family in TIRE_FAMILIES]
    for kind, family in track(jobs, description="tyres and ruts", console=console):
        lines.append(tire_and_rut_family(kind, family, m))
    lines += [
        "",
        f"* Measured with `python benchmarks/robustness.py --cases {n} --terrain-cases {m}`.",
    ]
    text = "\n".join(lines)
    console.print(text)
    if not args.no_docs:
        write_block("robustness", text)


if __name__ == "__main__":
    main()
