"""``roomba-bt sim``: what the served simulator keeps, what its help says."""

from __future__ import annotations

from pathlib import Path

import pytest

from roomba_bt.cli import build_parser, main, sim_cmd
from roomba_bt.sim import Simulator


def test_a_served_simulator_without_plot_keeps_no_trajectory(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # 16 minutes served grew the process by 3.3 MB: every 4th step's point kept for a plot
    # nobody asked for
    kept: list[Simulator] = []

    def serve(simulator: Simulator, endpoint: object, duration: object, **_: object) -> None:
        kept.append(simulator)
        endpoint.close()  # type: ignore[attr-defined]
        for _ in range(4000):  # a minute of robot time
            simulator.step()

    monkeypatch.setattr(sim_cmd, "_serve_until_stopped", serve)
    assert main(["sim", "--pty"]) == 0
    assert not kept[0].keeps_trace
    assert len(kept[0].trace) <= 1


def test_a_served_simulator_with_plot_keeps_its_trajectory(tmp_path: Path) -> None:
    args = build_parser().parse_args(["sim", "--pty", "--plot", str(tmp_path / "t.png")])
    simulator = sim_cmd._simulator(args)
    assert isinstance(simulator, Simulator) and simulator.keeps_trace


def test_help_says_what_latency_is_and_the_least_inject_every(
    capsys: pytest.CaptureFixture[str],
) -> None:
    with pytest.raises(SystemExit):
        main(["sim", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "per byte" not in text
    assert "before the robot's bytes become readable" in text
    assert "at least 0.015" in text
