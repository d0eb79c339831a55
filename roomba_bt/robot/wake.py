"""Keep-awake: pulse the BRC pin low once a minute so a robot in Passive never sleeps.

The Roomba 600 / Create 2 OI spec ("Passive Mode"): in Passive the robot sleeps after five
minutes of inactivity; "to disable sleep, pulse the BRC pin low periodically before these
five minutes expire. Each pulse resets this five minute counter", e.g. low for one second
every minute, which does not change the baud rate. A sleeping robot answers nothing and its
stream stops, so a mission waiting on the dock for a charge would end as a lost stream.

The USB cables wire BRC to a modem line (RTS on most, DTR on some): a transport that can
drive it has ``set_wake_line(low)`` (``SerialTransport`` drives RTS and DTR together, the
simulator's links model the pin). Asserted means BRC low::

    BRC  ──────┐     ┌──────────── ... ──────┐     ┌────
               └─────┘                       └─────┘
               t     t+1 s                   t+60 s

A transport without the method (a TCP bridge without RFC 2217, a replay) gets no pulses; the
connection says so once. Nor does a port whose lines cannot be set (a pty: the ioctl fails,
keep-awake turns itself off, said once): the hang-up that pulses BRC there once, to ask
whether a silent robot sleeps (:func:`~roomba_bt.robot.discovery.wake_pulse`), carries no
byte for its second, and a pulse a minute would stall the stream once a minute.
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Callable
from contextlib import AbstractContextManager
from typing import Protocol, runtime_checkable

from roomba_bt.oi.profiles import PASSIVE_SLEEP_S
from roomba_bt.robot import wording
from roomba_bt.robot.errors import StreamStalled
from roomba_bt.transport.link_kind import LinkKind, link_of

log = logging.getLogger(__name__)

#: Passive without activity for this long: the robot sleeps (600 spec, "Passive Mode").
SLEEP_AFTER_S = PASSIVE_SLEEP_S
#: Seconds between the starts of two pulses (well inside the five minutes).
PULSE_PERIOD_S = 60.0
#: Seconds BRC is held low: short enough not to be read as the baud-change gesture.
PULSE_LENGTH_S = 1.0
#: A line change that takes this long is remembered, to name a stall it caused
#: (:func:`named_stall`): a USB cable's ioctl takes microseconds.
HELD_S = 0.01


@runtime_checkable
class WakeLine(Protocol):
    """A transport that can drive the robot's BRC pin (asserted = low)."""

    def set_wake_line(self, low: bool) -> None: ...


@runtime_checkable
class HangUpLine(Protocol):
    """A transport that can hang its line up (output speed 0: DTR and RTS drop) for a block
    and restore the rate after: the BRC pulse where the modem lines cannot be set one by one
    (:meth:`~roomba_bt.transport.serial_port.SerialTransport.hung_up`)."""

    def hung_up(self) -> AbstractContextManager[None]: ...


class KeepAwake:
    """Pulses BRC low for :data:`PULSE_LENGTH_S` every :data:`PULSE_PERIOD_S`, driven by
    :meth:`tick` with the link's clock (so it runs on the virtual clock too)."""

    def __init__(
        self,
        line: WakeLine,
        *,
        period: float = PULSE_PERIOD_S,
        length: float = PULSE_LENGTH_S,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        if not 0.0 < length < period:
            raise ValueError(f"pulse length {length} s must be in 0..period ({period} s)")
        self.line = line
        self._clock = clock
        #: the last line change that took :data:`HELD_S` or more: when it ended (``clock``)
        #: and how long it took, or None
        self.held: tuple[float, float] | None = None
        self.period = period
        self.length = length
        self.pulses = 0
        #: called once, after the warning, when the line turns out unable to pulse (a pty):
        #: the runtime names the mission's waits that then cannot finish (runtime/long_run.py)
        self.on_unavailable: Callable[[str], None] | None = None
        self.last_pulse: float | None = None
        #: why the line cannot be driven (then no more pulses), or None
        self.unavailable: str | None = None
        self._low_until: float | None = None
        self._next: float | None = None
        #: the link time from which :meth:`tick` has something to do (a pulse to start or to
        #: end; infinity once the line cannot be driven): before it, a tick would do nothing,
        #: so the caller, which ticks before every read, need not call it
        self.due = -math.inf

    def tick(self, now: float) -> None:
        """Start or end a pulse if it is time; the first pulse starts at the first tick. A
        port that cannot drive the lines (a pty has none) turns keep-awake off, said once."""
        if self.unavailable is not None:
            return
        try:
            if self._low_until is not None:
                if now >= self._low_until:
                    self._set(False)
                    self._low_until = None
                    self.due = self._next if self._next is not None else -math.inf
                return
            if self._next is None or now >= self._next:
                self._set(True)
                self.pulses += 1
                self.last_pulse = now
                self._low_until = self.due = now + self.length
                self._next = now + self.period
                if self.pulses == 1:
                    self._say_the_wake()
        except OSError as exc:
            self.unavailable = str(exc)
            self._low_until = None
            self.due = math.inf
            # one line: on a 40-column SSH screen the whole story was ten lines, every run
            # what keep-awake is, whether it matters and how to silence it: "keep-awake off
            # (...: [Errno 25] Inappropriate ioctl for device): Passive sleeps after 5 min
            # (-v: why; --no-keep-awake)" on every pty run said none of it to a hobbyist
            words, caller = link_of(getattr(self.line, "name", "")), wording.current
            log.warning(
                "keep-awake (a BRC pulse a minute: Passive never sleeps) is off: %s; %s; "
                "%s silences this (%s)",
                words.no_modem_lines, words.sleep_advice, caller.keep_awake_off, caller.why,
            )  # fmt: skip
            log.debug(
                "keep-awake off (%s): no hang-up pulse instead (it would blank the stream for its "
                "second). A pty or a plain socket has no modem lines: the simulator serves "
                "them with --rfc2217; %s says it is meant",
                exc.strerror or exc, caller.keep_awake_off,
            )  # fmt: skip
            if self.on_unavailable is not None:
                self.on_unavailable(words.no_modem_lines)

    def _say_the_wake(self) -> None:
        """Said once, at the first pulse the line took: a robot that slept on its dock
        overnight is woken by BRC pulled low (the port's open asserted the lines, and this
        pulse holds them), which a 9:00 run's log did not say while docs/robot.md said the
        start-up could not wake it. Whether it slept no byte tells (a robot woken says
        nothing), so it is said as what the pulse does. Not on the simulator in this process
        (``sim://``), whose runs would each get the line."""
        name = getattr(self.line, "name", "")
        if link_of(name).kind is not LinkKind.OTHER:
            log.info(
                "%s: BRC pulled low (RTS and DTR: the port's open and keep-awake's first "
                "pulse): a robot that slept (on its dock overnight) is woken by it",
                name,
            )

    def _set(self, low: bool) -> None:
        """Drive the line, remembering a change that held the caller (:attr:`held`)."""
        clock = self._clock
        began = clock()
        self.line.set_wake_line(low)
        ended = clock()
        if ended - began >= HELD_S:
            self.held = (ended, ended - began)

    def release(self) -> None:
        """Leave BRC high (end of a run)."""
        if self._low_until is not None and self.unavailable is None:
            self.line.set_wake_line(False)
            self._low_until = None
            self.due = self._next if self._next is not None else -math.inf


def named_stall(
    stalled: StreamStalled, wake: KeepAwake | None, since: float
) -> StreamStalled | None:
    """The stall ``stalled`` naming the keep-awake line change that held the reads during it
    (one that ended after ``since``, the last valid frame: the stall is then this process's
    own, not the line's), or None if none did."""
    held = wake.held if wake is not None else None
    if held is None or held[0] <= since:
        return None
    note = (
        f"a keep-awake BRC pulse held this process's reads for {held[1] * 1000:.0f} ms "
        "(setting the modem lines)"
    )
    return StreamStalled(
        stalled.port, stalled.silent_for, stalled.watchdog, stalled.halted, stalled.mismatch,
        held=note,
    )  # fmt: skip


def keep_awake_for(transport: object, name: str, enabled: bool) -> KeepAwake | None:
    """A :class:`KeepAwake` on ``transport`` when enabled and the transport has the line;
    None (with one log line saying why the robot may sleep) otherwise."""
    if not enabled:
        return None
    if not isinstance(transport, WakeLine):
        log.info(
            "%s: no modem line to pulse BRC on this link: a robot left in Passive sleeps "
            "after 5 minutes",
            name,
        )
        return None
    now = getattr(transport, "now", None)
    return KeepAwake(transport, clock=now) if callable(now) else KeepAwake(transport)
