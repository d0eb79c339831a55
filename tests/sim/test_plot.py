"""The trajectory plot: a PNG when matplotlib is there, a clear error when it is not."""

from __future__ import annotations

import builtins
from pathlib import Path

import pytest

from roomba_bt.oi import commands as C
from roomba_bt.sim import Simulator, load_world
from roomba_bt.sim.plot import PlotUnavailableError, draw_world, plot_run, pyplot

from .helpers import BOX, world

#: the box with two dirt patches, one over the other's corner (the robot reads the higher)
DIRTY_BOX = BOX + (
    "dirt: [{rect: [1.0, 1.0, 1.5, 2.0], level: 40}, {rect: [1.4, 1.9, 2.0, 2.5], level: 200}]\n"
)


def run() -> Simulator:
    sim = Simulator(load_world("apartment"), seed=2)
    sim.receive(C.start().data + C.safe().data + C.drive(300, -32768).data)
    sim.run(15.0)
    return sim


@pytest.mark.extra("plot")
def test_plot_writes_a_png(tmp_path: Path) -> None:
    sim = run()
    assert any(e.kind == "bump" for e in sim.events)
    out = tmp_path / "run.png"
    plot_run(sim, out)
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert out.stat().st_size > 20_000


def test_without_matplotlib_the_error_says_how_to_install_it(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    real_import = builtins.__import__

    def no_matplotlib(name: str, *args: object, **kwargs: object) -> object:
        if name.startswith("matplotlib"):
            raise ImportError("No module named 'matplotlib'")
        return real_import(name, *args, **kwargs)  # type: ignore[arg-type]

    monkeypatch.setattr(builtins, "__import__", no_matplotlib)
    with pytest.raises(PlotUnavailableError, match=r"pip install 'roomba-bt\[plot\]'"):
        plot_run(run(), tmp_path / "run.png")
    assert not (tmp_path / "run.png").exists()


@pytest.mark.parametrize("labels", [True, False], ids=["run --plot", "eval --plot"])
@pytest.mark.extra("plot")
def test_the_world_drawing_shows_each_dirt_patch_with_its_level(labels: bool) -> None:
    """A world's dirt patches were not drawn (a plugin author's run over crumbs showed none):
    each is a shaded shape with the dirt-detect level (packet 15) written in its middle, in
    the one drawing ``run --plot`` and ``eval --plot`` share, named in the legend where the
    drawing has one."""
    plt = pyplot()
    fig, ax = plt.subplots()
    try:
        draw_world(ax, world(DIRTY_BOX), labels=labels)
        shaded = [p.get_path().get_extents().bounds for p in ax.patches if p.get_hatch() == ".."]
        assert shaded == [pytest.approx((1.0, 1.0, 0.5, 1.0)), pytest.approx((1.4, 1.9, 0.6, 0.6))]
        levels = {t.get_text(): t.get_position() for t in ax.texts}
        assert levels == {"40": pytest.approx((1.25, 1.5)), "200": pytest.approx((1.7, 2.2))}
        named = [label for label in ax.get_legend_handles_labels()[1] if "dirt" in label]
        assert named == (["dirt (level, packet 15)"] * 2 if labels else [])
    finally:
        plt.close(fig)


@pytest.mark.extra("plot")
def test_the_legend_stands_beside_the_map_not_on_it(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    """``run --plot`` put its legend in the map's upper right corner, over an owner's hall
    and step: it stands outside the axes now, and the saved image holds it."""
    plt = pyplot()
    drawn: list[object] = []
    monkeypatch.setattr(plt, "close", drawn.append)  # keep the figure to look at
    plot_run(run(), tmp_path / "run.png")
    (fig,) = drawn
    try:
        (ax,) = [a for a in fig.axes if a.get_legend() is not None]  # type: ignore[attr-defined]
        renderer = fig.canvas.get_renderer()  # type: ignore[attr-defined]
        legend = ax.get_legend().get_window_extent(renderer)
        assert not legend.overlaps(ax.get_window_extent(renderer))
    finally:
        monkeypatch.undo()
        plt.close(fig)
