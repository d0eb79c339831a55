"""The episode's bump reaction, measured on the simulator's requested wheel speeds: the
forward motion ends in the bump frame's own tick (the bump reflex's drive 0) and the back-off
comes one frame later (the tree, once the second frame confirms the bump)."""

from __future__ import annotations

from pathlib import Path

from roomba_bt.evaluate.episode import EpisodeResult, EpisodeSpec, run_episode
from roomba_bt.evaluate.report import bump_lines
from roomba_bt.evaluate.stats import summarize

MISSION = Path(__file__).resolve().parents[2] / "missions" / "bump-and-turn.yaml"


def test_every_bump_stops_forward_motion_in_its_frame_and_backs_off_in_the_next() -> None:
    spec = EpisodeSpec(str(MISSION), "corridor", seed=1, params=(("duration", "30s"),),
                       timeout_s=40.0)  # fmt: skip
    result: EpisodeResult = run_episode(spec)
    assert result.bumps >= 2, "the scenario must actually bump into walls"
    assert len(result.reaction_steps) >= result.bumps - 1  # the last may end the run
    assert set(result.reaction_steps) == {(0, 1)}, result.reaction_steps
    assert max(result.contact_steps) <= 2
    lines = bump_lines(summarize("bump-and-turn.yaml", "corridor", [result]), [result])
    stops = len(result.reaction_steps)
    assert f"to the write that ended forward motion: 0: {stops};" in lines[1]
