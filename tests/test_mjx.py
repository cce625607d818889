"""snowjax wheel forces inside MuJoCo MJX on a 3-D rover (issues 14, 35): `snowjax.mjx`.

Real MuJoCo MJX on CPU, float64.  Skipped only when the `mjx` extra is absent
(`pip install -e '.[mjx]'`; `make test` installs it, and CI fails without it).  The
compiled rollouts are shared through module-scoped fixtures: the initial velocities,
controls and snow are arguments, so the straight run, the turn and the braking runs
reuse one compile.
"""

import importlib.metadata
import pathlib
import re

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from .extras import require_extra

require_extra("mjx", "mujoco", "mujoco.mjx")

import mujoco  # noqa: E402
from mujoco import mjx  # noqa: E402

import snowjax as sj  # noqa: E402
from snowjax import Status  # noqa: E402
from snowjax import mjx as smjx  # noqa: E402
from snowjax._mjx.step import _dissipative, _solve_dense  # noqa: E402

from .notebook_runner import outputs_text, run_notebook  # noqa: E402
from .test_sim import LOAD, VEHICLE, _parameters, _run  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parents[1]
SNOW = sj.WongSnow.thesis_fresh_snow()
TORQUE = 540.0  # [N m] per wheel
STEPS = 600  # 3 s at 5 ms
RADIUS = 0.368  # [m]


def _readme_example():
    """The first Python block of the guide's MuJoCo page, as written there."""
    text = (ROOT / "docs" / "guide" / "mjx.md").read_text(encoding="utf-8")
    return text.split("```python\n", 1)[1].split("```", 1)[0]


@pytest.fixture(scope="module")
def rover():
    model, wheels = smjx.load_rover()
    m = mjx.put_model(model)
    return model, m, wheels, mjx.make_data(m)


@pytest.fixture(scope="module")
def readme():
    """The guide's example, run as written: 3 s from rest at 540 N m per wheel; its
    jitted `run(snow, ctrl, qvel)` is reused by the other scenarios (one compile)."""
    namespace = {}
    exec(compile(_readme_example(), "docs/guide/mjx.md", "exec"), namespace)  # noqa: S102
    return namespace


@pytest.fixture(scope="module")
def from_rest(readme):
    return readme["r"]


@pytest.fixture(scope="module")
def run(readme):
    """(initial qvel, ctrl, snow) -> 3 s `Rollout` of the guide's compiled `run`."""
    return lambda qvel, ctrl, snow: readme["run"](snow, ctrl, qvel)


def _moving(rover, speed, slip):
    """qvel of the rover driving straight along +x at `speed`, wheels at `slip`."""
    _, _, wheels, d0 = rover
    spin = speed / (RADIUS * (1 - slip))
    return d0.qvel.at[0].set(speed).at[np.asarray(wheels.dof_ids)].set(spin)


def test_the_installed_mujoco_satisfies_the_extra_and_works(rover):
    """A wrong pin fails here: the installed mujoco and mujoco-mjx are those the `mjx`
    extra allows, and MJX steps the shipped model (put_model, make_data, step)."""
    from packaging.requirements import Requirement

    text = (ROOT / "pyproject.toml").read_text(encoding="utf-8")
    extra = text.split("\nmjx = [", 1)[1].split("]", 1)[0]
    requirements = [Requirement(r) for r in re.findall(r'"([^"]+)"', extra)]
    assert {r.name for r in requirements} == {"mujoco", "mujoco-mjx"}
    for r in requirements:
        version = importlib.metadata.version(r.name)
        assert r.specifier.contains(version, prereleases=True), (r, version)
    _, m, _, d0 = rover
    d1 = jax.jit(mjx.step)(m, d0)
    assert np.all(np.isfinite(np.asarray(d1.qpos)))


def test_public_mujoco_api_only():
    """No private MuJoCo attribute (`._impl`, `mujoco.mjx._src`) in the bridge."""
    sources = [ROOT / "snowjax" / "mjx.py", *(ROOT / "snowjax" / "_mjx").glob("*.py")]
    for path in sources:
        text = path.read_text(encoding="utf-8")
        assert "._impl" not in text and "_src" not in text, path


def test_static_load_is_the_weight_share(rover):
    model, _, wheels, _ = rover
    total = sum(model.body_mass) * -model.opt.gravity[2]
    # Measured by MuJoCo after 2 s of settling through the wheels' contact sensors: the
    # front wheels carry 3499.82 N, the rear 3500.24 N, within 6.0e-5 of the weight's
    # share and 6.8e-5 of 3,500 N.
    np.testing.assert_allclose(wheels.static_load, total / 4, rtol=1e-4)
    np.testing.assert_allclose(wheels.static_load, LOAD, rtol=1e-4)  # 3,500 N, as test_sim


def test_straight_run_matches_simulate_longitudinal(from_rest):
    """The same wheel load, mass per wheel, inertia, snow and torque as `tests/test_sim.py`'s
    shared 2-wheel program (`_run`; reused, so its compile is shared): the same
    accelerating steady state, and the rover keeps straight."""
    r = from_rest
    traj, _ = _run(_parameters(SNOW, [TORQUE] * 3), 0.0)  # from rest, dt = 0.05 s
    late = slice(-100, None)  # the last 0.5 s of the 3 s
    slip = np.asarray(r.wheels.slip[late])
    assert np.ptp(slip, axis=0).max() < 1e-6  # the steady state is reached and flat
    k = int(np.argmin(np.abs(np.asarray(traj.time) - 3.0)))  # t = 3 s
    assert abs(float(traj.time[k]) - 3.0) < 1e-9
    # Steady slip: both solve T - M_w(i) = I domega/dt, m dv/dt = sum F(i).
    # Measured: within 2.0e-4 (the front and rear wheels carry 3499.8 and 3500.2 N, as at
    # rest, and slip 0.18338 and 0.18302 about the simulation's 0.18322 at 3,500 N).
    np.testing.assert_allclose(slip, float(traj.slip[k, 0]), atol=4e-4)
    accel = np.diff(np.asarray(r.qvel[late, 0])) / 0.005
    sim_accel = float(np.sum(traj.drawbar_pull[k])) / float(VEHICLE.mass)
    np.testing.assert_allclose(accel, sim_accel, rtol=1e-3)  # measured 2.9e-5
    np.testing.assert_allclose(float(r.qvel[-1, 0]), float(traj.speed[k]), rtol=3e-2)
    assert abs(float(r.qpos[-1, 1])) < 1e-6  # no drift sideways
    assert np.all(np.abs(np.asarray(r.wheels.lateral_force)) < 1e-6)


def test_no_nan_from_rest(from_rest):
    r = from_rest
    for name, leaf in vars(r.wheels).items():
        assert np.all(np.isfinite(np.asarray(leaf))), name
    assert np.all(np.isfinite(r.qpos)) and np.all(np.isfinite(r.qvel))
    assert np.all(np.asarray(r.wheels.status) == Status.CONVERGED)
    assert float(r.wheels.longitudinal_force[0, 0]) == 0.0  # at rest: no snow force
    assert float(r.qpos[-1, 0]) > 1.0  # it drives off
    np.testing.assert_allclose(np.asarray(r.wheels.normal[-1]), [[0, 0, 1]] * 4, atol=1e-9)


def _yaw_rate(qpos, qvel):
    rot = np.zeros(9)
    mujoco.mju_quat2Mat(rot, np.asarray(qpos[3:7]))
    return (rot.reshape(3, 3) @ np.asarray(qvel[3:6]))[2]


@pytest.mark.slow  # a long steady turn (make test-slow)
def test_steady_turn_radius_matches_simulate_planar(rover, run):
    """0.2 rad of (Ackermann) steering at 540 N m per wheel from 2 m/s: the turning radius
    |v| / yaw rate of the chassis agrees with `simulate_planar`'s for the same vehicle
    (mass, yaw inertia about the centre of mass from MuJoCo's mass matrix, wheels, loads)
    within 2 % (measured: 0.5, 0.6 and 1.0 %) at 1, 2 and 3 s, as the rover speeds up and
    its turn tightens (from 12 to 9 m)."""
    model, _, _, _ = rover
    delta, speed, slip = 0.2, 2.0, 0.2
    r = run(_moving(rover, speed, slip), smjx.rover_controls(delta, jnp.full(4, TORQUE)), SNOW)
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    mass_matrix = np.zeros((model.nv, model.nv))
    mujoco.mj_fullM(model, data, mass_matrix)
    vehicle = sj.PlanarVehicle(
        mass=float(model.body_mass.sum()), yaw_inertia=mass_matrix[5, 5], wheel_inertia=1.5,
        wheel=sj.RigidWheel.thesis_tire(), wheelbase=2.6, track_width=1.6,
    )  # fmt: skip
    spin = speed / (RADIUS * (1 - slip))
    planar = sj.simulate_planar(
        vehicle,
        SNOW,
        delta,
        jnp.full(4, TORQUE),
        3.0,
        0.01,
        initial=sj.InitialState(speed=speed, wheel_speed=jnp.full(4, spin)),
    )
    for t in (1.0, 2.0, 3.0):
        k, j = int(round(t / 0.005)) - 1, int(round(t / 0.01))
        qpos, qvel = np.asarray(r.qpos[k]), np.asarray(r.qvel[k])
        radius = np.hypot(qvel[0], qvel[1]) / _yaw_rate(qpos, qvel)
        reference = float(np.hypot(planar.speed[j], planar.lateral_speed[j]) / planar.yaw_rate[j])
        assert 5.0 < reference < 30.0
        np.testing.assert_allclose(radius, reference, rtol=2e-2)
    assert np.all(np.asarray(r.wheels.status) == Status.CONVERGED)
    assert float(np.min(r.wheels.lateral_force[-1])) > 100.0  # the snow holds the turn


PLATE = sj.WongSnow.thesis_plate_rule_snow()  # drawbar pull < 0 at slip 1 (and bottomed out)


def test_snow_never_delivers_power_and_never_pushes_a_braked_vehicle(rover, run):
    """On the plate-rule snow, driven from rest, braked and coasting with the wheels
    spinning backwards from 5 m/s: the snow's power on every wheel, `F_x v_x + F_y v_y -
    M_w omega`, is never positive; the braked and coasting rover never speeds up."""
    _, _, wheels, d0 = rover
    starts = {
        "driven": (d0.qvel, TORQUE),
        "braked": (_moving(rover, 5.0, 0.0), -TORQUE),
        "coasting": (_moving(rover, 5.0, 0.0).at[np.asarray(wheels.dof_ids)].set(-3 / RADIUS), 0.0),
    }  # fmt: skip
    for name, (qvel, torque) in starts.items():
        r = run(qvel, smjx.rover_controls(0.0, jnp.full(4, torque)), PLATE)
        w = r.wheels
        assert np.all(np.asarray(w.status) != Status.INVALID_INPUT), name
        axle = np.asarray(w.longitudinal_force * w.speed + w.lateral_force * w.lateral_speed)
        spin = np.asarray(-w.resisting_torque * w.wheel_speed)
        assert np.all(axle + spin <= 1e-12 * (np.abs(axle) + np.abs(spin))), name
        assert np.all(np.isfinite(r.qpos)) and np.all(np.isfinite(r.qvel)), name
        if name != "driven":  # (the chassis origin's speed; it pitches on its springs)
            speed = np.asarray(r.qvel[::50, 0])  # every 0.25 s
            assert np.all(np.diff(speed)[speed[1:] > 0.05] < 0.0), name
            assert speed.max() <= 5.0 + 1e-9, name
    assert (
        float(np.min(run(d0.qvel, smjx.rover_controls(0.0, jnp.full(4, TORQUE)), PLATE).qpos[:, 0]))
        > -1e-3
    )


@pytest.mark.slow  # two more MuJoCo models to compile (make test-slow)
def test_no_nan_on_a_slope_and_on_a_height_field():
    """From rest, 1 s at 540 N m per wheel: on a 0.1 rad climb (the snow's frame follows
    the inclined floor: every wheel's normal is the floor's) and on a bumpy height field
    with the loads from the contacts."""
    slope = 0.1
    x, y = np.meshgrid(np.linspace(-10, 10, 41), np.linspace(-10, 10, 41))
    bumps = 0.08 * (1 + np.sin(1.3 * x) * np.cos(0.9 * y))
    for ground, load in (({"slope": slope}, None), ({"heights": bumps}, "contact")):
        model, wheels = smjx.load_rover(**ground)
        m = mjx.put_model(model)
        ctrl = smjx.rover_controls(0.1, jnp.full(4, TORQUE))

        def drive(snow, m=m, wheels=wheels, load=load, ctrl=ctrl):
            return smjx.rollout(m, mjx.make_data(m), wheels, snow, ctrl, 200, load=load)

        r = jax.jit(drive)(SNOW)
        for leaf in jax.tree.leaves(r.wheels):
            assert np.all(np.isfinite(np.asarray(leaf))), ground
        assert np.all(np.isfinite(r.qpos)) and np.all(np.isfinite(r.qvel)), ground
        assert np.all(np.asarray(r.wheels.status) == Status.CONVERGED), ground
        if "slope" in ground:
            normal = np.array([-np.sin(slope), 0.0, np.cos(slope)])
            np.testing.assert_allclose(np.asarray(r.wheels.normal[-1]), [normal] * 4, atol=1e-6)
            assert float(r.qpos[-1, 0]) > 0.05  # it climbs
        else:
            tilt = np.asarray(r.wheels.normal[50:, :, 2])
            assert tilt.min() < 0.999  # the bumps tilt the frames
            loads = np.asarray(r.wheels.load[-50:].sum(-1))
            weight = float(sum(model.body_mass) * 9.80665)
            assert np.all(np.abs(loads / weight - 1) < 0.5)


@pytest.mark.slow  # forward-mode tangents through a rollout (make test-slow)
def test_forward_gradients_of_the_end_position(rover):
    """d(end x, end y)/d(p_w, steering) through 100 MJX steps (0.5 s) from 2 m/s, forward
    mode, against central differences."""
    _, m, wheels, d0 = rover
    d1 = d0.replace(qvel=_moving(rover, 2.0, 0.2))

    def end(p):
        snow = sj.WongSnow(p[0], SNOW.z_w, SNOW.cohesion, SNOW.tan_phi, SNOW.shear_modulus)
        ctrl = smjx.rover_controls(p[1], jnp.full(4, TORQUE))
        return smjx.rollout(m, d1, wheels, snow, ctrl, 100).qpos[-1, :2]

    @jax.jit
    def value_and_jacobian(p):
        along = lambda t: jax.jvp(end, (p,), (t,))  # noqa: E731
        value, tangents = jax.vmap(along, out_axes=(None, 0))(jnp.eye(2))
        return value, tangents

    p = jnp.array([SNOW.p_w, 0.15])
    _, jac = value_and_jacobian(p)
    jac = np.asarray(jac)  # jac[j, i] = d end_i / d p_j
    for j, h in ((0, 1e-4 * float(SNOW.p_w)), (1, 1e-4)):
        fd = (np.asarray(value_and_jacobian(p.at[j].add(h))[0])
              - np.asarray(value_and_jacobian(p.at[j].add(-h))[0])) / (2 * h)  # fmt: skip
        assert np.all(np.abs(fd) > 1e-9)
        np.testing.assert_allclose(jac[j], fd, rtol=1e-3, atol=1e-5 * np.abs(fd).max())


@pytest.mark.slow  # a vmapped episode of 1,024 environments (make test-slow)
def test_environment_runs_1024_randomised_instances_for_an_episode():
    """1,024 instances, each on its own snow and goal, for a whole (short: 10 steps of
    4 x 5 ms) episode, throttle and a proportional steering: no NaN, every instance done
    on time, the snows differ, every instance moves towards its goal."""
    env = smjx.SnowRoverEnv(episode_length=10, frame_skip=4)

    @jax.jit
    def episode(key):
        state = jax.vmap(env.reset)(jax.random.split(key, 1024))
        first = state

        def body(state, _):
            action = jnp.stack([jnp.clip(5 * state.obs[:, 1], -1, 1), jnp.ones(1024)], -1)
            state = jax.vmap(env.step)(state, action)
            return state, state.reward

        state, rewards = jax.lax.scan(body, state, None, length=env.episode_length)
        return first, state, rewards

    traced = episode.trace(jax.random.key(0))
    # No batched LAPACK LU beside MJX's batched Cholesky: the two block XLA:CPU's pool
    # threads at once and this episode deadlocked (`_solve_dense`).
    assert not re.search(r"= lu\b", str(traced.jaxpr))  # the primitive, not a variable
    first, state, rewards = traced.lower().compile()(jax.random.key(0))
    for leaf in jax.tree.leaves((state, rewards)):
        if jnp.issubdtype(jnp.asarray(leaf).dtype, jnp.floating):
            assert np.all(np.isfinite(np.asarray(leaf)))
    assert np.all(np.asarray(state.done) == 1.0)
    assert np.all(np.asarray(state.info["truncation"]) == 1.0)  # 0.4 s: no goal reached
    p_w = np.asarray(first.info["snow"].p_w)
    assert np.unique(p_w).size == 1024 and 60e3 <= p_w.min() and p_w.max() <= 240e3
    assert np.all(np.asarray(rewards).sum(0) > 0)
    assert state.obs.shape == (1024, env.observation_size)
    one = jax.jit(env.reset)(jax.random.key(1))  # a plain class: its methods jit directly
    assert one.obs.shape == (env.observation_size,) and float(one.done) == 0.0


@pytest.mark.slow  # the example's own compiles (make test-slow)
def test_evolution_strategies_example_improves_its_objective():
    """`examples/rover_reach_goal.py` on a small budget: 4 generations of 2 antithetic
    pairs on 1 episode each, 60-step (1.2 s) episodes; the objective (mean return over 4
    fixed evaluation episodes [m]) rises from the resting policy's 0 (measured: 0.75 m)."""
    import importlib.util

    spec = importlib.util.spec_from_file_location(
        "rover_reach_goal", ROOT / "examples" / "rover_reach_goal.py"
    )
    example = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(example)
    history, *_ = example.train(
        generations=4, population=2, snows=1, episode_length=60, progress=False
    )
    assert abs(history[0]) < 1e-3  # the zero policy does not move
    assert history[-1] > history[0] + 0.3


# The notebook's kernel compiles its own vmapped forward-mode rollout (about a minute on
# 2 cores): `make test-slow` runs it.
@pytest.mark.slow
def test_notebook_runs(tmp_path):
    nb = run_notebook("mjx_vehicle.ipynb", tmp_path)
    text = outputs_text(nb)
    assert "d distance / d p_w" in text
    assert "firm: distance" in text


def test_traced_bad_prescribed_loads_are_flagged(rover):
    """Under jit a negative or NaN prescribed load gives its wheel no snow force and
    `Status.INVALID_INPUT`; the other wheels are solved."""
    _, m, wheels, d0 = rover
    d1 = d0.replace(qvel=_moving(rover, 1.0, 0.0))
    out = jax.jit(lambda load: smjx.step(m, d1, wheels, SNOW, load=load)[1])(
        jnp.array([-100.0, 3500.0, jnp.nan, 3500.0])
    )
    status = np.asarray(out.status)
    assert list(status) == [Status.INVALID_INPUT, Status.CONVERGED] * 2
    assert np.all(np.asarray(out.longitudinal_force)[[0, 2]] == 0.0)
    assert np.all(np.isfinite(np.asarray(out.longitudinal_force)))


@pytest.mark.slow  # the rover's step compiled again (make test-slow)
def test_a_contact_model_traces_the_same_step(rover):
    """A bare terrain traces the step of `ContactModel(terrain)` (compared as jaxprs: no
    compile needed); a model part given as a keyword raises a `TypeError` naming the
    model's spelling."""
    _, m, wheels, d0 = rover
    plate = sj.WongReece(0.4, 0.3, -0.1)

    def forces(snow, **keywords):
        return smjx.step(m, d0, wheels, snow, **keywords)[1].longitudinal_force

    bare = jax.make_jaxpr(lambda s: forces(s))(SNOW)
    by_model = jax.make_jaxpr(lambda s: forces(sj.ContactModel(s)))(SNOW)
    assert str(by_model) == str(bare)  # a bare terrain is ContactModel(terrain)
    with_plate = jax.make_jaxpr(lambda s, p: forces(sj.ContactModel(s, p)))(SNOW, plate)
    assert str(with_plate) != str(bare)
    with pytest.raises(TypeError, match=r"step\(distribution=...\) is now spelled ContactModel"):
        forces(SNOW, distribution=plate)


@pytest.mark.slow  # the rover's step compiled at two accuracies (make test-slow)
def test_the_simulator_accuracy_step_is_within_1e_4_of_the_reference(rover):
    """One step, driving at 2 m/s and sliding sideways at 0.3 m/s (slip angles 0.15 rad):
    every wheel's forces at the simulator accuracy within 1e-4 of the wheel's load
    (moments: of load x r) of the reference accuracy's, and not equal to them (the
    setting reaches the wheels)."""
    _, m, wheels, d0 = rover
    qvel = _moving(rover, 2.0, 0.2).at[1].set(0.3)
    d = d0.replace(qvel=qvel, ctrl=smjx.rover_controls(0.0, jnp.full(4, TORQUE)))
    out = {
        a: smjx.step(m, d, wheels, sj.ContactModel(SNOW, accuracy=a))[1]
        for a in ("reference", "simulator")
    }
    load = np.asarray(out["reference"].load)
    diffs = {
        name: np.abs(np.asarray(getattr(out["simulator"], name) - getattr(out["reference"], name)))
        / (load * (RADIUS if "torque" in name else 1.0))
        for name in ("longitudinal_force", "lateral_force", "resisting_torque", "aligning_torque")
    }
    assert max(float(x.max()) for x in diffs.values()) <= 1e-4, diffs
    assert min(float(diffs[k].max()) for k in ("longitudinal_force", "lateral_force")) > 0, diffs


def test_bad_input_raises(rover):
    model, m, wheels, d0 = rover
    with pytest.raises(ValueError, match="no body named"):
        smjx.MjxWheels.from_model(model, ["nope"])
    with pytest.raises(ValueError, match="exactly one joint"):
        smjx.MjxWheels.from_model(model, ["chassis"])
    with pytest.raises(ValueError, match="radius"):
        smjx.MjxWheels.from_model(model, ["wheel_fl"], sj.RigidWheel(1.0, 0.2))
    with pytest.raises(TypeError, match="MjModel"):
        smjx.MjxWheels.from_model(m, ["wheel_fl"])
    frictional = smjx.rover_spec().compile()
    frictional.geom_condim[0] = 3  # the ground
    with pytest.raises(ValueError, match="condim"):
        smjx.MjxWheels.from_model(frictional, ["wheel_fl"])
    spec = smjx.rover_spec()
    spec.delete(spec.sensor("snow_contact_fl"))
    with pytest.raises(ValueError, match='contact geom1="contact_fl"'):
        smjx.MjxWheels.from_model(spec.compile(), ["wheel_fl"])
    with pytest.raises(ValueError, match="slope"):
        smjx.rover_spec(slope=1.0)
    with pytest.raises(ValueError, match="heights"):
        smjx.rover_spec(heights=np.full((3, 3), -1.0))
    with pytest.raises(TypeError, match="terrain"):
        smjx.step(m, d0, wheels, "snow")
    with pytest.raises(ValueError, match="load"):
        smjx.step(m, d0, wheels, SNOW, load="floor")
    rk4 = smjx.rover_spec().compile()
    rk4.opt.integrator = mujoco.mjtIntegrator.mjINT_RK4
    with pytest.raises(ValueError, match="Euler"):
        smjx.step(mjx.put_model(rk4), d0, wheels, SNOW)
    with pytest.raises(ValueError, match="ctrl"):
        smjx.rollout(m, d0, wheels, SNOW, jnp.zeros(3), 2)
    with pytest.raises(ValueError, match="snow.p_w must be finite"):
        smjx.step(m, d0, wheels, sj.WongSnow(np.nan, 0.2, 1e3, 0.1, 0.01))
    with pytest.raises(ValueError, match=r"load must be finite and >= 0 N"):
        smjx.step(m, d0, wheels, SNOW, load=jnp.array([-100.0, 3500.0, 3500.0, 3500.0]))
    with pytest.raises(ValueError, match="simplified"):
        smjx.step(m, d0, wheels, sj.ContactModel(SNOW, shear="simplified"))
    with pytest.raises(ValueError, match="episode_length"):
        smjx.SnowRoverEnv(episode_length=0)
    with pytest.raises(ValueError, match="accuracy must be one of"):
        smjx.SnowRoverEnv(accuracy="fast")


def test_the_dense_solve_matches_lapack():
    """`_solve_dense` (the step's M x = f without LAPACK) against NumPy's LAPACK solve:
    random well- and ill-conditioned matrices of the rover's n = 16 and smaller, ones
    whose leading entry is 0 (needs the row swap), vmapped; error <= 1e-13 x cond."""
    rng = np.random.default_rng(3)
    cases = []
    for n in (1, 2, 5, 16):
        for scale in (1.0, 1e-4, 1e6):
            a = rng.normal(size=(n, n)) * np.logspace(0, np.log10(scale), n)[None, :]
            cases.append((a, rng.normal(size=n)))
        if n > 1:  # a zero leading entry: solved only with the row swap
            a = rng.normal(size=(n, n))
            a[0, 0] = 0.0
            cases.append((a, rng.normal(size=n)))
    solve = jax.jit(_solve_dense)
    for a, b in cases:
        x = np.asarray(solve(jnp.asarray(a), jnp.asarray(b)))
        expected = np.linalg.solve(a, b)
        err = np.abs(x - expected).max() / np.abs(expected).max()
        assert err <= 1e-13 * np.linalg.cond(a), (a.shape, err)
    a, b = rng.normal(size=(64, 16, 16)), rng.normal(size=(64, 16))
    np.testing.assert_allclose(
        np.asarray(jax.jit(jax.vmap(_solve_dense))(jnp.asarray(a), jnp.asarray(b))),
        np.linalg.solve(a, b[..., None])[..., 0],
        rtol=1e-10,
        atol=1e-12,
    )


def test_the_implicit_blocks_keep_the_step_well_posed():
    """`_dissipative`: whatever the slopes, the symmetric part of each wheel's block plus
    W / (2 dt) is positive semi-definite (so M + dt (D_joint + K) keeps a symmetric part
    >= M / 2); a block from steady straight driving (the guide's rover on the thesis
    snow, wheel 0 after 3 s at 540 N m: measured slopes) is left as it is."""
    radius, dt = 0.368, 0.01
    inertia = jnp.array([[25.0, 25.0, 1.0, 1.0]] * 8)
    rng = np.random.default_rng(0)
    # Slopes as near rest: large, signed, far from symmetric (and a few mild ones).
    size = np.array([1e4, 1e4, 1e4, 1e4, 10, 10, 10, 10])[:, None, None]
    blocks = rng.normal(size=(8, 4, 3)) * size
    out = np.asarray(_dissipative(jnp.asarray(blocks), radius, inertia, dt))
    scale = np.array([1, 1, 1 / radius, 1 / radius])
    w = np.asarray(inertia) * scale**2 / (2 * dt)
    for k in range(8):
        scaled = scale[:, None] * out[k] * scale[None, :]
        sym = 0.5 * (scaled + scaled.T) + np.diag(w[k])
        assert np.linalg.eigvalsh(sym).min() >= -1e-9 * np.abs(sym).max()
        # Only the diagonal changes, and only upwards.
        off = ~np.eye(4, dtype=bool)[:, :3]
        np.testing.assert_array_equal(out[k][:, :3][off], blocks[k][off])
        assert np.all(np.diagonal(out[k][:3, :3]) >= np.diagonal(blocks[k][:3, :3]))
    steady = np.array(
        [[48.3129, 0.0, -14.5216], [0.0, 972.4526, 0.0], [-17.5875, 0.0, 5.2864],
         [0.0, 114.5835, 0.0]]
    )  # fmt: skip
    kept = np.asarray(_dissipative(jnp.asarray(steady[None]), radius, inertia[:1], 0.005))[0]
    np.testing.assert_array_equal(kept[:, :3], steady)
    np.testing.assert_array_equal(kept[:, 3], 0.0)
