"""The figures report: its own arithmetic, and where it reads and writes (the report itself
takes minutes: `make routines`)."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest

from roomba_bt.evaluate.report import experiments, main, two_worker_makespan


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


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        ([], "--docs DIR: where to write the figures"),
        (["--docs", "no/such/dir"], "--docs no/such/dir: no such directory"),
        (["--no-write", "--missions", "no/such/dir"], "--missions no/such/dir: no such"),
    ],
)
def test_the_page_and_the_missions_come_from_the_command_line(
    argv: list[str], message: str, usage_error: Callable[..., str]
) -> None:
    assert message in usage_error(main, argv)


def test_experiments_read_the_missions_folder_given() -> None:
    missions = Path("elsewhere/missions")
    paths = {Path(exp.mission).parent for exp in experiments(0.1, missions)}
    assert paths == {missions}
