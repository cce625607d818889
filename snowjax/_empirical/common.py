"""Constants and eager input checks shared by the empirical models of chapter 2."""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np
from jaxtyping import Array

from .._leaves import _is_traced as _traced

ICE_DENSITY = 917.0  # [kg/m^3] density of ice, rho_i of Van Es's model (section 2.4.3)

# Richmond's fit (2.23): R = 21.313 (rho_0 a w)^1.1918, (rho_0 a w) in kg/m, R in N.
_RICHMOND_COEFFICIENT = 21.313
_RICHMOND_EXPONENT = 1.1918

# Brixius's slip coefficients (a in 1 - exp(-a S), c in c S / sqrt(N_B)).
_BRIXIUS_SLIP_COEFFICIENTS = {
    "thesis": (0.75, 0.05),  # as printed in the thesis, eqs. (2.18)-(2.20)
    "brixius1987": (7.5, 0.5),  # Brixius (1987) / ASAE D497, slip as a fraction
}


# ----------------------------------------------------------------------------------------
# input checks
# ----------------------------------------------------------------------------------------


def _is_traced(*values) -> bool:
    return any(_traced(v) for v in values)


def _describe(value) -> str:
    arr = np.asarray(value)
    if arr.size == 1:
        return repr(float(arr.reshape(())))
    bad = arr.reshape(-1)
    return f"an array of shape {arr.shape} (min {np.nanmin(bad):g}, max {np.nanmax(bad):g})"


def _check(name: str, value, ok, allowed: str) -> None:
    """Raise `ValueError` unless `ok(value)` holds everywhere; skipped for tracers."""
    if _is_traced(value):
        return
    arr = np.asarray(value, dtype=float)
    with np.errstate(invalid="ignore"):
        good = np.all(ok(arr))
    if not good:
        raise ValueError(f"`{name}` must be {allowed}; got {_describe(arr)}.")


def _positive(name, value, unit):
    _check(name, value, lambda x: x > 0, f"> 0 {unit} (finite)")
    _check(name, value, np.isfinite, f"finite and > 0 {unit}")


def _nonnegative(name, value, unit):
    _check(name, value, lambda x: (x >= 0) & np.isfinite(x), f"finite and >= 0 {unit}")


def _check_pair(message: str, a, b, ok) -> None:
    """Raise `ValueError(message)` unless `ok(a, b)` (broadcast) holds; skipped for tracers."""
    if _is_traced(a, b):
        return
    with np.errstate(invalid="ignore", divide="ignore"):
        good = np.all(ok(np.asarray(a, dtype=float), np.asarray(b, dtype=float)))
    if not good:
        raise ValueError(message)


def _nan_unless(valid: Array, value: Array) -> Array:
    return jnp.where(valid, value, jnp.nan)


def _safe(valid: Array, x: Array, fill: float = 1.0) -> Array:
    return jnp.where(valid, x, fill)
