"""How a behaviour declares itself, once: parameters, packets read, commands sent, mode.

One :class:`Declaration` per behaviour feeds everything else: the mission validator (names,
types, units, ranges, required parameters, the static mode check), ``roomba-bt behaviours``,
the JSON Schema, and the stream request (``CompiledMission.packets``)::

    @declare(
        "bump",
        kind="condition",
        params=(Param("side", enum("left", "right", "any"), default="any"),),
        reads=(7,),
    )
    class Bump(Condition):
        def check(self, snapshot: Snapshot) -> bool: ...

The modes a behaviour needs are not written by hand: they are the intersection of the
``modes`` of the opcodes it declares in ``sends`` (read from :mod:`roomba_bt.oi.opcodes`), so
Drive (137) needs Safe or Full because the table says so.

The rest of what a plugin author uses has a module of its own: the leaves to derive from
(:mod:`.base`: ``RobotBehaviour``, ``Action``, ``Condition``), the mission's blackboard
(:mod:`.blackboard`: ``read_key``, ``write_key``, ``declare_keys``, ``@key`` references), the
driving leaves' shared helpers (:mod:`.driving`: ``WHEEL``, ``cycle_may_run``,
``left_driving_message``) and the guard's memo of pure conditions (:mod:`.frame_inputs`:
``FrameInputs``); ``roomba_bt.behaviours`` names the ones a plugin needs.

Every other public name this module's namespace held in 0.1.0 still imports from here, as
the very object its home defines: a plugin written then imported what it found here
(``InvalidStatus``, ``Snapshot``, ``SensorFrame``, ``DRIVING_MODES``, ``halt``...), not only
what was defined here. Each is in :data:`MOVED` and warns (a DeprecationWarning naming its
home) until 0.3.0 drops it; tests/test_moved_names.py holds the whole list, so a name
dropped fails a test, not a plugin.
"""

from __future__ import annotations

import math
import re
import sys
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any, Literal, TypeVar

from roomba_bt._lazy import moved_names
from roomba_bt.behaviours.base import Action, Condition, RobotBehaviour
from roomba_bt.behaviours.blackboard import BlackboardRef, blackboard_ref
from roomba_bt.behaviours.driving import WHEEL
from roomba_bt.behaviours.units import SPEED, VALUE_TYPES, UnitError, ValueType, closest
from roomba_bt.errors import RoombaBtError
from roomba_bt.oi.modes import ALL_MODES, OIMode
from roomba_bt.oi.odometry import SLOWEST_MOVING_SPEED_MM_S, WHEEL_SPEED_STEP_MM_S
from roomba_bt.oi.opcodes import COMMANDS, Effect
from roomba_bt.oi.packets import PACKETS
from roomba_bt.oi.profiles import RobotProfile
from roomba_bt.printable import CONTROL, yaml_written
from roomba_bt.yamlsource import character_name, quoted

#: The names this module offered in 0.1.0 that other modules define (each -> its module):
#: moved since, or only imported here for a declaration's use then, and so found here by
#: plugins written for it (``InvalidStatus`` from lean, ``Snapshot`` from robot.interface,
#: the modules ``logging``...). Each still gives the very object, with a DeprecationWarning
#: naming its home until 0.3.0 (tests/test_moved_names.py holds the whole list of 0.1.0's).
MOVED: dict[str, str] = {
    **dict.fromkeys(
        ("CheckedParams", "InvalidCheck", "UndeclaredCommand", "checked_truth"),
        "roomba_bt.behaviours.base",
    ),
    **dict.fromkeys(
        ("BLACKBOARD_REF", "KEY_TYPES_KEY", "MISSION_NAMESPACE", "SNAPSHOT_KEY", "KeyRange",
         "KeyType", "UnwrittenKey", "declare_keys", "read_key", "write_key"),
        "roomba_bt.behaviours.blackboard",
    ),
    **dict.fromkeys(
        ("CHARGER_ADVICE", "cycle_may_run", "left_driving_message", "on_home_base"),
        "roomba_bt.behaviours.driving",
    ),
    "FrameInputs": "roomba_bt.behaviours.frame_inputs",
    **dict.fromkeys(
        ("DirectLeaf", "InvalidStatus", "Selector", "Sequence", "behaviour_tick",
         "checked_status"),
        "roomba_bt.behaviours.lean",
    ),
    **dict.fromkeys(("MARK", "held"), "roomba_bt.behaviours.units"),
    **dict.fromkeys(("Command", "halt", "motors_off", "turns_wheels"), "roomba_bt.oi.encode"),
    **dict.fromkeys(("CHARGING_SOURCES_PACKETS", "SensorFrame"), "roomba_bt.oi.frames"),
    "DRIVING_MODES": "roomba_bt.oi.modes",
    "COMMANDS_BY_NAME": "roomba_bt.oi.opcodes",
    **dict.fromkeys(
        ("ModeChange", "Odometry", "RobotHandle", "Snapshot"), "roomba_bt.robot.interface"
    ),
    **{module: module for module in ("logging", "operator", "py_trees", "uuid")},
}  # fmt: skip

if not TYPE_CHECKING:  # to a type checker the old names are gone, and a typo no Any (PEP 562)
    __getattr__ = moved_names(__name__, MOVED)

__all__ = [
    # the declaration, defined here
    "B",
    "ComparesOf",
    "Comparison",
    "Declaration",
    "DeclarationError",
    "Kind",
    "ModeOf",
    "PacketsOf",
    "Param",
    "ParamError",
    "class_doc",
    "declare",
    "declare_like",
    "from_python",
    "mode_after_sending",
    "wheel_speed_param",
    # defined in base, blackboard and driving, and used here
    "WHEEL",
    "Action",
    "BlackboardRef",
    "Condition",
    "RobotBehaviour",
    "blackboard_ref",
]

Kind = Literal["action", "condition"]
_NAME = re.compile(r"^[a-z][a-z0-9_]*$")


class DeclarationError(ValueError, RoombaBtError):
    """A behaviour that declares itself wrongly (a plugin author's mistake)."""


class ParamError(TypeError, ValueError, RoombaBtError):
    """A leaf built in Python with a parameter its declaration does not have, a value its
    type cannot read, one out of range, or a required one missing: refused when the leaf is
    built, not at its first tick with the robot in Safe. A TypeError, as an unknown keyword
    argument is, and a ValueError, as a bad value is: either ``except`` catches it."""


@dataclass(frozen=True, slots=True)
class Param:
    """One parameter: its type (and so its unit), range in that unit, default, and doc."""

    name: str
    type: ValueType
    default: Any = None
    required: bool = False
    minimum: float | None = None
    maximum: float | None = None
    doc: str = ""
    #: may the value be ``@key`` (read from the blackboard at run time)?
    from_blackboard: bool = True
    #: why ``minimum`` is what it is, said after a value below it (``" (...)"``); a speed
    #: whose minimum is :data:`SLOWEST_MOVING_SPEED_MM_S` says the wheel stands still without
    #: it. A minimum set for another reason says nothing of standing still: a ``dock_search``
    #: speed of 10 mm/s said so, where 20 mm/s, refused alike, said nothing.
    minimum_why: str = ""
    #: the spec's name for it where other than ``name`` (the dock LED is the 600 spec's
    #: "Home"): a mission that writes the spec's word is pointed to ``name``
    spec_name: str = ""
    #: ``(positive, negative)``: which way a value of each sign goes, said after the value
    #: in the leaf's name (``turn``'s angle: ``turn(-45deg right)``), so that a negative
    #: value reads without the convention at hand; empty: the sign says enough
    signs: tuple[str, str] | tuple[()] = ()

    def check_range(self, value: Any, written: str = "") -> str | None:
        """An error message if ``value`` is outside the range, else None. ``written``: the
        value as the mission writes it, said first where it is not the canonical text
        (``velocity 1.5 m/s (1500 mm/s) is out of range``: ``1500 mm/s`` alone was no
        text the file held)."""
        if not isinstance(value, int | float) or isinstance(value, bool):
            return None
        lo, hi = self.minimum, self.maximum
        if (lo is not None and value < lo) or (hi is not None and value > hi):
            unit = f" {self.type.unit}" if self.type.unit else ""
            shown = f"{value:g}{unit}"
            written = written.strip()
            if written and written.replace(" ", "") != shown.replace(" ", ""):
                shown = f"{written} ({shown})"
            why = ""
            if lo is not None and 0 <= value < lo:  # a negative one is refused for its sign
                why = self.minimum_why
                if not why and self.type is SPEED and lo == SLOWEST_MOVING_SPEED_MM_S:
                    why = STANDS_STILL
            allowed = f"allowed {range_said(lo, hi, unit)}"
            return f"{self.name} {shown} is out of range: {allowed}{why}"
        return None

    def describe(self) -> str:
        parts = [self.type.describe()]
        if self.minimum is not None or self.maximum is not None:
            parts.append(f"{_bound(self.minimum)}..{_bound(self.maximum)}")
        if self.required:
            parts.append("required")
        elif self.default is not None:
            parts.append(f"default {yaml_written(self.default)}")
        return ", ".join(parts)


#: the types whose number from Python is a quantity in the type's unit
_QUANTITIES = frozenset({"duration", "speed", "distance", "angle", "percent", "radius"})


def from_python(param: Param, value: Any) -> Any:
    """``value`` as a leaf built in Python gives it, checked by ``param``'s declared type:
    a quantity is a finite real number in the type's unit (not a bool) or a text with its
    unit; a bool a bool, an int an int, an enum one of its words, a text a text without
    control characters (as the YAML reader has it: a text reaches the terminal). A
    :class:`BlackboardRef`, or a text ``"@key"`` / ``"@key.field"`` as YAML writes one, is a
    value read from the blackboard where the parameter allows it (``from_blackboard``), its
    key not checked until the run (no mission declares keys from Python); what is no text
    for a type of a behaviour's own passes as it is (its parsed form: song notes as (note,
    64ths) pairs). Raises :class:`UnitError` saying what was found and what is allowed."""
    kind = param.type
    if isinstance(value, str) and value.startswith("@"):
        value = blackboard_ref(value)  # "@leg" as in YAML
    if isinstance(value, BlackboardRef):
        if not param.from_blackboard:
            raise UnitError(f"a blackboard value ({value}) is not allowed here")
        return value
    if kind.name == "any":
        return value
    if value is None:
        raise UnitError(f"required: None gives no value ({kind.describe()})")
    if kind.name == "str":
        if not isinstance(value, str):
            raise UnitError(f"expected a text, got {quoted(value)} ({type(value).__name__})")
        control = CONTROL.search(value)
        if control is not None:
            raise UnitError(
                f"control character {character_name(control.group())} is not allowed in a "
                "text: it may hold printable characters, tabs and line breaks only"
            )
        return value
    if isinstance(value, str) or kind.choices or kind.name in ("int", "bool"):
        return kind.parse(value)  # a text with its unit, an enum's word, a bool, an int
    if kind.name not in _QUANTITIES and kind.name != "float":
        return value  # a type of its own (song notes, a sensor test): its parsed form as is
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise UnitError(
            f"expected {kind.describe()}: a number in {kind.unit or 'its unit'} or a text with "
            f"its unit, got {quoted(value)} ({type(value).__name__})"
        )
    if not math.isfinite(value):
        raise UnitError(f"must be a finite number, got {value!r}")
    return value


def _bound(value: float | None) -> str:
    return "" if value is None else f"{value:g}"


def range_said(lo: float | None, hi: float | None, unit: str = "") -> str:
    """A range as a message says it: ``0..2 mm``; open at one end, ``0 s or more`` or ``5 m
    or less`` (``allowed 0.. s`` left the reader to guess what the missing end meant).
    ``unit`` with its leading space, or ""."""
    if lo is None and hi is None:
        return f"any number{unit}"
    if hi is None:
        return f"{lo:g}{unit} or more"
    if lo is None:
        return f"{hi:g}{unit} or less"
    return f"{lo:g}..{hi:g}{unit}"


PacketsOf = Callable[[Mapping[str, Any]], tuple[int, ...]]
ModeOf = Callable[[Mapping[str, Any]], "OIMode | None"]
#: A packet test ``(packet id, operator, number)``: ``stasis == 2`` is ``(58, "==", 2.0)``.
Comparison = tuple[int, str, float]
#: The packet tests a condition's answer is, by the parameter that sets each
#: (``stasis: dirty`` -> ``(("state", (58, "==", 2.0)),)``).
ComparesOf = Callable[[Mapping[str, Any]], tuple[tuple[str, Comparison], ...]]


@dataclass(frozen=True, slots=True)
class Declaration:
    """Everything the rest of the system knows about a behaviour without running it."""

    name: str
    kind: Kind
    cls: type[RobotBehaviour]
    params: tuple[Param, ...] = ()
    reads: tuple[int, ...] | PacketsOf = ()
    sends: tuple[int, ...] = ()
    leads_to: OIMode | ModeOf | None = None
    doc: str = ""
    #: the parameter a scalar value stands for: ``wait: 2s`` is ``wait: {duration: 2s}``
    primary: str | None = None
    #: where it came from: "builtin", an entry point, or a file path
    origin: str = "builtin"
    #: cross-parameter rules: returns error messages for a set of given parameters
    constraints: Callable[[Mapping[str, Any]], list[str]] | None = None
    writes_keys: tuple[str, ...] = field(default=())  # params naming keys it writes
    reads_keys: tuple[str, ...] = field(default=())  # params naming keys it reads
    #: the type of the value written to or read from the key each of those parameters
    #: names, where the declaration says it (``writes_keys={"key": INT}``, as BT.CPP's
    #: ``OutputPort<int>``): validate holds the mission's ``blackboard:`` declaration of
    #: the key to it. A parameter not here is untyped: any key but a ``mark`` is taken
    key_types: tuple[tuple[str, ValueType], ...] = field(default=())
    #: its wheel commands only stop the wheels (``stop``: Drive 0), so it turns none
    halts_only: bool = False
    #: the modes its own mode commands take the robot to on the way to ``leads_to`` (an
    #: action that sends Full, drives, and sends Safe: ``passes_through=OIMode.FULL``,
    #: ``leads_to=OIMode.SAFE``): ``send()`` takes a mode command leading to one of these
    #: or to ``leads_to``, and the static mode check takes it that the leaf may fail or be
    #: halted in any of them. It succeeds in ``leads_to`` alone (held to when it succeeds)
    passes_through: tuple[OIMode, ...] = ()
    #: each time it starts, its first command is one of its mode commands (Safe or Full:
    #: ``mode_first=True``), so the static mode check judges only those where the leaf is
    #: reached, and its other commands in the modes they take it to: a leaf that sends its
    #: own Safe may be reached in Passive. Held to at ``send()``: another command first is
    #: refused (:class:`~roomba_bt.behaviours.base.UnkeptDeclaration`)
    mode_first: bool = False
    #: the packet tests its answer is, where a parameter names one by a word (``stasis:
    #: dirty`` is ``stasis == 2``): the per-profile range check reads them as it reads a
    #: ``sensor:`` test's, so a test the chosen robot cannot pass is said either way
    compares: ComparesOf | None = None
    #: the commands it sends with given parameters, where fewer than ``sends`` (``mode:
    #: passive`` sends Start alone): the static mode check holds the leaf to those
    sends_by: Callable[[Mapping[str, Any]], tuple[int, ...]] | None = None
    #: SUCCESS on the tick it starts, every time (``stop``, ``set``, ``log``): the static
    #: checks take what it does as done within that tick (a condition, never RUNNING, is
    #: done within it too, but may fail)
    at_once: bool = False
    #: whether it can end in SUCCESS by itself with given parameters, where it cannot always
    #: (``drive`` with no distance, angle or duration is RUNNING until something else ends
    #: it; ``dock_time_limit`` only fails): the static checks read a branch that never
    #: succeeds as one a parallel ticks on every tick. None: it can
    may_succeed: Callable[[Mapping[str, Any]], bool] | None = None
    #: it never ends in FAILURE (``wait``, ``log``): validate says a ``retry`` around it
    #: never retries, and an alternative after it in a fallback can never run
    #: (:mod:`roomba_bt.mission.deadends`). False: it may fail, as any action may
    never_fails: bool = False
    #: what the robot must have for it with given parameters, where not every model has it
    #: (``display`` the digit display, ``press: minute`` a clock panel's button): why the
    #: chosen profile lacks it, or None. Validate says it at the leaf as an error
    needs: Callable[[Mapping[str, Any], RobotProfile], str | None] | None = None
    #: whether the leaf runs all the same where ``needs`` finds the robot lacking (``button:
    #: minute`` on a Create 2 reads a bit that is there, always 0): validate warns, not refuses
    needs_only_warns: bool = False
    #: what it does in Passive beyond its commands' bytes, with given parameters (``press:
    #: clean`` starts the robot's own cleaning cycle, as a finger would), said with the fix;
    #: None: nothing. Validate warns where the leaf may be reached in Passive
    in_passive: Callable[[Mapping[str, Any]], str | None] | None = None
    #: whether, with given parameters, all it asks for is what the OI stopped already in
    #: Passive (``stop``; ``motors`` and ``vacuum`` off): the leaf sends nothing there and
    #: succeeds (``Action.stopped_already``), so validate accepts it in Passive, unless a
    #: built-in cycle the tree started may still drive (then it fails). None: never
    stops_only: Callable[[Mapping[str, Any]], bool] | None = None

    @property
    def defaults(self) -> dict[str, Any]:
        """Default values parsed into canonical units."""
        return {
            p.name: p.type.parse(p.default)
            for p in self.params
            if p.default is not None and not isinstance(p.default, BlackboardRef)
        }

    @property
    def modes(self) -> frozenset[OIMode]:
        """Modes in which every command it sends is accepted (all modes if it sends none)."""
        return _accepted_in(self.sends)

    def sent(self, params: Mapping[str, Any]) -> tuple[int, ...]:
        """The commands it sends with ``params``: ``sends``, or fewer (``sends_by``)."""
        return self.sends if self.sends_by is None else self.sends_by(params)

    def modes_for(self, params: Mapping[str, Any]) -> frozenset[OIMode]:
        """Modes in which every command it sends with ``params`` is accepted (``mode:
        passive`` sends Start alone, accepted in Off too)."""
        return _accepted_in(self.sent(params))

    def mode_comes_first(self, params: Mapping[str, Any]) -> bool:
        """Whether, with ``params``, its first command each start is one of its mode
        commands: a ``mode_first`` leaf whose commands with them (:meth:`sent`,
        ``sends_by``) hold one. One with none with them (``own_mode: false``) is judged as
        any leaf, all its commands where it is reached, and may send any first. The one rule
        both read: the static mode check (:meth:`sent_first`) and ``send()``, which held
        every ``mode_first`` leaf to a mode command first, stricter than the check."""
        if not self.mode_first:
            return False
        return any(COMMANDS[op].leads_to is not None for op in self.sent(params))

    def sent_first(self, params: Mapping[str, Any]) -> tuple[int, ...]:
        """The commands it may send in the mode it is reached in, with ``params``: all it
        sends, or, where its mode command comes first (:meth:`mode_comes_first`), its mode
        commands (its others come after one of those, in the mode it took the robot to). The
        static mode check holds the modes a leaf is reached in to these."""
        sent = self.sent(params)
        if not self.mode_comes_first(params):
            return sent
        return tuple(op for op in sent if COMMANDS[op].leads_to is not None)

    def reached_in(self, params: Mapping[str, Any]) -> frozenset[OIMode]:
        """Modes it may be reached in with ``params``: those that take every command of
        :meth:`sent_first` (a ``mode_first`` leaf that sends Safe: Passive, Safe, Full)."""
        return _accepted_in(self.sent_first(params))

    @property
    def turns_wheels(self) -> bool:
        """Whether it may turn the wheels (the compile-time Full-mode warning asks)."""
        return not self.halts_only and any(COMMANDS[op].drives_wheels for op in self.sends)

    @property
    def is_actuator(self) -> bool:
        return any(COMMANDS[op].is_actuator for op in self.sends)

    @property
    def starts_cycle(self) -> bool:
        """Whether it may start a built-in cycle (Clean, Spot, Max, Seek Dock): the robot
        is in Passive after it, whichever way it ends (a halt or a failure ends the cycle
        with Start: :meth:`Action.terminate`)."""
        return any(COMMANDS[op].effect is Effect.BUILTIN_CYCLE for op in self.sends)

    def packets(self, params: Mapping[str, Any]) -> tuple[int, ...]:
        return self.reads(params) if callable(self.reads) else self.reads

    def mode_after(self, params: Mapping[str, Any]) -> OIMode | None:
        return self.leads_to(params) if callable(self.leads_to) else self.leads_to

    def takes_blackboard_value(self, param: Param) -> bool:
        """Whether ``param`` may be given as ``@key`` (read from the blackboard when the leaf
        starts): where it says so (``from_blackboard``), and never a key parameter, whatever
        it says. The key a key parameter names is checked when the mission is compiled
        (declared, of the type the declaration says, written before it is read); a name read
        from the blackboard at run time passed every one of those checks unseen, and a
        plugin that left out ``from_blackboard=False`` wrote wherever the blackboard said."""
        return param.from_blackboard and key_role(self, param.name) is None

    def key_type(self, pname: str) -> ValueType | None:
        """The declared type of the key parameter ``pname`` names (None: untyped)."""
        for name, vtype in self.key_types:
            if name == pname:
                return vtype
        return None

    def param(self, name: str) -> Param | None:
        for p in self.params:
            if p.name == name:
                return p
        return None

    def checked(self, node: str, params: Mapping[str, Any]) -> dict[str, Any]:
        """``params`` as a leaf built in Python gives them, checked as the compiler checks a
        mission's: each name declared (else a did-you-mean), a text read through the
        parameter's type (``"200 mm/s"`` as in YAML; a number is taken in the type's unit,
        mm/s), each value within the declared range, the required ones given, and the
        cross-parameter rules. :class:`BlackboardRef` values pass as they are. Raises
        :class:`ParamError` naming the behaviour, the node and the parameter."""
        what = f"{self.name} {node!r}"
        if not isinstance(params, Mapping):
            raise ParamError(
                f"{what}: the parameters are a mapping of name to value, such as "
                f"{{'duration': '2 s'}}; got {quoted(params)}"
            )
        out: dict[str, Any] = {}
        for pname, value in params.items():
            param = self.param(pname)
            if param is None:
                names = [p.name for p in self.params]
                raise ParamError(
                    f"{what}: unknown parameter {pname!r}{closest(str(pname), names)}; "
                    f"{self.name} takes: {', '.join(names) or 'no parameters'}"
                )
            if value is None and not param.required:
                continue  # not given: its default
            if _is_blackboard_value(value) and key_role(self, pname) is not None:
                raise ParamError(f"{what}: {pname} {value}: not allowed{key_not_read(self, pname)}")
            try:
                value = from_python(param, value)
            except (UnitError, TypeError, ValueError, KeyError, AttributeError) as exc:
                raise ParamError(f"{what}: {pname}: {exc}") from None
            problem = param.check_range(value)
            if problem is not None:
                raise ParamError(f"{what}: {problem}")
            out[pname] = value
        missing = [p.name for p in self.params if p.required and p.name not in out]
        if missing:
            raise ParamError(f"{what}: missing required parameter(s) {', '.join(missing)}")
        for problem in self.constraints(out) if self.constraints is not None else ():
            raise ParamError(f"{what}: {problem}")
        return out

    def validate(self) -> None:
        """Raise :class:`DeclarationError` naming what is wrong."""
        if not _NAME.match(self.name):
            raise DeclarationError(f"name {self.name!r} is not snake_case ([a-z][a-z0-9_]*)")
        if self.kind not in ("action", "condition"):
            raise DeclarationError(f"kind must be 'action' or 'condition', got {self.kind!r}")
        problem = _kind_problem(self.kind, self.cls)
        if problem is not None:
            raise DeclarationError(problem)
        if not (isinstance(self.cls, type) and issubclass(self.cls, RobotBehaviour)):
            raise DeclarationError(f"{self.cls!r} is not a RobotBehaviour subclass")
        seen: set[str] = set()
        for p in self.params:
            problem = _param_problem(p)
            if problem is not None:
                raise DeclarationError(problem)
            if p.name in seen:
                raise DeclarationError(f"parameter {p.name!r} declared twice")
            seen.add(p.name)
        if not callable(self.reads):
            bad = [pid for pid in self.reads if pid not in PACKETS]
            if bad:
                raise DeclarationError(
                    f"reads unknown sensor packets {bad} (single ids 7-58; by name: "
                    "reads=packet_ids('wall_signal', ...), from roomba_bt.oi.packets)"
                )
        bad = [op for op in self.sends if op not in COMMANDS]
        if bad:
            raise DeclarationError(
                f"sends unknown opcodes {bad} (by name: sends=opcodes('drive', ...), from "
                "roomba_bt.oi.opcodes)"
            )
        problem = _powers_down(self.sends)
        if problem is None:
            problem = _passes_through_problem(self)
        if problem is None:
            problem = _mode_first_problem(self)
        if problem is not None:
            raise DeclarationError(problem)
        if self.kind == "condition" and self.sends:
            raise DeclarationError(
                f"a condition only reads: it sends nothing (sends={self.sends!r}); a behaviour "
                "that sends commands is kind='action'"
            )
        if self.primary is not None and self.primary not in seen:
            raise DeclarationError(f"primary parameter {self.primary!r} is not declared")
        problem = _key_param_problem(self)
        if problem is not None:
            raise DeclarationError(problem)
        problem = self.cls.declaration_problem(self)
        if problem is not None:
            raise DeclarationError(problem)


def _powers_down(sends: tuple[int, ...]) -> str | None:
    """Why ``sends`` may not list a command that powers the robot down (Power, 133: the
    opcode table's ``Effect.POWER_DOWN``), or None. The robot goes to sleep in Passive and
    its stream stops: the run saw a lost cable (CONNECTION LOST, exit 8, "the robot may have
    moved") where a leaf had sent it, and no leaf after it could run. roomba-bt never sends
    Power (docs/protocol.md). Refused when declared, not said at the run's end as Stop and
    Reset are: asleep, the robot answers nothing until it is woken (a
    BRC pulse, its button), and no mission needs it (its safe stop ends in Passive)."""
    for opcode in sends:
        spec = COMMANDS.get(opcode)
        if spec is not None and spec.effect is Effect.POWER_DOWN:
            return (
                f"sends {spec.name} ({opcode}), which roomba-bt never sends: the robot falls "
                "asleep and its sensor stream stops, which a run cannot tell from a lost "
                "cable; leave the robot in Passive with mode: passive, or by the run's end"
            )
    return None


def _passes_through_problem(decl: Declaration) -> str | None:
    """What is wrong with ``decl``'s ``passes_through=``, or None: each an :class:`OIMode`
    that one of its ``sends=`` leads to (a mode it cannot reach is a typo the mode check
    would believe), none the mode it leads to, and that mode said and led to by one of its
    commands: a leaf that passes through Full must send what takes it out again."""
    visits = decl.passes_through
    if not visits:
        return None
    wrong = [m for m in visits if not isinstance(m, OIMode)]
    if wrong:
        return f"passes_through= names OI modes (OIMode.FULL, ...), got {wrong[0]!r}"
    reached = {COMMANDS[op].leads_to for op in decl.sends if op in COMMANDS}
    said = ", ".join(m.label for m in visits)
    for mode in visits:
        if mode not in reached:
            senders = ", ".join(
                f"{c.name} ({c.opcode})"
                for c in COMMANDS.values()
                if c.leads_to is mode and c.effect is not Effect.POWER_DOWN
            )
            return (
                f"passes_through={said}, but none of its sends= leads to {mode.label} "
                f"({senders} would): add the command it sends, or drop {mode.label}"
            )  # fmt: skip
    if callable(decl.leads_to):  # the mode it ends in depends on its parameters
        return None
    if decl.leads_to is None:
        return (
            f"passes_through={said}, and no leads_to= says the mode it ends in (its other "
            "mode commands lead to no one mode): declare leads_to=OIMode.SAFE, say, if it "
            "ends there"
        )
    if decl.leads_to in visits:
        return (
            f"passes_through={said} names {decl.leads_to.label}, the mode it leads to "
            "(leads_to=): passes_through= names only the modes it leaves again"
        )
    if decl.leads_to not in reached:
        return (
            f"passes_through={said}, leads_to={decl.leads_to.label}, but none of its sends= "
            f"leads to {decl.leads_to.label}: add the mode command that takes it there"
        )
    return None


def _mode_first_problem(decl: Declaration) -> str | None:
    """What is wrong with ``decl``'s ``mode_first=True``, or None: it sends a mode command
    (one that could come first), says the mode its mode commands end in where they lead to
    several (else ``send()`` refuses each), and each of its other commands is taken in one
    of the modes its mode commands lead to (else it can never be sent where it was judged)."""
    if not decl.mode_first:
        return None
    leads = {COMMANDS[op].leads_to for op in decl.sends if op in COMMANDS} - {None}
    if not leads:
        return (
            "mode_first=True, but none of its sends= is a mode command (safe (131), full "
            "(132), ...) to come first: add the one it sends first, or drop mode_first="
        )
    if decl.leads_to is None and len(leads) > 1:
        return (
            "mode_first=True, and no leads_to= says the mode it ends in (its mode commands "
            "lead to several): declare leads_to=OIMode.SAFE, say, and passes_through= the "
            "modes it leaves again"
        )
    for op in decl.sends:
        spec = COMMANDS.get(op)
        if spec is None or spec.leads_to is not None or leads & spec.modes:
            continue
        modes = ", ".join(sorted(m.label for m in leads if m is not None))
        return (
            f"mode_first=True, but {spec.name} ({op}) is accepted in none of the modes its "
            f"mode commands lead to ({modes}): it could only be refused after them"
        )
    return None


def _kind_problem(kind: str, cls: type) -> str | None:
    """What is wrong with declaring ``cls`` as ``kind``, or None: a condition is a
    :class:`Condition` and an action an :class:`Action`. The validator believes ``kind``
    (only conditions in a guard, only actions may send), and the runtime the class (an
    Action's halt, a Condition's short tick): a class of the other kind would pass both and
    run as neither."""
    kinds = {
        "condition": (Condition, "a condition", "its check() says whether it holds"),
        "action": (Action, "an action", "its update() returns a Status"),
    }
    if kind not in kinds or issubclass(cls, kinds[kind][0]):
        return None
    base, a_kind, its_method = kinds[kind]
    other_kind = "action" if kind == "condition" else "condition"
    other = kinds[other_kind][0]
    derives = other.__name__ if issubclass(cls, other) else "neither Action nor Condition"
    return (
        f"kind={kind!r}, but {cls.__qualname__} derives from {derives}: {a_kind} derives from "
        f"roomba_bt.behaviours.{base.__name__} ({its_method}); declare kind={other_kind!r} or "
        f"derive it from {base.__name__}"
    )


def _key_param_problem(decl: Declaration) -> str | None:
    """What is wrong with the parameters ``writes_keys`` and ``reads_keys`` name, or None:
    each a declared ``STR`` parameter (the key's name is a text), each type a ValueType,
    each typed parameter one of them. ``primary=`` was checked and these were not: a key
    parameter misspelt, or an ``INT`` one, loaded, and the validator's key checks passed
    the behaviour by without a word."""
    for role in ("writes_keys", "reads_keys"):
        for pname in getattr(decl, role):
            param = decl.param(pname)
            if param is None:
                declared = ", ".join(p.name for p in decl.params) or "none"
                return (
                    f"{role} names {pname!r}, which is not a declared parameter (declared: "
                    f"{declared}); declare the parameter that names the key: "
                    f"Param({pname!r}, STR, from_blackboard=False)"
                )
            if param.type.name != "str":
                return (
                    f"{role} names {pname!r}, a parameter of type {param.type.name}: the parameter "
                    f"names the key, so it is a text, Param({pname!r}, STR, "
                    f"from_blackboard=False); the type of the value is the key's: "
                    f"{role}={{{pname!r}: {param.type.name.upper()}}}"
                )
    keyed = {*decl.writes_keys, *decl.reads_keys}
    typed: dict[str, object] = {}
    for pname, vtype in decl.key_types:
        if typed.setdefault(pname, vtype) != vtype:
            return (
                f"{pname!r} names a key it reads and writes, typed differently in "
                "writes_keys and reads_keys: one key holds one type"
            )
        if pname not in keyed:
            return f"key type given for {pname!r}, which neither writes_keys nor reads_keys names"
        if not isinstance(vtype, ValueType):
            known = ", ".join(t.name.upper() for t in VALUE_TYPES.values())
            return (
                f"the type given for the key {pname!r} names is {vtype!r}: a key's type is a "
                f"ValueType of roomba_bt.behaviours.units ({known})"
            )
    return None


def key_role(decl: Declaration, pname: str) -> str | None:
    """``"writes"`` or ``"reads"`` where ``pname`` names a key ``decl`` writes or reads
    (``writes_keys``, ``reads_keys``), else None."""
    if pname in decl.writes_keys:
        return "writes"
    return "reads" if pname in decl.reads_keys else None


def key_not_read(decl: Declaration, pname: str) -> str:
    """Why the key parameter ``pname`` of ``decl`` takes no ``@key``, said after the refusal
    (the compiler's at the mission's file:line:col, :meth:`Declaration.checked`'s for a tree
    built in Python), naming the plugin it comes from."""
    role = key_role(decl, pname)
    plugin = "" if decl.origin == "builtin" else f" (plugin {decl.origin})"
    return (
        f": {pname} names the key {decl.name}{plugin} {role}, which is checked before the "
        "run (declared, of its type, written before it is read); a name read from the "
        f"blackboard would skip those checks: write the key's name ({pname}: my_key)"
    )


def _is_blackboard_value(value: object) -> bool:
    """``value`` a :class:`BlackboardRef`, or a text ``"@..."`` as YAML writes one."""
    return isinstance(value, BlackboardRef) or (isinstance(value, str) and value.startswith("@"))


def key_roles(
    keys: tuple[str, ...] | Mapping[str, ValueType],
) -> tuple[tuple[str, ...], tuple[tuple[str, ValueType], ...]]:
    """``writes_keys=`` / ``reads_keys=`` as ``@declare`` takes them, parameter names alone
    (untyped, as before) or a mapping of each to the type of its key's value, as the
    names and the typed ones of a :class:`Declaration`."""
    if isinstance(keys, Mapping):
        return tuple(keys), tuple(keys.items())
    return tuple(keys), ()


def _type_hint(given: object) -> str:
    """What to write instead of a parameter type that is no :class:`ValueType`, where the
    mistake says it: the type's name as a text (``"speed"``), Python's own type (``int``), a
    tuple of words meant as a choice. A stranger's plugin wrote ``Param("velocity",
    "speed")`` and was told only the list of types."""
    name = given.__name__ if isinstance(given, type) else given
    if isinstance(name, str) and name.strip().lower() in VALUE_TYPES:
        word = name.strip().upper()
        what = f"Python's {name}" if isinstance(given, type) else f"the text {given!r}"
        return f": {what} is not one; write {word} (from roomba_bt.behaviours import {word})"
    if isinstance(given, (tuple, list)) and given and all(isinstance(w, str) for w in given):
        words = ", ".join(repr(w) for w in given)
        return f": a choice of words is enum({words}) (from roomba_bt.behaviours import enum)"
    return ""


def _param_problem(p: object) -> str | None:
    """What is wrong with one declared parameter, or None: its name, type, bounds (plain
    numbers in the type's unit, the lower first), and its default (of the type, within the
    bounds, and none when it is required). A bound given as text ("0 mm/s") passed here and
    broke ``roomba-bt behaviours`` and ``schema`` for every plugin with a traceback."""
    if not isinstance(p, Param):
        return f"params must be Param(...) objects, got {p!r}"
    if not isinstance(p.type, ValueType):
        known = ", ".join(t.name.upper() for t in VALUE_TYPES.values())
        return (
            f"parameter {p.name!r}: type must be a ValueType of roomba_bt.behaviours.units "
            f"({known}), got {p.type!r}{_type_hint(p.type)}"
        )
    if not (isinstance(p.name, str) and _NAME.match(p.name)):
        return f"parameter name {p.name!r} is not snake_case ([a-z][a-z0-9_]*)"
    if p.type is VALUE_TYPES["mark"]:  # a mark is the odometry the `mark` action keeps
        return (
            f"parameter {p.name!r}: type MARK has no written form, so no mission can give "
            "it a value (the `mark` action writes one to a key): a parameter that names a "
            f"mark key is Param({p.name!r}, STR, from_blackboard=False), the key typed with "
            f"reads_keys={{{p.name!r}: MARK}} (odometry's since) or writes_keys={{{p.name!r}: "
            "MARK}"
        )
    unit = p.type.unit or "the type's unit"
    for which, bound in (("minimum", p.minimum), ("maximum", p.maximum)):
        if bound is not None and not _is_number(bound):
            return (
                f"parameter {p.name!r}: {which} must be a plain number in {unit}, got "
                f"{bound!r} (e.g. {which}=0)"
            )
    if p.minimum is not None and p.maximum is not None and p.minimum > p.maximum:
        return f"parameter {p.name!r}: minimum {p.minimum:g} is above maximum {p.maximum:g}"
    if p.default is None or isinstance(p.default, BlackboardRef):
        return None
    if p.required:
        return f"parameter {p.name!r}: required and given a default: a required one has none"
    try:
        value = p.type.parse(p.default)
    except UnitError as exc:
        return f"default of {p.name!r}: {exc}"
    out_of_range = p.check_range(value)
    return f"default of {p.name!r}: {out_of_range}" if out_of_range else None


def _is_number(value: object) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value)


B = TypeVar("B", bound="type[RobotBehaviour]")


def mode_after_sending(
    sends: tuple[int, ...], passes_through: tuple[OIMode, ...] = ()
) -> OIMode | None:
    """The OI mode after the commands of ``sends``, from the opcode table's ``leads_to``:
    the one mode they lead to, besides those it only ``passes_through`` (Full, for an action
    that sends Full, drives and sends Safe: it leads to Safe); None when none of them
    changes the mode, or when they lead to several (a behaviour that sends Safe or Full by a
    parameter says which with a function of its parameters)."""
    after = {COMMANDS[op].leads_to for op in sends if op in COMMANDS} - {None}
    after -= set(passes_through)
    return after.pop() if len(after) == 1 else None


def _accepted_in(opcodes: tuple[int, ...]) -> frozenset[OIMode]:
    modes = ALL_MODES
    for opcode in opcodes:
        modes = modes & COMMANDS[opcode].modes
    return modes


# Long on purpose: one keyword per field of Declaration, each said in the docstring; split,
# a plugin author would read two places to learn one decorator.
def declare(
    name: str,
    *,
    kind: Kind,
    params: tuple[Param, ...] = (),
    reads: tuple[int, ...] | PacketsOf = (),
    sends: tuple[int, ...] = (),
    leads_to: OIMode | ModeOf | None = None,
    passes_through: OIMode | tuple[OIMode, ...] = (),
    mode_first: bool = False,
    primary: str | None = None,
    writes_keys: tuple[str, ...] | Mapping[str, ValueType] = (),
    reads_keys: tuple[str, ...] | Mapping[str, ValueType] = (),
    constraints: Callable[[Mapping[str, Any]], list[str]] | None = None,
    halts_only: bool = False,
    compares: ComparesOf | None = None,
    sends_by: Callable[[Mapping[str, Any]], tuple[int, ...]] | None = None,
    at_once: bool = False,
    may_succeed: Callable[[Mapping[str, Any]], bool] | None = None,
    never_fails: bool = False,
    needs: Callable[[Mapping[str, Any], RobotProfile], str | None] | None = None,
    needs_only_warns: bool = False,
    in_passive: Callable[[Mapping[str, Any]], str | None] | None = None,
    stops_only: Callable[[Mapping[str, Any]], bool] | None = None,
) -> Callable[[B], B]:
    """Class decorator: attach the :class:`Declaration` as ``cls.declaration``; the doc is
    the class docstring's first paragraph. ``leads_to`` defaults to what the opcode table
    says of the commands in ``sends`` (:func:`mode_after_sending`): Spot (134) leads to
    Passive, so ``spot`` need not say it. ``passes_through`` names the modes (one, or a
    tuple) its own mode commands take the robot to on the way to the one it leads to (an
    action that sends Full, drives, then sends Safe passes through Full and leads to Safe):
    ``send()`` refused its Full where ``leads_to=OIMode.SAFE`` was all it could say.
    ``mode_first=True`` says that each time it starts its first command is one of its mode
    commands (Safe, Full): validate then lets it be reached in Passive (it was refused there
    for its drive, which its own Safe came before), and ``send()`` refuses another first.
    ``halts_only=True`` says that its wheel commands only stop the wheels (``stop``): the
    Full-mode warning passes it by. ``at_once=True``
    says that it returns SUCCESS on the tick it starts, every time in the modes its commands
    are taken in (the static checks rely on it: a test ticks every built-in that says so;
    the robot's own fall to Passive is beyond them, and ``motors`` there fails at once:
    ``Action.send_going``). ``may_succeed`` says, of the
    parameters, whether it can succeed by itself at all (a ``drive`` with no end cannot);
    ``never_fails=True`` that it never ends in FAILURE (``wait``, ``log``).
    ``writes_keys`` / ``reads_keys`` name the ``STR`` parameters that name blackboard keys
    it writes / reads, alone or with the type of the value (``writes_keys={"key": INT}``):
    validate holds a typed one to the key's declaration in the mission. ``needs`` says,
    of the parameters and the chosen robot profile, why that robot cannot do it, or None
    (a warning, not an error, with ``needs_only_warns=True``). ``in_passive`` says, of the
    parameters, what the leaf does in Passive that the mission may not mean, or None:
    validate warns where it may be reached in Passive. ``stops_only`` says, of the
    parameters, whether it only stops what Passive has stopped already (the wheels, the
    motors), sending nothing there (``Action.stopped_already``): validate accepts it in
    Passive where no built-in cycle the tree started may drive."""
    visits = (passes_through,) if isinstance(passes_through, OIMode) else tuple(passes_through)
    after = mode_after_sending(sends, visits) if leads_to is None else leads_to
    writes, written_types = key_roles(writes_keys)
    reads_named, read_types = key_roles(reads_keys)

    def attach(cls: B) -> B:
        doc = " ".join((class_doc(cls) or "").strip().split("\n\n")[0].split())
        cls.declaration = Declaration(
            name, kind, cls, params, reads, sends, after, doc, primary,
            constraints=constraints, writes_keys=writes, reads_keys=reads_named,
            key_types=(*written_types, *read_types), halts_only=halts_only,
            compares=compares, sends_by=sends_by, at_once=at_once, may_succeed=may_succeed,
            never_fails=never_fails, needs=needs, needs_only_warns=needs_only_warns,
            in_passive=in_passive, stops_only=stops_only, passes_through=visits,
            mode_first=mode_first,
        )  # fmt: skip
        return cls

    return attach


def declare_like(
    parent: type,
    name: str,
    *,
    add_params: tuple[Param, ...] = (),
    drop_params: tuple[str, ...] = (),
    add_reads: tuple[int, ...] = (),
    add_sends: tuple[int, ...] = (),
    add_constraints: Callable[[Mapping[str, Any]], list[str]] | None = None,
    writes_keys: tuple[str, ...] | Mapping[str, ValueType] = (),
    reads_keys: tuple[str, ...] | Mapping[str, ValueType] = (),
    primary: str | None = None,
    at_once: bool = False,
    may_succeed: Callable[[Mapping[str, Any]], bool] | None = None,
) -> Callable[[B], B]:
    """Class decorator: declare a subclass of a declared behaviour (a built-in's, such as
    ``WallFollow``) as ``name``, the parent's declaration carried over and changed where
    said. A copy by hand (``params=WallFollow.declaration.params``) dropped what it did not
    copy without a word (``constraints=``: the front_clear / front_threshold check), and
    ``(*WallFollow.declaration.reads, ...)`` failed ``mypy --strict`` (``reads`` may be a
    function of the parameters).

    Carried: the kind; the parameters (without ``drop_params``, then ``add_params``, one of
    a parent's name in its place); the packets read (``add_reads`` after, a function's too),
    the commands sent (``add_sends`` after), ``leads_to``, ``passes_through``, ``mode_first``,
    ``sends_by``, ``compares``, ``halts_only``, ``needs``; the rules (``add_constraints`` too:
    both run, a dropped parameter not given to the parent's); the key parameters still
    declared (and ``writes_keys`` / ``reads_keys``); ``primary`` unless dropped or given.
    Not carried: ``at_once`` and ``may_succeed``, which say when ``update`` succeeds, what
    a subclass changes (the parent's "only with a ``duration``" would say a ``distance``
    subclass never succeeds); the doc, the subclass's docstring. For more: :func:`declare`."""
    base = getattr(parent, "declaration", None)
    if not isinstance(base, Declaration):
        raise DeclarationError(
            f"declare_like({getattr(parent, '__qualname__', parent)!r}, {name!r}): the parent "
            "is no declared behaviour (a class decorated with @declare)"
        )
    params = _extended_params(base, name, add_params, drop_params)
    names = {p.name for p in params if isinstance(p, Param)}
    writes, written_types = key_roles(writes_keys)
    reads_named, read_types = key_roles(reads_keys)
    key_types = (*base.key_types, *written_types, *read_types)
    changes: dict[str, Any] = {
        "name": name, "params": params, "origin": "builtin",
        "reads": _more_packets(base.reads, add_reads),
        "sends": (*base.sends, *(op for op in add_sends if op not in base.sends)),
        "primary": primary or (base.primary if base.primary in names else None),
        "constraints": _both(base.constraints, add_constraints),
        "writes_keys": (*(k for k in base.writes_keys if k in names), *writes),
        "reads_keys": (*(k for k in base.reads_keys if k in names), *reads_named),
        "key_types": tuple((k, t) for k, t in key_types if k in names),
        "at_once": at_once, "may_succeed": may_succeed,
    }  # fmt: skip

    def attach(cls: B) -> B:
        doc = " ".join((class_doc(cls) or "").strip().split("\n\n")[0].split())
        cls.declaration = replace(base, cls=cls, doc=doc, **changes)
        return cls

    return attach


def _extended_params(
    base: Declaration, name: str, add_params: tuple[Param, ...], drop_params: tuple[str, ...]
) -> tuple[Param, ...]:
    """The parameters of ``base`` without ``drop_params``, then ``add_params``: an added one
    of a parent's name takes its place, the others follow. A dropped name ``base`` does not
    declare is a :class:`DeclarationError` (a typo would keep the parameter silently)."""
    unknown = [p for p in drop_params if base.param(p) is None]
    if unknown:
        declared = ", ".join(p.name for p in base.params) or "none"
        raise DeclarationError(
            f"declare_like({base.name!r}, {name!r}): drop_params names {unknown}, which "
            f"{base.name} does not declare (it declares: {declared})"
        )
    replacing = {p.name: p for p in add_params if isinstance(p, Param)}
    kept = tuple(replacing.get(p.name, p) for p in base.params if p.name not in drop_params)
    return (*kept, *(p for p in add_params if p not in kept))


def _more_packets(
    reads: tuple[int, ...] | PacketsOf, more: tuple[int, ...]
) -> tuple[int, ...] | PacketsOf:
    """A parent's packets read and ``more`` after them (each once)."""
    if not more:
        return reads
    if not callable(reads):
        return (*reads, *(pid for pid in more if pid not in reads))
    of = reads

    def packets(params: Mapping[str, Any]) -> tuple[int, ...]:
        got = of(params)
        return (*got, *(pid for pid in more if pid not in got))

    return packets


def _both(
    first: Callable[[Mapping[str, Any]], list[str]] | None,
    then: Callable[[Mapping[str, Any]], list[str]] | None,
) -> Callable[[Mapping[str, Any]], list[str]] | None:
    """The cross-parameter rules of a parent and of its subclass, both run."""
    if first is None or then is None:
        return first or then
    parent, own = first, then
    return lambda params: [*parent(params), *own(params)]


def class_doc(cls: type) -> str | None:
    """``cls.__doc__``, or under ``python -OO`` (which drops docstrings) the docstring read
    from the class's source with :mod:`ast`: the descriptions in ``roomba-bt behaviours``, the
    JSON Schema and ``show`` are the docstrings, and a user's interpreter flags should not
    empty them. None when neither has one (no docstring, or no source file)."""
    if cls.__doc__ is not None or sys.flags.optimize < 2:
        return cls.__doc__
    import ast  # only under -OO
    import inspect
    import textwrap

    try:
        tree = ast.parse(textwrap.dedent(inspect.getsource(cls)))
    except (OSError, TypeError, SyntaxError):
        return None
    node = tree.body[0] if tree.body else None
    return ast.get_docstring(node) if isinstance(node, ast.ClassDef) else None


#: said after a speed below :data:`SLOWEST_MOVING_SPEED_MM_S` where that is the minimum
STANDS_STILL = (
    f" (a wheel asked for less than {SLOWEST_MOVING_SPEED_MM_S} mm/s stands still: "
    f"the speed controller turns it in steps of about {WHEEL_SPEED_STEP_MM_S} mm/s)"
)


def moving_minimum(share: float = 1.0) -> int:
    """The smallest speed (whole mm/s) whose ``share`` still turns a wheel: the speed
    controller's nearest step of anything slower is 0 (:data:`SLOWEST_MOVING_SPEED_MM_S`), and
    a leaf waiting for a wheel that stands still waits for ever."""
    return math.ceil(SLOWEST_MOVING_SPEED_MM_S / share)


# Here, beside Param, not in driving.py: driving.py is below the leaves' base module (which
# uses its helpers), and this module is above it.
#: A share of a speed parameter that a leaf sends to a wheel that must turn: the share and
#: when ("on the inside of its orbit round the force field"). See :func:`wheel_speed_param`.
SpeedShare = tuple[float, str]


def wheel_speed_param(
    name: str,
    default: str,
    *,
    minimum: float,
    doc: str = "",
    shares: tuple[SpeedShare, ...] = (),
) -> Param:
    """A forward wheel-speed parameter (a ``speed``, mm/s): from ``minimum`` up to what one
    wheel of Drive Direct takes (:data:`WHEEL`). A minimum that does not move a wheel is a
    declaration's mistake (its leaf would hang): refused when the behaviour is declared.

    ``shares``: each fixed share of the speed the leaf sends to a wheel that must turn (a
    turn in place's slow phase, a straight move at a share, an arc's inner wheel). The
    minimum is raised to what turns the slowest of them (:func:`moving_minimum`), and a
    value below it is refused when the mission is compiled, saying which wheel would stand
    still: ``dock_approach`` took ``speed: 30 mm/s``, and backed toward the beams' band at
    36% of it, 10.8 mm/s, a wheel that never turned, until the stage's time limit."""
    if minimum < SLOWEST_MOVING_SPEED_MM_S:
        raise ValueError(
            f"{name}: minimum {minimum:g} mm/s does not move a wheel (the speed controller "
            f"steps of {WHEEL_SPEED_STEP_MM_S} mm/s round it to 0): at least "
            f"{SLOWEST_MOVING_SPEED_MM_S} (moving_minimum())"
        )
    why = STANDS_STILL if minimum == SLOWEST_MOVING_SPEED_MM_S else ""
    if shares:
        share, when = min(shares)
        needed = moving_minimum(share)
        if needed > minimum:
            minimum = needed
            why = (
                f" (it sends a wheel {share:.0%} of {name} {when}: below {needed} mm/s that "
                f"is less than {SLOWEST_MOVING_SPEED_MM_S} mm/s, and the wheel stands still, "
                f"the speed controller turning it in steps of about {WHEEL_SPEED_STEP_MM_S} mm/s)"
            )
    return Param(
        name, SPEED, default=default, minimum=minimum, maximum=WHEEL.maximum, doc=doc,
        minimum_why=why,
    )  # fmt: skip
