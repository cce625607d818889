"""Tests of the empirical models of chapter 2 (snowjax/_empirical/).

Expected values are hand arithmetic written out with `math` (independent of the code under
test); gradients are checked against central finite differences.
"""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

import snowjax as sj

# Thesis tyre and Shoop's laboratory snow (thesis section 2.1.1), written out by hand.
D, B = 0.736, 0.235
KC, KPHI, N = 3.43e3, 218.84215e3, 1.0707148


# ----------------------------------------------------------------------------------------
# WES coefficients (2.13)-(2.15)
# ----------------------------------------------------------------------------------------


def test_wes_coefficients_hand_values():
    assert float(sj.net_traction_coefficient(600.0, 4000.0)) == pytest.approx(0.15)
    assert float(sj.rolling_resistance_coefficient(-280.0, 3500.0)) == pytest.approx(-0.08)
    # mu_t = Q / (r_r W) = 500 N m / (0.35 m * 4000 N)
    assert float(sj.gross_traction_coefficient(500.0, 0.35, 4000.0)) == pytest.approx(
        500.0 / 1400.0
    )


@pytest.mark.parametrize(
    "call, name",
    [
        (lambda: sj.net_traction_coefficient(1.0, 0.0), "load"),
        (lambda: sj.rolling_resistance_coefficient(1.0, -5.0), "load"),
        (lambda: sj.gross_traction_coefficient(1.0, 0.0, 10.0), "rolling_radius"),
    ],
)
def test_wes_coefficients_reject_bad_input(call, name):
    with pytest.raises(ValueError, match=f"`{name}`"):
        call()


# ----------------------------------------------------------------------------------------
# Brixius (2.17)-(2.20)
# ----------------------------------------------------------------------------------------


def test_brixius_literal_example():
    # CI 100 kPa, b 0.5 m, d 1.0 m, W 5 kN, no deflection:
    # N_B = (1e5 * 0.5 * 1.0 / 5000) * 1 / (1 + 3 * 0.5) = 10 / 2.5 = 4.
    out = sj.brixius(100e3, 0.5, 1.0, 5000.0, 0.0, 0.3, 0.2)
    assert float(out.wheel_numeric) == pytest.approx(4.0, rel=1e-14)
    # mu_T = 0.88 (1 - e^-0.4)(1 - e^-0.15) + 0.04 = 0.88 * 0.329680 * 0.139292 + 0.04
    assert float(out.gross_traction) == pytest.approx(0.080411, abs=2e-6)
    # mu_R = 1/4 + 0.04 + 0.05 * 0.2 / 2 = 0.295
    assert float(out.motion_resistance) == pytest.approx(0.295, rel=1e-14)
    # mu_P = 0.040411 - (0.25 + 0.005)
    assert float(out.net_traction) == pytest.approx(-0.214589, abs=2e-6)


@pytest.mark.parametrize("variant, a, c", [("thesis", 0.75, 0.05), ("brixius1987", 7.5, 0.5)])
def test_brixius_thesis_tyre_hand_values(variant, a, c):
    ci, load, delta, h, s = 450e3, 3500.0, 0.02, 0.17625, 0.15
    n_b = ci * B * D / load * (1 + 5 * delta / h) / (1 + 3 * B / D)
    traction = 0.88 * (1 - math.exp(-0.1 * n_b)) * (1 - math.exp(-a * s))
    mu_t = traction + 0.04
    mu_p = traction - (1.0 / n_b + c * s / math.sqrt(n_b))
    mu_r = 1.0 / n_b + 0.04 + c * s / math.sqrt(n_b)
    out = sj.brixius(ci, B, D, load, delta, h, s, variant=variant)
    assert float(out.wheel_numeric) == pytest.approx(n_b, rel=1e-13)
    assert float(out.gross_traction) == pytest.approx(mu_t, rel=1e-13)
    assert float(out.net_traction) == pytest.approx(mu_p, rel=1e-12)
    assert float(out.motion_resistance) == pytest.approx(mu_r, rel=1e-13)
    assert float(sj.brixius_wheel_numeric(ci, B, D, load, delta, h)) == pytest.approx(n_b)


def test_brixius_broadcasts_and_identities():
    slips = jnp.linspace(0.0, 1.0, 11)
    loads = jnp.array([2e3, 4e3, 6e3])[:, None]
    out = sj.brixius(300e3, B, D, loads, 0.01, 0.17, slips)
    assert out.gross_traction.shape == (3, 11)
    np.testing.assert_allclose(
        out.net_traction, out.gross_traction - out.motion_resistance, rtol=0, atol=1e-15
    )
    # free rolling: gross traction is the constant 0.04 and mu_R = 1/N_B + 0.04
    np.testing.assert_allclose(out.gross_traction[:, 0], 0.04, rtol=1e-15)
    np.testing.assert_allclose(
        out.motion_resistance[:, 0], 1.0 / out.wheel_numeric[:, 0] + 0.04, rtol=1e-14
    )
    # more load -> smaller wheel numeric -> more resistance
    assert np.all(np.diff(np.asarray(out.motion_resistance[:, 5])) > 0)


@pytest.mark.parametrize(
    "kwargs, name",
    [
        (dict(cone_index=0.0), "cone_index"),
        (dict(width=-0.2), "width"),
        (dict(diameter=0.0), "diameter"),
        (dict(load=0.0), "load"),
        (dict(deflection=-0.01), "deflection"),
        (dict(deflection=0.2, section_height=0.17), "deflection"),
        (dict(section_height=0.0), "section_height"),
        (dict(slip=15.0), "slip"),
        (dict(slip=-0.1), "slip"),
        (dict(slip=float("nan")), "slip"),
    ],
)
def test_brixius_rejects_bad_input(kwargs, name):
    args = dict(
        cone_index=300e3,
        width=B,
        diameter=D,
        load=3e3,
        deflection=0.01,
        section_height=0.17,
        slip=0.1,
    )
    args.update(kwargs)
    with pytest.raises(ValueError, match=f"`{name}`"):
        sj.brixius(**args)


def test_brixius_rejects_unknown_variant():
    with pytest.raises(ValueError, match="`variant`"):
        sj.brixius(300e3, B, D, 3e3, 0.01, 0.17, 0.1, variant="asae")


# ----------------------------------------------------------------------------------------
# Gawwad-Crolla (section 2.3.3)
# ----------------------------------------------------------------------------------------


def test_gawwad_crolla_hand_values():
    j0, k = sj.gawwad_crolla_slip_parameters(jnp.array([5.0, 2.0, 10.0]))
    # MOBN 5: j0 = -0.065 + 0.098 = 0.033, k = -0.06 + 0.132 = 0.072
    # MOBN 2: j0 = -0.065 + 0.245 = 0.180, k = -0.06 + 0.33 = 0.27
    # MOBN 10: j0 = -0.065 + 0.049 = -0.016, k = -0.06 + 0.066 = 0.006
    np.testing.assert_allclose(j0, [0.033, 0.180, -0.016], rtol=1e-12)
    np.testing.assert_allclose(k, [0.072, 0.27, 0.006], rtol=1e-12)


@pytest.mark.parametrize("mobn", [0.0, -1.0, 11.0, 20.0])
def test_gawwad_crolla_rejects_bad_mobility(mobn):
    with pytest.raises(ValueError, match="`mobility_number`"):
        sj.gawwad_crolla_slip_parameters(mobn)


# ----------------------------------------------------------------------------------------
# Richmond (2.23)
# ----------------------------------------------------------------------------------------


def test_richmond_hand_values():
    # rho_0 a w = 100 kg/m^3 * 0.05 m * 0.2 m = 1 kg/m  ->  R = 21.313 N exactly
    assert float(sj.richmond_resistance(100.0, 0.05, 0.2)) == pytest.approx(21.313, rel=1e-14)
    # thesis-like tyre in 200 kg/m^3 snow, 0.2 m contact arc: (9.4 kg/m)^1.1918
    expected = 21.313 * math.exp(1.1918 * math.log(200.0 * 0.2 * 0.235))
    got = float(sj.richmond_resistance(200.0, 0.2, 0.235))
    assert got == pytest.approx(expected, rel=1e-13)
    # physically sensible: a few hundred newtons (the note's sanity check)
    assert 250.0 < got < 350.0
    assert float(sj.richmond_resistance(200.0, 0.0, 0.235)) == 0.0


@pytest.mark.parametrize(
    "args, name",
    [
        ((1200.0, 0.2, 0.235), "density"),  # denser than ice
        ((0.0, 0.2, 0.235), "density"),
        ((200.0, -0.1, 0.235), "contact_length"),
        ((200.0, 0.2, 0.0), "width"),
    ],
)
def test_richmond_rejects_bad_input(args, name):
    with pytest.raises(ValueError, match=f"`{name}`"):
        sj.richmond_resistance(*args)


# ----------------------------------------------------------------------------------------
# Bekker (2.24), (2.25)
# ----------------------------------------------------------------------------------------


def test_bekker_compaction_literal():
    # n = 1, b = 0.5, k_c = 1000, k_phi = 8000: modulus 10000; z 0.1:
    # R = 0.5 * 10000 * 0.01 / 2 = 25 N
    assert float(sj.bekker_compaction_resistance(0.1, 0.5, 1000.0, 8000.0, 1.0)) == (
        pytest.approx(25.0, rel=1e-14)
    )


def test_bekker_compaction_lab_snow():
    z = 0.1
    expected = B * (KC / B + KPHI) * z ** (N + 1) / (N + 1)
    got = float(sj.bekker_compaction_resistance(z, B, KC, KPHI, N))
    assert got == pytest.approx(expected, rel=1e-13)
    assert float(sj.bekker_compaction_resistance(0.0, B, KC, KPHI, N)) == 0.0


def test_bekker_rolling_literal():
    # n = 1, D = 1, b = 0.5, k_c = 1000, k_phi = 8000 (k_c + b k_phi = 5000):
    # W = 0.008 * 2 * 5000 / 3 makes 3W / ((3-n)(k_c + b k_phi) sqrt(D)) = 0.008,
    # so z0 = 0.008^(2/3) = 0.04 m and (2.24) gives 0.5 * 10000 * 0.04^2 / 2 = 4 N.
    w = 0.008 * 2 * 5000 / 3
    assert float(sj.bekker_wheel_sinkage(w, 1.0, 0.5, 1000.0, 8000.0, 1.0)) == pytest.approx(
        0.04, rel=1e-13
    )
    assert float(sj.bekker_rolling_resistance(w, 1.0, 0.5, 1000.0, 8000.0, 1.0)) == (
        pytest.approx(4.0, rel=1e-13)
    )


def test_bekker_rolling_lab_snow_hand_values():
    w = 3500.0
    p = (2 * N + 2) / (2 * N + 1)
    m = 1 / (2 * N + 1)
    expected = (3 * w / math.sqrt(D)) ** p / ((3 - N) ** p * (N + 1) * B**m * (KC / B + KPHI) ** m)
    z0 = (3 * w / ((3 - N) * (KC + B * KPHI) * math.sqrt(D))) ** (2 / (2 * N + 1))
    assert float(sj.bekker_rolling_resistance(w, D, B, KC, KPHI, N)) == pytest.approx(
        expected, rel=1e-13
    )
    assert float(sj.bekker_wheel_sinkage(w, D, B, KC, KPHI, N)) == pytest.approx(z0, rel=1e-13)
    assert 0.2 < z0 < 0.3  # Shoop's soft snow: the wheel sinks ~25 cm (beyond D/6)


@settings(max_examples=60, deadline=None)
@given(
    load=st.floats(10.0, 2e4),
    diameter=st.floats(0.2, 2.0),
    width=st.floats(0.05, 1.0),
    k_c=st.floats(-1e3, 1e5),
    k_phi=st.floats(1e4, 5e6),
    n=st.floats(0.0, 2.9),
)
def test_bekker_closed_form_equals_compaction_at_rigid_wheel_sinkage(
    load, diameter, width, k_c, k_phi, n
):
    """(2.25) == (2.24) at z0 = [3W / ((3 - n)(k_c + b k_phi) sqrt(D))]^(2/(2n+1))."""
    assume(k_c + width * k_phi > 1e-3 * width * k_phi)
    z0 = (3 * load / ((3 - n) * (k_c + width * k_phi) * math.sqrt(diameter))) ** (2 / (2 * n + 1))
    closed = float(sj.bekker_rolling_resistance(load, diameter, width, k_c, k_phi, n))
    from_sinkage = float(sj.bekker_compaction_resistance(z0, width, k_c, k_phi, n))
    assert closed == pytest.approx(from_sinkage, rel=1e-10)


@pytest.mark.parametrize(
    "call, name",
    [
        (lambda: sj.bekker_compaction_resistance(-0.01, B, KC, KPHI, N), "sinkage"),
        (lambda: sj.bekker_compaction_resistance(0.1, 0.0, KC, KPHI, N), "width"),
        (lambda: sj.bekker_compaction_resistance(0.1, B, KC, KPHI, -0.5), "n"),
        (lambda: sj.bekker_compaction_resistance(0.1, B, -1e5, 10.0, N), "k_c / width"),
        (lambda: sj.bekker_rolling_resistance(-1.0, D, B, KC, KPHI, N), "load"),
        (lambda: sj.bekker_rolling_resistance(3e3, 0.0, B, KC, KPHI, N), "diameter"),
        (lambda: sj.bekker_rolling_resistance(3e3, D, B, KC, KPHI, 3.0), "n"),
        (lambda: sj.bekker_wheel_sinkage(3e3, D, B, KC, KPHI, 3.5), "n"),
    ],
)
def test_bekker_rejects_bad_input(call, name):
    with pytest.raises(ValueError, match=f"`{name}"):
        call()


# ----------------------------------------------------------------------------------------
# Van Es (2.26)
# ----------------------------------------------------------------------------------------


def test_van_es_compaction_literal():
    # rho_i 900, rho_0 300, rho_f 450, lambda 1: u_0 = 2, u_f = 1;
    # int_1^2 e^-u^2 du = (sqrt(pi)/2)(erf 2 - erf 1) = 0.886227 * 0.152621 = 0.135257
    # prefactor b sigma_i rho_0 h_0 / rho_i = 0.2 * 1e5 * 300 * 0.3 / 900 = 2000 N
    got = sj.van_es_compaction_resistance(0.2, 0.3, 300.0, 450.0, 1e5, ice_density=900.0)
    expected = 2000.0 * 0.5 * math.sqrt(math.pi) * (math.erf(2.0) - math.erf(1.0))
    assert float(got) == pytest.approx(expected, rel=1e-13)
    assert float(got) == pytest.approx(270.51, abs=0.01)


def test_van_es_compaction_is_the_work_of_the_implied_compaction_law():
    """D_c = b int p dh over the snow column, with p = sigma_i exp(-lambda r^2)."""
    from scipy.integrate import quad

    b, h0, rho0, rhof, sigma, lam, rhoi = 0.235, 0.2, 200.0, 420.0, 4e5, 1.6, 917.0

    def pressure_at_height(h):  # column squeezed from h0 to h: rho = rho0 h0 / h
        r = rhoi / (rho0 * h0 / h) - 1
        return sigma * math.exp(-lam * r * r)

    hf = rho0 * h0 / rhof
    work, _ = quad(pressure_at_height, hf, h0, epsabs=0, epsrel=1e-12)
    got = sj.van_es_compaction_resistance(b, h0, rho0, rhof, sigma, grain_index=lam)
    assert float(got) == pytest.approx(b * work, rel=1e-9)


def test_van_es_total_and_edge_cases():
    args = (0.235, 0.2, 200.0, 400.0, 4e5)
    d_c = float(sj.van_es_compaction_resistance(*args))
    total = sj.van_es_rolling_resistance(3000.0, *args, 0.015, displacement_drag=12.0)
    assert float(total) == pytest.approx(0.015 * 3000.0 + d_c + 12.0, rel=1e-14)
    # no compaction, no snow -> no compaction resistance
    assert float(sj.van_es_compaction_resistance(0.235, 0.2, 200.0, 200.0, 4e5)) == 0.0
    assert float(sj.van_es_compaction_resistance(0.235, 0.0, 200.0, 400.0, 4e5)) == 0.0
    # compaction all the way to ice: int_0^{u0} = (sqrt(pi)/2) erf(u0), u0 = 917/200 - 1
    full = sj.van_es_compaction_resistance(0.235, 0.2, 200.0, 917.0, 4e5)
    u0 = 917.0 / 200.0 - 1
    expected = 0.235 * 4e5 * 200.0 * 0.2 / 917.0 * 0.5 * math.sqrt(math.pi) * math.erf(u0)
    assert float(full) == pytest.approx(expected, rel=1e-13)


def test_van_es_small_compaction_is_accurate():
    # u_0 = 3.585, u_f = 3.5: erf(u) ~ 1 - 1e-6, a naive erf difference loses digits.
    rho_f = 917.0 / 4.5
    got = float(sj.van_es_compaction_resistance(0.235, 0.2, 200.0, rho_f, 4e5))
    from scipy.integrate import quad

    integral, _ = quad(lambda u: math.exp(-u * u), 3.5, 917.0 / 200.0 - 1, epsrel=1e-13)
    expected = 0.235 * 4e5 * 200.0 * 0.2 / 917.0 * integral
    assert got == pytest.approx(expected, rel=1e-10)


@pytest.mark.parametrize(
    "kwargs, name",
    [
        (dict(width=0.0), "width"),
        (dict(snow_depth=-0.1), "snow_depth"),
        (dict(initial_density=0.0), "initial_density"),
        (dict(initial_density=950.0, final_density=960.0), "initial_density"),
        (dict(final_density=150.0), "final_density"),
        (dict(final_density=1000.0), "final_density"),
        (dict(ice_pressure=-1.0), "ice_pressure"),
        (dict(grain_index=0.0), "grain_index"),
    ],
)
def test_van_es_rejects_bad_input(kwargs, name):
    args = dict(
        width=0.235,
        snow_depth=0.2,
        initial_density=200.0,
        final_density=400.0,
        ice_pressure=4e5,
    )
    args.update(kwargs)
    with pytest.raises(ValueError, match=f"`{name}`"):
        sj.van_es_compaction_resistance(**args)


def test_van_es_total_rejects_bad_input():
    with pytest.raises(ValueError, match="`hard_surface_coefficient`"):
        sj.van_es_rolling_resistance(3e3, 0.235, 0.2, 200.0, 400.0, 4e5, -0.01)
    with pytest.raises(ValueError, match="`load`"):
        sj.van_es_rolling_resistance(-3e3, 0.235, 0.2, 200.0, 400.0, 4e5, 0.01)


# ----------------------------------------------------------------------------------------
# gradients, jit, vmap, traced bad input
# ----------------------------------------------------------------------------------------

_MODELS = {
    "brixius_mu_r": (
        lambda ci, w, s: sj.brixius(ci, B, D, w, 0.02, 0.17625, s).motion_resistance,
        (450e3, 3500.0, 0.2),
    ),
    "brixius_mu_p": (
        lambda ci, w, s: sj.brixius(ci, B, D, w, 0.02, 0.17625, s).net_traction,
        (450e3, 3500.0, 0.2),
    ),
    "gawwad_crolla_k": (lambda m: sj.gawwad_crolla_slip_parameters(m)[1], (4.0,)),
    "richmond": (sj.richmond_resistance, (200.0, 0.25, 0.235)),
    "bekker_2_24": (
        lambda z, kc, kp, n: sj.bekker_compaction_resistance(z, B, kc, kp, n),
        (0.1, KC, KPHI, N),
    ),
    "bekker_2_25": (
        lambda w, d, kc, kp, n: sj.bekker_rolling_resistance(w, d, B, kc, kp, n),
        (3500.0, D, KC, KPHI, N),
    ),
    "van_es": (
        lambda h0, rho0, rhof, sig, lam: sj.van_es_rolling_resistance(
            3e3, B, h0, rho0, rhof, sig, 0.01, grain_index=lam
        ),
        (0.2, 200.0, 400.0, 4e5, 1.3),
    ),
}


@pytest.mark.parametrize("name", sorted(_MODELS))
def test_gradients_match_central_differences(name):
    fn, x0 = _MODELS[name]
    x0 = tuple(float(x) for x in x0)
    grads = jax.grad(lambda *a: fn(*a), argnums=tuple(range(len(x0))))(*x0)
    for i, g in enumerate(grads):
        assert np.isfinite(float(g))
        h = 1e-6 * max(abs(x0[i]), 1e-3)
        plus = list(x0)
        minus = list(x0)
        plus[i] += h
        minus[i] -= h
        fd = (float(fn(*plus)) - float(fn(*minus))) / (2 * h)
        assert float(g) == pytest.approx(fd, rel=1e-6, abs=1e-9 * max(1.0, abs(fd))), (name, i)


def test_gradients_finite_at_boundaries():
    # zero sinkage, zero contact length, zero load, free rolling, rho_f = rho_0
    g = jax.grad(lambda z: sj.bekker_compaction_resistance(z, B, KC, KPHI, N))(0.0)
    assert np.isfinite(float(g))
    g = jax.grad(lambda a: sj.richmond_resistance(200.0, a, B))(0.0)
    assert float(g) == 0.0
    g = jax.grad(lambda w: sj.bekker_rolling_resistance(w, D, B, KC, KPHI, N))(0.0)
    assert np.isfinite(float(g))
    g = jax.grad(lambda s: sj.brixius(300e3, B, D, 3e3, 0.0, 0.17, s).gross_traction)(0.0)
    assert float(g) == pytest.approx(0.88 * (1 - math.exp(-0.1 * _nb(300e3, 3e3, 0.0))) * 0.75)
    g = jax.grad(lambda rf: sj.van_es_compaction_resistance(B, 0.2, 200.0, rf, 4e5))(200.0)
    assert np.isfinite(float(g))


def _nb(ci, w, delta, h=0.17):
    return ci * B * D / w * (1 + 5 * delta / h) / (1 + 3 * B / D)


def test_jit_and_vmap_agree_with_eager():
    loads = jnp.linspace(1e3, 8e3, 5)
    eager = sj.bekker_rolling_resistance(loads, D, B, KC, KPHI, N)
    jitted = jax.jit(sj.bekker_rolling_resistance)(loads, D, B, KC, KPHI, N)
    mapped = jax.vmap(lambda w: sj.bekker_rolling_resistance(w, D, B, KC, KPHI, N))(loads)
    np.testing.assert_allclose(jitted, eager, rtol=1e-14)
    np.testing.assert_allclose(mapped, eager, rtol=1e-14)
    mu = jax.jit(lambda w: sj.brixius(300e3, B, D, w, 0.01, 0.17, 0.3))(loads)
    np.testing.assert_allclose(
        mu.motion_resistance,
        sj.brixius(300e3, B, D, loads, 0.01, 0.17, 0.3).motion_resistance,
        rtol=1e-14,
    )


def test_traced_bad_input_gives_nan_only_for_that_element():
    dens = jnp.array([200.0, -5.0, 300.0])
    out = jax.jit(lambda r: sj.richmond_resistance(r, 0.2, B))(dens)  # no eager check
    assert np.isfinite(out[0]) and np.isnan(out[1]) and np.isfinite(out[2])
    grad = jax.grad(lambda r: jnp.sum(jnp.where(r > 0, sj.richmond_resistance(r, 0.2, B), 0.0)))(
        dens
    )
    assert np.all(np.isfinite(grad))
    slips = jnp.array([0.1, 1.5])
    mu = jax.jit(lambda s: sj.brixius(300e3, B, D, 3e3, 0.0, 0.17, s).gross_traction)(slips)
    assert np.isfinite(mu[0]) and np.isnan(mu[1])
    rho_f = jnp.array([400.0, 100.0])
    d_c = jax.vmap(lambda rf: sj.van_es_compaction_resistance(B, 0.2, 200.0, rf, 4e5))(rho_f)
    assert np.isfinite(d_c[0]) and np.isnan(d_c[1])


# ----------------------------------------------------------------------------------------
# comparison of every motion-resistance model
# ----------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def comparison():
    return sj.compare_motion_resistance(np.array([1e3, 3.5e3, 7.5e3]))


def test_comparison_table_is_consistent(comparison):
    table, figure = comparison
    from matplotlib.figure import Figure

    assert isinstance(figure, Figure)
    loads = table["load"]
    np.testing.assert_array_equal(loads, [1e3, 3.5e3, 7.5e3])
    for key in ("bekker", "richmond", "van_es"):
        assert table[key].shape == (3,)
        assert np.all(np.isfinite(table[key])) and np.all(table[key] >= 0), key
    # Bekker column: eq. (2.25) by hand with the lab snow
    p = (2 * N + 2) / (2 * N + 1)
    m = 1 / (2 * N + 1)
    bekker = [
        (3 * w / math.sqrt(D)) ** p / ((3 - N) ** p * (N + 1) * B**m * (KC / B + KPHI) ** m)
        for w in loads
    ]
    np.testing.assert_allclose(table["bekker"], bekker, rtol=1e-12)
    # Richmond column from the reported contact arc, rho_0 = 200 kg/m^3
    richmond = [21.313 * (200.0 * a * B) ** 1.1918 for a in table["contact_length"]]
    np.testing.assert_allclose(table["richmond"], richmond, rtol=1e-12)
    # Van Es final density: mass conservation in the rut (capped at ice)
    rut = table.get("rigid_wheel_sinkage", table["bekker_sinkage"])
    h0 = 0.2717 * D
    expected_rho_f = []
    for z in np.asarray(rut):
        if not math.isfinite(z):
            expected_rho_f.append(math.nan)
        elif z >= h0:
            expected_rho_f.append(917.0)
        else:
            expected_rho_f.append(min(200.0 * h0 / (h0 - z), 917.0))
    np.testing.assert_allclose(table["final_density"], expected_rho_f, rtol=1e-12)
    # every model: more load, at least as much resistance (where the model has a value)
    for key in ("bekker", "richmond", "van_es", "rigid_wheel"):
        if key in table:
            values = table[key][np.isfinite(table[key])]
            assert np.all(np.diff(values) >= 0), key


def test_comparison_includes_rigid_wheel_when_available(comparison):
    table, _ = comparison
    if not hasattr(sj, "solve_wheel"):
        pytest.skip("snowjax.solve_wheel not available yet")
    state = sj.solve_wheel(  # same call as inside compare_motion_resistance: compiled once
        sj.RigidWheel.thesis_tire(),
        sj.WongSnow.thesis_fresh_snow(),
        jnp.asarray(table["load"]),
        jnp.asarray(0.0),
    )
    status = np.asarray(state.status)
    np.testing.assert_array_equal(table["rigid_wheel_status"], status)
    usable = (status == 0) | (status == 1)
    assert usable[0]  # 1 kN on the thesis snow converges
    np.testing.assert_allclose(
        table["rigid_wheel"][usable], np.asarray(state.motion_resistance)[usable], rtol=1e-12
    )
    assert np.all(np.isnan(table["rigid_wheel"][~usable]))
    assert np.all(table["rigid_wheel"][usable] > 0)
    assert np.all(table["rigid_wheel_sinkage"][usable] <= 0.2717 * D + 1e-12)
    # Richmond's contact arc is r * theta0 of the rigid wheel
    np.testing.assert_allclose(
        table["contact_length"][usable], D / 2 * np.asarray(state.entry_angle)[usable], rtol=1e-12
    )


def test_comparison_brixius_column():
    loads = np.array([1e3, 3.5e3, 7.5e3])  # the fixture's loads: the solver is compiled once
    table, _ = sj.compare_motion_resistance(
        loads, brixius=sj.BrixiusTyre(cone_index=200e3, section_height=0.17625, deflection=0.02)
    )
    for w, got in zip(loads, table["brixius"]):
        n_b = 200e3 * B * D / w * (1 + 5 * 0.02 / 0.17625) / (1 + 3 * B / D)
        assert got == pytest.approx((1 / n_b + 0.04) * w, rel=1e-12)
    with pytest.raises(TypeError, match=r"cone_index=...\) is now spelled brixius=BrixiusTyre"):
        sj.compare_motion_resistance(loads, cone_index=200e3)
    # Another snow cover: Richmond's resistance at its density, Van Es at its depth.
    cover = sj.SnowCover(density=250.0, depth=0.3)
    other, _ = sj.compare_motion_resistance(loads, cover=cover)
    arc = other["contact_length"]
    np.testing.assert_allclose(other["richmond"], sj.richmond_resistance(250.0, arc, B), rtol=1e-12)
    assert np.all(other["van_es"] != table["van_es"])
    with pytest.raises(TypeError, match=r"density=...\) is now spelled cover=SnowCover"):
        sj.compare_motion_resistance(loads, density=250.0)
