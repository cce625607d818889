"""Tests of `snowjax validate` (snowjax/_validate/, snowjax/_cli/validate.py).

One run of the CLI on the shipped data (module fixture); the checks recompute the
reported numbers independently from the CSVs it writes.
"""

import csv
import math

import numpy as np
import pytest

import snowjax as sj
from snowjax._cli.app import main
from snowjax._validate.validate import _loo_from_grid


def test_shipped_data_as_printed():
    t = sj.shoop_2001_table11(include_uncertain=True)
    assert len(t["row"]) == 28 and int(t["certain"].sum()) == 26
    # the first rows of Table 11 as printed, in its order
    first = np.column_stack(
        [t["snow_depth_m"], t["sinkage_m"], t["resistance_coefficient"], t["density_kg_m3"]]
    )
    np.testing.assert_array_equal(first[0], [0.13, 0.10, 0.05, 160])
    np.testing.assert_array_equal(first[11], [0.21, 0.17, 0.12, 220])
    np.testing.assert_array_equal(first[26], [0.14, 0.10, 0.02, 110])
    assert np.all(t["sinkage_m"] < t["snow_depth_m"])
    assert len(sj.shoop_2001_table11()["row"]) == 26
    ex = sj.crrel_95_1_examples()
    np.testing.assert_array_equal(ex["rut_depth_m"], [0.09, 0.09, 0.0, 0.0, 0.072])
    np.testing.assert_allclose(
        ex["gross_traction_n"] - ex["resistance_n"], ex["drawbar_n"], atol=0.11
    )


def test_leave_one_out_never_uses_the_held_out_row():
    # two parameter values; row 0 alone prefers column 1, the others column 0
    measured = np.array([10.0, 0.0, 0.0, 0.0])
    pred = np.array([[0.0, 10.0], [0.0, 1.0], [0.0, 1.0], [0.0, 1.0]])
    out, chosen = _loo_from_grid(pred, measured)
    assert chosen[0] == 0 and out[0] == 0.0  # chosen without row 0: a bad prediction of it
    # a column with a missing training prediction is never chosen
    pred_nan = pred.copy()
    pred_nan[1, 0] = np.nan
    _, chosen = _loo_from_grid(pred_nan, measured)
    assert chosen[0] == 1 and chosen[2] == 1


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    out = tmp_path_factory.mktemp("validate")
    assert main(["validate", "--out", str(out)]) == 0
    return out


def _read(path):
    with open(path, newline="", encoding="utf-8") as f:
        return list(csv.DictReader(f))


def test_cli_writes_the_report(run):
    for name in (
        "report.md",
        "metrics.csv",
        "predictions.csv",
        "crrel_95_1_examples.csv",
        "predicted_vs_measured.png",
    ):
        assert (run / name).stat().st_size > 0, name
    report = (run / "report.md").read_text(encoding="utf-8")
    assert "| model | calibrated |" in report and "predicted_vs_measured.png" in report
    assert "skipped" not in report  # every model ran (including the Bekker wheel)


def test_reported_metrics_match_the_predictions(run):
    preds = _read(run / "predictions.csv")
    metrics = _read(run / "metrics.csv")
    assert len(preds) == 26
    meas = {
        "sinkage": np.array([float(r["sinkage_measured_m"]) for r in preds]),
        "coefficient": np.array([float(r["coefficient_measured"]) for r in preds]),
    }
    keys = {m["model"] for m in metrics}
    assert {
        "baseline",
        "crrel",
        "crrel_fit",
        "richmond_measured_rut",
        "wheel_wong",
        "tire_wong",
        "wheel_wong_pit",
        "tire_wong_pit",
        "wheel_bekker",
        "bekker",
        "van_es",
    } <= keys
    for m in metrics:
        p = np.array([float(r[f"{m['quantity']}_{m['model']}"] or "nan") for r in preds])
        err = p - meas[m["quantity"]]
        err = err[np.isfinite(err)]
        assert int(m["n"]) == err.size
        assert float(m["rms"]) == pytest.approx(math.sqrt(np.mean(err**2)), rel=1e-5)
        assert float(m["worst"]) == pytest.approx(np.max(np.abs(err)), rel=1e-5)


# The deflecting tyre's held-out numbers as measured (2026-11-26, README "How well does it
# predict?"): a change that makes any of them worse by more than 10 % fails.
TIRE_NUMBERS = {
    ("tire_wong", "sinkage", "rms"): 0.00663,
    ("tire_wong", "coefficient", "rms"): 0.1345,
    ("tire_wong_pit", "sinkage", "rms"): 0.00663,
    ("tire_wong_pit", "coefficient", "rms"): 0.0165,
    ("tire_wong_pit", "coefficient", "bias"): 0.0064,
}


def test_tire_held_out_numbers_do_not_grow(run):
    metrics = {(m["model"], m["quantity"]): m for m in _read(run / "metrics.csv")}
    for (model, quantity, stat), value in TIRE_NUMBERS.items():
        got = abs(float(metrics[(model, quantity)][stat]))
        assert got <= 1.1 * value, (model, quantity, stat, got)
    # The targets: sinkage RMS <= 10 mm, R/W RMS <= 0.025, |R/W bias| <= 0.01.
    assert float(metrics[("tire_wong_pit", "sinkage")]["rms"]) <= 0.010
    assert float(metrics[("tire_wong_pit", "coefficient")]["rms"]) <= 0.025
    assert abs(float(metrics[("tire_wong_pit", "coefficient")]["bias"])) <= 0.01


def test_uncalibrated_crrel_predictions_are_the_formula(run):
    preds = _read(run / "predictions.csv")
    for r in preds:
        h, rho = float(r["snow_depth_m"]), float(r["density_kg_m3"])
        z = h * (1 - rho / 500.0)
        assert float(r["sinkage_crrel"]) == pytest.approx(z, rel=1e-6)
        a = 0.38 * math.acos(1 - z / 0.38)
        mu = 21.313 * (rho * 0.235 * a) ** 1.1918 / 6800.0
        assert float(r["coefficient_crrel"]) == pytest.approx(mu, rel=1e-6)


def test_worked_examples_reproduced(run):
    ex = _read(run / "crrel_95_1_examples.csv")
    for r in ex:
        assert float(r["rut_depth_snowjax_m"]) == pytest.approx(
            float(r["rut_depth_report_m"]), abs=5e-4
        )  # printed to 0.1 cm
        assert round(float(r["drawbar_coefficient_snowjax"]), 3) == pytest.approx(
            float(r["drawbar_coefficient_report"]), abs=1e-9
        )
