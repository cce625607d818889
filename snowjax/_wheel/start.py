"""Where the solver starts: its variable s (theta0 = theta_cap exp(-s^2)), the bracket
[s_min, S_MAX], a warm start from a previous entry angle, and the any-terrain start, W
at two entry angles or a scan of W (`_scan_start`); `front_rim.py` has the closed-form
start of a terrain that offers closed forms of its rim integrals.  See `equilibrium.py`
for the solver itself.
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
    """A few plain Newton steps on an elementwise residual of s (for the initial guess)."""

    def step(_, s):
        f, df = jax.jvp(residual, (s,), (jnp.ones_like(s),))
        delta = jnp.where(df < 0, f / jnp.where(df < 0, df, -1.0), 0.0)
        # Damped: at s ~ s_min the derivative is ~ s (theta0 = theta_cap exp(-s^2)), so a
        # full step can overshoot to where W underflows (float32).
        return jnp.clip(s - jnp.clip(delta, -0.5, 0.5), _s_min(s.dtype), S_MAX)

    return jax.lax.fori_loop(0, steps, step, s)


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


def _scan_grid(dtype):
    """Solver variable s at which a law whose pressure can fall (`AbstractTerrain.
    pressure_rises` False: `LayeredSnow`, whose W(theta0) can fall after the ice breaks)
    scans W before Newton (increasing: deep to shallow): s^2 from S_MIN^2 to S_MAX^2 in
    steps of 2 plus 39 points with theta0 / theta_cap evenly spaced in [0.1, 1] (steps of
    0.023), which resolve the crust's peak; a peak narrower than that can be missed (then
    a deeper root is returned)."""
    s2 = np.linspace(_s_min(dtype) ** 2, S_MAX**2, 9)
    s2 = np.unique(np.concatenate([s2, -np.log(np.linspace(0.1, 1.0, 40)[:-1])]))
    return jnp.asarray(np.sqrt(np.sort(s2)), dtype)


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


def _scan_start(vertical, theta_cap, load, terrain):
    """(over, target, lower, upper, s0) from W at a few entry angles (any terrain).

    A law whose pressure rises with depth (`AbstractTerrain.pressure_rises`): W is
    monotone in theta0 except for a braked wheel's backward shear, and two evaluations
    start Newton: W at the cap (s_min; the capacity) and at e^-8 of it (s^2 = 8) bracket
    the root in [s_min, S_MID] or [S_MID, S_MAX], and ln W linear in s^2 through both
    (exact for a power law; extrapolated beyond S_MID) gives s0.  A third point at s^2 =
    16, which this start once also evaluated, changed no result beyond 1e-11 relative
    and cost 4-9 % of the any-terrain solves.  Otherwise (`LayeredSnow`) W is scanned on
    `_scan_grid` and the shallowest grid interval where W crosses the load brackets the
    root (the shallowest equilibrium), interpolated the same way.
    """
    if not terrain.pressure_rises():
        return _grid_start(vertical, theta_cap, load, _scan_grid(load.dtype))
    dtype = load.dtype
    s_lo = _s_min(dtype)
    w_lo, w_mid = (
        vertical(_theta_from_s(jnp.full_like(load, s), theta_cap)) for s in (s_lo, S_MID)
    )
    over = w_lo < load
    target = jnp.where(over, 0.5 * w_lo, load)
    shallow = w_mid >= target  # the root lies above e^-8 of the cap
    lower = jnp.where(shallow, S_MID, s_lo)
    upper = jnp.where(shallow, S_MAX, S_MID)
    f_lo, f_mid = _log_ratio(w_lo, target), _log_ratio(w_mid, target)
    slope = jnp.where(f_lo > f_mid, (f_lo - f_mid) / (S_MID**2 - s_lo**2), 1.0)
    s0_squared = jnp.clip(s_lo**2 + f_lo / slope, lower**2, upper**2)
    return over, target, lower, upper, jnp.sqrt(s0_squared)


def _log_ratio(w, target):
    """ln(W / target), W floored at the smallest normal number (1e-300 is 0 in float32:
    log(0 / target) would be -inf and the interpolation NaN)."""
    return jnp.log(jnp.maximum(w, jnp.finfo(w.dtype).tiny) / target)


def _grid_start(vertical, theta_cap, load, s_grid):
    """`_scan_start` on the grid `s_grid` (increasing s, deep to shallow)."""
    points = s_grid.shape[0]
    w_grid = jax.vmap(lambda s: vertical(_theta_from_s(s, theta_cap)))(
        jnp.broadcast_to(s_grid[:, None], (points,) + load.shape)
    )
    over = ~jnp.any(w_grid >= load, axis=0)
    target = jnp.where(over, 0.5 * w_grid[0], load)
    carried = w_grid >= target
    # The shallowest grid point that carries the target (largest s), kept <= K - 2.
    k = jnp.clip(points - 1 - jnp.argmax(carried[::-1], axis=0), 0, points - 2)
    lower, upper = s_grid[k], s_grid[k + 1]
    f_lo = _log_ratio(jnp.take_along_axis(w_grid, k[None], 0)[0], target)
    f_hi = _log_ratio(jnp.take_along_axis(w_grid, k[None] + 1, 0)[0], target)
    frac = jnp.clip(f_lo / jnp.where(f_lo > f_hi, f_lo - f_hi, 1.0), 0.0, 1.0)
    return over, target, lower, upper, jnp.sqrt(lower**2 + frac * (upper**2 - lower**2))
