"""Contact integrals of any wheel on any terrain law, with any stress distribution (the
any-terrain rule), and the quadrature's node maps.

`general_contact` is the integrator of `AnyTerrainRule`, the rule the contact entry
(`contact._contact_batch`) takes for every combination except the plain rim (constant
width) on a law with closed-form rim integrals (`WongSnow`) on the front region running
straight, which takes the accelerations of `front_rim.py` (`FrontRimRule`); both rules
build their nodes from the maps here (`_power_map`, `_sinh_offsets`) and find the
braking sign change with `geometry._shear_sign_change`.  The wheel's geometry comes from its contact
(`AbstractContact`: the rim's, or a tyre's flat).

The rim stresses (normal stress from the terrain's pressure–sinkage law at the rim
sinkage, shear stress by the shear law from the shear displacement 4.10) are
integrated over theta_r <= theta <= theta0 (0 <= theta <= theta0 without a
distribution) by composite Gauss–Legendre quadrature.  The interval is cut at every
angle where an integrand has a kink or a jump: theta_m (peak of the Wong–Reece
distribution), the sign change of the shear displacement of a braked wheel, and the
angles where the rim passes a breakpoint of the terrain's law
(`AbstractTerrain.breakpoint_sinkages`, e.g. `LayeredSnow`'s ice failure; front and
mirrored rear).  Each piece is split in two halves whose nodes are graded towards
their outer ends by `x = end -+ s sinh(mu t^2)`: near an end the node spacing grows
like t^2, which makes the endpoint behaviour of power laws (sigma ~ (theta0 - theta)^n
at the entry angle and the exit angle) smooth in t, and s (the width of the shear layer
behind the entry angle or around the sign change) sets where the spacing starts to grow
geometrically.  A contact that is one piece with a smooth lower end is one panel graded
towards its entry (`_graded_panel`); under a mirrored distribution, a driven contact
cut inside takes one panel per piece clustered at both its ends (`_cut_panels`).

Breakpoints carry gradients (the integration limits and the failure angle, where the
integrand jumps, must); the grading scales do not (the exact integral does not depend
on them).
"""

from __future__ import annotations

import functools
from typing import ClassVar

import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array

from .batchwide import _all_in_batch
from .distribution import _is_front
from .geometry import (
    _layer_width,
    _rim_sinkage_between,
    _shear_displacement,
    _sin_cos,
)
from .rules import AbstractContactRule
from .start import _power_law_start, _scan_start, _warm_bracket_start
from .terms import ContactNodes, _total

GRADING_POWER = 2
# The power of the node map at a log-singular end (`_graded_half_panels`), and the share of
# the front region [lowest point, theta0] taken by the panel next to a base.  Measured on
# the thesis tyre, rigid, on Wong snow (slips 0.2, -0.3, 0.9) against SciPy for clearances
# of the lowest point from 0 to 0.9 z_w: every contact integral within 2.6e-7 (4.3e-5
# with the power-2 map and no extra panel, 9e-6 with the power-4 map alone).
LOG_GRADING_POWER = 4
BASE_PANEL = 1 / 32


@functools.cache
def _gauss_legendre(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Nodes on [0, 1] and weights (summing to 1) of the n-point Gauss–Legendre rule."""
    u, w = np.polynomial.legendre.leggauss(n)
    return (u + 1) / 2, w / 2


def _rule(n: int, dtype) -> tuple[Array, Array]:
    """`_gauss_legendre(n)` as arrays of `dtype`."""
    t, w = _gauss_legendre(n)
    return jnp.asarray(t, dtype=dtype), jnp.asarray(w, dtype=dtype)


def _power_map(t, w, power):
    """GL nodes t in [0, 1] mapped to u = t^power, with weights du = power t^(power-1) w:
    nodes clustered at 0, where the spacing grows like t^power (endpoint singularities and
    power-law ends of the integrands become smooth in t)."""
    return t**power, power * t ** (power - 1) * w


def _smoothstep_map(t, w):
    """GL nodes t in [0, 1] mapped to u = t^2 (3 - 2 t), with weights du = 6 t (1 - t) w:
    nodes clustered quadratically at both ends."""
    return t * t * (3 - 2 * t), 6 * t * (1 - t) * w


def _sinh_offsets(u, du, length, scale, min_ratio):
    """The sinh node map: offsets `x = s sinh(mu u)` from the clustered end of a panel of
    the given length, and their weights, for u in [0, 1] with weights du.

    `mu = asinh(length / s)` (the last node maps to the far end): the node spacing is ~ s
    at the clustered end and grows geometrically away from it.  s is clipped to
    [min_ratio, 10] x length; sinh and cosh come from one exp.
    """
    s = jnp.clip(scale, min_ratio * length, 10 * length)
    mu = jnp.arcsinh(length / s)
    e = jnp.exp(mu * u)
    inv = 1 / e
    return s * 0.5 * (e - inv), s * mu * 0.5 * (e + inv) * du


def _single_panel_nodes(n: int) -> int:
    """Nodes of a contact that is one panel whose lower end is smooth (`_graded_panel`),
    for n per half-panel of the general rule: ceil(5 n / 3) (20 for 12, 14 for 8)."""
    return -(-5 * n // 3)


def _graded_panel(lo, hi, scale_hi, n, dtype, both_ends=False):
    """Nodes and weights on [lo, hi] (shapes ()), for a contact that is one panel whose
    integrands are smooth at lo: one panel graded towards hi alone, the sinh map of the
    power map (`GRADING_POWER`) of the `_single_panel_nodes(n)`-point rule, where
    `_graded_half_panels` would put n nodes in each half and grade the lower half
    towards lo.

    Where: on a law without a base or breakpoints, in a contact cut only at its ends
    (driving, or without a shear stress: no braking split), the front region of a rim
    (lo the axle, where the rim is deepest and the law smooth) or of a tyre beyond its
    flat (lo the flat's front end, the arc's deepest point), and the Wong–Reece stress
    angle's [theta_m, theta0] of a rim (both regions' integrands are smooth at
    theta_m).  Measured against 60 nodes per half-panel on 400 random driven cases per
    law (Bekker's, Reece's; `tests/random_cases.py`): rims, straight and at a slip
    angle, within 1.6e-8 of the load (the half-panels' 24 nodes: 1.2e-6 on Bekker's
    front region, where the lower half's nodes were spent at the smooth end and the
    power-law entry got 12); tyres on the front region, half of them soft, within
    1.1e-8 (the half-panels: 1.5e-6).

    `both_ends` (static): the nodes cluster at lo too (`_smoothstep_map` instead of the
    power map), for a panel whose lower end is a cut (`_cut_panels`).
    """
    rule = _rule(_single_panel_nodes(n), dtype)
    u, du = _smoothstep_map(*rule) if both_ends else _power_map(*rule, GRADING_POWER)
    length = hi - lo
    positive = length > 0
    scale = jax.lax.stop_gradient(jnp.broadcast_to(scale_hi, hi.shape))
    offset, jac = _sinh_offsets(u, du, jnp.where(positive, length, 1.0), scale, 1e-3)
    return jnp.where(positive, hi - offset, hi), jnp.where(positive, jac, 0.0)


def _panel_nodes(
    points, start, theta0, entry_scale, n, smooth_start, base_end=None, smooth_cuts=False
):
    """Nodes and weights on [start, theta0] cut at `points` (`_panel_ends`' (angle,
    scale) pairs, the first two the ends): one panel graded towards theta0 alone
    (`_graded_panel`) where there is no cut but the ends and the integrands are smooth
    at `start` (`smooth_start`, static); where every inner cut is a kink or jump with
    no layer of its own (`smooth_cuts`, static: no braking split, no base's panel),
    one panel per piece clustered at both its ends (`_cut_panels`); else
    two graded half-panels per panel, the lower half of the panel that starts at
    `base_end` (a base's lowest point, or None) with the log-singular grading."""
    if smooth_start and len(points) == 2:
        return _graded_panel(start, theta0, entry_scale, n, theta0.dtype)
    if smooth_cuts:
        return _cut_panels(points, start, theta0, entry_scale, n)
    angles, scales = _panel_ends(points, start, theta0, entry_scale)
    log_end = None if base_end is None else angles[:-1] == base_end
    return _graded_half_panels(
        angles[:-1], angles[1:], scales[:-1], scales[1:], n, theta0.dtype, log_end
    )


def _cut_panels(points, start, theta0, entry_scale, n):
    """Nodes and weights on [start, theta0] cut at the inner `points` (`_panel_ends`),
    every one a kink or a jump of the integrands with no layer of its own (a tyre's
    flat's ends, a law's breakpoint; not a braked wheel's split): each piece one
    Gauss–Legendre panel whose nodes cluster quadratically at both its ends
    (`_smoothstep_map`), n nodes on the inner pieces and `_single_panel_nodes(n)` on
    the piece that reaches theta0, whose nodes also grade towards the entry's shear
    layer (the sinh map of `_graded_panel`, scale `entry_scale`).  Inner points at or
    beyond theta0 move to `start` (zero-length panels there), so the last piece
    always reaches the entry.  Where `_graded_half_panels` puts 2 n nodes on every
    piece: a driven rim on layered snow with Wong–Reece 12 + 20 nodes instead of 48, a
    driven tyre there 12 + 12 + 20 instead of 72.

    The ends cluster, though the integrands are smooth on either side of a cut: next
    to layered snow's ice the top layer's law is close to its own log singularity
    (the ice breaks at up to 98 % of that layer's z_w), and a plain Gauss–Legendre
    panel there erred by 3e-4 of the load.  Measured against SciPy (`tests/
    reference_terrain.py`, `tests/reference_tire.py`) at fixed entry angles on random
    driven cases, K 2-30 mm, slips 0-0.9, c1 0.3-0.45, c2 0.2-0.4, c3 0 or -0.1 to
    -0.001: rims on layered snow (the property tests' crusts, entry angles 0.05-0.999
    of the base's), 250 cases: within 1.9e-8 of the load (the half-panels: 7.4e-8);
    tyres on Wong snow (p_i 20 kPa-1 MPa) and on Bekker's law, 80 each: 1.4e-7 and
    1.9e-7, as the half-panels (their worst cases are rigid-mode tyres, whose error
    lies in the piece at the entry either way); rims on Wong snow with theta_m below
    a quarter of theta0 (c1 down to 0.02, entry angles to 1 - 1e-5 of the base's, one
    piece here): within 3.1e-8 (the half-panels: 4.6e-7).  At slip angles (-1 to 1
    rad; no SciPy reference there), 200 random equilibria on layered snow against 60
    nodes per half-panel: within 1.7e-8 (sinkage per D, forces per load, moments per
    load x r; the half-panels: 7.0e-8)."""
    angles, _ = _panel_ends(points, start, theta0, entry_scale, beyond_to_start=True)
    dtype = theta0.dtype
    u, du = _smoothstep_map(*_rule(n, dtype))
    lo, length = angles[:-2, None], (angles[1:-1] - angles[:-2])[:, None]  # inner pieces
    last, last_weight = _graded_panel(angles[-2], theta0, entry_scale, n, dtype, both_ends=True)
    return (
        jnp.concatenate([(lo + length * u).reshape(-1), last]),
        jnp.concatenate([(length * du).reshape(-1), last_weight]),
    )


def _graded_half_panels(lo, hi, scale_lo, scale_hi, n, dtype, log_end=None):
    """Nodes and weights on [lo, hi]: two halves graded towards lo and hi respectively.

    `lo`, `hi`, `scale_*` have shape (P,); returns arrays of shape (P * 2 * n,).  Each
    half is the sinh map of the power map (`GRADING_POWER`) of the n-point rule.
    Zero-length panels get zero weights.  `log_end` (None or (P,) booleans): the lower
    halves of those panels use the power `LOG_GRADING_POWER` instead (a logarithmic
    singularity at lo: the integrand times the map's Jacobian, t^3 ln t, is then smooth
    enough for Gauss–Legendre).
    """
    u, du = _power_map(*_rule(n, dtype), GRADING_POWER)
    half = 0.5 * (hi - lo)
    positive = half > 0
    length = jnp.where(positive, half, 1.0)[:, None]

    def graded(scale, u, du):
        return _sinh_offsets(u, du, length, jax.lax.stop_gradient(scale[:, None]), 1e-3)

    u_lo, du_lo = u, du
    if log_end is not None:
        u_log, du_log = _power_map(*_rule(n, dtype), LOG_GRADING_POWER)
        u_lo = jnp.where(log_end[:, None], u_log, u)
        du_lo = jnp.where(log_end[:, None], du_log, du)
    off_lo, jac_lo = graded(scale_lo, u_lo, du_lo)
    off_hi, jac_hi = graded(scale_hi, u, du)
    on = positive[:, None]
    x_lo = jnp.where(on, lo[:, None] + off_lo, lo[:, None])
    x_hi = jnp.where(on, hi[:, None] - off_hi, hi[:, None])
    w_lo = jnp.where(on, jac_lo, 0.0)
    w_hi = jnp.where(on, jac_hi, 0.0)
    return (
        jnp.concatenate([x_lo, x_hi], axis=1).reshape(-1),
        jnp.concatenate([w_lo, w_hi], axis=1).reshape(-1),
    )


def _front_base_end(distribution, terrain, contact):
    """The angle [rad] where a front-region contact is deepest (`contact.lowest_angle`), if
    the terrain has a base (static); None otherwise."""
    if not (_is_front(distribution) and terrain.has_base()):
        return None
    return contact.lowest_angle()


def _safe_arccos(x):
    """arccos with a finite gradient at +-1 (clipped arguments get gradient 0)."""
    inside = (x > -1) & (x < 1)
    return jnp.where(inside, jnp.arccos(jnp.where(inside, x, 0.0)), jnp.where(x >= 1, 0.0, jnp.pi))


def _below_base(sinkage, depth):
    """The rim sinkage [m] kept 4 ulp of `depth` [m] above the base.

    A wheel resting on the base (theta0 = the cap, `Status.BOTTOMED_OUT`) reaches the
    depth at theta = 0, where a law such as Wong's diverges (logarithmically: the integral
    is finite).  Nodes next to theta = 0 (a braking split by the axle, float32's coarse
    spacing) would get a sinkage that rounds to the depth and an infinite stress; there
    the stress is taken at 4 ulp above the base instead (the lost part of the integral is
    of the order of the node's width, 1e-8 relative in float64).  A converged entry angle
    stays further from the base (`S_MIN`), so its nodes are never moved.
    """
    eps = float(np.finfo(sinkage.dtype).eps)
    return jnp.minimum(sinkage, depth * (1 - 4 * eps))


def _stresses_at(theta, theta_eff, contact, terrain, width, guard=True):
    """(sigma [Pa], c [Pa], tan phi [-], K [m]) at angles theta [rad] whose stress angle is
    theta_eff [rad], of a wheel's `contact` (`AbstractContact`) of width b [m]: the
    law's (`_law_at`), the contact having the last word on the normal stress
    (`contact.normal_stress`: a tyre's flat carries its own pressure)."""
    sigma, strength = _law_at(theta, theta_eff, contact, terrain, width, guard)
    return contact.normal_stress(sigma, theta, theta_eff), *strength


def _law_at(theta, theta_eff, contact, terrain, width, guard=True):
    """(sigma [Pa], (c [Pa], tan phi [-], K [m])): the terrain's law at the depth of the
    point at angle theta [rad] whose stress angle is theta_eff [rad], of a wheel's
    `contact` (`AbstractContact`) of width b [m].

    The depth z = (the contact's deepest point) less `contact.rise(theta, theta_eff)`
    (on a rim 4.5, `D [sin^2(theta0/2) - sin^2(theta_eff/2)]`).  On a law with a base
    (`AbstractTerrain.has_base`) the normal stress is the law at the height above the
    base, `pressure_at_clearance((depth - z_low) + rise)`: free of the cancellation of
    depth - z next to the base, where a law such as Wong's diverges (in float32 the rim
    sinkage rounds to the base within 4e-4 rad of the lowest point).  The strength (c,
    tan phi, K) is the law's at z, kept 4 ulp above the base (`_below_base`; `guard`
    False: not kept).
    """
    low = contact.lowest_sinkage()
    rise = contact.rise(theta, theta_eff)
    z = low - rise
    sigma, cohesion, tan_phi, modulus = terrain.rim_properties(
        _below_base(z, terrain.depth) if guard else z, width
    )
    if terrain.has_base():
        # The lowest point's clearance, 0 within 4 ulp of the base: a wheel resting on
        # the base (the solver's cap, an entry angle rounded from the base's depth) has
        # none, and a rounding error of depth - low (float32: 1e-8 z_w) would otherwise
        # stand for it next to a singularity (the thrust of a bottomed, braked wheel:
        # 2e-3 in float32), or, negative, swamp the clearance of the nodes next to it.
        gap = terrain.depth - low
        eps = jnp.finfo(gap.dtype).eps
        clearance = jnp.where(gap > 4 * eps * terrain.depth, gap, 0.0) + rise
        tiny = jnp.finfo(clearance.dtype).tiny
        sigma = terrain.pressure_at_clearance(jnp.maximum(clearance, tiny), width)
    return sigma, (cohesion, tan_phi, modulus)


def _panel_ends(points, theta_r, theta0, entry_scale, beyond_to_start=False):
    """(angles [rad], grading scales [rad]) of the panels' ends, in increasing order:
    theta_r, the inner `points[2:]` ((angle, scale) pairs) clipped into [theta_r,
    theta0] and sorted, theta0 (`points[:2]` are the contact's ends, whose order is
    known).

    The inner points are sorted by an odd-even transposition network of `where`s
    (stable; the order carries no gradient): a contact has a few of them (none on a
    rim's front region running straight on a law without a base), and XLA's sort
    (`argsort` and the gathers it needs) cost 130-380 ns per element and evaluation on
    CPU, 7-26 % of the any-terrain W.  An inner point clipped to theta0
    (a breakpoint beyond the contact) takes the entry's grading scale: the panel that
    ends there is the one that reaches the entry (a zero-length panel follows it);
    with `beyond_to_start` (static) it moves to theta_r instead (a zero-length panel
    there: the last panel then always reaches the entry).
    """
    inner = [jnp.clip(angle, theta_r, theta0) for angle, _ in points[2:]]
    if beyond_to_start:
        inner = [jnp.where(angle >= theta0, theta_r, angle) for angle in inner]
    scales = [
        jnp.where(angle >= theta0, entry_scale, jnp.broadcast_to(scale, theta0.shape))
        for angle, (_, scale) in zip(inner, points[2:])
    ]
    for rnd in range(len(inner)):
        for i in range(rnd % 2, len(inner) - 1, 2):
            swap = jax.lax.stop_gradient(inner[i]) > jax.lax.stop_gradient(inner[i + 1])
            inner[i], inner[i + 1] = (
                jnp.where(swap, inner[i + 1], inner[i]),
                jnp.where(swap, inner[i], inner[i + 1]),
            )
            scales[i], scales[i + 1] = (
                jnp.where(swap, scales[i + 1], scales[i]),
                jnp.where(swap, scales[i], scales[i + 1]),
            )
    inf = jnp.full_like(theta0, jnp.inf)
    return (
        jnp.stack([theta_r, *inner, theta0]),
        jnp.stack([inf, *scales, jnp.broadcast_to(entry_scale, theta0.shape)]),
    )


def _braking_point(theta_r, slip, contact, terrain, distribution):
    """(angle, grading scale) of the panel cut at a braked wheel's sign change of the shear
    displacement (`contact.shear_sign_change`; where there is none, the middle of the
    contact and no grading), the scale the width of the shear layer there."""
    wheel, theta0 = contact.wheel, contact.entry_angle
    split, has_root = contact.shear_sign_change(theta_r, slip, not _is_front(distribution))
    split = jax.lax.stop_gradient(jnp.where(has_root, split, 0.5 * (theta_r + theta0)))
    theta_eff = distribution.stress_angle(split, theta0, slip)
    z_split = _rim_sinkage_between(theta_eff, theta0, wheel.diameter)
    k_split = terrain.rim_properties(z_split, type(wheel).contact_width(wheel, z_split))[3]
    slope = contact.shear_slope(split, slip)
    return split, jnp.where(has_root, _layer_width(k_split, wheel.diameter / 2, slope), jnp.inf)


def general_contact(
    contact, slip, terrain, distribution, law, n, running, braking=True, vertical_only=False,
    terms=(),
):  # fmt: skip
    """(W, R, T, M, F_y, M_z) of one wheel's `contact` (`AbstractContact`, scalar inputs)
    on any terrain; W alone if `vertical_only`.

    `distribution` is an `AbstractStressDistribution` (`FrontRegion`: 0..theta0;
    `WongReece`: theta_r..theta0 with the mirrored rear stresses), `law` the shear law
    (`AbstractShearLaw`: its mobilisation and the width of its layer at the entry).
    `braking=False` is valid only for slip >= 0 (no sign change of the shear
    displacement).

    `running` (`running.py`) is `Straight()` or `SlipAngle(beta, lateral)`: under a slip
    angle the shear stress is the combined law, F_y the lateral force [N] and M_z the
    moment about the vertical through the wheel centre [N m], with the sidewall
    bulldozing resistance if `lateral.bulldozing` (F_y = M_z = 0 running straight, unless
    a term of `terms` gives them).

    The stresses and forces are force terms (`terms.py`): the built-in ones of the
    running (`running.terms(law)`) and the model's own `terms` (`AbstractForceTerm`s),
    each given the nodes (`ContactNodes`) and summed.

    The contact gives the geometry at every node (`contact.points`: the normal's
    direction, the length element, the width, the shortening of the shear displacement;
    `contact.moment`: the stresses' moment about the axle) and the ends of its shape's
    pieces (`contact.panel_ends`, e.g. a tyre's flat); the quadrature never asks which
    wheel it has.
    """
    wheel, theta0 = contact.wheel, contact.entry_angle
    surface = jnp.zeros_like(theta0)
    k_surface = terrain.rim_properties(surface, type(wheel).contact_width(wheel, surface))[3]
    entry_scale = running.entry_scale(law, theta0, slip, wheel.diameter, terrain, k_surface)

    def total(at_nodes):  # the terms' sum at the nodes `at_nodes` gives
        nodes = _contact_nodes(contact, slip, terrain, running, *at_nodes)
        summed = _total(running.terms(law) + tuple(terms), nodes)
        return summed.vertical_load if vertical_only else summed.astuple()

    if distribution.mirrors_rear:

        def mirrored(smooth):
            return total(
                _mirrored_nodes(
                    contact, slip, terrain, distribution, law, n, braking, entry_scale, smooth
                )
            )

        smooth = _mirrored_smooth_start(contact, slip, terrain, distribution, law, braking)
        return _one_layout(smooth, mirrored)
    spans = contact.smooth_span(distribution)
    rates = (running.lateral_rate(slip, wheel.diameter, k_surface), k_surface)

    def direct(far):
        return total(
            _direct_nodes(
                contact, slip, terrain, distribution, law, n, braking, entry_scale, spans,
                rates, far,
            )
        )  # fmt: skip

    return _one_layout(_far_front_base(contact, slip, terrain, distribution, law, braking), direct)


def _one_layout(choice, contact_with):
    """`contact_with(choice)` for a static `choice` (a bool); for one per element, one
    layout for the whole batch, vmapped axes included (`_all_in_batch`): `contact_with
    (True)` where every element chose it, else `contact_with(False)` (one `lax.cond`)."""
    if isinstance(choice, bool):
        return contact_with(choice)
    return jax.lax.cond(
        _all_in_batch(choice), lambda: contact_with(True), lambda: contact_with(False)
    )


def _cut_inside(contact, slip, terrain, distribution, law, braking) -> bool:
    """Whether a contact's panels are cut inside (static): at a braked wheel's split, a
    break of its shape (`contact.panel_ends`) or a breakpoint of the law."""
    split = braking and law.mobilises
    return bool(split or contact.panel_ends(distribution, slip) or terrain.breakpoint_sinkages())


def _contact_nodes(contact, slip, terrain, running, theta, weight, geometry, stresses):
    """The `ContactNodes` of nodes theta [rad] with weights, their geometry (sin theta,
    cos theta, `ContactPoints`) and the stresses there (sigma [Pa], c [Pa], tan phi [-],
    K [m])."""
    sin, cos, at = geometry
    sigma, cohesion, tan_phi, modulus = stresses
    theta0, r = contact.entry_angle, contact.wheel.diameter / 2
    return ContactNodes(
        contact=contact,
        terrain=terrain,
        slip=slip,
        tan_slip_angle=running.tan_slip_angle(),
        theta=theta,
        weight=weight,
        sin=sin,
        cos=cos,
        points=at,
        sigma=sigma,
        cohesion=cohesion,
        tan_phi=tan_phi,
        modulus=modulus,
        # The rim's travel from the entry less the ground's (4.10), less what the
        # contact's shape takes from it (a tyre's flat).
        shear_displacement=_shear_displacement(theta, theta0, slip, r, sin, _sin_cos(theta0)[0])
        - r * at.shortening,
    )


def _contact_points(contact, theta):
    """(sin theta, cos theta, the contact's `ContactPoints`) at the nodes' angles theta
    [rad]."""
    sin, cos = _sin_cos(theta)
    return sin, cos, contact.points(theta, sin, cos)


def _direct_nodes(
    contact, slip, terrain, distribution, law, n, braking, entry_scale, spans=(), rates=(),
    far=False,
):  # fmt: skip
    """(theta, weight, (sin theta, cos theta, `ContactPoints`), (sigma, c, tan phi, K)) at
    the nodes of panels cut at the contact's ends theta_r and theta0, the distribution's
    breakpoints, the contact's shape's breaks, a base's lowest point, a braked wheel's
    split and the angles where the contact reaches the terrain's breakpoints (and their
    images in a rear region): the law evaluated at every node's stress angle.

    `spans` (the contact's `smooth_span`: at most one angle theta_s [rad]): [theta_r,
    theta_s] takes n nodes of its own (`_smooth_span_nodes`, its layer's width from
    `rates` = (the running's `lateral_rate` [1/rad], K [m])) and the panels cover
    [theta_s, theta0].  `far` (static): a front region's base lies far from the
    contact's lowest point (`_far_front_base`), which then takes no panel of its own:
    the contact beyond it is one panel graded towards theta0 (`_graded_panel`)."""
    theta0 = contact.entry_angle
    inf = jnp.asarray(jnp.inf, theta0.dtype)
    theta_r = distribution.exit_angle(theta0, slip)
    start = theta_r
    for end in spans:
        start = jnp.clip(end, theta_r, theta0)
    points = [(start, inf), (theta0, entry_scale)]
    points += [(angle, inf) for angle in distribution.breakpoints(theta0, slip)]
    points += [(angle, inf) for angle in contact.panel_ends(distribution, slip)]
    # A law with a base on the front region: the contact's lowest point (the rim's at
    # theta = 0, a tyre's flat's front end) may lie on or next to the base, where the
    # stress rises like ln(clearance + r theta^2 / 2); a short panel there takes it.
    base_end = None if far else _front_base_end(distribution, terrain, contact)
    if base_end is not None:
        points.append((base_end + (theta0 - base_end) * BASE_PANEL, inf))
    split = ()
    if braking and law.mobilises:
        split = (_braking_point(theta_r, slip, contact, terrain, distribution),)
        points += split
    for theta_f in _breakpoint_angles(contact, terrain):
        # Rim angle where the sinkage reaches a breakpoint of the terrain's law (front),
        # and its mirror image in the rear region.
        points.append((theta_f, inf))
        points += [(rear, inf) for rear in distribution.rear_angles(theta_f, theta0, slip)]
    # The front region starts at the axle (a tyre's: the flat's front end), smooth
    # without a base.
    smooth = _is_front(distribution) and (far or not terrain.has_base())
    theta, weight = _panel_nodes(points, start, theta0, entry_scale, n, smooth, base_end)
    for _ in spans:
        lead, lead_weight = _smooth_span_nodes(theta_r, start, slip, contact, law, n, split, rates)
        theta = jnp.concatenate([lead, theta])
        weight = jnp.concatenate([lead_weight, weight])
    geometry = _contact_points(contact, theta)
    # Normal stress: the terrain's law at the depth of the distribution's angle.
    theta_eff = distribution.stress_angle(theta, theta0, slip)
    stresses = _stresses_at(theta, theta_eff, contact, terrain, geometry[2].width)
    return theta, weight, geometry, stresses


def _smooth_span_nodes(lo, hi, slip, contact, law, n, split, rates):
    """Nodes and weights on a contact's `smooth_span` [lo, hi] (a tyre's flat): the normal
    stress is constant and the geometry smooth there, so Gauss–Legendre needs no power
    map at its ends, only the sinh map (`_sinh_offsets`) towards the layer where the
    shear mobilises: at hi, the flat's front end, whose width is K / (r |dj/dtheta|)
    (`contact.shear_slope` in the span's middle: on a flat j grows as i x) or, at a slip
    angle, the width of the combined displacement's rise (`rates` = (the running's
    `lateral_rate` [1/rad], K [m])); and a braked wheel's split on the span (`split`:
    the braking panel end (angle, scale) in a one-tuple, empty in the driving layout),
    where the span is cut in two pieces of n nodes.

    n nodes where the general rule would take two half-panels of n: over 24,000 random
    soft tyres on the front region (every law, straight and at 0.2 rad, a third braked,
    20-30 % flattened) the outputs are within 1.8e-9 of the load of that rule's, which
    n - 4 nodes would have left 2.8e-7 off.
    """
    lateral_rate, modulus = rates
    r = contact.wheel.diameter / 2
    if law.mobilises:
        slope = contact.shear_slope(jax.lax.stop_gradient(0.5 * (lo + hi)), slip)
        rate = jnp.hypot(r * slope / modulus, lateral_rate)
        layer = jax.lax.stop_gradient(1 / jnp.maximum(rate, 1e-12 * r / modulus))
    else:
        layer = jnp.full_like(hi, jnp.inf)
    t, w = _rule(n, hi.dtype)

    def toward(a, b, scale):  # the span [a, b] clustered at b (a > b: at its lower end)
        length = jnp.abs(b - a)
        filled = length > 0
        offset, jac = _sinh_offsets(t, w, jnp.where(filled, length, 1.0), scale, 1e-3)
        x = jnp.where(filled, b - jnp.sign(b - a) * offset, b)
        return x, jnp.where(filled, jac, 0.0)

    if not split:
        return toward(lo, hi, layer)
    ((angle, scale),) = jax.lax.stop_gradient(split)
    cut = jnp.clip(angle, lo, hi)
    on_span = cut < hi
    # Where the split is a sign change on the span, both pieces cluster at it; else the
    # piece that reaches hi clusters there (a split without a sign change, the middle of
    # the contact, has no layer: its scale is inf).
    rooted = on_span & jnp.isfinite(scale)
    first = toward(lo, cut, jnp.where(on_span, scale, layer))
    second = toward(
        jnp.where(rooted, hi, cut), jnp.where(rooted, cut, hi), jnp.where(rooted, scale, layer)
    )
    return jnp.concatenate([first[0], second[0]]), jnp.concatenate([first[1], second[1]])


def _mirrored_nodes(contact, slip, terrain, distribution, law, n, braking, entry_scale, smooth):
    """`_direct_nodes` for a distribution whose rear region [theta_r, theta_m] carries the
    stress of the front region [theta_m, theta0] mirrored linearly (`WongReece`;
    `AbstractStressDistribution.mirrors_rear`): the panels are cut in the stress angle
    theta* in [theta_m, theta0], at theta0 and theta_m and at the stress angles of every
    break of either region (the contact's shape, a braked wheel's split, the terrain's
    breakpoints), and each node theta* stands for two contact points, theta* in front
    and its mirror image theta_r + (theta0 - theta*) (theta_m - theta_r) / (theta0 -
    theta_m) behind, which share the law's stress at theta* (evaluated once: the law
    and the node map cost half as much as with nodes of their own in each region).
    `smooth` (static): the law is smooth at theta_m (`_mirrored_smooth_start`).  Returns
    the front nodes, then the rear ones."""
    theta0 = contact.entry_angle
    inf = jnp.asarray(jnp.inf, theta0.dtype)
    theta_m, theta_r = distribution.rear_region(theta0, slip)
    span = theta0 - theta_m
    # Rear length per unit of stress angle (d theta / d theta* in the rear, in magnitude).
    ratio = (theta_m - theta_r) / jnp.where(span > 0, span, 1.0)

    def star(angle):  # the stress angle of a contact angle: itself in front
        return distribution.stress_angle(angle, theta0, slip)

    points = [(theta_m, inf), (theta0, entry_scale)]
    points += [(star(angle), inf) for angle in contact.panel_ends(distribution, slip)]
    split = braking and law.mobilises
    if split:
        angle, width = _braking_point(theta_r, slip, contact, terrain, distribution)
        # A split behind theta_m: its layer's width in theta*.
        behind = angle < theta_m
        points.append((star(angle), jnp.where(behind, width / jnp.maximum(ratio, 1e-12), width)))
    points += [(theta_f, inf) for theta_f in _breakpoint_angles(contact, terrain)]
    front, weight = _panel_nodes(
        points, theta_m, theta0, entry_scale, n, smooth, smooth_cuts=not split
    )
    rear = theta_r + (theta0 - front) * ratio
    theta = jnp.concatenate([front, rear])
    geometry = _contact_points(contact, theta)
    width_front, width_rear = jnp.split(jnp.broadcast_to(geometry[2].width, theta.shape), 2)
    law_front, strength_front = _law_at(front, front, contact, terrain, width_front)
    _, strength_rear = _law_at(rear, front, contact, terrain, width_rear)
    sigma = contact.normal_stress(
        jnp.concatenate([law_front, law_front]), theta, jnp.concatenate([front, front])
    )
    strength = [
        jnp.concatenate([jnp.broadcast_to(f, front.shape), jnp.broadcast_to(r, rear.shape)])
        for f, r in zip(strength_front, strength_rear)
    ]
    return theta, jnp.concatenate([weight, weight * ratio]), geometry, (sigma, *strength)


# The least theta_m / theta0 at which a mirrored contact on a law with a base takes one
# panel (`_mirrored_smooth_start`).
SMOOTH_SHARE = 0.25


def _mirrored_smooth_start(contact, slip, terrain, distribution, law, braking):
    """Whether a mirrored contact's stresses are smooth at its deepest stress angle theta_m,
    so that one panel graded towards theta0 alone (`_graded_panel`) may cover [theta_m,
    theta0] where it is cut nowhere else (`_panel_nodes`): True (static) on a law without
    a base; on a law with a base (Wong's, whose stress grows like -ln of the clearance
    above it), per element, theta_m >= `SMOOTH_SHARE` theta0 where the panel is not cut
    inside (no braking split, no break of the contact's shape, no breakpoint of the
    law: else False, static).

    Along the panel the clearance above the base is c0 + D sin^2(theta* / 2) (c0 the
    lowest point's), which vanishes only at theta* = +-i 2 asinh(sqrt(c0 / D)): the
    log singularity lies at least theta_m from the panel's lower end, i.e. at least
    theta_m / (theta0 - theta_m) = 1/3 of its length at this share (the Gauss–Legendre
    nodes converge fast), whatever c0.  Measured against adaptive quadrature
    (`tests/reference_terrain.py`) on random driven rims on Wong snow with Wong–Reece,
    entry angles up to 0.99999 of the base's: the one panel's 20 nodes within 9e-9 of
    W, R, T and M at theta_m / theta0 >= 0.3 (the two half-panels' 24: 4.9e-8), 4.5e-8
    at 0.25 (5.7e-8), 2.2e-7 at 0.2 (6.6e-8); 2.3e-6 at 0.1.
    """
    if not terrain.has_base():
        return True
    if _cut_inside(contact, slip, terrain, distribution, law, braking):
        return False
    theta0 = contact.entry_angle
    theta_m = distribution.rear_region(theta0, slip)[0]
    return jax.lax.stop_gradient(theta_m >= SMOOTH_SHARE * theta0)


# The least distance of a front region's base singularity from the contact's lowest
# point, per length of the contact beyond it, at which that contact takes one panel
# (`_far_front_base`, where it is measured).
FAR_BASE = 1 / 2


def _far_front_base(contact, slip, terrain, distribution, law, braking):
    """Whether a front-region contact on a law with a base needs no panel at its lowest
    point (`_direct_nodes`' `far`): False (static) off the front region, without a base
    or where it is not known to be logarithmic (`AbstractTerrain.logarithmic_base`: on
    a law with a pole there, sigma = k z / (1 - z / h), a rim's one panel erred by
    3.3e-7 of the load at this share and 8.7e-6 at a third, where the short panel's
    layout erred by 2.5e-7: 40 random driven rims), or
    where the contact is cut inside (a braking split, a break of its shape, a breakpoint
    of the law); else, per element, whether the base's log singularity lies at least
    `FAR_BASE` of the panel [theta_s, theta0] from its lower end theta_s (the lowest
    point: the axle on a rim, a tyre's flat's front end).

    Beyond theta_s the clearance above the base is c + D [sin^2(theta / 2) - sin^2(theta_s
    / 2)], c the lowest point's, which vanishes at sin^2(theta* / 2) = q = sin^2(theta_s
    / 2) - c / D: at theta* = 2 arcsin(sqrt(q)) in [0, theta_s] where q >= 0, else at
    +-i 2 asinh(sqrt(-q)); the distance |theta_s - theta*|.  Measured against SciPy
    (`tests/reference_tire.py`) on 160 random driven tyres on Wong snow (K 2-30 mm, slips
    0-0.9, p_i 20 kPa-1 MPa, entry angles 0.1-0.995 of the cap): at this share, a half,
    the 146 that take one panel within 4.5e-8 of the load, median 2e-14, the rest (round
    treads next to the base) within 2.9e-7 with the short panel, whose layout
    erred by up to 2.9e-7 over all 160 (median 5e-12); at a third, 6.1e-7 on a round
    tread next to the base that then took one panel.
    """
    if not (_is_front(distribution) and terrain.has_base() and terrain.logarithmic_base()):
        return False
    if _cut_inside(contact, slip, terrain, distribution, law, braking):
        return False
    theta0, diameter = contact.entry_angle, contact.wheel.diameter
    start = jnp.clip(contact.lowest_angle(), 0.0, theta0)
    clearance = jnp.maximum(terrain.depth - contact.lowest_sinkage(), 0.0)
    q = _sin_cos(start / 2)[0] ** 2 - clearance / diameter
    real = 2 * jnp.arcsin(jnp.sqrt(jnp.clip(q, 0.0, 1.0)))
    imaginary = 2 * jnp.arcsinh(jnp.sqrt(jnp.maximum(-q, 0.0)))
    distance = jnp.where(q >= 0, start - real, jnp.sqrt(start**2 + imaginary**2))
    return jax.lax.stop_gradient(distance >= FAR_BASE * (theta0 - start))


def _breakpoint_angles(contact, terrain):
    """The rim angles [rad] where the front of the contact reaches each of the terrain's
    breakpoint sinkages (`AbstractTerrain.breakpoint_sinkages`): cos theta = cos theta0
    + z_b / r (4.5); 0 where the contact does not reach it."""
    theta0, r = contact.entry_angle, contact.wheel.diameter / 2
    cos0 = _sin_cos(theta0)[1]
    return [_safe_arccos(cos0 + z_b / r) for z_b in terrain.breakpoint_sinkages()]


def _deepest_stress_angle(distribution, slip, theta0):
    """The stress angle [rad] nearest the axle at entry angle theta0 [rad]: where the
    law meets the contact's deepest sinkage (0 on the front region, theta_m under
    Wong–Reece), the least of the stress angles at the axle (clipped into the contact)
    and at the distribution's breakpoints."""
    axle = jnp.clip(jnp.zeros_like(theta0), distribution.exit_angle(theta0, slip), theta0)
    points = (axle, *distribution.breakpoints(theta0, slip))
    return functools.reduce(
        jnp.minimum, [jnp.abs(distribution.stress_angle(p, theta0, slip)) for p in points]
    )


class AbstractGeneralRule(AbstractContactRule):
    """The any-terrain quadrature as a rule (abstract: its start is a subclass's):
    `general_contact` at the law's `nodes_any_terrain`."""

    warm_layout: ClassVar[bool] = False

    def law_nodes(self, law) -> tuple:
        """Nodes per half-panel without and with braking: the law's `nodes_any_terrain`."""
        if law.nodes_any_terrain is None:
            raise ValueError(f"the shear law {type(law).__name__} has no any-terrain rule")
        return law.nodes_any_terrain

    def uniform_nodes(self, n: int) -> tuple:
        return (n, n)

    def simulator_nodes(self, law) -> tuple:
        """The law's `nodes_simulator` (its any-terrain count) on every half-panel."""
        type(self).law_nodes(self, law)  # a ValueError for a law without this rule
        n = law.nodes_simulator[1]
        return (n, n)

    def contact(
        self, contact, slip, terrain, distribution, law, n, running, braking, vertical_only,
        terms, bottomed, moving_rule,
    ):  # fmt: skip
        del bottomed, moving_rule  # its nodes move with theta0 by construction
        return general_contact(
            contact, slip, terrain, distribution, law, n, running, braking, vertical_only, terms
        )


def _falling_law_start(vertical, theta_cap, load, slip, wheel, terrain, distribution, braking):
    """(over, target, lower, upper, s0, secant) of a cold start on a law that can fall
    (`start._scan_start`, at the distribution's deepest stress angle and the wheel's
    `start_angles`), for the secant steps of `BracketedSecant`."""
    deepest = functools.partial(_deepest_stress_angle, distribution, slip)
    # A wheel's bends serve the driving layout: a braked wheel's W is no power of theta0
    # between the grid's points either way (a 100 kPa tyre on Bekker's snow with
    # Wong–Reece, slips -0.3 to 0.9: as many Newton steps with the bend, 1.13x the time).
    bends = () if braking else type(wheel).start_angles(wheel, terrain)
    return _scan_start(vertical, theta_cap, load, terrain, wheel.diameter, deepest, bends)


class AnyTerrainRule(AbstractGeneralRule):
    """The any-terrain rule: `general_contact` at the law's `nodes_any_terrain`.  On a
    law whose pressure rises it starts from a power-law model of the law
    (`start._power_law_start`) and solves by secant steps (`BracketedSecant`: W alone at
    each step); on a law that can fall (the shallowest equilibrium is wanted), from W
    at two entry angles, at the wheel's `start_angles` and at the law's breakpoints
    (`start._scan_start`), by the same secant steps inside the bracket it finds."""

    def start(
        self, vertical, theta_cap, load, slip, wheel, terrain, distribution, shear, braking
    ):  # fmt: skip
        del shear
        if terrain.pressure_rises():
            return _power_law_start(theta_cap, load, slip, wheel, terrain, distribution)
        return _falling_law_start(
            vertical, theta_cap, load, slip, wheel, terrain, distribution, braking
        )

    def warm_start(self, vertical, theta_cap, load, slip, guess, wheel, terrain):
        del slip, wheel, terrain
        return *_warm_bracket_start(vertical, theta_cap, load, guess), None
