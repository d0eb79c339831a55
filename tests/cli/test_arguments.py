"""Shared argument types: a bad --baud or --watchdog is a usage error, never a traceback."""

from __future__ import annotations

import argparse

import pytest

from roomba_bt.cli import main
from roomba_bt.cli.arguments import baud_rate, seconds
from roomba_bt.oi.encode import BAUD_CODES


@pytest.mark.parametrize("rate", sorted(BAUD_CODES))
def test_every_oi_baud_rate_is_accepted(rate: int) -> None:
    assert baud_rate(str(rate)) == rate


@pytest.mark.parametrize("text", ["0", "-1", "12", "115201", "fast", ""])
def test_other_baud_rates_name_the_allowed_ones(text: str) -> None:
    with pytest.raises(argparse.ArgumentTypeError, match=r"allowed: 300, 600, .*, 115200"):
        baud_rate(text)


@pytest.mark.parametrize(("text", "value"), [("0", 0.0), ("0.1", 0.1), ("2", 2.0)])
def test_seconds(text: str, value: float) -> None:
    assert seconds(text) == value


@pytest.mark.parametrize("text", ["-1", "nan", "inf", "soon"])
def test_bad_seconds(text: str) -> None:
    with pytest.raises(argparse.ArgumentTypeError, match="seconds, 0 or more"):
        seconds(text)


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["run", "missions/dock.yaml", "--watchdog", "-1"], "--watchdog: found -1"),
        (["run", "missions/dock.yaml", "--baud", "12"], "--baud: found 12"),
        (["validate", "missions/dock.yaml", "--baud", "0"], "--baud: found 0"),
        (["sensors", "--baud", "-1"], "--baud: found -1"),
        (["run", "missions/dock.yaml", "--record", "/no/such/dir/run.log"], "no directory"),
        (["sim", "--pty", "--duration", "-1"], "--duration: found -1"),
    ],
)
def test_commands_refuse_them_with_exit_2(
    argv: list[str], message: str, capsys: pytest.CaptureFixture[str]
) -> None:
    with pytest.raises(SystemExit) as exit_:
        main(argv)
    assert exit_.value.code == 2
    assert message in capsys.readouterr().err
