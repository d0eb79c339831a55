"""``roomba-bt sim``: what the served simulator keeps, what its help says."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest
from quoted import assert_quoted  # tests/quoted.py: the docs' quotes

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


@pytest.mark.extra("plot")
def test_a_served_simulator_with_plot_keeps_its_trajectory(tmp_path: Path) -> None:
    args = build_parser().parse_args(["sim", "--pty", "--plot", str(tmp_path / "t.png")])
    simulator = sim_cmd._simulator(args)
    assert isinstance(simulator, Simulator) and simulator.keeps_trace


def test_help_says_what_latency_is_and_the_least_inject_every(
    help_text: Callable[[str], str],
) -> None:
    text = help_text("sim")
    assert "per byte" not in text
    assert "before the robot's bytes become readable" in text
    assert "at least 0.015" in text


def test_the_served_simulator_loses_the_clients_bytes_on_request_and_says_how_many(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """``sim --host-drop-rate``: the host->robot half of a bad cable, rehearsed on a pty."""

    def serve(simulator: Simulator, endpoint: object, duration: object, **_: object) -> None:
        endpoint.close()  # type: ignore[attr-defined]
        for _ in range(50):
            simulator.receive(b"\x89\x00\xc8\x80\x00")  # what a client writes

    monkeypatch.setattr(sim_cmd, "_serve_until_stopped", serve)
    args = ["sim", "--pty", "--host-drop-rate", "0.5", "--host-corrupt-rate", "0.1"]
    assert main([*args, "--seed", "4"]) == 0
    said = capsys.readouterr().err
    assert "roomba-bt sim: the line lost " in said and "of the bytes from the client" in said
    lost = int(said.split("the line lost ")[1].split()[0])
    assert 60 < lost < 190  # about half of 250


@pytest.mark.parametrize(("given", "charge"), [([], 0.7), (["--battery", "15%"], 0.15)])
def test_sim_takes_battery_as_run_and_eval_do(given: list[str], charge: float) -> None:
    """``sim --battery`` (session 37's stranger copied a world to try "dock when low" on a
    served robot: run and eval had the option, sim did not); the apartment's own is 0.7."""
    args = build_parser().parse_args(["sim", "--pty", "--world", "apartment", *given])
    simulator = sim_cmd._simulator(args)
    assert isinstance(simulator, Simulator)
    assert simulator.world.battery == pytest.approx(charge)
    assert simulator.battery_charge == pytest.approx(charge * 2696)  # mAh of a full one


def test_sim_refuses_an_empty_battery(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exited:
        main(["sim", "--pty", "--battery", "0"])
    assert exited.value.code == 2
    assert "an empty battery switches the simulated robot off" in capsys.readouterr().err


def test_the_served_simulator_says_the_clock_and_schedule_a_client_set(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """No packet reads the clock back, so a client's own Set Day/Time (168) and Schedule
    (167) on a pty were seen nowhere but ``--log``: the summary says what the robot holds,
    its clock run on by the simulated time, and says nothing of a clock nobody set."""
    from roomba_bt.oi import commands

    sent = commands.set_day_time("fri", 8, 59).data + commands.schedule({"tue": (9, 30)}).data

    def serve(simulator: Simulator, endpoint: object, duration: object, **_: object) -> None:
        endpoint.close()  # type: ignore[attr-defined]
        simulator.receive(commands.start().data + sent)
        for _ in range(4000):  # a minute of robot time
            simulator.step()

    monkeypatch.setattr(sim_cmd, "_serve_until_stopped", serve)
    assert main(["sim", "--pty", "--profile", "roomba600"]) == 0
    said = capsys.readouterr().err
    assert_quoted("docs/simulator.md", "roomba-bt sim: the robot's clock reads", said)
    sent = b""
    assert main(["sim", "--pty", "--profile", "roomba600"]) == 0
    assert "clock" not in capsys.readouterr().err
