"""Statistics of a batch of episodes."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import pytest

from roomba_bt.evaluate.episode import EpisodeResult
from roomba_bt.evaluate.stats import (
    Z95,
    mcnemar_exact,
    percentile,
    reason_group,
    summarize,
    wilson_interval,
)


def result(seed: int, outcome: str = "success", time_s: float = 10.0, reason: str = "",
           bumps: int = 0, docked: bool = False) -> EpisodeResult:  # fmt: skip
    return EpisodeResult(
        seed=seed, outcome=outcome, reason=reason, time_s=time_s, wall_s=0.1, ticks=1,
        start=(0.0, 0.0, 0.0), end=(0.0, 0.0, 0.0), bumps=bumps, contact_steps=(),
        docked=docked, charging=docked, cliffs=0, fell=False, violations=0, loops=0.0,
        longest_stall_s=0.0,
    )  # fmt: skip


@pytest.mark.parametrize(
    ("successes", "runs", "lo", "hi"),
    [
        (0, 10, 0.0, 0.2775),
        (10, 10, 0.7225, 1.0),
        (200, 200, 0.9812, 1.0),
        (196, 200, 0.9497, 0.9922),
        (5, 10, 0.2366, 0.7634),
    ],
)
def test_wilson_interval_matches_published_values(
    successes: int, runs: int, lo: float, hi: float
) -> None:
    got_lo, got_hi = wilson_interval(successes, runs)
    assert got_lo == pytest.approx(lo, abs=5e-4)
    assert got_hi == pytest.approx(hi, abs=5e-4)


def test_wilson_interval_refuses_impossible_counts() -> None:
    with pytest.raises(ValueError, match=r"0\.\.10"):
        wilson_interval(11, 10)
    assert wilson_interval(0, 0) == (0.0, 1.0)


def test_percentiles_interpolate_between_ranks() -> None:
    values = [10.0, 20.0, 30.0, 40.0]
    assert percentile(values, 50) == 25.0
    assert percentile(values, 90) == pytest.approx(37.0)
    assert percentile(values, 0) == 10.0
    assert percentile(values, 100) == 40.0
    assert percentile([], 50) is None


def test_reasons_group_without_leaf_parameters() -> None:
    a = result(1, "failure", reason="dock_time_limit(300 s): search: gave up")
    b = result(2, "failure", reason="dock_time_limit(600 s): search: gave up")
    c = result(3, "timeout", reason="--timeout 60 s of mission time ran out")
    assert reason_group(a) == reason_group(b) == "search: gave up"
    assert reason_group(c) == "TIMEOUT: --timeout 60 s of mission time ran out"


def test_summary_counts_rates_times_and_failures() -> None:
    results = [result(i, time_s=float(i), bumps=2, docked=True) for i in range(1, 9)]
    results += [result(9, "failure", reason="x(1): approach: lost"),
                result(10, "failure", reason="x(2): approach: lost")]  # fmt: skip
    summary = summarize("m.yaml", "room", results)
    assert (summary.successes, summary.runs, summary.docked) == (8, 10, 8)
    assert summary.rate == 0.8
    assert summary.median_time_s == 4.5
    assert summary.failures == (("approach: lost", 2),)
    assert summary.mean_bumps == pytest.approx(1.6)  # 8 episodes with 2, 2 with none
    text = str(summary)
    assert "8/10 = 80.0 %" in text and "Wilson" in text and "approach: lost" in text


def test_exact_mcnemar_is_the_binomial_test_of_the_discordant_pairs() -> None:
    from roomba_bt.evaluate.stats import mcnemar_exact

    assert mcnemar_exact(0, 0) == 1.0
    assert mcnemar_exact(3, 3) == 1.0
    # 0 of 6 discordant pairs for A: 2 * (1/2)^6
    assert mcnemar_exact(0, 6) == pytest.approx(2 / 64)
    # 1 of 10: 2 * (1 + 10) / 1024 (scipy.stats.binomtest(1, 10).pvalue)
    assert mcnemar_exact(1, 10 - 1) == pytest.approx(0.021484375)
    assert mcnemar_exact(9, 1) == mcnemar_exact(1, 9)


def test_median_interval_uses_the_binomial_order_statistics() -> None:
    from roomba_bt.evaluate.stats import median_interval

    assert median_interval([1.0, 2.0, 3.0, 4.0, 5.0]) is None  # 2/32 > 5 %
    assert median_interval([float(v) for v in range(6)]) == (0.0, 5.0)  # 2/64 <= 5 %
    # n = 20: k = 6 (2 P(Bin(20, 1/2) <= 5) = 0.041; k = 7 gives 0.115)
    assert median_interval([float(v) for v in range(20)]) == (5.0, 14.0)


def _log_binomial_cdf(k: int, n: int) -> float:
    """log P(Bin(n, 1/2) <= k) in floats (lgamma and a log-sum-exp): an independent check
    of the integer sums, with no 2**n anywhere."""
    import math

    logs = [math.lgamma(n + 1) - math.lgamma(i + 1) - math.lgamma(n - i + 1) for i in range(k + 1)]
    top = max(logs)
    return top + math.log(sum(math.exp(v - top) for v in logs)) - n * math.log(2)


@pytest.mark.parametrize(("only_a", "only_b"), [(600, 500), (2600, 2400), (2500, 2500), (1024, 0)])
def test_exact_mcnemar_holds_for_thousands_of_discordant_pairs(only_a: int, only_b: int) -> None:
    """``float(2**n)`` overflowed from 1024 discordant pairs: an A/B sweep of 1000 episodes
    with 1100 discordant ones ended in OverflowError instead of its report."""
    import math

    from roomba_bt.evaluate.stats import mcnemar_exact

    n, k = only_a + only_b, min(only_a, only_b)
    expected = min(1.0, 2 * math.exp(_log_binomial_cdf(k, n)))
    assert mcnemar_exact(only_a, only_b) == pytest.approx(expected, rel=1e-9, abs=1e-300)
    if (only_a, only_b) == (600, 500):  # the normal approximation agrees roughly: p ~ 0.0028
        z = (k + 0.5 - n / 2) / math.sqrt(n / 4)
        assert mcnemar_exact(only_a, only_b) == pytest.approx(
            math.erfc(-z / math.sqrt(2)), rel=0.05
        )


@pytest.mark.parametrize("n", [1024, 5000])
def test_median_interval_holds_for_thousands_of_values(n: int) -> None:
    """``float(2**n)`` overflowed from 1024 values (both variants succeeding in 1024
    episodes); the ranks are the largest ``k`` with ``2 P(Bin(n, 1/2) <= k - 1) <= 5 %``."""
    import math

    from roomba_bt.evaluate.stats import median_interval

    lo, hi = median_interval([float(v) for v in range(n)]) or (None, None)
    assert lo is not None and hi == n - 1 - lo
    k = int(lo) + 1  # the order statistic (k, n + 1 - k), ranks from 1
    assert 2 * math.exp(_log_binomial_cdf(k - 1, n)) <= 0.05 < 2 * math.exp(_log_binomial_cdf(k, n))
    assert abs(k - (n / 2 - Z95 * math.sqrt(n) / 2)) <= 2  # the normal approximation's rank


def test_the_exact_statistics_are_exact_at_a_hundred_thousand() -> None:
    """Thousands of pairs take milliseconds; at 100 000 the sums still end (integers)."""
    from roomba_bt.evaluate.stats import mcnemar_exact, median_interval

    assert median_interval(range(100_000)) == (49689, 50310)
    assert mcnemar_exact(50_000, 50_000) == 1.0


def test_compare_pairs_episodes_by_seed() -> None:
    from roomba_bt.evaluate.stats import compare

    a = [result(s, "success" if s != 3 else "failure", 10.0 + s) for s in range(8)]
    b = [result(s, "success" if s != 5 else "timeout", 8.0 + s) for s in reversed(range(8))]
    c = compare("A", "B", a, b)
    assert (c.pairs, c.both, c.only_a, c.only_b, c.neither) == (8, 6, 1, 1, 0)
    assert c.p_value == 1.0
    assert c.median_difference_s == pytest.approx(-2.0)
    assert c.difference_interval == (pytest.approx(-2.0), pytest.approx(-2.0))
    assert "only A 1, only B 1" in str(c) and "median -2.0 s" in str(c)
    with pytest.raises(ValueError, match="same seeds"):
        compare("A", "B", a, b[:-1])


def test_compare_pairs_the_floor_each_variant_cleaned() -> None:
    """Two cleaning missions were compared on success and time only (most time out: the
    floor cleaned is what differs): B's coverage minus A's, episode by episode, success or
    not; pairs where one ran no brush are left out, and none leaves the line out."""
    from dataclasses import replace

    from roomba_bt.evaluate.episode import Coverage
    from roomba_bt.evaluate.stats import compare

    def cleaned(r: EpisodeResult, final: float) -> EpisodeResult:
        return replace(r, coverage=Coverage("", final, (), final, (), 0.0, 60.0))

    a = [cleaned(result(s, "timeout"), 0.50 + 0.01 * s) for s in range(8)]
    b = [cleaned(result(s, "timeout"), 0.60 + 0.01 * s) for s in range(7)] + [result(7)]
    c = compare("A", "B", a, b)
    assert c.coverage_pairs == 7
    assert c.median_coverage_difference == pytest.approx(0.10)
    assert c.coverage_difference_interval == (pytest.approx(0.10), pytest.approx(0.10))
    assert "coverage B-A median +10.0 points (95 % interval +10.0..+10.0) over the 7 " in str(c)
    assert c.to_dict()["coverage_pairs"] == 7
    plain = compare("A", "B", [result(s) for s in range(3)], [result(s) for s in range(3)])
    assert plain.median_coverage_difference is None and "coverage" not in str(plain)
    assert plain.to_dict()["coverage_difference_interval"] is None


def test_the_json_summary_is_tidied_of_binary_noise() -> None:
    """A sum of 15 ms ticks printed 27.884999999999998 in ``eval --json``: floats are cut to
    ten significant digits (ints, text, infinities and nesting kept as they are)."""
    import math

    from roomba_bt.evaluate.stats import tidy

    assert 0.015 * 1859 != 27.885  # the noise is real
    data = {"t": 0.015 * 1859, "i": (0.4385029682449546, 1.0), "n": 3, "s": "x",
            "inf": math.inf, "none": None, "deep": [{"w": 0.10208152500126744}]}  # fmt: skip
    assert tidy(data) == {"t": 27.885, "i": [0.4385029682, 1.0], "n": 3, "s": "x",
                          "inf": math.inf, "none": None, "deep": [{"w": 0.102081525}]}  # fmt: skip


def test_a_variant_with_no_episode_says_so_instead_of_a_rate() -> None:
    """ "success 0/0 = 0.0 % (95 % Wilson interval 0.0 %..100.0 %)" for a variant Ctrl-C
    stopped before its first episode finished: no rate is a rate of none."""
    empty = summarize("dock.yaml", "apartment", [])
    assert "success      no episode finished" in str(empty) and "0/0" not in str(empty)
    assert empty.to_dict()["rate"] is None and empty.to_dict()["interval"] is None


def test_cpu_time_is_cpu_time_and_wall_time_is_said_to_be_wall_clock(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """ "N s of CPU time" summed the episodes' wall-clock times: 500 jobs on 2 cores said
    18846.9 s of CPU time. An episode's CPU time is its thread's (``time.thread_time``), the
    summary says both, each by its name, and the record has a ``cpu_time`` column."""
    import roomba_bt.evaluate.episode as episode
    from roomba_bt.evaluate import EpisodeSpec
    from roomba_bt.evaluate.records import from_record, to_record

    clock = iter([10.0, 12.5])
    monkeypatch.setattr(episode, "_cpu_clock", lambda: next(clock))
    bump = Path(__file__).resolve().parents[2] / "missions" / "bump-and-turn.yaml"
    spec = EpisodeSpec(str(bump), "corridor", seed=1, params=(("duration", "1s"),), timeout_s=5)
    ran = episode.run_episode(spec)
    assert ran.cpu_s == 2.5
    record = to_record(ran)
    assert record["cpu_time"] == 2.5 and from_record(record).cpu_s == 2.5
    del record["cpu_time"]  # a file written before the column
    assert from_record(record).cpu_s == 0.0

    waited = [replace(result(s, time_s=10.0), wall_s=5.0, cpu_s=2.0) for s in range(2)]
    text = str(summarize("m", "w", waited))
    assert "20 s of mission time in 4.0 s of CPU time (5x real time per CPU second); " in text
    assert "10.0 s of wall-clock time summed over the episodes" in text
    assert summarize("m", "w", waited).to_dict()["cpu_time"] == 4.0


def test_no_speed_is_said_when_no_episode_measured_its_cpu_time() -> None:
    """Every episode HUNG (none records CPU time): the line said "0x real time per CPU
    second", a simulator that stood still; it says the time was not measured."""
    hung = [replace(result(s, "hung", time_s=70.0), wall_s=0.3) for s in range(2)]
    text = str(summarize("m", "w", hung))
    assert "140 s of mission time, CPU time not measured (HUNG and DIED episodes record " in text
    assert "0x" not in text and "0.6 s of wall-clock time summed over the episodes" in text


def test_the_speed_is_of_the_episodes_that_measured_their_cpu_time() -> None:
    """A DIED episode (or a HUNG one in C code, or a record read back without the column)
    has its mission time and no CPU time: the speed summed its mission time over the others'
    CPU time and read high (40 s over 2 s: 20x, where the episodes measured ran 10x). It is
    of the episodes measured, and the others are said apart, in --json too."""
    timed = [replace(result(s, time_s=10.0), wall_s=1.0, cpu_s=1.0) for s in range(2)]
    died = replace(result(2, "died", time_s=20.0), wall_s=30.0)
    summary = summarize("m", "w", [*timed, died])
    text = str(summary)
    assert "40 s of mission time in 2.0 s of CPU time (10x real time per CPU second, over " in text
    assert "the 2 episode(s) that measured it: 1 DIED, HUNG or read back without CPU time " in text
    assert "32.0 s of wall-clock time summed over the episodes" in text  # every one's
    said = summary.to_dict()
    assert (said["real_time_factor"], said["episodes_without_cpu_time"]) == (10.0, 1)
    assert "that measured it" not in str(summarize("m", "w", timed))
    untimed = replace(summary, timings=False).to_dict()  # --reproducible: none measured
    assert (untimed["real_time_factor"], untimed["episodes_without_cpu_time"]) == (None, None)


def test_a_timeout_decorator_and_the_episode_s_timeout_group_apart(tmp_path: Path) -> None:
    """ "timeout: timed out after 2 s" (a decorator in the tree) and "timeout: --timeout 3 s
    of mission time ran out" (the episode's limit; ``eval`` names it by its flag, a spec made
    in Python as "the run's 3 s") read alike in a report's failures."""
    from roomba_bt.evaluate import episode_specs, run_episodes

    mission = tmp_path / "limit.yaml"
    mission.write_text(
        "parameters: {limit: {type: duration, default: 8 s}}\n"
        "tree:\n  sequence:\n    - mode: safe\n    - timeout:\n        after: '${limit}'\n"
        "        do: {drive: {velocity: 50 mm/s, distance: 5 m}}\n"
    )
    tight = (("limit", "2s"),)
    results = [
        *run_episodes(episode_specs(str(mission), runs=1, timeout_s=3.0)),
        *run_episodes(episode_specs(str(mission), runs=1, timeout_s=3.0, params=tight)),
    ]
    groups = [group for group, _ in summarize("limit.yaml", "empty-room", results).failures]
    assert sorted(groups) == [
        "TIMEOUT: the run's 3 s of mission time ran out in drive",  # no flag from Python
        "timeout: the tree's 2 s limit ran out in drive",
    ]


def test_a_report_fakes_no_line_with_what_a_mission_wrote() -> None:
    """A failure reason quoting a node's name ("\\n[ok] fake", "\\x1b[2J") and a mission
    file's name were printed raw in the failure groups: a line of their own, a cleared
    screen. Each stays on its line, escaped; ``eval --json`` keeps them as they are."""
    reason = "steps\n[ok] fake: \x1b[2J"
    results = [result(1), result(2, "failure", reason=reason)]
    summary = summarize("m\n[ok] fake.yaml", "room", results)
    lines = summary.lines()
    assert str(summary).splitlines() == lines
    assert not [line for line in lines if line.startswith("[ok]") or "\x1b" in line]
    assert "     1  steps\\x0a[ok] fake: \\x1b[2J" in lines
    assert lines[0] == "mission      m\\x0a[ok] fake.yaml in room"
    assert summary.to_dict()["failures"] == {reason: 1}
    unfinished = summarize("m\n[ok] fake.yaml", "room", [])
    assert unfinished.lines()[0] == "mission      m\\x0a[ok] fake.yaml in room"


def test_the_successes_are_counted_by_what_the_mission_said_last() -> None:
    """A patrol's laps done and its docking on a low battery are both a success: the report
    tells them apart by the mission's last words (``run``'s ``mission said`` line)."""
    from dataclasses import replace

    laps = [replace(result(i), said="patrol done (laps: 1)", distance_m=d)
            for i, d in enumerate((6.4, 7.8, 48.4))]  # fmt: skip
    docked = replace(result(3), said="docked on a low battery", distance_m=2.0)
    failed = replace(result(4, "failure", reason="x: lost"), said="lost")
    summary = summarize("patrol.yaml", "apartment", [*laps, docked, failed])
    assert summary.endings == (("patrol done (laps: 1)", 3), ("docked on a low battery", 1))
    said = summary.to_dict()
    assert said["success_endings"] == {"patrol done (laps: 1)": 3, "docked on a low battery": 1}
    # how far each ending's episodes drove: a lap round a table (6-8 m) and one round the
    # flat (48 m) both read "laps: 1", and --json could not tell them apart
    assert said["success_distances"] == {
        "patrol done (laps: 1)": {"min": 6.4, "median": 7.8, "max": 48.4},
        "docked on a low battery": {"min": 2.0, "median": 2.0, "max": 2.0},
    }  # fmt: skip
    lines = summary.lines()
    at = lines.index("successes    by what the mission said last")
    assert lines[at + 1 : at + 3] == [
        "     3  patrol done (laps: 1)  (6.4..48.4 m driven, median 7.8 m)",
        "     1  docked on a low battery  (2.0 m driven)",
    ]  # fmt: skip
    silent = summarize("dock.yaml", "room", [result(1), result(2)])  # no log leaf: no line
    assert silent.endings == () and "successes" not in str(silent)


def test_the_page_reads_the_two_sided_p_value_with_its_direction() -> None:
    """McNemar's p here is two-sided: 5 discordant pairs A's way and 1 B's give the p of 1
    A's way and 5 B's. docs/evaluation.md read 'a change "helped" when the p-value is
    small', which a B that failed more often also meets; it now says which way is read from
    the counts, and that a large p (or a time interval across zero) is no evidence of no
    difference."""
    assert mcnemar_exact(5, 1) == mcnemar_exact(1, 5) == pytest.approx(0.21875)
    page = Path(__file__).resolve().parents[2] / "docs" / "evaluation.md"
    text = " ".join(page.read_text(encoding="utf-8").split())
    assert 'A change "helped" when the p-value is small' not in text
    assert "it is two-sided, so which way is read from the counts" in text
    assert 'is no evidence of "no difference"' in text
