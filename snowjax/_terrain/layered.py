"""Layered snow: two Wong snow layers separated by an ice layer that fails, on a hard base."""

from __future__ import annotations

from typing import ClassVar

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, Float

from .._constants import (
    THESIS_DIAMETER,
)
from .._leaves import _as_float, parameter
from .base import AbstractTerrain, _half_angle_arc
from .wong import WongSnow, _xlogx, wong_pressure


class LayeredSnow(AbstractTerrain):
    """A snow cover with an ice layer between two snow layers on a hard base.

    Wong & Preston-Thomas (1983, J. Terramechanics 20(1):1-12; thesis section 2.1.2)
    measured plate pressure–sinkage curves in snow with an ice layer about 10 cm deep:
    the pressure rises as the snow above the ice compacts, climbs steeply as the
    deformation zone reaches the ice, drops suddenly when the ice breaks, then rises
    again towards the asymptote of the frozen ground.  They describe the curve *before
    as well as after* the failure of the ice layer by Wong's law (2.2/2.3), with z_w
    the depth of the ice layer before failure and that of the frozen ground after it.
    This class implements exactly that, in the total sinkage z:

    - before failure, z < z_f: `sigma = -top.p_w ln(1 - z / top.z_w)` (top.z_w = depth
      of the ice layer);
    - the ice fails when sigma reaches `ice_failure_pressure` p_f, i.e. at
      `z_f = top.z_w (1 - exp(-p_f / top.p_w))`;
    - after failure, z >= z_f: `sigma = -bottom.p_w ln(1 - z / bottom.z_w)`
      (bottom.z_w = depth of the frozen ground, the base).  The pressure drops from p_f
      to `-bottom.p_w ln(1 - z_f / bottom.z_w)` at z_f and then rises to the base
      asymptote.

    The shear strength and modulus are those of `top` before failure and of `bottom`
    after it.  On a rolling wheel every soil element under the front of the rim is
    loaded monotonically, so a law in z alone is the loading path of each element.
    Because the pressure drops, the wheel's vertical load W(theta0) need not be
    monotone; `solve_wheel` then returns the shallowest equilibrium (the sinkage a wheel
    reaches when lowered from the surface).

    **Fields:** `top`, `bottom`: `WongSnow` parameter sets of the two layers
    (top.z_w < bottom.z_w, both measured from the surface [m]); `ice_failure_pressure`:
    p_f, the pressure at which the ice layer breaks [Pa].
    """

    top: WongSnow
    bottom: WongSnow
    ice_failure_pressure: Float[Array, "..."] = eqx.field(
        converter=_as_float,
        metadata=parameter(
            "Pa",
            "pressure p_f at which the ice layer breaks",
            lower=0.0,
            open_lower=True,
            scale=1e4,
        ),
    )

    label: ClassVar[str] = "snow"

    # An explicit constructor: type checkers read the AbstractVar shear-strength fields,
    # which the properties below implement, as constructor arguments of the dataclass.
    def __init__(self, top: WongSnow, bottom: WongSnow, ice_failure_pressure):
        self.top = top
        self.bottom = bottom
        self.ice_failure_pressure = ice_failure_pressure

    @property
    def cohesion(self) -> Array:
        """c [Pa] of the top layer (the surface)."""
        return self.top.cohesion

    @property
    def tan_phi(self) -> Array:
        """tan phi [-] of the top layer (the surface)."""
        return self.top.tan_phi

    @property
    def shear_modulus(self) -> Array:
        """K [m] of the top layer (the surface)."""
        return self.top.shear_modulus

    def breakpoint_sinkages(self) -> tuple[Array, ...]:
        """(z_f,): the sinkage [m] where the ice breaks and the pressure drops."""
        return (self.failure_sinkage,)

    def logarithmic_base(self) -> bool:
        """True: the bottom layer's Wong law at the frozen ground."""
        return True

    def pressure_rises(self) -> bool:
        """False: the pressure drops where the ice breaks (static)."""
        return False

    @property
    def failure_sinkage(self) -> Array:
        """z_f = top.z_w (1 - exp(-p_f / top.p_w)): sinkage at which the ice breaks [m]."""
        return -self.top.z_w * jnp.expm1(-self.ice_failure_pressure / self.top.p_w)

    def pressure(self, sinkage, width=None):
        """Normal stress [Pa] at sinkage z [m] (see the class docstring); `width` unused."""
        return self.rim_properties(sinkage, width)[0]

    def rim_properties(self, sinkage, width=None):
        z = jnp.asarray(sinkage)
        before = z < self.failure_sinkage
        sigma = jnp.where(
            before,
            wong_pressure(jnp.where(before, z, 0.0), self.top.p_w, self.top.z_w),
            wong_pressure(z, self.bottom.p_w, self.bottom.z_w),
        )
        pick = lambda a, b: jnp.where(before, a, b)  # noqa: E731
        return (
            sigma,
            pick(self.top.cohesion, self.bottom.cohesion),
            pick(self.top.tan_phi, self.bottom.tan_phi),
            pick(self.top.shear_modulus, self.bottom.shear_modulus),
        )

    @property
    def depth(self) -> Array:
        """bottom.z_w: depth of the frozen ground [m]."""
        return self.bottom.z_w

    def pressure_at_clearance(self, clearance, width=None):
        """The law at `clearance` [m] above the frozen ground [Pa], with one logarithm:
        `-p_w ln(h / z_w)` of the layer that acts, h the clearance above that layer's
        base (the frozen ground below the ice's failure: the bottom layer's Wong law
        written without cancellation, `WongSnow.pressure_at_clearance`; above it the
        top layer's, h = top.z_w - z); `+inf` on the frozen ground."""
        clearance = jnp.asarray(clearance)
        after = self.depth - clearance >= self.failure_sinkage
        top, bottom = self.top, self.bottom
        # The layer's clearance over its z_w: one reciprocal per parameter set.  Above
        # the failure the top layer's is at least its value there, exp(-p_f / top.p_w)
        # (kept so where clearance - (bottom.z_w - top.z_w) loses its digits: float32,
        # p_f >> top.p_w).
        above_top_base = clearance - (bottom.z_w - top.z_w)
        top_ratio = jnp.maximum(above_top_base * (1 / top.z_w), self._failure_ratio)
        ratio = jnp.where(after, clearance * (1 / bottom.z_w), top_ratio)
        return -jnp.where(after, bottom.p_w, top.p_w) * jnp.log(ratio)

    @property
    def _failure_ratio(self) -> Array:
        """1 - z_f / top.z_w = exp(-p_f / top.p_w) [-]: the top layer's Z where the ice
        breaks."""
        return jnp.exp(-self.ice_failure_pressure / self.top.p_w)

    def front_rim_integrals(self, entry_angle, diameter, clearance):
        """Exact `int_0^theta0 sigma cos` and `int_0^theta0 sigma sin` [Pa] on the front
        region of a rim of diameter D [m] whose lowest point lies `clearance` [m] above
        the frozen ground (`AbstractTerrain.front_rim_integrals`).

        The rim point at theta is z = D [sin^2(theta0 / 2) - sin^2(theta / 2)] deep
        (4.5): the bottom layer's law holds from the axle to theta_f, where z reaches the
        failure sinkage z_f (`WongSnow.rim_integrals_to` of the bottom layer, at the
        clearance above the frozen ground), the top layer's from theta_f to theta0
        (theta_f = 0 where the contact stays above z_f).  On the top layer's part, with
        Z = 1 - z / top.z_w = Z0 + 2 a sin^2(theta / 2) (a = D / (2 top.z_w); Z0 < 0
        where the rim reaches below the top layer's z_w, which only the bottom layer's
        part does) and Z_f = Z(theta_f), integration by parts as in
        `WongSnow.front_rim_integrals` (Z(theta0) = 1) gives `int sigma cos = p_w ln(Z_f)
        sin(theta_f) + p_w a int sin^2 / Z` and `int sigma sin = (p_w / a)(1 - Z_f + Z_f
        ln Z_f)`; `a int_(theta_f)^(theta0) sin^2 / Z = [sin + (Z0 + a) theta / a] + K`
        with, in t = tan(theta / 2) and u = sqrt(Z0 + 2 a), `K = -(Z0 u^2 / a) int 2 dt /
        (Z0 + u^2 t^2) = -(2 / a) Z0 u x phi(Z0 x^2)`, x = u (t0 - t_f) / (Z0 + u^2 t_f
        t0), phi(y) = atan(sqrt y) / sqrt y (y > 0), atanh(sqrt -y) / sqrt -y (y < 0), 1
        at 0: the difference of the two ends' arctangents (or, Z0 < 0, logarithms)
        taken as one, so that neither sign of Z0 nor Z0 -> 0 loses digits.
        """
        top, bottom = self.top, self.bottom
        s_0 = jnp.sin(entry_angle / 2) ** 2
        theta_f = _half_angle_arc(s_0 - self.failure_sinkage / diameter)
        cos_b, sin_b = bottom.rim_integrals_to(theta_f, diameter, clearance)
        a = diameter / (2 * top.z_w)
        z0_rel = (clearance - (bottom.z_w - top.z_w)) / top.z_w
        # Z_f = exp(-p_f / top.p_w) where the contact reaches the failure, else Z0 (above
        # it): neither from Z0 + 2 a sin^2(theta_f / 2), which cancels where Z_f is small.
        failure = self._failure_ratio
        z_f = jnp.where(theta_f > 0, failure, jnp.maximum(z0_rel, failure))
        t_f, t_0 = jnp.tan(theta_f / 2), jnp.tan(entry_angle / 2)
        u2 = z0_rel + 2 * a
        u = jnp.sqrt(u2)
        # Z0 + u^2 t_f t0 = Z_f (1 + t_f^2) + u^2 t_f (t0 - t_f): two positive terms.
        rise = u * (t_0 - t_f)
        den = z_f * (1 + t_f**2) + u2 * t_f * (t_0 - t_f)
        x = rise / den
        # Z0 < 0 (beta = sqrt(-Z0)): K = (beta u / a) ln((den + beta rise) / (den - beta
        # rise)), den - beta rise = Z_f (1 + t_f^2)(1 + rise / (u t_f + beta)) without
        # the cancellation that leaves float32 no digits where Z_f is small.
        beta = jnp.sqrt(jnp.maximum(-z0_rel, 0.0))
        below = z0_rel < 0
        spread = jnp.where(below, u * t_f + beta, 1.0)
        near = z_f * (1 + t_f**2) * (1 + rise / spread)
        logs = beta * u / a * jnp.log(jnp.where(below, (den + beta * rise) / near, 1.0))
        arcs = -2 / a * z0_rel * u * x * _atan_ratio(jnp.maximum(z0_rel, 0.0) * x**2)
        turn = (
            jnp.sin(entry_angle) - jnp.sin(theta_f)
            + (z0_rel + a) * (entry_angle - theta_f) / a
            + jnp.where(below, logs, arcs)
        )  # fmt: skip
        cos_t = top.p_w * (jnp.log(z_f) * jnp.sin(theta_f) + turn)
        sin_t = top.p_w / a * (1 - z_f + _xlogx(z_f))
        return cos_b + cos_t, sin_b + sin_t

    def constraints(self):
        bottom_deeper = self.bottom.z_w > self.top.z_w
        return [
            *AbstractTerrain.constraints(self),
            ("bottom.z_w", self.bottom.z_w, bottom_deeper, "> top.z_w (m)"),
        ]

    @classmethod
    def reference(cls) -> "LayeredSnow":
        return cls.ice_layer_example()

    @classmethod
    def ice_layer_example(cls, diameter: float = THESIS_DIAMETER) -> "LayeredSnow":
        """Snow with an ice layer 10 cm deep over snow on frozen ground 30 cm deep.

        Modelled on the cover Wong & Preston-Thomas (1983) measured (ice about 10 cm
        below the surface; thesis section 2.1.2).  Their fitted values are not in the
        thesis, so both layers take the thesis's fresh-snow strength ratios
        (`WongSnow.thesis_fresh_snow`): top p_w 30 kPa, z_w 0.10 m; bottom p_w 40 kPa,
        z_w 0.30 m; the ice breaks at 60 kPa (z_f = 8.65 cm, where the pressure drops
        to 13.6 kPa).  An illustrative cover for the wheel, not a measured one.

        **Arguments:** `diameter`: wheel diameter the shear-modulus ratio refers to [m].
        """
        top = WongSnow.thesis_fresh_snow(diameter=diameter, p_w=30e3)
        bottom = WongSnow.thesis_fresh_snow(diameter=diameter, p_w=40e3)
        top = eqx.tree_at(lambda s: s.z_w, top, jnp.asarray(0.10))
        bottom = eqx.tree_at(lambda s: s.z_w, bottom, jnp.asarray(0.30))
        return cls(top=top, bottom=bottom, ice_failure_pressure=60e3)


def _atan_ratio(y):
    """atan(sqrt y) / sqrt y for y >= 0, 1 at y = 0 (a series below 1e-4, where the
    quotient loses digits)."""
    small = y < 1e-4
    root = jnp.sqrt(jnp.where(small, 1.0, y))
    return jnp.where(small, 1 - y / 3 + y * y / 5, jnp.arctan(root) / root)
