"""Coverage across episodes: spreads at fixed times, per area, stuck runs; eval's options."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import pytest

from roomba_bt.cli import main
from roomba_bt.evaluate import EpisodeSpec, run_episode
from roomba_bt.evaluate.coverage import STUCK_S, summarize_coverage
from roomba_bt.evaluate.episode import Coverage

MISSIONS = Path(__file__).resolve().parents[2] / "missions"
SWEEP = """
mission: sweep
tree:
  sequence:
    - mode: full
    - motors: {main_brush: true, side_brush: true, vacuum: true}
    - drive: {velocity: 200 mm/s, radius: 400 mm, duration: 40s}
    - mode: passive
"""


def coverage(final: float, idle: float) -> Coverage:
    curve = tuple((t * 30.0, final * min(1.0, t / 20)) for t in range(41))
    return Coverage("living-room", final, curve, final / 2, (("living-room", final),), idle, 1200)


def test_spreads_at_fixed_times_per_area_and_stuck_runs(tmp_path: Path) -> None:
    mission = tmp_path / "sweep.yaml"
    mission.write_text(SWEEP)
    result = run_episode(
        EpisodeSpec(str(mission), "apartment", seed=1, timeout_s=90, start_area="living-room")
    )
    assert result.coverage is not None and result.coverage.area == "living-room"
    assert 0.0 < result.coverage.at(30.0) <= result.coverage.final <= 1.0
    a = replace(result, time_s=1200.0, coverage=coverage(0.8, 10.0))
    b = replace(result, time_s=1200.0, coverage=coverage(0.6, STUCK_S + 5))
    summary = summarize_coverage([a, b])
    assert summary is not None
    at = dict(summary.at)
    assert at[600.0].mean == pytest.approx(0.7) and at[1200.0].low == pytest.approx(0.6)
    assert summary.stuck == 1 and summary.longest_idle_s == STUCK_S + 5
    assert "living-room" in str(summary)
    assert summarize_coverage([replace(a, coverage=None)]) is None


def test_eval_refuses_an_unknown_start_area(capsys: pytest.CaptureFixture[str]) -> None:
    code = main(["eval", str(MISSIONS / "dock.yaml"), "--world", "apartment", "--runs", "1",
                 "--start-area", "attic", "--no-progress"])  # fmt: skip
    assert code == 2
    assert "living-room, bedroom, kitchen" in capsys.readouterr().err


def test_areas_an_episode_could_not_reach_are_said_not_dropped(tmp_path: Path) -> None:
    """The per-area lines took their names from the first episode: one that started in the
    kitchen (behind its virtual wall) hid the other rooms from the whole report. Every area
    any episode reached is listed, in the world's order, with how many reached it, and the
    episodes whose reachable floor was only a part are counted."""
    mission = tmp_path / "sweep.yaml"
    mission.write_text(SWEEP)
    result = run_episode(EpisodeSpec(str(mission), "apartment", seed=1, timeout_s=5))

    def cleaned(by_area: tuple[tuple[str, float], ...]) -> Coverage:
        return Coverage("", 0.5, ((0.0, 0.0),), 0.5, by_area, 1.0, 60.0)

    kitchen_only = replace(result, coverage=cleaned((("kitchen", 0.9),)))
    whole = replace(
        result,
        coverage=cleaned((("living-room", 0.4), ("bedroom", 0.2), ("kitchen", 0.1))),
    )
    summary = summarize_coverage([kitchen_only, whole, whole])
    assert summary is not None
    assert [name for name, _ in summary.by_area] == ["living-room", "bedroom", "kitchen"]
    assert dict(summary.reached) == {"living-room": 2, "bedroom": 2, "kitchen": 3}
    assert summary.partial == 1
    text = str(summary)
    assert (
        "living-room   40.0 % (sd  0.0, 40.0..40.0) at the end (2 of 3 episodes reached it)" in text
    )
    assert "kitchen       36.7 %" in text and "kitchen       36.7 % (sd" in text
    assert "1 of 3 episodes could reach only part of the floor" in text
    assert summary.to_dict()["reached"] == {"living-room": 2, "bedroom": 2, "kitchen": 3}
    alike = summarize_coverage([whole, whole])
    assert alike is not None and alike.partial == 0 and "reached it" not in str(alike)


def test_an_episode_that_ended_between_samples_reads_its_final_coverage_later(
    tmp_path: Path,
) -> None:
    """The curve is sampled every 30 s: an episode that ended at 40 s read, at any later
    report time, its 30-s sample (the last 10 s of cleaning left out of "at 20 min" for a
    run whose map said the floor was done early)."""
    mission = tmp_path / "cover.yaml"
    mission.write_text(
        "tree:\n  sequence:\n    - mode: full\n"
        "    - motors: {main_brush: true, side_brush: true, vacuum: true}\n"
        "    - cover: {}\n"
    )
    result = run_episode(EpisodeSpec(str(mission), "empty-room", seed=1, timeout_s=45))
    coverage = result.coverage
    assert coverage is not None and 40.0 <= result.time_s < 60.0, result.reason
    assert coverage.at(30.0) < coverage.final
    assert coverage.at(60.0) == coverage.at(1200.0) == coverage.final
