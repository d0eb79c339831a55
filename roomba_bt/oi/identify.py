"""Telling robots apart by what they say: the reset banner, the stream's checksum, the mode.

Three things a robot shows without being told which model it is (``roomba-bt doctor`` reads
them; the simulator produces them from its profile):

* **The reset banner.** Reset (7) exists only on the Roomba 600 / Create 2 (the 500 spec has
  no opcode 7: a 500 stays silent). The firmware prints a welcome text that names its
  release, for example (a Roomba 620, and the spec's own example)::

      Roomba by iRobot!
      battery-current-zero 258
      r3_robot/tags/release-3.2.6:4975 CLEAN
      ...
      r3_robot/tags/release-stm32-3.7.7

  The 600 spec (Appendix B, "Dock wakeup"): firmware older than release-3.8.2 /
  release-stm32-3.7.7 does not wake by a BRC pulse while on the dock.
* **The stream checksum.** The 600 / Create 2 sum the header byte 19 into the checksum, the
  500 spec's example leaves it out (``docs/protocol.md``): a checksum that leaves it out is a
  500's. One that covers it rules nothing out: the 500 shares the 600's firmware, so which
  rule a real 500 follows is not certain, and the ``roomba500`` profile takes both.
* **The mode reading right after Start.** Passive is 1; firmware that reports mode + 1 reads
  2. Of the profiles only the Roomba 600 has that bug (``reports_mode_plus_one``): a 2 tells
  a 600, a 1 rules no model out (a 600 on firmware without the bug reads 1 too, and then
  looks like a Create 2 to every probe here but its label).
* **Values only one model's ranges allow.** The 500's wall signal (27) reaches 4095, the 600's
  1023; the 600's stasis (58) reads 2 or 3 (the wheel too dirty to read), the 500's 0 or 1. A
  reading outside a profile's range rules that profile out (a reading inside both says
  nothing: most readings).
"""

from __future__ import annotations

import re
from abc import ABC, abstractmethod
from collections.abc import Mapping
from dataclasses import dataclass
from typing import ClassVar

from roomba_bt.oi.frames import STREAM_HEADER, layout_for
from roomba_bt.oi.modes import OI_MODE_PACKET
from roomba_bt.oi.packets import PACKETS, packet_ids
from roomba_bt.oi.profiles import DEFAULT_PROFILE, PROFILES, RobotProfile

#: The packets whose ranges differ between the models: a reading only one allows tells it.
MODEL_RANGE_PACKETS: tuple[int, ...] = packet_ids("wall_signal", "stasis")
#: The first release of each firmware line that wakes by BRC on the dock (600 spec, App. B).
BRC_DOCK_WAKE_FIXED: dict[str, tuple[int, int, int]] = {
    "release": (3, 8, 2),
    "release-stm32": (3, 7, 7),
}
_RELEASE = re.compile(r"(release(?:-stm32)?)-(\d+)\.(\d+)\.(\d+)")


@dataclass(frozen=True, slots=True)
class FirmwareVersion:
    """A firmware release as the banner names it: ``release-stm32-3.7.7``."""

    line: str  # "release" or "release-stm32"
    number: tuple[int, int, int]

    @property
    def text(self) -> str:
        return f"{self.line}-{'.'.join(str(n) for n in self.number)}"

    @property
    def wakes_by_brc_on_dock(self) -> bool:
        """False before release-3.8.2 / release-stm32-3.7.7 (the 600 spec's Appendix B)."""
        return self.number >= BRC_DOCK_WAKE_FIXED[self.line]


def parse_firmware(text: str) -> FirmwareVersion | None:
    """The first ``release-X.Y.Z`` or ``release-stm32-X.Y.Z`` in ``text``, or None."""
    found = _RELEASE.search(text)
    if found is None:
        return None
    line, *numbers = found.groups()
    major, minor, patch = (int(n) for n in numbers)
    return FirmwareVersion(line, (major, minor, patch))


@dataclass(frozen=True, slots=True)
class Banner:
    """What the robot printed after Reset (7): its text and the firmware it names."""

    text: str
    firmware: FirmwareVersion | None


def parse_banner(data: bytes) -> Banner | None:
    """The banner in ``data`` (bytes read after Reset), or None if ``data`` holds no text
    (a Roomba 500, which has no Reset, answers nothing)."""
    text = data.decode("ascii", errors="replace")
    printable = sum(ch.isprintable() or ch in "\r\n" for ch in text)
    if not text.strip() or printable < 0.9 * len(text):
        return None
    return Banner(text, parse_firmware(text))


def checksum_covers_header(frame: bytes) -> bool | None:
    """Whether one stream frame ``[19][n][payload...][checksum]`` sums its header into the
    checksum (600 / Create 2: True) or not (500: False); None if neither sum is 0 (not a
    frame, or a corrupted one)."""
    if len(frame) < 3 or frame[0] != STREAM_HEADER or frame[1] != len(frame) - 3:
        return None
    total = sum(frame) & 0xFF
    if total == 0:
        return True
    if (total - STREAM_HEADER) & 0xFF == 0:
        return False
    return None


@dataclass(frozen=True, slots=True)
class Identification:
    """The profiles that fit what was seen, best first, and why."""

    candidates: tuple[RobotProfile, ...]
    evidence: tuple[str, ...]

    @property
    def best(self) -> RobotProfile | None:
        return self.candidates[0] if self.candidates else None

    @property
    def decided(self) -> bool:
        """One model fits: the evidence told it (several: it did not tell which)."""
        return len(self.candidates) == 1

    @property
    def cautious(self) -> RobotProfile | None:
        """Of several that fit, the one that sends no command another of them lacks (the
        ``roomba500``: no Reset 7, no Stop 173, whose effect on a 500 is written nowhere);
        the best when one fits, None when none does or none is so."""
        for profile in self.candidates:
            if all(set(profile.commands) <= set(other.commands) for other in self.candidates):
                return profile
        return self.best

    @property
    def assumed(self) -> RobotProfile:
        """The profile to speak to the robot with: the one that fits; of several, the
        default if it is one (the evidence cannot tell a Create 2 from a 600 without the
        mode + 1 bug or a 500 whose checksum covers the header, and a Create 2 owner is the
        likelier), else
        :attr:`cautious`; the default when none fits. ``doctor`` and ``--profile auto``
        fall back alike."""
        if self.best is None or (not self.decided and DEFAULT_PROFILE in self.candidates):
            return DEFAULT_PROFILE
        return self.cautious or DEFAULT_PROFILE


def identify(
    *,
    mode_plus_one: bool | None,
    header_in_checksum: bool | None,
    banner: Banner | None = None,
    reset_tried: bool = False,
    readings: Mapping[int, int] | None = None,
) -> Identification:
    """The profiles consistent with the evidence. ``reset_tried`` with no ``banner``: the
    robot ignored Reset, which only the 500 does. ``readings``: raw packet values seen (packet
    id -> value); each rules out the profiles whose range does not hold it."""
    candidates = list(PROFILES.values())
    evidence: list[str] = []

    if reset_tried:
        has_reset = banner is not None
        candidates = [p for p in candidates if p.has_command("reset") is has_reset]
        evidence.append(
            "it printed a banner after Reset (7): a 600 or a Create 2"
            if has_reset
            else "it ignored Reset (7): the Roomba 500 has none"
        )
    if header_in_checksum is not None:
        total = 0 if header_in_checksum else STREAM_HEADER
        candidates = [p for p in candidates if total in p.checksum_sums]
        evidence.append(
            "its stream checksum covers the header (a 600 or a Create 2, or a Roomba 500: "
            "which rule a 500 follows is not certain)"
            if header_in_checksum
            else "its stream checksum leaves the header out (Roomba 500)"
        )
    if mode_plus_one:
        candidates = [p for p in candidates if p.reports_mode_plus_one]
        evidence.append("it reports the OI mode + 1 (the Roomba 600 firmware bug)")
    elif mode_plus_one is not None:
        # rules no model out: the bug is some 600 firmware's, not every 600's, and the
        # runtime learns the offset whatever the profile (robot/modes.py)
        evidence.append(
            "it reports the OI mode as is (a Create 2 or a Roomba 500; a 600 on fixed firmware too)"
        )
    for pid, value in sorted((readings or {}).items()):
        fits = [p for p in candidates if p.packet(pid).minimum <= value <= p.packet(pid).maximum]
        if len(fits) < len(candidates):
            candidates = fits
            title = PACKETS[pid].title.lower()
            evidence.append(
                f"its {title} ({pid}) read {value}, in range for "
                f"{' and '.join(p.name for p in fits) or 'no profile'}"
            )
    return Identification(tuple(candidates), tuple(evidence))


def telling_apart(candidates: tuple[RobotProfile, ...]) -> list[str]:
    """The readings that would tell ``candidates`` apart: a value only one model's range
    allows (the banner after Reset 7 tells them too, but sends the 500 a byte its spec does
    not have: the caller offers it, if it may)."""
    ways: list[str] = []
    for pid in MODEL_RANGE_PACKETS:
        tops = {p.packet(pid).maximum for p in candidates}
        if len(tops) > 1:
            low, high = min(tops), max(tops)
            readers = " or ".join(p.title for p in candidates if p.packet(pid).maximum == high)
            ways.append(
                f"a {PACKETS[pid].title.lower()} ({pid}) over {low}, which only the {readers} reads"
            )
    return ways


def stream_readings(frame: bytes) -> dict[int, int]:
    """Packet id -> raw value of one stream frame ``[19][n][id][value]...[checksum]``, read
    by the packet table alone (no profile: the profile is what is being found out); empty
    if the frame does not cut cleanly."""
    readings: dict[int, int] = {}
    body = frame[2:-1]
    at = 0
    while at < len(body):
        spec = PACKETS.get(body[at])
        if spec is None or at + 1 + spec.size > len(body):
            return {}
        raw = body[at + 1 : at + 1 + spec.size]
        readings[spec.id] = int.from_bytes(raw, "big", signed=spec.signed)
        at += 1 + spec.size
    return readings


#: Frames that must fail a profile's stream checksum and pass the other rule before the
#: model is named: one could be a corrupted frame summing right by chance (1 in 256).
MISMATCH_FRAMES = 2


def checksum_rule(profile: RobotProfile) -> str:
    """How ``profile``'s stream checksum treats the header, in words."""
    if profile.checksum_accepts_both:
        return "the header 19 summed in or left out"
    return "the header 19 summed in" if profile.checksum_includes_header else "the header left out"


@dataclass(frozen=True, slots=True)
class ProfileMismatch(ABC):
    """Frames that say the robot is not the model of ``profile`` but most likely one of
    ``likely``: what the messages of both kinds read (:class:`ChecksumMismatch`,
    :class:`RangeMismatch`)."""

    profile: RobotProfile
    likely: tuple[RobotProfile, ...]
    #: the profile's check the frames fail, in words ("checksum", "range")
    CHECK: ClassVar[str] = ""

    @property
    def fails(self) -> str:
        """What the frames fail, in words (``the create2 profile's checksum``)."""
        return f"the {self.profile.name} profile's {self.CHECK}"

    @property
    def most_likely(self) -> str:
        """The models the frames fit, in words (``a Roomba 500 series or a ...``)."""
        return "a " + " or a ".join(p.title for p in self.likely)

    @property
    @abstractmethod
    def explained(self) -> str:
        """What was seen and what it means, without the fix (the caller knows its own)."""


@dataclass(frozen=True, slots=True)
class ChecksumMismatch(ProfileMismatch):
    """Stream frames that fail ``profile``'s checksum and pass another model's rule: the
    robot is most likely one of ``likely`` (a Roomba 500 read with the default profile: its
    checksum leaves the header out). Found from the stream parser's counters alone
    (``ParserCounters.other_checksum``, counted on a failure only), never on the tick path."""

    failures: int
    passing: int
    #: the rule the frames pass, in words ("the header left out")
    rule: str
    CHECK: ClassVar[str] = "checksum"

    @property
    def explained(self) -> str:
        return (
            f"{self.failures} frames failed the checksum of the {self.profile.name} profile "
            f"({checksum_rule(self.profile)}) and {self.passing} of them pass with {self.rule}: "
            f"the robot is most likely {self.most_likely}"
        )


def checksum_mismatch(
    profile: RobotProfile, *, frames: int, failures: int, other_checksum: int
) -> ChecksumMismatch | None:
    """Whether a stream with no frame taken (``frames``), ``failures`` checksum failures of
    which ``other_checksum`` pass the other rule, is a robot of another model; None if it
    does not say so (frames were taken, or most failures are noise)."""
    if frames or other_checksum < MISMATCH_FRAMES or 2 * other_checksum < failures:
        return None
    other = {0, STREAM_HEADER} - profile.checksum_sums
    likely = tuple(p for p in PROFILES.values() if p is not profile and p.checksum_sums & other)
    if not likely:
        return None
    rule = "the header 19 summed in" if 0 in other else "the header left out"
    return ChecksumMismatch(profile, likely, failures, other_checksum, rule)


@dataclass(frozen=True, slots=True)
class RangeMismatch(ProfileMismatch):
    """Stream frames that pass ``profile``'s checksum but carry a value out of its range
    that another model's range holds: the robot is most likely one of ``likely`` (a Roomba
    500 whose firmware sums the header, read with the default profile: its wall signal over
    1023). Found from the parser's last such frame (``StreamParser.out_of_range``) when a
    stream is declared lost, never on the tick path."""

    #: frames refused as out of range, and the first packet and value of the last one
    refused: int
    packet: int
    value: int
    CHECK: ClassVar[str] = "range"

    @property
    def explained(self) -> str:
        spec = self.profile.packet(self.packet)
        title = PACKETS[self.packet].title.lower()
        past = f"over {spec.maximum}" if self.value > spec.maximum else f"under {spec.minimum}"
        fits = " and ".join(
            f"the {p.title} range {p.packet(self.packet).minimum}-{p.packet(self.packet).maximum}"
            for p in self.likely
        )
        return (
            f"{self.refused} frames passed the checksum but not the range of the "
            f"{self.profile.name} profile: {title} ({self.packet}) read {self.value}, {past} "
            f"({self.profile.title}), within {fits}: the robot is most likely {self.most_likely}"
        )


def range_mismatch(
    profile: RobotProfile,
    frame: bytes | None,
    packet_ids: tuple[int, ...],
    *,
    refused: int,
    checksum_failures: int,
    mode_plus_one: bool | None = None,
) -> RangeMismatch | None:
    """Whether stream frames of ``packet_ids`` refused as out of ``profile``'s range
    (``refused`` of them, ``frame`` the last) are a robot of another model: a value of
    ``frame`` out of ``profile``'s range that another profile's range holds, every value of
    it in that profile's range and its checksum that profile's rule. None if not, or if too
    few were refused or most refusals were checksum failures (noise: a damaged frame passes
    the 8-bit sum 1 time in 256). ``mode_plus_one``: packet 35's offset as the session
    learned it (None: as each profile expects)."""
    if frame is None or refused < MISMATCH_FRAMES or refused < checksum_failures:
        return None
    outside = _outside_range(profile, frame, packet_ids, mode_plus_one)
    if outside is None:
        return None
    total = sum(frame) & 0xFF
    likely = tuple(
        other
        for other in PROFILES.values()
        if other is not profile
        and total in other.checksum_sums
        and _outside_range(other, frame, packet_ids, mode_plus_one) is None
    )
    if not likely:
        return None
    return RangeMismatch(profile, likely, refused, *outside)


def _outside_range(
    profile: RobotProfile, frame: bytes, packet_ids: tuple[int, ...], mode_plus_one: bool | None
) -> tuple[int, int] | None:
    """The first (packet id, value) of stream ``frame`` outside ``profile``'s ranges, each
    value read with the profile's own signedness (the encoders differ); None if all are in."""
    layout = layout_for(packet_ids, profile, True)
    if len(frame) != layout.frame_size:
        return None
    values = layout.struct.unpack_from(frame, 2)
    for pid, value in zip(layout.members, values, strict=True):
        spec = profile.packet(pid)
        low, high = spec.minimum, spec.maximum
        if pid == OI_MODE_PACKET:
            plus_one = profile.reports_mode_plus_one if mode_plus_one is None else mode_plus_one
            low, high = low + int(plus_one), high + int(plus_one)
        if not low <= value <= high:
            return pid, value
    return None
