"""The trajectory plot: a PNG when matplotlib is there, a clear error when it is not."""

from __future__ import annotations

import builtins
from pathlib import Path

import pytest

from roomba_bt.oi import commands as C
from roomba_bt.sim import Simulator, load_world
from roomba_bt.sim.plot import PlotUnavailableError, plot_run


def run() -> Simulator:
    sim = Simulator(load_world("apartment"), seed=2)
    sim.receive(C.start().data + C.safe().data + C.drive(300, -32768).data)
    sim.run(15.0)
    return sim


def test_plot_writes_a_png(tmp_path: Path) -> None:
    pytest.importorskip("matplotlib")
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
