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
# to rounding.  XLA aborts the process on a flag it does not know, so a child process
# tries it first (once: pytest-xdist's workers inherit the environment of the process
# that loads this file first).
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
