"""Time stepping of the planar vehicle simulation: `simulate_planar`.

The equations of motion, the wheel kinematics and the regularisation at rest are those of
`planar.py`; the state is `y = (X, Y, psi, u, v, r, omega_1, ..., omega_4)`.  The time
stepping is the longitudinal simulation's (`stepping.py`): implicit Euler steps of `dt` in
`diffrax.diffeqsolve`, each solved by the damped Newton iteration of
`levenberg_marquardt.py`, a step that is not solved retried as smaller steps, and the
wheels' entry angles carried in the solver state as the warm start of the next
`solve_wheel`; the saved wheel outputs are those of the steps' own solves.  Only the ODE
term (`_PlanarTerm`) and the shape of the warm start (four wheels) are this module's own.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import ArrayLike, Float

from .._leaves import _is_traced
from .._terrain.base import Terrain
from .._wheel.model import ContactModel, _takes_model
from .._wheel.passes import Ruts, _resolved, _VirginGround
from .options import InitialState, Stepping
from .planar import (
    NUM_WHEELS,
    PlanarTrajectory,
    PlanarVehicle,
    SteeringProfile,
    _body_forces,
    _check_steering_profile,
    _planar_wheel_forces,
    _steered_model,
    _steering_at,
)
from .stepping import _MOVED_TO_OPTIONS, _check_run, _integrate, _WarmStartTerm
from .vehicle import TorqueProfile, _check_concrete, _check_profile, _torque_at

__all__ = ["simulate_planar"]


class _PlanarTerm(_WarmStartTerm):
    """Right-hand side of the planar equations of motion, y = (X, Y, psi, u, v, r, omega)."""

    vehicle: PlanarVehicle
    contact: ContactModel
    steering: Any
    torque: Any
    speed_eps: float = eqx.field(static=True)
    max_wheel_steps: int = eqx.field(static=True)
    ground: Ruts | _VirginGround  # the terrain state the wheels run on (`_resolved`)
    OUTPUTS: ClassVar = (
        "drawbar_pull",
        "lateral_force",
        "resisting_torque",
        "aligning_torque",
        "sinkage",
        "entry_angle",
        "slip",
        "slip_angle",
    )

    def steer(self, t, y):
        """Steer angles (4,) [rad] at time t [s] and state y (10,)."""
        return self.vehicle.steer_angles(_steering_at(self.steering, t, y))

    def forces(self, t, y, hint):
        """(steer angles (4,) [rad], wheel forces) at time t [s] and state y (10,)."""
        steer = self.steer(t, y)
        f = _planar_wheel_forces(
            self.vehicle,
            self.contact,
            y[3],
            y[4],
            y[5],
            y[6:],
            steer,
            self.speed_eps,
            hint,
            self.max_wheel_steps,
            self.ground,
        )
        return steer, f

    def vf(self, t, y, args):
        y = y[0]
        steer, f = self.forces(t, y, args)
        fx, fy, moment = _body_forces(self.vehicle, f, steer)
        yaw, u, v, r = y[2], y[3], y[4], y[5]
        mass = self.vehicle.mass
        applied = _torque_at(self.torque, t, u, y[6:])
        inertia = jnp.broadcast_to(self.vehicle.wheel_inertia, applied.shape)
        c, s = jnp.cos(yaw), jnp.sin(yaw)
        rates = jnp.stack(
            [
                u * c - v * s,
                u * s + v * c,
                r,
                fx / mass + r * v,
                fy / mass - r * u,
                moment / self.vehicle.yaw_inertia,
            ]
        )
        domega = (applied - f.resisting_torque) / inertia
        return jnp.concatenate([rates, domega]), f.entry_angle, self.pack(f), f.status

    def num_wheels(self, y0):
        return NUM_WHEELS


@eqx.filter_jit
def _simulate_planar_jit(term, y0, n_steps, dt, save_every, adjoint, newton_steps):
    save_ts, ys, f, status, result = _integrate(
        term, y0, n_steps, dt, save_every, adjoint, newton_steps
    )
    steer = jax.vmap(term.steer)(save_ts, ys)
    applied = jax.vmap(lambda t, y: _torque_at(term.torque, t, y[3], y[6:]))(save_ts, ys)
    return PlanarTrajectory(
        time=save_ts,
        x=ys[:, 0],
        y=ys[:, 1],
        yaw=ys[:, 2],
        speed=ys[:, 3],
        lateral_speed=ys[:, 4],
        yaw_rate=ys[:, 5],
        wheel_speed=ys[:, 6:],
        steer_angle=steer,
        applied_torque=applied,
        status=status,
        result=result,
        **f,
    )


def _positive(x):
    return x > 0


def _any(x):
    return np.ones_like(x, bool)


def _check_vehicle(vehicle: PlanarVehicle) -> None:
    _check_concrete("vehicle.mass", vehicle.mass, _positive, "> 0 kg")
    _check_concrete("vehicle.yaw_inertia", vehicle.yaw_inertia, _positive, "> 0 kg m^2")
    _check_concrete("vehicle.wheel_inertia", vehicle.wheel_inertia, _positive, "> 0 kg m^2")
    _check_concrete("vehicle.wheelbase", vehicle.wheelbase, _positive, "> 0 m")
    _check_concrete("vehicle.track_width", vehicle.track_width, _positive, "> 0 m")
    inertia_shape = np.shape(vehicle.wheel_inertia)
    if inertia_shape not in ((), (NUM_WHEELS,)):
        raise ValueError(
            f"vehicle.wheel_inertia must be a scalar or of shape (4,); got {inertia_shape}"
        )
    for name in ("mass", "yaw_inertia", "wheelbase", "track_width", "cg_to_front_axle"):
        value = getattr(vehicle, name)
        if value is not None and np.shape(value) != ():
            raise ValueError(f"vehicle.{name} must be a scalar; got shape {np.shape(value)}")
    a = vehicle.cg_to_front_axle
    length = vehicle.wheelbase
    _check_concrete("vehicle.cg_to_front_axle", a, _positive, "> 0 m")
    if a is not None and not (_is_traced(a) or _is_traced(length)):
        if not float(a) < float(length):
            raise ValueError(
                "vehicle.cg_to_front_axle must be below the wheelbase "
                f"({float(length)!r} m); got {float(a)!r}"
            )


def _check_steering(steering) -> None:
    if isinstance(steering, SteeringProfile):
        _check_steering_profile(steering)
    elif not callable(steering):
        if isinstance(steering, (str, bytes)) or steering is None:
            raise TypeError(
                "steering must be a number [rad], a SteeringProfile or a callable; "
                f"got {type(steering).__name__}"
            )
        if np.shape(steering) != ():
            raise ValueError(
                f"a constant steering input must be a scalar [rad]; got shape {np.shape(steering)}"
            )
        _check_concrete("steering", steering, lambda x: np.abs(x) < np.pi / 2, "in (-pi/2, pi/2)")


@_takes_model(positional=6, **_MOVED_TO_OPTIONS)
def simulate_planar(
    vehicle: PlanarVehicle,
    snow: Terrain | ContactModel,
    steering: Float[ArrayLike, ""] | SteeringProfile | Callable,
    torque: Float[ArrayLike, "..."] | TorqueProfile | Callable,
    t1: float,
    dt: float,
    *,
    initial: InitialState = InitialState(),
    ruts: Ruts | None = None,
    stepping: Stepping = Stepping(),
) -> PlanarTrajectory:
    """Simulate a four-wheel vehicle that steers on snow, in the plane; differentiable.

    Integrates the planar rigid-body equations of `PlanarVehicle` (CG position X, Y [m],
    yaw psi [rad], body-frame velocities u, v [m/s], yaw rate r [rad/s], four wheel spins
    omega [rad/s]; see the module documentation of `snowjax/_sim/planar.py`) from rest at
    the origin, heading along +X, to `t1`.  Each wheel's forces come from `solve_wheel`
    with a slip angle: the quasi-static equilibrium (4.14) at the wheel's driving slip
    (eq. 2.6) and slip angle ([`snowjax.planar_wheel_kinematics`][], regularised at
    rest), giving its drawbar pull (2.10), lateral force, resisted torque M_w (2.12) and
    aligning torque, which are rotated by the wheel's steer angle into the body frame.
    Time stepping, accuracy and gradients are those of [`snowjax.simulate_longitudinal`][]
    (implicit Euler steps of `dt` in `diffrax.diffeqsolve`, damped Newton per step, warm
    start of the wheel equilibria, failed steps retried smaller): gradients w.r.t. every
    array leaf of `vehicle`, `snow` (the model's lateral law, distribution and terms
    too), `steering` and `torque` are exact derivatives of the discrete trajectory;
    `jax.grad` uses `stepping.adjoint` (default `diffrax.RecursiveCheckpointAdjoint()`),
    forward mode (`jax.jvp`, `jax.jacfwd`) needs
    `stepping=Stepping(adjoint=diffrax.ForwardMode())` and is much cheaper for a few
    parameters.  Works
    under `jax.vmap` (over terrains, profiles, vehicles).  The entry point is jitted
    (`eqx.filter_jit`): new array values reuse the compiled program; new shapes, `t1`,
    `dt`, static options or a new Python callable compile anew.

    With `steering = 0`, equal torques and the CG midway between the axles, the vehicle
    drives straight and the result is that of `simulate_longitudinal` for a `Vehicle` of
    the same mass and wheels (`solve_wheel`'s any-terrain quadrature, which it takes with
    a slip angle, agrees with the straight-running one within its 1e-7 accuracy; measured
    on the thesis's fresh snow: 5e-12).

    **Arguments:**

    - `vehicle`: `PlanarVehicle` (mass [kg], yaw inertia [kg m^2], wheel inertia
      [kg m^2], wheel, wheelbase [m], track width [m], CG position [m], Ackermann flag).
    - `snow`: the terrain, any `snowjax.Terrain` (SI parameter sets; scalar leaves), or a
      `ContactModel` (scalar leaves): its lateral law (`Lateral(K_y [m], unit weight
      [N/m^3], bulldozing)`, default `Lateral()`, K_y = the terrain's K), stress
      distribution, nodes per panel and force terms; its shear law `JanosiHanamoto()`
      or `NoShear()` (`ThesisSimplified()` has no lateral counterpart and is refused).
    - `steering`: steering input delta [rad], |delta| < pi/2, counter-clockwise positive
      (delta > 0 turns left): a number (constant), a `SteeringProfile` (piecewise linear
      in t) or a callable `steering(t, y) -> ()` of the time [s] and the state vector
      `y = (X, Y, psi, u, v, r, omega_1..4)` (a controller; make it an `eqx.Module` so
      that its parameters are traced and differentiable).
    - `torque`: applied torque per wheel T [N m], positive driving forwards: a number or
      an array of shape (4,) (constant), a `TorqueProfile` with values of shape (k,) or
      (k, 4), or a callable `torque(t, speed, wheel_speed) -> () or (4,)` with speed the
      forward speed u [m/s] and wheel_speed the spins (4,) [rad/s].
    - `t1`: final time [s]; `dt`: time step [s] (`round(t1 / dt)` steps; both static).
    - `initial`: `InitialState(speed [m/s], wheel_speed [rad/s], yaw_rate [rad/s])`:
      u(0), omega(0) (a number or (4,); default `speed / r_w`, free rolling on a
      straight path) and r(0); default at rest.  The lateral speed starts at 0.
    - `ruts`: None (default: every wheel on virgin snow, as before), or `Ruts(k_0,
      a_u)`: the rear wheels run in the front wheels' ruts, each seeing the rut's depth
      times its overlap with the front wheel's path (`Ruts`, `track_offset`: a turning
      vehicle's rear wheels leave the front ruts gradually).  A rear wheel's `sinkage`
      is then measured below the floor of its rut.
    - `stepping`: `Stepping(save_every, adjoint, newton_steps, wheel_max_steps,
      speed_eps)` (see `Stepping`): here `wheel_max_steps` defaults to 5, the wheel
      solver's batch-wide first phase (warm-started equilibria converge in one to three
      steps; about 70 % of the compile time); raise it if `status` shows
      `Status.NOT_CONVERGED`.

    **Returns:** `PlanarTrajectory` with `1 + round(t1 / dt) // stepping.save_every` rows.

    **Cost.**  With a slip angle `solve_wheel` uses its any-terrain quadrature: measured
    3.9 ms per step (four wheels, float64, a 1.5 m/s turn in steps of 0.05 s, on the
    project's shared 2-core CPU machine), 8.5 times `simulate_longitudinal` on the same
    four wheels; compiling takes 15-25 s there.

    **Tested.**  Driving straight it reproduces `simulate_longitudinal` (5e-12 relative);
    in a steady 1.5 m/s turn the rear axle's path radius is within 0.3 % of the Ackermann
    radius L / tan(delta); forward-mode derivatives w.r.t. p_w, steering knots and torque
    match central differences within 1e-7 relative, also from rest.

    **Errors.**  `ValueError` for non-positive or non-finite `t1`, `dt`, `speed_eps`,
    `save_every`, mass, inertias, wheelbase, track width, a CG position outside
    (0, wheelbase), a steering input outside (-pi/2, pi/2) (also a controller's output
    when it does not depend on the state), malformed profiles, non-finite initial speeds
    or snow and wheel parameters outside `solve_wheel`'s range (with concrete values);
    `TypeError` for arguments of the wrong type.  A steering controller whose output
    leaves (-pi/2, pi/2) during the run stops it with an `eqx.error_if` error.  A step
    that cannot be solved even after the retries stops the integration: `result` is set
    (no exception) and the remaining rows hold inf states.
    """
    model = _steered_model(snow, "simulate_planar")
    if not isinstance(vehicle, PlanarVehicle):
        raise TypeError(f"vehicle must be a PlanarVehicle, got {type(vehicle).__name__}")
    n_steps = _check_run(vehicle.wheel, model, t1, dt, initial, stepping)
    _check_vehicle(vehicle)
    _check_steering(steering)
    if isinstance(torque, TorqueProfile):
        _check_profile(torque, NUM_WHEELS)
    leaves = jax.tree_util.tree_leaves((vehicle, model.terrain, model.distribution, model.lateral))
    dtype = jnp.result_type(*leaves, float)
    speed0 = jnp.asarray(initial.speed, dtype)
    wheel_speed0 = initial.wheel_speed
    if wheel_speed0 is None:
        wheel_speed0 = speed0 / (vehicle.wheel.diameter / 2)
    if np.shape(wheel_speed0) not in ((), (NUM_WHEELS,)):
        raise ValueError(
            f"initial.wheel_speed must be a scalar or of shape (4,); got {np.shape(wheel_speed0)}"
        )
    zero = jnp.zeros(1, dtype)
    y0 = jnp.concatenate(
        [
            zero,
            zero,
            zero,
            speed0.reshape(1),
            zero,
            jnp.asarray(initial.yaw_rate, dtype).reshape(1),
            jnp.broadcast_to(jnp.asarray(wheel_speed0, dtype), (NUM_WHEELS,)),
        ]
    )
    if not callable(torque):
        _check_concrete("torque", torque, _any, "[N m]")
        if np.shape(torque) not in ((), (NUM_WHEELS,)):
            raise ValueError(
                f"a constant torque must be a scalar or of shape (4,); got {np.shape(torque)}"
            )
        torque = jnp.asarray(torque, dtype)
    if not callable(steering):
        steering = jnp.asarray(steering, dtype)
    ground = _resolved(ruts, NUM_WHEELS)
    term = _PlanarTerm(
        vehicle=vehicle,
        contact=model,
        steering=steering,
        torque=torque,
        speed_eps=stepping.speed_eps,
        max_wheel_steps=5 if stepping.wheel_max_steps is None else stepping.wheel_max_steps,
        ground=ground,
    )
    return _simulate_planar_jit(
        term, y0, n_steps, float(dt), stepping.save_every, stepping.adjoint, stepping.newton_steps
    )
