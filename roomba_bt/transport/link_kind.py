"""What kind of link a port is (a device path, a pty's own path, a network bridge), and the
words every message about that link uses.

A Wi-Fi bridge's user was told to "reseat the cable" of a robot behind an ESP8266, that a
network stall was "a frozen adapter or cable?", and "check the cable and its adapter" after
jitter. Each message took its words from its own ``if``, most from none. Here the port's name
is read once (:func:`link_of`), and a message asks its :class:`LinkWords` for the link's part:
what failed, what to check, what to do to reach the robot again. The same kind decides whether
a failed port is opened again for the safe stop (:attr:`LinkWords.reopens`) and whether BRC
can cross it (:attr:`LinkWords.modem_lines`).
"""

from __future__ import annotations

import enum
from dataclasses import dataclass, replace

#: the network URLs: a bridge (ser2net, esp-link, an ESP8266's raw TCP port) or ``roomba-bt
#: sim --tcp`` / ``--rfc2217``
NETWORK_PORTS = ("socket://", "rfc2217://")
#: Where a pseudo-terminal's own device paths are (Linux; macOS names its ``/dev/ttys00N``)
PTY_DEVICES = ("/dev/pts/", "/dev/ttys")


class LinkKind(enum.Enum):
    """What is between this computer and the robot's serial port."""

    DEVICE = "device"  # a serial adapter's device path, or a link to one (/dev/serial/by-id)
    PTY = "pty"  # a pseudo-terminal's own /dev/pts/N (a simulator, socat)
    NETWORK = "network"  # socket:// or rfc2217://: a bridge on the network
    OTHER = "other"  # loop:// and the like: no robot's line at all


@dataclass(frozen=True, slots=True)
class LinkWords:
    """A link's kind and its part of every message: each field is a phrase a message puts
    where it names the line, worded for the port's kind."""

    kind: LinkKind
    #: what is between this computer and the robot, as a message names it: "the cable", or
    #: "the bridge at HOST:PORT" (doctor's fixes name the bridge by it)
    between: str
    #: what a port that failed most likely means
    gone: str
    #: the line, as the last of a silent robot's causes ("switched off, a flat battery, or ...")
    line: str
    #: a stream that stopped and came back
    froze: str
    #: what rides such a gap through next time ("" where nothing is worth saying)
    gap_fix: str
    #: what to check when frames are lost or late, or commands are not obeyed
    check: str
    #: the likely causes of a port that could not be opened, when its error tells none
    open_causes: tuple[str, ...]
    #: doctor's fix for a port that could not be opened, its error telling no cause
    open_fix: str
    #: why a port was refused (ECONNREFUSED): nothing listens at its address
    refused: str
    #: why a port's address could not be reached (no route, the connect timed out); "" where
    #: no address is crossed
    unreachable: str
    #: where bytes between this computer and the robot are lost ("a loose or noisy cable?")
    lossy: str
    #: what a byte read wrong after a lost one points at ("a bad cable: a data byte 7 ...")
    bad_line: str
    #: what to check when bytes to the robot were found lost ("check the cable and ...")
    byte_check: str
    #: what a fall to Passive after such lost bytes points at ("so the cable is a likely cause")
    serial_side: str
    #: the robot's silence at start-up laid on the line's wiring (beside a wrong rate, sleep)
    wiring: str
    #: why a port gives back what is written to it (a loopback, not a robot)
    echo_causes: tuple[str, ...]
    #: how BRC reaches the robot where keep-awake could not pulse it on this port
    pulse_fix: str
    #: what to do to reach the robot again after a stop that did not get through: for a
    #: device or a bridge, bring the line back, then ``roomba-bt doctor`` on it; for a pty,
    #: that its path will not come back (its number goes to the next program that opens a
    #: pty, and doctor there would write its Query Lists and hang-up into that program)
    reach: str
    #: what comes back when a port that failed is opened again
    reopened: str
    #: why a connection carried nothing for the grace and did not close (a network's: the
    #: only kind taken for dead by its silence, ``silence.dead_connection``)
    went_silent: str
    #: whether a port that failed is opened again for the safe stop: a device path comes
    #: back (a loose connector, an adapter that reset) and a bridge's new connection reaches
    #: the same robot's serial port; a pty's own number, reused, is another program's line
    reopens: bool
    #: whether the modem lines (BRC) can reach the robot: False on a raw TCP bridge, which
    #: carries bytes only; None where only trying tells (a device, RFC 2217, a pty)
    modem_lines: bool | None
    #: why no BRC pulse can be given where the lines cannot be set
    no_modem_lines: str
    #: what a link without modem lines means for sleep, and what to do (keep-awake's warning)
    sleep_advice: str


# Long on purpose: one phrase a field, a table of the network's words read side by side with
# the cable's below (a message is worded by reading both)
def _network_words(port: str) -> LinkWords:
    """A bridge on the network: its address, its power and its Wi-Fi's reach."""
    scheme, _, rest = port.partition("://")
    where = rest.split("?", 1)[0].rstrip("/")
    bridge = f"the bridge at {where}"
    serves = "--tcp" if scheme.lower() == "socket" else "--rfc2217"
    serial_side = f"the serial side of {bridge}"
    return LinkWords(
        kind=LinkKind.NETWORK,
        between=bridge,
        gone="the bridge closed the connection or the network dropped",
        line=f"the network: is {bridge} powered and in Wi-Fi range?",
        froze="the network or the bridge stalled: Wi-Fi?",
        gap_fix=(
            "a larger --grace rides such a gap through, a larger --watchdog the shorter ones "
            f"without a drive 0; and look at {bridge}'s placement and power"
        ),
        check=(
            f"check the network: {bridge}, its power and its Wi-Fi signal; a larger --watchdog "
            "and --grace ride a Wi-Fi link's gaps through"
        ),
        open_causes=(
            "a wrong address or port",
            f"{bridge} off, rebooting or out of Wi-Fi range",
            "another client holding it",
        ),
        open_fix=(
            f"check the address, that {bridge} is powered and in Wi-Fi range on this "
            "computer's network, and that no other client holds it"
        ),
        refused=(
            f"nothing listens at {where}: is the bridge there running, and are its address and "
            f"port right? (roomba-bt sim {serves} serves one)"
        ),
        unreachable=(
            f"{bridge} cannot be reached: off, rebooting or out of Wi-Fi range, a wrong "
            "address, or this computer on another network"
        ),
        lossy=f"a loose or noisy wire on {serial_side}",
        bad_line=f"a bad wire on {serial_side}",
        byte_check=f"{serial_side}, its wiring to the robot: the network delivers bytes whole",
        serial_side=serial_side,
        wiring=(
            f"{serial_side} wired wrong (TX/RX swapped, a 3.3 V bridge without a level shifter on "
            "the robot's 5 V line) or at another rate than the robot's"
        ),
        echo_causes=(
            f"{bridge} gives back what it is sent (an echo service, or its serial side's "
            "transmit and receive lines joined)",
            "the wrong address",
        ),
        pulse_fix=(
            f"BRC must cross {bridge}: rfc2217:// to a bridge that wires BRC to RTS or DTR "
            "(esp-link can), or BRC on a pin of the bridge"
        ),
        reach=(
            f"wait for {bridge} to come back (it reset, or the Wi-Fi dropped), then "
            f"roomba-bt doctor --port {port}"
        ),
        reopened="the connection",
        went_silent=(
            f"{bridge} rebooted or left Wi-Fi range, and no reset reached this computer; "
            "or the robot switched off"
        ),
        reopens=True,
        modem_lines=False if port.lower().startswith("socket://") else None,
        no_modem_lines=(
            "a raw TCP bridge (socket://) has no modem lines: no BRC pulse reaches the robot "
            "(rfc2217:// to a bridge that wires BRC, as esp-link can, or BRC on a pin of the "
            "bridge does)"
        ),
        sleep_advice=(
            "a robot left 5 minutes in Passive sleeps, on its dock too, where Safe does not "
            "hold (the powered charger drops it to Passive, both specs): keep it in Safe off "
            "the dock"
        ),
    )


#: What to do about a pty that failed under a run: nothing comes back at its path. A stranger
#: was told "reseat the cable, then roomba-bt doctor --port /dev/pts/0" after the simulator
#: was killed; by then /dev/pts/0 was another program's pty (the kernel hands out the lowest
#: free number), and doctor wrote its Query Lists and a 1 s hang-up into it. The run's own
#: stop refuses such a path (``device_identity.py``); the advice no longer sends a user there.
_PTY_GONE = (
    "{port} will not come back (a pty's number goes to the next program that opens one: "
    "doctor there would talk to that program): start the simulator or bridge again and use "
    "the path it prints"
)


#: What a pty that failed most likely means: the program that held its other end (the
#: simulator, socat) ended or closed it. A run on ``sim --pty`` whose simulator was killed
#: ended "the port is gone (the cable was pulled or the adapter reset)" in its outcome, while
#: the advice under it (:data:`_PTY_GONE`) already spoke of the simulator.
_PTY_ENDED = (
    "the program at its other end, the simulator or a bridge such as socat, ended or closed it"
)


def _pty_words(port: str) -> LinkWords:
    """A pty's own path: a serial adapter's words where a bridge such as socat may carry the
    bytes to one, the program at its other end's where the simulator is there: its end
    (:data:`_PTY_ENDED`), the way back to it (:data:`_PTY_GONE`), and the line where a
    message names it (what to check, what loses bytes, what stalled, what is wired, what
    gives back its bytes, what carries BRC): ``sim --pty``, whose fault options lose and
    damage bytes on purpose and which stalls on a busy computer, or the cable behind a
    bridge, both said. A run on ``sim --pty --host-drop-rate 0.05`` said "(a loose or noisy
    cable?)", "so the cable is a likely cause" and "check the cable and its adapter" of a
    simulator told to drop bytes; one on ``sim --pty --asleep`` blamed "wrong cable or
    wiring", and a pty that echoed "loop:// or another test port"."""
    bridge = "a bridge such as socat"
    behind = f"behind {bridge}"
    host_faults = "the simulator's --host-drop-rate or --host-corrupt-rate"
    return replace(
        _cable_words(LinkKind.PTY, reopens=False, port=port),
        gone=_PTY_ENDED,
        reach=_PTY_GONE.format(port=port),
        line=f"the program at the pty's other end (the simulator, or {bridge} and the "
        "cable behind it)",
        froze=f"a stalled simulator, or the adapter or cable {behind}?",
        check=(
            "check what is at the pty's other end: the simulator's fault options (--drop-rate, "
            f"--host-drop-rate and the like lose bytes on purpose), or the cable and adapter "
            f"{behind}"
        ),
        lossy=f"the simulator's --host-drop-rate, or a loose or noisy cable {behind}",
        bad_line=f"a lossy line behind the pty ({host_faults}, or a bad cable {behind})",
        byte_check=(
            "the simulator's fault options (--host-drop-rate, --host-corrupt-rate), or the "
            f"cable and adapter {behind}"
        ),
        serial_side=f"the line behind the pty ({host_faults}, or the cable {behind})",
        between=f"the program at the pty's other end (the simulator, or {bridge})",
        wiring=(
            "a pty that is not the simulator's (give the path roomba-bt sim --pty printed), "
            f"or a cable {behind} wired wrong (TX/RX swapped, adapter not a 5 V TTL serial)"
        ),
        echo_causes=(
            "a program at the pty's other end that gives back what it is sent, not the "
            "simulator (give the path roomba-bt sim --pty printed)",
            f"a cable or adapter {behind} whose transmit and receive lines are joined",
        ),
        pulse_fix=(
            "a pty carries no modem lines: roomba-bt sim --rfc2217 carries BRC to the "
            "simulator's robot, and a robot's cable with BRC on RTS or DTR does it opened by "
            f"its own device path, not through {bridge}"
        ),
    )


def _cable_words(kind: LinkKind, reopens: bool, port: str) -> LinkWords:
    """A serial adapter's link (a device path, ``loop://``; a pty's words start from
    these, :func:`_pty_words`): its cable and adapter."""
    return LinkWords(
        kind=kind,
        between="the cable",
        gone="the cable was pulled or the adapter reset",
        line="the cable",
        froze="a frozen adapter or cable?",
        gap_fix="",
        check="check the cable and its adapter",
        open_causes=(
            "wrong device path or URL",
            "the port in use by another program",
            "permissions",
        ),
        open_fix=(
            "check the device path (ls /dev/ttyUSB* /dev/serial/by-id/), that no other "
            "program has it open, and that you may use it (the dialout group on Linux)"
        ),
        refused="nothing listens there (is the bridge, or roomba-bt sim --tcp, running?)",
        unreachable="",
        lossy="a loose or noisy cable",
        bad_line="a bad cable",
        byte_check="the cable and its adapter",
        serial_side="the cable",
        wiring="wrong cable or wiring (TX/RX swapped, adapter not a 5 V TTL serial)",
        echo_causes=(
            "loop:// or another test port given as the robot's",
            "a cable or adapter whose transmit and receive lines are joined",
            "the wrong device",
        ),
        pulse_fix="use a USB cable with BRC on RTS or DTR, or an rfc2217:// bridge",
        reach=f"reseat the cable, then roomba-bt doctor --port {port}",
        reopened="the port",
        # never said: a device path's silence is the stream's or the robot's (the port
        # itself fails when the adapter goes), and a pty's never comes back
        went_silent="",
        reopens=reopens,
        modem_lines=None,
        no_modem_lines="no modem lines on this port",
        # what is known of any such port, a pty's or a device's: no pulse can be sent, and a
        # robot (the simulator's too) left 5 minutes in Passive sleeps. It said "a simulator
        # never sleeps" of every one, and the same run then ended as the simulator fell asleep
        sleep_advice="Passive sleeps after 5 min",
    )


def link_of(port: str) -> LinkWords:
    """The kind and the words of the link named ``port`` (a ``--port`` value)."""
    if port.lower().startswith(NETWORK_PORTS):
        return _network_words(port)
    if "://" in port:
        return _cable_words(LinkKind.OTHER, reopens=False, port=port)
    if port.startswith(PTY_DEVICES):
        return _pty_words(port)
    return _cable_words(LinkKind.DEVICE, reopens=True, port=port)
