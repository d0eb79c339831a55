"""The summary printed at the end of every run: its lines, and the reason a time limit gives."""

from __future__ import annotations

from roomba_bt.evaluate.episode import failure_stage
from roomba_bt.runtime.summary import Outcome, RunSummary


def test_each_line_of_the_summary_stays_one_line() -> None:
    """The mission's name, the reason and the operator's forces quote what a mission's author
    wrote: "\\n[ok] robot stopped" printed raw faked a line of the summary, "\\x1b[2J"
    cleared the screen. They are escaped; the fields keep them as they are."""
    summary = RunSummary("faked\n[ok] robot stopped", Outcome.FAILURE, reason="x\x1b[2J")
    summary.forced = ["never\n[ok] fake to SUCCESS at tick 3 (t=0.045 s)"]
    lines = summary.lines()
    assert str(summary).splitlines() == lines
    assert not [line for line in lines if line.startswith("[ok]") or "\x1b" in line]
    assert lines[0] == "mission      faked\\x0a[ok] robot stopped"
    assert "outcome      FAILURE (x\\x1b[2J)" in lines
    assert (
        "forced       by the operator: never\\x0a[ok] fake to SUCCESS at tick 3 (t=0.045 s)"
        in lines
    )
    assert summary.mission == "faked\n[ok] robot stopped"


def test_a_time_limit_says_whose_it_is_and_keeps_the_stage_a_script_reads() -> None:
    """``run --fast``'s own limit was said as a ``--timeout`` nobody gave ("--timeout 7200 s
    of mission time ran out"); the end, "ran out in drive", is what ``failure_stage`` and
    eval's groups read, for either."""
    given = RunSummary("m")
    given.timed_out(90.0, " in drive")
    assert given.outcome is Outcome.TIMEOUT and given.exit_code == 1
    assert given.reason == "--timeout 90 s of mission time ran out in drive"
    own = RunSummary("m", time_limit="--fast's own limit of 7200 s")
    own.timed_out(7200.0, " in drive")
    assert own.outcome is Outcome.TIMEOUT and own.exit_code == 1
    assert own.reason == "--fast's own limit of 7200 s of mission time ran out in drive"
    assert failure_stage(given.reason) == failure_stage(own.reason) == "drive"
