"""Reverse-mode gradients through a rollout of the rover on snow (`snowjax.playground`,
extra `snowjax[rl]`; MJX's constraint solver unrolled, `solver_unroll`).  Its own file
so that pytest-xdist's `--dist loadscope` runs it beside `test_playground.py`.

Real MJX, Playground and Brax on the CPU.  Skipped only when the `rl` extra is absent
(`make test` installs it, and CI fails without it).  Small shapes throughout: the cost is
compiling the rover's step with the snow's forces.
"""

import jax
import jax.numpy as jnp
import pytest

from .extras import require_extra

require_extra("rl", "mujoco_playground", "brax")

import snowjax as sj  # noqa: E402
import snowjax.playground as sp  # noqa: E402
from snowjax import mjx as smjx  # noqa: E402

SNOW = sj.WongSnow.thesis_fresh_snow()


@pytest.mark.slow  # grad through 100 MJX steps with snow: minutes to compile (make test-slow)
def test_reverse_mode_gradient_of_a_100_step_rollout_matches_central_differences():
    """d(return)/d(policy parameters) and d(return)/d(p_w) by `jax.grad` through 25
    control steps of 4 MJX steps (100 MJX steps of 5 ms, snow forces on every wheel,
    MJX's constraint solver unrolled: `solver_unroll=2`), against central differences,
    within 1e-4 relative (measured: 4.7e-8, 1.3e-9, 9e-10 and 2.1e-9)."""
    model, wheels = smjx.load_rover()
    env = sp.SnowRover(
        config_overrides={"ctrl_dt": 0.02, "sim_dt": 0.005, "accuracy": "reference",
                          "solver_unroll": 2, "goal.distance": (12.0, 12.0)},
        model=model, wheels=wheels,
    )  # fmt: skip
    start = env.reset(jax.random.PRNGKey(3))

    def episode_return(theta, p_w):
        w, b = theta[:26].reshape(2, 13), theta[26:]
        snow = sj.WongSnow(p_w, SNOW.z_w, SNOW.cohesion, SNOW.tan_phi, SNOW.shear_modulus)
        state = start.replace(info=dict(start.info, snow=snow))

        def body(state, _):
            state = env.step(state, jnp.tanh(w @ state.obs + b))
            return state, state.reward

        _, rewards = jax.lax.scan(body, state, None, length=25)
        return jnp.sum(rewards)

    theta = 0.3 * jax.random.normal(jax.random.PRNGKey(1), (28,))
    theta = theta.at[27].set(0.8)  # throttle
    p_w = SNOW.p_w
    value = jax.jit(episode_return)
    grad_theta, grad_p = jax.jit(jax.grad(episode_return, argnums=(0, 1)))(theta, p_w)
    direction = jax.random.normal(jax.random.PRNGKey(5), (28,))
    checks = [
        (grad_theta[27], lambda h: value(theta.at[27].add(h), p_w), 1e-5),  # throttle bias
        (grad_theta[0], lambda h: value(theta.at[0].add(h), p_w), 1e-5),  # a weight
        (grad_theta @ direction, lambda h: value(theta + h * direction, p_w), 1e-5),
        (grad_p, lambda h: value(theta, p_w + h), 1e-5 * float(p_w)),
    ]
    for ad, f, h in checks:
        fd = (float(f(h)) - float(f(-h))) / (2 * h)
        assert abs(fd) > 1e-9
        assert abs(float(ad) - fd) <= 1e-4 * abs(fd), (float(ad), fd)
