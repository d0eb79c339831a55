"""YAML mission -> checked tree (:class:`~roomba_bt.mission.ir.Node`), every error collected.

A mission file::

    mission: square                      # name (default: the file name)
    description: drive a square
    parameters:                          # settable with -p side=50cm
      side: {type: distance, default: 1 m}
    blackboard:                          # declared keys, with types
      leg: distance
    plugins: [./my_behaviour.py]         # behaviour modules by path
    include: [lib/common.yaml]           # subtrees (and keys) of other files
    subtrees:
      back_off:
        parameters: {speed: {type: speed, default: 100 mm/s}}
        tree: {drive: {velocity: -${speed}, distance: 10cm}}
    tree:
      sequence:
        - mode: safe
        - drive: {distance: ${side}}

The parser never stops at the first error: each problem becomes a
:class:`~roomba_bt.mission.diagnostics.Diagnostic` and parsing goes on with the next node.
``docs/missions.md`` documents every word.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from roomba_bt.behaviours.declare import BlackboardRef, Declaration, Param
from roomba_bt.behaviours.registry import Registry
from roomba_bt.behaviours.units import (
    BOOL,
    CANONICAL,
    DURATION,
    INT,
    MARK,
    STR,
    VALUE_TYPES,
    UnitError,
    ValueType,
    closest,
    compatible,
    convert,
    enum,
    format_quantity,
)
from roomba_bt.mission.diagnostics import Diagnostic
from roomba_bt.mission.ir import (
    COMPOSITES,
    DECORATORS,
    LANGUAGE_WORDS,
    MODIFIERS,
    SIMPLE_DECORATORS,
    KeyDecl,
    Node,
)
from roomba_bt.mission.source import (
    Bad,
    Loc,
    compose,
    kind_of,
    loc_of,
    mapping,
    plain,
    scalar_text,
    sequence,
)

TOP_LEVEL = ("mission", "description", "parameters", "blackboard", "plugins", "include",
             "subtrees", "tree")  # fmt: skip
_SUBSTITUTION = re.compile(r"\$\{([A-Za-z_][A-Za-z0-9_]*)\}")
_FULL_SUBSTITUTION = re.compile(r"^\s*(-?)\$\{([A-Za-z_][A-Za-z0-9_]*)\}\s*$")
_REF = re.compile(r"^@([a-z_][a-z0-9_]*)(?:\.([a-z_][a-z0-9_]*))?$")
_IDENT = re.compile(r"^[a-z_][a-z0-9_]*$")


_PARAM_TYPES = [n for n in VALUE_TYPES if n != "mark"]


def unknown(what: str, name: str, known: list[str]) -> str:
    """``unknown parameter 'velocty' (did you mean 'velocity'?); known: ...``"""
    listing = ", ".join(known) if known else "none"
    return f"unknown {what} {name!r}{closest(name, known)}; known: {listing}"


class _Unknown:
    """The value of a subtree parameter with no default, when an unused subtree is checked."""

    def __repr__(self) -> str:
        return "<unknown>"


UNKNOWN: Any = _Unknown()


@dataclass(frozen=True, slots=True)
class Bound:
    """A parameter in scope: its type, canonical value and the text it was written as."""

    type: ValueType
    value: Any
    text: str


@dataclass(slots=True)
class SubtreeDef:
    name: str
    loc: Loc
    params: dict[str, tuple[ValueType, Any, Loc]]  # name -> (type, default or None, loc)
    body: yaml.Node | None
    body_loc: Loc
    used: bool = False


@dataclass
class Context:
    """Everything one compilation shares."""

    registry: Registry
    diagnostics: list[Diagnostic] = field(default_factory=list)
    keys: dict[str, KeyDecl] = field(default_factory=dict)
    subtrees: dict[str, SubtreeDef] = field(default_factory=dict)

    def error(self, diagnostic: Diagnostic) -> None:
        if diagnostic not in self.diagnostics:
            self.diagnostics.append(diagnostic)


@dataclass
class ParsedFile:
    name: str
    description: str
    params: dict[str, Bound]
    tree: Node | None
    tree_loc: Loc | None
    root_loc: Loc


# ============================================================================ values


def parse_type_name(node: yaml.Node, loc: Loc, *, allow_mark: bool = False) -> ValueType:
    text = scalar_text(node, loc, "type")
    vtype = VALUE_TYPES.get(text)
    if vtype is None or (vtype is MARK and not allow_mark):
        names = [n for n in VALUE_TYPES if allow_mark or n != "mark"]
        raise Bad(
            loc.at(f"unknown type {text!r}{closest(text, names)}; known types: {', '.join(names)}")
        )
    return vtype


def record_type(fields: dict[str, ValueType]) -> ValueType:
    """A mapping with typed fields: a waypoint ``{distance: 1 m, turn: 90deg}``."""

    def parse(value: object) -> dict[str, Any]:
        if not isinstance(value, dict):
            raise UnitError(f"expected a mapping with {', '.join(fields)}")
        unknown = [k for k in value if k not in fields]
        if unknown:
            raise UnitError(
                f"unknown field {unknown[0]!r}{closest(str(unknown[0]), list(fields))}; "
                f"fields: {', '.join(fields)}"
            )
        missing = [k for k in fields if k not in value]
        if missing:
            raise UnitError(f"missing field {missing[0]!r}")
        out = {}
        for k, t in fields.items():
            try:
                out[k] = t.parse(value[k])
            except UnitError as exc:
                raise UnitError(f"field {k}: {exc}") from None
        return out

    return ValueType(
        "record", parse, json_schema=(("type", "object"),), fields=tuple(fields.items())
    )


def record_fields(vtype: ValueType) -> dict[str, ValueType] | None:
    return dict(vtype.fields) if vtype.name == "record" else None


def _negate(value: Any) -> Any:
    if isinstance(value, int | float) and not isinstance(value, bool):
        return -value
    raise UnitError("only a number can be negated")


def resolve(
    ctx: Context,
    node: yaml.Node,
    loc: Loc,
    vtype: ValueType,
    env: Mapping[str, Bound],
    what: str,
    *,
    param: Param | None = None,
    allow_ref: bool = False,
) -> Any:
    """One value of type ``vtype``: ``${param}`` substituted, ``@key`` resolved to a
    :class:`BlackboardRef` (where allowed), units parsed, range checked. Raises :class:`Bad`."""
    fields = record_fields(vtype)
    if fields is not None and isinstance(node, yaml.MappingNode):
        given = {k: (v, vl) for k, v, _, vl in mapping(node, loc, what)}
        unknown_fields = [k for k in given if k not in fields]
        if unknown_fields:
            name = unknown_fields[0]
            raise Bad(loc.at(f"{what}: " + unknown("field", name, list(fields))))
        missing = [k for k in fields if k not in given]
        if missing:
            raise Bad(loc.at(f"{what}: missing field {missing[0]!r}"))
        return {
            k: resolve(ctx, given[k][0], given[k][1], t, env, f"{what}.{k}")
            for k, t in fields.items()
        }
    raw = plain(node, loc)
    if isinstance(raw, str):
        full = _FULL_SUBSTITUTION.match(raw)
        if full is not None:
            negative, pname = full.groups()
            bound = env.get(pname)
            if bound is None:
                raise Bad(
                    loc.at(f"{what}: unknown parameter ${{{pname}}}{closest(pname, list(env))}")
                )
            if bound.value is UNKNOWN:
                return UNKNOWN
            if compatible(bound.type, vtype):
                value = convert(bound.type, vtype, bound.value)
                if negative:
                    try:
                        value = _negate(value)
                    except UnitError as exc:
                        raise Bad(loc.at(f"{what}: {exc}")) from None
                return _check_range(value, loc, what, param)
            if bound.type.name != "str":
                raise Bad(
                    loc.at(
                        f"{what}: parameter ${{{pname}}} is a {bound.type.describe()}, "
                        f"but {what} needs {vtype.describe()}"
                    )
                )
            raw = ("-" if negative else "") + str(bound.value)
        elif "${" in raw:

            def substitute(match: re.Match[str]) -> str:
                bound = env.get(match.group(1))
                if bound is None:
                    name = match.group(1)
                    raise Bad(
                        loc.at(f"{what}: unknown parameter ${{{name}}}{closest(name, list(env))}")
                    )
                return bound.text

            names = _SUBSTITUTION.findall(raw)
            raw = _SUBSTITUTION.sub(substitute, raw)
            if any(env[name].value is UNKNOWN for name in names):
                return UNKNOWN
        if raw.startswith("@"):
            if not allow_ref:
                raise Bad(loc.at(f"{what}: a blackboard value (@key) is not allowed here"))
            return _reference(ctx, raw, loc, vtype, what)
    try:
        value = vtype.parse(raw)
    except UnitError as exc:
        raise Bad(loc.at(f"{what}: {exc}")) from None
    return _check_range(value, loc, what, param)


def _check_range(value: Any, loc: Loc, what: str, param: Param | None) -> Any:
    if param is not None:
        problem = param.check_range(value)
        if problem is not None:
            owner = what.rsplit(".", 1)[0] if "." in what else what
            raise Bad(loc.at(f"{owner}: {problem}"))
    return value


def _reference(ctx: Context, raw: str, loc: Loc, vtype: ValueType, what: str) -> BlackboardRef:
    match = _REF.match(raw)
    if match is None:
        raise Bad(loc.at(f"{what}: {raw!r} is not a blackboard reference (@key or @key.field)"))
    key, fname = match.groups()
    decl = ctx.keys.get(key)
    if decl is None:
        raise Bad(loc.at(f"{what}: unknown blackboard key {key!r}{closest(key, list(ctx.keys))}"))
    ktype = decl.type
    if fname is not None:
        fields = record_fields(ktype)
        if fields is None or fname not in fields:
            known = ", ".join(fields) if fields else "none: it is not a record"
            raise Bad(
                loc.at(f"{what}: blackboard key {key!r} has no field {fname!r} (fields: {known})")
            )
        ktype = fields[fname]
    if not compatible(ktype, vtype):
        raise Bad(
            loc.at(
                f"{what}: blackboard key {str(BlackboardRef(key, fname))[1:]!r} holds "
                f"{ktype.describe()}, but {what} needs {vtype.describe()}"
            )
        )
    return BlackboardRef(key, fname)


# ============================================================================ files


class Compiler:
    """Parses one mission file (and its includes) into a checked :class:`Node` tree."""

    def __init__(self, ctx: Context, display: Any = None) -> None:
        self.ctx = ctx
        self.display = display or (lambda p: str(p))
        self._include_stack: list[Path] = []
        self._use_stack: list[str] = []
        self.global_env: dict[str, Bound] = {}

    # ---------------------------------------------------------------- top level
    def compile_file(
        self, path: Path, overrides: Mapping[str, str], *, require_tree: bool = True
    ) -> ParsedFile | None:
        display = self.display(path)
        root, errors = compose(path, display)
        for e in errors:
            self.ctx.error(e)
        if root is None:
            return None
        root_loc = loc_of(root, display, "")
        try:
            items = mapping(root, root_loc, "a mission file")
        except Bad as bad:
            self.ctx.error(bad.diagnostic)
            return None
        self._include_stack.append(path.resolve())
        sections = {k: (v, kl, vl) for k, v, kl, vl in items}
        for key, _, key_loc, _ in items:
            if key not in TOP_LEVEL:
                self.ctx.error(
                    key_loc.at(
                        f"unknown top-level key {key!r}{closest(key, TOP_LEVEL)}; "
                        f"known: {', '.join(TOP_LEVEL)}"
                    )
                )
        self._file_sections(path, sections)
        name = path.stem
        description = ""
        for key in ("mission", "description"):
            if key in sections:
                node, _, vloc = sections[key]
                try:
                    text = scalar_text(node, vloc, key)
                except Bad as bad:
                    self.ctx.error(bad.diagnostic)
                    continue
                if key == "mission":
                    name = text
                else:
                    description = text
        params = self._parameters(sections.get("parameters"), overrides, root_loc)
        self.global_env = params
        description = _SUBSTITUTION.sub(
            lambda m: params[m.group(1)].text if m.group(1) in params else m.group(0), description
        )
        tree: Node | None = None
        tree_loc: Loc | None = None
        if "tree" in sections:
            node, _, vloc = sections["tree"]
            tree_loc = vloc
            tree = self.node(node, vloc, params)
        elif require_tree:
            self.ctx.error(root_loc.at("a mission needs a tree: (the root node); found none"))
        self._check_unused_subtrees()
        self._include_stack.pop()
        return ParsedFile(name, description, params, tree, tree_loc, root_loc)

    def _file_sections(self, path: Path, sections: dict[str, tuple[yaml.Node, Loc, Loc]]) -> None:
        """plugins, include, blackboard, subtrees: what an included file contributes too."""
        if "plugins" in sections:
            self._plugins(path, *sections["plugins"][::2])
        if "include" in sections:
            self._includes(path, *sections["include"][::2])
        if "blackboard" in sections:
            self._blackboard(*sections["blackboard"][::2])
        if "subtrees" in sections:
            self._subtrees(*sections["subtrees"][::2])

    def _plugins(self, path: Path, node: yaml.Node, loc: Loc) -> None:
        try:
            entries = sequence(node, loc, "plugins")
        except Bad as bad:
            self.ctx.error(bad.diagnostic)
            return
        for item, iloc in entries:
            try:
                text = scalar_text(item, iloc, "a plugin")
            except Bad as bad:
                self.ctx.error(bad.diagnostic)
                continue
            target = (path.parent / text).resolve()
            if not target.is_file():
                self.ctx.error(
                    iloc.at(
                        f"plugin file {text!r} not found (paths are relative to the file naming it)"
                    )
                )
                continue
            registry, error = self.ctx.registry.with_file(target)
            if error is not None:
                self.ctx.error(iloc.at(str(error)))
            self.ctx.registry = registry

    def _includes(self, path: Path, node: yaml.Node, loc: Loc) -> None:
        try:
            entries = sequence(node, loc, "include")
        except Bad as bad:
            self.ctx.error(bad.diagnostic)
            return
        for item, iloc in entries:
            try:
                text = scalar_text(item, iloc, "an include")
            except Bad as bad:
                self.ctx.error(bad.diagnostic)
                continue
            target = (path.parent / text).resolve()
            if target in self._include_stack:
                chain = [p.name for p in self._include_stack[self._include_stack.index(target) :]]
                self.ctx.error(iloc.at(f"include cycle: {' -> '.join([*chain, target.name])}"))
                continue
            if not target.is_file():
                self.ctx.error(
                    iloc.at(
                        f"included file {text!r} not found"
                        " (paths are relative to the including file)"
                    )
                )
                continue
            self._include(target, iloc)

    def _include(self, target: Path, iloc: Loc) -> None:
        display = self.display(target)
        root, errors = compose(target, display)
        for e in errors:
            self.ctx.error(e)
        if root is None:
            return
        root_loc = loc_of(root, display, "")
        try:
            items = mapping(root, root_loc, "an included file")
        except Bad as bad:
            self.ctx.error(bad.diagnostic)
            return
        allowed = ("description", "plugins", "include", "blackboard", "subtrees")
        for key, _, key_loc, _ in items:
            if key not in allowed:
                self.ctx.error(
                    key_loc.at(
                        f"an included file may only hold {', '.join(allowed)}; found {key!r}"
                    )
                )
        self._include_stack.append(target)
        self._file_sections(target, {k: (v, kl, vl) for k, v, kl, vl in items})
        self._include_stack.pop()

    def _parameters(
        self, section: tuple[yaml.Node, Loc, Loc] | None, overrides: Mapping[str, str], root: Loc
    ) -> dict[str, Bound]:
        env: dict[str, Bound] = {}
        declared: dict[str, tuple[ValueType, Loc]] = {}
        if section is not None:
            node, _, loc = section
            try:
                items = mapping(node, loc, "parameters")
            except Bad as bad:
                self.ctx.error(bad.diagnostic)
                items = []
            for name, value, key_loc, vloc in items:
                try:
                    vtype, default, has_default, _ = self._param_decl(value, vloc, name)
                except Bad as bad:
                    self.ctx.error(bad.diagnostic)
                    continue
                declared[name] = (vtype, key_loc)
                if name in overrides:
                    continue
                if not has_default:
                    self.ctx.error(
                        key_loc.at(
                            f"parameter {name!r} has no default: give it with -p {name}=VALUE"
                        )
                    )
                    env[name] = Bound(vtype, UNKNOWN, "?")  # reported once, not at every use
                    continue
                env[name] = Bound(vtype, default, _text(value, vloc, default))
        for name, text in overrides.items():
            if name not in declared:
                self.ctx.error(
                    root.at(
                        f"unknown parameter {name!r} given with -p{closest(name, list(declared))}; "
                        f"the mission declares: {', '.join(declared) or 'none'}"
                    )
                )
                continue
            vtype, key_loc = declared[name]
            try:
                value = vtype.parse(_cli_value(text, vtype))
            except UnitError as exc:
                self.ctx.error(key_loc.at(f"parameter {name}={text} (from -p): {exc}"))
                env[name] = Bound(vtype, UNKNOWN, "?")  # reported once, not at every use
                continue
            env[name] = Bound(vtype, value, text)
        return env

    def _param_decl(self, node: yaml.Node, loc: Loc, name: str) -> tuple[ValueType, Any, bool, str]:
        if not _IDENT.match(name):
            raise Bad(loc.at(f"parameter name {name!r} must be snake_case"))
        fields = {k: (v, kl, vl) for k, v, kl, vl in mapping(node, loc, f"parameter {name!r}")}
        for key, (_, kl, _) in fields.items():
            if key not in ("type", "default", "doc", "choices"):
                raise Bad(
                    kl.at(
                        unknown(
                            f"key in parameter {name!r}", key, ["type", "default", "doc", "choices"]
                        )
                    )
                )
        if "type" not in fields:
            raise Bad(loc.at(f"parameter {name!r} needs a type (one of {', '.join(_PARAM_TYPES)})"))
        tnode, _, tloc = fields["type"]
        if plain(tnode, tloc) == "enum":
            if "choices" not in fields:
                raise Bad(tloc.at(f"parameter {name!r} of type enum needs choices: [...]"))
            cnode, _, cloc = fields["choices"]
            choices = plain(cnode, cloc)
            if not isinstance(choices, list) or not all(isinstance(c, str) for c in choices):
                raise Bad(cloc.at("choices must be a list of words"))
            vtype = enum(*choices)
        else:
            vtype = parse_type_name(tnode, tloc)
        doc = ""
        if "doc" in fields:
            doc = scalar_text(fields["doc"][0], fields["doc"][2], "doc")
        if "default" not in fields:
            return vtype, None, False, doc
        dnode, _, dloc = fields["default"]
        default = resolve(self.ctx, dnode, dloc, vtype, {}, f"parameter {name}")
        return vtype, default, True, doc

    def _blackboard(self, node: yaml.Node, loc: Loc) -> None:
        try:
            items = mapping(node, loc, "blackboard")
        except Bad as bad:
            self.ctx.error(bad.diagnostic)
            return
        for name, value, key_loc, vloc in items:
            try:
                self._key_decl(name, value, key_loc, vloc)
            except Bad as bad:
                self.ctx.error(bad.diagnostic)

    def _key_decl(self, name: str, node: yaml.Node, key_loc: Loc, loc: Loc) -> None:
        if not _IDENT.match(name):
            raise Bad(key_loc.at(f"blackboard key {name!r} must be snake_case"))
        if name in self.ctx.keys:
            first = self.ctx.keys[name].loc
            raise Bad(
                key_loc.at(
                    f"blackboard key {name!r} declared twice (first at {first.file}:{first.line})"
                )
            )
        initial: Any = None
        has_initial = False
        doc = ""
        if isinstance(node, yaml.ScalarNode):
            vtype = parse_type_name(node, loc, allow_mark=True)
        else:
            fields = {
                k: (v, kl, vl) for k, v, kl, vl in mapping(node, loc, f"blackboard key {name!r}")
            }
            for key, (_, kl, _) in fields.items():
                if key not in ("type", "fields", "initial", "doc"):
                    raise Bad(
                        kl.at(
                            unknown(
                                f"key in blackboard key {name!r}",
                                key,
                                ["type", "fields", "initial", "doc"],
                            )
                        )
                    )
            if "fields" in fields:
                fnode, _, floc = fields["fields"]
                ftypes = {
                    fname: parse_type_name(fvalue, fvloc)
                    for fname, fvalue, _, fvloc in mapping(fnode, floc, "fields")
                }
                vtype = record_type(ftypes)
            elif "type" in fields:
                vtype = parse_type_name(fields["type"][0], fields["type"][2], allow_mark=True)
            else:
                raise Bad(loc.at(f"blackboard key {name!r} needs a type (or fields)"))
            if "initial" in fields:
                inode, _, iloc = fields["initial"]
                initial = resolve(
                    self.ctx, inode, iloc, vtype, self.global_env, f"initial value of {name}"
                )
                has_initial = True
            if "doc" in fields:
                doc = scalar_text(fields["doc"][0], fields["doc"][2], "doc")
        self.ctx.keys[name] = KeyDecl(name, vtype, key_loc, initial, has_initial, doc)

    def _subtrees(self, node: yaml.Node, loc: Loc) -> None:
        try:
            items = mapping(node, loc, "subtrees")
        except Bad as bad:
            self.ctx.error(bad.diagnostic)
            return
        for name, value, key_loc, vloc in items:
            try:
                self._subtree_def(name, value, key_loc, vloc)
            except Bad as bad:
                self.ctx.error(bad.diagnostic)

    def _subtree_def(self, name: str, node: yaml.Node, key_loc: Loc, loc: Loc) -> None:
        if not _IDENT.match(name):
            raise Bad(key_loc.at(f"subtree name {name!r} must be snake_case"))
        if name in self.ctx.subtrees:
            first = self.ctx.subtrees[name].loc
            raise Bad(
                key_loc.at(f"subtree {name!r} defined twice (first at {first.file}:{first.line})")
            )
        if name in LANGUAGE_WORDS or name in self.ctx.registry:
            raise Bad(key_loc.at(f"subtree name {name!r} is already a node name"))
        fields = {k: (v, kl, vl) for k, v, kl, vl in mapping(node, loc, f"subtree {name!r}")}
        for key, (_, kl, _) in fields.items():
            if key not in ("parameters", "tree", "doc"):
                raise Bad(
                    kl.at(unknown(f"key in subtree {name!r}", key, ["parameters", "tree", "doc"]))
                )
        params: dict[str, tuple[ValueType, Any, Loc]] = {}
        if "parameters" in fields:
            pnode, _, ploc = fields["parameters"]
            for pname, pvalue, pkloc, pvloc in mapping(pnode, ploc, "parameters"):
                try:
                    vtype, default, has_default, _ = self._param_decl(pvalue, pvloc, pname)
                except Bad as bad:
                    self.ctx.error(bad.diagnostic)
                    continue
                params[pname] = (vtype, default if has_default else None, pkloc)
        if "tree" not in fields:
            self.ctx.error(loc.at(f"subtree {name!r} needs a tree:"))
            body, body_loc = None, loc
        else:
            body, _, body_loc = fields["tree"]
        self.ctx.subtrees[name] = SubtreeDef(name, key_loc, params, body, body_loc)

    def _check_unused_subtrees(self) -> None:
        """Check subtrees no tree uses (library files), with unknown values for parameters
        that have no default, so their errors are found before someone uses them."""
        for sub in list(self.ctx.subtrees.values()):
            if sub.used or sub.body is None:
                continue
            sub.used = True
            env = dict(self.global_env)
            for pname, (vtype, default, _) in sub.params.items():
                env[pname] = Bound(vtype, UNKNOWN if default is None else default, "?")
            self._use_stack.append(sub.name)
            self.node(sub.body, sub.body_loc, env)
            self._use_stack.pop()

    # ---------------------------------------------------------------- nodes
    def node(self, ynode: yaml.Node, loc: Loc, env: Mapping[str, Bound]) -> Node | None:
        """Parse one node; errors are recorded and None returned for a node that cannot be
        built (its parent goes on with the other children)."""
        try:
            return self._node(ynode, loc, env)
        except Bad as bad:
            self.ctx.error(bad.diagnostic)
            return None

    def _node(self, ynode: yaml.Node, loc: Loc, env: Mapping[str, Bound]) -> Node | None:
        if isinstance(ynode, yaml.ScalarNode):
            word = plain(ynode, loc)
            if not isinstance(word, str):
                raise Bad(loc.at(f"expected a node, got {kind_of(ynode)}"))
            return self._word(word, None, loc, loc.child(ynode, word), loc, env)
        if not isinstance(ynode, yaml.MappingNode):
            raise Bad(
                loc.at(f"expected a node (a mapping such as drive: {{...}}), got {kind_of(ynode)}")
            )
        items = mapping(ynode, loc, "a node")
        words = [(k, v, kl, vl) for k, v, kl, vl in items if k not in MODIFIERS]
        mods = {k: (v, kl, vl) for k, v, kl, vl in items if k in MODIFIERS}
        if not words:
            raise Bad(
                loc.at(
                    f"a node needs a kind (such as sequence, drive, bump); found only "
                    f"{', '.join(mods)}"
                )
            )
        if len(words) > 1:
            names = [w[0] for w in words]
            known = [n for n in names if n in LANGUAGE_WORDS or n in self.ctx.registry]
            if len(known) == 1:
                other = next(w for w in words if w[0] not in known)
                raise Bad(other[2].at(self._unknown_word(other[0], f" next to {known[0]!r}")))
            raise Bad(
                words[1][2].at(
                    f"a node has exactly one kind; found {', '.join(names)} "
                    "(put several nodes in a sequence)"
                )
            )
        word, value, key_loc, value_loc = words[0]
        built = self._word(word, value, key_loc, value_loc, loc, env)
        if built is None:
            return None
        if "name" in mods:
            built.name = scalar_text(mods["name"][0], mods["name"][2], "name")
        for guard in ("until", "while"):
            if guard in mods:
                gnode, gkloc, gvloc = mods[guard]
                condition = self.node(gnode, gvloc, env)
                if condition is None:
                    continue
                self._check_guard(condition, guard)
                built = Node("guard", gkloc, f"{guard} {condition.name}", [condition, built],
                             options={"until": guard == "until"})  # fmt: skip
        return built

    def _unknown_word(self, word: str, where: str = "") -> str:
        names = [*LANGUAGE_WORDS, *self.ctx.registry.names(), *MODIFIERS]
        message = f"unknown node {word!r}{where}{closest(word, names)}"
        if self.ctx.registry.errors:
            failed = "; ".join(str(e) for e in self.ctx.registry.errors)
            message += f" (note: {failed})"
        return message

    def _check_guard(self, condition: Node, guard: str) -> None:
        for n in condition.walk():
            if n.decl is not None and n.decl.kind == "action":
                self.ctx.error(
                    n.loc.at(
                        f"{guard}: a guard is made of conditions; {n.decl.name!r} is an action"
                    )
                )

    def _word(
        self,
        word: str,
        value: yaml.Node | None,
        key_loc: Loc,
        value_loc: Loc,
        node_loc: Loc,
        env: Mapping[str, Bound],
    ) -> Node | None:
        if word in COMPOSITES:
            return self._composite(word, value, key_loc, value_loc, env)
        if word in SIMPLE_DECORATORS or word in DECORATORS:
            return self._decorator(word, value, key_loc, value_loc, env)
        if word == "subtree":
            return self._use_subtree(value, key_loc, value_loc, env)
        decl = self.ctx.registry.get(word)
        if decl is None:
            raise Bad(key_loc.at(self._unknown_word(word)))
        return self._leaf(decl, value, key_loc, value_loc, env)

    # ---------------------------------------------------------------- composites
    def _composite(
        self, word: str, value: yaml.Node | None, key_loc: Loc, loc: Loc, env: Mapping[str, Bound]
    ) -> Node | None:
        options: dict[str, Any] = {"memory": COMPOSITES[word][1]}
        children_node: yaml.Node | None = value
        children_loc = loc
        if isinstance(value, yaml.MappingNode):
            allowed = ["children", "memory", "name"] + (
                ["policy", "synchronise", "selected"] if word == "parallel" else []
            )
            fields = {}
            for k, v, kl, vl in mapping(value, loc, word):
                if k not in allowed:
                    self.ctx.error(kl.at(f"{word}: " + unknown("option", k, allowed)))
                    continue
                fields[k] = (v, vl)
            if "name" in fields:
                options["name"] = scalar_text(fields["name"][0], fields["name"][1], "name")
            if "memory" in fields:
                options["memory"] = resolve(
                    self.ctx, *fields["memory"], BOOL, env, f"{word}.memory"
                )
            if word == "parallel":
                policy_type = enum("all", "one", "selected")
                options["policy"] = (
                    resolve(self.ctx, *fields["policy"], policy_type, env, "parallel.policy")
                    if "policy" in fields else "all"
                )  # fmt: skip
                options["synchronise"] = (
                    resolve(self.ctx, *fields["synchronise"], BOOL, env, "parallel.synchronise")
                    if "synchronise" in fields else True
                )  # fmt: skip
                if "selected" in fields:
                    selected = plain(*fields["selected"])
                    if not isinstance(selected, list) or not all(
                        isinstance(s, str) for s in selected
                    ):
                        raise Bad(
                            fields["selected"][1].at(
                                "parallel.selected must be a list of child names"
                            )
                        )
                    options["selected"] = selected
                    options["selected_loc"] = fields["selected"][1]
                elif options["policy"] == "selected":
                    raise Bad(
                        key_loc.at("parallel with policy selected needs selected: [child names]")
                    )
            if "children" not in fields:
                raise Bad(key_loc.at(f"{word} needs children: [...]"))
            children_node, children_loc = fields["children"]
        elif word == "parallel":
            options["policy"], options["synchronise"] = "all", True
        if children_node is None or (
            isinstance(children_node, yaml.ScalarNode) and children_node.tag.endswith(":null")
        ):
            raise Bad(key_loc.at(f"{word} needs at least one child; it has none"))
        if not isinstance(children_node, yaml.SequenceNode):
            raise Bad(
                children_loc.at(f"{word} takes a list of children, got {kind_of(children_node)}")
            )
        children = []
        entries = sequence(children_node, children_loc, f"{word} children")
        if not entries:
            raise Bad(key_loc.at(f"{word} needs at least one child; it has none"))
        for child_node, child_loc in entries:
            child = self.node(child_node, child_loc, env)
            if child is not None:
                children.append(child)
        result = Node(word, key_loc, options.pop("name", word), children, options=options)
        if word == "parallel" and "selected" in options:
            names = [c.name for c in children]
            for sel in options["selected"]:
                if sel not in names:
                    self.ctx.error(
                        options["selected_loc"].at(
                            "parallel.selected: " + unknown("child name", sel, names)
                        )
                    )
        return result

    # ---------------------------------------------------------------- decorators
    def _decorator(
        self, word: str, value: yaml.Node | None, key_loc: Loc, loc: Loc, env: Mapping[str, Bound]
    ) -> Node | None:
        spec: dict[str, tuple[ValueType, bool]] = {
            "retry": {"times": (INT, True)},
            "repeat": {"times": (INT, False), "for": (DURATION, False)},
            "timeout": {"after": (DURATION, True)},
            "delay": {"for": (DURATION, True)},
            "oneshot": {"policy": (enum("on_success", "on_completion"), False)},
            "for_each": {"key": (STR, True), "in": (VALUE_TYPES["str"], True)},
        }.get(word, {})
        options: dict[str, Any] = {}
        child_node: yaml.Node | None
        child_loc = loc
        takes_child_directly = word in SIMPLE_DECORATORS or word == "oneshot"
        if value is None:
            raise Bad(key_loc.at(f"{word} needs a child under do:"))
        fields: dict[str, tuple[yaml.Node, Loc]] = {}
        if isinstance(value, yaml.MappingNode):
            items = mapping(value, loc, word)
            keys = [k for k, *_ in items]
            direct = takes_child_directly and "do" not in keys
            if direct:
                child_node = value
            else:
                for k, v, kl, vl in items:
                    if k != "do" and k not in spec:
                        allowed = ["do", *spec]
                        raise Bad(kl.at(f"{word}: " + unknown("option", k, allowed)))
                    fields[k] = (v, vl)
                if "do" not in fields:
                    raise Bad(key_loc.at(f"{word} needs a child under do:"))
                child_node, child_loc = fields.pop("do")
        elif takes_child_directly:
            child_node = value
        else:
            raise Bad(
                loc.at(
                    f"{word} takes options and a child: {word}: {{{', '.join([*spec, 'do'])}: ...}}"
                )
            )
        if isinstance(child_node, yaml.SequenceNode):
            raise Bad(
                child_loc.at(
                    f"{word} takes exactly one child, got a list of {len(child_node.value)} "
                    "(wrap them in a sequence)"
                )
            )
        for oname, (otype, required) in spec.items():
            if oname not in fields:
                if required:
                    raise Bad(key_loc.at(f"{word} needs {oname}:"))
                continue
            if word == "for_each" and oname == "in":
                continue
            onode, oloc = fields[oname]
            options[oname] = resolve(self.ctx, onode, oloc, otype, env, f"{word}.{oname}")
        if any(v is UNKNOWN for v in options.values()):
            pass  # an unused subtree's parameter: checked where the subtree is used
        elif word == "retry" and options["times"] < 1:
            raise Bad(
                fields["times"][1].at(f"retry.times must be at least 1, got {options['times']}")
            )
        if word == "repeat" and UNKNOWN not in options.values():
            if "times" in options and "for" in options:
                raise Bad(key_loc.at("repeat takes times: or for:, not both"))
            if options.get("times", 1) < 1:
                raise Bad(
                    fields["times"][1].at(
                        f"repeat.times must be at least 1, got {options['times']}"
                    )
                )
        if word == "for_each":
            self._for_each_items(options, fields, env)
        child = self.node(child_node, child_loc, env)
        if child is None:
            return None
        return Node(word, key_loc, word, [child], options=options)

    def _for_each_items(
        self,
        options: dict[str, Any],
        fields: dict[str, tuple[yaml.Node, Loc]],
        env: Mapping[str, Bound],
    ) -> None:
        key, (_, key_value_loc) = options["key"], fields["key"]
        decl = self.ctx.keys.get(key)
        if decl is None:
            raise Bad(
                key_value_loc.at(
                    "for_each.key: " + unknown("blackboard key", key, list(self.ctx.keys))
                )
            )
        inode, iloc = fields["in"]
        items = []
        for item, item_loc in sequence(inode, iloc, "for_each.in"):
            try:
                items.append(resolve(self.ctx, item, item_loc, decl.type, env, "for_each.in"))
            except Bad as bad:
                self.ctx.error(bad.diagnostic)
        options["items"] = items

    # ---------------------------------------------------------------- subtrees
    def _use_subtree(
        self, value: yaml.Node | None, key_loc: Loc, loc: Loc, env: Mapping[str, Bound]
    ) -> Node | None:
        if value is None:
            raise Bad(key_loc.at("subtree needs a name: subtree: NAME or subtree: {id: NAME, ...}"))
        args: list[tuple[str, yaml.Node, Loc, Loc]] = []
        if isinstance(value, yaml.MappingNode):
            items = mapping(value, loc, "subtree")
            ids = [i for i in items if i[0] == "id"]
            if not ids:
                raise Bad(key_loc.at("subtree needs id: NAME"))
            name = scalar_text(ids[0][1], ids[0][3], "subtree id")
            id_loc = ids[0][3]
            args = [i for i in items if i[0] != "id"]
        else:
            name = scalar_text(value, loc, "subtree")
            id_loc = loc
        sub = self.ctx.subtrees.get(name)
        if sub is None:
            raise Bad(
                id_loc.at(f"unknown subtree {name!r}{closest(name, list(self.ctx.subtrees))}")
            )
        if name in self._use_stack:
            chain = self._use_stack[self._use_stack.index(name) :]
            raise Bad(id_loc.at(f"recursive subtree: {' -> '.join([*chain, name])}"))
        sub.used = True
        sub_env = dict(self.global_env)
        for pname, pvalue, pkloc, pvloc in args:
            if pname not in sub.params:
                self.ctx.error(
                    pkloc.at(f"subtree {name!r}: " + unknown("parameter", pname, list(sub.params)))
                )
                continue
            vtype = sub.params[pname][0]
            try:
                resolved = resolve(self.ctx, pvalue, pvloc, vtype, env, f"{name}.{pname}")
            except Bad as bad:
                self.ctx.error(bad.diagnostic)
                resolved = UNKNOWN
            sub_env[pname] = Bound(
                vtype, resolved, shown(vtype, resolved) if resolved is not UNKNOWN else "?"
            )
        given = {a[0] for a in args}
        for pname, (vtype, default, _) in sub.params.items():
            if pname in given:
                continue
            if default is None:
                self.ctx.error(key_loc.at(f"subtree {name!r} needs parameter {pname!r}"))
                sub_env[pname] = Bound(vtype, UNKNOWN, "?")
            else:
                sub_env[pname] = Bound(vtype, default, shown(vtype, default))
        if sub.body is None:
            return None
        self._use_stack.append(name)
        try:
            body = self.node(sub.body, sub.body_loc, sub_env)
        finally:
            self._use_stack.pop()
        if body is not None and body.name == body.kind and body.kind != "leaf":
            body.name = name
        return body

    # ---------------------------------------------------------------- leaves
    def _leaf(
        self,
        decl: Declaration,
        value: yaml.Node | None,
        key_loc: Loc,
        loc: Loc,
        env: Mapping[str, Bound],
    ) -> Node | None:
        given: list[tuple[str, yaml.Node, Loc, Loc]] = []
        if value is None or (isinstance(value, yaml.ScalarNode) and value.tag.endswith(":null")):
            pass
        elif isinstance(value, yaml.MappingNode):
            given = mapping(value, loc, decl.name)
        elif decl.primary is not None:
            given = [(decl.primary, value, loc, loc)]
        else:
            names = ", ".join(p.name for p in decl.params) or "none"
            raise Bad(
                loc.at(
                    f"{decl.name} takes parameters as a mapping ({decl.name}: {{...}}); "
                    f"parameters: {names}"
                )
            )
        params: dict[str, Any] = {}
        options: dict[str, Any] = {}
        ok = True
        key_typed: dict[str, tuple[yaml.Node, Loc]] = {}
        for pname, pnode, pkloc, pvloc in given:
            param = decl.param(pname)
            if param is None:
                pnames = [p.name for p in decl.params]
                self.ctx.error(pkloc.at(f"{decl.name}: " + unknown("parameter", pname, pnames)))
                ok = False
                continue
            options[f"loc:{pname}"] = pvloc
            if param.type.name == "any":
                key_typed[pname] = (pnode, pvloc)
                continue
            try:
                params[pname] = resolve(
                    self.ctx, pnode, pvloc, param.type, env, f"{decl.name}.{pname}",
                    param=param, allow_ref=param.from_blackboard,
                )  # fmt: skip
            except Bad as bad:
                self.ctx.error(bad.diagnostic)
                ok = False
        for p in decl.params:
            if (
                p.required
                and p.name not in params
                and p.name not in key_typed
                and p.name not in {g[0] for g in given}
            ):
                self.ctx.error(
                    key_loc.at(
                        f"{decl.name}: missing required parameter {p.name!r} ({p.describe()})"
                    )
                )
                ok = False
        ok = self._key_params(decl, params, key_typed, options, env) and ok
        if ok and decl.constraints is not None and UNKNOWN not in params.values():
            for problem in decl.constraints(params):
                self.ctx.error(key_loc.at(f"{decl.name}: {problem}"))
                ok = False
        if not ok:
            return None
        return Node("leaf", key_loc, _leaf_name(decl.name, given, env), decl=decl, params=params,
                    options=options)  # fmt: skip

    def _key_params(
        self,
        decl: Declaration,
        params: dict[str, Any],
        key_typed: dict[str, tuple[yaml.Node, Loc]],
        options: dict[str, Any],
        env: Mapping[str, Bound],
    ) -> bool:
        """Parameters that name blackboard keys must name declared keys; ``any`` values take
        the type of the key (``set: {key: leg, value: 2 m}``)."""
        ok = True
        key_decl: KeyDecl | None = None
        for pname in (*decl.reads_keys, *decl.writes_keys):
            key = params.get(pname)
            if not isinstance(key, str):
                continue
            found = self.ctx.keys.get(key)
            where = options.get(f"loc:{pname}")
            if found is None:
                assert isinstance(where, Loc)
                self.ctx.error(
                    where.at(
                        f"{decl.name}.{pname}: "
                        + unknown("blackboard key", key, list(self.ctx.keys))
                    )
                )
                ok = False
                continue
            wants_mark = decl.name in ("mark", "odometry")
            if wants_mark != (found.type is MARK):
                assert isinstance(where, Loc)
                need = "a key of type mark" if wants_mark else "a key holding a value (not a mark)"
                self.ctx.error(
                    where.at(
                        f"{decl.name}.{pname}: blackboard key {key!r} is {found.type.describe()}; "
                        f"{decl.name} needs {need}"
                    )
                )
                ok = False
                continue
            key_decl = found
        for pname, (pnode, pvloc) in key_typed.items():
            if key_decl is None:
                ok = False
                continue
            try:
                params[pname] = resolve(
                    self.ctx, pnode, pvloc, key_decl.type, env, f"{decl.name}.{pname}"
                )
            except Bad as bad:
                self.ctx.error(bad.diagnostic)
                ok = False
        return ok


def shown(vtype: ValueType, value: Any) -> str:
    """A value as a mission would write it: ``150 mm/s`` rather than ``150.0``."""
    if vtype.name in CANONICAL and isinstance(value, int | float):
        return format_quantity(vtype.name, value)
    return str(value)


def _leaf_name(
    behaviour: str, given: list[tuple[str, yaml.Node, Loc, Loc]], env: Mapping[str, Bound]
) -> str:
    """``drive(velocity=100 mm/s, radius=-500 mm)``: what ``show`` prints for a leaf, with
    ``${parameters}`` shown as their values."""
    if not given:
        return behaviour

    def value_of(match: re.Match[str]) -> str:
        bound = env.get(match.group(1))
        return bound.text if bound is not None and bound.value is not UNKNOWN else match.group(0)

    parts = []
    for pname, node, key_loc, value_loc in given:
        text = str(node.value) if isinstance(node, yaml.ScalarNode) else "..."
        text = _SUBSTITUTION.sub(value_of, text)
        parts.append(text if key_loc is value_loc else f"{pname}={text}")
    return f"{behaviour}({', '.join(parts)})"


def _text(node: yaml.Node, loc: Loc, default: Any) -> str:
    for key, value in getattr(node, "value", []):
        if getattr(key, "value", None) == "default" and isinstance(value, yaml.ScalarNode):
            return str(value.value)
    return str(default)


def _cli_value(text: str, vtype: ValueType) -> object:
    """A ``-p name=value`` string as the type wants it: numbers and booleans as YAML reads
    them, everything else as written."""
    if vtype.name in ("int", "float", "bool"):
        try:
            return yaml.safe_load(text)
        except yaml.YAMLError:
            return text
    return text
