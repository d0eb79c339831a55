"""What a teacher's class of 30 students wrote that a message now meets (session 31, the
classroom report): a missing space after a colon, indentation and an unclosed ``{``, a
version ``1.10`` where a text is meant, files saved by a word processor or in an older
encoding. Each file's bytes are as the students' were."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from roomba_bt.cli import main
from roomba_bt.mission import compile_mission

Capsys = pytest.CaptureFixture[str]


def _problems(tmp_path: Path, data: bytes, name: str = "m.yaml") -> list[str]:
    """``line:column: message`` of each diagnostic of a file holding ``data`` as written."""
    path = tmp_path / name
    path.write_bytes(data)
    _, problems = compile_mission(path)
    return [f"{p.line}:{p.column}: {p.message}" for p in problems]


def test_a_word_and_its_value_without_a_space_say_to_write_one(tmp_path: Path) -> None:
    """``- mode:safe`` is the text 'mode:safe' to YAML, read as ``package:name``: it was "no
    installed plugin package is called 'mode'", which sent students looking for plugins."""
    text = "mission: m\ntree:\n  sequence:\n    - mode:safe\n    - wait:2s\n    - mode safe\n"
    assert _problems(tmp_path, text.encode()) == [
        "4:7: unknown node 'mode:safe': 'mode:safe' is one text to YAML: write a space after "
        "the colon: `mode: safe`",
        "5:7: unknown node 'wait:2s': 'wait:2s' is one text to YAML: write a space after the "
        "colon: `wait: 2s`",
        "6:7: unknown node 'mode safe': write a colon and a space after the word: `mode: safe`",
    ]


def test_a_no_break_space_after_the_colon_is_named(tmp_path: Path) -> None:
    """Pasted from a web page: the value's colon is followed by U+00A0, no space to YAML."""
    text = "mission: m\ntree:\n  sequence:\n    - mode: safe\n    - wait:\xa01s\n"
    assert _problems(tmp_path, text.encode()) == [
        "5:7: unknown node 'wait:\\xa01s': '\\xa0' (U+00A0 NO-BREAK SPACE) after the colon is "
        "no space to YAML: write a plain space: `wait: 1s`"
    ]


def test_a_no_break_space_after_a_top_level_colon_is_named_at_its_place(
    tmp_path: Path,
) -> None:
    """``mission:\\xa0x`` runs on into the next line as one text: the error was "mapping
    values are not allowed in this context" at 2:5, naming neither the space nor line 1."""
    text = "mission:\xa0nbsp\ntree:\n  sequence:\n    - stop\n"
    assert _problems(tmp_path, text.encode()) == [
        "1:9: YAML syntax error: '\\xa0' (U+00A0 NO-BREAK SPACE) after ':' is no space to YAML, "
        "so the key, the colon and the value are one text: write a plain space after the colon "
        "(mapping values are not allowed in this context at 2:5)"
    ]


#: what every indentation hint ends with
LINE_UP = "the entries of one list or mapping start in the same column)"
#: (file as written, the line and column of the error and where its structure began, or
#: None, the message)
STRUCTURE_ERRORS = [
    pytest.param(
        "mission: half\nparameters:\n  speed: {type: speed, default: 200 mm/s\ntree:\n"
        "  sequence:\n    - mode: safe\n",
        (4, 5, (3, 10)),
        "YAML syntax error: did not find expected ',' or '}' (in the { opened at 3:10: is its } "
        "missing?)",
        id="an unclosed brace",
    ),
    pytest.param(
        "mission: mix\ntree:\n  sequence:\n    - mode: safe\n  - stop\n",
        (5, 3, (3, 3)),
        "YAML syntax error: did not find expected key (in the mapping that starts at 3:3; line "
        f"5 is indented 2 spaces, the list item on line 4 above it 4: {LINE_UP}",
        id="a list item one level out",
    ),
    pytest.param(
        "mission: mix\ntree:\n  sequence:\n    - mode: safe\n     - stop\n",
        (5, 6, (4, 5)),
        "YAML syntax error: did not find expected '-' indicator (in the list that starts at "
        f"4:5; line 5 is indented 5 spaces, the list item on line 4 above it 4: {LINE_UP}",
        id="a list item a space in",
    ),
]


#: a node's option or modifier out of line (session 38), as STRUCTURE_ERRORS
MISPLACED = [
    pytest.param(
        "mission: m\ntree:\n  sequence:\n    - mode: safe\n    - drive: {velocity: 100 mm/s}\n"
        "        until: bump\n",
        (6, 9, (5, 7)),
        "until: in column 9 is in no node's mapping (YAML: did not find expected key): until "
        "is a modifier, written beside its node's word in the same column: the node above, "
        "drive (line 5), has its word in column 7; write until: there, indented 6 spaces",
        id="until under a word's value",
    ),
    pytest.param(
        "mission: m\ntree:\n  sequence:\n    - mode: safe\n    - drive:\n"
        "        velocity: 100 mm/s\n   until: bump\n",
        (7, 4, (3, 3)),
        "until: in column 4 is in no node's mapping (YAML: did not find expected key): until "
        "is a modifier, written beside its node's word in the same column: the node above, "
        "drive (line 5), has its word in column 7; write until: there, indented 6 spaces",
        id="until out of its node",
    ),
    pytest.param(
        "mission: m\ntree:\n  sequence:\n    - mode: safe\n        while: bump\n",
        (5, 9, None),
        "while: in column 9 is in no node's mapping (YAML: mapping values are not allowed in "
        "this context): while is a modifier, written beside its node's word in the same "
        "column: the node above, mode (line 4), has its word in column 7; write while: there, "
        "indented 6 spaces",
        id="while under a word's text",
    ),
    pytest.param(
        "mission: m\ntree:\n  sequence:\n    - fallback:\n        - bump: any\n"
        "        - cliff: any\n       until: {bump: any}\n",
        (7, 8, (4, 7)),
        "until: in column 8 is in no node's mapping (YAML: did not find expected key): until "
        "is a modifier, written beside its node's word in the same column: cliff's (line 6) "
        "is column 11, fallback's (line 4) column 7; write until: in the column of the node "
        "it belongs to",
        id="until between two nodes",
    ),
    pytest.param(
        "mission: m\ntree:\n  sequence:\n    - turn:\n        angle: 90deg\n"
        "       speed: 100 mm/s\n",
        (6, 8, (4, 7)),
        "speed: in column 8 is in no node's mapping (YAML: did not find expected key): the "
        "node above, turn (line 4), has its options in column 9 (angle, line 5) and its "
        "modifiers (name, while, until) beside its word, in column 7: write speed: in the "
        "column of the ones it belongs with",
        id="an option a space out",
    ),
]


@pytest.mark.parametrize(("text", "where", "problem"), [*STRUCTURE_ERRORS, *MISPLACED])
def test_a_structure_error_says_where_the_structure_began(
    text: str,
    where: tuple[int, int, tuple[int, int] | None],
    problem: str,
    tmp_path: Path,
    capsys: Capsys,
) -> None:
    """PyYAML's context ("while parsing a flow mapping ... line 3, column 10") was dropped: the
    line given (``tree:`` after a ``{`` left open) looked fine. Both places are said, in the
    message and, the structure's start, in ``--format json``'s ``began_at``. An ``until:``
    indented under no node (MISPLACED) got YAML's words alone ("did not find expected key"):
    now what was found (the key and its column), what is allowed (its node's word's column,
    or its options') and the fix, at the key's place; ``began_at`` as before."""
    line, column, began = where
    assert _problems(tmp_path, text.encode()) == [f"{line}:{column}: {problem}"]
    assert main(["validate", "--format", "json", str(tmp_path / "m.yaml")]) == 2
    [diagnostic] = json.loads(capsys.readouterr().out)["diagnostics"]
    assert (diagnostic["line"], diagnostic["column"]) == (line, column)
    expected = None if began is None else {"line": began[0], "column": began[1]}
    assert diagnostic["began_at"] == expected


def test_a_key_out_of_line_under_no_list_item_keeps_yaml_s_words(tmp_path: Path) -> None:
    """A subtree's ``tree:`` a space in has no node above it to name: YAML's message stays."""
    text = "mission: m\nsubtrees:\n  go:\n    doc: hi\n     tree: {stop}\ntree:\n  stop\n"
    assert _problems(tmp_path, text.encode()) == [
        "5:10: YAML syntax error: mapping values are not allowed in this context"
    ]


@pytest.mark.parametrize(
    ("written", "shown"),
    [("1.10", "1.1"), ("3.10", "3.1"), ("0x1F", "31"), ("1.5e+3", "1500.0")],
)
def test_a_number_that_shows_other_digits_is_refused_where_a_text_is_meant(
    written: str, shown: str, tmp_path: Path
) -> None:
    """A version ``1.10`` was logged as ``1.1``, though the docs say a text's place never gets
    a number other than the digits shown (``01234`` and ``12:30`` were refused already)."""
    text = (
        f"mission: m\nparameters:\n  ver: {{type: str, default: {written}}}\n"
        f"tree:\n  sequence:\n    - log: {written}\n"
    )
    said = f"'{written}' is read by YAML as the number {shown}, not as written: quote it where "
    quote = f'a text is meant ("{written}")'
    assert _problems(tmp_path, text.encode()) == [
        f"3:29: parameter ver: {said}{quote}",
        f"6:12: log.message: {said}{quote}",
    ]


def test_a_number_that_shows_its_own_digits_is_still_a_text(tmp_path: Path) -> None:
    text = "mission: m\nparameters:\n  ver: {type: str, default: 2.5}\n  n: {type: float, "
    text += "default: 1.10}\ntree:\n  sequence:\n    - log: 3\n    - log: '${ver}'\n"
    assert _problems(tmp_path, text.encode()) == []


WORD_PROCESSORS = [
    pytest.param(
        b"{\\rtf1\\ansi\\ansicpg1252\\cocoartf2709\n\\cocoatextscaling0\\cocoaplatform0",
        "1:1: mission file is not UTF-8 text: this is an RTF document (TextEdit's default): "
        "save it as plain text, UTF-8",
        id="RTF",
    ),
    pytest.param(
        b"PK\x03\x04\x14\x00\x00\x00\x00\x00\x8e:\x86]word/document.xml",
        "1:1: mission file is not UTF-8 text: this is a ZIP archive, such as a Word (.docx) or "
        "OpenDocument file: save it as plain text, UTF-8",
        id="docx",
    ),
    pytest.param(
        b"mission: cp1252\ndescription: \x93quoted\x94\ntree: {log: x}\n",
        "2:14: mission file is not UTF-8 text: byte 0x93 at offset 29 (invalid start byte; it "
        "reads as '\u201c' in Windows-1252 or Latin-1, an older encoding: save the file as "
        "UTF-8)",
        id="Windows-1252",
    ),
    pytest.param(
        b'mission: latin1\ndescription: "Zo\xeb f\xe4hrt"\ntree: {log: x}\n',
        "2:17: mission file is not UTF-8 text: byte 0xeb at offset 32 (invalid continuation "
        "byte; it reads as '\u00eb' in Windows-1252 or Latin-1, an older encoding: save the "
        "file as UTF-8)",
        id="Latin-1",
    ),
    pytest.param(  # a program's start (ELF): it was "byte 0xd0 at offset 24 ... it reads
        # as 'Ð' in Windows-1252 or Latin-1, an older encoding: save the file as UTF-8"
        b"\x7fELF\x02\x01\x01\x00" + bytes(16) + b"\xd0\x00",
        "1:1: mission file is not UTF-8 text: this is a binary file (it holds NUL bytes), not "
        "text: YAML is plain text, UTF-8",
        id="binary",
    ),
    pytest.param(
        b"mission: midbom\n\xef\xbb\xbftree:\n  sequence:\n    - stop\n",
        "2:1: '\\ufeff' (U+FEFF ZERO WIDTH NO-BREAK SPACE), a byte-order mark, is allowed only "
        "at the start of the file (two files pasted together?): delete it (most editors do not "
        "show it)",
        id="a BOM in the middle",
    ),
]


@pytest.mark.parametrize(("data", "problem"), WORD_PROCESSORS)
def test_a_word_processors_file_or_an_old_encoding_is_named(
    data: bytes, problem: str, tmp_path: Path
) -> None:
    """UTF-16 was named ("save it as UTF-8"); RTF was a YAML syntax error on line 2, a .docx
    "byte 0x8e", a Windows-1252 quote "byte 0x93", a BOM mid-file "did not find expected key"."""
    assert _problems(tmp_path, data) == [problem]


def test_a_bom_at_the_start_is_still_fine(tmp_path: Path) -> None:
    assert _problems(tmp_path, b"\xef\xbb\xbfmission: m\ntree: {log: x}\n") == []


def test_a_folder_is_every_yaml_file_under_it_in_path_order(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: Capsys
) -> None:
    """``validate submissions/`` was "a directory, not a mission file": a class's folder is
    every .yaml and .yml file under it, at any depth, hidden ones left out; a folder with none
    is an error that names it."""
    monkeypatch.chdir(tmp_path)
    for name, text in {
        "class/b/zoë müller.yml": "tree: wall\n",
        "class/a.yaml": "tree: {mde: safe}\n",
        "class/notes.txt": "not a mission",
        "class/.git/x.yaml": "not: [checked",
        "class/.hidden.yaml": "not: [checked",
        "empty/readme.md": "",
    }.items():
        (tmp_path / name).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / name).write_text(text, encoding="utf-8")
    assert main(["validate", "class", "empty"]) == 2
    out, err = capsys.readouterr()
    assert out.splitlines()[1:] == [
        "class/a.yaml: failed (1 error)",
        "class/b/zoë müller.yml: ok",
        "empty: failed (cannot read: a folder with no .yaml or .yml file in it (folders are "
        "read recursively))",
        "3 files: 1 ok, 0 with warnings only, 2 with errors",
    ]
    assert err == (
        "roomba-bt validate: empty: a folder with no .yaml or .yml file in it (folders are read "
        "recursively)\n"
    )


def test_p_in_a_batch_sets_the_parameter_where_a_file_declares_it(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: Capsys
) -> None:
    """``-p speed=...`` for 30 files failed each file that declares no ``speed``, an annotation
    on its line 1 for a command-line choice. The rule: a file takes the values of the
    parameters it declares; one no file of the batch declares (a typo) is said in each."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "fast.yaml").write_text(
        "parameters: {speed: {type: speed, default: 100 mm/s}}\n"
        "tree: {sequence: [mode: safe, drive: {velocity: '${speed}', distance: 1 m}]}\n"
    )
    (tmp_path / "plain.yaml").write_text("tree: wall\n")
    assert main(["validate", "-p", "speed=300mm/s", "fast.yaml", "plain.yaml"]) == 0
    capsys.readouterr()
    assert main(["validate", "-p", "speed=9000mm/s", "fast.yaml", "plain.yaml"]) == 2
    assert "fast.yaml:2:49: drive: velocity 9000 mm/s is out of range" in capsys.readouterr().out
    assert main(["validate", "-p", "sped=300mm/s", "fast.yaml", "plain.yaml"]) == 2
    out = capsys.readouterr().out
    assert "fast.yaml:1:1: unknown parameter 'sped' set on the command line (did you mean " in out
    assert "plain.yaml:1:1: unknown parameter 'sped' set on the command line;" in out
    assert main(["validate", "-p", "speed=300mm/s", "plain.yaml"]) == 2  # one file: as before


@pytest.fixture
def library(tmp_path: Path) -> Path:
    """A student's folder: ``s55_lib/moves.yaml`` defines ``wiggle``."""
    (tmp_path / "s55_lib").mkdir()
    (tmp_path / "s55_lib" / "moves.yaml").write_text("subtrees: {wiggle: {tree: {turn: 10deg}}}\n")
    return tmp_path


@pytest.mark.parametrize(
    ("written", "said"),
    [
        ("s55_lib\\\\moves.yaml", "'s55_lib\\moves.yaml' not found; did you mean "
         "'s55_lib/moves.yaml'? (paths are written with /, on Windows too)"),
        ("S55_lib/moves.yaml", "'S55_lib/moves.yaml' not found; did you mean "
         "'s55_lib/moves.yaml'? (names are case-sensitive)"),
        ("s55_lib/Moves.yaml", "'s55_lib/Moves.yaml' not found; did you mean "
         "'s55_lib/moves.yaml'? (names are case-sensitive)"),
        ("'s55_lib/moves.yaml '", "'s55_lib/moves.yaml ' not found; did you mean "
         "'s55_lib/moves.yaml'? (a space at an end of a name)"),
        ("s55_lib/moves", "'s55_lib/moves' not found; did you mean 's55_lib/moves.yaml'? (the "
         "name ends in .yaml)"),
        ("C:\\\\Users\\\\ana\\\\lib.yaml", "'C:\\Users\\ana\\lib.yaml' not found: an absolute "
         "Windows path names a file on one computer only; write the path relative to the "
         "including file, with /"),
    ],
    ids=["backslash", "folder case", "file case", "trailing space", "no .yaml", "C:"],
)  # fmt: skip
def test_an_include_not_found_names_what_was_likely_meant_as_written(
    written: str, said: str, library: Path
) -> None:
    """The message showed a backslash doubled (a student searched the file for ``\\\\``), and
    gave a "did you mean" for a file name in the wrong case only: not for a folder's, a space
    at the end, a missing .yaml, nor a Windows path from another computer."""
    text = f'mission: m\ninclude: ["{written}"]\ntree: {{subtree: wiggle}}\n'
    if written.startswith("'"):
        text = f"mission: m\ninclude: [{written}]\ntree: {{subtree: wiggle}}\n"
    problems = _problems(library, text.encode())
    assert problems[0] == f"2:11: included file {said}"


def test_a_name_not_in_snake_case_is_said_at_the_name_with_its_spelling(tmp_path: Path) -> None:
    """The parameter's error pointed at its value's ``{`` (8:12), and none said how to write it."""
    text = (
        "mission: x\nsubtrees:\n  MyTurn:\n    tree: {turn: 10deg}\nparameters:\n"
        "  MySpeed: {type: speed, default: 100 mm/s}\ntree: {subtree: MyTurn}\n"
    )
    assert _problems(tmp_path, text.encode()) == [
        "3:3: subtree name 'MyTurn' must be snake_case (write 'my_turn')",
        "6:3: parameter name 'MySpeed' must be snake_case (write 'my_speed')",
    ]


def test_the_schema_refuses_a_subtree_name_not_in_snake_case_as_validate_does() -> None:
    """``MyTurn:`` passed the editor (``subtrees`` had no ``propertyNames``) and failed
    ``validate``."""
    jsonschema = pytest.importorskip("jsonschema")
    from roomba_bt.mission.schema import mission_schema

    validator = jsonschema.Draft202012Validator(mission_schema())
    for name, ok in (("my_turn", True), ("MyTurn", False)):
        for parameters in ({}, {"parameters": {name: {"type": "angle"}}}):
            subtree = {"tree": {"turn": "10deg"}, **parameters}
            mission = {"subtrees": {"my_turn" if parameters else name: subtree}, "tree": "wall"}
            assert validator.is_valid(mission) is ok, mission
