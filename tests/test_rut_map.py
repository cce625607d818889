"""The rut map (`snowjax.RutMap`, `snowjax.drive_path`): on a straight track it agrees
with the one-track `multi_pass` model (the rear wheel reads exactly the depth the front
wheel marked, for a track at any angle to the grid); a wheel driving a circle meets its
own rut on the second lap (vmapped over two snows); forward-mode gradients through the
map against central differences (reverse mode against forward mode: a `slow` case);
reading, marking, memory and bad inputs."""

from __future__ import annotations

import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import snowjax as sj
from snowjax import Status

WHEEL = sj.RigidWheel.thesis_tire()
SNOW = sj.WongSnow.thesis_fresh_snow()
K_0, A_U = 1e6, 5e6  # [Pa/m], [Pa/m^2] (illustrative, as in test_rut.py)
LOAD, SLIP = 3500.0, 0.2
H = 0.05  # cell size [m]
EXTENT = (-1.0, 7.0, -1.0, 5.0)  # (x_min, x_max, y_min, y_max) [m]


def _straight(steps, step, angle, wheelbase):
    """Front and rear wheel centres (steps, 2, 2) on one line at `angle` [rad]."""
    s = jnp.arange(steps) * step
    t = jnp.array([math.cos(angle), math.sin(angle)])
    return jnp.stack([(s[:, None] + wheelbase) * t, s[:, None] * t], 1)


def test_straight_track_agrees_with_multi_pass_at_any_angle_to_the_grid():
    """Rear wheel 2.5 m behind the front one, 40 steps of 0.125 m, the track 0.6 rad off
    the grid's x axis: once the rear wheel's read point is in the front wheel's marks it
    sees exactly the depth marked (1e-12: the grid adds no error on a straight track of
    one width), and its results are `multi_pass`'s second pass within 1e-7 (the wheel
    solves' convergence).  The front wheel on the empty map is the first pass within
    1e-6: a rut of zero depth goes through the generic quadrature, the virgin Wong snow
    through its closed-form front region."""
    out = _drive(jnp.array([float(SNOW.p_w), LOAD, K_0]))
    assert np.all(np.asarray(out.status) == Status.CONVERGED)
    passes = sj.multi_pass(WHEEL, SNOW, jnp.array([LOAD, LOAD]), SLIP, K_0, A_U)
    front, rear = np.asarray(out.sinkage[:, 0]), np.asarray(out.rut_depth[:, 1])
    np.testing.assert_array_equal(out.rut_depth[:, 0], 0.0)
    np.testing.assert_allclose(front, passes.sinkage[0], rtol=1e-6)
    inside = np.flatnonzero(rear > 0)
    assert inside[0] < 24 and np.all(np.diff(inside) == 1)  # no gaps along the track
    steady = inside[2:]  # past the ramp where the read point enters the first marks
    np.testing.assert_allclose(rear[steady], front[0], rtol=1e-12)
    for name in ("sinkage", "motion_resistance", "drawbar_pull", "torque"):
        got = np.asarray(getattr(out, name)[steady, 1])
        np.testing.assert_allclose(got, getattr(passes, name)[1], rtol=1e-7, err_msg=name)
    assert float(passes.motion_resistance[1]) < 0.9 * float(passes.motion_resistance[0])


@pytest.mark.slow  # two laps of a path (make test-slow)
def test_a_wheel_driving_a_circle_meets_its_own_rut_on_the_second_lap():
    """One wheel, two laps of a 4 m circle in 200 steps, on two snows at once (vmap):
    lap 1 on virgin snow, lap 2 in its own rut, where it is `multi_pass`'s second pass
    (1e-7; the read depth equals the first lap's within 1e-12)."""
    angle = jnp.linspace(0.0, 4 * math.pi, 200)
    path = (4.0 * jnp.stack([jnp.cos(angle), jnp.sin(angle)], -1))[:, None, :]
    heading = (angle + math.pi / 2)[:, None]
    grid = sj.RutMap.empty((-5.0, 5.0, -5.0, 5.0), H, K_0, A_U)
    snows = jax.tree.map(
        lambda a, b: jnp.stack([a, b]), SNOW, sj.WongSnow.thesis_fresh_snow(p_w=60e3)
    )
    out = jax.vmap(lambda snow: sj.drive_path(WHEEL, snow, grid, path, heading, LOAD, SLIP))(snows)
    for k in range(2):
        snow = jax.tree.map(lambda x, k=k: x[k], snows)
        passes = sj.multi_pass(WHEEL, snow, jnp.array([LOAD, LOAD]), SLIP, K_0, A_U)
        seen = np.asarray(out.rut_depth[k, :, 0])
        np.testing.assert_array_equal(seen[:95], 0.0)  # lap 1: virgin snow
        # Lap 2, up to where the read point reaches the start of lap 2's own marks.
        lap2 = slice(110, 190)
        np.testing.assert_allclose(seen[196:], out.sinkage[k, 120, 0], rtol=1e-12)
        np.testing.assert_allclose(seen[lap2], out.sinkage[k, 10, 0], rtol=1e-12)
        for name in ("sinkage", "motion_resistance", "drawbar_pull"):
            got = np.asarray(getattr(out, name)[k, lap2, 0])
            np.testing.assert_allclose(got, getattr(passes, name)[1], rtol=1e-7, err_msg=name)
    # The map's memory is fixed by the grid: 200 x 200 cells of 8 bytes.
    assert grid.nbytes == 200 * 200 * 8


def _drive(x):
    """`drive_path` of the straight-track test as a function of x = (p_w [Pa], the front
    wheel's load [N], k_0 [Pa/m]) (one compile for that test and the gradients')."""
    snow = sj.WongSnow.thesis_fresh_snow(p_w=x[0])
    grid = sj.RutMap.empty(EXTENT, H, x[2], A_U)
    loads = jnp.stack([x[1], jnp.asarray(LOAD)])
    return sj.drive_path(WHEEL, snow, grid, _straight(40, 0.125, 0.6, 2.5), 0.6, loads, SLIP)


def _resistance(x):
    """The rear wheel's motion resistance [N], summed over its steps in the rut."""
    return jnp.sum(_drive(x).motion_resistance[24:, 1])


X = jnp.array([float(SNOW.p_w), 4000.0, K_0])


@pytest.mark.slow  # gradients through the map (make test-slow)
def test_gradients_through_the_map_match_central_differences():
    """Forward mode w.r.t. p_w, the front wheel's load and k_0 (each reaches the rear
    wheel only through the map) against central differences, 1e-6 relative (steps 1e-4
    relative)."""
    forward = jax.jacfwd(_resistance)(X)
    for k in range(3):
        h = 1e-4 * float(X[k])
        central = (_resistance(X.at[k].add(h)) - _resistance(X.at[k].add(-h))) / (2 * h)
        np.testing.assert_allclose(forward[k], central, rtol=1e-6)
        assert abs(float(forward[k])) > 0  # every input reaches the rear wheel


@pytest.mark.slow
def test_reverse_mode_through_the_map_equals_forward_mode():
    np.testing.assert_allclose(jax.grad(_resistance)(X), jax.jacfwd(_resistance)(X), rtol=1e-9)


def test_read_and_mark():
    grid = sj.RutMap.empty((0.0, 2.0, 0.0, 1.0), 0.1, K_0, A_U, reach=1.0)
    assert grid.depth.shape == (20, 10) and grid.window == 18
    # A wheel 0.2 m wide moves 0.5 m along x at y = 0.5 and reaches 0.1 m.
    marked = grid.mark(jnp.array([[0.5, 0.5]]), jnp.array([[1.0, 0.5]]), 0.2, 0.1)
    cells = np.asarray(marked.depth)
    x = 0.05 + 0.1 * np.arange(20)[:, None]
    y = 0.05 + 0.1 * np.arange(10)[None, :]
    reach = math.sqrt(2) * 0.1
    expected = (x >= 0.5 - reach) & (x <= 1.0) & (np.abs(y - 0.5) <= 0.1 + reach)
    np.testing.assert_array_equal(cells, np.where(expected, 0.1, 0.0))
    # The mark is a maximum: a shallower wheel over it changes nothing.
    again = marked.mark(jnp.array([[0.5, 0.5]]), jnp.array([[1.0, 0.5]]), 0.2, 0.05)
    np.testing.assert_array_equal(again.depth, marked.depth)
    # Read back across the width by a wheel behind the mark, looking 0.3 m ahead; the
    # map is bilinear inside and virgin (0) outside.
    np.testing.assert_allclose(marked.read(jnp.array([0.4, 0.5]), 0.0, 0.2, 0.3), 0.1)
    assert float(marked.read(jnp.array([3.0, 0.5]), 0.0, 0.2, 0.3)) == 0.0
    np.testing.assert_allclose(marked.sample(jnp.array([0.2, 0.5])), 0.0)
    # A wheel at rest marks nothing.
    rest = grid.mark(jnp.array([[1.0, 0.5]]), jnp.array([[1.0, 0.5]]), 0.2, 0.1)
    np.testing.assert_array_equal(rest.depth, 0.0)
    # A step longer than the map's reach (0.5 m by default) raises, also under jit.
    wide = sj.RutMap.empty((0.0, 5.0, 0.0, 5.0), 0.1, K_0, A_U)
    with pytest.raises(Exception, match="reach"):
        eqx.filter_jit(lambda m, a, b: m.mark(a, b, 0.2, 0.1))(
            wide, jnp.array([[0.5, 0.5]]), jnp.array([[2.0, 0.5]])
        )


@pytest.mark.parametrize(
    "call, match",
    [
        (lambda: sj.RutMap.empty((0, 1, 0, 1), 0.0, K_0, A_U), "cell_size"),
        (lambda: sj.RutMap.empty((0, -1, 0, 1), 0.1, K_0, A_U), "extent"),
        (lambda: sj.RutMap.empty((0, 1, 0, 1), 0.1, -1.0, A_U), "k_0"),
        (lambda: sj.RutMap.empty((0, 1, 0, 1), 0.1, K_0, jnp.nan), "a_u"),
        (
            lambda: sj.RutMap.empty((0, 1, 0, 1), 0.1, K_0, A_U).read(jnp.zeros(2), 0.0, 0.2, 0.1),
            "lookahead",
        ),
        (
            lambda: sj.drive_path(
                WHEEL,
                SNOW,
                sj.RutMap.empty((0, 2, 0, 2), 0.5, K_0, A_U),
                jnp.zeros((3, 1, 2)),
                0.0,
                LOAD,
                SLIP,
            ),
            "lookahead",
        ),  # fmt: skip
        (lambda: sj.Ruts(K_0, A_U, (0, -1)).layout(2), "follows"),
        (lambda: sj.Ruts(K_0, A_U).layout(3), "even"),
        (lambda: sj.Ruts(0.0, A_U).layout(2), "k_0"),
    ],
)
def test_bad_inputs_are_named(call, match):
    with pytest.raises(ValueError, match=match):
        call()
