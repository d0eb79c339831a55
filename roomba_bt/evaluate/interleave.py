"""An A/B's episodes run by seed (A1 B1 A2 B2 ...), its results handed back per variant.

Variants ran one after another: all of A's seeds, then all of B's. A sweep interrupted
half-way (Ctrl-C, a job scheduler's SIGTERM, the cluster lost) held A's episodes and none of
B's, and no comparison at all. Run by seed, what finished is a smaller paired sweep. Each
episode is decided by its spec alone, so the results are the same episodes; each variant's
are handed back in its own spec order, so ``--out`` (written variant by variant) holds the
same bytes as before. Only the partial file, written as episodes finish, has them in the
order they ran.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

from roomba_bt.evaluate.episode import EpisodeResult, EpisodeSpec

Progress = Callable[[int, int, EpisodeResult], None]

#: what tells an episode's result from another's: the spec's mission, parameters and seed
#: (a result carries them; two variants differ in one of the first two)
_Key = tuple[str, tuple[tuple[str, str], ...], int]


@dataclass(frozen=True)
class Interleaved:
    """Batches of specs (one per variant) as one list taken by seed: the first spec of each
    batch, then the second of each, ... (a shorter batch is left out once it is done);
    ``places[i]``: the batch and the place in it of ``specs[i]``."""

    specs: list[EpisodeSpec]
    places: list[tuple[int, int]]
    sizes: list[int]

    @classmethod
    def of(cls, batches: Sequence[Sequence[EpisodeSpec]]) -> Interleaved:
        longest = max((len(batch) for batch in batches), default=0)
        places = [
            (b, i) for i in range(longest) for b, batch in enumerate(batches) if i < len(batch)
        ]
        specs = [batches[b][i] for b, i in places]
        return cls(specs, places, [len(batch) for batch in batches])

    def split(self, results: Mapping[int, EpisodeResult]) -> list[list[EpisodeResult]]:
        """The results by index in :attr:`specs` (those that finished), per batch in its
        spec order."""
        out: list[list[EpisodeResult]] = [[] for _ in self.sizes]
        for index in sorted(results, key=lambda i: self.places[i][1]):
            out[self.places[index][0]].append(results[index])
        return out

    def progress(self, bars: Sequence[Progress | None]) -> Progress | None:
        """One progress callback for the interleaved run that calls batch ``b``'s bar with
        that batch's own count and total; None when there is no bar. Each episode's batch is
        found by its key (a result carries its mission, parameters and seed), forgotten once
        its result came: a deque per episode (760 bytes, kept to the end) was 76 MB at
        100 000 episodes; the batch alone is kept (about 100 bytes with its key), a deque
        only for a key several hold."""
        if not any(bars):
            return None
        waiting: dict[_Key, int | deque[int]] = {}
        for spec, (batch, _) in zip(self.specs, self.places, strict=True):
            key = _key_of(spec.mission, spec.params, spec.seed)
            held = waiting.get(key)
            if held is None:
                waiting[key] = batch
                continue
            queued = held if isinstance(held, deque) else deque([held])
            queued.append(batch)
            waiting[key] = queued
        done = [0] * len(self.sizes)

        def progress(_: int, __: int, result: EpisodeResult) -> None:
            key = _key_of(result.mission, result.params, result.seed)
            held = waiting[key]
            batch = held.popleft() if isinstance(held, deque) else held
            if not isinstance(held, deque) or not held:
                del waiting[key]
            done[batch] += 1
            bar = bars[batch]
            if bar is not None:
                bar(done[batch], self.sizes[batch], result)

        return progress


def _key_of(mission: str, params: tuple[tuple[str, str], ...], seed: int) -> _Key:
    return mission, tuple(params), seed
