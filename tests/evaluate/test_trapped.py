"""eval's "trapped" measure: the longest time off the dock without progress, brushes on or off.

The coverage block's idle line counts brush time only, so a robot trapped under a table's
chairs with its brushes off (the dock search, the way home) showed 0 there for 10 minutes
(the owner's dining room, session 34). The dock search has since learnt to leave such a trap,
so the test shuts the robot in a pen it cannot leave."""

from __future__ import annotations

from pathlib import Path

from roomba_bt.evaluate import EpisodeSpec, run_episode
from roomba_bt.evaluate.records import from_record, to_record
from roomba_bt.evaluate.stats import TRAPPED_S, summarize

MISSIONS = Path(__file__).resolve().parents[2] / "missions"
#: a robot shut in a pen 60 cm square (a playpen, a box fallen round it): whatever the dock
#: search tries, its centre stays within 13 cm of where it started
PEN = """
name: pen
rooms:
  - {rect: [0, 0, 4, 3]}
obstacles:
  - {name: pen-south, rect: [1.65, 1.15, 2.35, 1.20]}
  - {name: pen-north, rect: [1.65, 1.80, 2.35, 1.85]}
  - {name: pen-west, rect: [1.65, 1.15, 1.70, 1.85]}
  - {name: pen-east, rect: [2.30, 1.15, 2.35, 1.85]}
dock: {at: [2.0, 0.0], facing: 90}
robot:
  start: {at: [2.0, 1.5], heading: 0}
"""


def test_a_dock_search_shut_in_a_pen_is_said_trapped(tmp_path: Path) -> None:
    world = tmp_path / "pen.yaml"
    world.write_text(PEN)
    trapped = run_episode(
        EpisodeSpec(str(MISSIONS / "dock.yaml"), str(world), random_start=False,
                    timeout_s=900.0, trace_every=0)
    )  # fmt: skip
    assert trapped.outcome == "failure" and not trapped.docked, trapped.reason
    assert trapped.coverage is None  # no brush ran: the idle line cannot see it
    assert trapped.longest_trapped_s > 9 * TRAPPED_S  # its whole 10-minute search
    docked = run_episode(EpisodeSpec(str(MISSIONS / "dock.yaml"), "empty-room", seed=1))
    assert docked.succeeded and docked.docked
    assert docked.longest_trapped_s < TRAPPED_S  # the approach to the dock is progress

    summary = summarize("dock", "pen", [trapped, docked])
    line = next(line for line in summary.lines() if line.startswith("trapped"))
    assert line.startswith("trapped      1 of 2 episodes spent 60 s off the dock"), line
    assert f"longest {trapped.longest_trapped_s:.0f} s" in line
    said = summary.to_dict()
    assert said["trapped"] == 1 and said["longest_trapped"] == trapped.longest_trapped_s
    # eval --out keeps it, and reads it back
    assert from_record(to_record(trapped)).longest_trapped_s == trapped.longest_trapped_s


def test_a_results_file_from_before_the_measure_reads_as_zero() -> None:
    """Files written before the measure have no ``longest_trapped`` column."""
    record = to_record(run_episode(EpisodeSpec(str(MISSIONS / "dock.yaml"), "empty-room")))
    del record["longest_trapped"]
    assert from_record(record).longest_trapped_s == 0.0
