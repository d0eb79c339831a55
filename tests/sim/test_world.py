"""Worlds: the shipped ones, and errors that name file:line:col, the field, what was found
and what is allowed, all at once, never a traceback."""

from __future__ import annotations

import math
import pathlib

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from roomba_bt import printable, yamlsource
from roomba_bt.oi import commands as C
from roomba_bt.sim import WorldError, load_world, parse_world, shipped_worlds
from roomba_bt.sim import world as world_module
from roomba_bt.sim.world import ROBOT_RADIUS_MM

from .helpers import make, pose


def problems(text: str) -> list[str]:
    with pytest.raises(WorldError) as info:
        parse_world(text, "w.yaml")
    return [str(p) for p in info.value.problems]


def test_three_worlds_are_shipped_and_load() -> None:
    assert {"empty-room", "apartment", "corridor"} <= set(shipped_worlds())
    for name in shipped_worlds():
        world = load_world(name)
        assert world.pose_is_free(world.start)


def test_empty_room_starts_within_1_5_m_of_the_dock_and_samples_starts_there() -> None:
    world = load_world("empty-room")
    assert world.dock is not None
    docked = world.dock.docked_pose
    assert math.hypot(world.start.x - docked.x, world.start.y - docked.y) <= 1500.0
    headings = []
    for seed in range(40):
        start = world.sample_start(seed)
        assert math.hypot(start.x - docked.x, start.y - docked.y) <= 1500.0
        assert world.pose_is_free(start)
        headings.append(start.theta)
        assert world.sample_start(seed) == start
    assert max(headings) - min(headings) > math.pi  # any heading


def test_apartment_has_furniture_a_staircase_and_a_virtual_wall() -> None:
    world = load_world("apartment")
    assert len(world.obstacles) >= 5 and world.drops and world.virtual_walls
    stairs = world.drops[0]
    x = sum(p[0] for p in stairs) / len(stairs)
    y = sum(p[1] for p in stairs) / len(stairs)
    assert world.on_floor(x, y) and world.over_drop(x, y)


def test_corridor_is_a_loop() -> None:
    world = load_world("corridor")
    # free poses on all four sides of the central block
    for x, y in ((4500, 600), (8400, 3000), (4500, 5400), (600, 3000)):
        assert world.on_floor(x, y)
    assert not world.on_floor(4500, 3000)


def test_load_world_by_path(tmp_path: pathlib.Path) -> None:
    path = tmp_path / "mine.yaml"
    path.write_text("rooms: [[[0, 0], [3, 0], [3, 3], [0, 3]]]\n")
    world = load_world(path)
    assert world.name == "mine" and world.start.x == 1500.0


def test_unknown_world_lists_the_shipped_ones() -> None:
    with pytest.raises(WorldError, match="empty-room"):
        load_world("nowhere")


def test_unknown_key_with_line_column_and_did_you_mean() -> None:
    text = (
        "rooms: [[[0, 0], [3, 0], [3, 3], [0, 3]]]\n"
        "dock:\n  at: [1.5, 0]\n  facing: 90\n  buoy_rang: 2\n"
    )
    [problem] = problems(text)
    assert problem.startswith("w.yaml:5:3: dock.buoy_rang: found unknown key 'buoy_rang'")
    assert "did you mean 'buoy_range'?" in problem


def test_out_of_range_values_say_what_is_allowed() -> None:
    text = (
        "rooms: [[[0, 0], [3, 0], [3, 3], [0, 3]]]\n"
        "dock: {at: [1.5, 0], facing: 90, buoy_range: 9, red: [30, 10]}\n"
        "robot: {battery: 1.5}\n"
    )
    found = problems(text)
    assert "w.yaml:2:46: dock.buoy_range: found 9; allowed: a number in 0.2..5 m" in found
    assert any(
        "dock.red: found a list of 2; allowed: [from, to] with from < to" in p for p in found
    )
    assert any("w.yaml:3:18: robot.battery: found 1.5" in p for p in found)
    assert len(found) == 3  # all at once


def test_wrong_types_and_missing_fields() -> None:
    found = problems("name: 3\nrooms: [[[0, 0], [1, 'x']]]\nevents: [{kind: lift}]\n")
    assert any("w.yaml:1:7: name: found 3; allowed: a string" in p for p in found)
    assert any("rooms[0]: found a list of 2; allowed: a polygon" in p for p in found)
    assert any("events[0]: found no 'at'" in p for p in found)
    assert problems("walls: []\n") == [
        "w.yaml:1:1: (document): found no 'rooms'; allowed: a mapping with 'rooms'"
    ]


def test_bad_event_kind_suggests_the_right_one() -> None:
    [problem] = problems(
        "rooms: [[[0, 0], [3, 0], [3, 3], [0, 3]]]\nevents: [{at: 1, kind: lifted}]\n"
    )
    assert (
        "events[0].kind: found 'lifted'; allowed: one of bump, lift, charger_step, press" in problem
    )
    assert "did you mean 'lift'?" in problem


def test_an_overcurrent_event_names_a_motor_of_packet_14() -> None:
    """``motor`` is one of packet 14's names, only with ``kind: overcurrent``, and needed there."""
    found = problems(
        "rooms: [[[0, 0], [3, 0], [3, 3], [0, 3]]]\nevents:\n"
        "  - {at: 1, kind: overcurrent, motor: brush}\n"
        "  - {at: 2, kind: overcurrent}\n"
        "  - {at: 3, kind: bump, motor: main_brush}\n"
    )
    assert found == [
        "w.yaml:3:39: events[0].motor: found 'brush'; allowed: one of side_brush, main_brush, "
        "right_wheel, left_wheel (did you mean 'side_brush'?)",
        "w.yaml:4:5: events[1]: found no 'motor'; allowed: kind: overcurrent with a motor: "
        "side_brush, main_brush, right_wheel, left_wheel",
        "w.yaml:5:32: events[2].motor: found a motor for a bump; allowed: motor only with "
        "kind: overcurrent",
    ]


def test_a_press_event_takes_a_button_and_lasts_the_specs_press() -> None:
    room = "rooms: [[[0, 0], [3, 0], [3, 3], [0, 3]]]\n"
    [event] = parse_world(room + "events: [{at: 1, kind: press, button: clean}]\n").events
    assert (event.time, event.kind, event.button, event.duration) == (1.0, "press", "clean", 1 / 6)
    found = problems(
        room + "events:\n"
        "  - {at: 1, kind: press, button: clen}\n"
        "  - {at: 2, kind: press, duration: 2}\n"
        "  - {at: 3, kind: bump, button: clean}\n"
    )
    assert found == [
        "w.yaml:3:34: events[0].button: found 'clen'; allowed: one of clean, spot, dock, "
        "minute, hour, day, schedule, clock (did you mean 'clean'?)",
        "w.yaml:4:5: events[1]: found no 'button'; allowed: kind: press with a button: clean, "
        "spot, dock, minute, hour, day, schedule, clock",
        "w.yaml:4:36: events[1].duration: found a duration for a press; allowed: at, kind: "
        "press, button (a press lasts the spec's 1/6 s)",
        "w.yaml:5:33: events[2].button: found a button for a bump; allowed: button only with "
        "kind: press",
    ]


def test_duplicate_keys_and_yaml_syntax_errors_have_positions() -> None:
    # every duplicate, and the world's other problems with them, in the file's order (the
    # first duplicate was all a world file said)
    found = problems(
        "name: a\nrooms:\n  - name: r\n    name: s\n    outline: [[0, 0], [1, 0], [1, 1]]\n"
        "name: b\nseed: x\n"
    )
    assert found == [
        "w.yaml:3:5: rooms[0]: found neither or both of rect/polygon; allowed: exactly one of "
        "rect, polygon",
        "w.yaml:4:5: rooms[0].name: found the key 'name' again (first at line 3); allowed: each "
        "key once",
        "w.yaml:5:5: rooms[0].outline: found unknown key 'outline'; allowed: name, rect, polygon",
        "w.yaml:6:1: name: found the key 'name' again (first at line 1); allowed: each key once",
        "w.yaml:7:1: seed: found unknown key 'seed'; allowed: name, description, rooms, walls, "
        "obstacles, drops, dirt, virtual_walls, lighthouses, dock, robot, events, areas",
    ]
    [syntax] = problems("rooms: [[[0, 0]\n")
    assert syntax == "w.yaml:2:1: YAML syntax error: expected ',' or ']', but got '<stream end>'"


def _pure_compose(text: str) -> object:
    return yamlsource.compose(text, yamlsource.PURE_LOADER)


@pytest.mark.parametrize("name", shipped_worlds())
def test_a_shipped_world_reads_the_same_by_either_yaml_parser(
    name: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Worlds are read by libyaml where installed (faster): the same world, every position
    the same, as PyYAML's own parser reads."""
    text = (world_module.WORLDS_DIR / f"{name}.yaml").read_text()
    fast = parse_world(text, f"{name}.yaml")
    monkeypatch.setattr(world_module, "_compose_world", _pure_compose)
    assert parse_world(text, f"{name}.yaml") == fast


@pytest.mark.parametrize(
    "text",
    ["rooms: [[[0, 0]\n", "rooms:\n  - [[0, 0]]\n - x\n", "rooms: {a: 1\n", "a: *r\n",
     "rooms: !!int 3\n", "name: 'x\n"],
)  # fmt: skip
def test_a_broken_world_s_message_is_py_yaml_s_own_whichever_parser_read_it(
    text: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    """libyaml's syntax messages differ from PyYAML's: a text libyaml refuses is read again
    by PyYAML's parser, so the problem and its position do not depend on libyaml."""
    found = problems(text)
    monkeypatch.setattr(world_module, "_compose_world", _pure_compose)
    assert problems(text) == found


def test_a_start_pose_inside_a_wall_is_refused() -> None:
    text = "rooms: [[[0, 0], [3, 0], [3, 3], [0, 3]]]\nrobot: {start: {at: [0.1, 1], heading: 0}}\n"
    [problem] = problems(text)
    assert problem.startswith("w.yaml:2:")
    assert "robot.start: found a start pose (0.10, 1.00) m where the robot does not fit" in problem
    assert f"at least {ROBOT_RADIUS_MM / 1000:.2f} m from every wall" in problem


@pytest.mark.parametrize("facing", [90, 0, 45, 135, 200, -30])
def test_the_docked_pose_is_a_start_pose(facing: float) -> None:
    """The robot starting on the dock, at the docked pose the docs give (0.17 m in front of
    the plate, facing it): 0.17 was refused as not fitting, 0.171 taken. Touching the plate
    (and the wall behind it) fits; a millimetre closer does not."""
    room = "rooms: [[[-3, -3], [3, -3], [3, 3], [-3, 3]]]\n"
    dock = parse_world(f"{room}dock: {{at: [0, 0], facing: {facing}}}\n").dock
    assert dock is not None
    docked = dock.docked_pose
    at, heading = (docked.x / 1000, docked.y / 1000), math.degrees(docked.theta)
    text = (
        f"{room}dock: {{at: [0, 0], facing: {facing}}}\n"
        f"robot: {{start: {{at: [{at[0]!r}, {at[1]!r}], heading: {heading!r}}}}}\n"
    )
    world = parse_world(text, "w.yaml")
    assert world.pose_is_free(world.start)
    closer = 0.169 / 0.170
    nearer = text.replace(f"[{at[0]!r}, {at[1]!r}]", f"[{at[0] * closer!r}, {at[1] * closer!r}]")
    assert any("where the robot does not fit" in p for p in problems(nearer))


def test_near_dock_start_region_needs_a_dock() -> None:
    text = "rooms: [[[0, 0], [3, 0], [3, 3], [0, 3]]]\nrobot: {start_region: {near_dock: 1}}\n"
    assert any("near_dock only in a world with a dock" in p for p in problems(text))


def test_yaml_tags_that_build_objects_are_refused() -> None:
    [problem] = problems("rooms: !!python/object:os.system {}\n")
    assert problem.startswith("w.yaml:1:8: explicit tag !!python/object:os.system is not allowed")


DIRTY = """
name: dirty
rooms: [[[0, 0], [4, 0], [4, 4], [0, 4]]]
dirt:
  - {name: crumbs, rect: [2.5, 1.5, 3.0, 2.5], level: 40}
  - {polygon: [[2.8, 1.5], [3.5, 1.5], [3.5, 2.5]], level: 90}
robot: {start: {at: [2, 2], heading: 0}}
"""


def test_dirt_patches_set_packet_15_where_the_robot_is() -> None:
    world = parse_world(DIRTY, "w.yaml")
    assert [d.level for d in world.dirt] == [40, 90]
    assert (world.dirt_at(2000, 2000), world.dirt_at(2600, 2000)) == (0, 40)
    assert world.dirt_at(3200, 1600) == 90  # the higher of two overlapping patches
    host = make(DIRTY, start=pose(2.0, 2.0, 0))
    host.stream([15])
    assert host.frame().dirt_detect == 0  # clean floor
    host.send(C.drive(200, 32768))
    levels = [f.dirt_detect for f in host.frames(4.0)]
    assert levels[0] == 0 and 40 in levels  # drove onto the crumbs
    assert make(DIRTY, start=pose(2.7, 2.0, 0)).query([15]).dirt_detect == 40


def test_a_world_without_dirt_reads_0_and_bad_dirt_is_named() -> None:
    assert load_world("empty-room").dirt == ()
    found = problems(
        "rooms: [[[0, 0], [4, 0], [4, 4], [0, 4]]]\n"
        "dirt: [{rect: [1, 1, 2, 2], level: 0}, {rect: [1, 1, 2, 2]},\n"
        "       {rect: [1, 1, 2, 2], level: x}]\n"
    )
    assert len(found) == 3, found
    assert all("dirt" in p and "level" in p and "1..255" in p for p in found)
    assert found[0].startswith("w.yaml:2:")


def test_yaml_aliases_and_scalar_tags_in_a_world_are_refused_at_their_place() -> None:
    [alias] = problems("a: &r [[0, 0], [3, 0], [3, 3], [0, 3]]\nrooms: [*r]\n")
    assert alias.startswith("w.yaml:2:9: alias *r is not allowed: write the value out")
    [tag] = problems("rooms: [[[0, 0], [3, 0], [3, !!int x], [0, 3]]]\n")
    assert tag.startswith("w.yaml:1:30: explicit tag !!int is not allowed: write the plain value")


def test_every_alias_tag_and_control_character_of_a_world_is_refused_at_once() -> None:
    """Only the first was said: fixing it showed the next."""
    found = problems(
        "a: &r [[0, 0], [3, 0], [3, 3], [0, 3]]\n"
        "rooms: [*r, [[0, 0], [3, 0], [3, !!int x], [0, 3]]]\n"
        'name: "\\e[2J"\n'
    )
    assert [p.split(" is not allowed")[0] for p in found] == [
        "w.yaml:2:9: alias *r",
        "w.yaml:2:34: explicit tag !!int",
        "w.yaml:3:7: control character U+001B (an escape such as \\e, \\x1b or \\a in quotes)",
    ]


def test_a_world_of_many_aliases_reads_its_text_once_not_once_an_alias(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Each refused alias or tag was given the syntax error's tab hint and look-alike cause,
    which split the whole text into lines: a 600 KB world of 100,000 aliases took hours to
    refuse (``run --world``, ``validate``). A refusal is no syntax error: neither is asked."""
    split: list[int] = []
    real_hint = yamlsource.tab_hint
    monkeypatch.setattr(
        yamlsource, "tab_hint", lambda t, ln, c: split.append(ln) or real_hint(t, ln, c)
    )
    monkeypatch.setattr(yamlsource, "lookalike_cause", lambda t, ln, c: split.append(ln))
    found = problems("r: &r [[0, 0], [3, 0], [3, 3], [0, 3]]\nrooms: [" + "*r, " * 2000 + "*r]\n")
    assert len(found) == 2001 and split == []
    assert found[-1].startswith("w.yaml:2:8009: alias *r is not allowed")
    [tab] = problems("rooms: [[[0, 0], [3, 0], [3, 3], [0, 3]]]\n\tname: x\n")
    assert tab.endswith("(a tab: YAML indents with spaces)") and split == [2]


@pytest.mark.parametrize(
    "text",
    [
        "root:x:0:0:root:/root:/bin/bash\n" * 40,  # a page in one scalar (/etc/passwd)
        "root:*:20228:0:99999:7:::\ndaemon:*:20228:0:99999:7:::\n",  # keys (/etc/shadow)
        "db.example.com:5432:prod:admin:S3cretPgPass\n",  # ~/.pgpass
        "- https://alice:ghp_SECRETTOKEN@github.com\n",  # a list
    ],
)
def test_a_file_that_is_no_world_is_said_so_and_never_quoted(text: str) -> None:
    """A world given some other text file quoted its lines back (its scalar, or each line
    as an unknown key): a stranger's record naming ``/etc/shadow`` as its world had the
    monitor print the password hashes. It is said not to be a world, as a file that is not
    a mission is, and nothing of it is shown."""
    (problem,) = problems(text)
    assert problem == (
        "w.yaml:1:1: this file is not a world file: expected a mapping with some of name, "
        "description, rooms, walls, obstacles, drops, dirt, virtual_walls, lighthouses, dock, "
        "robot, events, areas"
    )


def test_a_tab_and_a_byte_that_is_not_utf8_in_a_world_are_placed(tmp_path: pathlib.Path) -> None:
    assert problems("rooms:\n\t- [[0, 0]]\n") == [
        "w.yaml:2:1: YAML syntax error: found character '\\t' that cannot start any token"
        " (a tab: YAML indents with spaces)"
    ]
    latin = tmp_path / "latin.yaml"
    latin.write_bytes(b"name: caf\xe9\n")
    with pytest.raises(WorldError) as info:
        load_world(str(latin))
    assert [str(p) for p in info.value.problems] == [
        f"{latin}:1:10: world: found byte 0xe9, not UTF-8 text (invalid continuation byte; it "
        "reads as '\xe9' in Windows-1252 or Latin-1, an older encoding: save the file as UTF-8); "
        "allowed: a UTF-8 YAML file"
    ]


@pytest.mark.parametrize(
    ("shape", "sides"),
    [
        # points out of order: a bow tie (its area is not zero, so that check lets it by)
        ("[[0, 0], [4, 4], [4, 0], [0, 3]]", "[0, 0]-[4, 4] and [4, 0]-[0, 3]"),
        # a corner on a side that is not its own: the floor pinched to a point
        ("[[0, 0], [4, 0], [4, 4], [2, 0], [0, 4]]", "[0, 0]-[4, 0] and [4, 4]-[2, 0]"),
    ],
)
def test_a_polygon_whose_sides_cross_is_refused_naming_them(shape: str, sides: str) -> None:
    assert problems(f"rooms: [{shape}]\n") == [
        f"w.yaml:1:9: rooms[0]: found a polygon whose sides cross ({sides}); allowed: a "
        "polygon whose points go once around it, in order (its sides meet only at its corners)"
    ]
    # obstacles, drops, dirt and areas are read by the same polygon check
    found = problems(
        f"rooms: [[[0, 0], [5, 0], [5, 5], [0, 5]]]\nobstacles: [{{name: x, polygon: {shape}}}]\n"
    )
    assert len(found) == 1 and "obstacles[0].polygon: found a polygon whose sides cross" in found[0]


def test_a_world_path_that_is_a_directory_or_a_device_is_named_so(tmp_path: pathlib.Path) -> None:
    for where, found in (
        (tmp_path, "a directory"),
        ("/dev/null", "a device or a pipe, not a file"),
    ):
        with pytest.raises(WorldError) as info:
            load_world(where)
        assert str(info.value.problems[0]).startswith(f"{where}: world: found {found}; allowed:")


def test_a_world_nested_deeper_than_the_reader_allows_is_refused_where_it_goes_over() -> None:
    """A world nested 990 deep was a RecursionError traceback out of ``roomba-bt run``."""
    deep = "[" * 989 + "0" + "]" * 989
    [problem] = problems(f"rooms: {deep}\n")
    column = 8 + yamlsource.MAX_NESTING - 1  # the list that is one too deep
    assert problem.startswith(f"w.yaml:1:{column}: lists and mappings nested more than ")


def test_a_world_file_over_a_mebibyte_is_named_not_read(tmp_path: pathlib.Path) -> None:
    path = tmp_path / "huge.yaml"
    path.write_text("rooms: [[[0, 0], [3, 0], [3, 3], [0, 3]]]\n# " + "x" * (1 << 20) + "\n")
    with pytest.raises(WorldError) as info:
        load_world(str(path))
    [problem] = [str(p) for p in info.value.problems]
    assert "at most 1,048,576 are read" in problem


def _every_pair_crossing(poly: tuple[tuple[float, float], ...]) -> tuple[int, int] | None:
    """The first crossing as every pair of sides finds it (the reference)."""
    from roomba_bt.sim.geometry import segments_meet

    n = len(poly)
    for a in range(n):
        for b in range(a + 1, n):
            if b == a + 1 or (a == 0 and b == n - 1):
                continue
            if segments_meet(poly[a], poly[(a + 1) % n], poly[b], poly[(b + 1) % n]):
                return a, b
    return None


_GRID_POINT = st.tuples(st.integers(0, 8), st.integers(0, 8)).map(
    lambda p: (p[0] * 250.0, p[1] * 250.0)  # on a grid: collinear and touching sides are common
)


@settings(max_examples=300, deadline=None)
@given(st.lists(_GRID_POINT, min_size=3, max_size=12, unique=True))
def test_the_grid_finds_the_crossing_every_pair_finds(points: list[tuple[float, float]]) -> None:
    poly = tuple(points)
    assert world_module._first_crossing(poly) == _every_pair_crossing(poly)


def test_a_floor_plan_of_many_points_tests_few_pairs(monkeypatch: pytest.MonkeyPatch) -> None:
    """Every pair of sides was tested: a 10,000-point floor plan (200 KB) took 37 s to load.
    Counted, not timed: the pairs tested grow with the points, not with their square."""
    from roomba_bt.sim import geometry

    tested = 0

    def counting(*args: tuple[float, float]) -> bool:
        nonlocal tested
        tested += 1
        return geometry.segments_meet(*args)

    monkeypatch.setattr(world_module, "segments_meet", counting)
    n = 4000
    circle = tuple(
        (5000 + 4000 * math.cos(math.tau * i / n), 5000 + 4000 * math.sin(math.tau * i / n))
        for i in range(n)
    )
    assert world_module._first_crossing(circle) is None
    assert tested < 10 * n  # every pair: n (n - 3) / 2, about 8 million
    bow = (circle[0], circle[2], circle[1], *circle[3:])  # two points out of order
    assert world_module._first_crossing(bow) == _every_pair_crossing(bow) == (0, 2)


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        # no robot.start: the default start was blamed on "rooms" as if the user wrote it
        (
            "rooms:\n  - [[0, 0], [4, 0], [4, 3], [0, 3]]\n  - [[1, 1], [2, 1], [2, 2], [1, 2]]\n",
            [
                "w.yaml:2:3: rooms: found no robot.start, and the default start pose "
                "(2.00, 1.50) m (the first room's middle) is where the robot does not fit"
            ],
        ),
        # a dock off the floor put the default start off the floor: said once, at the dock
        (
            "rooms: [[[0, 0], [4, 0], [4, 3], [0, 3]]]\ndock: {at: [10, 10], facing: 90}\n",
            ["w.yaml:2:12: dock.at: found a dock off the floor"],
        ),
        # a region with no room had no place at all (found when an episode started)
        (
            "rooms: [[[0, 0], [4, 0], [4, 3], [0, 3]]]\nrobot:\n"
            "  start_region: {rect: [10, 10, 12, 12], heading: any}\n",
            ["w.yaml:3:17: robot.start_region: found a region with no free pose for the robot"],
        ),
        # a region alone named robot.start
        (
            "rooms: [[[0, 0], [4, 0], [4, 3], [0, 3]]]\nobstacles: [{rect: [1.5, 1, 2.5, 2]}]\n"
            "robot:\n  start_region: {rect: [0.3, 0.3, 1, 1], heading: any}\n",
            ["w.yaml:1:8: rooms: found no robot.start, and the default start pose"],
        ),
    ],
)
def test_a_start_the_file_does_not_give_is_said_to_be_the_default(
    text: str, expected: list[str]
) -> None:
    found = problems(text)
    assert len(found) == len(expected), found
    for line, start in zip(found, expected, strict=True):
        assert line.startswith(start), line


def test_an_upside_down_rect_says_which_corner_is_wrong() -> None:
    [found] = problems(
        "rooms: [[[0, 0], [4, 0], [4, 3], [0, 3]]]\nobstacles: [{rect: [2, 1, 1, 3]}]\n"
    )
    # it said "found a list of 4"
    assert found == (
        "w.yaml:2:20: obstacles[0].rect: found [2, 1, 1, 3]: x0 2 not below x1 1; allowed: "
        "x0 < x1 and y0 < y1"
    )


def test_a_misspelt_shipped_world_is_named() -> None:
    with pytest.raises(
        WorldError, match=r"no such file or shipped world \(did you mean 'apartment'"
    ):
        world_module.load_world("apartmnt")


def test_a_bowtie_is_said_to_cross_not_to_have_no_area() -> None:
    """Its two halves' areas cancel: it read "a polygon of zero area", which said nothing of
    the points written out of order."""
    [found] = problems("rooms: [[[0, 0], [4, 3], [4, 0], [0, 3]]]\n")
    assert "found a polygon whose sides cross ([0, 0]-[4, 3] and [4, 0]-[0, 3])" in found
    [flat] = problems("rooms: [[[0, 0], [1, 0], [2, 0]]]\n")
    assert "found a polygon of zero area" in flat


def test_shapes_wholly_outside_every_room_are_named() -> None:
    """An obstacle at [10, 10] in a 4 m room (centimetres written for metres) loaded and did
    nothing; likewise a drop, dirt or an area. A drop sticking out of a room (stairs drawn
    past the wall) is fine."""
    found = problems(
        "rooms: [[[0, 0], [4, 0], [4, 3], [0, 3]]]\n"
        "obstacles: [{rect: [100, 100, 150, 150]}, {rect: [1, 1, 1.5, 1.5]}]\n"
        "drops: [{rect: [3, -1, 5, 1]}, {rect: [-3, 0, -1, 1]}]\n"
        "dirt: [{rect: [5, 5, 6, 6], level: 9}]\n"
        "areas: [{name: big, rect: [-1, -1, 5, 4]},\n"
        "        {name: far, polygon: [[9, 9], [10, 9], [9, 10]]}]\n"
        "robot: {start: {at: [2.5, 2], heading: 0}}\n"
    )
    assert found == [
        "w.yaml:2:13: obstacles[0]: found a shape wholly outside every room (x 100..150, "
        "y 100..150 m); allowed: a shape on a room's floor, in metres",
        "w.yaml:3:32: drops[1]: found a shape wholly outside every room (x -3..-1, y 0..1 m); "
        "allowed: a shape on a room's floor, in metres",
        "w.yaml:4:8: dirt[0]: found a shape wholly outside every room (x 5..6, y 5..6 m); "
        "allowed: a shape on a room's floor, in metres",
        "w.yaml:6:9: areas[1]: found a shape wholly outside every room (x 9..10, y 9..10 m); "
        "allowed: a shape on a room's floor, in metres",
    ]


def test_a_dock_at_the_top_of_the_stairs_is_refused() -> None:
    """The docked robot's centre stands 0.17 m out from the dock: over a drop there, every
    docking ends down the stairs."""
    [found] = problems(
        "rooms: [[[0, 0], [4, 0], [4, 3], [0, 3]]]\ndrops: [{rect: [3, 0, 4, 0.5]}]\n"
        "dock: {at: [3.5, 0], facing: 90}\nrobot: {start: {at: [1, 1.5], heading: 0}}\n"
    )
    assert found.startswith(
        "w.yaml:3:12: dock.at: found a dock whose docked robot stands over a drop"
    )


SOUTH_WALL_ROOM = "rooms: [{rect: [0, 0, 5, 4]}]\nrobot: {start: {at: [2.5, 2], heading: 0}}\n"


def test_a_dock_whose_docked_robot_would_stand_in_the_wall_is_refused_at_facing() -> None:
    """A dock on the south wall with ``facing: 0`` validated ``ok``: its docked robot, 0.17 m
    along the wall, stands half in it, and the dock mission failed after 10 minutes. The
    start pose was checked for a fit; the docked pose is now, and ``facing`` is blamed
    (with the facing that fits), since the point is right."""
    [found] = problems(SOUTH_WALL_ROOM + "dock: {at: [0.8, 0], facing: 0}\n")
    assert found == (
        "w.yaml:3:30: dock.facing: found a dock (facing 0) whose docked robot, at (0.97, 0.00) "
        "m, does not fit there (0.17 m from the plate, it reaches into a wall or an obstacle or "
        "off the floor); allowed: a facing (deg) that turns the dock's front into the room: 90 "
        "here"
    )


def test_a_dock_facing_out_of_the_room_is_said_at_facing_not_at() -> None:
    """``facing: -90`` on the south wall read ``dock.at: found a dock off the floor``: the
    point is on the floor, and the mistake is the facing."""
    [found] = problems(SOUTH_WALL_ROOM + "dock: {at: [0.8, 0], facing: -90}\n")
    assert found == (
        "w.yaml:3:30: dock.facing: found a dock facing -90, out of the room; allowed: a facing "
        "(deg) that turns the dock's front into the room: 90 here"
    )


def test_a_dock_against_nothing_is_still_said_at_at() -> None:
    """Where no facing would do (the point off every room), ``at`` stays the one to mend."""
    [found] = problems(SOUTH_WALL_ROOM + "dock: {at: [9, 9], facing: 90}\n")
    assert found.startswith("w.yaml:3:12: dock.at: found a dock off the floor; allowed: a point")


def test_a_dock_touching_a_corner_s_other_wall_fits_as_the_start_pose_does() -> None:
    """The docked pose touching a wall fits (as a start pose does): a dock 0.17 m from a
    corner is no mistake."""
    world = parse_world(SOUTH_WALL_ROOM + "dock: {at: [0.17, 0], facing: 90}\n", "w.yaml")
    assert world.dock is not None


def test_a_room_written_in_centimetres_is_questioned() -> None:
    """``rect: [0, 0, 500, 400]`` loaded as a 500 m hall: every obstacle in metres fit in it,
    so the check for shapes outside every room never fired."""
    found = problems("rooms: [{rect: [0, 0, 500, 400]}]\nobstacles: [{rect: [1, 1, 2, 2]}]\n")
    assert found == [
        "w.yaml:1:9: rooms[0]: found a room 500 x 400 m across (did you write centimetres? "
        "500 cm is 5 m); allowed: a room at most 150 m across, in metres"
    ]


def test_a_room_may_be_written_as_a_rect() -> None:
    """Obstacles, drops and areas take ``{rect: ...}``; a room written so was refused."""
    world = parse_world("rooms: [{rect: [0, 0, 4, 3]}]\n", "w.yaml")
    assert world.rooms == (((0.0, 0.0), (4000.0, 0.0), (4000.0, 3000.0), (0.0, 3000.0)),)


def test_a_world_in_a_folder_the_user_cannot_enter_is_a_world_error(
    tmp_path: pathlib.Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """``--world np/w.yaml`` (np chmod 000) was a traceback from ``world_text``'s
    ``is_file``; simulated (the tests run as root) by a ``stat`` that fails."""
    import errno

    real_stat = pathlib.Path.stat

    def stat(self: pathlib.Path, *args: object, **kwargs: object) -> object:
        if "np" in self.parts[:-1]:
            raise PermissionError(errno.EACCES, "Permission denied", str(self))
        return real_stat(self, *args, **kwargs)  # type: ignore[arg-type]

    monkeypatch.setattr(pathlib.Path, "stat", stat)
    with pytest.raises(WorldError) as info:
        world_module.world_text(tmp_path / "np" / "w.yaml")
    (problem,) = info.value.problems
    assert str(problem) == (
        f"{tmp_path / 'np' / 'w.yaml'}: world: cannot be read: Permission denied; wanted: a "
        "world file (YAML text) this user may read"
    )


def test_a_nel_or_line_separator_in_a_world_is_refused_at_its_place() -> None:
    """Both were read as line breaks: every problem after them was a line off."""
    found = problems(
        "# a NEL \x85 here\nname: a \u2028 b\nrooms: [[[0, 0], [3, 0], [3, 3], [0, 3]]]\n"
    )
    assert [p.split(" is not allowed")[0] for p in found] == [
        "w.yaml:1:9: control character U+0085 (NEL)",
        "w.yaml:2:9: line separator U+2028",
    ]


def test_keys_one_true_and_one_point_oh_are_three_keys_of_a_world() -> None:
    """Each was reported as a duplicate of ``1`` ("duplicate key 'True'")."""
    found = problems("rooms: [[[0, 0], [3, 0], [3, 3], [0, 3]]]\n1: a\ntrue: b\n1.0: c\n")
    assert [p.split(";")[0] for p in found] == [
        "w.yaml:2:1: 1: found unknown key 1",
        "w.yaml:3:1: true: found unknown key 'true'",
        "w.yaml:4:1: 1.0: found unknown key '1.0'",
    ]


def test_a_world_s_battery_may_be_a_percent_as_the_command_line_s() -> None:
    """``--battery 80%`` was taken and ``robot: {battery: 80%}`` refused."""
    rooms = "rooms: [[[0, 0], [4, 0], [4, 3], [0, 3]]]\n"
    assert parse_world(rooms + "robot: {battery: 80%}\n", "w.yaml").battery == 0.8
    [found] = problems(rooms + "robot: {battery: 120%}\n")
    assert found == (
        "w.yaml:2:18: robot.battery: found '120%'; allowed: a number in 0..1 (or a percent, "
        "0%..100%)"
    )


@pytest.mark.parametrize("empty", ["0", "0%", "0.0"])
def test_a_world_s_empty_battery_is_refused_as_the_command_line_s(empty: str) -> None:
    """``--battery 0`` is refused (the simulated robot is off and answers nothing: the run
    ended NO CONNECTION, blaming the cable); ``robot: {battery: 0}`` in a world was taken."""
    rooms = "rooms: [[[0, 0], [4, 0], [4, 3], [0, 3]]]\n"
    [found] = problems(rooms + f"robot: {{battery: {empty}}}\n")
    assert found.startswith("w.yaml:2:18: robot.battery: found ")
    assert found.endswith(
        ": an empty battery switches the simulated robot off, and it would answer nothing; "
        "allowed: a charge above 0, up to 1 (0.05, 5%)"
    )


def test_where_things_stand_is_said_with_the_other_problems_at_once() -> None:
    """A drop outside every room was said only after the file's other problems were mended
    (a second reading); with the rooms whole it is said beside them. A start is not judged
    beside a dock in error (the default start leans on it): no error of its own."""
    found = problems(
        "rooms: [[[0, 0], [4, 0], [4, 3], [0, 3]]]\n"
        "drops: [{rect: [10, 10, 11, 11]}]\n"
        "dock: {at: [2, 0], facing: north}\n"
        "areas: [{name: a, rect: [0, 0, 2, 3]}, {name: a, rect: [2, 0, 4, 3]}]\n"
    )
    assert [f.split(": found")[0] for f in found] == [
        "w.yaml:2:9: drops[0]",
        "w.yaml:3:28: dock.facing",
        "w.yaml:4:47: areas[1].name",
    ], found
    # rooms in error: nothing is placed against them
    assert len(problems("rooms: [[[0, 0], [4, 0]]]\ndrops: [{rect: [10, 10, 11, 11]}]\n")) == 1


def test_a_start_off_the_floor_is_said_beside_a_battery_in_error() -> None:
    """A stranger's world with ``battery: 1.5`` and a start off the floor was said the
    battery alone (every ``robot`` problem kept the start from being judged), and the start
    only once the battery was mended: the start does not lean on the charge. Beside an
    error in the start itself, or in the dock it defaults from, it is still not judged."""
    rooms = "rooms: [[[0, 0], [4, 0], [4, 3], [0, 3]]]\n"
    found = problems(rooms + "robot: {start: {at: [5, 2]}, battery: 1.5}\n")
    assert [f.split(": found")[0] for f in found] == [
        "w.yaml:2:16: robot.start",
        "w.yaml:2:39: robot.battery",
    ], found
    assert "found a start pose (5.00, 2.00) m where the robot does not fit" in found[0]
    [found_one] = problems(rooms + "robot: {start: {at: [5, 2], heading: east}}\n")
    assert found_one.startswith("w.yaml:2:38: robot.start.heading: found "), found_one


def _many_obstacles(count: int) -> str:
    """A 40 m x 35 m room holding ``count`` small triangles, one a line (the hostile file's)."""
    rows = [
        f"  - {{polygon: [[{x},{y}],[{x + 0.05},{y}],[{x + 0.05},{y + 0.05}]]}}"
        for x, y in ((1 + i % 38, 1 + i // 38 / 10) for i in range(count))
    ]
    room = "rooms: [[[0, 0], [40, 0], [40, 35], [0, 35]]]\nrobot: {start: {at: [0.5, 0.5]}}\n"
    return room + "obstacles:\n" + "\n".join(rows) + "\n"


def test_a_list_of_more_items_than_a_home_needs_is_one_error_at_the_list() -> None:
    """12,000 small obstacles (700 KB) took 13 s to load, the floor map's fills linear in the
    count: a list is held to MAX_LIST_ITEMS with one error, not read item by item."""
    limit = world_module.MAX_LIST_ITEMS
    assert len(parse_world(_many_obstacles(limit), "w.yaml").obstacles) == limit
    [problem] = problems(_many_obstacles(limit + 1))
    assert problem == (
        f"w.yaml:4:3: obstacles: found {limit + 1:,} items; allowed: at most {limit:,} (a "
        "whole furnished home needs a few hundred)"
    )
    [problem] = problems(f"rooms: [{', '.join(['[[0, 0], [1, 0], [1, 1]]'] * (limit + 1))}]\n")
    assert f"rooms: found {limit + 1:,} items" in problem


@pytest.mark.parametrize("name", shipped_worlds())
def test_a_shipped_worlds_start_warns_of_nothing(name: str) -> None:
    """Each shipped world's given start keeps the whole body off its drops: none of the
    warnings a start at an edge gets (:func:`world_module._warn_if_over_a_drop`)."""
    world = load_world(name)
    assert world.warnings == ()
    assert world.nearest_drop(world.start)[1] >= world_module.ROBOT_RADIUS_MM


def test_a_utf16_world_and_a_link_to_no_world_say_what_they_are(
    tmp_path: pathlib.Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A world saved as Notepad's "Unicode" was "found byte 0xff, not UTF-8 text", where a
    mission's says UTF-16; a link that loops or leads nowhere was "no such file or shipped
    world", where a mission's says which."""
    monkeypatch.chdir(tmp_path)
    pathlib.Path("w16.yaml").write_bytes("name: x\n".encode("utf-16"))
    pathlib.Path("loop.yaml").symlink_to("loop.yaml")
    pathlib.Path("gone.yaml").symlink_to("moved.yaml")
    said = {}
    for name in ("w16.yaml", "loop.yaml", "gone.yaml"):
        with pytest.raises(WorldError) as info:
            load_world(name)
        said[name] = str(info.value.problems[0])
    assert said["w16.yaml"] == (
        "w16.yaml:1:1: world: found UTF-16 text: save it as UTF-8; allowed: a UTF-8 YAML file"
    )
    assert said["loop.yaml"].startswith(
        "loop.yaml: world: found a symbolic link loop (it leads back to itself); allowed: "
    )
    assert said["gone.yaml"].startswith(
        "gone.yaml: world: found a broken symbolic link (to 'moved.yaml', which does not exist)"
    )


@pytest.mark.parametrize(
    ("shape", "said"),
    [
        ("[[0, 0], [4, 0], [4, 0], [0, 3]]",
         "w.yaml:1:26: rooms[0][2]: found [4, 0] again, the corner before it ([1])"),
        ("[[0, 0], [4, 0], [4, 3], [0, 3], [0, 0]]",
         "w.yaml:1:42: rooms[0][4]: found [0, 0] again, the first corner ([0]): a polygon "
         "closes by itself, leave the last out"),
    ],
)  # fmt: skip
def test_a_repeated_corner_is_named_at_its_place_not_said_to_cross(shape: str, said: str) -> None:
    """A corner written twice made a side of no length, which "met" its neighbours: it read
    "a polygon whose sides cross ([0, 0]-[4, 0] and [4, 0]-[4, 0])"."""
    assert problems(f"rooms: [{shape}]\n") == [
        f"{said}; allowed: each corner once, in order around the polygon"
    ]


@pytest.mark.parametrize("shape", ["[[0, 0], [4, 0], [2, 0], [1, 0]]", "[[0, 0], [1, 1], [3, 3]]"])
def test_a_room_on_one_line_is_said_to_have_no_area(shape: str) -> None:
    """Its sides lie over each other: it read "sides cross", which named no mistake."""
    assert problems(f"rooms: [{shape}]\n") == [
        "w.yaml:1:9: rooms[0]: found a polygon of zero area (its corners all on one line); "
        "allowed: a polygon enclosing some floor"
    ]


def test_a_wall_or_a_virtual_wall_of_no_length_is_refused_at_its_place() -> None:
    """Both loaded without a word: a wall from a point to itself stops nothing, and a
    virtual wall's beam from its emitter to the same point is seen nowhere a user expects."""
    room = "rooms: [[[0, 0], [4, 0], [4, 3], [0, 3]]]\n"
    assert problems(
        room + "walls: [[1, 1, 2, 1], [1, 1.5, 1, 1.5]]\n"
        "virtual_walls:\n  - {from: [1, 1], to: [2, 1]}\n"
        "  - {from: [3, 2], to: [3, 2], halo: 0.3}\n"
    ) == [
        "w.yaml:2:23: walls[1]: found a wall of no length (both ends at [1, 1.5]); allowed: a "
        "wall whose two ends differ",
        "w.yaml:5:24: virtual_walls[1].to: found a virtual wall of no length (both ends at "
        "[3, 2]); allowed: a virtual wall whose two ends differ",
    ]
    # a short one is a wall (1 mm)
    [wall] = parse_world(room + "walls: [[1, 1, 1.001, 1]]\n", "w.yaml").walls
    assert math.dist(wall[:2], wall[2:]) == pytest.approx(1.0)


@pytest.mark.parametrize("text", ["", "\n\n", "# my flat, to be drawn\n"])
def test_an_empty_world_file_is_said_at_1_1_with_what_a_world_needs(text: str) -> None:
    """It had no place ("roomba-bt: FILE: (document): found nothing; allowed: a mapping with
    keys ..."), so ``run`` began its line "roomba-bt:" where every other world problem is
    ``file:line:col``, and it named no example of what to write."""
    assert problems(text) == [
        "w.yaml:1:1: (document): found an empty file (no YAML in it, at most comments); "
        "allowed: a world: at least rooms, a list of floor polygons in metres, e.g. rooms: "
        "[[[0, 0], [4, 0], [4, 3], [0, 3]]] (roomba-bt worlds empty-room prints a whole one)"
    ]


def test_a_worlds_check_stops_at_the_cap_and_says_so_among_the_first_listed() -> None:
    """A world of 150,000 bad points built 150,000 problems (6 s, 350 MB) to list 100: the
    check stops at MAX_FOUND, the note (the hundredth line, seen) at the last one's place."""
    points = ", ".join(["[x, 1]"] * 10_500)
    with pytest.raises(WorldError) as info:
        parse_world(f"rooms: [[{points}]]\n", "w.yaml")
    found = info.value.problems
    assert len(found) == printable.MAX_FOUND
    assert all(p.field.startswith("rooms[0][") for p in found[:99] + found[100:])
    note = found[99]
    assert (note.line, note.column) == (1, 11 + 8 * (printable.MAX_FOUND - 1))  # its x
    assert str(note).endswith(
        ": checking stopped here, at 10,000 errors (at most 10,000 are said): the rest of the "
        "file is not checked (a file generated wrong?)"
    )
    lines = str(info.value).splitlines()
    assert lines[99] == str(note)
    assert lines[100] == "... and 9,900 more errors (the first 100 are listed)"
    # duplicate keys and refused aliases stop there too
    for text in (
        "rooms: [[[0, 0], [1, 0], [1, 1]]]\n" + "dock: {" + "at: 1, " * 10_500 + "}\n",
        "rooms: [[[0, 0], [1, 0], [1, 1]]]\nname: &a x\nwalls: [" + "*a, " * 10_500 + "]\n",
    ):
        with pytest.raises(WorldError) as info:
            parse_world(text, "w.yaml")
        assert len(info.value.problems) == printable.MAX_FOUND
        assert "checking stopped here, at 10,000 errors" in str(info.value.problems[99])
