"""The suite's one bound on a wait that only guards against a hang, and the waits that use it.

A test waits for things that take milliseconds on an idle machine: a thread told to stop, a
child process's end, an event another thread sets. CI runs the suite on a shared 2-core
machine, where a child's interpreter start alone took over 10 s and a thread was not
scheduled for seconds: fixed bounds of 5, 10, 20 and 30 s failed there by chance (each one a
lost submission), though nothing hung. Each wait here ends as soon as what it waits for
happens, so :data:`HANG_S` costs nothing when all is well and stops only a real hang, and
its failure names what hung (a bare ``assert event.wait(10)`` said ``assert False``).

A bound that is what a test is about (the product's own timeout, on the virtual clock)
is not one of these: it stays the test's own number.
"""

from __future__ import annotations

import contextlib
import os
import select
import socket
import subprocess
import threading
import time
from collections.abc import Callable, Coroutine, Iterator
from typing import IO, Any, TypeVar

#: The most a test waits for something that only a hang would keep from happening: generous
#: for a loaded 2-core machine (six busy loops on its 2 cores kept a monitor run from its
#: 1000th virtual frame for 20 s), never reached when all is well.
HANG_S = 120.0


def waited(event: threading.Event, what: str, within: float = HANG_S) -> None:
    """Return once ``event`` is set; fail, saying ``what`` never happened, if it is not
    within ``within`` seconds."""
    if not event.wait(within):
        raise AssertionError(f"{what}: not within {within:g} s (hung?)")


def until(condition: Callable[[], bool], what: str, within: float = HANG_S) -> None:
    """Return once ``condition()`` holds, looking every millisecond: for a state another
    thread or the kernel changes with no event to wait on. Fail, saying ``what`` never
    came, if it does not within ``within`` seconds."""
    deadline = time.monotonic() + within
    while not condition():
        if time.monotonic() > deadline:
            raise AssertionError(f"{what}: not within {within:g} s (hung?)")
        time.sleep(0.001)


def lines(
    stream: IO[str], ends: Callable[[str], bool], what: str, within: float = HANG_S
) -> list[str]:
    """The lines a child writes on ``stream`` (its text pipe), up to and including the first
    that ``ends`` holds for, or up to the pipe's end (the last then has no newline: ``""``
    where nothing came after the last line). Fail, saying ``what`` never came and what was
    written meanwhile, if neither comes within ``within`` seconds: a ``readline()`` waits
    for ever on a child that hangs before its line (session 42 found a dozen).

    Read a byte at a time from the pipe's descriptor, as the child writes it: the stream's
    buffer is never filled past the line, so what follows it is still the pipe's for the
    ``communicate()`` after (the lines before it are a few short ones)."""
    deadline = time.monotonic() + within
    fd = stream.fileno()
    got: list[str] = []
    pending = bytearray()
    while True:
        left = deadline - time.monotonic()
        ready, _, _ = select.select([fd], [], [], max(left, 0.0))
        if not ready or left < 0:  # a child that writes on and on, never the line, too
            said = "".join(got) + pending.decode(errors="replace")
            raise AssertionError(f"{what}: not within {within:g} s (hung?); it wrote {said!r}")
        byte = os.read(fd, 1)
        pending += byte
        if byte in (b"\n", b""):
            got.append(pending.decode(stream.encoding or "utf-8", errors="replace"))
            pending.clear()
            if not byte or ends(got[-1]):
                return got


def line(stream: IO[str], what: str, within: float = HANG_S) -> str:
    """The next line a child writes on ``stream`` (:func:`lines`), ``""`` at the pipe's end."""
    return lines(stream, lambda _: True, what, within)[-1]


def joined(thread: threading.Thread, what: str, within: float = HANG_S) -> None:
    """Return once ``thread`` has ended; fail, saying ``what`` hung, if it runs on after
    ``within`` seconds."""
    thread.join(within)
    if thread.is_alive():
        raise AssertionError(f"{what}: {thread.name!r} still ran after {within:g} s (hung?)")


_Result = TypeVar("_Result")


def awaited(
    coroutine: Callable[[], Coroutine[Any, Any, _Result]], what: str, within: float = HANG_S
) -> _Result:
    """What ``coroutine()`` returns, run to its end on an event loop of its own in a thread of
    its own (a page's reader: the browser tests' sync Playwright leaves this thread's loop
    running, and ``asyncio.run`` refuses to start under it); fail, saying ``what`` hung, if
    it runs on after ``within`` seconds. What it raised is raised here (in the thread it was
    printed, and the test failed on an empty answer)."""
    import asyncio

    answers: list[_Result] = []
    raised: list[BaseException] = []

    def run() -> None:
        try:
            answers.append(asyncio.run(asyncio.wait_for(coroutine(), within)))
        except BaseException as error:  # handed to the test's thread
            raised.append(error)

    thread = threading.Thread(target=run, name=what, daemon=True)
    thread.start()
    joined(thread, what, within + 5)  # the wait_for's bound, then its cancellation
    if raised:
        raise raised[0]
    return answers[0]


def ended(proc: subprocess.Popen[str], ceiling: float = HANG_S) -> tuple[str, str]:
    """What ``proc`` wrote on stdout and stderr, once it ended. Still running at
    ``ceiling``: SIGTERM (a run closes its port and says why; SIGKILL would leave a pty in
    the kernel's exclusive mode for the tests after), SIGKILL only if that is not heeded,
    and the test fails with its command line and what it said."""
    try:
        return proc.communicate(timeout=ceiling)
    except subprocess.TimeoutExpired:
        proc.terminate()
        try:
            out, err = proc.communicate(timeout=ceiling)
        except subprocess.TimeoutExpired:
            proc.kill()
            out, err = proc.communicate()
    raise AssertionError(f"{proc.args} still ran after {ceiling:g} s; it said: {out}{err}")


def finished(args: list[str], ceiling: float = HANG_S) -> subprocess.CompletedProcess[str]:
    """``args`` run to its end, its output read through text pipes (:func:`ended`:
    ``subprocess.run``'s timeout ends a late one with SIGKILL and loses what it said)."""
    with child(args, stdout=subprocess.PIPE, stderr=subprocess.PIPE) as proc:
        out, err = ended(proc, ceiling)
    return subprocess.CompletedProcess(proc.args, proc.returncode, out, err)


@contextlib.contextmanager
def child(args: list[str], within: float = HANG_S, **popen: Any) -> Iterator[subprocess.Popen[str]]:
    """``subprocess.Popen(args, text=True, **popen)`` for the ``with`` block, ended after it
    within ``within`` s. ``with Popen(...)`` waits for the child with no bound as it leaves
    the block: a test that failed before its child ended (a line that never came) held CI
    there for ever. A child still running after the block is told to stop (SIGTERM, as
    :func:`ended`), then killed; one that not even SIGKILL ends fails the test."""
    proc: subprocess.Popen[str] = subprocess.Popen(args, text=True, **popen)
    try:
        yield proc
    finally:
        for stream in (proc.stdin, proc.stdout, proc.stderr):
            if stream is not None:
                stream.close()
        for stop in (proc.terminate, proc.kill):
            if proc.poll() is not None:
                break
            stop()
            with contextlib.suppress(subprocess.TimeoutExpired):
                proc.wait(timeout=within)
        if proc.poll() is None:
            raise AssertionError(f"{proc.args} still ran after SIGKILL and {within:g} s (hung?)")


def reaped(pid: int, what: str, within: float = HANG_S) -> int:
    """The exit code of the child ``pid`` once it has ended, looking every millisecond; fail,
    saying ``what`` hung, if it runs on after ``within`` s. A bare ``os.waitpid(pid, 0)``
    waits for ever, even after a SIGKILL (a child stuck in the kernel, in a pty's close, is
    not ended by it)."""
    found: list[int] = []

    def gone() -> bool:
        done, status = os.waitpid(pid, os.WNOHANG)
        if done:
            found.append(os.waitstatus_to_exitcode(status))
        return bool(done)

    until(gone, what, within)
    return found[0]


def accepted(listener: socket.socket, what: str, within: float = HANG_S) -> socket.socket:
    """The next connection ``listener`` takes (blocking, as ``accept()`` returns it); fail,
    saying ``what`` never came, if none does within ``within`` s: a bare ``accept()`` on a
    listener without a timeout waits for ever for a client that never connects."""
    listener.settimeout(within)
    try:
        return listener.accept()[0]
    except TimeoutError:
        raise AssertionError(f"{what}: not within {within:g} s (hung?)") from None


def received(source: socket.socket | int, size: int, what: str, within: float = HANG_S) -> bytes:
    """Up to ``size`` bytes from a socket or a descriptor (a pty's master), once it has any
    (``b""`` at its end); fail, saying ``what`` never came, if nothing does within
    ``within`` s: a bare ``recv()`` or ``os.read()`` waits for ever on a far end that never
    writes. A socket keeps the timeout (its sends are bounded by it too)."""
    if isinstance(source, socket.socket):
        source.settimeout(within)
        try:
            return source.recv(size)
        except TimeoutError:
            raise AssertionError(f"{what}: not within {within:g} s (hung?)") from None
    if not select.select([source], [], [], within)[0]:
        raise AssertionError(f"{what}: not within {within:g} s (hung?)")
    return os.read(source, size)
