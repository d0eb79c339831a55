"""``roomba-bt doctor --port URL``: find the robot on a port and say what it is, step by step.

Each step prints what it saw and, when it fails, what to do next::

    port      the port opens (RTS and DTR released: BRC high, so opening wakes nothing)
    baud      Start and a Query List at 115200, then 19200 (robot/discovery.py)
    wake      silent at both: BRC pulsed one second through RTS/DTR (or, where they cannot be
              set, a one-second hang-up: speed 0), both rates again
    start     the mode packet right after Start: Passive reads 1, or 2 (the mode + 1 bug)
    reset     --allow-reset only: Reset (7) and its banner (a Roomba 500 has no Reset)
    stream    a short stream: frames counted, checksums checked, which checksum convention
    timing    when its frames came: the spread of their intervals and the longest gap, against
              what run's --watchdog and --grace tolerate (a network bridge's jitter, stalls)
    profile   the profiles that fit: the banner, the checksum convention, the mode reading,
              readings only one model's ranges allow (wall signal 27, stasis 58)
    setting   the model ROOMBA_BT_PROFILE or the project file names, and whether it fits
    battery   charge, capacity, voltage, current;  charging: state and sources;  mode
    missions  each shipped mission's stream frame against the bytes a 15 ms slot carries
    firmware  the release the banner names, and whether it wakes by BRC on the dock

The robot is left in Passive with the stream paused. Exit codes
(:class:`~roomba_bt.runtime.summary.ExitCode`, one table for every command): 0 the robot was
found and named; 2 usage; 3 the port could not be opened; 5 nothing answered at any OI rate
(even after a BRC pulse, or none could be given); 6 the robot answered but a later step
failed (no stream, the link lost, a reply that makes no sense); 130 interrupted.
"""

from __future__ import annotations

import argparse
import contextlib
import itertools
import sys
import warnings
from dataclasses import dataclass, field
from enum import IntEnum
from typing import TYPE_CHECKING, Any, TextIO

from roomba_bt._lazy import moved_warning
from roomba_bt.cli.arguments import add_command, baud_or_auto, duration, port_name
from roomba_bt.oi.frames import SLOT_SECONDS
from roomba_bt.oi.identify import MODEL_RANGE_PACKETS
from roomba_bt.oi.modes import OI_MODE_PACKET
from roomba_bt.oi.packets import packet_ids
from roomba_bt.robot.errors import DEFAULT_WATCHDOG
from roomba_bt.runtime.summary import DEFAULT_GRACE, INTERNAL_ERROR_SAID, POOR_LINK, ExitCode

if TYPE_CHECKING:
    from roomba_bt.oi.frames import SensorFrame
    from roomba_bt.robot.discovery import Search
    from roomba_bt.transport.link_kind import LinkWords

#: The battery step's Query List.
STATUS_PACKETS = packet_ids(
    "charging_state", "voltage", "current", "battery_charge", "battery_capacity",
    "charging_sources", "oi_mode",
)  # fmt: skip
(CHARGING_STATE_PACKET,) = packet_ids("charging_state")
#: How long the banner may take to print after Reset, and the quiet that ends it.
BANNER_LIMIT_S = 6.0
BANNER_QUIET_S = 0.5

#: a silent robot on the dock, whatever the link: old firmware does not wake by BRC there
DOCK_WAKE = (
    "a robot on the dock with firmware older than release-3.8.2 / release-stm32-3.7.7 does "
    "not wake by BRC there: lift it off the dock or press Clean"
)
#: the start of every fix for a silent robot that could not be pulsed
ASLEEP = (
    "a robot asleep (5 minutes in Passive) answers nothing until a BRC pulse or its Clean "
    "button, as does one a host powered down (Power, 133): press Clean and run doctor again"
)


@dataclass(frozen=True, slots=True)
class LinkFixes:
    """doctor's fixes where they name the line: a cable and its adapter on a device path (the
    words docs/doctor.md quotes), the bridge at its address, its power, its Wi-Fi and its
    serial side on a network port, the program at its other end on a pty's own path. A
    Wi-Fi bridge's user was told to check a cable there is none of. Chosen once from the
    port's :class:`~roomba_bt.transport.link_kind.LinkWords` (:attr:`Report.fixes`)."""

    #: silent at every rate, and this port cannot pulse BRC
    wake: str
    #: silent at every rate even after a BRC pulse
    silent: str
    #: bytes came at the rates tried, none an answer, even after a BRC pulse
    garbled: str
    #: the port gives back every byte written to it
    echo: str
    #: what to check before running doctor again ("check the cable")
    recheck: str
    #: why a robot that answers queries sends no whole stream frame
    drops: str
    #: why a status reply cannot be the robot's (garbled or stale bytes)
    delays: str
    #: why status replies a moment apart never agree
    garbles: str


CABLE_FIXES = LinkFixes(
    wake=(
        f"{ASLEEP}. To wake it from here, use a cable that wires BRC to RTS or DTR (the "
        "iRobot Create cable does) or an rfc2217:// bridge (roomba-bt sim --rfc2217 serves one)"
    ),
    silent=(
        "check that the robot is on (press Clean: its light comes on), that the cable is a "
        "5 V TTL serial adapter with TX and RX not swapped, and that no other program holds the "
        f"port; {DOCK_WAKE}"
    ),
    garbled=(
        "the robot may be there, but what it sends arrives garbled: check the cable and "
        "the adapter (noise on a long or loose cable, a bad adapter, a 3.3 V adapter on the 5 V "
        "line), and the port's serial settings (8N1, no flow control; a robot set to a rate "
        "other than 115200 or 19200 by Baud (129) answers at neither: power it off and on)"
    ),
    echo=(
        "this is not a robot's port: loop:// or a test port, a cable or adapter whose "
        "transmit and receive lines are joined, or the wrong device; give the robot's port (ls "
        "/dev/ttyUSB*)"
    ),
    recheck="check the cable",
    drops="a long cable, a bad adapter",
    delays="a long cable, a bad adapter, a relay",
    garbles="a loose or long cable, a wrong baud rate",
)


#: What the program at a pty's other end may be: ``roomba-bt sim --pty`` (whose fault options
#: garble, drop and delay bytes on purpose), or a bridge such as socat with a robot's cable
#: behind it (the words :func:`~roomba_bt.transport.link_kind.link_of` gives a pty's link)
_PTY_END = "the program at the pty's other end"
_SOCAT = "a bridge such as socat"
_SIM_PTY = "the path roomba-bt sim --pty printed"

#: doctor's fixes on a pty's own path (/dev/pts/N): the other end is a program, not a cable.
#: ``sim --pty --corrupt-rate 1.0`` was told to "check the cable and the adapter (noise on a
#: long or loose cable, ... a 3.3 V adapter on the 5 V line)"; a pty nobody reads, "that the
#: cable is a 5 V TTL serial adapter"; one that echoes, "give the robot's port (ls
#: /dev/ttyUSB*)". The cable is said only as what may be behind a bridge.
PTY_FIXES = LinkFixes(
    wake=(
        f"{ASLEEP}. To wake it from here: a pty carries no modem lines and could not be hung "
        "up either; roomba-bt sim --rfc2217 carries BRC to the simulator's robot, and a "
        "robot's cable with BRC on RTS or DTR carries it opened by its own device path, not "
        f"through {_SOCAT}"
    ),
    silent=(
        f"check that {_PTY_END} still runs and is the simulator (give {_SIM_PTY}), not "
        "another program's pty, and that no other program holds the port; behind "
        f"{_SOCAT}, that the robot is on (press Clean: its light comes on) and that the "
        f"cable is a 5 V TTL serial adapter with TX and RX not swapped; {DOCK_WAKE}"
    ),
    garbled=(
        f"the robot may be there, but what {_PTY_END} sends arrives garbled: the "
        "simulator's fault options garble it on purpose (--corrupt-rate, --noise, "
        f"--bit-flip-rate), or it is not the simulator (give {_SIM_PTY}); behind {_SOCAT}, "
        "check the cable and the adapter and the bridge's serial settings (8N1, no flow "
        "control, the robot's rate; a robot set to a rate other than 115200 or 19200 by Baud "
        "(129) answers at neither: power it off and on)"
    ),
    echo=(
        f"this is not a robot's port: {_PTY_END} gives back what it is sent, not the "
        f"simulator (give {_SIM_PTY}), or a cable or adapter behind {_SOCAT} has its "
        "transmit and receive lines joined"
    ),
    recheck=f"check {_PTY_END} (the simulator's fault options, or {_SOCAT} and its cable)",
    drops=f"the simulator's --drop-rate or a busy computer, a cable behind {_SOCAT}",
    delays=f"the simulator's --latency or a busy computer, {_SOCAT} and its cable",
    garbles=f"the simulator's --corrupt-rate or --bit-flip-rate, a cable behind {_SOCAT}",
)


def _network_fixes(bridge: str) -> LinkFixes:
    """The fixes on a network port (``bridge``: "the bridge at HOST:PORT"). The network
    itself delivers bytes whole (TCP): what garbles them is the bridge's serial side, its
    wiring and its rate, which over socket:// doctor's rates do not reach (pyserial sets no
    rate there: the bridge keeps the one it was set to)."""
    serial_side = (
        f"the serial side of {bridge}: wired to the robot's port (TX and RX not swapped; a "
        "3.3 V bridge wants a level shifter on the robot's 5 V line), at 8N1 with no flow "
        "control and the robot's rate (over socket:// the bridge keeps the rate it was set "
        "to: the rates doctor tries do not reach it)"
    )
    return LinkFixes(
        wake=(
            f"{ASLEEP}. To wake it from here, BRC must cross {bridge}: rfc2217:// to a "
            "bridge that wires BRC to RTS or DTR (esp-link can; roomba-bt sim --rfc2217 serves "
            f"one). If the robot is awake and still silent, check {serial_side}"
        ),
        silent=(
            "check that the robot is on (press Clean: its light comes on) and that "
            f"{bridge} wires BRC to the robot (not every bridge does); check {serial_side}; "
            f"{DOCK_WAKE}"
        ),
        garbled=(
            "the robot may be there, but what it sends arrives garbled (the network "
            f"delivers bytes whole): check {serial_side}; a robot set to a rate other than "
            "115200 or 19200 by Baud (129) answers at neither: power it off and on"
        ),
        echo=(
            f"this is not a robot's port: {bridge} gives back what it is sent (an echo "
            "service, or its serial side's transmit and receive lines joined), or it is the "
            "wrong address; give the address of the robot's bridge"
        ),
        recheck=f"check {bridge} (its power, its Wi-Fi signal)",
        drops=f"a weak Wi-Fi signal, {bridge} losing bytes on its serial side",
        delays=f"a slow or busy Wi-Fi network, {bridge}",
        garbles=f"the serial side of {bridge}: its wiring to the robot, a wrong baud rate",
    )


def _garbled(probes: Any) -> str:
    """The rates at which bytes came that were no answer ("115200: 3 bytes"), or ""."""
    seen: dict[int, int] = {}
    for probe in probes:
        count = len(probe.reply) + probe.noise
        if count and not probe.answered and not probe.echoed:
            seen[probe.baud] = seen.get(probe.baud, 0) + count
    return ", ".join(f"{baud}: {count} bytes" for baud, count in seen.items())


class _DoctorExit(IntEnum):
    """0.1.0's ``DoctorExit``, doctor's exit codes by their names there: the codes are
    :class:`ExitCode`'s now, one table for every command."""

    FOUND = ExitCode.OK
    INVALID = ExitCode.INVALID
    PORT = ExitCode.CONNECTION
    SILENT = ExitCode.NO_ANSWER
    UNHEALTHY = ExitCode.UNHEALTHY
    INTERRUPTED = ExitCode.INTERRUPTED


def _old_name(name: str) -> Any:
    """``DoctorExit``, kept for old imports until 0.3.0 with a DeprecationWarning at the
    importer's line: its codes are the same numbers, :class:`ExitCode`'s."""
    if name != "DoctorExit":
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    instead = (
        "use ExitCode from roomba_bt.runtime.summary instead (FOUND is OK, PORT is "
        "CONNECTION, SILENT is NO_ANSWER)"
    )
    warnings.warn(
        moved_warning(f"{__name__}.DoctorExit", instead), DeprecationWarning, stacklevel=2
    )
    return _DoctorExit


if not TYPE_CHECKING:  # to a type checker the old name is gone, and a typo no Any (PEP 562)
    __getattr__ = _old_name


def register(sub: Any) -> None:
    parser = add_command(
        sub,
        "doctor",
        doctor_command,
        f"""find the robot on a port and say what it is, step by step

        Find the robot on --port: the port, the baud rate (115200, then 19200), a BRC wake pulse if
        it is silent, Start, its profile, battery, charging, OI mode, a stream round-trip, whether
        the shipped missions' streams fit the rate, and (with --allow-reset) its firmware. Exit
        codes: 0 found, 2 usage, 3 the port could not be opened, 5 nothing answered, 6 it answered
        but a later step failed, {INTERNAL_ERROR_SAID}, 130 interrupted.
        """,
    )
    parser.add_argument(
        "--port", required=True, type=port_name,
        help="serial device or URL (/dev/ttyUSB0, rfc2217://, socket://)",
    )  # fmt: skip
    parser.add_argument(
        "--baud", type=baud_or_auto, default=None,
        help="a rate to try first (default auto: 115200, then 19200)",
    )  # fmt: skip
    parser.add_argument(
        "--listen", type=duration, default=None, metavar="DURATION",
        help="how long the stream step listens (default 0.5 s; 10s or more to judge an "
        "intermittent line, a cable or a network bridge's Wi-Fi: a line losing 5 %% of the "
        "frames or more is warned about, as run calls it poor)",
    )  # fmt: skip
    parser.add_argument(
        "--allow-reset", action="store_true",
        help="send Reset (7) to read the firmware version from its banner (restarts the OI of "
        "a 600 or a Create 2; the Roomba 500 has no Reset 7: its spec says nothing of what a "
        "500 does with the byte)",
    )  # fmt: skip


@dataclass
class Report:
    """The steps as they happen: ``[ok]``, ``[--]`` (skipped or not needed), ``[warn]``,
    ``[FAIL]``; a failure's fix on the next line."""

    out: TextIO
    #: the port's link, whose words every fix takes (a device path's unless told)
    link: LinkWords = field(default_factory=lambda: _words_of(""))
    failed: bool = False
    facts: dict[str, str] = field(default_factory=dict)
    #: the models the profile step found fitting (several when it could not tell which)
    models: tuple[Any, ...] = ()

    @property
    def fixes(self) -> LinkFixes:
        """The fixes worded for this port's link: a network bridge's, a pty's (a program at
        its other end), or a cable's."""
        from roomba_bt.transport.link_kind import LinkKind

        if self.link.kind is LinkKind.NETWORK:
            return _network_fixes(self.link.between)
        if self.link.kind is LinkKind.PTY:
            return PTY_FIXES
        return CABLE_FIXES

    def line(self, mark: str, step: str, text: str, fix: str = "", label: str = "fix") -> None:
        print(f"[{mark}]".ljust(7) + f"{step:<10}{text}", file=self.out, flush=True)
        if fix:
            print(" " * 17 + f"{label}: {fix}", file=self.out, flush=True)

    def ok(self, step: str, text: str, note: str = "") -> None:
        self.line("ok", step, text, note, label="note")

    def skip(self, step: str, text: str) -> None:
        self.line("--", step, text)

    def warn(self, step: str, text: str, fix: str = "") -> None:
        self.line("warn", step, text, fix)

    def fail(self, step: str, text: str, fix: str) -> None:
        self.failed = True
        self.line("FAIL", step, text, fix)


def _words_of(port: str) -> LinkWords:
    """The port's link words, imported when doctor runs: the transport package stays out of
    every other command's start (tests/cli/test_imports.py)."""
    from roomba_bt.transport.link_kind import link_of

    return link_of(port)


class _Failed(Exception):
    """A step failed (already reported); the exit code to end with."""

    def __init__(self, code: ExitCode) -> None:
        super().__init__(code.name)
        self.code = code


def doctor_command(args: argparse.Namespace) -> int:
    from roomba_bt.transport import SerialTransport, TransportError

    url = args.port
    report = Report(sys.stdout, _words_of(url))
    print(f"roomba-bt doctor: {url}", flush=True)
    from roomba_bt.robot.discovery import rates_to_try

    rates = rates_to_try(args.baud)
    try:
        transport = SerialTransport.open(url, rates[0], brc_high=True)
    except TransportError as exc:
        report.fail(
            "port",
            f"could not open {url}: {exc.cause}",
            ""  # a cause its error number told says what to do (transport/open_failure.py)
            if isinstance(exc.cause, str)
            else report.link.open_fix,
        )
        return ExitCode.CONNECTION
    report.ok("port", f"opened {url} (8N1, no flow control; RTS and DTR released: BRC high)")
    try:
        return _examine(transport, rates, args.allow_reset, report, args.listen)
    except _Failed as failed:
        return failed.code
    except KeyboardInterrupt:
        print("roomba-bt doctor: interrupted", file=sys.stderr)
        return ExitCode.INTERRUPTED
    except OSError as exc:
        report.fail("link", f"the port failed: {exc}", _link_fix(exc, report.fixes))
        return ExitCode.UNHEALTHY
    finally:
        _leave_passive(transport)
        transport.close()


def _link_fix(exc: OSError, fixes: LinkFixes) -> str:
    """What to do about a port that failed while doctor used it: a bridge or simulator that
    turned doctor away (another client holds it) is not a cable to check."""
    from roomba_bt.transport.open_failure import closed_at_once

    if closed_at_once(exc):
        return (
            "end the other client (a run, sensors or doctor on this robot) or wait for it to "
            "end, then run doctor again"
        )
    return f"{fixes.recheck} and the robot's power, then run doctor again"


def _leave_passive(transport: Any) -> None:
    """Pause any stream and Start: the robot is left in Passive (errors: nothing to save)."""
    from roomba_bt.oi import commands as oi

    with contextlib.suppress(OSError):
        transport.write(oi.pause_stream().data + oi.start().data)


def _search(transport: Any, rates: tuple[int, ...], report: Report, when: str) -> Search:
    """Each rate tried, a line each (``when``: after what); the probes made."""
    from roomba_bt.robot.discovery import search

    result = search(transport, rates)
    for probe in result.probes:
        mark = "ok" if probe.answered else "--"
        report.line(mark, "baud", f"{probe.baud}{when}: {probe.seen}")
    return result


def _after_pulse(transport: Any, rates: tuple[int, ...], before: Search, report: Report) -> Any:
    """Every rate again after the BRC pulse: the probe that answered, or the verdict (silent,
    or a line that garbles: bytes came, none an answer) and the doctor ends."""
    again = _search(transport, rates, report, " after the pulse")
    if again.found is not None:
        return again.found
    garbled = _garbled(before.probes + again.probes)
    if garbled:  # bytes came, none an answer: not a silent robot
        report.fail(
            "baud",
            f"bytes came but none was an answer at any OI rate, even after a BRC pulse "
            f"({garbled}): the line garbles them",
            report.fixes.garbled,
        )
    else:
        report.fail("baud", "silent at every OI rate, even after a BRC pulse", report.fixes.silent)
    raise _Failed(ExitCode.NO_ANSWER)


def _examine(
    transport: Any,
    rates: tuple[int, ...],
    allow_reset: bool,
    report: Report,
    listen: float | None = None,
) -> int:
    from roomba_bt.robot.discovery import overheard, wake_pulse

    left = overheard(transport)  # before Start: what a run that could not stop it left
    searched = _search(transport, rates, report, "")
    found = searched.found
    if found is None and all(probe.echoed for probe in searched.probes):
        report.fail("port", "it gives back every byte written to it: a loopback, no robot",
                    report.fixes.echo)  # fmt: skip
        raise _Failed(ExitCode.NO_ANSWER)
    if found is None:
        pulse = wake_pulse(transport)
        if pulse.problem is not None:
            report.fail(
                "wake",
                f"silent at {' and '.join(str(r) for r in rates)}, and this port cannot pulse "
                f"BRC: {pulse.problem}",
                report.fixes.wake,
            )
            raise _Failed(ExitCode.NO_ANSWER)
        report.ok("wake", f"silent at every rate: {pulse.how}")
        found = _after_pulse(transport, rates, searched, report)
        report.ok(
            "wake", "it answered after the pulse: the robot was asleep (or powered down by Power)"
        )
    else:
        report.skip("wake", "not needed: the robot answered")
    baud = found.baud
    report.facts["baud"] = str(baud)
    report.ok("baud", f"the robot talks at {baud} baud")
    mode_raw = found.reply[0]
    plus_one = mode_raw == 2
    report.ok(
        "start",
        f"Start (128): Passive; packet 35 reads {mode_raw}"
        + (" (this firmware reports the OI mode + 1)" if plus_one else ""),
    )
    if left is not None:
        _left_running(left, plus_one, report)
    banner, reset_tried = _reset(transport, baud, allow_reset, report)
    header_in_checksum, readings = _stream(transport, baud, report, listen)
    profile = _profile(plus_one, header_in_checksum, banner, reset_tried, readings, report)
    _setting(report)
    _status(transport, profile, plus_one, report)
    _missions(profile, baud, report)
    _firmware(banner, reset_tried, report)
    facts = report.facts
    print(
        f"found: {facts.get('model', profile.title)} on {transport.name} at {baud} baud, "
        f"{facts.get('mode', '?')}, battery {facts.get('battery', '?')}, "
        f"{facts.get('charging', '?')}",
        flush=True,
    )
    return ExitCode.UNHEALTHY if report.failed else ExitCode.OK


def _left_running(left: Any, plus_one: bool, report: Report) -> None:
    """A stream ran before doctor wrote a byte (``discovery.overheard``): a run whose stop
    did not get through (its bridge reset, its cable pulled) left the robot so. Said, with
    the mode it streamed in and whether its wheels turned: doctor's Start has stopped a robot
    left driving, and its user learns it was left driving."""
    from roomba_bt.oi.modes import DRIVING_MODES, mode_from_packet

    mode = None if left.mode_raw is None else mode_from_packet(left.mode_raw, plus_one)
    turned = left.wheels_turned
    wheels = {True: ", its wheels turning", False: ", its wheels still"}.get(turned, "")
    seen = f" in {mode.label}{wheels}" if mode is not None else wheels
    text = f"a stream was running when doctor came{seen}"
    if mode in DRIVING_MODES or turned:
        report.warn(
            "left", f"{text}: a run's stop did not reach the robot, which drove on; doctor's "
            "Start (128) has stopped it (Passive: wheels and motors off)",
            "see where it went and what it hit",
        )  # fmt: skip
    else:
        report.ok("left", f"{text}: a program left it running; nothing drives in Passive")


def _reset(transport: Any, baud: int, allow_reset: bool, report: Report) -> tuple[Any, bool]:
    """Reset (7) and read its banner (``--allow-reset``); then Start again."""
    from roomba_bt.oi import commands as oi
    from roomba_bt.oi.identify import parse_banner
    from roomba_bt.robot.discovery import search

    if not allow_reset:
        report.skip(
            "reset",
            "not asked: --allow-reset sends Reset (7) and reads the firmware from its banner",
        )
        return None, False
    transport.write(oi.reset().data)
    clock = transport.now
    started = quiet_since = clock()
    data = b""
    while clock() - quiet_since < BANNER_QUIET_S and clock() - started < BANNER_LIMIT_S:
        chunk = transport.read(0.05)
        if chunk:
            data += chunk
            quiet_since = clock()
    banner = parse_banner(data)
    if banner is None:
        report.ok(
            "reset",
            f"no banner after Reset (7) ({len(data)} bytes): the Roomba 500 has no Reset",
        )
    else:
        lines = [ln.strip() for ln in banner.text.splitlines() if ln.strip()]
        report.ok("reset", f"banner of {len(lines)} lines; last: {lines[-1]!r}")
    # Reset leaves the OI Off (and may restore the default rate): find it again, Start.
    again = search(transport, (baud, *(r for r in (115200, 19200) if r != baud)))
    if again.found is None:
        report.fail(
            "reset",
            "the robot did not answer after Reset (7)",
            "wait a few seconds (it reboots) and run doctor again without --allow-reset",
        )
        raise _Failed(ExitCode.UNHEALTHY)
    if again.found.baud != baud:
        report.warn("reset", f"after Reset the robot talks at {again.found.baud} baud")
    return banner, True


#: Frames a sample may fall short by at its window's edges (the first cut by the request's
#: way, the last by the window's end) before they count as lost.
EDGE_FRAMES = 1
#: A sample this long judges an intermittent cable; a shorter one's warning suggests it.
LONG_LISTEN_S = 10.0


def _stream(
    transport: Any, baud: int, report: Report, listen: float | None = None
) -> tuple[bool | None, dict[int, int]]:
    """A stream of ``listen`` s (:func:`~roomba_bt.robot.discovery.sample_stream`, as
    ``--profile auto`` reads one; its 0.5 s unless told): which checksum convention the
    frames follow, the widest reading of each packet seen (for the profile's ranges), and
    whether the line loses frames, judged by ``run``'s own bar (:data:`~roomba_bt.runtime.
    summary.POOR_LINK`): doctor said ``[ok]`` to a line losing 35 % of them (it warned below
    half only) while ``run`` called 5 % poor and sent its user here."""
    from roomba_bt.robot.discovery import SAMPLE_PACKETS, SAMPLE_S, sample_stream

    seconds = SAMPLE_S if listen is None else listen
    sample = sample_stream(transport, seconds=seconds)
    if sample.latency is not None:  # the line's delay, a slot at most more
        report.facts["latency"] = f"{sample.latency:.3f}"
    delay = _latency(report)  # the frames of the window's last `delay` s are still on the way
    expected = round(max(0.0, seconds - delay) / SLOT_SECONDS)
    frames, skipped = sample.frames, sample.skipped
    lost = max(0, expected - frames - EDGE_FRAMES)
    text = (
        f"Stream (148) of {list(SAMPLE_PACKETS)}: {frames} frames of {sample.frame_size} bytes "
        f"in {seconds:g} s (one per 15 ms: {expected}"
        + (f", the first {delay * 1000:.0f} ms after the request" if delay >= 0.05 else "")
        + f"), {skipped} bytes skipped"
    )
    if frames == 0:
        report.fail(
            "stream",
            text + f"; {sample.received} bytes came, no whole frame",
            "the robot answers queries but does not stream: another program may be talking "
            f"to it, or the line drops bytes ({report.fixes.drops})",
        )
        raise _Failed(ExitCode.UNHEALTHY)
    if expected and lost >= POOR_LINK * expected:
        report.warn(
            "stream",
            f"{text}; {100 * lost / expected:.0f} % of the frames lost",
            f"the line loses frames (run calls {100 * POOR_LINK:g} % or more a poor link): "
            + report.link.check
            + ("; --listen 10s samples longer" if seconds < LONG_LISTEN_S else ""),
        )
    elif skipped:
        fix = f"frames are lost or damaged on this line: {report.fixes.recheck}"
        report.warn("stream", text, fix)
    else:
        report.ok("stream", text)
    _timing(sample.arrivals, seconds, report)
    return sample.header_in_checksum, dict(sample.readings)


#: Frames a sample needs for its intervals' spread to say something
TIMING_FRAMES = 20
#: ``--watchdog`` and ``--grace`` suggested for a link with jitter and gaps are this many
#: times its 99th percentile interval and its longest gap: an ordinary burst must not trip
#: the watchdog (the robot stutters: drive 0, then the drive again), nor a stall outlast
#: the grace (the run ends)
TIMING_MARGIN = 2.0


def _timing(arrivals: tuple[float, ...], seconds: float, report: Report) -> None:
    """When the sample's frames were read: the median and 99th percentile interval and the
    longest gap, warned when ``run``'s defaults would not ride them, with the values that
    would. A WiFi bridge's 5-80 ms of jitter and its power-save bursts tripped the default
    0.1 s watchdog 5 times in 20 s, and a 3 s stall outlasted the default 2 s grace, while
    doctor said the stream was ``[ok]``: the reason a WiFi user runs it."""
    if len(arrivals) < TIMING_FRAMES:
        return
    # between the reads that brought frames: a bunch read at once (a late chunk and those it
    # held back, a stall's backlog) is one arrival, its wait one interval
    reads = sorted(set(arrivals))
    intervals = sorted(b - a for a, b in itertools.pairwise(reads)) or [0.0]
    longest = intervals[-1]
    rest = intervals[:-1] or intervals  # the longest gap said apart (a stall, maybe)
    median, p99 = rest[len(rest) // 2], rest[int(0.99 * (len(rest) - 1))]
    text = (
        f"frames came every {median * 1000:.0f} ms (the median), {p99 * 1000:.0f} ms at the "
        f"99th percentile, the longest gap aside: {longest * 1000:.0f} ms"
    )
    # the watchdog rides the ordinary jitter; a longer gap is a stall, ridden through within
    # the grace (the watchdog's drive 0 stops the wheels meanwhile: it is not widened for it)
    watchdog = max(DEFAULT_WATCHDOG, _rounded_up(TIMING_MARGIN * p99, 0.05))
    grace = max(DEFAULT_GRACE, _rounded_up(TIMING_MARGIN * longest, 1.0))
    options = []
    if watchdog > DEFAULT_WATCHDOG:
        options.append(
            f"--watchdog {watchdog:g} (the default {DEFAULT_WATCHDOG:g} s sends drive 0 at "
            "every gap longer, and the robot stutters)"
        )
    if grace > DEFAULT_GRACE:
        options.append(
            f"--grace {grace:g} (a stall longer than the default {DEFAULT_GRACE:g} s ends the run)"
        )
    if not options:
        report.ok("timing", text)
        return
    report.warn(
        "timing",
        text,
        "a link with jitter or stalls (a network bridge: WiFi, Bluetooth): run with "
        + " and ".join(options)
        + ("; --listen 10s samples longer" if seconds < LONG_LISTEN_S else ""),
    )


def _rounded_up(value: float, step: float) -> float:
    """``value`` up to the next multiple of ``step`` (a suggestion a person types)."""
    return round(-(-value // step) * step, 3)


def _profile(
    plus_one: bool,
    header: bool | None,
    banner: Any,
    reset_tried: bool,
    readings: dict[int, int],
    report: Report,
) -> Any:
    from roomba_bt.oi.identify import identify
    from roomba_bt.oi.profiles import DEFAULT_PROFILE

    found = identify(
        mode_plus_one=plus_one,
        header_in_checksum=header,
        banner=banner,
        reset_tried=reset_tried,
        readings={pid: readings[pid] for pid in MODEL_RANGE_PACKETS if pid in readings},
    )
    why = "; ".join(found.evidence)
    best = found.cautious
    report.models = found.candidates
    if best is None:
        report.warn(
            "profile",
            f"no profile fits: {why}; using {DEFAULT_PROFILE.title}",
            "report this robot's model and this output with an issue"
            + ("" if reset_tried else " (its banner too: doctor --allow-reset)"),
        )
        return DEFAULT_PROFILE
    if found.decided:
        report.ok("profile", f"{best.title} (--profile {best.name}): {why}")
    else:
        _undecided(found, why, reset_tried, report)
    return found.assumed


def _undecided(found: Any, why: str, reset_tried: bool, report: Report) -> None:
    """Several models fit: each named, and what would tell them apart. Where the default
    profile (the Create 2) is one of them, it is [ok] and the default's, the others named
    for an owner whose label says so: the evidence cannot tell a Create 2 from a Roomba 600
    without the mode + 1 bug or a Roomba 500 whose checksum covers the header, and a [warn]
    advising --profile roomba500 met every Create 2 owner (the most of them) for a doubt
    their label settles. Otherwise a [warn], and the one that sends nothing another lacks,
    to use until it is known (the profile the caller goes on with:
    ``Identification.assumed``)."""
    from roomba_bt.oi.identify import telling_apart
    from roomba_bt.oi.profiles import DEFAULT_PROFILE

    best = found.cautious
    candidates = found.candidates
    names = " or ".join(f"{p.title} (--profile {p.name})" for p in candidates)
    ways = ["the model on its label", *telling_apart(candidates)]
    if not reset_tried and len({p.has_command("reset") for p in candidates}) > 1:
        ways.append(
            "the banner a 600 or a Create 2 prints after Reset (7): doctor --allow-reset "
            "(Reset is not in the Roomba 500 spec: what a 500 does with it is written nowhere)"
        )
    if DEFAULT_PROFILE in candidates:
        others = " or ".join(
            f"a {p.title} (--profile {p.name})" for p in candidates if p is not DEFAULT_PROFILE
        )
        report.ok(
            "profile",
            f"{DEFAULT_PROFILE.title} (--profile {DEFAULT_PROFILE.name}, the default), or "
            f"{others} if its label says so: {why}",
            "tell them apart by " + "; or by ".join(ways),
        )
        titles = " or ".join(p.title for p in candidates if p is not DEFAULT_PROFILE)
        report.facts["model"] = f"{DEFAULT_PROFILE.title} (or a {titles}, by its label)"
        return
    report.warn(
        "profile",
        f"{names}: not told apart: {why}; until it is known, --profile {best.name} sends "
        "no command the others lack",
        "tell them apart by " + "; or by ".join(ways),
    )
    report.facts["model"] = " or ".join(p.title for p in found.candidates)


def _setting(report: Report) -> None:
    """The profile named once for every command (``ROOMBA_BT_PROFILE``, else the project
    file above the current directory: :mod:`roomba_bt.cli.profile_choice`) against the
    models the profile step found: a setting that names another model is a [warn], since
    every ``run`` would speak to this robot as that one."""
    from roomba_bt.cli.profile_choice import (
        AUTO_PROFILE,
        DOCUMENTED_AT,
        PROFILE_VARIABLE,
        BadSetting,
        choose_profile,
        profile_said,
    )

    choice = choose_profile(None)
    if isinstance(choice, BadSetting):
        report.warn("setting", str(choice), "set it to a profile's name or auto, or remove it")
        return
    if not choice.named:
        report.skip(
            "setting",
            f"no model named once: {PROFILE_VARIABLE} or profile under [tool.roomba-bt] "
            f"would spare each command its --profile ({DOCUMENTED_AT})",
        )
        return
    said = profile_said(choice)
    if choice.name == AUTO_PROFILE:
        report.ok("setting", f"{said}: run and sensors identify the robot as above, no Reset")
    elif any(p.name == choice.name for p in report.models):
        report.ok("setting", f"{said}: fits this robot")
    else:
        fits = " or ".join(p.name for p in report.models) or "auto"
        report.warn(
            "setting",
            f"{said}: this robot is no {choice.name}, and every command without --profile "
            "would speak to it as one",
            f"set it to {fits}, or to auto; or give --profile on the command line",
        )


#: The status packets that stay the same between two replies a moment apart.
STEADY_STATUS_PACKETS = packet_ids(
    "battery_charge", "battery_capacity", "charging_state", "charging_sources", "oi_mode"
)
#: Query Lists asked for the status before its replies must have agreed twice in a row.
STATUS_QUERIES = 4
#: How far two readings of the battery's voltage a moment apart may differ (mV): the
#: charger and the wheels move it, a garbled byte moves it by 256 mV or more.
VOLTAGE_AGREES_MV = 150


def _agree(first: SensorFrame, second: SensorFrame) -> bool:
    """Two status replies a moment apart tell the same: the charge, capacity, charging state,
    sources and mode equal, the voltage close (the current may change)."""
    return all(first[pid] == second[pid] for pid in STEADY_STATUS_PACKETS) and (
        abs(first.voltage_mv - second.voltage_mv) <= VOLTAGE_AGREES_MV
    )


def _latency(report: Report) -> float:
    """The line's delay the stream check measured (its first frame's), 0 if none came."""
    return float(report.facts.get("latency", "0"))


def _drain_quiet(transport: Any, latency: float) -> None:
    """Read and drop until the line is quiet for longer than its delay: a paused stream's
    frames still on their way come ``latency`` s after the pause (at 0.2 s, the 30 ms of
    discovery.drain ended before them, and a stale frame was read as the status reply)."""
    from roomba_bt.robot.discovery import QUIET_S, drain

    if latency <= QUIET_S / 2:
        drain(transport)
        return
    quiet = 1.5 * latency + QUIET_S
    drain(transport, quiet=quiet, limit=4 * quiet + 1.0)


def _implausible(frame: SensorFrame, plus_one: bool) -> str:
    """What in a status reply cannot be the robot's ("" if nothing): a reading out of its
    packet's range, a charge above the capacity, a mode other than Passive (Start came just
    before). A reply has no checksum: stale stream bytes read as one give such values."""
    from roomba_bt.oi.modes import OIMode, mode_from_packet
    from roomba_bt.oi.packets import PACKETS

    wrong = [
        f"{PACKETS[pid].name} {frame[pid]} (allowed {PACKETS[pid].minimum}..{PACKETS[pid].maximum})"
        for pid in STATUS_PACKETS
        if pid != OI_MODE_PACKET and not PACKETS[pid].minimum <= frame[pid] <= PACKETS[pid].maximum
    ]
    if frame.battery_charge_mah > frame.battery_capacity_mah:
        wrong.append(
            f"a charge of {frame.battery_charge_mah} mAh above the capacity, "
            f"{frame.battery_capacity_mah} mAh"
        )
    if mode_from_packet(frame.oi_mode_raw, plus_one) is not OIMode.PASSIVE:
        wrong.append(f"oi_mode {frame.oi_mode_raw} (Passive right after Start)")
    return "; ".join(wrong)


def _ask_status(transport: Any, profile: Any, latency: float) -> SensorFrame | None:
    """One status Query List and its reply, or None if none came in 0.5 s past the delay."""
    from roomba_bt.oi import commands as oi
    from roomba_bt.oi.stream import ReplyParser

    clock = transport.now
    parser = ReplyParser(STATUS_PACKETS, profile)
    transport.write(oi.query_list(STATUS_PACKETS).data)
    deadline = clock() + 0.5 + 2 * latency
    frame = None
    while frame is None and (remaining := deadline - clock()) > 0:
        frame = parser.feed(transport.read(remaining))
    return frame


def _agreed_status(transport: Any, profile: Any, plus_one: bool, report: Report) -> SensorFrame:
    """The status Query List's reply, asked until two in a row agree (:func:`_agree`) and
    are plausible (:func:`_implausible`); a failure (no answer, replies that never agree,
    implausible ones) is reported and ends the doctor."""
    ids = STATUS_PACKETS
    latency = _latency(report)
    # A reply has no checksum: one garbled byte read "65105 of 2696 mAh (2415 %)" as [ok],
    # a stale stream frame "277 of 27 mAh (1026 %)". Two replies in a row that agree on what
    # changes slowly, with plausible values, are the robot's.
    replies: list[SensorFrame] = []
    wrong = ""
    agreed = False  # two in a row agreed, and were implausible all the same
    for _ in range(STATUS_QUERIES):
        _drain_quiet(transport, latency)  # the paused stream's last frames, a stale reply
        frame = _ask_status(transport, profile, latency)
        if frame is None:
            report.fail(
                "battery",
                f"no answer to Query List {list(ids)} within {0.5 + 2 * latency:.2g} s",
                "the line drops bytes or another program talks to the robot: run doctor again",
            )
            raise _Failed(ExitCode.UNHEALTHY)
        wrong = _implausible(frame, plus_one)
        replies.append(frame)
        if len(replies) >= 2 and _agree(replies[-2], frame):
            if not wrong:
                return frame
            agreed = True
    _status_failed(report, replies, wrong if agreed else "", latency)
    raise _Failed(ExitCode.UNHEALTHY)


def _status_failed(report: Report, replies: list[SensorFrame], wrong: str, latency: float) -> None:
    ids = list(STATUS_PACKETS)
    fixes = report.fixes
    if wrong:
        report.fail(
            "battery",
            f"the reply to Query List {ids} cannot be the robot's: {wrong} (stale stream "
            f"bytes or a garbled line; the line's delay: {latency * 1000:.0f} ms)",
            f"the line garbles or delays bytes ({fixes.delays}), or another program talks to "
            f"the robot: {fixes.recheck} and run doctor again",
        )
        return
    shown = "; ".join(
        f"{r.battery_charge_mah} of {r.battery_capacity_mah} mAh, {r.voltage_mv} mV"
        for r in replies
    )
    report.fail(
        "battery",
        f"{STATUS_QUERIES} replies to Query List {ids} never agreed twice in a row ({shown})",
        f"the line garbles bytes ({fixes.garbles}): {fixes.recheck} and run doctor again",
    )


def _status(transport: Any, profile: Any, plus_one: bool, report: Report) -> None:
    from roomba_bt.oi.bits import ChargingState
    from roomba_bt.oi.modes import mode_from_packet

    frame = _agreed_status(transport, profile, plus_one, report)
    charge, capacity = frame.battery_charge_mah, frame.battery_capacity_mah
    percent = f"{100 * charge / capacity:.0f} %" if capacity else "capacity 0 (no battery?)"
    report.facts["battery"] = percent
    report.ok(
        "battery",
        f"{charge} of {capacity} mAh ({percent}), {frame.voltage_mv / 1000:.2f} V, "
        f"{frame.current_ma} mA",
    )
    charging = frame[CHARGING_STATE_PACKET]
    try:
        state = ChargingState(charging).name.lower().replace("_", " ")
    except ValueError:
        state = f"unknown state {charging}"
    sources = frame.charging_sources
    powered = [
        name
        for name, on in (("home base", sources.home_base), ("internal", sources.internal_charger))
        if on
    ]
    report.facts["charging"] = state
    report.ok(
        "charging",
        f"{state} ({CHARGING_STATE_PACKET} = {charging}); sources: {', '.join(powered) or 'none'}",
    )
    mode = mode_from_packet(frame.oi_mode_raw, plus_one)
    if mode is None:
        report.fail(
            "mode",
            f"packet {OI_MODE_PACKET} reads {frame.oi_mode_raw}, which is no OI mode",
            "another program may be talking to the robot; run doctor again",
        )
        raise _Failed(ExitCode.UNHEALTHY)
    report.facts["mode"] = mode.label
    quirk = "mode + 1 firmware: the runtime subtracts 1" if plus_one else "as is"
    report.ok("mode", f"{mode.label} ({OI_MODE_PACKET} = {frame.oi_mode_raw}, {quirk})")


def _missions(profile: Any, baud: int, report: Report) -> None:
    """Each shipped mission's stream (its packets and the runtime's) against the budget."""
    from roomba_bt.mission import RUNTIME_PACKETS, MissionError, load_mission
    from roomba_bt.mission.shipped import shipped_missions
    from roomba_bt.oi.frames import stream_frame_size
    from roomba_bt.oi.stream import stream_budget

    budget = stream_budget(baud)
    fits: list[str] = []
    too_big: list[str] = []
    for name, path in shipped_missions().items():
        try:
            mission = load_mission(path, profile=profile)
        except MissionError as exc:
            too_big.append(f"{name} (does not load: {exc.diagnostics[0]})")
            continue
        size = stream_frame_size(sorted(set(mission.packets) | set(RUNTIME_PACKETS)))
        (fits if size <= budget else too_big).append(f"{name} {size}")
    text = f"a 15 ms slot carries {budget} bytes at {baud} baud; frames: " + ", ".join(fits)
    if too_big:
        from roomba_bt.oi.profiles import SEND_BAUD, at_19200_of

        report.warn(
            "missions",
            text + "; too big: " + ", ".join(too_big),
            "switch the robot to 115200 to run those: "
            + at_19200_of(report.models or (profile,))
            + f" ({SEND_BAUD})",
        )
    else:
        report.ok("missions", text + ": all fit")


def _firmware(banner: Any, reset_tried: bool, report: Report) -> None:
    if banner is None or banner.firmware is None:
        why = (
            "the banner names no release"
            if reset_tried and banner is not None
            else "not read (--allow-reset: the reset banner names it)"
            if not reset_tried
            else "no banner (a Roomba 500)"
        )
        report.skip("firmware", why)
        return
    firmware = banner.firmware
    if firmware.wakes_by_brc_on_dock:
        report.ok("firmware", f"{firmware.text}: wakes by a BRC pulse on the dock too")
    else:
        report.warn(
            "firmware",
            f"{firmware.text}: older than release-3.8.2 / release-stm32-3.7.7, it does not "
            "wake by a BRC pulse on the dock",
            "on the dock keep it awake (keep-awake is on by default) or wake it with Clean",
        )
