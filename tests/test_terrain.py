"""Terrain laws against hand-computed values (thesis chapter 2 and 4)."""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import snowjax as sj


def test_bekker_hand_value():
    # Thesis lab snow fit (section 2.1.1) on a 23 cm plate at 10 cm sinkage.
    k_c, k_phi, n, b, z = 3.43e3, 218.84215e3, 1.0707148, 0.23, 0.10
    expected = (3430.0 / 0.23 + 218842.15) * 0.1**1.0707148  # 233 755 Pa/m^n * 0.08497
    assert expected == pytest.approx(19863.07, rel=1e-6)
    assert float(sj.bekker_pressure(z, b, k_c, k_phi, n)) == pytest.approx(expected, rel=1e-12)
    assert float(sj.bekker_pressure(-0.01, b, k_c, k_phi, n)) == 0.0
    g = jax.grad(sj.bekker_pressure)(0.0, b, k_c, k_phi, 0.5)  # n < 1: gradient at 0 finite
    assert np.isfinite(g)


def test_wong_law_and_inverse():
    # z = z_w (1 - e^{-sigma/p_w}); sigma = 3 p_w -> z = 0.95021 z_w (Wong's 95 % rule).
    assert float(sj.wong_sinkage(30e3, 10e3, 0.2)) == pytest.approx(
        0.2 * (1 - math.exp(-3)), rel=1e-13
    )
    assert 0.2 * (1 - math.exp(-3)) == pytest.approx(0.190043, rel=1e-5)
    # sigma = -p_w ln(1 - z / z_w): z = 0.1, z_w = 0.2 -> p_w ln 2.
    assert float(sj.wong_pressure(0.1, 10e3, 0.2)) == pytest.approx(10e3 * math.log(2), rel=1e-13)
    z = jnp.linspace(0.0, 0.199, 7)
    np.testing.assert_allclose(
        sj.wong_sinkage(sj.wong_pressure(z, 7e3, 0.2), 7e3, 0.2), z, atol=1e-14
    )
    # At and beyond the base the pressure is +inf, never NaN.
    assert np.all(np.isposinf(sj.wong_pressure(jnp.array([0.2, 0.3]), 7e3, 0.2)))
    assert np.isfinite(jax.grad(sj.wong_pressure)(0.1, 7e3, 0.2))
    assert float(jax.grad(sj.wong_pressure)(0.0, 7e3, 0.2)) == pytest.approx(7e3 / 0.2)


def test_reece_hand_value():
    # sigma = (c k'_c + gamma b k'_phi)(z/b)^n with c=2 kPa, gamma=2000 N/m^3, b=0.2, k'_c=10,
    # k'_phi=500, n=1.1, z=0.05: (20000 + 200000) * 0.25^1.1
    expected = (2000 * 10 + 2000 * 0.2 * 500) * 0.25**1.1
    got = sj.reece_pressure(0.05, 0.2, 2000.0, 2000.0, 10.0, 500.0, 1.1)
    assert float(got) == pytest.approx(expected, rel=1e-12)
    assert expected == pytest.approx(47880.28, rel=1e-6)


def test_mohr_coulomb_and_janosi_hanamoto():
    assert float(sj.mohr_coulomb(10e3, 1e3, 0.5)) == pytest.approx(6e3)
    # tau = (c + sigma tan phi)(1 - e^{-j/K}); j = K -> factor 1 - 1/e.
    tau = sj.janosi_hanamoto(0.01, 10e3, 1e3, 0.5, 0.01)
    assert float(tau) == pytest.approx(6e3 * (1 - math.exp(-1)), rel=1e-13)
    # Braking: odd in j, bounded by the strength.
    assert float(sj.janosi_hanamoto(-0.01, 10e3, 1e3, 0.5, 0.01)) == pytest.approx(-float(tau))
    assert float(sj.janosi_hanamoto(-5.0, 10e3, 1e3, 0.5, 0.01)) == pytest.approx(-6e3)
    # Slope at j = 0 is strength / K from both sides, and finite everywhere.
    d = jax.grad(sj.janosi_hanamoto)(0.0, 10e3, 1e3, 0.5, 0.01)
    assert float(d) == pytest.approx(6e3 / 0.01)
    d_neg = jax.grad(sj.janosi_hanamoto)(-1e-9, 10e3, 1e3, 0.5, 0.01)
    assert float(d_neg) == pytest.approx(6e3 / 0.01, rel=1e-6)
    assert np.isfinite(jax.grad(sj.janosi_hanamoto)(-50.0, 10e3, 1e3, 0.5, 0.01))


def test_gawwad_crolla():
    # (2.22): threshold j0 shifts the displacement: j = 0.02, j0 = 0.01, k = 0.03 -> 1 - e^{-1}.
    got = sj.gawwad_crolla_shear(0.02, 0.01, 10e3, 1e3, 0.5, 0.03)
    assert float(got) == pytest.approx(6e3 * (1 - math.exp(-1)), rel=1e-13)
    # (2.21): p = (k_c/b + k_phi) z_u^n - (k_0 + A_u z_u)(z_u - z).
    k_c, k_phi, n, b, z_u, z, k0, a_u = 4.37e3, 196.72e3, 1.6, 0.3, 0.1, 0.08, 2e5, 5e5
    peak = (k_c / b + k_phi) * z_u**n
    expected = peak - (k0 + a_u * z_u) * (z_u - z)
    assert expected == pytest.approx(306.9, abs=0.5)  # 5306.9 Pa - 2.5e5 Pa/m * 0.02 m
    got = sj.gawwad_crolla_unloading_pressure(z, z_u, b, k_c, k_phi, n, k0, a_u)
    assert float(got) == pytest.approx(expected, rel=1e-12)
    assert float(
        sj.gawwad_crolla_unloading_pressure(z_u, z_u, b, k_c, k_phi, n, k0, a_u)
    ) == pytest.approx(peak)
    assert float(sj.gawwad_crolla_unloading_pressure(0.0, z_u, b, k_c, k_phi, n, k0, a_u)) == 0.0


def test_wong_snow_from_a_snow_pit():
    """z_w = h (1 - rho0 / rho_f), CRREL 95-7 eq. 1: 0.20 m of 150 kg/m^3 snow compacted to
    500 kg/m^3 leaves 0.14 m; to 600, 0.15 m.  Bad pits are named; under jit no check."""
    snow = sj.WongSnow.from_snow_pit(0.20, 150.0, 30e3, 5e3, 0.1, 0.01)
    assert math.isclose(float(snow.z_w), 0.14, rel_tol=1e-15)
    assert float(snow.p_w) == 30e3 and float(snow.cohesion) == 5e3
    deeper = sj.WongSnow.from_snow_pit(0.20, 150.0, 30e3, 5e3, 0.1, 0.01, final_density=600.0)
    assert math.isclose(float(deeper.z_w), 0.15, rel_tol=1e-15)
    with pytest.raises(ValueError, match="density < final_density"):
        sj.WongSnow.from_snow_pit(0.20, 500.0, 30e3, 5e3, 0.1, 0.01)
    with pytest.raises(ValueError, match="depth > 0"):
        sj.WongSnow.from_snow_pit(0.0, 150.0, 30e3, 5e3, 0.1, 0.01)
    z_w = jax.jit(lambda h: sj.WongSnow.from_snow_pit(h, 150.0, 30e3, 5e3, 0.1, 0.01).z_w)
    assert math.isclose(float(z_w(0.2)), 0.14, rel_tol=1e-15)
    assert math.isclose(
        float(
            jax.grad(lambda h: sj.WongSnow.from_snow_pit(h, 150.0, 3e4, 5e3, 0.1, 0.01).z_w)(0.2)
        ),
        0.7,
        rel_tol=1e-15,
    )
