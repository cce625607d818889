"""Train a policy to drive the snowjax rover to a goal on randomised snow, with evolution
strategies (ES) on `snowjax.mjx.SnowRoverEnv`, and plot what it learnt.

    python examples/rover_reach_goal.py            # 30 generations, about 9 minutes on 2 CPU cores
    python examples/rover_reach_goal.py --quick    # 3 generations, small batches

The policy is linear with a tanh squashing, `action = tanh(W obs + b)` (28 parameters;
13 observations, 2 actions: steering and throttle), starting from zero (it does not move).
Each generation evaluates `population` antithetic pairs of Gaussian perturbations of the
parameters (OpenAI-ES, Salimans et al. 2017, arXiv:1703.03864) on `snows` episodes each,
every generation on freshly drawn snows and goals (domain randomisation), all of them in
one vmapped, jitted batch of environments; the centred ranks of the returns weight the
perturbations into a gradient estimate, and Adam takes the step.  The objective reported
is the mean return over a fixed set of evaluation episodes (the same for every
generation), so its rise is the policy's, not the draw's.

Writes `docs/figures/mjx_rover_reach_goal.png` (or `--out`): the objective per
generation, and the rover's paths to eight goals before and after training.
"""

from __future__ import annotations

import argparse
import pathlib
import time

import jax

jax.config.update("jax_enable_x64", True)
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402

from snowjax import mjx as smjx  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parents[1]


def policy(params, obs):
    """Linear policy with tanh squashing: actions in [-1, 1]^2."""
    w, b = params
    return jnp.tanh(obs @ w.T + b)


def episodes(env, params, keys):
    """Returns (shape (k,)) and chassis paths (steps, k, 2) [m] of `params` on the
    episodes of `keys` (k,): one vmapped scan over the environment."""
    state = jax.vmap(env.reset)(keys)

    def body(state, _):
        action = jax.vmap(policy, in_axes=(None, 0))(params, state.obs)
        state = jax.vmap(env.step)(state, action)
        return state, (state.reward, state.data.qpos[:, :2])

    state, (rewards, paths) = jax.lax.scan(body, state, None, length=env.episode_length)
    return rewards.sum(0), paths, state.info["goal"]


def train(
    generations: int = 30,
    population: int = 16,
    snows: int = 2,
    episode_length: int = 250,
    sigma: float = 0.1,
    learning_rate: float = 0.05,
    seed: int = 0,
    progress: bool = True,
):
    """ES on `SnowRoverEnv`: returns (history of the objective, one value before training
    and one per generation; the final parameters; the environment; the evaluation keys).

    `population` antithetic pairs, each member on the same `snows` episodes (common
    random numbers); the objective is the mean return over 2 x population x snows fixed
    evaluation episodes, so it compiles with the population's batch (one program).
    `sigma`: perturbation scale; `learning_rate`: Adam's.
    """
    env = smjx.SnowRoverEnv(episode_length=episode_length)
    shapes = ((env.action_size, env.observation_size), (env.action_size,))
    size = sum(int(np.prod(s)) for s in shapes)
    members = 2 * population

    def unflatten(theta):
        w = theta[: shapes[0][0] * shapes[0][1]].reshape(shapes[0])
        return w, theta[w.size :]

    @jax.jit
    def returns(thetas, keys):
        """Mean return of each parameter vector (members, size) over its episodes'
        keys (members, snows)."""
        one = lambda t, k: jnp.mean(episodes(env, unflatten(t), k)[0])  # noqa: E731
        return jax.vmap(one)(thetas, keys)

    theta = jnp.zeros(size)
    eval_keys = jax.random.split(jax.random.key(seed + 1), (members, snows))

    def objective(theta):
        return float(jnp.mean(returns(jnp.tile(theta, (members, 1)), eval_keys)))

    m, v = jnp.zeros(size), jnp.zeros(size)
    history = [objective(theta)]
    key = jax.random.key(seed)
    for g in range(generations):
        key, noise_key, episode_key = jax.random.split(key, 3)
        eps = jax.random.normal(noise_key, (population, size))
        thetas = jnp.concatenate([theta + sigma * eps, theta - sigma * eps])
        keys = jnp.broadcast_to(jax.random.split(episode_key, snows), (members, snows))
        f = returns(thetas, keys)
        ranks = jnp.argsort(jnp.argsort(f))
        centred = ranks / (members - 1) - 0.5
        grad = (centred[:population] - centred[population:]) @ eps / (population * sigma)
        m = 0.9 * m + 0.1 * grad  # Adam, ascending
        v = 0.999 * v + 0.001 * grad * grad
        step = (
            learning_rate
            * (m / (1 - 0.9 ** (g + 1)))
            / (jnp.sqrt(v / (1 - 0.999 ** (g + 1))) + 1e-8)
        )
        theta = theta + step
        history.append(objective(theta))
        if progress:
            print(f"generation {g + 1}/{generations}: objective {history[-1]:.3f}", flush=True)
    return np.asarray(history), unflatten(theta), env, eval_keys.reshape(-1)


def figure(history, params, env, keys, path):
    """Objective per generation; paths before (zero policy) and after training."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax0, ax1) = plt.subplots(1, 2, figsize=(11, 4.5))
    ax0.plot(np.arange(len(history)), history, "o-")
    ax0.set_xlabel("generation")
    ax0.set_ylabel("objective: mean return [m]")
    ax0.set_title("ES on SnowRoverEnv: mean return of 64 fixed episodes", fontsize=10)
    ax0.grid(alpha=0.3)
    zero = tuple(jnp.zeros_like(p) for p in params)
    keys = keys[:8]
    _, before, goals = episodes(env, zero, keys)
    _, after, _ = episodes(env, params, keys)
    for k in range(8):
        (line,) = ax1.plot(np.asarray(after[:, k, 0]), np.asarray(after[:, k, 1]), lw=1.5)
        ax1.plot(*np.asarray(goals[k]), "*", ms=12, color=line.get_color())
        circle = plt.Circle(np.asarray(goals[k]), env.goal_radius, fill=False, ls=":")
        ax1.add_patch(circle)
    ax1.plot(np.asarray(before[:, :, 0]).ravel(), np.asarray(before[:, :, 1]).ravel(), "k.",
             ms=6, label="before training (at rest)")  # fmt: skip
    ax1.set_aspect("equal")
    ax1.set_xlabel("x [m]")
    ax1.set_ylabel("y [m]")
    ax1.set_title("rover paths after training; stars: goals")
    ax1.legend(loc="lower left")
    ax1.grid(alpha=0.3)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="3 generations, small batches")
    parser.add_argument(
        "--out", type=pathlib.Path, default=ROOT / "docs/figures/mjx_rover_reach_goal.png"
    )
    args = parser.parse_args(argv)
    settings = dict(generations=3, population=4, snows=1, episode_length=100) if args.quick else {}
    start = time.perf_counter()
    history, params, env, keys = train(**settings)
    print(f"objective {history[0]:.3f} -> {history[-1]:.3f} in {time.perf_counter() - start:.0f} s")
    figure(history, params, env, keys, args.out)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
