"""The JSON Schema of mission files, generated from the same declarations the validator
reads (``roomba-bt schema > mission.schema.json``), for editor completion and CI.

The schema knows every node word, every behaviour's parameters with their types and units,
and the modifiers (``name``, ``while``, ``until``). What it cannot express (units in range,
modes, blackboard order, the stream budget) ``roomba-bt validate`` checks.
"""

from __future__ import annotations

from typing import Any

from roomba_bt.behaviours.declare import Declaration
from roomba_bt.behaviours.registry import Registry, default_registry
from roomba_bt.behaviours.units import VALUE_TYPES
from roomba_bt.mission.ir import COMPOSITES, SIMPLE_DECORATORS

SCHEMA_ID = "https://roomba-bt.example/mission.schema.json"
_NODE = {"$ref": "#/$defs/node"}
_SUBSTITUTION = {
    "type": "string",
    "pattern": r"^(-?\$\{[A-Za-z_][A-Za-z0-9_]*\}|@[a-z_][a-z0-9_]*(\.[a-z_][a-z0-9_]*)?)$",
    "description": "${parameter} or @blackboard_key",
}
_MODIFIERS: dict[str, Any] = {
    "name": {"type": "string", "description": "the node's name in displays"},
    "while": {**_NODE, "description": "run while this condition succeeds, else FAILURE"},
    "until": {**_NODE, "description": "run until this condition succeeds, then SUCCESS"},
}


def _with_modifiers(word: str, value: dict[str, Any], doc: str) -> dict[str, Any]:
    return {
        "type": "object",
        "description": doc,
        "properties": {word: value, **_MODIFIERS},
        "required": [word],
        "additionalProperties": False,
    }


def _param_schema(decl: Declaration) -> dict[str, Any]:
    props: dict[str, Any] = {}
    for p in decl.params:
        schema = p.type.schema()
        if p.minimum is not None and p.type.name in ("int", "float"):
            schema["minimum"] = p.minimum
        if p.maximum is not None and p.type.name in ("int", "float"):
            schema["maximum"] = p.maximum
        described = f"{p.doc} ({p.describe()})".strip() if p.doc else p.describe()
        props[p.name] = {
            "anyOf": [schema, _SUBSTITUTION] if schema else [{}],
            "description": described,
        }
    body: dict[str, Any] = {"type": "object", "properties": props, "additionalProperties": False}
    required = [p.name for p in decl.params if p.required]
    if required:
        body["required"] = required
    forms: list[dict[str, Any]] = [body]
    if not required:
        forms.append({"type": "null"})
    if decl.primary is not None:
        forms.append(props[decl.primary])
    return {"anyOf": forms}


def mission_schema(registry: Registry | None = None) -> dict[str, Any]:
    """The whole schema as a JSON-ready dict."""
    registry = registry or default_registry()
    defs: dict[str, Any] = {}
    node_forms: list[dict[str, Any]] = []
    bare: list[str] = []
    children = {"type": "array", "items": _NODE, "minItems": 1}
    for word, (cls, memory) in COMPOSITES.items():
        options: dict[str, Any] = {
            "children": children,
            "memory": {"type": "boolean", "default": memory},
            "name": {"type": "string"},
        }
        if word == "parallel":
            options |= {
                "policy": {"enum": ["all", "one", "selected"], "default": "all"},
                "synchronise": {"type": "boolean", "default": True},
                "selected": {"type": "array", "items": {"type": "string"}},
            }
        long_form = {
            "type": "object",
            "properties": options,
            "required": ["children"],
            "additionalProperties": False,
        }
        doc = f"py_trees {cls} (memory {str(memory).lower()} by default)"
        defs[word] = _with_modifiers(word, {"anyOf": [children, long_form]}, doc)
    decorator_options: dict[str, dict[str, Any]] = {
        "retry": {"times": {"type": "integer", "minimum": 1}},
        "repeat": {
            "times": {"type": "integer", "minimum": 1},
            "for": VALUE_TYPES["duration"].schema(),
        },
        "timeout": {"after": VALUE_TYPES["duration"].schema()},
        "delay": {"for": VALUE_TYPES["duration"].schema()},
        "oneshot": {"policy": {"enum": ["on_success", "on_completion"]}},
        "for_each": {"key": {"type": "string"}, "in": {"type": "array"}},
    }
    required_options = {"retry": ["times"], "timeout": ["after"], "delay": ["for"],
                        "for_each": ["key", "in"]}  # fmt: skip
    for word, opts in decorator_options.items():
        opts = {k: {"anyOf": [v, _SUBSTITUTION]} for k, v in opts.items()}
        long_form = {
            "type": "object",
            "properties": {**opts, "do": _NODE},
            "required": ["do", *required_options.get(word, [])],
            "additionalProperties": False,
        }
        value = {"anyOf": [long_form, _NODE]} if word == "oneshot" else long_form
        defs[word] = _with_modifiers(word, value, f"decorator {word}")
    for word in SIMPLE_DECORATORS:
        value = {"anyOf": [_NODE, {"type": "object", "properties": {"do": _NODE}}]}
        defs[word] = _with_modifiers(word, value, f"decorator {word}")
    subtree_use = {
        "anyOf": [
            {"type": "string"},
            {"type": "object", "properties": {"id": {"type": "string"}}, "required": ["id"]},
        ]
    }
    defs["subtree"] = _with_modifiers("subtree", subtree_use, "use a subtree by name")
    for decl in registry:
        defs[decl.name] = _with_modifiers(decl.name, _param_schema(decl), decl.doc)
        if not any(p.required for p in decl.params):
            bare.append(decl.name)
    node_forms = [{"$ref": f"#/$defs/{word}"} for word in defs]
    defs["node"] = {"anyOf": [*node_forms, {"enum": bare}]}
    type_names = [n for n in VALUE_TYPES if n != "mark"]
    parameter = {
        "type": "object",
        "properties": {
            "type": {"enum": [*type_names, "enum"]},
            "default": {},
            "doc": {"type": "string"},
            "choices": {"type": "array", "items": {"type": "string"}},
        },
        "required": ["type"],
        "additionalProperties": False,
    }
    key = {
        "anyOf": [
            {"enum": [*type_names, "mark"]},
            {
                "type": "object",
                "properties": {
                    "type": {"enum": [*type_names, "mark"]},
                    "fields": {"type": "object", "additionalProperties": {"enum": type_names}},
                    "initial": {},
                    "doc": {"type": "string"},
                },
                "additionalProperties": False,
            },
        ]
    }
    return {
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "$id": SCHEMA_ID,
        "title": "roomba-bt mission",
        "type": "object",
        "properties": {
            "mission": {"type": "string"},
            "description": {"type": "string"},
            "parameters": {"type": "object", "additionalProperties": parameter},
            "blackboard": {"type": "object", "additionalProperties": key},
            "plugins": {"type": "array", "items": {"type": "string"}},
            "include": {"type": "array", "items": {"type": "string"}},
            "subtrees": {
                "type": "object",
                "additionalProperties": {
                    "type": "object",
                    "properties": {
                        "parameters": {"type": "object", "additionalProperties": parameter},
                        "tree": _NODE,
                        "doc": {"type": "string"},
                    },
                    "required": ["tree"],
                    "additionalProperties": False,
                },
            },
            "tree": _NODE,
        },
        "additionalProperties": False,
        "$defs": defs,
    }
