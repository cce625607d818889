"""Derivative tables 4.3-4.6 of the thesis: autodiff vs finite differences vs the printed forms.

The reference for every derivative is a central finite difference of an independent NumPy
implementation of eqs. (4.1a), (4.5), (4.10), (4.11) and (4.13), written here in
dimensional form from the thesis; the published closed forms (snowjax/_wheel/derivatives.py
thesis_table_*) are then compared with autodiff.  Where the thesis is wrong, the test
asserts that the printed form disagrees and that the corrected form agrees.
"""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import snowjax as sj
from snowjax._wheel import derivatives as dv

# Table 4.1, made dimensional with an arbitrary D and p_w (the model is dimensionless).
D = 0.736
Z_W = 0.2717 * D
K = D / 73.6
P_W = 1.0e4
C = 0.2165 * P_W
TAN_PHI = 0.0787
THETA0 = 0.9398
# sigma_bar under the axle from (4.6) and (4.1b), by hand.
Z0 = 1 - D / 2 * (1 - math.cos(THETA0)) / Z_W
SIGMA_N0 = P_W / C * (-math.log(Z0))


def tau_bar_classic_np(sb, i):
    """tau / c of eq. (4.11) on the rim, sigma from Wong's law (4.1a), theta from (4.5)."""
    sigma = np.asarray(sb) * C
    z = Z_W * (1 - np.exp(-sigma / P_W))
    theta = np.arccos(2 * z / D + math.cos(THETA0))
    j = D / 2 * ((THETA0 - theta) - (1 - i) * (math.sin(THETA0) - np.sin(theta)))
    return (C + sigma * TAN_PHI) * (1 - np.exp(-j / K)) / C


def tau_bar_simplified_np(sb, i):
    """Eq. (4.13) with tau1, tau2 from their definitions."""
    tau1 = (D / K) * (Z_W / D) * (C / P_W) * math.cos(THETA0) / math.sin(THETA0)
    tau2 = 1 / math.cos(THETA0) - 1
    sb = np.asarray(sb)
    u0 = (i + tau2) * tau1 * sb + (2 * i - i**2) * tau1 * sb**3 / 6
    return (1 + sb * TAN_PHI) * (1 - np.exp(-u0))


NP_MODELS = {"classic": tau_bar_classic_np, "simplified": tau_bar_simplified_np}
SLIPS = np.array([0.0, 0.05, 0.2, 0.5, 0.8, 1.0])


def fd1(f, x, h):
    return (f(x + h) - f(x - h)) / (2 * h)


def fd2(f, x, h):
    return (f(x + h) - 2 * f(x) + f(x - h)) / h**2


def test_constants_and_axle_pressure():
    k = dv.DimensionlessConstants.thesis()
    assert float(dv.max_normalized_pressure(k)) == pytest.approx(SIGMA_N0, rel=1e-12)
    # The same constants from the thesis's dimensional parameter sets.
    kk = dv.DimensionlessConstants.from_parameters(
        sj.RigidWheel.thesis_tire(), sj.WongSnow.thesis_fresh_snow(), THETA0
    )
    for name, value in (
        ("z_w_over_d", 0.2717),
        ("c_over_p_w", 0.2165),
        ("u_k", 73.6),
        ("tan_phi", 0.0787),
        ("entry_angle", THETA0),
    ):
        assert float(getattr(kk, name)) == pytest.approx(value, rel=1e-12)


@pytest.mark.parametrize("model", ["classic", "simplified"])
def test_normalized_shear_matches_dimensional_form(model):
    sb = np.linspace(0.0, 0.99 * SIGMA_N0, 31)[:, None]
    f = dv.classic_normalized_shear if model == "classic" else dv.simplified_normalized_shear
    np.testing.assert_allclose(
        np.asarray(f(sb, SLIPS[None, :])),
        NP_MODELS[model](sb, SLIPS[None, :]),
        rtol=1e-10,
        atol=1e-14,
    )


@pytest.mark.parametrize("model", ["classic", "simplified"])
def test_autodiff_matches_finite_differences(model):
    f = NP_MODELS[model]
    sb = np.linspace(0.05, 0.9 * SIGMA_N0, 25)[:, None]
    i = np.array([0.05, 0.2, 0.5, 0.8, 0.95])[None, :]
    d = dv.shear_derivatives(sb, i, model=model)
    y1 = fd1(lambda x: f(x, i), sb, 1e-5)
    y2 = fd2(lambda x: f(x, i), sb, 2e-4)
    y3 = fd1(lambda x: f(sb, x), i, 1e-5)
    y4 = fd2(lambda x: f(sb, x), i, 2e-4)
    for name, ref, tol in (("y1", y1, 1e-7), ("y2", y2, 2e-5), ("y3", y3, 1e-7), ("y4", y4, 2e-5)):
        got = np.asarray(getattr(d, name))
        scale = np.abs(ref).max()
        np.testing.assert_allclose(got, ref, rtol=tol * 10, atol=tol * scale, err_msg=name)
    np.testing.assert_allclose(np.asarray(d.tau), f(sb, i), rtol=1e-10)


def _grid():
    sb = np.linspace(0.0, 0.95 * SIGMA_N0, 60)[:, None]
    return sb, np.linspace(0.0, 1.0, 11)[None, :]


def _assert_close(a, b, rtol=1e-9):
    a, b = np.asarray(a), np.asarray(b)
    np.testing.assert_allclose(b, a, rtol=rtol, atol=1e-13 * np.abs(a).max())


def test_table_4_3_exact_expressions_agree_with_autodiff():
    sb, i = _grid()
    sb = sb[1:]  # the printed forms divide by sin(theta0) - ... fine, but T3 has 0/0-free
    auto = dv.shear_derivatives(sb, i, model="classic")
    table = dv.thesis_table_4_3(sb, i)
    # The saturated region (u_k J up to ~50, exp(-u_k J) ~ 1e-22) is included: relative
    # accuracy there needs the custom derivative of 1 - exp(-x) (see _one_minus_exp).
    for name in ("y1", "y2", "y3", "y4"):
        _assert_close(getattr(auto, name), getattr(table, name))


def test_table_4_3_y2_approximations_are_not_identities():
    sb, i = _grid()
    auto = np.asarray(dv.shear_derivatives(sb, i, model="classic").y2)
    table = dv.thesis_table_4_3(sb, i)
    # First "≈": dropping T0 T_Δ.  At sigma_bar = 0 that is a few per cent of y2.
    rel0 = np.abs(np.asarray(table.y2_without_t_delta)[0] / auto[0] - 1)
    assert np.all(rel0 > 0.01) and np.all(rel0 < 0.1)
    np.testing.assert_allclose(
        np.asarray(table.y2) - np.asarray(table.y2_without_t_delta),
        np.asarray(table.t0 * table.t_delta),
        rtol=1e-12,
        atol=1e-15,
    )
    # Second "≈": -T0²(T1 + T2)² is off by orders of magnitude once exp(-u_k J) < 1.
    j = int(np.argmin(np.abs(sb[:, 0] - 1.0)))
    ratio = np.asarray(table.y2_squared)[j, 1:] / auto[j, 1:]
    assert np.all(ratio < 0.5)


def test_table_4_5_agrees_with_autodiff():
    sb = np.linspace(0.0, 1.2 * SIGMA_N0, 60)[:, None]
    i = np.linspace(0.05, 1.0, 10)[None, :]  # U3 = 0 at sigma_bar = 0 makes y4's U4/U3 0/0
    auto = dv.shear_derivatives(sb[1:], i, model="simplified")
    table = dv.thesis_table_4_5(sb[1:], i)
    for name in ("y1", "y2", "y3", "y4"):
        _assert_close(getattr(auto, name), getattr(table, name))


def test_table_4_6_y2_at_zero_has_a_sign_error():
    tau1 = 73.6 * 0.2717 * 0.2165 * math.cos(THETA0) / math.sin(THETA0)
    tau2 = 1 / math.cos(THETA0) - 1
    for slip in (0.0, 0.3, 0.9):
        u1 = tau1 * (slip + tau2)
        hand = -(u1**2) + 2 * u1 * TAN_PHI  # from y2 of Table 4.5 with U0 = U2 = 0
        fd = fd2(lambda x, slip=slip: tau_bar_simplified_np(x, slip), 2e-3, 2e-3)  # centred at 2e-3
        auto = float(dv.shear_derivatives(0.0, slip, model="simplified").y2)
        printed = float(dv.thesis_table_4_6(slip)["y2"][0])
        corrected = float(dv.thesis_table_4_6(slip, as_printed=False)["y2"][0])
        assert auto == pytest.approx(hand, rel=1e-12)
        assert fd == pytest.approx(hand, rel=2e-2)  # fd is taken slightly inside
        assert printed > 0 > auto  # the printed value has the wrong sign
        assert corrected == pytest.approx(auto, rel=1e-12)
        assert float(dv.thesis_table_4_6(slip)["y1"][0]) == pytest.approx(
            float(dv.shear_derivatives(0.0, slip, model="simplified").y1), rel=1e-12
        )


def test_table_4_4_zero_sinkage_values():
    for slip in (0.0, 0.3, 0.9):
        auto = dv.shear_derivatives(0.0, slip, model="classic")
        printed = dv.thesis_table_4_4(slip)
        exact = dv.thesis_table_4_4(slip, as_printed=False)
        # y1 at sigma_bar = 0 is exact, and equal to the simplified model's tau1 (i + tau2).
        assert float(printed["y1"][0]) == pytest.approx(float(auto.y1), rel=1e-12)
        assert float(auto.y1) == pytest.approx(
            float(dv.shear_derivatives(0.0, slip, model="simplified").y1), rel=1e-12
        )
        # y2 at sigma_bar = 0 as printed keeps only the leading term.
        assert abs(float(printed["y2"][0]) / float(auto.y2) - 1) > 0.005  # 10 % at i = 0
        assert float(exact["y2"][0]) == pytest.approx(float(auto.y2), rel=1e-10)
        # Independent: one-sided second difference of the NumPy model at sigma_bar = 0.
        h = 1e-4
        f = lambda x, slip=slip: tau_bar_classic_np(x, slip)
        fd = (2 * f(0.0) - 5 * f(h) + 4 * f(2 * h) - f(3 * h)) / h**2
        assert fd == pytest.approx(float(auto.y2), rel=1e-4)


def test_table_4_4_maximum_sinkage_limits_hold_only_without_slip():
    # i = 0: y1 -> tan(phi)(1 - exp(-u_k J0)) ~ tan(phi), as printed.
    near = SIGMA_N0 * (1 - 1e-10)
    y1_0 = float(dv.shear_derivatives(near, 0.0).y1)
    j0 = 0.5 * (THETA0 - math.sin(THETA0))
    assert y1_0 == pytest.approx(TAN_PHI * (1 - math.exp(-73.6 * j0)), rel=1e-4)
    assert float(dv.thesis_table_4_4(0.0)["y1"][1]) == pytest.approx(y1_0, rel=1e-2)
    # i > 0: y1 grows like (sigma_n0 - sigma_bar)^(-1/2) instead of tending to tan(phi).
    slip = 0.1
    gaps = np.array([1e-6, 1e-8, 1e-10])
    y1 = np.asarray(dv.shear_derivatives(SIGMA_N0 * (1 - gaps), slip).y1)
    assert np.all(np.diff(y1) > 0) and y1[-1] > 1.0 > 10 * TAN_PHI
    assert 8.0 < y1[-1] / y1[-2] < 10.5  # -> sqrt(100) = 10 as the gap closes
    # Independent: a difference quotient of the NumPy model right under the axle.
    delta = SIGMA_N0 * 1e-10
    fd = (tau_bar_classic_np(SIGMA_N0, slip) - tau_bar_classic_np(SIGMA_N0 - delta, slip)) / delta
    assert fd > 1.0
    assert float(dv.thesis_table_4_4(slip)["y1"][1]) == pytest.approx(TAN_PHI)  # as printed
    assert float(dv.thesis_table_4_4(slip, as_printed=False)["y1"][1]) == math.inf
    # y3, y4 under the axle are printed correctly.
    auto = dv.shear_derivatives(SIGMA_N0 * (1 - 1e-12), slip)
    printed = dv.thesis_table_4_4(slip)
    assert float(printed["y3"][1]) == pytest.approx(float(auto.y3), rel=1e-4)
    assert float(printed["y4"][1]) == pytest.approx(float(auto.y4), rel=1e-4)


def test_appendix_dz_dsigma_as_printed_is_wrong():
    c_over_p_w = 0.2165
    for sb in (0.0, 0.5, 3.0):
        fd = fd1(lambda x: math.exp(-c_over_p_w * x), sb, 1e-6)
        printed = float(dv.thesis_appendix_dz_dsigma(sb))
        corrected = float(dv.thesis_appendix_dz_dsigma(sb, as_printed=False))
        assert corrected == pytest.approx(fd, rel=1e-8)
        assert printed > 0 > fd
        assert jax.grad(lambda s: jnp.exp(-c_over_p_w * s))(sb) == pytest.approx(corrected)


def test_shapes_and_errors():
    d = dv.shear_derivatives(np.linspace(0, 1, 4)[:, None, None], np.array([0.1, 0.2]))
    assert d.y4.shape == (4, 1, 2)
    with pytest.raises(ValueError, match="model"):
        dv.shear_derivatives(0.5, 0.1, model="none")
