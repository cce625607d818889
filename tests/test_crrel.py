"""Tests of the CRREL shallow-snow model (snowjax/_empirical/crrel.py).

Hand values come from the reports: CRREL 95-1 Table A5 (CRM-1 sample runs, M113) and the
CRREL 95-7 final-density table; the arithmetic is written out with `math`.
"""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import snowjax as sj

M113_WEIGHT = 23401.0 * 0.45359237 * 9.80665  # [N], CRREL 95-1 vehicle file (23,401 lb)


def test_final_density_table_crrel_95_7():
    # 0.50 / 0.55 / 0.60 / 0.65 Mg/m^3 for p_max <= 210, > 210, > 350, > 700 kPa
    p = np.array([0.0, 100e3, 210e3, 210.001e3, 350e3, 350.001e3, 700e3, 700.001e3, 2e6])
    expected = [500, 500, 500, 550, 550, 600, 600, 650, 650]
    np.testing.assert_array_equal(np.asarray(sj.crrel_final_density(p)), expected)


def test_rut_depth_crm1_examples_to_printed_digits():
    # CRREL 95-1 Table A5: M113, 15 cm undisturbed snow of 0.2 Mg/m^3 on a road -> 9.0 cm;
    # 12 cm over ice -> 7.2 cm.  M113 nominal ground pressure (two 15 x 105 in tracks):
    pressure = M113_WEIGHT / (2 * 15 * 0.0254 * 105 * 0.0254)
    assert pressure == pytest.approx(51.22e3, rel=1e-3)  # <= 210 kPa -> 500 kg/m^3
    rho_f = sj.crrel_final_density(pressure)
    z = np.asarray(sj.crrel_sinkage(np.array([0.15, 0.12]), 200.0, rho_f))
    assert round(z[0] * 100, 1) == 9.0 and round(z[1] * 100, 1) == 7.2
    # and exactly h (1 - rho0/rho_f):
    np.testing.assert_allclose(z, [0.15 * 0.6, 0.12 * 0.6], rtol=1e-14)


def test_drawbar_crm1_examples_to_printed_digits():
    # (gross traction, level-ground resistance, slope deg) -> (drawbar N, coefficient)
    cases = [
        (44134.3, 5585.4, 0.0, 38548.9, 0.370),
        # example 2: the printed resistance 57631.6 N includes the 30 deg grade
        (39207.1, 57631.6 - M113_WEIGHT * 0.5, 30.0, -18424.5, -0.177),
        (29692.1, 3903.5, 0.0, 25788.6, 0.248),
        (29692.1, 5464.8, 0.0, 24227.2, 0.233),
        (16741.3, 5275.1, 0.0, 11466.2, 0.110),
    ]
    for t, r, deg, pull, coeff in cases:
        dp, c = sj.crrel_drawbar(t, r, M113_WEIGHT, math.radians(deg))
        assert float(dp) == pytest.approx(pull, abs=0.11)
        assert round(float(c), 3) == coeff
    # the printed grade resistance itself: 5585.4 + W sin 30 deg = 57631.6 (+- rounding)
    assert 5585.4 + M113_WEIGHT * 0.5 == pytest.approx(57631.6, abs=0.5)


def test_crrel_wheel_hand_values():
    # h 0.20 m, rho0 200 kg/m^3, rho_f 500: z = 0.12 m; r 0.38 m: a = 0.38 acos(1 - 0.12/0.38)
    out = sj.crrel_wheel(0.20, 200.0, 0.38, 0.235, 6800.0)
    z = 0.20 * (1 - 200 / 500)
    a = 0.38 * math.acos(1 - z / 0.38)
    r = 21.313 * (200 * 0.235 * a) ** 1.1918
    assert float(out.sinkage) == pytest.approx(z, rel=1e-14)
    assert float(out.contact_arc) == pytest.approx(a, rel=1e-14)
    assert float(out.motion_resistance) == pytest.approx(r, rel=1e-12)
    assert float(out.resistance_coefficient) == pytest.approx(r / 6800, rel=1e-12)
    assert float(out.final_density) == 500.0
    # a peak pressure above 350 kPa selects 600 kg/m^3
    hi = sj.crrel_wheel(0.20, 200.0, 0.38, 0.235, 6800.0, peak_pressure=400e3)
    assert float(hi.sinkage) == pytest.approx(0.20 * (1 - 200 / 600), rel=1e-14)


def test_sinkage_zero_when_snow_already_denser_than_final():
    assert float(sj.crrel_sinkage(0.2, 550.0, 500.0)) == 0.0


@pytest.mark.parametrize(
    "call, name",
    [
        (lambda: sj.crrel_sinkage(-0.1, 200.0), "snow_depth"),
        (lambda: sj.crrel_sinkage(0.1, 2000.0), "initial_density"),
        (lambda: sj.crrel_sinkage(0.1, 200.0, 0.5e4), "final_density"),
        (lambda: sj.crrel_final_density(-1.0), "peak_pressure"),
        (lambda: sj.crrel_contact_arc(0.0, 0.1), "radius"),
        (lambda: sj.crrel_wheel(0.2, 200.0, 0.38, 0.235, 0.0), "load"),
        (lambda: sj.crrel_drawbar(1.0, 1.0, 100.0, 30.0), "slope"),
        (lambda: sj.crrel_drawbar(1.0, 1.0, -5.0), "weight"),
    ],
)
def test_bad_input_names_the_argument(call, name):
    with pytest.raises(ValueError, match=f"`{name}`"):
        call()


def test_jit_vmap_grad_agree_with_eager_and_finite_differences():
    h = jnp.array([0.13, 0.18, 0.22])
    rho = jnp.array([160.0, 170.0, 220.0])

    def resistance(h, rho):
        return sj.crrel_wheel(h, rho, 0.38, 0.235, 6800.0).motion_resistance

    eager = resistance(h, rho)
    np.testing.assert_allclose(jax.jit(resistance)(h, rho), eager, rtol=1e-13)
    np.testing.assert_allclose(jax.vmap(resistance)(h, rho), eager, rtol=1e-13)
    grad = jax.grad(lambda h: resistance(h, rho[1]))(0.18)
    eps = 1e-6
    fd = (resistance(0.18 + eps, rho[1]) - resistance(0.18 - eps, rho[1])) / (2 * eps)
    assert float(grad) == pytest.approx(float(fd), rel=1e-6)
    g_rho = jax.grad(lambda r: sj.crrel_sinkage(0.2, r, 500.0))(200.0)
    assert float(g_rho) == pytest.approx(-0.2 / 500.0, rel=1e-12)
    # traced bad input: NaN for that element only
    out = jax.jit(lambda r: sj.crrel_sinkage(0.2, r))(jnp.array([200.0, -1.0]))
    assert np.isfinite(out[0]) and np.isnan(out[1])
