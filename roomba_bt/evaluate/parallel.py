"""Episodes in parallel, results in spec order whatever ran them: local worker processes
(``--jobs``) or a Dask cluster (:mod:`roomba_bt.evaluate.cluster`).

Every episode is decided by its :class:`~roomba_bt.evaluate.episode.EpisodeSpec` alone (the
seed picks the start pose and the simulator's random draws), so ``--jobs 1`` and ``--jobs 2``
give the same results in the same order; only the wall time differs. Workers are forked
(on Linux) so the mission and world modules are imported once, in the parent. Results are
taken as they finish (``progress`` sees that order; the list returned is in spec order), and
a worker that dies breaks the pool (``concurrent.futures``' BrokenProcessPool) instead of
hanging it: its unfinished episodes run again in a new one.
"""

from __future__ import annotations

import itertools
import multiprocessing
import signal
import sys
import time
from collections.abc import Callable, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass, field
from typing import TextIO

from roomba_bt.evaluate import episode
from roomba_bt.evaluate.episode import EpisodeResult, EpisodeSpec, run_episode

Progress = Callable[[int, int, EpisodeResult], None]


#: How many times a local evaluation starts its workers again after one died (killed by the
#: OOM killer or a ``kill -9``); after that it stops with :class:`WorkersLostError`.
POOL_RESTARTS = 2


class WorkersLostError(RuntimeError):
    """A local worker process died more often than :data:`POOL_RESTARTS`: the episodes
    that finished (``finished``, in spec order) and a message naming those that did not."""

    def __init__(self, message: str, finished: list[EpisodeResult], retried: int) -> None:
        super().__init__(message)
        self.finished = finished
        self.retried = retried


@dataclass
class LocalRun:
    """A local evaluation as it goes: results by spec index, the episodes run again."""

    results: dict[int, EpisodeResult] = field(default_factory=dict)
    retried: int = 0

    def in_order(self) -> list[EpisodeResult]:
        return [self.results[i] for i in sorted(self.results)]


def run_episodes(
    specs: Sequence[EpisodeSpec],
    jobs: int = 1,
    progress: Progress | None = None,
    run: LocalRun | None = None,
) -> list[EpisodeResult]:
    """Run every spec; results in spec order, ``progress(done, total, result)`` after each
    one finishes (in the order they finish). With ``jobs`` > 1 a worker that dies does not
    hang the evaluation: the episodes its pool had not finished run again in new workers
    (counted in ``run.retried``), up to :data:`POOL_RESTARTS` times, then
    :class:`WorkersLostError`. ``run`` holds what finished (also after a Ctrl-C)."""
    run = run if run is not None else LocalRun()
    total = len(specs)

    def finished(index: int, result: EpisodeResult) -> None:
        run.results[index] = result
        if progress is not None:
            progress(len(run.results), total, result)

    if jobs <= 1 or total <= 1:
        for index, spec in enumerate(specs):
            finished(index, run_episode(spec))
        return run.in_order()
    todo = list(range(total))
    for restart in range(POOL_RESTARTS + 1):
        lost, unstarted = _pool_round(specs, todo, jobs, finished)
        todo = sorted([*lost, *unstarted])
        if not todo:
            return run.in_order()
        if restart == POOL_RESTARTS:
            raise WorkersLostError(
                f"a worker process died {POOL_RESTARTS + 1} times (killed: the OOM killer?); "
                f"{len(todo)} episode(s) did not finish: seeds {_seeds(specs, todo)}",
                run.in_order(),
                run.retried,
            )
        run.retried += len(lost)
        print(f"roomba-bt eval: a worker process died (killed: the OOM killer?); the "
              f"{len(lost)} episode(s) its pool had taken run again in new workers: seeds "
              f"{_seeds(specs, lost)}", file=sys.stderr)  # fmt: skip
    return run.in_order()  # not reached: the last round returns or raises


def _seeds(specs: Sequence[EpisodeSpec], indices: Sequence[int], shown: int = 10) -> str:
    seeds = [str(specs[i].seed) for i in indices]
    more = f" and {len(seeds) - shown} more" if len(seeds) > shown else ""
    return ", ".join(seeds[:shown]) + more


def _pool_round(
    specs: Sequence[EpisodeSpec],
    todo: Sequence[int],
    jobs: int,
    finished: Callable[[int, EpisodeResult], None],
) -> tuple[list[int], list[int]]:
    """``specs[i]`` for each ``i`` in ``todo`` on ``jobs`` worker processes, each result to
    ``finished`` as it comes; when a worker died, the indices the pool had taken and lost
    (running or queued in it: a broken pool ends every worker) and those never handed to it.
    A few episodes are queued ahead per worker, not all: a million futures would fill memory."""
    method = "fork" if "fork" in multiprocessing.get_all_start_methods() else "spawn"
    executor = ProcessPoolExecutor(
        max_workers=min(jobs, len(todo)),
        mp_context=multiprocessing.get_context(method),
        initializer=_worker_started,
    )
    queue = iter(todo)
    running: dict[Future[EpisodeResult], int] = {}
    lost: list[int] = []

    def submit(index: int) -> None:
        try:
            running[executor.submit(run_episode, specs[index])] = index
        except BrokenProcessPool:  # a worker died since the last result
            lost.append(index)

    try:
        for index in itertools.islice(queue, 2 * jobs):
            submit(index)
        while running:
            ready, _ = wait(running, return_when=FIRST_COMPLETED)
            for future in ready:
                index = running.pop(future)
                if isinstance(future.exception(), BrokenProcessPool):
                    lost.append(index)
                    continue
                finished(index, future.result())
                nxt = None if lost else next(queue, None)
                if nxt is not None:
                    submit(nxt)
        return sorted(lost), list(queue)
    except BaseException:  # Ctrl-C (or an episode's bug): no worker left running
        _terminate(executor)
        raise
    finally:
        executor.shutdown(wait=True, cancel_futures=True)


def _terminate(executor: ProcessPoolExecutor) -> None:
    """End the workers at once (an episode on the simulator drives nothing)."""
    terminate = getattr(executor, "terminate_workers", None)  # Python 3.14
    if terminate is not None:
        terminate()
        return
    for process in list(getattr(executor, "_processes", {}).values()):
        process.terminate()


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
            run = LocalRun()
            try:
                run_episodes(specs, engine.jobs, bar, run)
            except KeyboardInterrupt:
                out.append(Evaluation(run.in_order(), run.retried, True, "local"))
                continue
            except WorkersLostError as exc:
                print(f"roomba-bt eval: {exc}; stopped", file=sys.stderr)
                out.append(Evaluation(run.in_order(), run.retried, True, "local"))
                continue
            out.append(Evaluation(run.in_order(), run.retried, False, "local"))
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
