"""A program opening a Roomba 500 with the default profile: the watchdog's error says the
frames pass the 500's checksum and how to pass the profile (it said only "no valid sensor
frame for 101 ms"). A Roomba 500 profile on a 600 / Create 2 reads it: the 500's parser
takes either checksum (``checksum_accepts_both``)."""

from __future__ import annotations

import pytest

from roomba_bt.oi.profiles import CREATE2, ROOMBA500, ROOMBA600, RobotProfile
from roomba_bt.robot import wording
from roomba_bt.robot.connection import Connection
from roomba_bt.robot.errors import StreamStalled
from roomba_bt.sim import SimLink, Simulator, load_world


def _connection(robot: RobotProfile, profile: RobotProfile) -> Connection:
    simulator = Simulator(load_world("empty-room"), robot, seed=1)
    connection = Connection(SimLink(simulator), profile)
    connection.start("passive", (100,))
    return connection


@pytest.mark.parametrize("profile", [CREATE2, ROOMBA600])
def test_the_stall_on_a_roomba500_names_its_profile(profile: RobotProfile) -> None:
    connection = _connection(ROOMBA500, profile)
    with pytest.raises(StreamStalled) as stalled:
        for _ in range(20):
            connection.poll(0.05)
    message = str(stalled.value)
    assert stalled.value.mismatch is not None
    assert f"failed the checksum of the {profile.name} profile (the header 19 summed in)" in message
    assert "pass with the header left out" in message
    assert "Connection.open(port, profile='roomba500')" in message
    assert "--profile roomba500" in message
    connection.close()


@pytest.mark.parametrize(
    ("setting", "fix"),
    [
        (None, "use --profile roomba500 (in Python, Connection.open(port, profile='roomba500'))"),
        ("--profile", "use --profile roomba500, or roomba-bt doctor"),
        ("ROOMBA_BT_PROFILE", "set ROOMBA_BT_PROFILE=roomba500 (or auto), or roomba-bt doctor"),
        ("/p/pyproject.toml:4", 'set profile = "roomba500" at /p/pyproject.toml:4 (or "auto")'),
    ],
    ids=["not known", "the flag", "the environment", "the project file"],
)
def test_the_stall_says_the_fix_where_the_profile_was_set(setting: str | None, fix: str) -> None:
    """``ROOMBA_BT_PROFILE=create2`` on a Roomba 500 was told "use --profile roomba500":
    one command fixed, the next wrong again. The fix is made where the setting is, and a
    command line's fix does not name the Python argument."""
    connection = _connection(ROOMBA500, CREATE2)
    connection.profile_setting = setting
    with pytest.raises(StreamStalled) as stalled:
        for _ in range(20):
            connection.poll(0.05)
    connection.close()
    assert fix in str(stalled.value)
    assert fix in stalled.value.headline  # the short first line carries the fix too
    assert stalled.value.headline.endswith("roomba-bt doctor to tell the model")
    assert ("Connection.open" in str(stalled.value)) is (setting is None)


@pytest.mark.parametrize("robot", [CREATE2, ROOMBA600])
def test_the_roomba500_profile_reads_a_600_and_a_create2(robot: RobotProfile) -> None:
    connection = _connection(robot, ROOMBA500)
    frames = 0
    for _ in range(10):
        frames += len(connection.poll(0.05))
    assert frames >= 10 and connection.counters.checksum_failures == 0
    connection.close()


def test_noise_is_not_a_wrong_profile() -> None:
    """Checksum failures that do not pass the other rule (noise) name no model, nor do a
    frame or two passing it by chance, nor any once the profile's own rule took frames."""
    from roomba_bt.oi.identify import checksum_mismatch  # new with the check

    assert checksum_mismatch(CREATE2, frames=0, failures=60, other_checksum=1) is None
    assert checksum_mismatch(CREATE2, frames=0, failures=60, other_checksum=20) is None
    assert checksum_mismatch(CREATE2, frames=5, failures=60, other_checksum=60) is None
    assert checksum_mismatch(ROOMBA500, frames=0, failures=60, other_checksum=60) is None
    found = checksum_mismatch(CREATE2, frames=0, failures=60, other_checksum=58)
    assert found is not None and found.likely == (ROOMBA500,)


#: A room whose south wall is 30 mm from the robot's right side: the wall sensor reads a
#: signal only a Roomba 500 sends (over the 600's 1023).
BESIDE_A_WALL = """
name: beside-a-wall
rooms: [[[0, 0], [4, 0], [4, 4], [0, 4]]]
robot: {start: {at: [2, 0.2], heading: 0}}
"""


def _stalled_beside_a_wall(
    robot: RobotProfile, profile: RobotProfile
) -> tuple[StreamStalled, Connection]:
    """A simulated ``robot`` in :data:`BESIDE_A_WALL`, read with ``profile`` until the
    watchdog trips: the stall and the connection (to close)."""
    from roomba_bt.sim import parse_world

    simulator = Simulator(parse_world(BESIDE_A_WALL), robot, seed=1)
    connection = Connection(SimLink(simulator), profile)
    connection.start("passive", (100,))
    with pytest.raises(StreamStalled) as stalled:
        for _ in range(20):
            connection.poll(0.05)
    assert simulator.values[27] > 1023, "the robot sees the wall"
    return stalled.value, connection


@pytest.mark.parametrize("profile", [CREATE2, ROOMBA600])
def test_a_roomba500_beside_a_wall_is_named_not_called_noise(profile: RobotProfile) -> None:
    """Its frames set bits the 600's wall-signal range leaves clear; they were counted as
    out of range before their checksum was judged, and the stall said "noise on the line,
    or a wrong baud rate" instead of naming the Roomba 500."""
    stalled, connection = _stalled_beside_a_wall(ROOMBA500, profile)
    assert stalled.mismatch is not None
    assert "--profile roomba500" in str(stalled)
    connection.close()


@pytest.mark.parametrize("profile", [CREATE2, ROOMBA600])
def test_a_roomba500_summing_the_header_beside_a_wall_is_named_by_its_range(
    profile: RobotProfile,
) -> None:
    """A 500 whose firmware sums the header into the checksum (the rule a real 500 follows is
    not certain): its frames pass the profile's checksum and fail only the range of its wall
    signal. Every one was dropped, and the stall named no packet, no value, no profile."""
    from dataclasses import replace

    from roomba_bt.oi.identify import RangeMismatch

    summing = replace(ROOMBA500, checksum_includes_header=True)
    stalled, connection = _stalled_beside_a_wall(summing, profile)
    assert isinstance(stalled.mismatch, RangeMismatch)
    assert connection.counters.checksum_failures == 0
    message = str(stalled)
    assert f"not the range of the {profile.name} profile: wall signal (27) read" in message
    assert "within the Roomba 500 series range 0-4095" in message
    assert "--profile roomba500" in message
    connection.close()


@pytest.mark.parametrize("sums_header", [True, False], ids=["range", "checksum"])
@pytest.mark.parametrize("hears", [True, False], ids=["heard", "deaf"])
@pytest.mark.parametrize(
    ("caller", "fix"),
    [(wording.PYTHON, "Connection.open(port, profile='roomba500')"),
     (wording.COMMAND_LINE, "--profile roomba500")],
    ids=["a program", "the command line"],
)  # fmt: skip
def test_the_stop_after_another_model_s_stall_says_what_is_known(
    sums_header: bool, hears: bool, caller: wording.ConnectionWording, fix: str
) -> None:
    """After a stall on a Roomba 500's frames read with create2 (its frames fail the range,
    or the checksum, of the profile), the stop was "unconfirmed: the robot had sent no valid
    frame for 0.11 s before it": a silence that was only the profile's, the robot streaming
    all along. Its Pause Stream heard (the line quiet) and a Query List answered confirm it;
    a robot that hears nothing leaves it unconfirmed, with the mismatch and its fix, in the
    caller's words (a program was told ``--profile roomba500``, an option it has not got)."""
    from dataclasses import replace

    summing = replace(ROOMBA500, checksum_includes_header=sums_header)
    with wording.spoken(caller):
        stalled, connection = _stalled_beside_a_wall(summing, CREATE2)
        assert stalled.mismatch is not None
        simulator = connection.transport.simulator  # type: ignore[attr-defined]
        simulator.deaf = not hears
        assert connection.close() is hears
    if hears:
        assert connection.stop_report is None
    else:
        report = connection.stop_report or ""
        assert "unconfirmed: its frames fail the create2 profile's" in report, report
        assert f"(most likely a Roomba 500 series: {fix})" in report, report
        assert "no valid frame" not in report


def test_a_600s_mode_plus_one_says_the_fix_where_the_profile_was_set(
    caplog: pytest.LogCaptureFixture,
) -> None:
    """The 600's mode + 1 warning gives the same fix as the 500's stall: where the setting
    is (``ROOMBA_BT_PROFILE=create2`` was told "use --profile roomba600")."""
    import logging

    caplog.set_level(logging.WARNING, logger="roomba_bt.robot.modes")
    simulator = Simulator(load_world("empty-room"), ROOMBA600, seed=1)
    connection = Connection(SimLink(simulator), CREATE2)
    connection.profile_setting = "ROOMBA_BT_PROFILE"
    connection.start("passive", (100,))
    connection.close()
    (line,) = [r.getMessage() for r in caplog.records if "mode + 1" in r.getMessage()]
    assert "most likely a Roomba 600 series: set ROOMBA_BT_PROFILE=roomba600 (or auto)" in line
    assert "use --profile" not in line
