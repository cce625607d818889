"""The chapter-3 combined-slip tyre forces on the chapter-4 wheel–snow equilibrium.

The thesis has two halves that it never connects.  Chapter 3 gives the tyre's shear forces
from the normalised slips (3.7)–(3.9), the shear distribution N(φ) (3.10) and the pure and
combined forces (3.11)–(3.16), with C_s, C_α, μ_x, μ_y, E1 fitted functions of the load
(3.17)–(3.21) (FEA of the 0.736 m tyre on fresh snow).  Chapter 4 gives the sinkage and
the motion resistance of a rigid wheel on shallow snow from the load balance (4.14)–(4.16).
`tire_forces_on_snow` evaluates both at the same load and driving slip and combines them
as thrust minus motion resistance (the drawbar-pull decomposition, 2.10).  The choices
that make this a model are snowjax's, not the thesis's; they are listed in the docstring
of `tire_forces_on_snow`.
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float, Int

from .._terrain.base import Terrain
from .._tire.common import _check
from .._tire.tire import (
    TireCoefficients,
    TireForces,
    TireParameters,
    _check_operating_point,
    _check_parameters,
    _forces,
    tire_parameters,
)
from .._wheel.equilibrium import Status, WheelState, solve_wheel
from .._wheel.geometry import AbstractWheel
from .._wheel.model import ContactModel, _as_model, _takes_model
from .._wheel.running import MAX_SLIP_ANGLE

__all__ = ["TireOnSnowForces", "tire_forces_on_snow"]


class TireOnSnowForces(eqx.Module):
    """Forces of a tyre on snow: chapter-3 combined-slip shear forces on the chapter-4
    sinkage and motion resistance (see [`snowjax.tire_forces_on_snow`][]).

    Every field has the broadcast shape of the inputs.

    **Fields:**

    - `longitudinal_force`: net longitudinal force along the wheel heading,
      `F_x|α≠0 − R_x` = combined shear force (3.14) minus motion resistance (4.16) [N];
      positive drives the vehicle forward (the drawbar pull of this model, cf. 2.10).
    - `lateral_force`: combined lateral shear force F_y|S_x≠0, eq. (3.15) [N], along the
      axle with the sign of the slip angle.
    - `sinkage`: z0 of the chapter-4 equilibrium, eq. (4.15) [m].
    - `motion_resistance`: R_x of the chapter-4 equilibrium, eq. (4.16) [N].
    - `shear_forces`: every chapter-3 force at the operating point, a
      [`snowjax.TireForces`][] (pure 3.11–3.13 and combined 3.14–3.16 forces [N],
      directions [rad]); `shear_forces.fx_combined` is the longitudinal shear force before
      the motion resistance is subtracted.
    - `wheel`: the chapter-4 [`snowjax.WheelState`][] of the straight-running wheel
      (entry angle, sinkage, motion resistance, the snow's own thrust and drawbar pull
      (2.9)–(2.10), torque), broadcast to the shape of the result.
    - `status`: the [`snowjax.Status`][] code of the wheel solve (int32);
      `INVALID_INPUT` also for a slip angle outside (−π/2, π/2) under `jit`, where every
      force field is NaN.
    """

    longitudinal_force: Float[Array, "..."]
    lateral_force: Float[Array, "..."]
    sinkage: Float[Array, "..."]
    motion_resistance: Float[Array, "..."]
    shear_forces: TireForces
    wheel: WheelState
    status: Int[Array, "..."]


@eqx.filter_jit
def _combine_jit(state: WheelState, load, slip, slip_angle, coefficients, parameters):
    """Chapter-3 forces at (load, slip, slip_angle) combined with a solved `state`."""
    params = tire_parameters(load, coefficients) if parameters is None else parameters
    shape = jnp.broadcast_shapes(
        state.sinkage.shape,
        jnp.shape(load),
        jnp.shape(slip),
        jnp.shape(slip_angle),
        *(jnp.shape(x) for x in jax.tree_util.tree_leaves(params)),
    )
    dtype = state.sinkage.dtype
    load, slip, slip_angle = (
        jnp.broadcast_to(x, shape).astype(dtype) for x in (load, slip, slip_angle)
    )
    state = jax.tree_util.tree_map(lambda x: jnp.broadcast_to(x, shape), state)
    valid = (state.status != Status.INVALID_INPUT) & (jnp.abs(slip_angle) < MAX_SLIP_ANGLE)
    # Safe stand-ins for invalid elements (their results are replaced by NaN below), so
    # that neither the value nor the gradient of the valid elements is poisoned.
    safe_load = jnp.where(valid, load, 1.0)
    safe_slip = jnp.where(valid, slip, 0.0)
    safe_angle = jnp.where(valid, slip_angle, 0.0)
    if parameters is None:  # the load functions at a safe load
        params = tire_parameters(safe_load, coefficients)
    forces = _forces(safe_load, safe_slip, safe_angle, params)
    nan = jnp.asarray(jnp.nan, dtype)

    def out(x):
        return jnp.where(valid, x, nan)

    forces = jax.tree_util.tree_map(out, forces)
    resistance = out(state.motion_resistance)
    return TireOnSnowForces(
        longitudinal_force=forces.fx_combined - resistance,
        lateral_force=forces.fy_combined,
        sinkage=out(state.sinkage),
        motion_resistance=resistance,
        shear_forces=forces,
        wheel=state,
        status=jnp.where(valid, state.status, Status.INVALID_INPUT).astype(jnp.int32),
    )


@_takes_model(positional=5)
def tire_forces_on_snow(
    wheel: AbstractWheel,
    terrain: Terrain | ContactModel,
    load: Float[ArrayLike, "..."],
    slip: Float[ArrayLike, "..."],
    slip_angle: Float[ArrayLike, "..."],
    *,
    coefficients: TireCoefficients | None = None,
    parameters: TireParameters | None = None,
) -> TireOnSnowForces:
    """Combined-slip tyre forces on snow: chapter 3's shear forces (3.7)–(3.16) with the
    sinkage and motion resistance of chapter 4's equilibrium (4.14)–(4.16).

    **What is computed, and where each quantity comes from:**

    1. *Sinkage and motion resistance (chapter 4).*  `solve_wheel(wheel, terrain, load,
       slip)` (`terrain` a terrain or a `ContactModel`): the entry angle with W(θ0) = F_z (4.14),
       the sinkage z0 (4.15) and the motion resistance R_x (4.16), for the wheel running
       straight (no slip angle).
    2. *Tyre parameters (chapter 3).*  C_s, C_α, μ_x, μ_y, E1 from the load functions
       (3.17)–(3.21) at the same load — **their published coefficients are in kN and
       kN/rad: the load in N is divided by 1000 for the formulas and the stiffnesses are
       returned in N/rad** ([`snowjax.tire_parameters`][]) — or the given `parameters`.
    3. *Shear forces (chapter 3).*  The normalised slips (3.7)–(3.9) with the same driving
       slip i (eq. 2.6 = S_d of 3.2, so S_x = −i and 1 + S_x = 1 − i in 3.8), N(φ) (3.10)
       and the combined forces F_x|α≠0 (3.14), F_y|S_x≠0 (3.15), exactly as
       [`snowjax.tire_forces`][].
    4. *Net forces.*  `longitudinal_force = F_x|α≠0 − R_x`, `lateral_force = F_y|S_x≠0`.

    **Modelling choices of snowjax (not in the thesis).**  The thesis never evaluates the
    two chapters together; this function does so as follows.

    - The chapter-3 shear force is read as the *gross* tractive (shear) force of the
      contact, the counterpart of chapter 4's thrust (2.9), and the chapter-4 motion
      resistance is subtracted from it, as drawbar pull = thrust − motion resistance
      (2.10).  The snow therefore enters the forces in two ways only: through the
      chapter-3 coefficients (fitted to FEA of the 0.736 m tyre on fresh snow, fixed
      unless `coefficients`/`parameters` are given) and through R_x.  The chapter-4
      snow's own thrust (Mohr–Coulomb / Janosi–Hanamoto shear) is *not* used for the
      forces — adding it would count the shear twice; it is returned in `wheel.thrust`
      and `wheel.drawbar_pull` for comparison.  The terrain's shear parameters still act
      on the sinkage and R_x, because the shear stress carries part of the load (4.14).
    - The equilibrium is solved at zero slip angle: chapter 4 has no slip angle, and the
      chapter-3 parameters depend on the load only, so sinkage and R_x are functions of
      (load, slip).  The lateral shear of the rigid-wheel model (`solve_wheel(...,
      slip_angle=...)`), which carries a little more load and lowers the sinkage, is not
      mixed in.  It also makes a slip-angle sweep cheap: the wheel is solved once for the
      broadcast shape of (wheel, terrain, load, slip), not per slip angle.
    - R_x acts along the wheel heading: it is the horizontal resultant of the radial
      normal stress on the rim, which lies in the wheel's plane.  No lateral resistance
      (sidewall bulldozing) is added; `solve_wheel(ContactModel(..., lateral=
      snowjax.Lateral(bulldozing=True)), ..., slip_angle=...)` has one.
    - The load functions were fitted for 3.5–7.5 kN on a 0.736 m tyre: use
      `RigidWheel.thesis_tire()` (0.736 m × 0.235 m) and a load in that range for a
      consistent pair; other wheels and loads are extrapolations of chapter 3.

    **Arguments** (`load`, `slip`, `slip_angle`, the leaves of `wheel`, `terrain`,
    `distribution` and of `parameters` or `coefficients` broadcast with NumPy rules):

    - `wheel`: [`snowjax.RigidWheel`][] (diameter [m], width [m]) or
      [`snowjax.DeflectingTire`][] (its sinkage and motion resistance those of the tyre
      that flattens; `snowjax reproduce` Fig. T.3).
    - `terrain`: any [`snowjax.Terrain`][], e.g. `WongSnow.thesis_fresh_snow()`, or a
      [`snowjax.ContactModel`][]: the shear model of the chapter-4 equilibrium
      (`JanosiHanamoto()` / `"classic"` (4.11), `ThesisSimplified()` / `"simplified"`
      (4.13) or `NoShear()` / `"none"`; see [`snowjax.solve_wheel`][]), the stress
      distribution (the front region, [`snowjax.WongReece`][] or another), the nodes
      per panel and force terms (its lateral law is not used: the equilibrium is solved at
      zero slip angle, above).
    - `load`: vertical wheel load F_z [N], > 0.
    - `slip`: driving slip i [-] in [−1, 1]: 0 free rolling, 1 spinning in place,
      negative braking.
    - `slip_angle`: α [rad], |α| < π/2; the lateral force has its sign.
    - `coefficients`: [`snowjax.TireCoefficients`][] of the load functions (**kN units**);
      default the thesis's.
    - `parameters`: [`snowjax.TireParameters`][] (C_s, C_α in N/rad) used instead of the
      load functions, e.g. friction coefficients fitted to another snow; not together
      with `coefficients`.

    Works under `jax.jit`, `jax.vmap` and `jax.grad` (the wheel's gradients come from the
    implicit function theorem).  Concrete inputs out of range raise `ValueError` naming
    them; under `jit` an invalid element gets `Status.INVALID_INPUT` and NaN forces, and
    the wheel's other statuses (`BOTTOMED_OUT`, `ENTRY_ANGLE_LIMIT`, ...) pass through.

    **Returns:** a [`snowjax.TireOnSnowForces`][] [N, m].

    Example: `snowjax.tire_forces_on_snow(snowjax.RigidWheel.thesis_tire(),
    snowjax.WongSnow.thesis_fresh_snow(), 5000.0, 0.2, 0.1).lateral_force`.
    """
    model = _as_model(terrain)
    if coefficients is not None and parameters is not None:
        raise ValueError("give `coefficients` or `parameters`, not both.")
    if parameters is not None and not isinstance(parameters, TireParameters):
        raise TypeError(
            f"parameters must be None or a snowjax.TireParameters, got {type(parameters).__name__}"
        )
    if coefficients is not None and not isinstance(coefficients, TireCoefficients):
        raise TypeError(
            "coefficients must be None or a snowjax.TireCoefficients, got "
            f"{type(coefficients).__name__}"
        )
    _check_operating_point(load, slip, slip_angle)
    _check("load", load, lambda x: x > 0, "a normal load > 0 N")
    if parameters is not None:
        _check_parameters(parameters)
    state = solve_wheel(wheel, model, load, slip)
    load, slip, slip_angle = (jnp.asarray(x) for x in (load, slip, slip_angle))
    return _combine_jit(state, load, slip, slip_angle, coefficients, parameters)
