"""A count of a few runs is said with its 95 % Wilson interval: the coverage report's
low-battery lines, and the lines of them docs/routines.md holds ("3 of 4 runs ended docked"
read as 75 %, where 4 runs allow 30-95 %)."""

from __future__ import annotations

import re
from pathlib import Path
from types import SimpleNamespace
from typing import Any

from roomba_bt.evaluate.coverage_report import _battery_lines

ROUTINES = Path(__file__).resolve().parents[2] / "docs" / "routines.md"


def _run(docked: bool) -> Any:
    return SimpleNamespace(docked=docked, charging=docked, outcome="success", fell=0)


def test_the_low_battery_lines_give_the_interval() -> None:
    [line] = _battery_lines({"clean": [_run(True)] * 3 + [_run(False)]})
    assert line.startswith(
        "* `clean.yaml`: 3 of 4 runs (95 % Wilson interval 30.1..95.4 %) ended docked and charging"
    )


def test_the_docs_low_battery_lines_are_said_as_the_report_says_them() -> None:
    lines = [line for line in ROUTINES.read_text().splitlines() if "runs ended docked" in line
             or "ended docked and charging" in line]  # fmt: skip
    assert lines
    for line in lines:
        assert re.search(r"\d+ of \d+ runs \(95 % Wilson interval [\d.]+\.\.[\d.]+ %\)", line), line
