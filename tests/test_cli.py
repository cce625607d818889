import csv

import pytest

from snowjax._cli import main


def test_reproduce_writes_table_csv_and_figures(tmp_path, capsys):
    assert main(["reproduce", "--out", str(tmp_path), "--slips", "3"]) == 0
    rows = list(csv.DictReader(open(tmp_path / "wheel_sweep.csv")))
    assert len(rows) == 3 * 3 * 3
    assert {r["status"] for r in rows} == {"CONVERGED"}
    assert (tmp_path / "fig_4_7_sinkage_vs_slip.png").stat().st_size > 10_000
    assert (tmp_path / "fig_4_8_motion_resistance_vs_slip.png").stat().st_size > 10_000
    assert "Thesis tyre on fresh shallow snow" in capsys.readouterr().out


def test_bad_arguments_exit_nonzero():
    with pytest.raises(SystemExit) as e:
        main(["reproduce", "--slips", "1"])
    assert e.value.code != 0
