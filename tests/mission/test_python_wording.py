"""The mission layer's messages to a Python caller name its arguments, not the command line's
flags (a py_trees user's report): ``load_mission`` said "allow its plugin files with
--allow-plugin-files", "allow its folder with --include-dir DIR", "unknown parameter 'sped'
set on the command line", to a program that had passed ``permissions=`` and ``params=``; and
``load_mission("dok")`` said "cannot read mission file", where ``roomba-bt validate dok``
offers 'dock'. The command line still names its flags (``tests/mission/test_permissions.py``,
``test_malformed.py``)."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest

from roomba_bt.cli import main
from roomba_bt.mission import MissionError, Permissions, compile_mission, load_mission
from roomba_bt.mission.wording import COMMAND_LINE

Write = Callable[..., Path]
FLAGS = ("--allow-plugin-files", "--include-dir", "command line", "-p ", "--profile", "--world")

PARAMETRISED = """
parameters:
  speed: {type: speed, default: 200 mm/s}
  t: {type: duration}
tree:
  sequence:
    - mode: safe
    - drive: {velocity: "${speed}", duration: "${t}"}
"""


def _messages(path: Path, params: dict[str, str] | None = None, **kwargs: object) -> list[str]:
    mission, diagnostics = compile_mission(path, params, **kwargs)  # type: ignore[arg-type]
    assert mission is None
    return [d.message for d in diagnostics]


def test_a_plugin_file_and_an_include_are_allowed_with_python_arguments(
    mission_file: Write, tmp_path: Path
) -> None:
    mission_file("x = 1\n", "near_wall.py")
    plugin = mission_file("plugins: [./near_wall.py]\ntree: {log: hi}\n", "plug.yaml")
    outside = tmp_path.parent / f"{tmp_path.name}-lib"
    outside.mkdir()
    (outside / "lib.yaml").write_text("subtrees: {hello: {tree: {log: hi}}}\n")
    include = mission_file(f"include: [{outside / 'lib.yaml'}]\ntree: {{subtree: {{id: hello}}}}\n")
    plugin_said = _messages(plugin)[0]  # then its word, unknown: not loaded
    include_said = _messages(include)[0]  # then its subtree, unknown: not included
    assert plugin_said == (
        "plugin file './near_wall.py' not loaded: a mission file cannot run code on its own; "
        "allow its plugin files with permissions=Permissions(plugin_files=True) (or install "
        "the plugin as a package)"
    )
    assert include_said.endswith(
        "the shipped library and the include folders granted (none); allow its folder with "
        f"permissions=Permissions(include_dirs=(Path('{outside}'),))"
    )
    for said in (plugin_said, include_said):
        assert not any(flag in said for flag in FLAGS), said
    # the command line's words where it compiles (validate, run, show, eval)
    granted = Permissions(wording=COMMAND_LINE)
    assert "with --allow-plugin-files (or" in _messages(plugin, permissions=granted)[0]
    assert (
        f"with --include-dir {outside}, or for every command with ROOMBA_BT_INCLUDE_PATH"
        in (_messages(include, permissions=granted)[0])
    )


def test_parameters_given_in_params_are_said_so(mission_file: Write) -> None:
    path = mission_file(PARAMETRISED)
    assert _messages(path, {"sped": "250mm/s", "t": "1s"}) == [
        "unknown parameter 'sped' given in params (did you mean 'speed'?); the mission "
        "declares: speed, t"
    ]
    assert _messages(path, {"speed": "250 km", "t": "1s"}) == [
        "parameter speed=250 km (given in params): unknown speed unit 'km' in '250 km'; use "
        "one of: mm/s, cm/s, m/s"
    ]
    [no_default] = _messages(path)
    assert no_default == "parameter 't' has no default: give it with params={'t': 'VALUE'}"
    [too_fast] = _messages(path, {"speed": "900mm/s", "t": "1s"})
    assert too_fast.endswith("(${speed} is speed=900mm/s, given in params)")


def test_a_mistyped_shipped_name_gets_its_did_you_mean_from_load_mission(
    capsys: pytest.CaptureFixture[str],
) -> None:
    with pytest.raises(MissionError) as raised:
        load_mission("dok")
    [said] = raised.value.diagnostics
    assert (said.file, said.line, said.column) == ("dok", 1, 1)
    assert said.message.startswith("no such mission file, and no shipped mission of that name")
    assert said.message.endswith("(did you mean 'dock'?)")
    assert "roomba-bt missions" not in said.message  # no command to list them from Python
    assert main(["validate", "dok"]) == 2  # the command line's, as it was
    err = capsys.readouterr().err
    assert "(shipped: " in err and "`roomba-bt missions` lists them) (did you mean 'dock'?)" in err


@pytest.mark.parametrize("name", ["empty-room", "empty-room.yaml"])
def test_a_shipped_world_s_name_given_to_load_mission_is_said_as_a_world(
    name: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """``load_mission("empty-room")`` listed the shipped missions alone, where ``roomba-bt
    validate empty-room`` says it is a shipped world (``tests/mission/test_cli.py``): the
    same sentence, with the Python call that loads the world, and no flag; what it names
    loads that world."""
    from roomba_bt import load_world

    monkeypatch.chdir(tmp_path)
    with pytest.raises(MissionError) as raised:
        load_mission(name)
    [said] = raised.value.diagnostics
    assert said.message.startswith("no such mission file, and no shipped mission of that name")
    assert said.message.endswith(
        "; empty-room is a shipped world, not a mission: load_world('empty-room') loads it, "
        "a Simulator on it runs a mission in it"
    ), said.message
    assert not any(flag in said.message for flag in FLAGS), said.message
    assert load_world("empty-room").name == "empty-room"
    (tmp_path / "worlds").mkdir()
    with pytest.raises(MissionError) as raised:  # a path is the user's file, never a world
        load_mission("worlds/empty-room.yaml")
    assert "shipped world" not in raised.value.diagnostics[0].message


def test_the_mission_layer_looks_for_shipped_worlds_where_the_simulator_keeps_them() -> None:
    """The mission layer imports no simulator: it names the worlds' folder itself, which
    must stay the simulator's (a moved folder would drop the hint without a word)."""
    from roomba_bt.mission.shipped import SHIPPED_WORLDS_DIR
    from roomba_bt.sim.world import WORLDS_DIR, shipped_worlds

    assert SHIPPED_WORLDS_DIR.resolve() == WORLDS_DIR.resolve()
    assert "empty-room" in shipped_worlds()
