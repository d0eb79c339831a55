"""The lines docs/runtime.md (and docs/monitor.md) quote of ``run --reproducible`` and of
``replay``, each made by the command the page describes, on one short record.

One record of a reader's repository (``missions/x.yaml`` including ``missions/lib.yaml``,
run from ``records/``) serves every quote: its replay whole, cut with ``--to``, with a
library edited since, cut short as a killed run leaves it, against another mission, and a
copy of it moved out of the repository. The runs are on the virtual clock, 1.5 s of mission
time each, made once for the module (tests/quoted.py's ``assert_quoted`` compares the page's
quotes with what was printed; their numbers are the page's example's)."""

from __future__ import annotations

import contextlib
import io
import shutil
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest
from quoted import assert_quoted  # tests/quoted.py: the docs' quotes

from roomba_bt.cli import main

MISSION = """\
mission: x
include: [lib.yaml]
tree:
  sequence:
    - mode: safe
    - subtree: leg
"""
#: the library the mission includes: a drive at 200 mm/s (``89 00 c8 80 00``, as the page's
#: first difference expects it)
LIBRARY = """\
subtrees:
  leg:
    tree:
      sequence:
        - drive: {velocity: 200 mm/s, distance: 20 cm}
        - wait: 0.5s
"""
#: the same mission at 100 mm/s (``89 00 64 80 00``, the page's sent command)
SLOWER = MISSION.replace(
    "    - subtree: leg\n", "    - drive: {velocity: 100 mm/s, distance: 20 cm}\n"
)


@dataclass(frozen=True)
class Said:
    """What a command printed: its exit code, stdout and stderr."""

    code: int
    out: str
    err: str


def said(*argv: str) -> Said:
    """``roomba-bt ARGV`` in this process, its output captured (a module's fixture has no
    ``capsys``)."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main([*argv, "--display", "none"])
    return Said(code, out.getvalue(), err.getvalue())


@dataclass(frozen=True)
class Replays:
    """The module's record and what each command printed of it."""

    root: Path  # the folder that holds the repository and the copy moved out of it
    reproducible: Said  # run --reproducible --record r.jsonl
    whole: Said  # replay r.jsonl
    window: Said  # replay r.jsonl --to 1s
    edited: Said  # replay r.jsonl, the library edited since (a comment: the same bytes)
    cut: Said  # replay of the record cut short, as a run killed there leaves it
    other: Said  # replay r.jsonl --mission slower.yaml
    moved: Said  # replay of a copy of a record with its mission's path, out of the repository


@pytest.fixture(scope="module")
def replays(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Replays]:
    root = tmp_path_factory.mktemp("replays")
    missions, records, elsewhere = root / "repo/missions", root / "repo/records", root / "else"
    for folder in (missions, records, elsewhere):
        folder.mkdir(parents=True)
    (missions / "x.yaml").write_text(MISSION)
    (missions / "lib.yaml").write_text(LIBRARY)
    (missions / "slower.yaml").write_text(SLOWER)
    with pytest.MonkeyPatch.context() as here:
        here.chdir(records)  # the page's commands run in records/
        reproducible = said("run", "../missions/x.yaml", "--fast", "--reproducible",
                            "--record", "r.jsonl")  # fmt: skip
        whole = said("replay", "r.jsonl")
        window = said("replay", "r.jsonl", "--to", "1s")
        other = said("replay", "r.jsonl", "--mission", "../missions/slower.yaml")
        # a record that names its mission's path (not --reproducible), copied elsewhere
        assert said("run", "../missions/x.yaml", "--fast", "--record", "n.jsonl").code == 0
        shutil.copy(records / "n.jsonl", elsewhere / "r.jsonl")
        here.chdir(elsewhere)
        moved = said("replay", "r.jsonl")
        here.chdir(records)
        lines = (records / "r.jsonl").read_text().splitlines(keepends=True)
        (records / "cut.jsonl").write_text("".join(lines[: len(lines) // 2]))
        cut = said("replay", "cut.jsonl")
        with (missions / "lib.yaml").open("a") as library:
            library.write("# a comment: the same tree, another file\n")
        edited = said("replay", "r.jsonl")
    yield Replays(root, reproducible, whole, window, edited, cut, other, moved)


def test_a_reproducible_run_s_ticks_line_is_the_count_alone(replays: Replays) -> None:
    assert replays.reproducible.code == 0, replays.reproducible
    assert_quoted("docs/runtime.md", "ticks 447", replays.reproducible.out, numbers=True)


def test_a_replay_of_the_same_bytes_says_how_many(replays: Replays) -> None:
    assert replays.whole.code == 0, replays.whole
    out = replays.whole.out
    assert_quoted(
        "docs/runtime.md", "replay: the tree wrote the same 43 bytes as", out, numbers=True
    )


def test_a_replay_cut_with_to_says_how_far_it_compared(replays: Replays) -> None:
    assert replays.window.code == 0, replays.window
    assert_quoted("docs/runtime.md", "replay: compared up to", replays.window.out, numbers=True)
    assert_quoted("docs/monitor.md", "replay: compared up to", replays.window.out, numbers=True)


def test_a_replay_on_an_edited_library_counts_the_files_changed(replays: Replays) -> None:
    """The same bytes, a file the record names changed since: a count, no names."""
    assert replays.edited.code == 0, replays.edited
    assert_quoted("docs/runtime.md", "replay: recorded with roomba-bt 0.2.0 (this release too)",
                  replays.edited.out, numbers=True)  # fmt: skip


def test_a_record_cut_short_is_compared_up_to_its_end(replays: Replays) -> None:
    assert replays.cut.code == 0, replays.cut
    assert_quoted("docs/runtime.md", "replay: the record ends at", replays.cut.out, numbers=True)
    out = replays.cut.out
    assert_quoted("docs/runtime.md", "replay: the tree wrote the same 28 bytes up to", out,
                  numbers=True)  # fmt: skip


def test_another_mission_s_first_difference_names_both_commands(replays: Replays) -> None:
    assert replays.other.code == 1, replays.other
    assert_quoted("docs/runtime.md", "replay: first difference at mission time 1.005 s",
                  replays.other.out, numbers=True)  # fmt: skip


def test_a_record_moved_out_of_its_repository_replays_the_mission_where_recorded(
    replays: Replays,
) -> None:
    assert replays.moved.code == 0, replays.moved
    page = {str(replays.root / "repo"): "/home/me/repo", str(replays.root): "/tmp"}
    assert_quoted("docs/runtime.md", "r.jsonl: mission '../missions/x.yaml' is not beside",
                  replays.moved.err, names=page)  # fmt: skip
