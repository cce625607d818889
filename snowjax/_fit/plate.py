"""Plate-sinkage fits: Bekker (2.1), Wong (2.3) or Reece (2.4) on the least-squares core.

`fit_plate_sinkage` fits a pressure–sinkage law to plate-sinkage data (SI: m, Pa).  A plate
fit becomes a terrain the wheel can use: `FitResult.bekker_soil(...)` (Bekker law) and
`FitResult.wong_snow(...)` (Wong law) add the shear strength the plate test does not
measure.  `thesis_plate_test` is the thesis's laboratory test (Table 2.1).

Equation numbers refer to Sankapalli (2004), *Predictive semi-empirical analysis for
tire/snow interaction*, MSc thesis, University of Alaska Fairbanks.
"""

from __future__ import annotations

import math
from typing import Any

import equinox as eqx
import numpy as np
from jaxtyping import ArrayLike, Float

from .._terrain.bekker import BekkerSoil, bekker_pressure
from .._terrain.reece import reece_pressure
from .._terrain.wong import WongSnow, wong_pressure
from .core import (
    FitResult,
    Transform,
    check_max_steps,
    estimate,
    fit_result,
    least_squares,
)
from .data import read_package_csv, rms, same_length, vector

__all__ = ["fit_plate_sinkage", "thesis_plate_test", "THESIS_PLATE_DIAMETER", "PLATE_LAWS"]

PLATE_LAWS = ("bekker", "wong", "reece")

# The plate of the thesis's laboratory test (Table 2.1): 23 cm diameter, circular.
THESIS_PLATE_DIAMETER = 0.23  # [m]


def thesis_plate_test() -> dict[str, np.ndarray]:
    """The thesis's laboratory plate-sinkage test, Table 2.1, in SI units.

    Shoop's test (thesis section 2.1.1): a 23 cm diameter rigid circular plate pushed into
    a 60 × 60 × 50 cm block of snow of about 200 kg/m³; 20 points digitised from the
    test curve.  The table is shipped as `snowjax/data/table_2_1.csv` in the thesis's
    units (m, N, kPa).

    **Plate dimension b.**  Bekker's b in (2.1) is "the smaller dimension of the contact
    patch" — for a circular plate usually its radius.  The thesis, however, used the
    *diameter*, b = 0.23 m: its published constants give k_c/b + k_φ = 3.43/0.23 +
    218.84215 = 233.7552 kN/m^(n+2), which is the least-squares combined modulus of this
    table (233.7552 kN/m^(n+2), with n = 1.0707148, as published, to 7 digits); with
    b = 0.115 m they would give 248.67.  `plate_size` is therefore 0.23 m here.
    (A single plate size determines only k_c/b + k_φ; see `fit_plate_sinkage`.)

    **Returns:** a dict of NumPy arrays, one entry per row:

    - `sinkage`: z [m].
    - `pressure`: the published pressure column [Pa] (kPa × 1000) — what the thesis fitted.
    - `load`: the published load column [N] (= pressure × π 0.115² m², except row 6, whose
      printed pressure 13.342 kPa is 1.8 % above its load / area = 13.112 kPa).
    - `plate_size`: b = 0.23 m, the plate diameter, for every row [m].
    """
    t = read_package_csv("table_2_1.csv")
    z = np.asarray(t["sinkage_m"], float)
    return {
        "sinkage": z,
        "pressure": np.asarray(t["pressure_kPa"], float) * 1e3,
        "load": np.asarray(t["load_N"], float),
        "plate_size": np.full_like(z, THESIS_PLATE_DIAMETER),
    }


# ---------------------------------------------------------------------------------------
# The model: residual, start values, names
# ---------------------------------------------------------------------------------------


class _PlateResidual(eqx.Module):
    """Residual (model − data) / pressure scale of a plate law, fitted variables u.

    θ = transform(u): Wong (p_w, z_w); one plate size (k_eq, n); two or more sizes
    (k_c, k_φ, n) for Bekker and (c k'_c, γ_s k'_φ, n) for Reece.
    """

    law: str = eqx.field(static=True)
    multi: bool = eqx.field(static=True)

    def __call__(self, u, args):
        z, p, b, pscale, transform = args
        theta = transform(u)
        return (_plate_pressure(self.law, self.multi, theta, z, b) - p) / pscale, None


def _plate_pressure(law, multi, theta, z, b):
    """Pressure [Pa] at sinkage z [m] and plate size b [m] of the law with parameters θ."""
    if law == "wong":
        return wong_pressure(z, theta[0], theta[1])
    if law == "bekker":
        if multi:  # (2.1): (k_c / b + k_phi) z^n
            return bekker_pressure(z, b, theta[0], theta[1], theta[2])
        return bekker_pressure(z, 1.0, 0.0, theta[0], theta[1])  # k_eq z^n
    # Reece (2.4): (c k'_c + gamma_s b k'_phi)(z / b)^n with c k'_c, gamma_s k'_phi fitted.
    if multi:
        return reece_pressure(z, b, 1.0, 1.0, theta[0], theta[1], theta[2])
    return reece_pressure(z, b, 1.0, 0.0, theta[0], 0.0, theta[1])  # k_eq (z / b)^n


def _loglog_init(z, p, b, law, sizes):
    """Start values from straight lines in log–log coordinates (one intercept per size)."""
    pos = (z > 0) & (p > 0)
    if pos.sum() < 2:
        raise ValueError(
            "fit_plate_sinkage needs at least two points with sinkage > 0 and pressure > 0"
        )
    x = np.log(z[pos] / b[pos]) if law == "reece" else np.log(z[pos])
    cols = [x] + [(b[pos] == s).astype(float) for s in sizes]
    a = np.stack(cols, axis=1)
    coef, *_ = np.linalg.lstsq(a, np.log(p[pos]), rcond=None)
    n0 = float(coef[0])
    moduli = np.exp(coef[1:])  # combined modulus at each plate size
    return n0, moduli


def _wong_start(z, p) -> tuple[np.ndarray, Transform]:
    """p_w = e^u0, z_w = z_max (1 + e^u1) > z_max; start from a scan of z_w."""
    zmax = float(z.max())
    if not zmax > 0:
        raise ValueError("the Wong fit needs some sinkage > 0")
    # Scan z_w = z_max (1 + g); p_w is linear given z_w.
    best = None
    for g in np.geomspace(1e-3, 1e2, 400):
        x = -np.log1p(-z / (zmax * (1 + g)))
        pw = float(x @ p / (x @ x))
        sse = float(np.sum((pw * x - p) ** 2))
        if pw > 0 and (best is None or sse < best[0]):
            best = (sse, pw, g)
    if best is None:
        raise ValueError("the Wong law cannot fit these data (no positive p_w)")
    u0 = np.array([np.log(best[1]), np.log(best[2])])
    return u0, Transform.make([True, True], shift=[0.0, 1.0], scale=[1.0, zmax])


def _modulus_start(z, p, b, law, sizes, multi) -> tuple[np.ndarray, Transform]:
    """Bekker / Reece: (ln k_eq, n) for one plate size, scaled (A, B, n) for several."""
    n0, moduli = _loglog_init(z, p, b, law, sizes)
    if not multi:
        return np.array([np.log(moduli[0]), n0]), Transform.make([True, False])
    # Combined modulus k_j = A g(b_j) + B: Bekker g = 1/b, Reece k = A + B b.
    g = 1.0 / sizes if law == "bekker" else sizes
    a_mat = (
        np.stack([g, np.ones_like(g)], 1) if law == "bekker" else np.stack([np.ones_like(g), g], 1)
    )
    ab, *_ = np.linalg.lstsq(a_mat, moduli, rcond=None)
    kscale = float(np.mean(moduli))
    if law == "bekker":  # theta = (k_c, k_phi): k_c / b ~ kscale u0
        consts = np.array([kscale / np.mean(1 / sizes), kscale])
    else:  # theta = (c k'_c, gamma k'_phi): gamma k'_phi b ~ kscale u1
        consts = np.array([kscale, kscale / np.mean(sizes)])
    u0 = np.array([ab[0] / consts[0], ab[1] / consts[1], n0])
    return u0, Transform.make([False] * 3, scale=[consts[0], consts[1], 1.0])


def _modulus_names(law, multi, sizes) -> tuple[list[str], dict[str, str], list[str]]:
    """Names, units and the single-plate-size warning of a Bekker / Reece fit."""
    if not multi:
        if law == "bekker":
            units = {"k_eq": "N/m^(n+2)", "n": "-"}
            combo, parts = "k_eq = k_c/b + k_phi", "k_c and k_phi"
        else:
            units = {"k_eq": "Pa", "n": "-"}
            combo, parts = "k_eq = c k'_c + gamma_s b k'_phi", "k'_c and k'_phi"
        warning = (
            f"{parts} are not identifiable from a single plate size (b = {sizes[0]:g} m): "
            f"only the combined modulus {combo} is determined, so only k_eq and n are "
            "returned. Test two or more plate sizes to separate them."
        )
        return ["k_eq", "n"], units, [warning]
    if law == "bekker":
        units = {"k_c": "N/m^(n+1)", "k_phi": "N/m^(n+2)", "n": "-", "k_eq": "N/m^(n+2)"}
        return ["k_c", "k_phi", "n"], units, []
    units = {
        "cohesion_k_c_prime": "Pa",
        "unit_weight_k_phi_prime": "N/m^3",
        "n": "-",
        "k_eq": "Pa",
        "k_c_prime": "-",
        "k_phi_prime": "-",
    }
    return ["cohesion_k_c_prime", "unit_weight_k_phi_prime", "n"], units, []


def _positive(name: str, value, unit: str) -> float:
    x = float(value)
    if not (math.isfinite(x) and x > 0):
        raise ValueError(f"{name} must be finite and > 0 {unit}, got {value!r}")
    return x


def _derived(law, theta, d, b_ref, cohesion, unit_weight):
    """Derived parameters of a several-size fit: names, values and rows of D = ∂θ/∂u.

    k_eq at the smallest plate b_ref; for Reece also k'_c = c k'_c / c and
    k'_φ = γ_s k'_φ / γ_s when c and γ_s are given.
    """
    if law == "bekker":  # k_eq = k_c / b_ref + k_phi
        return ["k_eq"], [theta[0] / b_ref + theta[1]], [d[0] / b_ref + d[1]]
    # k_eq = c k'_c + gamma k'_phi b_ref; k'_c = A / c; k'_phi = B / gamma
    names, values, rows = ["k_eq"], [theta[0] + theta[1] * b_ref], [d[0] + d[1] * b_ref]
    if cohesion is not None:
        c = _positive("cohesion", cohesion, "Pa")
        names.append("k_c_prime")
        values.append(theta[0] / c)
        rows.append(d[0] / c)
    if unit_weight is not None:
        gam = _positive("unit_weight", unit_weight, "N/m^3")
        names.append("k_phi_prime")
        values.append(theta[1] / gam)
        rows.append(d[1] / gam)
    return names, values, rows


# ---------------------------------------------------------------------------------------
# The fit
# ---------------------------------------------------------------------------------------


def fit_plate_sinkage(
    sinkage: Float[ArrayLike, " m"],
    pressure: Float[ArrayLike, " m"],
    law: str = "bekker",
    plate_size: Float[ArrayLike, " m"] | float | None = None,
    *,
    cohesion: float | None = None,
    unit_weight: float | None = None,
    max_steps: int = 200,
) -> FitResult:
    """Fit a pressure–sinkage law to plate-sinkage data by least squares on pressure.

    Minimises Σ (p_model(z_i) − p_i)² (residuals in Pa) with
    `optimistix.LevenbergMarquardt`; start values come from straight-line fits in log–log
    coordinates (Bekker, Reece) or a one-dimensional scan of z_w (Wong).

    **Laws and what a data set determines:**

    - `"bekker"`, eq. (2.1), `p = (k_c / b + k_φ) zⁿ`.  From **one plate size** only the
      combined modulus `k_eq = k_c / b + k_φ` [N/m^(n+2)] and `n` are identifiable: the
      result holds `k_eq`, `n` and a warning saying so (no arbitrary split is returned).
      With **two or more sizes** it holds `k_c` [N/m^(n+1)], `k_phi` [N/m^(n+2)], `n`, and
      `k_eq` evaluated at the smallest plate (`info["b_ref"]`).  Fitted variables:
      (ln k_eq, n) or (k_c, k_φ, n) (scaled).
    - `"reece"`, eq. (2.4), `p = (c k'_c + γ_s b k'_φ)(z / b)ⁿ`.  One size: `k_eq` =
      c k'_c + γ_s b k'_φ [Pa] and `n`, with the same warning.  Two or more sizes:
      `cohesion_k_c_prime` = c k'_c [Pa], `unit_weight_k_phi_prime` = γ_s k'_φ [N/m³],
      `n`, `k_eq` at the smallest plate, and — if `cohesion` c [Pa] / `unit_weight` γ_s
      [N/m³] are given — the dimensionless `k_c_prime`, `k_phi_prime`.
    - `"wong"`, eq. (2.3), `p = −p_w ln(1 − z / z_w)`: `p_w` [Pa] and `z_w` [m]; fitted as
      ln p_w and ln(z_w / z_max − 1), which keeps p_w > 0 and z_w above the deepest
      sinkage (where the law is finite).  `plate_size` is not used.

    **Arguments:**

    - `sinkage`: z [m], ≥ 0, one per measurement.
    - `pressure`: p [Pa], same length.
    - `law`: `"bekker"`, `"wong"` or `"reece"`.
    - `plate_size`: b [m], the plate's smaller dimension as used in (2.1)/(2.4) — a
      scalar or one value per measurement (required for Bekker and Reece).  Be explicit
      about the convention: the thesis used the 0.23 m plate *diameter* for Table 2.1
      (`thesis_plate_test`), while Bekker's convention for circular plates is the radius.
    - `cohesion`, `unit_weight`: optional c [Pa] and γ_s [N/m³] for Reece's k'_c, k'_φ
      (only with `law="reece"` and two or more plate sizes).
    - `max_steps`: Levenberg–Marquardt step limit (an integer >= 1).

    **Returns:** a `FitResult` (residuals in Pa, SSE in Pa²).  For the wheel:
    `result.bekker_soil(cohesion, tan_phi, shear_modulus=...)` (Bekker; with one plate
    size the split of k_eq is an assumption, see `FitResult.bekker_soil`) and
    `result.wong_snow(...)` (Wong) return the terrain `solve_wheel` takes.

    **Raises:** `ValueError` for an unknown law, unequal lengths, non-finite values or
    values too large for float64 arithmetic (|x| near 1e154 and above), negative
    sinkage, non-positive plate sizes, too few points (more than the number of
    parameters are needed), `cohesion` / `unit_weight` where they do not apply, or a fit
    that ends without a finite SSE.
    """
    if law not in PLATE_LAWS:
        raise ValueError(f"law must be one of {PLATE_LAWS}, got {law!r}")
    max_steps = check_max_steps(max_steps)
    reece_only = [
        nm for nm, v in (("cohesion", cohesion), ("unit_weight", unit_weight)) if v is not None
    ]
    if reece_only and law != "reece":
        raise ValueError(
            f"{' and '.join(reece_only)} only {'applies' if len(reece_only) == 1 else 'apply'}"
            f" to law='reece' (for its k'_c, k'_phi); got law={law!r}"
        )
    z = vector("sinkage", sinkage)
    p = vector("pressure", pressure)
    m = same_length(sinkage=z, pressure=p)
    if (z < 0).any():
        i = int(np.argmax(z < 0))
        raise ValueError(f"sinkage must be >= 0 m; got {z[i]!r} at index {i}")
    if law == "wong":
        b = np.ones_like(z)
        sizes = np.array([1.0])
    else:
        if plate_size is None:
            raise ValueError(f"law={law!r} needs plate_size (b [m]), a scalar or one per point")
        b = vector("plate_size", plate_size)
        if b.size == 1:
            b = np.full_like(z, b[0])
        same_length(sinkage=z, plate_size=b)
        if (b <= 0).any():
            i = int(np.argmax(b <= 0))
            raise ValueError(f"plate_size must be > 0 m; got {b[i]!r} at index {i}")
        sizes = np.unique(b)
    multi = law != "wong" and sizes.size >= 2
    if reece_only and not multi:
        raise ValueError(
            f"{' and '.join(reece_only)} give Reece's k'_c, k'_phi, which need two or more "
            f"plate sizes; the data have one (b = {sizes[0]:g} m)"
        )
    n_params = 3 if multi else 2
    if m <= n_params:
        raise ValueError(
            f"fit_plate_sinkage({law!r}) fits {n_params} parameters and needs more than "
            f"{n_params} points; got {m}"
        )
    pscale = rms(p)
    if not pscale > 0:
        raise ValueError("pressure must not be all zero")

    info: dict[str, Any] = {"law": law, "sse_unit": "Pa^2"}
    if law == "wong":
        u0, transform = _wong_start(z, p)
        names, units, notes = ["p_w", "z_w"], {"p_w": "Pa", "z_w": "m"}, []
        info.update(equation="(2.3)", title=f"Wong pressure-sinkage law (2.3), {m} points")
    else:
        u0, transform = _modulus_start(z, p, b, law, sizes, multi)
        names, units, notes = _modulus_names(law, multi, sizes)
        eq = "(2.1)" if law == "bekker" else "(2.4)"
        kind = "Bekker" if law == "bekker" else "Reece"
        sizes_txt = ", ".join(f"{s:g}" for s in sizes)
        info.update(
            equation=eq,
            plate_sizes=[float(s) for s in sizes],
            title=f"{kind} pressure-sinkage law {eq}, {m} points, plate size b = {sizes_txt} m",
        )

    residual = _PlateResidual(law=law, multi=bool(multi))
    args = (z, p, b, np.asarray(pscale), transform)
    sol = least_squares(residual, u0, args, max_steps=max_steps, tol=1e-12)
    fitted = list(names)
    theta = list(transform.values(sol.u))
    d = transform.jacobian(sol.u)
    if multi:
        b_ref = float(sizes.min())
        info["b_ref"] = b_ref
        more, values, rows = _derived(law, theta, d, b_ref, cohesion, unit_weight)
        names, theta = names + more, theta + values
        d = np.vstack([d] + [np.atleast_2d(rw) for rw in rows])
    r_pa = sol.residual * pscale
    part = estimate(sol.jacobian * pscale, r_pa, names, theta, d, fitted=fitted)
    return fit_result(
        sol, [part], residuals=r_pa, warnings=[*notes, *sol.warnings], units=units, info=info
    )


# ---------------------------------------------------------------------------------------
# Plate fit -> terrain (the methods `FitResult.bekker_soil` / `FitResult.wong_snow`)
# ---------------------------------------------------------------------------------------


def _shear_strength(cohesion, tan_phi, shear_modulus) -> tuple[float, float, float]:
    """(c [Pa] >= 0, tan φ [-] >= 0, K [m] > 0) as floats, or a ValueError."""
    values = []
    for name, v, ok, allowed in (
        ("cohesion", cohesion, lambda x: x >= 0, ">= 0 Pa"),
        ("tan_phi", tan_phi, lambda x: x >= 0, ">= 0"),
        ("shear_modulus", shear_modulus, lambda x: x > 0, "> 0 m"),
    ):
        x = float(v)
        if not (math.isfinite(x) and ok(x)):
            raise ValueError(f"{name} must be finite and {allowed}, got {v!r}")
        values.append(x)
    return values[0], values[1], values[2]


def _bekker_soil(
    result: FitResult, cohesion: float, tan_phi: float, shear_modulus: float, assume: str
) -> BekkerSoil:
    """`FitResult.bekker_soil` (documented there)."""
    if result.info.get("law") != "bekker":
        raise ValueError(
            "bekker_soil() needs the result of fit_plate_sinkage(law='bekker'); this is "
            f"{result.info.get('title', 'another fit')!r}"
        )
    c, t, k = _shear_strength(cohesion, tan_phi, shear_modulus)
    n = result.params["n"]
    if "k_c" in result.params:  # two or more plate sizes: k_c and k_phi identified
        k_c, k_phi = result.params["k_c"], result.params["k_phi"]
    else:
        if assume not in ("frictional", "cohesive"):
            raise ValueError(f"assume must be 'frictional' or 'cohesive', got {assume!r}")
        k_eq = result.params["k_eq"]
        plate = float(result.info["plate_sizes"][0])
        k_c, k_phi = (0.0, k_eq) if assume == "frictional" else (k_eq * plate, 0.0)
    return BekkerSoil(n=n, k_c=k_c, k_phi=k_phi, cohesion=c, tan_phi=t, shear_modulus=k)


def _wong_snow(
    result: FitResult, cohesion: float, tan_phi: float, shear_modulus: float
) -> WongSnow:
    """`FitResult.wong_snow` (documented there)."""
    if result.info.get("law") != "wong":
        raise ValueError(
            "wong_snow() needs the result of fit_plate_sinkage(law='wong'); this is "
            f"{result.info.get('title', 'another fit')!r}"
        )
    c, t, k = _shear_strength(cohesion, tan_phi, shear_modulus)
    return WongSnow(result.params["p_w"], result.params["z_w"], c, t, k)
