"""A mission whose leaves declare commands the chosen robot lacks. Validation used only the
profile's baud: ``validate --profile roomba500`` said ok for a plugin declaring
``sends=opcodes("reset")``, and the run stopped with ``outcome ERROR (UnsupportedCommandError
...)``, exit 4, after commands were written. Now: Reset 7 and Stop 173 on a Roomba 500 are
errors at the node (exit 2, nothing sent); Digit LEDs Raw 163 on a 600 / Create 2 (its
firmware does not honour it: the 600 spec's Appendix B) is a warning."""

from __future__ import annotations

from pathlib import Path

import pytest

from roomba_bt.cli import main
from roomba_bt.mission import Permissions, validate_files
from roomba_bt.oi.profiles import PROFILES

PLUGIN = '''
from roomba_bt.behaviours import Action, declare
from roomba_bt.oi import commands as oi
from roomba_bt.oi.opcodes import opcodes
from py_trees.common import Status


@declare("reboot", kind="action", sends=opcodes("reset"))
class Reboot(Action):
    """Reset (7): a 600 / Create 2 only."""

    def update(self):
        self.send(oi.reset())
        return Status.SUCCESS


@declare("power_off", kind="action", sends=opcodes("stop"))
class PowerOff(Action):
    """Stop (173): a 600 / Create 2 only."""

    def update(self):
        self.send(oi.stop())
        return Status.SUCCESS


@declare("raw_digits", kind="action", sends=opcodes("digit_leds_raw"))
class RawDigits(Action):
    """Digit LEDs Raw (163): works on a 500 only."""

    def update(self):
        self.send(oi.digit_leds_raw((0, 0, 0, 0)))
        return Status.SUCCESS
'''


def _mission(tmp_path: Path, leaf: str) -> Path:
    (tmp_path / "extra.py").write_text(PLUGIN)
    path = tmp_path / f"{leaf}.yaml"
    path.write_text(
        f"mission: {leaf}\nplugins: [./extra.py]\ntree:\n  sequence:\n"
        f"    - mode: safe\n    - {leaf}\n"
    )
    return path


@pytest.mark.parametrize(("leaf", "opcode"), [("reboot", "reset (7)"), ("power_off", "stop (173)")])
def test_a_command_the_roomba500_lacks_is_an_error_at_its_node(
    tmp_path: Path, leaf: str, opcode: str, capsys: pytest.CaptureFixture[str]
) -> None:
    path = _mission(tmp_path, leaf)
    code = main(["validate", str(path), "--profile", "roomba500", "--allow-plugin-files"])
    out, err = capsys.readouterr()
    assert code == 2, out + err
    assert f"{path.name}:6:7: {leaf}: {opcode} is not available on the Roomba 500 series " \
        "(roomba500); it exists on create2, roomba600" in out  # fmt: skip
    for profile in ("create2", "roomba600"):
        assert main(["validate", str(path), "--profile", profile, "--allow-plugin-files"]) == 0


def test_the_run_ends_before_anything_is_sent(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = _mission(tmp_path, "reboot")
    record = tmp_path / "run.jsonl"
    code = main(["run", str(path), "--profile", "roomba500", "--fast", "--display", "none",
                 "--allow-plugin-files", "--record", str(record)])  # fmt: skip
    err = capsys.readouterr().err
    assert code == 2, err
    assert "reset (7) is not available on the Roomba 500 series" in err
    assert "UnsupportedCommandError" not in err and not record.exists()


def test_digit_leds_raw_is_a_warning_on_every_profile_the_500_too(tmp_path: Path) -> None:
    """The 600 / Create 2 spec: 163 "does not work in current Create 2 and Roomba 500/600
    firmware versions"; a 560/570 owner was told nothing (it validated clean on roomba500)."""
    path = _mission(tmp_path, "raw_digits")
    allowed = Permissions(plugin_files=True)
    for name, profile in PROFILES.items():
        found = validate_files([path], profile=profile, permissions=allowed)
        assert [d.severity for d in found] == ["warning"], (name, found)
        assert (found[0].line, found[0].column) == (6, 7)
        assert found[0].message.startswith("raw_digits: digit_leds_raw (163) does not work on")


def _after_reboot(tmp_path: Path, *steps: str) -> Path:
    (tmp_path / "extra.py").write_text(PLUGIN)
    path = tmp_path / "back.yaml"
    path.write_text(
        "mission: back\nplugins: [./extra.py]\ntree:\n  sequence:\n    - mode: safe\n"
        "    - reboot\n" + "".join(f"    - {step}\n" for step in steps)
    )
    return path


def test_nothing_may_follow_a_reset_or_a_stop_not_even_mode_passive(tmp_path: Path) -> None:
    """Reset (7) and Stop (173) end the run: the OI is off and streams no more frames, the
    run's clock. ``mode: passive`` after them was the validator's advice (Start leads back
    from Off), and the run then waited for ever (roomba600-owner finding 1): now any leaf
    the tree may run after them is an error naming the leaf that sent it; last, it is ok."""
    allowed = Permissions(plugin_files=True)
    create2 = PROFILES["create2"]
    assert validate_files([_after_reboot(tmp_path)], profile=create2, permissions=allowed) == []
    for steps in (
        ("mode: passive", "mode: safe", "drive: {velocity: 0 mm/s}"),
        ("mode: safe",),
        ("leds: {dock: true}",),
        ("wait: 1s", "mode: passive"),
    ):
        found = validate_files(
            [_after_reboot(tmp_path, *steps)], profile=create2, permissions=allowed
        )
        assert len(found) == 1 and found[0].line == 7, found  # once, at the first after it
        message = found[0].message
        assert message.startswith(f"{steps[0].split(':')[0]} can run after reboot (line 6) sent")
        assert "which end the run" in message and "must be the last one the tree runs" in message


def test_the_way_to_end_in_off_is_offered_in_the_callers_words(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The error of a leaf after a Reset or Stop offered ``--end-in stop`` to a Python
    program too, which ends in Off with an argument (``mission/wording.py``); the command
    line keeps its flag."""
    path = _after_reboot(tmp_path, "mode: passive")
    allowed = Permissions(plugin_files=True)
    [found] = validate_files([path], profile=PROFILES["create2"], permissions=allowed)
    assert found.message.endswith(
        "to leave the robot in Off at the end of any mission, use end_in='stop' (RunStack's or "
        "Connection's) instead"
    )
    assert "--end-in" not in found.message
    code = main(["validate", str(path), "--profile", "create2", "--allow-plugin-files"])
    out, err = capsys.readouterr()
    assert code == 2, out + err
    assert "at the end of any mission, use --end-in stop instead" in out
