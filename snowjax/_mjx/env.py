# pyright: reportAttributeAccessIssue=false
# (mujoco is a C extension without type stubs: pyright cannot see its attributes.)
"""`SnowRoverEnv`: reach a goal on randomised snow with the shipped rover, a functional
environment in the shape of MuJoCo Playground's / Brax's (`reset(rng) -> State`,
`step(state, action) -> State`, pure, `jax.vmap`-able over thousands of instances)."""

from __future__ import annotations

import dataclasses
from typing import Any

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float, PRNGKeyArray

from .._terrain.rut_map import RutMap
from .._terrain.wong import WongSnow
from .._wheel.model import ContactModel, _accuracy_option
from .rover import ROVER_WHEELS, load_rover, rover_controls
from .step import step as snow_step
from .wheels import MjxWheels, mjx, mujoco

__all__ = ["SnowRanges", "State", "SnowRoverEnv"]


class SnowRanges(eqx.Module):
    """Domain randomisation: each episode draws a `WongSnow` with every parameter
    uniform in its (low, high) range (SI).  Defaults: around the thesis's fresh snow
    (Table 4.1), from half to twice as strong.

    - `p_w`: pressure at the bottom of the compressible layer [Pa].
    - `z_w`: depth of the compressible layer [m].
    - `cohesion` c [Pa]; `tan_phi`: tan of the friction angle [-];
      `shear_modulus` K [m].
    """

    p_w: tuple[float, float] = eqx.field(static=True, default=(60e3, 240e3))
    z_w: tuple[float, float] = eqx.field(static=True, default=(0.15, 0.35))
    cohesion: tuple[float, float] = eqx.field(static=True, default=(0.3e3, 1.2e3))
    tan_phi: tuple[float, float] = eqx.field(static=True, default=(0.25, 0.55))
    shear_modulus: tuple[float, float] = eqx.field(static=True, default=(0.01, 0.03))

    def sample(self, key: PRNGKeyArray, dtype: Any = float) -> WongSnow:
        """One snow drawn uniformly from the ranges."""
        names = ("p_w", "z_w", "cohesion", "tan_phi", "shear_modulus")
        u = jax.random.uniform(key, (len(names),), dtype)
        values = [lo + (hi - lo) * x for (lo, hi), x in zip((getattr(self, k) for k in names), u)]
        return WongSnow(*values)


class State(eqx.Module):
    """One environment's state (MuJoCo Playground's `State`): `data` (`mjx.Data`), `obs`
    (observation, shape (observation_size,)), `reward` [-], `done` (1.0 once the goal is
    reached or the episode's time is up), `metrics` (dict of scalars: `distance` to the
    goal [m], `speed` [m/s], `arrived` (1.0 on the step the goal is reached)), `info`
    (dict: `snow` (the episode's `WongSnow`), `goal` (x, y) [m], `entry_angle` (the
    wheels' warm start [rad]), `step` (int), `truncation` (1.0 when the episode ended on
    time), `rng`)."""

    data: mjx.Data
    obs: Float[Array, " obs"]
    reward: Float[Array, ""]
    done: Float[Array, ""]
    metrics: dict[str, Array]
    info: dict[str, Any]

    def replace(self, **changes: Any) -> "State":
        """A copy with the given fields replaced (`State.replace(done=...)`, as Brax's
        and MuJoCo Playground's wrappers call it on their states)."""
        return dataclasses.replace(self, **changes)


class SnowRoverEnv:
    """Drive the shipped rover (`load_rover`) to a goal on snow whose parameters change
    every episode.

    **Task.**  Each episode starts the rover at rest at the origin, facing +x, on a snow
    drawn from `ranges`, with a goal drawn at a distance in `goal_distance` [m] and a
    bearing within +-`goal_bearing` [rad] of its heading.  The reward per step is the
    progress towards the goal [m] (previous distance minus new distance), plus
    `goal_bonus` on arrival within `goal_radius` [m]; the episode ends on arrival
    (`done`) or after `episode_length` steps (`done` and `info["truncation"]`).

    **Action** (2,), in [-1, 1] (clipped; NaN counts as 0): steering (times
    `max_steer` [rad], Ackermann through `rover_controls`) and throttle (times
    `max_torque` [N m] on every wheel).  Each action is held for `frame_skip` MJX steps
    of 5 ms.  A step whose state turns non-finite ends the episode (`done` = 1, zero
    reward, zero observation), as MuJoCo Playground's environments do.

    **Observation** (13,): the goal in the chassis frame (x, y [m] / 10), the distance
    [m] / 10, the chassis's velocity (forward, left [m/s]) and yaw rate [rad/s], its
    roll and pitch [rad], the four wheels' slips [-] (snowjax's, so the snow's
    resistance is observable through them), and the last steering action.

    **Use:** `env = SnowRoverEnv()`; `state = jax.vmap(env.reset)(keys)`;
    `state = jax.vmap(env.step)(state, actions)`.  There is no automatic reset: a
    finished instance stays put (zero reward) until you `reset` it (or wrap the
    environment in Brax's `AutoResetWrapper`, which needs only `reset`/`step`/`State`
    and `State.replace`).
    Everything is jit-, vmap- and jvp-compatible (`jax.jit(env.step)` works: like
    Playground's environments this is a plain Python class holding the MJX model, not a
    pytree); with `solver_unroll` set, `jax.grad` too.  For Brax's trainers and
    Playground's registry, use `snowjax.playground.SnowRover` (the same task).

    **Attributes:** the settings below, `mj_model` (`mujoco.MjModel`), `model`
    (`mjx.Model`), `wheels` (`MjxWheels`), `ranges` (`SnowRanges`).
    """

    def __init__(
        self,
        ranges: SnowRanges | None = None,
        *,
        episode_length: int = 200,
        frame_skip: int = 4,
        max_steer: float = 0.5,
        max_torque: float = 1000.0,
        goal_distance: tuple[float, float] = (8.0, 15.0),
        goal_bearing: float = 1.0,
        goal_radius: float = 1.0,
        goal_bonus: float = 5.0,
        model: mujoco.MjModel | None = None,
        wheels: MjxWheels | None = None,
        accuracy: str = "reference",
        solver_unroll: int | None = None,
    ):
        """**Arguments:** `ranges`: `SnowRanges` (default `SnowRanges()`); the task's
        settings above (`episode_length`, `frame_skip`: ints >= 1; `max_steer` in
        (0, 0.6) rad; `max_torque` > 0 N m; `goal_distance` (low, high) [m], 0 < low <=
        high; `goal_bearing` [rad]; `goal_radius` [m], `goal_bonus` [-]); `model` and
        `wheels`: the rover on another ground (`load_rover(slope=...)` or
        `load_rover(heights=...)`), default the flat floor; `accuracy`: the contact
        model's (`ContactModel(snow, accuracy=...)`: `"reference"` or `"simulator"`, fewer
        quadrature nodes; the performance guide has its error and speed);
        `solver_unroll`: None, or k >= 1 to unroll MJX's constraint solver into k Newton
        iterations so that reverse mode (`jax.grad`) works (`snowjax.mjx.step`).

        **Raises:** `ValueError` for settings out of range."""
        if int(episode_length) < 1:
            raise ValueError("episode_length must be an integer >= 1")
        self.episode_length = int(episode_length)
        self._task = _RoverTask(
            model, wheels, SnowRanges() if ranges is None else ranges, frame_skip=frame_skip,
            max_steer=max_steer, max_torque=max_torque, goal_distance=goal_distance,
            goal_bearing=goal_bearing, goal_radius=goal_radius, goal_bonus=goal_bonus,
            accuracy=accuracy, solver_unroll=solver_unroll,
        )  # fmt: skip

    def __getattr__(self, name: str) -> Any:
        # The task's settings and models (`model`, `wheels`, `ranges`, `frame_skip`, ...).
        if name == "_task":  # not yet set (copying, unpickling): no recursion
            raise AttributeError(name)
        return getattr(self._task, name)

    @property
    def observation_size(self) -> int:
        return 13

    @property
    def action_size(self) -> int:
        return 2

    @property
    def dt(self) -> float:
        """Time per environment step [s]."""
        return self._task.dt

    def reset(self, rng: PRNGKeyArray) -> State:
        """A new episode: snow and goal drawn from `rng`, the rover at rest."""
        data, info, obs, metrics = self._task.new_episode(rng)
        info = dict(info, step=jnp.zeros((), jnp.int32), truncation=jnp.zeros_like(obs[0]))
        zero = jnp.zeros_like(obs[0])
        return State(data, obs, zero, zero, metrics, info)

    def step(self, state: State, action: Float[ArrayLike, "2"]) -> State:
        """One environment step: `frame_skip` MJX steps with the snow's forces under the
        action (held).  A finished instance (`done` = 1) is left unchanged."""
        out = self._task.advance(state.data, state.info, state.metrics, action)
        count = state.info["step"] + 1
        timeout = count >= self.episode_length
        info = dict(
            out.info, step=count,
            truncation=jnp.where(timeout & ~out.arrived, 1.0, 0.0).astype(out.reward.dtype),
        )  # fmt: skip
        done = (out.arrived | timeout | out.broken).astype(out.reward.dtype)
        new = State(out.data, out.obs, out.reward, done, out.metrics, info)
        # A finished instance keeps its state (and earns nothing).
        finished = state.done > 0
        kept = eqx.tree_at(lambda s: s.reward, state, jnp.zeros_like(state.reward))
        return jax.tree.map(lambda a, b: jnp.where(finished, a, b), kept, new)


class _Advance(eqx.Module):
    """What `_RoverTask.advance` returns: the next `data`, `info`, `obs`, `reward` [m],
    `metrics`, and flags `arrived` (within the goal's radius), `broken` (the state turned
    non-finite: zero observation and reward)."""

    data: Any
    info: dict[str, Any]
    obs: Array
    reward: Array
    metrics: dict[str, Array]
    arrived: Array
    broken: Array


class _RoverTask:
    """The reach-a-goal task on the shipped rover, shared by `SnowRoverEnv` and
    `snowjax.playground.SnowRover`: drawing an episode (snow, goal), driving the rover
    for one control step, the observation and the reward.  Its attributes are the
    settings `SnowRoverEnv` documents; it checks them."""

    def __init__(
        self, model, wheels, ranges: SnowRanges, *, frame_skip, max_steer, max_torque,
        goal_distance, goal_bearing, goal_radius, goal_bonus, accuracy, solver_unroll=None,
        max_speed=None, speed_gain=100.0, rut_map=None,
    ):  # fmt: skip
        if int(frame_skip) < 1:
            raise ValueError("frame_skip must be an integer >= 1")
        if not 0 < max_steer < 0.6 or not max_torque > 0:
            raise ValueError("max_steer must be in (0, 0.6) rad and max_torque > 0 N m")
        if not 0 < goal_distance[0] <= goal_distance[1] or not goal_radius > 0:
            raise ValueError("goal_distance must be 0 < low <= high [m], goal_radius > 0 m")
        if (model is None) != (wheels is None):
            raise ValueError("give both model and wheels (load_rover), or neither")
        if model is None or wheels is None:
            model, wheels = load_rover()
        assert model is not None
        if len(wheels.body_ids) != len(ROVER_WHEELS) or model.nu != 6:
            raise ValueError("model must be the shipped rover (load_rover), on any ground")
        if not isinstance(ranges, SnowRanges):
            raise TypeError(f"ranges must be a SnowRanges, got {type(ranges).__name__}")
        self.mj_model = model
        self.model = mjx.put_model(model)
        self.wheels = wheels
        self.ranges = ranges
        self.frame_skip = int(frame_skip)
        self.max_steer = float(max_steer)
        self.max_torque = float(max_torque)
        self.goal_distance = (float(goal_distance[0]), float(goal_distance[1]))
        self.goal_bearing = float(goal_bearing)
        self.goal_radius = float(goal_radius)
        self.goal_bonus = float(goal_bonus)
        self.accuracy = _accuracy_option(accuracy)
        self.solver_unroll = None if solver_unroll is None else int(solver_unroll)
        # Throttle as a wheel-speed command (a speed servo per wheel) or as torque.
        if max_speed is not None and not (max_speed > 0 and speed_gain > 0):
            raise ValueError("max_speed [m/s] and speed_gain [N m s/rad] must be > 0")
        self.max_speed = None if max_speed is None else float(max_speed)
        self.speed_gain = float(speed_gain)
        # Ruts in the rollout: each episode starts on this (empty) map, carried in `info`.
        if rut_map is not None and not isinstance(rut_map, RutMap):
            raise TypeError(f"rut_map must be None or a RutMap, got {type(rut_map).__name__}")
        self.rut_map = rut_map

    @property
    def dt(self) -> float:
        """Time per control step [s]."""
        return self.frame_skip * float(self.mj_model.opt.timestep)

    def new_episode(self, rng):
        """(data, info, obs, metrics) of a new episode: snow and goal drawn from `rng`,
        the rover at rest at the origin facing +x."""
        rng, snow_key, goal_key = jax.random.split(rng, 3)
        dtype = self.model.opt.gravity.dtype
        snow = self.ranges.sample(snow_key, dtype)
        u = jax.random.uniform(goal_key, (2,), dtype)
        lo, hi = self.goal_distance
        distance = lo + (hi - lo) * u[0]
        bearing = self.goal_bearing * (2 * u[1] - 1)
        goal = distance * jnp.stack([jnp.cos(bearing), jnp.sin(bearing)])
        data = mjx.make_data(self.model)
        info = {
            "snow": snow,
            "goal": goal,
            "entry_angle": jnp.full((len(ROVER_WHEELS),), jnp.nan, dtype),
            "rng": rng,
            "last_steer": jnp.zeros((), dtype),
            "slip": jnp.zeros((len(ROVER_WHEELS),), dtype),
        }
        if self.rut_map is not None:
            info["rut_map"] = self.rut_map
        zero = jnp.zeros((), dtype)
        metrics = {"distance": distance, "speed": zero, "arrived": zero}
        return data, info, self.observe(data, info), metrics

    def advance(self, data, info, metrics, action) -> _Advance:
        """`frame_skip` MJX steps with the snow's forces under `action` (held), then the
        observation, the reward (progress towards the goal [m], plus `goal_bonus` on
        arrival) and the metrics.  A NaN action steers straight and applies no torque."""
        dtype = data.qpos.dtype
        # NaN passes `jnp.clip` and would poison the rover's state for good.
        action = jnp.clip(jnp.nan_to_num(jnp.asarray(action, dtype), nan=0.0), -1.0, 1.0)
        steer = self.max_steer * action[0]
        snow = ContactModel(info["snow"], accuracy=self.accuracy)

        def frame(carry, _):
            data, theta, grid = carry
            data, out, *grid = snow_step(
                self.model, data.replace(ctrl=self._controls(data, steer, action[1])),
                self.wheels, snow, theta, ruts=grid, solver_unroll=self.solver_unroll,
            )  # fmt: skip
            theta = jax.lax.stop_gradient(
                jnp.where(jnp.isfinite(out.entry_angle), out.entry_angle, theta)
            )
            return (data, theta, grid[0] if grid else None), out.slip

        start = (data, info["entry_angle"], info.get("rut_map"))
        (data, theta, grid), slips = jax.lax.scan(frame, start, None, length=self.frame_skip)
        if grid is not None:
            info = dict(info, rut_map=grid)
        distance = jnp.linalg.norm(data.qpos[:2] - info["goal"])
        arrived = distance < self.goal_radius
        reward = metrics["distance"] - distance + self.goal_bonus * arrived
        info = dict(info, entry_angle=theta, last_steer=action[0], slip=slips[-1])
        obs = self.observe(data, info)
        # A state that turned non-finite (e.g. the physics diverged) ends the episode, as
        # MuJoCo Playground's environments do, with a finite observation and no reward.
        broken = ~(
            jnp.all(jnp.isfinite(data.qpos))
            & jnp.all(jnp.isfinite(data.qvel))
            & jnp.all(jnp.isfinite(obs))
            & jnp.isfinite(reward)
        )
        metrics = {
            "distance": jnp.where(broken, metrics["distance"], distance),
            "speed": jnp.linalg.norm(data.qvel[:2]),
            "arrived": arrived.astype(dtype),
        }
        return _Advance(
            data, info, jnp.where(broken, 0.0, obs), jnp.where(broken, 0.0, reward).astype(dtype),
            metrics, arrived, broken,
        )  # fmt: skip

    def _controls(self, data, steer, throttle):
        """The rover's ctrl: steering, and each wheel's torque: `throttle` times
        `max_torque`, or with `max_speed` a speed servo, `speed_gain` times (`throttle`
        `max_speed` / r - the wheel's spin) within +-`max_torque`."""
        if self.max_speed is None:
            torque = jnp.full((4,), self.max_torque) * throttle
        else:
            radius = self.wheels.wheel.diameter / 2
            spin = data.qvel[np.asarray(self.wheels.dof_ids)]
            error = throttle * self.max_speed / radius - spin
            torque = jnp.clip(self.speed_gain * error, -self.max_torque, self.max_torque)
        return rover_controls(steer, torque)

    def observe(self, data, info):
        """The 13 observations (`SnowRoverEnv`'s docstring)."""
        quat = data.qpos[3:7]
        rot = _quat_to_mat(quat)
        yaw = jnp.arctan2(rot[1, 0], rot[0, 0])
        c, s = jnp.cos(yaw), jnp.sin(yaw)
        rel = info["goal"] - data.qpos[:2]
        goal_body = jnp.stack([c * rel[0] + s * rel[1], -s * rel[0] + c * rel[1]])
        vel = data.qvel[:2]
        vel_body = jnp.stack([c * vel[0] + s * vel[1], -s * vel[0] + c * vel[1]])
        yaw_rate = (rot @ data.qvel[3:6])[2]
        roll = jnp.arctan2(rot[2, 1], rot[2, 2])
        pitch = -jnp.arcsin(jnp.clip(rot[2, 0], -1.0, 1.0))
        return jnp.concatenate(
            [
                goal_body / 10.0,
                jnp.linalg.norm(rel)[None] / 10.0,
                vel_body,
                jnp.stack([yaw_rate, roll, pitch]),
                info["slip"],
                info["last_steer"][None],
            ]
        )


def _quat_to_mat(q):
    """Rotation matrix of a unit quaternion (w, x, y, z)."""
    w, x, y, z = q[0], q[1], q[2], q[3]
    return jnp.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )
