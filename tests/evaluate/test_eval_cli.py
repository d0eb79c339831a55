"""``roomba-bt eval`` end to end, in process."""

from __future__ import annotations

import json
import shlex
import subprocess
import sys
from pathlib import Path

import pytest
from waits import HANG_S  # tests/waits.py: a hang's bound

from roomba_bt.cli import main
from roomba_bt.evaluate.stats import tidy

MISSIONS = Path(__file__).resolve().parents[2] / "missions"
BUMP = str(MISSIONS / "bump-and-turn.yaml")


@pytest.mark.extra("plot")
def test_eval_prints_the_report_and_plots(tmp_path: Path,
                                          capsys: pytest.CaptureFixture[str]) -> None:  # fmt: skip
    png = tmp_path / "runs.png"
    code = main(["eval", BUMP, "--runs", "2", "--seed", "3", "-p", "duration=3s",
                 "--plot", str(png)])  # fmt: skip
    out, err = capsys.readouterr()
    assert code == 0
    assert "success      2/2 = 100.0 %" in out and "Wilson" in out and "p90" in out
    assert "2/2 ok 2" in err
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_the_progress_label_of_a_mission_without_parameters_is_its_name_once_spaced(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """The bar's label is the mission and its parameters, each followed by one space: with
    no parameter it read ``bump-and-turn  [...`` (an empty parameter text between two)."""
    assert main(["eval", BUMP, "--runs", "1", "--timeout", "1s"]) == 0
    err = capsys.readouterr().err
    assert err.startswith(f"{BUMP} [") and "  [" not in err


@pytest.mark.extra("plot")
def test_every_variant_is_plotted_in_a_panel_of_its_own(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``eval A B --plot`` (here a sweep) drew the first variant only. An SVG keeps each
    panel's title as text (a comment over its glyphs): both are there, with their counts."""
    svg = tmp_path / "ab.svg"
    code = main(["eval", BUMP, "--runs", "2", "--seed", "3", "--sweep", "duration=2s,3s",
                 "--no-progress", "--plot", str(svg)])  # fmt: skip
    assert code == 0
    assert f"trajectories written to {svg}" in capsys.readouterr().err
    text = svg.read_text()
    assert text.count("succeeded (2)") == 2  # a legend a panel
    for value in ("2s", "3s"):
        assert f"{BUMP} -p duration={value}: 2/2" in text


def test_the_plot_help_names_the_formats_it_writes(capsys: pytest.CaptureFixture[str]) -> None:
    """``--plot x.pdf`` writes a PDF; the help said FILE.png."""
    with pytest.raises(SystemExit):
        main(["eval", "--help"])
    help_text = " ".join(capsys.readouterr().out.split())
    assert "--plot FILE " in help_text and "FILE.png" not in help_text
    assert ".png, .pdf, .svg" in help_text


@pytest.mark.parametrize("rate", ["0.5", "50%", "50 %"])
def test_min_rate_not_reached_exits_1(rate: str, capsys: pytest.CaptureFixture[str]) -> None:
    code = main(["eval", str(MISSIONS / "dock.yaml"), "--runs", "1", "--timeout", "1s",
                 "--min-rate", rate, "--no-progress"])  # fmt: skip
    assert code == 1
    assert "is below --min-rate 50.0 %" in capsys.readouterr().err


def test_within_and_battery_take_units_as_missions_do(tmp_path: Path) -> None:
    """``--within 150cm --battery 50%`` is ``--within 1.5 --battery 0.5`` (argparse refused
    the units with its usage): the same start poses, and the rerun line says the charge."""
    from roomba_bt.evaluate.records import read_results

    starts = []
    for within, battery in (("1.5", "0.5"), ("150cm", "50%"), ("1.5 m", "50 %")):
        out = tmp_path / f"{len(starts)}.jsonl"
        assert main(["eval", BUMP, "-p", "duration=1s", "--runs", "3", "--seed", "4",
                     "--within", within, "--battery", battery, "--no-progress",
                     "--out", str(out)]) == 0  # fmt: skip
        starts.append([(r.start, r.seed) for r in read_results(out)])
    assert starts[0] == starts[1] == starts[2]


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--within", "nan"], "--within: found 'nan'; allowed: a distance in 0.05..20 m"),
        (["--within", "1e-9"], "--within: found '1e-9'; allowed: a distance in 0.05..20 m"),
        # the same range as a world's near_dock (500 m blamed the world: "no free pose")
        (["--within", "500"], "--within: found '500'; allowed: a distance in 0.05..20 m"),
        (["--within", "5000cm"], "--within: found '5000cm'; allowed: a distance in 0.05..20 m"),
        (["--within", "2 parsec"], "--within: found '2 parsec'; allowed: a distance"),
        (["--within", "1.5%"], "--within: found '1.5%'; allowed: a distance"),
        (
            ["--battery", "2"],
            "--battery: found '2'; allowed: a fraction in 0..1 (0.5) or a "
            "percent in 0..100 % (50%)",
        ),
        (["--battery", "150%"], "--battery: found '150%'; allowed: a fraction in 0..1"),
        (["--battery", "half"], "--battery: found 'half'; allowed: a fraction in 0..1"),
        (["--min-rate=-1%"], "--min-rate: found '-1%'; allowed: a fraction in 0..1"),
        (["--min-rate", "90m"], "--min-rate: found '90m'; allowed: a fraction in 0..1"),
    ],
)
def test_bad_distances_and_fractions_exit_2_naming_the_option(
    argv: list[str], message: str, capsys: pytest.CaptureFixture[str]
) -> None:
    with pytest.raises(SystemExit) as exit_:
        main(["eval", BUMP, "--runs", "1", "--no-progress", *argv])
    assert exit_.value.code == 2
    out, err = capsys.readouterr()
    assert f"argument {message}" in err
    assert out == ""


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["missing.yaml"], "no such mission file"),
        ([BUMP, "--runs", "0"], "--runs 0"),
        ([BUMP, "--dock", "buoy_range=far"], "is not a number"),
        ([BUMP, "--dock", "colour=1"], "FIELD one of"),
        ([BUMP, "--dock", "buoy_range=nan"], "--dock buoy_range=nan: expected a number in"),
        ([BUMP, "--dock", "force_field=inf"], "--dock force_field=inf: expected a number in"),
        # a world file's range (any number above 0 was taken)
        ([BUMP, "--dock", "buoy_range=50"], "--dock buoy_range=50: expected a number in 0.2..5 m"),
        ([BUMP, "--dock", "red=-100,5"], "--dock red=-100,5: expected FROM,TO in degrees, -90 <="),
        # every spec is made up front: 10^11 ran the memory out with no word
        ([BUMP, "--runs", "100000000000"], "--runs 100000000000: expected 1..1,000,000"),
        ([BUMP, "--scheduler", ""], "--scheduler '': expected the scheduler's address"),
        # the sweep's values won and -p's never ran, silently
        (
            [BUMP, "-p", "speed=90mm/s", "--sweep", "speed=100mm/s,120mm/s"],
            "-p speed and --sweep speed: give its values in --sweep alone",
        ),
        ([BUMP, "--world", "moon"], "no such file or shipped world"),
        ([BUMP, "-p", "speed"], "NAME=VALUE"),
        ([BUMP, "-p", "speed=fast"], "speed"),
    ],
)
def test_bad_input_exits_2_with_a_message(
    argv: list[str], message: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["eval", *argv]) == 2
    assert message in capsys.readouterr().err


@pytest.mark.parametrize(
    "field", ["buoy_range", "force_field", "contact_tolerance", "angle_tolerance"]
)
def test_dock_overrides_are_refused_where_a_world_file_is(
    field: str, capsys: pytest.CaptureFixture[str]
) -> None:
    """``--dock FIELD=VALUE`` takes what the world file's ``dock:`` takes, no more: the range
    the world's problem states, its ends included."""
    import re

    from roomba_bt.cli.eval_cmd import parse_dock
    from roomba_bt.sim.world import WorldError, parse_world

    text = (
        "name: t\nrooms:\n  - [[0, 0], [4, 0], [4, 3.5], [0, 3.5]]\n"
        f"dock: {{at: [2, 0], facing: 90, {field}: 500}}\n"
    )
    with pytest.raises(WorldError) as refused:
        parse_world(text)
    allowed = re.search(r"allowed: (a number in ([-\d.]+)\.\.([-\d.]+) \w+)", str(refused.value))
    assert allowed is not None, str(refused.value)
    phrase, lo, hi = allowed.group(1), float(allowed.group(2)), float(allowed.group(3))
    for value in (500, lo / 2, 0, -1):
        assert main(["eval", BUMP, "--runs", "1", "--no-progress", "--dock",
                     f"{field}={value:g}"]) == 2  # fmt: skip
        assert f"--dock {field}={value:g}: expected {phrase}" in capsys.readouterr().err
    for value in (lo, hi):
        assert parse_dock([f"{field}={value:g}"]) == ((field, value),)
        parse_world(text.replace(": 500}", f": {value:g}}}"))  # the world takes it too


def test_plot_without_matplotlib_is_a_clear_error(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """Said when the arguments are read, before any episode runs."""
    monkeypatch.setitem(sys.modules, "matplotlib", None)
    with pytest.raises(SystemExit) as exit_:
        main(["eval", BUMP, "--runs", "1", "-p", "duration=1s", "--no-progress",
              "--plot", str(tmp_path / "x.png")])  # fmt: skip
    assert exit_.value.code == 2
    out, err = capsys.readouterr()
    assert "needs matplotlib" in err
    assert "success" not in out
    assert not (tmp_path / "x.png").exists()


@pytest.mark.parametrize("command", [["eval", BUMP, "--runs", "1"], ["run", BUMP, "--fast"],
                                     ["sim", "--pty", "--duration", "0"]])  # fmt: skip
@pytest.mark.extra("plot")
def test_plot_into_a_missing_directory_is_refused_before_running(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], command: list[str]
) -> None:
    target = tmp_path / "no" / "such" / "x.png"
    with pytest.raises(SystemExit) as exit_:
        main([*command, "--plot", str(target)])
    assert exit_.value.code == 2
    out, err = capsys.readouterr()
    assert f"--plot: found '{target}': there is no directory {target.parent}" in err
    assert out == ""


@pytest.mark.parametrize("command", [["eval", BUMP, "--runs", "1"], ["run", BUMP, "--fast"],
                                     ["sim", "--pty", "--duration", "0"]])  # fmt: skip
@pytest.mark.parametrize(("name", "why"), [("x.txt", "no picture format '.txt'"),
                                          ("x", "no suffix")])  # fmt: skip
@pytest.mark.extra("plot")
def test_plot_to_a_format_matplotlib_cannot_write_is_refused_before_running(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], command: list[str], name: str, why: str
) -> None:
    """Not matplotlib's ``Format 'txt' is not supported`` traceback after the run; without a
    suffix matplotlib would write another file than the one named (``x.png``)."""
    target = tmp_path / name
    with pytest.raises(SystemExit) as exit_:
        main([*command, "--plot", str(target)])
    assert exit_.value.code == 2
    out, err = capsys.readouterr()
    assert f"--plot: found '{target}': {why}; allowed: a file ending in " in err
    assert ".png" in err and ".svg" in err
    assert out == ""
    assert list(tmp_path.iterdir()) == []


def test_ab_report_on_two_variants_is_reproduced_from_its_records(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """bump-and-turn at two speeds on the same seeds and start poses (apartment, 6 s): the
    paired counts, McNemar's p and the median time difference in the --json report are what
    the per-episode records give, and a second run prints the same report."""
    import json

    from roomba_bt.evaluate.records import read_results
    from roomba_bt.evaluate.stats import compare, mcnemar_exact

    argv = ["eval", BUMP, "--world", "apartment", "--runs", "6", "--seed", "20",
            "-p", "duration=6s", "--timeout", "5s", "--sweep", "speed=200mm/s,400mm/s",
            "--no-progress", "--json"]  # fmt: skip
    out_file = tmp_path / "ab.jsonl"
    assert main([*argv, "--out", str(out_file)]) == 0
    report = json.loads(capsys.readouterr().out)
    (cmp,) = report["comparisons"]
    records = read_results(out_file)
    a = [r for r in records if r.params == (("duration", "6s"), ("speed", "200mm/s"))]
    b = [r for r in records if r.params == (("duration", "6s"), ("speed", "400mm/s"))]
    assert [r.seed for r in a] == [r.seed for r in b] == list(range(20, 26))
    assert [r.start for r in a] == [r.start for r in b], "same start poses"
    again = compare(cmp["a"], cmp["b"], a, b)
    assert tidy(again.to_dict()) == cmp
    assert cmp["pairs"] == cmp["both"] + cmp["only_a"] + cmp["only_b"] + cmp["neither"] == 6
    assert cmp["mcnemar_p"] == mcnemar_exact(cmp["only_a"], cmp["only_b"])
    assert [v["label"] for v in report["variants"]] == [cmp["a"], cmp["b"]]
    assert [v["coverage"] for v in report["variants"]] == [None, None]  # no brushes
    assert cmp["b"].endswith("-p speed=400mm/s")
    assert main(argv) == 0
    rerun = json.loads(capsys.readouterr().out)
    assert rerun["comparisons"] == report["comparisons"]


def test_the_json_summary_records_how_the_episodes_were_made(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """An archived ``--json`` said what ran, not under which conditions: its "conditions"
    object has them, in the units of the report (s, m, degrees, fractions); the other keys
    are as they were."""
    import json

    from roomba_bt import __version__

    assert main(["eval", BUMP, "-p", "duration=1s", "--runs", "2", "--seed", "7",
                 "--timeout", "2min", "--within", "150cm", "--battery", "40%",
                 "--dock", "buoy_range=0.8", "--dock", "red=-10,20", "--odometry-error", "0.01",
                 "--profile", "roomba600", "--no-progress", "--json"]) == 0  # fmt: skip
    report = json.loads(capsys.readouterr().out)
    assert set(report) == {
        "conditions",
        "engine",
        "retried",
        "interrupted",
        "interrupted_by",
        "interruption",
        "variants",
        "comparisons",
        "passed",
        "plugins",
        "methods",  # session 35: how each figure is computed
    }  # fmt: skip (session 29's two)
    assert report["conditions"] == {
        "timeout": 120.0,
        "wall_limit": 72.0,  # by default a minute and a tenth of --timeout
        "params": {"duration": "1s"},  # -p's, under every variant's own (session 35)
        "seed": 7,
        "runs": 2,
        "seeds": None,  # --seeds' list (session 35)
        "world": "empty-room",
        "within": 1.5,
        "start_area": None,
        "dock": {"buoy_range": 0.8, "red": [-10.0, 20.0]},
        "odometry_error": 0.01,
        "faults": [],  # the fault options given (session 32)
        "battery": 0.4,
        "profile": "roomba600",
        "min_rate": None,  # session 29: the bar it was judged against, and the world's digest
        "world_sha256": report["conditions"]["world_sha256"],
        "roomba_bt_version": __version__,
    }
    assert main(["eval", BUMP, "-p", "duration=1s", "--runs", "1", "--world", "apartment",
                 "--start-area", "kitchen", "--no-progress", "--json"]) == 0  # fmt: skip
    conditions = json.loads(capsys.readouterr().out)["conditions"]
    assert conditions["start_area"] == "kitchen" and conditions["world"] == "apartment"
    assert conditions["within"] is None and conditions["battery"] is None
    assert conditions["dock"] == {} and conditions["timeout"] == 900.0
    assert conditions["wall_limit"] == 150.0


def test_the_json_summary_names_each_figure_s_method_and_level(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """``interval``, ``p90_time``, ``mcnemar_p`` and ``time_difference_interval`` came with
    no method nor level: a paper had to read the docs to say what they were."""
    import json

    from roomba_bt.evaluate.stats import METHODS

    assert main(["eval", BUMP, "-p", "duration=1s", "--runs", "2", "--sweep", "speed=200mm/s,"
                 "300mm/s", "--no-progress", "--json"]) == 0  # fmt: skip
    methods = json.loads(capsys.readouterr().out)["methods"]
    assert methods == METHODS and methods["confidence_level"] == 0.95
    assert "Wilson" in methods["interval"] and "linear interpolation" in methods["p90_time"]
    assert "exact McNemar" in methods["mcnemar_p"]
    assert "at least 0.95" in methods["time_difference_interval"]
    assert "conditional on success" in methods["time_difference_interval"]
    assert "Bonferroni" in methods["multiple_comparisons"]


def test_a_variant_s_label_has_the_p_base_it_ran_with(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """``-p speed=250mm/s`` under ``--variant``s: B was labelled "-p duration=2s" alone,
    though it ran at 250 mm/s and A (which overrode the speed) did not; the text, the JSON's
    labels and comparisons now say every value each ran with, the JSON the base and each
    variant's own apart. One variant's ``-p`` were said nowhere in the text."""
    import json

    argv = ["eval", BUMP, "--runs", "2", "-p", "speed=250mm/s", "-p", "duration=1s",
            "--variant", "speed=300mm/s", "--variant", "duration=2s", "--no-progress"]  # fmt: skip
    assert main(argv) == 0
    out = capsys.readouterr().out
    a = f"{BUMP} -p duration=1s -p speed=300mm/s"
    b = f"{BUMP} -p speed=250mm/s -p duration=2s"
    assert f"A = {a}\n             B = {b}\n" in out
    assert main([*argv, "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["conditions"]["params"] == {"speed": "250mm/s", "duration": "1s"}
    assert [(v["label"], v["own_params"]) for v in report["variants"]] == [
        (a, {"speed": "300mm/s"}), (b, {"duration": "2s"})
    ]  # fmt: skip
    assert (report["comparisons"][0]["a"], report["comparisons"][0]["b"]) == (a, b)
    assert main(["eval", BUMP, "--runs", "1", "-p", "duration=1s", "--no-progress"]) == 0
    assert f"variant      {BUMP} -p duration=1s\nmission " in capsys.readouterr().out


def test_the_progress_bars_label_each_variant_as_the_report_does(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """The bar said ``bump-and-turn duration=1s speed=300mm/s`` (the file's stem, the
    parameters sorted, no ``-p``) over a report that said ``.../bump-and-turn.yaml -p
    speed=300mm/s -p duration=1s``: one variant in two forms and orders. Both are made by
    one function now."""
    argv = ["eval", BUMP, "--runs", "1", "-p", "speed=300mm/s", "--sweep", "duration=1s,2s"]
    assert main(argv) == 0
    out, err = capsys.readouterr()
    labels = [line.removeprefix("variant      ") for line in out.splitlines()
              if line.startswith("variant ")]  # fmt: skip
    assert labels == [f"{BUMP} -p speed=300mm/s -p duration={d}" for d in ("1s", "2s")]
    log = err.splitlines()[-1]  # into a pipe: a line with every variant's count
    assert all(f"{label} 1/1 ok" in log for label in labels), log


@pytest.mark.parametrize(
    ("variants", "said"),
    [
        (["--variant", "speed=200mm/s", "--variant", "speed=fast"],
         "parameter speed=fast (from --variant speed=fast): expected a speed"),
        (["--variant", "speed=200mm/s", "--variant", "duration=1s;sped=1"],
         "unknown parameter 'sped' set by --variant 'duration=1s;sped=1' (did you mean "),
        (["--sweep", "speed=200mm/s,fast"], "parameter speed=fast (from --sweep): expected a "),
        (["-p", "speed=fast", "--variant", "duration=1s"],
         "parameter speed=fast (from the command line): expected a speed"),
    ],
    ids=["variant-value", "variant-name", "sweep-value", "p-base"],
)  # fmt: skip
def test_a_bad_value_names_the_variant_it_came_from(
    variants: list[str], said: str, capsys: pytest.CaptureFixture[str]
) -> None:
    """Of ten ``--variant``s, "(from the command line)" left the user to find the bad one."""
    assert main(["eval", BUMP, "--runs", "1", *variants, "--no-progress"]) == 2
    assert said in capsys.readouterr().err


def test_the_same_value_in_two_spellings_is_the_same_variant_twice(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """``--sweep speed=300mm/s,0.3m/s`` ran both and "compared" them, median +0.0 s, with
    no word; refused before any episode runs, as the same spelling twice is."""
    argv = ["eval", BUMP, "--runs", "1", "-p", "duration=1s", "--no-progress"]
    assert main([*argv, "--sweep", "speed=300mm/s,0.3m/s"]) == 2
    said = capsys.readouterr().err
    assert (f"{BUMP} -p duration=1s -p speed=300mm/s and {BUMP} -p duration=1s -p speed=0.3m/s: "
            "the same variant twice (the mission reads the same values)") in said  # fmt: skip
    assert (
        main([*argv, "--variant", "speed=200mm/s", "--variant", "speed=200 mm/s;duration=1s"]) == 2
    )
    assert "the same variant twice" in capsys.readouterr().err
    assert main([*argv, "--sweep", "speed=300mm/s,0.31m/s"]) == 0


def test_two_missions_are_compared_and_the_text_report_says_so(
    capsys: pytest.CaptureFixture[str],
) -> None:
    dock = str(MISSIONS / "dock.yaml")
    builtin = str(MISSIONS / "dock-builtin.yaml")
    code = main(["eval", dock, builtin, "--runs", "2", "--within", "1", "--seed", "5",
                 "--no-progress"])  # fmt: skip
    out = capsys.readouterr().out
    assert code == 0
    assert f"A = {dock}" in out and f"B = {builtin}" in out
    assert "exact McNemar p = " in out and "time B - A   median" in out


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--sweep", "speed"], "expected NAME=V1,V2"),
        (["--sweep", "speed=1,2", "--variant", "speed=3"], "one or the other"),
        (["--variant", "speed"], "--variant 'speed': expected NAME=VALUE"),
        # the loader names the option the name or value came from (session 35)
        (["--sweep", "sped=1mm/s,2mm/s"], "unknown parameter 'sped' set by --sweep"),
        (["--variant", "speed=fast"], "parameter speed=fast (from --variant speed=fast)"),
    ],
)
def test_bad_comparison_and_output_options_exit_2(
    extra: list[str], message: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["eval", BUMP, *extra]) == 2
    assert message in capsys.readouterr().err


@pytest.mark.parametrize(
    ("where", "message"),
    [("folder", "a directory; expected a file name"), ("no/x.jsonl", "there is no directory"),
     ("results.txt", "allowed: a file ending in .jsonl or .csv"),
     # someone's data: written over by an hour's sweep before
     ("data.csv", "a file that is not an evaluation's results; --out writes over earlier")],
)  # fmt: skip
def test_an_out_file_that_cannot_be_written_is_refused_before_any_episode(
    where: str, message: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    (tmp_path / "folder").mkdir()
    (tmp_path / "data.csv").write_text("when,what\n2026-12-04,lunch\n")
    with pytest.raises(SystemExit) as exited:  # argparse's own exit, with its usage line
        main(["eval", BUMP, "--runs", "2", "--out", str(tmp_path / where)])
    assert exited.value.code == 2
    err = capsys.readouterr().err
    assert message in err and "1/2" not in err  # no episode ran
    assert (tmp_path / "data.csv").read_text() == "when,what\n2026-12-04,lunch\n"


@pytest.mark.parametrize("suffix", [".jsonl", ".csv"])
def test_earlier_results_are_written_over_only_when_forced(
    suffix: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Running again "to continue" wrote over a sweep's episodes without a word. Now a file
    that holds episodes is refused (exit 2, the file and the options named, no episode run)
    unless ``--force`` (or ``--resume``: tests/evaluate/test_resume.py)."""
    out = tmp_path / f"r{suffix}"
    argv = ["eval", BUMP, "-p", "duration=1s", "--no-progress", "--out", str(out)]
    assert main([*argv, "--runs", "2"]) == 0
    before = out.read_text()
    assert main([*argv, "--runs", "3"]) == 2
    err = capsys.readouterr().err
    assert f"--out {out}: the file already holds episodes of an earlier evaluation" in err
    assert "give --resume" in err and "--force to write over it" in err
    assert out.read_text() == before
    assert main([*argv, "--runs", "3", "--force"]) == 0
    assert capsys.readouterr().err.count("results written to") == 1
    lines = out.read_text().splitlines()
    assert len(lines) == (3 if suffix == ".jsonl" else 4)  # the second run's (CSV: a header)


def test_a_failed_results_write_keeps_the_summary(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """A disk that filled during an evaluation of hours: the summary is still printed."""
    import errno

    import roomba_bt.evaluate.records as records

    def full(path: object, results: object, *more: object, **options: object) -> int:
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(records, "write_results", full)
    code = main(["eval", BUMP, "--runs", "2", "--timeout", "5s", "--no-progress",
                 "--out", str(tmp_path / "r.jsonl")])  # fmt: skip
    out, err = capsys.readouterr()
    assert code == 2
    assert "success      " in out
    assert "No space left on device; the summary is above" in err


def test_the_partial_records_say_what_made_them_as_the_final_ones_do(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """OUT.partial.jsonl's rows had no provenance columns, while OUT's have them: a sweep
    that died left records that said nothing of the release, the world or the mission
    files that made them. Its rows are OUT's now (kept here by a write of OUT that fails)."""
    import errno
    import json

    import roomba_bt.evaluate.records as records

    argv = ["eval", BUMP, "-p", "duration=1s", "--runs", "2", "--no-progress", "--out"]
    assert main([*argv, str(tmp_path / "r.jsonl")]) == 0
    final = [json.loads(line) for line in (tmp_path / "r.jsonl").read_text().splitlines()]

    def full(path: object, results: object, *more: object, **options: object) -> int:
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(records, "write_results", full)
    assert main([*argv, str(tmp_path / "kept.jsonl")]) == 2
    partial = (tmp_path / "kept.jsonl.partial.jsonl").read_text().splitlines()
    made = [{c: json.loads(row)[c] for c in records.PROVENANCE_COLUMNS} for row in partial]
    assert made == [{c: row[c] for c in records.PROVENANCE_COLUMNS} for row in final]
    assert made[0]["sources"] and made[0]["roomba_bt_version"] and made[0]["world_sha256"]


def test_a_summary_that_fails_loses_no_episode(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """A 1000-episode A/B sweep ended in an OverflowError in the statistics, and --out was
    never written (only the partial file survived, unmentioned): the records are written
    before any statistics, and the error says where they are."""
    import roomba_bt.evaluate as evaluate
    from roomba_bt.evaluate.records import read_results

    def broken(*args: object, **kwargs: object) -> None:
        raise OverflowError("int too large to convert to float")

    monkeypatch.setattr(evaluate, "summarize", broken)
    out = tmp_path / "r.jsonl"
    code = main(["eval", BUMP, "-p", "duration=1s", "--runs", "3", "--no-progress",
                 "--out", str(out)])  # fmt: skip
    assert code == 70  # roomba-bt's own error: one line, not a traceback (cli/__init__.py)
    assert [r.seed for r in read_results(out)] == [0, 1, 2]
    err = capsys.readouterr().err
    assert f"the 3 episode(s) that finished are in {out}" in err
    assert "internal error: OverflowError: int too large to convert to float" in err


@pytest.mark.parametrize("b_finished", [2, 0])
def test_an_interrupted_ab_compares_the_seeds_both_finished(
    b_finished: int, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """Ctrl-C during B of an A/B run: B read "success 0/0 = 0.0 % (95 % Wilson interval
    0.0 %..100.0 %)" and the comparison was dropped without a word, even over seeds both
    finished. Now a variant with no episode says so, and the comparison is over the pairs
    that finished (or a line says why there is none)."""
    import roomba_bt.evaluate.parallel as parallel
    from roomba_bt.evaluate.parallel import Evaluation

    def interrupted_in_b(batches: list, engine: object, *_: object) -> list:  # type: ignore[type-arg]
        a = parallel.run_episodes(batches[0])
        return [Evaluation(a), Evaluation(parallel.run_episodes(batches[1][:b_finished]), 0, True)]

    monkeypatch.setattr(parallel, "evaluate", interrupted_in_b)
    code = main(["eval", BUMP, "--sweep", "duration=1s,2s", "--runs", "3", "--no-progress"])
    out = capsys.readouterr().out
    assert code == 130
    assert "0/0" not in out and "Wilson interval 0.0 %..100.0 %" not in out
    if b_finished:
        assert "paired       2 episodes, same seeds and start poses (interrupted" in out
    else:
        assert "success      no episode finished" in out
        assert "no comparison, no seed finished with both (interrupted)" in out


def _eval_past_its_first_episode(out: Path, *options: str) -> subprocess.Popen[bytes]:
    """``roomba-bt eval`` of 200 dock episodes writing ``out``, in a session of its own, once
    its progress bar says the first finished (read from its stderr, not a clock)."""
    import os

    proc = subprocess.Popen(
        [sys.executable, "-m", "roomba_bt.cli", "eval", str(MISSIONS / "dock.yaml"),
         "--runs", "200", "--within", "1.5", "--out", str(out), *options],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, start_new_session=True,
    )  # fmt: skip
    assert proc.stderr is not None and proc.stdout is not None
    seen = b""
    while b" 1/200 " not in seen:
        chunk = os.read(proc.stderr.fileno(), 4096)
        assert chunk, f"eval ended before its first episode: {seen!r}"
        seen += chunk
    return proc


@pytest.mark.parametrize(
    "engine",
    [["--jobs", "1"], ["--jobs", "2"],
     pytest.param(["--engine", "dask", "--jobs", "2"], marks=pytest.mark.extra("cluster"))],
)  # fmt: skip
def test_ctrl_c_prints_what_finished_and_exits_130(tmp_path: Path, engine: list[str]) -> None:
    """SIGINT after the first episode has reported, to the whole process group as a terminal
    sends it: the summary of the finished episodes, exit code 130, and no traceback (each
    pool worker, Dask nanny and worker printed its own)."""
    import os
    import signal

    out = tmp_path / "partial.jsonl"
    proc = _eval_past_its_first_episode(out, *engine)
    os.killpg(proc.pid, signal.SIGINT)
    stdout, stderr = proc.communicate(timeout=HANG_S)
    assert proc.returncode == 130, stderr
    finished = len(out.read_text(encoding="utf-8").splitlines())
    assert 1 <= finished < 200
    assert f"/{finished} = " in stdout.decode()
    said = f"by Ctrl-C or kill -INT (SIGINT); {finished} of 200 episode(s) finished"
    assert f"roomba-bt eval: interrupted {said}, summarised above" in stderr.decode()
    assert f"interrupted  {said}" in stdout.decode()
    assert "Traceback" not in stderr.decode() and "safe stop" not in stderr.decode(), stderr


@pytest.mark.parametrize("engine", [["--jobs", "2"], ["--jobs", "1", "--wall-limit", "none"]])
def test_a_sigterm_says_so_in_the_json_summary(tmp_path: Path, engine: list[str]) -> None:
    """``--json`` said ``"interrupted": true`` and not why: a job scheduler's SIGTERM read as
    an operator's Ctrl-C, or a cluster gone. Now ``interrupted_by`` names the signal and
    ``interruption`` says it as the text summary's ``interrupted`` line does; exit 130. Sent
    to the evaluation alone, as ``kill`` does: also while it runs an episode in its own
    process (``--jobs 1 --wall-limit none``), where the run's guard takes the signal."""
    import json
    import signal

    out = tmp_path / "partial.jsonl"
    proc = _eval_past_its_first_episode(out, "--json", *engine)
    proc.send_signal(signal.SIGTERM)
    stdout, stderr = proc.communicate(timeout=HANG_S)
    assert proc.returncode == 130, stderr
    report = json.loads(stdout)
    finished = len(out.read_text(encoding="utf-8").splitlines())
    assert report["variants"][0]["runs"] == finished
    assert (report["interrupted"], report["interrupted_by"]) == (True, "SIGTERM")
    assert report["interruption"] == "by SIGTERM"
    said = f"interrupted by SIGTERM; {finished} of 200 episode(s) finished, summarised above"
    assert f"roomba-bt eval: {said}" in stderr.decode()
    assert "Traceback" not in stderr.decode()


def test_an_evaluation_that_ran_to_its_end_says_no_interruption(
    capsys: pytest.CaptureFixture[str],
) -> None:
    import json

    assert main(["eval", BUMP, "-p", "duration=1s", "--runs", "2", "--no-progress"]) == 0
    assert "interrupted" not in capsys.readouterr().out
    assert main(["eval", BUMP, "-p", "duration=1s", "--runs", "2", "--no-progress",
                 "--json"]) == 0  # fmt: skip
    report = json.loads(capsys.readouterr().out)
    assert (report["interrupted"], report["interrupted_by"], report["interruption"]) == (
        False, None, None
    )  # fmt: skip


def test_strict_runs_no_episode_of_a_mission_with_warnings_exit_7_as_run_strict(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``validate --strict`` and ``run --strict`` refuse a mission with compile-time
    warnings; ``eval`` had no ``--strict`` and ran every episode of it. Now ``eval --strict``
    refuses it as ``run --strict`` does (exit 7, validate's verdict after the warning), before
    any episode or file; each mission with warnings is named, not the clean one beside it."""
    from roomba_bt.runtime.summary import ExitCode

    warned = tmp_path / "w1.yaml"
    warned.write_text("tree:\n  sequence:\n    - mode: full\n"
                      "    - drive: {velocity: 100 mm/s, duration: 1s}\n")  # fmt: skip
    out = tmp_path / "r.jsonl"
    dock = str(MISSIONS / "dock.yaml")
    options = ["--within", "1.5", "--runs", "2", "--no-progress", "--out", str(out)]
    argv = ["eval", dock, str(warned), *options]
    assert main([*argv, "--strict"]) == ExitCode.STRICT
    stdout, err = capsys.readouterr()
    assert stdout == ""
    assert err.startswith(f"{warned}:4:7: warning: drive can turn the wheels in Full mode")
    assert err.endswith(f"roomba-bt eval: {warned}: failed --strict (1 warning); no episode runs\n")
    assert dock not in err
    assert not out.exists() and not Path(f"{out}.partial.jsonl").exists()
    assert main(["run", str(warned), "--fast", "--display", "none", "--strict"]) == ExitCode.STRICT
    capsys.readouterr()
    assert main(["eval", dock, *options, "--strict"]) == ExitCode.OK  # the clean one alone
    # without --strict: run, the warning printed (--force: --out holds the run above's)
    assert main([*argv, "--force"]) == ExitCode.OK
    assert "warning: drive can turn the wheels in Full mode" in capsys.readouterr().err


def test_every_mission_that_cannot_run_is_said_before_any_episode(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``eval a.yaml b.yaml c.yaml`` stopped at the first invalid file: its user fixed them
    one run at a time. Each file that does not compile, and each not found, is said now,
    as ``validate`` says a batch, and no episode runs (exit 2)."""
    typo = tmp_path / "typo.yaml"
    typo.write_text("tree: {wal: {}}\n")
    keys = tmp_path / "keys.yaml"
    keys.write_text("tree:\n  sequence: {mode: safe, wall: {}}\n")
    missing = str(tmp_path / "nope.yaml")
    argv = ["eval", str(typo), BUMP, str(keys), missing, "--runs", "1", "--no-progress"]
    assert main(argv) == 2
    out, err = capsys.readouterr()
    assert out == ""
    lines = err.splitlines()
    assert lines[0].startswith(f"{typo}:1:8: unknown node 'wal' (did you mean 'wall'?)")
    assert lines[1].startswith(f"{keys}:2:14: a sequence's children are a list")
    assert lines[2].startswith(f"roomba-bt eval: {missing}: no such mission file")
    assert lines[3:] == [
        "roomba-bt eval: 3 of 4 missions cannot be evaluated (said above); no episode runs"
    ]


def test_several_missions_not_found_are_said_one_line_each(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """When no mission was found, their messages were joined with "; " on one line; each
    has its own now, as ``validate`` says them and as when some were found (exit 2)."""
    missing = [str(tmp_path / "a.yaml"), str(tmp_path / "b.yaml")]
    assert main(["eval", *missing, "--runs", "1", "--no-progress"]) == 2
    lines = capsys.readouterr().err.splitlines()
    assert [line.split(": no such mission file")[0] for line in lines[:2]] == [
        f"roomba-bt eval: {path}" for path in missing
    ]
    assert lines[2:] == [
        "roomba-bt eval: 2 of 2 missions cannot be evaluated (said above); no episode runs"
    ]


def test_json_says_why_no_episode_runs_as_json(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``eval --json`` of a mission that does not compile left stdout empty (exit 2), and a
    nightly script's ``json.load`` of it raised. stdout holds an object now, each error with
    its file, line and column; stderr and the exit code are as without ``--json``; so for a
    mission not found, and for ``--strict``'s warnings (exit 7)."""
    from roomba_bt.runtime.summary import ExitCode

    typo = tmp_path / "typo.yaml"
    typo.write_text("tree: {wal: {}}\n")
    options = ["--runs", "1", "--no-progress", "--json"]
    assert main(["eval", str(typo), *options]) == ExitCode.INVALID
    out, err = capsys.readouterr()
    said = json.loads(out)
    assert said["error"] == "1 of 1 missions cannot be evaluated; no episode runs"
    [error] = said["errors"]
    assert (error["file"], error["line"], error["column"]) == (str(typo), 1, 8)
    assert error["message"].startswith("unknown node 'wal' (did you mean 'wall'?)")
    assert err.startswith(f"{typo}:1:8: unknown node 'wal'")
    missing = str(tmp_path / "nope.yaml")
    assert main(["eval", BUMP, missing, *options]) == ExitCode.INVALID
    said = json.loads(capsys.readouterr().out)
    assert said["error"] == "1 of 2 missions cannot be evaluated; no episode runs"
    [error] = said["errors"]
    assert (error["file"], error["line"], error["column"]) == (missing, None, None)
    assert error["message"].startswith("no such mission file")
    warned = tmp_path / "w1.yaml"
    warned.write_text("tree:\n  sequence:\n    - mode: full\n"
                      "    - drive: {velocity: 100 mm/s, duration: 1s}\n")  # fmt: skip
    assert main(["eval", str(warned), *options, "--strict"]) == ExitCode.STRICT
    said = json.loads(capsys.readouterr().out)
    assert said["error"] == f"{warned}: failed --strict (1 warning); no episode runs"
    [warning] = said["errors"]
    assert (warning["line"], warning["column"], warning["severity"]) == (4, 7, "warning")


def test_json_names_the_world_file_asked_for_and_each_of_its_problems_places(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``--json``'s refusal for a world not found listed no error at all, and a mission not
    found had ``"file": null``: a script could not tell which file to fix. Each error names
    the file asked for now, as ``validate --format json`` does, and a world's problems come
    each at its line and column."""
    missing = str(tmp_path / "nowhere.yaml")
    options = ["--runs", "1", "--no-progress", "--json"]
    assert main(["eval", BUMP, "--world", missing, *options]) == 2
    [error] = json.loads(capsys.readouterr().out)["errors"]
    assert (error["file"], error["line"], error["column"]) == (missing, None, None)
    assert error["message"].startswith("world: found no such file or shipped world")
    broken = tmp_path / "broken.yaml"
    broken.write_text("name: broken\nrooms: 3\n")
    assert main(["eval", BUMP, "--world", str(broken), *options]) == 2
    [error] = json.loads(capsys.readouterr().out)["errors"]
    assert (error["file"], error["line"], error["column"]) == (str(broken), 2, 8)
    assert error["message"] == "rooms: found 3; allowed: a list"


def test_json_says_why_when_no_mission_is_found_or_an_option_is_wrong(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Refusals before any mission compiles (every mission missing, a number out of range)
    left stdout empty under ``--json`` as well; each is an object now, exit 2."""
    missing = [str(tmp_path / "a.yaml"), str(tmp_path / "b.yaml")]
    assert main(["eval", *missing, "--runs", "1", "--no-progress", "--json"]) == 2
    said = json.loads(capsys.readouterr().out)
    assert said["error"] == "2 of 2 missions cannot be evaluated; no episode runs"
    assert [e["file"] for e in said["errors"]] == missing
    assert all(e["message"].startswith("no such mission file") for e in said["errors"])
    assert main(["eval", BUMP, "--runs", "0", "--no-progress", "--json"]) == 2
    said = json.loads(capsys.readouterr().out)
    assert said == {"error": "--runs 0: expected 1..1,000,000 (more: several evaluations)",
                    "errors": []}  # fmt: skip


def test_a_mission_given_twice_is_evaluated_once(capsys: pytest.CaptureFixture[str]) -> None:
    """``eval dock.yaml ./dock.yaml`` ran an A/B of the file against itself, and ``eval dock
    dock`` refused "the same variant twice": each file once now, the other warned about."""
    again = str(MISSIONS / ".." / "missions" / "bump-and-turn.yaml")
    assert main(["eval", BUMP, again, "--runs", "1", "--no-progress"]) == 0
    out, err = capsys.readouterr()
    assert f"roomba-bt eval: warning: {again} is {BUMP} again: evaluated once" in err
    assert "A/B" not in out and out.count("mission      ") == 1
    assert main(["eval", BUMP, BUMP, "--runs", "1", "--no-progress"]) == 0
    out, err = capsys.readouterr()
    assert f"roomba-bt eval: warning: {BUMP} is given twice: evaluated once" in err
    assert "A/B" not in out


def test_a_cleaning_mission_reports_its_coverage_as_json(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    import json

    from roomba_bt.evaluate.coverage import summarize_coverage
    from roomba_bt.evaluate.records import read_results

    out_file = tmp_path / "clean.csv"
    argv = ["eval", str(MISSIONS / "clean.yaml"), "--world", "apartment", "--runs", "2",
            "--seed", "8", "--timeout", "40s", "--no-progress", "--json",
            "--out", str(out_file)]  # fmt: skip
    assert main(argv) in (0, 1)
    (variant,) = json.loads(capsys.readouterr().out)["variants"]
    coverage = summarize_coverage(read_results(out_file))
    assert coverage is not None and variant["coverage"] == tidy(coverage.to_dict())
    assert variant["coverage"]["episodes"] == 2 and 0 < variant["coverage"]["final"]["mean"] < 1


def test_a_behaviour_that_raises_in_an_episode_exits_4(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A plugin's exception is a bug, not a mission outcome: eval says which episode and how
    to see the traceback, and exits 4 as `run` does (it used to exit 0)."""
    (tmp_path / "boom.py").write_text(
        "from roomba_bt.behaviours import Condition, declare\n\n\n"
        '@declare("boom", kind="condition", reads=(27,))\n'
        "class Boom(Condition):\n"
        '    """Raises."""\n\n'
        "    def check(self, snapshot):\n"
        '        raise RuntimeError("kaboom")\n'
    )
    mission = tmp_path / "boom.yaml"
    mission.write_text("plugins: [./boom.py]\ntree:\n  sequence:\n    - boom\n")
    code = main(["eval", str(mission), "--runs", "2", "--seed", "3", "--allow-plugin-files",
                 "--no-progress"])  # fmt: skip
    err = capsys.readouterr().err
    assert code == 4
    assert "2 episode(s) ended with a behaviour's exception" in err
    assert "seed 3: " in err and "kaboom" in err and "boom.py:9" in err
    assert (f"roomba-bt -v run {mission} --fast --random-start --seed 3 --timeout 900 "
            "--allow-plugin-files") in err  # fmt: skip


def test_the_line_an_error_says_to_run_runs_that_episode_again_with_its_traceback(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """It said ``roomba-bt run M --fast --seed N -v``: ``-v`` after the command is refused,
    and without the seeded start, the world, ``-p`` and ``--allow-plugin-files`` it was
    another episode, or none."""
    (tmp_path / "odd.py").write_text(
        "from roomba_bt.behaviours import Condition, declare\n\n\n"
        '@declare("odd", kind="condition", reads=(43,))\n'
        "class Odd(Condition):\n"
        '    """Raises on some encoder counts: where depends on the start."""\n\n'
        "    def check(self, snapshot):\n"
        "        if snapshot.frame[43] % 7 == 3:\n"
        '            raise RuntimeError("odd count")\n'
        "        return False\n"
    )
    mission = tmp_path / "odd.yaml"
    mission.write_text(
        "plugins: [./odd.py]\nparameters: {speed: {type: speed, default: 100 mm/s}}\n"
        "tree:\n  sequence:\n    - mode: safe\n"
        "    - drive: {velocity: '${speed}', distance: 40 cm}\n      until: odd\n"
    )
    code = main(["eval", str(mission), "--runs", "4", "--seed", "5", "--world", "corridor",
                 "-p", "speed=250mm/s", "--allow-plugin-files", "--timeout", "2min",
                 "--odometry-error", "0.01", "--no-progress"])  # fmt: skip
    err = capsys.readouterr().err
    assert code == 4
    reason = err.split(": seed ", 1)[1].split(": ", 1)[1].split("; see its traceback with: ")[0]
    line = err.rsplit("see its traceback with: ", 1)[1].strip()
    assert "--world corridor" in line and "-p speed=250mm/s" in line
    # the limit and the encoders' error too (session 35: run's own limit applied, and the
    # line said run had no --odometry-error, which it has)
    assert "--timeout 120 --odometry-error 0.01" in line and "may differ" not in line
    words = shlex.split(line)
    assert words[:2] == ["roomba-bt", "-v"]
    assert main(words[1:]) == 4
    out, err = capsys.readouterr()
    assert f"outcome      ERROR ({reason})" in out
    assert "Traceback (most recent call last)" in err


def test_no_more_workers_than_episodes_are_started(capsys: pytest.CaptureFixture[str]) -> None:
    code = main(["eval", BUMP, "-p", "duration=1s", "--runs", "2", "--jobs", "16",
                 "--no-progress"])  # fmt: skip
    assert code == 0
    assert "engine       2 local processes;" in capsys.readouterr().out


def test_a_world_with_one_start_pose_is_said_to_run_one_episode_many_times(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The seed draws the start: without a start region (nor --within, --start-area), every
    episode ran alike and the report gave an interval as if they were independent."""
    world = tmp_path / "one-start.yaml"
    world.write_text(
        "rooms:\n  - [[0, 0], [3, 0], [3, 3], [0, 3]]\n"
        "robot: {start: {at: [1.5, 1.5], heading: 0}}\n"
    )
    argv = ["eval", BUMP, "-p", "duration=1s", "--world", str(world), "--no-progress"]
    assert main([*argv, "--runs", "3"]) == 0
    err = capsys.readouterr().err
    assert "has no robot.start_region" in err and "all 3 episodes start at (1.50, 1.50) m" in err
    assert main([*argv, "--runs", "1"]) == 0  # one episode: nothing to say
    assert "start_region" not in capsys.readouterr().err
    assert main(["eval", BUMP, "-p", "duration=1s", "--runs", "2", "--no-progress"]) == 0
    assert "start_region" not in capsys.readouterr().err  # the shipped worlds have one


def test_episodes_whose_robot_switched_off_are_failures_not_log_lines(
    capsys: pytest.CaptureFixture[str], caplog: pytest.LogCaptureFixture
) -> None:
    """A flat battery switches the simulated robot off: each episode ends as a lost
    connection, said once in the grouped failures, with no per-episode ERROR line."""
    code = main(["eval", BUMP, "--world", "corridor", "--battery", "0.0002", "--runs", "2",
                 "--no-progress"])  # fmt: skip
    assert code == 0  # an evaluation that ran (--min-rate makes a low rate exit 1)
    out, err = capsys.readouterr()
    assert "2  CONNECTION LOST:" in out and "most likely a flat battery" in out
    assert "unconfirmed" not in err
    assert not [r for r in caplog.records if r.name.startswith("roomba_bt")]


def test_a_killed_evaluation_leaves_the_records_it_finished(tmp_path: Path) -> None:
    """The records were written only at the end: a sweep the OOM killer or a kill -9 ended
    lost them all. Now each is in OUT.partial.jsonl as it finishes (removed once OUT is
    written)."""
    import signal
    import subprocess
    import time

    from roomba_bt.evaluate.records import read_results

    out = tmp_path / "sweep.csv"
    proc = subprocess.Popen(
        [sys.executable, "-m", "roomba_bt.cli", "eval", str(MISSIONS / "dock.yaml"),
         "--runs", "200", "--within", "1.5", "--out", str(out)],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE,
    )  # fmt: skip
    partial = tmp_path / "sweep.csv.partial.jsonl"
    deadline = time.monotonic() + HANG_S
    while not (partial.exists() and partial.read_text().count("\n") >= 2):
        assert proc.poll() is None and time.monotonic() < deadline, "no records as it ran"
        time.sleep(0.01)  # a poll for a file another process writes: no event to wait on
    proc.send_signal(signal.SIGKILL)
    proc.communicate(timeout=HANG_S)
    assert not out.exists()
    kept = read_results(partial)
    assert len(kept) >= 2 and [r.seed for r in kept[:2]] == [0, 1]


def test_a_finished_evaluation_leaves_no_partial_file(tmp_path: Path) -> None:
    out = tmp_path / "r.jsonl"
    assert main(["eval", BUMP, "-p", "duration=1s", "--runs", "2", "--no-progress",
                 "--out", str(out)]) == 0  # fmt: skip
    assert len(out.read_text().splitlines()) == 2
    assert sorted(p.name for p in tmp_path.iterdir()) == ["r.jsonl"]


def test_more_jobs_than_cores_is_warned_about(
    capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """--jobs 500 on 2 cores ran 500 processes without a word."""
    import os

    monkeypatch.setattr(os, "sched_getaffinity", lambda pid: {0}, raising=False)
    monkeypatch.setattr(os, "cpu_count", lambda: 1)
    assert main(["eval", BUMP, "-p", "duration=1s", "--runs", "2", "--jobs", "2",
                 "--no-progress"]) == 0  # fmt: skip
    assert "warning: --jobs 2 on 1 core(s)" in capsys.readouterr().err
    assert main(["eval", BUMP, "-p", "duration=1s", "--runs", "2", "--no-progress"]) == 0
    assert "warning: --jobs" not in capsys.readouterr().err


_SOMETIMES = '''\
from py_trees.common import Status

from roomba_bt.behaviours import Action, declare, write_key

STARTS = []


@declare("sometimes_writer", kind="action")
class SometimesWriter(Action):
    """Writes a key the mission does not declare, in every other episode of this process."""

    def start(self):
        STARTS.append(1)

    def update(self):
        if len(STARTS) % 2:
            write_key("secret", 5, self.name)
        return Status.SUCCESS
'''


def test_an_undeclared_key_written_is_said_once_with_its_episodes(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``run`` warns of a write to a key the mission does not declare; an episode's log is
    silenced, and the warning was said in no episode of an evaluation (or, unsilenced, once
    in each). Said once per variant, with the episodes it was written in, in the summary and
    in ``--json``. In this process (``--wall-limit none``) the plugin counts the episodes."""
    plugin = tmp_path / "sometimes.py"
    plugin.write_text(_SOMETIMES)
    mission = tmp_path / "sometimes.yaml"
    mission.write_text("plugins: [./sometimes.py]\nblackboard:\n  x: int\n"
                       "tree:\n  sequence:\n    - sometimes_writer\n")  # fmt: skip
    words = ["eval", str(mission), "--runs", "4", "--allow-plugin-files", "--no-progress",
             "--wall-limit", "none"]  # fmt: skip
    assert main(words) == 0
    out = capsys.readouterr().out
    said = (
        f"write_key('secret') by 'sometimes_writer' at {plugin}:17: blackboard key 'secret' is "
        "not declared by the mission, in 2 of 4 episodes; declare it under blackboard: "
        "(secret: {type: ...}), or name a declared key in a parameter listed in writes_keys"
    )
    assert out.count("write_key(") == 1 and f"warning      {said}\n" in out, out
    assert main([*words, "--json"]) == 0
    (variant,) = json.loads(capsys.readouterr().out)["variants"]
    assert variant["undeclared_keys"] == [
        {"key": "secret", "written": f"by 'sometimes_writer' at {plugin}:17", "episodes": 2,
         "did_you_mean": None}
    ]  # fmt: skip


def test_a_misspelt_key_is_said_with_its_did_you_mean_as_run_says_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``run``'s summary says ``write_key('dirt_levl') ... (did you mean 'dirt_level'?)``;
    ``eval``'s said the same warning without it (an episode's log is silenced, and its
    result kept no declared key). Said in the summary, ``--json`` and again from the
    records (``eval --from``: the ``undeclared_like`` column)."""
    plugin = tmp_path / "sometimes.py"
    plugin.write_text(_SOMETIMES.replace('"secret"', '"dirt_levl"'))
    mission = tmp_path / "sometimes.yaml"
    mission.write_text("plugins: [./sometimes.py]\nblackboard:\n  dirt_level: int\n"
                       "tree:\n  sequence:\n    - sometimes_writer\n")  # fmt: skip
    out_file = tmp_path / "r.jsonl"
    words = ["eval", str(mission), "--runs", "2", "--allow-plugin-files", "--no-progress",
             "--wall-limit", "none", "--out", str(out_file)]  # fmt: skip
    assert main(words) == 0
    said = (
        f"warning      write_key('dirt_levl') by 'sometimes_writer' at {plugin}:17: blackboard "
        "key 'dirt_levl' is not declared by the mission (did you mean 'dirt_level'?), in 1 of 2 "
        "episodes; declare it under blackboard: (dirt_levl: {type: ...}), or name a declared "
        "key in a parameter listed in writes_keys\n"
    )
    assert said in capsys.readouterr().out
    records = [json.loads(line) for line in out_file.read_text().splitlines()]
    assert [r["undeclared_like"] for r in records] == [{"dirt_levl": "dirt_level"}, {}]
    assert main(["eval", "--from", str(out_file)]) == 0
    assert said in capsys.readouterr().out
    assert main(["eval", "--from", str(out_file), "--json"]) == 0
    (variant,) = json.loads(capsys.readouterr().out)["variants"]
    assert variant["undeclared_keys"][0]["did_you_mean"] == "dirt_level"


_ROGUE = '''\
from py_trees.common import Status

from roomba_bt.behaviours import Action, declare
from roomba_bt.oi import commands


@declare("rogue", kind="action")
class Rogue(Action):
    """Queues Drive straight into the outbox, the robot in Passive: refused."""

    def update(self):
        self.robot.outbox.send(commands.drive(100, 0), self)
        return Status.SUCCESS
'''


def test_a_plugin_s_refused_action_is_told_once_with_its_episodes(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``run``'s stderr names an action of the user's own code whose commands the mode
    guard refused, and the fix; ``eval``'s summary said nothing of it. Said once per
    variant, with its episodes, in the summary, ``--json`` and the results file, which
    ``--from`` reads back and says again."""
    plugin = tmp_path / "rogue.py"
    plugin.write_text(_ROGUE)
    mission = tmp_path / "rogue.yaml"
    mission.write_text("plugins: [./rogue.py]\ntree:\n  sequence: [rogue]\n")
    results = tmp_path / "out.jsonl"
    words = ["eval", str(mission), "--runs", "2", "--allow-plugin-files", "--no-progress"]
    assert main([*words, "--out", str(results)]) == 0
    out = capsys.readouterr().out
    said = (
        f"warning      the mode guard refused commands of rogue (Rogue ({plugin}:7)), your "
        "code, in 2 of 2 episodes: an action that drives checks self.snapshot.mode each tick "
        "and, out of Safe/Full, returns self.wait_for_driving_mode() (roomba-bt docs plugins, "
        "When the robot leaves Safe/Full under your action)\n"
    )
    assert out.count("refused commands of") == 1 and said in out, out
    assert main([*words, "--json"]) == 0
    (variant,) = json.loads(capsys.readouterr().out)["variants"]
    assert variant["refused_actions"] == [
        {"action": "rogue", "where": f"Rogue ({plugin}:7)", "episodes": 2}
    ]
    rows = [json.loads(line) for line in results.read_text().splitlines()]
    assert [row["refused_actions"] for row in rows] == [{"rogue": f"Rogue ({plugin}:7)"}] * 2
    assert main(["eval", "--from", str(results), "--no-progress"]) == 0
    assert said in capsys.readouterr().out


def test_a_sweep_of_a_hundred_thousand_episodes_holds_little_before_the_first_runs(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """Every episode's spec was made before the first ran: ``--runs 100000`` of an A/B held
    75 MB of objects (and each worker forked from it) before its first result. They are made
    as they run: what ``eval`` holds when it hands them to the engine is the same for
    100 000 as for 10, and the engine is given each variant's 100 000 in seed order."""
    import tracemalloc

    from roomba_bt.evaluate import parallel

    held: list[int] = []
    seeds: list[list[int]] = []

    def at_the_engine(batches, engine, progress, labels):  # type: ignore[no-untyped-def]
        held.append(tracemalloc.get_traced_memory()[0])
        seeds.append([len(batch) for batch in batches] + [batches[-1][-1].seed])
        stopped = parallel.Interruption("SIGINT", "by Ctrl-C (SIGINT)")
        return [parallel.Evaluation([], 0, True, "local", stopped) for _ in batches]

    monkeypatch.setattr(parallel, "evaluate", at_the_engine)
    for runs in ("10", "100000"):
        tracemalloc.start()
        try:
            argv = ["eval", BUMP, "--sweep", "duration=1s,2s", "--runs", runs, "--seed", "5"]
            assert main([*argv, "--no-progress"]) == 130
        finally:
            tracemalloc.stop()
    capsys.readouterr()
    assert seeds[1] == [100_000, 100_000, 100_004]
    assert held[1] < held[0] + 1_000_000, held  # 73 MB more before


def test_the_text_report_says_the_faults_and_the_frames_they_lost(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``--byte-drop-rate`` and the like were said only in ``--json``'s conditions, and the
    frames the line lost nowhere: a report of a bad cable read as the mission's own. The
    text says both (the frames per variant, read back from the records too); a run without
    a fault says neither."""
    out_file = tmp_path / "r.csv"
    argv = ["eval", "dock", "--runs", "2", "--within", "1.5", "--no-progress"]
    assert main([*argv, "--byte-drop-rate", "0.01", "--odometry-error", "0.02",
                 "--out", str(out_file)]) == 0  # fmt: skip
    out = capsys.readouterr().out
    faults = ("faults       --byte-drop-rate 0.01 --odometry-error 0.02 (in every episode, each "
              "drawing from its own seed)\n")  # fmt: skip
    assert faults in out
    frames = [line for line in out.splitlines() if line.startswith("frames ")]
    assert len(frames) == 1 and " lost in 2 of 2 episodes (" in frames[0], out
    assert main(["eval", "--from", str(out_file)]) == 0
    assert frames[0] in capsys.readouterr().out.splitlines()
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert "faults " not in out and "frames " not in out
