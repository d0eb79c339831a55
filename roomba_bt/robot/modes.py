"""The OI mode model: a ``transitions`` state machine built from the opcode table.

States are the four OI modes. Each mode-changing command of the profile (``CommandSpec``
with ``leads_to``) is a trigger whose sources are the command's ``modes`` and whose
destination is its ``leads_to``; nothing is typed out again here, and ``auto_transitions`` is
off, so the model cannot jump where the robot cannot. Two kinds of internal trigger follow
what the robot does by itself, seen in packet 35:

* ``fall_back`` (Safe/Full -> Passive): a cliff while driving forward, a wheel drop or a
  powered charger; the cause is inferred from the same frame (packet 7 wheel-drop bits,
  packets 9-12 cliffs, packet 34 charging sources, else the frame before, else "unknown");
* ``resync_<mode>``: the robot reports a mode no rule leads to (another client on the port, a
  command the robot did not take); the model follows the robot and logs a warning.

The guard, :meth:`ModeModel.check`, refuses (before any byte is built) a command the current
mode does not accept, or one the profile does not have.

Packet 35 and the "mode + 1" bug
--------------------------------
Some 600-series firmware reports OI mode + 1 (Passive reads 2, Safe 3, Full 4). The offset
(0 or 1) is learned once, at start-up, by :meth:`ModeModel.calibrate`: right after Start the
robot is in Passive, so a reply of 1 means offset 0 and a reply of 2 offset 1; the
:class:`~roomba_bt.robot.connection.Connection` asks twice (a reply has no checksum) and
calibrates only when both replies agree. A stream frame never teaches the offset: one
corrupted frame with packet 35 = 4 made an earlier model take every later Safe for Passive,
which disarmed the safe stop. Until the offset is known, packet 35 is ignored.

With the offset known, the modes the robot may be in are the model's mode, the mode a command
just sent leads to (for ``settle`` seconds after it was sent, counted while frames flow: a gap
of :data:`HELD_GAP` or more since the frame before moves it on by the gap, as the link held the
command too), and Passive if either is Safe or
Full (a robot changes mode by itself only by falling back to Passive). A reading
``raw - offset`` that is one of those is followed; one that is another mode is a resync; one
that is no mode is ignored and counted in :attr:`ModeModel.invalid_readings`; never an
exception. A change the robot made by itself is followed only when two consecutive frames
report it (:attr:`ModeModel.confirm`), or when the frame that reports a fall to Passive also
shows its cause (a cliff, a wheel drop, the charger: the robot's reaction agrees with its
sensors, and the tree must not drive on for a frame): a single corrupted packet 35 that passed
the checksum and the range checks changes nothing. The profile's ``reports_mode_plus_one``
only decides whether finding the bug is expected (info) or a surprise (warning).
"""

from __future__ import annotations

import functools
import logging
import time
from collections.abc import Callable
from typing import Any

from transitions import Machine

from roomba_bt.oi.encode import Command
from roomba_bt.oi.frames import (
    BUMPS_PACKETS,
    CHARGING_SOURCES_PACKETS,
    CLIFF_PACKETS,
    SLOT_SECONDS,
    FrameLayout,
    SensorFrame,
)
from roomba_bt.oi.modes import DRIVING_MODES, OI_MODE_PACKET, OIMode
from roomba_bt.oi.opcodes import MODE_COMMANDS, CommandSpec
from roomba_bt.oi.profiles import DEFAULT_PROFILE, PROFILES, RobotProfile
from roomba_bt.robot.errors import ModeError, profile_fix
from roomba_bt.robot.interface import UNKNOWN_CAUSE, ModeChange

log = logging.getLogger(__name__)

#: Packet 34's bit of the home base (the dock's contacts); bit 0 is the internal charger.
HOME_BASE_BIT = 0b10

#: The mode machine's name: ``transitions`` puts ``"<name>: "`` first in each of its log
#: records, which is how :data:`QUIET_MACHINE` knows this library's records from others'.
MACHINE_NAME = "roomba-bt OI modes"


class _QuietMachine(logging.Filter):
    """Drops the INFO and DEBUG records ``transitions`` logs for this library's mode machine
    ("Finished processing state Safe enter callbacks", four a start-up): a program that calls
    ``logging.basicConfig(level=logging.INFO)`` saw them as if they were its own. A filter on
    ``transitions.core`` (the logger it logs to; it has no per-machine logger), not a level:
    a program's own machines log as ``transitions`` documents, the root logger and the
    levels are left as the program set them, and a WARNING or an error still shows. A
    program that sets a level on ``transitions`` itself (its README's way to see them, and
    ``roomba-bt -vv``'s) asked for them: it gets this machine's too. The mode changes that
    matter are this library's own records (``roomba_bt.robot``)."""

    def filter(self, record: logging.LogRecord) -> bool:
        args = record.args
        ours = isinstance(args, tuple) and bool(args) and args[0] == f"{MACHINE_NAME}: "
        return record.levelno >= logging.WARNING or not ours or _asked_for_by_name()


def _asked_for_by_name() -> bool:
    """A level set on ``transitions`` or ``transitions.core``: the program wants their
    records (the root logger's level alone says nothing of them)."""
    return any(
        logging.getLogger(name).level != logging.NOTSET
        for name in ("transitions", "transitions.core")
    )


#: On ``transitions.core`` from this module's import (``docs/robot.md``, Logging).
QUIET_MACHINE = _QuietMachine()
logging.getLogger("transitions.core").addFilter(QUIET_MACHINE)

FALL_BACK = "fall_back"
RESYNC_PREFIX = "resync_"
#: Seconds after a mode command during which packet 35 may still show the old mode.
DEFAULT_SETTLE = 0.1
#: While a mode command waits to show, no frame for this long (two slots) is the link holding
#: the frames back (a WiFi bridge's hiccup, a stall ridden through), and likely the command
#: with them: the settle is moved on by the hold, less the slot a frame takes. A 250 ms
#: hiccup as a mission sent ``mode: passive`` read the backlog's Safe as a resync and the
#: late Start's Passive as a fall by itself (unknown): ``--strict`` failed a correct run.
HELD_GAP = 2 * SLOT_SECONDS
#: Modes the robot can fall into by itself from each mode (Full never falls in the spec, but a
#: robot that reports it is followed rather than argued with).
FALLS: dict[OIMode, frozenset[OIMode]] = {
    OIMode.OFF: frozenset(),
    OIMode.PASSIVE: frozenset(),
    OIMode.SAFE: frozenset({OIMode.PASSIVE}),
    OIMode.FULL: frozenset({OIMode.PASSIVE}),
}
STATE_NAMES = tuple(m.label for m in OIMode)


def _label(mode: OIMode) -> str:
    return mode.label


def mode_transitions(profile: RobotProfile = DEFAULT_PROFILE) -> list[dict[str, Any]]:
    """The machine's transitions for ``profile``, read from the opcode table.

    One entry per mode-changing command the profile has (trigger = command name), then the
    internal ``fall_back`` and ``resync_<mode>`` triggers.
    """
    table: list[dict[str, Any]] = []
    for spec in MODE_COMMANDS:
        if profile.name not in spec.profiles or spec.leads_to is None:
            continue
        table.append(
            {
                "trigger": spec.name,
                "source": [_label(m) for m in sorted(spec.modes)],
                "dest": _label(spec.leads_to),
            }
        )
    fall_sources = [_label(m) for m in sorted(FALLS) if OIMode.PASSIVE in FALLS[m]]
    table.append({"trigger": FALL_BACK, "source": fall_sources, "dest": "Passive"})
    for mode in (OIMode.PASSIVE, OIMode.SAFE, OIMode.FULL):
        table.append(
            {"trigger": RESYNC_PREFIX + mode.name.lower(), "source": "*", "dest": _label(mode)}
        )
    return table


class _MachineModel:
    """The object ``transitions`` drives; its ``state`` is the mode label."""

    state: str


def _machine(profile: RobotProfile, model: _MachineModel | None, initial: OIMode) -> Machine:
    return Machine(
        model=model,
        states=list(STATE_NAMES),
        transitions=mode_transitions(profile),
        initial=_label(initial),
        auto_transitions=False,
        ignore_invalid_triggers=False,
        name=MACHINE_NAME,
    )


def build_machine(
    profile: RobotProfile = DEFAULT_PROFILE, initial: OIMode = OIMode.OFF
) -> tuple[Machine, _MachineModel]:
    """A machine of its own for ``profile`` and the model it drives (``docs/modes.md``)."""
    model = _MachineModel()
    return _machine(profile, model, initial), model


@functools.cache
def _rules(profile: RobotProfile) -> tuple[Machine, dict[OIMode, frozenset[int]]]:
    """The mode machine of ``profile`` with no model of its own, and the guard's table (the
    opcodes each mode accepts: mode commands from the machine, others from the opcode table),
    built once a process and shared by every :class:`ModeModel` of that profile.

    Neither changes once built: a model's state is an attribute of the model, which the
    machine's events read and set (``Event.trigger(model)``); no callback is ever added. A
    Machine built per connection was about 1.7 M instructions, a sixth of an evaluation
    episode's set-up."""
    machine = _machine(profile, None, OIMode.OFF)
    table: dict[OIMode, frozenset[int]] = {}
    for mode in OIMode:
        triggers = set(machine.get_triggers(_label(mode)))
        table[mode] = frozenset(
            spec.opcode
            for spec in profile.commands
            if (spec.name in triggers if spec.changes_mode else mode in spec.modes)
        )
    return machine, table


#: what packet 35 reads right after Start: Passive, or Passive + 1 on a robot with the
#: 600-series mode + 1 bug (oi/modes.py)
_PASSIVE_READINGS = (OIMode.PASSIVE, OIMode.PASSIVE + 1)


class OffsetDetector:
    """Learns whether packet 35 reads mode + 1 (see the module docstring for the rule)."""

    __slots__ = ("expected_plus_one", "offset", "profile", "setting")

    def __init__(self, profile: RobotProfile = DEFAULT_PROFILE) -> None:
        self.offset: int | None = None
        self.profile = profile
        #: where the profile was set, for the fix (``Connection.profile_setting``)
        self.setting: str | None = None
        self.expected_plus_one = profile.reports_mode_plus_one

    def interpret(self, raw: int) -> OIMode | None:
        """The mode ``raw`` means with the offset learned at start-up, or None (ignore: no
        offset yet, or no mode an open robot can report)."""
        offset = self.offset
        if offset is None or not 1 <= raw - offset <= 3:
            return None
        return OIMode(raw - offset)

    def calibrate(self, raw: int, port: str = "") -> bool:
        """Learn the offset from a reply read right after Start (Passive: 1, or 2 with the
        bug); False if ``raw`` is neither. ``port``: the robot's, named in what is said."""
        if raw not in _PASSIVE_READINGS:
            return False
        if self.offset != raw - 1:
            self._learn(raw - 1, raw, port)
        return True

    def _learn(self, offset: int, raw: int, port: str) -> None:
        """The offset learned, said when it is 1. A profile that does not expect it (the
        default create2 on a Roomba 600) is most likely the wrong one: the warning names the
        port and the fix, as the 500's checksum does
        (:func:`~roomba_bt.robot.errors.wrong_profile`). It said only "packet 35 reports the
        OI mode + 1 (read 2)", which with several robots named neither which one nor what
        to do."""
        previous, self.offset = self.offset, offset
        if offset != 1:
            return
        where = f"{port}: " if port else ""
        likely = [p for p in PROFILES.values() if p.reports_mode_plus_one]
        if self.expected_plus_one or not likely:
            level = logging.INFO if self.expected_plus_one and previous is None else logging.WARNING
            log.log(
                level,
                "%spacket 35 reports the OI mode + 1 (read %d); correcting every reading by -1",
                where, raw,
            )  # fmt: skip
            return
        log.warning(
            "%spacket 35 reports the OI mode + 1 (read %d), which the %s profile does not "
            "expect: the robot is most likely a %s: %s (correcting every reading by -1 "
            "meanwhile)", where, raw, self.profile.name, likely[0].title,
            profile_fix(likely[0].name, self.setting),
        )  # fmt: skip


def infer_cause(frame: SensorFrame, *earlier: SensorFrame | None) -> str:
    """Why the robot left Safe by itself, from the packets the frame carries, else from the
    frames before it (newest first)."""
    for candidate in (frame, *earlier):
        if candidate is None:
            continue
        causes: list[str] = []
        # A frame carries the packets its stream asked for: read only those it has.
        if all(pid in candidate for pid in BUMPS_PACKETS) and candidate.any_wheel_drop:
            causes.append("wheel drop")
        if any(candidate.get(pid) for pid in CLIFF_PACKETS):
            causes.append("cliff")
        sources = 0
        for pid in CHARGING_SOURCES_PACKETS:
            sources |= candidate.get(pid) or 0
        if sources:
            # packet 34: bit 1 the home base (a dock run's end), bit 0 alone the wall
            # charger's plug in the robot's socket, which the spec names the internal charger
            causes.append("charger" if sources & HOME_BASE_BIT else "internal charger")
        if causes:
            return " and ".join(causes)
    return UNKNOWN_CAUSE


class ModeModel:
    """What OI mode the robot is in, why, and since when; the guard of every command.

    ``time`` arguments are the link's clock (``Transport.now()``); ``wall_clock`` (default
    :func:`time.time`) only stamps messages such as "since 12:01:03.120".
    """

    def __init__(
        self,
        profile: RobotProfile = DEFAULT_PROFILE,
        *,
        initial: OIMode = OIMode.OFF,
        settle: float = DEFAULT_SETTLE,
        wall_clock: Callable[[], float] = time.time,
    ) -> None:
        self.profile = profile
        self.settle = settle
        self._wall_clock = wall_clock
        #: the profile's machine (shared: :func:`_rules`) and the state it moves, this model's
        self.machine, self._allowed = _rules(profile)
        self._model = _MachineModel()
        self.machine.set_state(_label(initial), model=self._model)
        #: the mode the robot is in, as the model has it: read-only outside the model (its
        #: commands and packet 35 set it); an attribute, not a property, as the runtime
        #: reads it once a tick
        self.mode = initial
        self.since: float = 0.0
        self.since_wall: float = wall_clock()
        self.cause: str | None = None  # set while the current mode is a fall-back's
        self.last_fallback: ModeChange | None = None
        self.detector = OffsetDetector(profile)
        self.invalid_readings = 0
        #: consecutive frames that must report a change the robot made by itself
        self.confirm = 2
        # (reported mode, frames so far, the first such frame, the frame before it)
        self._unconfirmed: tuple[OIMode, int, SensorFrame, SensorFrame | None] | None = None
        #: (from, to, when its allowance began: the write, moved on by every stall of the
        #: link since; the last frame's time since it): a mode command not yet seen taken
        self._pending: tuple[OIMode, OIMode, float, float] | None = None
        self._previous_frame: SensorFrame | None = None
        #: the layout of the frames reconciled last and packet 35's slot in it (None: not
        #: carried), found once per layout instead of by a lookup every frame
        self._mode_layout: FrameLayout | None = None
        self._mode_slot: int | None = None
        #: the packet 35 reading that changes nothing (:meth:`_track`)
        self._steady: int | None = None

    # ------------------------------------------------------------------ state
    def _track(self) -> None:
        """After every change of the mode, the command pending or the offset: the raw
        packet 35 reading that says the robot is where the model thinks with no command
        pending (the model's mode + the offset), or None when no reading can say that. What
        :meth:`reconcile` compares each frame with, in one test instead of three."""
        offset = self.detector.offset
        self._steady = None if self._pending is not None or offset is None else self.mode + offset

    @property
    def state(self) -> str:
        """The machine's state name (``"Passive"``...)."""
        return self._model.state

    @property
    def plus_one(self) -> bool | None:
        """True once the "mode + 1" bug is detected, False once ruled out, None unknown."""
        return None if self.detector.offset is None else self.detector.offset == 1

    def allows(self, command: Command | CommandSpec, mode: OIMode | None = None) -> bool:
        spec = command.spec if isinstance(command, Command) else command
        return spec.opcode in self._allowed[self.mode if mode is None else mode]

    # ------------------------------------------------------------------ guard
    def check(self, command: Command | CommandSpec) -> None:
        """Raise if ``command`` may not be sent now; return None if it may.

        :class:`~roomba_bt.oi.errors.UnsupportedCommandError` for a command the profile does
        not have, :class:`~roomba_bt.robot.errors.ModeError` for one the mode refuses.
        """
        spec = command.spec if isinstance(command, Command) else command
        if spec.opcode in self._allowed[self.mode]:
            return
        self.profile.check_supported(spec)
        raise self.refusal(spec)

    def refusal(self, spec: CommandSpec) -> ModeError:
        needs = frozenset(m for m in OIMode if spec.opcode in self._allowed[m])
        hint = ""
        if self.mode is OIMode.OFF:
            hint = "send start first"
        elif self.cause is None and needs <= DRIVING_MODES:
            hint = "send safe or full first"
        return ModeError(
            spec.name, needs, self.mode, self.since_wall, self.cause, hint, since=self.since
        )

    # ------------------------------------------------------------------ commands
    def calibrate(self, raw: int, time: float, port: str = "") -> bool:
        """The robot answered ``raw`` for packet 35 right after Start (twice, agreeing): learn
        the "mode + 1" offset and take the robot as in Passive. False if ``raw`` is no
        Passive reading (nothing changes). ``port``: the robot's, named in what is said."""
        if not self.detector.calibrate(raw, port):
            return False
        if self.mode is not OIMode.PASSIVE:
            self.force(OIMode.PASSIVE, time)
        self._pending = None
        self._track()
        return True

    def snapshot(self) -> tuple[Any, ...]:
        """What :meth:`restore` puts back: the model before commands that were not written."""
        return (self.mode, self._model.state, self.since, self.since_wall, self.cause,
                self._pending)  # fmt: skip

    def restore(self, saved: tuple[Any, ...]) -> None:
        """Undo :meth:`apply` for commands that never reached the wire (the write failed)."""
        mode, state, self.since, self.since_wall, self.cause, self._pending = saved
        self.machine.set_state(state, model=self._model)
        self.mode = mode
        self._track()

    def apply(self, command: Command | CommandSpec, time: float) -> None:
        """Record that ``command`` was written at link time ``time``: fire its trigger."""
        spec = command.spec if isinstance(command, Command) else command
        if spec.leads_to is None:
            return
        previous = self.mode
        self._fire(spec.name, spec.leads_to, time, cause=None)
        self._pending = (previous, spec.leads_to, time, time)
        self._track()

    def _fire(self, trigger: str, dest: OIMode, time: float, cause: str | None) -> float:
        """Move the machine and the model to ``dest``; returns when the mode it left began
        (a fall's :attr:`~roomba_bt.robot.interface.ModeChange.entered`)."""
        left_since = self.since
        event = self.machine.events.get(trigger)
        if event is None:  # what the model's own ``trigger`` raises (Machine._get_trigger)
            raise AttributeError(f"Do not know event named '{trigger}'.")
        event.trigger(self._model)
        if self.mode is not dest or cause is not None:
            self.since = time
            self.since_wall = self._wall_clock()
        self.mode = dest
        self.cause = cause
        self._track()
        return left_since

    def force(self, mode: OIMode, time: float = 0.0) -> None:
        """Set the mode without a command (a robot known to be in ``mode``: tests, replays)."""
        if mode is OIMode.OFF:
            self._reset_off(time)
        else:
            self._fire(RESYNC_PREFIX + mode.name.lower(), mode, time, None)
        self._pending = None
        self._track()

    def _reset_off(self, time: float) -> None:
        self.machine.set_state("Off", model=self._model)
        self.mode = OIMode.OFF
        self.since, self.since_wall, self.cause = time, self._wall_clock(), None
        self._track()

    # ------------------------------------------------------------------ packet 35
    def _settling(self, reported: OIMode, time: float) -> bool:
        """A mode command waits to show: True while ``reported`` changes nothing (the
        command's mode, seen: it is done; the old mode within the settle, counted while
        frames flow: a hold of the link of :data:`HELD_GAP` or more moves it on); False
        once the settle is over (the command no longer pending: the reading is judged as
        any other)."""
        pending = self._pending
        assert pending is not None
        if reported is pending[1]:
            self._pending = None
            self._unconfirmed = None
            self._track()
            return True
        began = pending[2]
        if time - pending[3] > HELD_GAP:  # the link held the frames (and, as likely, the
            began += time - pending[3] - SLOT_SECONDS  # command): that long more
        if time - began < self.settle:
            self._pending = (pending[0], pending[1], began, time)
            return True
        self._pending = None
        self._track()
        return False

    def reconcile(self, frame: SensorFrame, tick: int, time: float) -> ModeChange | None:
        """Follow packet 35 of ``frame``; return the change the robot made by itself, if any."""
        previous_frame, self._previous_frame = self._previous_frame, frame
        layout = frame.layout
        if layout is self._mode_layout:
            slot = self._mode_slot
        else:
            slot = self._mode_slot = layout.index.get(OI_MODE_PACKET)
            self._mode_layout = layout
        if slot is None:
            return None
        raw = frame.values[slot]
        if raw == self._steady:  # the common case, once per frame: the robot is where we
            self._unconfirmed = None  # think, no command pending
            return None
        reported = self.detector.interpret(raw)
        if reported is None:
            self.invalid_readings += 1
            return None
        if self._pending is not None and self._settling(reported, time):
            return None
        if reported is self.mode:
            self._unconfirmed = None
            return None
        before = self.mode
        falls = reported is OIMode.PASSIVE and before in DRIVING_MODES
        seen = self._unconfirmed
        if seen is None or seen[0] is not reported:
            seen = (reported, 0, frame, previous_frame)
        count = seen[1] + 1
        # A fall the same frame explains (a cliff, a wheel drop, the charger: the robot's own
        # reaction agrees with its sensors) is followed at once; anything else needs
        # ``confirm`` consecutive frames.
        if count < self.confirm and not (falls and infer_cause(frame) != UNKNOWN_CAUSE):
            self._unconfirmed = (reported, count, seen[2], seen[3])
            return None
        self._unconfirmed = None
        if falls:
            cause = infer_cause(frame, seen[2], seen[3])
            trigger = FALL_BACK
        else:
            cause = "unexpected report"
            trigger = RESYNC_PREFIX + reported.name.lower()
            log.warning(
                "packet 35 reports %s while the model expected %s; following the robot",
                reported.label,
                before.label,
            )
        entered = self._fire(trigger, reported, time, cause)  # when the mode it left began
        change = ModeChange(before, reported, tick, time, cause, self.since_wall, entered)
        self.last_fallback = change
        return change
