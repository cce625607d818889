"""Several wheels in one track: each pass runs on the rut the earlier ones left (`Rut`).

The rut's state is the deepest sinkage below the original surface any earlier wheel
reached, z_max (0 before the first pass).  Pass k runs on `Rut(terrain, z_max, b, k_0,
A_u)`; its lowest point lies `sinkage + floor_depth` below the original surface, and
z_max grows to it where the wheel went deeper (a wheel that stays within the rut's
elastic rebound leaves the state as it was: the next identical wheel repeats it).
"""

from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float, Int

from .._terrain.base import AbstractTerrain
from .._terrain.rut import Rut
from .equilibrium import solve_wheel
from .geometry import AbstractWheel
from .shear_law import AbstractShearLaw, ShearModel

__all__ = ["PassResult", "multi_pass"]


class PassResult(eqx.Module):
    """Each pass of `multi_pass`, along the last axis (pass 1 first).

    - `sinkage`: the wheel's lowest point below the original surface [m].
    - `rut_depth`: the rut's state after the pass, z_max [m].
    - `motion_resistance`, `drawbar_pull` [N], `torque` [N m]: as `WheelState`'s.
    - `status`: `Status` of each pass's equilibrium.
    """

    sinkage: Float[Array, "... n"]
    rut_depth: Float[Array, "... n"]
    motion_resistance: Float[Array, "... n"]
    drawbar_pull: Float[Array, "... n"]
    torque: Float[Array, "... n"]
    status: Int[Array, "... n"]


def multi_pass(
    wheel: AbstractWheel,
    terrain: AbstractTerrain,
    loads: Float[ArrayLike, "... n"],
    slip: Float[ArrayLike, "..."],
    k_0: Float[ArrayLike, "..."],
    a_u: Float[ArrayLike, "..."],
    *,
    distribution=None,
    shear: ShearModel | AbstractShearLaw = "classic",
) -> PassResult:
    """n wheels in one track, one after the other (a convoy, a tandem axle).

    **Arguments:**

    - `wheel`: every pass's wheel (`RigidWheel`, `DeflectingTire`, ...).
    - `terrain`: the virgin terrain (any law).
    - `loads`: F_z of each pass [N], the passes along the last axis (leading axes batch).
    - `slip`: driving slip of every pass [-] (broadcast against `loads`).
    - `k_0` [Pa/m], `a_u` [Pa/m^2]: the unloading modulus k_u = k_0 + A_u z_u of the
      terrain (`Rut`).
    - `distribution`, `shear`: as in `solve_wheel`.

    **Returns:** a `PassResult`.  Differentiable in every input (the rut's state is a
    running maximum: its derivative follows the pass that set it).
    """
    loads = jnp.asarray(loads, float)
    slips = jnp.broadcast_to(jnp.asarray(slip, loads.dtype), loads.shape)
    z_max = jnp.zeros(loads.shape[:-1], loads.dtype)
    rows = []
    for k in range(loads.shape[-1]):
        rut = Rut(terrain, z_max, wheel.width, k_0, a_u)
        st = solve_wheel(
            wheel, rut, loads[..., k], slips[..., k], distribution=distribution, shear=shear
        )
        total = st.sinkage + rut.floor_depth
        z_max = jnp.maximum(z_max, total)
        rows.append((total, z_max, st.motion_resistance, st.drawbar_pull, st.torque, st.status))
    return PassResult(*(jnp.stack(column, axis=-1) for column in zip(*rows)))
