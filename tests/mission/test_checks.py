"""The static passes accept what is right, not only reject what is wrong."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest

from roomba_bt.mission import RUNTIME_PACKETS, CompiledMission, Permissions, load_mission
from roomba_bt.mission.checks import check_stream

Errors = Callable[..., list[str]]


@pytest.mark.parametrize(
    "tree",
    [
        "{sequence: [{mode: safe}, {drive: {duration: 1s}}]}",
        "{sequence: [{fallback: [{mode: safe}, {mode: full}]}, {leds: {dock: true}}]}",
        "{sequence: [{mode: full}, {seek_dock: {wait: false}}, {mode: safe}, {play: 0}]}",
        "{sequence: [{mode: safe},"
        " {retry: {times: 3, do: {sequence: [{drive: {duration: 1s}}, wall]}}}]}",
        "{sequence: [{mode: safe}, {parallel: [{drive: {duration: 1s}}, {leds: {spot: true}}]}]}",
        "{sequence: [{mode: safe}, {wait: 1s, until: {bump: any}}, {stop: {}}]}",
        "{sequence: [{mode: safe}, {oneshot: {motors: {vacuum: true}}}, {vacuum: off}]}",
    ],
)
def test_actuators_after_a_mode_change_on_every_path(errors_of: Errors, tree: str) -> None:
    assert errors_of(f"tree: {tree}") == []


@pytest.mark.parametrize(
    "tree",
    [
        # the alternative taken when 'mode: safe' is never reached
        "{sequence: [{fallback: [wall, {mode: safe}]}, {vacuum: on}]}",
        # a repeat loops back to its start after seek_dock left the robot in Passive
        "{sequence: [{mode: safe},"
        " {repeat: {times: 2, do: {sequence: [{vacuum: on}, {seek_dock: {wait: false}}]}}}]}",
        # a parallel branch may change the mode under its sibling
        "{sequence: [{mode: safe}, {parallel: [{clean: {}}, {drive: {duration: 1s}}]}]}",
        # seek_dock fails by its own timeout after it sent Seek Dock: its end leaves Passive
        "{sequence: [{mode: safe},"
        " {fallback: [{seek_dock: {timeout: 2s}}, {drive: {duration: 1s}}]}]}",
        # a timeout may cut a sequence after clean and before safe
        "{sequence: [{mode: safe}, {force_success: {timeout: {after: 1s,"
        " do: {sequence: [clean, {mode: safe}]}}}}, {leds: {dock: true}}]}",
        # all Passive refuses of a leaf that stops, it refuses: the vacuum switched on
        "{sequence: [{mode: safe}, {mode: passive}, {motors: {vacuum: true, main_brush: false}}]}",
    ],
)
def test_paths_without_the_mode_change_are_found(errors_of: Errors, tree: str) -> None:
    [error] = errors_of(f"tree: {tree}")
    assert "accepted only in Safe or Full mode, but it can be reached in Passive mode" in error


def test_a_switch_read_from_the_blackboard_is_not_taken_for_off_in_passive(
    errors_of: Errors,
) -> None:
    """``vacuum: '@suck'`` may switch the vacuum on when it runs: not a stop, whatever the
    key's initial value."""
    text = "blackboard: {suck: {type: bool, initial: false}}\ntree: {vacuum: '@suck'}"
    [error] = errors_of(text)
    assert "accepted only in Safe or Full mode, but it can be reached in Passive mode" in error


@pytest.mark.parametrize(
    "tree",
    [
        "{sequence: [{mode: safe}, {drive: {duration: 1s}}, {mode: passive}, stop]}",
        "{sequence: [{mode: safe}, {vacuum: on}, {mode: passive}, {stop: {motors: true}}]}",
        "{sequence: [{mode: passive}, {motors: {}}, {vacuum: off}]}",
        "{sequence: [stop, {motors: {main_brush: false, side_brush_clockwise: true}}]}",
        # mode: passive ends a cycle it finds (Safe, drive 0, motors off, Start), as Safe does
        "{sequence: [{mode: safe}, clean, {mode: passive}, stop]}",
        "{sequence: [spot, {mode: safe}, {mode: passive}, stop]}",
        # the cycle's leaf failed: its end (Safe, drive 0, motors off, Start) ended the cycle
        "{sequence: [{mode: safe}, {inverter: {seek_dock: {timeout: 5s}}}, stop]}",
    ],
)
def test_a_stop_in_passive_with_no_cycle_is_accepted(errors_of: Errors, tree: str) -> None:
    """Decided in session 34 (docs/protocol.md, "Actuators in Passive"): Passive has
    stopped the wheels and motors, so ``stop`` there sends nothing and succeeds at run
    time (``Action.stopped_already``); ``motors`` and ``vacuum`` off too. ``validate``
    refused it wherever the tree could reach Passive, ``mode: passive`` included."""
    assert errors_of(f"tree: {tree}") == []


@pytest.mark.parametrize(
    ("tree", "started_by"),
    [
        ("{sequence: [{mode: safe}, clean, stop]}", "clean (line 1)"),
        ("{sequence: [{mode: safe}, max, {motors: {}}]}", "max (line 1)"),
        # a repeat loops back to its start after seek_dock left its cycle driving
        ("{sequence: [{mode: safe},"
         " {repeat: {times: 2, do: {sequence: [{stop: {}}, {seek_dock: {wait: false}}]}}}]}",
         "seek_dock(wait=false) (line 1)"),
        # a timeout may cut a sequence after clean and before safe
        ("{sequence: [{mode: safe},"
         " {force_success: {timeout: {after: 1s, do: {sequence: [clean, {mode: safe}]}}}}, stop]}",
         "clean (line 1)"),
    ],
)  # fmt: skip
def test_a_stop_where_a_cycle_the_tree_started_may_drive_is_refused(
    errors_of: Errors, tree: str, started_by: str
) -> None:
    """Drive 0 and Motors 0 are refused in Passive and cannot stop a Clean: the leaf fails
    there at run time, and validate names the leaf that started the cycle and the fix."""
    [error] = errors_of(f"tree: {tree}")
    assert f"can be reached in Passive while a built-in cycle started by {started_by}" in error
    assert "put mode: safe before it" in error


@pytest.mark.parametrize(
    "text",
    [
        pytest.param(
            """
            blackboard: {n: int}
            tree:
              sequence:
                - fallback:
                    - {sequence: [wall, {set: {key: n, value: 1}}]}
                    - {set: {key: n, value: 2}}
                - check: {key: n, value: 1}
            """,
            id="a key written on every path may be read",
        ),
        pytest.param(
            """
            blackboard: {leg: distance}
            tree:
              sequence:
                - mode: safe
                - for_each: {key: leg, in: [1 m], do: {drive: {distance: "@leg"}}}
                - drive: {distance: "@leg"}
            """,
            id="after a non-empty for_each its key holds its last item",
        ),
        pytest.param(
            """
            blackboard: {start: mark}
            tree: {sequence: [{mark: start}, {odometry: {since: start, distance: 1 m}}]}
            """,
            id="mark then odometry",
        ),
    ],
)
def test_blackboard_keys_accepted(errors_of: Errors, text: str) -> None:
    assert errors_of(text) == []


@pytest.mark.parametrize(
    ("text", "message"),
    [
        pytest.param(
            """
            blackboard: {n: int}
            tree:
              sequence:
                - fallback: [{sequence: [wall, {set: {key: n, value: 1}}]}, bump]
                - check: {key: n, value: 1}
            """,
            "reads blackboard key 'n' before anything writes it on some path",
            id="a key not written on every path",
        ),
        pytest.param(
            """
            blackboard: {leg: distance}
            tree: {set: {key: leg, value: 90deg}}
            """,
            "set.value: unknown distance unit 'deg' in '90deg'; use one of: mm, cm, m",
            id="a set value is typed by its key",
        ),
        pytest.param(
            """
            blackboard: {turn: angle}
            tree: {sequence: [{mode: safe}, {drive: {distance: "@turn"}}]}
            """,
            "blackboard key 'turn' holds angle (deg), but drive.distance needs distance (mm)",
            id="a blackboard value of another type",
        ),
    ],
)
def test_blackboard_keys_refused(errors_of: Errors, text: str, message: str) -> None:
    [error] = errors_of(text)
    assert message in error


SET_D, DRIVE_D = "{set: {key: d, value: 10cm}}", '{drive: {velocity: 200 mm/s, distance: "@d"}}'


@pytest.mark.parametrize(
    ("branches", "refused"),
    [
        ([SET_D, DRIVE_D], False),  # ticked in order: the set has written when the drive starts
        ([DRIVE_D, SET_D], True),
        (["{sequence: [{wait: 1s}, " + SET_D + "]}", DRIVE_D], True),  # writes later
        (["{sequence: [wall, " + SET_D + "]}", DRIVE_D], True),  # may fail before it writes
    ],
)
def test_a_parallel_s_branches_read_what_the_branches_before_them_wrote_at_once(
    errors_of: Errors, branches: list[str], refused: bool
) -> None:
    tree = f"{{sequence: [{{mode: safe}}, {{parallel: [{', '.join(branches)}]}}]}}"
    errors = errors_of(f"blackboard: {{d: distance}}\ntree: {tree}\n")
    unwritten = "reads blackboard key 'd' before anything writes it on some path"
    assert [unwritten in e for e in errors] == ([True] if refused else []), errors


def test_runtime_packets_and_stream_budget() -> None:
    assert {7, 9, 10, 11, 12, 34, 35, 43, 44} <= set(RUNTIME_PACKETS)
    assert check_stream((8,), 115200) is None
    problem = check_stream(tuple(range(46, 52)), 19200)
    assert problem is not None and "at 19200 baud" in problem
    # how to get the robot to the rate where it fits: it cannot be told from --baud alone
    assert problem.endswith(
        "; it fits at 115200: on the iRobot Create 2, 19200 comes after its Clean button was "
        "held while it powered off, until a descending tune, or three BRC pulses 2 s after "
        "power-on, and lasts until its processor loses battery power (take the battery out) or "
        "Baud (129) sets another rate (in Python, Connection.set_baud(115200) sends Baud (129); "
        "no roomba-bt command does)"
    )


@pytest.mark.parametrize(
    ("profile", "held", "back"),
    [
        ("roomba500", "held while it powered on", "until it is powered off or its battery is "
         "taken out"),
        ("roomba600", "held while it powered off", "until its processor loses battery power"),
    ],
)  # fmt: skip
def test_the_19200_advice_is_the_profiles_own(profile: str, held: str, back: str) -> None:
    """The 500 spec holds Clean "when powering on", the 600 spec "while powering off"; the
    advice gave the 600's to a 500, named "a Create 2", and sent the user to roomba-bt
    doctor for a Baud (129) no roomba-bt command sends."""
    from roomba_bt.oi.profiles import get_profile

    robot = get_profile(profile)
    problem = check_stream(tuple(range(46, 52)), 19200, robot)
    assert problem is not None
    assert f"on the {robot.title}, 19200 comes after its Clean button was {held}" in problem
    assert back in problem and "Connection.set_baud(115200) sends Baud (129)" in problem
    assert profile != "roomba500" or "Create 2" not in problem
    assert "roomba-bt doctor" not in problem


def test_baud_is_checked_per_mission(errors_of: Errors) -> None:
    text = "tree: {light_bumper: {threshold: 100}}"
    assert errors_of(text) == []
    [error] = errors_of(text, baud=19200)
    assert "do not fit the stream" in error


@pytest.mark.parametrize(
    ("params", "first"),
    [
        ({}, "2:3: parameter 't' has no default: give it with params={'t': 'VALUE'}"),
        ({"t": "soon"}, "2:3: parameter t=soon (given in params): expected a duration"),
    ],
    ids=["no-default", "bad-override"],
)
def test_a_parameter_without_a_value_is_reported_once(
    errors_of: Errors, params: dict[str, str], first: str
) -> None:
    """Its uses (a leaf, a subtree argument, a substitution in a text) are not reported
    again as unknown parameters: one mistake, one message."""
    errors = errors_of(
        """
        parameters:
          t: {type: duration}
        subtrees:
          pause:
            parameters: {d: {type: duration}}
            tree: {wait: "${d}"}
        tree:
          sequence:
            - wait: "${t}"
            - subtree: {id: pause, d: "${t}"}
            - log: "waited ${t}"
        """,
        params,
    )
    assert len(errors) == 1, errors
    assert errors[0].startswith(first)


BLIND = (
    "can turn the wheels in Full mode, where the robot does not stop at a cliff or a wheel "
    "drop, and no cliff sensor (packets 9-12) is read while it runs: use mode: safe, or end it "
    "on a cliff (until: {cliff: any})"
)
FULL_DRIVE = """
tree:
  sequence:
    - mode: {mode}
    - {extra}
    - drive: {{velocity: 200 mm/s, distance: 1 m}}
"""


@pytest.mark.parametrize(
    ("mode", "extra", "warned"),
    [
        ("full", "wait: 1s", ["5:7: drive"]),  # nothing reads a cliff: down the stairs
        ("full", "turn: 90deg", ["4:7: turn", "5:7: drive"]),  # each blind wheel leaf
        ("safe", "wait: 1s", []),  # Safe stops at a cliff by itself
        # read once, before the drive starts: the drive itself runs blind
        ("full", "cliff: {sensor: left}", ["5:7: drive"]),
        ("full", "leds: {dock: true}", ["5:7: drive"]),
        ("full", "stop", ["5:7: drive"]),  # stop sends Drive 0: it turns no wheel
    ],
)
def test_driving_in_full_with_no_cliff_sensor_read_is_a_warning(
    compile_text: Callable[..., CompiledMission], mode: str, extra: str, warned: list[str]
) -> None:
    mission = compile_text(FULL_DRIVE.format(mode=mode, extra=extra))  # compiles either way
    warnings = [f"{w.line}:{w.column}: {w.message}" for w in mission.warnings]
    assert warnings == [f"{where} {BLIND}" for where in warned]
    if warned:
        assert str(mission.warnings[0]).split(": ", 2)[1] == "warning"


@pytest.mark.parametrize(
    ("tree", "warned"),
    [
        # watched on every tick: a guard, an earlier child of a reactive composite, a
        # parallel branch ticked on every tick, or the leaf itself
        ("- drive: {velocity: 200 mm/s}\n  until: {cliff: any}", False),
        ("- drive: {velocity: 200 mm/s}\n  while: {inverter: {cliff: any}}", False),
        ("- reactive_sequence: [{inverter: {cliff: any}}, {drive: {velocity: 200 mm/s}}]", False),
        ("- reactive_fallback: [{cliff: any}, {drive: {velocity: 200 mm/s}}]", False),
        ("- parallel: {synchronise: false,"
         " children: [{drive: {velocity: 200 mm/s}}, {inverter: {cliff: any}}]}", False),
        ("- parallel: {policy: one, children: [{drive: {velocity: 200 mm/s}}, {cliff: any}]}",
         False),
        # a branch that never succeeds is ticked every tick, synchronised or not
        ("- parallel: [{drive: {velocity: 200 mm/s}}, {repeat: {do: {inverter: {cliff: any}}}}]",
         False),
        ("- parallel: [{drive: {velocity: 200 mm/s}},"
         " {wait: 1h, while: {inverter: {cliff: any}}, name: w}]", True),  # ends after 1 h
        ("- until: {cliff: any}\n  sequence: [{turn: 90deg}, {drive: {velocity: 200 mm/s}}]",
         False),
        ("- drive: {velocity: 200 mm/s}\n  while: {sensor: cliff_left == 0}", False),
        ("- drive: {velocity: 200 mm/s}\n  while: {sequence: [{inverter: {bump: any}},"
         " {inverter: {cliff: any}}]}", False),
        ("- drive: {velocity: 200 mm/s}\n"
         "  while: {timeout: {after: 1s, do: {inverter: {cliff: any}}}}", False),
        ("- cover: {}", False),
        # the cliff branch of a synchronised parallel succeeds on the first tick and is not
        # ticked again: the drive ran off the stairs with this (session 25)
        ("- parallel: [{drive: {velocity: 200 mm/s}}, {inverter: {cliff: any}}]", True),
        ("- parallel: {policy: selected, selected: [go], children:"
         " [{drive: {velocity: 200 mm/s}, name: go}, {inverter: {cliff: any}}]}", True),
        # read once, or read with a result that ends nothing
        ("- reactive_sequence: [{oneshot: {inverter: {cliff: any}}},"
         " {drive: {velocity: 200 mm/s}}]", True),
        ("- drive: {velocity: 200 mm/s}\n  while: {oneshot: {inverter: {cliff: any}}}", True),
        ("- parallel: {synchronise: false,"
         " children: [{drive: {velocity: 200 mm/s}}, {force_success: {cliff: any}}]}", True),
        ("- drive: {velocity: 200 mm/s}\n  until: {force_failure: {cliff: any}}", True),
        # read only when the sequence gets past its wait: not on every tick
        ("- parallel: {synchronise: false, children: [{drive: {velocity: 200 mm/s}},"
         " {repeat: {do: {sequence: [{wait: 100ms}, {inverter: {cliff: any}}]}}}]}", True),
        # a cliff that ends it the wrong way: runs only while a cliff is seen
        ("- drive: {velocity: 200 mm/s}\n  while: {cliff: any}", True),
        ("- drive: {velocity: 200 mm/s}\n  until: {inverter: {cliff: any}}", True),
        ("- reactive_sequence: [{cliff: any}, {drive: {velocity: 200 mm/s}}]", True),
        # not watched: a cliff read elsewhere, once, or after the drive
        ("- reactive_sequence: [{drive: {velocity: 200 mm/s}}, {inverter: {cliff: any}}]", True),
        ("- fallback: [{cliff: any}, {drive: {velocity: 200 mm/s}}]", True),
        ("- fallback: [{drive: {velocity: 200 mm/s, distance: 1 m}}, {cliff: any}]", True),
        ("- sequence: [{inverter: {cliff: any}}, {drive: {velocity: 200 mm/s}}]", True),
        ("- drive: {velocity: 200 mm/s}\n  until: {bump: any}", True),
        # held: a cliff ends it only after the hold (no stop at the edge); a cliff that
        # fails its child fails it at once (a while: ends the drive there)
        ("- drive: {velocity: 200 mm/s}\n  until: {held: {for: 1s, do: {cliff: any}}}", True),
        ("- drive: {velocity: 200 mm/s}\n"
         "  while: {held: {for: 15ms, do: {inverter: {cliff: any}}}}", False),
    ],
)  # fmt: skip
def test_the_full_mode_warning_asks_whether_a_cliff_is_read_while_the_wheels_turn(
    compile_text: Callable[..., CompiledMission], tree: str, warned: bool
) -> None:
    body = "\n".join("    " + line for line in tree.splitlines())
    mission = compile_text(f"tree:\n  sequence:\n    - mode: full\n{body}\n")
    full = [w for w in mission.warnings if "in Full mode" in w.message]  # not a dead end's
    assert [w.message.split(" ", 1)[0] for w in full] == (["drive"] if warned else []), tree


def test_a_subtree_used_twice_is_warned_at_its_place_once(
    compile_text: Callable[..., CompiledMission],
) -> None:
    mission = compile_text(
        """
subtrees:
  go:
    tree:
      drive: {velocity: 200 mm/s, distance: 1 m}
tree:
  sequence:
    - mode: full
    - subtree: go
    - subtree: go
    - subtree: go
      until: {cliff: any}
"""
    )
    assert [(w.line, w.column) for w in mission.warnings] == [(4, 7)]


def test_full_mode_without_wheels_is_no_warning(
    compile_text: Callable[..., CompiledMission],
) -> None:
    mission = compile_text("tree:\n  sequence:\n    - mode: full\n    - leds: {dock: true}\n")
    assert mission.warnings == ()


FULL_ITSELF = """
from py_trees.common import Status

from roomba_bt.behaviours import Action, declare
from roomba_bt.oi import commands
from roomba_bt.oi.opcodes import opcodes


@declare("faster", kind="action", sends=opcodes({sends}), reads={reads})
class Faster(Action):
    \"\"\"Switches to Full to go faster, and drives.\"\"\"

    def update(self):
        self.send(commands.full())
        self.send(commands.drive(300, 32768))
        return Status.RUNNING
"""


@pytest.mark.parametrize(
    ("sends", "reads", "warned"),
    [
        ('"full", "drive"', "()", True),  # not warned: entered in Safe, it drove 1 m in Full
        ('"full", "drive"', "(9, 10, 11, 12)", False),  # it reads the cliffs itself
        ('"safe", "drive"', "()", False),  # Safe stops at a cliff by itself
        ('"full", "leds"', "()", False),  # Full, but no wheels
    ],
)
def test_a_leaf_that_switches_to_full_itself_and_drives_is_warned(
    mission_file: Callable[..., Path], sends: str, reads: str, warned: bool
) -> None:
    """The check asked only for the modes a leaf is entered in (stranger report, session 36:
    ``declared_full`` entered in Safe sent Full and drove, with ``validate --strict`` ok)."""
    mission_file(FULL_ITSELF.format(sends=sends, reads=reads), "faster.py")
    path = mission_file("plugins: [./faster.py]\ntree:\n  sequence: [{mode: safe}, faster]\n")
    mission = load_mission(path, permissions=Permissions(plugin_files=True))
    assert [f"{w.line}:{w.column}: {w.message}" for w in mission.warnings] == (
        [
            "3:28: faster switches to Full mode itself and can turn the wheels there, where "
            "the robot does not stop at a cliff or a wheel drop, and no cliff sensor (packets "
            "9-12) is read while it runs: end it on a cliff (until: {cliff: any})"
        ]
        if warned
        else []
    )


#: an action that goes to Full itself, drives, and goes back to Safe (its drive is elided)
PASSES_FULL = """
from py_trees.common import Status

from roomba_bt.behaviours import Action, declare
from roomba_bt.oi import commands
from roomba_bt.oi.modes import OIMode
from roomba_bt.oi.opcodes import opcodes


@declare("dash", kind="action", sends=opcodes("full", "drive", "safe"),
         passes_through=OIMode.FULL, leads_to=OIMode.SAFE, reads={reads})
class Dash(Action):
    \"\"\"Dashes in Full, and goes back to Safe.\"\"\"

    def update(self):
        self.send(commands.full())
        self.send(commands.safe())
        return Status.SUCCESS
"""

#: the drive the mission puts after it
AFTER_DASH = "drive: {velocity: 100 mm/s, duration: 1s}"


@pytest.mark.parametrize(
    ("tree", "reads", "warned"),
    [
        (f"sequence: [{{mode: safe}}, dash, {{{AFTER_DASH}}}]", "(9, 10, 11, 12)", []),
        (f"sequence: [{{mode: safe}}, dash, {{{AFTER_DASH}}}]", "()",
         ["3:28: dash switches to Full mode itself and can turn the wheels there"]),
        (f"sequence: [{{mode: safe}}, selector: [dash, {{{AFTER_DASH}}}]]", "(9, 10, 11, 12)",
         ["3:46: drive can turn the wheels in Full mode"]),
    ],
    ids=["after its success: in Safe", "it does not read the cliffs", "after its failure"],
)  # fmt: skip
def test_a_leaf_that_passes_through_full_is_judged_in_the_modes_it_may_end_in(
    mission_file: Callable[..., Path], tree: str, reads: str, warned: list[str]
) -> None:
    """``passes_through=OIMode.FULL``, ``leads_to=OIMode.SAFE``: a drive after its success
    is judged in Safe, one on the fallback after its failure in Full too (it may fail on
    its way, in Full), and the leaf itself is warned of as any that sends Full and drives."""
    mission_file(PASSES_FULL.format(reads=reads), "dash.py")
    path = mission_file(f"plugins: [./dash.py]\ntree:\n  {tree}\n")
    mission = load_mission(path, permissions=Permissions(plugin_files=True))
    said = [f"{w.line}:{w.column}: {w.message}" for w in mission.warnings]
    assert [m.split(",")[0] for m in said] == warned, said


#: an action that sends its own Safe, then drives: reached in Passive, its Safe comes first
SAFE_FIRST = """
from py_trees.common import Status

from roomba_bt.behaviours import Action, declare
from roomba_bt.oi import commands
from roomba_bt.oi.opcodes import opcodes


@declare("creep_safe", kind="action", sends=opcodes("safe", "drive"){declared})
class CreepSafe(Action):
    \"\"\"Takes Safe itself, then creeps.\"\"\"

    def start(self):
        self.send(commands.safe())

    def update(self):
        self.send(commands.drive_straight(100))
        return Status.RUNNING
"""


@pytest.mark.parametrize(
    ("declared", "tree", "said"),
    [
        ("", "sequence: [creep_safe]",  # refused: the check cannot know the Safe comes first
         ["3:14: creep_safe sends Drive (137), accepted only in Safe or Full mode, but it can "
          "be reached in Passive mode: put a mode change (mode: safe or mode: full) before it "
          "on every path; or, if creep_safe sends its own Safe (131) before any other command "
          "each time it starts, say so in its @declare with mode_first=True (held to when it "
          "runs)"]),
        (", mode_first=True", "sequence: [creep_safe]", []),
        # a drive on the fallback after its failure: it may have failed in its own Safe, or
        # before its Safe, in the Passive it was reached in
        (", mode_first=True", f"selector: [creep_safe, {{{AFTER_DASH}}}]",
         ["3:27: drive sends Drive (137), Drive Direct (145), accepted only in Safe or Full "
          "mode, but it can be "
          "reached in Passive mode: put a mode change (mode: safe or mode: full) before it on "
          "every path"]),
        (", mode_first=True", f"sequence: [creep_safe, {{{AFTER_DASH}}}]", []),
    ],
    ids=["undeclared", "mode_first", "a drive after its failure", "a drive after its success"],
)  # fmt: skip
def test_a_mode_first_leaf_may_be_reached_in_passive(
    mission_file: Callable[..., Path],
    errors_of: Callable[..., list[str]],
    declared: str,
    tree: str,
    said: list[str],
) -> None:
    """A plugin leaf that sends its own Safe first was refused in Passive for its drive:
    the check cannot know the order of what a leaf sends. ``mode_first=True`` says it (held
    to at ``send()``), and the check judges its Safe where it is reached, its drive in Safe;
    the leaves after it as before. A leaf that does not say it is refused as before, and
    told of the word."""
    mission_file(SAFE_FIRST.format(declared=declared), "creep.py")
    got = errors_of(
        f"plugins: [./creep.py]\ntree:\n  {tree}\n", permissions=Permissions(plugin_files=True)
    )
    assert got == said


def test_a_drive_after_a_mode_first_leaf_s_failure_is_judged_in_its_mode_too(
    mission_file: Callable[..., Path],
) -> None:
    """A ``mode_first`` leaf may fail after its first command: in the mode that took it to
    (Full, here), where the drive on the fallback after it then runs, warned of as in Full."""
    full_first = SAFE_FIRST.replace('"safe", "drive"', '"full", "drive"')
    mission_file(full_first.format(declared=", reads=(9, 10, 11, 12), mode_first=True"), "c.py")
    path = mission_file(
        f"plugins: [./c.py]\ntree:\n  sequence: [{{mode: safe}}, selector: [creep_safe, "
        f"{{{AFTER_DASH}}}]]\n"
    )
    mission = load_mission(path, permissions=Permissions(plugin_files=True))
    said = [f"{w.line}:{w.column}: {w.message.split(',')[0]}" for w in mission.warnings]
    assert said == ["3:52: drive can turn the wheels in Full mode"], said


SENSOR_UNTIL = (
    "tree:\n  sequence:\n    - mode: safe\n    - drive: {{velocity: 100 mm/s}}\n"
    "      until: {{sensor: '{test}'}}\n"
)


@pytest.mark.parametrize(
    ("test", "message"),
    [
        ("stasis == 7", "'stasis == 7' can never be true on any OI robot: stasis reads 0..3"),
        ("wall_signal > 5000", "'wall_signal > 5000' can never be true on any OI robot: "
         "wall_signal reads 0..4095"),
        ("wall_signal >= 0", "'wall_signal >= 0' is always true on any OI robot: wall_signal "
         "reads 0..4095"),
        ("charging_state != 2.5", "'charging_state != 2.5' is always true on any OI robot: "
         "charging_state reads 0..5"),
        ("left_encoder_counts > 65535", "'left_encoder_counts > 65535' can never be true on "
         "any OI robot: left_encoder_counts reads -32768..65535"),
    ],
)  # fmt: skip
def test_a_sensor_test_no_reading_can_change_is_an_error(
    errors_of: Callable[..., list[str]], test: str, message: str
) -> None:
    """``until: {sensor: stasis == 7}`` validated and drove until the timeout: a test whose
    answer no robot's reading can change is an error where it is written."""
    assert errors_of(SENSOR_UNTIL.format(test=test)) == [f"5:23: sensor.test: {message}"]


def _warnings_on(path: Path, profile: str) -> list[str]:
    """The warnings of compiling ``path`` for ``profile``, as ``line:column: message``."""
    from roomba_bt.mission import load_mission
    from roomba_bt.oi.profiles import get_profile

    mission = load_mission(path, profile=get_profile(profile))
    return [f"{w.line}:{w.column}: {w.message}" for w in mission.warnings]


@pytest.mark.parametrize(
    ("test", "profile", "warned"),
    [
        ("stasis == 2", "roomba500",
         "can never be true on the Roomba 500 series: stasis reads 0..1"),
        ("stasis == 2", "create2", ""),
        ("left_encoder_counts < 0", "roomba500", "can never be true on the Roomba 500 series: "
         "left_encoder_counts reads 0..65535"),
        ("left_encoder_counts < 0", "roomba600", ""),
        ("wall_signal > 2000", "roomba600", "can never be true on the Roomba 600 series: "
         "wall_signal reads 0..1023"),
        ("wall_signal > 2000", "roomba500", ""),
        ("wall_signal <= 1023", "create2", "is always true on the iRobot Create 2"),
    ],
)  # fmt: skip
def test_a_sensor_test_the_chosen_robot_cannot_change_is_a_warning(
    mission_file: Callable[..., Path], test: str, profile: str, warned: str
) -> None:
    """A range narrower on one model (a Roomba 500's stasis 0..1, its unsigned encoders, a
    600's wall signal 0..1023) is warned of under that ``--profile``: the mission compiles
    (it may be meant for another model too)."""
    found = _warnings_on(mission_file(SENSOR_UNTIL.format(test=test)), profile)
    if warned:
        assert len(found) == 1 and found[0].startswith(f"5:23: sensor.test: '{test}' {warned}")
    else:
        assert found == []


@pytest.mark.parametrize(
    ("state", "profile", "warned"),
    [
        ("dirty", "roomba500", "'stasis == 2' can never be true on the Roomba 500 series: "
         "stasis reads 0..1"),
        ("dirty", "create2", ""),
        ("stuck", "roomba500", ""),
        ("moving", "roomba500", ""),
    ],
)  # fmt: skip
def test_stasis_dirty_is_warned_of_on_the_500_as_stasis_equals_2_is(
    mission_file: Callable[..., Path], state: str, profile: str, warned: str
) -> None:
    """``until: {stasis: dirty}`` validated silently on roomba500 (stasis reads 0..1: it never
    fires) while ``sensor: stasis == 2`` warned: the word is the same test, one check."""
    text = SENSOR_UNTIL.format(test="x").replace("{sensor: 'x'}", f"{{stasis: {state}}}")
    found = _warnings_on(mission_file(text), profile)
    assert found == ([f"5:23: stasis: {state}: {warned}"] if warned else [])


RESTARTED = "which starts it again on the next tick when it fails and a later child runs"


@pytest.mark.parametrize(
    ("children", "refused"),
    [
        # a later child that keeps running: the fallback is ticked again, the limit starts over
        ("[{timeout: {after: 1s, do: {drive: {velocity: 200 mm/s}}}}, {wait: 1s}]", True),
        ("[{timeout: {after: 1s, do: {drive: {velocity: 200 mm/s}}}}, bump,"
         " {drive: {velocity: 100 mm/s}}]", True),  # the bump fails at once: the drive runs
        ("[{retry: {times: 2, do: {drive: {velocity: 200 mm/s}}}}, {wait: 1s}]", True),
        # every later child ends on the tick it starts: the fallback ends when the limit
        # fails, and is not started again (r_nested, session 25: refused before)
        ("[{sequence: [{inverter: {bump: any}},"
         " {timeout: {after: 1s, do: {drive: {velocity: 200 mm/s}}}}]}, stop]", False),
        ("[{timeout: {after: 1s, do: {drive: {velocity: 200 mm/s}}}}, bump, {log: gave up}]",
         False),
        ("[{timeout: {after: 1s, do: {drive: {velocity: 200 mm/s}}}}, stop,"
         " {drive: {velocity: 100 mm/s}}]", False),  # stop succeeds: the drive is never reached
        ("[{retry: {times: 2, do: {drive: {velocity: 200 mm/s, duration: 1s}}}}, bump]", False),
    ],
)  # fmt: skip
def test_a_limit_a_reactive_fallback_restarts_is_refused_only_when_a_later_child_runs_on(
    errors_of: Errors, children: str, refused: bool
) -> None:
    for fallback in ("reactive_fallback: ", "fallback: {memory: false, children: "):
        close = "}" if "children" in fallback else ""
        text = f"tree:\n  sequence:\n    - mode: safe\n    - {fallback}{children}{close}\n"
        errors = errors_of(text)
        assert [RESTARTED in e for e in errors] == ([True] if refused else []), (text, errors)


#: the keys' parallel: their declarations and a subtree that writes one (branches from
#: line 10)
KEYED = """blackboard:
  n: int
  at: mark
subtrees:
  writer:
    parameters: {v: {type: int}}
    tree: {set: {key: n, value: "${v}"}}
tree:
  parallel:"""

#: for each check, the mission around its parallel (the branches go under ``parallel:``),
#: what its warning says a node does, where the parallel is, and what the warning says
#: comes of it
TWO_BRANCHES = {
    "wheels": ("tree:\n  sequence:\n    - mode: safe\n    - parallel:", "turns the wheels", "4:7",
               "only the last wheel command of a tick reaches the robot"),
    "keys": (KEYED, "writes blackboard key", "9:3", "the last write wins"),
}  # fmt: skip


@pytest.mark.parametrize(
    ("check", "branches", "warned"),
    [
        # two_drives (session 25): only the spin reached the robot; the distance drive ran on,
        # stopped, until --timeout
        ("wheels", ["{drive: {velocity: 200 mm/s, distance: 50cm}}",
                    "{drive: {velocity: 100 mm/s, radius: spin_left, duration: 1s}}"],
         ["6:12 drive ... drive (line 5)"]),
        ("wheels", ["{sequence: [{wait: 1s}, {turn: 90deg}]}", "{wait: 1s}",
                    "{drive: {velocity: 100 mm/s}, until: {bump: any}}"],
         ["7:12 drive ... turn (line 5)"]),
        ("wheels",
         ["{turn: 90deg}", "{drive: {velocity: 100 mm/s, duration: 1s}}",
          "{drive: {velocity: 50 mm/s, duration: 1s}}"],
         ["6:12 drive ... turn (line 5)", "7:12 drive ... turn (line 5)"]),
        # one wheel branch; a stop only halts; a sequence runs its drives one after the other
        ("wheels", ["{drive: {velocity: 200 mm/s, duration: 1s}}", "{leds: {dock: true}}",
                    "wall"], []),
        ("wheels", ["{drive: {velocity: 200 mm/s, duration: 1s}}", "stop"], []),
        ("wheels",
         ["{sequence: [{turn: 90deg}, {drive: {velocity: 200 mm/s, duration: 1s}}]}", "wall"],
         []),
        # bb.yaml (the py_trees expert, session 34): two uses of one subtree set n to 1 and
        # 2 in a parallel, and the check after it saw 2, silently
        ("keys", ["{subtree: {id: writer, v: 1}}", "{subtree: {id: writer, v: 2}}"],
         ["7:12 set(key=n, value=2) ... set(key=n, value=1) (line 7)"]),
        ("keys", ["{set: {key: n, value: 1}}", "{wait: 1s}", "{set: {key: n, value: 2}}"],
         ["12:8 set(key=n, value=2) ... set(key=n, value=1) (line 10)"]),
        ("keys", ["{mark: at}", "{sequence: [{wait: 1s}, {mark: at}]}"],
         ["11:32 mark(at) ... mark(at) (line 10)"]),
        ("keys", ["{for_each: {key: n, in: [1, 2], do: {wait: 1s}}}", "{set: {key: n, value: 3}}"],
         ["11:8 set(key=n, value=3) ... for_each (line 10)"]),
        # one writer a key; two writes in one branch, one after the other
        ("keys", ["{set: {key: n, value: 1}}", "{mark: at}"], []),
        ("keys",
         ["{sequence: [{set: {key: n, value: 1}}, {set: {key: n, value: 2}}]}", "{mark: at}"],
         []),
    ],
)  # fmt: skip
def test_two_branches_of_a_parallel_that_claim_one_thing_are_warned_of(
    compile_text: Callable[..., CompiledMission],
    check: str,
    branches: list[str],
    warned: list[str],
) -> None:
    """Two branches turning the wheels (only the last wheel command of a tick reaches the
    robot), or writing one blackboard key (the last write of a tick wins, by the branches'
    order): said at the later node, naming the first (a subtree used twice at its one
    place), each a warning. Every warning of the mission is such a one, as
    ``line:col later ... first (line N)``."""
    head, claim, parallel_at, outcome = TWO_BRANCHES[check]
    indent = " " * (len(head.rsplit("\n", 1)[-1]) - len("parallel:") + 2)  # under its key
    mission = compile_text(head + "".join(f"\n{indent}- {branch}" for branch in branches) + "\n")
    said = []
    for w in mission.warnings:
        assert f" {claim} " in w.message and w.severity == "warning", w
        assert outcome in w.message, w.message
        later, rest = w.message.split(f" {claim} ", 1)
        assert f"in one branch of the parallel ({parallel_at}) and " in rest, w.message
        first = rest.split(" and ", 1)[1].split(" in another")[0]
        said.append(f"{w.line}:{w.column} {later} ... {first}")
    assert said == warned


@pytest.mark.parametrize(
    ("children", "warned"),
    [
        # stutter (session 26): the drive started again every 315 ms, for ever
        ("[{wait: 300ms}, {drive: {velocity: 200 mm/s, distance: 30cm}}]",
         ["wait(300ms) ... stops drive(velocity=200 mm/s, distance=30cm) (line 4)"]),
        ("[{inverter: {bump: any}}, {turn: 90deg}, {wait: 1s}, wall]",
         ["turn(90deg left) ... stops wait(1s) (line 4)"]),
        # conditions, stop, a mode already entered, a oneshot end at once when ticked again;
        # a running child whose later ones all end at once ends the sequence with them
        ("[{inverter: {bump: any}}, {drive: {velocity: 200 mm/s, distance: 30cm}}]", []),
        ("[stop, {mode: safe}, {oneshot: {wait: 1s}}, {drive: {velocity: 200 mm/s}}]", []),
        ("[{drive: {velocity: 200 mm/s}}, {inverter: {cliff: any}}, {log: done}]", []),
    ],
)  # fmt: skip
def test_a_child_a_reactive_sequence_restarts_before_a_running_one_is_warned_of(
    compile_text: Callable[..., CompiledMission], children: str, warned: list[str]
) -> None:
    for sequence in ("reactive_sequence: ", "sequence: {memory: false, children: "):
        close = "}" if "children" in sequence else ""
        text = f"tree:\n  sequence:\n    - mode: safe\n    - {sequence}{children}{close}\n"
        mission = compile_text(text)
        restarts = [w for w in mission.warnings if "may be RUNNING" in w.message]  # no dead end
        said = [
            f"{w.message.split(' may be RUNNING')[0]} ... "
            + w.message.split("succeeds: it ")[1].split(" and starts")[0]
            for w in restarts
        ]
        assert said == warned, text
        for w in restarts:
            assert (
                w.line == 4
                and f"not the last child of the {sequence.split(':')[0]} (4:7)" in w.message
            )
            assert "from the start on every tick after it succeeds" in w.message
            assert w.severity == "warning"


def test_a_restarting_child_in_a_subtree_used_twice_is_warned_of_once(
    mission_file: Callable[..., Path],
) -> None:
    """Each use compiles the body again: the same place, said once."""
    from roomba_bt.mission import load_mission

    body = "[{wait: 300ms}, {drive: {velocity: 100 mm/s, distance: 10cm}}]"
    path = mission_file(
        f"subtrees: {{s: {{tree: {{reactive_sequence: {body}}}}}}}\n"
        "tree: {sequence: [{mode: safe}, {subtree: s}, {subtree: s}]}\n"
    )
    warned = [(w.line, w.message.split(" ", 1)[0]) for w in load_mission(path).warnings]
    assert warned == [(1, "wait(300ms)")]


#: the error of a branch a non-synchronised parallel would start over
RERUN = "can succeed, and the parallel (4:7) has synchronise: false"


@pytest.mark.parametrize(
    ("policy", "branches", "refused"),
    [
        # p_sync (session 28): the 20 cm drive drove 20 cm eleven times (2.23 m) and the
        # parallel ran until --fast's two hours; ps3: two waits of 1 s and 1.5 s took 103 s
        ("all", ["{drive: {velocity: 200 mm/s, distance: 20cm}}", "{wait: 3s}"],
         ["8:14 drive(velocity=200 mm/s, distance=20cm)", "9:14 wait(3s)"]),
        ("all", ["{wait: 1s}", "{repeat: {do: {inverter: {cliff: any}}}}"], ["8:14 wait(1s)"]),
        ("all", ["{log: hi}", "{repeat: {do: {wait: 1s}}}"], ["8:14 log(hi)"]),
        ("all", ["{repeat: {times: 2, do: {turn: 90deg}}}", "{repeat: {do: {wait: 1s}}}"],
         ["8:14 repeat"]),
        ("all", ["{sequence: [{bump: any}, {delay: {for: 1s, do: {bump: any}}}]}",
                 "{repeat: {do: {wait: 1s}}}"], ["8:14 sequence"]),
        # a guarded branch is said as the node it guards
        ("all", ["{wait: 1s, until: {bump: any}, name: w}", "{repeat: {do: {wait: 1s}}}"],
         ["8:14 w"]),
        ("all", ["{wait: 1s, while: {inverter: {bump: any}}, name: w}", "{wait: 2s}"],
         ["8:14 w", "9:14 wait(2s)"]),
        # a branch beside one that may still be RUNNING, however deep: a oneshot of a drive,
        # a sequence with a wait, a guarded drive
        ("all", ["{drive: {velocity: 200 mm/s, distance: 20cm}}",
                 "{oneshot: {drive: {velocity: 100 mm/s, distance: 10cm}}}"],
         ["8:14 drive(velocity=200 mm/s, distance=20cm)"]),
        ("all", ["{log: hi}", "{sequence: [{bump: any}, {wait: 1s}]}"], ["8:14 log(hi)"]),
        ("all", ["{turn: 90deg}", "{drive: {velocity: 100 mm/s}, while: {inverter: {bump: any}}}"],
         ["8:14 turn(90deg left)"]),
        # policy selected waits for the selected branches only: one not selected keeps
        # nothing running, and is itself started over while a selected one runs
        ("selected\n        selected: [w]", ["{wait: 1s, name: w}", "{repeat: {do: {wait: 1s}}}"],
         []),
        ("selected\n        selected: [w]", ["{wait: 1s, name: w}", "{log: hi}"],
         ["10:14 log(hi)"]),
        ("selected\n        selected: [w, v]", ["{wait: 1s, name: w}", "{wait: 2s, name: v}"],
         ["9:14 w", "10:14 v"]),
        ("selected\n        selected: [c]", ["{drive: {velocity: 200 mm/s, distance: 20cm}}",
                                          "{inverter: {cliff: any}, name: c}"], []),
        # beside branches that end on every tick (conditions, held, and composites and
        # decorators of them) the parallel ends on the tick the action succeeds (every
        # branch succeeded) or has failed before: nothing is started over. The watcher the
        # docs advised before session 28, and a wait beside conditions
        ("all", ["{drive: {velocity: 200 mm/s, distance: 20cm}}", "{inverter: {cliff: any}}"],
         []),
        ("all", ["{wait: 1s}", "{inverter: {cliff: any}}"], []),
        ("all", ["{wait: 1s, while: {inverter: {bump: any}}, name: w}", "{inverter: {cliff: any}}"],
         []),
        ("all", ["{turn: 90deg}", "{inverter: {held: {for: 1s, do: {bump: any}}}}",
                 "{sequence: [{inverter: {bump: any}}, {inverter: {cliff: any}}]}",
                 "{parallel: [{inverter: {wheel_drop: any}}, {timeout: {after: 1s, do: {inverter:"
                 " {cliff: any}}}}]}", "{bump: any, until: {cliff: any}, name: b}"],
         []),
        # what starts nothing over: conditions, held, a oneshot (it answers as the first
        # time), a branch that never succeeds (a drive with no end, a repeat for ever)
        ("all", ["{oneshot: {drive: {velocity: 200 mm/s, distance: 20cm}}}",
                 "{inverter: {cliff: any}}", "{inverter: {held: {for: 1s, do: {bump: any}}}}",
                 "{sequence: [{bump: any}, {inverter: {cliff: any}}]}"], []),
        ("all", ["{drive: {velocity: 200 mm/s}}", "{repeat: {do: {wait: 1s}}}",
                 "{drive: {velocity: 200 mm/s}, while: {inverter: {bump: any}}}",
                 "{wall_follow: {}}", "{dock_time_limit: 1min}"], []),
        # policy one ends at the first success: nothing is ticked after it
        ("one", ["{drive: {velocity: 200 mm/s, distance: 20cm}}", "{wait: 3s}"], []),
    ],
)  # fmt: skip
def test_a_branch_a_non_synchronised_parallel_would_start_over_is_refused(
    errors_of: Errors, policy: str, branches: list[str], refused: list[str]
) -> None:
    """py_trees' own semantics are kept (a branch that succeeded is ticked again, and starts
    over); what would re-run an action or a clock is refused where it is written."""
    items = "".join(f"\n          - {branch}" for branch in branches)
    text = (
        "tree:\n  sequence:\n    - mode: safe\n    - parallel:\n"
        f"        policy: {policy}\n        synchronise: false\n        children:{items}\n"
    )
    errors = errors_of(text)
    assert [e.split(f" {RERUN}")[0].replace(": ", " ", 1) for e in errors] == refused, errors
    for error in errors:
        assert "write synchronise: true (the default) to run it once" in error
        assert "under oneshot" in error and "repeat (no times or for)" in error


def test_the_error_names_the_branch_that_keeps_the_parallel_running(errors_of: Errors) -> None:
    """The 2.23 m case: the drive is started over because the wait beside it still runs."""
    errors = errors_of(
        "tree:\n  sequence:\n    - mode: safe\n    - parallel:\n        synchronise: false\n"
        "        children:\n          - drive: {velocity: 200 mm/s, distance: 20cm}\n"
        "          - wait: 3s\n"
    )
    assert errors[0].startswith(
        "7:13: drive(velocity=200 mm/s, distance=20cm) can succeed, and the parallel (4:7) has "
        "synchronise: false and waits for wait(3s) (line 8), which may still be RUNNING then"
    )


def test_a_branch_beside_one_not_built_is_not_judged(errors_of: Errors) -> None:
    """Whether a misspelt branch could keep the parallel running is not known: its own
    error is said, not a restart it may not cause."""
    errors = errors_of(
        "tree:\n  sequence:\n    - mode: safe\n    - parallel:\n        synchronise: false\n"
        "        children:\n          - drive: {velocity: 200 mm/s, distance: 20cm}\n"
        "          - wiat: 3s\n"
    )
    assert len(errors) == 1 and errors[0].startswith("8:13: unknown node 'wiat'"), errors


#: The cliff watcher docs/missions.md advised before session 28 ("`synchronise: false` on a
#: watching parallel", e80f20a), as an owner wrote it from those docs
OLD_DOCS_WATCHER = """\
mission: watched-full
parameters:
  dist: {type: distance, default: 20cm}
tree:
  sequence:
    - mode: full
    - parallel:
        synchronise: false
        children:
          - drive: {velocity: 200 mm/s, distance: "${dist}"}
          - inverter: {cliff: any}
    - mode: safe
    - stop
"""


def test_the_old_docs_cliff_watcher_is_accepted_and_drives_its_distance_once(
    mission_file: Callable[..., Path], capsys: pytest.CaptureFixture[str]
) -> None:
    """Beside a condition the parallel ends on the tick the drive succeeds (both succeed)
    or fails before (a cliff): the drive is never started over. Watched on every tick, so
    no Full-mode warning either; on the simulator it drives 20 cm, once."""
    from roomba_bt.cli import main
    from roomba_bt.mission import load_mission

    path = mission_file(OLD_DOCS_WATCHER)
    assert not load_mission(path).warnings
    code = main(["run", str(path), "--fast", "--display", "none", "--timeout", "1min"])
    out = capsys.readouterr().out
    assert code == 0, out
    assert "outcome      SUCCESS" in out and "distance     0.20 m" in out, out


# ------------------------------------------------------------------ songs


#: a song slot played that no song defines, or defined that no play plays (checks.song_slots):
#: (the mission, the warning's line and column, how it begins, the fix it names)
SLOT_WARNINGS = [
    pytest.param(
        """
mission: typo
tree:
  sequence:
    - song: {number: 0, notes: [C4 100ms]}
    - mode: safe
    - play: 3
    - play: 0
""",
        (6, 13),
        "play: song 3 is not defined by this mission (its song slots: 0)",
        "kept until it is switched off",
        id="a play of a slot no song defines",
    ),
    pytest.param(
        """
mission: silent tune
tree:
  sequence:
    - mode: safe
    - song: {number: 1, notes: [C4 125ms, E4 125ms]}
    - song: {number: 2, notes: [G4 250ms]}
    - play: 2
""",
        (5, 22),
        "song: song 1 is stored but no `play` of this mission plays it",
        "add `play: 1` where it should sound",
        id="a song no play plays",
    ),
]


@pytest.mark.parametrize(("text", "where", "begins", "fix"), SLOT_WARNINGS)
def test_a_song_slot_played_and_not_defined_or_defined_and_not_played_is_a_warning(
    compile_text: Callable[..., CompiledMission],
    text: str,
    where: tuple[int, int],
    begins: str,
    fix: str,
) -> None:
    """``play: 3`` where only slot 0 is written validated silently (a typo; the robot may
    hold a song from earlier, or none); a stranger's mission (session 41) stored a tune with
    ``song`` and never played it: ``validate`` said ok, and the run succeeded in silence.
    Each is a warning at the slot's number."""
    mission = compile_text(text)
    assert [(w.line, w.column) for w in mission.warnings] == [where]
    said = mission.warnings[0].message
    assert said.startswith(begins)
    assert fix in said


def test_a_song_of_the_default_slot_is_warned_at_the_song(
    compile_text: Callable[..., CompiledMission],
) -> None:
    mission = compile_text(
        "tree:\n  sequence:\n    - mode: safe\n    - song: {notes: [C4 100ms]}\n"
    )
    assert [(w.line, w.column, w.message[:12]) for w in mission.warnings] == [
        (4, 7, "song: song 0")
    ]


@pytest.mark.parametrize(("song", "play"), [('"@slot"', "1"), ("1", '"@slot"')])
def test_a_slot_a_blackboard_key_holds_is_no_warning(
    compile_text: Callable[..., CompiledMission], song: str, play: str
) -> None:
    """The slot a key holds is known only when the run reads it: the song it may define,
    the play it may play."""
    mission = compile_text(
        f"""
mission: by key
blackboard:
  slot: {{type: int, initial: 1}}
tree:
  sequence:
    - song: {{number: {song}, notes: [C4 100ms]}}
    - mode: safe
    - play: {play}
"""
    )
    assert not mission.warnings


PLAYS_ITSELF = """
from py_trees.common import Status

from roomba_bt.behaviours import Action, declare
from roomba_bt.oi import commands
from roomba_bt.oi.opcodes import opcodes


@declare("fanfare", kind="action", sends=opcodes({sends}))
class Fanfare(Action):
    \"\"\"Plays slot 3.\"\"\"

    def update(self):
        self.send(commands.play(3))
        return Status.SUCCESS
"""


@pytest.mark.parametrize(("sends", "warned"), [('"play"', False), ('"leds"', True)])
def test_a_song_a_plugin_may_play_is_no_warning(
    mission_file: Callable[..., Path], sends: str, warned: bool
) -> None:
    """A plugin's leaf that declares it sends Play may play any slot: nothing is said."""
    mission_file(PLAYS_ITSELF.format(sends=sends), "fanfare.py")
    path = mission_file(
        "plugins: [./fanfare.py]\ntree:\n  sequence:\n    - mode: safe\n"
        "    - song: {number: 3, notes: [C4 100ms]}\n    - fanfare\n"
    )
    mission = load_mission(path, permissions=Permissions(plugin_files=True))
    assert [w.message.startswith("song: song 3 is stored") for w in mission.warnings] == (
        [True] if warned else []
    )


@pytest.mark.parametrize(
    ("count", "parts"),
    [(17, ["[notes 1-16]", "[note 17]"]), (40, ["[notes 1-16]", "[notes 17-32]", "[notes 33-40]"])],
)
def test_a_song_over_16_notes_says_how_to_split_it(
    errors_of: Callable[..., list[str]], count: int, parts: list[str]
) -> None:
    notes = ", ".join(["C4 100ms"] * count)
    errors = errors_of(
        f"""
mission: long
tree:
  sequence:
    - mode: safe
    - song: {{number: 0, notes: [{notes}]}}
    - play: 0
"""
    )
    assert len(errors) == 1
    said = f"a song has at most 16 notes, got {count}: split it into {len(parts)} songs"
    assert said in errors[0]
    for slot, part in enumerate(parts):
        assert f"`song: {{number: {slot}, notes: {part}}}`" in errors[0]
        assert f"`play: {slot}`, `{{wait: 30s, until: {{sensor: song_playing == 0}}}}`" in errors[0]


BUTTON_IN_PASSIVE = """
tree:
  sequence:
    - {first}
    - wait: 10s
      until: {{button: {name}}}
"""
_EACH = "each start a cycle of its own"
_STARTS = "(the OI spec; the run ends at the press); put `mode: safe` first (Safe and Full "


@pytest.mark.parametrize(
    ("first", "name", "warned"),
    [
        ("wait: 1s", "clean", "the robot's Clean button starts its own cleaning cycle"),
        ("wait: 1s", "spot", "the robot's Spot button starts its own spot cycle"),
        ("wait: 1s", "dock", "the robot's Dock button starts its own search for its dock"),
        ("wait: 1s", "any", f"the robot's Clean, Spot and Dock buttons {_EACH}"),
        ("mode: passive", "clean", "the robot's Clean button starts its own cleaning cycle"),
        ("wait: 1s", "minute", ""),  # starts nothing
        ("mode: safe", "clean", ""),  # Safe takes no cycle at a button
        ("mode: full", "any", ""),
    ],
)
def test_a_button_that_starts_a_cycle_waited_for_in_passive_is_a_warning(
    compile_text: Callable[..., CompiledMission], first: str, name: str, warned: str
) -> None:
    """Maker finding 3 (session 32): "wait for the Clean button, then dance", with no
    ``mode: safe`` first, validated clean; the press started the robot's own cleaning
    cycle (the OI spec), which drove it off."""
    mission = compile_text(BUTTON_IN_PASSIVE.format(first=first, name=name))
    warnings = [f"{w.line}:{w.column}: {w.message}" for w in mission.warnings]
    warnings = [w for w in warnings if "in Passive" in w]  # minute: the Create 2 has none
    expected = f"5:15: button: in Passive {warned} {_STARTS}start no cycle at a button)"
    assert warnings == ([expected] if warned else [])
