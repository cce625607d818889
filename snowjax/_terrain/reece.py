"""Reece's pressure–sinkage law (eq. 2.4) and `ReeceSoil`."""

from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float

from .._constants import (
    DEFAULT_SHEAR_MODULUS,
)
from .._leaves import _as_float, parameter
from .base import (
    COHESION,
    SHEAR_MODULUS,
    TAN_PHI,
    AbstractTerrain,
    _clip_negative,
    _safe_power,
)


def reece_pressure(
    sinkage: Float[ArrayLike, "..."],
    width: Float[ArrayLike, "..."],
    cohesion: Float[ArrayLike, "..."],
    unit_weight: Float[ArrayLike, "..."],
    k_c_prime: Float[ArrayLike, "..."],
    k_phi_prime: Float[ArrayLike, "..."],
    n: Float[ArrayLike, "..."],
) -> Float[Array, "..."]:
    """Reece's pressure–sinkage law, eq. (2.4).

    `sigma = (c k'_c + gamma_s b k'_phi) (z / b)^n`.

    **Arguments:**

    - `sinkage`: z [m], clipped at 0.
    - `width`: b, smaller dimension of the plate or contact patch [m].
    - `cohesion`: c [Pa].
    - `unit_weight`: gamma_s, weight density of the terrain [N/m^3].
    - `k_c_prime`, `k_phi_prime`: dimensionless Reece moduli [-].
    - `n`: sinkage exponent [-].

    **Returns:** normal pressure sigma [Pa].
    """
    b = jnp.asarray(width)
    z = _clip_negative(sinkage)
    modulus = jnp.asarray(cohesion) * k_c_prime + jnp.asarray(unit_weight) * b * k_phi_prime
    return modulus * _safe_power(z / b, jnp.asarray(n))


class ReeceSoil(AbstractTerrain):
    """A terrain described by Reece's pressure–sinkage law (2.4) and Mohr–Coulomb (2.5).

    On the wheel, `sigma = (c k'_c + gamma_s b k'_phi) (z / b)^n` with b the wheel width
    (Reece 1965; Wong & Reece 1967 use it for the rigid wheel).  Infinitely deep.

    **Fields:**

    - `n`: sinkage exponent [-].
    - `k_c_prime`, `k_phi_prime`: Reece's dimensionless moduli k'_c, k'_phi [-].
    - `unit_weight`: gamma_s, the terrain's weight density [N/m^3].
    - `cohesion`: c [Pa].
    - `tan_phi`: tangent of the internal friction angle [-].
    - `shear_modulus`: K [m] (keyword; default `DEFAULT_SHEAR_MODULUS` = 10 mm).
    """

    n: Float[Array, "..."] = eqx.field(
        converter=_as_float,
        metadata=parameter("-", "sinkage exponent (2.4)", lower=0.0, open_lower=True),
    )
    k_c_prime: Float[Array, "..."] = eqx.field(
        converter=_as_float, metadata=parameter("-", "Reece's cohesive modulus k'_c (2.4)")
    )
    k_phi_prime: Float[Array, "..."] = eqx.field(
        converter=_as_float, metadata=parameter("-", "Reece's frictional modulus k'_phi (2.4)")
    )
    unit_weight: Float[Array, "..."] = eqx.field(
        converter=_as_float,
        metadata=parameter(
            "N/m^3", "weight density gamma_s of the terrain (2.4)", lower=0.0, scale=1e4
        ),
    )
    cohesion: Float[Array, "..."] = eqx.field(converter=_as_float, metadata=COHESION)
    tan_phi: Float[Array, "..."] = eqx.field(converter=_as_float, metadata=TAN_PHI)
    shear_modulus: Float[Array, "..."] = eqx.field(
        converter=_as_float, metadata=SHEAR_MODULUS, default=DEFAULT_SHEAR_MODULUS, kw_only=True
    )

    def sinkage_at_pressure(self, pressure, width, limit):
        """Reece's law (2.4) inverted, `z = b (sigma / (c k'_c + gamma_s b k'_phi))^(1/n)`
        [m], capped at `limit` [m]."""
        modulus = self.cohesion * self.k_c_prime + self.unit_weight * width * self.k_phi_prime
        ratio = jnp.asarray(pressure / modulus)
        return jnp.minimum(width * _safe_power(ratio, 1 / self.n), limit)

    def pressure(self, sinkage, width):
        """Reece's law (2.4), `sigma = (c k'_c + gamma_s b k'_phi)(z / b)^n` [Pa]."""
        return reece_pressure(
            sinkage,
            width,
            self.cohesion,
            self.unit_weight,
            self.k_c_prime,
            self.k_phi_prime,
            self.n,
        )

    def wheel_constraints(self, width):
        modulus = self.cohesion * self.k_c_prime + self.unit_weight * width * self.k_phi_prime
        return [("c k'_c + gamma_s b k'_phi", modulus, modulus > 0, "> 0 at the wheel width b")]

    @classmethod
    def reference(cls) -> "ReeceSoil":
        # Any valid set (stands in for invalid batch elements); not a published soil.
        return cls(
            n=1.0, k_c_prime=1.0, k_phi_prime=1000.0, unit_weight=15e3, cohesion=1e3, tan_phi=0.5
        )
