"""The abstract terrain every wheel model runs on, and helpers shared by the laws.

All values are SI: Pa, m, N/m^(n+1), N/m^(n+2).
"""

import abc
from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
from equinox import AbstractVar
from jaxtyping import Array, ArrayLike, Float

from .._leaves import (
    ParameterInfo,
    _check_real_leaves,
    _own_parameter_fields,
    _parameter_infos,
    _parameter_rules,
    parameter,
)


def _clip_negative(x) -> Array:
    """max(x, 0) with gradient 1 at x = 0 (jnp.maximum would split it 1/2 : 1/2)."""
    x = jnp.asarray(x)
    return jnp.where(x >= 0, x, 0.0)


def _half_angle_arc(s) -> Array:
    """2 asin(sqrt(s)) [rad] for s > 0 (the rim angle whose sin^2(theta / 2) is s), 0
    (with a zero gradient) elsewhere."""
    inside = s > 0
    return jnp.where(inside, 2 * jnp.arcsin(jnp.sqrt(jnp.where(inside, s, 1.0))), 0.0)


def _safe_power(x: Array, n: Array) -> Array:
    """`x**n` for x >= 0 whose value *and gradient* are finite at x = 0.

    Computed as exp(n ln x): XLA:CPU's float64 `pow` costs about eight times an exp
    and a log (22 ns against 2.7 ns per element, measured), and a law's power is
    evaluated at every quadrature node; the relative error, |n ln x| ulp, stays below
    1e-14 for the sinkages and exponents of the built-in laws."""
    positive = x > 0
    safe_x = jnp.where(positive, x, 1.0)
    return jnp.where(positive, jnp.exp(n * jnp.log(safe_x)), 0.0)


class AbstractTerrain(eqx.Module):
    """A terrain the wheel can run on: a pressure–sinkage law plus shear strength.

    Subclasses (`WongSnow`, `BekkerSoil`, `ReeceSoil`, `LayeredSnow`, or a law of your
    own) hold their physical parameters as array leaves declared with
    [`snowjax.parameter`][] (unit, allowed range, fitting space on the field), so they
    broadcast, vmap and differentiate like the rest of snowjax, and the checks, the
    fit and the sweep read what they need from the fields.  The wheel needs from a
    terrain:

    - `pressure(sinkage, width)` (abstract): the normal stress sigma [Pa] under a plate
      of the given width [m] at sinkage z [m] (the rim stress law of the wheel, eq. 4.1b
      for Wong's snow);
    - `cohesion` c [Pa], `tan_phi` [-] and `shear_modulus` K [m] (abstract variables:
      fields or properties), the Mohr–Coulomb strength (2.5) and the Janosi–Hanamoto
      modulus (2.8) at the surface;
    - `rim_properties(sinkage, width)`: sigma plus the c, tan phi and K that act at that
      sinkage (default: the surface values everywhere);
    - `depth`: the depth of the hard base [m] (default `inf`: infinitely deep), the
      largest sinkage the wheel can reach;
    - `breakpoint_sinkages()`: sinkages [m] at which the law has a kink or a jump
      (default none; `LayeredSnow`'s ice failure), where the contact quadrature cuts its
      panels;
    - `front_rim_integrals(entry_angle, diameter, clearance)` and
      `pressure_at_clearance(clearance, width)`: closed forms a law can offer for the
      front region of the rim (default none; `WongSnow`'s, and a `Rut`'s on a law that
      offers `rim_integrals_to`).  With them the solver starts from the closed-form
      load balance without shear and subtracts the singularity of the normal stress at
      the axle of a wheel on the base (the closed-form rule of
      `snowjax._wheel.front_rim`); `closed_form_rim()` says whether a law offers them;
    - `rim_integrals_to(angle, diameter, clearance)`: the same integrals from the axle to
      any angle (default none; `WongSnow`'s), with which a `Rut` on the law writes its
      own;
    - `sinkage_at_pressure(pressure, width, limit)`: the inverse of the law, the sinkage
      at which it reaches a pressure (default: bisection; closed forms for the built-in
      laws), used by a deflecting tyre (`DeflectingTire`) to place its flattened tread;
    - `reference()` (abstract class method): a valid parameter set of the kind, which
      stands in for invalid batch elements.
    """

    __check_init__ = _check_real_leaves

    cohesion: AbstractVar[Float[Array, "..."]]
    tan_phi: AbstractVar[Float[Array, "..."]]
    shear_modulus: AbstractVar[Float[Array, "..."]]

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
        return sigma, self.cohesion, self.tan_phi, self.shear_modulus

    @property
    def depth(self) -> Array:
        """Depth of the hard base below the surface [m]; `inf` when there is none."""
        return jnp.full_like(jnp.asarray(self.cohesion), jnp.inf)

    def has_base(self) -> bool:
        """Whether the law has a hard base at a finite depth (static): whether the class
        overrides `depth`.  The contact quadrature then grades its nodes towards the
        lowest point of a front-region contact, where a law such as Wong's diverges."""
        return type(self).depth is not AbstractTerrain.depth

    def logarithmic_base(self) -> bool:
        """Whether the law's pressure diverges at most like -ln(clearance) at its base
        (static; default False: not known, e.g. a pole).  The any-terrain rule then
        covers a front-region contact whose lowest point lies far from the base with one
        panel (`general._far_front_base`), where a stronger singularity keeps a short
        panel of its own next to the lowest point."""
        return False

    def breakpoint_sinkages(self) -> tuple[Array, ...]:
        """Sinkages [m] where the pressure–sinkage law has a kink or a jump (none)."""
        return ()

    def pressure_rises(self) -> bool:
        """Whether the pressure never falls as the sinkage grows (static).  Default: a
        law without breakpoints; a law with breakpoints may drop at one (`LayeredSnow`'s
        ice failure), so `solve_wheel`'s cold start also evaluates W where the contact's
        deepest sinkage reaches each breakpoint (W's local maxima) to bracket the
        shallowest equilibrium.  A law with kinks only (`Rut`) says True."""
        return not type(self).breakpoint_sinkages(self)

    def front_rim_integrals(
        self,
        entry_angle: Float[ArrayLike, "..."],
        diameter: Float[ArrayLike, "..."],
        clearance: Float[ArrayLike, "..."],
    ) -> tuple[Array, Array] | None:
        """Closed forms of `int_0^theta0 sigma cos(theta) dtheta` and
        `int_0^theta0 sigma sin(theta) dtheta` [Pa] for the normal stress sigma on the front
        region of a rim of diameter D [m] at entry angle theta0 [rad] whose lowest point
        lies `clearance` [m] above the base; None (the default) if the law offers none.
        A law that offers them has a base at a finite `depth` and also overrides
        `pressure_at_clearance`.
        """
        return None

    def closed_form_rim(self) -> bool:
        """Whether the law offers `front_rim_integrals` (static): whether the class
        overrides it."""
        return type(self).front_rim_integrals is not AbstractTerrain.front_rim_integrals

    def rim_integrals_to(
        self,
        angle: Float[ArrayLike, "..."],
        diameter: Float[ArrayLike, "..."],
        clearance: Float[ArrayLike, "..."],
    ) -> tuple[Array, Array] | None:
        """Closed forms of `int_0^angle sigma cos(theta) dtheta` and `int_0^angle sigma
        sin(theta) dtheta` [Pa] on a rim of diameter D [m] whose lowest point lies
        `clearance` [m] above the base, from the lowest point to any `angle` [rad] below
        the entry angle (where sigma need not be 0); None (the default) if the law offers
        none.  A law that offers them offers `front_rim_integrals` too."""
        return None

    def pressure_at_clearance(
        self, clearance: Float[ArrayLike, "..."], width: Float[ArrayLike, "..."]
    ) -> Float[Array, "..."]:
        """Normal stress sigma [Pa] at `clearance` [m] above the base, under a contact of
        width b [m]: `pressure(depth - clearance)` by default; a law with a singularity
        at the base writes it without the cancellation of depth - clearance."""
        return self.pressure(self.depth - clearance, width)

    def sinkage_at_pressure(
        self,
        pressure: Float[ArrayLike, "..."],
        width: Float[ArrayLike, "..."],
        limit: Float[ArrayLike, "..."],
    ) -> Float[Array, "..."]:
        """Sinkage z [m] in [0, `limit`] at which the law reaches `pressure` [Pa] under a
        contact of width b [m]: the inverse of `pressure`; `limit` [m] where the law stays
        below `pressure` up to there.

        Default: 64 bisection halvings of [0, limit] (a law that rises with sinkage; for
        one that jumps, e.g. `LayeredSnow`'s ice failure, the first crossing is not
        guaranteed), then one Newton correction whose derivative is held fixed, which
        gives the exact first derivatives of the root (implicit function theorem) with
        respect to the pressure, the width and every parameter.  A law with a closed
        form overrides it.
        """
        return _bisect_pressure(self, pressure, width, 0.0, limit)

    def constraints(self) -> list[tuple[str, Array, Array, str]]:
        """Validity of each parameter: (field path, value, ok mask, allowed range).

        Read from the `ParameterInfo` of every field (`snowjax.parameter`), nested
        parameter sets included; shear-strength fields declared without one (plain
        `eqx.field`) get the standard rules (c >= 0, tan phi >= 0, K > 0).
        """
        return _parameter_rules(self, _terrain_parameter_infos(self))

    def wheel_constraints(self, width) -> list[tuple[str, Array, Array, str]]:
        """Rules that involve the wheel width b [m] (e.g. a positive Bekker modulus)."""
        return []

    @classmethod
    @abc.abstractmethod
    def reference(cls) -> "AbstractTerrain":
        """A valid parameter set of this kind (stands in for invalid batch elements)."""

    def stand_in(self) -> "AbstractTerrain":
        """A valid parameter set of this terrain's structure, which stands in for invalid
        batch elements: `reference()` by default; a terrain that wraps another (`Rut`)
        builds it around the other's."""
        return type(self).reference()


# `snowjax.Terrain`: the same class under its shorter public name.
Terrain = AbstractTerrain

# Field metadata of the shear strength every law has (`eqx.field(..., metadata=COHESION)`).
COHESION = parameter("Pa", "Mohr–Coulomb cohesion c (2.5)", lower=0.0)
TAN_PHI = parameter("-", "tangent of the internal friction angle (2.5)", lower=0.0)
SHEAR_MODULUS = parameter(
    "m",
    "Janosi–Hanamoto shear deformation modulus K (2.8, 4.11)",
    lower=0.0,
    open_lower=True,
    scale=0.01,
)
_STRENGTH = {
    "cohesion": COHESION["parameter"],
    "tan_phi": TAN_PHI["parameter"],
    "shear_modulus": SHEAR_MODULUS["parameter"],
}


def _terrain_parameter_infos(terrain) -> dict[str, ParameterInfo]:
    """`ParameterInfo` of every parameter of a terrain by field path; shear-strength
    fields declared without one (plain `eqx.field`) get the standard one."""
    infos = _parameter_infos(terrain)
    for name, info in _own_parameter_fields(type(terrain)):
        if info is None and name in _STRENGTH:
            infos[name] = _STRENGTH[name]
    return infos


def _bisect_pressure(terrain, pressure, width, lower, upper) -> Array:
    """The sinkage z [m] in [`lower`, `upper`] at which `terrain`'s law reaches `pressure`
    [Pa] (width b [m]), `upper` where it stays below it up to there: 64 bisection
    halvings, then one Newton correction whose derivative is held fixed, which gives the
    exact first derivatives of the root (implicit function theorem) with respect to the
    pressure, the width and every parameter (`AbstractTerrain.sinkage_at_pressure`)."""
    p = jnp.asarray(pressure)
    upper = jnp.asarray(upper)
    shape = jnp.broadcast_shapes(p.shape, upper.shape, jnp.shape(lower))
    dtype = jnp.result_type(p, upper, float)
    lo = jax.lax.stop_gradient(jnp.broadcast_to(jnp.asarray(lower, dtype), shape))
    hi = jnp.broadcast_to(upper, shape).astype(dtype)
    law = jax.lax.stop_gradient(terrain)
    p_stop = jax.lax.stop_gradient(p)

    def halve(_, bounds):
        lo, hi = bounds
        mid = 0.5 * (lo + hi)
        below = law.pressure(mid, jax.lax.stop_gradient(width)) < p_stop
        return jnp.where(below, mid, lo), jnp.where(below, hi, mid)

    _, z = jax.lax.fori_loop(0, 64, halve, (lo, jax.lax.stop_gradient(hi)))
    z = jax.lax.stop_gradient(z)
    sigma, slope = jax.jvp(lambda x: law.pressure(x, width), (z,), (jnp.ones_like(z),))
    reached = (sigma >= p_stop) & (slope > 0) & jnp.isfinite(slope)
    safe_slope = jax.lax.stop_gradient(jnp.where(reached, slope, 1.0))
    correction = (terrain.pressure(z, width) - jax.lax.stop_gradient(sigma)) - (p - p_stop)
    return jnp.where(reached, z - correction / safe_slope, hi)
