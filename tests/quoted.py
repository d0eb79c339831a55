"""The lines a page of the docs quotes as a command prints them: ``roomba-bt CMD: ...`` in
backquotes. :func:`quotes` finds them, :func:`assert_quoted` holds one to what the command
printed (tests/test_docs_run.py runs the cheap ones' commands; a test that already makes a
harder one, a hung episode or a lost Dask worker, holds the page to its own output).

Besides those, the other lines a page quotes as printed (:data:`MESSAGE_KINDS`): a
diagnostic ``m.yaml:9:25: ...``, ``roomba-bt: ...``, ``replay: ...``, ``monitor: ...``, a
record's ``r.jsonl: ...`` and a line of the run summary, in backquotes or in an output block.

A quote may leave a part out as ``...``: it stands for any text there (``no such folder;
...``); the rest is compared to the character, the Markdown's line breaks aside. A quote of a
message the page says is logged leaves out the log line's time, level and logger
(``t=0.015 INFO roomba_bt.monitor: ``), and one of a diagnostic its ``[yaml.path]``.

A test names the quotes it holds by how they begin (:func:`begins`); a start that ends ``$``
is a whole quote, so that ``final mode Passive$`` is not also ``final mode Passive (not in
the stream: ...)``, a line of another run."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DOCS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
#: a quoted line of a command's: ``roomba-bt run: ...``, ``roomba-bt eval: warning: ...``
QUOTE = re.compile(r"`(roomba-bt [\w-]+: [^`]+)`")
#: the run summary's labels (runtime/summary.py), each a line's first word(s)
SUMMARY_LABELS = (
    "outcome", "safe stop", "final mode", "ticks", "tick guard", "unread", "unheard", "strict",
    "stalls", "falls", "paused", "forced", "commands", "battery", "charger",
)  # fmt: skip
#: the other kinds of line a page quotes as printed, by kind: a diagnostic
#: (``m.yaml:9:25: ...``), the program's own line (``roomba-bt: timeout: ...``), replay's and
#: the monitor's (``replay: ...``, ``monitor: ...``), a record's (``r.jsonl: ...``), a line
#: of the run summary (``final mode   Passive``)
MESSAGE_KINDS = {
    "diagnostic": re.compile(r"(?:\.\.\./)?[\w./-]+\.(?:yaml|yml|py|jsonl|toml):\d+:\d+: \S"),
    "program": re.compile(r"roomba-bt: \S"),
    "replay": re.compile(r"replay: \S"),
    "monitor": re.compile(r"monitor: \S"),
    "record": re.compile(r"[\w./-]+\.jsonl: \S"),
    "summary": re.compile(rf"(?:{'|'.join(SUMMARY_LABELS)}) \S"),
}
#: eval's report labels (cli/eval_report.py, evaluate/stats.py) and the run summary's
#: ``profile``, each a line's first word(s)
REPORT_LABELS = (
    "variant", "success", "time", "bumps", "docked", "trapped", "simulated", "A/B", "paired",
    "engine", "coverage", "key", "interrupted", "profile",
)  # fmt: skip
#: the kinds of line found only in an output block, where a page shows what a command
#: printed: a command's own line (``roomba-bt eval: ...``; in backquotes :data:`QUOTE` finds
#: it) and a line of eval's report (inline, a page names its labels: ``time B - A``). A block
#: that starts ``$ `` (a transcript, docs/doctor.md's) is compared whole by its own test.
SHOWN_KINDS = {
    "command": re.compile(r"roomba-bt [\w-]+: \S"),
    "report": re.compile(rf"(?:{'|'.join(map(re.escape, REPORT_LABELS))}) \S"),
}
#: a fenced block: its language, its text
FENCED = re.compile(r"^```(\w*)\n(.*?)^```", re.M | re.S)
#: the fenced blocks whose lines are output a page shows (a shell block's are commands)
OUTPUT_LANGS = ("", "text")


def quotes(doc: str) -> list[str]:
    """Every quote of the page ``doc`` (a path from the repository's root) of a line a
    command prints, in order, its line breaks made spaces: a ``roomba-bt CMD: ...`` in
    backquotes, and a line of :data:`MESSAGE_KINDS` in backquotes or as a line of an output
    block (its runs of spaces made one, as the summary's columns), and one of
    :data:`SHOWN_KINDS` in an output block."""
    raw = (ROOT / doc).read_text(encoding="utf-8")
    shown: list[str] = []
    reports: list[str] = []

    def fenced(block: re.Match[str]) -> str:
        if block[1] in OUTPUT_LANGS:
            lines = [" ".join(line.split()) for line in block[2].splitlines()]
            shown.extend(lines)
            if not block[2].startswith("$ "):
                reports.extend(line for line in lines if _kind(line, MESSAGE_KINDS) is None)
        return "\n"

    prose = " ".join(FENCED.sub(fenced, raw).split())
    found = QUOTE.findall(" ".join(raw.split()))
    inline = re.findall(r"`([^`]*)`", prose)  # an empty `` pairs its own two
    return (
        found
        + [quote for quote in (*inline, *shown) if _kind(quote, MESSAGE_KINDS) is not None]
        + [line for line in reports if _kind(line, SHOWN_KINDS) is not None]
    )


def _kind(line: str, kinds: dict[str, re.Pattern[str]]) -> str | None:
    return next((name for name, kind in kinds.items() if kind.match(line)), None)


def kind_of(quote: str) -> str:
    """The kind of a quote :func:`quotes` found: a name of :data:`MESSAGE_KINDS` or
    :data:`SHOWN_KINDS`, else ``command`` (``roomba-bt CMD: ...``)."""
    return _kind(quote, MESSAGE_KINDS) or _kind(quote, SHOWN_KINDS) or "command"


#: the YAML path that ends a diagnostic's line (``[tree.sequence[2].subtree]``)
YAML_PATH = re.compile(r" \[[\w.\[\]-]+\]$")
#: what begins a log line: its mission time on a run's log, its level and its logger
LOG_PREFIX = re.compile(r"(?:t=\d+\.\d+ )?(?:DEBUG|INFO|WARNING|ERROR|CRITICAL) [\w.]+: ")
#: a number of a quote that gives an example's numbers (``3 episode(s)``, ``seeds 17, 18``),
#: its sign with it (an interval's ``-12.6..+8.5 s``)
NUMBER = re.compile(r"[-+]?\d+(?:\.\d+)?")


def begins(quote: str, start: str) -> bool:
    """``quote`` begins ``start``, or is it when ``start`` ends ``$`` (a whole quote: a short
    line such as ``outcome SUCCESS$`` begins longer ones of other runs)."""
    return quote == start[:-1] if start.endswith("$") else quote.startswith(start)


def pattern(quote: str, numbers: bool = False) -> re.Pattern[str]:
    """The quote as a pattern of the whole line: ``...`` for any text, with ``numbers`` each
    number for any number, the rest as written."""

    def literal(part: str) -> str:
        if not numbers:
            return re.escape(part)
        return NUMBER.pattern.join(re.escape(piece) for piece in NUMBER.split(part))

    return re.compile(".*".join(literal(part) for part in quote.split("...")))


def assert_quoted(
    doc: str, start: str, printed: str, numbers: bool = False, names: dict[str, str] | None = None
) -> None:
    """Each quote of ``doc`` that begins ``start`` (:func:`begins`: one, or the same said
    again) is one of the lines ``printed`` (a command's stderr), whitespace runs made one
    space. With ``numbers``, the quote's numbers are an example's (the test makes 4 episodes
    hang where the page says 3) and stand for any number: its words are compared; ``names``,
    the test's paths (a ``tmp_path``'s) each replaced by the page's name of it."""
    quoted = [q for q in quotes(doc) if begins(q, start)]
    assert quoted, f"{doc} quotes no line that begins {start!r}"
    for name, page_name in (names or {}).items():
        printed = printed.replace(name, page_name)
    lines = [" ".join(line.split()) for line in printed.splitlines()]
    # a diagnostic's ``[yaml.path]`` ends its line (``file:line:col: message [yaml.path]``,
    # docs/missions.md): a quote may leave it out, as it leaves out the file's other lines
    lines += [YAML_PATH.sub("", line) for line in lines if YAML_PATH.search(line)]
    # a log line's time, level and logger begin it (``t=0.015 INFO roomba_bt.monitor: ...``): a
    # quote of the message the page says is logged leaves them out
    lines += [LOG_PREFIX.sub("", line) for line in lines if LOG_PREFIX.match(line)]
    for quote in quoted:
        assert any(pattern(quote, numbers).fullmatch(line) for line in lines), (
            f"{doc} quotes\n{quote}\nwhich the command did not print; it printed:\n{printed}"
        )
