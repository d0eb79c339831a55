"""The lines of eval's report docs/evaluation.md shows in its worked examples (an A/B of the
two dock missions, a sweep of ``turn_speed``, a sweep of ``search_speed``), each made by the
page's command (tests/quoted.py's ``assert_quoted``, the page's numbers its example's).

The page's evaluations run 40 to 100 episodes a variant, some in the apartment; here each runs
6 (the fewest whose paired times get a 95 % interval, ``stats.median_interval``) within 1.5 m
of the dock in the empty room, about a second of CPU in all: what is compared is each line's
words, which the number of episodes and the room do not change. Made once for the module."""

from __future__ import annotations

import contextlib
import io
import shlex
from collections.abc import Iterator

import pytest
from quoted import assert_quoted  # tests/quoted.py: the docs' quotes

from roomba_bt.cli import main

#: the page's three commands, each cut to a few episodes near the dock (the module's docstring)
SHORT = "--within 1.5 --runs 6 --seed 1 --no-progress"
COMMANDS = (
    f"eval dock dock-builtin {SHORT}",
    f"eval dock {SHORT} --sweep turn_speed=90mm/s,200mm/s",
    f"eval dock {SHORT} --sweep search_speed=250mm/s,350mm/s",
)


@pytest.fixture(scope="module")
def reports() -> Iterator[str]:
    """What the three evaluations printed on stdout, one after another."""
    printed = []
    for command in COMMANDS:
        out = io.StringIO()
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(io.StringIO()):
            assert main(shlex.split(command)) == 0, out.getvalue()
        printed.append(out.getvalue())
    yield "\n".join(printed)


def test_each_variant_s_lines_are_the_reports(reports: str) -> None:
    assert_quoted("docs/evaluation.md", "variant", reports, numbers=True)
    assert_quoted("docs/evaluation.md", "success", reports, numbers=True)
    assert_quoted("docs/evaluation.md", "time", reports, numbers=True)
    # docs/evaluation.md's pen, where every episode is trapped: the same words
    assert_quoted("docs/evaluation.md", "trapped", reports, numbers=True)


def test_the_a_b_lines_are_the_reports(reports: str) -> None:
    assert_quoted("docs/evaluation.md", "A/B", reports, numbers=True)
    assert_quoted("docs/evaluation.md", "paired", reports, numbers=True)
