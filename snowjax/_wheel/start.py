"""Where the solver starts: its variable s (theta0 = theta_cap exp(-s^2)), the bracket
[s_min, S_MAX], a warm start from a previous entry angle, and the any-terrain start, W
at two entry angles, at a deflecting tyre's switch to its elastic mode and, on a law
that can fall, at its breakpoints, then two secant steps (`_scan_start`);
`front_rim.py` has the closed-form start of a terrain that offers closed forms of its
rim integrals.  See `equilibrium.py` for the solver itself.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

__all__: list[str] = []


S_MIN = 1e-6  # lower bound of the solver variable s (theta0 = theta_cap exp(-s^2))


def _s_min(dtype) -> float:
    """S_MIN in float64; 1e-3 in float32, where theta_cap exp(-1e-12) rounds to theta_cap
    (the base itself, where Wong's pressure is infinite); 1e-3 keeps theta0 <= (1 - 1e-6)
    theta_cap."""
    return S_MIN if jnp.dtype(dtype) == jnp.float64 else 1e-3


S_MAX = 4.0  # theta0 = 1.1e-7 theta_cap: a contact that carries next to nothing


def _balance_residual(w, target):
    """ln(W / target), floored at ln(1e-30) where W <= 0 (a braked wheel's W can be)."""
    return jnp.log(jnp.maximum(w, 1e-30 * target) / target)


def _theta_from_s(s, theta_cap):
    return theta_cap * jnp.exp(-(s**2))


def _newton_s(residual, s, steps):
    """A few plain Newton steps on an elementwise residual of s (for the initial guess):
    (s, the residual's derivative at the last iterate before its step)."""

    def step(_, carry):
        s, _ = carry
        f, df = jax.jvp(residual, (s,), (jnp.ones_like(s),))
        return _damped_step(s, f, df), df

    return jax.lax.fori_loop(0, steps, step, (s, jnp.zeros_like(s)))


def _damped_step(s, f, df):
    """s after the Newton step for a residual f with derivative df (no step where df >= 0:
    the residual falls with s), damped to |step| <= 0.5 and kept in [s_min, S_MAX]: at
    s ~ s_min the derivative is ~ s (theta0 = theta_cap exp(-s^2)), so a full step can
    overshoot to where W underflows (float32)."""
    falling = df < 0
    delta = jnp.where(falling, f / jnp.where(falling, df, -1.0), 0.0)
    return jnp.clip(s - jnp.clip(delta, -0.5, 0.5), _s_min(s.dtype), S_MAX)


def _surface_stiffness(terrain, width, like):
    """k = dsigma/dz [Pa/m] of the law at the surface (Wong's law: p_w / z_w)."""
    zero, one = jnp.zeros_like(like), jnp.ones_like(like)
    return jax.jvp(lambda z: terrain.pressure(z, width), (zero,), (one,))[1]


def _warm_start(guess, theta_cap):
    """Solver start s0 from a previous entry angle (e.g. the last simulation step).

    Non-finite or non-positive guesses fall back to theta_cap / 2.
    """
    ok = jnp.isfinite(guess) & (guess > 0)
    ratio = jnp.clip(jnp.where(ok, guess, 0.5 * theta_cap) / theta_cap, jnp.exp(-(S_MAX**2)), 1.0)
    s_min = _s_min(ratio.dtype)
    s = jnp.sqrt(jnp.maximum(-jnp.log(ratio), s_min**2))
    return jax.lax.stop_gradient(jnp.clip(s, s_min, S_MAX))


def _warm_bracket_start(vertical, theta_cap, load, guess):
    """(over, target, lower, upper, s0) of a warm start from a previous entry angle
    `guess` (any terrain): the bracket is the whole range and the capacity W at s_min."""
    s_min = jnp.full_like(load, _s_min(load.dtype))
    w_top = vertical(_theta_from_s(s_min, theta_cap))
    over = w_top < load
    target = jnp.where(over, 0.5 * w_top, load)
    return over, target, s_min, jnp.full_like(load, S_MAX), _warm_start(guess, theta_cap)


# The second entry angle of the two-point start, s^2 = 8 (theta0 = e^-8 theta_cap).
S_MID = float(np.sqrt(8.0))


def _scan_start(vertical, theta_cap, load, terrain, diameter, deepest, bends=(), secant=True):
    """(over, target, lower, upper, s0) from W at a few entry angles (any terrain).

    A law whose pressure rises with depth (`AbstractTerrain.pressure_rises`): W is
    monotone in theta0 except for a braked wheel's backward shear.  W at the cap (s_min;
    the capacity), at e^-8 of it (s^2 = 8) and at the entry angles where the wheel's W
    bends (`bends`: a deflecting tyre's switch to its elastic mode,
    `AbstractWheel.start_angles`) brackets the root between two of them, or in [S_MID,
    S_MAX]; ln W linear in s^2 between the two (exact for a power law; extrapolated
    beyond S_MID) gives s0, which `_secant_steps` refine where `secant` (the driving
    layout: no slip < 0).  A braked wheel's W is no power law of theta0 (its backward
    shear pulls W below 0 at small entry angles, where the line through the two points
    then starts 35-80 % off the root on Bekker's snow), and two secant steps do not
    bring such a start close enough to save a Newton step: in the braking layout they
    are not taken (batches of slips -0.3 to 0.9 took as many Newton steps with them),
    nor are a wheel's `bends` evaluated (a 100 kPa tyre on Bekker's snow with
    Wong–Reece, batch 1,000 of those slips: as many Newton steps, 1.13x the time with
    the bend).
    A third fixed point at s^2 = 16, which this start once also evaluated, changed no
    result beyond 1e-11 relative and cost 4-9 % of the any-terrain solves.

    A law whose pressure can fall at a breakpoint (`LayeredSnow`, where the ice breaks):
    the solver wants the shallowest equilibrium, and W is no longer monotone.  W rises
    while the contact's deepest sinkage stays above a breakpoint, peaks when it reaches
    one (`_breakpoint_s`; `deepest(theta0)` the stress angle nearest the axle) and may
    fall just past it, then rises again.  W at the cap, at e^-8 of it and at every
    breakpoint's angle (its local maxima) brackets the shallowest crossing of the load
    between the shallowest grid point that carries it and the next (`_grid_start`).  A
    scan of 48 fixed angles, which this start replaced, cost about 80 % of such a solve
    and could miss a peak between its points (then returning a deeper root).  No secant
    steps follow on such a law: where W jumps, two steps of regula falsi (with the
    Illinois rule: secants through the last two points crossed the jump) left a few
    starts of a batch 10-25 % off, which then took as many Newton steps as before
    (layered snow, 1-9 kN / 4, slips 0-0.9, batch 20,000: 1.08x the time).
    """
    s_lo = _s_min(load.dtype)
    grid = [jnp.full_like(load, s) for s in (s_lo, S_MID)]
    grid += [_s_of_theta(theta, theta_cap) for theta in bends]
    if not terrain.pressure_rises():
        grid += _breakpoint_s(terrain, diameter, theta_cap, deepest)
    s_grid = jax.lax.stop_gradient(jnp.sort(jnp.stack(grid), axis=0))
    over, target, lower, upper, s0, f_lower, f_upper = _grid_start(
        vertical, theta_cap, load, s_grid, vmapped=not terrain.pressure_rises()
    )
    # A root shallower than every grid point (a load below W at e^-8 of the cap, on a
    # law that rises; the grid's last two points bracket it otherwise): its bracket is
    # [S_MID, S_MAX], s0 the extrapolation of ln W linear in s^2 through the two
    # shallowest points, W at S_MAX unknown.
    beyond = (f_upper >= 0) & terrain.pressure_rises()
    slope = jnp.where(f_lower > f_upper, (f_lower - f_upper) / (upper**2 - lower**2), 1.0)
    x_beyond = jnp.clip(upper**2 + f_upper / slope, upper**2, S_MAX**2)
    lower, f_lower = jnp.where(beyond, upper, lower), jnp.where(beyond, f_upper, f_lower)
    upper = jnp.where(beyond, S_MAX, upper)
    s0 = jnp.where(beyond, jnp.sqrt(x_beyond), s0)
    bracket = (lower, f_lower, upper, f_upper, ~beyond)
    if not (secant and terrain.pressure_rises()):
        return over, target, lower, upper, s0
    return over, target, *_secant_steps(vertical, theta_cap, target, bracket, s0)


# Secant steps of `_secant_steps`: on the thesis tyre, 1-9 kN, slips 0-0.9, the any-terrain
# solves then take 2 Newton steps (Bekker's snow and Reece's sand, front region and
# Wong–Reece) instead of 3-4, and the deflecting tyre on Wong snow 3 instead of 5-7.
SECANT_STEPS = 2


def _secant_steps(vertical, theta_cap, target, bracket, s0):
    """(lower, upper, s0) after `SECANT_STEPS` steps on f = ln(W / target) in s^2 from s0,
    in `bracket` = (lower, f(lower) >= 0, upper, f(upper) < 0, whether f(upper) is
    known: not where the bracket reaches S_MAX).

    Each step evaluates W alone at s0 (a Newton step also takes its tangent, about as
    costly again) and moves the bracket's end on s0's side there, so the bracket still
    holds a sign change of f.  The first step takes the secant through s0 and the
    bracket's other end (regula falsi; where f there is not known, the last point
    evaluated: an extrapolation), the next the secant through the last two points
    (superlinear where W is smooth).  Every s0 is kept in the bracket.

    Measured on the thesis tyre, 1-9 kN (Bekker's snow / 9, Reece's sand / 4), slips
    0-0.9, 64 cases each, the start's entry angle off the root
    by (median, max): Bekker 1e-5, 2e-5 (two points alone: 5e-2, 0.15); Reece 3e-8,
    7e-8 (3e-2, 4e-2); Wong–Reece on Wong snow 7e-8, 9e-6 (8e-3, 4e-2); the tyre at
    100 kPa on Wong snow, with its mode switch among the points, 3e-4, 4e-3 (0.29,
    0.34 without either).  The steps run in a `fori_loop`: written out one after the
    other, a step's W evaluation cost XLA:CPU 2.5x a W alone (Wong–Reece on Wong snow,
    braking layout, batch 1,000: 10 us against 4 us per element), in the loop 1x.
    """
    lower, f_lower, upper, f_upper, known = bracket
    # The first step's partner: the bracket's other end where f there is known, else
    # the last point evaluated (the bracket's lower end: an extrapolation).
    first_x = (jnp.where(known, upper, lower) ** 2, lower**2)
    first_f = (jnp.where(known, f_upper, f_lower), f_lower)

    def step(i, carry):
        lower, upper, s0, x_last, f_last = carry
        f0 = _log_ratio(vertical(_theta_from_s(s0, theta_cap)), target)
        x0 = s0**2
        deep = f0 >= 0  # W carries the target: the root lies at a larger s (shallower)
        # Later steps: the secant through the last two points.
        x_p = jnp.where(i > 0, x_last, jnp.where(deep, *first_x))
        f_p = jnp.where(i > 0, f_last, jnp.where(deep, *first_f))
        lower, upper = jnp.where(deep, s0, lower), jnp.where(deep, upper, s0)
        apart = f0 != f_p
        x_new = x0 - f0 * (x0 - x_p) / jnp.where(apart, f0 - f_p, 1.0)
        s0 = jnp.sqrt(jnp.clip(jnp.where(apart, x_new, x0), lower**2, upper**2))
        return lower, upper, s0, x0, f0

    carry = (lower, upper, s0, lower**2, f_lower)
    lower, upper, s0, *_ = jax.lax.fori_loop(0, SECANT_STEPS, step, carry)
    return jax.lax.stop_gradient((lower, upper, s0))


def _s_of_theta(theta, theta_cap):
    """The solver variable s [-] of entry angle theta [rad] (theta = theta_cap exp(-s^2)),
    kept in [s_min, S_MAX]: S_MAX at theta <= 0, s_min beyond the cap or where the cap
    is 0."""
    s_lo = _s_min(theta_cap.dtype)
    positive = theta_cap > 0
    ratio = jnp.where(positive, theta / jnp.where(positive, theta_cap, 1.0), 1.0)
    ratio = jnp.clip(ratio, jnp.exp(-(S_MAX**2)), 1.0)
    s = jnp.sqrt(jnp.maximum(-jnp.log(ratio), 0.0))
    return jax.lax.stop_gradient(jnp.broadcast_to(jnp.clip(s, s_lo, S_MAX), theta_cap.shape))


def _breakpoint_s(terrain, diameter, theta_cap, deepest):
    """The solver variable s at which the contact's deepest sinkage reaches each of the
    terrain's breakpoint sinkages z_b [m], less 8 ulp (a tyre's flat breaks through at
    the breakpoint itself, where W jumps: the point stays on the side before it).

    The deepest sinkage at entry angle theta0 is the undeflected circle's at the stress
    angle nearest the axle, `deepest(theta0)` (0 on the front region, theta_m under
    Wong–Reece): D [sin^2(theta0 / 2) - sin^2(deepest / 2)] (4.5), solved for theta0 by
    Newton from the axle's theta0 = 2 arcsin sqrt(z_b / D) (exact on the front region),
    within [that, theta_cap].  Kept in [s_min, S_MAX]: a breakpoint beyond the cap gives
    the cap, one at the surface the shallow end; a cap of 0 (a rut pressed to the base)
    the cap.
    """
    eps = float(np.finfo(theta_cap.dtype).eps)
    positive = theta_cap > 0
    cap = jnp.where(positive, theta_cap, 1.0)

    def depth_at(theta0):
        return diameter * (jnp.sin(theta0 / 2) ** 2 - jnp.sin(deepest(theta0) / 2) ** 2)

    out = []
    for z_b in terrain.breakpoint_sinkages():
        ratio = jnp.clip(jnp.where(jnp.isfinite(z_b), z_b, 0.0) / diameter, 0.0, 1.0)
        axle = jnp.minimum(2 * jnp.arcsin(jnp.sqrt(ratio)), cap)

        def newton(_, theta0, z_b=z_b, axle=axle):
            z, slope = jax.jvp(depth_at, (theta0,), (jnp.ones_like(theta0),))
            step = jnp.where(slope > 0, (z_b - z) / jnp.where(slope > 0, slope, 1.0), 0.0)
            return jnp.clip(theta0 + step, axle, cap)

        theta_b = jax.lax.fori_loop(0, 6, newton, axle) * (1 - 8 * eps)
        out.append(_s_of_theta(theta_b, theta_cap))
    return out


def _log_ratio(w, target):
    """ln(W / target), W floored at the smallest normal number (1e-300 is 0 in float32:
    log(0 / target) would be -inf and the interpolation NaN)."""
    return jnp.log(jnp.maximum(w, jnp.finfo(w.dtype).tiny) / target)


def _grid_start(vertical, theta_cap, load, s_grid, vmapped=True):
    """`_scan_start` on the grid `s_grid` of each element (shape (points, batch),
    increasing s along axis 0, deep to shallow): (over, target, lower, upper, s0,
    f(lower), f(upper)), f = ln(W / target).  W at the points by one `vmap` of
    `vertical`, or (`vmapped` False) one call per point: on a law that rises, whose grid
    has 2-3 points, the calls cost less (a rim at a slip angle of 0.1 rad on Wong snow
    with Wong–Reece, slips -0.3 to 0.9, batch 1,000: the vmap 1.2x the time of the
    solve in `benchmarks/compare.py`, three runs)."""
    points = s_grid.shape[0]
    if vmapped:
        w_grid = jax.vmap(lambda s: vertical(_theta_from_s(s, theta_cap)))(s_grid)
    else:
        w_grid = jnp.stack([vertical(_theta_from_s(s, theta_cap)) for s in s_grid])
    over = ~jnp.any(w_grid >= load, axis=0)
    target = jnp.where(over, 0.5 * w_grid[0], load)
    carried = w_grid >= target
    # The shallowest grid point that carries the target (largest s), kept <= K - 2.
    k = jnp.clip(points - 1 - jnp.argmax(carried[::-1], axis=0), 0, points - 2)[None]
    pick = lambda x, j: jnp.take_along_axis(x, j, 0)[0]  # noqa: E731
    lower, upper = pick(s_grid, k), pick(s_grid, k + 1)
    f_lo = _log_ratio(pick(w_grid, k), target)
    f_hi = _log_ratio(pick(w_grid, k + 1), target)
    frac = jnp.clip(f_lo / jnp.where(f_lo > f_hi, f_lo - f_hi, 1.0), 0.0, 1.0)
    s0 = jnp.sqrt(lower**2 + frac * (upper**2 - lower**2))
    return over, target, lower, upper, s0, f_lo, f_hi
