"""Calibration, sweeps and the vehicle simulation on every terrain.

Bekker's snow (Wong's Snow (U.S.) set) under the thesis tyre with the Wong–Reece stress
distribution.  Every `solve_wheel` call here uses leaves broadcast to 12 elements, so the
synthetic data, the sweep (one chunk of 12 rows) and the reference solves share one
compiled program; the two wheel fits share another.
"""

from __future__ import annotations

import math

import diffrax
import equinox as eqx
import numpy as np
import pytest
import scipy.integrate
import scipy.optimize

import snowjax as sj
from snowjax._cli.app import main
from snowjax._fit import wheel as _fit
from snowjax._sweep import sweep as _sweep

WHEEL = sj.RigidWheel.thesis_tire()  # D 0.736 m, b 0.235 m
BEKKER = sj.BekkerSoil.snow_us()  # n 1.6, k_c 4.37 kN/m^2.6, k_phi 196.72 kN/m^3.6
DIST = sj.WongReece(c1=0.43, c2=0.32)
N = 12
LOADS = np.repeat([250.0, 440.0, 625.0], 4)  # [N]
SLIPS = np.tile([0.05, 0.2, 0.4, 0.6], 3)
FITTED = ("k_phi", "n", "c1")


def _full(tree, n=N):
    """Every leaf broadcast to n elements (one compiled solve for the whole module)."""
    import jax

    return jax.tree_util.tree_map(lambda x: np.full(n, float(x)), tree)


def _solve(terrain, load, slip, distribution=DIST, wheel=WHEEL, shear="classic"):
    return sj.solve_wheel(
        _full(wheel),
        sj.ContactModel(
            _full(terrain),
            distribution=None if distribution is None else _full(distribution),
            shear=shear,
        ),
        np.broadcast_to(load, (N,)),
        np.broadcast_to(slip, (N,)),
    )


@pytest.fixture(scope="module")
def synthetic():
    st = _solve(BEKKER, LOADS, SLIPS)
    assert (np.asarray(st.status) == sj.Status.CONVERGED).all()
    return {"sinkage": np.asarray(st.sinkage), "drawbar_pull": np.asarray(st.drawbar_pull)}


def _start():
    soil = eqx.tree_at(lambda t: (t.k_phi, t.n), BEKKER, (1.3 * BEKKER.k_phi, 0.9 * BEKKER.n))
    return soil, sj.WongReece(c1=0.35, c2=DIST.c2)


def _true(name):
    return float(DIST.c1) if name == "c1" else float(getattr(BEKKER, name))


# ---------------------------------------------------------------------------------------
# fit_wheel on any terrain and distribution
# ---------------------------------------------------------------------------------------


def test_fit_names_and_transforms():
    assert _fit.fit_parameter_names(BEKKER, DIST) == (
        "n",
        "k_c",
        "k_phi",
        "cohesion",
        "tan_phi",
        "shear_modulus",
        "c1",
        "c2",
        "c3",
    )
    layered = sj.LayeredSnow.ice_layer_example()
    assert _fit.fit_parameter_names(layered)[:2] == ("top.p_w", "top.z_w")
    assert _fit.fit_parameter_names(layered)[-1] == "ice_failure_pressure"
    names, targets = _fit._resolve_fit_names(("distribution.c1", "terrain.k_c"), BEKKER, DIST)
    assert names == ("c1", "k_c") and targets == (("distribution", "c1"), ("terrain", "k_c"))
    soil, dist = _start()
    base = dict(
        wheel=WHEEL, snow=sj.ContactModel(soil, dist), load=LOADS, slip=SLIPS,
        measured={"sinkage": np.ones(N)},
    )  # fmt: skip
    with pytest.raises(ValueError, match=r"unknown parameter.*'p_w'.*allowed:.*'k_phi'.*'c1'"):
        sj.fit_wheel(**base, fit=("p_w",))
    with pytest.raises(ValueError, match="twice"):
        sj.fit_wheel(**base, fit=("c1", "distribution.c1"))
    with pytest.raises(ValueError, match="simplified"):
        sj.fit_wheel(**{**base, "snow": sj.ContactModel(soil, shear="simplified")}, fit=("n",))
    with pytest.raises(ValueError, match=r"snow.n must be finite and > 0"):
        bad = sj.ContactModel(eqx.tree_at(lambda t: t.n, soil, 0.0), dist)
        sj.fit_wheel(**{**base, "snow": bad}, fit=("n",))
    with pytest.raises(ValueError, match=r"c1 \+ c2 \* slip must be finite and in \[0, 1\)"):
        bad = sj.ContactModel(soil, sj.WongReece(0.9, 0.32))
        sj.fit_wheel(**{**base, "snow": bad}, fit=("n",))


@pytest.mark.slow  # a fit on the any-terrain rule (make test-slow)
def test_fit_wheel_recovers_bekker_and_wong_reece_noise_free(synthetic):
    soil, dist = _start()
    res = sj.fit_wheel(WHEEL, sj.ContactModel(soil, dist), LOADS, SLIPS, synthetic, fit=FITTED)
    assert res.success and list(res.params) == list(FITTED)
    for name in FITTED:
        assert res.params[name] == pytest.approx(_true(name), rel=1e-6), name
    assert res.info["transforms"] == {"k_phi": "linear", "n": "log", "c1": "linear"}
    assert res.units == {"k_phi": "N/m^(n+2)", "n": "-", "c1": "-"}
    fitted, fitted_dist = res.info["terrain"], res.info["distribution"]
    assert isinstance(fitted, sj.BekkerSoil) and isinstance(fitted_dist, sj.WongReece)
    assert float(fitted.k_phi) == res.params["k_phi"] and float(fitted_dist.c1) == res.params["c1"]
    assert float(fitted.k_c) == float(BEKKER.k_c) and float(fitted_dist.c2) == float(DIST.c2)
    assert res.sse < 1e-16 and (res.info["status"] == 0).all()


@pytest.mark.slow  # a fit on the any-terrain rule (make test-slow)
def test_fit_wheel_recovers_bekker_and_wong_reece_with_noise(synthetic):
    """1 % Gaussian noise (of each quantity's RMS), seed 0: within 5 % and 4 sigma."""
    rng = np.random.default_rng(0)
    data = {q: y + 0.01 * np.sqrt(np.mean(y**2)) * rng.standard_normal(N)
            for q, y in synthetic.items()}  # fmt: skip
    soil, dist = _start()
    res = sj.fit_wheel(WHEEL, sj.ContactModel(soil, dist), LOADS, SLIPS, data, fit=FITTED)
    assert res.success and res.dof == 2 * N - 3
    for name in FITTED:
        got, se, true = res.params[name], res.stderr[name], _true(name)
        assert abs(got / true - 1) < 0.05, (name, got, true)
        assert 0 < se < 0.05 * abs(true) and abs(got - true) < 4 * se, (name, got, true, se)


# ---------------------------------------------------------------------------------------
# Plate test -> BekkerSoil -> wheel
# ---------------------------------------------------------------------------------------


def test_two_plate_sizes_give_the_bekker_soil_of_the_wheel():
    z = np.tile(np.linspace(0.01, 0.15, 8), 2)
    b = np.repeat([0.1, 0.3], 8)
    p = (BEKKER.k_c / b + BEKKER.k_phi) * z**BEKKER.n
    res = sj.fit_plate_sinkage(z, np.asarray(p), "bekker", b)
    soil = res.bekker_soil(float(BEKKER.cohesion), float(BEKKER.tan_phi),
                           shear_modulus=float(BEKKER.shear_modulus))  # fmt: skip
    assert isinstance(soil, sj.BekkerSoil)
    for name in ("n", "k_c", "k_phi", "cohesion", "tan_phi", "shear_modulus"):
        assert float(getattr(soil, name)) == pytest.approx(float(getattr(BEKKER, name)), rel=1e-8)
    got, want = _solve(soil, LOADS, SLIPS), _solve(BEKKER, LOADS, SLIPS)
    np.testing.assert_allclose(got.sinkage, want.sinkage, rtol=1e-7)
    np.testing.assert_allclose(got.drawbar_pull, want.drawbar_pull, rtol=1e-6, atol=1e-6)
    with pytest.raises(ValueError, match="law='bekker'"):
        sj.fit_plate_sinkage(z[:8], p[:8], "wong").bekker_soil(1e3, 0.3)


def _plate_law_sinkage(k_eq, n, load, diameter, width):
    """No-shear wheel on the plate law sigma = k_eq z^n: W(theta0) = load by quad + brentq."""
    r = diameter / 2

    def w(theta0):
        f = lambda t: k_eq * (r * (math.cos(t) - math.cos(theta0))) ** n * math.cos(t)  # noqa: E731
        integral = scipy.integrate.quad(f, 0.0, theta0, epsabs=0, epsrel=1e-10, limit=200)[0]
        return r * width * integral

    theta0 = scipy.optimize.brentq(lambda t: w(t) - load, 1e-4, 1.4, xtol=1e-15)
    return r * (1 - math.cos(theta0))


# quad warns while brentq probes entry angles far from the root; the root is unaffected.
@pytest.mark.filterwarnings("ignore::scipy.integrate.IntegrationWarning")
def test_one_plate_size_bekker_soil_reproduces_the_plate_law_on_a_plate_width_wheel():
    """Thesis Table 2.1 (one 0.23 m plate): k_eq and n only.  On a wheel as wide as the
    plate both assumed splits give the plate law's sinkage; on another width they differ."""
    d = sj.thesis_plate_test()
    res = sj.fit_plate_sinkage(d["sinkage"], d["pressure"], "bekker", d["plate_size"])
    assert set(res.params) == {"k_eq", "n"}
    frictional = res.bekker_soil(1.03e3, 0.36)
    cohesive = res.bekker_soil(1.03e3, 0.36, assume="cohesive")
    assert float(frictional.k_c) == 0 and float(frictional.k_phi) == res.params["k_eq"]
    assert float(cohesive.k_phi) == 0
    assert float(cohesive.k_c) == pytest.approx(0.23 * res.params["k_eq"], rel=1e-15)
    plate_wheel = sj.RigidWheel(WHEEL.diameter, 0.23)
    loads = np.linspace(500.0, 3000.0, N)
    st_f = _solve(frictional, loads, 0.0, None, plate_wheel, "none")
    st_c = _solve(cohesive, loads, 0.0, None, plate_wheel, "none")
    assert (np.asarray(st_f.status) == 0).all()
    np.testing.assert_allclose(st_c.sinkage, st_f.sinkage, rtol=1e-12)
    for k in (0, 6, 11):
        want = _plate_law_sinkage(res.params["k_eq"], res.params["n"], loads[k], 0.736, 0.23)
        assert float(st_f.sinkage[k]) == pytest.approx(want, rel=1e-7)
    # A wider wheel: the cohesive split (k_eq b_p / b) is softer, so it sinks deeper.
    wide = sj.RigidWheel(WHEEL.diameter, 0.46)
    st_fw = _solve(frictional, loads, 0.0, None, wide, "none")
    st_cw = _solve(cohesive, loads, 0.0, None, wide, "none")
    assert (np.asarray(st_cw.sinkage) > 1.1 * np.asarray(st_fw.sinkage)).all()
    with pytest.raises(ValueError, match="assume"):
        res.bekker_soil(1e3, 0.3, assume="both")


# ---------------------------------------------------------------------------------------
# Sweeps
# ---------------------------------------------------------------------------------------

K_PHI = np.array([150e3, 196.72e3])
C1 = np.array([0.40, 0.43])
SWEEP_LOADS = np.array([250.0, 500.0])
SWEEP_SLIPS = np.array([0.1, 0.4, 0.7])


@pytest.fixture(scope="module")
def bekker_sweep(tmp_path_factory):
    out = tmp_path_factory.mktemp("bekker") / "sweep"
    soil = eqx.tree_at(lambda t: t.k_phi, BEKKER, K_PHI)
    dist = sj.WongReece(c1=C1, c2=DIST.c2, c3=DIST.c3)
    r = sj.sweep(
        WHEEL,
        sj.ContactModel(soil, dist),
        SWEEP_LOADS,
        SWEEP_SLIPS,
        out=out,
        progress=False,
        run=sj.SweepRun(chunk_size=N),
    )
    assert r.complete and r.n_points == N and r.computed_chunks == 1
    return out, soil, dist


def test_sweep_bekker_wong_reece_equals_solve_wheel(bekker_sweep):
    out, soil, dist = bekker_sweep
    rows = sj.load_sweep(out)
    assert list(rows) == ["index", "param_set", "load", "slip", "k_phi", "c1", "entry_angle",
                          "sinkage", "motion_resistance", "thrust", "drawbar_pull", "torque",
                          "status"]  # fmt: skip
    p = np.repeat([0, 1], 6)
    np.testing.assert_array_equal(rows["k_phi"], K_PHI[p])
    np.testing.assert_array_equal(rows["c1"], C1[p])
    st = sj.solve_wheel(
        _full(WHEEL),
        sj.ContactModel(
            eqx.tree_at(lambda t: t.k_phi, _full(BEKKER), K_PHI[p]),
            sj.WongReece(C1[p], _full(DIST).c2, _full(DIST).c3),
        ),
        rows["load"],
        rows["slip"],
    )
    assert (rows["status"] == 0).all()
    for name in (
        "entry_angle",
        "sinkage",
        "motion_resistance",
        "thrust",
        "drawbar_pull",
        "torque",
        "status",
    ):
        np.testing.assert_array_equal(rows[name], np.asarray(getattr(st, name)), err_msg=name)
    # A different terrain or distribution in the same directory is refused.
    with pytest.raises(ValueError, match="terrain: 'BekkerSoil' on disk, 'WongSnow' now"):
        sj.sweep(
            WHEEL,
            sj.WongSnow.thesis_fresh_snow(),
            SWEEP_LOADS,
            SWEEP_SLIPS,
            out=out,
            progress=False,
            run=sj.SweepRun(chunk_size=N),
        )
    with pytest.raises(ValueError, match="distribution: 'WongReece' on disk, None now"):
        sj.sweep(
            WHEEL,
            soil,
            SWEEP_LOADS,
            SWEEP_SLIPS,
            out=out,
            progress=False,
            run=sj.SweepRun(chunk_size=N),
        )
    with pytest.raises(ValueError, match=r"c1 \+ c2 \* slip must be finite and in \[0, 1\)"):
        sj.sweep(
            WHEEL,
            sj.ContactModel(soil, sj.WongReece(0.8, 0.32)),
            SWEEP_LOADS,
            SWEEP_SLIPS,
            out=out,
            run=sj.SweepRun(chunk_size=N),
        )
    layered = sj.LayeredSnow.ice_layer_example()
    model = sj.ContactModel(layered)
    d = _sweep._define(
        WHEEL, model, SWEEP_LOADS, SWEEP_SLIPS, grid=True, chunk_size=N, max_steps=64
    )
    assert "top.p_w" in d.parameters and "ice_failure_pressure" in d.parameters


def test_cli_sweep_bekker_writes_the_same_csv(bekker_sweep, tmp_path, capsys):
    out = tmp_path / "cli"
    argv = ["sweep", "--terrain", "bekker", "--preset", "snow-us", "--k-phi", "150e3,196.72e3",
            "--distribution", "wong-reece", "--c1", "0.40,0.43", "--loads", "250,500",
            "--slips", "0.1,0.4,0.7", "--chunk-size", "12", "--out", str(out),
            "--no-progress", "--format", "csv"]  # fmt: skip
    assert main(argv) == 0
    assert "12 points in 1 chunk(s) of 12 (1 computed" in capsys.readouterr().out
    assert (out / "sweep.csv").read_bytes() == (bekker_sweep[0] / "sweep.csv").read_bytes()
    for bad, message in [
        (["--p-w", "80e3"], "--p-w is not a parameter of --terrain bekker"),
        (["--preset", "thesis"], "not a preset of --terrain bekker"),
        (["--distribution", "none"], "--c1 only apply with --distribution wong-reece"),
        (["--terrain", "reece", "--preset", "none"], "not a preset of --terrain reece"),
        (
            argv[:3] + argv[5:] + ["--terrain", "reece", "--n", "1.1"],
            "--terrain reece has no preset: give --k-c-prime, --k-phi-prime, --unit-weight",
        ),
    ]:
        assert main(bad if bad[0] == "sweep" else argv + bad) == 2, bad
        err = capsys.readouterr().err
        assert err.startswith("snowjax sweep: error:") and message in err, err


# ---------------------------------------------------------------------------------------
# Vehicle simulation
# ---------------------------------------------------------------------------------------

LOAD = 440.0  # [N] per wheel


def test_wheel_forces_on_bekker_soil():
    r = float(WHEEL.diameter) / 2
    v = np.array([0.0, 1.0, 2.0, 1.0, 0.01, -1.0])
    w = np.array([0.0, 1.3, 2.0, 0.8, 0.03, -1.3]) / r
    f = sj.wheel_forces(v, w, LOAD, WHEEL, BEKKER)
    for name in ("longitudinal_force", "resisting_torque", "sinkage", "entry_angle", "slip"):
        assert np.all(np.isfinite(np.asarray(getattr(f, name)))), name
    assert (np.asarray(f.status) == sj.Status.CONVERGED).all()
    assert float(f.longitudinal_force[0]) == 0.0 and float(f.resisting_torque[0]) == 0.0
    st = sj.solve_wheel(WHEEL, BEKKER, LOAD, f.slip[1:4])
    np.testing.assert_allclose(f.longitudinal_force[1:4], st.drawbar_pull, rtol=1e-9)
    np.testing.assert_allclose(f.sinkage[1:4], st.sinkage, rtol=1e-9)
    # Mirror image: backwards travel flips the forces.
    np.testing.assert_allclose(f.longitudinal_force[5], -f.longitudinal_force[1], rtol=1e-12)


@pytest.mark.slow  # a simulation on the any-terrain rule (make test-slow)
def test_simulation_on_bekker_wong_reece_reaches_the_self_propelled_state():
    """Constant torque M_w(i*), i* the slip of zero drawbar pull (brentq on solve_wheel):
    the vehicle settles at i* with zero drawbar pull."""
    dp = lambda i: float(_solve(BEKKER, LOAD, i).drawbar_pull[0])  # noqa: E731
    slip_star = scipy.optimize.brentq(dp, 0.05, 0.6, xtol=1e-13)
    torque = float(_solve(BEKKER, LOAD, slip_star).torque[0])
    vehicle = sj.Vehicle(mass=2 * LOAD / 9.80665, wheel_inertia=0.5, wheel=WHEEL, num_wheels=2)
    traj = sj.simulate_longitudinal(
        vehicle,
        sj.ContactModel(BEKKER, DIST),
        torque,
        10.0,
        0.05,
        initial=sj.InitialState(speed=1.0),
        stepping=sj.Stepping(adjoint=diffrax.ForwardMode()),
    )
    assert traj.result == diffrax.RESULTS.successful
    for name in ("speed", "wheel_speed", "slip", "sinkage", "drawbar_pull", "resisting_torque"):
        assert np.all(np.isfinite(np.asarray(getattr(traj, name)))), name
    assert (np.asarray(traj.status) == sj.Status.CONVERGED).all()
    late = slice(-10, None)
    scale = float(_solve(BEKKER, LOAD, 0.0).motion_resistance[0])
    assert np.max(np.abs(np.asarray(traj.drawbar_pull[late]))) < 1e-6 * scale
    assert np.ptp(np.asarray(traj.slip[late])) < 1e-9
    np.testing.assert_allclose(traj.slip[-1], slip_star, atol=1e-8)
    st = _solve(BEKKER, LOAD, float(traj.slip[-1, 0]))
    assert abs(float(st.drawbar_pull[0])) < 1e-6 * scale
    np.testing.assert_allclose(float(st.torque[0]), torque, rtol=1e-8)


def test_cli_fit_wheel_on_bekker_wong_reece(synthetic, tmp_path, capsys):
    """`snowjax fit wheel --terrain bekker --distribution wong-reece` (the fit above)."""
    import json

    path = tmp_path / "wheel.csv"
    rows = zip(LOADS, SLIPS, synthetic["sinkage"], synthetic["drawbar_pull"])
    path.write_text(
        "load_N,slip,sinkage_m,drawbar_pull_N\n"
        + "".join(",".join(repr(float(x)) for x in r) + "\n" for r in rows)
    )
    soil, dist = _start()
    argv = [
        "fit",
        "wheel",
        "--data",
        str(path),
        "--terrain",
        "bekker",
        "--k-phi",
        repr(float(soil.k_phi)),
        "--n",
        repr(float(soil.n)),
        "--distribution",
        "wong-reece",
        "--c1",
        repr(float(dist.c1)),
        "--fit",
        "k_phi,n,c1",
        "--json",
    ]
    assert main(argv) == 0
    out = json.loads(capsys.readouterr().out)
    for name in FITTED:
        assert out["params"][name] == pytest.approx(_true(name), rel=1e-6), name
    assert main(argv[:-3] + ["--json"]) == 2  # no --fit: required for other terrains
    assert "give --fit" in capsys.readouterr().err
