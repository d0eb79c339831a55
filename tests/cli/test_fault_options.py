"""The simulator's fault options on every command that has a simulator (``sim``, ``run``,
``eval``): one definition (``cli/arguments.add_fault_options``), the same names and ranges.
A bad cable for an hour took an hour to rehearse: only ``sim`` had them, in real time."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from roomba_bt.cli import main
from roomba_bt.evaluate.episode import EpisodeSpec, run_episode
from roomba_bt.runtime.summary import ExitCode
from roomba_bt.sim import Faults

#: bump-and-turn, 3 s of it
BUMP = ["bump-and-turn", "-p", "duration=3s"]


@pytest.mark.parametrize(
    "argv",
    [
        ["sim", "--pty"],
        ["run", *BUMP, "--fast"],
        ["eval", *BUMP, "--runs", "1", "--no-progress"],
    ],
    ids=["sim", "run", "eval"],
)
@pytest.mark.parametrize("option", ["--host-drop-rate", "--byte-drop-rate"])
def test_a_fault_rate_out_of_range_is_refused_by_its_option(
    argv: list[str], option: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main([*argv, option, "2"]) == ExitCode.INVALID
    assert f"{option}: found 2.0; allowed: 0.0..1.0" in capsys.readouterr().err


def test_a_real_robot_is_given_no_simulated_faults(capsys: pytest.CaptureFixture[str]) -> None:
    argv = ["run", *BUMP, "--port", "/dev/ttyUSB9", "--host-drop-rate", "0.01", "--reset-at", "2"]
    assert main(argv) == ExitCode.INVALID
    err = capsys.readouterr().err
    assert "--reset-at 2.0, --host-drop-rate 0.01: the simulator's faults, and --port is a " in err
    assert "real robot: drop them or --port" in err


def test_run_fast_meets_the_faults_it_is_given(capsys: pytest.CaptureFixture[str]) -> None:
    """A reset 1 s into the stream, on the virtual clock: the run ends as on a robot that
    reset."""
    argv = ["run", *BUMP, "--fast", "--display", "none", "--reset-at", "1", "--faults-from-stream"]
    assert main(argv) == ExitCode.LINK_LOST
    assert "the robot reset: its start-up banner was on the line" in capsys.readouterr().err


def test_run_on_a_cable_losing_bytes_from_the_robot_says_how_many_and_keeps_time(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """``--byte-drop-rate``: 2 % of the robot's bytes lost in the middle of its frames (what
    a long, cheap cable does), seeded. The summary says how many the line lost, and they
    are the bytes that did not arrive (the record holds what did); the parser resyncs on
    every frame after a broken one, a ``wait: 10s`` lasts 10 s of mission time, and the
    record's header keeps the fault, so the run can be made again from it."""
    monkeypatch.chdir(tmp_path)
    Path("wait.yaml").write_text("tree:\n  sequence:\n    - mode: safe\n    - wait: 10s\n")
    argv = ["run", "wait.yaml", "--fast", "--display", "none", "--seed", "3",
            "--byte-drop-rate", "0.02", "--record", "r.jsonl"]  # fmt: skip
    assert main(argv) == ExitCode.OK
    out = capsys.readouterr().out
    said = out.split("simulator    the line lost ")[1].split()
    lost, sent = int(said[0]), int(said[3])
    assert said[4:8] == ["bytes", "from", "the", "robot"]
    assert 0.015 * sent < lost < 0.025 * sent
    lines = [json.loads(line) for line in Path("r.jsonl").read_text().splitlines()]
    arrived = sum(len(bytes.fromhex(line["b"])) for line in lines if line.get("d") == "in")
    assert arrived == sent - lost
    assert "duration     10.0" in out
    frames = out.split("frames       ")[1].split(",")
    assert int(frames[1].split()[0]) > 100  # lost: every broken frame's slot counted
    assert lines[0]["simulator"]["faults"] == {"byte_drop_rate": 0.02}


def test_a_stop_the_run_could_not_confirm_is_said_as_the_simulator_saw_it(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """``run dock --fast --byte-drop-rate 0.05``: 95 % of dock's frames broken, the line
    garbled past the grace, exit 8, "final mode unknown ... the stop was not delivered".
    The robot's own sensors could not say where it ended; the simulator knows, and the
    rehearsing user was not told: stopped in Passive (the stop went out on a clean line)."""
    argv = ["run", "dock", "--fast", "--display", "none", "--byte-drop-rate", "0.05"]
    assert main(argv) == ExitCode.LINK_LOST
    out = capsys.readouterr().out
    assert "final mode   unknown: last seen in Safe, the stop was not delivered" in out
    said = "simulator    the robot ended in Passive, wheels 0/0 mm/s (the run could not confirm"
    assert said in out


def test_each_episode_draws_its_faults_from_its_seed() -> None:
    """An evaluation with a bad cable is repeatable episode by episode: the same seed loses
    the same bytes, another seed others."""
    faults = Faults(host_drop_rate=0.05)

    def lost(seed: int) -> tuple[str, str, float]:
        spec = EpisodeSpec("bump-and-turn", seed=seed, params=(("duration", "5s"),),
                           faults=faults, trace_every=0)  # fmt: skip
        result = run_episode(spec)
        return result.outcome, result.reason, result.distance_m

    assert lost(1) == lost(1)
    assert len({lost(seed) for seed in range(4)}) > 1


def test_eval_records_the_faults_its_episodes_met(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "faulty.jsonl"
    argv = ["eval", *BUMP, "--runs", "2", "--no-progress", "--json", "--out", str(out),
            "--host-drop-rate", "0.02", "--reset-at", "1", "--faults-from-stream"]  # fmt: skip
    assert main(argv) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["conditions"]["faults"] == [
        "--reset-at 1.0",
        "--host-drop-rate 0.02",
        "--faults-from-stream",
    ]
    records = [json.loads(line) for line in out.read_text().splitlines()]
    assert [r["outcome"] for r in records] == ["CONNECTION LOST"] * 2


#: the robot resets as its stream is asked for: the start-up was answered, no frame came
RESET_BEFORE_A_FRAME = ["--reset-at", "0", "--faults-from-stream"]
#: what the reason of such a run (and episode) ends with
NOT_STARTED = (
    "the mission did not start: no sensor frame came after the robot answered the start-up, "
    "so nothing of the mission was sent"
)


def test_a_run_whose_stream_never_came_was_not_started(capsys: pytest.CaptureFixture[str]) -> None:
    """The link failed before the stream's first frame: the tree never ticked, nothing of
    the mission was sent. NO CONNECTION, exit 3, safe to retry (decided; it was 8, "lost
    after the run started", where a service's RestartPreventExitStatus=8 left it to a
    person; 0.1.0: CONNECTION LOST, exit 3)."""
    argv = ["run", *BUMP, "--fast", "--display", "none", *RESET_BEFORE_A_FRAME]
    assert main(argv) == ExitCode.CONNECTION
    out, err = capsys.readouterr()
    assert "outcome      NO CONNECTION (sim://empty-room: the robot reset: " in out
    assert "ticks        0 " in out
    assert f"; {NOT_STARTED})\n" in out
    assert err.startswith("roomba-bt: no connection: sim://empty-room: the robot reset: ")
    assert err.rstrip().endswith(NOT_STARTED)


def test_an_episode_whose_stream_never_came_is_no_connection(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``eval``'s episode says it as the run does: NO CONNECTION, not CONNECTION LOST."""
    out = tmp_path / "never.jsonl"
    argv = ["eval", *BUMP, "--runs", "1", "--no-progress", "--out", str(out),
            *RESET_BEFORE_A_FRAME]  # fmt: skip
    code = main(argv)
    [record] = [json.loads(line) for line in out.read_text().splitlines()]
    assert record["outcome"] == "NO CONNECTION"
    assert record["reason"].endswith(NOT_STARTED)
    assert "NO CONNECTION: sim://empty-room: the robot reset: " in capsys.readouterr().out
    assert code == ExitCode.OK  # an evaluation's own exit: its episodes ran (eval's table)
