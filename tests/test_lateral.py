"""The wheel under a slip angle: lateral force, aligning torque, sidewall bulldozing.

Checked against an independent SciPy reference written from the equations in
`snowjax/_wheel/lateral.py`'s docstring (the combined Janosi–Hanamoto law on the resultant
of the rim and axle shear displacements, the Wong 2008 sidewall bulldozing pressure), the
symmetries the model has (odd in beta), the straight-running results (beta = 0) and
central differences.
"""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy import integrate, optimize

import snowjax as sj
from snowjax import Lateral, Status

pytestmark = pytest.mark.filterwarnings("ignore::scipy.integrate.IntegrationWarning")

WHEEL = sj.RigidWheel(0.736, 0.235)
SHIPPED_SNOWS = {
    "fresh": sj.WongSnow.thesis_fresh_snow(),
    "plate_rule": sj.WongSnow.thesis_plate_rule_snow(),
    "snow_us": sj.BekkerSoil.snow_us(),
}


# --------------------------------------------------------------------------------------
# Independent reference (SciPy quad + brentq)
# --------------------------------------------------------------------------------------


def _reference_contact(theta0, slip, beta, D, b, law, c, tan_phi, K, K_y, fm, fr, gamma, bull):
    """(W, R, T, M, F_y, M_z) by adaptive quadrature over theta_r .. theta0."""
    r = D / 2
    tm, tr = fm * theta0, fr * theta0

    def theta_eff(th):
        if th >= tm or tm == tr:
            return th
        return theta0 - (th - tr) / (tm - tr) * (theta0 - tm)

    def sig(th):
        return law(r * (math.cos(theta_eff(th)) - math.cos(theta0)))

    def taus(th):
        jx = r * ((theta0 - th) - (1 - slip) * (math.sin(theta0) - math.sin(th)))
        jy = r * (1 - slip) * (theta0 - th) * math.tan(beta)
        a, bb = jx / K, jy / K_y
        u = math.hypot(a, bb)
        if u == 0:
            return 0.0, 0.0
        tau = (c + sig(th) * tan_phi) * -math.expm1(-u)
        return tau * a / u, tau * bb / u

    phi = math.atan(tan_phi)
    cot_x = 1 / math.tan(math.pi / 4 - phi / 2)

    def q_b(th):  # bulldozing force per unit angle, along +y
        h = max(r * (math.cos(th) - math.cos(theta0)), 0.0)
        q = 0.5 * gamma * h**2 * cot_x**2 * (1 + cot_x * tan_phi / 2) + 2 * c * h * cot_x
        return q * r * math.cos(th) * math.sin(beta)

    pts = {tr, tm, theta0}
    for m in (1, 4, 16, 64, 256):
        for p in (theta0 - m * min(K, K_y) / r, tr + (theta0 - tr) / 4**m):
            if tr < p < theta0:
                pts.add(p)
    pts = sorted(p for p in pts if tr <= p <= theta0)
    fns = [
        lambda t: sig(t) * math.cos(t) + taus(t)[0] * math.sin(t),
        lambda t: sig(t) * math.sin(t),
        lambda t: taus(t)[0] * math.cos(t),
        lambda t: taus(t)[0] * r,
        lambda t: taus(t)[1],
        lambda t: taus(t)[1] * r * math.sin(t),
    ]
    out = []
    for fn in fns:
        total = 0.0
        for lo, hi in zip(pts[:-1], pts[1:]):
            total += integrate.quad(fn, lo, hi, epsabs=0.0, epsrel=1e-12, limit=400)[0]
        out.append(total * r * b)
    if bull:
        out[4] += integrate.quad(q_b, tr, theta0, epsrel=1e-12)[0]
        out[5] += integrate.quad(lambda t: q_b(t) * r * math.sin(t), tr, theta0, epsrel=1e-12)[0]
    return np.array(out)


def _reference_solve(load, slip, beta, law, c, tan_phi, K, K_y, fm, fr, gamma, bull, th_max):
    args = (slip, beta, 0.736, 0.235, law, c, tan_phi, K, K_y, fm, fr, gamma, bull)
    theta0 = optimize.brentq(
        lambda th: _reference_contact(th, *args)[0] - load, 1e-3, th_max, xtol=1e-15, rtol=1e-14
    )
    return theta0, _reference_contact(theta0, *args)


CASES = [
    # (terrain, distribution, load, slip, beta [deg], lateral)
    (
        sj.BekkerSoil(1.1, 5e3, 800e3, 1.5e3, 0.55, shear_modulus=0.02),
        sj.WongReece(0.4, 0.3, -0.1),
        3000.0,
        0.3,
        20.0,
        Lateral(shear_modulus=0.03, unit_weight=14e3, bulldozing=True),
    ),
    (
        sj.BekkerSoil(1.1, 5e3, 800e3, 1.5e3, 0.55, shear_modulus=0.02),
        sj.WongReece(0.4, 0.3, -0.1),
        3000.0,
        -0.3,
        -35.0,
        Lateral(shear_modulus=0.01, unit_weight=14e3, bulldozing=True),
    ),
    (sj.WongSnow.thesis_fresh_snow(), None, 3500.0, 0.2, 15.0, Lateral()),
    (sj.WongSnow.thesis_fresh_snow(), None, 3500.0, -0.4, 50.0, Lateral(unit_weight=3e3)),
]


def _law(terrain):
    if isinstance(terrain, sj.BekkerSoil):
        n, kc, kphi = float(terrain.n), float(terrain.k_c), float(terrain.k_phi)
        return lambda z: (kc / 0.235 + kphi) * max(z, 0.0) ** n, math.radians(85)
    p_w, z_w = float(terrain.p_w), float(terrain.z_w)
    return (
        lambda z: -p_w * math.log1p(-max(z, 0.0) / z_w),
        math.acos(1 - 2 * z_w / 0.736) * (1 - 1e-9),
    )


@pytest.mark.parametrize("case", range(len(CASES)))
def test_equilibrium_and_lateral_force_match_adaptive_quadrature(case):
    terrain, dist, load, slip, deg, lateral = CASES[case]
    beta = math.radians(deg)
    st = sj.solve_wheel(
        WHEEL,
        sj.ContactModel(terrain, distribution=dist, lateral=lateral),
        load,
        slip,
        slip_angle=beta,
    )
    assert int(st.status) == Status.CONVERGED
    law, th_max = _law(terrain)
    c, tp, K = float(terrain.cohesion), float(terrain.tan_phi), float(terrain.shear_modulus)
    K_y = K if lateral.shear_modulus is None else float(lateral.shear_modulus)
    fm, fr = (0.0, 0.0) if dist is None else (0.4 + 0.3 * slip, -0.1)
    theta0, (w, r, t, m, fy, mz) = _reference_solve(
        load, slip, beta, law, c, tp, K, K_y, fm, fr, float(lateral.unit_weight),
        lateral.bulldozing, th_max,
    )  # fmt: skip
    assert float(st.entry_angle) == pytest.approx(theta0, rel=1e-7)
    assert float(st.motion_resistance) == pytest.approx(r, rel=1e-6)
    assert float(st.drawbar_pull) == pytest.approx(t - r, rel=1e-6, abs=1e-7 * load)
    assert float(st.torque) == pytest.approx(m, rel=1e-6)
    assert float(st.lateral_force) == pytest.approx(fy, rel=1e-6)
    assert float(st.aligning_torque) == pytest.approx(mz, rel=1e-6, abs=1e-9 * load)
    assert np.sign(float(st.lateral_force)) == np.sign(deg)


# --------------------------------------------------------------------------------------
# Straight running, symmetry, growth with the slip angle
# --------------------------------------------------------------------------------------

SLIPS = np.array([-0.5, -0.2, 0.0, 0.2, 0.5, 0.9])
# Loads each snow carries (plate-rule snow: a shallow layer; Snow (U.S.): soft, 21 cm
# sinkage at 1 kN).
LOADS = {"fresh": 3000.0, "plate_rule": 1500.0, "snow_us": 1000.0}


@pytest.mark.parametrize("name", ["fresh", pytest.param("snow_us", marks=pytest.mark.slow)])
def test_zero_slip_angle_reproduces_straight_running(name):
    terrain = SHIPPED_SNOWS[name]
    dist = sj.WongReece(0.43, 0.32) if name == "snow_us" else None
    loads = np.array([[1500.0], [4000.0]])
    before = sj.solve_wheel(WHEEL, sj.ContactModel(terrain, dist), loads, SLIPS)
    # A concrete zero takes the same solver path: bit for bit.
    same = sj.solve_wheel(WHEEL, sj.ContactModel(terrain, dist), loads, SLIPS, slip_angle=0.0)
    for field in ("entry_angle", "sinkage", "motion_resistance", "thrust", "torque", "status"):
        np.testing.assert_array_equal(getattr(same, field), getattr(before, field))
    np.testing.assert_array_equal(same.lateral_force, 0.0)
    # A traced zero takes the combined-shear quadrature: the same model.
    traced = jax.jit(
        lambda b: sj.solve_wheel(WHEEL, sj.ContactModel(terrain, dist), loads, SLIPS, slip_angle=b)
    )(0.0)
    np.testing.assert_array_equal(traced.status, before.status)
    np.testing.assert_allclose(traced.entry_angle, before.entry_angle, rtol=1e-9)
    for field in ("motion_resistance", "drawbar_pull", "torque"):
        np.testing.assert_allclose(
            getattr(traced, field), getattr(before, field), rtol=1e-7, atol=1e-9 * 4000
        )
    np.testing.assert_array_equal(traced.lateral_force, 0.0)
    np.testing.assert_array_equal(traced.aligning_torque, 0.0)


@pytest.mark.parametrize(
    "name",
    [pytest.param(n, marks=pytest.mark.slow if n == "snow_us" else ()) for n in SHIPPED_SNOWS],
)
def test_lateral_force_is_odd_and_grows_with_slip_angle_up_to_30_degrees(name):
    terrain = SHIPPED_SNOWS[name]
    betas = np.deg2rad(np.arange(2.5, 30.01, 2.5))[:, None]
    both = np.concatenate([betas, -betas])
    for lateral in (Lateral(), Lateral(unit_weight=3e3, bulldozing=True)):
        st = sj.solve_wheel(
            WHEEL, sj.ContactModel(terrain, lateral=lateral), LOADS[name], SLIPS, slip_angle=both
        )
        assert np.all(st.status == Status.CONVERGED)
        fy = np.asarray(st.lateral_force)
        pos, neg = fy[: len(betas)], fy[len(betas) :]
        np.testing.assert_allclose(neg, -pos, rtol=1e-12, atol=1e-9)
        np.testing.assert_allclose(
            st.aligning_torque[len(betas) :], -st.aligning_torque[: len(betas)], rtol=1e-12
        )
        for field in ("entry_angle", "drawbar_pull", "torque"):
            v = np.asarray(getattr(st, field))
            np.testing.assert_allclose(v[len(betas) :], v[: len(betas)], rtol=1e-12, atol=1e-9)
        assert np.all(pos > 0)
        assert np.all(np.diff(pos, axis=0) > 0), np.diff(pos, axis=0)


def test_resultant_shear_never_exceeds_mohr_coulomb():
    """Under a large slip angle the combined stress takes strength from the longitudinal
    direction: the traction of a driven wheel falls, the resultant stays bounded."""
    snow = SHIPPED_SNOWS["fresh"]
    st = sj.solve_wheel(WHEEL, snow, 3500.0, 0.3, slip_angle=np.deg2rad([0.1, 30.0, 60.0]))
    assert np.all(np.diff(st.thrust) < 0)
    # A wheel fully mobilised in every direction: |(T, F_y)| at most the strength's integral.
    rb = 0.368 * 0.235
    theta0 = float(st.entry_angle[-1])
    bound = rb * float(snow.cohesion) * theta0 + float(snow.tan_phi) * float(
        st.motion_resistance[-1]
    )
    bound += float(snow.tan_phi) * 3500.0
    assert float(jnp.hypot(st.thrust[-1], st.lateral_force[-1])) < bound


# --------------------------------------------------------------------------------------
# Gradients
# --------------------------------------------------------------------------------------


@pytest.mark.slow  # a gradient per leaf, compiled (make test-slow)
def test_gradients_wrt_every_leaf_match_central_differences():
    """d(sinkage, drawbar pull, F_y, M_z)/d(every leaf, load, slip, beta) against central
    differences, on Bekker + Wong–Reece with bulldozing (the model with every term)."""
    terrain = sj.BekkerSoil(1.1, 5e3, 800e3, 1.5e3, 0.55, shear_modulus=0.02)
    dist = sj.WongReece(0.4, 0.3, -0.1)
    lateral = Lateral(shear_modulus=0.03, unit_weight=14e3, bulldozing=True)
    params = (WHEEL, terrain, dist, lateral, jnp.asarray(3000.0), jnp.asarray(0.25), 0.3)

    def outputs(p):
        wh, tr, ds, lt, load, slip, beta = p
        st = sj.solve_wheel(
            wh, sj.ContactModel(tr, distribution=ds, lateral=lt), load, slip, slip_angle=beta
        )
        return jnp.stack([st.sinkage, st.drawbar_pull, st.lateral_force, st.aligning_torque])

    jac = jax.jit(jax.jacfwd(outputs))(params)
    jac_rev = jax.jit(jax.jacrev(outputs))(params)
    flat, tree = jax.tree_util.tree_flatten(params)
    flat_jac = jax.tree_util.tree_leaves(jac)
    flat_rev = jax.tree_util.tree_leaves(jac_rev)
    # Strongly typed float64 leaves (the modules' converters make weakly typed ones): one
    # compiled `f` serves every perturbed copy instead of one per leaf.
    flat = [jnp.asarray(x, jnp.float64) for x in flat]
    f = jax.jit(outputs)
    scale = np.abs(np.asarray(f(jax.tree_util.tree_unflatten(tree, flat))))
    for k, x in enumerate(flat):
        h = 1e-6 * max(abs(float(x)), 1e-3)

        def at(v, k=k):
            leaves = list(flat)
            leaves[k] = jnp.asarray(v, jnp.float64)
            return np.asarray(f(jax.tree_util.tree_unflatten(tree, leaves)))

        fd = (at(float(x) + h) - at(float(x) - h)) / (2 * h)
        got = np.asarray(flat_jac[k])
        err = np.abs(got - fd) * abs(float(x) if float(x) else 1.0) / np.maximum(scale, 1e-12)
        assert np.all(err < 2e-5), (k, got, fd)
        assert np.all(np.abs(np.asarray(flat_rev[k]) - got) <= 1e-9 * (np.abs(got) + scale)), k


@pytest.mark.slow  # two compiled Jacobians (make test-slow)
def test_gradients_at_small_slip_angles_on_a_braked_wheel_match_central_differences():
    """A braked wheel whose shear displacement changes sign near the axle, at slip angles
    that round that kink over a few % of the contact (the lane change of
    tests/test_planar.py: slip -0.08 to -0.11, 1.5 kN, |beta| <= 1e-3 rad): d(drawbar
    pull, F_y, M_z) / d(p_w, beta) by forward mode against central differences.  With
    the straight layer's grading at the split (10 uniform nodes over 0.3 rad) the worst
    of them was 3.3e-3 off (relative)."""
    cases = np.array([[-0.079, 5e-4], [-0.105, 1e-4], [-0.113, -5e-4], [-0.09, 1e-3]])
    base = SHIPPED_SNOWS["fresh"]

    def outputs(p_w, slip, beta):
        snow = sj.WongSnow(p_w, base.z_w, base.cohesion, base.tan_phi, base.shear_modulus)
        st = sj.solve_wheel(WHEEL, snow, 1500.0, slip, slip_angle=beta)
        return jnp.stack([st.drawbar_pull, st.lateral_force, st.aligning_torque])

    p_w = np.full(len(cases), float(base.p_w))
    slip, beta = cases[:, 0], cases[:, 1]
    f = jax.jit(jax.vmap(outputs))
    jac = jax.jit(jax.vmap(jax.jacfwd(outputs, argnums=(0, 2))))(p_w, slip, beta)
    h_p, h_b = 1e-5 * p_w, 1e-3 * np.abs(beta)
    fd = [
        (np.asarray(f(p_w + h_p, slip, beta)) - np.asarray(f(p_w - h_p, slip, beta)))
        / (2 * h_p[:, None]),
        (np.asarray(f(p_w, slip, beta + h_b)) - np.asarray(f(p_w, slip, beta - h_b)))
        / (2 * h_b[:, None]),
    ]
    for got, want in zip(jac, fd):
        np.testing.assert_allclose(np.asarray(got), want, rtol=1e-5, atol=1e-9)


# --------------------------------------------------------------------------------------
# Inputs, batching, float32
# --------------------------------------------------------------------------------------


def test_bad_slip_angle_and_lateral_inputs():
    snow = SHIPPED_SNOWS["fresh"]
    with pytest.raises(ValueError, match=r"slip_angle must be finite and in \(-pi/2, pi/2\)"):
        sj.solve_wheel(WHEEL, snow, 3000.0, 0.2, slip_angle=2.0)
    with pytest.raises(ValueError, match="slip_angle must be finite"):
        sj.solve_wheel(WHEEL, snow, 3000.0, 0.2, slip_angle=[0.1, np.nan])
    with pytest.raises(ValueError, match="lateral.shear_modulus must be finite and > 0 m"):
        sj.solve_wheel(
            WHEEL, sj.ContactModel(snow, lateral=Lateral(-0.01)), 3000.0, 0.2, slip_angle=0.1
        )
    with pytest.raises(ValueError, match="lateral.unit_weight"):
        sj.solve_wheel(
            WHEEL, sj.ContactModel(snow, lateral=Lateral(None, -1.0)), 3000.0, 0.2, slip_angle=0.1
        )
    with pytest.raises(TypeError, match="slip_angle must be a real number"):
        sj.solve_wheel(WHEEL, snow, 3000.0, 0.2, slip_angle="10 deg")
    with pytest.raises(TypeError, match="lateral must be None or a snowjax.Lateral"):
        sj.solve_wheel(WHEEL, sj.ContactModel(snow, lateral=0.02), 3000.0, 0.2, slip_angle=0.1)
    with pytest.raises(ValueError, match="simplified"):
        sj.solve_wheel(
            WHEEL, sj.ContactModel(snow, shear="simplified"), 3000.0, 0.2, slip_angle=0.1
        )
    with pytest.raises(ValueError, match="slip_angle"):
        sj.solve_wheel(WHEEL, snow, 3000.0, [0.1, 0.2], slip_angle=[0.1, 0.2, 0.3])
    # Under jit: a status per element, the rest of the batch solved.
    st = jax.jit(lambda b: sj.solve_wheel(WHEEL, snow, 3000.0, 0.2, slip_angle=b))(
        jnp.array([0.2, 2.0, jnp.nan])
    )
    np.testing.assert_array_equal(st.status, [Status.CONVERGED, 2, 2])
    assert np.isfinite(st.lateral_force[0]) and np.all(np.isnan(st.lateral_force[1:]))


@pytest.mark.parametrize(
    "terrain",
    [
        sj.ReeceSoil(0.8, 10.0, 800.0, 15e3, 1e3, 0.6, shear_modulus=0.02),
        sj.LayeredSnow.ice_layer_example(),
    ],
    ids=["reece", "layered"],
)
@pytest.mark.slow  # two more laws with slip angles (make test-slow)
def test_every_terrain_law_batched_with_slip_angle(terrain):
    betas = np.deg2rad([[-20.0], [0.0], [20.0]])
    st = sj.solve_wheel(
        WHEEL,
        sj.ContactModel(
            terrain,
            distribution=sj.WongReece(0.43, 0.32),
            lateral=Lateral(unit_weight=5e3, bulldozing=True),
        ),
        2500.0,
        [-0.3, 0.2],
        slip_angle=betas,
    )
    assert st.lateral_force.shape == (3, 2)
    assert np.all(st.status == Status.CONVERGED)
    np.testing.assert_allclose(st.lateral_force[0], -st.lateral_force[2], rtol=1e-12)
    assert np.all(st.lateral_force[2] > 0) and np.all(st.lateral_force[1] == 0)


@pytest.mark.slow  # the slip-angle solve compiled in float32 (make test-slow)
def test_float32_has_no_nan():
    f32 = lambda t: jax.tree_util.tree_map(lambda x: jnp.asarray(x, jnp.float32), t)  # noqa: E731
    st = sj.solve_wheel(
        f32(WHEEL),
        sj.ContactModel(
            f32(SHIPPED_SNOWS["fresh"]), lateral=f32(Lateral(0.02, 3e3, bulldozing=True))
        ),
        jnp.float32(3500.0),
        jnp.asarray(SLIPS, jnp.float32),
        slip_angle=jnp.float32(0.4),
    )
    assert st.lateral_force.dtype == jnp.float32
    assert np.all(np.isfinite(st.lateral_force)) and np.all(st.status == Status.CONVERGED)
    ref64 = sj.solve_wheel(
        WHEEL,
        sj.ContactModel(SHIPPED_SNOWS["fresh"], lateral=Lateral(0.02, 3e3, bulldozing=True)),
        3500.0,
        SLIPS,
        slip_angle=0.4,
    )
    np.testing.assert_allclose(st.lateral_force, ref64.lateral_force, rtol=1e-4)


@pytest.mark.slow  # a fit of the lateral modulus (make test-slow)
def test_fit_wheel_recovers_lateral_modulus_from_synthetic_lateral_forces():
    """fit_wheel with slip angles: K_y and tan(phi) come back from noise-free synthetic
    (sinkage, drawbar pull, lateral force) data made by solve_wheel."""
    terrain = sj.BekkerSoil(1.1, 0.0, 800e3, 1.5e3, 0.55, shear_modulus=0.02)
    dist = sj.WongReece(0.4, 0.2)
    truth = Lateral(shear_modulus=0.035)
    slips = np.array([-0.3, 0.0, 0.3, 0.6, -0.3, 0.0, 0.3, 0.6])
    betas = np.deg2rad([10.0, 10.0, 10.0, 10.0, 30.0, 30.0, 30.0, 30.0])
    loads = np.full(8, 3000.0)
    st = sj.solve_wheel(
        WHEEL,
        sj.ContactModel(terrain, distribution=dist, lateral=truth),
        loads,
        slips,
        slip_angle=betas,
    )
    start = sj.BekkerSoil(1.1, 0.0, 800e3, 1.5e3, 0.4, shear_modulus=0.02)
    res = sj.fit_wheel(
        WHEEL,
        sj.ContactModel(start, distribution=dist, lateral=Lateral(shear_modulus=0.02)),
        loads,
        slips,
        {"sinkage": st.sinkage, "drawbar_pull": st.drawbar_pull, "lateral_force": st.lateral_force},
        slip_angle=betas,
        fit=("tan_phi", "lateral.shear_modulus"),
    )
    assert res.params["tan_phi"] == pytest.approx(0.55, rel=1e-6)
    assert res.params["lateral.shear_modulus"] == pytest.approx(0.035, rel=1e-6)
    assert float(res.info["lateral"].shear_modulus) == pytest.approx(0.035, rel=1e-6)
    with pytest.raises(ValueError, match="lateral_force data need the slip_angle"):
        sj.fit_wheel(
            WHEEL, start, loads, slips, {"lateral_force": st.lateral_force}, fit=("tan_phi",)
        )


def test_a_vmapped_warm_start_takes_one_layout_for_the_whole_batch():
    """Vmapped (the rover's environments, four wheels each), the warm-started solve at a
    slip angle chooses its quadrature layout for the whole batch, as one flat batch of
    the same elements does (`batchwide._any_in_batch`): one braked wheel anywhere gives
    every element the four-panel layout.  A choice per environment (a batched
    `lax.cond`) had run both layouts for every environment."""
    from snowjax._wheel.batchwide import _all_in_batch, _any_in_batch

    x = jnp.array([[False, False], [False, True]])
    # one value for the batch (broadcast back to its shape by vmap); per row it would be
    # [False, True]
    np.testing.assert_array_equal(jax.vmap(_any_in_batch)(x), [True, True])
    np.testing.assert_array_equal(jax.vmap(_all_in_batch)(~x), [False, False])
    np.testing.assert_array_equal(jax.vmap(jax.vmap(_any_in_batch))(x), np.ones((2, 2), bool))
    np.testing.assert_array_equal(jax.vmap(_any_in_batch)(x[:1]), [False])

    wheel, snow = sj.RigidWheel.thesis_tire(), sj.WongSnow.thesis_fresh_snow()
    loads = jnp.array([[3e3, 5e3], [4e3, 6e3]])
    slips = jnp.array([[0.2, 0.3], [0.1, -0.1]])  # the second environment brakes a wheel

    def solve(load, slip):
        return sj.solve_wheel(
            wheel, snow, load, slip, slip_angle=jnp.full_like(slip, 0.05),
            initial_entry_angle=jnp.full_like(slip, 0.5),
        )  # fmt: skip

    vmapped = jax.jit(jax.vmap(solve))(loads, slips)
    flat = jax.jit(solve)(loads.reshape(-1), slips.reshape(-1))
    alone = jax.jit(solve)(loads[0], slips[0])  # the driving environment: two panels
    for name in ("entry_angle", "drawbar_pull", "torque", "lateral_force"):
        v, f = getattr(vmapped, name).reshape(-1), getattr(flat, name)
        np.testing.assert_allclose(v, f, rtol=1e-13, err_msg=name)
    # the driving environment took the four-panel layout (within 1e-7 of the two-panel)
    two_panel = alone.drawbar_pull
    np.testing.assert_allclose(vmapped.drawbar_pull[0], two_panel, rtol=1e-7)
    assert np.max(np.abs(vmapped.drawbar_pull[0] / two_panel - 1)) > 1e-13


def test_a_vmapped_batch_in_chunks_matches_one_vmapped_batch_and_its_derivatives(monkeypatch):
    """`batchwide._vmapped_in_chunks` (the rover's wheel forces in MJX, vmapped over
    environments): vmapped over 7 environments of 2 wheels in chunks of 2 environments
    (4 chunks, the last padded), the warm-started equilibria at a slip angle and their
    forward-mode slopes equal those of one vmapped batch within rounding; forward- and
    reverse-mode derivatives of the chunked function (its `custom_jvp`, whose rule is
    the plain function's) equal the plain function's.  No wheel brakes, so every chunk
    takes the layout the whole batch takes.  Fails if the chunks are cut or
    reassembled wrongly (elements of one environment swapped with another's) or if the
    padding leaks into the outputs."""
    from snowjax._wheel import batchwide

    wheel, snow = sj.RigidWheel.thesis_tire(), sj.WongSnow.thesis_fresh_snow()
    rng = np.random.default_rng(4)
    loads = jnp.asarray(rng.uniform(2e3, 6e3, (7, 2)))
    slips = jnp.asarray(rng.uniform(0.05, 0.5, (7, 2)))
    angles = jnp.asarray(rng.uniform(-0.2, 0.2, (7, 2)))
    p_w = 85.55e3  # shared by every environment (an unbatched argument)

    def forces(load, slip, angle, p):
        terrain = sj.WongSnow(p, snow.z_w, snow.cohesion, snow.tan_phi, snow.shear_modulus)

        def out(u):
            st = sj.solve_wheel(
                wheel, terrain, load, u[0], slip_angle=u[1],
                initial_entry_angle=jnp.full_like(load, 0.4),
            )  # fmt: skip
            return jnp.stack([st.drawbar_pull, st.lateral_force, st.torque, st.sinkage])

        u0 = jnp.stack([slip, angle])
        value, slopes = jax.vmap(lambda t: jax.jvp(out, (u0,), (t,)), out_axes=(None, 0))(
            jnp.eye(2)[:, :, None] * jnp.ones_like(slip)
        )
        return value, slopes

    chunked = batchwide._vmapped_in_chunks(forces, 2)
    monkeypatch.setattr(batchwide, "CHUNK_SIZE", 4)  # 2 environments of 2 wheels a chunk
    vmapped_chunks = jax.jit(jax.vmap(chunked, in_axes=(0, 0, 0, None)))
    one_batch = jax.jit(jax.vmap(forces, in_axes=(0, 0, 0, None)))
    got, want = vmapped_chunks(loads, slips, angles, p_w), one_batch(loads, slips, angles, p_w)
    for g, w in zip(got, want):
        assert g.shape == w.shape
        np.testing.assert_allclose(g, w, rtol=1e-12, atol=1e-9)
    assert np.all(np.isfinite(got[1])) and np.max(np.abs(got[1])) > 1.0

    def total(fn, p):  # a scalar of every output, vmapped over the environments
        value, slopes = jax.vmap(fn, in_axes=(0, 0, 0, None))(loads, slips, angles, p)
        return jnp.sum(value[:, 0]) + 1e-3 * jnp.sum(slopes[:, :, 1])

    for fn_derivative in (jax.grad, lambda f: lambda p: jax.jvp(f, (p,), (1.0,))[1]):
        d_chunked = jax.jit(fn_derivative(lambda p: total(chunked, p)))(p_w)
        d_plain = jax.jit(fn_derivative(lambda p: total(forces, p)))(p_w)
        assert abs(float(d_plain)) > 1e-6
        np.testing.assert_allclose(d_chunked, d_plain, rtol=1e-10)
