"""The JSON Schema of mission files, generated from the same declarations the validator
reads (``roomba-bt schema > mission.schema.json``), for editor completion and CI.

The schema knows every word of the language with its options and the rules between them
(from :data:`roomba_bt.behaviours.language.WORDS`), every behaviour's parameters with their
types, units and ranges, where an ``@key`` may stand, and the modifiers (``name``,
``while``, ``until``). What it cannot express ``roomba-bt validate`` checks: a quantity's
range (a pattern cannot compare numbers: the description says the range; a minus sign is
refused where the minimum is not below 0), a behaviour's own rules between its parameters,
modes, blackboard order and types, the stream budget, what a ``sensor:`` comparison names
(tests/mission/test_schema_agrees.py lists these, case by case).

The schema has no ``$id``: it is generated on each machine from the behaviours installed
there and published at no address, so an ``$id`` would give different documents one name
(0.1.0's was ``https://roomba-bt.example/mission.schema.json``, an address that does not
exist). Its references are all ``#/$defs/...``, resolved in the document itself, so an
editor or ``check-jsonschema`` reads it from wherever the file is.
"""

from __future__ import annotations

from typing import Any

from roomba_bt.behaviours.declare import Declaration, Param, range_said
from roomba_bt.behaviours.language import KEY_ITEMS, MODIFIERS, STRUCTURAL, WORDS, NodeKind, Shape
from roomba_bt.behaviours.registry import Registry, default_registry
from roomba_bt.behaviours.units import UNITS, VALUE_TYPES, boolean_schema, quantity_schema
from roomba_bt.mission.values import (
    LIST_ITEM_TYPES,
    PARAMETER_TYPE_NAMES,
    PARAMETER_TYPE_OPTIONS,
)

_NODE = {"$ref": "#/$defs/node"}
_NAME = r"[A-Za-z_][A-Za-z0-9_]*"
#: a ``${parameter}`` (``-${p}`` negates it): any option or parameter may be one
_PARAMETER = {
    "type": "string",
    "pattern": rf"^-?\$\{{{_NAME}\}}$",
    "description": "${parameter}",
}
#: an ``@key`` (``@record.field``): only a behaviour's parameter declared ``from_blackboard``
#: (the language's options and ``mode.to`` are read when the tree is built)
_KEY_REF = {
    "type": "string",
    "pattern": r"^@[a-z_][a-z0-9_]*(\.[a-z_][a-z0-9_]*)?$",
    "description": "@blackboard_key",
}
#: what a name a mission declares is (parameters, blackboard keys, subtrees)
_SNAKE_CASE = {"pattern": r"^[a-z_][a-z0-9_]*$"}
_MODIFIERS: dict[str, Any] = {
    word: {**({"type": "string"} if word == "name" else _NODE), "description": doc}
    for word, doc in MODIFIERS.items()
}
#: said in the description of every quantity with a range (docs/missions.md, "Schema")
RANGE_NOT_IN_SCHEMA = "checked by roomba-bt validate: a JSON Schema pattern cannot hold a range"


def _either(
    test: dict[str, Any], then: dict[str, Any], otherwise: dict[str, Any]
) -> dict[str, Any]:
    """``then`` where the value passes ``test`` (its type, its ``do:``), else ``otherwise``:
    the form validate reads it as, chosen as validate chooses (an ``anyOf`` of the forms
    reported a mistake in one as "not valid under any of the given schemas" at the node
    above, and every other form's mismatch beside it)."""
    return {"if": test, "then": then, "else": otherwise}


def _node_schema(words: dict[str, str], bare: list[str]) -> dict[str, Any]:
    """A node: a behaviour's name alone (``- stop``), or a mapping of one word (a word of the
    language, a behaviour's name or ``package:name``) and the modifiers. One object schema
    whose properties are every word, not an ``anyOf`` of one schema per word: a typo inside
    ``drive:`` is one error at ``drive``'s value (``'velocty' was unexpected``), an unknown
    word one error at the node; it was 500-900 errors under one "not valid under any of the
    given schemas" at the whole ``tree:``. ``words``: each word's description."""
    modifiers = list(MODIFIERS)
    one_word = [
        {"if": {"required": [word]}, "then": {"propertyNames": {"enum": [word, *modifiers]}}}
        for word in words
    ]
    mapping = {
        "type": "object",
        "properties": {
            **{
                word: {"$ref": f"#/$defs/{word}", "description": doc} for word, doc in words.items()
            },
            **_MODIFIERS,
        },
        "additionalProperties": False,
        # no word at all (only modifiers, or nothing): one of them is needed; a node with an
        # unknown word is said once, by additionalProperties
        "if": {"propertyNames": {"enum": modifiers}},
        "then": {"anyOf": [{"required": [word]} for word in words]},
        # and one at the most (a second word is said at the node)
        "allOf": one_word,
    }
    return _either({"type": "string"}, {"enum": bare}, mapping)


def _value_schema(param: Param) -> tuple[dict[str, Any], str]:
    """A value of ``param``'s type within its range, as far as JSON Schema holds it: an int's
    or a float's bounds; a quantity's sign (no minus where the minimum is not below 0), its
    range said in the returned note, not checked (a pattern cannot compare numbers)."""
    schema = param.type.schema()
    lo, hi = param.minimum, param.maximum
    if param.type.name in ("int", "float"):
        if lo is not None:
            schema["minimum"] = lo
        if hi is not None:
            schema["maximum"] = hi
        return schema, ""
    if param.type.name in UNITS and (lo is not None or hi is not None):
        schema = {**quantity_schema(param.type.name, signed=lo is None or lo < 0),
                  "description": schema.get("description", "")}  # fmt: skip
        said = range_said(lo, hi, f" {param.type.unit}")
        return schema, f"range {said}, {RANGE_NOT_IN_SCHEMA}"
    return schema, ""


def _option_schema(option: Param) -> dict[str, Any]:
    """A language option: its type (a ``${parameter}`` too, unless the compiler takes it as
    written; never an ``@key``: options are read when the tree is built), range and
    default."""
    schema, note = _value_schema(option)
    if option.type not in STRUCTURAL or option.type is KEY_ITEMS:  # for_each.in: a list one
        schema = {"anyOf": [schema, _PARAMETER]}
    if option.default is not None:
        schema["default"] = option.default
    doc = "; ".join(part for part in (option.doc, note) if part)
    if doc:
        schema["description"] = doc
    return schema


def _option_rules(kind: NodeKind) -> dict[str, Any]:
    """The language table's rules between options (:class:`NodeKind`), as JSON Schema:
    ``exclusive`` (at most one), ``required_if``, ``only_if``; ``refused`` values are left
    out of the option's own schema (:func:`_word_schema`)."""
    rules: list[dict[str, Any]] = [
        {"not": {"required": [a, b]}}
        for i, a in enumerate(kind.exclusive)
        for b in kind.exclusive[i + 1 :]
    ]
    for name, other, value in kind.required_if:
        rules.append({"if": {"properties": {other: {"const": value}}, "required": [other]},
                      "then": {"required": [name]}})  # fmt: skip
    for name, other, value in kind.only_if:
        given = {"anyOf": [{"const": value}, _PARAMETER]}  # a parameter's value is unknown here
        rules.append({"if": {"required": [name]},
                      "then": {"properties": {other: given}, "required": [other]}})  # fmt: skip
    return {"allOf": rules} if rules else {}


def _word_schema(kind: NodeKind) -> dict[str, Any]:
    """What may follow a word of the language, from its :class:`NodeKind`."""
    options = {p.name: _option_schema(p) for p in kind.options}
    for name, bad, _ in kind.refused:  # reactive_sequence's memory: only false (or off, no)
        if isinstance(bad, bool):
            only = [boolean_schema(not bad), _PARAMETER]
            options[name] = {**options[name], "anyOf": only}
    required = [p.name for p in kind.options if p.required]
    rules = _option_rules(kind)
    if kind.shape is Shape.SUBTREE:
        by_id = {"type": "object", "properties": options, "required": required}
        return _either({"type": "object"}, by_id, {"type": "string"})
    if kind.shape is Shape.CHILDREN:
        children = {"type": "array", "items": _NODE, "minItems": 1}
        long_form = {"type": "object", "properties": {"children": children, **options},
                     "required": ["children"], "additionalProperties": False, **rules}  # fmt: skip
        return _either({"type": "array"}, children, long_form)
    long_form = {"type": "object", "properties": {**options, "do": _NODE},
                 "required": ["do", *required], "additionalProperties": False, **rules}  # fmt: skip
    if kind.shape is Shape.CHILD_OR_DO:  # a mapping with do: is the long form (control.py)
        return _either({"type": "object", "required": ["do"]}, long_form, _NODE)
    return long_form


def _param_schema(decl: Declaration) -> dict[str, Any]:
    props: dict[str, Any] = {}
    for p in decl.params:
        schema, note = _value_schema(p)
        described = f"{p.doc} ({p.describe()})".strip() if p.doc else p.describe()
        written = [schema, _PARAMETER, *([_KEY_REF] if decl.takes_blackboard_value(p) else [])]
        props[p.name] = {
            "anyOf": written if schema else [{}],
            "description": f"{described}; {note}" if note else described,
        }
    body: dict[str, Any] = {"type": "object", "properties": props, "additionalProperties": False}
    required = [p.name for p in decl.params if p.required]
    if required:
        body["required"] = required
    # a mapping is the parameters, anything else the short form (leaves.py, _given)
    short: list[dict[str, Any]] = []
    if not required:
        short.append({"type": "null"})
    if decl.primary is not None:
        short.append(props[decl.primary])
    if not short:
        return body
    return _either({"type": "object"}, body, short[0] if len(short) == 1 else {"anyOf": short})


def _named(each: dict[str, Any]) -> dict[str, Any]:
    """A section of declarations by their names (parameters, blackboard keys, subtrees):
    each name snake_case, as ``validate`` checks it, each value ``each``."""
    return {"type": "object", "additionalProperties": each, "propertyNames": _SNAKE_CASE}


def _subtree_schema(parameter: dict[str, Any], key: dict[str, Any]) -> dict[str, Any]:
    """A subtree's definition: its tree, its doc, its parameters and its own blackboard
    keys (declared as the mission's are)."""
    return {
        "type": "object",
        "properties": {
            "parameters": _named(parameter),
            "blackboard": _named(key),
            "tree": _NODE,
            "doc": {"type": "string"},
        },
        "required": ["tree"],
        "additionalProperties": False,
    }


def mission_schema(registry: Registry | None = None) -> dict[str, Any]:
    """The whole schema as a JSON-ready dict."""
    registry = registry or default_registry()
    #: each word's value (what follows ``word:``), by the word
    defs: dict[str, Any] = {}
    docs: dict[str, str] = {}
    bare: list[str] = []
    for kind in WORDS.values():
        defs[kind.word], docs[kind.word] = _word_schema(kind), kind.doc
    # each behaviour by its name alone, unless two plugins declare it (a mission that uses
    # it so is refused), and by its package:name (roomba-bt:drive, roomba-bt-dirt:...)
    alone = [(d.name, d) for d in registry if (registry.clash(d.name) or ("",))[0] != "error"]
    for word, decl in [*alone, *registry.qualified()]:
        defs[word], docs[word] = _param_schema(decl), decl.doc
        if not any(p.required for p in decl.params):
            bare.append(word)
    defs["node"] = _node_schema(docs, bare)
    parameter, key = _declarations()
    return {
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "title": "roomba-bt mission",
        "type": "object",
        "properties": {
            "mission": {"type": "string"},
            "description": {"type": "string"},
            "parameters": _named(parameter),
            "blackboard": _named(key),
            "plugins": {"type": "array", "items": {"type": "string"}},
            "include": {"type": "array", "items": {"type": "string"}},
            "subtrees": _named(_subtree_schema(parameter, key)),
            "tree": _NODE,
            "literal": {"type": "array", "items": {"type": "string"}},
        },
        "additionalProperties": False,
        "$defs": defs,
    }


def _declarations() -> tuple[dict[str, Any], dict[str, Any]]:
    """A parameter declaration and a blackboard key declaration."""
    type_names = [n for n in VALUE_TYPES if n != "mark"]
    fields = {"type": "object", "additionalProperties": {"enum": type_names}}
    # a list's items: a value type, or records as a key's (waypoints: {fields: {...}})
    records = {
        "type": "object",
        "properties": {"fields": fields},
        "required": ["fields"],
        "additionalProperties": False,
    }
    parameter = {
        "type": "object",
        "properties": {
            "type": {"enum": list(PARAMETER_TYPE_NAMES)},
            "default": {},
            "doc": {"type": "string"},
            "choices": {"type": "array", "items": {"type": "string"}},
            "items": {"anyOf": [{"enum": list(LIST_ITEM_TYPES)}, records]},
        },
        "required": ["type"],
        "additionalProperties": False,
        # choices: with enum alone and items: with list alone, each needed there, as
        # validate says (an option another type does not read was silently ignored)
        "allOf": [
            {
                "if": {"properties": {"type": {"const": owner}}},
                "then": {"required": [option]},
                "else": {"not": {"required": [option]}},
            }
            for option, (owner, _) in PARAMETER_TYPE_OPTIONS.items()
        ],
    }
    key = {
        "anyOf": [
            {"enum": [*type_names, "mark"]},
            {
                "type": "object",
                "properties": {
                    "type": {"enum": [*type_names, "mark"]},
                    "fields": fields,
                    "initial": {},
                    "doc": {"type": "string"},
                },
                "additionalProperties": False,
                # a key needs its type (or a record's fields): "needs a type (or fields)"
                "anyOf": [{"required": ["type"]}, {"required": ["fields"]}],
            },
        ]
    }
    return parameter, key
