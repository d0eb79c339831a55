"""What a stranger's mission files and names did that a clear error now meets (session 27,
mission files, findings 2-6)."""

from __future__ import annotations

import logging
import re
from pathlib import Path

import pytest

from roomba_bt.cli import main
from roomba_bt.mission import Permissions, compile_mission
from roomba_bt.printable import ANY_CONTROL, escaped

#: the bidi and zero-width characters printable.INVISIBLE covers, by themselves: on the old
#: code that name did not exist
INVISIBLE = re.compile("[\u061c\u200b-\u200f\u202a-\u202e\u2060\u2066-\u2069\ufeff]")


def _problems(path: Path, params: dict[str, str] | None = None) -> list[str]:
    _, problems = compile_mission(path, params)
    return [f"{p.line}:{p.column}: {p.message}" for p in problems]


def _mission(tmp_path: Path, text: str) -> Path:
    """The mission file ``m.yaml`` holding ``text`` as written: what the stranger's editor
    wrote, quotes and spaces and all (``simrun.write_mission`` dedents)."""
    path = tmp_path / "m.yaml"
    path.write_text(text)
    return path


def test_an_include_through_a_symlink_loop_is_refused_at_the_include(tmp_path: Path) -> None:
    """It was "internal error while compiling (RuntimeError: Symlink loop ...)" at 1:1."""
    (tmp_path / "loop_a.yaml").symlink_to("loop_b.yaml")
    (tmp_path / "loop_b.yaml").symlink_to("loop_a.yaml")
    path = _mission(tmp_path, "mission: m\ninclude: [loop_a.yaml]\ntree: {log: x}\n")
    assert _problems(path) == [
        "2:11: an include 'loop_a.yaml' is a symbolic link loop (it leads back to itself), "
        "not a file: name the file itself"
    ]


def test_a_newline_in_a_file_name_cannot_fake_a_line_of_validate(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """``evil.yaml: ok<newline>z.yaml`` printed "evil.yaml: ok" for a file that does not exist
    and pinned the warning on a name that does not exist."""
    monkeypatch.chdir(tmp_path)
    name = "evil.yaml: ok\nz.yaml"
    Path(name).write_text(
        "mission: x\ntree:\n  sequence:\n    - mode: full\n"
        "    - drive: {velocity: 500 mm/s, duration: 9s}\n"
    )
    assert main(["validate", name]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert len(lines) == 2
    assert lines[0].startswith("evil.yaml: ok\\x0az.yaml:5:7: warning: drive can turn")
    assert lines[1] == "evil.yaml: ok\\x0az.yaml: ok, with warnings"


def test_run_reads_a_file_whose_name_holds_a_newline_as_validate_and_show_do(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """``validate`` and ``show`` read it; ``run`` refused it with load_mission's word for
    YAML text given as a path ("load_mission:1:1: ... compile YAML text with
    load_mission_text"), a message for a program, exit 2."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "new\nline.yaml").write_text("tree: {wait: 1s}\n")
    assert main(["run", "new\nline.yaml", "--fast", "--display", "none"]) == 0
    out, err = capsys.readouterr()
    assert "load_mission" not in out + err
    assert "mission      new\\x0aline\n" in out


def test_show_escapes_control_characters_a_command_line_text_brings_into_the_tree(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The tree line printed ``log(hello ESC[2J ESC]0;pwned BEL X)`` raw: it cleared the
    screen and retitled the window (the first line was escaped)."""
    path = _mission(
        tmp_path,
        "mission: m\nparameters: {who: {type: str, default: x}}\ntree: {log: 'hello ${who}'}\n",
    )
    assert main(["show", str(path), "-p", "who=\x1b[2J\x1b]0;pwned\x07X\nfake"]) == 0
    out = capsys.readouterr().out
    assert "\x1b" not in out and "\x07" not in out
    assert "--> log(hello \\x1b[2J\\x1b]0;pwned\\x07X\\x0afake)" in out.replace("{-}", "-->")


def test_bidi_and_zero_width_characters_are_escaped_wherever_names_are_printed(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``gentle<U+202E> s/mm 005`` rendered as "gentle 500 mm/s" in the live tree, the log,
    the summary and ``show``'s first line (Trojan Source)."""
    path = tmp_path / "bidi.yaml"
    path.write_text(
        'mission: "safe\\u202e mission"\n'
        'description: "slow \\u2066drive\\u2069 ok\\u200b"\n'
        "tree:\n"
        "  sequence:\n"
        "    - mode: safe\n"
        '    - name: "gentle\\u202e s/mm 005"\n'
        "      drive: {velocity: 100 mm/s, duration: 100ms}\n"
    )
    assert main(["show", str(path)]) == 0
    shown = capsys.readouterr().out
    assert shown.splitlines()[0] == "safe\\u202e mission: slow \\u2066drive\\u2069 ok\\u200b"
    assert main(["run", str(path), "--fast", "--display", "log"]) == 0
    ran = capsys.readouterr()
    printed = shown + ran.out + ran.err
    assert not INVISIBLE.search(printed)
    assert "gentle\\u202e s/mm 005" in ran.out + ran.err
    assert escaped("a\u202eb\u200dc\ufeff", ANY_CONTROL) == "a\\u202eb\\u200dc\\ufeff"


def test_a_200_kb_name_is_cut_with_its_length_said_wherever_it_is_printed(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], caplog: pytest.LogCaptureFixture
) -> None:
    """A 200 KB ``mission:`` name was printed whole by ``show`` and the run's summary, a node's
    by the tree and each log line (200 KB on the terminal, each time)."""
    caplog.set_level(logging.INFO)
    long = "N" * 200_000
    path = _mission(
        tmp_path,
        f"mission: {long}\ntree:\n  sequence:\n    - mode: safe\n"
        f"    - name: {long}\n      wait: {{duration: 30ms}}\n",
    )
    assert main(["show", str(path)]) == 0
    shown = capsys.readouterr().out
    assert main(["run", str(path), "--fast", "--display", "log"]) == 0
    ran = capsys.readouterr()
    lines = (shown + ran.out + ran.err).splitlines()
    assert max(len(line) for line in lines) < 200
    cut = "N" * 80 + "... (200,000 characters)"
    assert shown.startswith(cut + "\n")
    assert f"wait(30ms) named '{cut}'" in shown
    assert f"mission      {cut}" in ran.out
    assert f"{cut} -> SUCCESS" in caplog.messages


def test_a_key_yaml_reads_as_a_boolean_says_to_quote_it(tmp_path: Path) -> None:
    """``vacuum: {on: true}``, the long form of ``on: bool, required``, was refused without
    the hint an enum's ``yes`` gets; a text parameter's ``default: no`` likewise."""
    path = _mission(
        tmp_path,
        "mission: m\n"
        "parameters: {label: {type: str, default: no}}\n"
        "tree:\n"
        "  sequence:\n"
        "    - mode: safe\n"
        "    - vacuum: {on: true}\n",
    )
    assert _problems(path) == [
        "2:42: parameter label: expected a text, got a boolean (false): YAML 1.1 reads yes/no, "
        "on/off and true/false as booleans: quote the text",
        "6:16: keys of vacuum must be names, got 'on', read as the boolean true (YAML 1.1): "
        "quote it, 'on'",
    ]
    path.write_text("mission: m\ntree:\n  sequence: [mode: safe, vacuum: {'on': true}]\n")
    assert _problems(path) == []


@pytest.mark.parametrize("encoding", ["utf-16", "utf-16-le", "utf-16-be"])
def test_a_utf16_file_is_named_as_such(tmp_path: Path, encoding: str) -> None:
    """Notepad's "Unicode" gave "byte 0xff (invalid start byte)" with a BOM and "control
    character U+0000" without one."""
    path = tmp_path / "m.yaml"
    path.write_bytes("mission: m\ntree: {log: x}\n".encode(encoding))
    assert _problems(path) == [
        "1:1: mission file is not UTF-8 text: this is UTF-16 text: save it as UTF-8"
    ]


@pytest.mark.parametrize("encoding", ["utf-32", "utf-32-be"])
def test_a_utf32_file_is_named_as_such(tmp_path: Path, encoding: str) -> None:
    """Its byte-order mark (FF FE 00 00 in little-endian) begins as UTF-16's: it was called
    UTF-16 text."""
    path = tmp_path / "m.yaml"
    path.write_bytes(("\ufeff" if encoding.endswith("be") else "") .encode(encoding)
                     + "mission: m\ntree: {log: x}\n".encode(encoding))  # fmt: skip
    assert _problems(path) == [
        "1:1: mission file is not UTF-8 text: this is UTF-32 text: save it as UTF-8"
    ]


def test_a_merge_key_says_to_write_the_keys_out(tmp_path: Path) -> None:
    """A YAML merge key was ``keys of drive must be names, got merge <<``: neither what
    ``<<`` is to the reader nor what to write (session 42, a stranger's finding)."""
    text = "tree: {sequence: [mode: safe, drive: {<<: {velocity: 100 mm/s}, distance: 1m}]}\n"
    path = _mission(tmp_path, text)
    assert _problems(path) == [
        "1:39: keys of drive must be names, got '<<', a YAML merge key: a mission file copies "
        "no mapping into another (aliases, *name, are refused too); write the keys out"
    ]


def test_a_second_document_is_named_where_it_starts(tmp_path: Path) -> None:
    """It was PyYAML's fragment "but found another document"."""
    path = _mission(tmp_path, "mission: m\ntree: {log: x}\n---\nmission: n\n")
    assert _problems(path) == [
        "3:1: YAML syntax error: a mission file holds one YAML document; a second one (---) "
        "starts here"
    ]


# --- what a chat app, a word processor or Windows writes for YAML's own characters -------------


def _one_step(tmp_path: Path, step: str) -> Path:
    """A mission whose second step is ``step``, written as given (a flow or block line)."""
    return _mission(tmp_path, f"mission: m\ntree:\n  sequence:\n    - mode: safe\n    - {step}\n")


@pytest.mark.parametrize(
    ("opening", "named"),
    [("\u201c", "'\u201c' (U+201C LEFT DOUBLE QUOTATION MARK)"),
     ("\u2018", "'\u2018' (U+2018 LEFT SINGLE QUOTATION MARK)")],
)  # fmt: skip
def test_typographic_quotes_used_as_yaml_quotes_are_named_at_their_place(
    tmp_path: Path, opening: str, named: str
) -> None:
    """``{velocity: “${speed}”, ...}`` was "did not find expected ',' or '}'" at the ``{``."""
    closing = chr(ord(opening) + 1)
    path = _one_step(tmp_path, f"drive: {{velocity: {opening}${{speed}}{closing}, duration: 1s}}")
    assert _problems(path, {}) == [
        f'5:25: YAML syntax error: {named} is a typographic quote, not a YAML quote: write " '
        "or ' (did not find expected ',' or '}' at 5:27)"
    ]


def test_a_typographic_quote_inside_a_text_is_not_blamed_for_a_syntax_error(
    tmp_path: Path,
) -> None:
    """Only a quote where YAML's would open a value is named: one inside a quoted text is
    text, and PyYAML's sentence stands."""
    path = _one_step(tmp_path, 'log: "he said \u201chi\u201d" ]')
    (problem,) = _problems(path)
    assert problem.startswith("5:27: YAML syntax error: ") and "typographic" not in problem


def test_a_value_in_typographic_quotes_says_what_to_write(tmp_path: Path) -> None:
    """The typographic quotes were quoted back, never named: ``got '\u2018safe\u2019' (did
    you mean 'safe'?)``."""
    path = _mission(
        tmp_path,
        "mission: m\ntree:\n  sequence:\n    - mode: \u2018safe\u2019\n"
        "    - drive:\n        velocity: \u201c200 mm/s\u201d\n        duration: 1s\n",
    )
    assert _problems(path) == [
        "4:13: mode.to: expected one of passive, safe, full, got '\u2018safe\u2019': '\u2018' "
        '(U+2018 LEFT SINGLE QUOTATION MARK) is a typographic quote, not a YAML quote: write " '
        "or ' ('safe')",
        "6:19: drive.velocity: expected a speed such as 200 mm/s or 0.2 m/s, got "
        "'\u201c200 mm/s\u201d': '\u201c' (U+201C LEFT DOUBLE QUOTATION MARK) is a typographic "
        'quote, not a YAML quote: write " or \' ("200 mm/s")',
    ]


def test_a_no_break_space_indenting_a_key_is_named(tmp_path: Path) -> None:
    """It was "expected a node, got nothing (null) [tree]" and "unknown top-level key
    '\\xa0\\xa0sequence'": the character was shown, never named."""
    path = _mission(tmp_path, "mission: m\ntree:\n\xa0\xa0sequence:\n    - mode: safe\n")
    assert _problems(path) == [
        "3:1: '\\xa0' (U+00A0 NO-BREAK SPACE) indents this line: YAML indents with plain spaces "
        "only (write a space)"
    ]


def test_a_no_break_space_indenting_a_line_yaml_cannot_read_is_named(tmp_path: Path) -> None:
    """PyYAML's "could not find expected ':'" came a line after the pasted one."""
    path = _mission(
        tmp_path, "mission: m\ntree:\n  sequence:\n    - mode: safe\n    - log: x\n\xa0\xa0\n"
    )
    assert _problems(path) == [
        "6:1: YAML syntax error: '\\xa0' (U+00A0 NO-BREAK SPACE) indents this line: YAML indents "
        "with plain spaces only (write a space) (could not find expected ':' at 7:1)"
    ]


@pytest.mark.parametrize(
    ("step", "said"),
    [("drive: {velocity: \u2212200 mm/s, duration: 1s}",
      "5:25: drive.velocity: expected a speed such as 200 mm/s or 0.2 m/s, got '\u2212200 mm/s': "
      "'\u2212' (U+2212 MINUS SIGN) is not the ASCII minus: write -200 mm/s"),
     ("repeat: {times: \u22122, do: {log: x}}",
      "5:23: repeat.times: expected an integer, got '\u22122': '\u2212' (U+2212 MINUS SIGN) is "
      "not the ASCII minus: write -2"),
     ("turn: {angle: 90\u00ba}",
      "5:21: turn.angle: unknown angle unit '\u00ba' in '90\u00ba'; use one of: deg, \u00b0, rad, "
      "turn, turns: '\u00ba' (U+00BA MASCULINE ORDINAL INDICATOR) is not a degree sign: write "
      "90deg or 90\u00b0"),
     ("turn: {angle: 90\u02da}",
      "5:21: turn.angle: unknown angle unit '\u02da' in '90\u02da'; use one of: deg, \u00b0, rad, "
      "turn, turns: '\u02da' (U+02DA RING ABOVE) is not a degree sign: write 90deg or 90\u00b0"),
     ("wait: 100\u00b5s",
      "5:13: wait.duration: unknown duration unit '\u00b5s' in '100\u00b5s'; use one of: ms, s, "
      "sec, min, h, d (100\u00b5s is 0.1ms)"),
     ("wait: 100 us",
      "5:13: wait.duration: unknown duration unit 'us' in '100 us'; use one of: ms, s, sec, min, "
      "h, d (100us is 0.1ms)")],
)  # fmt: skip
def test_a_lookalike_in_a_number_or_a_unit_is_named(tmp_path: Path, step: str, said: str) -> None:
    """The Unicode minus and ``90º`` got the generic "expected a speed", ``100µs`` "expected a
    duration" without the units a duration has."""
    assert _problems(_one_step(tmp_path, step)) == [said]


def test_a_decimal_comma_says_to_write_a_point(tmp_path: Path) -> None:
    """In a flow mapping ``1,5 m`` was a bare 1 ("write the unit: 1mm") and an unknown
    parameter '5 m'; as a text, the generic "expected a distance"."""
    path = _one_step(tmp_path, "drive: {velocity: 100 mm/s, distance: 1,5 m}")
    assert _problems(path) == [
        "5:45: '1,5 m' holds a decimal comma, which ends the value here: write 1.5 m"
    ]
    path = _one_step(tmp_path, "drive:\n        velocity: 100 mm/s\n        distance: 1,5 m")
    assert _problems(path) == [
        "7:19: drive.distance: expected a distance such as 300 mm, 30cm or 1.5 m, got '1,5 m': "
        "a decimal comma: write 1.5 m"
    ]


def test_a_flat_note_says_its_sharp_and_no_python_repr_leaks(tmp_path: Path) -> None:
    """``Db4`` got only "write A4, C#5 or rest"; an empty item, a list and a mapping were
    said as ``None``, ``['C4', 250]`` and ``{'note': 'C4'}``."""
    path = _one_step(tmp_path, 'song: {number: 0, notes: ["Db4 250ms", "Cb4 1s", ~, [C4, 250]]}')
    problems = _problems(path)
    assert problems == [
        "5:33: song.notes: note 1 of 4: unknown note 'Db4': write C#4, the same pitch (the notes "
        "are C, C#, D, D#, E, F, F#, G, G#, A, A#, B: no flats)",
        "5:46: song.notes: note 2 of 4: unknown note 'Cb4': write B3, the same pitch (the notes "
        "are C, C#, D, D#, E, F, F#, G, G#, A, A#, B: no flats)",
        '5:56: song.notes: note 3 of 4: expected a note such as "C4 250ms" or "rest 125ms", got '
        "nothing (null): a note is one text, its name and duration",
        '5:59: song.notes: note 4 of 4: expected a note such as "C4 250ms" or "rest 125ms", got '
        "a list: a note is one text, its name and duration",
    ]
    assert not any("None" in problem or "[" in problem for problem in problems)


def test_a_note_takes_spaces_before_its_duration_as_a_duration_does(tmp_path: Path) -> None:
    """``"C4  250 ms"`` was refused, though ``250 ms`` is a duration everywhere else."""
    path = _one_step(tmp_path, 'song: {number: 0, notes: ["C4  250 ms", "rest 125ms"]}')
    mission, problems = compile_mission(path)
    assert problems == [] and mission is not None


def test_a_plugin_file_that_is_a_device_is_named_as_such(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``plugins: [/dev/zero]`` with ``--include-dir /dev`` said "not found": it exists."""
    path = _mission(tmp_path, "mission: m\nplugins: [/dev/zero]\ntree: {log: x}\n")
    args = ["validate", str(path), "--include-dir", "/dev", "--allow-plugin-files"]
    assert main(args) == 2
    assert capsys.readouterr().out.splitlines() == [
        f"{path}:2:11: plugin file '/dev/zero' is not a regular file (a device or a pipe); name "
        "a .py file [plugins[0]]",
        f"{path}: failed (1 error)",
    ]


def test_a_world_file_names_a_typographic_quote_too(tmp_path: Path) -> None:
    """The world reader words YAML errors as a mission's: the same hint, at the quote."""
    from roomba_bt.sim.world import WorldError, parse_world

    with pytest.raises(WorldError) as caught:
        parse_world("name: x\nrooms: [[[0, 0], [4, 0], [4, 3], \u201c{0, 3}\u201d]]\n", "w.yaml")
    assert str(caught.value) == (
        "w.yaml:2:34: YAML syntax error: '\u201c' (U+201C LEFT DOUBLE QUOTATION MARK) is a "
        "typographic quote, not a YAML quote: write \" or ' (expected ',' or ']', but got '{' at "
        "2:35)"
    )


def test_a_bad_note_is_said_at_its_own_line_in_a_list_written_down_the_page(
    tmp_path: Path,
) -> None:
    """A song's notes written one a line: a bad note on the list's third line was said at
    the list's first (8:11 here), and the reader counted down to it by hand."""
    path = _mission(
        tmp_path,
        "mission: m\n"
        "tree:\n"
        "  sequence:\n"
        "    - mode: safe\n"
        "    - song:\n"
        "        number: 0\n"
        "        notes:\n"
        "          - C4 250ms\n"
        "          - E4 250ms\n"
        "          - H4 250ms\n"
        "          - G4 9s\n",
    )
    assert _problems(path) == [
        "10:13: song.notes: note 3 of 4: unknown note 'H4': H is B in German names: write B4",
        "11:13: song.notes: note 4 of 4: note duration '9s' is out of range: 16ms..3.98s "
        "(1..255 of 1/64 s)",
    ]


@pytest.mark.parametrize(
    ("text", "said"),
    [
        # a subtree's argument that did not resolve
        ("subtrees:\n  go:\n    parameters: {m: {type: str}}\n    tree: {mode: '${m}'}\n"
         "tree:\n  sequence:\n    - subtree: {id: go, m: '${nope}'}\n",
         "8:28: go.m: unknown parameter ${nope}"),
        # a parameter declared wrongly (seeded mutation 259 of clean.yaml)
        ("parameters:\n  m: {type: enum, choices: [safe, full], default: safe, doc2s: x}\n"
         "tree:\n  sequence:\n    - mode: '${m}'\n",
         "3:57: parameter 'm': unknown key 'doc2s'"),
    ],
)  # fmt: skip
def test_a_mode_whose_value_is_not_known_is_its_error_not_an_internal_one(
    tmp_path: Path, text: str, said: str
) -> None:
    """``mode: "${m}"`` with ``m`` not known (its error said where it was given): the mode
    check read the mode it leads to from the unknown value, "internal error while compiling
    (KeyError: '<UNKNOWN>')" at 1:1."""
    path = _mission(tmp_path, "mission: m\n" + text)
    (problem,) = _problems(path)
    assert problem.startswith(said), problem


@pytest.mark.parametrize("spelt", ["paramaters", "paramters", "Parameters"])
def test_a_misspelt_parameters_section_is_one_error_not_one_per_use(
    tmp_path: Path, spelt: str
) -> None:
    """Each ``${speed}`` the tree used was "unknown parameter" besides the typo itself: the
    section is read as the one it was meant to be, and the typo is the only error."""
    path = _mission(
        tmp_path,
        f"mission: m\n{spelt}:\n  speed: {{type: speed, default: 200 mm/s}}\ntree:\n"
        "  sequence:\n    - mode: safe\n    - drive: {velocity: '${speed}', distance: 1 m}\n",
    )
    assert _problems(path) == [
        f"2:1: unknown top-level key {spelt!r} (did you mean 'parameters'?); known: mission, "
        "description, parameters, blackboard, plugins, include, subtrees, tree, literal"
    ]


def test_a_misspelt_section_beside_the_right_one_is_not_read(tmp_path: Path) -> None:
    """Read as the section it was meant to be only where the file lacks that section: beside
    ``parameters:``, ``paramaters:`` is an unknown key and nothing of it is read."""
    path = _mission(
        tmp_path,
        "mission: m\nparameters: {speed: {type: speed, default: 200 mm/s}}\n"
        "paramaters: {side: {type: distance, default: 1 m}}\n"
        "tree: {wait: '${side}'}\n",
    )
    assert [problem.split(";")[0] for problem in _problems(path)] == [
        "3:1: unknown top-level key 'paramaters' (did you mean 'parameters'?)",
        "4:14: wait.duration: unknown parameter ${side}",
    ]


@pytest.mark.parametrize(
    ("allowed", "there", "said"),
    [(False, False, "2:11: plugin file 'lib\\moves.py' not loaded: a mission file cannot run "
                    "code on its own; allow its plugin files with "
                    "permissions=Permissions(plugin_files=True) (or install the plugin as a "
                    "package)"),
     (True, False, "2:11: plugin file 'lib\\moves.py' not found (paths are relative to the file "
                   "naming it)"),
     (True, True, "2:11: plugin file 'lib\\moves.py' not found; did you mean 'lib/moves.py'? "
                  "(paths are written with /, on Windows too)")],
    ids=["refused", "not found", "lib/moves.py there"],
)  # fmt: skip
def test_a_plugin_file_written_the_windows_way_is_quoted_as_written(
    tmp_path: Path, allowed: bool, there: bool, said: str
) -> None:
    """``'lib\\\\moves.py'``: each backslash doubled by ``repr``, as the includes' messages
    no longer were; the node it was to provide names the file as written too. Where
    ``lib/moves.py`` is there, the hint an include gives: it said only "not found"."""
    if there:
        (tmp_path / "lib").mkdir()
        (tmp_path / "lib" / "moves.py").write_text("LURCH = 1\n")
    path = _mission(tmp_path, "mission: m\nplugins: ['lib\\moves.py']\ntree: {lurch: {}}\n")
    _, problems = compile_mission(path, permissions=Permissions(plugin_files=allowed))
    assert [f"{p.line}:{p.column}: {p.message}" for p in problems] == [
        said,
        "3:8: unknown node 'lurch' (the plugin file 'lib\\moves.py' was not loaded)",
    ]


def test_a_windows_path_where_a_value_goes_is_said_as_written(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``wait: 'C:\\missions\\a.yaml'`` (a path pasted in the wrong place) was said
    ``got 'C:\\\\missions\\\\a.yaml'``: each backslash doubled, no text the file holds."""
    path = _mission(tmp_path, "tree:\n  wait: 'C:\\missions\\a.yaml'\n")
    assert main(["validate", str(path)]) == 2
    assert "got 'C:\\missions\\a.yaml' [tree.wait]" in capsys.readouterr().out


DURATION_UNITS = "use one of: ms, s, sec, min, h, d"


@pytest.mark.parametrize(
    ("step", "said"),
    [("wait: 2m",
      f"5:13: wait.duration: unknown duration unit 'm' in '2m'; {DURATION_UNITS} (m is metres: "
      "for minutes write 2 min)"),
     ("wait: 2 mins",
      f"5:13: wait.duration: unknown duration unit 'mins' in '2 mins'; {DURATION_UNITS} (write "
      "2 min)"),
     ("wait: 3 hours",
      f"5:13: wait.duration: unknown duration unit 'hours' in '3 hours'; {DURATION_UNITS} "
      "(write 3 h)"),
     ("wait: 30 S",
      f"5:13: wait.duration: unknown duration unit 'S' in '30 S'; {DURATION_UNITS} (write 30 s)"),
     ("turn: 90 degrees",
      "5:13: turn.angle: unknown angle unit 'degrees' in '90 degrees'; use one of: deg, \u00b0, "
      "rad, turn, turns (write 90 deg)"),
     ("drive: {velocity: 200 mm/sec, distance: 1 m}",
      "5:25: drive.velocity: unknown speed unit 'mm/sec' in '200 mm/sec'; use one of: mm/s, "
      "cm/s, m/s (write 200 mm/s)"),
     ("drive: {velocity: 200 mm/s, distance: 2 meters}",
      "5:45: drive.distance: unknown distance unit 'meters' in '2 meters'; use one of: mm, cm, "
      "m (write 2 m)"),
     ("turn: 90 deg,",
      "5:13: turn.angle: expected an angle such as 90deg or 1.57rad, got '90 deg,': a stray "
      "',' after the value: write 90 deg"),
     ("wait: 2 min.",
      "5:13: wait.duration: expected a duration such as 500ms, 30s or 2min, got '2 min.': a "
      "stray '.' after the value: write 2 min"),
     ("drive: {velocity: 200 mm/s;, distance: 1 m}",
      "5:25: drive.velocity: expected a speed such as 200 mm/s or 0.2 m/s, got '200 mm/s;': a "
      "stray ';' after the value: write 200 mm/s"),
     ("wait: 1h30min,",
      "5:13: wait.duration: expected a duration such as 500ms, 30s or 2min, got '1h30min,': a "
      "stray ',' after the value: write 1h30min"),
     ("turn: 1/4 turn",
      "5:13: turn.angle: expected an angle such as 90deg or 1.57rad, got '1/4 turn': a "
      "fraction does not read as a number: write 0.25 turn or 90 deg"),
     ("turn: 1/2turns",
      "5:13: turn.angle: expected an angle such as 90deg or 1.57rad, got '1/2turns': a "
      "fraction does not read as a number: write 0.5turns or 180deg"),
     ("drive: {velocity: 200 mm/s, distance: 1/2 m}",
      "5:45: drive.distance: expected a distance such as 300 mm, 30cm or 1.5 m, got '1/2 m': "
      "a fraction does not read as a number: write 0.5 m or 500 mm")],
    ids=["2m", "mins", "hours", "capital S", "degrees", "mm/sec", "meters", "comma",
         "full stop", "semicolon", "compound", "quarter turn", "half turns", "metre"],
)  # fmt: skip
def test_a_value_written_otherwise_is_given_the_one_to_write(
    tmp_path: Path, step: str, said: str
) -> None:
    """``2 mins``, ``3 hours``, ``90 degrees`` said only the units there are, and a reader
    had to guess which was meant; ``2m`` for two minutes reads as metres to roomba-bt.
    ``angle: 90 deg,`` (a list's comma) and ``1/4 turn`` got the generic "expected an angle
    such as 90deg": now they get the value to write too (a fraction as its decimal, and in
    the canonical unit)."""
    assert _problems(_one_step(tmp_path, step)) == [said]


@pytest.mark.parametrize(
    ("step", "said"),
    [("drive: {velocity: 1.5 m/s, distance: 1 m}",
      "5:25: drive: velocity 1.5 m/s (1500 mm/s) is out of range: allowed -500..500 mm/s"),
     ("drive: {velocity: 600 mm/s, distance: 1 m}",
      "5:25: drive: velocity 600 mm/s is out of range: allowed -500..500 mm/s"),
     ("wait: {duration: -2 min}",
      "5:24: wait: duration -2 min (-120 s) is out of range: allowed 0 s or more")],
    ids=["m/s", "canonical already", "min"],
)  # fmt: skip
def test_a_value_out_of_range_is_said_as_written_with_the_unit_of_its_range(
    tmp_path: Path, step: str, said: str
) -> None:
    """``velocity: 1.5 m/s`` was refused as ``velocity 1500 mm/s``: a value the file does not
    hold. Said as written now, with the range's unit beside it to compare."""
    assert _problems(_one_step(tmp_path, step)) == [said]
