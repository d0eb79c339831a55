"""The wall-clock limit held by the monitor's pause (``runtime/wall_limit.py``): the time held
does not count, and the count goes on after it."""

from __future__ import annotations

import time

import pytest

from roomba_bt.runtime.wall_limit import WallLimit, WallLimitReached


def test_a_held_limit_does_not_run_out_and_runs_out_after_the_release() -> None:
    limit = WallLimit(0.3)
    with pytest.raises(WallLimitReached), limit:
        limit.hold(True)
        held_from = time.monotonic()
        while time.monotonic() - held_from < 0.6:  # twice the limit, held: nothing raised
            pass
        assert not limit.reached
        limit.hold(False)
        released = time.monotonic()
        while time.monotonic() - released < 30:  # stuck after the resume: the rest ends it
            pass
    assert limit.reached
