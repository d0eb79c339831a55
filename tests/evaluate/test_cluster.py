"""Episodes on Dask: a LocalCluster of worker processes, and a scheduler and workers started as
separate processes on 127.0.0.1 (`dask scheduler`, `dask worker`), give the same results,
episode by episode, as ``--jobs 1``; a worker killed mid-evaluation loses no episode.

What it costs: a local cluster or a scheduler with its workers is several processes, each
importing Dask (seconds of CPU on a loaded 2-core machine), so the tests that only submit
episodes and gather them share one local cluster (:class:`TestOnOneLocalCluster`); a test
that kills a worker or a scheduler, or checks how a cluster starts or closes, has its own,
with as few workers as what it checks needs."""

from __future__ import annotations

import contextlib
import dataclasses
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import Any

import pytest
from quoted import assert_quoted  # tests/quoted.py: the docs' quoted lines
from waits import HANG_S  # tests/waits.py: a hang's bound

from roomba_bt.evaluate import EpisodeResult, cluster, episode_specs, run_episodes
from roomba_bt.evaluate.cluster import dask_client, dask_logs_as_detail, run_on_client
from roomba_bt.evaluate.parallel import Engine, evaluate

MISSIONS = Path(__file__).resolve().parents[2] / "missions"
SPECS = episode_specs(str(MISSIONS / "dock.yaml"), world="empty-room", runs=8, seed=11,
                      within_m=1.5)  # fmt: skip
DASK = str(Path(sys.executable).parent / "dask")
#: every test here runs episodes on Dask, or reads what roomba-bt says of a cluster after
#: Dask is imported
pytestmark = [
    pytest.mark.extra("cluster"),
]


def _episodes(results: list[EpisodeResult]) -> list[EpisodeResult]:
    """The episode itself: without where and how long it ran."""
    return [dataclasses.replace(r, wall_s=0.0, worker="") for r in results]


@pytest.fixture(scope="module")
def one_job() -> list[EpisodeResult]:
    return _episodes(run_episodes(SPECS, jobs=1))


def test_a_local_dask_cluster_gives_the_results_of_one_job(
    one_job: list[EpisodeResult],
) -> None:
    (done,) = evaluate([SPECS], Engine("dask", jobs=2))
    assert not done.interrupted and done.retried == 0
    assert _episodes(done.results) == one_job
    assert len({r.worker for r in done.results}) == 2, "both workers ran episodes"


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


#: the scheduler's address, its workers' processes and its own
Separate = tuple[str, list[subprocess.Popen[bytes]], subprocess.Popen[bytes]]


@pytest.fixture
def scheduler(tmp_path: Path) -> Iterator[Callable[[int], Separate]]:
    """Starts a scheduler and ``workers`` single-threaded workers without nannies (a killed
    worker stays dead), each its own process, run from another folder (no shared files with
    the test); all killed at the end. As many workers as the test needs: each is a process
    importing Dask and roomba-bt, seconds of CPU on a loaded 2-core machine."""
    processes: list[subprocess.Popen[bytes]] = []
    log = open(tmp_path / "dask.log", "wb")  # noqa: SIM115 (closed below)

    def start(workers: int) -> Separate:
        port = _free_port()
        address = f"tcp://127.0.0.1:{port}"
        own = subprocess.Popen([DASK, "scheduler", "--host", "127.0.0.1", "--port", str(port),
                                "--no-dashboard"], cwd=tmp_path,
                               stdout=log, stderr=log)  # fmt: skip
        processes.append(own)
        started = [
            subprocess.Popen([DASK, "worker", address, "--nthreads", "1", "--no-nanny",
                              "--no-dashboard", "--host", "127.0.0.1"], cwd=tmp_path,
                             stdout=log, stderr=log)
            for _ in range(workers)
        ]  # fmt: skip
        processes.extend(started)
        return address, started, own

    try:
        yield start
    finally:
        for p in processes:
            p.kill()
        for p in processes:
            p.wait(timeout=HANG_S)
        log.close()


@contextlib.contextmanager
def _connected_when_ready(address: str) -> Iterator[Any]:
    """A client of the scheduler at ``address`` once it takes one (it is starting)."""
    deadline = time.monotonic() + HANG_S
    with contextlib.ExitStack() as stack:
        while True:
            try:
                client = stack.enter_context(cluster.scheduler_client(address, timeout=2.0))
                break
            except cluster.SchedulerUnreachableError:
                if time.monotonic() > deadline:
                    raise
                time.sleep(0.2)
        yield client


def test_separate_scheduler_and_workers_give_the_results_of_one_job_even_if_one_dies(
    one_job: list[EpisodeResult],
    scheduler: Callable[[int], Separate],
    capsys: pytest.CaptureFixture[str],
) -> None:
    """Two workers: one killed after the first episode, the other runs what it held."""
    address, workers, _ = scheduler(2)
    with _connected_when_ready(address) as client:
        client.wait_for_workers(2, timeout=HANG_S)
    (done,) = evaluate([SPECS], Engine("dask", scheduler=address))
    assert _episodes(done.results) == one_job
    assert done.retried == 0

    reported: list[int] = []

    def kill_a_worker_after_the_first(done: int, total: int, result: EpisodeResult) -> None:
        reported.append(result.seed)
        if done == 1:
            workers[0].kill()

    with dask_client(address) as client:
        results, retried, interrupted = run_on_client(client, SPECS, kill_a_worker_after_the_first)
    assert workers[0].wait(timeout=HANG_S) != 0, "the worker was killed"
    assert not interrupted
    assert sorted(reported) == [s.seed for s in SPECS], "every episode reported once"
    assert all(r is not None for r in results)
    assert _episodes([r for r in results if r is not None]) == one_job
    assert retried >= 1, "the killed worker's episode ran again elsewhere"
    # which ones, on stderr whatever --reproducible leaves out of stdout (it said nothing)
    said = f"roomba-bt eval: {retried} episode(s) ran again after a Dask worker holding them"
    assert said in capsys.readouterr().err


def test_the_seeds_run_again_are_named_from_their_keys(capsys: pytest.CaptureFixture[str]) -> None:
    """The scheduler names the futures a dead worker held by key; the seeds are their
    episodes', each once, in order, the first ten said; the line docs/evaluation.md quotes
    (of seeds 17 and 18) says them."""
    specs = [dataclasses.replace(SPECS[0], seed=seed) for seed in range(100, 112)]
    keys = [f"episode-0a1b2c-{i}" for i in (3, 1, 11, 0, 2, 4, 5, 6, 7, 8, 9, 10)]
    assert cluster._seeds_of(specs, [*keys[:2], "episode-0a1b2c-3-alone"]) == "101, 103"
    assert cluster._seeds_of(specs, keys) == (
        "100, 101, 102, 103, 104, 105, 106, 107, 108, 109 and 2 more"
    )
    # an A/B: seed 100 of each variant, each said with its variant (it read "100" once)
    ab = [specs[0], dataclasses.replace(specs[0], params=(("turn_speed", "90mm/s"),))]
    assert cluster._seeds_of(ab, ["episode-0a1b2c-1", "episode-0a1b2c-0"]) == (
        f"100 ({SPECS[0].mission}), 100 ({SPECS[0].mission} -p turn_speed=90mm/s)"
    )
    assert cluster._say_reruns(specs, keys[:2]) == 2
    err = capsys.readouterr().err
    assert_quoted("docs/evaluation.md", "roomba-bt eval: 2 episode(s) ran again", err, numbers=True)


#: ``roomba-bt`` whose Dask client gives a lost scheduler 5 s to come back, not the user's
#: 10 s (``SCHEDULER_CONNECT_TIMEOUT_S``, also its connect's bound: still generous for a
#: scheduler the test has just reached itself): what a test of a lost scheduler checks comes
#: after the client gave up, and the other 5 s were the suite's longest idle wait. The
#: constant is read when ``scheduler_client`` is called, so setting it before is enough
#: (:func:`test_the_connect_timeout_is_read_when_a_client_is_made`).
ROOMBA_BT_RECONNECTING_5_S = [
    sys.executable, "-c",
    "import sys; from roomba_bt.evaluate import cluster; "
    "cluster.SCHEDULER_CONNECT_TIMEOUT_S = 5.0; "
    "from roomba_bt.cli import main; sys.exit(main())",
]  # fmt: skip


def _evaluation_under_way(
    child: Callable[[Sequence[str]], subprocess.Popen[str]], address: str, out: Path,
    *options: str, roomba_bt: Sequence[str] = (sys.executable, "-m", "roomba_bt"),
    workers: int = 1,
) -> subprocess.Popen[str]:  # fmt: skip
    """``roomba-bt eval`` (run as ``roomba_bt``) of 400 dock episodes on the cluster at
    ``address`` once its ``workers`` have joined, writing ``out``, once its first episode is
    in the partial file (another process's file: polled)."""
    with _connected_when_ready(address) as client:
        client.wait_for_workers(workers, timeout=HANG_S)
    evaluation = child(
        [*roomba_bt, "eval", str(MISSIONS / "dock.yaml"), "--runs", "400", "--within", "1.5",
         "--no-progress", "--scheduler", address, "--out", str(out), *options]
    )  # fmt: skip
    partial = Path(f"{out}.partial.jsonl")
    deadline = time.monotonic() + HANG_S
    while not (partial.exists() and partial.read_text().strip()):
        assert evaluation.poll() is None and time.monotonic() < deadline
        time.sleep(0.05)  # another process's file: no event to wait on
    return evaluation


def test_a_cluster_whose_workers_are_gone_for_good_stops_after_worker_wait_with_exit_3(
    tmp_path: Path,
    scheduler: Callable[[int], Separate],
    child: Callable[[Sequence[str]], subprocess.Popen[str]],
) -> None:
    """Every worker killed mid-evaluation (no nanny starts them again): the scheduler held the
    episodes and the evaluation waited for ever. Now, after --worker-wait with no worker, it
    stops: exit 3 (the cluster's failure, not the missions'), why on stderr, and the episodes
    that finished summarised and written to --out. One worker: every worker is all of it."""
    from roomba_bt.evaluate.records import read_results

    address, workers, _ = scheduler(1)
    out = tmp_path / "out.jsonl"
    evaluation = _evaluation_under_way(child, address, out, "--worker-wait", "2s")
    for worker in workers:
        worker.kill()
    stdout, stderr = evaluation.communicate(timeout=HANG_S)
    assert evaluation.returncode == 3, stderr
    assert f"the Dask cluster at {address} has had no worker for " in stderr
    records = read_results(out)
    assert 1 <= len(records) < 400
    assert (
        f"(--worker-wait 2 s): its workers are gone; {len(records)} of 400 episode(s) "
        "finished, summarised above"
    ) in stderr
    assert "Traceback" not in stderr
    assert f"/{len(records)} = " in stdout  # the summary of those that finished
    assert f"interrupted  the Dask cluster at {address} has had no worker for " in stdout


def test_a_scheduler_lost_mid_evaluation_stops_it_with_exit_3_and_what_finished(
    tmp_path: Path,
    scheduler: Callable[[int], Separate],
    child: Callable[[Sequence[str]], subprocess.Popen[str]],
) -> None:
    """The scheduler killed mid-evaluation: Dask's client cancels every future it held, and
    the evaluation took the cancelled episodes for none to run: it ended exit 0, ``success
    18/18`` of 400 episodes, not a word of the others. Now it stops: exit 3 (the cluster's
    failure, as an unreachable --scheduler), why in the summary (``interrupted_by``:
    ``scheduler-lost``) and on stderr, and the episodes that finished, those the partial
    file held, summarised and written to --out. One worker: it is the scheduler that goes."""
    import json

    from roomba_bt.evaluate.records import read_results

    address, _, scheduler_process = scheduler(1)
    out = tmp_path / "out.jsonl"
    evaluation = _evaluation_under_way(
        child, address, out, "--json", roomba_bt=ROOMBA_BT_RECONNECTING_5_S
    )
    scheduler_process.kill()
    stdout, stderr = evaluation.communicate(timeout=HANG_S)
    assert evaluation.returncode == 3, stderr
    report = json.loads(stdout)
    lost = f"the connection to the Dask scheduler at {address} was lost"
    assert (report["interrupted"], report["interrupted_by"]) == (True, "scheduler-lost")
    assert report["interruption"].startswith(lost)
    records = read_results(out)
    (variant,) = report["variants"]
    assert 1 <= len(records) == variant["runs"] < 400
    assert sorted(r.seed for r in records) == [r.seed for r in records]
    assert f"{lost} " in stderr
    assert f"; {len(records)} of 400 episode(s) finished, summarised above" in stderr
    assert "Traceback" not in stderr
    assert not Path(f"{out}.partial.jsonl").exists(), "--out written: the partial file removed"


def test_a_client_that_closed_ends_the_gathering() -> None:
    """A result Dask was fetching when its scheduler died never completes its
    ``as_completed``, which waited for ever: now and then the evaluation hung after its
    scheduler was killed. Once the client has closed (it gave up reconnecting), the watch
    ends the gathering, also one that begins after."""
    import threading

    from roomba_bt.evaluate.cluster import WorkerWatch

    class Completing:
        def __init__(self) -> None:
            self.cleared = threading.Event()

        def clear(self) -> None:
            self.cleared.set()

    client = type("ClosedClient", (), {"status": "closed"})()
    with WorkerWatch(client, None) as watch:
        watch._thread.join(timeout=HANG_S)  # it ends once it has seen the client closed
        assert watch.closed
        late = Completing()
        watch.gathering(late)
        assert late.cleared.is_set()
    running = type("RunningClient", (), {"status": "running"})()
    with WorkerWatch(running, None) as watch:
        completing = Completing()
        watch.gathering(completing)
    assert not completing.cleared.is_set() and not watch.closed


def test_the_connect_timeout_is_read_when_a_client_is_made(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """``scheduler_client`` without a ``timeout`` gives Dask's client
    ``SCHEDULER_CONNECT_TIMEOUT_S`` as it is at the call: its default was the constant
    itself, bound as the module was made, so a program or a test that set the constant
    afterwards waited the user's 10 s all the same. Dask is not imported: a client that
    cannot connect stands in for it."""
    given: list[float] = []

    class Unreachable:
        def __init__(self, address: str, loop: object, timeout: float) -> None:
            given.append(timeout)
            raise OSError("nothing listens")

    fake = type("Distributed", (), {"Client": Unreachable})
    monkeypatch.setattr(cluster, "_import_distributed", lambda: fake)
    monkeypatch.setattr(cluster, "SCHEDULER_CONNECT_TIMEOUT_S", 0.25)
    for timeout in (None, 3.0):
        client = cluster.scheduler_client("tcp://127.0.0.1:1", timeout=timeout)
        with pytest.raises(cluster.SchedulerUnreachableError, match="cannot connect"), client:
            pass
    assert given == [0.25, 3.0]


def test_an_unreachable_scheduler_exits_3(
    capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """Nothing listens on the port: Dask's client retries the refused connection until the
    timeout, then exit code 3. The timeout is 1 s here, not the user's 10 s spent waiting.
    The client's IO loop thread is ended: Dask's client, closed by its own failed
    ``__init__``, left it running for the rest of the process (``Client.close`` returns at
    once for a closed client)."""
    from roomba_bt.cli import main
    from roomba_bt.evaluate import cluster

    monkeypatch.setattr(cluster, "SCHEDULER_CONNECT_TIMEOUT_S", 1.0)
    port = _free_port()  # nothing listens there
    loops = _io_loops()
    code = main(["eval", str(MISSIONS / "dock.yaml"), "--runs", "1", "--no-progress",
                 "--scheduler", f"tcp://127.0.0.1:{port}"])  # fmt: skip
    assert code == 3
    assert f"--scheduler tcp://127.0.0.1:{port}: cannot connect" in capsys.readouterr().err
    assert _io_loops() == loops


def test_a_client_whose_scheduler_was_lost_ends_its_io_loop(
    scheduler: Callable[[int], Separate],
) -> None:
    """The scheduler killed under a connected client: the client closes itself once it
    cannot reconnect (2 s here), and Dask's ``Client.close`` then returns at once without
    ending the client's IO loop thread; :func:`cluster.scheduler_client` ends it."""
    address, _, scheduler_process = scheduler(0)
    loops = _io_loops()
    with _connected_when_ready(address) as client:
        scheduler_process.kill()
        deadline = time.monotonic() + HANG_S
        while client.status != "closed" and time.monotonic() < deadline:
            time.sleep(0.1)  # Dask's own thread closes it: no event to wait on
        assert client.status == "closed"
    assert _io_loops() == loops


def _io_loops() -> set[threading.Thread]:
    """The event loop threads of Dask's clients running now: those Dask starts itself
    (``distributed.utils.LoopRunner``'s) and a ``--scheduler`` client's own."""
    names = {"IO loop", cluster.CLIENT_LOOP_THREAD}
    return {thread for thread in threading.enumerate() if thread.name in names}


@pytest.mark.parametrize(
    ("address", "why"),
    [
        ("foo", "missing port number"),
        ("tcp://10.0.0.5", "missing port number"),
        ("http://10.0.0.5:8786", "unknown scheme http://"),
        ("tcp://10.0.0.5:port", "invalid literal"),
        ("tcp://10.0.0.5:99999", "port 99999 is not 1..65535"),
        ("tcp://[::1", "ipv6 needs brackets"),
    ],
)
def test_a_malformed_scheduler_address_exits_2_naming_it(
    address: str, why: str, capsys: pytest.CaptureFixture[str]
) -> None:
    """A mistyped ``--scheduler`` is bad input (exit 2, the address, Dask's reason and the
    form expected), not a traceback from inside Dask's client and not a 10 s wait."""
    from roomba_bt.cli import main

    code = main(["eval", str(MISSIONS / "dock.yaml"), "--runs", "1", "--no-progress",
                 "--scheduler", address])  # fmt: skip
    assert code == 2
    err = capsys.readouterr().err
    assert f"--scheduler {address}: not a scheduler address (" in err
    assert why in err and "expected tcp://HOST:PORT" in err
    assert "Traceback" not in err


def test_dask_s_warnings_are_its_detail_too() -> None:
    """A warning Dask's code raises is ignored while a client is open and the log shows no
    DEBUG lines (the suite's filter makes one an error: here it is not), and the warning
    filters are as they were afterwards."""
    import warnings

    from roomba_bt.evaluate.cluster import dask_logs_as_detail

    def dask_warns() -> None:
        warnings.warn_explicit("a Dask warning", UserWarning, "client.py", 1,
                               module="distributed.client")  # fmt: skip

    with dask_logs_as_detail():
        dask_warns()
    with pytest.raises(UserWarning, match="a Dask warning"):
        dask_warns()


def test_a_scheduler_without_workers_is_said_to_have_none(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """--scheduler at a cluster with no worker waited for ever without a word."""
    import distributed

    from roomba_bt.evaluate.cluster import say_when_no_worker

    with (
        distributed.LocalCluster(
            n_workers=0,
            processes=False,
            dashboard_address=None,
            scheduler_kwargs={"dashboard": False, "dashboard_address": ":0"},  # no port 8787
        ) as cluster,
        distributed.Client(cluster) as client,
    ):
        say_when_no_worker(client, "tcp://example:8786", after_s=0.2)
        assert "the cluster at tcp://example:8786 has 0 workers; waiting" in capsys.readouterr().err
        cluster.scale(1)
        client.wait_for_workers(1, timeout=HANG_S)
        say_when_no_worker(client, "tcp://example:8786", after_s=5.0)
        assert "0 workers" not in capsys.readouterr().err


def _worker_settings(dask_worker: Any) -> tuple[bool, bool, float, float]:
    import dask

    callbacks = dask_worker.periodic_callbacks
    return (
        "profile" in callbacks,
        bool(dask.config.get("distributed.admin.system-monitor.disk")),
        callbacks["tick"].callback_time,
        callbacks["memory_monitor"].callback_time,
    )


@contextlib.contextmanager
def _port_8787_held() -> Iterator[None]:
    """Dask's default HTTP port taken, as by another evaluation's local cluster (or already
    taken by someone else: the same situation)."""
    with socket.socket() as held:
        held.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            held.bind(("127.0.0.1", 8787))
            held.listen()
        except OSError:
            pass  # someone else already holds it
        yield


@pytest.fixture(scope="class")
def _one_local_cluster() -> Iterator[Any]:
    """The local cluster of 2 worker processes that ``--engine dask --jobs 2`` starts
    (:func:`dask_client`), started once for the tests of :class:`TestOnOneLocalCluster`,
    while port 8787 is held. Scoped to the class, not the module: while it is open, this
    process's Dask loggers are silent and Dask's settings are the local cluster's, which the
    tests after it (the shutdown's) compare with what they were before a client."""
    with _port_8787_held(), dask_client(workers=2) as client:
        yield client


@pytest.fixture
def local_client(_one_local_cluster: Any) -> Iterator[Any]:
    """The shared local cluster's client, with Dask's logs and warnings its detail for the
    test (as they are for an evaluation's whole run; the suite's warning filter is set again
    for each test)."""
    with dask_logs_as_detail():
        yield _one_local_cluster


class TestOnOneLocalCluster:
    """Tests that only submit episodes and gather them, or read how the local cluster
    started: one cluster for them all (each cluster is 3 processes importing Dask). A test
    that kills a worker or the scheduler, or closes the cluster, has its own."""

    def test_a_local_cluster_takes_no_fixed_port(self, local_client: Any) -> None:
        """Two evaluations at once (two suites, two users) each start a local cluster: the
        scheduler's HTTP server must not take Dask's default port 8787, or the second one
        warns "Port 8787 is already in use" (an error under this suite's warning filter; the
        cluster was started with 8787 held)."""
        scheduler = local_client.cluster.scheduler
        assert scheduler.http_server is not None
        ports = {s.getsockname()[1] for s in scheduler.http_server._sockets.values()}
        assert 8787 not in ports

    def test_a_local_clusters_workers_run_without_what_only_a_dashboard_shows(
        self, local_client: Any
    ) -> None:
        """The local cluster has no dashboard: its workers start without the statistical
        profiler (it samples the episode's thread every 10 ms, holding the GIL) and the disk
        counters, and read the event-loop tick and their memory less often (that the
        settings do not leak into the process that started it:
        :func:`test_a_local_cluster_shuts_down_without_a_word`)."""
        assert set(local_client.run(_worker_settings).values()) == {(False, False, 500, 1000)}
        scheduler = local_client.cluster.scheduler
        assert scheduler.periodic_callbacks["tick"].callback_time == 500
        assert scheduler.periodic_callbacks["monitor"].callback_time == 2000

    def test_results_released_as_they_come_are_all_kept(
        self, local_client: Any, one_job: list[EpisodeResult], monkeypatch: pytest.MonkeyPatch
    ) -> None:
        """A result is released in batches of ``RELEASE_EVERY`` as it is gathered; one read
        after its own release read as cancelled, and its episode was lost (``make bench``'s
        48 episodes: 16 a batch). Released after each result here, every result is kept
        (4 episodes: each is its own batch)."""
        release = cluster._release_noting_reruns

        def released_and_forgotten(client: Any, futures: list[Any], ask: bool = True) -> list[str]:
            """Released, then waited for until the client has marked them so (its event loop
            does it a moment later: the race ``make bench`` lost now and then)."""
            held = list(futures)
            rerun = release(client, futures, ask)
            deadline = time.monotonic() + HANG_S
            while any(f.status != "cancelled" for f in held) and time.monotonic() < deadline:
                time.sleep(0.005)
            return rerun

        monkeypatch.setattr(cluster, "RELEASE_EVERY", 1)
        monkeypatch.setattr(cluster, "_release_noting_reruns", released_and_forgotten)
        results, retried, interrupted = run_on_client(local_client, SPECS[:4])
        assert interrupted is None and retried == 0
        assert all(r is not None for r in results)
        assert _episodes([r for r in results if r is not None]) == one_job[:4]

    def test_a_few_episodes_per_worker_are_on_the_cluster_at_a_time(
        self, local_client: Any, one_job: list[EpisodeResult], monkeypatch: pytest.MonkeyPatch
    ) -> None:
        """Every episode was submitted before the first result: 100 000 held 1.4 GB in the
        submitting process, and the local scheduler, busy with them, was taken for lost
        before any finished. A window of ``IN_FLIGHT_PER_THREAD`` per worker thread is on
        the cluster (1 each here: 2 of the 8), refilled as results come; the same
        results."""
        monkeypatch.setattr(cluster, "IN_FLIGHT_PER_THREAD", 1, raising=False)
        submit = local_client.submit
        sent: list[str] = []
        in_flight: list[int] = []

        def counted(*args: Any, **kwargs: Any) -> Any:
            sent.append(kwargs["key"])
            return submit(*args, **kwargs)

        def progress(done: int, total: int, result: EpisodeResult) -> None:
            in_flight.append(len(sent) - done + 1)  # this one's result is in

        monkeypatch.setattr(local_client, "submit", counted)
        results, retried, _ = run_on_client(local_client, SPECS, progress)
        assert len(sent) == len(SPECS) and max(in_flight) <= 2, in_flight
        assert _episodes([r for r in results if r is not None]) == one_job and retried == 0

    def test_results_are_released_as_they_are_gathered(
        self, local_client: Any, one_job: list[EpisodeResult], monkeypatch: pytest.MonkeyPatch
    ) -> None:
        """Every future was kept to the end: the scheduler held each finished episode (a dead
        worker's finished ones were computed again, and the retried count missed them). By
        the last result, the scheduler has forgotten the earlier ones."""
        monkeypatch.setattr(cluster, "RELEASE_EVERY", 1)
        held: list[int] = []

        def episodes_held(dask_scheduler: Any) -> int:
            return sum(1 for key in dask_scheduler.tasks if str(key).startswith("episode-"))

        def at_the_last(done: int, total: int, result: EpisodeResult) -> None:
            if done < total:
                return
            deadline = time.monotonic() + HANG_S
            while time.monotonic() < deadline:  # release is asynchronous: until it forgot them
                held.append(local_client.run_on_scheduler(episodes_held))
                if held[-1] == 0:
                    return
                time.sleep(0.01)

        results, retried, _ = run_on_client(local_client, SPECS[:4], at_the_last)
        assert held and held[-1] == 0, f"still held at the last result: {held[-1:]}"
        assert _episodes([r for r in results if r is not None]) == one_job[:4] and retried == 0


#: where Dask's shutdown races log: its own loggers, and those of the libraries its comms run
#: on (a worker's own ``distributed`` loggers are already quiet: ``silence_logs``)
LOSING = ("distributed.worker", "tornado.application", "asyncio")


def _lose_a_connection(who: str, loggers: Sequence[str] = LOSING) -> None:
    """An ERROR with its traceback on each of ``loggers``, as each is logged when a shutdown
    loses a connection."""
    import logging

    try:
        raise OSError("Stream is closed")
    except OSError:
        for name in loggers:
            logging.getLogger(name).exception("%s: lost at shutdown", who)


def _lost_at_shutdown() -> dict[str, int]:
    """Run on a worker once the shutdown has begun: its connections lost
    (:func:`_lose_a_connection`); the levels of the worker's Dask loggers."""
    import logging

    _lose_a_connection("worker")
    print("worker logged its loss", file=sys.stderr, flush=True)
    return {name: logging.getLogger(name).level for name in cluster.DASK_LOGGERS}


def test_a_local_cluster_shuts_down_without_a_word(capfd: pytest.CaptureFixture[str]) -> None:
    """A shutdown races Dask's own traffic (a worker's heartbeat meets the closed scheduler
    or its own closing connection pool), and Dask logs each loss as an ERROR with its
    traceback, in the worker's process or this one: on a loaded machine one came under the
    summary of an evaluation. Here the worker logs such an ERROR once the close has begun
    (as the client closes: the workers are silenced before it), and a worker plugin and a
    scheduler plugin log one as they close, where the race would: none reaches stderr; and
    this process's loggers and Dask settings are afterwards as they were before the client.

    The worker plugin's teardown is not a sure witness: a worker that does not close within
    4 s of its nanny's asking (Dask's ``Nanny.close(timeout=5)``, 0.8 of it) is killed before
    its teardown runs, which a loaded machine did (only "scheduler plugin closed" came).
    Nothing was lost (the results came with the futures), so its teardown is asked to have
    run only when the worker was not killed."""
    import logging
    import signal

    import dask
    from distributed import WorkerPlugin
    from distributed.diagnostics.plugin import SchedulerPlugin

    class ClosingWorker(WorkerPlugin):  # sent by value to the worker's process
        def teardown(self, worker: Any) -> None:
            _lose_a_connection("worker plugin")
            print("worker plugin closed", file=sys.stderr, flush=True)

    class ClosingScheduler(SchedulerPlugin):
        async def close(self) -> None:
            _lose_a_connection("scheduler", ("distributed.core", "tornado.application", "asyncio"))
            print("scheduler plugin closed", file=sys.stderr, flush=True)

    names = ("distributed", "distributed.worker", "tornado")
    levels = {name: logging.getLogger(name).level for name in names}
    keys = ("distributed.worker.profile.enabled", "distributed.admin.tick.interval")
    settings = [dask.config.get(key) for key in keys]
    on_worker: dict[str, dict[str, int]] = {}
    with dask_client(workers=1) as client:
        client.register_plugin(ClosingWorker())
        client.register_plugin(ClosingScheduler())
        assert client.submit(sum, [1, 2]).result() == 3
        (nanny,) = client.cluster.workers.values()
        worker_process = nanny.process.process  # its exit code, once the cluster has closed

        def closing_after_the_worker_lost_something() -> None:
            del client.close  # once: Client.__del__ closes it too
            on_worker.update(client.run(_lost_at_shutdown))
            client.close()

        client.close = closing_after_the_worker_lost_something  # close_quietly's next step
    err = capfd.readouterr().err
    (worker_levels,) = on_worker.values()
    assert "worker logged its loss" in err and "scheduler plugin closed" in err  # they ran
    killed = worker_process.exitcode == -signal.SIGKILL  # by its nanny: too slow to close
    assert "worker plugin closed" in err or killed, (worker_process.exitcode, err)
    assert "lost at shutdown" not in err and "Traceback" not in err, err
    assert set(worker_levels.values()) == {cluster.SILENT}  # why: silenced by the client
    assert {name: logging.getLogger(name).level for name in names} == levels
    assert [dask.config.get(key) for key in keys] == settings


def test_a_worker_killed_at_shutdown_leaves_no_copy_of_the_mission(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, one_job: list[EpisodeResult]
) -> None:
    """A worker writes its copy of the mission's bundle to the temporary folder and removes
    it at exit; one its nanny kills at shutdown (not closed 4 s after it was asked: a loaded
    machine; here stopped as the client closes) ran no atexit and left the copy behind, one
    folder per such worker and evaluation. The close removes it before."""
    import os
    import signal

    monkeypatch.setenv("TMPDIR", str(tmp_path))  # the worker's temporary folder
    with dask_client(workers=1) as client:
        results, _, _ = run_on_client(client, SPECS[:1])
        assert _episodes([r for r in results if r is not None]) == one_job[:1]
        (nanny,) = client.cluster.workers.values()
        worker_process = nanny.process.process
        (pid,) = client.run(os.getpid).values()

        def closing_with_the_worker_stopped() -> None:
            del client.close  # once: Client.__del__ closes it too
            os.kill(pid, signal.SIGSTOP)  # (SIGKILL ends a stopped process)
            client.close()

        client.close = closing_with_the_worker_stopped  # close_quietly's next step
    assert worker_process.exitcode == -signal.SIGKILL, "killed by its nanny"
    assert not list(tmp_path.glob("roomba-bt-*"))


def test_the_dask_engine_reaches_no_private_name_of_dask() -> None:
    """``cluster.py`` talks to Dask through its public API alone: no attribute and no
    ``getattr`` name that starts with one underscore (its own ``self._...`` aside), on
    anything. Ending a client's event loop took ``client._loop_runner``, Dask's own, which a
    Dask release may rename or change without a word; the client now runs on a loop of this
    evaluation's own (:func:`cluster._event_loop`), given as ``Client``'s ``loop``."""
    import ast
    import inspect

    tree = ast.parse(inspect.getsource(cluster))
    private = [
        f"line {node.lineno}: {ast.unparse(node)}"
        for node in ast.walk(tree)
        if (
            isinstance(node, ast.Attribute)
            and _private(node.attr)
            and not (isinstance(node.value, ast.Name) and node.value.id == "self")
        )
        or (
            isinstance(node, ast.Call)
            and isinstance(node.func, ast.Name)
            and node.func.id in {"getattr", "setattr", "hasattr"}
            and len(node.args) > 1
            and isinstance(node.args[1], ast.Constant)
            and _private(str(node.args[1].value))
        )
    ]
    assert private == []


def _private(name: str) -> bool:
    return name.startswith("_") and not name.startswith("__")


def test_an_episode_whose_dask_workers_kept_dying_is_said_with_its_variant(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """In an A/B every seed is two episodes: the lines of one whose Dask workers died (run
    again alone, recorded as DIED) said ``seed 3`` of either; the evaluation says each as
    :func:`~roomba_bt.evaluate.parallel.seeds_said` does, ``3 (dock.yaml -p
    turn_speed=90mm/s)``: its variant as the report labels it."""
    from distributed.scheduler import KilledWorker

    from roomba_bt.evaluate.parallel import seeds_said

    ab = [SPECS[0], dataclasses.replace(SPECS[0], params=(("turn_speed", "90mm/s"),))]
    said = seeds_said(ab, [1])
    first = KilledWorker("episode-0a1b2c-1", None, allowed_failures=0)
    assert cluster._killed_worker(ab[1], first, said) is first
    died = cluster.died_on_workers(ab[1], first, first, said)
    err = capsys.readouterr().err
    assert said == f"{SPECS[0].seed} ({SPECS[0].mission} -p turn_speed=90mm/s)"
    assert f"seed {said}: 1 Dask worker(s) died running it or with it queued" in err
    assert f"seed {said} killed its workers again, alone: recorded as DIED" in err
    assert died.outcome == "died"
