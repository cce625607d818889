"""Pressure–sinkage and shear-strength laws of chapter 2 and 4 of the thesis.

Every function is pure, element-wise and broadcasts its arguments with NumPy rules, so it
works unchanged under `jax.jit`, `jax.vmap` and `jax.grad`.  SI units throughout: lengths
in m, stresses and pressures in Pa, moduli in the units Bekker's law requires.

Equation numbers refer to Sankapalli (2004), *Predictive semi-empirical analysis for
tire/snow interaction*, MSc thesis, University of Alaska Fairbanks.
"""

from __future__ import annotations

import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float

__all__ = [
    "bekker_pressure",
    "wong_sinkage",
    "wong_pressure",
    "reece_pressure",
    "mohr_coulomb",
    "janosi_hanamoto",
    "gawwad_crolla_shear",
    "gawwad_crolla_unloading_pressure",
]


def _clip_negative(x) -> Array:
    """max(x, 0) with gradient 1 at x = 0 (jnp.maximum would split it 1/2 : 1/2)."""
    x = jnp.asarray(x)
    return jnp.where(x >= 0, x, 0.0)


def _safe_power(x: Array, n: Array) -> Array:
    """`x**n` for x >= 0 whose value *and gradient* are finite at x = 0."""
    positive = x > 0
    safe_x = jnp.where(positive, x, 1.0)
    return jnp.where(positive, safe_x**n, 0.0)


def bekker_pressure(
    sinkage: Float[ArrayLike, "..."],
    width: Float[ArrayLike, "..."],
    k_c: Float[ArrayLike, "..."],
    k_phi: Float[ArrayLike, "..."],
    n: Float[ArrayLike, "..."],
) -> Float[Array, "..."]:
    """Bekker's pressure–sinkage law, eq. (2.1): `p = (k_c / b + k_phi) z^n`.

    **Arguments:**

    - `sinkage`: z [m], clipped at 0 (no pressure above the surface).
    - `width`: b, the smaller dimension of the contact patch (plate width or radius
      convention of the test) [m].
    - `k_c`: cohesive modulus [N/m^(n+1)].
    - `k_phi`: frictional modulus [N/m^(n+2)].
    - `n`: sinkage exponent [-].

    **Returns:** pressure p [Pa].
    """
    z = _clip_negative(sinkage)
    return (jnp.asarray(k_c) / jnp.asarray(width) + k_phi) * _safe_power(z, jnp.asarray(n))


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


def reece_pressure(
    sinkage: Float[ArrayLike, "..."],
    width: Float[ArrayLike, "..."],
    cohesion: Float[ArrayLike, "..."],
    unit_weight: Float[ArrayLike, "..."],
    k_c_prime: Float[ArrayLike, "..."],
    k_phi_prime: Float[ArrayLike, "..."],
    n: Float[ArrayLike, "..."],
) -> Float[Array, "..."]:
    """Reece's pressure–sinkage law, eq. (2.4).

    `sigma = (c k'_c + gamma_s b k'_phi) (z / b)^n`.

    **Arguments:**

    - `sinkage`: z [m], clipped at 0.
    - `width`: b, smaller dimension of the plate or contact patch [m].
    - `cohesion`: c [Pa].
    - `unit_weight`: gamma_s, weight density of the terrain [N/m^3].
    - `k_c_prime`, `k_phi_prime`: dimensionless Reece moduli [-].
    - `n`: sinkage exponent [-].

    **Returns:** normal pressure sigma [Pa].
    """
    b = jnp.asarray(width)
    z = _clip_negative(sinkage)
    modulus = jnp.asarray(cohesion) * k_c_prime + jnp.asarray(unit_weight) * b * k_phi_prime
    return modulus * _safe_power(z / b, jnp.asarray(n))


def mohr_coulomb(
    normal_stress: Float[ArrayLike, "..."],
    cohesion: Float[ArrayLike, "..."],
    tan_phi: Float[ArrayLike, "..."],
) -> Float[Array, "..."]:
    """Mohr–Coulomb shear strength, eq. (2.5): `tau_max = c + sigma tan(phi)`.

    **Arguments:** `normal_stress` sigma [Pa], `cohesion` c [Pa], `tan_phi` tan of the
    internal friction angle [-].

    **Returns:** shear strength tau_max [Pa].
    """
    return jnp.asarray(cohesion) + jnp.asarray(normal_stress) * jnp.asarray(tan_phi)


def _signed_mobilisation(x: Array) -> Array:
    """`sign(x) (1 - exp(-|x|))`, written so that value and gradient are finite for all x.

    For x >= 0 it is the Janosi–Hanamoto factor `1 - exp(-x)`; for x < 0 it is its odd
    mirror image, so the shear stress of a braked wheel (negative shear displacement)
    points backwards and never exceeds the Mohr–Coulomb strength.  Its derivative is
    continuous (1 at x = 0) and the second derivative jumps there.
    """
    positive = x >= 0
    # |x| written with `where` so that its derivative is +-1 (never 0) at x = 0.
    magnitude = -jnp.expm1(-jnp.where(positive, x, -x))
    return jnp.where(positive, magnitude, -magnitude)


def janosi_hanamoto(
    shear_displacement: Float[ArrayLike, "..."],
    normal_stress: Float[ArrayLike, "..."],
    cohesion: Float[ArrayLike, "..."],
    tan_phi: Float[ArrayLike, "..."],
    shear_modulus: Float[ArrayLike, "..."],
) -> Float[Array, "..."]:
    """Janosi–Hanamoto shear stress–displacement law, eq. (2.8) / (4.11).

    `tau = (c + sigma tan phi) [1 - exp(-j / K)]` for j >= 0.  For negative shear
    displacement (braking, slip < 0) the law is mirrored:
    `tau = -(c + sigma tan phi) [1 - exp(-|j| / K)]`, so the stress is signed with j.

    **Arguments:**

    - `shear_displacement`: j [m].
    - `normal_stress`: sigma [Pa].
    - `cohesion`: c [Pa].
    - `tan_phi`: tan of the internal friction angle [-].
    - `shear_modulus`: K, the shear deformation modulus [m].

    **Returns:** shear stress tau [Pa].
    """
    strength = mohr_coulomb(normal_stress, cohesion, tan_phi)
    return strength * _signed_mobilisation(
        jnp.asarray(shear_displacement) / jnp.asarray(shear_modulus)
    )


def gawwad_crolla_shear(
    shear_displacement: Float[ArrayLike, "..."],
    threshold_displacement: Float[ArrayLike, "..."],
    normal_stress: Float[ArrayLike, "..."],
    cohesion: Float[ArrayLike, "..."],
    tan_phi: Float[ArrayLike, "..."],
    shear_modulus: Float[ArrayLike, "..."],
) -> Float[Array, "..."]:
    """Abd El-Gawwad & Crolla's shear law with a threshold displacement, eq. (2.22).

    `tau = (c + sigma tan phi) [1 - exp(-(j + j0) / k)]`; mirrored like
    :func:`janosi_hanamoto` when `j + j0 < 0`.

    **Arguments:**

    - `shear_displacement`: j [m].
    - `threshold_displacement`: j0, the threshold perimeter shear of the tyre [m].
    - `normal_stress`: sigma [Pa]; `cohesion`: c [Pa]; `tan_phi` [-].
    - `shear_modulus`: k [m].

    **Returns:** shear stress tau [Pa].
    """
    return janosi_hanamoto(
        jnp.asarray(shear_displacement) + jnp.asarray(threshold_displacement),
        normal_stress,
        cohesion,
        tan_phi,
        shear_modulus,
    )


def gawwad_crolla_unloading_pressure(
    sinkage: Float[ArrayLike, "..."],
    unloading_sinkage: Float[ArrayLike, "..."],
    width: Float[ArrayLike, "..."],
    k_c: Float[ArrayLike, "..."],
    k_phi: Float[ArrayLike, "..."],
    n: Float[ArrayLike, "..."],
    k_0: Float[ArrayLike, "..."],
    a_u: Float[ArrayLike, "..."],
) -> Float[Array, "..."]:
    """Pressure on the unloading (rear) part of the contact, eq. (2.21).

    `p = (k_c / b + k_phi) z_u^n - k_u (z_u - z)` with `k_u = k_0 + A_u z_u`; clipped at
    zero once the terrain has rebounded away from the tyre.

    **Arguments:**

    - `sinkage`: z [m], at most `unloading_sinkage`.
    - `unloading_sinkage`: z_u, the sinkage where unloading begins [m].
    - `width`: b [m]; `k_c` [N/m^(n+1)]; `k_phi` [N/m^(n+2)]; `n` [-] — Bekker's law.
    - `k_0`: unloading modulus at zero sinkage [Pa/m].
    - `a_u`: rate of change of the unloading modulus with z_u [Pa/m^2].

    **Returns:** normal pressure p [Pa], >= 0.
    """
    z_u = jnp.asarray(unloading_sinkage)
    k_u = jnp.asarray(k_0) + jnp.asarray(a_u) * z_u
    peak = bekker_pressure(z_u, width, k_c, k_phi, n)
    return jnp.maximum(peak - k_u * (z_u - jnp.asarray(sinkage)), 0.0)
