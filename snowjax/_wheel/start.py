"""Where the solver starts: its variable s (theta0 = theta_cap exp(-s^2)), the bracket
[s_min, S_MAX], a warm start from a previous entry angle, and the any-terrain cold
starts: on a law whose pressure rises, the entry angle at which a power-law model of the
law carries the load (`_power_law_start`, for the secant steps of `BracketedSecant`); on
a law that can fall, W at two entry angles, at a deflecting tyre's switch to its
elastic mode and at the law's breakpoints (`_scan_start`, for the same secant steps,
inside the bracket it finds), and for a driven rim on such a law's front region the same
grid from its closed-form no-shear load (`_falling_lower_bound_start`); `front_rim.py`
has the closed-form start of a terrain that offers closed forms of its rim integrals.
See `equilibrium.py` for the solver itself.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from .._terrain.base import _half_angle_arc
from .batchwide import _any_in_batch

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


def _power_law_root(wheel, terrain, load, theta_cap, distribution, slip):
    """(theta0 [rad], m [-]): the entry angle at which a rigid rim carries `load` [N]
    without shear if the law were, near the rim's deepest point, a power of the sinkage
    with its local exponent there; m = d ln W / d ln theta0 of that model, 2 n + 1.

    The model: under a plate law sigma = k z^n the front region of a rim whose lowest
    point is z0 deep (contact length r theta0 = sqrt(D z0), the rim a parabola there,
    z = z0 (1 - u^2) at u = theta / theta0) carries `W = b sqrt(D z0) sigma(z0) c(n)`,
    c(n) = int_0^1 (1 - u^2)^n du = sqrt(pi) Gamma(n + 1) / (2 Gamma(n + 3/2))
    (Bekker's rigid-wheel sinkage, written with the law's own sigma(z0)), here `sqrt(pi
    / (4 n + pi))` (within 0.6 % for every n >= 0, exact at n = 0 and as n -> infinity;
    a gamma function per step cost as much as the rest of the start).  A distribution
    whose rear region [theta_r, theta_m] mirrors the front [theta_m, theta0] linearly
    (`AbstractStressDistribution.mirrors_rear`, `rear_region`), on a law without a base,
    carries the front's stresses over u_m..1 on both: W times (1 - u_r) / (1 - u_m)
    I(u_m) / I(0), I(a) = int_a^1 (1 - u^2)^n du ~ (1 - a)^(n+1) (2 - (1 - a) (n + 1) /
    (n + 2))^n / (n + 1) (the smooth factor (1 + u)^n at the mean of the weight (1 -
    u)^n; exact as a -> 1, within 5 % at a = 0 for n <= 3; the start errs by at most
    2.2 % on Reece's sand and 5.1 % on Bekker's snow with Wong–Reece, 25 % and 33 %
    without the factor).  For any law, n = z0
    sigma'(z0) / sigma(z0) at the current z0: five Newton steps on ln W = ln F_z in ln
    z0 (slope 1/2 + n), from 2 % of D, kept below the cap's sinkage.

    A wheel whose tread flattens (`AbstractWheel.deflects`: a `DeflectingTire`) then
    takes one more Newton step on the model of its own contact at that depth (its
    `contact(entry_angle, terrain)`): a flat ending at theta_f that carries p_f over the
    share a = sin theta_f / sin theta0 of the contact's length, and beyond it the curved
    part of the rim, on which the law is the power p_f (z / z_f)^n from the flat's depth
    z_f = z0 (1 - a^2) (n the law's exponent there): `W = b sqrt(D z0) p_f (a + c(n)
    I(a) / (I(0) (1 - a^2)^n))`, the rim's model where a = 0; its slope d ln W / d ln z0
    by one forward-mode pass.  The 100 kPa thesis tyre, 1-9 kN (Reece's sand / 4), slips
    0-0.9, 2,000 random cases: the start within 0.6 % of the root (median; at most 2.9
    %) on Reece's sand, against 6.2 % (27 %) with the rim's model; 4.7 % (14 %) against
    5.1 % (14 %) on Wong snow, whose log law near the flat is no power; on Bekker's
    snow (1-9 kN / 9), where these tyres do not flatten (their switch to the elastic
    mode lies beyond the cap), 3.2 % (5 %) either way.

    Per element, without the contact quadrature: the start of `BracketedSecant`
    (`_power_law_start`), whose steps correct the model's misfit (shear, the law's
    departure from a power)."""
    d, b = wheel.diameter, wheel.width
    mirrored = distribution.mirrors_rear and not terrain.has_base()
    z_cap = d * jnp.sin(theta_cap / 2) ** 2
    top = jnp.log(jnp.maximum(z_cap, jnp.finfo(z_cap.dtype).tiny)) + float(np.log1p(-1e-9))
    tiny = jnp.finfo(load.dtype).tiny

    def tail(a, n):  # I(a) as above
        rest = 1 - a
        return rest ** (n + 1) * (2 - rest * (n + 1) / (n + 2)) ** n / (n + 1)

    def entry(z):  # theta0 [rad] of the rim whose lowest point is z [m] deep
        return _half_angle_arc(jnp.minimum(z / d, 1.0))

    def law(z):  # (sigma [Pa], n [-]) of the law at the sinkage z [m]
        sigma, slope = jax.jvp(lambda z: terrain.pressure(z, b), (z,), (jnp.ones_like(z),))
        ok = jnp.isfinite(sigma) & jnp.isfinite(slope) & (sigma > 0)
        n = jnp.clip(jnp.where(ok, z * slope / jnp.where(ok, sigma, 1.0), 50.0), 0.05, 50.0)
        return jnp.where(ok, sigma, jnp.finfo(load.dtype).max), n

    def rear(w, z, n):  # W with the mirrored rear region's share
        if not mirrored:
            return w
        theta0 = entry(z)
        theta_m, theta_r = distribution.rear_region(theta0, slip)
        u_m = jnp.clip(theta_m / theta0, 0.0, 0.99)
        u_r = jnp.clip(theta_r / theta0, -1.0, u_m)
        return w * (1 - u_r) / (1 - u_m) * tail(u_m, n) / tail(0.0, n)

    def rim_model(log_z):  # (W [N], d ln W / d ln z [-]) at the lowest point's sinkage z
        z = jnp.exp(log_z)
        sigma, n = law(z)
        w = b * jnp.sqrt(d * z) * sigma * jnp.sqrt(np.pi / (4 * n + np.pi))
        return rear(w, z, n), 0.5 + n

    def flat_model(log_z):  # `rim_model` of the wheel's contact, which may flatten
        def log_load(log_z):
            z = jnp.exp(log_z)
            contact = type(wheel).contact(wheel, entry(z), terrain)
            sigma, n = law(contact.lowest_sinkage())
            n = jax.lax.stop_gradient(n)
            zero = jnp.zeros_like(z)
            pressure = contact.normal_stress(sigma, zero, zero)
            a = _flat_share(contact.lowest_angle(), contact.entry_angle)
            share = a + jnp.sqrt(np.pi / (4 * n + np.pi)) * _curved_share(a, n) / tail(0.0, n)
            w = rear(b * jnp.sqrt(d * z) * pressure * share, z, n)
            return jnp.log(jnp.maximum(w, tiny)), n

        one = jnp.ones_like(log_z)
        log_w, slope, n = jax.jvp(log_load, (log_z,), (one,), has_aux=True)
        ok = jnp.isfinite(slope) & (slope > 0.05)
        return jnp.exp(log_w), jnp.where(ok, slope, 0.5 + n)

    def newton(log_z, model):
        w, slope = model(log_z)
        g = jnp.log(jnp.maximum(w, tiny) / load)
        return jnp.minimum(log_z - jnp.clip(g / slope, -3.0, 3.0), top), slope

    start = jnp.minimum(jnp.log(0.02 * d), top)
    log_z0 = jax.lax.fori_loop(0, 5, lambda _, log_z: newton(log_z, rim_model)[0], start)
    if wheel.deflects:
        log_z0, slope = newton(log_z0, flat_model)
    else:
        slope = rim_model(log_z0)[1]
    return jax.lax.stop_gradient((entry(jnp.exp(log_z0)), 2 * slope))


def _flat_share(flat_angle, entry_angle):
    """a = sin theta_f / sin theta0 [-]: the share of the front contact's length that a
    flat ending at theta_f [rad] takes (0 on a rim), below 0.99."""
    ratio = jnp.sin(flat_angle) / jnp.maximum(
        jnp.sin(entry_angle), jnp.finfo(entry_angle.dtype).tiny
    )
    return jnp.clip(ratio, 0.0, 0.99)


def _curved_share(a, n):
    """I(a) / (1 - a^2)^n [-] (`_power_law_root`'s I, without underflow): the load per
    b sqrt(D z0) p_f of the curved part beyond a flat that takes the share a of the
    contact's length, where the law is p_f (z / z_f)^n and z_f = z0 (1 - a^2)."""
    rest = 1 - a
    return rest * jnp.exp(n * jnp.log((2 - rest * (n + 1) / (n + 2)) / (1 + a))) / (n + 1)


def _power_law_start(theta_cap, load, slip, wheel, terrain, distribution):
    """(over, target, lower, upper, s0, secant) of the any-terrain cold start on a law
    whose pressure rises (`BracketedSecant` solves from it): s0 at the entry angle of
    `_power_law_root` (with the distribution's rear region where it mirrors the front,
    on a law without a base: on Wong snow, whose exponent at the lowest point grows
    without bound next to the base, the rear factor made the start worse, its largest
    error on 64 random cases 0.24 -> 0.35), the secant's first slope d ln W / d s^2 =
    -m from its exponent, and the whole range [s_min, S_MAX] as the bracket.

    No element is held at the cap: an element that ends on the cap is beyond the
    layer's capacity where W there, which the secant's last step evaluated (the steps
    take the cap where they would pass it, and the bracket collapses onto it), falls
    short of the load (`equilibrium._solve_layout`).  Measured on the thesis tyre, 1-9 kN
    (Bekker's snow / 9, Reece's sand / 4), slips -0.3 to 0.9, front region and
    Wong–Reece: the secant steps reach |ln(W / F_z)| < 1e-10 in 3-7 evaluations of W
    (Reece's sand with Wong–Reece 3, 5 without the rear factor; Bekker's snow 4; Wong
    snow with Wong–Reece 5; the 100 kPa tyre on Wong snow 4-7, on Reece's sand 3-4),
    where the start this replaced took four (W at two entry angles, two secant steps)
    and Newton two more with tangents."""
    theta, exponent = _power_law_root(wheel, terrain, load, theta_cap, distribution, slip)
    s0 = _s_of_theta(theta, theta_cap)
    lower = jnp.full_like(load, _s_min(load.dtype))
    secant = dict(slope=-exponent)
    over = jnp.zeros_like(load, dtype=bool)
    return over, load, lower, jnp.full_like(load, S_MAX), s0, secant


# The second entry angle of the two-point start, s^2 = 8 (theta0 = e^-8 theta_cap).
S_MID = float(np.sqrt(8.0))


def _scan_start(vertical, theta_cap, load, terrain, diameter, deepest, bends=()):
    """(over, target, lower, upper, s0, secant) from W at a few entry angles, on a law
    whose pressure can fall at a breakpoint (`LayeredSnow`, where the ice breaks;
    `AbstractTerrain.pressure_rises` False).

    The solver wants the shallowest equilibrium, and W is no longer monotone.  W rises
    while the contact's deepest sinkage stays above a breakpoint, peaks when it reaches
    one (`_breakpoint_s`; `deepest(theta0)` the stress angle nearest the axle) and may
    fall just past it, then rises again.  W at the cap (s_min; the capacity), at e^-8 of
    it (s^2 = 8), at every breakpoint's angle (its local maxima) and at the entry angles
    where the wheel's W bends (`bends`: a deflecting tyre's switch to its elastic mode,
    `AbstractWheel.start_angles`) brackets the shallowest crossing of the load between
    the shallowest grid point that carries it and the next (`_grid_start`), and ln W
    linear in s^2 between the two gives s0.  A scan of 48 fixed angles, which this start
    replaced, cost about 80 % of such a solve and could miss a peak between its points
    (then returning a deeper root).  Secant steps between the grid points, tried on such
    a law, crossed the jumps where the ice breaks: regula falsi with the Illinois rule
    left a few starts of a batch 10-25 % off, which took as many Newton steps as before
    (layered snow, 1-9 kN / 4, slips 0-0.9, batch 20,000: 1.08x the time).

    The solve from this start takes `BracketedSecant`'s steps (`secant`: f = ln(W /
    target) at the bracket's ends and the chord's slope in s^2 between them), one
    evaluation of W each where a Newton step took W and its tangent; the bracket keeps
    them on the shallowest crossing, as it kept Newton's.  Layered snow, 1-9 kN / 4,
    slips 0-0.9, batch 2,048 (one chunk), one core: 0.78x the time of the Newton steps
    on the front region, 0.53x with Wong–Reece.  More grid points between the
    breakpoint's angle and s^2 = 8 (one where the deepest sinkage is half the
    breakpoint's, s^2 + ln sqrt 2; two at s^2 + 0.1 and + 0.5, or + 0.15 and + 0.7), or
    the power-law model's root (`_power_law_root`) as one, cost more evaluations of W
    than they saved (1.11-1.38x the time).
    """
    s_lo = _s_min(load.dtype)
    grid = [jnp.full_like(load, s) for s in (s_lo, S_MID)]
    grid += [_s_of_theta(theta, theta_cap) for theta in bends]
    grid += _breakpoint_s(terrain, diameter, theta_cap, deepest)
    s_grid = jax.lax.stop_gradient(jnp.sort(jnp.stack(grid), axis=0))
    over, target, lower, upper, s0, f_lo, f_hi = _grid_start(vertical, theta_cap, load, s_grid)
    # The secant's options: f at the bracket's ends where it has the sign the bracket
    # assumes (+inf / -inf, unknown, where not), and the chord's slope in s^2.
    f_lo = jnp.where(jnp.isfinite(f_lo) & (f_lo > 0), f_lo, jnp.inf)
    f_hi = jnp.where(jnp.isfinite(f_hi) & (f_hi < 0), f_hi, -jnp.inf)
    known = jnp.isfinite(f_lo) & jnp.isfinite(f_hi) & (upper > lower)
    chord = (f_hi - f_lo) / jnp.where(known, upper**2 - lower**2, 1.0)
    secant = dict(f_lower=f_lo, f_upper=f_hi, slope=jnp.where(known, chord, -1.0))
    return over, target, lower, upper, s0, jax.lax.stop_gradient(secant)


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


def _grid_start(vertical, theta_cap, load, s_grid):
    """`_scan_start` on the grid `s_grid` of each element (shape (points, batch),
    increasing s along axis 0, deep to shallow): (over, target, lower, upper, s0,
    f(lower), f(upper)), f = ln(W / target), W at the points one after the other
    (`lax.map` of `vertical`).  A `vmap` over the points held every point's nodes at
    once, arrays of (points, batch, nodes) whose filling and traffic cost more than the
    quadrature: layered snow with Wong–Reece, 1-9 kN / 4, slips 0-0.9, batch 2,048 (one
    chunk), one core: the start took 40 ms of a 93 ms solve, now 17 ms of 66 ms (three
    points; a secant step of the batch costs 6 ms), and the first call compiles in 8.7 s
    instead of 9.8 s."""
    w_grid = jax.lax.map(lambda s: vertical(_theta_from_s(s, theta_cap)), s_grid)
    over, target, deep, shallow = _grid_bracket(w_grid, load)
    lower, upper = deep(s_grid), shallow(s_grid)
    f_lo = _balance_residual(deep(w_grid), target)
    f_hi = _balance_residual(shallow(w_grid), target)
    return over, target, lower, upper, _chord_root(lower, upper, f_lo, f_hi), f_lo, f_hi


def _grid_bracket(w_grid, load):
    """(over, target, deep, shallow) from W [N] on a grid of each element (shape (points,
    batch), deep to shallow): `over` where no point carries the load (the target then
    half of W at the deepest point), and `deep` / `shallow`, functions picking from such
    a grid the shallowest point that carries the target (kept <= points - 2) and the
    next."""
    points = w_grid.shape[0]
    over = ~jnp.any(w_grid >= load, axis=0)
    target = jnp.where(over, 0.5 * w_grid[0], load)
    carried = w_grid >= target
    k = jnp.clip(points - 1 - jnp.argmax(carried[::-1], axis=0), 0, points - 2)[None]
    return (
        over,
        target,
        lambda x: jnp.take_along_axis(x, k, 0)[0],
        lambda x: jnp.take_along_axis(x, k + 1, 0)[0],
    )


def _chord_root(lower, upper, f_lo, f_hi):
    """s where f, linear in s^2 between (lower, f_lo) and (upper, f_hi), crosses 0 (kept
    in [lower, upper])."""
    frac = jnp.clip(f_lo / jnp.where(f_lo > f_hi, f_lo - f_hi, 1.0), 0.0, 1.0)
    return jnp.sqrt(lower**2 + frac * (upper**2 - lower**2))


# Safeguarded Newton steps on the closed-form no-shear balance of a law that can fall.
NO_SHEAR_STEPS = 3


def _falling_lower_bound_start(vertical, no_shear, theta_cap, load, diameter, terrain, shear):
    """(over, target, lower, upper, s0, secant) of a driven rim's cold start (every slip
    >= 0) on the front region of a law that can fall (`LayeredSnow`), from its
    closed-form no-shear load `no_shear(theta0)` [N] (`front_rim._no_shear_load`), for
    the secant steps of `BracketedSecant`; `shear`: whether the shear law mobilises a
    stress (static).

    `general._falling_law_start` wants the shallowest equilibrium from W at the cap, at
    s^2 = 8 and at the breakpoints' angles (three quadratures on `LayeredSnow`).  Here
    those points take the closed form instead, and a quadrature only where it cannot
    decide: on a driven wheel (slip >= 0) the shear stress only adds to W, so a point
    whose no-shear load carries the load carries it; W is evaluated at the cap where its
    no-shear load falls short somewhere in the batch (then the capacity: `over`), and at
    a breakpoint's angle where it does (whether the shear carries the load before the
    ice breaks).  The shallow end s^2 = 8 is replaced by S_MAX (W rises monotonically
    before the first breakpoint, and nothing is known of W there).  Inside the closed
    form's bracket, `NO_SHEAR_STEPS` safeguarded Newton steps on the no-shear balance
    (bisection where a step would leave the bracket or W rises with s: just deeper than
    a breakpoint, where the law has dropped, W dips before it rises again, so such a
    bracket starts in its middle) give its root s_ns; one quadrature there gives the
    shear's factor W / W_ns and the secant a point already evaluated (f >= 0 on a driven
    wheel: the bracket's deep end), and one Newton step of the closed form for load /
    factor the start (as `front_rim._closed_form_start`).  The bracket holds the shallowest
    crossing of the load between the grid points, as the quadrature grid's.

    `LayeredSnow.ice_layer_example`, thesis tyre, 1-9 kN / 4, slips 0-0.9, one chunk of
    2,048: the start within 0.43 % of the load in W (median; 7.5 % at most), against 24
    % from the quadrature grid's interpolation; every element then converges within 4
    secant steps, where the grid's start left 14 % of the chunk unfinished after 5 (22
    group steps); over 6,000 random crusts (`tests/random_cases.py`, driven, straight
    and at slip angles to 60 degrees, 5 % resting on the base) the statuses and roots
    of the grid's start (sinkage within 2.7e-11 relative).  Two or five Newton steps
    gave the same solver steps there; three keep one for a bisection.
    """
    s_lo = _s_min(load.dtype)
    axle = lambda theta0: jnp.zeros_like(theta0)  # noqa: E731  (the front region's deepest)
    breaks = _breakpoint_s(terrain, diameter, theta_cap, axle)
    cap = jnp.full_like(load, s_lo)
    points = [cap, *breaks, jnp.full_like(load, S_MID)]
    s_grid = jax.lax.stop_gradient(jnp.sort(jnp.stack(points), axis=0))

    def w_ns_at(s):
        return no_shear(_theta_from_s(s, theta_cap))

    w_ns = jax.vmap(w_ns_at)(s_grid)
    # W where the closed form cannot decide: at the cap and the breakpoints' angles (the
    # grid's points below s^2 = 8), where the no-shear load falls short of the load.
    exact = jnp.zeros(s_grid.shape, bool)
    w_grid = w_ns
    for k in range(s_grid.shape[0] - 1):
        short = (w_ns[k] < load) & (s_grid[k] < S_MID)
        w_k = jax.lax.cond(
            _any_in_batch(short),
            lambda k=k: vertical(_theta_from_s(s_grid[k], theta_cap)),
            lambda k=k: w_ns[k],
        )
        w_grid = w_grid.at[k].set(jnp.where(short, w_k, w_ns[k]))
        exact = exact.at[k].set(short)
    over, target, deep, shallow = _grid_bracket(w_grid, load)
    lower, upper_ns = deep(s_grid), shallow(s_grid)
    f_lower = jnp.where(deep(exact), _balance_residual(deep(w_grid), target), jnp.inf)
    shallow_known = shallow(exact)
    upper = jnp.where(shallow_known, upper_ns, S_MAX)
    f_upper = jnp.where(shallow_known, _balance_residual(shallow(w_grid), target), -jnp.inf)
    # The no-shear root inside the closed form's bracket.
    f_lo = _balance_residual(deep(w_ns), target)
    f_hi = _balance_residual(shallow(w_ns), target)
    s_ns = _chord_root(lower, upper_ns, f_lo, f_hi)
    # Just deeper than a breakpoint the law has dropped (W dips there before it rises
    # again): a bracket whose shallow end is a breakpoint starts in its middle.
    s_ns = jnp.where(upper_ns < S_MID, 0.5 * (lower + upper_ns), s_ns)

    def residual(s):
        return _balance_residual(w_ns_at(s), target)

    def newton(_, carry):  # safeguarded (`BracketedNewton`'s step on the closed form)
        s, lo, hi, _ = carry
        f, df = jax.jvp(residual, (s,), (jnp.ones_like(s),))
        positive = f > 0
        lo, hi = jnp.where(positive, s, lo), jnp.where(positive, hi, s)
        step = s - f / jnp.where(df < 0, df, -1.0)
        # (A step onto the bracket's end is the root itself: |f| at rounding.)
        inside = (df < 0) & (step >= lo) & (step <= hi)
        return jnp.where(inside, step, 0.5 * (lo + hi)), lo, hi, df

    zero = jnp.zeros_like(s_ns)
    s_ns, *_, slope = jax.lax.fori_loop(0, NO_SHEAR_STEPS, newton, (s_ns, lower, upper_ns, zero))
    # The secant's first slope d f / d s^2, the closed form's where it falls.
    falling = slope < 0
    first_slope = jnp.where(falling, slope / (2 * jnp.where(falling, s_ns, 1.0)), -1.0)
    secant = dict(f_lower=f_lower, f_upper=f_upper, slope=first_slope)
    s0 = s_ns
    if shear:
        theta_g = _theta_from_s(s_ns, theta_cap)
        w_g = vertical(theta_g)
        factor = jnp.clip(w_g / jnp.maximum(w_ns_at(s_ns), 1e-30 * target), 0.5, 2.0)
        s0 = _damped_step(s_ns, jnp.log(factor), slope)
        # The point evaluated is one end of the bracket, and the secant's first point.
        f_g = _balance_residual(w_g, target)
        positive = f_g > 0
        lower = jnp.where(positive, jnp.maximum(lower, s_ns), lower)
        upper = jnp.where(positive, upper, jnp.minimum(upper, s_ns))
        secant["f_lower"] = jnp.where(positive, f_g, secant["f_lower"])
        secant["f_upper"] = jnp.where(positive, secant["f_upper"], f_g)
        secant["x_last"], secant["f_last"] = s_ns**2, f_g
    s0 = jnp.clip(s0, lower, upper)
    return jax.lax.stop_gradient((over, target, lower, upper, s0, secant))
