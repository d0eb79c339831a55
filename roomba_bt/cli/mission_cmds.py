"""``roomba-bt validate``, ``show``, ``missions``, ``behaviours`` and ``schema``: the mission
tools.

None of them opens a port. ``validate`` prints every error of every file as
``file:line:col: message [yaml.path]`` and exits 0 if all are valid, 2 if not.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import sys
import weakref
from pathlib import Path
from typing import TYPE_CHECKING, Any

from roomba_bt.cli import raise_lost_interrupt
from roomba_bt.cli.arguments import (
    add_command,
    add_param_option,
    add_permission_options,
    add_profile_option,
    baud_rate,
    given_once,
    mission_file,
    output_with_suffix,
    parse_params,
    permissions,
)
from roomba_bt.cli.language_words import (
    EVERY_WORD,
    every_word,
    language_word,
    word_facts,
    word_markdown,
)
from roomba_bt.cli.profile_choice import (
    BadSetting,
    chosen_profile,
    environment_profile,
    mission_near,
    resolved_profile,
)
from roomba_bt.cli.validate_report import FORMATS, Checked
from roomba_bt.oi.profiles import get_profile
from roomba_bt.printable import ANY_CONTROL, TEXT_LIMIT, escaped, shortened, yaml_written
from roomba_bt.runtime.summary import INTERNAL_ERROR_SAID, ExitCode

if TYPE_CHECKING:
    from roomba_bt.behaviours.declare import Declaration, Param
    from roomba_bt.behaviours.registry import PluginError, Registry
    from roomba_bt.mission.compiler import MissionText
    from roomba_bt.mission.diagnostics import Diagnostic


def register(sub: Any) -> None:
    """The five commands that read missions without running them; over 60 lines on purpose,
    long only by their help texts (strings, not the functions' docstrings, so that
    ``python -OO`` keeps them)."""
    validate = add_command(
        sub,
        "validate",
        validate_command,
        f"""check mission files before anything moves

        Check each FILE: names, parameters, units, ranges, subtrees, includes, blackboard keys, OI
        modes of every actuator, and the sensor stream budget. Every error is printed once as
        file:line:col: message, one in an included file with the include chain that reached
        it, then each FILE's verdict (ok, or failed and why). Exit 0 if all are valid, 2 if
        not; with --strict, 7 if warnings alone fail a file;
        {INTERNAL_ERROR_SAID}.
        """,
    )
    validate.add_argument(
        "files", nargs="+", metavar="FILE",
        help="a mission file, a shipped mission's name, or a world file (rooms:, no tree:), "
        "checked as --world reads it",
    )  # fmt: skip
    _common(validate)
    validate.add_argument(
        "--strict", action="store_true",
        help="fail on warnings too (the Full-mode drive with no cliff check, ...): exit 7 "
        "when warnings alone fail a file (2 stays for errors)",
    )  # fmt: skip
    validate.add_argument(
        "--format", choices=FORMATS, default="text",
        help="text (file:line:col: message, the default), json (every diagnostic and each "
        "file's verdict) or github (GitHub Actions ::error/::warning annotations)",
    )  # fmt: skip

    show = add_command(
        sub,
        "show",
        show_command,
        """print a mission's tree

        Print the compiled tree of FILE.
        """,
    )
    show.add_argument("file", metavar="FILE",
                      help="a mission file, a shipped mission's name, or a library file (its "
                      "subtrees listed with their parameters and doc)")  # fmt: skip
    show.add_argument("--subtree", metavar="NAME",
                      help="draw this subtree of the library FILE, -p giving its arguments "
                      "(-p dist=1m)")  # fmt: skip
    _common(show)
    show.add_argument("--dot", metavar="OUT.dot", type=output_with_suffix(".dot", ".gv"),
                      help="also write the tree as Graphviz dot")  # fmt: skip
    show.add_argument("--svg", metavar="OUT.svg", type=output_with_suffix(".svg"),
                      help="also write the tree as SVG (needs Graphviz's dot program)")  # fmt: skip

    missions = add_command(
        sub,
        "missions",
        missions_command,
        """list the shipped missions with their parameters, or print one

        List the missions shipped with roomba-bt (run one by name: roomba-bt run dock), each with
        its description and parameters (type, default, doc), and the shipped library a mission can
        include (include: [roomba-bt:lib/docking.yaml]). With NAME, print that mission's file
        (or a library file's, lib/docking.yaml) as shipped, its comments included: a start for
        one of your own.
        """,
    )
    missions.add_argument(
        "name", nargs="?", metavar="NAME",
        help="print this shipped mission (dock) or library file (lib/docking.yaml)",
    )  # fmt: skip

    behaviours = add_command(
        sub,
        "behaviours",
        behaviours_command,
        """list every behaviour with its parameters

        List the built-in and plugin behaviours: parameters (type, unit, range, default), sensor
        packets read, OI modes needed. A word of the mission language (retry, timeout, until)
        is no behaviour: asked for, its meaning and options are printed (--words lists them
        all). Exit 2 if an installed plugin did not load (it is named, with its error),
        unless --skip-broken-plugins.
        """,
    )
    behaviours.add_argument("names", nargs="*", help="only these behaviours")
    output = behaviours.add_mutually_exclusive_group()
    output.add_argument("--json", action="store_true", help="machine-readable output")
    output.add_argument(
        "--markdown",
        action="store_true",
        help="each as its entry in the missions page's reference (roomba-bt docs missions: its "
        "text and parameter table)",
    )
    output.add_argument(
        "--words",
        action="store_true",
        help="list the mission language's own words (composites, decorators, modifiers)",
    )
    _add_plugin_file_option(behaviours, "also list")
    _add_skip_broken_option(behaviours, "list the behaviours that loaded and exit 0")

    schema = add_command(
        sub,
        "schema",
        schema_command,
        """print the JSON Schema of mission files

        Print the JSON Schema of mission files (roomba-bt schema > mission.schema.json), generated
        from the behaviour declarations. If an installed plugin did not load, it is named with
        its error, no schema is printed and the exit code is 2: a schema without its
        behaviours would mark every mission that uses them wrong.
        """,
    )
    _add_plugin_file_option(schema, "also describe")
    _add_skip_broken_option(schema, "print the schema without their behaviours and exit 0")


def _add_plugin_file_option(parser: argparse.ArgumentParser, verb: str) -> None:
    parser.add_argument(
        "--plugin-file",
        action="append",
        default=[],
        metavar="FILE",
        help=f"{verb} the behaviours of this plugin file (imported: it is code), for "
        "missions that name it under plugins: (repeatable)",
    )


def _add_skip_broken_option(parser: argparse.ArgumentParser, then: str) -> None:
    parser.add_argument(
        "--skip-broken-plugins",
        action="store_true",
        help=f"when an installed plugin does not load, warn, {then}",
    )


def _registry_with_files(command: str, files: list[str]) -> tuple[Registry, list[str]] | int:
    """The default registry with the behaviours of each ``--plugin-file`` that loaded, and
    what each of its classes that did not load (or a file that did not import) says, as
    the command prints it; an exit code after saying which file could not be read."""
    from roomba_bt.behaviours import default_registry

    registry = default_registry()
    said: list[str] = []
    for file in files:
        path = Path(file)
        if not path.is_file():
            what = ("a directory, not a file" if path.is_dir() else
                    "not a regular file" if path.exists() else "no such file")  # fmt: skip
            print(f"roomba-bt {command}: --plugin-file {file}: {what}", file=sys.stderr)
            return ExitCode.INVALID
        registry, errors = registry.with_file(Path(file))
        said += [f"roomba-bt {command}: --plugin-file {file}: {error}" for error in errors]
    return registry, said


def _common(parser: argparse.ArgumentParser) -> None:
    add_param_option(parser, "set a mission parameter, e.g. -p speed=250mm/s (repeatable)")
    add_profile_option(parser, "the robot the mission is checked for")
    parser.add_argument("--baud", type=baud_rate, default=115200, help="baud rate (default 115200)")
    add_permission_options(parser)


def _params(items: list[str], command: str) -> dict[str, str] | None:
    """The ``-p`` values, or None after printing what is wrong with one, the command named
    as ``run`` and ``eval`` name theirs (it said ``roomba-bt: -p 'laps': ...``)."""
    params = parse_params(items)
    if isinstance(params, str):
        print(f"roomba-bt {command}: {params}", file=sys.stderr)
        return None
    return params


def validate_command(args: argparse.Namespace) -> int:
    """Each file checked, then said in ``--format`` (``cli/validate_report.py``)."""
    from roomba_bt.cli import validate_report as report

    params = _params(args.param, "validate")
    if params is None:
        return ExitCode.INVALID
    named = None if args.profile is not None else environment_profile()
    if isinstance(named, BadSetting):  # every file's: a usage error, not one file's
        print(f"roomba-bt validate: {named}", file=sys.stderr)
        return ExitCode.INVALID
    checked: list[report.Checked] = []
    paths: list[str] = []  # each checked file's path, "" for one that could not be read
    for file, found, problem in _each_file_once(args.files):
        raise_lost_interrupt(args)  # a signal Python dropped: nothing said, exit 130
        paths.append(found)
        if problem is not None:
            checked.append(report.Checked(file, problem=problem))
            continue
        checked.append(_checked(file, found, params, args))
    if len(checked) > 1 and params:  # each file its own -p values: the batch's rule
        declared = {name for one in checked for name in one.parameters}
        for index, (one, found) in enumerate(zip(checked, paths, strict=True)):
            own = {k: v for k, v in params.items() if k in one.parameters or k not in declared}
            if found and own != params:
                checked[index] = _checked(one.file, found, own, args)
    from roomba_bt.behaviours import default_registry

    registry = default_registry()
    warn_of_broken_plugins("roomba-bt validate", registry)
    # in the report too: a program reading the JSON, or the Actions page, saw none of them
    unloaded = [
        report.UnloadedPlugin(escaped(e.plugin, ANY_CONTROL), escaped(e.cause, ANY_CONTROL),
                              escaped(e.lost, ANY_CONTROL))
        for e in (registry.broken if registry.plugins_loaded else ())
    ]  # fmt: skip
    if args.format != "text":
        for one in checked:  # said on stderr too, as in text: a reader of the log sees it
            if one.problem is not None:
                problem = escaped(one.problem, ANY_CONTROL)
                print(f"roomba-bt validate: {problem}", file=sys.stderr)
    if args.format == "json":
        report.print_json(checked, strict=args.strict, plugins=unloaded)
    elif args.format == "github":
        report.print_github(checked, strict=args.strict, quiet=bool(args.quiet), plugins=unloaded)
    else:
        report.print_text(checked, strict=args.strict, quiet=bool(args.quiet))
    return report.exit_code(checked, args.strict)


def _each_file_once(given: list[str]) -> list[tuple[str, str, str | None]]:
    """``(file, path, problem)`` of each file ``validate`` checks, as :func:`files_under`
    names them, a file named twice kept once (:func:`given_once`); the path "" and what is
    wrong for one that cannot be read, else no problem."""
    problems: dict[str, str] = {}
    named: list[tuple[str, str]] = []
    for file in (each for one in given for each in files_under(one)):
        found = (f"{file}: {_NO_MISSIONS}",) if file and os.path.isdir(file) else mission_file(file)
        if isinstance(found, tuple):
            problems[file] = found[0]
        named.append((file, "" if isinstance(found, tuple) else found))
    return [(f, p, problems.get(f)) for f, p in given_once("validate", named, "checked")]


#: what a folder given to ``validate`` with no mission file in it is
_NO_MISSIONS = "a folder with no .yaml or .yml file in it (folders are read recursively)"


def files_under(given: str) -> list[str]:
    """``validate``'s file argument as the files it names: a folder as every ``.yaml`` and
    ``.yml`` file under it, at any depth, in the order of their paths (as ``git ls-files``
    lists them), hidden files and folders (``.git``) left out; anything else as itself. A
    folder needs no shell list: ``$(git ls-files ...)`` split "Zoë Müller (final).yaml" at
    its spaces and gave it octal-escaped (docs/ci.md)."""
    if not given or not os.path.isdir(given):  # "" is no folder (Path("") is "."), and a
        return [given]  # folder the user cannot enter is said by the file's own check
    folder = Path(given)
    found = []
    for parent, folders, names in os.walk(folder):
        folders[:] = [name for name in folders if not name.startswith(".")]
        inside = Path(parent).relative_to(folder)
        found += [(inside / name).as_posix() for name in names
                  if name.endswith((".yaml", ".yml")) and not name.startswith(".")]  # fmt: skip
    return [os.path.join(given, name) for name in sorted(found)] or [given]


def _checked(file: str, found: str, params: dict[str, str], args: argparse.Namespace) -> Checked:
    """What ``validate`` found in the file argument ``file`` (at ``found``): a world's
    diagnostics (checked as ``run --world`` reads it, so CI checks a world without running a
    mission in it), else a mission's or a library's, with the include folders granted to it,
    and the files it includes."""
    from roomba_bt.cli.worlds_cmd import world_diagnostics
    from roomba_bt.mission import Diagnostic, validate_file

    world = world_diagnostics(found)
    if world is not None:
        return Checked(file, world)
    # each file its own project's profile: a repository's missions, several projects' files
    choice = resolved_profile(args.profile, "validate", mission_near(file, found))
    if isinstance(choice, BadSetting):  # the project file's (the environment's: checked first)
        return Checked(file, [Diagnostic(choice.file, choice.line or 1, 1, choice.message)])
    validation = validate_file(
        found,
        params,
        profile=get_profile(choice.name),
        baud=args.baud,
        permissions=permissions(args, found),
    )
    return Checked(file, _neither(validation.diagnostics), includes=validation.includes,
                   parameters=validation.parameters)  # fmt: skip


def _neither(diagnostics: list[Diagnostic]) -> list[Diagnostic]:
    """``diagnostics``, an empty file's said as neither a mission nor a world: ``validate``
    takes both, and "the mission file is empty" was said of a world being drawn; so is a
    file it cannot read ("cannot read mission file 'w.yaml'" of a world: it cannot be told
    which). An empty file it includes is still an empty mission file (a library is expected
    there)."""
    from dataclasses import replace

    from roomba_bt.mission.source import (
        EITHER_WANTED,
        EMPTY_FILE,
        EMPTY_MISSION,
        MISSION_WANTED,
        UNREADABLE_FILE,
        UNREADABLE_MISSION,
    )

    if len(diagnostics) != 1 or diagnostics[0].included_from:
        return diagnostics
    (only,) = diagnostics
    if only.message == EMPTY_MISSION:
        return [replace(only, message=EMPTY_FILE)]
    if only.message.startswith(f"{UNREADABLE_MISSION} ") and only.message.endswith(MISSION_WANTED):
        said = only.message.removesuffix(MISSION_WANTED) + EITHER_WANTED
        return [replace(only, message=said.replace(UNREADABLE_MISSION, UNREADABLE_FILE, 1))]
    return diagnostics


def show_command(args: argparse.Namespace) -> int:
    import py_trees

    from roomba_bt.mission import compile_mission, reported

    params = _params(args.param, "show")
    if params is None:
        return ExitCode.INVALID
    found = mission_file(args.file)
    if isinstance(found, tuple):
        print(f"roomba-bt show: {escaped(found[0], ANY_CONTROL)}", file=sys.stderr)
        return ExitCode.INVALID
    missing = graph_tools_missing(dot=args.dot is not None, svg=args.svg is not None)
    missing = missing or chosen_profile(args, "show", mission_near(args.file, found))
    if missing is not None:  # said before the tree is printed, not after
        print(f"roomba-bt show: {missing}", file=sys.stderr)
        return ExitCode.INVALID
    drawn = _library_drawn(args, found, params)  # a library: listed, or a subtree drawn
    if isinstance(drawn, int):
        return drawn
    mission, diagnostics = compile_mission(
        found if drawn is None else drawn.path,
        params if drawn is None else {},  # a subtree's: its arguments in the text
        profile=get_profile(args.profile),
        baud=args.baud,
        permissions=permissions(args, found),
        text=drawn,
    )
    if mission is None:
        for line in reported(diagnostics):
            print(line)
        return ExitCode.INVALID
    # a name and a description as one line each shows them: a 10 MB description flooded it
    description = shortened(mission.description.strip(), TEXT_LIMIT)
    header = f"{shortened(mission.name)}: {description}".rstrip(": ")
    print(escaped(header, ANY_CONTROL))  # one line: "\n[ok] ..." in a text faked one
    reviewed = mission.reviewed()  # a node's name: beside what it is
    # a name or a log message from -p may hold "\e[2J" (each name is one line already)
    print(escaped(py_trees.display.unicode_tree(reviewed)))
    print(f"sensor packets: {list(mission.packets)}")
    if mission.parameters_shown:
        shown = ", ".join(f"{k}={shortened(v)}" for k, v in mission.parameters_shown.items())
        print(escaped(f"parameters: {shown}", ANY_CONTROL))
    for option, fmt in (("dot", "dot"), ("svg", "svg")):
        target = getattr(args, option)
        if target is None:
            continue
        problem = write_graph(reviewed, Path(target), fmt)
        if problem is not None:
            print(f"roomba-bt show: {problem}", file=sys.stderr)
            return ExitCode.INVALID
    return ExitCode.OK


def _library_drawn(
    args: argparse.Namespace, found: str, params: dict[str, str]
) -> MissionText | int | None:
    """``show`` of a library file: its subtrees listed (the exit code), or with ``--subtree
    NAME`` a mission of one use of it to draw; None for a mission file (drawn as it is). The
    library is compiled first: its errors are said as ``validate`` says them (exit 2)."""
    from roomba_bt.cli.library_show import library_listed, refused, subtree_mission
    from roomba_bt.mission import compile_mission, reported
    from roomba_bt.mission.compiler import is_library
    from roomba_bt.mission.shipped import describe_library
    from roomba_bt.yamlsource import read_text

    if not is_library(Path(found)):
        if args.subtree is None:
            return None
        return refused(
            f"--subtree draws a subtree of a library file (subtrees:, no tree:); {args.file} "
            "is a mission: its tree is drawn without --subtree"
        )
    _, diagnostics = compile_mission(
        found,
        profile=get_profile(args.profile),
        require_tree=False,
        permissions=permissions(args, found),
    )
    if any(d.severity != "warning" for d in diagnostics):  # its warnings are validate's
        for line in reported(diagnostics):
            print(line)
        return ExitCode.INVALID
    # it compiled: readable, and small enough
    description, subtrees = describe_library(read_text(Path(found)))
    if args.subtree is None:
        if params:
            return refused("-p sets a subtree's arguments: give --subtree NAME with it")
        return library_listed(args.file, subtrees, description)
    drawn = subtree_mission(args.file, Path(found), subtrees, args.subtree, params)
    if isinstance(drawn, str):
        return refused(drawn)
    alone, _ = compile_mission(
        drawn.path, profile=get_profile(args.profile), baud=args.baud,
        permissions=permissions(args, found), text=drawn,
    )  # fmt: skip
    if alone is not None:  # drawn as it runs: undock enters Full itself, from any mode
        return drawn
    # as a mission reaches one whose drives need a mode it does not enter (its errors, if
    # that is not why, said of this)
    safe = subtree_mission(args.file, Path(found), subtrees, args.subtree, params, safe_first=True)
    assert not isinstance(safe, str)  # the same subtree and arguments, found right above
    return safe


def missions_command(args: argparse.Namespace) -> int:
    from roomba_bt.cli.library_show import print_subtrees
    from roomba_bt.mission.shipped import (
        describe_library,
        describe_shipped,
        parameter_line,
        shipped_file,
        shipped_library_files,
        shipped_missions,
    )

    if args.name is not None:
        name = args.name.removeprefix("roomba-bt:").removesuffix(".yaml")
        path = shipped_missions().get(name) or shipped_file(f"roomba-bt:{name}.yaml")
        if path is None:
            from roomba_bt.behaviours.units import closest

            known = [*shipped_missions(), *(f.removeprefix("roomba-bt:").removesuffix(".yaml")
                                            for f in shipped_library_files())]  # fmt: skip
            print(
                f"roomba-bt missions: no shipped mission or library file {args.name!r}"
                f"{closest(name, known)}; shipped: {', '.join(known)}",
                file=sys.stderr,
            )
            return ExitCode.INVALID
        sys.stdout.write(path.read_text(encoding="utf-8"))
        return ExitCode.OK
    for entry in describe_shipped():
        print(f"{entry.name}  {entry.description}")
        for param in entry.parameters:
            print(f"    {parameter_line(param)}")
        print()
    print("library (include by name): " + ", ".join(shipped_library_files()))
    for name in shipped_library_files():  # each subtree with its doc: what to use, and how
        library = shipped_file(name)
        assert library is not None  # listed from the folder itself
        print(f"\n{name}")
        print_subtrees(describe_library(library.read_text(encoding="utf-8"))[1], indent="    ")
    return ExitCode.OK


def graph_tools_missing(*, dot: bool, svg: bool) -> str | None:
    """What ``--dot``/``--svg`` need and this machine lacks: pydot (both), Graphviz's ``dot``
    program (``--svg``, which it renders); None when nothing is missing or nothing is asked."""
    if not (dot or svg):
        return None
    try:
        import pydot  # noqa: F401
    except ImportError:
        return "--dot/--svg need pydot: pip install pydot (and Graphviz for --svg)"
    if svg and shutil.which("dot") is None:
        return (
            "--svg needs Graphviz's dot program, which is not on the PATH (apt-get install "
            "graphviz, brew install graphviz); --dot writes the graph as text without it"
        )
    return None


def write_graph(root: Any, target: Path, fmt: str) -> str | None:
    """Write the tree as dot or svg; an error message (never a traceback) if impossible."""
    missing = graph_tools_missing(dot=fmt == "dot", svg=fmt == "svg")
    if missing is not None:
        return missing
    import py_trees

    graph = py_trees.display.dot_tree(root)
    _labelled_by_name(graph, root)
    try:
        if fmt == "dot":
            target.write_text(graph.to_string(), encoding="utf-8")
        else:
            svg = graph.create(format="svg")
            target.write_bytes(svg if isinstance(svg, bytes) else str(svg).encode())
    except OSError as exc:
        return f"cannot write {target}: {exc}"
    except Exception as exc:  # pydot raises plain Exception when Graphviz fails
        return f"cannot render {fmt}: {exc}"
    print(f"wrote {target}", file=sys.stderr)
    return None


def _labelled_by_name(graph: Any, root: Any) -> None:
    """Each graph node labelled with its node's name. py_trees keeps the graph's node ids
    unique by adding ``*`` to a name already used, and labels the node with that id: the
    second ``bump(any)`` of a tree read ``bump(any)*``, a mark that is in no mission. The
    ids are worked out as py_trees makes them (depth first, from the root) and stay; only
    the labels say the name again. An id made otherwise by a later py_trees is left as it
    labelled it."""
    used = {root.name}
    renamed: dict[str, str] = {}

    def renaming(node: Any) -> None:
        for child in node.children:
            node_id = child.name
            while node_id in used:
                node_id += "*"
            used.add(node_id)
            if node_id != child.name:
                renamed[node_id] = child.name
            renaming(child)

    renaming(root)
    for dot_node in graph.get_nodes():
        name = renamed.get(dot_node.get_name())
        if name is not None:
            dot_node.set_label(str(dot_node.get_label()).replace(dot_node.get_name(), name, 1))


def describe_behaviours(
    names: list[str] | None = None, registry: Registry | None = None
) -> list[dict[str, Any]]:
    """The registry (by default the default one) as data: what ``behaviours --json`` prints."""
    from roomba_bt.behaviours import default_registry

    out = []
    registry = registry if registry is not None else default_registry()
    chosen = [decl for decl in registry if not names or decl.name in names]
    # a package:name asked for (roomba-bt behaviours roomba-bt-dirt:dirt_detect), in order
    chosen += [d for d in (registry.get(n) for n in names or () if ":" in n) if d is not None]
    for decl in chosen:
        clash = registry.clash(decl.name)
        out.append(
            {
                "name": decl.name,
                # how a mission names it whatever else declares its name (package:name)
                "qualified": decl.name if ":" in decl.name else registry.spelled(decl),
                "kind": decl.kind,
                "doc": decl.doc,
                "origin": decl.origin,
                # two plugins declare the name (a mission using it is refused), or a plugin
                # declares a built-in's (the built-in is used): said where it is listed
                "clash": None if clash is None else {"severity": clash[0], "why": clash[1]},
                "parameters": [_parameter_entry(p) for p in decl.params],
                "reads": "depends on parameters" if callable(decl.reads) else list(decl.reads),
                # the parameters naming blackboard keys, each with its value's type (None:
                # untyped, any key but a mark): what validate holds the mission's keys to
                "writes_keys": _key_roles(decl, decl.writes_keys),
                "reads_keys": _key_roles(decl, decl.reads_keys),
                "sends": list(decl.sends),
                "modes": [m.label for m in sorted(decl.modes)],
                "leads_to": _leads_to(decl),
                # the modes its own mode commands take it to on the way (passes_through=)
                "passes_through": [m.label for m in decl.passes_through],
                # its first command each time it starts is one of its mode commands: it may
                # be reached in a mode its other commands are refused in (mode_first=True)
                "mode_first": decl.mode_first,
            }
        )
    return out


def _parameter_entry(p: Param) -> dict[str, Any]:
    """A behaviour's parameter, or a language word's option, as ``behaviours --json``
    lists it."""
    return {
        "name": p.name,
        "type": p.type.name,
        "unit": p.type.unit,
        "choices": list(p.type.choices),
        "minimum": p.minimum,
        "maximum": p.maximum,
        "default": p.default,
        "required": p.required,
        "doc": p.doc,
    }


def _word_entry(name: str) -> dict[str, Any] | None:
    """A word of the mission language (``retry``, ``until``, ``include``) as ``behaviours
    --json`` lists it, beside the behaviours: its ``kind`` says it is no behaviour, ``is``
    what it is, ``parameters`` its options. It was said as text on stderr, and stdout was
    empty, exit 0: a script read an empty document as success."""
    facts = word_facts(name)
    if facts is None:
        return None
    what, doc, options = facts
    return {
        "name": name,
        "kind": "language word",
        "is": what,
        "doc": doc,
        "parameters": [_parameter_entry(p) for p in options],
    }


def _key_roles(decl: Declaration, names: tuple[str, ...]) -> list[dict[str, str | None]]:
    """Each parameter of ``names`` (its ``writes_keys`` or ``reads_keys``) with the type of
    its key's value, as ``behaviours --json`` lists them."""
    out: list[dict[str, str | None]] = []
    for pname in names:
        vtype = decl.key_type(pname)
        out.append({"parameter": pname, "type": None if vtype is None else vtype.name})
    return out


def _leads_to(decl: Any) -> str | None:
    if callable(decl.leads_to):
        return "depends on parameters"
    return decl.leads_to.label if decl.leads_to is not None else None


def behaviours_command(args: argparse.Namespace) -> int:
    """What each behaviour takes; with a ``--plugin-file`` one of whose classes is declared
    wrongly, the others are listed all the same and the errors said after them, exit 2, as
    for an installed plugin (it printed nothing)."""
    loaded = _registry_with_files("behaviours", args.plugin_file)
    if isinstance(loaded, int):
        return loaded
    registry, file_errors = loaded
    from roomba_bt.behaviours import default_registry

    said = _listed(args, registry, default_registry())  # the files' errors are said below
    for line in file_errors:  # after the listing, where a terminal leaves it in view
        print(line, file=sys.stderr)
    return ExitCode.INVALID if file_errors else said


def _listed(args: argparse.Namespace, registry: Registry, installed: Registry) -> int:
    """The behaviours ``args`` asks for, listed from ``registry``, and the exit code they
    call for; the ``installed`` plugins that did not load said after them."""
    if args.words:
        print("\n".join(every_word()))
        return ExitCode.OK
    # a word of the language asked about is answered (its meaning and options), not an error
    words = [word for word in map(language_word, args.names) if word is not None]
    # --json lists it as data beside the behaviours, --markdown as an entry: stdout holds
    # the answer in the format asked for, as it does a behaviour's
    word_entries = [e for e in map(_word_entry, args.names) if e is not None]
    word_entries_md = [e for e in map(word_markdown, args.names) if e is not None]
    if args.markdown and word_entries_md:
        print("\n".join(word_entries_md))
    for word in [] if args.json or args.markdown else words:
        print(f"{word}\n    ({EVERY_WORD})")
    unknown = [n for n in args.names if n not in registry and language_word(n) is None]
    if unknown:
        for name in unknown:
            print(f"roomba-bt behaviours: {_unknown_behaviour(name, registry)}", file=sys.stderr)
        # it may be one of a plugin that did not load: said as `behaviours` says them when
        # it lists (errors, then what is not listed), not as warnings of another command's
        _plugins_broken("behaviours", installed, args.skip_broken_plugins, "not listed: {lost}")
        return ExitCode.INVALID
    if words and len(words) == len(args.names):  # only words: every behaviour would bury them
        if args.json:
            print(json.dumps(word_entries, indent=2, default=str))
        return ExitCode.OK
    data = describe_behaviours(args.names, registry)
    # a name two plugins declare is no behaviour a mission can use (it is refused, exit 2):
    # asked for by name, the answer is that error, not one of the two as if it were in use
    contested = [e for e in data if e["clash"] and e["clash"]["severity"] == "error"]
    said = ExitCode.INVALID if args.names and contested else ExitCode.OK
    if args.json:
        print(json.dumps(word_entries + data, indent=2, default=str))
    elif args.markdown:
        from roomba_bt.behaviours.reference import markdown_entry

        chosen = [registry.get(entry["name"]) for entry in data]
        print("\n".join(markdown_entry(decl) for decl in chosen if decl is not None))
    else:
        for entry in data:
            if entry in contested:
                print(f"{entry['name']}  (declared by two plugins: a mission that uses it is "
                      "refused)")  # fmt: skip
                print(f"    error: {entry['clash']['why']}\n")
            else:
                _print_behaviour(entry)
    # after the listing, where a terminal leaves it in view
    if _plugins_broken("behaviours", installed, args.skip_broken_plugins, "not listed: {lost}"):
        return ExitCode.INVALID
    return said


def _unknown_behaviour(name: str, registry: Registry) -> str:
    """What ``behaviours NAME`` says of a name no behaviour has: the plugin that declares it
    and did not load (its error follows), else the plugins none of whose behaviours loaded,
    else a did-you-mean and where a plugin file's behaviours are listed. It said "a plugin
    file's are listed with --plugin-file FILE" of a name an installed plugin's refused class
    declares, as if the name were in a file."""
    from roomba_bt.behaviours.units import closest

    likely, declares = registry.may_have_meant(name)
    said = f"unknown behaviour {escaped(repr(name), ANY_CONTROL)}"
    why = registry.why_unknown(name)  # package:name: no such package, or no such behaviour
    if why is not None and not likely:
        return f"{said}: {escaped(why, ANY_CONTROL)}"
    plugins = escaped(", ".join(error.plugin for error in likely[:3]), ANY_CONTROL)
    if len(likely) > 3:
        plugins += f" and {len(likely) - 3} more"
    if declares and all(error.refused for error in likely):
        return f"{said}: {_half_loaded(likely, registry)}"
    if declares:
        return f"{said}: it is declared by plugin {plugins}, which did not load (below)"
    hint = closest(name, registry.names())
    if likely:
        return f"{said}{hint}; perhaps of a plugin that did not load (below): {plugins}"
    return f"{said}{hint}; a plugin file's are listed with --plugin-file FILE"


def _half_loaded(declaring: list[PluginError], registry: Registry) -> str:
    """Of the plugins whose refused class declares the name, each loaded in part (its other
    classes registered): what loaded and what was refused, ``it is declared by plugin 'x'
    (...), which loaded in part: loaded fine_a, fine_b; refused 'typo_str' (below)``. It said
    the plugin "did not load", and the user found its other behaviours listed."""
    said = []
    for plugin in dict.fromkeys(error.plugin for error in declaring):
        loaded = [d.name for d in registry if d.origin == plugin]
        refused = [e.refused for e in registry.errors if e.plugin == plugin and e.refused]
        said.append(
            f"it is declared by plugin {escaped(plugin, ANY_CONTROL)}, which loaded in part: "
            f"loaded {', '.join(loaded) or 'none'}; refused "
            f"{escaped(', '.join(refused), ANY_CONTROL)} (below)"
        )
    return "; ".join(said)


def _print_behaviour(entry: dict[str, Any]) -> None:
    """One behaviour of ``describe_behaviours`` as ``roomba-bt behaviours`` prints it, its
    docstring's and its parameters' reST inline markup as a terminal reads it
    (:func:`~roomba_bt.behaviours.reference.inline_text`: ```key``` printed as written);
    ``--json`` keeps the text as written."""
    from roomba_bt.behaviours.reference import inline_text

    modes = " or ".join(entry["modes"])
    head = f"{entry['name']}  ({entry['kind']}"
    if len(entry["modes"]) < 4:
        head += f"; needs {modes}"
        if entry["mode_first"]:
            head += ", which its own first command sets (mode_first)"
    if entry["passes_through"]:
        head += f"; passes through {' and '.join(entry['passes_through'])}"
    if entry["leads_to"]:
        head += f"; leads to {entry['leads_to']}"
    if entry["origin"] != "builtin":
        head += f"; from {entry['origin']}"
        if entry["qualified"] and entry["qualified"] != entry["name"]:
            head += f"; also written {entry['qualified']}"
    print(head + ")")
    if entry["clash"]:
        print(f"    {entry['clash']['severity']}: {entry['clash']['why']}")
    if entry["doc"]:
        print(f"    {inline_text(entry['doc'])}")
    for p in entry["parameters"]:
        parts = [p["type"] if not p["choices"] else "|".join(p["choices"])]
        if p["unit"]:
            parts[0] += f" [{p['unit']}]"
        if p["minimum"] is not None or p["maximum"] is not None:
            lo = "" if p["minimum"] is None else f"{p['minimum']:g}"
            hi = "" if p["maximum"] is None else f"{p['maximum']:g}"
            parts.append(f"range {lo}..{hi}")
        if p["required"]:
            parts.append("required")
        elif p["default"] is not None:
            parts.append(f"default {yaml_written(p['default'])}")  # true, not True
        else:
            parts.append("optional")
        doc = f"  {inline_text(p['doc'])}" if p["doc"] else ""
        print(f"    {p['name']}: {', '.join(parts)}{doc}")
    reads = entry["reads"]
    if reads:
        print(f"    reads packets: {reads}")
    for role, verb in (("writes_keys", "writes"), ("reads_keys", "reads")):
        for key in entry[role]:
            typed = (
                f"a value of type {key['type']}" if key["type"] else "untyped (any key but a mark)"
            )
            print(f"    {verb} the blackboard key named by {key['parameter']}: {typed}")
    print()


def schema_command(args: argparse.Namespace) -> int:
    from roomba_bt.mission.schema import mission_schema

    loaded = _registry_with_files("schema", args.plugin_file)
    if isinstance(loaded, int):
        return loaded
    registry, file_errors = loaded
    if file_errors:  # a schema without a file's behaviours marks its missions wrong
        for line in file_errors:
            print(line, file=sys.stderr)
        return ExitCode.INVALID
    # nothing printed: ``schema > mission.schema.json`` in CI or a bot wrote a schema
    # without the plugin's behaviours, exit 0, and every editor marked its missions wrong
    if _plugins_broken(
        "schema",
        registry,
        args.skip_broken_plugins,
        "no schema printed: it would lack {lost}",
    ):
        return ExitCode.INVALID
    print(json.dumps(mission_schema(registry), indent=2))
    return ExitCode.OK


def _plugins_broken(command: str, registry: Registry, skip: bool, consequence: str) -> bool:
    """Say each installed plugin that did not load (its entry point, module and distribution,
    the error in one line) and whether the command must fail for it: True unless ``skip``
    (``--skip-broken-plugins``), when they are warnings, as a name two plugins declare
    always is (nothing is missing: each is reached by ``package:name``). ``consequence``:
    what the command leaves undone, ``{lost}`` where it names exactly the behaviours it
    lacks (:attr:`PluginError.lost`: a half-loaded plugin's refused one, not "its")."""
    broken = registry.broken
    for error in registry.errors:
        kind = "error" if error in broken and not skip else "warning"
        print(f"roomba-bt {command}: {kind}: {escaped(str(error), ANY_CONTROL)}", file=sys.stderr)
    if not broken or skip:
        return False
    plugins = len({error.plugin for error in broken})  # a half-loaded one: an error a class
    one = plugins == 1
    what = "an installed plugin" if one else f"{plugins} installed plugins"
    it = "it" if one else "them"
    lost = escaped("; ".join(error.lost for error in broken), ANY_CONTROL)
    print(
        f"roomba-bt {command}: {what} did not load ({consequence.format(lost=lost)}): fix or "
        f"uninstall {it}, or pass --skip-broken-plugins to go on without {it}",
        file=sys.stderr,
    )
    return True


#: the registries whose broken plugins a command said (:func:`warn_of_broken_plugins`):
#: ``eval`` compiles each variant, and the warning is said once
_WARNED: weakref.WeakSet[Registry] = weakref.WeakSet()


def warn_of_broken_plugins(speaker: str, registry: Registry) -> None:
    """A warning on stderr, once, for each installed plugin whose behaviours a mission cannot
    use, naming exactly which (:attr:`PluginError.lost`); the loaded ones stay usable. For
    ``validate``, ``run``, ``replay`` and ``eval``, which said nothing of a half-loaded plugin
    while ``behaviours`` failed for it: a nightly ``validate`` hid it until a mission used
    the refused name. Only when the command looked for plugins
    (:attr:`Registry.plugins_loaded`): it does not scan for them to say this. A warning, not
    a failure (``--strict`` included): a mission that does not use the refused behaviour is
    right, and one that does gets its own error. ``speaker`` begins each line
    (``roomba-bt validate``)."""
    if registry in _WARNED or not registry.plugins_loaded:
        return
    _WARNED.add(registry)
    for error in registry.broken:
        said = escaped(f"{error}; a mission cannot use {error.lost}", ANY_CONTROL)
        print(f"{speaker}: warning: {said}", file=sys.stderr)
