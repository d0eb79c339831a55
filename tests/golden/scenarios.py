"""Golden scenarios: the simulator's bytes, recorded once and compared by every test run.

A scenario is a deterministic function that returns the bytes of one session on the wire: a
scripted host talking to the simulator (every robot profile in every shipped world, each fault
on its own), or a whole mission episode (each shipped mission through the real connection and
runner on the virtual clock). ``recordings.json`` holds, per scenario, the SHA-256 of the whole
transcript, its length, and a digest of the transcript at every 10 s of simulated time, so a
difference is reported with the stretch of time where it first appears.

Transcript records, one per write or read (``t`` in integer nanoseconds of simulated time)::

    [ '>' or '<' ][ t: 8 bytes, big-endian ][ n: 4 bytes, big-endian ][ n bytes ]
      > host to robot, < robot to host

Renew deliberately, only when a change of bytes is intended (say why in the commit)::

    python tests/golden/scenarios.py --renew        (make golden)
"""

from __future__ import annotations

import argparse
import hashlib
import json
import logging
import struct
import sys
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from roomba_bt.oi import commands as C
from roomba_bt.oi.profiles import PROFILES, RobotProfile, get_profile
from roomba_bt.sim import Faults, SimLink, Simulator, load_world, shipped_worlds

RECORDINGS = Path(__file__).with_name("recordings.json")
MISSIONS = Path(__file__).resolve().parents[2] / "missions"
CHECKPOINT_NS = 10_000_000_000  # a digest every 10 s of simulated time
STEP_NS = 15_000_000


@dataclass
class Transcript:
    """The session's bytes in both directions, with the simulated time of each."""

    data: bytearray = field(default_factory=bytearray)
    checkpoints: list[str] = field(default_factory=list)
    _next_checkpoint: int = CHECKPOINT_NS

    def add(self, direction: bytes, time_ns: int, payload: bytes) -> None:
        while time_ns >= self._next_checkpoint:
            self.checkpoints.append(hashlib.sha256(self.data).hexdigest()[:16])
            self._next_checkpoint += CHECKPOINT_NS
        if payload:
            self.data += direction + struct.pack(">QI", time_ns, len(payload)) + payload

    def summary(self, **extra: object) -> dict[str, object]:
        return {
            "sha256": hashlib.sha256(self.data).hexdigest(),
            "bytes": len(self.data),
            "checkpoints": self.checkpoints,
            **extra,
        }


def _ns(sim: Simulator) -> int:
    return round(sim.time * 1e9)


# --------------------------------------------------------------------------- scripted hosts


def _script(profile: RobotProfile) -> dict[int, bytes]:
    """Step number -> host bytes: every mode, the drive commands, built-in cycles, songs,
    LEDs, motors, queries and stream control, limited to the profile's commands."""
    known = {c.opcode for c in profile.commands}
    steps: dict[int, list[bytes]] = {
        0: [C.start().data, C.stream([100]).data],
        40: [C.safe().data, C.drive(250, 300).data],
        300: [C.query_list([35, 7, 19, 20, 43, 44]).data, C.sensors(6).data],
        400: [C.drive_direct(200, -150).data],
        600: [C.full().data, C.drive(-200, -1).data, C.motors(0b111).data],
        700: [C.leds(0b1111, 128, 255).data, C.song(0, [(60, 16), (64, 16)]).data],
        720: [C.play(0).data, C.pwm_motors(60, -40, 90).data],
        800: [C.stream([7, 8, 9, 10, 11, 12, 13, 19, 20, 35, 45, 46, 47, 52, 53]).data],
        900: [C.drive_pwm(120, 100).data],
        1100: [C.pause_stream().data],
        1200: [C.resume_stream().data, C.safe().data, C.drive(300, 32767).data],
        1500: [C.start().data, C.clean().data],
        2300: [C.spot().data],
        2800: [C.seek_dock().data],
        3600: [C.max_clean().data],
        4200: [C.safe().data, C.drive(0, 0).data, C.digit_leds_ascii("ABCD").data],
        4250: [C.power().data],
        4300: [C.start().data, C.stream([100]).data],
        4500: [C.stop().data],
    }
    out: dict[int, bytes] = {}
    for step, commands in steps.items():
        kept = [c for c in commands if c[0] in known]
        if kept:
            out[step] = b"".join(kept)
    return out


def scripted(
    profile: str, world: str, seed: int = 7, steps: int = 4800, faults: Faults | None = None
) -> Transcript:
    robot = get_profile(profile)
    sim = Simulator(load_world(world), robot, seed, faults, random_start=True)
    script = _script(robot)
    transcript = Transcript()
    for step in range(steps):
        if step in script:
            transcript.add(b">", _ns(sim), script[step])
            sim.receive(script[step])
            transcript.add(b"<", _ns(sim), sim.read())
        sim.step()
        if sim.disconnected:
            transcript.add(b"!", _ns(sim), b"disconnected")
            break
        transcript.add(b"<", _ns(sim), sim.read())
    transcript.add(b"=", _ns(sim), _final_state(sim))
    return transcript


def _final_state(sim: Simulator) -> bytes:
    """What the bytes do not show: where the robot ended and what the simulator saw."""
    state = (
        f"x={sim.x:.6f} y={sim.y:.6f} theta={sim.theta:.9f} mode={int(sim.mode)} "
        f"docked={sim.docked} fallen={sim.fallen} charge={sim.battery_charge:.6f} "
        f"events={[(e.kind, round(e.time, 6)) for e in sim.events]} "
        f"violations={len(sim.violations)} ignored={sim.ignored_bytes}"
    )
    return state.encode()


FAULTS: dict[str, Faults] = {
    "corrupt": Faults(corrupt_rate=0.01),
    "drop": Faults(drop_rate=0.05),
    "latency": Faults(latency=0.05),
    "inject": Faults(inject_text="bl-start\r\n2012-03-22-1549-L\r\n", inject_every=7.0),
    "disconnect": Faults(disconnect_at=20.0),
    "noise": Faults(noise=25.0),
}


# --------------------------------------------------------------------------- mission episodes


class RecordingLink(SimLink):
    """A SimLink that keeps a transcript of everything written and read."""

    def __init__(self, simulator: Simulator, transcript: Transcript) -> None:
        super().__init__(simulator)
        self.transcript = transcript

    def write(self, data: bytes) -> None:
        self.transcript.add(b">", _ns(self.simulator), bytes(data))
        super().write(data)

    def read(self, timeout: float) -> bytes:
        data = super().read(timeout)
        self.transcript.add(b"<", _ns(self.simulator), data)
        return data


def episode(
    mission: str,
    world: str,
    seed: int,
    params: dict[str, str] | None = None,
    timeout_s: float = 600.0,
    profile: str = "create2",
) -> Transcript:
    from roomba_bt.mission import load_mission
    from roomba_bt.runtime.stack import RunStack

    robot = get_profile(profile)
    compiled = load_mission(str(MISSIONS / mission), params or {}, profile=robot)
    sim = Simulator(load_world(world), robot, seed, random_start=True)
    transcript = Transcript()
    link = RecordingLink(sim, transcript)
    stack = RunStack(compiled, link, profile=robot, timeout_s=timeout_s)
    logger = logging.getLogger("roomba_bt")
    level = logger.level
    logger.setLevel(logging.ERROR)  # the mode drops it would log are in the bytes
    try:
        summary = stack.run()
    finally:
        logger.setLevel(level)
    outcome = f"outcome={summary.outcome.value} reason={summary.reason} ticks={summary.ticks}"
    transcript.add(b"=", _ns(sim), outcome.encode() + b" " + _final_state(sim))
    return transcript


# --------------------------------------------------------------------------- the set

SCENARIOS: dict[str, Callable[[], Transcript]] = {}
for _profile in PROFILES:
    for _world in shipped_worlds():
        SCENARIOS[f"sim/{_profile}/{_world}"] = (
            lambda p=_profile, w=_world: scripted(p, w)  # type: ignore[misc]
        )
for _name, _faults in FAULTS.items():
    SCENARIOS[f"fault/{_name}"] = lambda f=_faults: scripted(  # type: ignore[misc]
        "create2", "apartment", seed=11, faults=f
    )
SCENARIOS["fault/roomba600-corrupt"] = lambda: scripted(
    "roomba600", "corridor", seed=5, faults=Faults(corrupt_rate=0.02, drop_rate=0.02)
)
EPISODES: dict[str, tuple[str, str, int, dict[str, str], float]] = {
    "mission/dock/empty-room": ("dock.yaml", "empty-room", 1, {}, 300.0),
    "mission/dock/apartment": ("dock.yaml", "apartment", 3, {}, 600.0),
    "mission/dock-builtin/apartment": ("dock-builtin.yaml", "apartment", 3, {}, 600.0),
    "mission/patrol/corridor": ("patrol.yaml", "corridor", 2, {"laps": "1"}, 900.0),
    "mission/bump-and-turn/corridor": ("bump-and-turn.yaml", "corridor", 4, {}, 90.0),
    "mission/wall-follow/empty-room": ("wall-follow.yaml", "empty-room", 6, {}, 90.0),
}
for _name, (_mission, _world, _seed, _params, _timeout) in EPISODES.items():
    SCENARIOS[_name] = lambda m=_mission, w=_world, s=_seed, p=_params, t=_timeout: episode(  # type: ignore[misc]
        m, w, s, p, t
    )


def load_recordings() -> dict[str, dict[str, object]]:
    recorded: dict[str, dict[str, object]] = json.loads(RECORDINGS.read_text())
    return recorded


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=(__doc__ or "").partition("\n")[0])
    parser.add_argument("--renew", action="store_true", help="write recordings.json anew")
    parser.add_argument("names", nargs="*", help="scenarios (default: all)")
    args = parser.parse_args(argv)
    names = args.names or list(SCENARIOS)
    recorded = load_recordings() if RECORDINGS.exists() else {}
    differ = 0
    for name in names:
        now = SCENARIOS[name]().summary()
        same = recorded.get(name, {}).get("sha256") == now["sha256"]
        differ += not same
        print(f"{'same   ' if same else 'CHANGED'} {name}: {now['bytes']} bytes")
        recorded[name] = now
    if args.renew:
        RECORDINGS.write_text(json.dumps(recorded, indent=1, sort_keys=True) + "\n")
        print(f"wrote {RECORDINGS}")
    return 0 if args.renew or not differ else 1


if __name__ == "__main__":
    sys.exit(main())
