"""A ``@key`` value is held to the declared range of the parameter that reads it: the
validator checks the mission's constants (``initial``, ``set``) where they are written, and
the leaf checks what it reads when it starts (a plugin's or a ``for_each`` item's write).
900 mm/s in a key validated, and the run ended "drive raised EncodeError", blamed on the
built-in (field test, session 24)."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest

from roomba_bt.cli import main
from roomba_bt.runtime.summary import ExitCode

Errors = Callable[..., list[str]]

OUT_OF_RANGE = """
blackboard:
  v: {type: speed, initial: 900 mm/s}
  d: {type: duration, initial: -5s}
  w: {type: speed}
  wp: {fields: {distance: distance, turn: angle}, initial: {distance: 1 m, turn: 4000 deg}}
tree:
  sequence:
    - mode: safe
    - set: {key: w, value: -600 mm/s}
    - drive: {velocity: "@v", duration: 1s}
    - drive: {velocity: "@w", duration: "@d"}
    - turn: {angle: "@wp.turn"}
    - mode: passive
"""


def test_initial_and_set_values_are_checked_against_their_readers(errors_of: Errors) -> None:
    assert errors_of(OUT_OF_RANGE) == [
        "2:29: initial value of blackboard key 'v': drive's velocity reads it as @v (at 10:25): "
        "velocity 900 mm/s is out of range: allowed -500..500 mm/s",
        "3:32: initial value of blackboard key 'd': drive's duration reads it as @d (at 11:41): "
        "duration -5 s is out of range: allowed 0 s or more",
        "5:60: initial value of blackboard key 'wp': turn's angle reads it as @wp.turn (at 12:21): "
        "angle 4000 deg is out of range: allowed -3600..3600 deg",
        "9:28: set value of blackboard key 'w': drive's velocity reads it as @w (at 11:25): "
        "velocity -600 mm/s is out of range: allowed -500..500 mm/s",
    ]


def test_values_within_the_range_pass(errors_of: Errors) -> None:
    within = OUT_OF_RANGE.replace("900", "300").replace("-5s", "5s").replace("-600", "-100")
    assert errors_of(within.replace("4000", "40")) == []


PLUGIN = '''
from py_trees.common import Status

from roomba_bt.behaviours import DURATION, Action, Param, declare


@declare("pause", kind="action", params=(Param("duration", DURATION, minimum=0.1),))
class Pause(Action):
    """Waits."""

    def update(self):
        return Status.SUCCESS
'''


def _run(mission: Path) -> list[str]:
    return ["run", str(mission), "--fast", "--display", "none", "--timeout", "10s",
            "--allow-plugin-files"]  # fmt: skip


def test_a_plugin_s_range_is_checked_too(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A plugin's duration with minimum 0.1 got -5 s silently."""
    (tmp_path / "pause.py").write_text(PLUGIN)
    mission = tmp_path / "m.yaml"
    mission.write_text(
        "plugins: [./pause.py]\nblackboard:\n  d: {type: duration, initial: -5s}\n"
        "tree:\n  sequence: [{mode: safe}, {pause: {duration: '@d'}}, {mode: passive}]\n"
    )
    assert main(["validate", str(mission), "--allow-plugin-files"]) == 2
    out = capsys.readouterr().out
    assert (
        "m.yaml:3:32: initial value of blackboard key 'd': pause's duration reads it as @d "
        "(at 5:47): duration -5 s is out of range: allowed 0.1 s or more" in out
    ), out


def test_a_for_each_item_out_of_range_is_refused_where_it_is_written(
    mission_file: Callable[..., Path], capsys: pytest.CaptureFixture[str]
) -> None:
    """A for_each item is one of the mission's constants, like a ``set`` value: 900 mm/s
    in the list validated, and the run ended when the drive started (session 25)."""
    mission = mission_file(
        """
        blackboard:
          speed: {type: speed}
        tree:
          sequence:
            - mode: safe
            - for_each: {key: speed, in: [200 mm/s, 900 mm/s], do: {drive: {velocity: "@speed", distance: 1 m}}}
            - mode: passive
        """  # noqa: E501
    )
    assert main(["validate", str(mission)]) == ExitCode.INVALID
    out = capsys.readouterr().out
    assert (
        f"{mission}:6:45: for_each item of blackboard key 'speed': drive's velocity reads it "
        "as @speed (at 6:79): velocity 900 mm/s is out of range: allowed -500..500 mm/s "
        "[tree.sequence[1].for_each.in[1]]" in out
    ), out


def test_for_each_items_within_the_range_and_parameters_pass(errors_of: Errors) -> None:
    """Every item is checked, ``${parameter}`` ones with their value."""
    text = """
        parameters:
          fast: {type: speed, default: 400 mm/s}
        blackboard:
          v: {type: speed}
        tree:
          sequence:
            - mode: safe
            - for_each: {key: v, in: [100 mm/s, "${fast}"], do: {drive: {velocity: "@v", duration: 1s}}}
        """  # noqa: E501
    assert errors_of(text) == []
    assert errors_of(text, {"fast": "600 mm/s"}) == [
        "8:41: for_each item of blackboard key 'v': drive's velocity reads it as @v (at 8:76): "
        "velocity 600 mm/s is out of range: allowed -500..500 mm/s"
    ]


WRITER = '''
from py_trees.common import Status

from roomba_bt.behaviours import STR, Action, Param, declare, write_key


@declare("fast", kind="action", params=(Param("key", STR, required=True),), writes_keys=("key",))
class Fast(Action):
    """Writes what the validator cannot see."""

    def update(self):
        write_key(self.value("key"), VALUE)
        return Status.SUCCESS
'''


def test_a_plugin_s_write_out_of_range_ends_the_run_naming_the_reader(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """What the validator does not see (a plugin's write) is checked when the leaf starts:
    the run ends as an error naming the behaviour, the parameter and the key, not as the
    built-in's EncodeError."""
    assert main(_run(_written_then_driven(tmp_path, "900.0"))) == ExitCode.BEHAVIOUR_ERROR
    err = capsys.readouterr().err
    assert "EncodeError" not in err
    assert (
        "raised KeyRange: drive 'drive(velocity=@v, duration=0.5s)': velocity is @v, and "
        "blackboard key 'v' holds a value out of its range: velocity 900 mm/s is out of "
        "range: allowed -500..500 mm/s" in err
    ), err


def test_a_plugin_s_write_out_of_range_is_blamed_on_the_writer_not_the_reader(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The error pointed at roomba-bt's own ``base.py`` (the reader's ``read_parameters``)
    and never named the plugin that wrote the value (session 36, a stranger's finding): the
    last writer, its line, and whose fault it is are said, roomba-bt's file is not."""
    mission = _written_then_driven(tmp_path, "900.0")
    plugin = tmp_path / "fast.py"
    plugin.write_text(WRITER.replace("VALUE)", "900.0, self.name)"))
    assert main(_run(mission)) == ExitCode.BEHAVIOUR_ERROR
    err = capsys.readouterr().err
    assert (
        f"allowed -500..500 mm/s; the value was written last by 'fast(key=v)' (at {plugin}:12)"
        ": the fault is that writer's, drive only refused the value" in err
    ), err
    assert "base.py" not in err and "read_parameters" not in err, err
    # a writer that does not name itself: its line all the same
    plugin.write_text(WRITER.replace("VALUE", "900.0"))
    assert main(_run(mission)) == ExitCode.BEHAVIOUR_ERROR
    err = capsys.readouterr().err
    assert f"the value was written last (at {plugin}:12): the fault is that writer's" in err


def _written_then_driven(folder: Path, value: str) -> Path:
    """A mission whose plugin writes ``value`` (Python) to a speed key a drive reads."""
    (folder / "fast.py").write_text(WRITER.replace("VALUE", value))
    mission = folder / "m.yaml"
    mission.write_text(
        "plugins: [./fast.py]\nblackboard:\n  v: {type: speed}\ntree:\n  sequence:\n"
        "    - mode: safe\n    - fast: {key: v}\n"
        "    - drive: {velocity: '@v', duration: 0.5s}\n    - mode: passive\n"
    )
    return mission


def test_a_plugin_s_write_of_the_wrong_type_ends_the_run_naming_the_writer(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A text written to a speed key was stored as given and blamed on the drive that read
    it: "drive raised TypeError: type str doesn't define __round__ method" (session 25). The
    mission's declared types hold the plugin's write where it is made."""
    mission = _written_then_driven(tmp_path, "'fast'")
    assert main(_run(mission)) == ExitCode.BEHAVIOUR_ERROR
    err = capsys.readouterr().err
    assert (
        "fast(key=v) raised KeyType: write_key('v', 'fast'): blackboard key 'v' is declared "
        "speed (mm/s): expected a number of mm/s, got 'fast' (a str) in its update() "
        f"(at {tmp_path / 'fast.py'}:12)" in err
    ), err
