"""The robot layer's errors: one type per thing a caller handles differently.

* :class:`ModeError`: a command the robot's current OI mode would not accept; nothing was sent.
* :class:`ConnectionFailed`: the robot could not be reached at start-up (:class:`NoAnswer`:
  it answered nothing at the run's rate).
* :class:`LinkDown` and its kinds, each a cause named: :class:`PortLost` (the port raised:
  the port is gone), :class:`StreamStalled` (no valid frame within the watchdog: the run
  rides through it for a grace), :class:`StreamLost` (still none after the grace: the stream
  stopped, or the line is garbled), :class:`RobotReset` (the start-up banner came instead),
  :class:`RobotAsleep` (Passive past the sleep time, or silent until a BRC pulse),
  :class:`BaudChanged` (garbage, and frames at another rate).

The link errors subclass :class:`ConnectionError`, like
:class:`~roomba_bt.transport.TransportError`, so "the robot is unreachable" is one ``except``.
"""

from __future__ import annotations

import time

from roomba_bt.errors import RoombaBtError
from roomba_bt.oi.errors import OIError
from roomba_bt.oi.identify import ProfileMismatch
from roomba_bt.oi.modes import OIMode
from roomba_bt.oi.profiles import DEFAULT_PROFILE, RobotProfile
from roomba_bt.robot import wording


class RobotError(RoombaBtError):
    """Base of every error raised by :mod:`roomba_bt.robot`."""


class ConnectionClosed(RobotError, RuntimeError):
    """The connection was used after :meth:`~roomba_bt.robot.connection.Connection.close`
    (it read as a port gone: an unplugged cable)."""

    def __init__(self, port: str, given_to: str = "") -> None:
        """``given_to``: what it was handed to, said first (``RunStack(mission,
        connection)``, which refuses it when made, before the run blamed a cable)."""
        was = f"{given_to}: " if given_to else ""
        super().__init__(
            f"{port}: {was}the connection is closed (close() was called): open a new one"
        )


def format_wall_time(wall_time: float) -> str:
    """``12:01:03.120``: local time of day with milliseconds, for messages."""
    seconds = int(wall_time)
    millis = round((wall_time - seconds) * 1000)
    if millis == 1000:
        seconds, millis = seconds + 1, 0
    return time.strftime("%H:%M:%S", time.localtime(seconds)) + f".{millis:03d}"


#: How a fall-back cause reads after "after ...".
CAUSE_PHRASES = {
    "wheel drop": "a wheel drop",
    "cliff": "a cliff",
    "charger": "a powered charger",
    "internal charger": "the wall charger plugged in (the internal charger)",
    "unknown": "an unknown cause",
}


def describe_cause(cause: str) -> str:
    parts = [CAUSE_PHRASES.get(p, p) for p in cause.split(" and ")]
    return " and ".join(parts)


def _mode_list(modes: frozenset[OIMode]) -> str:
    labels = [m.label for m in sorted(modes)]
    if len(labels) <= 1:
        return "".join(labels) or "no mode"
    return ", ".join(labels[:-1]) + " or " + labels[-1]


class ModeError(RobotError, OIError, ValueError):
    """A command the current OI mode does not accept; it never reached the wire.

    ``str(error)`` reads like ``drive needs Safe or Full; the robot is in Passive since
    12:01:03.120, after a wheel drop``: the time of day, for a program using the connection;
    a run, whose log counts mission time, words it with its own clock (:meth:`worded`).
    """

    def __init__(
        self,
        command: str,
        needs: frozenset[OIMode],
        mode: OIMode,
        since_wall: float,
        cause: str | None = None,
        hint: str = "",
        since: float | None = None,
    ) -> None:
        self.command = command
        self.needs = needs
        self.mode = mode
        self.since_wall = since_wall
        #: when the mode began on the link's clock (None: not known)
        self.since = since
        self.cause = cause
        self.hint = hint
        super().__init__(self.worded(format_wall_time(since_wall)))

    def worded(self, since: str) -> str:
        """The message with ``since`` as the time the mode began (``t=12.300``)."""
        message = (
            f"{self.command} needs {_mode_list(self.needs)}; the robot is in {self.mode.label} "
            f"since {since}"
        )
        if self.cause is not None:
            message += f", after {describe_cause(self.cause)}"
        if self.hint:
            message += f" ({self.hint})"
        return message


class ConnectionFailed(RobotError, ConnectionError):
    """The robot did not answer, or the port could not be used; names the port and why."""

    def __init__(self, port: str, reason: str, likely_causes: tuple[str, ...] = ()) -> None:
        self.port = port
        self.reason = reason
        self.likely_causes = likely_causes
        message = f"{port}: {reason}"
        if likely_causes:
            message += "; likely causes: " + ", ".join(likely_causes)
        super().__init__(message)


class NoAnswer(ConnectionFailed):
    """The robot answered no Query List at start-up, at the run's rate (the connection then
    asks at the other OI rates: :func:`~roomba_bt.robot.silence.answers_elsewhere`)."""


class LinkDown(RobotError, ConnectionError):
    """The link failed while running: the port is gone or the stream stopped."""

    #: the frames that came show a robot of another model than the profile's (a
    #: :class:`StreamStalled`'s or a :class:`StreamLost`'s; None for every other failure):
    #: a setting, which fails the same way again, not a line that failed
    mismatch: ProfileMismatch | None = None

    def __init__(self, port: str, message: str, headline: str = "") -> None:
        self.port = port
        #: the message's short first line, for where it is repeated (a run's stderr line,
        #: the summary saying it whole); "" when the message is short enough to repeat
        self.headline = headline
        super().__init__(f"{port}: {message}")

    def also(self, said: str) -> None:
        """``said`` added at the message's end: what the session knows beside the cause (a
        stream that never came though it was asked for again)."""
        self.args = (f"{self.args[0]}; {said}",)


class PortLost(LinkDown):
    """Reading or writing the port raised (cable unplugged, bridge closed, robot reset)."""


class TurnedAway(PortLost):
    """The far end of a network link (``socket://``, ``rfc2217://``) closed the connection
    before it sent a byte: another client holds the bridge, and nothing of this run reached
    a robot. A run it ends before any robot answered was never started (exit 3, safe to
    retry: ``runtime/loop.ended_by``), not a link lost under a moving robot (exit 8)."""


class ConnectionSilent(PortLost):
    """A network link (``socket://``, ``rfc2217://``) that carried not a byte for the grace
    while a stream ran, and did not close: taken for dead (the safe stop closes it and tries
    a new connection, as after a reset: ``ending.PortReturn``). An ESP8266 bridge that
    rebooted or left Wi-Fi range leaves such a half-open connection: no reset reaches this
    computer, writes go on filling its buffer, and TCP gives up on them only after minutes;
    the watchdog's drive 0 and the stop went into it, and the robot drove on."""

    def __init__(
        self, port: str, silent_for: float, grace: float, *, watchdog: float, halted: bool
    ) -> None:
        # imported here: validate loads this module, and the transport package pyserial
        from roomba_bt.transport.link_kind import link_of

        self.silent_for = silent_for
        action = (
            f"the watchdog's drive 0 after {watchdog * 1000:.0f} ms went into it"
            if halted
            else "the robot was not driving"
        )
        super().__init__(
            port,
            f"the connection went silent: not a byte came through it for {silent_for:.1f} s, "
            f"and it did not close ({link_of(port).went_silent}); {action}; past the "
            f"{grace:g} s grace it is taken for dead: closed, and a new connection tried for "
            "the stop",
        )


class WaitCutShort(RobotError):
    """A read inside a wait bounded in wall time (the safe stop's,
    :meth:`~roomba_bt.robot.link.StreamLink.bounded`) came after the bound: the wait would
    otherwise have gone on, its end measured on a link clock that does not move as it reads
    (a transport of one's own, a virtual clock at its float's last bit). Not a port lost:
    the port may be fine, only the wait is given up."""


def wrong_profile(mismatch: ProfileMismatch, setting: str | None = None) -> str:
    """The frames pass another model's checksum, or only its range holds their values: what
    was seen and the fix, worded for where the profile was set (``setting``,
    :func:`profile_fix`)."""
    return f"{mismatch.explained}: {profile_fix(mismatch.likely[0].name, setting)}"


def wrong_profile_headline(port: str, mismatch: ProfileMismatch, setting: str | None) -> str:
    """The short first line of a wrong profile's ending, for where the full message
    (:func:`wrong_profile`) is repeated: the model, the profile it was read with, the fix. A
    run printed the same ~450 characters three times; a 40-column window wants the fix
    first."""
    return (
        f"{port}: the robot is most likely {mismatch.most_likely}, which the "
        f"{mismatch.profile.name} profile cannot read: "
        f"{profile_fix(mismatch.likely[0].name, setting)}"
    )


#: How every wrong-profile fix ends: the command that tells the model.
_DOCTOR = "or roomba-bt doctor to tell the model"


def profile_fix(name: str, setting: str | None = None) -> str:
    """The fix for a robot read with another model's profile, as every such message says
    it (a 500's checksum, a 600's mode + 1), worded for where the profile was set: the
    fix is made there, or the setting keeps coming back (``ROOMBA_BT_PROFILE=create2``
    with "use --profile roomba500" fixed one command and not the next). ``setting`` is the
    command line's, handed down as data (this layer reads no command line): ``"--profile"``,
    an environment variable's name (``ROOMBA_BT_PROFILE``), a project file's ``path:line``;
    None when not known (the default, a Python program): the option and the Python
    argument both."""
    if setting is None:
        python = f"Connection.open(port, profile={name!r})"
        return f"use --profile {name} (in Python, {python}), {_DOCTOR}"
    if setting.startswith("-"):
        return f"use {setting} {name}, {_DOCTOR}"
    if setting.isidentifier():
        return f"set {setting}={name} (or auto), {_DOCTOR}"
    # the project file's key (roomba_bt.project.PROFILE_KEY: a module this layer does not
    # import, tests/transport/test_layers.py)
    return f'set profile = "{name}" at {setting} (or "auto"), {_DOCTOR}'


#: Seconds without a valid frame before the watchdog trips (drive 0, :class:`StreamStalled`)
#: unless told (``run --watchdog``, ``Connection(watchdog=...)``). Here beside the trip, not in
#: :mod:`~roomba_bt.robot.link` where the watchdog runs: ``run --help`` says it, and every
#: command builds that parser, ``validate`` too, which must not load the link's pyserial
#: (``tests/cli/test_imports.py``); this module imports only the protocol's.
DEFAULT_WATCHDOG = 0.1


class StreamStalled(LinkDown):
    """No valid stream frame within the watchdog time; drive 0 was sent (if allowed).
    ``mismatch``: the frames that came pass another model's checksum, or only its range holds
    their values (the profile is wrong: certain at once, a run ends without riding it
    through); ``setting``: where the profile was set, for its fix (:func:`profile_fix`)."""

    def __init__(
        self, port: str, silent_for: float, watchdog: float, halted: bool,
        mismatch: ProfileMismatch | None = None, held: str | None = None,
        setting: str | None = None,
    ) -> None:  # fmt: skip
        self.silent_for = silent_for
        self.watchdog = watchdog
        self.halted = halted
        self.mismatch = mismatch
        self.setting = setting
        #: what held this process's reads meanwhile, if known (a keep-awake pulse's line
        #: change that took long): then the stall is ours, not the line's
        self.held = held
        action = "drive 0 sent" if halted else "the robot was not driving (drive 0 not needed)"
        why = f"; {wrong_profile(mismatch, setting)}" if mismatch is not None else ""
        why += f"; {held}" if held is not None else ""
        super().__init__(
            port,
            f"no valid sensor frame for {silent_for * 1000:.0f} ms (watchdog "
            f"{watchdog * 1000:.0f} ms){why}; {action}",
            wrong_profile_headline(port, mismatch, setting) if mismatch is not None else "",
        )


#: A stream that stopped for a reset within this many seconds of a command of ours may have
#: stopped at that command's doing: a robot resets on the byte it reads as Reset, and its
#: stream stops before its next frame (15 ms), a USB adapter's latency after that.
RESET_AFTER_WRITE_S = 0.1


class RobotReset(LinkDown):
    """The robot restarted while running: its start-up banner came down the line and the
    stream stopped (after a reset the OI is Off and streams nothing until Start).
    ``after_write``: seconds from our last command to the stall (None: not known). Within
    :data:`RESET_AFTER_WRITE_S` the cable is named too: a byte of that command lost on the
    line makes its next data byte an opcode, and a 7 (packet 7 in a stream request, a
    speed's low byte) is Reset (7): a battery or power dip is then the wrong thing to check
    alone."""

    def __init__(self, port: str, halted: bool, after_write: float | None = None) -> None:
        action = "drive 0 sent" if halted else "it was not driving"
        # imported here: validate loads this module, and the transport package pyserial
        from roomba_bt.transport.link_kind import link_of

        cable = (
            f", or a byte of our command {after_write:.2f} s before lost on the line "
            f"({link_of(port).bad_line}: a data byte 7 after it is read as Reset)"
            if after_write is not None and 0.0 <= after_write <= RESET_AFTER_WRITE_S
            else ""
        )
        super().__init__(
            port,
            "the robot reset: its start-up banner was on the line and the stream stopped (the "
            "OI is Off after a reset: a battery or power dip, a firmware fault, the power "
            f"button held{cable}); {action}",
        )


class StreamLost(LinkDown):
    """No valid frame came back within the grace after the watchdog tripped: the stream
    stopped (nothing arrived) or the line is garbled (bytes arrived, none made a frame).
    ``mismatch``: the garbled frames pass another model's checksum rule, or only its range
    holds their values (the profile is wrong: a Roomba 500 read as a Create 2, its wall
    signal over 1023); the message then names the model, the packet or the rule, and the fix,
    for where the profile was set (``setting``, :func:`profile_fix`), or else for the
    command line (``--profile``) and for Python (the ``profile`` argument). ``lost_before``:
    the bytes to the robot this run found lost, when it answers nothing after a silence
    (``silence.bytes_lost_said``): the silence is then said a Stop or Power made of lost
    bytes, not a bare "the sensor stream stopped" (seed 67 of the dock's 1 % sweep)."""

    def __init__(
        self,
        port: str,
        silent_for: float,
        grace: float,
        bytes_seen: int,
        *,
        watchdog: float,
        halted: bool,
        probed: str = "",
        mismatch: ProfileMismatch | None = None,
        came_back: float | None = None,
        setting: str | None = None,
        lost_before: str = "",
        waiter: str = "the run",
    ) -> None:
        self.silent_for = silent_for
        self.grace = grace
        self.bytes_seen = bytes_seen
        self.mismatch = mismatch
        #: seconds from the last frame until the robot answered again, when it did (asked
        #: after the grace): a line that froze and came back, not a robot that slept
        self.came_back = came_back
        # imported here: validate loads this module, and the transport package pyserial
        from roomba_bt.transport.link_kind import link_of

        headline = ""
        words = link_of(port)
        if came_back is not None:
            what = f"the stream stopped for {came_back:.1f} s and came back ({words.froze})"
        elif bytes_seen and mismatch is not None:
            what = (
                f"the line is garbled: no valid sensor frame for {silent_for:.1f} s while "
                f"{bytes_seen} bytes arrived; {wrong_profile(mismatch, setting)}"
            )
            headline = wrong_profile_headline(port, mismatch, setting)
        elif bytes_seen:
            what = (
                f"the line is garbled: no valid sensor frame for {silent_for:.1f} s while "
                f"{bytes_seen} bytes arrived (noise on the line, or a wrong baud rate)"
            )
        else:
            what = nothing_arrived(silent_for, lost_before, words.line)
        action = (
            f"the watchdog sent drive 0 after {watchdog * 1000:.0f} ms"
            if halted
            else "the robot was not driving"
        )
        #: what asking the robot afterwards showed (it still answers; nothing, even after a
        #: BRC pulse), or ""
        self.probed = probed
        tail = f"; {probed}" if probed else ""
        if came_back is not None and words.gap_fix:
            tail += f"; {words.gap_fix}"
        super().__init__(
            port,
            f"{what}; {action}, then {waiter} waited the {grace:g} s grace{tail}",
            headline,
        )


def nothing_arrived(silent_for: float, lost_before: str, line: str) -> str:
    """What :class:`StreamLost` says of a silence that not a byte broke: the OI gone Off by
    a lost byte where the run found bytes to the robot lost (``lost_before``), else the
    stream stopped, ``line`` (the link's words for its wire) among the causes."""
    if lost_before:
        return (
            "the robot's OI went Off mid-run: most likely a Stop (173) or Power (133) made of "
            f"lost bytes on this line: {lost_before}; nothing arrived for {silent_for:.1f} s"
        )
    return (
        f"the sensor stream stopped: nothing arrived for {silent_for:.1f} s (the robot "
        f"switched off or stopped streaming, or {line})"
    )


def idle_said(idle_s: float | None) -> str:
    """How long the robot had been without a command or a BRC pulse, as a message says it."""
    if idle_s is None:
        return "an unknown time"
    return f"{idle_s:.0f} s" if idle_s >= 0.5 else "less than a second"


class RobotAsleep(LinkDown):
    """The stream stopped because the robot slept: it sat in Passive five minutes with
    nothing from us (no command, no BRC pulse), or it answered nothing until a BRC pulse
    woke it (``woken_by``: how the pulse was given). Says how to keep it awake, and how the
    firmware that does not wake by BRC on the dock is found on ``profile``'s robot."""

    def __init__(
        self,
        port: str,
        idle_s: float | None,
        *,
        keep_awake: bool,
        pulses: bool,
        woken_by: str | None = None,
        profile: RobotProfile = DEFAULT_PROFILE,
        on_dock: bool = False,
    ) -> None:
        # imported here: validate loads this module, and the transport package pyserial
        from roomba_bt.transport.link_kind import link_of

        self.idle_s = idle_s
        self.woken_by = woken_by
        #: the last frame saw the dock's contacts (charging sources, 34): it slept charging
        self.on_dock = on_dock
        words = link_of(port)
        if not keep_awake:
            fix = (
                f"leave keep-awake on ({wording.current.keep_awake_on}): it pulses BRC once a "
                "minute"
            )
        elif not pulses:
            # woken by a hang-up, it was told this link cannot pulse BRC: keep-awake cannot
            hang_up = (
                "; the hang-up that woke it blanks the line for a second, too long to give "
                "once a minute" if woken_by is not None else ""
            )  # fmt: skip
            fix = (
                f"keep-awake cannot pulse BRC on this port (no modem lines{hang_up}): "
                f"{words.pulse_fix}"
            )
        else:
            fix = f"check that {words.between} wires BRC to RTS or DTR"
        idle = idle_said(idle_s)
        if woken_by is None:
            what = (
                f"the robot fell asleep: {idle} in Passive without a command or a BRC pulse "
                "(the OI sleeps after 5 minutes)"
            )
        else:
            what = (
                "the robot was asleep: its stream stopped and it answered nothing until a BRC "
                f"pulse woke it ({woken_by}); it had been {idle} without a command or a pulse "
                "from us when its stream stopped, and is awake now, in Passive"
            )
        if on_dock:  # a wait on the charger (patrol's charge_for) is not a robot in trouble
            what += (
                ", on its dock (charging: it sits there still); a wait in Passive longer than "
                "5 minutes cannot finish without keep-awake"
            )
        super().__init__(
            port,
            f"{what}; {fix}. Firmware older than "
            "release-3.8.2 / release-stm32-3.7.7 does not wake by BRC on the dock "
            f"({firmware_read(profile)})",
        )


def firmware_read(profile: RobotProfile) -> str:
    """How the firmware release of ``profile``'s robot is read: the banner Reset (7) prints
    (``doctor --allow-reset``), where the robot has Reset; the Roomba 500 has none, and its
    OI tells its release no other way (the advice named ``doctor --allow-reset`` to a 500
    owner, whose doctor then says "the Roomba 500 has no Reset")."""
    if profile.has_command("reset"):  # in the caller's words: a program has no doctor flags
        return wording.current.firmware_read
    return (
        f"the {profile.title} has no Reset (7), the one way its OI tells the version: a robot "
        "asleep on the dock that a BRC pulse does not wake has such firmware; take it off the "
        "dock to wake it"
    )


def rate_of(rate: int, user: str) -> str:
    """``the 115200 of the run``: the baud rate a connection was at, said for its ``user``
    (:attr:`~roomba_bt.robot.connection.Connection.waiter`, ``the run`` or the command that
    set its own name), where the robot is found talking at another: ``roomba-bt sensors``
    has no run, and said "not the 115200 of the run" (``the 115200 roomba-bt sensors
    opened it at``)."""
    return f"the {rate} of the run" if user == "the run" else f"the {rate} {user} opened it at"


class BaudChanged(LinkDown):
    """The robot's port changed its rate in the middle of the run (a battery swap or a reset
    brings a Create 2 back at its default rate): garbage on the line since the last valid
    frame, and frames again when the port listened at ``rate``. The port was left at that
    rate, so the stop reaches the robot. The garbage is said as a duration, like the other
    causes (the log line's ``t=`` stamp is the run's time), not a time of day."""

    def __init__(
        self, port: str, rate: int, was: int, garbage_s: float, garbage_bytes: int, *,
        halted: bool, user: str = "the run",
    ) -> None:  # fmt: skip
        self.rate = rate
        self.was = was
        self.garbage_s = garbage_s
        action = (
            f"drive 0 sent again at {rate} (the watchdog's at {was} could not be understood)"
            if halted
            else "it was not driving"
        )
        super().__init__(
            port,
            f"the robot now talks at another baud rate: {rate}, not {rate_of(was, user)}; "
            f"no valid sensor frame for {garbage_s * 1000:.0f} ms while {garbage_bytes} bytes "
            f"arrived, then valid frames at {rate}: the port followed it (a battery swap or a "
            f"reset brings the robot back at its default rate); {action}",
        )
