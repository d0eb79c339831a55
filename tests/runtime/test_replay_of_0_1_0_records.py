"""A record made by roomba-bt 0.1.0 (its header names no ``roomba_bt_version``): its replay
says so when the bytes differ, with where the changes are listed, and when its mission no
longer compiles, that the mission (not the record) is refused and how to replay it with the
fixed file (``--mission``). 0.2.0 said only an opcode difference, or only the validation
errors; the upgrader had to work out the cause and find ``--mission`` alone."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from quoted import assert_quoted  # tests/quoted.py: the docs' quotes

from roomba_bt import __version__
from roomba_bt.cli import main
from roomba_bt.oi.profiles import CREATE2
from roomba_bt.sim import SimLink, Simulator, load_world
from runtime.simrun import record_run  # tests/runtime: a run recorded

Capsys = pytest.CaptureFixture[str]

#: the mission as it is recorded, and run again with another wait (the bytes differ)
MISSION = (
    "mission: m\n{parameters}tree:\n  sequence:\n    - mode: safe\n    - wait: {wait}\n"
    "    - mode: passive\n"
)
#: a parameter that 0.1.0 accepted and 0.2.0 refuses (``choices:`` on an int)
REFUSED = "parameters:\n  n: {type: int, default: 1, choices: [1, 2]}\n"
FIXED = "parameters:\n  n: {type: int, default: 1}\n"
SAID = (
    "replay: recorded by roomba-bt 0.1.0 or earlier, as the record names no release; this is "
    f'{__version__}: what replays differently is in the CHANGELOG, "Upgrading from 0.1.0"'
)


def _mission(path: Path, parameters: str = "", wait: str = "0.1s") -> Path:
    path.write_text(MISSION.format(parameters=parameters, wait=wait), encoding="utf-8")
    return path


def _recorded_as_0_1_0(tmp_path: Path, parameters: str = "") -> tuple[Path, Path]:
    """A record of the mission (``tmp_path/m.yaml``, returned too), its header as 0.1.0
    wrote it: no release, no sources, no plugins."""
    record = record_run(tmp_path, SimLink(Simulator(load_world("empty-room"), CREATE2, 0)),
                        MISSION.format(parameters=parameters, wait="0.1s"))  # fmt: skip
    header, *rest = record.read_text(encoding="utf-8").splitlines(keepends=True)
    made = {k: v for k, v in json.loads(header).items()
            if k not in ("roomba_bt_version", "sources", "plugins")}  # fmt: skip
    record.write_text("".join([json.dumps(made) + "\n", *rest]), encoding="utf-8")
    return record, tmp_path / "m.yaml"


def test_a_0_1_0_record_that_differs_says_which_release_made_it(
    tmp_path: Path, capsys: Capsys
) -> None:
    record, mission = _recorded_as_0_1_0(tmp_path)
    assert main(["replay", str(record)]) == 0
    assert "recorded by" not in capsys.readouterr().out  # the same bytes: nothing to say
    _mission(mission, wait="0.2s")
    assert main(["replay", str(record)]) == 1
    out = capsys.readouterr().out
    assert f"{SAID}\nreplay: first difference at mission time" in out
    assert_quoted("docs/runtime.md", "replay: recorded by roomba-bt 0.1.0 or earlier", out)


def test_a_0_1_0_record_whose_mission_is_refused_says_to_pass_the_fixed_file(
    tmp_path: Path, capsys: Capsys
) -> None:
    record, mission = _recorded_as_0_1_0(tmp_path, FIXED)
    _mission(mission, REFUSED)  # the file as 0.1.0 took it
    assert main(["replay", str(record)]) == 2  # the exit code of a mission that is invalid
    err = capsys.readouterr().err
    assert "choices only goes with type: enum" in err
    assert err.endswith(
        f"replay: the record's mission {mission} is refused by roomba-bt {__version__}; the "
        "record was made by roomba-bt 0.1.0 or earlier, as the record names no release: fix a "
        'copy as said above (the CHANGELOG\'s "Upgrading from 0.1.0") and pass --mission FILE '
        "with the fixed file to replay this record\n"
    )
    assert_quoted("docs/runtime.md", "replay: the record's mission m.yaml is refused", err,
                  names={str(mission): "m.yaml"})  # fmt: skip
    fixed = _mission(tmp_path / "fixed.yaml", FIXED)
    assert main(["replay", str(record), "--mission", str(fixed)]) == 0  # byte for byte
    assert "the tree wrote the same" in capsys.readouterr().out
    assert main(["replay", str(record), "--mission", str(mission)]) == 2
    assert "--mission FILE" not in capsys.readouterr().err  # the file given is the one refused


def test_a_record_of_this_release_whose_mission_was_edited_since_is_not_sent_to_the_notes(
    tmp_path: Path, capsys: Capsys
) -> None:
    """The same ``replay:`` line for a record this release made, without the upgrade notes:
    its mission was refused by an edit, not by an upgrade."""
    record = record_run(tmp_path, SimLink(Simulator(load_world("empty-room"), CREATE2, 0)),
                        MISSION.format(parameters=FIXED, wait="0.1s"))  # fmt: skip
    mission = _mission(tmp_path / "m.yaml", REFUSED)
    assert main(["replay", str(record)]) == 2
    err = capsys.readouterr().err
    assert f"record was made by roomba-bt {__version__}: fix a copy as said above and " in err
    assert f"replay: the record's mission {mission} is refused" in err and "CHANGELOG" not in err
