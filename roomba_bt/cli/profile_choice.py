"""Which robot model a command speaks to, written once: the flag, then the environment, then
the project, then the default.

An owner of a Roomba 500 gave ``--profile roomba500`` to every ``run``, ``validate``,
``sensors`` and ``eval``, and a forgotten one was a two-second failure and a rerun. The model
may now be named once:

1. ``--profile NAME`` on the command line;
2. ``ROOMBA_BT_PROFILE=NAME`` in the environment (a shell's, a CI job's);
3. ``profile = "NAME"`` under ``[tool.roomba-bt]`` in the project file
   (:mod:`roomba_bt.project`: above the mission, as its ``include-dirs`` are; above the
   current directory for a shipped mission named by name and for a command that reads no
   mission);
4. the default, ``create2``.

``auto`` (from any of them) identifies the robot on ``--port`` when ``run`` and ``sensors``
connect (:func:`roomba_bt.cli.links.auto_profile`); a command that talks to no robot
(``validate``, ``show``, ``eval``, ``sim``, a run on the simulator) says so and takes the
default. A name that is no profile is a usage error naming the variable, or the project
file and line, and the names allowed.

The library reads neither: ``Connection.open``, ``load_mission`` and
``RunStack`` take the model from their ``profile=`` argument, ``create2`` when none is given,
so a program does the same in any shell and any folder (a CI job's ``ROOMBA_BT_PROFILE``
meant for the command line, a ``pyproject.toml`` in the folder a notebook was started from,
would otherwise change the model, and with it the commands it may send, without a line of
the program saying so). A program that wants the command line's choice asks for it by name:
:func:`configured_profile`, and passes what it returns.
"""

from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

from roomba_bt.errors import RoombaBtError
from roomba_bt.oi.profiles import DEFAULT_PROFILE, PROFILES
from roomba_bt.printable import ANY_CONTROL, escaped
from roomba_bt.project import PROFILE_KEY, PROJECT_FILE, PROJECT_TABLE, find_project_file, key_line

#: The environment variable naming the robot's model for every command.
PROFILE_VARIABLE = "ROOMBA_BT_PROFILE"

#: ``--profile auto``: the model identified on the port at connection.
AUTO_PROFILE = "auto"

#: Where ``--profile`` came from when nothing named it.
DEFAULT_SOURCE = "the default"

#: Where a user reads about it, said in the messages: the help an installed user has (it
#: said docs/robot.md, which the wheel does not ship).
DOCUMENTED_AT = "roomba-bt run --help, --profile"


@dataclass(frozen=True, slots=True)
class ProfileChoice:
    """A profile's name (or :data:`AUTO_PROFILE`) and where it came from, in the words a
    message uses: ``--profile``, ``ROOMBA_BT_PROFILE``, ``/p/pyproject.toml:4`` or
    :data:`DEFAULT_SOURCE`."""

    name: str
    source: str

    @property
    def named(self) -> bool:
        """Somebody named it (the flag, the environment, a project file)."""
        return self.source != DEFAULT_SOURCE


def allowed_names(auto: bool) -> str:
    """The names a setting may hold, in a message."""
    return ", ".join((*PROFILES, *((AUTO_PROFILE,) if auto else ())))


@dataclass(frozen=True, slots=True)
class BadSetting:
    """A setting that names no profile: the project file and line it is written at (``file``
    empty: the environment variable), and what is wrong with it, the names allowed."""

    message: str
    file: str = ""
    line: int = 0

    def __str__(self) -> str:
        where = f"{self.file}:{self.line}" if self.line else self.file
        return f"{where}: {self.message}" if where else self.message


def choose_profile(
    flag: str | None,
    near: Path | None = None,
    *,
    environ: Mapping[str, str] | None = None,
) -> ProfileChoice | BadSetting:
    """The profile the command line (``flag``: None when ``--profile`` was not given), the
    environment (``environ``, the process's by default) and the project file above ``near``
    (a mission's path; None: the current directory) name, first that names one; or where
    the bad value is written and the names allowed. ``auto`` is taken from any of them:
    whether the command can identify a robot is its caller's to say."""
    if flag is not None:
        return ProfileChoice(flag, "--profile")
    named = environment_profile(environ)
    if named is not None:
        return named
    return _from_project(near) or ProfileChoice(DEFAULT_PROFILE.name, DEFAULT_SOURCE)


def environment_profile(
    environ: Mapping[str, str] | None = None,
) -> ProfileChoice | BadSetting | None:
    """What ``ROOMBA_BT_PROFILE`` names (None: it is not set, or empty)."""
    env = os.environ if environ is None else environ
    value = env.get(PROFILE_VARIABLE, "").strip()
    if not value:
        return None
    if value.lower() not in (*PROFILES, AUTO_PROFILE):
        return BadSetting(
            f"{PROFILE_VARIABLE}={escaped(value, ANY_CONTROL)!r}: no robot profile of that "
            f"name; allowed: {allowed_names(True)} ({DOCUMENTED_AT})"
        )
    return ProfileChoice(value.lower(), PROFILE_VARIABLE)


def _from_project(near: Path | None) -> ProfileChoice | BadSetting | None:
    """The project file's ``profile``, or its problem, or None (no project file, no key).
    A project file that cannot be read (another user's, not TOML) names no profile, said
    as a warning once (the include folders' reading says the same words: once in all)."""
    from roomba_bt.cli.arguments import warn_once

    found = find_project_file(near if near is not None else Path.cwd() / PROJECT_FILE)
    if isinstance(found, str):
        warn_once(found)
    if not isinstance(found, tuple):
        return None
    path, table = found
    if not isinstance(table, dict) or PROFILE_KEY not in table:
        return None
    value = table[PROFILE_KEY]
    line = key_line(path, PROFILE_KEY)
    if not isinstance(value, str) or value.strip().lower() not in (*PROFILES, AUTO_PROFILE):
        return BadSetting(
            f"[tool.{PROJECT_TABLE}] {PROFILE_KEY} = {escaped(repr(value), ANY_CONTROL)}: no "
            f"robot profile of that name; allowed: {allowed_names(True)} ({DOCUMENTED_AT})",
            str(path),
            line,
        )
    return ProfileChoice(value.strip().lower(), f"{path}:{line}" if line else str(path))


class ProfileSettingError(ValueError, RoombaBtError):
    """``ROOMBA_BT_PROFILE`` or the project file's ``profile`` names no robot profile
    (:func:`configured_profile`): the message names the variable, or the file and line, and
    the names allowed, as the command line's usage error does."""


def configured_profile(near: str | Path | None = None) -> str:
    """The robot model the command line takes when no ``--profile`` is given, for a Python
    program that wants the same: ``ROOMBA_BT_PROFILE``, then ``profile`` under
    ``[tool.roomba-bt]`` in the project file above ``near`` (a mission file's path; None:
    the current directory), then ``create2``. Its name, for ``profile=`` of
    ``Connection.open``, ``load_mission`` or ``get_profile``; ``"auto"`` when the setting
    asks for the robot to be identified (``roomba_bt.robot.discovery.identify_robot`` on the
    open port). None of the library's functions reads these by itself (the module
    docstring says why). Raises :class:`ProfileSettingError` for a setting that names no
    profile."""
    choice = choose_profile(None, None if near is None else Path(near))
    if isinstance(choice, BadSetting):
        raise ProfileSettingError(str(choice))
    return choice.name


def resolved_profile(
    flag: str | None, command: str, near: Path | None = None, *, port: str | None = None
) -> ProfileChoice | BadSetting:
    """:func:`choose_profile`, with ``auto`` kept only where ``command`` connects to a robot
    on ``port`` (``run``, ``sensors`` given ``--port``); otherwise ``auto`` is the default,
    said on stderr once a process (``validate`` of a repository's every mission)."""
    choice = choose_profile(flag, near)
    if isinstance(choice, BadSetting) or choice.name != AUTO_PROFILE or port:
        return choice
    whom = "the simulator simulates" if command in SIMULATING else f"{command} talks to no robot"
    note = (
        f"roomba-bt {command}: {profile_said(choice)} identifies a robot on --port; {whom}: "
        f"the {DEFAULT_PROFILE.title} ({DEFAULT_PROFILE.name}), the default"
    )
    if note not in _NOTED:
        _NOTED.add(note)
        print(note, file=sys.stderr)
    return ProfileChoice(DEFAULT_PROFILE.name, DEFAULT_SOURCE)


#: The commands that run the simulator (``run`` and ``sensors`` without ``--port``).
SIMULATING = ("run", "sensors", "sim", "eval")

#: The notes :func:`resolved_profile` has printed in this process.
_NOTED: set[str] = set()


def chosen_profile(args: argparse.Namespace, command: str, near: Path | None = None) -> str | None:
    """``args.profile`` made the name ``command`` speaks to (or ``auto``, to identify on its
    ``--port``) and ``args.profile_source`` where it came from (:func:`resolved_profile`); a
    usage error instead (None: done)."""
    choice = resolved_profile(args.profile, command, near, port=getattr(args, "port", None))
    if isinstance(choice, BadSetting):
        return str(choice)
    args.profile, args.profile_source = choice.name, choice.source
    return None


def mission_near(given: str, found: str) -> Path | None:
    """Where a mission's project file is looked for: above the mission file the user gave
    (``given``, found at ``found``), as its include folders are; a shipped mission named by
    name (``dock``) is the current directory's project's (None)."""
    return Path(found) if Path(given).is_file() else None


def profile_said(choice: ProfileChoice) -> str:
    """How a message names the setting: ``--profile auto``, ``ROOMBA_BT_PROFILE=auto``,
    ``profile = "auto" (/p/pyproject.toml:4)``."""
    if choice.source == "--profile":
        return f"--profile {choice.name}"
    if choice.source == PROFILE_VARIABLE:
        return f"{PROFILE_VARIABLE}={choice.name}"
    return f'{PROFILE_KEY} = "{choice.name}" ({choice.source})'


def profile_setting(args: argparse.Namespace) -> str | None:
    """Where ``args.profile`` was set, as the robot layer words a wrong profile's fix
    (``Connection.profile_setting``, :func:`~roomba_bt.robot.errors.profile_fix`):
    ``--profile``, ``ROOMBA_BT_PROFILE`` or the project file's ``path:line``, where the fix
    is made (``ROOMBA_BT_PROFILE=create2`` was told "use --profile roomba500", which fixed
    one command and not the next); None for the default, and for a model ``auto``
    identified (nothing to set but the model itself)."""
    source: str = getattr(args, "profile_source", DEFAULT_SOURCE)
    # auto's is "--profile auto: identified ..." (cli/links.py); a file's is path:line
    return None if source == DEFAULT_SOURCE or ": " in source else source


def profile_line(args: argparse.Namespace) -> str:
    """The summary's profile line (``run``, ``eval``): as the runtime says it (nothing for
    the default, ``roomba500 (Roomba 500 series)`` for one the flag named), and where it
    came from when the flag did not name it: ``..., from ROOMBA_BT_PROFILE``."""
    from roomba_bt.runtime.summary import profile_shown

    profile = PROFILES[args.profile]
    source = getattr(args, "profile_source", DEFAULT_SOURCE)
    if source in (DEFAULT_SOURCE, "--profile"):
        return profile_shown(profile)
    return f"{profile.name} ({profile.title}), from {source}"
