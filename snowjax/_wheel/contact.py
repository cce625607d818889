"""The contact integrals of a wheel (chapter 4): the one entry to the quadrature
(`_contact_batch`, for the solver and `contact_forces`), which takes the contact rule it
is given (`rules.py`: the any-terrain rule of `general.py`, or the accelerations of
`front_rim.py` where a terrain offers closed forms of its rim integrals), and the
per-point rim stresses.

Notation (thesis, section 4.1): theta is measured from the vertical through the wheel
centre, theta0 is the entry angle, D the diameter, r = D / 2, b the width.
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
from .batchwide import _any_in_batch
from .distribution import AbstractStressDistribution, _as_distribution
from .front_rim import _clearance, _closed_form_rule, _contact_rule
from .general import (
    _stresses_at,
)
from .geometry import (
    AbstractWheel,
    shear_displacement,
)
from .model import ContactModel, _as_model, _takes_model
from .running import _STRAIGHT
from .shear_law import AbstractShearLaw, ShearModel

# --------------------------------------------------------------------------------------
# Geometry and stresses (pure functions of scalars or broadcastable arrays)
# --------------------------------------------------------------------------------------


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

    if not isinstance(snow, AbstractTerrain):
        raise TypeError(f"snow must be a snowjax terrain, got {type(snow).__name__}")
    model = ContactModel(snow, distribution, shear)  # checks the parts and the combination
    _check_model(wheel, model)
    law, distribution = model.shear, model.distribution
    contact = type(wheel).contact(wheel, jnp.asarray(entry_angle), snow)
    sigma, c, tan_phi, k = _rim_stress_properties(theta, slip, contact, snow, distribution)
    if _closed_form_rule(snow, distribution, wheel):
        sigma = normal_stress(theta, entry_angle, wheel, snow)
    if not law.mobilises:
        return jnp.zeros_like(sigma)
    theta = jnp.asarray(theta)
    shortening = contact.points(theta, jnp.sin(theta), jnp.cos(theta)).shortening
    j = shear_displacement(theta, entry_angle, slip, wheel.diameter) - wheel.radius * shortening
    g = law.mobilisation(j, k, sigma, entry_angle, slip, wheel.diameter, snow)
    return (c + sigma * tan_phi) * g


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


@_takes_model(positional=4)
def contact_forces(
    wheel: AbstractWheel,
    snow: AbstractTerrain | ContactModel,
    entry_angle: Float[ArrayLike, "..."],
    slip: Float[ArrayLike, "..."],
) -> ContactForces:
    """Contact integrals of a rigid wheel on a terrain at a given entry angle.

    Vertical load (4.14), motion resistance (4.16), thrust ((2.9) times r b), drawbar pull
    (2.10) and torque (2.12).  Without a `distribution` they are integrated over the
    front contact 0 <= theta <= theta0 as in the thesis; with `WongReece` over
    theta_r <= theta <= theta0.  All arguments broadcast against each other and against
    the leaves of `wheel`, `snow` and `distribution`.

    **Arguments:**

    - `wheel`: `RigidWheel` or `DeflectingTire`; `snow`: any terrain (`WongSnow`,
      `BekkerSoil`, `ReeceSoil`, `LayeredSnow`), SI, or a `ContactModel` with its shear
      law, stress distribution, nodes per panel and force terms (as in `solve_wheel`).
    - `entry_angle`: theta0 [rad], 0 < theta0 <= arccos(1 - 2 depth / D).
    - `slip`: driving slip i [-], eq. (2.6); negative when braking.

    **Returns:** `ContactForces` with fields in N (torque in N m).
    """
    from .inputs import _check_model

    model = _as_model(snow, "snow")
    _check_model(wheel, model)
    snow, law, distribution = model.terrain, model.shear, model.distribution
    rule = _contact_rule(snow, distribution, wheel, _STRAIGHT)
    # Unbound: see `solve_wheel`.
    n = type(rule).nodes(rule, law, model.nodes_per_panel, model.accuracy)
    return _contact_forces_jit(
        wheel, snow, distribution, model.terms, entry_angle, slip, law, n, _layout(slip), rule
    )


def _contact_batch(
    theta0,
    slip,
    wheel,
    terrain,
    distribution,
    running,
    terms,
    *,
    shear,
    n,
    braking,
    rule,
    vertical_only=False,
    bottomed=None,
    moving_rule=False,
):
    """Contact integrals of a flat batch (1-D leaves): W alone with `vertical_only`, else
    (W, R, T, M, F_y, M_z) (F_y = M_z = 0 running `Straight()`, unless a term gives
    them); `running` (`running.py`) and `terms`, the model's own force terms (a tuple),
    with 1-D leaves.

    The one entry to the quadrature, for the solver and `contact_forces`: every element
    by the contact `rule` (`rules.AbstractContactRule`, chosen by
    `front_rim._contact_rule`).  `bottomed` and `moving_rule` concern only the
    closed-form rule (the any-terrain rule's nodes move with theta0 by construction).
    """

    def one(th, i, wh, tr, ds, rn, tm, bt):
        contact = type(wh).contact(wh, th, tr)
        return rule.contact(
            contact, i, tr, ds, shear, n, rn, braking, vertical_only, tm, bt, moving_rule
        )

    return jax.vmap(one)(theta0, slip, wheel, terrain, distribution, running, terms, bottomed)


def _layout(slip, warm_start: bool = False) -> str:
    """Quadrature layout: "driving" (two panels) if no slip is < 0, else "braking".

    Traced slips (under `jit`, `vmap`, `grad`) get the general "braking" layout, which is
    valid for every slip, so that only one variant is compiled; with `warm_start` (a
    simulation step, compiled once and run many times) "auto": both are compiled and a
    step in which no wheel brakes (vmapped: no wheel of any environment,
    `batchwide._any_in_batch`) takes the two-panel rule (4 wheels warm-started in a
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
    braking = _any_in_batch(jax.lax.stop_gradient(slip) < 0)
    return jax.lax.cond(braking, lambda: fn(True), lambda: fn(False))


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
    wheel, terrain, distribution, terms, entry_angle, slip, shear, n, layout, rule
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
            _STRAIGHT,
            terms,
            shear=shear,
            n=n[braking],
            braking=braking,
            rule=rule,
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
