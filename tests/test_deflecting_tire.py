"""The deflecting tyre (`snowjax.DeflectingTire`): against an independent SciPy reference
(`tests/reference_tire.py`) on Wong snow, Bekker soil and a terrain law defined outside
the package, in both modes; the rigid limit; gradients across the mode boundary; the
smoothness of the switch; float32; bad input."""

from __future__ import annotations

import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import snowjax as sj

from . import reference_terrain as ref_terrain
from . import reference_tire as ref
from .test_extension import HyperbolicSnow

pytestmark = pytest.mark.filterwarnings("ignore::scipy.integrate.IntegrationWarning")

D, B, H = 0.736, 0.235, 0.176  # the thesis tyre's size (P235/75R15)
CARCASS = 5e3  # p_c [Pa]
FLEXING = 0.015  # f_h, the hard-surface rolling-resistance coefficient [-]
SNOW = sj.WongSnow.thesis_fresh_snow()
SOIL = sj.BekkerSoil.snow_us()


def _tire(inflation, carcass=CARCASS, sharpness=30.0, flexing=0.0):
    return sj.DeflectingTire(D, B, H, inflation, carcass, sharpness, flexing)


def _reference_law(terrain):
    if isinstance(terrain, sj.WongSnow):
        return ref_terrain.wong(float(terrain.p_w), float(terrain.z_w))
    if isinstance(terrain, sj.BekkerSoil):
        return ref_terrain.bekker(float(terrain.n), float(terrain.k_c), float(terrain.k_phi))
    k, h = float(terrain.modulus), float(terrain.layer_depth)
    return lambda z, b: k * max(z, 0.0) / (1 - max(z, 0.0) / h)


def _strength(terrain):
    return float(terrain.cohesion), float(terrain.tan_phi), float(terrain.shear_modulus)


# (terrain, distribution (c1, c2, c3) or None, load [N], inflation pressures [Pa]):
# each batch spans the rigid mode (delta < 1 um), the switch and the elastic mode
# (delta of centimetres), driving and braking.
CASES = {
    "wong-front": (SNOW, None, 4000.0, (3e5, 1e5, 6e4)),
    "bekker-front": (SOIL, None, 1500.0, (1e5, 2.1e4, 1.5e4)),
    "bekker-wong-reece-rear": (SOIL, (0.43, 0.32, -0.3), 1000.0, (1e5, 2e4, 7e3)),
    "own-law-front": (HyperbolicSnow.reference(), None, 3000.0, (4e5, 1e5, 5e4)),
}
SLIPS = (0.2, -0.2)


@pytest.mark.parametrize(
    "case",
    [
        pytest.param(
            c, marks=pytest.mark.slow if c in ("own-law-front", "bekker-wong-reece-rear") else ()
        )
        for c in CASES
    ],
)
def test_equilibrium_matches_scipy_reference_and_the_stiff_limit_is_the_rim(case):
    """Entry angle and forces of both modes within 1e-7 of quad + brentq (measured: at
    most 4.6e-13), the motion resistance with the flexing resistance f_h p_f b l of the
    reference's flat, l = 2 delta sqrt((D - delta) / (delta + 1e-9 D)) (the chord, made
    linear below 1e-9 D), p_f its pressure (the law at its sinkage).  A last row, p_i = 1e12 Pa,
    is `RigidWheel`: within 1e-9 on the same quadrature rule (measured at most 1.5e-13),
    within the rules' documented 1e-7 where the rim takes Wong snow's closed-form rule
    (measured 4.7e-12)."""
    terrain, wr, load, inflations = CASES[case]
    distribution = None if wr is None else sj.WongReece(*wr)
    p = np.append(inflations, 1e12)[:, None]
    slip = np.asarray(SLIPS)[None, :]
    tire = _tire(p, flexing=FLEXING)
    st = sj.solve_wheel(tire, sj.ContactModel(terrain, distribution), load, slip)
    assert np.all(np.asarray(st.status) == sj.Status.CONVERGED)
    deflection = np.asarray(tire.deflection(st.entry_angle, terrain))
    assert deflection[:-1].min() < 1e-6 and deflection.max() > 0.01  # both modes covered
    law = _reference_law(terrain)
    depth = float(terrain.depth)
    theta_max = math.acos(1 - 2 * depth / D) * (1 - 1e-9) if 2 * depth < D else None
    for a, inflation in enumerate(inflations):
        for k, i in enumerate(SLIPS):
            fm, fr = (0.0, 0.0) if wr is None else (wr[0] + wr[1] * i, wr[2])
            theta0, (w, r, t, m) = ref.solve(
                load, i, D, B, law, *_strength(terrain), inflation + CARCASS, 30.0, fm, fr,
                theta_max,
            )  # fmt: skip
            z_f, delta, _, _ = ref.flat(theta0, D, B, law, inflation + CARCASS, 30.0)
            chord = 2 * delta * math.sqrt((D - delta) / (delta + 1e-9 * D))
            flexing = FLEXING * law(z_f, B) * B * chord
            np.testing.assert_allclose(st.entry_angle[a, k], theta0, rtol=1e-7)
            np.testing.assert_allclose(st.motion_resistance[a, k], r + flexing, rtol=1e-7)
            np.testing.assert_allclose(st.thrust[a, k], t, rtol=1e-7)
            np.testing.assert_allclose(st.drawbar_pull[a, k], t - r - flexing, atol=1e-7 * r)
            np.testing.assert_allclose(st.torque[a, k], m, rtol=1e-7)
            np.testing.assert_allclose(st.sinkage[a, k], z_f, rtol=1e-7)
    rigid = sj.solve_wheel(sj.RigidWheel(D, B), sj.ContactModel(terrain, distribution), load, slip)
    closed_form = isinstance(terrain, sj.WongSnow) and wr is None
    for field in ("entry_angle", "sinkage", "motion_resistance", "thrust", "torque"):
        np.testing.assert_allclose(
            getattr(st, field)[-1], getattr(rigid, field)[0], rtol=1e-7 if closed_form else 1e-9
        )


def test_flat_carries_the_tire_pressure_and_the_sinkage_stops_growing():
    """Elastic mode (Bekker 1969; Wong, Theory of Ground Vehicles 2.5): the flat carries
    p_i + p_c, so its sinkage is the terrain's sinkage at that pressure whatever the load,
    and the stress on it is that pressure."""
    tire = _tire(1.5e4)
    loads = np.array([1350.0, 1500.0])
    st = sj.solve_wheel(tire, SOIL, loads, 0.2)
    assert np.all(np.asarray(st.status) == sj.Status.CONVERGED)
    capacity = 1.5e4 + CARCASS
    z_books = (capacity / (float(SOIL.k_c) / B + float(SOIL.k_phi))) ** (1 / float(SOIL.n))
    # This deep in the elastic mode the smooth switch leaves the flat within 6e-4 of the
    # books' pressure (measured 5.9e-4 and 2e-6), the sinkage within 6e-4 / n.
    sigma = np.asarray(sj.normal_stress(0.0, st.entry_angle, tire, SOIL))
    np.testing.assert_allclose(sigma, tire.flat_pressure(st.entry_angle, SOIL), rtol=1e-12)
    np.testing.assert_allclose(sigma, capacity, rtol=6e-4)
    np.testing.assert_allclose(st.sinkage, z_books, rtol=6e-4 / float(SOIL.n))
    # ... while the undeflected circle, and the deflection, grow with the load.
    assert np.all(np.diff(np.asarray(tire.deflection(st.entry_angle, SOIL))) > 0.01)


@pytest.mark.slow  # two compiles of the slip-angle solve (make test-slow)
def test_infinitely_stiff_tire_under_a_slip_angle_is_the_rigid_wheel():
    """With a slip angle (the combined shear law, lateral force and aligning torque) p_i =
    1e12 Pa reproduces `RigidWheel` to 1e-9."""
    slip = np.array([0.3, 0.05, -0.2])
    rigid = sj.solve_wheel(sj.RigidWheel(D, B), SOIL, 1000.0, slip, slip_angle=0.1)
    stiff = sj.solve_wheel(_tire(1e12), SOIL, 1000.0, slip, slip_angle=0.1)
    assert np.all(np.asarray(rigid.status) == sj.Status.CONVERGED)
    np.testing.assert_array_equal(stiff.status, rigid.status)
    for field in ("sinkage", "motion_resistance", "thrust", "torque", "lateral_force",
                  "aligning_torque"):  # fmt: skip
        np.testing.assert_allclose(getattr(stiff, field), getattr(rigid, field), rtol=1e-9)


def _outputs(x, terrain, slip=0.2):
    """(sinkage, R, drawbar pull, torque) of x = (p_i, p_c, load, snow parameter, tan phi)."""
    inflation, carcass, load, parameter, tan_phi = x
    tire = _tire(inflation, carcass, flexing=FLEXING)
    if isinstance(terrain, sj.WongSnow):
        terrain = eqx.tree_at(lambda s: (s.p_w, s.tan_phi), terrain, (parameter, tan_phi))
    else:
        terrain = eqx.tree_at(lambda s: (s.k_phi, s.tan_phi), terrain, (parameter, tan_phi))
    st = sj.solve_wheel(tire, terrain, load, slip)
    return jnp.stack([st.sinkage, st.motion_resistance, st.drawbar_pull, st.torque])


@pytest.mark.slow  # gradients on both sides of the switch (make test-slow)
def test_gradients_match_central_differences_across_the_mode_boundary():
    """d(sinkage, R, DP, M) / d(p_i, p_c, load, p_w or k_phi, tan phi) by the implicit
    function theorem (R and DP with the flexing resistance, whose sqrt(delta) must stay
    differentiable as delta -> 0), against central differences (step 1e-5 relative), from the rigid
    mode (delta ~ 1e-8 m) through the switch to the elastic mode, compared as
    elasticities (x / y) dy/dx (measured: the largest difference 2.3e-6, explained at the
    tolerance below, the others a tenth of the tolerance; the elastic mode's
    motion resistance hardly changes with the entry angle, and the quadrature resolves
    that small derivative to 4e-4 of itself).  Bekker soil at 1.5 kN: the books' boundary lies
    at p_i = 18.6 kPa, the smooth switch spans about 18-22 kPa; 15 kPa is deep in the
    elastic mode (delta 5 cm)."""
    terrain, load, inflations = SOIL, 1500.0, (5e4, 2.5e4, 2.1e4, 1.5e4)
    parameter = float(terrain.p_w) if isinstance(terrain, sj.WongSnow) else float(terrain.k_phi)
    jac = jax.jit(jax.jacfwd(lambda x: _outputs(x, terrain)))
    value = jax.jit(lambda x: _outputs(x, terrain))
    for inflation in inflations:
        x = np.array([inflation, CARCASS, load, parameter, float(terrain.tan_phi)])
        exact = np.asarray(jac(jnp.asarray(x)))
        central = np.empty_like(exact)
        for k in range(x.size):
            step = np.zeros_like(x)
            step[k] = 1e-5 * x[k]
            central[:, k] = (np.asarray(value(x + step)) - np.asarray(value(x - step))) / (
                2 * step[k]
            )
        y = np.asarray(value(x))[:, None]
        # atol: at p_i = 50 kPa (delta 5e-14 m) the flexing resistance is 2.5e-7 N with
        # elasticity -27 (about -m); a 1e-5 step moves delta by 1e-17 m, below what s - z_f
        # resolves, so the central difference reads 0 where the exact elasticity of the
        # drawbar pull (-2.9 N) is -2.3e-6.  At 25 kPa (delta 4e-6 m) both agree to 1e-7.
        np.testing.assert_allclose(exact * x / y, central * x / y, rtol=1e-5, atol=4e-6)


def _slope_jump(sharpness, spacing):
    """Largest change of d(sinkage)/d(p_i) between 32 neighbouring p_i `spacing` apart
    across the mode boundary (Bekker soil, 1500 N: the books' boundary at p_i = 18.6 kPa,
    where the rigid rim's lowest-point pressure is p_i + p_c; the smooth switch spans
    about 18-22 kPa)."""
    grid = 1.95e4 + spacing * (jnp.arange(32.0) - 15.5)
    slope = jax.vmap(
        jax.grad(lambda p: sj.solve_wheel(_tire(p, sharpness=sharpness), SOIL, 1500.0, 0.2).sinkage)
    )(grid)
    return float(jnp.max(jnp.abs(jnp.diff(slope)))), float(jnp.max(jnp.abs(slope)))


@pytest.mark.slow  # a fine scan of the switch (make test-slow)
def test_switch_is_continuous_in_value_and_slope():
    """C1 across the mode boundary: the slope's largest jump between neighbours shrinks
    with the spacing (like the spacing, for a continuous slope).  The books' hard switch
    (approached with sharpness 1e4) fails the same test: its slope jumps."""
    coarse, scale = _slope_jump(30.0, 400.0)
    fine, _ = _slope_jump(30.0, 100.0)
    assert fine < 0.5 * coarse  # measured: 0.25
    assert coarse < 0.2 * scale
    hard_coarse, _ = _slope_jump(1e4, 400.0)
    hard_fine, _ = _slope_jump(1e4, 100.0)
    assert hard_fine > 0.5 * hard_coarse


def test_float32_has_no_nan_in_either_mode():
    tire = jax.tree.map(lambda x: jnp.asarray(x, jnp.float32), _tire(jnp.array([3e5, 1e5, 6e4])))
    snow = jax.tree.map(lambda x: jnp.asarray(x, jnp.float32), SNOW)
    st = sj.solve_wheel(tire, snow, jnp.float32(4000.0), jnp.array([[0.2], [-0.2]], jnp.float32))
    for field in ("sinkage", "motion_resistance", "drawbar_pull", "torque"):
        assert np.all(np.isfinite(np.asarray(getattr(st, field)))), field
    assert np.all(np.asarray(st.status) == sj.Status.CONVERGED)


_solve_on_snow = jax.jit(lambda tire: sj.solve_wheel(tire, SNOW, 4000.0, 0.2))


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"inflation_pressure": 0.0}, "tire.inflation_pressure must be finite and > 0 Pa"),
        ({"inflation_pressure": math.nan}, "tire.inflation_pressure must be finite"),
        ({"carcass_pressure": -1.0}, "tire.carcass_pressure must be finite and >= 0 Pa"),
        ({"section_height": 0.4}, "tire.section_height / diameter must be finite and < 0.5"),
        ({"sharpness": 0.0}, "tire.sharpness must be finite and > 0"),
        (
            {"hard_surface_resistance": -0.01},
            "tire.hard_surface_resistance must be finite and >= 0",
        ),
    ],
)
def test_bad_tire_inputs_are_named_eagerly_and_invalid_under_jit(kwargs, message):
    fields = dict(
        diameter=D, width=B, section_height=H, inflation_pressure=1e5, carcass_pressure=CARCASS
    )
    bad = sj.DeflectingTire(**(fields | kwargs))
    with pytest.raises(ValueError, match=message.replace("(", r"\(").replace(")", r"\)")):
        sj.solve_wheel(bad, SNOW, 4000.0, 0.2)
    batch = jax.tree.map(lambda good, worse: jnp.stack([good, worse]), _tire(1e5), bad)
    st = _solve_on_snow(batch)
    assert list(np.asarray(st.status)) == [sj.Status.CONVERGED, sj.Status.INVALID_INPUT]
    assert np.isnan(float(st.sinkage[1]))


def test_the_simplified_shear_law_is_refused():
    with pytest.raises(ValueError, match="derived for a rigid rim"):
        sj.solve_wheel(_tire(1e5), sj.ContactModel(SNOW, shear="simplified"), 4000.0, 0.2)


def test_wheel_forces_of_a_simulation_step_are_the_tires_equilibrium():
    """`wheel_forces` (the step of both simulations and of `snowjax.mjx`) takes the tyre:
    at a forward speed well above the regularisation band its forces are the tyre's
    equilibrium at the step's slip, its flexing resistance included."""
    tire = _tire(6e4, flexing=FLEXING)
    speed, wheel_speed = 2.0, 2.0 / (0.8 * D / 2)  # slip 0.2
    f = sj.wheel_forces(speed, wheel_speed, 4000.0, tire, SNOW)
    st = sj.solve_wheel(tire, SNOW, 4000.0, f.slip)
    assert int(f.status) == sj.Status.CONVERGED
    np.testing.assert_allclose(f.slip, 0.2, rtol=1e-12)
    np.testing.assert_allclose(f.sinkage, st.sinkage, rtol=1e-12)
    np.testing.assert_allclose(f.longitudinal_force, st.drawbar_pull, rtol=1e-9)
    np.testing.assert_allclose(f.resisting_torque, st.torque, rtol=1e-9)
    assert float(tire.deflection(st.entry_angle, SNOW)) > 0.01  # the elastic mode
    stiff = eqx.tree_at(lambda t: t.hard_surface_resistance, tire, jnp.asarray(0.0))
    without = sj.solve_wheel(stiff, SNOW, 4000.0, f.slip)
    # In the elastic mode the flat's pressure is p_i + p_c within 1.4e-6.
    flexing = FLEXING * (6e4 + CARCASS) * B * tire.flat_length(st.entry_angle, SNOW)
    np.testing.assert_allclose(without.drawbar_pull - st.drawbar_pull, flexing, rtol=2e-6)
    assert float(flexing) > 50.0


@pytest.mark.slow  # a fit through the tyre's solve (make test-slow)
def test_fit_wheel_recovers_the_carcass_pressure():
    """Synthetic sinkage and drawbar pull of a tyre with p_c = 8 kPa on Bekker soil;
    `fit_wheel` from p_c = 3 kPa recovers it with tan phi (names `wheel.<field>`)."""
    true = _tire(1.5e4, carcass=8e3)
    loads = np.repeat([1000.0, 1300.0, 1500.0], 3)
    slips = np.tile([0.05, 0.2, 0.4], 3)
    st = sj.solve_wheel(true, SOIL, loads, slips)
    assert np.all(np.asarray(st.status) == sj.Status.CONVERGED)
    start = eqx.tree_at(lambda t: t.carcass_pressure, true, jnp.asarray(3e3))
    soil = eqx.tree_at(lambda s: s.tan_phi, SOIL, 0.25)
    result = sj.fit_wheel(
        start,
        soil,
        loads,
        slips,
        {"sinkage": st.sinkage, "drawbar_pull": st.drawbar_pull},
        fit=("wheel.carcass_pressure", "tan_phi"),
    )
    np.testing.assert_allclose(result.params["wheel.carcass_pressure"], 8e3, rtol=1e-6)
    np.testing.assert_allclose(result.params["tan_phi"], float(SOIL.tan_phi), rtol=1e-6)
    np.testing.assert_allclose(result.info["wheel"].carcass_pressure, 8e3, rtol=1e-6)
    with pytest.raises(ValueError, match="wheel.carcass_pressure"):
        sj.fit_wheel(start, soil, loads, slips, {"sinkage": st.sinkage}, fit=("wheel.nonsense",))


@pytest.mark.slow
def test_both_simulations_and_mjx_take_the_tire():
    """A short run of `simulate_longitudinal`, `simulate_planar` and `snowjax.mjx.rollout`
    on the tyre (their compiles take most of a minute: `make test-slow`); each ends
    without NaN, converged, with the tyre's sinkage (below the rigid rim's)."""
    from mujoco import mjx

    from snowjax import mjx as smjx

    tire = _tire(6e4)
    torque = sj.TorqueProfile(jnp.linspace(0.0, 1.0, 5), jnp.full(5, 300.0))
    vehicle = sj.Vehicle(mass=1600.0, wheel_inertia=1.5, wheel=tire, num_wheels=4)
    traj = sj.simulate_longitudinal(vehicle, SNOW, torque, 1.0, 0.01)
    assert np.all(np.isfinite(np.asarray(traj.speed)))
    assert np.all(np.asarray(traj.status) == sj.Status.CONVERGED)
    rigid = sj.solve_wheel(sj.RigidWheel(D, B), SNOW, 1600.0 * 9.80665 / 4, 0.0)
    assert float(traj.sinkage[-1, 0]) < float(rigid.sinkage)
    planar = sj.PlanarVehicle(
        mass=1600.0, yaw_inertia=2500.0, wheel_inertia=1.5, wheel=tire,
        wheelbase=2.6, track_width=1.6,
    )  # fmt: skip
    knots = jnp.linspace(0.0, 1.0, 5)
    traj_p = sj.simulate_planar(
        planar, SNOW, sj.SteeringProfile(knots, jnp.full(5, 0.1)),
        sj.TorqueProfile(knots, jnp.full(5, 300.0)), 1.0, 0.01,
    )  # fmt: skip
    assert np.all(np.isfinite(np.asarray(traj_p.x)))
    model, wheels = smjx.load_rover()
    wheels = eqx.tree_at(lambda w: w.wheel, wheels, tire)
    m = mjx.put_model(model)
    ctrl = smjx.rover_controls(0.1, jnp.full(4, 540.0))
    r = jax.jit(lambda s: smjx.rollout(m, mjx.make_data(m), wheels, s, ctrl, 200))(SNOW)
    assert np.all(np.isfinite(np.asarray(r.qpos)))
    assert np.all(np.asarray(r.wheels.status) == sj.Status.CONVERGED)


def test_the_flat_is_one_panel_graded_at_its_shear_layer():
    """On the front region the flat is the contact's `smooth_span`: one panel of n nodes,
    clustered at its front end by the width of the shear's layer there (and at a braked
    wheel's split).  A long flat on a firm soil with K = 2 mm (the layer a few mm wide),
    driven and braked: W, R, T, M within 1e-9 of the load of SciPy's quad (measured
    1.8e-10 driven, 1.6e-14 braked; 1.4e-8 driven without the clustering)."""
    soil = sj.BekkerSoil(
        SOIL.n, SOIL.k_c, 50 * SOIL.k_phi, SOIL.cohesion, SOIL.tan_phi, shear_modulus=0.002
    )
    law = ref_terrain.bekker(float(soil.n), float(soil.k_c), float(soil.k_phi))
    tire = _tire(3e3, carcass=2e3)
    theta0 = np.array([0.4, 0.6])
    flat = np.asarray(tire.flat_length(theta0, soil))
    assert np.all(flat > 0.2), flat  # flats of 24 and 39 cm
    for slips in (np.array([0.9, 0.3, 0.03]), np.array([0.9, -0.3, -0.05])):
        th, sl = np.meshgrid(theta0, slips)
        forces = sj.contact_forces(tire, soil, th, sl)
        got = [np.asarray(getattr(forces, f)) for f in ("vertical_load", "motion_resistance")]
        got += [np.asarray(forces.thrust), np.asarray(forces.torque) / (D / 2)]
        for k in np.ndindex(th.shape):
            w, r, t, m = ref.contact(th[k], sl[k], D, B, law, *_strength(soil), 5e3, 30.0)
            expected = (w, r, t, m / (D / 2))
            for value, reference in zip(got, expected):
                assert abs(value[k] - reference) <= 1e-9 * w, (th[k], sl[k], value[k], reference)


def test_the_tyres_start_models_its_flat():
    """The any-terrain cold start of a tyre whose tread flattens takes one Newton step on
    a power-law model of its own contact (the flat at p_f and the curved part beyond it,
    `start._power_law_root`): the 100 kPa tyre on Reece's sand, 1-9 kN / 4, slips 0-0.9,
    starts within 5 % of the root (measured 2.8 % on these 64 cases, 2.9 % on 2,000;
    the rim's model alone: 27 % on either)."""
    from snowjax._wheel.equilibrium import _entry_angle_cap
    from snowjax._wheel.start import _power_law_root

    reece = sj.ReeceSoil(0.8, 10.0, 800.0, 15e3, 1e3, 0.6, shear_modulus=0.02)
    tire = sj.DeflectingTire(D, B, H, 100e3)
    rng = np.random.default_rng(8)
    load, slip = rng.uniform(1e3, 9e3, 64) / 4, rng.uniform(0.0, 0.9, 64)
    root = sj.solve_wheel(tire, reece, load, slip)
    assert np.all(np.asarray(root.status) == sj.Status.CONVERGED)
    cap = _entry_angle_cap(tire.deepest_reach(reece), tire.diameter)[0]
    front = sj.FrontRegion()
    start = jax.vmap(lambda w, i: _power_law_root(tire, reece, w, cap, front, i)[0])
    error = np.asarray(start(jnp.asarray(load), jnp.asarray(slip))) / root.entry_angle - 1
    assert np.max(np.abs(error)) < 0.05, np.max(np.abs(error))


ROUND_FIELDS = ("entry_angle", "sinkage", "motion_resistance", "thrust", "torque")


def _round_cases(n=24, seed=3):
    rng = np.random.default_rng(seed)
    return rng.uniform(1e3, 9e3, n) / 9, rng.uniform(-0.3, 0.9, n)


def test_a_batch_of_round_treads_is_solved_as_its_rim():
    """Where every tread of a batch stays round at its root (`stays_round`: deflection
    <= 1e-12 of the sinkage), `solve_wheel` solves the batch with the tyre's rim
    (`equilibrium._round_first`): the 100 kPa tyre on Bekker's snow (with a flexing
    resistance, f_h 0.03), driven and braked, gives the rim's outputs and, in a batch
    whose first tyre (2 kPa) flattens, so that the batch takes the tyre's own contact,
    the same outputs within 1e-12 of the load (measured 6e-16) and the same gradients
    w.r.t. the load and k_phi within 1e-9."""
    from snowjax._wheel.contact import _STRAIGHT as straight
    from snowjax._wheel.equilibrium import _solves_as_rim
    from snowjax._wheel.front_rim import _contact_rule

    bekker, wong = sj.BekkerSoil.snow_us(), sj.WongSnow.thesis_fresh_snow()
    load, slip = _round_cases()
    pressure = np.full(load.shape, 100e3)
    tyre = sj.DeflectingTire(D, B, H, pressure, hard_surface_resistance=0.03)
    rule = type(_contact_rule(bekker, sj.FrontRegion(), tyre, straight))
    assert _solves_as_rim(tyre, tyre.round_rim(), bekker, sj.FrontRegion(), straight, rule)
    rule = type(_contact_rule(wong, sj.FrontRegion(), tyre, straight))
    assert not _solves_as_rim(tyre, tyre.round_rim(), wong, sj.FrontRegion(), straight, rule)

    round_ = sj.solve_wheel(tyre, bekker, load, slip)
    assert np.all(np.asarray(tyre.stays_round(round_.entry_angle, bekker)))
    rim = sj.solve_wheel(sj.RigidWheel(D, B), bekker, load, slip)
    soft = pressure.copy()
    soft[0] = 2e3
    mixed_tyre = sj.DeflectingTire(D, B, H, soft, hard_surface_resistance=0.03)
    mixed = sj.solve_wheel(mixed_tyre, bekker, load, slip)
    assert not bool(mixed_tyre.stays_round(mixed.entry_angle, bekker)[0])
    for name in ROUND_FIELDS:
        got = np.asarray(getattr(round_, name))
        np.testing.assert_allclose(got, np.asarray(getattr(rim, name)), rtol=1e-12, atol=0)
        error = np.abs(got - np.asarray(getattr(mixed, name)))[1:] / load[1:]
        assert np.max(error) <= 1e-12, (name, np.max(error))
    np.testing.assert_array_equal(round_.status[1:], mixed.status[1:])

    def total(load, k_phi, wheel):
        soil = eqx.tree_at(lambda s: s.k_phi, bekker, k_phi)
        state = sj.solve_wheel(wheel, soil, load, slip)
        return jnp.sum(state.motion_resistance[1:] + state.entry_angle[1:])

    grad = jax.grad(total, argnums=(0, 1))
    g_round = grad(jnp.asarray(load), bekker.k_phi, tyre)
    g_mixed = grad(jnp.asarray(load), bekker.k_phi, mixed_tyre)
    np.testing.assert_allclose(g_round[0][1:], g_mixed[0][1:], rtol=1e-9, atol=0)
    np.testing.assert_allclose(g_round[1], g_mixed[1], rtol=1e-9, atol=0)
    assert np.all(np.asarray(g_round[0][1:]) != 0)


def test_a_tread_that_flattens_after_the_start_falls_back_to_the_tyre(monkeypatch):
    """`_round_first` tries the rim where the start says every tread stays round, and
    keeps its roots only where they do: with the start's margin shrunk to 1 % of the
    sinkage, soft tyres (2 kPa on Bekker's snow; most treads flatten at their roots)
    are tried as the rim and still solved as tyres (their outputs those at the default
    margin; a rim's motion resistance differs by more than 10 %, and without the check
    of the roots this test failed by 50 %)."""
    import snowjax._wheel.equilibrium as equilibrium

    bekker = sj.BekkerSoil.snow_us()
    load, slip = _round_cases(n=20, seed=4)
    tyre = sj.DeflectingTire(D, B, H, 2e3)
    expected = sj.solve_wheel(tyre, bekker, load, slip)
    flat = ~np.asarray(tyre.stays_round(expected.entry_angle, bekker))
    assert np.sum(flat[:-1]) >= 10, flat
    rim = sj.solve_wheel(sj.RigidWheel(D, B), bekker, load, slip)
    assert np.max(np.abs(rim.motion_resistance / expected.motion_resistance - 1)) > 0.1
    monkeypatch.setattr(equilibrium, "ROUND_MARGIN", 0.01)
    # (a new shape: the solve is traced again with the margin)
    got = sj.solve_wheel(tyre, bekker, load[:-1], slip[:-1])
    for name in ROUND_FIELDS:
        np.testing.assert_allclose(
            np.asarray(getattr(got, name)), np.asarray(getattr(expected, name))[:-1], rtol=1e-12
        )


def test_round_treads_never_evaluate_the_tyres_contact(monkeypatch):
    """The batch of round treads (`test_a_batch_of_round_treads_is_solved_as_its_rim`)
    runs the rim's contact only: a callback in `DeflectingTire.contact` fires in none of
    its evaluations (the `lax.cond`s trace both branches and run one), and does fire
    once a flattening tyre joins the batch."""
    calls = []
    contact = sj.DeflectingTire.contact

    def counted(self, entry_angle, terrain):
        jax.debug.callback(lambda: calls.append(1))
        return contact(self, entry_angle, terrain)

    monkeypatch.setattr(sj.DeflectingTire, "contact", counted)
    bekker = sj.BekkerSoil.snow_us()
    load, slip = _round_cases(n=22, seed=5)  # (a shape of its own: traced with the callback)
    pressure = np.full(load.shape, 100e3)
    sj.solve_wheel(
        sj.DeflectingTire(D, B, H, pressure), bekker, load, slip
    ).status.block_until_ready()
    jax.effects_barrier()
    assert not calls
    pressure[0] = 2e3
    sj.solve_wheel(
        sj.DeflectingTire(D, B, H, pressure), bekker, load, slip
    ).status.block_until_ready()
    jax.effects_barrier()
    assert calls


def test_beyond_a_flat_far_from_the_base_the_contact_is_one_panel():
    """On a law with a base the front region's contact beyond its lowest point (the
    flat's front end, the axle on a round tread) is one panel graded towards theta0
    where the base's log singularity lies at least half that panel away from it
    (`general._far_front_base`), else it starts with a short panel of its own.  Driven
    tyres on Wong snow, soft (far: one panel) and stiff next to the base (not far),
    each alone and the three in one batch (not far: the short panel for all): W, R, T
    and M / r within 1e-7 of the load of SciPy's quad on the tyre's equations (measured:
    the one panel within 1.2e-10 alone, the batch's short panel 7.7e-10 on the soft ones
    and 7.1e-8 of W on the stiff one, next to the base).  The soft tyres' W alone and in
    the batch differ (the two layouts: 2.2e-10 of the load and more), so a wiring that
    never took the one panel fails here.  With every contact one panel (the share 0) the
    stiff tyre's W is off by 2.3e-3."""
    from snowjax._wheel.general import _far_front_base
    from snowjax._wheel.shear_law import _shear_law

    cap = 2 * math.asin(math.sqrt(float(SNOW.z_w) / D))
    rows = np.array([(6e4, 0.6, 0.3), (1e5, 0.9, 0.8), (1e9, 0.9995, 0.2)])
    tires = _tire(rows[:, 0])
    theta0, slip = jnp.asarray(rows[:, 1] * cap), jnp.asarray(rows[:, 2])
    far = _far_front_base(
        tires.contact(theta0, SNOW), slip, SNOW, sj.FrontRegion(), _shear_law("classic"), False
    )
    np.testing.assert_array_equal(far, [True, True, False])
    law = _reference_law(SNOW)
    batch = sj.contact_forces(tires, SNOW, theta0, slip)
    for k, (p_i, _, s) in enumerate(rows):
        alone = sj.contact_forces(_tire(p_i), SNOW, theta0[k], s)
        w, r, t, m = ref.contact(
            float(theta0[k]), s, D, B, law, *_strength(SNOW), p_i + CARCASS, 30.0
        )
        for forces in (alone, jax.tree.map(lambda x, k=k: x[k], batch)):
            got = (
                forces.vertical_load,
                forces.motion_resistance,
                forces.thrust,
                forces.torque / (D / 2),
            )
            for value, expected in zip(got, (w, r, t, m / (D / 2))):
                assert abs(float(value) - expected) <= 1e-7 * w, (k, float(value), expected)
        if far[k]:  # one panel alone, the short panel's layout in the mixed batch
            gap = abs(float(alone.vertical_load) - float(batch.vertical_load[k]))
            assert gap > 1e-12 * w, (k, gap)


def test_driven_tyres_with_wong_reece_take_a_panel_per_piece(monkeypatch):
    """Under Wong-Reece a driven tyre's contact is cut in the stress angle at its flat's
    ends, and each piece is one panel clustered at both its ends (`general._cut_panels`;
    the SciPy test above brakes, so its batches keep the half-panels).  Eight random
    driven tyres on Wong snow (p_i 20 kPa-1 MPa, K 2-30 mm, c3 0 or down to -0.1, entry
    angles to 0.995 of the cap; one batch, rigid and elastic modes): W, R, T and M / r
    within 2e-7 of the load of SciPy's quad on the tyre's equations (measured over 80
    such tyres: 1.4e-7, on rigid-mode tyres, whose error lies in the piece at the entry
    with the half-panels too).  The clustering at the cuts is guarded on layered snow
    (`test_terrains.py`), where a panel without it errs by 3e-4."""
    from snowjax._wheel import general

    taken = []
    cut_panels = general._cut_panels
    monkeypatch.setattr(general, "_cut_panels", lambda *a: taken.append(True) or cut_panels(*a))
    jax.clear_caches()  # traced afresh, whatever compiled these shapes before
    rng = np.random.default_rng(31)
    m = 8
    cap = 2 * math.asin(math.sqrt(float(SNOW.z_w) / D))
    p_i = np.exp(rng.uniform(math.log(2e4), math.log(1e6), m))
    modulus = rng.uniform(0.002, 0.03, m)
    slip = rng.uniform(0.0, 0.9, m)
    c1, c2 = rng.uniform(0.3, 0.45, m), rng.uniform(0.2, 0.4, m)
    c3 = np.where(rng.uniform(size=m) < 0.5, 0.0, -rng.uniform(0.001, 0.1, m))
    theta0 = rng.uniform(0.1, 0.995, m) * cap
    snow = sj.WongSnow(SNOW.p_w, SNOW.z_w, SNOW.cohesion, SNOW.tan_phi, modulus)
    model = sj.ContactModel(snow, sj.WongReece(c1, c2, c3))
    forces = sj.contact_forces(_tire(p_i), model, theta0, slip)
    assert taken
    deflection = np.asarray(_tire(p_i).deflection(theta0, snow))
    assert deflection.min() < 1e-6 and deflection.max() > 0.01  # both modes
    law = _reference_law(SNOW)
    c, tan_phi = float(SNOW.cohesion), float(SNOW.tan_phi)
    for k in range(m):
        w, r, t, moment = ref.contact(
            theta0[k], slip[k], D, B, law, c, tan_phi, modulus[k], p_i[k] + CARCASS, 30.0,
            c1[k] + c2[k] * slip[k], c3[k],
        )  # fmt: skip
        got = (
            forces.vertical_load[k],
            forces.motion_resistance[k],
            forces.thrust[k],
            forces.torque[k] / (D / 2),
        )
        for value, expected in zip(got, (w, r, t, moment / (D / 2))):
            assert abs(float(value) - expected) <= 2e-7 * w, (k, float(value), expected)
