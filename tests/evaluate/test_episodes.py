"""Episodes: seeded, measured on the simulator, the same in any number of processes."""

from __future__ import annotations

import dataclasses
import io
from pathlib import Path

import pytest

from roomba_bt.evaluate import EpisodeSpec, EvaluationError, episode_specs, run_episode
from roomba_bt.evaluate.episode import build_world, start_pose
from roomba_bt.evaluate.parallel import ProgressBar, run_episodes
from roomba_bt.evaluate.testing import assert_success_rate

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


class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_the_bar_redraws_on_a_terminal_and_writes_each_tenth_into_a_log() -> None:
    """A CI log got a carriage-return redraw per episode."""
    result = run_episode(episode_specs(BUMP, runs=1, params=(("duration", "1s"),))[0])
    log, terminal = io.StringIO(), _Terminal()
    for stream in (log, terminal):
        bar = ProgressBar(stream, width=10)
        for done in range(1, 51):
            bar(done, 50, result)
    lines = log.getvalue().splitlines()
    assert "\r" not in log.getvalue() and len(lines) == 11  # the first, then each tenth
    assert [line.split()[1] for line in lines[:3]] == ["1/50", "5/50", "10/50"]
    assert terminal.getvalue().count("\r") == 50 and terminal.getvalue().count("\n") == 1


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
