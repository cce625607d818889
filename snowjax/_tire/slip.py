"""Slip definitions and conversions (3.1)–(3.4), the shear distribution N(φ) (3.10) and the
normalised slips φ_x, φ_y, φ (3.7)–(3.9) of chapter 3.
"""

from __future__ import annotations

import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float

from .common import (
    _float_dtype,
    _safe_norm,
    _safe_ratio,
)

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
