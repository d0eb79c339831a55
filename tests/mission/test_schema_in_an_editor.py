"""The JSON Schema as an editor or check-jsonschema uses it: they read the mission as YAML
1.2, where ``on`` and ``1_000`` are texts, not a boolean and a number as PyYAML (YAML 1.1,
roomba-bt's reader) reads them; and they show the errors the schema gives, where it gives
them (docs/missions.md, "The JSON Schema").

Session 29 (a team lead's report, teamci #4): ``motors: {vacuum: on}`` passed ``validate``
and failed check-jsonschema (the schema wanted a JSON boolean), though the docs say the
schema is never stricter; one typo (``velocty``) gave 517 errors under "not valid under any
of the given schemas" at the whole ``tree:``.
"""

from __future__ import annotations

import functools
import re
from pathlib import Path
from typing import Any

import pytest
import yaml

from roomba_bt.mission import compile_mission
from roomba_bt.mission.schema import mission_schema

CORE = "tag:yaml.org,2002:"


class Yaml12Loader(yaml.SafeLoader):
    """PyYAML with YAML 1.2's core schema, as the VS Code YAML extension (yaml-language-server)
    reads a file: booleans are only true/false, integers decimal, 0o octal or 0x hex (no
    ``_``, no ``0b``, no base 60), floats without ``_``. (ruamel, check-jsonschema's reader,
    reads ``on`` as a text too, but ``1_000`` and ``0b11`` as numbers.)"""


Yaml12Loader.yaml_implicit_resolvers = {
    first: [(tag, rx) for tag, rx in resolvers if tag not in {CORE + "bool", CORE + "int",
                                                               CORE + "float"}]
    for first, resolvers in yaml.SafeLoader.yaml_implicit_resolvers.items()
}  # fmt: skip
Yaml12Loader.add_implicit_resolver(
    CORE + "bool", re.compile(r"^(?:true|True|TRUE|false|False|FALSE)$"), list("tTfF")
)
Yaml12Loader.add_implicit_resolver(
    CORE + "int", re.compile(r"^(?:[-+]?[0-9]+|0o[0-7]+|0x[0-9a-fA-F]+)$"), list("-+0123456789")
)
Yaml12Loader.add_implicit_resolver(
    CORE + "float",
    re.compile(r"^(?:[-+]?(?:\.[0-9]+|[0-9]+(?:\.[0-9]*)?)(?:[eE][-+]?[0-9]+)?"
               r"|[-+]?\.(?:inf|Inf|INF)|\.(?:nan|NaN|NAN))$"),
    list("-+0123456789."),
)  # fmt: skip


def _int12(loader: yaml.SafeLoader, node: yaml.ScalarNode) -> int:
    text = str(node.value)
    base = {"0o": 8, "0x": 16}.get(text[:2], 10)
    return int(text[2:] if base != 10 else text, base)


Yaml12Loader.add_constructor(CORE + "int", _int12)


@functools.cache
def _validator() -> Any:
    import jsonschema

    schema = mission_schema()
    jsonschema.Draft202012Validator.check_schema(schema)
    return jsonschema.Draft202012Validator(schema)


def _as_an_editor_reads(text: str) -> Any:
    return yaml.load(text, Loader=Yaml12Loader)  # a SafeLoader


def _validate(text: str, tmp_path: Path) -> tuple[list[str], list[str]]:
    path = tmp_path / "m.yaml"
    path.write_text(text, encoding="utf-8")
    mission, diagnostics = compile_mission(path)
    errors = [d.message for d in diagnostics if d.severity == "error"]
    warnings = [str(w) for w in (mission.warnings if mission is not None else [])]
    return errors, warnings


def _mission(*steps: str, head: str = "") -> str:
    return head + "tree:\n  sequence:\n    - mode: safe\n" + "".join(f"    - {s}\n" for s in steps)


_WAIT = "{wait: 1s}"
#: (case, mission text, validate accepts it)
YAML_1_1_SPELLINGS: list[tuple[str, str, bool]] = [
    ("vacuum on", _mission("motors: {vacuum: on, main_brush: yes}"), True),
    ("case variants", _mission("motors: {vacuum: ON, main_brush: Yes, side_brush: OFF}"), True),
    ("off where only false may stand",
     _mission(f"reactive_sequence: {{memory: off, children: [{_WAIT}]}}"), True),
    ("no where only false may stand",
     _mission(f"reactive_sequence: {{memory: No, children: [{_WAIT}]}}"), True),
    ("a parameter's bool default",
     _mission("motors: {vacuum: '${v}'}", head="parameters:\n  v: {type: bool, default: yes}\n"),
     True),
    ("underscores in an integer", _mission(f"repeat: {{times: 1_000, do: {_WAIT}}}"), True),
    ("a binary integer", _mission(f"repeat: {{times: 0b11, do: {_WAIT}}}"), True),
    ("underscores in a float", _mission("wall_follow: {kp: 0.1_5}"), True),
    ("underscores in a text", _mission("log: 1_000"), True),
    # y and n are texts to PyYAML too: both refuse them for a boolean
    ("y", _mission("motors: {vacuum: y}"), False),
    # refused by validate (YAML 1.1 reads other numbers than shown); 010 is 10 to the editor
    ("octal", _mission(f"repeat: {{times: 010, do: {_WAIT}}}"), False),
    ("base 60", _mission("wait: 1:30"), False),
    ("infinity", _mission("wall_follow: {kp: .inf}"), False),
]  # fmt: skip
#: what the schema read as YAML 1.2 takes and validate refuses: the schema more lenient
#: where it cannot tell, never stricter (docs/missions.md)
LENIENT = {"octal"}


@pytest.mark.parametrize(
    ("name", "text", "validate_ok"), YAML_1_1_SPELLINGS, ids=[c[0] for c in YAML_1_1_SPELLINGS]
)
def test_the_schema_read_as_yaml_1_2_is_never_stricter_than_validate(
    name: str, text: str, validate_ok: bool, tmp_path: Path
) -> None:
    errors, _ = _validate(text, tmp_path)
    assert (not errors) is validate_ok, errors
    schema_errors = [e.message for e in _validator().iter_errors(_as_an_editor_reads(text))]
    if validate_ok:
        assert schema_errors == [], f"the schema refuses what validate accepts: {name}"
    else:
        assert bool(schema_errors) is (name not in LENIENT), schema_errors


@pytest.mark.parametrize(
    ("written", "column", "reading"),
    [("repeat: {times: 1_000, do: {wait: 1s}}", 23, "1000"),
     ("repeat: {times: 0b11, do: {wait: 1s}}", 23, "3"),
     ("log: 1_000", 12, "1000")],
)  # fmt: skip
def test_validate_warns_of_a_number_an_editor_reads_as_a_text(
    written: str, column: int, reading: str, tmp_path: Path
) -> None:
    """Before, ``times: 1_000`` passed in silence: 1000 to roomba-bt, the text "1_000" to the
    editor's YAML extension."""
    errors, [warning] = _validate(_mission(written), tmp_path)
    assert errors == []
    assert re.match(rf".*m\.yaml:4:{column}: warning: '", warning), warning
    assert f"to YAML 1.2 (an editor's YAML extension reads it so): write {reading}," in warning


def test_a_boolean_word_is_no_warning(tmp_path: Path) -> None:
    """``vacuum: on`` is documented and the schema takes it: nothing to warn of."""
    assert _validate(_mission("motors: {vacuum: on}"), tmp_path) == ([], [])


def _errors(text: str) -> list[Any]:
    """Every error the schema gives, those under an anyOf's or oneOf's too."""
    found, pending = [], list(_validator().iter_errors(_as_an_editor_reads(text)))
    while pending:
        error = pending.pop()
        found.append(error)
        pending.extend(error.context)
    return found


TYPO_IN_A_LIBRARY_LOOP = """\
blackboard:
  leg: distance
tree:
  sequence:
    - mode: safe
    - for_each:
        key: leg
        in: [50 cm, 50 cm]
        do:
          sequence:
            - drive: {velocty: 200 mm/s, distance: "@leg"}
              until: {bump: any}
            - turn: 90deg
"""


@pytest.mark.parametrize(
    ("name", "text", "path", "said"),
    [
        ("a parameter's typo", TYPO_IN_A_LIBRARY_LOOP,
         "$.tree.sequence[1].for_each.do.sequence[0].drive", "'velocty' was unexpected"),
        ("a word's typo", _mission("drvie: {velocity: 100 mm/s}"), "$.tree.sequence[1]",
         "'drvie' was unexpected"),
        ("a bare name's typo", _mission("stp"), "$.tree.sequence[1]", "'stp' is not one of"),
        ("a value", _mission("drive: {velocity: 100, duration: 1s}"),
         "$.tree.sequence[1].drive.velocity", "is not valid under any of the given schemas"),
        ("an option's typo", _mission("repeat: {tims: 2, do: {wait: 1s}}"),
         "$.tree.sequence[1].repeat", "'tims' was unexpected"),
        ("two words", _mission("wait: 1s\n      stop: ~"), "$.tree.sequence[1]",
         "is not one of ['wait', 'name', 'while', 'until']"),
    ],
)  # fmt: skip
def test_a_mistake_is_one_error_at_its_node(name: str, text: str, path: str, said: str) -> None:
    """The node schema picks a node's form by its one key (and a word's by its type or its
    ``do:``), as validate does: the error is where the mistake is, alone. Before, the node
    was an ``anyOf`` of its 110 words and spellings, and the typo 887 errors, the one shown
    at ``$.tree``."""
    top = list(_validator().iter_errors(_as_an_editor_reads(text)))
    shown = [(e.json_path, e.message[:80]) for e in top]
    assert [e.json_path for e in top if said in e.message] == [path], shown
    assert len(top) == (2 if name == "two words" else 1), shown  # the second word's own
    # and what an anyOf holds (a value's forms) is about that value
    assert all(e.json_path.startswith(path) for e in _errors(text))
