"""The protocol layer's error types.

One error type for every bad argument (:class:`EncodeError`), so that a caller can catch
exactly "this command could not be encoded" and a user reads which command, which argument,
what is allowed and what was given.
"""

from __future__ import annotations

from roomba_bt.errors import RoombaBtError


class OIError(RoombaBtError):
    """Base of every error raised by :mod:`roomba_bt.oi`."""


class EncodeError(OIError, ValueError):
    """An argument is out of range or of the wrong type; no byte was produced."""

    def __init__(self, command: str, argument: str, allowed: str, value: object) -> None:
        self.command = command
        self.argument = argument
        self.allowed = allowed
        self.value = value
        super().__init__(f"{command}: {argument} must be {allowed}, got {value!r}")


class UnsupportedCommandError(OIError, ValueError):
    """The command exists in the OI but not on the chosen robot profile."""

    def __init__(self, command: str, profile: str, available_on: tuple[str, ...]) -> None:
        self.command = command
        self.profile = profile
        self.available_on = available_on
        super().__init__(
            f"{command} is not available on {profile}; it exists on {', '.join(available_on)}"
        )


class BandwidthError(OIError, ValueError):
    """A stream request would not fit in one 15 ms slot at the configured baud rate."""

    def __init__(self, frame_bytes: int, budget: int, baud: int) -> None:
        self.frame_bytes = frame_bytes
        self.budget = budget
        self.baud = baud
        super().__init__(
            f"stream frame of {frame_bytes} bytes does not fit in 15 ms at {baud} baud "
            f"(at most {budget} bytes); request fewer packets or a higher baud rate"
        )
