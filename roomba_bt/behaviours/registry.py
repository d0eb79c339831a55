"""One registry of behaviours: the built-ins and the plugins go through the same door.

Plugins are distributions that declare an entry point in the group ``roomba_bt.behaviours``::

    [project.entry-points."roomba_bt.behaviours"]
    dirt_detect = "roomba_bt_dirt:DirtDetect"

The value may name a behaviour class, a sequence of them, or a module (every declared
behaviour class defined in it). Entry points are read with :mod:`importlib.metadata` and
imported lazily: the first time a mission, ``validate``, ``behaviours`` or ``schema`` asks
the registry for its contents, never at ``import roomba_bt``. A plugin that fails to import,
or declares itself wrongly, becomes a :class:`PluginError` naming the plugin and the cause;
every other behaviour still loads. A mission may also name a module by path
(``plugins: [./my_behaviour.py]``): :meth:`Registry.with_file` loads it into a copy.

A mission names a behaviour by its name alone (``dirt_detect``) or by its package and name
(``roomba-bt-dirt:dirt_detect``, as ``include: [roomba-bt:lib/docking.yaml]`` names a file of
a package): the package is the installed distribution's name as pip takes it, and
``roomba-bt`` names the built-ins. The name alone is the behaviour's while no one else
declares it; two plugins that both declare it, a plugin's behaviour that takes a built-in's
name or a word of the language, are each reached by the package's spelling
(:meth:`Registry.get`), and the name alone is refused (two plugins) or stays the built-in's
and the language's.
"""

from __future__ import annotations

import importlib
import importlib.util
import inspect
import logging
import os
import re
import reprlib
import sys
import traceback
import types
from collections.abc import Iterable, Iterator
from dataclasses import dataclass, replace
from importlib.metadata import Distribution, EntryPoint, distributions, entry_points
from pathlib import Path

import py_trees

from roomba_bt.behaviours.base import RobotBehaviour
from roomba_bt.behaviours.declare import Declaration, DeclarationError
from roomba_bt.behaviours.language import RESERVED
from roomba_bt.behaviours.units import closest
from roomba_bt.robot.safety import (
    code_failure,
    failure_said,
    interrupts_told_apart,
    note_interrupted_in,
)

ENTRY_POINT_GROUP = "roomba_bt.behaviours"
#: the package a mission writes before ``:`` to name a built-in (``roomba-bt:drive``), as
#: ``include: [roomba-bt:lib/docking.yaml]`` names a shipped file
CORE_PACKAGE = "roomba-bt"

#: a plugin's import traceback is logged here at DEBUG: ``roomba-bt -v`` shows it
log = logging.getLogger("roomba_bt.plugins")


class NameClash(DeclarationError):
    """A behaviour declares a name another class (a built-in or another plugin's) took
    first: not a mistake in its declaration, a clash between the two. ``existing``: the
    declaration that holds the name."""

    def __init__(self, name: str, existing: Declaration, message: str | None = None) -> None:
        super().__init__(
            message
            or f"name {name!r} is already taken by {_qualname(existing.cls)} ({existing.origin})"
        )
        self.name = name
        self.existing = existing

    def clash(
        self, spelled: str | None = None, other: str | None = None, *, file: str | None = None
    ) -> str:
        """What a plugin's class that lost the name is told: not that it declared itself
        wrongly, but who else declares the name, what becomes of it, and how a mission
        names each (``spelled``: this class's ``package:name``, ``other``: the first's; None
        for a plugin file, which has no package; ``file``: the plugin file this class is
        in, where nothing is installed to uninstall, and the first may be in it too)."""
        holder = f"{class_where(self.existing.cls)}"
        if self.existing.origin == "builtin":
            reach = f"a mission reaches this one as {spelled!r}" if spelled else "this one is not"
            return (
                f"declares {self.name!r}, the name of the built-in {holder}: a name clash; the "
                f"built-in is used and {reach} (or rename it)"
            )
        between = "two plugins"
        if spelled and other:
            said = f"; write {other!r} or {spelled!r} to choose"
        elif file is None:
            said = " until one is uninstalled or renames its behaviour"
        elif file == self.existing.origin:
            between, said = "two classes of one plugin file", " until one of them is renamed"
        else:
            said = " until one is renamed, or its file left out of the mission's plugins:"
        return (
            f"declares {self.name!r}, as {holder} of plugin {self.existing.origin} does: a name "
            f"clash between {between}; a mission that uses {self.name!r} is refused (exit 2)"
            f"{said}"
        )


class _LanguageWord(DeclarationError):
    """A behaviour declares a word of the mission language (``retry``): the word stays the
    language's; the behaviour is reached by its package's spelling, if it has one."""

    def __init__(self, name: str) -> None:
        super().__init__(f"name {name!r} is a word of the mission language")
        self.name = name


def _language_word_refused(cls: type, name: str, spelled: str | None) -> str:
    """Why a plugin's class that declares a word of the language is not used under it: what
    was found, why it is refused, what to do (it read "the word is the language's, and it is
    not used (or rename it)"). ``spelled``: its package's spelling, if it has one."""
    reach = (
        f"this behaviour is reached only as {spelled!r}"
        if spelled
        else "this behaviour cannot be used"
    )
    return (
        f"{class_where(cls)} declares the name {name!r}, which is a word of the mission language: "
        f"{name!r} in a mission always means the language's own, so {reach}; rename it in its "
        "@declare"
    )


@dataclass(frozen=True, slots=True)
class PluginError:
    """A plugin that could not be loaded: which one, and why. ``imported`` is False when its
    module did not import at all (it raised): none of its behaviours exist, and a mission's
    unknown node names the file as not loaded."""

    plugin: str
    cause: str
    imported: bool = True
    #: the behaviour names it was to provide: the name a refused class declares, and an entry
    #: point's own name (``dirt_detect = "roomba_bt_dirt:DirtDetect"``); a mission's unknown
    #: node of one of them gets this error as its note (mission/nodes.py), not every broken
    #: plugin's
    names: tuple[str, ...] = ()
    #: False for a name two classes want (a clash, a word of the language): nothing is
    #: broken, each behaviour is still reached (by ``package:name``, or the name stays the
    #: built-in's). True when behaviours the plugin was to provide are missing: it did not
    #: import, or a class declared itself wrongly. ``schema`` and ``behaviours`` fail on these
    #: (a schema without them marks every mission that uses them wrong in an editor)
    loses_behaviours: bool = True
    #: what was refused alone, as said (the name the refused class declares, quoted, or an
    #: entry point's list item that is no behaviour class), when its plugin's other classes
    #: loaded: a half-loaded plugin, whose loaded behaviours missions use; "" when none of
    #: it loaded
    refused: str = ""
    #: the installed package (:func:`package_name` of its distribution) the error is of;
    #: "" for a plugin file's: ``package:name`` of a broken package says why it names
    #: nothing (:meth:`Registry.why_unknown`), not that no such package is installed
    package: str = ""

    def __str__(self) -> str:
        return f"plugin {self.plugin}: {self.cause}"

    @property
    def lost(self) -> str:
        """What no command has for this error, said exactly: a half-loaded plugin's one
        refused behaviour (0.2.0's ``behaviours`` said "its behaviours are not listed" and
        then listed the others), or every behaviour of a plugin that did not load."""
        if self.refused:
            return f"{self.refused} (refused alone: the plugin's other behaviours loaded)"
        return f"the behaviours of plugin {self.plugin}"


def _plain_py_trees_hint(cls: object) -> str:
    """What a plain py_trees behaviour given as ``behaviours=`` can be used in instead: a
    mission's YAML names only declared behaviours, but a tree built in Python runs one as it
    is (its user came from py_trees and meant to keep the class as written)."""
    if isinstance(cls, type) and issubclass(cls, py_trees.behaviour.Behaviour):
        return (
            f"; {cls.__qualname__} is a plain py_trees behaviour, which a mission's YAML cannot "
            "name, but a tree built in Python runs as it is: "
            "roomba_bt.TreeMission(root, name) (roomba-bt docs runtime, From Python: a tree "
            "built by hand)"
        )
    return ""


class Registry:
    """Behaviour name -> :class:`Declaration`. Long on purpose: every way a mission names a
    behaviour (a name alone, ``package:name``, ``roomba-bt:name``) and every clash between
    them resolve here; the package index (``_packages``, ``_package_of``) is the seam to
    split along when it grows."""

    def __init__(self, *, entry_point_group: str | None = ENTRY_POINT_GROUP) -> None:
        self._declarations: dict[str, Declaration] = {}
        #: entry-point plugins' declarations whose origin does not name the distribution
        #: yet, by name: the entry point that names it (:meth:`_named`)
        self._unnamed: dict[str, EntryPoint] = {}
        self._errors: list[PluginError] = []
        #: names two plugins both declare: who declares each, ``(class and origin, its
        #: package:name or None)``; which of them a mission meant is not known (:meth:`clash`)
        self._contested: dict[str, list[tuple[str, str | None]]] = {}
        #: built-in names a plugin declares too, who does; the built-in is used (:meth:`clash`)
        self._shadowed: dict[str, list[tuple[str, str | None]]] = {}
        #: every entry-point plugin's behaviour by package and name, with the entry point
        #: that names its origin (:meth:`_qualified`): those that hold their name alone, and
        #: those that lost it to a built-in, another plugin or the language
        self._packages: dict[str, dict[str, tuple[Declaration, EntryPoint]]] = {}
        #: each entry-point plugin's class -> its package (:func:`package_name`)
        self._package_of: dict[type, str] = {}
        self._group = entry_point_group
        self._loaded = entry_point_group is None
        #: plugins the mission was made with that are not here, each said (:meth:`expecting`)
        self.absent: tuple[str, ...] = ()

    # ------------------------------------------------------------------ registration
    def register(
        self,
        cls: type[RobotBehaviour],
        origin: str = "builtin",
        *,
        validated: bool = False,
        said_as: str | None = None,
        entry: EntryPoint | None = None,
    ) -> Declaration:
        """Register one behaviour class; raises :class:`DeclarationError` if it declares
        itself wrongly or takes a name already taken. ``validated``: its declaration is known
        to pass :meth:`Declaration.validate`, which is not run again (the built-ins: the test
        suite validates every one, and running it for the 45 of them was 1.2 M instructions
        of every process's first mission). ``said_as``: where it is from as a clash names
        it, when not ``origin`` (an entry point's with its distribution: the other side of a
        clash is named so, and which package to uninstall must be read from both).
        ``entry``: an installed plugin's entry point, whose package (:func:`package_name` of
        its distribution) reaches it as ``package:name`` even where its name alone is not
        its own."""
        declaration = getattr(cls, "declaration", None)
        if not isinstance(declaration, Declaration) or declaration.cls is not cls:
            raise DeclarationError(
                f"{_qualname(cls)} has no declaration of its own: decorate it with "
                "@declare(name, kind=..., params=...)"
            )
        if not validated:
            declaration.validate()
        if declaration.origin != origin:  # a built-in's own declaration says "builtin"
            declaration = replace(declaration, origin=origin)
        if entry is not None:
            self._add_qualified(_package(entry), declaration, entry)
        if declaration.name in RESERVED:
            raise _LanguageWord(declaration.name)
        existing = self._declarations.get(declaration.name)
        if existing is not None and existing.cls is not cls:
            existing = self._named(existing)
            who = (f"{_qualname(cls)} ({said_as or origin})", self.spelled(declaration))
            self._note_clash(declaration.name, existing, who)
            raise NameClash(declaration.name, existing)
        self._declarations[declaration.name] = declaration
        self._unnamed.pop(declaration.name, None)
        return declaration

    def _add_qualified(self, package: str, declaration: Declaration, entry: EntryPoint) -> None:
        """``package:name`` for a plugin's behaviour; one package that declares a name twice
        (two entry points, two classes) keeps the first and says so (:meth:`clash`)."""
        self._package_of[declaration.cls] = package
        held = self._packages.setdefault(package, {})
        first = held.get(declaration.name)
        if first is not None and first[0].cls is not declaration.cls:
            spelled = f"{package}:{declaration.name}"
            self._contested[spelled] = [
                (f"{_qualname(first[0].cls)} ({first[0].origin})", None),
                (f"{_qualname(declaration.cls)} ({declaration.origin})", None),
            ]
            return
        held[declaration.name] = (declaration, entry)

    def spelled(self, declaration: Declaration) -> str | None:
        """``package:name``: how a mission names an installed plugin's behaviour whatever
        else declares its name (``roomba-bt:name`` a built-in); None for a plugin file's."""
        package = self._package_of.get(declaration.cls)
        if package is not None:
            return f"{package}:{declaration.name}"
        held = self._declarations.get(declaration.name)
        builtin = held is not None and held.cls is declaration.cls and held.origin == "builtin"
        return f"{CORE_PACKAGE}:{declaration.name}" if builtin else None

    def _note_clash(self, name: str, existing: Declaration, other: tuple[str, str | None]) -> None:
        """A second class declares ``name`` (``other``: the class and where it is from, and
        its ``package:name``)."""
        if existing.origin == "builtin":
            self._shadowed.setdefault(name, []).append(other)
            return
        first = (f"{_qualname(existing.cls)} ({existing.origin})", self.spelled(existing))
        self._contested.setdefault(name, [first]).append(other)

    def clash(self, name: str) -> tuple[str, str] | None:
        """("error", why) for a name two plugins declare, ("warning", why) for a built-in's
        name a plugin declares too, else None: what a mission that uses it is told (a plugin
        that lost the name was only said by ``roomba-bt behaviours``). A ``package:name``
        has no clash, but where one package declares the name twice."""
        self._ensure_loaded()
        claimants = self._contested.get(name)
        if claimants is not None:
            spellings = [spelled for _, spelled in claimants if spelled]
            said = " and ".join([", ".join(who for who, _ in claimants[:-1]), claimants[-1][0]])
            if ":" in name:
                return "error", f"{name!r} is declared twice in its package, by {said}"
            unspelled = [who for who, spelled in claimants if not spelled]  # a plugin file's
            choose = f"write {' or '.join(repr(s) for s in spellings)} to choose"
            if unspelled:  # a file has no package: only a rename reaches it
                files = ", ".join(unspelled)
                reach = f"{choose} an installed one; " if spellings else ""
                choose = (
                    f"{reach}rename the behaviour of {files} (a plugin file has no package:name)"
                )
            return "error", (
                f"{name!r} is declared by {_count(len(claimants))} plugins, {said}: which one "
                "is meant "
                f"is not known ({choose})"
            )
        shadows = self._shadowed.get(name)
        if shadows is not None:
            who = ", ".join(who for who, _ in shadows)
            theirs = [repr(spelled) for _, spelled in shadows if spelled]
            reach = (
                f": write {CORE_PACKAGE + ':' + name!r} to say so, {' or '.join(theirs)} for "
                "the plugin's"
                if theirs
                else " (rename the plugin's behaviour)"
            )
            return "warning", (
                f"a plugin declares {name!r} too, {who}; the built-in is used{reach}"
            )
        return None

    def register_provider(
        self,
        provider: object,
        origin: str,
        *,
        said_as: str | None = None,
        entry: EntryPoint | None = None,
    ) -> list[Declaration]:
        """Register what an entry point or a plugin file provides (class, sequence of
        classes, or module); each class that declares itself wrongly, and each item of a list
        that is no behaviour class, becomes a recorded :class:`PluginError` naming it and
        where it is, and the others still load (not one bad class dropping the rest of its
        module, nor one bad item of a list its good classes, as a class of the list that
        declared itself wrongly is refused alone). ``said_as``: the
        origin the errors name, when it is not ``origin``; ``entry``: the entry point that
        provides them (its name is among each error's :attr:`PluginError.names`; its
        distribution, the package a mission may name them by)."""
        said = said_as or origin
        named = () if entry is None else (entry.name,)
        try:
            classes, unfit = _provided(provider)
        except DeclarationError as exc:  # nothing of it is a behaviour class
            self._errors.append(PluginError(said, f"declares itself wrongly: {exc}", names=named))
            return []
        for item, wrong in unfit:  # a list's item that is no class: refused alone
            self._errors.append(PluginError(said, wrong, names=named, refused=item))
        registered: list[Declaration] = []
        for cls in classes:
            # what a mission calls it: the name its declaration gives, refused or not
            declared = cls.__dict__.get("declaration")
            names = (declared.name, *named) if isinstance(declared, Declaration) else named
            try:
                if not issubclass(cls, RobotBehaviour):  # @declare on a plain class
                    raise _NotABehaviour(
                        f"class {cls.__qualname__} is decorated with @declare but is not a "
                        "behaviour: derive it from roomba_bt.behaviours.Action or Condition"
                    )
                registered.append(self.register(cls, origin, said_as=said, entry=entry))
            except NameClash as exc:  # it declared nothing wrongly: two classes want a name
                spelled = self.spelled(declared) if isinstance(declared, Declaration) else None
                file = origin if entry is None else None  # a plugin file's: none installed
                told = exc.clash(spelled, self.spelled(exc.existing), file=file)
                clash = f"{class_where(cls)} {told}"
                self._errors.append(PluginError(said, clash, names=names, loses_behaviours=False))
            except _LanguageWord as exc:  # the word is the language's; the class may be reached
                spelled = self.spelled(declared) if isinstance(declared, Declaration) else None
                word = _language_word_refused(cls, exc.name, spelled)
                self._errors.append(PluginError(said, word, names=names, loses_behaviours=False))
            except _NotABehaviour as exc:
                refused = repr(names[0]) if isinstance(declared, Declaration) else ""
                wrong = f"{class_where(cls)}: {exc}"
                self._errors.append(PluginError(said, wrong, names=names, refused=refused))
            except DeclarationError as exc:
                # a class of a list with no declaration of its own is refused alone too
                alone = class_where(cls) if len(classes) > 1 else ""
                refused = repr(names[0]) if isinstance(declared, Declaration) else alone
                wrong = f"{class_where(cls)} declares itself wrongly: {exc}"
                self._errors.append(PluginError(said, wrong, names=names, refused=refused))
        return registered

    # ------------------------------------------------------------------ lazy plugin loading
    def _ensure_loaded(self) -> None:
        if self._loaded:
            return
        self._loaded = True
        with interrupts_told_apart():  # a plugin's raise KeyboardInterrupt, from a Ctrl-C
            for ep in sorted(group_entry_points(self._group or ""), key=lambda e: e.name):
                self._load_entry_point(ep)

    def load_entry_point(self, ep: EntryPoint) -> list[Declaration]:
        """Import an entry point and register what it provides; a failure becomes a
        recorded :class:`PluginError` naming it."""
        return [self._named(declaration) for declaration in self._load_entry_point(ep)]

    def _load_entry_point(self, ep: EntryPoint) -> list[Declaration]:
        """:meth:`load_entry_point`, its declarations' origins not yet naming the
        distribution: that name is its METADATA's ``Name``, read by the e-mail parser,
        whose first import alone costs about 2.6 M instructions (more than importing and
        registering the example plugin), and a mission run or ``validate`` never shows a
        plugin's origin. :meth:`_named` writes it in when a declaration is handed out; an
        error names the distribution at once."""
        try:
            provider = ep.load()
        except BaseException as exc:  # any import-time failure of third-party code
            if not code_failure(exc):  # a Ctrl-C (not the plugin's KeyboardInterrupt)
                _cut_short(exc, f"importing plugin {_origin(ep)}", _package_of(ep))
                raise
            failed = (
                _missing_attribute(ep, exc)
                or _missing_module(ep, exc)
                or _import_failed(exc, _package_of(ep), _origin(ep))
            )
            self._errors.append(
                PluginError(
                    _origin(ep), failed, imported=False, names=(ep.name,), package=_package(ep)
                )
            )
            return []
        since = len(self._errors)
        registered = self.register_provider(
            provider, _origin(ep, named=False), said_as=_origin(ep), entry=ep
        )
        package = _package(ep)  # its errors are its package's (why_unknown)
        self._errors[since:] = [replace(e, package=package) for e in self._errors[since:]]
        for declaration in registered:
            self._unnamed[declaration.name] = ep
        return registered

    def _named(self, declaration: Declaration) -> Declaration:
        """``declaration`` as handed out: an entry-point plugin's with the origin that names
        its distribution (:meth:`_load_entry_point`), written in on the first read."""
        ep = self._unnamed.pop(declaration.name, None)
        if ep is None:
            return declaration
        declaration = replace(declaration, origin=_origin(ep))
        self._declarations[declaration.name] = declaration
        return declaration

    def with_file(self, path: Path) -> tuple[Registry, list[PluginError]]:
        """A copy of this registry plus the behaviours of the module at ``path``, and what
        went wrong loading it: one error if it did not import, else one for each of its
        classes that did not register (the others did)."""
        copy = self.copy()
        origin = str(path)
        module_name = _FILE_MODULE + "".join(c if c.isalnum() else "_" for c in str(path.resolve()))
        module = sys.modules.get(module_name)
        stamp = file_version(path)
        # imported once per version of the file: a mission reloaded (run --watch) after its
        # plugin file changed gets the new code, an unchanged one the module it had
        if module is None or getattr(module, "__roomba_bt_stamp__", stamp) != stamp:
            try:
                spec = importlib.util.spec_from_file_location(module_name, path)
                if spec is None or spec.loader is None:
                    raise ImportError(f"cannot load {path} as a Python module")
                module = importlib.util.module_from_spec(spec)
                module.__dict__["__roomba_bt_stamp__"] = stamp
                sys.modules[module_name] = module
                with interrupts_told_apart():
                    spec.loader.exec_module(module)
            except BaseException as exc:  # sys.exit() in it: not ours to exit
                sys.modules.pop(module_name, None)
                if not code_failure(exc):  # a Ctrl-C (not the plugin's KeyboardInterrupt)
                    _cut_short(exc, f"importing plugin {origin}", [path.resolve()])
                    raise
                if isinstance(exc, OSError) and _is_the_file(exc, path):
                    failed = f"cannot be read: {exc.strerror or exc}; {PLUGIN_FILE_WANTED}"
                else:
                    failed = _import_failed(exc, [path.resolve()], origin)
                return copy, [PluginError(origin, failed, imported=False)]
        before = len(copy._errors)
        copy.register_provider(module, origin)
        return copy, copy._errors[before:]

    def with_behaviours(
        self, classes: Iterable[type[RobotBehaviour]], origin: str = "the program"
    ) -> Registry:
        """A copy of this registry with ``classes`` registered too: behaviours a program
        defines itself (``load_mission(..., behaviours=[FarEnough])``), usable in its YAML by
        their declared names. Raises :class:`DeclarationError` naming the class for one that
        is not a declared behaviour, or whose name a built-in or a plugin holds already
        (a program's behaviour never replaces one: rename it)."""
        copy = self.copy()
        if isinstance(classes, type) or not isinstance(classes, Iterable):
            raise TypeError(
                f"behaviours= takes a list of behaviour classes, such as behaviours=[MyAction], "
                f"not {classes!r}"
            )
        for cls in classes:
            if not (isinstance(cls, type) and issubclass(cls, RobotBehaviour)):
                raise DeclarationError(
                    f"behaviours=[..., {cls!r}]: a behaviour class is one derived from "
                    "roomba_bt.behaviours.Action or Condition and decorated with "
                    f"@declare(name, ...){_plain_py_trees_hint(cls)}"
                )
            try:
                copy.register(cls, origin)
            except NameClash as clash:
                holder = clash.existing
                whose = "the built-in" if holder.origin == "builtin" else f"{holder.origin}'s"
                raise NameClash(clash.name, holder, (
                    f"behaviours=[{cls.__qualname__}]: {class_where(cls)} declares {clash.name!r}, "
                    f"the name of {whose} {_qualname(holder.cls)}; a program's behaviour does "
                    f"not replace it: declare another name, @declare('my_{clash.name}', ...)"
                )) from None  # fmt: skip
            except DeclarationError as wrong:
                raise DeclarationError(
                    f"behaviours=[{cls.__qualname__}]: {class_where(cls)} declares itself wrongly: "
                    f"{wrong}"
                ) from None
        return copy

    def copy(self) -> Registry:
        self._ensure_loaded()
        other = Registry(entry_point_group=None)
        other._declarations = dict(self._declarations)
        other._unnamed = dict(self._unnamed)
        other._errors = list(self._errors)
        other._contested = {name: list(who) for name, who in self._contested.items()}
        other._shadowed = {name: list(who) for name, who in self._shadowed.items()}
        other._packages = {package: dict(held) for package, held in self._packages.items()}
        other._package_of = dict(self._package_of)
        other.absent = self.absent
        other._group = self._group  # loaded already: named only by why_unknown
        return other

    def expecting(self, absent: Iterable[str]) -> Registry:
        """A copy that knows plugins the mission was made with are not here (``absent``,
        each said: ``plugin roomba-bt-lab 0.1.0, not installed``, a record's header's:
        runtime/provenance.py): an unknown node is most likely one of theirs, and is offered
        no "did you mean" a built-in that does something else (wall_follow for the plugin's
        wall_follow_for, which ends by distance)."""
        copy = self.copy()
        copy.absent = tuple(absent)
        return copy

    # ------------------------------------------------------------------ queries
    def may_have_meant(self, word: str) -> tuple[list[PluginError], bool]:
        """The plugins that did not load whose behaviour ``word`` may have been, and whether
        one declares it: those that declare the name (a class refused), else those that did
        not import at all (any name could have been theirs; one that imported and declared
        nothing had no name to give). A mission's "unknown node" and ``behaviours NAME`` note
        them; not every broken plugin on the machine, nor one whose error merely contains
        the word."""
        errors = self.errors
        named = [e for e in errors if word in e.names]
        return (named, True) if named else ([e for e in errors if not e.imported], False)

    def get(self, name: str) -> Declaration | None:
        """The declaration a mission's word names: a behaviour's name alone, or
        ``package:name`` (:meth:`_qualified`)."""
        if ":" in name:
            return self._qualified(name)
        found = self._declarations.get(name)
        if found is None:
            self._ensure_loaded()
            found = self._declarations.get(name)
        return found if found is None or not self._unnamed else self._named(found)

    def _qualified(self, word: str) -> Declaration | None:
        """``package:name``: a built-in (``roomba-bt:drive``, the declaration as its name
        alone gives it) or an installed plugin's behaviour, under the name the mission wrote
        (a plugin's ``drive`` is no built-in to the checks that know a built-in by name, and
        ``show`` says which it is)."""
        self._ensure_loaded()
        package, _, name = word.partition(":")
        package = package_name(package)
        if package == CORE_PACKAGE:
            found = self._declarations.get(name)
            return found if found is not None and found.origin == "builtin" else None
        held = self._packages.get(package, {}).get(name)
        if held is None:
            return None
        declaration, entry = held
        return replace(declaration, name=f"{package}:{name}", origin=_origin(entry))

    def served_by_package(self, name: str) -> str | None:
        """The installed plugin that serves the behaviour ``name`` (``'nw' (roomba_bt_nw,
        from roomba-bt-nw)``), None when none does (a built-in's name, a plugin file's, or
        no behaviour at all): a mission's ``plugins:`` entry the package took over can go."""
        self._ensure_loaded()
        for held in self._packages.values():
            if name in held:
                return _origin(held[name][1])
        return None

    def qualified(self) -> list[tuple[str, Declaration]]:
        """Every ``package:name`` a mission may write, the built-ins' (``roomba-bt:drive``)
        and each installed plugin's, with its declaration (:meth:`get`'s): what the JSON
        Schema lists beside the names alone."""
        self._ensure_loaded()
        words = [f"{CORE_PACKAGE}:{d.name}" for d in self._declarations.values()
                 if d.origin == "builtin"]  # fmt: skip
        words += [f"{package}:{name}" for package, held in self._packages.items() for name in held]
        found = [(word, self.get(word)) for word in sorted(words)]
        return [(word, declaration) for word, declaration in found if declaration is not None]

    def why_unknown(self, word: str) -> str | None:
        """Why ``package:name`` names nothing: no such package (the installed ones named),
        or the package has no such behaviour (a near name, else its behaviours); None for
        a name alone."""
        if ":" not in word:
            return None
        self._ensure_loaded()
        written, _, name = word.partition(":")
        package = package_name(written)
        if package == CORE_PACKAGE:
            builtins = [n for n, d in self._declarations.items() if d.origin == "builtin"]
            near = closest(name, builtins)
            return f"{CORE_PACKAGE} has no built-in behaviour {name!r}{near}"
        held = self._packages.get(package)
        broken = [e for e in self._errors if e.package == package and e.loses_behaviours]
        named = [e for e in broken if name in e.names]
        if named:  # installed, and broken: its error, not "no such package"
            return f"package {package!r} did not load {name!r}: {named[0]}"
        unimported = [e for e in broken if not e.imported]
        if unimported:  # which behaviours it has is not known
            return f"package {package!r} did not load (none of its behaviours): {unimported[0]}"
        if held is None:
            if self._group is not None and _installed_without_entry_point(written):
                return (
                    f"package {written!r} is installed but has no entry point in the group "
                    f"{self._group}, so none of its behaviours is found: add "
                    f'[project.entry-points."{self._group}"] to its pyproject.toml (a line '
                    'NAME = "its_module") and install it again (roomba-bt docs plugins, '
                    '"Package it")'
                )
            installed = ", ".join(sorted(self._packages)) or "none"
            return (
                f"no installed plugin package is called {written!r} (installed: {installed}; "
                f"{CORE_PACKAGE!r} names the built-ins)"
            )
        near = closest(name, list(held)) or f" (it has: {', '.join(sorted(held))})"
        return f"package {package!r} has no behaviour {name!r}{near}"

    def __contains__(self, name: object) -> bool:
        return isinstance(name, str) and self.get(name) is not None

    def names(self) -> list[str]:
        self._ensure_loaded()
        return sorted(self._declarations)

    def __iter__(self) -> Iterator[Declaration]:
        self._ensure_loaded()
        return iter([self._named(self._declarations[n]) for n in sorted(self._declarations)])

    @property
    def errors(self) -> list[PluginError]:
        self._ensure_loaded()
        return list(self._errors)

    @property
    def plugins_loaded(self) -> bool:
        """Whether the installed plugins were looked for (on first use, :meth:`get`): a
        command that did not has none of their errors to say, and need not scan for them."""
        return self._loaded

    @property
    def broken(self) -> list[PluginError]:
        """The errors of plugins whose behaviours are missing
        (:attr:`PluginError.loses_behaviours`): what ``schema`` and ``behaviours`` refuse to
        pass over in silence."""
        return [error for error in self.errors if error.loses_behaviours]


def group_entry_points(group: str) -> list[EntryPoint]:
    """``importlib.metadata.entry_points(group=group)``: the same entry points in the same
    order, from the same distributions (in the order found on ``sys.path``, the first of each
    name), but only a distribution whose ``entry_points.txt`` has a ``[group]`` line is parsed.
    ``entry_points`` parses every distribution's entry points to keep a group's: with the
    test extras installed that was a third of the plugin scan, about 6 of 19 M instructions.

    The ``[group]`` text is necessary, not sufficient (the parser strips a line and its
    brackets, so a section named ``group`` has that text); a distribution that has it is
    parsed and its entry points selected as ``entry_points`` selects them. Where the standard
    library no longer names distributions as ``entry_points`` does (``_normalized_name``), the
    function is ``entry_points`` itself."""
    if not _NAMES_DISTRIBUTIONS:
        return list(entry_points(group=group))
    header = f"[{group}]"
    seen: set[str] = set()
    found: list[EntryPoint] = []
    for dist in distributions():
        name: str = dist._normalized_name  # type: ignore[attr-defined]
        if name in seen:  # a distribution of this name came earlier on the path: it wins
            continue
        seen.add(name)
        text = dist.read_text("entry_points.txt")
        if text is not None and header in text:
            found.extend(dist.entry_points.select(group=group))
    return found


#: whether distributions have the name ``entry_points`` tells them apart by
_NAMES_DISTRIBUTIONS = hasattr(Distribution, "_normalized_name")


def package_name(name: str) -> str:
    """A distribution's name as ``package:name`` spells it: pip's normal form (PEP 503:
    lower case, each run of ``-``, ``_`` and ``.`` one ``-``), so ``Roomba_BT.Dirt`` is
    ``roomba-bt-dirt``, the spelling ``pip`` and ``roomba-bt behaviours`` show."""
    return re.sub(r"[-_.]+", "-", name).lower()


def _package(ep: EntryPoint) -> str:
    """The package a mission names an entry point's behaviours by: its distribution's name
    (:func:`package_name`), read off the ``.dist-info`` folder's name where the standard
    library has it (``_normalized_name``: the METADATA's e-mail parser is not loaded for
    it, :meth:`Registry._load_entry_point`); the entry point's own name when it has no
    distribution (one made in Python)."""
    if ep.dist is None:
        return package_name(ep.name)
    stem = getattr(ep.dist, "_normalized_name", None)
    return package_name(stem if isinstance(stem, str) else ep.dist.name)


def _installed_without_entry_point(name: str) -> bool:
    """Whether a distribution of this name is installed (it has no entry point of the
    group, or :meth:`Registry.why_unknown` would have found it): a plugin whose author
    left out its entry point, not a package that is missing."""
    from importlib.metadata import PackageNotFoundError, distribution

    try:
        distribution(name)
    except (PackageNotFoundError, ValueError):
        return False
    return True


def _count(n: int) -> str:
    return {2: "two", 3: "three"}.get(n, str(n))


def file_version(path: Path) -> tuple[int, int] | None:
    """The file's version as a reload sees it (modification time in ns, size); None if
    unreadable. A plugin file is imported again when it changes; the monitor's ``--watch``
    reloads a mission when one of its files does."""
    try:
        st = path.stat()
    except OSError:
        return None
    return (st.st_mtime_ns, st.st_size)


def _origin(ep: EntryPoint, *, named: bool = True) -> str:
    """Where an entry point's behaviours come from, as a declaration's origin and a plugin
    error say: ``'dirt' (roomba_bt_dirt, from roomba-bt-dirt)``; without the distribution
    when it has none, or ``named`` is False (:meth:`Registry._load_entry_point`)."""
    source = f", from {ep.dist.name}" if named and ep.dist else ""
    return f"{ep.name!r} ({ep.value}{source})"


def names_declared_in(path: Path) -> list[str]:
    """The behaviour names a plugin file declares as written in its source
    (``@declare("near_wall", ...)``, ``declare_like(Parent, "name")``), read without
    importing it: a file the caller did not allow to run may still be looked at, to say
    that an installed package serves what it would have. Empty when it cannot be read or
    parsed, or names none as a literal."""
    import ast

    try:
        tree = ast.parse(path.read_bytes())
    except (OSError, SyntaxError, ValueError):
        return []
    names = []
    for node in ast.walk(tree):
        if not isinstance(node, ast.Call):
            continue
        func = node.func
        called = func.id if isinstance(func, ast.Name) else getattr(func, "attr", "")
        args = node.args[1:] if called == "declare_like" else node.args
        if called not in ("declare", "declare_like") or not args:
            continue
        first = args[0]
        if isinstance(first, ast.Constant) and isinstance(first.value, str):
            names.append(first.value)
    return names


def class_where(cls: type) -> str:
    """``Level (badmod/__init__.py:12)``: a class and where it is defined, when known."""
    try:
        file = inspect.getsourcefile(cls)
        line = inspect.getsourcelines(cls)[1]
    except (OSError, TypeError):
        return cls.__qualname__
    return f"{cls.__qualname__} ({file}:{line})"


#: the prefix of the module name a plugin file is imported as (:meth:`Registry.with_file`)
_FILE_MODULE = "roomba_bt_mission_plugin_"


def _qualname(cls: object) -> str:
    """``roomba_bt_dirt.DirtDetect``; a plugin file's class by its name alone, which its
    origin (the file) follows: its module's name is the file's path mangled
    (``roomba_bt_mission_plugin__tmp_lab_mine_py.MySense``), no name a user wrote."""
    module = getattr(cls, "__module__", "?")
    qualname = getattr(cls, "__qualname__", repr(cls))
    return qualname if str(module).startswith(_FILE_MODULE) else f"{module}.{qualname}"


#: what a plugin file that is there and cannot be read is said to want, as a mission file
#: says it (it was "failed to import: PermissionError: [Errno 13] ...", Python's words for
#: what is no failure of the plugin's code)
PLUGIN_FILE_WANTED = "wanted: a Python file this user may read"


def _is_the_file(exc: OSError, path: Path) -> bool:
    """Whether ``exc`` is the system refusing to read the plugin file itself (not an
    ``OSError`` its code raised while it ran, such as a calibration file it opened)."""
    if exc.filename is None:
        return False
    try:
        return Path(os.fsdecode(exc.filename)).resolve() == path.resolve()
    except (OSError, TypeError, ValueError):
        return False


def _import_failed(exc: BaseException, home: list[Path], origin: str) -> str:
    """What a plugin's failed import says: the exception and the file:line where it raised
    in the plugin's own code (``home``: its file, or its package's folders), as a behaviour's
    run-time error does; the traceback is logged at DEBUG (``roomba-bt -v`` shows it)."""
    log.debug("plugin %s failed to import:\n%s", origin, "".join(traceback.format_exception(exc)))
    where = _raised_at(exc, home)
    return f"failed to import: {_cause(exc)}" + (f" (at {where})" if where else "")


def _missing_attribute(ep: EntryPoint, exc: BaseException) -> str | None:
    """What an entry point whose module imported but lacks the attribute it names says
    (``attr = "bad_attr:NoSuchClass"``): where the entry point is written, and the
    module's behaviour classes (a did-you-mean, else the list); None for any other failure.
    It said ``AttributeError: module 'bad_attr' has no attribute 'NoSuchClass'`` alone."""
    module = sys.modules.get(ep.module)
    if not isinstance(exc, AttributeError) or not ep.attr or module is None:
        return None
    first = ep.attr.split(".")[0]
    if hasattr(module, first):  # raised by the module's own code, or deeper in the path
        return None
    classes = [cls.__name__ for cls in _classes_of(module)]
    offered = closest(first, classes)
    if not offered:
        listed = ", ".join(classes[:5]) + (", ..." if len(classes) > 5 else "")
        offered = f"; its behaviour classes: {listed}" if classes else "; it has no behaviour class"
    return (
        f"the entry point names {ep.value}, but module {ep.module!r} has no attribute "
        f"{first!r}{offered} ({_written_at(ep)})"
    )


def _missing_module(ep: EntryPoint, exc: BaseException) -> str | None:
    """What an entry point whose module is not there says (``typo = "roomba_bt_brokn"``):
    where the entry point is written, as :func:`_missing_attribute` does; None for any other
    failure (a module the plugin itself imports and lacks is its own import's failure). It
    said ``failed to import: ModuleNotFoundError: No module named 'roomba_bt_brokn'``."""
    missing = getattr(exc, "name", None) if isinstance(exc, ModuleNotFoundError) else None
    if not missing or not (ep.module == missing or ep.module.startswith(f"{missing}.")):
        return None
    written = _written_at(ep)
    return f"the entry point names {ep.value}, but there is no module {missing!r} ({written})"


def _written_at(ep: EntryPoint) -> str:
    """``written in roomba-bt-lab's pyproject.toml: [project.entry-points...] lab = "..."``:
    where a user fixes an entry point that names what is not there."""
    written = f'[project.entry-points."{ep.group}"] {ep.name} = "{ep.value}"'
    where = f"in {ep.dist.name}'s pyproject.toml" if ep.dist else "in its distribution's metadata"
    return f"written {where}: {written}"


def _cut_short(exc: BaseException, what: str, home: list[Path]) -> None:
    """Note on a Ctrl-C's interrupt ``exc`` that it cut ``what`` short, and where in the
    plugin's own code (``home``) it was (:func:`~roomba_bt.robot.safety.note_interrupted_in`)."""
    where = _raised_at(exc, home)
    note_interrupted_in(exc, what + (f" (at {where})" if where else ""))


def cut_short_in(exc: BaseException, what: str, cls: type) -> None:
    """:func:`_cut_short` for code of the class ``cls`` (a behaviour built, set up): where
    in its file's folder the interrupt ``exc`` came."""
    try:
        home = [Path(inspect.getsourcefile(cls) or "").resolve().parent]
    except (OSError, TypeError):
        home = []
    _cut_short(exc, what, home)


def _raised_at(exc: BaseException, home: list[Path]) -> str | None:
    """The innermost frame of ``exc``'s traceback in a file under ``home``; for a syntax
    error there, its line. None if the plugin's own code is not on it (the entry point names
    a module that does not exist)."""
    for frame, line in reversed(list(traceback.walk_tb(exc.__traceback__))):
        if _within(frame.f_code.co_filename, home):
            return f"{frame.f_code.co_filename}:{line}"
    if isinstance(exc, SyntaxError) and exc.filename and _within(exc.filename, home):
        return f"{exc.filename}:{exc.lineno}"
    return None


def _within(filename: str, home: list[Path]) -> bool:
    if filename.startswith("<"):  # <frozen importlib._bootstrap>, <string>
        return False
    try:
        file = Path(filename).resolve()
    except (OSError, RuntimeError):
        return False
    return any(file == place or file.is_relative_to(place) for place in home)


def _package_of(ep: EntryPoint) -> list[Path]:
    """Where an entry point's code is: the folders of its top-level package (or its
    module's file), found without importing it; empty when not found."""
    top = ep.module.partition(".")[0]
    try:
        spec = importlib.util.find_spec(top)
    except (ImportError, ValueError):
        return []
    if spec is None:
        return []
    if spec.submodule_search_locations:
        return [Path(place).resolve() for place in spec.submodule_search_locations]
    return [Path(spec.origin).resolve()] if spec.origin else []


def _cause(exc: BaseException) -> str:
    """The exception in one line: a message of several lines (a plugin's own ``raise
    RuntimeError(...)``) would print as lines of their own under ``roomba-bt: warning:``,
    one of them looking like a line of the command's output."""
    if isinstance(exc, SystemExit):  # its exit code would have passed for one of ours
        return f"it called sys.exit({exc.code!r})"
    if not isinstance(exc, Exception):  # KeyboardInterrupt: its own, not a Ctrl-C
        return failure_said(exc)
    return " ".join(f"{type(exc).__name__}: {exc}".split())


class _NotABehaviour(DeclarationError):
    """A module's class decorated with @declare that is no behaviour: said on its own, the
    module's other classes still load."""


#: an item of an entry point's list that is no behaviour class: (the item as said, why)
Unfit = tuple[str, str]


def _provided(provider: object) -> tuple[list[type], list[Unfit]]:
    """The classes an entry point or a plugin file provides: behaviour classes, and the
    classes decorated with @declare that are not behaviours (each is an error of its own,
    :meth:`Registry.register_provider`); and each item of a list (or tuple) that is neither,
    said (:func:`_unfit_items`), refused alone. Raises :class:`DeclarationError` when it
    provides no class, or something else."""
    unfit: list[Unfit] = []
    if isinstance(provider, list | tuple):
        provider, unfit = _unfit_items(provider)
    classes = list(_classes_of(provider))
    if not classes and unfit:  # nothing of the list loads: the entry is refused whole
        raise DeclarationError("; ".join(why for _, why in unfit))
    if not classes:
        raise DeclarationError("it provides no behaviour class (decorated with @declare)")
    return classes, unfit


def _unfit_items(items: list[object] | tuple[object, ...]) -> tuple[list[type], list[Unfit]]:
    """A list's classes that are behaviours or say they are (decorated with @declare), and
    each other item, as said (``Helper (lab.py:12)``, ``'not a class'``) with why it is
    refused: its place in the list, what it is, what a list holds."""
    classes: list[type] = []
    unfit: list[Unfit] = []
    for place, item in enumerate(items, 1):
        if isinstance(item, type) and (
            issubclass(item, RobotBehaviour) or "declaration" in item.__dict__
        ):
            classes.append(item)
            continue
        if isinstance(item, type):
            said, wrong = (
                f"class {item.__qualname__}",
                (
                    f"class {class_where(item)}, derives from neither "
                    "roomba_bt.behaviours.Action nor Condition"
                ),
            )
        else:
            said = reprlib.repr(item)
            wrong = f"{said} (a {type(item).__name__}), is no class"
        unfit.append((said, (
            f"item {place} of its list, {wrong}: the list holds behaviour classes (derived "
            "from Action or Condition, each decorated with @declare)"
        )))  # fmt: skip
    return classes, unfit


def _classes_of(provider: object) -> Iterable[type]:
    if isinstance(provider, types.ModuleType):
        return [
            obj
            for _, obj in inspect.getmembers(provider, inspect.isclass)
            if obj.__module__ == provider.__name__ and "declaration" in obj.__dict__
        ]
    if isinstance(provider, type):
        if not issubclass(provider, RobotBehaviour):
            raise DeclarationError(f"{_qualname(provider)} is not a RobotBehaviour subclass")
        return [provider]
    if isinstance(provider, list | tuple):  # its classes (:func:`_unfit_items`)
        return list(provider)
    raise DeclarationError(
        f"the entry point names {provider!r}: expected a behaviour class, a list of them, "
        "or a module"
    )


def builtin_registry() -> Registry:
    """A registry with only the built-in behaviours (no entry points)."""
    from roomba_bt.behaviours.actions import ACTIONS
    from roomba_bt.behaviours.cleaning import CLEANING
    from roomba_bt.behaviours.conditions import CONDITIONS
    from roomba_bt.behaviours.coverage_map import COVERAGE
    from roomba_bt.behaviours.docking import DOCKING
    from roomba_bt.behaviours.homing import HOMING
    from roomba_bt.behaviours.panel import PANEL
    from roomba_bt.behaviours.wall import WALL_FOLLOWING

    registry = Registry(entry_point_group=None)
    # validated by test_every_builtin_is_registered_with_a_valid_declaration, not each start
    builtins = (*ACTIONS, *PANEL, *WALL_FOLLOWING, *CONDITIONS, *DOCKING, *CLEANING, *COVERAGE)
    for cls in (*builtins, *HOMING):
        registry.register(cls, "builtin", validated=True)
    return registry


_DEFAULT: Registry | None = None


def default_registry() -> Registry:
    """The process-wide registry: built-ins now, entry-point plugins on first use."""
    global _DEFAULT
    if _DEFAULT is None:
        registry = builtin_registry()
        registry._group = ENTRY_POINT_GROUP
        registry._loaded = False
        _DEFAULT = registry
    return _DEFAULT
