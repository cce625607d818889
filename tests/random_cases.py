"""Random in-range cases of every terrain law for the wheel solver, shared by the property
tests (`test_properties.py`, from hypothesis's numbers) and `benchmarks/robustness.py`
(from NumPy's)."""

import jax.numpy as jnp
import numpy as np

import snowjax as sj

KINDS = ("wong", "bekker", "reece", "layered")
UNIT_ROWS = 13  # numbers in [0, 1] per case


def _between(u, lo, hi):
    return lo + u * (hi - lo)


def _log_between(u, lo, hi):
    return np.exp(np.log(lo) + u * (np.log(hi) - np.log(lo)))


def _zero_or_between(u, lo, hi):
    """0 for u < 0.2, else in [lo, hi] (a magnitude between 0 and the working precision's
    smallest accepted value, 1.1e-10 in float32, is invalid input by design)."""
    return np.where(u < 0.2, 0.0, _between(np.clip((u - 0.2) / 0.8, 0, 1), lo, hi))


def any_terrain_inputs(kind, unit, corner, dtype):
    """(wheel, terrain, WongReece, Lateral, load, slip, slip angle) of a batch, from
    `unit`, 13 rows of numbers in [0, 1] (one column per case), and `corner` (bool, one
    per case).

    D 0.5-1.5 m, b 0.1-0.6 m, c 0.1-5 kPa, tan phi 0.1-0.8, K 5-50 mm, load 0.1-20 kN,
    slip -0.5-0.99, slip angle -60-60 deg, K_y 5-50 mm, gamma 1-20 kN/m^3, c1 0.3-0.45,
    c2 0.2-0.4, c3 0 or -0.1 to -0.001; Bekker/Reece n 0.5-1.6, k_phi 50-2000 kN/m^(n+2),
    k_c 0 or 0.1-20 kN/m^(n+1) (Reece k'_c 0 or 0.1-30, k'_phi 100-2000, gamma_s
    10-20 kN/m^3); Wong p_w 5-200 kPa, z_w 5 cm-min(35 cm, 0.45 D); layered top p_w
    10-60 kPa, z_w 5-15 cm, bottom p_w 10-80 kPa, z_w up to 25 cm deeper, p_f 1-4 top p_w.
    A corner case rests on
    the base (load 1 MN) at the slip whose braking sign change of the shear displacement
    lies at the axle, `1 - theta_cap / sin(theta_cap)`, shifted by up to +-1e-6.
    """
    u = np.asarray(unit, dtype=np.float64)
    corner = np.asarray(corner, dtype=bool)
    d = _between(u[0], 0.5, 1.5)
    b = _between(u[1], 0.1, 0.6)
    c = _log_between(u[2], 100.0, 5e3)
    tan_phi = _between(u[3], 0.1, 0.8)
    k = _log_between(u[4], 0.005, 0.05)
    load = _log_between(u[5], 100.0, 20e3)
    slip = _between(u[6], -0.5, 0.99)
    beta = _between(u[7], -np.pi / 3, np.pi / 3)
    a, e, f = u[8], u[9], u[10]
    if kind == "wong":
        z_w = _between(e, 0.05, np.minimum(0.35, 0.45 * d))
        terrain = (_log_between(a, 5e3, 200e3), z_w, c, tan_phi, k)
        depth = z_w
    elif kind == "bekker":
        k_phi = _log_between(f, 50e3, 2e6)
        terrain = (_between(a, 0.5, 1.6), _zero_or_between(e, 100, 20e3), k_phi, c, tan_phi, k)
        depth = np.full_like(d, np.inf)
    elif kind == "reece":
        terrain = (_between(a, 0.5, 1.6), _zero_or_between(e, 0.1, 30), _log_between(f, 100, 2000),
                   _between(u[11], 10e3, 20e3), c, tan_phi, k)  # fmt: skip
        depth = np.full_like(d, np.inf)
    else:
        top_p = _between(a, 10e3, 60e3)
        top_z = _between(e, 0.05, 0.15)
        bottom_z = np.minimum(top_z + _between(f, 0.05, 0.25), 0.45 * d)
        top_z = np.minimum(top_z, bottom_z - 0.02)
        terrain = (top_p, top_z, _between(u[11], 10e3, 80e3), bottom_z,
                   top_p * _between(u[12], 1.0, 4.0), c, tan_phi, k)  # fmt: skip
        depth = bottom_z
    cos_cap = np.where(np.isfinite(depth), 1 - 2 * np.minimum(depth, d) / d, -1.0)
    cap = np.minimum(np.arccos(np.clip(cos_cap, -1, 1)), np.deg2rad(85.0))
    corner_slip = 1 - cap / np.sin(cap) + (2 * u[12] - 1) * 1e-6
    slip = np.where(corner, corner_slip, slip)
    load = np.where(corner, 1e6, load)
    cast = lambda x: jnp.asarray(x, dtype)  # noqa: E731
    t = [cast(x) for x in terrain]
    if kind == "wong":
        terrain = sj.WongSnow(*t)
    elif kind == "bekker":
        terrain = sj.BekkerSoil(*t[:5], shear_modulus=t[5])
    elif kind == "reece":
        terrain = sj.ReeceSoil(*t[:6], shear_modulus=t[6])
    else:
        top = sj.WongSnow(t[0], t[1], t[5], t[6], t[7])
        bottom = sj.WongSnow(t[2], t[3], t[5], t[6], t[7])
        terrain = sj.LayeredSnow(top, bottom, t[4])
    distribution = sj.WongReece(
        cast(_between(a, 0.3, 0.45)),
        cast(_between(e, 0.2, 0.4)),
        cast(_zero_or_between(f, -0.1, -1e-3)),
    )
    lateral = sj.Lateral(
        cast(_log_between(u[11], 0.005, 0.05)), cast(_log_between(u[12], 1e3, 2e4))
    )
    wheel = sj.RigidWheel(cast(d), cast(b))
    return wheel, terrain, distribution, lateral, cast(load), cast(slip), cast(beta)


STIFF = 1e9  # [Pa]: a tyre 10^4 times stiffer than any terrain here (within float32's window)


def tire_and_rut_inputs(kind, unit, extra, corner, dtype):
    """(rim, tyres, terrain, WongReece, load, slip, ruts) of a batch: `any_terrain_inputs`
    (`unit`, `corner`) and `extra`, 3 rows of numbers in [0, 1].

    The first half of the tyres soft (p_i 10 kPa-1 MPa, p_c 0 or 1-20 kPa, flexing f_h 0
    or 0.001-0.03, section height 0.2 D), the second half `STIFF`; the ruts (`Rut` of the
    terrain, k_0 1 MPa/m, A_u 5 MPa/m^2, left by the same wheel) a third each of zero
    depth, of a share of the base's depth (0.3 m where there is none) and at the base
    itself (a leader that bottomed out).
    """
    wheel, terrain, distribution, _, load, slip, _ = any_terrain_inputs(kind, unit, corner, dtype)
    u = np.asarray(extra, dtype=np.float64)
    n = u.shape[1]
    stiff = np.arange(n) >= n // 2
    cast = lambda x: jnp.asarray(x, dtype)  # noqa: E731
    tires = sj.DeflectingTire(
        wheel.diameter,
        wheel.width,
        0.2 * wheel.diameter,
        cast(np.where(stiff, STIFF, _log_between(u[0], 1e4, 1e6))),
        cast(np.where(stiff, 0.0, _zero_or_between(u[1], 1e3, 2e4))),
        30.0,
        cast(np.where(stiff, 0.0, _zero_or_between(u[1], 1e-3, 0.03))),
    )
    depth = np.asarray(terrain.depth, dtype=np.float64)
    base = np.where(np.isfinite(depth), depth, 0.3)
    third = np.arange(n) % 3
    share = np.select([third == 0, third == 1], [0.0, _between(u[2], 0.01, 1.0)], 1.0)
    ruts = sj.Rut(terrain, cast(share * base), wheel.width, cast(1e6), cast(5e6))
    return wheel, tires, terrain, distribution, load, slip, ruts
