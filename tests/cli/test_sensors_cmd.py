"""``roomba-bt sensors`` on the simulator: the largest group that fits the baud rate."""

from __future__ import annotations

import pytest

from roomba_bt.cli import main
from roomba_bt.cli.sensors_cmd import group_for
from roomba_bt.oi.encode import BAUD_CODES
from roomba_bt.oi.frames import stream_frame_size
from roomba_bt.oi.stream import stream_budget


@pytest.mark.parametrize("rate", sorted(BAUD_CODES))
def test_the_group_chosen_fits_the_rate(rate: int) -> None:
    group = group_for(rate)
    if group is None:
        assert stream_frame_size((1,)) > stream_budget(rate)  # not even the smallest
    else:
        assert stream_frame_size((group,)) <= stream_budget(rate)
    assert group_for(115200) == 100 and group_for(38400) == 6 and group_for(19200) == 1


@pytest.mark.parametrize(("rate", "last"), [(115200, 58), (38400, 42), (19200, 16)])
def test_sensors_shows_a_table_at_each_rate(
    rate: int, last: int, capsys: pytest.CaptureFixture[str]
) -> None:
    """At 19200 baud group 6 (a 56-byte frame) does not fit the 28 bytes of a slot: this
    used to end in a BandwidthError traceback."""
    assert main(["sensors", "--baud", str(rate), "--count", "1"]) == 0
    rows = [line.split()[0] for line in capsys.readouterr().out.splitlines()[1:] if line]
    assert rows[0] == "7" and rows[-1] == str(last)


def test_a_rate_too_slow_for_any_stream_is_a_clear_error(
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert main(["sensors", "--baud", "4800", "--count", "1"]) == 2
    err = capsys.readouterr().err
    assert "--baud 4800: no sensor stream fits in 15 ms" in err and "9600 or more" in err
