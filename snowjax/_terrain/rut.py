"""A rut: terrain that an earlier wheel compacted, reloaded by the next wheel.

Model (Gawwad & Crolla, thesis eq. 2.21, the unloading of Bekker's law, here of any
law): an element of terrain loaded to the sinkage z_u, at the pressure p_u = sigma(z_u)
of the virgin law, unloads and reloads along the straight line

    p = p_u - k_u (z_u - z),    k_u = k_0 + A_u z_u,

and beyond z_u it follows the virgin law again.  The earlier wheel leaves the rut's
floor where that line reaches p = 0, at z_r = z_u - p_u / k_u below the original
surface (the elastic rebound p_u / k_u).  Where the line would reach zero above the
original surface (k_u z_u < p_u) the floor is the original surface (z_r = 0) and the
reloading line runs from there to (z_u, p_u): its slope is max(k_u, p_u / z_u).

p_u and with it the rebound are those of the earlier wheel's width b_1 (`width`).
`Rut` is a terrain in the sinkage z' below the rut's floor, z = z' + z_r, for a later
wheel of width b:

    sigma'(z') = sigma(z_u, b) z' / d     for z' < d = z_u - z_r  (reloading),
    sigma'(z') = sigma(z' + z_r, b)       beyond                  (the virgin law),

continuous at z' = d (a kink there, cut by the quadrature: `breakpoint_sinkages`); for
b = b_1 the reloading line is the one above.  The shear strength is the virgin
terrain's at the same depth; the base is z_r nearer.  A rut of zero depth (z_u = 0) is
the virgin terrain exactly.

Choices that are this package's: the rut is described by its depth z_u (the pressure
the earlier wheel reached is the virgin law's at z_u); a later wheel of another width
keeps the rut's floor and meets its own virgin law at z_u (the plate-size term of the
law), and runs in the same track (a wheel offset from the rut, or wider than it, is not
yet split between the rut and the virgin snow beside it); the compaction changes only
the pressure–sinkage law, not the shear strength.
"""

from __future__ import annotations

from typing import ClassVar

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, Float

from .._leaves import _as_float, parameter
from .base import AbstractTerrain

__all__ = ["Rut"]

# The earlier wheel's width [m] and k_0 [Pa/m], A_u [Pa/m^2] of the reference rut and of
# the stand-in for invalid batch elements.
_REFERENCE = (0.235, 5e6, 0.0)


class Rut(AbstractTerrain):
    """Terrain compacted by an earlier wheel to the sinkage z_u, reloaded along the
    unloading line of Gawwad & Crolla (thesis eq. 2.21) below z_u and along the virgin
    law beyond (see `snowjax._terrain.rut` for the model and its choices).  Sinkages are
    measured below the rut's floor.

    **Fields:**

    - `virgin`: the terrain before the earlier wheel (any `AbstractTerrain`).
    - `rut_sinkage`: z_u [m], >= 0: the earlier wheel's sinkage (e.g. its
      `WheelState.sinkage`; gradients flow through it).
    - `width`: b_1 [m], > 0: the earlier wheel's width.
    - `k_0`: unloading modulus at zero sinkage [Pa/m], > 0.
    - `a_u`: its growth with z_u [Pa/m^2], >= 0 (k_u = k_0 + A_u z_u).
    """

    virgin: AbstractTerrain
    rut_sinkage: Float[Array, "..."] = eqx.field(
        converter=_as_float,
        metadata=parameter("m", "sinkage z_u the earlier wheel reached", lower=0.0, scale=0.05),
    )
    width: Float[Array, "..."] = eqx.field(
        converter=_as_float,
        metadata=parameter("m", "width b_1 of the earlier wheel", lower=0.0, open_lower=True),
    )
    k_0: Float[Array, "..."] = eqx.field(
        converter=_as_float,
        metadata=parameter(
            "Pa/m", "unloading modulus at zero sinkage k_0", lower=0.0, open_lower=True, scale=1e6
        ),
    )
    a_u: Float[Array, "..."] = eqx.field(
        converter=_as_float,
        metadata=parameter("Pa/m^2", "growth A_u of the unloading modulus", lower=0.0, scale=1e7),
    )

    label: ClassVar[str] = "rut"

    def __init__(self, virgin: AbstractTerrain, rut_sinkage, width, k_0, a_u):
        self.virgin = virgin
        self.rut_sinkage = rut_sinkage
        self.width = width
        self.k_0 = k_0
        self.a_u = a_u

    @property
    def cohesion(self) -> Array:
        """c [Pa] of the virgin terrain at its surface."""
        return self.virgin.cohesion

    @property
    def tan_phi(self) -> Array:
        """tan phi [-] of the virgin terrain at its surface."""
        return self.virgin.tan_phi

    @property
    def shear_modulus(self) -> Array:
        """K [m] of the virgin terrain at its surface."""
        return self.virgin.shear_modulus

    @property
    def reloading_depth(self) -> Array:
        """d = min(p_u / k_u, z_u) [m]: the depth of the reloading branch below the
        floor (the elastic rebound), p_u the earlier wheel's pressure at z_u."""
        z_u = self.rut_sinkage
        p_u = self.virgin.pressure(z_u, self.width)
        return jnp.minimum(p_u / (self.k_0 + self.a_u * z_u), z_u)

    @property
    def floor_depth(self) -> Array:
        """z_r = z_u - d [m]: the rut's floor below the original surface."""
        return self.rut_sinkage - self.reloading_depth

    def pressure(self, sinkage, width):
        """sigma' [Pa] at the sinkage z' [m] below the rut's floor (module docstring)."""
        return self.rim_properties(sinkage, width)[0]

    def rim_properties(self, sinkage, width):
        z = jnp.asarray(sinkage)
        d = self.reloading_depth
        p_u = self.virgin.pressure(self.rut_sinkage, width)
        sigma, cohesion, tan_phi, modulus = self.virgin.rim_properties(
            z + self.rut_sinkage - d, width
        )
        reloading = z < d
        safe_d = jnp.where(d > 0, d, 1.0)
        sigma = jnp.where(reloading, p_u * jnp.where(reloading, z, 0.0) / safe_d, sigma)
        return sigma, cohesion, tan_phi, modulus

    @property
    def depth(self) -> Array:
        """The virgin base's depth below the rut's floor [m]."""
        return self.virgin.depth - self.floor_depth

    def breakpoint_sinkages(self) -> tuple[Array, ...]:
        """d, where reloading meets the virgin law, and the virgin law's own, shifted."""
        d = self.reloading_depth
        floor = self.rut_sinkage - d
        return (d, *(z - floor for z in self.virgin.breakpoint_sinkages()))

    def pressure_rises(self) -> bool:
        """The reloading line rises, so the law rises where the virgin law does."""
        return self.virgin.pressure_rises()

    def constraints(self, shear: str = "classic"):
        own = [r for r in AbstractTerrain.constraints(self, shear) if "." not in r[0]]
        shallower = self.rut_sinkage < self.virgin.depth
        return [
            *own,
            *((f"virgin.{name}", *rest) for name, *rest in self.virgin.constraints(shear)),
            ("rut_sinkage", self.rut_sinkage, shallower, "< the virgin base's depth (m)"),
        ]

    def wheel_constraints(self, width):
        return self.virgin.wheel_constraints(width)

    def stand_in(self) -> "Rut":
        """A rut of zero depth in the virgin terrain's stand-in."""
        return Rut(type(self.virgin).stand_in(self.virgin), 0.0, *_REFERENCE)

    @classmethod
    def reference(cls) -> "Rut":
        from .wong import WongSnow

        return cls(WongSnow.reference(), 0.05, *_REFERENCE)
