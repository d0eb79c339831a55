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

import pytest

from roomba_bt.cli import main
from roomba_bt.mission import MissionError, Permissions, compile_mission, load_mission

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
    """``# allow-plugin-files``: the file is compiled as with ``--allow-plugin-files``."""
    text = path.read_text(encoding="utf-8")
    return Permissions(plugin_files=re.search(r"^# allow-plugin-files$", text, re.M) is not None)


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
        "mission file is not UTF-8 text: byte 0xe9 (invalid continuation byte)"
    )
