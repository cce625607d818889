"""Parameter sets as `equinox.Module`s with array leaves, plus published presets.

Every physical parameter is an array leaf, so parameter sets can be batched (give a leaf
an array value and it broadcasts against loads and slips), vmapped and differentiated.
All values are SI: Pa, m, N/m^(n+1), N/m^(n+2).
"""

from __future__ import annotations

import math

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, Float

__all__ = ["WongSnow", "RigidWheel", "BekkerSoil"]


def _as_float(x):
    """Converter for parameter leaves: arrays of a floating dtype, other objects untouched.

    Python ints become the default float type; existing floating arrays keep their dtype,
    so a float32 parameter set stays float32.  Non-numeric placeholders (None, sentinels
    used by `jax.vmap` in_axes or `eqx.filter`) pass through unchanged.
    """
    if x is None or isinstance(x, jax.ShapeDtypeStruct):
        return x
    try:
        arr = jnp.asarray(x)
    except TypeError:
        return x
    if not jnp.issubdtype(arr.dtype, jnp.floating):
        arr = arr.astype(jnp.result_type(float))
    return arr


def _leaf():
    return eqx.field(converter=_as_float)


# The thesis does not give p_w.  Table 4.1 lists an entry angle of 53.6747 deg, which is
# exactly a sinkage z0 = D/2 (1 - cos theta0) = 0.1500 m = 0.75 z_w.  We take that state
# as the no-shear equilibrium (eq. 4.14 with tau = 0) at F_z = 5 kN, the middle of the
# thesis's FEA load range 3.5-7.5 kN (section 3.2), with the 0.235 m wide tyre below:
# p_w = F_z / (r b int_0^theta0 -ln(Z) cos(theta) dtheta) = 85.55 kPa (computed once with
# scipy.integrate.quad; tests/test_params.py re-derives it).
THESIS_P_W = 85_549.0  # [Pa]
# Wong's own rule (section 2.1.2: p_w is a third of the pressure at z = 0.95 z_w) applied
# to the thesis's plate data (Table 2.1, rows 17-18: 36.96 kPa at 0.1865 m, 39.54 kPa at
# 0.1915 m; 38.77 kPa at 0.95 z_w = 0.190 m).
PLATE_RULE_P_W = 38_770.0 / 3.0  # [Pa] = 12.92 kPa
# Section width of the P235/75R15 tyre whose nominal diameter (0.734 m) matches the
# thesis's D = 0.736 m; the thesis does not state the width used.
THESIS_TIRE_WIDTH = 0.235  # [m]
THESIS_DIAMETER = 0.736  # [m]


class WongSnow(eqx.Module):
    """Shallow snow described by Wong's pressure–sinkage law and Mohr–Coulomb shear.

    Pressure–sinkage: `sigma = -p_w ln(1 - z / z_w)` (eq. 2.3 / 4.1); shear strength
    `c + sigma tan(phi)` (eq. 2.5) mobilised with shear displacement over the modulus K
    (eq. 4.11).

    **Fields** (array leaves, broadcast against each other and against load and slip):

    - `p_w`: Wong's pressure parameter, a third of the pressure at z = 0.95 z_w [Pa].
    - `z_w`: asymptotic sinkage: depth of the ice layer or frozen base [m].
    - `cohesion`: c [Pa].
    - `tan_phi`: tangent of the internal friction angle [-].
    - `shear_modulus`: K, the shear deformation modulus of eq. (4.11) [m].
    """

    p_w: Float[Array, "..."] = _leaf()
    z_w: Float[Array, "..."] = _leaf()
    cohesion: Float[Array, "..."] = _leaf()
    tan_phi: Float[Array, "..."] = _leaf()
    shear_modulus: Float[Array, "..."] = _leaf()

    @classmethod
    def thesis_fresh_snow(
        cls, diameter: float = THESIS_DIAMETER, p_w: float = THESIS_P_W
    ) -> "WongSnow":
        """Fresh shallow snow of the thesis, Table 4.1, scaled to a wheel of `diameter`.

        Table 4.1 gives only ratios: z_w / D = 0.2717, c / p_w = 0.2165,
        u_k = D / K = 73.6 and tan(phi) = 0.0787, for D = 0.736 m.  So z_w = 0.200 m,
        K = 10.0 mm, and c = 0.2165 p_w.

        The thesis does not give p_w.  Its Table 4.1 entry angle, 53.6747 deg, is exactly
        the sinkage z0 = 0.150 m = 0.75 z_w; the default p_w = 85.55 kPa makes that the
        no-shear equilibrium (4.14) of the 0.736 m x 0.235 m tyre at 5 kN, the middle of
        the thesis's FEA load range (3.5-7.5 kN).  Then c = 18.5 kPa.  (Wong's plate rule,
        p_w = a third of the pressure at z = 0.95 z_w, applied to the thesis's plate data
        of Table 2.1 would give 12.9 kPa — see `thesis_plate_rule_snow` — but a 0.2 m
        layer with that p_w carries only 2.2 kN under this tyre, less than every FEA
        load.)  Override with `p_w=...`; the cohesion follows the thesis
        ratio.

        **Arguments:**

        - `diameter`: wheel diameter D the ratios refer to [m] (default 0.736 m).
        - `p_w`: Wong's pressure parameter [Pa] (default 85.55 kPa, `THESIS_P_W`).
        """
        return cls(
            p_w=p_w,
            z_w=0.2717 * diameter,
            cohesion=0.2165 * p_w,
            tan_phi=0.0787,
            shear_modulus=diameter / 73.6,
        )


    @classmethod
    def thesis_plate_rule_snow(cls, diameter: float = THESIS_DIAMETER) -> "WongSnow":
        """The thesis's fresh snow (Table 4.1 ratios) with p_w from Wong's plate rule.

        p_w = 12.92 kPa is a third of the pressure that the thesis's own plate test of
        the same fresh snow (Table 2.1) reaches at z = 0.95 z_w = 0.190 m (38.77 kPa,
        interpolated between rows 17 and 18); c = 0.2165 p_w = 2.80 kPa, z_w = 0.2717 D,
        K = D / 73.6, tan phi = 0.0787.  A softer snow than `thesis_fresh_snow`: a
        0.736 m x 0.235 m wheel bottoms out above about 2.2 kN.

        **Arguments:** `diameter`: the wheel diameter D the ratios refer to [m].
        """
        return cls.thesis_fresh_snow(diameter=diameter, p_w=PLATE_RULE_P_W)


class RigidWheel(eqx.Module):
    """A rigid wheel (the thesis's model of a tyre on soft snow, section 4.1).

    **Fields:**

    - `diameter`: D [m].
    - `width`: b [m].
    """

    diameter: Float[Array, "..."] = _leaf()
    width: Float[Array, "..."] = _leaf()

    @property
    def radius(self) -> Array:
        """r = D / 2 [m]."""
        return self.diameter / 2

    @classmethod
    def thesis_tire(cls) -> "RigidWheel":
        """The 0.736 m tyre of the thesis's FEA studies (section 3.2 and Table 4.1).

        The thesis gives D = 0.736 m but not the width; 0.235 m is the section width of a
        P235/75R15 tyre, whose nominal diameter (0.734 m) matches D.
        """
        return cls(diameter=THESIS_DIAMETER, width=THESIS_TIRE_WIDTH)


class BekkerSoil(eqx.Module):
    """A terrain described by Bekker's pressure–sinkage law (2.1) and Mohr–Coulomb (2.5).

    **Fields:**

    - `n`: sinkage exponent [-].
    - `k_c`: cohesive modulus [N/m^(n+1)].
    - `k_phi`: frictional modulus [N/m^(n+2)].
    - `cohesion`: c [Pa].
    - `tan_phi`: tangent of the internal friction angle [-].
    """

    n: Float[Array, "..."] = _leaf()
    k_c: Float[Array, "..."] = _leaf()
    k_phi: Float[Array, "..."] = _leaf()
    cohesion: Float[Array, "..."] = _leaf()
    tan_phi: Float[Array, "..."] = _leaf()

    @classmethod
    def _from_table(cls, n, k_c_kn, k_phi_kn, c_kpa, phi_deg) -> "BekkerSoil":
        return cls(
            n=n,
            k_c=k_c_kn * 1e3,
            k_phi=k_phi_kn * 1e3,
            cohesion=c_kpa * 1e3,
            tan_phi=math.tan(math.radians(phi_deg)),
        )

    @classmethod
    def snow_us(cls) -> "BekkerSoil":
        """Snow (U.S.): n 1.6, k_c 4.37 kN/m^(n+1), k_phi 196.72 kN/m^(n+2), c 1.03 kPa,
        phi 19.7 deg.  Source: Wong, *Theory of Ground Vehicles*, Table 2.3."""
        return cls._from_table(1.6, 4.37, 196.72, 1.03, 19.7)

    @classmethod
    def snow_harrison(cls) -> "BekkerSoil":
        """Snow (Harrison): n 1.6, k_c 2.49 kN/m^(n+1), k_phi 245.90 kN/m^(n+2), c 0.62 kPa,
        phi 23.2 deg.  Source: Wong, *Theory of Ground Vehicles*, Table 2.3."""
        return cls._from_table(1.6, 2.49, 245.90, 0.62, 23.2)

    @classmethod
    def snow_sweden(cls) -> "BekkerSoil":
        """Snow (Sweden): n 1.44, k_c 10.55 kN/m^(n+1), k_phi 66.08 kN/m^(n+2), c 6 kPa,
        phi 20.7 deg.  Source: Wong, *Theory of Ground Vehicles*, Table 2.3."""
        return cls._from_table(1.44, 10.55, 66.08, 6.0, 20.7)

    @classmethod
    def thesis_lab_snow(cls) -> "BekkerSoil":
        """Shoop's 200 kg/m^3 laboratory snow, as fitted in the thesis (section 2.1.1):
        n 1.0707148, k_c 3.43 kN/m^(n+1), k_phi 218.84215 kN/m^(n+2), from a 23 cm plate.
        The thesis gives no shear strength for this snow; cohesion 1.03 kPa and
        phi 19.7 deg are borrowed from Wong's Snow (U.S.) set (see `snow_us`)."""
        return cls(
            n=1.0707148,
            k_c=3.43e3,
            k_phi=218.84215e3,
            cohesion=1.03e3,
            tan_phi=math.tan(math.radians(19.7)),
        )
