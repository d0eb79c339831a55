"""``roomba-bt clock``: set the robot's own clock and weekly cleaning schedule, or clear it.

Two commands of the OI do it, in Passive, Safe or Full, changing no mode::

    Set Day/Time (168)  [168][day][hour][minute]                  day 0 Sunday .. 6 Saturday
    Schedule (167)      [167][days][sun h][sun m] ... [sat h][sat m]   days: bit 0 Sunday

No sensor packet reports either, so on a robot the command says what it sent, and what the
robot's buttons showed (it ignores both while its Clock or Schedule button is pressed); on
the simulator it reads back what the simulated robot holds. The Create 2 is refused:
``RobotProfile.clock_missing`` (docs/protocol.md, "The clock and the schedule"). The robot is
left in Passive on every ending (``talk_to_robot``).
"""

from __future__ import annotations

import argparse
import datetime
import re
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

from roomba_bt.cli.arguments import add_command, add_far_end_options
from roomba_bt.runtime.summary import INTERNAL_ERROR_SAID, ExitCode

if TYPE_CHECKING:
    from roomba_bt.oi.encode import Command
    from roomba_bt.oi.profiles import RobotProfile
    from roomba_bt.robot.connection import Connection
    from roomba_bt.sim import Simulator

#: the days as a message names them, the OI's order (0 Sunday)
DAY_TITLES = ("Sunday", "Monday", "Tuesday", "Wednesday", "Thursday", "Friday", "Saturday")
_TIME = re.compile(r"(?P<hour>\d{1,2}):(?P<minute>\d{2})")
TIME_ALLOWED = "a 24-hour time HH:MM, 00:00 to 23:59 (the OI takes hours 0-23, minutes 0-59)"
DAY_ALLOWED = "sun, mon, tue, wed, thu, fri, sat, or a day's whole name (monday), any case"
SCHEDULE_ALLOWED = (
    'days and 24-hour times, comma-separated: "mon 09:30, wed 10:00" (each day at most '
    "once; --clear-schedule for none)"
)


def register(sub: Any) -> None:
    parser = add_command(
        sub,
        "clock",
        clock_command,
        f"""set a Roomba 500/600's clock and weekly cleaning schedule

        Set the robot's day and time (Set Day/Time, 168) from this computer's clock
        (--set-now) or as given (--day, --time), and its weekly cleaning schedule
        (Schedule, 167: --schedule "mon 09:30, wed 10:00", or a YAML file of days and times,
        --schedule-file) or clear it (--clear-schedule).
        Without any of them, say what can be known: no sensor packet reports the clock or
        the schedule, so on a robot only whether its Clock or Schedule button is pressed
        (the robot ignores both commands while one is); the simulator (no --port) shows
        what it holds. The robot is left in Passive. The Create 2 (the default profile)
        keeps no schedule and is refused: give --profile roomba600 or roomba500. Exit
        codes: 0 done, 2 invalid option or a profile without a clock (nothing sent), 3
        connection failure or the Clock or Schedule button pressed (nothing sent),
        {INTERNAL_ERROR_SAID}, 130 interrupted. More: roomba-bt docs robot, "The robot's
        clock and weekly schedule".
        """,
    )
    add_far_end_options(
        parser,
        port_help="serial device or URL; default: the built-in simulator",
        world_help="simulator world (without --port)",
    )
    when = parser.add_mutually_exclusive_group()
    when.add_argument(
        "--set-now", action="store_true",
        help="set the day and time from this computer's local time, to the nearest minute",
    )  # fmt: skip
    when.add_argument("--day", type=weekday, help="the day to set (with --time): mon, Monday, ...")
    parser.add_argument("--time", type=time_of_day, help="the time to set (with --day): HH:MM")
    weekly = parser.add_mutually_exclusive_group()
    weekly.add_argument(
        "--schedule", type=weekly_schedule, metavar="'DAY HH:MM, ...'",
        help='clean on these days at these times: "mon 09:30, wed 10:00"; other days not',
    )  # fmt: skip
    weekly.add_argument(
        "--schedule-file", type=Path, metavar="FILE",
        help="the same from a YAML file of days and times (mon: 09:30, one a line)",
    )  # fmt: skip
    weekly.add_argument(
        "--clear-schedule", action="store_true", help="no scheduled cleaning (all 0s)"
    )


def weekday(text: str) -> int:
    """``--day``: a day as the OI numbers it (0 Sunday)."""
    from roomba_bt.oi.encode import day_number
    from roomba_bt.oi.errors import EncodeError

    try:
        return day_number(text.strip())
    except EncodeError:
        raise argparse.ArgumentTypeError(f"found {text!r}; allowed: {DAY_ALLOWED}") from None


def time_of_day(text: str) -> tuple[int, int]:
    """``--time``: a 24-hour ``HH:MM`` as (hour, minute)."""
    found = _TIME.fullmatch(text.strip())
    if found is None or int(found["hour"]) > 23 or int(found["minute"]) > 59:
        raise argparse.ArgumentTypeError(f"found {text!r}; allowed: {TIME_ALLOWED}")
    return int(found["hour"]), int(found["minute"])


def weekly_schedule(text: str) -> dict[str, tuple[int, int]]:
    """``--schedule``: ``"mon 09:30, wed 10:00"`` as ``{"mon": (9, 30), "wed": (10, 0)}``;
    the entry at fault named by its place and text."""
    times: dict[str, tuple[int, int]] = {}
    for place, entry in enumerate(text.split(","), 1):
        words = entry.split()
        said = f"entry {place}, {entry.strip()!r}"
        if len(words) != 2:
            raise argparse.ArgumentTypeError(
                f"{said}: found {len(words)} word(s); allowed: {SCHEDULE_ALLOWED}"
            )
        try:
            _add_day(times, words[0], words[1])
        except argparse.ArgumentTypeError as exc:
            raise argparse.ArgumentTypeError(f"{said}: {exc}") from None
    return times


def _add_day(times: dict[str, tuple[int, int]], day_text: str, time_text: str) -> None:
    """One day of a schedule and its time, as written, added to ``times``; a day given a
    second time, or a day or time that is none, is an ArgumentTypeError saying so."""
    day = _day_once(times, day_text)
    times[day] = time_of_day(time_text)


def _day_once(times: dict[str, tuple[int, int]], day_text: str) -> str:
    """``day_text``'s day (``mon``), refused if it is none or ``times`` holds it already."""
    from roomba_bt.oi.bits import WEEKDAYS

    day = WEEKDAYS[weekday(day_text)]
    if day in times:
        raise argparse.ArgumentTypeError(
            f"{DAY_TITLES[WEEKDAYS.index(day)]} a second time; allowed: each day at most once"
        )
    return day


class ScheduleFileError(ValueError):
    """What is wrong with a ``--schedule-file``: at ``file:line:col`` when ``placed``."""

    def __init__(self, message: str, placed: bool) -> None:
        super().__init__(message)
        self.placed = placed


def schedule_file(path: Path) -> dict[str, tuple[int, int]]:
    """``--schedule-file``: a YAML mapping of days to 24-hour times, one a line::

        # the robot cleans on Monday at 09:30 and on Thursday at 18:00
        mon: 09:30
        thursday: "18:00"

    as :func:`weekly_schedule`'s dict (an empty mapping, ``{}``: no scheduled cleaning; an
    empty file is refused, as a file cut short may be); :class:`ScheduleFileError` says what
    is wrong, at ``file:line:col`` where it has a place. A file with no day among its keys
    is said not to be a schedule, quoting none of it (a path may name any file)."""
    import yaml

    from roomba_bt import yamlsource
    from roomba_bt.oi.bits import WEEKDAYS

    shown = f"--schedule-file {yamlsource.quoted(str(path))}"
    try:
        root = yamlsource.compose(yamlsource.read_text(path))
    except OSError as exc:
        raise ScheduleFileError(f"{shown}: {exc.strerror or exc}", False) from None
    except (UnicodeDecodeError, yamlsource.FileTooLarge) as exc:
        raise ScheduleFileError(f"{shown}: not a schedule file ({exc})", False) from None
    except yaml.YAMLError as exc:
        line, column = yamlsource.error_position(exc) or (1, 1)
        problem = getattr(exc, "problem", None) or exc
        raise ScheduleFileError(f"{path}:{line}:{column}: {problem}", True) from None
    if root is None:
        raise ScheduleFileError(
            f"{shown}: the file holds no days; allowed: days and their times (mon: 09:30), "
            "or {} for no scheduled cleaning (--clear-schedule)", False,
        )  # fmt: skip
    if isinstance(root, yaml.MappingNode) and not root.value:
        return {}
    days = (*WEEKDAYS, *(title.lower() for title in DAY_TITLES))
    if not isinstance(root, yaml.MappingNode) or not yamlsource.holds_some_of(root, days):
        raise ScheduleFileError(
            f"{shown}: not a schedule file: expected a mapping of days to 24-hour times, one "
            "a line (mon: 09:30)", False,
        )  # fmt: skip
    times: dict[str, tuple[int, int]] = {}
    for key, value in root.value:
        at = key  # the node a problem is said at: the day's, or its time's
        try:
            if not isinstance(key, yaml.ScalarNode) or not isinstance(value, yaml.ScalarNode):
                raise argparse.ArgumentTypeError(
                    "found a list or a mapping; allowed: a day and its 24-hour time (mon: 09:30)"
                )
            day = _day_once(times, key.value)
            at = value
            times[day] = time_of_day(value.value)
        except argparse.ArgumentTypeError as exc:
            line, column = yamlsource.position(at)
            raise ScheduleFileError(f"{path}:{line}:{column}: {exc}", True) from None
    return times


def host_now() -> datetime.datetime:
    """This computer's local time (a test's stand-in replaces it)."""
    return datetime.datetime.now()


def nearest_minute(now: datetime.datetime) -> tuple[int, int, int]:
    """``now`` as the OI's day (0 Sunday), hour and minute, to the nearest minute: the OI
    takes no seconds, so 21:35:50 is sent as 21:36 (10 s ahead, not 50 s behind)."""
    rounded = (now + datetime.timedelta(seconds=30)).replace(second=0, microsecond=0)
    return rounded.isoweekday() % 7, rounded.hour, rounded.minute


def clock_said(day: int, hour: int, minute: int) -> str:
    return f"{DAY_TITLES[day]} {hour:02d}:{minute:02d}"


def schedule_said(times: dict[str, tuple[int, int]]) -> str:
    """``Mon 09:30, Wed 10:00`` (Sunday first), or that nothing is scheduled."""
    from roomba_bt.oi.bits import WEEKDAYS

    if not times:
        return "none (no scheduled cleaning)"
    return ", ".join(
        f"{day.title()} {times[day][0]:02d}:{times[day][1]:02d}" for day in WEEKDAYS if day in times
    )


def _commands(args: argparse.Namespace) -> list[tuple[str, Command]]:
    """What to send, in order (the clock first), each with what it sets, said."""
    from roomba_bt.oi import commands

    sent: list[tuple[str, Command]] = []
    if args.set_now:
        day, hour, minute = nearest_minute(host_now())
        sent.append((f"clock     {clock_said(day, hour, minute)}",
                     commands.set_day_time(day, hour, minute)))  # fmt: skip
    elif args.day is not None:
        sent.append((f"clock     {clock_said(args.day, *args.time)}",
                     commands.set_day_time(args.day, *args.time)))  # fmt: skip
    if args.schedule is not None or args.clear_schedule:
        times: dict[str, tuple[int, int]] = args.schedule or {}
        sent.append((f"schedule  {schedule_said(times)}", commands.schedule(times)))
    return sent


def clock_command(args: argparse.Namespace) -> int:
    from roomba_bt.cli.links import talk_to_robot

    if (args.day is None) != (args.time is None):
        given, missing = ("--day", "--time") if args.time is None else ("--time", "--day")
        print(f"roomba-bt clock: {given} needs {missing} too (the OI sets a day and a time "
              "together: --day wed --time 15:30), or --set-now", file=sys.stderr)  # fmt: skip
        return ExitCode.INVALID
    if args.schedule_file is not None:
        try:
            args.schedule = schedule_file(args.schedule_file)
        except ScheduleFileError as exc:
            print(exc if exc.placed else f"roomba-bt clock: {exc}", file=sys.stderr)
            return ExitCode.INVALID
        args.clear_schedule = not args.schedule
    to_send = _commands(args)

    def session(connection: Connection, simulator: Simulator | None) -> int:
        return _set(connection, simulator, to_send)

    def refuse(profile: RobotProfile, baud: int | None) -> str | None:
        return without_clock(profile, args)

    return talk_to_robot(args, "clock", session, refuse=refuse)


def without_clock(profile: RobotProfile, args: argparse.Namespace) -> str | None:
    """The refusal of a model that keeps no clock, with the fix made where the model was
    named (``ROOMBA_BT_PROFILE=create2`` was told to give --profile, which fixed one
    command and not the next): the flag, the variable or the project file's line."""
    from roomba_bt.cli.profile_choice import profile_setting
    from roomba_bt.project import PROFILE_KEY

    missing = profile.clock_missing()
    if missing is None:
        return None
    setting = profile_setting(args)
    if setting is None or setting.startswith("-"):
        fix = "give --profile roomba600 (or roomba500)"
    elif setting.isidentifier():
        fix = f"set {setting}=roomba600 (or roomba500), or give --profile roomba600"
    else:
        fix = f'set {PROFILE_KEY} = "roomba600" (or "roomba500") at {setting}'
    return f"{missing}: {fix} if your robot is one"


def _set(
    connection: Connection, simulator: Simulator | None, to_send: list[tuple[str, Command]]
) -> int:
    """Start in Passive, look at the Clock and Schedule buttons, send ``to_send``, and say
    what was sent and, on the simulator, what it holds now."""
    from roomba_bt.oi.bits import held_clock_buttons
    from roomba_bt.oi.packets import packet_ids
    from roomba_bt.robot.errors import ConnectionFailed

    connection.start("passive")
    frame = connection.query(packet_ids("buttons"))
    if frame is None:
        raise ConnectionFailed(connection.name, "no reply to a Query List (149) of its buttons")
    held = held_clock_buttons(frame[18])
    print(f"{connection.name}  ({connection.profile.title}), {connection.mode.label}")
    if held and to_send:
        print(f"roomba-bt clock: the robot's {held} button is pressed, and while it is the "
              "robot ignores Set Day/Time (168) and Schedule (167) (both OI specs); nothing "
              "was sent: release it and run this again", file=sys.stderr)  # fmt: skip
        return ExitCode.CONNECTION
    if to_send:
        connection.send_many(command for _, command in to_send)
        for said, command in to_send:
            print(f"sent {said}   [{' '.join(str(b) for b in command.data)}]")
    if simulator is not None:
        print(
            f"the simulator's clock     {clock_said(*simulator.robot_clock.shows(simulator.time))}"
        )
        print(f"the simulator's schedule  {schedule_said(simulator.robot_clock.cleans)}")
    elif not to_send:
        pressed = (
            f"its {held} button is pressed"
            if held
            else "its Clock and Schedule buttons are not pressed"
        )
        print(
            "the robot reports neither its clock nor its schedule (no sensor packet carries "
            f"them; its display shows the clock); {pressed}. Set them with --set-now or "
            '--day/--time, and --schedule "mon 09:30, ..." or --clear-schedule'
        )
    return ExitCode.OK
