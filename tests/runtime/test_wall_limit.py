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


def test_a_limit_that_runs_out_outside_every_behaviour_says_nothing_was_stuck() -> None:
    """A run still going (waiting for its next frame in roomba-bt's own code) when its
    ``--wall-limit`` runs out: the reason said only ``at .../sim/link.py:201``, which read as
    a bug in roomba-bt (a verifier's finding); it says no behaviour was stuck."""
    import sys
    import traceback

    from roomba_bt.runtime.wall_limit import ran_out

    frames = list(traceback.walk_stack(sys._getframe()))[::-1]  # outermost first: no behaviour
    behaviour, said = ran_out(10.0, frames)
    assert behaviour is None
    assert said.startswith("--wall-limit 10 s of wall-clock time ran out outside every ")
    assert "no behaviour was stuck, the run was still going" in said, said
    assert said.rstrip(")").endswith("a run this long needs a longer limit"), said
