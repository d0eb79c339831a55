"""The shipped clean.yaml: covers more of a room than the firmware's Clean on the same start,
docks when the battery runs low, ends when the floor is done, with and without the encoders'
error."""

from __future__ import annotations

from pathlib import Path

import pytest

from roomba_bt.evaluate import EpisodeSpec, run_episode
from roomba_bt.evaluate.episode import EpisodeResult

from .conftest import MISSIONS


def _living_room(mission: str, seed: int, minutes: int, **fields: object) -> EpisodeResult:
    spec = EpisodeSpec(
        str(MISSIONS / f"{mission}.yaml"), "apartment", seed,
        params=(("duration", f"{minutes}min"),), timeout_s=minutes * 60.0 + 30.0,
        start_area="living-room", **fields,  # type: ignore[arg-type]
    )  # fmt: skip
    return run_episode(spec)


def test_clean_covers_more_than_the_builtin_clean_on_the_same_start() -> None:
    ours = _living_room("clean", 3, 10)
    builtin = _living_room("clean-builtin", 3, 10)
    assert ours.start == builtin.start
    assert ours.coverage is not None and builtin.coverage is not None
    assert ours.coverage.final >= 0.7
    assert ours.coverage.final >= builtin.coverage.final + 0.1
    assert ours.coverage.longest_idle_s < 60.0
    assert ours.violations == 0 and not ours.fell


@pytest.mark.parametrize("odometry_error", [0.0, 0.015])
def test_clean_docks_when_the_battery_runs_low(odometry_error: float) -> None:
    spec = EpisodeSpec(
        str(MISSIONS / "clean.yaml"), "apartment", seed=4, battery=0.153, timeout_s=900.0,
        odometry_error=odometry_error,
    )  # fmt: skip
    result = run_episode(spec)
    assert result.outcome == "success", result.reason
    assert result.docked and result.charging
    assert result.coverage is not None and result.coverage.cleaning_s > 0


def test_clean_in_a_small_room_ends_when_the_floor_is_done_and_goes_home() -> None:
    """Done before its 20 minutes, it docks as the firmware's Clean does (it stayed where it
    stopped: a robot left in the middle of the room, its battery running down)."""
    result = run_episode(
        EpisodeSpec(str(MISSIONS / "clean.yaml"), "empty-room", seed=1, timeout_s=1300.0)
    )
    assert result.outcome == "success", result.reason
    assert result.coverage is not None and result.coverage.overall >= 0.9
    assert result.coverage.cleaning_s < 1200.0  # before the 20 minutes: it knew it was done
    assert result.docked and result.charging


def test_clean_without_going_home_or_without_a_dock_ends_where_it_stopped(
    tmp_path: Path,
) -> None:
    """``-p go_home=false`` stays; in a world with no dock the way home fails after its
    time limit, and the cleaning done is still a success (the log says why it stayed)."""
    stay = run_episode(
        EpisodeSpec(str(MISSIONS / "clean.yaml"), "empty-room", seed=1, timeout_s=1300.0,
                    params=(("go_home", "false"),))
    )  # fmt: skip
    assert stay.outcome == "success", stay.reason
    assert not stay.docked
    world = tmp_path / "no-dock.yaml"
    world.write_text("rooms: [[[0, 0], [3, 0], [3, 2.5], [0, 2.5]]]\n")
    homeless = run_episode(
        EpisodeSpec(str(MISSIONS / "clean.yaml"), str(world), seed=1, timeout_s=600.0,
                    params=(("duration", "1min"), ("dock_time_limit", "1min")))
    )  # fmt: skip
    assert homeless.outcome == "success", homeless.reason
    assert not homeless.docked and 120.0 <= homeless.time_s < 200.0
