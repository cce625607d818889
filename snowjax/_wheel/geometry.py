"""The wheel: the abstract module the contact pipeline runs, the rigid wheel (the thesis's
model of a tyre on soft snow, section 4.1), its contact geometry as the contact integrals
see it (`AbstractContact`, `RimContact`), and the rim geometry (4.5)-(4.10)."""

import abc
from typing import ClassVar, NamedTuple

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from equinox import AbstractVar
from jaxtyping import Array, ArrayLike, Float

from .._constants import THESIS_DIAMETER, THESIS_TIRE_WIDTH
from .._leaves import _as_float, _check_real_leaves, _parameter_rules, parameter


class Tread(NamedTuple):
    """The flattened part of a deflecting tyre's tread at one entry angle.

    - `half_angle`: theta_f [rad], the rim angle of the flat's front end (the flat spans
      -theta_f..theta_f of the undeflected circle); 0 for a rigid rim.
    - `sinkage`: z_f [m], the depth of the flat below the surface.
    - `cos_half_angle`: cos theta_f = 1 - delta / r, delta the deflection.
    - `pressure`: p_f [Pa], the normal stress on the flat.
    - `deflection`: delta [m], the flat's height above the undeflected circle's lowest point.
    """

    half_angle: Array
    sinkage: Array
    cos_half_angle: Array
    pressure: Array
    deflection: Array


class AbstractWheel(eqx.Module):
    """A wheel the contact pipeline can run: a rigid rim (`RigidWheel`) or a tyre that
    flattens (`DeflectingTire`), or one of your own.

    What the pipeline asks of a wheel:

    - `diameter` D [m] and `width` b [m] (abstract variables): the undeflected circle
      whose entry angle theta0 the solver finds, and the width of the contact;
    - `contact(entry_angle, terrain)`: its contact geometry at that entry angle, an
      `AbstractContact` (default `RimContact`, the rim of eqs. 4.5-4.10; a deflecting
      tyre's has a flat);
    - `contact_width(sinkage)`: the contact's width [m] at a point of the given depth
      [m] (default `width`; a wheel whose section widens with depth overrides it);
    - `contact_sinkage(entry_angle, terrain)`: the sinkage reported as
      `WheelState.sinkage` [m] (default the rim's, eq. 4.15);
    - `deepest_reach(terrain)`: how deep the undeflected circle may sink on the terrain
      [m] (default: to its base);
    - `start_angles(terrain)`: entry angles [rad] where the wheel's W(theta0) bends
      sharply, at which the any-terrain solver's start on a law that can fall evaluates W
      too (default none; a deflecting tyre's switch to its elastic mode);
    - `constraints()`: validity of each parameter (from the fields' `snowjax.parameter`
      metadata by default);
    - `reference()` (class method): a valid wheel of the kind, which stands in for
      invalid batch elements.
    """

    __check_init__ = _check_real_leaves

    diameter: AbstractVar[Float[Array, "..."]]
    width: AbstractVar[Float[Array, "..."]]

    #: Whether the wheel's tread can flatten (its deflection's parameters are fitted by
    #: `fit_wheel`; the any-terrain cold start models its contact, flat included).
    deflects: ClassVar[bool] = False
    #: Prefix used in error messages ("wheel.width must be ...").
    label: ClassVar[str] = "wheel"

    @property
    def radius(self) -> Array:
        """r = D / 2 [m]."""
        return self.diameter / 2

    def contact(self, entry_angle, terrain) -> "AbstractContact":
        """The contact geometry at entry angle theta0 [rad] on `terrain`: the rim's."""
        return RimContact(self, entry_angle)

    def contact_width(self, sinkage) -> Array:
        """The contact's width b [m] at a point `sinkage` [m] deep: `width`."""
        return self.width

    def contact_sinkage(self, entry_angle, terrain) -> Array:
        """Sinkage of the lowest point of the contact [m] at entry angle theta0 [rad]."""
        return max_sinkage(entry_angle, self.diameter)

    def deepest_reach(self, terrain) -> Array:
        """The deepest the undeflected circle's lowest point may sink [m] on `terrain`
        (the solver's cap on the entry angle): its base (`depth`) for a rim."""
        return terrain.depth

    def start_angles(self, terrain) -> tuple[Array, ...]:
        """Entry angles [rad] where W(theta0) bends sharply (the any-terrain start on a
        law that can fall evaluates W there too, `start._scan_start`): none for a rim."""
        del terrain
        return ()

    def round_rim(self) -> "AbstractWheel":
        """The rim whose contact this wheel's is while its tread stays round
        (`stays_round`): the wheel itself for a rim (the default); a `DeflectingTire`'s
        `RigidWheel` of its diameter and width.  Where every element of a batch stays
        round at its root, `solve_wheel` solves with this rim instead (its contact
        takes fewer nodes)."""
        return self

    def stays_round(self, entry_angle, terrain) -> Array:
        """Whether the contact at entry angle theta0 [rad] is `round_rim`'s within the
        solver's accuracy (boolean, per element): always for a rim."""
        del terrain
        return jnp.ones_like(entry_angle, dtype=bool)

    def constraints(self) -> list[tuple[str, Array, Array, str]]:
        """Validity of each parameter: (field path, value, ok mask, allowed range)."""
        return [
            (f"{self.label}.{name}", value, ok, allowed)
            for name, value, ok, allowed in _parameter_rules(self)
        ]

    @classmethod
    @abc.abstractmethod
    def reference(cls) -> "AbstractWheel":
        """A valid wheel of this kind (stands in for invalid batch elements)."""


def _plain_rim(wheel) -> bool:
    """Whether the wheel's contact is the rim of constant width (the closed-form rule of a
    law with closed-form rim integrals applies to it)."""
    kind = type(wheel)
    return (
        kind.contact is AbstractWheel.contact and kind.contact_width is AbstractWheel.contact_width
    )


class RigidWheel(AbstractWheel):
    """A rigid wheel (the thesis's model of a tyre on soft snow, section 4.1).

    **Fields:**

    - `diameter`: D [m].
    - `width`: b [m].
    """

    diameter: Float[Array, "..."] = eqx.field(
        converter=_as_float, metadata=parameter("m", "wheel diameter D", lower=0.0, open_lower=True)
    )
    width: Float[Array, "..."] = eqx.field(
        converter=_as_float, metadata=parameter("m", "wheel width b", lower=0.0, open_lower=True)
    )

    @classmethod
    def thesis_tire(cls) -> "RigidWheel":
        """The 0.736 m tyre of the thesis's FEA studies (section 3.2 and Table 4.1).

        The thesis gives D = 0.736 m but not the width; 0.235 m is the section width of a
        P235/75R15 tyre, whose nominal diameter (0.734 m) matches D.
        """
        return cls(diameter=THESIS_DIAMETER, width=THESIS_TIRE_WIDTH)

    @classmethod
    def reference(cls) -> "RigidWheel":
        return cls.thesis_tire()


# Taylor coefficients of sin(x) / x and cos(x) in powers of x^2, to x^20: on half-angles
# |x| <= pi / 2 the truncation error is below 1e-17 (the sum's rounding, ~3e-16, dominates).
_SIN_TAYLOR = tuple(
    (-1) ** k / float(np.prod(np.arange(2, 2 * k + 2, dtype=float))) for k in range(11)
)
_COS_TAYLOR = tuple(
    (-1) ** k / float(np.prod(np.arange(1, 2 * k + 1, dtype=float))) for k in range(11)
)


def _sincos_half(theta):
    """(sin(theta / 2), cos(theta / 2)) for |theta| <= pi [rad], by Taylor polynomials.

    XLA's general-purpose float64 sine and cosine (argument reduction for any x) cost
    about seven times an exp on CPU; rim angles stay within |theta| <= pi, where two
    short polynomials in the half-angle are exact to rounding (tested against NumPy).
    """
    x = theta / 2
    x2 = x * x
    sin_poly = jnp.zeros_like(x2)
    cos_poly = jnp.zeros_like(x2)
    for cs, cc in zip(_SIN_TAYLOR[::-1], _COS_TAYLOR[::-1]):
        sin_poly = sin_poly * x2 + cs
        cos_poly = cos_poly * x2 + cc
    return x * sin_poly, cos_poly


def _sin_cos(theta):
    """(sin theta, cos theta) for |theta| <= pi [rad] from the half-angle polynomials
    (`_sincos_half`): exact to rounding, and cheap to repeat where XLA fuses a value of
    one element into the loop over its quadrature nodes (XLA:CPU's float64 sine there
    ran once per node: a tyre's W took 2.2x as long)."""
    half_sin, half_cos = _sincos_half(theta)
    return 2 * half_sin * half_cos, 1 - 2 * half_sin**2


def rim_sinkage(theta: ArrayLike, entry_angle: ArrayLike, diameter: ArrayLike) -> Array:
    """Sinkage of the rim point at angle theta, eq. (4.5): `z = D/2 (cos theta - cos theta0)`.

    Written as `D [sin^2(theta0/2) - sin^2(theta/2)]` to avoid cancellation.

    **Arguments:** `theta` [rad], `entry_angle` theta0 [rad], `diameter` D [m].
    **Returns:** z [m].
    """
    return jnp.asarray(diameter) * (
        jnp.sin(jnp.asarray(entry_angle) / 2) ** 2 - jnp.sin(jnp.asarray(theta) / 2) ** 2
    )


def max_sinkage(entry_angle: ArrayLike, diameter: ArrayLike) -> Array:
    """Maximum sinkage under the axle, eq. (4.6) / (4.15): `z0 = D/2 (1 - cos theta0)`.

    **Arguments:** `entry_angle` theta0 [rad], `diameter` D [m].  **Returns:** z0 [m].
    """
    return jnp.asarray(diameter) * jnp.sin(jnp.asarray(entry_angle) / 2) ** 2


def _rim_sinkage_between(theta_eff, theta0, diameter):
    """z = r (cos theta_eff - cos theta0) = D sin(d / 2) sin(theta0 - d / 2) [m],
    d = theta0 - theta_eff in [0, pi] (no cancellation near the entry; the half-angle of d
    by `_sincos_half`, the sine and cosine of theta0 once per wheel)."""
    half_sin, half_cos = _sincos_half(theta0 - theta_eff)
    sin0, cos0 = _sin_cos(theta0)
    return diameter * half_sin * (sin0 * half_cos - cos0 * half_sin)


def shear_displacement(
    theta: ArrayLike, entry_angle: ArrayLike, slip: ArrayLike, diameter: ArrayLike
) -> Array:
    """Shear displacement along the rim, eq. (4.10).

    `j = D/2 [(theta0 - theta) - (1 - i)(sin theta0 - sin theta)]`.

    **Arguments:** `theta` [rad], `entry_angle` theta0 [rad], `slip` i [-] (driving slip,
    eq. 2.6; negative when braking), `diameter` D [m].  **Returns:** j [m].
    """
    theta, entry_angle = jnp.asarray(theta), jnp.asarray(entry_angle)
    return _shear_displacement(
        theta,
        entry_angle,
        jnp.asarray(slip),
        jnp.asarray(diameter) / 2,
        jnp.sin(theta),
        jnp.sin(entry_angle),
    )


def _shear_displacement(theta, theta0, slip, radius, sin_theta, sin_theta0):
    """Eq. (4.10), `j = r [(theta0 - theta) - (1 - i)(sin theta0 - sin theta)]` [m] (the
    one implementation; `radius` 1 gives j / r), given the sines of theta and theta0
    (the quadrature's from `_sincos_half`)."""
    return radius * ((theta0 - theta) - (1 - slip) * (sin_theta0 - sin_theta))


def _shear_displacement_slope(cos_theta, slip):
    """dj/dtheta / r = -1 + (1 - i) cos theta [-], the derivative of (4.10) along the rim."""
    return -1 + (1 - slip) * cos_theta


def _layer_width(modulus, radius, slope):
    """Width [rad] of the layer over which the shear mobilises where (4.10) changes with
    slope dj/dtheta / r = `slope` [-]: K / (r |slope|), K = `modulus` [m]."""
    return modulus / (radius * jnp.maximum(jnp.abs(slope), 1e-12))


def _shear_sign_change(theta0, theta_r, slip, steps, taylor, offset: ArrayLike = 0.0):
    """Where the shear displacement (4.10) of a braked wheel changes sign inside the
    contact theta_r..theta0 (`theta_r` None: 0, the front region): (angle, has_root,
    theta_star).

    For slip < 0 (k = 1 - i > 1), f(theta) = j / r = (theta0 - theta) - k (sin theta0 -
    sin theta) is concave and increasing on |theta| < theta_star = arccos(1/k) and
    vanishes at theta0; a second root exists when f(lo) < 0 and theta_star < theta0,
    lo = max(theta_r, -theta_star).  Newton from lo converges monotonically from the
    left, kept in [lo, theta_star].  Where there is no root, `angle` is the last iterate
    (unused).  `taylor`: the iteration's sine and cosine from the half-angle Taylor
    polynomials (faster to run, more code to compile) or XLA's.  `offset` (default 0):
    the root of f - offset instead (a deflecting tyre's rear arc, whose travel the flat
    shortened).
    """
    sin_theta0 = jnp.sin(theta0)
    theta_star = jnp.arccos(jnp.clip(1 / (1 - slip), -1.0, 1.0))  # where dj/dtheta = 0
    # The front region (theta_r None) starts at lo = 0.
    lo = jnp.zeros_like(theta0) if theta_r is None else jnp.maximum(theta_r, -theta_star)
    f_lo = _shear_displacement(lo, theta0, slip, 1.0, jnp.sin(lo), sin_theta0) - offset
    has_root = (slip < 0) & (f_lo < 0) & (theta_star < theta0)

    def newton(_, th):
        if taylor:  # |th| <= pi
            half_sin, half_cos = _sincos_half(th)
            sin, cos = 2 * half_sin * half_cos, 1 - 2 * half_sin**2
        else:
            sin, cos = jnp.sin(th), jnp.cos(th)
        f = _shear_displacement(th, theta0, slip, 1.0, sin, sin_theta0) - offset
        slope = _shear_displacement_slope(cos, slip)
        return jnp.clip(th - f / jnp.maximum(slope, 1e-12), lo, theta_star)

    angle = jax.lax.fori_loop(0, steps, newton, lo)
    return angle, has_root, theta_star


class ContactPoints(NamedTuple):
    """A wheel's contact at rim angles theta [rad] (each entry an array of the angles'
    shape, or a scalar where it does not vary), what the contact integrals need of it:

    - `shortening`: the travel from the entry that the wheel's shape takes from the shear
      displacement (4.10), per r [-] (0 on a rim);
    - `normal_cos`, `normal_sin`: the normal's direction, the normal stress's shares of W
      and of R (cos theta, sin theta on a rim; (1, 0) on a tyre's flat);
    - `element`: the length of the contact per r d theta [-] (1 on a rim);
    - `depth`: the point's depth below the surface [m] (4.5 on a rim);
    - `width`: the contact's width b [m] there.
    """

    shortening: Array | float
    normal_cos: Array
    normal_sin: Array
    element: Array | float
    depth: Array
    width: Array


class AbstractContact(eqx.Module):
    """A wheel's contact with the terrain at one entry angle theta0 [rad] (abstract): the
    geometry the contact integrals ask of a wheel, so that they never ask which wheel it
    is.  Every method has the rigid rim's answer (eqs. 4.5-4.10) as its default;
    `RimContact` is the rim, a deflecting tyre's flat (`TreadContact`) overrides them.
    """

    wheel: AbstractVar["AbstractWheel"]
    entry_angle: AbstractVar[Array]

    def lowest_angle(self) -> Array:
        """The rim angle [rad] of the front contact's deepest point (0 on a rim)."""
        return jnp.zeros_like(self.entry_angle)

    def lowest_sinkage(self) -> Array:
        """The depth [m] of the contact's deepest point (4.6 on a rim)."""
        return max_sinkage(self.entry_angle, self.wheel.diameter)

    def rise(self, theta, theta_eff) -> Array:
        """Height [m] above the deepest point of the point at angle theta whose stress
        angle is theta_eff (`D sin^2(theta_eff / 2)` on a rim, measured from its lowest
        point, free of cancellation near a base)."""
        return self.wheel.diameter * _sincos_half(theta_eff)[0] ** 2

    def normal_stress(self, sigma, theta, theta_eff) -> Array:
        """The normal stress [Pa] at angle theta given the terrain's, sigma, at its
        stress angle's depth (the terrain's on a rim)."""
        return sigma

    def points(self, theta, sin, cos) -> ContactPoints:
        """The contact at angles theta [rad] with sines and cosines `sin`, `cos`."""
        depth = _rim_sinkage_between(theta, self.entry_angle, self.wheel.diameter)
        width = type(self.wheel).contact_width(self.wheel, depth)
        return ContactPoints(0.0, cos, sin, 1.0, depth, width)

    def moment(self, sigma, tau, theta, sin) -> Array:
        """The stresses' moment about the axle per r [Pa] at angles theta [rad] (sines
        `sin`): on a rim the shear stress's, whose arm is r (4.9's M_w)."""
        return tau

    def panel_ends(self, distribution, slip) -> list[Array]:
        """Angles [rad] where the contact's shape breaks (panel ends; none on a rim)."""
        return []

    def smooth_span(self, distribution) -> tuple[Array, ...]:
        """The angle [rad] up to which the contact, from its exit end (0 on the front
        region), carries a constant normal stress on a straight piece (a tyre's flat), in
        a one-tuple: every integrand is smooth there but for the shear's layers, so the
        integrator covers it with one graded panel of its own (`general._direct_nodes`)
        instead of the two half-panels graded for power-law ends.  Empty (static): no
        such piece (a rim).  Asked only where the panels are cut in the contact angle
        (not where a rear region mirrors the front, `mirrors_rear`)."""
        del distribution
        return ()

    def shear_sign_change(self, exit_angle, slip, rear: bool) -> tuple[Array, Array]:
        """(angle [rad], found): where a braked wheel's shear displacement changes sign in
        the contact exit_angle..theta0 (`rear` False: no rear arc, the front region)."""
        angle, found, _ = _shear_sign_change(self.entry_angle, exit_angle, slip, 12, False)
        return angle, found

    def shear_slope(self, theta, slip) -> Array:
        """d j / d theta / r [-] at angle theta (4.10)."""
        return _shear_displacement_slope(jnp.cos(theta), slip)

    def flexing_resistance(self) -> Array:
        """The resistance of the wheel's own deformation [N], part of the motion
        resistance (0 for a rim)."""
        return jnp.zeros_like(self.entry_angle)


class RimContact(AbstractContact):
    """The contact of a rim (circular, the thesis's, eqs. 4.5-4.10): every default of
    `AbstractContact`."""

    wheel: "AbstractWheel"
    entry_angle: Array
