"""A smaller seeded run of tests/mission/mutations.py (the 10,000-mutation script): no
mutation of a shipped mission makes the compiler raise, and nothing is kept between compiles."""

from __future__ import annotations

import multiprocessing

from mutations import Tally, run  # beside this file (pytest puts its folder on the path)


def _in_a_process_of_its_own(count: int, seed: int) -> Tally:
    """:func:`run` in a fresh interpreter: the memory a compile keeps is measured against the
    caches the compiles themselves fill, not against whatever the tests run before this one
    in the same process left in them (bounded caches half full in one of ``make test``'s
    xdist workers counted 52 B a compile as growth; the script runs alone, as here)."""
    with multiprocessing.get_context("spawn").Pool(1) as pool:
        return pool.apply(run, (count,), {"seed": seed})


def test_seeded_mutations_give_no_internal_error_and_keep_no_memory() -> None:
    tally = _in_a_process_of_its_own(400, seed=16)
    assert tally.compiles == 400
    assert not tally.internal_errors, tally.internal_errors[0]
    assert 0 < tally.valid < 400  # some mutants still compile, most do not
    # traced memory kept over the last 200 compiles: about 6 B a compile here (caches that
    # fill once, e.g. abc's subclass checks); a compile that keeps anything of its own (its
    # path, a node, a diagnostic) is 50 B or more. The reader kept about 38 kB a compile
    # before it was made stateless, the mode pass's method lookups about 12 B (bounded).
    assert tally.growth_per_compile < 25, (tally.memory_early, tally.memory_late)
