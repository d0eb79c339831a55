"""Arguments shared by the commands: bad values become argparse's usage error (exit 2)
with what was found and what is allowed, never a traceback from deep inside; the mission's
``-p NAME=VALUE`` and ``--timeout``, read once for every command that takes them; and
:func:`add_command`, which declares each subcommand with its texts and the function that runs
it."""

from __future__ import annotations

import argparse
import inspect
import io
import json
import math
import os
import re
import sys
import zlib
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

from roomba_bt.installation import optional_import_failure
from roomba_bt.oi.encode import BAUD_CODES
from roomba_bt.oi.frames import SLOT_SECONDS
from roomba_bt.oi.profiles import DEFAULT_PROFILE, PROFILES, RobotProfile
from roomba_bt.printable import ANY_CONTROL, escaped, special_file

if TYPE_CHECKING:
    from roomba_bt.mission import Permissions
    from roomba_bt.sim.faults import Faults


def add_command(
    sub: Any, name: str, command: Callable[[argparse.Namespace], int], text: str
) -> argparse.ArgumentParser:
    """The subcommand ``name``, which runs ``command``. ``text`` is laid out like a docstring:
    its first line is the entry in ``roomba-bt --help``, the rest (if any) the description its
    own ``--help`` opens with (argparse refills the lines). A string given here, not
    ``command``'s docstring, because ``python -OO`` strips docstrings and left the listing
    blank."""
    summary, _, details = inspect.cleandoc(text).partition("\n")
    parser: argparse.ArgumentParser = sub.add_parser(
        name, help=summary, description=details.strip() or None
    )
    parser.set_defaults(func=command)
    # -v and -q after the command too (``roomba-bt run m.yaml -v``, as the hints say it):
    # counted with those before it (:func:`roomba_bt.cli.main` adds them up)
    parser.add_argument(
        "-v", "--verbose", dest="verbose_after", action="count", default=0, help="more logging"
    )
    parser.add_argument(
        "-q", "--quiet", dest="quiet_after", action="count", default=0, help="less logging"
    )
    return parser


def baud_rate(text: str) -> int:
    """One of the rates the OI's Baud command (129) knows: 300 .. 115200."""
    allowed = ", ".join(str(rate) for rate in BAUD_CODES)
    try:
        rate = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"found {text!r}; allowed: {allowed}") from None
    if rate not in BAUD_CODES:
        raise argparse.ArgumentTypeError(f"found {rate}; allowed: {allowed}")
    return rate


#: ``--baud auto``: find the rate (``robot/discovery.py``); argparse stores None.
AUTO_BAUD = "auto"


def baud_or_auto(text: str) -> int | None:
    """``auto`` (None: try the OI's rates, 115200 then 19200, and take the one that
    answers) or a rate as :func:`baud_rate`."""
    if text.strip().lower() == AUTO_BAUD:
        return None
    try:
        return baud_rate(text)
    except argparse.ArgumentTypeError as exc:
        raise argparse.ArgumentTypeError(f"{exc}, or auto") from None


def simulated_baud_refused(rate: int, profile: RobotProfile) -> str | None:
    """``sim --baud``: a rate the robot does not talk at from power-on (the profile's
    ``power_on_bauds``) is refused, since a simulated robot has just been powered on and
    nothing has sent it Baud (129); None for a rate it does. ``sim --profile roomba600
    --baud 57600`` served a robot at a rate no Roomba 600 starts at."""
    problem = profile.baud_problem(rate)
    if problem is None:
        return None
    allowed = ", ".join(str(r) for r in profile.power_on_bauds)
    return (
        f"--baud {rate}: {problem}, and a simulated robot has just been powered on; "
        f"allowed: {allowed}"
    )


def baud_warning(rate: int | None, profile: RobotProfile, *, simulated: bool) -> str | None:
    """``run``/``sensors --baud RATE``: a warning for a rate the ``--profile``'s robot does
    not talk at from power-on (a Baud command may have set it since, so the rate is still
    tried), None for one it does and for ``auto`` (None). On the simulator the simulated
    robot talks at its default rate whatever ``--baud`` says; only the stream's fit is
    checked at ``rate``. A Roomba 600 opened at 57600 was silent garbage, said only as a
    lost stream."""
    problem = None if rate is None else profile.baud_problem(rate)
    if problem is None:
        return None
    if simulated:
        then = (
            f"the simulated robot talks at {profile.default_baud} whatever --baud says; the "
            f"mission's stream is checked at {rate}"
        )
    else:
        then = "if it does not answer, --baud auto finds the rate it talks at"
    return f"warning: --baud {rate}: {problem}; {then}"


def port_name(text: str) -> str:
    """``--port``: a device path as given, or a URL pyserial opens
    (:func:`~roomba_bt.transport.open_failure.url_problem`, which ``Connection.open`` asks
    too). A typo in a URL is a usage error here; it was "could not open" (exit 3) with a fix
    about the device's group. So is a path to a regular file or a folder
    (:func:`~roomba_bt.transport.open_failure.not_a_device`): a retry cannot mend it. Imported
    here: ``validate`` and ``show`` load no serial port (tests/cli/test_imports)."""
    from roomba_bt.transport.open_failure import not_a_device, url_problem

    problem = url_problem(text)
    if problem is None and "://" not in text:
        problem = not_a_device(text)
    if problem is not None:
        raise argparse.ArgumentTypeError(problem)
    return text


def add_profile_option(parser: Any, what: str = "the robot's model", *, auto: bool = False) -> None:
    """``--profile``, the same on every command (``run``, ``sensors``, ``validate``, ``show``,
    ``eval``, ``sim``): its choices, what it changes, and where it comes from when not given
    (``ROOMBA_BT_PROFILE``, the project file, the default: :mod:`roomba_bt.cli.profile_choice`,
    which each command asks; argparse leaves None to say "not given"). ``auto``: the command
    connects to a robot and may identify it (``run``, ``sensors``). They had no help, and
    ``sim`` took free text."""
    models = ", ".join(
        f"{name} ({profile.title}{'; the default' if profile is DEFAULT_PROFILE else ''})"
        for name, profile in PROFILES.items()
    )
    identify = (
        "; auto: identify the robot on --port as doctor does, without a Reset" if auto else ""
    )
    parser.add_argument(
        "--profile", choices=sorted(PROFILES) + (["auto"] if auto else []), default=None,
        help=f"{what}: {models}{identify}. Default: ROOMBA_BT_PROFILE, else profile under "
        "[tool.roomba-bt] in a pyproject.toml above the mission (or the current directory), "
        "else create2. It sets the stream checksum (a Roomba 500's leaves the "
        "header out), how packet 35 reports the OI mode (a Roomba 600's reads the mode + 1) "
        "and the commands there are (a Roomba 500 has no Reset 7 or Stop 173; Digit LEDs "
        "Raw 163 does not work on current firmware of any of them); roomba-bt doctor tells which",
    )  # fmt: skip


def add_far_end_options(parser: Any, *, port_help: str, world_help: str) -> None:
    """What a command talks to (``run``, ``sensors``): ``--port`` (none: the simulator),
    ``--profile``, ``--baud`` (a rate or auto) and the simulator's ``--world``."""
    parser.add_argument("--port", type=port_name, help=port_help)
    add_profile_option(parser, auto=True)
    parser.add_argument(
        "--baud", type=baud_or_auto, default=115200,
        help="baud rate (default 115200), or auto: the OI's rate the robot answers at",
    )  # fmt: skip
    parser.add_argument("--world", help=world_help)


#: ``run --label``'s longest: the page's tab, its header and the summary's line show it whole
LABEL_LENGTH = 40


def run_label(text: str) -> str:
    """``run --label TEXT``: which run this is, to a person running several from one laptop
    (``blue robot``, ``group 3``): 1 to :data:`LABEL_LENGTH` printable characters, spaces
    inside allowed (around it, dropped). A control or invisible character (``ESC [2J``, a
    bidi override) is refused, not escaped: the label is shown in the terminal's live tree,
    its log lines and a browser's tab, and is the user's own choice."""
    label = text.strip()
    allowed = f"1 to {LABEL_LENGTH} printable characters, e.g. --label 'robot 3'"
    if not label:
        raise argparse.ArgumentTypeError(f"found an empty label; allowed: {allowed}")
    if not label.isprintable():
        odd = next(c for c in label if not c.isprintable())
        raise argparse.ArgumentTypeError(
            f"found the unprintable character U+{ord(odd):04X} (a control or invisible one); "
            f"allowed: {allowed}"
        )
    if len(label) > LABEL_LENGTH:
        raise argparse.ArgumentTypeError(f"found {len(label)} characters; allowed: {allowed}")
    return label


def seconds(text: str) -> float:
    """A time in seconds, 0 or more (``0.1``)."""
    return _real(text, "seconds, 0 or more", lambda value: value >= 0)


def duration(text: str) -> float:
    """A duration above 0 as ``--timeout`` takes it (``10``, ``10s``, ``1min``:
    :func:`parse_timeout`), as an argparse type: ``doctor --listen``."""
    value = parse_timeout(text, "")
    if isinstance(value, str):
        raise argparse.ArgumentTypeError(value.removeprefix(" ").strip())
    assert value is not None  # a text was given
    return value


def _real(text: str, allowed: str, fits: Callable[[float], bool]) -> float:
    """``text`` as a finite number that ``fits``; else the usage error saying what was found
    and what is ``allowed``."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"found {text!r}; allowed: {allowed}") from None
    if not (math.isfinite(value) and fits(value)):
        raise argparse.ArgumentTypeError(f"found {text}; allowed: {allowed}")
    return value


#: ``run --watchdog``'s least, seconds: two stream periods (15 ms each: 0.03 s). Less trips between
#: two frames that come on time; 0 turned off the watchdog, and with it every stall and
#: stream-loss check: a stopped stream froze the mission clock and the run hung, the robot
#: driving on with its last command, until Ctrl-C.
MIN_WATCHDOG = 2 * SLOT_SECONDS


def watchdog_seconds(text: str) -> float:
    """``run --watchdog``: seconds, :data:`MIN_WATCHDOG` or more (it cannot be turned off)."""
    allowed = f"seconds, {MIN_WATCHDOG:g} or more (two stream frames; the watchdog cannot be off)"
    return _real(text, allowed, lambda value: value >= MIN_WATCHDOG)


def odometry_error(text: str) -> float:
    """``--odometry-error``: the simulated encoders' error, a fraction 0..0.2
    (``Faults.odometry_error``)."""
    from roomba_bt.sim.faults import MAX_ODOMETRY_ERROR

    return _real(
        text, f"a fraction in 0..{MAX_ODOMETRY_ERROR:g} (0.015: 1.5 %)",
        lambda value: 0.0 <= value <= MAX_ODOMETRY_ERROR,
    )  # fmt: skip


def add_odometry_error_option(parser: Any, what: str = "") -> None:
    """``--odometry-error`` (``eval``, ``run``): one definition, read by :func:`odometry_error`."""
    parser.add_argument(
        "--odometry-error", type=odometry_error, default=0.0, metavar="FRACTION",
        help=f"{what}the encoders' error (0..0.2; e.g. 0.015: wheel scales off by up to 1.5 %%, "
        "a heading drift of up to 0.9 deg/min; seeded; default 0: exact)",
    )  # fmt: skip


#: The simulator's faults as options (``sim``; ``run`` on the simulator; ``eval``, each
#: episode's drawn from its seed): :class:`~roomba_bt.sim.Faults`' field, its type, default
#: and help; the ranges are the field's, checked by ``Faults`` (:func:`faults_given`).
FAULT_OPTIONS: tuple[tuple[str, type, object, str], ...] = (
    ("corrupt_rate", float, 0.0, "per-byte probability"),
    ("drop_rate", float, 0.0, "per-frame probability"),
    ("latency", float, 0.0, "seconds before the robot's bytes become readable (a delay, 0..10)"),
    ("inject_text", str, "", "ASCII printed into the stream"),
    ("inject_every", float, 1.0, "seconds between texts (at least 0.015: one a frame)"),
    ("disconnect_at", float, None, "drop the line at this time (s)"),
    ("noise", float, 0.0, "analog sensor noise (raw)"),
    ("bit_flip_rate", float, 0.0, "per-byte probability"),
    ("truncate_rate", float, 0.0, "per-frame probability"),
    (
        "byte_drop_rate",
        float,
        0.0,
        "per-byte probability (0..1) that a byte from the robot is lost (a long or cheap cable: "
        "its frame is broken, the parser finds the next one)",
    ),
    ("reset_at", float, None, "the robot resets at this time (s)"),
    ("stream_stop_at", float, None, "the stream stops at this time (s)"),
    ("stream_gap_at", float, None, "the stream pauses at this time (s), then goes on"),
    ("stream_gap_s", float, 0.8, "how long the stream's gap lasts (s)"),
    (
        "sleep_at",
        float,
        None,
        "the robot falls asleep at this time (s); due in Safe or Full, which never sleep, "
        "once in Passive with the client quiet 1 s",
    ),
    ("baud_change_at", float, None, "the robot's port changes its rate at this time (s)"),
    ("baud_change_to", int, None, "the rate it changes to (default: the other OI rate)"),
    ("host_drop_rate", float, 0.0, "per-byte probability that a byte from the client is lost"),
    (
        "host_corrupt_rate",
        float,
        0.0,
        "per-byte probability that a byte from the client arrives changed",
    ),
)


def add_fault_options(parser: Any, what: str) -> None:
    """The simulator's faults, :data:`FAULT_OPTIONS` and ``--faults-from-stream``, in one
    group, the same names and ranges on every command that has a simulator (``sim``, ``run``,
    ``eval``); ``what``: the group's description (where they apply). Read by
    :func:`faults_given`. A bad cable for an hour took an hour to rehearse: only ``sim``
    had them, in real time."""
    faults = parser.add_argument_group("faults", what)
    for name, kind, default, help in FAULT_OPTIONS:
        faults.add_argument("--" + name.replace("_", "-"), type=kind, default=default, help=help)
    faults.add_argument(
        "--faults-from-stream", dest="from_stream", action="store_true",
        help="count the --...-at times from the first Stream the client sends, not from the "
        "simulator's start (a client that connects late still meets them)",
    )  # fmt: skip


def fault_fields_set(args: argparse.Namespace) -> dict[str, Any]:
    """The fault options given other than at their defaults, by their ``Faults`` fields
    (``{"host_drop_rate": 0.01, "from_stream": True}``): what a record's header keeps."""
    given = {
        name: getattr(args, name)
        for name, _, default, _ in FAULT_OPTIONS
        if getattr(args, name) != default
    }
    return given | ({"from_stream": True} if args.from_stream else {})


def fault_options_set(args: argparse.Namespace) -> list[str]:
    """The fault options given other than at their defaults, as the command line writes
    them (``--host-drop-rate 0.01``): what ``run --port`` refuses and what ``eval``'s line to
    run an episode again repeats."""
    given = fault_fields_set(args)
    from_stream = ["--faults-from-stream"] if given.pop("from_stream", False) else []
    return [f"--{name.replace('_', '-')} {value}" for name, value in given.items()] + from_stream


def faults_given(args: argparse.Namespace, **more: Any) -> Faults | str:
    """The :class:`~roomba_bt.sim.Faults` the fault options (and ``more`` of its fields:
    ``odometry_error``) describe, or what is wrong, naming the option
    (``--host-drop-rate: found 1.5; allowed: 0.0..1.0``)."""
    from roomba_bt.sim.faults import Faults

    values = {name: getattr(args, name) for name, *_ in FAULT_OPTIONS}
    try:
        return Faults(**values, from_stream=args.from_stream, **more)
    except ValueError as exc:
        field, sep, rest = str(exc).partition(": ")
        name = field.removeprefix("faults.")
        return f"--{name.replace('_', '-')}: {rest}" if sep and name in values else str(exc)


def add_strict_option(parser: Any, then: str) -> None:
    """``--strict`` (``run``, ``eval``), as pytest's and mypy's: what the command only warned
    of fails it, exit 7; first of all a mission with compile-time warnings, refused as
    ``validate --strict`` fails it, in the same words on each command. ``then``: what else
    the command's ``--strict`` fails, or does instead of starting."""
    parser.add_argument(
        "--strict", action="store_true",
        help="fail on warnings too, exit 7: a mission with compile-time warnings (as validate "
        f"--strict fails it) is not started {then}",
    )  # fmt: skip


def metres(text: str, lo: float, hi: float) -> float:
    """A distance in metres, ``lo..hi``: a plain number (metres) or a distance as missions
    write it (``1.5m``, ``150cm``, ``300 mm``)."""
    allowed = f"a distance in {lo:g}..{hi:g} m: metres (1.5) or with a unit (1.5m, 150cm)"
    return _number_or_quantity(text, "distance", 1000.0, lo, hi, allowed)


def fraction(text: str) -> float:
    """A fraction 0..1: a plain number (``0.5``) or a percent (``50%``)."""
    allowed = "a fraction in 0..1 (0.5) or a percent in 0..100 % (50%)"
    return _number_or_quantity(text, "percent", 100.0, 0.0, 1.0, allowed)


#: The most seeds ``eval --seeds`` lists (its ``--runs`` limit: each spec is made up front).
MAX_SEEDS = 1_000_000


def seed_list(text: str) -> list[int]:
    """``eval --seeds``: seeds and ranges, ``1-40,42,43`` (each range's ends included), in
    the order given: the seeds a sweep is to run (those an interrupted one did not finish,
    or a few to look at again). ``--out`` and ``--json`` keep that order. A seed given twice
    is refused, naming it: it is one episode (the seed decides it), and run twice it counted
    twice in the rate and its interval; the list was sorted and such a seed dropped without
    a word, and a user reading the records in the order typed read them in another."""
    seeds: list[int] = []
    seen: set[int] = set()
    items = [item.strip() for item in text.split(",")]
    for item in items:
        added = _seed_range(item)
        if len(seeds) + added.stop - added.start > MAX_SEEDS:  # len(): an int of C size
            raise argparse.ArgumentTypeError(f"found {text!r}: more than {MAX_SEEDS:,} seeds")
        if not seen.isdisjoint(added):
            again = [seed for seed in added if seed in seen]
            earlier = next(one for one in items if again[0] in _seed_range(one))
            where = f"in {earlier!r} and {item!r}" if earlier != item else f"as {item!r} twice"
            more = f" ({len(again)} seeds given twice)" if len(again) > 1 else ""
            raise argparse.ArgumentTypeError(
                f"found seed {again[0]} {where}{more}; allowed: each seed once (a seed is one "
                "episode, the same each time it runs: twice, it would count twice)"
            )
        seeds.extend(added)
        seen.update(added)
    return seeds


def _seed_range(item: str) -> range:
    """One item of ``--seeds``: a seed (``42``) or a range, ends included (``1-40``)."""
    allowed = "allowed: seeds 0 or more and ranges, comma-separated: 1-40,42,43"
    first, dash, last = item.partition("-")
    try:
        lo = int(first)
        hi = int(last) if dash else lo
    except ValueError:
        raise argparse.ArgumentTypeError(f"found {item!r}; {allowed}") from None
    if hi < lo:  # "found '5-3'; allowed: ... 1-40" did not say what was wrong with it
        raise argparse.ArgumentTypeError(
            f"found {item!r}: a range from high to low; allowed: from low to high, {hi}-{lo}"
        )
    if lo < 0:
        raise argparse.ArgumentTypeError(f"found {item!r}; {allowed}")
    return range(lo, hi + 1)


def battery_charge(text: str) -> float:
    """The simulator's initial charge: a :func:`fraction` above 0. An empty battery switches
    the simulated robot off (docs/simulator.md), so nothing answers: ``--battery 0`` ended
    the run as NO CONNECTION, blaming the baud rate and the cable."""
    charge = fraction(text)
    if charge == 0:
        raise argparse.ArgumentTypeError(
            f"found {text!r}: an empty battery switches the simulated robot off, and it would "
            "answer nothing (a lost connection); allowed: a charge above 0, up to 1 (0.05, 5%)"
        )
    return charge


def add_battery_option(parser: Any, what: str = "") -> None:
    """``--battery`` (``eval``, ``run``, ``sim``): one definition, read by
    :func:`battery_charge`."""
    parser.add_argument(
        "--battery", type=battery_charge, metavar="FRACTION",
        help=f"{what}initial charge, above 0 up to 1, or a percent (0.5, 50%%; default: the "
        "world's)",
    )  # fmt: skip


def _number_or_quantity(
    text: str, dimension: str, per_unit: float, lo: float, hi: float, allowed: str
) -> float:
    """``text`` as a plain number, or as a quantity of ``dimension`` the way missions write it
    (:mod:`roomba_bt.behaviours.units`) divided by ``per_unit``; in ``lo..hi``."""
    from roomba_bt.behaviours.units import UnitError, parse_quantity

    try:
        value = float(text)
    except ValueError:
        try:
            value = parse_quantity(dimension, text) / per_unit
        except UnitError:
            raise argparse.ArgumentTypeError(f"found {text!r}; allowed: {allowed}") from None
    if not lo <= value <= hi:  # NaN and inf too
        raise argparse.ArgumentTypeError(f"found {text!r}; allowed: {allowed}")
    return value


def record_size_limit(text: str) -> int:
    """``run --record-max``: a size as people write one, a number and its unit (``500MB``,
    ``2 GB``, ``1.5GiB``, ``64kb``: the units of ``recording.BYTE_UNITS``, any case), in
    bytes; at least ``recording.MIN_RECORD_MAX``. A bare number is refused: 500 what?"""
    from roomba_bt.runtime.recording import BYTE_UNITS, MIN_RECORD_MAX, size_text

    allowed = (
        f"a size with its unit, {size_text(MIN_RECORD_MAX)} or more (500MB, 2GB, 1.5GiB; "
        "units: kB MB GB TB, or KiB MiB GiB TiB)"
    )
    units = {unit.lower(): per for unit, per in BYTE_UNITS.items()}
    found = re.fullmatch(r"\s*([0-9]+(?:\.[0-9]*)?|\.[0-9]+)\s*([A-Za-z]+)\s*", text)
    per = units.get(found[2].lower()) if found else None
    if found is None or per is None:
        raise argparse.ArgumentTypeError(f"found {text!r}; allowed: {allowed}")
    size = round(float(found[1]) * per)
    if size < MIN_RECORD_MAX:
        raise argparse.ArgumentTypeError(f"found {text!r}, {size:,} bytes; allowed: {allowed}")
    return size


def count(text: str) -> int:
    """A whole number, 0 or more (``--count``)."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"found {text!r}; allowed: a whole number, 0 or more"
        ) from None
    if value < 0:
        raise argparse.ArgumentTypeError(f"found {value}; allowed: a whole number, 0 or more")
    return value


#: the most refreshes a second a live view can show: one a stream frame (every 15 ms)
MAX_REFRESH_RATE = 66.0


def refresh_rate(text: str) -> float:
    """Refreshes a second (``sensors --rate``): above 0, at most one a stream frame."""
    allowed = f"refreshes a second, above 0 and at most {MAX_REFRESH_RATE:g}"
    return _real(text, allowed, lambda value: 0 < value <= MAX_REFRESH_RATE)


def output_file(text: str) -> str:
    """A file to write (--record, --plot, eval --out): not a directory, its directory must
    exist and be writable, and the file too if it is there, checked before anything runs, so
    that a long run (a sweep of hours) does not end in ``No such file or directory``."""
    path = Path(text)
    if path.is_dir():
        raise argparse.ArgumentTypeError(f"found {text!r}: a directory; expected a file name")
    folder = path.resolve().parent
    if not folder.is_dir():
        raise argparse.ArgumentTypeError(f"found {text!r}: there is no directory {folder}")
    if not os.access(folder, os.W_OK):
        raise argparse.ArgumentTypeError(f"found {text!r}: directory {folder} is not writable")
    if path.exists() and not os.access(path, os.W_OK):
        raise argparse.ArgumentTypeError(f"found {text!r}: the file is not writable")
    return text


def output_with_suffix(*suffixes: str) -> Callable[[str], str]:
    """An :func:`output_file` whose name ends in one of ``suffixes`` (``show --dot``, ``--svg``):
    ``show m.yaml --dot m.yaml`` wrote the graph over the mission."""

    def check(text: str) -> str:
        if Path(text).suffix.lower() not in suffixes:
            raise argparse.ArgumentTypeError(
                f"found {text!r}; allowed: a file ending in {' or '.join(suffixes)}"
            )
        return output_file(text)

    return check


def record_file(text: str) -> str:
    """A file for ``--record``: as :func:`output_file`, and if it exists, an earlier record
    (written over) and nothing else: ``run m.yaml --record m.yaml`` wrote the record over
    the mission (a record has no suffix to check, as a picture or a results file has)."""
    from roomba_bt.runtime.recording import RECORD_FORMAT, open_record

    if text == "-":  # a record is a file replay reads back, not a stream: not stdout
        raise argparse.ArgumentTypeError(
            "found '-': --record writes a file, not stdout (which the run's tree and summary "
            "use); name a file (run.jsonl)"
        )
    output_file(text)

    def is_record(first: str) -> bool:
        header = _json_object(first)
        return header is not None and header.get("format") == RECORD_FORMAT

    return _written_over_only(
        text, is_record, "a record (a mission? a world?); --record writes over an earlier "
        "record only: name a new file (run.jsonl)", opener=open_record,
    )  # fmt: skip


def results_file(text: str) -> str:
    """A file for ``eval --out``: as :func:`output_file`, ``.jsonl`` or ``.csv``, and if it
    exists, earlier results and nothing else (as :func:`record_file`: an hour's sweep written
    over someone's data): a JSON Lines record or a CSV header with the seed and outcome."""
    from roomba_bt.evaluate.records import FORMATS

    output_file(text)
    suffix = Path(text).suffix.lower()
    if suffix not in FORMATS:
        raise argparse.ArgumentTypeError(
            f"found {text!r}; allowed: a file ending in {' or '.join(FORMATS)}"
        )

    def is_results(first: str) -> bool:
        record = _json_object(first) if suffix == ".jsonl" else None
        columns = set(record or ()) if suffix == ".jsonl" else set(first.strip().split(","))
        return {"seed", "outcome"} <= columns

    return _written_over_only(
        text, is_results, "an evaluation's results; --out writes over earlier results only: "
        "name a new file",
    )  # fmt: skip


def _written_over_only(
    text: str,
    is_kind: Callable[[str], bool],
    refusal: str,
    opener: Callable[[Path], io.BufferedIOBase] = lambda path: path.open("rb"),
) -> str:
    """An existing file (not empty) only if its first line says it is of the kind written
    (``is_kind``): what else is there is someone's, not ours. ``opener``: how the file's
    bytes are read (an earlier record may be compressed: ``recording.open_record``)."""
    path = Path(text)
    if not path.is_file() or path.stat().st_size == 0:
        return text
    try:
        with opener(path) as file:  # a header line, parameters and all
            first = file.readline(1 << 16).decode("utf-8", errors="replace")
    # unreadable, compressed and damaged, or compressed otherwise (open_record's RecordError)
    except (OSError, EOFError, zlib.error, ValueError):
        first = ""
    if not is_kind(first):
        raise argparse.ArgumentTypeError(f"found {text!r}: a file that is not {refusal}")
    return text


def _json_object(line: str) -> dict[str, Any] | None:
    """``line`` as a JSON object, or None (not JSON, not an object, nested too deep)."""
    try:
        value = json.loads(line)
    except (ValueError, RecursionError):
        return None
    return value if isinstance(value, dict) else None


def plot_file(text: str) -> str:
    """A picture to draw (--plot): as :func:`output_file`; matplotlib (an optional extra) must
    be installed and write the file's suffix (.png, .svg, .pdf, ...), checked before anything
    runs: a run would otherwise end in matplotlib's ``Format 'txt' is not supported``, and
    a name without a suffix would be written with ``.png`` added."""
    try:
        import matplotlib  # noqa: F401  (the package itself: it is the extra)
        from matplotlib.backend_bases import FigureCanvasBase
    except ImportError as exc:
        needs = "--plot needs matplotlib, an optional extra: pip install 'roomba-bt[plot]'"
        raise argparse.ArgumentTypeError(optional_import_failure(exc, needs)) from None
    formats = sorted(FigureCanvasBase.get_supported_filetypes())
    suffix = Path(text).suffix.lower()
    if suffix[1:] not in formats:
        raise argparse.ArgumentTypeError(
            f"found {text!r}: {f'no picture format {suffix!r}' if suffix else 'no suffix'}; "
            f"allowed: a file ending in {', '.join('.' + f for f in formats)}"
        )
    return output_file(text)


def add_param_option(parser: Any, help: str | None = None) -> None:
    """``-p/--param NAME=VALUE`` (repeatable), read by :func:`parse_params`."""
    parser.add_argument(
        "-p", "--param", action="append", default=[], metavar="NAME=VALUE", help=help
    )


def parse_params(items: list[str]) -> dict[str, str] | str:
    """``["speed=250mm/s"]`` -> ``{"speed": "250mm/s"}``; a message string on error.

    The values stay text: the mission compiler reads them against each parameter's type and
    unit, and names the file and line where a value does not fit.
    """
    params: dict[str, str] = {}
    for item in items:
        name, sep, value = item.partition("=")
        if not sep or not name.strip():
            return f"-p {item!r}: expected NAME=VALUE, e.g. -p speed=250mm/s"
        params[name.strip()] = value.strip()
    return params


def parse_timeout(text: str | None, option: str = "--timeout") -> float | str | None:
    """``--timeout`` (or ``option``): seconds (``90``) or a duration as a mission writes one
    (``5min``, ``1d``, ``1h30min``: :func:`~roomba_bt.behaviours.units.parse_quantity`, the
    one grammar), above 0; a message string on error, None if not given."""
    if text is None:
        return None
    from roomba_bt.behaviours.units import UnitError, parse_quantity

    try:
        value = float(text)
    except ValueError:
        try:
            value = parse_quantity("duration", text)
        except UnitError as exc:
            return f"{option} {text!r}: {exc}"
    if not math.isfinite(value) or value <= 0:  # float() takes "nan" and "inf"
        return f"{option} {text!r}: must be a finite duration, more than 0 s"
    return value


#: ``--display``'s choices and what each shows, live (``run``)
DISPLAYS = {
    "auto": "the live tree on a terminal, else the log",
    "tree": "the tree",
    "log": "one line per status change",
    "none": "only the summary",
}


def add_display_option(parser: argparse.ArgumentParser, *, live: bool) -> None:
    """``--display``, one wording for ``run`` (``live``: every choice, ``auto`` its default)
    and ``replay``, which reads the record as fast as it can: a live tree would only flicker,
    so its ``tree`` is the tree as its last tick replayed left it, drawn once, and ``none``, the
    summary alone as before the option, its default. ``replay --display none`` was a usage
    error (its top-level usage) while ``run`` had the option."""
    choices = tuple(DISPLAYS) if live else ("tree", "log", "none")
    shown = {**DISPLAYS, "tree": "the tree" if live else "the tree as the last tick left it"}
    default = "auto" if live else "none"
    said = ", ".join(f"{shown[choice]} ({choice})" for choice in choices)
    parser.add_argument(
        "--display", choices=choices, default=default, help=f"{said}; default {default}"
    )


def add_window_options(parser: argparse.ArgumentParser, *, start: bool) -> None:
    """``--to`` (and with ``start``, ``--from``): a window of a long record's mission time,
    read by :func:`parse_window` (``monitor RECORD``, ``replay``)."""
    if start:
        parser.add_argument(
            "--from", dest="window_from", metavar="DURATION",
            help="keep the ticks from this mission time on, e.g. 1h30min (the run before it "
            "is replayed all the same, its events shown; the memory is the window's)",
        )  # fmt: skip
    parser.add_argument(
        "--to", dest="window_to", metavar="DURATION",
        help="end the replay at this mission time, e.g. 2h (the rest of the record is not read)",
    )  # fmt: skip


def parse_window(args: argparse.Namespace) -> tuple[float, float | None] | str:
    """``(--from, --to)`` in seconds of mission time (0 and None when not given), each a
    duration as ``--timeout`` takes it; a message string on error."""
    start = parse_timeout(getattr(args, "window_from", None), "--from")
    end = parse_timeout(args.window_to, "--to")
    if isinstance(start, str):
        return start
    if isinstance(end, str):
        return end
    if start is not None and end is not None and start >= end:
        return f"--from {args.window_from} is not before --to {args.window_to}"
    return start or 0.0, end


def limit_seconds(text: str, option: str) -> float | str | None:
    """A limit's ``option`` (``--wall-limit``, ``--worker-wait``): a duration in seconds
    (:func:`parse_timeout`), or ``none`` (no limit: None); a message when it is neither."""
    if text.strip().lower() == "none":
        return None
    limit = parse_timeout(text, option)
    return f"{limit}, or none" if isinstance(limit, str) else limit


def add_wall_limit_option(parser: Any, per: str, then: str) -> None:
    """``--wall-limit`` (``eval``, ``run``): one wording, read by :func:`limit_seconds`;
    ``per``: what the time is of, ``then``: what follows it and the default."""
    parser.add_argument(
        "--wall-limit", metavar="DURATION",
        help=f"wall-clock time {per}, after which it is recorded as HUNG (stuck: an endless "
        f"loop in a behaviour, named with its file:line) {then}",
    )  # fmt: skip


def mission_file(text: str) -> str | tuple[str]:
    """A mission argument as a path: an existing file, else the shipped mission of that name
    (``roomba-bt run dock``); ``(problem,)`` when neither exists, the name's control
    characters escaped (``run`` and ``eval`` printed a newline in it, a line of their own
    faked after it, where ``validate`` and ``show`` escaped it). The mission package (its
    compiler, the behaviours, py_trees and YAML) is imported here, when a command names a
    mission, not with the parser every command builds: ``roomba-bt --version`` or ``sim``
    need none of it."""
    from roomba_bt.mission.shipped import find_mission

    found = find_mission(text)
    if found.path is not None:
        return str(found.path)
    return (escaped(found.problem, ANY_CONTROL),)


def given_once(command: str, found: list[tuple[str, str]], done: str) -> list[tuple[str, str]]:
    """``(as given, path)`` of each mission argument, a file given twice kept once, at its
    first place (by its real path: ``dock.yaml ./dock.yaml``, a folder and a file in it, a
    shipped name and its file), the others said on stderr as a warning, ``done`` once
    (``checked``, ``evaluated``). ``validate`` said such a file twice, counted twice; ``eval``
    ran it as an A/B against itself, or refused "the same variant twice"."""
    first: dict[str, str] = {}
    kept = []
    for given, path in found:
        # "": not found (said by the caller), once a name; a path that exists is no such name
        real = os.path.realpath(path) if path else given
        same = first.get(real)
        if same is None:
            first[real] = given
            kept.append((given, path))
            continue
        again = "given twice" if same == given else f"{escaped(same, ANY_CONTROL)} again"
        print(
            f"roomba-bt {command}: warning: {escaped(given, ANY_CONTROL)} is {again}: {done} once",
            file=sys.stderr,
        )
    return kept


def add_permission_options(parser: argparse.ArgumentParser) -> None:
    """What a mission file may reach, granted here and never by the file: its plugin files
    (Python, imported) and include folders beyond its own folder tree and the shipped library."""
    parser.add_argument(
        "--allow-plugin-files",
        action="store_true",
        help="import the Python files the mission names under plugins: (a mission file runs "
        "no code without it; installed plugin packages need no permission)",
    )
    parser.add_argument(
        "--include-dir",
        action="append",
        default=[],
        metavar="DIR",
        type=include_dir,
        help="a folder the mission may also include from, and import plugin files from with "
        "--allow-plugin-files (repeatable; for every command: ROOMBA_BT_INCLUDE_PATH, or "
        "include-dirs under [tool.roomba-bt] in a pyproject.toml above the mission)",
    )


def include_dir(text: str) -> Path:
    """An existing folder (``--include-dir``); a file is said to be one, with its folder
    (``--include-dir lib/escapes.yaml`` was "there is no such directory"), and so is a pipe, a
    device or a broken link (:func:`~roomba_bt.printable.special_file`)."""
    folder = Path(text)
    if folder.is_file():
        raise argparse.ArgumentTypeError(
            f"found {text!r}: a file, not a folder; give the folder that holds it "
            f"(--include-dir {folder.parent})"
        )
    if not folder.is_dir():
        kind = special_file(folder)
        what = "there is no such directory" if kind is None else f"{kind}, not a folder"
        raise argparse.ArgumentTypeError(f"found {text!r}: {what}")
    return folder


def permissions(args: argparse.Namespace, mission: str | Path | None = None) -> Permissions:
    """The :class:`~roomba_bt.mission.Permissions` the user grants ``mission``: the command
    line's, and the include folders of ``ROOMBA_BT_INCLUDE_PATH`` and of the project file
    above the mission (:mod:`roomba_bt.mission.include_path`, which says what a project
    file may grant). What does not grant is said once on stderr, as a warning: the include
    it was meant for is refused at its own line. The messages about them, and about ``-p``
    values, name the command line's flags."""
    from roomba_bt.mission import Permissions
    from roomba_bt.mission.include_path import configured_include_dirs
    from roomba_bt.mission.wording import COMMAND_LINE

    given = tuple(getattr(args, "include_dir", None) or ())
    configured = configured_include_dirs(mission)
    for warning in configured.warnings:
        warn_once(warning)
    return Permissions(
        plugin_files=bool(getattr(args, "allow_plugin_files", False)),
        include_dirs=tuple(dict.fromkeys((*given, *configured.folders))),
        wording=COMMAND_LINE,
    )


#: The warnings :func:`warn_once` has printed in this process.
_WARNED: set[str] = set()


def warn_once(message: str) -> None:
    """``message`` on stderr as a warning, once a process: ``validate`` of every mission of
    a repository reads the same project file for each, and said its problem each time."""
    if message in _WARNED:
        return
    _WARNED.add(message)
    print(f"roomba-bt: warning: {escaped(message, ANY_CONTROL)}", file=sys.stderr)
