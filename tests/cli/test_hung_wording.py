"""eval's closing line words a HUNG episode from its own reason: a ``terminate()`` or a
``shutdown()`` that never returned was called "an endless loop?" too
(``cli/eval_report.py``: ``hung_how``)."""

from __future__ import annotations

from roomba_bt.cli.eval_report import (
    HUNG_IN_SHUTDOWN,
    HUNG_IN_TERMINATE,
    HUNG_PAST_LIMIT,
    hung_how,
)


def test_each_hung_reason_is_worded_as_its_cause() -> None:
    stop = "the tree's stop did not end within 5 s: x (X.terminate at x.py:3) had not returned"
    down = "the behaviours' shutdown() did not end within 5 s: x (X.shutdown at x.py:9) had "
    limit = "--wall-limit 1 s of wall-clock time ran out in behaviour sequence / stuck"
    assert hung_how(stop) == HUNG_IN_TERMINATE
    assert hung_how(stop + "; then " + down) == HUNG_IN_TERMINATE
    assert hung_how(down + "not returned") == HUNG_IN_SHUTDOWN
    assert hung_how(limit + "; then " + stop) == HUNG_PAST_LIMIT
    assert "endless loop" not in HUNG_IN_TERMINATE + HUNG_IN_SHUTDOWN
