"""Kept for old imports until 0.3.0: baud discovery and the BRC wake are
:mod:`roomba_bt.robot.discovery` (the session's start-up handshake is ``Connection.start``,
:mod:`roomba_bt.robot.startup`). Importing this warns, naming the new path."""

from roomba_bt._lazy import warn_moved_module
from roomba_bt.robot.discovery import (
    Found,
    Probe,
    Search,
    describe_silence,
    drain,
    find_robot,
    is_answer,
    probe,
    rates_to_try,
    search,
    wake_pulse,
)

__all__ = [
    "Found",
    "Probe",
    "Search",
    "describe_silence",
    "drain",
    "find_robot",
    "is_answer",
    "probe",
    "rates_to_try",
    "search",
    "wake_pulse",
]

warn_moved_module("roomba_bt.robot.handshake", "import from roomba_bt.robot.discovery instead")
