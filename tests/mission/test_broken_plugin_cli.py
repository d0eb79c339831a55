"""An installed plugin that fails to import makes ``roomba-bt schema`` and ``roomba-bt
behaviours`` fail (exit 2), naming the entry point, its module and distribution and the
error in one line (docs/plugins.md, "A plugin that does not load"). Before, both exited 0
with a warning: ``roomba-bt schema > mission.schema.json`` in CI wrote a schema without the
plugin's behaviours, and every editor then marked the missions that use them wrong.

The plugin is a tiny distribution installed for real (a ``.dist-info`` with its
``entry_points.txt`` and a module that raises on import, on ``sys.path``), so the registry
finds it as it finds any installed plugin."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from quoted import assert_quoted  # tests/quoted.py: the docs' quoted lines
from runtime.installed import (  # tests/runtime: plugins installed
    conditions_module,
    install_distribution,
    installed_registry,
)

from roomba_bt.cli import main
from roomba_bt.runtime.summary import ExitCode

Capsys = pytest.CaptureFixture[str]

#: a module whose import raises, with a message of two lines
BROKEN = 'raise RuntimeError("the lab\'s calibration file is missing\\nsee README")\n'
#: a plugin that loads
WORKING = conditions_module(
    ("s29_sound", "SoundCondition", "Always true: a plugin that loads.", True)
)


def _installed(
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    *distributions: tuple[str, str, str],
    compiler_too: bool = False,
) -> None:
    """``distributions`` (name, module, source) installed; the commands' registry reads the
    entry points afresh; ``compiler_too``: the mission compiler's as well (``validate``'s,
    which asks the registry module for it)."""
    import roomba_bt.behaviours as behaviours
    import roomba_bt.behaviours.registry as registries

    registry = installed_registry(tmp_path, monkeypatch, *distributions)
    monkeypatch.setattr(behaviours, "default_registry", lambda: registry)
    # the compiler's is put back after the test, whichever: one made meanwhile (a validate
    # of the test's) found the test's plugins, and later tests' reports said them
    monkeypatch.setattr(registries, "_DEFAULT", registry if compiler_too else registries._DEFAULT)


@pytest.fixture
def installed(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """``bt-s29-broken`` (entry point ``s29_broken``, raises on import) and ``bt-s29-sound``
    installed."""
    _installed(
        tmp_path,
        monkeypatch,
        ("bt-s29-broken", "s29_broken", BROKEN),
        ("bt-s29-sound", "s29_sound", WORKING),
    )


def _said(err: str) -> list[str]:
    """The lines of stderr that say the broken plugin's error (the last line names it too,
    as what the command lacks)."""
    return [line for line in err.splitlines() if ": plugin 's29_broken'" in line]


@pytest.mark.usefixtures("installed")
def test_schema_fails_and_prints_no_schema_when_a_plugin_does_not_import(capsys: Capsys) -> None:
    assert main(["schema"]) == 2
    out, err = capsys.readouterr()
    assert out == ""  # not a schema without the plugin's behaviours, to be redirected to a file
    [line] = _said(err)
    assert line.startswith(
        "roomba-bt schema: error: plugin 's29_broken' (s29_broken, from bt-s29-broken): failed "
        "to import: RuntimeError: the lab's calibration file is missing see README (at "
    )  # the entry point, its module, the distribution, the error on one line
    assert "s29_broken.py:1)" in line
    assert "--skip-broken-plugins" in err
    assert (
        "did not load (no schema printed: it would lack the behaviours of plugin 's29_broken'"
        in err
    )


@pytest.mark.usefixtures("installed")
def test_schema_skip_broken_plugins_goes_on_with_a_warning(capsys: Capsys) -> None:
    assert main(["schema", "--skip-broken-plugins"]) == 0
    out, err = capsys.readouterr()
    schema = json.loads(out)
    assert "s29_sound" in schema["$defs"]  # the plugin that loads is described
    [line] = _said(err)
    assert line.startswith("roomba-bt schema: warning: plugin 's29_broken'")


@pytest.mark.usefixtures("installed")
@pytest.mark.parametrize("json_output", [False, True])
def test_behaviours_lists_what_loaded_and_fails(capsys: Capsys, json_output: bool) -> None:
    assert main(["behaviours", *(["--json"] if json_output else [])]) == 2
    out, err = capsys.readouterr()
    assert "s29_sound" in out  # the listing is still printed
    [line] = _said(err)
    assert line.startswith("roomba-bt behaviours: error: plugin 's29_broken' (s29_broken, from ")
    assert main(["behaviours", "--skip-broken-plugins"]) == 0
    assert "warning: plugin 's29_broken'" in capsys.readouterr().err


def test_a_name_two_plugins_declare_is_no_broken_plugin(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: Capsys
) -> None:
    """A clash loses no behaviour (each is reached by ``package:name``; the schema lists
    those): a warning, exit 0, as before."""
    other = conditions_module(("s29_sound", "Other", "Always true: a plugin that loads.", True))
    _installed(
        tmp_path, monkeypatch, ("bt-s29-one", "s29_one", WORKING), ("bt-s29-two", "s29_two", other)
    )
    assert main(["schema"]) == 0
    out, err = capsys.readouterr()
    assert "bt-s29-one:s29_sound" in json.loads(out)["$defs"]
    assert "roomba-bt schema: warning: plugin 's29_two'" in err


def test_the_page_quotes_what_schema_and_behaviours_say_of_a_plugin_that_does_not_import(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: Capsys
) -> None:
    """docs/plugins.md's plugin, installed as the page names it (``roomba-bt-lab``, its
    package ``roomba_bt_lab``, the entry point ``lab``), whose line 42 imports a module
    that is not there: ``schema``'s error is the page's quote, and ``behaviours`` says it
    as the page says (``roomba-bt behaviours: error: ...``)."""
    _installed(tmp_path, monkeypatch)
    source = "\n" * 41 + "import nonexistent_mod\n"
    install_distribution(tmp_path / "site", "roomba-bt-lab", "roomba_bt_lab", source,
                         entry="lab", package=True)  # fmt: skip
    assert main(["schema"]) == 2
    assert_quoted(
        "docs/plugins.md", "roomba-bt schema: error: plugin 'lab'", capsys.readouterr().err
    )
    assert main(["behaviours"]) == 2
    assert_quoted("docs/plugins.md", "roomba-bt behaviours: error: ...", capsys.readouterr().err)


#: what an installed plugin's import may raise that is no ``Exception`` (session 29's
#: audit): every command answered ``interrupted`` (130) to its ``raise KeyboardInterrupt``,
#: ``validate`` of a mission that does not use it too, and printed Python's traceback for
#: a ``BaseException`` of its own; each is now the plugin that did not load, named
RAISES_AT_IMPORT = {
    "KeyboardInterrupt": (
        "raise KeyboardInterrupt\n",
        "KeyboardInterrupt (raised by its own code: no Ctrl-C or signal came)",
    ),
    "BaseException": (
        "class Own(BaseException):\n    pass\n\nraise Own('the lab is closed')\n",
        "Own: the lab is closed",
    ),
    "GeneratorExit": ("raise GeneratorExit\n", "GeneratorExit"),
}
#: a mission that uses no plugin
PLAIN = "tree:\n  sequence:\n    - mode: safe\n    - wait: 0.1s\n    - mode: passive\n"


@pytest.mark.parametrize("kind", list(RAISES_AT_IMPORT))
def test_what_else_an_import_raises_is_a_plugin_that_did_not_load(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: Capsys, kind: str
) -> None:
    source, said = RAISES_AT_IMPORT[kind]
    _installed(tmp_path, monkeypatch, ("bt-s29-rude", "s29_rude", source))
    mission = tmp_path / "plain.yaml"
    mission.write_text(PLAIN)
    assert main(["validate", str(mission)]) == 0  # it does not use the plugin
    assert main(["behaviours"]) == 2
    out, err = capsys.readouterr()
    [line] = [line for line in err.splitlines() if ": plugin 's29_rude'" in line]
    assert line.startswith(
        f"roomba-bt behaviours: error: plugin 's29_rude' (s29_rude, from bt-s29-rude): failed "
        f"to import: {said} (at "
    ), line
    assert "Traceback" not in out + err and "interrupted" not in err
    run = ["run", str(mission), "--fast", "--display", "none"]
    assert main(run) == 0  # a run of a mission that does not use it runs
    assert "outcome      SUCCESS" in capsys.readouterr().out


def test_a_real_ctrl_c_during_a_plugin_s_import_is_still_an_interrupt(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: Capsys
) -> None:
    """The SIGINT itself, delivered while the plugin imports (a slow import, the operator's
    Ctrl-C): the command is interrupted, 130, as before."""
    interrupting = "import signal\nsignal.raise_signal(signal.SIGINT)\n"
    _installed(tmp_path, monkeypatch, ("bt-s29-rude", "s29_rude", interrupting))
    assert main(["behaviours"]) == 130
    assert "roomba-bt: interrupted" in capsys.readouterr().err


def test_a_plugin_file_that_raises_keyboard_interrupt_is_a_mission_error(
    tmp_path: Path, capsys: Capsys
) -> None:
    (tmp_path / "rude.py").write_text("raise KeyboardInterrupt\n")
    mission = tmp_path / "m.yaml"
    mission.write_text("plugins: [./rude.py]\n" + PLAIN)
    assert main(["validate", str(mission), "--allow-plugin-files"]) == 2
    out, err = capsys.readouterr()
    assert (
        "failed to import: KeyboardInterrupt (raised by its own code: no Ctrl-C or signal "
        f"came) (at {tmp_path / 'rude.py'}:1)"
    ) in out, out + err
    assert "interrupted" not in err


#: an entry point to a list holding a good class, a string and a class declared wrongly:
#: refused whole until session 37, its good class with it
LISTED = (
    conditions_module(("s36_ok", "Ok", "Always true: in a list beside two bad items.", True))
    + '\n\n@declare("s36_bad", kind="action")\nclass Bad(Condition):\n'
    + '    """Declared an action, derived from Condition."""\n\n'
    + "    def check(self, snapshot):\n        return True\n\n\n"
    + 'class Helper:\n    """No behaviour: listed by mistake."""\n\n\n'
    + "LIST = [Ok, 'not a class', Bad, Helper]\n"
)


@pytest.fixture
def listed(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """``bt-s36-list``, whose entry point ``lst`` names ``s36_list:LIST``."""
    _installed(tmp_path, monkeypatch, ("bt-s36-list", "s36_list", LISTED), compiler_too=True)
    [info] = (tmp_path / "site").glob("bt_s36_list-*.dist-info")
    (info / "entry_points.txt").write_text("[roomba_bt.behaviours]\nlst = s36_list:LIST\n")


#: how the registry names the listed plugin
LST = "'lst' (s36_list:LIST, from bt-s36-list)"


@pytest.mark.usefixtures("listed")
def test_a_list_s_good_class_loads_and_each_bad_item_is_said_alone(
    tmp_path: Path, capsys: Capsys
) -> None:
    """One item of an entry point's list that was no behaviour class (a string) refused the
    whole list: its good class was an unknown node, though a class of the list declared
    wrongly was refused alone (session 37). The good class loads and runs; each bad item is
    a plugin that did not load, in ``validate``'s JSON as a warning, naming the entry point,
    the item and what is wrong, the good class not among what a mission cannot use."""
    mission = tmp_path / "m.yaml"
    mission.write_text("tree:\n  s36_ok\n")
    assert main(["validate", "--format", "json", str(mission)]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["summary"]["errors"] == 0
    item, helper, bad = report["plugins_not_loaded"]
    assert item["plugin"] == helper["plugin"] == bad["plugin"] == LST
    assert item["error"] == (
        "item 2 of its list, 'not a class' (a str), is no class: the list holds behaviour "
        "classes (derived from Action or Condition, each decorated with @declare)"
    )
    assert item["lost"] == "'not a class' (refused alone: the plugin's other behaviours loaded)"
    assert helper["error"].startswith("item 4 of its list, class Helper (")
    assert (
        "s36_list.py:20), derives from neither roomba_bt.behaviours.Action nor" in (helper["error"])
    )
    assert helper["lost"] == "class Helper (refused alone: the plugin's other behaviours loaded)"
    assert bad["error"].startswith("Bad (")
    assert "declares itself wrongly: kind='action', but Bad derives from Condition" in bad["error"]
    assert bad["lost"] == "'s36_bad' (refused alone: the plugin's other behaviours loaded)"
    said = (item, helper, bad)
    assert all(p["severity"] == "warning" and "s36_ok" not in p["message"] for p in said)
    assert main(["run", str(mission), "--fast", "--display", "none"]) == 0
    assert "outcome      SUCCESS" in capsys.readouterr().out


@pytest.mark.usefixtures("listed")
def test_an_unknown_node_of_a_list_s_refused_class_notes_that_class(
    tmp_path: Path, capsys: Capsys
) -> None:
    """The mission's ``unknown node`` of a name a refused class of the list declares has
    that class's error as its note (session 36 gave a note only for a plugin that did not
    import), not the other items'."""
    mission = tmp_path / "m.yaml"
    mission.write_text("tree:\n  s36_bad\n")
    assert main(["validate", str(mission)]) == 2
    out, err = capsys.readouterr()
    [line] = [line for line in (out + err).splitlines() if "unknown node 's36_bad'" in line]
    assert line.startswith(f"{mission}:2:3: unknown node 's36_bad' (note: plugin {LST}: Bad ("), (
        line
    )
    assert "declares itself wrongly: kind='action', but Bad derives from Condition" in line
    assert "not a class" not in line


@pytest.mark.usefixtures("listed")
def test_behaviours_of_a_name_a_plugin_that_did_not_load_declares_says_so_as_errors(
    capsys: Capsys,
) -> None:
    """``behaviours s36_bad`` said "a plugin file's are listed with --plugin-file FILE" (the
    name is an installed plugin's) and then the plugin's error as ``roomba-bt: warning:``,
    where ``behaviours`` of a name that loads says it as ``roomba-bt behaviours: error:``."""
    assert main(["behaviours", "s36_bad"]) == 2
    err = capsys.readouterr().err
    lines = err.splitlines()
    # half loaded: what loaded said beside what was refused (it said "did not load")
    assert lines[0] == (
        f"roomba-bt behaviours: unknown behaviour 's36_bad': it is declared by plugin {LST}, "
        "which loaded in part: loaded s36_ok; refused 'not a class', class Helper, 's36_bad' "
        "(below)"
    ), err
    said = f"roomba-bt behaviours: error: plugin {LST}: "
    assert [line[len(said) :][:6] for line in lines[1:4]] == ["item 2", "item 4", "Bad (/"], err
    # one plugin, half loaded: three of its items refused, each said (it said "3 installed
    # plugins did not load")
    assert lines[4].startswith("roomba-bt behaviours: an installed plugin did not load (not "), err
    assert "--plugin-file" not in err and "roomba-bt: warning" not in err, err
    assert main(["behaviours", "s36_bad", "--skip-broken-plugins"]) == 2  # still unknown
    assert f"roomba-bt behaviours: warning: plugin {LST}" in capsys.readouterr().err


def test_validate_s_json_and_github_formats_say_a_plugin_that_did_not_load(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: Capsys
) -> None:
    """With a broken plugin installed, ``validate --format json`` had no field for it and
    ``--format github`` no annotation: a plain stderr line was all (session 36, a
    stranger's finding). A warning in each: the mission, which does not use it, passes."""
    broken = ("bt-s29-broken", "s29_broken", BROKEN)
    _installed(tmp_path, monkeypatch, broken, compiler_too=True)
    mission = tmp_path / "plain.yaml"
    mission.write_text(PLAIN)
    assert main(["validate", "--format", "json", str(mission)]) == 0
    [plugin] = json.loads(capsys.readouterr().out)["plugins_not_loaded"]
    assert plugin["plugin"] == "'s29_broken' (s29_broken, from bt-s29-broken)"
    assert plugin["error"].startswith(
        "failed to import: RuntimeError: the lab's calibration file is missing see README (at "
    )
    assert (
        plugin["lost"] == "the behaviours of plugin 's29_broken' (s29_broken, from bt-s29-broken)"
    )
    assert (
        plugin["message"]
        == f"plugin {plugin['plugin']}: {plugin['error']}; a mission cannot use {plugin['lost']}"
    )
    assert plugin["severity"] == "warning"
    assert main(["validate", "--format", "github", str(mission)]) == 0
    [annotation] = [line for line in capsys.readouterr().out.splitlines() if "s29_broken" in line]
    assert annotation.startswith(
        "::warning title=roomba-bt validate::plugin 's29_broken' (s29_broken, from "
        "bt-s29-broken): failed to import: RuntimeError: "
    ), annotation
    assert annotation.endswith(
        "; a mission cannot use the behaviours of plugin 's29_broken' "
        "(s29_broken, from bt-s29-broken)"
    ), annotation


def test_a_plugin_file_an_installed_package_serves_is_a_warning_that_it_can_go(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: Capsys
) -> None:
    """A mission that kept its ``plugins:`` line after the plugin was installed as a package
    was told "(or install the plugin as a package)": it is installed. Then the entry was
    told it can go, and still refused, exit 2, though the package served all it declares.
    Decided: the entry is redundant, so a warning (the file read, not run; not loaded), the
    mission runs on the package's behaviour, and ``validate --strict`` fails it (exit 7); a
    file declaring a name no package serves is refused as before."""
    _installed(tmp_path, monkeypatch, ("bt-s29-sound", "s29_sound", WORKING), compiler_too=True)
    (tmp_path / "sound.py").write_text(WORKING)
    (tmp_path / "other.py").write_text(WORKING.replace('"s29_sound"', '"s29_other"'))
    redundant = tmp_path / "m.yaml"
    redundant.write_text("mission: m\nplugins: [./sound.py]\ntree: s29_sound\n")
    warned = (
        "m.yaml:2:11: warning: plugin file './sound.py' not loaded, and need not be: installed "
        "plugins serve what it declares (s29_sound by 's29_sound' (s29_sound, from "
        "bt-s29-sound)); take './sound.py' out of the mission's plugins:"
    )
    for command, code in (
        (["validate"], ExitCode.OK),
        (["validate", "--strict"], ExitCode.STRICT),
        (["run", "--fast", "--display", "none"], ExitCode.OK),
    ):
        assert main([*command, str(redundant)]) == code, command
        out, err = capsys.readouterr()
        assert warned in (out + err).replace(str(tmp_path) + "/", ""), out + err
    both = tmp_path / "both.yaml"
    both.write_text("mission: m\nplugins: [./sound.py, ./other.py]\ntree: s29_sound\n")
    assert main(["validate", str(both)]) == ExitCode.INVALID
    said = capsys.readouterr().out
    assert (
        "both.yaml:2:23: plugin file './other.py' not loaded: a mission file cannot run code "
        "on its own; allow its plugin files with --allow-plugin-files (or install the "
        "plugin as a package)"
    ) in said, said
    assert "both.yaml: failed (1 error)" in said  # the served entry is no error
