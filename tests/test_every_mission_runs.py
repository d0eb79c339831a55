"""Every mission file shipped in missions/ is loaded and run on the simulator.

Library files (subtrees only, no ``tree:``) are compiled through the missions that include
them. Each mission runs on the virtual clock for at most two minutes of mission time; it must
end in success, failure or that timeout, never in an invalid mission, a connection failure or
an exception, and the robot must be left stopped.
"""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from roomba_bt.cli import main

MISSIONS = Path(__file__).resolve().parents[1] / "missions"


def _has_tree(path: Path) -> bool:
    data = yaml.safe_load(path.read_text())
    return isinstance(data, dict) and "tree" in data


RUNNABLE = sorted(p for p in MISSIONS.rglob("*.yaml") if _has_tree(p))

#: Worlds a mission needs to make sense in (default: the empty room).
WORLDS = {"wall-follow.yaml": "corridor", "wall_follow.yaml": "corridor",
          "patrol.yaml": "corridor", "guarded_patrol.yaml": "corridor",
          "custom_condition.yaml": "corridor"}  # fmt: skip


def test_there_are_missions() -> None:
    assert len(RUNNABLE) >= 5


@pytest.mark.parametrize("path", RUNNABLE, ids=lambda p: str(p.relative_to(MISSIONS)))
def test_mission_runs_and_ends_safely(path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    world = WORLDS.get(path.name, "empty-room")
    code = main(["run", str(path), "--fast", "--display", "none", "--world", world,
                 "--timeout", "2min", "--seed", "3", "--allow-plugin-files"])  # fmt: skip
    out, err = capsys.readouterr()
    assert code in (0, 1), out + err
    assert "outcome      ERROR" not in out, out + err
    assert "Traceback" not in err
    assert "safe stop    sent" in out or "safe stop    nothing to send" in out, out
