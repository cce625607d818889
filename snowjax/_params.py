"""Parameter sets as `equinox.Module`s with array leaves, plus published presets.

Every physical parameter is an array leaf, so parameter sets can be batched (give a leaf
an array value and it broadcasts against loads and slips), vmapped and differentiated.
All values are SI: Pa, m, N/m^(n+1), N/m^(n+2).
"""

from __future__ import annotations

import abc
import math
from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float

from ._terrain import bekker_pressure, reece_pressure, wong_pressure

__all__ = [
    "Terrain",
    "WongSnow",
    "BekkerSoil",
    "ReeceSoil",
    "LayeredSnow",
    "RigidWheel",
    "DEFAULT_SHEAR_MODULUS",
]


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


# Shear deformation modulus used where a published parameter set gives none: the thesis's
# fresh snow, Table 4.1 (u_k = D / K = 73.6 with D = 0.736 m, so K = 10 mm).
DEFAULT_SHEAR_MODULUS = 0.736 / 73.6  # [m]


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


class WongSnow(Terrain):
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

    label: ClassVar[str] = "snow"

    def pressure(self, sinkage, width=None):
        """Wong's law (2.3 / 4.1b), `sigma = -p_w ln(1 - z / z_w)` [Pa]; `width` unused."""
        return wong_pressure(sinkage, self.p_w, self.z_w)

    @property
    def depth(self) -> Array:
        """z_w: the asymptotic sinkage, the depth of the ice layer or frozen base [m]."""
        return self.z_w

    def constraints(self, shear: str = "classic"):
        if shear == "simplified":  # the simplified model is normalised by c
            cohesion = ("cohesion", self.cohesion, self.cohesion > 0,
                        "> 0 Pa (the simplified model is normalised by c)")
        else:
            cohesion = ("cohesion", self.cohesion, self.cohesion >= 0, ">= 0 Pa")
        return [
            ("p_w", self.p_w, self.p_w > 0, "> 0 Pa"),
            ("z_w", self.z_w, self.z_w > 0, "> 0 m"),
            cohesion,
            ("tan_phi", self.tan_phi, self.tan_phi >= 0, ">= 0"),
            ("shear_modulus", self.shear_modulus, self.shear_modulus > 0, "> 0 m"),
        ]

    @classmethod
    def reference(cls) -> "WongSnow":
        return cls.thesis_fresh_snow()

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


class BekkerSoil(Terrain):
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

    n: Float[Array, "..."] = _leaf()
    k_c: Float[Array, "..."] = _leaf()
    k_phi: Float[Array, "..."] = _leaf()
    cohesion: Float[Array, "..."] = _leaf()
    tan_phi: Float[Array, "..."] = _leaf()
    shear_modulus: Float[Array, "..."] = eqx.field(
        converter=_as_float, default=DEFAULT_SHEAR_MODULUS, kw_only=True
    )

    def pressure(self, sinkage, width):
        """Bekker's law (2.1), `sigma = (k_c / b + k_phi) z^n` [Pa], b = `width` [m]."""
        return bekker_pressure(sinkage, width, self.k_c, self.k_phi, self.n)

    def constraints(self, shear: str = "classic"):
        return [
            ("n", self.n, self.n > 0, "> 0"),
            ("k_c", self.k_c, self.k_c * 0 == 0, "finite N/m^(n+1)"),
            ("k_phi", self.k_phi, self.k_phi * 0 == 0, "finite N/m^(n+2)"),
            *Terrain.constraints(self, shear),
        ]

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


class ReeceSoil(Terrain):
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

    n: Float[Array, "..."] = _leaf()
    k_c_prime: Float[Array, "..."] = _leaf()
    k_phi_prime: Float[Array, "..."] = _leaf()
    unit_weight: Float[Array, "..."] = _leaf()
    cohesion: Float[Array, "..."] = _leaf()
    tan_phi: Float[Array, "..."] = _leaf()
    shear_modulus: Float[Array, "..."] = eqx.field(
        converter=_as_float, default=DEFAULT_SHEAR_MODULUS, kw_only=True
    )

    def pressure(self, sinkage, width):
        """Reece's law (2.4), `sigma = (c k'_c + gamma_s b k'_phi)(z / b)^n` [Pa]."""
        return reece_pressure(
            sinkage, width, self.cohesion, self.unit_weight, self.k_c_prime,
            self.k_phi_prime, self.n,
        )

    def constraints(self, shear: str = "classic"):
        return [
            ("n", self.n, self.n > 0, "> 0"),
            ("k_c_prime", self.k_c_prime, self.k_c_prime * 0 == 0, "finite"),
            ("k_phi_prime", self.k_phi_prime, self.k_phi_prime * 0 == 0, "finite"),
            ("unit_weight", self.unit_weight, self.unit_weight >= 0, ">= 0 N/m^3"),
            *Terrain.constraints(self, shear),
        ]

    def wheel_constraints(self, width):
        modulus = self.cohesion * self.k_c_prime + self.unit_weight * width * self.k_phi_prime
        return [("c k'_c + gamma_s b k'_phi", modulus, modulus > 0, "> 0 at the wheel width b")]

    @classmethod
    def reference(cls) -> "ReeceSoil":
        # Any valid set (stands in for invalid batch elements); not a published soil.
        return cls(n=1.0, k_c_prime=1.0, k_phi_prime=1000.0, unit_weight=15e3,
                   cohesion=1e3, tan_phi=0.5)


class LayeredSnow(Terrain):
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
    ice_failure_pressure: Float[Array, "..."] = _leaf()

    label: ClassVar[str] = "snow"

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

    def constraints(self, shear: str = "classic"):
        rules = [
            (f"{part}.{name}", value, ok, allowed)
            for part, layer in (("top", self.top), ("bottom", self.bottom))
            for name, value, ok, allowed in WongSnow.constraints(layer, shear)
        ]
        rules.append(
            ("bottom.z_w", self.bottom.z_w, self.bottom.z_w > self.top.z_w, "> top.z_w (m)")
        )
        rules.append(
            ("ice_failure_pressure", self.ice_failure_pressure, self.ice_failure_pressure > 0,
             "> 0 Pa")
        )
        return rules

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
