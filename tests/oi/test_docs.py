"""docs/protocol.md names, for each decision, the test that pins it: those tests must exist."""

from __future__ import annotations

import pathlib
import re

ROOT = pathlib.Path(__file__).parents[2]


def test_every_test_the_protocol_doc_cites_exists() -> None:
    doc = (ROOT / "docs" / "protocol.md").read_text()
    cited = set(re.findall(r"\b(test_[a-z0-9_]+?)(?:\*|\[|`|\b)", doc))
    cited = {c.rstrip("_") for c in cited}
    # tests/oi's, and those of another folder's file the doc names by its path (a decision
    # the simulator or the batcher carries out: `tests/sim/test_protocol.py::...`)
    named = {ROOT / path for path in re.findall(r"\b(tests/[a-z_/]+/test_[a-z0-9_]+\.py)", doc)}
    files = [*(ROOT / "tests" / "oi").glob("test_*.py"), *named]
    sources = "\n".join(p.read_text() for p in files)
    defined = set(re.findall(r"^def (test_[a-z0-9_]+)", sources, re.MULTILINE))
    names = {p.stem for p in files}
    missing = {
        c
        for c in cited
        if c not in defined and c not in names and not any(d.startswith(c) for d in defined)
    }
    assert not missing, f"docs/protocol.md cites tests that do not exist: {sorted(missing)}"
    assert len(cited) > 30
