"""A decorator is judged by the :class:`~roomba_bt.behaviours.language.Answers` its word
declares, never by its name: every check function answers a word as the word whose answers
it was given, and a made-up decorator (one NodeKind, one class, nothing else) validates,
shows and runs, a cooldown of a condition under ``held`` among them."""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

import py_trees
import pytest
from py_trees.behaviour import Behaviour
from py_trees.common import Status

from roomba_bt.behaviours.declare import Param
from roomba_bt.behaviours.decorators import _MissionClock
from roomba_bt.behaviours.language import (
    FAILS,
    SUCCEEDS,
    WORDS,
    Answers,
    NodeKind,
    Shape,
)
from roomba_bt.behaviours.lean import DONE, DecoratorTick
from roomba_bt.behaviours.registry import builtin_registry
from roomba_bt.behaviours.units import DURATION
from roomba_bt.mission import deadends, ticks
from roomba_bt.mission.checks import KeyCheck, ModeCheck
from roomba_bt.mission.plan import Node
from roomba_bt.mission.source import Loc
from roomba_bt.oi.modes import OIMode

DECORATORS = sorted(word for word, kind in WORDS.items() if kind.answers is not None)
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
    node = Node(word, _HERE, word, [child], options={"key": "k", "items": [1]})
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


def test_a_made_up_decorator_validates_shows_and_runs(
    monkeypatch: pytest.MonkeyPatch,
    mission_file: Callable[..., Path],
    capsys: pytest.CaptureFixture[str],
) -> None:
    from roomba_bt.cli import main

    monkeypatch.setitem(WORDS, "cooldown", COOLDOWN)
    path = mission_file(HELD_COOLDOWN)
    assert main(["validate", str(path)]) == 0, capsys.readouterr()
    assert main(["show", str(path)]) == 0
    assert "cooldown" in capsys.readouterr().out
    code = main(["run", str(path), "--fast", "--display", "none", "--timeout", "1min"])
    out = capsys.readouterr().out
    assert code == 0, out
    assert "outcome      SUCCESS" in out and "distance     0.20 m" in out, out
