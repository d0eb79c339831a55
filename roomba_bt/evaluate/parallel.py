"""Episodes in parallel, results in spec order whatever ran them: local worker processes
(``--jobs``) or a Dask cluster (:mod:`roomba_bt.evaluate.cluster`).

Every episode is decided by its :class:`~roomba_bt.evaluate.episode.EpisodeSpec` alone (the
seed picks the start pose and the simulator's random draws), so ``--jobs 1`` and ``--jobs 2``
give the same results in the same order; only the wall time differs. Workers are forked
(on Linux) so the mission and world modules are imported once, in the parent. Results are
taken as they finish (``progress`` sees that order; the list returned is in spec order), and
a worker that dies breaks the pool (``concurrent.futures``' BrokenProcessPool) instead of
hanging it: its unfinished episodes run again in a new one, and those that were running when
it died first run alone, each in a worker of its own, so that an episode that kills its
worker (a behaviour calling ``os._exit``, a crash in C code) is found and recorded as
:data:`~roomba_bt.evaluate.episode.DIED` while the sweep goes on.
"""

from __future__ import annotations

import contextlib
import itertools
import multiprocessing
import os
import signal
import threading
import time
import traceback
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass, field
from multiprocessing.context import BaseContext
from multiprocessing.process import BaseProcess
from types import FrameType
from typing import Any, cast

from roomba_bt.evaluate import episode
from roomba_bt.evaluate.episode import (
    EpisodeResult,
    EpisodeSpec,
    died_result,
    hung_result,
    run_episode,
)
from roomba_bt.evaluate.interleave import (
    Interleaved,
    InterleavedSpecs,
    variant_count,
    variant_label,
)
from roomba_bt.evaluate.interleave import Progress as Progress  # re-exported: callers name it here
from roomba_bt.evaluate.progress import ProgressBar as ProgressBar  # re-exported, as Progress
from roomba_bt.evaluate.progress import end_bars as end_bars
from roomba_bt.evaluate.progress import say
from roomba_bt.runtime.ending import threads_left

#: How many times a local evaluation starts its workers again after one died with no episode
#: to blame (each episode it was running ran alone without a death: ended from outside, by
#: the OOM killer or a ``kill -9``); after that it stops with :class:`WorkersLostError`. An
#: episode that kills its worker again when it runs alone is recorded as DIED instead, and
#: is no such death: the sweep goes on.
POOL_RESTARTS = 2
#: How many threads stuck in a behaviour's ``terminate()`` or ``shutdown()`` an evaluation in
#: its own process (``--jobs 1 --wall-limit none``) lets its episodes leave before it stops
#: with :class:`ThreadsLeftError`. The run's end goes on without such a
#: thread (``runtime/ending.py``), a daemon, so the process still exits; but it lives until
#: then, holding its episode's tree, connection and simulator: one per episode, without
#: bound, over a sweep of thousands.
THREADS_LEFT_CAP = 10


class ThreadsLeftError(RuntimeError):
    """An evaluation in its own process stopped: its episodes left :data:`THREADS_LEFT_CAP`
    threads stuck in a behaviour's ``terminate()`` or ``shutdown()``; what finished is kept
    (``run``'s results, as on Ctrl-C)."""


class WorkerRetired(Exception):
    """Raised in a pool worker instead of running an episode: an episode before left a
    thread stuck in a behaviour's ``terminate()`` or ``shutdown()`` in that process
    (:func:`_watched_episode`). The round hands no more episodes to its pool and runs this
    one and the rest in a new one (:func:`_pool_round`): a worker with stuck threads is
    retired and replaced, the rule of a sweep in its own process
    (:data:`THREADS_LEFT_CAP`), where a process cannot be replaced, made that of each
    worker, which can (else a worker keeps one per such episode, without bound, each
    holding its episode's tree and simulator until the worker ends)."""


class WorkersLostError(RuntimeError):
    """A local worker process died more often than :data:`POOL_RESTARTS` with no episode to
    blame: the episodes that finished (``finished``, in spec order) and a message naming
    those that did not."""

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
    wall_limit_s: float | None = None,
) -> list[EpisodeResult]:
    """Run every spec; results in spec order, ``progress(done, total, result)`` after each
    one finishes (in the order they finish). In worker processes, a worker that dies does
    not hang the evaluation: the episodes its pool had not finished run again in new workers
    (counted in ``run.retried``), those it was running first alone (:func:`_blame`): one
    that kills its worker again is recorded as DIED and the sweep goes on; a death with no
    episode to blame is allowed :data:`POOL_RESTARTS` times, then :class:`WorkersLostError`.
    ``run`` holds what finished (also after a Ctrl-C).

    ``wall_limit_s``: an episode still running after that many seconds of wall-clock time
    is recorded as :data:`~roomba_bt.evaluate.episode.HUNG` (where it was stuck: its worker
    is asked, :func:`_say_where_stuck`) and its worker is ended, the pool's other episodes
    run again as after a death (not counted as one). Only a process can be ended whatever
    it runs, so with a limit even ``jobs`` 1 runs in a worker process; without one (None),
    ``jobs`` 1 runs in this process, and an endless loop in a behaviour hangs it (and one
    that ends its process ends the evaluation; a cap: :func:`_in_this_process`)."""
    run = run if run is not None else LocalRun()
    total = len(specs)

    def finished(index: int, result: EpisodeResult) -> None:
        run.results[index] = result
        if progress is not None:
            progress(len(run.results), total, result)

    if wall_limit_s is None and (jobs <= 1 or total <= 1):
        _in_this_process(specs, finished)
        return run.in_order()
    todo: Sequence[int] = range(total)  # a list of 100 000 indices was 3.6 MB
    deaths = 0
    while todo:
        ended = _pool_round(specs, todo, jobs, finished, wall_limit_s)
        todo = sorted([*ended.lost, *ended.unstarted])
        if not ended.lost:
            continue
        run.retried += len(ended.lost)
        if ended.hung:  # ended here: no death
            why = "; ".join(f"seed {specs[i].seed}: {run.results[i].reason}" for i in ended.hung)
            say(f"roomba-bt eval: an episode ran past its wall-clock limit, its worker ended "
                f"({why}); the {len(ended.lost)} episode(s) its pool had taken run again in "
                f"new workers: seeds {seeds_said(specs, ended.lost)}")  # fmt: skip
            continue
        todo = [i for i in todo if i not in ended.running]
        if _blame(specs, ended, finished, wall_limit_s) or not todo:
            continue
        if deaths == POOL_RESTARTS:
            raise WorkersLostError(
                f"a worker process died {POOL_RESTARTS + 1} times with no episode to blame "
                f"(ended from outside: the OOM killer?); {len(todo)} episode(s) did not "
                f"finish: seeds {seeds_said(specs, todo)}",
                run.in_order(),
                run.retried,
            )
        deaths += 1
    return run.in_order()


def _in_this_process(
    specs: Sequence[EpisodeSpec], finished: Callable[[int, EpisodeResult], None]
) -> None:
    """Every spec's episode in this process, one after the other, until they have left
    :data:`THREADS_LEFT_CAP` threads stuck in a behaviour: then :class:`ThreadsLeftError`."""
    total = len(specs)
    before = threads_left()  # a program's own, from runs before this one: not counted
    for index, spec in enumerate(specs):
        finished(index, run_episode(spec))
        left = threads_left() - before
        if left >= THREADS_LEFT_CAP and index + 1 < total:
            raise ThreadsLeftError(
                f"the sweep stopped: {left} episode(s) left a thread stuck in a behaviour's "
                "terminate() or shutdown() in this process (each keeps its episode's tree and "
                f"simulator until the process exits; at most {THREADS_LEFT_CAP}); "
                f"{total - index - 1} episode(s) not run"
            )


def _blame(
    specs: Sequence[EpisodeSpec],
    ended: _Round,
    finished: Callable[[int, EpisodeResult], None],
    wall_limit_s: float | None,
) -> bool:
    """After a worker died: each episode that was running then (any of them may have killed
    it; a broken pool ends the others) runs again alone, in a pool of one worker, and one
    whose worker dies again is recorded as DIED (:func:`~roomba_bt.evaluate.episode.died_result`,
    how it died as the reason). Whether one was: else the worker was ended from outside.
    What happens is said on stderr as it happens."""
    running = f"seed(s) {seeds_said(specs, ended.running)}" if ended.running else ""
    queued = [i for i in ended.lost if i not in ended.running]
    say(f"roomba-bt eval: a worker process died: {ended.died or 'exit status unknown'}; "
        + (f"{running} were running: each runs again alone" if running else
           "no episode was running: none to blame")
        + (f"; the {len(queued)} other episode(s) its pool had taken run again in new "
           f"workers: seeds {seeds_said(specs, queued)}" if queued else ""))  # fmt: skip
    blamed = False
    for index in ended.running:
        alone = _pool_round(specs, [index], 1, finished, wall_limit_s)
        if alone.lost:
            died = alone.died or "exit status unknown"
            how = f"{died}, twice (the second time running it alone)"
            finished(index, died_result(specs[index], how))
            say(f"roomba-bt eval: seed {seeds_said(specs, [index])} killed its worker again, "
                f"alone ({died}): recorded as DIED")  # fmt: skip
            blamed = True
    if ended.running and not blamed:
        say(f"roomba-bt eval: {running} ran alone without a death: the worker was "
            "ended from outside (the OOM killer? a kill -9?)")  # fmt: skip
    return blamed


def seeds_said(specs: Sequence[EpisodeSpec], indices: Sequence[int], shown: int = 10) -> str:
    """The seeds of ``specs[i]`` for each of ``indices`` (the first ``shown``), each with its
    variant when ``specs`` hold several (an A/B runs every seed once per variant: its seeds
    read ``28, 28``, the same episode twice to a reader): ``28 (dock), 28 (my-dock.yaml)``,
    each variant as the report labels it (:func:`~roomba_bt.evaluate.interleave.variant_label`)."""
    several = variant_count(specs) > 1
    seeds = [_seed_said(specs, i, several) for i in indices]
    more = f" and {len(seeds) - shown} more" if len(seeds) > shown else ""
    return ", ".join(seeds[:shown]) + more


def _seed_said(specs: Sequence[EpisodeSpec], index: int, variant: bool) -> str:
    """``specs[index]``'s seed, with its variant as the report labels it when ``variant``."""
    spec = specs[index]
    if not variant:
        return str(spec.seed)
    if isinstance(specs, InterleavedSpecs):
        return f"{spec.seed} ({specs.label(index)})"
    return f"{spec.seed} ({variant_label(spec.mission, spec.params)})"


@dataclass(frozen=True)
class _Round:
    """How a pool round ended. When a worker died: the episodes the pool had taken and lost
    (running or queued in it: a broken pool ends every worker), those of them that had
    started (``running``: one of these may have killed it) and how it died (its exit status,
    :meth:`_WorkersKept.how_one_died`; "" when unknown); the episodes never handed to the pool or
    refused by a retired worker (``unstarted``: :class:`WorkerRetired`), and those ended at
    the wall-clock limit (``hung``: their HUNG results
    are in)."""

    lost: list[int]
    running: list[int]
    unstarted: list[int]
    hung: list[int]
    died: str = ""


def _pool_round(
    specs: Sequence[EpisodeSpec],
    todo: Sequence[int],
    jobs: int,
    finished: Callable[[int, EpisodeResult], None],
    wall_limit_s: float | None = None,
) -> _Round:
    """``specs[i]`` for each ``i`` in ``todo`` on ``jobs`` worker processes, each result to
    ``finished`` as it comes, until they are done or a worker dies (:class:`_Round`). A few
    episodes are queued ahead per worker, not all: a million futures would fill memory."""
    forks = "fork" in multiprocessing.get_all_start_methods()
    context = multiprocessing.get_context("fork" if forks else "spawn")
    watch = _Watch(context, wall_limit_s)
    workers = _WorkersKept(context)  # their exit codes say how one died
    executor = ProcessPoolExecutor(
        max_workers=min(jobs, len(todo)),
        mp_context=cast(BaseContext, workers),
        initializer=_worker_started,
        initargs=(watch.reports, wall_limit_s or 0.0),
    )
    queue = iter(todo)
    running: dict[Future[EpisodeResult], int] = {}
    lost: list[int] = []
    retired: list[int] = []  # refused by a worker with stuck threads: the next round's

    def submit(index: int) -> None:
        try:
            with _signals_held_while_workers_start():  # a submit may fork the workers
                running[executor.submit(_watched_episode, index, specs[index])] = index
        except BrokenProcessPool:  # a worker died since the last result
            lost.append(index)

    try:
        for index in itertools.islice(queue, 2 * jobs):
            submit(index)
        while running:
            ready, _ = wait(running, timeout=watch.next_check(), return_when=FIRST_COMPLETED)
            for future in ready:
                index = running.pop(future)
                if index in watch.hung:
                    continue  # its HUNG result is in
                error = future.exception()
                if isinstance(error, BrokenProcessPool | WorkerRetired):
                    (retired if isinstance(error, WorkerRetired) else lost).append(index)
                    continue
                watch.ended(index)
                finished(index, future.result())
                nxt = None if lost or watch.hung or retired else next(queue, None)
                if nxt is not None:
                    submit(nxt)
            for index, result in watch.overdue(specs, running):
                finished(index, result)
    except BaseException:  # Ctrl-C (or an episode's bug): no worker left running
        workers.terminate()
        raise
    finally:
        executor.shutdown(wait=True, cancel_futures=True)
        began = watch.close(lost)
    died = workers.how_one_died() if lost and not watch.hung else ""
    return _Round(sorted(lost), began, sorted([*retired, *queue]), sorted(watch.hung), died)


class _WorkersKept:
    """The multiprocessing context a pool starts its workers with (``ProcessPoolExecutor``'s
    public ``mp_context``: the pool calls its ``Process`` for each worker), which keeps
    each worker it starts: once the pool is shut down (its workers joined), their exit codes
    say how the one that broke it ended (:meth:`how_one_died`), and a Ctrl-C ends them
    (:meth:`terminate`). Both read the pool's private ``_processes`` before, which a
    Python release may rename or empty at its shutdown; the rest is ``context``'s own."""

    def __init__(self, context: BaseContext) -> None:
        self._context = context
        self.processes: list[BaseProcess] = []

    def Process(self, *args: Any, **kwargs: Any) -> BaseProcess:  # the context's own name
        process = cast(BaseProcess, self._context.Process(*args, **kwargs))  # type: ignore[attr-defined]
        self.processes.append(process)
        return process

    def __getattr__(self, name: str) -> Any:
        return getattr(self._context, name)

    def terminate(self) -> None:
        """End every worker still running at once (an episode on the simulator drives
        nothing): SIGTERM, which a started worker takes at once (:func:`_worker_started`)."""
        for process in self.processes:
            if process.exitcode is None:
                process.terminate()

    def how_one_died(self) -> str:
        """How the worker that broke the pool ended, read once the pool is shut down (the
        others were ended with SIGTERM): ``exit status 1``, ``killed by SIGSEGV (a crash in
        C code)``; "" when none ended otherwise."""
        codes = [
            p.exitcode
            for p in self.processes
            if p.exitcode is not None and p.exitcode not in (0, -ENDS_A_WORKER)
        ]
        return "; ".join(exit_status(code) for code in dict.fromkeys(codes))


#: What a signal that killed a worker most often means.
_KILLED_BY = {
    "SIGKILL": " (the OOM killer? a kill -9?)",
    "SIGSEGV": " (a crash in C code)",
    "SIGBUS": " (a crash in C code)",
    "SIGABRT": " (a crash in C code: abort())",
}


def exit_status(code: int) -> str:
    """A process's exit code in words: ``exit status 1``, or ``killed by SIGSEGV (a crash in
    C code)`` for a negative one (the signal that ended it)."""
    if code >= 0:
        return f"exit status {code}"
    try:
        name = signal.Signals(-code).name
    except ValueError:
        return f"killed by signal {-code}"
    return f"killed by {name}{_KILLED_BY.get(name, '')}"


#: How long the parent waits for a stuck worker to say where it is before ending it, and
#: the longest wait between two looks at the episodes' wall-clock times (s).
STUCK_REPORT_S = 2.0
WATCH_POLL_S = 1.0


class _Watch:
    """A pool round's workers as they go: each says on ``reports`` when it starts an episode
    (index, pid, ``time.monotonic()``: one clock for every process of the machine), so that
    after a death the round knows which episodes were running (:meth:`began`); with a
    wall-clock limit, where it is stuck when asked (:func:`_say_where_stuck`)."""

    def __init__(self, context: Any, limit_s: float | None) -> None:
        # a SimpleQueue writes in the worker's own thread: a Queue's feeder thread might
        # never send the start of an episode stuck in C code, holding the GIL
        self.reports: Any = context.SimpleQueue()
        self.limit_s = limit_s
        self.started: dict[int, tuple[int, float]] = {}
        self.hung: set[int] = set()

    def _read(self, stuck: int | None = None) -> EpisodeResult | None:
        """Every report waiting; with ``stuck``, that episode's HUNG result, waited for up
        to :data:`STUCK_REPORT_S` (None: it did not come)."""
        deadline = time.monotonic() + STUCK_REPORT_S
        while True:
            if self.reports.empty():
                if stuck is None or time.monotonic() >= deadline:
                    return None
                time.sleep(0.01)  # a pipe another process writes: no event to wait on
                continue
            index, pid, started, result = self.reports.get()
            if result is None:
                self.started[index] = (pid, started)
            elif index == stuck:
                return cast(EpisodeResult, result)

    def close(self, lost: list[int]) -> list[int]:
        """The reports' pipe closed, once read: those of ``lost`` (with their pool) that had
        started. A worker says so before it runs one, in a pipe written at once, so it is
        there when the pool breaks (finished and hung episodes are no longer in
        :attr:`started`)."""
        self._read()
        self.reports.close()
        return sorted(i for i in lost if i in self.started)

    def ended(self, index: int) -> None:
        """Episode ``index`` finished: forgotten. Its start was written before its result,
        so it is read here, not later (where it would look like an episode running)."""
        self._read()
        self.started.pop(index, None)

    def next_check(self) -> float | None:
        """How long the round may wait for a result before looking again (None: no limit)."""
        if self.limit_s is None:
            return None
        self._read()
        now = time.monotonic()
        ends = [t + self.limit_s - now for _, t in self.started.values()]
        return max(0.01, min([WATCH_POLL_S, *ends]))

    def overdue(
        self, specs: Sequence[EpisodeSpec], running: dict[Future[EpisodeResult], int]
    ) -> list[tuple[int, EpisodeResult]]:
        """Each running episode past the limit, its HUNG result, its worker ended (the pool
        breaks: the round ends as after a death). One at a time: the others are lost with
        the pool, and run again."""
        if self.limit_s is None:
            return []
        self._read()
        taken = {i for f, i in running.items() if not f.done()}
        now = time.monotonic()
        limit = self.limit_s
        late = [i for i, (_, t) in self.started.items() if i in taken and now - t >= limit]
        if not late or self.hung:
            return []
        index = late[0]
        pid, _ = self.started.pop(index)
        result = None
        with contextlib.suppress(ProcessLookupError):
            if ASK_WHERE is not None:  # POSIX: the worker says where it is stuck first
                os.kill(pid, ASK_WHERE)
                result = self._read(stuck=index)
            os.kill(pid, END_AT_ONCE)
        if result is None:
            result = hung_result(specs[index], limit, None)
        self.hung.add(index)
        return [(index, result)]


#: The signal that asks a stuck worker where it is (POSIX's SIGUSR1; Windows has none: a
#: hung episode there is recorded without its place), and the one that ends it (SIGKILL;
#: Windows' os.kill with SIGTERM is TerminateProcess, as final)
ASK_WHERE: signal.Signals | None = getattr(signal, "SIGUSR1", None)
END_AT_ONCE: signal.Signals = getattr(signal, "SIGKILL", signal.SIGTERM)


#: The signals a pool worker leaves to its parent (a terminal sends Ctrl-C and its hangup to
#: the whole process group), and the one its parent ends it with (:meth:`_WorkersKept.terminate`).
LEFT_TO_THE_PARENT: tuple[signal.Signals, ...] = tuple(
    s for s in (signal.SIGINT, getattr(signal, "SIGHUP", None)) if s is not None
)
ENDS_A_WORKER: signal.Signals = signal.SIGTERM


@contextlib.contextmanager
def _signals_held_while_workers_start() -> Iterator[None]:
    """A forked worker starts with this process's Python signal handlers until its
    initializer (:func:`_worker_started`) replaces them: a Ctrl-C in that window raised
    KeyboardInterrupt in it, and the parent's SIGTERM raised the CLI's ``Terminated``
    (:func:`~roomba_bt.robot.safety.raise_terminated`), each a traceback under the summary
    (the window is long on a loaded machine). Meanwhile they are held here: a worker not
    started yet ignores what is left to the parent and ends at once at its SIGTERM; this
    process gets its own again, through its own handlers, once the submit is done."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    parent = os.getpid()
    came: list[int] = []

    def held(signum: int, frame: FrameType | None) -> None:
        if os.getpid() == parent:
            came.append(signum)
        elif signum == ENDS_A_WORKER:
            os._exit(128 + signum)  # a worker not started yet: nothing of it to keep

    previous = {s: signal.signal(s, held) for s in (*LEFT_TO_THE_PARENT, ENDS_A_WORKER)}
    try:
        yield
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, handler)
        for held_signal in dict.fromkeys(came):
            signal.raise_signal(held_signal)


def _worker_started(reports: Any = None, limit_s: float = 0.0) -> None:
    """A pool worker leaves Ctrl-C (and a hangup) to its parent, which ends the pool, and
    the SIGTERM it is ended with ends it at once (on the simulator nothing drives): each
    worker raising KeyboardInterrupt at Ctrl-C, or the CLI's ``Terminated`` at SIGTERM
    (handlers a forked worker inherits), printed its traceback under the summary.
    ``reports`` is the queue to the parent (each episode's start); with a wall-clock limit
    (``limit_s`` above 0), SIGUSR1 asks where the episode is stuck."""
    for signum in LEFT_TO_THE_PARENT:
        signal.signal(signum, signal.SIG_IGN)
    signal.signal(ENDS_A_WORKER, signal.SIG_DFL)
    episode.IN_POOL_WORKER = True
    threading.Thread(target=_end_with, args=(os.getppid(),), daemon=True).start()
    if reports is not None:
        _WORKER.update(reports=reports, limit_s=limit_s, running=None)
        if ASK_WHERE is not None and limit_s > 0:
            signal.signal(ASK_WHERE, _say_where_stuck)


def _end_with(parent: int) -> None:
    """A worker ends when its parent does: an evaluation killed (``kill -9``, the OOM killer)
    left its workers running their episodes, then waiting for more for ever, holding its
    terminal's pipes (a worker's parent is the evaluation: a new one once it is gone)."""
    while os.getppid() == parent:
        time.sleep(PARENT_POLL_S)
    os._exit(1)


#: How often a worker looks whether its evaluation is still there (s).
PARENT_POLL_S = 0.5

#: A watched worker's queue to its parent, its limit, and the episode running (index, spec).
_WORKER: dict[str, Any] = {}


def _watched_episode(index: int, spec: EpisodeSpec) -> EpisodeResult:
    """:func:`run_episode` in a pool worker; in a watched one, its start said to the parent
    first. Not in a worker an episode left a thread stuck in: :class:`WorkerRetired`."""
    if threads_left():  # a forked worker starts with none of its parent's threads
        raise WorkerRetired(f"a thread stuck in a behaviour in worker {os.getpid()}")
    reports = _WORKER.get("reports")
    if reports is None:
        return run_episode(spec)
    _WORKER["running"] = (index, spec)
    reports.put((index, os.getpid(), time.monotonic(), None))
    try:
        return run_episode(spec)
    finally:
        _WORKER["running"] = None


def _say_where_stuck(signum: int, frame: FrameType | None) -> None:
    """SIGUSR1 in a watched worker: the running episode's HUNG result, read from the stack
    it is stuck on (a signal's handler runs between two bytecodes of the main thread: in
    the loop itself), to the parent, which then ends this process."""
    running = _WORKER.get("running")
    if running is None or frame is None:  # between two episodes: nothing is stuck
        return
    index, spec = running
    frames = list(traceback.walk_stack(frame))[::-1]
    _WORKER["reports"].put((index, os.getpid(), 0.0, hung_result(spec, _WORKER["limit_s"], frames)))


#: The causes of an :class:`Interruption` that are no signal: the machinery that runs the
#: episodes failed, not the operator. Local worker processes kept dying with no episode to
#: blame (:class:`WorkersLostError`); the Dask cluster had no worker for ``--worker-wait``
#: (:class:`~roomba_bt.evaluate.cluster.NoWorkersError`); the Dask scheduler was lost, or
#: forgot the episodes (:class:`~roomba_bt.evaluate.cluster.SchedulerLostError`).
WORKERS_LOST = "workers-lost"
#: ... and the episodes of one in its own process left too many threads stuck in a
#: behaviour (:class:`ThreadsLeftError`): a bug in the behaviour, as a HUNG episode is
THREADS_LEFT = "threads-left"
NO_WORKERS = "no-workers"
SCHEDULER_LOST = "scheduler-lost"
ENVIRONMENT_FAILURES = frozenset({WORKERS_LOST, NO_WORKERS, SCHEDULER_LOST})


@dataclass(frozen=True)
class Interruption:
    """Why an evaluation stopped before its end: ``cause``, a word for scripts (the signal's
    name, ``SIGINT`` for Ctrl-C, or one of :data:`WORKERS_LOST`, :data:`NO_WORKERS`,
    :data:`SCHEDULER_LOST`), and ``said``, the same in words (``by Ctrl-C (SIGINT)``, the
    cluster's failure). ``eval --json`` said ``"interrupted": true`` and no more: a Ctrl-C,
    a job scheduler's SIGTERM and a cluster gone read alike."""

    cause: str
    said: str

    @property
    def environment_failed(self) -> bool:
        """The machinery that runs the episodes failed (``eval`` exits 3, as for a
        connection's failure); else a signal stopped it, the operator's (exit 130)."""
        return self.cause in ENVIRONMENT_FAILURES

    @property
    def behaviour_failed(self) -> bool:
        """A behaviour's bug stopped it (:data:`THREADS_LEFT`): ``eval`` exits 4."""
        return self.cause == THREADS_LEFT


def interruption_by(interrupt: KeyboardInterrupt) -> Interruption:
    """The :class:`Interruption` a Ctrl-C or a signal stands for (a
    :class:`~roomba_bt.robot.safety.Terminated` carries its signal: SIGTERM, SIGHUP), in the
    run summary's words."""
    from roomba_bt.robot.safety import signal_reason

    signum = getattr(interrupt, "signum", signal.SIGINT)
    said = signal_reason(signum)
    return Interruption(signal.Signals(signum).name, f"by {said}")


@dataclass(frozen=True)
class Evaluation:
    """What a batch of episodes gave: results in spec order (only those that finished when
    ``interrupted``), how many were run again after a worker died, and where they ran;
    ``interruption``, why it stopped before the end (a signal, or the workers or the cluster
    gone; set whenever the engine stopped it, with ``interrupted``)."""

    results: list[EpisodeResult]
    retried: int = 0
    interrupted: bool = False
    engine: str = "local"
    interruption: Interruption | None = None


#: How long an evaluation on Dask waits with no worker in the cluster before it stops (s;
#: ``eval --worker-wait``): long enough for a nanny to start a dead worker again, or a
#: worker machine to reboot; a cluster whose workers are gone for good held the episodes,
#: and the evaluation, for ever.
WORKER_WAIT_S = 120.0


@dataclass(frozen=True)
class Engine:
    """Where episodes run: ``local`` processes (``jobs``), or ``dask`` (a local cluster of
    ``jobs`` workers, or the cluster at ``scheduler``); each episode's wall-clock limit
    (s; None: none, :func:`run_episodes` and :func:`~roomba_bt.evaluate.cluster.run_on_worker`
    say what it does where); on Dask, how long to wait with no worker in the cluster before
    stopping (s; None: for ever, :class:`~roomba_bt.evaluate.cluster.WorkerWatch`)."""

    kind: str = "local"
    jobs: int = 1
    scheduler: str | None = None
    wall_limit_s: float | None = None
    worker_wait_s: float | None = WORKER_WAIT_S

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
    labels: Sequence[str] = (),
) -> list[Evaluation]:
    """Run each batch on ``engine``, the batches' episodes taken by seed (A1 B1 A2 B2 ...:
    :class:`~roomba_bt.evaluate.interleave.Interleaved`, so that an interrupted A/B still
    holds pairs), on one pool or one Dask client; ``progress[i]`` for batch ``i``, with its
    own count. An :class:`Evaluation` per batch, its results in its spec order. A Ctrl-C or
    a signal stops the run (each batch ``interrupted``, with its :class:`Interruption` and
    what finished), as do local workers that keep dying (:class:`WorkersLostError`) and a
    Dask cluster lost (no worker, no scheduler). The episodes run again after a worker was
    lost are counted once, on the first batch's: they ran in one pool. ``labels``: each
    batch's variant as the report names it, which the lines about its seeds say (none:
    made from its specs, :func:`~roomba_bt.evaluate.interleave.variant_label`)."""
    work = Interleaved.of(batches, labels)
    bar = work.progress(progress or [None] * len(batches))
    results: dict[int, EpisodeResult] = {}
    retried, interruption = 0, None
    if work.specs:  # none: every episode was there already (eval --resume), no pool started
        run = _on_dask if engine.kind == "dask" else _on_local_processes
        results, retried, interruption = run(work.specs, engine, bar)
    stopped = interruption is not None
    return [
        Evaluation(finished, retried if b == 0 else 0, stopped, engine.kind, interruption)
        for b, finished in enumerate(work.split(results))
    ]


#: What a run of episodes gave: the results that finished by spec index, the episodes run
#: again after a worker was lost, and why it stopped before its end (None: it did not)
_Ran = tuple[dict[int, EpisodeResult], int, "Interruption | None"]


def _on_local_processes(specs: Sequence[EpisodeSpec], engine: Engine, bar: Progress | None) -> _Ran:
    """:func:`run_episodes` on ``engine.jobs`` processes; what finished when a Ctrl-C, a
    signal or workers that keep dying stopped it."""
    run = LocalRun()
    interruption = None
    try:
        run_episodes(specs, engine.jobs, bar, run, engine.wall_limit_s)
    except KeyboardInterrupt as exc:
        interruption = interruption_by(exc)
    except WorkersLostError as exc:
        interruption = Interruption(WORKERS_LOST, str(exc))
    except ThreadsLeftError as exc:
        interruption = Interruption(THREADS_LEFT, str(exc))
    return run.results, run.retried, interruption


def _on_dask(specs: Sequence[EpisodeSpec], engine: Engine, bar: Progress | None) -> _Ran:
    """The episodes on a Dask cluster (:func:`~roomba_bt.evaluate.cluster.run_on_client`);
    what finished when a Ctrl-C, a signal or the cluster's loss stopped it."""
    from roomba_bt.evaluate.cluster import ClusterLostError, dask_client, run_on_client

    interruption = None
    with dask_client(engine.scheduler, engine.jobs, engine.worker_wait_s) as client:
        try:
            flat, retried, interrupt = run_on_client(
                client, specs, bar, engine.wall_limit_s, engine.worker_wait_s
            )
            if interrupt is not None:
                interruption = interruption_by(interrupt)
        except ClusterLostError as exc:
            flat, retried = exc.results, exc.retried
            interruption = Interruption(exc.cause, exc.why)
    return {i: r for i, r in enumerate(flat) if r is not None}, retried, interruption
