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

The unloading line is never softer than the virgin law's tangent at z_u: k_u = max(k_0 +
A_u z_u, dsigma/dz(z_u)) (this package's choice: an unloading path is elastic, and an
elastic modulus below the tangent modulus of the plastic loading curve would make the
rebound outgrow the compaction).  With it the floor z_r = max(z_u - p_u / k_u, 0) never
rises as z_u grows: where the tangent governs, dz_r/dz_u = p_u sigma'' / sigma'^2 >= 0 on
a law that is convex there (Wong's, Bekker's with n >= 1), and on a concave law with
sigma(0) = 0 (Bekker's n < 1) p_u / sigma' >= z_u, so the floor is the surface; where
k_0 + A_u z_u governs, dz_r/dz_u >= 1 - sigma' / k_u >= 0.  Where the law drops at a
breakpoint (`LayeredSnow`'s ice failure) so does the rebound's pressure, but not always
the ratio to a softer tangent: there the floor is kept at least as deep as a rut ending
just above the breakpoint leaves it (a running maximum over the breakpoints).  On Wong
snow the tangent p_w / (z_w - z_u) governs near the base, and the rebound (z_w - z_u)
ln(z_w / (z_w - z_u)) vanishes there: a rut pressed to the base (a bottomed-out leader, z_u = z_w,
p_u = +inf) has its floor on the base, and a later wheel rests on the base.

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
import jax
import jax.numpy as jnp
from jaxtyping import Array, Float

from .._leaves import _as_float, parameter
from .base import AbstractTerrain, _half_angle_arc

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

    def _rebound(self, z_u) -> Array:
        """min(p_u / k_u, z_u) [m] of a rut of depth `z_u` [m], k_u = max(k_0 + A_u z_u,
        dsigma/dz(z_u)) (module docstring); 0 for a rut pressed to the base (p_u infinite:
        nothing left to spring back)."""
        p_u, tangent = jax.jvp(
            lambda z: self.virgin.pressure(z, self.width), (z_u,), (jnp.ones_like(z_u),)
        )
        finite = jnp.isfinite(p_u) & jnp.isfinite(tangent)
        k_u = jnp.maximum(self.k_0 + self.a_u * z_u, jnp.where(finite, tangent, 0.0))
        return jnp.where(finite, jnp.minimum(jnp.where(finite, p_u, 0.0) / k_u, z_u), 0.0)

    @property
    def floor_depth(self) -> Array:
        """z_r [m]: the rut's floor below the original surface, z_u - min(p_u / k_u, z_u),
        and no shallower than the floor a rut ending just above one of the virgin law's
        breakpoints would have (module docstring: where the law drops, as at
        `LayeredSnow`'s ice failure, a deeper rut would otherwise rebound more)."""
        z_u = self.rut_sinkage
        floor = z_u - self._rebound(z_u)
        for end in self.virgin.breakpoint_sinkages():
            fixed = jax.lax.stop_gradient(end)
            below = end - (fixed - jnp.nextafter(fixed, jnp.zeros_like(fixed)))
            floor = jnp.where(end <= z_u, jnp.maximum(floor, below - self._rebound(below)), floor)
        return floor

    @property
    def reloading_depth(self) -> Array:
        """d = z_u - z_r [m]: the depth of the reloading branch below the floor (the
        elastic rebound)."""
        return self.rut_sinkage - self.floor_depth

    def pressure(self, sinkage, width):
        """sigma' [Pa] at the sinkage z' [m] below the rut's floor (module docstring)."""
        return self.rim_properties(sinkage, width)[0]

    def rim_properties(self, sinkage, width):
        z = jnp.asarray(sinkage)
        d = self.reloading_depth
        # The virgin law at most 4 ulp above its base (a rut pressed to the base has its
        # floor there, where a law such as Wong's is infinite).
        eps = jnp.finfo(jnp.result_type(z, float)).eps
        virgin_z = jnp.minimum(z + self.rut_sinkage - d, self.virgin.depth * (1 - 4 * eps))
        sigma, cohesion, tan_phi, modulus = self.virgin.rim_properties(virgin_z, width)
        reloading = z < d
        sigma = jnp.where(reloading, self._reloading(jnp.where(reloading, z, 0.0), d, width), sigma)
        return sigma, cohesion, tan_phi, modulus

    def _reloading(self, sinkage, d, width) -> Array:
        """The reloading line's sigma' = p_u z' / d [Pa] at the sinkage z' [m] below the
        floor, d [m] the `reloading_depth` (0 for a rut of no reloading depth)."""
        # The slope first: one product per point (a quadrature calls this at every node).
        return (self._loaded_pressure(width) / jnp.where(d > 0, d, 1.0)) * sinkage

    def _loaded_pressure(self, width) -> Array:
        """p_u [Pa]: the virgin law's pressure at the rut's depth z_u (0 where it is
        infinite: a rut pressed to the base, whose reloading depth is 0)."""
        p_u = self.virgin.pressure(self.rut_sinkage, width)
        return jnp.where(jnp.isfinite(p_u), p_u, 0.0)

    @property
    def depth(self) -> Array:
        """The virgin base's depth below the rut's floor [m]."""
        return self.virgin.depth - self.floor_depth

    def pressure_at_clearance(self, clearance, width):
        """sigma' [Pa] at `clearance` [m] above the base: the virgin law's own
        (`AbstractTerrain.pressure_at_clearance`, free of cancellation near a base where
        it diverges) beyond the reloading branch, the reloading line within it."""
        sinkage, d = self.depth - clearance, self.reloading_depth
        reloading = sinkage < d
        virgin = self.virgin.pressure_at_clearance(clearance, width)
        line = self._reloading(jnp.where(reloading, sinkage, 0.0), d, width)
        return jnp.where(reloading, line, virgin)

    def closed_form_rim(self) -> bool:
        """Whether the rut offers closed forms of its rim integrals (static): where the
        virgin law offers them to any angle (`rim_integrals_to`: `WongSnow`) and has no
        breakpoint of its own (the reloading line adds one kink, where the closed-form
        rule cuts its panels)."""
        virgin = type(self.virgin)
        return (
            virgin.rim_integrals_to is not AbstractTerrain.rim_integrals_to
            and virgin.breakpoint_sinkages is AbstractTerrain.breakpoint_sinkages
        )

    def front_rim_integrals(self, entry_angle, diameter, clearance):
        """Exact `int_0^theta0 sigma' cos` and `int_0^theta0 sigma' sin` [Pa] on the rim
        (`AbstractTerrain.front_rim_integrals`), for a virgin law that offers
        `rim_integrals_to` (`closed_form_rim`).

        The rim point at theta is z' = D [sin^2(theta0 / 2) - sin^2(theta / 2)] below the
        floor: the virgin law holds from the axle to theta_d, where z' = d, at the rim
        point's own clearance above the base (the virgin's `rim_integrals_to`), and the
        reloading line sigma' = (p_u / d) z' from theta_d to theta0, whose integrals are
        `(p_u / d) r [(theta0 - theta_d) / 2 + (sin 2 theta0 - sin 2 theta_d) / 4 - cos
        theta0 (sin theta0 - sin theta_d)]` and `(p_u / d) r (cos theta_d - cos
        theta0)^2 / 2`.  Where z' < d everywhere theta_d = 0; a rut of zero depth has
        theta_d = theta0.  The virgin law's closed forms take no width (p_u is the
        virgin's at the earlier wheel's width, as the protocol's laws are
        width-independent).
        """
        d = self.reloading_depth
        p_u = self.virgin.pressure(self.rut_sinkage, self.width)
        slope = jnp.where((d > 0) & jnp.isfinite(p_u), p_u / jnp.where(d > 0, d, 1.0), 0.0)
        s_0 = jnp.sin(entry_angle / 2) ** 2
        s_d = jnp.maximum(s_0 - d / diameter, 0.0)
        theta_d = _half_angle_arc(s_0 - d / diameter)
        virgin = self.virgin.rim_integrals_to(theta_d, diameter, clearance)
        if not virgin:
            raise TypeError(f"{type(self.virgin).__name__} offers no rim_integrals_to")
        cos_v, sin_v = virgin
        cos_0 = 1 - 2 * s_0
        r = diameter / 2
        cos_line = (
            (entry_angle - theta_d) / 2
            + (jnp.sin(2 * entry_angle) - jnp.sin(2 * theta_d)) / 4
            - cos_0 * (jnp.sin(entry_angle) - jnp.sin(theta_d))
        )
        sin_line = 2 * (s_0 - s_d) ** 2  # (cos theta_d - cos theta0)^2 / 2
        return cos_v + slope * r * cos_line, sin_v + slope * r * sin_line

    def breakpoint_sinkages(self) -> tuple[Array, ...]:
        """d, where reloading meets the virgin law, and the virgin law's own, shifted."""
        d = self.reloading_depth
        floor = self.rut_sinkage - d
        return (d, *(z - floor for z in self.virgin.breakpoint_sinkages()))

    def has_base(self) -> bool:
        """The virgin law's base, nearer by the floor's depth."""
        return self.virgin.has_base()

    def logarithmic_base(self) -> bool:
        """The virgin law's base (the reloading line is finite)."""
        return self.virgin.logarithmic_base()

    def pressure_rises(self) -> bool:
        """The reloading line rises, so the law rises where the virgin law does."""
        return type(self.virgin).pressure_rises(self.virgin)

    def constraints(self):
        own = [r for r in AbstractTerrain.constraints(self) if "." not in r[0]]
        shallower = self.rut_sinkage <= self.virgin.depth
        return [
            *own,
            *((f"virgin.{name}", *rest) for name, *rest in self.virgin.constraints()),
            ("rut_sinkage", self.rut_sinkage, shallower, "<= the virgin base's depth (m)"),
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
