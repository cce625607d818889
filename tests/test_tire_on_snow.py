"""`tire_forces_on_snow`: the chapter-3 combined-slip forces on the chapter-4 equilibrium.

Checked against independent computations: the thesis's load functions and force formulas
written out by hand in NumPy (kN coefficients converted here, not by the library), the
SciPy reference of the wheel equilibrium (tests/reference.py: adaptive quadrature and
brentq), and the stand-alone chapter-3 and chapter-4 functions in their limits.
"""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import snowjax as sj
from snowjax._coupled.tire_on_snow import tire_forces_on_snow
from tests import reference

WHEEL = sj.RigidWheel.thesis_tire()
SNOW = sj.WongSnow.thesis_fresh_snow()

# The grid shared by several tests: loads x slips x slip angles (the wheel is solved on
# loads x slips only).
LOADS = np.array([3500.0, 7500.0])[:, None, None]
SLIPS = np.array([-0.3, 0.0, 0.2, 0.6])[None, :, None]
ANGLES = np.radians([-10.0, 0.0, 10.0])[None, None, :]


@pytest.fixture(scope="module")
def grid():
    return tire_forces_on_snow(WHEEL, SNOW, LOADS, SLIPS, ANGLES)


@pytest.fixture(scope="module")
def straight():
    """The chapter-4 results on the same loads x slips, shaped (2, 4)."""
    st = sj.solve_wheel(WHEEL, SNOW, LOADS, SLIPS)
    return jax.tree_util.tree_map(lambda x: x[..., 0], st)


@pytest.mark.filterwarnings("ignore::scipy.integrate.IntegrationWarning")
def test_hand_values_at_one_point():
    load, slip, alpha = 5000.0, 0.2, math.radians(5.0)
    r = tire_forces_on_snow(WHEEL, SNOW, load, slip, alpha)
    by_model = tire_forces_on_snow(WHEEL, sj.ContactModel(SNOW), load, slip, alpha)
    assert float(by_model.lateral_force) == float(r.lateral_force)

    # Chapter 3 by hand: the load functions (3.17)-(3.21) take F_z in kN and give kN/rad.
    fz = load / 1000.0
    c_s = fz / (0.2026 + 0.1516 * fz) * 1000.0  # (3.17) -> N/rad
    c_a = fz / (0.1936 + 0.1190 * fz) * 1000.0  # (3.18) -> N/rad
    mu_x = 0.5386 - 0.0438 * fz + 6.9010e-4 * fz**2  # (3.19)
    mu_y = 0.4131 - 0.0673 * fz + 0.0037 * fz**2  # (3.20)
    e1 = 0.5 * (1 - math.exp(-((7.5852e-9) ** 2) * fz - 0.1203**2 * fz**2))  # (3.21)
    e2 = e1**2 + 1 / 12
    assert c_s == pytest.approx(5205.08, abs=0.01)  # 5.205 kN/rad at 5 kN
    phi_x = c_s * slip / (mu_x * load)  # (3.7), S_x = -i
    phi_y = c_a * (1 - slip) * math.tan(alpha) / (mu_y * load)  # (3.8), 1 + S_x = 1 - i
    phi = math.hypot(phi_x, phi_y)  # (3.9)
    n = 1 - math.exp(-phi - e1 * phi**2 - e2 * phi**3)  # (3.10)
    beta = math.atan2(phi_y, phi_x)
    fx = mu_x * load * n * math.cos(beta)  # (3.14)
    fy = mu_y * load * n * math.sin(beta)  # (3.15)

    # Chapter 4 by SciPy quadrature and brentq (the Table 4.1 snow, classic shear).
    D, b = 0.736, 0.235
    p_w = float(SNOW.p_w)
    solved = reference.solve(
        load, slip, D, b, p_w, 0.2717 * D, 0.2165 * p_w, 0.0787, D / 73.6, "classic"
    )
    assert solved is not None
    theta0, rx = float(solved[0]), float(solved[1][1])  # type: ignore[arg-type]
    z0 = D / 2 * (1 - math.cos(theta0))  # (4.15)

    # Measured: F_x 795.9 N, F_y 339.3 N, R_x 1380.9 N, z0 0.1408 m, net F_x -585.0 N.
    assert float(r.shear_forces.fx_combined) == pytest.approx(fx, rel=1e-12)
    assert float(r.lateral_force) == pytest.approx(fy, rel=1e-12)
    assert float(r.motion_resistance) == pytest.approx(rx, rel=1e-6)
    assert float(r.sinkage) == pytest.approx(z0, rel=1e-6)
    assert float(r.longitudinal_force) == pytest.approx(fx - rx, rel=1e-5)
    assert int(r.status) == sj.Status.CONVERGED


def test_shapes_and_fields(grid):
    shape = (2, 4, 3)
    for leaf in jax.tree_util.tree_leaves(grid):
        assert leaf.shape == shape
    assert np.all(np.asarray(grid.status) == sj.Status.CONVERGED)
    np.testing.assert_allclose(
        grid.longitudinal_force, grid.shear_forces.fx_combined - grid.motion_resistance, rtol=0
    )
    np.testing.assert_array_equal(grid.lateral_force, grid.shear_forces.fy_combined)
    np.testing.assert_array_equal(grid.sinkage, grid.wheel.sinkage)


def test_zero_slip_angle_reduces_to_pure_longitudinal_and_chapter_4(grid, straight):
    tire = sj.tire_forces(LOADS[..., 0], SLIPS[..., 0], 0.0)
    k = 1  # the slip angle 0 column
    np.testing.assert_array_equal(grid.lateral_force[..., k], 0.0)
    np.testing.assert_allclose(grid.shear_forces.fx_combined[..., k], tire.fx_pure, rtol=1e-13)
    np.testing.assert_allclose(grid.motion_resistance[..., k], straight.motion_resistance, rtol=0)
    np.testing.assert_allclose(grid.sinkage[..., k], straight.sinkage, rtol=0)
    np.testing.assert_allclose(grid.wheel.drawbar_pull[..., k], straight.drawbar_pull, rtol=0)
    np.testing.assert_allclose(
        grid.longitudinal_force[..., k],
        np.asarray(tire.fx_pure) - np.asarray(straight.motion_resistance),
        rtol=1e-13,
    )


def test_zero_slip_reduces_to_pure_lateral(grid, straight):
    j = 1  # slip 0
    tire = sj.tire_forces(LOADS[:, 0, :], 0.0, ANGLES[:, 0, :])
    np.testing.assert_allclose(grid.lateral_force[:, j], tire.fy_pure, rtol=1e-13)
    np.testing.assert_array_equal(grid.shear_forces.fx_combined[:, j], 0.0)
    np.testing.assert_allclose(
        grid.longitudinal_force[:, j],
        -np.asarray(straight.motion_resistance)[:, j, None] + 0 * ANGLES[:, 0],
        rtol=0,
    )


def test_lateral_force_odd_and_longitudinal_force_even_in_slip_angle(grid):
    fy = np.asarray(grid.lateral_force)
    fx = np.asarray(grid.longitudinal_force)
    np.testing.assert_allclose(fy[..., 0], -fy[..., 2], rtol=1e-14)
    np.testing.assert_allclose(fx[..., 0], fx[..., 2], rtol=1e-14)
    # Positive slip angle -> positive lateral force, except when spinning away (i < 1 here).
    assert np.all(fy[..., 2] > 0)
    # The sinkage does not depend on the slip angle (straight-running equilibrium).
    z = np.asarray(grid.sinkage)
    np.testing.assert_array_equal(z[..., 0], z[..., 1])
    np.testing.assert_array_equal(z[..., 2], z[..., 1])


def _at(angle):
    """The grid's loads x slips at traced slip angles."""
    return tire_forces_on_snow(WHEEL, SNOW, LOADS, SLIPS, angle)


# One compilation (of the whole solve, inside the outer jit) shared by two tests.
_AT_JIT = jax.jit(_at)


def test_jit_agrees_with_the_eager_call(grid):
    jitted = _AT_JIT(jnp.asarray(ANGLES))
    for a, b in zip(jax.tree_util.tree_leaves(grid), jax.tree_util.tree_leaves(jitted)):
        np.testing.assert_allclose(a, b, rtol=1e-13, atol=1e-10)


@pytest.mark.slow  # the wheel solve compiles again under vmap (~10 s)
def test_vmap_agrees_with_the_broadcast_call(grid):
    vmapped = jax.vmap(_at)(jnp.asarray(ANGLES[0, 0]))  # (3, 2, 4, 1): angle axis first
    for name in ("longitudinal_force", "lateral_force", "sinkage", "motion_resistance"):
        v = np.moveaxis(np.asarray(getattr(vmapped, name))[..., 0], 0, -1)
        np.testing.assert_allclose(v, getattr(grid, name), rtol=1e-13, atol=1e-10)


@pytest.mark.slow  # gradients through the coupled model (make test-slow)
def test_gradient_matches_central_differences():
    x0 = np.array([5200.0, 0.23, 0.12])  # load [N], slip [-], slip angle [rad]
    steps = np.array([1e-1, 1e-5, 1e-6])

    def fields(x):
        r = tire_forces_on_snow(WHEEL, SNOW, x[0], x[1], x[2])
        return jnp.stack([r.longitudinal_force, r.lateral_force, r.motion_resistance])

    # Forward mode through the wheel's implicit-function-theorem derivatives.
    jac = np.asarray(jax.jit(jax.jacfwd(fields))(jnp.asarray(x0)))
    # Scalar calls: they reuse the compilation of test_hand_values_at_one_point.
    pts = x0 + np.concatenate([np.diag(steps), -np.diag(steps)])
    values = np.stack([np.asarray(fields(x)) for x in pts], axis=1)
    fd = (values[:, :3] - values[:, 3:]) / (2 * steps)
    # The motion resistance does not depend on the slip angle.
    assert jac[2, 2] == 0.0 and fd[2, 2] == 0.0
    np.testing.assert_allclose(jac, fd, rtol=1e-6, atol=1e-6)


def test_parameters_and_coefficients_options():
    load, slip, alpha = 5000.0, 0.3, 0.1
    base = tire_forces_on_snow(WHEEL, SNOW, load, slip, alpha)
    same = tire_forces_on_snow(WHEEL, SNOW, load, slip, alpha, parameters=sj.tire_parameters(load))
    np.testing.assert_allclose(same.lateral_force, base.lateral_force, rtol=1e-14)
    # Doubling the friction limits through the coefficients of (3.19), (3.20).
    c = sj.TireCoefficients.thesis()
    doubled = sj.TireCoefficients(
        **{
            k: 2 * getattr(c, k) if k[0] in "AB" and k[1] in "123" else getattr(c, k)
            for k in _FIELDS
        }
    )
    twice = tire_forces_on_snow(WHEEL, SNOW, load, slip, alpha, coefficients=doubled)
    p = sj.tire_parameters(load)
    p2 = sj.TireParameters(p.c_s, p.c_alpha, 2 * p.mu_x, 2 * p.mu_y, p.e1)
    ref = sj.tire_forces_from_parameters(load, slip, alpha, p2)
    np.testing.assert_allclose(twice.lateral_force, ref.fy_combined, rtol=1e-13)
    np.testing.assert_allclose(twice.motion_resistance, base.motion_resistance, rtol=0)


_FIELDS = ("A1", "A2", "A3", "A4", "A5", "B1", "B2", "B3", "B4", "B5", "a1", "a2")


def test_bad_input():
    with pytest.raises(ValueError, match="slip_angle"):
        tire_forces_on_snow(WHEEL, SNOW, 5000.0, 0.2, 2.0)
    with pytest.raises(ValueError, match="slip"):
        tire_forces_on_snow(WHEEL, SNOW, 5000.0, 1.5, 0.1)
    with pytest.raises(ValueError, match="load"):
        tire_forces_on_snow(WHEEL, SNOW, -1.0, 0.2, 0.1)
    with pytest.raises(ValueError, match="not both"):
        tire_forces_on_snow(
            WHEEL,
            SNOW,
            5000.0,
            0.2,
            0.1,
            coefficients=sj.TireCoefficients.thesis(),
            parameters=sj.tire_parameters(5000.0),
        )
    with pytest.raises(TypeError, match="TireParameters"):
        tire_forces_on_snow(WHEEL, SNOW, 5000.0, 0.2, 0.1, parameters=1.0)  # type: ignore[arg-type]
    # Under jit: one bad element gets INVALID_INPUT and NaN, the rest is solved.
    r = _AT_JIT(jnp.radians(jnp.array([[[-10.0, 0.0, 100.0]]])))
    status = np.asarray(r.status)
    assert np.all(status[..., 2] == sj.Status.INVALID_INPUT)
    assert np.all(status[..., :2] == sj.Status.CONVERGED)
    for name in ("longitudinal_force", "lateral_force", "sinkage", "motion_resistance"):
        value = np.asarray(getattr(r, name))
        assert np.all(np.isnan(value[..., 2])) and np.all(np.isfinite(value[..., :2])), name
