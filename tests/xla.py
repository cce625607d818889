"""XLA's optimisation passes for the few programs whose running, not compiling, dominates.

The suite compiles with most of XLA's optimisations off (`conftest.py`): it is
compile-bound, and an unoptimised solve compiles faster.  A program that then runs for
long loses more than that: the coasting vehicles of `test_properties.py` took 4.8 s to
compile and 15.6 s to run without the passes, 9.1 s and 3.3 s with them (2026-11-26,
jaxlib 0.10.2, one core; the test's setup 37 s against 25 s).  The held-out single-wheel
fits and the 200-step Bekker simulation were measured too and gain nothing (3 s slower),
so they compile as the rest.  `optimised()` turns the passes on for what it encloses.  The
flag is read when a program is compiled and is not part of the jit cache's key: a
program compiled before, either way, is reused as it is.
"""

import contextlib

import jax


@contextlib.contextmanager
def optimised():
    before = jax.config.read("jax_disable_most_optimizations")
    jax.config.update("jax_disable_most_optimizations", False)
    try:
        yield
    finally:
        jax.config.update("jax_disable_most_optimizations", before)
