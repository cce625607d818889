import os
import pathlib

# A persistent XLA compilation cache shared by the test process and the notebook kernels
# and subprocesses it starts (they inherit the environment): a solve that a notebook
# compiles with the same shapes as a test is loaded from disk instead of recompiled.
_CACHE = pathlib.Path(__file__).resolve().parents[1] / ".pytest_cache" / "jax-compilation-cache"
os.environ.setdefault("JAX_COMPILATION_CACHE_DIR", str(_CACHE))
os.environ.setdefault("JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS", "0.5")
# The suite's cost is XLA compiling (about 1,050 of its 1,860 worker-seconds on 2 cores,
# 2026-11-26), not running: without LLVM's optimisation passes a solve compiles about 30 %
# faster (tests/test_wheel.py: 108 s of compiling against 75 s) and the simulations' long
# runs lose less than that.  Tests only (the kernels and subprocesses they start inherit
# it); the library and benchmarks compile with XLA's defaults.
os.environ.setdefault("JAX_DISABLE_MOST_OPTIMIZATIONS", "1")

import jax  # noqa: E402

jax.config.update("jax_enable_x64", True)
