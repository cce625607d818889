"""Expected CLI failures are one line naming the flag or value, exit status 2, never a
Python traceback; ordinary spellings are accepted."""

import pytest

from snowjax._cli.app import _attach_negative_values, main

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
]  # fmt: skip


@pytest.mark.parametrize(("argv", "message"), CASES)
def test_expected_failures_are_one_line(argv, message, tmp_path, capsys):
    (tmp_path / "file").write_text("not a directory")
    argv = [a.replace("{tmp}", str(tmp_path)) for a in argv]
    message = message.replace("{tmp}", str(tmp_path))
    assert main(argv) == 2
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
