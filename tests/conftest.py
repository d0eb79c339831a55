"""Suite-wide: under ``CI=true`` a test skipped for a missing test dependency fails instead;
``clean_blackboard`` for the folders whose tests write py_trees' blackboard; ``served_sim``,
``roomba-bt sim`` in a child process; ``child``, any child process, killed if a test leaves it
running; ``silent_port``, a pty nobody answers on;
``usage_error``, a command line that must be refused; ``until``, a wait for another thread;
``record_held``, a file held by a child as a run holds its ``--record``; with
``ROOMBA_BT_TEST_CPU=FILE`` set, each test's CPU seconds in ``FILE`` (:class:`CpuTimes`).

Outside CI a missing optional package (the peer clients pycreate2 and PyRoombaAdapter,
jsonschema, the example wall-follow plugin) skips its tests with the install hint; in CI
that would hide a broken install step, so the skip becomes a failure that says which
package is missing. The tests of roomba-bt's own extras (plot, monitor, cluster) say which
extra they need, ``@pytest.mark.extra("plot")`` or a folder in :data:`EXTRA_FOLDERS`, and
:func:`missing_extra` says why for both: skipped, naming the extra, for a packager who
builds the core alone; failed under ``CI=true``, where ``make test`` installs every extra
(docs/ci.md, "roomba-bt's own suite").
"""

from __future__ import annotations

import contextlib
import importlib.util
import os
import signal
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Generator, Iterator, Sequence
from pathlib import Path
from types import ModuleType
from typing import Any

import py_trees
import pytest
import waits  # tests/waits.py: the suite's one bound on a hang, and its waits
from waits import HANG_S


def _answer_the_signals_the_tests_send() -> None:
    """A suite started where a script's ``&`` (no job control) or ``nohup`` left SIGINT,
    SIGQUIT or SIGHUP ignored: every child inherits the ignoring, roomba-bt keeps a hang-up
    ignored at its start ignored (``robot.safety.IGNORED_AT_START``), and a child's Python
    has no KeyboardInterrupt for an ignored SIGINT, so the tests that send them (Ctrl-C, a
    hang-up) would see them ignored. Caught here, they are back to their default in a child
    after ``exec``; the suite itself still shrugs off a hang-up."""
    for signum in (signal.SIGINT, signal.SIGQUIT, signal.SIGHUP):
        if signal.getsignal(signum) is signal.SIG_IGN:
            handler = signal.default_int_handler if signum == signal.SIGINT else _shrug
            signal.signal(signum, handler)


def _shrug(signum: int, frame: object) -> None:
    """A hang-up or Ctrl-\\ the suite was started to ignore: still nothing, in the suite."""


_answer_the_signals_the_tests_send()

#: the checkout, first on a child's path (its ``roomba_bt``, whatever is installed)
ROOT = Path(__file__).resolve().parents[1]
#: skip reasons that mean "a test dependency is not installed"
MISSING_DEPENDENCY = ("could not import", "No module named", "pip install")


@pytest.fixture(autouse=True)
def _no_settings_from_the_shell(monkeypatch: pytest.MonkeyPatch) -> None:
    """A developer's ``ROOMBA_BT_INCLUDE_PATH`` grants include folders to every command,
    ``ROOMBA_BT_PROFILE`` names the robot for every command and ``ROOMBA_BT_WORLDS`` adds
    worlds that may take a shipped world's name: not for the suite's, whose refusals the
    first would turn into passes, whose profiles the second would change and whose worlds
    the third (children inherit this)."""
    for variable in ("ROOMBA_BT_INCLUDE_PATH", "ROOMBA_BT_PROFILE", "ROOMBA_BT_WORLDS"):
        monkeypatch.delenv(variable, raising=False)


def in_ci() -> bool:
    return os.environ.get("CI", "").lower() == "true"


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(
    item: pytest.Item, call: pytest.CallInfo[None]
) -> Generator[None, pytest.TestReport, None]:
    outcome = yield
    report: pytest.TestReport = outcome.get_result()
    if not (in_ci() and report.skipped and isinstance(report.longrepr, tuple)):
        return
    reason = str(report.longrepr[2])
    if any(sign in reason for sign in MISSING_DEPENDENCY):
        report.outcome = "failed"
        report.longrepr = fails_in_ci(reason)


def fails_in_ci(reason: str) -> str:
    return f"CI=true: a test dependency is missing, so this fails: {reason}"


#: pyproject.toml's optional extras that tests need, by the module each one installs
EXTRAS = {"plot": "matplotlib", "monitor": "aiohttp", "cluster": "distributed"}
#: folders whose every test needs an extra: their modules import it as they are collected
#: (the monitor's server imports aiohttp), so a mark on each test would come too late
EXTRA_FOLDERS = {ROOT / "tests" / "monitor": "monitor"}


def missing_extra(extra: str) -> str | None:
    """Why a test of the extra ``extra`` cannot run here, or None where it can. Whether it is
    installed is whether its module can be found: a half-installed extra (its module there, a
    dependency of it missing) is not skipped but fails in the test, as it would for a user."""
    module = EXTRAS[extra]
    if importlib.util.find_spec(module) is not None:
        return None
    return f"needs the {extra} extra ({module} is missing): pip install 'roomba-bt[{extra}]'"


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """A test marked ``@pytest.mark.extra(name)`` (or a ``pytest.param`` of one) is skipped
    where the extra is missing, at the test's own place in the report; under ``CI=true``
    :func:`pytest_runtest_makereport` fails it, as every skip for a missing package."""
    for item in items:
        for mark in item.iter_markers("extra"):
            if reason := missing_extra(*mark.args):
                item.add_marker(pytest.mark.skip(reason=reason))


@pytest.hookimpl(tryfirst=True)
def pytest_make_collect_report(collector: pytest.Collector) -> pytest.CollectReport | None:
    """A folder of :data:`EXTRA_FOLDERS` is skipped whole (failed under CI) before its
    conftest imports the extra; the ImportError there was a collection error that stopped
    the whole run."""
    extra = EXTRA_FOLDERS.get(collector.path) if isinstance(collector, pytest.Directory) else None
    reason = missing_extra(extra) if extra else None
    if reason is None:
        return None
    if in_ci():
        return pytest.CollectReport(collector.nodeid, "failed", fails_in_ci(reason), None)
    return pytest.CollectReport(collector.nodeid, "skipped", (str(collector.path), 0, reason), None)


#: the variable that turns :class:`CpuTimes` on: the file it writes
CPU_TIMES_VARIABLE = "ROOMBA_BT_TEST_CPU"


class CpuTimes:
    """Each test's CPU seconds, a line ``SECONDS<TAB>NODEID`` appended to a file as the test
    ends: the suite's budget is on a shared 2-core machine, where a test's wall time is
    mostly the other jobs' (``--durations`` ranks by it), and its CPU time is what it costs
    the machine. Counted: user and system time of this process and of the children it has
    waited for (``os.times()``), over setup, call and teardown; a module-scoped fixture's
    cost falls on the test that set it up and the one that tore it down. A child's time is
    counted when it is reaped: the session's browser (tests/monitor), torn down after the
    last test, is a line of its own, :data:`SESSION_END`, not that test's. Registered only
    where the variable is set: off, not a hook runs."""

    #: the line for the teardown after the last test (every scope's fixtures still set up)
    SESSION_END = "(the session's end: fixtures of every scope torn down, their children reaped)"

    def __init__(self, path: Path) -> None:
        self.out = path.open("a", encoding="utf-8")
        self.session_end = 0.0

    @staticmethod
    def spent() -> float:
        times = os.times()
        return times.user + times.system + times.children_user + times.children_system

    @pytest.hookimpl(hookwrapper=True)
    def pytest_runtest_protocol(self, item: pytest.Item) -> Generator[None, object, None]:
        start = self.spent()
        yield
        self.write(self.spent() - start - self.session_end, item.nodeid)
        if self.session_end:
            self.write(self.session_end, self.SESSION_END)

    @pytest.hookimpl(hookwrapper=True)
    def pytest_runtest_teardown(
        self, item: pytest.Item, nextitem: pytest.Item | None
    ) -> Generator[None, object, None]:
        start = self.spent()
        yield
        if nextitem is None:
            self.session_end = self.spent() - start

    def write(self, seconds: float, what: str) -> None:
        self.out.write(f"{seconds:.3f}\t{what}\n")
        self.out.flush()

    def pytest_unconfigure(self) -> None:
        self.out.close()


def pytest_configure(config: pytest.Config) -> None:
    config.pluginmanager.register(Leftovers(), LEFTOVERS)
    config.addinivalue_line(
        "markers",
        "leaves_behind(why): a test module that leaves threads or descriptors on purpose "
        "(tests/conftest.py, Leftovers)",
    )
    if path := os.environ.get(CPU_TIMES_VARIABLE):
        config.pluginmanager.register(CpuTimes(Path(path)), "roomba-bt-cpu-times")


@pytest.fixture
def clean_blackboard() -> Iterator[None]:
    """py_trees' blackboard is one per process: empty before the test and after it."""
    py_trees.blackboard.Blackboard.clear()
    yield
    py_trees.blackboard.Blackboard.clear()


#: The most a test waits for ``roomba-bt sim`` to print its address, or to end once told:
#: each wait ends as soon as it does, so this stops only a hung simulator. Its start is an
#: interpreter's (imports: seconds on a loaded 2-core machine), and 10 s for its end was as
#: fixed a bet as the pty tests' 30 s that failed there: the suite's hang bound.
SIM_WAIT_S = HANG_S


class ServedSim:
    """``roomba-bt sim ARGS`` in a child process, in real time; ``address`` is the first line
    it printed: the pty's path or the URL to open."""

    def __init__(self, *args: str) -> None:
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "roomba_bt.cli", "sim", *args],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        assert self.proc.stdout is not None
        # a whole line, bounded: a select alone let a part of one through to a readline
        self.address = waits.line(self.proc.stdout, "the simulator's address", SIM_WAIT_S).strip()

    def stop(self, sig: int = signal.SIGTERM) -> tuple[int, str]:
        """``sig`` to it if it still runs; its exit code and what it wrote on stderr (the
        summary line: simulated time, frames, mode, wheels)."""
        if self.proc.poll() is None:
            self.proc.send_signal(sig)
        _, err = self.proc.communicate(timeout=SIM_WAIT_S)
        return self.proc.returncode, err


@pytest.fixture
def served_sim() -> Iterator[Callable[..., ServedSim]]:
    """``served_sim("--pty", "--baud", "19200")`` starts a :class:`ServedSim`; each one a test
    started and did not stop is stopped after it."""
    started: list[ServedSim] = []

    def start(*args: str) -> ServedSim:
        sim = ServedSim(*args)
        started.append(sim)
        return sim

    yield start
    for sim in started:
        if sim.proc.poll() is None:
            sim.stop()


@pytest.fixture
def child() -> Iterator[Callable[[Sequence[str]], subprocess.Popen[str]]]:
    """``child([sys.executable, ...])`` starts a process with text pipes and this checkout
    first on its ``PYTHONPATH``; each one still running when the test ends (a failed
    assertion, a timeout) is killed, so none outlives its test."""
    started: list[subprocess.Popen[str]] = []

    def start(args: Sequence[str]) -> subprocess.Popen[str]:
        env = {**os.environ, "PYTHONPATH": str(ROOT)}
        proc = subprocess.Popen(
            list(args), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env
        )
        started.append(proc)
        return proc

    yield start
    for proc in started:
        if proc.poll() is None:
            proc.kill()
        proc.communicate(timeout=HANG_S)  # a grandchild may hold its pipes: not for ever


#: ``roomba-bt ARGS`` started as a shell script's ``roomba-bt ARGS &`` starts it: a shell
#: without job control starts its background jobs with SIGINT and SIGQUIT ignored, and a
#: started program keeps them so (``exec`` keeps an ignored signal ignored)
_AS_A_SCRIPTS_JOB = (
    "import os, signal, sys\n"
    "for s in (signal.SIGINT, signal.SIGQUIT): signal.signal(s, signal.SIG_IGN)\n"
    "os.execv(sys.executable, [sys.executable, '-m', 'roomba_bt', *sys.argv[1:]])\n"
)


@pytest.fixture
def script_job(
    child: Callable[[Sequence[str]], subprocess.Popen[str]],
) -> Callable[[Sequence[str]], subprocess.Popen[str]]:
    """``script_job(["run", ...])`` starts ``roomba-bt run ...`` as a script's background
    job (Ctrl-C ignored at start: a script's ``kill -INT $!`` is its only way to ask a
    stop), as :func:`child` starts a process."""

    def start(args: Sequence[str]) -> subprocess.Popen[str]:
        return child([sys.executable, "-c", _AS_A_SCRIPTS_JOB, *args])

    return start


#: a child that holds a file as ``run --record`` holds its record (``ClaimedFile``'s flock)
_HOLD = (
    "import sys, time\n"
    "from roomba_bt.runtime.claimed import ClaimedFile\n"
    "claim = ClaimedFile(sys.argv[1])\n"
    "print('held', flush=True)\n"
    "time.sleep(600)\n"
)


@pytest.fixture
def record_held(
    child: Callable[[Sequence[str]], subprocess.Popen[str]],
) -> Callable[[Path], subprocess.Popen[str]]:
    """``record_held(path)``: a child process holds ``path`` as a run's ``--record`` does
    (its lock) until it is killed (the test ends, or ``.kill()`` it: a ``kill -9``)."""

    def hold(path: Path) -> subprocess.Popen[str]:
        proc = child([sys.executable, "-c", _HOLD, str(path)])
        assert proc.stdout is not None
        said = waits.line(proc.stdout, f"a child holding {path.name}")
        assert said == "held\n", said
        return proc

    return hold


@pytest.fixture
def silent_port() -> Iterator[str]:
    """A pty's device path with nothing behind it: nobody reads what is written or answers."""
    master, slave = os.openpty()
    try:
        yield os.ttyname(slave)
    finally:
        os.close(master)
        os.close(slave)


@pytest.fixture
def usage_error(capsys: pytest.CaptureFixture[str]) -> Callable[..., str]:
    """``usage_error(main, argv)``: ``main(argv)`` must end in argparse's usage error (exit 2);
    what it wrote on stderr."""

    def refused(main: Callable[[list[str]], object], argv: list[str]) -> str:
        with pytest.raises(SystemExit) as exit_:
            main(argv)
        assert exit_.value.code == 2
        return capsys.readouterr().err

    return refused


#: How long :func:`until` waits before the test fails: generous, for a loaded 2-core machine
#: (what it waits for takes milliseconds on an idle one; a monitor session's run on the
#: virtual clock did not reach its 1000th frame in 20 s with six busy loops on the 2 cores):
#: the suite's hang bound.
UNTIL_SECONDS = HANG_S


@pytest.fixture
def until() -> Callable[[Callable[[], bool]], None]:
    """``until(condition)``: wait for another thread of this process (a served simulator's
    loop, a run's tick thread) to make ``condition()`` true, looking every millisecond; fail
    after :data:`UNTIL_SECONDS` (the traceback's line names the condition)."""

    def wait(condition: Callable[[], bool]) -> None:
        waits.until(condition, "the condition never held", UNTIL_SECONDS)

    return wait


#: What :func:`pipe_read` gives: the reader's result (or what it raised) and whether it
#: opened the pipe.
PipeRead = Callable[[Path, Callable[[], object]], tuple[object, bool]]


def _read_beside_a_writer(fifo: Path, read: Callable[[], object]) -> tuple[object, bool]:
    """What ``read()`` gives (or raises), and whether it opened the pipe ``fifo``, which a
    writer waits on: a reader that opens a pipe waits for a writer, for ever, and here one
    comes, so a reader that opens it ends (the test fails, it does not hang)."""
    opened = threading.Event()

    def write() -> None:
        with open(fifo, "w"):  # blocks until a reader opens it
            opened.set()

    writer = threading.Thread(target=write, daemon=True)
    writer.start()
    try:
        try:
            given = read()
        except Exception as exc:  # what a refusal raises is the test's to look at
            given = exc
    finally:
        was_opened = opened.is_set()
        # a reader held until the writer is done: its open() ends whenever it comes
        reader = os.open(fifo, os.O_RDONLY | os.O_NONBLOCK)
        try:
            waits.joined(writer, "the pipe's writer")
        finally:
            os.close(reader)
    return given, was_opened


@pytest.fixture
def pipe_read() -> PipeRead:
    """:func:`_read_beside_a_writer`: a test's check that a command never opens a pipe it
    was given (``validate``'s hint, ``monitor``'s record, ``eval --from``'s results)."""
    return _read_beside_a_writer


class SocketsMade:
    """The ``socket`` module as one module of the product (or pyserial's) sees it in a test,
    each socket it makes kept in :attr:`made`: a test of an error path sees every one
    closed, not left to the garbage collector (whose ``ResourceWarning`` fails whichever
    test is running when it collects them). Every other name is the module's."""

    def __init__(self) -> None:
        self.made: list[socket.socket] = []

    def socket(self, *args: Any, **kwargs: Any) -> socket.socket:
        sock = socket.socket(*args, **kwargs)
        self.made.append(sock)
        return sock

    def create_connection(self, *args: Any, **kwargs: Any) -> socket.socket:
        sock = socket.create_connection(*args, **kwargs)
        self.made.append(sock)
        return sock

    def all_closed(self) -> bool:
        """Whether it made a socket and closed each one it made."""
        return bool(self.made) and all(sock.fileno() == -1 for sock in self.made)

    def __getattr__(self, name: str) -> Any:
        return getattr(socket, name)


@pytest.fixture
def sockets_made(monkeypatch: pytest.MonkeyPatch) -> Callable[[ModuleType], SocketsMade]:
    """``sockets_made(module)``: the :class:`SocketsMade` that ``module``'s name ``socket``
    is, for the test."""

    def watch(module: ModuleType) -> SocketsMade:
        made = SocketsMade()
        monkeypatch.setattr(module, "socket", made)
        return made

    return watch


#: How long the threads a test module started are waited for to end, after the module,
#: before they are said left running: a thread told to stop ends in milliseconds on an idle
#: machine (the suite's hang bound)
LEFT_RUNNING_S = HANG_S


#: the descriptors :class:`Leftovers` watches, by how ``/proc/self/fd`` names them: sockets
#: and ptys. Not files nor pipes: the standard library and others keep some open for the
#: process on purpose (matplotlib its fonts, multiprocessing its resource tracker's pipe)
WATCHED = ("socket:", "/dev/pts/", "/dev/ptmx")


#: threads a library starts once for the whole process and keeps, by their names' start:
#: Dask's offload pool (``distributed.utils._offload_executor``), made by whichever module
#: uses Dask first
PROCESS_THREADS = ("Dask-Offload",)


def _threads() -> set[threading.Thread]:
    return {t for t in threading.enumerate() if not t.name.startswith(PROCESS_THREADS)}


def _descriptors() -> dict[int, str]:
    """This process's open file descriptors, each with what it names (``socket:[N]``, a
    pty's path, ``pipe:[N]``, a file's path); ``{}`` where ``/proc/self/fd`` is not."""
    held: dict[int, str] = {}
    with contextlib.suppress(OSError):
        for name in os.listdir("/proc/self/fd"):
            with contextlib.suppress(OSError):
                held[int(name)] = os.readlink(f"/proc/self/fd/{name}")
    return held


class Leftovers:
    """What a test module left behind in this process: threads still running and file
    descriptors (:data:`WATCHED`: sockets, ptys) still open after its last test and its
    own fixtures ended. A socket left to the garbage collector fails, with its
    ``ResourceWarning``, whichever test runs when the collector comes (CI's failure of
    session 40, a test that passed alone); a thread or a pty left open is a later test's
    surprise. What a session-scoped fixture holds (a browser, one simulator for the
    session) is set up inside the first module that uses it and held on purpose: its
    threads and descriptors are not counted (:meth:`pytest_fixture_setup`)."""

    def __init__(self) -> None:
        self.sessions_threads: set[threading.Thread] = set()
        self.sessions_descriptors: set[tuple[int, str]] = set()

    @pytest.hookimpl(hookwrapper=True)
    def pytest_fixture_setup(self, fixturedef: pytest.FixtureDef[Any]) -> Generator[None]:
        if fixturedef.scope != "session":
            yield
            return
        threads, descriptors = _threads(), _descriptors().items()
        yield
        self.sessions_threads |= _threads() - threads
        self.sessions_descriptors |= set(_descriptors().items()) - set(descriptors)

    def left(self, threads: set[threading.Thread], descriptors: dict[int, str]) -> list[str]:
        """What is held now that was not when ``threads`` and ``descriptors`` were. A socket
        dropped unclosed in a reference cycle is still open here, until the collector comes
        (no collection is forced: 80 ms of CPU a module, where the rest costs 0.3 ms)."""
        said: list[str] = []
        deadline = time.monotonic() + LEFT_RUNNING_S
        for thread in sorted(_threads() - threads - self.sessions_threads, key=str):
            thread.join(max(deadline - time.monotonic(), 0.0))  # ends as soon as it ends
            if thread.is_alive():
                said.append(f"the thread {thread.name!r} ({thread!r})")
        now = set(_descriptors().items()) - set(descriptors.items()) - self.sessions_descriptors
        said += [f"fd {fd}: {what}" for fd, what in sorted(now) if what.startswith(WATCHED)]
        return said


#: the name :class:`Leftovers` is registered by
LEFTOVERS = "roomba-bt-leftovers"


@pytest.fixture(scope="module", autouse=True)
def _nothing_left_behind(request: pytest.FixtureRequest) -> Iterator[None]:
    """Each test module ends with no thread of its own running and no descriptor of its own
    open (:class:`Leftovers`): else its last test errs at teardown, naming them. A module
    whose tests leave a thread on purpose (a behaviour's ``terminate()`` that never returns,
    which the run's end goes on without) says so and why:
    ``pytestmark = pytest.mark.leaves_behind("why")``."""
    leftovers: Leftovers = request.config.pluginmanager.get_plugin(LEFTOVERS)
    threads, descriptors = _threads(), _descriptors()
    yield
    if request.node.get_closest_marker("leaves_behind") is not None:
        return
    if left := leftovers.left(threads, descriptors):
        pytest.fail(f"{request.node.name} left behind: " + "; ".join(left), pytrace=False)
