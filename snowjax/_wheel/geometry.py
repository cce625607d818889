"""The wheel: the abstract module the contact pipeline runs, the rigid wheel (the thesis's
model of a tyre on soft snow, section 4.1), and the rim geometry (4.5)-(4.10)."""

import abc
from typing import ClassVar, NamedTuple

import equinox as eqx
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
    - `tread(entry_angle, terrain)`: None for a rigid rim (the default), or the `Tread`
      (the flat part of the tread, its depth and extent) at that entry angle;
    - `contact_sinkage(entry_angle, terrain)`: the sinkage reported as
      `WheelState.sinkage` [m] (default the rim's, eq. 4.15);
    - `deepest_reach(terrain)`: how deep the undeflected circle may sink on the terrain
      [m] (default: to its base);
    - `flexing_resistance(tread)`: the resistance of the wheel's own deformation [N],
      added to the motion resistance (default None: none, a rigid rim);
    - `constraints()`: validity of each parameter (from the fields' `snowjax.parameter`
      metadata by default);
    - `reference()` (class method): a valid wheel of the kind, which stands in for
      invalid batch elements.
    """

    __check_init__ = _check_real_leaves

    diameter: AbstractVar[Float[Array, "..."]]
    width: AbstractVar[Float[Array, "..."]]

    #: Whether the wheel's tread can flatten (the closed-form rule of the rigid rim on
    #: Wong snow is then not taken).
    deflects: ClassVar[bool] = False
    #: Prefix used in error messages ("wheel.width must be ...").
    label: ClassVar[str] = "wheel"

    @property
    def radius(self) -> Array:
        """r = D / 2 [m]."""
        return self.diameter / 2

    def tread(self, entry_angle, terrain) -> Tread | None:
        """The flattened tread at entry angle theta0 [rad] on `terrain`; None: a rigid rim."""
        return None

    def contact_sinkage(self, entry_angle, terrain) -> Array:
        """Sinkage of the lowest point of the contact [m] at entry angle theta0 [rad]."""
        return max_sinkage(entry_angle, self.diameter)

    def deepest_reach(self, terrain) -> Array:
        """The deepest the undeflected circle's lowest point may sink [m] on `terrain`
        (the solver's cap on the entry angle): its base (`depth`) for a rim."""
        return terrain.depth

    def flexing_resistance(self, tread: Tread | None) -> Array | None:
        """The resistance of the wheel's own deformation [N] with the tread `tread`, added
        to the motion resistance R (and so taken from the drawbar pull); None: none."""
        return None

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
    return diameter * half_sin * (jnp.sin(theta0) * half_cos - jnp.cos(theta0) * half_sin)


def shear_displacement(
    theta: ArrayLike, entry_angle: ArrayLike, slip: ArrayLike, diameter: ArrayLike
) -> Array:
    """Shear displacement along the rim, eq. (4.10).

    `j = D/2 [(theta0 - theta) - (1 - i)(sin theta0 - sin theta)]`.

    **Arguments:** `theta` [rad], `entry_angle` theta0 [rad], `slip` i [-] (driving slip,
    eq. 2.6; negative when braking), `diameter` D [m].  **Returns:** j [m].
    """
    return _shear_displacement(
        jnp.asarray(theta), jnp.asarray(entry_angle), jnp.asarray(slip), jnp.asarray(diameter) / 2
    )


def _shear_displacement(theta, theta0, slip, radius, sin_theta=None, sin_theta0=None):
    """Eq. (4.10), `j = r [(theta0 - theta) - (1 - i)(sin theta0 - sin theta)]` [m] (the
    one implementation; `radius` 1 gives j / r).  The sines may be passed in when the
    caller has them (the quadrature's from `_sincos_half`)."""
    sin_theta = jnp.sin(theta) if sin_theta is None else sin_theta
    sin_theta0 = jnp.sin(theta0) if sin_theta0 is None else sin_theta0
    return radius * ((theta0 - theta) - (1 - slip) * (sin_theta0 - sin_theta))


def _shear_displacement_slope(cos_theta, slip):
    """dj/dtheta / r = -1 + (1 - i) cos theta [-], the derivative of (4.10) along the rim."""
    return -1 + (1 - slip) * cos_theta
