"""A wheel on a rut (`snowjax.Rut`): against the SciPy reference of the rigid wheel
(`tests/reference_terrain.py`) on the rut's law written here from its equations; a rut of
zero depth is the virgin terrain; a second wheel at the same load and a heavier one;
gradients through the first wheel's sinkage into the second wheel's forces."""

from __future__ import annotations

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import snowjax as sj

from . import reference_terrain as ref

pytestmark = pytest.mark.filterwarnings("ignore::scipy.integrate.IntegrationWarning")

WHEEL = sj.RigidWheel(0.736, 0.235)
K_0, A_U = 1e6, 5e6  # unloading modulus k_u = k_0 + A_u z_u [Pa/m, Pa/m^2] (illustrative)
SLIP = 0.2
# (virgin terrain, distribution (c1, c2) or None, load [N])
CASES = {
    "wong-wong-reece": (sj.WongSnow.thesis_fresh_snow(), (0.43, 0.32), 4000.0),
    "bekker-front": (sj.BekkerSoil.snow_us(), None, 1000.0),
}


def _law(terrain):
    """(law(z, b) [Pa], its slope dsigma/dz(z, b) [Pa/m]), written from the equations."""
    if isinstance(terrain, sj.WongSnow):
        p_w, z_w = float(terrain.p_w), float(terrain.z_w)
        return ref.wong(p_w, z_w), lambda z, b: p_w / (z_w - z)
    n, k_c, k_phi = float(terrain.n), float(terrain.k_c), float(terrain.k_phi)
    return ref.bekker(n, k_c, k_phi), lambda z, b: n * (k_c / b + k_phi) * z ** (n - 1)


def _rut_law(virgin, z_u, b_1):
    """Thesis eq. 2.21 below z_u, the virgin law beyond, in the sinkage below the floor;
    the unloading modulus k_u = max(k_0 + A_u z_u, the virgin law's slope at z_u)."""
    virgin, slope = virgin
    p_u = virgin(z_u, b_1)
    d = min(p_u / max(K_0 + A_U * z_u, slope(z_u, b_1)), z_u)
    floor = z_u - d

    def law(z, b):
        return virgin(z_u, b) * z / d if z < d else virgin(z + floor, b)

    return law, d, floor


@pytest.mark.parametrize("case", list(CASES))
def test_second_wheel_matches_scipy_and_a_rut_of_zero_depth_is_the_virgin_terrain(case):
    """Rows: the same load on the rut, 1.5 times the load on it, the same load on a rut
    of zero depth.  Entry angle, motion resistance, drawbar pull and torque within 1e-7 of
    quad + brentq on the rut's law; the zero-depth rut equals the virgin terrain within
    the quadrature's 1e-7: the driven virgin rim is one panel graded towards its entry
    (Bekker's front region; Wong snow's Wong–Reece panel, `general._mirrored_smooth_start`)
    and the rut's is cut at its kink (measured on Bekker's 6.1e-9 of theta0, 2.6e-8 of
    the load; on Wong snow 2.7e-11 of theta0; 1e-15 before Wong–Reece's one panel, when
    both took the same quadrature)."""
    virgin, wr, load = CASES[case]
    dist = None if wr is None else sj.WongReece(*wr)
    first = sj.solve_wheel(WHEEL, sj.ContactModel(virgin, dist), load, SLIP)
    z_u = float(first.sinkage)
    depths = jnp.array([z_u, z_u, 0.0])
    loads = jnp.array([load, 1.5 * load, load])
    rut = sj.Rut(virgin, depths, WHEEL.width, K_0, A_U)
    st = sj.solve_wheel(WHEEL, sj.ContactModel(rut, dist), loads, SLIP)
    assert np.all(np.asarray(st.status) == sj.Status.CONVERGED)
    # The quadrature's tolerance: 1e-7 of theta0 and z0, of the load, of load x r.
    scale = dict(motion_resistance=load, drawbar_pull=load, torque=load * WHEEL.diameter / 2)
    for field in ("entry_angle", "sinkage", "motion_resistance", "drawbar_pull", "torque"):
        got, virgin_value = getattr(st, field)[2], getattr(first, field)
        tol = 1e-7 * scale.get(field, abs(float(virgin_value)))
        np.testing.assert_allclose(got, virgin_value, rtol=0, atol=tol)
    c, tan_phi, k = (float(x) for x in (virgin.cohesion, virgin.tan_phi, virgin.shear_modulus))
    law, d, floor = _rut_law(_law(virgin), z_u, float(WHEEL.width))
    np.testing.assert_allclose(rut.floor_depth[0], floor, rtol=1e-12)
    fm, fr = (0.0, 0.0) if wr is None else (wr[0] + wr[1] * SLIP, 0.0)
    depth = float(virgin.depth) - floor
    for row in (0, 1):
        theta0, (w, r, t, m) = ref.solve(
            float(loads[row]), SLIP, 0.736, 0.235, law, c, tan_phi, k, fm, fr, z_f=d, depth=depth
        )
        np.testing.assert_allclose(st.entry_angle[row], theta0, rtol=1e-7)
        np.testing.assert_allclose(st.motion_resistance[row], r, rtol=1e-7)
        np.testing.assert_allclose(st.drawbar_pull[row], t - r, rtol=1e-7, atol=1e-7 * r)
        np.testing.assert_allclose(st.torque[row], m, rtol=1e-7)
    # The same load (measured): on Wong snow the 177 mm rut rebounds 50 mm (the law's
    # tangent p_w / (z_w - z_u) = 3.7 MPa/m, stiffer than k_0 + A_u z_u = 1.9 MPa/m,
    # sets the unloading line) and the second wheel deepens it by 4 mm; on Bekker soil
    # (rebound 8 mm) it sinks 46 mm further (see docs/guide/ruts.md: a rigid wheel on a rut
    # carries its load over a shorter arc).  On both its compaction resistance drops
    # (by 41 % and 26 %).  The heavier wheel passes z_u into the virgin terrain.
    total = np.asarray(st.sinkage) + float(rut.floor_depth[0])
    if case.startswith("wong"):
        assert z_u < total[0] < z_u + 0.01
        np.testing.assert_allclose(rut.reloading_depth[0], 0.0496, rtol=1e-3)
    assert float(st.motion_resistance[0]) < 0.8 * float(first.motion_resistance)
    assert total[1] > z_u and float(st.sinkage[1]) > d


def test_a_rut_on_wong_snow_takes_the_closed_form_rule_and_matches_scipy():
    """A rigid rim on a `Rut` of Wong snow on the front region takes the closed-form rule
    (its panels cut at the reloading line's kink; braking too): driven and braked, with
    the contact inside the reloading branch and beyond its kink, entry angle, motion
    resistance, thrust and torque within 1e-7 of quad + brentq on the rut's law
    (measured: 6e-12 at most over 28 random cases).  Rows: (z_u [m], load [N], slip)."""
    from snowjax._wheel.front_rim import FrontRimRule, _contact_rule
    from snowjax._wheel.running import Straight

    snow = sj.WongSnow.thesis_fresh_snow()
    rows = np.array(
        [(0.15, 4000.0, 0.2), (0.15, 1500.0, 0.2), (0.04, 5000.0, 0.6), (0.04, 5000.0, -0.3),
         (0.12, 1500.0, -0.2), (0.19, 3000.0, 0.05)]
    )  # fmt: skip
    rut = sj.Rut(snow, rows[:, 0], WHEEL.width, K_0, A_U)
    assert isinstance(_contact_rule(rut, sj.FrontRegion(), WHEEL, Straight()), FrontRimRule)
    st = sj.solve_wheel(WHEEL, rut, rows[:, 1], rows[:, 2])
    assert np.all(np.asarray(st.status) == sj.Status.CONVERGED)
    c, tan_phi, k = (float(x) for x in (snow.cohesion, snow.tan_phi, snow.shear_modulus))
    crossed = []
    for row, (z_u, load, slip) in enumerate(rows):
        law, d, floor = _rut_law(_law(snow), z_u, float(WHEEL.width))
        depth = float(snow.depth) - floor
        theta0, (w, r, t, m) = ref.solve(
            load, slip, 0.736, 0.235, law, c, tan_phi, k, 0.0, 0.0, z_f=d, depth=depth
        )
        crossed.append(float(st.sinkage[row]) > d)
        np.testing.assert_allclose(st.entry_angle[row], theta0, rtol=1e-7)
        np.testing.assert_allclose(st.motion_resistance[row], r, rtol=1e-7)
        np.testing.assert_allclose(st.thrust[row], t, rtol=1e-7)
        np.testing.assert_allclose(st.torque[row], m, rtol=1e-7)
    assert any(crossed) and not all(crossed)  # both sides of the kink


@pytest.mark.slow  # gradients through two equilibria (make test-slow)
def test_gradients_flow_from_the_first_wheel_into_the_second():
    """d(second wheel's sinkage, R, DP) / d(p_w, k_0, load) with the rut left by the first
    wheel on the same snow (p_w moves both wheels), forward mode against central
    differences (measured: 4e-9 relative at most).  k_0 = 3 MPa/m, so that k_0 + A_u z_u
    (3.9 MPa/m) and not the law's tangent (3.7 MPa/m) sets the unloading line and k_0
    moves the second wheel."""
    snow = sj.WongSnow.thesis_fresh_snow()
    dist = sj.WongReece(0.43, 0.32)

    def second(x):
        p_w, k_0, load = x
        virgin = sj.WongSnow(p_w, snow.z_w, snow.cohesion, snow.tan_phi, snow.shear_modulus)
        z_u = sj.solve_wheel(WHEEL, sj.ContactModel(virgin, dist), load, SLIP).sinkage
        rut = sj.Rut(virgin, z_u, WHEEL.width, k_0, A_U)
        st = sj.solve_wheel(WHEEL, sj.ContactModel(rut, dist), load, SLIP)
        return jnp.stack([st.sinkage, st.motion_resistance, st.drawbar_pull])

    x = np.array([float(snow.p_w), 3e6, 4000.0])
    exact = np.asarray(jax.jit(jax.jacfwd(second))(jnp.asarray(x)))
    value = jax.jit(second)
    for k in range(x.size):
        h = 1e-5 * x[k]
        step = np.zeros_like(x)
        step[k] = h
        central = (np.asarray(value(x + step)) - np.asarray(value(x - step))) / (2 * h)
        scale = np.abs(np.asarray(value(x))) / x[k]
        assert np.all(np.abs(exact[:, k]) > 1e-3 * scale)  # every input moves every output
        np.testing.assert_allclose(exact[:, k], central, rtol=1e-5, atol=1e-9 * scale.max())


def test_bad_rut_inputs_are_named():
    snow = sj.WongSnow.thesis_fresh_snow()
    with pytest.raises(ValueError, match="rut_sinkage must be finite and <= the virgin base"):
        sj.solve_wheel(WHEEL, sj.Rut(snow, 0.3, 0.235, K_0, A_U), 4000.0, SLIP)
    with pytest.raises(ValueError, match="k_0 must be finite and > 0"):
        sj.solve_wheel(WHEEL, sj.Rut(snow, 0.1, 0.235, 0.0, A_U), 4000.0, SLIP)
    assert math.isfinite(float(sj.Rut(snow, 0.1, 0.235, K_0, A_U).floor_depth))


def test_multi_pass_is_the_chain_of_ruts_and_the_rut_deepens_to_the_base():
    """`multi_pass` on the thesis snow (Wong–Reece): equal 4 kN wheels, and 4 kN / 6 kN
    alternating (a heavier rear axle); each pass equals `solve_wheel` on the `Rut` of the
    deepest earlier pass, built here by hand (to 1e-12; the first on the virgin snow, as
    `multi_pass` solves it).  Equal wheels deepen the rut
    by less at every pass (measured: 177.1, 181.0, 183.7, 185.7 mm; R 1,768, 1,051,
    991, 945 N); the alternating ones press it to the base, where the last wheel rests
    (`BOTTOMED_OUT`, at the base's depth: measured 177.1, 198.3, 199.7, 200.0 mm)."""
    snow = sj.WongSnow.thesis_fresh_snow()
    dist = sj.WongReece(0.43, 0.32)
    loads = np.array([[4000.0] * 4, [4000.0, 6000.0, 4000.0, 6000.0]])
    res = sj.multi_pass(WHEEL, sj.ContactModel(snow, dist), loads, SLIP, K_0, A_U)
    status = np.asarray(res.status)
    assert np.all(status[0] == sj.Status.CONVERGED)
    assert np.all(status[1, :3] == sj.Status.CONVERGED)
    assert status[1, 3] == sj.Status.BOTTOMED_OUT
    for row in range(2):
        deepest = 0.0
        for k in range(4):
            rut = sj.Rut(snow, deepest, WHEEL.width, K_0, A_U)
            ground = snow if k == 0 else rut
            st = sj.solve_wheel(WHEEL, sj.ContactModel(ground, dist), loads[row, k], SLIP)
            floor = 0.0 if k == 0 else float(rut.floor_depth)
            total = min(float(st.sinkage) + floor, float(snow.z_w))
            deepest = max(deepest, total)
            np.testing.assert_allclose(res.sinkage[row, k], total, rtol=1e-12)
            np.testing.assert_allclose(res.rut_depth[row, k], deepest, rtol=1e-12)
            np.testing.assert_allclose(res.drawbar_pull[row, k], st.drawbar_pull, rtol=1e-12)
    steps = np.diff(np.asarray(res.sinkage[0]))
    assert np.all(steps > 0) and np.all(np.diff(steps) < 0)
    assert np.all(np.diff(np.asarray(res.motion_resistance[0])) < 0)
    np.testing.assert_allclose(res.sinkage[1, 3], snow.z_w, rtol=1e-12)


@pytest.mark.slow  # the tyre's and the slip angle's solves on a rut (make test-slow)
def test_a_tyre_and_a_slip_angle_on_a_rut():
    """A `DeflectingTire` on a rut: stiff (p_i = 1e12 Pa) it is the rim on the rut within
    1e-9; at 100 kPa it flattens and sinks less.  Under a slip angle on the rut: beta = 0
    is straight running (1e-7, the any-terrain quadrature against the straight one), and
    the lateral force is odd in beta and resists the side-slip."""
    snow = sj.WongSnow.thesis_fresh_snow()
    rut = sj.Rut(snow, 0.15, WHEEL.width, K_0, A_U)
    rim = sj.solve_wheel(WHEEL, rut, 4000.0, SLIP)
    tyres = sj.DeflectingTire(0.736, 0.235, 0.176, jnp.array([1e12, 100e3]))
    tyre = sj.solve_wheel(tyres, rut, 4000.0, SLIP)
    assert np.all(np.asarray(tyre.status) == sj.Status.CONVERGED)
    for field in ("sinkage", "motion_resistance", "drawbar_pull", "torque"):
        np.testing.assert_allclose(getattr(tyre, field)[0], getattr(rim, field), rtol=1e-9)
    assert float(tyre.sinkage[1]) < 0.9 * float(rim.sinkage)
    beta = jnp.deg2rad(jnp.array([0.0, 5.0, -5.0]))
    side = sj.solve_wheel(WHEEL, rut, 4000.0, SLIP, slip_angle=beta)
    assert np.all(np.asarray(side.status) == sj.Status.CONVERGED)
    for field in ("sinkage", "motion_resistance", "drawbar_pull", "torque"):
        np.testing.assert_allclose(getattr(side, field)[0], getattr(rim, field), rtol=1e-7)
    np.testing.assert_allclose(side.lateral_force[1], -side.lateral_force[2], rtol=1e-9)
    assert float(side.lateral_force[1]) > 0.02 * 4000.0


@pytest.mark.parametrize("braking", [False, True])
def test_the_solvers_tangent_on_a_rut_holds_the_kink_fixed_and_is_the_slope_of_w(braking):
    """The solver's W on a rut (`vertical_only`) holds every node fixed, the kink's too
    (`front_rim` module docstring): its tangent in theta0 is still the slope of W, whose
    layout moves with the kink at every theta0, within 1e-7 of central differences
    (h = 1e-5 rad; the kink inside the contact; the driving layout of three panels and
    the braking one of four, the panel that holds the kink cut there; measured 3e-9).
    Fixed nodes whose panel end missed the kink (by 3 %) leave the tangent 1.6e-3 off:
    its integrand then jumps inside a panel."""
    from snowjax._wheel.contact import _broadcast_leaves, _contact_batch
    from snowjax._wheel.front_rim import _contact_rule
    from snowjax._wheel.running import _STRAIGHT

    snow = sj.WongSnow.thesis_fresh_snow()
    rows = np.array([(0.15, 0.75, 0.2), (0.04, 0.4, 0.6), (0.12, 0.65, -0.2), (0.08, 0.55, 0.05)])
    rut = sj.Rut(snow, rows[:, 0], WHEEL.width, K_0, A_U)
    slip = rows[:, 2] if braking else np.abs(rows[:, 2])
    theta0, slip = jnp.asarray(rows[:, 1]), jnp.asarray(slip)
    kink = 2 * np.arcsin(np.sqrt(np.sin(rows[:, 1] / 2) ** 2 - rut.reloading_depth / 0.736))
    assert np.all((kink > 0) & (kink < rows[:, 1]))  # the kink inside every contact
    model = sj.ContactModel(rut)
    rule = _contact_rule(rut, model.distribution, WHEEL, _STRAIGHT)
    n = type(rule).nodes(rule, model.shear, None, "reference")
    trees = _broadcast_leaves(
        WHEEL, rut, model.distribution, (), jnp.full(4, 1e3), slip, None, _STRAIGHT
    )[2]
    w_b, t_b, d_b, terms, _, s_b, _, r_b = trees

    def vertical(th):
        return _contact_batch(
            th, s_b, w_b, t_b, d_b, r_b, terms, shear=model.shear, n=n[int(braking)],
            braking=braking, rule=rule, vertical_only=True,
        )  # fmt: skip

    w, tangent = jax.jvp(vertical, (theta0,), (jnp.ones_like(theta0),))
    h = 1e-5
    central = (vertical(theta0 + h) - vertical(theta0 - h)) / (2 * h)
    np.testing.assert_allclose(tangent, central, rtol=1e-7)
    assert np.all(np.asarray(w) > 0)
