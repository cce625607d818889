"""Property-based checks of the wheel solver and of the force the snow applies in a
simulation step (hypothesis).

1. The equilibrium, over the documented range: random wheels, terrains, loads and slips
   (driving and braking), every terrain law, both stress distributions, slip angles with
   and without sidewall bulldozing, float64 and float32, and the bottomed-out corner (a
   wheel resting on the base whose braking sign change of the shear displacement lies at
   the axle, where Wong's pressure diverges): every element is converged or flagged, no
   field is inf or NaN unless the status is INVALID_INPUT, and gradients are finite
   wherever the solve converged.  Each example is a batch of cases solved in one jitted
   call (one compile per family and dtype).
2. Dissipation: over random axle and rim speeds of every sign (and side speeds, yaw rates
   and steer angles for the planar vehicle), the power the snow delivers to a wheel,
   `F_x v_x + F_y v_y - M_w omega` with the signs of `wheel_forces` (`I domega/dt =
   T - M_w`), is never positive, on every terrain law and both stress distributions; and
   with zero drive torque a coasting vehicle's kinetic energy never increases
   (`simulate_longitudinal`, `simulate_planar`; `snowjax.mjx` in `tests/test_mjx.py`).
3. The rover's environment (`snowjax.mjx.SnowRoverEnv`) under random actions, NaN and
   +-inf among them, float64 and float32: observations and rewards finite, no instance
   poisoned by a NaN action, a broken state ends its episode; its `State.replace`.
"""

import os
import subprocess
import sys

import diffrax
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from hypothesis import Phase, given, settings
from hypothesis import strategies as st

import snowjax as sj
from snowjax import Status
from snowjax._sim.planar import _body_to_wheel, _planar_wheel_forces
from snowjax._wheel.passes import _resolved

from .random_cases import UNIT_ROWS, any_terrain_inputs, tire_and_rut_inputs

SHEAR_MODELS = ("classic", "simplified", "none")
BATCH = 24
FIELDS = ("entry_angle", "sinkage", "motion_resistance", "thrust", "drawbar_pull", "torque")
ALL_FIELDS = (*FIELDS, "lateral_force", "aligning_torque")
TERRAIN_PARAMETERS = {
    "wong": ("p_w", "z_w", "cohesion", "tan_phi", "shear_modulus"),
    "bekker": ("n", "k_c", "k_phi", "cohesion", "tan_phi", "shear_modulus"),
    "reece": ("n", "k_c_prime", "k_phi_prime", "cohesion", "tan_phi", "shear_modulus"),
    "layered": ("ice_failure_pressure",),
}


def _uniform(lo, hi):
    return st.floats(lo, hi, allow_nan=False, allow_infinity=False)


def _log_uniform(lo, hi):
    return _uniform(np.log(lo), np.log(hi)).map(np.exp)


# ---------------------------------------------------------------------------------------
# 1a. WongSnow on the front region (the thesis's quadrature), every shear model
# ---------------------------------------------------------------------------------------

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
    state = sj.solve_wheel(wheel, sj.ContactModel(snow, shear=shear), load, slip)
    return jnp.sum(state.drawbar_pull), state


@jax.jit
def _solve_and_differentiate(wheel, snow, load, slip):
    """States for every shear model; gradients of the summed drawbar pull w.r.t. the snow
    (per element: the elements are independent) for the classic and simplified ones."""
    states, grads = {}, {}
    for shear in SHEAR_MODELS:
        if shear == "none":
            states[shear] = sj.solve_wheel(wheel, sj.ContactModel(snow, shear=shear), load, slip)
            continue
        fn = jax.grad(_drawbar_pull_sum, has_aux=True)
        grads[shear], states[shear] = fn(snow, wheel, load, slip, shear)
    return states, grads


def _check_state(state, dtype, label, fields=FIELDS):
    """Every element flagged or converged, no inf/NaN field; returns the status."""
    status = np.asarray(state.status)
    assert np.all(status != Status.INVALID_INPUT), label  # every case is in range
    assert np.all(np.isin(status, [s.value for s in Status])), label
    for name in fields:
        value = np.asarray(getattr(state, name))
        assert value.dtype == dtype
        bad = ~np.isfinite(value)
        assert not bad.any(), (label, name, status[bad], value[bad])
    # At most a small share of the batch may be left unbalanced.
    assert np.mean(status == Status.NOT_CONVERGED) <= 0.1, (label, status)
    return status


def _tiers(fast, kinds=("wong", "bekker", "reece", "layered")):
    """Every (kind, dtype) pair for a parametrisation; the pairs not in `fast` run in the
    slow tier (`make test-slow`): each pair compiles programs of its own."""
    return [
        pytest.param(kind, dtype, marks=() if (kind, dtype) in fast else pytest.mark.slow)
        for kind in kinds
        for dtype in (jnp.float64, jnp.float32)
    ]


def _check_gradients(grads, status, names, label):
    converged = status == Status.CONVERGED
    for name in names:
        g = np.asarray(getattr(grads, name))
        assert np.all(np.isfinite(g[converged])), (label, name, g[converged])


@pytest.mark.parametrize("dtype", [jnp.float64, pytest.param(jnp.float32, marks=pytest.mark.slow)])
@settings(max_examples=10, deadline=None, derandomize=True)
@given(cases=BATCHES)
def test_converged_or_flagged_never_nan_and_finite_gradients(cases, dtype):
    wheel, snow, load, slip = _inputs(cases, dtype)
    states, grads = _solve_and_differentiate(wheel, snow, load, slip)
    for shear, state in states.items():
        status = _check_state(state, dtype, shear)
        if shear in grads:
            _check_gradients(grads[shear], status, TERRAIN_PARAMETERS["wong"], shear)


def test_float32_gradient_at_a_vanishing_braking_slip_is_finite():
    """Found by the property test: a float32 slip of -1.7e-36 made the simplified model's
    braking layout overflow (level / (tau1 B) with B ~ -slip / 3) in the capacity check,
    whose NaN did not show in the values but poisoned every gradient."""
    f32 = np.float32
    wheel = sj.RigidWheel(f32(0.5), f32(0.5))

    def drawbar_pull(p_w, slip):
        snow = sj.WongSnow(p_w, f32(0.05), f32(np.exp(5)), f32(0.5), f32(np.exp(-5)))
        return sj.solve_wheel(
            wheel, sj.ContactModel(snow, shear="simplified"), f32(np.exp(5)), slip
        ).drawbar_pull

    grad = jax.jit(jax.grad(drawbar_pull, argnums=(0, 1)))
    tiny, zero = grad(f32(np.exp(9)), f32(-1.7339896679487998e-36)), grad(f32(np.exp(9)), f32(0))
    for g_tiny, g_zero in zip(tiny, zero):
        assert np.isfinite(g_tiny)
        np.testing.assert_allclose(g_tiny, g_zero, rtol=1e-4)


# ---------------------------------------------------------------------------------------
# 1b. Every terrain law, both distributions, slip angles, the bottomed-out corner
# ---------------------------------------------------------------------------------------

UNIT = _uniform(0.0, 1.0)
# One case: 13 numbers in [0, 1] mapped onto the ranges of `random_cases.any_terrain_inputs`,
# and whether it is a bottomed-out-corner case.
ANY_CASE = st.tuples(st.tuples(*[UNIT] * UNIT_ROWS), st.booleans())
ANY_BATCHES = st.lists(ANY_CASE, min_size=BATCH, max_size=BATCH)
# (distribution, slip angle, bulldozing, shear): every terrain runs all of them in one
# compiled call, with gradients where there is shear (Wong snow on the front region without
# a slip angle is 1a).  Between them: both distributions, slip angles with and without
# bulldozing, with and without shear.
CONFIGS = (
    ("front", True, True, "classic"),
    ("wong_reece", False, False, "classic"),
    ("wong_reece", True, False, "none"),
)


def _any_terrain_inputs(kind, cases, dtype):
    unit = np.array([c[0] for c in cases], dtype=np.float64).T
    return any_terrain_inputs(kind, unit, [c[1] for c in cases], dtype)


def _forces_sum(terrain, wheel, distribution, lateral, load, slip, beta, config):
    dist, steered, bulldozing, shear = config
    state = sj.solve_wheel(
        wheel,
        sj.ContactModel(
            terrain,
            distribution=distribution if dist == "wong_reece" else None,
            shear=shear,
            lateral=sj.Lateral(lateral.shear_modulus, lateral.unit_weight, bulldozing=bulldozing),
        ),
        load,
        slip,
        slip_angle=beta if steered else None,
    )
    return jnp.sum(state.drawbar_pull + state.lateral_force), state


@jax.jit
def _any_terrain_solve(wheel, terrain, distribution, lateral, load, slip, beta):
    """States of every `CONFIGS` entry; gradients of the summed drawbar pull and lateral
    force w.r.t. the terrain for those with shear."""
    out = []
    for config in CONFIGS:
        args = (terrain, wheel, distribution, lateral, load, slip, beta, config)
        if config[3] == "none":
            out.append((None, _forces_sum(*args)[1]))
        else:
            out.append(jax.grad(_forces_sum, has_aux=True)(*args))
    return out


@pytest.mark.parametrize(("kind", "dtype"), _tiers({("bekker", jnp.float32)}))
@settings(max_examples=4, deadline=None, derandomize=True)
@given(cases=ANY_BATCHES)
def test_every_terrain_converged_or_flagged_never_nan_and_finite_gradients(cases, kind, dtype):
    inputs = _any_terrain_inputs(kind, cases, dtype)
    for config, (grads, state) in zip(CONFIGS, _any_terrain_solve(*inputs)):
        label = (kind, *config)
        status = _check_state(state, dtype, label, ALL_FIELDS)
        if grads is not None:
            names = [f"top.{n}" for n in ("p_w", "z_w", "cohesion")] if kind == "layered" else []
            for name in (*TERRAIN_PARAMETERS[kind], *names):
                leaf = grads
                for part in name.split("."):
                    leaf = getattr(leaf, part)
                g = np.asarray(leaf)
                assert np.all(np.isfinite(g[status == Status.CONVERGED])), (label, name)


@pytest.mark.parametrize(
    "terrain, slip",
    [
        # The braking sign change 1e-8 rad from the axle of a bottomed-out wheel: the
        # nodes next to it had a sinkage that rounded to the base (float64: inf forces).
        (sj.LayeredSnow.ice_layer_example(), -0.40922),
        (sj.WongSnow.thesis_fresh_snow(), 0.2),
    ],
)
@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_bottomed_out_any_terrain_path_is_finite(terrain, slip, dtype):
    """The reproductions: the thesis tyre bottomed out at 20 kN (float32: every
    bottomed-out front-region contact on a Wong-law layer got NaN/inf forces)."""
    f = lambda x: jax.tree_util.tree_map(lambda y: jnp.asarray(y, dtype), x)  # noqa: E731
    state = sj.solve_wheel(
        f(sj.RigidWheel.thesis_tire()), f(terrain), dtype(20e3), dtype(slip), slip_angle=dtype(0.1)
    )
    assert int(state.status) == Status.BOTTOMED_OUT
    for name in ALL_FIELDS:
        assert np.isfinite(float(getattr(state, name))), name


# ---------------------------------------------------------------------------------------
# 1c. Deflecting tyres and ruts on every terrain law
# ---------------------------------------------------------------------------------------

# One case: an any-terrain case (1b) and three more numbers in [0, 1]: the soft tyre's
# inflation pressure, its flexing coefficient and the rut's depth as a share of the base's.
TIRE_CASE = st.tuples(ANY_CASE, st.tuples(UNIT, UNIT, UNIT))
TIRE_BATCHES = st.lists(TIRE_CASE, min_size=BATCH, max_size=BATCH)
# A failing batch is reported as found: shrinking a batch of solves takes minutes.
NO_SHRINK = (Phase.explicit, Phase.reuse, Phase.generate)


def _tires_and_ruts(kind, cases, dtype):
    unit = np.array([c[0][0] for c in cases], dtype=np.float64).T
    extra = np.array([c[1] for c in cases], dtype=np.float64).T
    return tire_and_rut_inputs(kind, unit, extra, [c[0][1] for c in cases], dtype)


@jax.jit
def _tire_and_rut_solve(wheel, tires, terrain, distribution, load, slip, ruts):
    """States of the tyres (front region, Wong–Reece), the rim (front region, Wong–Reece)
    and the rim on the ruts (front region)."""
    out = {}
    for name, dist in (("front", None), ("wong_reece", distribution)):
        out[f"tire {name}"] = sj.solve_wheel(tires, sj.ContactModel(terrain, dist), load, slip)
        out[f"rim {name}"] = sj.solve_wheel(wheel, sj.ContactModel(terrain, dist), load, slip)
    out["rut"] = sj.solve_wheel(wheel, ruts, load, slip)
    return out


@pytest.mark.parametrize(("kind", "dtype"), _tiers({("wong", jnp.float32)}))
@settings(max_examples=2, deadline=None, derandomize=True, phases=NO_SHRINK)
@given(cases=TIRE_BATCHES)
def test_tyres_and_ruts_never_nan_and_a_stiff_tyre_is_the_rim(
    cases, kind, dtype, optimised_compile
):
    """Soft tyres (with flexing) and stiff ones, ruts of zero depth, mid-depth and at the
    base, driving and braking, the bottomed-out corner: every element converged or
    flagged, no inf/NaN (`random_cases.tire_and_rut_inputs`); and a 1e9 Pa tyre is the
    rim on every law and both distributions, its status and every field within 1e-6
    (float32: 1e-3).  Float32 compiles with XLA's optimisations (`conftest.py`'s
    `optimised_compile`: the suite's switches miscompiled a float32 case at the cap)."""
    inputs = _tires_and_ruts(kind, cases, dtype)
    with optimised_compile(dtype == jnp.float32):
        states = _tire_and_rut_solve(*inputs)
    for label, state in states.items():
        _check_state(state, dtype, (kind, label))
    stiff = slice(BATCH // 2, None)
    rtol = 1e-6 if dtype == jnp.float64 else 1e-3
    for dist in ("front", "wong_reece"):
        tire, rim = states[f"tire {dist}"], states[f"rim {dist}"]
        np.testing.assert_array_equal(tire.status[stiff], rim.status[stiff])
        for name in FIELDS:
            expected = np.asarray(getattr(rim, name)[stiff])
            got = np.asarray(getattr(tire, name)[stiff])
            scale = np.abs(np.asarray(rim.motion_resistance[stiff]))
            atol = rtol * scale if name in ("thrust", "drawbar_pull") else 0.0
            error = np.abs(got - expected) - rtol * np.abs(expected) - atol
            assert np.all(error <= 0), (kind, dist, name, got[error > 0], expected[error > 0])


@pytest.mark.parametrize("kind", ["wong", "bekker", "reece", "layered"])
@settings(max_examples=5, deadline=None, derandomize=True, phases=NO_SHRINK)
@given(cases=ANY_BATCHES, moduli=st.tuples(_log_uniform(1e4, 1e8), _log_uniform(1e-3, 1e9)))
def test_a_deeper_rut_never_leaves_a_shallower_floor(cases, moduli, kind):
    """`Rut.floor_depth` is non-decreasing in `rut_sinkage` from the surface to the base
    (0.5 m on a law without one), for random terrains of every law and unloading moduli
    k_0 10 kPa/m-100 MPa/m, A_u up to 1 GPa/m^2 (the audit: on Wong snow the floor
    returned to the surface as the rut reached the base)."""
    terrain = _any_terrain_inputs(kind, cases, jnp.float64)[1]
    depth = np.asarray(terrain.depth)
    base = np.where(np.isfinite(depth), depth, 0.5)
    z_u = jnp.asarray(np.linspace(0.0, 1.0, 2001)[:, None] * base)  # (grid, batch)
    floor = np.asarray(sj.Rut(terrain, z_u, 0.3, *moduli).floor_depth)
    assert np.all(np.isfinite(floor))
    assert np.all(np.diff(floor, axis=0) >= -1e-12 * base), np.diff(floor, axis=0).min()
    assert np.all((floor >= 0) & (floor <= np.asarray(z_u) * (1 + 1e-12)))


# ---------------------------------------------------------------------------------------
# 2. Dissipation: the snow never drives a wheel or a vehicle
# ---------------------------------------------------------------------------------------

WHEEL = sj.RigidWheel.thesis_tire()
RADIUS = float(WHEEL.diameter) / 2
EPS = 0.05  # default speed_eps [m/s]
TERRAINS = {
    "wong": sj.WongSnow.thesis_plate_rule_snow(),  # drawbar pull < 0 at slip 1
    "bekker": sj.BekkerSoil.snow_us(),
    "reece": sj.ReeceSoil(1.1, 5.0, 800.0, 15e3, 1e3, 0.5, shear_modulus=0.02),
    "layered": sj.LayeredSnow.ice_layer_example(),
}


def _speed(u):
    """A speed [m/s] of either sign: half in the regularisation band, half up to 10 m/s."""
    return np.where(u[1] < 0.5, 0.12, 10.0) * (2 * u[0] - 1)


SPEEDS = st.tuples(UNIT, UNIT, UNIT, UNIT, _log_uniform(0.3, 3.0), UNIT)


def _power_scale(*terms):
    """Rounding scale of a sum of power terms [W]."""
    return sum(np.abs(np.asarray(t)) for t in terms)


def _scaled_terrain(terrain, factor):
    """The preset with its pressure scale multiplied by `factor` (random snows)."""
    if isinstance(terrain, sj.WongSnow):
        return sj.WongSnow(terrain.p_w * factor, terrain.z_w, terrain.cohesion,
                           terrain.tan_phi, terrain.shear_modulus)  # fmt: skip
    if isinstance(terrain, sj.LayeredSnow):
        top, bottom = (_scaled_terrain(s, factor) for s in (terrain.top, terrain.bottom))
        return sj.LayeredSnow(top, bottom, terrain.ice_failure_pressure * factor)
    if isinstance(terrain, sj.BekkerSoil):
        return sj.BekkerSoil(terrain.n, terrain.k_c * factor, terrain.k_phi * factor,
                             terrain.cohesion, terrain.tan_phi,
                             shear_modulus=terrain.shear_modulus)  # fmt: skip
    return sj.ReeceSoil(terrain.n, terrain.k_c_prime * factor, terrain.k_phi_prime * factor,
                        terrain.unit_weight, terrain.cohesion, terrain.tan_phi,
                        shear_modulus=terrain.shear_modulus)  # fmt: skip


@jax.jit
def _wheel_power(terrain, distribution, speed, wheel_speed, load):
    """(power [W], power scale [W], status) of `wheel_forces`, front region and Wong–Reece."""
    out = []
    for dist in (None, distribution):
        f = sj.wheel_forces(speed, wheel_speed, load, WHEEL, sj.ContactModel(terrain, dist))
        terms = (f.longitudinal_force * speed, -f.resisting_torque * wheel_speed)
        out.append((*terms, jnp.abs(terms[0]) + jnp.abs(terms[1]), f.status))
    return out


@pytest.mark.parametrize(
    "kind", [pytest.param(k, marks=pytest.mark.slow if k != "wong" else ()) for k in TERRAINS]
)
@settings(max_examples=5, deadline=None, derandomize=True)
@given(states=st.lists(SPEEDS, min_size=64, max_size=64))
def test_snow_never_delivers_power_to_a_wheel(states, kind):
    """`F v - M_w omega <= 0` for axle and rim speeds of every sign, in and out of the
    regularisation band, on every terrain law and both distributions (random snow
    stiffness: the preset's pressure scale times 0.3-3).  And a locked wheel, or one
    spinning against the axle's motion (omega r v <= 0), never pushes the axle along its
    motion, `F v <= 0`: the total power alone cannot show that (a counter-rotating wheel's
    shear absorbs more than a wrongly signed resistance gives).  A free-rolling wheel may:
    at slip 0 the model's thrust exceeds its motion resistance on some soils (the rim
    still slides backwards over the snow ahead of the bottom point)."""
    x = np.array(states).T
    speed, rim = _speed(x[0:2]), _speed(x[2:4])
    terrain = _scaled_terrain(TERRAINS[kind], float(x[4][0]))
    load = 500.0 + 5000.0 * x[5]
    against = rim * speed <= 0
    for axle, spin, scale, status in _wheel_power(
        terrain, sj.WongReece(0.4, 0.3, -0.05), speed, rim / RADIUS, load
    ):
        assert np.all(np.asarray(status) != Status.INVALID_INPUT)
        power, scale = np.asarray(axle + spin), np.asarray(scale)
        worst = int(np.argmax(power - 1e-12 * scale))
        assert power[worst] <= 1e-12 * scale[worst], (speed[worst], rim[worst], power[worst])
        pushed = against & (np.asarray(axle) > 0)
        assert not pushed.any(), (speed[pushed], rim[pushed], np.asarray(axle)[pushed])


def test_the_issue_reproduction_resists_the_motion():
    """v = 8 m/s, omega r = -11 m/s on the plate-rule snow (drawbar pull < 0 at slip 1):
    the snow pushed the axle forward with +136 N; it must resist the motion."""
    f = sj.wheel_forces(8.0, -30.0, 1500.0, WHEEL, sj.WongSnow.thesis_plate_rule_snow())
    assert int(f.status) == Status.CONVERGED
    assert float(f.longitudinal_force) < -100.0
    assert float(f.resisting_torque) < 0.0  # the torque on the wheel spins it up forwards


PLANAR = sj.PlanarVehicle(1500.0, 2500.0, 1.5, WHEEL, 2.6, 1.6)


@jax.jit
def _planar_power(terrain, u, v, r, omega, delta):
    """Per-wheel power (and its scale) and the vehicle's, with the aligning torques'
    `M_z r`, of the planar wheel forces, without and with sidewall bulldozing."""
    steer = jax.vmap(PLANAR.steer_angles)(delta)
    vx, vy = _body_to_wheel(PLANAR, u, v, r, steer)
    out = []
    for lateral in (sj.Lateral(), sj.Lateral(None, 1.2e4, bulldozing=True)):
        contact = sj.ContactModel(terrain, lateral=lateral)
        virgin = _resolved(None, 4)
        f = _planar_wheel_forces(PLANAR, contact, u, v, r, omega, steer, EPS, None, 64, virgin)
        terms = (f.drawbar_pull * vx, f.lateral_force * vy, -f.resisting_torque * omega)
        wheel = sum(terms)
        vehicle = jnp.sum(wheel + f.aligning_torque * r[:, None], axis=1)
        scale = sum(jnp.abs(t) for t in terms)
        against = omega * vx <= 0
        out.append((wheel, scale, vehicle, jnp.where(against, terms[0], 0.0), f.status))
    return out


@pytest.mark.parametrize("kind", ["wong", pytest.param("layered", marks=pytest.mark.slow)])
@settings(max_examples=4, deadline=None, derandomize=True)
@given(states=st.lists(st.tuples(*[UNIT] * 14), min_size=32, max_size=32))
def test_snow_never_delivers_power_to_a_steered_wheel(states, kind):
    """`F_x v_x + F_y v_y - M_w omega <= 0` for each wheel of the planar vehicle, at random
    body velocities (u, v, yaw rate r), spins of every sign and steer angles, with and
    without bulldozing; the vehicle's whole power (with `M_z r`) is not positive; and a
    locked or counter-rotating wheel never pushes along its heading, `F_x v_x <= 0`."""
    x = np.array(states).T
    u, v = _speed(x[0:2]), 0.5 * _speed(x[2:4])
    r = 0.5 * (2 * x[4] - 1) * np.where(x[5] < 0.5, 0.1, 1.0)
    omega = np.stack([_speed(x[6 + 2 * k : 8 + 2 * k]) for k in range(4)], -1) / RADIUS
    delta = (2 * x[13] - 1) * 0.5
    for wheel, scale, vehicle, pushed, status in _planar_power(
        TERRAINS[kind], u, v, r, omega, delta
    ):
        assert np.all(np.asarray(status) != Status.INVALID_INPUT)
        wheel, scale = np.asarray(wheel), np.asarray(scale)
        assert np.all(wheel <= 1e-12 * scale), wheel.max()
        assert np.all(np.asarray(vehicle) <= 0.0), np.asarray(vehicle).max()
        assert np.all(np.asarray(pushed) <= 0.0), np.asarray(pushed).max()


# Coasting and braked vehicles: one compiled program per simulation, vmapped over cases.
LONGITUDINAL = sj.Vehicle(mass=4 * 3500.0 / 9.80665, wheel_inertia=1.5, wheel=WHEEL, num_wheels=4)


@jax.jit
@jax.vmap
def _longitudinal(speed, wheel_speed, torque):
    return sj.simulate_longitudinal(
        LONGITUDINAL,
        TERRAINS["wong"],
        torque,
        0.5,
        0.025,
        initial=sj.InitialState(speed=speed, wheel_speed=wheel_speed),
    )


def _longitudinal_energy(traj):
    speed, spin = np.asarray(traj.speed), np.asarray(traj.wheel_speed)
    inertia = float(LONGITUDINAL.wheel_inertia)
    return 0.5 * float(LONGITUDINAL.mass) * speed**2 + 0.5 * inertia * np.sum(spin**2, -1)


@pytest.fixture(scope="module")
def longitudinal_runs():
    """One vmapped batch (one compile): six coasting runs from random speeds and wheel
    spins of every sign (counter-rotating wheels included), then -2000 N m per wheel from
    8 m/s and 600 N m per wheel from rest."""
    x = np.random.default_rng(5).uniform(size=(8, 6))
    spins = np.stack([_speed(x[2:4]), _speed(x[4:6]), -_speed(x[0:2]), _speed(x[6:8])], -1)
    speed = np.append(_speed(x[0:2]), [8.0, 0.0])
    spins = np.concatenate([spins / RADIUS, [[8.0 / RADIUS] * 4, [0.0] * 4]])
    torque = np.concatenate([np.zeros((6, 4)), [[-2000.0] * 4, [600.0] * 4]])
    traj = _longitudinal(speed, spins, torque)
    assert np.all(np.asarray(traj.result == diffrax.RESULTS.successful))
    return traj


@pytest.mark.slow  # a vmapped batch of 160 implicit steps
def test_coasting_longitudinal_vehicle_never_gains_energy(longitudinal_runs):
    """Zero drive torque on the plate-rule snow: the kinetic energy never increases."""
    energy = _longitudinal_energy(longitudinal_runs)[:6]
    assert np.all(np.diff(energy, axis=1) <= 1e-9 * energy[:, :-1] + 1e-9)


@pytest.mark.slow
def test_braked_vehicle_slows_and_driven_vehicle_does_not_go_backwards(longitudinal_runs):
    """The reproductions (found on the layered snow; here the plate-rule snow, whose
    drawbar pull at slip 1 is negative too): -2000 N m per wheel from 8 m/s sped the
    vehicle up to 10 m/s in 1 s; 600 N m per wheel from rest drove it backwards (here,
    before the fix: 8.23 m/s and -0.31 m/s after 0.5 s)."""
    braked, driven = np.asarray(longitudinal_runs.speed)[6:]
    assert np.all(np.diff(braked) <= 1e-9)  # never speeds up while moving forwards
    assert braked[-1] < 7.0  # and it slows down (6.6 m/s after 0.5 s on this soft snow)
    # On this snow the drawbar pull at slip 1 is negative: the driven vehicle digs in and
    # creeps forward inside the regularisation band, never backwards.
    assert np.all(driven >= -1e-9) and driven.max() < 2 * EPS


PLANAR_ROWS = 4


@jax.jit
@jax.vmap
def _planar(u0, r0, omega0, delta):
    return sj.simulate_planar(
        PLANAR,
        TERRAINS["wong"],
        delta,
        0.0,
        0.5,
        0.05,
        initial=sj.InitialState(speed=u0, yaw_rate=r0, wheel_speed=omega0),
    )


@pytest.mark.slow  # a vmapped batch of planar runs
def test_coasting_planar_vehicle_never_gains_energy():
    """Zero drive torque, constant steering, random speeds, yaw rates and wheel spins of
    every sign on the plate-rule snow: translational, yaw and spin energy never increase."""
    rng = np.random.default_rng(3)
    u0 = rng.uniform(-8, 8, PLANAR_ROWS)
    r0 = rng.uniform(-0.5, 0.5, PLANAR_ROWS)
    omega0 = rng.uniform(-8, 8, (PLANAR_ROWS, 4)) / RADIUS
    delta = rng.uniform(-0.4, 0.4, PLANAR_ROWS)
    traj = _planar(u0, r0, omega0, delta)
    assert np.all(np.asarray(traj.result == diffrax.RESULTS.successful))
    mass, yaw = float(PLANAR.mass), float(PLANAR.yaw_inertia)
    energy = (
        0.5 * mass * (np.asarray(traj.speed) ** 2 + np.asarray(traj.lateral_speed) ** 2)
        + 0.5 * yaw * np.asarray(traj.yaw_rate) ** 2
        + 0.5 * 1.5 * np.sum(np.asarray(traj.wheel_speed) ** 2, -1)
    )
    assert np.all(np.diff(energy, axis=1) <= 1e-9 * energy[:, :-1] + 1e-9)


# ---------------------------------------------------------------------------------------
# 3. The rover's environment under any action, NaN and inf included
# ---------------------------------------------------------------------------------------

ENV_BATCH, ENV_STEPS = 8, 4
# An action component: any finite value (clipped to [-1, 1]), NaN or +-inf.
ACTION = st.one_of(_uniform(-3.0, 3.0), st.sampled_from([np.nan, np.inf, -np.inf]))
ACTIONS = st.lists(st.tuples(ACTION, ACTION), min_size=ENV_BATCH * ENV_STEPS,
                   max_size=ENV_BATCH * ENV_STEPS)  # fmt: skip

# The rollout, run in this process (float64) and in a float32 one (`_ENV_SCRIPT`):
# reset a batch, break one instance's state (NaN velocities), then step with the actions.
_ENV_CODE = """
import jax, jax.numpy as jnp
import snowjax.mjx as smjx

env = smjx.SnowRoverEnv(episode_length=20, frame_skip=2)

@jax.jit
def rollout(key, actions):
    state = jax.vmap(env.reset)(jax.random.split(key, actions.shape[1]))
    qvel = state.data.qvel.at[-1].set(jnp.nan)  # the last instance's state is broken
    state = state.replace(data=state.data.replace(qvel=qvel))
    def body(state, action):
        state = jax.vmap(env.step)(state, action)
        return state, (state.obs, state.reward, state.done, state.data.qpos)
    return jax.lax.scan(body, state, actions)[1]
"""


def _mjx_or_skip():
    """`snowjax.mjx`, or a skip where the `mjx` extra is absent (a failure in CI)."""
    try:
        import snowjax.mjx  # noqa: F401
    except ImportError:
        if os.environ.get("CI", "").lower() == "true":
            raise
        pytest.skip("the snowjax[mjx] extra (mujoco, mujoco-mjx) is not installed")


@pytest.fixture(scope="module")
def rover_rollout():
    _mjx_or_skip()
    namespace: dict = {}
    exec(_ENV_CODE, namespace)  # noqa: S102
    return namespace["rollout"]


def _check_rollout(obs, reward, done, qpos, dtype):
    """Every observation and reward finite; a non-finite state only in an instance that
    is done (the broken last one from its first step, no other)."""
    assert obs.dtype == dtype and reward.dtype == dtype
    assert np.all(np.isfinite(obs)) and np.all(np.isfinite(reward))
    assert np.all(done[:, -1] == 1.0) and np.all(reward[:, -1] == 0.0)
    broken = ~np.all(np.isfinite(qpos), axis=-1)
    assert not broken[:, :-1].any()  # NaN actions never poison an instance
    assert np.all(done[~np.all(np.isfinite(qpos), axis=-1)] == 1.0)


@settings(max_examples=3, deadline=None, derandomize=True, phases=NO_SHRINK)
@given(actions=ACTIONS)
def test_the_rover_environment_never_turns_nan_under_any_action(rover_rollout, actions):
    """Random actions, a quarter of their components NaN or +-inf on average, over a
    batch whose last instance starts from a broken state (float64): observations and
    rewards stay finite; NaN actions never poison an instance (the audit: NaN passed
    `jnp.clip` and the instance stayed NaN under later valid actions); the broken
    instance ends its episode (`done` = 1) with zero reward, as Playground's do."""
    a = np.asarray(actions, np.float64).reshape(ENV_STEPS, ENV_BATCH, 2)
    obs, reward, done, qpos = (np.asarray(x) for x in rover_rollout(jax.random.key(0), a))
    _check_rollout(obs, reward, done, qpos, np.float64)


@pytest.mark.slow  # a float32 process compiling the rollout again
def test_the_rover_environment_never_turns_nan_in_float32(tmp_path):
    """The same rollout in a float32 process, with fixed random actions (a third of
    their components NaN or +-inf)."""
    _mjx_or_skip()
    rng = np.random.default_rng(7)
    a = rng.uniform(-3, 3, (ENV_STEPS, ENV_BATCH, 2))
    a[rng.uniform(size=a.shape) < 0.33] = rng.choice([np.nan, np.inf, -np.inf])
    np.save(tmp_path / "actions.npy", a.astype(np.float32))
    script = _ENV_CODE + (
        "import numpy as np\n"
        f"a = jnp.asarray(np.load({str(tmp_path / 'actions.npy')!r}))\n"
        "out = rollout(jax.random.key(0), a)\n"
        f"np.savez({str(tmp_path / 'out.npz')!r}, *[np.asarray(x) for x in out])\n"
    )
    env = dict(os.environ, JAX_ENABLE_X64="0", JAX_PLATFORMS="cpu")
    done = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr[-3000:]
    out = np.load(tmp_path / "out.npz")
    _check_rollout(*(out[f"arr_{k}"] for k in range(4)), np.float32)


def test_the_environment_state_takes_replace_as_the_wrappers_call_it(rover_rollout):
    """`State.replace(done=...)` (Brax's `AutoResetWrapper` / `EpisodeWrapper`, MuJoCo
    Playground's `BraxAutoResetWrapper`): eagerly, under `jit` and under `vmap` (the
    audit: an equinox Module without `replace`, `AttributeError`)."""
    import snowjax.mjx as smjx

    env = smjx.SnowRoverEnv(episode_length=20, frame_skip=2)
    state = jax.vmap(env.reset)(jax.random.split(jax.random.key(1), 2))
    done = state.replace(done=jnp.ones_like(state.done))
    assert isinstance(done, smjx.State) and np.all(np.asarray(done.done) == 1.0)
    np.testing.assert_array_equal(done.obs, state.obs)
    reset = jax.jit(jax.vmap(lambda s: s.replace(done=jnp.zeros_like(s.done), reward=s.reward)))
    again = reset(done)
    assert np.all(np.asarray(again.done) == 0.0)
    assert jax.tree.structure(again) == jax.tree.structure(state)
