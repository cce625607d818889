"""Bekker's pressure–sinkage law (eq. 2.1) and `BekkerSoil` with its published presets."""

from __future__ import annotations

import math

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


def bekker_pressure(
    sinkage: Float[ArrayLike, "..."],
    width: Float[ArrayLike, "..."],
    k_c: Float[ArrayLike, "..."],
    k_phi: Float[ArrayLike, "..."],
    n: Float[ArrayLike, "..."],
) -> Float[Array, "..."]:
    """Bekker's pressure–sinkage law, eq. (2.1): `p = (k_c / b + k_phi) z^n`.

    **Arguments:**

    - `sinkage`: z [m], clipped at 0 (no pressure above the surface).
    - `width`: b, the smaller dimension of the contact patch (plate width or radius
      convention of the test) [m].
    - `k_c`: cohesive modulus [N/m^(n+1)].
    - `k_phi`: frictional modulus [N/m^(n+2)].
    - `n`: sinkage exponent [-].

    **Returns:** pressure p [Pa].
    """
    z = _clip_negative(sinkage)
    return (jnp.asarray(k_c) / jnp.asarray(width) + k_phi) * _safe_power(z, jnp.asarray(n))


class BekkerSoil(AbstractTerrain):
    """A terrain described by Bekker's pressure–sinkage law (2.1) and Mohr–Coulomb (2.5).

    On the wheel, `sigma = (k_c / b + k_phi) z^n` with b the wheel width, and the shear
    stress follows Janosi–Hanamoto (2.8 / 4.11) with modulus K.  Infinitely deep: the
    wheel never reaches a base (no `Status.BOTTOMED_OUT`).

    **Fields:**

    - `n`: sinkage exponent [-].
    - `k_c`: cohesive modulus [N/m^(n+1)].
    - `k_phi`: frictional modulus [N/m^(n+2)].
    - `cohesion`: c [Pa].
    - `tan_phi`: tangent of the internal friction angle [-].
    - `shear_modulus`: K, the Janosi–Hanamoto shear deformation modulus [m] (keyword;
      default `DEFAULT_SHEAR_MODULUS` = 10 mm, the thesis's fresh snow, Table 4.1,
      since Wong's Table 2.3 gives no K for its snows).
    """

    n: Float[Array, "..."] = eqx.field(
        converter=_as_float,
        metadata=parameter("-", "sinkage exponent (2.1)", lower=0.0, open_lower=True),
    )
    k_c: Float[Array, "..."] = eqx.field(
        converter=_as_float, metadata=parameter("N/m^(n+1)", "cohesive modulus (2.1)", scale=1e3)
    )
    k_phi: Float[Array, "..."] = eqx.field(
        converter=_as_float, metadata=parameter("N/m^(n+2)", "frictional modulus (2.1)", scale=1e5)
    )
    cohesion: Float[Array, "..."] = eqx.field(converter=_as_float, metadata=COHESION)
    tan_phi: Float[Array, "..."] = eqx.field(converter=_as_float, metadata=TAN_PHI)
    shear_modulus: Float[Array, "..."] = eqx.field(
        converter=_as_float, metadata=SHEAR_MODULUS, default=DEFAULT_SHEAR_MODULUS, kw_only=True
    )

    def pressure(self, sinkage, width):
        """Bekker's law (2.1), `sigma = (k_c / b + k_phi) z^n` [Pa], b = `width` [m]."""
        return bekker_pressure(sinkage, width, self.k_c, self.k_phi, self.n)

    def sinkage_at_pressure(self, pressure, width, limit):
        """Bekker's law (2.1) inverted, `z = (sigma / (k_c / b + k_phi))^(1/n)` [m], capped
        at `limit` [m]."""
        modulus = self.k_c / width + self.k_phi
        return jnp.minimum(_safe_power(jnp.asarray(pressure / modulus), 1 / self.n), limit)

    def wheel_constraints(self, width):
        modulus = self.k_c / width + self.k_phi
        return [("k_c / b + k_phi", modulus, modulus > 0, "> 0 at the wheel width b")]

    @classmethod
    def reference(cls) -> "BekkerSoil":
        return cls.snow_us()

    @classmethod
    def _from_table(cls, n, k_c_kn, k_phi_kn, c_kpa, phi_deg) -> "BekkerSoil":
        return cls(
            n=n,
            k_c=k_c_kn * 1e3,
            k_phi=k_phi_kn * 1e3,
            cohesion=c_kpa * 1e3,
            tan_phi=math.tan(math.radians(phi_deg)),
            shear_modulus=DEFAULT_SHEAR_MODULUS,
        )

    @classmethod
    def snow_us(cls) -> "BekkerSoil":
        """Snow (U.S.): n 1.6, k_c 4.37 kN/m^(n+1), k_phi 196.72 kN/m^(n+2), c 1.03 kPa,
        phi 19.7 deg.  Source: Wong, *Theory of Ground Vehicles*, Table 2.3;
        K = 10 mm (`DEFAULT_SHEAR_MODULUS`)."""
        return cls._from_table(1.6, 4.37, 196.72, 1.03, 19.7)

    @classmethod
    def snow_harrison(cls) -> "BekkerSoil":
        """Snow (Harrison): n 1.6, k_c 2.49 kN/m^(n+1), k_phi 245.90 kN/m^(n+2), c 0.62 kPa,
        phi 23.2 deg.  Source: Wong, *Theory of Ground Vehicles*, Table 2.3;
        K = 10 mm (`DEFAULT_SHEAR_MODULUS`)."""
        return cls._from_table(1.6, 2.49, 245.90, 0.62, 23.2)

    @classmethod
    def snow_sweden(cls) -> "BekkerSoil":
        """Snow (Sweden): n 1.44, k_c 10.55 kN/m^(n+1), k_phi 66.08 kN/m^(n+2), c 6 kPa,
        phi 20.7 deg.  Source: Wong, *Theory of Ground Vehicles*, Table 2.3;
        K = 10 mm (`DEFAULT_SHEAR_MODULUS`)."""
        return cls._from_table(1.44, 10.55, 66.08, 6.0, 20.7)

    @classmethod
    def thesis_lab_snow(cls) -> "BekkerSoil":
        """Shoop's 200 kg/m^3 laboratory snow, as fitted in the thesis (section 2.1.1):
        n 1.0707148, k_c 3.43 kN/m^(n+1), k_phi 218.84215 kN/m^(n+2), from a 23 cm plate.
        The thesis gives no shear strength for this snow; cohesion 1.03 kPa and
        phi 19.7 deg are borrowed from Wong's Snow (U.S.) set (see `snow_us`); K is
        `DEFAULT_SHEAR_MODULUS` (10 mm, Table 4.1)."""
        return cls(
            n=1.0707148,
            k_c=3.43e3,
            k_phi=218.84215e3,
            cohesion=1.03e3,
            tan_phi=math.tan(math.radians(19.7)),
            shear_modulus=DEFAULT_SHEAR_MODULUS,
        )
