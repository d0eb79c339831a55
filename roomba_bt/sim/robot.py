"""The simulated robot: OI bytes in, OI bytes out, physics and sensors on 15 ms steps.

The simulator is a robot, not a mock of one: it parses the host's bytes with the same opcode
table the encoder uses (an incomplete command waits for its data bytes), applies the spec's
mode rules (``CommandSpec.modes`` / ``leads_to``), ignores actuator commands in Passive and Off
as the robot does (and counts them in :attr:`Simulator.violations`), and answers Sensors (142),
Query List (149) and Stream (148) with bytes laid out by the packet table::

    host -> robot   [128] [131] [148][2][7][35] [145][0][100][0][100] ...
    robot -> host   [19][4][7][b7][35][b35][chk]            every 15 ms while streaming
                    [b7][b35]                               reply to [149][2][7][35]

One :meth:`Simulator.step` is one 15 ms stream slot: timeline events, wheel motion (with
collisions), sensors from the world's geometry, Safe-mode safety, battery, the passive sleep
timer, then one stream frame. The hot path is written for speed (the simulator must run far
faster than real time): sensor values live in one flat list indexed by packet id, frames are
packed by a precompiled :class:`struct.Struct`, and geometry is only recomputed when the pose
or the world changes. ``tests/sim`` checks every frame against
:meth:`roomba_bt.oi.frames.FrameLayout.stream_frame`.

:class:`Simulator` is the facade over the layers of state.py (one module per seam: sensing,
motion, power, replies, protocol) and the components of cycles.py and timeline.py; this
module holds the constructor, the step and the timeline's effects.
"""

from __future__ import annotations

import math

from roomba_bt.oi.modes import OIMode
from roomba_bt.oi.odometry import WHEEL_SPEED_STEP_MM_S
from roomba_bt.oi.opcodes import COMMANDS, opcodes
from roomba_bt.oi.profiles import CREATE2, RobotProfile, profile_given
from roomba_bt.sim.coverage import ALL_BRUSHES, SweptArea
from roomba_bt.sim.cycles import BuiltinCycle
from roomba_bt.sim.faults import Faults
from roomba_bt.sim.motion import drive_wheel_speeds
from roomba_bt.sim.protocol import PASSIVE_SLEEP_SECONDS, OIProtocol
from roomba_bt.sim.sensing import FAR_ALL
from roomba_bt.sim.state import STEP_SECONDS, SimEvent, TracePoint, Violation
from roomba_bt.sim.timeline import Timeline
from roomba_bt.sim.world import Pose, World

__all__ = [
    "STEP_SECONDS",
    "WHEEL_SPEED_STEP_MM_S",
    "SimEvent",
    "Simulator",
    "TracePoint",
    "Violation",
    "drive_wheel_speeds",
]

#: a step in nanoseconds, a float: the clock (``_time_ns``) counts whole nanoseconds in a float,
#: exact up to 2**53 ns (104 days), and divided by 1e9 gives the same time as an int would
#: (an int is made a float first), without converting a big int to a float every step
_STEP_NS = float(round(STEP_SECONDS * 1e9))
_from_bytes = int.from_bytes
_PASSIVE, _SAFE, _FULL = OIMode.PASSIVE, OIMode.SAFE, OIMode.FULL
#: The kind of a ``sleep_at`` fault that came due in Safe or Full and waited for Passive.
SLEEP_IN_PASSIVE = "sleep, once in Passive (Safe and Full never sleep)"
#: How long such a sleep waits in Passive with no byte or BRC pulse from the host: the five
#: idle minutes of the OI's own sleep, shortened so a test sees it, long enough that the
#: run's stop into Passive is confirmed first.
QUIET_BEFORE_SLEEP_S = 1.0


class Simulator(OIProtocol):
    """A virtual Roomba / Create 2 in a :class:`~roomba_bt.sim.world.World`.

    ``receive(bytes)`` takes host bytes, ``step()`` advances 15 ms, ``read()`` drains what the
    robot sent. Same world, seed, faults and input bytes -> the same output bytes.
    """

    #: its own state's attributes (state.py: slots, not a dict, on the step's path)
    __slots__ = (
        "_disconnect_at", "_fault_at", "_fault_clock_waits", "_next_timed", "_timed_faults",
        "_timeline", "keeps_trace", "swept",
    )  # fmt: skip

    def __init__(
        self,
        world: World,
        profile: RobotProfile | str | None = CREATE2,
        seed: int = 0,
        faults: Faults | None = None,
        *,
        start: Pose | None = None,
        random_start: bool = False,
        old_firmware_angle: bool = False,
        mode: OIMode = OIMode.OFF,
        coverage: bool = False,
        trace: bool = True,
        cycle_commands_pause: bool = False,
    ) -> None:
        #: keep the trajectory (``trace``: a point every 4th step and at each mode change, for
        #: a plot or an evaluation's record); without it only the start is kept and memory
        #: stays flat however long the run (12.7 MB per robot-hour with it)
        self.keeps_trace = trace
        super().__init__(
            world, profile_given(profile, "Simulator"), seed, faults, start, random_start,
            old_firmware_angle, mode,
        )  # fmt: skip
        self._init_sensing()
        self._init_motion()
        self._init_power()
        self._init_output()
        self._init_protocol()
        self.cycle_commands_pause = cycle_commands_pause
        self._timeline = Timeline(world.events) if world.events else None
        self._disconnect_at = (
            math.inf if self.faults.disconnect_at is None else self.faults.disconnect_at
        )
        self._timed_faults = list(self.faults.timed)
        self._next_timed = self._timed_faults[0][0] if self._timed_faults else math.inf
        #: the first of the two: one comparison a step
        self._fault_at = min(self._disconnect_at, self._next_timed)
        #: ``Faults.from_stream``: the times above are offsets from a stream not started yet;
        #: until then every step looks for it (:meth:`_timed_fault`) and no link is cut
        self._fault_clock_waits = self.faults.from_stream and self._fault_at < math.inf
        if self._fault_clock_waits:
            self._disconnect_at, self._fault_at = math.inf, 0.0
        self._sense()
        self._battery(0.0)
        #: the floor cleaned so far (``coverage=True``; it reads the pose, never the bytes)
        self.swept: SweptArea | None = SweptArea(world, self.pose) if coverage else None

    # One function, the whole 15 ms (over 60 lines on purpose): it is the hot path, and each
    # call it made instead of running inline would cost a tenth of a microsecond, 3 % of it.
    def step(self, dt: float = STEP_SECONDS) -> None:
        """Advance one 15 ms slot and send one stream frame if a stream is on."""
        self.ticks += 1
        # Whole nanoseconds, no drift: 200 steps are exactly 3.0 s (round(t, 9) costs more
        # than a third of a microsecond, the integer sum a tenth of that).
        self._time_ns += _STEP_NS if dt == STEP_SECONDS else round(dt * 1e9)
        now = self.time = self._time_ns / 1e9
        if now >= self._fault_at:  # the link lost, or a timed fault due
            if now >= self._disconnect_at:
                self._cut_link()
                return  # this step is the link's; the robot goes on from the next
            self._timed_fault()
        timeline = self._timeline
        if timeline is not None:
            self._world_events(timeline)
        if self.asleep:
            if (self.docked and self.dock_powered) or self.plugged_in:
                self._battery(dt)  # asleep on a charger, the battery still charges
            return
        if now >= self._held_until:  # a song's end or the buttons' release (protocol.py)
            self._release_held(now)
        mode = self.mode
        cycle = self.builtin
        if cycle is not None and mode is _PASSIVE:
            left, right = cycle.wheels(self)
            if cycle.ended is not None:
                self._end_builtin(cycle)
        elif mode is _SAFE or mode is _FULL:
            left, right = self.requested_left, self.requested_right
        else:
            left = right = 0.0
        if left or right or self.left_speed or self.right_speed:
            self._move(left, right, dt)
        if self._geometry_dirty:
            # the far sensors measured now only if read every step (sensing.py)
            stream = self._stream
            far = 0 if stream is None else stream.far
            self._sense(FAR_ALL if self.builtin is not None else far)
            if self._drops:  # one test a moved step where no drop is (the usual world)
                self._fall_check()
        if mode is _SAFE and self._safety_due:
            self._safety()
        if self._power_due or self.ticks >= self._battery_at or dt != STEP_SECONDS:
            self._battery(dt)
            if self._charge <= 0.0 and self._current < 0.0:  # drained: it switches off
                self.fall_asleep("battery empty")
        else:
            self._charge_owed += 1  # the charge's step, taken later with the others (power.py)
        swept = self.swept
        if swept is not None:
            cycle = self.builtin
            if cycle is None or cycle.name == "seek_dock":
                motors = self.motor_bits
            else:  # the firmware's Clean, Spot and Max run every motor
                motors = ALL_BRUSHES
            if motors & ALL_BRUSHES or now >= swept.idle_until:
                swept.update(now, self.x, self.y, self.theta, motors)
            else:  # no brush: all an update would do (coverage.py)
                swept.last_time = now
        if (
            mode is _PASSIVE
            and now - self._last_activity >= PASSIVE_SLEEP_SECONDS
            and self.builtin is None
        ):
            self._fall_asleep("5 min idle", deaf=True)
            return
        stream = self._stream
        if stream is not None and not self._stream_paused:
            if now >= self._next_inject:
                faults = self.faults
                self._emit(faults.inject_text.encode("ascii"))
                self._next_inject += faults.inject_every
            values = self._snapshot_values(stream) if stream.snapshot else self.values
            # the values packed, the header, ids and checksum or-ed in (replies.py)
            pack, getter, byte_sum, framings, size = stream.frame_tools
            packed = pack(*getter(values))
            frame = (_from_bytes(packed) | framings[byte_sum(packed) & 0xFF]).to_bytes(size)
            if self._plain_output:  # no fault on the way out: straight into the output
                self.frames_sent += 1
                self.bytes_sent += size
                unread = self._frame  # a step's frame not read yet (replies.py)
                if unread is not None:
                    self._out.append(unread)
                self._frame = frame
            else:
                self._send_frame(frame)

    def _fall_check(self) -> None:
        """A drive wheel over a drop: the robot falls, in any mode (in Safe its wheel drop then
        gives Passive: :meth:`_safety`); driving forward in Safe, the cliff sensors saw the
        edge first and stopped it. A method of its own, called only where there are drops:
        inline, the test measured 1 % of a step more in a world with none (``bench.icount
        --sim dock``)."""
        if not self.fallen and self._wheel_over_drop():
            self._fall()

    def settle_wheels(self) -> None:
        """The wheels' speeds (``left_speed``, ``right_speed``: the last step's) set now to
        the 0 the next step would turn them at, when it would: in Passive or Off with no
        built-in cycle, or in Safe or Full asked for 0. A host that stopped the robot and
        let go (:meth:`SimLink.close <roomba_bt.sim.link.SimLink.close>`) then reads a
        stopped robot, as the wire said it, not the speed of the step before its stop.
        What the next step does is unchanged: the stop's bookkeeping (:meth:`_move` to 0)
        done early, which that step then finds done; a speed other than 0 waits for the
        step, which moves the robot."""
        if not (self.left_speed or self.right_speed):
            return
        mode = self.mode
        if mode is _PASSIVE and self.builtin is not None:
            return  # the cycle's own wheels, worked out by the step
        if (mode is _SAFE or mode is _FULL) and (self.requested_left or self.requested_right):
            return
        self._move(0.0, 0.0, STEP_SECONDS)

    def _send_frame(self, frame: bytes) -> None:
        """A stream frame through the faults of the link: dropped, cut short, then
        corrupted, flipped or delayed (:meth:`_emit`); none once the link is cut."""
        if self.disconnected:
            return
        faults = self.faults
        if faults.drop_rate and self._fault_rng.random() < faults.drop_rate:
            return
        if faults.truncate_rate and self._fault_rng.random() < faults.truncate_rate:
            frame = frame[: self._fault_rng.randrange(1, len(frame))]
        self.frames_sent += 1
        self._emit(frame)

    def run(self, seconds: float) -> bytes:
        """Step for ``seconds`` of simulated time; return everything sent meanwhile."""
        out = bytearray()
        for _ in range(round(seconds / STEP_SECONDS)):
            self.step()
            out += self.read()
        return bytes(out)

    def _cut_link(self) -> None:
        """``Faults.disconnect_at``: the link goes, the robot does not. The OI has no command
        timeout, so the robot goes on with the last command it heard (a drive in Full until
        it falls or its battery is flat; in Safe until a cliff or wheel drop stops it), and the
        simulator goes on simulating it: nothing more is heard or sent (frames go nowhere, not
        counted), and no other fault comes (they are the session's, which is over). The event
        says what the robot was doing (:func:`roomba_bt.sim.narrate.after_the_cut` reads it)."""
        self.disconnected = True
        self._discard_output()
        self._plain_output = False  # frames through _send_frame, which drops them
        self._disconnect_at = self._next_timed = self._fault_at = math.inf
        self._timed_faults.clear()
        if self.mode is _SAFE or self.mode is _FULL:
            doing = f"wheels {self.requested_left:.0f}/{self.requested_right:.0f} mm/s"
        elif self.builtin is not None:
            doing = f"its own {self.builtin.name} cycle"
        else:
            doing = "wheels not driven"
        self.event("disconnect", f"link lost in {self.mode.label}, {doing}")

    def _timed_fault(self) -> None:
        """The one-off faults due now (``Faults.reset_at``, ``stream_stop_at``, ``sleep_at``,
        ``baud_change_at``). ``sleep_at`` is the power-saving sleep of five idle minutes in
        Passive; the OI spec's Safe and Full "never sleep", so a robot in them when it is due
        sleeps once in Passive and idle (:meth:`_may_sleep`): a run that ends sleeps after
        its safe stop, and a run that drives never meets a sleep no robot has."""
        if self._fault_clock_waits:
            if self._stream is None:
                return  # _fault_at stays due: the next step looks again
            self._start_fault_clock()
        waits_for_passive = False
        while self._timed_faults and self._timed_faults[0][0] <= self.time:
            _, kind = self._timed_faults.pop(0)
            if kind.startswith("sleep") and not self._may_sleep(kind):
                waits_for_passive = True
                continue
            self.event("fault", kind)
            if kind == "reset":  # as Reset (7) does: the mode it leads to, then the banner
                spec = COMMANDS[opcodes("reset")[0]]
                if spec.leads_to is not None:
                    self._command_mode(spec)
                self._on_reset(b"")
            elif kind == "stream gap":  # no frame until the gap's end; its stream kept
                self._gapped_stream, self._stream = self._stream, None
            elif kind == "stream gap end":
                if self._stream is None:  # unless a new one came meanwhile
                    self._stream = self._gapped_stream
                    self._settle_far()  # the far sensors may be streamed again
                self._gapped_stream = None
            elif kind.startswith("sleep"):
                self.fall_asleep(f"fault: {kind}")  # deaf until BRC, as the 5-min sleep
            elif kind == "baud change":
                to = self.faults.baud_change_to
                self.baud = to if to is not None else 19200 if self.baud == 115200 else 115200
                self.event("baud", f"now {self.baud}")
            else:
                self._end_stream()
        if waits_for_passive:  # looked at again next step: it sleeps once in Passive
            self._timed_faults.insert(0, (self.time, SLEEP_IN_PASSIVE))
        self._next_timed = self._timed_faults[0][0] if self._timed_faults else math.inf
        self._fault_at = min(self._disconnect_at, self._next_timed)

    def _may_sleep(self, kind: str) -> bool:
        """Whether a ``sleep_at`` fault due now sleeps now: never in Safe or Full (the OI
        spec: they "never sleep"); in Passive at once, or, once it waited for Passive
        (:data:`SLEEP_IN_PASSIVE`), after :data:`QUIET_BEFORE_SLEEP_S` with nothing from the
        host. A sleep the instant a run's stop put the robot in Passive cut that stop's
        confirmation short (the run then named a lost stream); a real robot waits five
        minutes of that quiet."""
        if self.mode is _SAFE or self.mode is _FULL:
            return False
        return kind != SLEEP_IN_PASSIVE or self.time - self._last_activity >= QUIET_BEFORE_SLEEP_S

    def _start_fault_clock(self) -> None:
        """``Faults.from_stream``: the first step with a stream on; the fault times, offsets
        until now, are counted from it."""
        now = self.time
        self._fault_clock_waits = False
        self._timed_faults = [(now + at, kind) for at, kind in self._timed_faults]
        if self.faults.disconnect_at is not None:
            self._disconnect_at = now + self.faults.disconnect_at

    def _world_events(self, timeline: Timeline) -> None:
        """The timeline's events due now: marked, and their effects on the body."""
        for kind, detail in timeline.advance(self.time):
            self.event(kind, detail)
        for button in timeline.pressed:
            self.press_button(button)
        effects = timeline.effects()
        held = (
            self._event_bump, self.lifted, self.dock_powered, self._event_overcurrents,
            self.plugged_in,
        )  # fmt: skip
        if effects != held:
            (
                self._event_bump, self.lifted, self.dock_powered, self._event_overcurrents,
                self.plugged_in,
            ) = effects  # fmt: skip
            self._timeline_changed_power()  # a charger may have come on or gone off
            self._check_safety()  # a plug put in is one of Safe mode's stops
            self._body_changed()
            self._geometry_dirty = True
            self._ir_stale = True
        if timeline.over:
            self._timeline = None

    def _end_builtin(self, cycle: BuiltinCycle) -> None:
        """A built-in cycle ended by itself (the event says why); the robot stays in Passive."""
        self.builtin = None
        self.event("builtin", cycle.ended or "")
