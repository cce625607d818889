"""Vehicles in their own ruts (`snowjax.Ruts`): in `simulate_longitudinal`,
`simulate_planar` and `snowjax.mjx.rollout` the rear wheels' sinkage and forces follow
`multi_pass` at the slips the simulation reached; a turning vehicle's rear wheels leave
the front ruts by the offset of `track_offset` (checked against circle geometry).  With
`ruts=None` the simulations are the existing ones (their own tests).

`make test` runs the three simulations' force functions (the code their steps call);
the full `simulate_longitudinal`, `simulate_planar` and MJX rollouts are `slow` cases (a
simulation's compile takes 15-25 s here)."""

from __future__ import annotations

import dataclasses

import diffrax
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import snowjax as sj
from snowjax import Status

WHEEL = sj.RigidWheel.thesis_tire()
SNOW = sj.WongSnow.thesis_fresh_snow()
RUTS = sj.Ruts(1e6, 5e6)  # k_0 [Pa/m], A_u [Pa/m^2] (illustrative, as in test_rut.py)
LOAD = 3500.0  # [N] per wheel


def _rear_follows_multi_pass(loads, slips, rear_pull, rear_torque, rear_sinkage, front_sinkage):
    """The rear wheel's drawbar pull, torque and depth equal pass 2 of `multi_pass` at
    the simulated slips (front, rear) within 1e-7 (the simulation's wheel solves are
    converged to 1e-9 in ln W), and differ from the same wheel on virgin snow."""
    passes = sj.multi_pass(WHEEL, SNOW, jnp.asarray(loads), jnp.asarray(slips), RUTS.k_0, RUTS.a_u)
    assert np.all(np.asarray(passes.status) == Status.CONVERGED)
    scale = float(passes.motion_resistance[0])
    np.testing.assert_allclose(rear_pull, passes.drawbar_pull[1], rtol=0, atol=1e-7 * scale)
    np.testing.assert_allclose(rear_torque, passes.torque[1], rtol=1e-7)
    np.testing.assert_allclose(front_sinkage, passes.sinkage[0], rtol=1e-7)
    rut = sj.Rut(SNOW, passes.sinkage[0], WHEEL.width, RUTS.k_0, RUTS.a_u)
    np.testing.assert_allclose(rear_sinkage + rut.floor_depth, passes.sinkage[1], rtol=1e-7)
    virgin = sj.solve_wheel(WHEEL, SNOW, loads[1], slips[1])
    # The front/rear difference: the rear wheel in the rut pulls measurably otherwise.
    assert abs(float(virgin.drawbar_pull) - rear_pull) > 0.05 * scale
    return passes


def test_longitudinal_wheel_forces_put_the_rear_wheel_in_the_front_wheels_rut():
    """The longitudinal simulation's force function with `Ruts` (default layout of a
    tandem: wheel 1 behind wheel 0) at two states: the rear wheel is `multi_pass`'s
    second pass at the slips of its kinematics, the front wheel its first."""
    from snowjax._sim.vehicle import _wheel_forces

    contact = sj.ContactModel(SNOW)
    ruts = sj.Ruts(RUTS.k_0, RUTS.a_u, RUTS.layout(2))
    speed = jnp.array([[2.0], [1.0]])
    radius = float(WHEEL.diameter) / 2
    omega = speed / radius / jnp.array([[0.8, 0.9], [0.5, 0.6]])  # slips 0.2 / 0.1, ...
    f = jax.jit(lambda v, w: _wheel_forces(v, w, LOAD, WHEEL, contact, 0.05, None, 64, ruts))(
        speed, omega
    )
    assert np.all(np.asarray(f.status) == Status.CONVERGED)
    for k in range(2):
        passes = _rear_follows_multi_pass(
            [LOAD, LOAD],
            np.asarray(f.slip[k]),
            float(f.longitudinal_force[k, 1]),
            float(f.resisting_torque[k, 1]),
            float(f.sinkage[k, 1]),
            float(f.sinkage[k, 0]),
        )
        scale = float(passes.motion_resistance[0])
        np.testing.assert_allclose(
            f.longitudinal_force[k, 0], passes.drawbar_pull[0], rtol=0, atol=1e-7 * scale
        )


@pytest.mark.slow
def test_longitudinal_rear_wheel_runs_in_the_front_wheels_rut():
    """A tandem (2 wheels, 3.5 kN each, 600 N m on each) from 1 m/s for 2 s."""
    vehicle = sj.Vehicle(mass=2 * LOAD / 9.80665, wheel_inertia=1.5, wheel=WHEEL, num_wheels=2)
    traj = sj.simulate_longitudinal(
        vehicle,
        SNOW,
        600.0,
        2.0,
        0.05,
        ruts=RUTS,
        initial=sj.InitialState(speed=1.0),
        stepping=sj.Stepping(save_every=40),
    )
    assert traj.result == diffrax.RESULTS.successful
    assert np.all(np.asarray(traj.status) == Status.CONVERGED)
    slips = np.asarray(traj.slip[-1])
    passes = _rear_follows_multi_pass(
        [LOAD, LOAD],
        slips,
        float(traj.drawbar_pull[-1, 1]),
        float(traj.resisting_torque[-1, 1]),
        float(traj.sinkage[-1, 1]),
        float(traj.sinkage[-1, 0]),
    )
    # The front wheel is on virgin snow: its own forces are solve_wheel's.
    scale = float(passes.motion_resistance[0])
    np.testing.assert_allclose(
        traj.drawbar_pull[-1, 0], passes.drawbar_pull[0], rtol=0, atol=1e-7 * scale
    )


def test_track_offset_is_the_difference_of_the_radii_about_the_turning_centre():
    rng = np.random.default_rng(3)
    for _ in range(20):
        centre, lead, follow = rng.normal(size=(3, 2)) * [[5.0], [1.0], [1.0]]
        r = rng.normal()
        v = r * np.array([-(lead - centre)[1], (lead - centre)[0]])  # r z x (p - c)
        expected = abs(np.linalg.norm(follow - centre) - np.linalg.norm(lead - centre))
        np.testing.assert_allclose(sj.track_offset(lead, follow, v, r), expected, rtol=1e-10)
    # Straight: the follower's distance from the leader's line of motion; at rest 0.
    np.testing.assert_allclose(sj.track_offset([0.0, 0.0], [-2.0, 0.3], [1.5, 0.0], 0.0), 0.3)
    assert float(sj.track_offset([0.0, 0.0], [-2.0, 0.3], [0.0, 0.0], 0.0)) == 0.0
    # The share of a follower's width over its leader's rut (offset, width, rut width):
    # equal widths, a narrower wheel inside, a wider one, one beside the rut.
    overlap = sj._wheel.passes._overlap
    cases = [(0.05, 0.2, 0.2, 0.75), (0.02, 0.1, 0.3, 1.0), (0.0, 0.4, 0.2, 0.5),
             (0.1, 0.4, 0.2, 0.5), (0.25, 0.2, 0.4, 0.25), (0.5, 0.2, 0.2, 0.0)]  # fmt: skip
    for offset, width, rut, share in cases:
        np.testing.assert_allclose(overlap(offset, width, rut), share, rtol=1e-12)


MASS = 4 * LOAD / 9.80665
PLANAR = sj.PlanarVehicle(MASS, MASS * (2.5**2 + 1.5**2) / 12, 1.5, WHEEL, 2.5, 1.5)


@pytest.mark.slow  # the planar forces on ruts (make test-slow)
def test_planar_wheel_forces_put_the_rear_wheels_in_the_front_ruts():
    """The planar simulation's force function with `Ruts` at three states (one vmapped
    solve): driving straight at slips 0.2 / 0.1, the rear wheels are `multi_pass`'s
    second pass; turning at 1.5 m/s with yaw rates giving 40 % and 0 % overlap (offsets
    of the rear wheels' paths from the front wheels', `track_offset`), the rear wheels
    under their slip angles see that share of the rut, and none on virgin snow."""
    from snowjax._sim.planar import _planar_wheel_forces, _rut_overlap

    radius = float(WHEEL.diameter) / 2
    u = jnp.array([2.0, 1.5, 1.5])
    r = jnp.array([0.0, 0.06, 0.5])  # [rad/s]: straight, radius 25 m, 3 m
    steer = jax.vmap(PLANAR.steer_angles)(jnp.arctan(2.5 * r / u))  # Ackermann, (3, 4)
    omega = jnp.stack([u / (0.8 * radius)] * 2 + [u / (0.9 * radius)] * 2, -1)
    ruts = sj.Ruts(RUTS.k_0, RUTS.a_u, (-1, -1, 0, 1))
    contact = sj.ContactModel(SNOW, None, "classic", sj.Lateral())
    v = 1.25 * r  # the centre of gravity's side speed with the rear axle on the radius

    @jax.jit
    def forces(u, v, r, omega, steer):
        return _planar_wheel_forces(PLANAR, contact, u, v, r, omega, steer, 0.05, None, 64, ruts)

    f = jax.vmap(forces)(u, v, r, omega, steer)
    assert np.all(np.asarray(f.status) == Status.CONVERGED)
    overlap = np.asarray(_rut_overlap(PLANAR, u, v, r, (-1, -1, 0, 1)))
    np.testing.assert_allclose(overlap[0], 1.0, atol=1e-12)
    assert 0.2 < overlap[1, 2] < 0.8 and overlap[2, 2] == 0.0
    _rear_follows_multi_pass(
        [LOAD, LOAD],
        np.asarray(f.slip[0, ::2]),
        float(f.drawbar_pull[0, 2]),
        float(f.resisting_torque[0, 2]),
        float(f.sinkage[0, 2]),
        float(f.sinkage[0, 0]),
    )
    # Turning: each rear wheel on the rut of its front wheel's depth times its overlap
    # (in the sharp turn a rut of zero depth: the virgin law, `test_rut.py`).
    depth = overlap[1:, 2:] * np.asarray(f.sinkage[1:, :2])
    rut = sj.Rut(SNOW, depth, WHEEL.width, RUTS.k_0, RUTS.a_u)
    rear = sj.solve_wheel(WHEEL, rut, LOAD, f.slip[1:, 2:], slip_angle=f.slip_angle[1:, 2:])
    np.testing.assert_allclose(f.drawbar_pull[1:, 2:], rear.drawbar_pull, rtol=1e-7)
    np.testing.assert_allclose(f.lateral_force[1:, 2:], rear.lateral_force, rtol=1e-7)
    assert np.all(depth[0] > 0.2 * np.asarray(f.sinkage[1, :2])) and np.all(depth[1] == 0)


@pytest.mark.slow
def test_planar_rear_wheels_follow_the_front_ruts_and_leave_them_in_a_turn():
    """Straight (delta = 0), a gentle turn (0.1 rad) and a sharp one (0.3 rad) at 300 N m
    per wheel from 1.5 m/s for 2 s (one vmapped program): straight, the rear wheels are
    `multi_pass`'s second pass; in the sharp turn their offset exceeds the wheel's width
    and they run on virgin snow (`solve_wheel` with their slip angle)."""
    vehicle = PLANAR

    def run(steer):
        return sj.simulate_planar(
            vehicle,
            SNOW,
            steer,
            300.0,
            2.0,
            0.05,
            ruts=RUTS,
            initial=sj.InitialState(speed=1.5),
            stepping=sj.Stepping(save_every=40),
        )

    traj = jax.jit(jax.vmap(run))(jnp.array([0.0, 0.1, 0.3]))
    assert np.all(np.asarray(traj.status) == Status.CONVERGED)
    assert np.all(traj.result == diffrax.RESULTS.successful)
    last = jax.tree.map(lambda x: np.asarray(x)[:, -1], dataclasses.replace(traj, result=None))
    _rear_follows_multi_pass(
        [LOAD, LOAD],
        last.slip[0, ::2],
        last.drawbar_pull[0, 2],
        last.resisting_torque[0, 2],
        last.sinkage[0, 2],
        last.sinkage[0, 0],
    )
    overlap = sj._sim.planar._rut_overlap(
        vehicle, last.speed, last.lateral_speed, last.yaw_rate, (-1, -1, 0, 1)
    )
    np.testing.assert_allclose(overlap[0], 1.0, atol=1e-12)
    assert 0.2 < float(overlap[1, 2]) < 0.9 and float(overlap[2, 2]) == 0.0
    virgin = sj.solve_wheel(WHEEL, SNOW, LOAD, last.slip[2, 2], slip_angle=last.slip_angle[2, 2])
    # (A rut of zero depth is the virgin law through the generic quadrature, which agrees
    # with Wong snow's closed-form front region within its accuracy.)
    np.testing.assert_allclose(last.drawbar_pull[2, 2], virgin.drawbar_pull, rtol=1e-6)
    np.testing.assert_allclose(last.sinkage[2, 2], virgin.sinkage, rtol=1e-7)
    # In the gentle turn the rear wheels are partly in the ruts: shallower than virgin.
    assert float(last.sinkage[1, 2]) < float(last.sinkage[2, 2])


@pytest.mark.slow  # the rover's step on ruts (make test-slow)
def test_mjx_snow_forces_put_the_rear_wheels_in_the_front_wheels_ruts():
    """`snowjax.mjx`'s force function (what `step` calls after MJX's velocity stage) with
    `Ruts`, the shipped rover at 2 m/s with its wheels at slip 0.2: the rear wheels'
    forces are `multi_pass`'s second pass at their slips and static loads."""
    pytest.importorskip("mujoco")
    from mujoco import mjx

    import snowjax.mjx as smjx
    from snowjax._mjx.step import _snow_forces
    from snowjax._sim.planar import _steered_model

    model, wheels = smjx.load_rover()
    m = mjx.put_model(model)
    d = mjx.make_data(m)
    omega = 2.0 / (float(WHEEL.diameter) / 2 * 0.8)
    d = d.replace(qvel=d.qvel.at[0].set(2.0).at[np.asarray(wheels.dof_ids)].set(omega))
    ruts = sj.Ruts(RUTS.k_0, RUTS.a_u, RUTS.layout(4))

    @jax.jit
    def forces(d):
        d = mjx.fwd_velocity(m, mjx.fwd_position(m, d))
        load = wheels.static_load
        contact = _steered_model(SNOW, "the test")
        return _snow_forces(m, d, wheels, contact, None, load, 0.05, ruts)[-1]

    out = jax.tree.map(np.asarray, forces(d))
    assert np.all(out.status == Status.CONVERGED)
    loads = np.asarray(wheels.static_load)
    passes = sj.multi_pass(WHEEL, SNOW, loads[::2], out.slip[::2], RUTS.k_0, RUTS.a_u)
    np.testing.assert_allclose(out.longitudinal_force[2], passes.drawbar_pull[1], rtol=1e-7)
    np.testing.assert_allclose(out.resisting_torque[2], passes.torque[1], rtol=1e-7)
    np.testing.assert_allclose(out.longitudinal_force[0], passes.drawbar_pull[0], rtol=1e-6)
    assert out.spin_damping[2] > 0 and np.isfinite(out.spin_damping).all()


@pytest.mark.slow
def test_mjx_rear_wheels_run_in_the_front_wheels_ruts():
    pytest.importorskip("mujoco")
    from mujoco import mjx

    import snowjax.mjx as smjx

    model, wheels = smjx.load_rover()
    m = mjx.put_model(model)
    d = mjx.make_data(m)
    d = d.replace(qvel=d.qvel.at[0].set(1.0))
    ctrl = smjx.rover_controls(0.0, jnp.full(4, 500.0))
    out = jax.jit(lambda d: smjx.rollout(m, d, wheels, SNOW, ctrl, 40, ruts=RUTS).wheels)(d)
    last = jax.tree.map(lambda x: np.asarray(x)[-1], out)
    assert np.all(last.status == Status.CONVERGED)
    loads = np.asarray(wheels.static_load)
    passes = sj.multi_pass(WHEEL, SNOW, loads[::2], last.slip[::2], RUTS.k_0, RUTS.a_u)
    # The shipped rover's wheels: front left, front right, rear left, rear right.
    np.testing.assert_allclose(last.longitudinal_force[2], passes.drawbar_pull[1], rtol=1e-7)
    np.testing.assert_allclose(last.resisting_torque[2], passes.torque[1], rtol=1e-7)
    virgin = sj.wheel_forces(last.speed[2], last.wheel_speed[2], loads[2], WHEEL, SNOW)
    assert abs(float(virgin.resisting_torque) - last.resisting_torque[2]) > 0.05 * abs(
        float(virgin.resisting_torque)
    )
