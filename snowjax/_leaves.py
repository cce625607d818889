"""Parameter leaves: the field converter of every parameter set and leaf paths.

Every physical parameter is an array leaf, so parameter sets can be batched (give a leaf
an array value and it broadcasts against loads and slips), vmapped and differentiated.
Nested parameter sets (`LayeredSnow`) name their leaves by dotted field path (`top.p_w`).
"""

from __future__ import annotations

import dataclasses
import functools
import math
from typing import Any

import equinox as eqx
import jax
import jax.numpy as jnp
from jax.core import Tracer


def _is_traced(x: Any) -> bool:
    """True for a JAX tracer (inside `jit`, `vmap`, `grad`): its value is not known yet."""
    return isinstance(x, Tracer)


def _as_float(x: Any) -> Any:
    """Converter for parameter leaves: arrays of a floating dtype, other objects untouched.

    Python ints become the default float type; existing floating arrays keep their dtype,
    so a float32 parameter set stays float32.  Non-numeric placeholders (None, sentinels
    used by `jax.vmap` in_axes or `eqx.filter`) pass through unchanged, and so do
    booleans, complex numbers and strings, which `_check_real_leaves` then refuses by
    name (a `p_w` of `True` is not 1 Pa).
    """
    if x is None or isinstance(x, jax.ShapeDtypeStruct):
        return x
    try:
        arr = jnp.asarray(x)
    except TypeError:
        return x
    if arr.dtype.kind in "iu":
        arr = arr.astype(jnp.result_type(float))
    return arr


@dataclasses.dataclass(frozen=True)
class ParameterInfo:
    """What snowjax knows about a physical parameter, kept on its field (`parameter`).

    - `unit`: SI unit, `"-"` for a dimensionless parameter.
    - `description`: one line, in the thesis's words.
    - `lower`: the smallest allowed value (`-inf`: none); `open_lower`: whether the
      bound itself is excluded (`> lower` rather than `>= lower`).
    - `log_space`: whether `fit_wheel` fits the parameter as u = ln(value) (for a
      parameter that is never negative), rather than linearly.
    - `scale`: typical magnitude, in `unit`; the step of a linearly fitted parameter
      whose start value is 0.

    The input checks, `fit_wheel` and the `snowjax sweep` help read these, so a terrain
    law defined outside snowjax needs no table anywhere else.
    """

    unit: str
    description: str
    lower: float = -math.inf
    open_lower: bool = False
    log_space: bool = False
    scale: float = 1.0

    def allowed(self) -> str:
        """The allowed range as the error messages print it: "> 0 Pa", ">= 0", "finite m"."""
        unit = "" if self.unit == "-" else f" {self.unit}"
        if self.lower == -math.inf:
            return f"finite{unit}"
        return f"{'>' if self.open_lower else '>='} {self.lower:g}{unit}"

    def ok(self, value):
        """Elementwise: whether `value` lies in the allowed range (finite is checked apart)."""
        if self.lower == -math.inf:
            return value * 0 == 0
        return value > self.lower if self.open_lower else value >= self.lower


def parameter(
    unit: str,
    description: str,
    *,
    lower: float = -math.inf,
    open_lower: bool = False,
    log_space: bool | None = None,
    scale: float = 1.0,
) -> dict[str, ParameterInfo]:
    """The field metadata of a physical parameter: `{"parameter": ParameterInfo(...)}`.

    Declare a parameter field as
    `p_w: Float[Array, "..."] = eqx.field(converter=snowjax.as_float,
    metadata=snowjax.parameter("Pa", "Wong's pressure parameter", lower=0, open_lower=True))`.
    `log_space` defaults to `lower >= 0` (a parameter that is never negative is fitted in
    log space).
    """
    if log_space is None:
        log_space = lower >= 0
    return {"parameter": ParameterInfo(unit, description, lower, open_lower, log_space, scale)}


@functools.cache
def _own_parameter_fields(cls) -> tuple[tuple[str, ParameterInfo | None], ...]:
    """(field name, its `ParameterInfo` or None) of every non-static field of a class."""
    return tuple(
        (f.name, f.metadata.get("parameter"))
        for f in dataclasses.fields(cls)
        if not f.metadata.get("static", False)
    )


def _parameter_infos(obj, prefix: str = "") -> dict[str, ParameterInfo]:
    """`ParameterInfo` of every parameter field of a module, by dotted field path."""
    out: dict[str, ParameterInfo] = {}
    for name, info in _own_parameter_fields(type(obj)):
        value = getattr(obj, name, None)
        if isinstance(value, eqx.Module):
            out.update(_parameter_infos(value, f"{prefix}{name}."))
        elif info is not None:
            out[f"{prefix}{name}"] = info
    return out


def _parameter_rules(obj, infos=None) -> list[tuple[str, Any, Any, str]]:
    """(field path, value, ok mask, allowed range) of every parameter field of `obj`
    (nested modules included) from its `ParameterInfo` (or from `infos`, path ->
    `ParameterInfo`); `None` values are skipped."""
    rules = []
    for path, info in (_parameter_infos(obj) if infos is None else infos).items():
        value = _get_path(obj, path)
        if value is not None:
            rules.append((path, value, info.ok(value), info.allowed()))
    return rules


def as_float(x: Any) -> Any:
    """The converter of parameter fields: a number or array becomes a floating array.

    Python ints and integer arrays become the default float type; floating arrays keep
    their dtype (a float32 parameter set stays float32); `None` and other placeholders
    pass through.  Use it as `eqx.field(converter=snowjax.as_float, ...)` in a terrain
    law or stress distribution of your own.
    """
    return _as_float(x)


_KINDS = {
    "b": "a boolean",
    "c": "a complex number",
    "U": "a string",
    "S": "bytes",
    "O": "an object",
}


def _check_real_leaves(module) -> None:
    """`__check_init__` of parameter sets: TypeError naming a leaf that is not real-valued.

    Leaves that are not arrays (vmap / filter sentinels, None) are left alone.
    """
    for path, leaf in _module_leaves(module).items():
        if isinstance(leaf, (str, bytes)):
            what = "a string"
        elif hasattr(leaf, "dtype") and not isinstance(leaf, jax.ShapeDtypeStruct):
            kind = leaf.dtype.kind
            if kind == "f":
                continue
            what = _KINDS.get(kind, f"dtype {leaf.dtype}")
        else:
            continue
        raise TypeError(
            f"{type(module).__name__}.{path} must be a real number or array of real numbers"
            f" (SI units), got {what}"
        )


def _module_leaves(obj, prefix: str = "") -> dict[str, Any]:
    """Array leaves of a parameter set by field path, in pytree order.

    Nested parameter sets get dotted paths (`LayeredSnow`: `top.p_w`, ...,
    `ice_failure_pressure`); static fields are skipped.
    """
    out: dict[str, Any] = {}
    for f in dataclasses.fields(obj):
        if f.metadata.get("static", False):
            continue
        value = getattr(obj, f.name)
        if isinstance(value, eqx.Module):
            out.update(_module_leaves(value, f"{prefix}{f.name}."))
        else:
            out[f"{prefix}{f.name}"] = value
    return out


def _get_path(obj, path: str):
    for part in path.split("."):
        obj = getattr(obj, part)
    return obj


def _with_leaves(obj, values: dict[str, Any]):
    """`obj` with the leaves at the given field paths replaced (no converters run)."""
    paths = tuple(values)
    if not paths:
        return obj
    return eqx.tree_at(
        lambda o: tuple(_get_path(o, p) for p in paths), obj, tuple(values[p] for p in paths)
    )


def _parameter_names(terrain, distribution, reserved=()) -> dict[str, tuple[str, str]]:
    """Public name -> (owner, field path) of every leaf of a terrain and a distribution.

    The name is the field path (`k_phi`, `top.p_w`, `c1`) unless the same path exists in
    the other object or among `reserved` names; then it is prefixed with its owner
    (`terrain.` or `distribution.`).
    """
    t_paths = list(_module_leaves(terrain))
    d_paths = [] if distribution is None else list(_module_leaves(distribution))
    taken = set(reserved)
    out: dict[str, tuple[str, str]] = {}
    for owner, paths, other in (
        ("terrain", t_paths, d_paths),
        ("distribution", d_paths, t_paths),
    ):
        for p in paths:
            out[p if p not in other and p not in taken else f"{owner}.{p}"] = (owner, p)
    return out
