"""One table of exit codes for every command: ``ExitCode`` (``runtime/summary.py``), which
docs/runtime.md's "Exit codes" prints. doctor's 5 and 6 were a table of their own
(``DoctorExit``), where a reader looking for "the CLI's exit codes" did not find them."""

from __future__ import annotations

import ast
import re
from collections.abc import Callable
from pathlib import Path

import pytest

from roomba_bt.runtime.summary import ExitCode

ROOT = Path(__file__).resolve().parents[2]
CLI = ROOT / "roomba_bt" / "cli"

#: every command whose ``--help`` lists its exit codes
LISTING = ("run", "replay", "sensors", "doctor", "eval", "validate", "behaviours")


def _docs_table() -> dict[int, tuple[str, str]]:
    """docs/runtime.md's exit codes: code -> (``ExitCode`` name, the commands cell)."""
    text = (ROOT / "docs" / "runtime.md").read_text()
    section = text.split("\n## Exit codes\n", 1)[1].split("\n## ", 1)[0]
    rows = re.findall(r"^\| (\d+) \| `(\w+)` \| [^\n]*\| ([^|\n]+) \|$", section, re.M)
    return {int(code): (name, commands) for code, name, commands in rows}


def test_the_docs_table_is_exit_code_s() -> None:
    assert _docs_table() == {
        int(code): (code.name, _docs_table()[int(code)][1]) for code in ExitCode
    }
    assert {int(code) for code in ExitCode} >= {0, 1, 2, 3, 4, 5, 6, 7, 8, 70, 130}


def test_doctor_s_codes_are_exit_code_s_and_collide_with_none() -> None:
    """5 and 6 are doctor's alone: no other command's code shares their numbers, and
    doctor's 0, 2, 3 and 130 mean what they mean for every command."""
    assert ExitCode.NO_ANSWER == 5 and ExitCode.UNHEALTHY == 6
    assert len({int(code) for code in ExitCode}) == len(ExitCode)  # no alias: one meaning
    assert _docs_table()[5][1] == _docs_table()[6][1] == "`doctor`"


@pytest.mark.parametrize("command", LISTING)
def test_every_code_a_command_s_help_lists_is_in_the_table_for_it(
    command: str, help_text: Callable[[str], str]
) -> None:
    after = re.split(r"\bExit\b", help_text(command), maxsplit=1)[1]
    said = re.split(r"positional arguments:|options:", after)[0].strip()
    codes = {int(code) for code in re.findall(r"(?:^|, |; )(\d+) ", said)}
    table = _docs_table()
    assert codes and codes <= set(table), said
    for code in codes:
        cell = table[code][1]
        assert f"`{command}`" in cell or cell.startswith("every command"), (code, cell)


def _returned_numbers(tree: ast.AST) -> list[int]:
    """Exit codes written as bare numbers: ``return 3``, ``sys.exit(3)``,
    ``SystemExit(3)``, ``exit_code = 3``."""
    numbers = []
    for node in ast.walk(tree):
        value: ast.expr | None = None
        if isinstance(node, ast.Return):
            value = node.value
        elif isinstance(node, ast.Call) and ast.unparse(node.func) in ("sys.exit", "SystemExit"):
            value = node.args[0] if node.args else None
        if isinstance(value, ast.Constant) and type(value.value) is int:
            numbers.append(value.value)
    return numbers


def test_no_command_exits_with_a_number_of_its_own() -> None:
    """The CLI says each exit code by its ``ExitCode`` name, so the table is every code a
    command returns: a bare ``return 5`` would be a code the table may not hold."""
    found = {
        str(path.relative_to(ROOT)): numbers
        for path in sorted(CLI.rglob("*.py"))
        if (numbers := _returned_numbers(ast.parse(path.read_text())))
    }
    assert found == {}


def test_no_other_enum_of_exit_codes_is_defined() -> None:
    """Only ``ExitCode``, and 0.1.0's ``DoctorExit`` kept for old imports (its numbers
    ``ExitCode``'s): another table would be one a reader does not find."""
    enums = []
    for path in sorted((ROOT / "roomba_bt").rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ClassDef) and "Exit" in node.name:
                enums.append(f"{path.relative_to(ROOT)}:{node.name}")
    assert enums == [
        "roomba_bt/cli/doctor_cmd.py:_DoctorExit",
        "roomba_bt/runtime/summary.py:ExitCode",
    ]
