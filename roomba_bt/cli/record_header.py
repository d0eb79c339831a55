"""What ``run --record`` says of its run in the record's header, and ``--reproducible``.

A record is committed beside its missions (``repo/records/dock.jsonl``) and replayed in
every checkout CI makes elsewhere. Its header names the mission, each file the mission came
from and the simulator's world by their paths relative to the record's folder
(``../missions/docking/dock.yaml``) where the two lie under a common folder
(:func:`~roomba_bt.runtime.provenance.near`), so a replay in another checkout finds them,
and keeps the mission's absolute path for the reader. The simulator's options and the run's
own (``--timeout``, ``--include-dir``, ...) are there as given: the record says how to make it
again (docs/runtime.md, Recording and replay).

``--reproducible`` leaves out what changes from one run to the next with nothing changed:
the start time (``SOURCE_DATE_EPOCH``'s, when set, as the reproducible-builds convention
has it), the absolute path, and the summary's wall-clock measurements.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING, Any

from roomba_bt.cli.arguments import fault_fields_set

if TYPE_CHECKING:
    from roomba_bt.runtime.claimed import ClaimedFile
    from roomba_bt.runtime.stack import Recording

REPRODUCIBLE_HELP = (
    "byte-stable output for committing: leave out the wall-clock measurements (wall and CPU "
    "time, the slowest tick, worker ids) and the absolute paths, and write a record's "
    "'started' only from SOURCE_DATE_EPOCH"
)


def add_reproducible_option(parser: argparse.ArgumentParser) -> None:
    """``--reproducible`` (``run`` and ``eval``)."""
    parser.add_argument("--reproducible", action="store_true", help=REPRODUCIBLE_HELP)


def started_said(args: argparse.Namespace) -> str | None:
    """The header's ``started``: ``SOURCE_DATE_EPOCH``'s time when it is set (checked by
    :func:`epoch_problem` before the run), else the run's start; None with ``--reproducible``
    and no ``SOURCE_DATE_EPOCH`` (a header without it loads, as one made before did)."""
    from roomba_bt.runtime.recording import source_date_epoch, utc_stamp

    epoch = source_date_epoch()
    if epoch is not None:
        return utc_stamp(epoch)
    return None if getattr(args, "reproducible", False) else utc_stamp(args.started)


def epoch_problem() -> str | None:
    """What is wrong with ``SOURCE_DATE_EPOCH``, said before the run (exit 2), or None."""
    from roomba_bt.runtime.recording import source_date_epoch

    try:
        source_date_epoch()
    except ValueError as exc:
        return str(exc)
    return None


def recording(
    args: argparse.Namespace,
    mission: Any,
    params: dict[str, str],
    claimed: ClaimedFile | None,
) -> Recording:
    """The header ``run --record`` writes: the mission (a shipped one by its name, a file
    by its path from the record's folder, :func:`~roomba_bt.runtime.provenance.source_name`),
    its sources and plugins, the simulator's options and the run's."""
    from roomba_bt.runtime.provenance import plugin_digests, source_digests, source_name
    from roomba_bt.runtime.stack import Recording

    folder = Path(args.record).resolve().parent
    reproducible = bool(getattr(args, "reproducible", False))
    name = source_name(Path(args.mission), folder)
    relative = not Path(name).is_absolute() and not name.startswith("roomba-bt:")
    return Recording(
        args.record, name, params,
        port=args.robot, started=started_said(args), label=args.label,
        sources=source_digests(mission.files, folder), plugins=plugin_digests(mission.root),
        mission_path=str(Path(args.mission).resolve()) if relative and not reproducible else None,
        simulator=simulator_options(args, folder), options=run_options(args, folder),
        paths_from_record=True, claimed=claimed, max_bytes=args.record_max,
        required=bool(getattr(args, "require_record", False)),
    )  # fmt: skip


def simulator_options(args: argparse.Namespace, folder: Path) -> dict[str, Any] | None:
    """The simulator's options as given: the world (its name when it was given by name, a
    shipped world's or one of ``ROOMBA_BT_WORLDS``'s; a file's path from the record's
    ``folder``) and its file's digest, the seed, ``--random-start``, ``--battery``,
    ``--odometry-error`` and ``--fast``, and the fault options given (``faults``, by their
    ``Faults`` fields: ``{"byte_drop_rate": 0.02}``; absent when none was, as in a record
    made before they were kept); None on a robot's port.

    A world of ``ROOMBA_BT_WORLDS``'s was written as its file's path from the record's
    folder (``../../worlds/living.yaml``), and ``monitor RECORD``, which reads a record's world
    file only inside the folder holding the record and its mission, refused it: by its name,
    it is found again where the user keeps their worlds, and the digest tells whether it is
    the same file."""
    if args.port:
        return None
    from roomba_bt.cli.links import DEFAULT_WORLD
    from roomba_bt.runtime.provenance import file_digest, source_name

    given = args.world or DEFAULT_WORLD
    source = Path(getattr(args, "world_source", "") or given)
    by_name = not Path(given).is_file()  # as load_world took it: no file, so a name
    options: dict[str, Any] = {
        "world": given if by_name else source_name(source, folder),
        "world_sha256": file_digest(source),
        "seed": args.seed,
        "random_start": bool(args.random_start),
        "battery": args.battery,
        "odometry_error": args.odometry_error or 0.0,
        "fast": bool(args.fast),
    }
    faults = fault_fields_set(args)
    if faults:  # a run on a bad cable said nothing of it, and was made again on a clean one
        options["faults"] = faults
    return options


def run_options(args: argparse.Namespace, folder: Path) -> dict[str, Any]:
    """The run's options besides the mission and the simulator that decide its bytes, as
    given: ``--timeout`` (None: none given), the include folders granted (``--include-dir``,
    ``ROOMBA_BT_INCLUDE_PATH`` and the project file's, each from the record's ``folder`` as
    the mission is: a replay grants them, :func:`replayed_include_dirs`), ``--allow-plugin-files``
    and ``--end-in``. Only ``--include-dir``'s were kept, and a record made with the
    environment's folders could not say what it needed."""
    from roomba_bt.cli.arguments import permissions
    from roomba_bt.runtime.provenance import source_name

    granted = permissions(args, args.mission).include_dirs
    return {
        "timeout": args.timeout,
        "include_dirs": [source_name(Path(d), folder) for d in granted],
        "allow_plugin_files": bool(args.allow_plugin_files),
        "end_in": args.end_in,
    }


def replayed_include_dirs(record: str, header: dict[str, Any], mission: str) -> tuple[Path, ...]:
    """The include folders a replay of ``record`` grants ``mission`` from its header's
    ``options.include_dirs``: the folders its run was granted, read from the record's folder.

    A record may come from someone else, as a project file may, and is held to the same
    rule (docs/missions.md, Include folders): it grants only folders inside the folder that
    holds both the record and the mission (a repository with ``records/`` and ``missions/``),
    symbolic links followed, never one whose only common folder is the file system's root;
    and only from a header whose paths are relative to the record (a record made before has
    the recording machine's absolute ones). What it does not grant is a warning, said once:
    the include it was meant for is refused at its own line, with ``--include-dir``."""
    from roomba_bt.cli.arguments import warn_once
    from roomba_bt.runtime.recording import held_to_record, record_holder, recorded_path

    options = header.get("options")
    names = options.get("include_dirs") if isinstance(options, dict) else None
    if not isinstance(names, list):
        return ()
    common = record_holder(Path(record), Path(mission))
    granted: list[Path] = []
    for name in names:
        folder = recorded_path(name, header, Path(record)) if isinstance(name, str) else None
        if folder is None or not folder.is_dir():
            warn_once(f"{record}: include folder {name!r} of the recorded run is not here")
            continue
        if not held_to_record(folder, common):
            warn_once(
                f"{record}: include folder {name!r} of the recorded run is outside the folder "
                f"that holds the record and its mission ({common}): a record grants only "
                f"folders there; give it with --include-dir or ROOMBA_BT_INCLUDE_PATH; not granted"
            )
            continue
        granted.append(folder.resolve())
    return tuple(granted)
