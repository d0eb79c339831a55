"""tests/waits.py's reading of a child's lines: a line that never comes fails the test within
the bound, saying what never came and what the child wrote meanwhile (a ``readline()`` held
a hung child's test, and CI, for ever); the line read leaves what follows to the pipe."""

from __future__ import annotations

import ast
import subprocess
from collections.abc import Iterator
from pathlib import Path

import pytest
from waits import HANG_S, child, line, lines

#: a child that writes two lines, then waits for nothing, for ever (killed after the test)
SAYS_THEN_HANGS = ["sh", "-c", "echo one; echo two; sleep 600"]


def test_a_line_that_never_comes_fails_within_the_bound_saying_what_came() -> None:
    with child(SAYS_THEN_HANGS, stdout=subprocess.PIPE) as proc:  # killed after the block
        assert proc.stdout is not None
        with pytest.raises(AssertionError) as hung:
            lines(proc.stdout, lambda said: "three" in said, "the third line", within=0.5)
    assert str(hung.value) == "the third line: not within 0.5 s (hung?); it wrote 'one\\ntwo\\n'"


def test_a_line_is_read_whole_and_what_follows_is_left_to_the_pipe() -> None:
    with child(["sh", "-c", "echo one; echo two"], stdout=subprocess.PIPE) as proc:
        assert proc.stdout is not None
        assert line(proc.stdout, "the first line") == "one\n"
        out, _ = proc.communicate(timeout=HANG_S)
    assert out == "two\n"


def test_the_lines_until_one_and_at_the_pipe_s_end() -> None:
    with child(["sh", "-c", "echo a; echo b; echo c"], stdout=subprocess.PIPE) as proc:
        assert proc.stdout is not None
        assert lines(proc.stdout, lambda said: said == "b\n", "b") == ["a\n", "b\n"]
        assert lines(proc.stdout, lambda said: False, "the end") == ["c\n", ""]
        assert line(proc.stdout, "nothing more") == ""
        proc.wait(timeout=HANG_S)


#: the suite's test code: every wait in it is bounded (this module's helpers, or a timeout)
TEST_CODE = [Path(__file__).parent, *Path(__file__).parents[1].glob("plugins/*/tests")]
#: calls that wait for ever without an argument: a thread's or a process's ``join()`` or
#: ``wait()``, a queue's ``get()``, an Event's ``wait()``, a pipe's ``communicate()``
NO_BOUND_WITHOUT_ARGUMENTS = ("join", "wait", "get", "communicate")
SUBPROCESS_RUNS = ("run", "call", "check_call", "check_output")
#: a socket's waits, whose bound (a timeout set on the socket) the call does not show:
#: :func:`waits.accepted` and :func:`waits.received` set it and say what never came
SOCKET_WAITS = ("accept", "recv", "recv_into", "recvfrom", "recvmsg")


def unbounded_waits(tree: ast.AST) -> Iterator[tuple[int, str]]:
    """(line, call) of each call in ``tree`` that may wait for ever: a ``readline()`` (of a
    child's pipe: :func:`waits.line`), one of :data:`NO_BOUND_WITHOUT_ARGUMENTS` with no
    argument and no ``timeout``, a ``subprocess.run`` (and its kin) with no ``timeout``, a
    socket's ``accept()`` or ``recv()`` (:data:`SOCKET_WAITS`), an ``os.waitpid`` without
    ``WNOHANG`` (:func:`waits.reaped`), and a ``with Popen(...)`` block, whose end waits for
    the child with no bound (:func:`waits.child`)."""
    for node in ast.walk(tree):
        if isinstance(node, ast.With | ast.AsyncWith):
            for item in node.items:
                made = item.context_expr
                if isinstance(made, ast.Call) and ast.unparse(made.func).endswith("Popen"):
                    yield node.lineno, f"with {ast.unparse(made)}"
        if not isinstance(node, ast.Call) or not isinstance(node.func, ast.Attribute):
            continue
        name, timed = node.func.attr, any(k.arg == "timeout" for k in node.keywords)
        on = ast.unparse(node.func.value)
        if (
            name in ("readline", "readlines")
            or (name in NO_BOUND_WITHOUT_ARGUMENTS and not node.args and not timed)
            or (name == "communicate" and len(node.args) < 2 and not timed)
            or (on == "subprocess" and name in SUBPROCESS_RUNS and not timed)
            or name in SOCKET_WAITS
            or (name == "waitpid" and "WNOHANG" not in ast.unparse(node.args[1:]))
        ):
            yield node.lineno, ast.unparse(node)


@pytest.mark.parametrize(
    "code",
    [
        "conn, _ = listener.accept()",
        "data = sock.recv(4096)",
        "sock.recv_into(buffer)",
        "_, status = os.waitpid(pid, 0)",
        "with subprocess.Popen(['sh'], stdout=subprocess.PIPE) as proc:\n    pass",
        "with Popen(['sh']) as proc, open('f') as f:\n    pass",
        "proc.stdout.readline()",
        "proc.wait()",
        "proc.communicate(b'in')",
        "subprocess.run(['true'])",
    ],
)
def test_the_guard_finds_each_kind_of_wait_without_a_bound(code: str) -> None:
    """Each kind the guard below looks for, put back as a test would write it, is found (a
    guard that found none of a kind would pass a suite full of them)."""
    assert [line for line, _ in unbounded_waits(ast.parse(code))] == [1]


@pytest.mark.parametrize(
    "code",
    [
        "conn = accepted(listener, 'the client')",
        "data = received(sock, 4096, 'the answer')",
        "os.waitpid(pid, os.WNOHANG)",
        "with child(['sh'], stdout=subprocess.PIPE) as proc:\n    pass",
        "proc.wait(timeout=HANG_S)",
        "proc.communicate(timeout=HANG_S)",
        "subprocess.run(['true'], timeout=HANG_S)",
    ],
)
def test_the_guard_passes_the_bounded_waits(code: str) -> None:
    assert list(unbounded_waits(ast.parse(code))) == []


def test_no_wait_in_the_tests_is_without_a_bound() -> None:
    """Session 42 found a dozen: a child's ``readline()``, a bare ``Popen.wait()``,
    ``waitpid``, ``join()``, each of which held CI for its 90 minutes had what it waited for
    never come; before 0.2.0 two dozen socket ``accept()``/``recv()`` without a timeout, the
    ends of four ``with Popen`` blocks and a ``waitpid`` after a SIGKILL were left too.
    This module's helpers (or a ``timeout``) fail within :data:`HANG_S` instead, naming
    what hung."""
    found = [
        f"{path.relative_to(TEST_CODE[0].parent)}:{line}: {call}"
        for folder in TEST_CODE
        for path in sorted(folder.rglob("*.py"))
        if path.name != "waits.py"  # the bounds themselves (each call there is bounded)
        for line, call in unbounded_waits(ast.parse(path.read_text(encoding="utf-8")))
    ]
    assert not found, "waits with no bound (tests/waits.py has one for each):\n" + "\n".join(found)
