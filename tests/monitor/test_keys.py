"""The monitor's terminal keys (``p`` pause, ``r`` resume, ``q`` stop), typed on a real pty
that is the run's controlling terminal, the run in its foreground; what they did is read
from the run's record, where the monitor notes each act."""

from __future__ import annotations

import contextlib
import json
import os
import re
import select
import signal
import sys
import time
import urllib.request
from collections.abc import Iterator
from pathlib import Path

import pytest
from quoted import assert_quoted  # tests/quoted.py: the docs' quotes
from waits import HANG_S, reaped  # tests/waits.py: a hang's bound

from roomba_bt.cli import main

pty = pytest.importorskip("pty")
termios = pytest.importorskip("termios")

SHUTTLE = Path(__file__).resolve().parent / "missions" / "shuttle.yaml"  # drives for ever


#: the terminals a test opened, closed after it (:func:`_terminals_closed`)
_OPENED: list[Terminal] = []


@pytest.fixture(autouse=True)
def _terminals_closed() -> Iterator[None]:
    yield
    while _OPENED:
        _OPENED.pop().close()


class Terminal:
    """The CLI on a pty of its own (``pty.fork``: its session, its controlling terminal),
    closed after the test (its pty's side was left open, three a module)."""

    def __init__(self, *args: str, cwd: Path, stderr: Path | None = None) -> None:
        """``stderr``: the run's log into that file, its hang-ups ignored (``trap '' HUP``:
        a run meant to outlive its SSH session), so that what it says once its terminal is
        gone can be read."""
        self.pid, self.fd = pty.fork()
        if self.pid == 0:  # the child: the run, in the terminal's foreground
            os.chdir(cwd)
            if stderr is not None:
                signal.signal(signal.SIGHUP, signal.SIG_IGN)  # kept ignored across exec
                os.dup2(os.open(stderr, os.O_WRONLY | os.O_CREAT | os.O_APPEND), 2)
            os.execv(sys.executable, [sys.executable, "-m", "roomba_bt.cli", *args])
        self.screen = ""
        self.hung_up = False
        _OPENED.append(self)

    def close(self) -> None:
        """The run ended (killed if a failed test left it running) and its pty closed."""
        with contextlib.suppress(ChildProcessError):  # reaped already by :meth:`exited`
            if os.waitpid(self.pid, os.WNOHANG) == (0, 0):
                os.kill(self.pid, signal.SIGKILL)
                reaped(self.pid, "the run left running by a failed test, killed")
        self.hang_up()

    def hang_up(self) -> None:
        """This side of the pty closed (once): the terminal gone, as an SSH session drops."""
        if not self.hung_up:
            self.hung_up = True
            os.close(self.fd)

    def read(self, timeout: float) -> bool:
        """What the run wrote within ``timeout`` s, onto :attr:`screen`; False once it ended."""
        ready, _, _ = select.select([self.fd], [], [], timeout)
        if ready:
            try:
                self.screen += os.read(self.fd, 65536).decode(errors="replace")
            except OSError:  # the run ended: its side of the pty closed
                return False
        return True

    def until(self, text: str, timeout: float = HANG_S) -> None:
        deadline = time.monotonic() + timeout
        while text not in self.screen:
            assert time.monotonic() < deadline, f"never saw {text!r} in {self.screen!r}"
            if not self.read(0.05):
                break

    def type(self, key: str) -> None:
        os.write(self.fd, key.encode())

    def exited(self, within: float = HANG_S) -> int:
        """The run's exit code once it has ended, what it still writes read onto
        :attr:`screen` meanwhile (a full pty would hold it). Still running after ``within``
        s: the test fails, saying so and what the terminal showed (a bare ``waitpid`` held
        a hung run's test, and CI, for ever); :meth:`close` then kills it."""
        deadline = time.monotonic() + within
        while (ended := os.waitpid(self.pid, os.WNOHANG)) == (0, 0):
            assert time.monotonic() < deadline, (
                f"the run still ran {within:g} s after it was told to stop; "
                f"the terminal showed {self.screen[-2000:]!r}"
            )
            if self.hung_up or not self.read(0.05):  # no terminal, or its side closed
                time.sleep(0.01)
        return os.waitstatus_to_exitcode(ended[1])


def _until_in(log: Path, text: str, timeout: float = HANG_S) -> None:
    """Wait until ``text`` is in the file ``log`` (a run's stderr)."""
    deadline = time.monotonic() + timeout
    while text not in log.read_text(errors="replace"):
        assert time.monotonic() < deadline, log.read_text(errors="replace")[-2000:]
        time.sleep(0.05)


def _acts(record: Path) -> list[str]:
    notes = [json.loads(line) for line in record.read_text().splitlines()[1:]]
    return [next(iter(n["note"])) for n in notes if n.get("d") == "note"]


def test_p_pauses_r_resumes_q_stops_and_the_terminal_is_given_back(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    record = tmp_path / "run.jsonl"
    run = Terminal(
        "run", str(SHUTTLE), "--monitor", "127.0.0.1:0", "--display", "log",
        "--record", str(record), "--timeout", "60s", cwd=tmp_path,
    )  # fmt: skip
    run.until("keys: p pause, r resume, n step, q stop")
    run.until("drive(velocity=100 mm/s, distance=3 cm) -> RUNNING")
    run.type("p")
    deadline = time.monotonic() + HANG_S
    while not record.exists() or "pause" not in _acts(record):  # noted as it is done
        assert time.monotonic() < deadline, "p did not pause"
        run.read(0.05)
    run.until("monitor: pause (paused by the operator)")  # the terminal said nothing of it
    run.type("r")
    run.until("monitor: resume (resumed by the operator)")
    run.type("q")
    run.until("outcome      INTERRUPTED (stopped by the operator)")
    assert run.exited() == 130
    settings = termios.tcgetattr(run.fd)[3]  # the terminal as the run found it: cooked
    assert settings & termios.ICANON and settings & termios.ECHO
    # the operator's acts; the tick guard's drive 0 before the tree's stop, if the wheels
    # turned at the stop, is a note of its own
    acts = [act for act in _acts(record) if act != "tick_guard"]
    assert acts == ["pause", "resume", "ended"]  # the run's end note last: q, the stop
    # its replay says how the recorded run ended (docs/runtime.md)
    capsys.readouterr()
    assert main(["replay", str(record), "--display", "none"]) == 0
    out = capsys.readouterr().out
    assert_quoted("docs/runtime.md", "replay: the recorded run was stopped by", out, numbers=True)


def test_a_key_that_does_nothing_says_why(tmp_path: Path) -> None:
    """``r`` while running and a key that is none of the four were passed over without a
    word; each gets a status line."""
    run = Terminal(
        "run", str(SHUTTLE), "--monitor", "127.0.0.1:0", "--display", "log",
        "--timeout", "60s", cwd=tmp_path,
    )  # fmt: skip
    run.until("keys: p pause, r resume, n step, q stop")
    run.until("drive(velocity=100 mm/s, distance=3 cm) -> RUNNING")
    run.type("r")
    run.until("monitor: key r (resume) refused: the run is not paused")
    run.type("n")
    run.until("monitor: key n (step) refused: step needs a paused run: pause first")
    run.type("x")
    run.until("monitor: key 'x' does nothing (keys: p pause, r resume, n step, q stop)")
    run.type("q")
    run.until("outcome      INTERRUPTED (stopped by the operator)")
    assert run.exited() == 130
    assert_quoted("docs/monitor.md", "monitor: key r (resume) refused", run.screen)
    assert_quoted("docs/monitor.md", "monitor: key 'x' does nothing", run.screen)


def test_a_read_only_page_leaves_the_keys_to_the_operator(tmp_path: Path) -> None:
    """``--monitor-readonly`` turned the terminal's keys off too: "LAN viewers read-only, me
    at the keyboard in control" was not possible. The keys are the local operator's: the
    page refuses every control (403), and ``p`` still pauses, ``q`` still stops."""
    import re
    import urllib.error
    import urllib.request

    run = Terminal(
        "run", str(SHUTTLE), "--monitor", "127.0.0.1:0", "--monitor-readonly",
        "--display", "log", "--timeout", "60s", cwd=tmp_path,
    )  # fmt: skip
    run.until("keys: p pause, r resume, n step, q stop")
    port = re.search(r"monitor: http://127\.0\.0\.1:(\d+)/", run.screen)
    assert port, run.screen
    request = urllib.request.Request(
        f"http://127.0.0.1:{port.group(1)}/api/control", data=b'{"action": "pause"}',
        headers={"Content-Type": "application/json"}, method="POST",
    )  # fmt: skip
    with pytest.raises(urllib.error.HTTPError) as refused:
        urllib.request.urlopen(request, timeout=HANG_S)
    refused.value.close()
    assert refused.value.code == 403
    run.until("drive(velocity=100 mm/s, distance=3 cm) -> RUNNING")
    run.type("p")
    run.until("monitor: pause (paused by the operator)")
    run.type("q")
    run.until("outcome      INTERRUPTED (stopped by the operator)")
    assert run.exited() == 130


def test_a_terminal_that_hangs_up_turns_the_keys_off_once(tmp_path: Path) -> None:
    """An SSH session dropped under a run that outlives it (SIGHUP ignored): its terminal
    reads as the end of the file, at once and for ever. Each empty read was taken for a key
    that "does nothing", a log line each, about 6 000 a second for the rest of the run (10 MB
    of log in 15 s, a core busy), and the keys' thread raised as it ended (a traceback in
    the log). The keys go off, said once; the page's stop still ends the run."""
    log = tmp_path / "stderr.log"
    run = Terminal(
        "run", str(SHUTTLE), "--monitor", "127.0.0.1:0", "--display", "log",
        "--timeout", "60s", cwd=tmp_path, stderr=log,
    )  # fmt: skip
    run.until("keys: p pause, r resume, n step, q stop")
    port = re.search(r"monitor: http://127\.0\.0\.1:(\d+)/", run.screen)
    assert port, run.screen
    # the keys are read once a key typed is said (typed before their thread set the
    # terminal up, it is flushed: typed again until then)
    deadline = time.monotonic() + HANG_S
    while "key 'x' does nothing" not in log.read_text(errors="replace"):
        assert time.monotonic() < deadline, log.read_text(errors="replace")[-2000:]
        run.type("x")
        run.read(0.5)
    typed = log.read_text(errors="replace").count("does nothing")
    run.hang_up()  # the terminal hangs up
    _until_in(log, "keys: off (the terminal hung up")
    time.sleep(1.0)  # a spinning reader writes thousands of lines meanwhile
    said = log.read_text(errors="replace")
    assert said.count("keys: off (the terminal hung up") == 1
    assert said.count("does nothing") == typed, said.count("does nothing")
    assert "Traceback" not in said and "Exception in thread" not in said
    assert_quoted("docs/monitor.md", "monitor: keys: off", said)
    base = f"http://127.0.0.1:{port.group(1)}"
    with urllib.request.urlopen(f"{base}/api/state", timeout=HANG_S) as answer:
        run_id = json.load(answer)["header"]["run"]["id"]
    stop = urllib.request.Request(
        f"{base}/api/control", data=json.dumps({"action": "stop", "run": run_id}).encode(),
        headers={"Content-Type": "application/json"}, method="POST",
    )  # fmt: skip
    with urllib.request.urlopen(stop, timeout=HANG_S) as answer:
        assert answer.status == 202
    assert run.exited() == 130
    said = log.read_text(errors="replace")
    assert "Traceback" not in said and "Exception in thread" not in said, said[-3000:]
