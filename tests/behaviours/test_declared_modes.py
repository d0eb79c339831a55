"""What a leaf declares of its modes is held to at ``send()``, as ``sends=`` is: a
``halts_only=True`` leaf may send nothing that sets the robot going, and a leaf may send no
mode command leading elsewhere than its ``leads_to=``. The Full-mode warning and the static
mode check read both, and a plugin's word was taken for them: ``halt_liar`` drove 0.63 m in
Full unwarned, and a drive after ``mode_liar`` (``leads_to=Safe``, sent Full) ran in Full
(stranger report, session 36). A declaration's Power (133) is refused when registered."""

from __future__ import annotations

import pytest
from py_trees.common import Status

from roomba_bt.behaviours import BOOL, Action, Param, declare
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
    ) as raised:
        leaf.tick_once()
    assert "and passes_through=OIMode.FULL if it goes there on the way" in str(raised.value)


class _Scripted(Action):
    """Sends, on each tick, that tick's commands, and answers that tick's status."""

    script: list[tuple[list[Command], Status]]

    def start(self) -> None:
        self.ticks = iter(self.script)

    def update(self) -> Status:
        sent, status = next(self.ticks)
        for command in sent:
            self.send(command)
        return status


#: Full, a drive in it, then Safe: what an action that dashes in Full itself declares
DASH = dict(sends=opcodes("full", "drive", "safe"), passes_through=OIMode.FULL)
#: its ticks: Full and a drive; the halt and Safe, SUCCESS
DASHES = [
    ([commands.full(), commands.drive(300, 32767)], Status.RUNNING),
    ([commands.halt(), commands.safe()], Status.SUCCESS),
]


def _scripted(script: list[tuple[list[Command], Status]], **declared: object) -> Action:
    class Dash(_Scripted):
        """Sends what its script says."""

    Dash.script = script
    declared_cls = declare("dash", kind="action", **declared)(Dash)  # type: ignore[arg-type]
    Registry(entry_point_group=None).register(declared_cls, "test")  # its declaration checked
    leaf: Action = declared_cls("dash")
    leaf.setup(robot=StubRobot())
    return leaf


@pytest.mark.parametrize(
    "declared",
    [{**DASH, "leads_to": OIMode.SAFE}, DASH, {**DASH, "passes_through": (OIMode.FULL,)}],
    ids=["leads_to said", "leads_to from its other commands", "a tuple of modes"],
)
def test_an_action_that_passes_through_full_and_ends_in_safe_runs(
    declared: dict[str, object],
) -> None:
    """It went to Full itself, drove, and went back to Safe, and said so as it could
    (``leads_to=Safe``): refused at its Full, since the declarations had no way to say
    "passes through Full" (session 37). ``passes_through=`` says it; ``leads_to`` is then
    what its other mode commands lead to, where not said."""
    leaf = _scripted(DASHES, **declared)
    assert leaf.declaration.leads_to is OIMode.SAFE
    assert leaf.declaration.passes_through == (OIMode.FULL,)
    assert leaf.robot is not None
    for sent, status in DASHES:  # each tick's commands queued, and written (drained)
        leaf.tick_once()
        assert leaf.status is status
        assert leaf.robot.outbox.drain() == sent


def test_a_mode_command_neither_passed_through_nor_led_to_is_refused() -> None:
    leaf = _scripted(
        [([commands.start()], Status.SUCCESS)],
        sends=opcodes("full", "drive", "safe", "start"), passes_through=OIMode.FULL,
        leads_to=OIMode.SAFE,
    )  # fmt: skip
    with pytest.raises(UnkeptDeclaration, match=r"dash sent start \(128\) 80, but its @declare "
                       r"\(at .*\) says leads_to=Safe, passes_through=Full, and start leads to "
                       r"Passive"):  # fmt: skip
        leaf.tick_once()


def test_a_success_in_a_mode_it_only_passes_through_is_refused() -> None:
    """Its ``leads_to`` is where the mode check has the leaves after it start: a SUCCESS
    left in Full had a drive after it run in Full, unwarned."""
    leaf = _scripted([([commands.full()], Status.SUCCESS)], **DASH)
    with pytest.raises(UnkeptDeclaration, match=r"dash sent full \(132\) 84, but its @declare "
                       r"\(at .*\) says leads_to=Safe, passes_through=Full, and it returned "
                       r"SUCCESS with no mode command after this one: it ended in Full, not "
                       r"Safe") as raised:  # fmt: skip
        leaf.tick_once()
    assert raised.value.returned is Status.SUCCESS  # the run names its return


@pytest.mark.parametrize("ending", ["failure", "halted"])
def test_a_failure_or_a_halt_on_the_way_is_no_broken_declaration(ending: str) -> None:
    """The mode check takes it that such a leaf fails, or is halted, in a mode it passes
    through (a drive on the fallback after it is judged in Full)."""
    script = [([commands.full()], Status.FAILURE if ending == "failure" else Status.RUNNING)]
    leaf = _scripted(script, **DASH)
    leaf.tick_once()
    if ending == "halted":
        leaf.stop(Status.INVALID)
    assert leaf.status is (Status.FAILURE if ending == "failure" else Status.INVALID)


@pytest.mark.parametrize(
    ("declared", "said"),
    [
        ({"sends": opcodes("drive", "safe"), "passes_through": OIMode.FULL},
         "passes_through=Full, but none of its sends= leads to Full (full (132) would)"),
        ({**DASH, "leads_to": OIMode.FULL},
         "passes_through=Full names Full, the mode it leads to"),
        ({"sends": opcodes("full", "drive"), "passes_through": OIMode.FULL},
         "passes_through=Full, and no leads_to= says the mode it ends in"),
        ({**DASH, "leads_to": OIMode.PASSIVE},
         "passes_through=Full, leads_to=Passive, but none of its sends= leads to Passive"),
        ({**DASH, "passes_through": ("full",)},
         "passes_through= names OI modes (OIMode.FULL, ...), got 'full'"),
        ({"sends": opcodes("drive"), "mode_first": True},
         "mode_first=True, but none of its sends= is a mode command"),
        ({"sends": opcodes("safe", "full", "drive"), "mode_first": True},
         "mode_first=True, and no leads_to= says the mode it ends in"),
        ({"sends": opcodes("start", "drive"), "mode_first": True},
         "mode_first=True, but drive (137) is accepted in none of the modes its mode "
         "commands lead to (Passive)"),
    ],
    ids=["a mode it cannot reach", "the mode it ends in", "no end", "an end it cannot reach",
         "not a mode", "mode_first: no mode command", "mode_first: no end",
         "mode_first: refused where it leads"],
)  # fmt: skip
def test_a_mode_declaration_that_cannot_be_kept_is_refused_when_registered(
    declared: dict[str, object], said: str
) -> None:
    with pytest.raises(DeclarationError) as raised:
        _scripted(DASHES, **declared)
    assert said in str(raised.value)


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


#: a leaf that sends its own Safe before it drives, and says so
SAFE_FIRST = dict(sends=opcodes("safe", "drive"), mode_first=True)
HONEST = [commands.safe(), commands.drive(200, 32767)]


def _starts(*starts: list[Command], **declared: object) -> Action:
    """A leaf that sends ``starts[n]`` on the first tick of its n-th start, and succeeds."""

    class Dash(_Scripted):
        """Sends, each start, the next start's commands."""

        def start(self) -> None:
            self.ticks = iter([(next(self.starts), Status.SUCCESS)])

    Dash.starts = iter(starts)  # type: ignore[attr-defined]
    declared_cls = declare("dash", kind="action", **declared)(Dash)  # type: ignore[arg-type]
    Registry(entry_point_group=None).register(declared_cls, "test")
    leaf: Action = declared_cls("dash")
    leaf.setup(robot=StubRobot())
    return leaf


def test_a_mode_first_leaf_that_sends_its_mode_first_runs_again_and_again() -> None:
    """Each start sends its mode command first: the second start too (the flag that its
    mode command came is cleared as it stops, so a start without one is caught)."""
    leaf = _starts(HONEST, HONEST, **SAFE_FIRST)
    assert leaf.robot is not None
    for _ in range(2):
        leaf.tick_once()
        assert leaf.status is Status.SUCCESS
        assert leaf.robot.outbox.drain()[0] == commands.safe()  # the drive halted since


@pytest.mark.parametrize("which", ["its first start", "a later start"])
def test_a_mode_first_leaf_whose_first_command_is_another_is_refused(which: str) -> None:
    """Validate let it be reached in Passive on its word: a drive first would be refused
    there by the mode guard, or, entered in Safe from a mode: safe the word replaced, run
    where the mission had not put one. The runtime holds it to its word every start."""
    lie = [commands.drive(200, 32767), commands.safe()]
    leaf = (
        _starts(lie, **SAFE_FIRST)
        if which == "its first start"
        else _starts(HONEST, lie, **SAFE_FIRST)
    )
    if which == "a later start":
        leaf.tick_once()
        assert leaf.status is Status.SUCCESS
    with pytest.raises(UnkeptDeclaration, match=r"dash sent drive \(137\) 89 00 c8 7f ff, but "
                       r"its @declare \(at .*\) says mode_first=True \(each time it starts, its "
                       r"first command is one of its mode commands\), and this one came before "
                       r"any since it started"):  # fmt: skip
        leaf.tick_once()


def _own_mode(params: object) -> tuple[int, ...]:
    """A ``sends_by``: Safe and a drive, or with ``own_mode: false`` the drive alone."""
    given = params if isinstance(params, dict) else {}
    return opcodes("safe", "drive") if given.get("own_mode", True) else opcodes("drive")


@pytest.mark.parametrize("own_mode", [True, False])
def test_a_mode_first_leaf_is_held_to_its_mode_command_where_its_parameters_send_one(
    own_mode: bool,
) -> None:
    """``mode_first=True`` with a ``sends_by`` that sends no mode command with some
    parameters: validate judged all its commands where it is reached (a drive: Safe or
    Full), and the runtime still refused its drive first, stricter than the check. One rule
    (``Declaration.mode_comes_first``), read by both: with ``own_mode: false`` it is any
    leaf, judged and run so; with its Safe it is held to sending it first."""

    class Hop(_Scripted):
        """Drives, sending its own Safe first where asked to."""

        def start(self) -> None:
            self.ticks = iter([([commands.drive(200, 32767)], Status.SUCCESS)])

    declared = declare(
        "hop", kind="action", sends=opcodes("safe", "drive"), mode_first=True,
        sends_by=_own_mode, params=[Param("own_mode", BOOL, default=True)],
    )(Hop)  # fmt: skip
    Registry(entry_point_group=None).register(declared, "test")
    decl = declared.declaration
    params = {"own_mode": own_mode}
    assert decl.mode_comes_first(params) is own_mode
    assert decl.sent_first(params) == (opcodes("safe") if own_mode else opcodes("drive"))
    assert (OIMode.PASSIVE in decl.reached_in(params)) is own_mode
    leaf: Action = declared("hop", params)
    leaf.setup(robot=StubRobot())
    if own_mode:  # it says its Safe comes first, and drove first
        with pytest.raises(UnkeptDeclaration, match="says mode_first=True"):
            leaf.tick_once()
        return
    leaf.tick_once()  # reached in Safe, as validate held it to: its drive goes
    assert leaf.status is Status.SUCCESS
