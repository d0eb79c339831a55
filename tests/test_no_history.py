"""The product's code says why, not when: no comment or docstring of ``roomba_bt/``,
``bench/`` or ``plugins/`` names a development session ("decided, session 36") or a
numbered finding ("maker finding 3"). A wheel's reader has no sessions: the reason is what
stays true, said in the present tense (what the code guards against), and the history is
the changelog's (CHANGELOG.md, docs/performance.md and the architecture page's decisions,
which are not scanned here).
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
#: the product's code, as a wheel and the repository's benchmarks and example plugins ship it
SCANNED = ("roomba_bt", "bench", "plugins")
#: "session 36", "sessions 33 and 34", "Session 37's", "session\n    #: 39" (a line broken
#: inside it), "finding 3": a date of the project's history, not a reason. The robot
#: layer's "the session's writer" (a connection's session) names no number and stays.
HISTORY = re.compile(r"\b(?:sessions?|finding)\b(?:\s|#:?)+\d+", re.IGNORECASE)


def history_in(text: str) -> list[tuple[int, str]]:
    """Each place ``text`` names a session or a finding by number: its line and the words."""
    return [
        (text.count("\n", 0, match.start()) + 1, " ".join(match.group().replace("#:", "").split()))
        for match in HISTORY.finditer(text)
    ]


def _product_files() -> list[Path]:
    return sorted(
        path
        for folder in SCANNED
        for path in (ROOT / folder).rglob("*.py")
        if ".venv" not in path.parts and "build" not in path.parts
    )


def test_the_pattern_finds_history_and_leaves_the_connections_session() -> None:
    text = (
        "#: How long it waits (decided, session 36): a reason\n"
        "    (sessions 33 and 34), Session 37's stranger, maker finding 3, until session\n"
        "    #: 39's fix\n"
        "the session's writer, a session's parts, one per session\n"
    )
    assert [words for _, words in history_in(text)] == [
        "session 36",
        "sessions 33",
        "Session 37",
        "finding 3",
        "session 39",
    ]
    assert history_in("the session's writer, this session 's asks") == []


@pytest.mark.parametrize("path", _product_files(), ids=lambda p: str(p.relative_to(ROOT)))
def test_product_code_names_no_session(path: Path) -> None:
    found = history_in(path.read_text(encoding="utf-8"))
    assert not found, (
        f"{path.relative_to(ROOT)} says when, not why: "
        + "; ".join(f"line {line}: {words!r}" for line, words in found)
        + " (say the reason, in the present tense; the history is the changelog's)"
    )
