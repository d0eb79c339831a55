"""Behaviour leaves: a word of the registry with its declared parameters.

``drive: {velocity: 100 mm/s, distance: ${side}}``: each parameter checked against the
behaviour's :class:`~roomba_bt.behaviours.declare.Declaration` (name, type, unit, range,
required), blackboard keys against the declared keys, then the cross-parameter rules.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import yaml

from roomba_bt.behaviours.blackboard import BlackboardRef
from roomba_bt.behaviours.declare import Declaration, Param, key_not_read, key_role
from roomba_bt.behaviours.units import MARK, ValueType, percent_sign_kept
from roomba_bt.mission.diagnostics import Later
from roomba_bt.mission.plan import KeyDecl, Node
from roomba_bt.mission.source import Bad, Loc, mapping
from roomba_bt.mission.values import (
    UNKNOWN,
    Bound,
    Context,
    UnknownNames,
    Written,
    key_written_in,
    parameters_used,
    record_fields,
    resolve,
    said_defaults,
    said_origin,
    substituted,
    unknown,
)
from roomba_bt.printable import shortened


class _UnknownParameters(UnknownNames):
    """``unknown parameter 'home'`` of one leaf, with the parameter the spec calls so where
    one does (``(did you mean 'dock'? the spec's Home LED)``), else the closest name,
    worked out when the error is shown (:class:`UnknownNames`: a leaf may hold thousands)."""

    def __init__(self, decl: Declaration) -> None:
        super().__init__("parameter", [p.name for p in decl.params], decl.name)
        self._spec = {p.spec_name.lower(): p for p in decl.params if p.spec_name}

    def said(self, pname: str) -> tuple[str, Later | None]:
        param = self._spec.get(pname.lower()) if self._spec else None
        if param is None:
            return self(pname)
        hint = f" (did you mean {param.name!r}? {param.spec_name} is the spec's name for it)"
        return unknown("parameter", pname, self.known, hint=hint), None


def parse_leaf(ctx: Context, decl: Declaration, at: Written) -> Node:
    """The leaf, or with every problem recorded in ``ctx`` an ``unbuilt`` node naming
    ``decl`` (:class:`~roomba_bt.mission.plan.Node`)."""
    key_loc, env = at.key_loc, at.env
    given = _given(decl, at.value, at.loc)
    params: dict[str, Any] = {}
    options: dict[str, Any] = {}
    ok = True
    key_typed: dict[str, tuple[yaml.Node, Loc]] = {}
    unknown_parameter: _UnknownParameters | None = None  # made at the first
    for pname, pnode, pkloc, pvloc in given:
        param = decl.param(pname)
        if param is None:
            unknown_parameter = unknown_parameter or _UnknownParameters(decl)
            message, later = unknown_parameter.said(pname)
            ctx.error(pkloc.at(f"{decl.name}: {message}", later))
            ok = False
            continue
        options[f"loc:{pname}"] = pvloc
        if param.type.name == "any":
            key_typed[pname] = (pnode, pvloc)
            continue
        try:
            params[pname] = _value(ctx, (decl, param), (pnode, pvloc), env, options)
        except Bad as bad:
            ctx.report(bad)
            ok = False
    written = {pname: pnode for pname, pnode, _, _ in given}
    for p in decl.params:
        if p.required and not (p.name in params or p.name in key_typed or p.name in written):
            ctx.error(
                key_loc.at(f"{decl.name}: missing required parameter {p.name!r} ({p.describe()})")
            )
            ok = False
    # each value's type, as its text is shown in the leaf's name: a key-typed value's
    # (check's, set's) is its key's, filled in by _key_params
    types = {p.name: p.type for p in decl.params}
    ok = _key_params(ctx, decl, params, (key_typed, types), options, (env, written)) and ok
    known = UNKNOWN not in params.values()
    if ok and decl.constraints is not None and known:
        for problem in decl.constraints(params):
            defaults = said_defaults(written.values(), env, key_loc, problem)
            ctx.error(key_loc.at(f"{decl.name}: {problem}{defaults}"))
            ok = False
    # A value not known (a parameter declared wrongly, a subtree argument that did not
    # resolve: reported there) is unbuilt too: what the leaf sends and the mode it leads to
    # may depend on it (`mode: "${m}"`), and reading them from it was an internal error.
    if not ok or not known:  # kept in its place, unbuilt: the checks still judge around it
        return _unbuilt(decl, key_loc, params, options)
    name = leaf_name(decl, given, env, types, params)
    options = {k: v for k, v in options.items() if not k.startswith("found:")}
    return Node("leaf", key_loc, name, decl=decl, params=params, options=options,
                parameter_in_name=_parameter_in(given))  # fmt: skip


def _value(
    ctx: Context,
    declared: tuple[Declaration, Param],
    written: tuple[yaml.Node, Loc],
    env: Mapping[str, Bound],
    options: dict[str, Any],
) -> Any:
    """The value of a leaf's parameter as written (its node and place), :class:`Bad` when
    wrong. An ``"@${out}"`` names a key of the body that gave the name (the key's scope
    kept in ``options`` as ``scope:PARAMETER``, for that body's use to rename it)."""
    decl, param = declared
    pnode, pvloc = written
    pname = param.name
    keys, written_in = key_written_in(ctx, pnode, env)
    value = resolve(
        ctx, pnode, pvloc, param.type, env, f"{decl.name}.{pname}",
        param=param, allow_ref=decl.takes_blackboard_value(param),
        no_ref=key_not_read(decl, pname) if key_role(decl, pname) else "",
        keys=None if written_in is None else keys,
    )  # fmt: skip
    if written_in is not None and isinstance(value, BlackboardRef):
        options[f"scope:{pname}"] = written_in
    return value


def _unbuilt(
    decl: Declaration, key_loc: Loc, params: dict[str, Any], options: dict[str, Any]
) -> Node:
    """A leaf whose parameters were wrong, kept in its place with the keys it writes where
    they name a declared key (a ``set`` whose value alone is wrong; ``options``, where each
    was found: :func:`_key_params`): the read-before-write check judges the other keys'
    readers in the same pass."""
    writes = {p: params[p] for p in decl.writes_keys if f"found:{p}" in options}
    scopes = {f"scope:{p}": options[f"scope:{p}"] for p in writes if f"scope:{p}" in options}
    return Node("unbuilt", key_loc, decl.name, params=writes, partial=decl, options=scopes)


def _parameter_in(given: list[tuple[str, yaml.Node, Loc, Loc]]) -> Loc | None:
    """Where the first value its name shows is written with a ``${parameter}``
    (``bump(${side})`` is named ``bump(left)``: another value, another name), or None."""
    for _, node, _, value_loc in given:
        if isinstance(node, yaml.ScalarNode) and parameters_used(str(node.value)):
            return value_loc
    return None


def _given(
    decl: Declaration, value: yaml.Node | None, loc: Loc
) -> list[tuple[str, yaml.Node, Loc, Loc]]:
    """``(parameter, value node, key loc, value loc)`` as written: none (``- stop``), a
    mapping, or the short form's scalar (``wait: 2s``)."""
    if value is None or (isinstance(value, yaml.ScalarNode) and value.tag.endswith(":null")):
        return []
    if isinstance(value, yaml.MappingNode):
        return mapping(value, loc, decl.name)
    if decl.primary is not None:
        return [(decl.primary, value, loc, loc)]
    names = ", ".join(p.name for p in decl.params) or "none"
    raise Bad(
        loc.at(
            f"{decl.name} takes parameters as a mapping ({decl.name}: {{...}}); parameters: {names}"
        )
    )


def _key_params(
    ctx: Context,
    decl: Declaration,
    params: dict[str, Any],
    typed_by_key: tuple[dict[str, tuple[yaml.Node, Loc]], dict[str, ValueType]],
    options: dict[str, Any],
    scope: tuple[Mapping[str, Bound], Mapping[str, yaml.Node]],
) -> bool:
    """Parameters that name blackboard keys must name declared keys; ``any`` values take
    the type of the key (``set: {key: leg, value: 2 m}``), written into the types of
    ``typed_by_key`` (the values to type, and every parameter's type). ``scope``: the
    parameters in scope and the values as written (a key given as a subtree's ``${out}``
    names its use, and is a key of the body that gave it: :func:`key_written_in`, marked
    ``scope:PARAMETER`` in ``options`` for that use to rename)."""
    key_typed, types = typed_by_key
    env, written = scope
    ok = True
    key_type: ValueType | None = None
    for pname in (*decl.reads_keys, *decl.writes_keys):
        key = params.get(pname)
        if not isinstance(key, str):
            continue
        where = options.get(f"loc:{pname}")
        assert isinstance(where, Loc)
        said = f"{decl.name}.{pname}{said_origin(written[pname], env)}: "
        keys, written_in = key_written_in(ctx, written[pname], env)
        if written_in is not None:
            options[f"scope:{pname}"] = written_in
        reads = pname in decl.reads_keys
        try:
            found = _key_type(ctx, (key, keys, written_in), where, reads=reads, who=decl.name)
        except LookupError as problem:
            ctx.error(where.at(said + str(problem.args[0])))
            ok = False
            continue
        if key in keys:  # a declared key, not a field: what a leaf left unbuilt writes
            options[f"found:{pname}"] = True
        mismatch = _key_type_problem(decl, pname, key, found)
        if mismatch is not None:
            ctx.error(where.at(said + mismatch))
            ok = False
            continue
        key_type = found
    for pname, (pnode, pvloc) in key_typed.items():
        if key_type is None:
            ok = False
            continue
        types[pname] = key_type
        try:
            params[pname] = resolve(ctx, pnode, pvloc, key_type, env, f"{decl.name}.{pname}")
        except Bad as bad:
            ctx.report(bad)
            ok = False
    return ok


def _key_type_problem(decl: Declaration, pname: str, key: str, found: ValueType) -> str | None:
    """What is wrong with the key ``pname`` names being of type ``found``, or None. A typed
    key parameter (``writes_keys={"key": INT}``; ``mark`` and ``odometry.since`` are typed
    ``mark``) needs a key of its type; a number written as an ``int`` fits a ``float`` key,
    and a ``float`` reader takes an ``int`` key, as ``write_key`` holds them. A type of
    another name is an error, units included: a dirt level (an ``int``) in a ``speed`` key is
    read by a ``drive`` as mm/s, though ``write_key`` takes the number. An untyped one (as
    every plugin's was before) takes any key but a ``mark``, whose value no reader of a
    value can use."""
    wanted = decl.key_type(pname)
    verb = "reads" if pname in decl.reads_keys else "writes"
    if wanted is None or wanted.name == "any":
        if found is not MARK:
            return None
        return (
            f"blackboard key {key!r} is {found.describe()}; {decl.name} needs a key holding a "
            "value (not a mark)"
        )
    written, held_as = (found, wanted) if verb == "reads" else (wanted, found)
    if _shape(written) == _shape(held_as) or (written.name, held_as.name) == ("int", "float"):
        return None
    typed = f"{decl.name} {verb} a value of type {wanted.describe()}"
    if wanted is MARK:
        return f"blackboard key {key!r} is {found.describe()}; {decl.name} needs a key of type mark"
    return (
        f"blackboard key {key!r} is declared {found.describe()}, and {typed} "
        f"(its declaration: {verb}_keys={{{pname!r}: {wanted.name.upper()}}}): declare "
        f"{key!r} with type {wanted.name}, or name a key of that type"
    )


def _shape(vtype: ValueType) -> tuple[Any, ...]:
    """What makes two types one: name, unit, an enum's words, a record's fields (an enum
    made twice is two objects of one type)."""
    fields = tuple((name, _shape(each)) for name, each in vtype.fields)
    return vtype.name, vtype.unit, vtype.choices, fields


def _key_type(
    ctx: Context,
    named: tuple[str, Mapping[str, KeyDecl], object],
    where: Loc,
    *,
    reads: bool,
    who: str,
) -> ValueType:
    """The type of the blackboard value ``key`` names among ``keys`` (``named``, with the
    scope it was written in, None: this body's): a declared key, or, read (``check: {key:
    wp.distance}``), a field of a record key, as ``@wp.distance`` reads one (py_trees' own
    ``key.attribute``); ``check`` refused it as an unknown key. LookupError says what is
    wrong and what is allowed: a field is never written alone (``set`` writes the whole
    record)."""
    key, keys, scope = named
    found = keys.get(key)
    if found is not None:
        return found.type
    name, dot, field = key.partition(".")
    record = keys.get(name) if dot else None
    if record is None:
        raise LookupError(ctx.unknown_key(key, where, None if scope is None else keys))
    fields = record_fields(record.type)
    if fields is None:
        raise LookupError(
            f"blackboard key {name!r} is {record.type.describe()}, not a record: only a "
            f"record's field is read as KEY.FIELD; here write {name!r}"
        )
    if not reads:
        raise LookupError(
            f"{key!r} is a field of record key {name!r}, and {who} writes a whole key: a "
            f"field is read (check, @{key}), never written alone; write {name!r} with every "
            f"field ({', '.join(fields)})"
        )
    if field not in fields:
        raise LookupError(f"record key {name!r}: " + unknown("field", field, list(fields)))
    return fields[field]


def leaf_name(
    decl: Declaration,
    given: list[tuple[str, yaml.Node, Loc, Loc]],
    env: Mapping[str, Bound],
    types: Mapping[str, ValueType],
    params: Mapping[str, Any],
) -> str:
    """``drive(velocity=100 mm/s, radius=-500 mm)``: what ``show`` prints for a leaf, and
    its name in the run's tree, the log, the outcome, a record and the monitor, with
    ``${parameters}`` shown as their values; a value of a percent (``types``: each
    parameter's, a key-typed one's its key's) written as a bare zero is ``0%``, as a
    parameter's is.

    One name for one meaning, however the file wrote it: the parameters in the order the
    declaration gives them (not the file's), and the primary one alone in the short form
    (``turn: {angle: 45deg}`` is ``turn(45deg)``, as ``turn: 45deg``, not
    ``turn(angle=45deg)``). A parameter that declares which way each sign goes
    (:attr:`Param.signs`) says it after the value (``params``, the values read): ``turn(
    -45deg right)``, ``turn(90deg left)``, so a negative angle reads without the convention
    at hand."""
    if not given:
        return decl.name
    place = {p.name: i for i, p in enumerate(decl.params)}
    written = sorted(given, key=lambda g: place.get(g[0], len(place)))
    short = len(written) == 1 and written[0][0] == decl.primary
    parts = []
    for pname, node, _, _ in written:
        text = written_text(node, env)
        if pname in types:
            text = percent_sign_kept(types[pname], text)
        if not short:  # check's op, "==", was op===: a text holding = or , is quoted, and <
            # or > with it, so that every op reads alike (op="<" as op="<="; op=> an arrow)
            text = f"{pname}={_quoted(text) if any(c in text for c in '=,<>') else text}"
        parts.append(text + _sign_said(decl.param(pname), params.get(pname)))
    return f"{decl.name}({', '.join(parts)})"


def _sign_said(param: Param | None, value: object) -> str:
    """`` left`` or `` right`` after a value whose parameter says which way each sign goes
    (:attr:`Param.signs`); nothing for zero, for a value read at run time (``@key``), or for
    a parameter whose sign says enough."""
    if param is None or not param.signs or isinstance(value, bool):
        return ""
    if not isinstance(value, int | float) or value == 0:
        return ""
    return " " + (param.signs[0] if value > 0 else param.signs[1])


def _quoted(text: str) -> str:
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"') + '"'


def written_text(node: yaml.Node, env: Mapping[str, Bound], *, lists: bool = False) -> str:
    """A value as the file writes it, each ``${parameter}`` as its value's own text: what
    ``show`` prints for a leaf's parameter and a decorator's option. A list of scalars
    (``for_each.in``) is written out when ``lists``; anything else longer is ``...``."""

    def value_of(name: str) -> str | None:
        bound = env.get(name)
        return bound.text if bound is not None and bound.value is not UNKNOWN else None

    if isinstance(node, yaml.ScalarNode):
        return substituted(str(node.value), value_of)
    if lists and isinstance(node, yaml.SequenceNode):  # each item, records too: the waypoints
        items = [shortened(_item_text(item, env)) for item in node.value[:LISTED_ITEMS]]
        more = len(node.value) - LISTED_ITEMS
        return f"[{', '.join([*items, *([f'... and {more} more'] if more > 0 else [])])}]"
    return "..."


#: how many items of a list ``show`` writes out (``for_each(key=wp, in=[...])``): a
#: reviewer reads the route, and a generated list of thousands stays one line
LISTED_ITEMS = 8


def _item_text(node: yaml.Node, env: Mapping[str, Bound]) -> str:
    """A list item as the file writes it: a scalar, or a record's fields (``{distance:
    80cm, turn: 90deg}``: a ``for_each`` over waypoints showed ``in=...``)."""
    if isinstance(node, yaml.MappingNode):
        fields = (f"{key.value}: {written_text(value, env)}" for key, value in node.value)
        return "{" + ", ".join(fields) + "}"
    return written_text(node, env)
