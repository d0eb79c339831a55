"""A plugin's key parameters may say the type of the value (``writes_keys={"key": INT}``,
as BT.CPP's ``OutputPort<int>``), and validate holds the mission's ``blackboard:``
declaration of the key to it. A plugin author's ``dirt_seen`` (an int dirt level) validated
into a ``str`` key and ended the run 18 s in with ``KeyType``; into a ``speed`` key it ran
silently, the level read as mm/s (session 31). ``roomba-bt behaviours`` lists the key
parameters with their types."""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path

import pytest
from py_trees.common import Status

from roomba_bt.behaviours import (
    FLOAT,
    INT,
    STR,
    Action,
    BlackboardRef,
    Condition,
    Param,
    ParamError,
    ValueType,
    declare,
    default_registry,
    write_key,
)
from roomba_bt.cli import main
from roomba_bt.robot.interface import Snapshot

Errors = Callable[..., list[str]]


@declare(
    "dirt_seen",
    kind="condition",
    params=(
        Param("level", INT, default=1, minimum=1, maximum=255),
        Param("key", STR, from_blackboard=False, doc="a declared int key"),
    ),
    reads=(15,),
    writes_keys={"key": INT},
    primary="level",
)
class DirtSeen(Condition):
    """The dirt detector hears dirt; the level seen is written to ``key`` (her plugin's)."""

    def check(self, snapshot: Snapshot) -> bool:
        level = snapshot.frame.dirt_detect
        if level >= self.number("level"):
            write_key(str(self.value("key")), level, self.name)
            return True
        return False


@declare(
    "above",
    kind="condition",
    params=(Param("key", STR, required=True, from_blackboard=False), Param("than", FLOAT)),
    reads_keys={"key": FLOAT},
)
class Above(Condition):
    """A float key above a number (a typed reader)."""

    def check(self, snapshot: Snapshot) -> bool:
        return False


@declare(
    "untyped_writer",
    kind="action",
    params=(Param("key", STR, required=True, from_blackboard=False),),
    writes_keys=("key",),
)
class UntypedWriter(Action):
    """A plugin written before keys had types: any key but a mark is still taken."""

    def update(self) -> Status:
        return Status.SUCCESS


REGISTRY = default_registry().with_behaviours([DirtSeen, Above, UntypedWriter])


def _mission(key_type: str, leaf: str = "dirt_seen: {level: 20, key: lvl}") -> str:
    return (
        f"blackboard:\n  lvl: {{type: {key_type}}}\n  wp: {{fields: {{d: distance, n: int}}}}\n"
        f"tree:\n  sequence:\n    - set: {{key: wp, value: {{d: 1 m, n: 2}}}}\n    - {leaf}\n"
    )


WRITES_INT_INTO = (
    "7:35: dirt_seen.key: blackboard key 'lvl' is declared {found}, and dirt_seen writes a value "
    "of type int (its declaration: writes_keys={{'key': INT}}): declare 'lvl' with type int, or "
    "name a key of that type"
)


@pytest.mark.parametrize(
    ("key_type", "found"),
    [("str", "str"), ("speed", "speed (mm/s)"), ("bool", "bool"), ("mark", "mark")],
)
def test_a_typed_writer_into_a_key_of_another_type_is_an_error_where_the_key_is_named(
    errors_of: Errors, key_type: str, found: str
) -> None:
    """Units included: an int dirt level in a ``speed`` key is an error, not a warning
    (``write_key`` takes the number, and a ``drive`` reads it as mm/s)."""
    assert errors_of(_mission(key_type), registry=REGISTRY) == [WRITES_INT_INTO.format(found=found)]


@pytest.mark.parametrize("key_type", ["int", "float"])
def test_a_typed_writer_into_its_type_or_a_float_key_validates(
    errors_of: Errors, key_type: str
) -> None:
    """An int is a float (``write_key`` takes 40 into a float key): no error."""
    assert errors_of(_mission(key_type), registry=REGISTRY) == []


@pytest.mark.parametrize(
    ("leaf", "expected"),
    [
        ("above: {key: lvl}", []),  # an int key read as a float
        ("above: {key: wp.n}", []),  # a record's int field, the same
        (
            "above: {key: wp.d}",
            [
                "7:20: above.key: blackboard key 'wp.d' is declared distance (mm), and above "
                "reads a value of type float (its declaration: reads_keys={'key': FLOAT}): "
                "declare 'wp.d' with type float, or name a key of that type"
            ],
        ),
    ],
)
def test_a_typed_reader_is_held_to_the_key_it_reads(
    errors_of: Errors, leaf: str, expected: list[str]
) -> None:
    text = _mission("int", leaf).replace("    - above", "    - dirt_seen: {key: lvl}\n    - above")
    assert errors_of(text, registry=REGISTRY) == [e.replace("7:", "8:", 1) for e in expected]


def test_an_untyped_key_parameter_takes_any_key_but_a_mark(errors_of: Errors) -> None:
    """Backward compatible: a plugin's ``writes_keys=("key",)`` validates as before."""
    assert errors_of(_mission("str", "untyped_writer: {key: lvl}"), registry=REGISTRY) == []
    assert errors_of(_mission("mark", "untyped_writer: {key: lvl}"), registry=REGISTRY) == [
        "7:29: untyped_writer.key: blackboard key 'lvl' is mark; untyped_writer needs a key "
        "holding a value (not a mark)"
    ]


def test_the_shipped_key_parameters_are_typed() -> None:
    """``mark`` writes a mark and ``odometry`` reads one, said by their declarations (the
    validator named the two behaviours in its code); ``set`` and ``check`` take the key's
    type, untyped."""
    registry = default_registry()
    types: dict[str, ValueType | None] = {}
    for name, pname in (("mark", "key"), ("odometry", "since"), ("set", "key"), ("check", "key")):
        declaration = registry.get(name)
        assert declaration is not None
        types[name] = declaration.key_type(pname)
    assert {name: t and t.name for name, t in types.items()} == {
        "mark": "mark",
        "odometry": "mark",
        "set": None,
        "check": None,
    }


PLUGIN = '''
from roomba_bt.behaviours import INT, STR, Condition, Param, declare


@declare("dirt_seen", kind="condition",
         params=(Param("key", STR, from_blackboard=False),), writes_keys={"key": INT})
class DirtSeen(Condition):
    """Dirt seen."""

    def check(self, snapshot):
        return False
'''


def test_behaviours_lists_the_key_parameters_and_their_types(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``behaviours`` (text and ``--json``) did not say that a behaviour writes or reads
    keys at all."""
    plugin = tmp_path / "dirt.py"
    plugin.write_text(PLUGIN)
    assert main(["behaviours", "dirt_seen", "check", "--plugin-file", str(plugin)]) == 0
    out = capsys.readouterr().out
    assert "    writes the blackboard key named by key: a value of type int\n" in out
    assert "    reads the blackboard key named by key: untyped (any key but a mark)\n" in out
    assert main(["behaviours", "dirt_seen", "mark", "--json", "--plugin-file", str(plugin)]) == 0
    listed = {e["name"]: e for e in json.loads(capsys.readouterr().out)}
    assert listed["dirt_seen"]["writes_keys"] == [{"parameter": "key", "type": "int"}]
    assert listed["dirt_seen"]["reads_keys"] == []
    assert listed["mark"]["writes_keys"] == [{"parameter": "key", "type": "mark"}]


@declare(
    "count_into",
    kind="action",
    params=(Param("key", STR, required=True, doc="left from_blackboard=True, as a plugin may"),),
    writes_keys={"key": INT},
)
class CountInto(Action):
    """Writes 3 to the key its parameter names; its author forgot ``from_blackboard=False``."""

    def update(self) -> Status:
        write_key(str(self.value("key")), 3, self.name)
        return Status.SUCCESS


COUNTING_PLUGIN = '''
from py_trees.common import Status

from roomba_bt.behaviours import INT, STR, Action, Param, declare, write_key


@declare("count_into", kind="action", params=(Param("key", STR, required=True),),
         writes_keys={"key": INT})
class CountInto(Action):
    """Writes 3 to the key its parameter names (from_blackboard left at its default)."""

    def update(self):
        write_key(str(self.value("key")), 3, self.name)
        return Status.SUCCESS
'''
POINTER = (
    "blackboard:\n  lvl: {type: int}\n  pointer: {type: str, initial: top}\n"
    '  top: {type: speed}\ntree:\n  sequence:\n    - count_into: {key: "@pointer"}\n'
)


def test_a_key_parameter_never_reads_its_key_s_name_from_the_blackboard(
    mission_file: Callable[..., Path], capsys: pytest.CaptureFixture[str]
) -> None:
    """``key: "@pointer"`` validated and ran when the plugin left ``from_blackboard`` at its
    default: the key's name came from the blackboard at run time, and the checks of the key
    (declared, of its type, written before read) were passed by; the int went into ``top``,
    a speed. A key parameter takes its key's name only, said at the file:line:col with the
    plugin, by ``validate`` and by ``run`` before anything moves (exit 2)."""
    path = mission_file("plugins: [counting.py]\n" + POINTER, name="pointer.yaml")
    plugin = path.parent / "counting.py"
    plugin.write_text(COUNTING_PLUGIN, encoding="utf-8")
    for command in (["validate"], ["run", "--fast"]):
        assert main([*command, "--allow-plugin-files", str(path)]) == 2
        said = "".join(capsys.readouterr())  # validate says it on stdout, run on stderr
        assert (
            f"{path}:8:25: count_into.key: a blackboard value (@key) is not allowed here: key "
            f"names the key count_into (plugin {plugin}) writes, which is checked before the "
            "run (declared, of its type, written before it is read); a name read from the "
            "blackboard would skip those checks: write the key's name (key: my_key)"
        ) in said, said


def test_a_key_parameter_built_in_python_refuses_a_blackboard_value() -> None:
    """The same rule for a tree built in Python, which nothing validates: refused when the
    leaf is built (``ParamError``), not read at its start as any other ``@key`` is."""
    with pytest.raises(ParamError) as refused:
        CountInto("count", {"key": "@pointer"})
    assert str(refused.value).startswith(
        "count_into 'count': key @pointer: not allowed: key names the key count_into writes"
    )
    with pytest.raises(ParamError):
        CountInto("count", {"key": BlackboardRef("pointer")})
    assert CountInto("count", {"key": "lvl"}).value("key") == "lvl"
