"""Data for the calibration fits: the shipped thesis tables and checks of measured arrays."""

from __future__ import annotations

import importlib.resources
import math
import sys

import numpy as np

from .._leaves import _is_traced

__all__ = ["read_package_csv", "vector", "same_length", "rms", "MAX_MAGNITUDE"]

# The largest magnitude whose square is finite in float64 (about 1.34e154).
MAX_MAGNITUDE = math.sqrt(sys.float_info.max)


def read_package_csv(name: str) -> dict[str, np.ndarray]:
    """A table shipped in `snowjax/data`: '#' comment lines, a header line, rows of numbers.

    **Returns:** column name -> NumPy float array, in the table's own units.
    """
    path = importlib.resources.files("snowjax") / "data" / name
    lines = [
        ln.strip()
        for ln in path.read_text(encoding="utf-8-sig").splitlines()
        if ln.strip() and not ln.lstrip().startswith("#")
    ]
    header = [h.strip() for h in lines[0].split(",")]
    values = np.array([[float(x) for x in ln.split(",")] for ln in lines[1:]])
    return {h: values[:, k] for k, h in enumerate(header)}


def vector(name: str, x, *, min_size: int = 1) -> np.ndarray:
    """A finite 1-D float array, or a ValueError naming `name` (a scalar becomes length 1).

    Values whose sum of squares overflows float64 (|x| of order `MAX_MAGNITUDE`, 1.3e154,
    and above) are refused too: the fits square their data (residual scales, the SSE) and
    raise them to powers (zⁿ), so such values would make the fit's arithmetic inf or NaN.
    """
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
        raise ValueError(f"{name} must be finite; got {float(arr[i])!r} at index {i}")
    with np.errstate(over="ignore"):
        overflow = not np.isfinite(np.sum(np.square(arr)))
    if overflow:
        i = int(np.argmax(np.abs(arr)))
        raise ValueError(
            f"{name} = {float(arr[i])!r} at index {i} is too large for the float64 arithmetic of "
            f"the fit (the sum of the squares of {name} overflows; keep |{name}| well below "
            f"{MAX_MAGNITUDE:.3g})"
        )
    return arr


def same_length(**arrays: np.ndarray) -> int:
    """The common length of the named arrays, or a ValueError listing their lengths."""
    sizes = {k: v.size for k, v in arrays.items()}
    if len(set(sizes.values())) > 1:
        desc = ", ".join(f"{k} has {n}" for k, n in sizes.items())
        raise ValueError(f"shape mismatch: the data arrays must have equal length ({desc})")
    return next(iter(sizes.values()))


def rms(y: np.ndarray) -> float:
    """The root-mean-square of `y`, sqrt(mean(y²)), in the unit of `y`, without the
    underflow or overflow of squaring (scaled by max |y|: 1e-300 values give 1e-300, not 0)."""
    top = float(np.max(np.abs(y))) if y.size else 0.0
    if not top > 0:
        return top
    return top * math.sqrt(float(np.mean((y / top) ** 2)))
