"""The Python examples of docs/plugins.md run as written: the blackboard fixture, a mission
with a plugin file on the simulator from pytest (``RunStack`` and ``assert_success_rate``,
the plugin file allowed), and an action that waits for Safe/Full and fails once stranded."""

from __future__ import annotations

import os
import re
import sys
from pathlib import Path
from typing import Any

import pytest
from py_trees.common import Status
from setuptools.config.pyprojecttoml import read_configuration
from waits import finished  # tests/waits.py: a child run to its end, no fixed wait

from roomba_bt.oi.modes import OIMode
from roomba_bt.robot.testing import StubRobot

ROOT = Path(__file__).resolve().parents[2]
DOC = ROOT / "docs" / "plugins.md"


def _section(section: str) -> str:
    text = DOC.read_text(encoding="utf-8")
    assert section in text, f"docs/plugins.md lost its section {section!r}"
    return text.split(section, 1)[1].split("\n## ", 1)[0]


def _blocks(section: str, lang: str = "python") -> list[str]:
    body = _section(section)
    return [str(b) for b in re.findall(rf"```{lang}\n(.*?)```", body, flags=re.DOTALL)]


def _run(block: str, name: str) -> dict[str, Any]:
    namespace: dict[str, Any] = {"__name__": f"docs_plugins_{name}"}
    exec(compile(block, f"{DOC}:{name}", "exec"), namespace)
    return namespace


def _section_2_files(folder: Path) -> None:
    """§2's two files in ``folder`` as the reader made them there: ``plugins/near_wall.py``
    and ``custom_condition.yaml`` (not the repository's copies in missions/examples, which a
    wheel's user has not: session 39)."""
    section = "## 2. A condition in a file next to the mission"
    [plugin] = [b for b in _blocks(section) if b.startswith("# plugins/near_wall.py\n")]
    [mission] = [b for b in _blocks(section, "yaml") if b.startswith("mission: custom_condition")]
    (folder / "plugins").mkdir()
    (folder / "plugins" / "near_wall.py").write_text(plugin, encoding="utf-8")
    (folder / "custom_condition.yaml").write_text(mission, encoding="utf-8")


def test_the_testing_files_pass_as_the_page_runs_them(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    """§3's three files, each saved where its first line says (``plugins/test_near_wall.py``
    beside §2's plugin, ``plugins/conftest.py``, ``plugins/test_on_the_simulator.py``), pass
    under ``pytest plugins`` run from the mission's folder, as the page runs them. The page
    named no place for the first (in the mission's folder its ``from near_wall import
    NearWall`` is a ModuleNotFoundError) nor for the other two (the simulator's test names
    the mission by a path relative to the folder pytest runs in)."""
    _section_2_files(tmp_path)
    blocks = _blocks("## 3. Test it without a robot")
    for block in blocks:
        named = re.match(r"# ([\w-]+(?:/[\w-]+)*\.py)\n", block)
        assert named is not None, f"a block of §3 names no file to save it in: {block[:60]!r}"
        (tmp_path / named[1]).write_text(block, encoding="utf-8")
    monkeypatch.chdir(tmp_path)  # the mission's folder: the child runs there
    done = finished([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "plugins"])
    assert done.returncode == 0 and "3 passed" in done.stdout, done.stdout + done.stderr


def test_the_testing_examples_run(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    """The fixture clears the blackboard; the mission naming near_wall.py runs on the
    simulator to SUCCESS with the plugin file allowed, once and from the start three times."""
    _, fixture, on_sim = _blocks("## 3. Test it without a robot")
    assert "Blackboard.clear()" in fixture
    assert "clean_blackboard" in _run(fixture, "fixture")
    _section_2_files(tmp_path)
    monkeypatch.chdir(tmp_path)  # the example's path is relative to that folder, as pytest's
    namespace = _run(on_sim, "simulator")
    namespace["test_near_wall_stops_the_drive_in_the_corridor"]()
    namespace["test_near_wall_succeeds_from_the_corridor_s_start"]()


def test_the_declare_like_example_keeps_wall_follow_s_checks() -> None:
    """``wall_follow_for``, declared like ``WallFollow``: its parameters without duration
    and with distance, the encoders read too, and the hysteresis check carried (a copy by
    hand dropped it); it follows the wall and ends at the distance."""
    _, extended = _blocks("## 4. An action: spot cleaning")[1:]
    cls = _run(extended, "wall_follow_for")["WallFollowFor"]
    declaration = cls.declaration
    assert declaration.param("duration") is None and declaration.primary == "distance"
    assert declaration.packets({})[-2:] == (43, 44)
    with pytest.raises(ValueError, match="front_clear 900 is above front_threshold 800"):
        cls("follow", {"distance": "1 m", "front_clear": 900})
    robot = StubRobot(mode=OIMode.SAFE)
    node = cls("follow", {"distance": "10 mm"})
    node.setup(robot=robot)
    signals = {7: 0, 48: 0, 49: 0, 50: 0, 51: 600}  # the wall on the right, on target
    robot.set_frame({**signals, 43: 0, 44: 0})
    node.tick_once()
    assert node.status is Status.RUNNING and [c.opcode for c in robot.flush()] == [145]
    robot.set_frame({**signals, 43: 100, 44: 100})  # both wheels about 44 mm on
    node.tick_once()
    assert node.status is Status.SUCCESS and [c.args for c in robot.flush()] == [(0, 0)]


def test_the_typed_key_example_declares_its_key_s_type() -> None:
    """``dirt_seen`` of §6: ``writes_keys={"key": INT}``, checked when declared."""
    [example] = _blocks("### Key parameters and their types")
    declaration = _run(example, "dirt_seen")["DirtSeen"].declaration
    declaration.validate()
    assert declaration.writes_keys == ("key",) and declaration.key_type("key").name == "int"


def test_the_wait_for_driving_mode_example_fails_once_stranded() -> None:
    """``creep`` drives in Safe, waits (RUNNING) in Passive, and fails after the grace with
    the cause; nothing is sent while it waits."""
    creep, _ = _blocks("## 4. An action: spot cleaning")[1:]
    cls = _run(creep, "creep")["Creep"]
    robot = StubRobot(mode=OIMode.SAFE)
    node = cls("creep", {})
    node.setup(robot=robot)
    robot.set_frame({})
    node.tick_once()
    assert node.status is Status.RUNNING
    assert [c.opcode for c in robot.flush()] == [137]
    robot.set_frame({}, mode=OIMode.PASSIVE)  # a cliff in Safe: the OI drops to Passive
    node.tick_once()
    assert node.status is Status.RUNNING and robot.flush() == []
    robot.set_frame({}, ticks=70)  # 1.05 s later, still in Passive
    node.tick_once()
    assert node.status is Status.FAILURE
    assert "left Safe/Full mode and was not brought back within 1 s" in node.feedback_message


def frame_attribute_table() -> str:
    """The table of ``SensorFrame``'s attributes in docs/plugins.md, from the code: each
    public property, the packets it reads (found by reading it from frames that lack them:
    each ``MissingPacket`` names one more; with every value 0, so that ``a or b`` reads both,
    and every value 1, so that a ratio reads its numerator) and the type it gives. A plugin
    author found the names with ``help()``; the doc did not list them."""
    from roomba_bt.oi.frames import SensorFrame

    rows = ["| attribute | packets | gives |", "|---|---|---|"]
    for name, attr in sorted(vars(SensorFrame).items()):
        if name.startswith("_") or not isinstance(attr, property) or name == "packet_ids":
            continue
        ids: set[int] = set()
        for fill in (0, 1):
            value = _read_growing(name, ids, fill)
        packets = ", ".join(str(pid) for pid in sorted(ids))
        rows.append(f"| `{name}` | {packets} | {type(value).__name__} |")
    return "\n".join(rows)


def _read_growing(name: str, ids: set[int], fill: int) -> object:
    """Frame attribute ``name`` read from a frame of ``ids`` (each value ``fill``), each
    packet it names missing added to ``ids`` until it reads."""
    from roomba_bt.oi.frames import MissingPacket, layout_for
    from roomba_bt.oi.profiles import CREATE2

    while True:
        layout = layout_for(tuple(sorted(ids)), CREATE2, False)
        frame = layout.decode(layout.pack(dict.fromkeys(ids, fill)))
        try:
            return getattr(frame, name)
        except MissingPacket as exc:
            assert isinstance(exc.packet_id, int) and exc.packet_id not in ids
            ids.add(exc.packet_id)


def test_the_frame_attributes_listed_are_the_code_s() -> None:
    """If this fails, the frame's attributes changed: put the table it prints between the
    ``SensorFrame attributes`` markers of docs/plugins.md."""
    text = DOC.read_text(encoding="utf-8")
    listed = text.split("<!-- SensorFrame attributes: begin -->\n", 1)[1].split(
        "\n<!-- SensorFrame attributes: end -->", 1
    )[0]
    assert listed == frame_attribute_table(), frame_attribute_table()


def test_the_held_for_condition_counts_only_while_it_is_ticked() -> None:
    """The example of a condition's state: low for ``held`` while ticked every tick holds,
    across frames the link lost too; a hold from before a tick it missed (the guard was left)
    counts for nothing."""
    example = _blocks("#### A condition's state across ticks")[0]
    cls = _run(example, "battery_low_for")["BatteryLowFor"]
    robot = StubRobot()
    node = cls("battery_low_for", {"below": "15%", "held": "3s"})
    node.setup(robot=robot)
    low = {25: 100, 26: 1000}  # 10 %

    def tick(ticks: int = 1) -> Status:
        robot.set_frame(low, ticks=ticks)
        node.tick_once()
        return node.status

    assert tick() is Status.FAILURE
    for _ in range(199):  # 2.985 s later: not yet
        assert tick() is Status.FAILURE
    assert tick() is Status.SUCCESS  # 3 s after it was first seen low
    assert tick(ticks=400) is Status.SUCCESS  # 6 s of frames lost: no tick it missed
    robot.set_frame(low)  # the tree ticked without it: the hold starts again
    assert tick() is Status.FAILURE
    for _ in range(199):
        assert tick() is Status.FAILURE
    assert tick() is Status.SUCCESS
    robot.set_frame({25: 900, 26: 1000})
    node.tick_once()
    assert node.status is Status.FAILURE


def test_the_behaviour_in_your_own_program_example_compiles_its_mission(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The class defined in the program is named in the YAML through ``behaviours=``."""
    [example] = _blocks("### A behaviour in your own program")
    (tmp_path / "lab.yaml").write_text(
        "tree:\n  sequence:\n    - mode: safe\n    - drive: {velocity: 200 mm/s}\n"
        "      until: {far_enough: 300 mm}\n"
    )
    monkeypatch.chdir(tmp_path)
    mission = _run(example, "own_program")["mission"]
    assert any(node.name.startswith("far_enough") for node in mission.root.iterate())


def test_the_package_of_section_5_builds_and_serves_near_wall(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    """§5's ``pyproject.toml`` builds as written, and its entry point gives ``near_wall`` to
    a mission with no ``plugins:``, as the page's ``roomba-bt behaviours near_wall`` shows.
    The page's toml was the example package's, cut: no ``[build-system]`` and no
    ``version``, so a reader who wrote it as shown met setuptools' ``project must contain
    ['version'] properties`` at ``pip install`` (a stranger's session, from the wheel). The
    package's metadata is made by setuptools' own build hook (no network, no install into
    this venv), and a child process finds it on its path as pip's install would leave it."""
    section = "## 5. Package it"
    [toml] = _blocks(section, "toml")
    first, _, _ = toml.partition("\n")
    assert first == "# roomba-bt-near-wall/pyproject.toml", first
    _section_2_files(tmp_path)
    package = tmp_path / "roomba-bt-near-wall"
    (package / "roomba_bt_near_wall").mkdir(parents=True)
    (tmp_path / "plugins" / "near_wall.py").rename(package / "roomba_bt_near_wall" / "__init__.py")
    (package / "pyproject.toml").write_text(toml, encoding="utf-8")
    project = read_configuration(package / "pyproject.toml")["project"]  # as pip's build
    name, version = project["name"], project["version"]
    meta = tmp_path / "site"  # the dist-info pip's install would leave, made from it
    info = meta / f"{name.replace('-', '_')}-{version}.dist-info"
    info.mkdir(parents=True)
    metadata = f"Metadata-Version: 2.1\nName: {name}\nVersion: {version}\n"
    (info / "METADATA").write_text(metadata, encoding="utf-8")
    points = "".join(
        f"[{group}]\n" + "".join(f"{k} = {v}\n" for k, v in entries.items())
        for group, entries in project["entry-points"].items()
    )
    (info / "entry_points.txt").write_text(points, encoding="utf-8")
    mission = tmp_path / "custom_condition.yaml"
    text = mission.read_text(encoding="utf-8")
    mission.write_text(text.replace("plugins: [./plugins/near_wall.py]\n", ""), encoding="utf-8")
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join([str(package), str(meta), str(ROOT)]))
    fenced = re.findall(r"^```(\w*)\n(.*?)^```$", _section(section), flags=re.DOTALL | re.M)
    [said] = [b for lang, b in fenced if not lang and "$ roomba-bt behaviours near_wall\n" in b]
    shown = said.split("$ roomba-bt behaviours near_wall\n", 1)[1].split("\n$ ", 1)[0]
    listed = finished([sys.executable, "-m", "roomba_bt", "behaviours", "near_wall"])
    assert listed.returncode == 0, listed.stderr
    assert listed.stdout.strip() == shown.strip()
    ran = finished(
        [sys.executable, "-m", "roomba_bt", "run", "custom_condition.yaml", "--world",
         "corridor", "--fast"]
    )  # fmt: skip
    assert ran.returncode == 0, ran.stdout[-2000:] + ran.stderr[-2000:]
    assert "outcome      SUCCESS" in ran.stdout


def test_the_page_lists_every_parameter_type_a_declaration_takes() -> None:
    """The page's list of parameter types is the one table's (``VALUE_TYPES``, which the
    declaration error lists): it left out ``RADIUS`` and ``MARK``, and neither could be
    imported from ``roomba_bt.behaviours``, the place the page and the error's "write
    RADIUS (from roomba_bt.behaviours import RADIUS)" send the reader."""
    import roomba_bt.behaviours as behaviours
    from roomba_bt.behaviours.units import VALUE_TYPES

    text = DOC.read_text(encoding="utf-8")
    listing = text.split("Parameter types (all in `roomba_bt.behaviours`): ", 1)[1]
    listing = listing.split('and `enum("a", "b")`', 1)[0]
    listed = re.findall(r"`([A-Z]+)`", re.sub(r"\([^()]*\)", "", listing))
    assert listed == [vtype.name.upper() for vtype in VALUE_TYPES.values()]
    for name in listed:
        assert getattr(behaviours, name) is VALUE_TYPES[name.lower()], name
