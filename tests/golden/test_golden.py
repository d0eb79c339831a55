"""The simulator's bytes, scenario by scenario, against the recordings in recordings.json.

A failure means some bytes on the wire changed: a refactoring that should not change behaviour
did, or a deliberate change needs its recordings renewed (``make golden``, and say why in the
commit).
"""

from __future__ import annotations

import pytest

from roomba_bt.sim import Simulator

from .scenarios import CHECKPOINT_NS, SCENARIOS, load_recordings

RECORDED = load_recordings()


def test_every_scenario_is_recorded_and_every_recording_has_a_scenario() -> None:
    assert set(RECORDED) == set(SCENARIOS)


def first_difference(recorded: dict[str, object], now: dict[str, object]) -> str:
    old, new = recorded["checkpoints"], now["checkpoints"]
    assert isinstance(old, list) and isinstance(new, list)
    for i, (a, b) in enumerate(zip(old, new, strict=False)):
        if a != b:
            lo, hi = i * CHECKPOINT_NS / 1e9, (i + 1) * CHECKPOINT_NS / 1e9
            return f"first difference between t={lo:.0f} s and t={hi:.0f} s"
    return f"first difference after t={min(len(old), len(new)) * CHECKPOINT_NS / 1e9:.0f} s"


@pytest.mark.parametrize("name", sorted(SCENARIOS))
def test_bytes_are_as_recorded(name: str) -> None:
    now = SCENARIOS[name]().summary()
    recorded = RECORDED[name]
    if now["sha256"] != recorded["sha256"]:
        pytest.fail(
            f"{name}: bytes changed ({recorded['bytes']} recorded, {now['bytes']} now; "
            f"{first_difference(recorded, now)})"
        )


ONE_OF_EACH_KIND = ("sim/create2/empty-room", "fault/roomba600-corrupt",
                    "mission/bump-and-turn/corridor")  # fmt: skip


@pytest.mark.parametrize("name", ONE_OF_EACH_KIND)
def test_a_one_byte_change_is_caught(name: str, monkeypatch: pytest.MonkeyPatch) -> None:
    """One byte of what the simulator sends changed, 30 s into a session: the comparison
    sees it, in a scripted session, one with faults, and a whole mission episode."""
    read = Simulator.read

    def read_with_one_byte_changed(self: Simulator) -> bytes:
        data = read(self)
        if data and abs(self.time - 30.0) < 0.0075:
            data = bytes([data[0] ^ 0x01]) + data[1:]
        return data

    assert SCENARIOS[name]().summary()["sha256"] == RECORDED[name]["sha256"]
    monkeypatch.setattr(Simulator, "read", read_with_one_byte_changed)
    changed = SCENARIOS[name]().summary()
    assert changed["sha256"] != RECORDED[name]["sha256"]
    assert "between t=30 s and t=40 s" in first_difference(RECORDED[name], changed)


def test_every_kind_of_scenario_is_recorded() -> None:
    """Every profile in every shipped world, faults, and whole episodes of the shipped
    missions."""
    from roomba_bt.oi.profiles import PROFILES
    from roomba_bt.sim import shipped_worlds

    assert {f"sim/{p}/{w}" for p in PROFILES for w in shipped_worlds()} <= set(RECORDED)
    assert any(n.startswith("fault/") for n in RECORDED)
    missions = {n.split("/")[1] for n in RECORDED if n.startswith("mission/")}
    assert missions >= {"dock", "dock-builtin", "patrol", "bump-and-turn", "wall-follow"}
