"""The command's own stdout and stderr, made so that writing to them never ends a command.

Over SSH, from cron, under systemd or into a pipe, the streams fail in ways a terminal never
does, and each, unguarded, ends the command at the first ``print``, before or after the
run, with the wrong exit code: ``| head -5`` closes the pipe (``BrokenPipeError``: exit 0 for
a mission that never connected, an invalid mission, a replay that differs), ``> /dev/full``
fills the disk (``OSError`` traceback, exit 1), ``>&-`` leaves ``sys.stdout`` None (py_trees
reads its ``encoding`` at import: an ``AttributeError`` traceback in every subcommand), and
an ASCII or Latin-1 stdout cannot encode the report's ``✓`` or ``m²`` (``UnicodeEncodeError``
after a run that succeeded: exit 1).

:func:`guard_std_streams` wraps both in a :class:`GuardedStream`: a write that fails is noted
(:attr:`GuardedStream.failure`), the stream's file descriptor is pointed at ``os.devnull`` (so
that what is still buffered, and the interpreter's flush at exit, go nowhere instead of
failing again) and the command goes on, its exit code its outcome's (Python's advice for
SIGPIPE, https://docs.python.org/3/library/signal.html#note-on-sigpipe, applied per write).
A character the stream's encoding lacks is written as ``\\u2713`` (``backslashreplace``); the
run's report picks ASCII symbols itself where the stream cannot show them
(:func:`roomba_bt.printable.encodes`).
"""

from __future__ import annotations

import contextlib
import os
import sys
import threading
from typing import Any, TextIO, cast

#: Why a stream takes no text: its descriptor was closed before the process started (``>&-``)
CLOSED = "closed"


class GuardedStream:
    """A text stream whose ``write`` and ``flush`` never raise: the first failure is kept in
    :attr:`failure`, and from then on the text is dropped. Everything else (``encoding``,
    ``isatty``, ``fileno``...) is the wrapped stream's.

    ``closed``: the process's descriptor was closed (``>&-``) and ``stream`` stands in for
    it; it fails at the first text written to it, not before: a command that printed nothing
    there (``validate -q``) lost nothing, and says nothing about it."""

    def __init__(self, stream: TextIO, name: str, *, closed: bool = False) -> None:
        self.stream = stream
        self.name = name
        #: why the stream takes no more text (``Broken pipe``, ``No space left on device``,
        #: :data:`CLOSED`, ``I/O operation on closed file.``); None while it works
        self.failure: str | None = None
        #: the failure is the reader gone (EPIPE: ``| head``), which Unix programs keep quiet
        self.reader_gone = False
        #: the command said the failure itself (a run: its outcome on stderr instead)
        self.failure_said = False
        self._closed = closed
        self._lock = threading.Lock()

    def write(self, text: str) -> int:
        if self.failure is None and text:
            if self._closed:
                self.failure = CLOSED
                return len(text)
            try:
                try:
                    return self.stream.write(text)
                except UnicodeEncodeError:  # a stream reconfigure() could not set errors= on
                    self.stream.write(_encodable(text, self.stream))
            except (OSError, ValueError) as exc:
                self._failed(exc)
        return len(text)

    def flush(self) -> None:
        if self.failure is None:
            try:
                self.stream.flush()
            except (OSError, ValueError) as exc:
                self._failed(exc)

    def writelines(self, lines: Any) -> None:
        for line in lines:
            self.write(line)

    def __getattr__(self, name: str) -> Any:
        return getattr(self.stream, name)

    def _failed(self, exc: OSError | ValueError) -> None:
        """Note why, and point the descriptor at ``os.devnull``: the wrapped stream's buffer
        still holds what it could not write, which its next flush (the interpreter's, at
        exit) would fail on again ("Exception ignored ... BrokenPipeError", exit 120)."""
        with self._lock:
            if self.failure is not None:
                return
            self.reader_gone = isinstance(exc, BrokenPipeError)
            if isinstance(exc, OSError):
                self.failure = exc.strerror or str(exc)
            else:  # the stream closed under us (``I/O operation on closed file.``), or other
                self.failure = str(exc) or type(exc).__name__
            discard(self.stream)


def _encodable(text: str, stream: TextIO) -> str:
    """``text`` with what ``stream``'s encoding lacks written as ``\\u2713``, as
    ``errors="backslashreplace"`` writes it."""
    encoding = getattr(stream, "encoding", None) or "ascii"
    try:
        return text.encode(encoding, "backslashreplace").decode(encoding)
    except LookupError:  # an encoding Python does not know: ASCII, which every one has
        return text.encode("ascii", "backslashreplace").decode("ascii")


def discard(stream: TextIO) -> None:
    """From now on, what ``stream``'s file descriptor is written goes to ``os.devnull`` (a
    stream with no descriptor: nothing to do)."""
    with contextlib.suppress(OSError, ValueError, AttributeError):
        fd = stream.fileno()
        devnull = os.open(os.devnull, os.O_WRONLY)
        try:
            os.dup2(devnull, fd)
        finally:
            os.close(devnull)


def _opened(stream: TextIO | None, name: str) -> GuardedStream:
    """``stream`` guarded; None (the descriptor was closed: ``>&-``) is ``os.devnull``, failed
    at its first text (:class:`GuardedStream`'s ``closed``), so py_trees, logging and the
    report find a stream."""
    if stream is None:
        devnull = open(os.devnull, "w", encoding="utf-8")  # noqa: SIM115 (the process's)
        return GuardedStream(devnull, name, closed=True)
    reconfigure = getattr(stream, "reconfigure", None)
    if reconfigure is not None:
        with contextlib.suppress(ValueError, OSError):  # a stream of another kind
            reconfigure(errors="backslashreplace")
    return GuardedStream(stream, name)


def guard_std_streams() -> tuple[GuardedStream, GuardedStream]:
    """``sys.stdout`` and ``sys.stderr`` guarded (:class:`GuardedStream`); once per process,
    before anything imports py_trees or sets up logging."""
    guarded = []
    for name in ("stdout", "stderr"):
        current = getattr(sys, name)
        if not isinstance(current, GuardedStream):
            current = _opened(current, name)
            setattr(sys, name, cast(TextIO, current))
        guarded.append(current)
    return guarded[0], guarded[1]


def failed_stdout(*, saying: bool = False) -> str | None:
    """Why stdout takes no more text, if it is guarded and failed (None: it works, or it is
    not guarded: a program calling :func:`roomba_bt.cli.main` with its own streams).
    ``saying``: the caller says it on stderr, so the command's end does not again
    (:func:`stdout_problem`)."""
    stdout = sys.stdout
    if not isinstance(stdout, GuardedStream):
        return None
    if saying and stdout.failure is not None:
        stdout.failure_said = True
    return stdout.failure


def stdout_problem() -> str | None:
    """What the command says on stderr at its end when its stdout failed, or None: nothing
    when it worked, nor for a reader gone (``| head``: what it wanted, it had)."""
    stdout = sys.stdout
    if not isinstance(stdout, GuardedStream) or stdout.failure is None:
        return None
    if stdout.reader_gone or stdout.failure_said:
        return None
    if stdout.failure == CLOSED:
        return "stdout is closed: what the command printed there is lost"
    return f"cannot write to stdout ({stdout.failure}): the rest of the output is lost"
