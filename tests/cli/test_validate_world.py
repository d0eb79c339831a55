"""``roomba-bt validate WORLD.yaml``: a world file checked on its own, as ``run --world``
reads it, with a mission's error style (file:line:col, exit 2 for a bad file). CI reached a
world's checks only by running a mission in it, whose first error line began with
``roomba-bt: `` and broke a ``^file:line:col`` matcher."""

from __future__ import annotations

from pathlib import Path

import pytest

from roomba_bt.cli import main

Capsys = pytest.CaptureFixture[str]

GOOD = """\
name: lab
rooms:
  - {rect: [0, 0, 5, 4]}
dock: {at: [2, 0], facing: 90}
"""

BAD = """\
name: bad
rooms:
  - {rect: [0, 0, 5, 4]}
obstacles:
  - {name: x, rect: [30, 30, 40, 40]}
dock: {at: [2, 0], facng: 90}
"""


@pytest.fixture
def worlds(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    (tmp_path / "worlds").mkdir()
    (tmp_path / "worlds" / "lab.yaml").write_text(GOOD)
    (tmp_path / "worlds" / "bad.yaml").write_text(BAD)
    monkeypatch.chdir(tmp_path)
    return tmp_path


def test_a_good_world_validates(worlds: Path, capsys: Capsys) -> None:
    assert main(["validate", "worlds/lab.yaml", "dock"]) == 0
    assert capsys.readouterr().out.splitlines() == [
        "worlds/lab.yaml: ok",
        "dock: ok",
        "2 files: 2 ok, 0 with warnings only, 0 with errors",
    ]


def test_a_bad_world_is_every_problem_at_its_place(worlds: Path, capsys: Capsys) -> None:
    assert main(["validate", "worlds/bad.yaml", "worlds/lab.yaml"]) == 2
    out, err = capsys.readouterr()
    assert out.splitlines() == [
        "worlds/bad.yaml:5:5: obstacles[0]: found a shape wholly outside every room (x 30..40, "
        "y 30..40 m); allowed: a shape on a room's floor, in metres",
        "worlds/bad.yaml:6:7: dock: found no 'facing'; allowed: a mapping with 'facing'",
        "worlds/bad.yaml:6:20: dock.facng: found unknown key 'facng'; allowed: at, facing, red, "
        "green, buoy_range, force_field, contact_tolerance, angle_tolerance, family, plate_width "
        "(did you mean 'facing'?)",
        "worlds/bad.yaml: failed (3 errors)",
        "worlds/lab.yaml: ok",
        "2 files: 1 ok, 0 with warnings only, 1 with errors",
    ]
    assert err == ""


def test_a_world_yaml_cannot_read_is_still_a_world(worlds: Path, capsys: Capsys) -> None:
    """Told from its unindented ``rooms:``: the YAML error at its place, not "this file is
    not a mission"."""
    (worlds / "worlds" / "broken.yaml").write_text("rooms: [[[0, 0], [1, 0]]\nname: x\n")
    assert main(["validate", "worlds/broken.yaml"]) == 2
    assert capsys.readouterr().out.startswith("worlds/broken.yaml:2:1: YAML syntax error: ")


def test_run_prints_a_worlds_problems_as_validate_does(worlds: Path, capsys: Capsys) -> None:
    argv = ["run", "dock", "--fast", "--display", "none", "--world", "worlds/bad.yaml"]
    assert main(argv) == 2
    first = capsys.readouterr().err.splitlines()[0]
    assert first.startswith("worlds/bad.yaml:5:5: obstacles[0]: found a shape"), first


def test_worlds_given_a_file_says_how_to_check_it(worlds: Path, capsys: Capsys) -> None:
    assert main(["worlds", "worlds/lab.yaml"]) == 2
    assert capsys.readouterr().err == (
        "roomba-bt worlds: worlds/lab.yaml is a file, not a shipped world's name: check it with "
        "roomba-bt validate worlds/lab.yaml; run a mission in it with --world worlds/lab.yaml\n"
    )


@pytest.mark.parametrize(
    "argv",
    [
        ["validate", "worlds/many.yaml"],
        ["run", "dock", "--fast", "--display", "none", "--world", "worlds/many.yaml"],
        ["sim", "--tcp", "0", "--world", "worlds/many.yaml"],
        ["eval", "dock", "--runs", "1", "--world", "worlds/many.yaml"],
    ],
    ids=["validate", "run", "sim", "eval"],
)
def test_a_world_of_thousands_of_errors_lists_the_first_hundred(
    worlds: Path, capsys: Capsys, argv: list[str]
) -> None:
    """A world of 20,000 bad obstacles printed 20,000 error lines on ``run``: a world's
    errors are cut as a mission's are, the first hundred and how many more."""
    bad = "".join(f"  - {{polygon: [[x, 1], [2, 2], [3, {n}]]}}\n" for n in range(900))
    text = f"rooms: [[[0, 0], [4, 0], [4, 3], [0, 3]]]\nobstacles:\n{bad}drops:\n{bad}"
    (worlds / "worlds" / "many.yaml").write_text(text)
    assert main(argv) == 2
    out, err = capsys.readouterr()
    lines = (out + err).splitlines()
    assert len(lines) < 110
    assert "... and 1,700 more errors (the first 100 are listed)" in lines
    first = "worlds/many.yaml:3:17: obstacles[0].polygon[0][0]: found 'x'"
    assert any(first in line for line in lines[:2]), lines[:2]  # after "sim: invalid world:"


@pytest.mark.parametrize(
    ("argv", "before"),
    [
        (["run", "dock", "--fast", "--display", "none", "--world", "worlds/empty.yaml"], []),
        (["sim", "--tcp", "0", "--world", "worlds/empty.yaml"], ["roomba-bt sim: invalid world:"]),
    ],
    ids=["run", "sim"],
)
def test_an_empty_world_is_said_at_its_place_by_run_and_sim(
    worlds: Path, capsys: Capsys, argv: list[str], before: list[str]
) -> None:
    """``run`` said "roomba-bt: worlds/empty.yaml: (document): found nothing", the one world
    problem not at ``file:line:col``; both say it as every other now."""
    (worlds / "worlds" / "empty.yaml").write_text("# to be drawn\n")
    assert main(argv) == 2
    lines = capsys.readouterr().err.splitlines()
    assert lines[: len(before)] == before
    assert lines[len(before)].startswith(
        "worlds/empty.yaml:1:1: (document): found an empty file (no YAML in it, at most "
        "comments); allowed: a world: at least rooms"
    ), lines


def world_starting_at(x: float) -> str:
    """A room 5 x 4 m with stairs down from x = 3 m, the robot given a start at ``x``
    (tests/docs_inputs.py's EDGE, at 2.9 m: docs/simulator.md quotes its warning)."""
    return (
        "name: edge\n"
        "rooms:\n"
        "  - {rect: [0, 0, 5, 4]}\n"
        "drops:\n"
        "  - {name: stairs, rect: [3, 0, 5, 4]}\n"
        "robot:\n"
        f"  start: {{at: [{x}, 2], heading: 0}}\n"
    )


def test_a_given_start_whose_body_is_over_a_drop_is_warned_of(worlds: Path, capsys: Capsys) -> None:
    """The centre 0.1 m from the stairs' edge: the body (0.17 m) reaches 0.07 m over them.
    A drawn start keeps it 20 mm off; a given one loads (a test may put a robot at an edge
    on purpose) with a warning at robot.start's place, by how much; --strict fails it."""
    (worlds / "worlds" / "edge.yaml").write_text(world_starting_at(2.9))
    assert main(["validate", "worlds/edge.yaml"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0] == (
        "worlds/edge.yaml:7:10: warning: robot.start: found a start pose (2.900, 2.000) m "
        "whose body reaches 0.070 m over drops[0] (its edge 0.100 m from the centre, the "
        "body's radius 0.170 m): the robot may fall or read a cliff at once; allowed: a start "
        "with the whole body off every drop (0.19 m from its edge, as a drawn start keeps it), "
        "or this on purpose (a test at an edge)"
    )
    assert out[-1] == "worlds/edge.yaml: ok, with warnings"
    assert main(["validate", "--strict", "worlds/edge.yaml"]) == 7
    capsys.readouterr()
    argv = ["run", "dock", "--fast", "--display", "none", "--timeout", "1", "--world"]
    main([*argv, "worlds/edge.yaml"])
    assert out[0] in capsys.readouterr().err.splitlines()


@pytest.mark.parametrize(
    ("x", "said"),
    [
        (2.5, None),  # the body 0.33 m off the edge: nothing to say
        (3.1, "where the robot does not fit"),  # the centre over the stairs: an error
    ],
)
def test_a_start_clear_of_the_drop_or_over_it_is_no_warning(
    x: float, said: str | None, worlds: Path, capsys: Capsys
) -> None:
    (worlds / "worlds" / "edge.yaml").write_text(world_starting_at(x))
    assert main(["validate", "worlds/edge.yaml"]) == (0 if said is None else 2)
    out = capsys.readouterr().out
    assert "warning" not in out
    assert said is None or said in out


def test_eval_says_a_given_start_s_warning_once(worlds: Path, capsys: Capsys) -> None:
    """eval in a world whose given start reaches over a drop said nothing, where run and
    validate warn: once on stderr for all its episodes, which all start there."""
    (worlds / "worlds" / "edge.yaml").write_text(world_starting_at(2.9))
    argv = ["eval", "dock", "--runs", "2", "--jobs", "1", "--timeout", "1"]
    main([*argv, "--world", "worlds/edge.yaml"])
    err = capsys.readouterr().err.splitlines()
    said = [line for line in err if line.startswith("worlds/edge.yaml:7:10: warning: robot.start")]
    assert len(said) == 1, err


@pytest.mark.parametrize("text", ["", "# to be drawn\n\n"], ids=["nothing", "comments"])
def test_validate_says_an_empty_file_is_neither_a_mission_nor_a_world(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: Capsys, text: str
) -> None:
    """``validate`` takes a mission or a world, and said "the mission file is empty" of a
    world being drawn: an empty file is neither, and both are named. Where a mission is
    expected (``run``, an include), it is still an empty mission file."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "empty.yaml").write_text(text)
    (tmp_path / "m.yaml").write_text("include: [empty.yaml]\ntree: {sequence: [stop]}\n")
    assert main(["validate", "empty.yaml", "m.yaml"]) == 2
    lines = capsys.readouterr().out.splitlines()
    assert lines[0] == (
        "empty.yaml:1:1: an empty file (no YAML in it, at most comments): neither a mission nor "
        "a world; expected a mission (at least tree:, or a library's subtrees:) or a world (at "
        "least rooms:, the floor's polygons in metres; roomba-bt worlds empty-room prints a "
        "whole one)"
    )
    assert "empty.yaml:1:1: the mission file is empty (included from m.yaml:1:11)" in lines
    assert main(["run", "empty.yaml", "--fast", "--display", "none"]) == 2
    assert "empty.yaml:1:1: the mission file is empty" in capsys.readouterr().err


@pytest.mark.parametrize(
    "argv",
    [
        ["run", "dock", "--fast", "--display", "none", "--world"],
        ["sensors", "--world"],
        ["monitor", "r.jsonl", "--monitor", "0", "--world"],
    ],
    ids=["run", "sensors", "monitor"],
)
@pytest.mark.parametrize("world", ["worlds/gone.yaml", "worlds"], ids=["no such file", "a folder"])
def test_a_world_that_cannot_be_read_is_said_by_the_command_that_read_it(
    worlds: Path, capsys: Capsys, argv: list[str], world: str
) -> None:
    """A world with no place to point at (no such file, a folder) began ``roomba-bt: ``
    where ``eval`` and every other error of these commands say ``roomba-bt run: ``: said
    after the command's name, as eval says it."""
    if argv[0] == "monitor":
        pytest.importorskip("aiohttp")  # the monitor extra
    assert main([*argv, world]) == 2
    command = argv[0]
    err = capsys.readouterr().err
    assert err.startswith(f"roomba-bt {command}: {world}: world: found "), err
    assert main(["eval", "dock", "--runs", "1", "--world", world]) == 2
    assert capsys.readouterr().err.startswith(f"roomba-bt eval: {world}: world: found ")
