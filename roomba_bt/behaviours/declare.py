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
"""

from __future__ import annotations

import logging
import math
import operator
import re
import sys
import uuid
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any, Literal, TypeVar

import py_trees

from roomba_bt.behaviours.lean import (
    DirectLeaf,
    InvalidStatus,
    Selector,
    Sequence,
    behaviour_tick,
    checked_status,
)
from roomba_bt.behaviours.units import (
    MARK,
    SPEED,
    VALUE_TYPES,
    UnitError,
    ValueType,
    closest,
    held,
)
from roomba_bt.oi.encode import Command, halt, motors_off, turns_wheels
from roomba_bt.oi.frames import CHARGING_SOURCES_PACKETS, SensorFrame
from roomba_bt.oi.modes import ALL_MODES, DRIVING_MODES, OIMode
from roomba_bt.oi.opcodes import COMMANDS, COMMANDS_BY_NAME, Effect
from roomba_bt.oi.packets import PACKETS
from roomba_bt.printable import CONTROL
from roomba_bt.robot.interface import ModeChange, Odometry, RobotHandle, Snapshot
from roomba_bt.yamlsource import character_name, quoted

#: what a behaviour's own mistakes that the runtime mended are said on (as the mission's)
_log = logging.getLogger("roomba_bt.mission")

#: The blackboard key the runtime mirrors the snapshot under (for plugins that prefer it).
SNAPSHOT_KEY = "/roomba/snapshot"
#: The declared type of each mission key, by name (:func:`declare_keys`): not a key of its own.
KEY_TYPES_KEY = "/roomba/key_types"
#: Mission blackboard keys live under this namespace: ``leg`` is ``/mission/leg``.
MISSION_NAMESPACE = "/mission/"

Kind = Literal["action", "condition"]
_NAME = re.compile(r"^[a-z][a-z0-9_]*$")
_BUILTIN_CYCLE = Effect.BUILTIN_CYCLE  # read once: send() asks on every command
_SILENCES = Effect.SILENCES
_SEEK_DOCK = COMMANDS_BY_NAME["seek_dock"]


class DeclarationError(ValueError):
    """A behaviour that declares itself wrongly (a plugin author's mistake)."""


class ParamError(TypeError, ValueError):
    """A leaf built in Python with a parameter its declaration does not have, a value its
    type cannot read, one out of range, or a required one missing: refused when the leaf is
    built, not at its first tick with the robot in Safe. A TypeError, as an unknown keyword
    argument is, and a ValueError, as a bad value is: either ``except`` catches it."""


class CheckedParams(dict[str, Any]):
    """Parameters the mission compiler has checked and parsed (each problem said at its
    file:line:col): a leaf built with them takes them as they are, with no second check."""


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

    def check_range(self, value: Any) -> str | None:
        """An error message if ``value`` is outside the range, else None."""
        if not isinstance(value, int | float) or isinstance(value, bool):
            return None
        lo, hi = self.minimum, self.maximum
        if (lo is not None and value < lo) or (hi is not None and value > hi):
            unit = f" {self.type.unit}" if self.type.unit else ""
            shown = f"{value:g}{unit}"
            return f"{self.name} {shown} is out of range: allowed {_bound(lo)}..{_bound(hi)}{unit}"
        return None

    def describe(self) -> str:
        parts = [self.type.describe()]
        if self.minimum is not None or self.maximum is not None:
            parts.append(f"{_bound(self.minimum)}..{_bound(self.maximum)}")
        if self.required:
            parts.append("required")
        elif self.default is not None:
            parts.append(f"default {self.default}")
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


#: ``@key`` or ``@key.field``: a value read from the blackboard, in YAML and from Python
BLACKBOARD_REF = re.compile(r"^@([a-z_][a-z0-9_]*)(?:\.([a-z_][a-z0-9_]*))?$")


def blackboard_ref(text: str) -> BlackboardRef:
    """``"@leg"`` -> ``BlackboardRef("leg")``; raises :class:`UnitError` for a text that is
    not one (``@Leg``, ``@a.b.c``)."""
    match = BLACKBOARD_REF.match(text)
    if match is None:
        raise UnitError(f"{text!r} is not a blackboard reference (@key or @key.field)")
    return BlackboardRef(*match.groups())


@dataclass(frozen=True, slots=True)
class BlackboardRef:
    """A parameter value read from the blackboard when the behaviour starts: ``@leg`` or
    ``@waypoint.x`` (a field of a record)."""

    key: str
    field: str | None = None

    def __str__(self) -> str:
        return f"@{self.key}" + (f".{self.field}" if self.field else "")


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
    #: its wheel commands only stop the wheels (``stop``: Drive 0), so it turns none
    halts_only: bool = False
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
        return any(COMMANDS[op].effect is _BUILTIN_CYCLE for op in self.sends)

    def packets(self, params: Mapping[str, Any]) -> tuple[int, ...]:
        return self.reads(params) if callable(self.reads) else self.reads

    def mode_after(self, params: Mapping[str, Any]) -> OIMode | None:
        return self.leads_to(params) if callable(self.leads_to) else self.leads_to

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
        if self.kind == "condition" and self.sends:
            raise DeclarationError(
                f"a condition only reads: it sends nothing (sends={self.sends!r}); a behaviour "
                "that sends commands is kind='action'"
            )
        if self.primary is not None and self.primary not in seen:
            raise DeclarationError(f"primary parameter {self.primary!r} is not declared")
        problem = self.cls.declaration_problem(self)
        if problem is not None:
            raise DeclarationError(problem)


def _kind_problem(kind: str, cls: type) -> str | None:
    """What is wrong with declaring ``cls`` as ``kind``, or None: a condition is a
    :class:`Condition` and an action an :class:`Action`. The validator believes ``kind``
    (only conditions in a guard, only actions may send), and the runtime the class (an
    Action's halt, a Condition's short tick): a class of the other kind passed both and ran
    as neither (session 27)."""
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
            f"({known}), got {p.type!r}"
        )
    if not (isinstance(p.name, str) and _NAME.match(p.name)):
        return f"parameter name {p.name!r} is not snake_case ([a-z][a-z0-9_]*)"
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


def mode_after_sending(sends: tuple[int, ...]) -> OIMode | None:
    """The OI mode after the commands of ``sends``, from the opcode table's ``leads_to``:
    the one mode they lead to; None when none of them changes the mode, or when they lead to
    several (a behaviour that sends Safe or Full by a parameter says which with a function
    of its parameters)."""
    after = {COMMANDS[op].leads_to for op in sends if op in COMMANDS} - {None}
    return after.pop() if len(after) == 1 else None


def _accepted_in(opcodes: tuple[int, ...]) -> frozenset[OIMode]:
    modes = ALL_MODES
    for opcode in opcodes:
        modes = modes & COMMANDS[opcode].modes
    return modes


def declare(
    name: str,
    *,
    kind: Kind,
    params: tuple[Param, ...] = (),
    reads: tuple[int, ...] | PacketsOf = (),
    sends: tuple[int, ...] = (),
    leads_to: OIMode | ModeOf | None = None,
    primary: str | None = None,
    writes_keys: tuple[str, ...] = (),
    reads_keys: tuple[str, ...] = (),
    constraints: Callable[[Mapping[str, Any]], list[str]] | None = None,
    halts_only: bool = False,
    compares: ComparesOf | None = None,
    sends_by: Callable[[Mapping[str, Any]], tuple[int, ...]] | None = None,
    at_once: bool = False,
    may_succeed: Callable[[Mapping[str, Any]], bool] | None = None,
) -> Callable[[B], B]:
    """Class decorator: attach the :class:`Declaration` as ``cls.declaration``; the doc is
    the class docstring's first paragraph. ``leads_to`` defaults to what the opcode table
    says of the commands in ``sends`` (:func:`mode_after_sending`): Spot (134) leads to
    Passive, so ``spot`` need not say it. ``halts_only=True`` says that its wheel commands
    only stop the wheels (``stop``): the Full-mode warning passes it by. ``at_once=True``
    says that it returns SUCCESS on the tick it starts, every time (the static checks rely
    on it: a test ticks every built-in that says so). ``may_succeed`` says, of the
    parameters, whether it can succeed by itself at all (a ``drive`` with no end cannot)."""
    after = mode_after_sending(sends) if leads_to is None else leads_to

    def attach(cls: B) -> B:
        doc = " ".join((class_doc(cls) or "").strip().split("\n\n")[0].split())
        cls.declaration = Declaration(
            name, kind, cls, params, reads, sends, after, doc, primary,
            constraints=constraints, writes_keys=writes_keys, reads_keys=reads_keys,
            halts_only=halts_only, compares=compares, sends_by=sends_by, at_once=at_once,
            may_succeed=may_succeed,
        )  # fmt: skip
        return cls

    return attach


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
                f"send() takes a Command from roomba_bt.oi.commands (such as "
                f"commands.drive(200, 32767)), not {type(command).__name__} {command!r:.60}"
            )
        spec = command.spec
        if spec.opcode not in self.declaration.sends:  # the compile-time checks read sends=
            raise UndeclaredCommand(self, command)
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

    #: whether the last wheel command it sent set them turning (:meth:`send` notes it)
    _started_motion = False
    #: whether it sent a built-in cycle (Clean, Spot, Max, Seek Dock) not yet ended by it
    _started_cycle = False

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

    def initialise(self) -> None:
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
        self.start()

    def start(self) -> None:
        """Called once each time the behaviour starts (after ``@key`` values are read)."""


class UnwrittenKey(LookupError):
    """A behaviour started with a parameter ``@key`` whose key nothing had written. A
    mission's validator proves every read comes after a write; a tree built in Python has
    no such proof, and None read as a drive's distance would drive without one."""


class KeyRange(ValueError):
    """A behaviour started with a parameter ``@key`` whose key holds a value out of the
    parameter's declared range (written by a plugin, which the validator cannot see; it
    checks ``initial`` and ``set`` values and ``for_each`` items). It would otherwise
    reach the robot, or a command's encoder, as the behaviour's own bug."""

    def __init__(self, node: RobotBehaviour, pname: str, ref: BlackboardRef, problem: str):
        self.node, self.param, self.ref = node, pname, ref
        super().__init__(
            f"{node.declaration.name} {node.name!r}: {pname} is {ref}, and blackboard key "
            f"{str(ref)[1:]!r} holds a value out of its range: {problem}"
        )


def read_key(key: str) -> Any:
    """A mission blackboard key's value (None if never written)."""
    storage = py_trees.blackboard.Blackboard.storage
    return storage.get(MISSION_NAMESPACE + key)


#: the id the mission's own writes (``set``, ``mark``, ``for_each``, initial values) carry in
#: py_trees' activity stream
_MISSION_WRITER = uuid.uuid4()


#: the name write_key gives the mission's own writes in py_trees' activity stream
_MISSION_WRITER_NAME = "roomba-bt mission"


def declare_keys(types: Mapping[str, ValueType]) -> None:
    """The mission's keys and their declared types (``blackboard:``), which
    :func:`write_key` holds every write to from now on; they replace those declared before
    (``declare_keys({})``: none). ``CompiledMission.setup`` calls it before each run. Kept
    on py_trees' blackboard (:data:`KEY_TYPES_KEY`), with the values: its ``clear()``, which
    a test calls between missions, forgets them too."""
    storage = py_trees.blackboard.Blackboard.storage
    if types:
        storage[KEY_TYPES_KEY] = dict(types)
    else:
        storage.pop(KEY_TYPES_KEY, None)


class KeyType(TypeError):
    """A value written to a mission key (a plugin's ``write_key``) that is not of the
    key's declared type in its canonical unit: ``"fast"`` in a speed, ``1`` in a bool. The
    readers take the type for granted; said where it is written, it is not blamed on the
    leaf that reads it later."""

    def __init__(self, key: str, vtype: ValueType, value: Any, problem: str, writer: str):
        self.key, self.type, self.value = key, vtype, value
        by = "" if writer == _MISSION_WRITER_NAME else f" by {writer!r}"
        super().__init__(
            f"write_key({key!r}, {quoted(value)}){by}: blackboard key {key!r} is declared "
            f"{vtype.describe()}: {problem}"
        )


def _write_problem(vtype: ValueType, value: Any) -> str | None:
    if vtype is not MARK:
        return held(vtype, value)
    if isinstance(value, Odometry):  # a mark's form is the robot's, not a written one
        return None
    return f"expected an odometry mark (snapshot.odometry), got a {type(value).__name__}"


def write_key(key: str, value: Any, writer: str = _MISSION_WRITER_NAME) -> None:
    """Write a mission key. Into the store directly (no py_trees client per node: a client
    registers each key it may touch and checks it on every access), and, when py_trees'
    activity stream is on (``Blackboard.enable_activity_stream()``), said there as a client's
    write would be: a py_trees user's tools show ``/mission/leg`` changing. A key the
    mission declared (:func:`declare_keys`) takes only a value of its type: else
    :class:`KeyType`, and nothing is written."""
    blackboard = py_trees.blackboard.Blackboard
    types = blackboard.storage.get(KEY_TYPES_KEY)
    vtype = types.get(key) if types is not None else None
    if vtype is not None:
        problem = _write_problem(vtype, value)
        if problem is not None:
            raise KeyType(key, vtype, value, problem, writer)
    name = MISSION_NAMESPACE + key
    stream = blackboard.activity_stream
    if stream is not None:
        had = name in blackboard.storage
        kind = py_trees.blackboard.ActivityType
        stream.push(
            py_trees.blackboard.ActivityItem(
                key=name,
                client_name=writer,
                client_id=_MISSION_WRITER,
                # its value, as py_trees' own clients push it (its display compares with it)
                activity_type=(kind.WRITE if had else kind.INITIALISED).value,
                previous_value=blackboard.storage.get(name) if had else None,
                current_value=value,
            )
        )
    blackboard.storage[name] = value


#: One wheel's speed as Drive Direct takes it, mm/s (-500..500, from the opcode table): the
#: bound of every wheel-speed parameter and of what a driving action sends.
WHEEL = COMMANDS_BY_NAME["drive_direct"].args[0]


def wheel_speed_param(name: str, default: str, *, minimum: float, doc: str = "") -> Param:
    """A forward wheel-speed parameter (a ``speed``, mm/s): from ``minimum`` up to what one
    wheel of Drive Direct takes (:data:`WHEEL`)."""
    return Param(name, SPEED, default=default, minimum=minimum, maximum=WHEEL.maximum, doc=doc)


#: What to do when Safe was refused on a powered charger: the user's two ways out, the
#: second by the name the shipped missions use (missions/lib/undock.yaml)
CHARGER_ADVICE = (
    "Safe mode on a powered dock drops to Passive at once: start the robot off the dock, or "
    "begin the mission with the `undock` subtree (`subtree: {id: undock}`, from "
    "`include: [roomba-bt:lib/undock.yaml]`), which backs off the dock in Full first, as "
    "missions/clean.yaml does"
)


def left_driving_message(change: ModeChange | None, waited: str = "") -> str:
    """The failure message of a leaf whose robot left Safe/Full by itself: the cause, and,
    when the cause is the charger refusing a Safe just sent (the robot started on its
    dock), what to do about it; the bare "(charger)" left an owner guessing."""
    cause = f" ({change.cause})" if change is not None else ""
    message = f"the robot left Safe/Full mode{cause}{waited}"
    if change is not None and change.refused_on_charger:
        message += f"; {CHARGER_ADVICE}"
    return message


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
        """Out of Safe/Full, where the mode model would refuse a drive command: RUNNING
        while it waits for them, FAILURE once :meth:`stranded` (``grace``) after it began
        to move."""
        stranded = self.stranded(grace) if self._started_motion else None
        if stranded is not None:
            self._started_motion = False
            self.feedback_message = stranded
            return _FAILURE
        return _RUNNING

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
        override it without calling ``super().terminate()``: the halt was skipped, and the
        robot drove on after the leaf had ended, with no leaf in charge of it (session 27: at
        200 mm/s through a whole ``wait: 5s``, and the bump reflex sent the dead action's
        drive again). Every stop of a leaf comes here: py_trees' ticks and the lean ones
        (:mod:`~roomba_bt.behaviours.lean`), the composites' and decorators' stops of their
        children, and the run's end (:func:`~roomba_bt.runtime.teardown.stop_nodes`)."""
        self._terminated = False
        super().stop(new_status)
        if self._started_motion or (self._started_cycle and new_status is not _SUCCESS):
            self._end_what_terminate_left(new_status)

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


def on_home_base(frame: SensorFrame) -> bool:
    """Whether ``frame`` carries packet 34 and it shows the home base's power."""
    return all(pid in frame for pid in CHARGING_SOURCES_PACKETS) and (
        frame.charging_sources.home_base
    )


def cycle_may_run(robot: RobotHandle) -> bool:
    """Whether a built-in cycle may still be driving the robot: one was written and nothing
    has ended it since (:attr:`Snapshot.cycle_may_run
    <roomba_bt.robot.interface.Snapshot.cycle_may_run>`), the robot is in Passive, and it is
    not a Seek Dock on its home base (docked: that cycle ended there). Any other cycle on the
    home base may be about to drive off it (Clean sent on the dock); ending it there is
    harmless, as Safe on a powered dock drops to Passive at once."""
    snap = robot.snapshot
    if not snap.cycle_may_run or snap.mode is not OIMode.PASSIVE:
        return False
    cycle = robot.outbox.last_on("wheels")
    return cycle is None or cycle.spec is not _SEEK_DOCK or not on_home_base(snap.frame)


_RUNNING, _SUCCESS, _FAILURE = (
    py_trees.common.Status.RUNNING, py_trees.common.Status.SUCCESS, py_trees.common.Status.FAILURE
)  # fmt: skip
_DEBUG = py_trees.logging.Level.DEBUG


class Condition(RobotBehaviour):
    """A condition: SUCCESS or FAILURE from this tick's frame, never RUNNING."""

    #: True on a class whose ``check`` reads nothing but its own parameters and, from
    #: ``snapshot.frame``, the packets it declares: its result is then a function of those
    #: packets' values (see :class:`FrameInputs`). Said by the class that defines ``check``:
    #: a subclass with a ``check`` of its own is not taken to be pure unless it says so too.
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
#: terminate and stop (:meth:`FrameInputs.usable` compares the six at once)
_SHORT_LIFECYCLE = (
    _CONDITION_UPDATE, _CONDITION_INITIALISE, _CONDITION_START, _CONDITION_TERMINATE,
    _CONDITION_STOP,
)  # fmt: skip


class FrameInputs:
    """What decides the statuses of a subtree of frame-pure conditions: the values of the
    packets its leaves read, in this tick's frame.

    Such a subtree is :class:`Condition` leaves (of ``frame_pure`` classes, without ``@key``
    parameters) under py_trees' sequences and selectors (the lean ones, exactly: no subclass
    with steps of its own). Ticked on the same values as last time, from the statuses that
    tick left, it ends with the same statuses: each leaf's status is a function of the
    values, a composite's of its children's, and its lifecycle calls (the leaves'
    ``terminate`` and ``initialise``, the composites') do nothing. So the ``while``/``until``
    guard, which re-ticks its condition every frame, may leave it as it is while
    :meth:`unchanged` holds for the values :meth:`values` gave after its last tick.

    Everything is looked up once, here and when a stream's layout is first seen: the slots
    of the packets in the frame's values (one ``itemgetter`` reads them all, one tuple
    comparison compares them), the lifecycle each class must still have, and each leaf's
    ``__dict__``, where what is patched into one node (the monitor forces a condition by
    giving it an ``update`` of its own) is found by name. (Reading a node's ``__dict__``
    makes CPython 3.11 keep a dictionary for it, which slows every later read of its
    attributes a little; these leaves are ticked only when their packets change.)
    """

    __slots__ = ("_classes", "_layout", "_nodes", "_packets", "_read", "_robot")

    def __init__(self, leaves: list[Condition]) -> None:
        #: per class, its pure check and the lifecycle of the short tick: a patch differs
        self._classes = [
            (cls, (cls._pure_check, *_SHORT_LIFECYCLE))
            for cls in {type(leaf): None for leaf in leaves}
        ]
        #: the leaves' own attributes (the dictionary is the node's for good once read)
        self._nodes = [vars(leaf) for leaf in leaves]
        self._packets = tuple(
            sorted({pid for leaf in leaves for pid in leaf.declaration.packets(leaf.params)})
        )
        self._robot: RobotHandle = leaves[0].robot  # type: ignore[assignment]
        self._layout: object = None
        self._read: Callable[[tuple[int, ...]], object] | None = None

    @classmethod
    def of(cls, root: py_trees.behaviour.Behaviour) -> FrameInputs | None:
        """The inputs of the subtree at ``root``, or None when it is not made only of
        frame-pure conditions (or has no robot yet)."""
        leaves: list[Condition] = []
        if not _collect_pure(root, leaves) or not leaves:
            return None
        robot = leaves[0].robot
        if robot is None or any(leaf.robot is not robot for leaf in leaves):
            return None
        return cls(leaves)

    def values(self) -> object:
        """The values of the subtree's packets in this tick's frame (None: the frame lacks
        one of them; the subtree's own tick then says so). A layout not seen before has
        its slots looked up (the same for every frame of a stream)."""
        frame = self._robot.snapshot.frame
        layout = frame.layout
        if layout is not self._layout:
            try:
                slots = [layout.index[pid] for pid in self._packets]
            except KeyError:
                return None
            self._layout, self._read = layout, operator.itemgetter(*slots)
        assert self._read is not None
        return self._read(frame.values)

    def unchanged(self, values: object) -> bool:
        """This tick's frame has ``values`` at the slots last read, and the subtree's tick
        would still be the pure one (:meth:`usable`)."""
        frame = self._robot.snapshot.frame
        read = self._read
        # the frame's fields, not its properties (two Python calls a guard a tick)
        if frame.layout is not self._layout or read is None or read(frame.values) != values:
            return False
        return self.usable()

    def usable(self) -> bool:
        """Nothing has been patched in since (a class's lifecycle or ``check``, a node's own
        ``update`` as the monitor forces one, or ``check``), the leaves still have this robot,
        and debug logging (which a tick would write to) is off."""
        if py_trees.logging.level is _DEBUG:
            return False
        for cls, lifecycle in self._classes:
            if (
                cls.check, cls.update, cls.initialise, cls.start, cls.terminate, cls.stop
            ) != lifecycle:  # fmt: skip
                return False
        robot = self._robot
        for node in self._nodes:
            if "update" in node or "check" in node or node.get("robot") is not robot:
                return False
        return True


def _collect_pure(node: py_trees.behaviour.Behaviour, leaves: list[Condition]) -> bool:
    """Add the leaves under ``node`` to ``leaves``; False if one of the nodes is not a
    frame-pure condition nor a lean sequence or selector."""
    if type(node) in (Sequence, Selector):
        return all(_collect_pure(child, leaves) for child in node.children)
    if not isinstance(node, Condition):
        return False
    cls = type(node)
    pure = cls.frame_pure and cls._pure_check is not None and cls.check is cls._pure_check
    if not pure or any(isinstance(v, BlackboardRef) for v in node.params.values()):
        return False
    leaves.append(node)
    return True
