"""Calibration: least-squares fits with identifiability diagnostics and uncertainty.

Three fits, all by `optimistix.least_squares` with Levenberg–Marquardt:

- `fit_plate_sinkage`: a pressure–sinkage law — Bekker (2.1), Wong (2.3) or Reece (2.4) —
  to plate-sinkage data (SI: m, Pa).
- `fit_tire_coefficients`: the load functions (3.17)–(3.21) of chapter 3 to data shaped
  like the thesis's Table 3.2 (the thesis's units: kN, kN/rad).
- `fit_wheel`: any subset of the parameters of any terrain (`WongSnow`, `BekkerSoil`,
  `ReeceSoil`, `LayeredSnow`) and of the Wong–Reece stress distribution to measured
  sinkage and/or drawbar pull / motion resistance versus slip at one or more loads,
  straight through the vmapped wheel equilibrium `solve_wheel` (eq. 4.14); its gradients
  come from the implicit function theorem (`optimistix.ImplicitAdjoint`), not from
  unrolled iterations.

A plate fit becomes a terrain the wheel can use: `FitResult.bekker_soil(...)` (Bekker
law) and `FitResult.wong_snow(...)` (Wong law) add the shear strength the plate test
does not measure.

Every fit returns a `FitResult`: point estimates, Gauss–Newton standard errors,
the residuals, and plain-language warnings when a parameter is poorly determined.

**Uncertainty.**  With J the Jacobian of the (weighted) residual vector r with respect to
the fitted variables u at the optimum, m residuals and p fitted variables, the covariance
is the Gauss–Newton estimate `Cov(u) = s² (JᵀJ)⁻¹` with `s² = SSE / (m − p)`.  It is
computed from the SVD of J with unit-norm columns; a (numerically) singular J makes the
standard error of every parameter in its null space `inf`.  Parameters fitted through a
transform θ = T(u) (log space for positivity, a shift for Wong's z_w, a plain scale
elsewhere) are transformed back by the delta method, `Cov(θ) = D Cov(u) Dᵀ` with
`D = ∂θ/∂u` — exact for the linearised model, so e.g. a log-space fit gives the same
standard errors as a direct fit at the same optimum (`se(θ) = θ · se(ln θ)`).

**Warnings** (in `FitResult.warnings`): a parameter whose standard error exceeds its
magnitude; a pair of fitted parameters with |correlation| > 0.95; a column-scaled
Jacobian with condition number > 1e4; a singular Jacobian (not identifiable); no degrees
of freedom left; an optimiser that stopped without converging; and fit-specific ones
(a single plate size for Bekker/Reece; a coefficient at its bound; failed or bottomed-out
wheel equilibria).

Equation numbers refer to Sankapalli (2004), *Predictive semi-empirical analysis for
tire/snow interaction*, MSc thesis, University of Alaska Fairbanks.
"""

from __future__ import annotations

import dataclasses
import importlib.resources
import math
from collections.abc import Sequence
from typing import Any

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import optimistix as optx
from jaxtyping import ArrayLike, Float

from .._constants import DEFAULT_SHEAR_MODULUS
from .._leaves import _is_traced, _module_leaves, _parameter_names, _with_leaves
from .._terrain.base import Terrain
from .._terrain.bekker import BekkerSoil, bekker_pressure
from .._terrain.reece import reece_pressure
from .._terrain.wong import WongSnow, wong_pressure
from .._tire.tire import (
    TireCoefficients,
    lateral_friction,
    lateral_stiffness,
    longitudinal_friction,
    longitudinal_stiffness,
)
from .._wheel.distribution import WongReece
from .._wheel.equilibrium import Status, _check_model, solve_wheel
from .._wheel.inputs import _checks as _wheel_checks
from .._wheel.geometry import RigidWheel

__all__ = [
    "FitResult",
    "fit_plate_sinkage",
    "fit_tire_coefficients",
    "fit_wheel",
    "fit_parameter_names",
    "thesis_plate_test",
    "thesis_tire_table",
    "THESIS_PLATE_DIAMETER",
    "PLATE_LAWS",
    "WHEEL_PARAMETERS",
    "WHEEL_QUANTITIES",
    "LOG_SPACE_PARAMETERS",
]

# Diagnostic thresholds (documented in the module docstring).
CORRELATION_LIMIT = 0.95
CONDITION_LIMIT = 1e4
# A singular value below this fraction of the largest one counts as zero.
_RANK_TOL = 1e-10

PLATE_LAWS = ("bekker", "wong", "reece")
WHEEL_PARAMETERS = ("p_w", "z_w", "cohesion", "tan_phi", "shear_modulus")
WHEEL_QUANTITIES = ("sinkage", "drawbar_pull", "motion_resistance")
_WHEEL_UNITS = {"p_w": "Pa", "z_w": "m", "cohesion": "Pa", "tan_phi": "-", "shear_modulus": "m"}

# The plate of the thesis's laboratory test (Table 2.1): 23 cm diameter, circular.
THESIS_PLATE_DIAMETER = 0.23  # [m]


# ---------------------------------------------------------------------------------------
# Result
# ---------------------------------------------------------------------------------------


@dataclasses.dataclass(frozen=True)
class FitResult:
    """Outcome of a calibration fit.

    - `params`: fitted (and derived) parameters, name -> float, in the units of `units`.
    - `stderr`: standard error of each entry of `params`, from the Gauss–Newton covariance
      `s² (JᵀJ)⁻¹`, `s² = SSE / (m − p)` (delta method for transformed parameters); `nan`
      when undefined (no degrees of freedom, parameter at a bound), `inf` when the
      parameter is not identifiable.
    - `sse`: sum of squared `residuals`.
    - `residuals`: the residual vector model − data that was minimised, in the units each
      fit documents (Pa for plates; the thesis's units for the tire table; dimensionless
      scaled residuals for the wheel).
    - `warnings`: plain-language diagnostics (empty when nothing is suspicious).
    - `units`: unit of each parameter.
    - `covariance`, `correlation`: matrices over the entries of `params`, in their order.
    - `condition_number`: of the column-normalised Jacobian of the fitted variables.
    - `dof`: m − p.
    - `success`: whether Levenberg–Marquardt met its tolerance.
    - `num_steps`: optimiser steps taken.
    - `info`: fit-specific extras (law, plate sizes, wheel predictions and statuses, ...).
    """

    params: dict[str, float]
    stderr: dict[str, float]
    sse: float
    residuals: np.ndarray
    warnings: list[str]
    units: dict[str, str] = dataclasses.field(default_factory=dict)
    covariance: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros((0, 0)))
    correlation: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros((0, 0)))
    condition_number: float = float("nan")
    dof: int = 0
    success: bool = True
    num_steps: int = 0
    info: dict[str, Any] = dataclasses.field(default_factory=dict)

    def bekker_soil(
        self,
        cohesion: float,
        tan_phi: float,
        *,
        shear_modulus: float = DEFAULT_SHEAR_MODULUS,
        assume: str = "frictional",
    ) -> BekkerSoil:
        """The `BekkerSoil` of a Bekker plate fit (`fit_plate_sinkage(law="bekker")`).

        A plate test measures only the pressure–sinkage law (2.1); the shear strength
        (2.5) and the Janosi–Hanamoto modulus (2.8) come from a shear test and are given
        here.

        - **Two or more plate sizes** (k_c, k_φ and n fitted): exact,
          `BekkerSoil(n, k_c, k_phi, cohesion, tan_phi, shear_modulus=...)`.  On the wheel
          b is the wheel width, the smaller dimension of its contact patch; the k_c so
          obtained is in the convention of the `plate_size` values of the fit (the thesis
          used a circular plate's diameter, Bekker's convention is its radius: a
          diameter-based k_c is twice the radius-based one).  `assume` is not used.
        - **One plate size b_p** (only k_eq = k_c / b_p + k_φ and n identifiable): the
          split of k_eq is unknown, so it must be assumed.  `assume="frictional"`
          (default): k_c = 0, k_φ = k_eq; `assume="cohesive"`: k_c = k_eq b_p, k_φ = 0.
          Both reproduce the plate law exactly for a wheel of width b = b_p (and then give
          the same wheel); for another width the true modulus k_c / b + k_φ lies between
          the two (when k_c, k_φ >= 0): the frictional choice keeps k_eq whatever the
          width, the cohesive one scales it by b_p / b.  Test two plate sizes to know.

        **Arguments:**

        - `cohesion`: c [Pa] (>= 0).
        - `tan_phi`: tan φ [-] (>= 0).
        - `shear_modulus`: K [m] (> 0; default `DEFAULT_SHEAR_MODULUS`, 10 mm).
        - `assume`: `"frictional"` or `"cohesive"` (one plate size only, see above).

        **Returns:** a `BekkerSoil` with scalar leaves, ready for `solve_wheel`.

        **Raises:** `ValueError` if this is not a Bekker plate fit or an argument is out
        of range.
        """
        if self.info.get("law") != "bekker":
            raise ValueError(
                "bekker_soil() needs the result of fit_plate_sinkage(law='bekker'); this is "
                f"{self.info.get('title', 'another fit')!r}"
            )
        strength = _shear_strength(cohesion, tan_phi, shear_modulus)
        n = self.params["n"]
        if "k_c" in self.params:  # two or more plate sizes: k_c and k_phi identified
            k_c, k_phi = self.params["k_c"], self.params["k_phi"]
        else:
            if assume not in ("frictional", "cohesive"):
                raise ValueError(f"assume must be 'frictional' or 'cohesive', got {assume!r}")
            k_eq = self.params["k_eq"]
            plate = float(self.info["plate_sizes"][0])
            k_c, k_phi = (0.0, k_eq) if assume == "frictional" else (k_eq * plate, 0.0)
        return BekkerSoil(
            n=n, k_c=k_c, k_phi=k_phi, cohesion=strength[0], tan_phi=strength[1],
            shear_modulus=strength[2],
        )  # fmt: skip

    def wong_snow(
        self, cohesion: float, tan_phi: float, *, shear_modulus: float = DEFAULT_SHEAR_MODULUS
    ) -> WongSnow:
        """The `WongSnow` of a Wong plate fit (`fit_plate_sinkage(law="wong")`).

        Wong's law (2.3) does not depend on the plate size, so p_w and z_w carry over to
        the wheel as they are.  **Arguments:** `cohesion` c [Pa] (>= 0), `tan_phi` [-]
        (>= 0), `shear_modulus` K [m] (> 0; default 10 mm).  **Returns:** `WongSnow`.
        """
        if self.info.get("law") != "wong":
            raise ValueError(
                "wong_snow() needs the result of fit_plate_sinkage(law='wong'); this is "
                f"{self.info.get('title', 'another fit')!r}"
            )
        c, t, k = _shear_strength(cohesion, tan_phi, shear_modulus)
        return WongSnow(self.params["p_w"], self.params["z_w"], c, t, k)

    def table(self) -> str:
        """A readable table of the parameters, standard errors and warnings."""
        lines = [str(self.info.get("title", "fit"))]
        width = max([9] + [len(k) for k in self.params])
        lines.append(f"  {'parameter':<{width}}  {'value':>14}  {'std. error':>11}  unit")
        for k, v in self.params.items():
            se = self.stderr.get(k, float("nan"))
            lines.append(f"  {k:<{width}}  {v:>14.7g}  {se:>11.3g}  {self.units.get(k, '')}")
        sse_unit = self.info.get("sse_unit", "")
        status = "converged" if self.success else "did NOT converge"
        lines.append(
            f"  SSE = {self.sse:.6g}{' ' + sse_unit if sse_unit else ''}; "
            f"{self.residuals.size} residuals, {self.dof} degrees of freedom; "
            f"Levenberg-Marquardt {status} in {self.num_steps} steps"
        )
        lines.append(f"  condition number of the scaled Jacobian: {self.condition_number:.3g}")
        if self.warnings:
            lines.append("  warnings:")
            lines.extend(f"    - {w}" for w in self.warnings)
        return "\n".join(lines)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict (non-finite numbers become None)."""

        def num(x):
            x = float(x)
            return x if math.isfinite(x) else None

        out = {
            "params": {k: num(v) for k, v in self.params.items()},
            "stderr": {k: num(v) for k, v in self.stderr.items()},
            "units": dict(self.units),
            "sse": num(self.sse),
            "residuals": [num(x) for x in np.ravel(self.residuals)],
            "warnings": list(self.warnings),
            "correlation": [[num(x) for x in row] for row in np.asarray(self.correlation)],
            "condition_number": num(self.condition_number),
            "dof": int(self.dof),
            "success": bool(self.success),
            "num_steps": int(self.num_steps),
        }
        for key in ("title", "law", "equation", "plate_sizes", "sse_unit"):
            if key in self.info:
                out[key] = self.info[key]
        return out


def _shear_strength(cohesion, tan_phi, shear_modulus) -> tuple[float, float, float]:
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
    return tuple(values)


# ---------------------------------------------------------------------------------------
# Package data
# ---------------------------------------------------------------------------------------


def _read_package_csv(name: str) -> dict[str, np.ndarray]:
    """A shipped table: '#' comment lines, a header line, then rows of numbers."""
    path = importlib.resources.files("snowjax") / "data" / name
    lines = [
        ln.strip()
        for ln in path.read_text(encoding="utf-8").splitlines()
        if ln.strip() and not ln.lstrip().startswith("#")
    ]
    header = [h.strip() for h in lines[0].split(",")]
    values = np.array([[float(x) for x in ln.split(",")] for ln in lines[1:]])
    return {h: values[:, k] for k, h in enumerate(header)}


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
    t = _read_package_csv("table_2_1.csv")
    z = np.asarray(t["sinkage_m"], float)
    return {
        "sinkage": z,
        "pressure": np.asarray(t["pressure_kPa"], float) * 1e3,
        "load": np.asarray(t["load_N"], float),
        "plate_size": np.full_like(z, THESIS_PLATE_DIAMETER),
    }


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
    t = _read_package_csv("table_3_2.csv")
    return {k: np.asarray(t[k], float) for k in ("load_kN", "cs", "ca", "mux", "muy", "e1")}


# ---------------------------------------------------------------------------------------
# Shared machinery
# ---------------------------------------------------------------------------------------


def _least_squares_impl(residual, max_steps, tol, u0, args):
    """Levenberg–Marquardt on `residual(u, args) -> (r, aux)`.

    Returns the optimum u, and r, J = ∂r/∂u and aux *at that optimum* (the solver's last
    accepted state, so no second trace of the model is needed).  The Jacobian is
    materialised by reverse mode (`jac="bwd"`): with forward mode optimistix evaluates
    its zero-initialised linearisation on the first step, which makes the implicit JVP
    of a nested root find (the wheel equilibrium) see a zero operator.
    """
    solver = optx.LevenbergMarquardt(rtol=tol, atol=tol)
    sol = optx.least_squares(
        residual,
        solver,
        u0,
        args,
        options=dict(jac="bwd"),
        has_aux=True,
        max_steps=max_steps,
        throw=False,
    )
    state = sol.state
    return (
        sol.value,
        state.f_info.residual,
        state.f_info.jac.as_matrix(),
        state.aux,
        sol.result == optx.RESULTS.successful,
        sol.stats["num_steps"],
    )


# On CPU, the fits compile with cheaper XLA settings: a wheel fit is a large program (a
# Levenberg–Marquardt loop around the reverse-mode Jacobian of nested root finds) that
# runs for a fraction of a second, so halving its compile time (measured: 15.6 s -> 7.0 s
# of CPU) matters far more than the slower run time.  The arithmetic is the same.
_CPU_COMPILER_OPTIONS = {
    "xla_backend_optimization_level": 0,
    "xla_llvm_disable_expensive_passes": True,
}
_least_squares_cpu = jax.jit(
    _least_squares_impl, static_argnums=(0, 1, 2), compiler_options=_CPU_COMPILER_OPTIONS
)
_least_squares_default = jax.jit(_least_squares_impl, static_argnums=(0, 1, 2))


def _least_squares(residual, u0, args, max_steps, tol):
    fn = _least_squares_cpu if jax.default_backend() == "cpu" else _least_squares_default
    return fn(residual, int(max_steps), float(tol), u0, args)


def _run(residual, u0, args, max_steps, tol):
    u, r, jac, aux, ok, steps = _least_squares(residual, u0, args, int(max_steps), float(tol))
    to_np = lambda x: np.asarray(x, dtype=float)  # noqa: E731
    return (
        to_np(u),
        to_np(r),
        to_np(jac),
        jax.tree_util.tree_map(np.asarray, aux),
        bool(ok),
        int(steps),
    )


@dataclasses.dataclass
class _Uncertainty:
    cov_u: np.ndarray  # covariance of the fitted variables u
    cond: float
    dof: int
    s2: float
    unidentified: np.ndarray  # bool per fitted variable


def _gauss_newton_covariance(jac: np.ndarray, residual: np.ndarray) -> _Uncertainty:
    """`s² (JᵀJ)⁻¹`, s² = SSE/(m − p), via the SVD of J with unit-norm columns."""
    m, p = jac.shape
    dof = m - p
    sse = float(np.sum(residual**2))
    s2 = sse / dof if dof > 0 else float("nan")
    bad_col = ~np.isfinite(jac).all(axis=0)  # a derivative the model could not provide
    jac = np.where(np.isfinite(jac), jac, 0.0)
    norms = np.linalg.norm(jac, axis=0)
    zero_col = ~(norms > 0) | bad_col
    safe = np.where(zero_col, 1.0, norms)
    js = jac / safe
    _, sv, vt = np.linalg.svd(js, full_matrices=False)
    smax = sv[0] if sv.size else 0.0
    small = sv <= _RANK_TOL * smax if smax > 0 else np.ones_like(sv, bool)
    with np.errstate(divide="ignore"):
        cond = float(smax / sv[-1]) if sv.size and sv[-1] > 0 else float("inf")
    inv_s2 = np.where(small, 0.0, 1.0 / np.where(small, 1.0, sv) ** 2)
    cov_scaled = (vt.T * inv_s2) @ vt
    # Variables with a component in the (numerical) null space are not identifiable.
    null = vt[small] if small.any() else np.zeros((0, p))
    unidentified = zero_col | (np.abs(null) > 1e-8).any(axis=0)
    cov_u = s2 * cov_scaled / np.outer(safe, safe)
    cov_u[unidentified, :] = np.inf
    cov_u[:, unidentified] = np.inf
    return _Uncertainty(cov_u=cov_u, cond=cond, dof=dof, s2=s2, unidentified=unidentified)


def _propagate(unc: _Uncertainty, dtheta_du: np.ndarray):
    """Delta method: Cov(θ) = D Cov(u) Dᵀ; returns (cov, stderr, correlation)."""
    d = np.asarray(dtheta_du, float)
    cov_u = unc.cov_u
    finite = ~unc.unidentified
    cov = np.full((d.shape[0], d.shape[0]), np.nan)
    cf = cov_u[np.ix_(finite, finite)]
    df = d[:, finite]
    with np.errstate(invalid="ignore"):
        cov = df @ cf @ df.T
    # A parameter that depends on an unidentifiable variable has an infinite error.
    depends_bad = (np.abs(d[:, ~finite]) > 0).any(axis=1)
    cov[depends_bad, :] = np.inf
    cov[:, depends_bad] = np.inf
    var = np.diag(cov).copy()
    stderr = np.sqrt(np.where(var >= 0, var, np.nan))
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = cov / np.outer(stderr, stderr)
    corr[~np.isfinite(corr)] = np.nan
    np.fill_diagonal(corr, np.where(np.isfinite(stderr) & (stderr > 0), 1.0, np.nan))
    return cov, stderr, corr


def _diagnose(names, values, stderr, corr, unc: _Uncertainty, fitted, prefix="") -> list[str]:
    """Plain-language warnings about poorly determined parameters."""
    out = []
    pre = f"{prefix}: " if prefix else ""
    if unc.dof <= 0:
        out.append(
            f"{pre}no degrees of freedom left ({unc.dof + len(fitted)} data = "
            f"{len(fitted)} parameters): the standard errors are undefined."
        )
    for i, name in enumerate(names):
        v, se = values[i], stderr[i]
        if np.isinf(se):
            out.append(
                f"{pre}{name} is not identifiable from these data (the Jacobian is "
                f"singular in its direction): its standard error is infinite."
            )
        elif np.isfinite(se) and se > abs(v):
            out.append(
                f"{pre}{name} is poorly determined: its standard error {se:.3g} exceeds "
                f"its magnitude |{v:.4g}|."
            )
    idx = [names.index(n) for n in fitted if n in names]
    for a in range(len(idx)):
        for b in range(a + 1, len(idx)):
            rho = corr[idx[a], idx[b]]
            if np.isfinite(rho) and abs(rho) > CORRELATION_LIMIT:
                out.append(
                    f"{pre}{names[idx[a]]} and {names[idx[b]]} are strongly correlated "
                    f"(correlation {rho:+.4f}, |rho| > {CORRELATION_LIMIT}): the data "
                    "determine a combination of them better than each one."
                )
    if np.isfinite(unc.cond) and unc.cond > CONDITION_LIMIT:
        out.append(
            f"{pre}the column-scaled Jacobian is ill-conditioned (condition number "
            f"{unc.cond:.3g} > {CONDITION_LIMIT:g}): some combination of "
            f"{', '.join(fitted)} is poorly determined."
        )
    return out


def _not_converged(steps: int, max_steps: int) -> str:
    return (
        f"Levenberg-Marquardt stopped without meeting its tolerance after {steps} steps "
        f"(max_steps = {max_steps}); the estimates may not be the optimum."
    )


def _vector(name: str, x, *, min_size: int = 1) -> np.ndarray:
    """A finite 1-D float array, or a ValueError naming `name`."""
    if _is_traced(x):
        raise TypeError(f"{name} must be a concrete array (the fits are not traceable)")
    try:
        arr = np.asarray(x, dtype=float)
    except (TypeError, ValueError) as e:
        raise ValueError(f"{name} must be an array of numbers ({e})") from None
    if arr.ndim == 0:
        arr = arr.reshape(1)
    if arr.ndim != 1:
        raise ValueError(f"{name} must be one-dimensional, got shape {arr.shape}")
    if arr.size < min_size:
        raise ValueError(f"{name} needs at least {min_size} values, got {arr.size}")
    bad = ~np.isfinite(arr)
    if bad.any():
        i = int(np.argmax(bad))
        raise ValueError(f"{name} must be finite; got {arr[i]!r} at index {i}")
    return arr


def _same_length(**arrays) -> int:
    sizes = {k: v.size for k, v in arrays.items()}
    if len(set(sizes.values())) > 1:
        desc = ", ".join(f"{k} has {n}" for k, n in sizes.items())
        raise ValueError(f"shape mismatch: the data arrays must have equal length ({desc})")
    return next(iter(sizes.values()))


# ---------------------------------------------------------------------------------------
# 1. Plate sinkage: Bekker (2.1), Wong (2.3), Reece (2.4)
# ---------------------------------------------------------------------------------------


class _PlateResidual(eqx.Module):
    """Residual (model − data) / pressure scale of a plate law, fitted variables u."""

    law: str = eqx.field(static=True)
    multi: bool = eqx.field(static=True)

    def __call__(self, u, args):
        z, p, b, pscale, consts = args
        model = _plate_model(self.law, self.multi, u, z, b, consts)
        return (model - p) / pscale, None


def _plate_theta(law, multi, u, consts):
    """Natural parameters from the fitted variables (see `fit_plate_sinkage`)."""
    if law == "wong":  # p_w = exp(u0), z_w = z_max (1 + exp(u1)) > z_max
        return jnp.exp(u[0]), consts[0] * (1 + jnp.exp(u[1]))
    if not multi:  # k_eq = exp(u0), n = u1
        return jnp.exp(u[0]), u[1]
    return consts[0] * u[0], consts[1] * u[1], u[2]  # two moduli (scaled), n


def _plate_model(law, multi, u, z, b, consts):
    theta = _plate_theta(law, multi, u, consts)
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
    - `cohesion`, `unit_weight`: optional c [Pa] and γ_s [N/m³] for Reece's k'_c, k'_φ.
    - `max_steps`: Levenberg–Marquardt step limit.

    **Returns:** a `FitResult` (residuals in Pa, SSE in Pa²).  For the wheel:
    `result.bekker_soil(cohesion, tan_phi, shear_modulus=...)` (Bekker; with one plate
    size the split of k_eq is an assumption, see `FitResult.bekker_soil`) and
    `result.wong_snow(...)` (Wong) return the terrain `solve_wheel` takes.

    **Raises:** `ValueError` for an unknown law, unequal lengths, non-finite values,
    negative sinkage, non-positive plate sizes, or too few points (more than the number
    of parameters are needed).
    """
    if law not in PLATE_LAWS:
        raise ValueError(f"law must be one of {PLATE_LAWS}, got {law!r}")
    z = _vector("sinkage", sinkage)
    p = _vector("pressure", pressure)
    m = _same_length(sinkage=z, pressure=p)
    if (z < 0).any():
        i = int(np.argmax(z < 0))
        raise ValueError(f"sinkage must be >= 0 m; got {z[i]!r} at index {i}")
    if law == "wong":
        b = np.ones_like(z)
        sizes = np.array([1.0])
    else:
        if plate_size is None:
            raise ValueError(f"law={law!r} needs plate_size (b [m]), a scalar or one per point")
        b = _vector("plate_size", plate_size)
        if b.size == 1:
            b = np.full_like(z, b[0])
        _same_length(sinkage=z, plate_size=b)
        if (b <= 0).any():
            i = int(np.argmax(b <= 0))
            raise ValueError(f"plate_size must be > 0 m; got {b[i]!r} at index {i}")
        sizes = np.unique(b)
    multi = law != "wong" and sizes.size >= 2
    n_params = 3 if multi else 2
    if m <= n_params:
        raise ValueError(
            f"fit_plate_sinkage({law!r}) fits {n_params} parameters and needs more than "
            f"{n_params} points; got {m}"
        )
    pscale = float(np.sqrt(np.mean(p**2)))
    if not pscale > 0:
        raise ValueError("pressure must not be all zero")

    warnings: list[str] = []
    info: dict[str, Any] = {"law": law, "sse_unit": "Pa^2"}
    if law == "wong":
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
        consts = np.array([zmax])
        names, units = ["p_w", "z_w"], {"p_w": "Pa", "z_w": "m"}
        info.update(equation="(2.3)", title=f"Wong pressure-sinkage law (2.3), {m} points")
    else:
        n0, moduli = _loglog_init(z, p, b, law, sizes)
        if not multi:
            u0 = np.array([np.log(moduli[0]), n0])
            consts = np.zeros(1)
        else:
            # Combined modulus k_j = A g(b_j) + B: Bekker g = 1/b, Reece k = A + B b.
            g = 1.0 / sizes if law == "bekker" else sizes
            a_mat = (
                np.stack([g, np.ones_like(g)], 1)
                if law == "bekker"
                else np.stack([np.ones_like(g), g], 1)
            )
            ab, *_ = np.linalg.lstsq(a_mat, moduli, rcond=None)
            kscale = float(np.mean(moduli))
            if law == "bekker":  # theta = (k_c, k_phi): k_c / b ~ kscale u0
                consts = np.array([kscale / np.mean(1 / sizes), kscale])
            else:  # theta = (c k'_c, gamma k'_phi): gamma k'_phi b ~ kscale u1
                consts = np.array([kscale, kscale / np.mean(sizes)])
            u0 = np.array([ab[0] / consts[0], ab[1] / consts[1], n0])
        eq = "(2.1)" if law == "bekker" else "(2.4)"
        kind = "Bekker" if law == "bekker" else "Reece"
        sizes_txt = ", ".join(f"{s:g}" for s in sizes)
        info.update(
            equation=eq,
            plate_sizes=[float(s) for s in sizes],
            title=f"{kind} pressure-sinkage law {eq}, {m} points, plate size b = {sizes_txt} m",
        )
        if not multi:
            names = ["k_eq", "n"]
            if law == "bekker":
                units = {"k_eq": "N/m^(n+2)", "n": "-"}
                combo, parts = "k_eq = k_c/b + k_phi", "k_c and k_phi"
            else:
                units = {"k_eq": "Pa", "n": "-"}
                combo, parts = "k_eq = c k'_c + gamma_s b k'_phi", "k'_c and k'_phi"
            warnings.append(
                f"{parts} are not identifiable from a single plate size (b = {sizes[0]:g} m): "
                f"only the combined modulus {combo} is determined, so only k_eq and n are "
                "returned. Test two or more plate sizes to separate them."
            )
        elif law == "bekker":
            names = ["k_c", "k_phi", "n"]
            units = {"k_c": "N/m^(n+1)", "k_phi": "N/m^(n+2)", "n": "-", "k_eq": "N/m^(n+2)"}
        else:
            names = ["cohesion_k_c_prime", "unit_weight_k_phi_prime", "n"]
            units = {
                "cohesion_k_c_prime": "Pa",
                "unit_weight_k_phi_prime": "N/m^3",
                "n": "-",
                "k_eq": "Pa",
                "k_c_prime": "-",
                "k_phi_prime": "-",
            }

    residual = _PlateResidual(law=law, multi=bool(multi))
    args = (z, p, b, np.asarray(pscale), np.asarray(consts, float))
    u, r, jac, _, ok, steps = _run(residual, u0, args, max_steps, 1e-12)
    if not ok:
        warnings.append(_not_converged(steps, max_steps))
    r_pa = r * pscale
    unc = _gauss_newton_covariance(jac * pscale, r_pa)

    # Natural parameters and D = dtheta/du (elementwise transforms).
    if law == "wong":
        theta = [math.exp(u[0]), consts[0] * (1 + math.exp(u[1]))]
        d = np.diag([theta[0], consts[0] * math.exp(u[1])])
    elif not multi:
        theta = [math.exp(u[0]), float(u[1])]
        d = np.diag([theta[0], 1.0])
    else:
        theta = [consts[0] * u[0], consts[1] * u[1], float(u[2])]
        d = np.diag([consts[0], consts[1], 1.0])
        b_ref = float(sizes.min())
        info["b_ref"] = b_ref
        rows = []
        if law == "bekker":  # k_eq = k_c / b_ref + k_phi
            names.append("k_eq")
            theta.append(theta[0] / b_ref + theta[1])
            rows.append(d[0] / b_ref + d[1])
        else:  # k_eq = c k'_c + gamma k'_phi b_ref; k'_c = A / c; k'_phi = B / gamma
            names.append("k_eq")
            theta.append(theta[0] + theta[1] * b_ref)
            rows.append(d[0] + d[1] * b_ref)
            if cohesion is not None:
                c = float(cohesion)
                if not (math.isfinite(c) and c > 0):
                    raise ValueError(f"cohesion must be finite and > 0 Pa, got {cohesion!r}")
                names.append("k_c_prime")
                theta.append(theta[0] / c)
                rows.append(d[0] / c)
            if unit_weight is not None:
                gam = float(unit_weight)
                if not (math.isfinite(gam) and gam > 0):
                    raise ValueError(
                        f"unit_weight must be finite and > 0 N/m^3, got {unit_weight!r}"
                    )
                names.append("k_phi_prime")
                theta.append(theta[1] / gam)
                rows.append(d[1] / gam)
        d = np.vstack([d] + [np.atleast_2d(rw) for rw in rows])
    fitted = names[: len(u)]
    cov, stderr, corr = _propagate(unc, d)
    warnings += _diagnose(names, theta, stderr, corr, unc, fitted)
    return FitResult(
        params={k: float(v) for k, v in zip(names, theta)},
        stderr={k: float(s) for k, s in zip(names, stderr)},
        sse=float(np.sum(r_pa**2)),
        residuals=r_pa,
        warnings=warnings,
        units={k: units[k] for k in names},
        covariance=cov,
        correlation=corr,
        condition_number=unc.cond,
        dof=unc.dof,
        success=ok,
        num_steps=steps,
        info=info,
    )


# ---------------------------------------------------------------------------------------
# 2. Tire load functions (3.17)–(3.21)
# ---------------------------------------------------------------------------------------

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
    """Stacked scaled residuals of the present load functions (separable blocks)."""

    keys: tuple = eqx.field(static=True)
    sizes: tuple = eqx.field(static=True)

    def __call__(self, u, args):
        f_kn, data, scales, active = args
        theta = u * scales * active  # inactive variables are held at 0 (a bound)
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
    Every array has the length of `load_kN` and is finite.  `max_steps`:
    Levenberg–Marquardt step limit.

    **Returns:** a `FitResult`; `residuals` are model − data in the data's units, stacked
    in the order C_s, C_α, μ_x, μ_y, E1 (present ones); standard errors and warnings
    (|correlation| > 0.95, standard error > |value|, a coefficient at its bound, no
    degrees of freedom) are per load function, each with its own s² = SSE / (m − p).
    """
    f = _vector("load_kN", load_kN)
    if (f <= 0).any():
        i = int(np.argmax(f <= 0))
        raise ValueError(f"load_kN must be > 0 kN; got {f[i]!r} at index {i}")
    given = {"cs": cs, "ca": ca, "mux": mux, "muy": muy, "e1": e1}
    blocks = [blk for blk in _TIRE_BLOCKS if given[blk[0]] is not None]
    if not blocks:
        raise ValueError("fit_tire_coefficients needs at least one of cs, ca, mux, muy, e1")
    data = {}
    for key, *_ in blocks:
        y = _vector(key, given[key])
        _same_length(load_kN=f, **{key: y})
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

    keys = tuple(b[0] for b in blocks)
    sizes = tuple(len(b[2]) for b in blocks)
    theta0 = np.concatenate([_tire_init(k, f, data[k]) for k in keys])
    active = np.ones_like(theta0)
    scales = np.where(np.abs(theta0) > 0, np.abs(theta0), 1.0)
    e1_start = sum(sizes[:-1]) if keys[-1] == "e1" else None
    if e1_start is not None:
        for j in range(2):
            if theta0[e1_start + j] < 0:  # bound a_j² >= 0 active from the start
                active[e1_start + j] = 0.0
        if active[e1_start] == 0.0 and active[e1_start + 1] == 1.0:
            fe = f**2
            q2 = float(fe @ -np.log1p(-2 * data["e1"]) / (fe @ fe))
            theta0[e1_start + 1] = q2
            scales[e1_start + 1] = abs(q2) if q2 != 0 else 1.0
    args_data = dict(data)
    for k in keys:
        args_data[k + "_scale"] = np.asarray(np.sqrt(np.mean(data[k] ** 2)))
    residual = _TireResidual(keys=keys, sizes=sizes)

    for _attempt in range(3):
        args = (f, args_data, scales, active)
        u0 = np.where(active > 0, theta0 / scales, 0.0)
        u, r, jac, _, ok, steps = _run(residual, u0, args, max_steps, 1e-12)
        theta = u * scales * active
        if e1_start is None:
            break
        hit = [j for j in range(2) if active[e1_start + j] > 0 and theta[e1_start + j] < 0]
        # KKT check of a held bound: release it if raising a_j² from 0 lowers the SSE.
        q = np.maximum(theta[e1_start : e1_start + 2], 0.0)
        e1_res = _tire_e1_np(q, f) - data["e1"]
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

    # Per-block covariance, diagnostics, back transforms.
    params, stderr, units = {}, {}, {}
    warnings: list[str] = []
    if not ok:
        warnings.append(_not_converged(steps, max_steps))
    residual_raw, row, col = [], 0, 0
    n = f.size
    cov_blocks, corr_blocks, conds, dofs, sse_by = [], [], [], [], {}
    for key, eq, names, qty in blocks:
        size = len(names)
        scale_row = float(args_data[key + "_scale"])
        r_b = r[row : row + n] * scale_row
        act = active[col : col + size] > 0
        # J w.r.t. the natural variables theta (= q for E1) of the active ones.
        j_b = jac[row : row + n, col : col + size][:, act] * scale_row
        j_b = j_b / scales[col : col + size][act]
        th_b = theta[col : col + size]
        unc = _gauss_newton_covariance(j_b, r_b)
        fitted = [nm for nm, a in zip(names, act) if a]
        if key == "e1":
            vals, drows = [], []
            k = 0
            for j, nm in enumerate(names):
                if act[j]:
                    q = max(th_b[j], 0.0)
                    a = math.sqrt(q)
                    vals.append(a)
                    row_d = np.zeros(int(act.sum()))
                    row_d[k] = 1.0 / (2 * a) if a > 0 else np.inf
                    drows.append(row_d)
                    k += 1
                else:
                    vals.append(0.0)
                    drows.append(None)
            cov_a = np.full((size, size), np.nan)
            se = np.full(size, np.nan)
            idx = [j for j in range(size) if act[j]]
            if idx:
                d = np.vstack([drows[j] for j in idx])
                c_sub, se_sub, _ = _propagate(unc, d)
                cov_a[np.ix_(idx, idx)] = c_sub
                se[idx] = se_sub
            with np.errstate(invalid="ignore", divide="ignore"):
                corr = cov_a / np.outer(se, se)
            for j, nm in enumerate(names):
                if not act[j]:
                    q_free = _unconstrained_q(f, data["e1"], j)
                    warnings.append(
                        f"{eq} E1: {nm} is degenerate: the data want {nm}^2 < 0 (a straight-"
                        f"line fit of -ln(1 - 2 E1) = a1^2 F + a2^2 F^2 gives {nm}^2 = "
                        f"{q_free:.3g}), so {nm} is held at its bound 0 and has no standard "
                        "error. (E1 depends on a1 only through a1^2; the thesis's "
                        "a1 = 7.5852e-9 is the same boundary optimum.)"
                    )
            theta_b = vals
        else:
            d = np.eye(size)
            cov_a, se, corr = _propagate(unc, d)
            theta_b = list(th_b)
        prefix = f"{eq} {qty.split()[0]}"
        warnings += _diagnose(list(names), theta_b, se, corr, unc, fitted, prefix=prefix)
        for nm, v, s in zip(names, theta_b, se):
            params[nm] = float(v)
            stderr[nm] = float(s)
            units[nm] = _TIRE_UNITS[nm]
        residual_raw.append(r_b)
        cov_blocks.append(cov_a)
        corr_blocks.append(corr)
        conds.append(unc.cond)
        dofs.append(unc.dof)
        sse_by[key] = float(np.sum(r_b**2))
        row += n
        col += size

    res = np.concatenate(residual_raw)
    order = [nm for blk in _TIRE_BLOCKS for nm in blk[2] if nm in params]
    # Block-diagonal covariance/correlation in the thesis's coefficient order.
    cov = _block_diag(cov_blocks)
    corr = _block_diag(corr_blocks)
    names_blockorder = [nm for _, _, names, _ in blocks for nm in names]
    perm = [names_blockorder.index(nm) for nm in order]
    return FitResult(
        params={k: params[k] for k in order},
        stderr={k: stderr[k] for k in order},
        sse=float(np.sum(res**2)),
        residuals=res,
        warnings=warnings,
        units={k: units[k] for k in order},
        covariance=cov[np.ix_(perm, perm)],
        correlation=corr[np.ix_(perm, perm)],
        condition_number=float(max(conds)),
        dof=int(min(dofs)),
        success=ok,
        num_steps=steps,
        info={
            "title": f"Tire load functions (3.17)-(3.21), {n} loads (thesis units: kN, kN/rad)",
            "equation": "(3.17)-(3.21)",
            "sse_by_quantity": sse_by,
            "sse_unit": "(summed over mixed units; per quantity: info['sse_by_quantity'])",
            "dof_by_quantity": dict(zip(keys, dofs)),
        },
    )


def _tire_e1_np(q, f):
    """(3.21) in q = (a1², a2²), NumPy."""
    return -0.5 * np.expm1(-q[0] * f - q[1] * f**2)


def _unconstrained_q(f, e1, j):
    """Unconstrained least-squares a_j² of (3.21), linearised (for the warning text)."""
    q, *_ = np.linalg.lstsq(np.stack([f, f**2], 1), -np.log1p(-2 * e1), rcond=None)
    return float(q[j])


def _block_diag(blocks):
    size = sum(b.shape[0] for b in blocks)
    out = np.zeros((size, size))
    k = 0
    for b in blocks:
        s = b.shape[0]
        out[k : k + s, k : k + s] = b
        k += s
    return out


# ---------------------------------------------------------------------------------------
# 3. Wheel calibration through the equilibrium (4.14)
# ---------------------------------------------------------------------------------------

# Scaled residual given to data points whose equilibrium failed at the current iterate
# (constant, zero gradient): it raises the loss, so Levenberg–Marquardt rejects a step
# into a region where the model cannot be evaluated.
_FAILED_RESIDUAL = 10.0

# Unit of every known parameter leaf, by field name (the last component of its path).
_PARAMETER_UNITS = {
    **_WHEEL_UNITS,
    "n": "-",
    "k_c": "N/m^(n+1)",
    "k_phi": "N/m^(n+2)",
    "k_c_prime": "-",
    "k_phi_prime": "-",
    "unit_weight": "N/m^3",
    "ice_failure_pressure": "Pa",
    "c1": "-",
    "c2": "-",
    "c3": "-",
}
# Leaves that are never negative are fitted in log space (u = ln theta); all others
# (k_c, k_phi, k_c_prime, k_phi_prime, c1, c2, c3, and any leaf of a user-defined
# terrain) as theta = start + scale u.
LOG_SPACE_PARAMETERS = (
    "p_w", "z_w", "cohesion", "tan_phi", "shear_modulus", "n", "unit_weight",
    "ice_failure_pressure",
)  # fmt: skip
# Scale of a linearly fitted parameter whose start value is 0 (otherwise |start|).
_LINEAR_SCALES = {
    "k_c": 1e3,  # N/m^(n+1)
    "k_phi": 1e5,  # N/m^(n+2)
    "k_c_prime": 1.0,
    "k_phi_prime": 1.0,
    "c1": 0.1,
    "c2": 0.1,
    "c3": 0.1,
}


def _field(path: str) -> str:
    return path.rsplit(".", 1)[-1]


def fit_parameter_names(terrain, distribution=None) -> tuple[str, ...]:
    """The names `fit_wheel` accepts in `fit=` for this terrain and distribution.

    A leaf is named by its field path: the terrain's fields (`p_w`, `k_phi`, `n`, ...),
    nested ones dotted (`top.p_w`, `bottom.z_w` for `LayeredSnow`), and the
    distribution's (`c1`, `c2`, `c3` for `WongReece`).  A name that both hold is
    written `terrain.<path>` / `distribution.<path>`; these prefixed forms are accepted
    for every leaf.

    **Arguments:** `terrain`: a `snowjax.Terrain`; `distribution`: `None` or a
    `snowjax.WongReece`.

    **Returns:** the canonical names, terrain first, in field order.
    """
    return tuple(_parameter_names(terrain, distribution))


class _WheelResidual(eqx.Module):
    """Scaled residuals (model − data) / scale of the chosen quantities, quantity-major."""

    names: tuple = eqx.field(static=True)
    quantities: tuple = eqx.field(static=True)
    shear: str = eqx.field(static=True)
    nodes_per_panel: Any = eqx.field(static=True)
    solve_max_steps: int = eqx.field(static=True)
    # (owner, field path) of each fitted variable; owner "terrain" or "distribution".
    targets: tuple = eqx.field(static=True, default=())
    # "log" (theta = exp(u)) or "linear" (theta = offset + step u) per fitted variable.
    transforms: tuple = eqx.field(static=True, default=())

    def __call__(self, u, args):
        wheel, snow, distribution, load, slip, data, scale, offset, step = args
        if all(t == "log" for t in self.transforms):
            values = _finite_cotangent(jnp.exp(u))  # every parameter stays > 0
        else:
            values = _finite_cotangent(
                jnp.stack([
                    jnp.exp(u[i]) if t == "log" else offset[i] + step[i] * u[i]
                    for i, t in enumerate(self.transforms)
                ])
            )  # fmt: skip
        new = {"terrain": {}, "distribution": {}}
        for i, (owner, path) in enumerate(self.targets):
            new[owner][path] = values[i]
        snow = _with_leaves(snow, new["terrain"])
        if distribution is not None:
            distribution = _with_leaves(distribution, new["distribution"])
        st = solve_wheel(
            wheel,
            snow,
            load,
            slip,
            self.shear,
            distribution=distribution,
            nodes_per_panel=self.nodes_per_panel,
            max_steps=self.solve_max_steps,
        )
        pred = jnp.stack([getattr(st, q) for q in self.quantities])
        return _masked_residual(pred, data, scale, st.status).reshape(-1), (pred, st.status)


@jax.custom_vjp
def _finite_cotangent(x):
    """Identity whose backward pass replaces non-finite cotangents by 0.

    A derivative the model cannot provide (e.g. w.r.t. z_w once z_w exceeds the wheel
    diameter, where `solve_wheel`'s base angle arccos(1 − 2 z_w/D) is clipped) then
    shows up as a zero Jacobian column — "not identifiable" in the diagnostics — instead
    of a NaN that would stop the Levenberg–Marquardt linear solves.
    """
    return x


def _finite_cotangent_fwd(x):
    return x, None


def _finite_cotangent_bwd(_, ct):
    return (jnp.where(jnp.isfinite(ct), ct, 0.0),)


_finite_cotangent.defvjp(_finite_cotangent_fwd, _finite_cotangent_bwd)


def _masked_residual(pred, data, scale, status):
    """(pred − data) / scale where the equilibrium is valid; `_FAILED_RESIDUAL` elsewhere.

    `pred`, `data`, `scale`: (quantities, points); `status`: (points,).  Valid means
    `CONVERGED` or `BOTTOMED_OUT`.  Failed points get a constant (no gradient), and the
    NaN a failed solve may return never reaches the value or the Jacobian.
    """
    ok = ((status == Status.CONVERGED) | (status == Status.BOTTOMED_OUT))[None]
    safe_pred = jnp.where(ok, pred, data)
    return jnp.where(ok, (safe_pred - data) / scale, _FAILED_RESIDUAL)


def _resolve_fit_names(fit, terrain, distribution):
    """User names -> (canonical names, (owner, path) targets), or a ValueError."""
    table = _parameter_names(terrain, distribution)
    aliases = dict((name, name) for name in table)
    for name, (owner, path) in table.items():
        aliases.setdefault(f"{owner}.{path}", name)
    if isinstance(terrain, WongSnow) and distribution is None:
        allowed_txt = f"{WHEEL_PARAMETERS}"
    else:
        allowed_txt = (
            f"{tuple(table)} (for {type(terrain).__name__}"
            + ("" if distribution is None else f" with {type(distribution).__name__}")
            + "; the prefixed forms 'terrain.<name>' / 'distribution.<name>' work too)"
        )
    if isinstance(fit, str):
        fit = (fit,)
    given = tuple(fit)
    if not given:
        raise ValueError(f"fit must name at least one of {allowed_txt}")
    unknown = [nm for nm in given if nm not in aliases]
    if unknown:
        raise ValueError(f"unknown parameter name(s) {unknown} in fit; allowed: {allowed_txt}")
    names = tuple(aliases[nm] for nm in given)
    if len(set(names)) != len(names):
        raise ValueError(f"fit names a parameter twice: {list(given)}")
    return names, tuple(table[nm] for nm in names)


def fit_wheel(
    wheel: RigidWheel,
    snow: Terrain,
    load: Float[ArrayLike, " m"],
    slip: Float[ArrayLike, " m"],
    *,
    sinkage: Float[ArrayLike, " m"] | None = None,
    drawbar_pull: Float[ArrayLike, " m"] | None = None,
    motion_resistance: Float[ArrayLike, " m"] | None = None,
    fit: Sequence[str] = ("p_w", "z_w", "tan_phi"),
    shear: str = "classic",
    scale: dict[str, float] | None = None,
    max_steps: int = 100,
    nodes_per_panel: int | None = None,
    solve_max_steps: int = 64,
    distribution: WongReece | None = None,
) -> FitResult:
    """Fit terrain (and stress-distribution) parameters to wheel measurements through
    the equilibrium (4.14).

    For each data point (load F_z, slip i) the model is `snowjax.solve_wheel`: the entry
    angle with W(θ0) = F_z (4.14), then sinkage (4.15), motion resistance (4.16) and
    drawbar pull (2.10), on any terrain (`WongSnow`, `BekkerSoil`, `ReeceSoil`,
    `LayeredSnow`) with the front-region stresses (`distribution=None`) or Wong & Reece's
    distribution.  All points are solved in one vmapped call per residual evaluation,
    and `optimistix.least_squares` (Levenberg–Marquardt) differentiates straight through
    that root find with the implicit function theorem.

    **Parameter names** (`fit=`): every array leaf of the terrain and of the
    distribution, by field path — `WongSnow`: `p_w`, `z_w`, `cohesion`, `tan_phi`,
    `shear_modulus`; `BekkerSoil`: `n`, `k_c`, `k_phi`, `cohesion`, `tan_phi`,
    `shear_modulus`; `ReeceSoil`: `n`, `k_c_prime`, `k_phi_prime`, `unit_weight`,
    `cohesion`, `tan_phi`, `shear_modulus`; `LayeredSnow`: `top.p_w`, ...,
    `bottom.shear_modulus` (dotted: the nested layers) and `ice_failure_pressure`;
    `WongReece`: `c1`, `c2`, `c3`.  `distribution.c1` / `terrain.k_phi` (prefixed) are
    accepted too, and are the only form of a name both objects hold.
    `fit_parameter_names(terrain, distribution)` lists them; an unknown name raises a
    `ValueError` that lists them.  `FitResult.params` uses the unprefixed names.

    **Fitted variables.**  Parameters that are never negative — `p_w`, `z_w`,
    `cohesion`, `tan_phi`, `shear_modulus`, `n`, `unit_weight`, `ice_failure_pressure`
    (`LOG_SPACE_PARAMETERS`) — are fitted as u = ln θ (so they stay positive; their
    start value must be > 0).  The moduli that may be zero or negative (`k_c`, `k_phi`,
    `k_c_prime`, `k_phi_prime`: Bekker's k_c is negative for some soils) and the
    distribution's `c1`, `c2`, `c3` (c3 < 0 puts the exit behind the axle) are fitted
    linearly, θ = θ_start + s u with s = |θ_start|, or, for a zero start value, a
    typical magnitude (k_c 1e3 N/m^(n+1), k_phi 1e5 N/m^(n+2), k'_c and k'_φ 1,
    c1..c3 0.1).  The other parameters keep their values in `snow` / `distribution`,
    which also supply the start values.  Standard errors come back by the delta
    method, se(θ) = θ se(u) (log) or s se(u) (linear).  Iterates where the model is
    invalid (e.g. c1 + c2 i outside [0, 1)) get the failed-point residual below, so
    the optimiser steps back from them.

    **Residuals.**  For each measured quantity q, r = (model − data) / scale_q, stacked
    quantity-major (all sinkages, then all drawbar pulls, then all motion resistances).
    The default scale_q is the root-mean-square of the measured values, which weighs every
    quantity equally in relative terms whatever its unit and keeps residuals finite when
    drawbar pull crosses zero; pass `scale={"sinkage": σ_z, ...}` (m, N; a scalar or one
    value per point) with the measurement uncertainties for a weighted fit.
    `FitResult.residuals` and `sse` are these dimensionless scaled residuals;
    `info["predictions"]` holds the model values at the optimum in SI units.

    **Failed equilibria.**  A point whose solve fails at some iterate (status
    `NOT_CONVERGED`, `ENTRY_ANGLE_LIMIT` or `INVALID_INPUT`) gets a constant residual of
    10 (zero gradient) there, so the optimiser rejects steps into such regions instead of
    being poisoned by NaN.  If points still fail at the optimum they are left out of the
    standard errors and named in `warnings`; bottomed-out points (`BOTTOMED_OUT`, the
    wheel on the base: sinkage = z_w) are valid model values but carry no information
    on p_w, and are reported too.  `info["status"]` holds every point's status.

    **Arguments:**

    - `wheel`: `RigidWheel` (scalar diameter [m], width [m]).
    - `snow`: the terrain, any `snowjax.Terrain` with scalar leaves (SI units: Pa, m,
      N/m^(n+1), N/m^(n+2), N/m^3; see each class): start values of the fitted
      parameters and fixed values of the rest.  Every value must be valid for
      `solve_wheel`.
    - `load`: F_z [N] (> 0), one per data point (several loads allowed).
    - `slip`: driving slip i [-] in [-1, 1], same length.
    - `sinkage` [m], `drawbar_pull` [N], `motion_resistance` [N]: measured values, same
      length; at least one of them.
    - `fit`: names of the parameters to fit (see above; a non-empty subset of
      `fit_parameter_names(snow, distribution)`).
    - `shear`: `"classic"`, `"simplified"` or `"none"` (as `solve_wheel`;
      `"simplified"` only for `WongSnow` without a distribution).
    - `scale`: optional residual scale per quantity [m or N] (scalar or per point), see
      above.
    - `max_steps`: Levenberg–Marquardt step limit; `nodes_per_panel`, `solve_max_steps`:
      passed to `solve_wheel` (its quadrature nodes and Newton iteration limit).
    - `distribution`: `None` (the thesis's front-region stresses) or a
      `snowjax.WongReece` (c1, c2, c3 [-], scalar leaves) whose leaves can be fitted too.

    **Returns:** a `FitResult`; `info` has `snow` and `terrain` (the fitted terrain, of
    the type of `snow`), `distribution` (the fitted distribution or `None`),
    `transforms` (name -> `"log"` / `"linear"`), `predictions` (dict of model values at
    the optimum), `status`, `scale`.

    Use float64 (`jax.config.update("jax_enable_x64", True)`): the standard errors need
    derivatives accurate well beyond float32.  Each new combination of data length,
    fitted names, measured quantities, terrain / distribution type and shear model
    compiles once (about 10 s on a CPU); later fits of the same kind take a fraction of
    a second.
    """
    if not isinstance(wheel, RigidWheel):
        raise TypeError(f"wheel must be a snowjax.RigidWheel, got {type(wheel).__name__}")
    if not isinstance(snow, Terrain):
        raise TypeError(
            "snow must be a snowjax terrain (WongSnow, BekkerSoil, ReeceSoil, LayeredSnow), "
            f"got {type(snow).__name__}"
        )
    if distribution is not None and not isinstance(distribution, WongReece):
        raise TypeError(
            f"distribution must be None or a snowjax.WongReece, got {type(distribution).__name__}"
        )
    names, targets = _resolve_fit_names(fit, snow, distribution)
    if shear not in ("classic", "simplified", "none"):
        raise ValueError(f"shear must be 'classic', 'simplified' or 'none', got {shear!r}")
    _check_model(wheel, snow, distribution, shear)

    ld = _vector("load", load)
    sl = _vector("slip", slip)
    m = _same_length(load=ld, slip=sl)
    if (ld <= 0).any():
        raise ValueError(f"load must be > 0 N; got {ld[int(np.argmax(ld <= 0))]!r}")
    if (np.abs(sl) > 1).any():
        raise ValueError(f"slip must lie in [-1, 1]; got {sl[int(np.argmax(np.abs(sl) > 1))]!r}")
    measured = {"sinkage": sinkage, "drawbar_pull": drawbar_pull,
                "motion_resistance": motion_resistance}  # fmt: skip
    quantities = tuple(q for q in WHEEL_QUANTITIES if measured[q] is not None)
    if not quantities:
        raise ValueError("fit_wheel needs at least one of sinkage, drawbar_pull, motion_resistance")
    data = []
    for q in quantities:
        y = _vector(q, measured[q])
        _same_length(load=ld, **{q: y})
        data.append(y)
    data = np.stack(data)
    scale = {} if scale is None else dict(scale)
    unknown_scale = [k for k in scale if k not in quantities]
    if unknown_scale:
        raise ValueError(
            f"scale has entries {unknown_scale} for quantities not measured {quantities}"
        )
    scales = []
    for q, y in zip(quantities, data):
        s = np.asarray(scale.get(q, np.sqrt(np.mean(y**2))), dtype=float)
        if s.ndim > 1 or s.size not in (1, m):
            raise ValueError(f"scale[{q!r}] must be a scalar or have one value per data point")
        if not (np.isfinite(s).all() and (s > 0).all()):
            raise ValueError(f"the residual scale of {q} must be finite and > 0, got {s!r}")
        scales.append(np.broadcast_to(s, (m,)))
    scales = np.stack(scales)  # (quantities, points): one compilation for both forms
    m_total = m * len(quantities)
    if m_total <= len(names):
        raise ValueError(
            f"fit_wheel fits {len(names)} parameters and needs more than {len(names)} "
            f"measured values; got {m_total}"
        )

    # Start values: scalar, finite; log-space ones > 0 when fitted (>= 0 otherwise).
    fitted_paths = {owner: {p for o, p in targets if o == owner}
                    for owner in ("terrain", "distribution")}  # fmt: skip
    start: dict[str, dict[str, float]] = {"terrain": {}, "distribution": {}}
    objects = {"terrain": snow, "distribution": distribution}
    labels = {"terrain": "snow", "distribution": "distribution"}
    for owner, obj in objects.items():
        if obj is None:
            continue
        for path, value in _module_leaves(obj).items():
            v = np.asarray(value, dtype=float)
            if v.size != 1:
                raise ValueError(
                    f"{labels[owner]}.{path} must be a scalar for fit_wheel, got shape {v.shape}"
                )
            v = float(v.reshape(()))
            fitted = path in fitted_paths[owner]
            if _field(path) in LOG_SPACE_PARAMETERS:
                if not math.isfinite(v) or v < 0 or (fitted and v <= 0):
                    raise ValueError(
                        f"{labels[owner]}.{path} must be finite and "
                        f"{'> 0' if fitted else '>= 0'}, got {v!r}"
                        + (" (it is fitted in log space)" if fitted and v == 0 else "")
                    )
            elif not math.isfinite(v):
                raise ValueError(f"{labels[owner]}.{path} must be finite, got {v!r}")
            start[owner][path] = v
    for nm in ("diameter", "width"):
        v = np.asarray(getattr(wheel, nm), dtype=float)
        if v.size != 1 or not (np.isfinite(v).all() and (v > 0).all()):
            raise ValueError(f"wheel.{nm} must be a finite scalar > 0, got {v!r}")
    # The start values must be valid for solve_wheel at every data point.
    to_np = lambda x: np.asarray(x, dtype=float)  # noqa: E731
    with np.errstate(invalid="ignore", over="ignore"):
        rules = _wheel_checks(
            jax.tree_util.tree_map(to_np, wheel), jax.tree_util.tree_map(to_np, snow),
            None if distribution is None else jax.tree_util.tree_map(to_np, distribution),
            ld, sl, shear,
        )  # fmt: skip
    for rule, value, ok, allowed in rules:
        value = np.asarray(value, dtype=float)
        good = np.isfinite(value) & np.asarray(ok)
        if not good.all():
            shape = np.broadcast_shapes(good.shape, value.shape)
            first = np.broadcast_to(value, shape)[~np.broadcast_to(good, shape)].flat[0]
            raise ValueError(
                f"fit_wheel: the start values are not valid for solve_wheel: {rule} must be "
                f"finite and {allowed}; got {float(first)!r}"
            )

    dtype = jnp.result_type(float)
    wheel_a = RigidWheel(
        jnp.asarray(float(wheel.diameter), dtype), jnp.asarray(float(wheel.width), dtype)
    )
    if isinstance(snow, WongSnow):
        snow_a = WongSnow(**{k: jnp.asarray(v, dtype) for k, v in start["terrain"].items()})
    else:
        snow_a = _with_leaves(snow, {p: jnp.asarray(v, dtype) for p, v in start["terrain"].items()})
    dist_a = None
    if distribution is not None:
        dist_a = _with_leaves(
            distribution, {p: jnp.asarray(v, dtype) for p, v in start["distribution"].items()}
        )
    transforms = tuple("log" if _field(p) in LOG_SPACE_PARAMETERS else "linear"
                       for _, p in targets)  # fmt: skip
    theta0 = np.array([start[o][p] for o, p in targets])
    steps = np.array([
        abs(t0) if t0 != 0 else _LINEAR_SCALES.get(_field(p), 1.0)
        for t0, (_, p) in zip(theta0, targets)
    ])  # fmt: skip
    offsets = np.where(np.array([t == "linear" for t in transforms]), theta0, 0.0)
    steps = np.where(np.array([t == "linear" for t in transforms]), steps, 1.0)
    residual = _WheelResidual(
        names=names,
        quantities=quantities,
        shear=shear,
        nodes_per_panel=None if nodes_per_panel is None else int(nodes_per_panel),
        solve_max_steps=int(solve_max_steps),
        targets=targets,
        transforms=transforms,
    )
    u0 = np.array([
        math.log(t0) if t == "log" else 0.0 for t0, t in zip(theta0, transforms)
    ])  # fmt: skip
    args = (
        wheel_a,
        snow_a,
        dist_a,
        jnp.asarray(ld, dtype),
        jnp.asarray(sl, dtype),
        jnp.asarray(data, dtype),
        jnp.asarray(scales, dtype),
        jnp.asarray(offsets, dtype),
        jnp.asarray(steps, dtype),
    )
    u0 = jnp.asarray(u0, dtype)
    u, r, jac, (pred, status), ok, n_steps = _run(residual, u0, args, max_steps, 1e-10)

    warnings: list[str] = []
    if dtype != jnp.float64:
        warnings.append(
            "computed in float32: enable float64 (jax_enable_x64) for reliable standard errors."
        )
    if not ok:
        warnings.append(_not_converged(n_steps, max_steps))
    status = np.asarray(status).astype(int)
    good = (status == Status.CONVERGED) | (status == Status.BOTTOMED_OUT)
    for code in (Status.NOT_CONVERGED, Status.ENTRY_ANGLE_LIMIT, Status.INVALID_INPUT):
        bad = np.flatnonzero(status == code)
        if bad.size:
            warnings.append(
                f"{bad.size} of {m} data points have no equilibrium at the fitted parameters "
                f"(status {code.name}, points {bad.tolist()}); they are left out of the "
                "standard errors and the SSE. Check the start values and the data."
            )
    bottomed = np.flatnonzero(status == Status.BOTTOMED_OUT)
    if bottomed.size:
        warnings.append(
            f"{bottomed.size} of {m} data points bottom out at the fitted parameters "
            f"(status BOTTOMED_OUT, points {bottomed.tolist()}): the wheel rests on the "
            "base, sinkage = z_w, and these points say nothing about p_w."
        )
    rows = np.tile(good, len(quantities))
    r_used = np.where(rows, r, 0.0)
    unc = _gauss_newton_covariance(jac[rows], r[rows])
    is_log = np.array([t == "log" for t in transforms])
    theta = np.where(is_log, np.exp(np.where(is_log, u, 0.0)), offsets + steps * u)
    diameter = float(wheel.diameter)
    for k, nm in enumerate(names):
        if _field(targets[k][1]) == "z_w" and theta[k] >= diameter:
            warnings.append(
                f"{nm} = {theta[k]:.4g} m is not below the wheel diameter "
                f"{diameter:g} m: the data do not reach the base, and the model gives no "
                f"derivative with respect to {nm} there (fix {nm} or add data near the base)."
            )
    cov, se, corr = _propagate(unc, np.diag(np.where(is_log, theta, steps)))
    warnings += _diagnose(list(names), list(theta), se, corr, unc, list(names))

    final = {o: dict(start[o]) for o in start}
    for (owner, path), v in zip(targets, theta):
        final[owner][path] = float(v)
    if isinstance(snow, WongSnow):
        fitted_snow = WongSnow(**final["terrain"])
    else:
        fitted_snow = _with_leaves(
            snow, {p: jnp.asarray(v, dtype) for p, v in final["terrain"].items()}
        )
    fitted_dist = None
    if distribution is not None:
        fitted_dist = _with_leaves(
            distribution, {p: jnp.asarray(v, dtype) for p, v in final["distribution"].items()}
        )
    q_txt = ", ".join(quantities)
    model_txt = ""
    if not (isinstance(snow, WongSnow) and distribution is None):
        model_txt = f", {type(snow).__name__}" + (
            "" if distribution is None else f" with {type(distribution).__name__}"
        )
    return FitResult(
        params={nm: float(v) for nm, v in zip(names, theta)},
        stderr={nm: float(s) for nm, s in zip(names, se)},
        sse=float(np.sum(r_used**2)),
        residuals=r_used,
        warnings=warnings,
        units={nm: _PARAMETER_UNITS.get(_field(p), "") for nm, (_, p) in zip(names, targets)},
        covariance=cov,
        correlation=corr,
        condition_number=unc.cond,
        dof=unc.dof,
        success=ok,
        num_steps=n_steps,
        info={
            "title": f"Wheel calibration through the equilibrium (4.14): {m} points "
            f"({q_txt}), shear={shear!r}{model_txt}",
            "snow": fitted_snow,
            "terrain": fitted_snow,
            "distribution": fitted_dist,
            "transforms": dict(zip(names, transforms)),
            "predictions": {q: np.asarray(pred[k]) for k, q in enumerate(quantities)},
            "status": status,
            "scale": {q: scales[k].copy() for k, q in enumerate(quantities)},
            "quantities": quantities,
            "sse_unit": "(scaled residuals, dimensionless)",
        },
    )
