"""The contact integrals of a rigid wheel (chapter 4): the one entry to the quadrature
(`_contact_batch`, for the solver and `contact_forces`), the per-point rim stresses, and
Wong snow's accelerated rule for the front region described below (every other
combination takes the any-terrain rule of `general.py`).

Notation (thesis, section 4.1): theta is measured from the vertical through the wheel
centre, theta0 is the entry angle, D the diameter, r = D / 2, b the width.

Quadrature.  The normal stress `sigma = -p_w ln Z` with `Z = Z0 + 2 a sin^2(theta / 2)`,
`a = D / (2 z_w)`, has a logarithmic singularity at theta = 0 when the wheel bottoms out
(Z0 -> 0), and the shear mobilisation rises from zero at the entry angle over a layer of
width ~ K / (r |1 - (1 - i) cos theta0|), which is steep for small K and large slip.
For a braked wheel the shear displacement changes sign inside the contact, which puts a
kink in the shear stress.  The integrals are therefore computed as

1.  *singularity subtraction*: for every integrand f = sigma h + (smooth), the part
    `sigma (h(0) cos theta + h'(0) sin theta)` is integrated in closed form
    (`_sigma_cos_integral`, `_sigma_sin_integral`), which leaves a remainder that vanishes
    like theta^2 ln theta at the singular end;
2.  *graded composite Gauss–Legendre* on four panels split at the sign change of the
    shear displacement (or at theta0 / 2 when there is none): a quadratic map clusters
    nodes at theta = 0, and sinh maps cluster them at the sign change and at the entry
    angle, with the width of the shear layer as their scale.

Node positions are functions of the inputs but carry no gradient (`stop_gradient`): the
exact integrals do not depend on them, so derivatives are those of the quadrature rule
with the nodes held fixed (with `moving_rule`, fixed relative to [0, theta0], which
second derivatives w.r.t. theta0 need; `solve_wheel`'s derivative rule uses it). Their error is
that of the rule applied to the derivative integrands, which live inside the shear layer
and so are larger than the values' error where the layer is thin: measured against the
exact model (SciPy quad + brentq) on random in-range cases, equilibrium gradients are
within 6e-7 relative for the simplified model (whose braking panels end where |U0|
saturates, see `_simplified_layout`), and within 1.2e-4 relative (d/dK; 1.3e-5 for d/dc,
9e-6 for d/dslip, below 1e-6 for the rest; worst of 161 cases) for classic braking at
its default nodes, where the panels are placed by the linear width of the shear layer
(`_classic_layout`).
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
from .._terrain.shear import _signed_mobilisation
from .distribution import AbstractStressDistribution, _as_distribution, _is_thesis_path
from .general import (
    DEFAULT_GENERAL_NODES,
    _layer_width,
    _power_map,
    _rule,
    _shear_sign_change,
    _sinh_offsets,
    general_contact,
)
from .geometry import (
    RigidWheel,
    _rim_sinkage_between,
    _shear_displacement,
    _shear_displacement_slope,
    _sincos_half,
    max_sinkage,
    shear_displacement,
)
from .model import ContactModel, _unpack_model
from .shear_law import AbstractShearLaw, ShearModel, _shear_name

# Gauss–Legendre nodes per panel, (two-panel rule for batches without braking,
# four-panel rule otherwise: one count per panel, axle to entry), chosen so that every
# contact integral stays within 1e-7 of adaptive quadrature over the documented range
# (tests; measured worst cases: classic 4e-8 / 9e-8, simplified 3e-9 driving, none
# 4e-10).  The simplified model's cubic exponent makes its shear layer steeper, hence
# more nodes; the classic model's entry panel needs only 8.
DEFAULT_NODES_PER_PANEL = {
    "classic": (10, (10, 10, 10, 8)),
    "simplified": (24, (16, 16, 16, 16)),
    "none": (8, (8, 8, 8, 8)),
}


def _nodes_for(shear: str, nodes_per_panel: int | None, thesis: bool) -> tuple:
    """Nodes of the rule (without braking, with braking), indexed by `braking`.

    `thesis` (Wong snow's rule): nodes per panel of the two-panel rule, and of each panel
    of the four-panel rule; otherwise nodes per half-panel of the any-terrain rule.
    """
    if nodes_per_panel is None:
        return DEFAULT_NODES_PER_PANEL[shear] if thesis else DEFAULT_GENERAL_NODES[shear]
    n = int(nodes_per_panel)
    if n < 2:
        raise ValueError(f"nodes_per_panel must be >= 2, got {n}")
    return (n, (n, n, n, n)) if thesis else (n, n)


# --------------------------------------------------------------------------------------
# Geometry and stresses (pure functions of scalars or broadcastable arrays)
# --------------------------------------------------------------------------------------


def _relative_sinkage_at_axle(entry_angle, diameter, z_w):
    """Z0 = 1 - z0 / z_w, eq. (4.4), clipped at 0 (bottomed out)."""
    return jnp.maximum(1 - max_sinkage(entry_angle, diameter) / z_w, 0.0)


def normal_stress(
    theta: ArrayLike,
    entry_angle: ArrayLike,
    wheel: RigidWheel,
    snow: AbstractTerrain,
    *,
    slip: ArrayLike = 0.0,
    distribution: AbstractStressDistribution | None = None,
) -> Array:
    """Normal stress on the rim at angle theta: the terrain's pressure–sinkage law at the
    rim sinkage (4.5) of the distribution's stress angle.

    On `WongSnow` with the front region this is eq. (4.1b) written as `sigma = -p_w ln Z`,
    `Z = 1 - z / z_w = Z0 + (D / z_w) sin^2(theta / 2)` (no cancellation near the entry).
    On any terrain and distribution, `sigma = terrain.pressure(z)` with
    `z = r (cos theta* - cos theta0)`, theta* = `distribution.stress_angle(theta, ...)`
    (theta in the front region, the mirrored front angle in Wong–Reece's rear region).

    **Arguments:** `theta` [rad] (in theta_r..theta0), `entry_angle` theta0 [rad],
    `wheel`, `snow` (any terrain); keywords: `slip` i [-] (where the distribution
    depends on it: Wong–Reece's theta_m), `distribution` (None: the front region).
    **Returns:** sigma [Pa]; `+inf` only at theta = 0 of a wheel resting on a Wong base.
    """
    distribution = _as_distribution(distribution)
    if _is_thesis_path(snow, distribution):
        z0_rel = _relative_sinkage_at_axle(entry_angle, wheel.diameter, snow.z_w)
        big_z = z0_rel + wheel.diameter / snow.z_w * jnp.sin(jnp.asarray(theta) / 2) ** 2
        return -snow.p_w * jnp.log(big_z)
    return _rim_stress_properties(theta, entry_angle, slip, wheel, snow, distribution)[0]


def _rim_stress_properties(theta, entry_angle, slip, wheel, terrain, distribution):
    """(sigma [Pa], c [Pa], tan phi [-], K [m]) at rim angle theta on any terrain."""
    theta0 = jnp.asarray(entry_angle)
    stress_angle = distribution.stress_angle(jnp.asarray(theta), theta0, slip)
    z = _rim_sinkage_between(stress_angle, theta0, wheel.diameter)
    return terrain.rim_properties(z, wheel.width)


def _simplified_coefficients(entry_angle, diameter, snow):
    """tau_1 and tau_2 of eq. (4.13), evaluated at the current entry angle."""
    u_k = diameter / snow.shear_modulus
    tau1 = u_k * (snow.z_w / diameter) * (snow.cohesion / snow.p_w) / jnp.tan(entry_angle)
    tau2 = 1 / jnp.cos(entry_angle) - 1
    return tau1, tau2


def _simplified_exponent(sigma_bar, slip, tau1, tau2):
    """U0 of eq. (4.13): `(i + tau2) tau1 s + (2i - i^2) tau1 s^3 / 6`, s = sigma / c."""
    return (slip + tau2) * tau1 * sigma_bar + (2 * slip - slip**2) * tau1 * sigma_bar**3 / 6


def shear_stress(
    theta: ArrayLike,
    entry_angle: ArrayLike,
    slip: ArrayLike,
    wheel: RigidWheel,
    snow: AbstractTerrain,
    shear: ShearModel | AbstractShearLaw = "classic",
    *,
    distribution: AbstractStressDistribution | None = None,
) -> Array:
    """Shear stress on the rim [Pa] for one of the thesis's shear models.

    - `"classic"`: Janosi–Hanamoto with the rigid-wheel shear displacement, eq. (4.11):
      `tau = (c + sigma tan phi)[1 - exp(-j / K)]`, on any terrain and distribution (c,
      tan phi and K those acting at the stress angle's sinkage: `rim_properties`).
    - `"simplified"`: the thesis's model, eq. (4.13) (`WongSnow`, front region only):
      `tau = c (1 + sigma_bar tan phi)[1 - exp(-U0)]`, `sigma_bar = sigma / c`,
      `U0 = (i + tau2) tau1 sigma_bar + (2i - i^2) tau1 sigma_bar^3 / 6`,
      `tau1 = (D / K)(z_w / D)(c / p_w) cot theta0`, `tau2 = 1 / cos theta0 - 1`, with tau1
      and tau2 evaluated at the current entry angle.
    - `"none"`: tau = 0.

    For a braked wheel (slip < 0) the shear displacement j (classic) or the exponent U0
    (simplified) can be negative; the mobilisation factor is then mirrored,
    `-[1 - exp(-|j| / K)]`, so the stress is signed and bounded by Mohr–Coulomb.

    **Arguments:** `theta` [rad], `entry_angle` theta0 [rad], `slip` i [-], `wheel`,
    `snow` (any terrain), `shear` (model name); keyword `distribution` (None: the front
    region).
    """
    from .inputs import _check_model

    shear = _shear_name(shear)
    _check_model(wheel, snow, distribution, shear)
    distribution = _as_distribution(distribution)
    if _is_thesis_path(snow, distribution):
        sigma = normal_stress(theta, entry_angle, wheel, snow)
        return _shear_from_sigma(sigma, theta, entry_angle, slip, wheel.diameter, snow, shear)
    sigma, c, tan_phi, k = _rim_stress_properties(
        theta, entry_angle, slip, wheel, snow, distribution
    )
    if shear == "none":
        return jnp.zeros_like(sigma)
    j = shear_displacement(theta, entry_angle, slip, wheel.diameter)
    return (c + sigma * tan_phi) * _signed_mobilisation(j / k)


def _shear_from_sigma(sigma, theta, entry_angle, slip, diameter, snow, shear):
    if shear == "none":
        return jnp.zeros_like(sigma)
    strength = snow.cohesion + sigma * snow.tan_phi
    return strength * _mobilisation(sigma, theta, entry_angle, slip, diameter, snow, shear)


def _mobilisation(sigma, theta, entry_angle, slip, diameter, snow, shear):
    """The factor g in tau = (c + sigma tan phi) g, for the classic or simplified model."""
    if shear == "classic":
        j = shear_displacement(theta, entry_angle, slip, diameter)
        return _signed_mobilisation(j / snow.shear_modulus)
    tau1, tau2 = _simplified_coefficients(entry_angle, diameter, snow)
    u0 = _simplified_exponent(sigma / snow.cohesion, slip, tau1, tau2)
    return _signed_mobilisation(u0)


# --------------------------------------------------------------------------------------
# Closed forms used by the singularity subtraction
# --------------------------------------------------------------------------------------


def _safe_sqrt(x):
    positive = x > 0
    return jnp.where(positive, jnp.sqrt(jnp.where(positive, x, 1.0)), 0.0)


def _sigma_cos_integral(theta0, z0_rel, a, p_w):
    """Exact `int_0^theta0 sigma cos(theta) dtheta` for Wong's law on the rim.

    With Z = A - a cos(theta), A = Z0 + a, integration by parts (Z(theta0) = 1) gives
    `p_w a int_0^theta0 sin^2 / Z`, and
    `int sin^2/(A - a cos) = sin/a + A theta/a^2 - 2 sqrt(A^2 - a^2)/a^2
    atan(sqrt((A + a)/(A - a)) tan(theta/2))`.  Finite as Z0 -> 0.
    """
    sq_z0 = _safe_sqrt(z0_rel)
    sq_2a = jnp.sqrt(z0_rel + 2 * a)
    big_a = z0_rel + a
    angle = jnp.arctan2(sq_2a * jnp.tan(theta0 / 2), sq_z0)
    return p_w * (jnp.sin(theta0) + big_a * theta0 / a - 2 * sq_z0 * sq_2a / a * angle)


def _sigma_sin_integral(z0_rel, a, p_w):
    """Exact `int_0^theta0 sigma sin(theta) dtheta = (p_w / a)(1 - Z0 + Z0 ln Z0)`."""
    positive = z0_rel > 0
    xlogx = jnp.where(positive, z0_rel * jnp.log(jnp.where(positive, z0_rel, 1.0)), 0.0)
    return p_w / a * (1 - z0_rel + xlogx)


# --------------------------------------------------------------------------------------
# Quadrature nodes
# --------------------------------------------------------------------------------------


def _sinh_panel(t, w, lo, hi, scale, toward_hi):
    """GL nodes t in [0, 1] with weights w mapped onto [lo, hi] by the sinh map
    (`_sinh_offsets`), clustered at hi (`toward_hi`) or lo with the given scale."""
    offset, jac = _sinh_offsets(t, w, hi - lo, scale, 1e-4)
    return jnp.where(toward_hi, hi - offset, lo + offset), jac


def _axle_gap(dtype) -> float:
    """Sign changes of the shear stress closer to the axle than this fraction of theta0 are
    left to the first panel (which then misses a layer at most that wide).  1e-9 in
    float64; 1e-3 in float32, where a split closer to the axle would put nodes so close
    to theta = 0 that sin^2(theta / 2) underflows (infinite pressure on a bottomed-out
    wheel)."""
    return 1e-9 if jnp.dtype(dtype) == jnp.float64 else 1e-3


def _classic_layout(theta0, slip, diameter, snow, entry_scale):
    """Panel ends and sinh scales of the four-panel rule for the classic model.

    The shear displacement j(theta) / r = (theta0 - theta) - k (sin theta0 - sin theta),
    k = 1 - i, vanishes at the entry; for a braked wheel with k cos theta0 > 1 it rises
    from the entry to a maximum at theta* = arccos(1 / k) and, if j(0) < 0, falls through
    zero at the split below theta* (backward shear near the axle, a kink in the stress).
    Panels: [0, split / 2] (quadratic map at the axle), [split / 2, split] and
    [split, b3] clustered at the split with the linear layer width
    K / (r |dj/dtheta|), and [b3, theta0] clustered at the entry with twice the entry
    layer width.  b3 is theta*, kept within the middle 60 % of [split, theta0]: each of
    the last two panels then holds one monotone branch of j.  Without a sign change the
    split is theta0 / 2 and b3 the midpoint of [split, theta0].

    Returns (b1, split, b3, scale2, scale3, scale4).
    """
    th, has_root, theta_star = _shear_sign_change(theta0, None, slip, 8, True)
    slope = _shear_displacement_slope(1 - 2 * _sincos_half(th)[0] ** 2, slip)
    split_scale = _layer_width(snow.shear_modulus, diameter / 2, slope)
    has_root = has_root & (th > _axle_gap(theta0.dtype) * theta0)
    split = jnp.where(has_root, th, theta0 / 2)
    gap = theta0 - split
    b3 = jnp.where(
        has_root, jnp.clip(theta_star, split + 0.2 * gap, theta0 - 0.2 * gap), split + 0.5 * gap
    )
    scale = jnp.where(has_root, split_scale, jnp.inf)
    return split / 2, split, b3, scale, scale, 2 * entry_scale


# Level of |U0| beyond which the mobilisation is saturated to rounding: exp(-40) = 4e-18.
_SATURATED_U0 = 40.0


def _theta_at_sigma_bar(s, snow, z0_rel, a):
    """Rim angle where sigma / c = s (Wong's law on the rim, inverted); 0 past the axle."""
    z = jnp.exp(-snow.cohesion / snow.p_w * s)
    return 2 * jnp.arcsin(jnp.sqrt(jnp.clip((z - z0_rel) / (2 * a), 0.0, 1.0)))


def _simplified_layout(theta0, slip, diameter, snow, z0_rel, a, entry_scale):
    """Panel ends and sinh scales of the four-panel rule for the simplified model.

    U0 = tau1 s (A - B s^2), s = sigma / c, A = i + tau2, B = (i^2 - 2i) / 6, is a cubic in
    s, and s falls monotonically from the axle to the entry, so every level of |U0| is
    reached at an angle known from a root of the cubic (`_theta_at_sigma_bar`).  The
    mobilisation varies only where |U0| < 40; the nodes must resolve that layer, all the
    more because the integrands of the derivatives (~ U0 exp(-|U0|)) live only there.

    - U0 changes sign at s_r = sqrt(A / B) (i < 0 < A).  Below the split (s > s_r) |U0|
      grows like the cubic, much faster than its slope at the root suggests: panel 2 is
      [theta(|U0| = 40), split] (at least [split / 2, split]) and clusters at the split
      with twice the distance to |U0| = 1; panel 3 clusters at the split with four times
      the linear scale 1 / |dU0/dtheta|, panel 4 at the entry as without a split.
    - No sign change: |U0| = tau1 s (|A| + |B| s^2) grows monotonically from the entry;
      panel 4 is [theta(|U0| = 40), theta0] (at least the upper half of [theta0 / 2,
      theta0]) and clusters at theta0 with the distance to |U0| = 1 (or the entry scale,
      if less).

    Returns (b1, split, b3, scale2, scale3, scale4): the panels are [0, b1], [b1, split],
    [split, b3] and [b3, theta0].
    """
    tiny = jnp.finfo(theta0.dtype).tiny
    tau1, tau2 = _simplified_coefficients(theta0, diameter, snow)
    big_a = slip + tau2
    big_b = (slip**2 - 2 * slip) / 6
    sign_change = (slip < 0) & (big_a > 0)
    s_root = jnp.sqrt(jnp.where(sign_change, big_a / jnp.where(sign_change, big_b, 1.0), 0.0))
    th_root = _theta_at_sigma_bar(s_root, snow, z0_rel, a)
    z_root = jnp.exp(-snow.cohesion / snow.p_w * s_root)
    gap = _axle_gap(theta0.dtype) * theta0
    has_root = sign_change & (z_root > z0_rel) & (th_root < theta0) & (th_root > gap)
    # |U0| = tau1 s (bb s^2 - aa) beyond the root (s > s_r), or from the entry when U0 has
    # one sign; increasing and convex there, so Newton from an upper bound converges
    # monotonically: s_r + cbrt(level / (tau1 B)) beyond a root, else the smaller of
    # cbrt(level / (tau1 |B|)) and level / (tau1 |A|) (within a factor 2 of the root).
    # A sign change left to the first panel counts as none: the levels are then those of
    # the upper bound tau1 s (|A| + |B| s^2) of |U0|, reached from the entry.
    aa = jnp.where(has_root, big_a, -jnp.abs(big_a))
    bb = jnp.maximum(jnp.abs(big_b), tiny)
    s_floor = jnp.where(has_root, s_root, 0.0)

    def s_at(level):
        # cbrt of each factor: B ~ -i / 3 can be ~1e-37 (float32 slip of -1e-36), and
        # level / (tau1 B) would overflow.
        c3 = jnp.cbrt(level / tau1) / jnp.cbrt(bb)
        s = jnp.where(has_root, s_root + c3, jnp.minimum(c3, level / jnp.maximum(-tau1 * aa, tiny)))
        for _ in range(8):
            f = tau1 * s * (bb * s**2 - aa) - level
            slope = jnp.maximum(tau1 * (3 * bb * s**2 - aa), tiny)
            s = jnp.maximum(s - f / slope, s_floor)
        return s

    th_1 = _theta_at_sigma_bar(s_at(1.0), snow, z0_rel, a)
    th_sat = _theta_at_sigma_bar(s_at(_SATURATED_U0), snow, z0_rel, a)
    # |dU0/dtheta| at the root: dU0/ds * ds/dtheta.
    du_ds = tau1 * (big_a - 3 * big_b * s_root**2)
    ds_dth = snow.p_w / snow.cohesion * a * jnp.sin(th_root) / jnp.maximum(z_root, tiny)
    linear = 1 / jnp.maximum(jnp.abs(du_ds * ds_dth), 1e-12)
    split = jnp.where(has_root, th_root, theta0 / 2)
    b1 = jnp.where(has_root, jnp.maximum(split / 2, th_sat), split / 2)
    b3 = jnp.where(has_root, (split + theta0) / 2, jnp.maximum((split + theta0) / 2, th_sat))
    scale2 = jnp.where(has_root, 2 * jnp.minimum(th_root - th_1, linear), jnp.inf)
    scale3 = jnp.where(has_root, 4 * linear, jnp.inf)
    scale4 = jnp.where(has_root, entry_scale, jnp.minimum(theta0 - th_1, entry_scale))
    return b1, split, b3, scale2, scale3, scale4


def _entry_scale(theta0, slip, diameter, snow, shear, a):
    """Width [rad] of the layer behind the entry angle over which the shear mobilises."""
    if shear == "none":
        return jnp.full_like(theta0, jnp.inf)
    # Linear rise of j / K (classic) or of U0's linear term (simplified, identical).
    slope = _shear_displacement_slope(jnp.cos(theta0), slip)
    scale = _layer_width(snow.shear_modulus, diameter / 2, slope)
    if shear == "simplified":
        # U0's cubic term: sigma_bar ~ k1 (theta0 - theta) near the entry, so
        # |2i - i^2| tau1 (k1 d)^3 / 6 = 1 at d = 1 / (k1 cbrt(|2i - i^2| tau1 / 6)).
        tau1, _ = _simplified_coefficients(theta0, diameter, snow)
        k1 = snow.p_w / snow.cohesion * a * jnp.sin(theta0)
        cubic = jnp.abs(2 * slip - slip**2) * tau1 / 6
        scale = jnp.minimum(scale, 1 / (k1 * jnp.cbrt(cubic) + 1e-300))
    return scale


def _nodes(theta0, slip, diameter, snow, shear, z0_rel, a, n, braking=True):
    """Graded composite Gauss–Legendre nodes and weights on [0, theta0] (no gradient).

    `braking=False` (valid when slip >= 0, where the shear stress has one sign): two
    panels of n nodes, [0, theta0/2] with a quadratic map clustering nodes at the log
    singularity theta = 0 and [theta0/2, theta0] with a sinh map clustering them in the
    shear layer behind the entry angle.  `braking=True`: four panels split at the sign
    change of the shear stress (or at theta0 / 2 when there is none), with sinh maps
    clustering nodes on both sides of it (`_classic_layout`, `_simplified_layout`); `n`
    is then one count per panel, axle to entry (`_nodes_for`).
    """
    theta0, slip, diameter, snow, z0_rel, a = jax.lax.stop_gradient(
        (theta0, slip, diameter, snow, z0_rel, a)
    )
    entry_scale = _entry_scale(theta0, slip, diameter, snow, shear, a)
    if not braking:
        t, w = _rule(n, theta0.dtype)
        half = theta0 / 2
        u, du = _power_map(t, w, 2)
        x2, w2 = _sinh_panel(t, w, half, theta0, entry_scale, True)
        return jnp.concatenate([half * u, x2]), jnp.concatenate([half * du, w2])
    if shear == "simplified":
        b1, split, b3, scale2, scale3, scale4 = _simplified_layout(
            theta0, slip, diameter, snow, z0_rel, a, entry_scale
        )
    elif shear == "classic":
        b1, split, b3, scale2, scale3, scale4 = _classic_layout(
            theta0, slip, diameter, snow, entry_scale
        )
    else:  # no shear stress, no layer: four equal panels
        b1, split, b3 = theta0 / 4, theta0 / 2, 0.75 * theta0
        scale2 = scale3 = scale4 = jnp.full_like(theta0, jnp.inf)
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


def _g_at_axle(theta0, slip, diameter, snow, shear, z0_rel):
    """Mobilisation g and dg/dtheta at theta = 0 (used by the singularity subtraction)."""
    if shear == "none":
        zero = jnp.zeros_like(theta0)
        return zero, zero
    if shear == "classic":
        x = shear_displacement(0.0, theta0, slip, diameter) / snow.shear_modulus
        g0 = _signed_mobilisation(x)
        dj_dtheta = -diameter / 2 * slip  # dj/dtheta at theta = 0
        g1 = jnp.exp(-jnp.abs(x)) * dj_dtheta / snow.shear_modulus
        return g0, g1
    # simplified: g depends on theta only through sigma, and dsigma/dtheta = 0 at theta = 0.
    sigma0 = -snow.p_w * jnp.log(jnp.maximum(z0_rel, 1e-30))
    tau1, tau2 = _simplified_coefficients(theta0, diameter, snow)
    g0 = _signed_mobilisation(_simplified_exponent(sigma0 / snow.cohesion, slip, tau1, tau2))
    return g0, jnp.zeros_like(theta0)


def _contact_scalar(
    theta0,
    slip,
    diameter,
    width,
    snow,
    shear,
    n,
    bottomed=None,
    braking=True,
    vertical_only=False,
    moving_rule=False,
):
    """(W, R, T, M) for scalar inputs, or W alone with `vertical_only`.

    `moving_rule=True` moves the quadrature rule with theta0 for derivatives (values are
    unchanged): needed for second derivatives w.r.t. theta0, whose Leibniz term the
    fixed nodes drop (the first derivative's term vanishes: the stresses are 0 at the
    entry), and slower, so only `solve_wheel`'s derivative rule asks for it.

    `bottomed` forces Z0 = 0 structurally; `braking=False` selects the two-panel rule,
    valid for slip >= 0 only (see `_nodes`).
    """
    r = diameter / 2
    a = diameter / (2 * snow.z_w)
    z0_rel = _relative_sinkage_at_axle(theta0, diameter, snow.z_w)
    if bottomed is not None:
        z0_rel = jnp.where(bottomed, 0.0, z0_rel)
    theta, weight = _nodes(theta0, slip, diameter, snow, shear, z0_rel, a, n, braking)
    if moving_rule:
        # The rule scaled with theta0 (a factor 1 in value): its nodes move with the
        # upper limit, so that derivatives w.r.t. theta0 of every order are those of the
        # rule on [0, theta0].
        stretch = theta0 / jax.lax.stop_gradient(theta0)
        theta, weight = theta * stretch, weight * stretch

    half_sin, half_cos = _sincos_half(theta)
    sin = 2 * half_sin * half_cos
    cos = 1 - 2 * half_sin**2
    sigma = -snow.p_w * jnp.log(z0_rel + 2 * a * half_sin**2)
    if shear == "none":
        tau = jnp.zeros_like(sigma)
    elif shear == "classic":
        j = _shear_displacement(theta, theta0, slip, r, sin)
        tau = (snow.cohesion + sigma * snow.tan_phi) * _signed_mobilisation(j / snow.shear_modulus)
    else:
        tau = (snow.cohesion + sigma * snow.tan_phi) * _mobilisation(
            sigma, theta, theta0, slip, diameter, snow, shear
        )

    # Singularity subtraction: f = sigma h + smooth; remove sigma (h0 cos + h1 sin).
    g0, g1 = _g_at_axle(theta0, slip, diameter, snow, shear, z0_rel)
    tp = snow.tan_phi
    # Blend weight: 1 near bottoming (where it is needed), ~4 (z0/z_w)^2 for shallow
    # sinkage, where the closed forms lose digits to cancellation.
    blend = (1 - z0_rel**2) ** 2
    c_cos = _sigma_cos_integral(theta0, z0_rel, a, snow.p_w)
    c_sin = _sigma_sin_integral(z0_rel, a, snow.p_w)
    sig_cos, sig_sin = sigma * cos, sigma * sin
    rb = r * width

    def integral(f, h0, h1):
        quad = jnp.sum((f - blend * (h0 * sig_cos + h1 * sig_sin)) * weight)
        return quad + blend * (h0 * c_cos + h1 * c_sin)

    w_int = integral(sig_cos + tau * sin, 1.0, tp * g0)
    if vertical_only:
        return w_int * rb
    r_int = integral(sig_sin, 0.0, 1.0)
    t_int = integral(tau * cos, tp * g0, tp * g1)
    m_int = integral(tau, tp * g0, tp * g1)
    return w_int * rb, r_int * rb, t_int * rb, m_int * rb * r


def contact_forces(
    wheel: RigidWheel,
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

    - `wheel`: `RigidWheel`; `snow`: any terrain (`WongSnow`, `BekkerSoil`, `ReeceSoil`,
      `LayeredSnow`), SI, or a `ContactModel` (then leave `shear`, `distribution` and
      `nodes_per_panel` out).
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
    snow, shear, distribution, _, nodes_per_panel = _unpack_model(
        snow, shear, distribution, nodes_per_panel=nodes_per_panel
    )
    shear = _shear_name(shear)
    from .inputs import _check_model

    _check_model(wheel, snow, distribution, shear)
    distribution = _as_distribution(distribution)
    thesis = _is_thesis_path(snow, distribution)
    n = _nodes_for(shear, nodes_per_panel, thesis)
    return _contact_forces_jit(
        wheel, snow, distribution, entry_angle, slip, shear, n, _layout(slip), thesis
    )


def _contact_batch(
    theta0,
    slip,
    wheel,
    terrain,
    distribution,
    side,
    *,
    shear,
    n,
    braking,
    thesis,
    bulldozing=False,
    vertical_only=False,
    bottomed=None,
    moving_rule=False,
):
    """Contact integrals of a flat batch (1-D leaves): W alone with `vertical_only`, else
    (W, R, T, M, F_y, M_z) (F_y = M_z = 0 without a slip angle, `side` None).

    The one entry to the quadrature, for the solver and `contact_forces`.  `thesis`
    (`WongSnow` on the front region, straight running) takes Wong snow's accelerated rule
    (`_contact_scalar`: graded panels placed by the shear law, the log singularity at a
    bottomed axle subtracted in closed form); every other combination the any-terrain
    rule (`general_contact`: panels cut at the distribution's angles, the terrain's
    breakpoints and the shear law's sign change).  `bottomed` and `moving_rule` concern
    only the former (the latter's nodes move with theta0 by construction).
    """

    def one(th, i, wh, tr, ds, sd, bt):
        if thesis:
            out = _contact_scalar(
                th, i, wh.diameter, wh.width, tr, shear, n, bt, braking, vertical_only, moving_rule
            )
        else:
            out = general_contact(
                th,
                i,
                wh.diameter,
                wh.width,
                tr,
                ds,
                shear,
                n,
                braking,
                vertical_only,
                sd,
                bulldozing,
            )
        if vertical_only or sd is not None:
            return out
        return (*out, jnp.zeros_like(th), jnp.zeros_like(th))

    return jax.vmap(one)(theta0, slip, wheel, terrain, distribution, side, bottomed)


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
    if shear == "none" or layout == "driving":
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
def _contact_forces_jit(wheel, terrain, distribution, entry_angle, slip, shear, n, layout, thesis):
    shape, _, (wheel, terrain, distribution, theta0, slip) = _broadcast_leaves(
        wheel, terrain, distribution, entry_angle, slip
    )

    def forces(braking):
        return _contact_batch(
            theta0,
            slip,
            wheel,
            terrain,
            distribution,
            None,
            shear=shear,
            n=n[braking],
            braking=braking,
            thesis=thesis,
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
