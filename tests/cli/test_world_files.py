"""World files a command cannot use (``--world FILE`` of ``run``, ``eval`` and ``sim``): each
one clear line naming the file, what it is and what is wanted, exit 2 (INVALID,
docs/runtime.md's table), before anything is sent; never Python's ``[Errno 13] ...``."""

from __future__ import annotations

import os
from pathlib import Path

import pytest
from mission.test_hostile_files import refuse_open  # chmod 000 as root cannot have it
from quoted import assert_quoted  # tests/quoted.py: the docs' quoted lines

from roomba_bt.cli import main

Capsys = pytest.CaptureFixture[str]

#: each command that reads ``--world``, as a test runs it (the world read before any link)
COMMANDS = {
    "run": ["run", "dock"],
    "eval": ["eval", "dock", "--runs", "1", "--no-progress"],
    "sim": ["sim", "--pty"],
}

#: what each says of a world file it cannot read: as a mission file or a plugin file says it
UNREADABLE = (
    "w.yaml: world: cannot be read: Permission denied; wanted: a world file (YAML text) this "
    "user may read"
)


def assert_said(command: str, line: str, capsys: Capsys) -> str:
    """``command`` run on ``--world w.yaml`` in the current folder: exit 2, and ``line`` on
    stderr as the command says a world's problem: ``sim`` after its ``roomba-bt sim:
    invalid world:``, ``run`` a problem at a place as its own ``file:line:col`` line (as
    ``validate`` prints it), otherwise after ``roomba-bt COMMAND:``; no traceback and no
    Python error number."""
    assert main([*COMMANDS[command], "--world", "w.yaml"]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err and "Errno" not in err, err
    lines = err.splitlines()
    if command == "sim":
        assert lines[-2:] == ["roomba-bt sim: invalid world:", line], lines
    else:
        assert line in lines or f"roomba-bt {command}: {line}" in lines, lines
    return err


@pytest.mark.parametrize("command", list(COMMANDS))
def test_a_world_file_that_cannot_be_read_says_what_is_wanted(
    command: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: Capsys
) -> None:
    """``chmod 000 w.yaml``, as its open fails for a user who is not root (the tests run as
    root, which it does not stop). It was ``w.yaml: world: found an unreadable file ([Errno
    13] Permission denied: 'w.yaml'); allowed: a UTF-8 YAML file``."""
    (tmp_path / "w.yaml").write_text("rooms: [[[0, 0], [3, 0], [3, 3], [0, 3]]]\n")
    monkeypatch.chdir(tmp_path)
    refuse_open(monkeypatch, "w.yaml")
    err = assert_said(command, UNREADABLE, capsys)
    if command == "run":
        assert_quoted("docs/simulator.md", "roomba-bt run: w.yaml: world: cannot be read", err)


@pytest.mark.skipif(
    not hasattr(os, "geteuid") or os.geteuid() == 0, reason="root reads a file chmod 000"
)
def test_a_world_file_chmod_000_says_what_is_wanted(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: Capsys
) -> None:
    """The same, with the file system's own refusal (a user who is not root)."""
    (tmp_path / "w.yaml").write_text("rooms: [[[0, 0], [3, 0], [3, 3], [0, 3]]]\n")
    (tmp_path / "w.yaml").chmod(0)
    monkeypatch.chdir(tmp_path)
    assert_said("run", UNREADABLE, capsys)


@pytest.mark.parametrize("command", list(COMMANDS))
@pytest.mark.parametrize(
    ("content", "line"),
    [
        (None, "w.yaml: world: found a directory; allowed: a YAML file or one of apartment, "
               "corridor, empty-room"),
        # the start of a program (ELF): it was "found byte 0xd0, not UTF-8 text"
        (b"\x7fELF\x02\x01\x01\x00" + bytes(range(256)),
         "w.yaml:1:1: world: found a binary file (it holds NUL bytes), not text: YAML is "
         "plain text, UTF-8; allowed: a UTF-8 YAML file"),
        (b"name: caf\xe9\n",
         "w.yaml:1:10: world: found byte 0xe9, not UTF-8 text (invalid continuation byte; it "
         "reads as '\xe9' in Windows-1252 or Latin-1, an older encoding: save the file as "
         "UTF-8); allowed: a UTF-8 YAML file"),
    ],
    ids=["directory", "binary", "latin-1"],
)  # fmt: skip
def test_a_world_that_is_no_text_file_is_one_clear_line(
    command: str,
    content: bytes | None,
    line: str,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: Capsys,
) -> None:
    """A folder, a program and a Latin-1 file given as the world: what each is, exit 2."""
    if content is None:
        (tmp_path / "w.yaml").mkdir()
    else:
        (tmp_path / "w.yaml").write_bytes(content)
    monkeypatch.chdir(tmp_path)
    assert_said(command, line, capsys)
