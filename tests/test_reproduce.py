"""`snowjax reproduce --small` end to end, the numbers behind its figures, and the notebooks.

The reproduction runs once per session (module fixture) through the command line entry
point, in the slow tier (`make test-slow`: about two minutes of a worker).  The numbers it
writes are checked against independent computations: the SciPy reference of the wheel
(tests/reference.py), hand formulas of the load functions and the shear force model, and
the NumPy normalised shear stress of tests/test_derivatives.py.
"""

import contextlib
import csv
import io
import math

import numpy as np
import pytest

from snowjax._cli.app import main
from snowjax._reproduce.chapter3 import TABLE_3_2
from snowjax._reproduce.registry import FIGURES
from tests import reference
from tests.notebook_runner import outputs_text, run_notebook
from tests.test_derivatives import SIGMA_N0, tau_bar_classic_np

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


@pytest.fixture(scope="module")
def small_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("reproduce")
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        rc = main(["reproduce", "--out", str(out), "--small"])
    return out, rc, buf.getvalue()


def _csv(path):
    with open(path, newline="") as fh:
        rows = list(csv.reader(fh))
    return rows[0], rows[1:]


@pytest.mark.slow  # the reproduction's run (make test-slow)
def test_every_expected_file_appears(small_run):
    out, rc, stdout = small_run
    missing = [s.number for s in FIGURES if not (out / f"{s.stem}.png").exists()]
    assert not missing, f"figures not produced: {missing}\n{stdout}"
    assert rc == 0, stdout
    for spec in FIGURES:
        png = (out / f"{spec.stem}.png").read_bytes()
        assert png.startswith(PNG_MAGIC) and len(png) > 10_000, spec.number
        header, rows = _csv(out / f"{spec.stem}.csv")
        assert len(header) >= 2 and len(rows) >= 4, spec.number
    for name in ("wheel_sweep.csv", "derivative_tables.csv", "report.md"):
        assert (out / name).stat().st_size > 500, name
    assert "report.md" in stdout and "Report:" in stdout


@pytest.mark.slow
def test_report_shows_every_figure_with_caption_equations_table_and_comparison(small_run):
    out, _, _ = small_run
    report = (out / "report.md").read_text(encoding="utf-8")
    assert "Not produced" not in report and "Failures" not in report
    for spec in FIGURES:
        assert f"![Fig. {spec.number}]({spec.stem}.png)" in report, spec.number
        section = report.split(f"## Fig. {spec.number} — ", 1)[1].split("\n## ", 1)[0]
        assert "*Caption.*" in section and "*Equations:*" in section
        assert "**Comparison with the thesis.**" in section
        assert section.count("\n|") >= 4, spec.number  # a table with a few rows
        assert f"[{spec.number}](#{spec.stem})" in report  # listed in the overview
    assert "Derivative tables 4.3–4.6" in report
    assert "−U1² + 2U1 tan φ" in report  # the Table 4.6 sign error is reported


@pytest.mark.slow
def test_wheel_sweep_satisfies_equilibrium_by_independent_quadrature(small_run):
    out, _, _ = small_run
    header, rows = _csv(out / "wheel_sweep.csv")
    rec = [dict(zip(header, r)) for r in rows]
    assert len(rec) == 3 * 3 * 5
    assert {r["status"] for r in rec} == {"CONVERGED"}
    D, b = 0.736, 0.235
    p_w = 85_549.0
    snow = dict(p_w=p_w, z_w=0.2717 * D, c=0.2165 * p_w, tan_phi=0.0787, K=D / 73.6)
    picks = [r for r in rec if float(r["load_N"]) == 5000.0 and float(r["slip"]) in (0.0, 0.5)]
    assert len(picks) == 6
    for r in picks:
        theta0 = math.radians(float(r["entry_angle_deg"]))
        w, rr, t, m = reference.contact_integrals(
            theta0,
            float(r["slip"]),
            D,
            b,
            snow["p_w"],
            snow["z_w"],
            snow["c"],
            snow["tan_phi"],
            snow["K"],
            r["shear"],
        )
        assert w == pytest.approx(5000.0, rel=1e-6)
        assert float(r["motion_resistance_N"]) == pytest.approx(rr, rel=1e-6)
        assert float(r["thrust_N"]) == pytest.approx(t, rel=1e-6, abs=1e-6)
        assert float(r["sinkage_m"]) == pytest.approx(D / 2 * (1 - math.cos(theta0)), rel=1e-12)
    none = [float(r["sinkage_m"]) for r in rec if r["shear"] == "none" and r["load_N"] == "5000.0"]
    assert np.ptp(none) < 1e-12  # the no-shear sinkage does not depend on slip (Fig. 4.7)
    # Table 4.1's entry angle is the no-shear equilibrium at 5 kN (the preset's calibration).
    assert float(
        next(r for r in rec if r["shear"] == "none" and r["load_N"] == "5000.0")["entry_angle_deg"]
    ) == pytest.approx(53.6747, abs=2e-3)


@pytest.mark.slow
def test_load_function_tables_match_hand_formulas(small_run):
    out, _, _ = small_run
    header, rows = _csv(out / "fig_3_3.csv")
    for r in rows[::3]:
        f = float(r[0])  # kN
        assert float(r[1]) == pytest.approx(f / (0.2026 + 0.1516 * f), rel=1e-12)
        assert float(r[2]) == pytest.approx(f / (0.1936 + 0.1190 * f), rel=1e-12)
    report = (out / "report.md").read_text(encoding="utf-8")
    # The Table 3.2 comparison in the report uses the thesis's FEA values.
    assert f"{TABLE_3_2[3.5][0]:.4g}" in report and f"{TABLE_3_2[7.5][4]:.4g}" in report


def _fx(load_kn, slip, c_s=None, mu=None, e1=None):
    """Pure longitudinal force (3.10, 3.11) with the load functions (3.17, 3.19, 3.21), kN."""
    f = load_kn
    c_s = f / (0.2026 + 0.1516 * f) if c_s is None else c_s
    mu = 0.5386 - 0.0438 * f + 6.9010e-4 * f * f if mu is None else mu
    e1 = 0.5 * (1 - math.exp(-(7.5852e-9**2) * f - 0.1203**2 * f * f)) if e1 is None else e1
    phi = c_s * slip / (mu * f)
    return mu * f * (1 - math.exp(-phi - e1 * phi**2 - (e1**2 + 1 / 12) * phi**3))


@pytest.mark.slow
def test_variation_ratios_match_hand_computation(small_run):
    out, _, _ = small_run
    header, rows = _csv(out / "fig_3_6.csv")
    par = lambda f: (
        f / (0.2026 + 0.1516 * f),
        0.5386 - 0.0438 * f + 6.9010e-4 * f * f,
        0.5 * (1 - math.exp(-(0.1203**2) * f * f)),
    )
    (c1, m1, e1), (c2, m2, e2) = par(3.5), par(7.5)
    for r in rows[2::4]:
        s = float(r[0])
        base = _fx(3.5, s)
        total = _fx(7.5, s) - base
        assert float(r[1]) == pytest.approx((_fx(7.5, s, c2, m1, e1) - base) / total, rel=1e-9)
        assert float(r[2]) == pytest.approx((_fx(7.5, s, c1, m2, e1) - base) / total, rel=1e-9)
        assert float(r[3]) == pytest.approx((_fx(7.5, s, c1, m1, e2) - base) / total, rel=1e-9)


@pytest.mark.slow
def test_normalised_shear_of_fig_4_6_matches_numpy(small_run):
    out, _, _ = small_run
    header, rows = _csv(out / "fig_4_6.csv")
    slips = [float(h.split("_i")[1]) for h in header[1:] if h.startswith("classic")]
    data = np.array(rows, dtype=float)
    assert data[-1, 0] < SIGMA_N0
    for k, slip in enumerate(slips):
        np.testing.assert_allclose(
            data[:, 1 + k], tau_bar_classic_np(data[:, 0], slip), rtol=1e-10, atol=1e-14
        )


@pytest.mark.slow
def test_derivative_table_verdicts(small_run):
    out, _, _ = small_run
    header, rows = _csv(out / "derivative_tables.csv")
    rec = [dict(zip(header, r)) for r in rows]
    t45 = [r for r in rec if r["table"] == "Table 4.5"]
    assert len(t45) == 4 and all(float(r["max_rel_diff_vs_autodiff"]) < 1e-9 for r in t45)
    printed = next(
        r for r in rec if "U1² + 2 U1" in r["expression"] and "printed" in r["expression"]
    )
    corrected = next(r for r in rec if "corrected" in r["expression"])
    assert float(printed["max_rel_diff_vs_autodiff"]) > 1.0  # wrong sign: relative error > 100 %
    assert float(corrected["max_rel_diff_vs_autodiff"]) < 1e-10


def test_quick_start_notebook(tmp_path):
    nb = run_notebook("quick_start.ipynb", tmp_path)
    text = outputs_text(nb)
    assert "status       CONVERGED" in text and "(autodiff)" in text


@pytest.mark.slow  # a kernel and its own compiles (make test-slow)
def test_sensitivity_study_notebook(tmp_path):
    nb = run_notebook("sensitivity_study.ipynb", tmp_path)
    assert "elasticity of drawbar_pull" in outputs_text(nb)
