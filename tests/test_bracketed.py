"""The batched root finder of `solve_wheel`: both of its paths find the same roots."""

import jax
import jax.numpy as jnp
import numpy as np

from snowjax._wheel.bracketed import FIRST_PHASE_STEPS, STRAGGLERS, solve_elementwise

TOL = 1e-12


def _residual(y, params):
    """Decreasing on average but not monotone where b c > 1: f(0) = a > 0 > f(10)."""
    a, b, c = params
    return a - y - b * jnp.sin(c * y)


def _params(n):
    rng = np.random.default_rng(4)
    return (rng.uniform(1.0, 8.0, n), rng.uniform(0.0, 1.0, n), rng.uniform(0.5, 6.0, n))


@jax.jit
def _solve(params):
    n = params[0].shape[0]
    lower, upper = jnp.zeros(n), jnp.full(n, 10.0)
    start = jnp.full(n, 5.0)
    return solve_elementwise(_residual, start, lower, upper, params, TOL, 64)


def test_a_large_batch_and_its_single_group_slices_agree():
    """Above `STRAGGLERS` elements the batch takes `FIRST_PHASE_STEPS` steps together and
    its stragglers continue in groups; at most `STRAGGLERS` elements are one solve.  Both
    take the same Newton steps, so they end on the same root (measured: equal to
    rounding, 9e-16; 110 of the 200 elements are stragglers)."""
    n = 3 * STRAGGLERS + 8
    params = _params(n)
    bracket = (jnp.zeros(n), jnp.full(n, 10.0))
    early = solve_elementwise(_residual, jnp.full(n, 5.0), *bracket, params, TOL, FIRST_PHASE_STEPS)
    stragglers = np.abs(np.asarray(_residual(early, params))) > TOL
    assert stragglers.sum() > STRAGGLERS  # more than one group of them
    whole = np.asarray(_solve(params))
    sliced = np.concatenate(
        [
            np.asarray(_solve(tuple(p[k : k + STRAGGLERS] for p in params)))
            for k in range(0, n, STRAGGLERS)
        ]
    )
    assert np.all(np.abs(np.asarray(_residual(whole, params))) <= TOL)
    np.testing.assert_allclose(sliced, whole, rtol=1e-12, atol=1e-12)
