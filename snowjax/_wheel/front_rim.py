"""Wong's accelerations: the contact rule of a rigid rim running straight on the front
region of a terrain law that offers closed forms of its rim integrals
(`AbstractTerrain.front_rim_integrals`: `WongSnow`, and a `Rut` on it), as one rule module
(`FrontRimRule`), and the one place that chooses it (`_contact_rule`); every other
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
    at the axle, `_axle_mobilisation`), which leaves a remainder that vanishes like
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
the sinkage d) has a panel end there (`_nodes`: three panels driving, each braking panel
cut in two), which moves with the kink for derivatives (`_moving`); its closed forms
include the reloading line's share.  Measured against SciPy (quad + brentq on the rut's
law) over 28 random ruts, driven and braked: within 6e-12.

The solver's start on this rule is the closed-form no-shear balance (`_closed_form_start`).
"""

from __future__ import annotations

from typing import ClassVar

import jax
import jax.numpy as jnp

from .._terrain.base import AbstractTerrain, _half_angle_arc
from .distribution import _is_front
from .general import (
    AbstractGeneralRule,
    AnyTerrainRule,
    _power_map,
    _rule,
    _sinh_offsets,
)
from .geometry import _plain_rim, _shear_displacement, _sincos_half, max_sinkage
from .inputs import _magnitude_window
from .rules import AbstractContactRule
from .start import (
    S_MAX,
    _balance_residual,
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
    `Rut` on it) on the front region (straight running; the caller checks the slip
    angle)."""
    return terrain.closed_form_rim() and _is_front(distribution) and _plain_rim(wheel)


def _kinked(terrain) -> bool:
    """Whether a law with closed forms has a kink (static: its class overrides
    `breakpoint_sinkages`; a `Rut`'s reloading line meets the virgin law at d)."""
    return type(terrain).breakpoint_sinkages is not AbstractTerrain.breakpoint_sinkages


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


def _nodes(theta0, slip, diameter, terrain, law, z0_rel, n, braking=True, kinks=()):
    """Graded composite Gauss–Legendre nodes and weights on [0, theta0] (no gradient), and
    their pieces for `_moving` (none without a kink).

    `braking=False` (valid when slip >= 0, where the shear stress has one sign): two
    panels of n nodes, [0, theta0/2] with a quadratic map clustering nodes at the log
    singularity theta = 0 and [theta0/2, theta0] with a sinh map clustering them in the
    shear layer behind the entry angle (`law.entry_layer`).  `braking=True`: four panels
    split at the sign change of the shear stress (or at theta0 / 2 when there is none),
    with sinh maps clustering nodes on both sides of it (`law.braking_panels`); `n` is
    then one count per panel, axle to entry (`AbstractShearLaw.nodes`).

    With `kinks` holding one angle (a law's kink, `_kink_angle`) the kink is a panel
    end: driving, three panels, [0, m] quadratic, [m, M] and [M, theta0] sinh, m and M
    the kink and theta0 / 2 in order; braking, each of the four panels is cut where its
    map reaches the kink, and both parts keep its nodes' map (GL on [0, tau] and [tau,
    1] of its variable: twice the nodes; the part beyond a panel that does not hold the
    kink is empty).  Each piece is (nodes, lo, hi, lo at the kink, hi at the kink).
    """
    theta0, slip, diameter, terrain, z0_rel, kinks = jax.lax.stop_gradient(
        (theta0, slip, diameter, terrain, z0_rel, kinks)
    )
    entry_scale = law.entry_layer(theta0, slip, diameter, terrain, terrain.shear_modulus)
    zero = jnp.zeros_like(theta0)
    if not braking:
        t, w = _rule(n, theta0.dtype)
        half = theta0 / 2
        u, du = _power_map(t, w, 2)
        if not kinks:
            x2, w2 = _sinh_panel(t, w, half, theta0, entry_scale, True)
            return jnp.concatenate([half * u, x2]), jnp.concatenate([half * du, w2]), ()
        (kink,) = kinks
        low, high = jnp.minimum(kink, half), jnp.maximum(kink, half)
        # The middle panel clusters towards its upper end at the entry layer's width plus
        # its distance from the entry: towards a kink next to the entry (the layer's
        # tail), nearly uniform below theta0 / 2.  A kink at the entry (a rut of zero
        # depth) leaves the last panel empty and the others those of the two-panel rule.
        x2, w2 = _graded_or_empty(t, w, low, high, entry_scale + (theta0 - high), 0.0)
        x3, w3 = _graded_or_empty(t, w, high, theta0, entry_scale, half)
        at_low, no = kink <= half, jnp.zeros_like(theta0, bool)
        pieces = (
            (n, zero, low, no, at_low), (n, low, high, at_low, ~at_low),
            (n, high, theta0, ~at_low, no),
        )  # fmt: skip
        return jnp.concatenate([low * u, x2, x3]), jnp.concatenate([low * du, w2, w3]), pieces
    b1, split, b3, scale2, scale3, scale4 = law.braking_panels(
        theta0, slip, diameter, terrain, z0_rel, entry_scale
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
    parts = [
        _cut_panel(t1, w1, zero, b1, zero, False, kink, quadratic=True),
        _cut_panel(*rules[0], b1, split, scale2, True, kink),
        _cut_panel(*rules[1], split, b3, scale3, False, kink),
        _cut_panel(*rules[2], b3, theta0, scale4, True, kink),
    ]
    nodes = jnp.concatenate([x for x, _, _ in parts])
    return nodes, jnp.concatenate([w for _, w, _ in parts]), sum((q for *_, q in parts), ())


def _cut_panel(t, w, lo, hi, scale, toward_hi, kink, quadratic=False):
    """A braking panel's map (`quadratic` from lo, else sinh towards hi or lo at `scale`)
    on GL nodes of [0, tau] and [tau, 1], tau where it reaches `kink` clipped
    into [lo, hi]; (nodes, weights, its two pieces for `_moving`)."""
    cut = jnp.clip(kink, lo, hi)
    inside = (kink > lo) & (kink < hi)
    # An empty panel (no contact: a rut pressed to the base) is mapped from [lo, lo + 1]
    # and its weights are zero.
    filled = hi > lo
    length = jnp.where(filled, hi - lo, 1.0)
    if quadratic:  # x = lo + length t^2
        tau = jnp.sqrt((cut - lo) / length)
    else:  # x = hi -+ s sinh(mu t) (`_sinh_offsets`)
        s = jnp.clip(scale, 1e-4 * length, 10 * length)
        offset = jnp.where(toward_hi, hi - cut, cut - lo)
        tau = jnp.arcsinh(offset / s) / jnp.arcsinh(length / s)
    tau = jnp.clip(tau, 0.0, 1.0)
    t_cut = jnp.concatenate([tau * t, tau + (1 - tau) * t])
    w_cut = jnp.concatenate([tau * w, (1 - tau) * w])
    if quadratic:
        u, du = _power_map(t_cut, w_cut, 2)
        x, jac = lo + length * u, length * du
    else:
        x, jac = _sinh_panel(t_cut, w_cut, lo, lo + length, scale, toward_hi)
    x, jac = jnp.where(filled, x, lo), jnp.where(filled, jac, 0.0)
    # The first part runs from the map's clustered end to the cut.
    near, far = (hi, lo) if toward_hi else (lo, hi)
    no = jnp.zeros_like(inside)
    m = t.shape[0]
    pieces = ((m, near, cut, no, inside), (m, cut, far, inside, no))
    return x, jac, pieces


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


def _axle_mobilisation(theta0, slip, diameter, width, terrain, law, clearance):
    """(g [-], dg/dtheta [1/rad]) at theta = 0, for the closed-form rule's singularity
    subtraction: the law's `mobilisation` and its derivative along the rim through the
    shear displacement (4.10), dj/dtheta = -r i at the axle.  The normal stress is held
    at its axle value, sigma(0) (dsigma/dtheta = 0 there by symmetry), taken 1e-30 z_w
    above the base where the rim rests on it (finite for a law that diverges there)."""
    if not law.mobilises:
        zero = jnp.zeros_like(theta0)
        return zero, zero
    sigma0 = terrain.pressure_at_clearance(jnp.maximum(clearance, 1e-30 * terrain.depth), width)
    modulus = terrain.shear_modulus

    def along_rim(theta):
        j = _shear_displacement(theta, theta0, slip, diameter / 2, jnp.sin(theta), jnp.sin(theta0))
        return law.mobilisation(j, modulus, sigma0, theta0, slip, diameter, terrain)

    zero = jnp.zeros_like(theta0)
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
):
    """(W, R, T, M, F_y, M_z) of a rim's `contact` (scalar inputs), or W alone with
    `vertical_only`, by the closed-form rule (a law with `front_rim_integrals` on the
    front region); the model's own force `terms` are summed on the rule's nodes.

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
    theta, weight, pieces = _nodes(theta0, slip, diameter, terrain, law, z0_rel, n, braking, kinks)
    # With `moving_rule` the rule moves with theta0 (a factor 1 in value), so that
    # derivatives w.r.t. theta0 of every order are those of the rule on [0, theta0]; a
    # kink's panels move with it.
    theta, weight = _moving(theta, weight, theta0, kinks, pieces, moving_rule)

    half_sin, half_cos = _sincos_half(theta)
    sin = 2 * half_sin * half_cos
    cos = 1 - 2 * half_sin**2
    height = clearance + diameter * half_sin**2
    if kinks:  # (a rut's layer of no depth)
        height = jnp.maximum(height, jnp.finfo(height.dtype).tiny)
    sigma = terrain.pressure_at_clearance(height, width)
    j = _shear_displacement(theta, theta0, slip, r, sin, jnp.sin(theta0))
    if law.mobilises:
        g = law.mobilisation(j, terrain.shear_modulus, sigma, theta0, slip, diameter, terrain)
        tau = (terrain.cohesion + sigma * terrain.tan_phi) * g
    else:
        tau = jnp.zeros_like(sigma)
    extra = Resultants()
    if terms:
        nodes = ContactNodes(
            contact, terrain, slip, 0.0, theta, weight, sin, cos,
            contact.points(theta, sin, cos), sigma, terrain.cohesion, terrain.tan_phi,
            terrain.shear_modulus, j,
        )  # fmt: skip
        extra = _total(terms, nodes)

    # Singularity subtraction: every integrand is f = sigma h + smooth, h = cos theta,
    # sin theta or tan phi g (cos theta); remove sigma (h(0) cos + h'(0) sin), whose
    # integral is known in closed form, leaving a remainder that vanishes like
    # theta^2 ln theta at the singular end.
    lowest = jnp.maximum(clearance, jnp.finfo(clearance.dtype).tiny) if kinks else clearance
    g0, g1 = _axle_mobilisation(theta0, slip, diameter, width, terrain, law, lowest)
    tp = terrain.tan_phi
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
    own = Resultants(w_int * rb, r_int * rb, t_int * rb, m_int * rb * r, zero, zero)
    return (own + extra).astuple()


def _no_shear_load(theta0, diameter, width, terrain):
    """W without shear stress on the front region, in closed form [N]:
    r b int_0^theta0 sigma cos(theta) dtheta (`AbstractTerrain.front_rim_integrals`)."""
    clearance = _clearance(theta0, diameter, terrain)
    return diameter / 2 * width * terrain.front_rim_integrals(theta0, diameter, clearance)[0]


def _initial_guess(theta_cap, load, diameter, width, terrain, stiffness):
    """Solver start s0 from the no-shear load balance, using its closed form.

    Starting from the small-angle law W ~ r b (r k) theta0^3 / 3, k = `stiffness`
    (`_surface_stiffness`), three Newton steps on `ln(W_no_shear(theta0) / F_z)`
    (`_no_shear_load`) refine the guess; the shear stress adds to W for a driven wheel,
    so the true theta0 is a little lower.
    """
    r = diameter / 2
    theta = jnp.cbrt(3 * load / (r * width * r * stiffness))
    s_min = _s_min(theta.dtype)
    s = jnp.sqrt(jnp.maximum(-jnp.log(jnp.minimum(theta / theta_cap, 1.0)), s_min**2))

    def residual(s):
        w = _no_shear_load(_theta_from_s(s, theta_cap), diameter, width, terrain)
        return _balance_residual(w, load)

    return jax.lax.stop_gradient(_newton_s(residual, jnp.clip(s, s_min, S_MAX), 3))


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
        jnp.all(surely_carried), lambda: jnp.full_like(load, jnp.inf), lambda: vertical(theta_top)
    )
    over = load >= capacity
    # Elements that cannot be balanced are solved for half their capacity (any solvable
    # target would do) so that the batch's Newton iteration terminates quickly.
    target = jnp.where(over, 0.5 * capacity, load)
    return over, target, s_min, jnp.full_like(load, S_MAX)


def _closed_form_start(vertical, theta_cap, load, slip, wheel, snow, shear):
    """(over, target, lower, upper, s0) of a cold start (`_closed_form_bracket`): the
    closed-form no-shear balance, corrected once by the shear stress's share of W (one
    quadrature at the no-shear guess gives W / W_no_shear, and the closed form is
    re-solved for load / factor: the guess's error falls from ~4 % to ~0.3 %, one Newton
    step fewer)."""
    diameter, width = wheel.diameter, wheel.width
    over, target, lower, upper = _closed_form_bracket(vertical, theta_cap, load, slip, wheel, snow)
    stiffness = _surface_stiffness(snow, width, load)
    s0 = _initial_guess(theta_cap, target, diameter, width, snow, stiffness)
    if shear.mobilises:
        theta_g = _theta_from_s(s0, theta_cap)
        w_ns = _no_shear_load(theta_g, diameter, width, snow)
        factor = jnp.clip(vertical(theta_g) / jnp.maximum(w_ns, 1e-30 * target), 0.5, 2.0)
        factor = jax.lax.stop_gradient(factor)
        s0 = _initial_guess(theta_cap, target / factor, diameter, width, snow, stiffness)
    return over, target, lower, upper, s0


def _flush_tiny_slip(slip):
    """Slips below the input magnitude window (1.2e-77 in float64, 1.1e-10 in float32) are
    0 in value, keeping the gradient 1: the braking quadrature's layout divides by
    quantities proportional to the slip, which underflow for a float32 slip of 1e-38."""
    small, _ = _magnitude_window(slip.dtype)
    flushed = jnp.where(jnp.abs(slip) < small, 0.0, slip)
    return slip + jax.lax.stop_gradient(flushed - slip)


class AbstractClosedFormStart(AbstractContactRule):
    """A rule that starts the solver from the closed-form no-shear balance of a rigid
    rim on the front region of a terrain that offers closed forms of its rim integrals
    (`_closed_form_start`), and brackets a warm start with its no-shear capacity
    (`_closed_form_bracket`); abstract: its contact integrals are a subclass's."""

    def start(self, vertical, theta_cap, load, slip, wheel, terrain, distribution, shear):
        del distribution  # the front region
        return _closed_form_start(vertical, theta_cap, load, slip, wheel, terrain, shear)

    def warm_start(self, vertical, theta_cap, load, slip, guess, wheel, terrain):
        bracket = _closed_form_bracket(vertical, theta_cap, load, slip, wheel, terrain)
        return *bracket, _warm_start(guess, theta_cap)


class FrontRimRule(AbstractClosedFormStart):
    """The closed-form rule (module documentation): graded panels placed by the shear
    law (its `nodes_closed_form`), the log singularity at a bottomed axle subtracted
    with the terrain's closed forms, the closed-form no-shear start, and both node
    layouts compiled for a warm-started solve."""

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

    def contact(
        self, contact, slip, terrain, distribution, law, n, running, braking, vertical_only,
        terms, bottomed, moving_rule,
    ):  # fmt: skip
        del distribution, running  # the front region, running straight
        return _closed_form_contact(
            contact, slip, terrain, law, n, bottomed, braking, vertical_only, moving_rule, terms
        )


class SteeredRimRule(AbstractClosedFormStart, AbstractGeneralRule):
    """A rigid rim at a slip angle on the front region of a terrain that offers closed
    forms of its rim integrals: the any-terrain rule's quadrature (the combined shear
    law and the lateral stresses have no closed form) with the closed-form rule's start
    and bracket (`_closed_form_start`, `_closed_form_bracket`; a driven wheel's
    longitudinal shear stress only adds to W under a slip angle too, and the start's
    shear factor takes the combined law's share).

    Measured on the thesis tyre on Wong snow at a slip angle of 10 degrees (1-9 kN,
    slips 0-0.9, one process, interleaved): the start's theta0 within 0.5 % of the root
    where the any-terrain start (`_scan_start`) was 17-20 % off, 3 Newton steps of the
    batch instead of 5 (2 with `bracketed._finished`'s predicted stop), and 0.68x the
    time of a solve (0.70x with braking slips); a warm-started solve skips W at the cap
    where every wheel of the batch is driven and surely carried."""


def _contact_rule(terrain, distribution, wheel, running) -> AbstractContactRule:
    """The contact rule of a combination: where the terrain offers closed forms of its
    rim integrals, on the front region of a rigid rim (`_closed_form_rule`),
    `FrontRimRule` running straight (`running.straight`) and `SteeredRimRule` at a slip
    angle; else `AnyTerrainRule`."""
    if _closed_form_rule(terrain, distribution, wheel):
        return _FRONT_RIM_RULE if running.straight else _STEERED_RIM_RULE
    return _ANY_TERRAIN_RULE


# One instance of each (no fields): building and hashing a module on every eager call
# (the jit cache hashes its static arguments) cost about 14 us of a 500 us batch-1 solve.
_FRONT_RIM_RULE = FrontRimRule()
_STEERED_RIM_RULE = SteeredRimRule()
_ANY_TERRAIN_RULE = AnyTerrainRule()
