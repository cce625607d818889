"""snowjax wheel forces inside MuJoCo MJX (issue 14): `snowjax.mjx`.

Real MuJoCo MJX on CPU, float64.  Skipped only when the `mjx` extra is absent
(`pip install -e '.[mjx]'`; `make test` installs it).  The compiled rollouts are shared
through module-scoped fixtures; the snow parameters are traced, so every scenario with
the same shapes reuses one compile.
"""

import os
import pathlib

import jax
import jax.numpy as jnp
import numpy as np
import pytest

try:
    import mujoco
    from mujoco import mjx
except ImportError:  # the extra is absent: a skip locally, a failure in CI
    if os.environ.get("CI", "").lower() == "true":
        raise
    pytest.skip(
        "the snowjax[mjx] extra (mujoco, mujoco-mjx) is not installed", allow_module_level=True
    )

import snowjax as sj  # noqa: E402
from snowjax import Status  # noqa: E402
from snowjax import mjx as smjx  # noqa: E402

from .notebook_runner import outputs_text, run_notebook  # noqa: E402
from .test_sim import LOAD, VEHICLE, _parameters, _run  # noqa: E402

SNOW = sj.WongSnow.thesis_fresh_snow()
TORQUE = 540.0  # [N m] per wheel
README = pathlib.Path(__file__).resolve().parents[1] / "README.md"


def _snow(x):
    return sj.WongSnow(x[0], SNOW.z_w, SNOW.cohesion, x[1], SNOW.shear_modulus)


def _readme_example():
    """The Python block of the README's MuJoCo MJX section, as written there."""
    text = README.read_text(encoding="utf-8")
    section = text.split("## MuJoCo MJX", 1)[1]
    return section.split("```python\n", 1)[1].split("```", 1)[0]


@pytest.fixture(scope="module")
def vehicle():
    model, wheels = smjx.load_vehicle()
    m = mjx.put_model(model)
    return model, m, wheels, mjx.make_data(m)


@pytest.fixture(scope="module")
def from_rest():
    """The README's example, run as written: 3 s from rest at 540 N m per wheel."""
    namespace = {}
    exec(compile(_readme_example(), "README.md (MuJoCo MJX)", "exec"), namespace)  # noqa: S102
    return namespace["r"]


def test_static_load_is_the_weight_share(vehicle):
    model, _, wheels, _ = vehicle
    total = sum(model.body_mass) * -model.opt.gravity[2]
    # Measured by MuJoCo after 2 s of settling (the contact's residual motion: 1e-5).
    np.testing.assert_allclose(wheels.static_load, total / 4, rtol=3e-5)
    np.testing.assert_allclose(wheels.static_load, LOAD, rtol=3e-5)  # 3,500 N, as test_sim


def test_matches_simulate_longitudinal(from_rest):
    """The same wheel load, mass per wheel, inertia, snow and torque as `tests/test_sim.py`'s
    shared 2-wheel program (`_run`; reused, so its compile is shared): the same
    accelerating steady state."""
    r = from_rest
    traj, _ = _run(_parameters(SNOW, [TORQUE] * 3), 0.0)  # from rest, dt = 0.05 s
    late = slice(-100, None)  # the last 0.5 s of the 3 s
    slip = np.asarray(r.wheels.slip[late])
    assert np.ptp(slip) < 1e-6  # the steady state is reached and flat
    k = int(np.argmin(np.abs(np.asarray(traj.time) - 3.0)))  # t = 3 s
    assert abs(float(traj.time[k]) - 3.0) < 1e-9
    # Steady slip: both solve T - M_w(i) = I domega/dt, m dv/dt = sum F(i).
    np.testing.assert_allclose(slip, float(traj.slip[k, 0]), atol=1e-4)
    # Acceleration at that slip (MJX: finite differences of the axle speed).
    accel = np.diff(np.asarray(r.qvel[late, 0])) / 0.005
    sim_accel = float(np.sum(traj.drawbar_pull[k])) / float(VEHICLE.mass)
    np.testing.assert_allclose(accel, sim_accel, rtol=1e-3)
    # Speed after 3 s: the transients from rest differ (MJX's chassis pitches on the
    # frictionless floor at start-up; implicit Euler at 0.05 s vs Euler at 0.005 s): 3 %.
    np.testing.assert_allclose(float(r.qvel[-1, 0]), float(traj.speed[k]), rtol=3e-2)


def test_no_nan_from_rest(from_rest):
    r = from_rest
    for name in ("slip", "sinkage", "longitudinal_force", "resisting_torque", "entry_angle",
                 "spin_damping", "slip_angle"):  # fmt: skip
        assert np.all(np.isfinite(np.asarray(getattr(r.wheels, name)))), name
    assert np.all(np.isfinite(r.qpos)) and np.all(np.isfinite(r.qvel))
    assert np.all(np.asarray(r.wheels.status) == Status.CONVERGED)
    assert float(r.wheels.longitudinal_force[0, 0]) == 0.0  # at rest: no snow force
    assert float(r.qpos[-1, 0]) > 1.0  # it drives off
    assert abs(float(r.qpos[-1, 1])) < 1e-3  # and stays on the floor


@pytest.fixture(scope="module")
def short_rollout(vehicle):
    """0.2 s from rest, loads from MuJoCo's floor contact (load transfer included): the
    distance and its forward-mode derivatives w.r.t. (p_w, tan phi).

    One compiled function returns both (the jvp vmapped over the two directions), so the
    central differences below reuse the compile."""
    _, m, wheels, d0 = vehicle

    def distance(x):
        r = smjx.rollout(m, d0, wheels, _snow(x), jnp.full(4, TORQUE), 40, load="contact")
        return r.qpos[-1, 0], r.wheels.load

    def value_and_derivatives(x):
        def along(direction):
            return jax.jvp(distance, (x,), (direction,))

        (value, loads), (tangent, _) = jax.vmap(along, out_axes=(None, 0))(jnp.eye(2))
        return value, tangent, loads

    return jax.jit(value_and_derivatives)


def test_contact_loads_carry_the_weight(short_rollout):
    _, _, loads = short_rollout(jnp.array([SNOW.p_w, SNOW.tan_phi]))
    loads = np.asarray(loads)
    assert np.all(loads[0] == 0.0)  # step 0 reads the contacts of make_data (none yet)
    # After the start-up transient (the chassis settles and pitches) the floor carries
    # the weight; the drive torques pitch the chassis back, so the rear wheels carry more.
    np.testing.assert_allclose(loads[-1].sum(), 4 * LOAD, rtol=1e-3)
    assert np.all(loads[-1, 2:] > loads[-1, :2] + 500.0)


def test_gradient_from_rest_matches_central_differences(short_rollout):
    """Through 40 MJX steps from rest with contact loads (measured: 2e-6 and 4e-5)."""
    x = jnp.array([SNOW.p_w, SNOW.tan_phi])
    _, g, _ = short_rollout(x)
    g = np.asarray(g)
    assert np.all(np.isfinite(g))  # no overflow at rest (the slip's floor, issue 14)
    for k, rel in ((0, 1e-4), (1, 1e-3)):
        h = rel * float(x[k])
        plus = float(short_rollout(x.at[k].add(h))[0])
        minus = float(short_rollout(x.at[k].add(-h))[0])
        fd = (plus - minus) / (2 * h)
        assert abs(fd) > 1e-9
        np.testing.assert_allclose(g[k], fd, rtol=1e-3)


@pytest.mark.slow  # the reverse-mode compile through MJX takes one to two minutes
def test_reverse_mode_with_one_solver_iteration():
    """jax.grad through `rollout`: MJX allows reverse mode with opt.iterations = 1."""
    model, wheels = smjx.load_vehicle()
    model.opt.iterations = 1
    m = mjx.put_model(model)
    d0 = mjx.make_data(m)
    d1 = d0.replace(qvel=d0.qvel.at[0].set(1.0).at[3:].set(1.0 / 0.368 / 0.8))

    def speed(p_w):
        snow = sj.WongSnow(p_w, SNOW.z_w, SNOW.cohesion, SNOW.tan_phi, SNOW.shear_modulus)
        return smjx.rollout(m, d1, wheels, snow, jnp.full(4, TORQUE), 5).qvel[-1, 0]

    value_and_grad = jax.jit(jax.value_and_grad(speed))
    _, g = value_and_grad(SNOW.p_w)
    h = 1e-4 * float(SNOW.p_w)
    fd = (value_and_grad(SNOW.p_w + h)[0] - value_and_grad(SNOW.p_w - h)[0]) / (2 * h)
    np.testing.assert_allclose(float(g), float(fd), rtol=3e-3)


PLATE = sj.WongSnow.thesis_plate_rule_snow()  # drawbar pull < 0 at slip 1 (and bottomed out)


@pytest.fixture(scope="module")
def plate_runs(vehicle):
    """1 s (200 steps) on the plate-rule snow from three states, one compiled rollout:
    540 N m per wheel from rest; -540 N m per wheel from 5 m/s; coasting from 5 m/s with
    the wheels spinning backwards (rim speed -3 m/s)."""
    _, m, wheels, d0 = vehicle
    run = jax.jit(
        lambda qvel, ctrl: smjx.rollout(m, d0.replace(qvel=qvel), wheels, PLATE, ctrl, 200)
    )
    spin = 1 / float(wheels.wheel.diameter / 2)
    starts = {
        "driven": (0.0, 0.0, TORQUE),
        "braked": (5.0, 5.0 * spin, -TORQUE),
        "coasting": (5.0, -3.0 * spin, 0.0),
    }
    return {
        name: run(d0.qvel.at[0].set(v).at[3:].set(w), jnp.full(4, torque))
        for name, (v, w, torque) in starts.items()
    }


def test_snow_never_delivers_power_and_never_pushes_a_braked_vehicle(plate_runs):
    """The snow's power on every wheel, `F v - M_w omega`, is never positive; a wheel
    locked or spinning against its motion never pushes along it; the driven vehicle never
    goes backwards (it went 76 m backwards in 10 s on the layered snow) and the braked and
    coasting ones never speed up."""
    for name, r in plate_runs.items():
        w = r.wheels
        assert np.all(np.asarray(w.status) != Status.INVALID_INPUT), name
        axle = np.asarray(w.longitudinal_force * w.speed)
        spin = np.asarray(-w.resisting_torque * w.wheel_speed)
        assert np.all(axle + spin <= 1e-12 * (np.abs(axle) + np.abs(spin))), name
        against = np.asarray(w.speed * w.wheel_speed) <= 0
        assert np.all(axle[against] <= 0.0), name
        assert np.all(np.isfinite(r.qpos)) and np.all(np.isfinite(r.qvel)), name
    assert float(np.min(plate_runs["driven"].qpos[:, 0])) > -1e-3
    for name in ("braked", "coasting"):
        speed = np.asarray(plate_runs[name].qvel[:, 0])
        assert np.all(np.diff(speed) <= 1e-9), name
        assert speed[-1] < 5.0, name


def test_traced_bad_prescribed_loads_are_flagged(vehicle):
    """Under jit a negative or NaN prescribed load gives its wheel no snow force and
    `Status.INVALID_INPUT`; the other wheels are solved."""
    _, m, wheels, d0 = vehicle
    d1 = d0.replace(qvel=d0.qvel.at[0].set(1.0).at[3:].set(1.0 / 0.368))
    out = jax.jit(lambda load: smjx.step(m, d1, wheels, SNOW, load=load)[1])(
        jnp.array([-100.0, 3500.0, jnp.nan, 3500.0])
    )
    status = np.asarray(out.status)
    assert list(status) == [Status.INVALID_INPUT, Status.CONVERGED] * 2
    assert np.all(np.asarray(out.longitudinal_force)[[0, 2]] == 0.0)
    assert np.all(np.isfinite(np.asarray(out.longitudinal_force)))


# The longest test of `make test` (51 s of a worker on 2 cores, 43 s of it compiling the
# vmapped forward-mode rollout in the notebook's kernel): `make test-all` runs it.
@pytest.mark.slow
def test_notebook_runs(tmp_path):
    nb = run_notebook("mjx_vehicle.ipynb", tmp_path)
    text = outputs_text(nb)
    assert "d distance / d p_w" in text
    assert "firm: distance" in text


def test_a_contact_model_traces_the_same_step(vehicle):
    """`ContactModel` in place of the terrain: the traced step is the one of the separate
    keywords (compared as jaxprs: no compile needed)."""
    _, m, wheels, d0 = vehicle
    plate = sj.WongReece(0.4, 0.3, -0.1)

    def forces(snow, **keywords):
        return smjx.step(m, d0, wheels, snow, **keywords)[1].longitudinal_force

    # The distribution as an argument in both, so that its leaves are inputs of both.
    by_keywords = jax.make_jaxpr(lambda s, p: forces(s, distribution=p))(SNOW, plate)
    by_model = jax.make_jaxpr(lambda s, p: forces(sj.ContactModel(s, p)))(SNOW, plate)
    assert str(by_model) == str(by_keywords)
    model = sj.ContactModel(SNOW, plate)
    with pytest.raises(TypeError, match="distribution given both"):
        forces(model, distribution=plate)


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
    with pytest.raises(TypeError, match="terrain"):
        smjx.step(m, d0, wheels, "snow")
    with pytest.raises(ValueError, match="load"):
        smjx.step(m, d0, wheels, SNOW, load="floor")
    rk4 = mujoco.MjModel.from_xml_path(smjx.vehicle_model_path())
    rk4.opt.integrator = mujoco.mjtIntegrator.mjINT_RK4
    with pytest.raises(ValueError, match="Euler"):
        smjx.step(mjx.put_model(rk4), d0, wheels, SNOW)
    with pytest.raises(ValueError, match="ctrl"):
        smjx.rollout(m, d0, wheels, SNOW, jnp.zeros(3), 2)
    # Concrete bad snows and prescribed loads raise before anything is traced (a NaN snow
    # gave NaN forces, a negative load zero forces with status CONVERGED).
    with pytest.raises(ValueError, match="snow.p_w must be finite"):
        smjx.step(m, d0, wheels, sj.WongSnow(np.nan, 0.2, 1e3, 0.1, 0.01))
    with pytest.raises(ValueError, match=r"load must be finite and >= 0 N"):
        smjx.step(m, d0, wheels, SNOW, load=jnp.array([-100.0, 3500.0, 3500.0, 3500.0]))
    with pytest.raises(ValueError, match="simplified"):
        smjx.step(m, d0, wheels, SNOW, shear="simplified")
