"""Expected CLI failures are one line naming the flag or value, exit status 2, never a
Python traceback; ordinary spellings are accepted."""

import importlib.resources
import warnings

import numpy as np
import pytest

from snowjax._cli import fit as fit_cli
from snowjax._cli.app import _attach_negative_values, main

# Small data files, written into the test's tmp_path as {tmp}/<name>.
_LOADS = np.repeat([3500.0, 7500.0], 6)
_SLIPS = np.tile(np.linspace(0.05, 0.8, 6), 2)
FILES = {
    # 12 points, sinkage and drawbar pull: the shapes of the wheel fits of test_fit.py,
    # so the compiled fit is shared.
    "wheel.csv": "load_N,slip,sinkage_m,drawbar_pull_N\n"
    + "".join(f"{float(ld)!r},{float(sl)!r},0.12,400.0\n" for ld, sl in zip(_LOADS, _SLIPS)),
    "plate_huge.csv": "sinkage_m,pressure_Pa\n0.01,1000\n1e300,2100\n0.03,3000\n0.04,4400\n",
    "plate_two_units.csv": "sinkage_m,pressure_Pa,pressure_kPa\n0.01,1000,1\n0.02,2100,2.1\n",
    "plate_sized.csv": "sinkage_m,pressure_Pa,plate_size_m\n0.01,1000,0.2\n0.02,2100,0.2\n",
    "tire_huge.csv": "load_kN,cs,ca,mux,muy,e1\n3.5,1e308,5.86,0.39,0.22,0.04\n"
    "4.5,4.98,6.10,0.36,0.18,0.08\n6.24,5.09,6.34,0.29,0.14,0.19\n7.5,5.90,7.17,0.25,0.12,0.35\n",
    "tire_sum_overflows.csv": "load_kN,cs,ca,mux,muy,e1\n3.5,1e154,5.86,0.39,0.22,0.04\n"
    "4.5,1e154,6.10,0.36,0.18,0.08\n6.24,1e154,6.34,0.29,0.14,0.19\n"
    "7.5,1e154,7.17,0.25,0.12,0.35\n",
}

CASES = [
    (["sweep", "--loads", "1000:2000:100000000000", "--out", "{tmp}/s"],
     "--loads '1000:2000:100000000000': 100,000,000,000 values would take 745.1 GiB"),
    (["sweep", "--loads", "1000:2000:10000000", "--slips", "0:0.9:100000", "--out", "{tmp}/s"],
     "1,000,000,000,000 points would write about"),
    (["sweep", "--out", ""], "--out must name a directory"),
    (["sweep", "--slips", "0:1:x", "--out", "{tmp}/s"], "--slips '0:1:x': expected start:stop:num"),
    (["reproduce", "--out", "{tmp}/file"], "--out {tmp}/file: exists and is not a directory"),
    (["reproduce", "--out", "{tmp}/file/sub"], "--out {tmp}/file/sub: cannot create the directory"),
    (["reproduce", "--out", "/proc/snowjax"], "--out /proc/snowjax: cannot create the directory"),
    (["reproduce", "--out", ""], "--out must name a directory"),
    # Usage errors: one line too (argparse alone prints the whole usage first).
    (["fit", "wheel", "--data", "{tmp}/wheel.csv", "--max-steps", "x"],
     "snowjax fit wheel: error: argument --max-steps: invalid int value: 'x' (see 'snowjax"),
    # fit: the wheel model has no equilibrium anywhere (snow 13.6 wheel diameters deep).
    (["fit", "wheel", "--data", "{tmp}/wheel.csv", "--z-w", "10"],
     "12 of 12 data points have no equilibrium"),
    # fit: runs that ended as a bogus 'converged' result.
    (["fit", "wheel", "--data", "{tmp}/wheel.csv", "--cohesion", "0", "--shear", "simplified"],
     "{tmp}/wheel.csv: fit_wheel: the start values are not valid for solve_wheel: snow.cohesion"),
    (["fit", "wheel", "--data", "{tmp}/wheel.csv", "--max-steps", "0"],
     "--max-steps must be >= 1 (Levenberg-Marquardt steps), got 0"),
    (["fit", "wheel", "--data", "{tmp}/wheel.csv", "--max-steps", "-3"],
     "--max-steps must be >= 1 (Levenberg-Marquardt steps), got -3"),
    (["fit", "plate", "--data", "{tmp}/plate_huge.csv", "--plate-size", "0.2"],
     "{tmp}/plate_huge.csv: line 3 (data row 2), column 'sinkage_m': 1e300 is too large for "
     "float64 arithmetic"),
    (["fit", "tire", "--data", "{tmp}/tire_huge.csv"],
     "{tmp}/tire_huge.csv: line 2 (data row 1), column 'cs': 1e308 is too large"),
    (["fit", "tire", "--data", "{tmp}/tire_sum_overflows.csv"],
     "{tmp}/tire_sum_overflows.csv: cs = 1e+154 at index 0 is too large for the float64"),
    # fit: the same quantity in two units.
    (["fit", "plate", "--data", "{tmp}/plate_two_units.csv", "--plate-size", "0.2"],
     "{tmp}/plate_two_units.csv: line 1 (header): columns 'pressure_Pa' and 'pressure_kPa' "
     "give the same quantity in different units"),
    # Options that would do nothing in this combination.
    (["fit", "plate", "--data", "{tmp}/plate_sized.csv", "--plate-size", "0.2"],
     "{tmp}/plate_sized.csv: --plate-size and the plate_size_m column both give the plate size"),
    (["fit", "plate", "--data", "{tmp}/plate_sized.csv", "--law", "wong", "--plate-size", "0.2"],
     "--plate-size is not used by --law wong"),
    (["fit", "plate", "--data", "{tmp}/plate_sized.csv", "--cohesion", "1000"],
     "--cohesion only applies with --law reece"),
    (["fit", "plate", "--data", "{tmp}/plate_sized.csv", "--law", "wong", "--cohesion", "1",
      "--unit-weight", "2"], "--cohesion and --unit-weight only apply with --law reece"),
    (["sweep", "--list", "--param-grid", "--p-w", "60e3,80e3", "--out", "{tmp}/s"],
     "--param-grid does nothing with --list"),
    (["sweep", "--param-grid", "--out", "{tmp}/s"],
     "--param-grid combines parameter lists, but no parameter option has more than one value"),
    # A rule of the terrain with the wheel width, checked per parameter set before any
    # chunk is padded (the chunk's padding was counted as invalid elements).
    (["sweep", "--terrain", "bekker", "--set", "k_phi=-1e9,5e5", "--param-grid", "--loads",
      "1000,2000", "--slips", "0.1,0.2", "--out", "{tmp}/s"],
     "snowjax sweep: error: k_c / b + k_phi must be finite and > 0 at the wheel width b; got"
     " -999981404.2553191 at parameter set 0"),
    (["sweep", "--coordinator", "localhost:1234", "--out", "{tmp}/s"],
     "--coordinator only applies with --distributed"),
    (["sweep", "--num-processes", "2", "--process-id", "0", "--out", "{tmp}/s"],
     "--num-processes, --process-id only apply with --distributed"),
    # validate: bad values, one line each.
    (["validate", "--wheel-load", "inf", "--out", "{tmp}/v"],
     "--wheel-load must be a finite number > 0 (newtons), got inf"),
    (["validate", "--tyre-width", "3", "--out", "{tmp}/v"],
     "--tyre-width must be in (0, 2) metres, got 3.0"),
    (["validate", "--out", "{tmp}/file"], "--out {tmp}/file: exists and is not a directory"),
]  # fmt: skip


@pytest.mark.parametrize(("argv", "message"), CASES)
def test_expected_failures_are_one_line(argv, message, tmp_path, capsys):
    (tmp_path / "file").write_text("not a directory")
    for name, text in FILES.items():
        (tmp_path / name).write_text(text)
    argv = [a.replace("{tmp}", str(tmp_path)) for a in argv]
    message = message.replace("{tmp}", str(tmp_path))
    try:
        status = main(argv)
    except SystemExit as exit_:  # usage errors exit from the argument parser
        status = exit_.code
    assert status == 2
    err = capsys.readouterr().err
    assert message in err
    assert "Traceback" not in err
    assert len(err.strip().splitlines()) == 1


def test_negative_values_follow_their_option():
    assert _attach_negative_values(["sweep", "--slips", "-0.5:0:3", "--loads", "3000"]) == [
        "sweep",
        "--slips=-0.5:0:3",
        "--loads",
        "3000",
    ]
    assert _attach_negative_values(["sweep", "--slips=-0.5", "-h"]) == [
        "sweep",
        "--slips=-0.5",
        "-h",
    ]


def test_negative_slips_run(tmp_path, capsys):
    out = tmp_path / "neg"
    argv = ["sweep", "--slips", "-0.5:0:3", "--loads", "3000", "--out", str(out), "--no-progress"]
    assert main(argv) == 0
    assert (out / "sweep.csv").read_text().count("\n") == 4  # header + 3 rows
    printed = capsys.readouterr().out
    rate = float(printed.split(" points/s")[0].rsplit(" ", 1)[1].replace(",", ""))
    assert rate > 0  # three points in a few seconds: a rate below 1, not "0 points/s"


def test_csv_with_a_byte_order_mark_is_read(tmp_path, capsys):
    """Spreadsheet programs save 'CSV UTF-8' with a byte-order mark before the header."""
    table = importlib.resources.files("snowjax") / "data" / "table_2_1.csv"
    plain = tmp_path / "plain.csv"
    plain.write_text(table.read_text(encoding="utf-8"), encoding="utf-8")
    marked = tmp_path / "marked.csv"
    marked.write_text(table.read_text(encoding="utf-8"), encoding="utf-8-sig")
    assert marked.read_bytes().startswith(b"\xef\xbb\xbf")
    outputs = []
    for path in (plain, marked):
        assert main(["fit", "plate", "--data", str(path), "--plate-size", "0.23"]) == 0
        outputs.append(capsys.readouterr().out.replace(str(path), "DATA"))
    assert outputs[0] == outputs[1]


def test_numpy_warnings_are_not_shown(tmp_path, monkeypatch, capsys):
    """A RuntimeWarning (overflow, 0/0) raised while a command runs never reaches the
    user: every command reports non-finite results itself."""

    def overflowing(args):
        np.float64(1e308) * 10.0  # overflow: a RuntimeWarning with its source line
        np.zeros(1) / np.zeros(1)  # invalid value
        return 0

    monkeypatch.setattr(fit_cli, "run", overflowing)
    (tmp_path / "d.csv").write_text("x\n1\n")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        assert main(["fit", "tire", "--data", str(tmp_path / "d.csv")]) == 0
    assert not [w for w in caught if issubclass(w.category, RuntimeWarning)]
    assert "RuntimeWarning" not in capsys.readouterr().err


def test_fit_with_extreme_values_prints_no_runtime_warning(tmp_path, capsys):
    """Extreme but valid data (sinkages of 1e-300 m, whose squares underflow) and data
    whose arithmetic overflows (refused): neither shows a RuntimeWarning."""
    tiny = tmp_path / "tiny.csv"
    tiny.write_text(
        "sinkage_m,pressure_Pa\n" + "".join(f"{k}e-300,{1000 * k}\n" for k in range(1, 6))
    )
    (tmp_path / "tire_huge.csv").write_text(FILES["tire_huge.csv"])
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        assert main(["fit", "plate", "--data", str(tiny), "--plate-size", "0.2"]) == 0
        assert main(["fit", "tire", "--data", str(tmp_path / "tire_huge.csv")]) == 2
    captured = capsys.readouterr()
    assert not [w for w in caught if issubclass(w.category, RuntimeWarning)]
    assert "RuntimeWarning" not in captured.err + captured.out


def _single_wheel_folder(tmp_path, edit=None, drop_grousered=False):
    """A copy of the measured single-wheel data, `edit(text) -> text` applied to
    smooth_wheel.csv."""
    from .test_single_wheel import _data_folder

    source = _data_folder()
    folder = tmp_path / "data"
    folder.mkdir()
    for name in ("smooth_wheel.csv", "grousered_wheel.csv"):
        if name == "grousered_wheel.csv" and drop_grousered:
            continue
        text = (source / name).read_text(encoding="utf-8")
        if edit is not None and name == "smooth_wheel.csv":
            text = edit(text)
        (folder / name).write_text(text, encoding="utf-8")
    return folder


def _replace_field(line_number, column, value):
    """An edit that sets one field of one line (1-based, the header is line 1)."""

    def edit(text):
        lines = text.splitlines()
        header = lines[0].split(",")
        fields = lines[line_number - 1].split(",")
        fields[header.index(column)] = value
        lines[line_number - 1] = ",".join(fields)
        return "\n".join(lines) + "\n"

    return edit


SINGLE_WHEEL_CASES = [
    (
        dict(edit=_replace_field(5, "fx_N", "n/a")),
        "smooth_wheel.csv: line 5 (data row 4), column 'fx_N': 'n/a' is not a finite number",
    ),
    (
        dict(edit=lambda t: t.replace("fz_N,", "force_z,", 1)),
        "smooth_wheel.csv: missing column(s) fz_N",
    ),
    # Cut in the middle of row 30: the last line is short.
    (
        dict(edit=lambda t: t[: t.index("\n", sum(len(x) + 1 for x in t.splitlines()[:30])) - 40]),
        "smooth_wheel.csv: line 31 (data row 30): 17 field(s), the header has 22 (is the file",
    ),
    # Cut after row 40: whole rows are missing (the 75 deg rows among them).
    (
        dict(edit=lambda t: "\n".join(t.splitlines()[:41]) + "\n"),
        "smooth_wheel.csv: no usable row at slip angle 75 deg (needed for the extrapolation",
    ),
    (dict(drop_grousered=True), "single-wheel data not found: "),
]


@pytest.mark.parametrize("files, message", SINGLE_WHEEL_CASES)
def test_validate_single_wheel_bad_files_are_one_line_before_any_compile(
    tmp_path, capsys, monkeypatch, files, message
):
    """Every data file is read and checked before the first calibration (minutes): a
    malformed or truncated file, or a missing one, is one line and exit status 2."""
    from snowjax._validate import single_wheel

    def must_not_run(*args, **kwargs):
        raise AssertionError("the calibration started before the files were checked")

    monkeypatch.setattr(single_wheel, "single_wheel_study", must_not_run)
    folder = _single_wheel_folder(tmp_path, **files)
    argv = ["validate", "--single-wheel", str(folder), "--out", str(tmp_path / "out")]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert message in err
    assert "Traceback" not in err
    assert len(err.strip().splitlines()) == 1
