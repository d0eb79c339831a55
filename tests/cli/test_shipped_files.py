"""The shipped missions and worlds can be read from an installed wheel: `roomba-bt missions
NAME` and `roomba-bt worlds [NAME]` print them (a newcomer found them only by opening the
package's folder: the docs say each mission is documented at its top)."""

from __future__ import annotations

import pytest

from roomba_bt.cli import main
from roomba_bt.mission.shipped import shipped_missions
from roomba_bt.sim.world import WORLDS_DIR, parse_world, shipped_worlds


@pytest.mark.parametrize("name", sorted(shipped_missions()))
def test_a_shipped_mission_is_printed_with_its_comments(
    name: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["missions", name]) == 0
    assert capsys.readouterr().out == shipped_missions()[name].read_text(encoding="utf-8")


def test_a_library_file_is_printed_and_an_unknown_name_is_refused(
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert main(["missions", "lib/docking"]) == 0
    assert "subtrees:" in capsys.readouterr().out
    assert main(["missions", "dok"]) == 2
    err = capsys.readouterr().err
    assert "no shipped mission or library file 'dok' (did you mean 'dock'?)" in err
    assert "lib/docking" in err


def test_worlds_lists_each_shipped_world_and_prints_one(
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert main(["worlds"]) == 0
    out = capsys.readouterr().out
    for name in shipped_worlds():
        assert f"\n{name}  " in f"\n{out}"
    assert "8 x 6 m, a dock; areas: living-room, bedroom, kitchen" in out
    assert main(["worlds", "apartment"]) == 0
    text = capsys.readouterr().out
    assert text == (WORLDS_DIR / "apartment.yaml").read_text(encoding="utf-8")
    assert parse_world(text, "apartment.yaml").name == "apartment"
    assert main(["worlds", "apartmnt"]) == 2
    assert "roomba-bt worlds: no shipped world 'apartmnt' (did you mean 'apartment'?)" in (
        capsys.readouterr().err
    )
