"""The shipped clean.yaml: covers more of a room than the firmware's Clean on the same start,
docks when the battery runs low, ends when the floor is done, with and without the encoders'
error."""

from __future__ import annotations

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


def test_clean_in_a_small_room_ends_when_the_floor_is_done() -> None:
    result = run_episode(
        EpisodeSpec(str(MISSIONS / "clean.yaml"), "empty-room", seed=1, timeout_s=1300.0)
    )
    assert result.outcome == "success", result.reason
    assert result.time_s < 1200.0  # before the 20 minutes: it knew it was done
    assert result.coverage is not None and result.coverage.overall >= 0.9
    assert not result.docked  # done, not a low battery: no dock


@pytest.mark.parametrize("minutes", [1, 7])
def test_the_builtin_clean_ends_at_its_duration_within_a_cycle(minutes: int) -> None:
    """``-p duration=7min`` cleaned 10 minutes: ``repeat: {for: ...}`` stops only between
    its 5-minute cycles. The cleaning stops at the duration, the motors off, in Passive."""
    result = _living_room("clean-builtin", 3, minutes)
    assert result.outcome == "success", result.reason
    assert minutes * 60.0 <= result.time_s < minutes * 60.0 + 1.0
    assert result.coverage is not None
    assert result.coverage.cleaning_s == pytest.approx(minutes * 60.0, abs=1.0)
