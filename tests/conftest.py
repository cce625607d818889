import contextlib
import os
import subprocess
import sys

# The suite is compile-bound (most of its time is tracing, lowering and compiling small
# programs), so it compiles without LLVM's optimisation passes: a solve compiles about
# 30 % faster and the few long runs lose less than that.  Tests only (the notebook
# kernels and subprocesses they start inherit it); the library and the benchmarks
# compile with XLA's defaults.
os.environ.setdefault("JAX_DISABLE_MOST_OPTIMIZATIONS", "1")
# XLA:CPU's fusion emitters (its default code generator) take about twice as long to
# compile a wheel solve as the classic elemental emitters, while the compiled code runs
# about 1.5 times slower: a good trade for tests, whose time is compiling.  Values agree
# to rounding, with one exception found (together with the switch above: jax 0.10.2,
# `optimised_compile` below).  XLA aborts the process on a flag it does not know, so a
# child process tries it first (once: pytest-xdist's workers inherit the environment of
# the process that loads this file first).
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
import pytest  # noqa: E402

jax.config.update("jax_enable_x64", True)


@contextlib.contextmanager
def _optimised(enabled: bool = True):
    previous = jax.config.read("jax_disable_most_optimizations")
    jax.config.update("jax_disable_most_optimizations", previous and not enabled)
    try:
        yield
    finally:
        jax.config.update("jax_disable_most_optimizations", previous)


@pytest.fixture(scope="session")
def optimised_compile():
    """A context manager, `optimised_compile(enabled=True)`: programs first compiled
    inside it get XLA's optimisations back (`jax_disable_most_optimizations` off), as
    the library and its users compile them.

    The two switches above together miscompiled one float32 program (jax 0.10.2, XLA:CPU,
    AMD EPYC): a wheel held at the 85 degree cap on Bekker soil, braking at the slip
    whose shear sign change lies at the axle (n 0.5, k_phi 50 kN/m^2.5, K 5 mm, D 0.5 m,
    b 0.109 m, load 1 MN, slip -0.48919666) solved to W = 1,144.8 N and R = 556.3 N in
    a batch of two identical elements and 677.8 N and 397.7 N alone; bit-identical
    inputs gave 677.8 N and 397.7 N through `contact_forces`, in float64, with either
    switch alone, with neither, and with a `jax.debug.print` added to the solve (the
    contact is continuous there: forcing the sign change to any point in [0, 1e-3]
    moves W by 1e-4 N).  The float32 property test of tyres against the rim
    (`test_properties.py`) passed or failed on it with the batch around that element.
    The jit cache does not key on the switch: use it around a function's first call."""
    return _optimised
