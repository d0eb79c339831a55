"""``roomba-bt validate / show / behaviours / schema``: exit codes and output, no traceback."""

from __future__ import annotations

import json
import re
from collections.abc import Callable
from pathlib import Path

import pytest

from roomba_bt.cli import main

EXAMPLES = Path(__file__).resolve().parents[2] / "missions" / "examples"
Capsys = pytest.CaptureFixture[str]


def test_validate_valid_files_exits_0(capsys: Capsys) -> None:
    files = [str(p) for p in sorted(EXAMPLES.glob("*.yaml"))]
    lib = str(EXAMPLES / "lib" / "escapes.yaml")
    assert main(["validate", *files, lib, "--allow-plugin-files"]) == 0
    out, err = capsys.readouterr()
    assert err == ""
    assert out.count(": ok") == len(files) + 1


def test_validate_reports_every_file(mission_file: Callable[..., Path], capsys: Capsys) -> None:
    good = mission_file("tree: wall\n", "good.yaml")
    bad = mission_file("tree: {wal: {}}\n", "bad.yaml")
    assert main(["validate", str(bad), str(good)]) == 2
    out, _ = capsys.readouterr()
    bad_line, bad_verdict, good_line, counts = out.strip().splitlines()
    assert bad_line.endswith("bad.yaml:1:8: unknown node 'wal' (did you mean 'wall'?) [tree.wal]")
    assert bad_verdict == f"{bad}: failed (1 error)"  # each file's verdict, a failed one too
    assert good_line == f"{good}: ok"
    assert counts == "2 files: 1 ok, 0 with warnings only, 1 with errors"  # a batch's count


def test_validate_takes_parameters(mission_file: Callable[..., Path], capsys: Capsys) -> None:
    path = mission_file("parameters: {t: {type: duration}}\ntree: {wait: '${t}'}\n")
    assert main(["validate", str(path)]) == 2
    assert "parameter 't' has no default: give it with -p t=VALUE" in capsys.readouterr().out
    assert main(["validate", str(path), "-p", "t=2s"]) == 0
    assert main(["validate", str(path), "-p", "t"]) == 2


def test_validate_prints_warnings_and_still_exits_0(
    mission_file: Callable[..., Path], capsys: Capsys
) -> None:
    path = mission_file(
        "tree:\n  sequence:\n    - mode: full\n    - drive: {velocity: 100 mm/s, distance: 1 m}\n"
    )
    assert main(["validate", str(path)]) == 0
    out = capsys.readouterr().out
    assert f"{path}:4:7: warning: drive can turn the wheels in Full mode" in out
    assert out.rstrip().endswith(f"{path}: ok, with warnings")


def test_validate_a_missing_file(capsys: Capsys, tmp_path: Path) -> None:
    assert main(["validate", str(tmp_path / "nope.yaml")]) == 2
    assert "nope.yaml: no such mission file, and no shipped mission" in capsys.readouterr().err


@pytest.mark.parametrize(
    "command", [["validate"], ["show"], ["run", "--fast"], ["eval", "--runs", "1"]]
)
def test_a_shipped_world_s_name_given_for_a_mission_is_said_as_a_world(
    command: list[str], capsys: Capsys, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """``validate empty-room`` listed the shipped missions alone, as if the name were a typo
    of one: it is a shipped world, which the error now says, with how to see it and how to
    run a mission in it. A path (a ``/`` in it) is a file of the user's, never a world."""
    monkeypatch.chdir(tmp_path)
    assert main([command[0], "empty-room", *command[1:]]) == 2
    err = capsys.readouterr().err
    assert err.rstrip().endswith(
        "; empty-room is a shipped world, not a mission: `roomba-bt worlds empty-room` shows "
        "it, `roomba-bt run MISSION --world empty-room` runs a mission in it"
    ), err
    assert main([command[0], "worlds/empty-room.yaml", *command[1:]]) == 2
    assert "shipped world" not in capsys.readouterr().err
    assert main(["worlds", "empty-room"]) == 0  # what the hint gives runs
    assert "name: empty-room" in capsys.readouterr().out


@pytest.mark.parametrize(
    "command", [["validate"], ["show"], ["run", "--fast"], ["eval", "--runs", "1"]]
)
def test_a_missing_file_s_name_is_said_on_one_line_by_every_command(
    command: list[str], capsys: Capsys, tmp_path: Path
) -> None:
    """A name holding a newline (a paste) was printed raw by ``run`` and ``eval``, and what
    followed it read as a line of roomba-bt's own; ``validate`` and ``show`` escaped it."""
    name = str(tmp_path / "x\n[ok] y.yaml")
    assert main([command[0], name, *command[1:]]) == 2
    err = capsys.readouterr().err
    assert "x\\x0a[ok] y.yaml: no such mission file" in err
    assert not any(line.startswith("[ok]") for line in err.splitlines()), err


def test_show_prints_the_tree(capsys: Capsys) -> None:
    assert main(["show", str(EXAMPLES / "square.yaml"), "-p", "side=2m"]) == 0
    out, _ = capsys.readouterr()
    assert "square: Drive a square of side 2m" in out
    assert "-^- for_each" in out
    assert "until bump(any)" in out
    assert "sensor packets: [7, 43, 44]" in out


def test_show_writes_dot(capsys: Capsys, tmp_path: Path) -> None:
    target = tmp_path / "tree.dot"
    assert main(["show", str(EXAMPLES / "dock.yaml"), "--dot", str(target)]) == 0
    assert target.read_text().startswith("digraph")


def test_show_dot_labels_each_node_by_its_name_not_its_unique_id(
    mission_file: Callable[..., Path], tmp_path: Path
) -> None:
    """py_trees makes a second ``bump(any)`` the graph node ``bump(any)*``, and labelled it
    so: the label is the node's text; the ids stay unique (three nodes, three ids)."""
    path = mission_file(
        "tree:\n  sequence:\n    - bump: any\n    - inverter: {bump: any}\n"
        "    - inverter: {bump: any}\n"
    )
    target = tmp_path / "tree.dot"
    assert main(["show", str(path), "--dot", str(target)]) == 0
    dot = target.read_text()
    assert "*" not in "".join(re.findall(r'label="?([^",]*)', dot)), dot
    assert dot.count('label="bump(any)"') == 3, dot
    assert dot.count("label=inverter") == 2, dot
    assert '"bump(any)**"' in dot  # ids are still unique


SPOOF = """\
mission: spoof
description: Gently drives 10 cm forward at 50 mm/s.
tree:
  sequence:
    - mode: safe
    - drive: {velocity: 500 mm/s, duration: 10s}
      name: "drive(velocity=50 mm/s, distance=10cm)"
    - sequence: [stop]
      name: "tidy\\n    --> wait(1s)"
"""


def test_show_says_what_a_renamed_node_is_before_its_name(
    mission_file: Callable[..., Path], capsys: Capsys, tmp_path: Path
) -> None:
    """``name:`` replaced the label whole in ``show`` and ``--dot``: a drive at 500 mm/s could
    be named ``drive(velocity=50 mm/s, distance=10cm)``, and a review saw only that. What the
    node is comes first, then its name (quoted: a newline in it cannot make a line of its
    own); the live tree keeps the name."""
    from roomba_bt.mission import load_mission

    path = mission_file(SPOOF)
    target = tmp_path / "tree.dot"
    assert main(["show", str(path), "--dot", str(target)]) == 0
    out = capsys.readouterr().out
    assert out.splitlines()[1:5] == [
        "{-} sequence",
        "    --> mode(safe)",
        "    --> drive(velocity=500 mm/s, duration=10s) named "
        "'drive(velocity=50 mm/s, distance=10cm)'",
        "    {-} sequence named 'tidy\\n    --> wait(1s)'",
    ]
    assert "named 'drive(velocity=50 mm/s, distance=10cm)'" in target.read_text()
    live = [node.name for node in load_mission(path).root.iterate()]
    assert "drive(velocity=50 mm/s, distance=10cm)" in live


def test_show_svg_without_graphviz_is_a_clear_error(
    capsys: Capsys, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("PATH", str(tmp_path))  # no 'dot' executable
    assert main(["show", str(EXAMPLES / "dock.yaml"), "--svg", str(tmp_path / "t.svg")]) == 2
    out, err = capsys.readouterr()
    assert "Graphviz's dot program, which is not on the PATH" in err
    assert "Traceback" not in err
    assert out == ""  # said before the tree, not after it


def test_show_refuses_a_graph_file_it_cannot_write_before_anything_else(
    capsys: Capsys, tmp_path: Path
) -> None:
    with pytest.raises(SystemExit) as exited:  # argparse's own exit, with its usage line
        main(["show", str(EXAMPLES / "dock.yaml"), "--dot", str(tmp_path / "no" / "t.dot")])
    assert exited.value.code == 2
    out, err = capsys.readouterr()
    assert "--dot: found" in err and "there is no directory" in err
    assert "Graphviz" not in err and out == ""


@pytest.mark.parametrize("option", ["--dot", "--svg"])
def test_show_writes_its_graph_only_to_a_file_named_for_it(
    option: str, capsys: Capsys, tmp_path: Path
) -> None:
    """``show m.yaml --dot m.yaml`` wrote the graph over the mission."""
    mission = tmp_path / "m.yaml"
    mission.write_text("tree: {wait: 1s}\n")
    with pytest.raises(SystemExit) as exited:
        main(["show", str(mission), option, str(mission)])
    assert exited.value.code == 2
    err = capsys.readouterr().err
    assert f"{option}: found {str(mission)!r}; allowed: a file ending in ." in err
    assert mission.read_text() == "tree: {wait: 1s}\n"


def test_show_an_invalid_mission(mission_file: Callable[..., Path], capsys: Capsys) -> None:
    assert main(["show", str(mission_file("tree: []\n"))]) == 2
    assert "expected a node" in capsys.readouterr().out


def test_behaviours_lists_every_behaviour_with_parameters(capsys: Capsys) -> None:
    assert main(["behaviours"]) == 0
    out, _ = capsys.readouterr()
    for name in ("drive", "turn", "seek_dock", "bump", "ir", "sensor", "wall_follow"):
        assert f"\n{name}  (" in f"\n{out}"
    assert "velocity: speed [mm/s], range -500..500, default 200 mm/s" in out


def test_behaviours_json_and_unknown_names(capsys: Capsys) -> None:
    assert main(["behaviours", "drive", "--json"]) == 0
    [drive] = json.loads(capsys.readouterr().out)
    assert drive["modes"] == ["Safe", "Full"]
    assert drive["sends"] == [137, 145]
    assert main(["behaviours", "drvie"]) == 2
    assert "did you mean 'drive'" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("name", "said"),
    [
        ("roomba-bt-nope:near_wall", "no installed plugin package is called 'roomba-bt-nope' "
         "(installed: "),
        ("roomba-bt:drvie", "roomba-bt has no built-in behaviour 'drvie' (did you mean "
         "'drive'?)"),
    ],
)  # fmt: skip
def test_behaviours_of_a_package_name_says_what_validate_says(
    capsys: Capsys, name: str, said: str
) -> None:
    """``behaviours roomba-bt-lab:near_wall`` of an uninstalled package said "a plugin
    file's are listed with --plugin-file FILE" (a file has no package), where validate
    said the package is not installed and named those that are."""
    assert main(["behaviours", name]) == 2
    err = capsys.readouterr().err
    assert f"roomba-bt behaviours: unknown behaviour '{name}': {said}" in err, err
    assert "--plugin-file" not in err


def test_behaviours_lists_a_plugin_files_behaviours_with_plugin_file(capsys: Capsys) -> None:
    """``schema`` took ``--plugin-file``; ``behaviours`` had no way to show a file's."""
    assert main(["behaviours", "near_wall"]) == 2
    assert "; a plugin file's are listed with --plugin-file FILE" in capsys.readouterr().err
    plugin = str(EXAMPLES / "plugins" / "near_wall.py")
    assert main(["behaviours", "near_wall", "--plugin-file", plugin]) == 0
    out = capsys.readouterr().out
    assert out.startswith(f"near_wall  (condition; from {plugin})")
    assert "closer_than: int" in out
    assert main(["behaviours", "--plugin-file", "no_such.py"]) == 2
    assert "--plugin-file no_such.py: no such file" in capsys.readouterr().err


#: a plugin whose docstrings are written in reST, as Python's and Sphinx's habit has them
REST_DOCS = '''\
from roomba_bt.behaviours import BOOL, Condition, Param, declare


@declare("s39_rest", kind="condition", reads=(7,),
         params=[Param("side", BOOL, default=True, doc="read ``left`` **first**")])
class Rest(Condition):
    """True where :class:`~roomba_bt.behaviours.Condition`'s ``check`` says, *see*
    `the spec <https://example.org/oi>`_ and :func:`roomba_bt.oi.commands.safe`.

    The rest of the docstring is no part of the entry.
    """

    def check(self, snapshot):
        return True
'''


def test_behaviours_prints_a_docstring_s_rest_as_a_terminal_reads_it(
    tmp_path: Path, capsys: Capsys
) -> None:
    """A plugin's docstring was printed as written (````check````, ``:class:`~...```); its
    literals and roles are code in single backquotes, as roomba-bt's own messages write it,
    its link its text and address, its stresses their words. ``--json`` keeps it as written:
    data for a program that may render reST itself."""
    plugin = tmp_path / "rest.py"
    plugin.write_text(REST_DOCS)
    assert main(["behaviours", "s39_rest", "--plugin-file", str(plugin)]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[1] == (
        "    True where `Condition`'s `check` says, see the spec (https://example.org/oi) and "
        "`roomba_bt.oi.commands.safe`."
    ), out
    assert out[2] == "    side: bool, default true  read `left` first", out
    assert main(["behaviours", "s39_rest", "--plugin-file", str(plugin), "--json"]) == 0
    (entry,) = json.loads(capsys.readouterr().out)
    assert entry["doc"].startswith("True where :class:`~roomba_bt.behaviours.Condition`'s")
    assert main(["behaviours", "s39_rest", "--plugin-file", str(plugin), "--markdown"]) == 0
    assert "True where `Condition`'s `check` says" in capsys.readouterr().out


def test_behaviours_print_each_default_as_a_mission_writes_it(
    tmp_path: Path, capsys: Capsys
) -> None:
    """``behaviours`` printed a bool's default as Python's ``True``, its ``--markdown`` (the
    entries of docs/missions.md) as `` `False` ``, and a language word's options alike,
    where a mission writes ``true`` and ``false``."""
    plugin = tmp_path / "rest.py"
    plugin.write_text(REST_DOCS.replace("default=True", "default=False"))
    assert main(["behaviours", "s39_rest", "--plugin-file", str(plugin)]) == 0
    assert "    side: bool, default false  read `left` first" in capsys.readouterr().out
    assert main(["behaviours", "s39_rest", "--plugin-file", str(plugin), "--markdown"]) == 0
    assert "| `side` | bool |  | `false` | read `left` first |" in capsys.readouterr().out
    assert main(["behaviours", "parallel"]) == 0
    said = capsys.readouterr().out
    assert "memory: bool, default false;" in said and "synchronise: bool, default true;" in said
    assert main(["behaviours", "seek_dock", "--markdown"]) == 0
    assert "| `wait` | bool |  | `true` |" in capsys.readouterr().out
    assert main(["behaviours"]) == 0
    listed = capsys.readouterr().out
    assert "default True" not in listed and "default False" not in listed


@pytest.mark.parametrize(
    ("value", "written"),
    [
        (True, "true"), (False, "false"), (None, "null"), (2, "2"), (0.5, "0.5"),
        (float("inf"), ".inf"), (float("-inf"), "-.inf"), (float("nan"), ".nan"),
        ("10min", "10min"), ([1, True, None], "[1, true, null]"),
        ({"on": False}, "{on: false}"),
    ],
)  # fmt: skip
def test_a_value_is_written_as_yaml_writes_it(value: object, written: str) -> None:
    """The one spelling of a default or an initial value in every listing (``behaviours``,
    its Markdown, ``missions``: a shipped mission's ``default: null`` was listed "none", a
    text to YAML)."""
    from roomba_bt.printable import yaml_written

    assert yaml_written(value) == written


#: a plugin file with one good class, one declared wrongly and two that declare one name
PARTLY_BAD = """\
from py_trees.common import Status
from roomba_bt.behaviours import Action, declare


@declare("s31_fine", kind="action")
class Fine(Action):
    \"\"\"Loads.\"\"\"
    def update(self):
        return Status.SUCCESS


@declare("S31 Bad", kind="action")
class Bad(Action):
    \"\"\"Not snake_case.\"\"\"
    def update(self):
        return Status.SUCCESS


@declare("s31_twice", kind="action")
class Once(Action):
    \"\"\"The name's first.\"\"\"
    def update(self):
        return Status.SUCCESS


@declare("s31_twice", kind="action")
class Again(Action):
    \"\"\"The same name in the same file.\"\"\"
    def update(self):
        return Status.SUCCESS
"""


def test_behaviours_lists_what_a_plugin_file_loaded_beside_a_bad_class(
    tmp_path: Path, capsys: Capsys
) -> None:
    """One badly declared class left stdout empty (exit 2), where an installed plugin's
    good behaviours are still listed; the errors now follow the listing, exit 2 still. Two
    classes of one file that clash are told to rename one, not to be uninstalled."""
    plugin = tmp_path / "partly_bad.py"
    plugin.write_text(PARTLY_BAD)
    assert main(["behaviours", "s31_fine", "--plugin-file", str(plugin)]) == 2
    out, err = capsys.readouterr()
    assert out.startswith(f"s31_fine  (action; from {plugin})")
    said = [line for line in err.splitlines() if line.startswith("roomba-bt behaviours: --plugin")]
    assert len(said) == 2
    assert "Bad (" in said[0] and "declares itself wrongly: name 'S31 Bad' is not" in said[0]
    assert said[1].endswith(
        "a name clash between two classes of one plugin file; a mission that uses 's31_twice' "
        "is refused (exit 2) until one of them is renamed"
    )
    assert "installed plugin" not in err  # the file's errors are not the installed ones'
    assert main(["schema", "--plugin-file", str(plugin)]) == 2  # no schema without them
    out, err = capsys.readouterr()
    assert out == "" and "declares itself wrongly" in err


def test_schema_is_json_with_every_behaviour(capsys: Capsys) -> None:
    assert main(["schema"]) == 0
    schema = json.loads(capsys.readouterr().out)
    defs = schema["$defs"]
    for word in ("sequence", "parallel", "retry", "for_each", "subtree", "drive", "wall_follow"):
        assert word in defs
    drive = defs["drive"]["then"]  # drive's value when it is a mapping
    assert set(drive["properties"]) >= {"velocity", "radius", "distance"}
    assert drive["additionalProperties"] is False
    assert defs["turn"]["then"]["required"] == ["angle"]
    node = defs["node"]["else"]  # a node that is a mapping: one word and the modifiers
    assert {"drive", "name", "while", "until"} <= set(node["properties"])
    assert node["properties"]["drive"]["$ref"] == "#/$defs/drive"


def test_schema_with_a_plugin_file_describes_its_behaviours(capsys: Capsys) -> None:
    assert main(["schema"]) == 0
    assert "near_wall" not in json.loads(capsys.readouterr().out)["$defs"]
    plugin = str(EXAMPLES / "plugins" / "near_wall.py")
    assert main(["schema", "--plugin-file", plugin]) == 0
    assert "near_wall" in json.loads(capsys.readouterr().out)["$defs"]
    assert main(["schema", "--plugin-file", "no_such.py"]) == 2


@pytest.mark.parametrize("command", ["validate", "show"])
def test_a_terminal_escape_in_a_mission_never_reaches_the_screen(
    mission_file: Callable[..., Path], capsys: Capsys, command: str
) -> None:
    """``"\\e[2J"`` in a name, a description, a log message or a key cleared the user's
    screen through ``show`` (and the run's display, log and summary), and a key's path in an
    error line was printed raw."""
    mission = mission_file(
        'mission: "\\e[31mRED"\n'
        "tree:\n"
        "  sequence:\n"
        "    - mode: safe\n"
        '    - "\\e[2Jdrvie": {velocity: "\\e]0;t\\a"}\n'
        '    - log: "\\e[41m log"\n'
    )
    assert main([command, str(mission)]) == 2
    out, err = capsys.readouterr()
    lines = out.splitlines()
    if command == "validate":
        assert lines.pop() == f"{mission}: failed (4 errors)"
    assert lines[0] == (
        f"{mission}:1:10: control character U+001B (an escape such as \\e, \\x1b or \\a in "
        "quotes) is not allowed in a value: a text may hold printable characters, tabs and "
        "line breaks only"
    )
    assert [line.split(": control character U+001B")[0] for line in lines] == [
        f"{mission}:{at}" for at in ("1:10", "5:7", "5:32", "6:12")
    ]
    assert "\x1b" not in out + err
    assert "\x07" not in out + err


def test_show_a_library_lists_its_subtrees(
    mission_file: Callable[..., Path], capsys: Capsys
) -> None:
    """``show roomba-bt:lib/docking.yaml`` said "a mission needs a tree", as if the shipped
    library were broken; then that it is a library, not run (exit 2): it lists the library's
    subtrees, each with its doc: and parameters (library report finding 9)."""
    assert main(["show", "roomba-bt:lib/docking.yaml"]) == 0
    out = capsys.readouterr().out
    assert "\ndock  Dock from the beams (no Seek Dock)" in out
    assert "    time_limit: duration, default 10min  give up after this long\n" in out
    assert "needs a tree" not in out
    library = mission_file("subtrees:\n  pause: {tree: {wait: 1s}}\n", "lib.yaml")
    assert main(["show", str(library)]) == 0
    assert capsys.readouterr().out.endswith("\npause\n")
    assert main(["validate", str(library)]) == 0


def test_running_a_library_says_its_include_path_is_the_current_folders(
    tmp_path: Path, capsys: Capsys, monkeypatch: pytest.MonkeyPatch
) -> None:
    """``run common/lib/legs.yaml`` said ``include: [common/lib/legs.yaml]``, which a
    mission in ``missions/`` then wrote and was refused, "not found": an include is relative
    to its file (session 42, a stranger's finding). The shipped library's name is the same
    from everywhere, and said alone."""
    (tmp_path / "lib").mkdir()
    (tmp_path / "lib" / "legs.yaml").write_text("subtrees:\n  pause: {tree: {wait: 1s}}\n")
    monkeypatch.chdir(tmp_path)
    assert main(["run", "lib/legs.yaml", "--fast"]) == 2
    said = "include it in a mission (include: [lib/legs.yaml] from a mission in the current "
    assert said + "folder; an include is relative to its file) and use them there" in (
        capsys.readouterr().err
    )
    assert main(["run", "roomba-bt:lib/docking.yaml", "--fast"]) == 2
    err = capsys.readouterr().err
    assert "(include: [roomba-bt:lib/docking.yaml]) and use them there" in err, err


def test_a_plugin_that_did_not_load_is_said_by_behaviours_name_and_by_schema(
    capsys: Capsys, monkeypatch: pytest.MonkeyPatch
) -> None:
    """An entry point whose module is misspelt: ``behaviours typo_cond`` said only "unknown
    behaviour", ``schema`` nothing at all (its behaviours silently missing)."""
    from importlib.metadata import EntryPoint

    import roomba_bt.behaviours as behaviours

    registry = behaviours.builtin_registry()
    registry.load_entry_point(EntryPoint("typo", "typo_mdo", "roomba_bt.behaviours"))
    monkeypatch.setattr(behaviours, "default_registry", lambda: registry)
    assert main(["behaviours", "typo_cond"]) == 2
    err = capsys.readouterr().err
    assert "unknown behaviour 'typo_cond'" in err
    missing = "plugin 'typo' (typo_mdo): the entry point names typo_mdo, but there is no module"
    # said as `behaviours` says it when it lists (session 36: `roomba-bt: warning:` here)
    said = f"roomba-bt behaviours: error: {missing} 'typo_mdo' (written in its distribution's"
    assert said in err, err
    assert "perhaps of a plugin that did not load (below): 'typo' (typo_mdo)" in err, err
    # it does not import: no schema without its behaviours (tests/mission/test_broken_plugin_cli.py)
    assert main(["schema"]) == 2
    out, err = capsys.readouterr()
    assert not out and f"error: {missing}" in err
    assert main(["schema", "--skip-broken-plugins"]) == 0
    out, err = capsys.readouterr()
    assert json.loads(out) and f"warning: {missing}" in err


@pytest.mark.parametrize(
    ("name", "said"),
    [
        ("retry", "'retry' is a decorator of the mission language, not a behaviour: re-run "
         "the child after a failure (options: times: int, 1.., required)"),
        ("reactive_sequence", "'reactive_sequence' is a composite of the mission language"),
        ("subtree", "'subtree' is a word (the node that uses a subtree) of the mission"),
        ("until", "'until' is a modifier of the mission language, written beside any node's "
         "word, not a behaviour: run until this condition succeeds, then SUCCESS"),
        ("include", "'include' is a section of a mission file, not a behaviour"),
    ],
)  # fmt: skip
def test_behaviours_of_a_word_of_the_language_says_what_it_is(
    capsys: Capsys, name: str, said: str
) -> None:
    """``behaviours retry`` said ``unknown behaviour 'retry' (did you mean 'odometry'?)``;
    then it said what the word is, but exited 2 (asking is no error) and pointed a pip user
    to docs/missions.md, a page the wheel has not got."""
    assert main(["behaviours", name]) == 0
    out, err = capsys.readouterr()
    assert out.startswith(said) and not err
    assert "(every word of the language: roomba-bt behaviours --words)" in out
    assert "docs/missions.md" not in out


def test_behaviours_of_a_word_and_a_behaviour_lists_both(capsys: Capsys) -> None:
    """A word beside a behaviour: the word's answer, then the behaviour as ever; beside
    --json the word is an entry of the JSON list, before the behaviour, and stderr says
    nothing."""
    assert main(["behaviours", "timeout", "wait"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("'timeout' is a decorator of the mission language")
    assert "options: after: duration (s), 0.015.., required" in out
    assert "\nwait  (action" in out
    assert main(["behaviours", "--json", "timeout", "wait"]) == 0
    out, err = capsys.readouterr()
    assert [entry["name"] for entry in json.loads(out)] == ["timeout", "wait"]
    assert not err
    assert main(["behaviours", "timeout", "no_such_thing"]) == 2
    assert "unknown behaviour 'no_such_thing'" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("name", "is_", "options"),
    [
        ("retry", "a decorator of the mission language", ["times"]),
        ("reactive_sequence", "a composite of the mission language", ["memory", "name"]),
        ("until", "a modifier of the mission language, written beside any node's word", []),
        ("include", "a section of a mission file", []),
    ],
)
def test_behaviours_json_of_a_word_of_the_language_is_its_entry(
    capsys: Capsys, name: str, is_: str, options: list[str]
) -> None:
    """``behaviours --json retry`` printed nothing on stdout (the answer as text on
    stderr), exit 0: a script read an empty document as success (verify session 34)."""
    assert main(["behaviours", "--json", name]) == 0
    out, err = capsys.readouterr()
    [entry] = json.loads(out)
    assert (entry["name"], entry["kind"], entry["is"]) == (name, "language word", is_)
    assert [option["name"] for option in entry["parameters"]] == options
    assert entry["doc"] and not err


def test_behaviours_words_lists_every_word_of_the_language(capsys: Capsys) -> None:
    """No command listed the language's own words: ``--words`` does, one line each."""
    from roomba_bt.behaviours.language import MODIFIERS, RESERVED, WORDS

    assert main(["behaviours", "--words"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert len(lines) == len(RESERVED)
    assert [line.split("'")[1] for line in lines[: len(WORDS)]] == list(WORDS)
    for word in (*MODIFIERS, "include", "tree"):
        assert any(line.startswith(f"{word!r} is a ") for line in lines), word


def test_behaviours_markdown_prints_the_entry_docs_missions_md_holds(capsys: Capsys) -> None:
    """docs/missions.md said its reference "comes from the declarations", and a contributor
    typed each entry by hand to match the test: ``--markdown`` prints what the page holds."""
    doc = (Path(__file__).resolve().parents[2] / "docs" / "missions.md").read_text()
    assert main(["behaviours", "--markdown", "bump", "turn"]) == 0
    out = capsys.readouterr().out
    bump, turn = out.split("\n\n**`")
    assert bump.startswith(
        "**`bump`**: A bumper is pressed (packet 7: bit 0 right, bit 1 left).  \n"
    )
    assert turn.startswith("turn`**: ")
    for row in (line for line in out.splitlines() if line.startswith("| ")):
        assert row in doc, row
    assert "| `side` | one of left, right, any |  | `any` |  |" in out
    with pytest.raises(SystemExit) as refused:  # one format at a time: argparse's usage error
        main(["behaviours", "--markdown", "--json"])
    assert refused.value.code == 2
    assert "not allowed with argument" in capsys.readouterr().err


def test_behaviours_markdown_of_a_word_is_its_entry_on_stdout(capsys: Capsys) -> None:
    """``behaviours --markdown retry`` said its answer on stderr, stdout empty, exit 0
    (``--json retry`` and ``--words`` print on stdout): the word is an entry in the
    behaviours' shape, on stdout, before the behaviours asked for with it."""
    assert main(["behaviours", "--markdown", "retry", "bump"]) == 0
    out, err = capsys.readouterr()
    assert not err
    retry, bump = out.split("\n\n**`")
    assert retry.startswith(
        "**`retry`**: a decorator of the mission language, not a behaviour: re-run the child "
    )
    assert "| `times` | int | 1.. | **required** | attempts in all |" in retry
    assert bump.startswith("bump`**: A bumper is pressed")
    assert main(["behaviours", "--markdown", "until"]) == 0  # a word without options
    out, err = capsys.readouterr()
    assert out.startswith("**`until`**: a modifier of the mission language") and not err
    assert "| parameter |" not in out
    assert main(["behaviours", "--markdown", "retry", "no_such_thing"]) == 2
    assert "unknown behaviour 'no_such_thing'" in capsys.readouterr().err


def test_show_prints_what_a_mission_wrote_each_on_its_line(capsys: Capsys, tmp_path: Path) -> None:
    """The mission's name, its description and a parameter's value went raw into show's
    first and last lines: "\\n[ok] fake" started a line of its own. Escaped; the tree's
    names as before (py_trees draws a newline as a space, a renamed node quotes it)."""
    path = tmp_path / "faked.yaml"
    path.write_text(
        'mission: "faked\\n[ok] mission"\n'
        'description: "says ${word}"\n'
        "parameters:\n"
        "  word: {type: str, default: hi}\n"
        "tree:\n"
        '  wait: 1s\n  name: "waited\\n[ok] fake"\n'
    )
    assert main(["show", str(path), "-p", "word=x\n[ok] word"]) == 0
    out, _ = capsys.readouterr()
    assert not [line for line in out.splitlines() if line.startswith("[ok]")], out
    assert "faked\\x0a[ok] mission: says x\\x0a[ok] word" in out
    assert "parameters: word=x\\x0a[ok] word" in out


def test_show_cuts_a_long_description_and_parameter_value(capsys: Capsys, tmp_path: Path) -> None:
    """A description of 300,000 characters (or one a 100,000-character ``-p`` fills in) was
    printed whole on show's first line, and the parameter's value whole on its last: each
    is cut, its length said, as a long name is."""
    path = tmp_path / "long.yaml"
    path.write_text(
        f'mission: long\ndescription: "{"D" * 300_000} ${{word}}"\n'
        "parameters:\n  word: {type: str, default: hi}\ntree: {wait: 1s}\n"
    )
    assert main(["show", str(path), "-p", f"word={'W' * 100_000}"]) == 0
    out = capsys.readouterr().out
    assert len(out) < 1_000, len(out)
    first, *_, last = out.splitlines()
    assert first == f"long: {'D' * 500}... (400,001 characters)"
    assert last == f"parameters: word={'W' * 80}... (100,000 characters)"


def _installed(folder: Path, dist: str, module: str, cls: str) -> None:
    """A distribution ``dist`` on ``folder`` (put on sys.path by the caller) whose entry
    point ``module`` provides a condition ``cls`` named ``wiggle_s27``."""
    (folder / f"{module}.py").write_text(
        "from roomba_bt.behaviours import Condition, declare\n\n\n"
        f'@declare("wiggle_s27", kind="condition")\nclass {cls}(Condition):\n'
        f'    """{dist}\'s wiggle."""\n\n    def check(self, snapshot):\n        return True\n'
    )
    info = folder / f"{dist.replace('-', '_')}-1.0.dist-info"
    info.mkdir(parents=True)
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {dist}\nVersion: 1.0\n")
    (info / "entry_points.txt").write_text(f"[roomba_bt.behaviours]\n{module} = {module}\n")


def test_behaviours_of_a_name_two_plugins_declare_is_the_clash_and_exit_2(
    capsys: Capsys, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """It showed one of the two as if it were in use, and exit 0; the clash named one side
    with its distribution and the other without (which to uninstall was half said)."""
    import roomba_bt.behaviours as behaviours
    from roomba_bt.behaviours.registry import ENTRY_POINT_GROUP, Registry

    _installed(tmp_path, "bt-first", "s27_first", "FirstWiggle")
    _installed(tmp_path, "bt-second", "s27_second", "SecondWiggle")
    monkeypatch.syspath_prepend(str(tmp_path))
    registry = Registry(entry_point_group=ENTRY_POINT_GROUP)
    for cls in behaviours.builtin_registry():
        registry.register(cls.cls, validated=True)
    monkeypatch.setattr(behaviours, "default_registry", lambda: registry)
    assert main(["behaviours", "wiggle_s27"]) == 2
    out, _ = capsys.readouterr()
    assert out.startswith("wiggle_s27  (declared by two plugins: a mission that uses it is ")
    assert "'s wiggle" not in out  # neither doc, as if it were the one in use
    assert (
        "error: 'wiggle_s27' is declared by two plugins, s27_first.FirstWiggle ('s27_first' "
        "(s27_first, from bt-first)) and s27_second.SecondWiggle ('s27_second' (s27_second, "
        "from bt-second))"
    ) in out
    assert main(["behaviours", "wiggle_s27", "--json"]) == 2
    [entry] = json.loads(capsys.readouterr().out)
    assert entry["clash"]["severity"] == "error"
    assert main(["behaviours", "wait"]) == 0  # a name no one contests


def test_a_plugin_file_declaring_a_word_of_the_language_is_told_to_rename_it(
    tmp_path: Path, capsys: Capsys
) -> None:
    """A file's class named ``retry`` has no package spelling to be reached by: the refusal
    says what was found, why, and what to do (it read "the word is the language's, and it is
    not used (or rename it)")."""
    plugin = tmp_path / "worded.py"
    plugin.write_text(
        "from roomba_bt.behaviours import Condition, declare\n\n\n"
        '@declare("retry", kind="condition")\nclass Again(Condition):\n'
        '    """Takes a word."""\n\n    def check(self, snapshot):\n        return True\n'
    )
    assert main(["behaviours", "wait", "--plugin-file", str(plugin)]) == 2
    err = capsys.readouterr().err
    assert (
        "declares the name 'retry', which is a word of the mission language: 'retry' in a "
        "mission always means the language's own, so this behaviour cannot be used; rename it "
        "in its @declare"
    ) in err
