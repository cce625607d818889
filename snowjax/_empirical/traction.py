"""Empirical traction models of chapter 2: the WES mobility coefficients (2.13)–(2.15),
Brixius (2.17)–(2.20) and Abd El-Gawwad & Crolla's slip parameters (section 2.3.3).
"""

from __future__ import annotations

from typing import Literal

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float

from .common import (
    _BRIXIUS_SLIP_COEFFICIENTS,
    _check,
    _check_pair,
    _nan_unless,
    _nonnegative,
    _positive,
    _safe,
)

# ----------------------------------------------------------------------------------------
# WES mobility coefficients, eqs. (2.13)-(2.15)
# ----------------------------------------------------------------------------------------


def net_traction_coefficient(
    drawbar_pull: Float[ArrayLike, "..."], load: Float[ArrayLike, "..."]
) -> Float[Array, "..."]:
    """Net traction (pull) coefficient of the WES method, eq. (2.13): `mu_p = P / W`.

    Source: the NRMM-II force analysis as summarised by Saarilahti (2002) [6 in the thesis].

    **Arguments:**

    - `drawbar_pull`: P, the drawbar pull [N].
    - `load`: W, the wheel load [N], > 0.

    **Returns:** mu_p [-].
    """
    _positive("load", load, "N")
    w = jnp.asarray(load)
    return _nan_unless(w > 0, jnp.asarray(drawbar_pull) / _safe(w > 0, w))


def rolling_resistance_coefficient(
    rolling_resistance: Float[ArrayLike, "..."], load: Float[ArrayLike, "..."]
) -> Float[Array, "..."]:
    """Rolling resistance (towed force) coefficient of the WES method, eq. (2.14):
    `mu_r = P_r / W`.

    Source: as eq. (2.13).

    **Arguments:**

    - `rolling_resistance`: P_r, the resistance to movement (towed force) [N].
    - `load`: W, the wheel load [N], > 0.

    **Returns:** mu_r [-].
    """
    _positive("load", load, "N")
    w = jnp.asarray(load)
    return _nan_unless(w > 0, jnp.asarray(rolling_resistance) / _safe(w > 0, w))


def gross_traction_coefficient(
    torque: Float[ArrayLike, "..."],
    rolling_radius: Float[ArrayLike, "..."],
    load: Float[ArrayLike, "..."],
) -> Float[Array, "..."]:
    """Gross traction (thrust) coefficient of the WES method, eq. (2.15):
    `mu_t = Q / (r_r W)`.

    Source: as eq. (2.13).  (The thesis states Q in kN m and W in kN; any consistent
    units give the same ratio, here N m and N.)

    **Arguments:**

    - `torque`: Q, the wheel torque [N m].
    - `rolling_radius`: r_r, the rolling radius of the wheel [m], > 0.
    - `load`: W, the wheel load [N], > 0.

    **Returns:** mu_t [-].
    """
    _positive("rolling_radius", rolling_radius, "m")
    _positive("load", load, "N")
    denom = jnp.asarray(rolling_radius) * jnp.asarray(load)
    valid = (jnp.asarray(rolling_radius) > 0) & (jnp.asarray(load) > 0)
    return _nan_unless(valid, jnp.asarray(torque) / _safe(valid, denom))


# ----------------------------------------------------------------------------------------
# Brixius, eqs. (2.17)-(2.20)
# ----------------------------------------------------------------------------------------


def _check_tire(cone_index, width, diameter, load, deflection, section_height):
    _positive("cone_index", cone_index, "Pa")
    _positive("width", width, "m")
    _positive("diameter", diameter, "m")
    _positive("load", load, "N")
    _positive("section_height", section_height, "m")
    _nonnegative("deflection", deflection, "m")
    _check_pair(
        "`deflection` must be smaller than `section_height` (0 <= delta/h < 1): "
        "a tyre cannot deflect by its whole section height.",
        deflection,
        section_height,
        lambda d, h: d < h,
    )


def _wheel_numeric(cone_index, width, diameter, load, deflection, section_height):
    ci, b, d, w = (jnp.asarray(x) for x in (cone_index, width, diameter, load))
    delta, h = jnp.asarray(deflection), jnp.asarray(section_height)
    valid = (ci > 0) & (b > 0) & (d > 0) & (w > 0) & (h > 0) & (delta >= 0) & (delta < h)
    b_s, d_s, w_s, h_s = (_safe(valid, x) for x in (b, d, w, h))
    numeric = ci * b_s * d_s / w_s * (1 + 5 * delta / h_s) / (1 + 3 * b_s / d_s)
    return numeric, valid


def brixius_wheel_numeric(
    cone_index: Float[ArrayLike, "..."],
    width: Float[ArrayLike, "..."],
    diameter: Float[ArrayLike, "..."],
    load: Float[ArrayLike, "..."],
    deflection: Float[ArrayLike, "..."],
    section_height: Float[ArrayLike, "..."],
) -> Float[Array, "..."]:
    """Brixius's wheel numeric (mobility number), eq. (2.17).

    `N_B = (CI b d / W) (1 + 5 delta/h) / (1 + 3 b/d)`.

    Source: Brixius, W. W., *Traction prediction equations for bias ply tires*, ASAE
    Paper 87-1622 (1987) [24 in the thesis].  N_B is dimensionless because CI b d / W is
    (Pa m m / N).

    **Arguments:**

    - `cone_index`: CI, cone index of the terrain [Pa] (the thesis's penetrometer: 30 deg
      cone of 0.5 in^2 base), > 0.
    - `width`: b, tyre section width [m], > 0.
    - `diameter`: d, unloaded tyre diameter [m], > 0.
    - `load`: W, wheel load [N], > 0.
    - `deflection`: delta, tyre deflection [m], 0 <= delta < h.
    - `section_height`: h, tyre section height [m], > 0.

    **Returns:** N_B [-].
    """
    _check_tire(cone_index, width, diameter, load, deflection, section_height)
    numeric, valid = _wheel_numeric(cone_index, width, diameter, load, deflection, section_height)
    return _nan_unless(valid, numeric)


class BrixiusTraction(eqx.Module):
    """Brixius's traction prediction for one tyre, eqs. (2.17)–(2.20).

    **Fields** (dimensionless coefficients, per unit wheel load):

    - `wheel_numeric`: N_B, eq. (2.17).
    - `gross_traction`: mu_T = Q / (r W), eq. (2.18).
    - `net_traction`: mu_P = P / W (drawbar pull over load), eq. (2.19).
    - `motion_resistance`: mu_R = (Q/r - P) / W, eq. (2.20).

    `net_traction == gross_traction - motion_resistance` holds exactly.
    """

    wheel_numeric: Float[Array, "..."]
    gross_traction: Float[Array, "..."]
    net_traction: Float[Array, "..."]
    motion_resistance: Float[Array, "..."]


def brixius(
    cone_index: Float[ArrayLike, "..."],
    width: Float[ArrayLike, "..."],
    diameter: Float[ArrayLike, "..."],
    load: Float[ArrayLike, "..."],
    deflection: Float[ArrayLike, "..."],
    section_height: Float[ArrayLike, "..."],
    slip: Float[ArrayLike, "..."],
    *,
    variant: Literal["thesis", "brixius1987"] = "thesis",
) -> BrixiusTraction:
    """Brixius's traction equations for a pneumatic tyre, eqs. (2.17)–(2.20).

    With the wheel numeric N_B of eq. (2.17) and the slip S:

    - gross traction (2.18): `mu_T = 0.88 (1 - exp(-0.1 N_B)) (1 - exp(-a S)) + 0.04`
    - net traction (2.19): `mu_P = 0.88 (1 - exp(-0.1 N_B)) (1 - exp(-a S))
      - (1 / N_B + c S / sqrt(N_B))`
    - motion resistance (2.20): `mu_R = 1 / N_B + 0.04 + c S / sqrt(N_B)`

    **Slip coefficients.**  The thesis prints a = 0.75 and c = 0.05 (`variant="thesis"`,
    the default, reproduces the thesis).  Brixius (1987) — and ASAE Standard D497, which
    adopted his equations — use a = 7.5 and c = 0.5 with the slip as a decimal fraction
    (equivalently 0.075 and 0.005 with slip in percent), so the thesis's coefficients
    agree with the original in neither convention: with them mu_T reaches only 0.4 of its
    asymptote at S = 1.  Pass `variant="brixius1987"` for the published coefficients.

    Source: Brixius, W. W., *Traction prediction equations for bias ply tires*, ASAE Paper
    87-1622 (1987) [24 in the thesis], fitted to John Deere drawbar-pull tests of farm
    tractor (bias-ply) tyres.  **Range of validity:** the thesis states none; the
    equations were fitted to bias-ply tractor tyres on agricultural soils, so applying
    them to snow (or to radial car tyres) is an extrapolation.  Only the mathematical
    domain is enforced.

    **Arguments:**

    - `cone_index`: CI [Pa], > 0.
    - `width`: b, tyre section width [m], > 0.
    - `diameter`: d, unloaded tyre diameter [m], > 0.
    - `load`: W, wheel load [N], > 0.
    - `deflection`: delta, tyre deflection [m], 0 <= delta < h.
    - `section_height`: h, tyre section height [m], > 0.
    - `slip`: S, driving slip of eq. (2.6) as a fraction [-], 0 <= S <= 1.
    - `variant`: `"thesis"` (a = 0.75, c = 0.05) or `"brixius1987"` (a = 7.5, c = 0.5).

    **Returns:** a [`snowjax.BrixiusTraction`][] with the dimensionless coefficients.
    """
    if variant not in _BRIXIUS_SLIP_COEFFICIENTS:
        raise ValueError(
            f"`variant` must be one of {sorted(_BRIXIUS_SLIP_COEFFICIENTS)}; got {variant!r}."
        )
    _check_tire(cone_index, width, diameter, load, deflection, section_height)
    _check("slip", slip, lambda s: (s >= 0) & (s <= 1), "in [0, 1] (a fraction, not %)")
    a, c = _BRIXIUS_SLIP_COEFFICIENTS[variant]
    numeric, valid = _wheel_numeric(cone_index, width, diameter, load, deflection, section_height)
    s = jnp.asarray(slip)
    valid = valid & (numeric > 0) & (s >= 0) & (s <= 1)
    n_b = _safe(valid, numeric)
    traction = 0.88 * (-jnp.expm1(-0.1 * n_b)) * (-jnp.expm1(-a * s))
    soil_loss = 1.0 / n_b + c * s / jnp.sqrt(n_b)
    gross = traction + 0.04
    resistance = soil_loss + 0.04
    net = traction - soil_loss
    return BrixiusTraction(
        wheel_numeric=_nan_unless(valid, numeric),
        gross_traction=_nan_unless(valid, gross),
        net_traction=_nan_unless(valid, net),
        motion_resistance=_nan_unless(valid, resistance),
    )


# ----------------------------------------------------------------------------------------
# Abd El-Gawwad & Crolla, section 2.3.3
# ----------------------------------------------------------------------------------------

# k = -0.06 + 0.66 / MOBN is positive only for MOBN < 0.66 / 0.06 = 11.
_GC_MAX_MOBILITY = 11.0


def gawwad_crolla_slip_parameters(
    mobility_number: Float[ArrayLike, "..."],
) -> tuple[Float[Array, "..."], Float[Array, "..."]]:
    """Abd El-Gawwad & Crolla's slip-shear parameters from the mobility number
    (section 2.3.3, used in the shear law 2.22):

    `j0 = -0.065 + 0.49 / MOBN`,  `k = -0.06 + 0.66 / MOBN`.

    Source: Abd El-Gawwad, K. A. & Crolla, D. A., *Off-road tyre modelling 1–4*, Journal of
    Terramechanics 36 (1999) [30–33 in the thesis]; fitted to tyre tests in **clay**
    (cohesive soil), as the thesis says.

    **Assumptions (the thesis leaves these undefined):**

    - MOBN is taken as a dimensionless tyre mobility number (wheel numeric) supplied by
      the caller; the thesis does not say which definition (e.g. Brixius's N_B of
      eq. 2.17, or a Turnage/Wismer–Luth numeric) the fit used.
    - j0 and k are returned in **metres** (SI), the unit the thesis uses for lengths.

    **Range of validity:** k > 0 only for MOBN < 11, so MOBN must lie in (0, 11); j0 is
    negative for MOBN > 7.54 (no threshold, a delayed shear build-up instead) — allowed.

    **Arguments:**

    - `mobility_number`: MOBN [-], 0 < MOBN < 11.

    **Returns:** `(j0, k)`: threshold shear displacement j0 [m] and shear deformation
    modulus k [m], ready for [`snowjax.gawwad_crolla_shear`][].
    """
    _check(
        "mobility_number",
        mobility_number,
        lambda m: (m > 0) & (m < _GC_MAX_MOBILITY),
        f"in (0, {_GC_MAX_MOBILITY:g}) (k = -0.06 + 0.66/MOBN must stay > 0)",
    )
    m = jnp.asarray(mobility_number)
    valid = (m > 0) & (m < _GC_MAX_MOBILITY)
    m_s = _safe(valid, m)
    j0 = -0.065 + 0.49 / m_s
    k = -0.06 + 0.66 / m_s
    return _nan_unless(valid, j0), _nan_unless(valid, k)
