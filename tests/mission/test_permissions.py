"""A mission file is data: it imports no plugin file and reads no file outside its tree unless
the command line allows it (``--allow-plugin-files``, ``--include-dir``)."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest

from roomba_bt.cli import main
from roomba_bt.mission import Permissions, compile_mission

EXAMPLES = Path(__file__).resolve().parents[2] / "missions" / "examples"
Capsys = pytest.CaptureFixture[str]
Write = Callable[..., Path]

#: a plugin file that leaves a trace when imported (the test's proof of "nothing imported")
PLUGIN = """
from pathlib import Path
Path(__file__).with_name("imported.txt").write_text("imported")
from roomba_bt.behaviours import Condition, declare
@declare("always_true", kind="condition", reads=(8,))
class AlwaysTrue(Condition):
    '''Always.'''
    def check(self, snapshot):
        return True
"""


@pytest.fixture
def plugin_mission(mission_file: Write) -> Path:
    mission_file(PLUGIN, "evil.py")
    return mission_file("plugins: [./evil.py]\ntree: {sequence: [always_true, {wait: 1s}]}\n")


@pytest.mark.parametrize(
    "command",
    [
        ["validate"],
        ["show"],
        ["run", "--fast", "--display", "none", "--timeout", "5s"],
        ["eval", "--runs", "1", "--no-progress", "--timeout", "5s"],
    ],
    ids=lambda c: c[0],
)
def test_a_plugin_file_needs_the_command_lines_permission(
    plugin_mission: Path, command: list[str], capsys: Capsys
) -> None:
    assert main([command[0], str(plugin_mission), *command[1:]]) == 2
    out, err = capsys.readouterr()
    assert "m.yaml:1:11: plugin file './evil.py' not loaded" in out + err
    assert "--allow-plugin-files" in out + err
    assert not (plugin_mission.parent / "imported.txt").exists()
    assert "Traceback" not in out + err
    # the plugin's word is put down to the file not loaded, not "did you mean" another
    assert "unknown node 'always_true' (the plugin file './evil.py' was not loaded)" in out + err


def test_with_the_permission_the_plugin_file_loads(plugin_mission: Path, capsys: Capsys) -> None:
    assert main(["validate", str(plugin_mission), "--allow-plugin-files"]) == 0
    assert (plugin_mission.parent / "imported.txt").exists()


@pytest.mark.parametrize(
    "source",
    ["raise RuntimeError('kaboom')\n", "import nonexistent_module_xyz\n", "def oops(:\n"],
    ids=["raises", "missing-import", "syntax-error"],
)
def test_a_plugin_file_that_fails_to_import_is_named_at_its_nodes(
    mission_file: Write, source: str
) -> None:
    """With the permission, a plugin file that raised on import left its word a bare
    "unknown node 'boom'", without the note a file not allowed gets."""
    mission_file(source, "boom.py")
    path = mission_file("plugins: [./boom.py]\ntree: {sequence: [{mode: safe}, boom]}\n")
    _, diagnostics = compile_mission(path, permissions=Permissions(plugin_files=True))
    messages = [f"{d.line}:{d.column}: {d.message}" for d in diagnostics]
    assert messages[0].startswith(f"1:11: plugin {path.parent / 'boom.py'}: failed to import: ")
    assert messages[1:] == [
        "2:33: unknown node 'boom' (the plugin file './boom.py' was not loaded)"
    ]


def test_the_shipped_plugin_example_runs_with_the_permission(capsys: Capsys) -> None:
    mission = str(EXAMPLES / "custom_condition.yaml")
    assert main(["validate", mission]) == 2
    argv = ["run", mission, "--fast", "--display", "none", "--world", "corridor"]
    assert main([*argv, "--timeout", "5min", "--allow-plugin-files"]) == 0


def test_an_included_plugin_file_needs_it_too(mission_file: Write) -> None:
    mission_file(PLUGIN, "lib/evil.py")
    mission_file("plugins: [./evil.py]\nsubtrees: {t: {tree: {wait: 1s}}}\n", "lib/l.yaml")
    path = mission_file("include: [lib/l.yaml]\ntree: {wait: 1s}\n")
    _, diagnostics = compile_mission(path)
    assert [(d.file.endswith("l.yaml"), d.line, d.column) for d in diagnostics][:1] == [
        (True, 1, 11)
    ]
    assert not (path.parent / "lib" / "imported.txt").exists()


@pytest.mark.parametrize("target", ["/etc/passwd", "../outside/secret.yaml"])
@pytest.mark.parametrize("command", ["validate", "show", "run"])
def test_an_include_outside_the_mission_folder_is_refused(
    tmp_path: Path, target: str, command: str, capsys: Capsys
) -> None:
    (tmp_path / "outside").mkdir()
    (tmp_path / "outside" / "secret.yaml").write_text("password: hunter2\n")
    folder = tmp_path / "mission"
    folder.mkdir()
    path = folder / "m.yaml"
    path.write_text(f"include: [{target}]\ntree: {{wait: 1s}}\n")
    extra = ["--fast", "--display", "none"] if command == "run" else []
    assert main([command, str(path), *extra]) == 2
    out, err = capsys.readouterr()
    assert f"m.yaml:1:11: include {target!r} is outside the mission's folder" in out + err
    assert "--include-dir" in out + err
    assert "hunter2" not in out + err and "root:" not in out + err


@pytest.mark.parametrize("where", ["absolute", "../", "symlink"])
def test_an_allowed_plugin_file_outside_the_mission_folder_is_refused_as_an_include(
    tmp_path: Path, where: str, capsys: Capsys, monkeypatch: pytest.MonkeyPatch
) -> None:
    """``--allow-plugin-files`` imported ``plugins: [/tmp/x.py]`` or ``../../x.py`` from
    anywhere, where an include is held to the mission's folder: the user who read the
    ``.py`` files of an emailed folder ran whatever another user left elsewhere. The same
    rule, the same message, the same ``--include-dir``."""
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    (elsewhere / "evil.py").write_text(PLUGIN)
    folder = tmp_path / "mail"
    folder.mkdir()
    (folder / "link.py").symlink_to(elsewhere / "evil.py")
    target = {"absolute": str(elsewhere / "evil.py"), "../": "../elsewhere/evil.py",
              "symlink": "link.py"}[where]  # fmt: skip
    path = folder / "m.yaml"
    path.write_text(f"plugins: ['{target}']\ntree: {{sequence: [always_true, {{wait: 1s}}]}}\n")
    monkeypatch.chdir(tmp_path)
    assert main(["validate", str(path), "--allow-plugin-files"]) == 2
    assert capsys.readouterr().out.splitlines()[0] == (
        f"mail/m.yaml:1:11: plugin file {target!r} is outside the mission's folder (mail), the "
        "shipped library and the include folders granted (none); allow its folder with "
        "--include-dir elsewhere, or for every command with ROOMBA_BT_INCLUDE_PATH or "
        "include-dirs under [tool.roomba-bt] in a pyproject.toml (roomba-bt run --help, "
        "--include-dir) [plugins[0]]"
    )
    assert not (elsewhere / "imported.txt").exists()
    allowed = ["--allow-plugin-files", "--include-dir", str(elsewhere)]
    assert main(["validate", str(path), *allowed]) == 0
    assert (elsewhere / "imported.txt").exists()


def test_include_dir_allows_a_folder(tmp_path: Path, capsys: Capsys) -> None:
    shared = tmp_path / "shared"
    shared.mkdir()
    (shared / "lib.yaml").write_text("subtrees: {pause: {tree: {wait: 1s}}}\n")
    folder = tmp_path / "mission"
    folder.mkdir()
    path = folder / "m.yaml"
    path.write_text("include: [../shared/lib.yaml]\ntree: {subtree: pause}\n")
    assert main(["validate", str(path)]) == 2
    assert main(["validate", str(path), "--include-dir", str(shared)]) == 0
    mission, _ = compile_mission(path, permissions=Permissions(include_dirs=(shared,)))
    assert mission is not None


def test_a_symlink_out_of_the_tree_is_outside(tmp_path: Path) -> None:
    (tmp_path / "outside.yaml").write_text("subtrees: {pause: {tree: {wait: 1s}}}\n")
    folder = tmp_path / "mission"
    folder.mkdir()
    (folder / "link.yaml").symlink_to(tmp_path / "outside.yaml")
    path = folder / "m.yaml"
    path.write_text("include: [link.yaml]\ntree: {subtree: pause}\n")
    _, diagnostics = compile_mission(path)
    assert "is outside the mission's folder" in diagnostics[0].message


def test_a_file_that_is_not_a_mission_is_never_echoed(tmp_path: Path, capsys: Capsys) -> None:
    passwd = tmp_path / "passwd"
    passwd.write_text("root:x:0:0:root:/root:/bin/bash\n")
    config = tmp_path / "config.yaml"
    config.write_text("password: hunter2\ntoken: abc\n")
    (tmp_path / "m.yaml").write_text("include: [passwd, config.yaml]\ntree: {wait: 1s}\n")
    for path in (passwd, config, tmp_path / "m.yaml"):
        assert main(["validate", str(path)]) == 2
    out, err = capsys.readouterr()
    assert "is not a mission file" in out
    assert "root:" not in out + err and "hunter2" not in out + err and "abc" not in out + err


def test_the_shipped_library_is_allowed_from_anywhere(tmp_path: Path) -> None:
    from roomba_bt.mission import SHIPPED_LIBRARY

    by_path = SHIPPED_LIBRARY[0] / "lib" / "docking.yaml"
    for name in ("roomba-bt:lib/docking.yaml", str(by_path)):
        path = tmp_path / "m.yaml"
        path.write_text(f"include: [{name}]\ntree: {{subtree: dock}}\n")
        mission, diagnostics = compile_mission(path)
        assert diagnostics == []
        assert mission is not None


def test_a_pickled_command_line_wording_still_names_every_command_s_configuration(
    tmp_path: Path,
) -> None:
    """eval's workers get the permissions pickled: a copy of ``COMMAND_LINE``, not the object,
    and the refusal must still name the environment variable and the project file."""
    import pickle

    from roomba_bt.mission.wording import COMMAND_LINE

    copied = pickle.loads(pickle.dumps(Permissions(wording=COMMAND_LINE)))
    (tmp_path / "shared").mkdir()
    (tmp_path / "shared" / "lib.yaml").write_text("subtrees: {pause: {tree: {wait: 1s}}}\n")
    folder = tmp_path / "mission"
    folder.mkdir()
    path = folder / "m.yaml"
    path.write_text("include: [../shared/lib.yaml]\ntree: {subtree: pause}\n")
    _, diagnostics = compile_mission(path, permissions=copied)
    assert "--include-dir" in diagnostics[0].message
    assert "ROOMBA_BT_INCLUDE_PATH" in diagnostics[0].message
