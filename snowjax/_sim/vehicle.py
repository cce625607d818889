"""Vehicle model of the longitudinal simulation: the equations of motion, the slip and its
regularisation at rest, and the wheel force function `wheel_forces`.

**Model.**  A rigid vehicle of mass m moves along x on `num_wheels` identical rigid wheels,
each carrying the static share `m g / n` of its weight.  The state is
`y = (v, x, omega_1, ..., omega_n)` (speed [m/s], distance [m], wheel spins [rad/s]):

    m dv/dt        = sum_k F_k          F_k: drawbar pull of wheel k, eq. (2.10)
    dx/dt          = v
    I domega_k/dt  = T_k(t) - M_k       M_k: wheel torque resisted by the snow, eq. (2.12)

Each wheel's (F_k, M_k) is the thesis's equilibrium of a wheel rolling steadily into
undisturbed snow (eq. 4.14, `solve_wheel`) at the wheel's current slip: the contact model
is **quasi-static**, so transients faster than the passage of the snow under the wheel
(contact length / speed) are outside it.  Not modelled: aerodynamic drag, grade, load
transfer, tyre deflection.  A wheel whose applied torque is zero rolls freely (undriven).

**Slip.**  The argument of `solve_wheel` is the driving slip of eq. (2.6),
`i = 1 - v / (omega r)`, computed as `(omega r - v) / max(|omega r|, v / 2)`, clipped to
[-1, 1]: exact for driving (0 <= v <= omega r, i in [0, 1]) and for braking down to
`v = 2 omega r` (i = -1); harder braking, up to the locked wheel and a wheel spinning
backwards slower than the vehicle moves forwards, is held at i = -1, where the shear
stress of the thesis's snow (K << D) is already mobilised backwards over nearly the whole
contact.  A wheel whose rim moves backwards (v + omega r < 0) is the mirror image of one
whose rim moves forwards: the model is evaluated at (-v, -omega) and its forces change
sign.  In that frame (v' = d v, omega' = d omega, d = sign(v + omega r)) the rim speed
omega' r is at least -v', so the rim slides backwards over the snow wherever the model's
shear acts forwards, and vice versa.

**Every sign of v and omega: the snow never drives the vehicle.**  The contact's shear
(the thrust T and the torque M_w, from the shear displacement 4.10) opposes the sliding of
the rim over the snow, and the compaction resistance R_x (4.16) opposes the axle's motion:

    F = d * phi * (T - psi R_x),      M = d * phi * M_w,

psi = 1 wherever the axle moves forwards in the mirrored frame (v' >= 2 speed_eps, or a
braked wheel, v' >= omega' r), so that F is the drawbar pull (2.10) of `solve_wheel`, and
psi = -1 where it moves backwards (v' <= -2 speed_eps): a wheel spinning faster than the
vehicle moves the other way (slip above 1, held at 1; e.g. v = 8 m/s with
omega r = -11 m/s, or a driven wheel sliding back down a slope), whose model front region
lies behind the axle's motion.  In between, for a wheel spinning nearly in place,
`psi = a + (1 - a) b` with `a = 2 s - s |s|`, `s = clip(v' / (2 speed_eps), -1, 1)`, and
b the smoothstep `3 t^2 - 2 t^3` of `t = clip(2 v' / (omega' r) - 1, 0, 1)`: psi is
continuous (C^1 away from rest, where phi = 0) and has the sign of v'.  The power the snow
delivers, `F v - M omega`, is then `-phi psi R_x v'` plus the shear's power, which is
never positive where the shear displacement and the rim's sliding velocity have the same
sign everywhere on the contact (driving, slip above 1).  A braked wheel's shear can return
some of the energy stored in the snow (the Janosi–Hanamoto stress follows the shear
displacement, which falls again behind its peak): measured at most 43 % of R_x v' over
600,000 random in-range braking cases of Wong snow (front region and two Wong–Reece
distributions), so the total stays dissipative; the tests check
`F v - M omega <= 0` over random states of every sign on every terrain.  The simplified
shear model (4.13) is refused here: its braking extension can deliver power (a braked
wheel on snow with c >> p_w gets a forward thrust; see `wheel_forces`).

**Start from rest (regularisation).**  At v = omega = 0 the slip is 0/0, and the model,
whose forces at zero slip are not zero (the rim's geometry shears the snow even at i = 0),
does not describe a wheel at rest.  Both contact forces are therefore multiplied by

    phi(|v + omega r| / (2 speed_eps)),    phi(s) = 1 - (1 - min(s, 1))^2,

which is C^1, 0 at rest and exactly 1 once the mean of hub and rim speed exceeds
`speed_eps` (default 0.05 m/s); the slip ratio itself stays bounded (|i| <= 1) and only
its 0/0 at the origin is guarded.  Consequences, all tested: a vehicle at rest with no
torque stays at rest; a coasting vehicle comes to rest and stays there; a torque below
the self-propelled torque `M_w(i*)` (i* where the drawbar pull vanishes) leaves the
vehicle creeping at a speed below `speed_eps` (a viscous contact, the price of the
regularisation; the compaction factor psi lets a wheel spinning in place creep forward
until psi R_x balances the thrust); nothing in states with `|v + omega r| >= 2 speed_eps`
and `|v| >= 2 speed_eps` depends on `speed_eps`.  The force factor is also 0 on the
counter-rotation line `v = -omega r` (wheel spinning backwards as fast as the vehicle
moves forwards), where the mirror switches; a constant negative torque stops the vehicle
and then drives it backwards.

The time stepping of these equations is `stepping.simulate_longitudinal`.
"""

from __future__ import annotations

from typing import Any

import diffrax
import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float, Int

from .._leaves import _as_float, _check_real_leaves, _is_traced
from .._terrain.base import Terrain
from .._wheel.equilibrium import _check_model, solve_wheel
from .._wheel.geometry import AbstractWheel
from .._wheel.inputs import _check_lateral_and_terms, _validate_eagerly
from .._wheel.model import ContactModel, _as_model, _takes_model
from .._wheel.passes import _VirginGround
from .._wheel.shear_law import _shear_law

__all__ = [
    "STANDARD_GRAVITY",
    "DEFAULT_SPEED_EPS",
    "Vehicle",
    "TorqueProfile",
    "WheelForces",
    "Trajectory",
    "wheel_forces",
    "wheel_kinematics",
]

STANDARD_GRAVITY = 9.80665  # [m/s^2]
DEFAULT_SPEED_EPS = 0.05  # [m/s]
MAX_MODEL_SLIP_ANGLE = float(np.deg2rad(85.0))  # [rad] the clip of the slip angle


# ---------------------------------------------------------------------------------------
# Slip and the force function
# ---------------------------------------------------------------------------------------


def _compaction_direction(speed, rim_speed, speed_eps):
    """psi of the module docs: the direction of the axle's motion, which the compaction
    resistance opposes, at mirrored speeds (v', omega' r); in [-1, 1], C^1 except at rest.

    `a = band(v' / (2 speed_eps))` (odd, C^1, +-1 outside the band) is blended towards 1
    as the speed ratio q = v' / (omega' r) rises from 1/2 to 1 (slip from 1/2 to 0), so a
    braked wheel (q >= 1, or a rim at rest or turning backwards) has psi = 1 at any speed.
    """
    s = jnp.clip(speed / (2 * speed_eps), -1.0, 1.0)
    a = 2 * s - s * jnp.abs(s)
    turning = rim_speed > 0
    q = jnp.where(turning, speed / jnp.where(turning, rim_speed, 1.0), 1.0)
    t = jnp.clip(2 * q - 1, 0.0, 1.0)
    braked = t * t * (3 - 2 * t)
    return a + (1 - a) * braked


def _kinematics(speed, wheel_speed, radius, speed_eps):
    """(model slip, direction, force scale, compaction direction) of the module docs."""
    rim = wheel_speed * radius
    direction = jnp.where(speed + rim >= 0, 1.0, -1.0).astype(rim.dtype)
    v, u = direction * speed, direction * rim  # the mirror image whose rim moves forwards
    # Only to avoid 0 / 0 at rest: below speed_eps * eps the force factor is 0 to rounding.
    # (A floor of sqrt(tiny) made d slip / dv ~ 1e154 at rest, and second derivatives,
    # e.g. forward mode over the slopes snowjax.mjx uses, overflowed to inf.)
    floor = speed_eps * float(np.finfo(rim.dtype).eps)
    slip = (u - v) / jnp.maximum(jnp.maximum(jnp.abs(u), 0.5 * jnp.abs(v)), floor)
    slip = jnp.clip(slip, -1.0, 1.0)
    gap = 1 - jnp.minimum(jnp.abs(speed + rim) / (2 * speed_eps), 1.0)
    scale = 1 - gap * gap  # C^1: 0 at v + omega r = 0, 1 from |v + omega r| >= 2 eps on
    return slip, direction, scale, _compaction_direction(v, u, speed_eps)


def wheel_kinematics(
    speed: Float[ArrayLike, "..."],
    wheel_speed: Float[ArrayLike, "..."],
    radius: Float[ArrayLike, "..."],
    speed_eps: float = DEFAULT_SPEED_EPS,
) -> tuple[Float[Array, "..."], Float[Array, "..."]]:
    """Slip and force factor of a wheel as the simulation uses them (regularised at rest).

    - slip: the driving slip of eq. (2.6), `i = (omega r - v) / max(omega r, v / 2)`
      for a wheel travelling forwards (v + omega r >= 0), clipped to [-1, 1]; for one
      travelling backwards, the same of (-v, -omega).  Equal to the thesis's
      `1 - v / (omega r)` for 0 <= v <= 2 omega r; 1 for a wheel spinning in place,
      -1 for a locked or strongly braked one, 0 at rest.
    - force factor: `phi(|v + omega r| / (2 speed_eps))`, `phi(s) = 1 - (1 - min(s,
      1))^2`, the factor on both contact forces: 0 at rest, 1 as soon as
      `|v + omega r| >= 2 speed_eps`, C^1 in between.  The forces of `wheel_forces` are
      `d * factor * (thrust - psi * motion resistance, M_w)` at this slip, with
      d = sign(v + omega r) and psi in [-1, 1] the direction of the axle's motion in
      the mirrored frame (v' = d v, omega' = d omega): `psi = a + (1 - a) b`,
      `a = 2 s - s |s|`, `s = clip(v' / (2 speed_eps), -1, 1)`, b the smoothstep of
      `clip(2 v' / (omega' r) - 1, 0, 1)` (b = 1 for a rim at rest or turning
      backwards): the compaction resistance opposes the axle's motion, also where the
      axle moves against the rim (slip above 1, held at 1).

    **Arguments:** `speed` v [m/s], `wheel_speed` omega [rad/s], `radius` r = D/2 [m],
    `speed_eps` [m/s] (> 0).

    **Returns:** `(slip [-], force_factor [-])`.
    """
    dtype = jnp.result_type(speed, wheel_speed, radius, float)
    slip, _, factor, _ = _kinematics(
        jnp.asarray(speed, dtype),
        jnp.asarray(wheel_speed, dtype),
        jnp.asarray(radius, dtype),
        speed_eps,
    )
    return slip, factor


class WheelForces(eqx.Module):
    """Forces of the snow on one rigid wheel in a simulation step (see `wheel_forces`).

    - `longitudinal_force`: force along +x on the axle [N]: the drawbar pull (2.10),
      thrust minus motion resistance, with the motion resistance turned against the
      axle's motion (`wheel_kinematics`) and regularised at rest.
    - `resisting_torque`: M_w (2.12), the torque of the snow about the axle opposing a
      forward-spinning wheel [N m] (regularised); the wheel obeys
      `I domega/dt = T - resisting_torque`.
    - `sinkage`: z0 (4.15) [m] (not regularised: the equilibrium sinkage at the slip).
    - `entry_angle`: theta0 [rad]; pass it back as `initial_entry_angle` next step.
    - `slip`: the slip i [-] the contact model was evaluated at (`wheel_kinematics`).
    - `status`: `Status` code of the equilibrium solve (int32).
    """

    longitudinal_force: Float[Array, "..."]
    resisting_torque: Float[Array, "..."]
    sinkage: Float[Array, "..."]
    entry_angle: Float[Array, "..."]
    slip: Float[Array, "..."]
    status: Int[Array, "..."]


def _planar_kinematics(vx, vy, omega, radius, speed_eps):
    """(slip, slip angle, direction, longitudinal factor, lateral factor, compaction
    direction) of `snowjax/_sim/planar.py`'s module docs."""
    slip, direction, scale_x, compaction = _kinematics(vx, omega, radius, speed_eps)
    floor = speed_eps * float(np.finfo(vx.dtype).eps)
    along, side = jnp.abs(vx), -direction * vy
    moving = along + jnp.abs(side) > floor
    beta = jnp.arctan2(jnp.where(moving, side, 0.0), jnp.where(moving, along, 1.0))
    beta = jnp.clip(beta, -MAX_MODEL_SLIP_ANGLE, MAX_MODEL_SLIP_ANGLE)
    rim_mean, side_speed = (vx + omega * radius) / 2, vy
    q2 = rim_mean * rim_mean + side_speed * side_speed
    sliding = q2 > floor * floor
    q = jnp.where(sliding, jnp.sqrt(jnp.where(sliding, q2, 1.0)), 0.0)
    gap = 1 - jnp.minimum(q / speed_eps, 1.0)
    scale_y = 1 - gap * gap
    return slip, beta, direction, scale_x, scale_y, compaction


class _FrameForces(eqx.Module):
    """Wheel forces in the wheel frames (regularised) and the solve's outputs."""

    drawbar_pull: Array  # along the heading [N]
    lateral_force: Array  # along the axle [N]
    resisting_torque: Array  # about the axle [N m]
    aligning_torque: Array  # about the vertical [N m]
    sinkage: Array
    entry_angle: Array
    slip: Array
    slip_angle: Array
    status: Array


def _frame_forces(wheel, contact, load, vx, vy, omega, speed_eps, guess, steps, ground, overlap):
    """Snow forces on wheels in their own frames (heading, axle, vertical) from the wheel
    centres' velocities and spins: the one force function of `wheel_forces`, both
    simulations and `snowjax.mjx`.

    `vx` along the heading, `vy` along the axle [m/s] (None: the wheels run straight,
    without a slip angle: `solve_wheel`'s straight-running rules and no lateral force),
    `omega` the spins [rad/s]; `load` [N]; `guess` the warm start (or None); `steps`
    `solve_wheel`'s `max_steps`.  The wheels run on `ground` (`passes._VirginGround`, or
    `Ruts` with its layout resolved: the wheel axis last, a follower seeing `overlap`
    (..., n) of its leader's rut)."""
    radius = wheel.diameter / 2
    if vy is None:  # straight running: no slip angle, no lateral force
        slip, direction, scale_x, compaction = _kinematics(vx, omega, radius, speed_eps)
        beta, scale_y = None, jnp.zeros_like(scale_x)
    else:
        kinematics = _planar_kinematics(vx, vy, omega, radius, speed_eps)
        slip, beta, direction, scale_x, scale_y, compaction = kinematics

    def solve(c, take):
        part = jax.tree.map(lambda x: take(x) if jnp.ndim(x) == 1 else x, wheel)
        st = solve_wheel(
            part,
            c,
            take(load),
            take(slip),
            slip_angle=None if beta is None else take(beta),
            max_steps=steps,
            initial_entry_angle=None if guess is None else take(guess),
        )
        return st, st.sinkage

    st = ground._solve(contact, wheel.width, overlap, solve)
    # The mirror image of a wheel travelling backwards is turned by 180 degrees about the
    # vertical: forces along the heading and the axle change sign, the moment about the
    # vertical does not.
    return _FrameForces(
        drawbar_pull=direction * scale_x * (st.thrust - compaction * st.motion_resistance),
        lateral_force=direction * scale_y * st.lateral_force,
        resisting_torque=direction * scale_x * st.torque,
        aligning_torque=scale_y * st.aligning_torque,
        sinkage=st.sinkage,
        entry_angle=st.entry_angle,
        slip=slip * jnp.ones_like(st.sinkage),
        slip_angle=(0.0 if beta is None else beta) * jnp.ones_like(st.sinkage),
        status=st.status,
    )


def _wheel_forces(speed, wheel_speed, load, wheel, contact, speed_eps, guess, steps, ground):
    """`WheelForces` of wheels running straight (`wheel_forces`, `simulate_longitudinal`;
    `_frame_forces` without a lateral speed) on `ground` (`_resolved(ruts, n)`: with
    `Ruts`, the wheels along the last axis run in the ruts of the wheels ahead, straight
    ahead: full overlap)."""
    f = _frame_forces(
        wheel, contact, load, speed, None, wheel_speed, speed_eps, guess, steps, ground, 1.0
    )
    return WheelForces(
        longitudinal_force=f.drawbar_pull,
        resisting_torque=f.resisting_torque,
        sinkage=f.sinkage,
        entry_angle=f.entry_angle,
        slip=f.slip,
        status=f.status,
    )


_wheel_forces_jit = eqx.filter_jit(_wheel_forces)


def _check_dynamic_shear(shear, where: str) -> None:
    """The shear models a simulation step accepts: "classic" and "none".

    The simplified model's braking extension (4.13 with the mobilisation mirrored for
    slip < 0) can deliver power to the wheel: on snow with c >> p_w its exponent U0 stays
    positive over the whole contact of a braked wheel at a large entry angle, so the snow
    pushes the braked wheel forward (`tests/test_properties.py` keeps such a case).
    """
    law = _shear_law(shear)
    if not law.in_simulations:
        raise ValueError(
            f"shear={law.name!r} ({type(law).__name__}) is refused by {where}: its braking "
            "extension can push a braked wheel forward (it delivers power on snow with "
            "cohesion >> p_w); use shear='classic' (or 'none')."
        )


def _check_parameters(wheel, model) -> None:
    """`solve_wheel`'s checks of the wheel's and the model's leaves, eagerly (the force
    functions call `solve_wheel` inside a compiled program, where they are traced):
    ValueError naming the field of a concrete out-of-range value."""
    terrain, distribution, shear = model.terrain, model.distribution, model.shear
    dtype = _validate_eagerly(wheel, terrain, distribution, np.ones(()), np.zeros(()), shear)
    _check_lateral_and_terms(model.lateral, model.terms, dtype)


def _check_concrete(name, value, ok, allowed):
    if _is_traced(value) or value is None:
        return
    arr = np.asarray(value, dtype=float)
    if not np.all(np.isfinite(arr) & ok(arr)):
        raise ValueError(f"{name} must be finite and {allowed}; got {value!r}")


@_takes_model(positional=5)
def wheel_forces(
    speed: Float[ArrayLike, "..."],
    wheel_speed: Float[ArrayLike, "..."],
    load: Float[ArrayLike, "..."],
    wheel: AbstractWheel,
    snow: Terrain | ContactModel,
    *,
    speed_eps: float = DEFAULT_SPEED_EPS,
    initial_entry_angle: Float[ArrayLike, "..."] | None = None,
    max_steps: int = 64,
) -> WheelForces:
    """Snow forces on a rigid wheel from its kinematic state: the force function to call
    inside any simulator step (MJX, Brax, your own integrator).

    Computes the slip and force factor of `wheel_kinematics` (eq. 2.6, regularised at
    rest), solves the quasi-static equilibrium (4.14) with `solve_wheel` at that slip,
    and returns the drawbar pull (2.10) as the longitudinal force on the axle and M_w
    (2.12) as the torque resisting the wheel's spin, both multiplied by the force factor
    (and mirrored for a wheel whose rim moves backwards).  For every sign of `speed` and
    `wheel_speed` the shear opposes the rim's sliding over the snow and the motion
    resistance opposes the axle's motion (it is turned round, through a C^1 band of
    width 2 `speed_eps`, when the axle moves against the rim), so the power the snow
    delivers, `longitudinal_force * speed - resisting_torque * wheel_speed`, is never
    positive (tested over random states of every sign).
    Pure JAX: works under `jax.jit`, `jax.vmap`, `jax.grad` and `jax.jvp`; `speed`,
    `wheel_speed`, `load` and `initial_entry_angle` broadcast with NumPy rules.

    **Arguments:**

    - `speed`: v, forward speed of the axle over the snow [m/s].
    - `wheel_speed`: omega, spin of the wheel [rad/s] (positive rolls forwards).
    - `load`: vertical load F_z on the wheel [N], > 0.
    - `wheel`, `snow`: `RigidWheel` (D, b [m]) or `DeflectingTire`, and the terrain,
      any `snowjax.Terrain` (`WongSnow`, `BekkerSoil`, `ReeceSoil`, `LayeredSnow`; SI
      parameter sets), or a `ContactModel` in place of the terrain: its stress
      distribution, nodes per panel and force terms as in `solve_wheel`, its shear law
      `JanosiHanamoto()` (default) or `NoShear()` (`ThesisSimplified()` is refused: its
      braking extension can push a braked wheel forward).
    - `speed_eps`: regularisation speed [m/s], > 0.
    - `initial_entry_angle`: warm start theta0 [rad] for `solve_wheel`, e.g. the
      `entry_angle` of the previous simulator step; changes only the iteration count.
    - `max_steps`: Newton iteration limit, passed to `solve_wheel`.

    **Returns:** `WheelForces` (longitudinal force [N], resisting torque [N m], sinkage
    [m], entry angle [rad], slip [-], status).

    **Use in MJX / Brax.**  `snowjax.mjx` (extra `snowjax[mjx]`) does this for MuJoCo
    MJX: `snowjax.mjx.step` computes v (the axle's velocity along the wheel's heading),
    omega (the spin about the axle) and the load for every wheel body, calls this
    function, and writes `longitudinal_force * heading` and `-resisting_torque * axle`
    into the wheel rows of `data.xfrc_applied`, with a linearly implicit spin update.  In
    another simulator, do the same and keep `entry_angle` in the environment state to
    pass back as `initial_entry_angle`.  The contact forces are quasi-static: the
    simulator's step should resolve the wheel spin dynamics (the wheel equation is stiff
    near the self-propelled slip; explicit steps need dt well below
    `I omega^2 r / (v dM_w/di)`, or use an implicit step as `simulate_longitudinal` and
    `snowjax.mjx.step` do).

    **Errors.**  With concrete inputs, non-finite `speed`/`wheel_speed`, `load <= 0`,
    `speed_eps <= 0` or a wheel, terrain or distribution parameter out of `solve_wheel`'s
    range raise `ValueError` naming it; under `jit` invalid elements give
    `Status.INVALID_INPUT` and NaN fields (see `solve_wheel`).
    """
    model = _as_model(snow, "snow")
    _check_dynamic_shear(model.shear, "wheel_forces")
    _check_model(wheel, model)
    _check_parameters(wheel, model)
    _check_concrete("speed", speed, lambda x: np.ones_like(x, bool), "a number [m/s]")
    _check_concrete("wheel_speed", wheel_speed, lambda x: np.ones_like(x, bool), "a number [rad/s]")
    _check_concrete("load", load, lambda x: x > 0, "> 0 N")
    if not (np.isfinite(speed_eps) and speed_eps > 0):
        raise ValueError(f"speed_eps must be finite and > 0 m/s; got {speed_eps!r}")
    dtype = jnp.result_type(speed, wheel_speed, load, float)
    return _wheel_forces_jit(
        jnp.asarray(speed, dtype),
        jnp.asarray(wheel_speed, dtype),
        jnp.asarray(load, dtype),
        wheel,
        model,
        float(speed_eps),
        initial_entry_angle,
        int(max_steps),
        _VirginGround(),
    )


# ---------------------------------------------------------------------------------------
# Vehicle, torque input, trajectory
# ---------------------------------------------------------------------------------------


class Vehicle(eqx.Module):
    """A longitudinal vehicle on `num_wheels` identical rigid wheels.

    **Fields:**

    - `mass`: total mass m, wheels included [kg]; every wheel carries
      `m g / num_wheels` (g = 9.80665 m/s^2), with no load transfer.
    - `wheel_inertia`: I, moment of inertia of each wheel about its axle, including the
      driveline reflected to it [kg m^2]; scalar or one value per wheel.
    - `wheel`: `RigidWheel` (diameter D, width b [m]) or `DeflectingTire`.
    - `num_wheels`: number of wheels n (static).  Which of them are driven is set by
      the torque: a wheel with zero applied torque rolls freely.
    """

    __check_init__ = _check_real_leaves

    mass: Float[Array, ""] = eqx.field(converter=_as_float)
    wheel_inertia: Float[Array, "..."] = eqx.field(converter=_as_float)
    wheel: AbstractWheel
    num_wheels: int = eqx.field(static=True, default=4)

    @property
    def wheel_load(self) -> Float[Array, ""]:
        """Static vertical load on each wheel, `m g / n` [N]."""
        return self.mass * STANDARD_GRAVITY / self.num_wheels


class TorqueProfile(eqx.Module):
    """Applied wheel torque as a piecewise-linear function of time.

    `T(t)` interpolates `values` linearly between the knot `times` and is constant
    beyond the ends, so it is differentiable w.r.t. every knot value (the leaves are
    arrays: pass the profile through `jax.grad`, or optimise `values`).

    **Fields:**

    - `times`: knot times [s], increasing, shape (k,).
    - `values`: torque at the knots [N m], shape (k,) (same for every wheel) or (k, n)
      (one column per wheel).
    """

    __check_init__ = _check_real_leaves

    times: Float[Array, " k"] = eqx.field(converter=_as_float)
    values: Float[Array, "k ..."] = eqx.field(converter=_as_float)

    @classmethod
    def uniform(cls, t1: float, values: Float[ArrayLike, "k ..."]) -> "TorqueProfile":
        """Knots equally spaced over [0, t1] [s]; `values` [N m] of shape (k,) or (k, n)."""
        values = jnp.asarray(values, float)
        return cls(jnp.linspace(0.0, t1, values.shape[0]), values)

    def __call__(
        self, t: Float[ArrayLike, ""], speed: Any = None, wheel_speed: Any = None
    ) -> Float[Array, "..."]:
        """Torque [N m] at time t [s]: shape () or (n,).  `speed`, `wheel_speed` unused."""
        del speed, wheel_speed
        if self.values.ndim == 1:
            return jnp.interp(t, self.times, self.values)
        return jax.vmap(lambda col: jnp.interp(t, self.times, col), in_axes=1)(self.values)


class Trajectory(eqx.Module):
    """Result of `simulate_longitudinal`: the state and wheel forces at the saved times.

    Shapes: (s,) or (s, n) for s saved times and n wheels.

    - `time` [s]; `speed` v [m/s]; `distance` x [m]; `wheel_speed` omega [rad/s].
    - `slip`: slip i [-] each wheel's contact was evaluated at (`wheel_kinematics`).
    - `sinkage`: z0 (4.15) [m]; `entry_angle` theta0 [rad].
    - `drawbar_pull`: longitudinal force of each wheel, eq. (2.10), regularised [N];
      their sum is m dv/dt.
    - `resisting_torque`: M_w (2.12), regularised [N m]; `applied_torque` T [N m].
    - `status`: `Status` of each wheel's equilibrium (int32).  Rows after a failed time
      step (see `result`) hold inf states and `Status.INVALID_INPUT`.
    - `result`: `diffrax.RESULTS` of the time integration (successful unless an implicit
      step's Newton iteration failed).
    """

    time: Float[Array, " s"]
    speed: Float[Array, " s"]
    distance: Float[Array, " s"]
    wheel_speed: Float[Array, "s n"]
    slip: Float[Array, "s n"]
    sinkage: Float[Array, "s n"]
    entry_angle: Float[Array, "s n"]
    drawbar_pull: Float[Array, "s n"]
    resisting_torque: Float[Array, "s n"]
    applied_torque: Float[Array, "s n"]
    status: Int[Array, "s n"]
    result: diffrax.RESULTS


def _torque_at(torque, t, speed, wheel_speed):
    """Applied torque per wheel [N m], shape of `wheel_speed`; ValueError naming `torque`
    for a value (or a controller's output) of another shape than () or (n,)."""
    value = jnp.asarray(torque(t, speed, wheel_speed) if callable(torque) else torque)
    if value.shape not in ((), wheel_speed.shape):
        source = "the torque controller returned" if callable(torque) else "got"
        raise ValueError(
            f"torque must be a number or one value per wheel, shape {wheel_speed.shape}"
            f" [N m]; {source} shape {value.shape}"
        )
    return jnp.broadcast_to(value.astype(wheel_speed.dtype), wheel_speed.shape)


def _check_profile(profile, n):
    times, values = profile.times, profile.values
    if (
        times.ndim != 1
        or values.shape[:1] != times.shape
        or values.ndim > 2
        or (values.ndim == 2 and values.shape[1] != n)
    ):
        raise ValueError(
            "TorqueProfile: times must have shape (k,) and values (k,) or (k, num_wheels);"
            f" got {times.shape} and {values.shape} for {n} wheels"
        )
    _check_increasing("TorqueProfile", times)


def _check_increasing(owner, times):
    """Knot times [s] of a profile strictly increasing (when concrete)."""
    if not _is_traced(times) and not np.all(np.diff(np.asarray(times, dtype=float)) > 0):
        raise ValueError(f"{owner}: times must be strictly increasing")
