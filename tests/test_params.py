"""Parameter sets and presets."""

import math

import jax.numpy as jnp
import numpy as np
import pytest
from scipy import integrate

import snowjax as sj


def test_thesis_fresh_snow_ratios_table_4_1():
    s = sj.WongSnow.thesis_fresh_snow()
    D = 0.736
    assert float(s.z_w) / D == pytest.approx(0.2717)
    assert float(s.cohesion / s.p_w) == pytest.approx(0.2165)
    assert D / float(s.shear_modulus) == pytest.approx(73.6)
    assert float(s.tan_phi) == pytest.approx(0.0787)
    # Overridable p_w, cohesion follows the ratio.
    s2 = sj.WongSnow.thesis_fresh_snow(p_w=50e3)
    assert float(s2.cohesion) == pytest.approx(0.2165 * 50e3)


def test_default_p_w_reproduces_table_4_1_entry_angle():
    """p_w is chosen so that theta0 = 53.6747 deg is the no-shear equilibrium at 5 kN."""
    D, b = 0.736, 0.235
    z_w = 0.2717 * D
    theta0 = math.radians(53.6747)
    assert D / 2 * (1 - math.cos(theta0)) == pytest.approx(0.150, abs=1e-5)  # z0 = 15 cm
    z0_rel = 1 - D / 2 * (1 - math.cos(theta0)) / z_w
    J = integrate.quad(
        lambda t: -math.log(z0_rel + D / z_w * math.sin(t / 2) ** 2) * math.cos(t),
        0,
        theta0,
        epsrel=1e-13,
    )[0]
    p_w = 5000.0 / (D / 2 * b * J)
    assert float(sj.WongSnow.thesis_fresh_snow().p_w) == pytest.approx(p_w, rel=1e-5)


def test_bekker_presets_wong_table_2_3_in_si():
    us = sj.BekkerSoil.snow_us()
    assert float(us.n) == 1.6
    assert float(us.k_c) == pytest.approx(4370.0)
    assert float(us.k_phi) == pytest.approx(196720.0)
    assert float(us.cohesion) == pytest.approx(1030.0)
    assert float(us.tan_phi) == pytest.approx(math.tan(math.radians(19.7)))
    h = sj.BekkerSoil.snow_harrison()
    assert (float(h.n), float(h.k_c), float(h.k_phi), float(h.cohesion)) == pytest.approx(
        (1.6, 2490.0, 245900.0, 620.0)
    )
    sw = sj.BekkerSoil.snow_sweden()
    assert (float(sw.n), float(sw.k_c), float(sw.k_phi), float(sw.cohesion)) == pytest.approx(
        (1.44, 10550.0, 66080.0, 6000.0)
    )
    assert float(sw.tan_phi) == pytest.approx(math.tan(math.radians(20.7)))


def test_leaves_are_float_arrays():
    w = sj.RigidWheel(1, 0.3)  # ints become floats
    assert jnp.issubdtype(w.diameter.dtype, jnp.floating)
    w32 = sj.RigidWheel(np.float32(0.7), np.float32(0.2))
    assert w32.diameter.dtype == jnp.float32
    assert float(sj.RigidWheel.thesis_tire().radius) == pytest.approx(0.368)
