"""The rut map in the MJX rollout (`snowjax.mjx.rollout(..., ruts=RutMap)`): each wheel
of the shipped rover reads the rut ahead of it and marks its own behind it.

Real MuJoCo MJX on CPU, float64.  Skipped only when the `mjx` extra is absent (as
`tests/test_mjx.py`).  One compiled rollout of `CHUNK` steps is shared through a module
fixture: the state, the map, the controls and the warm start are its arguments, so the
straight run and the two laps chain calls of the same compile.  The rover steps at 10 ms
here (MuJoCo's `timestep`, 5 ms in the shipped model) to halve the laps' cost: the laps'
mean depths at 5 ms agree with these within 0.3 mm.
"""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from .extras import require_extra

require_extra("mjx", "mujoco", "mujoco.mjx")

from mujoco import mjx  # noqa: E402

import snowjax as sj  # noqa: E402
from snowjax import Status  # noqa: E402
from snowjax import mjx as smjx  # noqa: E402

SNOW = sj.WongSnow.thesis_fresh_snow()
K_0, A_U = 1e6, 5e6  # [Pa/m], [Pa/m^2] (illustrative, as in tests/test_rut.py)
RADIUS = 0.368  # [m]
DT = 0.01  # [s]
CHUNK = 200  # steps per call of the compiled rollout (2 s)
# One map for every run (one compile): 10 cm cells over the straight track along +x
# and the circle left of it, 310 x 220 cells.
EXTENT, CELL = (-11.0, 20.0, -3.0, 19.0), 0.1


def _map():
    return sj.RutMap.empty(EXTENT, CELL, K_0, A_U)


@pytest.fixture(scope="module")
def rover():
    model, wheels = smjx.load_rover()
    m = mjx.put_model(model)
    m = m.replace(opt=m.opt.replace(timestep=DT))
    return m, wheels, mjx.make_data(m)


def _moving(rover, speed, slip):
    """The rover driving straight along +x at `speed` [m/s], its wheels at `slip`."""
    _, wheels, d0 = rover
    spin = speed / (RADIUS * (1 - slip))
    return d0.replace(qvel=d0.qvel.at[0].set(speed).at[np.asarray(wheels.dof_ids)].set(spin))


@pytest.fixture(scope="module")
def drive(rover):
    """(start data, rut map, ctrl, chunks) -> (MjxWheelForces and qpos of every step as
    NumPy arrays, the final `Rollout`): `chunks` calls of one compiled `CHUNK`-step
    rollout, each continuing the last (state, map, warm start)."""
    m, wheels, _ = rover

    @jax.jit
    def run(d, rut_map, ctrl, theta):
        return smjx.rollout(m, d, wheels, SNOW, ctrl, CHUNK, entry_angle=theta, ruts=rut_map)

    def drive(d, rut_map, ctrl, chunks):
        theta = jnp.full(wheels.num_wheels, jnp.nan, d.qpos.dtype)
        # Every argument committed to the device, as `run`'s results are: jit compiles
        # again for arguments placed differently (created here, or returned by `run`).
        d, rut_map, ctrl, theta = jax.device_put((d, rut_map, ctrl, theta), jax.devices()[0])
        outs, qpos = [], []
        for _ in range(chunks):
            r = run(d, rut_map, ctrl, theta)
            d, rut_map, theta = r.data, r.rut_map, r.wheels.entry_angle[-1]
            outs.append(jax.tree.map(np.asarray, r.wheels))
            qpos.append(np.asarray(r.qpos))
        return jax.tree.map(lambda *x: np.concatenate(x), *outs), np.concatenate(qpos), r

    return drive


@pytest.fixture(scope="module")
def straight(rover, drive):
    """4 s straight along +x at 540 N m per wheel from 2 m/s, wheels at slip 0.2."""
    ctrl = smjx.rover_controls(0.0, jnp.full(4, 540.0))
    return drive(_moving(rover, 2.0, 0.2), _map(), ctrl, 2)


def test_rear_wheels_in_the_front_ruts_are_multi_pass_second_pass(rover, straight):
    """Driving straight, a rear wheel meets the front wheel's rut only once its read
    point (a wheel radius ahead) reaches the front wheel's first mark, 0.8 s in (not at
    once, as with quasi-static `Ruts`).  Once the front wheels have settled (from 1.2 s:
    their slip changes by less than 1e-4 per 0.1 s; the rear wheels' slip keeps rising,
    from 0.85 to 0.93), a rear wheel sees the depth the front wheel marked when it was
    there and its drawbar pull, resisting torque and depth are `multi_pass`'s second
    pass at the front wheel's slip then and its own slip now, within 1e-6 (measured:
    the depth seen within 2.0e-7 of the front wheel's, forces, torques and depths within
    4.3e-8 of `multi_pass`; the map adds no error
    on a straight track of one width: what is left is which step of the front wheel
    the comparison picks, the one whose chassis position is nearest, and the front
    wheel's zero-depth `Rut` against the closed-form virgin snow of `multi_pass`'s
    first pass.  In the front wheels' transient, 0.9-1.5 s, where the front depth changes
    between the marks a read interpolates, the same comparison gives up to 2.9e-5)."""
    _, wheels, _ = rover
    w, qpos, _ = straight
    assert np.all(w.status == Status.CONVERGED)
    assert np.all(w.rut_depth[:, :2] == 0.0)  # the front wheels: virgin snow ahead
    np.testing.assert_array_equal(w.depth[:, :2], w.sinkage[:, :2])
    first = int(np.flatnonzero(w.rut_depth[:, 2] > 0)[0])
    assert 70 <= first <= 90 and np.all(w.rut_depth[first + 5 :, 2:] > 0.1)  # (a ramp)
    loads = np.asarray(wheels.static_load)
    x = qpos[:, 0]
    settled = 120  # the front wheels' steps from 1.2 s
    compared = []
    for k in range(first, len(x), 10):
        # When the front wheels were where the rear wheels read now (the chassis a
        # wheelbase less a radius behind): the step whose chassis x is nearest.
        kk = int(np.argmin(np.abs(x - (x[k] - 2.6 + RADIUS))))
        if kk < settled:
            continue
        compared.append(k)
        for front, rear in ((0, 2), (1, 3)):
            np.testing.assert_allclose(w.rut_depth[k, rear], w.depth[kk, front], rtol=1e-6)
            passes = sj.multi_pass(
                wheels.wheel, SNOW, loads[[front, rear]],
                jnp.array([w.slip[kk, front], w.slip[k, rear]]), K_0, A_U,
            )  # fmt: skip
            np.testing.assert_allclose(
                w.longitudinal_force[k, rear], passes.drawbar_pull[1], rtol=1e-6
            )
            np.testing.assert_allclose(w.resisting_torque[k, rear], passes.torque[1], rtol=1e-6)
            np.testing.assert_allclose(w.depth[k, rear], passes.sinkage[1], rtol=1e-6)
    assert len(compared) >= 20
    # The ruts matter: the rear wheels carry less torque and slip more than the front.
    assert np.all(w.slip[compared, 2] > w.slip[compared, 0] + 0.5)


def test_the_second_lap_runs_in_the_first_laps_ruts(rover, drive):
    """Two laps of a circle (0.3 rad of steering, 380 N m per wheel from 2 m/s; about
    8.5 m radius, 22 and 15 s per lap): on the second lap every wheel meets the ruts of
    the first (mean rut depth seen 36-62 mm per wheel, against 5-32 mm on the first
    lap, where the rear wheels run partly in the front wheels' ruts), and the wheels'
    mean depth below the original surface is deeper (measured 123.5-126.3 mm against
    119.8-121.2 mm; the wheels also slip more in the ruts, mean slip -0.09 to -0.06 on
    the first lap, 0.02 to 0.16 on the second: a wheel in a rut carries less torque)."""
    ctrl = smjx.rover_controls(0.3, jnp.full(4, 380.0))
    w, qpos, r = drive(_moving(rover, 2.0, 0.2), _map(), ctrl, 19)
    yaw = np.unwrap(2 * np.arctan2(qpos[:, 6], qpos[:, 3]))  # (small roll and pitch)
    lap = np.floor(yaw / (2 * np.pi)).astype(int)
    assert lap.max() >= 2  # two laps completed
    assert np.all(w.status == Status.CONVERGED)
    first, second = (w.depth[lap == k].mean(0) for k in (0, 1))
    seen = [w.rut_depth[lap == k].mean(0) for k in (0, 1)]
    assert np.all(second > first + 2e-3), (first, second)
    assert np.all(seen[1] > seen[0] + 0.02) and np.all(seen[1] > 0.03), seen
    assert float(r.rut_map.depth.max()) > float(first.max())


def test_outputs_and_a_map_ahead(rover, drive, straight):
    """`rollout` returns the map after the last step; `step` returns it third (shapes
    only: `jax.eval_shape`), and without a map returns (data, forces) with `rut_depth`
    and `depth` per wheel.  The rover put back at the start of its straight track meets
    the ruts it left there from its first step, its front wheels too, and the map keeps
    the deepest of both runs."""
    m, wheels, _ = rover
    _, _, r = straight
    assert r.rut_map.depth.shape == _map().depth.shape
    assert float(r.rut_map.depth.max()) > 0.1
    ctrl = smjx.rover_controls(0.0, jnp.full(4, 540.0))
    d1 = _moving(rover, 2.0, 0.2).replace(ctrl=ctrl)
    data, out, after = jax.eval_shape(lambda g: smjx.step(m, d1, wheels, SNOW, ruts=g), _map())
    assert after.depth.shape == _map().depth.shape and out.rut_depth.shape == (4,)
    data, out = jax.eval_shape(lambda d: smjx.step(m, d, wheels, SNOW), d1)
    assert out.rut_depth.shape == out.depth.shape == (4,)
    w, _, again = drive(d1, r.rut_map, ctrl, 1)
    assert np.all(w.status == Status.CONVERGED)
    assert np.all(w.rut_depth[0] > 0.1) and np.all(w.depth >= w.rut_depth)
    assert np.all(np.asarray(again.rut_map.depth) >= np.asarray(r.rut_map.depth))


def test_a_reversing_wheel_reads_the_rut_behind_it(rover, drive, straight):
    """At the end of the straight run the front wheels have virgin snow ahead; put in
    reverse there (1 m/s backwards, 300 N m backwards), every wheel reads its own track
    behind it: the front wheels run in the ruts from the first step."""
    _, wheels, _ = rover
    w, _, r = straight
    assert np.all(w.rut_depth[-1, :2] == 0.0)
    back = r.data.qvel.at[0].set(-1.0).at[np.asarray(wheels.dof_ids)].set(-1.0 / RADIUS)
    ctrl = smjx.rover_controls(0.0, jnp.full(4, -300.0))
    w, qpos, _ = drive(r.data.replace(qvel=back), r.rut_map, ctrl, 1)
    assert np.all(w.status == Status.CONVERGED)
    assert qpos[-1, 0] < qpos[0, 0] - 1.0  # it reverses along its track
    assert np.all(w.speed < 0) and np.all(w.rut_depth > 0.1)


def test_bad_input_raises(rover):
    m, wheels, d0 = rover
    coarse = sj.RutMap.empty(EXTENT, 0.3, K_0, A_U)  # sqrt(2) h = 0.42 m > the radius
    with pytest.raises(ValueError, match="lookahead must exceed"):
        smjx.step(m, d0, wheels, SNOW, ruts=coarse)
    with pytest.raises(ValueError, match="lookahead must exceed"):
        smjx.rollout(m, d0, wheels, SNOW, d0.ctrl, 2, ruts=coarse)
    with pytest.raises(TypeError, match="ruts must be None"):
        smjx.step(m, d0, wheels, SNOW, ruts=_map().depth)
    with pytest.raises(ValueError, match="solver_unroll"):
        smjx.step(m, d0, wheels, SNOW, solver_unroll=0)


@pytest.mark.slow  # a vmapped forward-mode rollout on maps (make test-slow)
def test_forward_gradients_through_the_map_vmapped_over_maps(rover, straight):
    """Two environments, each on its own map (virgin; the straight run's ruts), vmapped:
    d(end x)/d(p_w, k_0) through 40 steps (0.4 s) from 2 m/s, forward mode, against
    central differences within 1e-6 (measured: 2.5e-7 and 4.4e-8 for p_w, 1.6e-9 for
    k_0); k_0 acts only where there are ruts, and the ruts nearly double d(end x)/d p_w."""
    m, wheels, _ = rover
    _, _, r = straight
    maps = jax.tree.map(lambda a, b: jnp.stack([a, b]), _map(), r.rut_map)
    d1 = _moving(rover, 2.0, 0.2)
    ctrl = smjx.rover_controls(0.0, jnp.full(4, 540.0))

    def end(p, grid):
        snow = sj.WongSnow(p[0], SNOW.z_w, SNOW.cohesion, SNOW.tan_phi, SNOW.shear_modulus)
        grid = eqx.tree_at(lambda g: g.k_0, grid, p[1])
        return smjx.rollout(m, d1, wheels, snow, ctrl, 40, ruts=grid).qpos[-1, 0]

    @jax.jit
    def value_and_jacobian(p):
        def one(grid):
            along = lambda t: jax.jvp(lambda q: end(q, grid), (p,), (t,))  # noqa: E731
            return jax.vmap(along, out_axes=(None, 0))(jnp.eye(2))

        return jax.vmap(one)(maps)

    p = jnp.array([float(SNOW.p_w), K_0])
    _, jac = value_and_jacobian(p)
    jac = np.asarray(jac)  # jac[env, j] = d end / d p_j
    for j, h in ((0, 1e-4 * float(SNOW.p_w)), (1, 1e-4 * K_0)):
        fd = (np.asarray(value_and_jacobian(p.at[j].add(h))[0])
              - np.asarray(value_and_jacobian(p.at[j].add(-h))[0])) / (2 * h)  # fmt: skip
        np.testing.assert_allclose(jac[:, j], fd, rtol=1e-6)
    assert abs(jac[0, 1]) == 0.0 and abs(jac[1, 1]) > 0.0  # k_0 only on the ruts
    assert jac[1, 0] > 1.5 * jac[0, 0] > 0  # the ruts change d/dp_w


@pytest.mark.slow  # the rover's step with `Ruts` compiled (make test-slow)
def test_quasi_static_ruts_report_the_rut_and_the_depth(rover):
    """With `Ruts` (no map), driving straight at 2 m/s with the wheels at slip 0.2: a rear
    wheel's `rut_depth` is its front wheel's `depth` at once (the overlap is 1), and its
    `depth` and forces are `multi_pass`'s second pass at the two slips (1e-7; the front
    wheel runs on the virgin snow's closed form, as `multi_pass`'s first pass)."""
    m, wheels, _ = rover
    d = _moving(rover, 2.0, 0.2).replace(ctrl=smjx.rover_controls(0.0, jnp.full(4, 540.0)))
    _, out = jax.jit(lambda d: smjx.step(m, d, wheels, SNOW, ruts=sj.Ruts(K_0, A_U)))(d)
    out = jax.tree.map(np.asarray, out)
    assert np.all(out.status == Status.CONVERGED)
    np.testing.assert_array_equal(out.rut_depth[:2], 0.0)
    np.testing.assert_allclose(out.rut_depth[2:], out.depth[:2], rtol=1e-12)  # (overlap 1)
    np.testing.assert_array_equal(out.depth[:2], out.sinkage[:2])
    loads = np.asarray(wheels.static_load)
    for front, rear in ((0, 2), (1, 3)):
        passes = sj.multi_pass(
            wheels.wheel, SNOW, loads[[front, rear]], out.slip[[front, rear]], K_0, A_U
        )
        np.testing.assert_allclose(out.depth[[front, rear]], passes.sinkage, rtol=1e-7)
        np.testing.assert_allclose(out.longitudinal_force[rear], passes.drawbar_pull[1], rtol=1e-7)
        assert out.depth[rear] > out.sinkage[rear] + 0.05  # below the rut's floor
