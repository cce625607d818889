"""Vehicle model of the planar simulation: a four-wheel vehicle that steers, its wheel
kinematics (slip, slip angle, their regularisation at rest) and the wheel forces.

**Frames and state.**  The ground frame has axes (X, Y) and the vehicle's yaw psi is the
angle from X to the body's forward axis.  The body frame has its origin at the centre of
gravity (CG), x forward, y to the left, z up.  The state is

    y = (X, Y, psi, u, v, r, omega_1, ..., omega_4)

(CG position [m], yaw [rad], body-frame velocities u forward and v to the left [m/s], yaw
rate r [rad/s], counter-clockwise seen from above, wheel spins [rad/s]).  The wheels are,
in this order, front left, front right, rear left, rear right, at body positions
`(a, +w/2), (a, -w/2), (-(L - a), +w/2), (-(L - a), -w/2)` (wheelbase L, track width w,
CG a behind the front axle).  The front wheels steer: wheel k has its own frame rotated by
its steer angle delta_k (counter-clockwise positive, the rear wheels' is 0), with x_k along
its heading and y_k along its axle.

**Equations of motion** (rigid body in the plane, quasi-static wheel contacts):

    dX/dt = u cos psi - v sin psi,      dY/dt = u sin psi + v cos psi,     dpsi/dt = r
    m (du/dt - r v) = sum_k F_x,k        m (dv/dt + r u) = sum_k F_y,k
    I_z dr/dt       = sum_k (x_k F_y,k - y_k F_x,k + M_z,k)
    I_w domega_k/dt = T_k(t) - M_w,k

with (F_x,k, F_y,k) the wheel's (drawbar pull, lateral force) rotated by delta_k into the
body frame, M_z,k its aligning torque (about the vertical through the wheel centre,
counter-clockwise positive; with the thesis's front-region stresses the lateral stresses
act ahead of the axle, so it is positive for beta > 0) and M_w,k the torque the snow
resists (all from
`solve_wheel` with a slip angle: the thesis's steady-rolling equilibrium, eq. 4.14, with
the combined lateral shear of `snowjax.Lateral`).  Each wheel carries its static load:
`m g (L - a) / (2 L)` on a front wheel, `m g a / (2 L)` on a rear one.  Not modelled: load
transfer (longitudinal and lateral), aerodynamic drag, grade, tyre deflection, the spin
inertia's gyroscopic terms.  The contact model is quasi-static: transients faster than the
passage of the snow under the wheel are outside it.

**Wheel kinematics.**  The velocity of wheel k's centre in the body frame is
`(u - r y_k, v + r x_k)`; rotated into the wheel's frame it is (v_x, v_y).  The driving
slip (eq. 2.6) is that of the heading's component, `i = 1 - v_x / (omega r_w)`, computed,
clipped to [-1, 1] and regularised at rest exactly as in the longitudinal simulation
(`snowjax.wheel_kinematics`; a wheel travelling backwards, v_x + omega r_w < 0, is the
mirror image of one travelling forwards, here a rotation by 180 degrees about the
vertical).  The slip angle is

    beta = atan2(-d v_y, |v_x|),   clipped to |beta| <= 85 degrees,

with d = sign(v_x + omega r_w) the direction of travel: the angle by which the wheel's
velocity (V cos beta, -V sin beta) turns clockwise from its heading, so that the lateral
force of `solve_wheel` (positive for beta > 0) opposes the side-slip.  A wheel sliding
sideways at v_x -> 0 has beta -> +-90 degrees; the clip keeps `tan(beta)` finite there,
where the lateral shear is fully mobilised anyway.  As in the longitudinal simulation
the force along the heading is the thrust minus psi times the motion resistance, psi in
[-1, 1] the direction of the wheel's motion along its heading (`snowjax.wheel_kinematics`;
+-1 outside a band of width 2 `speed_eps` about v_x = 0, and 1 for a braked wheel): the
compaction resistance opposes the wheel's motion along its heading, also when the wheel
spins against it.

**Start from rest (regularisation).**  The longitudinal forces (drawbar pull, M_w) carry
the factor of `snowjax.wheel_kinematics`, `phi(|v_x + omega r_w| / (2 speed_eps))` with
`phi(s) = 1 - (1 - min(s, 1))^2`, so straight running is exactly the longitudinal model.
The lateral force and the aligning torque carry `phi(q / (2 speed_eps))` with
`q = sqrt((v_x + omega r_w)^2 + (2 v_y)^2)`: 0 at rest, 1 once
`sqrt(((v_x + omega r_w) / 2)^2 + v_y^2)` (the mean of hub and rim speed along the heading
combined with the side speed) reaches `speed_eps`; a wheel sliding sideways without rolling
is therefore resisted.  Where `|v_x| + |v_y|` is below `speed_eps` times the machine
epsilon (1.1e-17 m/s by default in float64) the slip angle is set to 0, so that at rest
every value and every derivative is finite.  Slip and slip angle do not depend on
`speed_eps`, so nothing in states where both factors are 1 and `|v_x| >= 2 speed_eps`
does.

The time stepping of these equations is `planar_stepping.simulate_planar`.
"""

from __future__ import annotations

import math
from typing import Any

import diffrax
import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float, Int

from .._leaves import _as_float, _check_real_leaves, _is_traced
from .._wheel.geometry import AbstractWheel
from .._wheel.model import ContactModel, _as_model
from .._wheel.passes import _follower_overlap
from .._wheel.running import _default_lateral
from .vehicle import (
    DEFAULT_SPEED_EPS,
    MAX_MODEL_SLIP_ANGLE,
    STANDARD_GRAVITY,
    _check_increasing,
    _frame_forces,
    _planar_kinematics,
)

__all__ = [
    "MAX_MODEL_SLIP_ANGLE",
    "PlanarVehicle",
    "SteeringProfile",
    "PlanarTrajectory",
    "planar_wheel_kinematics",
]

NUM_WHEELS = 4  # front left, front right, rear left, rear right


# ---------------------------------------------------------------------------------------
# The vehicle and the steering input
# ---------------------------------------------------------------------------------------


class PlanarVehicle(eqx.Module):
    """A four-wheel vehicle moving in the plane (x, y, yaw) whose front wheels steer.

    Wheel order: front left, front right, rear left, rear right.  Body frame: origin at
    the centre of gravity (CG), x forward, y left.

    **Fields:**

    - `mass`: total mass m, wheels included [kg].
    - `yaw_inertia`: I_z, moment of inertia about the vertical through the CG [kg m^2].
    - `wheel_inertia`: I_w, moment of inertia of each wheel about its axle, including the
      driveline reflected to it [kg m^2]; scalar or one value per wheel, shape (4,).
    - `wheel`: `RigidWheel` (diameter D, width b [m]) or `DeflectingTire`, the same on
      every corner.
    - `wheelbase`: L, distance from the rear to the front axle [m].
    - `track_width`: w, distance between the left and right wheel centres [m].
    - `cg_to_front_axle`: a, distance of the CG behind the front axle [m], 0 < a < L;
      `None` (default): L / 2.  It sets the static loads (`wheel_load`).
    - `ackermann`: whether the front wheels follow Ackermann steering (static, default
      True): the steering input delta is then the bicycle-model angle and the inner and
      outer wheels turn about a common point on the rear axle line,
      `tan delta_inner/outer = L tan delta / (L -+ (w/2) tan delta)`.  With False both
      front wheels are at delta (parallel steering).
    """

    __check_init__ = _check_real_leaves

    mass: Float[Array, ""] = eqx.field(converter=_as_float)
    yaw_inertia: Float[Array, ""] = eqx.field(converter=_as_float)
    wheel_inertia: Float[Array, "..."] = eqx.field(converter=_as_float)
    wheel: AbstractWheel
    wheelbase: Float[Array, ""] = eqx.field(converter=_as_float)
    track_width: Float[Array, ""] = eqx.field(converter=_as_float)
    cg_to_front_axle: Float[Array, ""] | None = eqx.field(converter=_as_float, default=None)
    ackermann: bool = eqx.field(static=True, default=True)

    @property
    def front_axle(self) -> Float[Array, ""]:
        """a, the CG's distance behind the front axle [m]."""
        if self.cg_to_front_axle is None:
            return self.wheelbase / 2
        return self.cg_to_front_axle

    @property
    def wheel_positions(self) -> Float[Array, "4 2"]:
        """Body-frame positions (x_k, y_k) of the four wheel centres [m], shape (4, 2)."""
        a, b, half = self.front_axle, self.wheelbase - self.front_axle, self.track_width / 2
        x = jnp.stack([a, a, -b, -b])
        y = jnp.stack([half, -half, half, -half])
        return jnp.stack([x, y], axis=-1)

    @property
    def wheel_load(self) -> Float[Array, "4"]:
        """Static vertical load on each wheel [N], shape (4,): `m g (L - a) / (2 L)` at
        the front, `m g a / (2 L)` at the rear (g = 9.80665 m/s^2)."""
        a, length = self.front_axle, self.wheelbase
        front = self.mass * STANDARD_GRAVITY * (length - a) / (2 * length)
        rear = self.mass * STANDARD_GRAVITY * a / (2 * length)
        return jnp.stack([front, front, rear, rear])

    def steer_angles(self, steering: Float[ArrayLike, ""]) -> Float[Array, "4"]:
        """Steer angle of each wheel [rad], shape (4,), for the steering input delta [rad]
        (counter-clockwise positive: delta > 0 turns left); the rear wheels' are 0."""
        delta = jnp.asarray(steering)
        if not self.ackermann:
            front_left = front_right = delta
        else:
            front_left, front_right = _ackermann(delta, self.wheelbase, self.track_width)
        zero = jnp.zeros_like(front_left)
        return jnp.stack([front_left, front_right, zero, zero])


def _ackermann(delta, wheelbase, track_width):
    """(left, right) front steer angles [rad] of Ackermann steering for the bicycle-model
    angle delta [rad]: `tan delta_k = L tan delta / (L - y_k tan delta)`, y_k = +-w/2,
    written without tan (finite for every delta)."""
    half = track_width / 2
    s, c = jnp.sin(delta), jnp.cos(delta)
    left = jnp.arctan2(wheelbase * s, wheelbase * c - half * s)
    right = jnp.arctan2(wheelbase * s, wheelbase * c + half * s)
    return left, right


class SteeringProfile(eqx.Module):
    """Steering input delta [rad] as a piecewise-linear function of time.

    `delta(t)` interpolates `values` linearly between the knot `times` and is constant
    beyond the ends, so it is differentiable w.r.t. every knot value (the leaves are
    arrays: pass the profile through `jax.grad`, or optimise `values`).  delta is the
    steer angle of both front wheels, or with `PlanarVehicle.ackermann` the angle of the
    equivalent bicycle model; counter-clockwise positive (delta > 0 turns left).

    **Fields:**

    - `times`: knot times [s], increasing, shape (k,).
    - `values`: steering input at the knots [rad], shape (k,).
    """

    __check_init__ = _check_real_leaves

    times: Float[Array, " k"] = eqx.field(converter=_as_float)
    values: Float[Array, " k"] = eqx.field(converter=_as_float)

    @classmethod
    def uniform(cls, t1: float, values: Float[ArrayLike, " k"]) -> SteeringProfile:
        """Knots equally spaced over [0, t1] [s]; `values` [rad] of shape (k,)."""
        values = jnp.asarray(values, float)
        return cls(jnp.linspace(0.0, t1, values.shape[0]), values)

    def __call__(self, t: Float[ArrayLike, ""], state: Any = None) -> Float[Array, ""]:
        """Steering input [rad] at time t [s].  `state` unused."""
        del state
        return jnp.interp(t, self.times, self.values)


def _steered_model(snow, who) -> ContactModel:
    """The `ContactModel` of a steered wheel's terrain or model (`simulate_planar`,
    `snowjax.mjx`): its shear law checked to have a lateral counterpart, its lateral law
    defaulted to `Lateral()`.  `who` names the caller in the errors."""
    model = _as_model(snow, "snow")
    law = model.shear
    if not law.lateral:
        raise ValueError(
            f"shear={law.name!r} ({type(law).__name__}) has no lateral counterpart: use "
            f"ContactModel(terrain, shear='classic') (or 'none') with {who}."
        )
    if model.lateral is None:
        lateral = _default_lateral(bool(jax.config.read("jax_enable_x64")))
        model = eqx.tree_at(lambda m: m.lateral, model, lateral, is_leaf=lambda x: x is None)
    return model


def _check_steering_profile(profile: SteeringProfile) -> None:
    times, values = profile.times, profile.values
    if times.ndim != 1 or values.shape != times.shape:
        raise ValueError(
            "SteeringProfile: times and values must both have shape (k,); "
            f"got {times.shape} and {values.shape}"
        )
    _check_increasing("SteeringProfile", times)
    if not _is_traced(values):
        arr = np.asarray(values, dtype=float)
        if not np.all(np.isfinite(arr) & (np.abs(arr) < np.pi / 2)):
            raise ValueError(
                f"SteeringProfile: values must be finite and in (-pi/2, pi/2) rad; got {arr!r}"
            )


def _steering_at(steering, t, y):
    """Steering input delta [rad] at time t; a run-time error (`eqx.error_if`) if it is not
    finite and inside (-pi/2, pi/2): a controller's output is only known then (constant and
    profile inputs are also checked before the run, when concrete)."""
    raw: Any = steering(t, y) if callable(steering) else steering
    shape = jnp.shape(raw)
    if math.prod(shape) != 1:
        raise ValueError(f"steering must be one angle [rad]; got shape {shape}")
    message = "simulate_planar: the steering input is outside (-pi/2, pi/2) rad or not finite"
    if not _is_traced(raw) and not abs(float(np.asarray(raw))) < np.pi / 2:
        raise ValueError(f"{message}: {float(np.asarray(raw))!r}")
    value = jnp.asarray(raw, y.dtype).reshape(())
    return eqx.error_if(value, ~(jnp.abs(value) < np.pi / 2), message)


# ---------------------------------------------------------------------------------------
# Wheel kinematics and forces
# ---------------------------------------------------------------------------------------


def planar_wheel_kinematics(
    speed: Float[ArrayLike, "..."],
    lateral_speed: Float[ArrayLike, "..."],
    wheel_speed: Float[ArrayLike, "..."],
    radius: Float[ArrayLike, "..."],
    speed_eps: float = DEFAULT_SPEED_EPS,
) -> tuple[Float[Array, "..."], Float[Array, "..."], Float[Array, "..."], Float[Array, "..."]]:
    """Slip, slip angle and force factors of a wheel as `simulate_planar` uses them.

    - slip: the driving slip of eq. (2.6) of the heading's speed component, exactly as
      [`snowjax.wheel_kinematics`][] (clipped to [-1, 1], mirrored for a wheel travelling
      backwards, 0 at rest).
    - slip angle: `atan2(-d v_y, |v_x|)`, d = sign(v_x + omega r), clipped to
      |beta| <= 85 degrees; positive when the wheel slides towards -y of its own frame,
      where `solve_wheel`'s lateral force (positive) opposes the slide; 0 at rest.
    - longitudinal factor: `phi(|v_x + omega r| / (2 speed_eps))`, that of
      `wheel_kinematics`, on the drawbar pull and the resisted torque.
    - lateral factor: `phi(q / (2 speed_eps))`, `q = sqrt((v_x + omega r)^2 + (2 v_y)^2)`,
      on the lateral force and the aligning torque; `phi(s) = 1 - (1 - min(s, 1))^2`.

    Values and derivatives are finite everywhere, rest included.

    **Arguments:** `speed` v_x, the wheel centre's speed along its heading [m/s];
    `lateral_speed` v_y, along its axle (positive to the wheel's left) [m/s];
    `wheel_speed` omega [rad/s]; `radius` r = D/2 [m]; `speed_eps` [m/s] (> 0).

    **Returns:** `(slip [-], slip_angle [rad], longitudinal_factor [-],
    lateral_factor [-])`.
    """
    if not (np.isfinite(speed_eps) and speed_eps > 0):
        raise ValueError(f"speed_eps must be finite and > 0 m/s; got {speed_eps!r}")
    dtype = jnp.result_type(speed, lateral_speed, wheel_speed, radius, float)
    vx, vy, omega, r = (jnp.asarray(x, dtype) for x in (speed, lateral_speed, wheel_speed, radius))
    vx, vy, omega, r = jnp.broadcast_arrays(vx, vy, omega, r)
    slip, beta, _, scale_x, scale_y, _ = _planar_kinematics(vx, vy, omega, r, float(speed_eps))
    return slip, beta, scale_x, scale_y


def _body_to_wheel(vehicle, u, v, r, steer):
    """Wheel-frame velocities (v_x, v_y) [m/s] of the wheel centres, (..., 4) each."""
    pos = vehicle.wheel_positions
    vx_body = u[..., None] - r[..., None] * pos[:, 1]
    vy_body = v[..., None] + r[..., None] * pos[:, 0]
    c, s = jnp.cos(steer), jnp.sin(steer)
    return c * vx_body + s * vy_body, -s * vx_body + c * vy_body


def _rut_overlap(vehicle, u, v, r, follows):
    """Each wheel's overlap with its leader's rut (1 for a leader), (..., 4): the
    follower sees `clip(1 - |e| / b, 0, 1)` of the rut's depth, e its offset from the
    leader's path about the instantaneous centre of rotation (`passes._follower_overlap`)."""
    pos = vehicle.wheel_positions
    velocity = jnp.stack(
        [u[..., None] - r[..., None] * pos[:, 1], v[..., None] + r[..., None] * pos[:, 0]], -1
    )
    return _follower_overlap(pos, velocity, r[..., None], vehicle.wheel.width, follows)


def _planar_wheel_forces(vehicle, contact, u, v, r, omega, steer, speed_eps, guess, steps, ground):
    """Snow forces on the four wheels at body velocities (u, v, r) and spins omega, for a
    `ContactModel` `contact` on `ground` (`_resolved(ruts, 4)`: with `Ruts` the rear
    wheels run in the front wheels' ruts, `_rut_overlap`)."""
    vx, vy = _body_to_wheel(vehicle, u, v, r, steer)
    overlap = ground._overlap(lambda follows: _rut_overlap(vehicle, u, v, r, follows))
    return _frame_forces(
        vehicle.wheel, contact, vehicle.wheel_load, vx, vy, omega, speed_eps, guess, steps,
        ground, overlap,
    )  # fmt: skip


def _body_forces(vehicle, f, steer):
    """(sum F_x, sum F_y [N], yaw moment [N m]) about the CG in the body frame."""
    c, s = jnp.cos(steer), jnp.sin(steer)
    fx = c * f.drawbar_pull - s * f.lateral_force
    fy = s * f.drawbar_pull + c * f.lateral_force
    pos = vehicle.wheel_positions
    moment = pos[:, 0] * fy - pos[:, 1] * fx + f.aligning_torque
    return jnp.sum(fx, -1), jnp.sum(fy, -1), jnp.sum(moment, -1)


# ---------------------------------------------------------------------------------------
# Result
# ---------------------------------------------------------------------------------------


class PlanarTrajectory(eqx.Module):
    """Result of `simulate_planar`: the state and wheel forces at the saved times.

    Shapes: (s,) or (s, 4) for s saved times; wheels in the order front left, front
    right, rear left, rear right.

    - `time` [s]; `x`, `y`: CG position in the ground frame [m]; `yaw` psi [rad].
    - `speed` u, `lateral_speed` v: CG velocity in the body frame (forward, left) [m/s];
      `yaw_rate` r [rad/s] (counter-clockwise positive).
    - `wheel_speed` omega [rad/s]; `steer_angle` delta_k of each wheel [rad].
    - `slip` i [-] and `slip_angle` beta [rad] each wheel's contact was evaluated at
      (`planar_wheel_kinematics`).
    - `sinkage` z0 (4.15) [m]; `entry_angle` theta0 [rad].
    - `drawbar_pull` (2.10), along each wheel's heading [N]; `lateral_force`, along its
      axle [N]; `resisting_torque` M_w (2.12) [N m]; `aligning_torque` M_z about the
      vertical through the wheel centre [N m]: the snow's forces on the wheel in its own
      frame, regularised at rest.
    - `applied_torque` T [N m].
    - `status`: `Status` of each wheel's equilibrium (int32).  Rows after a failed time
      step (see `result`) hold inf states and `Status.INVALID_INPUT`.
    - `result`: `diffrax.RESULTS` of the time integration.
    """

    time: Float[Array, " s"]
    x: Float[Array, " s"]
    y: Float[Array, " s"]
    yaw: Float[Array, " s"]
    speed: Float[Array, " s"]
    lateral_speed: Float[Array, " s"]
    yaw_rate: Float[Array, " s"]
    wheel_speed: Float[Array, "s 4"]
    steer_angle: Float[Array, "s 4"]
    slip: Float[Array, "s 4"]
    slip_angle: Float[Array, "s 4"]
    sinkage: Float[Array, "s 4"]
    entry_angle: Float[Array, "s 4"]
    drawbar_pull: Float[Array, "s 4"]
    lateral_force: Float[Array, "s 4"]
    resisting_torque: Float[Array, "s 4"]
    aligning_torque: Float[Array, "s 4"]
    applied_torque: Float[Array, "s 4"]
    status: Int[Array, "s 4"]
    result: diffrax.RESULTS
