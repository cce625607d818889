import os
import pathlib

# A persistent XLA compilation cache shared by the test process and the notebook kernels
# and subprocesses it starts (they inherit the environment): a solve that a notebook
# compiles with the same shapes as a test is loaded from disk instead of recompiled.
_CACHE = pathlib.Path(__file__).resolve().parents[1] / ".pytest_cache" / "jax-compilation-cache"
os.environ.setdefault("JAX_COMPILATION_CACHE_DIR", str(_CACHE))
os.environ.setdefault("JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS", "0.5")

import jax  # noqa: E402

jax.config.update("jax_enable_x64", True)
