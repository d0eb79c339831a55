"""The summary printed at the end of every run."""

from __future__ import annotations

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
