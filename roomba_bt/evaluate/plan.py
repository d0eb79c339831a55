"""An evaluation's episodes as a plan: the fields every episode shares and the seeds, each
episode's :class:`~roomba_bt.evaluate.episode.EpisodeSpec` made when it is taken.

``eval --runs 100000`` made every spec before the first episode ran: 60 MB more in the
parent than for 1000 (an A/B twice that), and in each worker forked from it, before the
first result.
A plan holds one spec and a ``range`` of seeds, whatever the number of episodes; its specs
are the same ones, made again from it each time (a spec is a few microseconds to make, an
episode milliseconds to seconds to run).
"""

from __future__ import annotations

from collections.abc import Container, Iterator, Sequence
from dataclasses import dataclass, field, replace
from functools import cached_property
from typing import Any, overload

from roomba_bt.evaluate.episode import EpisodeSpec


@dataclass(frozen=True, eq=False)
class EpisodePlan(Sequence[EpisodeSpec]):
    """``template`` run on each of ``seeds`` (in their order): ``plan[i]`` is ``template``
    with ``seeds[i]`` as its seed. ``seeds`` is a ``range`` for ``--seed`` and ``--runs``
    (its size is its two ends), the list given for ``--seeds``."""

    template: EpisodeSpec
    seeds: Sequence[int] = field(default=range(0))

    def __len__(self) -> int:
        return len(self.seeds)

    @overload
    def __getitem__(self, index: int) -> EpisodeSpec: ...

    @overload
    def __getitem__(self, index: slice) -> EpisodePlan: ...

    def __getitem__(self, index: int | slice) -> EpisodeSpec | EpisodePlan:
        if isinstance(index, slice):
            return replace(self, seeds=self.seeds[index])
        return replace(self.template, seed=self.seeds[index])

    def __iter__(self) -> Iterator[EpisodeSpec]:
        template = self.template
        for seed in self.seeds:
            yield replace(template, seed=seed)

    def __repr__(self) -> str:  # a plan of 100 000 episodes is said in a line
        return f"EpisodePlan({self.template!r}, seeds={_seeds_said(self.seeds)})"

    def place(self, seed: int) -> int | None:
        """Where the episode of ``seed`` is in the plan (None: it is not): at once for a
        range, from an index made at the first question for a list."""
        if isinstance(self.seeds, range):
            return self.seeds.index(seed) if seed in self.seeds else None
        return self._places.get(seed)

    @cached_property
    def _places(self) -> dict[int, int]:
        return {seed: i for i, seed in enumerate(self.seeds)}

    def with_fields(self, **fields: Any) -> EpisodePlan:
        """The plan with ``fields`` set in every episode's spec (``keys`` for ``--key``)."""
        return replace(self, template=replace(self.template, **fields))

    def without(self, seeds: Container[int]) -> EpisodePlan:
        """The plan without the episodes of ``seeds`` (those ``--resume`` read back), in
        its order; the same plan when it holds none of them."""
        left = tuple(seed for seed in self.seeds if seed not in seeds)
        return self if len(left) == len(self.seeds) else replace(self, seeds=left)


def _seeds_said(seeds: Sequence[int]) -> str:
    if isinstance(seeds, range) or len(seeds) <= 6:
        return repr(seeds)
    return f"[{', '.join(map(str, seeds[:3]))}, ... {seeds[-1]}] ({len(seeds)} seeds)"
