"""Reading a long run's record afterwards: ``roomba-bt replay`` and ``roomba-bt monitor``,
their wall time and peak resident memory (the figures of docs/performance.md, "Reading a
long record").

::

    python -m bench.record_reading                      # makes bench-long.jsonl first
    python -m bench.record_reading --record long.jsonl  # an existing record
    python -m bench.record_reading --code /other/tree   # another checkout's code (before/after)

The record is a ``clean`` of about 70 minutes (60 of cleaning, then the dock search) on the
simulator's virtual clock in ``bench/data/big-house.yaml`` (24 x 18 m), about 56 MB. Each
command runs in a child process; its peak RSS is the kernel's (``wait4``'s ``ru_maxrss``).
The monitor is timed to its first line (``monitor: ...``), to its address, and to its answer to a
seek to the middle of the run (``/api/state?tick=``), then ended with SIGTERM.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import signal
import subprocess
import sys
import time
import urllib.request
from pathlib import Path

HERE = Path(__file__).resolve().parent
WORLD = HERE / "data" / "big-house.yaml"
MAKE = [
    "run", "clean", "--fast", "--world", str(WORLD), "--profile", "roomba600",
    "-p", "duration=60min", "--timeout", "2h", "--display", "none",
]  # fmt: skip


def _child(code: Path, argv: list[str], **kwargs: object) -> subprocess.Popen[str]:
    env = {**os.environ, "PYTHONPATH": str(code)}
    return subprocess.Popen(  # type: ignore[call-overload, no-any-return]
        [sys.executable, "-m", "roomba_bt", *argv], env=env, text=True, **kwargs
    )


def _reaped(child: subprocess.Popen[str]) -> tuple[int, str]:
    """The child's exit status, and its CPU time and peak RSS."""
    _, status, usage = os.wait4(child.pid, 0)
    child.returncode = os.waitstatus_to_exitcode(status)
    cpu = usage.ru_utime + usage.ru_stime
    return child.returncode, f"CPU {cpu:.1f} s, peak RSS {usage.ru_maxrss / 1024:.1f} MB"


def replay(code: Path, record: Path) -> None:
    started = time.perf_counter()
    child = _child(code, ["replay", str(record)], stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    out, err = child.stdout.read(), child.stderr.read()  # type: ignore[union-attr]
    rc, rss = _reaped(child)
    wall = time.perf_counter() - started
    last = out.strip().splitlines()[-1] if out.strip() else err.strip()
    progress = sum(1 for line in err.splitlines() if "% of" in line)
    print(f"replay   wall {wall:.1f} s, {rss}, exit {rc}, progress lines {progress}")
    print(f"         {last}")


def monitor(code: Path, record: Path) -> None:
    started = time.perf_counter()
    child = _child(
        code, ["monitor", str(record), "--monitor", "127.0.0.1:0"],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
    )  # fmt: skip
    first = url = None
    ticks = 0
    for line in child.stdout:  # type: ignore[union-attr]
        if line.startswith("monitor:"):  # its first word (the run's warnings aside)
            first = first or time.perf_counter() - started
        found = re.search(r"(\d+) ticks", line)
        ticks = int(found.group(1)) if found else ticks
        if line.startswith("monitor: http"):
            url = line.split()[1]
            break
    served = time.perf_counter() - started
    seek = ""
    if url is not None:
        asked = time.perf_counter()
        with urllib.request.urlopen(f"{url.rstrip('/')}/api/state?tick={ticks // 2}") as answer:
            state = json.load(answer)["state"]
        seek = f", seek to tick {state['tick']} answered in {time.perf_counter() - asked:.2f} s"
    child.send_signal(signal.SIGTERM)
    rc, rss = _reaped(child)
    print(f"monitor  first word {first or 0:.1f} s, address {served:.1f} s{seek}; {rss}, exit {rc}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--record", type=Path, help="default: bench-long.jsonl, made if missing")
    parser.add_argument("--code", type=Path, default=HERE.parent, help="the tree to run")
    args = parser.parse_args()
    record = args.record or Path("bench-long.jsonl")
    if not record.exists():
        made = _child(args.code, [*MAKE, "--record", str(record)], stdout=subprocess.DEVNULL)
        made.wait()
    print(f"record   {record}: {record.stat().st_size / 1e6:.1f} MB; code {args.code}")
    replay(args.code, record)
    monitor(args.code, record)


if __name__ == "__main__":
    main()
