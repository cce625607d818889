"""Empirical traction and motion-resistance models of chapter 2 of the thesis.

WES mobility coefficients (2.13)–(2.15), Brixius's wheel numeric and traction equations
(2.17)–(2.20), Abd El-Gawwad & Crolla's slip parameters (section 2.3.3), Richmond's motion
resistance in shallow snow (2.23), Bekker's compaction resistance (2.24)/(2.25) and
Van Es's rolling resistance in dry snow (2.26), plus a side-by-side comparison of every
motion-resistance model of the project (including the rigid wheel, eq. 4.16).

Every model is a pure, element-wise function that broadcasts its arguments with NumPy
rules, so it works unchanged under `jax.jit`, `jax.vmap` and `jax.grad`.  SI units
throughout: N, m, Pa, kg/m^3.

**Bad input.**  When the arguments are concrete (Python numbers, NumPy or JAX arrays
outside a trace) values outside the domain of a model raise a `ValueError` that names the
argument and the allowed range.  Under `jit`/`vmap`/`grad` (tracers) that check cannot run;
an element outside the domain then evaluates to NaN — and only that element: the NaN is
produced by `jnp.where` on a safe branch, so the value and gradient of every valid element
stay finite.

Equation numbers refer to Sankapalli (2004), *Predictive semi-empirical analysis for
tire/snow interaction*, MSc thesis, University of Alaska Fairbanks.
"""

from __future__ import annotations

import math
from typing import Literal

import equinox as eqx
import jax.numpy as jnp
import jax.scipy.special as jsp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from .._leaves import _is_traced as _traced

__all__ = [
    "net_traction_coefficient",
    "rolling_resistance_coefficient",
    "gross_traction_coefficient",
    "brixius_wheel_numeric",
    "BrixiusTraction",
    "brixius",
    "gawwad_crolla_slip_parameters",
    "richmond_resistance",
    "bekker_compaction_resistance",
    "bekker_wheel_sinkage",
    "bekker_rolling_resistance",
    "van_es_compaction_resistance",
    "van_es_rolling_resistance",
    "compare_motion_resistance",
    "ICE_DENSITY",
]

ICE_DENSITY = 917.0  # [kg/m^3] density of ice, rho_i of Van Es's model (section 2.4.3)

# Richmond's fit (2.23): R = 21.313 (rho_0 a w)^1.1918, (rho_0 a w) in kg/m, R in N.
_RICHMOND_COEFFICIENT = 21.313
_RICHMOND_EXPONENT = 1.1918

# Brixius's slip coefficients (a in 1 - exp(-a S), c in c S / sqrt(N_B)).
_BRIXIUS_SLIP_COEFFICIENTS = {
    "thesis": (0.75, 0.05),  # as printed in the thesis, eqs. (2.18)-(2.20)
    "brixius1987": (7.5, 0.5),  # Brixius (1987) / ASAE D497, slip as a fraction
}


# ----------------------------------------------------------------------------------------
# input checks
# ----------------------------------------------------------------------------------------


def _is_traced(*values) -> bool:
    return any(_traced(v) for v in values)


def _describe(value) -> str:
    arr = np.asarray(value)
    if arr.size == 1:
        return repr(float(arr.reshape(())))
    bad = arr.reshape(-1)
    return f"an array of shape {arr.shape} (min {np.nanmin(bad):g}, max {np.nanmax(bad):g})"


def _check(name: str, value, ok, allowed: str) -> None:
    """Raise `ValueError` unless `ok(value)` holds everywhere; skipped for tracers."""
    if _is_traced(value):
        return
    arr = np.asarray(value, dtype=float)
    with np.errstate(invalid="ignore"):
        good = np.all(ok(arr))
    if not good:
        raise ValueError(f"`{name}` must be {allowed}; got {_describe(arr)}.")


def _positive(name, value, unit):
    _check(name, value, lambda x: x > 0, f"> 0 {unit} (finite)")
    _check(name, value, np.isfinite, f"finite and > 0 {unit}")


def _nonnegative(name, value, unit):
    _check(name, value, lambda x: (x >= 0) & np.isfinite(x), f"finite and >= 0 {unit}")


def _check_pair(message: str, a, b, ok) -> None:
    """Raise `ValueError(message)` unless `ok(a, b)` (broadcast) holds; skipped for tracers."""
    if _is_traced(a, b):
        return
    with np.errstate(invalid="ignore", divide="ignore"):
        good = np.all(ok(np.asarray(a, dtype=float), np.asarray(b, dtype=float)))
    if not good:
        raise ValueError(message)


def _nan_unless(valid: Array, value: Array) -> Array:
    return jnp.where(valid, value, jnp.nan)


def _safe(valid: Array, x: Array, fill: float = 1.0) -> Array:
    return jnp.where(valid, x, fill)


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


# ----------------------------------------------------------------------------------------
# Richmond, eq. (2.23)
# ----------------------------------------------------------------------------------------


def richmond_resistance(
    density: Float[ArrayLike, "..."],
    contact_length: Float[ArrayLike, "..."],
    width: Float[ArrayLike, "..."],
) -> Float[Array, "..."]:
    """Richmond's motion resistance of a wheel in shallow snow, eq. (2.23).

    `R_s = 21.313 (rho_0 a w)^1.1918`.

    Source: Richmond, P. W., *Motion resistance of wheeled vehicles in snow*, USA CRREL
    (the thesis cites CRREL Report 90-9, Blaisdell et al., *Wheels and tracks in snow:
    validation study of the CRREL shallow snow mobility model*, and [38]); the same
    equation is quoted by Richmond (1995), CRREL Report 95-7, as "the currently used
    shallow snow resistance" equation of Richmond et al. (1990).

    **Units.**  CRREL Report 95-7 states that the term (rho_0 w a) is in **kilograms per
    metre** (rho_0 in kg/m^3, a and w in m), and the resistance is in **newtons** — the
    SI units of this function, so no conversion is needed.  Sanity check: a 0.235 m wide
    tyre with a 0.2 m contact arc in 200 kg/m^3 snow gives rho_0 a w = 9.4 kg/m and
    R_s = 308 N, a resistance coefficient of 0.04–0.1 for a 3–8 kN wheel load.

    **Range of validity:** a leading (first-pass) wheel in undisturbed shallow snow; the
    resistance is due to the snow only (the hard-surface rolling resistance of the tyre
    is not included).  The CRREL data behind it are shallow natural snow packs (the
    1993 tests of Report 95-7 span initial densities of 110–250 kg/m^3 and depths of
    0.10–0.37 m); the thesis quotes no range.

    **Arguments:**

    - `density`: rho_0, average initial undisturbed snow density [kg/m^3],
      0 < rho_0 <= 917 (ice).
    - `contact_length`: a, arc length of the tyre in contact with the snow [m], >= 0.
    - `width`: w, maximum tyre width [m], > 0.

    **Returns:** motion resistance R_s [N].
    """
    _check(
        "density",
        density,
        lambda r: (r > 0) & (r <= ICE_DENSITY),
        f"in (0, {ICE_DENSITY:g}] kg/m^3 (a snow density, in kg/m^3 — not g/cm^3)",
    )
    _nonnegative("contact_length", contact_length, "m")
    _positive("width", width, "m")
    rho, a, w = (jnp.asarray(x) for x in (density, contact_length, width))
    valid = (rho > 0) & (rho <= ICE_DENSITY) & (a >= 0) & (w > 0)
    x = rho * a * w
    positive = valid & (x > 0)
    value = _RICHMOND_COEFFICIENT * _safe(positive, x) ** _RICHMOND_EXPONENT
    return _nan_unless(valid, jnp.where(positive, value, 0.0))


# ----------------------------------------------------------------------------------------
# Bekker, eqs. (2.24), (2.25)
# ----------------------------------------------------------------------------------------


def _check_bekker(width, k_c, k_phi, n, *, max_n=None):
    _positive("width", width, "m")
    if max_n is None:
        _check("n", n, lambda x: (x >= 0) & np.isfinite(x), "finite and >= 0")
    else:
        _check("n", n, lambda x: (x >= 0) & (x < max_n), f"in [0, {max_n:g})")
    if not _is_traced(k_c, width, k_phi):
        modulus = np.asarray(k_c, dtype=float) / np.asarray(width, dtype=float) + np.asarray(
            k_phi, dtype=float
        )
        if not np.all((modulus > 0) & np.isfinite(modulus)):
            raise ValueError(
                "`k_c / width + k_phi` must be finite and > 0 (the modulus of Bekker's law "
                "2.1, N/m^(n+2)); check the signs and units of `k_c` [N/m^(n+1)] and "
                f"`k_phi` [N/m^(n+2)]; got {_describe(modulus)}."
            )


def bekker_compaction_resistance(
    sinkage: Float[ArrayLike, "..."],
    width: Float[ArrayLike, "..."],
    k_c: Float[ArrayLike, "..."],
    k_phi: Float[ArrayLike, "..."],
    n: Float[ArrayLike, "..."],
) -> Float[Array, "..."]:
    """Bekker's compaction resistance of a wheel from its sinkage, eq. (2.24).

    `R_c = b (k_c / b + k_phi) z0^(n+1) / (n + 1)`

    — the work per unit travel of pressing a plate of width b to the depth z0 in a soil
    obeying Bekker's pressure–sinkage law (2.1).

    Source: Bekker, M. G., *Introduction to terrain–vehicle systems* (1969) [4 in the
    thesis].  **Range of validity:** homogeneous terrain of unlimited depth (Bekker's law);
    the radial-pressure assumption of the derivation is stated in the thesis; Wong
    (*Theory of Ground Vehicles*) recommends Bekker's rigid-wheel method for moderate
    sinkage (z0 <= D/6) and wheels larger than about 0.5 m in diameter.

    **Arguments:**

    - `sinkage`: z0, wheel sinkage [m], >= 0.
    - `width`: b, wheel width [m], > 0.
    - `k_c`: cohesive modulus [N/m^(n+1)].
    - `k_phi`: frictional modulus [N/m^(n+2)]; `k_c / b + k_phi` must be > 0.
    - `n`: sinkage exponent [-], >= 0.

    **Returns:** compaction (motion) resistance R_c [N].
    """
    _nonnegative("sinkage", sinkage, "m")
    _check_bekker(width, k_c, k_phi, n)
    z, b, kc, kp, nn = (jnp.asarray(x) for x in (sinkage, width, k_c, k_phi, n))
    valid = (z >= 0) & (b > 0) & (nn >= 0)
    b_s = _safe(valid, b)
    modulus = kc / b_s + kp
    valid = valid & (modulus > 0)
    nn_s = _safe(valid, nn, 0.0)
    positive = valid & (z > 0)
    z_pow = jnp.where(positive, _safe(positive, z) ** (nn_s + 1), 0.0)
    return _nan_unless(valid, b_s * modulus * z_pow / (nn_s + 1))


def bekker_wheel_sinkage(
    load: Float[ArrayLike, "..."],
    diameter: Float[ArrayLike, "..."],
    width: Float[ArrayLike, "..."],
    k_c: Float[ArrayLike, "..."],
    k_phi: Float[ArrayLike, "..."],
    n: Float[ArrayLike, "..."],
) -> Float[Array, "..."]:
    """Bekker's closed-form sinkage of a rigid wheel, the sinkage that turns (2.24) into
    (2.25):

    `z0 = [3 W / ((3 - n) (k_c + b k_phi) sqrt(D))]^(2 / (2n + 1))`.

    Source: Bekker (1969) [4 in the thesis]; obtained from vertical equilibrium of a
    rigid wheel in Bekker soil with the contact length approximated by sqrt(D z0).
    **Range of validity:** as [`snowjax.bekker_compaction_resistance`][]
    (z0 <= D/6, D >~ 0.5 m, unlimited depth) and n < 3.

    **Arguments:**

    - `load`: W, wheel load [N], >= 0.
    - `diameter`: D, wheel diameter [m], > 0.
    - `width`: b, wheel width [m], > 0.
    - `k_c` [N/m^(n+1)], `k_phi` [N/m^(n+2)]: Bekker's moduli, `k_c / b + k_phi > 0`.
    - `n`: sinkage exponent [-], 0 <= n < 3.

    **Returns:** sinkage z0 [m].
    """
    _check_rolling(load, diameter, width, k_c, k_phi, n)
    base, exponent, valid = _bekker_wheel_base(load, diameter, width, k_c, k_phi, n)
    positive = valid & (base > 0)
    z0 = jnp.where(positive, _safe(positive, base) ** (2 * exponent), 0.0)
    return _nan_unless(valid, z0)


def _check_rolling(load, diameter, width, k_c, k_phi, n):
    _nonnegative("load", load, "N")
    _positive("diameter", diameter, "m")
    _check_bekker(width, k_c, k_phi, n, max_n=3.0)


def _bekker_wheel_base(load, diameter, width, k_c, k_phi, n):
    """`3 W / ((3 - n)(k_c + b k_phi) sqrt(D))` and `1 / (2n + 1)`, with validity."""
    w, d, b, kc, kp, nn = (jnp.asarray(x) for x in (load, diameter, width, k_c, k_phi, n))
    valid = (w >= 0) & (d > 0) & (b > 0) & (nn >= 0) & (nn < 3)
    stiffness = kc + b * kp
    valid = valid & (stiffness > 0)
    nn_s = _safe(valid, nn, 0.0)
    base = 3 * w / ((3 - nn_s) * _safe(valid, stiffness) * jnp.sqrt(_safe(valid, d)))
    return base, 1.0 / (2 * nn_s + 1), valid


def bekker_rolling_resistance(
    load: Float[ArrayLike, "..."],
    diameter: Float[ArrayLike, "..."],
    width: Float[ArrayLike, "..."],
    k_c: Float[ArrayLike, "..."],
    k_phi: Float[ArrayLike, "..."],
    n: Float[ArrayLike, "..."],
) -> Float[Array, "..."]:
    """Bekker's compaction resistance of a rigid wheel in closed form, eq. (2.25).

    `R_c = (3 W / sqrt(D))^((2n+2)/(2n+1))
           / [(3 - n)^((2n+2)/(2n+1)) (n + 1) b^(1/(2n+1)) (k_c / b + k_phi)^(1/(2n+1))]`

    It equals (2.24) evaluated at [`snowjax.bekker_wheel_sinkage`][].

    Source: Bekker (1969) [4 in the thesis].  **Range of validity:** homogeneous soil of
    unlimited depth, n < 3 (the factor 3 - n), moderate sinkage (z0 <= D/6) and wheels
    larger than about 0.5 m (Wong, *Theory of Ground Vehicles*); the thesis notes that the
    assumed pressure distribution (maximum at the bottom dead centre) disagrees with
    measurements, which show the peak ahead of it, moving with slip.

    **Arguments:**

    - `load`: W, wheel load [N], >= 0.
    - `diameter`: D, wheel diameter [m], > 0.
    - `width`: b, wheel width [m], > 0.
    - `k_c` [N/m^(n+1)], `k_phi` [N/m^(n+2)]: Bekker's moduli, `k_c / b + k_phi > 0`.
    - `n`: sinkage exponent [-], 0 <= n < 3.

    **Returns:** compaction (motion) resistance R_c [N].
    """
    _check_rolling(load, diameter, width, k_c, k_phi, n)
    w, d, b, kc, kp, nn = (jnp.asarray(x) for x in (load, diameter, width, k_c, k_phi, n))
    valid = (w >= 0) & (d > 0) & (b > 0) & (nn >= 0) & (nn < 3)
    b_s = _safe(valid, b)
    modulus = kc / b_s + kp
    valid = valid & (modulus > 0)
    nn_s = _safe(valid, nn, 0.0)
    m = 1.0 / (2 * nn_s + 1)
    p = (2 * nn_s + 2) * m
    force = 3 * w / jnp.sqrt(_safe(valid, d))
    positive = valid & (force > 0)
    numerator = jnp.where(positive, _safe(positive, force) ** p, 0.0)
    denominator = (3 - nn_s) ** p * (nn_s + 1) * b_s**m * _safe(valid, modulus) ** m
    return _nan_unless(valid, numerator / denominator)


# ----------------------------------------------------------------------------------------
# Van Es, eq. (2.26)
# ----------------------------------------------------------------------------------------


def _check_van_es(
    width, snow_depth, initial_density, final_density, ice_pressure, grain_index, ice_density
):
    _positive("width", width, "m")
    _nonnegative("snow_depth", snow_depth, "m")
    _positive("ice_pressure", ice_pressure, "Pa")
    _check(
        "grain_index",
        grain_index,
        lambda x: (x > 0) & np.isfinite(x),
        "finite and > 0 (Van Es: 1 to 2, 1 for natural snow)",
    )
    _positive("ice_density", ice_density, "kg/m^3")
    _positive("initial_density", initial_density, "kg/m^3")
    _check_pair(
        "`initial_density` must not exceed `ice_density` (snow is less dense than ice).",
        initial_density,
        ice_density,
        lambda r0, ri: r0 <= ri,
    )
    _check_pair(
        "`final_density` must lie in [initial_density, ice_density]: compaction cannot "
        "loosen the snow, nor compress it beyond ice.",
        final_density,
        initial_density,
        lambda rf, r0: rf >= r0,
    )
    _check_pair(
        "`final_density` must lie in [initial_density, ice_density]: compaction cannot "
        "loosen the snow, nor compress it beyond ice.",
        final_density,
        ice_density,
        lambda rf, ri: rf <= ri,
    )


def van_es_compaction_resistance(
    width: Float[ArrayLike, "..."],
    snow_depth: Float[ArrayLike, "..."],
    initial_density: Float[ArrayLike, "..."],
    final_density: Float[ArrayLike, "..."],
    ice_pressure: Float[ArrayLike, "..."],
    *,
    grain_index: Float[ArrayLike, "..."] = 1.0,
    ice_density: Float[ArrayLike, "..."] = ICE_DENSITY,
) -> Float[Array, "..."]:
    """Van Es's compaction resistance of a tyre in dry snow, the D_c term of eq. (2.26).

    `D_c = b sigma_i rho_0 h_0 / (rho_i sqrt(lambda)) * int_{u_f}^{u_0} exp(-u^2) du`

    with `u_0 = sqrt(lambda) (rho_i / rho_0 - 1)`, `u_f = sqrt(lambda) (rho_i / rho_f - 1)`
    and `int_{u_f}^{u_0} exp(-u^2) du = (sqrt(pi)/2) (erf(u_0) - erf(u_f))`, evaluated as
    `(sqrt(pi)/2) (erfc(u_f) - erfc(u_0))` (the same number, without the cancellation of
    two erf values close to 1; u_0 >= u_f >= 0).

    **sigma_i (undefined in the thesis).**  The formula is exactly the compaction work per
    unit travel, `b * int p dh`, of a snow column of initial depth h_0 compressed from
    rho_0 to rho_f (mass conservation: h rho = h_0 rho_0) under the pressure–void-ratio law

    `p(r) = sigma_i exp(-lambda r^2)`,  r = rho_i / rho - 1  (the void ratio),

    so sigma_i is the **pressure scale of that compaction law: the (extrapolated) pressure
    that would compress the snow to the density of ice (r = 0)** [Pa].  It must be
    supplied by the user (no value is given in the thesis).  The law also fixes the final
    density reached under a contact pressure p: `rho_f = rho_i / (1 + sqrt(ln(sigma_i/p)
    / lambda))` for p < sigma_i.

    Source: Van Es, G. W. H., *Method for prediction of rolling resistance of aircraft
    tires in dry snow*, Journal of Aircraft 36(5), 762–768 (1999) [40 in the thesis].
    **Range of validity:** dry snow (the method is for aircraft tyres rolling on
    snow-covered runways); lambda from 1 to 2, 1 for natural snow (thesis).

    **Arguments:**

    - `width`: b, effective tyre width at the snow surface [m], > 0.
    - `snow_depth`: h_0, initial snow depth [m], >= 0.
    - `initial_density`: rho_0 [kg/m^3], 0 < rho_0 <= rho_i.
    - `final_density`: rho_f, density after compaction [kg/m^3], rho_0 <= rho_f <= rho_i.
    - `ice_pressure`: sigma_i, pressure scale of the compaction law (see above) [Pa], > 0.
    - `grain_index`: lambda, grain structure index [-], > 0 (1 to 2; 1 for natural snow).
    - `ice_density`: rho_i [kg/m^3] (default 917).

    **Returns:** compaction resistance D_c [N].
    """
    _check_van_es(
        width, snow_depth, initial_density, final_density, ice_pressure, grain_index, ice_density
    )
    b, h0, rho0, rhof, sig, lam, rhoi = (
        jnp.asarray(x)
        for x in (
            width,
            snow_depth,
            initial_density,
            final_density,
            ice_pressure,
            grain_index,
            ice_density,
        )
    )
    valid = (
        (b > 0)
        & (h0 >= 0)
        & (sig > 0)
        & (lam > 0)
        & (rhoi > 0)
        & (rho0 > 0)
        & (rho0 <= rhof)
        & (rhof <= rhoi)
    )
    rho0_s = _safe(valid, rho0)
    rhof_s = _safe(valid, rhof)
    rhoi_s = _safe(valid, rhoi)
    sqrt_lam = jnp.sqrt(_safe(valid, lam))
    u0 = sqrt_lam * (rhoi_s / rho0_s - 1)
    uf = sqrt_lam * (rhoi_s / rhof_s - 1)
    integral = 0.5 * math.sqrt(math.pi) * (jsp.erfc(uf) - jsp.erfc(u0))
    d_c = b * sig * rho0_s * h0 / (rhoi_s * sqrt_lam) * integral
    return _nan_unless(valid, d_c)


def van_es_rolling_resistance(
    load: Float[ArrayLike, "..."],
    width: Float[ArrayLike, "..."],
    snow_depth: Float[ArrayLike, "..."],
    initial_density: Float[ArrayLike, "..."],
    final_density: Float[ArrayLike, "..."],
    ice_pressure: Float[ArrayLike, "..."],
    hard_surface_coefficient: Float[ArrayLike, "..."],
    *,
    displacement_drag: Float[ArrayLike, "..."] = 0.0,
    grain_index: Float[ArrayLike, "..."] = 1.0,
    ice_density: Float[ArrayLike, "..."] = ICE_DENSITY,
) -> Float[Array, "..."]:
    """Van Es's total rolling resistance of a tyre in dry snow, eq. (2.26).

    `D_rolling = D_r + D_c + D_d`

    - `D_c`: compaction resistance, [`snowjax.van_es_compaction_resistance`][] (see there
      for sigma_i, which the thesis leaves undefined).
    - `D_r`: rolling resistance on a dry hard surface.  **Not defined in the thesis**;
      here `D_r = f_r W` with a user-supplied hard-surface rolling-resistance coefficient
      f_r (no default: typically 0.01–0.02 for road/aircraft tyres; pass 0 to keep only
      the snow's share).
    - `D_d`: displacement drag (the snow pushed ahead of and aside by the tyre).  **Not
      defined in the thesis**; a user input in N, default 0 — negligible at the taxi
      speeds of Van Es's comparisons, but it grows with speed in Van Es's method, so give
      it at high speed.

    Source: Van Es (1999) [40 in the thesis].  **Range of validity:** dry snow, as
    [`snowjax.van_es_compaction_resistance`][].

    **Arguments:**

    - `load`: W, wheel load [N], >= 0.
    - `width`, `snow_depth`, `initial_density`, `final_density`, `ice_pressure`,
      `grain_index`, `ice_density`: as [`snowjax.van_es_compaction_resistance`][]
      ([m], [m], [kg/m^3], [kg/m^3], [Pa], [-], [kg/m^3]).
    - `hard_surface_coefficient`: f_r, rolling-resistance coefficient on a hard surface
      [-], >= 0.
    - `displacement_drag`: D_d [N], >= 0 (default 0).

    **Returns:** total rolling resistance D_rolling [N].
    """
    _nonnegative("load", load, "N")
    _nonnegative("hard_surface_coefficient", hard_surface_coefficient, "")
    _nonnegative("displacement_drag", displacement_drag, "N")
    d_c = van_es_compaction_resistance(
        width,
        snow_depth,
        initial_density,
        final_density,
        ice_pressure,
        grain_index=grain_index,
        ice_density=ice_density,
    )
    w, f_r, d_d = (jnp.asarray(x) for x in (load, hard_surface_coefficient, displacement_drag))
    valid = (w >= 0) & (f_r >= 0) & (d_d >= 0)
    return _nan_unless(valid, f_r * w + d_c + d_d)


# ----------------------------------------------------------------------------------------
# comparison of every motion-resistance model (issue 4, part 6)
# ----------------------------------------------------------------------------------------

# Default sigma_i for the comparison: the compaction law p = sigma_i exp(-lambda r^2) with
# lambda = 1 reaches rho_f = 500 kg/m^3 at 210 kPa — CRREL's final-density rule for tyres
# with a peak contact pressure up to 210 kPa (Richmond 1995, CRREL Report 95-7).
_CRREL_FINAL_DENSITY = 500.0  # [kg/m^3]
_CRREL_PRESSURE = 210e3  # [Pa]
DEFAULT_ICE_PRESSURE = _CRREL_PRESSURE * math.exp((ICE_DENSITY / _CRREL_FINAL_DENSITY - 1) ** 2)


def compare_motion_resistance(
    loads=None,
    *,
    wheel=None,
    wong_snow=None,
    bekker_snow=None,
    density: float = 200.0,
    snow_depth: float | None = None,
    slip: float = 0.0,
    ice_pressure: float = DEFAULT_ICE_PRESSURE,
    grain_index: float = 1.0,
    hard_surface_coefficient: float = 0.0,
    cone_index: float | None = None,
    section_height: float | None = None,
    deflection: float = 0.0,
    shear: str = "classic",
):
    """Motion resistance versus wheel load for every model of the project, one snow, one tyre.

    Models (all in N, per wheel):

    - `rigid_wheel`: the rigid-wheel equilibrium of chapter 4, eq. (4.16), with the Wong
      snow `wong_snow` at slip `slip` (via `snowjax.solve_wheel`).
    - `bekker`: Bekker's closed form (2.25) with the Bekker fit `bekker_snow` (unlimited
      depth).  `bekker_sinkage` (its z0) is reported too.
    - `richmond`: Richmond (2.23) with rho_0 = `density` and the contact arc
      a = r theta_0, theta_0 the rigid wheel's entry angle (the rut the same tyre makes
      in the same snow).  Without the rigid-wheel solver, a = r arccos(1 - z0/r) from
      Bekker's sinkage z0 instead (flagged in `table["richmond_contact"]`).
    - `van_es`: Van Es (2.26) with D_r = `hard_surface_coefficient` W (default 0: only the
      snow's share, like the other models), D_d = 0, rho_0 = `density`, h_0 =
      `snow_depth`, lambda = `grain_index`, sigma_i = `ice_pressure`, and the final density
      from mass conservation in the rut of the rigid wheel:
      rho_f = min(rho_0 h_0 / (h_0 - z0), rho_i), z0 the rigid-wheel sinkage.
      The default sigma_i = 421 kPa makes Van Es's compaction law reach 500 kg/m^3 at
      210 kPa — CRREL's final-density rule for tyres with peak contact pressure up to
      210 kPa (Richmond 1995, CRREL Report 95-7).  It is an assumption, not a thesis value.
    - `brixius` (only when `cone_index` is given — the thesis gives no cone index for its
      snow): mu_R W from eq. (2.20) (`variant="thesis"`) with `section_height` (then
      required) and `deflection`, at slip `slip`.

    Defaults: the thesis tyre (`RigidWheel.thesis_tire()`: D 0.736 m, b 0.235 m), the
    thesis's fresh snow (`WongSnow.thesis_fresh_snow()`, and its Bekker fit
    `BekkerSoil.thesis_lab_snow()`: Shoop's 200 kg/m^3 laboratory snow), snow depth
    h_0 = z_w = 0.2 m, loads 1–8 kN.

    **Arguments:**

    - `loads`: wheel loads [N] (default 15 loads from 1 to 8 kN).
    - `wheel`: `snowjax.RigidWheel`; `wong_snow`: `snowjax.WongSnow`;
      `bekker_snow`: `snowjax.BekkerSoil`.
    - `density`: rho_0 [kg/m^3]; `snow_depth`: h_0 [m] (default z_w of `wong_snow`).
    - `slip`: slip of the rigid wheel [-] (default 0, a towed wheel).
    - `ice_pressure`: sigma_i of Van Es [Pa]; `grain_index`: lambda [-].
    - `hard_surface_coefficient`: f_r of Van Es's D_r [-].
    - `cone_index` [Pa], `section_height` [m], `deflection` [m]: Brixius's inputs.
    - `shear`: shear model passed to `snowjax.solve_wheel`.

    **Returns:** `(table, figure)`: `table` is a dict of NumPy arrays keyed `"load"` [N]
    and one key per model [N] (NaN where the rigid-wheel solve neither converged nor
    bottomed out), plus `"rigid_wheel_sinkage"`, `"bekker_sinkage"`, `"contact_length"`
    [m], `"final_density"` [kg/m^3], `"rigid_wheel_status"` (`snowjax.Status` codes) and
    boolean `"<model>_in_range"` masks: Bekker z0 <= min(D/6, h_0); rigid wheel
    converged (not resting on the base); Van Es rho_f below ice density.  `figure` is a
    matplotlib `Figure` (Agg canvas, not shown) of motion resistance and resistance
    coefficient versus load; open markers are outside the stated range.
    """
    from .._terrain.bekker import BekkerSoil
    from .._terrain.wong import WongSnow
    from .._wheel.geometry import RigidWheel

    if loads is None:
        loads = np.linspace(1e3, 8e3, 15)
    loads = np.asarray(loads, dtype=float)
    _positive("loads", loads, "N")
    wheel = RigidWheel.thesis_tire() if wheel is None else wheel
    wong_snow = WongSnow.thesis_fresh_snow() if wong_snow is None else wong_snow
    bekker_snow = BekkerSoil.thesis_lab_snow() if bekker_snow is None else bekker_snow
    diameter = float(wheel.diameter)
    radius = diameter / 2
    width = float(wheel.width)
    h0 = float(wong_snow.z_w) if snow_depth is None else float(snow_depth)
    _positive("snow_depth", h0, "m")

    table: dict[str, np.ndarray] = {"load": loads}

    bekker_args = (diameter, width, bekker_snow.k_c, bekker_snow.k_phi, bekker_snow.n)
    table["bekker"] = np.asarray(bekker_rolling_resistance(loads, *bekker_args))
    table["bekker_sinkage"] = np.asarray(bekker_wheel_sinkage(loads, *bekker_args))

    solve_wheel = _find_solve_wheel()
    if solve_wheel is not None:
        state = solve_wheel(wheel, wong_snow, jnp.asarray(loads), jnp.asarray(slip), shear=shear)
        status = np.asarray(state.status)
        # converged (0) or resting on the base (1, sinkage = z_w): usable; anything else
        # (invalid, not converged, entry-angle limit) is reported as NaN, never plotted.
        usable = (status == 0) | (status == 1)
        table["rigid_wheel"] = np.where(usable, np.asarray(state.motion_resistance), np.nan)
        table["rigid_wheel_sinkage"] = np.where(usable, np.asarray(state.sinkage), np.nan)
        table["rigid_wheel_status"] = status
        entry_angle = np.where(usable, np.asarray(state.entry_angle), np.nan)
        rut = table["rigid_wheel_sinkage"]
        table["richmond_contact"] = np.array("rigid-wheel entry angle")
    else:
        z_b = np.minimum(table["bekker_sinkage"], radius)
        entry_angle = np.arccos(1 - z_b / radius)
        rut = table["bekker_sinkage"]
        table["richmond_contact"] = np.array("Bekker sinkage (rigid-wheel solver missing)")

    table["contact_length"] = radius * entry_angle
    arc = np.where(np.isfinite(entry_angle), table["contact_length"], 0.0)
    table["richmond"] = np.where(
        np.isfinite(entry_angle), np.asarray(richmond_resistance(density, arc, width)), np.nan
    )

    known = np.isfinite(rut)
    rut = np.minimum(np.where(known, rut, 0.0), h0)
    rho_f = np.where(rut < h0, density * h0 / np.maximum(h0 - rut, 1e-300), ICE_DENSITY)
    rho_f = np.clip(rho_f, density, ICE_DENSITY)
    van_es = van_es_rolling_resistance(
        loads,
        width,
        h0,
        density,
        rho_f,
        ice_pressure,
        hard_surface_coefficient,
        grain_index=grain_index,
    )
    table["final_density"] = np.where(known, rho_f, np.nan)
    table["van_es"] = np.where(known, np.asarray(van_es), np.nan)

    if cone_index is not None:
        if section_height is None:
            raise ValueError("`section_height` [m] is required with `cone_index` (Brixius).")
        mu_r = brixius(cone_index, width, diameter, loads, deflection, section_height, slip)
        table["brixius"] = np.asarray(mu_r.motion_resistance) * loads

    # where each model is inside the range its source states (open markers otherwise)
    table["bekker_in_range"] = table["bekker_sinkage"] <= min(diameter / 6, h0)
    if "rigid_wheel" in table:
        table["rigid_wheel_in_range"] = table["rigid_wheel_status"] == 0
    table["richmond_in_range"] = np.isfinite(table["richmond"])
    table["van_es_in_range"] = np.isfinite(table["van_es"]) & (table["final_density"] < ICE_DENSITY)
    figure = _comparison_figure(
        table,
        wheel_label=f"D {diameter:.3f} m, b {width:.3f} m",
        snow_label=f"rho0 {density:.0f} kg/m^3, h0 {h0:.2f} m",
    )
    return table, figure


_MODEL_LABELS = {
    "rigid_wheel": "rigid wheel, Wong snow (4.16)",
    "bekker": "Bekker closed form (2.25)",
    "richmond": "Richmond (2.23)",
    "van_es": "Van Es (2.26)",
    "brixius": "Brixius mu_R W (2.20)",
}


def _find_solve_wheel():
    try:
        from .._wheel import equilibrium as _wheel  # noqa: PLC0415
    except ImportError:
        return None
    return getattr(_wheel, "solve_wheel", None)


def _comparison_figure(table, *, wheel_label: str, snow_label: str):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    figure = Figure(figsize=(10, 4.2), layout="constrained")
    FigureCanvasAgg(figure)
    ax_force, ax_coeff = figure.subplots(1, 2)
    load_kn = table["load"] / 1e3
    for key, label in _MODEL_LABELS.items():
        if key not in table:
            continue
        force = np.asarray(table[key], dtype=float)
        inside = np.asarray(table.get(f"{key}_in_range", np.ones_like(force, dtype=bool)))
        for ax, y in ((ax_force, force), (ax_coeff, force / table["load"])):
            (line,) = ax.plot(load_kn, y, label=label)
            ax.plot(load_kn[inside], y[inside], "o", ms=4, color=line.get_color())
            ax.plot(load_kn[~inside], y[~inside], "o", ms=4, mfc="none", color=line.get_color())
    ax_force.set_xlabel("wheel load W [kN]")
    ax_force.set_ylabel("motion resistance [N]")
    ax_force.set_title("Motion resistance vs load")
    ax_coeff.set_xlabel("wheel load W [kN]")
    ax_coeff.set_ylabel("resistance coefficient R / W [-]")
    ax_coeff.set_title("Resistance coefficient vs load")
    for ax in (ax_force, ax_coeff):
        ax.grid(True, alpha=0.3)
    ax_force.legend(fontsize=8)
    figure.suptitle(
        f"Tyre {wheel_label}; snow {snow_label}   (open markers: outside the model's stated range)",
        fontsize=10,
    )
    return figure
