"""Chunked, resumable, sharded sweeps (`snowjax.sweep`, `snowjax sweep`).

Every sweep here uses chunks of 8 rows with the default solver options, so the jitted
solve compiles once per process (the reference `solve_wheel` calls use the same shape
and share it).  The 4-device sharded sweep (a subprocess) starts with the module, so
its compiles overlap the other tests.
"""

from __future__ import annotations

import json
import os
import pathlib
import re
import shutil
import subprocess
import sys
import textwrap

import numpy as np
import pytest

import snowjax as sj
from snowjax._cli.app import main
from snowjax._sweep import sweep as _sweep
from tests.notebook_runner import outputs_text, run_notebook

REPO = pathlib.Path(__file__).resolve().parents[1]
C = 8  # chunk size of every sweep in this file
WHEEL = sj.RigidWheel.thesis_tire()
P_W = np.array([60e3, 85.55e3])
SNOW = sj.WongSnow.thesis_fresh_snow(p_w=P_W)  # two parameter sets: p_w and cohesion vary
LOADS = np.array([3000.0, 6000.0])
SLIPS = np.linspace(0.0, 0.8, 5)
N = P_W.size * LOADS.size * SLIPS.size  # 20 points: chunks of 8, 8 and 4 (padded)
OUTPUTS = ("entry_angle", "sinkage", "motion_resistance", "thrust", "drawbar_pull", "torque")

SHARDED_SCRIPT = textwrap.dedent(
    """
    import sys
    import jax
    jax.config.update("jax_enable_x64", True)
    import numpy as np
    import snowjax as sj
    assert len(jax.devices()) == 4, jax.devices()
    r = sj.sweep(
        sj.RigidWheel.thesis_tire(),
        sj.WongSnow.thesis_fresh_snow(p_w=np.array([60e3, 85.55e3])),
        np.array([3000.0, 6000.0]), np.linspace(0.0, 0.8, 5),
        out=sys.argv[1], progress=False, formats=("npz",), run=sj.SweepRun(chunk_size=8),
    )
    assert r.complete and r.computed_chunks == 3, r
    """
)


class _Background:
    """Slow, independent work started when the module starts (it overlaps the tests)."""

    def __init__(self, tmp_path_factory, names):
        self.sharded_out = tmp_path_factory.mktemp("sharded") / "sweep"
        self.proc = None
        if "test_sharded_sweep_equals_single_device" in names:
            # The same sweep on 4 (virtual CPU) devices, in a fresh process.
            env = dict(
                os.environ,
                XLA_FLAGS=os.environ.get("XLA_FLAGS", "")
                + " --xla_force_host_platform_device_count=4",
                JAX_PLATFORMS="cpu",
            )
            self.proc = subprocess.Popen(
                [sys.executable, "-c", SHARDED_SCRIPT, str(self.sharded_out)],
                cwd=REPO,
                env=env,
                stdout=subprocess.PIPE,
                stderr=subprocess.STDOUT,
                text=True,
            )


@pytest.fixture(scope="module", autouse=True)
def background(request, tmp_path_factory):
    names = {item.name for item in request.session.items}
    work = _Background(tmp_path_factory, names)
    yield work
    if work.proc is not None and work.proc.poll() is None:
        work.proc.kill()
        work.proc.wait()


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    """An uninterrupted single-device sweep: its directory and rows."""
    out = tmp_path_factory.mktemp("reference") / "sweep"
    result = sj.sweep(
        WHEEL, SNOW, LOADS, SLIPS, out=out, progress=False, run=sj.SweepRun(chunk_size=C)
    )
    assert result.complete and result.computed_chunks == 3 and result.skipped_chunks == 0
    return out, sj.load_sweep(out)


def _direct(wheel_leaves, snow_leaves, load, slip):
    """`solve_wheel` on flat inputs, in blocks of C (the last one padded, then cut)."""
    n = load.size
    pad = lambda x: np.pad(np.broadcast_to(x, (n,))[a:b], (0, C - (b - a)), mode="edge")  # noqa: E731
    parts = []
    for a in range(0, n, C):
        b = min(a + C, n)
        st = sj.solve_wheel(
            sj.RigidWheel(**{k: pad(v) for k, v in wheel_leaves.items()}),
            sj.WongSnow(**{k: pad(v) for k, v in snow_leaves.items()}),
            pad(load),
            pad(slip),
        )
        parts.append({f: np.asarray(getattr(st, f))[: b - a] for f in (*OUTPUTS, "status")})
    return {f: np.concatenate([p[f] for p in parts]) for f in parts[0]}


def _assert_rows_equal(got, want):
    assert list(got) == list(want)
    for name in want:
        np.testing.assert_array_equal(got[name], want[name], err_msg=name)
        assert got[name].dtype == want[name].dtype, name


def test_grid_sweep_equals_solve_wheel(reference):
    out, rows = reference
    # The grid (parameter set, load, slip), slip fastest, built here independently.
    p, l, s = (
        g.reshape(-1) for g in np.meshgrid(np.arange(2), np.arange(2), np.arange(5), indexing="ij")
    )
    np.testing.assert_array_equal(rows["index"], np.arange(N))
    np.testing.assert_array_equal(rows["param_set"], p)
    np.testing.assert_array_equal(rows["load"], LOADS[l])
    np.testing.assert_array_equal(rows["slip"], SLIPS[s])
    np.testing.assert_array_equal(rows["p_w"], P_W[p])
    np.testing.assert_array_equal(rows["cohesion"], np.asarray(SNOW.cohesion)[p])
    assert "z_w" not in rows and "diameter" not in rows  # constant leaves are not columns
    want = _direct(
        {"diameter": WHEEL.diameter, "width": WHEEL.width},
        {
            "p_w": P_W[p],
            "z_w": SNOW.z_w,
            "cohesion": np.asarray(SNOW.cohesion)[p],
            "tan_phi": SNOW.tan_phi,
            "shear_modulus": SNOW.shear_modulus,
        },
        LOADS[l],
        SLIPS[s],
    )
    for name in OUTPUTS:
        np.testing.assert_allclose(rows[name], want[name], rtol=1e-12, atol=0, err_msg=name)
    np.testing.assert_array_equal(rows["status"], want["status"])
    assert np.all(rows["status"] == sj.Status.CONVERGED)
    # The CSV holds the same rows, losslessly (%.17g), and the chunks agree with sweep.npz.
    table = np.loadtxt(out / "sweep.csv", delimiter=",", skiprows=1)
    header = (out / "sweep.csv").read_text().splitlines()[0].split(",")
    assert header == list(rows)
    for j, name in enumerate(header):
        np.testing.assert_array_equal(table[:, j], rows[name].astype(float), err_msg=name)
    chunks = list(sj.iter_sweep_chunks(out))
    assert [c["index"].size for c in chunks] == [8, 8, 4]
    _assert_rows_equal({k: np.concatenate([c[k] for c in chunks]) for k in rows}, rows)


def test_list_sweep_equals_solve_wheel(tmp_path):
    rng = np.random.default_rng(3)
    n = 11
    loads = rng.uniform(2000.0, 7000.0, n)
    slips = rng.uniform(-0.3, 0.9, n)
    p_w = rng.uniform(50e3, 120e3, n)
    np.save(tmp_path / "loads.npy", loads)
    loads_mm = np.load(tmp_path / "loads.npy", mmap_mode="r")  # inputs are read by slices
    snow = sj.WongSnow(p_w, 0.2, 15e3, 0.0787, 0.01)
    r = sj.sweep(
        WHEEL,
        snow,
        loads_mm,
        slips,
        grid=False,
        out=tmp_path / "s",
        progress=False,
        formats=("npz",),
        run=sj.SweepRun(chunk_size=C),
    )
    assert r.n_points == n and r.n_chunks == 2 and r.files == {"npz": tmp_path / "s/sweep.npz"}
    rows = sj.load_sweep(tmp_path / "s")
    assert list(rows) == ["index", "load", "slip", "p_w", *OUTPUTS, "status"]
    np.testing.assert_array_equal(rows["load"], loads)
    want = _direct(
        {"diameter": WHEEL.diameter, "width": WHEEL.width},
        {"p_w": p_w, "z_w": 0.2, "cohesion": 15e3, "tan_phi": 0.0787, "shear_modulus": 0.01},
        loads,
        slips,
    )
    for name in OUTPUTS:
        np.testing.assert_allclose(rows[name], want[name], rtol=1e-12, atol=0, err_msg=name)
    np.testing.assert_array_equal(rows["status"], want["status"])
    assert not (tmp_path / "s/sweep.csv").exists()


def test_interrupted_sweep_resumes_row_for_row(reference, tmp_path):
    ref_out, ref_rows = reference
    out = tmp_path / "s"

    def stop_after_first(k, path):
        assert path.exists()
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        sj.sweep(
            WHEEL,
            SNOW,
            LOADS,
            SLIPS,
            out=out,
            progress=False,
            run=sj.SweepRun(chunk_size=C, callback=stop_after_first),
        )
    assert sorted(p.name for p in out.iterdir()) == ["chunk_000000.npz", "manifest.json"]
    with pytest.raises(ValueError, match="not finished"):
        sj.load_sweep(out)
    seen = []
    r = sj.sweep(
        WHEEL,
        SNOW,
        LOADS,
        SLIPS,
        out=out,
        progress=False,
        run=sj.SweepRun(chunk_size=C, callback=lambda k, path: seen.append(k)),
    )
    assert seen == [1, 2] and r.computed_chunks == 2 and r.skipped_chunks == 1 and r.complete
    _assert_rows_equal(sj.load_sweep(out), ref_rows)
    for name in ("sweep.csv", "sweep.npz", "chunk_000000.npz", "chunk_000002.npz"):
        assert (out / name).read_bytes() == (ref_out / name).read_bytes(), name
    # A finished sweep run again computes nothing and rewrites nothing.
    mtime = (out / "sweep.csv").stat().st_mtime_ns
    r = sj.sweep(WHEEL, SNOW, LOADS, SLIPS, out=out, progress=False, run=sj.SweepRun(chunk_size=C))
    assert r.computed_chunks == 0 and r.complete
    assert (out / "sweep.csv").stat().st_mtime_ns == mtime


def test_damaged_files_are_detected_and_recomputed(reference, tmp_path):
    ref_out, ref_rows = reference
    out = tmp_path / "s"
    shutil.copytree(ref_out, out)
    chunk = out / "chunk_000001.npz"
    chunk.write_bytes(chunk.read_bytes()[:1000])  # truncated by a crash mid-write
    stray = out / ".chunk_000002.npz.tmp.p0.12345"  # left by a killed process
    stray.write_bytes(b"partial")
    (out / "sweep.npz").write_bytes((out / "sweep.npz").read_bytes()[:-10])
    (out / "sweep.csv").unlink()
    with pytest.warns(UserWarning, match="chunk_000001.npz"):
        r = sj.sweep(
            WHEEL, SNOW, LOADS, SLIPS, out=out, progress=False, run=sj.SweepRun(chunk_size=C)
        )
    assert r.computed_chunks == 1 and r.skipped_chunks == 2 and r.complete
    assert not stray.exists()
    _assert_rows_equal(sj.load_sweep(out), ref_rows)
    for name in ("sweep.csv", "sweep.npz", "chunk_000001.npz"):
        assert (out / name).read_bytes() == (ref_out / name).read_bytes(), name
    # A chunk with the wrong rows (e.g. from another sweep) is rejected too.
    np.savez(out / "chunk_000002.npz", **{k: v[:4] for k, v in ref_rows.items()})
    assert not _sweep._chunk_ok(out / "chunk_000002.npz", _definition(), 2)
    assert _sweep._chunk_ok(out / "chunk_000000.npz", _definition(), 0)


def _definition(**kw):
    """The sweep's definition; `shear=` and `nodes_per_panel=` go into the model."""
    parts = {k: kw.pop(k) for k in ("shear", "nodes_per_panel") if k in kw}
    args = dict(grid=True, chunk_size=C, max_steps=64) | kw
    return _sweep._define(WHEEL, sj.ContactModel(SNOW, **parts), LOADS, SLIPS, **args)


def test_a_different_sweep_is_refused(reference, tmp_path):
    out = tmp_path / "s"
    shutil.copytree(reference[0], out)
    # A ContactModel holding the same terrain is the same sweep: nothing left to compute.
    r = sj.sweep(
        WHEEL,
        sj.ContactModel(SNOW),
        LOADS,
        SLIPS,
        out=out,
        progress=False,
        run=sj.SweepRun(chunk_size=C),
    )
    assert r.complete and r.computed_chunks == 0 and r.skipped_chunks == r.n_chunks
    with pytest.raises(ValueError, match="chunk_size: 8 on disk, 4 now"):
        sj.sweep(WHEEL, SNOW, LOADS, SLIPS, out=out, progress=False, run=sj.SweepRun(chunk_size=4))
    with pytest.raises(ValueError, match="shear: 'classic' on disk, 'none' now"):
        sj.sweep(
            WHEEL,
            sj.ContactModel(SNOW, shear="none"),
            LOADS,
            SLIPS,
            out=out,
            run=sj.SweepRun(chunk_size=C),
        )
    with pytest.raises(ValueError, match="input values"):
        sj.sweep(
            WHEEL, SNOW, LOADS + 1.0, SLIPS, out=out, progress=False, run=sj.SweepRun(chunk_size=C)
        )
    (out / "manifest.json").unlink()
    with pytest.raises(ValueError, match="no manifest.json"):
        sj.sweep(WHEEL, SNOW, LOADS, SLIPS, out=out, progress=False, run=sj.SweepRun(chunk_size=C))
    # resume=False starts over, deleting the sweep's files and nothing else.
    (out / "notes.txt").write_text("mine")
    r = sj.sweep(
        WHEEL,
        SNOW,
        LOADS,
        SLIPS,
        out=out,
        progress=False,
        formats=("npz",),
        run=sj.SweepRun(chunk_size=C, resume=False),
    )
    assert r.computed_chunks == 3 and r.complete
    assert sorted(p.name for p in out.iterdir()) == [
        "chunk_000000.npz",
        "chunk_000001.npz",
        "chunk_000002.npz",
        "manifest.json",
        "notes.txt",
        "sweep.npz",
    ]
    _assert_rows_equal(sj.load_sweep(out), reference[1])
    # The definition hash covers every input and option, and only those.
    base = _definition().digest()
    assert _definition().digest() == base
    for kw in (
        dict(chunk_size=4),
        dict(shear="none"),
        dict(max_steps=32),
        dict(nodes_per_panel=12),
        dict(grid=False),
    ):
        try:
            other = _definition(**kw).digest()
        except ValueError:  # grid=False: these inputs cannot be zipped
            continue
        assert other != base, kw


def test_chunks_are_dealt_to_processes(reference, tmp_path):
    for n_chunks, count in ((10, 3), (7, 1), (5, 8)):
        owners = [_sweep._owner(k, count) for k in range(n_chunks)]
        for index in range(count):
            mine = [k for k in range(n_chunks) if owners[k] == index]
            assert mine == list(range(index, n_chunks, count))
    # Two "processes" sharing a directory: each writes only its chunks; the one that
    # finds every chunk on disk writes the outputs.
    out = tmp_path / "s"
    written = {0: [], 1: []}
    r0 = sj.sweep(
        WHEEL,
        SNOW,
        LOADS,
        SLIPS,
        out=out,
        progress=False,
        run=sj.SweepRun(
            chunk_size=C,
            process_index=0,
            process_count=2,
            callback=lambda k, p: written[0].append(k),
        ),
    )
    assert written[0] == [0, 2] and not r0.complete and r0.files == {}
    assert not (out / "chunk_000001.npz").exists() and not (out / "sweep.csv").exists()
    r1 = sj.sweep(
        WHEEL,
        SNOW,
        LOADS,
        SLIPS,
        out=out,
        progress=False,
        run=sj.SweepRun(
            chunk_size=C,
            process_index=1,
            process_count=2,
            callback=lambda k, p: written[1].append(k),
        ),
    )
    assert written[1] == [1] and r1.complete and set(r1.files) == {"npz", "csv"}
    _assert_rows_equal(sj.load_sweep(out), reference[1])


@pytest.mark.slow  # worker processes, each compiling (make test-slow)
def test_worker_processes_write_the_same_rows(reference, tmp_path):
    # Three local workers (this process and two pinned children) deal the 3 chunks.
    out = tmp_path / "w"
    result = sj.sweep(
        WHEEL, SNOW, LOADS, SLIPS, out=out, progress=False, run=sj.SweepRun(chunk_size=C, workers=3)
    )
    assert result.complete and result.computed_chunks == 3 and result.skipped_chunks == 0
    assert result.files and not list(out.glob(".chunk_*"))  # no temporary files left
    _assert_rows_equal(sj.load_sweep(out), reference[1])
    # A resume finds everything on disk and starts no worker.
    again = sj.sweep(
        WHEEL, SNOW, LOADS, SLIPS, out=out, progress=False, run=sj.SweepRun(chunk_size=C, workers=3)
    )
    assert again.complete and again.computed_chunks == 0 and again.skipped_chunks == 3
    # The default uses workers only for long CPU sweeps.
    d = _definition()
    assert d.n_points < _sweep.AUTO_WORKERS_POINTS
    assert _sweep._default_workers(d, [WHEEL, SNOW], (LOADS, SLIPS), (None,) * 4) == 1
    with pytest.raises(ValueError, match="workers must be >= 1"):
        sj.sweep(
            WHEEL, SNOW, LOADS, SLIPS, out=tmp_path / "x", run=sj.SweepRun(chunk_size=C, workers=0)
        )
    with pytest.raises(ValueError, match="excludes devices"):
        sj.sweep(
            WHEEL,
            SNOW,
            LOADS,
            SLIPS,
            out=tmp_path / "x",
            run=sj.SweepRun(callback=lambda k, p: None, workers=2),
        )


def test_bad_inputs_raise_clear_errors(tmp_path):
    out = tmp_path / "s"
    cases = [
        (
            dict(loads=np.array([3000.0, -1.0])),
            "loads must be finite and > 0 N; got -1.0 at index 1",
        ),
        (dict(slips=np.array([0.1, 1.5])), "slips must be finite and in \\[-1, 1\\]"),
        (dict(snow=sj.WongSnow(85e3, 0.2, 15e3, -0.1, 0.01)), "tan_phi must be finite and >= 0"),
        (
            dict(
                snow=sj.WongSnow(np.array([60e3, 80e3]), np.array([0.1, 0.2, 0.3]), 1e4, 0.1, 0.01)
            ),
            "same length",
        ),
        (dict(loads=np.ones((2, 2))), "loads must be a scalar or 1-D"),
        (dict(grid=False), "same length"),
        (dict(run=sj.SweepRun(chunk_size=0)), "chunk_size must be a positive integer"),
        (dict(formats=("parquet",)), "formats must be among"),
    ]
    for change, message in cases:
        kw = dict(wheel=WHEEL, snow=SNOW, loads=LOADS, slips=SLIPS, out=out, run=sj.SweepRun(C))
        kw.update(change)
        with pytest.raises(ValueError, match=message):
            sj.sweep(**kw)
    with pytest.raises(TypeError, match="RigidWheel"):
        sj.sweep(SNOW, SNOW, LOADS, SLIPS, out=out)
    with pytest.raises(TypeError, match=r"run must be a snowjax.SweepRun, got int"):
        sj.sweep(WHEEL, SNOW, LOADS, SLIPS, out=out, run=C)
    with pytest.raises(TypeError, match=r"sweep\(chunk_size=...\) is now spelled run=SweepRun"):
        sj.sweep(WHEEL, SNOW, LOADS, SLIPS, out=out, chunk_size=C)
    with pytest.raises(TypeError, match=r"sweep\(shear=...\) is now spelled ContactModel"):
        sj.sweep(WHEEL, SNOW, LOADS, SLIPS, out=out, shear="none")
    with pytest.raises(ValueError, match="process_index"):
        sj.sweep(
            WHEEL, SNOW, LOADS, SLIPS, out=out, run=sj.SweepRun(process_index=2, process_count=2)
        )
    (tmp_path / "file").write_text("")
    with pytest.raises(ValueError, match="not a directory"):
        sj.sweep(WHEEL, SNOW, LOADS, SLIPS, out=tmp_path / "file", run=sj.SweepRun(chunk_size=C))
    assert not out.exists()  # nothing written for a bad definition


def test_sharded_sweep_equals_single_device(background, reference):
    proc, out = background.proc, background.sharded_out
    log, _ = proc.communicate(timeout=300)
    assert proc.returncode == 0, log
    rows = sj.load_sweep(out)
    ref = reference[1]
    assert list(rows) == list(ref)
    for name in ref:
        if name in OUTPUTS:
            np.testing.assert_allclose(rows[name], ref[name], rtol=1e-12, atol=0, err_msg=name)
        else:
            np.testing.assert_array_equal(rows[name], ref[name], err_msg=name)


def test_cli_sweep_resumes_and_reports_bad_specs(reference, tmp_path, capsys):
    out = tmp_path / "cli"
    argv = [
        "sweep",
        "--loads",
        "3000,6000",
        "--slips",
        "0:0.8:5",
        "--p-w",
        "60e3,85.55e3",
        "--chunk-size",
        "8",
        "--out",
        str(out),
        "--no-progress",
    ]
    assert main(argv) == 0
    assert "20 points in 3 chunk(s) of 8 (3 computed, 0 already" in capsys.readouterr().out
    # The thesis preset with two p_w values (cohesion = 0.2165 p_w): the reference sweep.
    _assert_rows_equal(sj.load_sweep(out), reference[1])
    assert (out / "sweep.csv").read_bytes() == (reference[0] / "sweep.csv").read_bytes()
    assert main(argv) == 0  # the same command again: nothing left to compute
    assert "(0 computed, 3 already" in capsys.readouterr().out
    # --param-grid: the p_w and cohesion lists combine into 4 parameter sets.
    grid_argv = argv[:-3] + [
        "--cohesion",
        "12990,18521",
        "--param-grid",
        "--format",
        "none",
        "--out",
        str(tmp_path / "grid"),
        "--no-progress",
    ]
    assert main(grid_argv) == 0
    rows = sj.load_sweep(tmp_path / "grid")
    assert rows["index"].size == 40 and not (tmp_path / "grid/sweep.csv").exists()
    assert list(zip(rows["p_w"][::10], rows["cohesion"][::10])) == [
        (60e3, 12990.0),
        (60e3, 18521.0),
        (85.55e3, 12990.0),
        (85.55e3, 18521.0),
    ]
    capsys.readouterr()
    for bad, message in [
        (["--loads", "1:2"], "--loads '1:2': expected start:stop:num"),
        (["--slips", "0:1:x"], "--slips '0:1:x'"),
        (["--loads", "-5"], "loads must be finite and > 0 N"),
        (["--chunk-size", "4"], "chunk_size: 8 on disk, 4 now"),
        (["--format", "parquet"], "--format 'parquet'"),
        (["--z-w", "0.1,0.2,0.3"], "--p-w has 2, --z-w has 3"),
    ]:
        args = argv + bad
        assert main(args) == 2, bad
        err = capsys.readouterr().err
        assert err.startswith("snowjax sweep: error:") and message in err, err
        assert "Traceback" not in err


@pytest.mark.slow  # a kernel and its own compiles (make test-slow)
def test_parameter_sweep_notebook(tmp_path):
    """Runs `notebooks/parameter_sweep.ipynb` (small sizes)."""
    text = outputs_text(run_notebook("parameter_sweep.ipynb", tmp_path))
    assert "computed_chunks=0" in text  # the rerun resumed instead of recomputing
    counts = dict(re.findall(r"^(\w+): (\d+) points$", text, flags=re.M))
    assert int(counts["CONVERGED"]) > 0 and sum(map(int, counts.values())) == 48, counts
    assert (tmp_path / "sweep-output" / "sweep.csv").exists()


def _free_port() -> int:
    import socket

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.mark.slow  # two processes, each compiling (make test-slow)
def test_distributed_sweep_whose_peer_dies_ends_in_one_line(tmp_path):
    """Two `--distributed` processes on this machine (loopback); process 1 dies (its whole
    process group is killed) once process 0 has written a chunk.  JAX's distributed
    service then aborts process 0 (SIGABRT, a C++ stack trace) when the heartbeats stop
    (`--heartbeat-timeout 5`): the user sees one line saying so and how to resume."""
    import signal
    import time

    out = tmp_path / "out"
    port = _free_port()
    main_code = "import sys; from snowjax._cli.app import main; sys.exit(main())"

    def start(k):
        argv = ["sweep", "--loads", "1000:8000:600", "--slips", "0:0.9:600", "--chunk-size",
                "6000", "--out", str(out), "--no-progress", "--distributed", "--coordinator",
                f"127.0.0.1:{port}", "--num-processes", "2", "--process-id", str(k),
                "--heartbeat-timeout", "5"]  # fmt: skip
        return subprocess.Popen(
            [sys.executable, "-c", main_code, *argv],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            start_new_session=True,
        )

    first, second = start(0), start(1)
    try:
        deadline = time.monotonic() + 240
        while not list(out.glob("chunk_*.npz")) and time.monotonic() < deadline:
            assert first.poll() is None and second.poll() is None, "a process ended early"
            time.sleep(0.1)
        os.killpg(second.pid, signal.SIGKILL)
        _, err = first.communicate(timeout=240)
    finally:
        for proc in (first, second):
            if proc.poll() is None:
                os.killpg(proc.pid, signal.SIGKILL)
    assert first.returncode == 1
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert "another process of the run died or stopped answering" in lines[0]
    assert "run the same command again on every process to resume" in lines[0]
    # JAX's own report (and its stack trace) is kept in the log the line names.
    assert "distributed service" in (out / ".sweep.process0.log").read_text()


@pytest.mark.slow  # the tyre's sweep compiled (make test-slow)
def test_a_deflecting_tire_sweeps_like_solve_wheel(tmp_path):
    """A `DeflectingTire` with two inflation pressures (one rigid mode, one elastic) and a
    flexing resistance: the rows equal `solve_wheel`, the varying leaf is a column named
    by its field, the wheel's type is part of the definition, and a bad leaf is named."""
    inflation = np.array([3e5, 6e4])
    tire = sj.DeflectingTire(0.736, 0.235, 0.176, inflation, 5e3, hard_surface_resistance=0.015)
    snow = sj.WongSnow.thesis_fresh_snow()
    slips = np.array([0.2, -0.2])
    r = sj.sweep(
        tire, snow, 4000.0, slips, out=tmp_path / "s", progress=False, run=sj.SweepRun(chunk_size=C)
    )
    assert r.n_points == 4
    rows = sj.load_sweep(tmp_path / "s")
    assert list(rows)[:5] == ["index", "param_set", "load", "slip", "inflation_pressure"]
    np.testing.assert_array_equal(rows["inflation_pressure"], np.repeat(inflation, 2))
    st = sj.solve_wheel(
        sj.DeflectingTire(0.736, 0.235, 0.176, rows["inflation_pressure"], 5e3, 30.0, 0.015),
        snow,
        rows["load"],
        rows["slip"],
    )
    for name in OUTPUTS:
        np.testing.assert_allclose(rows[name], getattr(st, name), rtol=1e-12, err_msg=name)
    np.testing.assert_array_equal(rows["status"], st.status)
    manifest = json.loads((tmp_path / "s" / "manifest.json").read_text())
    assert manifest["definition"]["wheel"] == "DeflectingTire"
    bad = sj.DeflectingTire(0.736, 0.235, 0.176, np.array([1e5, 0.0]), 5e3)
    with pytest.raises(ValueError, match="tire.inflation_pressure must be finite and > 0 Pa"):
        sj.sweep(
            bad,
            snow,
            4000.0,
            slips,
            out=tmp_path / "bad",
            progress=False,
            run=sj.SweepRun(chunk_size=C),
        )
