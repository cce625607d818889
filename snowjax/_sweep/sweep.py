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
- **Sharded.**  The rows of a chunk are split over the local JAX devices, each device
  solving its slice as its own program (dispatched asynchronously, so the devices run
  concurrently; on a CPU, forced host devices gain nothing: use `workers`); with several
  processes (`jax.distributed.initialize`) chunk k is computed by process
  `k % process_count`, so the processes write disjoint chunks into a shared directory.
- **Both CPU cores.**  XLA:CPU solves one batch on about 1.4 of a machine's cores; a
  sweep on the CPU therefore runs `workers` processes, each pinned to its own core and
  computing chunks `k % workers` (the split above, run locally): on 2 cores the solve
  runs at 2.0x the throughput of one pinned core against 1.4x for one process
  (`benchmarks/run.py`).  Each worker compiles its own solve, so by default only sweeps
  of at least `AUTO_WORKERS_POINTS` points use them.
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
import json
import os
import pathlib
import time
import warnings
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
from jaxtyping import ArrayLike, Float

from .._terrain.base import Terrain
from .._wheel.geometry import AbstractWheel
from .._wheel.model import ContactModel, _as_model, _takes_model
from .definition import (
    _FORMATS,
    _OUR_FILES,
    _OUTPUT_FIELDS,
    _OUTPUT_FILES,
    MANIFEST,
    _define,
    _Definition,
)
from .storage import (
    _atomic,
    _chunk_name,
    _chunk_ok,
    _owner,
    _write_csv,
    _write_json,
    _write_npz,
)

# ---------------------------------------------------------------------------------------
# Solving one chunk
# ---------------------------------------------------------------------------------------


class _Solver:
    """Dispatches chunks to `solve_wheel`: each device solves its own slice of the chunk,
    one program per device, dispatched asynchronously."""

    def __init__(self, d: _Definition, devices):
        self.d = d
        self.devices = list(devices)
        self.n_devices = len(self.devices)
        # Pad every chunk to the same multiple of the device count: one program shape.
        self.padded = -(-d.chunk_size // self.n_devices) * self.n_devices

    def submit(self, k: int):
        """Start solving chunk k (asynchronous dispatch); returns a handle for `result`."""
        import jax
        import jax.numpy as jnp

        from .._wheel.equilibrium import solve_wheel

        rows = self.d.chunk_inputs(k)
        n = rows["index"].size
        pad = lambda x: np.pad(x, (0, self.padded - n), mode="edge")  # noqa: E731
        columns = {f: pad(rows[f]) for f in ("load", "slip", *self.d.parameters)}
        size = self.padded // self.n_devices
        states = []
        for j, device in enumerate(self.devices):
            if self.n_devices == 1:
                # Placement left to jit: the sweep shares its compiled solve with plain
                # `solve_wheel` calls of the same shape.
                x = {f: jnp.asarray(v) for f, v in columns.items()}
            else:
                # A slice per device, each its own program, not one program sharded over
                # a mesh: the batch-wide convergence test of the Newton loop would then
                # synchronise the devices every iteration (two host CPU devices, batch
                # 1e5: the sharded solve measured 0.8x one device's throughput).  On a
                # CPU, two host devices gain nothing over one device, which already
                # uses about 1.4 cores (XLA:CPU's threads); `workers` uses both.
                x = {
                    f: jax.device_put(v[j * size : (j + 1) * size], device)
                    for f, v in columns.items()
                }
            wheel, terrain, distribution = self.d.build(x)
            model = ContactModel(
                terrain,
                distribution,
                self.d.shear,
                None,
                self.d.nodes_per_panel,
                self.d.terms,
                self.d.accuracy,
            )
            states.append(
                solve_wheel(wheel, model, x["load"], x["slip"], max_steps=self.d.max_steps)
            )
        return k, rows, n, states

    def result(self, handle) -> tuple[int, dict[str, np.ndarray]]:
        k, rows, n, states = handle
        out = {name: rows[name] for name in self.d.columns if name in rows}
        for name in (*_OUTPUT_FIELDS, "status"):
            value = np.concatenate([np.asarray(getattr(state, name)) for state in states])
            out[name] = value[:n].astype(self.d.columns[name])
        return k, {name: out[name] for name in self.d.columns}


# ---------------------------------------------------------------------------------------
# Worker processes (both CPU cores)
# ---------------------------------------------------------------------------------------

# Sweeps with at least this many points use one worker process per available CPU core by
# default.  A worker first imports snowjax and compiles (about 7 s), so they pay off only
# for long sweeps: on 2 cores, 2e6 points took 13.0 s with 2 workers against 13.6 s with
# one process (4e5 points: 7.0 s against 6.1 s; 6e6: 29.4 s against 33.1 s).
AUTO_WORKERS_POINTS = 2_000_000


def _cores() -> list[int]:
    """CPU cores this process may run on."""
    if hasattr(os, "sched_getaffinity"):
        return sorted(os.sched_getaffinity(0))
    return list(range(os.cpu_count() or 1))


def _pin(core: int | None) -> None:
    """Pin this process to one core (where the OS allows it)."""
    if core is not None and hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {core})


def _default_workers(d: _Definition, objects, inputs, custom) -> int:
    """One worker per core for a long CPU sweep of snowjax's own types (which the workers
    can unpickle) whose inputs are small to pickle (a grid, or lists below 256 MiB); else 1.
    """
    import jax

    if any(x is not None for x in custom) or jax.default_backend() != "cpu":
        return 1
    if jax.process_count() > 1:  # jax.distributed: the processes already share the chunks
        return 1
    if d.n_points < AUTO_WORKERS_POINTS or len(_cores()) < 2:
        return 1
    if not all(type(x).__module__.startswith("snowjax.") for x in objects if x is not None):
        return 1
    if sum(np.asarray(x).nbytes for x in inputs) > 2**28:
        return 1
    return min(len(_cores()), d.n_chunks)


def _worker(args_path: str, x64: bool) -> None:
    """Entry point of a worker process: `python -c` calls it with its pickled arguments
    and the parent's float64 setting (applied before the arrays are unpickled)."""
    import pickle

    import jax

    jax.config.update("jax_enable_x64", x64)
    with open(args_path, "rb") as f:
        job = pickle.load(f)
    _pin(job.pop("core"))
    sweep(*job.pop("args"), **job)


def _start_workers(args, kwargs, chunk_size, count, cores):
    """Start workers 1..count-1 (the caller is worker 0); returns [(process, log, job)]."""
    import pickle
    import subprocess
    import sys
    import tempfile

    import jax

    started = []
    for index in range(1, count):
        job = dict(
            kwargs,
            args=args,
            run=SweepRun(chunk_size, process_index=index, process_count=count, workers=1),
            progress=False,
            formats=(),
            core=cores[index] if len(cores) >= count else None,
        )
        with tempfile.NamedTemporaryFile("wb", suffix=".pkl", delete=False) as f:
            pickle.dump(job, f)
        log = tempfile.TemporaryFile("w+")  # the worker's output, shown if it fails
        x64 = bool(jax.config.read("jax_enable_x64"))
        code = f"from snowjax._sweep.sweep import _worker; _worker({f.name!r}, {x64})"
        proc = subprocess.Popen([sys.executable, "-c", code], stdout=log, stderr=log)
        started.append((proc, log, pathlib.Path(f.name)))
    return started


def _join_workers(started, stop: bool = False) -> None:
    """Wait for the workers (terminating them first with `stop`); without `stop`, a
    failed one raises `RuntimeError` with the end of its output."""
    failures = []
    for proc, log, job in started:
        if stop:
            proc.terminate()
        code = proc.wait()
        log.seek(0)
        text = log.read()
        log.close()
        job.unlink(missing_ok=True)
        if code != 0:
            failures.append(f"a worker process exited with {code}: ...{text.strip()[-2000:]}")
    if failures and not stop:
        raise RuntimeError("sweep: " + "\n".join(failures))


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
                " directory or run=SweepRun(resume=False) to start over"
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
                " run=SweepRun(resume=False) (`--restart` on the command line) to discard it."
            )
        return manifest
    if any(p.name.startswith("chunk_") for p in out.iterdir()):
        raise ValueError(
            f"sweep: {out} has chunk files but no {MANIFEST}, so they cannot be checked"
            " against this sweep; use another directory or run=SweepRun(resume=False) to"
            " discard them"
        )
    manifest = {"definition_hash": digest, "definition": d.summary(), "outputs": {}}
    _write_json(manifest_path, manifest, tag)
    return manifest


@dataclasses.dataclass(frozen=True)
class SweepRun:
    """How a sweep is cut into chunks and who computes them (`run=` of `sweep`).

    - `chunk_size`: rows per chunk C (rounded up to a multiple of the device count for
      the solve; the padding is discarded).  Memory grows with C, not with the number
      of points; C is part of the sweep definition.  Default 8192.
    - `resume`: `True` (default) resumes a sweep in `out` with the same definition (and
      refuses a different one); `False` deletes the sweep files in `out` and starts over.
    - `devices`: devices to shard each chunk over (default `jax.local_devices()`).
    - `process_index`, `process_count`: this process and the number of processes
      (default `jax.process_index()`, `jax.process_count()`, i.e. after
      `jax.distributed.initialize()`).  Chunk k is computed by process
      `k % process_count`; the process that finds every chunk on disk when it
      finishes writes the consolidated outputs.
    - `callback`: called as `callback(k, path)` after chunk k is safely on disk.
    - `workers`: processes that share the chunks on this machine (chunk k by worker
      `k % workers`), each pinned to its own CPU core; this process is worker 0 and
      writes the outputs once all are done.  Default `None`: one per available core
      when the sweep runs on the CPU, has at least `AUTO_WORKERS_POINTS` (10^6) points
      and none of `devices`, `process_index`, `process_count` and `callback` is given;
      else 1.  `workers > 1` excludes those four.  The arguments are pickled to the
      workers, so a terrain, distribution, shear law or force term class of your own
      must be importable.
    """

    chunk_size: int = 8192
    resume: bool = True
    devices: Sequence[Any] | None = None
    process_index: int | None = None
    process_count: int | None = None
    callback: Callable[[int, pathlib.Path], None] | None = None
    workers: int | None = None


_MOVED_TO_RUN = {
    name: f"run=SweepRun({name}=...)"
    for name in (
        "chunk_size", "resume", "devices", "process_index", "process_count", "callback",
        "workers",
    )
}  # fmt: skip


@_takes_model(positional=4, **_MOVED_TO_RUN)
def sweep(
    wheel: AbstractWheel | Sequence[AbstractWheel],
    snow: Terrain | ContactModel | Sequence[Terrain],
    loads: Float[ArrayLike, " loads"],
    slips: Float[ArrayLike, " slips"],
    *,
    out: str | os.PathLike = "snowjax-sweep",
    grid: bool = True,
    formats: Sequence[str] = ("npz", "csv"),
    progress: bool = True,
    max_steps: int = 64,
    run: SweepRun = SweepRun(),
) -> SweepResult:
    """Sweep the wheel equilibrium (4.14) over loads x slips x parameter sets, to disk.

    Chunked (memory of one chunk, whatever the number of points), resumable (run the
    same call again after an interruption: finished chunks are kept, missing or damaged
    ones recomputed, no row lost or duplicated), sharded over the local JAX devices,
    and shareable between processes.  Every row equals `solve_wheel` at its inputs.

    **Arguments:**

    - `wheel`: `RigidWheel` or `DeflectingTire` (or another `AbstractWheel`), or a
      list of them of one type.  Leaves may be scalars or 1-D arrays (a leading batch of
      parameter sets); their columns are named by their fields (`diameter`,
      `inflation_pressure`, ...).
    - `snow`: the terrain: a `snowjax.Terrain` (`WongSnow`, `BekkerSoil`, `ReeceSoil`,
      `LayeredSnow`; SI leaves, see their docs), a list of terrains of one type, or a
      `ContactModel` (its shear law, stress distribution, nodes per panel and force
      terms, as in `solve_wheel`; `"simplified"` shear needs a `WongSnow` and no
      distribution); leaves scalar or 1-D like `wheel`.  In grid mode every leaf that
      varies (of wheel, terrain and distribution together) must have the same length
      P: parameter set p takes element p of each of them (zipped).  The terrain's and
      the distribution's types and leaf names are part of the sweep definition: a sweep
      of another terrain or distribution in `out` is refused.
    - `loads`: wheel loads F_z [N], > 0 (scalar or 1-D).
    - `slips`: driving slips i [-] in [-1, 1] (scalar or 1-D).
    - `out`: directory for `manifest.json`, the chunks and the outputs.
    - `grid`: `True` for the Cartesian product P x loads x slips, flat index
      `(p * n_loads + l) * n_slips + s`; `False` for a list: loads, slips and the
      varying leaves are zipped (equal lengths, or length 1).  List inputs are read by
      slices, so `np.memmap` arrays work for inputs too large for RAM.
    - `formats`: consolidated outputs to write once every chunk is done: `"npz"`
      (`sweep.npz`, one array per column) and/or `"csv"` (`sweep.csv`); `()` keeps only
      the chunk directory (the best choice for 1e8 points; read it with
      `iter_sweep_chunks`).
    - `progress`: show a `rich` progress bar (chunks, points/s).
    - `max_steps`: `solve_wheel`'s Newton iteration limit.
    - `run`: `SweepRun(chunk_size, resume, devices, process_index, process_count,
      callback, workers)`: the chunk size, resuming, and the devices, processes and
      workers that share the chunks (default: chunks of 8192 rows, resumed, on the
      local devices, one worker per core from 10^6 points on the CPU).

    **Returns:** `SweepResult`.  Rows are read back with `load_sweep` or
    `iter_sweep_chunks`.

    **Errors:** `ValueError` for out-of-range inputs (naming them), mismatched lengths,
    bad options, or an `out` directory holding a different sweep.
    """
    import jax

    start_time = time.perf_counter()
    formats = _checked_formats(formats)
    if not isinstance(run, SweepRun):
        raise TypeError(f"sweep: run must be a snowjax.SweepRun, got {type(run).__name__}")
    given = snow  # the workers get the arguments as given
    chunk_size, devices, callback = run.chunk_size, run.devices, run.callback
    model = _as_model(snow, "snow")
    snow, distribution = model.terrain, model.distribution
    d = _define(wheel, model, loads, slips, grid=grid, chunk_size=chunk_size, max_steps=max_steps)
    p_index, p_count = _process(run.process_index, run.process_count)
    custom = (devices, run.process_index, run.process_count, callback)
    n_workers = _worker_count(run.workers, d, (wheel, snow, distribution), (loads, slips), custom)
    if n_workers > 1:
        p_index, p_count = 0, n_workers
    devices = list(jax.local_devices() if devices is None else devices)
    if not devices:
        raise ValueError("sweep: devices is empty")
    out = pathlib.Path(out)
    tag = f"p{p_index}.{os.getpid()}"
    digest = d.digest()
    _prepare_dir(out, d, digest, run.resume, tag)

    mine = [k for k in range(d.n_chunks) if _owner(k, p_count) == p_index]
    done = _chunks_on_disk(out, d, mine, p_index, p_count)
    todo = [k for k in mine if k not in done]

    started, affinity = [], None
    # Workers 1..n-1 run in processes of their own (this process is worker 0); their
    # chunks still to compute (missing or damaged now) count as computed here.
    theirs = [
        k
        for k in range(d.n_chunks)
        if n_workers > 1 and _owner(k, n_workers) != 0 and not _chunk_ok(out / _chunk_name(k), d, k)
    ]
    todo += theirs
    if theirs:
        kwargs: dict[str, Any] = dict(out=out, grid=grid, max_steps=max_steps)
        cores = _cores()
        started = _start_workers((wheel, given, loads, slips), kwargs, chunk_size, n_workers, cores)
        if len(cores) >= n_workers and hasattr(os, "sched_setaffinity"):
            affinity = os.sched_getaffinity(0)
            _pin(cores[0])
    computed_points = sum(min(d.chunk_size, d.n_points - k * d.chunk_size) for k in todo)
    solve_time = 0.0
    try:
        if todo:
            on_disk = d.n_chunks - len(todo) if started else len(done)
            total = d.n_chunks if started else len(mine)
            solve_time = _compute(
                d, devices, out, todo, total, on_disk, progress, tag, callback, started
            )
    except BaseException:  # e.g. KeyboardInterrupt: stop the workers too
        _join_workers(started, stop=True)
        raise
    finally:
        if affinity is not None:
            os.sched_setaffinity(0, affinity)
    _join_workers(started)
    if n_workers > 1:  # every chunk is this sweep's now
        p_index, p_count = 0, 1

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


def _checked_formats(formats) -> tuple[str, ...]:
    formats = tuple(formats)
    for fmt in formats:
        if fmt not in _FORMATS:
            raise ValueError(f"sweep: formats must be among {_FORMATS}, got {fmt!r}")
    return formats


def _process(process_index, process_count) -> tuple[int, int]:
    """(this process's index, the number of processes): JAX's where not given."""
    import jax

    p_count = jax.process_count() if process_count is None else int(process_count)
    p_index = jax.process_index() if process_index is None else int(process_index)
    if p_count < 1 or not 0 <= p_index < p_count:
        raise ValueError(
            f"sweep: need 0 <= process_index < process_count, got {p_index}, {p_count}"
        )
    return p_index, p_count


def _chunks_on_disk(out, d, mine, p_index, p_count) -> set[int]:
    """This process's chunks (`mine`) already on disk and valid.

    Stray temporary files are left-overs of an interrupted write (only the owner writes
    a chunk) and are removed; damaged chunk files are removed with a warning (they will
    be recomputed)."""
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
            stacklevel=3,
        )
    return done


def _worker_count(workers, d, trees, inputs, custom) -> int:
    """The processes sharing the chunks: `workers`, or by default one per core from
    1,000,000 points on (`_default_workers`); `ValueError` for a count below 1 or workers
    with a custom device, process or callback setting."""
    if workers is None:
        objects = [
            x for tree in trees for x in (tree if isinstance(tree, (list, tuple)) else [tree])
        ]
        n_workers = _default_workers(d, objects, inputs, custom)
    else:
        n_workers = int(workers)
    if n_workers < 1:
        raise ValueError(f"sweep: workers must be >= 1, got {workers}")
    if n_workers > 1 and any(x is not None for x in custom):
        raise ValueError(
            "sweep: workers > 1 excludes devices, process_index, process_count and callback"
        )
    return n_workers


def _compute(d, devices, out, todo, total, on_disk, progress, tag, callback, workers):
    """Solve and write this process's chunks of `todo` (all of them without `workers`),
    then, with workers, wait for them, the bar counting every chunk file written;
    returns the seconds taken."""
    solver = _Solver(d, devices)
    mine = [k for k in todo if not workers or _owner(k, len(workers) + 1) == 0]
    t0 = time.perf_counter()
    points = 0

    def count() -> int:  # chunks on disk (workers write theirs meanwhile)
        return on_disk + sum((out / _chunk_name(k)).exists() for k in todo)

    with _progress_bar(progress, total, on_disk) as bar:
        pending = solver.submit(mine[0]) if mine else None
        for i, k in enumerate(mine):
            # Dispatch chunk i + 1 before waiting for chunk i: solving overlaps writing.
            nxt = solver.submit(mine[i + 1]) if i + 1 < len(mine) else None
            k, rows = solver.result(pending)
            path = out / _chunk_name(k)
            with _atomic(path, tag) as f:
                np.savez(f, **rows)  # pyright: ignore[reportArgumentType]  (column arrays only)
            points += rows["index"].size
            done = count() if workers else None
            rate = (points if done is None else (done - on_disk) * d.chunk_size) / (
                time.perf_counter() - t0
            )
            bar(rate, done)
            if callback is not None:
                callback(k, path)
            pending = nxt
        while workers and any(proc.poll() is None for proc, _, _ in workers):
            time.sleep(0.2)
            done = count()
            bar((done - on_disk) * d.chunk_size / (time.perf_counter() - t0), done)
    return time.perf_counter() - t0


def rate_text(rate: float) -> str:
    """A rate for people: thousands separated above 100, three significant digits below
    (a sweep of a few points runs at a few points per second, compile included)."""
    return f"{rate:,.0f}" if rate >= 100 else f"{rate:.3g}"


@contextlib.contextmanager
def _progress_bar(show: bool, total: int, done: int):
    if not show:
        yield lambda rate, completed=None: None
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

        def advance(rate: float, completed: int | None = None) -> None:
            """One more chunk done, or `completed` chunks done in all."""
            text = f"{rate_text(rate)} points/s"
            if completed is None:
                prog.update(task, advance=1, rate=text)
            else:
                prog.update(task, completed=completed, rate=text)

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
