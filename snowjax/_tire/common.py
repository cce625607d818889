"""Unit conversion, the thesis's load range, and numerically safe helpers of the tyre model
(finite value *and* gradient everywhere).
"""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np
from jaxtyping import Array

from .._leaves import _is_traced

_KN = 1e3  # [N per kN]
# The load range of the FEA data the load functions were fitted to (Table 3.2).
THESIS_LOAD_RANGE = (3.5e3, 7.5e3)  # [N]


# ----------------------------------------------------------------------------------------
# Small numerically safe helpers (finite value *and* gradient everywhere)
# ----------------------------------------------------------------------------------------


def _safe_ratio(num: Array, den: Array) -> Array:
    """`num / den`; ±inf where den == 0 (sign of num), 0 where both are 0.

    The infinities are constants, so the gradient stays finite (zero) there.
    """
    num, den = jnp.asarray(num), jnp.asarray(den)
    zero = den == 0
    safe_den = jnp.where(zero, 1.0, den)
    limit = jnp.where(num > 0, jnp.inf, jnp.where(num < 0, -jnp.inf, 0.0))
    return jnp.where(zero, limit, num / safe_den)


def _safe_norm(a: Array, b: Array) -> Array:
    """`sqrt(a² + b²)` with gradient 0 (instead of NaN) at a = b = 0."""
    sq = a * a + b * b
    positive = sq > 0
    return jnp.where(positive, jnp.sqrt(jnp.where(positive, sq, 1.0)), 0.0)


def _safe_arctan2(y: Array, x: Array) -> Array:
    """`arctan2(y, x)`, defined as 0 (with gradient 0) at x = y = 0."""
    nonzero = (x * x + y * y) > 0
    safe_x = jnp.where(nonzero, x, 1.0)
    safe_y = jnp.where(nonzero, y, 0.0)
    return jnp.where(nonzero, jnp.arctan2(safe_y, safe_x), 0.0)


def _float_dtype(*xs) -> jnp.dtype:
    dtype = jnp.result_type(*xs)
    if not jnp.issubdtype(dtype, jnp.floating):
        dtype = jnp.result_type(float)
    return dtype


def _check(name: str, value, ok, allowed: str) -> None:
    """Eager input check: raise `ValueError` when a concrete `value` fails `ok`.

    Traced values (inside `jit`, `vmap`, `grad`) are not checked; the model then returns
    finite numbers for them (see the module docstring for the intended ranges).
    """
    if value is None or _is_traced(value):
        return
    arr = np.asarray(value)
    with np.errstate(invalid="ignore"):
        good = ok(arr)
    if not np.all(good):
        bad = arr[~good] if arr.ndim else arr
        raise ValueError(f"`{name}` must be {allowed}; got {np.ravel(bad)[:5]}.")
