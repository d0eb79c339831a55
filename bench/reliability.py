"""``make reliability``: the figures of docs/reliability.md, from one command.

Three parts (``python -m bench.reliability noise|faults|memory``, all three by default;
``faults --only NAME`` for the fault rows whose name starts with NAME; ``--details FILE``
each trial as a JSON line, ``--keep DIR`` each trial's record):

* **noise**: bump-and-turn in the corridor on the virtual clock, single-bit flips on the
  robot's bytes (``Faults.bit_flip_rate``) at 10^-3 and 10^-2 per byte, back-to-back runs of
  at most an hour until the robot-hours are reached. A *phantom hazard stop* is a run that
  ends on a cliff or a wheel drop: the corridor has no drop and the simulator's wheels never
  drop, so every one is a corrupted frame the tree believed. A *phantom bump* is a bump the
  tree saw start that the simulator's bumpers did not show in the last three steps (an
  unneeded back-off and turn). Each rate also without the hazard confirmation (the runner's
  :class:`~roomba_bt.robot.hazards.HazardConfirmation` bypassed), for comparison.
* **faults**: each fault injected N times (20 by default) over a pty: ``roomba-bt sim --pty``
  in one process, ``roomba-bt run --port`` in another with ``--record``; exit code, the message
  naming the cause, the simulator's final mode and wheels (its summary line), whether the run
  said the stop was undeliverable, and the time from the last valid frame (or the signal) to
  the first drive 0 written (from the record), or to the process's end.
* **memory**: ``roomba-bt run patrol --fast`` for 4 robot-hours without ``--plot``: resident
  memory sampled every simulated 10 minutes.

Figures vary with the machine's load (the fault timings are wall-clock); the counts do not.
"""

from __future__ import annotations

import argparse
import dataclasses
import functools
import json
import os
import signal
import statistics
import subprocess
import sys
import tempfile
import textwrap
import time
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from roomba_bt.runtime.loop import MissionRunner
    from roomba_bt.runtime.summary import RunSummary
    from roomba_bt.sim import Simulator

CLI = [sys.executable, "-m", "roomba_bt.cli"]
HALT = bytes([137, 0, 0, 0, 0])
SPIN = """
mission: spin-forever
tree:
  sequence:
    - mode: safe
    - drive: {velocity: 200 mm/s, radius: spin_left}
"""
WAIT_IN_PASSIVE = """
mission: wait-in-passive
tree:
  wait: 10min
"""


# ----------------------------------------------------------------------------- noise
@dataclass
class NoiseResult:
    rate: float
    confirm: bool
    robot_hours: float = 0.0
    runs: int = 0
    phantom_stops: int = 0
    phantom_bumps: int = 0
    real_bumps: int = 0
    #: bump onsets of the simulator's own bumpers (every contact, seen by the tree or not)
    sim_bumps: int = 0
    lost_connection: int = 0
    stalls: int = 0
    stalls_ridden: int = 0
    unconfirmed: int = 0
    reasons: list[str] = field(default_factory=list)

    def row(self) -> str:
        hours = self.robot_hours or 1.0
        return (
            f"| {self.rate:g} | {'yes' if self.confirm else 'no (bypassed)'} | "
            f"{self.robot_hours:.1f} | {self.phantom_stops} ({self.phantom_stops / hours:.2f}"
            f" per robot-hour) | {self.phantom_bumps} ({self.phantom_bumps / hours:.1f}/h) | "
            f"{self.real_bumps} | {self.sim_bumps} | {self.unconfirmed} | "
            f"{self.stalls} / {self.stalls_ridden} | "
            f"{self.lost_connection} |"
        )


NOISE_HEADER = (
    "| bit flips per byte | hazard confirmation | robot-hours | phantom hazard stops | "
    "phantom bumps | real bumps | the simulator's bump onsets | onsets held and never "
    "confirmed | watchdog stalls / ridden through | ended as lost connection |\n"
    "|---|---|---|---|---|---|---|---|---|---|"
)


def noise(rate: float, hours: float, confirm: bool, seed: int = 1) -> NoiseResult:
    from roomba_bt.mission import load_mission
    from roomba_bt.mission.shipped import shipped_missions
    from roomba_bt.oi.profiles import CREATE2
    from roomba_bt.robot import hazards
    from roomba_bt.runtime.stack import RunStack
    from roomba_bt.sim import Faults, SimLink, Simulator, load_world

    result = NoiseResult(rate, confirm)
    world = load_world("corridor")
    original = hazards.HazardConfirmation.frame
    if not confirm:
        hazards.HazardConfirmation.frame = (  # type: ignore[method-assign]
            lambda self, frame, robot_reacted=False: frame
        )
    try:
        left = hours * 3600.0
        while left > 1.0:
            chunk = min(3600.0, left)
            mission = load_mission(
                shipped_missions()["bump-and-turn"], {"duration": f"{chunk:.0f}s"}, profile=CREATE2
            )
            sim = Simulator(
                world, CREATE2, seed + result.runs, Faults(bit_flip_rate=rate), trace=False
            )
            observer = _BumpWitness(sim, result)
            summary = RunStack(mission, SimLink(sim), profile=CREATE2, observer=observer).run()
            _count(result, summary)
            result.sim_bumps += sum(1 for event in sim.events if event.kind == "bump")
            left -= summary.mission_time_s
            if summary.mission_time_s < 1.0:
                break  # a run that cannot start: do not spin
    finally:
        hazards.HazardConfirmation.frame = original  # type: ignore[method-assign]
    return result


class _BumpWitness:
    """A tick observer: each bump the tree saw start is real if the simulator's bumpers showed
    it in the last three steps, else a phantom (a corrupted frame believed)."""

    def __init__(self, sim: Simulator, result: NoiseResult) -> None:
        self.sim = sim
        self.result = result
        self.truth = [0, 0, 0]
        self.seen = 0

    def __call__(self, runner: MissionRunner) -> None:
        from roomba_bt.oi.bits import BUMP_BITS
        from roomba_bt.oi.frames import BUMPS_PACKETS

        (packet,) = BUMPS_PACKETS
        shown = runner.snapshot.frame[packet] & BUMP_BITS
        self.truth.pop(0)
        self.truth.append(self.sim.values[packet] & BUMP_BITS)
        onset = shown & ~self.seen
        if onset:
            if onset & (self.truth[0] | self.truth[1] | self.truth[2]):
                self.result.real_bumps += 1
            else:
                self.result.phantom_bumps += 1
        self.seen = shown


def _count(result: NoiseResult, summary: RunSummary) -> None:
    """One run's robot-hours, stalls and ending added to ``result``."""
    from roomba_bt.runtime.summary import Outcome

    result.runs += 1
    result.robot_hours += summary.mission_time_s / 3600.0
    result.stalls += summary.stalls
    result.stalls_ridden += summary.stalls_ridden
    result.unconfirmed += summary.unconfirmed_hazards
    if summary.outcome is Outcome.CONNECTION_LOST:
        result.lost_connection += 1
    if summary.outcome is Outcome.FAILURE and (
        "cliff" in summary.reason or "wheel drop" in summary.reason
    ):
        result.phantom_stops += 1
        result.reasons.append(summary.reason)
    elif summary.outcome is not Outcome.SUCCESS:
        result.reasons.append(f"{summary.outcome.value}: {summary.reason}")


# ----------------------------------------------------------------------------- faults
@dataclass
class Trial:
    exit_code: int | None
    message: str
    sim_line: str
    undeliverable: bool
    to_stop_ms: float | None
    traceback: bool
    summary_printed: bool
    #: the run's stdout and stderr, for --details
    output: str = ""
    #: the wheels commanded again (a drive other than drive 0) after the measured stop
    commanded_again: bool = False
    #: wall-clock time (time.time) when the run ended, to set a slow trial beside the host's
    #: load at that moment
    ended_wall: float = 0.0


@dataclass
class Fault:
    name: str
    sim_args: tuple[str, ...] = ()
    mission: str = SPIN
    run_args: tuple[str, ...] = ()
    #: what the script does to the run or the simulator once the robot drives
    act: Callable[[subprocess.Popen[str], subprocess.Popen[str]], float | None] | None = None
    #: simulated time of a fault the simulator injects by itself (a run that was not yet
    #: driving then is retried: under load a run can take seconds to start)
    at: float | None = None
    drives: bool = True
    #: what in the record shows the run is under way (hex of a command written): the drive
    #: (89), or the stream's start (94) for a mission that waits in Passive
    ready: str = '"b": "89'
    #: which drive 0 after the watchdog's counts as the stop: 0 the watchdog's own, 1 the
    #: next (a baud change: the watchdog's goes out at the old rate, the next at the new)
    halt_index: int = 0


#: The oracle's stream loss: frames stop for 0.8 s, then come back (shorter than the grace).
GAP = "stream gap 0.8 s (the oracle's stream loss; ridden through, the run ends by --timeout)"


def _signal(*signums: int, gap: float = 0.005) -> Callable[..., float]:
    def act(run: subprocess.Popen[str], sim: subprocess.Popen[str]) -> float:
        sent = time.monotonic()
        for i, signum in enumerate(signums):
            if i:
                time.sleep(gap)
            run.send_signal(signum)
        return sent

    return act


def _kill_sim(run: subprocess.Popen[str], sim: subprocess.Popen[str]) -> float:
    sent = time.monotonic()
    sim.kill()
    return sent


FAULTS = (
    Fault("robot reset", ("--reset-at", "12"), at=12.0),
    Fault("port vanished (simulator killed)", act=_kill_sim),
    Fault("stream stopped", ("--stream-stop-at", "12"), at=12.0),
    Fault(
        GAP,
        ("--stream-gap-at", "12"),
        run_args=("--timeout", "15s"),
        at=12.0,
    ),
    Fault(
        "baud change mid-run (the robot's port to 19200 at 12 s)",
        ("--baud-change-at", "12"),
        at=12.0,
        halt_index=1,
    ),
    Fault("baud mismatch (robot at 19200, run at 115200)", ("--baud", "19200"), drives=False),
    Fault(
        "single-bit flips on 1 % of the bytes for 30 s (no fault: it must not end early)",
        ("--bit-flip-rate", "0.01"),
        run_args=("--timeout", "30s"),
    ),
    Fault(
        "robot asleep (falls asleep in Passive; over the pty, no modem lines)",
        ("--sleep-at", "12"),
        mission=WAIT_IN_PASSIVE,
        at=12.0,
        ready='"b": "94',
    ),
    Fault("SIGINT", act=_signal(signal.SIGINT)),
    Fault("double SIGINT", act=_signal(signal.SIGINT, signal.SIGINT)),
    Fault("SIGTERM", act=_signal(signal.SIGTERM)),
)


def _wait_for(predicate: Callable[[], bool], timeout: float) -> bool:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if predicate():
            return True
        time.sleep(0.02)
    return False


def _record(path: Path) -> list[dict[str, object]]:
    if not path.exists():
        return []
    out = []
    for line in path.read_text().splitlines():
        try:
            out.append(json.loads(line))
        except json.JSONDecodeError:
            continue
    return out


#: where each trial's record is copied (``--keep DIR``), or None
KEEP_RECORDS: Path | None = None


def trial(fault: Fault, workdir: Path, index: int) -> Trial:
    """One trial; a robot-side fault that came before the run drove is tried again."""
    for attempt in range(5):
        result = _trial(fault, workdir, index * 10 + attempt)
        if result is not None:
            return result
    raise RuntimeError(f"{fault.name}: the run never drove before the fault in 5 attempts")


def _trial(fault: Fault, workdir: Path, index: int) -> Trial | None:
    mission = workdir / f"{index}.yaml"
    mission.write_text(textwrap.dedent(fault.mission))
    record = workdir / f"{index}.jsonl"
    sim = subprocess.Popen(
        [*CLI, "sim", "--pty", *fault.sim_args],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    assert sim.stdout is not None
    port = sim.stdout.readline().strip()
    sim_started = time.monotonic()
    run = subprocess.Popen(
        [*CLI, "run", str(mission), "--port", port, "--record", str(record), "--display",
         "none", *fault.run_args],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    sent = None
    if fault.drives:
        ready = fault.ready
        started = _wait_for(lambda: ready in (record.read_text() if record.exists() else ""), 30)
        late = fault.at is not None and time.monotonic() - sim_started > fault.at - 1.0
        if not started or late:  # the fault would come before the run drove: again
            for proc in (run, sim):
                proc.kill()
                proc.communicate()
            return None
        if fault.act is not None:
            time.sleep(0.5)
            sent = fault.act(run, sim)
    out, err, sim_err, ended = _finish(run, sim)
    if KEEP_RECORDS is not None and record.exists():  # to look at a slow trial afterwards
        KEEP_RECORDS.mkdir(parents=True, exist_ok=True)
        kept = KEEP_RECORDS / f"{time.strftime('%H%M%S')}-{workdir.name}-{index}.jsonl"
        kept.write_bytes(record.read_bytes())
    entries = _record(record)
    to_stop = _to_stop_ms(entries, fault.halt_index)
    if sent is not None:  # a signal or the port: to the process's end
        to_stop = (ended - sent) * 1000
    reason = next(
        (
            line
            for line in err.splitlines()
            if line.startswith(("roomba-bt: connection lost", "roomba-bt: HUNG"))
        ),
        next((line for line in out.splitlines() if line.startswith("outcome")), ""),
    )
    return Trial(
        exit_code=run.returncode,
        message=reason,
        sim_line=next((ln for ln in sim_err.splitlines() if "simulated" in ln), "(killed)"),
        undeliverable="NOT DELIVERED" in out,
        to_stop_ms=to_stop,
        traceback="Traceback" in err,
        summary_printed="safe stop" in out,
        output=err + out,
        commanded_again=_commanded_again(entries),
        ended_wall=time.time() - (time.monotonic() - ended),
    )


def _finish(run: subprocess.Popen[str], sim: subprocess.Popen[str]) -> tuple[str, str, str, float]:
    """The run to its end (killed after 60 s: HUNG), then the simulator (SIGINT, killed after
    10 s): the run's stdout and stderr, the simulator's stderr, when the run ended."""
    try:
        out, err = run.communicate(timeout=60)
    except subprocess.TimeoutExpired:
        run.kill()
        out, err = run.communicate()
        err = "roomba-bt: HUNG: killed after 60 s\n" + err
    ended = time.monotonic()
    if sim.poll() is None:
        sim.send_signal(signal.SIGINT)
    try:
        _, sim_err = sim.communicate(timeout=10)
    except subprocess.TimeoutExpired:
        sim.kill()
        _, sim_err = sim.communicate()
    return out, err, sim_err, ended


def _to_stop_ms(entries: list[dict[str, object]], halt_index: int) -> float | None:
    """Time from the last valid frame to the stop, from a record: a watchdog's drive 0 is one
    written 50 ms or more after the last chunk that completed a valid frame (a tick's drive 0
    follows its frame at once); ``halt_index`` 1: the drive 0 after it. The stall measured is
    the run's last: a stall ridden through earlier (frames came back: a loaded host's hiccup)
    is not the fault's, and counting from its frame measured 7601 ms for a stop 120 ms after
    the baud change's last frame::

        frame ─ drive 0 ─ frames ... frame ─ drive 0 (watchdog) ─ listen ─ drive 0 (new rate)
        └ an earlier stall, ridden through  └──────── measured ─────────────────────┘
    """
    from roomba_bt.oi.profiles import get_profile
    from roomba_bt.oi.stream import StreamParser

    if not entries or "packets" not in entries[0]:
        return None
    header = entries[0]
    packets = tuple(int(p) for p in header["packets"])  # type: ignore[attr-defined]
    parser = StreamParser(packets, get_profile(str(header.get("profile", "create2"))))
    last_frame: float | None = None
    reference: float | None = None  # the last valid frame before this stall's first drive 0
    halts = 0
    measured: float | None = None
    for entry in entries[1:]:
        at = float(entry.get("t", 0.0))  # type: ignore[arg-type]
        data = bytes.fromhex(str(entry.get("b", "")))
        if entry.get("d") == "in":
            if parser.feed(data, at):
                last_frame = at
        elif entry.get("d") == "out" and data.startswith(HALT):
            if last_frame is None:
                continue
            if at - last_frame >= 0.05 and (reference is None or last_frame > reference):
                reference, halts, measured = last_frame, 0, None  # a new stall
            elif reference is None:
                continue
            if halts == halt_index:
                measured = (at - reference) * 1000
            halts += 1
    return measured


def _commanded_again(entries: list[dict[str, object]]) -> bool:
    """Whether a drive other than drive 0 was written after the last drive 0 that followed a
    stall (the wheels given their command again once frames came back)."""
    halted = False
    for entry in entries[1:]:
        if entry.get("d") != "out":
            continue
        data = bytes.fromhex(str(entry.get("b", "")))
        if data.startswith(HALT):
            halted = True
        elif halted and data[:1] == HALT[:1]:
            return True
    return False


FAULT_HEADER = (
    "| fault | trials | exit codes | the message (first trial; trials with its cause) | "
    "simulator at the end (first trial; trials left in Passive, wheels 0) | stop "
    "undeliverable, said so | fault to drive 0 (ms: median, max) | "
    "traceback / no summary / hung |\n|---|---|---|---|---|---|---|---|"
)


def fault_row(fault: Fault, trials: list[Trial]) -> str:
    codes = sorted({t.exit_code for t in trials}, key=lambda c: (c is None, c or 0))
    times = [t.to_stop_ms for t in trials if t.to_stop_ms is not None]
    timing = f"{statistics.median(times):.0f}, {max(times):.0f}" if times else "n/a"
    if fault.act is not None and fault.name != "port vanished (simulator killed)":
        timing += " (signal to exit)"
    if fault.name.startswith("port vanished"):
        timing = f"none possible ({timing} to exit)"
    if fault.name.startswith("baud mismatch"):
        timing = "never drove (start-up refused)"
    if fault.name.startswith("robot asleep"):
        timing = "not driving (Passive: no drive 0 needed)"
    if fault.name.startswith("single-bit"):
        timing = "n/a (ends by its --timeout: exit 1)"
    if fault.name == GAP:
        again = sum(t.commanded_again for t in trials)
        timing += f"; the wheels commanded again after the gap in {again} of {len(trials)}"
    bad = sum(t.traceback for t in trials), sum(not t.summary_printed for t in trials)
    hung = sum("HUNG" in t.message for t in trials)
    first = trials[0]
    same = sum(cause(t.message) == cause(first.message) for t in trials)
    stopped = sum(STOPPED_IN_PASSIVE in t.sim_line for t in trials)
    return (
        f"| {fault.name} | {len(trials)} | {', '.join(str(c) for c in codes)} | "
        f"{first.message.replace('|', '/')} ({same} of {len(trials)} the same cause) | "
        f"{first.sim_line.removeprefix('roomba-bt sim: ')} ({stopped} of {len(trials)} in "
        f"Passive, wheels 0) | "
        f"{sum(t.undeliverable for t in trials)} | {timing} | {bad[0]} / {bad[1]} / {hung} |"
    )


#: The simulator's summary line of a robot left stopped in Passive.
STOPPED_IN_PASSIVE = "mode Passive, wheels 0/0 mm/s"


def cause(message: str) -> str:
    """A message's cause, without the port and the figures that vary from trial to trial:
    ``the robot reset``, ``the sensor stream stopped``."""
    text = message.split(": ", 3)[-1] if message.startswith("roomba-bt:") else message
    what = text.split(":", 1)[0].split(";", 1)[0]
    if "grace; " in text:  # what asking the robot showed
        what += " / " + text.split("grace; ", 1)[1].split(":", 1)[0]
    return what


def faults(
    count: int, workers: int, only: tuple[str, ...] = (), details: Path | None = None
) -> list[str]:
    """The fault table; ``only``: the rows whose fault name starts with one of these;
    ``details``: each trial appended to this file as a JSON line (to look at one trial)."""
    rows = [FAULT_HEADER]

    def chosen(name: str) -> bool:
        return not only or name.startswith(only)

    with tempfile.TemporaryDirectory() as tmp:
        for n, fault in enumerate(FAULTS):
            if not chosen(fault.name):
                continue
            workdir = Path(tmp) / str(n)
            workdir.mkdir()
            with ThreadPoolExecutor(workers) as pool:
                trials = list(pool.map(functools.partial(trial, fault, workdir), range(count)))
            rows.append(fault_row(fault, trials))
            print(rows[-1], flush=True)
            if details is not None:
                with details.open("a") as out:
                    for t in trials:
                        out.write(json.dumps({"fault": fault.name, **dataclasses.asdict(t)}))
                        out.write("\n")
    if chosen(ASLEEP_BY_IDLE):
        rows.append(asleep_row(count))
        print(rows[-1], flush=True)
    return rows


ASLEEP_BY_IDLE = "robot asleep (5 min in Passive, --no-keep-awake; virtual clock, in process)"


def asleep_row(count: int) -> str:
    """The robot falls asleep (5 minutes in Passive, keep-awake off): on the virtual clock, in
    process (on a pty each trial would take 5 minutes of wall time)."""
    from roomba_bt.mission import load_mission
    from roomba_bt.oi.profiles import CREATE2
    from roomba_bt.runtime.stack import RunStack
    from roomba_bt.sim import SimLink, Simulator, load_world

    codes: set[int] = set()
    message = sim_line = ""
    waits: list[float] = []
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "wait.yaml"
        path.write_text(WAIT_IN_PASSIVE)
        for seed in range(count):
            mission = load_mission(path, {}, profile=CREATE2)
            sim = Simulator(load_world("empty-room"), CREATE2, seed, trace=False)
            stack = RunStack(mission, SimLink(sim), profile=CREATE2, keep_awake=False)
            summary = stack.run()
            stack.close()
            codes.add(summary.exit_code)
            slept = next(e.time for e in sim.events if e.kind == "sleep")
            waits.append(sim.time - slept)
            if not message:
                message = summary.reason
                sim_line = (
                    f"mode {sim.mode.label}, asleep {sim.asleep}, wheels "
                    f"{sim.requested_left:.0f}/{sim.requested_right:.0f} mm/s"
                )
    return (
        f"| {ASLEEP_BY_IDLE} | "
        f"{count} | {', '.join(map(str, sorted(codes)))} | {message} | {sim_line} | 0 | "
        f"not driving (Passive: no drive 0 needed); sleep to the run's end "
        f"{statistics.median(waits) * 1000:.0f} ms | 0 / 0 / 0 |"
    )


# ----------------------------------------------------------------------------- memory
def memory(hours: float, trace: bool = False) -> str:
    """Resident memory of a patrol run on the virtual clock, every simulated 10 minutes."""
    import resource

    from roomba_bt.mission import load_mission
    from roomba_bt.mission.shipped import shipped_missions
    from roomba_bt.oi.profiles import CREATE2
    from roomba_bt.runtime.stack import RunStack
    from roomba_bt.sim import SimLink, Simulator, load_world

    def rss_mb() -> float:
        with open("/proc/self/statm") as statm:
            return int(statm.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 1e6

    samples: list[tuple[float, float]] = []
    mission = load_mission(
        shipped_missions()["patrol"], {"laps": "100000", "low_battery": "0%"}, profile=CREATE2
    )
    world = load_world("corridor")
    sim = Simulator(world, CREATE2, 1, coverage=True, trace=trace)  # trace off: run, no --plot
    full = sim.battery_charge

    def observe(runner: MissionRunner) -> None:
        now = runner.snapshot.time
        if not samples or now - samples[-1][0] >= 600:
            samples.append((now, rss_mb()))
            sim.battery_charge = full  # topped up every 10 min: hours of driving, no dock

    stack = RunStack(mission, SimLink(sim), profile=CREATE2, timeout_s=hours * 3600,
                     observer=observe)  # fmt: skip
    summary = stack.run()
    samples.append((summary.mission_time_s, rss_mb()))
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1000
    after_warmup = [mb for t, mb in samples if t >= 600]
    spread = max(after_warmup) - min(after_warmup) if after_warmup else 0.0
    points = ", ".join(
        f"{t / 3600:.1f} h {mb:.1f}" for t, mb in samples[:: max(1, len(samples) // 9)]
    )
    return (
        f"patrol, corridor, {summary.mission_time_s / 3600:.2f} robot-hours "
        f"({summary.outcome.value}), trace {'kept' if trace else 'off'}: resident memory (MB) "
        f"{points}; from 10 min to the end it varies by {spread:.1f} MB (peak {peak:.0f} MB)"
    )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=(__doc__ or "").partition("\n")[0])
    parser.add_argument("part", nargs="*", choices=("noise", "faults", "memory"), default=[])
    parser.add_argument("--hours", type=float, default=10.0, help="robot-hours at 1e-3")
    parser.add_argument("--hours-1e-2", type=float, default=3.0, help="robot-hours at 1e-2")
    parser.add_argument(
        "--hours-bypassed", type=float, default=2.0,
        help="robot-hours at each rate without the hazard confirmation",
    )  # fmt: skip
    parser.add_argument("--trials", type=int, default=20, help="trials per fault")
    parser.add_argument("--workers", type=int, default=2, help="trials at once")
    parser.add_argument(
        "--only", action="append", default=[], metavar="NAME",
        help="faults: only the rows whose name starts with NAME (repeatable)",
    )  # fmt: skip
    parser.add_argument(
        "--details", type=Path, metavar="FILE",
        help="faults: each trial appended to FILE as a JSON line",
    )  # fmt: skip
    parser.add_argument(
        "--keep", type=Path, metavar="DIR",
        help="faults: copy each trial's record into DIR (named by time, row and trial)",
    )  # fmt: skip
    parser.add_argument("--memory-hours", type=float, default=4.0)
    args = parser.parse_args(argv)
    parts = args.part or ["noise", "faults", "memory"]
    global KEEP_RECORDS
    KEEP_RECORDS = args.keep
    if "noise" in parts:
        print(NOISE_HEADER, flush=True)
        for rate, hours in ((1e-3, args.hours), (1e-2, args.hours_1e_2)):
            for confirm in (True, False):
                if (hours if confirm else args.hours_bypassed) <= 0:
                    continue  # --hours-bypassed 0: the rows with the confirmation only
                result = noise(rate, hours if confirm else args.hours_bypassed, confirm)
                print(result.row(), flush=True)
                for reason in result.reasons[:3]:
                    print(f"  e.g. {reason}", file=sys.stderr)
    if "faults" in parts:
        faults(args.trials, args.workers, tuple(args.only), args.details)
    if "memory" in parts:
        print(memory(args.memory_hours), flush=True)
        print(memory(1.0, trace=True), flush=True)  # what it was: the trace kept
    return 0


if __name__ == "__main__":
    sys.exit(main())
