"""What a stranger's mission files and names did that a clear error now meets (session 27,
mission files, findings 2-6)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from roomba_bt.cli import main
from roomba_bt.mission import compile_mission
from roomba_bt.printable import ANY_CONTROL, escaped

#: the bidi and zero-width characters printable.INVISIBLE covers, by themselves: on the old
#: code that name did not exist
INVISIBLE = re.compile("[\u061c\u200b-\u200f\u202a-\u202e\u2060\u2066-\u2069\ufeff]")


def _problems(path: Path, params: dict[str, str] | None = None) -> list[str]:
    _, problems = compile_mission(path, params)
    return [f"{p.line}:{p.column}: {p.message}" for p in problems]


def test_an_include_through_a_symlink_loop_is_refused_at_the_include(tmp_path: Path) -> None:
    """It was "internal error while compiling (RuntimeError: Symlink loop ...)" at 1:1."""
    (tmp_path / "loop_a.yaml").symlink_to("loop_b.yaml")
    (tmp_path / "loop_b.yaml").symlink_to("loop_a.yaml")
    path = tmp_path / "m.yaml"
    path.write_text("mission: m\ninclude: [loop_a.yaml]\ntree: {log: x}\n")
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
        "mission: x\ntree:\n  sequence:\n    - mode: full\n    - drive: {velocity: 500 mm/s}\n"
    )
    assert main(["validate", name]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert len(lines) == 2
    assert lines[0].startswith("evil.yaml: ok\\x0az.yaml:5:7: warning: drive can turn")
    assert lines[1] == "evil.yaml: ok\\x0az.yaml: ok, with warnings"


def test_show_escapes_control_characters_a_command_line_text_brings_into_the_tree(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The tree line printed ``log(hello ESC[2J ESC]0;pwned BEL X)`` raw: it cleared the
    screen and retitled the window (the first line was escaped)."""
    path = tmp_path / "m.yaml"
    path.write_text(
        "mission: m\nparameters: {who: {type: str, default: x}}\ntree: {log: 'hello ${who}'}\n"
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


def test_a_key_yaml_reads_as_a_boolean_says_to_quote_it(tmp_path: Path) -> None:
    """``vacuum: {on: true}``, the long form of ``on: bool, required``, was refused without
    the hint an enum's ``yes`` gets; a text parameter's ``default: no`` likewise."""
    path = tmp_path / "m.yaml"
    path.write_text(
        "mission: m\n"
        "parameters: {label: {type: str, default: no}}\n"
        "tree:\n"
        "  sequence:\n"
        "    - mode: safe\n"
        "    - vacuum: {on: true}\n"
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


def test_a_second_document_is_named_where_it_starts(tmp_path: Path) -> None:
    """It was PyYAML's fragment "but found another document"."""
    path = tmp_path / "m.yaml"
    path.write_text("mission: m\ntree: {log: x}\n---\nmission: n\n")
    assert _problems(path) == [
        "3:1: YAML syntax error: a mission file holds one YAML document; a second one (---) "
        "starts here"
    ]
