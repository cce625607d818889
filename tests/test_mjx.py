"""snowjax wheel forces inside MuJoCo MJX (issue 14): `snowjax.mjx`.

Real MuJoCo MJX on CPU, float64.  Skipped only when the `mjx` extra is absent
(`pip install -e '.[mjx]'`; `make test` installs it).  The compiled rollouts are shared
through module-scoped fixtures; the snow parameters are traced, so every scenario with
the same shapes reuses one compile.
"""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

mujoco = pytest.importorskip("mujoco", reason="the snowjax[mjx] extra (mujoco) is not installed")
pytest.importorskip("mujoco.mjx", reason="the snowjax[mjx] extra (mujoco-mjx) is not installed")
from mujoco import mjx  # noqa: E402

import snowjax as sj  # noqa: E402
from snowjax import Status  # noqa: E402
from snowjax import mjx as smjx  # noqa: E402

SNOW = sj.WongSnow.thesis_fresh_snow()
WHEEL = sj.RigidWheel.thesis_tire()
TORQUE = 540.0  # [N m] per wheel
VEHICLE = sj.Vehicle(mass=1427.0, wheel_inertia=1.5, wheel=WHEEL, num_wheels=4)


def _snow(x):
    return sj.WongSnow(x[0], SNOW.z_w, SNOW.cohesion, x[1], SNOW.shear_modulus)


@pytest.fixture(scope="module")
def vehicle():
    model, wheels = smjx.load_vehicle()
    m = mjx.put_model(model)
    return model, m, wheels, mjx.make_data(m)


@pytest.fixture(scope="module")
def from_rest(vehicle):
    """3 s from rest at 540 N m per wheel, the loads of `sj.Vehicle` (600 steps)."""
    _, m, wheels, d0 = vehicle
    run = jax.jit(
        lambda x: smjx.rollout(m, d0, wheels, _snow(x), jnp.full(4, TORQUE), 600,
                               load=VEHICLE.wheel_load)
    )
    return run(jnp.array([SNOW.p_w, SNOW.tan_phi]))


def test_static_load_is_the_weight_share(vehicle):
    model, _, wheels, _ = vehicle
    total = sum(model.body_mass) * -model.opt.gravity[2]
    np.testing.assert_allclose(wheels.static_load, total / 4, rtol=1e-6)
    np.testing.assert_allclose(float(jnp.sum(wheels.static_load)), 1427.0 * 9.81, rtol=1e-6)


def test_matches_simulate_longitudinal(from_rest):
    """Same vehicle, snow, torque and loads: the same accelerating steady state."""
    r = from_rest
    traj = sj.simulate_longitudinal(VEHICLE, SNOW, TORQUE, t1=3.0, dt=0.05)
    late = slice(-100, None)  # the last 0.5 s
    slip = np.asarray(r.wheels.slip[late])
    assert np.ptp(slip) < 1e-6  # the steady state is reached and flat
    # Steady slip: both solve T - M_w(i) = I domega/dt, m dv/dt = sum F(i) (tolerance 1e-4).
    np.testing.assert_allclose(slip, float(traj.slip[-1, 0]), atol=1e-4)
    # Acceleration at that slip (MJX: finite differences of the axle speed).
    accel = np.diff(np.asarray(r.qvel[late, 0])) / 0.005
    sim_accel = float(np.sum(traj.drawbar_pull[-1])) / float(VEHICLE.mass)
    np.testing.assert_allclose(accel, sim_accel, rtol=1e-3)
    # Speed after 3 s: the transients from rest differ (MJX's chassis pitches on the
    # frictionless floor at start-up; implicit Euler at 0.05 s vs Euler at 0.005 s): 3 %.
    np.testing.assert_allclose(float(r.qvel[-1, 0]), float(traj.speed[-1]), rtol=3e-2)


def test_no_nan_from_rest(from_rest):
    r = from_rest
    for name in ("slip", "sinkage", "longitudinal_force", "resisting_torque", "entry_angle",
                 "spin_damping", "slip_angle"):
        assert np.all(np.isfinite(np.asarray(getattr(r.wheels, name)))), name
    assert np.all(np.isfinite(r.qpos)) and np.all(np.isfinite(r.qvel))
    assert np.all(np.asarray(r.wheels.status) == Status.CONVERGED)
    assert float(r.wheels.longitudinal_force[0, 0]) == 0.0  # at rest: no snow force
    assert float(r.qpos[-1, 0]) > 1.0  # it drives off
    assert abs(float(r.qpos[-1, 1])) < 1e-3  # and stays on the floor


@pytest.fixture(scope="module")
def short_rollout(vehicle):
    """0.2 s from 1 m/s, free rolling: distance and its forward-mode Jacobian."""
    _, m, wheels, d0 = vehicle
    qvel = d0.qvel.at[0].set(1.0).at[3:].set(1.0 / 0.368)
    d1 = d0.replace(qvel=qvel)

    def distance(x):
        return smjx.rollout(m, d1, wheels, _snow(x), jnp.full(4, TORQUE), 40).qpos[-1, 0]

    return jax.jit(distance), jax.jit(jax.jacfwd(distance))


@pytest.mark.slow  # about 90 s: forward mode through 2 x 40 MJX steps compiles slowly
def test_gradient_matches_central_differences(short_rollout):
    distance, jac = short_rollout
    x = jnp.array([SNOW.p_w, SNOW.tan_phi])
    g = np.asarray(jac(x))
    assert np.all(np.isfinite(g))
    for k, rel in ((0, 1e-4), (1, 1e-3)):
        h = rel * float(x[k])
        fd = (float(distance(x.at[k].add(h))) - float(distance(x.at[k].add(-h)))) / (2 * h)
        assert abs(fd) > 1e-9
        np.testing.assert_allclose(g[k], fd, rtol=1e-3)


def test_bad_input_raises(vehicle):
    model, m, wheels, d0 = vehicle
    with pytest.raises(ValueError, match="no body named"):
        smjx.MjxWheels.from_model(model, ["nope"])
    with pytest.raises(ValueError, match="exactly one joint"):
        smjx.MjxWheels.from_model(model, ["chassis"])
    with pytest.raises(ValueError, match="radius"):
        smjx.MjxWheels.from_model(model, ["wheel_fl"], sj.RigidWheel(1.0, 0.2))
    with pytest.raises(TypeError, match="MjModel"):
        smjx.MjxWheels.from_model(m, ["wheel_fl"])
    frictional = mujoco.MjModel.from_xml_path(smjx.vehicle_model_path())
    frictional.geom_condim[0] = 3  # the floor
    with pytest.raises(ValueError, match="condim"):
        smjx.MjxWheels.from_model(frictional, smjx.WHEEL_BODIES)
    with pytest.raises(TypeError, match="WongSnow"):
        smjx.step(m, d0, wheels, "snow")
    with pytest.raises(ValueError, match="load"):
        smjx.step(m, d0, wheels, SNOW, load="floor")
    rk4 = mujoco.MjModel.from_xml_path(smjx.vehicle_model_path())
    rk4.opt.integrator = mujoco.mjtIntegrator.mjINT_RK4
    with pytest.raises(ValueError, match="Euler"):
        smjx.step(mjx.put_model(rk4), d0, wheels, SNOW)
    with pytest.raises(ValueError, match="ctrl"):
        smjx.rollout(m, d0, wheels, SNOW, jnp.zeros(3), 2)
