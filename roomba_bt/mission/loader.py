"""The loader: YAML mission file (and its includes) -> checked tree, every error collected.

A mission file::

    mission: square                      # name (default: the file name)
    description: drive a square
    parameters:                          # settable with -p side=50cm
      side: {type: distance, default: 1 m}
    blackboard:                          # declared keys, with types
      leg: distance
    plugins: [./my_behaviour.py]         # behaviour modules by path (needs permission)
    include: [lib/common.yaml]           # subtrees (and keys) of other files; the shipped
                                         # library: roomba-bt:lib/docking.yaml
    subtrees:
      back_off:
        parameters: {speed: {type: speed, default: 100 mm/s}}
        tree: {drive: {velocity: -${speed}, distance: 10cm}}
    tree:
      sequence:
        - mode: safe
        - drive: {distance: ${side}}

The loader reads the file-level sections (plugins, includes, parameters, the blackboard,
subtree definitions); :class:`~roomba_bt.mission.nodes.NodeParser` parses the trees. Neither
stops at the first error: each problem becomes a
:class:`~roomba_bt.mission.diagnostics.Diagnostic` and parsing goes on with the next node.
``docs/missions.md`` documents every word.

A mission file is data, never code: a plugin file it names is imported only when the caller
grants :attr:`Permissions.plugin_files` (the command line's ``--allow-plugin-files``), and an
include or a plugin file resolves only inside the top mission's folder tree, the shipped
library (:data:`SHIPPED_LIBRARY`) and the folders the caller adds (``--include-dir``). A file
that is not a mission is reported as such, never quoted back. A message says how the caller
grants or sets what it names in the caller's own words (:attr:`Permissions.wording`: a
Python program's arguments, or the command line's flags).
"""

from __future__ import annotations

import itertools
import os
import re
import unicodedata
from collections.abc import Callable, Collection, Iterable, Mapping, Sequence
from dataclasses import dataclass
from decimal import Decimal, InvalidOperation
from pathlib import Path
from typing import Any, Protocol

import yaml

from roomba_bt.behaviours.language import WORDS
from roomba_bt.behaviours.registry import Registry, names_declared_in
from roomba_bt.behaviours.units import (
    ANY,
    STR,
    UnitError,
    ValueType,
    closest,
    closest_name,
    enum,
    list_of,
    percent_sign_kept,
)
from roomba_bt.mission.diagnostics import Diagnostic
from roomba_bt.mission.include_path import (
    DOCUMENTED_AT,
    INCLUDE_DIRS_KEY,
    INCLUDE_PATH_VARIABLE,
    PROJECT_FILE,
    PROJECT_TABLE,
    granted_files,
)
from roomba_bt.mission.nodes import NodeParser
from roomba_bt.mission.plan import KeyDecl, Node
from roomba_bt.mission.shipped import (
    DOCKING_LIBRARY,
    SHIPPED_DIR,
    SHIPPED_PREFIX,
    in_shipped_library,
    other_package,
    shipped_library_files,
    shipped_name,
)
from roomba_bt.mission.source import (
    Bad,
    Loc,
    compose,
    compose_text,
    empty_name,
    kind_of,
    loc_of,
    mapping,
    named_entries,
    plain,
    scalar_text,
    sequence,
    written_keys,
)
from roomba_bt.mission.values import (
    LIST_ITEM_TYPES,
    PARAMETER_TYPE_NAMES,
    PARAMETER_TYPE_OPTIONS,
    PARAMETER_TYPES,
    UNKNOWN,
    Bound,
    Context,
    SubtreeDef,
    check_literal_names,
    parameters_used,
    parse_type_name,
    read_literal,
    record_type,
    resolve,
    substituted,
    unknown,
    warn_escaped,
)
from roomba_bt.mission.wording import COMMAND_LINE, PYTHON, Wording
from roomba_bt.printable import path_written
from roomba_bt.yamlsource import (
    holds_some_of,
    named_character,
    not_a_file_of,
    too_many_digits,
    yaml11_number_problem,
)

#: what a subtree's definition may hold
_SUBTREE_FIELDS = ("parameters", "blackboard", "tree", "doc")
TOP_LEVEL = ("mission", "description", "parameters", "blackboard", "plugins", "include",
             "subtrees", "tree", "literal")  # fmt: skip
_IDENT = re.compile(r"^[a-z_][a-z0-9_]*$")
_INCLUDED_KEYS = ("description", "plugins", "include", "blackboard", "subtrees", "literal")

#: Folders every mission may include from, wherever it lives: the shipped missions' folder
#: (package data, named ``roomba-bt:lib/docking.yaml`` in an include), wherever installed.
SHIPPED_LIBRARY: tuple[Path, ...] = (SHIPPED_DIR.resolve(),)


@dataclass(frozen=True, slots=True)
class Permissions:
    """What a mission file may reach beyond its own data, granted by whoever runs it (the
    command line), never by the file.

    ``plugin_files``: import the Python files its ``plugins:`` names (``--allow-plugin-files``).
    ``include_dirs``: folders it may include from (and import plugin files from, when allowed)
    besides its own folder tree and the shipped library (``--include-dir``).
    ``wording``: how the messages say what the caller grants and sets (a permission, a
    parameter, the profile): a Python program's arguments (``wording.PYTHON``, the
    default), or the command line's flags (``wording.COMMAND_LINE``, which the CLI gives)."""

    plugin_files: bool = False
    include_dirs: tuple[Path, ...] = ()
    wording: Wording = PYTHON

    def __post_init__(self) -> None:
        """Checked here, the folders made paths: a ``str`` among ``include_dirs`` (the obvious
        thing to write) had the compiler say "internal error ... please report it"."""
        if not isinstance(self.plugin_files, bool):
            raise TypeError(
                f"Permissions(plugin_files=...) takes True or False, "
                f"not {type(self.plugin_files).__name__} {self.plugin_files!r}"
            )
        folders = self.include_dirs
        if isinstance(folders, str | bytes | os.PathLike) or not isinstance(folders, Iterable):
            raise TypeError(
                f"Permissions(include_dirs=...) takes a tuple of folders, such as "
                f"include_dirs=(Path('lib'),), not {type(folders).__name__} {folders!r}"
            )
        paths = []
        for folder in folders:
            if not isinstance(folder, str | os.PathLike) or isinstance(folder, bytes):
                raise TypeError(
                    "Permissions(include_dirs=...): each folder is a path or a str, not "
                    f"{type(folder).__name__} {folder!r}"
                )
            paths.append(Path(folder))
        object.__setattr__(self, "include_dirs", tuple(paths))


#: The default: a mission file imports nothing and includes only from its tree and the library.
NO_PERMISSIONS = Permissions()


class GivenText(Protocol):
    """A mission given as text (``compiler.MissionText``): its YAML."""

    @property
    def yaml(self) -> str: ...


@dataclass
class ParsedFile:
    name: str
    description: str
    params: dict[str, Bound]
    tree: Node | None
    tree_loc: Loc | None
    root_loc: Loc


def _literal_section(ctx: Context, sections: dict[str, tuple[yaml.Node, Loc, Loc]]) -> None:
    """A file's ``literal:``, if any (:func:`~roomba_bt.mission.values.read_literal`): read
    before any text of the file, for the mission and each included library alike."""
    if "literal" in sections:
        node, _, vloc = sections["literal"]
        read_literal(ctx, node, vloc)


def _names_written(
    ctx: Context, path: Path, sections: dict[str, tuple[yaml.Node, Loc, Loc]]
) -> tuple[str, str]:
    """``mission:`` (the file's stem if absent, or if it names nothing: an error) and
    ``description:`` as written."""
    found = {"mission": path.stem, "description": ""}
    for key in found:
        if key in sections:
            node, _, vloc = sections[key]
            try:
                found[key] = scalar_text(node, vloc, key)
            except Bad as bad:
                ctx.report(bad)
    if not found["mission"].strip():  # show's first line and the summary said nothing
        ctx.error(sections["mission"][2].at(empty_name("mission", found["mission"], path.stem)))
        found["mission"] = path.stem
    return found["mission"], found["description"]


class Loader:
    """Reads one mission file and what it includes: sections, plugins, parameters, the
    blackboard and subtree definitions; the trees go to the :class:`NodeParser`."""

    def __init__(
        self,
        ctx: Context,
        display: Callable[[Path], str] | None = None,
        permissions: Permissions = NO_PERMISSIONS,
    ) -> None:
        self.ctx = ctx
        self.display: Callable[[Path], str] = display or (lambda p: str(p))
        self.nodes = NodeParser(ctx)
        self.permissions = permissions
        self._include_stack: list[Path] = []
        self._include_roots: tuple[Path, ...] = ()
        #: each file included so far, with the include that first named it
        self._included: dict[Path, Loc] = {}
        #: every file read: the mission file, then each include and plugin file as reached
        self.files: list[Path] = []
        #: the parameters the compiled file declares (``validate``'s ``-p`` over many files)
        self.parameters: tuple[str, ...] = ()

    @property
    def include_sites(self) -> dict[str, Loc]:
        """Each included file, named as its diagnostics name it, with the include entry that
        first reached it: the links of a diagnostic's include chain."""
        return {self.display(target): loc for target, loc in self._included.items()}

    def compile_file(
        self,
        path: Path,
        overrides: Mapping[str, str],
        *,
        require_tree: bool = True,
        text: GivenText | None = None,
    ) -> ParsedFile | None:
        """``text``: YAML read in place of the file at ``path`` (``load_mission_text``)."""
        resolved = path.resolve()  # once: a resolve is a system call per folder on the way
        read = self._read_sections(path, resolved, None if text is None else text.yaml)
        if read is None:
            return None
        sections, root_loc = read
        self._include_roots = (
            resolved.parent,
            *SHIPPED_LIBRARY,
            *(folder.resolve() for folder in self.permissions.include_dirs),
        )
        self.nodes.granted = self._include_roots
        self._include_stack.append(resolved)
        _literal_section(self.ctx, sections)  # before any text of the file is read
        # the parameters first: a blackboard key's initial value may be one ("${speed}"),
        # and read before them it was an "unknown parameter" the declaration had just made
        params = bind_parameters(self.ctx, sections.get("parameters"), overrides, root_loc)
        self.parameters = tuple(params)
        self.nodes.global_env = params
        self._file_sections(path, sections)
        if "tree" in sections:  # a library alone: its names may be an including mission's
            check_literal_names(self.ctx, params)
        name, description = self._names(path, sections)
        if "description" in sections and "$" in description:
            node, _, vloc = sections["description"]
            warn_escaped(self.ctx, description, node, vloc, params, "description")
        description = substituted(
            description, lambda name: params[name].text if name in params else None
        )
        tree: Node | None = None
        tree_loc: Loc | None = None
        if "tree" in sections:
            node, _, vloc = sections["tree"]
            tree_loc = vloc
            tree = self.nodes.node(node, vloc, params)
        elif require_tree and "subtrees" in sections:
            self.ctx.error(root_loc.at(_a_library(resolved, path)))
        elif require_tree:
            self.ctx.error(root_loc.at("a mission needs a tree: (the root node); found none"))
        self.nodes.check_unused_subtrees()
        self._include_stack.pop()
        return ParsedFile(name, description, params, tree, tree_loc, root_loc)

    def _compose(
        self,
        path: Path,
        resolved: Path,
        include: tuple[str, Loc] | None = None,
        text: str | None = None,
    ) -> tuple[yaml.Node, Loc] | None:
        """One file of the mission (the main file or an include) read as YAML nodes: its
        root and the root's place, None when it cannot be read or parsed (reported). The
        file is remembered (``files``, resolved) for ``--watch``. ``include``: the include's
        text and place, where a file that cannot be opened is reported (its own 1:1 names
        no line the user wrote)."""
        display = self.display(path)
        if text is not None:  # a mission given as text: no file to read or watch
            root, said = compose_text(text, display)
        else:
            self.files.append(resolved)
            root, said = compose(path, display, include)
        self.ctx.said(said)
        if root is None:
            return None
        return root, loc_of(root, display, "")

    def _read_sections(
        self, path: Path, resolved: Path, text: str | None = None
    ) -> tuple[dict[str, tuple[yaml.Node, Loc, Loc]], Loc] | None:
        """The file's top-level sections by key (node, key's and value's place) and the
        root's place; None when it is no mission file. Unknown keys are reported."""
        read = self._compose(path, resolved, text=text)
        if read is None:
            return None
        root, root_loc = read
        if _is_world(root):  # its name: and description: are mission words too: 11 lines
            self.ctx.error(root_loc.at(
                "this file is a world (rooms:, no tree:), not a mission: run a mission on it "
                f"with {self.permissions.wording.on_world.format(path=str(path))}"
            ))  # fmt: skip
            return None
        sections = self._sections(
            root,
            root_loc,
            TOP_LEVEL,
            not_a_mission=root_loc.at(not_a_file_of("this file", "mission", TOP_LEVEL)),
            called="a mission file",
            unknown_key=lambda key: (
                f"unknown top-level key {key!r}{closest(key, TOP_LEVEL)}; "
                f"known: {', '.join(TOP_LEVEL)}"
            ),
            read_misspelt=True,
        )
        return None if sections is None else (sections, root_loc)

    def _sections(
        self,
        root: yaml.Node,
        root_loc: Loc,
        words: tuple[str, ...],
        *,
        not_a_mission: Diagnostic,
        called: str,
        unknown_key: Callable[[str], str],
        read_misspelt: bool = False,
    ) -> dict[str, tuple[yaml.Node, Loc, Loc]] | None:
        """The sections of a file's root (a mission, or a library it includes) by key:
        None, ``not_a_mission`` reported, when the root is no mapping with one of ``words``
        (its content is not quoted back), or when its keys are not all names (``called``
        names the file in that error). A key not in ``words`` is reported with
        ``unknown_key(key)`` and the others are read on; with ``read_misspelt`` (a mission,
        whose message says "did you mean"), as the section it misspells (:func:`_by_key`)."""
        if not holds_some_of(root, words):
            self.ctx.error(not_a_mission)
            return None
        try:
            items = mapping(root, root_loc, called)
        except Bad as bad:
            self.ctx.report(bad)
            return None
        for key, _, key_loc, _ in items:
            if key not in words:
                self.ctx.error(key_loc.at(unknown_key(key)))
        return _by_key(items, words if read_misspelt else ())

    def _names(
        self, path: Path, sections: dict[str, tuple[yaml.Node, Loc, Loc]]
    ) -> tuple[str, str]:
        """``mission:`` (the file's stem if absent) and ``description:`` as written."""
        return _names_written(self.ctx, path, sections)

    def _file_sections(self, path: Path, sections: dict[str, tuple[yaml.Node, Loc, Loc]]) -> None:
        """plugins, include, blackboard, subtrees: what an included file contributes too."""
        if "plugins" in sections:
            self._plugins(path, *sections["plugins"][::2])
        if "include" in sections:
            self._includes(path, *sections["include"][::2])
        if "blackboard" in sections:
            self._each(*sections["blackboard"][::2], "blackboard", self._key_decl)
        if "subtrees" in sections:
            self._each(*sections["subtrees"][::2], "subtrees", self._subtree_def)

    def _files(
        self, path: Path, node: yaml.Node, loc: Loc, what: str, each: str
    ) -> list[tuple[str, Path, Loc]]:
        """``(text, resolved path, loc)`` of each entry of a list of paths relative to the
        file naming them; a bad entry is reported and skipped."""
        try:
            entries = sequence(node, loc, what)
        except Bad as bad:
            self.ctx.report(bad)
            return []
        out = []
        for item, iloc in entries:
            try:
                text = scalar_text(item, iloc, each)
            except Bad as bad:
                self.ctx.report(bad)
                continue
            if not text.strip():  # the folder of the file naming it: "is a directory"
                self.ctx.error(iloc.at(f"{each} is an empty path: name a file"))
                continue
            try:
                out.append((text, _named_file(path, text), iloc))
            except (RuntimeError, OSError):  # Python 3.11 raises RuntimeError for a loop
                self.ctx.error(iloc.at(_link_loop(each, text)))
        return out

    def _plugins(self, path: Path, node: yaml.Node, loc: Loc) -> None:
        for text, target, iloc in self._files(path, node, loc, "plugins", "a plugin"):
            if self._refused(text, target, iloc, "plugin file", self.permissions.plugin_files):
                self.ctx.unloaded_plugins.append(text)
                continue
            not_a_file = _not_a_plugin_file(path, text, target)
            if not_a_file is not None:
                self.ctx.unloaded_plugins.append(text)
                self.ctx.error(iloc.at(not_a_file))
                continue
            self.files.append(target)  # read like an include: run --watch watches it too
            registry, errors = self.ctx.registry.with_file(target)
            for error in errors:  # each class that did not register: the others did
                self.ctx.error(iloc.at(str(error)))
                if not error.imported:  # as a file not allowed: its nodes say it
                    self.ctx.unloaded_plugins.append(text)
            self.ctx.registry = registry

    def _includes(self, path: Path, node: yaml.Node, loc: Loc) -> None:
        for text, target, iloc in self._files(path, node, loc, "include", "an include"):
            if not self._include_entry(path, text, target, iloc):
                # what it would have defined is unknown: its uses say why (values.Context)
                self.ctx.unread_includes.append((text, iloc))

    def _include_entry(self, path: Path, text: str, target: Path, iloc: Loc) -> bool:
        """Read the file one include entry names, unless it may not or cannot be read
        (reported): False then. A cycle or a file read already is no loss: True."""
        if self._refused(text, target, iloc, "include", allowed=True):
            return False
        if target in self._include_stack:
            # named as diagnostics name them: a library's docking.yaml, and the shipped one
            cycle = self._include_stack[self._include_stack.index(target) :]
            chain = [self.display(p) for p in (*cycle, target)]
            self.ctx.error(iloc.at(f"include cycle: {' -> '.join(chain)}"))
            return True
        misnamed = _package_file_problem(text, target, self.permissions.wording)
        if misnamed is not None:
            self.ctx.error(iloc.at(misnamed))
            return False
        unreadable = _unreadable(target)
        if unreadable is not None:
            self.ctx.error(iloc.at(f"cannot read included file {path_written(text)}: {unreadable}"))
            return False
        if not target.is_file():
            self.ctx.error(iloc.at(_not_a_file(path, text, target, self._include_roots)))
            return False
        if self._again(target, text, iloc):
            return True
        self._included[target] = iloc
        return self._include(target, text, iloc)

    def _refused(self, text: str, target: Path, iloc: Loc, what: str, allowed: bool) -> bool:
        """``target`` may not be read, said at its entry: a plugin file not ``allowed``, or
        ``target`` (resolved: a link out is out) outside the top mission's folder tree, the
        shipped library and the ``--include-dir`` folders. An include and a plugin file
        alike: ``plugins: [/tmp/x.py]`` or ``../../x.py`` imported a file from anywhere once
        ``--allow-plugin-files`` was given for the mission's own folder."""
        wording, roots = self.permissions.wording, self._include_roots
        if allowed and any(target.is_relative_to(root) for root in roots):
            return False
        said = _outside_message(what, text, target, roots, wording) if allowed else None
        _say_refused(self.ctx, iloc, said, (text, wording, target))
        return True

    def _again(self, target: Path, text: str, iloc: Loc) -> bool:
        """``target`` was included already: read once. Named twice by one file, an error at
        the second include (its subtrees were "defined twice" at a line of the included file,
        the same line twice); reached again through another file (the mission and a library
        of its both include the docking library), left out without a word."""
        first = self._included.get(target)
        if first is None:
            return False
        if first.file == iloc.file:
            self.ctx.error(
                iloc.at(
                    f"included file {path_written(text)} is included twice (first at line "
                    f"{first.line})"
                )
            )
        return True

    def _include(self, target: Path, text: str, iloc: Loc) -> bool:
        """Read an included library's sections; False when it is no library (reported)."""
        read = self._compose(target, target, (text, iloc))
        if read is None:
            return False
        root, root_loc = read
        # a whole mission, not a library: said at the include, whatever else it holds (one
        # with a description: was three errors at lines of the included file, none here); a
        # library with a stray tree: is a library, its subtrees read, the tree: an error there
        if holds_some_of(root, ("mission", "tree")) and not holds_some_of(root, ("subtrees",)):
            self.ctx.error(iloc.at(
                f"included file {path_written(text)} is a mission (it has mission: or tree:), "
                f"not a library: an included file may hold only {', '.join(_INCLUDED_KEYS)}"
            ))  # fmt: skip
            return False
        sections = self._sections(
            root,
            root_loc,
            _INCLUDED_KEYS,
            not_a_mission=iloc.at(
                not_a_file_of(f"included file {path_written(text)}", "mission", _INCLUDED_KEYS)
            ),
            called="an included file",
            unknown_key=lambda key: (
                f"an included file may only hold {', '.join(_INCLUDED_KEYS)}; found {key!r}"
            ),
        )
        if sections is None:
            return False
        self._include_stack.append(target)
        _literal_section(self.ctx, sections)
        self._file_sections(target, sections)
        self._include_stack.pop()
        return True

    def _each(
        self,
        node: yaml.Node,
        loc: Loc,
        what: str,
        declare: Callable[[str, yaml.Node, Loc, Loc], None],
    ) -> None:
        """Each entry of a section (``blackboard``, ``subtrees``): a bad entry is reported
        and the others go on."""
        try:
            items = mapping(node, loc, what)
        except Bad as bad:
            self.ctx.report(bad)
            return
        for name, value, key_loc, vloc in items:
            try:
                declare(name, value, key_loc, vloc)
            except Bad as bad:
                self.ctx.report(bad)

    def _key_decl(self, name: str, node: yaml.Node, key_loc: Loc, loc: Loc) -> None:
        _new_name(name, key_loc, "blackboard key", "blackboard key", self.ctx.keys, "declared")
        try:
            key_decl(self.ctx, self.nodes.global_env, name, node, key_loc, loc)
        except Bad:  # declared wrongly: its uses are not reported again as an unknown key
            self.ctx.keys[name] = KeyDecl(name, ANY, key_loc, None, True, "")
            raise

    def _subtree_def(self, name: str, node: yaml.Node, key_loc: Loc, loc: Loc) -> None:
        try:
            self._new_subtree(name, node, key_loc, loc)
        except Bad:  # defined wrongly: its error is said once, here, not again at every use
            # as "unknown subtree" (a compiler's cascade); a name defined twice keeps its first
            self.ctx.subtrees.setdefault(
                name, SubtreeDef(name, key_loc, {}, None, loc, written_wrongly=True)
            )
            raise

    def _new_subtree(self, name: str, node: yaml.Node, key_loc: Loc, loc: Loc) -> None:
        _new_name(name, key_loc, "subtree name", "subtree", self.ctx.subtrees, "defined")
        if name in WORDS or name in self.ctx.registry:
            raise Bad(key_loc.at(f"subtree name {name!r} is already a node name"))
        fields = known_fields(node, loc, f"subtree {name!r}", _SUBTREE_FIELDS)
        params: dict[str, tuple[ValueType, Any, Loc]] = {}
        default_texts: dict[str, str] = {}
        default_at: dict[str, tuple[Loc, tuple[Loc, ...]]] = {}
        broken: set[str] = set()
        if "parameters" in fields:
            pnode, _, ploc = fields["parameters"]
            for pname, pvalue, pkloc, pvloc in mapping(pnode, ploc, "parameters"):
                try:
                    decl = param_decl(self.ctx, pvalue, pvloc, pname, pkloc)
                    vtype, default, has_default, _ = decl
                except Bad as bad:
                    self.ctx.report(bad)
                    broken.add(pname)  # not reported again at its uses and arguments
                    continue
                params[pname] = (vtype, default if has_default else None, pkloc)
                if has_default:
                    default_texts[pname] = _default_text(vtype, pvalue, default)
                    default_at[pname] = _default_at(pvalue, pvloc)
        local, initials = subtree_keys(self.ctx, fields, self.nodes.global_env, params, broken)
        if "tree" not in fields:
            self.ctx.error(loc.at(f"subtree {name!r} needs a tree:"))
            body, body_loc = None, loc
        else:
            body, _, body_loc = fields["tree"]
        self.ctx.subtrees[name] = SubtreeDef(
            name, key_loc, params, body, body_loc, broken=frozenset(broken),
            default_texts=default_texts, default_at=default_at, keys=local, initials=initials,
        )  # fmt: skip


def bind_parameters(
    ctx: Context,
    section: tuple[yaml.Node, Loc, Loc] | None,
    overrides: Mapping[str, str],
    root: Loc,
) -> dict[str, Bound]:
    """The mission's parameters bound to their values: ``-p`` overrides first, else each
    default; each wrong declaration or value reported once (a use of it reads "unknown")."""
    env: dict[str, Bound] = {}
    declared: dict[str, tuple[ValueType, Loc]] = {}
    broken: set[str] = set()  # declared wrongly: reported once, not at each use nor -p
    wording = ctx.wording  # how the caller sets a parameter
    names: list[str] = []  # every name declared, a wrongly declared one too
    if section is not None:
        items = _parameter_entries(ctx, section, env, broken)
        names = [name for name, *_ in items]
        for name, value, key_loc, vloc in items:
            try:
                vtype, default, has_default, _ = param_decl(ctx, value, vloc, name, key_loc)
            except Bad as bad:
                ctx.report(bad)
                env[name] = Bound(STR, UNKNOWN, "?")  # a use reads "unknown": no type check
                broken.add(name)
                continue
            declared[name] = (vtype, key_loc)
            if name in overrides:
                continue
            if not has_default:
                ctx.error(
                    key_loc.at(
                        f"parameter {name!r} has no default: give it with "
                        f"{wording.give(name + '=VALUE')}"
                    )
                )
                env[name] = Bound(vtype, UNKNOWN, "?")  # reported once, not at every use
                continue
            at, items_at = _default_at(value, vloc)
            env[name] = Bound(
                vtype,
                default,
                _default_text(vtype, value, default),
                default_at=at,
                default_items=items_at,
                wording=wording,
            )
    for name, text in overrides.items():
        if name not in broken:
            _bind_override(ctx, name, text, declared, env, root, names)
    return env


def _bind_override(
    ctx: Context,
    name: str,
    text: str,
    declared: Mapping[str, tuple[ValueType, Loc]],
    env: dict[str, Bound],
    root: Loc,
    names: list[str],
) -> None:
    """One value the caller set (``-p name=text``, ``params=``) bound in ``env``, or said
    wrong: a name the mission does not declare (``names``: every name it declares, one
    declared wrongly too, which ``declared`` leaves out: "declares: none" was said of a
    mission whose one parameter had a bad default), a value its type refuses."""
    wording = ctx.wording
    if name not in declared:
        ctx.error(
            root.at(
                f"unknown parameter {name!r} {wording.set_by_for(name)}"
                f"{closest(name, names)}; "
                f"the mission declares: {', '.join(names) or 'none'}"
            )
        )
        return
    vtype, key_loc = declared[name]
    try:
        given = _cli_value(text, vtype)
        value = vtype.parse(given)
    except UnitError as exc:
        where = f"parameter {name}={text} ({wording.set_from_for(name)})"
        ctx.error(key_loc.at(f"{where}: {exc}"))
        env[name] = Bound(vtype, UNKNOWN, "?")  # reported once, not at every use
        return
    # a percent's share as the percent it means (``-p low=0.2``: ``below 20%``); the origin
    # keeps what was typed, so the user finds it on their command line
    written = given if vtype.name == "percent" and isinstance(given, str) else text
    origin = f"{name}={text}, {wording.set_by_for(name)}"
    env[name] = Bound(vtype, value, percent_sign_kept(vtype, written), origin)


def known_fields(
    node: yaml.Node, loc: Loc, what: str, allowed: tuple[str, ...]
) -> dict[str, tuple[yaml.Node, Loc, Loc]]:
    """The mapping ``node`` as ``{key: (value, key loc, value loc)}``; :class:`Bad` at the
    first key not ``allowed`` (naming the closest allowed one)."""
    fields = {k: (v, kl, vl) for k, v, kl, vl in mapping(node, loc, what)}
    for key, (_, kl, _) in fields.items():
        if key not in allowed:
            raise Bad(kl.at(f"{what}: " + unknown("key", key, list(allowed))))
    return fields


def _parameter_entries(
    ctx: Context, section: tuple[yaml.Node, Loc, Loc], env: dict[str, Bound], broken: set[str]
) -> list[tuple[str, yaml.Node, Loc, Loc]]:
    """The parameters section's entries named by a name. A key that is none (``off:``, YAML
    1.1's false) is reported once and its uses read "unknown" (``env``, ``broken``): the
    other parameters stand (they were all "unknown" at each use)."""
    node, _, loc = section
    try:
        items, not_names = named_entries(node, loc, "parameters")
    except Bad as bad:
        ctx.report(bad)
        return []
    if not_names is not None:
        ctx.report(not_names)
        named = {name for name, *_ in items}
        for written in written_keys(node):
            if written not in named:
                env[written] = Bound(STR, UNKNOWN, "?")
                broken.add(written)
    return items


def param_decl(
    ctx: Context, node: yaml.Node, loc: Loc, name: str, name_loc: Loc
) -> tuple[ValueType, Any, bool, str]:
    """A parameter's declaration (the mission's or a subtree's): its type, default (when it
    has one: the third item) and doc; ``name_loc``, where its name is written. Raises
    :class:`Bad`."""
    if not _IDENT.match(name):
        raise Bad(name_loc.at(f"parameter name {name!r} must be {_snake_rule(name)}"))
    fields = known_fields(
        node, loc, f"parameter {name!r}", ("type", "default", "doc", "choices", "items")
    )
    if "type" not in fields:
        raise Bad(
            loc.at(f"parameter {name!r} needs a type (one of {', '.join(PARAMETER_TYPE_NAMES)})")
        )
    vtype = _declared_type(name, fields)
    doc = ""
    if "doc" in fields:
        doc = scalar_text(fields["doc"][0], fields["doc"][2], "doc")
    if "default" not in fields:
        return vtype, None, False, doc
    dnode, _, dloc = fields["default"]
    used = parameters_used(str(dnode.value)) if isinstance(dnode, yaml.ScalarNode) else []
    if used:  # no parameter is known where defaults are read: not "unknown parameter ${a}"
        whom = "itself" if used[0] == name else "a parameter"
        raise Bad(dloc.at(
            f"parameter {name}: a default cannot refer to {whom} (${{{used[0]}}}): write its "
            f"value; {ctx.wording.set_instead}"
        ))  # fmt: skip
    default = resolve(ctx, dnode, dloc, vtype, {}, f"parameter {name}")
    return vtype, default, True, doc


def _declared_type(name: str, fields: Mapping[str, tuple[yaml.Node, Loc, Loc]]) -> ValueType:
    """The type parameter ``name``'s declaration ``fields`` give: a name
    (:data:`PARAMETER_TYPES`), ``enum`` with its ``choices:``, or ``list`` with its
    ``items:`` type (a list parameter: ``for_each.in: "${legs}"``, given ``-p legs=[1m,
    2m]``). Raises :class:`Bad`."""
    tnode, _, tloc = fields["type"]
    written = plain(tnode, tloc)
    for option, (owner, meaning) in PARAMETER_TYPE_OPTIONS.items():
        if option in fields and written != owner:  # read by no other type: it was ignored
            raise Bad(fields[option][2].at(
                f"parameter {name!r}: {option} only goes with type: {owner} ({meaning}), not "
                f"with type: {written}: drop {option}, or write type: {owner}"
            ))  # fmt: skip
        if written == owner and option not in fields:
            raise Bad(tloc.at(f"parameter {name!r} of type {owner} needs {option}: "
                              f"{_OPTION_SAID[option]}"))  # fmt: skip
    if written == "enum":
        return enum(*_choices(*fields["choices"][::2]))
    if written == "list":
        inode, _, iloc = fields["items"]
        if isinstance(inode, yaml.MappingNode):  # records: items: {fields: {...}}
            record = known_fields(inode, iloc, f"parameter {name!r} items", ("fields",))
            if "fields" not in record:
                raise Bad(iloc.at(f"parameter {name!r}: items of records need fields: "
                                  "{NAME: TYPE, ...}, as a blackboard key's"))  # fmt: skip
            return list_of(record_declared(*record["fields"]))
        return list_of(_type_named(inode, iloc, LIST_ITEM_TYPES, "item type"))
    return _type_named(tnode, tloc, PARAMETER_TYPES, "type", also=("enum", "list"))


#: what each option of :data:`PARAMETER_TYPE_OPTIONS` is said to need when it is missing
_OPTION_SAID = {
    "choices": "[...], the words it may take",
    "items": f"TYPE, the type of each item (one of {', '.join(LIST_ITEM_TYPES)}), or "
    "{fields: {NAME: TYPE, ...}} for records",
}


def _type_named(
    node: yaml.Node, loc: Loc, types: Mapping[str, ValueType], what: str, also: tuple[str, ...] = ()
) -> ValueType:
    """The type of ``types`` that ``node`` names; :class:`Bad` naming the known ones (and
    ``also``, the names the caller reads itself) when it names none."""
    text = scalar_text(node, loc, what)
    if text in types:
        return types[text]
    names = [*types, *also]
    raise Bad(loc.at(f"unknown {what} {text!r}{closest(text, names)}; known types: "
                     f"{', '.join(names)}"))  # fmt: skip


def _choices(node: yaml.Node, loc: Loc) -> list[str]:
    """An enum parameter's ``choices``: a list of different words, at least one. Raises
    :class:`Bad` naming what was found (``no`` is YAML 1.1's false: say to quote it)."""
    items = sequence(node, loc, "choices")
    if not items:
        raise Bad(loc.at("choices is an empty list: list the words the parameter may take"))
    words: list[str] = []
    for item, iloc in items:
        value = plain(item, iloc)
        if isinstance(value, bool):
            raise Bad(iloc.at(
                f"choices must be a list of words; {item.value!r} was read as the boolean "
                f"{str(value).lower()} (YAML 1.1): quote it, '{item.value}'"
            ))  # fmt: skip
        if not isinstance(value, str):
            raise Bad(iloc.at(f"choices must be a list of words, got {kind_of(item)}"))
        if value in words:
            raise Bad(iloc.at(f"choice {value!r} is listed twice"))
        words.append(value)
    return words


def subtree_keys(
    ctx: Context,
    fields: Mapping[str, tuple[yaml.Node, Loc, Loc]],
    mission: Mapping[str, Bound],
    params: Mapping[str, tuple[ValueType, Any, Loc]],
    broken: set[str],
) -> tuple[dict[str, KeyDecl], dict[str, tuple[yaml.Node, Loc]]]:
    """A subtree's own ``blackboard:`` (among its definition's ``fields``), keys of each
    use's own (docs/missions.md, Subtrees), each entry declared as a mission's key is, a
    wrong one reported and the others read on: its keys by
    name, and the ``initial:`` of each that uses one of the subtree's ``params`` with its
    place, resolved at each use (``NodeParser``) with the values that use gives. Here those
    parameters are unknown; ``mission``'s are known."""
    keys: dict[str, KeyDecl] = {}
    initials: dict[str, tuple[yaml.Node, Loc]] = {}
    section = fields.get("blackboard")
    if section is None:
        return keys, initials
    env = {**mission, **{p: Bound(vtype, UNKNOWN, "?") for p, (vtype, _, _) in params.items()}}
    env.update((pname, Bound(STR, UNKNOWN, "?")) for pname in broken)
    node, _, loc = section
    try:
        items = mapping(node, loc, "blackboard")
    except Bad as bad:
        ctx.report(bad)
        return keys, initials
    for name, value, key_loc, vloc in items:
        try:
            _new_name(name, key_loc, "blackboard key", "blackboard key", keys, "declared")
            try:
                key_decl(ctx, env, name, value, key_loc, vloc, into=keys)
            except Bad:  # declared wrongly: not reported again at each read as unknown
                keys[name] = KeyDecl(name, ANY, key_loc, None, True, "")
                raise
        except Bad as bad:
            ctx.report(bad)
            continue
        inode = _initial_node(value)
        used = [p for text in _scalars(inode) for p in parameters_used(text)] if inode else []
        if inode is not None and any(pname in params for pname in used):
            initials[name] = (inode, keys[name].initial_loc or vloc)
    return keys, initials


def key_decl(
    ctx: Context,
    env: Mapping[str, Bound],
    name: str,
    node: yaml.Node,
    key_loc: Loc,
    loc: Loc,
    *,
    into: dict[str, KeyDecl] | None = None,
) -> None:
    """A blackboard key's declaration into ``into`` (``ctx.keys`` when None; a subtree's own
    keys otherwise); its initial value may use the mission's parameters, ``env``. Raises
    :class:`Bad`."""
    initial: Any = None
    has_initial = False
    initial_loc: Loc | None = None
    doc = ""
    if isinstance(node, yaml.ScalarNode):
        vtype = parse_type_name(node, loc, allow_mark=True)
    else:
        allowed = ("type", "fields", "initial", "doc")
        fields = known_fields(node, loc, f"blackboard key {name!r}", allowed)
        if "fields" in fields:
            vtype = record_declared(*fields["fields"])
        elif "type" in fields:
            vtype = parse_type_name(fields["type"][0], fields["type"][2], allow_mark=True)
        else:
            raise Bad(loc.at(f"blackboard key {name!r} needs a type (or fields)"))
        if "initial" in fields:
            inode, _, iloc = fields["initial"]
            initial = resolve(ctx, inode, iloc, vtype, env, f"initial value of {name}")
            has_initial, initial_loc = True, iloc
        if "doc" in fields:
            doc = scalar_text(fields["doc"][0], fields["doc"][2], "doc")
    keys = ctx.keys if into is None else into
    keys[name] = KeyDecl(name, vtype, key_loc, initial, has_initial, doc, initial_loc)


def _initial_node(node: yaml.Node) -> yaml.Node | None:
    """The value of a key declaration's ``initial:``, None when it has none."""
    if not isinstance(node, yaml.MappingNode):
        return None
    for knode, vnode in node.value:
        if isinstance(knode, yaml.ScalarNode) and knode.value == "initial":
            found: yaml.Node = vnode
            return found
    return None


def _scalars(node: yaml.Node) -> list[str]:
    """Every scalar's text in ``node`` (a record's fields, a list's items too)."""
    if isinstance(node, yaml.ScalarNode):
        return [str(node.value)]
    if isinstance(node, yaml.SequenceNode):
        return [text for item in node.value for text in _scalars(item)]
    if isinstance(node, yaml.MappingNode):
        return [text for _, value in node.value for text in _scalars(value)]
    return []


def record_declared(node: yaml.Node, _key_loc: Loc, loc: Loc) -> ValueType:
    """A record's ``fields: {distance: distance, turn: angle}``, each field a value type:
    one reading for a blackboard key's and a list parameter's items (``{type: list, items:
    {fields: {...}}}``: waypoints given with ``-p``). Raises :class:`Bad`."""
    return record_type(
        {fname: parse_type_name(fvalue, fvloc) for fname, fvalue, _, fvloc in
         mapping(node, loc, "fields")}
    )  # fmt: skip


def _served_by_packages(text: str, target: Path, registry: Registry) -> str | None:
    """The warning for a ``plugins:`` entry whose every declared behaviour (read from its
    source, not run) an installed package serves, when plugin files are not allowed: the
    entry is redundant, so the mission runs on the packages' behaviours, the file not
    loaded; None for any other entry. Decided: it was refused (exit 2) with "take it out",
    though nothing was missing; "or install the plugin as a package" before that told a
    user who had installed it to do so. With plugin files allowed the file is loaded, and
    its names clash with the packages' (docs/plugins.md, Two plugins, one name)."""
    if _module_named(text, target):
        return None
    names = names_declared_in(target)
    served = {name: registry.served_by_package(name) for name in names}
    if not names or not all(served.values()):
        return None
    packages = "; ".join(f"{name} by {origin}" for name, origin in served.items())
    return (
        f"plugin file {path_written(text)} not loaded, and need not be: installed plugins "
        f"serve what it declares ({packages}); take {path_written(text)} out of the "
        "mission's plugins:"
    )


def _say_refused(
    ctx: Context, iloc: Loc, said: str | None, plugin: tuple[str, Wording, Path]
) -> None:
    """An entry refused at ``iloc``: ``said`` (outside the folders it may be read from), or
    a plugin file not allowed, an error (:func:`_not_allowed`) unless installed packages
    serve all it declares: then a warning that it can go (:func:`_served_by_packages`), the
    file not loaded all the same."""
    text, wording, target = plugin
    served = None if said else _served_by_packages(text, target, ctx.registry)
    if served is not None:
        ctx.warn(iloc.at(served).as_warning())
    else:
        ctx.error(iloc.at(said or _not_allowed(text, wording, target)))


def _not_allowed(text: str, wording: Wording, target: Path) -> str:
    """Why a plugin file is not imported without the caller's permission, and how to give it;
    for a module's name, which no permission would import, that it is none
    (:func:`_module_named`). One an installed package serves whole is no error
    (:func:`_served_by_packages`): not here."""
    named = _module_named(text, target)
    if named:
        return named
    return (
        f"plugin file {path_written(text)} not loaded: a mission file cannot run code on its "
        f"own; allow its plugin files with {wording.allow_plugin_files} (or install the "
        "plugin as a package)"
    )


def _by_key(
    items: list[tuple[str, yaml.Node, Loc, Loc]], misspelt: tuple[str, ...]
) -> dict[str, tuple[yaml.Node, Loc, Loc]]:
    """A file's sections by key, a key that misspells one of ``misspelt`` the file lacks
    (``paramaters:``, ``Parameters:``: the "did you mean" its error says) read as that
    section, so that the typo's error is the only one: each ``${speed}`` of the tree was
    "unknown parameter" too, pointing away from it."""
    written = {key for key, *_ in items}
    sections: dict[str, tuple[yaml.Node, Loc, Loc]] = {}
    for key, value, key_loc, value_loc in items:
        meant = closest_name(key, misspelt) if key not in misspelt else None
        sections.setdefault(key if meant is None or meant in written else meant,
                            (value, key_loc, value_loc))  # fmt: skip
    return sections


def _outside_message(
    what: str, text: str, target: Path, roots: tuple[Path, ...], wording: Wording
) -> str:
    """Why an include (or plugin file) outside ``roots`` (the mission's folder, the shipped
    library, the include folders granted: resolved, in that order) is refused: where a file
    may be read from, and how to allow its folder, here or for every command. The fix was
    "--include-dir DIR" alone, and the user who had given it to ``validate`` met the
    refusal again at ``run``, ``eval`` and ``replay``."""
    mission_folder, granted = roots[0], roots[1 + len(SHIPPED_LIBRARY) :]
    folders = ", ".join(_shown_path(folder) for folder in granted) or "none"
    allow = wording.include_dir.replace("DIR", _shown_path(target.parent))
    every = (  # the command line reads these; a Python call is given its folders
        f", or for every command with {INCLUDE_PATH_VARIABLE} or {INCLUDE_DIRS_KEY} under "
        f"[tool.{PROJECT_TABLE}] in a {PROJECT_FILE} ({DOCUMENTED_AT})"
        if wording == COMMAND_LINE  # by value: eval's workers get a pickled copy
        else ""
    )
    return (
        f"{what} {path_written(text)} is outside the mission's folder "
        f"({_shown_path(mission_folder)}), the shipped library and the include folders granted "
        f"({folders}); allow its folder with {allow}{every}"
    )


def _package_file_problem(text: str, target: Path, wording: Wording) -> str | None:
    """Why an include that names a package's file (``PACKAGE:PATH``) names none, or None:
    a ``roomba-bt:`` name the shipped library does not hold (naming those it does), or
    another package's name (``makerspace-bt:lib/x.yaml``, unless a file of the mission's
    folder is called so): a package's files are reached only in the shipped library; a
    plugin package ships behaviours (an entry point), and a library of subtrees is a
    folder the mission is allowed to include from."""
    if text.startswith(SHIPPED_PREFIX):
        if in_shipped_library(target):
            return None
        return (
            f"included file {path_written(text)} is not in the shipped library; "
            f"it holds {', '.join(shipped_library_files()) or 'nothing'}"
        )
    package = other_package(text)
    if package is None or target.is_file():
        return None
    allow = wording.include_dir.replace("DIR", "FOLDER")
    return (
        f"included file {path_written(text)} names a file of package {package!r}: only the "
        f"shipped library is included by a package's name ({SHIPPED_PREFIX}PATH, such as "
        f"{DOCKING_LIBRARY}); a plugin package provides behaviours, not included files: put "
        f"the library in the mission's folder, or allow the FOLDER that holds it with {allow} "
        "and include it by its path"
    )


def _shown_path(folder: Path) -> str:
    """``folder`` (or a file) as a user passes it from here: relative to the current
    directory when inside it, else whole."""
    try:
        return str(folder.relative_to(Path.cwd().resolve())) or "."
    except (ValueError, OSError):  # elsewhere, or the current directory is gone
        return str(folder)


def _not_a_file(path: Path, text: str, target: Path, roots: Sequence[Path] = ()) -> str:
    """What an include names when it is no file: a directory, or nothing, with the file it
    most likely meant (``lib\\b.yaml`` written the Windows way, ``lib/B.yaml`` in the wrong
    case: both found on Windows, not here); else a file of its name in ``roots``, the
    folders the mission may include from (:func:`_same_name_in`): where it was moved?"""
    if target.is_dir():
        return (
            f"included file {path_written(text)} is a directory, not a file: name a .yaml file "
            "in it"
        )
    if target.exists():  # a pipe, a device: no file to read (it "was not found")
        return (
            f"included file {path_written(text)} is not a regular file; an include is a .yaml file"
        )
    slashed = text.replace("\\", "/")
    if _WINDOWS_ABSOLUTE.match(text):
        return (
            f"included file {path_written(text)} not found: an absolute Windows path names a file "
            "on one computer only; write the path relative to the including file, with /"
        )
    windows_way = _written_with_backslashes("included file", path.parent, text)
    if windows_way is not None:
        return windows_way
    meant = _near_path(path.parent, slashed)
    if meant is not None:
        why = ("names are case-sensitive" if meant.lower() == slashed.lower() else
               "a space at an end of a name" if meant == slashed.strip() else
               "the name ends in .yaml")  # fmt: skip
        return (
            f"included file {path_written(text)} not found; did you mean {path_written(meant)}? "
            f"({why})"
        )
    looked = _shown_path(target)  # where "../lib/x.yaml" led, unless the text says it
    looked_for = f"looked for {looked}: " if looked != text else ""
    moved = [  # each as this file's include would write it; the shipped one said below
        Path(os.path.relpath(p, path.parent)).as_posix()
        for p in _same_name_in(roots, target.name)
        if shipped_name(p) is None
    ]
    if moved:
        found = " or ".join(path_written(each) for each in moved)
        said = f"; moved? a file of that name is {found}"
    elif target.name in _SHIPPED_NAMES:  # the shipped library, maybe meant
        said = f"; the shipped docking library is {DOCKING_LIBRARY}"
    else:
        said = ""
    return (
        f"included file {path_written(text)} not found ({looked_for}paths are relative to the "
        f"including file{said})"
    )


#: the shipped library's file names: an include of one not found may mean it
_SHIPPED_NAMES = frozenset(("docking.yaml", "undock.yaml"))


def _same_name_in(roots: Iterable[Path], name: str, limit: int = 3) -> list[Path]:
    """Up to ``limit`` files named ``name`` in ``roots`` (the folders a mission may include
    from, :func:`granted_files`): where an included file not found may have been moved."""
    same = (path for path in granted_files(roots) if path.name == name)
    return list(itertools.islice(same, limit))


def _written_with_backslashes(what: str, folder: Path, text: str) -> str | None:
    """``lib\\b.yaml`` naming a file that ``lib/b.yaml`` names, in ``folder``: found on
    Windows, not here. The message, with the path it meant; None when the path has no
    backslash or the slashed one names no file either. Said alike of an include and a
    plugin file: a plugin said only "not found"."""
    slashed = text.replace("\\", "/")
    if slashed == text or not (folder / slashed).is_file():
        return None
    return (
        f"{what} {path_written(text)} not found; did you mean {path_written(slashed)}? "
        "(paths are written with /, on Windows too)"
    )


#: ``C:\\Users\\...`` or ``D:/lab/...``: a path on one Windows computer
_WINDOWS_ABSOLUTE = re.compile(r"[A-Za-z]:[\\/]")


def _near_path(folder: Path, text: str) -> str | None:
    """The file ``text`` (relative to ``folder``, written with /) most likely meant when it
    names none: each step found again with another case (``S55_lib/Moves.yaml``, found on
    Windows and macOS), without a space at its ends, or the last one with ``.yaml`` added;
    None when a step has no such match."""
    here = folder
    found: list[str] = []
    steps = text.split("/")
    for index, step in enumerate(steps):
        if step in ("", ".", "..") or (here / step).exists():
            here /= step
            found.append(step)
            continue
        last = index == len(steps) - 1
        try:
            names = sorted(p.name for p in here.iterdir()) if here.is_dir() else []
        except OSError:  # a folder the user cannot list: nothing to offer
            return None
        same = [name for name in names
                if name.lower() == step.lower() or name == step.strip()
                or (last and name == f"{step}.yaml")]  # fmt: skip
        if not same:
            return None
        here /= same[0]
        found.append(same[0])
    return "/".join(found) if here.is_file() else None


def _not_a_plugin_file(path: Path, text: str, target: Path) -> str | None:
    """Why ``target``, named ``text`` in ``plugins:`` of the file ``path``, cannot be
    imported, or None for a regular file: unreadable, a directory, something else that
    exists (``/dev/zero``, a pipe: it was "not found"), or nothing there (``sub\\my.py``
    for ``sub/my.py``, as an include says)."""
    unreadable = _unreadable(target)
    if unreadable is not None:
        return f"cannot read plugin file {path_written(text)}: {unreadable}"
    if target.is_file():
        return None
    if target.is_dir():
        return f"plugin file {path_written(text)} is a directory, not a file: name a .py file in it"
    if target.exists():
        return (
            f"plugin file {path_written(text)} is not a regular file (a device or a pipe); name "
            "a .py file"
        )
    return (
        _written_with_backslashes("plugin file", path.parent, text)
        or _module_named(text, target)
        or f"plugin file {path_written(text)} not found (paths are relative to the file naming it)"
    )


#: ``json.decoder``, ``rbt_good``: a dotted Python name, no path (no ``/``, no ``.py``)
_MODULE_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*(\.[A-Za-z_][A-Za-z0-9_]*)*")


def _module_named(text: str, target: Path) -> str | None:
    """What a ``plugins:`` entry not found says when it reads as a Python module's name
    (``plugins: [mypkg.behaviours]``): the list takes files only, and an installed package's
    behaviours come by its entry point with no entry here (docs/plugins.md, Package it).
    "plugin file 'json.decoder' not found" left the writer looking for a file. None for
    anything that reads as a path, or names a file (``target``, where it resolves)."""
    if text.endswith(".py") or _MODULE_NAME.fullmatch(text) is None or target.exists():
        return None
    return (
        f"plugin file {path_written(text)} not found: {path_written(text)} looks like a "
        "module name, and plugins: takes files (a path to a .py file, relative to the file "
        "naming it); an installed package's behaviours are found by its entry point in the "
        "group roomba_bt.behaviours, with no plugins: entry (roomba-bt docs plugins, Package it; "
        "roomba-bt behaviours lists them)"
    )


def _unreadable(target: Path) -> str | None:
    """Why the file system will not say what ``target`` is (a folder on the way the user
    cannot enter: ``stat`` fails with "Permission denied"), None when it answers."""
    try:
        target.stat()
    except (FileNotFoundError, NotADirectoryError):  # "not found", as is_file() says
        return None
    except OSError as exc:  # not a traceback: "cannot read" where the path is written
        return str(exc.strerror or exc)
    return None


def are_world_keys(keys: Collection[str]) -> bool:
    """A file's top-level ``keys`` are a simulator world's (sim/world.py), not a mission's:
    ``rooms:`` and no ``tree:`` (no mission has a ``rooms`` section). The one rule of the
    loader and of ``validate``, which checks such a file as a world."""
    return "rooms" in keys and "tree" not in keys


def _is_world(root: yaml.Node) -> bool:
    """A mapping whose keys are a world's (:func:`are_world_keys`)."""
    if not isinstance(root, yaml.MappingNode):
        return False
    return are_world_keys({key.value for key, _ in root.value if isinstance(key, yaml.ScalarNode)})


def _a_library(resolved: Path, path: Path) -> str:
    """What ``show`` or ``run`` says of a library file (``subtrees:``, no ``tree:``), such
    as the shipped ``roomba-bt:lib/docking.yaml``: "a mission needs a tree" read as if the
    file were broken, when it is whole and only meant to be included."""
    shipped = shipped_name(resolved)
    # a file's path as given is the current folder's, where an include is its mission's:
    # include: [common/lib/legs.yaml] in missions/x.yaml was "not found"
    where = ""
    if not shipped:
        where = " from a mission in the current folder; an include is relative to its file"
    return (
        "this file is a library of subtrees (subtrees:, no tree:), to be included, not run: "
        f"include it in a mission (include: [{shipped or path}]{where}) and use them there "
        "with subtree: NAME (validate checks a library on its own)"
    )


def _new_name(
    name: str,
    key_loc: Loc,
    called: str,
    what: str,
    taken: Mapping[str, KeyDecl] | Mapping[str, SubtreeDef],
    verb: str,
) -> None:
    """A name a file declares: snake_case, and not declared before (here or in an include)."""
    if not _IDENT.match(name):
        raise Bad(key_loc.at(f"{called} {name!r} must be {_snake_rule(name)}"))
    if name in taken:
        first = taken[name].loc
        raise Bad(key_loc.at(f"{what} {name!r} {verb} twice (first at {first.file}:{first.line})"))


def _snake_rule(name: str) -> str:
    """What a name refused by :data:`_IDENT` must be, as its error says it: ``snake_case``,
    with the spelling meant (:func:`_snake_hint`); for a name with a letter that is not
    ASCII (``vitesse_\u00e9``, snake_case by any reading), that the letters must be ASCII,
    the first other one named: "must be snake_case" said nothing of what was wrong."""
    odd = next((char for char in name if not char.isascii()), None)
    if odd is None:
        return f"snake_case{_snake_hint(name)}"
    plain = "".join(
        char for char in unicodedata.normalize("NFKD", name) if not unicodedata.combining(char)
    )
    hint = _snake_hint(plain) if plain != name else ""
    if not hint and plain != name and _IDENT.match(plain):
        hint = f" (write {plain!r})"
    return (
        f"ASCII snake_case (a-z, 0-9 and _, not starting with a digit): {named_character(odd)} "
        f"is not ASCII{hint}"
    )


def _snake_hint(name: str) -> str:
    """`` (write 'my_speed')`` for ``MySpeed``, ``my-speed`` or ``my speed``; "" when no
    snake_case spelling of it is plain."""
    words = re.sub(r"(?<=[a-z0-9])(?=[A-Z])", "_", name.strip())
    snake = re.sub(r"[-\s]+", "_", words).lower()
    return f" (write {snake!r})" if snake != name and _IDENT.match(snake) else ""


def _named_file(path: Path, text: str) -> Path:
    """The file an include or plugin entry ``text`` of the mission ``path`` names, resolved;
    a symbolic link loop raises (``RuntimeError`` on Python 3.11, ``OSError`` later)."""
    if text.startswith(SHIPPED_PREFIX):
        return (SHIPPED_DIR / text[len(SHIPPED_PREFIX) :]).resolve()
    return (path.parent / text).resolve()


def _link_loop(each: str, text: str) -> str:
    """An entry naming a symbolic link loop: it was "internal error (RuntimeError)" at 1:1."""
    return (
        f"{each} {path_written(text)} is a symbolic link loop (it leads back to itself), not a "
        "file: name the file itself"
    )


def _default_at(node: yaml.Node, loc: Loc) -> tuple[Loc, tuple[Loc, ...]]:
    """Where the ``default:`` of a parameter's declaration ``node`` (at ``loc``) is written,
    and, a list, where each of its items is (none otherwise)."""
    for key, value in getattr(node, "value", []):
        if getattr(key, "value", None) == "default":
            at = loc.child(value, "default")
            if not isinstance(value, yaml.SequenceNode):
                return at, ()
            return at, tuple(at.child(item, f"[{i}]") for i, item in enumerate(value.value))
    return loc, ()


def _default_text(vtype: ValueType, declaration: yaml.Node, default: Any) -> str:
    """A parameter's default as its declaration writes it (``10min``, not ``600 s``): the
    text its uses insert and its nodes' names show; a text's default is its value, whose
    ``$$`` is already one ``$``."""
    if vtype is STR:
        return str(default)
    for key, value in getattr(declaration, "value", []):
        if getattr(key, "value", None) == "default" and isinstance(value, yaml.ScalarNode):
            return percent_sign_kept(vtype, str(value.value))
        if getattr(key, "value", None) == "default" and isinstance(value, yaml.SequenceNode):
            return _flow_list(value)
    return str(default)


def _flow_list(node: yaml.SequenceNode) -> str:
    """A list as YAML's flow style writes it, its items as written: ``[1m, 2m]`` (a list
    parameter's default, as ``-p legs=[1m, 2m]`` gives one), a record's fields too:
    ``[{distance: 1m, turn: 90deg}]``."""
    return f"[{', '.join(_flow_item(item) for item in node.value)}]"


def _flow_item(node: yaml.Node) -> str:
    """One item of :func:`_flow_list`: a scalar as written, a record as its fields."""
    if isinstance(node, yaml.ScalarNode):
        return str(node.value)
    if isinstance(node, yaml.MappingNode):
        fields = (f"{_flow_item(key)}: {_flow_item(value)}" for key, value in node.value)
        return "{" + ", ".join(fields) + "}"
    return "..."


def _cli_percent(text: str) -> str:
    """A percent given as ``-p``, as the text its uses insert and its nodes' names show: a
    plain number below 1 is a share of the whole, as ``--battery 0.2`` reads it, written as
    the percent it means (``0.2``, ``.2`` and ``2e-1`` are ``20%``: ``below 0.2`` read as
    0.2 %), so the two options of one command agree; a plain number is one as ``--battery``
    reads it (Python's number syntax, so ``1e-1`` as well as ``.2``). 1 and
    above stay refused, since ``1`` could mean 1% or all of it, and the message says both
    ways to write it; a negative number, or one with its unit, is left to the type, as a
    file's value is: there a number's meaning is written once, with its unit."""
    try:
        number = Decimal(text.strip())  # exact: 0.123456789 is 12.3456789%, not rounded
    except InvalidOperation:
        return text
    if not number.is_finite() or number <= 0:
        return text
    if number < 1:
        return f"{_plain_number(number * 100)}%"
    raise UnitError(
        f"{text.strip()!r} has no unit; write {_plain_number(number)}% (a plain number below 1 "
        "is a share of the whole: 0.2 is 20%)"
    )


def _cli_list(text: str) -> object:
    """A list given as ``-p legs=[1m, 2m]``: YAML's flow list, each item as the file's
    would be read (``[C4 200ms, rest 100ms]`` for ``notes``). Anything else is left to the
    type, which says a list is written in brackets."""
    try:
        return yaml.safe_load(text)
    except yaml.YAMLError as exc:
        problem = getattr(exc, "problem", None) or "not YAML"
        raise UnitError(f"{text!r} is no list YAML reads ({problem}): write [a, b]") from None


def _plain_number(number: Decimal) -> str:
    """``number`` as people write it: ``20``, not ``20.0`` or ``2E+1``; ``12.3456789``."""
    digits = format(number, "f")
    return digits.rstrip("0").rstrip(".") if "." in digits else digits


def _cli_value(text: str, vtype: ValueType) -> object:
    """A ``-p name=value`` string as the type wants it: numbers and booleans as YAML reads
    them, a percent's share as :func:`_cli_percent` reads it, everything else as written."""
    if vtype.name == "percent":
        return _cli_percent(text)
    if vtype.item is not None or vtype.name == "notes":
        return _cli_list(text)
    if vtype.name in ("int", "float", "bool"):
        octal_or_base_60 = yaml11_number_problem(text, in_a_file=False)
        if octal_or_base_60 is not None:  # -p c=0200 sent 128: refused as in a file
            raise UnitError(octal_or_base_60)
        try:
            return yaml.safe_load(text)
        except yaml.YAMLError:
            return text
        except ValueError:  # an integer too long to read: "internal error" at 1:1
            raise UnitError(too_many_digits(text)) from None
    return text
