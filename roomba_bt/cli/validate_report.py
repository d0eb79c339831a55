"""What ``roomba-bt validate`` says of the files it checked: as text, JSON or GitHub
workflow commands, each with a verdict per file.

A team library included by five missions holds one error; the missions fail through it. The
text and the GitHub annotations say the error once, at its place in the library, with the
include chain that first reached it, and name every file that failed, through which include
(``to-kitchen.yaml: failed (an included file has errors: 1 error in lib/escapes.yaml,
included at line 5)``): before, the library's line came once for each mission that included
it and the missions were named nowhere. JSON keeps every diagnostic of every checked file
(``checked_file``), for a program to group as it likes.

``--strict`` fails a file on its warnings too (the compiler's: a drive in Full mode with no
cliff check, ...), exit 7 when warnings alone failed it, as ``run --strict``'s 7 is a run
that did what only warned. Errors stay exit 2.
"""

from __future__ import annotations

import json
import sys
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from roomba_bt.printable import ANY_CONTROL, UNPRINTABLE, escaped

if TYPE_CHECKING:
    from collections.abc import Sequence

    from roomba_bt.mission.diagnostics import Diagnostic, IncludeSite

#: ``--format``'s choices; text is the default
FORMATS = ("text", "json", "github")

#: the ``title=`` of every GitHub annotation
ANNOTATION_TITLE = "roomba-bt validate"


@dataclass(frozen=True)
class UnloadedPlugin:
    """An installed plugin whose behaviours a mission cannot use (it did not import, or a
    class was refused), as ``validate`` reports it beside the files: a warning, which fails
    no file (a mission that uses one of its behaviours gets its own error). It was said
    only as a plain stderr line, which ``--format json`` and ``--format github`` readers
    (a bot, the Actions page) never saw."""

    #: the plugin as its errors name it: ``'dirt' (roomba_bt_dirt, from roomba-bt-dirt)``
    plugin: str
    #: why it did not load, on one line
    error: str
    #: what no mission has for it: ``the behaviours of plugin 'dirt' (...)``, or the one
    #: refused behaviour of a half-loaded plugin
    lost: str

    @property
    def message(self) -> str:
        """The warning as stderr says it: ``plugin 'dirt' (...): ...; a mission cannot use
        the behaviours of plugin 'dirt' (...)``."""
        return f"plugin {self.plugin}: {self.error}; a mission cannot use {self.lost}"


@dataclass
class Checked:
    """One file argument of ``validate`` and what its check found: its diagnostics (errors
    and warnings, in files it includes too), or ``problem`` when no such file exists; and
    ``includes``, the files it includes (JSON's reverse view: which missions a library
    reaches); ``parameters``, the names it declares (which ``-p`` values it takes in a
    batch)."""

    file: str
    diagnostics: list[Diagnostic] = field(default_factory=list)
    problem: str | None = None
    includes: tuple[str, ...] = ()
    parameters: tuple[str, ...] = ()

    @property
    def problem_said(self) -> str:
        """``problem`` in its own words, without the file's name it starts with."""
        problem = self.problem or ""
        return problem.removeprefix(f"{self.file}: ").removeprefix(f"{self.file!r}: ")

    def count(self, severity: str) -> int:
        return sum(d.severity == severity for d in self.diagnostics) + (
            self.problem is not None and severity == "error"
        )

    def failing(self, strict: bool) -> list[Diagnostic]:
        """What fails the file: its errors, and under ``--strict`` its warnings."""
        return [d for d in self.diagnostics if strict or d.severity == "error"]

    def failed(self, strict: bool) -> bool:
        return self.problem is not None or bool(self.failing(strict))

    def verdict(self, strict: bool) -> str:
        """What follows ``FILE: `` in the text: ``ok``, ``ok, with warnings`` or ``failed``
        with what failed it, its own count and each included file's."""
        if self.problem is not None:  # its own words: a log kept from stdout alone, or JSON,
            # has no "above" to point to (the stderr line says it with the command's name)
            return f"failed (cannot read: {escaped(self.problem_said, ANY_CONTROL)})"
        failing = self.failing(strict)
        if not failing:
            return "ok, with warnings" if self.diagnostics else "ok"
        own = [d for d in failing if not d.included_from]
        included: dict[str, list[Diagnostic]] = {}
        for d in failing:
            if d.included_from:
                included.setdefault(d.file, []).append(d)
        parts = [counted(own)] if own else []
        if included:
            each = ", ".join(
                f"{counted(found)} in {escaped(file, ANY_CONTROL)}, included at line "
                f"{found[0].included_from[-1].line}"
                for file, found in included.items()
            )
            noun = counted([d for found in included.values() for d in found], nouns_only=True)
            parts.append(f"an included file has {noun}: {each}")
        strictly = "" if any(d.severity == "error" for d in failing) else " --strict"
        return f"failed{strictly} ({'; '.join(parts)})"

    def through_includes(self, strict: bool) -> dict[IncludeSite, list[Diagnostic]]:
        """The include entries of this file that brought in a failing diagnostic, with what
        each brought: where a GitHub annotation on the mission itself goes."""
        sites: dict[IncludeSite, list[Diagnostic]] = {}
        for d in self.failing(strict):
            if d.included_from:
                sites.setdefault(d.included_from[-1], []).append(d)
        return sites


def failed_strict(file: str, warnings: Sequence[Diagnostic]) -> str:
    """What ``run --strict`` says of a mission with compile-time warnings (a drive in Full
    mode with no cliff check, ...), in ``validate --strict``'s words: ``w.yaml: failed
    --strict (1 warning)``. A run does not start it, and ``run --strict --watch`` does not
    reload it: the two say it alike, so a reload is refused for what a start is."""
    return f"{escaped(file, ANY_CONTROL)}: {Checked(file, list(warnings)).verdict(strict=True)}"


def counted(diagnostics: list[Diagnostic], *, nouns_only: bool = False) -> str:
    """``1 error``, ``2 warnings``, ``1 error and 2 warnings``; ``nouns_only``: ``errors``,
    ``warnings`` or ``errors and warnings``."""
    errors = sum(d.severity == "error" for d in diagnostics)
    warnings = len(diagnostics) - errors
    said = []
    for count, noun in ((errors, "error"), (warnings, "warning")):
        if count:
            plural = f"{noun}s" if count != 1 or nouns_only else noun
            said.append(plural if nouns_only else f"{count:,} {plural}")
    return " and ".join(said)


def exit_code(checked: list[Checked], strict: bool) -> int:
    """2 when a file has an error (or is missing); 7 when ``--strict`` and warnings alone
    fail a file; 0 otherwise."""
    from roomba_bt.runtime.summary import ExitCode

    if any(c.problem is not None or c.count("error") for c in checked):
        return ExitCode.INVALID
    if strict and any(c.count("warning") for c in checked):
        return ExitCode.STRICT
    return ExitCode.OK


def print_text(checked: list[Checked], *, strict: bool, quiet: bool) -> None:
    """Each diagnostic once per place (the first include chain that reached it), then each
    file's verdict; ``quiet``: the verdicts of files that passed are left out."""
    from roomba_bt.mission import reported

    seen: set[Diagnostic] = set()
    for one in checked:
        if one.problem is not None:  # as show and run say it: stderr, the command named;
            # and its verdict on stdout, as every file's (a CI log may keep stdout alone)
            print(f"roomba-bt validate: {escaped(one.problem, ANY_CONTROL)}", file=sys.stderr)
            print(f"{escaped(one.file, ANY_CONTROL) or repr('')}: {one.verdict(strict)}")
            continue
        fresh = _unseen(one.diagnostics, seen)
        for line in reported(fresh):
            print(line)
        if one.failed(strict) or not quiet:
            # one line: a file's name may hold "\n"
            print(f"{escaped(one.file, ANY_CONTROL)}: {one.verdict(strict)}")
    _print_summary(checked, strict=strict, quiet=quiet)


def _print_summary(checked: list[Checked], *, strict: bool, quiet: bool) -> None:
    said = summary(checked, strict=strict, quiet=quiet)
    if said is not None:
        print(said)


def _unseen(diagnostics: list[Diagnostic], seen: set[Diagnostic]) -> list[Diagnostic]:
    """The diagnostics whose place and message were not said yet (``seen`` updated)."""
    fresh = []
    for d in diagnostics:
        before = len(seen)
        seen.add(d.located())  # one hash a diagnostic (a file may have 68,000)
        if len(seen) != before:
            fresh.append(d)
    return fresh


def print_json(
    checked: list[Checked], *, strict: bool, plugins: Sequence[UnloadedPlugin] = ()
) -> None:
    """One JSON document: ``files`` (each file's verdict, counts and includes) and ``diagnostics``
    (every one of every file, with ``checked_file``, the file argument that found it; the
    first :data:`~roomba_bt.mission.diagnostics.MAX_REPORTED` of a file, the rest counted
    in its ``diagnostics_omitted``), and ``plugins_not_loaded``, each of ``plugins``."""
    from roomba_bt.mission.diagnostics import MAX_REPORTED

    files: list[dict[str, Any]] = []
    diagnostics: list[dict[str, Any]] = []
    for one in checked:
        failed = one.failed(strict)
        verdict = one.verdict(strict)
        entry: dict[str, Any] = {
            "file": one.file,
            "verdict": "failed" if failed else verdict,
            "said": verdict,
            "errors": one.count("error"),
            "warnings": one.count("warning"),
            "diagnostics_omitted": max(0, len(one.diagnostics) - MAX_REPORTED),
            "includes": list(one.includes),
        }
        if one.problem is not None:  # a diagnostic too: a program reads the reason there
            entry["problem"] = one.problem
            diagnostics.append({**problem_as_json(one), "checked_file": one.file})
        files.append(entry)
        diagnostics += [
            {**diagnostic_as_json(d), "checked_file": one.file}
            for d in one.diagnostics[:MAX_REPORTED]
        ]
    document = {
        "strict": strict,
        "exit_code": int(exit_code(checked, strict)),
        "summary": dict(zip(("files", "ok", "warnings_only", "errors"), tally(checked),
                            strict=True)),
        "files": files,
        "diagnostics": diagnostics,
        "plugins_not_loaded": [
            {"plugin": p.plugin, "error": p.error, "lost": p.lost, "message": p.message,
             "severity": "warning"}
            for p in plugins
        ],
    }  # fmt: skip
    print(json.dumps(document, indent=2))


def problem_as_json(one: Checked) -> dict[str, Any]:
    """A file argument that is no file to read (missing, a folder with no mission, a FIFO)
    as a diagnostic: at no line or column (null), the reason its message."""
    return error_as_json(one.file, one.problem_said)


def error_as_json(
    file: str, message: str, line: int | None = None, column: int | None = None
) -> dict[str, Any]:
    """An error the mission compiler did not find (a file not found, a world file's
    problem) with a diagnostic's fields (:func:`diagnostic_as_json`), so that a program
    reads every error of a report alike; no line or column: null."""
    return {
        "file": file,
        "line": line,
        "column": column,
        "severity": "error",
        "message": message,
        "yaml_path": "",
        "included_from": [],
        "began_at": None,
        "used_in": [],
        "in_subtree": [],
    }


def tally(checked: list[Checked]) -> tuple[int, int, int, int]:
    """How many files were checked, and how many of them are ok, have warnings only, have
    errors (or could not be read)."""
    errors = sum(bool(c.problem is not None or c.count("error")) for c in checked)
    warned = sum(c.problem is None and not c.count("error") and bool(c.count("warning"))
                 for c in checked)  # fmt: skip
    return len(checked), len(checked) - errors - warned, warned, errors


def summary(checked: list[Checked], *, strict: bool, quiet: bool) -> str | None:
    """The closing line of a batch (more than one file): ``31 files: 28 ok, 1 with warnings
    only, 2 with errors``; None for one file, and under ``quiet`` when every file passed
    (nothing else is printed then either)."""
    files, ok, warned, errors = tally(checked)
    if files < 2 or (quiet and not errors and not (strict and warned)):
        return None
    failing = " (failed: --strict)" if strict and warned else ""
    said = f"{warned:,} with warnings only{failing}, {errors:,} with errors"
    return f"{files:,} files: {ok:,} ok, {said}"


def diagnostic_as_json(d: Diagnostic) -> dict[str, Any]:
    """A diagnostic's fields by their names, the include chain innermost first; ``began_at``,
    ``{line, column}`` of where a YAML syntax error's structure began, else null;
    ``used_in``, each use of a subtree it was found at, a list of ``{subtree, file, line,
    column}`` innermost first (the use, then the use of the subtree it is in), or of one said
    at a use, each use in the mission that found it, its own line first; ``in_subtree``, of
    one said at the use in a mission that caused it, where in the library's subtree it was
    found: ``{subtree, file, line, column, yaml_path}``, the body's place first, then the
    uses between."""
    return {
        "file": d.file,
        "line": d.line,
        "column": d.column,
        "severity": d.severity,
        "message": d.shown().message,
        "yaml_path": d.yaml_path,
        "included_from": [
            {"file": s.file, "line": s.line, "column": s.column} for s in d.included_from
        ],
        "began_at": {"line": d.began_at[0], "column": d.began_at[1]} if d.began_at else None,
        "used_in": [
            [{"subtree": u.name, "file": u.file, "line": u.line, "column": u.column} for u in chain]
            for chain in d.used_in
        ],
        "in_subtree": [
            {
                "subtree": u.name,
                "file": u.file,
                "line": u.line,
                "column": u.column,
                "yaml_path": u.path,
            }
            for u in d.in_subtree
        ],
    }


def print_github(
    checked: list[Checked], *, strict: bool, quiet: bool, plugins: Sequence[UnloadedPlugin] = ()
) -> None:
    """GitHub Actions workflow commands: ``::error file=F,line=L,col=C,title=...::message``
    (``::warning`` for a warning), each diagnostic once per place; a file that failed
    through an include gets one more at that include, so the mission is marked too; the
    verdicts follow as plain lines of the job's log. Each of ``plugins`` first, a
    ``::warning`` with no file (it is the machine's, no mission's)."""
    from roomba_bt.mission.diagnostics import MAX_REPORTED

    title = command_property(ANNOTATION_TITLE)
    for plugin in plugins:
        print(f"::warning title={title}::{command_data(plugin.message)}")
    seen: set[Diagnostic] = set()
    for one in checked:
        if one.problem is not None:
            print(
                f"::error title={command_property(ANNOTATION_TITLE)}::{command_data(one.problem)}"
            )
            print(f"{escaped(one.file, ANY_CONTROL)}: {one.verdict(strict)}")
            continue
        for d in _unseen(one.diagnostics[:MAX_REPORTED], seen):
            message = d.shown().message + d.uses_said()
            where = f"{message} [{d.yaml_path}]" if d.yaml_path else message
            severity = d.severity
            if strict and severity == "warning":  # it fails the job: marked as what fails it
                severity, where = "error", f"warning (an error under --strict): {where}"
            print(_annotation(severity, d.file, d.line, d.column, where + d.chain_said()))
        for site, brought in one.through_includes(strict).items():
            first = "" if len(brought) == 1 else ", the first"
            said = f"this include brings in {counted(brought)}{first}: {brought[0].located()}"
            print(_annotation("error", site.file, site.line, site.column, said))
        if one.failed(strict) or not quiet:
            print(f"{escaped(one.file, ANY_CONTROL)}: {one.verdict(strict)}")
    _print_summary(checked, strict=strict, quiet=quiet)


def _annotation(severity: str, file: str, line: int, column: int, message: str) -> str:
    kind = "warning" if severity == "warning" else "error"
    where = f"file={command_property(file)},line={line},col={column}"
    return f"::{kind} {where},title={command_property(ANNOTATION_TITLE)}::{command_data(message)}"


def command_data(text: str) -> str:
    """A workflow command's message, escaped as the Actions toolkit escapes it (``%``, CR and
    LF), its other control characters shown as ``\\x1b``."""
    text = text.replace("%", "%25").replace("\r", "%0D").replace("\n", "%0A")
    return escaped(text, UNPRINTABLE)


def command_property(text: str) -> str:
    """A workflow command's property value (a file's name, the title): :func:`command_data`'s
    escapes, and ``:`` and ``,``, which end a property."""
    return command_data(text).replace(":", "%3A").replace(",", "%2C")
