"""The ``roomba-bt`` command line.

Each subcommand lives in its own module of this package, which exposes
``register(subparsers)``; :data:`SUBCOMMAND_MODULES` lists them in help order. Every one
ships: one that is missing is a broken installation (a wheel built without it), said as such
and exit 2, never a traceback and never a subcommand silently gone from the help.
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import logging
import re
import signal
import sys
import warnings
from collections.abc import Sequence
from typing import NoReturn

from roomba_bt import __version__
from roomba_bt._entry import (
    EARLY_SIGNALS,
    INTERRUPTED,
    dropped_interrupt,
    interrupted_early,
    swallowed_interrupt,
    take_signals_early,
)
from roomba_bt.cli.streams import guard_std_streams, stdout_problem
from roomba_bt.installation import IncompleteInstallation, missing_from_installation
from roomba_bt.robot.wording import COMMAND_LINE, UNATTENDED, ConnectionWording, spoken

# Nothing heavier at the top: the process's signal handlers (:func:`_as_the_process`) are set
# once this module has loaded, and each module imported here delays them. The exit codes'
# module (``runtime/summary.py``, with the protocol tables under it: two thirds of this
# module's import time) is imported where a code is returned.

SUBCOMMAND_MODULES: tuple[str, ...] = (
    "roomba_bt.cli.run_cmd",
    "roomba_bt.cli.mission_cmds",
    "roomba_bt.cli.sim_cmd",
    "roomba_bt.cli.worlds_cmd",
    "roomba_bt.cli.sensors_cmd",
    "roomba_bt.cli.clock_cmd",
    "roomba_bt.cli.doctor_cmd",
    "roomba_bt.cli.eval_cmd",
    "roomba_bt.cli.monitor_cmd",
    "roomba_bt.cli.docs_cmd",
)


class _Parser(argparse.ArgumentParser):
    """argparse exits with 2 on usage errors, which is our INVALID code too."""

    def error(self, message: str) -> NoReturn:
        # ``--timeout -3s``: argparse takes "-3s" for an option, not for the value, and says
        # only "expected one argument"; the way to give such a value is after "=".
        option = _VALUE_MISSING.fullmatch(message)
        if option is not None:
            name = option["option"].split("/")[-1]
            message += f" (if the value starts with '-', write {name}=VALUE)"
        super().error(message)


_VALUE_MISSING = re.compile(r"argument (?P<option>\S+): expected one argument")


class _CommandParser(_Parser):
    """A subcommand's parser: an argument it does not know is its own usage error, said with
    its own usage (``usage: roomba-bt replay [-h] ... RECORD``). argparse hands a
    subcommand's unknown arguments up to the top parser, which said ``usage: roomba-bt [-h]
    [--version] [-v] [-q] COMMAND ...`` to ``roomba-bt replay rec.jsonl --display none``,
    and left the user to find the command's options."""

    def parse_known_args(  # type: ignore[override]
        self, args: Sequence[str] | None = None, namespace: argparse.Namespace | None = None
    ) -> tuple[argparse.Namespace, list[str]]:
        parsed, unknown = super().parse_known_args(args, namespace)
        if unknown:
            self.error(f"unrecognized arguments: {' '.join(unknown)}")
        return parsed, unknown


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="roomba-bt",
        description="Behaviour-tree missions for iRobot Open Interface robots.",
    )
    parser.add_argument("--version", action="version", version=f"roomba-bt {__version__}")
    parser.add_argument("-v", "--verbose", action="count", default=0, help="more logging")
    parser.add_argument("-q", "--quiet", action="count", default=0, help="less logging")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_CommandParser)
    for name in SUBCOMMAND_MODULES:
        try:
            module = importlib.import_module(name)
        except ModuleNotFoundError as exc:
            if exc.name == name:
                said = missing_from_installation(name, __version__, "subcommand module")
                raise IncompleteInstallation(said, name=name) from None
            raise
        module.register(sub)
    return parser


def setup_logging(verbose: int, quiet: int) -> None:
    level = logging.INFO + 10 * (quiet - verbose)
    from roomba_bt.runtime.display import MissionClockFormatter

    handler = logging.StreamHandler(sys.stderr)
    handler.setFormatter(MissionClockFormatter())
    logging.basicConfig(level=max(logging.DEBUG, min(level, logging.CRITICAL)), handlers=[handler])
    # transitions logs every state callback at INFO: only worth seeing at -vv.
    logging.getLogger("transitions").setLevel(logging.DEBUG if verbose >= 2 else logging.WARNING)
    # matplotlib logs its first font-cache build (a first --plot) at INFO: not ours to show.
    logging.getLogger("matplotlib").setLevel(logging.DEBUG if verbose >= 2 else logging.WARNING)


def _cannot_run(exc: ImportError, verbose: int) -> int:
    """An installation roomba-bt cannot run on: a py_trees release the tree is not proven
    against (``UnsupportedPyTrees`` says which to install), a dependency missing or
    installed incompletely, a module of roomba-bt missing: what to install or reinstall
    (:func:`~roomba_bt.installation.import_failure`), exit 2, the traceback with ``-v``.
    An ImportError of roomba-bt's own code is its bug: :func:`_internal_error`, exit 70."""
    import traceback

    from roomba_bt.installation import import_failure
    from roomba_bt.runtime.summary import ExitCode

    said = import_failure(exc, __version__)
    if said is None:
        return _internal_error(exc, verbose)
    with contextlib.suppress(OSError):
        if verbose:
            traceback.print_exception(exc, file=sys.stderr)
        print(f"roomba-bt: {said}", file=sys.stderr)
    return ExitCode.INVALID


def _command_line_wording() -> ConnectionWording:
    """The command line's words for the connections' messages: a terminal's, or, where stdin
    is no TTY (a systemd service, cron, a timer: nobody to press Clean), the unattended
    robot's owner's (:data:`~roomba_bt.robot.wording.UNATTENDED`)."""
    try:
        attended = sys.stdin is not None and sys.stdin.isatty()
    except (OSError, ValueError):  # stdin closed
        attended = False
    return COMMAND_LINE if attended else UNATTENDED


def main(argv: Sequence[str] | None = None) -> int:
    """The command: ``argv`` None is the process itself (``roomba-bt``), whose streams and
    signals are its own to set (:func:`_as_the_process`); a list is a program's call."""
    process = argv is None
    code: int | None = None  # the command's answer, once known
    try:
        if process:  # inside: a signal may come while it imports, its handlers set
            _as_the_process()
        with spoken(_command_line_wording()):  # the connections' messages name the flags
            code = _command(argv)
        dropped = dropped_interrupt() if process else None
        if dropped is not None and code != INTERRUPTED:  # a run's own ending says it
            code = _interrupted(dropped, process)  # Python dropped it, and the command went on
        return code
    except KeyboardInterrupt as exc:  # Ctrl-C, or SIGTERM/SIGHUP before a run took them
        code = _interrupted(exc, process)
        return code
    except RuntimeError as exc:
        interrupt = _signal_interrupt(exc)
        if interrupt is None:
            raise
        code = _interrupted(interrupt, process)
        return code
    finally:
        if process:
            _answer_given(code)  # the command's answer is out
            problem = stdout_problem()
            if problem is not None:
                print(f"roomba-bt: {problem}", file=sys.stderr)
            _the_exit()


def _interrupted(exc: KeyboardInterrupt, process: bool) -> int:
    """A signal's interrupt that ended the command outside a run's own handling (before it
    took the signal, or a command without one): said in one line, exit 130
    (:attr:`ExitCode.INTERRUPTED`). A robot's connection the command had opened was closed
    on the way, with its stop; a run says its own ending."""
    from roomba_bt.runtime.summary import ExitCode

    if process:
        _answer_given(ExitCode.INTERRUPTED)  # only the last words are left
    from roomba_bt.robot.safety import interrupted_in

    cut_short = interrupted_in(exc)  # a plugin's import or __init__ it cut short, where
    said = f" while {cut_short}" if cut_short else ""
    print(f"roomba-bt: interrupted{_by_signal(exc)}{said}", file=sys.stderr)
    return ExitCode.INTERRUPTED


def _signal_interrupt(exc: BaseException) -> KeyboardInterrupt | None:
    """The signal's interrupt ``exc`` stands for (Python wraps one raised in a class body's
    ``__set_name__`` in a RuntimeError: :func:`~roomba_bt.robot.safety.signal_interrupt`),
    or None."""
    from roomba_bt.robot.safety import signal_interrupt

    return signal_interrupt(exc)


def _command(argv: Sequence[str] | None) -> int:
    try:
        parser = build_parser()
    except ImportError as exc:  # before the arguments are read: -v as the user typed it
        given = sys.argv[1:] if argv is None else argv
        return _cannot_run(exc, sum(1 for a in given if re.fullmatch(r"-v+|--verbose", a)))
    args = parser.parse_args(argv)
    # the process itself (``roomba-bt``), whose signals a command may set to its exit: a
    # program's call keeps its own handlers (run_cmd's answer_given)
    args.as_the_process = argv is None
    args.verbose += getattr(args, "verbose_after", 0)
    args.quiet += getattr(args, "quiet_after", 0)
    setup_logging(args.verbose, args.quiet)
    func = getattr(args, "func", None)
    from roomba_bt.runtime.summary import ExitCode  # imported by the parser's commands

    if func is None:
        parser.print_help(sys.stderr)
        return ExitCode.INVALID
    try:
        return int(func(args))
    except ImportError as exc:  # the subcommands import the tree and the robot lazily
        return _cannot_run(exc, args.verbose)
    except Exception as exc:  # each command has closed what it held (a run: its port)
        if _signal_interrupt(exc) is not None:
            raise  # a signal's, not a bug: main() says it, exit 130
        return _internal_error(exc, args.verbose)


def _internal_error(exc: Exception, verbose: int) -> int:
    """roomba-bt's own bug, in one line with the file:line it came from, the traceback with
    ``-v``; exit 70 (:attr:`ExitCode.INTERNAL_ERROR`). It was Python's traceback and exit 1,
    which a script reads as "the mission failed"."""
    import traceback

    from roomba_bt.runtime.summary import ExitCode

    frames = traceback.extract_tb(exc.__traceback__)
    where = f" (at {frames[-1].filename}:{frames[-1].lineno})" if frames else ""
    with contextlib.suppress(OSError):
        if verbose:
            traceback.print_exception(exc, file=sys.stderr)
        print(f"roomba-bt: internal error: {type(exc).__name__}: {exc}{where}: a bug in roomba-bt, "
              "please report it" + ("" if verbose else " with the traceback (run with -v)"),
              file=sys.stderr)  # fmt: skip
    return ExitCode.INTERNAL_ERROR


def _as_the_process() -> None:
    """What only the process itself sets, first of all (before py_trees is imported, which
    reads ``sys.stdout.encoding``, and before the slow imports of the subcommands):

    * stdout and stderr that a closed pipe, a full disk, a closed descriptor or an encoding
      without ``✓`` cannot end the command with (:func:`~roomba_bt.cli.streams.guard_std_streams`):
      its exit code is its outcome's, never 0 for a broken pipe;
    * the handlers of the entry point (:func:`roomba_bt._entry.take_signals_early`, in
      before this module was imported; here when ``main()`` was reached another way) give
      way to the run's kind, which wait for a safe point
      (:data:`~roomba_bt.robot.safety.interrupts_deferred`: a compressed record's header
      and first flush, written before a run's own handlers are in, are whole whatever
      signal comes): SIGTERM, SIGHUP and SIGQUIT raise
      :class:`~roomba_bt.robot.safety.Terminated`, SIGINT a marked
      :class:`KeyboardInterrupt` (:func:`~roomba_bt.robot.safety.raise_interrupt`), exit 130,
      also when the process was started with SIGINT or SIGQUIT ignored (a script's
      ``roomba-bt run ... &``: its ``kill -INT $!`` was lost in the seconds of start-up,
      and the whole mission ran, exit 0). A SIGHUP started ignored (``nohup``) stays so;
    * a 0.1.0 plugin's call of the encoder's module shown on stderr, at the plugin's line
      (:data:`~roomba_bt.oi.encode.ENCODE_MODULE_CALLED`): Python hides a DeprecationWarning
      outside ``__main__``, and this one's reader is whoever runs the plugin. Not when
      ``-W`` or ``PYTHONWARNINGS`` chose what to show (``error`` makes the call fail)."""
    guard_std_streams()
    take_signals_early()  # a process started by another way than roomba_bt._entry
    from roomba_bt.robot.safety import raise_interrupt, raise_terminated

    for signum in EARLY_SIGNALS:
        with contextlib.suppress(ValueError):  # not the main thread
            if signal.getsignal(signum) is interrupted_early:
                raising = raise_interrupt if signum == signal.SIGINT else raise_terminated
                signal.signal(signum, raising)
    dropped = swallowed_interrupt()  # its raise fell in a callback Python drops it from
    if dropped is not None:
        raise dropped
    if not sys.warnoptions:
        from roomba_bt.oi.encode import ENCODE_MODULE_CALLED

        warnings.filterwarnings("default", re.escape(ENCODE_MODULE_CALLED), DeprecationWarning)


def raise_lost_interrupt(args: argparse.Namespace) -> None:
    """A check a command makes before what an operator's signal must stop (a run's start,
    each file ``validate`` checks): the interrupt a signal handler of the process raised
    that never ended the command (Python dropped it in a weakref callback or a finalizer,
    importlib's module locks run one as a plugin imports; a plugin's ``except
    BaseException`` took it) is raised here. The mission ran to its end, exit 0, and a
    ``validate`` of a thousand files went on to say them all. The process's alone
    (``args.as_the_process``): only its handlers keep what they raise for it."""
    if getattr(args, "as_the_process", False):
        lost = swallowed_interrupt()
        if lost is not None:
            raise lost.with_traceback(None)


def _answer_given(code: int | None) -> None:
    """The command's answer is out (``code``, its exit code; None: an exception goes on), and
    a run's port and record closed: an ending signal lets the last words finish, 2 s at
    most, and the process exits with that answer
    (:func:`~roomba_bt.robot.safety.answer_given`)."""
    from roomba_bt.robot.safety import answer_given

    answer_given(code)


def _the_exit() -> None:
    """The last words flushed (a signal meanwhile ends the process within
    :data:`~roomba_bt.robot.safety.LAST_WORDS_S`), then the ending signals ignored up to the
    process's end (:func:`~roomba_bt.robot.safety.signals_wait_for_the_exit`): one in
    Python's finalization was its default action, the process killed by SIGINT after it had
    said exit 130."""
    from roomba_bt.robot.safety import signals_wait_for_the_exit

    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(OSError, ValueError, AttributeError):  # closed, or None
            stream.flush()
    signals_wait_for_the_exit()


def _by_signal(exc: KeyboardInterrupt) -> str:
    """`` by SIGTERM``: the signal an interrupt stands for, if not Ctrl-C."""
    signum = getattr(exc, "signum", None)
    return f" by {signal.Signals(signum).name}" if signum is not None else ""


if __name__ == "__main__":
    sys.exit(main())
