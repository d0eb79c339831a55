"""The malformed-mission corpus: each file ends with the exact errors it must produce.

A file's trailing ``# expect: LINE:COL: message`` comments list every diagnostic, in order;
``# baud: N``, ``# params: name=value ...`` and ``# allow-plugin-files`` lines set what the
command line would. The
test also checks that ``roomba-bt validate`` prints the same lines and exits 2, with no
traceback.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import pytest

from roomba_bt.cli import main
from roomba_bt.mission import (
    Diagnostic,
    MissionError,
    Permissions,
    compile_mission,
    load_mission,
)
from roomba_bt.mission.wording import COMMAND_LINE

CORPUS = Path(__file__).parent / "malformed"
FILES = sorted(CORPUS.glob("*.yaml"))


def expectations(path: Path) -> tuple[list[str], int, dict[str, str] | None]:
    text = path.read_text(encoding="utf-8")
    expected = re.findall(r"^# expect: (.*)$", text, re.M)
    baud = re.search(r"^# baud: (\d+)$", text, re.M)
    params = re.search(r"^# params: (.*)$", text, re.M)
    given = dict(item.split("=", 1) for item in params.group(1).split()) if params else None
    return expected, int(baud.group(1)) if baud else 115200, given


def granted(path: Path) -> Permissions:
    """``# allow-plugin-files``: the file is compiled as with ``--allow-plugin-files``. The
    corpus's expected lines are what ``roomba-bt validate`` prints (checked below), so the
    messages name the command line's flags (``-p``), as it words them."""
    text = path.read_text(encoding="utf-8")
    allowed = re.search(r"^# allow-plugin-files$", text, re.M) is not None
    return Permissions(plugin_files=allowed, wording=COMMAND_LINE)


@pytest.fixture(autouse=True)
def _in_the_corpus(monkeypatch: pytest.MonkeyPatch) -> None:
    """Run from the corpus's folder: a message names the folders it looked in relative to
    the current directory, and each file's expectation holds wherever the tests run."""
    monkeypatch.chdir(CORPUS)


def test_the_corpus_has_at_least_30_missions() -> None:
    assert len(FILES) >= 30


@pytest.mark.parametrize("path", FILES, ids=lambda p: p.stem)
def test_malformed_mission_gives_its_exact_errors(path: Path) -> None:
    expected, baud, params = expectations(path)
    assert expected, f"{path.name} has no '# expect:' line"
    mission, diagnostics = compile_mission(path, params, baud=baud, permissions=granted(path))
    assert mission is None
    assert [f"{d.line}:{d.column}: {d.message}" for d in diagnostics] == expected
    for d in diagnostics:
        assert d.file.endswith(path.name) or "lib" in d.file
        assert str(d).startswith(f"{d.file}:{d.line}:{d.column}: ")
    with pytest.raises(MissionError) as raised:
        load_mission(path, params, baud=baud, permissions=granted(path))
    assert raised.value.diagnostics == diagnostics


@pytest.mark.parametrize("path", FILES[:5] + FILES[-5:], ids=lambda p: p.stem)
def test_validate_prints_them_and_exits_2(path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    expected, baud, params = expectations(path)
    argv = ["validate", str(path), "--baud", str(baud)]
    if granted(path).plugin_files:
        argv.append("--allow-plugin-files")
    for name, value in (params or {}).items():
        argv += ["-p", f"{name}={value}"]
    assert main(argv) == 2
    out, err = capsys.readouterr()
    lines = out.splitlines()
    assert lines.pop() == f"{path}: failed ({len(expected)} error{'s' * (len(expected) > 1)})"
    assert len(lines) == len(expected)
    for line, want in zip(lines, expected, strict=True):
        assert f":{want}" in line
    assert "Traceback" not in out + err


def test_a_tab_and_a_byte_that_is_not_utf8_are_placed_and_named(tmp_path: Path) -> None:
    """Two things a stranger's editor leaves: a tab in the indentation (PyYAML's sentence
    says nothing of tabs) and a Latin-1 byte (the position of the byte, not 1:1)."""
    tabbed = tmp_path / "tabbed.yaml"
    tabbed.write_text("tree:\n  sequence:\n\t- mode: safe\n")
    _, (problem,) = compile_mission(tabbed)
    assert (problem.line, problem.column) == (3, 1)
    assert problem.message.startswith("YAML syntax error: ")
    assert problem.message.endswith("(a tab: YAML indents with spaces)")
    latin = tmp_path / "latin.yaml"
    latin.write_bytes(b"tree:\n  sequence:\n    - log: {message: caf\xe9}\n")
    _, (problem,) = compile_mission(latin)
    assert (problem.line, problem.column) == (3, 25)
    assert problem.message == (
        "mission file is not UTF-8 text: byte 0xe9 at offset 42 (invalid continuation byte; "
        "it reads as 'é' in Windows-1252 or Latin-1, an older encoding: save the file as UTF-8)"
    )


def _nested_sequences(nodes: int) -> str:
    """A tree ``nodes`` deep: sequences inside each other around one ``mode: safe``."""
    return "{sequence: [" * (nodes - 1) + "{mode: safe}" + "]}" * (nodes - 1)


def test_a_tree_nested_past_the_limit_is_refused_once_where_it_goes_over(
    tmp_path: Path,
) -> None:
    """A tree 250 deep was "internal error while compiling (RecursionError ...)"; one that
    deep is now refused by the YAML reader (two collections a level), 140 by the parser."""
    from roomba_bt.mission.nodes import MAX_TREE_DEPTH

    path = tmp_path / "deep.yaml"
    path.write_text(f"mission: deep\ntree: {_nested_sequences(MAX_TREE_DEPTH)}\n")
    assert compile_mission(path)[1] == []
    for nodes in (MAX_TREE_DEPTH + 1, 140):
        path.write_text(f"mission: deep\ntree: {_nested_sequences(nodes)}\n")
        _, (problem,) = compile_mission(path)
        # the node past the limit: the 101st "{", after "tree: " and 12 characters a level
        assert (problem.line, problem.column) == (2, 7 + 12 * MAX_TREE_DEPTH)
        assert problem.message.startswith(f"the tree nests more than {MAX_TREE_DEPTH} nodes")


def test_subtrees_count_toward_the_depth_as_they_are_built(tmp_path: Path) -> None:
    """Subtrees are expanded where they are used: the tree built is as deep as both."""
    from roomba_bt.mission.nodes import MAX_TREE_DEPTH

    half = MAX_TREE_DEPTH // 2 + 1
    path = tmp_path / "deep.yaml"
    inner = _nested_sequences(half)
    outer = "{sequence: [" * (half - 1) + "{subtree: inner}" + "]}" * (half - 1)
    path.write_text(f"mission: deep\nsubtrees:\n  inner: {{tree: {inner}}}\ntree: {outer}\n")
    _, problems = compile_mission(path)
    assert [p.line for p in problems] == [3]
    assert problems[0].message.startswith(f"the tree nests more than {MAX_TREE_DEPTH} nodes")


def test_subtrees_that_multiply_are_stopped_while_they_are_expanded(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """30 levels of a subtree using the next twice (2^30 leaves, 1.9 KB) hung ``validate``
    past 1.3 GB: the count stops the expansion at the limit. Counted in nodes parsed, not
    in seconds (a busy CI host took 8 s for what takes one)."""
    from roomba_bt.mission.nodes import MAX_TREE_NODES, NodeParser

    parsed = 0
    parse = NodeParser.node

    def counted(self: NodeParser, *args: Any, **kwargs: Any) -> Any:
        nonlocal parsed
        parsed += 1
        return parse(self, *args, **kwargs)

    monkeypatch.setattr(NodeParser, "node", counted)

    levels = [f"  s{i}: {{tree: {{sequence: [{{subtree: s{i + 1}}}, {{subtree: s{i + 1}}}]}}}}"
              for i in range(30)]  # fmt: skip
    path = tmp_path / "expo.yaml"
    path.write_text("subtrees:\n" + "\n".join(levels) + "\n  s30: {tree: {wait: 0s}}\n"
                    "tree: {subtree: s0}\n")  # fmt: skip
    _, (problem,) = compile_mission(path)
    assert parsed <= MAX_TREE_NODES + 100  # the 2^30 nodes were never reached
    assert problem.message.startswith(f"the tree grows past {MAX_TREE_NODES:,} nodes here")
    assert problem.yaml_path.endswith(".subtree")  # at a subtree use, not at a leaf


def test_the_cli_names_a_deep_file_with_exit_2_and_a_short_path(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "deep.yaml"
    path.write_text(f"mission: deep\ntree: {_nested_sequences(140)}\n")
    assert main(["validate", str(path)]) == 2
    out, err = capsys.readouterr()
    line, verdict = out.splitlines()
    assert verdict == f"{path}: failed (1 error)"
    assert "nodes deep here" in line
    assert line.endswith(" ... (95 more) ... sequence[0].sequence[0].sequence[0]]")
    assert len(line) < 300
    assert "Traceback" not in out + err


def test_a_long_yaml_path_is_shown_by_its_ends() -> None:
    from roomba_bt.mission.diagnostics import PATH_SHOWN, Diagnostic, shortened_path

    short = "tree.sequence[2].drive.velocity"
    assert shortened_path(short) == short
    steps = [f"sequence[{i}]" for i in range(40)]
    long = ".".join(["tree", *steps, "mode"])
    assert len(long) > PATH_SHOWN
    assert shortened_path(long) == (
        "tree.sequence[0].sequence[1] ... (36 more) ... sequence[38].sequence[39].mode"
    )
    assert str(Diagnostic("m.yaml", 1, 2, "bad", long)).endswith(f"[{shortened_path(long)}]")
    assert Diagnostic("m.yaml", 1, 2, "bad", long).yaml_path == long  # the data keeps it whole


def test_a_value_out_of_range_from_the_command_line_says_so_where_it_is_used(
    tmp_path: Path,
) -> None:
    """``run dock -p search_speed=600mm/s`` was refused at a line of the shipped docking
    library, a file the user never wrote, with nothing tying it to their ``-p``."""
    (tmp_path / "lib.yaml").write_text(
        "subtrees:\n"
        "  go:\n"
        "    parameters: {v: {type: speed, default: 100 mm/s}, n: {type: int, default: 2}}\n"
        "    tree:\n"
        "      repeat: {times: '${n}', do: {drive: {velocity: '${v}', distance: 5cm}}}\n"
    )
    path = tmp_path / "m.yaml"
    path.write_text(
        "include: [lib.yaml]\n"
        "parameters: {speed: {type: speed, default: 100 mm/s}, laps: {type: int, default: 2}}\n"
        "tree:\n"
        "  sequence:\n"
        "    - mode: safe\n"
        "    - drive: {velocity: '${speed}', distance: 5cm}\n"
        "    - subtree: {id: go, v: '${speed}', n: '${laps}'}\n"
    )
    _, problems = compile_mission(path, {"speed": "600mm/s"})
    # each said in the mission: the second at the subtree's use, which passed it on
    assert [(p.file.rsplit("/", 1)[-1], p.line, p.message) for p in problems] == [
        ("m.yaml", 6, "drive: velocity 600 mm/s is out of range: allowed -500..500 mm/s "
                      "(${speed} is speed=600mm/s, given in params)"),
        ("m.yaml", 7, "drive: velocity 600 mm/s is out of range: allowed -500..500 mm/s "
                      "(${v} is speed=600mm/s, given in params)"),
    ]  # fmt: skip
    _, (problem,) = compile_mission(path, {"laps": "0"})
    assert (problem.line, problem.message) == (
        7,
        "repeat.times must be at least 1, got 0 (${n} is laps=0, given in params)",
    )
    assert compile_mission(path, {"speed": "400mm/s"})[1] == []


def test_a_bad_value_from_a_parameter_s_default_names_the_parameter_and_its_default(
    tmp_path: Path,
) -> None:
    """The upgrade report's ``turn: {speed: "${creep}"}`` with ``creep`` defaulting to 10
    mm/s was refused at the use only: nothing said the value was creep's default, at line 3,
    or that ``-p creep=15mm/s`` would do. An error a leaf makes as a whole names the default
    whose value it says (the speed, not the distance); a value set with -p is said as set."""
    path = tmp_path / "m.yaml"
    path.write_text(
        "parameters:\n"
        "  dist: {type: distance, default: 20cm}\n"
        "  creep: {type: speed, default: 10 mm/s}\n"
        "  laps: {type: int, default: 0}\n"
        "tree:\n"
        "  sequence:\n"
        "    - mode: safe\n"
        "    - turn: {angle: 45deg, speed: '${creep}'}\n"
        "    - drive: {velocity: '${creep}', distance: '${dist}'}\n"
        "    - repeat: {times: '${laps}', do: {log: hi}}\n"
        "    - turn: {angle: 5deg, speed: '-${creep}'}\n"
    )
    _, problems = compile_mission(path)
    assert [f"{p.line}:{p.column}: {p.message}" for p in problems] == [
        "8:35: turn: speed 10 mm/s is out of range: allowed 15..500 mm/s (a wheel asked for "
        "less than 15 mm/s stands still: the speed controller turns it in steps of about 28.5 "
        "mm/s) (${creep} is 10 mm/s, the default of parameter creep at 3:33: give "
        "params={'creep': '15mm/s'}, or another default there)",
        "9:7: drive: drive at 10 mm/s (below half the speed controller's step of about 28.5 "
        "mm/s: the wheels stand still) never covers its distance (its centre does not move): it "
        "would run for ever; give a speed of at least 15 mm/s, or end it by angle or duration "
        "(${creep} is 10 mm/s, the default of parameter creep at 3:33: give "
        "params={'creep': 'VALUE'}, or another default there)",
        "10:23: repeat.times must be at least 1, got 0 (${laps} is 0, the default of parameter "
        "laps at 4:30: give params={'laps': 'VALUE'}, or another default there)",
        "11:34: turn: speed -10 mm/s is out of range: allowed 15..500 mm/s (${creep} is 10 "
        "mm/s, the default of parameter creep at 3:33: give params={'creep': 'VALUE'}, or "
        "another default there)",
    ]
    _, problems = compile_mission(path, {"creep": "12mm/s", "laps": "1"})
    assert "(${creep} is creep=12mm/s, given in params)" in problems[0].message
    assert all("default" not in p.message for p in problems), problems
    _, problems = compile_mission(path, {"creep": "15mm/s", "laps": "1"})
    assert [p.line for p in problems] == [11]  # only the negated speed is left


def test_a_bad_value_a_subtree_use_passes_names_that_use(tmp_path: Path) -> None:
    """``subtree: {id: go, speed: 900 mm/s}`` was refused only in the subtree's body (its
    line and YAML path), naming none of the uses: each use that gives a bad value is named
    now, as a ``-p`` value is; one given a good value is not. A key given as a ``str``
    parameter (an output "port") names its use too."""
    path = tmp_path / "m.yaml"
    path.write_text(
        "blackboard: {out: int}\n"
        "subtrees:\n"
        "  go:\n"
        "    parameters: {speed: {type: speed}, result: {type: str, default: out}}\n"
        "    tree:\n"
        "      sequence:\n"
        "        - drive: {velocity: '${speed}', distance: 10cm}\n"
        "        - set: {key: '${result}', value: 1}\n"
        "tree:\n"
        "  sequence:\n"
        "    - mode: safe\n"
        "    - subtree: {id: go, speed: 100 mm/s}\n"
        "    - subtree: {id: go, speed: 900 mm/s}\n"
        "    - subtree: {id: go, speed: -600 mm/s, result: nokey}\n"
    )
    _, problems = compile_mission(path)
    assert [(p.line, p.column, p.message) for p in problems] == [
        (7, 29, "drive: velocity -600 mm/s is out of range: allowed -500..500 mm/s "
                f"(${{speed}} is -600 mm/s, given at {path}:14:32 to subtree go)"),
        (7, 29, "drive: velocity 900 mm/s is out of range: allowed -500..500 mm/s "
                f"(${{speed}} is 900 mm/s, given at {path}:13:32 to subtree go)"),
        (8, 22, f"set.key (${{result}} is nokey, given at {path}:14:51 to subtree go): "
                "unknown blackboard key 'nokey'; known: out"),
    ]  # fmt: skip


def test_a_mission_or_include_over_a_mebibyte_is_named_not_read(tmp_path: Path) -> None:
    from roomba_bt.yamlsource import MAX_FILE_BYTES

    big = "# " + "x" * MAX_FILE_BYTES + "\n"
    path = tmp_path / "big.yaml"
    path.write_text("mission: big\ntree: {wait: 1s}\n" + big)
    _, (problem,) = compile_mission(path)
    assert (problem.line, problem.column) == (1, 1)
    assert problem.message.startswith("mission file of 1,048,6")
    (tmp_path / "lib.yaml").write_text("subtrees: {}\n" + big)
    path.write_text("include: [lib.yaml]\ntree: {wait: 1s}\n")
    _, problems = compile_mission(path)
    assert any("lib.yaml" in p.file and "at most 1,048,576 are read" in p.message for p in problems)


@pytest.mark.parametrize(
    ("text", "expected"),
    [("mission: nul\ntree:\n  sequence: [{mode: safe}, stop]\n\x00\n", "4:1: control character "
      "U+0000 is not allowed in a YAML file: it may hold printable characters, tabs and line "
      "breaks only"),
     ("mission: bell\ntree:\n  sequence: [{mode: safe}, stop]\n  # bell \x07 here\n", "4:10: "
      "control character U+0007 is not allowed in a YAML file: it may hold printable "
      "characters, tabs and line breaks only")],
    ids=["nul", "bel-in-a-comment"],
)  # fmt: skip
def test_a_control_character_in_the_file_is_one_line_at_its_place(
    tmp_path: Path, text: str, expected: str, capsys: pytest.CaptureFixture[str]
) -> None:
    """A NUL or a BEL (in a comment too) was ``1:1: YAML error: unacceptable character
    #x0000 ...`` and a second line ``in "<unicode string>", position 52``."""
    path = tmp_path / "ctl.yaml"
    path.write_text(text, encoding="utf-8")
    assert main(["validate", str(path)]) == 2
    out, err = capsys.readouterr()
    assert out.splitlines() == [f"{path}:{expected}", f"{path}: failed (1 error)"]
    assert "Traceback" not in out + err


def test_an_error_line_escapes_control_characters_of_its_path_and_file() -> None:
    """What the reader cannot refuse (a file's name, a path built from elsewhere) is still
    shown as ``\\x1b``, never sent raw to the terminal; tab and newline stay in a message."""
    line = str(Diagnostic("a\x1b[2J.yaml", 5, 7, "unknown node\tx", "tree.\x1b[2Jdrvie\n"))
    assert line == "a\\x1b[2J.yaml:5:7: unknown node\tx [tree.\\x1b[2Jdrvie\\x0a]"
