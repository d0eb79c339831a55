"""The leaves a behaviour derives from: :class:`RobotBehaviour`, :class:`Action`,
:class:`Condition`.

py_trees behaviours ticked by the lean tick (:class:`~roomba_bt.behaviours.lean.DirectLeaf`).
A leaf is configured in ``__init__`` with its declared parameters (checked there when built
from Python: :meth:`Declaration.checked <roomba_bt.behaviours.declare.Declaration.checked>`),
gets the robot in ``setup(robot=...)``, reads the tick's :class:`Snapshot
<roomba_bt.robot.interface.Snapshot>` and queues commands in the outbox (:meth:`send`,
holding each to its declaration's ``sends=``). An :class:`Action` stops what it set going on
every ending; a :class:`Condition` says SUCCESS or FAILURE from this tick's frame, by a short
tick when its lifecycle is its own. How a behaviour declares itself is
:mod:`roomba_bt.behaviours.declare`; its blackboard, :mod:`roomba_bt.behaviours.blackboard`.
"""

from __future__ import annotations

import contextlib
import functools
import inspect
import logging
from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING, Any

import py_trees

from roomba_bt.behaviours.blackboard import BlackboardRef, KeyRange, UnwrittenKey, read_key
from roomba_bt.behaviours.driving import (
    cycle_may_run,
    left_driving_message,
    needs_mode_message,
)
from roomba_bt.behaviours.lean import DirectLeaf, InvalidStatus, behaviour_tick, checked_status
from roomba_bt.oi.encode import COMMAND_WANTED, Command, halt, motors_off, turns_wheels
from roomba_bt.oi.modes import DRIVING_MODES, OIMode
from roomba_bt.oi.opcodes import COMMANDS, Effect
from roomba_bt.robot.hazards import sets_going
from roomba_bt.robot.interface import Outbox, RobotHandle, Snapshot
from roomba_bt.yamlsource import quoted

if TYPE_CHECKING:
    from roomba_bt.behaviours.declare import Declaration

#: what a behaviour's own mistakes that the runtime mended are said on (as the mission's)
_log = logging.getLogger("roomba_bt.mission")

_BUILTIN_CYCLE = Effect.BUILTIN_CYCLE  # read once: send() asks on every command
_SILENCES = Effect.SILENCES
#: what a halts_only leaf that set something going is told (:class:`UnkeptDeclaration`)
_HALTS_ONLY = (
    "halts_only=True (its commands only stop: Drive 0, Drive Direct 0 0, Motors 0), and this "
    "one sets the wheels, a cycle or a motor going; the Full-mode warning passes a halts_only "
    "leaf by: drop halts_only=True if it drives"
)
#: what a mode_first leaf whose first command was no mode command is told
_MODE_FIRST = (
    "mode_first=True (each time it starts, its first command is one of its mode commands), "
    "and this one came before any since it started: validate judged only its mode commands "
    "where it is reached (Passive, say) and this one in the mode they lead to; send its Safe "
    "or Full first, or drop mode_first=True and put mode: safe before it in the mission"
)

_RUNNING, _SUCCESS, _FAILURE = (
    py_trees.common.Status.RUNNING, py_trees.common.Status.SUCCESS, py_trees.common.Status.FAILURE
)  # fmt: skip
_DEBUG = py_trees.logging.Level.DEBUG


class CheckedParams(dict[str, Any]):
    """Parameters the mission compiler has checked and parsed (each problem said at its
    file:line:col): a leaf built with them takes them as they are, with no second check."""


class UndeclaredCommand(TypeError):
    """A behaviour sent a command its declaration's ``sends=`` does not list. What it sends
    is what the compiler reads: the modes the mission needs, the mode check, the Full-mode
    warning about driving blind at a cliff; an undeclared Drive escaped all three (decided:
    the behaviour's error, at its first such send, before the command is queued)."""

    def __init__(self, behaviour: RobotBehaviour, command: Command) -> None:
        declaration = behaviour.declaration
        if declaration.kind == "condition":  # sends= is refused on a condition: not that
            super().__init__(
                f"{declaration.name} sent {command.spec.name} ({command.spec.opcode}), but it "
                "is a condition, which only reads: a behaviour that sends commands is an "
                f"action (derive {type(behaviour).__name__} from roomba_bt.behaviours.Action, "
                f"declare kind='action', sends=opcodes({command.spec.name!r}), and return a "
                "Status from update())"
            )
            return
        listed = ", ".join(f"{COMMANDS[op].name} ({op})" for op in declaration.sends) or "nothing"
        super().__init__(
            f"{declaration.name} sent {command.spec.name} ({command.spec.opcode}), which its "
            f"declaration does not list: add {command.spec.opcode} to @declare(sends=...) "
            f"(it lists {listed})"
        )


class UnkeptDeclaration(TypeError):
    """A behaviour sent a command that breaks what its declaration says of it beyond
    ``sends=``: ``halts_only=True`` and a command that sets something going (a turning
    wheel, a built-in cycle, a running brush), or ``leads_to=`` one mode and a mode command
    leading to another. The Full-mode warning reads ``halts_only`` and the static mode check
    ``leads_to``, as both read ``sends``: a declaration taken on trust would let a leaf
    drive in Full unwarned, so the behaviour's error comes at that send, before the command
    is queued, as :class:`UndeclaredCommand`'s does."""

    def __init__(
        self,
        behaviour: RobotBehaviour,
        command: Command,
        broken: str,
        returned: py_trees.common.Status | None = None,
    ) -> None:
        #: the behaviour, and the status it returned where that broke it (a SUCCESS in a
        #: mode it only passes through): the run's error names the ``return`` that gave it
        self.node, self.returned = behaviour, returned
        #: what the tree drawn after the run says beside the leaf, where the run refused
        #: what it returned (``its SUCCESS refused: it ended in Full, not Safe``); "" else
        self.refusal = ""
        cls = type(behaviour)
        where = ""
        with contextlib.suppress(OSError, TypeError):
            where = f" (at {inspect.getsourcefile(cls)}:{inspect.getsourcelines(cls)[1]})"
        spec = command.spec
        super().__init__(
            f"{behaviour.declaration.name} sent {spec.name} ({spec.opcode}) "
            f"{command.data.hex(' ')}, but its @declare{where} says {broken}"
        )


class RobotBehaviour(DirectLeaf, py_trees.behaviour.Behaviour):
    """Base of every leaf: configuration in ``__init__``, the robot in ``setup(robot=...)``.

    Ticked by :class:`~roomba_bt.behaviours.lean.DirectLeaf` (py_trees' leaf tick without
    its per-tick debug formatting, and without a generator when ticked by ``tick_once``).

    ``params`` are the validated values in canonical units (``velocity`` in mm/s, ``duration``
    in s), or :class:`BlackboardRef` for ``@key`` values, resolved by :meth:`value` when the
    behaviour starts. Subclasses override :meth:`update` (and :meth:`start` for what must
    happen once when the behaviour starts), never block and never touch a port.
    """

    declaration: Declaration
    _defaults: dict[str, Any]

    def __init__(self, name: str, params: Mapping[str, Any] | None = None) -> None:
        super().__init__(name=name)
        cls = type(self)
        defaults = cls.__dict__.get("_defaults")
        if defaults is None:  # parsed once per class, not once per node
            defaults = cls.declaration.defaults
            cls._defaults = defaults
        values = dict(defaults)
        # the compiler's are checked (at file:line:col); Python's are checked here: none
        # given ({} or None) too, for the required ones, and a non-mapping (Wait("n", "2s"))
        if type(params) is CheckedParams:
            values.update(params)
        else:
            values.update(cls.declaration.checked(name, {} if params is None else params))
        self.params: dict[str, Any] = values
        self.robot: RobotHandle | None = None
        self._resolved: dict[str, Any] = values
        self._refs: dict[str, BlackboardRef] | None = None

    @classmethod
    def declaration_problem(cls, declaration: Declaration) -> str | None:
        """What makes ``declaration`` wrong for this class, beyond what every declaration is
        checked for (None: nothing). A base class whose subclasses must declare something
        it relies on says so here, so a plugin's mistake is named when it is declared, not
        at its first tick on a robot."""
        return None

    def setup(self, **kwargs: Any) -> None:
        robot = kwargs.get("robot")
        if robot is not None:
            self.robot = robot

    @property
    def snapshot(self) -> Snapshot:
        robot = self.robot
        if robot is None:
            raise RuntimeError(
                f"behaviour {self.name!r} was ticked before setup(robot=...): call "
                "CompiledMission.setup(robot) first"
            )
        return robot.snapshot

    def send(self, command: Command) -> None:
        robot = self.robot
        if robot is None:
            raise RuntimeError(f"behaviour {self.name!r} has no robot: call setup(robot=...)")
        if type(command) is not Command:  # raw bytes would pass no mode guard nor range check
            raise TypeError(
                f"send() takes {COMMAND_WANTED}, not {type(command).__name__} {command!r:.60}"
            )
        spec = command.spec
        declaration = self.declaration
        if spec.opcode not in declaration.sends:  # the compile-time checks read sends=
            raise UndeclaredCommand(self, command)
        if declaration.halts_only and sets_going(command):  # the Full-mode warning reads it
            raise UnkeptDeclaration(self, command, _HALTS_ONLY)
        if spec.leads_to is not None:  # the static mode check reads leads_to=
            self._hold_to_leads_to(command, spec.leads_to)
            self._mode_sent = True
        elif declaration.mode_first and not self._mode_sent and self._mode_comes_first():
            raise UnkeptDeclaration(self, command, _MODE_FIRST)  # validate read mode_first=
        if spec.drives_wheels:  # what it set turning is stopped when it ends (terminate)
            self._started_motion = turns_wheels(command)
        elif spec.effect is _BUILTIN_CYCLE:  # ended when it is halted or fails (terminate)
            if cycle_may_run(robot):
                # a cycle command into a running cycle pauses it (600 / Create 2 spec):
                # end that one first (Safe, drive 0, motors off, Start), then start this
                robot.outbox.end_cycle(self)
            # another leaf's cycle command queued in this tick: written and ended before
            # this one, not replaced by it (its leaf says SUCCESS for a command it sent)
            robot.outbox.end_queued_cycle(self)
            self._started_cycle = True
        elif spec.effect is _SILENCES and robot.snapshot.mode in DRIVING_MODES:
            # Stop and Reset say nothing of the wheels and brushes: sent where they may
            # turn, they go after drive 0 and motors off, as --end-in stop's Stop does
            robot.outbox.send(halt(), self)
            robot.outbox.send(motors_off(), self)
        robot.outbox.send(command, self)

    def _mode_comes_first(self) -> bool:
        """Whether this leaf, with its parameters as the mission gives them (the static
        check's, ``@key`` values unread), sends a mode command first each start
        (:meth:`~roomba_bt.behaviours.declare.Declaration.mode_comes_first`: one rule with
        validate); asked once, at the first command before a mode command."""
        first = self._mode_first
        if first is None:
            first = self._mode_first = self.declaration.mode_comes_first(self.params)
        return first

    def _hold_to_leads_to(self, command: Command, sent: OIMode) -> None:
        """Refuse a mode command (leading to ``sent``) leading elsewhere than the mode its
        declaration says it leads to with its parameters (none said: the check took the mode
        as unchanged) or a mode it says it passes through on the way (``passes_through=``:
        noted, :attr:`_passing`, until a command leads on to the mode it leads to)."""
        declaration = self.declaration
        declared = declaration.mode_after(self._resolved)
        if sent is declared:
            self._passing = None
            return
        visits = declaration.passes_through
        if sent in visits:
            self._passing = command
            return
        through = f", passes_through={', '.join(m.label for m in visits)}" if visits else ""
        if declared is None:
            broken = (
                "it leaves the mode as it found it (its sends= lead to no one mode, and it "
                f"gives no leads_to=){through}: declare leads_to=OIMode.{sent.name} if it "
                f"ends there, or passes_through=OIMode.{sent.name} and the mode it ends in "
                "if it leaves it again"
            )
        else:
            broken = (
                f"leads_to={declared.label}{through}, and {command.spec.name} leads to "
                f"{sent.label}: the mode check follows leads_to= to judge the leaves after it; "
                "declare the mode it ends in (a function of its parameters where they decide), "
                f"and passes_through=OIMode.{sent.name} if it goes there on the way"
            )
        raise UnkeptDeclaration(self, command, broken)

    def _left_passing(self) -> None:
        """Refuse a SUCCESS in a mode it only passes through (``passes_through=``): the mode
        check takes the leaves after it to start in its ``leads_to``, and a drive after it
        would run in Full unwarned. Said with the command that took it there."""
        command = self._passing
        assert command is not None
        self._passing = None
        declaration = self.declaration
        declared = declaration.mode_after(self._resolved)
        visits = ", ".join(m.label for m in declaration.passes_through)
        ended = declared.label if declared is not None else "the mode it leads to"
        passed = command.spec.leads_to
        assert passed is not None  # a mode command: the one that took it there
        refused = UnkeptDeclaration(
            self,
            command,
            f"leads_to={ended}, passes_through={visits}, and it returned SUCCESS with no mode "
            f"command after this one: it ended in {passed.label}, not {ended}; send the "
            f"command that takes it to {ended} before it succeeds",
            _SUCCESS,
        )
        refused.refusal = f"its SUCCESS refused: it ended in {passed.label}, not {ended}"
        raise refused

    #: whether the last wheel command it sent set them turning (:meth:`send` notes it)
    _started_motion = False
    #: the mode command it last sent where that leads to a mode its declaration's
    #: ``passes_through=`` names, not yet followed by one leading to its ``leads_to``
    #: (:meth:`_hold_to_leads_to`); None: none
    _passing: Command | None = None
    #: whether it sent a built-in cycle (Clean, Spot, Max, Seek Dock) not yet ended by it
    _started_cycle = False
    #: whether it sent a mode command since it started (a ``mode_first`` leaf's first
    #: command is one: :meth:`send`); cleared as it stops (:meth:`Action.stop`)
    _mode_sent = False
    #: whether its first command must be a mode command with its parameters (None: not
    #: asked yet: :meth:`_mode_comes_first`)
    _mode_first: bool | None = None

    def value(self, name: str) -> Any:
        """The parameter ``name`` for this run (blackboard references resolved at start)."""
        return self._resolved.get(name)

    def number(self, name: str) -> float:
        """A numeric parameter as a float (for comparisons). One the declaration lacks (a
        plugin's subclass that re-declared a stage without its parameters) is named as such,
        not as a bare ``KeyError: 'speed'``."""
        try:
            return float(self._resolved[name])
        except KeyError:
            declaration = self.declaration
            if declaration.param(name) is not None:  # declared, with no default, not given
                raise KeyError(
                    f"{type(self).__name__} reads parameter {name!r}, which {self.name!r} was "
                    f"not given and {declaration.name!r} declares with no default (give it "
                    "one, or make it required)"
                ) from None
            declared = ", ".join(p.name for p in declaration.params) or "none"
            raise KeyError(
                f"{type(self).__name__} reads parameter {name!r}, which its declaration "
                f"{declaration.name!r} does not have; it declares: {declared}"
            ) from None

    def __init_subclass__(cls, **kwargs: Any) -> None:
        """A subclass's own ``initialise`` (the py_trees idiom, seldom with ``super()``, as
        py_trees' own does nothing) is wrapped so that the parameters are read first
        (:meth:`read_parameters`): left out, its ``@key`` values stayed references and the
        first ``number()`` raised ``float() argument must be ... not 'BlackboardRef'``,
        naming nothing it did wrong. Only such classes pay for the wrapper; ``start`` stays
        the place for what this class's ``initialise`` should run."""
        super().__init_subclass__(**kwargs)
        own = vars(cls).get("initialise")
        if callable(own) and not getattr(own, "reads_parameters_first", False):
            cls.initialise = _parameters_read_first(own)  # type: ignore[method-assign,assignment]

    def initialise(self) -> None:
        self.read_parameters()
        self.start()

    def read_parameters(self) -> None:
        """This start's parameters: each ``@key`` value read from the blackboard (checked
        against the parameter's range), and the last start's feedback message cleared.
        Done at every start, before :meth:`start` or an ``initialise`` of a subclass's."""
        # started again (a retry's next attempt): what the last run said is not said of this
        # one (``cover [✓]`` showed an earlier attempt's cliff failure at the end of a clean)
        self.feedback_message = ""
        refs = self._refs
        if refs is None:  # the parameters never change: look for @key values once
            refs = self._refs = {
                k: v for k, v in self.params.items() if isinstance(v, BlackboardRef)
            }
        if refs:
            resolved = dict(self.params)
            for pname, ref in refs.items():
                # typed when written (the validator's values; write_key holds a plugin's):
                # the key's type fits this parameter, so no parsing happens during a tick
                raw = read_key(ref.key)
                if ref.field is not None:
                    raw = raw.get(ref.field) if isinstance(raw, Mapping) else None
                if raw is None:  # only a tree built in Python: a mission's reads are proved
                    raise UnwrittenKey(
                        f"{pname} is {ref}, but nothing has written blackboard key "
                        f"{str(ref)[1:]!r} before {self.name!r} started (write it first: a "
                        "SetKey node, or write_key from roomba_bt.behaviours.declare)"
                    )
                param = self.declaration.param(pname)
                problem = param.check_range(raw) if param is not None else None
                if problem is not None:
                    raise KeyRange(self, pname, ref, problem)
                resolved[pname] = raw
            self._resolved = resolved

    def start(self) -> None:
        """Called once each time the behaviour starts (after ``@key`` values are read)."""


def _parameters_read_first(initialise: Callable[[Any], None]) -> Callable[[Any], None]:
    """``initialise`` (a subclass's own) run after :meth:`RobotBehaviour.read_parameters`.
    One that calls ``super().initialise()`` reads them twice, at its start only: the same
    values, as nothing ticks between."""

    @functools.wraps(initialise)
    def reads_parameters_first(self: RobotBehaviour) -> None:
        self.read_parameters()
        initialise(self)

    reads_parameters_first.reads_parameters_first = True  # type: ignore[attr-defined]
    return reads_parameters_first


class Action(RobotBehaviour):
    """An action: puts commands in the outbox. Motion started must stop on every ending."""

    #: Kept for plugins written before :meth:`send` noted motion by itself: a flag that
    #: nothing needs to set (an action that sets the wheels turning is halted when it ends).
    moves = False

    #: how long an action that set the wheels moving waits, once the robot has left Safe and
    #: Full by itself (a cliff, a wheel drop, the charger), for something to bring it back
    PASSIVE_GRACE_S = 1.0
    _out_of_driving_since: float | None = None

    def stranded(self, grace: float | None = None) -> str | None:
        """A failure message once the robot has been out of Safe/Full for longer than
        ``grace`` (s; :attr:`PASSIVE_GRACE_S` unless given; 0: in the tick it shows) while
        this action was driving it, else None. Waiting on silently left the robot in Passive
        until it slept (5 minutes) and the run ended as a lost connection; failing lets the
        tree recover (``retry`` with ``mode: safe``) or end with the cause."""
        snap = self.snapshot
        if snap.mode in DRIVING_MODES:
            self._out_of_driving_since = None
            return None
        if self._out_of_driving_since is None:
            self._out_of_driving_since = snap.time
        if grace is None:
            grace = self.PASSIVE_GRACE_S
        if snap.time - self._out_of_driving_since < grace - 1e-9:
            return None
        waited = f" and was not brought back within {grace:g} s" if grace > 0 else ""
        return left_driving_message(snap.last_fallback, waited)

    def wait_for_driving_mode(self, grace: float | None = None) -> py_trees.common.Status:
        """Out of Safe/Full, where the mode guard would refuse a drive command: an action
        that set the wheels turning waits for them (RUNNING: the robot stopped when it
        fell, and something may bring it back), FAILURE once :meth:`stranded` (``grace``);
        one whose wheels were not turning (it starts there, or fell while it stood) fails
        on its second tick out of them, saying the mode, the fall and the fix
        (:meth:`refused_motion`). It waited for ever, sending nothing: nothing but the tree
        can bring Safe back, and the tree was waiting on it. The first tick is the mode
        command's that a ``parallel`` may queue beside it in the same tick (in either order):
        written after that tick, it has the robot in Safe by the next."""
        if self._started_motion:
            stranded = self.stranded(grace)
            if stranded is None:
                return _RUNNING
            self._started_motion = False
            self.feedback_message = stranded
            return _FAILURE
        if self._out_of_driving_since is None:
            self._out_of_driving_since = self.snapshot.time
            return _RUNNING
        self.feedback_message = self.refused_motion()
        return _FAILURE

    def refused_motion(self, command: Command | None = None) -> str:
        """Why this action may not set the robot going now, the robot being out of the
        modes its command (``command``; None: a wheel command) takes: the failure message
        of :func:`~.driving.needs_mode_message`."""
        needs = DRIVING_MODES if command is None else command.spec.modes
        return needs_mode_message(self.declaration.name, needs, self.snapshot)

    def send_going(self, command: Command) -> py_trees.common.Status:
        """An at-once action's tick: ``command`` queued, SUCCESS; or FAILURE, nothing queued,
        when it would set something going (a brush, the vacuum, a wheel:
        :func:`~roomba_bt.robot.hazards.sets_going`) where the guard will refuse it: the
        robot in a mode that does not take it, and no mode command that does queued before
        it in this tick (a ``parallel``'s ``mode: safe`` beside it). Its message says the
        mode, the fall and the fix (:meth:`refused_motion`). The guard refused it after the
        tick, and the leaf had said SUCCESS for a vacuum that never ran. A halt or motors
        off the guard will refuse is :meth:`stopped_already`'s, as ``stop``'s is."""
        if self.will_be_refused(command):
            if sets_going(command):
                self.feedback_message = self.refused_motion(command)
                return _FAILURE
            return self.stopped_already(command)
        self.send(command)
        return _SUCCESS

    def stopped_already(self, command: Command) -> py_trees.common.Status:
        """The tick of a halt or motors off (``command``) the guard will refuse, out of Safe
        and Full: nothing queued. SUCCESS, said, when no built-in cycle may be driving: both
        specs say the robot "stops all motors and reverts to the Passive mode" when it
        falls, and ``mode: passive`` switches the wheels and motors off before its Start, so
        what the leaf asks for holds already (the refused bytes, counted as a refusal that
        fails ``--strict``, said nothing more; ``motors`` off and ``stop`` alike). FAILURE,
        said, while a cycle (Clean, Spot, Max, Seek Dock) may be driving: in Passive nothing
        the host sends stops its wheels, brushes or vacuum; ``mode: safe`` does
        (docs/protocol.md, "Actuators in Passive")."""
        robot = self.robot
        name, mode = self.declaration.name, self.snapshot.mode.label
        refused = f"{command.spec.title} {command.spec.opcode} is refused there"
        if robot is not None and cycle_may_run(robot):
            self.feedback_message = (
                f"the robot is in {mode} and its own cycle may be driving it: {refused} and "
                f"cannot stop it; put `mode: safe` before {name} (Safe ends the cycle)"
            )
            return _FAILURE
        self.feedback_message = (
            f"the robot is in {mode}: its wheels and motors are stopped already (the OI "
            f"stops them when it leaves Safe/Full), so {name} sent nothing ({refused})"
        )
        return _SUCCESS

    def send_accepted(self, command: Command) -> py_trees.common.Status:
        """An at-once action's tick for a command that sets nothing going but does nothing
        if refused (the LEDs, the display, a Play): ``command`` queued, SUCCESS; or FAILURE,
        nothing queued, where the guard will refuse it (:meth:`will_be_refused`), saying the
        command, the mode, the fall and the fix: SUCCESS there would say ``leds`` and ``play``
        in Passive (after a cliff) lit LEDs and played a song the guard kept off the wire, and
        the mission would go on as if they had."""
        if self.will_be_refused(command):
            spec = command.spec
            what = f"{self.declaration.name} ({spec.title} {spec.opcode})"
            self.feedback_message = needs_mode_message(what, spec.modes, self.snapshot)
            return _FAILURE
        self.send(command)
        return _SUCCESS

    def will_be_refused(self, command: Command) -> bool:
        """Whether the mode guard will refuse ``command`` queued now: the robot is in a mode
        that does not take it, and no mode command that does is queued before it in this
        tick (a ``parallel``'s ``mode: safe`` beside it, written first)."""
        takes = command.spec.modes
        robot = self.robot
        return self.snapshot.mode not in takes and (
            robot is None or queued_mode(robot.outbox) not in takes
        )

    def terminate(self, new_status: py_trees.common.Status) -> None:
        """However the action ends (success, failure, or preempted: INVALID), wheels it
        set turning are stopped: ``[137][0][0][0][0]`` queued in this tick's outbox, unless
        another behaviour already queued a wheel command in this tick (the branch that
        preempted this one: its Drive stands), or the robot is out of Safe and Full: it
        stopped its wheels when it fell to Passive (a cliff, a wheel drop, the charger),
        and the mode guard would refuse the halt.

        A built-in cycle it started is ended when it fails or is halted (INVALID: preempted,
        or its parent halted or started over after it succeeded) while the cycle may still
        drive (:func:`cycle_may_run`): Safe, drive 0, motors off, Start
        (:meth:`~roomba_bt.robot.interface.Outbox.end_cycle`; its cycle command queued in
        this very tick is not written). In Passive nothing else the
        tree sends stops it, and the firmware drove on while the tree showed the leaf
        halted. Its SUCCESS ends nothing: ``clean`` succeeds as its cycle starts,
        ``seek_dock`` once docked."""
        robot = self.robot
        if self._started_motion and robot is not None and robot.snapshot.mode in DRIVING_MODES:
            robot.outbox.send_stop(halt(), self)
        if self._started_cycle and new_status is not _SUCCESS:
            self._started_cycle = False
            if robot is not None:
                robot.outbox.end_cycle(self, running=cycle_may_run(robot))
        self._started_motion = False
        self._out_of_driving_since = None
        self._terminated = True

    #: whether :meth:`terminate` (this class's) ran during the stop under way (:meth:`stop`)
    _terminated = False

    def stop(self, new_status: py_trees.common.Status) -> None:
        """py_trees' stop (``terminate``, then the status); then, if the wheels this action
        set turning are still turning, or a built-in cycle it started still runs, what
        :meth:`terminate` does for them is done here, and said once per class
        (:func:`_said_left_going`). py_trees' own ``terminate`` does nothing, so its users
        override it without calling ``super().terminate()``: the halt would be skipped, and the
        robot drive on after the leaf had ended, with no leaf in charge of it (at 200 mm/s
        through a whole ``wait: 5s``, the bump reflex sending the dead action's drive again).
        Every stop of a leaf comes here: py_trees' ticks and the lean ones
        (:mod:`~roomba_bt.behaviours.lean`), the composites' and decorators' stops of their
        children, and the run's end (:func:`~roomba_bt.runtime.teardown.stop_nodes`)."""
        self._terminated = False
        super().stop(new_status)
        self._mode_sent = False  # its next start sends its mode command first again (not
        # before its terminate: a halt sent there comes after this start's mode command)
        if self._started_motion or (self._started_cycle and new_status is not _SUCCESS):
            self._end_what_terminate_left(new_status)
        if self._passing is not None:  # a mode it passes through: not where it may succeed
            if new_status is _SUCCESS:
                # the run decided it failed: the tree drawn after it showed [✓] beside the
                # refusal (py_trees' stop had set the SUCCESS it returned)
                self.status = _FAILURE
                self._left_passing()
            self._passing = None

    def _end_what_terminate_left(self, new_status: py_trees.common.Status) -> None:
        """The halt (and the cycle's end) that an override of :meth:`terminate` left out, or
        undid by sending a wheel command after ``super().terminate()``. Not at a run's end
        (the tree's stop, each ``terminate`` patched into its node to guard it:
        runtime/teardown.py): the safe stop that follows stops the robot, the outbox is
        dropped, and what the terminate queued is said there as not written (a halt queued
        here would replace it, unsaid)."""
        if "terminate" in vars(self):
            self._started_motion = self._started_cycle = False
            self._out_of_driving_since = None
            return
        robot = self.robot
        driving = (
            self._started_motion and robot is not None and robot.snapshot.mode in DRIVING_MODES
        )
        cycle = (
            self._started_cycle
            and new_status is not _SUCCESS
            and robot is not None
            and cycle_may_run(robot)
        )
        after_super = self._terminated
        Action.terminate(self, new_status)
        if driving or cycle:
            _said_left_going(self, after_super, driving)


def queued_mode(outbox: Outbox) -> OIMode | None:
    """The mode the last mode command queued in ``outbox`` this tick leads to (the flush
    writes each before what was queued after it), or None."""
    for command in reversed(outbox.pending()):
        if command.spec.leads_to is not None:
            return command.spec.leads_to
    return None


#: the classes whose terminate left the wheels turning (or a cycle running) already said
_LEFT_GOING_SAID: set[type] = set()


def _said_left_going(node: Action, after_super: bool, driving: bool) -> None:
    """A warning, once per class, that ``node``'s ``terminate`` left the robot going and that
    :meth:`Action.stop` stopped it: the behaviour, the class, and the file:line of the
    ``terminate`` it has (``after_super``: it called ``super().terminate()`` and then sent
    a wheel command; ``driving``: the wheels, else a built-in cycle)."""
    cls = type(node)
    if cls in _LEFT_GOING_SAID:
        return
    _LEFT_GOING_SAID.add(cls)
    code = getattr(cls.terminate, "__code__", None)
    where = f" at {code.co_filename}:{code.co_firstlineno}" if code is not None else ""
    what = "the wheels were left turning; halted"
    if not driving:
        what = "the built-in cycle it started was left running; ended (Start)"
    how = (
        "sent a wheel command after super().terminate()"
        if after_super
        else "did not call super().terminate()"
    )
    _log.warning(
        "%s (%s.terminate%s) %s: %s (an action that has ended leaves the robot stopped)",
        node.name, cls.__name__, where, how, what,
    )  # fmt: skip


class Condition(RobotBehaviour):
    """A condition: SUCCESS or FAILURE from this tick's frame, never RUNNING."""

    #: True on a class whose ``check`` reads nothing but its own parameters and, from
    #: ``snapshot.frame``, the packets it declares: its result is then a function of those
    #: packets' values (see :class:`~roomba_bt.behaviours.frame_inputs.FrameInputs`). Said
    #: by the class that defines ``check``: a subclass with a ``check`` of its own is not
    #: taken to be pure unless it says so too.
    frame_pure = False
    #: the ``check`` that ``frame_pure`` was said of
    _pure_check: Callable[[Condition, Snapshot], bool] | None = None

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        if vars(cls).get("frame_pure"):
            cls._pure_check = cls.check

    def check(self, snapshot: Snapshot) -> bool:
        raise NotImplementedError

    def update(self) -> py_trees.common.Status:
        ok = self.check(self.snapshot)
        if ok is True:
            return _SUCCESS
        if ok is False:
            return _FAILURE
        return _SUCCESS if checked_truth(self, ok) else _FAILURE

    def tick_direct(self, started: bool = False) -> None:
        """The leaf tick (:func:`~roomba_bt.behaviours.lean.behaviour_tick`) of a condition
        that keeps this lifecycle, with the calls that do nothing left out: ``initialise``
        only reads ``@key`` parameters (``start`` does nothing), and ``stop`` is the status
        (``terminate`` does nothing). The reactive guards restart every condition on every
        tick, so this is most of what a tree's tick calls. A class with a lifecycle step of
        its own (looked up each tick: a test may patch one in) gets the whole leaf tick;
        ``update`` is looked up on the node, so a node's own (the monitor forces a condition
        so) decides, and when it is :meth:`update` itself, ``check`` is called directly. The
        node's ``__dict__`` is not read: on CPython 3.11 that gives the node a dictionary for
        good, and every attribute read of it gets slower."""
        cls = type(self)
        if (
            started
            or self.status is _RUNNING
            or py_trees.logging.level is _DEBUG
            or cls.initialise is not _CONDITION_INITIALISE
            or cls.start is not _CONDITION_START
            or cls.terminate is not _CONDITION_TERMINATE
            or cls.stop is not _CONDITION_STOP
        ):
            behaviour_tick(self, started)
            return
        refs = self._refs
        if refs is None or refs:  # not looked for yet, or @key parameters to read at each start
            self.initialise()
        update = self.update
        if getattr(update, "__func__", None) is _CONDITION_UPDATE:  # update is check
            robot = self.robot
            ok = self.check(robot.snapshot if robot is not None else self.snapshot)
            if ok is True:
                self.status = _SUCCESS
            elif ok is False:
                self.status = _FAILURE
            else:
                self.status = _SUCCESS if checked_truth(self, ok) else _FAILURE
            return
        status = update()
        if status is not _SUCCESS and status is not _FAILURE:
            status = checked_status(self, status)
        self.status = status


class InvalidCheck(InvalidStatus):
    """A condition's ``check`` returned no truth value: None (a forgotten ``return``), a
    text (``"no"`` was true), a Status (``check`` written as ``update``: FAILURE was true),
    or anything else that is not a bool or a number. Raised as :class:`InvalidStatus` is
    (the run ends as the behaviour's error, exit 4)."""

    method = "check"

    @staticmethod
    def describe(node: py_trees.behaviour.Behaviour, status: object) -> str:
        hint = ""
        if isinstance(status, py_trees.common.Status):
            hint = " (check says whether the condition holds; update returns a Status)"
        return (
            f"{type(node).__name__}.check() returned {quoted(status)}, not a bool: it must "
            f"return True or False (a number is taken by its truth){hint}"
        )


def checked_truth(node: Condition, ok: object) -> bool:
    """What ``check`` returned (neither True nor False) as a truth: a bool or a number
    (anything with ``__float__``, such as numpy's ``bool_`` and numbers: 0 is false);
    anything else (None, a text, a Status, a list) raises :class:`InvalidCheck`."""
    if isinstance(ok, bool) or (
        hasattr(type(ok), "__float__") and not isinstance(ok, str | bytes | bytearray)
    ):
        return bool(ok)
    raise InvalidCheck(node, ok)


#: the lifecycle steps a condition's short tick stands for (:meth:`Condition.tick_direct`)
_CONDITION_UPDATE, _CONDITION_INITIALISE, _CONDITION_START = (
    Condition.update, Condition.initialise, Condition.start
)  # fmt: skip
_CONDITION_TERMINATE, _CONDITION_STOP = Condition.terminate, Condition.stop


#: what a class with the short tick has after ``check``: its update, initialise, start,
#: terminate and stop (:meth:`FrameInputs.usable
#: <roomba_bt.behaviours.frame_inputs.FrameInputs.usable>` compares the six at once)
SHORT_LIFECYCLE = (
    _CONDITION_UPDATE, _CONDITION_INITIALISE, _CONDITION_START, _CONDITION_TERMINATE,
    _CONDITION_STOP,
)  # fmt: skip
