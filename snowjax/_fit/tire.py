"""Tire load-function fits: (3.17)–(3.21) of chapter 3 on the least-squares core.

`fit_tire_coefficients` fits the load functions to data shaped like the thesis's Table 3.2
(the thesis's units: kN, kN/rad); `thesis_tire_table` is that table.  The five load
functions are separate blocks of one least-squares problem: one solve, one estimate per
block (each with its own s² = SSE / (m − p)).

Equation numbers refer to Sankapalli (2004), *Predictive semi-empirical analysis for
tire/snow interaction*, MSc thesis, University of Alaska Fairbanks.
"""

from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import ArrayLike, Float

from .._tire.tire import (
    TireCoefficients,
    lateral_friction,
    lateral_stiffness,
    longitudinal_friction,
    longitudinal_stiffness,
)
from .core import (
    Estimate,
    FitResult,
    Solution,
    Transform,
    check_max_steps,
    estimate,
    fit_result,
    least_squares,
)
from .data import read_package_csv, rms, same_length, vector

__all__ = ["fit_tire_coefficients", "thesis_tire_table"]

# (data key, equation, coefficient names, quantity)
_TIRE_BLOCKS = (
    ("cs", "(3.17)", ("A4", "A5"), "C_s [kN/rad]"),
    ("ca", "(3.18)", ("B4", "B5"), "C_alpha [kN/rad]"),
    ("mux", "(3.19)", ("A1", "A2", "A3"), "mu_x [-]"),
    ("muy", "(3.20)", ("B1", "B2", "B3"), "mu_y [-]"),
    ("e1", "(3.21)", ("a1", "a2"), "E1 [-]"),
)
_TIRE_UNITS = {
    "A4": "rad", "A5": "rad/kN", "B4": "rad", "B5": "rad/kN",
    "A1": "-", "A2": "1/kN", "A3": "1/kN^2", "B1": "-", "B2": "1/kN", "B3": "1/kN^2",
    "a1": "kN^(-1/2)", "a2": "1/kN",
}  # fmt: skip


def thesis_tire_table() -> dict[str, np.ndarray]:
    """The thesis's FEA tire data, Table 3.2, **in the thesis's units**.

    FEA of a 0.736 m tire on fresh snow at four loads (thesis section 3.2), shipped as
    `snowjax/data/table_3_2.csv`.  These are the data the load functions (3.17)–(3.21)
    were fitted to (`fit_tire_coefficients`).

    **Returns:** a dict of NumPy arrays of length 4:

    - `load_kN`: normal load F_z [kN] (3.5, 4.5, 6.24, 7.5).
    - `cs`: longitudinal stiffness C_s [kN/rad].
    - `ca`: lateral stiffness C_α [kN/rad].
    - `mux`, `muy`: longitudinal and lateral friction coefficients [-].
    - `e1`: contact pressure constant E1 [-].
    """
    t = read_package_csv("table_3_2.csv")
    return {k: np.asarray(t[k], float) for k in ("load_kN", "cs", "ca", "mux", "muy", "e1")}


# ---------------------------------------------------------------------------------------
# The model: residual, start values
# ---------------------------------------------------------------------------------------


def _tire_block_model(key, theta, f_kn):
    """One load function at loads f_kn [kN], thesis units; reuses snowjax._tire."""
    load_n = f_kn * 1e3
    zero = jnp.zeros((), theta.dtype)
    if key in ("cs", "ca"):
        a, b = theta
        kw = dict(A1=zero, A2=zero, A3=zero, A4=a, A5=b, B1=zero, B2=zero, B3=zero,
                  B4=a, B5=b, a1=zero, a2=zero)  # fmt: skip
        fn = longitudinal_stiffness if key == "cs" else lateral_stiffness
        return fn(load_n, TireCoefficients(**kw)) / 1e3  # N/rad -> kN/rad
    if key in ("mux", "muy"):
        c1, c2, c3 = theta
        kw = dict(A1=c1, A2=c2, A3=c3, A4=zero, A5=zero, B1=c1, B2=c2, B3=c3,
                  B4=zero, B5=zero, a1=zero, a2=zero)  # fmt: skip
        fn = longitudinal_friction if key == "mux" else lateral_friction
        return fn(load_n, TireCoefficients(**kw))
    # (3.21) in q1 = a1², q2 = a2² (as contact_pressure_constant, without the sqrt):
    q1, q2 = theta
    return -0.5 * jnp.expm1(-q1 * f_kn - q2 * f_kn**2)


class _TireResidual(eqx.Module):
    """Stacked scaled residuals of the present load functions (separable blocks).

    θ = transform(u) = s u, one scale per coefficient; a coefficient held at its bound 0
    has scale 0.
    """

    keys: tuple = eqx.field(static=True)
    sizes: tuple = eqx.field(static=True)

    def __call__(self, u, args):
        f_kn, data, transform = args
        theta = transform(u)
        out, start = [], 0
        for key, size in zip(self.keys, self.sizes):
            th = theta[start : start + size]
            start += size
            out.append((_tire_block_model(key, th, f_kn) - data[key]) / data[key + "_scale"])
        return jnp.concatenate(out), None


def _tire_init(key, f, y):
    if key in ("cs", "ca"):  # F / C = A4 + A5 F
        a5, a4 = np.polyfit(f, f / y, 1)
        return np.array([a4, a5])
    if key in ("mux", "muy"):
        return np.polyfit(f, y, 2)[::-1].copy()
    # -ln(1 - 2 E1) = q1 F + q2 F²
    q, *_ = np.linalg.lstsq(np.stack([f, f**2], 1), -np.log1p(-2 * y), rcond=None)
    return q


def _tire_e1_np(q, f):
    """(3.21) in q = (a1², a2²), NumPy."""
    return -0.5 * np.expm1(-q[0] * f - q[1] * f**2)


def _unconstrained_q(f, e1, j):
    """Unconstrained least-squares a_j² of (3.21), linearised (for the warning text)."""
    q, *_ = np.linalg.lstsq(np.stack([f, f**2], 1), -np.log1p(-2 * e1), rcond=None)
    return float(q[j])


def _tire_data(load_kN, given) -> tuple[np.ndarray, list, dict[str, np.ndarray]]:
    """Checked loads [kN], the blocks of the quantities given, and their data."""
    f = vector("load_kN", load_kN)
    if (f <= 0).any():
        i = int(np.argmax(f <= 0))
        raise ValueError(f"load_kN must be > 0 kN; got {f[i]!r} at index {i}")
    blocks = [blk for blk in _TIRE_BLOCKS if given[blk[0]] is not None]
    if not blocks:
        raise ValueError("fit_tire_coefficients needs at least one of cs, ca, mux, muy, e1")
    data = {}
    for key, *_ in blocks:
        y = vector(key, given[key])
        same_length(load_kN=f, **{key: y})
        if key in ("cs", "ca") and (y <= 0).any():
            raise ValueError(f"{key} must be > 0 kN/rad; got {y[int(np.argmax(y <= 0))]!r}")
        if key == "e1" and ((y <= 0) | (y >= 0.5)).any():
            bad = y[int(np.argmax((y <= 0) | (y >= 0.5)))]
            raise ValueError(f"e1 must lie in (0, 0.5) (eq. 3.21); got {bad!r}")
        data[key] = y
    for key, _, names, _ in blocks:
        if f.size < len(names):
            raise ValueError(
                f"fitting {key} needs at least {len(names)} loads (it has {len(names)} "
                f"coefficients); got {f.size}"
            )
    return f, blocks, data


def _solve_with_bounds(residual, f, args_data, theta0, e1_start, max_steps):
    """Levenberg–Marquardt with the bounds a1², a2² >= 0 of (3.21) as an active set.

    A bound is held (scale 0) where the start or the optimum wants a_j² < 0, and released
    again where raising a_j² from 0 would lower the SSE (its KKT condition fails); at most
    three solves.  Returns the solution, its transform and the active mask.
    """
    active = np.ones_like(theta0)
    scales = np.where(np.abs(theta0) > 0, np.abs(theta0), 1.0)
    if e1_start is not None:
        for j in range(2):
            if theta0[e1_start + j] < 0:  # bound a_j² >= 0 active from the start
                active[e1_start + j] = 0.0
        if active[e1_start] == 0.0 and active[e1_start + 1] == 1.0:
            fe = f**2
            q2 = float(fe @ -np.log1p(-2 * args_data["e1"]) / (fe @ fe))
            theta0[e1_start + 1] = q2
            scales[e1_start + 1] = abs(q2) if q2 != 0 else 1.0
    attempt = 0
    while True:
        attempt += 1
        transform = Transform.make(np.zeros(theta0.size, bool), scale=scales * active)
        u0 = np.where(active > 0, theta0 / scales, 0.0)
        args = (f, args_data, transform)
        sol = least_squares(residual, u0, args, max_steps=max_steps, tol=1e-12)
        theta = transform.values(sol.u)
        if e1_start is None:
            break
        hit = [j for j in range(2) if active[e1_start + j] > 0 and theta[e1_start + j] < 0]
        # KKT check of a held bound: release it if raising a_j² from 0 lowers the SSE.
        q = np.maximum(theta[e1_start : e1_start + 2], 0.0)
        e1_res = _tire_e1_np(q, f) - args_data["e1"]
        dq = [f, f**2]
        release = [
            j for j in range(2)
            if active[e1_start + j] == 0 and float(e1_res @ (0.5 * dq[j] * np.exp(
                -q[0] * f - q[1] * f**2))) < 0
        ]  # fmt: skip
        if not hit and not release:
            break
        for j in hit:  # the optimum crossed the bound a_j² = 0: hold it there and refit
            active[e1_start + j] = 0.0
        theta0 = np.where(active > 0, theta, 0.0)
        for j in release:
            active[e1_start + j] = 1.0
            theta0[e1_start + j] = 1e-3 * max(abs(theta0[e1_start + 1 - j]), 1e-6)
            scales[e1_start + j] = abs(theta0[e1_start + j])
        if attempt == 3:  # at most three solves
            break
    return sol, transform, active


def _block_estimate(block, sol: Solution, transform: Transform, active, rows, cols, f, data):
    """Coefficients of one load function with their covariance and warnings."""
    key, eq, names, qty = block
    scale_row = float(data[key + "_scale"])
    r_b = sol.residual[rows] * scale_row
    act = active[cols] > 0
    j_b = sol.jacobian[rows, cols][:, act] * scale_row
    d = transform.jacobian(sol.u)[cols, cols][:, act]
    theta = transform.values(sol.u)[cols]
    notes = []
    if key == "e1":  # a_j = sqrt(a_j²), se(a) = se(a²) / (2 a)
        values = np.where(act, np.sqrt(np.maximum(theta, 0.0)), 0.0)
        k = np.cumsum(act) - 1
        d = np.zeros((len(names), int(act.sum())))
        for j, a in enumerate(values):
            if act[j]:
                s = float(transform.scale[cols][j])
                d[j, k[j]] = s / (2 * a) if a > 0 else np.inf
            else:
                q_free = _unconstrained_q(f, data["e1"], j)
                nm = names[j]
                notes.append(
                    f"{eq} E1: {nm} is degenerate: the data want {nm}^2 < 0 (a straight-"
                    f"line fit of -ln(1 - 2 E1) = a1^2 F + a2^2 F^2 gives {nm}^2 = "
                    f"{q_free:.3g}), so {nm} is held at its bound 0 and has no standard "
                    "error. (E1 depends on a1 only through a1^2; the thesis's "
                    "a1 = 7.5852e-9 is the same boundary optimum.)"
                )
    else:
        values = theta
    fitted = [nm for nm, a in zip(names, act) if a]
    part = estimate(
        j_b,
        r_b,
        names,
        values,
        d,
        fitted=fitted,
        held=~act,
        prefix=f"{eq} {qty.split()[0]}",
        notes=notes,
    )
    return part, r_b


# ---------------------------------------------------------------------------------------
# The fit
# ---------------------------------------------------------------------------------------


def fit_tire_coefficients(
    load_kN: Float[ArrayLike, " m"],
    cs: Float[ArrayLike, " m"] | None,
    ca: Float[ArrayLike, " m"] | None,
    mux: Float[ArrayLike, " m"] | None,
    muy: Float[ArrayLike, " m"] | None,
    e1: Float[ArrayLike, " m"] | None,
    *,
    max_steps: int = 200,
) -> FitResult:
    """Fit the tire load functions (3.17)–(3.21) to FEA or test data like Table 3.2.

    **Units: the thesis's** (its coefficients are defined for them): `load_kN` F_z [kN],
    `cs`, `ca` [kN/rad].  The functions fitted, each by least squares on its own
    quantity (the problem is separable; one Levenberg–Marquardt solve on the stacked,
    per-quantity-scaled residuals gives the same optimum as five separate fits):

    - (3.17) `C_s = F_z / (A4 + A5 F_z)`, (3.18) `C_α = F_z / (B4 + B5 F_z)`;
    - (3.19) `μ_x = A1 + A2 F_z + A3 F_z²`, (3.20) `μ_y = B1 + B2 F_z + B3 F_z²`;
    - (3.21) `E1 = 0.5 [1 − exp(−a1² F_z − a2² F_z²)]`, fitted in (a1², a2²) ≥ 0.  When
      the least-squares optimum wants a1² < 0 (Table 3.2 does), a1 is held at its bound
      0, reported with a `nan` standard error and a warning; the thesis's a1 = 7.6e-9 is
      the same boundary optimum.  Standard errors of a1, a2 follow from those of a1², a2²
      by the delta method, se(a) = se(a²) / (2a).

    Returns the coefficients under the thesis's names and units (A4 [rad], A5 [rad/kN],
    A1 [-], A2 [1/kN], A3 [1/kN²], likewise B1…B5, a1 [kN^(-1/2)], a2 [1/kN]), so
    `snowjax.TireCoefficients(**result.params)` builds the load functions from a full fit.

    **Arguments:** `load_kN` [kN] (> 0); `cs`, `ca` [kN/rad] (> 0); `mux`, `muy` [-];
    `e1` [-] in (0, 0.5); any of the five quantities may be `None` to skip its fit.
    Every array has the length of `load_kN` and is finite (and well below 1e154 in
    magnitude: larger values overflow the fit's float64 arithmetic).  `max_steps`:
    Levenberg–Marquardt step limit (an integer >= 1).

    **Raises:** `ValueError` for data out of these ranges, too few loads for a load
    function, or a fit that ends without a finite SSE.

    **Returns:** a `FitResult`; `residuals` are model − data in the data's units, stacked
    in the order C_s, C_α, μ_x, μ_y, E1 (present ones); standard errors and warnings
    (|correlation| > 0.95, standard error > |value|, a coefficient at its bound, no
    degrees of freedom) are per load function, each with its own s² = SSE / (m − p).
    """
    max_steps = check_max_steps(max_steps)
    given = {"cs": cs, "ca": ca, "mux": mux, "muy": muy, "e1": e1}
    f, blocks, data = _tire_data(load_kN, given)
    keys = tuple(b[0] for b in blocks)
    sizes = tuple(len(b[2]) for b in blocks)
    theta0 = np.concatenate([_tire_init(k, f, data[k]) for k in keys])
    e1_start = sum(sizes[:-1]) if keys[-1] == "e1" else None
    args_data = dict(data)
    for k in keys:
        args_data[k + "_scale"] = np.asarray(rms(data[k]))
    residual = _TireResidual(keys=keys, sizes=sizes)
    sol, transform, active = _solve_with_bounds(residual, f, args_data, theta0, e1_start, max_steps)

    n = f.size
    parts: list[Estimate] = []
    residuals: list[np.ndarray] = []
    row = col = 0
    for block, size in zip(blocks, sizes):
        rows, cols = slice(row, row + n), slice(col, col + size)
        part, r_b = _block_estimate(block, sol, transform, active, rows, cols, f, args_data)
        parts.append(part)
        residuals.append(r_b)
        row += n
        col += size
    return fit_result(
        sol,
        parts,
        residuals=np.concatenate(residuals),
        warnings=sol.warnings,
        units=_TIRE_UNITS,
        info={
            "title": f"Tire load functions (3.17)-(3.21), {n} loads (thesis units: kN, kN/rad)",
            "equation": "(3.17)-(3.21)",
            "sse_by_quantity": {k: float(np.sum(r**2)) for k, r in zip(keys, residuals)},
            "sse_unit": "(summed over mixed units; per quantity: info['sse_by_quantity'])",
            "dof_by_quantity": {k: part.dof for k, part in zip(keys, parts)},
        },
    )
