"""Episodes: seeded, measured on the simulator, the same in any number of processes."""

from __future__ import annotations

import dataclasses
import io
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from roomba_bt.evaluate import EpisodeSpec, EvaluationError, episode_specs, run_episode
from roomba_bt.evaluate.episode import EpisodeResult, build_world, start_pose
from roomba_bt.evaluate.parallel import ProgressBar, run_episodes
from roomba_bt.evaluate.testing import assert_success_rate

from .terminal import Terminal, a_terminal_that_takes_codes

pytestmark = pytest.mark.usefixtures(a_terminal_that_takes_codes.__name__)

MISSIONS = Path(__file__).resolve().parents[2] / "missions"
BUMP = str(MISSIONS / "bump-and-turn.yaml")


def _without_wall_time(results: list) -> list:  # type: ignore[type-arg]
    return [dataclasses.replace(r, wall_s=0.0) for r in results]


def test_same_results_with_one_or_two_jobs() -> None:
    specs = episode_specs(BUMP, world="apartment", runs=4, seed=7,
                          params=(("duration", "6s"),), timeout_s=30)  # fmt: skip
    one = run_episodes(specs, jobs=1)
    two = run_episodes(specs, jobs=2)
    assert _without_wall_time(one) == _without_wall_time(two)
    assert [r.seed for r in two] == [7, 8, 9, 10]
    assert len({r.start for r in one}) == 4, "each seed starts somewhere else"


def test_start_poses_within_a_distance_of_the_dock() -> None:
    for seed in range(20):
        spec = EpisodeSpec(BUMP, "empty-room", seed=seed, within_m=0.5)
        world = build_world(spec)
        pose = start_pose(world, spec)
        assert world.dock is not None
        docked = world.dock.docked_pose
        assert (pose.x - docked.x) ** 2 + (pose.y - docked.y) ** 2 <= 500.0**2


def test_dock_overrides_reach_the_world() -> None:
    spec = EpisodeSpec(BUMP, "empty-room", dock=(("buoy_range", 0.5), ("red", (-3, 15))))
    dock = build_world(spec).dock
    assert dock is not None
    assert dock.buoy_range == 500.0
    assert dock.red[1] == pytest.approx(0.2618, abs=1e-4)


@pytest.mark.parametrize(
    ("spec", "message"),
    [
        (EpisodeSpec(BUMP, "no-such-world"), "no such file or shipped world"),
        (EpisodeSpec(BUMP, "corridor", dock=(("colour", 1.0),)), "unknown dock field"),
        (EpisodeSpec("missions/none.yaml", "empty-room"), "none.yaml"),
    ],
)
def test_bad_input_is_an_evaluation_error(spec: EpisodeSpec, message: str) -> None:
    with pytest.raises(EvaluationError, match=message):
        run_episode(spec)


def test_progress_bar_counts_successes() -> None:
    stream = io.StringIO()
    bar = ProgressBar(stream, width=10)
    specs = episode_specs(BUMP, runs=2, params=(("duration", "2s"),), timeout_s=10)
    run_episodes(specs, jobs=1, progress=bar)
    text = stream.getvalue()
    assert "2/2 ok 2" in text and text.endswith("\n")


def test_the_bar_redraws_on_a_terminal_and_writes_each_tenth_into_a_log() -> None:
    """A CI log got a carriage-return redraw per episode."""
    result = run_episode(episode_specs(BUMP, runs=1, params=(("duration", "1s"),))[0])
    log, terminal = io.StringIO(), Terminal()
    for stream in (log, terminal):
        bar = ProgressBar(stream, width=10)
        for done in range(1, 51):
            bar(done, 50, result)
    lines = log.getvalue().splitlines()
    assert "\r" not in log.getvalue() and len(lines) == 11  # the first, then each tenth
    assert [line.split()[1] for line in lines[:3]] == ["1/50", "5/50", "10/50"]
    assert terminal.getvalue().count("\r") == 50 and terminal.getvalue().count("\n") == 1


def test_a_redraw_on_a_terminal_erases_what_the_longer_line_before_left() -> None:
    """A redraw writes over the line from its start: one shorter than the line before it
    (the ETA from 100 s to 99 s; an A/B's two bars share the line, and ``dock`` redrew over
    ``my-dock``) left the longer one's last characters, ``ETA 99ss``. Each redraw ends by
    erasing the rest of the line; a log gets no terminal code."""
    result = run_episode(episode_specs(BUMP, runs=1, params=(("duration", "1s"),))[0])
    log, terminal = io.StringIO(), Terminal()
    for stream in (log, terminal):
        long, short = (
            ProgressBar(stream, width=10, label="my-dock "),
            ProgressBar(stream, width=10, label="dock "),
        )
        long(1, 1000, result)
        short(1, 1000, result)
    redraws = terminal.getvalue().split("\r")[1:]
    assert [r.startswith(("my-dock [", "dock [")) for r in redraws] == [True, True]
    assert all(r.endswith("\x1b[K") for r in redraws)
    assert "\x1b" not in log.getvalue()


def test_a_bar_left_mid_line_by_an_interrupted_evaluation_is_ended_before_what_follows() -> None:
    """Ctrl-C on a terminal stopped the bars mid-line, and ``results written to int.jsonl``
    followed the last one on its line (``ETA 567s^Cresults written ...``). ``end_bars``
    ends the line the last drawn bar left open, once; a bar that drew its last episode
    (its own end of line), or a log's, needs none."""
    from roomba_bt.evaluate.parallel import end_bars

    result = run_episode(episode_specs(BUMP, runs=1, params=(("duration", "1s"),))[0])
    terminal, log = Terminal(), io.StringIO()
    a, b = ProgressBar(terminal, label="a "), ProgressBar(terminal, label="b ")
    a(3, 10, result)
    b(3, 10, result)
    end_bars([a, None, b])
    end_bars([a, b])
    assert terminal.getvalue().endswith("\x1b[K\n") and terminal.getvalue().count("\n") == 1
    b(10, 10, result)  # finished: its own end of line
    end_bars([a, b])
    assert terminal.getvalue().count("\n") == 2
    in_a_log = ProgressBar(log)
    in_a_log(3, 10, result)
    end_bars([in_a_log])
    assert log.getvalue().count("\n") == 1


def test_assert_success_rate_passes_and_fails_with_the_report() -> None:
    summary = assert_success_rate(BUMP, runs=2, within_s=20, rate=1.0,
                                  params={"duration": "3s"})  # fmt: skip
    assert summary.successes == 2
    with pytest.raises(AssertionError, match=r"0 of 2 runs within 2 s .*\n.*mission"):
        assert_success_rate(str(MISSIONS / "dock.yaml"), runs=2, within_s=2, rate=0.5)


def test_without_a_trace_the_episode_is_the_same_and_keeps_no_trajectory() -> None:
    """``eval`` without ``--plot`` asks for no trajectory (``trace_every=0``): the simulator
    keeps no trace and the result none, everything else as with one."""
    traced = run_episode(EpisodeSpec(BUMP, "corridor", seed=4, timeout_s=20.0))
    untraced = run_episode(EpisodeSpec(BUMP, "corridor", seed=4, timeout_s=20.0, trace_every=0))
    assert len(traced.trajectory) > 100
    assert untraced.trajectory == ()
    assert _without_wall_time([untraced]) == _without_wall_time(
        [dataclasses.replace(traced, trajectory=())]
    )


def test_an_evaluations_specs_carry_one_reading_of_each_file(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Made self-contained together, an evaluation's episodes share one reading of the
    mission (and of a world file): parsed once, not once an episode, and the same bytes in
    all of them even if the file is saved while they are submitted."""
    import roomba_bt.evaluate.episode as episode

    world = tmp_path / "room.yaml"
    world.write_text((MISSIONS.parent / "roomba_bt/sim/worlds/corridor.yaml").read_text())
    specs = episode_specs(BUMP, world=str(world), runs=3, seed=1)
    specs += episode_specs(str(MISSIONS / "dock.yaml"), world=str(world), runs=2, seed=1)
    read: list[str] = []
    bundle = episode.bundle_mission
    monkeypatch.setattr(episode, "bundle_mission", lambda p: read.append(p) or bundle(p))
    travelling = episode.all_self_contained(specs)
    assert read == [BUMP, str(MISSIONS / "dock.yaml")]
    assert len({id(s.sources) for s in travelling}) == 2
    assert len({id(s.world_file) for s in travelling}) == 1
    assert travelling[0] == episode.self_contained(specs[0])
    assert [dataclasses.replace(s, sources=None, world_file=None) for s in travelling] == specs


@pytest.mark.parametrize(
    ("mission", "named"),
    [("bounce.yaml", "lib/escapes.yaml"), ("custom_condition.yaml", "plugins/near_wall.py")],
)
def test_a_self_contained_spec_needs_none_of_its_files(
    tmp_path: Path, mission: str, named: str
) -> None:
    """The mission and the file it includes (or the plugin it loads) travel as texts: the
    episode runs the same after the files are gone (a worker without a shared disk)."""
    import shutil

    from roomba_bt.evaluate.episode import self_contained

    folder = tmp_path / "examples"
    for name in (mission, named):
        (folder / name).parent.mkdir(parents=True, exist_ok=True)
        shutil.copy(MISSIONS / "examples" / name, folder / name)
    from roomba_bt.mission import Permissions

    allowed = Permissions(plugin_files=True)  # as eval --allow-plugin-files grants
    spec = EpisodeSpec(str(folder / mission), "empty-room", seed=3, timeout_s=3.0,
                       permissions=allowed)  # fmt: skip
    from_files = run_episode(spec)
    travelling = self_contained(spec)
    assert travelling.sources is not None
    assert sorted(n for n, _ in travelling.sources.files) == sorted([mission, named])
    shutil.rmtree(folder)
    assert _without_wall_time([run_episode(travelling)]) == _without_wall_time([from_files])


def test_a_world_of_ones_own_and_a_shipped_mission_travel_by_their_names(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A world found by its name in a folder of ``ROOMBA_BT_WORLDS`` is on no other machine:
    it travels as its text, as a world given by path does (a shipped world's name stays a
    name: every installation has those). A shipped mission named as ``eval``'s results name
    it (``roomba-bt:bump-and-turn.yaml``) travels as the file it is."""
    from roomba_bt.evaluate.episode import self_contained
    from roomba_bt.sim.world import WORLDS_DIR

    own = tmp_path / "worlds"
    own.mkdir()
    (own / "room.yaml").write_text((WORLDS_DIR / "corridor.yaml").read_text())
    monkeypatch.setenv("ROOMBA_BT_WORLDS", str(own))
    spec = EpisodeSpec("roomba-bt:bump-and-turn.yaml", "room", seed=3, timeout_s=3.0,
                       params=(("duration", "2s"),))  # fmt: skip
    travelling = self_contained(spec)
    assert travelling.world_file == ("room.yaml", (own / "room.yaml").read_text())
    assert travelling.sources is not None
    assert [name for name, _ in travelling.sources.files] == ["bump-and-turn.yaml"]
    assert self_contained(dataclasses.replace(spec, world="corridor")).world_file is None
    from_files = run_episode(spec)
    monkeypatch.delenv("ROOMBA_BT_WORLDS")  # the worker's machine has no such folder
    assert _without_wall_time([run_episode(travelling)]) == _without_wall_time([from_files])


# A worker's episode that misbehaves on purpose, set in the parent before the pool forks: the
# worker running ``seed`` kills itself with SIGKILL (``every`` time, or once: a marker file),
# or waits for the marker (made by the parent) before running it.
_HOOK: dict[str, object] = {}


def _hooked_episode(spec: EpisodeSpec):  # type: ignore[no-untyped-def]
    import os
    import signal
    import time

    mark = Path(str(_HOOK["mark"]))
    if spec.seed == _HOOK["seed"]:
        if _HOOK["what"] == "wait":
            while not mark.exists():  # a file the parent makes: no event crosses processes
                time.sleep(0.01)
        elif _HOOK["what"] == "kill-always" or (_HOOK["what"] == "kill-once" and not mark.exists()):
            mark.touch()
            os.kill(os.getpid(), signal.SIGKILL)
    if _HOOK["what"] == "kill-unless-alone" and spec.seed >= int(str(_HOOK["seed"])):
        import psutil

        parent = psutil.Process(os.getppid())  # its forked workers run its command line
        if _living_twins(parent) > 1:  # a pool of 2
            os.kill(os.getpid(), signal.SIGKILL)
    return run_episode(spec)


def _living_twins(parent: Any) -> int:
    """The parent's children that run its command line; a worker just killed is a zombie
    until the pool reaps it, and its command line cannot be read (psutil.ZombieProcess)."""
    import psutil

    count = 0
    for child in parent.children():
        try:
            count += child.cmdline() == parent.cmdline()
        except psutil.Error:
            continue
    return count


@pytest.fixture
def hooked(tmp_path: Path, monkeypatch: pytest.MonkeyPatch):  # type: ignore[no-untyped-def]
    """Sets the hook; the pool's old code hung for ever on a dead worker: 120 s, then fail."""
    import signal

    import roomba_bt.evaluate.parallel as parallel

    def hook(seed: int, what: str) -> Path:
        _HOOK.update(seed=seed, what=what, mark=str(tmp_path / "mark"))
        return tmp_path / "mark"

    def hung(signum: int, frame: object) -> None:
        raise TimeoutError("the evaluation hung")

    monkeypatch.setattr(parallel, "run_episode", _hooked_episode)
    previous = signal.signal(signal.SIGALRM, hung)
    signal.alarm(120)
    yield hook
    signal.alarm(0)
    signal.signal(signal.SIGALRM, previous)
    _HOOK.clear()


def _short_specs(runs: int = 8) -> list[EpisodeSpec]:
    return episode_specs(BUMP, world="corridor", runs=runs, seed=0,
                         params=(("duration", "2s"),), timeout_s=10)  # fmt: skip


def _ctrl_c_after(count: int, seen: list[int]) -> Callable[[int, int, EpisodeResult], None]:
    """A progress callback that notes each finished episode's seed in ``seen`` and, at the
    ``count``-th, stops the evaluation as a Ctrl-C does."""

    def progress(done: int, total: int, result: EpisodeResult) -> None:
        seen.append(result.seed)
        if len(seen) == count:
            raise KeyboardInterrupt

    return progress


def test_a_worker_killed_mid_evaluation_loses_no_episode_and_hangs_nothing(hooked) -> None:  # type: ignore[no-untyped-def]
    """A worker killed (kill -9, the OOM killer) hung the pool for ever, silently: now the
    unfinished episodes run again in new workers, counted, with the same results."""
    from roomba_bt.evaluate.parallel import Engine, evaluate

    specs = _short_specs()
    alone = run_episode  # the hook is only in the pool: --jobs 1 is the reference
    expected = _without_wall_time([alone(s) for s in specs])
    hooked(3, "kill-once")
    (done,) = evaluate([specs], Engine("local", 2))
    assert not done.interrupted
    assert _without_wall_time(done.results) == expected
    # seed 3 at least (it was running when its worker died), at most what the pool had
    # taken (2 x jobs in flight), not every episode still to run
    assert 1 <= done.retried <= 2 * 2


def test_an_episode_that_always_kills_its_worker_is_died_and_the_others_finish(
    hooked,  # type: ignore[no-untyped-def]
    capsys: pytest.CaptureFixture[str],
) -> None:
    """It ended the evaluation after three deaths (WorkersLostError: exit 130), the episodes
    queued behind it unrun. Now it runs alone, dies again, and is recorded as DIED."""
    from roomba_bt.evaluate.episode import DIED
    from roomba_bt.evaluate.parallel import LocalRun

    specs = _short_specs()
    hooked(3, "kill-always")
    results = run_episodes(specs, 2, None, LocalRun())
    assert [r.seed for r in results] == list(range(8))
    assert results[3].outcome == DIED
    assert results[3].reason == (
        "the worker running it died: killed by SIGKILL (the OOM killer? a kill -9?), twice "
        "(the second time running it alone)"
    )
    others = results[:3] + results[4:]
    assert _without_wall_time(others) == _without_wall_time(
        [run_episode(s) for s in specs if s.seed != 3]
    )
    err = capsys.readouterr().err
    assert "seed 3 killed its worker again, alone (killed by SIGKILL" in err


def test_workers_that_keep_dying_with_no_episode_to_blame_end_with_a_message(
    hooked,  # type: ignore[no-untyped-def]
    capsys: pytest.CaptureFixture[str],
) -> None:
    """Deaths that no episode repeats alone (the OOM killer under memory pressure) are
    allowed POOL_RESTARTS times; then the episodes that finished and the seeds that did not."""
    pytest.importorskip("psutil")
    from roomba_bt.evaluate.parallel import POOL_RESTARTS, LocalRun, WorkersLostError

    specs = _short_specs(12)
    hooked(3, "kill-unless-alone")
    with pytest.raises(
        WorkersLostError, match=r"with no episode to blame .*did not finish"
    ) as raised:
        run_episodes(specs, 2, None, LocalRun())
    kept = [r.seed for r in raised.value.finished]
    assert kept == sorted(kept) and {0, 1, 2} <= set(kept) and len(kept) < 12
    err = capsys.readouterr().err
    assert (
        err.count("ran alone without a death: the worker was ended from outside")
        == POOL_RESTARTS + 1
    )


def test_eval_ends_3_when_its_workers_keep_dying_with_no_episode_to_blame(
    hooked,  # type: ignore[no-untyped-def]
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """Workers killed from outside again and again (the OOM killer under memory pressure)
    ended ``eval`` 130, as a Ctrl-C, and ``--json`` said ``"interrupted": true`` alone: a
    CI job read its operator's stop. The run environment failed, not the missions and not
    the operator: exit 3, as for a Dask cluster whose workers are gone (docs/evaluation.md),
    why said in the JSON (``interrupted_by``: ``workers-lost``) and on stderr, and what
    finished written to --out."""
    import json

    from roomba_bt.cli import main
    from roomba_bt.evaluate.records import read_results

    hooked(3, "kill-unless-alone")
    out = tmp_path / "out.jsonl"
    code = main(["eval", BUMP, "-p", "duration=2s", "--world", "corridor", "--runs", "12",
                 "--timeout", "10s", "--jobs", "2", "--no-progress", "--json",
                 "--out", str(out)])  # fmt: skip
    stdout, err = capsys.readouterr()
    assert code == 3, err
    report = json.loads(stdout)
    assert (report["interrupted"], report["interrupted_by"]) == (True, "workers-lost")
    assert report["interruption"].startswith("a worker process died 3 times with no episode")
    finished = len(read_results(out))
    assert 3 <= finished < 12 and report["variants"][0]["runs"] == finished
    assert f"; {finished} of 12 episode(s) finished, summarised above" in err
    assert "Traceback" not in err


def test_results_are_taken_as_they_finish_and_a_ctrl_c_keeps_them(hooked) -> None:  # type: ignore[no-untyped-def]
    """pool.imap handed results back in seed order: episodes finished after a slow one were
    neither in the partial file nor kept by a Ctrl-C. Seed 0 waits here until three later
    episodes have reached the parent, which then stops the evaluation (as Ctrl-C does)."""
    from roomba_bt.evaluate.parallel import LocalRun

    specs = _short_specs()
    mark = hooked(0, "wait")
    seen: list[int] = []
    progress = _ctrl_c_after(3, seen)

    run = LocalRun()
    with pytest.raises(KeyboardInterrupt):
        run_episodes(specs, 2, progress, run)
    assert 0 not in seen and len(seen) == 3
    assert [r.seed for r in run.in_order()] == sorted(seen)
    mark.touch()


def test_a_ctrl_c_ends_the_pools_workers_without_a_word(
    hooked,  # type: ignore[no-untyped-def]
    capfd: pytest.CaptureFixture[str],
) -> None:
    """``roomba-bt`` raises ``Terminated`` at SIGTERM (its handler, which a forked worker
    inherits), and a Ctrl-C ends the pool with SIGTERM: a worker waiting for its next
    episode raised it there and printed its traceback under the summary. Seed 0 holds one
    worker; the other finishes seeds 1 and 2 and waits; then the parent stops (as at
    Ctrl-C) and ends both."""
    import signal

    from roomba_bt.evaluate.parallel import LocalRun
    from roomba_bt.robot.safety import raise_terminated

    specs = _short_specs(3)
    mark = hooked(0, "wait")
    seen: list[int] = []
    progress = _ctrl_c_after(2, seen)

    previous = signal.signal(signal.SIGTERM, raise_terminated)
    try:
        with pytest.raises(KeyboardInterrupt):
            run_episodes(specs, 2, progress, LocalRun())
    finally:
        signal.signal(signal.SIGTERM, previous)
        mark.touch()
    assert sorted(seen) == [1, 2]
    err = capfd.readouterr().err
    assert "Traceback" not in err and "Terminated" not in err, err


def test_a_signal_while_the_pool_starts_its_workers_comes_once_they_are_started() -> None:
    """A forked worker has its parent's handlers until its initializer: meanwhile Ctrl-C and
    SIGTERM are held, and raised in the parent, by its own handlers, once the submit is
    done (a worker not started yet ignores the Ctrl-C; the parent ends it with SIGTERM)."""
    import os
    import signal

    from roomba_bt.evaluate.parallel import _signals_held_while_workers_start

    reached = False
    with pytest.raises(KeyboardInterrupt), _signals_held_while_workers_start():
        os.kill(os.getpid(), signal.SIGINT)
        reached = True
    assert reached and signal.getsignal(signal.SIGINT) is signal.default_int_handler


_BOOM = """\
from roomba_bt.behaviours import Condition, declare


@declare("boom", kind="condition", reads=(27,))
class Boom(Condition):
    \"\"\"Raises.\"\"\"

    def check(self, snapshot):
        raise RuntimeError("kaboom")
"""


@pytest.mark.parametrize(
    ("tree", "outcome", "stage"),
    [
        # a behaviour that raised: the node its path ends in (the stage was empty)
        ("    - boom\n", "error", "boom"),
        # a timeout decorator: the leaf it stopped (empty: "timeout: timed out after 1 s")
        ("    - timeout:\n        after: 1s\n        do: {drive: {velocity: 50 mm/s, "
         "distance: 5 m}}\n", "failure", "drive"),
        # a while guard: the leaf it stopped
        ("    - drive: {velocity: 100 mm/s, distance: 5 m}\n"
         "      while: {inverter: {odometry: {distance: 5 cm}}}\n", "failure", "drive"),
        # a leaf without parameters that failed: its name is its reason, and its stage
        ("    - charging\n", "failure", "charging"),
    ],
)  # fmt: skip
def test_the_stage_names_the_node_of_an_error_or_a_decorator_failure(
    tmp_path: Path, tree: str, outcome: str, stage: str
) -> None:
    from roomba_bt.mission import Permissions

    (tmp_path / "boom.py").write_text(_BOOM)
    mission = tmp_path / "m.yaml"
    mission.write_text(f"plugins: [./boom.py]\ntree:\n  sequence:\n    - mode: safe\n{tree}")
    spec = EpisodeSpec(str(mission), seed=1, timeout_s=3.0,
                       permissions=Permissions(plugin_files=True))  # fmt: skip
    result = run_episode(spec)
    assert (result.outcome, result.stage) == (outcome, stage), result.reason


def test_the_dock_missions_timeout_names_its_stage_not_its_time_limit() -> None:
    """The shipped dock mission runs its stages in a parallel beside ``dock_time_limit``,
    a timer RUNNING until its 10 minutes are up. The run's ``--timeout`` (3 s here, the
    search still turning) ran out "in dock_time_limit", the timer, for every episode: a
    1000-episode sweep's failures read ``261  TIMEOUT: --timeout 1 min of mission time ran
    out in dock_time_limit``, no stage. Now the stage the robot was in is named, as a
    ``wait`` beside ``cover`` leaves ``cover`` named."""
    spec = EpisodeSpec(str(MISSIONS / "dock.yaml"), "apartment", seed=3, timeout_s=3.0)
    result = run_episode(spec)
    assert (result.outcome, result.stage) == ("timeout", "dock_search"), result.reason
    assert result.reason.endswith("ran out in dock_search")


def test_a_sweep_s_results_are_kept_small_in_the_process_that_gathers_them() -> None:
    """The parent of a sweep keeps every result until its report: it held about 3 KB an
    episode (300 MB at 100 000 episodes), mostly each result's ``__dict__`` and its own copy
    of the same words (mission, world, outcome, reason, worker...) unpickled from its worker.
    Results arrive from the pool as pickles; 2 000 of them, as the pool hands them over, are
    now kept in about 0.96 KB each (2.66 KB before, on CPython 3.11), their words shared."""
    import pickle
    import tracemalloc

    spec = episode_specs(BUMP, runs=1, params=(("duration", "1s"),), trace_every=0)[0]
    result = run_episode(spec)  # as eval runs one without --plot: no trajectory
    arriving = [
        pickle.dumps(dataclasses.replace(result, seed=s, time_s=s / 7)) for s in range(2000)
    ]
    tracemalloc.start()
    try:
        before = tracemalloc.get_traced_memory()[0]
        kept = [pickle.loads(one) for one in arriving]
        per_result = (tracemalloc.get_traced_memory()[0] - before) / len(kept)
    finally:
        tracemalloc.stop()
    assert per_result < 1300, per_result  # 2 660 B before
    assert not hasattr(kept[0], "__dict__")
    assert kept[0].reason is kept[1].reason and kept[0].mission is kept[1].mission
    assert kept[0] == dataclasses.replace(result, seed=0, time_s=0.0)


def test_results_from_worker_processes_share_their_words() -> None:
    """The pool's results are unpickled as they arrive, each text shared with the results
    before it: a word held once, not once an episode."""
    results = run_episodes(_short_specs(4), jobs=2)
    assert len({id(r.mission) for r in results}) == 1
    assert len({id(r.world) for r in results}) == 1
    assert len({id(r.outcome) for r in results}) == 1


@pytest.mark.extra("plot")
def test_eval_plot_s_results_hold_their_paths_as_drawn_made_in_the_workers(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """``eval --plot`` kept every trace point of every episode (one each 8 steps, about
    100 KB an apartment dock episode) in its parent until the end, where the plot and the
    records drew a few hundred of them: a 2 000-episode sweep held 200 MB for its picture.
    The episodes run for a plot keep their path as drawn (``simplify_path``), in the worker."""
    import roomba_bt.cli.eval_cmd as eval_cmd
    from roomba_bt.cli import main
    from roomba_bt.evaluate.records import kept_path

    held: list[EpisodeResult] = []
    statistics = eval_cmd.statistics

    def noted(args: Any, chosen: Any, done: Any, world: str) -> Any:
        held.extend(r for e in done for r in e.results)
        return statistics(args, chosen, done, world)

    monkeypatch.setattr(eval_cmd, "statistics", noted)
    argv = ["eval", "dock", "--within", "1", "--timeout", "20s", "--runs", "2", "--jobs", "2",
            "--no-progress", "--plot", str(tmp_path / "p.png")]  # fmt: skip
    main(argv)
    assert len(held) == 2 and all(len(r.trajectory) > 2 for r in held)
    assert all(r.trajectory == kept_path(r.trajectory) for r in held)
    spec = EpisodeSpec("dock", seed=0, timeout_s=20.0, within_m=1.0, time_limit="--timeout 20 s")
    raw = run_episode(spec)  # the same episode, every point
    assert held[0].outcome == raw.outcome and held[0].time_s == raw.time_s
    assert len(held[0].trajectory) < len(raw.trajectory) / 3  # the same episode, every point
