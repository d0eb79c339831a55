"""Turning SIGTERM, SIGHUP, SIGTSTP and SIGQUIT into an exception, so that ``with Connection(...)``
stops the robot; and one signal per run (:class:`InterruptGuard`: a second Ctrl-C waits for
the safe stop).

Python turns SIGINT into :class:`KeyboardInterrupt`, which unwinds ``with`` blocks and so runs
:meth:`~roomba_bt.robot.connection.Connection.close`. SIGTERM (``kill``, systemd, a container
stopping) and SIGHUP (the terminal gone: an SSH session to the robot's computer dropped, its
window closed) would end the process without unwinding anything, SIGQUIT (Ctrl-\\, the key
pressed when Ctrl-C seems slow) would end it at once with a core dump, and SIGTSTP (Ctrl-Z)
would suspend it, each leaving the robot driving in Safe mode: the Open Interface has no
command timeout. Inside :func:`sigterm_raises` they raise :class:`Terminated` instead; the
previous handlers come back on the way out. A signal the process was started with ignored
(``nohup``'s SIGHUP) stays ignored: :data:`IGNORED_AT_START`.
"""

from __future__ import annotations

import contextlib
import logging
import math
import os
import select
import signal
import sys
import threading
from collections.abc import Callable, Iterator
from types import FrameType
from typing import Any, ClassVar

from roomba_bt._entry import DELIVERED_BY, EARLY_SIGNALS, kept, note_dropped
from roomba_bt._entry import Terminated as Terminated  # its home before the entry point took it
from roomba_bt._entry import delivered as delivered

log = logging.getLogger(__name__)

#: Signals whose usual meaning leaves a robot on the wall clock driving, so on the wall clock
#: they end the run with its safe stop (decided): Ctrl-Z (a suspended process cannot stop its
#: robot, which would drive on with its last Drive until ``fg``). Where nothing drives on the
#: wall clock (an evaluation, ``--fast``, a replay) it keeps its meaning. POSIX only. Ctrl-\
#: (SIGQUIT, quit at once with a core dump) is not one: it ends every run and every
#: command as SIGTERM does (:data:`~roomba_bt._entry.EARLY_SIGNALS`): an
#: operator who presses it wants a stop, and a ``--fast`` run's record closed whole.
WALL_CLOCK_SIGNALS: tuple[int, ...] = tuple(
    getattr(signal, name) for name in ("SIGTSTP",) if hasattr(signal, name)
)

#: The terminal's own stops, Ctrl-Z's kin: a process in the background is stopped by SIGTTOU
#: when it writes to a terminal set with ``stty tostop`` or changes the terminal's settings,
#: and by SIGTTIN when it reads from it, its robot driving on. On the wall clock they are
#: ignored: the write goes through (POSIX), a read fails with EIO.
TERMINAL_STOP_SIGNALS: tuple[int, ...] = tuple(
    getattr(signal, name) for name in ("SIGTTOU", "SIGTTIN") if hasattr(signal, name)
)


@contextlib.contextmanager
def terminal_stops_ignored(ignore: bool = True) -> Iterator[None]:
    """Within the block the terminal's stops (:data:`TERMINAL_STOP_SIGNALS`) are ignored (if
    ``ignore``, and in the main thread: signal handlers are its), as a run on the wall clock
    has them (:class:`InterruptGuard`): a run in a worker thread (``RunStack.ticks()``),
    whose guard can set no handler, is watched so by the program's thread. A background job
    of a ``stty tostop`` terminal whose loop body wrote a line was stopped whole (SIGTTOU),
    the robot driving on with its last command."""
    if not ignore or threading.current_thread() is not threading.main_thread():
        yield
        return
    put_back = terminal_stops_kept()
    for signum in TERMINAL_STOP_SIGNALS:
        signal.signal(signum, signal.SIG_IGN)
    try:
        yield
    finally:
        put_back()


def terminal_stops_kept() -> Callable[[], None]:
    """The terminal's stops (:data:`TERMINAL_STOP_SIGNALS`) as they are now, and a call that
    puts them back: a run's handlers are given back before its report (a signal then is the
    report's, not the run's), and a run on the wall clock held these ignored; given back
    too, the report written from the background to a ``stty tostop`` terminal stopped the
    process (SIGTTOU) while a script waited for its exit."""
    now = {signum: signal.getsignal(signum) for signum in TERMINAL_STOP_SIGNALS}

    def put_back() -> None:
        for signum, handler in now.items():
            with contextlib.suppress(ValueError, TypeError):  # not the main thread; unknown
                signal.signal(signum, handler)

    return put_back


#: The signals that end a run with its safe stop: those that end the command from its first
#: line (Ctrl-C, ``kill``/systemd, the terminal gone, Ctrl-\:
#: :data:`~roomba_bt._entry.EARLY_SIGNALS`), and :data:`WALL_CLOCK_SIGNALS`.
ENDING_SIGNALS: tuple[int, ...] = (*EARLY_SIGNALS, *WALL_CLOCK_SIGNALS)


#: The ending signals this process was started with ignored, which stay so (decided): ``nohup``
#: starts a run with SIGHUP ignored, so that a multi-hour run outlives the SSH session that
#: started it. Only SIGHUP: it is the one a program is started with ignored on purpose. A
#: shell without job control (a script's ``roomba-bt run ... &``) starts its background jobs
#: with SIGINT and SIGQUIT ignored too, by accident of job control; a script's ``kill -INT``
#: or ``timeout -s INT`` then asks the run to stop, and a stop asked of a process that
#: drives a robot is taken (kept ignored, the robot would drive on for the whole mission,
#: and the run exit 0). Never SIGTERM either: ``kill``, systemd and
#: a container's stop send it, and their next word is SIGKILL, which would leave the robot
#: driving. Read when this module is first imported, before any handler of ours (a run puts
#: its previous handlers back).
IGNORED_AT_START: frozenset[int] = frozenset(
    signum
    for signum in ENDING_SIGNALS
    if getattr(signal, "SIGHUP", None) == signum and signal.getsignal(signum) is signal.SIG_IGN
)


def _has_a_terminal() -> bool:
    """Whether this process has a controlling terminal (``/dev/tty`` opens): one started by
    systemd, cron or ``setsid`` has none, and a SIGHUP then comes from a program, not from a
    terminal hung up."""
    try:
        os.close(os.open("/dev/tty", os.O_RDONLY | getattr(os, "O_NOCTTY", 0)))
    except OSError:
        return False
    return True


#: Whether the process had a controlling terminal when this module was first imported, as
#: it starts: after an SSH session drops, its terminal is gone, and asking then would say none
HAD_A_TERMINAL = _has_a_terminal()


def _taken(signals: tuple[int, ...]) -> tuple[int, ...]:
    """``signals`` less those the process keeps ignored (:data:`IGNORED_AT_START`)."""
    return tuple(signum for signum in signals if signum not in IGNORED_AT_START)


#: How a run's summary names SIGINT: a process cannot tell who sent it, a terminal's Ctrl-C or
#: another process's ``kill -INT`` (a script's ``kill -INT $!``, ``timeout -s INT``), so the
#: words are true of both; "Ctrl-C" first, as a run's reason has read since the start, so
#: ``grep 'INTERRUPTED (Ctrl-C'`` finds such runs still (``Ctrl-C`` alone would be untrue
#: of a script's ``kill -INT``)
SIGINT_SAID = "Ctrl-C or kill -INT (SIGINT)"
#: ... and the other two a key sends, alike (the key alone, ``Ctrl-\ (SIGQUIT)``, would be
#: untrue of a script's ``kill -QUIT``)
SIGQUIT_SAID = "Ctrl-\\ or kill -QUIT (SIGQUIT)"
SIGTSTP_SAID = "Ctrl-Z or kill -TSTP (SIGTSTP)"


def interrupt_reason(interrupt: KeyboardInterrupt) -> str:
    """How a run's summary names the signal whose interrupt ``interrupt`` is: a
    :class:`Terminated`'s signal (:func:`signal_reason`), else SIGINT's
    (:data:`SIGINT_SAID`)."""
    if isinstance(interrupt, Terminated):
        return signal_reason(interrupt.signum)
    return SIGINT_SAID


def signal_reason(signum: int, *, terminal: bool | None = None) -> str:
    """How a run's summary names the signal that ended it (SIGINT: :data:`SIGINT_SAID`). A
    SIGHUP is a terminal's hang-up only where the process had one (``terminal``;
    :data:`HAD_A_TERMINAL` when not given): under a service or cron it was sent by a program,
    and "the terminal was closed" sent the reader of the evening's log after an SSH session
    that never was."""
    if signum == getattr(signal, "SIGHUP", None):
        if HAD_A_TERMINAL if terminal is None else terminal:
            return "SIGHUP: the terminal was closed (an SSH session dropped?)"
        return (
            "SIGHUP, with no terminal to hang up: sent by a program (kill -HUP, a logrotate "
            "postrotate script, systemctl reload?)"
        )
    if signum == signal.SIGINT:
        return SIGINT_SAID
    if signum == getattr(signal, "SIGTSTP", None):
        return f"{SIGTSTP_SAID}: a suspended run could not stop its robot, so it ended"
    if signum == getattr(signal, "SIGQUIT", None):
        return f"{SIGQUIT_SAID}: the run ended with its safe stop, not at once"
    return signal.Signals(signum).name


def raise_terminated(signum: int, frame: FrameType | None) -> None:
    """A signal handler: the signal raises :class:`Terminated` in the main thread (the CLI
    installs it for SIGTERM and SIGHUP as the process starts, before a run has its own),
    marked as a signal's (:func:`signal_delivered`), at a safe point
    (:data:`interrupts_deferred`); kept in case Python drops it
    (:func:`~roomba_bt._entry.kept`)."""
    raised_when_safe(kept(delivered(Terminated(signum), signum)))


def raise_interrupt(signum: int, frame: FrameType | None) -> None:
    """A signal handler for SIGINT: Python's own (a :class:`KeyboardInterrupt`), marked as a
    signal's (:func:`signal_delivered`), at a safe point (:data:`interrupts_deferred`);
    :func:`interrupts_told_apart` installs it; kept as :func:`raise_terminated` keeps it."""
    raised_when_safe(kept(delivered(KeyboardInterrupt(), signum)))


class InterruptsDeferred:
    """A block of the main thread that an interrupt of ours never lands inside: one a
    signal brings meanwhile is raised where the block ends (its safe point), or at once
    outside one. For a write whose steps must all be done or none: ``GzipFile.write``
    writes the compressed text to the file, then adds its length and CRC-32 to what the
    gzip trailer says; a SIGTERM that raises between the two (a ``--fast`` run writes its
    compressed record all the time) leaves a trailer that does not match the text, and
    ``gzip -t`` and replay refuse the whole record (3 of 17 signalled ``--fast`` ``.gz``
    records were so, undeferred). A flag the handlers read, not the signals held in the thread's
    mask (:func:`~roomba_bt.robot.ending.signals_deferred`): that is two system calls a
    block, and a signal already caught whose handler runs as the mask is set raises before
    the block that would give the mask back begins. Only our handlers wait for it (those of
    this module); Python's own SIGINT handler, outside a run and
    :func:`interrupts_told_apart`, raises as ever. Blocks nest; another thread's count
    nothing (a signal's handler runs in the main thread, and raises there)."""

    #: the main thread's blocks now open
    depth: ClassVar[int] = 0
    #: the first interrupt a signal brought inside them, raised when the last one ends
    pending: ClassVar[KeyboardInterrupt | None] = None

    def __enter__(self) -> None:
        if threading.get_ident() == _MAIN_THREAD:
            InterruptsDeferred.depth += 1

    def __exit__(self, *exc_info: object) -> None:
        if threading.get_ident() != _MAIN_THREAD:
            return
        InterruptsDeferred.depth -= 1
        pending = InterruptsDeferred.pending
        if pending is not None and not InterruptsDeferred.depth:
            InterruptsDeferred.pending = None
            raise pending


_MAIN_THREAD = threading.main_thread().ident

#: ``with interrupts_deferred:`` a block no interrupt of ours lands inside
#: (:class:`InterruptsDeferred`)
interrupts_deferred = InterruptsDeferred()


def raised_when_safe(interrupt: KeyboardInterrupt) -> None:
    """Raise ``interrupt`` (a signal handler's) now, or keep it for the end of the
    :data:`interrupts_deferred` block the main thread is in (the first one kept)."""
    if not InterruptsDeferred.depth:
        raise interrupt
    if InterruptsDeferred.pending is None:
        InterruptsDeferred.pending = interrupt


def signal_interrupt(exc: BaseException) -> KeyboardInterrupt | None:
    """The interrupt a signal delivered (:func:`signal_delivered`) that ``exc`` is, or that
    Python wrapped it in: a signal whose handler raised inside a class body's
    ``__set_name__`` (a dataclass's fields, as a module is imported) comes out as
    ``RuntimeError: Error calling __set_name__ ...`` before Python 3.12, its ``__cause__``
    the interrupt. A SIGTERM in the first second of ``roomba-bt run`` landed there (in
    ``runtime/summary.py``): a traceback and exit 1, not exit 130. None: no signal's."""
    if isinstance(exc, RuntimeError) and isinstance(exc.__cause__, KeyboardInterrupt):
        exc = exc.__cause__
    if isinstance(exc, KeyboardInterrupt) and signal_delivered(exc):
        return exc
    return None


def signal_delivered(exc: BaseException) -> bool:
    """Whether ``exc`` is an interrupt a signal delivered, the operator's Ctrl-C or a
    ``kill`` (exit 130), and not a ``raise KeyboardInterrupt`` in a plugin's code (decided:
    that is the plugin's error, exit 4: nobody pressed Ctrl-C). Every handler of ours marks
    the interrupt it raises (:func:`delivered`); so an unmarked one came from code where one
    of ours holds its signal (a run's :class:`InterruptGuard`, :func:`interrupts_told_apart`,
    the CLI's :func:`raise_terminated`), and in any thread but the main one, which signals
    never reach. Elsewhere (a program's own handler, Python's default outside those) the two
    cannot be told apart, and an interrupt is taken for a signal's, as it always was."""
    if not isinstance(exc, KeyboardInterrupt):
        return False
    mark = getattr(exc, DELIVERED_BY, None)
    if mark is not None:
        return bool(mark)  # 0: told apart as the code's (interrupts_told_apart)
    if threading.current_thread() is not threading.main_thread():
        return False
    signum = exc.signum if isinstance(exc, Terminated) else signal.SIGINT
    with contextlib.suppress(ValueError):  # a number that is no signal here: not ours
        return not _ours(signal.getsignal(signum))
    return True


def _ours(handler: object) -> bool:
    """Whether ``handler`` is one of ours, which mark what they raise."""
    if handler is raise_terminated or handler is raise_interrupt:
        return True
    return isinstance(getattr(handler, "__self__", None), InterruptGuard)


class RunAborted(BaseException):
    """Base of an exception another thread raises into a run's thread (its asynchronous
    exception: an evaluation's wall-clock limit, ``WallLimitReached``). It goes on through
    the run as it came, after the safe stop, never taken for the error of the behaviour it
    happened to land in (any other exception a behaviour raises is its error: exit 4)."""


#: the attribute of a signal's interrupt that says what it cut short in a plugin's code
INTERRUPTED_IN = "_roomba_bt_interrupted_in"


def note_interrupted_in(exc: BaseException, what: str) -> None:
    """Say on the interrupt ``exc`` what it cut short (``importing plugin 'slow' (...) at
    .../__init__.py:14``), the innermost such place kept: the CLI's ``roomba-bt:
    interrupted`` said nothing more, and a ``validate`` that a plugin's import (a network
    call, a loop) held until Ctrl-C named no plugin to look at."""
    if getattr(exc, INTERRUPTED_IN, None) is None:
        with contextlib.suppress(AttributeError, TypeError):
            setattr(exc, INTERRUPTED_IN, what)


def interrupted_in(exc: BaseException) -> str | None:
    """What a signal's interrupt cut short in a plugin's code (:func:`note_interrupted_in`),
    or None."""
    what = getattr(exc, INTERRUPTED_IN, None)
    return what if isinstance(what, str) else None


def code_failure(exc: BaseException) -> bool:
    """Whether ``exc``, raised out of a plugin's or a behaviour's code (its import, its
    ``__init__``, a method), is that code's failure, to be said as such with its file:line:
    any exception, ``sys.exit()`` (SystemExit), ``GeneratorExit``, a ``BaseException`` of its
    own, a ``KeyboardInterrupt`` it raised itself; all but an interrupt a signal delivered
    (:func:`signal_delivered`: the operator's; or the ``RuntimeError`` Python wrapped one
    in, :func:`signal_interrupt`, for the CLI to say as the signal's) and
    :class:`RunAborted` (from outside the run), which go on as they came. Before, only
    ``Exception`` (and SystemExit) was caught: a plugin's ``sys.exit(0)`` in ``shutdown()``
    exited 0 after a failed mission, its ``raise KeyboardInterrupt`` read ``INTERRUPTED
    (Ctrl-C)``, its ``BaseException`` was a traceback and exit 1."""
    return not isinstance(exc, RunAborted) and signal_interrupt(exc) is None


def failure_said(exc: BaseException) -> str:
    """A code's failure (:func:`code_failure`) in one line, its exception named: ``SystemExit
    (it called sys.exit(0))`` (``SystemExit: 0`` read as a run that went well), a
    ``KeyboardInterrupt`` said to be the code's own, an exception without a message by its
    name alone (``GeneratorExit``), else ``Type: message`` (its lines joined)."""
    name = type(exc).__name__
    if isinstance(exc, SystemExit):
        return f"{name} (it called sys.exit({exc.code!r}))"
    if isinstance(exc, KeyboardInterrupt):
        name += " (raised by its own code: no Ctrl-C or signal came)"
    text = " ".join(str(exc).split())
    return f"{name}: {text}" if text else name


@contextlib.contextmanager
def interrupts_told_apart() -> Iterator[None]:
    """Within the block, a Ctrl-C raises a :class:`KeyboardInterrupt` marked as the signal's
    (:func:`raise_interrupt`), so that one a plugin's code raises (at its import, in its
    ``__init__``) is told apart from it (:func:`signal_delivered`); Python's own handler
    comes back on the way out. Only where Python's own holds SIGINT, in the main thread: a
    program's own handler is left as it is (and its interrupts taken for signals'). One no
    signal delivered that leaves the block is marked as the code's on its way out, so that
    it is told apart after the block too."""
    main = threading.current_thread() is threading.main_thread()
    if not main or signal.getsignal(signal.SIGINT) is not signal.default_int_handler:
        yield
        return
    signal.signal(signal.SIGINT, raise_interrupt)
    try:
        yield
    except KeyboardInterrupt as exc:  # told apart here, where it can be: marked for later
        if getattr(exc, DELIVERED_BY, None) is None:
            setattr(exc, DELIVERED_BY, 0)  # no signal's: raised by code
        raise
    finally:
        signal.signal(signal.SIGINT, signal.default_int_handler)


@contextlib.contextmanager
def sigterm_raises() -> Iterator[None]:
    """Within the block, SIGTERM, SIGHUP, SIGTSTP and SIGQUIT raise :class:`Terminated`; the old
    handlers are restored.

    Signal handlers belong to the main thread: elsewhere this does nothing (and says so).
    """
    if threading.current_thread() is not threading.main_thread():
        log.debug("sigterm_raises() outside the main thread: SIGTERM left as it is")
        yield
        return
    if _TermHandlers.depth == 0:
        _TermHandlers.previous = {
            signum: signal.signal(signum, raise_terminated)
            for signum in _taken(ENDING_SIGNALS)
            if signum != signal.SIGINT
        }
    _TermHandlers.depth += 1
    try:
        yield
    finally:
        _TermHandlers.depth -= 1
        if _TermHandlers.depth == 0:
            for signum, handler in _TermHandlers.previous.items():
                signal.signal(signum, handler)


class _TermHandlers:
    """The handlers :func:`sigterm_raises` found, given back when its last block ends: two
    runs' blocks stepped in turn (two ``RunStack.ticks()``) end in the order they began, and
    each giving back what it found left the process with ours after both."""

    depth: ClassVar[int] = 0
    previous: ClassVar[dict[int, Any]] = {}


#: What the run is doing while it stops, as a Ctrl-C or SIGTERM meanwhile says it
#: (:meth:`InterruptGuard.stopping`): the safe stop itself (the default)
SAFE_STOP_UNDER_WAY = "the safe stop is under way"
#: ... and what the run's reason says such a signal came during (``... during the safe stop``)
THE_SAFE_STOP = "the safe stop"

#: What a held run does once it has returned (:class:`InterruptGuard`'s ``hold``), as a
#: Ctrl-C or SIGTERM meanwhile says it
CLOSING_UNDER_WAY = "the run's record, monitor and port are being closed"

#: What a signal came during, as the run's reason says it: a text, or what makes it from the
#: main thread's frame when the signal came (the behaviour it was in: a ``terminate()``)
During = str | Callable[[FrameType | None], str]


def say_if_room(fd: int, text: bytes) -> None:
    """Write ``text`` to ``fd`` if it can take it now, else drop it: a signal handler's word
    (:class:`InterruptGuard`) must not block the main thread, which runs the safe stop, on a
    terminal or pipe that takes nothing (a stalled SSH session, ``2>&1 | less``). A pipe
    that selects writable takes ``PIPE_BUF`` bytes (512 or more) without blocking."""
    with contextlib.suppress(OSError, ValueError):
        if os.name == "posix":  # elsewhere select() takes sockets only: written as it was
            _, writable, _ = select.select([], [fd], [], 0)
            if not writable:
                return
        os.write(fd, text)


def _waiting(doing: str, raises: bool) -> bytes:
    """What a Ctrl-C or SIGTERM while the run stops prints (straight to stderr: a handler may
    run while the main thread is inside a write to it): what the run is doing, and what comes
    after it, the summary (the CLI prints it) or the interrupt raised in the program that
    started the run. Made before it is needed: a handler formats nothing."""
    then = "then the interrupt is raised" if raises else "the summary follows"
    return f"roomba-bt: {doing}; waiting for it to end ({then})\n".encode()


#: how long the command's last writes may take after a signal that came during them before
#: the process ends by itself (:func:`answer_given`)
LAST_WORDS_S = 2.0


def answer_given(code: int | None = None) -> None:
    """The command's answer is known: ``code``, its exit code (None: the process's end is
    near, the code not given here; a signal's then). From now on the ending signals
    (:data:`ENDING_SIGNALS`, those :data:`IGNORED_AT_START` aside) do not change it: the
    first lets the last words (a run's summary and report, a NO CONNECTION's hint) be
    written and the command exit with its answer, but no longer than
    :data:`LAST_WORDS_S`: a thread then ends the process, even while a blocked write
    holds the stream's lock, which no handler in the main thread can get past, with
    ``128 + signal``: the last words were cut short by the signal, and the exit code
    says so (the answer, 0 for a run that succeeded, would tell a script its report was
    whole); the answer is said on stderr if it takes it at once. The others change
    nothing. The terminal's stop (Ctrl-Z) suspends, as ever.

    The CLI's, as the process (a program that calls its ``main(argv)`` keeps its
    handlers), once nothing a robot or the next run needs is left: after a run, the
    record's end note written, the monitor shut down, the port closed and its exclusive
    mode cleared, the stop tried again if it was not delivered; a run that never started
    (no connection, exit 3), once its port is closed. A report written to a stdout nobody
    reads (a ``less`` left unscrolled, a frozen SSH session) blocks, and signals held then
    left a process only SIGKILL could end.

    One rule for both endings: with two, a NO CONNECTION's first signal putting the default
    actions back, a second would kill the process (status -15 or -2, where the command had
    said 3), while after a run's end a signal let its report finish and kept its code. The
    signals' default action here would kill the process by SIGINT (status -2, "killed by
    signal INT" in systemd's log), sometimes before the summary was printed, when an
    operator's Ctrl-C pressed a few times 0.3 s apart reached the command after its run;
    and a SIGTERM as a run that never started printed its summary would exit 130 or 143,
    which tells a service a run was stopped where none had started and a retry is safe."""
    if code is not None:
        _ANSWER[:] = [code]
    for signum in _taken(ENDING_SIGNALS):
        with contextlib.suppress(ValueError):  # not the main thread
            if signum in WALL_CLOCK_SIGNALS:  # Ctrl-Z: suspends, as ever
                signal.signal(signum, signal.SIG_DFL)
            else:
                signal.signal(signum, _ends_after_the_last_words)


def _ends_after_the_last_words(signum: int, frame: FrameType | None) -> None:
    """:func:`answer_given`'s handler: the first signal sets the process's end
    :data:`LAST_WORDS_S` later, by a thread; the others change nothing.

    No lock: a handler runs in the main thread, between two bytecodes of whatever ran
    there, this handler too, so a second signal's handler can run inside the first's. With
    a lock it would wait for ever for the one the first held (three SIGTERMs sent together
    as a summary prints: 3 of 6 processes never exit). The mark is made before
    anything that can be interrupted; at worst two timers start, and the first ends it."""
    if _LAST_WORDS:
        return
    _LAST_WORDS.append(signum)
    ender = threading.Timer(LAST_WORDS_S, _last_words_run_out, (signum,))
    ender.daemon = True  # the process's own exit ends it first
    ender.start()


def _last_words_run_out(signum: int) -> None:
    """The process's end :data:`LAST_WORDS_S` after ``signum`` came: with ``128 + signum``
    while the last words are not out (the report cut short: blocked on a pipe or terminal
    nobody reads), the command's answer said on stderr if it takes it now (it is most often
    the same blocked pipe); with the answer once they are (:func:`signals_wait_for_the_exit`:
    only the interpreter's exit was left)."""
    if _ANSWER and _WORDS_OUT:
        os._exit(_ANSWER[-1])
    if _ANSWER:
        say_if_room(2, _cut_short(signum, _ANSWER[-1]))
    os._exit(128 + signum)


def _cut_short(signum: int, answer: int) -> bytes:
    """What :func:`_last_words_run_out` says of a command whose last words ``signum`` cut
    short: its own answer, which the exit code no longer gives."""
    name = signal.Signals(signum).name
    return (
        f"roomba-bt: the report was cut short: {name} came and it was not written within "
        f"{LAST_WORDS_S:g} s; exit {128 + signum}, where the command's answer was {answer}\n"
    ).encode()


#: the most the process's exit may take once its last words are out
#: (:func:`signals_wait_for_the_exit`): far more than Python's finalization takes
EXIT_BOUND_S = 10.0


def signals_wait_for_the_exit() -> None:
    """The command's last words are written and flushed, its exit code decided: the ending
    signals (:data:`~roomba_bt._entry.EARLY_SIGNALS`, those :data:`IGNORED_AT_START` aside)
    are ignored from here to the process's end, and the kernel's alarm (SIGALRM, whose
    default action ends the process) set for :data:`EXIT_BOUND_S` in case the exit itself
    hangs (a thread that never ends: nothing else could end it then but SIGKILL).
    Python's finalization puts its own handlers back to their default action, so a
    Ctrl-C in it (the third of three pressed 0.3 s apart, after the run's summary) killed
    the process by SIGINT, status -2 where the command said 130; an ignored one is not
    Python's to put back. A signal's end already set going (:func:`answer_given`) then
    exits with the command's answer: its words are out."""
    _WORDS_OUT.append(True)
    for signum in _taken(EARLY_SIGNALS):
        with contextlib.suppress(ValueError):  # not the main thread
            signal.signal(signum, signal.SIG_IGN)
    if hasattr(signal, "alarm"):  # POSIX
        signal.alarm(math.ceil(EXIT_BOUND_S))


#: the signal whose :func:`_ends_after_the_last_words` set the process's end going (one)
_LAST_WORDS: list[int] = []
#: the command's exit code once known (:func:`answer_given`), what that end exits with once
#: the last words are out
_ANSWER: list[int] = []
#: not empty once the command's last words are written and flushed
#: (:func:`signals_wait_for_the_exit`)
_WORDS_OUT: list[bool] = []


class InterruptGuard:
    """Ctrl-C and SIGTERM end a run once: the first raises (:class:`KeyboardInterrupt`,
    :class:`Terminated`), and once :meth:`stopping` was called (the safe stop began) every
    further one is noted and ignored, so the stop is written whole and the summary printed.
    The first one to come during the stop of a run no signal had ended is kept
    (:attr:`late`): the runner raises it, or reports it, once the stop is done, so an
    operator's Ctrl-C is never lost because it came late (a program would drive its next
    mission). ``raises``: the interrupt is raised in the program after the stop (what the
    message printed meanwhile says), not only summarised. The first one's interrupt is kept
    too (:attr:`kept`) until the run takes it: one Python dropped (its handler ran inside a
    finalizer) or a plugin swallowed is raised again at the run's next frame.

    Used as a context manager around a run; the previous handlers come back on the way out,
    or with ``hold`` every signal stays noted and ignored after it, until :meth:`release`
    (the CLI: the record's end note, the monitor's shutdown and the port's close are still to
    come, then the summary). Ignored there, not ended by (decided): the port's close clears
    its kernel exclusive mode (``TIOCEXCL``), which a process ended before it leaves set on
    a simulator's pty, refusing the next run until the simulator restarts; a stop that was
    not delivered is tried again there, the robot's last chance; and the record's end note
    tells replay how the run ended. Only then, around the report alone, does the CLI let the
    signals end the process (:func:`answer_given`). The terminal's stops
    (:data:`TERMINAL_STOP_SIGNALS`) stay ignored: a summary written from the background
    goes out. Signal handlers belong to the main thread:
    elsewhere it does nothing.
    """

    def __init__(
        self,
        *,
        hold: bool = False,
        wall_clock: bool = True,
        enabled: bool = True,
        raises: bool = False,
    ) -> None:
        self.hold = hold
        self.raises = raises
        self._waiting = _waiting(SAFE_STOP_UNDER_WAY, raises)
        self._during: During = THE_SAFE_STOP
        #: False: no handler at all (an evaluation's worker process: its parent takes Ctrl-C
        #: and ends the workers, which have nothing driving to stop)
        self.enabled = enabled
        #: Ctrl-Z and Ctrl-\ (:data:`WALL_CLOCK_SIGNALS`) end the run too; ``wall_clock``
        #: False where no robot moves on the wall clock (an evaluation, ``--fast``): there a
        #: suspended or quit process leaves nothing driving
        #: those :data:`IGNORED_AT_START` stay ignored (``nohup``'s SIGHUP)
        self.signals = _taken(
            tuple(s for s in ENDING_SIGNALS if wall_clock or s not in WALL_CLOCK_SIGNALS)
        )
        #: :data:`TERMINAL_STOP_SIGNALS`, ignored on the wall clock
        self.ignoring = TERMINAL_STOP_SIGNALS if wall_clock else ()
        self.stop_begun = False
        #: a handler raised: the run unwinds into its stop because of a signal
        self.raised = False
        #: the first signal that came during the stop of a run no signal had ended (None:
        #: none did), for the runner to raise or report once the stop is done
        self.late: int | None = None
        #: what the run was doing when :attr:`late` came (:meth:`stopping`'s ``during``)
        self.late_during = THE_SAFE_STOP
        self.ignored = 0
        #: the held run has returned: a signal now is ignored, never kept as :attr:`late`
        self.closing = False
        self._said = False  # the message for what is under way now
        self._previous: dict[int, object] = {}
        #: the hook put in for what Python drops (:func:`~roomba_bt._entry.note_dropped`)
        self._hooked: Callable[[sys.UnraisableHookArgs], None] | None = None
        #: the interrupt a handler raised, until the run takes it (:meth:`take`): Python
        #: drops one raised while a finalizer or a weakref callback runs ("Exception ignored
        #: in ..."), and a plugin's ``except BaseException`` swallows one raised in its code;
        #: either way the tree ticked on, the robot driving, and a second signal only waited
        #: for a stop that never began. The run's loop raises it again at its next frame (a
        #: list: the loop reads it there, one test a frame)
        self.kept: list[KeyboardInterrupt] = []

    def stopping(self, doing: str = SAFE_STOP_UNDER_WAY, during: During = THE_SAFE_STOP) -> None:
        """The run's stop begins, or its next step: from now on a signal waits for it, and
        the first one says ``doing`` (what the run does now: the tree's stop, the safe stop,
        the nodes' shutdown); ``during``: what the run's reason says a late one came during
        (:attr:`late_during`; a callable is given the main thread's frame then)."""
        self._waiting = _waiting(doing, self.raises)
        self._during = during
        self.stop_begun = True

    def _handle(self, signum: int, frame: FrameType | None) -> None:
        if self.stop_begun:
            self.ignored += 1
            if not self.raised and self.late is None and not self.closing:
                self.late = signum  # not lost: raised or reported once the stop is done
                during = self._during
                self.late_during = during(frame) if callable(during) else during
            if not self._said:
                self._said = True
                say_if_room(2, self._waiting)
            return
        self.stop_begun = self.raised = True  # the run now unwinds into its safe stop
        interrupt = KeyboardInterrupt() if signum == signal.SIGINT else Terminated(signum)
        self.kept[:] = [delivered(interrupt, signum)]  # until the run takes it: it may be lost
        raised_when_safe(interrupt)

    def take(self) -> KeyboardInterrupt | None:
        """The interrupt a handler raised that the run has not taken (:attr:`kept`), taken:
        the run's end calls it, and a signal's interrupt that ended the run is this one."""
        kept = self.kept[:1]
        self.kept.clear()
        return kept[0] if kept else None

    def late_interrupt(self) -> KeyboardInterrupt | None:
        """The interrupt a signal that came during the stop stands for (:attr:`late`), or
        None."""
        if self.late is None:
            return None
        late = KeyboardInterrupt() if self.late == signal.SIGINT else Terminated(self.late)
        return delivered(late, self.late)

    def __enter__(self) -> InterruptGuard:
        if self.enabled and threading.current_thread() is threading.main_thread():
            for signum in self.signals:
                self._previous[signum] = signal.signal(signum, self._handle)
            for signum in self.ignoring:
                self._previous[signum] = signal.signal(signum, signal.SIG_IGN)
            if sys.unraisablehook is sys.__unraisablehook__:  # a program's own hook stays
                # a program's run says where Python dropped its interrupt, as the CLI does
                sys.unraisablehook = self._hooked = note_dropped
        return self

    def __exit__(self, *exc_info: object) -> None:
        if self.hold:  # still ignored, said once more: the run's closing is under way
            self.stop_begun = self.closing = True
            self._waiting = _waiting(CLOSING_UNDER_WAY, self.raises)
            self._said = False
            return
        self.release()

    def release(self) -> None:
        """The previous handlers back (a held guard: once the summary is printed)."""
        for signum, previous in self._previous.items():
            signal.signal(signum, previous)  # type: ignore[arg-type]
        self._previous.clear()
        if self._hooked is not None and sys.unraisablehook is self._hooked:
            sys.unraisablehook = sys.__unraisablehook__
        self._hooked = None
