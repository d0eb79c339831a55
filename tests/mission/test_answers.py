"""A decorator is judged by the :class:`~roomba_bt.behaviours.language.Answers` its word
declares, a composite by its :class:`~roomba_bt.behaviours.language.Combines`, never by
its name: every check function answers a word as the word whose answers it was given, and a
made-up decorator or composite (one NodeKind, one class, nothing else) validates, shows and
runs: a cooldown of a condition under ``held``, a race of a drive and a wait."""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

import py_trees
import pytest
from py_trees.behaviour import Behaviour
from py_trees.common import Status

from roomba_bt.behaviours import lean
from roomba_bt.behaviours.declare import Param
from roomba_bt.behaviours.decorators import _MissionClock
from roomba_bt.behaviours.language import (
    ALL,
    CHILD_NAMES,
    FAILS,
    FAILURE,
    ONE,
    SELECTED,
    SUCCEEDS,
    TEXT,
    WORDS,
    Answers,
    Combines,
    NodeKind,
    Shape,
)
from roomba_bt.behaviours.lean import DONE, DecoratorTick
from roomba_bt.behaviours.registry import builtin_registry
from roomba_bt.behaviours.units import BOOL, DURATION
from roomba_bt.behaviours.units import enum as enum_type
from roomba_bt.mission import checks, deadends, ticks
from roomba_bt.mission.checks import KeyCheck, ModeCheck
from roomba_bt.mission.compiler import compile_mission
from roomba_bt.mission.plan import Node
from roomba_bt.mission.source import Loc
from roomba_bt.oi.modes import OIMode

DECORATORS = sorted(word for word, kind in WORDS.items() if kind.answers is not None)
COMPOSITES = sorted(word for word, kind in WORDS.items() if kind.combines is not None)
_HERE = Loc("answers.yaml", 1, 1, "tree")


def _leaf(name: str, **params: Any) -> Node:
    return Node("leaf", _HERE, name, decl=builtin_registry().get(name), params=params)


#: children that tell the answers apart: one that ends at once and reads the cliffs, one
#: that runs and ends, one that never succeeds, one that changes the mode
CHILDREN: dict[str, Callable[[], Node]] = {
    "cliff": lambda: _leaf("cliff", sensor="any"),
    "drive 30 cm": lambda: _leaf("drive", velocity=0.2, distance=0.3),
    "drive for ever": lambda: _leaf("drive", velocity=0.2),
    "mode: safe": lambda: _leaf("mode", to="safe"),
}


def _judged(word: str, child: Node) -> tuple[object, ...]:
    """Every answer the static checks give of a ``word`` node over ``child``."""
    return _judgements(Node(word, _HERE, word, [child], options={"key": "k", "items": [1]}))


def _judgements(node: Node) -> tuple[object, ...]:
    """Every answer the static checks give of ``node``."""
    modes = ModeCheck()
    keys = KeyCheck()
    entries = (frozenset({OIMode.PASSIVE}), frozenset({OIMode.SAFE, OIMode.FULL}))
    return (
        ticks.at_once(node),
        ticks.succeeds_at_once(node),
        ticks.never_succeeds(node),
        ticks.runs_again(node),
        ticks.cliff_ends(node),
        [modes.visit(node, entry) for entry in entries],
        keys.visit(node, frozenset()),
        deadends.outcomes(node),
        deadends.outcomes(node, first_tick=True),  # held's FAILURE: Answers.first_tick
        # a step of a sequence ticked once that can only fail on its first tick: an error
        len(deadends.dead_ends(Node("sequence", _HERE, "sequence", [node]))[0]),
    )


def test_every_word_declares_answers_exactly_when_it_is_a_decorator() -> None:
    for word, kind in WORDS.items():
        decorates = kind.shape in (Shape.DO, Shape.CHILD_OR_DO)
        assert (kind.answers is not None) == decorates, word


def test_a_decorator_without_answers_is_refused_when_it_is_declared() -> None:
    with pytest.raises(TypeError, match=r"'cooldown' is a decorator .* needs answers="):
        NodeKind("cooldown", Shape.DO, lambda n, k, o: k[0])


def test_every_word_declares_how_it_combines_exactly_when_it_is_a_composite() -> None:
    for word, kind in WORDS.items():
        assert (kind.combines is not None) == (kind.shape is Shape.CHILDREN), word


def test_a_composite_without_combines_or_memory_is_refused_when_it_is_declared() -> None:
    """Without them, which children it ticks, when, and what it answers would be a guess."""
    with pytest.raises(TypeError, match=r"'race' is a composite and needs combines="):
        NodeKind("race", Shape.CHILDREN, lambda n, k, o: k[0])
    with pytest.raises(TypeError, match=r"'chain' ticks its children in turn .* memory"):
        NodeKind("chain", Shape.CHILDREN, lambda n, k, o: k[0], combines=Combines(FAILURE))


def test_a_first_tick_answer_without_its_why_is_refused_when_it_is_declared() -> None:
    """validate's error says why a step can only fail on its first tick: not said, it
    would read ``held is FAILURE on the tick it starts ()``."""
    with pytest.raises(TypeError, match="needs first_tick_why"):
        Answers(SUCCEEDS, FAILS, first_tick=FAILS)


@pytest.mark.parametrize("word", DECORATORS)
def test_each_answer_comes_from_the_declared_answers_not_the_word(
    word: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Given another word's answers, ``word`` is judged as that word, by every function."""
    for other in DECORATORS:
        if WORDS[word].writes_key != WORDS[other].writes_key:
            continue  # for_each's key is an option of its own, read where it is written
        expected = {name: _judged(other, make()) for name, make in CHILDREN.items()}
        with monkeypatch.context() as patch:
            patch.setitem(WORDS, word, replace(WORDS[word], answers=WORDS[other].answers))
            got = {name: _judged(word, make()) for name, make in CHILDREN.items()}
        assert got == expected, f"{word} given {other}'s answers"


def test_a_condition_beside_what_inverts_it_is_found_by_the_answers_not_the_word(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """``parallel: [bump, inverter: {bump}]`` never succeeds: said of any word with the
    inverter's answers, and not of ``inverter`` given another's."""

    def warned(word: str) -> int:
        inverted = Node(word, _HERE, word, [_leaf("bump", side="any")])
        branches = [_leaf("bump", side="any"), inverted]
        parallel = Node("parallel", _HERE, "parallel", branches, options={"policy": "all"})
        return len(deadends.dead_ends(parallel)[1])

    assert warned("inverter") == 1
    monkeypatch.setitem(WORDS, "negate", replace(WORDS["inverter"], word="negate"))
    assert warned("negate") == 1
    force_success = WORDS["force_success"].answers
    monkeypatch.setitem(WORDS, "inverter", replace(WORDS["inverter"], answers=force_success))
    assert warned("inverter") == 0


# ------------------------------------------------------------- a decorator from a test


class Cooldown(_MissionClock, DecoratorTick, py_trees.decorators.Decorator):
    """After its child ends, FAILURE without ticking it for ``duration`` of mission time."""

    def __init__(self, name: str, child: Behaviour, duration: float) -> None:
        super().__init__(name=name, child=child)
        self.duration = duration
        self.ended_at: float | None = None

    def tick_start(self) -> int:
        if self.ended_at is not None and self.now() - self.ended_at < self.duration:
            self.status = Status.FAILURE
            return DONE
        return super().tick_start()

    def update(self) -> Status:
        status: Status = self.decorated.status
        if status is not Status.RUNNING:
            self.ended_at = self.now()
        return status


def _cooldown(name: str, kids: Sequence[Behaviour], o: Mapping[str, Any]) -> Behaviour:
    return Cooldown(name, kids[0], float(o["for"]))


COOLDOWN = NodeKind(
    "cooldown",
    Shape.DO,
    _cooldown,
    (Param("for", DURATION, required=True, doc="mission time after the child ends"),),
    doc="FAILURE without ticking the child for a while after it ends",
    answers=Answers(SUCCEEDS, FAILS, alone=FAILS),
)

#: the contributor's case: a cooldown of a condition ends on every tick, as held needs
HELD_COOLDOWN = """\
tree:
  sequence:
    - mode: safe
    - drive: {velocity: 100 mm/s, distance: 20cm}
      until: {held: {for: 1s, do: {cooldown: {for: 1s, do: {bump: any}}}}}
"""


# ------------------------------------------------------------ composites by their Combines

#: children in orders that tell the combinations apart: a cliff check first or last, a drive
#: that never succeeds before or after one that ends, a condition beside its inverter
ORDERS: dict[str, Callable[[], list[Node]]] = {
    "as listed": lambda: [make() for make in CHILDREN.values()],
    "reversed": lambda: [make() for make in reversed(CHILDREN.values())],
    "a bump and its inverter": lambda: [
        _leaf("bump", side="any"),
        Node("inverter", _HERE, "inverter", [_leaf("bump", side="any")]),
    ],
}


def _combined(word: str, options: Mapping[str, Any], children: list[Node]) -> tuple[object, ...]:
    """Every answer the static checks give of a ``word`` composite over ``children``, and
    of what it says of them (cliff watches, dead ends, restarts, wheel branches)."""
    node = Node(word, _HERE, word, children, options=dict(options))
    root = Node("sequence", _HERE, "sequence", [node], options={"memory": True})
    return (
        *_judgements(node),
        [watched for _, watched in ticks.watched_children(node, False)],
        [len(found) for found in deadends.dead_ends(root)],
        len(checks.restarted_runs(root)),
        len(checks.restarted_limits(root)),
        len(checks.restarted_branches(root)),
        len(checks.parallel_wheels(root)),
    )


@pytest.mark.parametrize("word", COMPOSITES)
def test_each_answer_comes_from_the_declared_combination_not_the_word(
    word: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Given another composite's Combines (and its options: its memory, its policy),
    ``word`` is judged as that word, by every function."""
    for other in COMPOSITES:
        options = {**WORDS[other].defaults, "synchronise": False}
        expected = {name: _combined(other, options, make()) for name, make in ORDERS.items()}
        with monkeypatch.context() as patch:
            # its options too: the Combines name them (a parallel's policy, synchronise)
            given = replace(WORDS[word], combines=WORDS[other].combines,
                            options=WORDS[other].options)  # fmt: skip
            patch.setitem(WORDS, word, given)
            got = {name: _combined(word, options, make()) for name, make in ORDERS.items()}
        assert got == expected, f"{word} given {other}'s combination"


# ------------------------------------------------------------- a composite from a test


class Race(lean.Parallel):
    """Every child on every tick; SUCCESS with the first that succeeds, FAILURE with the
    first that fails."""

    def __init__(self, name: str, children: Sequence[Behaviour]) -> None:
        super().__init__(name, py_trees.common.ParallelPolicy.SuccessOnOne(), list(children))


RACE = NodeKind(
    "race",
    Shape.CHILDREN,
    lambda name, kids, o: Race(name, kids),
    (Param("name", TEXT, doc="the node's name"),),
    doc="every child on every tick, SUCCESS with the first that succeeds",
    combines=Combines(None, needs=ONE),
)

#: a drive raced against a long wait: the drive's success ends the race
DRIVE_RACE = """\
tree:
  sequence:
    - mode: safe
    - race:
        - drive: {velocity: 100 mm/s, distance: 20cm}
        - wait: 30s
"""


@pytest.mark.parametrize(
    ("kind", "mission"), [(COOLDOWN, HELD_COOLDOWN), (RACE, DRIVE_RACE)], ids=["cooldown", "race"]
)
def test_a_made_up_word_validates_shows_and_runs(
    kind: NodeKind,
    mission: str,
    monkeypatch: pytest.MonkeyPatch,
    mission_file: Callable[..., Path],
    capsys: pytest.CaptureFixture[str],
) -> None:
    """A decorator, a composite: one NodeKind and one class, and nothing else, each."""
    from roomba_bt.cli import main

    monkeypatch.setitem(WORDS, kind.word, kind)
    path = mission_file(mission)
    assert main(["validate", str(path)]) == 0
    assert "warning" not in capsys.readouterr().out
    assert main(["show", str(path)]) == 0
    assert kind.word in capsys.readouterr().out
    code = main(["run", str(path), "--fast", "--display", "none", "--timeout", "1min"])
    out = capsys.readouterr().out
    assert code == 0, out
    assert "outcome      SUCCESS" in out and "distance     0.20 m" in out, out


# ----------------------------------------------- a parallel-like composite, options its own


def _together(name: str, kids: Sequence[Behaviour], o: Mapping[str, Any]) -> Behaviour:
    """A parallel whose options are named otherwise: ``wait_for``, ``picks``, ``hold``."""
    policy: py_trees.common.ParallelPolicy.Base
    hold = TOGETHER_COMBINES.synchronised(o)
    if TOGETHER_COMBINES.waits(o) == ONE:
        policy = py_trees.common.ParallelPolicy.SuccessOnOne()
    elif TOGETHER_COMBINES.waits(o) == SELECTED:
        chosen = [kids[i] for i in TOGETHER_COMBINES.waited_for(o, len(kids))]
        policy = py_trees.common.ParallelPolicy.SuccessOnSelected(chosen, hold)
    else:
        policy = py_trees.common.ParallelPolicy.SuccessOnAll(hold)
    return lean.Parallel(name, policy, list(kids))


TOGETHER_COMBINES = Combines(None, policy="wait_for", chosen="picks", synchronise="hold")

#: every child on every tick, as a parallel, with options of its own names: the checks know
#: them from its Combines alone (session 36: they read ``synchronise`` and ``selected_at``)
TOGETHER = NodeKind(
    "together",
    Shape.CHILDREN,
    _together,
    (
        Param("name", TEXT, doc="the node's name"),
        Param("wait_for", enum_type(ALL, ONE, SELECTED), default=ALL, doc="whose successes"),
        Param("picks", CHILD_NAMES, doc="child names, for wait_for: selected"),
        Param("hold", BOOL, default=True, doc="do not re-tick a child that succeeded"),
    ),
    doc="every child on every tick",
    required_if=(("picks", "wait_for", SELECTED),),
    only_if=(("picks", "wait_for", SELECTED),),
    combines=TOGETHER_COMBINES,
)

#: a drive beside a wait, the drive ticked again once it succeeded: it drives again
TOGETHER_RERUN = """\
tree:
  sequence:
    - mode: safe
    - together:
        hold: false
        children:
          - drive: {velocity: 100 mm/s, distance: 20cm}
          - wait: 3s
"""

#: waiting for the drive alone (picked by name), the wait beside it never waited for
TOGETHER_PICKS = """\
tree:
  sequence:
    - mode: safe
    - together:
        wait_for: selected
        picks: [leg]
        children:
          - drive: {velocity: 100 mm/s, distance: 20cm}
            name: leg
          - wait: 30s
"""


def test_a_made_up_parallel_is_judged_by_the_options_its_combines_names(
    monkeypatch: pytest.MonkeyPatch, errors_of: Callable[..., list[str]]
) -> None:
    """Its ``hold: false`` is a parallel's ``synchronise: false``: the drive that would
    drive again is refused, said by the word's own option; ``hold: true`` is not."""
    monkeypatch.setitem(WORDS, "together", TOGETHER)
    errors = errors_of(TOGETHER_RERUN)
    assert [error.split(" can succeed")[0] for error in errors] == [
        "7:13: drive(velocity=100 mm/s, distance=20cm)",
        "8:13: wait(3s)",
    ], errors
    assert "the together (4:7) has hold: false and waits for wait(3s)" in errors[0]
    for error in errors:
        assert "write hold: true (the default) to run it once" in error
    assert errors_of(TOGETHER_RERUN.replace("hold: false", "hold: true")) == []


def test_a_made_up_parallel_waits_for_the_children_its_own_option_picks(
    monkeypatch: pytest.MonkeyPatch,
    mission_file: Callable[..., Path],
    capsys: pytest.CaptureFixture[str],
) -> None:
    """``wait_for: selected, picks: [leg]``: the checks (``waited_for``) and the builder
    read the picked places from the option the Combines names; the run ends with the
    drive, not the 30 s wait."""
    from roomba_bt.cli import main

    monkeypatch.setitem(WORDS, "together", TOGETHER)
    path = mission_file(TOGETHER_PICKS)
    assert main(["validate", str(path)]) == 0
    assert "warning" not in capsys.readouterr().out
    node = compile_mission(path)[0]
    assert node is not None
    together = node.plan.children[1]
    assert ticks.needs(together) == SELECTED and ticks.waited_for(together) == [0]
    code = main(["run", str(path), "--fast", "--display", "none", "--timeout", "10s"])
    out = capsys.readouterr().out
    assert code == 0, out
    assert "outcome      SUCCESS" in out and "distance     0.20 m" in out, out


def test_combines_naming_an_option_the_word_lacks_is_refused_when_it_is_declared() -> None:
    """A ``Combines(synchronise="hold")`` on a word without ``hold`` would judge every node
    as synchronised, whatever it wrote."""
    with pytest.raises(TypeError, match=r"'race': its Combines name 'hold'"):
        NodeKind("race", Shape.CHILDREN, lambda n, k, o: k[0], (),
                 combines=Combines(None, synchronise="hold"))  # fmt: skip


def test_a_made_up_parallel_s_pick_errors_name_its_own_option(
    monkeypatch: pytest.MonkeyPatch, errors_of: Callable[..., list[str]]
) -> None:
    """A pick made with a parameter is refused, said by the word's option (it said
    ``selected:`` whatever the word)."""
    monkeypatch.setitem(WORDS, "together", TOGETHER)
    text = "parameters: {x: {type: str, default: leg}}\n" + TOGETHER_PICKS.replace(
        "picks: [leg]", 'picks: ["${x}"]'
    )
    [error] = errors_of(text)
    assert "together.picks: '${x}'" in error and "so picks: cannot pick it" in error, error
