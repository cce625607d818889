"""Tests of `snowjax validate` (snowjax/_validate/, snowjax/_cli/validate.py).

One run of the CLI on the shipped data (module fixture); the checks recompute the
reported numbers independently from the CSVs it writes: the held-out errors, the skill
against the baseline, the folds, the bounds of every calibration.
"""

import csv
import math

import numpy as np
import pytest

import snowjax as sj
from snowjax._cli.app import main
from snowjax._validate.validate import _fold_choice, snow_groups


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


def test_cross_validation_never_uses_the_held_out_fold():
    # Two parameter values; the rows of fold 0 prefer column 1, the others column 0.
    measured = np.array([10.0, 10.0, 0.0, 0.0, 0.0])
    pred = np.array([[0.0, 10.0], [0.0, 10.0], [0.0, 1.0], [0.0, 1.0], [0.0, 1.0]])
    folds = np.array([0, 0, 1, 1, 2])
    chosen = _fold_choice((pred - measured[:, None]) ** 2, folds)
    assert list(chosen) == [0, 0, 1, 1, 1]  # fold 0 chosen without fold 0: column 0
    # With row 0 alone held out (leave-one-out), row 1 pulls towards column 1 for it.
    loo = _fold_choice((pred - measured[:, None]) ** 2, np.arange(5))
    assert loo[0] == 1
    # A column with a missing training prediction is never chosen.
    pred_nan = pred.copy()
    pred_nan[2, 0] = np.nan
    assert list(_fold_choice((pred_nan - measured[:, None]) ** 2, folds)) == [1, 1, 1, 1, 1]
    rows = sj.shoop_2001_table11()
    groups = snow_groups(rows)
    assert len(np.unique(groups)) == 3  # 160, 170 and 220 kg/m^3
    for g in np.unique(groups):
        assert np.unique(rows["density_kg_m3"][groups == g]).size == 1


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    out = tmp_path_factory.mktemp("validate")
    assert main(["validate", "--out", str(out)]) == 0
    return out


def _number(cell: str) -> float:
    """A cell of the CSVs: a number, or '-' / empty for none."""
    return math.nan if cell in ("", "-") else float(cell)


def _read(path):
    with open(path, newline="", encoding="utf-8") as f:
        return list(csv.DictReader(f))


@pytest.mark.slow  # `snowjax validate` end to end, about a minute (make test-slow)
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
    assert "| model | kind | parameters |" in report and "predicted_vs_measured.png" in report
    assert "skipped" not in report  # every model ran (including the Bekker wheel)


@pytest.mark.slow
def test_reported_metrics_match_the_predictions(run):
    """RMS, worst error and skill (1 - MSE / MSE of the baseline on the same held-out rows)
    recomputed from predictions.csv."""
    preds = _read(run / "predictions.csv")
    metrics = _read(run / "metrics.csv")
    assert len(preds) == 26
    meas = {
        "sinkage": np.array([float(r["sinkage_measured_m"]) for r in preds]),
        "coefficient": np.array([float(r["coefficient_measured"]) for r in preds]),
    }
    keys = {m["model"] for m in metrics}
    assert {
        "baseline", "crrel", "crrel_fit", "richmond_measured_rut", "van_es",
        "wheel_wong_pit_predicted", "tire_wong_pit_predicted", "bekker",
        "wheel_wong", "tire_wong", "wheel_wong_pit", "tire_wong_pit",
    } <= keys  # fmt: skip
    folds = np.array([int(float(r["fold"])) for r in preds])
    for q, m in meas.items():
        base = np.array([float(r[f"{q}_baseline"]) for r in preds])
        for fold in np.unique(folds):  # the mean of the other snows' rows
            np.testing.assert_allclose(base[folds == fold], m[folds != fold].mean(), rtol=1e-6)
    for m in metrics:
        p = np.array([_number(r[f"{m['quantity']}_{m['model']}"]) for r in preds])
        err = p - meas[m["quantity"]]
        finite = np.isfinite(err)
        base = np.array([float(r[f"{m['quantity']}_baseline"]) for r in preds])
        assert int(m["n"]) == finite.sum()
        if not finite.any():
            continue
        assert float(m["rms"]) == pytest.approx(math.sqrt(np.mean(err[finite] ** 2)), rel=1e-5)
        assert float(m["worst"]) == pytest.approx(np.max(np.abs(err[finite])), rel=1e-5)
        base_mse = np.mean((base - meas[m["quantity"]])[finite] ** 2)
        skill = 1 - np.mean(err[finite] ** 2) / base_mse
        assert float(m["skill"]) == pytest.approx(skill, rel=1e-4, abs=1e-6)


@pytest.mark.slow
def test_no_fitted_quantity_is_called_a_prediction_and_every_fit_is_bounded(run):
    """A model is a prediction only if nothing was fitted on the rows; a calibration's
    every parameter has a range from a cited source, its choices in every fold lie
    within it, and a choice at an end is flagged in metrics.csv and the report."""
    models = {m.key: m for m in sj.validation_models()}
    metrics = _read(run / "metrics.csv")
    report = (run / "report.md").read_text(encoding="utf-8")
    for m in metrics:
        model = models[m["model"]]
        assert m["kind"] == model.kind
        if model.grid is None:
            assert m["kind"] in ("prediction", "baseline") and not m["chosen"]
            continue
        assert m["kind"] == "calibration" and model.bounds
        columns = model.grid.reshape(len(model.grid), -1)
        assert columns.shape[1] == len(model.bounds)
        for k, bound in enumerate(model.bounds):
            assert bound.source and bound.lower < bound.upper
            np.testing.assert_allclose(columns[:, k].min(), bound.lower, rtol=1e-12)
            np.testing.assert_allclose(columns[:, k].max(), bound.upper, rtol=1e-12)
        chosen = [[float(v) for v in c.split("/")] for c in m["chosen"].split()]
        assert chosen
        at_end = False
        for values in chosen:
            for v, bound in zip(values, model.bounds):
                assert bound.lower * (1 - 1e-9) <= v <= bound.upper * (1 + 1e-9)
                at_end |= math.isclose(v, bound.lower, rel_tol=1e-6)
                at_end |= math.isclose(v, bound.upper, rel_tol=1e-6)
        assert bool(m["at_bounds"]) == at_end
    assert "**at its bound**" in report  # CRREL's rho_f runs to 650 kg/m^3
    assert "fixed: rho_f = 500 kg/m^3 (CRREL 95-7" in report


@pytest.mark.slow
def test_tyre_rows_report_their_own_contribution(run):
    """Every tyre model names its rigid-rim counterpart, and the report gives tyre minus
    rim at the parameters chosen, recomputed here for the prediction."""
    report = (run / "report.md").read_text(encoding="utf-8")
    models = sj.validation_models()
    tyres = [m for m in models if m.key.startswith("tire_")]
    assert len(tyres) == 3 and all(m.compare_to for m in tyres)
    assert report.count("tyre − rim R/W at the parameters chosen") == 3
    preds = _read(run / "predictions.csv")
    tyre = np.array([float(r["coefficient_tire_wong_pit_predicted"]) for r in preds])
    rim = np.array([float(r["coefficient_wheel_wong_pit_predicted"]) for r in preds])
    assert f"tyre − rim R/W at the parameters chosen: mean {np.mean(tyre - rim):.2g}" in report


@pytest.mark.slow
def test_uncalibrated_crrel_predictions_are_the_formula(run):
    preds = _read(run / "predictions.csv")
    for r in preds:
        h, rho = float(r["snow_depth_m"]), float(r["density_kg_m3"])
        z = h * (1 - rho / 500.0)
        assert float(r["sinkage_crrel"]) == pytest.approx(z, rel=1e-6)
        a = 0.38 * math.acos(1 - z / 0.38)
        mu = 21.313 * (rho * 0.235 * a) ** 1.1918 / 6800.0
        assert float(r["coefficient_crrel"]) == pytest.approx(mu, rel=1e-6)


@pytest.mark.slow
def test_worked_examples_reproduced(run):
    ex = _read(run / "crrel_95_1_examples.csv")
    for r in ex:
        assert float(r["rut_depth_snowjax_m"]) == pytest.approx(
            float(r["rut_depth_report_m"]), abs=5e-4
        )  # printed to 0.1 cm
        assert round(float(r["drawbar_coefficient_snowjax"]), 3) == pytest.approx(
            float(r["drawbar_coefficient_report"]), abs=1e-9
        )
