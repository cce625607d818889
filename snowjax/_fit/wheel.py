"""Wheel calibration through the equilibrium (4.14) on the least-squares core.

`fit_wheel` fits any subset of the parameters of any terrain (`WongSnow`, `BekkerSoil`,
`ReeceSoil`, `LayeredSnow`) and of the Wong–Reece stress distribution to measured
sinkage and/or drawbar pull / motion resistance versus slip at one or more loads,
straight through the vmapped wheel equilibrium `solve_wheel` (eq. 4.14); its gradients
come from the implicit function theorem at the root, not from unrolled iterations.
`fit_parameter_names` lists the names a terrain and distribution offer; parameters that
are never negative are fitted in log space, the others linearly, as the `ParameterInfo` on
each field says (`snowjax.parameter`).

Equation numbers refer to Sankapalli (2004), *Predictive semi-empirical analysis for
tire/snow interaction*, MSc thesis, University of Alaska Fairbanks.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import ArrayLike, Float

from .._leaves import (
    ParameterInfo,
    _module_leaves,
    _parameter_infos,
    _parameter_names,
    _with_leaves,
)
from .._terrain.base import Terrain, _terrain_parameter_infos
from .._terrain.wong import WongSnow
from .._wheel.distribution import FrontRegion, _as_distribution
from .._wheel.equilibrium import Status, solve_wheel
from .._wheel.geometry import AbstractWheel
from .._wheel.inputs import _check_model
from .._wheel.inputs import _checks as _wheel_checks
from .._wheel.lateral import Lateral
from .._wheel.model import ContactModel, _as_model, _takes_model
from .._wheel.shear_law import AbstractShearLaw
from .core import (
    FitResult,
    NonFiniteModelError,
    Transform,
    check_max_steps,
    estimate,
    fit_result,
    least_squares,
)
from .data import rms, same_length, vector

__all__ = [
    "fit_wheel",
    "fit_parameter_names",
    "WHEEL_PARAMETERS",
    "WHEEL_QUANTITIES",
]

WHEEL_PARAMETERS = ("p_w", "z_w", "cohesion", "tan_phi", "shear_modulus")
WHEEL_QUANTITIES = ("sinkage", "drawbar_pull", "motion_resistance", "lateral_force")
# Scaled residual given to data points whose equilibrium failed at the current iterate
# (constant, zero gradient): it raises the loss, so Levenberg–Marquardt rejects a step
# into a region where the model cannot be evaluated.
_FAILED_RESIDUAL = 10.0


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


# ---------------------------------------------------------------------------------------
# The model: residual, names, transform
# ---------------------------------------------------------------------------------------


class _WheelResidual(eqx.Module):
    """Scaled residuals (model − data) / scale of the chosen quantities, quantity-major.

    θ = transform(u): e^u for log-space parameters, θ_start + s u for the others.
    """

    names: tuple = eqx.field(static=True)
    quantities: tuple = eqx.field(static=True)
    shear: AbstractShearLaw = eqx.field(static=True)
    nodes_per_panel: int | None = eqx.field(static=True)
    solve_max_steps: int = eqx.field(static=True)
    accuracy: str = eqx.field(static=True, default="reference")
    # (owner, field path) of each fitted variable; owner "terrain", "distribution",
    # "lateral" or "wheel".
    targets: tuple = eqx.field(static=True, default=())

    def __call__(self, u, args):
        wheel, snow, distribution, lateral, load, slip, slip_angle, *rest = args
        data, scale, transform, terms = rest
        values = transform(u)
        new = {"terrain": {}, "distribution": {}, "lateral": {}, "wheel": {}}
        for i, (owner, path) in enumerate(self.targets):
            new[owner][path] = values[i]
        wheel = _with_leaves(wheel, new["wheel"])
        snow = _with_leaves(snow, new["terrain"])
        if distribution is not None:
            distribution = _with_leaves(distribution, new["distribution"])
        if lateral is not None:
            lateral = _with_leaves(lateral, new["lateral"])
        model = ContactModel(
            snow, distribution, self.shear, lateral, self.nodes_per_panel, terms, self.accuracy
        )
        st = solve_wheel(
            wheel, model, load, slip, slip_angle=slip_angle, max_steps=self.solve_max_steps
        )
        pred = jnp.stack([getattr(st, q) for q in self.quantities])
        return _masked_residual(pred, data, scale, st.status).reshape(-1), (pred, st.status)


def _masked_residual(pred, data, scale, status):
    """(pred − data) / scale where the equilibrium is valid; `_FAILED_RESIDUAL` elsewhere.

    `pred`, `data`, `scale`: (quantities, points); `status`: (points,).  Valid means
    `CONVERGED` or `BOTTOMED_OUT`.  Failed points get a constant (no gradient), and the
    NaN a failed solve may return never reaches the value or the Jacobian.
    """
    ok = ((status == Status.CONVERGED) | (status == Status.BOTTOMED_OUT))[None]
    safe_pred = jnp.where(ok, pred, data)
    return jnp.where(ok, (safe_pred - data) / scale, _FAILED_RESIDUAL)


def _lateral_names(lateral) -> dict[str, tuple[str, str]]:
    """`lateral.<field>` -> ("lateral", field) for the array leaves of a `Lateral`."""
    if lateral is None:
        return {}
    leaves = _module_leaves(lateral)
    return {f"lateral.{p}": ("lateral", p) for p, v in leaves.items() if v is not None}


def _wheel_names(wheel) -> dict[str, tuple[str, str]]:
    """`wheel.<field>` -> ("wheel", field) for the array leaves of a wheel that deflects
    (`DeflectingTire`: e.g. `wheel.carcass_pressure`); none for a rigid rim."""
    if wheel is None or not type(wheel).deflects:
        return {}
    return {f"wheel.{p}": ("wheel", p) for p in _module_leaves(wheel)}


def _resolve_fit_names(fit, terrain, distribution, lateral=None, wheel=None):
    """User names -> (canonical names, (owner, path) targets), or a ValueError."""
    table = {
        **_parameter_names(terrain, distribution),
        **_lateral_names(lateral),
        **_wheel_names(wheel),
    }
    aliases = dict((name, name) for name in table)
    for name, (owner, path) in table.items():
        aliases.setdefault(f"{owner}.{path}", name)
    if isinstance(terrain, WongSnow) and distribution is None and not _wheel_names(wheel):
        allowed_txt = f"{WHEEL_PARAMETERS}"
    else:
        allowed_txt = (
            f"{tuple(table)} (for {type(terrain).__name__}"
            + ("" if distribution is None else f" with {type(distribution).__name__}")
            + ("" if lateral is None else " and Lateral")
            + ("" if not _wheel_names(wheel) else f" on a {type(wheel).__name__}")
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


def _infos(objects) -> dict[tuple[str, str], ParameterInfo]:
    """(owner, field path) -> `ParameterInfo` of every declared parameter of the objects
    (a terrain's plain shear-strength fields get the standard one)."""
    return {
        (owner, path): info
        for owner, obj in objects.items()
        if obj is not None
        for path, info in (
            _terrain_parameter_infos(obj) if owner == "terrain" else _parameter_infos(obj)
        ).items()
    }


def _transform(targets, theta0, infos) -> Transform:
    """Log space (θ = eᵘ) for parameters whose `ParameterInfo.log_space` is set; θ = θ_start
    + s u for the others (and for leaves declared without a `ParameterInfo`).

    s = |θ_start|, or the parameter's typical magnitude (`ParameterInfo.scale`, else 1)
    for a zero start value.
    """
    is_log = np.array([t in infos and infos[t].log_space for t in targets])
    steps = np.array([
        abs(t0) if t0 != 0 else (infos[t].scale if t in infos else 1.0)
        for t0, t in zip(theta0, targets)
    ])  # fmt: skip
    return Transform.make(
        is_log, shift=np.where(is_log, 0.0, theta0), scale=np.where(is_log, 1.0, steps)
    )


def _unit(infos, target) -> str:
    """The unit of a leaf from its `ParameterInfo` ("-": dimensionless; "": unknown)."""
    info = infos.get(target)
    return "" if info is None else info.unit


# ---------------------------------------------------------------------------------------
# Checks of the data and the start values
# ---------------------------------------------------------------------------------------


def _start_models(wheel, snow, distribution, lateral, start, dtype):
    """(wheel, terrain, distribution, lateral law) at the start values, in `dtype`."""
    wheel_a = _rebuild(wheel, start["wheel"], dtype)
    if isinstance(snow, WongSnow):
        snow_a = WongSnow(**{k: jnp.asarray(v, dtype) for k, v in start["terrain"].items()})
    else:
        snow_a = _rebuild(snow, start["terrain"], dtype)
    dist_a = None if distribution is None else _rebuild(distribution, start["distribution"], dtype)
    lateral_a = None if lateral is None else _rebuild(lateral, start["lateral"], dtype)
    return wheel_a, snow_a, dist_a, lateral_a


def _valid_points(status, n_quantities: int, n_names: int) -> np.ndarray:
    """The points with an equilibrium at the end of the fit (converged or bottomed out);
    `ValueError` if they leave fewer valid values than fitted parameters."""
    m = len(status)
    good = (status == Status.CONVERGED) | (status == Status.BOTTOMED_OUT)
    n_valid = int(good.sum()) * n_quantities
    if n_valid < n_names:
        raise ValueError(
            f"fit_wheel: the fit failed: {m - int(good.sum())} of {m} data points have no "
            f"equilibrium at the end of the fit ({_status_summary(status)}), which leaves "
            f"{n_valid} valid value(s) for {n_names} fitted parameter(s); check the start "
            "values and the data"
        )
    return good


def _measured_quantities(measured) -> dict[str, Any]:
    """`fit_wheel`'s `measured` mapping, every quantity present (None where not
    measured); a `ValueError` names an unknown key."""
    if not isinstance(measured, Mapping):
        raise TypeError(
            'measured must be a mapping of quantity to values, e.g. {"sinkage": z}; got '
            f"{type(measured).__name__}"
        )
    unknown = [key for key in measured if key not in WHEEL_QUANTITIES]
    if unknown:
        raise ValueError(f"measured has unknown quantities {unknown}; known: {WHEEL_QUANTITIES}")
    return {q: measured.get(q) for q in WHEEL_QUANTITIES}


def _wheel_data(load, slip, measured, scale, slip_angle=None):
    """Checked loads [N], slips [-], measured quantities (quantities × points), scales,
    slip angles [rad] (or None)."""
    ld = vector("load", load)
    sl = vector("slip", slip)
    m = same_length(load=ld, slip=sl)
    sa = None
    if slip_angle is not None:
        sa = vector("slip_angle", slip_angle)
        same_length(load=ld, slip_angle=sa)
        if not (np.abs(sa) < np.pi / 2).all():
            bad = sa[int(np.argmax(~(np.abs(sa) < np.pi / 2)))]
            raise ValueError(f"slip_angle must lie in (-pi/2, pi/2) rad; got {bad!r}")
    if measured.get("lateral_force") is not None and sa is None:
        raise ValueError("lateral_force data need the slip_angle of every point")
    if (ld <= 0).any():
        raise ValueError(f"load must be > 0 N; got {ld[int(np.argmax(ld <= 0))]!r}")
    if (np.abs(sl) > 1).any():
        raise ValueError(f"slip must lie in [-1, 1]; got {sl[int(np.argmax(np.abs(sl) > 1))]!r}")
    quantities = tuple(q for q in WHEEL_QUANTITIES if measured[q] is not None)
    if not quantities:
        raise ValueError(
            "fit_wheel needs at least one of sinkage, drawbar_pull, motion_resistance, "
            "lateral_force"
        )
    rows = []
    for q in quantities:
        y = vector(q, measured[q])
        same_length(load=ld, **{q: y})
        rows.append(y)
    data = np.stack(rows)
    scale = {} if scale is None else dict(scale)
    unknown_scale = [k for k in scale if k not in quantities]
    if unknown_scale:
        raise ValueError(
            f"scale has entries {unknown_scale} for quantities not measured {quantities}"
        )
    scales = []
    for q, y in zip(quantities, data):
        s = np.asarray(scale.get(q, rms(y)), dtype=float)
        if s.ndim > 1 or s.size not in (1, m):
            raise ValueError(f"scale[{q!r}] must be a scalar or have one value per data point")
        if not (np.isfinite(s).all() and (s > 0).all()):
            raise ValueError(f"the residual scale of {q} must be finite and > 0, got {s!r}")
        scales.append(np.broadcast_to(s, (m,)))
    # (quantities, points): one compilation for both forms
    return ld, sl, m, quantities, data, np.stack(scales), sa


def _start_values(
    snow, distribution, targets, lateral=None, wheel=None
) -> dict[str, dict[str, float]]:
    """Every leaf as a float, owner -> path -> value: scalar, finite; log-space ones
    > 0 when fitted (>= 0 otherwise)."""
    owners = ("terrain", "distribution", "lateral", "wheel")
    fitted_paths = {owner: {p for o, p in targets if o == owner} for owner in owners}
    start: dict[str, dict[str, float]] = {owner: {} for owner in owners}
    objects = {"terrain": snow, "distribution": distribution, "lateral": lateral, "wheel": wheel}
    labels = {o: "snow" if o == "terrain" else o for o in owners}
    infos = _infos(objects)
    for owner, obj in objects.items():
        if obj is None:
            continue
        for path, value in _module_leaves(obj).items():
            if value is None:  # Lateral.shear_modulus None: the terrain's modulus
                continue
            v = np.asarray(value, dtype=float)
            if v.size != 1:
                raise ValueError(
                    f"{labels[owner]}.{path} must be a scalar for fit_wheel, got shape {v.shape}"
                )
            v = float(v.reshape(()))
            fitted = path in fitted_paths[owner]
            info = infos.get((owner, path))
            if info is not None and info.log_space:
                if not math.isfinite(v) or v < 0 or (fitted and v <= 0):
                    raise ValueError(
                        f"{labels[owner]}.{path} must be finite and "
                        f"{'> 0' if fitted else '>= 0'}, got {v!r}"
                        + (" (it is fitted in log space)" if fitted and v == 0 else "")
                    )
            elif not math.isfinite(v):
                raise ValueError(f"{labels[owner]}.{path} must be finite, got {v!r}")
            start[owner][path] = v
    return start


def _check_solvable(wheel, snow, distribution, ld, sl, shear) -> None:
    """The wheel's size, and the start values valid for solve_wheel at every data point."""
    for nm in ("diameter", "width"):
        v = np.asarray(getattr(wheel, nm), dtype=float)
        if v.size != 1 or not (np.isfinite(v).all() and (v > 0).all()):
            raise ValueError(f"wheel.{nm} must be a finite scalar > 0, got {v!r}")
    to_np = lambda x: np.asarray(x, dtype=float)
    with np.errstate(invalid="ignore", over="ignore"):
        rules = _wheel_checks(
            jax.tree_util.tree_map(to_np, wheel), jax.tree_util.tree_map(to_np, snow),
            jax.tree_util.tree_map(to_np, _as_distribution(distribution)),
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


def _rebuild(obj, values: dict[str, float], dtype):
    """`obj` with its leaves set to `values` (JAX arrays of `dtype`)."""
    return _with_leaves(obj, {p: jnp.asarray(v, dtype) for p, v in values.items()})


def _status_summary(status: np.ndarray) -> str:
    """'12 ENTRY_ANGLE_LIMIT, 3 CONVERGED': the count of each status, most frequent first."""
    codes, counts = np.unique(np.asarray(status).astype(int), return_counts=True)
    order = np.argsort(-counts, kind="stable")
    return ", ".join(f"{counts[k]} {Status(int(codes[k])).name}" for k in order)


@eqx.filter_jit
def _evaluate(residual, u, args):
    """`residual(u, args)`, compiled once per residual configuration and shapes."""
    return residual(u, args)


def _start_diagnosis(residual, u0, args, start, targets, m, infos) -> str:
    """'; at the start values (...) k of m data points have no equilibrium (...)', or ''.

    Lists the fitted and the held parameters; evaluated only after a failed fit (one more
    compilation of the forward model).
    """
    try:
        _, (_, status) = _evaluate(residual, jnp.asarray(u0), args)
    except Exception:  # the diagnosis is a courtesy: never hide the original error
        return ""
    status = np.asarray(status).astype(int)
    failed = int(np.sum((status != Status.CONVERGED) & (status != Status.BOTTOMED_OUT)))

    def listed(fitted: bool) -> str:
        return ", ".join(
            f"{path} = {v:.6g} {_unit(infos, (owner, path))}".removesuffix(" -").rstrip()
            for owner, leaves in start.items()
            for path, v in leaves.items()
            if ((owner, path) in targets) == fitted
        )

    held = listed(False)
    values = f"fitted: {listed(True)}" + (f"; held: {held}" if held else "")
    if not failed:
        return f"; at the start values ({values}) every data point has an equilibrium"
    return (
        f"; at the start values ({values}) {failed} of {m} data points have no "
        f"equilibrium ({_status_summary(status)})"
    )


def _status_warnings(status: np.ndarray, m: int) -> list[str]:
    """Warnings about failed and bottomed-out equilibria at the fitted parameters."""
    out = []
    for code in (Status.NOT_CONVERGED, Status.ENTRY_ANGLE_LIMIT, Status.INVALID_INPUT):
        bad = np.flatnonzero(status == code)
        if bad.size:
            out.append(
                f"{bad.size} of {m} data points have no equilibrium at the fitted parameters "
                f"(status {code.name}, points {bad.tolist()}); they are left out of the "
                "standard errors and the SSE. Check the start values and the data."
            )
    bottomed = np.flatnonzero(status == Status.BOTTOMED_OUT)
    if bottomed.size:
        out.append(
            f"{bottomed.size} of {m} data points bottom out at the fitted parameters "
            f"(status BOTTOMED_OUT, points {bottomed.tolist()}): the wheel rests on the "
            "base, sinkage = z_w, and these points say nothing about p_w."
        )
    return out


# ---------------------------------------------------------------------------------------
# The fit
# ---------------------------------------------------------------------------------------


def _fitted_parts(wheel, model, slip_angle):
    """(distribution, lateral) of `fit_wheel`'s model, the parts it fits beside the
    terrain (the wheel / shear law pair checked, `_check_model`): the front region as
    None (no leaves to fit), the lateral law `Lateral()` where a slip angle is given
    (None without)."""
    _check_model(wheel, model)
    distribution = None if isinstance(model.distribution, FrontRegion) else model.distribution
    if slip_angle is None:
        return distribution, None
    return distribution, Lateral() if model.lateral is None else model.lateral


def _fit_warnings(dtype, sol, status, m, names, targets, theta, diameter) -> list[str]:
    """`fit_wheel`'s warnings: float32, the solver's, the data points without an
    equilibrium (`status`), a fitted z_w [m] not below the wheel diameter [m]."""
    warnings: list[str] = []
    if dtype != jnp.float64:
        warnings.append(
            "computed in float32: enable float64 (jax_enable_x64) for reliable standard errors."
        )
    warnings += sol.warnings
    warnings += _status_warnings(status, m)
    for k, nm in enumerate(names):
        if _field(targets[k][1]) == "z_w" and theta[k] >= diameter:
            warnings.append(
                f"{nm} = {theta[k]:.4g} m is not below the wheel diameter "
                f"{diameter:g} m: the data do not reach the base, and the model gives no "
                f"derivative with respect to {nm} there (fix {nm} or add data near the base)."
            )
    return warnings


def _title(m, quantities, shear, snow, distribution) -> str:
    """The fit's title: its points, quantities, shear law and (other than Wong snow on the
    front region) terrain and distribution."""
    model_txt = ""
    if not (isinstance(snow, WongSnow) and distribution is None):
        model_txt = f", {type(snow).__name__}" + (
            "" if distribution is None else f" with {type(distribution).__name__}"
        )
    return (
        f"Wheel calibration through the equilibrium (4.14): {m} points "
        f"({', '.join(quantities)}), shear={shear.name!r}{model_txt}"
    )


def _fitted(models, start, targets, theta, dtype):
    """(terrain, distribution, lateral law, wheel) with the fitted values `theta` at
    `targets` and the start values elsewhere."""
    snow, distribution, lateral, wheel = models
    final = {o: dict(start[o]) for o in start}
    for (owner, path), v in zip(targets, theta):
        final[owner][path] = float(v)
    if isinstance(snow, WongSnow):
        fitted_snow = WongSnow(**final["terrain"])
    else:
        fitted_snow = _rebuild(snow, final["terrain"], dtype)
    fitted_dist = None
    if distribution is not None:
        fitted_dist = _rebuild(distribution, final["distribution"], dtype)
    fitted_lateral = None if lateral is None else _rebuild(lateral, final["lateral"], dtype)
    return fitted_snow, fitted_dist, fitted_lateral, _rebuild(wheel, final["wheel"], dtype)


@_takes_model(
    positional=5,
    **{q: f'measured={{"{q}": ...}}' for q in WHEEL_QUANTITIES},
)
def fit_wheel(
    wheel: AbstractWheel,
    snow: Terrain | ContactModel,
    load: Float[ArrayLike, " m"],
    slip: Float[ArrayLike, " m"],
    measured: Mapping[str, Float[ArrayLike, " m"]],
    *,
    fit: Sequence[str] = ("p_w", "z_w", "tan_phi"),
    scale: Mapping[str, Float[ArrayLike, "..."]] | None = None,
    slip_angle: Float[ArrayLike, " m"] | None = None,
    max_steps: int = 100,
    solve_max_steps: int = 64,
) -> FitResult:
    """Fit terrain (and stress-distribution) parameters to wheel measurements through
    the equilibrium (4.14).

    For each data point (load F_z, slip i) the model is `snowjax.solve_wheel`: the entry
    angle with W(θ0) = F_z (4.14), then sinkage (4.15), motion resistance (4.16) and
    drawbar pull (2.10), on any terrain (`WongSnow`, `BekkerSoil`, `ReeceSoil`,
    `LayeredSnow`) with the front-region stresses or Wong & Reece's distribution (the
    `ContactModel`'s).  All points are solved in one vmapped call per residual evaluation,
    and `optimistix.least_squares` (Levenberg–Marquardt) differentiates straight through
    that root find with the implicit function theorem.

    **Parameter names** (`fit=`): every array leaf of the terrain and of the
    distribution, by field path — `WongSnow`: `p_w`, `z_w`, `cohesion`, `tan_phi`,
    `shear_modulus`; `BekkerSoil`: `n`, `k_c`, `k_phi`, `cohesion`, `tan_phi`,
    `shear_modulus`; `ReeceSoil`: `n`, `k_c_prime`, `k_phi_prime`, `unit_weight`,
    `cohesion`, `tan_phi`, `shear_modulus`; `LayeredSnow`: `top.p_w`, ...,
    `bottom.shear_modulus` (dotted: the nested layers) and `ice_failure_pressure`;
    `WongReece`: `c1`, `c2`, `c3`.  `distribution.c1` / `terrain.k_phi` (prefixed) are
    accepted too, and are the only form of a name both objects hold.  A
    `DeflectingTire`'s leaves as `wheel.<field>` (`wheel.carcass_pressure`,
    `wheel.inflation_pressure`, ...).
    `fit_parameter_names(terrain, distribution)` lists the terrain's and distribution's;
    an unknown name raises a `ValueError` that lists them.  `FitResult.params` uses the
    unprefixed names.

    **Fitted variables.**  As each field's `ParameterInfo` says (`snowjax.parameter`):
    parameters that are never negative — `p_w`, `z_w`, `cohesion`, `tan_phi`,
    `shear_modulus`, `n`, `unit_weight`, `ice_failure_pressure` — are fitted as u = ln θ
    (so they stay positive; their start value must be > 0).  The moduli that may be zero
    or negative (`k_c`, `k_phi`, `k_c_prime`, `k_phi_prime`: Bekker's k_c is negative for
    some soils), the distribution's `c1`, `c2`, `c3` (c3 < 0 puts the exit behind the
    axle) and leaves declared without a `ParameterInfo` are fitted linearly,
    θ = θ_start + s u with s = |θ_start|, or, for a zero start value, the field's typical
    magnitude `ParameterInfo.scale` (k_c 1e3 N/m^(n+1), k_phi 1e5 N/m^(n+2), k'_c and k'_φ
    1, c1..c3 0.1; 1 without a `ParameterInfo`).  The other parameters keep their values
    in `snow` / `distribution`, which also supply the start values.  Standard errors
    come back by the delta method, se(θ) = θ se(u) (log) or s se(u) (linear).  Iterates
    where the model is invalid (e.g. c1 + c2 i outside [0, 1)) get the failed-point
    residual below, so the optimiser steps back from them.

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
    on p_w, and are reported too.  `info["status"]` holds every point's status.  A fit
    that ends with fewer valid values (valid points × measured quantities) than fitted
    parameters raises a `ValueError` that counts the statuses, as does one whose model
    gave non-finite values to its own linear solves (the message then counts the
    statuses at the start values).

    **Arguments:**

    - `wheel`: `RigidWheel` (scalar diameter [m], width [m]) or `DeflectingTire` (scalar
      leaves; its parameters can be fitted as `wheel.<field>`, e.g.
      `fit=("wheel.carcass_pressure",)`).
    - `snow`: the terrain, any `snowjax.Terrain` with scalar leaves (SI units: Pa, m,
      N/m^(n+1), N/m^(n+2), N/m^3; see each class): start values of the fitted
      parameters and fixed values of the rest.  Every value must be valid for
      `solve_wheel`.  Or a `ContactModel` (scalar leaves) with:
      - `shear`: any shear law (as `solve_wheel`; `ThesisSimplified()` only for
        `WongSnow` without a distribution);
      - `distribution`: `None` (the thesis's front-region stresses) or a
        `snowjax.WongReece` (c1, c2, c3 [-]) whose leaves can be fitted too;
      - `lateral`: a `snowjax.Lateral` (default `Lateral()` when a `slip_angle` is
        given); its leaves are fitted as `lateral.shear_modulus` (give it a value to
        fit it) and `lateral.unit_weight`; `bulldozing` is held;
      - `nodes_per_panel`, `accuracy` and `terms` (force terms of your own, held at
        their values), as in `solve_wheel`.
    - `load`: F_z [N] (> 0), one per data point (several loads allowed).
    - `slip`: driving slip i [-] in [-1, 1], same length.
    - `measured`: the measured values by quantity, a mapping with at least one of
      `"sinkage"` [m], `"drawbar_pull"` [N], `"motion_resistance"` [N] and
      `"lateral_force"` [N] (F_y; needs `slip_angle`), each one value per point.
    - `fit`: names of the parameters to fit (see above; a non-empty subset of
      `fit_parameter_names(snow, distribution)`).
    - `scale`: optional residual scale per quantity [m or N] (scalar or per point),
      keyed like `measured`; see above.
    - `slip_angle`: slip angle beta [rad] of every point (|beta| < pi/2), or None
      (straight running); with it the model is `solve_wheel(..., slip_angle=beta)`.
    - `max_steps`: Levenberg–Marquardt step limit (an integer >= 1); `solve_max_steps`:
      `solve_wheel`'s Newton iteration limit.

    **Returns:** a `FitResult`; `info` has `snow` and `terrain` (the fitted terrain, of
    the type of `snow`'s), `distribution` (the fitted distribution or `None`),
    `lateral`, `wheel`, `model` (the fitted `ContactModel`, to pass to `solve_wheel`),
    `transforms` (name -> `"log"` / `"linear"`), `predictions` (dict of model values at
    the optimum), `status`, `scale`.

    **Raises:** `ValueError` for bad data or start values (naming the argument and the
    value), and for a fit that fails (see "Failed equilibria"); `TypeError` for a wheel,
    terrain or distribution of the wrong type.

    Use float64 (`jax.config.update("jax_enable_x64", True)`): the standard errors need
    derivatives accurate well beyond float32.  Each new combination of data length,
    fitted names, measured quantities, terrain / distribution type and shear model
    compiles once (about 10 s on a CPU); later fits of the same kind take a fraction of
    a second.
    """
    model = _as_model(snow, "snow")
    snow, shear, nodes_per_panel, terms = (
        model.terrain,
        model.shear,
        model.nodes_per_panel,
        model.terms,
    )
    distribution, lateral = _fitted_parts(wheel, model, slip_angle)
    names, targets = _resolve_fit_names(fit, snow, distribution, lateral, wheel)
    max_steps = check_max_steps(max_steps)
    shear_model = shear

    measured = _measured_quantities(measured)
    ld, sl, m, quantities, data, scales, sa = _wheel_data(load, slip, measured, scale, slip_angle)
    m_total = m * len(quantities)
    if m_total <= len(names):
        raise ValueError(
            f"fit_wheel fits {len(names)} parameters and needs more than {len(names)} "
            f"measured values; got {m_total}"
        )
    start = _start_values(snow, distribution, targets, lateral, wheel)
    _check_solvable(wheel, snow, distribution, ld, sl, shear_model)

    dtype = jnp.result_type(float)
    models = _start_models(wheel, snow, distribution, lateral, start, dtype)
    theta0 = np.array([start[o][p] for o, p in targets])
    infos = _infos(
        {"terrain": snow, "distribution": distribution, "lateral": lateral, "wheel": wheel}
    )
    transform = _transform(targets, theta0, infos)
    residual = _WheelResidual(
        names=names,
        quantities=quantities,
        shear=shear_model,
        nodes_per_panel=None if nodes_per_panel is None else int(nodes_per_panel),
        solve_max_steps=int(solve_max_steps),
        accuracy=model.accuracy,
        targets=targets,
    )
    u0 = np.array([
        math.log(t0) if log else 0.0 for t0, log in zip(theta0, transform.log)
    ])  # fmt: skip
    arrays = [jnp.asarray(x, dtype) for x in (ld, sl, data, scales)]
    angles = None if sa is None else jnp.asarray(sa, dtype)
    args = (*models, *arrays[:2], angles, *arrays[2:], transform.cast(dtype), terms)
    try:
        sol = least_squares(residual, jnp.asarray(u0, dtype), args, max_steps=max_steps, tol=1e-10)
    except NonFiniteModelError as err:
        at_start = _start_diagnosis(residual, u0, args, start, targets, m, infos)
        raise NonFiniteModelError(f"fit_wheel: {err}{at_start}") from None
    pred, status = sol.aux

    status = np.asarray(status).astype(int)
    good = _valid_points(status, len(quantities), len(names))
    rows = np.tile(good, len(quantities))
    r_used = np.where(rows, sol.residual, 0.0)
    theta = transform.values(sol.u)
    warnings = _fit_warnings(dtype, sol, status, m, names, targets, theta, float(wheel.diameter))
    d = transform.jacobian(sol.u)
    part = estimate(sol.jacobian[rows], sol.residual[rows], names, theta, d, fitted=names)

    fitted_snow, fitted_dist, fitted_lateral, fitted_wheel = _fitted(
        (snow, distribution, lateral, wheel), start, targets, theta, dtype
    )
    units = {nm: _unit(infos, t) for nm, t in zip(names, targets)}
    return fit_result(
        sol,
        [part],
        residuals=r_used,
        warnings=warnings,
        units=units,
        info={
            "title": _title(m, quantities, shear, snow, distribution),
            "snow": fitted_snow,
            "terrain": fitted_snow,
            "distribution": fitted_dist,
            "lateral": fitted_lateral,
            "wheel": fitted_wheel,
            "model": ContactModel(
                fitted_snow,
                fitted_dist,
                shear,
                fitted_lateral,
                nodes_per_panel,
                terms,
                model.accuracy,
            ),
            "transforms": {nm: "log" if log else "linear" for nm, log in zip(names, transform.log)},
            "predictions": {q: np.asarray(pred[k]) for k, q in enumerate(quantities)},
            "status": status,
            "scale": {q: scales[k].copy() for k, q in enumerate(quantities)},
            "quantities": quantities,
            "sse_unit": "(scaled residuals, dimensionless)",
        },
    )
