"""The generated JSON Schema accepts every shipped mission and rejects unknown words.

Checked with the jsonschema package (in the test extra) and with a small validator for the
subset the schema uses (type, enum, const, pattern, properties, required,
additionalProperties, propertyNames, items, minItems, maxItems, anyOf, allOf, if/then/else,
$ref), which needs nothing.
"""

from __future__ import annotations

import functools
import re
from pathlib import Path
from typing import Any

import pytest
import yaml

from roomba_bt.mission.schema import mission_schema

EXAMPLES = Path(__file__).resolve().parents[2] / "missions" / "examples"
SCHEMA = mission_schema()
_TYPES = {
    "object": dict, "array": list, "string": str, "boolean": bool, "null": type(None),
}  # fmt: skip


def valid(value: Any, schema: dict[str, Any]) -> bool:
    if "$ref" in schema:
        target = SCHEMA["$defs"][schema["$ref"].rsplit("/", 1)[1]]
        if not valid(value, target):
            return False
    if "anyOf" in schema and not any(valid(value, s) for s in schema["anyOf"]):
        return False
    if not all(valid(value, s) for s in schema.get("allOf", [])):
        return False
    if "if" in schema:
        chosen = schema.get("then" if valid(value, schema["if"]) else "else", {})
        if not valid(value, chosen):
            return False
    names = schema.get("propertyNames")
    if isinstance(value, dict) and names and not all(valid(key, names) for key in value):
        return False
    if "enum" in schema and value not in schema["enum"]:
        return False
    if "const" in schema and value != schema["const"]:
        return False
    kind = schema.get("type")
    if kind == "integer":
        if isinstance(value, bool) or not isinstance(value, int):
            return False
    elif kind == "number":
        if isinstance(value, bool) or not isinstance(value, int | float):
            return False
    elif kind is not None and not isinstance(value, _TYPES[kind]):
        return False
    if "pattern" in schema and isinstance(value, str) and not re.search(schema["pattern"], value):
        return False
    if isinstance(value, dict):
        props = schema.get("properties", {})
        if any(key not in value for key in schema.get("required", [])):
            return False
        extra = schema.get("additionalProperties", True)
        for key, item in value.items():
            rule = props.get(key, extra)
            if rule is False or (isinstance(rule, dict) and not valid(item, rule)):
                return False
    if isinstance(value, list):
        if len(value) < schema.get("minItems", 0) or len(value) > schema.get("maxItems", 10**9):
            return False
        if "items" in schema and not all(valid(item, schema["items"]) for item in value):
            return False
    return True


MISSIONS = EXAMPLES.parent
SHIPPED = sorted(
    {*MISSIONS.glob("*.yaml"), *MISSIONS.glob("lib/*.yaml"), *EXAMPLES.glob("*.yaml"),
     *EXAMPLES.glob("lib/*.yaml")}
)  # fmt: skip


def _schema_for(mission: dict[str, Any], path: Path) -> dict[str, Any]:
    """The published schema, or for a mission with plugin files the one ``roomba-bt schema
    --plugin-file FILE`` publishes (the installed behaviours plus those files')."""
    if "plugins" not in mission:
        return SCHEMA
    from roomba_bt.behaviours.registry import default_registry

    registry = default_registry()
    for plugin in mission["plugins"]:
        registry, errors = registry.with_file(path.parent / plugin)
        assert errors == [], errors
    return mission_schema(registry)


@functools.cache
def _published() -> Any:
    """A jsonschema validator of the published schema, the schema itself checked once."""
    import jsonschema

    jsonschema.Draft202012Validator.check_schema(SCHEMA)
    return jsonschema.Draft202012Validator(SCHEMA)


@pytest.mark.parametrize("path", SHIPPED, ids=lambda p: str(p.relative_to(MISSIONS)))
def test_every_shipped_mission_and_example_is_valid_by_jsonschema(path: Path) -> None:
    """With the jsonschema package (a test dependency): what editors and CI would use."""
    import jsonschema

    mission = yaml.safe_load(path.read_text(encoding="utf-8"))
    schema = _schema_for(mission, path)
    if schema is SCHEMA:
        _published().validate(mission)
        assert valid(mission, schema)
    else:
        jsonschema.validate(mission, schema, cls=jsonschema.Draft202012Validator)


def test_the_published_schema_knows_no_plugin_file_behaviour() -> None:
    import jsonschema

    path = EXAMPLES / "custom_condition.yaml"
    mission = yaml.safe_load(path.read_text(encoding="utf-8"))
    with pytest.raises(jsonschema.ValidationError):
        _published().validate(mission)


def test_jsonschema_rejects_what_the_validator_rejects() -> None:
    import jsonschema

    for tree in ({"drvie": {"velocity": "100 mm/s"}}, {"drive": {"velocity": 100}}):
        with pytest.raises(jsonschema.ValidationError):
            _published().validate({"tree": tree})


@pytest.mark.parametrize(
    "tree",
    [
        {"drvie": {"velocity": "100 mm/s"}},
        {"drive": {"velocty": "100 mm/s"}},
        {"drive": {"velocity": 100}},
        {"bump": "middle"},
        {"turn": {"speed": "100 mm/s"}},
        {"sequence": []},
        {"retry": {"do": "wall"}},
    ],
)
def test_the_schema_rejects_what_the_validator_rejects(tree: dict[str, Any]) -> None:
    assert not valid({"tree": tree}, SCHEMA)
    assert valid({"tree": "wall"}, SCHEMA)


@pytest.mark.parametrize(
    "tree",
    [
        # e10r (session 28): passed the schema and the validator; py_trees refused it at
        # the run's start, exit 4
        {"parallel": {"policy": "selected", "selected": [],
                      "children": [{"wait": "1s", "name": "a"}, {"wait": "3s"}]}},
        {"for_each": {"key": "d", "in": [], "do": {"log": "x"}}},
    ],
)  # fmt: skip
def test_the_schema_refuses_an_empty_list_option(tree: dict[str, Any]) -> None:
    import jsonschema

    mission = {"blackboard": {"d": {"type": "distance"}}, "tree": tree}
    assert not valid(mission, SCHEMA)
    with pytest.raises(jsonschema.ValidationError):
        _published().validate(mission)


def test_every_list_option_of_the_language_says_it_is_never_empty() -> None:
    """Each option of the language table whose value is a list (``parallel.selected``,
    ``for_each.in``) is refused empty by the compiler: its schema says ``minItems: 1``."""
    from roomba_bt.behaviours.language import WORDS

    lists = [
        (kind.word, param.name, dict(param.type.json_schema))
        for kind in WORDS.values()
        for param in kind.options
        if dict(param.type.json_schema).get("type") == "array"
    ]
    assert {(word, name) for word, name, _ in lists} == {("parallel", "selected"),
                                                          ("for_each", "in")}  # fmt: skip
    assert all(schema.get("minItems") == 1 for _, _, schema in lists), lists
