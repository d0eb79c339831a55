"""The slowest tick's behaviour, named in the summary (runtime/tick_watch.py): a plugin's
``update()`` that blocks (``time.sleep``) showed under ``run --fast`` only as ``slowest 503.89
ms``, and the plugin's author, who tests there, could not tell which leaf it was.

End to end the plugin blocks on a pipe until the watch has seen it blocked for half a second
(twenty looks), and is let go right after that look: the tick ends a wake-up after the
watch's last look inside it, and began at most a look before the first. A fixed
``time.sleep(0.5)`` flaked under load: its tick began before the watch thread's first look,
and the run ended two ticks after it, before another look, so each end was a look short, and
a late look on top of that went past the slack ("slowest 5xx ms", no behaviour named). The
slack was three looks (75 ms) however late the looks came, and the pipe's wait left 46-74 ms
of it used with two busy loops beside the run; it is now what the looks around the tick
could not see, measured from their own times (the watch's looks come late under load, the
slack with them)."""

from __future__ import annotations

import os
import threading
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest
from quoted import assert_quoted  # tests/quoted.py: the docs' quotes

from roomba_bt.cli import main
from roomba_bt.mission import Permissions
from roomba_bt.runtime.summary import ExitCode, RunSummary
from roomba_bt.runtime.tick_watch import SlowTickWatch

from .simrun import RunMission, write_mission

#: the plugin, its first tick blocked by ``{blocks}``
PLUGIN = '''
import os
import time

from py_trees.common import Status

from roomba_bt.behaviours import Action, declare


@declare("sleepy", kind="action")
class Sleepy(Action):
    """Blocks its first tick (half a second, or until the test lets it go), then runs two
    ticks more."""

    def initialise(self):
        self.ticks = 0

    def update(self):
        self.ticks += 1
        if self.ticks == 1:
            {blocks}
        return Status.SUCCESS if self.ticks >= 3 else Status.RUNNING
'''

MISSION = "plugins: [./sleepy.py]\ntree:\n  sequence: [{mode: safe}, {wait: 100ms}, sleepy]\n"


@pytest.fixture
def mission(tmp_path: Path) -> Path:
    """The mission whose plugin sleeps half a second."""
    return write_mission(
        tmp_path, MISSION, "m.yaml", {"sleepy.py": PLUGIN.format(blocks="time.sleep(0.5)")}
    )


class HeldPipe:
    """The pipe the plugin of :func:`watched_mission` blocks reading: its other end is
    closed (the read returns) right after the look at which the watch has seen it inside
    for 0.5 s, or after a minute if no look ever does (the test fails, it does not hang).
    :meth:`again` holds the next run's read as this one's, at the same descriptor (the
    plugin's text, and so the mission's files, unchanged)."""

    def __init__(self) -> None:
        self.read_end, write_end = os.pipe()
        self._open = [write_end]
        self._lock = threading.Lock()
        self._last_resort = threading.Timer(60.0, self.release)
        self._last_resort.start()

    def release(self) -> None:
        with self._lock:
            if self._open:
                os.close(self._open.pop())

    def again(self) -> None:
        self.release()
        fresh, write_end = os.pipe()
        os.dup2(fresh, self.read_end)
        os.close(fresh)
        with self._lock:
            self._open.append(write_end)

    def close(self) -> None:
        self._last_resort.cancel()
        self.release()
        os.close(self.read_end)


@pytest.fixture
def held_pipe(monkeypatch: pytest.MonkeyPatch) -> Iterator[HeldPipe]:
    """A :class:`HeldPipe`, let go by the watch's look that has seen a tick 0.5 s long."""
    pipe = HeldPipe()
    look = SlowTickWatch.look

    def look_then_release(watch: SlowTickWatch, ticks: int, where_now: Callable[[], str]) -> None:
        look(watch, ticks, where_now)
        if watch.longest_s >= 0.5:
            pipe.release()

    monkeypatch.setattr(SlowTickWatch, "look", look_then_release)
    yield pipe
    pipe.close()


@pytest.fixture
def watched_mission(tmp_path: Path, held_pipe: HeldPipe) -> Path:
    """The mission whose plugin blocks reading :func:`held_pipe`'s pipe."""
    plugin = PLUGIN.format(blocks=f"os.read({held_pipe.read_end}, 1)")
    return write_mission(tmp_path, MISSION, "m.yaml", {"sleepy.py": plugin})


def test_run_fast_names_the_behaviour_of_its_slowest_tick(
    watched_mission: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """On the virtual clock there is no tick guard; the ticks line names the leaf all the
    same, as the guard would: the behaviour, its method and the line it was blocked at."""
    argv = ["run", str(watched_mission), "--fast", "--display", "none", "--allow-plugin-files"]
    assert main(argv) == ExitCode.OK
    out = capsys.readouterr().out
    ticks = next(line for line in out.splitlines() if line.startswith("ticks "))
    plugin = watched_mission.parent / "sleepy.py"
    assert " ms in sleepy (Sleepy.update at " in ticks, ticks
    assert f"{plugin}:21)" in ticks, ticks  # the line it blocked at


def test_a_program_s_run_starts_no_watch_unless_asked(
    run_mission: RunMission, mission: Path
) -> None:
    """A program's runs start no watch thread: ``roomba-bt run`` sets ``names_slow_ticks``
    (and an evaluation's episode starts a dormant one: the tests below)."""
    run = run_mission(MISSION, permissions=Permissions(plugin_files=True), timeout=10.0)
    assert run.summary.max_tick_s > 0.4
    assert getattr(run.summary, "slowest_in", "") == ""


def test_only_a_slow_tick_is_named() -> None:
    """The ticks line names a behaviour only for a slowest tick over the 15 ms slot, and the
    watch only one whose stretch inside a behaviour was about as long as the slowest tick."""
    from roomba_bt.runtime.tick_watch import SlowTickWatch  # here: the tests above run on old code

    summary = RunSummary("m", ticks=3, max_tick_s=0.010, slowest_in="w (W.update at w.py:3)")
    assert "slowest 10.00 ms)" in str(summary)
    summary.max_tick_s = 0.5
    assert "slowest 500.00 ms in w (W.update at w.py:3))" in str(summary)
    watch = SlowTickWatch(summary, look_every_s=0.025)
    watch.longest_s, watch.where = 0.45, "w (W.update at w.py:3)"
    assert watch.culprit() == "w (W.update at w.py:3)"
    watch.longest_s = 0.2  # another, shorter tick's: not the slowest one
    assert watch.culprit() == ""


class FakeThread:
    """The ticking thread's clocks as a test sets them: the wall clock, and the seconds on a
    CPU and waiting for one (a loaded host's run queue) that :func:`thread_times` reads."""

    def __init__(self) -> None:
        self.now = 100.0
        self.on_cpu = 5.0
        self.waiting = 1.0
        self.reads = 0

    def times(self) -> tuple[float, float]:
        self.reads += 1
        return self.on_cpu, self.waiting

    def run(self, seconds: float, cpu_share: float, waiting_share: float) -> None:
        self.now += seconds
        self.on_cpu += seconds * cpu_share
        self.waiting += seconds * waiting_share


def _watched_tick(cpu_share: float, waiting_share: float) -> SlowTickWatch:
    """Two short ticks, then one that lasts 125 ms (five looks of 25 ms) inside wall_follow,
    the thread's time spent as the shares say, then short ones again."""
    thread = FakeThread()
    summary = RunSummary("m", max_tick_s=0.001)
    watch = SlowTickWatch(summary, 0.025, clock=lambda: thread.now, times=thread.times)
    where = "wall_follow (WallFollow.update at wall.py:192)"
    for ticks in (1, 2):  # short ticks: the times read at each look that finds new ones
        thread.run(0.025, 1.0, 0.0)
        watch.look(ticks, lambda: where)
    for _ in range(5):  # the slow one: still running at each look, nothing more read
        thread.run(0.025, cpu_share, waiting_share)
        watch.look(2, lambda: where)
    assert thread.reads == 2
    summary.max_tick_s = 0.125  # the loop's measure, once it ended
    thread.run(0.025, 1.0, 0.0)  # the next ticks, short and computing, as --fast's are
    watch.look(3, lambda: where)
    summary.slowest_in, summary.slowest_host_busy = watch.culprit(), watch.host_kept_it()
    return watch


def test_a_tick_the_host_kept_from_running_is_said_so_not_blamed_on_its_behaviour() -> None:
    """The soak's loaded host (load 6 to 8 on 2 cores): "slowest 126.74 ms in wall_follow
    ... wall.py:192", a leaf that computes in a millisecond; the thread was waiting for a
    CPU. Its times over the looks around the tick say so."""
    watch = _watched_tick(cpu_share=0.05, waiting_share=0.9)
    assert watch.culprit() == ""
    said = "31.25 ms of CPU in 150.00 ms, 112.50 ms of it waiting for a CPU"
    assert watch.host_kept_it() == said
    assert f"slowest 125.00 ms: the host was busy ({said}))" in str(watch.summary)
    assert "wall_follow" not in str(watch.summary)
    assert_quoted("docs/runtime.md", "ticks 8001 (", str(watch.summary), numbers=True)


def test_a_wait_counted_from_before_the_window_never_says_more_than_its_time() -> None:
    """The kernel counts a wait when the thread gets its CPU, so a wait that began before
    the looks' window is counted in it: a watcher saw "0.46 ms of CPU in 25.13 ms, 29.96 ms
    of it waiting for a CPU". The time said holds what it says was spent in it."""
    watch = _watched_tick(cpu_share=0.02, waiting_share=1.4)
    said = watch.host_kept_it()
    cpu, _, rest = said.partition(" ms of CPU in ")
    window, _, rest = rest.partition(" ms, ")
    waiting = rest.partition(" ms")[0]
    assert float(cpu) + float(waiting) <= float(window) + 0.01, said
    assert said == "27.50 ms of CPU in 202.50 ms, 175.00 ms of it waiting for a CPU"


@pytest.mark.parametrize(
    ("cpu_share", "waiting_share"), [(0.95, 0.0), (0.0, 0.0), (0.6, 0.4)],
    ids=["computed", "blocked (time.sleep)", "computed, some waiting"],
)  # fmt: skip
def test_a_tick_its_behaviour_spent_is_named_as_before(
    cpu_share: float, waiting_share: float
) -> None:
    """A behaviour that computes has the CPU; one that blocks (the sleepy plugin above, I/O,
    a lock) has none but waits for none either: both are the behaviour's to answer for."""
    watch = _watched_tick(cpu_share, waiting_share)
    assert watch.host_kept_it() == ""
    assert "slowest 125.00 ms in wall_follow (WallFollow.update at wall.py:192))" in str(
        watch.summary
    )


def test_a_slow_tick_no_look_saw_running_is_judged_by_the_looks_around_it() -> None:
    """On a loaded host the watch's own thread waits for a CPU too: its looks come late, and
    the slowest tick may run and end between two of them. The times read at both still say
    whose it was; a later, slower tick the host did not keep is named by nobody's verdict."""
    thread = FakeThread()
    summary = RunSummary("m", max_tick_s=0.001)
    watch = SlowTickWatch(summary, 0.025, clock=lambda: thread.now, times=thread.times)
    watch.look(10, str)
    thread.run(0.3, 0.2, 0.75)  # a 164 ms tick among short ones, the process mostly waiting
    summary.max_tick_s = 0.164
    watch.look(20, str)
    assert watch.host_kept_it() == "60.00 ms of CPU in 300.00 ms, 225.00 ms of it waiting for a CPU"
    thread.run(0.3, 0.0, 0.0)  # a later, slower one: blocked, not waiting (a sleep)
    summary.max_tick_s = 0.25
    watch.close()  # the run ended before the next look
    assert watch.host_kept_it() == ""


@pytest.mark.parametrize(
    ("gap_before", "gap_after", "named"),
    [(0.100, 0.090, True), (0.025, 0.025, False)],
    ids=["its looks came late: named", "looks on time: a slower tick no look saw"],
)  # fmt: skip
def test_what_the_looks_did_not_see_of_a_tick_is_measured_not_a_fixed_three_looks(
    gap_before: float, gap_after: float, named: bool
) -> None:
    """A tick blocked half a second, seen inside its behaviour by twenty looks, the loop's
    measure of it 670 ms. On a loaded host the watch's own looks came late around it (the one
    before its first look inside 100 ms after its predecessor, the one after its end 90 ms
    after its last): it began and ended in those gaps, and is named (three looks of slack,
    75 ms, left it unnamed). Looks on time could not have missed 170 ms of it: a 670 ms
    slowest tick was another, and this one is not called that."""
    thread = FakeThread()
    summary = RunSummary("m", max_tick_s=0.001)
    watch = SlowTickWatch(summary, 0.025, clock=lambda: thread.now, times=thread.times)
    where = "sleepy (Sleepy.update at sleepy.py:21)"
    thread.run(0.025, 1.0, 0.0)
    watch.look(1, lambda: where)
    thread.run(gap_before, 1.0, 0.0)  # short ticks, then the blocked one begins
    watch.look(2, lambda: where)
    for _ in range(20):  # blocked (a read): no CPU, no wait for one
        thread.run(0.025, 0.0, 0.0)
        watch.look(2, lambda: where)
    assert watch.longest_s == pytest.approx(0.5)
    thread.run(gap_after, 0.0, 0.0)
    summary.max_tick_s = 0.670  # the loop's measure, once it ended
    watch.look(3, lambda: where)
    watch.close()
    assert watch.culprit() == (where if named else "")


def test_without_the_thread_s_times_every_slow_tick_is_named_as_before() -> None:
    summary = RunSummary("m", max_tick_s=0.1)
    clock = iter(0.025 * n for n in range(10))
    watch = SlowTickWatch(summary, 0.025, clock=lambda: next(clock), times=lambda: None)
    for _ in range(5):
        watch.look(1, lambda: "w (W.update at w.py:3)")
    assert (watch.culprit(), watch.host_busy) == ("w (W.update at w.py:3)", "")


def test_the_thread_s_times_are_read_from_the_kernel_where_it_keeps_them() -> None:
    """Linux's schedstat of the calling thread: its time on a CPU grows as it computes."""
    from roomba_bt.runtime.tick_watch import SchedStat

    stats = SchedStat(threading.get_native_id())
    before = stats.read()
    if before is None:
        pytest.skip("no /proc/self/task/TID/schedstat here")
    after = before
    for _ in range(1000):  # the kernel adds a running thread's time up at its clock's ticks
        sum(range(100_000))
        after = stats.read()
        if after is not None and after[0] > before[0]:
            break
    stats.close()
    assert after is not None and after[0] > before[0] and after[1] >= before[1]
    assert stats.read() is None  # closed
    assert SchedStat(-1).read() is None


def _a_second_a_tick(
    caplog: pytest.LogCaptureFixture, virtual_clock: bool, seconds: float, per_tick: float
) -> list[str]:
    """A run whose every tick blocks ``per_tick`` wall seconds inside a behaviour, watched
    for ``seconds`` of wall time: what the watch warned."""
    thread = FakeThread()
    summary = RunSummary("m", virtual_clock=virtual_clock)
    watch = SlowTickWatch(summary, 0.025, clock=lambda: thread.now, times=thread.times)
    where = "hang (Hang.update at x.py:9)"
    caplog.set_level("WARNING", logger="roomba_bt.runtime.tick_watch")
    ticks = 0
    while thread.now - 100.0 < seconds:
        ticks += 1
        watch.look(ticks, lambda: where)  # a new tick, then looks inside it
        for _ in range(max(1, round(per_tick / 0.025)) - 1):
            thread.run(0.025, 0.0, 0.0)  # blocked: no CPU, no wait for one
            watch.look(ticks, lambda: where)
        thread.run(0.025, 0.0, 0.0)
    return [r.getMessage() for r in caplog.records]


def test_a_fast_run_slower_than_a_robot_is_said_once_naming_the_behaviour(
    caplog: pytest.LogCaptureFixture,
) -> None:
    """A plugin's ``time.sleep(1)`` a tick made a 2 s ``timeout`` under ``--fast`` take some
    130 s of wall time, mission time moving 15 ms a tick, with nothing said until the
    summary: a plugin author's first run looked hung. The watch says it once, off the tick
    path, naming the behaviour and what --fast's mission time is."""
    said = _a_second_a_tick(caplog, virtual_clock=True, seconds=10.0, per_tick=1.0)
    assert len(said) == 1, said
    assert said[0].startswith(
        "run --fast: behaviours have held the ticks 2.0 s of wall time for 0.04 s of mission "
        "time (44x slower than a robot), now hang (Hang.update at x.py:9): --fast ticks the "
        "tree as fast as it allows and mission time is the frames ticked (15 ms each)"
    ), said
    assert said[0].endswith("the run is not hung")


@pytest.mark.parametrize(
    ("virtual_clock", "per_tick"),
    [(False, 1.0), (True, 0.01)],
    ids=["on the wall clock", "a fast run faster than a robot"],
)
def test_no_run_that_keeps_up_or_is_on_the_wall_clock_is_warned(
    caplog: pytest.LogCaptureFixture, virtual_clock: bool, per_tick: float
) -> None:
    """On the wall clock a blocked tick is the tick guard's and the summary's; a --fast run
    that keeps ahead of a robot's time says nothing, however long."""
    assert _a_second_a_tick(caplog, virtual_clock, seconds=10.0, per_tick=per_tick) == []


def test_a_fast_run_paused_by_its_monitor_is_not_said_slow(
    caplog: pytest.LogCaptureFixture,
) -> None:
    """A ``run --fast --monitor`` paused for a minute waits in the runtime's own code: only
    the time the looks find the ticks inside a behaviour counts, so its first slowish tick
    after the resume is not said to hold a run that kept ahead of a robot."""
    thread = FakeThread()
    summary = RunSummary("m", virtual_clock=True)
    watch = SlowTickWatch(summary, 0.025, clock=lambda: thread.now, times=thread.times)
    caplog.set_level("WARNING", logger="roomba_bt.runtime.tick_watch")
    watch.look(500, lambda: "")
    for _ in range(2400):  # paused: the loop waits on the monitor's gate, in no behaviour
        thread.run(0.025, 0.0, 0.0)
        watch.look(500, lambda: "")
    for _ in range(10):  # resumed: a tick of a quarter of a second in cover
        thread.run(0.025, 1.0, 0.0)
        watch.look(501, lambda: "cover (Cover.update at coverage_map.py:700)")
    assert watch.held_s == pytest.approx(0.225)  # its first look found a new tick
    assert not caplog.records


def test_eval_names_the_behaviour_that_held_its_episode_s_ticks(
    watched_mission: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``eval`` started no watch: a plugin blocked in its ``update`` was said only by
    ``--wall-limit``'s HUNG. Its dormant watch wakes once the episode goes slower than the
    wall clock, the tick already blocked, and the report names the behaviour once, as
    ``run``'s ticks line does. In this process (``--wall-limit none``): the fixture's pipe.
    ``--out``'s records hold it too (``slowest_tick_in``), so ``eval --from`` says it again:
    it said nothing, the records a sweep is read from afterwards without it."""
    out_file = watched_mission.parent / "results.jsonl"
    argv = ["eval", str(watched_mission), "--runs", "1", "--allow-plugin-files",
            "--no-progress", "--wall-limit", "none", "--out", str(out_file)]  # fmt: skip
    assert main(argv) == ExitCode.OK
    plugin = watched_mission.parent / "sleepy.py"
    said = f" ms in sleepy (Sleepy.update at {plugin}:21), in 1 of 1 episodes: a behaviour "
    for again in (False, True):
        if again:
            assert main(["eval", "--from", str(out_file)]) == ExitCode.OK
        out = capsys.readouterr().out
        warnings = [line for line in out.splitlines() if line.startswith("warning ")]
        assert len(warnings) == 1, out
        assert warnings[0].startswith("warning      slowest tick "), out
        assert said in warnings[0], out


@pytest.mark.parametrize("report", ["text", "json"])
def test_eval_reproducible_says_the_slow_tick_on_stderr_its_report_the_same_bytes(
    watched_mission: Path, held_pipe: HeldPipe, report: str, capsys: pytest.CaptureFixture[str]
) -> None:
    """``--reproducible``'s report is byte-stable across runs (docs/evaluation.md): its
    ``slowest tick 2000.16 ms in sleepy ...`` warning was the host's milliseconds (the next
    run said 2000.15), and whether a tick is found slow at all is the host's too (the watch
    looks on the wall clock). The report leaves it out (``--json``'s ``slow_ticks`` null, as
    its ``wall_time``); stderr says it, as the report does without the option."""
    argv = ["eval", str(watched_mission), "--runs", "1", "--allow-plugin-files",
            "--no-progress", "--wall-limit", "none", "--reproducible",
            *(["--json"] if report == "json" else [])]  # fmt: skip
    outs = []
    for again in (False, True):
        if again:
            held_pipe.again()
        assert main(argv) == ExitCode.OK
        out, err = capsys.readouterr()
        outs.append(out)
        slow = [line for line in err.splitlines() if "slowest tick" in line]
        assert len(slow) == 1 and slow[0].startswith("roomba-bt eval: warning: slowest tick "), err
        assert " ms in sleepy (Sleepy.update at " in slow[0], err
        assert_quoted("docs/evaluation.md", "roomba-bt eval: warning: slowest tick", err, True)
    assert outs[0] == outs[1]
    assert "slowest" not in outs[0] and "Sleepy.update" not in outs[0], outs[0]
    if report == "json":
        assert '"slow_ticks": null' in outs[0], outs[0]


def _dormant(thread: FakeThread) -> SlowTickWatch:
    summary = RunSummary("m", max_tick_s=0.001)
    return SlowTickWatch(
        summary, 0.025, clock=lambda: thread.now, times=thread.times, dormant_s=0.5
    )


def test_a_dormant_watch_stays_asleep_while_the_episode_outruns_the_wall_clock() -> None:
    """An evaluation's episode runs hundreds of times faster than a robot: its watch reads
    the tick count twice a second and never looks closer (the tick path is run's, and an
    episode at its usual pace pays two wakes a second of another thread)."""
    thread = FakeThread()
    watch = _dormant(thread)
    ticks = 0
    assert not watch.wakes(ticks)  # read as it was made: no time, no tick
    for _ in range(10):
        thread.run(0.5, 1.0, 0.0)
        ticks += 3000  # 45 s of mission time in half a second
        assert not watch.wakes(ticks)
    thread.run(0.5, 1.0, 0.0)
    ticks += 34  # 0.51 s of mission time in 0.5 s: as fast as a robot, still not slower
    assert not watch.wakes(ticks)


def test_a_dormant_watch_wakes_into_a_long_tick_and_still_judges_it_whole() -> None:
    """A tick blocked 1.3 s: the read after its start still finds ticks added (it began
    between two reads), the next finds none and wakes the watch 0.7 s into the tick. The
    looks from there see 0.6 s of it; what no look saw (from the read before the count last
    changed) is counted as unseen, so the tick is named, as a watch awake all along would."""
    thread = FakeThread()
    watch = _dormant(thread)
    where = "sleepy (Sleepy.update at sleepy.py:21)"
    watch.wakes(0)
    thread.run(0.5, 1.0, 0.0)
    assert not watch.wakes(2000)
    thread.run(0.5, 1.0, 0.0)  # 200 more ticks in 0.2 s, then the blocked one begins
    assert not watch.wakes(2200)
    thread.run(0.5, 0.0, 0.0)
    assert watch.wakes(2200)  # none in half a second: slower than a robot
    for _ in range(24):
        thread.run(0.025, 0.0, 0.0)
        watch.look(2200, lambda: where)
    thread.run(0.025, 0.0, 0.0)
    watch.summary.max_tick_s = 1.3  # the loop's measure, once it ended
    watch.look(2201, lambda: where)
    watch.close()
    assert watch.longest_s == pytest.approx(0.6)
    assert watch.culprit() == where


def test_a_tick_a_dormant_watch_woke_into_is_judged_by_its_own_window() -> None:
    """``eval`` of a plugin that slept 2 s in one tick named it in 1 of 3 episodes: the
    watch woke inside the tick, no look had read the thread's times before it, so the tick
    was judged at the run's end by the 3 ms after it (the episode's last ticks, the thread
    waiting for a CPU there: "the host was busy (0.34 ms of CPU in 2.94 ms, ...)"), and its
    behaviour went unnamed. The times read at the wake are the window's start: the 2 s tick
    was a sleep, not a busy host."""
    thread = FakeThread()
    watch = _dormant(thread)
    where = "blocker (Blocker.update at blocker.py:23)"
    watch.wakes(0)
    thread.run(0.5, 1.0, 0.0)
    assert not watch.wakes(68)  # 68 ticks in a few ms, then the blocked one (from t=0.01)
    thread.run(0.5, 0.0, 0.0)
    assert watch.wakes(68)
    for _ in range(40):
        thread.run(0.025, 0.0, 0.0)
        watch.look(68, lambda: where)
    thread.run(0.02, 0.0, 0.0)
    watch.summary.max_tick_s = 2.0  # the loop's measure, once it ended
    watch.look(69, lambda: where)
    thread.run(0.003, 0.1, 0.9)  # the last ticks: the thread waits for a CPU, the run ends
    watch.close()
    assert watch.host_kept_it() == ""
    assert watch.culprit() == where
