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

import jax.numpy as jnp
import jax.scipy.special as jsp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from .common import (
    _RICHMOND_COEFFICIENT,
    _RICHMOND_EXPONENT,
    ICE_DENSITY,
    _check,
    _check_pair,
    _describe,
    _is_traced,
    _nan_unless,
    _nonnegative,
    _positive,
    _safe,
)

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
