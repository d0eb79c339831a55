"""An evaluation's progress bars as a user sees them: on a terminal (what stays on the screen,
read through a small emulator of the few codes the bars write), in a log, and resumed."""

from __future__ import annotations

import io
import re
from pathlib import Path

import pytest

from roomba_bt.cli import main
from roomba_bt.evaluate.episode import EpisodeResult

from .terminal import Terminal, a_terminal_that_takes_codes

pytestmark = pytest.mark.usefixtures(a_terminal_that_takes_codes.__name__)

MISSIONS = Path(__file__).resolve().parents[2] / "missions"
BUMP = str(MISSIONS / "bump-and-turn.yaml")
_AB = ["eval", BUMP, "--sweep", "duration=1s,2s", "--runs", "6", "--jobs", "1",
       "--wall-limit", "none", "--timeout", "10s"]  # fmt: skip


def screen(written: str) -> list[str]:
    """The lines a terminal shows after ``written``: text, ``\\r``, ``\\n``, and the ANSI
    codes the bars use (EL ``ESC[K``, CPL ``ESC[nF``, ED ``ESC[J``); any other is an error."""
    lines, row, col = [""], 0, 0
    for token in re.findall(r"\x1b\[\d*[A-Za-z]|\r|\n|[^\x1b\r\n]+", written):
        if token == "\r":
            col = 0
        elif token == "\n":
            row, col = row + 1, 0
            lines += [""] * (row + 1 - len(lines))
        elif token.startswith("\x1b["):
            code, count = token[-1], int(token[2:-1] or 1)
            if code == "K":
                lines[row] = lines[row][:col]
            elif code == "F":
                row, col = max(0, row - count), 0
            elif code == "J":
                lines[row] = lines[row][:col]
                del lines[row + 1 :]
            else:
                raise AssertionError(f"unexpected terminal code {token!r}")
        else:
            line = lines[row].ljust(col)
            lines[row] = line[:col] + token + line[col + len(token) :]
            col += len(token)
    return lines


def _result(outcome: str) -> EpisodeResult:
    """An episode's result as a bar reads it: its outcome (the rest does not matter)."""
    return EpisodeResult(seed=1, outcome=outcome, reason="", time_s=1.0, wall_s=0.1, ticks=1,
                         start=(0, 0, 0), end=(0, 0, 0), bumps=0, contact_steps=(),
                         docked=False, charging=False, cliffs=0, fell=False, violations=0,
                         loops=0.0, longest_stall_s=0.0)  # fmt: skip


def _bars(lines: list[str]) -> list[str]:
    return [line for line in lines if "[" in line and "] " in line and " ok " in line]


def test_an_a_b_s_bars_each_keep_a_line_of_their_own_on_a_terminal(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """The two variants' bars were redrawn with a carriage return on the one line, taking
    turns there (a flicker no one could read, and at the end one of them was left). Each now
    keeps a line, redrawn in place, both there after every episode and at the end."""
    terminal = Terminal()
    monkeypatch.setattr("sys.stderr", terminal)
    monkeypatch.setattr("roomba_bt.evaluate.progress.REDRAW_S", 0.0)  # each episode drawn
    monkeypatch.setenv("COLUMNS", "80")  # the terminal's size (it has no file to ask)
    monkeypatch.setenv("LINES", "24")
    assert main(_AB) == 0
    written = terminal.getvalue().split("variant ")[0]  # the bars, before the report
    shown = _bars(screen(written))
    assert [line.split(" [")[0].split()[-2:] for line in shown] == [
        ["-p", "duration=1s"],
        ["-p", "duration=2s"],
    ], shown
    assert all(" 6/6 ok " in line for line in shown), shown
    # the label is the report's, the mission's whole path: on this 80-column terminal its
    # start is left out, not the count and ETA at the line's end
    assert all(line.startswith("...") and line.endswith(" ETA 0s") for line in shown), shown
    # after each episode, not only at the end: the screen holds both bars, one above the other
    cut = [m.end() for m in re.finditer(re.escape("\x1b[K"), written)]
    for end in cut[1::2]:
        assert len(_bars(screen(written[:end]))) == 2, screen(written[:end])


def test_an_a_b_s_progress_in_a_log_is_a_few_lines_without_terminal_codes(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """Into a pipe (a CI log), each variant's bar wrote a line at each tenth of its own: 22
    lines for an A/B, ten times that for a sweep of ten. One line now, at the first episode,
    each tenth of the whole and the last, every variant's count on it; no control code."""
    assert main([*_AB[:5], "10", *_AB[6:]]) == 0
    err = capsys.readouterr().err
    assert "\r" not in err and "\x1b" not in err
    lines = [line for line in err.splitlines() if " ok " in line and "] " in line]
    assert 2 <= len(lines) <= 12, lines
    assert lines[-1].startswith("[#") and " 20/20 ok " in lines[-1]
    assert f"{BUMP} -p duration=1s 10/10 ok" in lines[-1]
    assert f"{BUMP} -p duration=2s 10/10 ok" in lines[-1]


def test_a_resumed_evaluation_s_bars_count_the_episodes_read_back(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``--resume`` after 3 of 6 seeds a variant: the bars counted only what was left (``1/3``
    to ``3/3``), as if the sweep had started again; they go on from ``4/6`` to ``6/6``."""
    out = str(tmp_path / "ab.jsonl")
    first = [*_AB[:5], "3", *_AB[6:], "--out", out]
    assert main(first) == 0
    capsys.readouterr()
    assert main([*_AB, "--out", out, "--resume"]) == 0
    err = capsys.readouterr().err
    lines = [line for line in err.splitlines() if " ok " in line and "] " in line]
    assert " 7/12 ok " in lines[0], lines  # the first episode run now: 6 read back, and it
    assert " 12/12 ok " in lines[-1], lines
    assert "duration=1s 6/6 ok" in lines[-1] and "duration=2s 6/6 ok" in lines[-1]
    assert not any("/3 ok" in line or "/6 ok" in line.split(": ")[0] for line in lines), lines


def test_a_message_said_while_the_bars_are_drawn_takes_their_place_on_its_own_line() -> None:
    """A worker's death said on stderr while the bars were drawn began mid-line, glued to the
    last bar's text. The bars are taken away first, the message
    takes their place and they are drawn again below it."""
    from roomba_bt.evaluate import progress

    terminal = Terminal()
    bars = progress.ProgressBars(["a", "b"], [4, 4], stream=terminal, interval_s=0.0)
    result = _result("success")
    bars.bar(0)(1, 4, result)
    bars.bar(1)(1, 4, result)
    import contextlib

    with contextlib.redirect_stderr(terminal):
        progress.say("roomba-bt eval: a worker process died: killed by SIGKILL")
    bars.bar(0)(2, 4, result)
    shown = screen(terminal.getvalue())
    assert shown[0] == "roomba-bt eval: a worker process died: killed by SIGKILL", shown
    assert [line.split()[0] for line in shown[1:]] == ["a", "b"], shown
    assert " 2/4 ok 2 " in shown[1] and " 1/4 ok 1 " in shown[2]


def test_a_resumed_variant_yet_to_run_an_episode_says_no_eta() -> None:
    """A variant whose episodes so far were all read back said ``ETA 0s`` beside its
    ``162/1000``: nothing of it had run to tell its pace. It says ``ETA ?`` until one has;
    a variant with none left says ``ETA 0s``."""
    from roomba_bt.evaluate import progress

    log = io.StringIO()
    bars = progress.ProgressBars(["a", "b", "c"], [10, 10, 4], stream=log,
                                 already=[(4, 4), (4, 4), (4, 3)])  # fmt: skip
    result = _result("failure")
    bars.bar(0)(1, 6, result)
    lines = bars._lines(elapsed=3.0, width=10)
    assert lines[0].startswith("a [") and lines[0].endswith("] 5/10 ok 4 elapsed 3s ETA 15s")
    assert lines[1].endswith("] 4/10 ok 4 elapsed 3s ETA ?"), lines
    assert lines[2].endswith("] 4/4 ok 3 elapsed 3s ETA 0s"), lines
    assert log.getvalue().count("\n") == 1 and "13/24 ok 11" in log.getvalue()


def test_a_log_gets_a_line_after_a_while_without_one(monkeypatch: pytest.MonkeyPatch) -> None:
    """Into a log, a line came only at each tenth of the whole: half an hour apart in a
    100 000-episode sweep, and a CI service that ends a job silent for 10 minutes ended it.
    A line also comes after ``LOG_EVERY_S`` without one (here 0: after each episode)."""
    from roomba_bt.evaluate import progress

    result = _result("success")
    counted = []
    for every in (300.0, 0.0):
        monkeypatch.setattr(progress, "LOG_EVERY_S", every)
        log = io.StringIO()
        bars = progress.ProgressBars(["a"], [1000], stream=log)
        for _ in range(50):
            bars.bar(0)(0, 0, result)
        counted.append(log.getvalue().count("\n"))
    assert counted == [1, 50]


def test_a_dumb_terminal_gets_a_log_s_lines(monkeypatch: pytest.MonkeyPatch) -> None:
    """``TERM=dumb`` (an editor's shell buffer) shows ANSI codes as text: the bars wrote
    ``ESC[K`` and carriage returns there. It gets a log's lines, no code."""
    from roomba_bt.evaluate import progress

    monkeypatch.setenv("TERM", "dumb")
    terminal = Terminal()
    bars = progress.ProgressBars(["a", "b"], [3, 3], stream=terminal)
    single = progress.ProgressBar(terminal, label="c ")
    for b in (0, 1, 0, 1, 0, 1):
        bars.bar(b)(0, 0, _result("success"))
    single(1, 1, _result("success"))
    assert "\x1b" not in terminal.getvalue() and "\r" not in terminal.getvalue()
    assert terminal.getvalue().splitlines()[-2].endswith("a 3/3 ok 3, b 3/3 ok 3")


def test_more_variants_than_the_terminal_has_lines_share_one_line(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A sweep of more values than the terminal shows lines: the cursor cannot go up past
    the screen's top, and each redraw of the block wrote a new one under the last. They
    share one line then, every variant's count on it, redrawn in place."""
    from roomba_bt.evaluate import progress

    monkeypatch.setenv("LINES", "5")
    monkeypatch.setenv("COLUMNS", "400")
    terminal = Terminal()
    names = [f"v{i}" for i in range(6)]
    bars = progress.ProgressBars(names, [2] * 6, stream=terminal, interval_s=0.0)
    for _ in range(2):
        for b in range(6):
            bars.bar(b)(0, 0, _result("success"))
    shown = [line for line in screen(terminal.getvalue()) if line]
    assert len(shown) == 1, shown
    assert shown[0].startswith("[") and " 12/12 ok 12 " in shown[0]
    assert shown[0].endswith(", ".join(f"{name} 2/2 ok 2" for name in names))


def test_a_run_on_dask_counts_its_finished_episodes_as_they_come() -> None:
    """Each result on Dask told the bar how many had finished by counting them again over
    the whole list (at 100 000 episodes, 5 billion looks in the submitting process). The
    count is kept as they come: the list is never read through."""
    from roomba_bt.evaluate.cluster import _Finished

    class Unread(list):  # type: ignore[type-arg]
        def __iter__(self):  # type: ignore[no-untyped-def]
            raise AssertionError("the results were read through to count them")

    told: list[tuple[int, int]] = []
    finished = _Finished(Unread([None] * 4), lambda done, total, _: told.append((done, total)))
    for i in (2, 0, 0, 3):  # the same episode twice (run again alone): counted once
        finished(i, _result("success"))
    finished(1, None)  # cancelled: not finished
    assert told == [(1, 4), (2, 4), (2, 4), (3, 4)]
