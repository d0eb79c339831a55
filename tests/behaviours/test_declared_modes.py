"""What a leaf declares of its modes is held to at ``send()``, as ``sends=`` is: a
``halts_only=True`` leaf may send nothing that sets the robot going, and a leaf may send no
mode command leading elsewhere than its ``leads_to=``. The Full-mode warning and the static
mode check read both, and a plugin's word was taken for them: ``halt_liar`` drove 0.63 m in
Full unwarned, and a drive after ``mode_liar`` (``leads_to=Safe``, sent Full) ran in Full
(stranger report, session 36). A declaration's Power (133) is refused when registered."""

from __future__ import annotations

import pytest
from py_trees.common import Status

from roomba_bt.behaviours import Action, declare
from roomba_bt.behaviours.actions import Mode, Stop
from roomba_bt.behaviours.base import UnkeptDeclaration
from roomba_bt.behaviours.declare import DeclarationError
from roomba_bt.behaviours.registry import Registry
from roomba_bt.oi import commands
from roomba_bt.oi.encode import Command
from roomba_bt.oi.modes import OIMode
from roomba_bt.oi.opcodes import opcodes
from roomba_bt.robot.testing import StubRobot


class _Sends(Action):
    """Sends, on its first tick, the command it is given."""

    command: Command

    def update(self) -> Status:
        self.send(self.command)
        return Status.SUCCESS


def _leaf(command: Command, **declared: object) -> Action:
    class Liar(_Sends):
        """Sends ``command``, whatever it declares."""

    Liar.command = command
    declared_cls = declare("liar", kind="action", **declared)(Liar)  # type: ignore[arg-type]
    leaf: Action = declared_cls("liar")
    leaf.setup(robot=StubRobot())
    return leaf


HALTS = dict(sends=opcodes("drive", "drive_direct", "motors"), halts_only=True)


@pytest.mark.parametrize(
    "command",
    [commands.drive(300, 32768), commands.drive_direct(0, 100), commands.motors(0b100)],
    ids=["drive", "one wheel", "the main brush"],
)
def test_a_halts_only_leaf_that_sets_something_going_is_refused(command: Command) -> None:
    leaf = _leaf(command, **HALTS)
    with pytest.raises(UnkeptDeclaration, match=r"liar sent .* says halts_only=True") as raised:
        leaf.tick_once()
    assert "drop halts_only=True if it drives" in str(raised.value)
    assert "its @declare (at " in str(raised.value)  # where the declaration is
    assert leaf.robot is not None and leaf.robot.outbox.pending() == []  # refused before queued


@pytest.mark.parametrize(
    "command",
    [commands.halt(), commands.drive(0, 1), commands.drive_direct(0, 0), commands.motors(0)],
    ids=["drive 0", "a radius alone", "both wheels 0", "motors off"],
)
def test_a_halts_only_leaf_that_halts_sends(command: Command) -> None:
    leaf = _leaf(command, **HALTS)
    leaf.tick_once()
    assert leaf.status is Status.SUCCESS
    assert leaf.robot is not None and leaf.robot.outbox.pending() == [command]


def test_the_core_stop_still_sends_its_halt() -> None:
    stop = Stop("stop", {"motors": True})
    stop.setup(robot=StubRobot())
    stop.tick_once()
    assert stop.status is Status.SUCCESS
    assert stop.robot is not None
    assert stop.robot.outbox.pending() == [commands.halt(), commands.motors_off()]


def test_a_mode_command_leading_elsewhere_than_leads_to_is_refused() -> None:
    leaf = _leaf(commands.full(), sends=opcodes("safe", "full"), leads_to=OIMode.SAFE)
    with pytest.raises(
        UnkeptDeclaration,
        match=r"liar sent full \(132\) 84, but its @declare \(at .*test_declared_modes.py:\d+\) "
        r"says leads_to=Safe, and full leads to Full",
    ):
        leaf.tick_once()


def test_a_mode_command_with_no_mode_declared_is_refused() -> None:
    """Safe and Full in ``sends`` lead to no one mode: the check took the mode as unchanged."""
    leaf = _leaf(commands.full(), sends=opcodes("safe", "full", "drive"))
    with pytest.raises(UnkeptDeclaration, match=r"it leaves the mode as it found it .* "
                       r"declare leads_to=OIMode.FULL"):  # fmt: skip
        leaf.tick_once()


@pytest.mark.parametrize(
    ("command", "declared"),
    [
        (commands.full(), {"sends": opcodes("full", "drive")}),  # the table's leads_to
        (commands.safe(), {"sends": opcodes("safe", "full"), "leads_to": OIMode.SAFE}),
        (commands.full(), {"sends": opcodes("safe", "full"),
                           "leads_to": lambda params: OIMode.FULL}),
    ],
    ids=["from the table", "declared", "a function of the parameters"],
)  # fmt: skip
def test_a_mode_command_leading_where_declared_is_sent(
    command: Command, declared: dict[str, object]
) -> None:
    leaf = _leaf(command, **declared)
    leaf.tick_once()
    assert leaf.robot is not None and leaf.robot.outbox.pending() == [command]


@pytest.mark.parametrize("to", ["passive", "safe", "full"])
def test_the_core_mode_sends_the_command_of_its_parameter(to: str) -> None:
    mode = Mode("mode", {"to": to})
    mode.setup(robot=StubRobot(mode=OIMode.OFF if to == "passive" else OIMode.PASSIVE))
    mode.tick_once()
    assert mode.robot is not None
    assert [c.spec.leads_to for c in mode.robot.outbox.pending()] == [OIMode[to.upper()]]


def test_power_in_sends_is_refused_when_registered() -> None:
    """Power put the robot to sleep: the run saw a lost cable (exit 8, "the robot may have
    moved") where the tree had sent it."""

    @declare("do_power", kind="action", sends=opcodes("power"))
    class DoPower(_Sends):
        """Sends Power."""

        command = commands.power()

    with pytest.raises(DeclarationError, match=r"sends power \(133\), which roomba-bt never "
                       r"sends: the robot falls asleep"):  # fmt: skip
        Registry(entry_point_group=None).register(DoPower, "test")
