"""The figures report's own arithmetic (the report itself takes minutes: `make routines`)."""

from __future__ import annotations

import pytest

from roomba_bt.evaluate.report import two_worker_makespan


@pytest.mark.parametrize(
    ("durations", "makespan"),
    [
        ([1.0, 1.0], 1.0),
        ([4.0, 1.0, 1.0, 1.0, 1.0], 4.0),  # the long one first: it alone bounds the pair
        ([1.0, 1.0, 1.0, 1.0, 4.0], 6.0),  # the long one last: it starts when one is free
        ([3.0, 1.0, 1.0, 1.0], 3.0),
        ([2.0], 2.0),
    ],
)
def test_two_workers_taking_episodes_in_order(durations: list[float], makespan: float) -> None:
    assert two_worker_makespan(durations) == makespan
