"""The simulator accuracy setting, `ContactModel(accuracy="simulator")`: its error against
SciPy and against the reference accuracy over random cases of every law, and the speed it
buys.

    python benchmarks/accuracy.py            # ~5 min on 2 cores
    python benchmarks/accuracy.py --quick    # fewer cases
    python benchmarks/accuracy.py --no-docs

Families: every terrain law (Wong snow, Bekker, Reece, layered snow) x the front region
and Wong–Reece x running straight and at a slip angle, each from `tests/random_cases.py`
(the property tests' ranges: D 0.5-1.5 m, loads 0.1-20 kN, slips -0.5 to 0.99, slip
angles up to 60 degrees; about a third of the cases brake, so every batch takes the
braking layout).  Per family and output:

- against SciPy (`tests/reference_terrain.py` straight, `tests/test_lateral.py`'s
  reference at a slip angle, adaptive quadrature and brentq; not layered snow at a slip
  angle, which that reference does not have): the worst and the median error of the
  simulator setting over the first `--scipy-cases` cases that converge;
- against the reference accuracy (itself within 1e-7 of SciPy): the worst error over
  `--cases` cases;
- the time of a batch of `--cases` at the reference accuracy over the simulator's (best
  of three, same process).

Errors: the sinkage relative to its value; R, T and F_y relative to the load; M and M_z
relative to load x r.  Writes the table between `<!-- accuracy:start -->` and
`<!-- accuracy:end -->` in docs/guide/performance.md.
"""

from __future__ import annotations

import argparse
import math
import pathlib
import sys
import warnings

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # tests/: the random cases and the SciPy references
sys.path.insert(0, str(ROOT / "benchmarks"))

import jax  # noqa: E402

jax.config.update("jax_enable_x64", True)
import numpy as np  # noqa: E402
from doc_block import add_no_docs, write_block  # noqa: E402
from rich.console import Console  # noqa: E402
from rich.progress import track  # noqa: E402
from rich.table import Table  # noqa: E402
from run import best_time, machine  # noqa: E402
from scipy import integrate, optimize  # noqa: E402

import snowjax as sj  # noqa: E402
from snowjax import Status  # noqa: E402
from tests import reference_terrain as ref  # noqa: E402
from tests.random_cases import KINDS, UNIT_ROWS, any_terrain_inputs  # noqa: E402
from tests.test_lateral import _reference_contact  # noqa: E402

OUTPUTS = ("sinkage", "motion_resistance", "thrust", "torque", "lateral_force", "aligning_torque")
LABELS = ("z0", "R", "T", "M", "F_y", "M_z")


def _scales(st, load, radius):
    """The error scale of each output: |z0|, the load, load x r."""
    moment = load * radius
    return (np.abs(st["sinkage"]), load, load, moment, load, moment)


def _solve(wheel, terrain, dist, lateral, load, slip, beta, accuracy):
    model = sj.ContactModel(terrain, distribution=dist, lateral=lateral, accuracy=accuracy)
    st = sj.solve_wheel(wheel, model, load, slip, slip_angle=beta)
    return {f: np.asarray(getattr(st, f)) for f in (*OUTPUTS, "entry_angle", "status")}


def _law(kind, terrain, k):
    """(reference law of (z, b), failure sinkage or None, lower layer's strength or None,
    depth) of case k."""
    v = lambda x: float(np.asarray(x)[k])  # noqa: E731
    if kind == "wong":
        return ref.wong(v(terrain.p_w), v(terrain.z_w)), None, None, v(terrain.z_w)
    if kind == "bekker":
        return ref.bekker(v(terrain.n), v(terrain.k_c), v(terrain.k_phi)), None, None, math.inf
    if kind == "reece":
        law = ref.reece(
            v(terrain.n), v(terrain.k_c_prime), v(terrain.k_phi_prime), v(terrain.unit_weight),
            v(terrain.cohesion),
        )  # fmt: skip
        return law, None, None, math.inf
    top, bottom = terrain.top, terrain.bottom
    law, z_f = ref.layered(
        v(top.p_w), v(top.z_w), v(bottom.p_w), v(bottom.z_w), v(terrain.ice_failure_pressure)
    )
    lower = (v(bottom.cohesion), v(bottom.tan_phi), v(bottom.shear_modulus))
    return law, z_f, lower, v(bottom.z_w)


def _strength(kind, terrain, k):
    layer = terrain.top if kind == "layered" else terrain
    return tuple(
        float(np.asarray(x)[k]) for x in (layer.cohesion, layer.tan_phi, layer.shear_modulus)
    )


def _scipy_case(kind, wheel, terrain, dist, lateral, load, slip, beta, k, wong_reece):
    """(z0, R, T, M, F_y, M_z) of case k by SciPy (F_y = M_z = 0 running straight)."""
    v = lambda x: float(np.asarray(x)[k])  # noqa: E731
    d, b, ld, i = v(wheel.diameter), v(wheel.width), v(load), v(slip)
    law, z_f, lower, depth = _law(kind, terrain, k)
    c, tan_phi, modulus = _strength(kind, terrain, k)
    fm, fr = (v(dist.c1) + v(dist.c2) * i, v(dist.c3)) if wong_reece else (0.0, 0.0)
    if beta is None:
        theta0, (w, r, t, m) = ref.solve(
            ld, i, d, b, law, c, tan_phi, modulus, fm, fr, z_f=z_f, lower=lower, depth=depth,
            shallowest=kind == "layered",
        )  # fmt: skip
        fy = mz = 0.0
    else:
        angle = v(beta)
        theta_max = math.radians(85.0)
        if math.isfinite(depth) and 2 * depth / d < 2:
            theta_max = min(theta_max, math.acos(1 - 2 * depth / d) * (1 - 1e-9))
        args = (
            i, angle, d, b, lambda z: law(z, b), c, tan_phi, modulus,
            v(lateral.shear_modulus), fm, fr, v(lateral.unit_weight), False,
        )  # fmt: skip
        vertical = lambda th: _vertical(th, args) - ld  # noqa: E731
        theta0 = optimize.brentq(vertical, 1e-4, theta_max, xtol=1e-15, rtol=1e-14)
        w, r, t, m, fy, mz = _reference_contact(theta0, *args)
    return np.array([d / 2 * (1 - math.cos(theta0)), r, t, m, fy, mz])


def _vertical(theta0, args):
    return _reference_contact(theta0, *args)[0]


def family(kind, wong_reece, steered, n, n_scipy, seed):
    """(errors against the reference accuracy (cases, outputs), against SciPy (SciPy
    cases, outputs) or None, reference / simulator time, converged cases)."""
    rng = np.random.default_rng(seed)
    unit = rng.uniform(size=(UNIT_ROWS, n))
    wheel, terrain, dist, lateral, load, slip, beta = any_terrain_inputs(
        kind, unit, np.zeros(n, bool), np.float64
    )
    dist = dist if wong_reece else None
    beta = beta if steered else None
    args = (wheel, terrain, dist, lateral, load, slip, beta)
    ref_st = _solve(*args, "reference")
    sim_st = _solve(*args, "simulator")
    load_np, radius = np.asarray(load), np.asarray(wheel.diameter) / 2
    both = (ref_st["status"] == Status.CONVERGED) & (sim_st["status"] == Status.CONVERGED)
    scales = _scales(ref_st, load_np, radius)
    vs_reference = np.stack(
        [np.abs(sim_st[f] - ref_st[f])[both] / s[both] for f, s in zip(OUTPUTS, scales)], 1
    )
    times = []
    for accuracy in ("reference", "simulator"):
        run = lambda a=accuracy: _solve(*args, a)  # noqa: E731
        run()  # compiled
        times.append(best_time(run, 3))
    scipy_errors = []
    if not (steered and kind == "layered"):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", integrate.IntegrationWarning)
            for k in np.flatnonzero(both)[:n_scipy]:
                exact = _scipy_case(
                    kind, wheel, terrain, dist, lateral, load, slip, beta, k, wong_reece
                )
                got = np.array([sim_st[f][k] for f in OUTPUTS])
                scale = np.array([abs(exact[0]), *(s[k] for s in scales[1:])])
                scipy_errors.append(np.abs(got - exact) / scale)
    errors = np.array(scipy_errors) if scipy_errors else None
    return vs_reference, errors, times[0] / times[1], int(both.sum())


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="1,000 cases, 4 against SciPy")
    parser.add_argument("--cases", type=int, default=None, help="cases per family (10,000)")
    parser.add_argument("--scipy-cases", type=int, default=None, help="SciPy cases per family (12)")
    add_no_docs(parser)
    args = parser.parse_args(argv)
    n = args.cases or (1_000 if args.quick else 10_000)
    n_scipy = args.scipy_cases or (4 if args.quick else 12)
    families = [
        (kind, wr, steered) for kind in KINDS for wr in (False, True) for steered in (False, True)
    ]
    rows = []
    for seed, (kind, wr, steered) in enumerate(track(families, description="families")):
        vs_ref, errors, speedup, converged = family(kind, wr, steered, n, n_scipy, seed)
        name = f"{kind}, {'Wong-Reece' if wr else 'front region'}, " + (
            "slip angle" if steered else "straight"
        )
        cells = []
        for j in range(len(OUTPUTS)):
            if not steered and j >= 4:
                cells.append("-")
                continue
            sci = (
                "-"
                if errors is None
                else f"{errors[:, j].max():.0e} / {np.median(errors[:, j]):.0e}"
            )
            cells.append(f"{sci}; {vs_ref[:, j].max():.0e} / {np.median(vs_ref[:, j]):.0e}")
        k = 0 if errors is None else errors.shape[0]
        rows.append((name, *cells, f"{speedup:.2f}x", f"{k} / {converged:,}"))
    header = ("family", *LABELS, "reference / simulator time", "SciPy / reference cases")
    console = Console(width=200)
    table = Table(title="simulator accuracy")
    for h in header:
        table.add_column(h)
    for row in rows:
        table.add_row(*row)
    console.print(table)
    text = "\n".join(
        [
            f"Measured on: {machine()}, with `python benchmarks/accuracy.py` "
            f"({n:,} random cases per family, float64).",
            "",
            "Each cell: the simulator setting's worst / median error against SciPy over the "
            "SciPy cases; then its worst / median error against the reference accuracy over "
            "all the cases that converged at both. z0 relative to itself, R, T, F_y to the "
            "load, M, M_z to load x r.",
            "",
            "| " + " | ".join(header) + " |",
            "|" + "---|" * len(header),
            *("| " + " | ".join(row) + " |" for row in rows),
        ]
    )
    if not args.no_docs:
        path = write_block("accuracy", text)
        console.print(f"wrote {path}")


if __name__ == "__main__":
    main()
