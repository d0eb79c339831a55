"""docs/protocol.md names, for each decision, the test that pins it: those tests must exist."""

from __future__ import annotations

import pathlib
import re

ROOT = pathlib.Path(__file__).parents[2]


def test_every_test_the_protocol_doc_cites_exists() -> None:
    doc = (ROOT / "docs" / "protocol.md").read_text()
    cited = set(re.findall(r"\b(test_[a-z0-9_]+?)(?:\*|\[|`|\b)", doc))
    cited = {c.rstrip("_") for c in cited}
    sources = "\n".join(p.read_text() for p in (ROOT / "tests" / "oi").glob("test_*.py"))
    defined = set(re.findall(r"^def (test_[a-z0-9_]+)", sources, re.MULTILINE))
    names = {p.stem for p in (ROOT / "tests" / "oi").glob("test_*.py")}
    missing = {
        c
        for c in cited
        if c not in defined and c not in names and not any(d.startswith(c) for d in defined)
    }
    assert not missing, f"docs/protocol.md cites tests that do not exist: {sorted(missing)}"
    assert len(cited) > 30
