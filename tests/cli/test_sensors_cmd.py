"""``roomba-bt sensors`` on the simulator: the largest group that fits the baud rate."""

from __future__ import annotations

import re

import pytest
from quoted import assert_quoted  # tests/quoted.py: the docs' quotes
from robot.sim_backend import sim_pty_server  # tests/robot: the simulator on a pty

from roomba_bt.cli import main
from roomba_bt.cli.sensors_cmd import group_for
from roomba_bt.oi.encode import BAUD_CODES
from roomba_bt.oi.frames import stream_frame_size
from roomba_bt.oi.stream import stream_budget
from roomba_bt.transport.link_kind import link_of


@pytest.mark.parametrize("rate", sorted(BAUD_CODES))
def test_the_group_chosen_fits_the_rate(rate: int) -> None:
    group = group_for(rate)
    if group is None:
        assert stream_frame_size((1,)) > stream_budget(rate)  # not even the smallest
    else:
        assert stream_frame_size((group,)) <= stream_budget(rate)
    assert group_for(115200) == 100 and group_for(38400) == 6 and group_for(19200) == 1


def table_rows(out: str) -> dict[str, str]:
    """Packet id -> its row, of the last table ``sensors`` printed."""
    table = out.strip().split("\n\n")[-1].splitlines()[1:]
    return {line.split()[0]: line for line in table}


@pytest.mark.parametrize("rate", [115200, 57600, 38400, 19200, 9600])
def test_sensors_shows_every_packet_at_each_rate(
    rate: int, capsys: pytest.CaptureFixture[str]
) -> None:
    """At 19200 baud group 6 (a 56-byte frame) does not fit the 28 bytes of a slot: this
    used to end in a BandwidthError traceback; then the table showed group 1 alone (7-16),
    no battery, mode or encoders (audit finding 14). Below 57600 each table is now a Query
    List (149) of group 100: every packet, 7-58, at every rate."""
    assert main(["sensors", "--baud", str(rate), "--count", "2", "--rate", "66"]) == 0
    rows = table_rows(capsys.readouterr().out)
    assert list(rows) == [str(pid) for pid in range(7, 59)]
    assert "passive" in rows["35"] and "battery_charge" in rows["25"]
    assert "left_encoder_counts" in rows["43"]


@pytest.mark.parametrize(
    ("rate", "said"),
    [(115200, "streaming [100]"), (19200, "no stream (a Query List (149) each reading)")],
)
def test_the_start_up_log_says_how_the_sensors_are_read(
    rate: int, said: str, caplog: pytest.LogCaptureFixture
) -> None:
    """Below 57600 no stream is asked for: the connection's start-up said "streaming []",
    a stream of nothing, where each table is a Query List."""
    caplog.set_level("INFO", logger="roomba_bt.robot.connection")
    assert main(["sensors", "--baud", str(rate), "--count", "1"]) == 0
    started = [r.getMessage() for r in caplog.records if " in Passive, " in r.getMessage()]
    assert len(started) == 1 and started[0].endswith(f"in Passive, {said}")
    assert "streaming []" not in caplog.text


def test_sensors_at_19200_over_a_pty_queries_every_packet(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """The same through a serial line: the simulator on a pty, the robot's port at 19200
    (as after Clean held at power-off), no stream asked for."""
    from roomba_bt.oi.profiles import CREATE2

    with sim_pty_server(CREATE2, "--baud", "19200") as port:
        code = main(["sensors", "--port", port, "--baud", "19200", "--count", "2"])
    captured = capsys.readouterr()
    assert code == 0, captured.err
    rows = table_rows(captured.out)
    assert list(rows) == [str(pid) for pid in range(7, 59)]
    assert "passive" in rows["35"]


def test_a_rate_too_slow_for_any_stream_is_a_clear_error(
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert main(["sensors", "--baud", "4800", "--count", "1"]) == 2
    err = capsys.readouterr().err
    assert "--baud 4800: no sensor stream fits in 15 ms" in err and "9600 or more" in err


@pytest.mark.parametrize(
    ("option", "value", "allowed"),
    [
        ("--rate", "0", "above 0 and at most 66"),  # was a ZeroDivisionError traceback
        ("--rate", "-1", "above 0 and at most 66"),
        ("--rate", "nan", "above 0 and at most 66"),
        ("--rate", "inf", "above 0 and at most 66"),
        ("--rate", "100", "above 0 and at most 66"),
        ("--count", "-1", "a whole number, 0 or more"),  # printed nothing and exited 0
    ],
)
def test_a_refresh_rate_or_count_out_of_range_is_a_usage_error(
    option: str, value: str, allowed: str, capsys: pytest.CaptureFixture[str]
) -> None:
    with pytest.raises(SystemExit) as exit_:
        main(["sensors", option, value, "--count", "1"] if option == "--rate" else
             ["sensors", option, value])  # fmt: skip
    assert exit_.value.code == 2
    err = capsys.readouterr().err
    assert f"argument {option}: found {value}; allowed: " in err and allowed in err


def test_the_first_table_is_shown_at_once_at_a_slow_rate(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """The first table waited a whole period from the clock's zero (at --rate 1e-9, 31
    years: for ever)."""
    assert main(["sensors", "--rate", "1e-9", "--count", "1"]) == 0
    assert "bumps_wheel_drops" in capsys.readouterr().out


def test_sensors_rides_through_a_stall_as_run_does(capsys: pytest.CaptureFixture[str]) -> None:
    """On a line dropping most frames the table goes on after each watchdog trip (it ended
    with exit 3 at the first: the tool one looks at a flaky line with died on it)."""
    from roomba_bt.oi.profiles import CREATE2

    with sim_pty_server(CREATE2, "--drop-rate", "0.7", "--seed", "3") as port:
        code = main(["sensors", "--port", port, "--count", "40", "--rate", "66"])
    err = capsys.readouterr().err
    assert code == 0, err
    assert "waiting up to 2 s for valid frames" in err and "valid frames are back" in err


@pytest.mark.parametrize("rate", [19200, 115200], ids=["query list", "stream"])
def test_sensors_interrupted_says_so_and_exits_130(
    rate: int, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """A Ctrl-C (or SIGINT) while the tables go on: exit 130 with the usual line, as every
    command; it exited 130 without a word."""
    from roomba_bt.cli import sensors_cmd

    def interrupted(*_: object) -> None:
        raise KeyboardInterrupt

    monkeypatch.setattr(sensors_cmd, "_print_table", interrupted)
    assert main(["sensors", "--baud", str(rate)]) == 130
    assert capsys.readouterr().err.strip().splitlines()[-1] == "roomba-bt: interrupted"


def test_a_lost_stream_says_sensors_waited_the_grace_not_a_run(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """``sensors`` during a stall that did not end said "then the run waited the 2 s grace":
    no run was there. Its own name now."""
    from roomba_bt.oi.profiles import CREATE2

    with sim_pty_server(CREATE2, "--sleep-at", "0.5", "--faults-from-stream") as port:
        code = main(["sensors", "--port", port, "--count", "1000", "--rate", "66"])
    err = capsys.readouterr().err
    assert code == 3, err
    assert "then roomba-bt sensors waited the 2 s grace" in err, err
    assert "the run" not in err, err


def test_a_robot_at_another_rate_is_said_at_the_rate_sensors_opened_it_at_not_a_run_s(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """``sensors`` on a robot that talks at 19200 said "the robot answers at 19200 baud, not
    at the 115200 of the run": no run was there. The rate is said as sensors' own (one
    function words it for both, the connection's user passed in)."""
    from roomba_bt.oi.profiles import CREATE2

    with sim_pty_server(CREATE2, "--baud", "19200") as port:
        code = main(["sensors", "--port", port, "--count", "1"])
    err = capsys.readouterr().err
    assert code == 3, err
    assert (
        "the robot answers at 19200 baud, not at the 115200 roomba-bt sensors opened it at:" in err
    )
    assert "the run" not in err, err


def test_sensors_on_a_cable_losing_bytes_says_what_it_lost_as_run_s_summary_does(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """``sensors`` on a cable that lost 1 % of the robot's bytes (more than half of its
    84-byte frames broken) showed its tables and exited 0 without a word of it: each table is
    the newest whole frame, and one came. At its end, the run summary's ``frames`` and
    ``link`` lines; nothing on a clean line."""
    from roomba_bt.oi.profiles import CREATE2

    with sim_pty_server(CREATE2, "--byte-drop-rate", "0.01", "--seed", "3") as port:
        code = main(["sensors", "--port", port, "--count", "150", "--rate", "66"])
    err = capsys.readouterr().err
    assert code == 0, err
    said = re.search(
        r"roomba-bt sensors: frames +(\d+) read, (\d+) lost, (\d+) checksum failures, 0 out of "
        r"range, (\d+) bytes skipped", err
    )  # fmt: skip
    assert said is not None, err
    read, lost, checksums, skipped = map(int, said.groups())
    assert read >= 150 and lost > 0.3 * (read + lost) and checksums > 0 and skipped > 0
    assert re.search(r"roomba-bt sensors: link +poor: \d+ % of the robot's frames lost", err), err
    cable = {link_of(port).check: "check the cable and its adapter"}  # the page's: a cable
    assert_quoted("docs/doctor.md", "roomba-bt sensors: frames", err, numbers=True)
    assert_quoted("docs/doctor.md", "roomba-bt sensors: link", err, numbers=True, names=cable)
    assert main(["sensors", "--count", "3"]) == 0  # the built-in simulator: a clean line
    assert "frames" not in capsys.readouterr().err
