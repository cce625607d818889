"""Sensitivity of the tyre forces to the load-dependent parameters (section 3.3): shear-force
variation ratios between two loads and the derivatives of the forces w.r.t. C_s, C_α, μ_x,
μ_y and E1.
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from .._leaves import _is_traced
from .common import (
    THESIS_LOAD_RANGE,
    _check,
    _float_dtype,
)
from .tire import (
    TireCoefficients,
    TireForces,
    TireParameters,
    _check_operating_point,
    _coefficients,
    _forces,
    pure_longitudinal_force,
    tire_parameters,
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

    load_f, slip_f, angle_f = (flat(x) for x in arrays)
    out = _sensitivities_jit(
        load_f, slip_f, angle_f, jax.tree_util.tree_unflatten(treedef, [flat(x) for x in leaves])
    )
    return jax.tree_util.tree_map(lambda x: x.reshape(shape), out)
