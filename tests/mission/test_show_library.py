"""``roomba-bt show LIB.yaml`` lists a library's subtrees with their parameters and ``doc:``
(it refused the file: "a library ... not run"), and ``--subtree NAME`` draws one of them
(library report finding 9)."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest

from roomba_bt.cli import main

Capsys = pytest.CaptureFixture[str]

LIBRARY = """
description: Bump recovery, shared by three missions.
subtrees:
  bump_recovery:
    doc: Back off and turn away from the bumped side.
    parameters:
      back: {type: distance, default: 10cm, doc: how far to back up}
    tree: {drive: {velocity: -150 mm/s, distance: "${back}"}}
  drive_leg:
    doc: Drive one leg, recovering from bumps.
    parameters:
      dist: {type: distance}
      tries: {type: int, default: 3}
    tree:
      retry:
        times: "${tries}"
        do:
          fallback:
            - {drive: {velocity: 200 mm/s, distance: "${dist}"}, while: {inverter: {bump: any}}}
            - force_failure: {subtree: bump_recovery}
"""


@pytest.fixture
def library(mission_file: Callable[..., Path], monkeypatch: pytest.MonkeyPatch) -> str:
    path = mission_file(LIBRARY, "lib/recovery.yaml")
    monkeypatch.chdir(path.parent.parent)
    return "lib/recovery.yaml"


def test_a_library_is_listed_with_each_subtree_s_doc_and_parameters(
    library: str, capsys: Capsys
) -> None:
    assert main(["show", library]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0] == "lib/recovery.yaml: Bump recovery, shared by three missions."
    assert "roomba-bt show lib/recovery.yaml --subtree NAME" in out[1]
    assert out[3:] == [
        "bump_recovery  Back off and turn away from the bumped side.",
        "    back: distance, default 10cm  how far to back up",
        "drive_leg  Drive one leg, recovering from bumps.",
        "    dist: distance, required",
        "    tries: int, default 3",
    ]


def test_one_subtree_is_drawn_with_its_arguments(library: str, capsys: Capsys) -> None:
    assert main(["show", library, "--subtree", "drive_leg", "-p", "dist=1m", "-p", "tries=2"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("drive_leg: Drive one leg, recovering from bumps.\n")
    # every use one look, with the arguments it wrote: a decorator's body was "retry(times=2)
    # named 'drive_leg'", a sequence's "bump_recovery", neither with its arguments
    assert "-^- subtree drive_leg(dist=1m, tries=2): retry(times=2)\n" in out
    assert "--> subtree bump_recovery: drive(velocity=-150 mm/s, distance=10cm)\n" in out
    assert "[-] while not bump(any)\n" in out  # what the guard tests, not "while inverter"
    assert "drive(velocity=200 mm/s, distance=1m)" in out


@pytest.mark.parametrize(
    ("argv", "mode_first"),
    [
        # drives that need a mode it does not enter: after mode: safe, as a mission has it
        (["lib/recovery.yaml", "--subtree", "drive_leg", "-p", "dist=1m"], True),
        # enters Full itself, from any mode: drawn as it runs, no mode step before it
        (["roomba-bt:lib/undock.yaml", "--subtree", "undock"], False),
    ],
)
def test_a_subtree_is_drawn_after_a_mode_step_only_where_its_body_needs_one(
    argv: list[str], mode_first: bool, library: str, capsys: Capsys
) -> None:
    assert main(["show", *argv]) == 0
    drawn = capsys.readouterr().out.splitlines()
    assert drawn[1] == "{-} sequence"
    assert (drawn[2] == "    --> mode(safe)") is mode_first
    assert drawn[2 + mode_first].startswith(("    -^- subtree", "    {o} subtree"))


def test_a_long_use_is_drawn_whole_up_to_the_text_limit(
    library: str, mission_file: Callable[..., Path], capsys: Capsys
) -> None:
    """A use's arguments are texts the mission wrote, as its description: cut at
    TEXT_LIMIT, not at a name's 80 characters (the shipped dock's use has 165)."""
    from roomba_bt.printable import TEXT_LIMIT

    long_use = "subtree drive_leg(dist=1." + "0" * 150 + "m)"
    mission_file(
        "include: [lib/recovery.yaml]\ntree:\n  sequence:\n    - mode: safe\n"
        f"    - subtree: {{id: drive_leg, dist: 1.{'0' * 150}m}}\n"
        f"    - subtree: {{id: drive_leg, dist: 2.{'0' * 600}m}}\n"
    )
    assert main(["show", "m.yaml"]) == 0
    out = capsys.readouterr().out
    assert f"-^- {long_use}: retry(times=3)" in out
    cut = (
        "subtree drive_leg(dist=2."
        + "0" * (TEXT_LIMIT - len("drive_leg(dist=2."))
        + "... (619 characters)"
    )
    assert cut in out


def test_a_use_s_arguments_are_drawn_at_the_use(
    library: str, mission_file: Callable[..., Path], capsys: Capsys
) -> None:
    mission_file(
        """
        include: [lib/recovery.yaml]
        tree:
          sequence:
            - mode: safe
            - subtree: {id: bump_recovery, back: 20cm}
            - subtree: {id: drive_leg, dist: 2m}
        """
    )
    assert main(["show", "m.yaml"]) == 0
    out = capsys.readouterr().out
    assert "--> subtree bump_recovery(back=20cm): drive(velocity=-150 mm/s, distance=20cm)" in out
    assert "-^- subtree drive_leg(dist=2m): retry(times=3)" in out


@pytest.mark.parametrize(
    ("argv", "said"),
    [
        (
            ["--subtree", "drive_leg"],
            "subtree 'drive_leg' needs a value for dist (distance) (no default): "
            "give -p dist=VALUE",
        ),
        (
            ["--subtree", "drive_leg", "-p", "dist=1m", "-p", "trie=2"],
            "subtree 'drive_leg' has no parameter 'trie' (did you mean 'tries'?)",
        ),
        (
            ["--subtree", "bump_recoveri"],
            "defines no subtree 'bump_recoveri' (did you mean 'bump_recovery'?); it defines: "
            "bump_recovery, drive_leg",
        ),
        (["-p", "dist=1m"], "-p sets a subtree's arguments: give --subtree NAME with it"),
    ],
)
def test_what_cannot_be_drawn_is_said(
    library: str, capsys: Capsys, argv: list[str], said: str
) -> None:
    assert main(["show", library, *argv]) == 2
    err = capsys.readouterr().err
    assert err.startswith("roomba-bt show: ") and said in err, err


def test_subtree_is_refused_for_a_mission(
    mission_file: Callable[..., Path], capsys: Capsys
) -> None:
    path = mission_file("tree: wall\n")
    assert main(["show", str(path), "--subtree", "x"]) == 2
    assert "is a mission: its tree is drawn without --subtree" in capsys.readouterr().err


def test_a_broken_library_says_its_errors_as_validate_does(
    mission_file: Callable[..., Path], capsys: Capsys
) -> None:
    path = mission_file("subtrees: {leg: {tree: {drive: {velocity: 900 mm/s}}}}\n")
    assert main(["show", str(path)]) == 2
    assert "velocity 900 mm/s is out of range" in capsys.readouterr().out
