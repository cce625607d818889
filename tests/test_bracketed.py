"""The batched root finder of `solve_wheel`: both of its paths find the same roots."""

import jax
import jax.numpy as jnp
import numpy as np

from snowjax._wheel.bracketed import (
    FIRST_PHASE_STEPS,
    STRAGGLERS,
    BracketedNewton,
    _BracketState,
    solve_elementwise,
)

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


def test_an_element_ends_where_it_finished_whatever_its_batch():
    """A finished element stays put while the rest of its batch iterates, so its root does
    not depend on its neighbours: each element alone and in one batch with the others
    (whose slowest takes more Newton steps) end on the same float (the predicted stop
    leaves residuals of up to 0.1 tol, which further steps would otherwise refine)."""
    n = STRAGGLERS
    params = _params(n)
    whole = np.asarray(_solve(params))
    alone = np.array([float(_solve(tuple(p[k : k + 1] for p in params))[0]) for k in range(8)])
    np.testing.assert_allclose(alone, whole[:8], rtol=1e-15, atol=0)


def test_the_predicted_stop_needs_two_newton_steps_in_the_quadratic_regime():
    """A step counts an element as converged when its residual is predicted below 0.1
    atol by two Newton steps in a row (|f| <= 1e-3 before the last); a step after a
    bisection (or the first step) predicts nothing, a prediction above 0.1 atol is not
    enough, and an element once converged stays so (`bracketed._finished`)."""
    solver = BracketedNewton(rtol=1e-9, atol=1e-9)
    y = jnp.zeros(5)
    bracket = (jnp.full(5, -1.0), jnp.full(5, 1.0))
    f_now = jnp.array([1e-5, 1e-5, 1e-5, 2e-3, 2e-3])
    no = jnp.zeros(5, bool)
    previous = _BracketState(
        *bracket, jnp.full(5, 1e-2), jnp.array([1e-2, 1e-2, 1e-4, 1e-2, 1e-2]),
        jnp.array([True, False, True, True, True]), no.at[4].set(True), no,
    )  # fmt: skip
    # f(z) = f_now - z: the Newton step is -f_now, so d_k = -f_now.
    new_y, state, _ = solver.step(lambda z, _: (f_now - z, None), y, None, {}, previous, None)
    # 0: 1e-5 (1e-5 / 1e-2)^2 = 1e-11 <= 1e-10; 1: the step before bisected; 2: 1e-5 (1e-5
    # / 1e-4)^2 = 1e-7 > 1e-10; 3: |f| = 2e-3 is not yet quadratic convergence; 4: as 3,
    # but converged before, so it stays converged and where it was.
    assert np.asarray(state.converged).tolist() == [True, False, False, False, True]
    assert not np.any(np.asarray(state.collapsed))
    np.testing.assert_array_equal(np.asarray(new_y), [1e-5, 1e-5, 1e-5, 2e-3, 0.0])
