"""Longitudinal vehicle simulation on snow (issue 7): `snowjax.simulate_longitudinal`,
the force function `snowjax.wheel_forces` and the start-from-rest regularisation.

Every simulation here is one compiled program, `_run`: a 2-wheel vehicle, 80 implicit
steps of 0.05 s, the thesis tyre and snow with p_w and tan(phi) traced, and a 3-knot
`TorqueProfile`; it returns the trajectory and the forward-mode (`diffrax.ForwardMode`)
derivatives of the final speed w.r.t. (p_w, tan phi, the three knot torques).  The
scenarios differ only in array values, so they share that compile.  The last section's
examples (why the simulation keeps its own implicit Euler step and damped Newton iteration
instead of diffrax's and optimistix's) compile small programs of their own.
"""

import diffrax
import equinox as eqx
import jax
import jax.numpy as jnp
import lineax as lx
import numpy as np
import optimistix as optx
import pytest
import scipy.optimize

import snowjax as sj
from snowjax import Status
from snowjax._sim.levenberg_marquardt import _LevenbergMarquardt, _PassiveBlockSolver

from .notebook_runner import outputs_text, run_notebook

WHEEL = sj.RigidWheel.thesis_tire()
SNOW = sj.WongSnow.thesis_fresh_snow()
LOAD = 3500.0  # [N] per wheel: the thesis's lightest FEA load
VEHICLE = sj.Vehicle(mass=2 * LOAD / 9.80665, wheel_inertia=1.5, wheel=WHEEL, num_wheels=2)
T1, DT = 4.0, 0.05
KNOT_TIMES = jnp.linspace(0.0, T1, 3)
EPS = 0.05  # default speed_eps [m/s]


def _parameters(snow, knots):
    """Vector x = (p_w, tan phi, 3 knot torques) of the shared program."""
    return jnp.concatenate([jnp.array([snow.p_w, snow.tan_phi], float), jnp.asarray(knots, float)])


def _simulate(x, v0):
    snow = sj.WongSnow(x[0], SNOW.z_w, SNOW.cohesion, x[1], SNOW.shear_modulus)
    torque = sj.TorqueProfile(KNOT_TIMES, x[2:])
    return sj.simulate_longitudinal(
        VEHICLE,
        snow,
        torque,
        T1,
        DT,
        initial=sj.InitialState(speed=v0),
        stepping=sj.Stepping(adjoint=diffrax.ForwardMode()),
    )


@jax.jit
def _run(x, v0):
    """(trajectory, d speed(T1) / dx), from one forward-mode linearisation."""

    def final_speed(x):
        traj = _simulate(x, v0)
        return traj.speed[-1], traj

    _, tangent, traj = jax.linearize(final_speed, x, has_aux=True)
    return traj, jax.vmap(tangent)(jnp.eye(x.shape[0]))


def _self_propelled_slip(load):
    """Slip i* with zero drawbar pull and its torque M_w(i*), by brentq on solve_wheel."""
    dp = lambda i: float(sj.solve_wheel(WHEEL, SNOW, load, i).drawbar_pull)  # noqa: E731
    slip = scipy.optimize.brentq(dp, -0.5, 0.5, xtol=1e-14)
    return slip, float(sj.solve_wheel(WHEEL, SNOW, load, slip).torque)


# ----------------------------------------------------------------------------------------
# Steady state
# ----------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def steady():
    slip, torque = _self_propelled_slip(LOAD)
    traj, _ = _run(_parameters(SNOW, [torque] * 3), 1.0)
    return slip, torque, traj


def test_constant_torque_reaches_the_self_propelled_steady_state(steady):
    slip_star, torque, traj = steady
    assert traj.result == diffrax.RESULTS.successful
    assert np.all(np.asarray(traj.status) == Status.CONVERGED)
    # Drawbar pull -> 0 and slip constant at the end (the last second).
    late = slice(-20, None)
    dp_scale = float(sj.solve_wheel(WHEEL, SNOW, LOAD, 0.0).motion_resistance)
    assert np.max(np.abs(traj.drawbar_pull[late])) < 1e-6 * dp_scale
    assert np.ptp(np.asarray(traj.slip[late])) < 1e-9
    assert np.ptp(np.asarray(traj.speed[late])) < 1e-8
    # ... at the slip brentq finds independently, with the kinematics of eq. (2.6).
    np.testing.assert_allclose(traj.slip[-1], slip_star, atol=1e-8)
    kinematic = 1 - traj.speed[-1] / (traj.wheel_speed[-1] * WHEEL.diameter / 2)
    np.testing.assert_allclose(traj.slip[-1], kinematic, rtol=1e-12)
    # Above the regularisation band: the steady state is the model's own.
    assert float(traj.speed[-1]) > 2 * EPS
    # Independent check: solve_wheel at the simulated final slip.
    st = sj.solve_wheel(WHEEL, SNOW, LOAD, float(traj.slip[-1, 0]))
    assert abs(float(st.drawbar_pull)) < 1e-6 * dp_scale
    np.testing.assert_allclose(float(st.torque), torque, rtol=1e-9)
    np.testing.assert_allclose(traj.sinkage[-1], float(st.sinkage), rtol=1e-9)


def test_transient_obeys_newtons_law(steady):
    """m dv/dt = sum of drawbar pulls (implicit Euler: forces at the step's end)."""
    _, _, traj = steady
    dv = np.diff(np.asarray(traj.speed)) / DT
    force = np.sum(np.asarray(traj.drawbar_pull), axis=1)[1:] / float(VEHICLE.mass)
    np.testing.assert_allclose(dv, force, rtol=1e-6, atol=1e-7)
    np.testing.assert_allclose(np.diff(traj.distance) / DT, traj.speed[1:], rtol=1e-7)


# ----------------------------------------------------------------------------------------
# Start from rest, gradients
# ----------------------------------------------------------------------------------------

X_REST = _parameters(SNOW, [545.0, 520.0, 535.0])


@pytest.fixture(scope="module")
def from_rest():
    return _run(X_REST, 0.0)


def test_start_from_rest_is_finite_and_physical(from_rest):
    traj, jac = from_rest
    assert traj.result == diffrax.RESULTS.successful
    for name in (
        "speed",
        "distance",
        "wheel_speed",
        "slip",
        "sinkage",
        "drawbar_pull",
        "resisting_torque",
        "entry_angle",
    ):
        assert np.all(np.isfinite(getattr(traj, name))), name
    assert np.all(np.isfinite(jac)) and np.all(jac != 0)
    assert np.all(np.asarray(traj.status) == Status.CONVERGED)
    assert float(traj.speed[0]) == 0.0 and float(traj.drawbar_pull[0, 0]) == 0.0
    # Driving slip throughout: the rim runs ahead of the vehicle, which accelerates.
    assert np.all(np.asarray(traj.slip[1:]) > 0.02)
    assert np.all(np.diff(np.asarray(traj.speed)) > 0)
    assert float(traj.speed[-1]) > 1.0


@pytest.mark.parametrize(
    "index, rel_step",
    [(0, 1e-4), (1, 1e-3), (2, 1e-5), (3, 1e-5), (4, 1e-5)],
    ids=["p_w", "tan_phi", "knot0", "knot1", "knot2"],
)
def test_gradient_of_final_speed_matches_central_differences(from_rest, index, rel_step):
    _, jac = from_rest
    h = rel_step * float(X_REST[index])
    up, _ = _run(X_REST.at[index].add(h), 0.0)
    down, _ = _run(X_REST.at[index].add(-h), 0.0)
    fd = (float(up.speed[-1]) - float(down.speed[-1])) / (2 * h)
    assert abs(fd) > 1e-6  # a sensitivity worth testing
    np.testing.assert_allclose(float(jac[index]), fd, rtol=1e-2)


# ----------------------------------------------------------------------------------------
# Regularisation at rest
# ----------------------------------------------------------------------------------------


def test_wheel_kinematics_regularisation():
    r = 0.5
    v = np.array([0.0, 0.0, 1.0, 1.5, 3.0, -1.5, 0.01, 0.0, 1e-3, 0.03])
    w = np.array([0.0, 2.0, 0.0, 4.0, 4.0, -4.0, 0.02, 0.06, 0.0, -0.06]) / r
    slip, factor = sj.wheel_kinematics(v, w, r, EPS)
    expected_slip = [
        0.0,  # at rest
        1.0,  # spinning in place
        -1.0,  # locked wheel
        1 - 1.5 / 4.0,  # driving, eq. (2.6)
        1 - 3.0 / 4.0,  # braking with v <= 2 omega r, eq. (2.6)
        1 - 1.5 / 4.0,  # the mirror image of the driving case
        0.5,  # inside the band: still the ratio
        1.0,
        -1.0,
        1.0,  # counter-rotating, mirrored: (+0.06 rim, 0 speed) spins in place
    ]
    np.testing.assert_allclose(slip, expected_slip, atol=1e-15)
    s = np.abs(v + w * r) / (2 * EPS)
    np.testing.assert_allclose(factor, 1 - (1 - np.minimum(s, 1)) ** 2, atol=1e-15)
    assert factor[0] == 0 and factor[3] == 1 and factor[5] == 1
    # C^1 at the band edge and linear growth from rest.
    d = jax.grad(lambda u: sj.wheel_kinematics(u, u / r, r, EPS)[1])
    assert float(d(jnp.asarray(2 * EPS / 2 - 1e-9))) == pytest.approx(0.0, abs=1e-6)
    assert float(d(jnp.asarray(0.0))) == pytest.approx(2 / EPS)


@pytest.fixture(scope="module")
def forces_at_states():
    """wheel_forces on a batch of states, and solve_wheel at the same slips."""
    r = float(WHEEL.diameter) / 2
    v = jnp.array([0.0, 2.0, 3.0, -2.0, 0.01, 0.0, 1.0])
    w = jnp.array([0.0, 2.5, 2.0, -2.5, 0.03, 0.08, 0.0]) / r
    f = sj.wheel_forces(v, w, LOAD, WHEEL, SNOW)
    st = sj.solve_wheel(WHEEL, SNOW, LOAD, f.slip)
    return v, w, f, st


def test_wheel_forces_are_the_regularised_equilibrium(forces_at_states):
    v, w, f, st = forces_at_states
    slip, factor = sj.wheel_kinematics(v, w, WHEEL.diameter / 2, EPS)
    sign = np.where(v + w * WHEEL.diameter / 2 >= 0, 1.0, -1.0)
    # The motion resistance's direction psi (module docs of wheel_forces), by hand: 1 when
    # the axle moves forwards beyond the band or the wheel brakes; for (v, omega r) =
    # (0.01, 0.03) m/s, psi = 2 s - s^2 = 0.19 with s = 0.01 / (2 eps) (slip 2/3, so no
    # blend towards 1); 0 for a wheel spinning in place.
    psi = np.array([1.0, 1.0, 1.0, 1.0, 0.19, 0.0, 1.0])
    force = sign * factor * (st.thrust - psi * st.motion_resistance)
    np.testing.assert_allclose(f.slip, slip)
    np.testing.assert_allclose(f.longitudinal_force, force, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(f.resisting_torque, sign * factor * st.torque, rtol=1e-12)
    np.testing.assert_allclose(f.sinkage, st.sinkage, rtol=1e-12)
    # At rest: no force.  Above the band: exactly the thesis model at slip 1 - v/(omega r).
    assert float(f.longitudinal_force[0]) == 0.0 and float(f.resisting_torque[0]) == 0.0
    exact = sj.solve_wheel(WHEEL, SNOW, LOAD, jnp.array([1 - 2.0 / 2.5, 1 - 3.0 / 2.0]))
    np.testing.assert_allclose(f.longitudinal_force[1:3], exact.drawbar_pull, rtol=1e-12)
    np.testing.assert_allclose(f.resisting_torque[1:3], exact.torque, rtol=1e-12)
    # The mirror image travelling backwards.
    np.testing.assert_allclose(f.longitudinal_force[3], -f.longitudinal_force[1], rtol=1e-12)
    np.testing.assert_allclose(f.resisting_torque[3], -f.resisting_torque[1], rtol=1e-12)
    assert np.all(np.asarray(f.status) == Status.CONVERGED)
    # The same forces given a ContactModel in place of the terrain.
    by_model = sj.wheel_forces(v, w, LOAD, WHEEL, sj.ContactModel(SNOW))
    np.testing.assert_array_equal(by_model.longitudinal_force, f.longitudinal_force)


def test_wheel_forces_gradients_at_and_near_rest():
    """Reverse mode through the force function: finite at rest, equal to differences."""

    def pull(x):
        return sj.wheel_forces(x[0], x[1], LOAD, WHEEL, SNOW).longitudinal_force

    grad = jax.jit(jax.grad(pull))
    g0 = grad(jnp.array([0.0, 0.0]))
    assert np.all(np.isfinite(g0))
    x = np.array([0.02, 0.04])  # inside the band, driving
    g = grad(jnp.asarray(x))
    for k in range(2):
        h = np.zeros(2)
        h[k] = 1e-6
        fd = (float(pull(x + h)) - float(pull(x - h))) / 2e-6
        np.testing.assert_allclose(float(g[k]), fd, rtol=1e-4)


def test_coasting_vehicle_comes_to_rest_and_stays():
    traj, _ = _run(_parameters(SNOW, [0.0, 0.0, 0.0]), 3.0)
    assert traj.result == diffrax.RESULTS.successful
    speed = np.asarray(traj.speed)
    assert np.all(speed > -1e-6)
    stop = np.argmax(speed < 1e-6)
    assert 0 < stop < len(speed) - 10
    assert np.all(np.abs(speed[stop:]) < 1e-6)
    assert np.ptp(np.asarray(traj.distance[stop:])) < 1e-6
    # Unpowered wheels: the snow's torque only decelerates the wheel, I domega/dt = -M_w.
    inertia = float(VEHICLE.wheel_inertia)
    np.testing.assert_allclose(
        -inertia * np.diff(np.asarray(traj.wheel_speed), axis=0) / DT,
        traj.resisting_torque[1:],
        rtol=1e-6,
        atol=1e-4,
    )
    assert np.all(np.asarray(traj.slip[1:stop]) < 0)  # braking slip, eq. (2.6)


def test_torque_below_the_self_propelled_torque_only_creeps(steady):
    _, torque, _ = steady
    traj, _ = _run(_parameters(SNOW, [0.5 * torque] * 3), 0.0)
    assert traj.result == diffrax.RESULTS.successful
    assert 0 < float(traj.speed[-1]) < EPS


# `make test-slow` (19 s of a worker, two compiles of its own): `make test` starts vmapped
# batches from rest in `test_properties.py` (the coasting and driven vehicles) and
# `test_planar.py` (the soft snow from rest), which the bug below broke too.
@pytest.mark.slow
def test_vmap_over_terrains_from_rest():
    """A batch of two snows from rest in one vmapped program equals the two runs (this
    raised in lineax while the damped Newton's Jacobian came from `jax.linearize`: NaN
    tangents of the untaken branch of the equilibrium's `lax.cond`)."""
    snows = [SNOW, sj.WongSnow.thesis_fresh_snow(p_w=50e3)]
    batch = jax.tree.map(lambda a, b: jnp.stack([a, b]), *snows)
    run = lambda snow: sj.simulate_longitudinal(VEHICLE, snow, 300.0, 0.2, 0.05)  # noqa: E731
    speeds = jax.vmap(lambda snow: run(snow).speed)(batch)
    assert np.all(np.isfinite(np.asarray(speeds)))
    assert abs(float(speeds[0, -1] - speeds[1, -1])) > 1e-3  # independent rows
    for k, snow in enumerate(snows):
        np.testing.assert_allclose(speeds[k], run(snow).speed, rtol=1e-9, atol=1e-12)


@pytest.mark.slow  # a simulation with a failing step, compiled (make test-slow)
def test_a_step_not_solved_even_when_retried_stops_the_integration():
    """With one iteration allowed, the steps from rest are not solved even at the step-size
    controller's smallest step: the root finder's failure is the result, and the rows
    after it hold inf states with `Status.INVALID_INPUT`."""
    traj = sj.simulate_longitudinal(
        VEHICLE, SNOW, 545.0, 0.5, DT, stepping=sj.Stepping(newton_steps=1)
    )
    assert traj.result == diffrax.RESULTS.nonlinear_max_steps_reached
    assert float(traj.speed[0]) == 0.0 and np.all(np.isinf(np.asarray(traj.speed[1:])))
    assert np.all(np.asarray(traj.status[1:]) == Status.INVALID_INPUT)
    # The same run given a ContactModel in place of the terrain.
    model = sj.ContactModel(SNOW, shear=sj.JanosiHanamoto())
    by_model = sj.simulate_longitudinal(
        VEHICLE, model, 545.0, 0.5, DT, stepping=sj.Stepping(newton_steps=1)
    )
    np.testing.assert_array_equal(by_model.speed, traj.speed)
    assert by_model.result == traj.result


# ----------------------------------------------------------------------------------------
# Bad input, notebook
# ----------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(dt=0.0), "dt"),
        (dict(t1=-1.0), "t1"),
        (dict(initial=sj.InitialState(speed=np.nan)), "initial.speed"),
        (
            dict(initial=sj.InitialState(yaw_rate=0.1)),
            "drives straight: initial.yaw_rate must be 0",
        ),
        (dict(vehicle=sj.Vehicle(-1.0, 1.5, WHEEL, 2)), "mass"),
        (dict(torque=sj.TorqueProfile([0.0, 1.0], [[1.0, 2.0, 3.0]] * 2)), "TorqueProfile"),
        (dict(torque=sj.TorqueProfile([1.0, 0.0], [1.0, 2.0])), "increasing"),
        (dict(torque=np.ones(3)), r"torque must be a number or one value per wheel, shape \(2,\)"),
        (dict(torque=lambda t, v, w: jnp.ones(3)), r"the torque controller returned shape \(3,\)"),
        (dict(snow=sj.WongSnow(np.nan, 0.2, 1e3, 0.1, 0.01)), "p_w"),
        (dict(snow=sj.ContactModel(SNOW, shear="simplified")), "braking extension"),
    ],
)
def test_bad_input_raises(kwargs, match):
    args = dict(vehicle=VEHICLE, snow=SNOW, torque=600.0, t1=1.0, dt=0.1)
    args.update(kwargs)
    t1, dt = args.pop("t1"), args.pop("dt")
    with pytest.raises(ValueError, match=match):
        sj.simulate_longitudinal(
            args.pop("vehicle"), args.pop("snow"), args.pop("torque"), t1, dt, **args
        )
    with pytest.raises(ValueError, match="load"):
        sj.wheel_forces(1.0, 2.0, -5.0, WHEEL, SNOW)
    with pytest.raises(ValueError, match="speed_eps must be finite and > 0"):
        sj.Stepping(speed_eps=0.0)
    with pytest.raises(ValueError, match="save_every must be a positive integer"):
        sj.Stepping(save_every=0)
    with pytest.raises(TypeError, match="adjoint must be a diffrax.AbstractAdjoint"):
        sj.Stepping(adjoint="forward")
    with pytest.raises(ValueError, match="snow.p_w must be finite"):
        sj.wheel_forces(1.0, 2.0, 3000.0, WHEEL, sj.WongSnow(np.nan, 0.2, 1e3, 0.1, 0.01))
    with pytest.raises(ValueError, match="shear='simplified'"):
        sj.wheel_forces(1.0, 2.0, 3000.0, WHEEL, sj.ContactModel(SNOW, shear="simplified"))


# 45 s of a worker on 2 cores, compiling the forward-mode Jacobians of the notebook's
# least-squares fits in its kernel: `make test-slow` runs it.
@pytest.mark.slow
def test_notebook_runs(tmp_path):
    nb = run_notebook("vehicle_simulation.ipynb", tmp_path)
    text = outputs_text(nb)
    assert "recovered p_w" in text
    assert "time to 5 m/s" in text


# ----------------------------------------------------------------------------------------
# Why the simulation keeps its own implicit Euler step and damped Newton iteration
# ----------------------------------------------------------------------------------------

RADIUS = float(WHEEL.diameter) / 2
COASTING = jnp.array([3.0, 0.0, 3.0 / RADIUS, 3.0 / RADIUS])  # (v, x, omega_1, omega_2)
TOL = 1e-9  # the simulation's float64 rtol = atol
# How the simulation differentiates each implicit step (`snowjax/_sim/stepping.py`; its
# `_PassiveBlockSolver` solves the block of the state so).
STEP_ADJOINT = optx.ImplicitAdjoint(linear_solver=lx.AutoLinearSolver(well_posed=False))


def _rate(y, torque, p_w):
    """dy/dt of VEHICLE at y = (v, x, omega_1, omega_2), through `wheel_forces`."""
    snow = sj.WongSnow(p_w, SNOW.z_w, SNOW.cohesion, SNOW.tan_phi, SNOW.shear_modulus)
    f = sj.wheel_forces(y[:1], y[2:], VEHICLE.wheel_load, WHEEL, snow)
    dv = jnp.sum(f.longitudinal_force) / VEHICLE.mass
    domega = (torque - f.resisting_torque) / VEHICLE.wheel_inertia
    return jnp.concatenate([dv[None], y[:1], domega])


def _implicit_step(y0, torque):
    """Residual of one implicit Euler step of DT from y0, as `fn(y1, p_w)`."""
    return lambda y, p_w: y - y0 - DT * _rate(y, torque, p_w)


def _solve_step(step, y0, solver, options=None, p_w=SNOW.p_w):
    return optx.root_find(
        step,
        solver,
        y0,
        p_w,
        options=options,
        throw=False,
        max_steps=100,
        adjoint=STEP_ADJOINT,
    )


@pytest.mark.slow  # diffrax's own implicit solver compiled (make test-slow)
def test_diffrax_implicit_euler_cannot_replace_the_warm_start_step():
    """`diffrax.ImplicitEuler` with optimistix's Newton, under the simulation's step-size
    controller, keeps a step whose root find failed: coasting from 3 m/s, where
    `simulate_longitudinal` takes every step of DT (the coasting test above), the
    integration stops at its first step.  Nor can it carry the warm start of the wheel
    equilibria from step to step: its solver state is None."""
    ts = jnp.arange(21) * DT
    controller = diffrax.ClipStepSizeController(
        diffrax.PIDController(rtol=0.0, atol=1.0, dtmax=2 * DT, dtmin=1e-4 * DT), step_ts=ts
    )
    solver = diffrax.ImplicitEuler(
        root_finder=optx.Newton(rtol=TOL, atol=TOL), root_find_max_steps=100
    )
    term = diffrax.ODETerm(lambda t, y, args: _rate(y, 0.0, SNOW.p_w))
    sol = diffrax.diffeqsolve(
        term,
        solver,
        ts[0],
        ts[-1],
        DT,
        COASTING,
        stepsize_controller=controller,
        saveat=diffrax.SaveAt(ts=ts),
        max_steps=200,
        throw=False,
    )
    assert sol.result != diffrax.RESULTS.successful
    assert int(sol.stats["num_accepted_steps"]) <= 1
    assert solver.init(term, ts[0], ts[1], COASTING, None) is None


@pytest.mark.slow  # three root finders compiled in a simulation (make test-slow)
def test_optimistix_root_finders_cannot_replace_the_damped_newton():
    """Why `_sim/levenberg_marquardt.py` exists (runs in `make test`, so that the reason
    cannot expire unseen): the first implicit step from rest under 545 N m per wheel (the
    regularised forces' kink at rest).  `_LevenbergMarquardt` solves it (16 iterations);
    optimistix's `LevenbergMarquardt` and `Dogleg` do not in 100 (measured with optimistix
    0.1.0: residual 18 and 0.4; they converge on coasting, driving and braking steps,
    `LevenbergMarquardt` with 3x the iterations when driving).  `optx.Newton`, undamped,
    fails here too (and see the diffrax test above).  Before optimistix 0.1.0 both damped
    solvers raised on their first step instead; a raise counts as a failure here too."""
    rest = jnp.zeros(4)
    step = _implicit_step(rest, 545.0)
    ours = _solve_step(step, rest, _LevenbergMarquardt(rtol=TOL, atol=TOL))
    assert ours.result == optx.RESULTS.successful
    assert float(jnp.max(jnp.abs(step(ours.value, SNOW.p_w)))) < TOL
    for solver in (optx.LevenbergMarquardt(rtol=TOL, atol=TOL), optx.Dogleg(rtol=TOL, atol=TOL)):
        try:
            sol = _solve_step(step, rest, solver)
        except eqx.EquinoxRuntimeError:
            continue
        assert sol.result != optx.RESULTS.successful, type(solver).__name__
        assert float(jnp.max(jnp.abs(step(sol.value, SNOW.p_w)))) > 1e-2


def _passive_residual(z, theta):
    """Active rows r(a, theta) = 0 (a: 2 unknowns) and passive rows p - g(a, theta) (3)."""
    a, p = z[:2], z[2:]
    r = jnp.stack([a[0] ** 3 + a[0] - theta[0], a[1] - jnp.sin(a[0]) * theta[1]])
    g = jnp.stack([a[0] * a[1], jnp.exp(a[0]) + theta[0], theta[1] ** 2 * a[1]])
    return jnp.concatenate([r, p - g]), a[0]


def test_passive_unknowns_are_the_outputs_at_the_root_with_their_derivatives():
    """How the simulations carry the saved wheel outputs (`_LevenbergMarquardt(passive=k)`,
    `_PassiveBlockSolver`): the passive unknowns equal g at the root of the active rows,
    and their forward- and reverse-mode derivatives (the reverse mode through the
    solver's transpose) are those of g(a(theta), theta), here against the root of the
    active rows alone followed by g."""

    def passive(theta):
        solver = _LevenbergMarquardt(rtol=1e-12, atol=1e-12, passive=3)
        adjoint = optx.ImplicitAdjoint(linear_solver=_PassiveBlockSolver(passive=3))
        sol = optx.root_find(
            _passive_residual, solver, jnp.zeros(5), theta, has_aux=True, adjoint=adjoint
        )
        return sol.value

    def separate(theta):
        def active(a, theta):
            residual, _ = _passive_residual(jnp.concatenate([a, jnp.zeros(3)]), theta)
            return residual[:2]

        solver = _LevenbergMarquardt(rtol=1e-12, atol=1e-12)
        a = optx.root_find(active, solver, jnp.zeros(2), theta, adjoint=STEP_ADJOINT).value
        residual, _ = _passive_residual(jnp.concatenate([a, jnp.zeros(3)]), theta)
        return jnp.concatenate([a, -residual[2:]])

    theta = jnp.array([2.0, 0.7])
    np.testing.assert_allclose(passive(theta), separate(theta), rtol=1e-12)
    for jacobian in (jax.jacfwd, jax.jacrev):
        np.testing.assert_allclose(
            jacobian(passive)(theta), jax.jacfwd(separate)(theta), rtol=1e-10, atol=1e-14
        )
