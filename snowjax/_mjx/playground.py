# pyright: reportAttributeAccessIssue=false
# (mujoco is a C extension without type stubs: pyright cannot see its attributes.)
"""`SnowRover`: the reach-a-goal task on snow as a MuJoCo Playground environment (a
subclass of `mujoco_playground.MjxEnv` with its `ConfigDict`), registered in
Playground's registry, and `wrap_for_brax_training` for Brax's trainers."""

from __future__ import annotations

import math
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import ArrayLike, Float, PRNGKeyArray
from ml_collections import config_dict
from mujoco_playground import MjxEnv, State, dm_control_suite
from mujoco_playground import wrapper as playground_wrapper

from .._terrain.rut_map import RutMap
from .env import SnowRanges, _RoverTask
from .rover import load_rover, rover_model_path
from .wheels import MjxWheels, mjx, mujoco

__all__ = ["SnowRover", "default_config", "wrap_for_brax_training"]

NAME = "SnowRover"  # its name in Playground's registry

# The rover's snows: `SnowRanges`' defaults with tan(phi) from 0.35.  On weaker snow the
# rover is often immobilised whatever it does (full throttle straight ahead for 5 s: it
# moved less than 2 m on 63 of 152 snows drawn from `SnowRanges()` with tan(phi) < 0.35,
# on 3 of 360 with tan(phi) >= 0.35; the RL guide), and a goal it cannot reach teaches a
# policy nothing.
_MOBILE_TAN_PHI = (0.35, 0.55)


def default_config() -> config_dict.ConfigDict:
    """`SnowRover`'s settings (Playground's convention: `ctrl_dt`, `sim_dt`,
    `episode_length`, `action_repeat` for the trainer, the task's own below).

    - `ctrl_dt` [s]: time per environment step, a whole number of `sim_dt`;
      `sim_dt` [s]: the MJX time step (10 ms; the MJX tests run the rover at 5 ms: at
      10 ms its position after 5 s differed by 0.3-2 %, the RL guide).
    - `episode_length`: control steps per episode (10 s at the defaults);
      `action_repeat`: for `wrap_for_brax_training` (1).
    - `accuracy`: the contact model's (`"simulator"`, within 3e-4 of the load of
      `"reference"`: the performance guide).
    - `solver_unroll`: 0 for MJX's constraint solver as the model sets it (a
      `while_loop`: forward mode only); k >= 1 for k Newton iterations of it unrolled,
      which reverse mode can differentiate (`snowjax.mjx.step`'s `solver_unroll`; set it
      for `jax.grad` through the environment, e.g. Brax's APG).
    - `max_steer` [rad] in (0, 0.6): the steering action's scale.
    - `max_speed` [m/s] > 0: the throttle action commands each wheel's rim speed,
      throttle x `max_speed` (a speed servo per wheel: torque `speed_gain` [N m s/rad]
      times the spin error, within +-`max_torque` [N m]); 0 for a torque throttle
      (throttle x `max_torque`, `SnowRoverEnv`'s).
    - `goal.distance` (low, high) [m], `goal.bearing` [rad] (goals within +-bearing of
      the rover's initial heading; pi: any direction), `goal.radius` [m]: arrival.
    - `snow`: `SnowRanges`' ranges (low, high) of `WongSnow`'s parameters, SI
      (`p_w` [Pa], `z_w` [m], `cohesion` [Pa], `tan_phi` [-], `shear_modulus` [m]):
      `SnowRanges`' defaults except tan(phi) in (0.35, 0.55), where the rover can move
      (below 0.35 it was immobilised on 41 % of the snows tried; the RL guide).
    - `reward_config.scales`: `progress` (per metre towards the goal) and `arrival`
      (once, on reaching it).
    - `ruts`: `cell_size` [m] > 0 carries a `RutMap` in the state (`info["rut_map"]`,
      empty at every reset) over the square +-`extent` [m] about the start, with the
      unloading modulus `k_0` [Pa/m], `a_u` [Pa/m^2] (`snowjax.Rut`): each wheel reads
      the rut ahead of it and marks its own behind it (`snowjax.mjx.step` with a
      `RutMap` for `ruts`); 0 (default) for virgin snow under every wheel.  Memory per
      environment: (2 extent / cell_size)^2 numbers (160 KiB at 0.2 m, 20 m, float32).
    """
    ranges = SnowRanges()
    snow = {k: tuple(getattr(ranges, k)) for k in SnowRanges.__dataclass_fields__}
    snow["tan_phi"] = _MOBILE_TAN_PHI
    return config_dict.create(
        ctrl_dt=0.1,
        sim_dt=0.01,
        episode_length=100,
        action_repeat=1,
        accuracy="simulator",
        solver_unroll=0,
        max_steer=0.5,
        max_torque=1000.0,
        max_speed=5.0,
        speed_gain=100.0,
        goal=config_dict.create(distance=(8.0, 15.0), bearing=math.pi, radius=1.0),
        snow=config_dict.create(**snow),
        reward_config=config_dict.create(scales=config_dict.create(progress=1.0, arrival=5.0)),
        ruts=config_dict.create(cell_size=0.0, extent=20.0, k_0=1e6, a_u=5e6),
    )


class SnowRover(MjxEnv):
    """Drive the shipped rover (`snowjax.mjx.load_rover`) to a goal on snow drawn anew
    every episode: a MuJoCo Playground environment (`reset(rng)`, `step(state,
    action)` on Playground's `State`, pure and `jax.vmap`-able).

    **Task** (`snowjax.mjx.SnowRoverEnv`'s, by default on the snows where the rover can
    move: `default_config`): each episode draws a `WongSnow` uniformly from
    `config.snow`'s ranges and a goal `config.goal.distance`
    away within +-`config.goal.bearing` of the rover's heading (any direction by
    default); the rover starts at rest at the origin facing +x.  Reward per step:
    `scales.progress` times the progress towards the goal [m] plus `scales.arrival` on
    arrival within `config.goal.radius`; the episode ends (`done`) on arrival or when the
    state turns non-finite (zero reward and observation).  The time limit is the
    trainer's (`episode_length`, Brax's `EpisodeWrapper`).

    **Action** (2,) in [-1, 1]: steering (times `max_steer`, Ackermann) and throttle
    (each wheel's commanded rim speed, times `max_speed`; or its torque, times
    `max_torque`, with `max_speed = 0`), held for `ctrl_dt / sim_dt` MJX steps with the
    snow's forces (`snowjax.mjx.step`, the contact model at `config.accuracy`).
    **Observation** (13,): as `SnowRoverEnv`'s.  **Metrics:** `distance` to the goal
    [m], `speed` [m/s], `arrived` (1.0 on the step the goal is reached: summed over an
    episode it is the success).  **Info:** `snow`, `goal` [m], `entry_angle` [rad],
    `slip` [-], `last_steer`, `rng`, and `rut_map` (the `RutMap`, with `config.ruts`).

    **Use:** `env = SnowRover()` or `mujoco_playground.registry.load("SnowRover")`
    (after `import snowjax.playground`); train with Brax through
    `snowjax.playground.wrap_for_brax_training` (Playground's, with a full reset, so
    that each new episode draws a new snow and goal).
    """

    def __init__(
        self,
        config: config_dict.ConfigDict | None = None,
        config_overrides: dict[str, Any] | None = None,
        *,
        model: mujoco.MjModel | None = None,
        wheels: MjxWheels | None = None,
    ):
        """**Arguments:** `config` (default `default_config()`), `config_overrides`
        (flattened keys, e.g. `{"goal.bearing": 1.0}`); `model` and `wheels`: the rover on
        another ground (`load_rover(slope=...)`), whose time step must equal `sim_dt`.

        **Raises:** `ValueError` for settings out of range (`ctrl_dt` not a whole number
        of `sim_dt`, a model whose time step is not `sim_dt`, the task's ranges)."""
        super().__init__(default_config() if config is None else config, config_overrides)
        cfg: Any = self._config  # (ConfigDict attributes are untyped)
        frame_skip = cfg.ctrl_dt / cfg.sim_dt
        if not (cfg.sim_dt > 0 and frame_skip >= 1 and abs(frame_skip - round(frame_skip)) < 1e-9):
            raise ValueError(
                f"ctrl_dt ({cfg.ctrl_dt} s) must be a whole number >= 1 of sim_dt ({cfg.sim_dt} s)"
            )
        if model is None and wheels is None:
            model, wheels = load_rover()
            assert model is not None
            model.opt.timestep = cfg.sim_dt
        elif model is not None and abs(model.opt.timestep - cfg.sim_dt) > 1e-12:
            raise ValueError(
                f"the model's time step ({model.opt.timestep} s) must equal sim_dt ({cfg.sim_dt} s)"
            )
        scales = cfg.reward_config.scales
        self._task = _RoverTask(
            model, wheels, SnowRanges(**{k: tuple(v) for k, v in cfg.snow.items()}),
            frame_skip=round(frame_skip), max_steer=cfg.max_steer, max_torque=cfg.max_torque,
            goal_distance=tuple(cfg.goal.distance), goal_bearing=cfg.goal.bearing,
            goal_radius=cfg.goal.radius, goal_bonus=scales.arrival / scales.progress,
            accuracy=cfg.accuracy, solver_unroll=cfg.solver_unroll or None,
            max_speed=cfg.max_speed or None, speed_gain=cfg.speed_gain,
            rut_map=_empty_map(cfg.ruts),
        )  # fmt: skip
        self._progress = float(scales.progress)

    def reset(self, rng: PRNGKeyArray) -> State:
        """A new episode: snow and goal drawn from `rng`, the rover at rest."""
        data, info, obs, metrics = self._task.new_episode(rng)
        zero = jnp.zeros_like(obs[0])
        return State(data, obs, zero, zero, metrics, info)

    def step(self, state: State, action: Float[ArrayLike, "2"]) -> State:
        """One control step (`ctrl_dt`) under `action`."""
        out = self._task.advance(state.data, state.info, state.metrics, action)
        done = (out.arrived | out.broken).astype(out.reward.dtype)
        metrics = dict(state.metrics, **out.metrics)  # (wrappers add their own keys)
        return State(out.data, out.obs, self._progress * out.reward, done, metrics, out.info)

    @property
    def xml_path(self) -> str:
        return str(rover_model_path())

    @property
    def action_size(self) -> int:
        return 2

    @property
    def observation_size(self) -> int:
        return 13

    @property
    def mj_model(self) -> mujoco.MjModel:
        return self._task.mj_model

    @property
    def mjx_model(self) -> mjx.Model:
        return self._task.model

    @property
    def wheels(self) -> MjxWheels:
        return self._task.wheels

    @property
    def goal_radius(self) -> float:
        """Arrival radius [m]."""
        return self._task.goal_radius


def _empty_map(ruts: Any) -> RutMap | None:
    """The empty `RutMap` of `config.ruts` (None for `cell_size = 0`), in JAX's float."""
    if not ruts.cell_size:
        return None
    e = float(ruts.extent)
    return RutMap.empty((-e, e, -e, e), ruts.cell_size, ruts.k_0, ruts.a_u)


def wrap_for_brax_training(
    env: MjxEnv,
    episode_length: int = 100,
    action_repeat: int = 1,
    randomization_fn: Any = None,
    full_reset: bool = True,
) -> MjxEnv:
    """MuJoCo Playground's `wrap_for_brax_training` (vmap, episode length, automatic
    reset), with `full_reset=True` by default: a finished episode is reset by calling
    `env.reset`, so the next one draws a new snow and goal (Playground's default
    restores a cached first state and keeps each environment's snow for the whole run).
    Pass it to Brax's trainers as `wrap_env_fn`."""
    return playground_wrapper.wrap_for_brax_training(
        env, episode_length, action_repeat, randomization_fn, full_reset=full_reset
    )


def _device_put_replicated(x, devices):
    """`jax.device_put_replicated` (removed in JAX 0.10) as JAX's migration guide gives it
    (https://docs.jax.dev/en/latest/migrate_pmap.html): each leaf stacked once per device
    along a new leading axis, sharded over the devices."""
    mesh = jax.sharding.Mesh(np.array(devices), ("x",))
    sharding = jax.sharding.NamedSharding(mesh, jax.sharding.PartitionSpec("x"))
    return jax.tree.map(lambda y: jax.device_put(jnp.stack([y] * len(devices)), sharding), x)


def _brax_compat() -> None:
    """Brax 0.14.2 (the newest release) calls `jax.device_put_replicated`, which JAX 0.10
    removed (google/brax#671, open): its trainers fail at their first step.  Supply the
    drop-in replacement, only where JAX lacks the function (an older JAX keeps its own)."""
    try:
        jax.device_put_replicated  # noqa: B018 (JAX raises AttributeError once removed)
    except AttributeError:
        jax.device_put_replicated = _device_put_replicated  # pyright: ignore


def _register() -> None:
    """Register `SnowRover` in Playground's registry (its `dm_control_suite` table, whose
    `load` needs no download), so `registry.load("SnowRover")` builds it."""
    dm_control_suite.register_environment(NAME, SnowRover, default_config)


_brax_compat()
_register()
