"""The batched root finders of `solve_wheel`: both of their paths find the same roots,
and the secant finds the Newton iteration's."""

import jax
import jax.numpy as jnp
import lineax as lx
import numpy as np
import optimistix as optx
import pytest

from snowjax._wheel.bracketed import (
    FIRST_PHASE_STEPS,
    STRAGGLERS,
    BracketedNewton,
    BracketedSecant,
    _BracketState,
    _SecantState,
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
    return solve_elementwise(_residual, start, lower, upper, params, TOL, 64)[0]


@jax.jit
def _solve_secant(params):
    n = params[0].shape[0]
    lower, upper = jnp.zeros(n), jnp.full(n, 10.0)
    # The secant's first step takes this slope of f in y^2 (f' = -1 - b c cos(c y) at
    # y = 5: the guess -1 / (2 y) ignores the sine).
    secant = dict(slope=jnp.full(n, -0.1))
    return solve_elementwise(_residual, jnp.full(n, 5.0), lower, upper, params, TOL, 64, secant)[0]


def test_a_large_batch_and_its_single_group_slices_agree():
    """Above `STRAGGLERS` elements the batch takes `FIRST_PHASE_STEPS` steps together and
    its stragglers continue in groups; at most `STRAGGLERS` elements are one solve.  Both
    take the same Newton steps, so they end on the same root (measured: equal to
    rounding, 9e-16; 110 of the 200 elements are stragglers)."""
    n = 3 * STRAGGLERS + 8
    params = _params(n)
    bracket = (jnp.zeros(n), jnp.full(n, 10.0))
    early = solve_elementwise(
        _residual, jnp.full(n, 5.0), *bracket, params, TOL, FIRST_PHASE_STEPS
    )[0]
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


def test_the_first_phase_ends_once_its_stragglers_fit_in_one_group():
    """`until_left` ends a solve once at most that many elements are unfinished
    (`solve_elementwise`'s first phase, whose stragglers continue in a group of
    `STRAGGLERS`): on 4 x STRAGGLERS elements, all but 40 linear (finished after two
    Newton steps), the solve with `until_left=STRAGGLERS` stops after those two steps,
    successful, with the 40 unfinished, where the whole solve takes more steps; and
    `solve_elementwise` ends every element on the root the whole solve finds."""
    n, hard = 4 * STRAGGLERS, 40
    a, b, c = _params(n)
    b = np.where(np.arange(n) < hard, np.maximum(b, 0.9), 0.0)  # f = a - y elsewhere
    c = np.where(np.arange(n) < hard, np.maximum(c, 4.0), c)
    params = (a, b, c)
    y0, options = jnp.full(n, 5.0), dict(lower=jnp.zeros(n), upper=jnp.full(n, 10.0))

    def root_find(until_left):
        return optx.root_find(
            _residual, BracketedNewton(rtol=TOL, atol=TOL, until_left=until_left), y0,
            args=params, options=options, max_steps=64, throw=False,
            tags=frozenset({lx.diagonal_tag}),
        )  # fmt: skip

    first, whole = root_find(STRAGGLERS), root_find(0)
    assert int(first.stats["num_steps"]) == 2 < int(whole.stats["num_steps"])
    assert first.result == optx.RESULTS.successful
    unfinished = ~np.asarray(first.state.converged | first.state.collapsed)
    assert 0 < unfinished.sum() <= STRAGGLERS and not unfinished[hard:].any()
    assert np.all(np.asarray(whole.state.converged))
    np.testing.assert_allclose(np.asarray(_solve(params)), np.asarray(whole.value), rtol=1e-12)


@pytest.mark.parametrize("secant", [False, True])
def test_the_residual_returned_is_the_one_at_the_root_where_it_was_evaluated_there(secant):
    """`solve_elementwise`'s second output, f at y where the last step evaluated it there
    (`solve_wheel` takes a layer's capacity from it where an element collapsed onto the
    deep end of its bracket, where the secant steps go): on 3 x STRAGGLERS + 8 elements,
    20 of them with f < 0 on the whole bracket (no root, as for a load beyond the
    layer's capacity), the secant's end on its lower end with f finite there, Newton's
    within the tolerance of it; wherever f is finite it equals the residual at y
    (stragglers included)."""
    n = 3 * STRAGGLERS + 8
    a, b, c = _params(n)
    a = np.where(np.arange(n) < 20, -0.5, a)  # f(0) = a < 0
    params = (a, b, c)
    bracket = (jnp.zeros(n), jnp.full(n, 10.0))
    options = dict(slope=jnp.full(n, -0.1)) if secant else None
    y, f = jax.jit(solve_elementwise, static_argnums=(0, 5, 6))(
        _residual, jnp.full(n, 5.0), *bracket, params, TOL, 64, options
    )
    y, f = np.asarray(y), np.asarray(f)
    exact = np.asarray(_residual(jnp.asarray(y), params))
    if secant:
        assert np.all(y[:20] == 0.0) and np.all(np.isfinite(f[:20]))
    else:
        assert np.all(y[:20] <= 2 * TOL)
    finite = np.isfinite(f)
    np.testing.assert_array_equal(f[finite], exact[finite])
    assert np.all(np.abs(exact[20:]) <= TOL)


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


def test_one_newton_step_ends_an_element_within_the_reach_of_a_loose_tolerance():
    """With `one_step`, a Newton step from |f| <= sqrt(0.1 atol) counts as converged (its
    next residual is C f^2 <= 0.1 atol where C <= 1); a step from just beyond does not,
    nor does a bisection, nor the same step without `one_step`."""
    atol = 1e-6
    reach = np.sqrt(0.1 * atol)  # 3.16e-4
    f_now = jnp.array([0.9 * reach, 1.1 * reach, 0.9 * reach])
    bracket = (jnp.full(3, -1.0), jnp.array([1.0, 1.0, 1e-5]))  # 2: the step leaves it
    no = jnp.zeros(3, bool)
    previous = _BracketState(*bracket, jnp.full(3, 1e-2), jnp.full(3, 1e-2), no, no, no)
    for one_step, expected in ((True, [True, False, False]), (False, [False] * 3)):
        solver = BracketedNewton(rtol=atol, atol=atol, one_step=one_step)
        # f(z) = f_now - z: the Newton step goes to f_now (element 2 bisects instead).
        _, state, _ = solver.step(
            lambda z, _: (f_now - z, None), jnp.zeros(3), None, {}, previous, None
        )
        assert np.asarray(state.converged).tolist() == expected
    # On a residual whose C is known, the step's result is within 0.1 atol:
    # f(y) = e^-y - a, C = |f''| / (2 f'^2) = 1 / (2 e^-y) ~ 0.5 at the root y = 0.
    a = jnp.full(4, 1.0)
    start = jnp.array([0.9, 0.5, 0.1, 0.02]) * reach

    def residual(y, a):
        return jnp.exp(-y) - a

    y, _ = solve_elementwise(
        residual, start, jnp.full(4, -1.0), jnp.full(4, 1.0), a, atol, 8, one_step=True
    )
    assert np.all(np.abs(np.asarray(residual(y, a))) <= 0.1 * atol)


def test_the_secant_finds_roots_and_its_paths_agree():
    """`BracketedSecant` (f alone at each step) on the same non-monotone residuals: every
    element within the tolerance of a root, Newton's where the root is unique (b c <=
    1: f falls monotonically; measured: to 1e-15), and its straggler groups end where
    one-group solves of the same elements end."""
    n = 3 * STRAGGLERS + 8
    params = _params(n)
    secant = np.asarray(_solve_secant(params))
    newton = np.asarray(_solve(params))
    assert np.all(np.abs(np.asarray(_residual(jnp.asarray(secant), params))) <= TOL)
    unique = params[1] * params[2] <= 1
    assert unique.sum() > 20
    np.testing.assert_allclose(secant[unique], newton[unique], rtol=1e-12, atol=1e-12)
    sliced = np.concatenate(
        [
            np.asarray(_solve_secant(tuple(p[k : k + STRAGGLERS] for p in params)))
            for k in range(0, n, STRAGGLERS)
        ]
    )
    np.testing.assert_allclose(sliced, secant, rtol=1e-12, atol=1e-12)


def test_a_secant_step_stays_in_its_bracket_and_predicts_from_its_contraction():
    """A secant step through the last point that would leave the bracket takes regula
    falsi where f is known at both ends, bisection where not; an element converges
    when the last contraction |f_k / f_(k-1)|, repeated, predicts a residual below 0.1
    atol after two secant steps through evaluated points, both residuals within the
    superlinear regime (|f| <= 1e-3; `bracketed._secant_finished`; a first step, whose
    slope is the start's estimate, predicts nothing, nor does a contraction from
    outside the regime), and stays converged."""
    solver = BracketedSecant(rtol=1e-9, atol=1e-9)
    n = 7
    y = jnp.full(n, 0.5)
    inf = jnp.full(n, jnp.inf)
    no = jnp.zeros(n, bool)
    previous = _SecantState(
        lower=jnp.zeros(n), upper=jnp.ones(n),
        f_lower=jnp.array([jnp.inf, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0]),
        f_upper=jnp.array([-jnp.inf, -1.0, -1.0, -1.0, -1.0, -1.0, -1.0]),
        x_last=jnp.full(n, 0.24),
        f_last=jnp.array([0.91, 0.91, 1e-4, 1e-4, 1e-4, jnp.nan, 1e-2]),
        slope=jnp.full(n, -1.0),
        diff=inf,
        interpolated=jnp.array([False, False, True, True, False, False, True]),
        converged=no.at[3].set(True), collapsed=no,
    )  # fmt: skip
    # f at y = 0.5 (x = 0.25): 0, 1 far from the root, where the secant through the last
    # point (slope -1 in x) runs out of [0, 1]; 2-6 close to it, 5 at its first step
    # (no point evaluated before: the start's slope).
    f_now = jnp.array([0.9, 0.9, 5e-8, 5e-8, 5e-8, 5e-8, 5e-8])
    new_y, state, _ = solver.step(lambda z, _: (f_now + 0 * z, None), y, None, {}, previous, None)
    new_y = np.asarray(new_y)
    # 0: bisection of [0.5, 1] (f at its upper end unknown); 1: regula falsi in y^2
    # between f(0.5) = 0.9 and f(1) = -1.
    assert new_y[0] == pytest.approx(0.75, rel=1e-12)
    assert new_y[1] == pytest.approx(np.sqrt(0.25 + 0.9 / 1.9 * 0.75), rel=1e-12)
    # 2: the secant step; 5e-8 (5e-8 / 1e-4) = 2.5e-11 <= 1e-10 after two secant steps:
    # converged.  3: converged before, stays where it was.  4: as 2, but the step that
    # reached y was the first (the start's slope): no prediction.  6: as 2, but from
    # f = 1e-2, outside the regime (5e-8 (5e-8 / 1e-2) = 2.5e-13 would predict): none.
    assert new_y[2] == pytest.approx(np.sqrt(0.25 + 5e-8 * 0.01 / (1e-4 - 5e-8)), rel=1e-12)
    assert np.asarray(state.converged).tolist() == [False, False, True, True, False, False, False]
    assert new_y[3] == 0.5
    # 5 took the start's slope: the step after it predicts nothing either.
    assert new_y[5] == pytest.approx(np.sqrt(0.25 + 5e-8), rel=1e-12)
    assert np.asarray(state.interpolated).tolist() == [False, False, True, True, True, False, True]
