"""``eval --plot``'s legends are drawn where they hide nothing of the map, one panel or
several: their boxes, as matplotlib lays them out, against the world's drawn extent."""

from __future__ import annotations

import pytest

from roomba_bt.evaluate.episode import EpisodeResult
from roomba_bt.sim import World, load_world


def _episode(world: World, seed: int, succeeded: bool) -> EpisodeResult:
    """An episode that crossed the whole world, corner to corner: paths to the map's edges."""
    xs = [x for room in world.rooms for x, _ in room]
    ys = [y for room in world.rooms for _, y in room]
    corners = ((min(xs) / 1000, min(ys) / 1000), (max(xs) / 1000, max(ys) / 1000))
    start = (corners[0][0], corners[0][1], 0.0)
    return EpisodeResult(
        seed=seed, outcome="success" if succeeded else "failure", reason="", time_s=1.0,
        wall_s=0.1, ticks=60, start=start, end=start, bumps=0, contact_steps=(), docked=False,
        charging=False, cliffs=0, fell=False, violations=0, loops=0.0, longest_stall_s=0.0,
        trajectory=corners,
    )  # fmt: skip


@pytest.mark.extra("plot")
@pytest.mark.parametrize("world_name", ["apartment", "empty-room"])
@pytest.mark.parametrize("variants", [1, 3])
def test_the_legends_do_not_cover_the_world(world_name: str, variants: int) -> None:
    """``eval --plot`` put each panel's legend at its upper right, over the map (an
    apartment's bedroom, its paths there): below the map now, outside every panel's world."""
    from matplotlib.transforms import Bbox

    from roomba_bt.evaluate.plot import variants_figure
    from roomba_bt.sim.plot import pyplot

    world = load_world(world_name)
    episodes = [_episode(world, 1, True), _episode(world, 2, False)]
    fig = variants_figure(world, [(f"variant {i}", episodes) for i in range(variants)])
    try:
        fig.canvas.draw()
        renderer = fig.canvas.get_renderer()
        xs = [x / 1000 for room in world.rooms for x, _ in room]
        ys = [y / 1000 for room in world.rooms for _, y in room]
        maps = [
            Bbox(ax.transData.transform([(min(xs), min(ys)), (max(xs), max(ys))]))
            for ax in fig.axes
        ]
        legends = [ax.get_legend() for ax in fig.axes]
        assert len(maps) == variants and all(legend is not None for legend in legends)
        labels = [ax.xaxis.label.get_window_extent(renderer) for ax in fig.axes]
        for legend in legends:
            box = legend.get_window_extent(renderer)
            assert [m for m in maps if box.overlaps(m)] == [], (box, maps)
            assert [x for x in labels if box.overlaps(x)] == [], (box, labels)  # "x (m)" too
            texts = [t.get_text() for t in legend.get_texts()]
            assert texts == ["succeeded (1)", "did not (1)"]
    finally:
        pyplot().close(fig)
