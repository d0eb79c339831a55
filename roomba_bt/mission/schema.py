"""The JSON Schema of mission files, generated from the same declarations the validator
reads (``roomba-bt schema > mission.schema.json``), for editor completion and CI.

The schema knows every word of the language with its options (from
:data:`roomba_bt.behaviours.language.WORDS`), every behaviour's parameters with their types
and units, and the modifiers (``name``, ``while``, ``until``). What it cannot express (units
in range, modes, blackboard order, the stream budget) ``roomba-bt validate`` checks.
"""

from __future__ import annotations

from typing import Any

from roomba_bt.behaviours.declare import Declaration, Param
from roomba_bt.behaviours.language import MODIFIERS, STRUCTURAL, WORDS, NodeKind, Shape
from roomba_bt.behaviours.registry import Registry, default_registry
from roomba_bt.behaviours.units import VALUE_TYPES

SCHEMA_ID = "https://roomba-bt.example/mission.schema.json"
_NODE = {"$ref": "#/$defs/node"}
_SUBSTITUTION = {
    "type": "string",
    "pattern": r"^(-?\$\{[A-Za-z_][A-Za-z0-9_]*\}|@[a-z_][a-z0-9_]*(\.[a-z_][a-z0-9_]*)?)$",
    "description": "${parameter} or @blackboard_key",
}
_MODIFIERS: dict[str, Any] = {
    word: {**({"type": "string"} if word == "name" else _NODE), "description": doc}
    for word, doc in MODIFIERS.items()
}


def _with_modifiers(word: str, value: dict[str, Any], doc: str) -> dict[str, Any]:
    return {
        "type": "object",
        "description": doc,
        "properties": {word: value, **_MODIFIERS},
        "required": [word],
        "additionalProperties": False,
    }


def _option_schema(option: Param) -> dict[str, Any]:
    """A language option: its type (a ``${parameter}`` too, unless the compiler takes it as
    written), minimum and default."""
    schema = option.type.schema()
    if option.minimum is not None:
        schema["minimum"] = option.minimum
    if option.type not in STRUCTURAL:
        schema = {"anyOf": [schema, _SUBSTITUTION]}
    if option.default is not None:
        schema["default"] = option.default
    if option.doc:
        schema["description"] = option.doc
    return schema


def _word_schema(kind: NodeKind) -> dict[str, Any]:
    """What may follow a word of the language, from its :class:`NodeKind`."""
    options = {p.name: _option_schema(p) for p in kind.options}
    required = [p.name for p in kind.options if p.required]
    if kind.shape is Shape.SUBTREE:
        by_id = {"type": "object", "properties": options, "required": required}
        return {"anyOf": [{"type": "string"}, by_id]}
    if kind.shape is Shape.CHILDREN:
        children = {"type": "array", "items": _NODE, "minItems": 1}
        long_form = {"type": "object", "properties": {"children": children, **options},
                     "required": ["children"], "additionalProperties": False}  # fmt: skip
        return {"anyOf": [children, long_form]}
    long_form = {"type": "object", "properties": {**options, "do": _NODE},
                 "required": ["do", *required], "additionalProperties": False}  # fmt: skip
    return {"anyOf": [long_form, _NODE]} if kind.shape is Shape.CHILD_OR_DO else long_form


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
    for kind in WORDS.values():
        defs[kind.word] = _with_modifiers(kind.word, _word_schema(kind), kind.doc)
    for decl in registry:
        defs[decl.name] = _with_modifiers(decl.name, _param_schema(decl), decl.doc)
        if not any(p.required for p in decl.params):
            bare.append(decl.name)
    node_forms = [{"$ref": f"#/$defs/{word}"} for word in defs]
    defs["node"] = {"anyOf": [*node_forms, {"enum": bare}]}
    parameter, key = _declarations()
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


def _declarations() -> tuple[dict[str, Any], dict[str, Any]]:
    """A parameter declaration and a blackboard key declaration."""
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
    return parameter, key
