"""``make coverage``'s chart (docs/routines/coverage-living-room.png) has its legend below
the chart, where it hides none of the curves: its box, as matplotlib lays it out, against the
chart's area, its x label and tick labels, as ``eval --plot``'s (test_plot_legend.py)."""

from __future__ import annotations

from types import SimpleNamespace
from typing import Any

import pytest

from roomba_bt.evaluate.coverage_report import DRIFT
from roomba_bt.evaluate.episode import Coverage


def _episode(pace: float) -> Any:
    """An episode's coverage (all the chart reads of one): 30 s samples for 20 minutes, up
    to the whole room, so the curves and bands reach the chart's corners."""
    curve = tuple((30.0 * i, min(1.0, pace * i / 40)) for i in range(41))
    return SimpleNamespace(coverage=Coverage("living-room", curve[-1][1], curve, 0.0, (), 0.0, 0.0))


@pytest.mark.extra("plot")
def test_the_legend_is_below_the_chart_a_row_a_mission() -> None:
    """The legend was at the chart's lower right, over the bands from 5 minutes on."""
    from roomba_bt.evaluate.coverage_report import curves_figure
    from roomba_bt.sim.plot import pyplot

    missions = ("clean", "clean-builtin", DRIFT)
    fig = curves_figure({name: [_episode(p) for p in (0.6, 1.0, 1.4)] for name in missions})
    try:
        fig.canvas.draw()
        renderer = fig.canvas.get_renderer()
        [ax] = fig.axes
        legend = ax.get_legend()
        box = legend.get_window_extent(renderer)
        chart = ax.get_window_extent(renderer)
        assert not box.overlaps(chart), (box, chart)
        assert box.y1 < chart.y0  # below it, not beside it
        labels = [ax.xaxis.label, *ax.get_xticklabels()]
        covered = [t.get_text() for t in labels if box.overlaps(t.get_window_extent(renderer))]
        assert covered == []
        texts = [t.get_text() for t in legend.get_texts()]
        assert texts == [
            "clean.yaml (mean)",
            "clean-builtin.yaml (mean)",
            "clean.yaml, odometry error 1.5 % (mean)",
            "clean.yaml (10th..90th percentile)",
            "clean-builtin.yaml (10th..90th percentile)",
            "clean.yaml, odometry error 1.5 % (10th..90th percentile)",
        ]
    finally:
        pyplot().close(fig)
