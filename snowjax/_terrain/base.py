"""The abstract terrain every wheel model runs on, and helpers shared by the laws.

All values are SI: Pa, m, N/m^(n+1), N/m^(n+2).
"""

from __future__ import annotations

import abc
from typing import ClassVar

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float

from .._leaves import _check_real_leaves


def _clip_negative(x) -> Array:
    """max(x, 0) with gradient 1 at x = 0 (jnp.maximum would split it 1/2 : 1/2)."""
    x = jnp.asarray(x)
    return jnp.where(x >= 0, x, 0.0)


def _safe_power(x: Array, n: Array) -> Array:
    """`x**n` for x >= 0 whose value *and gradient* are finite at x = 0."""
    positive = x > 0
    safe_x = jnp.where(positive, x, 1.0)
    return jnp.where(positive, safe_x**n, 0.0)


class Terrain(eqx.Module):
    """A terrain the rigid wheel can run on: a pressure–sinkage law plus shear strength.

    Subclasses (`WongSnow`, `BekkerSoil`, `ReeceSoil`, `LayeredSnow`) hold their physical
    parameters as array leaves, so they broadcast, vmap and differentiate like the rest
    of snowjax.  The wheel needs three things from a terrain:

    - `pressure(sinkage, width)`: the normal stress sigma [Pa] under a plate of the
      given width [m] at sinkage z [m] (the rim stress law of the wheel, eq. 4.1b for
      Wong's snow);
    - `rim_properties(sinkage, width)`: sigma plus the Mohr–Coulomb cohesion [Pa],
      tan(phi) [-] and Janosi–Hanamoto shear modulus K [m] that act at that sinkage;
    - `depth`: the depth of the hard base [m] (`inf` for an infinitely deep terrain), the
      largest sinkage the wheel can reach.
    """

    __check_init__ = _check_real_leaves

    #: Prefix used in error messages ("snow.p_w must be ...").
    label: ClassVar[str] = "terrain"

    @abc.abstractmethod
    def pressure(
        self, sinkage: Float[ArrayLike, "..."], width: Float[ArrayLike, "..."]
    ) -> Float[Array, "..."]:
        """Normal stress sigma [Pa] at sinkage z [m] under a contact of width b [m]."""

    def rim_properties(
        self, sinkage: Float[ArrayLike, "..."], width: Float[ArrayLike, "..."]
    ) -> tuple[Array, Array, Array, Array]:
        """(sigma [Pa], cohesion c [Pa], tan phi [-], shear modulus K [m]) at sinkage z [m]."""
        sigma = self.pressure(sinkage, width)
        return sigma, self.cohesion, self.tan_phi, self.shear_modulus  # type: ignore[attr-defined]

    @property
    def depth(self) -> Array:
        """Depth of the hard base below the surface [m]; `inf` when there is none."""
        return jnp.full_like(jnp.asarray(self.cohesion), jnp.inf)  # type: ignore[attr-defined]

    def constraints(self, shear: str = "classic") -> list[tuple[str, Array, Array, str]]:
        """Validity of each parameter: (field name, value, ok mask, allowed range)."""
        return [
            ("cohesion", self.cohesion, self.cohesion >= 0, ">= 0 Pa"),  # type: ignore[attr-defined]
            ("tan_phi", self.tan_phi, self.tan_phi >= 0, ">= 0"),  # type: ignore[attr-defined]
            ("shear_modulus", self.shear_modulus, self.shear_modulus > 0, "> 0 m"),  # type: ignore[attr-defined]
        ]

    def wheel_constraints(self, width) -> list[tuple[str, Array, Array, str]]:
        """Rules that involve the wheel width b [m] (e.g. a positive Bekker modulus)."""
        return []

    @classmethod
    @abc.abstractmethod
    def reference(cls) -> "Terrain":
        """A valid parameter set of this kind (stands in for invalid batch elements)."""
