"""Every node kind of the language, compiled from YAML and ticked against a stub robot."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import py_trees
import pytest
from py_trees.common import Status

from roomba_bt.behaviours.blackboard import read_key
from roomba_bt.behaviours.language import WORDS
from roomba_bt.mission import CompiledMission
from roomba_bt.oi.modes import OIMode
from roomba_bt.robot.testing import StubRobot

Compile = Callable[..., CompiledMission]
R, S, F = Status.RUNNING, Status.SUCCESS, Status.FAILURE


class Run:
    """A compiled mission on a stub robot: ``run.tick(bump=1)`` sets packet 7 and ticks."""

    def __init__(self, mission: CompiledMission) -> None:
        self.mission = mission
        self.robot = StubRobot(mode=OIMode.SAFE)
        mission.setup(self.robot)

    def tick(self, **packets: int) -> Status:
        values = {7: packets.get("bump", 0), 8: packets.get("wall", 0), 35: 2, 43: 0, 44: 0}
        self.robot.set_frame(values)
        self.mission.root.tick_once()
        return self.mission.root.status

    def ticks(self, n: int, **packets: int) -> list[Status]:
        return [self.tick(**packets) for _ in range(n)]

    def sent(self) -> list[list[int]]:
        return [list(c.data) for c in self.robot.flush()]


def run(compile_text: Compile, text: str, params: dict[str, str] | None = None) -> Run:
    return Run(compile_text(text, params))


def test_sequence_with_memory_does_not_recheck_finished_children(compile_text: Compile) -> None:
    r = run(compile_text, "tree: {sequence: [{bump: left}, {wait: 30ms}]}")
    assert r.tick(bump=2) is R
    assert r.tick(bump=0) is R  # the bump is not checked again
    assert r.tick(bump=0) is S
    assert isinstance(r.mission.root, py_trees.composites.Sequence)
    assert r.mission.root.memory is True


def test_reactive_sequence_rechecks_every_tick(compile_text: Compile) -> None:
    r = run(compile_text, "tree: {reactive_sequence: [{bump: left}, {wait: 1s}]}")
    assert r.tick(bump=2) is R
    assert r.tick(bump=0) is F
    assert r.mission.root.memory is False


def test_memory_can_be_chosen_explicitly(compile_text: Compile) -> None:
    r = run(compile_text, "tree: {sequence: {memory: false, children: [wall, {wait: 1s}]}}")
    assert r.mission.root.memory is False
    assert r.tick(wall=1) is R
    assert r.tick(wall=0) is F


def test_a_preempting_branch_keeps_its_first_drive(compile_text: Compile) -> None:
    """A reactive fallback ticks the higher-priority branch first and stops the running one
    after it: the stopped branch's halt must not replace the new branch's Drive in that
    tick's outbox. It did: the new branch's drive was lost and, sending only on change, it
    never sent it again (a patrol's dock stood still at a low battery)."""
    r = run(
        compile_text,
        """
        tree:
          sequence:
            - mode: safe
            - reactive_fallback:
                - sequence: [{bump: any}, {drive: {velocity: -100 mm/s}}]
                - drive: {velocity: 200 mm/s}
        """,
    )
    assert r.tick() is R
    assert r.sent()[-1] == [137, 0, 200, 0x80, 0]  # the lower branch drives
    assert r.tick() is R
    assert r.sent() == []  # and keeps driving
    assert r.tick(bump=1) is R
    assert r.sent() == [[137, 0xFF, 0x9C, 0x80, 0]]  # the new branch's drive, not a halt


def test_an_ending_drive_is_still_halted(compile_text: Compile) -> None:
    """Its own command in the same tick does not keep it moving: the halt replaces it."""
    r = run(compile_text, "tree: {sequence: [{mode: safe}, {drive: {velocity: 200 mm/s, "
                          "duration: 30ms}}, {wait: 1s}]}")  # fmt: skip
    statuses = r.ticks(4)
    assert statuses[-1] is R
    sent = [c for c in r.sent() if c[0] == 137]
    assert sent[-1] == [137, 0, 0, 0, 0]


def test_fallback_tries_alternatives(compile_text: Compile) -> None:
    r = run(compile_text, "tree: {fallback: [{bump: left}, {bump: right}]}")
    assert r.tick(bump=1) is S
    assert r.tick(bump=0) is F
    assert isinstance(r.mission.root, py_trees.composites.Selector)


def test_selector_is_a_synonym_and_reactive_fallback_preempts(compile_text: Compile) -> None:
    r = run(compile_text, "tree: {reactive_fallback: [{bump: any}, {wait: 1s}]}")
    assert r.tick() is R
    assert r.tick(bump=1) is S  # the higher-priority condition took over
    r = run(compile_text, "tree: {selector: [{bump: any}, {wait: 1s}]}")
    assert r.mission.root.memory is True


@pytest.mark.parametrize(
    ("word", "reactive"),
    [("sequence", False), ("reactive_sequence", True), ("fallback", False),
     ("selector", False), ("reactive_fallback", True), ("reactive_selector", True)],
)  # fmt: skip
def test_each_composite_word_resumes_or_rechecks_as_documented(
    compile_text: Compile, word: str, reactive: bool
) -> None:
    """Each word's behaviour, not only its flag: a reactive composite re-ticks its first
    child while a later one runs (a condition preempts), one with memory resumes the running
    child. ``reactive_selector`` given memory, or ``selector`` losing it, fails here."""
    if "sequence" in word:
        r = run(compile_text, f"tree: {{{word}: [{{bump: left}}, {{wait: 1s}}]}}")
        assert r.tick(bump=2) is R
        assert r.tick(bump=0) is (F if reactive else R)
    else:
        r = run(compile_text, f"tree: {{{word}: [{{bump: any}}, {{wait: 1s}}]}}")
        assert r.tick() is R
        assert r.tick(bump=1) is (S if reactive else R)
    assert r.mission.root.memory is not reactive


@pytest.mark.parametrize(("policy", "expected"), [("all", [R, R, S]), ("one", [S])])
def test_parallel_policies(compile_text: Compile, policy: str, expected: list[Status]) -> None:
    r = run(
        compile_text, f"tree: {{parallel: {{policy: {policy}, children: [{{wait: 30ms}}, wall]}}}}"
    )
    assert r.ticks(len(expected), wall=1) == expected


def test_parallel_selected_names_its_children(compile_text: Compile) -> None:
    r = run(
        compile_text,
        """
        tree:
          parallel:
            policy: selected
            selected: [quick]
            children:
              - {wait: 1s, name: slow}
              - {wait: 30ms, name: quick}
        """,
    )
    assert r.ticks(3) == [R, R, S]


def test_a_timeout_under_a_reactive_fallback_whose_later_child_ends_at_once_ends_it(
    compile_text: Compile,
) -> None:
    """What the validator accepts since session 25 (it refused it, saying the limit would
    never end the mission): the timeout fails, ``stop`` succeeds at once, the fallback ends."""
    r = run(
        compile_text,
        "tree: {sequence: [{mode: safe}, {reactive_fallback: [{sequence: [{inverter: {bump: "
        "any}}, {timeout: {after: 60ms, do: {drive: {velocity: 200 mm/s}}}}]}, stop]}]}",
    )
    assert r.ticks(5) == [R, R, R, R, S]  # the timeout at 60 ms, then stop
    assert r.sent()[-1] == [137, 0, 0, 0, 0]


def test_a_parallel_branch_reads_what_an_earlier_branch_set_on_the_same_tick(
    compile_text: Compile,
) -> None:
    """The order the validator relies on since session 25 (it refused this): the ``set``
    is ticked before the drive starts, which drives the distance it wrote."""
    r = run(
        compile_text,
        "blackboard: {d: distance}\ntree: {sequence: [{mode: safe}, {parallel: [{set: {key: d, "
        'value: 10cm}}, {drive: {velocity: 200 mm/s, distance: "@d"}}]}]}',
    )
    assert r.tick() is R
    assert r.sent() == [[137, 0, 200, 128, 0]]
    assert read_key("d") == 100


def test_parallel_selected_names_a_guarded_child_by_the_name_written_beside_its_guard(
    compile_text: Compile,
) -> None:
    """``name: patrol`` beside ``until:`` names the drive the guard wraps; ``selected:
    [patrol]`` picks the guarded child (it was 'unknown child name', the only name the
    parallel knew being the guard's, ``until bump(any)``). The name stays on the drive,
    in the live tree and the guard's reasons."""
    r = run(
        compile_text,
        """
        tree:
          parallel:
            policy: selected
            selected: [patrol]
            children:
              - {wait: 1s, name: slow}
              - name: patrol
                wait: 30ms
                until: {bump: any}
              - name: other
                wait: 1s
                until: {bump: any}
        """,
    )
    guard = r.mission.root.children[1]
    assert guard.name == "until bump(any)" and guard.children[1].name == "patrol"
    assert r.ticks(3) == [R, R, S]


@pytest.mark.parametrize(
    ("text", "said"),
    [
        # two children named alike: selected: picked both, and 'known: timer, timer'
        ("parallel:\n  policy: selected\n  selected: [timer]\n  children:\n"
         "    - {name: timer, wait: 1s}\n    - {name: timer, wait: 2s}\n",
         "4:15: parallel.selected: 'timer' names 2 children, at 6:9 and 7:9; give each its "
         "own name (name: ...)"),
        # two guards of the same condition answer to the same name
        ("parallel:\n  policy: selected\n  selected: [until bump(any)]\n  children:\n"
         "    - {wait: 1s, until: {bump: any}}\n    - {wait: 2s, until: {bump: any}}\n",
         "4:15: parallel.selected: 'until bump(any)' names 2 children, at 6:9 and 7:9"),
        # selected: under another policy was ignored, or 'unknown child name'
        ("parallel:\n  policy: one\n  selected: [t]\n  children: [{name: t, wait: 1s}]\n",
         "4:15: parallel: selected: only goes with policy: selected (policy is one)"),
        ("parallel:\n  selected: [t]\n  children: [{name: t, wait: 1s}]\n",
         "3:15: parallel: selected: only goes with policy: selected (policy is all)"),
        # a reactive composite with memory is a plain one: it was accepted silently
        ("reactive_sequence: {memory: true, children: [wall]}",
         "2:31: reactive_sequence: memory: true is refused: a reactive_sequence ticks every "
         "child from the first on every tick: it has no memory (write sequence for one that "
         "resumes its RUNNING child)"),
        ("reactive_fallback: {memory: true, children: [wall]}",
         "(write fallback for one that resumes its RUNNING child)"),
    ],
)  # fmt: skip
def test_options_that_contradict_each_other_are_refused(
    errors_of: Callable[..., list[str]], text: str, said: str
) -> None:
    errors = errors_of("tree:\n" + "".join(f"  {line}\n" for line in text.splitlines()))
    assert [e for e in errors if said in e] != [], errors
    assert len(errors) == 1, errors


def test_reactive_composites_without_memory_and_a_sequence_without_it_are_accepted(
    errors_of: Callable[..., list[str]],
) -> None:
    assert errors_of("tree: {reactive_sequence: {memory: false, children: [wall]}}") == []
    assert errors_of("tree: {sequence: {memory: false, children: [wall]}}") == []


def test_parallel_short_form_is_policy_all(compile_text: Compile) -> None:
    r = run(compile_text, "tree: {parallel: [{wait: 15ms}, wall]}")
    assert r.ticks(2, wall=1) == [R, S]


def test_retry(compile_text: Compile) -> None:
    r = run(compile_text, "tree: {retry: {times: 2, do: wall}}")
    assert r.tick(wall=0) is R
    assert r.tick(wall=0) is F
    r = run(compile_text, "tree: {retry: {times: 2, do: wall}}")
    assert r.ticks(2, wall=1) == [S, S]


def test_repeat_times_and_for_a_duration(compile_text: Compile) -> None:
    r = run(compile_text, "tree: {repeat: {times: 2, do: wall}}")
    assert r.ticks(2, wall=1) == [R, S]
    r = run(compile_text, "tree: {repeat: {for: 45ms, do: wall}}")
    assert r.ticks(4, wall=1) == [R, R, R, S]
    r = run(compile_text, "tree: {repeat: {do: wall}}")
    assert r.ticks(5, wall=1) == [R] * 5
    assert r.tick(wall=0) is F


def test_timeout_counts_mission_time(compile_text: Compile) -> None:
    r = run(compile_text, "tree: {timeout: {after: 30ms, do: {wait: 1s}}}")
    assert r.ticks(3) == [R, R, F]


def test_delay(compile_text: Compile) -> None:
    r = run(compile_text, "tree: {delay: {for: 30ms, do: wall}}")
    assert r.ticks(3, wall=1) == [R, R, S]


def test_held_until_a_drive_stops_it_only_after_the_hold(compile_text: Compile) -> None:
    """A bump flickering (pressed, free, pressed...) never holds; pressed on every tick for
    45 ms it does: the drive is halted then, not at the first press."""
    r = run(
        compile_text,
        """
        tree:
          sequence:
            - mode: safe
            - drive: {velocity: 100 mm/s}
              until: {held: {for: 45ms, do: {bump: any}}}
        """,
    )
    assert r.tick() is R  # in Safe already: the drive starts
    assert r.sent() == [[137, 0, 100, 128, 0]]
    for _ in range(5):
        assert r.ticks(2, bump=1) == [R, R]
        assert r.tick() is R  # free again: the hold starts over
    assert r.sent() == []  # driving on throughout, no halt
    assert r.ticks(3, bump=1) == [R, R, R]
    assert r.tick(bump=1) is S  # 45 ms after the first of the steady presses
    assert r.sent() == [[137, 0, 0, 0, 0]]


def test_held_in_a_fallback_does_not_count_an_old_hold(compile_text: Compile) -> None:
    """A reactive sequence's ``held`` not ticked while an earlier child fails: when it is
    ticked again, its hold starts again (the wall it saw before the gap does not count).
    The first alternative of a reactive fallback, ticked on every tick the wait runs (a
    failed root would end the run: validate refuses held so)."""
    r = run(
        compile_text,
        """
        tree:
          reactive_fallback:
            - reactive_sequence:
                - inverter: {bump: any}
                - held: {for: 45ms, do: wall}
            - wait: 1h
        """,
    )
    assert r.ticks(3, wall=1) == [R, R, R]  # held 30 ms
    assert r.tick(wall=1, bump=1) is R  # held not ticked
    assert r.ticks(4, wall=1) == [R, R, R, S]


@pytest.mark.parametrize(
    ("node", "said"),
    [
        # the value as written, then in the option's unit, as a leaf's parameter is said
        (
            "held: {for: 5ms, do: wall}",
            "3:17: held.for must be at least 0.015 s, got 5ms (0.005 s)",
        ),
        (
            "held: {for: 0.0001 min, do: wall}",
            "3:17: held.for must be at least 0.015 s, got 0.0001 min (0.006 s)",
        ),
        ("held: {for: 0s, do: wall}", "3:17: held.for must be at least 0.015 s, got 0 s"),
        ("held: {for: -2s, do: wall}", "3:17: held.for must be at least 0.015 s, got -2 s"),
        ("held: {for: 3 m, do: wall}", "3:17: held.for: unknown duration unit 'm'"),
        ("held: {for: fast, do: wall}", "3:17: held.for: "),
        ("held: {do: wall}", "3:5: held needs for:"),
        ("held: {for: 1s}", "3:5: held needs a child under do:"),
        ("held: 1s", "3:11: held takes options and a child: held: {for, do: ...}"),
        ("held: {for: 1s, do: [wall, bump]}", "3:25: held takes exactly one child, got a list"),
        ("held: {for: 1s, after: 2s, do: wall}", "3:21: held: unknown option 'after'"),
    ],
)
def test_held_bad_options_are_errors_at_their_place(
    errors_of: Callable[..., list[str]], node: str, said: str
) -> None:
    errors = errors_of(f"tree:\n  sequence:\n  - {node}\n")
    assert len(errors) == 1 and errors[0].startswith(said), errors


@pytest.mark.parametrize(
    ("child", "said"),
    [
        ("{drive: {velocity: 100 mm/s}}",
         "4:26: held: its child is ticked as a condition on every tick; 'drive' is an action"),
        ("{sequence: [wall, {wait: 1s}]}", "4:44: held: its child is ticked as a condition on "
         "every tick; 'wait' is an action"),
        ("{stop: {}}", "4:26: held: its child is ticked as a condition on every tick; 'stop' is "
         "an action"),
        ("{delay: {for: 1s, do: wall}}", "4:26: held: its child must end on every tick "
         "(conditions, and sequences, fallbacks and inverters of them); delay may be RUNNING, "
         "and held would halt it and start it again on every tick"),
        ("{repeat: {times: 2, do: wall}}", "4:26: held: its child must end on every tick"),
    ],
)  # fmt: skip
def test_held_refuses_a_child_that_is_no_condition(
    errors_of: Callable[..., list[str]], child: str, said: str
) -> None:
    errors = errors_of(f"tree:\n  sequence:\n  - mode: safe\n  - held: {{for: 1s, do: {child}}}\n")
    assert len(errors) == 1 and errors[0].startswith(said), errors


def test_held_takes_conditions_and_what_ends_at_once(errors_of: Callable[..., list[str]]) -> None:
    for child in (
        "wall",
        "{sequence: [wall, {bump: any}]}",
        "{reactive_fallback: [wall, {inverter: {bump: any}}]}",
        "{timeout: {after: 1s, do: wall}}",
        "{held: {for: 30ms, do: wall}}",
        "{sensor: bumps_wheel_drops < 4}",
    ):
        assert errors_of(f"tree: {{held: {{for: 1s, do: {child}}}}}") == [], child


def test_inverter_and_forced_results(compile_text: Compile) -> None:
    assert run(compile_text, "tree: {inverter: wall}").tick(wall=1) is F
    assert run(compile_text, "tree: {inverter: {do: wall}}").tick(wall=0) is S
    assert run(compile_text, "tree: {force_success: wall}").tick(wall=0) is S
    assert run(compile_text, "tree: {force_failure: {bump: any}}").tick(bump=1) is F


def test_oneshot_runs_its_child_once(compile_text: Compile) -> None:
    r = run(compile_text, "tree: {oneshot: {policy: on_completion, do: {log: hello}}}")
    assert r.tick() is S
    assert r.tick() is S
    r = run(compile_text, "tree: {oneshot: wall}")
    assert isinstance(r.mission.root, py_trees.decorators.OneShot)
    assert r.tick(wall=0) is F
    assert r.tick(wall=1) is S


def test_for_each_walks_waypoints_through_the_blackboard(compile_text: Compile) -> None:
    r = run(
        compile_text,
        """
        blackboard:
          leg: {fields: {distance: distance, turn: angle}}
          last: distance
        tree:
          for_each:
            key: leg
            in: [{distance: 1 m, turn: 90deg}, {distance: 50cm, turn: -90deg}]
            do: {set: {key: last, value: 0 mm}}
        """,
    )
    assert r.ticks(2) == [R, S]
    assert read_key("leg") == {"distance": 500.0, "turn": -90.0}


def test_until_guard_on_any_node_halts_a_drive(compile_text: Compile) -> None:
    r = run(
        compile_text,
        "tree: {sequence: [{mode: safe}, {drive: {velocity: 100 mm/s}, until: {bump: any}}]}",
    )
    assert r.tick() is R
    assert r.sent() == [[137, 0, 100, 0x80, 0]]
    assert r.tick(bump=1) is S
    assert r.sent() == [[137, 0, 0, 0, 0]]


def test_while_guard_fails_when_its_condition_stops_holding(compile_text: Compile) -> None:
    r = run(compile_text, "tree: {wait: 1s, while: {inverter: {bump: any}}}")
    assert r.tick() is R
    assert r.tick(bump=2) is F


def test_guard_may_be_a_subtree_of_conditions(compile_text: Compile) -> None:
    r = run(compile_text, "tree: {wait: 1s, until: {fallback: [{bump: left}, wall]}}")
    assert r.tick() is R
    assert r.tick(wall=1) is S


def test_name_modifier_names_the_node(compile_text: Compile) -> None:
    r = run(compile_text, "tree: {sequence: [wall], name: main}")
    assert r.mission.root.name == "main"


def test_subtrees_with_parameters(compile_text: Compile) -> None:
    mission = compile_text(
        """
        subtrees:
          back_off:
            parameters: {speed: {type: speed, default: 100 mm/s}}
            tree: {drive: {velocity: "-${speed}", duration: 15ms}}
        tree:
          sequence:
            - mode: safe
            - subtree: back_off
            - subtree: {id: back_off, speed: 200 mm/s}
        """
    )
    r = Run(mission)
    r.tick()
    assert r.sent() == [[137, 0xFF, 0x9C, 0x80, 0x00]]  # -100 mm/s
    r.tick()  # the first back-off ends (halt) and the second starts: the last one wins
    assert r.sent() == [[137, 0xFF, 0x38, 0x80, 0x00]]  # -200 mm/s


def test_include_brings_subtrees(mission_file: Callable[..., Path]) -> None:
    from roomba_bt.mission import load_mission

    mission_file("subtrees:\n  touch: {tree: {bump: any}}\n", "lib/common.yaml")
    path = mission_file("include: [lib/common.yaml]\ntree: {subtree: touch}\n")
    r = Run(load_mission(path))
    assert r.tick(bump=1) is S


def test_plugin_by_path(mission_file: Callable[..., Path]) -> None:
    from roomba_bt.mission import Permissions, load_mission

    mission_file(
        "from roomba_bt.behaviours import Condition, declare\n"
        "@declare('always_true', kind='condition', reads=(8,))\n"
        "class AlwaysTrue(Condition):\n"
        "    '''Always.'''\n"
        "    def check(self, snapshot):\n"
        "        return True\n",
        "my_behaviour.py",
    )
    path = mission_file("plugins: [./my_behaviour.py]\ntree: always_true\n")
    mission = load_mission(path, permissions=Permissions(plugin_files=True))
    assert Run(mission).tick() is S
    assert 8 in mission.packets


def test_a_plugin_class_that_raises_when_built_is_its_error_at_its_node(
    mission_file: Callable[..., Path],
) -> None:
    """It was "internal error while compiling (ValueError: ...); please report it" at 1:1."""
    from roomba_bt.mission import Permissions, compile_mission

    plugin = mission_file(
        "from roomba_bt.behaviours import Condition, declare\n"
        "@declare('touchy', kind='condition', reads=(8,))\n"
        "class Touchy(Condition):\n"
        "    '''Refuses to be built.'''\n"
        "    def __init__(self, *args, **kwargs):\n"
        "        super().__init__(*args, **kwargs)\n"
        "        raise ValueError('no calibration file')\n",
        "touchy.py",
    )
    path = mission_file("plugins: [./touchy.py]\ntree:\n  sequence: [touchy]\n")
    mission, (problem,) = compile_mission(path, permissions=Permissions(plugin_files=True))
    assert mission is None
    assert (problem.line, problem.column) == (3, 14)
    assert problem.message == (
        f"touchy: building it raised ValueError: no calibration file (at {plugin}:7)"
    )


def test_parameters_defaults_and_overrides(compile_text: Compile) -> None:
    text = """
        parameters:
          speed: {type: speed, default: 200 mm/s}
          laps: {type: int, default: 1}
          loud: {type: bool, default: false}
          side: {type: enum, choices: [left, right], default: left}
        tree: {sequence: [{mode: safe}, {drive: {velocity: "${speed}"}}]}
    """
    assert compile_text(text).parameters == {
        "speed": 200.0,
        "laps": 1,
        "loud": False,
        "side": "left",
    }
    overridden = compile_text(
        text, {"speed": "0.25 m/s", "laps": "3", "loud": "true", "side": "right"}
    )
    assert overridden.parameters == {"speed": 250.0, "laps": 3, "loud": True, "side": "right"}
    r = Run(compile_text(text, {"speed": "150mm/s"}))
    r.tick()
    assert r.sent() == [[137, 0, 150, 0x80, 0]]


PERCENT_PARAMETER = """
    parameters:
      low: {type: percent, default: 15%}
    tree: {sequence: [{mode: safe}, {battery: {below: "${low}"}}, {log: "below ${low}"}]}
"""


@pytest.mark.parametrize(
    ("given", "percent", "shown"),
    [
        ("0.2", 20.0, "20%"),
        (".15", 15.0, "15%"),
        ("1e-1", 10.0, "10%"),
        ("2E-1", 20.0, "20%"),
        ("0.125", 12.5, "12.5%"),
        ("20%", 20.0, "20%"),
        ("0", 0.0, "0%"),  # was battery(below=0) beside battery(below=20%)
        ("-0.0", 0.0, "0%"),
    ],
)
def test_a_percent_parameter_takes_a_share_below_one_as_battery_does(
    compile_text: Compile, given: str, percent: float, shown: str
) -> None:
    """``-p low_battery=0.2`` was refused ("has no unit") while the same command's
    ``--battery 0.2`` was taken: a plain number below 1 is a share of the whole for both,
    as ``--battery`` reads a plain number (``1e-1`` as well as ``.2``). It is shown as the
    percent it means wherever the value is inserted: ``battery(below=0.2)`` and the log's
    ``below 0.2`` read as 0.2 %."""
    mission = compile_text(PERCENT_PARAMETER, {"low": given})
    assert mission.parameters == {"low": percent}
    names = [node.name for node in mission.root.iterate()]
    assert names[1:3] == [f"battery(below={shown})", f"log(below {shown})"], names


def test_a_percent_written_as_a_bare_zero_shows_its_sign_everywhere(compile_text: Compile) -> None:
    """A percent's bare ``0`` (a default, a value written in a leaf, a subtree's argument,
    a percent key's value in ``check``) showed as ``0`` where every other percent shows
    as ``20%``: each is ``0%``; a speed's bare ``0`` is as written (no percent)."""
    mission = compile_text(
        """
        parameters:
          low: {type: percent, default: 0}
        blackboard:
          level: {type: percent, initial: 0}
        subtrees:
          low_battery:
            parameters: {under: {type: percent, default: 5%}}
            tree: {battery: {below: "${under}"}}
        tree:
          sequence:
            - mode: safe
            - battery: {below: "${low}"}
            - battery: {below: 0}
            - subtree: {id: low_battery, under: 0}
            - check: {key: level, op: ">=", value: 0}
            - drive: {velocity: 0, duration: 15ms}
        """
    )
    names = [node.name for node in mission.root.iterate()]
    assert [n for n in names if n.startswith(("battery", "check", "drive"))] == [
        "battery(below=0%)",
        "battery(below=0%)",
        "battery(below=0%)",
        'check(key=level, op=">=", value=0%)',
        "drive(velocity=0, duration=15ms)",
    ], names


SAME_TURNS = """
parameters:
  back: {type: angle, default: -45deg}
tree:
  sequence:
    - mode: {to: safe}
    - turn: -45deg
    - turn: {angle: -45deg}
    - turn: "${back}"
    - turn: 45deg
    - turn: {angle: 0.125turn}
    - turn: {speed: 50 mm/s, angle: -90deg}
    - turn: {angle: -90deg, speed: 50 mm/s}
    - turn: 0deg
    - drive: {distance: 20cm, velocity: 100 mm/s}
"""


def test_a_leaf_is_named_alike_however_the_file_writes_the_same_value(
    compile_text: Compile,
) -> None:
    """``turn: -45deg`` was ``turn(-45deg)`` and ``turn: {angle: -45deg}`` was
    ``turn(angle=-45deg)``; the parameters were said in the file's order. One name now
    (the primary parameter alone in the short form, the others in the declaration's order),
    and a turn's angle says which way it goes (docs/missions.md: positive turns left)."""
    names = [node.name for node in compile_text(SAME_TURNS).root.iterate() if not node.children]
    assert names == [
        "mode(safe)",
        "turn(-45deg right)",
        "turn(-45deg right)",
        "turn(-45deg right)",
        "turn(45deg left)",
        "turn(0.125turn left)",
        "turn(angle=-90deg right, speed=50 mm/s)",
        "turn(angle=-90deg right, speed=50 mm/s)",
        "turn(0deg)",
        "drive(velocity=100 mm/s, distance=20cm)",
    ], names


def test_a_drives_radius_says_which_side_it_bends_to(compile_text: Compile) -> None:
    """``drive(velocity=-200 mm/s, radius=-500 mm)`` left the reader to know the sign's
    convention, as ``turn(-45deg)`` did: a radius says the side the turn's centre is on,
    the way the path bends forward and backing up alike (docs/missions.md: positive turns
    left); a word (``straight``, ``spin_left``) or a key read at run time says itself."""
    mission = compile_text(
        """
        blackboard: {r: {type: radius, initial: 300 mm}}
        tree:
          sequence:
            - mode: safe
            - drive: {velocity: 200 mm/s, radius: 50cm, distance: 20cm}
            - drive: {velocity: -200 mm/s, radius: -500 mm, distance: 20cm}
            - drive: {radius: straight, duration: 1s}
            - drive: {radius: spin_left, duration: 1s}
            - drive: {radius: "@r", duration: 1s}
        """
    )
    names = [node.name for node in mission.root.iterate() if not node.children]
    assert names[1:] == [
        "drive(velocity=200 mm/s, radius=50cm left, distance=20cm)",
        "drive(velocity=-200 mm/s, radius=-500 mm right, distance=20cm)",
        "drive(radius=straight, duration=1s)",
        "drive(radius=spin_left, duration=1s)",
        "drive(radius=@r, duration=1s)",
    ], names


def test_show_draws_the_names_the_run_uses(
    mission_file: Callable[..., Path], capsys: pytest.CaptureFixture[str]
) -> None:
    """``show`` and the run's tree, log and outcome say a leaf by the one name."""
    from roomba_bt.cli import main

    path = mission_file(SAME_TURNS)
    assert main(["show", str(path)]) == 0
    shown = capsys.readouterr().out
    assert shown.count("--> turn(-45deg right)\n") == 3, shown
    assert "turn(angle=" not in shown.replace("turn(angle=-90deg right, speed=50 mm/s)", "")
    assert main(["run", str(path), "--fast", "--display", "tree", "--timeout", "1min"]) == 0
    ran = capsys.readouterr().out
    assert "turn(-45deg right)" in ran and "turn(angle=-90deg right, speed=50 mm/s)" in ran


@pytest.mark.parametrize(("given", "percent"), [("20", "20%"), ("1e1", "10%"), ("1.50", "1.5%")])
def test_a_bare_percent_of_one_or_more_is_refused_with_both_ways_to_write_it(
    errors_of: Callable[..., list[str]], given: str, percent: str
) -> None:
    """``1`` could mean 1% or all of it: refused, the message naming the percent and the
    share, the percent as people write it (``10%``, not ``1e+1%``)."""
    (said,) = errors_of(PERCENT_PARAMETER, {"low": given})
    assert said == (
        f"2:3: parameter low={given} (given in params): '{given}' has no unit; write {percent} "
        "(a plain number below 1 is a share of the whole: 0.2 is 20%)"
    )


def test_blackboard_initial_values_set_and_check(compile_text: Compile) -> None:
    mission = compile_text(
        """
        blackboard:
          count: {type: int, initial: 1}
        tree:
          sequence:
            - check: {key: count, op: "==", value: 1}
            - set: {key: count, value: 2}
            - check: {key: count, value: 2}
        """
    )
    assert mission.blackboard_initial == {"count": 1}
    assert Run(mission).tick() is S
    assert read_key("count") == 2


def test_compiled_mission_reports_packets_modes_and_source(compile_text: Compile) -> None:
    mission = compile_text(
        """
        mission: demo
        description: a demo
        tree:
          sequence:
            - mode: full
            - drive: {distance: 1m}
              until: {cliff: front_left}
            - light_bumper: {sensor: right, threshold: 100}
        """
    )
    assert mission.name == "demo"
    assert mission.description == "a demo"
    assert mission.packets == (10, 43, 44, 51)
    assert mission.modes_needed == {OIMode.SAFE, OIMode.FULL}
    assert mission.source.name == "m.yaml"


def test_every_leaf_receives_the_robot_in_setup(compile_text: Compile) -> None:
    mission = compile_text("tree: {sequence: [wall, {mode: safe}, {drive: {duration: 1s}}]}")
    robot = StubRobot()
    mission.setup(robot)
    leaves: list[Any] = [n for n in mission.root.iterate() if hasattr(n, "robot")]
    assert leaves and all(n.robot is robot for n in leaves)


MINIMAL = {
    "sequence": ("{sequence: [wall]}", py_trees.composites.Sequence),
    "reactive_sequence": ("{reactive_sequence: [wall]}", py_trees.composites.Sequence),
    "fallback": ("{fallback: [wall]}", py_trees.composites.Selector),
    "selector": ("{selector: [wall]}", py_trees.composites.Selector),
    "reactive_fallback": ("{reactive_fallback: [wall]}", py_trees.composites.Selector),
    "reactive_selector": ("{reactive_selector: [wall]}", py_trees.composites.Selector),
    "parallel": ("{parallel: [wall]}", py_trees.composites.Parallel),
    "inverter": ("{inverter: wall}", py_trees.decorators.Inverter),
    "force_success": ("{force_success: wall}", py_trees.decorators.FailureIsSuccess),
    "force_failure": ("{force_failure: wall}", py_trees.decorators.SuccessIsFailure),
    "retry": ("{retry: {times: 2, do: wall}}", py_trees.decorators.Retry),
    "repeat": ("{repeat: {times: 2, do: wall}}", py_trees.decorators.Decorator),
    "timeout": ("{timeout: {after: 1s, do: wall}}", py_trees.decorators.Decorator),
    "delay": ("{delay: {for: 1s, do: wall}}", py_trees.decorators.Decorator),
    "held": ("{held: {for: 1s, do: wall}}", py_trees.decorators.Decorator),
    "oneshot": ("{oneshot: wall}", py_trees.decorators.OneShot),
    "for_each": ("{for_each: {key: n, in: [1], do: wall}}", py_trees.decorators.Decorator),
    "subtree": ("{subtree: s}", py_trees.composites.Sequence),
}


@pytest.mark.parametrize("word", sorted(WORDS))
def test_every_language_word_compiles_onto_py_trees(compile_text: Compile, word: str) -> None:
    assert word in MINIMAL, (
        f"add a minimal example of {word!r} to MINIMAL in tests/mission/test_nodes.py: its "
        "mission text and the py_trees class it builds"
    )
    unknown = set(MINIMAL) - set(WORDS)
    assert not unknown, f"MINIMAL names words the language does not have: {unknown}"
    text, cls = MINIMAL[word]
    mission = compile_text(
        f"blackboard: {{n: int}}\nsubtrees: {{s: {{tree: {{sequence: [wall]}}}}}}\ntree: {text}\n"
    )
    assert isinstance(mission.root, cls)
    Run(mission).tick(wall=1)  # ticks without error


def test_a_while_guard_says_which_condition_failed(compile_text: Compile) -> None:
    from roomba_bt.behaviours.reasons import failure_reason

    r = run(
        compile_text,
        """
        tree:
          sequence:
            - mode: safe
            - wait: 1s
              while:
                reactive_sequence: [{inverter: {wall: {}}}, {inverter: {bump: any}}]
        """,
    )
    assert r.tick() is R
    assert r.tick(bump=1) is F
    # the inverted condition that held is named (it said "inverter", as in the docs' own
    # while: {inverter: {cliff: any}}), in the words of its description first
    assert failure_reason(r.mission.root) == (
        "stopped: a bumper is pressed, while 'wait(1s)' ran (bump(any) held)"
        " (stage wait was running)"
    )


def test_a_while_guard_names_the_node_it_wraps_through_an_until_inside_it(
    compile_text: Compile,
) -> None:
    """With both ``while:`` and ``until:``, the ``until`` is inside the ``while``: the reason
    names the node they wrap (``'outbound'``), as without the ``until``; it named the inner
    guard, ``'until bump(any)'``."""
    from roomba_bt.behaviours.reasons import failure_reason

    r = run(
        compile_text,
        """
        tree:
          sequence:
            - mode: safe
            - name: outbound
              wait: 1s
              while: {inverter: {wall: {}}}
              until: {bump: any}
        """,
    )
    assert r.tick() is R
    assert r.tick(wall=1) is F
    assert failure_reason(r.mission.root) == (
        "stopped: the right-side wall sensor sees a wall, while 'outbound' ran (wall held)"
        " (stage outbound was running)"
    )


@pytest.mark.parametrize(
    ("condition", "said"),
    [
        # the robot lifted: it said "while inverter: condition no longer holds:
        # wheel_drop(any) held"
        (
            "{inverter: {wheel_drop: any}}",
            "stopped: a wheel has dropped, as when the robot is lifted or a wheel goes over an "
            "edge, while 'clean' ran (wheel_drop(any) held)",
        ),
        # a name the mission gave the condition is its own words: kept
        (
            "{name: on the floor, inverter: {wheel_drop: any}}",
            "stopped: on the floor (wheel_drop(any) held) while 'clean' ran",
        ),
        # a condition that stopped holding, not one that held: named as written
        (
            "{sensor: bumps_wheel_drops < 4}",
            "stopped: sensor(bumps_wheel_drops < 4) no longer holds while 'clean' ran",
        ),
    ],
)
def test_a_while_guard_says_what_stopped_which_node_in_the_condition_s_words(
    compile_text: Compile, condition: str, said: str
) -> None:
    from roomba_bt.behaviours.reasons import failure_reason

    r = run(
        compile_text,
        f"""
        tree:
          sequence:
            - mode: safe
            - sequence:
                name: clean
                children: [{{wait: 1s}}]
              while: {condition}
        """,
    )
    assert r.tick() is R
    assert r.tick(bump=0b1100) is F  # both wheels dropped (packet 7, bits 2 and 3)
    assert failure_reason(r.mission.root) == said + " (stage wait was running)"  # eval's stage


def test_the_mission_s_writes_show_in_py_trees_activity_stream(compile_text: Compile) -> None:
    """A py_trees user's ``enable_activity_stream`` listed only the runtime's snapshot: the
    mission's writes (``for_each``, ``set``) went to the store without a word."""
    py_trees.blackboard.Blackboard.enable_activity_stream(100)
    try:
        r = run(
            compile_text,
            """
            blackboard:
              last: distance
            tree:
              for_each:
                key: last
                in: [1 m, 50cm]
                do: {set: {key: last, value: 2 mm}}
            """,
        )
        r.ticks(2)
        stream = py_trees.blackboard.Blackboard.activity_stream
        assert stream is not None
        said = [(i.activity_type, i.current_value) for i in stream.data
                if i.key == "/mission/last"]  # fmt: skip
        assert said == [("INITIALISED", 1000.0), ("WRITE", 2.0), ("WRITE", 500.0), ("WRITE", 2.0)]
        writers = {i.client_name for i in stream.data if i.key == "/mission/last"}
        assert "/mission/last : WRITE" in py_trees.display.unicode_blackboard_activity_stream()
        assert any("set" in w for w in writers) and any("for_each" in w for w in writers)
    finally:
        py_trees.blackboard.Blackboard.disable_activity_stream()
