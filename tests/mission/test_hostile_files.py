"""Files a stranger throws at ``roomba-bt validate``: folders the user cannot enter, and
other edges of the file system. Each case is rc 2 (or a diagnostic) at the place the user
wrote, never a traceback."""

from __future__ import annotations

import errno
import importlib.machinery
import os
import re
from collections.abc import Callable
from pathlib import Path

import pytest
from quoted import assert_quoted  # tests/quoted.py: the docs' quoted lines

from roomba_bt.cli import main
from roomba_bt.mission import Permissions, compile_mission

Capsys = pytest.CaptureFixture[str]


def lock(monkeypatch: pytest.MonkeyPatch, folder: str) -> None:
    """Make every path inside a folder named ``folder`` unreachable, as ``chmod 000`` on the
    folder does for a user who is not root (the tests run as root, which it does not stop):
    ``stat`` and ``open`` fail with "Permission denied"."""

    def refused(path: object) -> bool:
        return folder in Path(str(path)).parts[:-1]

    def denied(path: object) -> PermissionError:
        return PermissionError(errno.EACCES, "Permission denied", str(path))

    real_stat, real_open = Path.stat, Path.open

    def stat(self: Path, *args: object, **kwargs: object) -> object:
        if refused(self):
            raise denied(self)
        return real_stat(self, *args, **kwargs)  # type: ignore[arg-type]

    def open_(self: Path, *args: object, **kwargs: object) -> object:
        if refused(self):
            raise denied(self)
        return real_open(self, *args, **kwargs)  # type: ignore[arg-type]

    monkeypatch.setattr(Path, "stat", stat)
    monkeypatch.setattr(Path, "open", open_)


def refuse_open(monkeypatch: pytest.MonkeyPatch, name: str) -> None:
    """Make opening a file called ``name`` fail with "Permission denied", as ``chmod 000`` on
    the file does for a user who is not root (its folder still lets one see it)."""
    real_open = Path.open

    def open_(self: Path, *args: object, **kwargs: object) -> object:
        if self.name == name:
            raise PermissionError(errno.EACCES, "Permission denied", str(self))
        return real_open(self, *args, **kwargs)  # type: ignore[arg-type]

    monkeypatch.setattr(Path, "open", open_)


def test_a_mission_in_a_folder_the_user_cannot_enter_is_rc_2(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: Capsys
) -> None:
    """``validate np/a.yaml`` (np chmod 000) was a traceback from ``find_mission``."""
    (tmp_path / "np").mkdir()
    (tmp_path / "np" / "a.yaml").write_text("tree: {wait: 1s}\n")
    monkeypatch.chdir(tmp_path)
    lock(monkeypatch, "np")
    assert main(["validate", "np/a.yaml"]) == 2
    out, err = capsys.readouterr()
    assert err.splitlines() == ["roomba-bt validate: cannot read np/a.yaml: Permission denied"]
    assert "Traceback" not in out + err


def test_an_include_or_plugin_in_a_locked_folder_is_named_where_it_is_written(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """They were "internal error while compiling (PermissionError ...); please report it"
    at 1:1 of the top file."""
    (tmp_path / "locked").mkdir()
    (tmp_path / "locked" / "z.yaml").write_text("subtrees: {z: {tree: {wait: 1s}}}\n")
    (tmp_path / "locked" / "p.py").write_text("")
    mission = tmp_path / "l.yaml"
    mission.write_text(
        "mission: l\ninclude: [locked/z.yaml]\nplugins: [locked/p.py]\ntree: {wait: 1s}\n"
    )
    lock(monkeypatch, "locked")
    _, problems = compile_mission(mission, permissions=Permissions(plugin_files=True))
    assert [(p.line, p.column, p.message) for p in problems] == [
        (2, 11, "cannot read included file 'locked/z.yaml': Permission denied"),
        (3, 11, "cannot read plugin file 'locked/p.py': Permission denied"),
    ]


def test_an_include_that_cannot_be_opened_is_named_at_the_include(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A file the folder lets one see but not read (chmod 000 on the file): at the include's
    line:col, not at 1:1 of a file the user may never have opened."""
    (tmp_path / "z.yaml").write_text("subtrees: {z: {tree: {wait: 1s}}}\n")
    mission = tmp_path / "m.yaml"
    mission.write_text("mission: m\ninclude: [z.yaml]\ntree: {wait: 1s}\n")
    refuse_open(monkeypatch, "z.yaml")
    _, problems = compile_mission(mission)
    (problem,) = problems
    assert (problem.line, problem.column) == (2, 11)
    assert problem.file.endswith("m.yaml")
    assert problem.message == "cannot read included file 'z.yaml': Permission denied"


def test_a_plugin_file_that_cannot_be_read_is_named_with_what_is_wanted(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """``chmod 000 p.py`` (its folder lets one see it): the import's read fails. It was
    ``failed to import: PermissionError: [Errno 13] Permission denied: '/.../p.py'``, Python's
    words for what is no failure of the plugin's code. An ``OSError`` the plugin's own code
    raises (a file it opens) is still its import's failure, with its line."""
    (tmp_path / "p.py").write_text("")
    (tmp_path / "q.py").write_text("\nopen('/nonexistent/calibration.json')\n")
    mission = tmp_path / "m.yaml"
    mission.write_text("mission: m\nplugins: [p.py, q.py]\ntree: {wait: 1s}\n")
    real_get_data = importlib.machinery.SourceFileLoader.get_data

    def get_data(self: importlib.machinery.SourceFileLoader, path: str) -> bytes:
        if Path(path).name == "p.py":
            raise PermissionError(errno.EACCES, "Permission denied", path)
        return real_get_data(self, path)

    monkeypatch.setattr(importlib.machinery.SourceFileLoader, "get_data", get_data)
    _, problems = compile_mission(mission, permissions=Permissions(plugin_files=True))
    assert [(p.line, p.column, p.message) for p in problems] == [
        (
            2,
            11,
            f"plugin {tmp_path / 'p.py'}: cannot be read: Permission denied; wanted: a Python "
            "file this user may read",
        ),
        (
            2,
            17,
            f"plugin {tmp_path / 'q.py'}: failed to import: FileNotFoundError: [Errno 2] No such "
            f"file or directory: '/nonexistent/calibration.json' (at {tmp_path / 'q.py'}:2)",
        ),
    ]


#: what every command says of a mission file that is there and cannot be read: named, with
#: what is wanted, as an include or a plugin file is (it was "cannot read mission file:
#: Permission denied")
UNREADABLE = (
    "m.yaml:1:1: cannot read mission file 'm.yaml': {why}; wanted: a mission file (YAML text) "
    "this user may read"
)
#: what ``validate`` says, which takes a mission or a world and cannot tell which a file it
#: cannot read is (it said "cannot read mission file 'w.yaml' ...; wanted: a mission file" of
#: a world)
UNREADABLE_EITHER = (
    "{name}:1:1: cannot read file '{name}': {why}; wanted: a mission or a world file (YAML "
    "text) this user may read"
)


@pytest.mark.parametrize(
    ("name", "text"),
    [("m.yaml", "tree: {wait: 1s}\n"), ("w.yaml", "rooms:\n  - [[0, 0], [2, 0], [2, 2]]\n")],
    ids=["mission", "world"],
)
def test_validate_names_a_file_it_cannot_read_as_either(
    name: str, text: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: Capsys
) -> None:
    """``validate w.yaml``, a world it cannot read: "cannot read mission file 'w.yaml' ...;
    wanted: a mission file". It cannot tell a mission from a world unread: the file, and
    either."""
    (tmp_path / name).write_text(text)
    monkeypatch.chdir(tmp_path)
    refuse_open(monkeypatch, name)
    assert main(["validate", name]) == 2
    out = capsys.readouterr().out
    assert UNREADABLE_EITHER.format(name=name, why="Permission denied") in out.splitlines(), out
    assert_quoted("docs/ci.md", "w.yaml:1:1: cannot read file", out.replace("m.yaml", "w.yaml"))


@pytest.mark.parametrize("command", [["show"], ["run", "--fast"], ["eval", "--runs", "1"]])
def test_a_mission_file_that_cannot_be_read_is_named_with_what_is_wanted(
    command: list[str], tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: Capsys
) -> None:
    """``chmod 000 m.yaml``, as the file's open fails for a user who is not root (the tests
    run as root, which it does not stop): exit 2 (INVALID, docs/runtime.md), nothing sent."""
    (tmp_path / "m.yaml").write_text("tree: {wait: 1s}\n")
    monkeypatch.chdir(tmp_path)
    refuse_open(monkeypatch, "m.yaml")
    assert main([command[0], "m.yaml", *command[1:]]) == 2
    out, err = capsys.readouterr()
    assert UNREADABLE.format(why="Permission denied") in (out + err).splitlines(), out + err
    assert "Traceback" not in out + err
    assert_quoted("docs/runtime.md", "m.yaml:1:1: cannot read mission file", out + err)


@pytest.mark.skipif(
    not hasattr(os, "geteuid") or os.geteuid() == 0, reason="root reads a file chmod 000"
)
def test_a_mission_file_chmod_000_is_named_with_what_is_wanted(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: Capsys
) -> None:
    """The same, with the file system's own refusal (a user who is not root)."""
    (tmp_path / "m.yaml").write_text("tree: {wait: 1s}\n")
    (tmp_path / "m.yaml").chmod(0)
    monkeypatch.chdir(tmp_path)
    assert main(["validate", "m.yaml"]) == 2
    said = UNREADABLE_EITHER.format(name="m.yaml", why="Permission denied")
    assert said in capsys.readouterr().out.splitlines()


@pytest.mark.skipif(not Path("/proc/self/mem").is_file(), reason="Linux's /proc/self/mem")
def test_a_mission_file_the_system_fails_to_read_is_named_with_what_is_wanted(
    capsys: Capsys,
) -> None:
    """A regular file whose read fails for root too (``/proc/self/mem`` at offset 0: an
    input/output error): the system's words, the file, and what is wanted."""
    assert main(["validate", "/proc/self/mem"]) == 2
    said = UNREADABLE_EITHER.format(name="/proc/self/mem", why="Input/output error")
    assert said in capsys.readouterr().out.splitlines()


def test_a_library_reached_through_two_files_is_read_once(tmp_path: Path) -> None:
    """The mission and a library of its both include the docking library: read once (its
    subtrees were "defined twice" at a line of the installed package)."""
    (tmp_path / "mine.yaml").write_text(
        "include: [roomba-bt:lib/docking.yaml]\nsubtrees: {home: {tree: {subtree: {id: dock}}}}\n"
    )
    mission = tmp_path / "m.yaml"
    mission.write_text(
        "include: [roomba-bt:lib/docking.yaml, mine.yaml]\n"
        "tree: {sequence: [{mode: safe}, {subtree: home}]}\n"
    )
    assert compile_mission(mission)[1] == []


def test_command_line_paths_that_are_no_file_say_what_they_are(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: Capsys
) -> None:
    """An empty path was ": a directory"; a broken link or a link loop "no such mission
    file, and no shipped mission of that name"; ``ok`` beside ok.yaml suggested "dock".
    Said as ``show`` and ``run`` say them: on stderr, the command named (``validate -`` was
    on stdout, unprefixed, among the diagnostics); stdout has each file's verdict line."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "ok.yaml").write_text("tree: {wait: 1s}\n")
    (tmp_path / "broken.yaml").symlink_to("nothere.yaml")
    (tmp_path / "loop1.yaml").symlink_to("loop2.yaml")
    (tmp_path / "loop2.yaml").symlink_to("loop1.yaml")
    assert main(["validate", "", "-", "broken.yaml", "loop1.yaml", "ok"]) == 2
    out, err = capsys.readouterr()
    *verdicts, counts = [line.partition(": failed (cannot read: ")[0] for line in out.splitlines()]
    assert verdicts == ["''", "-", "broken.yaml", "loop1.yaml", "ok"]
    assert counts == "5 files: 0 ok, 0 with warnings only, 5 with errors"
    assert out.splitlines()[0] == (
        "'': failed (cannot read: an empty path; give a mission file or a shipped mission's "
        "name (`roomba-bt missions` lists them))"
    )
    lines = [line.removeprefix("roomba-bt validate: ") for line in err.splitlines()]
    assert len(lines) == len(err.split("roomba-bt validate: ")) - 1 == 5
    assert lines[:4] == [
        "'': an empty path; give a mission file or a shipped mission's name "
        "(`roomba-bt missions` lists them)",
        "reading a mission from standard input is not supported: give a file",
        "broken.yaml: a broken symbolic link (to 'nothere.yaml', which does not exist)",
        "loop1.yaml: a symbolic link loop (it leads back to itself), not a mission file",
    ]
    assert lines[4].startswith("ok: no such mission file")
    assert lines[4].endswith("; did you mean ./ok.yaml?")
    assert "Traceback" not in out + err


def test_each_error_is_looked_up_once_not_against_every_error_before_it(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Each new error was compared with every one before it: N errors cost N**2/2 comparisons
    (20,000 aliases took 40 s to validate, a 1 MiB file hours). Comparisons counted: a few
    per error, not hundreds."""
    from roomba_bt.behaviours.registry import default_registry
    from roomba_bt.mission.diagnostics import Diagnostic
    from roomba_bt.mission.values import Context

    compared = 0
    real_eq = Diagnostic.__eq__

    def counted(self: Diagnostic, other: object) -> bool:
        nonlocal compared
        compared += 1
        return real_eq(self, other)

    monkeypatch.setattr(Diagnostic, "__eq__", counted)
    ctx = Context(registry=default_registry())
    count = 1_000
    for i in range(count):
        ctx.error(Diagnostic("m.yaml", i + 1, 1, "alias *a is not allowed"))
    ctx.error(Diagnostic("m.yaml", 1, 1, "alias *a is not allowed"))  # the same again: once
    assert len(ctx.diagnostics) == count
    assert compared <= 2 * count


def test_a_file_of_thousands_of_errors_lists_the_first_hundred_and_counts_the_rest(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: Capsys
) -> None:
    """``validate``, ``show`` and ``run`` printed every error: 350,000 lines for a 1 MiB file of
    aliases. The first 100, then how many more; the exit code is still 2."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "al.yaml").write_text("a: &a x\nb: [" + ",".join(["*a"] * 250) + "]\n")
    for command in ("validate", "show", "run"):
        assert main([command, "al.yaml", *(["--fast"] if command == "run" else [])]) == 2
        out, err = capsys.readouterr()
        lines = (out + err).splitlines()
        if command == "validate":  # the file's verdict counts them all
            assert lines.pop() == "al.yaml: failed (250 errors)"
        assert len(lines) == 101, command
        assert all("alias *a is not allowed" in line for line in lines[:100])
        assert lines[100] == "... and 150 more errors (the first 100 are listed)"


def test_a_file_over_the_limit_is_refused_before_it_is_read(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: Capsys
) -> None:
    """``validate`` read the whole file to see whether it was a library (a 4 GB file took
    8 GB of memory) before the compiler refused it by its size; ``show`` and ``run`` did not."""
    monkeypatch.chdir(tmp_path)
    with (tmp_path / "big.yaml").open("wb") as file:
        file.truncate(1 << 30)  # sparse: no disk used
    monkeypatch.setattr(Path, "read_text", None)  # never read whole
    monkeypatch.setattr(Path, "read_bytes", None)
    for command in ("validate", "show", "run"):
        assert main([command, "big.yaml", *(["--fast"] if command == "run" else [])]) == 2
        out, err = capsys.readouterr()
        verdict = ["big.yaml: failed (1 error)"] if command == "validate" else []
        assert (out + err).splitlines() == [
            "big.yaml:1:1: mission file of 1,073,741,824 bytes; at most 1,048,576 are read (a "
            "mission or a world is a few KB: a file generated wrong?)",
            *verdict,
        ], command


def test_an_integer_too_long_to_read_is_placed_in_a_mission_a_world_and_a_parameter(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: Capsys
) -> None:
    """Over 4,300 digits: "internal error while compiling (ValueError ...)" at 1:1 of a
    mission or for ``-p``; a world's was a traceback, exit 1, from ``run`` and ``sim``."""
    monkeypatch.chdir(tmp_path)
    digits = "9" * 5000
    too_long = (
        "an integer of 5,000 digits is too large a number: at most 4,300 digits are read "
        "(a file generated wrong?)"
    )
    (tmp_path / "m.yaml").write_text(
        f"mission: m\ntree:\n  repeat: {{times: {digits}, do: stop}}\n"
    )
    (tmp_path / "p.yaml").write_text(
        "parameters: {n: {type: int, default: 1}}\n"
        "tree: {sequence: [{mode: safe}, {repeat: {times: '${n}', do: stop}}]}\n"
    )
    (tmp_path / "w.yaml").write_text(f"name: w\nrooms: [[[0, 0], [{digits}, 0], [1, 1]]]\n")
    assert main(["validate", "m.yaml"]) == 2
    assert main(["validate", "p.yaml", "-p", f"n={digits}"]) == 2
    assert capsys.readouterr().out.splitlines() == [
        f"m.yaml:3:19: {too_long} [tree.repeat.times]",
        "m.yaml: failed (1 error)",
        f"p.yaml:1:14: parameter n={digits} (from the command line): {too_long} [parameters.n]",
        "p.yaml: failed (1 error)",
    ]
    assert main(["run", "dock", "--fast", "--world", "w.yaml"]) == 2
    assert main(["sim", "--pty", "--world", "w.yaml"]) == 2
    out, err = capsys.readouterr()
    assert err.count(f"w.yaml:2:19: {too_long}") == 2
    assert "Traceback" not in out + err


def test_a_bare_integer_no_float_holds_in_a_quantity_is_placed(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: Capsys
) -> None:
    """10**1000 (under 4,300 digits, so read) where a quantity needs its unit was "internal
    error while compiling (OverflowError)" at 1:1: the "write the unit" hint computed a
    float of it. It is said at its place, as ``repeat.times: 10**1000`` is."""
    monkeypatch.chdir(tmp_path)
    big = str(10**1000)
    (tmp_path / "big.yaml").write_text(
        "mission: num\ntree:\n  sequence:\n    - mode: safe\n"
        f"    - drive: {{velocity: {big}, distance: 0.2 m}}\n    - wait: {{duration: {big}}}\n"
    )
    assert main(["validate", "big.yaml"]) == 2
    too_large = "an integer of 1,001 digits is too large a number: at most about 1.8e+308"
    assert capsys.readouterr().out.splitlines() == [
        f"big.yaml:5:25: drive.velocity: {too_large} [tree.sequence[1].drive.velocity]",
        f"big.yaml:6:24: wait.duration: {too_large} [tree.sequence[2].wait.duration]",
        "big.yaml: failed (2 errors)",
    ]


def test_includes_that_are_no_library_say_what_they_are_at_the_include(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: Capsys
) -> None:
    """A pipe was "not found"; ``""`` "a directory" (the including file's folder); the shipped
    mission ``dock`` (it has a description:) three errors at lines of the installed file and
    none at the include; ``schema --plugin-file`` of a folder "no such file"."""
    import os

    monkeypatch.chdir(tmp_path)
    os.mkfifo(tmp_path / "pipe.yaml")
    (tmp_path / "m.yaml").write_text(
        'include: ["roomba-bt:dock.yaml", "", pipe.yaml]\nplugins: [" "]\ntree: {wait: 1s}\n'
    )
    assert main(["validate", "m.yaml", "--allow-plugin-files"]) == 2
    assert capsys.readouterr().out.splitlines() == [
        "m.yaml:1:11: included file 'roomba-bt:dock.yaml' is a mission (it has mission: or "
        "tree:), not a library: an included file may hold only description, plugins, include, "
        "blackboard, subtrees, literal [include[0]]",
        "m.yaml:1:34: an include is an empty path: name a file [include[1]]",
        "m.yaml:1:38: included file 'pipe.yaml' is not a regular file; an include is a .yaml "
        "file [include[2]]",
        "m.yaml:2:11: a plugin is an empty path: name a file [plugins[0]]",
        "m.yaml: failed (4 errors)",
    ]
    assert main(["schema", "--plugin-file", str(tmp_path)]) == 2
    assert main(["schema", "--plugin-file", "pipe.yaml"]) == 2
    assert capsys.readouterr().err.splitlines() == [
        f"roomba-bt schema: --plugin-file {tmp_path}: a directory, not a file",
        "roomba-bt schema: --plugin-file pipe.yaml: not a regular file",
    ]


def test_a_pipe_beside_the_mission_is_not_opened_for_an_unknown_subtrees_hint(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, pipe_read: Callable[..., tuple[object, bool]]
) -> None:
    """The hint of ``unknown subtree 'x'`` reads the mission folder's YAML files for one that
    defines it; a pipe named ``fifo.yaml`` there hung ``validate`` in ``open()`` for ever."""
    monkeypatch.chdir(tmp_path)
    fifo = tmp_path / "fifo.yaml"
    os.mkfifo(fifo)
    (tmp_path / "lib.yaml").write_text("subtrees:\n  x: {tree: {wait: 1s}}\n")
    mission = tmp_path / "m.yaml"
    mission.write_text("mission: m\ntree: {subtree: {id: x}}\n")
    compiled, opened = pipe_read(fifo, lambda: compile_mission(mission))
    assert not opened
    (problem,) = compiled[1]  # type: ignore[index]
    assert problem.message == "unknown subtree 'x' (lib.yaml defines it: include it)"


def test_a_file_of_thousands_of_unknown_names_reads_the_library_and_the_folder_a_few_times(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Each unknown node's error parsed the shipped library's YAML to see whether it names a
    subtree there, and each unknown subtree walked and read the mission's folder: a file of
    100,000 unknown nodes took hours to validate. The library is read once a process, and
    the folder for the first :data:`HINTS_LOOKED_UP` names of a compile."""
    from roomba_bt.mission import nodes, shipped

    monkeypatch.chdir(tmp_path)
    shipped._library_subtrees.cache_clear()
    parsed: list[object] = []
    real_load = shipped.yaml.safe_load
    monkeypatch.setattr(shipped.yaml, "safe_load", lambda t: parsed.append(t) or real_load(t))
    walked: list[object] = []
    real_granted = nodes.granted_files
    monkeypatch.setattr(nodes, "granted_files", lambda r: walked.append(r) or real_granted(r))
    (tmp_path / "lib.yaml").write_text("subtrees:\n  x0: {tree: {wait: 1s}}\n")
    mission = tmp_path / "m.yaml"
    uses = [f"{{subtree: {{id: x{i}}}}}" for i in range(60)] + [f"bogus{i}" for i in range(60)]
    mission.write_text(f"mission: m\ntree: {{sequence: [{', '.join(uses)}]}}\n")
    _, problems = compile_mission(mission)
    assert len(problems) == 120
    assert problems[0].message == "unknown subtree 'x0' (lib.yaml defines it: include it)"
    assert problems[60].message.startswith("unknown node 'bogus0'")
    assert len(parsed) == len(shipped.shipped_library_files())  # once each, not 60 times
    assert len(walked) == nodes.HINTS_LOOKED_UP
    assert compile_mission(mission)[1] == problems  # the same errors the second time
    assert len(parsed) == len(shipped.shipped_library_files())


@pytest.mark.parametrize(
    ("value", "said"),
    [("{" + ",".join(["a: 1"] * 12_001) + "}", "duplicate key 'a'"),
     ("[" + ",".join(["!!str a"] * 12_000) + "]", "explicit tag !!str is not allowed")],
)  # fmt: skip
def test_a_missions_check_stops_at_the_cap_and_says_so_among_the_first_listed(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: Capsys, value: str, said: str
) -> None:
    """A mission of 100,000 duplicate keys (60,000 tags) built and counted as many errors,
    where a world's check stops at ``printable.MAX_FOUND``: it stops there too, the note
    that it stopped at the place of the last found and listed as the hundredth line, where
    it is seen (a note sorted to the file's end would be among those only counted)."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "many.yaml").write_text(f"mission: m\ntree: {{sequence: [stop]}}\nx: {value}\n")
    assert main(["validate", "many.yaml"]) == 2
    lines = capsys.readouterr().out.splitlines()
    assert lines[-1] == "many.yaml: failed (10,000 errors)"
    assert lines[-2] == "... and 9,900 more errors (the first 100 are listed)"
    assert len(lines) == 102
    assert sum(said in line for line in lines[:100]) == 99, lines[:3]
    assert re.fullmatch(
        r"many\.yaml:3:\d+: checking stopped here, at 10,000 errors \(at most 10,000 are said\): "
        r"the rest of the file is not checked \(a file generated wrong\?\)",
        lines[99],
    ), lines[99]
    # the page's column is its example's: a value's length moves it
    assert_quoted(
        "docs/missions.md", "many.yaml:3:50005: checking stopped", lines[99], numbers=True
    )
    mission, diagnostics = compile_mission(tmp_path / "many.yaml")
    assert mission is None and len(diagnostics) == 10_000  # each kept, the note among them


def test_a_tree_cut_short_is_said_among_the_first_listed(tmp_path: Path, capsys: Capsys) -> None:
    """The tree cut at ``MAX_TREE_NODES`` explains every node after it, but its line sorted
    after the hundred errors of the nodes before it, which are all a command lists: a user
    read a hundred bad velocities and ``... and 301 more errors``, never why. It is listed
    as the hundredth now, as the check's stop at 10,000 errors is."""
    from roomba_bt.mission.nodes import MAX_TREE_NODES

    bad = "    - drive: {velocity: 9 parsecs}\n" * 200  # two errors each
    good = "    - stop\n" * (MAX_TREE_NODES + 100)
    (tmp_path / "cut.yaml").write_text(f"mission: m\ntree:\n  sequence:\n{bad}{good}")
    assert main(["validate", str(tmp_path / "cut.yaml")]) == 2
    lines = capsys.readouterr().out.splitlines()
    assert lines[-2] == "... and 301 more errors (the first 100 are listed)"
    assert re.search(r"cut\.yaml:\d+:7: the tree grows past 10,000 nodes here ", lines[99])
    assert sum("grows past" in line for line in lines) == 1
    assert all("parsecs" in line or "Passive" in line for line in lines[:99])


def _twelve_thousand_warnings(path: Path) -> str:
    """A valid mission of 12,000 warnings written to ``path`` (a blackboard key each, its
    ``initial`` the YAML 1.1 number ``1_0``): the blackboard's lines, for a variant."""
    keys = "".join(f"  k{i}: {{type: int, initial: 1_0}}\n" for i in range(12_000))
    path.write_text(f"mission: m\nblackboard:\n{keys}tree: {{sequence: [stop]}}\n")
    return keys


def test_a_missions_warnings_stop_at_the_cap_and_say_so_among_the_first_listed(
    tmp_path: Path, capsys: Capsys
) -> None:
    """Warnings had no cap, and each was looked up in the list of those kept: 16,000 YAML
    1.1 numbers (``1_0``, four bytes) took 44 s to validate, a file of 1 MiB holds 170,000.
    They stop at ``printable.MAX_FOUND`` as errors do (the check goes on for errors), the
    note at the place of the last and listed as the hundredth line."""
    keys = _twelve_thousand_warnings(tmp_path / "w.yaml")
    assert main(["validate", str(tmp_path / "w.yaml")]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[-1].endswith("w.yaml: ok, with warnings")
    assert lines[-2] == "... and 9,900 more warnings (the first 100 are listed)"
    assert sum("'1_0' is the number 10" in line for line in lines[:100]) == 99
    assert re.fullmatch(
        r".*w\.yaml:10002:31: warning: warnings stopped here, at 10,000 \(at most 10,000 are "
        r"said\): the rest of the file is checked for errors only \(a file generated wrong\?\)",
        lines[99],
    ), lines[99]
    said = lines[99].replace(f"{tmp_path}/", "")
    assert_quoted("docs/missions.md", "w.yaml:10002:31: warning: warnings stopped", said)
    mission, diagnostics = compile_mission(tmp_path / "w.yaml")
    assert mission is not None and not diagnostics and len(mission.warnings) == 10_000
    (tmp_path / "w.yaml").write_text(f"mission: m\nblackboard:\n{keys}tree: {{sequence: [nope]}}\n")
    assert main(["validate", str(tmp_path / "w.yaml")]) == 2  # the errors after are found
    assert "unknown" in capsys.readouterr().out


def test_validate_json_counts_the_warnings_kept_and_lists_a_hundred(
    tmp_path: Path, capsys: Capsys
) -> None:
    """``--format json``, which CI reads (docs/ci.md), of the file above: the file's
    ``warnings`` are the 10,000 kept (the cap's note among them), 100 diagnostics are listed
    with the note last, and ``diagnostics_omitted`` counts the 9,900 others, so that the
    listed and the omitted add up to the count a program reads."""
    import json

    _twelve_thousand_warnings(tmp_path / "w.yaml")
    assert main(["validate", "--format", "json", str(tmp_path / "w.yaml")]) == 0
    report = json.loads(capsys.readouterr().out)
    [file] = report["files"]
    assert (file["verdict"], file["errors"], file["warnings"]) == ("ok, with warnings", 0, 10_000)
    assert file["diagnostics_omitted"] == 9_900
    listed = report["diagnostics"]
    assert len(listed) == 100 and {d["severity"] for d in listed} == {"warning"}
    assert [d["yaml_path"] for d in listed[:99]] == [f"blackboard.k{i}.initial" for i in range(99)]
    assert (listed[-1]["line"], listed[-1]["column"]) == (10002, 31)
    assert listed[-1]["message"].startswith("warnings stopped here, at 10,000")
    assert len(listed) + file["diagnostics_omitted"] == file["warnings"]
