"""The rover as a MuJoCo Playground environment, Brax's trainers on it, and reverse-mode
gradients through a rollout on snow (`snowjax.playground`, extra `snowjax[rl]`).

Real MJX, Playground and Brax on the CPU.  Skipped only when the `rl` extra is absent
(`make test` installs it, and CI fails without it).  Small shapes throughout: the cost is
compiling the rover's step with the snow's forces.
"""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from .extras import require_extra

require_extra("rl", "mujoco_playground", "brax")

from mujoco_playground import MjxEnv, registry  # noqa: E402

import snowjax as sj  # noqa: E402
import snowjax.playground as sp  # noqa: E402
from snowjax import mjx as smjx  # noqa: E402

SNOW = sj.WongSnow.thesis_fresh_snow()


def test_loads_the_playground_way_with_its_config():
    """`registry.load("SnowRover")` builds it with the config and its overrides; the
    environment is a Playground `MjxEnv`; bad settings raise."""
    env = registry.load("SnowRover", config_overrides={"goal.bearing": 1.0, "ctrl_dt": 0.05})
    assert isinstance(env, sp.SnowRover) and isinstance(env, MjxEnv)
    assert env.dt == 0.05 and env.sim_dt == 0.01 and env.n_substeps == 5
    assert env._config.goal.bearing == 1.0
    assert float(env.mj_model.opt.timestep) == 0.01
    assert env.observation_size == 13 and env.action_size == 2
    assert env.xml_path.endswith("mjx_rover.xml")
    default = sp.default_config()
    assert default.episode_length * default.ctrl_dt == pytest.approx(10.0)
    # The snows where the rover can move (the RL guide): SnowRanges' but tan(phi) >= 0.35.
    assert tuple(default.snow.tan_phi) == (0.35, 0.55)
    assert tuple(default.snow.p_w) == smjx.SnowRanges().p_w
    with pytest.raises(ValueError, match="whole number"):
        sp.SnowRover(config_overrides={"ctrl_dt": 0.015})
    with pytest.raises(ValueError, match="goal_distance"):
        sp.SnowRover(config_overrides={"goal.distance": (5.0, 2.0)})
    model, wheels = smjx.load_rover()  # 5 ms
    with pytest.raises(ValueError, match="sim_dt"):
        sp.SnowRover(model=model, wheels=wheels)


def test_brax_wrapper_autoresets_and_vmaps_256_environments_without_nan():
    """Playground's wrapper (full reset) around `SnowRover`: 256 environments for 12 steps
    of 4-step episodes (so three resets each): every leaf finite, every environment done
    three times, each new episode on a new snow and goal, the episode counter reset."""
    env = sp.SnowRover(config_overrides={"ctrl_dt": 0.02, "sim_dt": 0.01})
    wrapped = sp.wrap_for_brax_training(env, episode_length=4)
    n = 256

    @jax.jit
    def run(key):
        state = wrapped.reset(jax.random.split(key, n))

        def body(state, _):
            action = jnp.stack([jnp.clip(5 * state.obs[:, 1], -1, 1), jnp.ones(n)], -1)
            state = wrapped.step(state, action)
            return state, (state.done, state.info["snow"].p_w, state.info["goal"])

        return jax.lax.scan(body, state, None, length=12)

    state, (done, p_w, goal) = run(jax.random.PRNGKey(0))
    for leaf in jax.tree.leaves((state.obs, state.reward, state.data.qpos, state.data.qvel)):
        assert np.all(np.isfinite(np.asarray(leaf)))
    done, p_w, goal = (np.asarray(x) for x in (done, p_w, goal))
    assert np.all(done.sum(0) == 3)
    assert np.all(done[3::4] == 1)
    # The step that finishes an episode returns the next episode's first state (full
    # reset): snow and goal change on those steps only.
    changed = np.diff(p_w, axis=0) != 0
    assert np.array_equal(changed, done[1:] == 1)
    assert np.array_equal((np.diff(goal, axis=0) != 0).any(-1), done[1:] == 1)
    assert np.unique(p_w[-1]).size == n
    # Brax's episode counter: 4 on the finishing step, reset at the next.
    assert np.all(np.asarray(state.info["steps"]) == 4) and np.all(np.asarray(state.done) == 1)


@pytest.mark.slow  # Brax PPO's own compiles (make test-slow)
def test_ppo_on_a_tiny_budget_raises_the_mean_return():
    """Brax's PPO, through `wrap_for_brax_training`, on 16 environments for 6 iterations
    of short episodes (2 s, goals 4-6 m ahead): the deterministic policy's mean return
    over 32 fixed episodes rises above the untrained policy's (a smoke test).  Measured
    (float64): from 0.03 to 0.99 m (seed 1; seed 2: -0.01 to 1.30); after 3 iterations
    seed 1 had not moved (-0.02)."""
    import functools

    from brax.training.agents.ppo import networks as ppo_networks
    from brax.training.agents.ppo import train as ppo

    env = sp.SnowRover(
        config_overrides={"episode_length": 20, "goal.distance": (4.0, 6.0), "goal.bearing": 0.5}
    )
    snapshots = []
    make_policy, params, _ = ppo.train(
        environment=env, num_timesteps=6 * 16 * 4 * 10, episode_length=20, num_envs=16,
        batch_size=16, num_minibatches=4, unroll_length=10, num_updates_per_batch=4,
        learning_rate=3e-3, entropy_cost=1e-3, discounting=0.97, normalize_observations=True,
        wrap_env_fn=sp.wrap_for_brax_training, num_evals=2, num_eval_envs=4, seed=1,
        network_factory=functools.partial(
            ppo_networks.make_ppo_networks, policy_hidden_layer_sizes=(16,),
            value_hidden_layer_sizes=(32,),
        ),
        policy_params_fn=lambda step, make, p: snapshots.append(p),
    )  # fmt: skip
    keys = jax.random.split(jax.random.PRNGKey(7), 32)

    @jax.jit
    def mean_return(p):
        policy = make_policy(p, deterministic=True)
        state = jax.vmap(env.reset)(keys)

        def body(carry, key):
            state, total, live = carry
            action, _ = policy(state.obs, key)
            state = jax.vmap(env.step)(state, action)
            total = total + live * state.reward
            return (state, total, live * (1 - state.done)), None

        start = (state, jnp.zeros(32), jnp.ones(32))
        (_, total, _), _ = jax.lax.scan(body, start, jax.random.split(keys[0], 20))
        return jnp.mean(total)

    before, after = float(mean_return(snapshots[0])), float(mean_return(params))
    assert np.isfinite(before) and after > before + 0.1, (before, after)


def test_the_environment_carries_a_rut_map_through_steps_and_resets():
    """With `ruts.cell_size` set, the state carries a `RutMap`: empty at reset, marked
    where the wheels drove (4 tracks), read back by the rear wheels; a full reset (the
    wrapper) starts the next episode on an empty map."""
    env = sp.SnowRover(
        config_overrides={"ruts.cell_size": 0.1, "ruts.extent": 4.0, "goal.bearing": 0.0}
    )
    wrapped = sp.wrap_for_brax_training(env, episode_length=15)
    state = wrapped.reset(jax.random.split(jax.random.PRNGKey(0), 2))
    assert state.info["rut_map"].depth.shape == (2, 80, 80)
    assert float(jnp.max(state.info["rut_map"].depth)) == 0.0
    step = jax.jit(wrapped.step)
    for _ in range(14):
        state = step(state, jnp.array([[0.0, 0.6], [0.0, 0.6]]))
    depth = np.asarray(state.info["rut_map"].depth)
    assert depth.max() > 0.05  # [m] the wheels' ruts below the original surface
    marked = depth[0] > 0
    assert 0 < marked.mean() < 0.2  # tracks, not the whole map
    # Two tracks across y (the left and right wheels; rear wheels in the front's ruts).
    rows = np.flatnonzero(marked.any(0))
    assert rows.size >= 4 and np.any(np.diff(rows) > 5)
    state = step(state, jnp.array([[0.0, 0.6], [0.0, 0.6]]))  # the 15th: done, reset
    assert float(jnp.max(state.info["rut_map"].depth)) == 0.0


@pytest.mark.slow  # 64 ten-second episodes (make test-slow)
def test_random_controls_do_not_throw_the_rover():
    """Uniformly random steering and throttle, held 0.1 s each, on 64 episodes of
    `SnowRover`'s default task (10 ms MJX steps): the chassis stays on the ground and
    slow.  Before the implicit blocks were kept well posed (`snowjax.mjx.step`), this
    run threw 3 of the 64 rovers at about 25 m/s and 1.7 m high."""
    env = sp.SnowRover()
    n = 64

    @jax.jit
    def run(keys):
        state = jax.vmap(env.reset)(keys)

        def body(state, key):
            action = jax.random.uniform(key, (n, 2), minval=-1.0, maxval=1.0)
            state = jax.vmap(env.step)(state, action)
            return state, (state.metrics["speed"], state.data.qpos[:, 2])

        return jax.lax.scan(body, state, jax.random.split(jax.random.PRNGKey(0), 100))[1]

    speed, height = (np.asarray(x) for x in run(jax.random.split(jax.random.PRNGKey(3), n)))
    assert np.all(np.isfinite(speed)) and speed.max() < 3.0
    assert height.max() < 0.4  # the chassis's rest height is 0.37 m
