"""The definition of a sweep: validated inputs, the rows of chunk k, the columns, the hash
that identifies the sweep on disk, and the file format constants.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import re
from collections.abc import Sequence
from typing import Any

import numpy as np

from .._constants import VERSION
from .._leaves import _get_path, _module_leaves, _parameter_names, _with_leaves
from .._terrain.base import Terrain
from .._wheel.distribution import AbstractStressDistribution, FrontRegion
from .._wheel.geometry import AbstractWheel, RigidWheel
from .._wheel.shear_law import AbstractShearLaw

MANIFEST = "manifest.json"
_FORMAT_TAG = "snowjax-sweep/1"
_OUTPUT_FIELDS = (
    "entry_angle",
    "sinkage",
    "motion_resistance",
    "thrust",
    "drawbar_pull",
    "torque",
)
_FORMATS = ("npz", "csv")
_OUTPUT_FILES = {"npz": "sweep.npz", "csv": "sweep.csv"}
# Every file a sweep writes (resume=False deletes exactly these).
_OUR_FILES = re.compile(
    r"(chunk_\d{6,}\.npz|sweep\.npz|sweep\.csv|manifest\.json"
    r"|\.(chunk_\d{6,}\.npz|sweep\.npz|sweep\.csv|manifest\.json)\.tmp\..*)"
)
_BLOCK = 1 << 20  # elements per block when validating or hashing list-mode inputs


# ---------------------------------------------------------------------------------------
# The sweep definition: inputs -> rows of chunk k, hash, columns
# ---------------------------------------------------------------------------------------

_TERRAIN_WHAT = "a snowjax terrain (WongSnow, BekkerSoil, ReeceSoil, LayeredSnow)"
_WHEEL_WHAT = "a snowjax wheel (RigidWheel, DeflectingTire)"
_RESERVED = ("index", "param_set", "load", "slip", *_OUTPUT_FIELDS, "status")


def _leaf_arrays(obj, cls, what, kind=None):
    """Leaves of a parameter set (or a list of them) as NumPy arrays, scalar or 1-D.

    Returns (template, {field path: array}); the template is the parameter set (the
    first one of a list), whose structure rebuilds a parameter set from the columns.
    """
    kind = kind or f"snowjax.{cls.__name__}"
    if isinstance(obj, cls):
        leaves = {f: np.asarray(x) for f, x in _module_leaves(obj).items()}
        for f, x in leaves.items():
            if x.ndim > 1:
                raise ValueError(
                    f"sweep: {what}.{f} must be a scalar or 1-D (a leading batch of parameter"
                    f" sets); got shape {x.shape}"
                )
        return obj, leaves
    if isinstance(obj, Sequence) and not isinstance(obj, (str, bytes)) and len(obj) > 0:
        if not all(isinstance(o, cls) for o in obj):
            raise TypeError(f"sweep: {what} must be {kind} or a list of them")
        if len({type(o) for o in obj}) > 1:
            raise TypeError(
                f"sweep: a list of {what} parameter sets must hold one type, got "
                + ", ".join(sorted({type(o).__name__ for o in obj}))
            )
        out = {}
        for f in _module_leaves(obj[0]):
            values = [np.asarray(_get_path(o, f)) for o in obj]
            if any(v.ndim != 0 for v in values):
                raise ValueError(
                    f"sweep: in a list of {type(obj[0]).__name__}, every {f} must be a scalar"
                )
            out[f] = np.stack(values)
        return obj[0], out
    raise TypeError(
        f"sweep: {what} must be {kind} or a non-empty list of them, got {type(obj).__name__}"
    )


def _rules():
    return {
        "load": (lambda x: x > 0, "> 0 N"),
        "slip": (lambda x: (x >= -1) & (x <= 1), "in [-1, 1]"),
    }


def _blocks(n: int):
    for a in range(0, n, _BLOCK):
        yield a, min(a + _BLOCK, n)


def _check_parameter_sets(
    template, leaves, rules_of, label, where, slips=None, grid=True, widths=None
):
    """Check the leaves of a terrain / distribution with its own `constraints`, by blocks.

    `leaves`: {field path: scalar or 1-D array} (1-D ones of a common length);
    `rules_of(obj, slip)` returns the object's (name, value, ok, allowed) rules.  A
    distribution's rules depend on the slip: `slips` are then the sweep's slips, every
    slip with every parameter set (grid) or zipped with the rows (list).  A terrain's
    rules that involve the wheel width b: `widths` (scalar or 1-D, aligned with the
    leaves), passed as `rules_of(obj, width)`.
    """
    sizes = [x.size for x in leaves.values()] + [1 if widths is None else widths.size]
    size = max(sizes + [1 if slips is None or grid else slips.size])
    cut = lambda x: x.reshape(-1)[a:b] if x.size > 1 else x.reshape(-1)[:1]  # noqa: E731
    for a, b in _blocks(size):
        block = {f: np.asarray(cut(x), dtype=float) for f, x in leaves.items()}
        slip: np.ndarray | None = None
        if slips is not None:
            flat = np.asarray(slips, dtype=float).reshape(-1)
            if grid:
                block = {f: x[:, None] for f, x in block.items()}
                slip = flat[None, :]
            else:
                slip = flat[a:b] if flat.size > 1 else flat
        obj = _with_leaves(template, block)
        with np.errstate(invalid="ignore", over="ignore", divide="ignore"):
            rules = rules_of(obj, slip if widths is None else np.asarray(cut(widths), float))
        for name, value, ok, allowed in rules:
            value = np.asarray(value, dtype=float)
            good = np.isfinite(value) & np.asarray(ok)
            if good.all():
                continue
            shape = np.broadcast_shapes(good.shape, value.shape)
            good = np.broadcast_to(good, shape)
            value = np.broadcast_to(value, shape)
            bad = [int(k) for k in np.unravel_index(int(np.argmin(good)), shape)] if shape else []
            got = float(value[tuple(bad)]) if shape else float(value)
            if shape and size > 1:
                at = f" at index {a + int(bad[0])}"
                if widths is not None and grid:
                    at = f" at parameter set {a + int(bad[0])}"
                if slip is not None and grid:
                    at = f" at parameter set {a + int(bad[0])}, slip {float(slip[0, bad[1]])!r}"
            elif shape and slip is not None and grid and slip.size > 1:
                at = f" at slip {float(slip[0, bad[-1]])!r}"
            else:
                at = ""
            raise ValueError(f"sweep: {label}{name} must be finite and {allowed}; got {got!r}{at}")
    for f, x in leaves.items():  # leaves a (user-defined) terrain's rules do not cover
        flat = x.reshape(-1)
        for a, b in _blocks(flat.size):
            v = np.asarray(flat[a:b], dtype=float)
            if not np.isfinite(v).all():
                j = a + int(np.argmin(np.isfinite(v)))
                raise ValueError(
                    f"sweep: {where}.{f} must be finite; got {float(flat[j])!r}"
                    + (f" at index {j}" if flat.size > 1 else "")
                )


@dataclasses.dataclass(frozen=True)
class _Definition:
    """Everything that determines the rows of a sweep (and nothing else)."""

    grid: bool
    inputs: dict[str, np.ndarray]  # load, slip, wheel / terrain / distribution leaves
    n_points: int
    shape: tuple[int, ...]  # grid: (parameter sets, loads, slips); list: (n,)
    chunk_size: int
    shear: AbstractShearLaw
    nodes_per_panel: int | None  # None: solve_wheel's default
    max_steps: int
    dtype: np.dtype
    version: str
    wheel: Any  # template parameter sets (structure only; values come from inputs)
    terrain: Any
    distribution: Any
    names: dict[str, tuple[str, str]]  # column -> (owner, field path) of each leaf
    terms: tuple = ()  # the model's own force terms (the same in every row)
    accuracy: str = "reference"  # the model's accuracy setting

    @property
    def n_chunks(self) -> int:
        return -(-self.n_points // self.chunk_size)

    @property
    def parameters(self) -> tuple[str, ...]:
        """Every parameter leaf, as column names: wheel, terrain, distribution."""
        return tuple(self.names)

    @property
    def varying(self) -> tuple[str, ...]:
        """Parameter leaves that vary from row to row (stored as columns)."""
        return tuple(f for f in self.parameters if self.inputs[f].size > 1)

    @property
    def columns(self) -> dict[str, np.dtype]:
        cols: dict[str, np.dtype] = {"index": np.dtype(np.int64)}
        if self.grid:
            cols["param_set"] = np.dtype(np.int64)
        for name in ("load", "slip", *self.varying, *_OUTPUT_FIELDS):
            cols[name] = self.dtype
        cols["status"] = np.dtype(np.int32)
        return cols

    def chunk_bounds(self, k: int) -> tuple[int, int]:
        return k * self.chunk_size, min((k + 1) * self.chunk_size, self.n_points)

    def chunk_inputs(self, k: int) -> dict[str, np.ndarray]:
        """Input columns of chunk k (index, param_set, load, slip, every parameter leaf)."""
        a, b = self.chunk_bounds(k)
        index = np.arange(a, b, dtype=np.int64)
        out = {"index": index}
        if self.grid:
            p, i_load, i_slip = np.unravel_index(index, self.shape)
            out["param_set"] = p.astype(np.int64)
            pick = {"load": i_load, "slip": i_slip}
            pick.update({f: p for f in self.parameters})
            for name, sel in pick.items():
                x = self.inputs[name]
                out[name] = (x[sel] if x.size > 1 else np.full(b - a, x.reshape(-1)[0])).astype(
                    self.dtype
                )
        else:
            for name, x in self.inputs.items():
                out[name] = np.asarray(
                    x[a:b] if x.size > 1 else np.full(b - a, x.reshape(-1)[0]), dtype=self.dtype
                )
        return out

    def build(self, columns: dict[str, Any]):
        """(wheel, terrain, distribution) with their leaves taken from `columns`."""
        parts = {"wheel": {}, "terrain": {}, "distribution": {}}
        for name, (owner, path) in self.names.items():
            parts[owner][path] = columns[name]
        wheel = _with_leaves(self.wheel, parts["wheel"])
        terrain = _with_leaves(self.terrain, parts["terrain"])
        distribution = (
            None
            if self.distribution is None
            else _with_leaves(self.distribution, parts["distribution"])
        )
        return wheel, terrain, distribution

    def digest(self) -> str:
        h = hashlib.sha256()
        header = dict(self.summary(with_values=False))
        h.update(json.dumps(header, sort_keys=True).encode())
        for name in sorted(self.inputs):
            x = self.inputs[name]
            h.update(f"|{name}:{x.shape}|".encode())
            flat = x.reshape(-1)
            for a, b in _blocks(flat.size):
                h.update(
                    np.ascontiguousarray(flat[a:b], dtype=self.dtype.newbyteorder("<")).tobytes()
                )
        return h.hexdigest()

    def summary(self, with_values: bool = True) -> dict[str, Any]:
        s: dict[str, Any] = {
            "format": _FORMAT_TAG,
            "snowjax_version": self.version,
            "mode": "grid" if self.grid else "list",
            # The wheel's type, except for the rigid wheel (its sweeps keep their hash).
            **({} if isinstance(self.wheel, RigidWheel) else {"wheel": type(self.wheel).__name__}),
            "terrain": type(self.terrain).__name__,
            "distribution": (
                None if self.distribution is None else type(self.distribution).__name__
            ),
            "parameter_names": list(self.parameters),
            "shape": list(self.shape),
            "n_points": self.n_points,
            "chunk_size": self.chunk_size,
            "n_chunks": self.n_chunks,
            "shear": self.shear.name,
            # A model's own force terms, by type and parameter values (none: no key, so
            # sweeps without them keep their hash).
            **({"terms": [_term_summary(t) for t in self.terms]} if self.terms else {}),
            "nodes_per_panel": self.nodes_per_panel,
            # The simulator accuracy (the reference: no key, so such sweeps keep their hash).
            **({"accuracy": self.accuracy} if self.accuracy != "reference" else {}),
            "max_steps": self.max_steps,
            "dtype": self.dtype.name,
            "columns": list(self.columns),
        }
        if with_values:
            small = lambda x: x.size <= 100_000  # noqa: E731
            s["parameters"] = {
                f: (self.inputs[f].astype(float).tolist() if small(self.inputs[f]) else "(array)")
                for f in self.parameters
            }
            if self.grid:
                s["loads"] = self.inputs["load"].astype(float).tolist()
                s["slips"] = self.inputs["slip"].astype(float).tolist()
        return s


def _check_points(inputs) -> None:
    """The loads and slips: scalars or 1-D, not empty, finite and in `solve_wheel`'s
    range; every input real."""
    for name in ("load", "slip"):
        x = inputs[name]
        if x.ndim > 1:
            raise ValueError(f"sweep: {name}s must be a scalar or 1-D, got shape {x.shape}")
        if x.size == 0:
            raise ValueError(f"sweep: {name}s is empty")
    for name, x in inputs.items():
        if not (np.issubdtype(x.dtype, np.floating) or np.issubdtype(x.dtype, np.integer)):
            raise TypeError(f"sweep: {name} must be real numbers, got dtype {x.dtype}")
    rules = _rules()
    for name in ("load", "slip"):
        x = inputs[name]
        ok, allowed = rules[name]
        flat = x.reshape(-1)
        for a, b in _blocks(flat.size):
            v = np.asarray(flat[a:b], dtype=float)
            good = np.isfinite(v) & ok(v)
            if not good.all():
                j = a + int(np.argmin(good))
                what = {"load": "loads", "slip": "slips"}.get(name, name)
                raise ValueError(
                    f"sweep: {what} must be finite and {allowed}; got {float(flat[j])!r}"
                    + (f" at index {j}" if flat.size > 1 else "")
                )


def _shape(grid, inputs, leaves) -> tuple[int, ...]:
    """(parameter sets, loads, slips) of a grid, (points,) of a zipped list."""
    sizes = {name: x.size for name, x in leaves.items() if x.size > 1}
    if grid:
        if len(set(sizes.values())) > 1:
            raise ValueError(
                "sweep: the parameter leaves that vary must all have the same length (the"
                f" number of parameter sets); got {sizes}"
            )
        n_sets = next(iter(sizes.values()), 1)
        shape = (n_sets, inputs["load"].size, inputs["slip"].size)
    else:
        lengths = {name: x.size for name, x in inputs.items() if x.size > 1}
        if len(set(lengths.values())) > 1:
            raise ValueError(
                "sweep(grid=False) zips its inputs: loads, slips and every varying parameter"
                f" leaf must have the same length (or length 1); got {lengths}"
            )
        shape = (next(iter(lengths.values()), 1),)
    return shape


def _term_summary(term) -> dict[str, Any]:
    """A force term's type and parameter values, for the manifest and the hash."""
    import jax

    leaves = jax.tree_util.tree_leaves(term)
    return {"type": type(term).__name__, "values": [np.asarray(x).tolist() for x in leaves]}


def _define(wheel, model, loads, slips, *, grid, chunk_size, max_steps):
    """The sweep of `wheel` on `model` (a `ContactModel`, checked when built) over the
    loads, slips and the varying parameter leaves, checked: `_Definition`."""
    import jax.numpy as jnp

    from .._wheel.equilibrium import _check_model

    snow, shear, distribution = model.terrain, model.shear, model.distribution
    if (
        isinstance(chunk_size, bool)
        or not isinstance(chunk_size, (int, np.integer))
        or chunk_size < 1
    ):
        raise ValueError(f"sweep: chunk_size must be a positive integer, got {chunk_size!r}")
    if isinstance(max_steps, bool) or int(max_steps) < 1:
        raise ValueError(f"sweep: max_steps must be a positive integer, got {max_steps!r}")
    wheel_t, wheel_leaves = _leaf_arrays(wheel, AbstractWheel, "wheel", _WHEEL_WHAT)
    terrain_t, terrain_leaves = _leaf_arrays(snow, Terrain, "snow", _TERRAIN_WHAT)
    dist_t, dist_leaves = None, {}
    if isinstance(distribution, FrontRegion):  # the front region is spelled None in a sweep
        distribution = None
    if distribution is not None:
        dist_t, dist_leaves = _leaf_arrays(distribution, AbstractStressDistribution, "distribution")
    try:
        _check_model(wheel_t, model)
    except ValueError as err:
        raise ValueError(f"sweep: {err}") from None
    # Wheel leaves by their field names (`diameter`, `inflation_pressure`), the terrain's
    # and the distribution's after them (prefixed where a name is taken).
    names = {p if p not in _RESERVED else f"wheel.{p}": ("wheel", p) for p in wheel_leaves}
    names.update(_parameter_names(terrain_t, dist_t, reserved=(*_RESERVED, *names)))
    owners = {"wheel": wheel_leaves, "terrain": terrain_leaves, "distribution": dist_leaves}
    leaves = {name: owners[owner][path] for name, (owner, path) in names.items()}
    inputs = {"load": np.asarray(loads), "slip": np.asarray(slips), **leaves}
    _check_points(inputs)
    dtype = np.dtype(jnp.result_type(float))
    shape = _shape(grid, inputs, leaves)
    # The wheel's, the terrain's and the distribution's own validity rules (those of
    # solve_wheel).
    _check_parameter_sets(wheel_t, wheel_leaves, lambda w, _: w.constraints(), "", "wheel")
    _check_parameter_sets(
        terrain_t,
        terrain_leaves,
        lambda t, width: [
            *t.constraints(),
            *t.wheel_constraints(width),
            *shear.constraints(t),
        ],
        "",
        "snow",
        widths=wheel_leaves["width"],
    )
    if dist_t is not None:
        _check_parameter_sets(
            dist_t,
            dist_leaves,
            lambda d, slip: d.constraints(slip),
            "",
            "distribution",
            slips=inputs["slip"],
            grid=grid,
        )
    n_points = int(np.prod(shape))
    return _Definition(
        grid=bool(grid),
        inputs=inputs,
        n_points=n_points,
        shape=tuple(int(s) for s in shape),
        chunk_size=int(chunk_size),
        shear=shear,
        nodes_per_panel=model.nodes_per_panel,
        max_steps=int(max_steps),
        dtype=dtype,
        version=VERSION,
        wheel=wheel_t,
        terrain=terrain_t,
        distribution=dist_t,
        names=names,
        terms=model.terms,
        accuracy=model.accuracy,
    )
