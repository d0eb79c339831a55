"""``roomba-bt eval`` end to end, in process."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

from roomba_bt.cli import main

MISSIONS = Path(__file__).resolve().parents[2] / "missions"
BUMP = str(MISSIONS / "bump-and-turn.yaml")


def test_eval_prints_the_report_and_plots(tmp_path: Path,
                                          capsys: pytest.CaptureFixture[str]) -> None:  # fmt: skip
    png = tmp_path / "runs.png"
    code = main(["eval", BUMP, "--runs", "2", "--seed", "3", "-p", "duration=3s",
                 "--plot", str(png)])  # fmt: skip
    out, err = capsys.readouterr()
    assert code == 0
    assert "success      2/2 = 100.0 %" in out and "Wilson" in out and "p90" in out
    assert "2/2 ok 2" in err
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_min_rate_not_reached_exits_1(capsys: pytest.CaptureFixture[str]) -> None:
    code = main(["eval", str(MISSIONS / "dock.yaml"), "--runs", "1", "--timeout", "1s",
                 "--min-rate", "0.5", "--no-progress"])  # fmt: skip
    assert code == 1
    assert "below --min-rate" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["missing.yaml"], "no such mission file"),
        ([BUMP, "--runs", "0"], "--runs 0"),
        ([BUMP, "--dock", "buoy_range=far"], "is not a number"),
        ([BUMP, "--dock", "colour=1"], "FIELD one of"),
        ([BUMP, "--world", "moon"], "no such file or shipped world"),
        ([BUMP, "--within", "1", "--world", "empty-room", "--battery", "2"], "--battery"),
        ([BUMP, "-p", "speed"], "NAME=VALUE"),
        ([BUMP, "-p", "speed=fast"], "speed"),
    ],
)
def test_bad_input_exits_2_with_a_message(
    argv: list[str], message: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["eval", *argv]) == 2
    assert message in capsys.readouterr().err


def test_plot_without_matplotlib_is_a_clear_error(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """Said when the arguments are read, before any episode runs."""
    monkeypatch.setitem(sys.modules, "matplotlib", None)
    with pytest.raises(SystemExit) as exit_:
        main(["eval", BUMP, "--runs", "1", "-p", "duration=1s", "--no-progress",
              "--plot", str(tmp_path / "x.png")])  # fmt: skip
    assert exit_.value.code == 2
    out, err = capsys.readouterr()
    assert "needs matplotlib" in err
    assert "success" not in out
    assert not (tmp_path / "x.png").exists()


@pytest.mark.parametrize("command", [["eval", BUMP, "--runs", "1"], ["run", BUMP, "--fast"],
                                     ["sim", "--pty", "--duration", "0"]])  # fmt: skip
def test_plot_into_a_missing_directory_is_refused_before_running(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], command: list[str]
) -> None:
    target = tmp_path / "no" / "such" / "x.png"
    with pytest.raises(SystemExit) as exit_:
        main([*command, "--plot", str(target)])
    assert exit_.value.code == 2
    out, err = capsys.readouterr()
    assert f"--plot: found '{target}': there is no directory {target.parent}" in err
    assert out == ""
