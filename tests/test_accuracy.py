"""The simulator accuracy setting, `ContactModel(accuracy="simulator")`: checked, fewer
nodes, close to the reference accuracy, and carried by every function that rebuilds a
model (`sweep`, `fit_wheel`).  Its error against SciPy over random cases of every law is
measured by `benchmarks/accuracy.py` (the performance guide's table)."""

import re

import numpy as np
import pytest

import snowjax as sj
from snowjax._sweep import sweep as _sweep
from snowjax._wheel.front_rim import _ANY_TERRAIN_RULE, _FRONT_RIM_RULE
from snowjax._wheel.shear_law import JanosiHanamoto, NoShear, ThesisSimplified

WHEEL = sj.RigidWheel.thesis_tire()
SNOW = sj.WongSnow.thesis_fresh_snow()
LOADS = np.array([1500.0, 4000.0, 8000.0, 4000.0])
SLIPS = np.array([0.1, 0.5, 0.9, -0.3])
FIELDS = ("sinkage", "motion_resistance", "thrust", "torque", "lateral_force", "aligning_torque")


@pytest.mark.parametrize(
    ("value", "error", "message"),
    [("fast", ValueError, "accuracy must be one of ('reference', 'simulator'), got 'fast'"),
     (1e-4, TypeError, "accuracy must be one of ('reference', 'simulator'), got 0.0001")],
)  # fmt: skip
def test_the_accuracy_is_checked(value, error, message):
    with pytest.raises(error, match=re.escape(message)):
        sj.ContactModel(SNOW, accuracy=value)


def test_the_simulator_takes_the_laws_simulator_nodes():
    law = JanosiHanamoto()
    assert _FRONT_RIM_RULE.nodes(law, None, "simulator") == (6, (6, 6, 6, 6))
    assert _ANY_TERRAIN_RULE.nodes(law, None, "simulator") == (8, 8)
    assert _FRONT_RIM_RULE.nodes(ThesisSimplified(), None, "simulator") == (8, (8, 8, 8, 8))
    assert _ANY_TERRAIN_RULE.nodes(NoShear(), None, "simulator") == (8, 8)
    # The reference: the laws' tables; nodes_per_panel, where given, wins.
    assert _FRONT_RIM_RULE.nodes(law, None, "reference") == law.nodes_closed_form
    assert _ANY_TERRAIN_RULE.nodes(law, None, "reference") == law.nodes_any_terrain
    assert _ANY_TERRAIN_RULE.nodes(law, 5, "simulator") == (5, 5)
    with pytest.raises(ValueError, match="ThesisSimplified has no any-terrain rule"):
        _ANY_TERRAIN_RULE.nodes(ThesisSimplified(), None, "simulator")


CASES = {
    # name: (wheel, terrain, distribution, slip angle [rad] or None)
    "Wong front region (closed forms)": (WHEEL, SNOW, None, None),
    "Wong + Wong-Reece, slip angle": (WHEEL, SNOW, sj.WongReece(0.43, 0.32), 0.2),
    "Bekker + Wong-Reece, slip angle": (
        WHEEL, sj.BekkerSoil.snow_us(), sj.WongReece(0.43, 0.32), -0.3,
    ),
    "layered": (WHEEL, sj.LayeredSnow.ice_layer_example(), None, None),
    "tyre on Wong": (sj.DeflectingTire(0.736, 0.235, 0.176, 100e3), SNOW, None, 0.1),
}  # fmt: skip


@pytest.mark.parametrize("name", CASES)
def test_the_simulator_is_within_1e_4_of_the_reference(name):
    """Every output within 1e-4 of the load (moments: of load x r, the sinkage of itself)
    of the reference accuracy (itself within 1e-7 of SciPy), and not equal to it: the
    setting takes effect."""
    wheel, terrain, dist, angle = CASES[name]
    loads = LOADS / 18 if isinstance(terrain, sj.BekkerSoil) else LOADS
    out = {}
    for accuracy in ("reference", "simulator"):
        model = sj.ContactModel(terrain, dist, accuracy=accuracy)
        st = sj.solve_wheel(wheel, model, loads, SLIPS, slip_angle=angle)
        assert np.all(np.asarray(st.status) <= sj.Status.BOTTOMED_OUT), st.status
        out[accuracy] = {f: np.asarray(getattr(st, f)) for f in FIELDS}
    ref, sim = out["reference"], out["simulator"]
    moment = loads * float(wheel.diameter) / 2
    scales = (np.abs(ref["sinkage"]), loads, loads, moment, loads, moment)
    errors = {f: np.max(np.abs(sim[f] - ref[f]) / s) for f, s in zip(FIELDS, scales)}
    assert max(errors.values()) <= 1e-4, errors
    assert errors["sinkage"] > 0 and errors["torque"] > 0, errors


@pytest.mark.parametrize("angle", [None, 0.1])
def test_the_simulators_loose_tolerance_leaves_its_roots_within_1e_7(angle):
    """The simulator accuracy also solves to 1e-6 (`equilibrium._tolerance`): a warm start
    within a simulation step's reach (3e-5 off the root, |ln(W / F_z)| ~ 1e-4) then
    ends after one Newton step (`bracketed._finished`) where the reference tolerance
    takes two.  Against the reference tolerance at the same nodes (`nodes_per_panel=6`,
    the simulator's on Wong snow's closed-form rules): every element CONVERGED, cold
    solves the same, warm ones different (the setting takes effect: measured 1e-9 in
    the entry angle, 5e-10 of the load in the forces) and within 1e-7 (the
    quadrature's own error is up to ~3e-4)."""
    loads, slips = np.linspace(1e3, 9e3, 9), np.linspace(0.0, 0.9, 9)
    solves = {}
    for name, model in (
        ("tight", sj.ContactModel(SNOW, nodes_per_panel=6)),
        ("loose", sj.ContactModel(SNOW, accuracy="simulator")),
    ):
        cold = sj.solve_wheel(WHEEL, model, loads, slips, slip_angle=angle)
        guess = np.asarray(cold.entry_angle) * (1 + 3e-5)
        warm = sj.solve_wheel(
            WHEEL, model, loads, slips, slip_angle=angle, initial_entry_angle=guess
        )
        solves[name] = (cold, warm)
    for kind, tight, loose in zip(("cold", "warm"), solves["tight"], solves["loose"]):
        assert np.all(np.asarray(loose.status) == sj.Status.CONVERGED), loose.status
        theta = np.abs(np.asarray(loose.entry_angle) / np.asarray(tight.entry_angle) - 1)
        assert (np.max(theta) > 0) == (kind == "warm"), (kind, theta)
        assert np.max(theta) <= 1e-7
        for field in ("thrust", "torque", "lateral_force"):
            diff = np.asarray(getattr(loose, field)) - np.asarray(getattr(tight, field))
            assert np.max(np.abs(diff) / loads) <= 1e-7, field


def test_contact_forces_take_the_simulator_nodes():
    forces = {
        a: sj.contact_forces(WHEEL, sj.ContactModel(SNOW, accuracy=a), 0.4, SLIPS)
        for a in ("reference", "simulator")
    }
    diff = np.abs(np.asarray(forces["simulator"].torque - forces["reference"].torque))
    assert 0 < np.max(diff) <= 1e-4 * np.max(np.abs(np.asarray(forces["reference"].torque)))


def test_a_sweep_keeps_the_accuracy_and_its_hash_tells_them_apart(tmp_path):
    def define(accuracy):
        model = sj.ContactModel(SNOW, accuracy=accuracy)
        return _sweep._define(WHEEL, model, LOADS, SLIPS[:2], grid=True, chunk_size=4, max_steps=64)

    reference, simulator = define("reference"), define("simulator")
    assert "accuracy" not in reference.summary()  # the reference sweeps keep their hash
    assert simulator.summary()["accuracy"] == "simulator"
    assert simulator.digest() != reference.digest()
    model = sj.ContactModel(SNOW, accuracy="simulator")
    # A braked slip: the sweep's traced slips and this eager solve take the same layout.
    result = sj.sweep(WHEEL, model, LOADS, SLIPS[2:], out=tmp_path / "s", progress=False)
    rows = sj.load_sweep(tmp_path / "s")
    st = sj.solve_wheel(WHEEL, model, LOADS[:, None], SLIPS[None, 2:])
    assert result.complete
    # Within rounding (the batches differ in shape); the reference accuracy is 1e-7 away.
    np.testing.assert_allclose(rows["sinkage"], np.asarray(st.sinkage).reshape(-1), rtol=1e-13)


def test_fit_wheel_solves_and_returns_the_models_accuracy():
    """Data made at the simulator accuracy are fitted exactly by a fit at that accuracy
    (measured: p_w within 1e-13; a fit at the reference accuracy is 1.8e-8 off).  A
    braked point puts the data and the fit (whose slips are traced) on the same layout."""
    model = sj.ContactModel(SNOW, accuracy="simulator")
    loads, slips = np.repeat([3000.0, 6000.0], 3), np.tile([-0.2, 0.3, 0.8], 2)
    st = sj.solve_wheel(WHEEL, model, loads, slips)
    start = sj.WongSnow(0.9 * SNOW.p_w, SNOW.z_w, SNOW.cohesion, SNOW.tan_phi, SNOW.shear_modulus)
    res = sj.fit_wheel(
        WHEEL,
        sj.ContactModel(start, accuracy="simulator"),
        loads,
        slips,
        {"sinkage": np.asarray(st.sinkage)},
        fit=("p_w",),
    )
    assert res.info["model"].accuracy == "simulator"
    assert res.params["p_w"] == pytest.approx(float(SNOW.p_w), rel=1e-11)
