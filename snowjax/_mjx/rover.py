# pyright: reportAttributeAccessIssue=false
# (mujoco is a C extension without type stubs: pyright cannot see its attributes.)
"""The shipped rover (`snowjax/data/mjx_rover.xml`), its grounds and its controls."""

from __future__ import annotations

import importlib.resources

import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from .._sim.planar import _ackermann
from .._wheel.geometry import RigidWheel
from .wheels import MjxWheels, mujoco

__all__ = [
    "ROVER_WHEELS",
    "ROVER_WHEELBASE",
    "ROVER_TRACK",
    "rover_model_path",
    "rover_spec",
    "load_rover",
    "rover_controls",
]

ROVER_WHEELS = ("wheel_fl", "wheel_fr", "wheel_rl", "wheel_rr")
ROVER_WHEELBASE = 2.6  # [m]
ROVER_TRACK = 1.6  # [m]
_RADIUS = 0.368  # [m], the thesis tyre's D / 2


def rover_model_path() -> str:
    """Path of the shipped MJCF model `snowjax/data/mjx_rover.xml`: a 4-wheel rover with
    a free-floating chassis, sprung wheels and Ackermann-steered front wheels (1,427.6 kg
    in all; the thesis tyre, D = 0.736 m, b = 0.235 m, I = 1.5 kg m^2; 3,500 N per wheel
    at rest; wheelbase 2.6 m, track 1.6 m; actuators `steer_fl`, `steer_fr` (position
    servos, ctrl = steer angle [rad]) and `motor_fl/fr/rl/rr` (ctrl = torque [N m])) on a
    flat floor, g = 9.80665 m/s^2."""
    return str(importlib.resources.files("snowjax") / "data" / "mjx_rover.xml")


def rover_spec(
    slope: float = 0.0,
    heights: Float[ArrayLike, "rows cols"] | None = None,
    extent: tuple[float, float] = (20.0, 20.0),
) -> mujoco.MjSpec:
    """The shipped rover as a `mujoco.MjSpec` (edit it, then `.compile()`), on its ground:

    - default: the flat floor;
    - `slope` [rad], |slope| < 0.6: the floor inclined about the world's y axis, rising
      towards +x (a climb for the rover, which faces +x); the rover starts on it, level
      with it;
    - `heights` [m]: a MuJoCo height field instead of the floor, elevations >= 0 on a
      regular grid of shape (rows, cols) (rows along y, cols along x) centred on the
      origin, spanning `extent` = (length along x, width along y) [m]; the rover starts
      with its wheels 2 cm above the highest of the four ground points under them.

    **Raises:** `ValueError` for a slope outside (-0.6, 0.6) rad, both a slope and
    heights, or heights that are not a finite, non-negative 2-D grid of at least 2 x 2.
    """
    slope = float(slope)
    if not abs(slope) < 0.6:
        raise ValueError(f"slope must be in (-0.6, 0.6) rad; got {slope!r}")
    spec = mujoco.MjSpec.from_file(rover_model_path())
    ground = spec.geom("ground")
    chassis = spec.body("chassis")
    if heights is not None:
        if slope != 0.0:
            raise ValueError("give a slope or heights, not both")
        h = np.asarray(heights, float)
        if h.ndim != 2 or min(h.shape) < 2 or not np.all(np.isfinite(h) & (h >= 0)):
            raise ValueError("heights must be a finite, non-negative grid of shape (rows, cols)")
        length, width = (float(e) for e in extent)
        top = max(float(h.max()), 1e-6)
        spec.add_hfield(
            name="terrain",
            size=[length / 2, width / 2, top, 0.1],
            nrow=h.shape[0],
            ncol=h.shape[1],
            userdata=(h / top).ravel().tolist(),
        )
        ground.type = mujoco.mjtGeom.mjGEOM_HFIELD
        ground.hfieldname = "terrain"
        under = [
            _height_at(h, length, width, x, y)
            for x in (-ROVER_WHEELBASE / 2, ROVER_WHEELBASE / 2)
            for y in (-ROVER_TRACK / 2, ROVER_TRACK / 2)
        ]
        chassis.pos = [0.0, 0.0, _RADIUS + max(under) + 0.02]
    elif slope != 0.0:
        # A rotation by -slope about y turns the floor's normal to (-sin slope, 0,
        # cos slope): the floor rises towards +x.  The chassis turns with it.
        half = -slope / 2
        ground.quat = [np.cos(half), 0.0, np.sin(half), 0.0]
        chassis.quat = [np.cos(half), 0.0, np.sin(half), 0.0]
        chassis.pos = [-_RADIUS * np.sin(slope), 0.0, _RADIUS * np.cos(slope)]
    return spec


def _height_at(h, length, width, x, y):
    """Bilinear elevation [m] of the grid h at (x, y) [m] (MuJoCo's layout)."""
    rows, cols = h.shape
    c = np.clip((x / length + 0.5) * (cols - 1), 0, cols - 1)
    r = np.clip((y / width + 0.5) * (rows - 1), 0, rows - 1)
    c0, r0 = min(int(c), cols - 2), min(int(r), rows - 2)
    fc, fr = c - c0, r - r0
    top = h[r0, c0] * (1 - fc) + h[r0, c0 + 1] * fc
    bottom = h[r0 + 1, c0] * (1 - fc) + h[r0 + 1, c0 + 1] * fc
    return float(top * (1 - fr) + bottom * fr)


def load_rover(
    slope: float = 0.0,
    heights: Float[ArrayLike, "rows cols"] | None = None,
    extent: tuple[float, float] = (20.0, 20.0),
    wheel: RigidWheel | None = None,
) -> tuple[mujoco.MjModel, MjxWheels]:
    """The shipped rover on its ground (`rover_spec`): `(mujoco.MjModel, MjxWheels)` with
    the thesis tyre (or `wheel`, of the same diameter) on its four wheels.
    `mjx.put_model(model)` gives the MJX model."""
    model = rover_spec(slope, heights, extent).compile()
    return model, MjxWheels.from_model(model, ROVER_WHEELS, wheel)


def rover_controls(
    steering: Float[ArrayLike, "..."], torque: Float[ArrayLike, "... 4"]
) -> Float[Array, "... 6"]:
    """The shipped rover's `ctrl` for a steering input and wheel torques.

    - `steering`: delta [rad], the bicycle-model steer angle, counter-clockwise positive
      (left); the front wheels get the Ackermann angles of `snowjax.PlanarVehicle`
      (`steer_angles`, wheelbase 2.6 m, track 1.6 m), limited to +-0.6 rad.
    - `torque`: drive torque per wheel [N m] (fl, fr, rl, rr), shape (..., 4) or
      broadcastable; positive drives forwards.

    **Returns:** ctrl of shape (..., 6): steer_fl, steer_fr [rad], motor_fl, motor_fr,
    motor_rl, motor_rr [N m].
    """
    dtype = jnp.result_type(steering, torque, float)
    delta = jnp.asarray(steering, dtype)
    torque = jnp.asarray(torque, dtype)
    left, right = _ackermann(delta, ROVER_WHEELBASE, ROVER_TRACK)
    shape = jnp.broadcast_shapes(delta.shape, torque.shape[:-1] if torque.ndim else ())
    steer = jnp.stack([jnp.broadcast_to(left, shape), jnp.broadcast_to(right, shape)], -1)
    torque = jnp.broadcast_to(torque, (*shape, 4))
    return jnp.concatenate([steer, torque], -1)
