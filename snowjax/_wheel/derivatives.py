"""Derivatives of the normalised shear stress of chapter 4 (Tables 4.2–4.6).

The thesis builds its simplified shear model (4.13) by matching the first and second
derivatives of the classic model (4.12) with respect to the normalised pressure
σ̄ = σ_n / c and the slip i (Tables 4.3–4.6, Figures 4.2–4.6).  This module computes those
derivatives by automatic differentiation (`jax.grad`, `jax.hessian`) and also transcribes
the thesis's closed-form expressions *as published*, so that the two can be compared.

**Setting (section 4.2).**  Everything is dimensionless and evaluated on the rim of a wheel
with a *fixed* entry angle θ0 (Table 4.1: θ0 = 0.9398 rad):

- relative sinkage `Z = 1 - z / z_w = exp(-(c / p_w) σ̄)` (4.3), so σ̄ runs from 0 at the
  entry point (θ = θ0, Z = 1) to `σ̄_n0 = (p_w / c)(-ln Z0)` under the axle (θ = 0), with
  `Z0 = 1 - z0 / z_w`, `z0 = D/2 (1 - cos θ0)` (4.4, 4.6, Table 4.2);
- the rim angle θ(σ̄) follows from (4.5): `Z = 1 - (D / 2 z_w)(cos θ - cos θ0)`;
- `J = j / D = ½[(θ0 - θ) - (1 - i)(sin θ0 - sin θ)]` (4.10 divided by D), `u_k = D / K`,
  `J_k = u_k exp(-u_k J)`.

The classic model (4.12) is `τ̄ = (1 + σ̄ tan φ)(1 - J_k / u_k)` with θ = θ(σ̄); the
derivative "with respect to σ̄" is the derivative along the rim, at fixed θ0 and i, and the
derivative "with respect to i" is at fixed σ̄ (i.e. fixed θ).  The simplified model (4.13)
is `τ̄ = (1 + σ̄ tan φ)[1 - exp(-U0)]` with
`U0 = (i + τ2) τ1 σ̄ + (2i - i²) τ1 σ̄³ / 6`, `τ1 = u_k (z_w/D)(c/p_w) cot θ0`,
`τ2 = sec θ0 - 1`.

**What the comparison shows** (tests/test_derivatives.py):

- Table 4.3 (classic model): y1, y3, y4 and the full form of y2,
  `-T0²(T1 T3 + T2 T4) + T0 T_Δ`, agree with autodiff to rounding.  The two approximations
  printed after it, `≈ -T0²(T1 T3 + T2 T4) ≈ -T0²(T1 + T2)²`, are not identities: the first
  drops T0 T_Δ (about 3 % of y2 at σ̄ = 0 for Table 4.1, more where y2 is small), the second
  is off by the factor Q0 / u_k = e^{-u_k J}(1 + σ̄ tan φ) and is exact only at σ̄ = 0 (and
  even there misses the 2/sin²θ terms of T3, T4).
- Table 4.5 (simplified model): all four expressions (with U1–U4) agree with autodiff.
- Table 4.6: the zero-sinkage value of y2 is printed as `U1² + 2 U1 tan φ`; the correct
  value is `-U1² + 2 U1 tan φ` (sign error; the printed value is positive although the
  text says y2 is always negative).
- Table 4.4: the zero-sinkage value of y2, `-T0² u_k² (Q1 + Q2)²`, keeps only the leading
  term of the exact value; the maximum-sinkage limits `T1 + T2 -> 0` and `y1 -> tan φ` hold
  only for i = 0: for i > 0, Q1 = i cot θ diverges at θ = 0 (dσ̄/dθ = 0 under the axle
  while dτ̄/dθ ≠ 0), so the classic τ̄(σ̄) has a vertical tangent at σ̄_n0.  The divergent
  part is multiplied by exp(-u_k J0) (< 8e-3 for Table 4.1), so it is confined to the
  last sliver of the σ̄ range.
- Appendix, step 3: `∂Z/∂σ̄ = (c/p_w) exp[-(c/p_w) σ̄] Z` as printed is wrong (sign, and
  a factor Z too many); `∂Z/∂σ̄ = -(c/p_w) Z`.  The final results of Table 4.3 use the
  correct form.

Reading of the text file (OCR): `J_k = u_k exp(-u_k J)` (so `1 - J_k / u_k` is the
Janosi–Hanamoto factor); in T3 the first term is `-(2 / sin²θ)(1 / cos θ)`; in Table 4.5
`U4 = -(1/3) τ1 σ̄³` and `y4 = -(U3 - U4 / U3) y3`.  These readings are the only ones that
make the printed final expressions consistent with (4.12) and (4.13), and with them they
are exact.
"""

from __future__ import annotations

from typing import Literal, NamedTuple

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from .._leaves import _as_float
from .geometry import _shear_displacement

__all__ = [
    "DimensionlessConstants",
    "ShearDerivatives",
    "ThesisTable43",
    "ThesisTable45",
    "max_normalized_pressure",
    "contact_angle_at_pressure",
    "classic_normalized_shear",
    "simplified_normalized_shear",
    "shear_derivatives",
    "thesis_table_4_3",
    "thesis_table_4_5",
    "thesis_table_4_4",
    "thesis_table_4_6",
    "thesis_appendix_dz_dsigma",
]

NormalizedShearModel = Literal["classic", "simplified"]


class DimensionlessConstants(eqx.Module):
    """The five dimensionless inputs of section 4.2 (Table 4.1).

    **Fields** (array leaves, broadcast against σ̄ and i):

    - `z_w_over_d`: z_w / D, geometric [-].
    - `entry_angle`: θ0 [rad], geometric.
    - `c_over_p_w`: c / p_w, material [-].
    - `u_k`: D / K_shear, material [-].
    - `tan_phi`: tan φ, material [-].
    """

    z_w_over_d: Float[Array, "..."] = eqx.field(converter=_as_float)
    entry_angle: Float[Array, "..."] = eqx.field(converter=_as_float)
    c_over_p_w: Float[Array, "..."] = eqx.field(converter=_as_float)
    u_k: Float[Array, "..."] = eqx.field(converter=_as_float)
    tan_phi: Float[Array, "..."] = eqx.field(converter=_as_float)

    @classmethod
    def thesis(cls) -> "DimensionlessConstants":
        """Table 4.1: z_w/D = 0.2717, θ0 = 0.9398 rad (53.6747°), c/p_w = 0.2165,
        u_k = D/K = 73.6, tan φ = 0.0787."""
        return cls(
            z_w_over_d=0.2717, entry_angle=0.9398, c_over_p_w=0.2165, u_k=73.6, tan_phi=0.0787
        )

    @classmethod
    def from_parameters(cls, wheel, snow, entry_angle) -> "DimensionlessConstants":
        """The constants of a `RigidWheel`, a `WongSnow` and an entry angle θ0 [rad]."""
        d = wheel.diameter
        return cls(
            z_w_over_d=snow.z_w / d,
            entry_angle=entry_angle,
            c_over_p_w=snow.cohesion / snow.p_w,
            u_k=d / snow.shear_modulus,
            tan_phi=snow.tan_phi,
        )


def _constants(k: DimensionlessConstants | None) -> DimensionlessConstants:
    return DimensionlessConstants.thesis() if k is None else k


# --------------------------------------------------------------------------------------
# Rim geometry in dimensionless form (4.3)-(4.6), Table 4.2
# --------------------------------------------------------------------------------------


def _relative_sinkage(sigma_bar, k):
    """Z = exp(-(c/p_w) σ̄), eq. (4.3)."""
    return jnp.exp(-k.c_over_p_w * sigma_bar)


def max_normalized_pressure(constants: DimensionlessConstants | None = None) -> Array:
    """σ̄_n0 = (p_w / c)(-ln Z0) under the axle (θ = 0), Table 4.2.

    `Z0 = 1 - z0 / z_w` (4.4) with `z0 = D/2 (1 - cos θ0)` (4.6), i.e.
    `Z0 = 1 - (D / z_w) sin²(θ0 / 2)`.  About 6.489 for Table 4.1.

    **Arguments:** `constants` (default Table 4.1).  **Returns:** σ̄_n0 [-].
    """
    k = _constants(constants)
    z0_rel = 1 - jnp.sin(k.entry_angle / 2) ** 2 / k.z_w_over_d
    return -jnp.log(z0_rel) / k.c_over_p_w


def contact_angle_at_pressure(
    sigma_bar: Float[ArrayLike, "..."], constants: DimensionlessConstants | None = None
) -> Array:
    """Rim angle θ where the normalised pressure is σ̄, from (4.3) and (4.5).

    `cos θ = cos θ0 + 2 (z_w / D)(1 - Z)`, written as
    `sin²(θ/2) = sin²(θ0/2) - (z_w/D)(1 - Z)` for accuracy near θ = 0.

    **Arguments:** `sigma_bar` σ̄ (dimensionless), 0 <= σ̄ <= σ̄_n0; `constants` (default
    Table 4.1).
    **Returns:** θ [rad] (NaN beyond σ̄_n0, where no rim point has that pressure).
    """
    k = _constants(constants)
    sigma_bar = jnp.asarray(sigma_bar)
    # 1 - Z = -expm1(-(c/p_w) σ̄)
    s2 = jnp.sin(k.entry_angle / 2) ** 2 + k.z_w_over_d * jnp.expm1(-k.c_over_p_w * sigma_bar)
    return 2 * jnp.arcsin(jnp.sqrt(s2))


@jax.custom_jvp
def _one_minus_exp(x):
    """1 - exp(-x), accurate for small x (expm1) and with derivative exp(-x).

    `-jnp.expm1(-x)` alone would do for the value, but JAX differentiates expm1 as
    `expm1(x) + 1`, which loses all relative precision once exp(-x) is far below 1 (e.g.
    a 3e-4 relative error in y3 at u_k J = 27); the custom rule keeps the derivatives
    accurate to rounding in the saturated region too.
    """
    return -jnp.expm1(-x)


@_one_minus_exp.defjvp
def _one_minus_exp_jvp(primals, tangents):
    (x,), (t,) = primals, tangents
    return _one_minus_exp(x), jnp.exp(-x) * t


def _normalized_displacement(theta, slip, k):
    """J = j / D = ½[(θ0 - θ) - (1 - i)(sin θ0 - sin θ)], eq. (4.10) / D."""
    return _shear_displacement(
        theta, k.entry_angle, slip, 0.5, jnp.sin(theta), jnp.sin(k.entry_angle)
    )


def classic_normalized_shear(
    sigma_bar: Float[ArrayLike, "..."],
    slip: Float[ArrayLike, "..."],
    constants: DimensionlessConstants | None = None,
) -> Array:
    """Classic normalised shear stress on the rim, eq. (4.12).

    `τ̄ = τ / c = (1 + σ̄ tan φ)(1 - J_k / u_k)`, `J_k = u_k exp(-u_k J)`, with J at the rim
    angle θ(σ̄) of `contact_angle_at_pressure` (entry angle θ0 fixed).

    **Arguments:** `sigma_bar` σ̄ = σ_n / c in [0, σ̄_n0]; `slip` i [-];
    `constants` (default Table 4.1).  **Returns:** τ̄ [-].
    """
    k = _constants(constants)
    sigma_bar = jnp.asarray(sigma_bar)
    theta = contact_angle_at_pressure(sigma_bar, k)
    big_j = _normalized_displacement(theta, jnp.asarray(slip), k)
    return (1 + sigma_bar * k.tan_phi) * _one_minus_exp(k.u_k * big_j)


def _tau1_tau2(k):
    """τ1 = u_k (z_w/D)(c/p_w) cot θ0 and τ2 = sec θ0 - 1 of eq. (4.13)."""
    tau1 = k.u_k * k.z_w_over_d * k.c_over_p_w / jnp.tan(k.entry_angle)
    tau2 = 1 / jnp.cos(k.entry_angle) - 1
    return tau1, tau2


def simplified_normalized_shear(
    sigma_bar: Float[ArrayLike, "..."],
    slip: Float[ArrayLike, "..."],
    constants: DimensionlessConstants | None = None,
) -> Array:
    """The thesis's simplified normalised shear stress, eq. (4.13).

    `τ̄ = (1 + σ̄ tan φ)[1 - exp(-U0)]`,
    `U0 = (i + τ2) τ1 σ̄ + (2i - i²) τ1 σ̄³ / 6`, `τ1 = u_k (z_w/D)(c/p_w) cot θ0`,
    `τ2 = sec θ0 - 1`.

    **Arguments:** `sigma_bar` σ̄ >= 0; `slip` i [-]; `constants` (default Table 4.1).
    **Returns:** τ̄ [-].
    """
    k = _constants(constants)
    s = jnp.asarray(sigma_bar)
    i = jnp.asarray(slip)
    tau1, tau2 = _tau1_tau2(k)
    u0 = (i + tau2) * tau1 * s + (2 * i - i * i) * tau1 * s**3 / 6
    return (1 + s * k.tan_phi) * _one_minus_exp(u0)


_MODELS = {"classic": classic_normalized_shear, "simplified": simplified_normalized_shear}


# --------------------------------------------------------------------------------------
# Autodiff
# --------------------------------------------------------------------------------------


class ShearDerivatives(eqx.Module):
    """τ̄ and its derivatives, computed by `jax.grad` / `jax.hessian` (Tables 4.3, 4.5).

    Every field has the broadcast shape of σ̄, i and the constants.

    - `tau`: τ̄ [-].
    - `y1`: ∂τ̄/∂σ̄.   - `y2`: ∂²τ̄/∂σ̄².
    - `y3`: ∂τ̄/∂i.   - `y4`: ∂²τ̄/∂i².
    - `y_mixed`: ∂²τ̄/∂σ̄∂i (not in the thesis).
    """

    tau: Float[Array, "..."]
    y1: Float[Array, "..."]
    y2: Float[Array, "..."]
    y3: Float[Array, "..."]
    y4: Float[Array, "..."]
    y_mixed: Float[Array, "..."]


@eqx.filter_jit
def _derivatives_jit(sigma_bar, slip, k, model):
    f = _MODELS[model]

    def scalar(s, i, kk):
        return f(s, i, kk)

    grad = jax.grad(scalar, argnums=(0, 1))
    hess = jax.hessian(scalar, argnums=(0, 1))

    def one(s, i, kk):
        g = grad(s, i, kk)
        h = hess(s, i, kk)
        return scalar(s, i, kk), g[0], h[0][0], g[1], h[1][1], h[0][1]

    return jax.vmap(one)(sigma_bar, slip, k)


def shear_derivatives(
    sigma_bar: Float[ArrayLike, "..."],
    slip: Float[ArrayLike, "..."],
    constants: DimensionlessConstants | None = None,
    model: NormalizedShearModel = "classic",
) -> ShearDerivatives:
    """First and second derivatives of τ̄ w.r.t. σ̄ and i by automatic differentiation.

    y1 = ∂τ̄/∂σ̄, y2 = ∂²τ̄/∂σ̄², y3 = ∂τ̄/∂i, y4 = ∂²τ̄/∂i² of the classic model (4.12,
    Table 4.3; derivative along the rim at fixed θ0) or the simplified model (4.13,
    Table 4.5).

    **Arguments:**

    - `sigma_bar`: σ̄ = σ_n / c [-]; for the classic model 0 <= σ̄ < σ̄_n0
      (`max_normalized_pressure`); at σ̄_n0 itself y1 is infinite for i > 0.
    - `slip`: i [-].
    - `constants`: a `DimensionlessConstants` (default Table 4.1).
    - `model`: `"classic"` (4.12) or `"simplified"` (4.13).

    **Returns:** `ShearDerivatives` (broadcast shape).
    """
    if model not in _MODELS:
        raise ValueError(f"model must be 'classic' or 'simplified', got {model!r}")
    k = _constants(constants)
    leaves, treedef = jax.tree_util.tree_flatten(k)
    arrays = [jnp.asarray(sigma_bar), jnp.asarray(slip)] + [jnp.asarray(x) for x in leaves]
    dtype = jnp.result_type(*arrays, float)
    shape = jnp.broadcast_shapes(*(a.shape for a in arrays))
    size = int(np.prod(shape, dtype=int))
    # Flatten and pad to a power of two (>= 8) with copies of the first element, so that
    # calls of similar sizes share one compilation.
    padded = max(8, 1 << max(size - 1, 0).bit_length())
    flat = [jnp.broadcast_to(a.astype(dtype), shape).reshape(size) for a in arrays]
    flat = [
        jnp.concatenate([f, jnp.broadcast_to(f[:1], (padded - size,))])
        if size
        else jnp.zeros(padded, dtype)
        for f in flat
    ]
    kk = jax.tree_util.tree_unflatten(treedef, flat[2:])
    out = _derivatives_jit(flat[0], flat[1], kk, model)
    return ShearDerivatives(*(x[:size].reshape(shape) for x in out))


# --------------------------------------------------------------------------------------
# The thesis's closed forms, transcribed as published
# --------------------------------------------------------------------------------------


class ThesisTable43(NamedTuple):
    """Table 4.3 as published (classic model 4.12), plus its intermediate quantities.

    - `y1 = tan φ (1 - J_k/u_k) + T0 (T1 + T2)`
    - `y2 = -T0² (T1 T3 + T2 T4) + T0 T_Δ`
    - `y2_without_t_delta = -T0² (T1 T3 + T2 T4)` (the first "≈" of the table)
    - `y2_squared = -T0² (T1 + T2)²` (the second "≈")
    - `y3 = ½ J_k (1 + σ̄ tan φ)(sin θ0 - sin θ)`
    - `y4 = -½ u_k (sin θ0 - sin θ) y3`
    """

    y1: Array
    y2: Array
    y2_without_t_delta: Array
    y2_squared: Array
    y3: Array
    y4: Array
    theta: Array
    t0: Array
    t1: Array
    t2: Array
    t3: Array
    t4: Array
    t_delta: Array
    j_k: Array


def thesis_table_4_3(
    sigma_bar: Float[ArrayLike, "..."],
    slip: Float[ArrayLike, "..."],
    constants: DimensionlessConstants | None = None,
) -> ThesisTable43:
    """Table 4.3 (derivatives of eq. 4.12), transcribed as printed in the thesis.

    With θ = θ(σ̄) (4.5), `J = ½[(θ0 - θ) - (1 - i)(sin θ0 - sin θ)]`,
    `Z = 1 - ½(D/z_w)(cos θ - cos θ0)`, `J_k = u_k exp(-u_k J)`, `σ̄ = (p_w/c)(-ln Z)`:

    - `T0 = Z (z_w/D)(c/p_w)`
    - `T_Δ = [2 J_k tan φ - (c/p_w) J_k (1 + σ̄ tan φ)] [i cos θ/sin θ + (1 - cos θ)/sin θ]`
    - `T1 = J_k (1 + σ̄ tan φ)(i cos θ / sin θ)`, `T2 = J_k (1 + σ̄ tan φ)(1 - cos θ)/sin θ`
    - `T3 = -(2 / sin²θ)(1 / cos θ) + u_k (i cos θ / sin θ) + 2 u_k (1 - cos θ)/sin θ`
    - `T4 = 2 / sin²θ + u_k (1 - cos θ)/sin θ`

    and y1…y4 as listed in `ThesisTable43`.

    **Arguments:** `sigma_bar` σ̄ in [0, σ̄_n0); `slip` i; `constants` (default Table 4.1).
    """
    return _table_4_3_jit(jnp.asarray(sigma_bar), jnp.asarray(slip), _constants(constants))


@eqx.filter_jit
def _table_4_3_jit(s, i, k):
    theta0 = k.entry_angle
    theta = contact_angle_at_pressure(s, k)
    big_j = _normalized_displacement(theta, i, k)
    big_z = 1 - 0.5 / k.z_w_over_d * (jnp.cos(theta) - jnp.cos(theta0))
    j_k = k.u_k * jnp.exp(-k.u_k * big_j)
    sigma_from_z = -jnp.log(big_z) / k.c_over_p_w  # = σ̄ (the table's own definition)
    strength = 1 + sigma_from_z * k.tan_phi
    sin, cos = jnp.sin(theta), jnp.cos(theta)
    q1 = i * cos / sin
    q2 = (1 - cos) / sin
    t0 = big_z * k.z_w_over_d * k.c_over_p_w
    t_delta = (2 * j_k * k.tan_phi - k.c_over_p_w * j_k * strength) * (q1 + q2)
    t1 = j_k * strength * q1
    t2 = j_k * strength * q2
    t3 = -(2 / sin**2) * (1 / cos) + k.u_k * q1 + 2 * k.u_k * q2
    t4 = 2 / sin**2 + k.u_k * q2
    y1 = k.tan_phi * (1 - j_k / k.u_k) + t0 * (t1 + t2)
    y2_main = -(t0**2) * (t1 * t3 + t2 * t4)
    y3 = 0.5 * j_k * strength * (jnp.sin(theta0) - sin)
    y4 = -0.5 * k.u_k * (jnp.sin(theta0) - sin) * y3
    return ThesisTable43(
        y1=y1,
        y2=y2_main + t0 * t_delta,
        y2_without_t_delta=y2_main,
        y2_squared=-(t0**2) * (t1 + t2) ** 2,
        y3=y3,
        y4=y4,
        theta=theta,
        t0=t0,
        t1=t1,
        t2=t2,
        t3=t3,
        t4=t4,
        t_delta=t_delta,
        j_k=j_k,
    )


class ThesisTable45(NamedTuple):
    """Table 4.5 as published (simplified model 4.13), plus U0…U4.

    - `y1 = tan φ + [U1 (1 + σ̄ tan φ) - tan φ] exp(-U0)`
    - `y2 = 2 U1 tan φ exp(-U0) - (U1² - U2)(1 + σ̄ tan φ) exp(-U0)`
    - `y3 = (1 + σ̄ tan φ) U3 exp(-U0)`
    - `y4 = -(U3 - U4 / U3) y3`
    """

    y1: Array
    y2: Array
    y3: Array
    y4: Array
    u0: Array
    u1: Array
    u2: Array
    u3: Array
    u4: Array


def thesis_table_4_5(
    sigma_bar: Float[ArrayLike, "..."],
    slip: Float[ArrayLike, "..."],
    constants: DimensionlessConstants | None = None,
) -> ThesisTable45:
    """Table 4.5 (derivatives of eq. 4.13), transcribed as printed in the thesis.

    `U1 = τ1 (i + τ2) + ½ σ̄ U2`, `U2 = (2i - i²) τ1 σ̄`, `U3 = τ1 σ̄ - (1 - i) U4`,
    `U4 = -(1/3) τ1 σ̄³`, U0 of (4.13); y1…y4 as listed in `ThesisTable45`.

    **Arguments:** `sigma_bar` σ̄ >= 0; `slip` i; `constants` (default Table 4.1).
    """
    return _table_4_5_jit(jnp.asarray(sigma_bar), jnp.asarray(slip), _constants(constants))


@eqx.filter_jit
def _table_4_5_jit(s, i, k):
    tau1, tau2 = _tau1_tau2(k)
    u0 = (i + tau2) * tau1 * s + (2 * i - i * i) * tau1 * s**3 / 6
    u2 = (2 * i - i * i) * (tau1 * s)
    u1 = tau1 * (i + tau2) + 0.5 * s * u2
    u4 = -(1.0 / 3.0) * (tau1 * s**3)
    u3 = tau1 * s - (1 - i) * u4
    e = jnp.exp(-u0)
    strength = 1 + s * k.tan_phi
    y1 = k.tan_phi + (u1 * strength - k.tan_phi) * e
    y2 = 2 * (u1 * k.tan_phi) * e - (u1**2 - u2) * strength * e
    y3 = strength * u3 * e
    y4 = -(u3 - u4 / u3) * y3
    return ThesisTable45(y1=y1, y2=y2, y3=y3, y4=y4, u0=u0, u1=u1, u2=u2, u3=u3, u4=u4)


def thesis_table_4_4(
    slip: Float[ArrayLike, "..."],
    constants: DimensionlessConstants | None = None,
    *,
    as_printed: bool = True,
) -> dict[str, tuple[Array, Array]]:
    """Boundary values of Table 4.4 (classic model): `{name: (at σ̄ = 0, at σ̄ = σ̄_n0)}`.

    Names: `"t0"`, `"t1_plus_t2"`, `"y1"`, `"y2"`, `"y3"`, `"y4"`.  With
    `as_printed=True` the thesis's entries (Q1 = i cot θ, Q2 = (1 - cos θ)/sin θ,
    J0 = ½(θ0 - sin θ0) + ½ i sin θ0, J_k0 = u_k exp(-u_k J0)):

    - T0: `(z_w/D)(c/p_w)`, `Z0 (z_w/D)(c/p_w)`
    - T1 + T2: `u_k (Q1 + Q2)|θ0`, `0`
    - y1: `T0|Z=1 u_k (Q1 + Q2)|θ0`, `tan φ`
    - y2: `-(T0|Z=1)² u_k² (Q1 + Q2)²|θ0`, `0`
    - y3: `0`, `½ J_k0 (1 + σ̄_n0 tan φ) sin θ0`
    - y4: `0`, `-½ u_k sin θ0 y3|θ=0`

    With `as_printed=False` the exact values: y2 at σ̄ = 0 gains the terms the table drops
    (`+T0 T_Δ` and the 2/sin²θ parts of T3, T4), and for i > 0 the maximum-sinkage
    values of T1 + T2 and y1 are `+inf` (Q1 = i cot θ diverges at θ = 0).
    """
    k = _constants(constants)
    i = jnp.asarray(slip)
    theta0 = k.entry_angle
    sin0, cos0 = jnp.sin(theta0), jnp.cos(theta0)
    q_sum = (i * cos0 + 1 - cos0) / sin0  # Q1 + Q2 at θ0
    t0_entry = k.z_w_over_d * k.c_over_p_w
    z0_rel = 1 - jnp.sin(theta0 / 2) ** 2 / k.z_w_over_d
    sigma_n0 = -jnp.log(z0_rel) / k.c_over_p_w
    big_j0 = 0.5 * (theta0 - sin0) + 0.5 * i * sin0
    j_k0 = k.u_k * jnp.exp(-k.u_k * big_j0)
    y3_max = 0.5 * j_k0 * (1 + sigma_n0 * k.tan_phi) * sin0
    zero = jnp.zeros_like(q_sum)
    if as_printed:
        t12_max = zero
        y1_max = k.tan_phi + zero
        y2_entry = -(t0_entry**2) * k.u_k**2 * q_sum**2
    else:
        diverges = jnp.where(i > 0, jnp.inf, 0.0)
        t12_max = zero + diverges
        y1_max = k.tan_phi * (1 - j_k0 / k.u_k) + diverges
        # Exact: at θ0, J = 0, J_k = u_k, σ̄ = 0, Z = 1; Q1 T3 + Q2 T4 =
        # u_k (Q1 + Q2)² + 2 (1 - i - cos θ0) / sin³θ0.
        y2_entry = (
            -(t0_entry**2) * k.u_k * (k.u_k * q_sum**2 + 2 * (1 - i - cos0) / sin0**3)
            + t0_entry * k.u_k * (2 * k.tan_phi - k.c_over_p_w) * q_sum
        )
    return {
        "t0": (t0_entry + zero, z0_rel * t0_entry + zero),
        "t1_plus_t2": (k.u_k * q_sum, t12_max),
        "y1": (t0_entry * k.u_k * q_sum, y1_max),
        "y2": (y2_entry, zero),
        "y3": (zero, y3_max),
        "y4": (zero, -0.5 * k.u_k * sin0 * y3_max),
    }


def thesis_table_4_6(
    slip: Float[ArrayLike, "..."],
    constants: DimensionlessConstants | None = None,
    *,
    as_printed: bool = True,
) -> dict[str, tuple[Array, Array]]:
    """Boundary values of Table 4.6 (simplified model): `{name: (σ̄ = 0, σ̄ = σ̄_n0)}`.

    Names `"y1"`, `"y2"`, `"y3"`, `"y4"`.  As printed:
    y1: `U1|0 = τ1 (i + τ2)`, `tan φ`; y2: `(U1|0)² + 2 U1|0 tan φ`, `0`; y3, y4: `0, 0`.

    With `as_printed=False` the zero-sinkage y2 is the correct `-(U1|0)² + 2 U1|0 tan φ`
    (y2 = 2 U1 tan φ e^{-U0} - (U1² - U2)(1 + σ̄ tan φ) e^{-U0} with U0 = U2 = 0, σ̄ = 0).
    The maximum-sinkage values are limits for large U0 (exp(-U0) ≈ 7e-7 at i = 0 for
    Table 4.1) in both cases.
    """
    k = _constants(constants)
    i = jnp.asarray(slip)
    tau1, tau2 = _tau1_tau2(k)
    u1 = tau1 * (i + tau2)
    zero = jnp.zeros_like(u1)
    sign = 1.0 if as_printed else -1.0
    return {
        "y1": (u1, k.tan_phi + zero),
        "y2": (sign * u1**2 + 2 * u1 * k.tan_phi, zero),
        "y3": (zero, zero),
        "y4": (zero, zero),
    }


def thesis_appendix_dz_dsigma(
    sigma_bar: Float[ArrayLike, "..."],
    constants: DimensionlessConstants | None = None,
    *,
    as_printed: bool = True,
) -> Array:
    """∂Z/∂σ̄ of the appendix (step 3, identities).

    As printed: `(c/p_w) exp[-(c/p_w) σ̄] Z` (= (c/p_w) Z², positive).  Correct
    (`as_printed=False`): `-(c/p_w) Z`, from Z = exp(-(c/p_w) σ̄) (4.3).
    """
    k = _constants(constants)
    s = jnp.asarray(sigma_bar)
    z = _relative_sinkage(s, k)
    if as_printed:
        return k.c_over_p_w * jnp.exp(-k.c_over_p_w * s) * z
    return -k.c_over_p_w * z
