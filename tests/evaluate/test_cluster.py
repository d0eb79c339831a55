"""Episodes on Dask: a LocalCluster of worker processes, and a scheduler and workers started as
separate processes on 127.0.0.1 (`dask scheduler`, `dask worker`), give the same results,
episode by episode, as ``--jobs 1``; a worker killed mid-evaluation loses no episode."""

from __future__ import annotations

import dataclasses
import socket
import subprocess
import sys
import time
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import Any

import pytest

from roomba_bt.evaluate import EpisodeResult, cluster, episode_specs, run_episodes
from roomba_bt.evaluate.cluster import dask_client, run_on_client
from roomba_bt.evaluate.parallel import Engine, evaluate

MISSIONS = Path(__file__).resolve().parents[2] / "missions"
SPECS = episode_specs(str(MISSIONS / "dock.yaml"), world="empty-room", runs=8, seed=11,
                      within_m=1.5)  # fmt: skip
DASK = str(Path(sys.executable).parent / "dask")
#: every test here runs episodes on Dask, or reads what roomba-bt says of a cluster after
#: Dask is imported
pytestmark = pytest.mark.extra("cluster")


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


def test_results_released_as_they_come_are_all_kept(
    one_job: list[EpisodeResult], monkeypatch: pytest.MonkeyPatch
) -> None:
    """A result is released in batches of ``RELEASE_EVERY`` as it is gathered; one read
    after its own release read as cancelled, and its episode was lost (``make bench``'s 48
    episodes: 16 a batch). Released after each result here, every result is kept."""
    release = cluster._release_noting_reruns

    def released_and_forgotten(client: Any, futures: list[Any], ask: bool = True) -> list[str]:
        """Released, then waited for until the client has marked them so (its event loop
        does it a moment later: the race ``make bench`` lost now and then)."""
        held = list(futures)
        rerun = release(client, futures, ask)
        deadline = time.monotonic() + 10
        while any(f.status != "cancelled" for f in held) and time.monotonic() < deadline:
            time.sleep(0.005)
        return rerun

    monkeypatch.setattr(cluster, "RELEASE_EVERY", 1)
    monkeypatch.setattr(cluster, "_release_noting_reruns", released_and_forgotten)
    (done,) = evaluate([SPECS], Engine("dask", jobs=2))
    assert not done.interrupted
    assert _episodes(done.results) == one_job


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


#: the scheduler's address, its workers' processes and its own
Separate = tuple[str, list[subprocess.Popen[bytes]], subprocess.Popen[bytes]]


@pytest.fixture
def scheduler(tmp_path: Path) -> Iterator[Separate]:
    """A scheduler and two single-threaded workers without nannies (a killed worker stays
    dead), each its own process, run from another folder (no shared files with the test)."""
    port = _free_port()
    address = f"tcp://127.0.0.1:{port}"
    log = open(tmp_path / "dask.log", "wb")  # noqa: SIM115 (closed below)
    processes = [subprocess.Popen([DASK, "scheduler", "--host", "127.0.0.1", "--port",
                                   str(port), "--no-dashboard"], cwd=tmp_path,
                                  stdout=log, stderr=log)]  # fmt: skip
    workers = [
        subprocess.Popen([DASK, "worker", address, "--nthreads", "1", "--no-nanny",
                          "--no-dashboard", "--host", "127.0.0.1"], cwd=tmp_path,
                         stdout=log, stderr=log)
        for _ in range(2)
    ]  # fmt: skip
    processes += workers
    try:
        yield address, workers, processes[0]
    finally:
        for p in processes:
            p.kill()
        for p in processes:
            p.wait(timeout=30)
        log.close()


def _connect_when_ready(address: str) -> object:
    from distributed import Client

    deadline = time.monotonic() + 60
    while True:
        try:
            return Client(address, timeout="2s")
        except OSError:
            if time.monotonic() > deadline:
                raise
            time.sleep(0.2)


def test_separate_scheduler_and_workers_give_the_results_of_one_job_even_if_one_dies(
    one_job: list[EpisodeResult],
    scheduler: Separate,
    capsys: pytest.CaptureFixture[str],
) -> None:
    address, workers, _ = scheduler
    client = _connect_when_ready(address)
    with client:  # type: ignore[attr-defined]
        client.wait_for_workers(2, timeout=60)  # type: ignore[attr-defined]
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
    assert workers[0].wait(timeout=30) != 0, "the worker was killed"
    assert not interrupted
    assert sorted(reported) == [s.seed for s in SPECS], "every episode reported once"
    assert all(r is not None for r in results)
    assert _episodes([r for r in results if r is not None]) == one_job
    assert retried >= 1, "the killed worker's episode ran again elsewhere"
    # which ones, on stderr whatever --reproducible leaves out of stdout (it said nothing)
    said = f"roomba-bt eval: {retried} episode(s) ran again after a Dask worker holding them"
    assert said in capsys.readouterr().err


def test_the_seeds_run_again_are_named_from_their_keys() -> None:
    """The scheduler names the futures a dead worker held by key; the seeds are their
    episodes', each once, in order, the first ten said."""
    specs = [dataclasses.replace(SPECS[0], seed=seed) for seed in range(100, 112)]
    keys = [f"episode-0a1b2c-{i}" for i in (3, 1, 11, 0, 2, 4, 5, 6, 7, 8, 9, 10)]
    assert cluster._seeds_of(specs, [*keys[:2], "episode-0a1b2c-3-alone"]) == "101, 103"
    assert cluster._seeds_of(specs, keys) == (
        "100, 101, 102, 103, 104, 105, 106, 107, 108, 109 and 2 more"
    )


#: ``roomba-bt`` whose Dask client gives a lost scheduler 5 s to come back, not the user's
#: 10 s (``SCHEDULER_CONNECT_TIMEOUT_S``, also its connect's bound: still generous for a
#: scheduler the test has just reached itself): what a test of a lost scheduler checks comes
#: after the client gave up, and the other 5 s were the suite's longest idle wait.
#: ``test_an_unreachable_scheduler_exits_3`` sets the same constant in process.
ROOMBA_BT_RECONNECTING_5_S = [
    sys.executable, "-c",
    "import sys; from roomba_bt.evaluate import cluster; "
    "cluster.SCHEDULER_CONNECT_TIMEOUT_S = 5.0; "
    "from roomba_bt.cli import main; sys.exit(main())",
]  # fmt: skip


def _evaluation_under_way(
    child: Callable[[Sequence[str]], subprocess.Popen[str]], address: str, out: Path,
    *options: str, roomba_bt: Sequence[str] = (sys.executable, "-m", "roomba_bt"),
) -> subprocess.Popen[str]:  # fmt: skip
    """``roomba-bt eval`` (run as ``roomba_bt``) of 400 dock episodes on the cluster at
    ``address``, writing ``out``, once its first episode is in the partial file (another
    process's file: polled)."""
    with _connect_when_ready(address) as client:  # type: ignore[attr-defined]
        client.wait_for_workers(2, timeout=60)
    evaluation = child(
        [*roomba_bt, "eval", str(MISSIONS / "dock.yaml"), "--runs", "400", "--within", "1.5",
         "--no-progress", "--scheduler", address, "--out", str(out), *options]
    )  # fmt: skip
    partial = Path(f"{out}.partial.jsonl")
    deadline = time.monotonic() + 120
    while not (partial.exists() and partial.read_text().strip()):
        assert evaluation.poll() is None and time.monotonic() < deadline
        time.sleep(0.05)  # another process's file: no event to wait on
    return evaluation


def test_a_cluster_whose_workers_are_gone_for_good_stops_after_worker_wait_with_exit_3(
    tmp_path: Path,
    scheduler: Separate,
    child: Callable[[Sequence[str]], subprocess.Popen[str]],
) -> None:
    """Every worker killed mid-evaluation (no nanny starts them again): the scheduler held the
    episodes and the evaluation waited for ever. Now, after --worker-wait with no worker, it
    stops: exit 3 (the cluster's failure, not the missions'), why on stderr, and the episodes
    that finished summarised and written to --out."""
    from roomba_bt.evaluate.records import read_results

    address, workers, _ = scheduler
    out = tmp_path / "out.jsonl"
    evaluation = _evaluation_under_way(child, address, out, "--worker-wait", "2s")
    for worker in workers:
        worker.kill()
    stdout, stderr = evaluation.communicate(timeout=120)
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
    scheduler: Separate,
    child: Callable[[Sequence[str]], subprocess.Popen[str]],
) -> None:
    """The scheduler killed mid-evaluation: Dask's client cancels every future it held, and
    the evaluation took the cancelled episodes for none to run: it ended exit 0, ``success
    18/18`` of 400 episodes, not a word of the others. Now it stops: exit 3 (the cluster's
    failure, as an unreachable --scheduler), why in the summary (``interrupted_by``:
    ``scheduler-lost``) and on stderr, and the episodes that finished, those the partial
    file held, summarised and written to --out."""
    import json

    from roomba_bt.evaluate.records import read_results

    address, _, scheduler_process = scheduler
    out = tmp_path / "out.jsonl"
    evaluation = _evaluation_under_way(
        child, address, out, "--json", roomba_bt=ROOMBA_BT_RECONNECTING_5_S
    )
    scheduler_process.kill()
    stdout, stderr = evaluation.communicate(timeout=120)
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
        watch._thread.join(timeout=30)  # it ends once it has seen the client closed
        assert watch.closed
        late = Completing()
        watch.gathering(late)
        assert late.cleared.is_set()
    running = type("RunningClient", (), {"status": "running"})()
    with WorkerWatch(running, None) as watch:
        completing = Completing()
        watch.gathering(completing)
    assert not completing.cleared.is_set() and not watch.closed


def test_an_unreachable_scheduler_exits_3(
    capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """Nothing listens on the port: Dask's client retries the refused connection until the
    timeout, then exit code 3. The timeout is 1 s here, not the user's 10 s spent waiting."""
    from roomba_bt.cli import main
    from roomba_bt.evaluate import cluster

    monkeypatch.setattr(cluster, "SCHEDULER_CONNECT_TIMEOUT_S", 1.0)
    port = _free_port()  # nothing listens there
    code = main(["eval", str(MISSIONS / "dock.yaml"), "--runs", "1", "--no-progress",
                 "--scheduler", f"tcp://127.0.0.1:{port}"])  # fmt: skip
    assert code == 3
    assert f"--scheduler tcp://127.0.0.1:{port}: cannot connect" in capsys.readouterr().err


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


def test_a_local_cluster_takes_no_fixed_port() -> None:
    """Two evaluations at once (two suites, two users) each start a local cluster: the
    scheduler's HTTP server must not take Dask's default port 8787, or the second one warns
    "Port 8787 is already in use" (an error under this suite's warning filter)."""
    with socket.socket() as held:
        held.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            held.bind(("127.0.0.1", 8787))
            held.listen()
        except OSError:
            pass  # someone else already holds it: the same situation
        with dask_client(workers=1) as client:
            scheduler = client.cluster.scheduler
            assert scheduler.http_server is not None
            ports = {s.getsockname()[1] for s in scheduler.http_server._sockets.values()}
            assert 8787 not in ports


def _worker_settings(dask_worker: Any) -> tuple[bool, bool, float, float]:
    import dask

    callbacks = dask_worker.periodic_callbacks
    return (
        "profile" in callbacks,
        bool(dask.config.get("distributed.admin.system-monitor.disk")),
        callbacks["tick"].callback_time,
        callbacks["memory_monitor"].callback_time,
    )


def test_a_local_clusters_workers_run_without_what_only_a_dashboard_shows() -> None:
    """The local cluster has no dashboard: its workers start without the statistical profiler
    (it samples the episode's thread every 10 ms, holding the GIL) and the disk counters, and
    read the event-loop tick and their memory less often; the settings do not leak into the
    process that started it."""
    import dask
    import distributed  # noqa: F401  (its defaults join dask's configuration)

    keys = ("distributed.worker.profile.enabled", "distributed.admin.tick.interval")
    before = [dask.config.get(key) for key in keys]
    with dask_client(workers=1) as client:
        assert set(client.run(_worker_settings).values()) == {(False, False, 500, 1000)}
        scheduler = client.cluster.scheduler
        assert scheduler.periodic_callbacks["tick"].callback_time == 500
        assert scheduler.periodic_callbacks["monitor"].callback_time == 2000
    assert [dask.config.get(key) for key in keys] == before


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
        client.wait_for_workers(1, timeout=120)
        say_when_no_worker(client, "tcp://example:8786", after_s=5.0)
        assert "0 workers" not in capsys.readouterr().err


def test_results_are_released_as_they_are_gathered(
    one_job: list[EpisodeResult], monkeypatch: pytest.MonkeyPatch
) -> None:
    """Every future was kept to the end: the scheduler held each finished episode (a dead
    worker's finished ones were computed again, and the retried count missed them). By the
    last result, the scheduler has forgotten the earlier ones."""
    import roomba_bt.evaluate.cluster as cluster

    monkeypatch.setattr(cluster, "RELEASE_EVERY", 1, raising=False)  # (none in old code)
    held: list[int] = []

    def episodes_held(dask_scheduler: Any) -> int:
        return sum(1 for key in dask_scheduler.tasks if str(key).startswith("episode-"))

    with dask_client(None, 1) as client:

        def at_the_last(done: int, total: int, result: EpisodeResult) -> None:
            if done < total:
                return
            for _ in range(3000):  # release is asynchronous: until the scheduler forgot them
                held.append(client.run_on_scheduler(episodes_held))
                if held[-1] == 0:
                    return
                time.sleep(0.01)

        results, retried, _ = run_on_client(client, SPECS[:4], at_the_last)
    assert held and held[-1] == 0, f"still held at the last result: {held[-1:]}"
    assert _episodes([r for r in results if r is not None]) == one_job[:4] and retried == 0


def test_a_local_cluster_shuts_down_without_a_word(capfd: pytest.CaptureFixture[str]) -> None:
    """A shutdown races Dask's own traffic (a worker's heartbeat meets the closed scheduler
    or its own closing connection pool), and Dask logs each loss as an ERROR with its
    traceback, in the worker's process or this one: on a loaded machine one came under the
    summary of an evaluation. Here a worker plugin and a scheduler plugin log such an ERROR
    as they close, where the race would: neither reaches stderr, and this process's
    loggers are afterwards as they were before the client."""
    import logging

    from distributed import WorkerPlugin
    from distributed.diagnostics.plugin import SchedulerPlugin

    class ClosingWorker(WorkerPlugin):  # sent by value to the worker's process
        def teardown(self, worker: Any) -> None:
            try:
                raise OSError("Stream is closed")
            except OSError:
                logging.getLogger("distributed.worker").exception("worker: lost at shutdown")
            print("worker plugin closed", file=sys.stderr, flush=True)

    class ClosingScheduler(SchedulerPlugin):
        async def close(self) -> None:
            try:
                raise OSError("Stream is closed")
            except OSError:
                logging.getLogger("distributed.core").exception("scheduler: lost at shutdown")
            print("scheduler plugin closed", file=sys.stderr, flush=True)

    names = ("distributed", "distributed.worker", "tornado")
    levels = {name: logging.getLogger(name).level for name in names}
    with dask_client(workers=1) as client:
        client.register_plugin(ClosingWorker())
        client.register_plugin(ClosingScheduler())
        assert client.submit(sum, [1, 2]).result() == 3
    err = capfd.readouterr().err
    assert "worker plugin closed" in err and "scheduler plugin closed" in err  # they ran
    assert "lost at shutdown" not in err and "Traceback" not in err, err
    assert {name: logging.getLogger(name).level for name in names} == levels
