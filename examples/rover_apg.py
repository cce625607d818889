"""Train the snowjax rover on `rover_ppo.py`'s task by analytic policy gradients:
back-propagation through time through the environment itself (MJX's dynamics and the
snow's wheel forces with their implicit equilibria), `horizon` control steps at a time.

    python examples/rover_apg.py --ppo-json ppo.json   # the guide's run; compares with PPO
    python examples/rover_apg.py --quick               # a tiny budget, to check it runs

The environment is `snowjax.playground.SnowRover` with `solver_unroll=2` (MJX's
constraint solver as two unrolled Newton iterations, which reverse mode can
differentiate; its default `while_loop` cannot) and the default config otherwise,
through `snowjax.playground.wrap_for_brax_training` (automatic full reset).  The policy
is deterministic (an MLP of two 64-unit layers, tanh outputs); each update runs
`num_envs` environments for `horizon` control steps from where the last update left
them and follows the gradient of minus their mean return (Adam, global norm clipped),
the state's gradient cut at the start of each window (as Brax's APG does).  An update
whose gradient is not finite is skipped and counted: through a randomly steered rover
the reverse-mode derivative can overflow float32 (Brax's APG, which has no such guard,
turned its parameters to NaN after 12 updates on this task).

The same 64 held-out episodes as `rover_ppo.py` give the success rate.  Writes
`docs/figures/rl_apg_vs_ppo.png` (or `--out`): the evaluation success rate of both
methods against env-steps (PPO's from `--ppo-json`, written by `rover_ppo.py --save`).
"""

from __future__ import annotations

import argparse
import json
import pathlib
import sys
import time

import jax
import jax.numpy as jnp
import numpy as np
import optax

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import rover_ppo  # noqa: E402  (the held-out evaluation and the task)

import snowjax.playground as sp  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parents[1]

# Chosen before the run for a 2-core CPU (short windows: the dense progress reward needs
# no long horizon, and the derivative grows with it); not tuned on the held-out seed.
SETTINGS = dict(
    updates=300, horizon=5, num_envs=64, learning_rate=1e-3, max_gradient_norm=1.0,
    num_evals=11, num_eval_envs=64,
)  # fmt: skip
QUICK = dict(SETTINGS, updates=4, horizon=3, num_envs=8, num_evals=2, num_eval_envs=8)
EVAL_SEED = 777  # the evaluation episodes during training (not the held-out seed)


def _mlp(key, sizes):
    """Parameters of an MLP with `sizes` (LeCun-normal weights, zero biases)."""
    keys = jax.random.split(key, len(sizes) - 1)
    return [
        (jax.random.normal(k, (a, b)) / np.sqrt(a), jnp.zeros(b))
        for k, a, b in zip(keys, sizes[:-1], sizes[1:])
    ]


def _act(params, obs):
    """The deterministic policy: tanh of the MLP (swish hidden layers)."""
    x = obs
    for w, b in params[:-1]:
        x = jax.nn.swish(x @ w + b)
    w, b = params[-1]
    return jnp.tanh(x @ w + b)


def make_policy(params, deterministic=True):
    """A Brax-style policy, `(obs, key) -> (action, extras)`, for `rover_ppo.held_out`."""
    return lambda obs, key: (_act(params, obs), {})


def train(settings: dict, seed: int = 0, log=print):
    """Back-propagation through time on `SnowRover` (solver unrolled): returns (env,
    policy factory, parameters, learning curve rows (env-steps, wall seconds, success,
    mean return), wall time [s], updates skipped for a non-finite gradient)."""
    env = sp.SnowRover(config_overrides={"solver_unroll": 2})
    length = env._config.episode_length
    wrapped = sp.wrap_for_brax_training(env, episode_length=length)
    n, horizon = settings["num_envs"], settings["horizon"]
    optimizer = optax.chain(
        optax.clip_by_global_norm(settings["max_gradient_norm"]),
        optax.adam(settings["learning_rate"]),
    )
    key_params, key_env = jax.random.split(jax.random.PRNGKey(seed))
    params = _mlp(key_params, [env.observation_size, 64, 64, env.action_size])
    opt_state = optimizer.init(params)

    def loss(params, state):
        def body(s, _):
            s = wrapped.step(s, _act(params, s.obs))
            return s, s.reward

        state, rewards = jax.lax.scan(body, state, None, length=horizon)
        return -jnp.sum(rewards) / n, state

    @jax.jit
    def update(params, opt_state, state):
        (value, state), grads = jax.value_and_grad(loss, has_aux=True)(
            params, jax.lax.stop_gradient(state)
        )
        finite = jnp.all(jnp.stack([jnp.all(jnp.isfinite(g)) for g in jax.tree.leaves(grads)]))
        grads = jax.tree.map(lambda g: jnp.where(finite, g, 0.0), grads)
        steps, new_opt = optimizer.update(grads, opt_state, params)
        new_params = optax.apply_updates(params, steps)
        keep = lambda new, old: jax.tree.map(lambda a, b: jnp.where(finite, a, b), new, old)  # noqa: E731
        return keep(new_params, params), keep(new_opt, opt_state), state, finite

    eval_keys = jax.random.split(jax.random.PRNGKey(EVAL_SEED), settings["num_eval_envs"])

    @jax.jit
    def evaluate(params):
        state = jax.vmap(env.reset)(eval_keys)

        def body(carry, _):
            state, arrived, ret = carry
            state = jax.vmap(env.step)(state, _act(params, state.obs))
            live = ~arrived
            ret = ret + jnp.where(live, state.reward, 0.0)
            return (state, arrived | (state.metrics["arrived"] > 0), ret), None

        zeros = jnp.zeros(len(eval_keys))
        (_, arrived, ret), _ = jax.lax.scan(body, (state, zeros > 0, zeros), None, length=length)
        return arrived.mean(), ret.mean()

    curve, progress = rover_ppo.recorder(log)
    start = time.perf_counter()
    state = wrapped.reset(jax.random.split(key_env, n))
    every = max(settings["updates"] // max(settings["num_evals"] - 1, 1), 1)
    skipped = 0
    for k in range(settings["updates"] + 1):
        if k % every == 0 or k == settings["updates"]:
            success, ret = evaluate(params)
            metrics = {"eval/episode_arrived": success, "eval/episode_reward": ret}
            progress(k * n * horizon, metrics)
        if k == settings["updates"]:
            break
        params, opt_state, state, finite = update(params, opt_state, state)
        skipped += int(not bool(finite))
    return env, make_policy, params, curve, time.perf_counter() - start, skipped


def figure(apg_curve, ppo_curve, path):
    """Evaluation success rate and mean return against env-steps, APG and (if given) PPO."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    for name, curve, style in (("APG (BPTT)", apg_curve, "o-"), ("PPO", ppo_curve, "s-")):
        if curve:
            c = np.asarray(curve)
            label = f"{name} ({c[-1, 1]:.0f} s)"
            axes[0].plot(c[:, 0] / 1e6, c[:, 2], style, ms=4, label=label)
            axes[1].plot(c[:, 0] / 1e6, c[:, 3], style, ms=4, label=label)
    axes[0].set_ylabel("evaluation success rate")
    axes[0].set_ylim(-0.02, 1.02)
    axes[1].set_ylabel("evaluation mean return [m of progress + bonus]")
    for ax in axes:
        ax.set_xlabel("env-steps [millions]")
        ax.grid(alpha=0.3)
        ax.legend(title="wall time on 2 CPU cores", fontsize=8)
    fig.suptitle("SnowRover: analytic policy gradients vs PPO", fontsize=10)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="a tiny budget, to check it runs")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--ppo-json", type=pathlib.Path, help="rover_ppo.py --save's output")
    parser.add_argument("--out", type=pathlib.Path, default=ROOT / "docs/figures/rl_apg_vs_ppo.png")
    parser.add_argument("--save", type=pathlib.Path, help="write the run's numbers (JSON)")
    args = parser.parse_args(argv)
    settings = QUICK if args.quick else SETTINGS
    env, make_policy, params, curve, wall, skipped = train(settings, seed=args.seed)
    arrived, _, _ = rover_ppo.held_out(env, make_policy, params)
    steps = curve[-1][0]
    print(
        f"APG: {arrived.mean():.0%} of 64 held-out episodes reach the goal after {steps:,} "
        f"env-steps in {wall:.0f} s ({skipped} of {settings['updates']} updates skipped: "
        "gradient not finite)"
    )
    ppo_curve = json.loads(args.ppo_json.read_text())["curve"] if args.ppo_json else None
    figure(curve, ppo_curve, args.out)
    print(f"wrote {args.out}")
    if args.save:
        record = dict(settings=settings, seed=args.seed, curve=curve, wall_s=wall,
                      held_out_success=float(arrived.mean()), env_steps=steps,
                      skipped=skipped)  # fmt: skip
        args.save.write_text(json.dumps(record, indent=1))


if __name__ == "__main__":
    main()
