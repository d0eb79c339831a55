"""The summary printed at the end of every run: its lines, the reason a time limit gives, and
what it says of the robot's own falls to Passive; a run's outcome as an exception, for a
program that would rather not read it: ``stack.run().raise_for_outcome()``, as requests'
``raise_for_status``."""

from __future__ import annotations

from pathlib import Path

import py_trees
import pytest
from quoted import assert_quoted  # tests/quoted.py: the docs' quotes

from roomba_bt.behaviours.actions import Mode
from roomba_bt.evaluate.episode import failure_stage
from roomba_bt.oi.profiles import CREATE2
from roomba_bt.runtime.stack import RunStack, TreeMission
from roomba_bt.runtime.summary import ExitCode, Outcome, RunFailed, RunSummary
from roomba_bt.sim import SimLink, Simulator, load_world

from .simrun import DRIVE_TO_WALL, LEDGE, SHORT_DRIVE, TWICE_OVER_THE_EDGE, RunMission


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
    of mission time ran out"), and so was a Python caller's ``RunStack(timeout_s=90)``: the
    runtime says the limit as the thing it is, the command line as its flag. The end, "ran
    out in drive", is what ``failure_stage`` and eval's groups read, for each."""
    python = RunSummary("m")
    python.timed_out(90.0, " in drive")
    assert python.outcome is Outcome.TIMEOUT and python.exit_code == 1
    assert python.reason == "the run's 1 min 30 s of mission time ran out in drive"
    given = RunSummary("m", time_limit="--timeout 90 s")  # as ``run`` and ``eval`` name it
    given.timed_out(90.0, " in drive")
    assert given.reason == "--timeout 90 s of mission time ran out in drive"
    own = RunSummary("m", time_limit="--fast's own limit of 2 h")
    own.timed_out(7200.0, " in drive")
    assert own.outcome is Outcome.TIMEOUT and own.exit_code == 1
    assert own.reason == "--fast's own limit of 2 h of mission time ran out in drive"
    assert failure_stage(python.reason) == failure_stage(given.reason) == "drive"
    assert failure_stage(own.reason) == "drive"


def test_a_success_is_returned() -> None:
    summary = RunSummary("dock", Outcome.SUCCESS)
    assert summary.raise_for_outcome() is summary


@pytest.mark.parametrize("outcome", [o for o in Outcome if o is not Outcome.SUCCESS])
def test_every_other_outcome_raises_with_its_reason_and_exit_code(outcome: Outcome) -> None:
    summary = RunSummary("dock", outcome, reason="because")
    with pytest.raises(RunFailed) as raised:
        summary.raise_for_outcome()
    failed = raised.value
    assert failed.summary is summary and failed.outcome is outcome
    assert failed.reason == "because" and failed.exit_code == outcome.exit_code
    assert str(failed) == (
        f"mission dock ended {outcome.value.upper()}: because (exit code {int(outcome.exit_code)})"
    )


#: each outcome's exit code, as scripts and systemd units read them: 3 was a run that never
#: started and a link lost mid-run alike, and a service could not retry the one alone
EXIT_CODES = {
    Outcome.SUCCESS: 0,
    Outcome.FAILURE: 1,
    Outcome.TIMEOUT: 1,
    Outcome.INPUT_ENDED: 1,
    Outcome.NO_CONNECTION: 3,  # nothing of the mission sent: safe to retry
    Outcome.WRONG_PROFILE: 2,  # nothing of the mission sent, and a retry fails the same way
    Outcome.ERROR: 4,
    Outcome.HUNG: 4,
    Outcome.CONNECTION_LOST: 8,  # the robot may have moved: a person looks first
    Outcome.INTERRUPTED: 130,
}


@pytest.mark.parametrize("outcome", list(Outcome), ids=lambda outcome: outcome.name)
def test_each_outcome_exits_with_its_documented_code(outcome: Outcome) -> None:
    assert int(RunSummary("dock", outcome).exit_code) == EXIT_CODES[outcome]


def test_a_run_that_fails_raises_after_the_robot_is_stopped() -> None:
    root = py_trees.composites.Sequence("s", memory=True, children=[
        Mode("safe", {"to": "safe"}), py_trees.behaviours.Failure("refuses"),
    ])  # fmt: skip
    simulator = Simulator(load_world("empty-room"), CREATE2, seed=0)
    stack = RunStack(TreeMission(root, "fails"), SimLink(simulator), profile=CREATE2)
    try:
        with pytest.raises(RunFailed) as raised:
            stack.run().raise_for_outcome()
    finally:
        stack.close()
    assert raised.value.outcome is Outcome.FAILURE
    assert raised.value.exit_code is ExitCode.MISSION_FAILED
    assert raised.value.summary.stop_delivered and simulator.mode.label == "Passive"
    assert str(raised.value) == "mission fails ended FAILURE: refuses: failure (exit code 1)"


def test_the_exception_says_the_outcome_on_one_line() -> None:
    """As the summary's lines: a name holding a newline fakes no line of its own."""
    summary = RunSummary("faked\n[ok] robot stopped", Outcome.FAILURE, reason="x\x1b[2J")
    with pytest.raises(RunFailed) as raised:
        summary.raise_for_outcome()
    assert str(raised.value) == (
        "mission faked\\x0a[ok] robot stopped ended FAILURE: x\\x1b[2J (exit code 1)"
    )
    assert raised.value.reason == "x\x1b[2J"  # the field as it is


def test_the_robot_s_own_falls_are_counted_by_cause(
    run_mission: RunMission, tmp_path: Path
) -> None:
    """The connection logs the first fall of a cause as a WARNING and the rest at INFO
    ('..., 7 times so far'); the summary said none of them."""
    (tmp_path / "ledge.yaml").write_text(LEDGE)
    run = run_mission(TWICE_OVER_THE_EDGE, world=str(tmp_path / "ledge.yaml"))
    assert run.summary.outcome is Outcome.FAILURE  # the second drive: over the edge again
    assert run.summary.falls == {"cliff": 2}
    assert "falls        the robot fell to Passive by itself 2 times (cliff)" in str(run.summary)


#: three ``log`` leaves: the last said at info or above is the summary's
SAYS = """
tree:
  sequence:
    - log: first
    - wait: 0.1s
    - log: "second, said last"
    - log: {message: tracing, level: debug}
"""


def test_the_mission_s_last_log_is_said_under_its_outcome(run_mission: RunMission) -> None:
    """A success by a way out (a patrol docked on a low battery before any lap) read as any
    success: the mission's own last words (a ``log`` leaf, not one at ``debug``, the
    author's tracing) are the ``mission said`` line; a mission that says nothing has none."""
    summary = run_mission(SAYS).summary
    assert summary.outcome is Outcome.SUCCESS
    assert summary.said == "second, said last"
    lines = summary.lines()
    assert lines[lines.index("outcome      SUCCESS") + 1] == "mission said second, said last"
    assert "mission said" not in str(run_mission(DRIVE_TO_WALL).summary)


def test_a_long_log_message_and_label_are_cut_on_their_lines(
    run_mission: RunMission, caplog: pytest.LogCaptureFixture
) -> None:
    """A ``log`` message of 200,000 characters (a default, a ``-p``) was written whole to
    the log, the live tree and the summary's ``mission said``, and a record's hand-edited
    label whole to a replay's ``label`` line: each is cut, its length said."""
    long = "M" * 200_000
    with caplog.at_level("INFO", logger="roomba_bt.mission"):
        summary = run_mission(f"tree: {{log: {long}}}").summary
    cut = f"{'M' * 500}... (200,000 characters)"
    assert summary.said == cut
    assert [r.getMessage() for r in caplog.records if r.name == "roomba_bt.mission"] == [cut]
    summary.label = "L" * 100_000
    lines = summary.lines()
    assert lines[0] == f"label        {'L' * 80}... (100,000 characters)"
    assert f"mission said {cut}" in lines


def test_a_run_without_falls_has_no_falls_line(run_mission: RunMission) -> None:
    run = run_mission(DRIVE_TO_WALL)
    assert run.summary.outcome is Outcome.SUCCESS
    assert run.summary.falls == {}
    assert "falls" not in str(run.summary)


def test_falls_of_several_causes_are_said_the_commonest_first() -> None:
    summary = RunSummary("m", falls={"wheel drop": 1, "cliff": 20})
    assert "falls        the robot fell to Passive by itself 21 times (cliff 20, wheel drop 1)" in (
        summary.lines()
    )
    assert_quoted("docs/runtime.md", "falls the robot fell", "\n".join(summary.lines()))
    summary = RunSummary("m", falls={"charger": 1, "cliff": 2})
    assert summary.falls_text() == "the robot fell to Passive by itself 2 times (cliff)"
    assert "charger      docked once" in summary.lines()


def test_the_refusals_warning_names_the_strict_check_as_its_caller_sets_it() -> None:
    """A Python caller's summary said "--strict fails such a run", a flag it never typed;
    the command line still names its flag."""
    summary = RunSummary("m", Outcome.SUCCESS, refused_commands=3)
    assert summary.lines()[-1].endswith(": the strict check fails such a run (exit 7)")
    summary.strict_named = "--strict"
    assert summary.lines()[-1].endswith(": --strict fails such a run (exit 7)")


@pytest.mark.parametrize(
    ("seconds", "said"),
    [(3.0, ""), (59.9, ""), (60.0, " (1 min)"), (90.4, " (1 min 30 s)"),
     (15123.0, " (4 h 12 min 3 s)"), (43200.0, " (12 h)"), (93784.0, " (1 d 2 h 3 min 4 s)")],
)  # fmt: skip
def test_a_long_duration_is_said_in_hours_and_minutes_too(seconds: float, said: str) -> None:
    """The soak: "43200.00 s mission time, 209.05 s wall" after a night. The seconds stay
    (scripts read them), and a minute or more is said as a person says it too."""
    summary = RunSummary("m", mission_time_s=seconds, wall_time_s=seconds)
    assert f"duration     {seconds:.2f} s mission time{said}, {seconds:.2f} s wall{said}" in (
        summary.lines()
    )


def test_dockings_are_counted_apart_from_the_falls_with_the_time_on_the_charger() -> None:
    """A patrol that docks ten times read "the robot fell to Passive by itself 10 times
    (charger)": ten faults, to a reader. The OI's drop to Passive on the charger is how a
    docking ends: the charger line counts it, with the hours on the charger; the falls line
    keeps the hazards."""
    summary = RunSummary("m", falls={"charger": 10}, on_charger_s=48603.0)
    lines = summary.lines()
    assert "charger      docked 10 times, on it 13 h 30 min 3 s in all" in lines
    assert not [line for line in lines if line.startswith("falls")]
    summary.falls["cliff"] = 1
    assert "falls        the robot fell to Passive by itself once (cliff)" in summary.lines()
    assert RunSummary("m", on_charger_s=0.5).charger_text() == ""  # the dock's last frame
    assert RunSummary("m", on_charger_s=75.0).charger_text() == "on it 1 min 15 s in all"
    # docs/runtime.md's night: two dockings, 2 h 41 min on the charger
    page = RunSummary("m", falls={"charger": 2}, on_charger_s=2 * 3600 + 41 * 60)
    assert_quoted("docs/runtime.md", "charger docked 2 times", "\n".join(page.lines()))


def test_the_lowest_battery_level_is_said_when_it_was_lower_than_the_last() -> None:
    assert RunSummary("m", battery_percent=46.2, lowest_battery_percent=18.4).battery_text() == (
        "46%, the lowest 18%"
    )
    assert RunSummary("m", battery_percent=46.2, lowest_battery_percent=45.9).battery_text() == (
        "46%"
    )
    assert RunSummary("m").battery_text() == "n/a"
    page = RunSummary("m", battery_percent=67.3, lowest_battery_percent=19.8)  # docs/runtime.md's
    assert_quoted("docs/runtime.md", "battery 67%", "\n".join(page.lines()))


DOCK_AND_REST = """\
mission: dock and rest
include: [roomba-bt:lib/docking.yaml]
tree:
  sequence:
    - subtree: {id: dock}
    - mode: passive
    - wait: 2min
"""


def test_a_run_counts_its_time_on_the_charger_and_its_lowest_battery(
    run_mission: RunMission,
) -> None:
    """Looked at once a second of mission time (runtime/long_run.py): the two minutes of
    rest on the charger, to the second, and the battery's low point before it charged."""
    run = run_mission(DOCK_AND_REST, timeout=None)
    summary = run.summary
    assert summary.outcome is Outcome.SUCCESS
    assert summary.falls == {"charger": 1}
    assert 119.0 <= summary.on_charger_s <= 121.0
    assert summary.lowest_battery_percent is not None and summary.battery_percent is not None
    assert summary.lowest_battery_percent < summary.battery_percent  # it charged
    assert "charger      docked once, on it 2 min in all" in summary.lines()


@pytest.mark.parametrize(
    ("seconds", "said"),
    [(86400.0, "1 d"), (90000.0, "1 d 1 h"), (5400.0, "1 h 30 min"), (7200.0, "2 h"),
     (45.0, "45 s"), (0.25, "0.25 s"), (60.0, "1 min"), (90.5, "90.5 s")],
)  # fmt: skip
def test_a_duration_a_message_names_reads_as_a_person_says_it(seconds: float, said: str) -> None:
    """``--timeout 1d`` ran out as "the run's 86400 s" (and ``--timeout 86400 s``): one
    spelling for every message that names a limit, below every layer (``printable``)."""
    from roomba_bt.printable import duration_said

    assert duration_said(seconds) == said
    summary = RunSummary("m")
    summary.timed_out(seconds, "")
    assert summary.reason == f"the run's {said} of mission time ran out"


@pytest.mark.parametrize(
    ("virtual", "said"),
    [
        (True, "(2010 over 15 ms of host time, none late on the virtual clock; slowest 313.68 ms)"),
        (False, "(2010 overruns > 15 ms, slowest 313.68 ms)"),
    ],
)
def test_slow_ticks_on_the_virtual_clock_are_not_called_overruns(virtual: bool, said: str) -> None:
    """An 8-hour ``--fast`` run said "2010 overruns > 15 ms" of a clock that waits for each
    tick: noise. There the count is of host time, said to have made no tick late."""
    summary = RunSummary(mission="m", ticks=1920001, overruns=2010, max_tick_s=0.31368)
    summary.virtual_clock = virtual
    line = next(x for x in str(summary).splitlines() if x.startswith("ticks"))
    assert line == f"ticks        1920001 {said}"


@pytest.mark.parametrize(
    ("packets", "final"),
    [
        (None, "Passive"),
        ((7, 9, 10, 11, 12, 43, 44), "Passive (not in the stream: the run's own model)"),
    ],
    ids=["packet 35 streamed", "no packet 35"],
)
def test_the_final_mode_of_a_stream_without_packet_35_is_said_as_the_models(
    packets: tuple[int, ...] | None, final: str
) -> None:
    """A program's own packet list without packet 35 (the OI mode): the summary's ``final
    mode`` read ``Passive`` as if the robot had shown it, where it was only what the run had
    written (the mode model, never checked against the robot). It says whose it is; with
    packet 35 streamed, the mode as ever."""
    from roomba_bt import load_mission_text

    stack = RunStack(
        load_mission_text(SHORT_DRIVE),
        SimLink(Simulator(load_world("empty-room"), CREATE2)),
        profile=CREATE2,
        packets=packets,
        timeout_s=30.0,
    )
    with stack:
        summary = stack.run()
    assert summary.outcome is Outcome.SUCCESS, summary
    assert summary.final_mode_text() == final
    assert f"final mode   {final}" in summary.lines()
    if packets is not None:
        assert_quoted("docs/runtime.md", "final mode Passive (not in", "\n".join(summary.lines()))


def test_an_unconfirmed_stop_of_a_robot_the_run_set_nothing_going_is_said_calmly() -> None:
    """A robot seen only in Passive, its wheels never commanded (a Roomba 500 read with the
    Create 2's profile), its stop unconfirmed: the run may have left nothing moving, so the
    final mode says so rather than "the stop was not delivered" (docs/runtime.md)."""
    from roomba_bt.oi.modes import OIMode

    summary = RunSummary(
        "m", final_mode=OIMode.PASSIVE, stop_delivered=False, set_nothing_going=True
    )
    assert_quoted("docs/runtime.md", "final mode unknown: last seen in Passive, the run set",
                  "\n".join(summary.lines()))  # fmt: skip
    summary.set_nothing_going = False
    assert "the run set nothing going" not in "\n".join(summary.lines())
