"""Shared arguments: a bad --baud or --watchdog is a usage error, never a traceback; -p and
--timeout read once for every command."""

from __future__ import annotations

import argparse
import os
import re
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import pytest
from waits import HANG_S  # tests/waits.py: a hang's bound

from roomba_bt.cli import build_parser, main
from roomba_bt.cli.arguments import (
    add_command,
    baud_rate,
    parse_params,
    parse_timeout,
    port_name,
    record_size_limit,
    seconds,
)
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
    ("text", "size"),
    [
        ("500MB", 500_000_000),
        ("2 GB", 2_000_000_000),
        ("1.5GiB", 3 << 29),
        ("64kb", 64_000),
        ("100KiB", 102_400),
        (" 2tb ", 2 * 1000**4),
    ],
)
def test_a_record_size_limit_is_read_as_people_write_sizes(text: str, size: int) -> None:
    assert record_size_limit(text) == size


@pytest.mark.parametrize(
    ("text", "found"),
    [
        ("500", "found '500'; allowed: a size with its unit"),  # 500 what?
        ("2 GBs", "found '2 GBs'"),
        ("big", "found 'big'"),
        ("-1MB", "found '-1MB'"),
        ("10kB", "found '10kB', 10,000 bytes; allowed: a size with its unit, 64 kB or more"),
    ],
)
def test_a_bad_record_size_limit_says_what_is_allowed(text: str, found: str) -> None:
    with pytest.raises(argparse.ArgumentTypeError, match=re.escape(found)):
        record_size_limit(text)


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["run", "missions/dock.yaml", "--record-max", "2G"], "--record-max: found '2G'"),
        (["run", "missions/dock.yaml", "--watchdog", "-1"], "--watchdog: found -1"),
        # 0 turned the watchdog off, and with it stall and stream-loss detection: a stopped
        # stream froze the mission clock and the run hung, the robot driving on
        (
            ["run", "missions/dock.yaml", "--watchdog", "0"],
            "--watchdog: found 0; allowed: seconds, 0.03 or more",
        ),
        (["run", "missions/dock.yaml", "--watchdog", "0.02"], "--watchdog: found 0.02"),
        (["run", "missions/dock.yaml", "--baud", "12"], "--baud: found 12"),
        (["validate", "missions/dock.yaml", "--baud", "0"], "--baud: found 0"),
        (["sensors", "--baud", "-1"], "--baud: found -1"),
        (["run", "missions/dock.yaml", "--record", "/no/such/dir/run.log"], "no directory"),
        (["sim", "--pty", "--duration", "-1"], "--duration: found -1"),
        # a URL typo was "could not open" (exit 3) with a fix about the dialout group
        (["doctor", "--port", "bogus://x"], "'bogus://x', a URL of no scheme pyserial knows"),
        (["run", "dock", "--port", "socket://robot"], "allowed: socket://HOST:PORT"),
        (["sensors", "--port", "rfc2217://h:99999"], "a port in 1..65535"),
        # a file or a folder given as the port was exit 3, "could not start", which a
        # service retried for ever (Restart=on-failure); no retry mends it
        (
            ["run", "dock", "--port", __file__],
            "--port: not a serial port but a file (--port takes a serial port's character "
            "device such as /dev/ttyUSB0",
        ),
        (["doctor", "--port", str(Path(__file__).parent)], "not a serial port but a folder"),
        # argparse takes "-3s" for an option: it said only "expected one argument"
        (["run", "dock", "--timeout", "-3s"], "write --timeout=VALUE"),
        (["run", "dock", "-p"], "write --param=VALUE"),
        # one definition for run and eval (arguments.py), the range Faults allows
        (
            ["run", "dock", "--odometry-error", "0.3"],
            "--odometry-error: found 0.3; allowed: a fraction in 0..0.2",
        ),
        (["eval", "dock", "--odometry-error", "-0.1"], "--odometry-error: found -0.1"),
        (["run", "dock", "--odometry-error", "much"], "--odometry-error: found 'much'"),
    ],
)
def test_commands_refuse_them_with_exit_2(
    argv: list[str], message: str, usage_error: Callable[..., str]
) -> None:
    assert message in usage_error(main, argv)


@pytest.mark.parametrize(
    "port", ["/dev/ttyUSB0", "COM3", "socket://127.0.0.1:7777", "SOCKET://bridge:23", "loop://",
             "rfc2217://localhost:7777?logging=debug"],
)  # fmt: skip
def test_port_names_pyserial_opens_are_taken_as_given(port: str) -> None:
    assert port_name(port) == port


def test_params_are_read_as_text_name_to_value() -> None:
    assert parse_params(["speed=250mm/s", " laps = 2 ", "empty="]) == {
        "speed": "250mm/s",
        "laps": "2",
        "empty": "",
    }


@pytest.mark.parametrize("item", ["speed", "=250mm/s", " =1"])
def test_a_param_without_a_name_or_value_sign_is_a_message(item: str) -> None:
    message = parse_params(["laps=2", item])
    assert message == f"-p {item!r}: expected NAME=VALUE, e.g. -p speed=250mm/s"


@pytest.mark.parametrize(
    ("text", "value"), [(None, None), ("90", 90.0), ("90s", 90.0), ("5min", 300.0)]
)
def test_timeout(text: str | None, value: float | None) -> None:
    assert parse_timeout(text) == value


@pytest.mark.parametrize(("text", "message"), [("0", "more than 0 s"), ("soon", "'soon'")])
def test_bad_timeout_is_a_message(text: str, message: str) -> None:
    result = parse_timeout(text)
    assert isinstance(result, str) and result.startswith(f"--timeout {text!r}: ")
    assert message in result


def _launch(args: argparse.Namespace) -> int:
    return 0


def _plain(args: argparse.Namespace) -> int:
    return 0


def test_a_command_is_declared_with_its_texts() -> None:
    parser = argparse.ArgumentParser(prog="roomba-bt")
    sub = parser.add_subparsers()
    launch = add_command(
        sub,
        "launch",
        _launch,
        """launch the thing

        Launch it at --speed, and report
        where it landed.
        """,
    )
    plain = add_command(sub, "plain", _plain, "do it")
    listing = parser.format_help()
    assert re.search(r"launch +launch the thing", listing) and re.search(r"plain +do it", listing)
    assert launch.description == "Launch it at --speed, and report\nwhere it landed."
    assert "Launch it at --speed, and report where it landed." in launch.format_help()
    assert plain.description is None
    assert parser.parse_args(["launch"]).func is _launch
    assert parser.parse_args(["plain"]).func is _plain


def _help_under_oo(*args: str) -> str:
    """``roomba-bt ARGS --help`` in a ``python -OO`` process (docstrings stripped)."""
    done = subprocess.run(
        [sys.executable, "-OO", "-m", "roomba_bt.cli", *args, "--help"],
        capture_output=True, text=True, timeout=HANG_S, check=True,
        env={**os.environ, "COLUMNS": "100"},
    )  # fmt: skip
    return done.stdout


def test_the_help_survives_python_oo(monkeypatch: pytest.MonkeyPatch) -> None:
    """``-OO`` strips docstrings: the listing and a command's description must not come from
    them (they did, and every command's line in ``roomba-bt --help`` was blank)."""
    monkeypatch.setenv("COLUMNS", "100")
    parser = build_parser()
    listing = _help_under_oo()
    assert listing == parser.format_help()
    commands = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    for name in commands.choices:
        assert re.search(rf"^    {name} +\S", listing, re.MULTILINE), name
    assert "Exit codes: 0 succeeded" in _help_under_oo("run")


def test_run_s_watchdog_default_is_the_connection_s_in_the_value_and_the_help(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """``run --watchdog`` wrote its own 0.1, in its default and again in its help, beside
    the connection's ``DEFAULT_WATCHDOG``: a change to one reached neither of the others.
    The option reads the one constant for both (changed here, both follow)."""
    import inspect

    from roomba_bt.cli import run_cmd

    monkeypatch.setattr(run_cmd, "DEFAULT_WATCHDOG", 0.25, raising=False)
    parser = build_parser()
    assert parser.parse_args(["run", "missions/dock.yaml"]).watchdog == 0.25
    commands = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    run_help = " ".join(commands.choices["run"].format_help().split())
    assert "came for this long (default 0.25; 0.03 or more" in run_help
    monkeypatch.undo()
    from roomba_bt.robot.connection import Connection
    from roomba_bt.robot.errors import DEFAULT_WATCHDOG

    assert run_cmd.DEFAULT_WATCHDOG is DEFAULT_WATCHDOG  # the connection's own default
    assert inspect.signature(Connection).parameters["watchdog"].default is DEFAULT_WATCHDOG


def _commands() -> list[str]:
    subparsers = next(
        action
        for action in build_parser()._actions
        if isinstance(action, argparse._SubParsersAction)
    )
    return sorted(subparsers.choices)


#: what a command needs besides its options, to be parsed as far as an unknown option
REQUIRED = {
    "doctor": ["--port", "/dev/ttyUSB0"], "eval": ["m.yaml"], "monitor": ["r.jsonl"],
    "replay": ["r.jsonl"], "run": ["m.yaml"], "show": ["m.yaml"], "sim": ["--pty"],
    "validate": ["m.yaml"],
}  # fmt: skip


@pytest.mark.parametrize("command", _commands())
def test_an_option_a_command_does_not_know_prints_that_command_s_usage(
    command: str, capsys: pytest.CaptureFixture[str]
) -> None:
    """``roomba-bt replay rec.jsonl --display none`` printed the top-level usage (``usage:
    roomba-bt [-h] [--version] [-v] [-q] COMMAND ...``): argparse hands a subcommand's unknown
    arguments up to the top parser. Each command now says its own, exit 2."""
    with pytest.raises(SystemExit) as ended:
        main([command, *REQUIRED.get(command, []), "--no-such-option"])
    assert ended.value.code == 2
    err = capsys.readouterr().err
    assert err.startswith(f"usage: roomba-bt {command} "), err
    assert f"roomba-bt {command}: error: unrecognized arguments: --no-such-option" in err


def test_replay_takes_the_displays_that_fit_a_record_read_as_fast_as_it_can() -> None:
    """``--display`` as ``run`` has it, where it fits a replay: the tree with its final
    statuses, the log of status changes, or the summary alone (its default); no live tree."""
    parser = build_parser()
    assert parser.parse_args(["replay", "rec.jsonl"]).display == "none"
    for display in ("tree", "log", "none"):
        assert parser.parse_args(["replay", "rec.jsonl", "--display", display]).display == display
    assert parser.parse_args(["run", "dock"]).display == "auto"
