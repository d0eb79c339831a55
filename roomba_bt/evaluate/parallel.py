"""Episodes in parallel worker processes, results in spec order whatever the number of jobs.

Every episode is decided by its :class:`~roomba_bt.evaluate.episode.EpisodeSpec` alone (the
seed picks the start pose and the simulator's random draws), so ``--jobs 1`` and ``--jobs 2``
give the same results in the same order; only the wall time differs. Workers are forked
(on Linux) so the mission and world modules are imported once, in the parent.
"""

from __future__ import annotations

import multiprocessing
import os
import sys
import time
from collections.abc import Callable, Sequence
from typing import TextIO

from roomba_bt.evaluate.episode import EpisodeResult, EpisodeSpec, run_episode

Progress = Callable[[int, int, EpisodeResult], None]


def default_jobs() -> int:
    return max(1, min(len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity")
                      else (os.cpu_count() or 1), 8))  # fmt: skip


def run_episodes(
    specs: Sequence[EpisodeSpec], jobs: int = 1, progress: Progress | None = None
) -> list[EpisodeResult]:
    """Run every spec; ``progress(done, total, result)`` after each one finishes."""
    total = len(specs)
    results: list[EpisodeResult] = []
    if jobs <= 1 or total <= 1:
        for spec in specs:
            results.append(run_episode(spec))
            if progress is not None:
                progress(len(results), total, results[-1])
        return results
    method = "fork" if "fork" in multiprocessing.get_all_start_methods() else "spawn"
    context = multiprocessing.get_context(method)
    with context.Pool(processes=min(jobs, total)) as pool:
        for result in pool.imap(run_episode, specs, chunksize=1):
            results.append(result)
            if progress is not None:
                progress(len(results), total, result)
    return results


class ProgressBar:
    """``[#########.........] 12/50 ok 11 ETA 8s`` on stderr, redrawn in place."""

    def __init__(self, stream: TextIO | None = None, width: int = 30, label: str = "") -> None:
        self.stream = stream if stream is not None else sys.stderr
        self.width = width
        self.label = label
        self.started = time.perf_counter()
        self.ok = 0

    def __call__(self, done: int, total: int, result: EpisodeResult) -> None:
        self.ok += result.succeeded
        filled = round(self.width * done / max(total, 1))
        elapsed = time.perf_counter() - self.started
        eta = elapsed / done * (total - done) if done else 0.0
        bar = "#" * filled + "." * (self.width - filled)
        end = "\n" if done == total else ""
        self.stream.write(
            f"\r{self.label}[{bar}] {done}/{total} ok {self.ok} "
            f"elapsed {elapsed:.0f}s ETA {eta:.0f}s{end}"
        )
        self.stream.flush()
