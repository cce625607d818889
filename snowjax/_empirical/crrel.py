"""The CRREL shallow-snow mobility model: sinkage, motion resistance and drawbar.

What is implemented, and where it comes from:

- final density from the peak contact pressure and the sinkage
  `z = h (1 - rho_0 / rho_f)`: Richmond (1995), *Motion resistance of wheeled vehicles in
  snow*, CRREL Report 95-7, eq. 1 and the rho_f table beside it; the same rule gives the rut
  depth of the CRM-1 model of Richmond, Shoop & Blaisdell (1995), *Cold regions mobility
  models*, CRREL Report 95-1 (Table A5: 9.0 cm and 7.2 cm for the M113);
- the motion resistance of a leading wheel in undisturbed shallow snow
  `R = 21.313 (rho_0 w a)^1.1918` (rho_0 w a in kg/m, R in N): CRREL 95-7 eq. 4, "the
  currently used shallow snow resistance" of Richmond et al. (1990) (CRREL 90-9), the
  thesis's eq. (2.23) (`snowjax.richmond_resistance`), here fed with the CRREL sinkage;
- the drawbar pull and drawbar coefficient `DP = T - R - W sin(slope)`, `DP / W`: the
  bookkeeping of CRM-1's outputs (CRREL 95-1 Table A5, checked there to the printed digits).

What is **not** implemented, because the stored copies of the reports do not show it
legibly (their equations are images lost in the text copies): CRREL 95-7's improved
regression for the whole-vehicle resistance (its eq. 8, with terms in h/0.22 m, 1.26,
0.0475 and 0.0246 for the second and third axles: the digits are legible, the equation is
not), its eqs. 2, 3 and 7; the CRM-1 / NRMM gross-traction equations in snow for wheels and
tracks (CRREL 95-1, 90-9); the track motion-resistance equation; the hard-surface
(internal) resistance coefficients.  No coefficient of those is guessed here.

SI units in the API; the reports use Mg/m^3 and cm, converted at this boundary (the
final densities 0.50–0.65 Mg/m^3 are 500–650 kg/m^3; the pressure thresholds 210, 350 and
700 kPa are 210e3, 350e3, 700e3 Pa).  Every function is a pure, element-wise JAX function
that broadcasts its arguments (jit, vmap, grad); concrete bad input raises `ValueError`
naming the argument, traced bad input gives NaN for that element only.
"""

from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float

from .common import ICE_DENSITY, _check, _nan_unless, _nonnegative, _positive, _safe
from .models import richmond_resistance

__all__ = [
    "CRREL_FINAL_DENSITIES",
    "crrel_final_density",
    "crrel_sinkage",
    "crrel_contact_arc",
    "CRRELWheel",
    "crrel_wheel",
    "crrel_drawbar",
]

# CRREL 95-7, beside eq. 1: rho_f [Mg/m^3] for the peak contact pressure p_max [kPa]:
# 0.50 for p_max <= 210, 0.55 for > 210, 0.60 for > 350, 0.65 for > 700.  In SI:
CRREL_FINAL_DENSITIES = (
    (0.0, 500.0),
    (210e3, 550.0),
    (350e3, 600.0),
    (700e3, 650.0),
)  # (pressure above which [Pa], final density [kg/m^3])


def crrel_final_density(peak_pressure: Float[ArrayLike, "..."]) -> Float[Array, "..."]:
    """Final (compacted) snow density under a tyre or track, CRREL 95-7 (beside eq. 1).

    `rho_f` = 500 kg/m^3 for p_max <= 210 kPa, 550 for p_max > 210 kPa, 600 for
    > 350 kPa, 650 for > 700 kPa (the report gives 0.50–0.65 Mg/m^3; converted here).
    The report uses 500 kg/m^3 for the CRREL Instrumented Vehicle's Michelin XCH4 tyres at
    the inflation pressures of its tests.  A step function: its derivative with respect to
    the pressure is zero (not differentiable at the thresholds).

    Source: Richmond, P. W. (1995), *Motion resistance of wheeled vehicles in snow*,
    CRREL Report 95-7; used by CRM-1 (CRREL Report 95-1, subroutine `density`).

    **Arguments:**

    - `peak_pressure`: p_max, the maximum contact pressure of the tyre or track [Pa], >= 0.

    **Returns:** rho_f [kg/m^3].
    """
    _nonnegative("peak_pressure", peak_pressure, "Pa")
    p = jnp.asarray(peak_pressure, dtype=float)
    rho = jnp.full_like(p, CRREL_FINAL_DENSITIES[0][1])
    for threshold, density in CRREL_FINAL_DENSITIES[1:]:
        rho = jnp.where(p > threshold, density, rho)
    return _nan_unless((p >= 0) & jnp.isfinite(p), rho)


def crrel_sinkage(
    snow_depth: Float[ArrayLike, "..."],
    initial_density: Float[ArrayLike, "..."],
    final_density: Float[ArrayLike, "..."] = 500.0,
) -> Float[Array, "..."]:
    """Sinkage (rut depth) in shallow undisturbed snow, CRREL 95-7 eq. 1.

    `z = h (1 - rho_0 / rho_f)`: the snow column under the tyre is compressed from its
    initial density rho_0 to the final density rho_f (mass conservation, no lateral flow),
    down to the base.  Where rho_0 >= rho_f the snow is not compacted further and z = 0
    (a guard added here; the report's formula would give a negative sinkage).  Smooth
    (differentiable) in h, rho_0 and rho_f wherever rho_0 < rho_f.

    Source: Richmond (1995), CRREL Report 95-7, eq. 1; the CRM-1 model (CRREL 95-1) gives
    the same rut depth for undisturbed snow (Table A5: M113 in 15 cm of 0.2 Mg/m^3 snow:
    9.0 cm; in 12 cm over ice: 7.2 cm; both at rho_f = 0.5 Mg/m^3).

    **Arguments:**

    - `snow_depth`: h, depth of the undisturbed snow [m], >= 0.
    - `initial_density`: rho_0, average initial density of the snow [kg/m^3],
      0 < rho_0 <= 917.
    - `final_density`: rho_f [kg/m^3], > 0 (default 500, the CRREL value for peak contact
      pressures up to 210 kPa; see [`snowjax.crrel_final_density`][]).

    **Returns:** z [m], 0 <= z < h.
    """
    _nonnegative("snow_depth", snow_depth, "m")
    _check(
        "initial_density",
        initial_density,
        lambda r: (r > 0) & (r <= ICE_DENSITY),
        f"in (0, {ICE_DENSITY:g}] kg/m^3 (kg/m^3, not Mg/m^3)",
    )
    _check(
        "final_density",
        final_density,
        lambda r: (r > 0) & (r <= ICE_DENSITY),
        f"in (0, {ICE_DENSITY:g}] kg/m^3 (kg/m^3, not Mg/m^3)",
    )
    h, r0, rf = (jnp.asarray(x, dtype=float) for x in (snow_depth, initial_density, final_density))
    valid = (h >= 0) & (r0 > 0) & (rf > 0) & (r0 <= ICE_DENSITY) & (rf <= ICE_DENSITY)
    z = h * jnp.maximum(1.0 - r0 / _safe(valid, rf), 0.0)
    return _nan_unless(valid, z)


def crrel_contact_arc(
    radius: Float[ArrayLike, "..."], sinkage: Float[ArrayLike, "..."]
) -> Float[Array, "..."]:
    """Arc length a of an undeflected tyre in contact with the snow at sinkage z.

    `a = r arccos(1 - z / r)` (0 <= z <= r): the arc from the bottom of the tyre to where
    its rim meets the undisturbed snow surface.  CRREL 95-7 defines a as "the arc length
    of the tire in contact with the snow" (its Figure 4, not legible in the stored copy);
    this rigid-rim geometry is the reading used here, not a formula printed by the report.
    Differentiable for 0 < z < r (infinite slope at z = 0, like sqrt).

    **Arguments:**

    - `radius`: r, tyre radius [m], > 0.
    - `sinkage`: z [m], 0 <= z <= r.

    **Returns:** a [m].
    """
    _positive("radius", radius, "m")
    _nonnegative("sinkage", sinkage, "m")
    r, z = jnp.asarray(radius, dtype=float), jnp.asarray(sinkage, dtype=float)
    valid = (r > 0) & (z >= 0) & (z <= r)
    r_s = _safe(valid, r)
    cos_theta = jnp.clip(1.0 - _safe(valid, z, 0.0) / r_s, -1.0, 1.0)
    # arccos has an infinite derivative at 1: keep the gradient finite at z = 0.
    positive = valid & (z > 0)
    theta = jnp.where(positive, jnp.arccos(jnp.where(positive, cos_theta, 0.5)), 0.0)
    return _nan_unless(valid, r_s * theta)


class CRRELWheel(eqx.Module):
    """A leading wheel in shallow undisturbed snow by the CRREL model ([`snowjax.crrel_wheel`][]).

    **Fields:** `final_density` [kg/m^3], `sinkage` [m], `contact_arc` [m],
    `motion_resistance` [N] (the snow's share only), `resistance_coefficient` [-]
    (motion resistance / wheel load).
    """

    final_density: Float[Array, "..."]
    sinkage: Float[Array, "..."]
    contact_arc: Float[Array, "..."]
    motion_resistance: Float[Array, "..."]
    resistance_coefficient: Float[Array, "..."]


def crrel_wheel(
    snow_depth: Float[ArrayLike, "..."],
    initial_density: Float[ArrayLike, "..."],
    radius: Float[ArrayLike, "..."],
    width: Float[ArrayLike, "..."],
    load: Float[ArrayLike, "..."],
    *,
    peak_pressure: Float[ArrayLike, "..."] | None = None,
    final_density: Float[ArrayLike, "..."] | None = None,
) -> CRRELWheel:
    """Sinkage and motion resistance of a leading wheel, CRREL shallow-snow model.

    1. rho_f from the peak contact pressure (CRREL 95-7, table beside eq. 1) — or given.
    2. z = h (1 - rho_0 / rho_f) (CRREL 95-7 eq. 1), [`snowjax.crrel_sinkage`][].
    3. a = r arccos(1 - z / r), [`snowjax.crrel_contact_arc`][] (geometry; see there).
    4. R = 21.313 (rho_0 w a)^1.1918 [N] with rho_0 w a in kg/m (CRREL 95-7 eq. 4, from
       Richmond et al. 1990, CRREL 90-9; the thesis's eq. 2.23),
       [`snowjax.richmond_resistance`][].

    The resistance is the snow's share for a leading (first-pass) wheel; the tyre's
    hard-surface (internal) resistance is not included (its CRREL coefficients are not in
    the stored copies of the reports).  Trailing wheels: CRREL 95-7 eq. 8 is not
    implemented (see the module docstring).

    **Arguments:**

    - `snow_depth`: h [m], >= 0.
    - `initial_density`: rho_0 [kg/m^3], 0 < rho_0 <= 917.
    - `radius`: r, unloaded tyre radius [m], > 0.
    - `width`: w, maximum tyre width [m], > 0.
    - `load`: W, wheel load [N], > 0 (only used for the resistance coefficient).
    - `peak_pressure`: p_max [Pa] (keyword); gives rho_f by the CRREL table.
    - `final_density`: rho_f [kg/m^3] (keyword), overrides `peak_pressure`.  With
      neither, rho_f = 500 kg/m^3 (p_max <= 210 kPa, the CRREL value for the CIV's tyres).

    **Returns:** a [`snowjax.CRRELWheel`][].
    """
    _positive("load", load, "N")
    if final_density is None:
        final_density = 500.0 if peak_pressure is None else crrel_final_density(peak_pressure)
    rho_f = jnp.asarray(final_density, dtype=float)
    z = crrel_sinkage(snow_depth, initial_density, rho_f)
    _positive("radius", radius, "m")
    r = jnp.asarray(radius, dtype=float)
    # z < h and a shallow layer: clamp at the radius so the arc stays defined (z > r would
    # mean snow deeper than the wheel radius, outside the shallow-snow model).
    a = crrel_contact_arc(r, jnp.minimum(z, r))
    resistance = richmond_resistance(initial_density, a, width)
    w = jnp.asarray(load, dtype=float)
    coefficient = resistance / _safe(w > 0, w)
    return CRRELWheel(
        final_density=jnp.broadcast_to(rho_f, jnp.shape(z)) + 0.0 * z,
        sinkage=z,
        contact_arc=a,
        motion_resistance=resistance,
        resistance_coefficient=_nan_unless(w > 0, coefficient),
    )


def crrel_drawbar(
    gross_traction: Float[ArrayLike, "..."],
    resistance: Float[ArrayLike, "..."],
    weight: Float[ArrayLike, "..."],
    slope: Float[ArrayLike, "..."] = 0.0,
) -> tuple[Float[Array, "..."], Float[Array, "..."]]:
    """Drawbar pull and drawbar coefficient of the CRM-1 model (CRREL 95-1).

    `DP = T - R - W sin(slope)`,  `DP / W`.

    The grade adds W sin(slope) to the level-ground resistance R, and the coefficient
    divides by the weight W (not W cos(slope)): this reproduces CRREL 95-1 Table A5 to the
    printed digits (M113, 23,401 lb: example 1, 44,134.3 - 5,585.4 N -> 38,548.9 N, 0.370;
    example 2 on a 30 deg slope: -18,424.5 N, -0.177).  The gross traction T and the
    resistance R themselves come from CRM-1 equations that are not in the stored copies
    of the reports; pass them in.

    **Arguments:**

    - `gross_traction`: T [N].
    - `resistance`: R, total motion resistance on level ground (terrain + internal) [N].
    - `weight`: W, vehicle (or assembly) weight [N], > 0.
    - `slope`: uphill slope [rad], in (-pi/2, pi/2) (default 0).

    **Returns:** `(drawbar_pull [N], drawbar_coefficient [-])`.
    """
    _positive("weight", weight, "N")
    _check(
        "slope",
        slope,
        lambda s: (s > -jnp.pi / 2) & (s < jnp.pi / 2),
        "in (-pi/2, pi/2) rad (radians, not degrees)",
    )
    t, r, w, s = (jnp.asarray(x, dtype=float) for x in (gross_traction, resistance, weight, slope))
    valid = (w > 0) & (jnp.abs(s) < jnp.pi / 2)
    pull = t - r - w * jnp.sin(s)
    return _nan_unless(valid, pull), _nan_unless(valid, pull / _safe(valid, w))
