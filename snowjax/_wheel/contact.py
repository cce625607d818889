"""The contact integrals of a rigid wheel (chapter 4): the one entry to the quadrature
(`_contact_batch`, for the solver and `contact_forces`), the per-point rim stresses, and
the closed-form rule described below, taken on the front region of a terrain law that
offers closed forms of its rim integrals (`AbstractTerrain.front_rim_integrals`:
`WongSnow`); every other combination takes the any-terrain rule of `general.py`.

Notation (thesis, section 4.1): theta is measured from the vertical through the wheel
centre, theta0 is the entry angle, D the diameter, r = D / 2, b the width.

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
"""

from __future__ import annotations

from typing import cast

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from .._leaves import _is_traced
from .._terrain.base import AbstractTerrain
from .distribution import AbstractStressDistribution, _as_distribution, _is_front
from .general import (
    _power_map,
    _rule,
    _sinh_offsets,
    _stresses_at,
    general_contact,
)
from .geometry import (
    AbstractWheel,
    _plain_rim,
    _shear_displacement,
    _sincos_half,
    max_sinkage,
    shear_displacement,
)
from .model import ContactModel, _unpack_model
from .shear_law import AbstractShearLaw, ShearModel, _shear_law
from .terms import ContactNodes, Resultants, _total

# --------------------------------------------------------------------------------------
# Geometry and stresses (pure functions of scalars or broadcastable arrays)
# --------------------------------------------------------------------------------------


def _clearance(entry_angle, diameter, terrain):
    """Height [m] of the lowest rim point above the base, max(depth - z0, 0) (4.15)."""
    return jnp.maximum(terrain.depth - max_sinkage(entry_angle, diameter), 0.0)


def _closed_form_rule(terrain, distribution, wheel) -> bool:
    """Whether the contact takes the closed-form rule: a rigid rim on a law that offers
    closed forms of its rim integrals (`AbstractTerrain.front_rim_integrals`: `WongSnow`)
    on the front region (straight running; the caller checks the slip angle)."""
    offered = type(terrain).front_rim_integrals is not AbstractTerrain.front_rim_integrals
    return offered and _is_front(distribution) and _plain_rim(wheel)


def normal_stress(
    theta: ArrayLike,
    entry_angle: ArrayLike,
    wheel: AbstractWheel,
    snow: AbstractTerrain,
    *,
    slip: ArrayLike = 0.0,
    distribution: AbstractStressDistribution | None = None,
) -> Array:
    """Normal stress on the rim at angle theta: the terrain's pressure–sinkage law at the
    rim sinkage (4.5) of the distribution's stress angle.

    On any terrain and distribution, `sigma = terrain.pressure(z)` with
    `z = r (cos theta* - cos theta0)`, theta* = `distribution.stress_angle(theta, ...)`
    (theta in the front region, the mirrored front angle in Wong–Reece's rear region).
    On the front region of a law with closed forms (`WongSnow`) the law is evaluated at
    the rim point's height above the base, `clearance(theta0) + D sin^2(theta / 2)`
    (eq. 4.1b as `sigma = -p_w ln Z`, `Z = Z0 + (D / z_w) sin^2(theta / 2)`: no
    cancellation near the base).

    **Arguments:** `theta` [rad] (in theta_r..theta0), `entry_angle` theta0 [rad],
    `wheel`, `snow` (any terrain); keywords: `slip` i [-] (where the distribution
    depends on it: Wong–Reece's theta_m), `distribution` (None: the front region).
    **Returns:** sigma [Pa]; `+inf` only at theta = 0 of a wheel resting on a Wong base.
    """
    distribution = _as_distribution(distribution)
    if _closed_form_rule(snow, distribution, wheel):
        height = (
            _clearance(entry_angle, wheel.diameter, snow)
            + wheel.diameter * jnp.sin(jnp.asarray(theta) / 2) ** 2
        )
        return snow.pressure_at_clearance(height, wheel.width)
    contact = type(wheel).contact(wheel, jnp.asarray(entry_angle), snow)
    return _rim_stress_properties(theta, slip, contact, snow, distribution)[0]


def _rim_stress_properties(theta, slip, contact, terrain, distribution):
    """(sigma [Pa], c [Pa], tan phi [-], K [m]) at rim angle theta on any terrain, of a
    wheel's `contact` (`AbstractContact`: a deflecting tyre's flat at its sinkage)."""
    theta0, theta = contact.entry_angle, jnp.asarray(theta)
    stress_angle = distribution.stress_angle(theta, theta0, slip)
    sin, cos = jnp.sin(theta), jnp.cos(theta)
    width = contact.points(theta, sin, cos).width
    return _stresses_at(theta, stress_angle, contact, terrain, width, guard=False)


def shear_stress(
    theta: ArrayLike,
    entry_angle: ArrayLike,
    slip: ArrayLike,
    wheel: AbstractWheel,
    snow: AbstractTerrain,
    shear: ShearModel | AbstractShearLaw = "classic",
    *,
    distribution: AbstractStressDistribution | None = None,
) -> Array:
    """Shear stress on the rim [Pa]: `tau = (c + sigma tan phi) g`, g the shear law's
    mobilisation (`AbstractShearLaw.mobilisation`).

    - `"classic"` (`JanosiHanamoto()`): Janosi–Hanamoto with the rigid-wheel shear
      displacement, eq. (4.11): `g = 1 - exp(-j / K)`, on any terrain and distribution
      (c, tan phi and K those acting at the stress angle's sinkage: `rim_properties`).
    - `"simplified"` (`ThesisSimplified()`): the thesis's model, eq. (4.13) (`WongSnow`,
      front region only): `g = 1 - exp(-U0)`, `sigma_bar = sigma / c`,
      `U0 = (i + tau2) tau1 sigma_bar + (2i - i^2) tau1 sigma_bar^3 / 6`,
      `tau1 = (D / K)(z_w / D)(c / p_w) cot theta0`, `tau2 = 1 / cos theta0 - 1`, with tau1
      and tau2 evaluated at the current entry angle.
    - `"none"` (`NoShear()`): tau = 0.

    For a braked wheel (slip < 0) the shear displacement j (classic) or the exponent U0
    (simplified) can be negative; the mobilisation factor is then mirrored,
    `-[1 - exp(-|j| / K)]`, so the stress is signed and bounded by Mohr–Coulomb.

    **Arguments:** `theta` [rad], `entry_angle` theta0 [rad], `slip` i [-], `wheel`,
    `snow` (any terrain), `shear` (a shear law or its name); keyword `distribution`
    (None: the front region).
    """
    from .inputs import _check_model

    law = _shear_law(shear)
    _check_model(wheel, snow, distribution, law)
    distribution = _as_distribution(distribution)
    contact = type(wheel).contact(wheel, jnp.asarray(entry_angle), snow)
    if _closed_form_rule(snow, distribution, wheel):
        sigma = normal_stress(theta, entry_angle, wheel, snow)
        c, tan_phi, k = snow.cohesion, snow.tan_phi, snow.shear_modulus
    else:
        sigma, c, tan_phi, k = _rim_stress_properties(theta, slip, contact, snow, distribution)
    if not law.mobilises:
        return jnp.zeros_like(sigma)
    theta = jnp.asarray(theta)
    shortening = contact.points(theta, jnp.sin(theta), jnp.cos(theta)).shortening
    j = shear_displacement(theta, entry_angle, slip, wheel.diameter) - wheel.radius * shortening
    g = law.mobilisation(j, k, sigma, entry_angle, slip, wheel.diameter, snow)
    return (c + sigma * tan_phi) * g


# --------------------------------------------------------------------------------------
# Quadrature nodes
# --------------------------------------------------------------------------------------


def _sinh_panel(t, w, lo, hi, scale, toward_hi):
    """GL nodes t in [0, 1] with weights w mapped onto [lo, hi] by the sinh map
    (`_sinh_offsets`), clustered at hi (`toward_hi`) or lo with the given scale."""
    offset, jac = _sinh_offsets(t, w, hi - lo, scale, 1e-4)
    return jnp.where(toward_hi, hi - offset, lo + offset), jac


def _nodes(theta0, slip, diameter, terrain, law, z0_rel, n, braking=True):
    """Graded composite Gauss–Legendre nodes and weights on [0, theta0] (no gradient).

    `braking=False` (valid when slip >= 0, where the shear stress has one sign): two
    panels of n nodes, [0, theta0/2] with a quadratic map clustering nodes at the log
    singularity theta = 0 and [theta0/2, theta0] with a sinh map clustering them in the
    shear layer behind the entry angle (`law.entry_layer`).  `braking=True`: four panels
    split at the sign change of the shear stress (or at theta0 / 2 when there is none),
    with sinh maps clustering nodes on both sides of it (`law.braking_panels`); `n` is
    then one count per panel, axle to entry (`AbstractShearLaw.nodes`).
    """
    theta0, slip, diameter, terrain, z0_rel = jax.lax.stop_gradient(
        (theta0, slip, diameter, terrain, z0_rel)
    )
    entry_scale = law.entry_layer(theta0, slip, diameter, terrain, terrain.shear_modulus)
    if not braking:
        t, w = _rule(n, theta0.dtype)
        half = theta0 / 2
        u, du = _power_map(t, w, 2)
        x2, w2 = _sinh_panel(t, w, half, theta0, entry_scale, True)
        return jnp.concatenate([half * u, x2]), jnp.concatenate([half * du, w2])
    b1, split, b3, scale2, scale3, scale4 = law.braking_panels(
        theta0, slip, diameter, terrain, z0_rel, entry_scale
    )
    # Panel 1: [0, b1], quadratic map clustering at the log singularity theta = 0;
    # panels 2-4 (sinh maps): towards the split from below and above, and towards the
    # entry angle.  (One call per panel: a stacked (3, n) map costs XLA:CPU twice as
    # much under vmap.)
    (t1, w1), *rules = [_rule(m, theta0.dtype) for m in n]
    u1, du1 = _power_map(t1, w1, 2)
    x2, j2 = _sinh_panel(*rules[0], b1, split, scale2, True)
    x3, j3 = _sinh_panel(*rules[1], split, b3, scale3, False)
    x4, j4 = _sinh_panel(*rules[2], b3, theta0, scale4, True)
    return jnp.concatenate([b1 * u1, x2, x3, x4]), jnp.concatenate([b1 * du1, j2, j3, j4])


# --------------------------------------------------------------------------------------
# Contact integrals
# --------------------------------------------------------------------------------------


class ContactForces(eqx.Module):
    """Resultants of the rim stresses for a given entry angle (per unit of nothing: N).

    - `vertical_load`: W, eq. (4.14) / (2.11) [N].
    - `motion_resistance`: R_x, eq. (4.16) [N].
    - `thrust`: horizontal component of the shear stress, eq. (2.9) times r b [N].
    - `drawbar_pull`: thrust - motion resistance, eq. (2.10) [N].
    - `torque`: M_w, eq. (2.12) [N m].
    """

    vertical_load: Float[Array, "..."]
    motion_resistance: Float[Array, "..."]
    thrust: Float[Array, "..."]
    drawbar_pull: Float[Array, "..."]
    torque: Float[Array, "..."]


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
        j = _shear_displacement(theta, theta0, slip, diameter / 2, jnp.sin(theta))
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
    theta, weight = _nodes(theta0, slip, diameter, terrain, law, z0_rel, n, braking)
    if moving_rule:
        # The rule scaled with theta0 (a factor 1 in value): its nodes move with the
        # upper limit, so that derivatives w.r.t. theta0 of every order are those of the
        # rule on [0, theta0].
        stretch = theta0 / jax.lax.stop_gradient(theta0)
        theta, weight = theta * stretch, weight * stretch

    half_sin, half_cos = _sincos_half(theta)
    sin = 2 * half_sin * half_cos
    cos = 1 - 2 * half_sin**2
    sigma = terrain.pressure_at_clearance(clearance + diameter * half_sin**2, width)
    j = _shear_displacement(theta, theta0, slip, r, sin)
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
    g0, g1 = _axle_mobilisation(theta0, slip, diameter, width, terrain, law, clearance)
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


def contact_forces(
    wheel: AbstractWheel,
    snow: AbstractTerrain | ContactModel,
    entry_angle: Float[ArrayLike, "..."],
    slip: Float[ArrayLike, "..."],
    shear: ShearModel | AbstractShearLaw = "classic",
    nodes_per_panel: int | None = None,
    *,
    distribution: AbstractStressDistribution | None = None,
) -> ContactForces:
    """Contact integrals of a rigid wheel on a terrain at a given entry angle.

    Vertical load (4.14), motion resistance (4.16), thrust ((2.9) times r b), drawbar pull
    (2.10) and torque (2.12).  Without a `distribution` they are integrated over the
    front contact 0 <= theta <= theta0 as in the thesis; with `WongReece` over
    theta_r <= theta <= theta0.  All arguments broadcast against each other and against
    the leaves of `wheel`, `snow` and `distribution`.

    **Arguments:**

    - `wheel`: `RigidWheel` or `DeflectingTire`; `snow`: any terrain (`WongSnow`,
      `BekkerSoil`, `ReeceSoil`, `LayeredSnow`), SI, or a `ContactModel` (then leave
      `shear`, `distribution` and `nodes_per_panel` out).
    - `entry_angle`: theta0 [rad], 0 < theta0 <= arccos(1 - 2 depth / D).
    - `slip`: driving slip i [-], eq. (2.6); negative when braking.
    - `shear`: the shear law, `JanosiHanamoto()` / `"classic"` (4.11),
      `ThesisSimplified()` / `"simplified"` (4.13; WongSnow on the front region only) or
      `NoShear()` / `"none"`.
    - `nodes_per_panel`: Gauss–Legendre nodes per panel (defaults as in `solve_wheel`).
    - `distribution`: `FrontRegion()` or None (front region), `WongReece`, or any
      `AbstractStressDistribution`.

    **Returns:** `ContactForces` with fields in N (torque in N m).
    """
    snow, shear, distribution, _, nodes_per_panel, terms = _unpack_model(
        snow, shear, distribution, nodes_per_panel=nodes_per_panel
    )
    law = _shear_law(shear)
    from .inputs import _check_model

    _check_model(wheel, snow, distribution, law)
    distribution = _as_distribution(distribution)
    closed_form = _closed_form_rule(snow, distribution, wheel)
    n = type(law).nodes(law, nodes_per_panel, closed_form)  # unbound: see inputs
    return _contact_forces_jit(
        wheel, snow, distribution, terms, entry_angle, slip, law, n, _layout(slip), closed_form
    )


def _contact_batch(
    theta0,
    slip,
    wheel,
    terrain,
    distribution,
    side,
    terms,
    *,
    shear,
    n,
    braking,
    closed_form,
    bulldozing=False,
    vertical_only=False,
    bottomed=None,
    moving_rule=False,
):
    """Contact integrals of a flat batch (1-D leaves): W alone with `vertical_only`, else
    (W, R, T, M, F_y, M_z) (F_y = M_z = 0 without a slip angle, `side` None, unless a
    term gives them); `terms` the model's own force terms (a tuple, leaves 1-D).

    The one entry to the quadrature, for the solver and `contact_forces`.  `closed_form`
    (a law with closed-form rim integrals, `WongSnow`, on the front region, running
    straight: `_closed_form_rule`) takes the closed-form rule (`_closed_form_contact`:
    graded panels placed by the shear law, the log singularity at a bottomed axle
    subtracted in closed form); every other combination the any-terrain
    rule (`general_contact`: panels cut at the distribution's angles, the terrain's
    breakpoints and the shear law's sign change).  `bottomed` and `moving_rule` concern
    only the former (the latter's nodes move with theta0 by construction).
    """

    def one(th, i, wh, tr, ds, sd, tm, bt):
        contact = type(wh).contact(wh, th, tr)
        if closed_form:
            return _closed_form_contact(
                contact, i, tr, shear, n, bt, braking, vertical_only, moving_rule, tm
            )
        return general_contact(
            contact, i, tr, ds, shear, n, braking, vertical_only, sd, bulldozing, tm
        )

    return jax.vmap(one)(theta0, slip, wheel, terrain, distribution, side, terms, bottomed)


def _layout(slip, warm_start: bool = False) -> str:
    """Quadrature layout: "driving" (two panels) if no slip is < 0, else "braking".

    Traced slips (under `jit`, `vmap`, `grad`) get the general "braking" layout, which is
    valid for every slip, so that only one variant is compiled; with `warm_start` (a
    simulation step, compiled once and run many times) "auto": both are compiled and a
    step in which no wheel brakes takes the two-panel rule (4 wheels warm-started in a
    `lax.scan`: 2.4 us per wheel against 5.0, for 0.9 s more compile).
    """
    if _is_traced(slip):
        return "auto" if warm_start else "braking"
    return "braking" if np.any(np.asarray(slip) < 0) else "driving"


def _with_rule_for(slip, shear, fn, layout="auto"):
    """`fn(braking)` with the two-panel rule when no element of the batch brakes.

    `layout` "driving"/"braking" when known before tracing; "auto" decides once per batch
    at run time (`lax.cond`), so an all-driving batch pays for half the nodes.
    """
    if not shear.mobilises or layout == "driving":
        return fn(False)
    if layout == "braking":
        return fn(True)
    return jax.lax.cond(jnp.any(slip < 0), lambda: fn(True), lambda: fn(False))


def _broadcast_leaves(*trees):
    """Cast every leaf to one floating dtype, broadcast them together and flatten.

    Returns (broadcast shape, dtype, trees with 1-D leaves of the broadcast size).
    """
    leaves = [jnp.asarray(x) for t in trees for x in jax.tree_util.tree_leaves(t)]
    dtype = jnp.result_type(*leaves, float)
    shape = jnp.broadcast_shapes(*(x.shape for x in leaves))
    flat = lambda x: jnp.broadcast_to(jnp.asarray(x, dtype), shape).reshape(-1)  # noqa: E731
    return shape, dtype, [jax.tree_util.tree_map(flat, t) for t in trees]


@eqx.filter_jit
def _contact_forces_jit(
    wheel, terrain, distribution, terms, entry_angle, slip, shear, n, layout, closed_form
):
    shape, _, (wheel, terrain, distribution, terms, theta0, slip) = _broadcast_leaves(
        wheel, terrain, distribution, terms, entry_angle, slip
    )

    def forces(braking):
        return _contact_batch(
            theta0,
            slip,
            wheel,
            terrain,
            distribution,
            None,
            terms,
            shear=shear,
            n=n[braking],
            braking=braking,
            closed_form=closed_form,
        )

    w, r, t, m, _, _ = cast(tuple, _with_rule_for(slip, shear, forces, layout))
    reshape = lambda x: x.reshape(shape)  # noqa: E731
    return ContactForces(
        vertical_load=reshape(w),
        motion_resistance=reshape(r),
        thrust=reshape(t),
        drawbar_pull=reshape(t - r),
        torque=reshape(m),
    )
