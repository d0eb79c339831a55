"""What a plugin declares about blackboard keys and about a built-in it extends, checked
when it loads, and its writes to keys the mission never declared, said once at run time
(a plugin author's findings, session 31):

- ``writes_keys`` / ``reads_keys`` naming an undeclared parameter, or an ``INT`` one,
  loaded without a word, while ``primary=`` was refused;
- re-declaring a subclass of ``WallFollow`` by hand dropped its ``constraints=`` (the
  front_clear / front_threshold check), and ``(*WallFollow.declaration.reads, ...)`` failed
  ``mypy --strict``: :func:`declare_like` carries the parent's declaration;
- ``write_key("secret", 5)`` in a mission that never declared ``secret`` ran silently.
"""

from __future__ import annotations

import logging
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import pytest
from py_trees.common import Status

from roomba_bt.behaviours import (
    DISTANCE,
    INT,
    STR,
    Action,
    DeclarationError,
    Param,
    ParamError,
    builtin_registry,
    declare,
    declare_keys,
    declare_like,
    write_key,
)
from roomba_bt.behaviours.wall import WallFollow
from roomba_bt.cli import main
from roomba_bt.oi.frames import ENCODER_PACKETS
from roomba_bt.runtime.summary import ExitCode

BAD_KEYS = '''
from roomba_bt.behaviours import INT, STR, Action, Param, declare


@declare("d_writes", kind="action", writes_keys=("nokey",))
class Writes(Action):
    """A key parameter that is not declared."""


@declare("d_writes_int", kind="action", params=(Param("k", INT, default=3),), writes_keys=("k",))
class WritesInt(Action):
    """An INT parameter marked as naming a key."""


@declare("d_reads_typed", kind="action", params=(Param("k", STR),), reads_keys={"k": "int"})
class ReadsTyped(Action):
    """A key's type that is no ValueType."""


@declare("d_twice", kind="action", params=(Param("k", STR),), reads_keys={"k": INT},
         writes_keys={"k": STR})
class Twice(Action):
    """One key read and written as two types."""


@declare("d_fine", kind="action", params=(Param("k", STR, from_blackboard=False),),
         writes_keys={"k": INT})
class Fine(Action):
    """A typed key parameter, declared right."""
'''


def test_key_parameters_are_checked_when_the_plugin_loads(tmp_path: Path) -> None:
    """Each names a declared STR parameter, each type a ValueType: said with the class,
    its file:line and the fix, as the other declaration checks say theirs."""
    plugin = tmp_path / "keys.py"
    plugin.write_text(BAD_KEYS)
    registry, errors = builtin_registry().with_file(plugin)
    assert "d_fine" in registry
    said = sorted(str(error) for error in errors)
    assert [line.split(" declares itself wrongly: ")[0].rsplit(": ", 1)[-1] for line in said] == [
        f"ReadsTyped ({plugin}:15)",
        f"Twice ({plugin}:20)",
        f"Writes ({plugin}:5)",
        f"WritesInt ({plugin}:10)",
    ]
    reads_typed, twice, writes, writes_int = (line.split(" wrongly: ")[1] for line in said)
    assert writes == (
        "writes_keys names 'nokey', which is not a declared parameter (declared: none); declare "
        "the parameter that names the key: Param('nokey', STR, from_blackboard=False)"
    )
    assert writes_int == (
        "writes_keys names 'k', a parameter of type int: the parameter names the key, so it is "
        "a text, Param('k', STR, from_blackboard=False); the type of the value is the key's: "
        "writes_keys={'k': INT}"
    )
    assert reads_typed.startswith(
        "the type given for the key 'k' names is 'int': a key's type is a ValueType of "
        "roomba_bt.behaviours.units (DURATION, SPEED,"
    )
    assert twice == (
        "'k' names a key it reads and writes, typed differently in writes_keys and "
        "reads_keys: one key holds one type"
    )


# -- declare_like: extending a built-in ---------------------------------------------------


@declare_like(
    WallFollow,
    "wall_follow_for",
    drop_params=("duration",),
    add_params=(
        Param("distance", DISTANCE, required=True, minimum=0, maximum=50_000),
        Param("speed", WallFollow.declaration.params[0].type, default="100 mm/s", minimum=20),
    ),
    add_reads=ENCODER_PACKETS,
    primary="distance",
)
class WallFollowFor(WallFollow):
    """Follow a wall on the right for a distance (her plugin's, declared like the parent)."""


def test_declare_like_carries_the_parent_s_declaration_with_the_changes_said() -> None:
    parent, child = WallFollow.declaration, WallFollowFor.declaration
    assert child.name == "wall_follow_for" and child.cls is WallFollowFor
    assert child.kind == "action" and child.sends == parent.sends
    assert child.doc.startswith("Follow a wall on the right for a distance")
    names = [p.name for p in child.params]
    # duration dropped, speed replaced in its place, distance after the parent's
    assert names == [p.name for p in parent.params if p.name != "duration"] + ["distance"]
    speed = child.param("speed")
    assert speed is not None and speed.default == "100 mm/s"
    assert child.packets({}) == (*parent.packets({}), *ENCODER_PACKETS)
    assert child.primary == "distance"
    assert child.may_succeed is None  # "only with a duration" is the parent's, not carried
    child.validate()


def test_declare_like_keeps_the_parent_s_cross_parameter_checks() -> None:
    """The front_clear / front_threshold hysteresis check, which a copy by hand dropped."""
    with pytest.raises(ParamError, match="front_clear 900 is above front_threshold 800"):
        WallFollowFor("follow", {"distance": "1 m", "front_clear": 900})
    WallFollowFor("follow", {"distance": "1 m", "front_clear": 300})


def _at_most_one_metre(params: Mapping[str, Any]) -> list[str]:
    distance = params.get("distance")
    return ["distance at most 1 m here"] if isinstance(distance, float) and distance > 1000 else []


@declare_like(
    WallFollowFor,
    "short_follow",
    add_constraints=_at_most_one_metre,
)
class ShortFollow(WallFollowFor):
    """Both the parent's rules and its own."""


def test_added_constraints_run_beside_the_parent_s() -> None:
    with pytest.raises(ParamError, match="front_clear 900 is above"):
        ShortFollow("s", {"distance": "0.5 m", "front_clear": 900})
    with pytest.raises(ParamError, match="distance at most 1 m here"):
        ShortFollow("s", {"distance": "2 m"})
    assert ShortFollow.declaration.primary == "distance"


@declare("key_writer", kind="action", params=(Param("out", STR, from_blackboard=False),),
         writes_keys={"out": INT}, reads=lambda params: (7,))  # fmt: skip
class KeyWriter(Action):
    """A parent with a typed key and packets that depend on the parameters."""

    def update(self) -> Status:
        return Status.SUCCESS


def test_declare_like_carries_keys_still_declared_and_reads_of_a_function() -> None:
    @declare_like(KeyWriter, "key_writer_plus", add_reads=(7, 8))
    class Plus(KeyWriter):
        """Carries the key and the parent's packets, the added ones after them."""

    @declare_like(KeyWriter, "key_writer_less", drop_params=("out",))
    class Less(KeyWriter):
        """Its key parameter dropped: the key goes with it."""

    plus, less = Plus.declaration, Less.declaration
    assert plus.writes_keys == ("out",) and plus.key_type("out") is INT
    assert plus.packets({}) == (7, 8)
    assert less.writes_keys == () and less.key_types == ()
    less.validate()


def test_declare_like_refuses_a_parent_without_a_declaration_and_an_unknown_drop() -> None:
    with pytest.raises(DeclarationError, match="drop_params names \\['durration'\\], which "):
        declare_like(WallFollow, "x", drop_params=("durration",))
    with pytest.raises(DeclarationError, match="the parent is no declared behaviour"):
        declare_like(Action, "x")


# -- a write to a key the mission never declared -----------------------------------------


@declare("undeclared_writer", kind="action")
class UndeclaredWriter(Action):
    """Writes a key it never declared (her bad.py's)."""

    def update(self) -> Status:
        write_key("secret", 5, self.name)
        return Status.SUCCESS


def _warnings(caplog: pytest.LogCaptureFixture) -> list[str]:
    return [r.getMessage() for r in caplog.records if r.levelno == logging.WARNING]


def test_a_write_to_an_undeclared_key_is_warned_of_once_a_key_a_run(
    caplog: pytest.LogCaptureFixture,
) -> None:
    declare_keys({"x": INT})
    node = UndeclaredWriter("undeclared_writer", {})
    with caplog.at_level(logging.WARNING, logger="roomba_bt.mission"):
        node.update()
        node.update()  # the same key again: said once
        write_key("x", 1)  # declared: nothing said
    [said] = _warnings(caplog)
    assert said.startswith(
        "write_key('secret') by 'undeclared_writer' at "
        f"{Path(__file__).resolve()}:{UndeclaredWriter.update.__code__.co_firstlineno + 1}: "
        "blackboard key 'secret' is not declared by the mission (it declares: x), so no check "
        "or @secret of the mission reads it; declare it under blackboard: (secret: {type: ...})"
    ), said
    caplog.clear()
    declare_keys({})  # the next run, of a mission that declares none: said again
    with caplog.at_level(logging.WARNING, logger="roomba_bt.mission"):
        node.update()
    [said] = _warnings(caplog)
    assert "(it declares: none)" in said


def test_a_tree_that_declares_no_keys_writes_any_without_a_word(
    caplog: pytest.LogCaptureFixture,
) -> None:
    """No mission, no declare_keys (a tree built in Python): its keys are its own."""
    with caplog.at_level(logging.WARNING, logger="roomba_bt.mission"):
        UndeclaredWriter("undeclared_writer", {}).update()
    assert _warnings(caplog) == []


UNDECLARED_WRITER = '''
from py_trees.common import Status

from roomba_bt.behaviours import Action, declare, write_key


@declare("undeclared_writer", kind="action")
class UndeclaredWriter(Action):
    """Writes a key it never declared."""

    def update(self):
        write_key("secret", 5, self.name)
        return Status.SUCCESS
'''


def _writer_run(tmp_path: Path, plugin: str, keys: str) -> list[str]:
    """``run``'s words for her ``m_w2.yaml``: ``plugin`` as ``bad.py``, the mission declaring
    ``keys`` (YAML under ``blackboard:``) and running its writer after a log."""
    (tmp_path / "bad.py").write_text(plugin)
    mission = tmp_path / "m_w2.yaml"
    mission.write_text(
        f"mission: w2\nplugins: [./bad.py]\nblackboard:\n  {keys}\n"
        "tree:\n  sequence:\n    - log: hi\n    - undeclared_writer\n"
    )
    return ["run", str(mission), "--fast", "--allow-plugin-files", "--display", "none"]


def test_a_run_says_the_undeclared_write_and_still_succeeds(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    """Her ``m_w2.yaml``: SUCCESS with not a word. Warned, not refused: nothing drives on
    it (an undeclared command escapes the mode check, and is refused), but no reader in the
    mission can see it."""
    argv = _writer_run(tmp_path, UNDECLARED_WRITER, "x: int\n  y: int")
    with caplog.at_level(logging.WARNING, logger="roomba_bt.mission"):
        assert main(argv) == ExitCode.OK
    [said] = _warnings(caplog)
    assert f"by 'undeclared_writer' at {tmp_path / 'bad.py'}:12: " in said
    assert "blackboard key 'secret' is not declared by the mission (it declares: x, y)" in said


MISSPELT_WRITER = UNDECLARED_WRITER.replace('"secret"', '"dirt_levl"')


def test_a_run_s_summary_says_the_undeclared_write_with_a_did_you_mean_and_strict_fails_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], caplog: pytest.LogCaptureFixture
) -> None:
    """A plugin's misspelt key (``dirt_levl``, the mission declaring ``dirt_level``) was one
    log line among the run's, the summary silent and ``--strict`` passing it: the summary
    now says it as eval's does, with the key it may be, and ``--strict`` fails the run (the
    mission's own fault, as a refused command is)."""
    argv = _writer_run(tmp_path, MISSPELT_WRITER, "dirt_level: int\n  y: int")
    with caplog.at_level(logging.WARNING, logger="roomba_bt.mission"):
        assert main(argv) == ExitCode.OK
    [logged] = _warnings(caplog)
    assert "not declared by the mission (did you mean 'dirt_level'?) (it declares:" in logged
    out = capsys.readouterr().out
    where = f"by 'undeclared_writer' at {tmp_path / 'bad.py'}:12"
    assert (
        f"warning      write_key('dirt_levl') {where}: blackboard key 'dirt_levl' is not "
        "declared by the mission (did you mean 'dirt_level'?); declare it under blackboard: "
        "(dirt_levl: {type: ...}), or name a declared key in a parameter listed in writes_keys\n"
    ) in out
    assert main([*argv, "--strict"]) == ExitCode.STRICT
    out, err = capsys.readouterr()
    found = (
        "1 blackboard key written that the mission does not declare (the first: "
        f"write_key('dirt_levl') {where} (did you mean 'dirt_level'?))"
    )
    assert f"strict       FAILED (exit 7): {found}\n" in out
    assert f"roomba-bt: --strict: {found}" in err


def test_a_run_s_summary_gives_no_did_you_mean_for_a_key_like_none_declared(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    argv = _writer_run(tmp_path, UNDECLARED_WRITER, "x: int")
    assert main(argv) == ExitCode.OK
    out = capsys.readouterr().out
    assert "blackboard key 'secret' is not declared by the mission; declare it" in out
