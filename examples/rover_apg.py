"""Train the snowjax rover on `rover_ppo.py`'s task by analytic policy gradients: Brax's
APG (`brax.training.agents.apg`), which back-propagates the return through the
environment itself: MJX's dynamics and the snow's wheel forces (their implicit
equilibria), `horizon_length` control steps at a time.

    python examples/rover_apg.py --ppo-json ppo.json   # the guide's run; compares with PPO
    python examples/rover_apg.py --quick               # a tiny budget, to check it runs

The environment is `snowjax.playground.SnowRover` with `solver_unroll=2` (MJX's
constraint solver as two unrolled Newton iterations, which reverse mode can
differentiate; its default `while_loop` cannot) and the default config otherwise.
The same 64 held-out episodes as `rover_ppo.py` give the success rate.  Writes
`docs/figures/rl_apg_vs_ppo.png` (or `--out`): the evaluation success rate of both
methods against env-steps (PPO's from `--ppo-json`, written by `rover_ppo.py --save`).
"""

from __future__ import annotations

import argparse
import functools
import json
import pathlib
import sys
import time

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import rover_ppo  # noqa: E402  (the held-out evaluation and the task)

import snowjax.playground as sp  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parents[1]

# Chosen before the run (Brax's APG defaults where they fit a 2-core CPU); not tuned on
# the held-out seed.
SETTINGS = dict(
    policy_updates=120,
    horizon_length=10,
    num_envs=64,
    learning_rate=3e-4,
    max_gradient_norm=1.0,
    num_evals=11,
    num_eval_envs=64,
)
QUICK = dict(SETTINGS, policy_updates=4, horizon_length=4, num_envs=8, num_evals=2,
             num_eval_envs=8)  # fmt: skip


def train(settings: dict, seed: int = 0, log=print):
    """APG on `SnowRover` (solver unrolled): returns (env, inference function factory,
    parameters, learning curve rows (env-steps, wall seconds, success, mean return), wall
    time [s])."""
    from brax.training.agents.apg import networks as apg_networks
    from brax.training.agents.apg import train as apg

    env = sp.SnowRover(config_overrides={"solver_unroll": 2})
    cfg = env._config
    # Brax's APG reports the evaluation's index; its env-steps per evaluation interval:
    per_eval = round(settings["policy_updates"] / max(settings["num_evals"] - 1, 1))
    per_eval *= settings["num_envs"] * settings["horizon_length"]
    curve, progress = rover_ppo.recorder(log, lambda index: int(index) * per_eval)
    start = time.perf_counter()

    make_policy, params, _ = apg.train(
        environment=env,
        episode_length=cfg.episode_length,
        action_repeat=cfg.action_repeat,
        wrap_env_fn=sp.wrap_for_brax_training,
        normalize_observations=True,
        network_factory=functools.partial(
            apg_networks.make_apg_networks, hidden_layer_sizes=(64, 64)
        ),
        progress_fn=progress,
        seed=seed,
        **settings,
    )
    return env, make_policy, params, curve, time.perf_counter() - start


def figure(apg_curve, ppo_curve, path):
    """Success rate against env-steps, APG and (if given) PPO."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.5, 4.2))
    for name, curve, style in (("APG", apg_curve, "o-"), ("PPO", ppo_curve, "s-")):
        if curve:
            c = np.asarray(curve)
            ax.plot(c[:, 0] / 1e6, c[:, 2], style, label=f"{name} ({c[-1, 1]:.0f} s)")
    ax.set_xlabel("env-steps [millions]")
    ax.set_ylabel("success rate (Brax's evaluation episodes)")
    ax.set_ylim(-0.02, 1.02)
    ax.grid(alpha=0.3)
    ax.legend(title="wall time on 2 CPU cores")
    ax.set_title("SnowRover: analytic policy gradients vs PPO", fontsize=10)
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
    env, make_policy, params, curve, wall = train(settings, seed=args.seed)
    arrived, _, _ = rover_ppo.held_out(env, make_policy, params)
    steps = curve[-1][0]
    print(
        f"APG: {arrived.mean():.0%} of 64 held-out episodes reach the goal after {steps:,} "
        f"env-steps in {wall:.0f} s"
    )
    ppo_curve = json.loads(args.ppo_json.read_text())["curve"] if args.ppo_json else None
    figure(curve, ppo_curve, args.out)
    print(f"wrote {args.out}")
    if args.save:
        record = dict(settings=settings, seed=args.seed, curve=curve, wall_s=wall,
                      held_out_success=float(arrived.mean()), env_steps=steps)  # fmt: skip
        args.save.write_text(json.dumps(record, indent=1))


if __name__ == "__main__":
    main()
