"""Tire–snow shear forces of chapter 3: slips, the shear distribution N(φ), pure and
combined forces, the load-dependent tire parameters and their sensitivity.

The model (Sankapalli 2004, section 3.1): the longitudinal and lateral slips are normalised
by the friction limit, `φ_x = C_s S / (μ_x F_z)` (3.7) and
`φ_y = C_α (1 + S_x) tan α / (μ_y F_z)` (3.8); the shear distribution
`N(φ) = 1 - exp(-φ - E1 φ² - E2 φ³)` (3.10) turns a normalised slip into the fraction of
the friction limit that is mobilised.  *Pure* forces apply N to each slip alone
(3.11–3.13); *combined* forces apply N to the combined slip `φ = |(φ_x, φ_y)|` (3.9) and
split it along the slip direction β (3.14–3.16).  The tire parameters C_s, C_α, μ_x, μ_y
and E1 are fitted functions of the load (3.17–3.21) whose published coefficients are in
kN; see :class:`TireCoefficients`.

**Conventions** (the same in every function of this module):

- *Units.*  SI in the API: load F_z in N, forces in N, stiffnesses C_s, C_α in N/rad,
  angles in rad.  The thesis's load functions (3.17)–(3.21) are written for F_z in kN and
  stiffness in kN/rad; the functions here convert the load to kN at the boundary, apply the
  published formula, and convert the stiffness back to N/rad.  Because C_s and F_z are in
  the same force unit, φ_x and φ_y are dimensionless either way.
- *Slip.*  `slip` is the project's slip i, the **driving slip** S_d of eq. (3.2) (= eq. 2.6's
  i): 0 = free rolling, 1 = spinning in place, negative = braking.  The thesis's generalised
  slip is `S_x = -i` (3.4).  The thesis plots its forces as positive for slips 0…1, so it
  evidently uses the slip magnitude in (3.7); here `φ_x = C_s i / (μ_x F_z)`, so that a
  driving slip gives a positive (tractive) F_x and a braking slip a negative F_x.  The factor
  `(1 + S_x)` of (3.8) is `(1 - i) = V_x / (ω r)`: the lateral normalised slip vanishes when
  the wheel spins in place (V_x = 0) and grows as a braked wheel locks.  The model is meant
  for `i <= 1`.  With this reading the thesis's finding F_pure >= F_combined (3.4.1) holds
  for every 0 <= i <= 1 (N is concave with N(0) = 0 for 0 <= E1 <= 1/2, and
  |1 - i| <= 1); reading (1 + S_x) as (1 + i) instead would break it at small slips.
- *Slip angle.*  α in rad, |α| < π/2.  F_y has the sign of α (odd symmetry), which is the
  ISO / Pacejka convention `tan α = -V_y / V_x` in which a positive slip angle gives a
  positive lateral force.  N(φ) is applied to |φ| and the sign restored, so the pure forces
  are odd in their slip and every lateral force is odd in α.
- *Directions.*  `beta_pure` and `beta_combined` are the directions of the pure and the
  combined resultant force.  The β of (3.14)–(3.15), tan β = φ_y / φ_x, is `beta_slip`;
  it equals `beta_combined` when μ_x = μ_y and depends on μ_x / μ_y otherwise, whereas
  the direction of the combined force never depends on μ (section 3.4.3).

Equation numbers refer to Sankapalli (2004), *Predictive semi-empirical analysis for
tire/snow interaction*, MSc thesis, University of Alaska Fairbanks, chapter 3.
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from .._leaves import _as_float, _is_traced

__all__ = [
    "longitudinal_slip",
    "driving_slip",
    "braking_slip",
    "longitudinal_from_driving_slip",
    "driving_from_longitudinal_slip",
    "longitudinal_from_braking_slip",
    "braking_from_longitudinal_slip",
    "shear_distribution",
    "normalized_longitudinal_slip",
    "normalized_lateral_slip",
    "normalized_combined_slip",
    "pure_longitudinal_force",
    "pure_lateral_force",
    "TireCoefficients",
    "TireParameters",
    "TireForces",
    "longitudinal_stiffness",
    "lateral_stiffness",
    "longitudinal_friction",
    "lateral_friction",
    "contact_pressure_constant",
    "tire_parameters",
    "tire_forces_from_parameters",
    "tire_forces",
    "ShearForceVariationRatios",
    "shear_force_variation_ratios",
    "TireSensitivities",
    "tire_force_sensitivities",
]

_KN = 1e3  # [N per kN]
# The load range of the FEA data the load functions were fitted to (Table 3.2).
THESIS_LOAD_RANGE = (3.5e3, 7.5e3)  # [N]


# ----------------------------------------------------------------------------------------
# Small numerically safe helpers (finite value *and* gradient everywhere)
# ----------------------------------------------------------------------------------------


def _safe_ratio(num: Array, den: Array) -> Array:
    """`num / den`; ±inf where den == 0 (sign of num), 0 where both are 0.

    The infinities are constants, so the gradient stays finite (zero) there.
    """
    num, den = jnp.asarray(num), jnp.asarray(den)
    zero = den == 0
    safe_den = jnp.where(zero, 1.0, den)
    limit = jnp.where(num > 0, jnp.inf, jnp.where(num < 0, -jnp.inf, 0.0))
    return jnp.where(zero, limit, num / safe_den)


def _safe_norm(a: Array, b: Array) -> Array:
    """`sqrt(a² + b²)` with gradient 0 (instead of NaN) at a = b = 0."""
    sq = a * a + b * b
    positive = sq > 0
    return jnp.where(positive, jnp.sqrt(jnp.where(positive, sq, 1.0)), 0.0)


def _safe_arctan2(y: Array, x: Array) -> Array:
    """`arctan2(y, x)`, defined as 0 (with gradient 0) at x = y = 0."""
    nonzero = (x * x + y * y) > 0
    safe_x = jnp.where(nonzero, x, 1.0)
    safe_y = jnp.where(nonzero, y, 0.0)
    return jnp.where(nonzero, jnp.arctan2(safe_y, safe_x), 0.0)


def _float_dtype(*xs) -> jnp.dtype:
    dtype = jnp.result_type(*xs)
    if not jnp.issubdtype(dtype, jnp.floating):
        dtype = jnp.result_type(float)
    return dtype


def _check(name: str, value, ok, allowed: str) -> None:
    """Eager input check: raise `ValueError` when a concrete `value` fails `ok`.

    Traced values (inside `jit`, `vmap`, `grad`) are not checked; the model then returns
    finite numbers for them (see the module docstring for the intended ranges).
    """
    if value is None or _is_traced(value):
        return
    arr = np.asarray(value)
    with np.errstate(invalid="ignore"):
        good = ok(arr)
    if not np.all(good):
        bad = arr[~good] if arr.ndim else arr
        raise ValueError(f"`{name}` must be {allowed}; got {np.ravel(bad)[:5]}.")


# ----------------------------------------------------------------------------------------
# 1. Slip definitions and conversions (3.1)–(3.4)
# ----------------------------------------------------------------------------------------


def longitudinal_slip(
    forward_speed: Float[ArrayLike, "..."],
    angular_speed: Float[ArrayLike, "..."],
    rolling_radius: Float[ArrayLike, "..."],
) -> Float[Array, "..."]:
    """Generalised longitudinal slip, eq. (3.1): `S_x = (V_x - ω r) / (ω r)`.

    Negative when driving (S_x = -S_d), positive when braking.

    **Arguments:**

    - `forward_speed`: V_x, linear speed of the tire centre [m/s].
    - `angular_speed`: ω, angular speed of the tire [rad/s].
    - `rolling_radius`: r, rolling radius of the free-rolling tire [m].

    **Returns:** S_x [-]; `+inf` for a locked wheel (ω = 0, V_x > 0), 0 at standstill.
    """
    wr = jnp.asarray(angular_speed) * jnp.asarray(rolling_radius)
    return _safe_ratio(jnp.asarray(forward_speed) - wr, wr)


def driving_slip(
    forward_speed: Float[ArrayLike, "..."],
    angular_speed: Float[ArrayLike, "..."],
    rolling_radius: Float[ArrayLike, "..."],
) -> Float[Array, "..."]:
    """Driving slip, eq. (3.2): `S_d = (ω r - V_x) / (ω r)` — the project's slip i.

    0 = free rolling, 1 = spinning in place; negative when braking.

    **Arguments:** `forward_speed` V_x [m/s], `angular_speed` ω [rad/s],
    `rolling_radius` r [m].

    **Returns:** S_d [-]; `-inf` for a locked wheel (ω = 0, V_x > 0), 0 at standstill.
    """
    wr = jnp.asarray(angular_speed) * jnp.asarray(rolling_radius)
    return _safe_ratio(wr - jnp.asarray(forward_speed), wr)


def braking_slip(
    forward_speed: Float[ArrayLike, "..."],
    angular_speed: Float[ArrayLike, "..."],
    rolling_radius: Float[ArrayLike, "..."],
) -> Float[Array, "..."]:
    """Braking slip, eq. (3.3): `S_b = (V_x - ω r) / V_x`.

    0 = free rolling, 1 = locked wheel; negative when driving.

    **Arguments:** `forward_speed` V_x [m/s], `angular_speed` ω [rad/s],
    `rolling_radius` r [m].

    **Returns:** S_b [-]; `-inf` when spinning in place (V_x = 0, ω r > 0), 0 at standstill.
    """
    v = jnp.asarray(forward_speed)
    wr = jnp.asarray(angular_speed) * jnp.asarray(rolling_radius)
    return _safe_ratio(v - wr, v)


def longitudinal_from_driving_slip(driving_slip: Float[ArrayLike, "..."]) -> Float[Array, "..."]:
    """Eq. (3.4): `S_x = -S_d`.  **Argument:** driving slip S_d [-].  **Returns:** S_x [-]."""
    return -jnp.asarray(driving_slip)


def driving_from_longitudinal_slip(
    longitudinal_slip: Float[ArrayLike, "..."],
) -> Float[Array, "..."]:
    """Eq. (3.4): `S_d = -S_x`.  **Argument:** longitudinal slip S_x [-].
    **Returns:** driving slip S_d [-]."""
    return -jnp.asarray(longitudinal_slip)


def longitudinal_from_braking_slip(braking_slip: Float[ArrayLike, "..."]) -> Float[Array, "..."]:
    """Eq. (3.4): `S_x = S_b / (1 - S_b)`.

    **Argument:** braking slip S_b [-].  **Returns:** S_x [-] (`+inf` at S_b = 1, a locked
    wheel).
    """
    s_b = jnp.asarray(braking_slip)
    return _safe_ratio(s_b, 1.0 - s_b)


def braking_from_longitudinal_slip(
    longitudinal_slip: Float[ArrayLike, "..."],
) -> Float[Array, "..."]:
    """Eq. (3.4): `S_b = S_x / (1 + S_x)`.

    **Argument:** longitudinal slip S_x [-].  **Returns:** S_b [-] (`-inf` at S_x = -1, a
    wheel spinning in place).
    """
    s_x = jnp.asarray(longitudinal_slip)
    return _safe_ratio(s_x, 1.0 + s_x)


# ----------------------------------------------------------------------------------------
# 2. Normalised slips (3.7)–(3.9) and the shear distribution (3.10)
# ----------------------------------------------------------------------------------------


def _e2(e1: Array) -> Array:
    """Second-order contact pressure constant, `E2 = E1² + 1/12` (below eq. 3.10)."""
    return e1 * e1 + 1.0 / 12.0


def shear_distribution(
    phi: Float[ArrayLike, "..."], e1: Float[ArrayLike, "..."]
) -> Float[Array, "..."]:
    """Normalised shear force, eq. (3.10): `N(φ) = 1 - exp(-φ - E1 φ² - E2 φ³)`.

    `E2 = E1² + 1/12`.  Boundary conditions (Table 3.1): N(0) = 0, N'(0) = 1,
    N''(0) = 2 E1 - 1, N'''(0) = 6 (E2 - E1) + 1, N(∞) = 1.

    This is the thesis's formula as written, meant for φ >= 0; the force functions apply it
    to |φ| and restore the sign of the slip.

    **Arguments:**

    - `phi`: normalised slip φ [-].
    - `e1`: first-order contact pressure constant E1 [-] (0 <= E1 <= 1/2 for N'' <= 0).

    **Returns:** N(φ) [-], the mobilised fraction of the friction limit.
    """
    phi = jnp.asarray(phi)
    e1 = jnp.asarray(e1)
    g = phi * (1.0 + phi * (e1 + phi * _e2(e1)))
    return -jnp.expm1(-g)


def _shear_distribution_over_phi(phi: Array, e1: Array) -> Array:
    """`N(φ) / φ` for φ >= 0, with its limit 1 at φ = 0 and 0 at φ = ∞.

    Value and gradient are finite everywhere.  Below φ = eps^(1/4) (1.2e-4 in float64) the
    Taylor series `1 + (E1 - 1/2) φ + (E2 - E1 + 1/6) φ² + (E1/2 - E1²/2 - E2 - 1/24) φ³`
    is used; its truncation error there is below eps.
    """
    phi, e1 = jnp.asarray(phi), jnp.asarray(e1)
    threshold = float(jnp.finfo(_float_dtype(phi, e1)).eps) ** 0.25
    small = phi < threshold
    phi_small = jnp.where(small, phi, 0.0)
    phi_large = jnp.where(small, 1.0, phi)
    e2 = _e2(e1)
    c1 = e1 - 0.5
    c2 = e2 - e1 + 1.0 / 6.0
    c3 = 0.5 * e1 - 0.5 * e1 * e1 - e2 - 1.0 / 24.0
    series = 1.0 + phi_small * (c1 + phi_small * (c2 + phi_small * c3))
    direct = shear_distribution(phi_large, e1) / phi_large
    return jnp.where(small, series, direct)


def _signed_shear(phi: Array, e1: Array) -> Array:
    """`sign(φ) N(|φ|)` written as `φ · N(|φ|)/|φ|`: odd in φ, slope 1 at 0, finite gradient."""
    return phi * _shear_distribution_over_phi(jnp.abs(phi), e1)


def normalized_longitudinal_slip(
    load: Float[ArrayLike, "..."],
    slip: Float[ArrayLike, "..."],
    c_s: Float[ArrayLike, "..."],
    mu_x: Float[ArrayLike, "..."],
) -> Float[Array, "..."]:
    """Normalised longitudinal slip, eq. (3.7): `φ_x = C_s i / (μ_x F_z)`.

    The thesis writes `C_s S_x / (μ_x F_z)`; with the driving slip `i = -S_x` the sign is
    chosen so that driving gives φ_x > 0 (see the module docstring).

    **Arguments:**

    - `load`: normal load F_z [N].
    - `slip`: driving slip i [-] (0 free rolling, 1 spinning in place, < 0 braking).
    - `c_s`: longitudinal tire stiffness C_s = ∂F_x/∂S_x at S_x = 0 [N/rad].
    - `mu_x`: longitudinal friction coefficient μ_x [-].

    **Returns:** φ_x [-] (±inf for zero friction limit μ_x F_z = 0, 0 if also i = 0).
    """
    return _safe_ratio(jnp.asarray(c_s) * jnp.asarray(slip), jnp.asarray(mu_x) * jnp.asarray(load))


def normalized_lateral_slip(
    load: Float[ArrayLike, "..."],
    slip: Float[ArrayLike, "..."],
    slip_angle: Float[ArrayLike, "..."],
    c_alpha: Float[ArrayLike, "..."],
    mu_y: Float[ArrayLike, "..."],
) -> Float[Array, "..."]:
    """Normalised lateral slip, eq. (3.8): `φ_y = C_α (1 + S_x) tan α / (μ_y F_z)`.

    With the driving slip `i = -S_x`, `1 + S_x = 1 - i` (= V_x / ω r).

    **Arguments:**

    - `load`: normal load F_z [N].
    - `slip`: driving slip i [-].
    - `slip_angle`: α [rad], |α| < π/2.
    - `c_alpha`: lateral tire stiffness C_α = ∂F_y/∂α at α = 0 [N/rad].
    - `mu_y`: lateral friction coefficient μ_y [-].

    **Returns:** φ_y [-].
    """
    num = jnp.asarray(c_alpha) * (1.0 - jnp.asarray(slip)) * jnp.tan(jnp.asarray(slip_angle))
    return _safe_ratio(num, jnp.asarray(mu_y) * jnp.asarray(load))


def normalized_combined_slip(
    phi_x: Float[ArrayLike, "..."], phi_y: Float[ArrayLike, "..."]
) -> Float[Array, "..."]:
    """Normalised combined slip, eq. (3.9): `φ = sqrt(φ_x² + φ_y²)`.

    Its gradient at φ_x = φ_y = 0 is defined as 0 (a safe norm), never NaN.

    **Arguments:** `phi_x`, `phi_y`: normalised slips of (3.7), (3.8) [-].

    **Returns:** φ [-] >= 0.
    """
    return _safe_norm(jnp.asarray(phi_x), jnp.asarray(phi_y))


# ----------------------------------------------------------------------------------------
# 3. Forces (3.11)–(3.16)
# ----------------------------------------------------------------------------------------


def _guarded(strength: Array) -> Array:
    return jnp.where(strength != 0, strength, 1.0)


def pure_longitudinal_force(
    load: Float[ArrayLike, "..."],
    slip: Float[ArrayLike, "..."],
    c_s: Float[ArrayLike, "..."],
    mu_x: Float[ArrayLike, "..."],
    e1: Float[ArrayLike, "..."],
) -> Float[Array, "..."]:
    """Pure longitudinal shear force (zero slip angle), eq. (3.11):
    `F_x|α=0 = μ_x F_z N(φ_x)`, φ_x from (3.7), N from (3.10).

    Odd in the slip: positive (tractive) for driving slip, negative for braking.

    **Arguments:** `load` F_z [N]; `slip` driving slip i [-]; `c_s` [N/rad]; `mu_x` [-];
    `e1` contact pressure constant E1 [-].

    **Returns:** F_x [N] (0 when μ_x F_z = 0).
    """
    strength = jnp.asarray(mu_x) * jnp.asarray(load)
    phi_x = jnp.asarray(c_s) * jnp.asarray(slip) / _guarded(strength)
    return strength * _signed_shear(phi_x, jnp.asarray(e1))


def pure_lateral_force(
    load: Float[ArrayLike, "..."],
    slip_angle: Float[ArrayLike, "..."],
    c_alpha: Float[ArrayLike, "..."],
    mu_y: Float[ArrayLike, "..."],
    e1: Float[ArrayLike, "..."],
) -> Float[Array, "..."]:
    """Pure lateral shear force (zero slip), eq. (3.12):
    `F_y|S_x=0 = μ_y F_z N(φ_y|S_x=0)`, φ_y from (3.8) with S_x = 0.

    Odd in the slip angle.

    **Arguments:** `load` F_z [N]; `slip_angle` α [rad]; `c_alpha` [N/rad]; `mu_y` [-];
    `e1` [-].

    **Returns:** F_y [N].
    """
    strength = jnp.asarray(mu_y) * jnp.asarray(load)
    phi_y = jnp.asarray(c_alpha) * jnp.tan(jnp.asarray(slip_angle)) / _guarded(strength)
    return strength * _signed_shear(phi_y, jnp.asarray(e1))


class TireParameters(eqx.Module):
    """The five tire/snow parameters of the shear force model, in SI units.

    Build them from a load with :func:`tire_parameters` (eqs. 3.17–3.21), or directly to
    vary one parameter at a time (section 3.3).

    **Fields** (array leaves, broadcast against load, slip and slip angle):

    - `c_s`: longitudinal tire stiffness C_s [N/rad] (3.7, 3.17).
    - `c_alpha`: lateral tire stiffness C_α [N/rad] (3.8, 3.18).
    - `mu_x`: longitudinal friction coefficient μ_x [-] (3.19).
    - `mu_y`: lateral friction coefficient μ_y [-] (3.20).
    - `e1`: first-order contact pressure constant E1 [-] (3.10, 3.21); E2 = E1² + 1/12.
    """

    c_s: Float[Array, "..."] = eqx.field(converter=_as_float)
    c_alpha: Float[Array, "..."] = eqx.field(converter=_as_float)
    mu_x: Float[Array, "..."] = eqx.field(converter=_as_float)
    mu_y: Float[Array, "..."] = eqx.field(converter=_as_float)
    e1: Float[Array, "..."] = eqx.field(converter=_as_float)


class TireForces(eqx.Module):
    """Pure and combined shear forces of one tire (eqs. 3.11–3.16) and their directions.

    All fields have the broadcast shape of the inputs.

    **Fields:**

    - `fx_pure`: pure longitudinal force F_x|α=0 = μ_x F_z N(φ_x), eq. (3.11) [N].
    - `fy_pure`: pure lateral force F_y|S_x=0 = μ_y F_z N(φ_y|S_x=0), eq. (3.12) [N].
    - `pure`: F_pure = sqrt(fx_pure² + fy_pure²), eq. (3.13) [N].
    - `fx_combined`: combined longitudinal force μ_x F_z N(φ) cos β_φ, eq. (3.14) [N].
    - `fy_combined`: combined lateral force μ_y F_z N(φ) sin β_φ, eq. (3.15) [N].
    - `combined`: F_Σ = sqrt(fx_combined² + fy_combined²), eq. (3.16) [N].
    - `beta_pure`: direction of the pure resultant, atan2(fy_pure, fx_pure) [rad]
      (section 3.4.2).
    - `beta_combined`: direction of the combined resultant, atan2(fy_combined,
      fx_combined) = atan2(C_α (1 - i) tan α, C_s i) [rad] (sections 3.4.2–3.4.3).  The
      friction coefficients and the load cancel, so it depends on neither (for given
      C_s, C_α) — the thesis's finding of section 3.4.3.
    - `beta_slip`: β_φ of (3.14)–(3.15), tan β_φ = φ_y / φ_x [rad]: the direction of the
      normalised-slip vector.  Equals `beta_combined` in the isotropic case μ_x = μ_y.

    At zero slip and zero slip angle all angles are defined as 0.
    """

    fx_pure: Float[Array, "..."]
    fy_pure: Float[Array, "..."]
    pure: Float[Array, "..."]
    fx_combined: Float[Array, "..."]
    fy_combined: Float[Array, "..."]
    combined: Float[Array, "..."]
    beta_pure: Float[Array, "..."]
    beta_combined: Float[Array, "..."]
    beta_slip: Float[Array, "..."]


def _forces(load, slip, slip_angle, params: TireParameters) -> TireForces:
    """Eqs. (3.7)–(3.16) on broadcast arrays (no checks, no jit)."""
    arrays = jnp.broadcast_arrays(
        jnp.asarray(load),
        jnp.asarray(slip),
        jnp.asarray(slip_angle),
        params.c_s,
        params.c_alpha,
        params.mu_x,
        params.mu_y,
        params.e1,
    )
    dtype = _float_dtype(*arrays)
    load, slip, slip_angle, c_s, c_alpha, mu_x, mu_y, e1 = (a.astype(dtype) for a in arrays)

    strength_x = mu_x * load  # friction limits μ F_z [N]
    strength_y = mu_y * load
    tan_a = jnp.tan(slip_angle)
    long_num = c_s * slip  # C_s i [N]
    lat_num = c_alpha * tan_a  # C_α tan α [N]
    phi_x = long_num / _guarded(strength_x)  # (3.7)
    phi_y_pure = lat_num / _guarded(strength_y)  # (3.8) at S_x = 0
    phi_y = (1.0 - slip) * phi_y_pure  # (3.8), 1 + S_x = 1 - i

    # Pure forces (3.11)-(3.13).
    fx_pure = strength_x * _signed_shear(phi_x, e1)
    fy_pure = strength_y * _signed_shear(phi_y_pure, e1)
    pure = _safe_norm(fx_pure, fy_pure)

    # Combined forces (3.9), (3.14)-(3.16): μ F_z N(φ) cos β_φ = μ_x F_z φ_x N(φ)/φ.
    phi = _safe_norm(phi_x, phi_y)
    n_over_phi = _shear_distribution_over_phi(phi, e1)
    fx_combined = strength_x * phi_x * n_over_phi
    fy_combined = strength_y * phi_y * n_over_phi
    combined = _safe_norm(fx_combined, fy_combined)

    return TireForces(
        fx_pure=fx_pure,
        fy_pure=fy_pure,
        pure=pure,
        fx_combined=fx_combined,
        fy_combined=fy_combined,
        combined=combined,
        beta_pure=_safe_arctan2(fy_pure, fx_pure),
        # fy/fx = μ_y φ_y / (μ_x φ_x) = C_α (1 - i) tan α / (C_s i): μ and F_z cancel.
        beta_combined=_safe_arctan2((1.0 - slip) * lat_num, long_num),
        beta_slip=_safe_arctan2(phi_y, phi_x),
    )


def _check_operating_point(load, slip, slip_angle) -> None:
    _check("load", load, lambda x: x >= 0, "a normal load >= 0 N")
    _check("slip", slip, lambda x: x <= 1, "a driving slip <= 1 (1 = spinning in place)")
    _check(
        "slip_angle",
        slip_angle,
        lambda x: np.abs(x) < np.pi / 2,
        "a slip angle in rad with |slip_angle| < pi/2",
    )


def _check_parameters(params: TireParameters) -> None:
    _check("parameters.c_s", params.c_s, lambda x: x > 0, "> 0 N/rad")
    _check("parameters.c_alpha", params.c_alpha, lambda x: x > 0, "> 0 N/rad")
    _check("parameters.mu_x", params.mu_x, lambda x: x > 0, "> 0")
    _check("parameters.mu_y", params.mu_y, lambda x: x > 0, "> 0")
    _check("parameters.e1", params.e1, lambda x: (x >= 0) & (x <= 0.5), "in [0, 0.5]")


@eqx.filter_jit
def _forces_jit(load, slip, slip_angle, params):
    return _forces(load, slip, slip_angle, params)


def tire_forces_from_parameters(
    load: Float[ArrayLike, "..."],
    slip: Float[ArrayLike, "..."],
    slip_angle: Float[ArrayLike, "..."],
    parameters: TireParameters,
) -> TireForces:
    """Pure and combined shear forces for given tire parameters, eqs. (3.7)–(3.16).

    The lower-level form of :func:`tire_forces`: C_s, C_α, μ_x, μ_y and E1 are given
    directly instead of through the load functions (3.17)–(3.21), so one parameter can be
    varied at a time (section 3.3).

    **Arguments** (broadcast with NumPy rules):

    - `load`: normal load F_z [N], >= 0.
    - `slip`: driving slip i [-], <= 1 (0 free rolling, 1 spinning in place, < 0 braking).
    - `slip_angle`: α [rad], |α| < π/2.
    - `parameters`: a :class:`TireParameters` (C_s, C_α in N/rad).

    Concrete inputs out of range raise `ValueError`; under `jit`/`vmap`/`grad` they are
    not checked.  Gradients are finite everywhere, including zero slip and zero slip angle.

    **Returns:** a :class:`TireForces` [N, rad].
    """
    _check_operating_point(load, slip, slip_angle)
    _check_parameters(parameters)
    return _forces_jit(jnp.asarray(load), jnp.asarray(slip), jnp.asarray(slip_angle), parameters)


# ----------------------------------------------------------------------------------------
# 4. Load-dependent parameters (3.17)–(3.21)
# ----------------------------------------------------------------------------------------


class TireCoefficients(eqx.Module):
    """Coefficients of the load functions (3.17)–(3.21), **in the thesis's kN units**.

    The load functions evaluate `F_z` in kN (the API functions take N and divide by 1000)
    and give stiffness in kN/rad (converted to N/rad on return):

    - `C_s = F_z / (A4 + A5 F_z)` (3.17), `C_α = F_z / (B4 + B5 F_z)` (3.18) [kN/rad];
    - `μ_x = A1 + A2 F_z + A3 F_z²` (3.19), `μ_y = B1 + B2 F_z + B3 F_z²` (3.20);
    - `E1 = 0.5 [1 - exp(-a1² F_z - a2² F_z²)]` (3.21).

    **Fields** (array leaves; F_z in kN):

    - `A1` [-], `A2` [1/kN], `A3` [1/kN²]: longitudinal friction (3.19).
    - `A4` [rad], `A5` [rad/kN]: longitudinal stiffness (3.17) (the thesis writes A5 in
      (kN)⁻¹).
    - `B1` [-], `B2` [1/kN], `B3` [1/kN²]: lateral friction (3.20).
    - `B4` [rad], `B5` [rad/kN]: lateral stiffness (3.18).
    - `a1` [kN^(-1/2)], `a2` [1/kN]: contact pressure constant (3.21).

    The fits were made to FEA data for 3.5–7.5 kN (Table 3.2) on a 0.736 m tire in fresh
    snow; outside that range they are extrapolations (μ_x of (3.19) turns negative between
    16.7 and 46.8 kN).
    """

    A1: Float[Array, "..."] = eqx.field(converter=_as_float)
    A2: Float[Array, "..."] = eqx.field(converter=_as_float)
    A3: Float[Array, "..."] = eqx.field(converter=_as_float)
    A4: Float[Array, "..."] = eqx.field(converter=_as_float)
    A5: Float[Array, "..."] = eqx.field(converter=_as_float)
    B1: Float[Array, "..."] = eqx.field(converter=_as_float)
    B2: Float[Array, "..."] = eqx.field(converter=_as_float)
    B3: Float[Array, "..."] = eqx.field(converter=_as_float)
    B4: Float[Array, "..."] = eqx.field(converter=_as_float)
    B5: Float[Array, "..."] = eqx.field(converter=_as_float)
    a1: Float[Array, "..."] = eqx.field(converter=_as_float)
    a2: Float[Array, "..."] = eqx.field(converter=_as_float)

    @classmethod
    def thesis(cls) -> "TireCoefficients":
        """The published coefficients of section 3.2 (fitted to Table 3.2):

        A4 = 0.2026, A5 = 0.1516 /kN; B4 = 0.1936, B5 = 0.1190 /kN;
        A1 = 0.5386, A2 = -0.0438 /kN, A3 = 6.9010e-4 /kN²;
        B1 = 0.4131, B2 = -0.0673 /kN, B3 = 0.0037 /kN²; a1 = 7.5852e-9, a2 = 0.1203.
        """
        return cls(
            A1=0.5386,
            A2=-0.0438,
            A3=6.9010e-4,
            A4=0.2026,
            A5=0.1516,
            B1=0.4131,
            B2=-0.0673,
            B3=0.0037,
            B4=0.1936,
            B5=0.1190,
            a1=7.5852e-9,
            a2=0.1203,
        )


def _coefficients(coefficients: TireCoefficients | None) -> TireCoefficients:
    return TireCoefficients.thesis() if coefficients is None else coefficients


def _load_kn(load) -> Array:
    return jnp.asarray(load) / _KN


def longitudinal_stiffness(
    load: Float[ArrayLike, "..."], coefficients: TireCoefficients | None = None
) -> Float[Array, "..."]:
    """Longitudinal tire stiffness, eq. (3.17): `C_s = F_z / (A4 + A5 F_z)`, F_z in kN.

    **Arguments:**

    - `load`: normal load F_z [N] (converted to kN for the formula).
    - `coefficients`: a :class:`TireCoefficients` (default: the thesis's).

    **Returns:** C_s [N/rad] (the thesis's kN/rad times 1000).
    """
    c = _coefficients(coefficients)
    fz = _load_kn(load)
    return _KN * fz / (c.A4 + c.A5 * fz)


def lateral_stiffness(
    load: Float[ArrayLike, "..."], coefficients: TireCoefficients | None = None
) -> Float[Array, "..."]:
    """Lateral tire stiffness, eq. (3.18): `C_α = F_z / (B4 + B5 F_z)`, F_z in kN.

    **Arguments:** `load` F_z [N]; `coefficients` (default: the thesis's).

    **Returns:** C_α [N/rad] (the thesis's kN/rad times 1000).
    """
    c = _coefficients(coefficients)
    fz = _load_kn(load)
    return _KN * fz / (c.B4 + c.B5 * fz)


def longitudinal_friction(
    load: Float[ArrayLike, "..."], coefficients: TireCoefficients | None = None
) -> Float[Array, "..."]:
    """Longitudinal friction coefficient, eq. (3.19): `μ_x = A1 + A2 F_z + A3 F_z²`, F_z in
    kN.

    **Arguments:** `load` F_z [N]; `coefficients` (default: the thesis's).

    **Returns:** μ_x [-].
    """
    c = _coefficients(coefficients)
    fz = _load_kn(load)
    return c.A1 + fz * (c.A2 + fz * c.A3)


def lateral_friction(
    load: Float[ArrayLike, "..."], coefficients: TireCoefficients | None = None
) -> Float[Array, "..."]:
    """Lateral friction coefficient, eq. (3.20): `μ_y = B1 + B2 F_z + B3 F_z²`, F_z in kN.

    **Arguments:** `load` F_z [N]; `coefficients` (default: the thesis's).

    **Returns:** μ_y [-].
    """
    c = _coefficients(coefficients)
    fz = _load_kn(load)
    return c.B1 + fz * (c.B2 + fz * c.B3)


def contact_pressure_constant(
    load: Float[ArrayLike, "..."], coefficients: TireCoefficients | None = None
) -> Float[Array, "..."]:
    """First-order contact pressure constant, eq. (3.21):
    `E1 = 0.5 [1 - exp(-a1² F_z - a2² F_z²)]`, F_z in kN.

    **Arguments:** `load` F_z [N]; `coefficients` (default: the thesis's).

    **Returns:** E1 [-], in [0, 0.5).
    """
    c = _coefficients(coefficients)
    fz = _load_kn(load)
    return -0.5 * jnp.expm1(-(c.a1**2) * fz - (c.a2**2) * fz**2)


def tire_parameters(
    load: Float[ArrayLike, "..."], coefficients: TireCoefficients | None = None
) -> TireParameters:
    """All five tire parameters at a load, eqs. (3.17)–(3.21).

    **Arguments:**

    - `load`: normal load F_z [N] (converted to kN inside the fitted formulas).
    - `coefficients`: a :class:`TireCoefficients` in kN units (default: the thesis's).

    **Returns:** a :class:`TireParameters` with C_s, C_α in N/rad.
    """
    c = _coefficients(coefficients)
    return TireParameters(
        c_s=longitudinal_stiffness(load, c),
        c_alpha=lateral_stiffness(load, c),
        mu_x=longitudinal_friction(load, c),
        mu_y=lateral_friction(load, c),
        e1=contact_pressure_constant(load, c),
    )


# ----------------------------------------------------------------------------------------
# 5. Public entry point
# ----------------------------------------------------------------------------------------


@eqx.filter_jit
def _tire_forces_jit(load, slip, slip_angle, coefficients):
    load = jnp.maximum(load, 0.0)
    return _forces(load, slip, slip_angle, tire_parameters(load, coefficients))


def tire_forces(
    load: Float[ArrayLike, "..."],
    slip: Float[ArrayLike, "..."],
    slip_angle: Float[ArrayLike, "..."],
    coefficients: TireCoefficients | None = None,
) -> TireForces:
    """Pure and combined tire/snow shear forces at a load, slip and slip angle (chapter 3).

    The tire parameters come from the load functions (3.17)–(3.21) — whose coefficients
    are in kN; the load given here in N is converted — and the forces from (3.7)–(3.16).

    **Arguments** (broadcast with NumPy rules; every output has the broadcast shape):

    - `load`: normal load F_z [N], >= 0 (the fit covers 3.5–7.5 kN; negative loads are
      clipped to 0 under `jit`).
    - `slip`: driving slip i [-], <= 1: 0 free rolling, 1 spinning in place, negative
      braking (= -S_x of eq. 3.1).  Driving gives a positive (tractive) F_x.
    - `slip_angle`: α [rad], |α| < π/2; F_y has the sign of α.
    - `coefficients`: a :class:`TireCoefficients` (kN units); default the thesis's.

    Concrete inputs out of range raise `ValueError`; under `jit`/`vmap`/`grad` they are
    not checked.  Gradients are finite everywhere, including zero slip and zero slip angle.

    **Returns:** a :class:`TireForces`: `fx_pure, fy_pure, pure, fx_combined, fy_combined,
    combined` [N] and `beta_pure, beta_combined, beta_slip` [rad].

    Example: `snowjax.tire_forces(5000.0, 0.2, 0.1).combined`.
    """
    _check_operating_point(load, slip, slip_angle)
    return _tire_forces_jit(
        jnp.asarray(load), jnp.asarray(slip), jnp.asarray(slip_angle), coefficients
    )


# ----------------------------------------------------------------------------------------
# 6. Sensitivity analysis (section 3.3)
# ----------------------------------------------------------------------------------------


class ShearForceVariationRatios(eqx.Module):
    """The three "shear force variation ratios" of section 3.3.1 (pure longitudinal slip).

    With `F_x(F_z, μ_x, C_s, E1)` the pure longitudinal force (3.11), loads F_z1 < F_z2 and
    parameters `p_k = p(F_zk)` from (3.17), (3.19), (3.21), and the total variation
    `D = F_x(F_z2, μ_x2, C_s2, E1_2) - F_x(F_z1, μ_x1, C_s1, E1_1)`:

    - `stiffness`: `[F_x(F_z2, μ_x1, C_s2, E1_1) - F_x(F_z1, μ_x1, C_s1, E1_1)] / D` [-].
    - `friction`: `[F_x(F_z2, μ_x2, C_s1, E1_1) - F_x(F_z1, μ_x1, C_s1, E1_1)] / D` [-].
    - `pressure_constant`: `[F_x(F_z2, μ_x1, C_s1, E1_2) - F_x(F_z1, μ_x1, C_s1, E1_1)] / D`
      [-].

    Each numerator changes the load and one parameter, exactly as the thesis writes them,
    so the three ratios need not add up to 1.
    """

    stiffness: Float[Array, "..."]
    friction: Float[Array, "..."]
    pressure_constant: Float[Array, "..."]


@eqx.filter_jit
def _ratios_jit(slip, load_1, load_2, coefficients):
    p1 = tire_parameters(load_1, coefficients)
    p2 = tire_parameters(load_2, coefficients)

    def fx(load, mu_x, c_s, e1):  # argument order of the thesis, eq. (3.11)
        return pure_longitudinal_force(load, slip, c_s, mu_x, e1)

    base = fx(load_1, p1.mu_x, p1.c_s, p1.e1)
    total = fx(load_2, p2.mu_x, p2.c_s, p2.e1) - base
    numerators = (
        fx(load_2, p1.mu_x, p2.c_s, p1.e1) - base,
        fx(load_2, p2.mu_x, p1.c_s, p1.e1) - base,
        fx(load_2, p1.mu_x, p1.c_s, p2.e1) - base,
    )
    # Limits as slip -> 0, where F_x ~ C_s i: (C_s2 - C_s1)/(C_s2 - C_s1) = 1, 0, 0.
    limits = (1.0, 0.0, 0.0)
    zero = total == 0
    safe_total = jnp.where(zero, 1.0, total)
    ratios = [jnp.where(zero, lim, num / safe_total) for num, lim in zip(numerators, limits)]
    shape = jnp.broadcast_shapes(slip.shape, load_1.shape, load_2.shape)
    ratios = [jnp.broadcast_to(r, shape) for r in ratios]
    return ShearForceVariationRatios(*ratios)


def shear_force_variation_ratios(
    slip: Float[ArrayLike, "..."],
    load_1: Float[ArrayLike, "..."] = THESIS_LOAD_RANGE[0],
    load_2: Float[ArrayLike, "..."] = THESIS_LOAD_RANGE[1],
    coefficients: TireCoefficients | None = None,
) -> ShearForceVariationRatios:
    """Shear force variation ratios due to C_s, μ_x and E1 (section 3.3.1, Figure 3.6).

    The thesis does not state the two loads of Figure 3.6; the defaults are the ends of its
    FEA load range, 3.5 and 7.5 kN (Table 3.2).  (Its Figure 3.11 runs μ_x from 0.3938 to
    0.1696, i.e. (3.19) from 3.5 to 10 kN — pass `load_2=10e3` for that range.)

    **Arguments:**

    - `slip`: driving slip i [-] (the thesis plots 0…1).
    - `load_1`, `load_2`: the two normal loads F_z1, F_z2 [N] (converted to kN inside the
      load functions).
    - `coefficients`: a :class:`TireCoefficients` (default: the thesis's).

    At zero slip (0/0) the ratios take their limits 1, 0, 0 (F_x ≈ C_s i there).

    **Returns:** a :class:`ShearForceVariationRatios` [-], shaped like the broadcast inputs.
    """
    _check("slip", slip, lambda x: x <= 1, "a driving slip <= 1")
    _check("load_1", load_1, lambda x: x > 0, "a normal load > 0 N")
    _check("load_2", load_2, lambda x: x > 0, "a normal load > 0 N")
    if not _is_traced(load_1) and not _is_traced(load_2):
        if np.any(np.asarray(load_1) == np.asarray(load_2)):
            raise ValueError("`load_1` and `load_2` must differ.")
    return _ratios_jit(
        jnp.asarray(slip), jnp.asarray(load_1), jnp.asarray(load_2), _coefficients(coefficients)
    )


class TireSensitivities(eqx.Module):
    """Exact (automatic-differentiation) sensitivities of every field of :class:`TireForces`.

    Section 3.3 of the thesis estimates sensitivities from finite changes of one parameter
    at a time; these are the exact derivatives at the operating point.  Each field is a
    :class:`TireForces` holding the element-wise derivative of each force/angle:

    - `c_s`: ∂/∂C_s [N per N/rad = rad; angles: rad per N/rad].
    - `c_alpha`: ∂/∂C_α [same units].
    - `mu_x`: ∂/∂μ_x [N; angles: rad].
    - `mu_y`: ∂/∂μ_y [N; angles: rad].
    - `e1`: ∂/∂E1 [N; angles: rad].
    - `load_direct`: ∂/∂F_z with C_s, C_α, μ_x, μ_y, E1 held fixed [N/N; angles: rad/N].
    - `load`: total d/dF_z, through the load functions (3.17)–(3.21) [N/N; rad/N]:
      `load = load_direct + Σ_p (∂F/∂p) (dp/dF_z)`.

    For example `s.c_s.combined` is ∂F_Σ/∂C_s and `s.load.fx_pure` is dF_x|α=0/dF_z.
    """

    c_s: TireForces
    c_alpha: TireForces
    mu_x: TireForces
    mu_y: TireForces
    e1: TireForces
    load_direct: TireForces
    load: TireForces


_PARAMETER_NAMES = ("c_s", "c_alpha", "mu_x", "mu_y", "e1")


@eqx.filter_jit
def _sensitivities_jit(load, slip, slip_angle, coefficients):
    """On flat, equally shaped (n,) inputs (flattened by the caller, so that calls of any
    shape with the same number of elements share one compilation)."""

    def one(fz, i, alpha, coeffs):
        params = tire_parameters(fz, coeffs)
        # One forward-mode pass with six tangents: F_z and the five parameters.
        jac = jax.jacfwd(lambda x: _forces(x[0], i, alpha, x[1]))((fz, params))
        d_load_direct = jax.tree_util.tree_map(
            lambda d: d[0], jac, is_leaf=lambda x: isinstance(x, tuple)
        )
        d_params = jax.tree_util.tree_map(
            lambda d: d[1], jac, is_leaf=lambda x: isinstance(x, tuple)
        )
        # Total load derivative by the chain rule through (3.17)-(3.21).
        dp_dload = jax.jacfwd(lambda f: tire_parameters(f, coeffs))(fz)
        d_load = jax.tree_util.tree_map(
            lambda direct, dp: (
                direct + sum(getattr(dp, n) * getattr(dp_dload, n) for n in _PARAMETER_NAMES)
            ),
            d_load_direct,
            d_params,
            is_leaf=lambda x: isinstance(x, TireParameters),
        )
        return d_params, d_load_direct, d_load

    d_params, d_load_direct, d_load = jax.vmap(one)(load, slip, slip_angle, coefficients)

    def wrt(name):
        return jax.tree_util.tree_map(
            lambda p: getattr(p, name),
            d_params,
            is_leaf=lambda x: isinstance(x, TireParameters),
        )

    return TireSensitivities(
        c_s=wrt("c_s"),
        c_alpha=wrt("c_alpha"),
        mu_x=wrt("mu_x"),
        mu_y=wrt("mu_y"),
        e1=wrt("e1"),
        load_direct=d_load_direct,
        load=d_load,
    )


def tire_force_sensitivities(
    load: Float[ArrayLike, "..."],
    slip: Float[ArrayLike, "..."],
    slip_angle: Float[ArrayLike, "..."],
    coefficients: TireCoefficients | None = None,
) -> TireSensitivities:
    """Exact derivatives of the pure and combined forces (3.11)–(3.16) with respect to
    C_s, C_α, μ_x, μ_y, E1 and the load, by forward-mode autodiff (`jax.jacfwd`).

    The parameters are those of the load functions (3.17)–(3.21) at `load`.  The load
    derivative is given both at fixed parameters (`load_direct`) and in total, through the
    load functions (`load`).

    **Arguments** (broadcast with NumPy rules):

    - `load`: normal load F_z [N], > 0.
    - `slip`: driving slip i [-], <= 1.
    - `slip_angle`: α [rad], |α| < π/2.
    - `coefficients`: a :class:`TireCoefficients` (kN units); default the thesis's.

    **Returns:** a :class:`TireSensitivities` (units listed there), every leaf shaped like
    the broadcast inputs.
    """
    _check_operating_point(load, slip, slip_angle)
    _check("load", load, lambda x: x > 0, "a normal load > 0 N")
    arrays = [jnp.asarray(load), jnp.asarray(slip), jnp.asarray(slip_angle)]
    leaves, treedef = jax.tree_util.tree_flatten(_coefficients(coefficients))
    shape = jnp.broadcast_shapes(*(jnp.shape(x) for x in arrays + leaves))
    size = int(np.prod(shape, dtype=int))
    dtype = _float_dtype(*arrays, *leaves)

    def flat(x):  # one dtype, no weak types: calls of equal size share a compilation
        return jnp.broadcast_to(jnp.asarray(x).astype(dtype), shape).reshape(size)

    out = _sensitivities_jit(
        *(flat(x) for x in arrays),
        jax.tree_util.tree_unflatten(treedef, [flat(x) for x in leaves]),
    )
    return jax.tree_util.tree_map(lambda x: x.reshape(shape), out)
