"""Property-based check of the wheel solver over the documented range (hypothesis).

Random in-range wheels, snows, loads and slips (driving and braking, every shear model,
float64 and float32): every element is converged or flagged, no field is NaN unless the
status is INVALID_INPUT, and gradients are finite wherever the solve converged.  Each
example is a batch of cases solved in one jitted call (one compile per shear model and
dtype).
"""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import snowjax as sj
from snowjax import Status

SHEAR_MODELS = ("classic", "simplified", "none")
BATCH = 24
FIELDS = ("entry_angle", "sinkage", "motion_resistance", "thrust", "drawbar_pull", "torque")


def _uniform(lo, hi):
    return st.floats(lo, hi, allow_nan=False, allow_infinity=False)


def _log_uniform(lo, hi):
    return _uniform(np.log(lo), np.log(hi)).map(np.exp)


# One case: D, b, p_w, z_w / min(0.35, 0.45 D) scaled into [0.05, ...], c, tan phi, K,
# load, slip; the documented range of `solve_wheel`.
CASE = st.tuples(
    _uniform(0.5, 1.5),
    _uniform(0.1, 0.6),
    _log_uniform(5e3, 200e3),
    _uniform(0.0, 1.0),
    _log_uniform(100.0, 20e3),
    _uniform(0.02, 0.8),
    _log_uniform(0.002, 0.08),
    _log_uniform(100.0, 20e3),
    _uniform(-0.5, 0.99),
)
BATCHES = st.lists(CASE, min_size=BATCH, max_size=BATCH)


def _inputs(cases, dtype):
    x = np.array(cases, dtype=np.float64).T
    d, b, p_w, z_frac, c, tan_phi, k, load, slip = x
    z_w = 0.05 + z_frac * (np.minimum(0.35, 0.45 * d) - 0.05)
    cast = lambda a: jnp.asarray(a, dtype)  # noqa: E731
    wheel = sj.RigidWheel(cast(d), cast(b))
    snow = sj.WongSnow(cast(p_w), cast(z_w), cast(c), cast(tan_phi), cast(k))
    return wheel, snow, cast(load), cast(slip)


def _drawbar_pull_sum(snow, wheel, load, slip, shear):
    state = sj.solve_wheel(wheel, snow, load, slip, shear=shear)
    return jnp.sum(state.drawbar_pull), state


@jax.jit
def _solve_and_differentiate(wheel, snow, load, slip):
    """States for every shear model; gradients of the summed drawbar pull w.r.t. the snow
    (per element: the elements are independent) for the classic and simplified ones."""
    states, grads = {}, {}
    for shear in SHEAR_MODELS:
        if shear == "none":
            states[shear] = sj.solve_wheel(wheel, snow, load, slip, shear=shear)
            continue
        fn = jax.grad(_drawbar_pull_sum, has_aux=True)
        grads[shear], states[shear] = fn(snow, wheel, load, slip, shear)
    return states, grads


@pytest.mark.parametrize("dtype", [jnp.float64, jnp.float32])
@settings(max_examples=10, deadline=None, derandomize=True)
@given(cases=BATCHES)
def test_converged_or_flagged_never_nan_and_finite_gradients(cases, dtype):
    wheel, snow, load, slip = _inputs(cases, dtype)
    states, grads = _solve_and_differentiate(wheel, snow, load, slip)
    for shear, state in states.items():
        status = np.asarray(state.status)
        assert np.all(status != Status.INVALID_INPUT), shear  # every case is in range
        assert np.all(np.isin(status, [s.value for s in Status])), shear
        for name in FIELDS:
            value = np.asarray(getattr(state, name))
            assert value.dtype == dtype
            assert np.all(np.isfinite(value)), (shear, name, status[~np.isfinite(value)])
        # At most a small share of the batch may be left unbalanced.
        assert np.mean(status == Status.NOT_CONVERGED) <= 0.1, (shear, status)
        if shear in grads:
            converged = status == Status.CONVERGED
            for name in ("p_w", "z_w", "cohesion", "tan_phi", "shear_modulus"):
                g = np.asarray(getattr(grads[shear], name))
                assert np.all(np.isfinite(g[converged])), (shear, name, g[converged])


def test_float32_gradient_at_a_vanishing_braking_slip_is_finite():
    """Found by the property test: a float32 slip of -1.7e-36 made the simplified model's
    braking layout overflow (level / (tau1 B) with B ~ -slip / 3) in the capacity check,
    whose NaN did not show in the values but poisoned every gradient."""
    f32 = np.float32
    wheel = sj.RigidWheel(f32(0.5), f32(0.5))

    def drawbar_pull(p_w, slip):
        snow = sj.WongSnow(p_w, f32(0.05), f32(np.exp(5)), f32(0.5), f32(np.exp(-5)))
        return sj.solve_wheel(wheel, snow, f32(np.exp(5)), slip, shear="simplified").drawbar_pull

    grad = jax.jit(jax.grad(drawbar_pull, argnums=(0, 1)))
    tiny, zero = grad(f32(np.exp(9)), f32(-1.7339896679487998e-36)), grad(f32(np.exp(9)), f32(0))
    for g_tiny, g_zero in zip(tiny, zero):
        assert np.isfinite(g_tiny)
        np.testing.assert_allclose(g_tiny, g_zero, rtol=1e-4)
