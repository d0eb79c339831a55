"""Episodes on a Dask distributed cluster: an existing one (``--scheduler tcp://HOST:8786``) or
a local one started for the evaluation (``--engine dask``).

Nothing here schedules, retries or balances by itself: Dask does. Each episode is one future
of :func:`run_on_worker` on a :func:`~roomba_bt.evaluate.episode.self_contained` spec (the
mission's texts travel with it, so workers need only ``pip install roomba-bt[cluster]``, no
shared file system). A worker that dies mid-episode loses nothing: the scheduler hands its
episodes to another worker (Dask's own resubmission, up to its ``allowed-failures``), and
since an episode is decided by its spec alone the rerun gives the same result. Each result
is released as it is gathered (in batches), so a dead worker's finished episodes are not
computed again; how many episodes were run again is read from the scheduler (each task's
``suspicious`` count: the times a worker died while holding it) just before each batch is
released.

Results come back in spec order; progress is reported as futures complete, in completion
order. Ctrl-C (KeyboardInterrupt) cancels the futures still pending and returns what
finished, with the interrupt. A cluster that can run no more of them (no worker for
``--worker-wait``, its scheduler lost) stops the evaluation with what finished
(:class:`ClusterLostError`).
"""

from __future__ import annotations

import contextlib
import logging
import signal
import threading
import time
import traceback
import uuid
import warnings
from collections.abc import Callable, Iterable, Iterator, Sequence
from dataclasses import dataclass, field
from typing import Any

from roomba_bt.evaluate.episode import (
    Bundles,
    EpisodeResult,
    EpisodeSpec,
    died_result,
    hung_result,
    run_episode,
)
from roomba_bt.evaluate.parallel import NO_WORKERS, SCHEDULER_LOST, seeds_said
from roomba_bt.evaluate.progress import say
from roomba_bt.evaluate.sources import remove_copies
from roomba_bt.installation import optional_import_failure
from roomba_bt.runtime.wall_limit import WallLimit, WallLimitReached


class ClusterUnavailableError(RuntimeError):
    """Dask distributed is not installed (the cluster extra): a usage problem."""


class SchedulerUnreachableError(ClusterUnavailableError):
    """The scheduler at ``--scheduler`` did not answer: a connection problem."""


class SchedulerAddressError(ClusterUnavailableError):
    """``--scheduler`` is not an address Dask can connect to: a usage problem."""


def check_scheduler_address(scheduler: str) -> None:
    """Raise :class:`SchedulerAddressError` unless Dask can parse ``scheduler``: a known
    scheme (``tcp://`` when none is written) and, on the network ones, a host and a port
    1..65535. Dask's own parsers decide; a port out of range it would only time out on."""
    distributed = _import_distributed()
    from distributed.comm.addressing import parse_address, parse_host_port

    known = sorted(distributed.comm.registry.backends)
    try:
        scheme, location = parse_address(scheduler)
        if scheme not in known:
            raise ValueError(f"unknown scheme {scheme}://, known: {', '.join(known)}")
        if scheme != "inproc":
            _, port = parse_host_port(location)
            if not 0 < int(port) < 65536:
                raise ValueError(f"port {port} is not 1..65535")
    except (ValueError, TypeError) as exc:
        raise SchedulerAddressError(
            f"--scheduler {scheduler}: not a scheduler address ({exc}); expected "
            "tcp://HOST:PORT, as `dask scheduler` prints it (e.g. tcp://192.168.1.20:8786)"
        ) from None


def run_on_worker(spec: EpisodeSpec, wall_limit_s: float | None = None) -> EpisodeResult:
    """One episode on a Dask worker, within ``wall_limit_s`` (:func:`within_wall_limit`);
    the result names the worker."""
    from dataclasses import replace

    from distributed import get_worker

    result = run_episode(spec) if wall_limit_s is None else within_wall_limit(spec, wall_limit_s)
    with contextlib.suppress(ValueError):
        return replace(result, worker=get_worker().address)
    return result


def within_wall_limit(spec: EpisodeSpec, limit_s: float) -> EpisodeResult:
    """:func:`run_episode`, or its HUNG result when it is still running after ``limit_s``
    of wall-clock time. A Dask worker runs its tasks in threads, and a thread cannot be
    ended: :class:`~roomba_bt.runtime.wall_limit.WallLimit` raises ``WallLimitReached`` in
    it instead, so a loop in Python ends there, the robot's safe stop runs, and the worker
    goes on. A loop in C code never sees it, and one that catches BaseException swallows
    it: either holds its worker until it is restarted (a local pool, ``--engine local``,
    ends its worker process whatever it runs)."""
    try:
        with WallLimit(limit_s):
            return run_episode(spec)
    except WallLimitReached as exc:
        return hung_result(spec, limit_s, list(traceback.walk_tb(exc.__traceback__)))


def _import_distributed() -> Any:
    try:
        import distributed
    except ImportError as exc:
        needs = "the Dask engine needs the cluster extra: pip install 'roomba-bt[cluster]'"
        raise ClusterUnavailableError(optional_import_failure(exc, needs)) from None
    return distributed


#: Dask settings of the local cluster (``--engine dask``), read by its scheduler, nannies and
#: workers as they start. It has no dashboard, so nothing shows what these would collect:
#: each worker's statistical profiler samples the episode's thread every 10 ms, holding the
#: GIL (about 0.4 s of a worker's CPU in 48 dock episodes, taken from the episodes), and the
#: system monitor reads the disk counters twice a second. What stays is read less often, on
#: the two cores the workers need: the event-loop tick every 0.5 s, not 20 ms (a metric and
#: an INFO line about a blocked loop, which this cluster's logging drops; Dask's own test
#: clusters use 0.5 s), the memory monitors of nannies and workers every 1 s, not 0.1 s
#: (a runaway worker is still paused and restarted), the system monitor every 2 s, not 0.5 s.
#: Together the submitting process (scheduler, nannies, client) spent 0.43 s of CPU on 48
#: dock episodes with 2 workers where it spent 0.61 s with Dask's defaults
#: (docs/performance.md).
#: Its scheduler gives up on an episode at the first death of a worker holding it
#: (``allowed-failures`` 0, not 3): the episodes that worker held run again alone
#: (:func:`run_on_client`), which tells the one that killed it from those queued beside it;
#: with 3, an episode that kills its worker (``os._exit`` in a behaviour) cost 4 worker
#: restarts, 4 more alone, 8 to 26 s on the 2-core VM, and a restart that timed out on the
#: loaded machine left the cluster without a worker.
#: A cluster of one's own (``--scheduler``) keeps its own settings.
LOCAL_CLUSTER_CONFIG: dict[str, object] = {
    "distributed.scheduler.allowed-failures": 0,
    "distributed.worker.profile.enabled": False,
    "distributed.admin.system-monitor.disk": False,
    "distributed.admin.tick.interval": "500ms",
    "distributed.worker.memory.monitor-interval": "1s",
    "distributed.admin.system-monitor.interval": "2s",
}


#: How long a ``--scheduler`` has to answer before the evaluation gives up (exit code 3):
#: long enough for a scheduler across a slow network, short enough for a mistyped port that
#: nothing listens on (Dask's client retries a refused connection until then).
SCHEDULER_CONNECT_TIMEOUT_S = 10.0


@contextlib.contextmanager
def dask_client(
    scheduler: str | None = None, workers: int = 2, worker_wait_s: float | None = None
) -> Iterator[Any]:
    """A client of the scheduler at ``scheduler``, or of a local cluster of ``workers``
    single-threaded worker processes (closed on exit); Dask's own log lines and warnings
    meanwhile its detail (:func:`dask_logs_as_detail`). ``worker_wait_s``: how long the
    evaluation will wait for a worker (None: for ever), as said when a scheduler has none."""
    distributed = _import_distributed()
    with dask_logs_as_detail() as level:
        if scheduler is not None:
            check_scheduler_address(scheduler)
            with scheduler_client(scheduler) as client:
                say_when_no_worker(client, scheduler, worker_wait_s)
                yield client
            return
        with _local_cluster(distributed, workers, level) as client:
            yield client


@contextlib.contextmanager
def scheduler_client(scheduler: str, timeout: float | None = None) -> Iterator[Any]:
    """A client of the scheduler at ``scheduler`` on an event loop of this evaluation's own
    (:func:`_event_loop`, ended on exit with the client closed);
    :class:`SchedulerUnreachableError` if it cannot connect within ``timeout`` s, by default
    :data:`SCHEDULER_CONNECT_TIMEOUT_S` as it is at the call (a default of the constant itself
    was bound at import: a program or a test that set the constant later waited the 10 s all
    the same)."""
    if timeout is None:
        timeout = SCHEDULER_CONNECT_TIMEOUT_S
    distributed = _import_distributed()
    with _event_loop() as loop:
        try:
            client = distributed.Client(scheduler, loop=loop, timeout=timeout)
        except (OSError, TimeoutError) as exc:
            why = f"--scheduler {scheduler}: cannot connect ({exc})"
            raise SchedulerUnreachableError(why) from None
        with client:
            yield client


#: The name of the thread that runs a ``--scheduler`` client's event loop.
CLIENT_LOOP_THREAD = "roomba-bt Dask client loop"


@contextlib.contextmanager
def _event_loop() -> Iterator[Any]:
    """A Tornado IO loop running in a thread of its own (:data:`CLIENT_LOOP_THREAD`), for a
    client given it as its public ``loop``: ended on exit, whatever became of the client.
    A client that starts its own loop leaves it running once it is closed by anything but
    its ``close()``: a client whose scheduler was lost closes itself, one that could not
    connect is closed by its failed ``__init__``, and ``Client.close`` then returns at once.
    Each such evaluation left an "IO loop" thread and its event loop's two sockets for the
    rest of the process (tests/conftest.py's Leftovers found them after test_cluster.py);
    ending it took the client's private ``_loop_runner``. A loop given to the client is
    the caller's to end (Dask's ``LoopRunner`` neither starts nor stops a loop it did not
    make), so this one is ended here, through nothing but asyncio's and Tornado's own API."""
    import asyncio

    from tornado.ioloop import IOLoop

    running: list[tuple[Any, asyncio.Event]] = []
    ready = threading.Event()

    async def serve() -> None:
        stop = asyncio.Event()
        running.append((IOLoop.current(), stop))
        ready.set()
        await stop.wait()  # then asyncio.run cancels what the client left scheduled

    def run() -> None:
        try:
            asyncio.run(serve())
        finally:
            ready.set()  # also when it could not start: not waited on for ever

    thread = threading.Thread(target=run, name=CLIENT_LOOP_THREAD, daemon=True)
    thread.start()
    ready.wait()
    if not running:
        raise RuntimeError("the Dask client's event loop did not start")
    loop, stop = running[0]
    try:
        yield loop
    finally:
        loop.add_callback(stop.set)
        thread.join(LOOP_STOP_S)  # a daemon: one still ending does not hold the exit


#: How long the end of a client's event loop is waited for (s), as Dask's ``LoopRunner``
#: waits for its own: its tasks are cancelled in milliseconds.
LOOP_STOP_S = 10.0


@contextlib.contextmanager
def _local_cluster(distributed: Any, workers: int, log_level: int) -> Iterator[Any]:
    """A client of a local cluster of ``workers`` single-threaded worker processes, closed
    on exit (:func:`close_quietly`); its workers log from ``log_level`` on."""
    import dask

    with dask.config.set(LOCAL_CLUSTER_CONFIG):
        with _ctrl_c_left_to_this_process():
            cluster = distributed.LocalCluster(
                n_workers=workers,
                threads_per_worker=1,
                processes=True,
                dashboard_address=None,
                # the scheduler's HTTP server (health routes) would take port 8787 even with
                # no dashboard, and two evaluations at once would collide: any free port
                scheduler_kwargs={"dashboard": False, "dashboard_address": ":0"},
                silence_logs=log_level,  # each worker process's own Dask log lines
            )
        with cluster:
            client = distributed.Client(cluster)
            try:
                yield client
            finally:
                close_quietly(client, cluster)


#: The loggers Dask says what it does on: its own, and those of the libraries its comms run
#: on (Tornado's streams, asyncio's tasks).
DASK_LOGGERS = ("distributed", "tornado", "asyncio")

#: A level above every record's: a logger set to it says nothing.
SILENT = logging.CRITICAL + 1


def dask_log_level() -> int:
    """From which level Dask's own log lines are shown: its warnings and errors once this
    process's log shows DEBUG lines (``roomba-bt -v``), else none (:data:`SILENT`). What it
    logs as an evaluation goes (a task failed because its worker died, a nanny restarting a
    worker, a worker removed with the episodes it held) is Dask's detail of what roomba-bt
    says on stderr in its own words (a seed that killed its workers, the episodes run
    again); by default its lines came beside each of ours, a wall of its internals."""
    return logging.WARNING if logging.getLogger().isEnabledFor(logging.DEBUG) else SILENT


@contextlib.contextmanager
def dask_logs_as_detail() -> Iterator[int]:
    """Dask's loggers (:data:`DASK_LOGGERS`) at :func:`dask_log_level` (the level given to
    the body) and, when that is silent, the warnings Dask's code raises ignored; the levels
    and the warning filters as they were on exit."""
    level = dask_log_level()
    levels = set_dask_log_level(level)
    try:
        with warnings.catch_warnings():
            if level == SILENT:
                warnings.filterwarnings("ignore", module=r"(distributed|tornado)\b")
            yield level
    finally:
        restore_log_levels(levels)


#: How long the workers get to hear that the shutdown begins (s): one round trip each, then
#: the cluster is closed anyway.
SHUTDOWN_NOTICE_S = 5.0


def close_quietly(client: Any, cluster: Any) -> None:
    """Close a local cluster in order, without a word: first each worker's loggers are
    silenced and its copies of the missions removed (in the worker's process, by the client:
    :func:`_closing_worker`), then those of this process (its
    scheduler, nannies and client) until the end, then the client closes, then the
    cluster. A shutdown races Dask's own traffic (a worker's heartbeat meets the closed
    scheduler or its own closing connection pool), and Dask logs each such loss as an ERROR
    with its traceback: on a loaded machine one came under the summary of an evaluation,
    after a Ctrl-C or not. What the evaluation asked is done by then; its errors came back
    with the futures. So a worker that has not closed 4 s after its nanny asked (0.8 of
    ``Nanny.close``'s 5 s; a loaded machine) and is killed loses nothing: its plugins'
    teardown and its atexit handlers do not run (its copies of the missions are removed
    before: they were left in the temporary folder), the nanny's warning is silenced, and
    Dask purges the worker's directory lock the next time a cluster starts."""
    levels = set_dask_log_level()
    try:
        with contextlib.suppress(Exception):  # a worker that does not answer is ended anyway
            client.run(_closing_worker, on_error="ignore",
                       callback_timeout=SHUTDOWN_NOTICE_S)  # fmt: skip
        client.close()
        cluster.close()
    finally:
        restore_log_levels(levels)


def _closing_worker() -> None:
    """Runs on each worker of a local cluster as it closes: its Dask loggers silenced, its
    copies of the missions removed (it runs no more episodes)."""
    set_dask_log_level()
    remove_copies()


def set_dask_log_level(level: int = SILENT) -> dict[str, int]:
    """Every logger of :data:`DASK_LOGGERS` and each of their children (some have a level of
    their own from Dask's configuration) set to ``level``: the levels before."""
    manager = logging.Logger.manager
    names = [
        name for name in [*DASK_LOGGERS, *manager.loggerDict] if name.split(".")[0] in DASK_LOGGERS
    ]
    levels = {}
    for name in dict.fromkeys(names):
        logger = logging.getLogger(name)
        levels[name] = logger.level
        logger.setLevel(level)
    return levels


def restore_log_levels(levels: dict[str, int]) -> None:
    """Each logger named in ``levels`` set back to its level there."""
    for name, level in levels.items():
        logging.getLogger(name).setLevel(level)


#: How long an evaluation waits for a worker of a ``--scheduler`` cluster before saying so.
NO_WORKER_AFTER_S = 5.0


def say_when_no_worker(
    client: Any, scheduler: str, worker_wait_s: float | None = None,
    after_s: float = NO_WORKER_AFTER_S,
) -> None:  # fmt: skip
    """A scheduler with no worker takes the futures and waits for one: after ``after_s``
    without a worker, say so on stderr (once; the evaluation goes on waiting, up to
    ``worker_wait_s`` with none (None: for ever, :class:`WorkerWatch`), Ctrl-C ends it). A
    scheduler that answers about nothing else is left to the futures."""
    with contextlib.suppress(TimeoutError):
        client.wait_for_workers(1, timeout=after_s)
        return
    with contextlib.suppress(Exception):
        workers = len(client.scheduler_info().get("workers", {}))
        if workers:  # one joined as the wait ended
            return
    up_to = "" if worker_wait_s is None else f" up to {worker_wait_s:g} s (--worker-wait)"
    say(
        f"roomba-bt eval: the cluster at {scheduler} has 0 workers; waiting{up_to} for one "
        f"(start `dask worker {scheduler} --nthreads 1` on a machine; Ctrl-C to stop)..."
    )


class ClusterLostError(RuntimeError):
    """The cluster can run no more of the evaluation's episodes: it stopped. ``why``, the
    cluster's failure in words; ``cause``, the same as a word for scripts
    (:class:`~roomba_bt.evaluate.parallel.Interruption`); ``results``: in spec order, None
    where an episode did not finish; ``retried``: as :func:`run_on_client` counts them."""

    cause = ""

    def __init__(self, why: str, results: list[EpisodeResult | None], retried: int) -> None:
        done = sum(r is not None for r in results)
        super().__init__(f"{why}; stopped with {done} of {len(results)} episode(s) finished")
        self.why = why
        self.results = results
        self.retried = retried


class NoWorkersError(ClusterLostError):
    """The cluster had no worker for the evaluation's ``worker_wait_s`` (its workers gone
    for good, or never there)."""

    cause = NO_WORKERS


class SchedulerLostError(ClusterLostError):
    """The scheduler was lost mid-evaluation (it died, its machine or the network went
    down: Dask's client cancels every future it had), or cancelled the episodes itself
    (restarted by another client of a shared cluster). Its episodes that had not come back
    are lost with it; the evaluation ended as if every episode had run, exit 0, its summary
    over those that had (``20/20`` of 400)."""

    cause = SCHEDULER_LOST


#: The reason Dask's client gives the futures it cancels when its scheduler's connection closes
CONNECTION_LOST = "scheduler-connection-lost"


def scheduler_lost(address: str, cancelled_because: str, unfinished: int) -> str:
    """Why ``unfinished`` episodes never came back, the scheduler at ``address`` having
    cancelled them (``cancelled_because``: Dask's reason, :data:`CONNECTION_LOST` when its
    connection closed), in words."""
    if cancelled_because == CONNECTION_LOST:
        return (
            f"the connection to the Dask scheduler at {address} was lost (the scheduler "
            f"ended, or its machine or the network went down): the {unfinished} episode(s) "
            "not finished were lost with it"
        )
    return (
        f"the Dask scheduler at {address} cancelled {unfinished} episode(s) "
        f"({cancelled_because or 'no reason given'}: restarted by another client?)"
    )


def _scheduler_address(client: Any) -> str:
    return getattr(client.scheduler, "address", None) or "its scheduler"


#: The longest a :class:`WorkerWatch` goes between two questions to the scheduler (s).
WORKER_POLL_S = 1.0


class WorkerWatch:
    """Whether the cluster has a worker, asked in a thread of its own every second (a
    scheduler that does not answer has none): after ``limit_s`` with none, the futures given
    to :meth:`guard` are cancelled, so that the evaluation's wait for them ends, and
    :attr:`expired` says why. Dask's scheduler holds the futures of a cluster without
    workers for ever (its ``no-workers-timeout`` is off by default, and a cluster of one's
    own keeps its settings); a local cluster whose nanny could not start a worker again was
    one such. ``limit_s`` None: no limit.

    It also ends the gathering (:meth:`gathering`) once the client has closed, having
    failed to reconnect to a scheduler that was lost: a result Dask was fetching when its
    scheduler died never completes its ``as_completed``, which then waited for ever. What
    it last heard of the cluster's worker threads (:attr:`threads`) says how many episodes
    :class:`_Submitted` keeps on it."""

    def __init__(self, client: Any, limit_s: float | None) -> None:
        self.client = client
        self.limit_s = limit_s
        self.expired = ""
        #: the cluster's worker threads, as last heard (0: none, or no answer)
        self.threads = 0
        self._guarded: list[Any] = []
        self._completing: Any = None
        #: the client has closed: it lost its scheduler and could not reconnect
        self.closed = False
        self._lock = threading.Lock()
        self._done = threading.Event()
        self._thread = threading.Thread(target=self._watch, name="roomba-bt worker watch",
                                        daemon=True)  # fmt: skip

    def __enter__(self) -> WorkerWatch:
        self.threads = self._threads()
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._done.set()
        if self._thread.is_alive():
            self._thread.join()

    def guard(self, futures: Iterable[Any]) -> None:
        """Cancel ``futures`` too if the watch expires (at once if it has); those guarded
        before that are done are let go."""
        with self._lock:
            self._guarded = [f for f in self._guarded if not f.done()]
            self._guarded.extend(futures)
            if self.expired:
                self.client.cancel(self._guarded)

    def gathering(self, completing: Any) -> None:
        """``completing`` (Dask's ``as_completed``) ended if the client closes: what came
        back before is in by then (a closed client gets nothing more), so nothing is lost;
        at once if it has closed."""
        with self._lock:
            self._completing = completing
            if self.closed:
                completing.clear()

    def _end_the_gathering_if_closed(self) -> bool:
        if getattr(self.client, "status", "running") != "closed":
            return False
        with self._lock:
            self.closed = True
            if self._completing is not None:
                self._completing.clear()
        return True

    def _threads(self) -> int:
        with contextlib.suppress(Exception):  # no answer: no worker the evaluation can use
            return sum(self.client.nthreads().values())
        return 0

    def _watch(self) -> None:
        seen = time.monotonic()
        poll = WORKER_POLL_S if self.limit_s is None else min(WORKER_POLL_S, self.limit_s / 4)
        while not self._done.wait(poll):
            now = time.monotonic()
            if self._end_the_gathering_if_closed():
                return
            self.threads = self._threads()
            if self.limit_s is None or self.threads:
                seen = now
            elif now - seen >= self.limit_s:
                address = _scheduler_address(self.client)
                with self._lock:
                    self.expired = (
                        f"the Dask cluster at {address} has had no worker for {now - seen:.0f} "
                        f"s (--worker-wait {self.limit_s:g} s): its workers are gone"
                    )
                    with contextlib.suppress(Exception):
                        self.client.cancel(self._guarded)
                return


@contextlib.contextmanager
def _ctrl_c_left_to_this_process() -> Iterator[None]:
    """The local cluster's processes start with Ctrl-C ignored (a started Python keeps an
    ignored SIGINT ignored, and asyncio then leaves it so): a terminal's Ctrl-C reaches the
    whole process group, and every nanny and worker printed its KeyboardInterrupt traceback
    under the summary. This process takes it and closes the cluster.

    A worker that dies is started again by its nanny later, from the cluster's threads in
    this process, once Ctrl-C is this process's again: it started with Ctrl-C live, and a
    Ctrl-C during its start-up's imports or its run printed a traceback. So Ctrl-C is also
    blocked here, in this thread's signal mask, while the cluster starts: its event-loop
    thread, made now, and every thread that one starts (those that start the nannies'
    worker processes) keep that mask for good, a process started from them keeps it through
    ``exec``, and Python never unblocks it. This thread's own mask is given back, so Ctrl-C
    reaches this process as before. Dask's other way, its workers started from a fork
    server that ignores Ctrl-C (``distributed.worker.multiprocessing-method: forkserver``),
    changes how every worker starts (docs/evaluation.md); this one changes nothing else."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    mask = getattr(signal, "pthread_sigmask", None)  # POSIX; Windows sends no Ctrl-C to a group
    if mask is not None:
        # multiprocessing's resource tracker unblocks Ctrl-C in the thread that starts it
        # (the first queue of a spawned process does): started now, before the block
        from multiprocessing import resource_tracker

        resource_tracker.ensure_running()
    held = mask(signal.SIG_BLOCK, {signal.SIGINT}) if mask is not None else None
    try:
        yield
    finally:
        if mask is not None and held is not None:
            mask(signal.SIG_SETMASK, held)
        signal.signal(signal.SIGINT, previous)


#: Gathered results are released in batches of this many, each after reading how many of
#: them were run again (one scheduler round trip per batch).
RELEASE_EVERY = 16


def run_on_client(
    client: Any,
    specs: Sequence[EpisodeSpec],
    progress: Callable[[int, int, EpisodeResult], None] | None = None,
    wall_limit_s: float | None = None,
    worker_wait_s: float | None = None,
) -> tuple[list[EpisodeResult | None], int, KeyboardInterrupt | None]:
    """``(results in spec order (None where cancelled), episodes retried, the Ctrl-C or
    signal that interrupted it (None: none did))``; each episode within ``wall_limit_s``
    (:func:`within_wall_limit`). The cluster lost stops it, with what finished: no worker
    for ``worker_wait_s`` (:class:`WorkerWatch`, :class:`NoWorkersError`; None: waited for
    ever), the scheduler gone or cancelling episodes itself (:class:`SchedulerLostError`).

    Each result is released once gathered (in batches of :data:`RELEASE_EVERY`, after the
    scheduler says which of them a dead worker held): futures kept to the end made the
    scheduler compute again what a dead worker had finished, and the count missed those.
    An episode Dask gave up on (its workers kept dying) runs again alone once the others
    are done (:func:`_alone`): DIED if it kills its workers again; it ended the evaluation.

    A few episodes per worker thread are on the cluster at a time (:class:`_Submitted`),
    the next sent as each result comes: every one sent at once held 1.4 GB in this process
    at 100 000 episodes (its futures, the scheduler's tasks, the specs with their missions'
    texts), and the local cluster's scheduler, busy with them, was taken for lost before
    the first result."""
    total = len(specs)
    address = _scheduler_address(client)  # a client that lost its scheduler forgets it
    finished = _Finished([None] * total, progress)
    results = finished.results
    gathered = _Gathered()
    interrupt: KeyboardInterrupt | None = None

    with WorkerWatch(client, worker_wait_s) as watch:
        sent = _Submitted(client, watch, specs, wall_limit_s)
        try:
            given_up = _gather(client, watch, specs, sent, gathered, finished)
            for i, first in sorted(given_up.items()):
                if gathered.cancelled_because:  # the scheduler is gone: nothing runs alone
                    break
                key = f"{sent.key(i)}-alone"
                finished(i, _alone(client, watch, sent.bundled(specs[i]), wall_limit_s, key,
                                   first, gathered, seeds_said(specs, [i])))  # fmt: skip
        except KeyboardInterrupt as exc:
            interrupt = exc
            client.cancel([f for f in sent.pending.values() if not f.done()])
    gathered.rerun += _release_noting_reruns(
        client, [*gathered.futures, *sent.pending.values()], gathered.asks_scheduler
    )
    retried = _say_reruns(specs, gathered.rerun)
    if watch.expired:
        raise NoWorkersError(watch.expired, results, retried)
    unfinished = sum(r is None for r in results)
    if unfinished and interrupt is None:  # cancelled, not by us: the summary would say 20/20
        because = gathered.cancelled_because or (CONNECTION_LOST if watch.closed else "")
        why = scheduler_lost(address, because, unfinished)
        raise SchedulerLostError(why, results, retried)
    return results, retried, interrupt


@dataclass
class _Finished:
    """The results of a run on Dask by spec index (None: not finished, or cancelled), each
    one told to ``progress`` as it comes with how many have finished, counted as they come:
    the count was taken again over every result after each (``sum(...)`` over the list: at
    100 000 episodes, 5 billion looks in the submitting process)."""

    results: list[EpisodeResult | None]
    progress: Callable[[int, int, EpisodeResult], None] | None
    done: int = 0

    def __call__(self, i: int, result: EpisodeResult | None) -> None:
        if result is None:  # cancelled: the watch found no worker for it, or the scheduler
            return
        self.done += self.results[i] is None
        self.results[i] = result
        if self.progress is not None:
            self.progress(self.done, len(self.results), result)


#: How many episodes are on the cluster at a time per worker thread (and with no worker
#: yet, as for one): enough that a worker finds its next one queued when it ends one,
#: whatever the round trip of its result and the next submission.
IN_FLIGHT_PER_THREAD = 4


class _Submitted:
    """The episodes on the cluster, sent a window at a time: each a future of
    :func:`run_on_worker` on its spec made :func:`~roomba_bt.evaluate.episode.self_contained`
    as it is sent, keyed ``episode-BATCH-i`` (``i``: its spec's index, :func:`_index_of`),
    at most :data:`IN_FLIGHT_PER_THREAD` per worker thread of the cluster
    (:attr:`WorkerWatch.threads`) pending; each guarded by ``watch``."""

    def __init__(
        self, client: Any, watch: WorkerWatch, specs: Sequence[EpisodeSpec],
        wall_limit_s: float | None,
    ) -> None:  # fmt: skip
        self.client = client
        self.watch = watch
        self.specs = specs
        self.wall_limit_s = wall_limit_s
        self.batch = uuid.uuid4().hex[:12]  # keys unique on a cluster shared by many
        self.bundled = Bundles()
        self.pending: dict[str, Any] = {}
        self.sent = 0

    def key(self, index: int) -> str:
        return f"episode-{self.batch}-{index}"

    def more(self, completing: Any) -> None:
        """The next episodes sent, and added to ``completing`` (Dask's ``as_completed``),
        until the window is full or every one is sent; once half of it has come back, not
        at each result: each submission is a message to the scheduler, and half a window
        at a time sends fewer while each worker still has the next one queued."""
        window = IN_FLIGHT_PER_THREAD * max(1, self.watch.threads)
        if self.sent and len(self.pending) > window // 2:
            return
        new = []
        while len(self.pending) < window and self.sent < len(self.specs):
            i, key = self.sent, self.key(self.sent)
            future = self.client.submit(run_on_worker, self.bundled(self.specs[i]),
                                        self.wall_limit_s, key=key, pure=False)  # fmt: skip
            self.pending[key] = future
            new.append(future)
            self.sent += 1
        self.watch.guard(new)
        for future in new:
            completing.add(future)


def _index_of(key: str) -> int:
    """The spec index of the episode keyed ``episode-BATCH-i`` (or ``...-i-alone``)."""
    return int(key.split("-")[2])


@dataclass
class _Gathered:
    """The futures gathered and not released yet, the episodes retried among those released
    (:func:`_release_noting_reruns`), and why the scheduler cancelled an episode when it did
    (Dask's reason: :data:`CONNECTION_LOST` when the scheduler was lost; "" when none was
    cancelled, or only by the evaluation's own :class:`WorkerWatch`, which gives none)."""

    futures: list[Any] = field(default_factory=list)
    #: the keys of the released futures a dead worker held (their episodes ran again)
    rerun: list[str] = field(default_factory=list)
    cancelled_because: str = ""

    def cancelled(self, error: BaseException) -> None:
        """A future cancelled with ``error`` (Dask's ``FutureCancelledError``): its reason
        kept, the first one given."""
        reason = getattr(error, "reason", None)
        if reason and reason != "unknown" and not self.cancelled_because:
            self.cancelled_because = str(reason)

    @property
    def asks_scheduler(self) -> bool:
        """Whether the scheduler can be asked anything: a lost one would be waited for
        (Dask's client tries to reconnect for 10 s) before each question failed."""
        return self.cancelled_because != CONNECTION_LOST


def _gather(
    client: Any,
    watch: WorkerWatch,
    specs: Sequence[EpisodeSpec],
    sent: _Submitted,
    gathered: _Gathered,
    finished: Callable[[int, EpisodeResult], None],
) -> dict[int, BaseException]:
    """Each episode sent (``sent``, by key ``...-i`` for ``specs[i]``) as it completes, its
    result to ``finished``, gathered on the client's event loop (not one blocking round
    trip from this thread each), the next episodes sent in its place; each moved from
    ``sent.pending`` to ``gathered`` and released there in batches of
    :data:`RELEASE_EVERY`. A cancelled one (a :class:`WorkerWatch` found no worker, the
    scheduler was lost) has no result: why is noted (:meth:`_Gathered.cancelled`), and no
    more are sent; ``watch`` ends the gathering if the client closes
    (:meth:`WorkerWatch.gathering`). The episodes Dask gave up on, by spec index: their
    errors (:func:`_killed_worker`)."""
    distributed = _import_distributed()
    given_up: dict[int, BaseException] = {}
    completing = distributed.as_completed(with_results=True, raise_errors=False)
    watch.gathering(completing)
    sent.more(completing)
    cancelled = False
    for future, result in completing:
        status = future.status  # before the release below, which marks it cancelled
        gathered.futures.append(sent.pending.pop(future.key))
        if len(gathered.futures) >= RELEASE_EVERY:
            gathered.rerun += _release_noting_reruns(client, gathered.futures,
                                                     gathered.asks_scheduler)  # fmt: skip
        i = _index_of(future.key)
        if status == "error":  # (type, exception, traceback)
            given_up[i] = _killed_worker(specs[i], result[1], seeds_said(specs, [i]))
        elif status == "cancelled":  # its result is Dask's FutureCancelledError
            gathered.cancelled(result)
            cancelled = True
        else:
            finished(i, result)
        if not (cancelled or watch.expired or watch.closed):
            sent.more(completing)
    return given_up


def _killed_worker(spec: EpisodeSpec, error: BaseException, said: str = "") -> BaseException:
    """``error``, Dask's ``KilledWorker`` (each worker that held the episode died, more than
    the scheduler's ``allowed-failures``), said on stderr. A worker runs the episodes queued
    on it one after the other, and they all count each death: the one that killed it is
    not told from the others by this alone. Any other error of a future is roomba-bt's own
    (an episode's errors are in its result): raised again."""
    from distributed.scheduler import KilledWorker

    if not isinstance(error, KilledWorker):
        raise error
    say(f"roomba-bt eval: seed {said or spec.seed}: {error.allowed_failures + 1} Dask "
        "worker(s) died running it or with it queued: it runs again alone once the others "
        "are done")  # fmt: skip
    return error


def _alone(
    client: Any, watch: WorkerWatch, spec: EpisodeSpec, wall_limit_s: float | None, key: str,
    first: BaseException, gathered: _Gathered, said: str = "",
) -> EpisodeResult | None:  # fmt: skip
    """The episode Dask gave up on (``first``, its ``KilledWorker``) run again with no other
    episode of the evaluation beside it: its result, or DIED when its workers die again
    (:func:`died_on_workers`), said on stderr (its seed as ``said``, with its variant in
    an A/B: :func:`~roomba_bt.evaluate.parallel.seeds_said`); None when it was cancelled
    (``watch`` found no worker for it, the scheduler was lost: noted in ``gathered``)."""
    from concurrent.futures import CancelledError

    from distributed.scheduler import KilledWorker

    future = client.submit(run_on_worker, spec, wall_limit_s, key=key, pure=False)
    watch.guard([future])
    try:
        result: EpisodeResult = future.result()
    except KilledWorker as again:
        return died_on_workers(spec, first, again, said)
    except CancelledError as cancelled:
        gathered.cancelled(cancelled)
        return None
    finally:
        if not future.done():  # Ctrl-C
            client.cancel([future])
        future.release()
    say(f"roomba-bt eval: seed {said or spec.seed} ran alone without a death (it was "
        "queued on a "
        "dying worker)")  # fmt: skip
    return result


def died_on_workers(
    spec: EpisodeSpec, first: BaseException, again: BaseException, said: str = ""
) -> EpisodeResult:
    """The DIED record of an episode whose Dask workers kept dying (``first``, Dask's
    ``KilledWorker`` among the others) and again when it ran alone (``again``): a behaviour
    calling ``os._exit``, a crash in C code; how many died, the last worker, said on stderr."""
    allowed = int(getattr(again, "allowed_failures", 0))
    last = str(getattr(getattr(again, "last_worker", None), "address", "") or "unknown")
    how = (f"{int(getattr(first, 'allowed_failures', 0)) + 1} Dask worker(s) died running it, "
           f"{allowed + 1} more when it ran alone, the last {last} (the scheduler's "
           f"distributed.scheduler.allowed-failures is {allowed})")  # fmt: skip
    say(f"roomba-bt eval: seed {said or spec.seed} killed its workers again, alone: recorded "
        "as DIED")  # fmt: skip
    return died_result(spec, how, worker=last)


def _release_noting_reruns(client: Any, futures: list[Any], ask: bool = True) -> list[str]:
    """The keys of ``futures`` a dead worker held (read from the scheduler; none unless
    ``ask``: a scheduler known lost is not asked), then each released (``futures``
    emptied): the scheduler forgets them."""
    rerun: list[str] = []
    with contextlib.suppress(Exception):  # the count is a report, never a reason to fail
        if ask:
            rerun = list(client.run_on_scheduler(_retried, keys=[f.key for f in futures]))
    for future in futures:
        future.release()
    futures.clear()
    return rerun


def _say_reruns(specs: Sequence[EpisodeSpec], keys: list[str]) -> int:
    """How many episodes (keyed ``keys``) ran again after a worker holding them was lost,
    their seeds said on stderr, as the local pool says its own: whatever ``--reproducible``
    leaves out of stdout, a lost worker leaves this trace."""
    if keys:
        say(f"roomba-bt eval: {len(keys)} episode(s) ran again after a Dask worker holding "
            f"them was lost: seeds {_seeds_of(specs, keys)}")  # fmt: skip
    return len(keys)


def _seeds_of(specs: Sequence[EpisodeSpec], keys: list[str], shown: int = 10) -> str:
    """The seeds of the episodes keyed ``episode-BATCH-i`` (or ``...-i-alone``), the first
    ``shown`` of them, in order, each with its variant in an A/B (:func:`seeds_said`: they
    read ``75, 75``, one seed for two episodes)."""
    return seeds_said(specs, sorted({_index_of(key) for key in keys}), shown)


def warm_up(client: Any) -> None:
    """Import the episode's modules on every worker (what a worker's first episode would
    otherwise pay), so timings measure episodes."""
    client.run(_import_episode_modules)


def _import_episode_modules() -> None:
    import roomba_bt.evaluate.episode
    import roomba_bt.mission  # noqa: F401


def _retried(dask_scheduler: Any, keys: list[str]) -> list[str]:
    """Runs on the scheduler: those of ``keys`` held by a worker that died."""
    tasks = dask_scheduler.tasks
    return [k for k in keys if k in tasks and tasks[k].suspicious > 0]
