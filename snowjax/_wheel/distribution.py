"""Normal-stress distributions around the rim of a rigid wheel.

A distribution says where the contact ends behind the axle (the exit angle theta_r) and
at which rim sinkage the terrain's pressure–sinkage law gives the normal stress at each
angle of the contact (`stress_angle`).  The thesis (chapter 4) integrates only the front
of the contact, 0 <= theta <= theta0, with the normal stress given by the law at the
rim's own sinkage: `FrontRegion` (also spelled `distribution=None`).  `WongReece` is the
distribution of Wong & Reece (1967), used by most terramechanics codes: the stress peaks
at theta_m and the rear of the contact, theta_r <= theta <= theta_m, carries the stress
of the mirrored front angle.
"""

import abc
from typing import ClassVar

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float

from .._leaves import _as_float, _check_real_leaves, parameter

__all__ = ["AbstractStressDistribution", "FrontRegion", "WongReece"]


class AbstractStressDistribution(eqx.Module):
    """How the normal stress is distributed around the rim (abstract).

    A distribution implements `stress_angle`; it may override `exit_angle` (default 0:
    the contact ends under the axle), `breakpoints` (angles where the stress has a kink,
    default none), `rear_angles` (the other angles whose stress angle is a given one:
    where a kink of the terrain's law shows up a second time; default none),
    `constraints` and `reference` (a valid instance, which stands in for invalid batch
    elements; the default `cls()` serves only a distribution without fields).  Angles
    in rad, measured from the vertical through the wheel centre, theta0 the entry angle,
    slip the driving slip i [-] (2.6).  The shear stress follows the rim's shear
    displacement (4.10) over the whole contact.
    Parameters are array leaves (`eqx.field(converter=..., metadata=parameter(...))`):
    they broadcast, vmap, differentiate and can be fitted like terrain parameters.
    """

    __check_init__ = _check_real_leaves

    #: Whether the rear region mirrors the front linearly (`rear_region`).
    mirrors_rear: ClassVar[bool] = False

    @abc.abstractmethod
    def stress_angle(
        self,
        theta: Float[ArrayLike, "..."],
        entry_angle: Float[ArrayLike, "..."],
        slip: Float[ArrayLike, "..."],
    ) -> Float[Array, "..."]:
        """The angle [rad] whose rim sinkage, r (cos(.) - cos theta0), gives the normal
        stress at the contact angle theta [rad] (theta itself in the front region)."""

    def exit_angle(
        self, entry_angle: Float[ArrayLike, "..."], slip: Float[ArrayLike, "..."]
    ) -> Float[Array, "..."]:
        """theta_r [rad], where the contact ends (0: under the axle)."""
        return jnp.zeros_like(jnp.asarray(entry_angle))

    def breakpoints(
        self, entry_angle: Float[ArrayLike, "..."], slip: Float[ArrayLike, "..."]
    ) -> tuple[Array, ...]:
        """Angles [rad] in (theta_r, theta0) where the normal stress has a kink (none)."""
        return ()

    def rear_angles(
        self,
        angle: Float[ArrayLike, "..."],
        entry_angle: Float[ArrayLike, "..."],
        slip: Float[ArrayLike, "..."],
    ) -> tuple[Array, ...]:
        """Angles [rad] other than `angle` whose `stress_angle` is `angle` (none)."""
        return ()

    def constraints(self, slip) -> list[tuple[str, Array, Array, str]]:
        """Validity per element: (name, value, ok mask, allowed range); none by default."""
        return []

    def rear_region(
        self, entry_angle: Float[ArrayLike, "..."], slip: Float[ArrayLike, "..."]
    ) -> tuple[Array, Array]:
        """(theta_m, theta_r) [rad] of a distribution whose rear region [theta_r, theta_m]
        carries at theta the stress of the front angle theta0 - (theta - theta_r)
        (theta0 - theta_m) / (theta_m - theta_r) (`mirrors_rear`): the contact
        integrals then place their nodes once in [theta_m, theta0] for both regions.
        Only called where `mirrors_rear` is True."""
        raise NotImplementedError

    @classmethod
    def reference(cls) -> "AbstractStressDistribution":
        """A valid parameter set of this kind (stands in for invalid batch elements)."""
        return cls()


class FrontRegion(AbstractStressDistribution):
    """The thesis's distribution (chapter 4): the front of the contact only,
    0 <= theta <= theta0, with the normal stress of the terrain's law at the rim's own
    sinkage (4.1b with 4.5).  `distribution=None` means this distribution.  No fields.
    """

    def stress_angle(self, theta, entry_angle, slip):
        """theta itself [rad]."""
        return jnp.asarray(theta)


_FRONT_REGION = FrontRegion()


def _is_front(distribution: AbstractStressDistribution) -> bool:
    """Whether the distribution is the thesis's front region (`FrontRegion()`; the
    functions that accept None for it convert it first, `_as_distribution`)."""
    return isinstance(distribution, FrontRegion)


def _as_distribution(distribution) -> AbstractStressDistribution:
    """`FrontRegion()` for None (the short spelling of the front region)."""
    return _FRONT_REGION if distribution is None else distribution


class WongReece(AbstractStressDistribution):
    """Wong & Reece (1967) stress distribution around the rim.

    Wong, J. Y. & Reece, A. R. (1967), "Prediction of rigid wheel performance based on
    the analysis of soil–wheel stresses, Part I", *J. Terramechanics* 4(1):81-98.

    - maximum-stress angle `theta_m = (c1 + c2 i) theta0` (i the slip);
    - exit (rear) angle `theta_r = c3 theta0` (negative behind the vertical);
    - front region theta_m <= theta <= theta0: `sigma(z(theta))`, the terrain's
      pressure–sinkage law at the rim sinkage z(theta) = r (cos theta - cos theta0);
    - rear region theta_r <= theta <= theta_m: sigma at the mirrored angle
      `theta* = theta0 - (theta - theta_r) / (theta_m - theta_r) (theta0 - theta_m)`;
    - shear stress from the shear displacement (4.10) over the whole contact; the
      resultants integrate over theta_r ... theta0.

    **Fields** (array leaves: they broadcast, vmap and differentiate like terrain
    parameters): `c1` [-], `c2` [-], `c3` [-] (default 0: the contact ends under the
    axle).  Wong & Reece give c1 ~ 0.43, c2 ~ 0.32 for sand.

    **Valid range** (checked per element; invalid elements get `Status.INVALID_INPUT`,
    concrete inputs raise `ValueError`): `0 <= c1 + c2 i < 1` and `-1 < c3 <= c1 + c2 i`.
    """

    __check_init__ = _check_real_leaves

    c1: Float[Array, "..."] = eqx.field(
        converter=_as_float, metadata=parameter("-", "theta_m / theta0 at zero slip", scale=0.1)
    )
    c2: Float[Array, "..."] = eqx.field(
        converter=_as_float,
        metadata=parameter("-", "slope of theta_m / theta0 in the slip", scale=0.1),
    )
    c3: Float[Array, "..."] = eqx.field(
        converter=_as_float, metadata=parameter("-", "theta_r / theta0", scale=0.1), default=0.0
    )

    def angle_fractions(self, slip: Float[ArrayLike, "..."]) -> tuple[Array, Array]:
        """(theta_m / theta0, theta_r / theta0) = (c1 + c2 i, c3) at driving slip i [-]."""
        return self.c1 + self.c2 * slip, self.c3 + 0.0 * slip

    mirrors_rear: ClassVar[bool] = True

    def exit_angle(self, entry_angle, slip):
        """theta_r = c3 theta0 [rad]."""
        return self.c3 * entry_angle

    def rear_region(self, entry_angle, slip):
        """(theta_m, theta_r) = ((c1 + c2 i) theta0, c3 theta0) [rad]: the rear region
        carries the front's stresses mirrored linearly (`stress_angle`)."""
        return (self.c1 + self.c2 * slip) * entry_angle, self.c3 * entry_angle

    def breakpoints(self, entry_angle, slip):
        """(theta_m,) = ((c1 + c2 i) theta0,) [rad], the peak of the normal stress."""
        return ((self.c1 + self.c2 * slip) * entry_angle,)

    def stress_angle(self, theta, entry_angle, slip):
        """theta in the front region; in the rear, the mirrored front angle
        theta0 - (theta - theta_r) / (theta_m - theta_r) (theta0 - theta_m) [rad]."""
        theta_m = (self.c1 + self.c2 * slip) * entry_angle
        theta_r = self.c3 * entry_angle
        span = jnp.where(theta_m > theta_r, theta_m - theta_r, 1.0)
        mirrored = entry_angle - (theta - theta_r) / span * (entry_angle - theta_m)
        return jnp.where(theta >= theta_m, theta, mirrored)

    def rear_angles(self, angle, entry_angle, slip):
        """The rear angle theta_r + (theta0 - angle) / (theta0 - theta_m) (theta_m - theta_r)
        whose mirrored front angle is `angle` [rad]."""
        theta0 = jnp.asarray(entry_angle)
        theta_m = (self.c1 + self.c2 * slip) * theta0
        theta_r = self.c3 * theta0
        span = jnp.where(theta0 > theta_m, theta0 - theta_m, 1.0)
        return (theta_r + (theta0 - angle) / span * (theta_m - theta_r),)

    def constraints(self, slip) -> list[tuple[str, Array, Array, str]]:
        """Validity per element: (name, value, ok mask, allowed range)."""
        fm, fr = WongReece.angle_fractions(self, slip)
        return [
            ("distribution.c1 + c2 * slip", fm, (fm >= 0) & (fm < 1), "in [0, 1)"),
            (
                "distribution.c3",
                self.c3 + 0.0 * fm,
                (fr > -1) & (fr <= fm),
                "in (-1, c1 + c2 * slip]",
            ),
        ]

    @classmethod
    def reference(cls) -> "WongReece":
        """c1 = 0.43, c2 = 0.32, c3 = 0 (Wong & Reece 1967, sand)."""
        return cls(c1=0.43, c2=0.32, c3=0.0)
