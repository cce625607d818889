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
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from .._leaves import _as_float, _check_real_leaves
from .common import (
    _KN,
    _check,
    _float_dtype,
    _safe_arctan2,
    _safe_norm,
)
from .slip import (
    _shear_distribution_over_phi,
    _signed_shear,
)

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

    __check_init__ = _check_real_leaves

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

    __check_init__ = _check_real_leaves

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
