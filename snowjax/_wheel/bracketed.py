"""Root finders inside a per-element bracket: the batched load-balance solvers.

`solve_wheel` solves one scalar equation per batch element (elements are independent,
the Jacobian is diagonal).  `optx.Newton` alone does not do this job: its convergence
test is batch-wide, and it has no bracket, so a single element whose W(theta0) is not
monotone (a braked wheel, whose backward shear stress pulls it down; a layered snow)
keeps the whole batch iterating to `max_steps`, after which a vmapped `optx.Bisection`
costs about 35 more evaluations of the batch.  That made braking batches ~30x slower
than driving ones.  Two solvers do the job, both optimistix root finders kept inside a
bracket and tested elementwise:

- `BracketedNewton`, the classic safeguarded Newton ("rtsafe", Press et al., Numerical
  Recipes, 3rd ed., section 9.4): a warm start (the last simulation step's root) lies
  so close that two Newton steps end the solve;
- `BracketedSecant`, the secant method in the solver variable's square (Dekker's
  safeguard: a step that leaves the bracket takes regula falsi or bisection instead):
  no tangent, so each step costs one evaluation of the residual instead of two (a
  tangent through a quadrature costs 1.6-3x the values on CPU), for the cold starts,
  which come from a cheap estimate (`start.py`).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
import lineax as lx
import optimistix as optx
from jaxtyping import Array, Bool, Float


class _BracketState(eqx.Module):
    lower: Float[Array, " n"]
    upper: Float[Array, " n"]
    f: Float[Array, " n"]
    diff: Float[Array, " n"]
    # Whether the last step was a Newton step (its `diff` can predict the next residual).
    newton: Bool[Array, " n"]
    # Per element, latched once true (`_finished`): converged, and the bracket collapsed.
    converged: Bool[Array, " n"]
    collapsed: Bool[Array, " n"]


class BracketedNewton(optx.AbstractRootFinder):
    """Elementwise Newton on independent scalar equations f_k(y_k) = 0, kept in a bracket.

    `options=dict(lower=..., upper=...)` (arrays shaped like y) must bracket a sign
    change of every element with `f(lower) > 0 > f(upper)`; f need not be monotone in
    between.  Each step evaluates f and its diagonal derivative (one forward-mode
    tangent), shrinks each bracket to the side that keeps the sign change, and takes the
    Newton step where it has the right slope and stays strictly inside the bracket, else
    bisects.  An element whose |f| is already within `atol` only takes a Newton step
    that stays in the bracket (it never bisects away from a root).  An element is
    finished when |f| <= atol and its last step was below `atol + rtol |y|`, or when
    the quadratic convergence of its last two Newton steps predicts that (`_finished`),
    or when its bracket is narrower than that; it then stays where it is while the rest
    of the batch iterates, and the solve stops when every element is finished.
    """

    rtol: float
    atol: float
    # The solve also ends once at most this many elements are unfinished (static; 0:
    # when every one is), for a first phase whose stragglers continue on their own
    # (`solve_elementwise`).
    until_left: int = eqx.field(default=0, static=True)
    # Whether one Newton step from |f| <= sqrt(`PREDICTION_MARGIN` atol) ends an element
    # (`_finished`; static): for the simulator accuracy's loose tolerance.
    one_step: bool = eqx.field(default=False, static=True)
    # Required by optimistix's solver interface; the tests here are elementwise
    # (`_finished`), so the norm only reports |f| in optimistix's own diagnostics.
    norm: ClassVar[Callable] = optx.max_norm

    def init(self, fn, y, args, options, f_struct, aux_struct, tags) -> _BracketState:
        del fn, args, aux_struct, tags
        lower = jnp.broadcast_to(jnp.asarray(options["lower"], f_struct.dtype), y.shape)
        upper = jnp.broadcast_to(jnp.asarray(options["upper"], f_struct.dtype), y.shape)
        inf = jnp.full(y.shape, jnp.inf, f_struct.dtype)
        no = jnp.zeros(y.shape, bool)
        collapsed = upper - lower <= self.atol + self.rtol * jnp.abs(y)
        return _BracketState(lower, upper, inf, inf, no, no, collapsed)

    def step(self, fn, y, args, options, state: _BracketState, tags):
        del options, tags
        f, lin, aux = jax.linearize(lambda z: fn(z, args), y, has_aux=True)
        df = lin(jnp.ones_like(y))
        positive = f > 0  # the sign change lies above y
        lower = jnp.where(positive, y, state.lower)
        upper = jnp.where(positive, state.upper, y)
        newton = y - f / jnp.where(df < 0, df, -1.0)
        inside = (df < 0) & (newton > lower) & (newton < upper)
        done = jnp.abs(f) <= self.atol
        bisect = jnp.where(done, y, lower + 0.5 * (upper - lower))
        # A finished element stays where it finished (its f is evaluated with the batch and
        # dropped): its result does not depend on how long the rest of its batch iterates.
        stay = state.converged | state.collapsed
        new_y = jnp.where(stay, y, jnp.where(inside, newton, bisect))
        diff = y - new_y
        new = _BracketState(lower, upper, f, diff, inside, state.converged, state.collapsed)
        flags = _finished(state, new, new_y, self.atol, self.rtol, self.one_step)
        return new_y, dataclasses.replace(new, converged=flags[0], collapsed=flags[1]), aux

    def terminate(self, fn, y, args, options, state: _BracketState, tags):
        """Stop when every element is finished; the result is then `successful` only if
        every element converged (a bracket that collapsed onto a jump of f is not a root).
        (optimistix stops iterating at the first result that is not `successful`, so an
        unfinished solve must report success.)"""
        del fn, args, options, tags
        return _terminate(state, self.until_left)

    def postprocess(self, fn, y, aux, args, options, state, tags, result):
        del fn, args, options, state, tags, result
        return y, aux, {}


# |f| below which two Newton steps in a row predict the next residual (`_finished`), and
# the margin of that prediction below the tolerance.
QUADRATIC_REGIME = 1e-3
PREDICTION_MARGIN = 0.1


def _terminate(state, until_left: int = 0) -> tuple[Array, optx.RESULTS]:
    """(finished, result) of a bracketed solve: finished where every element converged or
    collapsed, or where at most `until_left` have not (a first phase, whose stragglers
    continue on their own: then `successful`); `nonlinear_divergence` where every
    element finished and some did not converge."""
    unfinished = ~(state.converged | state.collapsed)
    every: Bool[Array, ""] = ~jnp.any(unfinished)
    finished = every
    if until_left:
        finished = every | (jnp.sum(unfinished) <= until_left)
    failed = every & ~jnp.all(state.converged)
    result = optx.RESULTS.where(failed, optx.RESULTS.nonlinear_divergence, optx.RESULTS.successful)
    return finished, result


def _finished(
    previous: _BracketState, state: _BracketState, y, atol, rtol, one_step: bool = False
) -> tuple[Array, Array]:
    """Per element, after the step from `previous` to `state` and `y`: (converged,
    collapsed: the bracket is narrower than atol + rtol |y|), each latched once true.

    Converged: |f| <= atol at the step's start and the step below atol + rtol |y|; or,
    after two Newton steps in a row with |f| <= `QUADRATIC_REGIME` before the last, the
    residual at the new iterate predicted by their quadratic convergence, |f(y_k)| ~
    |f(y_{k-1})| (d_k / d_{k-1})^2, below `PREDICTION_MARGIN` atol.  The prediction
    saves the evaluation that would only confirm it where every element of a batch gets
    there in time (measured on the thesis tyre: the batch of the rim on Wong snow, and
    of the rim at a slip angle there, 2 Newton steps instead of 3; Bekker's snow with
    Wong–Reece 4 instead of 5; its front region 4 either way); `solve_wheel` checks the
    balance at the root itself (its final quadrature) and reports `NOT_CONVERGED` where
    it is off by more than 10 atol.  Computed once per step and carried in the state,
    so that the loop's test reads it.

    With `one_step` (static), also converged after one Newton step from |f| <=
    sqrt(`PREDICTION_MARGIN` atol): Newton's next residual is C f^2, below
    `PREDICTION_MARGIN` atol where C = |f''| / (2 f'^2) <= 1.  For a loose tolerance
    (the simulator accuracy's, 1e-6), where the warm start of a simulation step lies
    within that reach (the rover in MJX: |f| 5e-5 to 2.4e-4 before the step, C about
    0.15 after it): one Newton step with its tangent instead of two; the balance
    check at the root reports `NOT_CONVERGED` where C was larger.
    """
    scale = atol + rtol * jnp.abs(y)
    f = jnp.abs(state.f)
    confirmed = (f <= atol) & (jnp.abs(state.diff) <= scale)
    ratio = state.diff / jnp.where(previous.newton, previous.diff, jnp.inf)
    quadratic = state.newton & previous.newton & (f <= QUADRATIC_REGIME)
    predicted = quadratic & (f * ratio**2 <= PREDICTION_MARGIN * atol)
    if one_step:
        predicted |= state.newton & (f <= math.sqrt(PREDICTION_MARGIN * atol))
    converged = previous.converged | confirmed | predicted
    collapsed = previous.collapsed | (state.upper - state.lower <= scale)
    return converged, collapsed


class _SecantState(eqx.Module):
    lower: Float[Array, " n"]
    upper: Float[Array, " n"]
    # f at the bracket's ends: +inf / -inf where not evaluated (only the sign is known).
    f_lower: Float[Array, " n"]
    f_upper: Float[Array, " n"]
    # The last evaluated point, x = y^2 and f there (f NaN before the first step).
    x_last: Float[Array, " n"]
    f_last: Float[Array, " n"]
    # df/dx where no point has been evaluated yet (the start's estimate).
    slope: Float[Array, " n"]
    diff: Float[Array, " n"]
    # Whether the last step was a secant step through two evaluated points (its
    # residuals can predict the next one).
    interpolated: Bool[Array, " n"]
    converged: Bool[Array, " n"]
    collapsed: Bool[Array, " n"]


class BracketedSecant(optx.AbstractRootFinder):
    """Elementwise secant steps on independent scalar equations f_k(y_k) = 0, kept in a
    bracket; each step evaluates f alone (no tangent).

    The steps interpolate f linearly in x = y^2 (the solver variable of `solve_wheel` is
    s with theta0 = theta_cap exp(-s^2): ln W is nearly linear in s^2 where W is nearly
    a power of theta0): the first from the slope df/dx given in `options["slope"]`,
    the next through the last two points.  A step that would leave the bracket (or
    that has the wrong slope) takes regula falsi between the bracket's ends where f is
    known at both, else bisection.  `options`: `lower`, `upper` (arrays shaped like y)
    bracketing a sign change, f(lower) > 0 > f(upper); optionally `f_lower`, `f_upper`
    (the values there, where evaluated; +inf / -inf otherwise) and `x_last`, `f_last`
    (a point already evaluated, e.g. by a start; f NaN where none).  Termination as
    `BracketedNewton`'s, the prediction from the secant's superlinear convergence: after
    two secant steps in a row (each through two evaluated points: not the first step,
    whose slope is the start's estimate and whose contraction says nothing of the
    next) with both residuals <= `QUADRATIC_REGIME`, the next residual |f_k|^2 / |f_(k-1)|
    (the last contraction repeated: the secant's only improves, e_(k+1) / e_k = C
    e_(k-1) < C e_(k-2) = e_k / e_(k-1)) below `PREDICTION_MARGIN` atol.
    """

    rtol: float
    atol: float
    # As `BracketedNewton.until_left`.
    until_left: int = eqx.field(default=0, static=True)
    norm: ClassVar[Callable] = optx.max_norm

    def init(self, fn, y, args, options, f_struct, aux_struct, tags) -> _SecantState:
        del fn, args, aux_struct, tags
        dtype = f_struct.dtype

        def option(name, fill):
            return jnp.broadcast_to(jnp.asarray(options.get(name, fill), dtype), y.shape)

        lower, upper = option("lower", 0.0), option("upper", 0.0)
        inf = jnp.full(y.shape, jnp.inf, dtype)
        no = jnp.zeros(y.shape, bool)
        collapsed = upper - lower <= self.atol + self.rtol * jnp.abs(y)
        return _SecantState(
            lower, upper, option("f_lower", jnp.inf), option("f_upper", -jnp.inf),
            option("x_last", 0.0), option("f_last", jnp.nan), option("slope", -1.0),
            inf, no, no, collapsed,
        )  # fmt: skip

    def step(self, fn, y, args, options, state: _SecantState, tags):
        del options, tags
        f, aux = fn(y, args)
        positive = f > 0  # the sign change lies above y
        lower = jnp.where(positive, y, state.lower)
        upper = jnp.where(positive, state.upper, y)
        f_lower = jnp.where(positive, f, state.f_lower)
        f_upper = jnp.where(positive, state.f_upper, f)
        x = y * y
        known = jnp.isfinite(state.f_last) & (x != state.x_last)
        chord = (f - state.f_last) / jnp.where(known, x - state.x_last, 1.0)
        slope = jnp.where(known, chord, state.slope)
        falling = slope < 0
        x_new = x - f / jnp.where(falling, slope, -1.0)
        lo2, hi2 = lower * lower, upper * upper
        inside = falling & (x_new > lo2) & (x_new < hi2)
        # Regula falsi where f is known at both ends of the bracket, else bisection.
        ends_known = jnp.isfinite(f_lower) & jnp.isfinite(f_upper)
        span = jnp.where(ends_known, f_lower - f_upper, 1.0)
        falsi = jnp.sqrt(lo2 + (f_lower / span) * (hi2 - lo2))
        fallback = jnp.where(ends_known, falsi, lower + 0.5 * (upper - lower))
        # A step past a deep end where f is not known yet tries that end (an element
        # the layer cannot carry then collapses onto it at once instead of bisecting
        # its way there).
        beyond = falling & (x_new <= lo2) & ~jnp.isfinite(f_lower)
        fallback = jnp.where(beyond, lower, fallback)
        done = jnp.abs(f) <= self.atol
        candidate = jnp.where(inside, jnp.sqrt(jnp.where(inside, x_new, 1.0)), fallback)
        # An element within the tolerance only takes a step that stays in the bracket.
        candidate = jnp.where(done & ~inside, y, candidate)
        stay = state.converged | state.collapsed
        new_y = jnp.where(stay, y, candidate)
        # A step through two evaluated points (not the start's slope, not regula falsi
        # or bisection): the contractions of two of them in a row predict the next.
        secant = inside & known
        new = _SecantState(
            lower, upper, f_lower, f_upper, x, f, state.slope, y - new_y, secant,
            state.converged, state.collapsed,
        )  # fmt: skip
        flags = _secant_finished(state, new, new_y, self.atol, self.rtol)
        return new_y, dataclasses.replace(new, converged=flags[0], collapsed=flags[1]), aux

    def terminate(self, fn, y, args, options, state: _SecantState, tags):
        """As `BracketedNewton.terminate`."""
        del fn, args, options, tags
        return _terminate(state, self.until_left)

    def postprocess(self, fn, y, aux, args, options, state, tags, result):
        del fn, args, options, state, tags, result
        return y, aux, {}


def _secant_finished(previous, state, y, atol, rtol) -> tuple[Array, Array]:
    """`_finished` for `BracketedSecant`: (converged, collapsed), latched.  Converged:
    |f| <= atol and the step below atol + rtol |y|; or, after two secant steps in a row
    with both |f| <= `QUADRATIC_REGIME`, the next residual predicted by the last
    contraction, |f_k| |f_k / f_(k-1)|, below `PREDICTION_MARGIN` atol."""
    scale = atol + rtol * jnp.abs(y)
    f = jnp.abs(state.f_last)
    confirmed = (f <= atol) & (jnp.abs(state.diff) <= scale)
    ratio = f / jnp.where(previous.interpolated, jnp.abs(previous.f_last), jnp.inf)
    # Both residuals in the regime: a contraction from far out (a step across a tyre's
    # mode switch, f 0.18 -> 3e-6 -> 4e-7) says nothing of the next one.
    regime = state.interpolated & previous.interpolated & (f <= QUADRATIC_REGIME)
    regime &= jnp.abs(previous.f_last) <= QUADRATIC_REGIME
    predicted = regime & (f * ratio <= PREDICTION_MARGIN * atol)
    converged = previous.converged | confirmed | predicted
    collapsed = previous.collapsed | (state.upper - state.lower <= scale)
    return converged, collapsed


# The most steps every element of a batch takes together; elements still unconverged
# then (a braked wheel whose W(theta0) is not monotone, a poor initial guess) continue
# alone, as they do once they fit in one group of STRAGGLERS.
FIRST_PHASE_STEPS = 5
# Such stragglers are gathered into small batches of this many and solved one batch
# after the other.
STRAGGLERS = 64


def solve_elementwise(
    residual, y0, lower, upper, params, tol, max_steps, secant=None, one_step=False
):  # fmt: skip
    """Roots of `residual(y, params)` (elementwise over 1-D y) by `BracketedNewton`, or
    by `BracketedSecant` where `secant` is given.

    A batched iteration runs until its slowest element converges, so one straggler
    would make every element of the batch pay for its extra steps.  All elements
    take up to `FIRST_PHASE_STEPS` steps together, fewer where the unconverged ones fit
    in one group before; those are then gathered in groups of `STRAGGLERS`, solved on
    their own from where they stopped, and scattered back (a rim in a rut on Wong snow:
    a few elements per 2,048 whose root lies just past the rut's kink, where Newton
    converges linearly for a step, took every element of their chunk through a third
    step).  A batch of at most `STRAGGLERS` elements is one such group from the start: one
    solve of `max_steps` (one compiled loop instead of two; its elements that finish
    early stay where they finished while the last one iterates).  Forward-mode
    derivatives w.r.t. `params` come from each `optx.root_find`'s implicit adjoint;
    reverse mode does not pass the groups' `lax.while_loop` (`solve_wheel` passes
    stopped parameters and differentiates at the root instead).

    **Arguments:** `residual(y, params) -> f` elementwise, `y0`, `lower`, `upper` (1-D,
    bracketing a sign change, `f(lower) > 0 > f(upper)`), `params` (a pytree of arrays with
    the batch on axis 0), `tol` (absolute, on f and on the step), `max_steps` (total),
    `secant` (None: Newton; else a dict of `BracketedSecant`'s other options, arrays
    shaped like y0: `slope` and any of `f_lower`, `f_upper`, `x_last`, `f_last`),
    `one_step` (`BracketedNewton.one_step`).
    **Returns:** (y, f): y, shape of y0, and the residual there where the solver's last
    evaluation was at y (`_value_and_residual`; NaN elsewhere; no derivative).
    """
    kind = BracketedSecant if secant else BracketedNewton
    newton = {} if secant else dict(one_step=one_step)
    tags = frozenset({lx.diagonal_tag})

    def solve(y_start, options, p, steps, until_left=0):
        return optx.root_find(
            residual,
            kind(rtol=tol, atol=tol, until_left=until_left, **newton),
            y_start,
            args=p,
            options=jax.lax.stop_gradient(options),
            max_steps=steps,
            throw=False,
            tags=tags,
        )

    options = dict(lower=lower, upper=upper, **(secant or {}))
    size = y0.shape[0]
    if size <= STRAGGLERS or max_steps <= FIRST_PHASE_STEPS:
        # One group holds the whole batch (one solve, one compiled loop), or no steps
        # are left for the stragglers.
        return _value_and_residual(solve(y0, options, params, max_steps))
    rest = max_steps - FIRST_PHASE_STEPS
    # The first phase ends where its stragglers fit in one group.
    first = solve(y0, options, params, FIRST_PHASE_STEPS, STRAGGLERS)
    y, f = _value_and_residual(first)
    state = first.state
    left = ~(state.converged | state.collapsed)
    m = STRAGGLERS
    # Where the stragglers continue from: their brackets (and, for the secant, what it
    # knows of f).
    names = ("lower", "upper") + (
        ("f_lower", "f_upper", "x_last", "f_last", "slope") if secant else ()
    )
    resume = {name: getattr(state, name) for name in names}

    def next_group(carry):
        # Up to m stragglers gathered, solved from where they stopped, scattered back.
        # Slots beyond them hold index `size`: gathered as the last element (any valid
        # input), dropped when scattering back.
        y, f, left = carry
        idx = jnp.nonzero(left, size=m, fill_value=size)[0]
        pick = lambda x: jnp.take(x, idx, axis=0, mode="clip")  # noqa: E731
        sub = solve(
            jax.lax.stop_gradient(pick(y)),
            jax.tree_util.tree_map(pick, resume),
            jax.tree_util.tree_map(pick, params),
            rest,
        )
        y_sub, f_sub = _value_and_residual(sub)
        scatter = lambda x, new: x.at[idx].set(new, mode="drop")  # noqa: E731
        return scatter(y, y_sub), scatter(f, f_sub), scatter(left, False)

    # One group at a time (none, usually): one compiled solve of m elements serves any
    # number of stragglers.
    y, f, _ = jax.lax.while_loop(lambda carry: jnp.any(carry[2]), next_group, (y, f, left))
    return y, f


def _value_and_residual(solution) -> tuple[Array, Array]:
    """(y, f(y)) of a bracketed solve: the residual at y where its last step evaluated
    it there (an element that ended where it stood: finished earlier, or collapsed onto
    the point just evaluated), NaN where the last step moved it."""
    state = solution.state
    f = state.f_last if isinstance(state, _SecantState) else state.f
    return solution.value, jnp.where(state.diff == 0, jax.lax.stop_gradient(f), jnp.nan)
