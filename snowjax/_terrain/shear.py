"""Shear-strength and shear-mobilisation laws of chapters 2 and 4 (Mohr–Coulomb,
Janosi–Hanamoto, Gawwad–Crolla).

Every function is pure, element-wise and broadcasts its arguments with NumPy rules, so it
works unchanged under `jax.jit`, `jax.vmap` and `jax.grad`.  SI units throughout.
"""

from __future__ import annotations

import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float

from .bekker import bekker_pressure


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
