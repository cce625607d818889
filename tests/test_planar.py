"""Planar vehicle simulation on snow: `simulate_planar` (four wheels, front steering).

Every planar simulation here is one compiled program, `_run`: `jax.vmap` over rows of
(snow, x), each row one 4 s run of 40 implicit steps of 0.1 s of a light vehicle (1.5 kN per
wheel) on the thesis's fresh snow or a softer one (p_w = 50 kPa), with the forward-mode
(`diffrax.ForwardMode`) derivatives of its end state (X, Y, yaw, u) w.r.t. (p_w, tan phi,
five steering knots, torque, u(0), r(0)).  The scenarios differ only in array values, so
they share that compile.  Besides it: one `simulate_longitudinal` program (the
straight-driving reference), small eager checks, and the notebook.
"""

import diffrax
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import snowjax as sj
from snowjax import PlanarVehicle, Status, SteeringProfile, planar_wheel_kinematics, simulate_planar

from .notebook_runner import outputs_text, run_notebook

# The whole file is in the slow tier (make test-slow): its one program, 40 implicit steps
# with forward-mode derivatives, compiles for about a minute.  `make test` reaches the
# planar vehicle's wheel forces through tests/test_properties.py and test_rut_vehicles.py.
pytestmark = pytest.mark.slow

EPS = 0.05  # default speed_eps [m/s]
WHEEL = sj.RigidWheel.thesis_tire()
RADIUS = float(WHEEL.diameter) / 2
LOAD = 1500.0  # [N] per wheel
WHEELBASE, TRACK = 2.0, 1.4  # [m]
MASS = 4 * LOAD / 9.80665  # [kg]
VEHICLE = PlanarVehicle(MASS, MASS * (WHEELBASE**2 + TRACK**2) / 12, 1.5, WHEEL, WHEELBASE, TRACK)
FRESH = sj.WongSnow.thesis_fresh_snow()  # p_w = 85.55 kPa
SOFT = sj.WongSnow.thesis_fresh_snow(p_w=50e3)
T1, DT = 4.0, 0.1
KNOTS = jnp.linspace(0.0, T1, 5)  # steering and torque knots [s]


def _pair(a, b):
    return jax.tree.map(lambda u, v: jnp.stack([u, v]), a, b)


SNOWS = _pair(FRESH, SOFT)


@jax.jit
@jax.vmap
def _run(snow, x):
    """(trajectory, d(X, Y, yaw, u at T1) / d(p_w, tan phi, x)), x = (5 steering knots
    [rad], torque per wheel [N m], u(0) [m/s], r(0) [rad/s]); vmapped over rows."""

    def end_state(z):
        trial = sj.WongSnow(z[0], snow.z_w, snow.cohesion, z[1], snow.shear_modulus)
        traj = simulate_planar(
            VEHICLE,
            trial,
            SteeringProfile(KNOTS, z[2:7]),
            sj.TorqueProfile(KNOTS, jnp.full(5, z[7])),
            T1,
            DT,
            initial=sj.InitialState(speed=z[8], yaw_rate=z[9]),
            stepping=sj.Stepping(adjoint=diffrax.ForwardMode()),
        )
        return jnp.stack([traj.x[-1], traj.y[-1], traj.yaw[-1], traj.speed[-1]]), traj

    z = jnp.concatenate([jnp.stack([snow.p_w, snow.tan_phi]), x])
    jacobian, traj = jax.jacfwd(end_state, has_aux=True)(z)
    return traj, jacobian


def _x(steering, torque, u0=0.0, r0=0.0):
    """A row x of `_run`: (5 steering knots [rad], torque [N m], u(0), r(0))."""
    knots = np.broadcast_to(np.asarray(steering, float), (5,))
    return np.concatenate([knots, [torque, u0, r0]])


def _drive(snows, rows):
    traj, jac = _run(snows, jnp.asarray(np.stack(rows)))
    return traj, np.asarray(jac)


def _row(traj, k):
    return jax.tree.map(lambda leaf: leaf[k], traj)


def _self_propelled_torques():
    """M_w at the slip where a straight-running wheel's drawbar pull vanishes, for FRESH and
    SOFT: one `solve_wheel` over a slip grid (step 0.005), interpolated linearly."""
    slips = np.linspace(-0.3, 0.1, 81)
    snows = jax.tree.map(lambda leaf: leaf[:, None], SNOWS)
    st = sj.solve_wheel(WHEEL, snows, LOAD, slips)
    torques = []
    for pull, torque in zip(np.asarray(st.drawbar_pull), np.asarray(st.torque)):
        k = int(np.flatnonzero(np.diff(np.sign(pull)) > 0)[0])
        w = pull[k] / (pull[k] - pull[k + 1])
        torques.append(float(torque[k] + w * (torque[k + 1] - torque[k])))
    return torques


@pytest.fixture(scope="module")
def torques():
    """Self-propelled torque of each snow [N m] (drawbar pull zero at that wheel torque)."""
    return _self_propelled_torques()


# ----------------------------------------------------------------------------------------
# (a) Straight driving is the longitudinal simulation; (e) vmap over two terrains
# ----------------------------------------------------------------------------------------

STRAIGHT_TORQUE = 250.0  # [N m] per wheel, from rest


@pytest.fixture(scope="module")
def straight():
    traj, _ = _drive(SNOWS, [_x(0.0, STRAIGHT_TORQUE)] * 2)
    longitudinal = sj.Vehicle(
        mass=VEHICLE.mass, wheel_inertia=VEHICLE.wheel_inertia, wheel=VEHICLE.wheel, num_wheels=4
    )
    torque = sj.TorqueProfile(KNOTS, jnp.full(5, STRAIGHT_TORQUE))
    references = [
        sj.simulate_longitudinal(longitudinal, snow, torque, T1, DT) for snow in (FRESH, SOFT)
    ]
    return traj, references


def test_straight_driving_equals_the_longitudinal_simulation(straight):
    """Two snows in one vmapped run, each equal to its own `simulate_longitudinal` run."""
    traj, references = straight
    assert np.all(traj.result == diffrax.RESULTS.successful)
    for k, ref in enumerate(references):
        row = _row(traj, k)
        assert ref.result == diffrax.RESULTS.successful
        assert float(ref.speed[-1]) > 2.0  # well above the regularisation band
        # Measured: 5e-12 relative at most (the any-terrain quadrature that `solve_wheel`
        # takes with a slip angle agrees with the front-region one far below its 1e-7).
        np.testing.assert_allclose(row.x, ref.distance, rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(row.speed, ref.speed, rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(row.wheel_speed, ref.wheel_speed, rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(row.slip, ref.slip, rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(row.drawbar_pull, ref.drawbar_pull, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(row.resisting_torque, ref.resisting_torque, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(row.sinkage, ref.sinkage, rtol=1e-9)
        # Symmetric: no side slip, no yaw, no lateral force (to rounding: measured 5e-18 m).
        for name in ("y", "yaw", "lateral_speed", "yaw_rate", "slip_angle"):
            assert np.max(np.abs(np.asarray(getattr(row, name)))) < 1e-12, name
        assert np.max(np.abs(np.asarray(row.lateral_force))) < 1e-9
        assert np.all(np.asarray(row.status) == Status.CONVERGED)
    # The two snows differ (the batch rows are independent runs).
    assert abs(float(traj.x[0, -1]) - float(traj.x[1, -1])) > 0.1


# ----------------------------------------------------------------------------------------
# (b) A steady low-speed turn follows the kinematic (Ackermann) radius
# ----------------------------------------------------------------------------------------

TURNS = (0.2, 0.1)  # steering input delta [rad]: fresh snow, soft snow
TURN_SPEED = 1.5  # [m/s]


@pytest.fixture(scope="module")
def turn(torques):
    rows = [
        _x(delta, torque, TURN_SPEED, TURN_SPEED * np.tan(delta) / WHEELBASE)
        for delta, torque in zip(TURNS, torques)
    ]
    traj, _ = _drive(SNOWS, rows)
    return traj


def test_steady_turn_follows_the_kinematic_radius(turn):
    """At 1.5 m/s (lateral acceleration 0.23 m/s^2 at delta = 0.2) the rear-axle midpoint's
    path radius is within 0.5 % of L / tan(delta) (measured: 0.14 % and 0.27 % short), and
    the CG's path, fitted by a circle over the last second, within 0.5 % of the kinematic
    sqrt(R^2 + b^2) (measured: 0.16 % and 0.28 % short)."""
    assert np.all(turn.result == diffrax.RESULTS.successful)
    b = WHEELBASE - float(VEHICLE.front_axle)  # CG to rear axle [m]
    for k, delta in enumerate(TURNS):
        row = _row(turn, k)
        kinematic = WHEELBASE / np.tan(delta)
        u, v, r = (float(getattr(row, n)[-1]) for n in ("speed", "lateral_speed", "yaw_rate"))
        rear = np.hypot(u, v - r * b) / r
        late = slice(-10, None)
        xs, ys = np.asarray(row.x[late]), np.asarray(row.y[late])
        a = np.column_stack([2 * xs, 2 * ys, np.ones_like(xs)])
        cx, cy, c = np.linalg.lstsq(a, xs**2 + ys**2, rcond=None)[0]
        fitted = np.sqrt(c + cx**2 + cy**2)
        assert abs(rear / kinematic - 1) < 5e-3, (rear, kinematic)
        # Quasi-steady: body-frame state nearly constant over the last second (measured:
        # 6e-4 relative; the self-propelled torque of straight running leaves the turn's
        # extra resistance, the lateral forces of the steered wheels, unbalanced).
        assert np.ptp(np.asarray(row.yaw_rate[late])) < 2e-3 * r
        assert np.ptp(np.asarray(row.speed[late])) < 2e-3 * u
        assert abs(fitted / np.hypot(kinematic, b) - 1) < 5e-3
        # Turning left: the rear wheels slide outwards (beta > 0), the lateral forces
        # point to the centre of the turn.
        assert np.all(np.asarray(row.slip_angle[-1, 2:]) > 0)
        assert np.all(np.asarray(row.lateral_force[-1]) > 0)
        assert np.all(np.asarray(row.status) == Status.CONVERGED)


# ----------------------------------------------------------------------------------------
# (c) Gradients against central differences; (d) from rest: no NaN
# ----------------------------------------------------------------------------------------

LANE_CHANGE = (0.0, 0.06, 0.0, -0.06, 0.0)  # [rad]
LANE_SPEED = 5.0  # [m/s]
FROM_REST = (0.1, 250.0)  # constant steering [rad], torque [N m]


@pytest.fixture(scope="module")
def gradients(torques):
    """Row 0: a lane change on fresh snow; row 1: the soft snow from rest, steering left."""
    rows = [_x(LANE_CHANGE, torques[0], LANE_SPEED), _x(*FROM_REST)]
    return _drive(SNOWS, rows)


# (name, column of the Jacobian, column of x or None for p_w, relative step, row)
CASES = [
    ("p_w", 0, None, 1e-4, 0),
    ("steering_knot_1", 3, 1, 1e-3, 0),
    ("torque", 7, 5, 1e-4, 0),
    ("steering_from_rest", 4, 2, 1e-3, 1),
]


@pytest.mark.parametrize("name, column, index, rel_step, row", CASES, ids=[c[0] for c in CASES])
def test_gradient_matches_central_differences(
    gradients, torques, name, column, index, rel_step, row
):
    """d(X, Y, yaw at T1) / d(parameter) from forward mode vs central differences, both
    snows' rows of the batch being the +h and -h runs (measured agreement: 3e-8 relative or
    better)."""
    _, jac = gradients
    x = _x(LANE_CHANGE, torques[0], LANE_SPEED) if row == 0 else _x(*FROM_REST)
    snow = FRESH if row == 0 else SOFT
    if index is None:
        h = rel_step * float(snow.p_w)
        up = sj.WongSnow(snow.p_w + h, snow.z_w, snow.cohesion, snow.tan_phi, snow.shear_modulus)
        down = sj.WongSnow(snow.p_w - h, snow.z_w, snow.cohesion, snow.tan_phi, snow.shear_modulus)
        traj, _ = _drive(_pair(up, down), [x, x])
    else:
        h = rel_step * max(abs(float(x[index])), 0.1)
        step = np.zeros_like(x)
        step[index] = h
        traj, _ = _drive(_pair(snow, snow), [x + step, x - step])
    assert np.all(traj.result == diffrax.RESULTS.successful)
    end = np.stack([np.asarray(getattr(traj, n)[:, -1]) for n in ("x", "y", "yaw")])
    fd = (end[:, 0] - end[:, 1]) / (2 * h)
    ad = jac[row, :3, column]
    assert np.all(np.abs(fd) > 1e-8)  # sensitivities worth testing
    np.testing.assert_allclose(ad, fd, rtol=1e-6, atol=1e-12)


def test_start_from_rest_is_finite(gradients):
    traj, jac = gradients
    rest = _row(traj, 1)
    assert rest.result == diffrax.RESULTS.successful
    for name in (
        "x", "y", "yaw", "speed", "lateral_speed", "yaw_rate", "wheel_speed", "slip",
        "slip_angle", "sinkage", "drawbar_pull", "lateral_force", "resisting_torque",
        "aligning_torque",
    ):  # fmt: skip
        assert np.all(np.isfinite(np.asarray(getattr(rest, name)))), name
    assert np.all(np.isfinite(jac)), "derivatives"
    assert np.all(np.asarray(rest.status) == Status.CONVERGED)
    # At rest: no force at all.  Then it drives off turning left.
    assert float(rest.speed[0]) == 0.0
    assert np.all(np.asarray(rest.drawbar_pull[0]) == 0.0)
    assert np.all(np.asarray(rest.lateral_force[0]) == 0.0)
    assert float(rest.speed[-1]) > 1.0
    assert float(rest.y[-1]) > 0 and float(rest.yaw[-1]) > 0 and float(rest.yaw_rate[-1]) > 0
    # From rest every derivative of the end position is non-zero: p_w, the steering
    # knots (the first one's only through the first 1 s), the torque, u(0).
    assert np.all(jac[1, :2, [0, 2, 3, 4, 7, 8]] != 0)


# ----------------------------------------------------------------------------------------
# Wheel kinematics, geometry, bad input (eager, no simulation)
# ----------------------------------------------------------------------------------------


def test_planar_wheel_kinematics():
    r = 0.5
    vx = np.array([0.0, 2.0, 2.0, 2.0, -2.0, 0.0, 0.01])
    vy = np.array([0.0, 0.0, -0.2, 0.2, -0.2, 1.0, 0.0])
    w = np.array([0.0, 2.5, 2.5, 2.5, -2.5, 0.0, 0.02]) / r
    slip, beta, fx, fy = planar_wheel_kinematics(vx, vy, w, r, EPS)
    long_slip, long_factor = sj.wheel_kinematics(vx, w, r, EPS)
    np.testing.assert_array_equal(slip, long_slip)  # the longitudinal slip, unchanged
    np.testing.assert_array_equal(fx, long_factor)
    expected_beta = [
        0.0,  # at rest
        0.0,  # straight
        np.arctan2(0.2, 2.0),  # sliding towards -y: beta > 0, the lateral force pushes +y
        -np.arctan2(0.2, 2.0),
        -np.arctan2(0.2, 2.0),  # backwards, sliding to -y: mirrored, the force still +y
        -np.deg2rad(85.0),  # sliding sideways (to +y) only: clipped
        0.0,
    ]
    np.testing.assert_allclose(beta, expected_beta, atol=1e-15)
    q = np.hypot(vx + w * r, 2 * vy) / (2 * EPS)
    np.testing.assert_allclose(fy, 1 - (1 - np.minimum(q, 1)) ** 2, atol=1e-15)
    assert fy[0] == 0 and fy[5] == 1  # a wheel sliding sideways is resisted

    def lateral(z):
        s, b, _, f = planar_wheel_kinematics(z[0], z[1], z[2], r, EPS)
        return f * jnp.sin(b) + s

    grad = jax.jit(jax.grad(lateral))
    assert np.all(np.isfinite(grad(jnp.zeros(3))))
    assert np.all(np.isfinite(grad(jnp.array([0.0, 1e-3, 0.0]))))


def test_vehicle_geometry():
    positions = np.asarray(VEHICLE.wheel_positions)
    np.testing.assert_allclose(positions[:, 0], [1.0, 1.0, -1.0, -1.0])
    np.testing.assert_allclose(positions[:, 1], [0.7, -0.7, 0.7, -0.7])
    np.testing.assert_allclose(np.sum(VEHICLE.wheel_load), float(VEHICLE.mass) * 9.80665)
    np.testing.assert_allclose(VEHICLE.wheel_load, LOAD)
    front_heavy = PlanarVehicle(1000.0, 500.0, 1.5, VEHICLE.wheel, 2.5, 1.5, cg_to_front_axle=1.0)
    load = np.asarray(front_heavy.wheel_load)
    np.testing.assert_allclose(load[0] / load[2], 1.5 / 1.0)
    # Ackermann: every wheel's axle line through one point of the rear axle line.
    delta = 0.3
    steer = np.asarray(VEHICLE.steer_angles(delta))
    radius = WHEELBASE / np.tan(delta)
    np.testing.assert_allclose(np.tan(steer[:2]), WHEELBASE / (radius + np.array([-0.7, 0.7])))
    assert steer[0] > delta > steer[1] and np.all(steer[2:] == 0)
    np.testing.assert_allclose(VEHICLE.steer_angles(-delta), -steer[[1, 0, 2, 3]], atol=1e-15)
    parallel = PlanarVehicle(1000.0, 500.0, 1.5, VEHICLE.wheel, 2.5, 1.5, ackermann=False)
    np.testing.assert_allclose(parallel.steer_angles(delta), [delta, delta, 0, 0])
    profile = SteeringProfile.uniform(2.0, [0.0, 0.2, 0.0])
    np.testing.assert_allclose(profile(jnp.array(0.5)), 0.1)


@pytest.mark.parametrize(
    "kwargs, error, match",
    [
        (dict(dt=0.0), ValueError, "dt"),
        (dict(steering=2.0), ValueError, "steering"),
        (dict(steering="left"), TypeError, "steering"),
        (dict(steering=SteeringProfile([1.0, 0.0], [0.0, 0.1])), ValueError, "increasing"),
        (dict(steering=SteeringProfile([0.0, 1.0], [0.0, 2.0])), ValueError, "pi/2"),
        # A controller's output: checked when it is known (here at trace time).
        (dict(steering=lambda t, y: 3.0), ValueError, "steering input is outside"),
        (dict(torque=sj.TorqueProfile([0.0, 1.0], [[1.0, 2.0]] * 2)), ValueError, "Profile"),
        (dict(torque=np.ones(3)), ValueError, "torque"),
        (dict(initial=sj.InitialState(speed=np.inf)), ValueError, "initial.speed"),
        (dict(initial=sj.InitialState(wheel_speed=np.ones(3))), ValueError, r"shape \(4,\)"),
        (dict(snow=sj.ContactModel(FRESH, shear="simplified")), ValueError, "simplified"),
        (dict(lateral=sj.Lateral()), TypeError, r"lateral=...\) is now spelled ContactModel"),
        (dict(stepping=2), TypeError, "stepping must be a snowjax.Stepping"),
        (dict(vehicle=sj.Vehicle(600.0, 1.5, sj.RigidWheel.thesis_tire())), TypeError, "Planar"),
        (dict(snow=1.0), TypeError, "terrain"),
        (dict(vehicle=PlanarVehicle(-1.0, 1.0, 1.5, VEHICLE.wheel, 2.0, 1.4)), ValueError, "mass"),
        (
            dict(vehicle=PlanarVehicle(600.0, 1.0, 1.5, VEHICLE.wheel, 2.0, 1.4, 2.5)),
            ValueError,
            "cg_to_front_axle",
        ),
        (
            dict(vehicle=PlanarVehicle(600.0, 1.0, 1.5, VEHICLE.wheel, 2.0, -1.4)),
            ValueError,
            "track_width",
        ),
    ],
)
def test_bad_input_raises(kwargs, error, match):
    args = dict(vehicle=VEHICLE, snow=FRESH, steering=0.1, torque=100.0, t1=1.0, dt=0.1)
    args.update(kwargs)
    t1, dt = args.pop("t1"), args.pop("dt")
    vehicle, snow = args.pop("vehicle"), args.pop("snow")
    steering, torque = args.pop("steering"), args.pop("torque")
    with pytest.raises(error, match=match):
        simulate_planar(vehicle, snow, steering, torque, t1, dt, **args)


def test_a_contact_model_traces_the_same_simulation():
    """A bare terrain traces the program of `ContactModel(terrain)` with the default
    lateral law (compared as jaxprs: no compile needed); the keywords that moved into the
    model, `InitialState` and `Stepping` raise a `TypeError` naming their new spelling."""
    lateral = sj.Lateral(shear_modulus=0.02)
    default = sj.Lateral()  # built outside the trace, as the cached default is

    def run(snow, **keywords):
        return simulate_planar(VEHICLE, snow, 0.1, 100.0, 0.2, 0.1, **keywords).x

    # A bare terrain is ContactModel(terrain) with the default lateral law, Lateral().
    bare = jax.make_jaxpr(lambda s: run(s))(FRESH)
    by_model = jax.make_jaxpr(lambda s: run(sj.ContactModel(s, lateral=default)))(FRESH)
    assert str(by_model) == str(bare)
    with_law = jax.make_jaxpr(lambda s: run(sj.ContactModel(s, lateral=lateral)))(FRESH)
    assert str(with_law) != str(bare)
    with pytest.raises(TypeError, match=r"simulate_planar\(lateral=...\) is now spelled"):
        run(FRESH, lateral=lateral)
    with pytest.raises(TypeError, match=r"initial=InitialState\(speed=...\)"):
        run(FRESH, initial_speed=1.0)
    with pytest.raises(TypeError, match=r"stepping=Stepping\(save_every=...\)"):
        run(FRESH, save_every=2)


def test_a_steering_controller_out_of_range_stops_the_run():
    """A controller whose output depends on the state is only known while the program runs:
    `eqx.error_if` stops it there (it used to run unflagged at 3 rad)."""
    from snowjax._sim.planar import _steering_at

    steer = jax.jit(lambda y: _steering_at(lambda t, state: 3.0 * state[0], 0.0, y))
    assert float(steer(jnp.full(10, 0.1))) == pytest.approx(0.3)
    with pytest.raises(Exception, match="steering input is outside"):
        steer(jnp.ones(10)).block_until_ready()


# ----------------------------------------------------------------------------------------
# Notebook
# ----------------------------------------------------------------------------------------


def test_notebook_runs(tmp_path):
    """A lane change on two snows, then Gauss–Newton steering to a 2 m offset."""
    text = outputs_text(run_notebook("planar_vehicle.ipynb", tmp_path))
    assert "fresh (85.55 kPa)" in text
    assert text.count("end offset 2.0000 m") == 2
