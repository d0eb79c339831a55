"""Episodes in parallel, results in spec order whatever ran them: local worker processes
(``--jobs``) or a Dask cluster (:mod:`roomba_bt.evaluate.cluster`).

Every episode is decided by its :class:`~roomba_bt.evaluate.episode.EpisodeSpec` alone (the
seed picks the start pose and the simulator's random draws), so ``--jobs 1`` and ``--jobs 2``
give the same results in the same order; only the wall time differs. Workers are forked
(on Linux) so the mission and world modules are imported once, in the parent.
"""

from __future__ import annotations

import multiprocessing
import signal
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TextIO

from roomba_bt.evaluate import episode
from roomba_bt.evaluate.episode import EpisodeResult, EpisodeSpec, run_episode

Progress = Callable[[int, int, EpisodeResult], None]


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
    with context.Pool(processes=min(jobs, total), initializer=_worker_started) as pool:
        for result in pool.imap(run_episode, specs, chunksize=1):
            results.append(result)
            if progress is not None:
                progress(len(results), total, result)
    return results


def _worker_started() -> None:
    """A pool worker leaves Ctrl-C to its parent, which ends the pool (SIGTERM ends a worker
    at once: on the simulator nothing drives): each worker raising KeyboardInterrupt printed
    its traceback under the summary."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    episode.IN_POOL_WORKER = True


@dataclass(frozen=True)
class Evaluation:
    """What a batch of episodes gave: results in spec order (only those that finished when
    ``interrupted``), how many were run again after a worker died, and where they ran."""

    results: list[EpisodeResult]
    retried: int = 0
    interrupted: bool = False
    engine: str = "local"


@dataclass(frozen=True)
class Engine:
    """Where episodes run: ``local`` processes (``jobs``), or ``dask`` (a local cluster of
    ``jobs`` workers, or the cluster at ``scheduler``)."""

    kind: str = "local"
    jobs: int = 1
    scheduler: str | None = None

    def describe(self) -> str:
        if self.kind == "local":
            return f"{self.jobs} local process{'es' if self.jobs > 1 else ''}"
        if self.scheduler is not None:
            return f"Dask cluster at {self.scheduler}"
        return f"local Dask cluster of {self.jobs} workers"


def evaluate(
    batches: Sequence[Sequence[EpisodeSpec]],
    engine: Engine = Engine(),
    progress: Sequence[Progress | None] | None = None,
) -> list[Evaluation]:
    """Run each batch on ``engine`` (one Dask client for all of them); ``progress[i]`` for
    batch ``i``. A Ctrl-C stops the batch running and skips the rest (each ``interrupted``)."""
    bars: Sequence[Progress | None] = progress or [None] * len(batches)
    out: list[Evaluation] = []
    if engine.kind == "local":
        for specs, bar in zip(batches, bars, strict=True):
            if out and out[-1].interrupted:
                out.append(Evaluation([], 0, True, "local"))
                continue
            done: list[EpisodeResult] = []
            try:
                run_episodes(specs, engine.jobs, _collect(done, bar))
            except KeyboardInterrupt:
                out.append(Evaluation(done, 0, True, "local"))
                continue
            out.append(Evaluation(done, 0, False, "local"))
        return out
    from roomba_bt.evaluate.cluster import dask_client, run_on_client

    with dask_client(engine.scheduler, engine.jobs) as client:
        for specs, bar in zip(batches, bars, strict=True):
            if out and out[-1].interrupted:
                out.append(Evaluation([], 0, True, "dask"))
                continue
            results, retried, interrupted = run_on_client(client, specs, bar)
            finished = [r for r in results if r is not None]
            out.append(Evaluation(finished, retried, interrupted, "dask"))
    return out


def _collect(into: list[EpisodeResult], bar: Progress | None) -> Progress:
    def progress(done: int, total: int, result: EpisodeResult) -> None:
        into.append(result)
        if bar is not None:
            bar(done, total, result)

    return progress


class ProgressBar:
    """``[#########.........] 12/50 ok 11 ETA 8s`` on stderr, redrawn in place on a terminal;
    into a file or a pipe (a CI log), a line of its own after the first episode, each tenth
    and the last (a redraw per episode filled logs with carriage returns)."""

    def __init__(self, stream: TextIO | None = None, width: int = 30, label: str = "") -> None:
        self.stream = stream if stream is not None else sys.stderr
        self.width = width
        self.label = label
        self.started = time.perf_counter()
        self.ok = 0
        isatty = getattr(self.stream, "isatty", None)
        self.redraw = bool(isatty()) if isatty is not None else False

    def __call__(self, done: int, total: int, result: EpisodeResult) -> None:
        self.ok += result.succeeded
        if (
            not self.redraw
            and done not in (1, total)
            and done * 10 // total == (done - 1) * 10 // total
        ):
            return
        filled = round(self.width * done / max(total, 1))
        elapsed = time.perf_counter() - self.started
        eta = elapsed / done * (total - done) if done else 0.0
        bar = "#" * filled + "." * (self.width - filled)
        start, end = ("\r", "\n" if done == total else "") if self.redraw else ("", "\n")
        self.stream.write(
            f"{start}{self.label}[{bar}] {done}/{total} ok {self.ok} "
            f"elapsed {elapsed:.0f}s ETA {eta:.0f}s{end}"
        )
        self.stream.flush()
