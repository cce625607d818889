"""The `snowjax reproduce` command line: arguments, summary, exit status.

The real reproduction runs once in tests/test_reproduce.py; here `reproduce` is replaced
by a stub that writes the expected file names, so the command-line logic is tested in
milliseconds.
"""

import pathlib

import pytest

from snowjax._cli.app import main
from snowjax._reproduce import registry as _reproduce


def _stub(missing=()):
    calls = []

    def fake(out_dir, *, small=False, progress=True, figures=None):
        calls.append(dict(out=pathlib.Path(out_dir), small=small))
        out = pathlib.Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        files = []
        for spec in _reproduce.FIGURES:
            if spec.number in missing:
                continue
            files += [out / f"{spec.stem}.png", out / f"{spec.stem}.csv"]
        files += [out / "wheel_sweep.csv", out / "derivative_tables.csv", out / "report.md"]
        for f in files:
            f.write_text("x")
        return files

    return fake, calls


def test_reproduce_passes_options_and_prints_summary(tmp_path, monkeypatch, capsys):
    fake, calls = _stub()
    monkeypatch.setattr(_reproduce, "reproduce", fake)
    assert main(["reproduce", "--out", str(tmp_path / "o"), "--small"]) == 0
    assert calls == [dict(out=tmp_path / "o", small=True)]
    text = capsys.readouterr().out
    assert "report.md" in text and "4.8" in text and "FAILED" not in text


def test_reproduce_defaults(tmp_path, monkeypatch):
    fake, calls = _stub()
    monkeypatch.setattr(_reproduce, "reproduce", fake)
    monkeypatch.chdir(tmp_path)
    assert main(["reproduce"]) == 0
    assert calls == [dict(out=pathlib.Path("snowjax-output"), small=False)]


def test_reproduce_fails_when_a_figure_is_missing(tmp_path, monkeypatch, capsys):
    fake, _ = _stub(missing=("2.1",))
    monkeypatch.setattr(_reproduce, "reproduce", fake)
    assert main(["reproduce", "--out", str(tmp_path)]) == 1
    assert "2.1" in capsys.readouterr().out


def test_bad_arguments_exit_nonzero():
    with pytest.raises(SystemExit) as e:
        main(["reproduce", "--slips", "3"])
    assert e.value.code != 0


def test_help_lists_options(capsys):
    with pytest.raises(SystemExit) as e:
        main(["reproduce", "--help"])
    assert e.value.code == 0
    text = capsys.readouterr().out
    assert "--out" in text and "--small" in text
