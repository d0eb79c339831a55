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

from bisect import bisect_right
from collections import deque
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import overload

from roomba_bt.evaluate.episode import EpisodeResult, EpisodeSpec
from roomba_bt.evaluate.plan import EpisodePlan
from roomba_bt.mission.shipped import mission_label

Progress = Callable[[int, int, EpisodeResult], None]

#: what tells an episode's result from another's: the spec's mission, parameters and seed
#: (a result carries them; two variants differ in one of the first two)
_Key = tuple[str, tuple[tuple[str, str], ...], int]
_Variant = tuple[str, tuple[tuple[str, str], ...]]


@dataclass(frozen=True)
class _Stretch:
    """The rows ``first`` .. ``first + rows - 1`` of the interleaved order, in which each of
    ``batches`` (those longer than ``first``) gives one spec a row; ``start``, the index of
    the stretch's first spec."""

    start: int
    first: int
    rows: int
    batches: tuple[int, ...]


class InterleavedSpecs(Sequence[EpisodeSpec]):
    """The specs of batches taken by seed (A1 B1 A2 B2 ...), each found in its batch when
    it is asked for: a list of them all held every spec of a 100 000-episode sweep before
    the first ran, and a list of their places a tuple each."""

    def __init__(
        self, batches: Sequence[Sequence[EpisodeSpec]], labels: Sequence[str] = ()
    ) -> None:
        self.batches = batches
        self.labels = labels
        sizes = [len(batch) for batch in batches]
        # the rows are cut where a batch ends: between two such cuts, the batches still
        # going give one spec each a row
        self._stretches: list[_Stretch] = []
        start = row = 0
        for end in sorted(set(sizes)):
            going = tuple(b for b, size in enumerate(sizes) if size > row)
            if end > row:
                self._stretches.append(_Stretch(start, row, end - row, going))
                start += (end - row) * len(going)
            row = end
        self._starts = [stretch.start for stretch in self._stretches]
        self._len = start

    def __len__(self) -> int:
        return self._len

    def place(self, index: int) -> tuple[int, int]:
        """The batch and the place in it of the ``index``-th spec."""
        if not 0 <= index < self._len:
            raise IndexError(index)
        stretch = self._stretches[bisect_right(self._starts, index) - 1]
        row, column = divmod(index - stretch.start, len(stretch.batches))
        return stretch.batches[column], stretch.first + row

    def label(self, index: int) -> str:
        """The ``index``-th spec's variant as the report names it: its batch's label, given
        by the evaluation (``eval``'s, with the ``-p`` base first), else made from the spec
        (:func:`variant_label`)."""
        batch, at = self.place(index)
        if self.labels:
            return self.labels[batch]
        spec = self.batches[batch][at]
        return variant_label(spec.mission, spec.params)

    @overload
    def __getitem__(self, index: int) -> EpisodeSpec: ...

    @overload
    def __getitem__(self, index: slice) -> list[EpisodeSpec]: ...

    def __getitem__(self, index: int | slice) -> EpisodeSpec | list[EpisodeSpec]:
        if isinstance(index, slice):
            return [self[i] for i in range(*index.indices(self._len))]
        batch, at = self.place(index + self._len if index < 0 else index)
        return self.batches[batch][at]

    def __iter__(self) -> Iterator[EpisodeSpec]:
        for stretch in self._stretches:
            for row in range(stretch.first, stretch.first + stretch.rows):
                for b in stretch.batches:
                    yield self.batches[b][row]


@dataclass(frozen=True)
class Interleaved:
    """Batches of specs (one per variant) as one sequence taken by seed: the first spec of
    each batch, then the second of each, ... (a shorter batch is left out once it is done);
    :meth:`place` of ``i``: the batch and the place in it of ``specs[i]``."""

    specs: InterleavedSpecs
    sizes: list[int]

    @classmethod
    def of(
        cls, batches: Sequence[Sequence[EpisodeSpec]], labels: Sequence[str] = ()
    ) -> Interleaved:
        """``batches`` interleaved, each labelled as ``labels`` says (none: each spec's
        variant made from it, :func:`variant_label`)."""
        return cls(InterleavedSpecs(batches, labels), [len(batch) for batch in batches])

    def place(self, index: int) -> tuple[int, int]:
        return self.specs.place(index)

    def split(self, results: Mapping[int, EpisodeResult]) -> list[list[EpisodeResult]]:
        """The results by index in :attr:`specs` (those that finished), per batch in its
        spec order."""
        out: list[list[EpisodeResult]] = [[] for _ in self.sizes]
        for index in sorted(results, key=lambda i: self.place(i)[1]):
            out[self.place(index)[0]].append(results[index])
        return out

    def progress(self, bars: Sequence[Progress | None]) -> Progress | None:
        """One progress callback for the interleaved run that calls batch ``b``'s bar with
        that batch's own count and total; None when there is no bar. Each result's batch is
        the one of its variant (a result carries its mission and parameters), found at
        once, nothing kept per episode: a deque per episode (760 bytes, kept to the end)
        was 76 MB at 100 000 episodes, its batch by its key 10 MB. Only where batches hold
        the same variant (a program may give one twice) is each such episode's batch kept,
        by its seed, until its result comes: the first result of a seed goes to the first
        batch holding it, the next to the next."""
        if not any(bars):
            return None
        batches = self.specs.batches
        owners: dict[_Variant, list[int]] = {}
        for b, batch in enumerate(batches):
            for variant in _variants_of(batch):
                owners.setdefault(variant, []).append(b)
        waiting: dict[_Key, deque[int]] = {}
        for b, batch in enumerate(batches):
            shared = {v for v in _variants_of(batch) if len(owners[v]) > 1}
            for spec in batch if shared else ():
                if (spec.mission, tuple(spec.params)) in shared:
                    key = _key_of(spec.mission, spec.params, spec.seed)
                    waiting.setdefault(key, deque()).append(b)
        done = [0] * len(self.sizes)

        def progress(_: int, __: int, result: EpisodeResult) -> None:
            holding = owners[(result.mission, tuple(result.params))]
            batch = holding[0]
            if len(holding) > 1:
                key = _key_of(result.mission, result.params, result.seed)
                held = waiting[key]
                batch = held.popleft()
                if not held:
                    del waiting[key]
            done[batch] += 1
            bar = bars[batch]
            if bar is not None:
                bar(done[batch], self.sizes[batch], result)

        return progress


def _variants_of(batch: Sequence[EpisodeSpec]) -> set[_Variant]:
    """The variants ``batch`` holds: its template's for a plan (one), each spec's else."""
    if isinstance(batch, EpisodePlan):
        return {(batch.template.mission, tuple(batch.template.params))} if len(batch) else set()
    if isinstance(batch, InterleavedSpecs):
        return {variant for one in batch.batches for variant in _variants_of(one)}
    return {(spec.mission, tuple(spec.params)) for spec in batch}


def variant_label(
    mission: str, params: Iterable[tuple[str, str]], own: Iterable[tuple[str, str]] = ()
) -> str:
    """A variant as the report, its progress bar and the lines about its seeds name it: the
    mission as a report labels it (a shipped one by its name, ``dock``:
    :func:`~roomba_bt.mission.shipped.mission_label`), then each parameter that applied as
    ``-p`` gives it, those of ``params`` that its ``own`` (a ``--sweep`` value, a
    ``--variant`` set) do not override first, then its own: ``dock -p
    search_speed=250mm/s -p turn_speed=90mm/s``. The bar said ``dock
    search_speed=250mm/s turn_speed=90mm/s``, in another order and form than the report
    under it."""
    mine = dict(own)
    applied = [*((k, v) for k, v in params if k not in mine), *mine.items()]
    return " ".join([mission_label(mission), *(f"-p {k}={v}" for k, v in applied)])


def variant_count(specs: Sequence[EpisodeSpec]) -> int:
    """How many variants ``specs`` hold, without making a plan's every spec (a message
    about one episode of a 100 000-episode sweep made them all)."""
    return len(_variants_of(specs))


def _key_of(mission: str, params: tuple[tuple[str, str], ...], seed: int) -> _Key:
    return mission, tuple(params), seed
