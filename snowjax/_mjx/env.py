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
from jaxtyping import Array, ArrayLike, Float, PRNGKeyArray

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
    goal [m], `speed` [m/s]), `info` (dict: `snow` (the episode's `WongSnow`), `goal`
    (x, y) [m], `entry_angle` (the wheels' warm start [rad]), `step` (int), `truncation`
    (1.0 when the episode ended on time), `rng`)."""

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
    pytree).

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
    ):
        """**Arguments:** `ranges`: `SnowRanges` (default `SnowRanges()`); the task's
        settings above (`episode_length`, `frame_skip`: ints >= 1; `max_steer` in
        (0, 0.6) rad; `max_torque` > 0 N m; `goal_distance` (low, high) [m], 0 < low <=
        high; `goal_bearing` [rad]; `goal_radius` [m], `goal_bonus` [-]); `model` and
        `wheels`: the rover on another ground (`load_rover(slope=...)` or
        `load_rover(heights=...)`), default the flat floor; `accuracy`: the contact
        model's (`ContactModel(snow, accuracy=...)`: `"reference"` or `"simulator"`, fewer
        quadrature nodes; the performance guide has its error and speed).

        **Raises:** `ValueError` for settings out of range."""
        if int(episode_length) < 1 or int(frame_skip) < 1:
            raise ValueError("episode_length and frame_skip must be integers >= 1")
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
        self.mj_model = model
        self.model = mjx.put_model(model)
        self.wheels = wheels
        self.ranges = SnowRanges() if ranges is None else ranges
        self.episode_length = int(episode_length)
        self.frame_skip = int(frame_skip)
        self.max_steer = float(max_steer)
        self.max_torque = float(max_torque)
        self.goal_distance = (float(goal_distance[0]), float(goal_distance[1]))
        self.goal_bearing = float(goal_bearing)
        self.goal_radius = float(goal_radius)
        self.goal_bonus = float(goal_bonus)
        self.accuracy = _accuracy_option(accuracy)

    @property
    def observation_size(self) -> int:
        return 13

    @property
    def action_size(self) -> int:
        return 2

    @property
    def dt(self) -> float:
        """Time per environment step [s]."""
        return self.frame_skip * float(self.mj_model.opt.timestep)

    def reset(self, rng: PRNGKeyArray) -> State:
        """A new episode: snow and goal drawn from `rng`, the rover at rest."""
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
            "step": jnp.zeros((), jnp.int32),
            "truncation": jnp.zeros((), dtype),
            "rng": rng,
            "last_steer": jnp.zeros((), dtype),
            "slip": jnp.zeros((len(ROVER_WHEELS),), dtype),
        }
        zero = jnp.zeros((), dtype)
        metrics = {"distance": distance, "speed": zero}
        obs = self._observe(data, info)
        return State(data, obs, zero, zero, metrics, info)

    def step(self, state: State, action: Float[ArrayLike, "2"]) -> State:
        """One environment step: `frame_skip` MJX steps with the snow's forces under the
        action (held).  A finished instance (`done` = 1) is left unchanged."""
        info = state.info
        dtype = state.reward.dtype
        # A NaN action steers straight and applies no torque (inf is clipped to +-1):
        # NaN passes `jnp.clip` and would poison the rover's state for good.
        action = jnp.clip(jnp.nan_to_num(jnp.asarray(action, dtype), nan=0.0), -1.0, 1.0)
        steer = self.max_steer * action[0]
        ctrl = rover_controls(steer, jnp.full((4,), self.max_torque) * action[1])

        def frame(carry, _):
            data, theta = carry
            snow = ContactModel(info["snow"], accuracy=self.accuracy)
            data, out = snow_step(self.model, data.replace(ctrl=ctrl), self.wheels, snow, theta)
            theta = jax.lax.stop_gradient(
                jnp.where(jnp.isfinite(out.entry_angle), out.entry_angle, theta)
            )
            return (data, theta), out.slip

        (data, theta), slips = jax.lax.scan(
            frame, (state.data, info["entry_angle"]), None, length=self.frame_skip
        )
        goal = info["goal"]
        distance = jnp.linalg.norm(data.qpos[:2] - goal)
        arrived = distance < self.goal_radius
        count = info["step"] + 1
        timeout = count >= self.episode_length
        reward = state.metrics["distance"] - distance + self.goal_bonus * arrived
        new_info = dict(
            info, entry_angle=theta, step=count, last_steer=action[0], slip=slips[-1],
            truncation=jnp.where(timeout & ~arrived, 1.0, 0.0).astype(dtype),
        )  # fmt: skip
        speed = jnp.linalg.norm(data.qvel[:2])
        obs = self._observe(data, new_info)
        # A state that turned non-finite (e.g. the physics diverged) ends the episode, as
        # MuJoCo Playground's environments do, with a finite observation and no reward.
        broken = ~(
            jnp.all(jnp.isfinite(data.qpos))
            & jnp.all(jnp.isfinite(data.qvel))
            & jnp.all(jnp.isfinite(obs))
            & jnp.isfinite(reward)
        )
        new = State(
            data,
            jnp.where(broken, 0.0, obs),
            jnp.where(broken, 0.0, reward).astype(dtype),
            (arrived | timeout | broken).astype(dtype),
            {"distance": jnp.where(broken, state.metrics["distance"], distance), "speed": speed},
            new_info,
        )
        # A finished instance keeps its state (and earns nothing).
        finished = state.done > 0
        kept = eqx.tree_at(lambda s: s.reward, state, jnp.zeros_like(state.reward))
        return jax.tree.map(lambda a, b: jnp.where(finished, a, b), kept, new)

    def _observe(self, data, info):
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
