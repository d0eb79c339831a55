"""Exit codes of ``roomba-bt``, documented in the README and ``docs/runtime.md``."""

from __future__ import annotations

from enum import IntEnum


class ExitCode(IntEnum):
    OK = 0  # mission succeeded / command did what was asked
    MISSION_FAILED = 1  # the tree ended in FAILURE (or the timeout ran out)
    INVALID = 2  # invalid mission, world or command-line usage
    CONNECTION = 3  # port could not be opened, robot did not answer, stream lost
    INTERRUPTED = 130  # Ctrl-C or SIGTERM, after the safe stop
