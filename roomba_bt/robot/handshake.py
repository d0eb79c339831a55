"""Kept for old imports: baud discovery and the BRC wake are :mod:`roomba_bt.robot.discovery`
(the session's start-up handshake is ``Connection.start``, :mod:`roomba_bt.robot.startup`)."""

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
