"""``dock_search`` shuttling between two blocked headings from the same two places: noticed
and left.

Fresh apartment start 324 (``roomba-bt eval dock --world apartment --seed 324 --runs 1``):
(5.33, 1.55) m, heading 103 deg. At 124 s the search came into the kitchen's north-east
corner (the table, the counter and the north wall about 0.5 m apart) and from then on
chose two opposite headings in turn: a 36 cm leg north until something was met, a
back-off, a turn round, 36 cm south, every 6 s, 79 legs until the 10-minute limit. The trap
rule never fired: the two ends lie 29 cm apart (out of its 0.5 m circle) and a hazard came
only every 6 s (it wants ten in 30 s). Now eight legs in a row ended by a hazard, each begun
within 3 cm of where the leg two before began and on its heading, make the search want a
wall: the next obstacle is followed out of there. It docks in 308 s.
"""

from __future__ import annotations

from pathlib import Path

from roomba_bt.evaluate import EpisodeSpec, run_episode

ROOT = Path(__file__).resolve().parents[2]
DOCK = ROOT / "missions" / "dock.yaml"


def test_a_shuttle_between_two_blocked_headings_is_left_and_the_dock_found() -> None:
    result = run_episode(EpisodeSpec(str(DOCK), "apartment", seed=324, trace_every=0))
    assert result.start[:2] == (5.329808516, 1.549130181)  # the start the shuttle began from
    assert result.outcome == "success", result.reason
    assert result.docked and result.charging
