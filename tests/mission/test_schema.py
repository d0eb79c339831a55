"""The generated JSON Schema accepts every shipped mission and rejects unknown words.

jsonschema is not a dependency, so this file carries a small validator for the subset the
schema uses (type, enum, const, pattern, properties, required, additionalProperties, items,
minItems, maxItems, anyOf, $ref).
"""

from __future__ import annotations

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


@pytest.mark.parametrize(
    "path", sorted(EXAMPLES.glob("*.yaml")) + sorted(EXAMPLES.glob("lib/*.yaml")), ids=str
)
def test_the_schema_accepts_every_example(path: Path) -> None:
    mission = yaml.safe_load(path.read_text(encoding="utf-8"))
    if "plugins" in mission:
        pytest.skip("behaviours from plugin files are not in the published schema")
    assert valid(mission, SCHEMA)


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
