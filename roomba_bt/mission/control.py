"""Composites and decorators: their options read from the language table
(:data:`roomba_bt.behaviours.language.WORDS`), never listed here.

What a word takes (which options, their types, which are required, ranges, options that
exclude each other) is the table's; this module only knows the two shapes a value has:
children (``sequence: [...]``) or one child under ``do:``.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

import yaml

from roomba_bt.behaviours.declare import Param
from roomba_bt.behaviours.language import (
    CHILD_NAMES,
    KEY_ITEMS,
    TEXT,
    WORDS,
    NodeKind,
    Shape,
    places_option,
)
from roomba_bt.behaviours.units import ValueType, list_of
from roomba_bt.mission.leaves import written_text
from roomba_bt.mission.plan import Node
from roomba_bt.mission.source import (
    Bad,
    Loc,
    empty_name,
    kind_of,
    mapping,
    plain,
    scalar_text,
    sequence,
)
from roomba_bt.mission.ticks import at_once
from roomba_bt.mission.values import (
    ESCAPE_HINT,
    UNKNOWN,
    Bound,
    Context,
    UnknownNames,
    Written,
    key_written_in,
    name_text,
    parameters_used,
    resolve,
    said_defaults,
    said_origin,
    substituted,
    unknown,
    warn_escaped,
    whole_parameter,
)

if TYPE_CHECKING:
    from roomba_bt.mission.nodes import NodeParser

#: the options as written: name -> (value node, value loc)
Fields = dict[str, tuple[yaml.Node, Loc]]


def option_value(
    ctx: Context,
    kind: NodeKind,
    param: Param,
    node: yaml.Node,
    loc: Loc,
    env: Mapping[str, Bound],
    options: dict[str, Any],
) -> Any:
    """One option's value; a name with its ``${parameter}`` replaced as the ``name:``
    modifier's is (:func:`name_text`); child names taken as written (a ``${`` in one is
    refused, :func:`_child_names`); everything else through :func:`resolve`
    (``${parameter}``, units)."""
    if param.type is TEXT:
        written = scalar_text(node, loc, param.name)
        text, uses_parameter = name_text(written, loc, env)
        warn_escaped(ctx, written, node, loc, None, f"{kind.word}.{param.name}")
        if uses_parameter:
            options[_PARAMETER_IN_NAME] = loc
        if param.name == "name" and not text.strip():  # as the name: modifier's
            ctx.error(loc.at(empty_name(f"{kind.word}.name", text, kind.word)))
        return text
    if param.type is CHILD_NAMES:
        names = plain(node, loc)
        if not isinstance(names, list) or not all(isinstance(s, str) for s in names):
            raise Bad(loc.at(f"{kind.word}.{param.name} must be a list of child names"))
        if not names:
            raise Bad(loc.at(_empty_list(kind, param, "child name")))
        options[f"{param.name}_loc"] = loc
        return _child_names(f"{kind.word}.{param.name}", names, loc)
    return resolve(ctx, node, loc, param.type, env, f"{kind.word}.{param.name}")


#: the option a composite's own ``name:`` that uses a parameter leaves its place in, for
#: :attr:`Node.parameter_in_name <roomba_bt.mission.plan.Node.parameter_in_name>`
_PARAMETER_IN_NAME = "parameter_in_name"


def _child_names(what: str, names: list[str], loc: Loc) -> list[str]:
    """``selected:``'s names, each ``$$`` one ``$`` as in the name it picks. A
    ``${parameter}`` is refused: a child's name that uses one changes with its value
    (``-p side=right``), and a pick that held on the default would name no child, or
    another, with another value; so names are matched as written, never substituted."""
    for name in names:
        used = parameters_used(name)
        if used:
            raise Bad(
                loc.at(
                    f"{what}: {name!r}: child names are matched as written, and ${{"
                    f"{used[0]}}} is not replaced here: a name made with a parameter "
                    f"changes with its value, so {what.rsplit('.', 1)[-1]}: cannot pick it; "
                    f"give the child a fixed name (name: ...) and pick that; {ESCAPE_HINT}"
                )
            )
    return [substituted(name, lambda _: None) for name in names]


def _given_whole(node: yaml.Node) -> bool:
    """Whether a list option is written as one value, a ``${parameter}`` or an ``@key``,
    not as the list itself."""
    return isinstance(node, yaml.ScalarNode) and str(node.value).strip().startswith(("$", "@"))


#: why ``for_each.in`` takes no ``@key``: its items are known when the mission is validated
_ITEMS_FIXED = (
    " (for_each.in is known when the mission is validated, each item checked against the "
    "ranges of the key's readers: write the list, or give a list parameter, "
    '"${legs}" with legs: {type: list, items: distance})'
)


def _list_parameter(
    ctx: Context,
    node: yaml.Node,
    loc: Loc,
    item: ValueType,
    env: Mapping[str, Bound],
    said: tuple[str, str],
) -> tuple[list[Any], list[Loc], list[str]]:
    """``for_each.in: "${legs}"``: the items of a list parameter whose items are of the
    key's type ``item``, each with where a finding about it is said, and what that says of
    where it came from: an item of the parameter's default at its own place in the default
    (the line to change), naming the use; another (-p, a subtree's argument) at the use,
    naming where it was set. None when its value is unknown. ``said``: the option, and its
    error when empty."""
    what, empty = said
    value = resolve(ctx, node, loc, list_of(item), env, what, no_ref=_ITEMS_FIXED)
    if value is UNKNOWN:
        return [], [], []
    if not value:
        raise Bad(loc.at(empty + (said_origin(node, env) or said_defaults([node], env, loc))))
    whole = whole_parameter(node, env)
    if whole is None or whole[1].origin or len(whole[1].default_items) != len(value):
        return list(value), [loc] * len(value), [said_origin(node, env)] * len(value)
    name, bound = whole
    notes = [
        f" (item {number} of the default of parameter {name}, {what} at {loc.said_from(at)})"
        for number, at in enumerate(bound.default_items, 1)
    ]
    return list(value), list(bound.default_items), notes


def _empty_list(kind: NodeKind, param: Param, item: str) -> str:
    """The error of a list option (``CHILD_NAMES``, ``KEY_ITEMS``: the schema says
    ``minItems: 1`` of both) written empty: ``parallel.selected: []`` passed, and py_trees
    refused it when the run began (exit 4, "a bug"); ``for_each.in: []`` ran its child
    never."""
    return f"{kind.word}.{param.name} is an empty list: give at least one {item}"


def _null(node: yaml.Node) -> bool:
    return isinstance(node, yaml.ScalarNode) and node.tag.endswith(":null")


def parse_composite(parser: NodeParser, kind: NodeKind, at: Written) -> Node | None:
    """``word: [children]`` or ``word: {children: [...], option: value, ...}``."""
    value, key_loc, loc, env = at.value, at.key_loc, at.loc, at.env
    word, ctx = kind.word, parser.ctx
    options: dict[str, Any] = kind.defaults
    children_node: yaml.Node | None = value
    children_loc = loc
    fields: Fields = {}
    if isinstance(value, yaml.MappingNode):
        allowed = ["children", *(p.name for p in kind.options)]
        unknown_option = UnknownNames("option", allowed, word)
        items = mapping(value, loc, word)
        _children_as_keys(parser, word, [(k, kl) for k, _, kl, _ in items if k not in allowed])
        for k, v, kl, vl in items:
            if k not in allowed:
                message, later = unknown_option(k)
                ctx.error(kl.at(f"{word}: {message}", later))
                continue
            fields[k] = (v, vl)
        for param in kind.options:
            if param.name in fields:
                options[param.name] = option_value(ctx, kind, param, *fields[param.name], env,
                                                   options)  # fmt: skip
        _option_rules(kind, options, fields, key_loc)
        if "children" not in fields:
            raise Bad(key_loc.at(f"{word} needs children: [...]"))
        children_node, children_loc = fields["children"]
    if children_node is None or _null(children_node):
        raise Bad(key_loc.at(f"{word} needs at least one child; it has none"))
    if not isinstance(children_node, yaml.SequenceNode):
        raise Bad(children_loc.at(f"{word} takes a list of children, got {kind_of(children_node)}"))
    children = []
    entries = sequence(children_node, children_loc, f"{word} children")
    if not entries:
        raise Bad(key_loc.at(f"{word} needs at least one child; it has none"))
    for child_node, child_loc in entries:
        child = parser.node(child_node, child_loc, env)
        # one that could not be built keeps its place (its errors are reported): the
        # checks judge its siblings where they are written (plan.Node)
        children.append(child if child is not None else Node("unbuilt", child_loc, "unbuilt"))
    name, parameter_in_name = options.pop("name", word), options.pop(_PARAMETER_IN_NAME, None)
    result = Node(word, key_loc, name, children, options=options,
                  parameter_in_name=parameter_in_name,
                  options_written=_options_written(fields, env))  # fmt: skip
    for param in kind.options:
        if param.type is CHILD_NAMES and param.name in options:
            _chosen(ctx, f"{word}.{param.name}", options, children, [e[1] for e in entries])
    return result


def _children_as_keys(parser: NodeParser, word: str, strays: list[tuple[str, Loc]]) -> None:
    """``sequence: {drive: ..., turn: ...}``: children written as keys of the composite, not
    as a list. Each was "unknown option 'drive'", and then "sequence needs children": one
    error (:class:`Bad`), at the first, with the fix. Nothing when no stray key is a node."""
    nodes = [key for key, _ in strays if key in parser.ctx.registry or key in WORDS]
    if nodes:
        raise Bad(strays[0][1].at(
            f"a {word}'s children are a list, not keys of it: write each as `- {nodes[0]}: "
            f"...`, one under another (found {', '.join(key for key, _ in strays)} as keys)"
        ))  # fmt: skip


def _child_as_key(parser: NodeParser, word: str, key: str) -> str:
    """``retry: {times: 3, drive: {...}}``: the child written as a key beside the options,
    where the language names a decorator's child ``do:``. The error said only "unknown option
    'drive'"; now, when the key is a node, also where the child goes."""
    if key not in parser.ctx.registry and key not in WORDS:
        return ""
    return f"; a {word}'s child goes under do:, not beside its options: do: {{{key}: ...}}"


def _chosen(ctx: Context, what: str, options: dict[str, Any], children: list[Node],
            places: list[Loc]) -> None:  # fmt: skip
    """The children an option of child names (``parallel.selected``) picks, by place in
    ``options[places_option(option)]``: the builder picks them by place, since show renames
    the nodes it reviews (build.CompiledMission.reviewed). A name no child answers to is an
    error, and so is one that two answer to (two ``name: timer``, or two guards ``until
    bump(any)``): it picked both."""
    option = what.rsplit(".", 1)[1]
    where: Loc = options[f"{option}_loc"]
    answers = [_answering(c) for c in children]
    # a child that could not be parsed at all has lost its name: not said unknown for that
    nameless = any(c.kind == "unbuilt" and c.partial is None for c in children)
    for chosen in options[option]:
        picked = [places[i] for i, nodes in enumerate(answers)
                  if any(n.name == chosen for n in nodes)]  # fmt: skip
        if not picked and not nameless:
            known = list(dict.fromkeys(nodes[-1].name for nodes in answers))
            ctx.error(where.at(f"{what}: " + unknown("child name", chosen, known)))
        elif len(picked) > 1:
            at = " and ".join(f"{p.line}:{p.column}" for p in picked)
            ctx.error(where.at(f"{what}: {chosen!r} names {len(picked)} children, at {at}; "
                               "give each its own name (name: ...)"))  # fmt: skip
        for nodes in answers:
            _picked_by_parameter(ctx, what, where, chosen, nodes)
    options[places_option(option)] = [
        i for i, nodes in enumerate(answers) if {n.name for n in nodes} & set(options[option])
    ]


def _picked_by_parameter(
    ctx: Context, what: str, where: Loc, chosen: str, answering: list[Node]
) -> None:
    """``selected: [turn left]`` picking a child named ``"turn ${side}"``: refused at the
    name, since with ``-p side=right`` it would pick none (or another child)."""
    for node in answering:
        if node.name == chosen and node.parameter_in_name is not None:
            ctx.error(
                node.parameter_in_name.at(
                    f"{what} (at {where.line}:{where.column}) picks this child by its name "
                    f"{chosen!r}, which is made with a parameter: another value would name "
                    "another child, or none; give the child a fixed name (name: ...) for "
                    f"{what.rsplit('.', 1)[-1]}: to pick; {ESCAPE_HINT}"
                )
            )


def _answering(child: Node) -> list[Node]:
    """The nodes whose names a child answers to in ``selected:``: its own and, through the
    guards ``while:``/``until:`` wrap it in (named ``until bump(any)``), the node they
    guard, which carries the ``name:`` written beside them; that one last."""
    nodes = [child]
    while child.kind == "guard":
        child = child.children[1]
        nodes.append(child)
    return nodes


def _option_rules(kind: NodeKind, options: dict[str, Any], fields: Fields, key_loc: Loc) -> None:
    """The table's rules between a word's options (:class:`NodeKind`): ``parallel`` with
    ``policy: selected`` needs ``selected:``, which no other policy reads; a reactive
    composite refuses ``memory: true``. Not judged on an unused subtree's unknown value."""
    for name, other, value in kind.required_if:
        if name not in options and options.get(other) == value:
            param = kind.option(name)
            assert param is not None
            raise Bad(key_loc.at(f"{kind.word} with {other} {value} needs {name}: "
                                 f"[{param.type.name}]"))  # fmt: skip
    for name, other, value in kind.only_if:
        given = options.get(other)
        if name in fields and given != value and given is not UNKNOWN:
            raise Bad(fields[name][1].at(f"{kind.word}: {name}: only goes with {other}: "
                                         f"{value} ({other} is {given})"))  # fmt: skip
    for name, bad, why in kind.refused:
        if name in fields and options.get(name) == bad:
            said = str(bad).lower() if isinstance(bad, bool) else str(bad)
            raise Bad(fields[name][1].at(f"{kind.word}: {name}: {said} is refused: {why}"))


def parse_decorator(parser: NodeParser, kind: NodeKind, at: Written) -> Node | None:
    """``word: {option: value, ..., do: child}``, or the child itself for the words that
    take it directly (``inverter: {bump: any}``)."""
    value, key_loc, loc, env = at.value, at.key_loc, at.loc, at.env
    word, spec = kind.word, [p.name for p in kind.options]
    child_node: yaml.Node | None
    child_loc = loc
    takes_child_directly = kind.shape is Shape.CHILD_OR_DO
    if value is None:
        raise Bad(key_loc.at(f"{word} needs a child under do:"))
    fields: Fields = {}
    if isinstance(value, yaml.MappingNode):
        items = mapping(value, loc, word)
        if takes_child_directly and "do" not in [k for k, *_ in items]:
            child_node = value
        else:
            for k, v, kl, vl in items:
                if k != "do" and k not in spec:
                    raise Bad(kl.at(f"{word}: " + unknown("option", k, ["do", *spec], word)
                                    + _child_as_key(parser, word, k)))  # fmt: skip
                fields[k] = (v, vl)
            if "do" not in fields:
                raise Bad(key_loc.at(f"{word} needs a child under do:"))
            child_node, child_loc = fields.pop("do")
    elif takes_child_directly:
        child_node = value
    else:
        raise Bad(
            loc.at(f"{word} takes options and a child: {word}: {{{', '.join([*spec, 'do'])}: ...}}")
        )
    if isinstance(child_node, yaml.SequenceNode):
        count = len(child_node.value)
        fix = (
            "wrap them in a sequence"
            if count != 1
            else (f"drop the list: {word}: NODE" if child_loc is loc else "drop the list: do: NODE")
        )
        raise Bad(child_loc.at(f"{word} takes exactly one child, got a list of {count} ({fix})"))
    try:
        options = _decorator_options(parser.ctx, kind, fields, key_loc, env)
        if kind.writes_key is not None:
            _key_items(parser.ctx, kind, options, fields, env)
    except Bad:
        # a bad option (``repeat.times: 0``) does not hide the child's own errors, said in
        # the same pass (they showed only once the option was fixed); the option's error
        # then makes the decorator unbuilt
        parser.node(child_node, child_loc, env)
        raise
    child = parser.node(child_node, child_loc, env)
    if child is None:
        return None
    if kind.condition_child:
        _condition_child(parser.ctx, word, parser.uses.marked(child))
    return Node(word, key_loc, word, [child], options=options,
                options_written=_options_written(fields, env))  # fmt: skip


def _options_written(fields: Fields, env: Mapping[str, Bound]) -> str:
    """``policy=one, synchronise=false``: the options the file writes for a composite or
    decorator, in its order, as it writes them (what ``show`` says the node is, as a leaf's
    parameters; options left at their default are not written, so not said). Neither its
    children nor its ``name:``, which ``show`` says apart."""
    return ", ".join(
        f"{option}={written_text(node, env, lists=True)}"
        for option, (node, _) in fields.items()
        if option not in ("children", "name")
    )


def _condition_child(ctx: Context, word: str, child: Node) -> None:
    """A word that ticks its child as a condition (``held``): every action under it is an
    error (ticked on every tick and halted each time, a drive would jerk and a ``wait``
    never end), and so is a node that may be RUNNING (a ``delay``, a ``repeat``), the
    innermost such, which it would halt and start again on every tick. Said at the node."""
    actions = [n for n in child.walk() if n.declared is not None and n.declared.kind == "action"]
    for node in actions:
        assert node.declared is not None
        ctx.error(node.loc.at(
            f"{word}: its child is ticked as a condition on every tick; "
            f"{node.declared.name!r} is an action (put the action beside it: "
            f"drive: {{...}}, until: {{{word}: {{...}}}})"
        ))  # fmt: skip
    if actions or any(n.kind == "unbuilt" for n in child.walk()):
        return
    running = [n for n in child.walk() if not at_once(n) and all(map(at_once, n.children))]
    for node in running:
        ctx.error(node.loc.at(
            f"{word}: its child must end on every tick (conditions, and sequences, fallbacks "
            f"and inverters of them); {node.name} may be RUNNING, and {word} would halt it and "
            "start it again on every tick"
        ))  # fmt: skip


def _decorator_options(
    ctx: Context,
    kind: NodeKind,
    fields: Fields,
    key_loc: Loc,
    env: Mapping[str, Bound],
) -> dict[str, Any]:
    """Required options present, values resolved, then (unless a value is an unused
    subtree's unknown parameter) exclusive options and minimums checked."""
    word = kind.word
    options = kind.defaults
    for param in kind.options:
        if param.name not in fields:
            if param.required:
                raise Bad(key_loc.at(f"{word} needs {param.name}:"))
            continue
        if param.type is KEY_ITEMS:
            continue
        options[param.name] = option_value(ctx, kind, param, *fields[param.name], env, options)
    if any(v is UNKNOWN for v in options.values()):
        return options  # an unused subtree's parameter: checked where the subtree is used
    if kind.exclusive and all(name in options for name in kind.exclusive):
        given = " or ".join(f"{name}:" for name in kind.exclusive)
        raise Bad(key_loc.at(f"{word} takes {given}, not both"))
    for param in kind.options:
        value = options.get(param.name)
        if param.minimum is not None and value is not None and value < param.minimum:
            written, where = fields[param.name]
            raise Bad(
                where.at(
                    f"{word}.{param.name} must be at least {_amount(param, param.minimum)}, "
                    f"got {_amount_written(param, value, written, env)}"
                    + (said_origin(written, env) or said_defaults([written], env, where))
                )
            )
    return options


def _amount(param: Param, value: float) -> str:
    """``0.015 s``, ``1``: a value with the unit of the option's type, if it has one."""
    return f"{value:g} {param.type.unit}" if param.type.unit else f"{value:g}"


def _amount_written(
    param: Param, value: float, written: yaml.Node, env: Mapping[str, Bound]
) -> str:
    """The value found, as the file writes it and then in the option's unit where the two
    differ (``10ms (0.01 s)``), as a leaf's parameter is said (``Param.check_range``):
    ``timeout: {after: 10ms}`` said only ``got 0.01 s``, a text the file did not hold."""
    shown = _amount(param, value)
    if not isinstance(written, yaml.ScalarNode):
        return shown
    text = written_text(written, env).strip()
    same = text.replace(" ", "") == shown.replace(" ", "")
    return shown if not text or same else f"{text} ({shown})"


def _key_items(ctx: Context, kind: NodeKind, options: dict[str, Any], fields: Fields,
               env: Mapping[str, Bound]) -> None:  # fmt: skip
    """``for_each.in``: every item a value of the type of the key the node writes (a key
    named by a parameter: one of the body that gave it, :func:`key_written_in`)."""
    assert kind.writes_key is not None
    key_option = kind.writes_key
    key, (key_node, key_value_loc) = options[key_option], fields[key_option]
    keys, scope = key_written_in(ctx, key_node, env)
    if scope is not None:
        options[f"scope:{key_option}"] = scope
    decl = keys.get(key)
    if decl is None:
        said = ctx.unknown_key(key, key_value_loc, None if scope is None else keys)
        raise Bad(key_value_loc.at(f"{kind.word}.{key_option}{said_origin(key_node, env)}: {said}"))
    for param in kind.options:
        if param.type is not KEY_ITEMS:
            continue
        what = f"{kind.word}.{param.name}"
        inode, iloc = fields[param.name]
        empty = _empty_list(kind, param, "item, a value of the key's type")
        items: list[Any] = []
        locs: list[Loc] = []
        notes: list[str] = []  # where a parameter's item came from: none written here
        if _given_whole(inode):
            items, locs, notes = _list_parameter(ctx, inode, iloc, decl.type, env, (what, empty))
        else:
            entries = sequence(inode, iloc, what)
            if not entries:
                raise Bad(iloc.at(empty))
            for item, item_loc in entries:
                try:
                    items.append(resolve(ctx, item, item_loc, decl.type, env, what))
                    locs.append(item_loc)
                except Bad as bad:
                    ctx.report(bad)
        options["items"] = items
        options["loc:items"] = locs  # where each is written: the range check of its readers
        options["said:items"] = notes or [""] * len(items)
