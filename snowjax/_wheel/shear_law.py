"""Shear laws of the rim: how the shear stress mobilises along the contact.

Every function with a `shear` argument takes one of these modules or its name:
`JanosiHanamoto()` (`"classic"`, eq. 4.11), `ThesisSimplified()` (`"simplified"`,
eq. 4.13) or `NoShear()` (`"none"`).  A shear law says what it needs of the terrain and
the stress distribution (`check`): the thesis's simplified law is derived from Wong's
pressure–sinkage law on the front region of the contact.  With a slip angle the classic
law becomes the combined (lateral and longitudinal) law of `Lateral`.

The quadrature dispatches on `name`; the name is what `sweep` records and what the
command line spells.
"""

import abc
from typing import ClassVar, Literal, cast

import equinox as eqx

from .._terrain.wong import WongSnow
from .distribution import _is_front

__all__ = ["AbstractShearLaw", "JanosiHanamoto", "ThesisSimplified", "NoShear"]

ShearModel = Literal["classic", "simplified", "none"]


class AbstractShearLaw(eqx.Module):
    """A shear law of the rim (abstract): `name` is its spelling as a string."""

    name: ClassVar[str]

    @abc.abstractmethod
    def check(self, terrain, distribution) -> None:
        """Raise `ValueError` if the law does not apply to this terrain and distribution
        (`distribution` is None or `FrontRegion()` for the front region)."""


class JanosiHanamoto(AbstractShearLaw):
    """Janosi–Hanamoto on the rigid-wheel shear displacement, eq. (4.11) (`"classic"`):
    `tau = (c + sigma tan phi)[1 - exp(-j / K)]`, j from (4.10), mirrored for j < 0.
    Every terrain and distribution; with a slip angle, the combined law of `Lateral`."""

    name: ClassVar[str] = "classic"

    def check(self, terrain, distribution) -> None:
        """Applies everywhere."""


class ThesisSimplified(AbstractShearLaw):
    """The thesis's simplified shear law, eq. (4.13) (`"simplified"`): derived from Wong's
    pressure–sinkage law on the front region, so it needs a `WongSnow` and the
    front-region distribution; no slip angle, and not in the vehicle simulations (its
    braking extension can deliver power to the wheel)."""

    name: ClassVar[str] = "simplified"

    def check(self, terrain, distribution) -> None:
        """`ValueError` unless the terrain is `WongSnow` on the front region."""
        if not (_is_front(distribution) and isinstance(terrain, WongSnow)):
            raise ValueError(
                "shear='simplified' (eq. 4.13) is derived from Wong's law on the front region "
                "of the contact: it needs a WongSnow terrain and distribution=None; use "
                "shear='classic' for other terrains and for the Wong–Reece distribution."
            )


class NoShear(AbstractShearLaw):
    """No shear stress (`"none"`): the normal stress alone (motion resistance and sinkage)."""

    name: ClassVar[str] = "none"

    def check(self, terrain, distribution) -> None:
        """Applies everywhere."""


SHEAR_LAWS: dict[str, AbstractShearLaw] = {
    law.name: law for law in (JanosiHanamoto(), ThesisSimplified(), NoShear())
}


def _shear_law(shear) -> AbstractShearLaw:
    """The shear-law module for a module or its name; `ValueError` for anything else."""
    if isinstance(shear, AbstractShearLaw):
        return shear
    if isinstance(shear, str) and shear in SHEAR_LAWS:
        return SHEAR_LAWS[shear]
    raise ValueError(
        f"shear must be one of {tuple(SHEAR_LAWS)} or a snowjax shear law "
        f"(JanosiHanamoto(), ThesisSimplified(), NoShear()), got {shear!r}"
    )


def _shear_name(shear) -> ShearModel:
    """The name of a shear law given as a module or a name (checked)."""
    return cast(ShearModel, _shear_law(shear).name)
