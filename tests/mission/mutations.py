"""Seeded mutations of the shipped missions through the validator, in-process.

    python tests/mission/mutations.py 10000 --seed 1

Each mutation edits one shipped mission or example (a character, a line, a token: numbers,
units, brackets, YAML anchors, aliases and tags, indentation) and compiles it with
:func:`~roomba_bt.mission.compile_mission`. Counted: internal errors (the compiler's own
exceptions, which must be none), the slowest compile, and the memory kept by the second
half: traced from the first half's end (after a garbage collection) to the end, per compile,
is what a compile keeps (flat: nothing). The first half warms the caches that fill once
(imports, the registry, interned names), untraced: tracing every allocation makes a compile
about five times slower, and what the first half allocates is not measured. The suite runs
a smaller seeded set (tests/mission/test_mutations.py).
"""

from __future__ import annotations

import argparse
import gc
import random
import re
import shutil
import sys
import tempfile
import time
import tracemalloc
from dataclasses import dataclass, field
from pathlib import Path

from roomba_bt.mission import compile_mission

MISSIONS = Path(__file__).resolve().parents[2] / "missions"
SOURCES = sorted({*MISSIONS.glob("*.yaml"), *MISSIONS.glob("examples/*.yaml")})
TOKENS = ("0", "-1", "1e9", "2s", "mm/s", "deg", "100 mm/s", "${speed}", "@key", "&a ", "*a",
          "!!int ", "!!float ", "!!bool ", "!!python/object:os.system ", "{", "}", "[", "]",
          ": ", "- ", ",", "'", '"', "\t", "  ", "null", "~", "true", "sequence", "drive",
          "reactive_fallback", "retry", "timeout", "subtree", "include", "plugins",
          "<<: ")  # fmt: skip


def mutate(text: str, rng: random.Random) -> str:
    """One to three random edits of ``text``."""
    for _ in range(rng.randint(1, 3)):
        lines = text.splitlines(keepends=True) or ["\n"]
        kind = rng.randrange(7)
        at = rng.randrange(len(text) + 1)
        if kind == 0:  # delete a few characters
            text = text[:at] + text[at + rng.randint(1, 4) :]
        elif kind == 1:  # insert a token
            text = text[:at] + rng.choice(TOKENS) + text[at:]
        elif kind == 2:  # replace a character
            text = text[:at] + chr(rng.randint(32, 126)) + text[at + 1 :]
        elif kind == 3:  # duplicate a line
            i = rng.randrange(len(lines))
            lines.insert(i, lines[i])
            text = "".join(lines)
        elif kind == 4:  # delete a line
            del lines[rng.randrange(len(lines))]
            text = "".join(lines)
        elif kind == 5:  # re-indent a line
            i = rng.randrange(len(lines))
            lines[i] = " " * rng.choice((0, 1, 2, 4, 6)) + lines[i].lstrip(" ")
            text = "".join(lines)
        else:  # swap two lines
            i, j = rng.randrange(len(lines)), rng.randrange(len(lines))
            lines[i], lines[j] = lines[j], lines[i]
            text = "".join(lines)
    return text


@dataclass
class Tally:
    compiles: int = 0
    valid: int = 0
    internal_errors: list[str] = field(default_factory=list)
    slowest_s: float = 0.0
    slowest: str = ""
    memory_early: int = 0  # traced bytes as tracing starts, after the first half
    memory_late: int = 0  # and at the end

    @property
    def growth_per_compile(self) -> float:
        """Traced bytes kept per compile over the second half."""
        return (self.memory_late - self.memory_early) / max(1, self.compiles - self.compiles // 2)


def _kept() -> int:
    """Traced bytes still held: after a collection, with the interpreter's method cache
    emptied (it holds up to 4,096 attribute-name strings, keyed by their address: the ones
    the io module builds per open file, "incrementaldecoder", would count as growth until it
    is full) and with ``re``'s cache of compiled patterns emptied: bounded at 512, it is
    filled by the patterns a compile builds from a mutant's names (``mission/nodes.py``), so
    its growth was whatever room the tests run before this one in the same process had left
    it (52 B a compile in an xdist worker of ``make test``, under the bar in one process)."""
    gc.collect()
    sys._clear_type_cache()
    re.purge()
    return tracemalloc.get_traced_memory()[0]


def run(count: int, seed: int, *, measure_time: bool = False) -> Tally:
    """``count`` mutations from ``seed``, compiled in a copy of the missions folder (so
    includes resolve as they would)."""
    rng = random.Random(seed)
    tally = Tally()
    texts = {p.relative_to(MISSIONS): p.read_text(encoding="utf-8") for p in SOURCES}
    names = sorted(texts)
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp) / "missions"
        shutil.copytree(MISSIONS, folder)
        for n in range(count):
            name = rng.choice(names)
            target = folder / name.parent / f"mutant_{n % 2}.yaml"
            text = mutate(texts[name], rng)
            target.write_text(text, encoding="utf-8")
            start = time.perf_counter() if measure_time else 0.0
            mission, diagnostics = compile_mission(target)
            if measure_time and (spent := time.perf_counter() - start) > tally.slowest_s:
                tally.slowest_s, tally.slowest = spent, f"{name} #{n}"
            tally.compiles += 1
            tally.valid += mission is not None
            for d in diagnostics:
                if "internal error" in d.message:
                    tally.internal_errors.append(f"{name} #{n}: {d.message}\n{text}")
            # the mutant's text too: alive at a measurement, its size (a few KB, another
            # mission's each time) counted as growth
            del mission, diagnostics, text
            if n + 1 == count // 2:
                tracemalloc.start()
                tally.memory_early = _kept()
        tally.memory_late = _kept()
    tracemalloc.stop()
    return tally


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=(__doc__ or "").partition("\n")[0])
    parser.add_argument("count", type=int, nargs="?", default=10_000)
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args(argv)
    tally = run(args.count, args.seed, measure_time=True)
    print(f"{tally.compiles} mutations (seed {args.seed}): {tally.valid} still valid, "
          f"{len(tally.internal_errors)} internal errors, slowest compile "
          f"{tally.slowest_s:.3f} s ({tally.slowest}), traced memory after the first half "
          f"{tally.memory_early / 1e6:.3f} MB, at the end {tally.memory_late / 1e6:.3f} MB "
          f"({tally.growth_per_compile:+.1f} B a compile)")  # fmt: skip
    for error in tally.internal_errors[:5]:
        print(error, file=sys.stderr)
    return 1 if tally.internal_errors else 0


if __name__ == "__main__":
    sys.exit(main())
