"""The snowjax rover as a MuJoCo Playground environment: `snowjax.playground` (optional
extra `snowjax[rl]`: `playground`, `brax`, and the `mjx` extra).

Not imported by `import snowjax`.  Importing it registers `SnowRover` in Playground's
registry, so the Playground way works:

    import snowjax.playground  # registers "SnowRover"
    from mujoco_playground import registry

    env = registry.load("SnowRover", config_overrides={"goal.bearing": 1.0})

`SnowRover` is a `mujoco_playground.MjxEnv` with a `ConfigDict` (`default_config()`):
the rover of `snowjax.mjx` driving to a goal on a snow drawn anew every episode (the
snow's forces from `snowjax.mjx.step`).  `wrap_for_brax_training` is Playground's
wrapper (vmap, episode length, automatic reset) with a full reset, so each new episode
draws a new snow and goal; pass it to Brax's trainers (`brax.training.agents.ppo.train`,
`apg.train`) as `wrap_env_fn`.  The RL guide (docs/guide/rl.md) trains it with PPO and
with analytic policy gradients through the snow.
"""

from __future__ import annotations

from ._mjx.playground import SnowRover, default_config, wrap_for_brax_training

__all__ = ["SnowRover", "default_config", "wrap_for_brax_training"]
