"""The shipped clean.yaml: covers more of a room than the firmware's Clean on the same start,
docks when the battery runs low, ends when the floor is done, with and without the encoders'
error."""

from __future__ import annotations

import logging
import re
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

import pytest
from py_trees.common import Status

from roomba_bt.behaviours.coverage_map import FloorMap
from roomba_bt.evaluate import EpisodeSpec, run_episode
from roomba_bt.evaluate.episode import EpisodeResult
from roomba_bt.mission import load_mission
from roomba_bt.mission.build import CompiledMission
from roomba_bt.oi.modes import OIMode
from roomba_bt.runtime.stack import RunStack
from roomba_bt.runtime.summary import RunSummary
from roomba_bt.sim import Pose, SimLink, Simulator, load_world

from .conftest import MISSIONS


def _living_room(mission: str, seed: int, minutes: int, **fields: object) -> EpisodeResult:
    spec = EpisodeSpec(
        str(MISSIONS / f"{mission}.yaml"), "apartment", seed,
        params=(("duration", f"{minutes}min"),), timeout_s=minutes * 60.0 + 30.0,
        start_area="living-room", **fields,  # type: ignore[arg-type]
    )  # fmt: skip
    return run_episode(spec)


def test_clean_covers_more_than_the_builtin_clean_on_the_same_start() -> None:
    ours = _living_room("clean", 3, 10)
    builtin = _living_room("clean-builtin", 3, 10)
    assert ours.start == builtin.start
    assert ours.coverage is not None and builtin.coverage is not None
    assert ours.coverage.final >= 0.7
    assert ours.coverage.final >= builtin.coverage.final + 0.1
    assert ours.coverage.longest_idle_s < 60.0
    assert ours.violations == 0 and not ours.fell


@pytest.mark.parametrize("odometry_error", [0.0, 0.015])
def test_clean_docks_when_the_battery_runs_low(odometry_error: float) -> None:
    spec = EpisodeSpec(
        str(MISSIONS / "clean.yaml"), "apartment", seed=4, battery=0.153, timeout_s=900.0,
        odometry_error=odometry_error,
    )  # fmt: skip
    result = run_episode(spec)
    assert result.outcome == "success", result.reason
    assert result.docked and result.charging
    assert result.coverage is not None and result.coverage.cleaning_s > 0


def test_clean_in_a_small_room_ends_when_the_floor_is_done_and_goes_home() -> None:
    """Done before its 20 minutes, it docks as the firmware's Clean does (it stayed where it
    stopped: a robot left in the middle of the room, its battery running down)."""
    result = run_episode(
        EpisodeSpec(str(MISSIONS / "clean.yaml"), "empty-room", seed=1, timeout_s=1300.0)
    )
    assert result.outcome == "success", result.reason
    assert result.coverage is not None and result.coverage.overall >= 0.9
    assert result.coverage.cleaning_s < 1200.0  # before the 20 minutes: it knew it was done
    assert result.docked and result.charging


DINING = Path(__file__).resolve().parents[1] / "data" / "dining.yaml"


@pytest.mark.parametrize("seed", [105, 109])
def test_clean_takes_a_table_with_chairs_for_furniture_not_for_the_room(seed: int) -> None:
    """A table with six chairs stands free in the room, their legs 40 cm apart. From these
    starts the first edge went round the chairs (105) or under the table (109), the map
    closed on the legs, and cleaning ended "the floor is done" at 21 % and 12 %: the open
    floor round them was never cleaned. The floor past the legs is floor too. One pass: the
    first pass's end is what closed on the legs (a second sweeps on to the 20 minutes)."""
    result = run_episode(
        EpisodeSpec(str(MISSIONS / "clean.yaml"), str(DINING), seed=seed, timeout_s=1300.0,
                    params=(("passes", "1"),))
    )  # fmt: skip
    assert result.coverage is not None and result.coverage.overall >= 0.7, result.coverage
    assert result.outcome == "success", result.reason
    assert result.docked


CHAIRS_APART = DINING.with_name("chairs-apart.yaml")


def test_the_dock_search_after_cleaning_leaves_a_chair_the_way_the_robot_came_in() -> None:
    """Six chairs a robot's width apart; this start's cleaning ended between two chairs'
    legs, and with no dock beam seen while it cleaned the dock search started there. Its
    trail began there too: trapped, its way out back the way it came led to where it had
    started, and it bounced among the legs for its 10 minutes (the mission failed, not
    home). Now the search's trail begins with the way ``cover`` kept (``WAY_KEY``)."""
    result = run_episode(
        EpisodeSpec(str(MISSIONS / "clean.yaml"), str(CHAIRS_APART), seed=2, timeout_s=900.0)
    )
    assert result.outcome == "success", result.reason
    assert result.docked and result.time_s < 400.0, result.time_s


def test_clean_without_going_home_succeeds_and_without_a_dock_fails(tmp_path: Path) -> None:
    """``-p go_home=false`` stays where it stopped: a success. In a world with no dock the way
    home fails after its time limit: the floor was cleaned, but the robot is not home (its
    battery running down mid-floor), and the mission fails (exit 1) saying why; until
    session 25 it was a success, said in an INFO log line that ``--display none`` hid."""
    stay = run_episode(
        EpisodeSpec(str(MISSIONS / "clean.yaml"), "empty-room", seed=1, timeout_s=1300.0,
                    params=(("go_home", "false"),))
    )  # fmt: skip
    assert stay.outcome == "success", stay.reason
    assert not stay.docked
    world = tmp_path / "no-dock.yaml"
    world.write_text("rooms: [[[0, 0], [3, 0], [3, 2.5], [0, 2.5]]]\n")
    homeless = run_episode(
        EpisodeSpec(str(MISSIONS / "clean.yaml"), str(world), seed=1, timeout_s=600.0,
                    params=(("duration", "1min"), ("dock_time_limit", "1min")))
    )  # fmt: skip
    assert homeless.outcome == "failure"
    assert "dock_time_limit(1min)" in homeless.reason
    assert homeless.coverage is not None and homeless.coverage.overall > 0.3  # it cleaned
    assert not homeless.docked and 120.0 <= homeless.time_s < 200.0


def _clean_on_the_simulator(
    world: str,
    start: Pose | None,
    params: dict[str, str],
    timeout_s: float,
    link: type[SimLink] = SimLink,
) -> tuple[Simulator, RunSummary, CompiledMission]:
    """clean.yaml through the real runtime on the simulator's virtual clock; the simulator
    kept, for its events (the mode changes) and its coverage, and the mission, for its tree
    as it ended."""
    compiled = load_mission(str(MISSIONS / "clean.yaml"), params)
    sim = Simulator(load_world(world), start=start, coverage=True, trace=False)
    summary = RunStack(compiled, link(sim), profile=sim.profile, timeout_s=timeout_s).run()
    return sim, summary, compiled


def _modes(sim: Simulator) -> list[str]:
    return [e.detail for e in sim.events if e.kind == "mode"]


class _Said(logging.Handler):
    """Every message of the loggers it is added to, at INFO and above."""

    def __init__(self) -> None:
        super().__init__(logging.INFO)
        self.messages: list[str] = []

    def emit(self, record: logging.LogRecord) -> None:
        self.messages.append(record.getMessage())


@dataclass(frozen=True)
class _Cleaned:
    sim: Simulator
    summary: RunSummary
    compiled: CompiledMission
    said: list[str]  # the mission's log messages (INFO and above)


@pytest.fixture(scope="module")
def cleaned_at_a_cliff(cliff_world: str) -> _Cleaned:
    """clean.yaml for 4 minutes in the cliff room, not going home, one pass (its floor done
    in the 4 minutes: a second would sweep on to the time up): one run (230 s of mission
    time, most of a second of CPU) for the tests that read its modes, its floor, its tree
    and its words. They only read it."""
    logger = logging.getLogger("roomba_bt.mission")
    said, level = _Said(), logger.level
    logger.setLevel(logging.INFO)
    logger.addHandler(said)
    try:
        sim, summary, compiled = _clean_on_the_simulator(
            cliff_world, None, {"duration": "4min", "go_home": "false", "passes": "1"}, 400.0
        )
    finally:
        logger.removeHandler(said)
        logger.setLevel(level)
    return _Cleaned(sim, summary, compiled, said.messages)


def test_clean_runs_in_safe_mode_and_cleans_on_after_the_firmware_stops_at_a_cliff(
    cleaned_at_a_cliff: _Cleaned,
) -> None:
    """The firmware's own cliff stop stays on (Safe): at the drop it stops the robot and
    falls to Passive (the brushes stop too); the mission enters Safe again, turns the motors
    on and ``cover`` goes on with the map it had, to the whole floor before the drop. In
    Full (until session 25) a host that died mid-lane left it driving down the stairs."""
    sim, summary = cleaned_at_a_cliff.sim, cleaned_at_a_cliff.summary
    assert summary.outcome.value == "success", summary.reason
    modes = _modes(sim)
    assert not any("Full" in m for m in modes), modes
    drops = [i for i, m in enumerate(modes) if "safety: cliff" in m]
    assert drops, modes
    assert any("->Safe" in m for m in modes[drops[-1] :]), modes  # Safe again after the last
    assert not sim.fallen
    assert sim.swept is not None and sim.swept.coverage() >= 0.85  # the floor before the drop
    # each drop handled as in Full (back off, the lane or edge goes on): a fresh decision
    # after each drove at the same edge again (90 drops, the floor not done in 4 minutes)
    assert len(drops) <= 30 and summary.mission_time_s < 230.0, (len(drops), summary)
    # each drop: Safe again within a few ticks (``cover`` fails at once, the cliff mapped;
    # it waited a second in Passive each time, about 21 times a run in the apartment)
    events = [e for e in sim.events if e.kind == "mode"]
    for i, event in enumerate(events):
        if "safety: cliff" in event.detail:
            back = next(e for e in events[i:] if "->Safe" in e.detail)
            assert back.time - event.time < 0.1, (event, back)


#: A room 4 m x 2.5 m whose near 0.8 m is a drop (a landing's edge, 4 m of it), the robot
#: 0.8 m from it, facing it.
LEDGE = """
name: ledge
rooms: [[[0, 0], [4, 0], [4, 2.5], [0, 2.5]]]
drops: [{name: landing, rect: [0, 0, 4, 0.8]}]
robot: {start: {at: [2.0, 1.6], heading: -90}}
"""


def test_clean_meets_a_drop_it_knows_far_less_often(tmp_path: Path) -> None:
    """Each cliff in Safe mode is a drop to Passive with the front caster over the edge.
    ``cover`` met this landing's edge 40 times in 4 minutes (the floor not done): its edge,
    with no wall on its right (the light bumper sees none over a drop), curved right into
    it every 20 cm and did it again on every later edge along it, and lanes met it wherever
    the few cells it had marked were not. Now the drop it met is on its map, joined along
    the edge: the edge follows it as a wall, lanes end short of it (drops.py)."""
    world = tmp_path / "ledge.yaml"
    world.write_text(LEDGE)
    spec = EpisodeSpec(
        str(MISSIONS / "clean.yaml"), str(world), random_start=False, timeout_s=270.0,
        params=(("duration", "4min"), ("go_home", "false")), trace_every=0,
    )  # fmt: skip
    result = run_episode(spec)
    assert result.outcome == "success", result.reason
    assert not result.fell
    falls = dict(result.falls).get("cliff", 0)
    assert 0 < falls <= 16, result.falls  # 40 before: at most two fifths of that
    assert result.coverage is not None and result.coverage.overall >= 0.95  # 0.961 before


def test_clean_says_why_it_stopped_and_a_retried_cover_shows_no_old_failure(
    cleaned_at_a_cliff: _Cleaned,
) -> None:
    """At the end of a clean with cliff stops, the tree showed ``cover [✓] -- the robot left
    Safe/Full mode (cliff) and was not brought back within 1 s``, an earlier attempt's
    failure, and nothing said why cleaning stopped."""
    sim, summary, compiled = (
        cleaned_at_a_cliff.sim, cleaned_at_a_cliff.summary, cleaned_at_a_cliff.compiled
    )  # fmt: skip
    assert summary.outcome.value == "success", summary.reason
    assert any("safety: cliff" in m for m in _modes(sim))  # cover failed and was retried
    cover = next(n for n in compiled.root.iterate() if n.name.startswith("cover("))
    assert cover.status is Status.SUCCESS
    assert re.fullmatch(r"floor done: \d+\.\d m² swept by its own map", cover.feedback_message)
    assert _stopped(cleaned_at_a_cliff.said) == ["cleaning stopped: the floor is done"]
    assert summary.said == "cleaning stopped: the floor is done"  # its map left none open


#: what clean.yaml says when cover's map still shows floor it found no way to
FLOOR_LEFT = (
    "cleaning stopped: the floor is done by its map, but its map shows unswept floor it "
    "found no way to: cover's warning says where and what stopped it"
)


def test_clean_says_in_its_summary_that_its_map_left_floor_it_found_no_way_to(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A floor done while cover's map still showed unswept floor beside what it swept was a
    warning in the log and cover's message in the final tree; the summary's ``mission
    said`` line read "cleaning stopped: the floor is done" (the apartment, 1.5 % encoder
    error: the bedroom never entered, session 38). Now cover writes ``unreached`` and the
    mission says it there. Its map is made to show 2.5 m of such floor 3 m ahead of its
    start (a small room's own map shows none); cover's warning says where it is."""
    left = [FloorMap.cell(3050.0, y * 100.0 + 50.0) for y in range(25)]
    monkeypatch.setattr(FloorMap, "unreached_cells", lambda self: left)
    room = tmp_path / "small.yaml"
    room.write_text(
        "rooms: [[[0, 0], [2, 0], [2, 1.5], [0, 1.5]]]\n"
        "robot: {start: {at: [1.0, 0.75], heading: 0}}\n"
    )
    _, summary, compiled = _clean_on_the_simulator(str(room), None, {"go_home": "false"}, 900.0)
    assert summary.outcome.value == "success", summary.reason
    assert summary.said == FLOOR_LEFT
    cover = next(n for n in compiled.root.iterate() if n.name.startswith("cover("))
    assert re.search(
        r"; its map shows unswept floor along 2\.5 m of the floor it swept that it found no "
        r"way to, the nearest \d+\.\d m from where it stopped \(about 3\.0 m ahead and "
        r"0\.1 m to the left of where it started\): \w",
        cover.feedback_message,
    ), cover.feedback_message


def _stopped(messages: Iterable[str]) -> list[str]:
    return [message for message in messages if "cleaning stopped" in message]


def test_clean_says_its_time_is_up_or_its_battery_low(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    caplog.set_level(logging.INFO, logger="roomba_bt.mission")
    _clean_on_the_simulator("empty-room", None, {"duration": "5s", "go_home": "false"}, 30.0)
    assert _stopped(caplog.messages) == ["cleaning stopped: the time is up (5s)"]
    caplog.clear()
    low = tmp_path / "low.yaml"
    low.write_text(
        "rooms: [[[0, 0], [3, 0], [3, 2.5], [0, 2.5]]]\n"
        "robot: {start: {at: [1.5, 1.2], heading: 0}, battery: 0.1}\n"
    )
    _clean_on_the_simulator(str(low), None, {}, 2.0)
    assert _stopped(caplog.messages) == ["cleaning stopped: the battery is below 15%"]


class _HostDiesLink(SimLink):
    """The host dies (kill -9, a cable pulled) 3 s into the run: nothing it writes from then on
    reaches the robot, which keeps its last command (the OI has no command timeout)."""

    def write(self, data: bytes) -> None:
        if self.simulator.time < 3.0:
            super().write(data)


def test_clean_stops_at_the_stairs_when_the_host_dies_mid_lane() -> None:
    """The stairs ahead, the host gone while the robot drives at them: in Safe the firmware
    stops it at the edge (Passive); in Full it went down the stairs ("fell")."""
    stairs = Pose(4600.0, 800.0, 0.0)  # the apartment, 1.6 m from its stairs, facing them
    sim, _, _ = _clean_on_the_simulator("apartment", stairs, {}, 5.0, _HostDiesLink)
    assert sim.left_speed > 0 or sim.mode is OIMode.PASSIVE  # driving when the host died
    for _ in range(round(30.0 / 0.015)):  # the robot alone for 30 s
        sim.step()
        sim.read()
    assert not sim.fallen
    assert sim.mode is OIMode.PASSIVE
    assert any("safety: cliff" in m for m in _modes(sim))


def test_clean_with_mode_full_is_the_owners_choice(cliff_world: str) -> None:
    """``-p mode=full`` keeps the brushes running at a cliff (no drop to Passive): for an
    owner who accepts that a dead host leaves the robot driving with no cliff stop."""
    sim, summary, _ = _clean_on_the_simulator(
        cliff_world, None, {"duration": "1min", "go_home": "false", "mode": "full"}, 200.0
    )
    assert summary.outcome.value == "success", summary.reason
    assert any("Full" in m for m in _modes(sim)) and not sim.fallen


def test_clean_started_on_the_dock_backs_off_it_before_safe() -> None:
    """Safe on a powered charger drops to Passive at once: off the dock first (in Full, 25 cm
    back), then Safe and cleaning."""
    dock = load_world("empty-room").dock
    assert dock is not None
    sim, summary, _ = _clean_on_the_simulator(
        "empty-room", dock.docked_pose, {"duration": "1min", "go_home": "false"}, 200.0
    )
    assert summary.outcome.value == "success", summary.reason
    assert sim.swept is not None and sim.swept.coverage() >= 0.2


@pytest.mark.parametrize(("odometry_error", "seed"), [(0.0, 6), (0.015, 0)])
def test_clean_goes_home_by_its_map_before_searching_for_the_beams(
    odometry_error: float, seed: int
) -> None:
    """Done cleaning, it drives back along its map to where it saw the dock's beams before
    the dock search. Seed 0 in the living room: 43 s from the end of cleaning to the dock by
    the search alone, 20 s by its map; with the encoders' error the search alone ran out of
    the run's time (347 s, not docked), by its map 81 s. With exact encoders, seed 6 since
    session 36 (19 s home; 32 s before): seed 0's cleaning, its back-offs looking behind
    them now (behaviours/reversing.py), ends elsewhere, and its way home ends wedged against
    the dock's side, at (1.33, 0.17) m, heading 148 deg, where ``dock.yaml`` started on main
    stays wedged for its 10 minutes too (the approach's, not the cleaning's: not mended).

    Those were 20-minute cleans; 10 minutes (session 42: half the CPU, 6 s a run) end as far
    from the dock, 58-65 % of the room swept: home by the map in 23 s (seed 6) and 22 s (seed
    0, the encoders' error); with ``home_by_map`` taken out of clean.yaml both runs' 30 s
    past the cleaning ran out in the dock search, not docked (the test fails)."""
    result = _living_room("clean", seed, 10, odometry_error=odometry_error)
    assert result.outcome == "success", result.reason
    assert result.docked and result.charging
    assert result.coverage is not None
    home_s = result.time_s - result.coverage.cleaning_s  # the way home, the drops' ticks
    assert home_s < (30.0 if odometry_error == 0.0 else 150.0), home_s


@pytest.mark.parametrize("brush", ["main_brush", "side_brush"])
def test_clean_stops_a_jammed_brush_goes_home_and_fails_naming_it(
    brush: str, tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    """A brush overcurrent (packet 14: hair, a phone cable) was ignored for the whole run, the
    brush driven for 20 minutes: cleaning stops at once, the brushes and vacuum off, the
    reason said (the summary's ``mission said`` line), and the robot goes home with them off.
    Docked, the run FAILS naming the brush (exit 1): it ended SUCCESS until session 35, and an
    unattended run's owner (cron, a scheduler reading the exit code) took the floor for done
    and the brush for free."""
    caplog.set_level(logging.INFO, logger="roomba_bt.mission")
    tangled = tmp_path / "tangled.yaml"
    tangled.write_text(
        "rooms: [[[0, 0], [3, 0], [3, 2.5], [0, 2.5]]]\n"
        "dock: {at: [1.5, 0], facing: 90}\n"
        "robot: {start: {at: [1.5, 1.2], heading: 0}}\n"
        f"events: [{{at: 20, kind: overcurrent, motor: {brush}, duration: 3}}]\n"
    )
    sim, summary, _ = _clean_on_the_simulator(str(tangled), None, {}, 600.0)
    assert _stopped(caplog.messages) == [
        "cleaning stopped: a brush is jammed (its overcurrent, packet 14): free it before the "
        "next run"
    ]
    named = brush.replace("_", " ")
    assert summary.outcome.value == "failure"
    assert summary.exit_code == 1
    assert summary.reason == (
        "cleaning cut short by a jammed brush: brushes is "
        f"'the {named} jammed (its overcurrent, packet 14)', not == 'free'"
    )
    assert summary.said is not None and "a brush is jammed" in summary.said
    assert sim.docked and sim.mode is OIMode.PASSIVE
    assert sim.swept is not None and sim.swept.cleaning_time < 24.0  # stopped at 20 s


#: An owner's living room (5 x 4 m, a 1.2 m hall, a TV stand on the west wall), started on
#: the dock: at 17 % the way home met the stand's side beyond the bumper's reach
LIVING_ROOM = """
rooms: [{rect: [0, 0, 7, 4]}]
walls: [[5, 0, 5, 1.6], [5, 2.4, 5, 4], [5, 1.2, 7, 1.2], [5, 2.8, 7, 2.8]]
obstacles:
  - {name: sofa, rect: [1.0, 3.1, 3.2, 4.0]}
  - {name: armchair, rect: [3.6, 3.2, 4.4, 4.0]}
  - {rect: [1.5, 2.0, 1.55, 2.05]}
  - {rect: [2.65, 2.0, 2.7, 2.05]}
  - {rect: [1.5, 2.6, 1.55, 2.65]}
  - {rect: [2.65, 2.6, 2.7, 2.65]}
  - {rect: [3.3, 0.5, 3.36, 0.56]}
  - {rect: [4.34, 0.5, 4.4, 0.56]}
  - {rect: [3.3, 1.24, 3.36, 1.3]}
  - {rect: [4.34, 1.24, 4.4, 1.3]}
  - {rect: [3.5, 1.45, 3.53, 1.48]}
  - {rect: [3.9, 1.45, 3.93, 1.48]}
  - {rect: [3.5, 1.85, 3.53, 1.88]}
  - {rect: [3.9, 1.85, 3.93, 1.88]}
  - {rect: [3.5, 0.05, 3.53, 0.08]}
  - {rect: [3.9, 0.05, 3.93, 0.08]}
  - {rect: [3.5, 0.3, 3.53, 0.33]}
  - {rect: [3.9, 0.3, 3.93, 0.33]}
  - {name: tv-stand, rect: [0.0, 1.0, 0.4, 2.6]}
drops: [{rect: [6.6, 1.2, 7.0, 2.8]}]
dock: {at: [0.8, 0.0], facing: 90}
robot: {start: {at: [0.8, 0.172], heading: -90}, battery: 0.17}
"""


def test_the_way_home_backs_off_a_wedge_rather_than_pushing_for_minutes(tmp_path: Path) -> None:
    """At 17 % the way home stalled against the TV stand's side (no bump shown), and each of
    ``home_by_map``'s plans pushed the same way again: 5 attempts of 75 s, 6.5 minutes of
    battery spent with the wheels stalled, then the search found the dock 1.4 m away. A leg
    that makes no progress is now left as after a bump (backed off, its cell avoided)."""
    living = tmp_path / "living.yaml"
    living.write_text(LIVING_ROOM)
    sim, summary, _ = _clean_on_the_simulator(str(living), None, {}, 900.0)
    assert summary.outcome.value == "success", summary.reason
    assert sim.docked
    assert sim.time < 300.0  # docked at 586 s before, cleaning having stopped at 194 s
    assert summary.unheard == 0  # the wheels never stood still for a second under a drive
