"""Train the snowjax rover to reach goals in any direction on snow drawn per episode, with
Brax's PPO on the MuJoCo Playground environment `snowjax.playground.SnowRover`.

    python examples/rover_ppo.py            # the guide's run (see docs/guide/rl.md)
    python examples/rover_ppo.py --quick    # a few seconds of training, to check it runs

The task: goals 8-15 m away in any direction, a new `WongSnow` and goal every episode
(`SnowRover`'s default config: 10 s episodes of 0.1 s control steps, 10 MJX steps of
10 ms each with the snow's forces on the four wheels).  PPO (`brax.training.agents.ppo`)
with a tanh-Gaussian policy, through `snowjax.playground.wrap_for_brax_training`
(automatic full reset).  float32 throughout.

After training, the deterministic policy is run on 64 held-out episodes (snows and goals
drawn from a seed the training never sees) and the success rate (goal reached within the
episode) is printed with the env-steps and the wall time.  Writes
`docs/figures/rl_ppo.png` (or `--out`): Brax's evaluation success rate and return
against env-steps, and the held-out paths.  `--save` writes the run's numbers as JSON
(the guide's table is made from it).
"""

from __future__ import annotations

import argparse
import functools
import json
import pathlib
import time

import jax
import jax.numpy as jnp
import numpy as np

import snowjax.playground as sp

ROOT = pathlib.Path(__file__).resolve().parents[1]

# The guide's run.  Chosen before the run for a 2-core CPU and a budget of 10^6
# env-steps: many small PPO iterations (10,240 env-steps each: 4 unrolls of 20 steps in
# 128 environments, 8 epochs of 8 minibatches) rather than Playground's few huge ones;
# not tuned on the held-out seed.
SETTINGS = dict(
    num_timesteps=1_000_000,
    num_envs=128,
    batch_size=64,
    num_minibatches=8,
    unroll_length=20,
    num_updates_per_batch=8,
    discounting=0.97,
    learning_rate=3e-4,
    entropy_cost=1e-2,
    reward_scaling=1.0,
    num_evals=11,
    num_eval_envs=64,
    deterministic_eval=True,
    max_grad_norm=1.0,
)
QUICK = dict(
    SETTINGS, num_timesteps=20_480, num_envs=64, batch_size=32, num_minibatches=8,
    unroll_length=10, num_evals=2, num_eval_envs=16,
)  # fmt: skip
HELD_OUT_SEED = 12345  # the 64 evaluation episodes (training uses seed and seed + 1 ...)


def recorder(log=print, env_steps=int):
    """(curve, progress): Brax's `progress_fn` appending (env-steps, wall seconds since the
    recorder was made, evaluation success rate, mean return) to `curve` and logging it;
    `env_steps` maps the trainer's step count to env-steps."""
    curve = []
    start = time.perf_counter()

    def progress(steps, metrics):
        row = (
            env_steps(steps),
            time.perf_counter() - start,
            float(metrics["eval/episode_arrived"]),
            float(metrics["eval/episode_reward"]),
        )
        curve.append(row)
        log(f"{row[0]:>9} env-steps  {row[1]:7.0f} s  success {row[2]:.2f}  return {row[3]:.2f}")

    return curve, progress


def train(settings: dict, seed: int = 0, config_overrides: dict | None = None, log=print):
    """PPO on `SnowRover`: returns (env, inference function factory, parameters, learning
    curve rows (env-steps, wall seconds, success rate, mean return), wall time [s])."""
    from brax.training.agents.ppo import networks as ppo_networks
    from brax.training.agents.ppo import train as ppo

    env = sp.SnowRover(config_overrides=config_overrides)
    cfg = env._config
    curve, progress = recorder(log)
    start = time.perf_counter()

    network_factory = functools.partial(
        ppo_networks.make_ppo_networks,
        policy_hidden_layer_sizes=(64, 64),
        value_hidden_layer_sizes=(128, 128),
    )
    make_policy, params, _ = ppo.train(
        environment=env,
        episode_length=cfg.episode_length,
        action_repeat=cfg.action_repeat,
        wrap_env_fn=sp.wrap_for_brax_training,
        normalize_observations=True,
        network_factory=network_factory,
        progress_fn=progress,
        seed=seed,
        **settings,
    )
    return env, make_policy, params, curve, time.perf_counter() - start


def held_out(env, make_policy, params, episodes: int = 64):
    """The deterministic policy on `episodes` held-out episodes: (success per episode,
    chassis paths (steps, episodes, 2) [m], goals (episodes, 2) [m])."""
    policy = make_policy(params, deterministic=True)
    keys = jax.random.split(jax.random.PRNGKey(HELD_OUT_SEED), episodes)
    length = env._config.episode_length

    @jax.jit
    def run(keys):
        state = jax.vmap(env.reset)(keys)
        act_keys = jax.random.split(jax.random.PRNGKey(0), length)

        def body(carry, key):
            state, arrived = carry
            action, _ = policy(state.obs, key)
            state = jax.vmap(env.step)(state, action)
            arrived = arrived | (state.metrics["arrived"] > 0)
            return (state, arrived), state.data.qpos[:, :2]

        start = (state, jnp.zeros(episodes, bool))
        (state, arrived), paths = jax.lax.scan(body, start, act_keys)
        return arrived, paths, state.info["goal"]

    arrived, paths, goals = run(keys)
    return np.asarray(arrived), np.asarray(paths), np.asarray(goals)


def figure(curve, arrived, paths, goals, radius, path):
    """Learning curve (Brax's evaluation episodes) and 16 held-out paths."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    curve = np.asarray(curve)
    fig, (ax0, ax1) = plt.subplots(1, 2, figsize=(11, 4.5))
    ax0.plot(curve[:, 0] / 1e6, curve[:, 2], "o-", label="success rate")
    ax0.set_xlabel("env-steps [millions]")
    ax0.set_ylabel("success rate (Brax's evaluation episodes)")
    ax0.set_ylim(-0.02, 1.02)
    ax0.grid(alpha=0.3)
    twin = ax0.twinx()
    twin.plot(curve[:, 0] / 1e6, curve[:, 3], "s--", color="C1", label="return")
    twin.set_ylabel("mean return [m of progress + bonus]", color="C1")
    ax0.set_title("PPO on SnowRover", fontsize=10)
    for k in range(min(16, len(goals))):
        (line,) = ax1.plot(paths[:, k, 0], paths[:, k, 1], lw=1.2)
        ax1.plot(*goals[k], "*" if arrived[k] else "x", ms=10, color=line.get_color())
        ax1.add_patch(plt.Circle(goals[k], radius, fill=False, ls=":", color=line.get_color()))
    ax1.plot(0, 0, "ko")
    ax1.set_aspect("equal")
    ax1.set_xlim(-17, 17)
    ax1.set_ylim(-17, 17)
    ax1.set_xlabel("x [m]")
    ax1.set_ylabel("y [m]")
    ax1.set_title(f"held-out episodes: {arrived.mean():.0%} of 64 reach the goal (16 shown)")
    ax1.grid(alpha=0.3)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="a tiny budget, to check it runs")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", type=pathlib.Path, default=ROOT / "docs/figures/rl_ppo.png")
    parser.add_argument("--save", type=pathlib.Path, help="write the run's numbers (JSON)")
    args = parser.parse_args(argv)
    settings = QUICK if args.quick else SETTINGS
    env, make_policy, params, curve, wall = train(settings, seed=args.seed)
    arrived, paths, goals = held_out(env, make_policy, params)
    steps = curve[-1][0]
    print(
        f"PPO: {arrived.mean():.0%} of 64 held-out episodes reach the goal after {steps:,} "
        f"env-steps in {wall:.0f} s"
    )
    figure(curve, arrived, paths, goals, env.goal_radius, args.out)
    print(f"wrote {args.out}")
    if args.save:
        record = dict(settings=settings, seed=args.seed, curve=curve, wall_s=wall,
                      held_out_success=float(arrived.mean()), env_steps=steps)  # fmt: skip
        args.save.write_text(json.dumps(record, indent=1))


if __name__ == "__main__":
    main()
