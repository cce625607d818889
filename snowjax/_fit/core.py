"""The least-squares core of the calibration fits: one solver, one result, one uncertainty path.

Each fit (`plate`, `tire`, `wheel`) is a model on this core: a residual function
`residual(u, args) -> (r, aux)` of the fitted variables u, a `Transform` from u to the
natural parameters θ, and the names of θ.  The core

- minimises Σ r² with `optimistix.least_squares` and `optimistix.LevenbergMarquardt`
  (`least_squares`), returning r, the Jacobian J = ∂r/∂u and the auxiliary output at the
  optimum;
- turns J and r into the covariance, standard errors, correlations, condition number,
  degrees of freedom and warnings of a block of named parameters (`estimate`);
- assembles the `FitResult` from one or more such blocks (`fit_result`).

**Uncertainty.**  With J the Jacobian of the (weighted) residual vector r with respect to
the fitted variables u at the optimum, m residuals and p fitted variables, the covariance
is the Gauss–Newton estimate `Cov(u) = s² (JᵀJ)⁻¹` with `s² = SSE / (m − p)`.  It is
computed from the SVD of J with unit-norm columns; a (numerically) singular J makes the
standard error of every parameter in its null space `inf`.  Parameters fitted through a
transform θ = T(u) (log space for positivity, a shift for Wong's z_w, a plain scale
elsewhere) are transformed back by the delta method, `Cov(θ) = D Cov(u) Dᵀ` with
`D = ∂θ/∂u` — exact for the linearised model, so e.g. a log-space fit gives the same
standard errors as a direct fit at the same optimum (`se(θ) = θ · se(ln θ)`).  Derived
parameters (a combined modulus, a dimensionless one) are further rows of D.

**Failures.**  The solver never sees a non-finite number from the model: a residual that
is NaN or inf at an iterate is replaced by a constant penalty (`NONFINITE_RESIDUAL`, 1e3,
zero gradient; the residuals of every fit are scaled to order one), so Levenberg–Marquardt
rejects a step into a region where the model cannot be evaluated and can start in one,
and a non-finite derivative becomes a zero Jacobian entry.  A fit that still ends without
a usable optimum raises a `ValueError` instead of returning a result: a residual that is
not finite at the end (a non-finite SSE), fewer valid residuals than fitted parameters in
a block, or a model whose own linear solves received non-finite values
(`NonFiniteModelError`).

**Warnings** (in `FitResult.warnings`): a parameter whose standard error exceeds its
magnitude; a pair of fitted parameters with |correlation| > 0.95; a column-scaled
Jacobian with condition number > 1e4; a singular Jacobian (not identifiable); no degrees
of freedom left; an optimiser that stopped without converging; and fit-specific ones
(a single plate size for Bekker/Reece; a coefficient at its bound; failed or bottomed-out
wheel equilibria).
"""

from __future__ import annotations

import contextlib
import dataclasses
import logging
import math
from collections.abc import Callable, Mapping, Sequence
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
import optimistix as optx
from numpy.typing import ArrayLike

from .._constants import DEFAULT_SHEAR_MODULUS
from .._terrain.bekker import BekkerSoil
from .._terrain.wong import WongSnow

__all__ = [
    "FitResult",
    "Transform",
    "Solution",
    "Estimate",
    "NonFiniteModelError",
    "least_squares",
    "check_max_steps",
    "estimate",
    "fit_result",
    "CORRELATION_LIMIT",
    "CONDITION_LIMIT",
    "NONFINITE_RESIDUAL",
]

# Diagnostic thresholds (documented in the module docstring).
CORRELATION_LIMIT = 0.95
CONDITION_LIMIT = 1e4
# A singular value below this fraction of the largest one counts as zero.
_RANK_TOL = 1e-10
# Residual given to a non-finite model value at an iterate (constant, zero gradient): far
# above the residuals of the fits, which are scaled to order one, so a step that makes a
# value non-finite always raises the loss and is rejected.
NONFINITE_RESIDUAL = 1e3


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
        from .plate import _bekker_soil

        return _bekker_soil(self, cohesion, tan_phi, shear_modulus, assume)

    def wong_snow(
        self, cohesion: float, tan_phi: float, *, shear_modulus: float = DEFAULT_SHEAR_MODULUS
    ) -> WongSnow:
        """The `WongSnow` of a Wong plate fit (`fit_plate_sinkage(law="wong")`).

        Wong's law (2.3) does not depend on the plate size, so p_w and z_w carry over to
        the wheel as they are.  **Arguments:** `cohesion` c [Pa] (>= 0), `tan_phi` [-]
        (>= 0), `shear_modulus` K [m] (> 0; default 10 mm).  **Returns:** `WongSnow`.
        """
        from .plate import _wong_snow

        return _wong_snow(self, cohesion, tan_phi, shear_modulus)

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


# ---------------------------------------------------------------------------------------
# Parameter transform
# ---------------------------------------------------------------------------------------


class Transform(NamedTuple):
    """The natural parameters θ of the fitted variables u, one of two forms per variable.

    - log space (`log` true): θ = scale · (shift + eᵘ) > scale · shift.  With shift 0 and
      scale 1 this is θ = eᵘ, which keeps a parameter positive; Wong's z_w is
      z_max (1 + eᵘ) > z_max (shift 1, scale z_max).
    - linear: θ = shift + scale · u, a variable scaled to order one (θ = θ_start + s u,
      or θ = s u).  A scale of 0 holds the variable at its shift (an active bound).

    `shift` and `scale` are per variable (scale in the unit of θ; shift in the unit of θ
    for linear variables, of θ / scale in log space).  The transform is a pytree of arrays
    that travels in the residual's `args`, so new values reuse the compiled fit.
    """

    log: Any
    shift: Any
    scale: Any

    @classmethod
    def make(cls, log: ArrayLike, shift: ArrayLike = 0.0, scale: ArrayLike = 1.0) -> Transform:
        """NumPy arrays (bool, float64) of the length of `log`; scalars broadcast."""
        lg = np.asarray(log, dtype=bool).reshape(-1)
        size = lg.shape
        return cls(
            log=lg,
            shift=np.broadcast_to(np.asarray(shift, dtype=float), size).copy(),
            scale=np.broadcast_to(np.asarray(scale, dtype=float), size).copy(),
        )

    def cast(self, dtype) -> Transform:
        """The same transform as JAX arrays of a floating `dtype` (for `args`)."""
        return Transform(
            log=jnp.asarray(self.log, dtype=bool),
            shift=jnp.asarray(self.shift, dtype),
            scale=jnp.asarray(self.scale, dtype),
        )

    def __call__(self, u):
        """θ(u) inside a residual (JAX); the exponential of linear variables is not taken."""
        e = jnp.exp(jnp.where(self.log, u, 0.0))
        return jnp.where(self.log, self.scale * (self.shift + e), self.shift + self.scale * u)

    def values(self, u) -> np.ndarray:
        """θ(u) at the optimum, NumPy float64."""
        log, shift, scale = self._numpy()
        u = np.asarray(u, dtype=float)
        e = np.exp(np.where(log, u, 0.0))
        return np.where(log, scale * (shift + e), shift + scale * u)

    def jacobian(self, u) -> np.ndarray:
        """D = ∂θ/∂u (diagonal: scale · eᵘ in log space, scale otherwise), NumPy float64."""
        log, _, scale = self._numpy()
        u = np.asarray(u, dtype=float)
        return np.diag(scale * np.where(log, np.exp(np.where(log, u, 0.0)), 1.0))

    def _numpy(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return (
            np.asarray(self.log, dtype=bool),
            np.asarray(self.shift, dtype=float),
            np.asarray(self.scale, dtype=float),
        )


# ---------------------------------------------------------------------------------------
# The solver
# ---------------------------------------------------------------------------------------


@jax.custom_vjp
def _finite_cotangent(x):
    """Identity whose backward pass replaces non-finite cotangents by 0.

    A derivative the model cannot provide (e.g. the wheel's with respect to z_w once z_w
    exceeds the wheel diameter, where the base angle arccos(1 − 2 z_w/D) is clipped)
    then shows up as a zero Jacobian column — "not identifiable" in the diagnostics —
    instead of a NaN that would stop the Levenberg–Marquardt linear solves.
    """
    return x


def _finite_cotangent_fwd(x):
    return x, None


def _finite_cotangent_bwd(_, ct):
    return (jnp.where(jnp.isfinite(ct), ct, 0.0),)


_finite_cotangent.defvjp(_finite_cotangent_fwd, _finite_cotangent_bwd)


def _guarded(residual):
    """`residual` with finite values and derivatives: (r, aux) -> (r', (aux, finite)).

    r' is r where it is finite and `NONFINITE_RESIDUAL` (no gradient) elsewhere;
    `finite` marks the residuals that were finite.  Non-finite entries of the gradient
    with respect to u become 0 (`_finite_cotangent`).
    """

    def fn(u, args):
        r, aux = residual(_finite_cotangent(u), args)
        finite = jnp.isfinite(r)
        return jnp.where(finite, r, NONFINITE_RESIDUAL), (aux, finite)

    return fn


def _least_squares_impl(residual, max_steps, tol, u0, args):
    """Levenberg–Marquardt on `residual(u, args) -> (r, aux)`, guarded by `_guarded`.

    Returns the optimum u, and r, J = ∂r/∂u, aux and the mask of finite residuals *at
    that optimum* (the solver's last accepted state, so no second trace of the model is
    needed).  The Jacobian is materialised by reverse mode (`jac="bwd"`): with forward
    mode optimistix evaluates its zero-initialised linearisation on the first step, which
    makes the implicit JVP of a nested root find (the wheel equilibrium) see a zero
    operator.
    """
    solver = optx.LevenbergMarquardt(rtol=tol, atol=tol)
    sol = optx.least_squares(
        _guarded(residual),
        solver,
        u0,
        args,
        options=dict(jac="bwd"),
        has_aux=True,
        max_steps=max_steps,
        throw=False,
    )
    state = sol.state
    aux, finite = state.aux
    return (
        sol.value,
        state.f_info.residual,
        state.f_info.jac.as_matrix(),
        aux,
        finite,
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


@dataclasses.dataclass(frozen=True)
class Solution:
    """The optimum of a least-squares problem, as NumPy values.

    - `u`: fitted variables; `residual`: r(u), NaN where the model was not finite;
      `jacobian`: J = ∂r/∂u (m × p).
    - `aux`: the residual function's auxiliary output at u (NumPy leaves).
    - `converged`: whether Levenberg–Marquardt met its tolerance; `num_steps`, `max_steps`.
    """

    u: np.ndarray
    residual: np.ndarray
    jacobian: np.ndarray
    aux: Any
    converged: bool
    num_steps: int
    max_steps: int

    @property
    def warnings(self) -> list[str]:
        """The warning of an optimiser that stopped short (empty when it converged)."""
        if self.converged:
            return []
        return [
            f"Levenberg-Marquardt stopped without meeting its tolerance after "
            f"{self.num_steps} steps (max_steps = {self.max_steps}); the estimates may not "
            "be the optimum."
        ]


class NonFiniteModelError(ValueError):
    """The model's own linear solves (a nested root find's implicit derivative) received
    NaN or inf during a fit, so Levenberg–Marquardt could not continue."""


class _DropCallbackFailures(logging.Filter):
    """Drops JAX's log record of a failed host callback (the traceback it prints)."""

    def filter(self, record: logging.LogRecord) -> bool:
        return "pure_callback failed" not in record.getMessage()


@contextlib.contextmanager
def _quiet_callback_failures():
    """Inside: a failing `error_if` callback raises without JAX also logging its traceback.

    The error itself still propagates (with the callback's message); `least_squares`
    turns the expected one (non-finite model values) into a `NonFiniteModelError`.
    """
    logger = logging.getLogger("jax._src.callback")
    drop = _DropCallbackFailures()
    logger.addFilter(drop)
    try:
        yield
    finally:
        logger.removeFilter(drop)


def check_max_steps(max_steps) -> int:
    """`max_steps` as an int >= 1, or a ValueError naming it (a bool is not a count)."""
    if isinstance(max_steps, (bool, np.bool_)) or not isinstance(max_steps, (int, np.integer)):
        raise ValueError(
            f"max_steps must be an integer >= 1 (Levenberg-Marquardt steps), got {max_steps!r}"
        )
    if max_steps < 1:
        raise ValueError(
            f"max_steps must be an integer >= 1 (Levenberg-Marquardt steps), got {max_steps}"
        )
    return int(max_steps)


def least_squares(
    residual: Callable[[Any, Any], tuple[Any, Any]],
    u0,
    args,
    *,
    max_steps: int,
    tol: float,
) -> Solution:
    """Minimise Σ r(u, args)² from `u0` with Levenberg–Marquardt (rtol = atol = `tol`).

    `residual` is a hashable callable (an `equinox.Module` with static fields): it is a
    static argument of the compiled solver, so each distinct residual — and each new
    shape of `u0` and `args` — compiles once.  Non-finite residuals and derivatives are
    kept away from the solver (see the module docstring); the returned `residual` is NaN
    where the model was not finite at the optimum.

    **Raises:** `ValueError` for `max_steps` < 1; `NonFiniteModelError` (a `ValueError`)
    when the model's own linear solves received non-finite values.
    """
    steps_limit = check_max_steps(max_steps)
    fn = _least_squares_cpu if jax.default_backend() == "cpu" else _least_squares_default
    try:
        with _quiet_callback_failures():
            u, r, jac, aux, finite, ok, steps = jax.block_until_ready(
                fn(residual, steps_limit, float(tol), u0, args)
            )
    except (RuntimeError, ValueError) as err:
        # lineax's error_if inside the compiled solve: a JaxRuntimeError, or a plain
        # ValueError with the same text when the executable was already compiled.
        if "non-finite" not in str(err):
            raise
        raise NonFiniteModelError(
            "the model gave non-finite values (NaN or inf) to one of its own linear solves "
            "during the fit, so Levenberg-Marquardt could not continue: the start values "
            "or the data are outside the range where the model can be evaluated"
        ) from None
    to_np = lambda x: np.asarray(x, dtype=float)
    return Solution(
        u=to_np(u),
        residual=np.where(np.asarray(finite, bool), to_np(r), np.nan),
        jacobian=to_np(jac),
        aux=jax.tree_util.tree_map(np.asarray, aux),
        converged=bool(ok),
        num_steps=int(steps),
        max_steps=steps_limit,
    )


# ---------------------------------------------------------------------------------------
# Covariance, standard errors and identifiability
# ---------------------------------------------------------------------------------------


@dataclasses.dataclass
class _Uncertainty:
    cov_u: np.ndarray  # covariance of the fitted variables u
    cond: float
    dof: int
    s2: float
    unidentified: np.ndarray  # bool per fitted variable


def _norms(a: np.ndarray) -> np.ndarray:
    """2-norms of the columns of `a`, scaled by their largest entry so that squaring
    neither underflows nor overflows (residuals of 1e-300 Pa have a norm, not 0)."""
    top = np.max(np.abs(a), axis=0) if a.shape[0] else np.zeros(a.shape[1:])
    safe = np.where(top > 0, top, 1.0)
    return top * np.linalg.norm(a / safe, axis=0)


def _gauss_newton_covariance(jac: np.ndarray, residual: np.ndarray) -> _Uncertainty:
    """`s² (JᵀJ)⁻¹`, s² = SSE/(m − p), via the SVD of J with unit-norm columns.

    Computed as `(s / |J_i|)(s / |J_j|) (J_sᵀJ_s)⁻¹_ij` with J_s the column-normalised J,
    so residuals and Jacobians in tiny or huge units do not underflow or overflow.
    """
    m, p = jac.shape
    dof = m - p
    s = float(_norms(residual.reshape(-1, 1))[0]) / math.sqrt(dof) if dof > 0 else math.nan
    s2 = s * s
    bad_col = ~np.isfinite(jac).all(axis=0)  # a derivative the model could not provide
    jac = np.where(np.isfinite(jac), jac, 0.0)
    norms = _norms(jac)
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
    w = s / safe
    cov_u = cov_scaled * np.outer(w, w)
    cov_u[unidentified, :] = np.inf
    cov_u[:, unidentified] = np.inf
    return _Uncertainty(cov_u=cov_u, cond=cond, dof=dof, s2=s2, unidentified=unidentified)


def _propagate(unc: _Uncertainty, dtheta_du: np.ndarray, held: np.ndarray):
    """Delta method: Cov(θ) = D Cov(u) Dᵀ; returns (cov, stderr, correlation).

    Parameters marked `held` (at a bound, not fitted) get `nan` rows and columns.
    """
    d = np.asarray(dtheta_du, float)
    cov_u = unc.cov_u
    finite = ~unc.unidentified
    cf = cov_u[np.ix_(finite, finite)]
    df = d[:, finite]
    with np.errstate(invalid="ignore", over="ignore"):  # inf: an error too large for float64
        cov = df @ cf @ df.T
    # A parameter that depends on an unidentifiable variable has an infinite error.
    depends_bad = (np.abs(d[:, ~finite]) > 0).any(axis=1)
    cov[depends_bad, :] = np.inf
    cov[:, depends_bad] = np.inf
    cov[held, :] = np.nan
    cov[:, held] = np.nan
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


@dataclasses.dataclass(frozen=True)
class Estimate:
    """A block of named parameters with their uncertainty and diagnostics.

    - `names`, `values`: the parameters θ (fitted, derived and held ones).
    - `covariance`, `stderr`, `correlation`: over `names`, in their order.
    - `condition_number`, `dof`: of the Jacobian of the block's fitted variables.
    - `warnings`: the block's notes followed by its diagnostics.
    """

    names: tuple[str, ...]
    values: np.ndarray
    covariance: np.ndarray
    stderr: np.ndarray
    correlation: np.ndarray
    condition_number: float
    dof: int
    warnings: list[str]


def estimate(
    jac: np.ndarray,
    residual: np.ndarray,
    names: Sequence[str],
    values: Sequence[float] | np.ndarray,
    d: np.ndarray,
    *,
    fitted: Sequence[str],
    held: Sequence[bool] | np.ndarray | None = None,
    prefix: str = "",
    notes: Sequence[str] = (),
) -> Estimate:
    """Covariance, standard errors and warnings of the parameters θ of one block.

    **Arguments:**

    - `jac`: J = ∂r/∂u of the block's residuals with respect to its fitted variables
      (m × p), in the units of `residual` (the units the fit reports).
    - `residual`: the block's residuals r (m) at the optimum.
    - `names`, `values`: the parameters θ (k of them).
    - `d`: D = ∂θ/∂u (k × p); derived parameters are extra rows, held ones zero rows.
    - `fitted`: the names of the fitted parameters (checked for correlation).
    - `held`: bool per parameter held at a bound: `nan` standard error and correlations.
    - `prefix`: put before every diagnostic (e.g. the equation of a tire load function).
    - `notes`: model warnings that come before the diagnostics.

    **Raises:** `ValueError` when a residual is not finite (the SSE would be NaN or inf)
    or there are fewer residuals than fitted variables (p).
    """
    names = tuple(names)
    _check_usable(np.asarray(residual, dtype=float), np.shape(jac)[1], prefix)
    vals = np.asarray(values, dtype=float)
    held_mask = np.zeros(len(names), bool) if held is None else np.asarray(held, bool)
    unc = _gauss_newton_covariance(jac, residual)
    cov, stderr, corr = _propagate(unc, d, held_mask)
    diagnostics = _diagnose(list(names), list(vals), stderr, corr, unc, list(fitted), prefix)
    return Estimate(
        names=names,
        values=vals,
        covariance=cov,
        stderr=stderr,
        correlation=corr,
        condition_number=unc.cond,
        dof=unc.dof,
        warnings=[*notes, *diagnostics],
    )


def _check_usable(residual: np.ndarray, p: int, prefix: str = "") -> None:
    """A ValueError unless every residual is finite and there are at least `p` of them."""
    pre = f"{prefix}: " if prefix else ""
    m = residual.size
    bad = int(np.sum(~np.isfinite(residual)))
    if bad:
        raise ValueError(
            f"{pre}the fit failed: {bad} of {m} residuals are not finite (NaN or inf) at the "
            "end of the fit, so the sum of squared residuals is not finite"
        )
    if m < p:
        raise ValueError(
            f"{pre}the fit failed: {m} valid residual(s) for {p} fitted parameter(s); a fit "
            "needs at least as many valid data as parameters"
        )


def _block_diag(blocks: Sequence[np.ndarray]) -> np.ndarray:
    size = sum(b.shape[0] for b in blocks)
    out = np.zeros((size, size))
    k = 0
    for b in blocks:
        s = b.shape[0]
        out[k : k + s, k : k + s] = b
        k += s
    return out


def fit_result(
    solution: Solution,
    parts: Sequence[Estimate],
    *,
    residuals: np.ndarray,
    warnings: Sequence[str],
    units: Mapping[str, str],
    info: dict[str, Any],
) -> FitResult:
    """The `FitResult` of a solved fit from its parameter blocks.

    Blocks (independent load functions, say) are combined block-diagonally: covariance
    and correlation zero between blocks, the largest condition number and the fewest
    degrees of freedom.  `warnings` come first (the model's, with `solution.warnings`
    where the model places them), then each block's.  `sse` is Σ `residuals`².

    **Raises:** `ValueError` when the SSE is not finite.
    """
    with np.errstate(over="ignore", invalid="ignore"):
        sse = float(np.sum(residuals**2))
    if not math.isfinite(sse):
        raise ValueError(f"the fit failed: the sum of squared residuals is {sse}")
    names = [n for part in parts for n in part.names]
    values = [float(v) for part in parts for v in part.values]
    stderr = [float(s) for part in parts for s in part.stderr]
    return FitResult(
        params=dict(zip(names, values)),
        stderr=dict(zip(names, stderr)),
        sse=sse,
        residuals=residuals,
        warnings=[*warnings, *(w for part in parts for w in part.warnings)],
        units={k: units.get(k, "") for k in names},
        covariance=_block_diag([part.covariance for part in parts]),
        correlation=_block_diag([part.correlation for part in parts]),
        condition_number=float(max(part.condition_number for part in parts)),
        dof=int(min(part.dof for part in parts)),
        success=solution.converged,
        num_steps=solution.num_steps,
        info=info,
    )
