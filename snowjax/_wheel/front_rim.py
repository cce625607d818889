"""Wong's accelerations: the contact rule of a rigid rim, running straight or at a slip
angle, on the front region of a terrain law that offers closed forms of its rim integrals
(`AbstractTerrain.front_rim_integrals`: `WongSnow`, a `Rut` on it, `LayeredSnow`), as one
rule module (`FrontRimRule`; `FallingFrontRimRule` on a law that can fall at its
breakpoint), and the one place that chooses it (`_contact_rule`); every other
combination takes the any-terrain rule of `general.py` (`AnyTerrainRule`).

Quadrature.  Wong's normal stress `sigma = -p_w ln Z` with `Z = Z0 + 2 a sin^2(theta / 2)`,
`a = D / (2 z_w)`, has a logarithmic singularity at theta = 0 when the wheel bottoms out
(Z0 -> 0), and the shear mobilisation rises from zero at the entry angle over a layer of
width ~ K / (r |1 - (1 - i) cos theta0|), which is steep for small K and large slip.
For a braked wheel the shear displacement changes sign inside the contact, which puts a
kink in the shear stress.  The integrals are therefore computed as

1.  *singularity subtraction*: for every integrand f = sigma h + (smooth), the part
    `sigma (h(0) cos theta + h'(0) sin theta)` is integrated in closed form (the
    terrain's `front_rim_integrals`; h(0), h'(0) from the shear law's `mobilisation`
    at the axle, or at a slip angle its combined law's shares along the rim and the
    axle, `_axle_mobilisation`), which leaves a remainder that vanishes like
    theta^2 ln theta at the singular end;
2.  *graded composite Gauss–Legendre* on four panels split at the sign change of the
    shear displacement (or at theta0 / 2 when there is none; the shear law's
    `braking_panels`): a quadratic map clusters nodes at theta = 0, and sinh maps
    cluster them at the sign change and at the entry angle, with the width of the shear
    layer as their scale.

Node positions are functions of the inputs but carry no gradient (`stop_gradient`): the
exact integrals do not depend on them, so derivatives are those of the quadrature rule
with the nodes held fixed (with `moving_rule`, fixed relative to [0, theta0], which
second derivatives w.r.t. theta0 need; `solve_wheel`'s derivative rule uses it). Their
error is that of the rule applied to the derivative integrands, which live inside the
shear layer and so are larger than the values' error where the layer is thin: measured
against the exact model (SciPy quad + brentq) on random in-range cases, equilibrium
gradients are within 6e-7 relative for the simplified model (whose braking panels end
where |U0| saturates, see `ThesisSimplified.braking_panels`), and within 1.2e-4
relative (d/dK; 1.3e-5 for d/dc, 9e-6 for d/dslip, below 1e-6 for the rest; worst of
161 cases) for classic braking at its default nodes, where the panels are placed by the
linear width of the shear layer (`AbstractShearLaw.braking_panels`).

A law with one kink (a `Rut` on Wong snow, whose reloading line meets the virgin law at
the sinkage d) has a panel end there (`_nodes`: three panels driving, the braking panel
that holds it cut in two), which moves with the kink for derivatives (`_moving`); its closed forms
include the reloading line's share.  Measured against SciPy (quad + brentq on the rut's
law) over 28 random ruts, driven and braked: within 6e-12.  The solver's W
(`vertical_only`) holds every node fixed, the kink's too: its one derivative, the
Newton tangent in theta0, is the same to the quadrature's accuracy (the stress is
continuous at the kink, so the Leibniz terms of the panels that meet there cancel, and
it is 0 at the entry; `tests/test_rut.py`).  A law whose pressure drops at its one
breakpoint (`LayeredSnow`, where the ice breaks) has the same panel end there,
driving the next panel graded towards it (`_nodes`, `jumps`); c, tan phi and K are then
those of each node's layer (`_strength_varies`).

The solver's start on this rule is the closed-form no-shear balance (`_closed_form_start`);
on a law that can fall, the any-terrain rule's scan (`FallingFrontRimRule`).
"""

from __future__ import annotations

import functools
from typing import ClassVar

import jax
import jax.numpy as jnp

from .._terrain.base import AbstractTerrain, _half_angle_arc
from .batchwide import _all_in_batch
from .distribution import _is_front
from .general import (
    AnyTerrainRule,
    _falling_law_start,
    _power_map,
    _rule,
    _sinh_offsets,
    general_contact,
)
from .geometry import _plain_rim, _shear_displacement, _sincos_half, max_sinkage
from .inputs import _magnitude_window
from .rules import AbstractContactRule
from .running import _STRAIGHT
from .start import (
    S_MAX,
    _balance_residual,
    _damped_step,
    _falling_lower_bound_start,
    _newton_s,
    _s_min,
    _surface_stiffness,
    _theta_from_s,
    _warm_start,
)
from .terms import ContactNodes, Resultants, _total

__all__: list[str] = []


def _clearance(entry_angle, diameter, terrain):
    """Height [m] of the lowest rim point above the base, max(depth - z0, 0) (4.15)."""
    return jnp.maximum(terrain.depth - max_sinkage(entry_angle, diameter), 0.0)


def _closed_form_rule(terrain, distribution, wheel) -> bool:
    """Whether the contact takes the closed-form rule: a rigid rim on a law that offers
    closed forms of its rim integrals (`AbstractTerrain.closed_form_rim`: `WongSnow`, a
    `Rut` on it, `LayeredSnow`) on the front region, running straight or at a slip
    angle."""
    # Unbound calls: an equinox bound method costs ~40 us to create (every eager call).
    closed = type(terrain).closed_form_rim(terrain)
    return closed and _is_front(distribution) and _plain_rim(wheel)


def _kinked(terrain) -> bool:
    """Whether a law with closed forms has a kink (static: its class overrides
    `breakpoint_sinkages`; a `Rut`'s reloading line meets the virgin law at d)."""
    return type(terrain).breakpoint_sinkages is not AbstractTerrain.breakpoint_sinkages


def _kink_scale(kink, diameter, terrain):
    """The angle [rad] over which the stress changes its slope on the shallow side of a
    law's one breakpoint z_b, at rim angle `kink`: the sinkage scale zeta = |sigma' /
    sigma''| of the law just above z_b (z_w Z_f for a Wong layer whose Z falls to Z_f
    there: the distance to its asymptote) carried onto the rim, r sin(kink) delta + r
    delta^2 / 2 = zeta."""
    (z_b,) = terrain.breakpoint_sinkages()
    z = z_b * (1 - 16 * jnp.finfo(kink.dtype).eps)
    one = jnp.ones_like(z)

    def slope(z):
        return jax.jvp(lambda z: terrain.pressure(z, None), (z,), (one,))[1]

    first, second = jax.jvp(slope, (z,), (one,))
    zeta = jnp.abs(first / jnp.where(second != 0, second, jnp.finfo(kink.dtype).tiny))
    ratio = 2 * zeta / (diameter / 2)
    sin = jnp.sin(kink)
    return ratio / (sin + jnp.sqrt(sin**2 + ratio))


def _strength_varies(terrain) -> bool:
    """Whether a law's c, tan phi and K may change with the sinkage (static): whether its
    class overrides `rim_properties` (`LayeredSnow`; a `Rut`, which takes its virgin
    law's).  The closed-form rule then takes them at each node's sinkage."""
    return type(terrain).rim_properties is not AbstractTerrain.rim_properties


def _kink_angle(theta0, diameter, terrain):
    """theta_d [rad]: where the rim meets a law's one kink, the sinkage d [m] below the
    surface (`breakpoint_sinkages`): sin^2(theta_d / 2) = sin^2(theta0 / 2) - d / D,
    0 where the contact stays above d (4.5 in half angles)."""
    (d,) = terrain.breakpoint_sinkages()
    return _half_angle_arc(jnp.sin(theta0 / 2) ** 2 - d / diameter)


def _sinh_panel(t, w, lo, hi, scale, toward_hi):
    """GL nodes t in [0, 1] with weights w mapped onto [lo, hi] by the sinh map
    (`_sinh_offsets`), clustered at hi (`toward_hi`) or lo with the given scale."""
    offset, jac = _sinh_offsets(t, w, hi - lo, scale, 1e-4)
    return jnp.where(toward_hi, hi - offset, lo + offset), jac


def _graded_or_empty(t, w, lo, hi, scale, stand_in):
    """`_sinh_panel` on [lo, hi] clustered at hi; an empty panel (lo = hi) puts its nodes
    at hi with zero weights (mapped from [`stand_in`, hi], any shorter start)."""
    filled = hi > lo
    x, jac = _sinh_panel(t, w, jnp.where(filled, lo, stand_in), hi, scale, True)
    return jnp.where(filled, x, hi), jnp.where(filled, jac, 0.0)


def _nodes(
    theta0, slip, diameter, terrain, law, z0_rel, n, scales, braking=True, kinks=(), jumps=False
):  # fmt: skip
    """Graded composite Gauss–Legendre nodes and weights on [0, theta0] (no gradient), and
    their pieces for `_moving` (none without a kink).

    `braking=False` (valid when slip >= 0, where the shear stress has one sign): two
    panels of n nodes, [0, theta0/2] with a quadratic map clustering nodes at the log
    singularity theta = 0 and [theta0/2, theta0] with a sinh map clustering them in the
    shear layer behind the entry angle (`scales` = (entry_scale [rad], its width: the
    running's `entry_scale`; lateral_rate [1/rad]: the running's `lateral_rate`)).
    `braking=True`: four panels
    split at the sign change of the shear stress (or at theta0 / 2 when there is none),
    with sinh maps clustering nodes on both sides of it (`law.braking_panels`); `n` is
    then one count per panel, axle to entry (`AbstractShearLaw.nodes`).

    With `kinks` holding one angle (a law's kink, `_kink_angle`) the kink is a panel
    end: driving, three panels, [0, m] quadratic, [m, M] and [M, theta0] sinh, m and M
    the kink and theta0 / 2 in order; braking, the one panel that holds the kink is cut
    where its map reaches it, and both parts keep the map (GL on [0, tau] and [tau, 1]
    of its variable): the four panels' nodes on [0, tau] (on all of a panel that does
    not hold the kink) and one more set on [tau, 1] of the panel that does, with the
    most nodes of a panel (zero weights where none does; under vmap each element's own
    panel).  Each piece is (nodes, lo, hi, lo at the kink, hi at the kink).  `jumps`
    (static; a law whose pressure drops at the kink): driving, three panels, [0, kink]
    quadratic, [kink, m] sinh towards the kink at `_kink_scale`, [m, theta0] sinh
    towards the entry, m midway between the kink and theta0.
    """
    theta0, slip, diameter, terrain, z0_rel, kinks, scales = jax.lax.stop_gradient(
        (theta0, slip, diameter, terrain, z0_rel, kinks, scales)
    )
    entry_scale, lateral_rate = scales
    zero = jnp.zeros_like(theta0)
    if not braking:
        t, w = _rule(n, theta0.dtype)
        half = theta0 / 2
        u, du = _power_map(t, w, 2)
        if not kinks:
            x2, w2 = _sinh_panel(t, w, half, theta0, entry_scale, True)
            return jnp.concatenate([half * u, x2]), jnp.concatenate([half * du, w2]), ()
        (kink,) = kinks
        no, yes = jnp.zeros_like(theta0, bool), jnp.ones_like(theta0, bool)
        if jumps:
            # A law that drops at its breakpoint (`LayeredSnow`): its stress is largest,
            # and steepest, on the kink's shallow side, where the law before the drop
            # may near its own asymptote.  Three panels: the axle's to the kink, one
            # graded towards the kink at that law's own scale there (`_kink_scale`),
            # one towards the entry.
            mid = 0.5 * (kink + theta0)
            scale = _kink_scale(kink, diameter, terrain)
            x2, w2 = _sinh_panel(t, w, kink, mid, scale, False)
            x3, w3 = _sinh_panel(t, w, mid, theta0, entry_scale, True)
            pieces = ((n, zero, kink, no, yes), (n, kink, mid, yes, no), (n, mid, theta0, no, no))
            x, jac = [kink * u, x2, x3], [kink * du, w2, w3]
            return jnp.concatenate(x), jnp.concatenate(jac), pieces
        low, high = jnp.minimum(kink, half), jnp.maximum(kink, half)
        # The middle panel clusters towards its upper end at the entry layer's width plus
        # its distance from the entry: towards a kink next to the entry (the layer's
        # tail), nearly uniform below theta0 / 2.  A kink at the entry (a rut of zero
        # depth) leaves the last panel empty and the others those of the two-panel rule.
        x2, w2 = _graded_or_empty(t, w, low, high, entry_scale + (theta0 - high), 0.0)
        x3, w3 = _graded_or_empty(t, w, high, theta0, entry_scale, half)
        at_low = kink <= half
        pieces = (
            (n, zero, low, no, at_low), (n, low, high, at_low, ~at_low),
            (n, high, theta0, ~at_low, no),
        )  # fmt: skip
        return jnp.concatenate([low * u, x2, x3]), jnp.concatenate([low * du, w2, w3]), pieces
    b1, split, b3, scale2, scale3, scale4 = law.braking_panels(
        theta0, slip, diameter, terrain, z0_rel, entry_scale, lateral_rate
    )
    # Panel 1: [0, b1], quadratic map clustering at the log singularity theta = 0;
    # panels 2-4 (sinh maps): towards the split from below and above, and towards the
    # entry angle.  (One call per panel: a stacked (3, n) map costs XLA:CPU twice as
    # much under vmap.)
    (t1, w1), *rules = [_rule(m, theta0.dtype) for m in n]
    if not kinks:
        u1, du1 = _power_map(t1, w1, 2)
        x2, j2 = _sinh_panel(*rules[0], b1, split, scale2, True)
        x3, j3 = _sinh_panel(*rules[1], split, b3, scale3, False)
        x4, j4 = _sinh_panel(*rules[2], b3, theta0, scale4, True)
        nodes = jnp.concatenate([b1 * u1, x2, x3, x4])
        return nodes, jnp.concatenate([b1 * du1, j2, j3, j4]), ()
    (kink,) = kinks
    panels = [  # (t, w, lo, hi, scale, toward_hi, quadratic), axle to entry
        (t1, w1, zero, b1, zero, False, True),
        (*rules[0], b1, split, scale2, True, False),
        (*rules[1], split, b3, scale3, False, False),
        (*rules[2], b3, theta0, scale4, True, False),
    ]
    cuts = [_cut(lo, hi, scale, toward, q, kink) for _, _, lo, hi, scale, toward, q in panels]
    # Each panel's nodes on [0, tau] of its variable (all of it where the kink is not
    # inside) ...
    xs, ws, pieces = [], [], ()
    no = jnp.zeros_like(theta0, bool)
    for (t, w, lo, hi, scale, toward, q), (tau, inside, length, cut) in zip(panels, cuts):
        a = jnp.where(inside, tau, 1.0)
        x, jac = _panel_map(a * t, a * w, lo, length, scale, toward, q)
        near, far = (hi, lo) if toward else (lo, hi)
        xs.append(jnp.where(hi > lo, x, lo))
        ws.append(jnp.where(hi > lo, jac, 0.0))
        pieces += ((t.shape[0], near, jnp.where(inside, cut, far), no, inside),)
    # ... and the rest, [tau, 1], of the one panel that holds the kink, on its map (GL
    # of the most nodes of a panel; zero weights where no panel holds the kink).
    t_rest, w_rest = _rule(max(n), theta0.dtype)
    held = [inside for _, inside, _, _ in cuts]
    pick = lambda values: jnp.select(held, values, values[-1])  # noqa: E731
    lo, length, scale, tau, cut = (
        pick([p[2] for p in panels]), pick([c[2] for c in cuts]),
        pick([p[4] for p in panels]), pick([c[0] for c in cuts]), pick([c[3] for c in cuts]),
    )  # fmt: skip
    toward = pick([jnp.asarray(p[5]) for p in panels])
    any_held = functools.reduce(jnp.logical_or, held)
    tau = jnp.where(any_held, tau, 1.0)
    t_b, w_b = tau + (1 - tau) * t_rest, (1 - tau) * w_rest
    x_sinh, jac_sinh = _panel_map(t_b, w_b, lo, length, scale, toward, False)
    x_quad, jac_quad = _panel_map(t_b, w_b, lo, length, scale, toward, True)
    x_b = jnp.where(held[0], x_quad, x_sinh)
    jac_b = jnp.where(held[0], jac_quad, jac_sinh)
    far = jnp.where(toward, lo, lo + length)
    pieces += ((t_rest.shape[0], cut, jnp.where(any_held, far, cut), any_held, no),)
    nodes = jnp.concatenate([*xs, jnp.where(any_held, x_b, cut)])
    return nodes, jnp.concatenate([*ws, jnp.where(any_held, jac_b, 0.0)]), pieces


def _panel_map(t, w, lo, length, scale, toward_hi, quadratic):
    """Points t in [0, 1] with weights w on a braking panel [lo, lo + length]: the
    quadratic map from lo (`quadratic`, static) or the sinh map towards hi (`toward_hi`)
    or lo at `scale`; (nodes, weights)."""
    if quadratic:  # x = lo + length t^2
        u, du = _power_map(t, w, 2)
        return lo + length * u, length * du
    return _sinh_panel(t, w, lo, lo + length, scale, toward_hi)


def _cut(lo, hi, scale, toward_hi, quadratic, kink):
    """Where a braking panel's map reaches `kink`: (tau in [0, 1] of its variable,
    whether the kink is inside the panel, its length (1 for an empty panel: a rut
    pressed to the base has no contact), the kink clipped into [lo, hi])."""
    cut = jnp.clip(kink, lo, hi)
    inside = (kink > lo) & (kink < hi)
    length = jnp.where(hi > lo, hi - lo, 1.0)
    if quadratic:
        tau = jnp.sqrt((cut - lo) / length)
    else:  # x = hi -+ s sinh(mu t) (`_sinh_offsets`)
        s = jnp.clip(scale, 1e-4 * length, 10 * length)
        offset = jnp.where(toward_hi, hi - cut, cut - lo)
        tau = jnp.arcsinh(offset / s) / jnp.arcsinh(length / s)
    return jnp.clip(tau, 0.0, 1.0), inside, length, cut


def _moving(theta, weight, theta0, kinks, pieces, moving_rule):
    """The nodes and weights of `_nodes` (values unchanged) moving with their panels' ends:
    with `moving_rule`, scaled with theta0; with a kink (`pieces`), each piece
    stretched from its ends without derivatives to its ends with them, the kink's always
    (a derivative that moves it, e.g. w.r.t. a rut's depth, then carries the jump of the
    integrand's slope there at second order, as the any-terrain rule's breakpoints do)
    and the others scaled with theta0 with `moving_rule`."""
    if moving_rule:
        stretch = theta0 / jax.lax.stop_gradient(theta0)
    else:
        stretch = jnp.ones_like(theta0)
    if not pieces:
        return (theta * stretch, weight * stretch) if moving_rule else (theta, weight)
    (kink,) = kinks
    xs, ws, k = [], [], 0
    for size, lo, hi, lo_kink, hi_kink in pieces:
        lo_live = jnp.where(lo_kink, kink, lo * stretch)
        hi_live = jnp.where(hi_kink, kink, hi * stretch)
        span = hi - lo
        scale = (hi_live - lo_live) / jnp.where(span != 0, span, 1.0)
        xs.append(lo_live + (theta[k : k + size] - lo) * scale)
        ws.append(weight[k : k + size] * jnp.abs(scale))
        k += size
    return jnp.concatenate(xs), jnp.concatenate(ws)


def _axle_mobilisation(contact, slip, terrain, law, clearance, stresses, tan_beta, modulus):
    """((g_x, g_y) [-], (dg_x/dtheta, dg_y/dtheta) [1/rad]) at theta = 0, for the
    closed-form rule's singularity subtraction (K = `modulus` [m], the law's at the
    axle's sinkage): the `stresses` term's shares of the
    strength along the contact and the axle (`TerrainStresses.shares`: running straight,
    the law's `mobilisation` and g_y = 0; at a slip angle of tangent `tan_beta`, its
    combined law) and their derivatives along the rim through the shear displacements
    (4.10: dj/dtheta = -r i at the axle; j_y = r (1 - i)(theta0 - theta) tan beta).  The
    normal stress is held at its axle value, sigma(0) (dsigma/dtheta = 0 there by
    symmetry), taken 1e-30 z_w above the base where the rim rests on it (finite for a
    law that diverges there)."""
    theta0, diameter = contact.entry_angle, contact.wheel.diameter
    zero = jnp.zeros_like(theta0)
    if not law.mobilises:
        return (zero, zero), (zero, zero)
    sigma0 = terrain.pressure_at_clearance(
        jnp.maximum(clearance, 1e-30 * terrain.depth), contact.wheel.width
    )
    r = diameter / 2

    def along_rim(theta):
        j = _shear_displacement(theta, theta0, slip, r, jnp.sin(theta), jnp.sin(theta0))
        j_y = r * (1 - slip) * (theta0 - theta) * tan_beta
        return stresses.shares(j, j_y, modulus, sigma0, theta0, slip, diameter, terrain)

    return jax.jvp(along_rim, (zero,), (jnp.ones_like(theta0),))


def _closed_form_contact(
    contact,
    slip,
    terrain,
    law,
    n,
    bottomed=None,
    braking=True,
    vertical_only=False,
    moving_rule=False,
    terms=(),
    running=_STRAIGHT,
):
    """(W, R, T, M, F_y, M_z) of a rim's `contact` (scalar inputs), or W alone with
    `vertical_only`, by the closed-form rule (a law with `front_rim_integrals` on the
    front region), running straight or at a slip angle (`running`, `running.py`: its
    stresses term gives the shear and lateral stresses at the nodes); the running's
    other built-in terms and the model's own force `terms` are summed on the rule's
    nodes.

    `moving_rule=True` moves the quadrature rule with theta0 for derivatives (values are
    unchanged): needed for second derivatives w.r.t. theta0, whose Leibniz term the
    fixed nodes drop (the first derivative's term vanishes: the stresses are 0 at the
    entry), and slower, so only `solve_wheel`'s derivative rule asks for it.

    `bottomed` puts the lowest rim point on the base structurally (clearance 0);
    `braking=False` selects the two-panel rule, valid for slip >= 0 only (see `_nodes`).
    """
    theta0 = contact.entry_angle
    diameter, width = contact.wheel.diameter, contact.wheel.width
    r = diameter / 2
    clearance = _clearance(theta0, diameter, terrain)
    if bottomed is not None:
        clearance = jnp.where(bottomed, 0.0, clearance)
    z0_rel = clearance / terrain.depth
    kinks = ()
    if _kinked(terrain):
        kinks = (_kink_angle(theta0, diameter, terrain),)
        # A rut's layer may have no depth (pressed to the base): no contact, theta0 = 0,
        # every node on the base, where the stress is taken at the least positive
        # clearance.
        layer = terrain.depth > 0
        z0_rel = jnp.where(layer, clearance / jnp.where(layer, terrain.depth, 1.0), 0.0)
    modulus = terrain.shear_modulus
    scales = (
        running.entry_scale(law, theta0, slip, diameter, terrain, modulus),
        running.lateral_rate(slip, diameter, modulus),
    )
    theta, weight, pieces = _nodes(
        theta0, slip, diameter, terrain, law, z0_rel, n, scales, braking, kinks,
        not terrain.pressure_rises(),
    )  # fmt: skip
    # With `moving_rule` the rule moves with theta0 (a factor 1 in value), so that
    # derivatives w.r.t. theta0 of every order are those of the rule on [0, theta0]; a
    # kink's panels move with it, except in the solver's W (module docstring: a law
    # whose stress is continuous at the kink).
    if not (vertical_only and terrain.pressure_rises()):
        theta, weight = _moving(theta, weight, theta0, kinks, pieces, moving_rule)

    half_sin, half_cos = _sincos_half(theta)
    sin = 2 * half_sin * half_cos
    cos = 1 - 2 * half_sin**2
    height = clearance + diameter * half_sin**2
    if kinks:  # (a rut's layer of no depth)
        height = jnp.maximum(height, jnp.finfo(height.dtype).tiny)
    sigma = terrain.pressure_at_clearance(height, width)
    # The strength acting at each node's sinkage (a layered law's changes with depth).
    cohesion, tan_phi, node_modulus = terrain.cohesion, terrain.tan_phi, modulus
    if _strength_varies(terrain):
        _, cohesion, tan_phi, node_modulus = terrain.rim_properties(terrain.depth - height, width)
    j = _shear_displacement(theta, theta0, slip, r, sin, jnp.sin(theta0))
    nodes = ContactNodes(
        contact, terrain, slip, running.tan_slip_angle(), theta, weight, sin, cos,
        contact.points(theta, sin, cos), sigma, cohesion, tan_phi, node_modulus, j,
    )  # fmt: skip
    # The running's stresses term (the rule integrates it itself, below); its other
    # built-in terms and the model's own are summed on the nodes.
    stresses, *built_in = running.terms(law)
    _, tau, tau_y = stresses.stresses(nodes)
    tau = jnp.broadcast_to(tau, sigma.shape)
    extra = _total(tuple(built_in) + tuple(terms), nodes)

    # Singularity subtraction: every integrand is f = sigma h + smooth, h = cos theta,
    # sin theta or tan phi g (cos theta); remove sigma (h(0) cos + h'(0) sin), whose
    # integral is known in closed form, leaving a remainder that vanishes like
    # theta^2 ln theta at the singular end.
    lowest = jnp.maximum(clearance, jnp.finfo(clearance.dtype).tiny) if kinks else clearance
    # The strength at the axle: the subtracted part's (a layered law's deepest layer).
    tp, axle_modulus = terrain.tan_phi, modulus
    if _strength_varies(terrain):
        _, _, tp, axle_modulus = terrain.rim_properties(terrain.depth - lowest, width)
    (g0, gy0), (g1, gy1) = _axle_mobilisation(
        contact, slip, terrain, law, lowest, stresses, running.tan_slip_angle(), axle_modulus
    )
    # Blend weight: 1 near bottoming (where it is needed), ~4 (z0/z_w)^2 for shallow
    # sinkage, where the closed forms lose digits to cancellation.
    blend = (1 - z0_rel**2) ** 2
    c_cos, c_sin = terrain.front_rim_integrals(theta0, diameter, clearance)
    sig_cos, sig_sin = sigma * cos, sigma * sin
    rb = r * width

    def integral(f, h0, h1):
        quad = jnp.sum((f - blend * (h0 * sig_cos + h1 * sig_sin)) * weight)
        return quad + blend * (h0 * c_cos + h1 * c_sin)

    w_int = integral(sig_cos + tau * sin, 1.0, tp * g0)
    if vertical_only:
        return w_int * rb + extra.vertical_load
    r_int = integral(sig_sin, 0.0, 1.0)
    t_int = integral(tau * cos, tp * g0, tp * g1)
    m_int = integral(tau, tp * g0, tp * g1)
    zero = jnp.zeros_like(theta0)
    lateral = zero, zero
    if stresses.combined:  # tau_y = (c + sigma tan phi) g_y; M_z's arm r sin theta
        fy_int = integral(tau_y, tp * gy0, tp * gy1)
        mz_int = integral(tau_y * sin, 0.0, tp * gy0)
        lateral = fy_int * rb, mz_int * rb * r
    own = Resultants(w_int * rb, r_int * rb, t_int * rb, m_int * rb * r, *lateral)
    return (own + extra).astuple()


def _no_shear_load(theta0, diameter, width, terrain):
    """W without shear stress on the front region, in closed form [N]:
    r b int_0^theta0 sigma cos(theta) dtheta (`AbstractTerrain.front_rim_integrals`)."""
    clearance = _clearance(theta0, diameter, terrain)
    return diameter / 2 * width * terrain.front_rim_integrals(theta0, diameter, clearance)[0]


def _initial_guess(theta_cap, load, diameter, width, terrain, stiffness):
    """Solver start s0 from the no-shear load balance, using its closed form, and the
    balance's derivative d ln(W_no_shear) / ds there (`_newton_s`).

    Starting from the small-angle law W ~ r b (r k) theta0^3 / 3, k = `stiffness`
    (`_surface_stiffness`), two Newton steps on `ln(W_no_shear(theta0) / F_z)`
    (`_no_shear_load`) refine the guess; the shear stress adds to W for a driven wheel,
    so the true theta0 is a little lower.  (A third step, which this start once took,
    left the start's error after the shear correction at the same worst case: on the
    thesis tyre, 1-9 kN, slips -0.5 to 0.9, 600 random cases each of Wong snow, ruts
    0-15 cm and slip angles 0-0.3 rad, within 4.2e-3 of the root either way, median
    1.3e-3 against 1e-3, and the solver's Newton steps unchanged.)
    """
    r = diameter / 2
    theta = jnp.cbrt(3 * load / (r * width * r * stiffness))
    s_min = _s_min(theta.dtype)
    s = jnp.sqrt(jnp.maximum(-jnp.log(jnp.minimum(theta / theta_cap, 1.0)), s_min**2))

    def residual(s):
        w = _no_shear_load(_theta_from_s(s, theta_cap), diameter, width, terrain)
        return _balance_residual(w, load)

    return jax.lax.stop_gradient(_newton_s(residual, jnp.clip(s, s_min, S_MAX), 2))


def _closed_form_bracket(vertical, theta_cap, load, slip, wheel, snow):
    """(over, target, lower, upper) from the closed-form no-shear load (a terrain with
    `front_rim_integrals` on the front region), for either start.

    The capacity of the layer is W at s_min.  For slip >= 0 the shear stress only adds to
    W, so loads below the closed-form no-shear capacity are known to be carried and the
    quadrature is only needed if some element brakes or is heavier than that (a
    `lax.cond` that costs nothing when not needed).
    """
    s_min = jnp.full_like(load, _s_min(load.dtype))
    theta_top = _theta_from_s(s_min, theta_cap)
    no_shear_capacity = _no_shear_load(theta_top, wheel.diameter, wheel.width, snow)
    surely_carried = (no_shear_capacity > load * (1 + 1e-6)) & (slip >= 0)
    capacity = jax.lax.cond(
        _all_in_batch(jax.lax.stop_gradient(surely_carried)),
        lambda: jnp.full_like(load, jnp.inf),
        lambda: vertical(theta_top),
    )
    over = load >= capacity
    # Elements that cannot be balanced are solved for half their capacity (any solvable
    # target would do) so that the batch's Newton iteration terminates quickly.
    target = jnp.where(over, 0.5 * capacity, load)
    return over, target, s_min, jnp.full_like(load, S_MAX)


def _closed_form_start(vertical, theta_cap, load, slip, wheel, snow, shear):
    """(over, target, lower, upper, s0) of a cold start (`_closed_form_bracket`): the
    closed-form no-shear balance, corrected once by the shear stress's share of W (one
    quadrature at the no-shear guess gives the factor W / W_no_shear; one Newton step
    of the closed-form balance, with the slope of its last iteration, moves the guess to
    load / factor: the guess's error falls from ~4 % to ~0.3 %, one Newton step fewer).

    The step replaced a second solve of the closed form for load / factor (three more
    Newton iterations of it): on the thesis tyre, 1-9 kN, slips 0-0.9, 4,000 random
    cases, the start's entry angle is within 3.5e-3 of the root (median 1e-3; the
    re-solve: 5.2e-3, 1.7e-3) and the solver's Newton steps are unchanged (2); on ruts
    2-12 cm deep, 2.6e-3 (2.3e-3) (measured with the no-shear solve's third Newton step,
    since dropped: `_initial_guess`).  `benchmarks/compare.py`, two rounds: batches of
    1,000-100,000 on Wong snow 0.92-0.93x the time, at a slip angle of 0.1 rad 0.83x,
    in a rut 0.80x."""
    diameter, width = wheel.diameter, wheel.width
    over, target, lower, upper = _closed_form_bracket(vertical, theta_cap, load, slip, wheel, snow)
    stiffness = _surface_stiffness(snow, width, load)
    s0, slope = _initial_guess(theta_cap, target, diameter, width, snow, stiffness)
    if shear.mobilises:
        theta_g = _theta_from_s(s0, theta_cap)
        w_ns = _no_shear_load(theta_g, diameter, width, snow)
        factor = jnp.clip(vertical(theta_g) / jnp.maximum(w_ns, 1e-30 * target), 0.5, 2.0)
        factor = jax.lax.stop_gradient(factor)
        # The no-shear balance for load / factor: its residual is the one solved (0 at
        # s0) plus ln(factor), so one Newton step with the last slope.
        s0 = jax.lax.stop_gradient(_damped_step(s0, jnp.log(factor), slope))
    return over, target, lower, upper, s0


def _flush_tiny_slip(slip):
    """Slips below the input magnitude window (1.2e-77 in float64, 1.1e-10 in float32) are
    0 in value, keeping the gradient 1: the braking quadrature's layout divides by
    quantities proportional to the slip, which underflow for a float32 slip of 1e-38."""
    small, _ = _magnitude_window(slip.dtype)
    flushed = jnp.where(jnp.abs(slip) < small, 0.0, slip)
    return slip + jax.lax.stop_gradient(flushed - slip)


class FrontRimRule(AbstractContactRule):
    """The closed-form rule (module documentation): graded panels placed by the shear
    law (its `nodes_closed_form`), the log singularity at a bottomed axle subtracted
    with the terrain's closed forms, running straight or at a slip angle; the solver
    starts from the closed-form no-shear balance (`_closed_form_start`) and brackets a
    warm start with the no-shear capacity (`_closed_form_bracket`); both node layouts
    are compiled for a warm-started solve.

    At a slip angle (the thesis tyre on Wong snow at 10 degrees, 1-9 kN, slips 0-0.9,
    batch 1e5, one process, interleaved with the previous rule, the any-terrain
    quadrature with this start): 0.86-1.16x the time of the same batch running straight,
    where the any-terrain quadrature took 2.20-2.44x; braking slips 1.59-1.91x against
    4.70-5.00x, before `SteeredRimRule`'s 16 nodes beside the split, which cost 1.20x
    at batch 1,000 of slips -0.3 to 0.9 (`benchmarks/compare.py`).  Against SciPy over
    600 random cases (`tests/random_cases.py`, slip angles to 60 degrees, a third
    braked): within 6e-9 of the load."""

    warm_layout: ClassVar[bool] = True

    def law_nodes(self, law) -> tuple:
        """Nodes of the two-panel rule and of each panel of the four-panel rule: the
        law's `nodes_closed_form`."""
        return law.nodes_closed_form

    def uniform_nodes(self, n: int) -> tuple:
        return (n, (n,) * 4)

    def simulator_nodes(self, law) -> tuple:
        """The law's `nodes_simulator` (its closed-form count) on every panel."""
        return type(self).uniform_nodes(self, law.nodes_simulator[0])

    def prepare_slip(self, slip):
        return _flush_tiny_slip(slip)

    def start(
        self, vertical, theta_cap, load, slip, wheel, terrain, distribution, shear, braking
    ):  # fmt: skip
        del distribution, braking  # the front region; the closed form serves either layout
        start = _closed_form_start(vertical, theta_cap, load, slip, wheel, terrain, shear)
        return *start, None

    def warm_start(self, vertical, theta_cap, load, slip, guess, wheel, terrain):
        bracket = _closed_form_bracket(vertical, theta_cap, load, slip, wheel, terrain)
        return *bracket, _warm_start(guess, theta_cap), None

    def contact(
        self, contact, slip, terrain, distribution, law, n, running, braking, vertical_only,
        terms, bottomed, moving_rule,
    ):  # fmt: skip
        del distribution  # the front region
        return _closed_form_contact(
            contact, slip, terrain, law, n, bottomed, braking, vertical_only, moving_rule,
            terms, running,
        )  # fmt: skip


class SteeredRimRule(FrontRimRule):
    """`FrontRimRule` at a slip angle (the rover in MJX, its main user).  Its
    warm-started solve compiles both layouts and takes the two-panel one where no
    element of the batch brakes, vmapped axes included (`batchwide._any_in_batch`:
    vmapped over environments, a per-environment choice became a select that runs both,
    so this rule had been compiled with the four-panel layout alone: the rover's four
    wheels at 1,024 environments, driven, took 8.2 us per wheel for their equilibria
    that way, 2.6 us with the two-panel layout and the start's capacity skipped;
    `benchmarks/mjx.py`'s snow forces went from 5.5x the MJX step to 2.2x).

    The four-panel layout's two panels beside a braked wheel's split take at least
    `split_nodes` nodes: the slip angle rounds the kink there over a width that can be
    a few % of the contact (`AbstractShearLaw.braking_panels`).  Measured on the lane
    change of tests/test_planar.py (1.2-1.8 kN, slips -0.12 to -0.04, |beta| 1e-7 to
    0.1 rad log-uniform, 300 cases), d(sinkage, drawbar pull, F_y, M_z) / d(p_w, load,
    slip, beta) against the same rule at 48 nodes per panel, times (p_w, the load, 0.1,
    0.1 rad) over (1 cm, 1 kN, 1 kN, 50 N m): within 6.6e-8 with 16 nodes; 5.8e-7 with
    10; 1.5e-5 with 10 nodes and the straight layer's width at the split."""

    #: Least nodes of each of the two panels beside the split.
    split_nodes: ClassVar[int] = 16

    def law_nodes(self, law) -> tuple:
        """The law's `nodes_closed_form`, with at least `split_nodes` on the two panels
        beside the split."""
        two, (axle, below, above, entry) = law.nodes_closed_form
        least = self.split_nodes
        return two, (axle, max(below, least), max(above, least), entry)


class FallingFrontRimRule(FrontRimRule):
    """The closed-form rule on a law whose pressure can fall at its breakpoint
    (`LayeredSnow`, where the ice breaks), running straight or at a slip angle.

    A batch without braked elements takes three panels (`_nodes`, `jumps`): the axle's
    to the kink (the breakpoint's angle), one graded towards the kink at the scale of
    the law just before its drop (`_kink_scale`: its largest and steepest stress sits
    on the kink's shallow side, next to the top layer's own asymptote where the ice is
    strong), one towards the entry.  Against the any-terrain rule at 40 nodes per
    half-panel, on 600 entry angles of `LayeredSnow.ice_layer_example` with K 2 mm, 1 cm
    and 3 cm (slips 0-0.9): within 3.3e-8 of W and 4.9e-8 in R, T, M (any-terrain
    default 8.6e-7 at K = 2 mm), where `FrontRimRule`'s driving layout, cut at the kink
    and graded towards the entry, erred by 2.4e-5; over 4,000 random crusts (p_f 1-20
    top.p_w, K 2-30 mm, 0.2-3 kN, slips 0-0.9) the equilibrium sinkage within 4.0e-6 of
    that reference (its default: 4.5e-6), where a uniform panel next to the kink erred
    by 2.7e-4.  A layout with braked elements takes the any-terrain rule
    (`general_contact` at the law's `nodes_any_terrain`): the four-panel layout cut at
    the kink erred by 1.1e-6 of W at K = 1 cm.  The cold start of a driven batch comes
    from the law's closed-form no-shear load (`start._falling_lower_bound_start`), a braked
    one's is the any-terrain rule's on such a law (`general._falling_law_start`: W at a
    few entry angles); both then take secant steps towards the shallowest
    equilibrium."""

    def law_nodes(self, law) -> tuple:
        """The law's two-panel `nodes_closed_form` driving, its `nodes_any_terrain`
        braking."""
        return law.nodes_closed_form[0], AnyTerrainRule.law_nodes(_ANY_TERRAIN_RULE, law)[1]

    def uniform_nodes(self, n: int) -> tuple:
        return (n, n)

    def simulator_nodes(self, law) -> tuple:
        """The law's `nodes_simulator`: its closed-form count driving, its any-terrain
        count braking."""
        AnyTerrainRule.law_nodes(_ANY_TERRAIN_RULE, law)  # a ValueError without that rule
        return law.nodes_simulator

    def start(
        self, vertical, theta_cap, load, slip, wheel, terrain, distribution, shear, braking
    ):  # fmt: skip
        if braking:
            return _falling_law_start(
                vertical, theta_cap, load, slip, wheel, terrain, distribution, braking
            )
        no_shear = functools.partial(
            _no_shear_load, diameter=wheel.diameter, width=wheel.width, terrain=terrain
        )
        return _falling_lower_bound_start(
            vertical, no_shear, theta_cap, load, wheel.diameter, terrain, shear.mobilises
        )

    def contact(
        self, contact, slip, terrain, distribution, law, n, running, braking, vertical_only,
        terms, bottomed, moving_rule,
    ):  # fmt: skip
        if braking:
            return general_contact(
                contact, slip, terrain, distribution, law, n, running, braking, vertical_only,
                terms,
            )  # fmt: skip
        return FrontRimRule.contact(
            self, contact, slip, terrain, distribution, law, n, running, braking,
            vertical_only, terms, bottomed, moving_rule,
        )  # fmt: skip


def _contact_rule(terrain, distribution, wheel, running) -> AbstractContactRule:
    """The contact rule of a combination: where the terrain offers closed forms of its
    rim integrals, on the front region of a rigid rim (`_closed_form_rule`),
    `FrontRimRule` running straight and `SteeredRimRule` at a slip angle, or
    `FallingFrontRimRule` either way on a law that can fall; else `AnyTerrainRule`."""
    if _closed_form_rule(terrain, distribution, wheel):
        if not type(terrain).pressure_rises(terrain):  # unbound: see `_closed_form_rule`
            return _FALLING_FRONT_RIM_RULE
        return _FRONT_RIM_RULE if running.straight else _STEERED_RIM_RULE
    return _ANY_TERRAIN_RULE


# One instance of each (no fields): building and hashing a module on every eager call
# (the jit cache hashes its static arguments) cost about 14 us of a 500 us batch-1 solve.
_FRONT_RIM_RULE = FrontRimRule()
_STEERED_RIM_RULE = SteeredRimRule()
_FALLING_FRONT_RIM_RULE = FallingFrontRimRule()
_ANY_TERRAIN_RULE = AnyTerrainRule()
