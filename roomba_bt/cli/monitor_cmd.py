"""The live monitor on the command line: ``run --monitor``/``--watch`` and
``roomba-bt monitor RECORD.jsonl``.

``run`` calls :func:`add_run_arguments` for its options and :class:`LiveMonitor` around its
runner; everything else about the monitor lives in :mod:`roomba_bt.monitor`.
"""

from __future__ import annotations

import argparse
import contextlib
import errno
import logging
import os
import select
import signal
import socket
import string
import sys
import threading
from collections.abc import Mapping
from dataclasses import dataclass
from datetime import datetime
from pathlib import Path
from typing import TYPE_CHECKING, Any

from roomba_bt.cli import raise_lost_interrupt
from roomba_bt.cli.arguments import (
    add_command,
    add_param_option,
    add_permission_options,
    add_window_options,
    parse_window,
)
from roomba_bt.monitor import INSTALL_HINT, server_available
from roomba_bt.monitor.address import DEFAULT_HOST, lan_addresses, parse_address
from roomba_bt.printable import name_shown
from roomba_bt.runtime.summary import ExitCode, Outcome

if TYPE_CHECKING:  # loaded when a world is drawn
    from roomba_bt.sim.world import World

log = logging.getLogger("roomba_bt.monitor")
KEYS_HELP = "keys: p pause, r resume, n step, q stop"
#: said once (in the log and the page's event log) when the run's terminal hangs up
KEYS_HUNG_UP = (
    "monitor: keys: off (the terminal hung up: an SSH session dropped?); the page's controls work"
)
#: after the page's URL when the token is the operator's (``--monitor-token``)
CHOSEN_TOKEN = " (add ?token= and your --monitor-token, or open your bookmark)"
#: after the view-only URL when its token is the operator's (``--monitor-view-token``)
CHOSEN_VIEW_TOKEN = " (add ?token= and your --monitor-view-token, or open its bookmark)"


#: how many ports after a taken one are tried for one free now (:func:`free_port_after`)
FREE_PORT_TRIES = 32


def bind_problem(host: str, port: int) -> OSError | None:
    """Why ``host:port`` cannot be listened on now (None: it can), found by binding a socket
    and closing it, with the address reuse the server's own socket has (a port whose last
    connection waits out TIME_WAIT is free to it)."""
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    try:
        with socket.socket(family, socket.SOCK_STREAM) as probe:
            probe.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            probe.bind((host, port))
    except OSError as exc:
        return exc
    return None


def free_port_after(host: str, port: int) -> int | None:
    """The first port after ``port`` that ``host`` can listen on right now, of the next
    :data:`FREE_PORT_TRIES`; None if none is. The suggestion was ``port + 1`` unchecked, and
    a teacher starting several runs was sent to a port another run had."""
    last = min(port + FREE_PORT_TRIES, 65535)
    return next((p for p in range(port + 1, last + 1) if bind_problem(host, p) is None), None)


def _monitor_option(host: str, port: int) -> str:
    """``--monitor 8766`` on the default host, else ``--monitor HOST:8766``."""
    if host == DEFAULT_HOST:
        return f"--monitor {port}"
    return f"--monitor [{host}]:{port}" if ":" in host else f"--monitor {host}:{port}"


def address_problem(host: str, port: int, exc: OSError) -> str:
    """Why the monitor's page cannot be served at ``host:port``; a port taken (another run's
    monitor, most likely) names a port free now and ``--monitor 0``, which takes any free
    port and prints it: the answer for several runs on one machine."""
    if exc.errno == errno.EADDRINUSE or "address already in use" in str(exc):
        free = free_port_after(host, port)
        instead = f"{free} is free now: {_monitor_option(host, free)}; or " if free else ""
        return (
            f"--monitor {host}:{port}: the port is taken (another run's monitor?); "
            f"{instead}{_monitor_option(host, 0)} takes any free port (the run prints it)"
        )
    return f"--monitor {host}:{port}: {exc.strerror or exc}"


def monitor_address(text: str) -> tuple[str, int]:
    """``--monitor [HOST:]PORT``: checked when the arguments are read, the web library too,
    so a run without it ends with exit 2 before anything moves."""
    if not server_available():
        raise argparse.ArgumentTypeError(INSTALL_HINT)
    try:
        return parse_address(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


#: the environment's ``--monitor-token``, for a bookmark that outlives the run
TOKEN_VARIABLE = "ROOMBA_BT_MONITOR_TOKEN"
#: the environment's ``--monitor-view-token``: a view-only bookmark (a class's, a
#: projector's) that outlives the run
VIEW_TOKEN_VARIABLE = "ROOMBA_BT_MONITOR_VIEW_TOKEN"
#: each chosen token: its option, its ``args`` attribute and its environment variable
CHOSEN_TOKENS = (
    ("--monitor-token", "monitor_token", TOKEN_VARIABLE),
    ("--monitor-view-token", "monitor_view_token", VIEW_TOKEN_VARIABLE),
)
#: the switches that shape the page ``--monitor`` serves: without it each is said to be a
#: mistake, as a token is (``--monitor-readonly`` alone read like "a read-only monitor",
#: and the run served no page without a word)
MONITOR_SWITCHES = (
    ("--monitor-readonly", "monitor_readonly"),
    ("--monitor-force", "monitor_force"),
)
#: a token's length: as long as the generated one's at least (``secrets.token_urlsafe(18)``,
#: 24 characters), at most what a URL and a cookie carry without trouble
TOKEN_LENGTH = (24, 256)
#: a token's characters: URL-safe base64's, so it goes into the URL and the cookie as it is
TOKEN_CHARACTERS = frozenset(string.ascii_letters + string.digits + "-_")
MAKE_ONE = "python -c 'import secrets; print(secrets.token_urlsafe(18))'"


def token_problem(token: str) -> str:
    """What is wrong with a chosen monitor token, or "" (the token itself is never said: it
    must not end up in a terminal's scrollback or a CI log from a message)."""
    shortest, longest = TOKEN_LENGTH
    if not shortest <= len(token) <= longest:
        said = f"it has {len(token)} character{'' if len(token) == 1 else 's'}"
    elif not set(token) <= TOKEN_CHARACTERS:
        said = "it has a character other than A-Z a-z 0-9 - _"
    else:
        return ""
    return (
        f"{said}; a token is {shortest} to {longest} characters of A-Z a-z 0-9 - _ "
        f"(make one: {MAKE_ONE})"
    )


def monitor_token(text: str) -> str:
    """``--monitor-token TOKEN``: checked when the arguments are read (exit 2)."""
    problem = token_problem(text)
    if problem:
        raise argparse.ArgumentTypeError(problem)
    return text


def chosen_token(args: argparse.Namespace, environ: Mapping[str, str] = os.environ) -> str:
    """``--monitor-token`` and ``--monitor-view-token``, each else its variable from
    ``environ`` (:data:`CHOSEN_TOKENS`; checked here: its problem names the variable), into
    ``args``; "" when all is well, else what is wrong. A token on the command line without
    ``--monitor`` is a mistake said as such; a variable, set once for every run, is left
    unused then. The two the same is a mistake too: the view link would have the controls.
    A switch of :data:`MONITOR_SWITCHES` without ``--monitor`` is the same mistake."""
    if args.monitor is None:
        for option, attribute in MONITOR_SWITCHES:
            if getattr(args, attribute, False):
                return f"{option} is for --monitor: add it"
    for option, attribute, variable in CHOSEN_TOKENS:
        if getattr(args, attribute, None) is not None:
            if args.monitor is None:
                return f"{option} is for --monitor: add it"
            continue
        from_environment = environ.get(variable, "")
        if not from_environment or args.monitor is None:
            continue
        problem = token_problem(from_environment)
        if problem:
            return f"{variable}: {problem}"
        setattr(args, attribute, from_environment)
    control, view = args.monitor_token, getattr(args, "monitor_view_token", None)
    if control is not None and control == view:
        return (
            "the view-only token (--monitor-view-token or "
            f"{VIEW_TOKEN_VARIABLE}) is the control token (--monitor-token or {TOKEN_VARIABLE}): "
            f"whoever has the view link would have the controls; choose another ({MAKE_ONE})"
        )
    return ""


def say_where(host: str, url: str, which: str) -> None:
    """What the URL alone does not say: a wildcard address is no address to open from
    another machine (browsers refuse 0.0.0.0), so the machine's name and LAN addresses
    follow it (``run`` and ``monitor RECORD`` alike: a record shown on a phone needs them
    too). ``which``: the line's start after ``monitor: `` (which link it is)."""
    if host not in WILDCARD_HOSTS:
        return
    bound = f"//[{host}]:" if ":" in host else f"//{host}:"
    named = url.replace(bound, f"//{socket.gethostname()}:", 1)
    by_address = [
        url.replace(bound, f"//[{a}]:" if ":" in a else f"//{a}:", 1)
        for a in lan_addresses(ipv6=host == "::")
    ]
    also = f" or, by address, {' or '.join(by_address)}" if by_address else ""
    print(f"monitor: {which} on every address of this machine: {named}{also}", flush=True)


def add_run_arguments(run: argparse.ArgumentParser) -> None:
    run.add_argument(
        "--monitor", nargs="?", const="", type=monitor_address, metavar="[HOST:]PORT",
        help="serve the live monitor page (default 127.0.0.1:8765; another address needs the "
        "token printed in the URL)",
    )  # fmt: skip
    run.add_argument(
        "--monitor-readonly", action="store_true",
        help="the monitor page has no controls (the terminal's keys still work)",
    )  # fmt: skip
    run.add_argument(
        "--monitor-token", type=monitor_token, metavar="TOKEN",
        help=f"the page's token instead of a new one each run, so a bookmark keeps working "
        f"(also {TOKEN_VARIABLE}); {TOKEN_LENGTH[0]} to {TOKEN_LENGTH[1]} of A-Z a-z 0-9 - _; "
        "not printed",
    )  # fmt: skip
    run.add_argument(
        "--monitor-view-token", type=monitor_token, metavar="TOKEN",
        help="the view-only link's token (the page without its controls, for a class or a "
        f"projector) instead of a new one each run (also {VIEW_TOKEN_VARIABLE}); as "
        "--monitor-token, and not the same; not printed",
    )  # fmt: skip
    run.add_argument(
        "--monitor-force", action="store_true",
        help="allow forcing conditions from the page on a real robot (always on the simulator)",
    )  # fmt: skip
    run.add_argument(
        "--watch", action="store_true",
        help="reload the mission when its file changes: valid, the new tree starts at the next "
        "safe point; invalid, the run goes on and the errors are shown",
    )  # fmt: skip


#: addresses that listen on every interface: no address to open a page at
WILDCARD_HOSTS = ("0.0.0.0", "::", "")


@dataclass(frozen=True)
class MonitorOptions:
    """What one run's live monitor does, typed, so that a program can build one as well as
    ``run`` can (:meth:`from_args` converts its options; :class:`LiveMonitor` took the
    argparse namespace itself, and read it by attribute names a caller had to guess)."""

    #: the mission file: what ``watch`` reloads, and the first of the files it watches
    mission: Path
    #: (host, port) to serve the page at (``--monitor``); None: no page
    address: tuple[str, int] | None = None
    #: the page has no controls (``--monitor-readonly``); the terminal's keys still work
    readonly: bool = False
    #: the page's token (``--monitor-token``); None: a new one each run, said in the URL
    token: str | None = None
    #: the view-only link's token (``--monitor-view-token``); None: a new one each run
    #: where a token is in force, said in the view-only URL
    view_token: str | None = None
    #: conditions may be forced from the page on a real robot (``--monitor-force``; always
    #: allowed on the simulator)
    allow_force: bool = False
    #: reload the mission when one of its files changes (``--watch``)
    watch: bool = False
    #: a reloaded mission with compile-time warnings is refused (``run --strict``, which
    #: does not start one either)
    strict: bool = False
    #: the run is on the virtual clock (``--fast``): the session paces it, and the page is
    #: told it may end before anyone opens it
    virtual_clock: bool = False

    @classmethod
    def from_args(cls, args: argparse.Namespace) -> MonitorOptions:
        """``run``'s options as the monitor reads them (the token already taken from the
        environment by :func:`chosen_token`)."""
        return cls(
            mission=Path(args.mission),
            address=args.monitor,
            readonly=bool(args.monitor_readonly),
            token=args.monitor_token,
            view_token=getattr(args, "monitor_view_token", None),
            allow_force=bool(args.monitor_force),
            watch=bool(args.watch),
            strict=bool(getattr(args, "strict", False)),
            virtual_clock=bool(args.fast),
        )


class LiveMonitor:
    """The feed, session, server, file watcher and terminal keys of one ``run``."""

    def __init__(
        self,
        options: MonitorOptions,
        mission: Any,
        *,
        simulator: Any,
        packets: tuple[int, ...],
        loader: Any,
        robot: str = "",
        started: datetime | None = None,
        label: str = "",
    ) -> None:
        from roomba_bt.monitor.feed import EventLogHandler, RunFeed
        from roomba_bt.monitor.session import MonitorSession
        from roomba_bt.monitor.views import world_view
        from roomba_bt.runtime.display import live_names

        self.options = options
        self.loader = loader
        self._watched = _files_of(mission, options.mission)
        truth = None
        world = None
        if simulator is not None:

            def truth() -> tuple[float, float, float]:
                return (simulator.x, simulator.y, simulator.theta)

            world = world_view(simulator)
        self.feed = RunFeed(
            source="simulator" if simulator is not None else "robot",
            truth=truth,
            world=world,
            mission_name=mission.name,
            robot=robot,
            started=started,
            label=label,
        )
        self.feed.set_tree(mission.root, live_names(mission))
        self.session = MonitorSession(
            self.feed,
            simulator=simulator is not None,
            allow_force=options.allow_force,
            paced=options.virtual_clock,
            stream_packets=packets,
        )
        if options.watch:
            self.session.state.watching = str(options.mission)
        self.server: Any = None
        self._handler = EventLogHandler(self.feed)
        self._done = threading.Event()
        self._threads: list[threading.Thread] = []
        self._terminal: Any = None

    def bind(self) -> int | None:
        """Serve the page (when asked), before the robot is opened: an address that cannot
        be used is an exit code (2) before anything is opened or moved. Its URL is said by
        :meth:`start`, once the robot's port is open."""
        if self.options.address is not None:
            from roomba_bt.monitor.server import MonitorServer

            host, port = self.options.address
            self.server = MonitorServer(
                self.feed, self.session, host=host, port=port,
                readonly=self.options.readonly, token=self.options.token,
                view_token=self.options.view_token,
            )  # fmt: skip
            try:
                self.server.start()
            except OSError as exc:
                print(f"roomba-bt: {address_problem(host, port, exc)}", file=sys.stderr)
                return ExitCode.INVALID
        return None

    def start(self) -> None:
        """The robot's port is open (or the simulator made): say the page's URL, with the
        mission and the robot it is for, and start the watcher and the keys. The URL was said
        before the port was opened, and a busy port left a URL in the terminal that never
        served a page."""
        if self.server is not None:
            self._say_urls()
        logging.getLogger("roomba_bt").addHandler(self._handler)
        if self.options.watch:
            self._spawn(self._watch, "roomba-bt watch")
        from roomba_bt.runtime.display import in_foreground

        if sys.stdin.isatty():  # the operator's at the keyboard, --monitor-readonly or not
            if in_foreground(sys.stdin.fileno()):
                print(KEYS_HELP, flush=True)
                self._spawn(self._keys, "roomba-bt keys")
            else:  # setting the terminal from the background (&) stopped the run (SIGTTOU)
                print("keys: off (started in the background); the page's controls work")

    def _say_urls(self) -> None:
        """The page's URL with the control token, then (where a token is in force) the
        view-only one to share: a class, a projector, a link sent on; each with the
        machine's own addresses when it listens on every one. A chosen token is the
        operator's own: known to them, printed nowhere."""
        assert self.server is not None and self.options.address is not None
        host, server = self.options.address[0], self.server
        chosen = self.options.token
        url = _without_token(server.url) if chosen else server.url
        feed = self.feed
        # each on one line and cut, as the summary says them (a 10 MB mission name)
        mission, robot, label = (name_shown(t) for t in (feed.mission_name, feed.robot, feed.label))
        which = f"{mission} on {robot}" if robot else ""
        which = ": ".join(filter(None, (label, which)))
        which = f" ({which})" if which else ""
        print(f"monitor: {url}{which}{CHOSEN_TOKEN if chosen else ''}", flush=True)
        say_where(host, url, "it listens")
        if server.view_url is not None:
            chosen_view = self.options.view_token
            view_url = _without_token(server.view_url) if chosen_view else server.view_url
            said = CHOSEN_VIEW_TOKEN if chosen_view else ""
            print(f"monitor: view only: {view_url}{said}", flush=True)
            say_where(host, view_url, "view only: it listens")
        if self.options.virtual_clock:
            print(
                "roomba-bt: --fast runs the mission on the virtual clock: it may end before a "
                "page opens (in real time without --fast; or --record it and open the record "
                "with roomba-bt monitor FILE)",
                file=sys.stderr,
            )

    def _spawn(self, target: Any, name: str) -> None:
        thread = threading.Thread(target=target, name=name, daemon=True)
        thread.start()
        self._threads.append(thread)

    def finish(self, summary: Any) -> None:
        """After the run (``summary``), or when it could not start (None)."""
        from roomba_bt.monitor.feed import Ending

        if summary is None:
            self.feed.end("the run did not start", None)
        else:
            # what the robot was left in, which no tick shows (the safe stop comes after the
            # last one): the banner says it, and the robot panel shows it in place of the
            # last tick's Safe, wheels turning and brushes on
            ending = Ending.of(summary)
            self.feed.end(ending.banner(), ending)
        self._done.set()
        logging.getLogger("roomba_bt").removeHandler(self._handler)
        for thread in self._threads:
            thread.join(1.0)
        if self.server is not None:
            self.server.close(grace_s=0.3)

    # ---------------------------------------------------------------- --watch
    def _watch(self) -> None:
        """Every 0.25 s: has the mission file or a file it includes changed? Then reload. The
        files watched are those of the last mission that loaded (an include added or removed
        by a valid reload is watched from then on), and always the mission file."""
        from roomba_bt.behaviours.registry import file_version

        path = self.options.mission
        stamps = {f: file_version(f) for f in self._watched}
        shown = ", ".join(_shown(f) for f in self._watched)
        print(f"watching {shown}: a change reloads the mission", flush=True)
        while not self._done.wait(0.25):
            now = {f: file_version(f) for f in self._watched}
            if now == stamps:
                continue
            changed = [f for f in self._watched if now[f] != stamps.get(f)]
            # the stamps seen before the reload reads the files: an edit made while it reads
            # is seen at the next look (stamps taken after it would hide that edit)
            stamps = now
            mission = self._reload(path, changed)
            if mission is not None:
                self._watched = _files_of(mission, path)
                stamps = {f: now[f] if f in now else file_version(f) for f in self._watched}

    def _reload(self, path: Path, changed: list[Path]) -> Any:
        """The new mission once it is handed to the session, or None (refused: why is said
        on the terminal and in the page's events, and the old mission runs on)."""
        from roomba_bt.mission import reported

        names = ", ".join(_shown(f) for f in changed)
        self.feed.event("reload", f"changed: {names}; checking {path}")
        mission, refused = self._reloadable(path)
        if refused:
            for line in refused:
                print(f"reload refused: {line}", file=sys.stderr, flush=True)
            self.feed.event("error", "reload refused, the run goes on: " + "; ".join(refused))
            return None
        for line in reported(mission.warnings):  # said, as run says them at its start
            print(f"reload: {line}", file=sys.stderr, flush=True)
            self.feed.event("warning", f"reloaded with a warning: {line}")
        print(f"reload: {path} is valid; the new tree starts at the next safe point", flush=True)
        self.session.reload(mission)
        return mission

    def _reloadable(self, path: Path) -> tuple[Any, list[str]]:
        """The mission at ``path`` and why it may not replace the running one (empty: it
        may). Under ``--strict`` a mission with compile-time warnings may not, in ``validate
        --strict``'s words: ``run --strict`` does not start one, and a reload took it."""
        from roomba_bt.cli.validate_report import failed_strict
        from roomba_bt.mission import MissionError, reported

        try:
            mission = self.loader(path)
        except MissionError as exc:
            return None, reported(exc.diagnostics)
        except OSError as exc:
            return None, [f"{path}: {exc.strerror or exc}"]
        warnings = mission.warnings
        if self.options.strict and warnings:
            return mission, [*reported(warnings), failed_strict(str(path), warnings)]
        why = self.session.check_reloadable(mission)
        return mission, [] if why is None else [f"{path}: {why}"]

    # ---------------------------------------------------------------- terminal keys
    def _keys(self) -> None:
        """Read the operator's keys until the run ends or the terminal goes. A terminal that
        hung up (an SSH session dropped, its window closed) reads as the end of the file, at
        once and for ever: each empty read was taken for a key that "does nothing", said on
        its own log line, about 6 000 a second (10 MB of log in 15 s, a core busy) for as
        long as the run went on without its terminal (SIGHUP ignored), and giving the
        terminal back its settings then raised in this thread (a traceback in the log)."""
        import termios
        import tty

        fd = sys.stdin.fileno()
        try:
            saved = termios.tcgetattr(fd)
            tty.setcbreak(fd)
        except termios.error:
            return
        actions = {"p": "pause", "r": "resume", "n": "step", "q": "stop"}
        try:
            while not self._done.is_set():
                ready, _, _ = select.select([fd], [], [], 0.2)
                if not ready:
                    continue
                try:
                    read = os.read(fd, 1)
                except OSError:  # the terminal gone, or read from the background (EIO)
                    return
                if not read:
                    log.warning(KEYS_HUNG_UP)
                    return
                key = read.decode(errors="replace").lower()
                self._key(key, actions.get(key))
        finally:
            with contextlib.suppress(termios.error):  # a terminal gone has nothing to restore
                termios.tcsetattr(fd, termios.TCSADRAIN, saved)

    def _key(self, key: str, action: str | None) -> None:
        """One key's request; a key that does nothing (one not listed, ``r`` while running)
        says why on a status line: it was passed over without a word."""
        if action is None:
            log.info("monitor: key %r does nothing (%s)", key, KEYS_HELP)
            return
        try:
            self.session.request(action, by="the terminal's keys")
        except ValueError as exc:  # ControlRefused: e.g. resume when not paused
            log.info("monitor: key %s (%s) refused: %s", key, action, exc)


def _without_token(url: str) -> str:
    """``url`` without its ``?token=...``: a chosen token is not printed."""
    return url.split("?token=", 1)[0]


def _files_of(mission: Any, path: Path) -> tuple[Path, ...]:
    """The mission file and the files it includes, each once."""
    files = getattr(mission, "files", ()) or ()
    return tuple(dict.fromkeys([path.resolve(), *files]))


def _shown(path: Path) -> str:
    with contextlib.suppress(ValueError):
        return str(path.relative_to(Path.cwd()))
    return str(path)


# -------------------------------------------------------------------- roomba-bt monitor
def register(sub: Any) -> None:
    monitor = add_command(
        sub,
        "monitor",
        monitor_command,
        """the live monitor's page for a recorded run (run --record)

        Replay RECORD (written by run --record) through its mission and serve the monitor page for
        it: scrub the timeline, play at any speed. Ctrl-C ends it.
        """,
    )
    monitor.add_argument("record", help="a file written by run --record")
    monitor.add_argument(
        "--monitor", type=monitor_address, default=None, metavar="[HOST:]PORT",
        help="where to serve the page (default 127.0.0.1:8765)",
    )  # fmt: skip
    monitor.add_argument("--mission", help="mission to replay against (default: the recorded one)")
    monitor.add_argument(
        "--world", metavar="FILE_OR_NAME",
        help="the world to draw the run in (a file, or a world's name as run --world takes it; "
        "default: the one the record names, read only beside the record and its mission, in "
        "your world folders or by name)",
    )  # fmt: skip
    add_param_option(monitor, "set a mission parameter for the replay (repeatable)")
    add_permission_options(monitor)
    add_window_options(monitor, start=True)


#: a record from this size of text on is said to be read before its page is served: its URL
#: comes after the replay, about a second a MB on the development machine (a 6-minute clean
#: run's 4.9 MB record: 5 s, silent before); its progress is said from run_cmd's
#: PROGRESS_FROM_BYTES on
READING_NOTICE_BYTES = 1 << 20
#: how many times its file's size a compressed record's text is taken to be where its gzip
#: trailer cannot say (a run killed): 10 to 12 measured (docs/runtime.md, Long unattended runs)
COMPRESSED_TEXT_RATIO = 10


def reading_notice(path: str) -> str | None:
    """What ``roomba-bt monitor`` says before it reads a record of a second or more (None: a
    shorter one, or a file it cannot read, which the load then names): its size, and a
    compressed record's text size beside its file's (the replay's time goes by the text).
    It said the compressed file's size as the record's (``2.3 MB`` for 23.6 MB of record),
    and a compressed record under 1 MB, 10 MB of record, was read without a word."""
    from roomba_bt.runtime.recording import record_size

    try:
        size = record_size(Path(path))
    except OSError:
        return None
    text = size.text if size.text is not None else size.file * COMPRESSED_TEXT_RATIO
    if text < READING_NOTICE_BYTES:
        return None
    if not size.compressed:
        words = f"{size.file / 1e6:.1f} MB"
    elif size.text is not None:
        words = f"{size.text / 1e6:.1f} MB of record, {size.file / 1e6:.1f} MB compressed"
    else:  # no trailer to say it: a run killed, or one still writing it
        words = f"{size.file / 1e6:.1f} MB compressed, its record's own size known once read"
    return (
        f"monitor: reading {path} ({words}) before serving it: the page's timeline is the "
        "whole run's, so every tick is replayed first"
    )


#: how often a record's page looks for a Ctrl-C Python dropped (:func:`_serve_record`)
DROPPED_LOOK_S = 0.25


def _usage_error(message: str) -> int:
    """``roomba-bt monitor: MESSAGE``, exit 2: the command named, as every command's usage
    errors name theirs (run_cmd._error)."""
    print(f"roomba-bt monitor: {message}", file=sys.stderr)
    return ExitCode.INVALID


def _chosen_world(given: str | None) -> World | str | None:
    """``monitor --world``'s world (None: none given), or its problems as the lines to print:
    read before the replay, which takes minutes for a long record."""
    if given is None:
        return None
    from roomba_bt.cli.worlds_cmd import world_error_text
    from roomba_bt.sim.world import WorldError, load_world

    try:
        return load_world(given)
    except WorldError as exc:
        return world_error_text(exc, "monitor")


def _draw_recorded_world(
    feed: Any, record: Any, mission: Any, shown: str, chosen: World | None
) -> None:
    """The world ``record`` names (or the user's ``chosen``, ``--world``) into its page
    (odometry's 0 where the robot started in it), or why not on stderr (``shown``: the record
    as the user named it); ``mission``: the compiled mission replayed, whose file, with the
    record's, bounds where the record's world may be."""
    from roomba_bt.monitor.recorded import recorded_world

    drawn = recorded_world(record, mission.files[0] if mission.files else record.path, chosen)
    if isinstance(drawn, str):
        print(f"monitor: {shown}: {drawn}", file=sys.stderr)
    elif drawn is not None:
        feed.world, feed.truth_start = drawn


def monitor_command(args: argparse.Namespace) -> int:
    from roomba_bt.cli.run_cmd import load_recorded, replay_progress

    if not server_available():
        print(f"roomba-bt: {INSTALL_HINT}", file=sys.stderr)
        return ExitCode.INVALID
    from roomba_bt.monitor.recorded import replay_into_feed
    from roomba_bt.runtime.provenance import changed_since

    host, port = args.monitor or parse_address(None)
    taken = bind_problem(host, port) if port else None
    if taken is not None:  # said before the replay: a long record's took minutes first
        print(f"roomba-bt: {address_problem(host, port, taken)}", file=sys.stderr)
        return ExitCode.INVALID
    window = parse_window(args)
    if isinstance(window, str):
        return _usage_error(window)
    chosen = _chosen_world(args.world)
    if isinstance(chosen, str):  # each problem at its file:line:col, as run --world says them
        print(chosen, file=sys.stderr)
        return ExitCode.INVALID
    notice = reading_notice(args.record)  # load_recorded says what is wrong with the file
    if notice is not None:  # a second or more before the page
        print(notice, file=sys.stderr, flush=True)
    recorded = load_recorded(args)
    if isinstance(recorded, int):
        return recorded
    raise_lost_interrupt(args)  # one Python dropped as the mission's plugins imported
    record, mission, profile, baud, packets = recorded
    if window[0] > record.last_t:
        return _usage_error(f"--from {args.window_from}: the record ends at {record.last_t:.2f} s")

    def diverged_at(text: str) -> None:
        """Where the replay diverged, and each file and plugin changed since the record was
        made."""
        for line in (text, *changed_since(record.header, mission.files, mission.root, record.path)):
            print(f"monitor: {args.record}: {line}", file=sys.stderr)

    feed, summary = replay_into_feed(
        record, mission, profile, packets, baud, args.record,
        progress=replay_progress("monitor", record), diverged_at=diverged_at, window=window,
    )  # fmt: skip
    if summary.outcome is Outcome.INTERRUPTED:  # a signal's, as `replay` says it: no page
        print(
            f"monitor: {args.record}: interrupted ({summary.reason}) at mission time "
            f"{summary.mission_time_s:.3f} s of {record.last_t:.3f} s, as it was read: no page "
            "served",
            file=sys.stderr,
        )
        return ExitCode.INTERRUPTED
    _draw_recorded_world(feed, record, mission, args.record, chosen)
    return _serve_record(feed, host, port, args)


def _serve_record(feed: Any, host: str, port: int, args: argparse.Namespace) -> int:
    """The page of a replayed record, until Ctrl-C or SIGTERM (exit 0); a port that cannot be
    served is exit 2. A Ctrl-C whose interrupt Python dropped (a finalizer or weakref callback
    ran as it came: ``roomba-bt: SIGINT came while Python ran ...``) ends it too, before the
    page is served (exit 130) or at the next look, four times a second, once it is: it was
    served until a second Ctrl-C."""
    from roomba_bt.monitor.server import MonitorServer

    raise_lost_interrupt(args)  # one Python dropped as the record was replayed: no page
    path = args.record
    server = MonitorServer(feed, None, host=host, port=port, readonly=True)
    try:
        url = server.start()
    except OSError as exc:
        print(f"roomba-bt: {address_problem(host, port, exc)}", file=sys.stderr)
        return ExitCode.INVALID
    print(f"{path}: {feed.finished}")
    ended = threading.Event()
    # SIGTERM (a service manager, `kill`) ends it as Ctrl-C does: the pages told, exit 0; it
    # killed the process before (exit 143, no word)
    previous = signal.signal(signal.SIGTERM, lambda *_: ended.set())
    print(f"monitor: {url}  (Ctrl-C ends)", flush=True)
    say_where(host, url, "it listens")
    try:
        while not ended.wait(DROPPED_LOOK_S):
            raise_lost_interrupt(args)  # ends it as Ctrl-C does
        print("monitor: ended by SIGTERM", flush=True)
    except KeyboardInterrupt:
        pass
    finally:
        signal.signal(signal.SIGTERM, previous)
        server.close()
    return ExitCode.OK
