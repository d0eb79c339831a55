"""A ``drive`` with no end of its own and no bumper read while it runs is warned of: Safe
and Full do not stop at a wall (session 37's stranger ran docs/missions.md's ``held``
example, guarded by the battery alone: it pushed on the apartment's first wall for the 2
hours of ``--fast``)."""

from __future__ import annotations

import pytest

from roomba_bt.mission import load_mission_text

HEAD = "mission: m\nblackboard:\n  here: mark\ntree:\n  sequence:\n    - mode: safe\n"
PUSHES = "pushes on the first one it meets"


def _warnings(body: str) -> list[str]:
    mission = load_mission_text(HEAD + body)
    return [f"{w.line}:{w.column}: {w.message}" for w in mission.warnings if PUSHES in w.message]


def test_a_drive_guarded_by_the_battery_alone_is_warned_of() -> None:
    body = (
        "    - drive: {velocity: 200 mm/s}\n"
        "      until: {held: {for: 3s, do: {battery: {below: 15%}}}}\n"
    )
    [said] = _warnings(body)
    assert said.startswith("7:7: drive(velocity=200 mm/s) has no end of its own"), said
    assert "also end it on a bump (until: {fallback: [{bump: any}, ...]})" in said


@pytest.mark.parametrize(
    "body",
    [
        # a bump beside the battery (the example as it is now)
        "    - drive: {velocity: 200 mm/s}\n"
        "      until: {fallback: [{bump: any}, {battery: {below: 15%}}]}\n",
        # a light bumper; a while: that fails at a bump
        "    - drive: {velocity: 200 mm/s}\n      until: {light_bumper: {sensor: any}}\n",
        "    - drive: {velocity: 200 mm/s}\n      while: {inverter: {bump: any}}\n",
        # ends of its own, a distance by odometry, a timeout around it
        "    - drive: {velocity: 200 mm/s, distance: 1 m}\n",
        "    - drive: {velocity: 200 mm/s, duration: 5s}\n",
        "    - mark: {key: here}\n    - drive: {velocity: 200 mm/s}\n"
        "      until: {odometry: {since: here, distance: 1 m}}\n",
        "    - timeout: {after: 10s, do: {drive: {velocity: 200 mm/s}}}\n",
        # an earlier child of a reactive parent, a parallel branch, that read the bumper
        "    - reactive_sequence: [{inverter: {bump: any}}, {drive: {velocity: 200 mm/s}}]\n",
        "    - parallel:\n        policy: one\n"
        "        children: [{drive: {velocity: 200 mm/s}}, {bump: any}]\n",
        # a drive that does not move
        "    - drive: {velocity: 0 mm/s}\n      until: {battery: {below: 15%}}\n",
    ],
)
def test_a_drive_a_bump_or_its_own_end_stops_is_not(body: str) -> None:
    assert _warnings(body) == []
