"""An episode stuck in a behaviour's endless loop is recorded as HUNG at its wall-clock
limit, where it was stuck, and the sweep goes on (its worker process ended and replaced)."""

from __future__ import annotations

import re
import shlex
import threading
from pathlib import Path

import pytest
from waits import joined  # tests/waits.py: a hang's bound

from roomba_bt.cli import main
from roomba_bt.evaluate import EpisodeResult, EpisodeSpec, episode_specs, parallel
from roomba_bt.evaluate.episode import HUNG
from roomba_bt.evaluate.parallel import LocalRun, run_episodes
from roomba_bt.mission import Permissions

MISSIONS = Path(__file__).resolve().parents[2] / "missions"
BUMP = str(MISSIONS / "bump-and-turn.yaml")

_STUCK = """\
import hashlib

from roomba_bt.behaviours import Condition, declare


@declare("stuck", kind="condition", reads=(27,))
class Stuck(Condition):
    \"\"\"Never returns: a loop in Python.\"\"\"

    def check(self, snapshot):
        while True:
            pass


@declare("stuck_in_c", kind="condition", reads=(27,))
class StuckInC(Condition):
    \"\"\"Never returns while a test runs: two billion rounds of a hash in C (OpenSSL's),
    which does not go back to Python, where a signal's handler would run.\"\"\"

    def check(self, snapshot):
        return bool(hashlib.pbkdf2_hmac("sha256", b"x", b"y", 2**31 - 1))
"""


def _stuck(tmp_path: Path, leaf: str = "stuck") -> EpisodeSpec:
    (tmp_path / "stuck.py").write_text(_STUCK)
    mission = tmp_path / f"{leaf}.yaml"
    mission.write_text(
        f"plugins: [./stuck.py]\ntree:\n  sequence:\n    - mode: safe\n    - wait: 1s\n"
        f"    - {leaf}\n"
    )
    (spec,) = episode_specs(str(mission), runs=1, seed=5, timeout_s=5.0,
                            permissions=Permissions(plugin_files=True))  # fmt: skip
    return spec


def _quick(runs: int) -> list[EpisodeSpec]:
    return episode_specs(BUMP, runs=runs, seed=1, timeout_s=3.0, params=(("duration", "1s"),))


def test_a_stuck_episode_is_hung_where_it_was_and_the_others_run(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The sweep hung until Ctrl-C. With --jobs 1 too (a worker process: only a process can
    be ended whatever it runs), and the ended worker is no death: with no restart allowed
    the episodes queued behind it still run."""
    monkeypatch.setattr(parallel, "POOL_RESTARTS", 0)
    run = LocalRun()
    results = run_episodes([_stuck(tmp_path), *_quick(3)], jobs=1, run=run, wall_limit_s=2.0)
    hung, *others = results
    assert hung.outcome == HUNG and hung.seed == 5
    assert hung.stage == "stuck"
    assert hung.reason.startswith("--wall-limit 2 s of wall-clock time ran out in behaviour ")
    assert re.search(rf"stuck \(at {re.escape(str(tmp_path))}/stuck.py:1[12]\)$", hung.reason)
    assert hung.time_s == pytest.approx(1.02)  # the mission time it was stuck at
    # the CPU time its loop burnt is its own (it recorded none: the summary's speed counted
    # its mission time over the other episodes' CPU time alone)
    assert hung.cpu_s > 0
    assert [r.outcome for r in others] == ["success"] * 3
    assert run.retried >= 1  # queued in the pool behind it


def test_a_loop_in_c_code_is_ended_all_the_same(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """No Python frame can say where it is (the signal's handler never runs): the worker is
    ended after a wait, and the record says why it has no stage."""
    monkeypatch.setattr(parallel, "STUCK_REPORT_S", 0.2)
    (hung,) = run_episodes([_stuck(tmp_path, "stuck_in_c")], wall_limit_s=1.0)
    assert hung.outcome == HUNG and hung.stage == ""
    assert hung.reason == (
        "--wall-limit 1 s of wall-clock time ran out: no Python frame answered (a loop in C code?)"
    )


def test_on_a_dask_worker_the_limit_raises_in_the_episode_s_thread(tmp_path: Path) -> None:
    """A Dask worker runs episodes in threads, which cannot be ended: the limit raises in
    the thread, the robot's safe stop runs, the result is HUNG with where it was."""
    from roomba_bt.evaluate.cluster import within_wall_limit

    out: list[EpisodeResult] = []
    thread = threading.Thread(target=lambda: out.append(within_wall_limit(_stuck(tmp_path), 1.0)))
    thread.start()
    joined(thread, "an episode past its 1 s wall limit")
    (hung,) = out
    assert (hung.outcome, hung.stage) == (HUNG, "stuck")
    assert "ran out in behaviour sequence / stuck (at " in hung.reason
    assert hung.commands_sent > 0  # the start-up's and the safe stop's
    assert hung.cpu_s > 0  # its thread's, measured in it
    (quick,) = _quick(1)
    assert within_wall_limit(quick, 30.0).outcome == "success"


def test_eval_reports_hung_episodes_and_exits_4(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    spec = _stuck(tmp_path)
    code = main(["eval", spec.mission, "--runs", "1", "--seed", "5", "--timeout", "5s",
                 "--wall-limit", "1s", "--allow-plugin-files", "--no-progress"])  # fmt: skip
    out, err = capsys.readouterr()
    assert code == 4
    assert "HUNG: --wall-limit 1 s of wall-clock time ran out in behaviour sequence / stuck" in out
    assert "1 episode(s) ran past --wall-limit (stuck: an endless loop in a behaviour?)" in err
    assert main(["eval", BUMP, "--wall-limit", "soon"]) == 2
    assert "--wall-limit 'soon': expected a duration" in capsys.readouterr().err
    # the advice's run, with the evaluation's limit: it ends there and says where, as eval
    # did (it had no --wall-limit, and the run it gave hung with no word)
    advice = err.split("run it alone with: ", 1)[1].splitlines()[0]
    words = shlex.split(advice)
    assert words[:3] == ["roomba-bt", "-v", "run"] and "--wall-limit" in words
    assert words[words.index("--timeout") + 1] == "5"  # eval's limit, not run's 2 h
    assert main(words[1:]) == 4
    # the same outcome and words as the episode's (it said ERROR, as if the tree had raised)
    stuck = "--wall-limit 1 s of wall-clock time ran out in behaviour sequence / stuck (at "
    out, err = capsys.readouterr()
    assert f"outcome      HUNG ({stuck}" in out
    assert f"roomba-bt: hung: {stuck}" in err


@pytest.mark.extra("cluster")
def test_a_dask_worker_goes_on_after_a_hung_episode(tmp_path: Path) -> None:
    """On a real (local) cluster of one worker: the episode after the stuck one runs there."""
    from roomba_bt.evaluate.parallel import Engine, evaluate

    (done,) = evaluate([[_stuck(tmp_path), *_quick(1)]], Engine("dask", 1, wall_limit_s=2.0))
    hung, quick = done.results
    assert (hung.outcome, hung.stage, quick.outcome) == (HUNG, "stuck", "success")
    assert hung.worker == quick.worker and not done.interrupted


def test_without_a_signal_to_ask_where_a_stuck_episode_is_still_hung_and_ended(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Windows has no SIGUSR1 (nor SIGKILL): the worker is not asked where it is stuck, only
    ended; the episode is HUNG without its place and the sweep goes on (every worker looked
    dead when SIGUSR1 was taken for granted)."""
    monkeypatch.setattr(parallel, "ASK_WHERE", None)
    monkeypatch.setattr(parallel, "POOL_RESTARTS", 0)
    results = run_episodes([_stuck(tmp_path), *_quick(1)], jobs=1, run=LocalRun(), wall_limit_s=2.0)
    hung, other = results
    assert hung.outcome == HUNG and hung.stage == ""
    assert hung.reason.startswith("--wall-limit 2 s of wall-clock time ran out")
    assert other.outcome == "success"
