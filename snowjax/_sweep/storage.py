"""Sweep files: atomic writes, chunk validation, the manifest, consolidated outputs, and
reading a finished sweep back (`load_sweep`, `iter_sweep_chunks`).
"""

from __future__ import annotations

import contextlib
import json
import os
import pathlib
import zipfile
from collections.abc import Iterator, Sequence

import numpy as np

from .definition import (
    _OUTPUT_FILES,
    MANIFEST,
    _Definition,
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
