import os
import subprocess
import sys

# The suite is compile-bound: tracing, lowering and compiling took 1,290 of its 1,640
# worker-seconds on 2 cores with LLVM's optimisation passes off (2026-11-26).  Without
# those passes a solve compiles about 30 % faster (tests/test_wheel.py: 75 s of
# compiling against 108 s) and the simulations' long runs lose less than that.  With the
# elemental emitters below as well, a fresh clone's tests took 8 min 36 s (13 min 51 s
# without them and before small batches became one Newton loop; 18 min 10 s with XLA's
# defaults).  Tests only (the notebook kernels and subprocesses they start inherit both);
# the library and the benchmarks compile with XLA's defaults.
os.environ.setdefault("JAX_DISABLE_MOST_OPTIMIZATIONS", "1")
# XLA:CPU's fusion emitters (its default code generator) take twice as long to compile a
# wheel solve as the classic elemental emitters (2.8 s against 5.6 s for three solves,
# jaxlib 0.10.2), while the compiled code runs about 1.5 times slower: a good trade for
# tests, whose time is compiling.  Values agree to rounding.  XLA aborts the process on
# a flag it does not know, so a child process tries it first (once: pytest-xdist's
# workers inherit the environment of the process that loads this file first).
_EMITTERS = "--xla_cpu_use_fusion_emitters=false"


def _xla_accepts(flag: str) -> bool:
    env = dict(os.environ, XLA_FLAGS=flag, JAX_PLATFORMS="cpu")
    probe = "import jax.numpy as jnp; jnp.zeros(1).block_until_ready()"
    return (
        subprocess.run([sys.executable, "-c", probe], env=env, capture_output=True).returncode == 0
    )


if "xla_cpu_use_fusion_emitters" not in os.environ.get("XLA_FLAGS", "") and _xla_accepts(_EMITTERS):
    os.environ["XLA_FLAGS"] = (os.environ.get("XLA_FLAGS", "") + " " + _EMITTERS).strip()
# No persistent compilation cache: writing such unoptimised executables to it crashed a
# worker (segmentation fault in `compilation_cache.put_executable_and_time`, jax 0.10.2)
# in both full runs that had both.
os.environ.setdefault("JAX_ENABLE_COMPILATION_CACHE", "false")

import jax  # noqa: E402

jax.config.update("jax_enable_x64", True)

# pytest-xdist's `--dist loadscope` hands out test files in collection order, one at a
# time as a worker frees up; alphabetical order left a long file (test_wheel.py) for the
# end and one worker idle meanwhile (958 worker-seconds in 508 s of wall time).  The
# longest files go first (longest-processing-time-first scheduling), by their summed test
# durations on 2 cores (2026-11-26, seconds, without the `slow` cases): properties 188,
# wheel 115, terrains 101, sim 84, lateral 71, deflecting_tire 57, single_wheel 48, planar
# 43, reproduce 37; mjx about 170 since the 3-D rover (2026-11-27), second.  The rut files
# (rut 31, rut_vehicles 26, rut_map 17 on 2026-11-26; the same files' sums move by 20 %
# from run to run, and by 30 s when a file lands on a worker without the programs it
# reuses) are left to the tail, where the runs with them there were the faster ones.  A
# file missing from the list keeps its place after them.  The order also decides which
# files share a worker, and with them the compiled programs reused.
_LONGEST_FIRST = (
    "test_properties.py",
    "test_mjx.py",
    "test_wheel.py",
    "test_terrains.py",
    "test_sim.py",
    "test_lateral.py",
    "test_deflecting_tire.py",
    "test_single_wheel.py",
    "test_planar.py",
    "test_reproduce.py",
)


def pytest_collection_modifyitems(items):
    def rank(item):
        name = item.path.name
        return _LONGEST_FIRST.index(name) if name in _LONGEST_FIRST else len(_LONGEST_FIRST)

    items.sort(key=rank)  # stable: the order within a file is kept
