"""Static checks over the whole tree, before anything moves.

* **Modes.** Each actuator leaf (Drive 137, Motors 138, LEDs 139, Play 141, ...) is accepted
  only in Safe or Full (the opcode table's ``modes``). Starting from Passive (the runtime's
  Start 128), the set of modes the robot may be in is carried through the tree: a sequence
  threads it child to child; a fallback hands each alternative the modes its predecessor may
  have *failed* in; a parallel branch also sees the modes its sibling branches may set; loops
  (retry, repeat, for_each, reactive composites) iterate to a fixed point; a preempting
  decorator (timeout, while/until) may end its child anywhere. An actuator reached with any
  mode outside its allowed set is an error: some path lacks the mode change. A leaf that
  only stops what Passive has stopped (``stop``, ``motors`` off: the declaration's
  ``stops_only``) is allowed in Passive too, where it sends nothing, but not in the Passive
  of a built-in cycle the tree started (Clean, Spot, Max, Seek Dock: :class:`Cycle`), which
  its refused Drive 0 cannot stop.
  (At run time the mode model guards every command again: a cliff in Safe drops the robot
  to Passive whatever this proof said.)
* **Blackboard.** Every key read (``@key`` values, ``check``, ``odometry.since``) must be
  written on every path before it: by an ``initial`` value, a ``set``/``mark`` earlier in a
  sequence, or the ``for_each`` that owns it. Fallback alternatives and parallel branches
  guarantee only what all of them write. A parallel ticks its branches in order, so a
  branch that succeeds on the tick it starts (``set``) has written its keys before the
  branches after it start: they may read them (not the branches before it).
* **Limits a reactive parent resets.** A reactive fallback re-ticks its children from the
  first on every tick: a child that failed while a later one runs starts again, fresh, on the
  next tick. A time limit (``timeout``, ``dock_time_limit``) or a ``retry`` in such a child
  would never end anything (it fails, and its count or clock starts over for ever), so it is
  an error unless it sits in the last child, whose failure fails the parent, or every child
  after it ends on the tick it starts (``stop``, a condition): then the parent ends too.
* **Bandwidth.** The packets the leaves read, plus the runtime's own
  (:data:`RUNTIME_PACKETS`), must fit one 15 ms stream frame at the chosen baud.
* **Blind in Full (a warning).** In Full mode the robot's firmware does not stop at a cliff
  or a wheel drop (it does in Safe, by falling to Passive). A leaf that turns the wheels and
  can run in Full, with no cliff sensor read on every tick it runs with a result that ends
  it (by itself, a guard around it, an earlier child of a reactive parent, a parallel branch
  ticked on every tick: :mod:`roomba_bt.mission.ticks`), drives down the stairs if it meets
  them: compiled, with a warning (:func:`blind_in_full`). A leaf that sends Full itself
  (its own ``sends``, by the opcode table's ``leads_to``) and a wheel command is such a
  leaf in whatever mode it is entered.
* **Two wheel branches (a warning).** Two branches of a ``parallel`` with a leaf that turns
  the wheels: the robot gets the last wheel command of a tick only (:func:`parallel_wheels`).
* **Two writers of a key (a warning).** Two branches of a ``parallel`` writing the same
  blackboard key (``set``, ``mark``, a plugin's key, a ``for_each``): the last write of a
  tick wins (:func:`parallel_keys`).
* **A parallel's restarted branches.** Not synchronised (``synchronise: false``, policies
  ``all`` and ``selected``: the options its word's ``Combines`` names) a branch that
  succeeded is ticked again and starts over: one that can succeed and would start an
  action or a clock again is an error when another branch the parallel waits for may
  still be RUNNING on the tick it succeeds (beside conditions alone the parallel ends on
  that tick: :func:`restarted_branches`).
* **A reactive sequence's restarts (a warning).** A child that is not the last and may be
  RUNNING starts again after it succeeded, stopping a later running child each time
  (:func:`restarted_runs`).
* **Commands the robot has.** Each leaf whose declared ``sends`` include a command the chosen
  profile lacks (Reset 7 and Stop 173 on the Roomba 500) is an error at that leaf; one the
  profile has but whose firmware does not honour it (Digit LEDs Raw 163: the 600 spec says
  it does not work on current Create 2 and Roomba 500/600 firmware) is a warning: it is
  still sent (:func:`profile_commands`). A leaf that needs what the model lacks (``display``
  on a Create 2, which has no display: the declaration's ``needs``) is an error too; one whose
  leaf runs all the same (``button: minute`` on a Create 2 reads a bit always 0 there:
  ``needs_only_warns``) a warning.
* **What Passive adds (a warning).** A leaf that does more in Passive than its bytes say
  (``press: clean`` starts the robot's own cleaning cycle: the declaration's ``in_passive``)
  reachable in Passive by the mode pass (:func:`in_passive`).
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping
from enum import Enum
from typing import Any

from roomba_bt.behaviours.blackboard import BlackboardRef
from roomba_bt.behaviours.conditions import comparison_problem
from roomba_bt.behaviours.declare import Declaration, Param
from roomba_bt.behaviours.language import ALL, FAILURE, SELECTED, SUCCESS, WORDS, Outcomes
from roomba_bt.mission.diagnostics import Diagnostic
from roomba_bt.mission.plan import KeyDecl, Node, is_own_key, said_key, written_ref
from roomba_bt.mission.source import Loc
from roomba_bt.mission.ticks import (
    OBSTACLES,
    answers,
    at_once,
    combines,
    every_tick,
    goes_on,
    needs,
    never_succeeds,
    packet_tests,
    reactive,
    reads_cliffs,
    runs_again,
    succeeds_at_once,
    synchronised,
    waited_for,
    watched_children,
)
from roomba_bt.mission.wording import PYTHON, Wording
from roomba_bt.oi.errors import BandwidthError
from roomba_bt.oi.frames import (
    CHARGING_SOURCES_PACKETS,
    ENCODER_PACKETS,
    HAZARD_PACKETS,
)
from roomba_bt.oi.modes import DRIVING_MODES, OI_MODE_PACKET, OIMode
from roomba_bt.oi.opcodes import COMMANDS, Effect, opcodes
from roomba_bt.oi.profiles import DEFAULT_PROFILE, PASSIVE_SLEEP_S, SEND_BAUD, RobotProfile
from roomba_bt.oi.stream import check_bandwidth

#: Packets the runtime always streams, whatever the mission reads: bumps and wheel drops (7),
#: the four cliffs (9-12) for its safety stop, charging sources (34), OI mode (35) for the
#: mode model, and the encoders (43, 44) for odometry. The runtime and the validator both
#: use this one constant. (The runtime adds battery charge and capacity, 25 and 26, for its
#: summary, only when they fit the baud rate's budget.)
RUNTIME_PACKETS: tuple[int, ...] = (
    *HAZARD_PACKETS,
    *CHARGING_SOURCES_PACKETS,
    OI_MODE_PACKET,
    *ENCODER_PACKETS,
)
assert RUNTIME_PACKETS == (7, 9, 10, 11, 12, 34, 35, 43, 44)


class Cycle(Enum):
    """The mode pass's one state beside the four OI modes: Passive while a built-in cycle
    the tree started (Clean, Spot, Max, Seek Dock) may still drive the robot. A leaf that
    is taken in Passive is taken there too; ``stop`` (and ``motors`` off) is taken in
    Passive without it, where the OI stopped the wheels and motors already and it sends
    nothing, but not with it: Drive 0 is refused in Passive and cannot stop the cycle
    (``Action.stopped_already``). A mode command ends the cycle: ``mode: safe`` (Safe),
    ``mode: passive`` (its leaf ends a cycle it finds), as does the failure of the leaf
    that started it."""

    DRIVING = "Passive, a built-in cycle driving"


#: a mode the robot may be in, as the mode pass carries it
Mode = OIMode | Cycle
Modes = frozenset[Mode]
_EMPTY: Modes = frozenset()
_CYCLE_DRIVING: Modes = frozenset({Cycle.DRIVING})
#: where a leaf taken in Passive is taken: the Passive of a cycle is Passive too
_PASSIVE_STATES: Modes = frozenset({OIMode.PASSIVE, Cycle.DRIVING})


def _label(modes: frozenset[OIMode]) -> str:
    return " or ".join(m.label for m in sorted(modes))


#: The opcodes that end the run when the tree sends them (Reset 7, Stop 173: the opcode
#: table's :attr:`~roomba_bt.oi.opcodes.Effect.SILENCES`).
SILENCING = frozenset(op for op, spec in COMMANDS.items() if spec.effect is Effect.SILENCES)

#: what makes a stored song sound (a ``song`` alone only stores its notes)
(PLAY,) = opcodes("play")

#: Why nothing may follow a leaf that sends Reset or Stop (the validator's error,
#: docs/runtime.md); ``{end_in_stop}``: how the caller ends in Off (:attr:`Wording.end_in_stop`)
ENDS_THE_RUN = (
    "which end the run: the OI is off and streams no more sensor frames, and the frames are "
    "the run's clock (the runtime ends the run at once when the tree sends either). A leaf "
    "that sends Reset or Stop must be the last one the tree runs; to leave the robot in Off "
    "at the end of any mission, use {end_in_stop} instead"
)


class ModeCheck:
    """The static mode pass; ``errors`` after :meth:`run`. ``wording``: how the caller ends a
    mission in Off, which the error of a leaf after a Reset or Stop offers instead (a Python
    program was told of ``--end-in stop``, a flag it cannot give)."""

    def __init__(self, wording: Wording = PYTHON) -> None:
        self.wording = wording
        self.errors: list[Diagnostic] = []
        self._reported: set[int] = set()
        #: the leaves that send Reset (7) or Stop (173), in the order reached
        self.silencers: list[Node] = []
        #: the leaves that start a built-in cycle (Clean, Spot, Max, Seek Dock), in that order
        self.cycle_starters: list[Node] = []
        #: each leaf reached, and every mode it may be entered in
        self.entered: dict[int, tuple[Node, Modes]] = {}

    def run(self, root: Node, start: Modes = frozenset({OIMode.PASSIVE})) -> None:
        self.visit(root, start)

    def visit(self, node: Node, entry: Modes) -> tuple[Modes, Modes]:
        """(modes on SUCCESS, modes on FAILURE) after ``node`` entered in ``entry``."""
        if not entry:
            return _EMPTY, _EMPTY
        handler = _MODE_HANDLERS.get(node.kind)
        if handler is None:  # a word: a composite as it combines its children, or a decorator
            combination = combines(node)
            if combination is None:
                handler = ModeCheck._decorator
            else:
                handler = _COMPOSITE_HANDLERS[combination.goes_on]
        return handler(self, node, entry)

    def _leaf(self, node: Node, entry: Modes) -> tuple[Modes, Modes]:
        """A leaf fails in the modes it was entered in; one that starts a built-in cycle
        (``seek_dock: {timeout: ...}``) may fail after it sent it, and its failure ends the
        cycle in Passive (Start): a ``drive`` on its fallback needs a ``mode: safe`` first.
        One that passes through modes on its way (``passes_through=``: Full, then Safe) may
        fail in those too, or in the mode it leads to, once it got there."""
        decl = node.decl
        assert decl is not None
        self._entered(node, decl, entry)
        entry = entry - {OIMode.OFF}  # told once (_entered): what follows is judged without it
        if SILENCING.intersection(decl.sent(node.params)):
            # whatever else it sends, the run ends once it sent Reset or Stop: a leaf after
            # it is entered in Off, and told so (_entered)
            self.silencers.append(node)
            return frozenset({OIMode.OFF}), entry
        if decl.starts_cycle:  # its cycle drives on after its SUCCESS; its failure ends it
            self.cycle_starters.append(node)
            return _CYCLE_DRIVING, entry | {OIMode.PASSIVE}
        after = decl.mode_after(node.params)
        return (frozenset({after}) if after is not None else entry), entry | _visited(decl, after)

    def _unbuilt(self, node: Node, entry: Modes) -> tuple[Modes, Modes]:
        """A node that could not be built: a behaviour whose parameters were wrong is judged
        where it is reached (what it sends does not depend on them), and the modes go on
        past it when the mode it leads to does not depend on them either; after a ``mode``
        whose mode did not parse nothing is judged (which mode would follow is not known).
        A node not parsed at all (an unknown word) is passed over, as if it were not there."""
        decl = node.partial
        if decl is None:
            return entry, entry
        if callable(decl.leads_to):
            return _EMPTY, _EMPTY
        self._entered(node, decl, entry)
        if decl.starts_cycle:
            return _CYCLE_DRIVING, entry | {OIMode.PASSIVE}
        after = decl.leads_to
        return (frozenset({after}) if after is not None else entry), entry | _visited(decl, after)

    def _entered(self, node: Node, decl: Declaration, entry: Modes) -> None:
        """``node`` (of behaviour ``decl``) reached in ``entry``: an error, once, if one of
        those modes refuses a command it sends."""
        seen = self.entered.get(id(node))
        self.entered[id(node)] = (node, entry if seen is None else seen[1] | entry)
        if OIMode.OFF in entry:
            if id(node) not in self._reported:
                self._reported.add(id(node))
                self.errors.append(node.loc.at(self._after_the_end(decl)))
            return
        allowed = self._taken_in(node, decl)
        bad = entry - allowed
        if bad and id(node) not in self._reported:
            self._reported.add(id(node))
            if bad == _CYCLE_DRIVING and OIMode.PASSIVE in allowed:  # a stop, a cycle on
                self.errors.append(node.loc.at(self._in_a_cycle(decl)))
                return
            # the Passive of a cycle refuses it as plain Passive does: said as Passive
            said = frozenset(m if isinstance(m, OIMode) else OIMode.PASSIVE for m in bad)
            sent = decl.sent_first(node.params)
            refused = [COMMANDS[op] for op in sent if said - COMMANDS[op].modes]
            sends = ", ".join(f"{c.title} ({c.opcode})" for c in refused)
            taken = decl.reached_in(node.params)
            self.errors.append(
                node.loc.at(
                    f"{decl.name} sends {sends}, accepted only in {_label(taken)} mode, "
                    f"but it can be reached in {_label(said)} mode: put a mode change (mode: "
                    f"safe or mode: full) before it on every path{_own_mode_first(decl, said)}"
                )
            )

    @staticmethod
    def _taken_in(node: Node, decl: Declaration) -> Modes:
        """The modes ``node`` may be entered in: those that take every command it sends
        with its parameters, the Passive of a cycle with Passive, and plain Passive too for
        a leaf that only stops what Passive has stopped (``stop``: its ``stops_only``); not
        one whose parameters did not parse (``node.decl`` None): what it asks is not known."""
        allowed: Modes = decl.reached_in(node.params)
        if OIMode.PASSIVE in allowed:
            return allowed | _CYCLE_DRIVING
        if node.decl is not None and decl.stops_only is not None and decl.stops_only(node.params):
            return allowed | {OIMode.PASSIVE}
        return allowed

    def _in_a_cycle(self, decl: Declaration) -> str:
        """The error of a ``stop`` (a ``stops_only`` leaf) the tree may reach in Passive
        while a cycle it started may drive, naming the leaves that start one."""
        starters = ", ".join(
            dict.fromkeys(f"{s.name} (line {s.loc.line})" for s in self.cycle_starters)
        )
        return (
            f"{decl.name} can be reached in Passive while a built-in cycle started by "
            f"{starters or 'a leaf'} may still drive the robot: it sends nothing there, and "
            "the cycle drives on (Drive and Motors are refused in Passive); put mode: safe "
            "before it (Safe ends the cycle), or mode: passive (it ends the cycle too)"
        )

    def _after_the_end(self, decl: Declaration) -> str:
        """The error of a leaf the tree may run after a leaf that sends Reset or Stop,
        naming those leaves (where they are)."""
        senders = ", ".join(dict.fromkeys(f"{s.name} (line {s.loc.line})" for s in self.silencers))
        return (
            f"{decl.name} can run after {senders or 'a leaf'} sent Reset (7) or Stop (173), "
            f"{ENDS_THE_RUN.format(end_in_stop=self.wording.end_in_stop)}"
        )

    def _chain(self, node: Node, entry: Modes, *, on_success: bool) -> tuple[Modes, Modes]:
        """Children in order: a sequence goes on after a success, a selector after a
        failure, so each child starts in the modes the previous one ended in that way."""

        def once(start: Modes) -> tuple[Modes, Modes, Modes]:
            current, stopped, seen = start, _EMPTY, start
            for child in node.children:
                ok, ko = self.visit(child, current)
                go_on, stop = (ok, ko) if on_success else (ko, ok)
                stopped |= stop
                seen |= ok | ko
                current = go_on
            return current, stopped, seen

        finished, stopped, seen = once(entry)
        if not node.options.get("memory", True):  # reactive: earlier children run again
            finished, stopped, _ = once(entry | seen)
        return (finished, stopped) if on_success else (stopped, finished)

    def _sequence(self, node: Node, entry: Modes) -> tuple[Modes, Modes]:
        return self._chain(node, entry, on_success=True)

    def _selector(self, node: Node, entry: Modes) -> tuple[Modes, Modes]:
        return self._chain(node, entry, on_success=False)

    def _parallel(self, node: Node, entry: Modes) -> tuple[Modes, Modes]:
        produced = entry
        for child in node.children:
            ok, ko = self.visit(child, entry)
            produced |= ok | ko
        success, failure = _EMPTY, _EMPTY
        for child in node.children:
            ok, ko = self.visit(child, produced)
            success |= ok
            failure |= ko
        return success | failure, failure | success

    def _loop(self, node: Node, entry: Modes, again_on: Outcomes) -> tuple[Modes, Modes]:
        """A decorator that starts its child again after the endings ``again_on``: the
        child starts in the modes it ended in that way too, until they settle."""
        child = node.children[0]
        current = entry
        for _ in range(4):
            ok, ko = self.visit(child, current)
            again = entry | (ok if SUCCESS in again_on else _EMPTY)
            again |= ko if FAILURE in again_on else _EMPTY
            if again == current:
                break
            current = again
        return ok, ko

    def _decorator(self, node: Node, entry: Modes) -> tuple[Modes, Modes]:
        """A guard, or a decorator judged by its declared answers: each answer holds the
        modes of the child's endings it answers; a limit's failure can come anywhere in its
        child; an answer given without ticking the child, in the modes it was entered in."""
        if node.kind == "guard":
            self.visit(node.children[0], entry)
            ok, ko = self.visit(node.children[1], entry)
            anywhere = entry | ok | ko | _leads_to_within(node.children[1])
            return (ok | anywhere, ko) if node.options["until"] else (ok, ko | anywhere)
        decorator = answers(node)
        assert decorator is not None, f"{node.kind} is neither a decorator nor handled"
        again_on = decorator.restarts_on
        if again_on:
            ok, ko = self._loop(node, entry, again_on)
        else:
            ok, ko = self.visit(node.children[0], entry)
        ended = {SUCCESS: ok, FAILURE: ko}
        success = _EMPTY.union(*(m for e, m in ended.items() if SUCCESS in decorator.answer(e)))
        failure = _EMPTY.union(*(m for e, m in ended.items() if FAILURE in decorator.answer(e)))
        if decorator.limit and FAILURE in decorator.while_running:  # timeout: the child halted
            failure |= ok | ko | entry | _leads_to_within(node.children[0])
        if decorator.replays or SUCCESS in decorator.alone:
            success |= entry
        if decorator.replays or FAILURE in decorator.alone:
            failure |= entry
        return success, failure


_ModeHandler = Callable[[ModeCheck, Node, Modes], tuple[Modes, Modes]]

#: The mode pass's handler of the node kinds that are not words; a composite is handled as
#: its word combines its children (:data:`_COMPOSITE_HANDLERS`), every other kind is a
#: decorator. Tables, not ``getattr(self, f"_{kind}")``: that built a new name string per
#: node visited, and the interpreter's method cache (keyed by the string's address) kept up
#: to thousands of them, so memory grew over a long run of compiles.
_MODE_HANDLERS: dict[str, _ModeHandler] = {
    "leaf": ModeCheck._leaf,
    "unbuilt": ModeCheck._unbuilt,
}

#: A composite's handler by :attr:`Combines.goes_on
#: <roomba_bt.behaviours.language.Combines.goes_on>`: in turn after a success (a
#: sequence), after a failure (a fallback), or every child on every tick (a parallel).
_COMPOSITE_HANDLERS: dict[str | None, _ModeHandler] = {
    SUCCESS: ModeCheck._sequence,
    FAILURE: ModeCheck._selector,
    None: ModeCheck._parallel,
}


def _leads_to_within(node: Node) -> Modes:
    """The modes the leaves under ``node`` may leave the robot in, where a limit halts
    them anywhere: those they lead to, and those they pass through (``passes_through=``)."""
    out: set[OIMode] = set()
    for n in node.walk():
        if n.decl is not None:
            after = n.decl.mode_after(n.params)
            if after is not None:
                out.add(after)
            out.update(n.decl.passes_through)
    return frozenset(out)


def _own_mode_first(decl: Declaration, refused_in: Modes) -> str:
    """The error's word to a plugin leaf that sends a mode command of its own that is taken
    in ``refused_in``, where the check could not know it comes first: ``mode_first=True``
    says it (held to at ``send()``); "" for a built-in, or a leaf that says it already."""
    if decl.origin == "builtin" or decl.mode_first:
        return ""
    own = [
        COMMANDS[op]
        for op in decl.sends
        if COMMANDS[op].leads_to in DRIVING_MODES and not refused_in - COMMANDS[op].modes
    ]
    if not own:
        return ""
    names = " or ".join(f"{c.title} ({c.opcode})" for c in own)
    return (
        f"; or, if {decl.name} sends its own {names} before any other command each time it "
        "starts, say so in its @declare with mode_first=True (held to when it runs)"
    )


def _visited(decl: Declaration, after: OIMode | None) -> Modes:
    """The modes a leaf that passes through some (``passes_through=``) may fail in besides
    those it was entered in: those, and the one it leads to (``after``), once there; a
    ``mode_first`` leaf's, in the one its first command took it to too. Empty for every
    other leaf: it fails where it was entered."""
    if decl.mode_first and after is not None:
        return frozenset({after, *decl.passes_through})
    if not decl.passes_through:
        return _EMPTY
    return frozenset(decl.passes_through) | (frozenset({after}) if after is not None else _EMPTY)


class KeyCheck:
    """The static read-before-write pass over blackboard keys."""

    def __init__(self, passed: Mapping[int, Node] | None = None) -> None:
        self.errors: list[Diagnostic] = []
        self._reported: set[tuple[int, str]] = set()
        #: of a check of one body's own keys (``OwnKeys.checked``): each leaf of a body it
        #: uses, by id, with the use in the judged body it is reached through, where a read
        #: of a key passed down there is said (:meth:`_unwritten`)
        self._passed: Mapping[int, Node] = passed or {}
        #: the keys judged (a subtree's own at one use, in its body and where a body it uses
        #: was given one by name: ``OwnKeys.checked``); None: every key but a use's own,
        #: which its body alone judges (nothing outside it reads or writes them)
        self._judged: frozenset[str] | None = None

    def run(
        self, root: Node, initial: frozenset[str], judged: frozenset[str] | None = None
    ) -> None:
        """Unless a node that could not be built may have written a key it does not name (a
        ``for_each`` not parsed, a behaviour whose key did not resolve): its readers are
        judged in the pass after it is fixed, not said unwritten because of it. One that
        names its key (a ``set`` whose value alone is wrong) is taken to write it there, as
        it will once fixed: the other keys' readers are judged now (a read-before-write
        error showed only after the type errors beside it were fixed)."""
        if any(_may_write(node) for node in root.walk()):
            return
        self._judged = judged
        self.visit(root, initial)

    def _judges(self, key: str) -> bool:
        return not is_own_key(key) if self._judged is None else key in self._judged

    def _unwritten(self, node: Node, key: str, loc: Loc) -> Diagnostic:
        """``node`` reads ``key`` (at ``loc``) before anything writes it. Said at the read;
        or, a key passed down by name to a body the judged one uses (``self._passed``), at
        that use in the judged body, naming the read: the body that passes it is the one
        to fix (write it before the use, or give it an initial value), and the read's line
        alone, in a subtree that has no such key, did not say which use passed it."""
        fix = "give it an initial value under blackboard:, or write it first (set, mark, for_each)"
        use = self._passed.get(id(node))
        if use is None or use.use_loc is None:
            return loc.at(
                f"{node.name} reads blackboard key {said_key(key)} before anything writes it "
                f"on some path: {fix}"
            )
        return use.use_loc.at(
            f"subtree {use.use} reads blackboard key {said_key(key)} before anything writes "
            f"it on some path (passed down to {node.name} at {loc.said_from(use.use_loc)}): "
            f"{fix}"
        )

    def visit(self, node: Node, written: frozenset[str]) -> frozenset[str]:
        """Keys certainly written after ``node`` succeeds."""
        kind = node.kind
        if kind == "unbuilt":  # writes only the keys it names (run); its reads are not known
            return written | frozenset(node.params.values())
        if kind == "leaf":
            for key, loc in node.keys_read():
                if key in written or not self._judges(key):
                    continue
                if (id(node), key) not in self._reported:
                    self._reported.add((id(node), key))
                    self.errors.append(self._unwritten(node, key, loc))
            return written | frozenset(node.keys_written())
        order = goes_on(node)
        if order == SUCCESS:  # a sequence
            current = written
            for child in node.children:
                current = self.visit(child, current)
            return current
        if order == FAILURE:  # a fallback
            outs = [self.visit(child, written) for child in node.children]
            return frozenset.intersection(*outs) if outs else written
        if every_tick(node):  # a parallel
            outs, current = [], written
            for child in node.children:  # in order: a set before a reader has written
                outs.append(self.visit(child, current))
                current = outs[-1] if succeeds_at_once(child) else current
            if needs(node) == ALL:
                return frozenset().union(*outs)
            return frozenset.intersection(*outs) if outs else written
        if kind == "guard":
            self.visit(node.children[0], written)
            inner = self.visit(node.children[1], written)
            return written if node.options["until"] else inner
        word = WORDS[kind]
        if word.writes_key is not None:  # for_each: written for its child, and after it
            key = node.options[word.writes_key]
            self.visit(node.children[0], written | {key})
            return written | ({key} if node.options.get("items") else set())
        inner = self.visit(node.children[0], written)
        decorator = word.answers
        assert decorator is not None, f"{kind} is neither a decorator nor handled"
        # what the child wrote holds when the decorator succeeds only on its child's success
        # (not an inverter's, force_success's, or a oneshot's answer given again)
        only_after = decorator.on_failure | decorator.while_running | decorator.alone
        if SUCCESS in decorator.on_success and SUCCESS not in only_after and not decorator.replays:
            return inner
        return written


def _may_write(node: Node) -> bool:
    """Whether ``node`` could not be built and may have written a blackboard key it does
    not name (its key parameters that resolved are its ``params``)."""
    if node.kind != "unbuilt":
        return False
    return node.partial is None or len(node.params) < len(node.partial.writes_keys)


#: a parameter reading a key as ``@key``: the behaviour's name, the parameter, the reference,
#: and where it is written
_Reader = tuple[str, Param, BlackboardRef, Loc]
#: a value the mission writes to a key: what writes it, the value, where it is written (a
#: list parameter's item: in the default), and what the message adds after the key (the
#: ``for_each`` such an item is given to)
_Write = tuple[str, Any, Loc, str]


def key_ranges(root: Node, keys: Mapping[str, KeyDecl]) -> list[Diagnostic]:
    """Each ``initial`` value, ``set`` value and ``for_each`` item (the mission's constants
    written to a key) checked against the range of every parameter that reads the key as
    ``@key``: 900 mm/s in a key a drive reads was the drive's EncodeError at run time, blamed
    on the built-in. Said where the value is written, naming the reader and where it reads
    it. (A plugin's write is held to the key's type by ``write_key``, and to the range by
    the reader when it starts.)"""
    readers, writes = _ranged_key_uses(root)
    out: list[Diagnostic] = []
    for key, reads in readers.items():
        declared = keys.get(key)
        written = list(writes.get(key, ()))
        if declared is not None and declared.has_initial:
            where = declared.initial_loc or declared.loc
            written.insert(0, ("initial value", declared.initial, where, ""))
        for what, value, where, note in written:
            for behaviour, param, ref, use in reads:
                read = value.get(ref.field) if ref.field and isinstance(value, dict) else value
                problem = None if ref.field and read is value else param.check_range(read)
                if problem is None:
                    continue
                at = use.said_from(where)
                out.append(
                    where.at(
                        f"{what} of blackboard key {said_key(key)}{note}: {behaviour}'s "
                        f"{param.name} reads it as {written_ref(ref)} (at {at}): {problem}"
                    )
                )
    return out


def _ranged_key_uses(root: Node) -> tuple[dict[str, list[_Reader]], dict[str, list[_Write]]]:
    """The parameters with a declared range that read a key as ``@key``, and the values the
    mission writes itself (``set`` leaves, ``for_each`` items), with where each is written,
    by key."""
    readers: dict[str, list[_Reader]] = {}
    writes: dict[str, list[_Write]] = {}
    for node in root.walk():
        decl = node.decl
        if node.kind == "for_each":
            items, locs = node.options.get("items", ()), node.options.get("loc:items", ())
            notes = node.options.get("said:items", ())
            writes.setdefault(node.options["key"], []).extend(
                ("for_each item", *written) for written in zip(items, locs, notes, strict=True)
            )
        if node.kind != "leaf" or decl is None:
            continue
        for pname, value in node.params.items():
            param = decl.param(pname)
            if (
                isinstance(value, BlackboardRef)
                and param is not None
                and (param.minimum is not None or param.maximum is not None)
            ):
                use = node.options.get(f"loc:{pname}", node.loc)
                readers.setdefault(value.key, []).append((decl.name, param, value, use))
        key = node.params.get("key")
        if decl.name == "set" and isinstance(key, str):
            where = node.options.get("loc:value", node.loc)
            writes.setdefault(key, []).append(("set value", node.params.get("value"), where, ""))
    return readers, writes


#: Leaves that fail when their time is up (the ``timeout`` decorator is the other limit).
TIME_LIMIT_LEAVES = frozenset({"dock_time_limit"})


def _limits(node: Node) -> list[Node]:
    """The time limits and retries in ``node``'s subtree."""
    return [
        n
        for n in node.walk()
        if ((decorator := answers(n)) is not None and decorator.limit)
        or (n.declared is not None and n.declared.name in TIME_LIMIT_LEAVES)
    ]


def _runs_on_after(children: list[Node]) -> bool:
    """Whether the reactive fallback may still run after its child before ``children``
    fails: the next that ends at once with a failure hands on, one that succeeds at once
    ends the fallback, one that may be RUNNING keeps it running (and it is ticked again)."""
    for child in children:
        if succeeds_at_once(child):
            return False
        if not at_once(child):
            return True
    return False


def _line_of(loc: Loc, said_at: Loc) -> str:
    """``loc`` named in a message said at ``said_at``: ``line 7``, with its file when that
    is another (a subtree of an included file)."""
    return f"line {loc.line}" if loc.file == said_at.file else f"{loc.file}:{loc.line}"


def restarted_limits(root: Node) -> list[Diagnostic]:
    """A limit under a reactive fallback's non-last child: its failure lets a later child
    run, and the next tick starts it again with a fresh clock or count. Not when every
    child after it ends on the tick it starts (``stop``, a condition): the fallback ends
    then, and the limit did end it."""
    errors = []
    for node in root.walk():
        if goes_on(node) != FAILURE or not reactive(node):  # not a reactive fallback
            continue
        for index, child in enumerate(node.children[:-1]):
            if not _runs_on_after(node.children[index + 1 :]):
                continue
            for limit in _limits(child):
                word = limit.declared.name if limit.declared is not None else limit.kind
                where = _line_of(limit.loc, child.loc)
                errors.append(
                    child.loc.at(
                        f"{word} ({where}) is under {node.kind} ({node.loc.line}:"
                        f"{node.loc.column}), which starts it again on the next tick when it "
                        f"fails and a later child runs: it would never end the mission; put "
                        f"what it limits under a sequence or fallback with memory, or make it "
                        "the last child"
                    )
                )
    return errors


#: the policies that wait for more than one success, where being synchronised counts
_WAITING_POLICIES = frozenset({ALL, SELECTED})


def _still_running(parallel: Node, index: int) -> list[Node]:
    """The branches, other than the one at ``index``, that may still be RUNNING on the tick
    it succeeds and so keep the parallel running into the next tick, where it starts over.

    The parallel ends on any tick where a branch fails, or where every branch it waits for
    (:func:`~roomba_bt.mission.ticks.waited_for`) succeeds. A branch that ends on every
    tick it is ticked (:func:`~roomba_bt.mission.ticks.at_once`: a condition, ``held``, ``stop``, a
    composite or decorator of such) has ended on that tick too, one way or the other: so
    when every other branch waited for is one, the parallel ends on the very tick this one
    succeeds (all succeeded) or has failed before, and nothing is started over
    (``[drive 20 cm, inverter: {cliff: any}]``, the cliff watcher 0.1.0's docs advised). A
    branch the parallel does not wait for (not ``selected``) keeps nothing running,
    and one that could not be built is not known to: its own error is said."""
    return [
        parallel.children[i]
        for i in waited_for(parallel)
        if i != index
        and not at_once(parallel.children[i])
        and not any(n.kind == "unbuilt" for n in parallel.children[i].walk())
    ]


def restarted_branches(root: Node) -> list[Diagnostic]:
    """Errors: a branch of a ``parallel`` with ``synchronise: false`` (policy ``all`` or
    ``selected``) that can succeed and would start something over when ticked again
    (:func:`~roomba_bt.mission.ticks.runs_again`), beside a branch the parallel waits for
    that may still be RUNNING then (:func:`_still_running`). py_trees ticks every branch
    on every tick, and one that succeeded starts again: ``[drive 20 cm, wait 3s]`` drove
    20 cm eleven times (2.2 m), and the parallel, which succeeds only on a tick where every
    branch succeeds, ran until the run's time limit. An error, not a warning: a robot that
    drives ten times the distance asked is a safety matter. Said at the branch, naming the
    branch that keeps the parallel running, with the fixes: run it once (``synchronise:
    true``, or ``oneshot`` to keep the others watched on every tick) or say the re-run
    (``repeat``). A subtree used twice is one place."""
    errors: list[Diagnostic] = []
    for node in root.walk():
        if not every_tick(node) or synchronised(node) or needs(node) not in _WAITING_POLICIES:
            continue
        for index, branch in enumerate(node.children):
            if (
                never_succeeds(branch)
                or not runs_again(branch)
                or any(n.kind == "unbuilt" for n in branch.walk())
            ):
                continue
            running = _still_running(node, index)
            if not running:
                continue
            named = _guarded(branch)
            keeper = _guarded(running[0])
            unsynchronised, synchronise = _synchronise_said(node)
            errors.append(
                named.loc.at(
                    f"{named.name} can succeed, and the {node.kind} ({node.loc.line}:"
                    f"{node.loc.column}) {unsynchronised} and waits for {keeper.name} "
                    f"({_line_of(keeper.loc, named.loc)}), which may still be RUNNING then: "
                    "it ticks every branch on every tick, so once this one succeeds it starts "
                    "again (a drive drives its distance again, a wait waits again), and the "
                    "parallel succeeds only on a tick where every branch it waits for succeeds; "
                    f"{synchronise} to run it once, put it under oneshot to "
                    "run it once and keep its success while the other branches are ticked on "
                    "every tick, or under repeat (no times or for) if it should run again and "
                    "again"
                )
            )
    return list(dict.fromkeys(errors))  # a subtree used twice is one place


def _synchronise_said(node: Node) -> tuple[str, str]:
    """How a composite that ticks a succeeded child again is said to (``has synchronise:
    false``), and the fix (``write synchronise: true (the default)``): by the option its
    word's :class:`~roomba_bt.behaviours.language.Combines` names, none for a word that
    always does."""
    combination = combines(node)
    option = None if combination is None else combination.synchronise
    if combination is None or option is None:
        return "ticks a succeeded branch again", f"use another word than {node.kind}"
    default = " (the default)" if combination.synchronised_by_default else ""
    return f"has {option}: false", f"write {option}: true{default}"


def _guarded(branch: Node) -> Node:
    """A branch as it is said: the node its ``while:``/``until:`` guards."""
    while branch.kind == "guard":
        branch = branch.children[1]
    return branch


def restarted_runs(root: Node) -> list[Diagnostic]:
    """Warnings: a child of a reactive sequence that is not the last and may be RUNNING
    (``wait``, ``drive``), with a later child that may be RUNNING too. The sequence ticks
    every child from the first on every tick, so once the first has succeeded and a later
    one runs, the next tick starts the first again: RUNNING, it stops the later one, which
    starts again when it succeeds (``[wait 300ms, drive 30cm]`` restarts the drive every
    315 ms, for ever; BT.CPP's ReactiveSequence does the same). Not for a child that ends
    on the tick it starts again (a condition, ``stop``, ``mode``, a ``oneshot``). A
    warning: whether a later child ends before the first starts again is not known here.
    Said once for a subtree used twice."""
    warnings: list[Diagnostic] = []
    for node in root.walk():
        if goes_on(node) != SUCCESS or not reactive(node):  # not a reactive sequence
            continue
        for index, child in enumerate(node.children[:-1]):
            later = [c for c in node.children[index + 1 :] if not _ends_again_at_once(c)]
            if _ends_again_at_once(child) or not later:
                continue
            warnings.append(
                child.loc.at(
                    f"{child.name} may be RUNNING and is not the last child of the "
                    f"{node.kind} ({node.loc.line}:{node.loc.column}), which ticks it again "
                    f"from the start on every tick after it succeeds: it stops "
                    f"{later[0].name} ({_line_of(later[0].loc, child.loc)}) and starts it "
                    "again each time, for ever; put the two in a sequence (with memory), or "
                    "keep only conditions before the last child"
                ).as_warning()
            )
    return list(dict.fromkeys(warnings))  # a subtree used twice is one place


#: Leaves that, ticked again after they succeeded, succeed on that tick: ``mode`` (the robot
#: is in the mode already; nothing is sent)
SETTLED_LEAVES = frozenset({"mode"})


def _ends_again_at_once(node: Node) -> bool:
    """Whether ``node``, ticked again after it succeeded, ends on that tick: what ends at
    once, a ``oneshot`` (it answers as the first time), a :data:`SETTLED_LEAVES` leaf."""
    settled = node.decl is not None and node.decl.name in SETTLED_LEAVES
    decorator = answers(node)
    return at_once(node) or (decorator is not None and decorator.replays) or settled


def _claimed_in_two_branches(
    root: Node, claims: Callable[[Node], list[str]]
) -> Iterator[tuple[Node, str, Node, Node]]:
    """Each thing (the wheels, a blackboard key) that nodes of two branches of a
    ``parallel`` claim, as ``(parallel, thing, first, later)``: ``first`` the first node
    claiming it in an earlier branch, ``later`` the first in a later one. A parallel ticks
    its branches in order within one tick, so what two of them set on the same tick, the
    later sets last. Said once per place of ``later`` (a subtree used twice is one place)."""
    seen: set[tuple[str, str, int, int]] = set()
    for node in root.walk():
        if not every_tick(node):
            continue
        first: dict[str, Node] = {}
        for branch in node.children:
            here: dict[str, Node] = {}
            for inner in branch.walk():
                for thing in claims(inner):
                    here.setdefault(thing, inner)
            for thing, later in here.items():
                if thing not in first:
                    first[thing] = later
                    continue
                where = (thing, str(later.loc.file), later.loc.line, later.loc.column)
                if where not in seen:
                    seen.add(where)
                    yield node, thing, first[thing], later


def _wheels(node: Node) -> list[str]:
    """``["wheels"]`` for a leaf that turns them (:func:`parallel_wheels`)."""
    return ["wheels"] if node.decl is not None and node.decl.turns_wheels else []


def parallel_wheels(root: Node) -> list[Diagnostic]:
    """Warnings: a leaf that turns the wheels in a branch of a ``parallel`` after another
    branch with one. The outbox keeps the last wheel command of a tick, so of two drives
    started in the same tick only the later one reaches the robot; the other runs on
    without ever having moved it (a ``distance`` drive never ends) and the later one's halt
    stops the wheels under it. A warning, not an error: whether the two run at the same
    time is not known here (a branch may finish its drive before the other starts one).
    Said at the later leaf, naming the first; a subtree used twice is one place."""
    warnings: list[Diagnostic] = []
    for parallel, _, first, leaf in _claimed_in_two_branches(root, _wheels):
        assert leaf.decl is not None and first.decl is not None
        warnings.append(
            leaf.loc.at(
                f"{leaf.decl.name} turns the wheels in one branch of the parallel "
                f"({parallel.loc.line}:{parallel.loc.column}) and {first.decl.name} "
                f"({_line_of(first.loc, leaf.loc)}) in another: when both run, only the "
                "last wheel command of a tick reaches the robot, so one of them never "
                "moves it (a distance drive never ends); run them one after the other "
                "(a sequence)"
            ).as_warning()
        )
    return warnings


def _keys_written(node: Node) -> list[str]:
    """The blackboard keys ``node`` writes: a leaf's (``set``, ``mark``, a plugin's
    ``writes_keys``, a subtree's among them once expanded) or a ``for_each``'s own key."""
    word = WORDS.get(node.kind)
    if word is not None and word.writes_key is not None:
        return [str(node.options[word.writes_key])]
    return node.keys_written()


def parallel_keys(root: Node) -> list[Diagnostic]:
    """Warnings: a blackboard key written in two branches of a ``parallel``. The branches
    are ticked in order, so when both write on one tick the later branch's value is the one
    read after it (two uses of a subtree setting ``n`` to 1 and 2 left 2, silently), and
    which wins depends on the order of the branches, not on what happened. A warning, not
    an error, as :func:`parallel_wheels`: the two writes may not fall on the same tick.
    Said at the later writer, naming the first and the key."""
    warnings: list[Diagnostic] = []
    for parallel, key, first, later in _claimed_in_two_branches(root, _keys_written):
        warnings.append(
            later.loc.at(
                f"{later.name} writes blackboard key {said_key(key)} in one branch of the parallel "
                f"({parallel.loc.line}:{parallel.loc.column}) and {first.name} "
                f"({_line_of(first.loc, later.loc)}) in another: the branches are ticked in "
                "order, so when both write on one tick the last write wins and the value "
                "read after depends on the branches' order; write it in one branch, or use "
                "a key for each"
            ).as_warning()
        )
    return warnings


def blind_in_full(root: Node, modes: ModeCheck) -> list[Diagnostic]:
    """Warnings (see the module docstring): each leaf that turns the wheels, can run in Full,
    reads no cliff sensor itself, and runs with nothing around it that reads one on every
    tick with a result that ends it (:func:`~roomba_bt.mission.ticks.watched_children`). A
    cliff read elsewhere (a check before a drive, a parallel branch that succeeded and is
    not ticked again, a ``oneshot``, a ``force_success``) does not stop this drive at the
    stairs."""
    warnings: list[Diagnostic] = []
    seen: set[tuple[str, int, int]] = set()  # a subtree used twice is one place in its file
    pending = [(root, False)]
    while pending:
        node, watched = pending.pop()
        if node.kind != "leaf":
            pending.extend(reversed(watched_children(node, watched)))
            continue
        decl = node.decl
        entered = modes.entered.get(id(node))
        if (
            watched
            or decl is None
            or entered is None
            or not decl.turns_wheels
            or reads_cliffs(node)
        ):
            continue
        enters_full = _enters_full(decl, node.params)
        if OIMode.FULL not in entered[1] and not enters_full:
            continue
        where = (str(node.loc.file), node.loc.line, node.loc.column)
        if where in seen:
            continue
        seen.add(where)
        how, fix = (
            ("switches to Full mode itself and can turn the wheels there", "")
            if enters_full  # mode: safe before it changes nothing
            else ("can turn the wheels in Full mode", "use mode: safe, or ")
        )
        warnings.append(
            node.loc.at(
                f"{decl.name} {how}, where the robot does not stop at a cliff or a wheel drop, "
                f"and no cliff sensor (packets 9-12) is read while it runs: {fix}end it on a "
                "cliff (until: {cliff: any})"
            ).as_warning()
        )
    return warnings


#: a ``drive``'s own ends: with one of these it stops by itself
_DRIVE_ENDS = ("distance", "duration", "angle")


def pushes_on_walls(root: Node, modes: ModeCheck) -> list[Diagnostic]:
    """Warnings: each ``drive`` with no end of its own (no ``distance``, ``duration`` or
    ``angle``) that can run in Safe or Full, under no ``timeout``, and with no bumper, light
    bumper or odometry read on every tick it runs with a result that ends it (the cliff
    watch of :func:`blind_in_full`, pointed at :data:`~roomba_bt.mission.ticks.OBSTACLES`).
    Neither mode stops the wheels at a bump: such a drive meets a wall and pushes on it at
    its speed until something else ends it (docs/missions.md's ``held`` example, guarded
    by the battery alone, would push on the apartment's first wall for the 2 hours of
    ``--fast``)."""
    warnings: list[Diagnostic] = []
    seen: set[tuple[str, int, int]] = set()
    pending = [(root, False)]
    while pending:
        node, watched = pending.pop()
        if node.kind != "leaf":
            watched = watched or node.kind == "timeout"  # a time end of its own
            pending.extend(reversed(watched_children(node, watched, OBSTACLES)))
            continue
        decl, params = node.decl, node.params
        entered = modes.entered.get(id(node))
        if (
            watched
            or decl is None
            or decl.name != "drive"
            or entered is None
            or entered[1].isdisjoint({OIMode.SAFE, OIMode.FULL})
            or any(params.get(end) is not None for end in _DRIVE_ENDS)
            or all(params.get(speed) in (None, 0.0) for speed in ("velocity", "left", "right"))
            or reads_cliffs(node, OBSTACLES)
        ):
            continue
        where = (str(node.loc.file), node.loc.line, node.loc.column)
        if where not in seen:
            seen.add(where)
            warnings.append(
                node.loc.at(
                    f"{node.name} has no end of its own (distance, duration, angle), and no "
                    "bumper, wall sensor or odometry is read while it runs: Safe and "
                    "Full do not stop at a wall, so it pushes on the first one it meets; also "
                    "end it on a bump (until: {fallback: [{bump: any}, ...]}), or give it a "
                    "distance or a timeout"
                ).as_warning()
            )
    return warnings


def _enters_full(decl: Declaration, params: Mapping[str, Any]) -> bool:
    """Whether a leaf's own commands with ``params`` include Full (132, by the opcode
    table's ``leads_to``): one that sends Full and then drives runs its drive in Full
    whatever mode it was entered in, and the mode check's ``entered`` (the modes before it)
    does not show it (without this, a plugin's ``sends=opcodes("full", "drive")`` would go
    unwarned where the same drive after ``mode: full`` is warned)."""
    return any(COMMANDS[op].leads_to is OIMode.FULL for op in decl.sent(params))


def profile_commands(
    root: Node, profile: RobotProfile, wording: Wording = PYTHON
) -> tuple[list[Diagnostic], list[Diagnostic]]:
    """Errors and warnings (see the module docstring) for each leaf's declared ``sends`` on
    ``profile``: an error where the robot lacks a command (the run would stop with an
    UnsupportedCommandError after its first commands were written) or the hardware the leaf
    needs (its declaration's ``needs``: ``display`` on a Create 2, which has no display), a
    warning where the firmware ignores it. A subtree used twice is one place in its file:
    said once. ``wording``: how the caller chooses another profile (the command line's
    ``--profile``)."""
    errors: list[Diagnostic] = []
    warnings: list[Diagnostic] = []
    seen: set[tuple[str, int, int]] = set()
    choose = f"(choose the robot's {wording.profile}, or leave this node out)"
    for node in root.walk():
        decl = node.decl
        where = (str(node.loc.file), node.loc.line, node.loc.column)
        if decl is None or where in seen:
            continue
        seen.add(where)
        for opcode in decl.sends:
            problem = profile.command_unavailable(opcode)
            if problem is not None:
                # "reboot: reset (7) is not available ...": it read "reboot sends reset (7)
                # is not available ...", two verbs
                errors.append(node.loc.at(f"{decl.name}: {problem} {choose}"))
                continue
            warning = profile.command_warning(opcode)
            if warning is not None:
                warnings.append(node.loc.at(f"{decl.name}: {warning}").as_warning())
        lacking = None if decl.needs is None else decl.needs(node.params, profile)
        if lacking is None:
            continue
        if decl.needs_only_warns:
            warnings.append(node.loc.at(f"{decl.name}: {lacking}").as_warning())
        else:
            errors.append(node.loc.at(f"{decl.name}: {lacking} {choose}"))
    return errors, warnings


def _restarts_a_cycle(node: Node, looping: bool = False) -> bool:
    """Whether ``node`` holds a leaf that starts a built-in cycle (Clean, Spot, Max, Seek
    Dock) under a decorator that starts its child again (a ``repeat``): a cycle sent over
    and over, as clean-builtin's Clean every ``${cycle}``."""
    decorator = answers(node)
    looping = looping or (decorator is not None and bool(decorator.restarts_on))
    if node.decl is not None and node.decl.starts_cycle:
        return looping
    return any(_restarts_a_cycle(child, looping) for child in node.children)


def _beside_a_cycle(root: Node) -> set[int]:
    """The nodes of each parallel's branch that runs beside another branch that starts a
    built-in cycle over and over (:func:`_restarts_a_cycle`): while they run, the robot
    cleans and hears its cycle's command again and again, and sleeps at no point of it."""
    beside: set[int] = set()
    for node in root.walk():
        if not every_tick(node):
            continue
        cycling = [_restarts_a_cycle(branch) for branch in node.children]
        for index, branch in enumerate(node.children):
            if any(cycles for other, cycles in enumerate(cycling) if other != index):
                beside.update(id(n) for n in branch.walk())
    return beside


def waits_past_sleep(root: Node, modes: ModeCheck, profile: RobotProfile) -> tuple[str, ...]:
    """Each ``wait`` longer than the 5 minutes (:data:`~roomba_bt.oi.profiles.PASSIVE_SLEEP_S`)
    that the mode pass found may run in Passive, said ``file:line:column: wait(10min)``,
    where ``profile``'s robot sleeps in Passive: with nothing from us, it cannot finish
    unless keep-awake pulses BRC (the patrol's ``charge_for=10min`` on a port without BRC
    wiring slept on its charger 5 minutes into it, and the run ended "the robot fell
    asleep", exit 8). Not a warning of
    ``validate``: whether the port can pulse is known only when the run starts
    (:func:`roomba_bt.runtime.long_run.say_waits_past_sleep`). Not a wait beside a branch
    of its parallel that starts a built-in cycle over and over (:func:`_beside_a_cycle`):
    clean-builtin's ``wait: ${duration}`` was named so on every run without keep-awake,
    "it cannot finish", and the run ended SUCCESS."""
    found: list[str] = []
    beside = _beside_a_cycle(root)
    for node, entry in modes.entered.values():
        decl = node.decl
        duration = node.params.get("duration")
        if (
            decl is None
            or id(node) in beside
            or decl.name != "wait"
            or OIMode.PASSIVE not in entry
            or not isinstance(duration, float)
            or duration <= PASSIVE_SLEEP_S
            or not profile.sleeps_in_passive
        ):
            continue
        place = f"{node.loc.file}:{node.loc.line}:{node.loc.column}"
        if not any(said.startswith(place) for said in found):  # a subtree used twice
            found.append(f"{place}: {node.name}")
    return tuple(found)


def in_passive(root: Node, modes: ModeCheck) -> list[Diagnostic]:
    """Warnings: each leaf that does more in Passive than its commands say (its
    declaration's ``in_passive``: ``press: clean`` starts the robot's own cleaning cycle,
    as a finger on its Clean button does) and that the mode pass found reachable in
    Passive. A warning: a mission may mean the cycle; most mean the press in packet 18."""
    warnings: list[Diagnostic] = []
    for node, entry in modes.entered.values():
        decl = node.decl
        if decl is None or decl.in_passive is None or entry.isdisjoint(_PASSIVE_STATES):
            continue
        said = decl.in_passive(node.params)
        if said is not None:
            warnings.append(node.loc.at(f"{decl.name}: {said}").as_warning())
    return warnings


def sensor_ranges(root: Node, profile: RobotProfile) -> list[Diagnostic]:
    """Warnings: each packet test (``sensor: stasis == 2``, or a word that is one: ``stasis:
    dirty``, the declaration's ``compares``) whose answer cannot change on the chosen robot,
    whose packet reads a narrower range than another model's (a Roomba 500's stasis is 0..1,
    a 600's wall signal 0..1023, a 500's encoders unsigned): one check, the profile's packet
    table. A warning, not an error: the same mission may be meant for another model too; a
    test no model can change is already an error where it is written."""
    warnings: list[Diagnostic] = []
    for node in root.walk():
        for name, said, test in packet_tests(node):
            problem = comparison_problem(test, profile.packets, f" on the {profile.title}")
            if problem is not None:
                loc = node.options.get(f"loc:{name}", node.loc)
                warnings.append(loc.at(f"{said}: {problem}").as_warning())
    return warnings


def check_stream(
    packets: tuple[int, ...], baud: int, profile: RobotProfile = DEFAULT_PROFILE
) -> str | None:
    """The bandwidth error message for a mission reading ``packets`` on ``profile``'s robot,
    or None; where it fits at the usual rate, how that robot comes back to it."""
    ids = tuple(sorted(set(packets) | set(RUNTIME_PACKETS)))
    try:
        check_bandwidth(ids, baud)
    except BandwidthError as exc:
        extra = sorted(set(packets) - set(RUNTIME_PACKETS))
        fix, usual = "", DEFAULT_PROFILE.default_baud  # every model's rate after power-up
        if baud < usual and check_stream(packets, usual) is None:
            fix = f"; it fits at {usual}: {profile.at_19200} ({SEND_BAUD})"
        return (
            f"the sensor packets this mission reads ({extra} plus the runtime's "
            f"{list(RUNTIME_PACKETS)}) do not fit the stream: {exc}{fix}"
        )
    return None


def song_slots(root: Node) -> list[Diagnostic]:
    """Warnings of the song slots a mission writes and plays, said where the number is
    written (or at the leaf, for the default slot 0):

    - each ``play`` of a slot no ``song`` of this mission defines (``play: 3`` where only
      slot 0 was written: a typo, most likely);
    - each ``song`` whose slot no ``play`` of this mission plays (``song`` only stores the
      notes, Song 140: a tune written and never played ran in silence, validated ok).

    Warnings, not errors: the robot keeps the songs it was given until it is switched off,
    so a slot may hold an earlier program's song (or be empty: the robot plays nothing),
    and a song may be left for a later program. A slot not known here says nothing of the
    slots on the other side: a ``song`` or ``play`` whose number is a blackboard key, or a
    plugin's leaf that declares it sends Play (any slot)."""
    songs: list[Node] = []
    plays: list[Node] = []
    for node in root.walk():
        decl = node.decl
        if decl is not None and decl.name == "song":
            songs.append(node)
        elif decl is not None and PLAY in decl.sends:
            plays.append(node)
    defined = _slots(songs)
    played = _slots(plays)
    warnings: list[Diagnostic] = []
    if defined is not None:
        for node in plays:
            number = node.params.get("number", 0) if _is(node, "play") else None
            if isinstance(number, int) and number not in defined:
                slots = ", ".join(map(str, sorted(defined))) or "none"
                warnings.append(_at_number(node,
                    f"play: song {number} is not defined by this mission (its song slots: "
                    f"{slots}): the robot plays what an earlier program left in slot "
                    f"{number}, kept until it is switched off, or nothing; add "
                    f"`song: {{number: {number}, notes: [...]}}` before it"
                ))  # fmt: skip
    if played is not None:
        for node in songs:
            number = node.params.get("number", 0)
            if isinstance(number, int) and number not in played:
                warnings.append(_at_number(node,
                    f"song: song {number} is stored but no `play` of this mission plays it "
                    f"(song only gives the robot the notes): add `play: {number}` where it "
                    f"should sound; a song left for a later program is kept until the robot is "
                    f"switched off"
                ))  # fmt: skip
    return warnings


def _slots(nodes: list[Node]) -> set[int] | None:
    """The song slots ``nodes`` (songs, or the leaves that play) name; None where one is
    not known before the run (a blackboard key; a plugin's leaf that sends Play)."""
    slots: set[int] = set()
    for node in nodes:
        number = node.params.get("number", 0)
        if not isinstance(number, int) or not (_is(node, "song") or _is(node, "play")):
            return None
        slots.add(number)
    return slots


def _is(node: Node, name: str) -> bool:
    return node.decl is not None and node.decl.name == name


def _at_number(node: Node, message: str) -> Diagnostic:
    loc: Loc = node.options.get("loc:number", node.loc)
    return loc.at(message).as_warning()
