"""Wong's pressure–sinkage law for shallow snow on a hard base (eq. 2.3 / 4.1) and `WongSnow`."""

from __future__ import annotations

from typing import ClassVar

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from .._constants import (
    PLATE_RULE_P_W,
    THESIS_DIAMETER,
    THESIS_P_W,
)
from .._leaves import _as_float, _is_traced, parameter
from .base import (
    COHESION,
    SHEAR_MODULUS,
    TAN_PHI,
    AbstractTerrain,
    _clip_negative,
)


def wong_sinkage(
    pressure: Float[ArrayLike, "..."],
    p_w: Float[ArrayLike, "..."],
    z_w: Float[ArrayLike, "..."],
) -> Float[Array, "..."]:
    """Wong's pressure–sinkage law for shallow snow, eq. (2.2) / (4.1a).

    `z = z_w [1 - exp(-sigma / p_w)]`.

    **Arguments:**

    - `pressure`: normal pressure sigma [Pa].
    - `p_w`: Wong's pressure parameter, a third of the pressure at which z = 0.95 z_w [Pa].
    - `z_w`: asymptotic sinkage, roughly the depth of the ice layer or frozen base [m].

    **Returns:** sinkage z [m], in [0, z_w).
    """
    return -jnp.asarray(z_w) * jnp.expm1(-jnp.asarray(pressure) / jnp.asarray(p_w))


def wong_pressure(
    sinkage: Float[ArrayLike, "..."],
    p_w: Float[ArrayLike, "..."],
    z_w: Float[ArrayLike, "..."],
) -> Float[Array, "..."]:
    """Inverse of Wong's law, eq. (2.3) / (4.1b): `sigma = -p_w ln(1 - z / z_w)`.

    **Arguments:**

    - `sinkage`: z [m]; negative values are clipped to 0.
    - `p_w`: Wong's pressure parameter [Pa].
    - `z_w`: asymptotic sinkage [m].

    **Returns:** normal pressure sigma [Pa].  It diverges logarithmically as z -> z_w;
    for z >= z_w (the plate stands on the base) the result is `+inf`, never NaN.
    """
    z = _clip_negative(sinkage)
    z_w = jnp.asarray(z_w)
    ratio = z / z_w
    below = ratio < 1.0
    safe = jnp.where(below, ratio, 0.0)
    return jnp.where(below, -jnp.asarray(p_w) * jnp.log1p(-safe), jnp.inf)


def _safe_sqrt(x):
    """sqrt(x) for x > 0, 0 elsewhere (finite gradient)."""
    positive = x > 0
    return jnp.where(positive, jnp.sqrt(jnp.where(positive, x, 1.0)), 0.0)


def _xlogx(x):
    """x ln x, 0 at x = 0 (finite gradient)."""
    positive = x > 0
    return jnp.where(positive, x * jnp.log(jnp.where(positive, x, 1.0)), 0.0)


def _sin2_over_z(angle, z0_rel, a, guard=False):
    """a int_0^angle sin^2 / Z dtheta [-], Z = Z0 + 2 a sin^2(theta / 2) (the rim in Wong's
    law, `WongSnow.front_rim_integrals`): sin + A angle / a - 2 sqrt(A^2 - a^2) / a
    atan(sqrt((A + a) / (A - a)) tan(angle / 2)), A = Z0 + a, written without the
    cancellation of A - a = Z0.  `guard`: a finite gradient also with no contact on the
    base (angle 0, Z0 0: a rut pressed to it)."""
    sq_z0 = _safe_sqrt(z0_rel)
    sq_2a = jnp.sqrt(z0_rel + 2 * a)
    rise = sq_2a * jnp.tan(angle / 2)
    if guard:
        some = (rise > 0) | (sq_z0 > 0)
        turn = jnp.where(some, jnp.arctan2(jnp.where(some, rise, 1.0), sq_z0), 0.0)
    else:
        turn = jnp.arctan2(rise, sq_z0)
    return jnp.sin(angle) + (z0_rel + a) * angle / a - 2 * sq_z0 * sq_2a / a * turn


class WongSnow(AbstractTerrain):
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

    p_w: Float[Array, "..."] = eqx.field(
        converter=_as_float,
        metadata=parameter(
            "Pa", "Wong's pressure parameter (2.3)", lower=0.0, open_lower=True, scale=1e4
        ),
    )
    z_w: Float[Array, "..."] = eqx.field(
        converter=_as_float,
        metadata=parameter(
            "m", "asymptotic sinkage, the depth of the base (2.3)", lower=0.0, open_lower=True
        ),
    )
    cohesion: Float[Array, "..."] = eqx.field(converter=_as_float, metadata=COHESION)
    tan_phi: Float[Array, "..."] = eqx.field(converter=_as_float, metadata=TAN_PHI)
    shear_modulus: Float[Array, "..."] = eqx.field(converter=_as_float, metadata=SHEAR_MODULUS)

    label: ClassVar[str] = "snow"

    def pressure(self, sinkage, width=None):
        """Wong's law (2.3 / 4.1b), `sigma = -p_w ln(1 - z / z_w)` [Pa]; `width` unused."""
        return wong_pressure(sinkage, self.p_w, self.z_w)

    @property
    def depth(self) -> Array:
        """z_w: the asymptotic sinkage, the depth of the ice layer or frozen base [m]."""
        return self.z_w

    def logarithmic_base(self) -> bool:
        """True: -p_w ln(clearance / z_w) at the base."""
        return True

    def sinkage_at_pressure(self, pressure, width, limit):
        """Wong's law (2.2) in closed form, `z = z_w [1 - exp(-sigma / p_w)]` [m] (below
        the base for every pressure), capped at `limit` [m]."""
        return jnp.minimum(wong_sinkage(pressure, self.p_w, self.z_w), limit)

    def pressure_at_clearance(self, clearance, width=None):
        """Wong's law at `clearance` = z_w - z [m] above the base, `-p_w ln(clearance /
        z_w)` [Pa] (no cancellation near the base); `+inf` on the base."""
        # One reciprocal per parameter set, a product per point (a quadrature calls this
        # at every node).
        return -self.p_w * jnp.log(clearance * (1 / self.z_w))

    def front_rim_integrals(self, entry_angle, diameter, clearance):
        """Exact `int_0^theta0 sigma cos` and `int_0^theta0 sigma sin` [Pa] on the rim.

        On the rim, sigma = -p_w ln Z with Z = Z0 + 2 a sin^2(theta / 2) = A - a cos
        theta, Z0 = clearance / z_w, a = D / (2 z_w), A = Z0 + a.  Integration by parts
        (Z(theta0) = 1) gives `int sigma cos = p_w a int_0^theta0 sin^2 / Z`, and
        `int sin^2/(A - a cos) = sin/a + A theta/a^2 - 2 sqrt(A^2 - a^2)/a^2
        atan(sqrt((A + a)/(A - a)) tan(theta/2))`; `int sigma sin = (p_w / a)(1 - Z0 +
        Z0 ln Z0)`.  Both are finite as Z0 -> 0 (the wheel on the base).
        """
        z0_rel = clearance / self.z_w
        a = diameter / (2 * self.z_w)
        cos_integral = self.p_w * _sin2_over_z(entry_angle, z0_rel, a)
        return cos_integral, self.p_w / a * (1 - z0_rel + _xlogx(z0_rel))

    def rim_integrals_to(self, angle, diameter, clearance):
        """Exact `int_0^angle sigma cos` and `int_0^angle sigma sin` [Pa] on a rim of
        diameter D [m] whose lowest point lies `clearance` [m] above the base, for any
        `angle` [rad] in [0, pi) (`front_rim_integrals` at angle = theta0, where sigma is
        0).  By parts as there, with the boundary term sigma(angle) sin(angle):
        `int sigma cos = sigma(angle) sin(angle) + p_w a int_0^angle sin^2 / Z`, and
        `int sigma sin = (p_w / a)[Z ln Z - Z] from Z(angle) to Z0`.
        """
        z0_rel = clearance / self.z_w
        a = diameter / (2 * self.z_w)
        z_end = z0_rel + 2 * a * jnp.sin(angle / 2) ** 2
        # sigma(angle) sin(angle), 0 at angle = 0 (finite there also on the base, Z = 0).
        above = z_end > 0
        boundary = jnp.where(above, -self.p_w * jnp.log(jnp.where(above, z_end, 1.0)), 0.0)
        turn = _sin2_over_z(angle, z0_rel, a, guard=True)
        cos_integral = boundary * jnp.sin(angle) + self.p_w * turn
        sin_integral = self.p_w / a * (_xlogx(z0_rel) - z0_rel - _xlogx(z_end) + z_end)
        return cos_integral, sin_integral

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
    def from_snow_pit(
        cls,
        depth: Float[ArrayLike, "..."],
        density: Float[ArrayLike, "..."],
        p_w: Float[ArrayLike, "..."],
        cohesion: Float[ArrayLike, "..."],
        tan_phi: Float[ArrayLike, "..."],
        shear_modulus: Float[ArrayLike, "..."],
        final_density: Float[ArrayLike, "..."] = 500.0,
    ) -> "WongSnow":
        """Wong snow from what a snow pit measures: the layer's depth and density.

        Wong's z_w is the sinkage at which the layer stops compressing; a layer of depth h
        and density rho0 compacted to the final density rho_f leaves a rut of depth
        `z_w = h (1 - rho0 / rho_f)` (CRREL Report 95-7, Richmond, Shoop & Blaisdell 1995,
        eq. 1), with rho_f = 500 kg/m^3 for contact pressures up to 210 kPa (550 above,
        600 above 350 kPa, 650 above 700 kPa: `snowjax.crrel_final_density`; 500 is the
        report's value for the CRREL Instrumented Vehicle's tyres).  Range of the report's
        tests: depths 0.10-0.37 m, densities 110-250 kg/m^3.  p_w and the shear strength
        are not given by depth and density (no density law for them was found in the
        sources snowjax cites): pass them, e.g. fitted (`fit_wheel`) or Table 4.1's ratios
        c = 0.2165 p_w, tan phi = 0.0787 (`thesis_fresh_snow`).

        **Arguments** (broadcast together): `depth` h [m], `density` rho0 [kg/m^3] (below
        `final_density`), `p_w` [Pa], `cohesion` [Pa], `tan_phi` [-], `shear_modulus` K
        [m], `final_density` rho_f [kg/m^3] (default 500).

        **Raises:** `ValueError` for a concrete density that is not below the final
        density, or a depth that is not > 0 (z_w must be > 0).
        """
        h = _as_float(depth)
        rho0, rho_f = _as_float(density), _as_float(final_density)
        if not any(_is_traced(x) for x in (h, rho0, rho_f)):
            ratio = np.asarray(rho0, float) / np.asarray(rho_f, float)
            if not np.all((ratio >= 0) & (ratio < 1)) or not np.all(np.asarray(h, float) > 0):
                raise ValueError(
                    "WongSnow.from_snow_pit: need depth > 0 m and 0 <= density < final_density "
                    f"(kg/m^3); got depth {h!r}, density {rho0!r}, final_density {rho_f!r}"
                )
        return cls(
            p_w=p_w,
            z_w=h * (1 - rho0 / rho_f),
            cohesion=cohesion,
            tan_phi=tan_phi,
            shear_modulus=shear_modulus,
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
