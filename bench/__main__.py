"""``make bench``: run every ``bench/bench_*.py`` in one process and print their ratios.

Each benchmark module exposes ``main() -> None`` and prints its own lines; ratios are always
measured against a baseline run in the same process (bare py_trees, a peer decoder, a bare
``serial.write``), never against a number from another machine.
"""

from __future__ import annotations

import importlib
import pathlib
import sys
import time


def main() -> int:
    here = pathlib.Path(__file__).parent
    sys.path.insert(0, str(here.parent))
    only = set(sys.argv[1:])
    failures = 0
    for path in sorted(here.glob("bench_*.py")):
        name = path.stem
        if only and name not in only and name.removeprefix("bench_") not in only:
            continue
        print(f"== {name}", flush=True)
        started = time.perf_counter()
        try:
            importlib.import_module(f"bench.{name}").main()
        except Exception as exc:  # a broken benchmark must not hide the others
            failures += 1
            print(f"   FAILED: {type(exc).__name__}: {exc}")
        print(f"   ({time.perf_counter() - started:.1f} s)\n", flush=True)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
