"""What a user sees: the sensor line, the live tree, one log line per status change."""

from __future__ import annotations

import gc
import io
import logging
import threading
import weakref
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import py_trees
import pytest
from waits import HANG_S, joined, waited  # tests/waits.py: a hang's bound, no fixed bet

from roomba_bt.oi.modes import OIMode
from roomba_bt.robot.testing import StubRobot
from roomba_bt.runtime.display import (
    MissionClockFormatter,
    OffTickHandler,
    OffTickWriter,
    StatusChangeLogger,
    TerminalDisplay,
    fitted_tree,
    live_names,
    logging_off_the_tick,
    observer_for,
    sensor_line,
    sensor_lines,
    text_tree,
    use_mission_clock,
)
from roomba_bt.runtime.loop import MissionRunner

from .simrun import RunMission


@pytest.fixture(autouse=True)
def _writers_closed(monkeypatch: pytest.MonkeyPatch) -> Iterator[None]:
    """Each :class:`OffTickWriter` a test made (a :class:`TerminalDisplay`'s too) is closed
    after it: its thread waits for text until then, and was left running, one a display
    (tests/conftest.py's ``Leftovers`` said so)."""
    made: weakref.WeakSet[OffTickWriter] = weakref.WeakSet()  # a dropped one ends by itself
    made_by = OffTickWriter.__init__

    def making(writer: OffTickWriter, *args: Any, **kwargs: Any) -> None:
        made_by(writer, *args, **kwargs)
        made.add(writer)

    monkeypatch.setattr(OffTickWriter, "__init__", making)
    yield
    for writer in made:
        writer.close(0)


DRIVE = """
tree:
  sequence:
    - mode: safe
    - drive: {velocity: 200 mm/s, distance: 10 cm}
"""

NAMED = """
tree:
  sequence:
    - mode: safe
    - timeout:
        after: 5s
        do:
          drive: {velocity: 200 mm/s, distance: 10 cm}
          name: gentle
"""


def test_sensor_line_names_bumps_cliffs_ir_and_charger() -> None:
    stub = StubRobot()
    snap = stub.set_frame(
        {7: 0b0110, 9: 1, 10: 0, 11: 0, 12: 1, 17: 172, 52: 0, 53: 0, 34: 2, 25: 1000,
         26: 2000, 35: 2},
    )  # fmt: skip
    line = sensor_line(snap)
    assert "mode=Safe" in line
    assert "bump=L" in line  # bit 1: bump left
    assert "drop=R" in line  # bit 2: wheel drop right
    assert "cliff=LR" in line
    assert "ir=172(RG)" in line
    assert "charger=home" in line
    assert "battery=50%" in line


def test_status_changes_are_logged_once_each(
    run_mission: RunMission, caplog: pytest.LogCaptureFixture
) -> None:
    caplog.set_level(logging.INFO, logger="roomba_bt.run")
    logger = StatusChangeLogger()
    run = run_mission(DRIVE)
    # Replay the statuses the finished run left: a fresh logger reports each node once.
    logger(run.runner)
    lines = [r.getMessage() for r in caplog.records if r.name == "roomba_bt.run"]
    assert any("sequence -> SUCCESS" in line for line in lines)
    assert any("drive" in line and line.endswith("-> SUCCESS") for line in lines), lines
    logger(run.runner)  # nothing changed: nothing more is logged
    assert len([r for r in caplog.records if r.name == "roomba_bt.run"]) == len(lines)


def test_terminal_display_draws_the_tree_with_statuses(run_mission: RunMission) -> None:
    run = run_mission(DRIVE)
    out = _Terminal()
    display = TerminalDisplay(out)
    display.render(run.runner)
    assert display.writer.wait_written(HANG_S)  # written off the tick loop, by its own thread
    text = out.getvalue()
    assert text.startswith("\x1b[H\x1b[J")
    assert "sequence" in text and "drive" in text
    assert "✓" in text
    assert f"mode={OIMode.PASSIVE.label}" in text or "mode=Safe" in text


def test_the_live_tree_names_each_node_as_the_printed_trees_do(run_mission: RunMission) -> None:
    """The trees printed before and after a run say ``show``'s names (``timeout(after=5s)``),
    while the live tree between them said the nodes' own (``timeout``): two trees for one.
    A node renamed by ``name:`` keeps that name live (``gentle``): ``show``'s ``drive(...)
    named 'gentle'`` is for reviewing it, and a long one pushed the status off the line."""
    run = run_mission(NAMED)
    out = _Terminal()
    display = TerminalDisplay(out, size=lambda: (120, 24))
    display.render(run.runner)
    assert display.writer.wait_written(HANG_S)
    assert "-^- timeout(after=5s) [" in out.getvalue(), out.getvalue()  # its drive folded in
    names = live_names(run.runner.mission)
    assert names is not None
    assert sorted(names.values()) == ["gentle", "mode(safe)", "sequence", "timeout(after=5s)"]


def test_the_live_tree_and_the_log_lines_say_the_run_s_label(
    run_mission: RunMission, caplog: pytest.LogCaptureFixture
) -> None:
    """Several runs in several terminals of one laptop could be told apart only by their
    ports: ``run --label`` is the live tree's first line and on each log line."""
    run = run_mission(DRIVE)
    out = _Terminal()
    display = TerminalDisplay(out, label="robot 3")
    display.render(run.runner)
    assert display.writer.wait_written(HANG_S)
    assert out.getvalue().startswith("\x1b[H\x1b[Jrobot 3\n")
    record = logging.LogRecord("roomba_bt.run", logging.INFO, "", 0, "drive -> RUNNING", (), None)
    use_mission_clock(run.runner, label="robot 3")
    try:
        assert "[robot 3] INFO roomba_bt.run: drive -> RUNNING" in MissionClockFormatter().format(
            record
        )
    finally:
        use_mission_clock(None)
    assert "[robot 3]" not in MissionClockFormatter().format(record)  # the run's alone


def test_a_run_s_log_line_is_never_stamped_before_the_line_above_it(
    run_mission: RunMission,
) -> None:
    """A stall's lines read the link's clock past the last frame; the frames back count its
    slots only once the schedule has judged them, and a line meanwhile read less: 't=4.305
    ... frames are back' and then 't=4.240 ... no valid sensor frame'. A run's lines keep
    the stamp of the line above until its clock passes it; the next run starts afresh."""
    run = run_mission(DRIVE)

    def line(at: float) -> str:
        record = logging.LogRecord("roomba_bt.run", logging.INFO, "", 0, "x", (), None)
        record.mission_time = at
        return MissionClockFormatter().format(record).split()[0]

    use_mission_clock(run.runner)
    try:
        assert [line(at) for at in (4.305, 4.240, 4.3, 4.5)] == [
            "t=4.305", "t=4.305", "t=4.305", "t=4.500"
        ]  # fmt: skip
        use_mission_clock(run.runner)  # another run's clock
        assert line(1.0) == "t=1.000"
    finally:
        use_mission_clock(None)
    assert line(0.5) == "t=0.500"  # no run's clock: each line its own time


LONG = """
tree:
  sequence:
    - mode: safe
""" + "".join(
    f"""    - sequence:
        - wait: 0.05s
        - drive: {{velocity: 100 mm/s, distance: {i + 1} mm}}
"""
    for i in range(30)
)


def test_the_live_tree_fits_the_terminal_and_keeps_the_running_path(
    run_mission: RunMission,
) -> None:
    """A 90-node tree on a 60x12 terminal: each redraw is the status line and at most 9 tree
    lines, finished subtrees folded, and the running leaf is always among them."""
    out = _Terminal()
    display = TerminalDisplay(out, size=lambda: (60, 12))
    screens: list[str] = []

    def observe(runner: MissionRunner) -> None:
        out.seek(0)
        out.truncate()
        display.render(runner)
        assert display.writer.wait_written(HANG_S)
        screens.append(out.getvalue())

    run_mission(LONG, observer=observe)
    assert len(screens) > 30
    running_seen = 0
    for screen in screens:
        assert screen.startswith("\x1b[H\x1b[J")  # redrawn in place, never scrolled
        lines = screen[len("\x1b[H\x1b[J") :].rstrip("\n").split("\n")
        assert len(lines) <= 11 and all(len(line) <= 60 for line in lines), screen
        assert lines[0].startswith("t=")  # the status line stays on top
        running = [line for line in lines if line.endswith("[*]")]
        if "drive" in screen and running:
            running_seen += 1
            assert any("drive" in line or "wait" in line for line in running), screen
    assert running_seen > 30
    assert any("[✓] +2" in screen for screen in screens)  # a finished sequence folded


def test_fitted_tree_says_how_many_lines_it_left_out(run_mission: RunMission) -> None:
    run = run_mission(LONG)
    lines = fitted_tree(run.runner.mission.root, rows=8, columns=80)
    assert len(lines) == 8
    assert lines[-1].startswith("... ") and "more lines" in lines[-1]
    assert lines[0].startswith("{-} sequence [✓]")


class _StalledTerminal(io.StringIO):
    """A terminal that stops taking text (an SSH session on a stalled network) until let go."""

    def __init__(self) -> None:
        super().__init__()
        self.go = threading.Event()
        self.entered = threading.Event()

    def write(self, text: str) -> int:
        self.entered.set()
        self.go.wait(HANG_S)  # a test that failed before it let go leaves no thread for ever
        return super().write(text)


def test_a_stalled_terminal_holds_up_nothing_and_sees_the_newest_screen() -> None:
    terminal = _StalledTerminal()
    writer = OffTickWriter(terminal)
    writer.post("first screen", latest_only=True)
    waited(terminal.entered, "the writer's first write")  # its thread is stuck in the write
    for i in range(100):  # the tick loop goes on: each post returns at once
        writer.post(f"screen {i}", latest_only=True)
    assert len(writer._lines.items) == 1  # only the newest waits
    terminal.go.set()
    assert writer.wait_written(HANG_S)
    assert terminal.getvalue() == "first screen" + "screen 99"


def test_log_lines_wait_up_to_a_limit_then_the_oldest_are_dropped_and_counted() -> None:
    terminal = _StalledTerminal()
    writer = OffTickWriter(terminal, limit=10)
    writer.post("line 0\n")
    waited(terminal.entered, "the writer's first write")
    for i in range(1, 31):
        writer.post(f"line {i}\n")
    assert writer.dropped == 20
    terminal.go.set()
    writer.close(HANG_S)
    assert terminal.getvalue().splitlines() == ["line 0", *(f"line {i}" for i in range(21, 31))]


def test_a_display_dropped_without_close_ends_its_thread_once_its_screen_is_written() -> None:
    """A program that drops its :class:`TerminalDisplay` (or an :class:`OffTickWriter`)
    without ``close()``: its writer is collected, and its thread writes what was posted and
    ends. The thread held the writer and waited for text for the rest of the process, one
    a display."""
    terminal = _StalledTerminal()
    display = TerminalDisplay(terminal)
    thread = display.writer._thread
    display.writer.post("first screen", latest_only=True)
    waited(terminal.entered, "the display's first write")  # the thread is in the write
    display.writer.post("last screen", latest_only=True)
    del display
    gc.collect()
    terminal.go.set()
    joined(thread, "the dropped display's writer thread")
    assert terminal.getvalue() == "first screen" + "last screen"


def test_a_terminal_that_fails_ends_the_writing_not_the_caller() -> None:
    class Gone(io.StringIO):
        def write(self, text: str) -> int:
            raise OSError(5, "Input/output error")  # EIO: the terminal hung up

    writer = OffTickWriter(Gone())
    writer.post("screen", latest_only=True)
    assert writer.wait_written(HANG_S) and writer.gone
    writer.post("more")  # nothing raised, nothing kept
    assert not writer._lines.items


def test_log_lines_go_through_the_writer_only_during_the_block() -> None:
    root = logging.getLogger()
    stream = io.StringIO()
    handler = logging.StreamHandler(stream)
    root.addHandler(handler)
    try:
        with logging_off_the_tick():
            assert handler not in root.handlers
            off = [h for h in root.handlers if isinstance(h, OffTickHandler)]
            assert len(off) == 1 and off[0].writer.stream is stream
            root.warning("during the run")
        assert handler in root.handlers and off[0] not in root.handlers
        assert stream.getvalue() == "during the run\n"  # written before the block ended
    finally:
        root.removeHandler(handler)


def test_log_lines_the_terminal_did_not_take_are_counted_after_the_run(
    caplog: pytest.LogCaptureFixture,
) -> None:
    root = logging.getLogger()
    terminal = _StalledTerminal()
    handler = logging.StreamHandler(terminal)
    root.addHandler(handler)
    try:
        with logging_off_the_tick(timeout=0.1):
            off = next(h for h in root.handlers if isinstance(h, OffTickHandler))
            off.writer.limit = 5
            for i in range(20):
                root.warning("line %d", i)
            waited(terminal.entered, "the log handler's first write")
            terminal.go.set()  # the lines past the limit are dropped already
    finally:
        root.removeHandler(handler)
    assert off.writer.dropped > 0
    assert f"{off.writer.dropped} log line(s) of the run were dropped" in caplog.text


def test_the_live_tree_says_each_node_s_kind_folded_or_not() -> None:
    """Folded, a reactive fallback read ``reactive [✓] +1`` and one with memory the same:
    which ticks its children again could not be seen while the tree ran. Each line starts
    with the kind as py_trees' ``unicode_tree`` draws it (``[o]`` reactive, ``{o}`` with
    memory), the running path's lines too."""
    reactive = py_trees.composites.Selector(
        "reactive", memory=False, children=[py_trees.behaviours.Success(name="first")]
    )
    remembering = py_trees.composites.Selector(
        "remembering", memory=True, children=[py_trees.behaviours.Success(name="second")]
    )
    running = py_trees.behaviours.Running(name="drive")
    root = py_trees.composites.Sequence(
        "steps", memory=True, children=[reactive, remembering, running]
    )
    root.tick_once()
    assert fitted_tree(root, rows=10, columns=80) == [
        "{-} steps [*]",
        "  [o] reactive [✓] +1",
        "  {o} remembering [✓] +1",
        "  --> drive [*]",
    ]


def test_the_live_tree_into_a_pipe_prints_each_screen_without_cursor_codes(
    run_mission: RunMission,
) -> None:
    """``--display tree`` into a log or a pipe wrote ``ESC [H ESC [J`` before every screen
    (garbage in ``less``, in CI's log). Decided: where the stream is no terminal each screen
    is printed under the last, as on ``TERM=dumb``, rather than the option refused."""
    run = run_mission(DRIVE)
    out = io.StringIO()  # no terminal: isatty() is False
    display = TerminalDisplay(out)
    for _ in range(2):
        display.render(run.runner)
        assert display.writer.wait_written(HANG_S)
    text = out.getvalue()
    assert "\x1b" not in text
    assert text.count("{-} sequence [✓]") == 2  # two screens, one under the other


def test_a_name_stays_on_its_line_in_the_live_tree_and_the_log() -> None:
    """A node's name printed raw: "\\n[ok] fake" drew a line of its own in the live tree and
    in a status-change log line, "\\x1b[2J" cleared the screen. Escaped, one line each; a
    message the program wrote on several lines keeps them, its arguments do not."""
    leaf = py_trees.behaviours.Success(name="\x1b[2J")
    root = py_trees.composites.Sequence("steps\n[ok] fake", memory=True, children=[leaf])
    root.tick_once()
    lines = fitted_tree(root, rows=10, columns=80)
    assert lines == ["{-} steps\\x0a[ok] fake [✓]", "  --> \\x1b[2J [✓]"]
    formatter = MissionClockFormatter()
    record = logging.LogRecord("roomba_bt.run", logging.INFO, __file__, 1, "%s -> %s",
                               (root.name, "SUCCESS"), None)  # fmt: skip
    assert formatter.format(record) == "INFO roomba_bt.run: steps\\x0a[ok] fake -> SUCCESS"
    raw = logging.LogRecord("roomba_bt.run", logging.WARNING, __file__, 1, "a\n\x1b[2Jb %d",
                            (3,), None)  # fmt: skip
    assert formatter.format(raw) == "WARNING roomba_bt.run: a\n\\x1b[2Jb 3"


def test_the_tree_at_the_end_is_py_trees_drawing_its_texts_escaped(
    run_mission: RunMission,
) -> None:
    """``run`` prints the tree before and after a run as py_trees draws it; drawn by
    ``text_tree`` so that a leaf's message and a node's name are escaped (py_trees prints
    them raw): the same text where nothing needs it, the leaf's own line where it does."""
    run = run_mission(DRIVE)
    root = run.runner.mission.root
    for show_status in (False, True):
        drawn = py_trees.display.unicode_tree(root, show_status=show_status)
        assert text_tree(root, show_status=show_status) == drawn
    leaf = py_trees.behaviours.Failure(name="\x1b[2J")
    root = py_trees.composites.Selector("tries\n[ok] fake", memory=False, children=[leaf])
    root.tick_once()
    leaf.feedback_message = "\x1b[2J\n[ok] robot stopped"
    assert text_tree(root, show_status=True).splitlines() == [
        "[o] tries\\x0a[ok] fake [✕]",
        "    --> \\x1b[2J [✕] -- \\x1b[2J\\x0a[ok] robot stopped",
    ]
    assert leaf.feedback_message == "\x1b[2J\n[ok] robot stopped"  # the leaf's, as it was


def test_a_blocking_writer_waits_for_room_and_drops_no_line() -> None:
    """``run --fast`` behind a slow pipe (``2>&1 | less``) dropped 4965 of 7033 lines though
    nothing drives on the virtual clock; there a post waits for the thread instead."""
    terminal = _StalledTerminal()
    writer = OffTickWriter(terminal, limit=10, blocks=True)
    writer.post("line 0\n")
    waited(terminal.entered, "the writer's first write")
    poster = threading.Thread(target=lambda: [writer.post(f"line {i}\n") for i in range(1, 31)])
    poster.start()
    terminal.go.set()
    joined(poster, "a post to a blocking writer")
    writer.close(None)
    assert writer.dropped == 0
    assert terminal.getvalue().splitlines() == [f"line {i}" for i in range(31)]


def test_a_fast_run_logs_through_a_blocking_writer(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    """``run --fast`` asks for the blocking writer; a run on the wall clock keeps dropping
    (a stalled terminal must not hold up the tick of a robot that drives)."""
    from roomba_bt.cli import main
    from roomba_bt.runtime import display

    asked: list[bool] = []
    original = display.logging_off_the_tick

    def spy(timeout: float = 1.0, *, blocks: bool = False) -> Any:
        asked.append(blocks)
        return original(timeout, blocks=blocks)

    monkeypatch.setattr(display, "logging_off_the_tick", spy)
    mission = tmp_path / "m.yaml"
    mission.write_text(DRIVE)
    assert main(["run", str(mission), "--fast", "--display", "none"]) == 0
    assert main(["run", str(mission), "--display", "none"]) == 0
    assert asked == [True, False]


class _Terminal(io.StringIO):
    """A terminal as ``isatty`` says it."""

    def isatty(self) -> bool:
        return True


def test_a_dumb_terminal_gets_no_cursor_movement(
    run_mission: RunMission, monkeypatch: pytest.MonkeyPatch
) -> None:
    """``TERM=dumb`` (an Emacs shell, a serial console) showed ``ESC [H ESC [J`` as garbage:
    ``auto`` picks the log there, and ``--display tree`` prints plain screens."""
    monkeypatch.setenv("TERM", "dumb")
    assert isinstance(observer_for("auto", _Terminal()), StatusChangeLogger)
    run = run_mission(DRIVE)
    out = _Terminal()
    display = TerminalDisplay(out)
    display.render(run.runner)
    assert display.writer.wait_written(HANG_S)
    assert "\x1b" not in out.getvalue() and "sequence [✓]" in out.getvalue()
    monkeypatch.setenv("TERM", "xterm")
    assert isinstance(observer_for("auto", _Terminal()), TerminalDisplay)


@pytest.mark.parametrize("env", [{"NO_COLOR": "1"}, {"TERM": "dumb"}])
def test_no_color_and_a_dumb_terminal_get_no_colour(
    monkeypatch: pytest.MonkeyPatch, env: dict[str, str]
) -> None:
    """py_trees colours the marks whenever stdout was a terminal when it was imported (the
    test makes its symbols so); ``NO_COLOR`` and ``TERM=dumb`` are honoured."""
    from roomba_bt.cli import run_cmd

    status = py_trees.common.Status
    symbols = py_trees.display.unicode_symbols
    monkeypatch.setitem(symbols, status.INVALID, "\x1b[33m-\x1b[0m")
    monkeypatch.setitem(symbols, status.SUCCESS, "\x1b[32m✓\x1b[0m")
    monkeypatch.setenv("TERM", "xterm")
    monkeypatch.delenv("NO_COLOR", raising=False)
    monkeypatch.setattr("sys.stdout", _Terminal())
    root = py_trees.composites.Sequence("s", memory=True, children=[])
    mission = type("M", (), {"root": root})()
    assert "\x1b[33m" in run_cmd._render_tree(mission, status=True)  # a terminal: colour
    for name, value in env.items():
        monkeypatch.setenv(name, value)
    drawn = run_cmd._render_tree(mission, status=True)
    assert "\x1b" not in drawn and drawn == "{-} s [-]\n"


def test_the_sensor_line_wraps_on_a_narrow_terminal(run_mission: RunMission) -> None:
    """At 40 columns the sensor line was cut (``t=   0.84s  mode=Safe  bump=-  drop=-  c``):
    the cliffs, the battery and the odometry were lost. It wraps between fields."""
    run = run_mission(DRIVE)
    out = _Terminal()
    display = TerminalDisplay(out, size=lambda: (40, 24))
    display.render(run.runner)
    assert display.writer.wait_written(HANG_S)
    screen = out.getvalue().removeprefix("\x1b[H\x1b[J")
    lines = screen.split("\n")
    assert all(len(line) <= 40 for line in lines), lines
    status = "  ".join(lines[: lines.index("")])
    assert status == sensor_line(run.runner.snapshot)
    assert "cliff=" in status and "battery=" in status and "odo=" in status
    assert sensor_lines(run.runner.snapshot, 200) == [sensor_line(run.runner.snapshot)]


def test_an_ascii_terminal_gets_ascii_marks(run_mission: RunMission) -> None:
    """A terminal whose encoding has no ``✓`` (``LANG=C`` on a serial console) is shown
    ``[ok]``, not ``UnicodeEncodeError`` (or ``\\u2713``)."""
    run = run_mission(DRIVE)
    out = io.TextIOWrapper(io.BytesIO(), encoding="ascii")
    display = TerminalDisplay(out)
    display.render(run.runner)
    assert display.writer.wait_written(HANG_S) and not display.writer.gone
    out.flush()
    assert b"sequence [ok]" in out.buffer.getvalue()  # type: ignore[attr-defined]


WAIT = """
tree:
  sequence:
    - mode: safe
    - wait: 10min
"""


@pytest.mark.parametrize(("heartbeat", "beats"), [("1min", [60, 120]), ("none", [])])
def test_the_log_says_how_the_run_goes_every_heartbeat_of_mission_time(
    tmp_path: Path, caplog: pytest.LogCaptureFixture, heartbeat: str, beats: list[int]
) -> None:
    """A patrol's ``--display log`` printed nothing for 3.5 hours between its first tick and
    its docking: "fine" and "hung" read the same in the journal. A line every heartbeat of
    mission time (``--fast`` too) says the battery, the distance, the mode and the ticks."""
    from roomba_bt.cli import main

    mission = tmp_path / "wait.yaml"
    mission.write_text(WAIT, encoding="utf-8")
    argv = ["run", str(mission), "--fast", "--display", "log", "--duration", "150s"]
    caplog.set_level(logging.INFO, logger="roomba_bt.run")
    assert main([*argv, "--heartbeat", heartbeat]) == 0
    said = [(r.mission_time, r.getMessage()) for r in caplog.records if "still" in r.getMessage()]
    assert said == [
        (t, f"still running: battery 60 %, 0.00 m driven, Safe, tick {t * 1000 // 15}")
        for t in beats
    ]
