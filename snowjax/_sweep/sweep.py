"""Chunked, resumable, sharded sweeps of `solve_wheel` to disk.

`sweep` evaluates the wheel equilibrium (eq. 4.14) over a grid (Cartesian product) or a
list (zipped arrays) of loads x slips x parameter sets, in chunks of a fixed size:

- **Bounded memory.**  The index space is never materialised: chunk k covers the flat
  indices [k C, (k + 1) C), and its inputs are computed from the flat index (grid order
  parameter set, load, slip; slip varies fastest).  Memory is that of one chunk, whatever
  the number of points.
- **One compile.**  Every chunk is solved by one jitted `solve_wheel` call of a fixed
  shape: the last chunk is padded (with copies of its last row), the padding discarded.
- **Crash-safe, resumable.**  Each chunk is written atomically (temporary file, fsync,
  `os.replace`) as `chunk_000123.npz`; `manifest.json` holds a hash of the sweep
  definition (inputs, terrain and distribution types, shear model, quadrature, chunk
  size, dtype, snowjax version).  A
  restart with the same definition validates the chunks on disk (loadable, right columns,
  dtypes and flat indices), recomputes the missing or damaged ones and skips the rest;
  a restart with a different definition refuses with a `ValueError`.
- **Sharded.**  The rows of a chunk are spread over the local JAX devices with
  `jax.sharding.NamedSharding(Mesh(devices, ("batch",)), P("batch"))`; with several
  processes (`jax.distributed.initialize`) chunk k is computed by process
  `k % process_count`, so the processes write disjoint chunks into a shared directory.
- **Outputs.**  Once every chunk is on disk the chunks are concatenated, streaming one
  chunk at a time, into `sweep.csv` and/or `sweep.npz` (one `.npy` member per column,
  written column by column, so consolidation needs the memory of one chunk too).  The
  chunk directory is itself the dataset: `iter_sweep_chunks` reads it chunk by chunk.

**Any terrain, any stress distribution.**  `snow` is any `snowjax.Terrain` (`WongSnow`,
`BekkerSoil`, `ReeceSoil`, `LayeredSnow`) and `distribution` `None` or a `WongReece`; the
terrain's type, the distribution's type and the names of their leaves are part of the
sweep definition (and of its hash), so a sweep of another terrain or distribution in the
same directory is refused.

Columns (one row per point, `index` the flat index): `index`, `param_set` (grid mode),
`load` [N], `slip` [-], every parameter leaf that varies — the wheel's `diameter` [m],
`width` [m], then the terrain's leaves under their field names (`WongSnow`: `p_w` [Pa],
`z_w` [m], `cohesion` [Pa], `tan_phi` [-], `shear_modulus` [m]; `BekkerSoil`: `n` [-],
`k_c` [N/m^(n+1)], `k_phi` [N/m^(n+2)], `cohesion`, `tan_phi`, `shear_modulus`;
`ReeceSoil`: `n`, `k_c_prime` [-], `k_phi_prime` [-], `unit_weight` [N/m^3], `cohesion`,
`tan_phi`, `shear_modulus`; `LayeredSnow`: dotted names of the nested layers,
`top.p_w`, ..., `bottom.shear_modulus`, then `ice_failure_pressure` [Pa]), then the
distribution's (`c1`, `c2`, `c3` [-]) — then `entry_angle` [rad], `sinkage` [m],
`motion_resistance` [N], `thrust` [N], `drawbar_pull` [N], `torque` [N m], `status`
(`Status` code).  A leaf name that would clash with another column (possible only for a
user-defined terrain) is prefixed with `terrain.` or `distribution.`.
"""

from __future__ import annotations

import contextlib
import dataclasses
import hashlib
import json
import os
import pathlib
import re
import time
import warnings
import zipfile
from collections.abc import Callable, Iterator, Sequence
from typing import Any

import numpy as np
from jaxtyping import ArrayLike, Float

from .._leaves import _get_path, _module_leaves, _parameter_names, _with_leaves
from .._terrain.base import Terrain
from .._wheel.distribution import WongReece
from .._wheel.geometry import RigidWheel

__all__ = ["sweep", "SweepResult", "load_sweep", "iter_sweep_chunks"]

MANIFEST = "manifest.json"
_FORMAT_TAG = "snowjax-sweep/1"
_WHEEL_FIELDS = ("diameter", "width")
_OUTPUT_FIELDS = (
    "entry_angle",
    "sinkage",
    "motion_resistance",
    "thrust",
    "drawbar_pull",
    "torque",
)
_FORMATS = ("npz", "csv")
_SHEAR_MODELS = ("classic", "simplified", "none")
_OUTPUT_FILES = {"npz": "sweep.npz", "csv": "sweep.csv"}
# Every file a sweep writes (resume=False deletes exactly these).
_OUR_FILES = re.compile(
    r"(chunk_\d{6,}\.npz|sweep\.npz|sweep\.csv|manifest\.json"
    r"|\.(chunk_\d{6,}\.npz|sweep\.npz|sweep\.csv|manifest\.json)\.tmp\..*)"
)
_BLOCK = 1 << 20  # elements per block when validating or hashing list-mode inputs


# ---------------------------------------------------------------------------------------
# Parameter sets by name: the leaves of a terrain / distribution as named columns
# ---------------------------------------------------------------------------------------


# ---------------------------------------------------------------------------------------
# The sweep definition: inputs -> rows of chunk k, hash, columns
# ---------------------------------------------------------------------------------------

_TERRAIN_WHAT = "a snowjax terrain (WongSnow, BekkerSoil, ReeceSoil, LayeredSnow)"


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
        "diameter": (lambda x: x > 0, "> 0 m"),
        "width": (lambda x: x > 0, "> 0 m"),
    }


def _blocks(n: int):
    for a in range(0, n, _BLOCK):
        yield a, min(a + _BLOCK, n)


def _check_parameter_sets(template, leaves, rules_of, label, where, slips=None, grid=True):
    """Check the leaves of a terrain / distribution with its own `constraints`, by blocks.

    `leaves`: {field path: scalar or 1-D array} (1-D ones of a common length);
    `rules_of(obj, slip)` returns the object's (name, value, ok, allowed) rules.  A
    distribution's rules depend on the slip: `slips` are then the sweep's slips, every
    slip with every parameter set (grid) or zipped with the rows (list).
    """
    size = max([x.size for x in leaves.values()] + [1 if slips is None or grid else slips.size])
    for a, b in _blocks(size):
        block = {
            f: np.asarray(x.reshape(-1)[a:b] if x.size > 1 else x.reshape(-1)[:1], dtype=float)
            for f, x in leaves.items()
        }
        slip = None
        if slips is not None:
            flat = np.asarray(slips, dtype=float).reshape(-1)
            if grid:
                block = {f: x[:, None] for f, x in block.items()}
                slip = flat[None, :]
            else:
                slip = flat[a:b] if flat.size > 1 else flat
        obj = _with_leaves(template, block)
        with np.errstate(invalid="ignore", over="ignore", divide="ignore"):
            rules = rules_of(obj, slip)
        for name, value, ok, allowed in rules:
            value = np.asarray(value, dtype=float)
            good = np.isfinite(value) & np.asarray(ok)
            if good.all():
                continue
            shape = np.broadcast_shapes(good.shape, value.shape)
            good = np.broadcast_to(good, shape)
            value = np.broadcast_to(value, shape)
            bad = np.unravel_index(int(np.argmin(good)), shape) if shape else ()
            got = float(value[bad]) if shape else float(value)
            if shape and size > 1:
                at = f" at index {a + int(bad[0])}"
                if slips is not None and grid:
                    at = f" at parameter set {a + int(bad[0])}, slip {float(slip[0, bad[1]])!r}"
            elif shape and slips is not None and grid and slip.size > 1:
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
    shear: str
    nodes_per_panel: int | None  # None: solve_wheel's default
    max_steps: int
    dtype: np.dtype
    version: str
    terrain: Any  # template parameter sets (structure only; values come from inputs)
    distribution: Any
    names: dict[str, tuple[str, str]]  # column -> (owner, field path) of each leaf

    @property
    def n_chunks(self) -> int:
        return -(-self.n_points // self.chunk_size)

    @property
    def parameters(self) -> tuple[str, ...]:
        """Every parameter leaf, as column names: wheel, terrain, distribution."""
        return _WHEEL_FIELDS + tuple(self.names)

    @property
    def varying(self) -> tuple[str, ...]:
        """Parameter leaves that vary from row to row (stored as columns)."""
        return tuple(f for f in self.parameters if self.inputs[f].size > 1)

    @property
    def columns(self) -> dict[str, np.dtype]:
        cols = {"index": np.dtype(np.int64)}
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
        wheel = RigidWheel(**{f: columns[f] for f in _WHEEL_FIELDS})
        parts = {"terrain": {}, "distribution": {}}
        for name, (owner, path) in self.names.items():
            parts[owner][path] = columns[name]
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
            "terrain": type(self.terrain).__name__,
            "distribution": (
                None if self.distribution is None else type(self.distribution).__name__
            ),
            "parameter_names": list(self.parameters),
            "shape": list(self.shape),
            "n_points": self.n_points,
            "chunk_size": self.chunk_size,
            "n_chunks": self.n_chunks,
            "shear": self.shear,
            "nodes_per_panel": self.nodes_per_panel,
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


def _define(
    wheel,
    snow,
    loads,
    slips,
    *,
    grid,
    shear,
    chunk_size,
    nodes_per_panel,
    max_steps,
    distribution=None,
):
    import jax.numpy as jnp

    import snowjax

    from .._wheel.equilibrium import _check_model

    if shear not in _SHEAR_MODELS:
        raise ValueError(f"sweep: shear must be one of {_SHEAR_MODELS}, got {shear!r}")
    if nodes_per_panel is not None and (
        isinstance(nodes_per_panel, bool) or int(nodes_per_panel) < 2
    ):
        raise ValueError(f"sweep: nodes_per_panel must be >= 2, got {nodes_per_panel!r}")
    if (
        isinstance(chunk_size, bool)
        or not isinstance(chunk_size, (int, np.integer))
        or chunk_size < 1
    ):
        raise ValueError(f"sweep: chunk_size must be a positive integer, got {chunk_size!r}")
    if isinstance(max_steps, bool) or int(max_steps) < 1:
        raise ValueError(f"sweep: max_steps must be a positive integer, got {max_steps!r}")
    wheel_t, wheel_leaves = _leaf_arrays(wheel, RigidWheel, "wheel")
    terrain_t, terrain_leaves = _leaf_arrays(snow, Terrain, "snow", _TERRAIN_WHAT)
    dist_t, dist_leaves = None, {}
    if distribution is not None:
        dist_t, dist_leaves = _leaf_arrays(distribution, WongReece, "distribution")
    try:
        _check_model(wheel_t, terrain_t, dist_t, shear)
    except ValueError as err:
        raise ValueError(f"sweep: {err}") from None
    names = _parameter_names(
        terrain_t,
        dist_t,
        reserved=("index", "param_set", "load", "slip", *_WHEEL_FIELDS, *_OUTPUT_FIELDS, "status"),
    )
    leaves = {f: wheel_leaves[f] for f in _WHEEL_FIELDS}
    for name, (owner, path) in names.items():
        leaves[name] = (terrain_leaves if owner == "terrain" else dist_leaves)[path]
    inputs = {"load": np.asarray(loads), "slip": np.asarray(slips), **leaves}
    for name in ("load", "slip"):
        x = inputs[name]
        if x.ndim > 1:
            raise ValueError(f"sweep: {name}s must be a scalar or 1-D, got shape {x.shape}")
        if x.size == 0:
            raise ValueError(f"sweep: {name}s is empty")
    for name, x in inputs.items():
        if not (np.issubdtype(x.dtype, np.floating) or np.issubdtype(x.dtype, np.integer)):
            raise TypeError(f"sweep: {name} must be real numbers, got dtype {x.dtype}")
    dtype = np.dtype(jnp.result_type(float))
    rules = _rules()
    for name in ("load", "slip", *_WHEEL_FIELDS):
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
    # The terrain's and the distribution's own validity rules (those of solve_wheel).
    _check_parameter_sets(terrain_t, terrain_leaves, lambda t, _: t.constraints(shear), "", "snow")
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
        nodes_per_panel=None if nodes_per_panel is None else int(nodes_per_panel),
        max_steps=int(max_steps),
        dtype=dtype,
        version=snowjax.__version__,
        terrain=terrain_t,
        distribution=dist_t,
        names=names,
    )


# ---------------------------------------------------------------------------------------
# Files: atomic writes, chunk validation, manifest
# ---------------------------------------------------------------------------------------


def _chunk_name(k: int) -> str:
    return f"chunk_{k:06d}.npz"


def _tmp_name(final: str, tag: str) -> str:
    return f".{final}.tmp.{tag}"


def _fsync_dir(path: pathlib.Path) -> None:
    if not hasattr(os, "O_DIRECTORY"):  # pragma: no cover (Windows)
        return
    fd = os.open(path, os.O_RDONLY | os.O_DIRECTORY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


@contextlib.contextmanager
def _atomic(path: pathlib.Path, tag: str):
    """Open a temporary file next to `path`; on success fsync and rename it to `path`."""
    tmp = path.with_name(_tmp_name(path.name, tag))
    try:
        with open(tmp, "wb") as f:
            yield f
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
        _fsync_dir(path.parent)
    finally:
        if tmp.exists():
            tmp.unlink()


def _write_json(path: pathlib.Path, data, tag: str) -> None:
    with _atomic(path, tag) as f:
        f.write(json.dumps(data, indent=1).encode())


def _chunk_ok(path: pathlib.Path, d: _Definition, k: int) -> bool:
    """Whether chunk file k is complete: loads, right columns, dtypes and flat indices."""
    a, b = d.chunk_bounds(k)
    try:
        with np.load(path, allow_pickle=False) as z:
            if set(z.files) != set(d.columns):
                return False
            for name, dtype in d.columns.items():
                x = z[name]
                if x.shape != (b - a,) or x.dtype != dtype:
                    return False
            return bool(np.array_equal(z["index"], np.arange(a, b, dtype=np.int64)))
    except Exception:  # any unreadable file (truncated, not a zip, bad CRC) is incomplete
        return False


def _owner(k: int, process_count: int) -> int:
    """The process that computes chunk k: chunks are dealt round-robin."""
    return k % process_count


# ---------------------------------------------------------------------------------------
# Solving one chunk
# ---------------------------------------------------------------------------------------


class _Solver:
    """Dispatches chunks to `solve_wheel`, rows sharded over the devices of a 1-D mesh."""

    def __init__(self, d: _Definition, devices):
        import jax
        from jax.sharding import Mesh, NamedSharding, PartitionSpec

        self.d = d
        self.n_devices = len(devices)
        # Pad every chunk to the same multiple of the device count: one compile.
        self.padded = -(-d.chunk_size // self.n_devices) * self.n_devices
        if self.n_devices > 1:
            mesh = Mesh(np.asarray(devices), ("batch",))
            sharding = NamedSharding(mesh, PartitionSpec("batch"))
            self.place = lambda x: jax.device_put(x, sharding)  # noqa: E731
        else:
            # One device: leave the placement to jit, so the sweep shares its compiled
            # solve with plain `solve_wheel` calls of the same shape.
            self.place = lambda x: x  # noqa: E731

    def submit(self, k: int):
        """Start solving chunk k (asynchronous dispatch); returns a handle for `result`."""
        import jax.numpy as jnp

        from .._wheel.equilibrium import solve_wheel

        rows = self.d.chunk_inputs(k)
        n = rows["index"].size
        pad = lambda x: np.pad(x, (0, self.padded - n), mode="edge")  # noqa: E731
        x = {f: jnp.asarray(self.place(pad(rows[f]))) for f in ("load", "slip", *self.d.parameters)}
        wheel, terrain, distribution = self.d.build(x)
        state = solve_wheel(
            wheel,
            terrain,
            x["load"],
            x["slip"],
            self.d.shear,
            distribution=distribution,
            nodes_per_panel=self.d.nodes_per_panel,
            max_steps=self.d.max_steps,
        )
        return k, rows, n, state

    def result(self, handle) -> tuple[int, dict[str, np.ndarray]]:
        k, rows, n, state = handle
        out = {name: rows[name] for name in self.d.columns if name in rows}
        for name in (*_OUTPUT_FIELDS, "status"):
            out[name] = np.asarray(getattr(state, name))[:n].astype(self.d.columns[name])
        return k, {name: out[name] for name in self.d.columns}


# ---------------------------------------------------------------------------------------
# Consolidated outputs
# ---------------------------------------------------------------------------------------


def _write_csv(f, d: _Definition, chunk_paths) -> None:
    names = list(d.columns)
    float_fmt = "%.17g" if d.dtype == np.float64 else "%.9g"
    fmt = ["%d" if np.issubdtype(t, np.integer) else float_fmt for t in d.columns.values()]
    f.write((",".join(names) + "\n").encode())
    for path in chunk_paths:
        with np.load(path, allow_pickle=False) as z:
            table = np.column_stack([z[c].astype(np.float64) for c in names])
        np.savetxt(f, table, fmt=fmt, delimiter=",")


def _write_npz(f, d: _Definition, chunk_paths) -> None:
    """An `.npz` with one `.npy` member per column, streamed column by column."""
    from numpy.lib import format as npy

    with zipfile.ZipFile(f, "w", zipfile.ZIP_STORED, allowZip64=True) as zf:
        for name, dtype in d.columns.items():
            with zf.open(f"{name}.npy", "w", force_zip64=True) as member:
                header = {
                    "descr": npy.dtype_to_descr(dtype),
                    "fortran_order": False,
                    "shape": (d.n_points,),
                }
                npy.write_array_header_2_0(member, header)
                for path in chunk_paths:
                    with np.load(path, allow_pickle=False) as z:
                        member.write(np.ascontiguousarray(z[name], dtype=dtype).tobytes())


# ---------------------------------------------------------------------------------------
# Public API
# ---------------------------------------------------------------------------------------


@dataclasses.dataclass(frozen=True)
class SweepResult:
    """What `sweep` did.

    - `out`: the sweep directory.
    - `n_points`, `n_chunks`, `chunk_size`: size of the sweep.
    - `computed_chunks`: chunks solved by this call; `skipped_chunks`: valid chunks found
      on disk (a resumed sweep) or owned by other processes.
    - `complete`: every chunk is on disk (and the requested outputs were written).
    - `files`: format (`"npz"`, `"csv"`) -> path of the consolidated output.
    - `elapsed_s`: wall time of the call [s]; `points_per_second`: points solved by this
      call per second of solving and writing chunks (compile included).
    """

    out: pathlib.Path
    n_points: int
    n_chunks: int
    chunk_size: int
    computed_chunks: int
    skipped_chunks: int
    complete: bool
    files: dict[str, pathlib.Path]
    elapsed_s: float
    points_per_second: float


def _prepare_dir(out: pathlib.Path, d: _Definition, digest: str, resume: bool, tag: str):
    if out.exists() and not out.is_dir():
        raise ValueError(f"sweep: out={str(out)!r} exists and is not a directory")
    out.mkdir(parents=True, exist_ok=True)
    manifest_path = out / MANIFEST
    if not resume:
        for p in out.iterdir():
            if p.is_file() and _OUR_FILES.fullmatch(p.name):
                p.unlink()
    if manifest_path.exists():
        try:
            manifest = json.loads(manifest_path.read_text())
            old_digest = manifest["definition_hash"]
        except (ValueError, KeyError, TypeError) as err:
            raise ValueError(
                f"sweep: {manifest_path} is not a snowjax sweep manifest ({err}); use another"
                " directory or resume=False to start over"
            ) from None
        if old_digest != digest:
            old = manifest.get("definition", {})
            new = d.summary(with_values=False)
            diff = [
                f"{key}: {old.get(key)!r} on disk, {new[key]!r} now"
                for key in new
                if key != "columns" and old.get(key) != new[key]
            ]
            why = (
                "; ".join(diff) if diff else "the input values (loads, slips or parameters) differ"
            )
            raise ValueError(
                f"sweep: {out} holds a different sweep ({why}). Use another directory, or"
                " resume=False (`--restart` on the command line) to discard it."
            )
        return manifest
    if any(p.name.startswith("chunk_") for p in out.iterdir()):
        raise ValueError(
            f"sweep: {out} has chunk files but no {MANIFEST}, so they cannot be checked"
            " against this sweep; use another directory or resume=False to discard them"
        )
    manifest = {"definition_hash": digest, "definition": d.summary(), "outputs": {}}
    _write_json(manifest_path, manifest, tag)
    return manifest


def sweep(
    wheel: RigidWheel | Sequence[RigidWheel],
    snow: Terrain | Sequence[Terrain],
    loads: Float[ArrayLike, " loads"],
    slips: Float[ArrayLike, " slips"],
    *,
    shear: str = "classic",
    distribution: WongReece | Sequence[WongReece] | None = None,
    out: str | os.PathLike = "snowjax-sweep",
    chunk_size: int = 8192,
    grid: bool = True,
    progress: bool = True,
    resume: bool = True,
    formats: Sequence[str] = ("npz", "csv"),
    nodes_per_panel: int | None = None,
    max_steps: int = 64,
    devices: Sequence[Any] | None = None,
    process_index: int | None = None,
    process_count: int | None = None,
    callback: Callable[[int, pathlib.Path], None] | None = None,
) -> SweepResult:
    """Sweep the wheel equilibrium (4.14) over loads x slips x parameter sets, to disk.

    Chunked (memory of one chunk, whatever the number of points), resumable (run the
    same call again after an interruption: finished chunks are kept, missing or damaged
    ones recomputed, no row lost or duplicated), sharded over the local JAX devices,
    and shareable between processes.  Every row equals `solve_wheel` at its inputs.

    **Arguments:**

    - `wheel`: `RigidWheel`, or a list of them.  Leaves may be scalars or 1-D arrays
      (a leading batch of parameter sets).
    - `snow`: the terrain: a `snowjax.Terrain` (`WongSnow`, `BekkerSoil`, `ReeceSoil`,
      `LayeredSnow`; SI leaves, see their docs), or a list of terrains of one type;
      leaves scalar or 1-D like `wheel`.  In grid mode every leaf that varies (of
      wheel, terrain and distribution together) must have the same length P: parameter
      set p takes element p of each of them (zipped).
    - `loads`: wheel loads F_z [N], > 0 (scalar or 1-D).
    - `slips`: driving slips i [-] in [-1, 1] (scalar or 1-D).
    - `shear`: `"classic"`, `"simplified"` or `"none"` (see `solve_wheel`;
      `"simplified"` needs a `WongSnow` and no distribution).
    - `distribution`: `None` (the thesis's front-region stresses) or a `WongReece`
      (c1, c2, c3 [-]; scalar or 1-D leaves, or a list of them), as in `solve_wheel`.
      The terrain's and the distribution's types and leaf names are part of the sweep
      definition: a sweep of another terrain or distribution in `out` is refused.
    - `out`: directory for `manifest.json`, the chunks and the outputs.
    - `chunk_size`: rows per chunk C (rounded up to a multiple of the device count for
      the solve; the padding is discarded).  Memory grows with C, not with the number of
      points; C is part of the sweep definition.
    - `grid`: `True` for the Cartesian product P x loads x slips, flat index
      `(p * n_loads + l) * n_slips + s`; `False` for a list: loads, slips and the
      varying leaves are zipped (equal lengths, or length 1).  List inputs are read by
      slices, so `np.memmap` arrays work for inputs too large for RAM.
    - `progress`: show a `rich` progress bar (chunks, points/s).
    - `resume`: `True` resumes a sweep in `out` with the same definition (and refuses a
      different one); `False` deletes the sweep files in `out` and starts over.
    - `formats`: consolidated outputs to write once every chunk is done: `"npz"`
      (`sweep.npz`, one array per column) and/or `"csv"` (`sweep.csv`); `()` keeps only
      the chunk directory (the best choice for 1e8 points; read it with
      `iter_sweep_chunks`).
    - `nodes_per_panel`, `max_steps`: passed to `solve_wheel`.
    - `devices`: devices to shard each chunk over (default `jax.local_devices()`).
    - `process_index`, `process_count`: this process and the number of processes
      (default `jax.process_index()`, `jax.process_count()`, i.e. after
      `jax.distributed.initialize()`).  Chunk k is computed by process
      `k % process_count`; the process that finds every chunk on disk when it
      finishes writes the consolidated outputs.
    - `callback`: called as `callback(k, path)` after chunk k is safely on disk.

    **Returns:** `SweepResult`.  Rows are read back with `load_sweep` or
    `iter_sweep_chunks`.

    **Errors:** `ValueError` for out-of-range inputs (naming them), mismatched lengths,
    bad options, or an `out` directory holding a different sweep.
    """
    import jax

    start_time = time.perf_counter()
    formats = tuple(formats)
    for fmt in formats:
        if fmt not in _FORMATS:
            raise ValueError(f"sweep: formats must be among {_FORMATS}, got {fmt!r}")
    d = _define(
        wheel,
        snow,
        loads,
        slips,
        grid=grid,
        shear=shear,
        chunk_size=chunk_size,
        nodes_per_panel=nodes_per_panel,
        max_steps=max_steps,
        distribution=distribution,
    )
    p_count = jax.process_count() if process_count is None else int(process_count)
    p_index = jax.process_index() if process_index is None else int(process_index)
    if p_count < 1 or not 0 <= p_index < p_count:
        raise ValueError(
            f"sweep: need 0 <= process_index < process_count, got {p_index}, {p_count}"
        )
    devices = list(jax.local_devices() if devices is None else devices)
    if not devices:
        raise ValueError("sweep: devices is empty")
    out = pathlib.Path(out)
    tag = f"p{p_index}.{os.getpid()}"
    digest = d.digest()
    _prepare_dir(out, d, digest, resume, tag)

    # Chunks of this process: stray temporary files are left-overs of an interrupted
    # write (only the owner writes a chunk); finished chunks are validated and kept.
    mine = [k for k in range(d.n_chunks) if _owner(k, p_count) == p_index]
    for p in out.glob(".chunk_*.npz.tmp.*"):
        try:
            k = int(p.name[len(".chunk_") :].split(".")[0])
        except ValueError:
            continue
        if _owner(k, p_count) == p_index:
            p.unlink(missing_ok=True)
    done, damaged = set(), []
    for k in mine:
        path = out / _chunk_name(k)
        if path.exists():
            if _chunk_ok(path, d, k):
                done.add(k)
            else:
                damaged.append(k)
                path.unlink()
    if damaged:
        warnings.warn(
            f"sweep: {len(damaged)} incomplete or damaged chunk file(s) in {out} will be"
            f" recomputed: {', '.join(_chunk_name(k) for k in damaged[:5])}"
            + (" ..." if len(damaged) > 5 else ""),
            stacklevel=2,
        )
    todo = [k for k in mine if k not in done]

    computed_points, solve_time = 0, 0.0
    if todo:
        solver = _Solver(d, devices)
        with _progress_bar(progress, len(mine), len(done)) as bar:
            t0 = time.perf_counter()
            pending = solver.submit(todo[0])
            for i, k in enumerate(todo):
                # Dispatch chunk i + 1 before waiting for chunk i: solving overlaps writing.
                nxt = solver.submit(todo[i + 1]) if i + 1 < len(todo) else None
                k, rows = solver.result(pending)
                path = out / _chunk_name(k)
                with _atomic(path, tag) as f:
                    np.savez(f, **rows)
                computed_points += rows["index"].size
                solve_time = time.perf_counter() - t0
                bar(computed_points / solve_time)
                if callback is not None:
                    callback(k, path)
                pending = nxt

    # Everything on disk?  (Chunks of other processes are checked as they are now.)
    others = [k for k in range(d.n_chunks) if _owner(k, p_count) != p_index]
    complete = all(_chunk_ok(out / _chunk_name(k), d, k) for k in others)
    files = {}
    if complete:
        files = _finalize(out, d, digest, formats, tag, cleanup=p_count == 1)
    elapsed = time.perf_counter() - start_time
    return SweepResult(
        out=out,
        n_points=d.n_points,
        n_chunks=d.n_chunks,
        chunk_size=d.chunk_size,
        computed_chunks=len(todo),
        skipped_chunks=d.n_chunks - len(todo),
        complete=complete,
        files=files,
        elapsed_s=elapsed,
        points_per_second=computed_points / solve_time if solve_time > 0 else 0.0,
    )


@contextlib.contextmanager
def _progress_bar(show: bool, total: int, done: int):
    if not show:
        yield lambda rate: None
        return
    from rich.progress import (
        BarColumn,
        MofNCompleteColumn,
        Progress,
        TextColumn,
        TimeElapsedColumn,
        TimeRemainingColumn,
    )

    with Progress(
        TextColumn("[progress.description]{task.description}"),
        BarColumn(),
        MofNCompleteColumn(),
        TextColumn("chunks"),
        TextColumn("{task.fields[rate]}"),
        TimeElapsedColumn(),
        TimeRemainingColumn(),
    ) as prog:
        task = prog.add_task("sweep", total=total, completed=done, rate="")

        def advance(rate: float) -> None:
            prog.update(task, advance=1, rate=f"{rate:,.0f} points/s")

        yield advance


def _finalize(out, d, digest, formats, tag, cleanup) -> dict[str, pathlib.Path]:
    """Write the consolidated outputs that are missing or stale; record them."""
    manifest_path = out / MANIFEST
    if cleanup:
        for p in out.glob(".sweep.*.tmp.*"):
            p.unlink(missing_ok=True)
    manifest = json.loads(manifest_path.read_text())
    recorded = manifest.setdefault("outputs", {})
    chunks = [out / _chunk_name(k) for k in range(d.n_chunks)]
    files = {}
    for fmt in formats:
        path = out / _OUTPUT_FILES[fmt]
        entry = recorded.get(fmt)
        if not (entry and path.exists() and path.stat().st_size == entry.get("bytes")):
            writer = _write_npz if fmt == "npz" else _write_csv
            with _atomic(path, tag) as f:
                writer(f, d, chunks)
            recorded[fmt] = {"file": path.name, "rows": d.n_points, "bytes": path.stat().st_size}
            manifest["definition_hash"] = digest
            _write_json(manifest_path, manifest, tag)
        files[fmt] = path
    return files


def _read_manifest(out: pathlib.Path) -> dict:
    path = pathlib.Path(out) / MANIFEST
    if not path.exists():
        raise ValueError(f"{out} is not a snowjax sweep directory (no {MANIFEST})")
    return json.loads(path.read_text())


def iter_sweep_chunks(
    out: str | os.PathLike, columns: Sequence[str] | None = None
) -> Iterator[dict[str, np.ndarray]]:
    """Read a sweep directory chunk by chunk, in flat-index order (memory of one chunk).

    **Arguments:** `out`: the sweep directory; `columns`: names to read (default all;
    see the module docstring for names and units).

    **Yields:** one dict of 1-D NumPy arrays per chunk.  Raises `ValueError` if a chunk
    is missing (the sweep is unfinished: run it again to complete it).
    """
    out = pathlib.Path(out)
    definition = _read_manifest(out)["definition"]
    names = list(definition["columns"] if columns is None else columns)
    for k in range(definition["n_chunks"]):
        path = out / _chunk_name(k)
        if not path.exists():
            raise ValueError(f"{out}: {path.name} is missing; the sweep is not finished")
        with np.load(path, allow_pickle=False) as z:
            yield {c: z[c] for c in names}


def load_sweep(
    out: str | os.PathLike, columns: Sequence[str] | None = None
) -> dict[str, np.ndarray]:
    """All rows of a finished sweep as a dict of 1-D NumPy arrays, in flat-index order.

    Reads `sweep.npz` when it was written, the chunk files otherwise.  For sweeps too big
    for memory read a few `columns` or use `iter_sweep_chunks`.

    **Arguments:** `out`: the sweep directory; `columns`: names to read (default all).
    """
    out = pathlib.Path(out)
    manifest = _read_manifest(out)
    names = list(manifest["definition"]["columns"] if columns is None else columns)
    npz = out / _OUTPUT_FILES["npz"]
    entry = manifest.get("outputs", {}).get("npz")
    if entry and npz.exists() and npz.stat().st_size == entry.get("bytes"):
        with np.load(npz, allow_pickle=False) as z:
            return {c: z[c] for c in names}
    parts = list(iter_sweep_chunks(out, names))
    return {c: np.concatenate([p[c] for p in parts]) for c in names}
