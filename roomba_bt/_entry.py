"""The ``roomba-bt`` command's entry point (``[project.scripts]``, ``python -m roomba_bt``):
the ending signals taken before anything heavy is imported.

The command line's module (argparse, logging, the streams' guard, the wording) takes from 30
ms on an idle machine to a second on a loaded one to import, and handlers put in only once
it has loaded leave that time open: a SIGTERM would end the process with 143, a script's
``kill -INT $!`` (SIGINT ignored at start in a shell's background job) be lost and the whole
mission run, and a terminal's Ctrl-C print Python's own traceback. This module imports
only ``sys`` and ``_signal`` (the C module under ``signal``, which Python itself loaded as
it started: ``signal`` imports ``enum``, ``functools`` and ``collections``, 15 ms and more
where nothing else had loaded them), and the top package before it, which drops the current
folder off ``sys.path`` (``_safe_path`` stays first) and imports nothing else (not
``typing`` nor the lazy names' module, and this module not ``signal``, ``contextlib`` nor
``typing``, before a handler is in), so its handlers are in a fraction of a millisecond
after Python's own start-up; ``signal`` itself is imported once they are. The CLI's handlers
(:func:`roomba_bt.cli._as_the_process`) take their place once it has loaded, and a signal
before then is ``roomba-bt: interrupted``, exit 130, nothing sent.

It also holds what those handlers raise, :class:`Terminated` and the mark of a signal's
interrupt (:func:`delivered`), which :mod:`roomba_bt.robot.safety` raises too: one class
for a signal's ending from the first line of the command to the run's last. Standard library
only, below every layer.
"""

from __future__ import annotations

import sys

TYPE_CHECKING = False  # typing's, without importing typing (see above)
if TYPE_CHECKING:
    import signal as _signal
    from types import FrameType
    from typing import TypeVar

    _Interrupt = TypeVar("_Interrupt", bound=KeyboardInterrupt)
else:
    import _signal  # the handlers' C module, loaded before any line of ours ran

#: The signals that end the command from its first line, as they end a run: Ctrl-C, ``kill``
#: and systemd, the terminal gone, and Ctrl-\ (SIGQUIT: an operator who presses it wants a
#: stop, never the core dump that is its default, which leaves a robot driving). SIGHUP and
#: SIGQUIT exist on POSIX only. Ctrl-Z is not here: a command suspended in its start-up has
#: sent nothing yet, and a run on the wall clock takes it.
EARLY_SIGNALS: tuple[int, ...] = tuple(
    getattr(_signal, name)
    for name in ("SIGINT", "SIGTERM", "SIGHUP", "SIGQUIT")
    if hasattr(_signal, name)
)

#: the attribute a signal's interrupt carries (its signal's number), which one a plugin's
#: code raised lacks (:func:`roomba_bt.robot.safety.signal_delivered`)
DELIVERED_BY = "roomba_bt_signal"


def delivered(interrupt: _Interrupt, signum: int) -> _Interrupt:
    """``interrupt`` marked as the one signal ``signum`` delivered (each handler of ours
    raises it so): :func:`~roomba_bt.robot.safety.signal_delivered` tells it from a ``raise
    KeyboardInterrupt`` in a plugin's code."""
    setattr(interrupt, DELIVERED_BY, signum)
    return interrupt


class Terminated(KeyboardInterrupt):
    """Raised in the main thread when SIGTERM, SIGHUP, SIGTSTP (Ctrl-Z) or SIGQUIT (Ctrl-\\)
    arrives while one of our handlers holds it (the command's, from its first line; a run's
    :class:`~roomba_bt.robot.safety.InterruptGuard`;
    :func:`~roomba_bt.robot.safety.sigterm_raises`).

    A :class:`KeyboardInterrupt`, so whatever handles Ctrl-C (the CLI: exit code 130) handles
    it too, and ``except Exception`` does not swallow it.
    """

    def __init__(self, signum: int = _signal.SIGTERM) -> None:
        self.signum = signum
        super().__init__(f"terminated by signal {_name(signum)}")


#: the interrupt an early handler, or the CLI's own after it, raised last, until the CLI
#: took it (:func:`swallowed_interrupt`, :func:`main`): Python drops one raised while a
#: weakref callback or a finalizer runs (importlib's module locks run such a callback as the
#: CLI imports, a plugin's import too: an "Exception ignored in ..." line), and the command
#: went on, the whole mission run, exit 0 (:func:`kept`)
_RAISED: list[KeyboardInterrupt] = []


def kept(interrupt: _Interrupt) -> _Interrupt:
    """``interrupt``, which a handler of the command's is about to raise, kept
    (:data:`_RAISED`) in case Python drops it: the start-up's end and a run's start raise it
    again (:func:`swallowed_interrupt`)."""
    _RAISED[:] = [interrupt]
    return interrupt


def interrupted_early(signum: int, frame: FrameType | None) -> None:
    """The handler of :data:`EARLY_SIGNALS` until the CLI's own are in: Ctrl-C's
    :class:`KeyboardInterrupt`, another signal's :class:`Terminated`, marked as the signal's.
    Nothing is written yet, so nothing waits for a safe point. Kept too, in case Python
    drops it (:data:`_RAISED`)."""
    interrupt = KeyboardInterrupt() if signum == _signal.SIGINT else Terminated(signum)
    raise kept(delivered(interrupt, signum))


def swallowed_interrupt() -> KeyboardInterrupt | None:
    """The interrupt a handler of the command's raised that never ended it (Python dropped
    it: :data:`_RAISED`), taken: the CLI raises it once its own handlers are in, where the
    start-up ends, and as a run begins (a Ctrl-C dropped as a plugin imported). None: none,
    or the one raised was handled (:func:`main`)."""
    kept = _RAISED[:1]
    _RAISED.clear()
    if kept and _DROPPED and _DROPPED[0] is kept[0]:
        _DROPPED.clear()  # raised again by whoever took it: no longer dropped
    return kept[0] if kept else None


#: the signal's interrupt (ours: :data:`DELIVERED_BY`) that Python dropped in a callback
#: (:func:`note_dropped`), until it is taken (:func:`dropped_interrupt`)
_DROPPED: list[KeyboardInterrupt] = []


def note_dropped(unraisable: sys.UnraisableHookArgs) -> None:
    """``sys.unraisablehook`` while the command runs (:func:`take_signals_early`): Python
    calls it for an exception it drops, one raised in a finalizer or a weakref callback. A
    signal's interrupt of ours dropped there is kept (:data:`_DROPPED`) for the command to
    end on at its next check, and said in one line naming the callback (its traceback,
    Python's "Exception ignored in ...", named nothing a user could act on); anything else
    goes to Python's own hook."""
    interrupt = unraisable.exc_value
    signum = getattr(interrupt, DELIVERED_BY, None)
    if not isinstance(interrupt, KeyboardInterrupt) or signum is None:
        sys.__unraisablehook__(unraisable)
        return
    _DROPPED[:] = [interrupt]
    where = _callback_named(unraisable.object)
    try:  # noqa: SIM105  (contextlib is not imported here: see above)
        print(
            f"roomba-bt: {_name(signum)} came while Python ran {where}, a finalizer or weakref "
            "callback, which drops what it raises: it is raised again at the next check",
            file=sys.stderr,
        )
    except OSError:  # stderr closed: the exit code says it all the same
        pass


def _callback_named(callback: object) -> str:
    """``WeakKeyDictionary.__init__.<locals>.remove (.../weakref.py:369)``: the callback (a
    function, a bound ``__del__``, a generator) by its qualified name and where it is
    written (a plugin's module has a made-up name: its file says whose it is)."""
    if callback is None:
        return "a finalizer"
    name = getattr(callback, "__qualname__", None) or type(callback).__qualname__
    code = (
        getattr(callback, "__code__", None)
        or getattr(getattr(callback, "__func__", None), "__code__", None)
        or getattr(callback, "gi_code", None)
    )
    if code is None:
        return str(name)
    return f"{name} ({code.co_filename}:{code.co_firstlineno})"


def dropped_interrupt() -> KeyboardInterrupt | None:
    """The signal's interrupt Python dropped in a callback (:func:`note_dropped`) that
    nothing raised again and no later signal's took the place of, taken: a command that
    went on past it ends on it (exit 130). None: none was dropped, or a signal came after
    it, whose interrupt ended the command or was caught on purpose (the monitor's Ctrl-C,
    its way to end, exit 0), or a run's own handler dropped it (the run raises it again
    itself). Unlike :func:`swallowed_interrupt`, never one a command caught on purpose."""
    dropped = _DROPPED[:1]
    _DROPPED.clear()
    if not dropped or not _RAISED or _RAISED[0] is not dropped[0]:
        return None
    _RAISED.clear()
    return dropped[0]


def take_signals_early() -> None:
    """Put :func:`interrupted_early` in for each of :data:`EARLY_SIGNALS` that has its default
    action, or Python's, or that the process was started with ignored, SIGHUP aside: a
    script's background job starts with SIGINT and SIGQUIT ignored by accident of job control,
    and its ``kill -INT`` is the script's only way to ask a stop, while ``nohup`` ignores
    SIGHUP on purpose (it stays ignored, and so the safety module reads it:
    :data:`~roomba_bt.robot.safety.IGNORED_AT_START`). A handler a program set is left as it
    is. Signal handlers are the main thread's: elsewhere nothing is set. Python's hook for
    the exceptions it drops gives way to :func:`note_dropped` (one a program set stays)."""
    if sys.unraisablehook is sys.__unraisablehook__:
        sys.unraisablehook = note_dropped
    hang_up = getattr(_signal, "SIGHUP", None)
    for signum in EARLY_SIGNALS:
        now = _signal.getsignal(signum)
        if now in (_signal.SIG_DFL, _signal.SIG_IGN, _signal.default_int_handler) and not (
            now == _signal.SIG_IGN and signum == hang_up
        ):
            try:  # noqa: SIM105  (contextlib is not imported here: see above)
                _signal.signal(signum, interrupted_early)
            except ValueError:  # not the main thread
                pass


def main() -> int:
    """``roomba-bt``: the signals taken, then the command line's module imported and run. An
    interrupt before its ``main`` has its own handling (its import, a class made as it loads,
    which Python wraps the interrupt of in a RuntimeError before 3.12) is said in one line,
    exit 130, as the CLI says it. The signals are taken inside the ``try``: a SIGINT whose
    handler is in while the next signal's is being put in was Python's traceback."""
    try:
        take_signals_early()
        from roomba_bt.cli import main as command

        return command()
    except KeyboardInterrupt as exc:
        _RAISED.clear()
        return _interrupted(exc)
    except RuntimeError as exc:
        if not isinstance(exc.__cause__, KeyboardInterrupt):
            raise
        _RAISED.clear()
        return _interrupted(exc.__cause__)


def _interrupted(exc: KeyboardInterrupt) -> int:
    """``roomba-bt: interrupted [by SIGTERM]``, exit 130 (``ExitCode.INTERRUPTED``, whose
    module is not imported for it); a second signal now ends the process at once."""
    for signum in EARLY_SIGNALS:
        if _signal.getsignal(signum) != _signal.SIG_IGN:
            _signal.signal(signum, _signal.SIG_DFL)
    ending = getattr(exc, "signum", None)
    by = f" by {_name(ending)}" if ending is not None else ""
    try:  # noqa: SIM105  (contextlib is not imported here: see above)
        print(f"roomba-bt: interrupted{by}", file=sys.stderr)
    except OSError:  # stderr closed: the exit code says it all the same
        pass
    return INTERRUPTED


#: ``ExitCode.INTERRUPTED`` (``tests/cli/test_entry.py`` checks the two agree)
INTERRUPTED = 130


def _name(signum: int) -> str:
    """``SIGTERM``: the signal's name, for the signals a run ends on from a table of its own
    (a handler names its signal, and ``signal``'s ``enum`` is what this module does without:
    imported in a handler, it could meet ``signal`` half-imported by the interrupted line);
    another from ``signal``."""
    name = _NAMES.get(signum)
    if name is not None:
        return name
    import signal

    return signal.Signals(signum).name


#: the names of the signals a run ends on (:func:`_name`), as ``signal.Signals`` says them
_NAMES: dict[int, str] = {
    getattr(_signal, name): name
    for name in ("SIGINT", "SIGTERM", "SIGHUP", "SIGQUIT", "SIGTSTP")
    if hasattr(_signal, name)
}
