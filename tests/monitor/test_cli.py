"""``run --monitor`` and ``roomba-bt monitor`` on the command line: usage errors are exit 2,
before anything moves."""

from __future__ import annotations

import hashlib
import ipaddress
import json
import logging
import queue
import re
import signal
import socket
import subprocess
import sys
import threading
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import pytest
from quoted import assert_quoted  # tests/quoted.py: the docs' quotes
from runtime.test_terminate_never_returns import HANG_ON_STOP, MISSION, WAIT_LINE
from waits import HANG_S, joined, lines  # tests/waits.py: a hang's bound

from roomba_bt.cli import main
from roomba_bt.runtime import ending
from roomba_bt.runtime.summary import ExitCode

if TYPE_CHECKING:  # the server needs the monitor extra, which each test checks for first
    from roomba_bt.monitor.server import MonitorServer

SHUTTLE = Path(__file__).resolve().parent / "missions" / "shuttle.yaml"

#: a record view's stdout and stderr (``served_record(record, *options)``)
ServedRecord = Callable[..., tuple[str, str]]


def _record_the_shuttle(record: Path, *options: str, mission: Path = SHUTTLE) -> int:
    """Run the shuttle for 2 s of mission time into ``record`` (it times out): its exit code.
    ``options``: more of ``run``'s (``--world apartment``); ``mission``: a copy of it to run
    (one in the folder that holds the record and its world)."""
    return main(["run", str(mission), "--fast", "--display", "none", "--timeout", "2",
                 "--record", str(record), *options])  # fmt: skip


@pytest.fixture
def served_record(child: Callable[[Sequence[str]], subprocess.Popen[str]]) -> ServedRecord:
    """``served_record(record, *options, until=START)``: ``roomba-bt monitor RECORD`` up to
    its first line starting with ``until`` (its URL), then ended by SIGTERM: its stdout and
    stderr (it must exit 0). Lines after ``until``'s may be lost (read ahead, then not
    returned by ``communicate``). One the test leaves running (a failed assertion, a
    timeout) is killed by ``child``."""

    def serve(record: Path, *options: str, until: str = "monitor: http") -> tuple[str, str]:
        proc = child([sys.executable, "-m", "roomba_bt.cli", "monitor", str(record),
                      "--monitor", "0", *options])  # fmt: skip
        assert proc.stdout is not None
        lines = []
        for line in proc.stdout:
            lines.append(line)
            if line.startswith(until):
                break
        proc.send_signal(signal.SIGTERM)
        out, err = proc.communicate(timeout=HANG_S)
        assert proc.returncode == 0, err
        return "".join(lines) + out, err

    return serve


@pytest.fixture
def viewed_record(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> ServedRecord:
    """``viewed_record(record, *options)``: ``roomba-bt monitor RECORD`` in this process, up to
    the page it would serve (the record read and replayed, its world drawn or why not said):
    its stdout and stderr (it must reach the page). What the command says of a record's world
    is said before the page is served, so the world's tests need no child: the page served
    until SIGTERM is :func:`served_record`'s tests'. A child's start is seconds of a loaded
    machine (the interpreter, aiohttp, the replay): the world's three tests started nine,
    30 to 77 s of waiting on a shared 2-core machine."""
    from roomba_bt.cli import monitor_cmd

    served: list[object] = []

    def serve(feed: object, host: str, port: int, path: str) -> int:
        served.append(feed)
        return 0

    monkeypatch.setattr(monitor_cmd, "_serve_record", serve)

    def view(record: Path, *options: str) -> tuple[str, str]:
        capsys.readouterr()
        code = main(["monitor", str(record), "--monitor", "0", *options])
        out, err = capsys.readouterr()
        assert code == 0 and served, err
        served.clear()
        return out, err

    return view


def test_without_the_extra_monitor_says_how_to_install_it_and_exits_2(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setattr("roomba_bt.cli.monitor_cmd.server_available", lambda: False)
    with pytest.raises(SystemExit) as exited:
        main(["run", str(SHUTTLE), "--fast", "--monitor"])
    assert exited.value.code == 2
    captured = capsys.readouterr()
    assert "pip install 'roomba-bt[monitor]'" in captured.err
    assert "mission" not in captured.out  # nothing ran
    with pytest.raises(SystemExit) as exited:
        main(["monitor", "missing.jsonl", "--monitor", "8000"])
    assert exited.value.code == 2


def _two_ports_held() -> tuple[socket.socket, socket.socket]:
    """Two listening sockets on ports one after the other (another run's monitor on one,
    something else on the next)."""
    for _ in range(50):
        first, second = socket.socket(), socket.socket()
        first.bind(("127.0.0.1", 0))
        first.listen()
        try:
            second.bind(("127.0.0.1", first.getsockname()[1] + 1))
        except OSError:
            first.close()
            second.close()
            continue
        second.listen()
        return first, second
    raise AssertionError("no two free ports one after the other")


def test_a_taken_port_names_one_free_now_and_any_free_port(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """It suggested port + 1 unchecked: a teacher starting several runs was sent to the next
    run's port. The suggestion is a port free now, and --monitor 0 (any free port)."""
    from roomba_bt.cli.monitor_cmd import bind_problem

    first, second = _two_ports_held()
    with first, second:
        port = first.getsockname()[1]
        code = main(["run", str(SHUTTLE), "--fast", "--display", "none", "--monitor", str(port)])
        err = capsys.readouterr().err
        assert code == 2
        assert f"--monitor 127.0.0.1:{port}: the port is taken (another run's monitor?)" in err
        said = re.search(r"; (\d+) is free now: --monitor (\d+); or --monitor 0 takes any free "
                         r"port \(the run prints it\)", err)  # fmt: skip
        assert said, err
        assert said[1] == said[2] and int(said[1]) not in (port, port + 1)
        assert bind_problem("127.0.0.1", int(said[1])) is None  # free indeed


def test_a_record_view_on_a_taken_port_says_so_before_reading_the_record(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """`roomba-bt monitor RECORD` replayed the whole record (minutes for a long one) before
    it found its port taken."""
    with socket.socket() as held:
        held.bind(("127.0.0.1", 0))
        held.listen()
        port = held.getsockname()[1]
        code = main(["monitor", str(tmp_path / "not-read.jsonl"), "--monitor", str(port)])
    assert code == 2
    err = capsys.readouterr().err
    assert f"--monitor 127.0.0.1:{port}: the port is taken" in err
    assert "not-read.jsonl" not in err  # the record was not read


def test_the_url_is_said_once_the_robot_s_port_is_open_with_the_mission_and_robot(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The URL was printed before the port was opened: a busy port left a URL that never
    served a page. It names the mission and the robot, as the summary does."""
    missing = str(tmp_path / "no-such-tty")
    code = main(["run", str(SHUTTLE), "--port", missing, "--monitor", "0", "--display", "none"])
    out, err = capsys.readouterr()
    assert code == 3, err
    assert "monitor: http" not in out and "monitor: http" not in err
    assert f"roomba-bt: {missing}" in err
    code = main(["run", str(SHUTTLE), "--fast", "--display", "none", "--monitor", "0",
                 "--timeout", "1s"])  # fmt: skip
    out, _ = capsys.readouterr()
    assert code == 1
    assert re.fullmatch(
        r"monitor: http://127\.0\.0\.1:\d+/ \(shuttle on simulator empty-room\)",
        out.splitlines()[0],
    ), out
    # the page's run is bump-and-turn on a robot's port: the line's words, its mission and robot
    robot = {"shuttle on simulator empty-room": "bump-and-turn on /dev/ttyUSB0"}
    assert_quoted("docs/monitor.md", "monitor: http://127.0.0.1:8765/", out, numbers=True,
                  names=robot)  # fmt: skip
    assert "mission      shuttle\nrobot        simulator empty-room\nstarted      " in out


def test_a_record_still_being_written_is_shown_as_such(
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    record_held: Callable[[Path], subprocess.Popen[str]],
    served_record: ServedRecord,
) -> None:
    """A record read while its run wrote it (the run holds its lock) was shown as ended
    ('input ended (recorded run, 829 ticks)'), on the page and on the first line."""
    record = tmp_path / "live.jsonl"
    _record_the_shuttle(record)
    capsys.readouterr()
    lines = record.read_text(encoding="utf-8").splitlines(keepends=True)
    record.write_text("".join(lines[: len(lines) // 2]), encoding="utf-8")  # written so far
    record_held(record)
    out, _ = served_record(record)
    assert re.search(
        rf"{re.escape(str(record))}: the record is still being written \(a run in progress\?\): "
        r"shown up to t=\d+\.\d\d s \(recorded run, \d+ ticks\)",
        out,
    ), out


@pytest.mark.parametrize("torn", [False, True])
def test_a_killed_run_s_record_is_shown_as_such_as_replay_says_it(
    torn: bool, tmp_path: Path, capsys: pytest.CaptureFixture[str], served_record: ServedRecord
) -> None:
    """A record without its run's end (``kill -9``; a last line cut short too) was shown as
    'input ended (recorded run, 335 ticks)' on the page and the first line, where ``replay``
    said the run was killed: both say it in one text (``Record.end_said``)."""
    record = tmp_path / "killed.jsonl"
    _record_the_shuttle(record)
    capsys.readouterr()
    text = record.read_text(encoding="utf-8")
    lines = text.splitlines(keepends=True)
    kept = "".join(lines[: len(lines) // 2])
    record.write_text(kept + (lines[len(lines) // 2][:20] if torn else ""), encoding="utf-8")
    out, _ = served_record(record)
    said = (
        rf"{re.escape(str(record))}: the record ends at \d+\.\d{{3}} s without the run's end: "
        r"the run was killed, or writing its record failed \(.*\)"
    )
    if torn:
        said += rf"; its last line \({len(lines) // 2 + 1}\) was cut short and is left out"
    assert re.search(said + r" \(recorded run, \d+ ticks\)", out), out
    assert "input ended" not in out


def test_a_compressed_record_is_shown_as_a_plain_one_is(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], served_record: ServedRecord
) -> None:
    """``roomba-bt monitor RECORD.jsonl.gz`` (``run --record`` compresses a ``.gz``) replays
    it into its page; a gzipped record was refused ('byte 0x8b, not UTF-8 text')."""
    record = tmp_path / "run.jsonl.gz"
    _record_the_shuttle(record)
    capsys.readouterr()
    assert record.read_bytes().startswith(b"\x1f\x8b")  # gzip's magic number
    out, _ = served_record(record)
    assert f"{record}: the recorded run ended in timeout at t=2.01 s" in out, out


@pytest.mark.parametrize(
    ("address", "message"),
    [("99999", "0 to 65535"), ("host:port", "allowed: [HOST:]PORT"), ("-1", "0 to 65535")],
)
def test_a_bad_address_is_a_usage_error(
    address: str, message: str, capsys: pytest.CaptureFixture[str]
) -> None:
    with pytest.raises(SystemExit) as exited:
        main(["run", str(SHUTTLE), "--fast", f"--monitor={address}"])
    assert exited.value.code == 2
    assert message in capsys.readouterr().err


def test_an_address_in_use_is_exit_2_before_the_run(capsys: pytest.CaptureFixture[str]) -> None:
    taken = socket.socket()
    taken.bind(("127.0.0.1", 0))
    taken.listen()
    try:
        port = taken.getsockname()[1]
        code = main(["run", str(SHUTTLE), "--fast", "--monitor", str(port), "--display", "none"])
    finally:
        taken.close()
    assert code == 2
    captured = capsys.readouterr()
    assert f"--monitor 127.0.0.1:{port}:" in captured.err
    assert "outcome" not in captured.out
    assert "Traceback" not in captured.err


def test_monitor_names_a_bad_record(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    bad = tmp_path / "bad.jsonl"
    bad.write_text('{"format": "something else"}\n')
    assert main(["monitor", str(bad), "--monitor", "0"]) == 2
    assert f"{bad}:1: not a roomba-bt-record file" in capsys.readouterr().err


MAIN_WITH_LIBRARY = """\
mission: shuttle-with-a-library
description: The shuttle, its leg in an included file.
include: [leg.yaml]
tree:
  sequence:
    - mode: safe
    - repeat:
        do: {subtree: leg}
"""
LEG = """\
subtrees:
  leg:
    tree:
      sequence:
        name: there and back
        children:
          - drive: {velocity: 100 mm/s, distance: 3 cm}
          - drive: {velocity: -100 mm/s, distance: 3 cm}
"""


class WatchedRun:
    """``roomba-bt run ... --watch`` in a subprocess, its output lines read as they come."""

    def __init__(self, *args: str, display: str = "none") -> None:
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "roomba_bt.cli", "run", *args, "--watch",
             "--display", display],
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        )  # fmt: skip
        self.lines: queue.SimpleQueue[str] = queue.SimpleQueue()
        self.readers = [
            threading.Thread(target=self._read, args=(stream, label), daemon=True)
            for stream, label in ((self.proc.stdout, "out"), (self.proc.stderr, "err"))
        ]
        for reader in self.readers:
            reader.start()

    def _read(self, stream: Any, label: str) -> None:
        for line in stream:
            self.lines.put(f"{label}: {line}")

    def expect(self, text: str) -> str:
        seen: list[str] = []
        while True:
            try:
                line = self.lines.get(timeout=HANG_S)
            except queue.Empty:
                raise AssertionError(f"never saw {text!r}; saw {seen}") from None
            seen.append(line)
            if text in line:
                return line

    def interrupt(self) -> int:
        self.proc.send_signal(signal.SIGINT)
        return self.proc.wait(timeout=HANG_S)

    def said(self) -> str:
        """What the process wrote that :meth:`expect` has not read, once it has ended."""
        for reader in self.readers:
            joined(reader, "reading what the ended monitor wrote")
        left: list[str] = []
        while not self.lines.empty():
            left.append(self.lines.get_nowait())  # the readers ended: all there is
        return "".join(left)

    def close(self) -> None:
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait(timeout=HANG_S)
        for reader in self.readers:
            reader.join(HANG_S)  # killed: its pipes end at once
        for stream in (self.proc.stdout, self.proc.stderr):
            if stream is not None:
                stream.close()


def test_watch_reloads_when_an_included_file_changes(tmp_path: Path) -> None:
    mission, leg = tmp_path / "main.yaml", tmp_path / "leg.yaml"
    mission.write_text(MAIN_WITH_LIBRARY)
    leg.write_text(LEG)
    run = WatchedRun(str(mission))
    try:
        watching = run.expect("out: watching ")  # the watcher has the files' first stamps
        assert "main.yaml" in watching and "leg.yaml" in watching
        leg.write_text(LEG.replace("there and back", "out and home, a longer name"))
        run.expect(f"out: reload: {mission} is valid")
        leg.write_text(LEG.replace("velocity: 100 mm/s", "velocity: fast"))
        refused = run.expect("err: reload refused:")
        assert re.search(rf"{re.escape(str(leg))}:\d+:\d+", refused), refused
        assert run.interrupt() == 130
    finally:
        run.close()


def test_ctrl_c_while_a_reload_waits_for_a_terminate_that_never_returns(tmp_path: Path) -> None:
    """A change reloads the mission while its plugin's leaf drives; the old tree's stop
    blocks in that leaf's terminate() for ever, and a Ctrl-C comes meanwhile. The run ends,
    exit 130, its end waiting for that same stop (the bound of a run's end) rather than
    calling the terminate a second time beside it, then the safe stop and the summary,
    naming the terminate and its line. Before, the reload waited for ever, and the Ctrl-C
    ended nothing."""
    plugin, mission = tmp_path / "hang.py", tmp_path / "hang.yaml"
    plugin.write_text(HANG_ON_STOP)
    mission.write_text(MISSION)
    run = WatchedRun(str(mission), "--allow-plugin-files", display="log")
    try:
        run.expect("out: watching ")
        run.expect("hang_on_stop -> RUNNING")  # its leaf drives: the stop will terminate it
        mission.write_text(MISSION.replace("mission: hang_on_stop", "mission: renamed"))
        run.expect("err: terminate entered")
        assert run.interrupt() == 130
        said = run.said()
    finally:
        run.close()
    where = f"hang_on_stop (HangOnStop.terminate at {plugin}:{WAIT_LINE})"
    assert "out: outcome      INTERRUPTED (Ctrl-C or kill -INT (SIGINT); then the tree's " in said
    assert (
        f"the tree's stop did not end within {ending.TREE_STOP_LIMIT_S:g} s: {where} had not "
        "returned; the run's end went on without it (the safe stop, the summary; its "
        "shutdown() not called)"
    ) in said, said
    assert "terminate entered" not in said  # called once, at the reload
    assert "out: final mode   Passive" in said, said


MAIN_WITH_PLUGIN = """\
mission: shuttle-with-a-plugin
plugins: [./always.py]
tree:
  sequence:
    - mode: safe
    - repeat:
        do:
          sequence:
            - always_clear
            - drive: {velocity: 100 mm/s, distance: 3 cm}
            - drive: {velocity: -100 mm/s, distance: 3 cm}
"""
PLUGIN = """\
from roomba_bt.behaviours import Condition, declare


@declare("always_clear", kind="condition", reads=(7,))
class AlwaysClear(Condition):
    \"\"\"The way is clear (a plugin file of the mission's own).\"\"\"

    def check(self, snapshot):
        return True
"""


def test_watch_reloads_when_a_plugin_file_changes(tmp_path: Path) -> None:
    """--allow-plugin-files: the plugin files the mission loads are watched as includes are,
    and a changed one is imported again (a broken one is refused, naming where it is listed)."""
    mission, plugin = tmp_path / "main.yaml", tmp_path / "always.py"
    mission.write_text(MAIN_WITH_PLUGIN)
    plugin.write_text(PLUGIN)
    run = WatchedRun(str(mission), "--allow-plugin-files")
    try:
        watching = run.expect("out: watching ")
        assert "main.yaml" in watching and "always.py" in watching, watching
        plugin.write_text(PLUGIN.replace("(a plugin file", "(a changed plugin file"))
        run.expect(f"out: reload: {mission} is valid")
        plugin.write_text(PLUGIN.replace("def check(self, snapshot):", "def check(self, snapshot:"))
        refused = run.expect("err: reload refused:")
        assert re.search(rf"{re.escape(str(mission))}:2:\d+: .*always.py", refused), refused
        assert "SyntaxError" in refused, refused
        assert run.interrupt() == 130
    finally:
        run.close()


#: a drive in Safe mode, and the same drive in Full mode with no cliff check: one warning
SAFE_DRIVE = """\
tree:
  sequence:
    - mode: safe
    - drive: {velocity: 100 mm/s, duration: 1s}
"""
FULL_DRIVE = SAFE_DRIVE.replace("mode: safe", "mode: full")


def test_the_banner_of_a_run_whose_link_was_lost_says_each_thing_once() -> None:
    """A run's link lost (the simulator's port gone, as a cable pulled) while it drove: the
    page's banner ran the summary's words together over five lines of a laptop's window,
    ``last seen in Safe`` twice, ``the stop was not delivered`` three times (the final mode,
    the safe stop's ``NOT DELIVERED`` and its report), the advice at the end. It says what
    happened, where the robot was left and what to do, a line each."""
    from roomba_bt.cli import build_parser
    from roomba_bt.cli.monitor_cmd import LiveMonitor, MonitorOptions
    from roomba_bt.mission import load_mission
    from roomba_bt.oi.profiles import CREATE2
    from roomba_bt.runtime.stack import RunStack
    from roomba_bt.sim import Faults, SimLink, Simulator, load_world

    mission = load_mission(SHUTTLE, {}, profile=CREATE2)
    simulator = Simulator(load_world("empty-room"), CREATE2, 0, Faults(disconnect_at=1.0))
    stack = RunStack(mission, SimLink(simulator), profile=CREATE2, timeout_s=60.0)
    try:
        summary = stack.run(raise_interrupts=False)
    finally:
        stack.close()
    assert summary.safe_stop.startswith("NOT DELIVERED: last seen in Safe"), summary.safe_stop
    options = MonitorOptions.from_args(build_parser().parse_args(["run", str(SHUTTLE)]))
    monitor = LiveMonitor(options, mission, simulator=None, packets=(), loader=load_mission)
    monitor.finish(summary)
    assert monitor.feed.finished is not None
    happened, robot, to_do = monitor.feed.finished.split("\n")
    assert happened == f"connection lost: {summary.reason}"
    assert robot.startswith("the robot: last seen in Safe at "), robot  # its wheels
    assert robot.endswith("; the stop was not delivered: the port is gone"), robot
    assert to_do == (
        "the robot may still be moving: pick it up or press its Clean or power button; "
        "reseat the cable, then roomba-bt doctor --port sim://empty-room"
    )
    said = monitor.feed.finished
    assert said.count("last seen") == said.count("not delivered") == 1, said
    ending = monitor.feed.ending  # the robot panel's words, as before
    assert ending is not None
    assert ending.mode == "unknown: last seen in Safe, the stop was not delivered"


@pytest.mark.parametrize("strict", [True, False], ids=["strict", "not-strict"])
def test_a_reload_with_compile_time_warnings_is_refused_under_strict(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], strict: bool
) -> None:
    """``run --strict`` does not start a mission with compile-time warnings (exit 7, in
    ``validate --strict``'s words), and ``run --strict --watch`` took one changed into it:
    the run went on under a tree --strict refuses. It is refused as an invalid change is,
    the terminal and the page saying why, and the old tree runs on. Without ``--strict`` it
    is taken, its warning said (a reload said nothing of it)."""
    from roomba_bt.cli import build_parser
    from roomba_bt.cli.monitor_cmd import LiveMonitor, MonitorOptions
    from roomba_bt.mission import load_mission

    mission = tmp_path / "drive.yaml"
    mission.write_text(SAFE_DRIVE)
    argv = ["run", str(mission), "--watch", *(["--strict"] if strict else [])]
    options = MonitorOptions.from_args(build_parser().parse_args(argv))
    assert options.strict is strict
    monitor = LiveMonitor(
        options, load_mission(mission), simulator=None, packets=(), loader=load_mission
    )
    mission.write_text(FULL_DRIVE)
    reloaded = monitor._reload(mission, [mission])
    monitor.finish(None)
    err = capsys.readouterr().err
    [warning] = [str(w) for w in load_mission(mission).warnings]
    assert warning.startswith(f"{mission}:4:7: warning: drive can turn the wheels in Full mode")
    last = monitor.feed.events[-1]
    if strict:
        assert reloaded is None
        verdict = f"{mission}: failed --strict (1 warning)"
        assert err == f"reload refused: {warning}\nreload refused: {verdict}\n"
        assert (last.kind, last.text) == (
            "error", f"reload refused, the run goes on: {warning}; {verdict}"
        )  # fmt: skip
    else:
        assert reloaded is not None
        assert err == f"reload: {warning}\n"
        assert (last.kind, last.text) == ("warning", f"reloaded with a warning: {warning}")


def test_a_recorded_run_of_a_mission_with_a_plugin_file_can_be_shown(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``monitor RECORD`` said "allow its plugin files with --allow-plugin-files", and then
    refused that option: a recorded plugin mission could not be shown at all."""
    from roomba_bt.cli import build_parser
    from roomba_bt.cli.run_cmd import Recorded, load_recorded

    (tmp_path / "plugin.py").write_text(PLUGIN)
    mission = tmp_path / "m.yaml"
    mission.write_text(
        "plugins: [./plugin.py]\ntree:\n  sequence: [{mode: safe}, always_clear, "
        "{drive: {velocity: 100 mm/s, distance: 3 cm}}]\n"
    )
    record = tmp_path / "run.jsonl"
    argv = ["run", str(mission), "--fast", "--display", "none", "--allow-plugin-files"]
    assert main([*argv, "--record", str(record)]) == 0
    capsys.readouterr()
    refused = load_recorded(build_parser().parse_args(["monitor", str(record)]))
    assert refused == 2
    assert "allow its plugin files with --allow-plugin-files" in capsys.readouterr().err
    args = build_parser().parse_args(["monitor", str(record), "--allow-plugin-files"])
    recorded = load_recorded(args)
    assert isinstance(recorded, Recorded)
    assert recorded.packets == tuple(recorded.record.header["packets"])


def test_the_page_is_told_what_the_robot_was_left_in(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """After the run the page's robot panel holds the last tick before the safe stop: it
    showed Safe and the wheels turning under "the run ended". The banner says the end."""
    from roomba_bt.cli import monitor_cmd

    told: list[str | None] = []
    finish = monitor_cmd.LiveMonitor.finish

    def finish_and_note(self: monitor_cmd.LiveMonitor, summary: Any) -> None:
        finish(self, summary)
        told.append(self.feed.finished)

    monkeypatch.setattr(monitor_cmd.LiveMonitor, "finish", finish_and_note)
    argv = ["run", str(SHUTTLE), "--fast", "--display", "none", "--monitor", "0", "--timeout", "2s"]
    assert main(argv) == 1
    [ended] = told
    assert ended is not None and ended.startswith("timeout: ")
    assert ended.endswith(
        "(final mode Passive; safe stop sent drive, motors, pause_resume_stream, start)"
    )


def test_the_robot_panel_after_the_run_shows_what_the_safe_stop_left(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """The robot panel froze on the last tick before the safe stop: after the run it showed
    Safe, the wheels at their last speed and the brushes on, though the robot was stopped
    and in Passive. The newest tick's panel, once the run has ended, is the final state."""
    from roomba_bt.cli import monitor_cmd
    from roomba_bt.monitor.views import state_view

    shown: list[dict[str, Any]] = []
    finish = monitor_cmd.LiveMonitor.finish

    def finish_and_look(self: monitor_cmd.LiveMonitor, summary: Any) -> None:
        finish(self, summary)
        last = self.feed.latest()
        assert last is not None
        before = self.feed.record(last.seq - 1)
        assert before is not None
        shown.append(state_view(self.feed, last, self.feed.at(last.tick)[1]))
        shown.append(state_view(self.feed, before, self.feed.at(before.tick)[1]))

    monkeypatch.setattr(monitor_cmd.LiveMonitor, "finish", finish_and_look)
    brushes = SHUTTLE.with_name("brushes.yaml")
    argv = ["run", str(brushes), "--fast", "--display", "none", "--monitor", "0", "--timeout", "2s"]
    assert main(argv) == 1
    ended, rewound = (state["robot"] for state in shown)
    assert ended["mode"] == "Passive"
    assert (ended["wheels"]["left"], ended["wheels"]["right"]) == (0, 0)
    motors = ended["motors"]
    assert [motors[m]["percent"] for m in ("main_brush", "side_brush", "vacuum")] == [0, 0, 0]
    assert motors["note"] == "off: the run's safe stop"
    assert shown[0]["ended"]["stopped"] is True
    assert shown[0]["ended"]["outcome"].startswith("timeout: ")
    # a tick before the end is shown as it was: Safe, the brushes on
    assert rewound["mode"] == "Safe" and rewound["motors"]["main_brush"]["percent"] == 100
    assert "ended" not in shown[1]


def test_a_run_s_label_is_on_its_url_line_page_summary_and_record(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """A teacher running several robots from one laptop told pages and terminals apart only
    by their ports: ``run --label`` names the run on the monitor's URL line, on the page
    (its header's ``run``: the tab's title and the header), in the summary and the record's
    header, which ``roomba-bt monitor RECORD`` shows again."""
    from roomba_bt.cli import monitor_cmd
    from roomba_bt.mission import load_mission
    from roomba_bt.monitor.recorded import replay_into_feed
    from roomba_bt.monitor.views import run_view
    from roomba_bt.oi.profiles import CREATE2
    from roomba_bt.runtime.recording import load_record

    runs: list[dict[str, str]] = []
    finish = monitor_cmd.LiveMonitor.finish

    def finish_and_look(self: monitor_cmd.LiveMonitor, summary: Any) -> None:
        finish(self, summary)
        runs.append(run_view(self.feed))

    monkeypatch.setattr(monitor_cmd.LiveMonitor, "finish", finish_and_look)
    record = tmp_path / "run.jsonl"
    argv = ["run", str(SHUTTLE), "--fast", "--display", "none", "--monitor", "0", "--timeout",
            "1s", "--label", " robot 3 ", "--record", str(record)]  # fmt: skip
    assert main(argv) == 1
    out = capsys.readouterr().out
    url_line = r"monitor: http://127\.0\.0\.1:\d+/ \(robot 3: shuttle on simulator empty-room\)"
    assert re.match(url_line, out), out
    assert "\nlabel        robot 3\nmission      shuttle\n" in out
    robot = {"shuttle on simulator empty-room": "dock on /dev/ttyUSB1"}  # the page's robot
    assert_quoted("docs/monitor.md", "monitor: http://127.0.0.1:8766/", out, numbers=True,
                  names=robot)  # fmt: skip
    assert runs[0]["label"] == "robot 3"
    loaded = load_record(record)
    assert loaded.header["label"] == "robot 3"
    mission = load_mission(SHUTTLE, {}, profile=CREATE2)
    packets = tuple(loaded.header["packets"])
    feed, _ = replay_into_feed(loaded, mission, CREATE2, packets, 115200, "run")
    assert run_view(feed)["label"] == "robot 3"


@pytest.mark.parametrize(
    ("label", "said"),
    [
        ("", "found an empty label"),
        ("   ", "found an empty label"),
        ("robot\x1b[2J", "found the unprintable character U+001B (a control or invisible one)"),
        ("robot\u202e3", "found the unprintable character U+202E (a control or invisible one)"),
        ("r" * 41, "found 41 characters"),
    ],
)
def test_a_label_that_will_not_do_is_a_usage_error(
    label: str, said: str, capsys: pytest.CaptureFixture[str]
) -> None:
    with pytest.raises(SystemExit) as exited:
        main(["run", str(SHUTTLE), "--fast", "--label", label])
    assert exited.value.code == 2
    err = capsys.readouterr().err
    assert f"argument --label: {said}; allowed: 1 to 40 printable characters" in err, err
    assert "\x1b" not in err


def test_a_wildcard_address_and_the_virtual_clock_are_said(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """``--monitor 0.0.0.0:PORT`` printed only ``http://0.0.0.0:...``, which no browser on
    another machine opens; ``--fast`` ran to its end before a page could open, unsaid."""
    argv = ["run", str(SHUTTLE), "--fast", "--display", "none", "--monitor", "0.0.0.0:0",
            "--timeout", "1s"]  # fmt: skip
    assert main(argv) == 1
    out, err = capsys.readouterr()
    lines = out.splitlines()
    assert lines[0].startswith("monitor: http://0.0.0.0:")
    assert lines[1].startswith(f"monitor: it listens on every address of this machine: "
                               f"http://{socket.gethostname()}:")  # fmt: skip
    assert "--fast runs the mission on the virtual clock: it may end before a page opens" in err


def test_monitor_of_a_record_ends_on_sigterm_as_on_ctrl_c(
    tmp_path: Path, served_record: ServedRecord
) -> None:
    """SIGTERM killed ``roomba-bt monitor RECORD``: exit 143 and no word (Ctrl-C gave 0).
    Nothing is wrong with the record, so nothing is said on stderr: it said "INFO
    roomba_bt.robot.connection: replay:run.jsonl: iRobot Create 2 in Passive, streaming
    [...]" for every record (docs/monitor.md says what stderr shows)."""
    record = tmp_path / "run.jsonl"
    _record_the_shuttle(record)
    out, err = served_record(record)  # up to its URL, then SIGTERM
    assert "monitor: ended by SIGTERM" in out
    assert err == "", err
    assert_quoted("docs/monitor.md", "monitor: ended by SIGTERM", out)


#: a plugin whose condition, on the first tick it is checked, sends its own process the signal
#: ROOMBA_BT_TEST_SIGNAL names (a Ctrl-C or SIGTERM as the record is replayed), or nothing
_SIGNALLING_PLUGIN = """\
import os, signal
from roomba_bt.behaviours import Condition, declare
@declare("s45_signaller", kind="condition", reads=(27,))
class Signaller(Condition):
    \"\"\"True; its first check sends the signal the environment names.\"\"\"
    def check(self, snapshot):
        name = os.environ.pop("ROOMBA_BT_TEST_SIGNAL", "")
        if name:
            os.kill(os.getpid(), getattr(signal, name))
        return True
"""

#: Safe, the signalling plugin's condition, a wait, Passive
_SIGNALLED = (
    "mission: signalled\nplugins: [./signal.py]\ntree:\n  sequence:\n    - mode: safe\n"
    "    - s45_signaller\n    - wait: 0.3s\n    - mode: passive\n"
)


def _record_view(
    child: Callable[[Sequence[str]], subprocess.Popen[str]], *argv: str
) -> tuple[int, list[str], str]:
    """``roomba-bt monitor ARGV... --monitor 0`` as the process: its exit code, its stdout
    up to its URL (or all of it, where none comes) and its stderr. One that serves is ended
    by SIGTERM."""
    proc = child([sys.executable, "-m", "roomba_bt", "monitor", *argv, "--monitor", "0"])
    assert proc.stdout is not None
    out = lines(proc.stdout, lambda line: line.startswith("monitor: http"), "its URL or end")
    if out and out[-1].startswith("monitor: http"):  # served: ended, as a user would
        proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=HANG_S)
    return proc.returncode, out, err


@pytest.mark.parametrize("signame", ["SIGINT", "SIGTERM"])
def test_a_signal_while_the_record_is_read_ends_monitor_without_a_page(
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    child: Callable[[Sequence[str]], subprocess.Popen[str]],
    signame: str,
) -> None:
    """A Ctrl-C (or SIGTERM) while ``roomba-bt monitor`` replayed a long record cut the
    replay short, said its safe stop as a difference (``replay diverged from the record at
    t=267.16 s: expected Drive (137) ..., sent Motors (138) 8a 00``) and served the page of
    what was read until a second Ctrl-C. It ends the command, exit 130, in ``replay``'s
    words, and no page is served."""
    (tmp_path / "signal.py").write_text(_SIGNALLING_PLUGIN)
    mission = tmp_path / "signalled.yaml"
    mission.write_text(_SIGNALLED)
    record = tmp_path / "run.jsonl"
    ran = ["run", str(mission), "--fast", "--display", "none", "--allow-plugin-files"]
    assert main([*ran, "--record", str(record)]) == 0
    monkeypatch.setenv("ROOMBA_BT_TEST_SIGNAL", signame)
    code, out, err = _record_view(child, str(record), "--allow-plugin-files")
    assert not any(line.startswith("monitor: http") for line in out), out
    assert code == ExitCode.INTERRUPTED, (out, err)
    assert "diverged" not in err, err
    said = f"monitor: {record}: interrupted ({'SIGTERM' if signame == 'SIGTERM' else 'Ctrl-C'}"
    assert said in err, err
    assert "as it was read: no page served" in err, err
    if signame == "SIGINT":
        names = {str(record): "long.jsonl"}
        assert_quoted(
            "docs/monitor.md", "monitor: long.jsonl: interrupted", err, numbers=True, names=names
        )


def test_a_ctrl_c_python_dropped_as_the_mission_loads_ends_monitor_without_a_page(
    tmp_path: Path, child: Callable[[Sequence[str]], subprocess.Popen[str]]
) -> None:
    """A Ctrl-C whose interrupt Python dropped (its handler ran in a weakref callback, as
    importlib's module locks run one while a mission's plugin imports): ``roomba-bt
    monitor`` said it would be "raised again at the next check", replayed the record and
    served its page until a second Ctrl-C. It ends the command there, exit 130."""
    from cli.test_entry import _DROPPING_PLUGIN  # tests/cli: the callback that drops it

    tree = "tree:\n  sequence:\n    - mode: safe\n    - wait: 0.1s\n    - mode: passive\n"
    (tmp_path / "plain.yaml").write_text(f"mission: m\n{tree}")
    (tmp_path / "drop.py").write_text(_DROPPING_PLUGIN)
    (tmp_path / "drop.yaml").write_text(f"mission: m\nplugins: [./drop.py]\n{tree}")
    record = tmp_path / "run.jsonl"
    ran = ["run", str(tmp_path / "plain.yaml"), "--fast", "--display", "none"]
    assert main([*ran, "--record", str(record)]) == 0
    code, out, err = _record_view(
        child, str(record), "--mission", str(tmp_path / "drop.yaml"), "--allow-plugin-files"
    )
    assert "the import went on\n" in out  # the interrupt was dropped, as in the field
    assert not any(line.startswith("monitor: http") for line in out), out
    assert code == ExitCode.INTERRUPTED, (out, err)
    assert err.splitlines()[-1] == "roomba-bt: interrupted", err
    assert_quoted("docs/monitor.md", "roomba-bt: interrupted", err)


@pytest.mark.parametrize("level", [logging.INFO, logging.DEBUG], ids=["default", "-v"])
def test_a_record_view_says_its_replay_s_start_only_at_v(
    tmp_path: Path, caplog: pytest.LogCaptureFixture, level: int
) -> None:
    """The replay's connection's INFO lines (its start, "streaming [...]") are the page's to
    show, not stderr's; ``-v`` (the DEBUG level) still says them, as it says the rest."""
    from roomba_bt.cli import build_parser
    from roomba_bt.cli.run_cmd import load_recorded
    from roomba_bt.monitor.recorded import replay_into_feed

    record = tmp_path / "run.jsonl"
    _record_the_shuttle(record)
    recorded = load_recorded(build_parser().parse_args(["monitor", str(record)]))
    assert not isinstance(recorded, int)
    caplog.clear()
    caplog.set_level(level)
    replay_into_feed(
        recorded.record, recorded.mission, recorded.profile, recorded.packets, recorded.baud,
        str(record),
    )  # fmt: skip
    started = [r for r in caplog.records if "streaming [" in r.getMessage()]
    assert len(started) == (level == logging.DEBUG), caplog.text


@pytest.mark.parametrize("level", [logging.INFO, logging.DEBUG], ids=["default", "-v"])
def test_replay_says_its_start_only_at_v_and_the_mission_s_log_as_the_run_did(
    tmp_path: Path, caplog: pytest.LogCaptureFixture, level: int
) -> None:
    """``roomba-bt replay RECORD`` printed ``INFO roomba_bt.robot.connection:
    replay:RECORD: iRobot Create 2 in Passive, streaming [...]`` on stderr for every record,
    where ``monitor RECORD`` said it only at ``-v`` (the DEBUG level): one rule for both
    (``replay_judged``). The mission's own ``log`` lines stay: ``replay`` has no page."""
    mission = tmp_path / "said.yaml"
    mission.write_text(LOGGED)
    record = tmp_path / "run.jsonl"
    assert main(["run", str(mission), "--fast", "--display", "none", "--record", str(record)]) == 0
    caplog.clear()
    caplog.set_level(level)
    assert main(["replay", str(record), "--display", "none"]) == 0
    said = [r.getMessage() for r in caplog.records]
    started = [m for m in said if m.startswith("replay:") and "streaming [" in m]
    assert len(started) == (level == logging.DEBUG), said
    assert "starting the leg" in said and "the leg is done" in said, said


#: a mission whose log says something at info and at warning
LOGGED = """\
tree:
  sequence:
    - mode: safe
    - log: starting the leg
    - drive: {velocity: 100 mm/s, distance: 0.1 m}
    - log: {message: the leg is done, level: warning}
    - mode: passive
"""


@pytest.mark.parametrize("level", [logging.INFO, logging.DEBUG], ids=["default", "-v"])
def test_a_record_view_puts_the_mission_s_log_on_its_page_not_on_stderr(
    tmp_path: Path, caplog: pytest.LogCaptureFixture, level: int
) -> None:
    """``monitor RECORD`` printed each ``log`` line of the recorded run on stderr, without its
    time, before the page's URL: its warning is in the page's event log, as a live run's page
    has it, and its info line is there as its leaf's status; ``-v`` says them on stderr too."""
    pytest.importorskip("aiohttp")
    from roomba_bt.cli import build_parser
    from roomba_bt.cli.run_cmd import load_recorded
    from roomba_bt.monitor.recorded import replay_into_feed

    mission = tmp_path / "said.yaml"
    mission.write_text(LOGGED)
    record = tmp_path / "run.jsonl"
    assert main(["run", str(mission), "--fast", "--display", "none", "--record", str(record)]) == 0
    recorded = load_recorded(build_parser().parse_args(["monitor", str(record)]))
    assert not isinstance(recorded, int)
    caplog.clear()
    caplog.set_level(level)
    feed, _ = replay_into_feed(
        recorded.record, recorded.mission, recorded.profile, recorded.packets, recorded.baud,
        str(record),
    )  # fmt: skip
    said = [r.getMessage() for r in caplog.records if r.name == "roomba_bt.mission"]
    assert said == (["starting the leg", "the leg is done"] if level == logging.DEBUG else [])
    events = [(e.kind, e.text) for e in feed.events]
    assert ("warning", "the leg is done") in events, events
    assert any(t.startswith("log(starting the leg) -> SUCCESS") for _, t in events), events


def test_monitor_of_a_record_on_a_wildcard_address_says_the_machine_s_name(
    tmp_path: Path, served_record: ServedRecord
) -> None:
    """``monitor RECORD --monitor 0.0.0.0:PORT`` printed only the 0.0.0.0 URL, which a phone
    cannot open; ``run`` said the machine's name and addresses too."""
    record = tmp_path / "run.jsonl"
    _record_the_shuttle(record)
    out, _ = served_record(record, "--monitor", "0.0.0.0:0", until="monitor: it listens")
    lines = out.splitlines()
    at = next(i for i, line in enumerate(lines) if line.startswith("monitor: http://0.0.0.0:"))
    assert lines[at + 1].startswith(
        f"monitor: it listens on every address of this machine: http://{socket.gethostname()}:"
    )


def test_a_wildcard_address_is_said_by_the_machine_s_lan_addresses_too(
    capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """A bare host name often does not resolve from a phone on a home LAN: the addresses
    do (``http://192.0.2.2:8765/?token=...``)."""
    from roomba_bt.cli import monitor_cmd

    monkeypatch.setattr(monitor_cmd, "lan_addresses", lambda ipv6=False: ["192.0.2.77"])
    argv = ["run", str(SHUTTLE), "--fast", "--display", "none", "--monitor", "0.0.0.0:0",
            "--timeout", "1s"]  # fmt: skip
    assert main(argv) == 1
    lines = capsys.readouterr().out.splitlines()
    match = re.fullmatch(
        r"monitor: http://0\.0\.0\.0:(\d+)/\?token=(\S+) \(shuttle on simulator empty-room\)",
        lines[0],
    )
    assert match, lines[0]
    port, token = match.groups()
    assert lines[1].endswith(f" or, by address, http://192.0.2.77:{port}/?token={token}")
    # the view-only link, to share (a class, a projector), said the same way
    match = re.fullmatch(
        rf"monitor: view only: http://0\.0\.0\.0:{port}/view/\?token=(\S+)", lines[2]
    )
    assert match, lines[2]
    view = match.group(1)
    assert view != token
    assert lines[3].startswith("monitor: view only: it listens on every address of this machine")
    assert lines[3].endswith(f" or, by address, http://192.0.2.77:{port}/view/?token={view}")
    # the page's: its tokens CONTROL and VIEW, its machine vm, its run dock on a robot's port
    page = {token: "CONTROL", view: "VIEW", socket.gethostname(): "vm",
            "shuttle on simulator empty-room": "dock on /dev/ttyUSB0"}  # fmt: skip
    said = "\n".join(lines)
    assert_quoted("docs/monitor.md", "monitor: http://0.0.0.0:8765/?token=CONTROL", said,
                  numbers=True, names=page)  # fmt: skip
    assert_quoted("docs/monitor.md", "monitor: it listens on every address", said, numbers=True,
                  names=page)  # fmt: skip
    assert_quoted("docs/monitor.md", "monitor: view only: http://0.0.0.0:8765/view/?token=VIEW",
                  said, numbers=True, names=page)  # fmt: skip
    assert_quoted("docs/monitor.md", "monitor: view only: it listens", said, numbers=True,
                  names=page)  # fmt: skip


def test_the_lan_addresses_leave_out_loopback_and_link_local() -> None:
    from roomba_bt.monitor.address import lan_addresses

    for text in lan_addresses(ipv6=True):
        address = ipaddress.ip_address(text)
        assert not (address.is_loopback or address.is_link_local or address.is_unspecified)


def test_a_record_view_whose_replay_diverges_says_where_on_stderr_and_the_page(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], served_record: ServedRecord
) -> None:
    """A record whose replay diverges (another mission, an older record) ended the view there
    saying only 'input ended (recorded run, N ticks)'; stderr said nothing. Now it says where,
    what was expected and what was sent, as ``replay`` does; the page's banner holds the same
    (``feed.finished``)."""
    record = tmp_path / "run.jsonl"
    _record_the_shuttle(record)
    capsys.readouterr()
    faster = tmp_path / "faster.yaml"
    faster.write_text(SHUTTLE.read_text().replace("velocity: 100 mm/s", "velocity: 150 mm/s"))
    out, err = served_record(record, "--mission", str(faster))
    said = (
        "replay diverged from the record at t=0.01 s: expected Drive (137) 89 00 64 80 00, "
        "sent Drive (137) 89 00 96 80 00; the timeline ends there"
    )
    assert f"monitor: {record}: {said}" in err, err
    assert out.startswith(f"{record}: {said} (recorded run, "), out


def test_a_record_says_how_its_run_ended_and_its_replay_ends_there(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], served_record: ServedRecord
) -> None:
    """The record's end note: ``replay`` and the record view say how the recorded run ended
    (they said 'input ended'), and a replay ends a timed-out run where it timed out."""
    record = tmp_path / "run.jsonl"
    assert _record_the_shuttle(record) == 1
    capsys.readouterr()
    ended = "the recorded run ended in timeout at t=2.01 s: --timeout 2 s of mission time ran out"
    assert main(["replay", str(record)]) == 0
    out = capsys.readouterr().out
    assert f"replay: {ended}" in out
    assert "the tree wrote the same" in out
    out, _ = served_record(record)
    assert out.startswith(f"{record}: {ended}"), out


def _status(request: Any) -> int:
    """The HTTP status the monitor answers ``request`` (a ``urllib.request.Request``) with."""
    import urllib.error
    import urllib.request

    try:
        with urllib.request.urlopen(request, timeout=HANG_S) as response:
            return int(response.status)
    except urllib.error.HTTPError as exc:
        exc.close()
        return exc.code


#: a token of the operator's own (32 URL-safe characters)
CHOSEN = "Bookmark-ed_token-0123456789abcd"


def _probe_once_up(
    monkeypatch: pytest.MonkeyPatch, requests_to: Callable[[MonitorServer], dict[str, Any]]
) -> dict[str, int]:
    """Once the run's page is up: the HTTP status of each request ``requests_to(server)``
    names, by its name (filled in while the run is on: read it once the run has ended)."""
    from roomba_bt.monitor.server import MonitorServer

    statuses: dict[str, int] = {}
    start = MonitorServer.start

    def probed(server: MonitorServer) -> str:
        url = start(server)
        for name, request in requests_to(server).items():
            statuses[name] = _status(request)
        return url

    monkeypatch.setattr(MonitorServer, "start", probed)
    return statuses


def _probe_the_page(monkeypatch: pytest.MonkeyPatch) -> dict[str, int]:
    """Once the run's page is up: the page's HTTP status with the chosen token, with none
    and with another (``"given"``, ``"none"``, ``"wrong"``)."""
    import urllib.request

    def requests_to(server: MonitorServer) -> dict[str, Any]:
        page = f"http://127.0.0.1:{server.port}/"
        return {
            name: urllib.request.Request(page, headers={"X-Monitor-Token": token} if token else {})
            for name, token in (("given", CHOSEN), ("none", ""), ("wrong", "x" * 32))
        }

    return _probe_once_up(monkeypatch, requests_to)


def _run_with_a_chosen_token(
    token: str, given_by: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> Path:
    """Run the shuttle with its page on every address and ``token``, a token of the
    operator's own, given by ``given_by``: a command-line option (``--monitor-token``) or an
    environment variable (``ROOMBA_BT_MONITOR_TOKEN``). The run's record, once its
    ``--timeout`` has ended it."""
    record = tmp_path / "run.jsonl"
    argv = ["run", str(SHUTTLE), "--fast", "--display", "log", "--monitor", "0.0.0.0:0",
            "--timeout", "1s", "--record", str(record)]  # fmt: skip
    if given_by.startswith("--"):
        argv += [given_by, token]
    else:
        monkeypatch.setenv(given_by, token)
    assert main(argv) == 1
    return record


@pytest.mark.parametrize("given_by", ["--monitor-token", "ROOMBA_BT_MONITOR_TOKEN"])
def test_a_chosen_token_outlives_the_run_and_is_printed_nowhere(
    given_by: str,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
    caplog: pytest.LogCaptureFixture,
) -> None:
    """A new token every run broke a bookmark or a phone's shortcut every run.
    ``--monitor-token`` (or ``ROOMBA_BT_MONITOR_TOKEN``) is the page's token instead; the
    operator knows it, so the URL printed leaves it out, and neither the log nor the record
    holds it."""
    statuses = _probe_the_page(monkeypatch)
    record = _run_with_a_chosen_token(CHOSEN, given_by, tmp_path, monkeypatch)
    assert statuses == {"given": 200, "none": 401, "wrong": 403}
    out, err = capsys.readouterr()
    first = out.splitlines()[0]
    assert re.fullmatch(r"monitor: http://0\.0\.0\.0:\d+/ \(shuttle on simulator empty-room\) "
                        r"\(add \?token= and your --monitor-token, or open your bookmark\)",
                        first), first  # fmt: skip
    assert CHOSEN not in out + err + caplog.text + record.read_text()
    robot = {"shuttle on simulator empty-room": "dock on /dev/ttyUSB0"}  # the page's robot
    assert_quoted("docs/monitor.md", "monitor: http://0.0.0.0:8765/ (dock on", first,
                  numbers=True, names=robot)  # fmt: skip


@pytest.mark.parametrize(
    ("token", "said"),
    [
        ("short-token", "it has 11 characters; a token is 24 to 256 characters"),
        ("a token with spaces in it!", "it has a character other than A-Z a-z 0-9 - _"),
    ],
)
def test_a_chosen_token_that_will_not_do_is_a_usage_error_that_does_not_repeat_it(
    token: str, said: str, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    argv = ["run", str(SHUTTLE), "--fast", "--display", "none", "--monitor", "0"]
    with pytest.raises(SystemExit) as exited:
        main([*argv, "--monitor-token", token])
    assert exited.value.code == 2
    err = capsys.readouterr().err
    assert f"argument --monitor-token: {said}" in err and token not in err
    monkeypatch.setenv("ROOMBA_BT_MONITOR_TOKEN", token)
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert f"roomba-bt run: ROOMBA_BT_MONITOR_TOKEN: {said}" in err and token not in err
    assert "secrets.token_urlsafe(18)" in err


#: a view-only token of the operator's own (a projector's bookmark)
VIEW_CHOSEN = "Projector-view_token-0123456789ab"


@pytest.mark.parametrize(
    "option",
    [
        ["--monitor-token", CHOSEN],
        ["--monitor-view-token", VIEW_CHOSEN],
        ["--monitor-readonly"],
        ["--monitor-force"],
    ],
    ids=lambda option: option[0],
)
def test_a_monitor_option_without_a_page_is_said(
    option: list[str], capsys: pytest.CaptureFixture[str]
) -> None:
    """``--monitor-readonly`` and ``--monitor-force`` alone were ignored without a word
    (the run served no page) while a token alone was this error."""
    assert main(["run", str(SHUTTLE), "--fast", "--display", "none", *option]) == 2
    assert f"roomba-bt run: {option[0]} is for --monitor: add it" in capsys.readouterr().err


def _probe_the_view_link(monkeypatch: pytest.MonkeyPatch) -> dict[str, int]:
    """Once the run's page is up: the HTTP status of its page and of a pause with
    :data:`VIEW_CHOSEN` (``"page"``, ``"control"``)."""
    import urllib.request

    def requests_to(server: MonitorServer) -> dict[str, Any]:
        base, headers = f"http://127.0.0.1:{server.port}", {"X-Monitor-Token": VIEW_CHOSEN}
        body = json.dumps({"action": "pause", "run": server.feed.run_id}).encode()
        return {
            "page": urllib.request.Request(f"{base}/", headers=headers),
            "control": urllib.request.Request(f"{base}/api/control", body, headers),
        }

    return _probe_once_up(monkeypatch, requests_to)


@pytest.mark.parametrize("given_by", ["--monitor-view-token", "ROOMBA_BT_MONITOR_VIEW_TOKEN"])
def test_a_chosen_view_token_opens_the_page_without_controls_and_is_printed_nowhere(
    given_by: str,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
    caplog: pytest.LogCaptureFixture,
) -> None:
    """A projector's bookmark of the view-only link, kept from run to run
    (``--monitor-view-token`` or ``ROOMBA_BT_MONITOR_VIEW_TOKEN``): it opens the page, its
    pause is refused (403), and the URL printed leaves it out, as a chosen control token."""
    statuses = _probe_the_view_link(monkeypatch)
    record = _run_with_a_chosen_token(VIEW_CHOSEN, given_by, tmp_path, monkeypatch)
    assert statuses == {"page": 200, "control": 403}
    out, err = capsys.readouterr()
    lines = out.splitlines()
    assert re.fullmatch(r"monitor: http://0\.0\.0\.0:\d+/\?token=\S+ \(shuttle on simulator "
                        r"empty-room\)", lines[0]), lines[0]  # fmt: skip
    view_line = r"monitor: view only: http://0\.0\.0\.0:\d+/view/ \(add \?token= and your "
    view_line += r"--monitor-view-token, or open its bookmark\)"
    assert re.fullmatch(view_line, lines[2]), lines[2]
    assert VIEW_CHOSEN not in out + err + caplog.text + record.read_text()
    assert_quoted("docs/monitor.md", "monitor: view only: http://0.0.0.0:8765/view/ (add", out,
                  numbers=True)  # fmt: skip


def test_a_view_token_that_is_the_control_token_is_a_usage_error(
    capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """Whoever had the view link would have had the controls."""
    argv = ["run", str(SHUTTLE), "--fast", "--display", "none", "--monitor", "0"]
    assert main([*argv, "--monitor-token", CHOSEN, "--monitor-view-token", CHOSEN]) == 2
    err = capsys.readouterr().err
    assert "the view-only token (--monitor-view-token or ROOMBA_BT_MONITOR_VIEW_TOKEN)" in err
    assert "whoever has the view link would have the controls" in err and CHOSEN not in err
    monkeypatch.setenv("ROOMBA_BT_MONITOR_VIEW_TOKEN", CHOSEN)
    assert main([*argv, "--monitor-token", CHOSEN]) == 2
    assert "would have the controls" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("name", "size_said"),
    [
        ("run.jsonl", r"1\.\d MB"),
        # the text's size, from gzip's trailer, beside the file's: it said the file's alone,
        # and this one, under 1 MB, was read without a word
        ("run.jsonl.gz", r"1\.\d MB of record, 0\.\d MB compressed"),
    ],
    ids=["plain", "compressed"],
)
def test_a_record_of_a_megabyte_says_at_once_that_it_is_read_before_its_page(
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
    name: str,
    size_said: str,
) -> None:
    """``roomba-bt monitor RECORD`` replays the whole record before it serves the page (its
    timeline is the whole run's): a 6-minute clean run's record printed nothing for 5 s, and
    the URL seemed slow to come. From 1 MB of record on it says so first, before the
    replay."""
    from roomba_bt.monitor.server import MonitorServer

    record = tmp_path / name
    argv = ["run", str(SHUTTLE), "--fast", "--display", "none", "--timeout", "170s"]
    main([*argv, "--record", str(record)])
    capsys.readouterr()
    replayed: list[bool] = []

    def port_taken(server: MonitorServer) -> str:  # the replay is done: end here
        replayed.append(True)
        raise OSError(98, "Address already in use")

    monkeypatch.setattr(MonitorServer, "start", port_taken)
    assert main(["monitor", str(record), "--monitor", "0"]) == 2
    assert replayed  # the notice came, then the replay, then the serving
    first = capsys.readouterr().err.splitlines()[0]
    assert re.fullmatch(
        f"monitor: reading {re.escape(str(record))} \\({size_said}\\) before serving it: the "
        "page's timeline is the whole run's, so every tick is replayed first",
        first,
    ), first
    if name == "run.jsonl":
        assert_quoted("docs/monitor.md", "monitor: reading long.jsonl", first, numbers=True,
                      names={str(record): "long.jsonl"})  # fmt: skip


def test_a_record_s_page_names_the_robot_and_start_its_header_gives(tmp_path: Path) -> None:
    """The record's view named neither: three robots' records of one class mission looked
    the same."""
    from roomba_bt.monitor.views import run_view

    from .live import replayed_record

    feed, _ = replayed_record(SHUTTLE, "1s", tmp_path / "shuttle.jsonl")
    header = json.loads((tmp_path / "shuttle.jsonl").read_text().splitlines()[0])
    shown = run_view(feed)
    assert shown["robot"] == "simulator empty-room"
    assert shown["started"] == header["started"]


def test_a_record_made_before_it_held_its_start_shows_the_start_unknown(
    tmp_path: Path,
) -> None:
    """A record made before the header held ``started`` showed the time the monitor was
    opened as the run's start (a record of 00:30:08 "started" at 00:31:30); the robot it
    does not name either was shown as unknown (empty) already."""
    from roomba_bt.mission import load_mission
    from roomba_bt.monitor.recorded import replay_into_feed
    from roomba_bt.monitor.views import run_view
    from roomba_bt.oi.profiles import CREATE2
    from roomba_bt.runtime.recording import load_record

    from .live import replayed_record

    made = tmp_path / "shuttle.jsonl"
    replayed_record(SHUTTLE, "1s", made)
    lines = made.read_text(encoding="utf-8").splitlines(keepends=True)
    header = json.loads(lines[0])
    older = tmp_path / "older.jsonl"
    before = {k: v for k, v in header.items() if k not in ("port", "started")}
    older.write_text("".join([json.dumps(before) + "\n", *lines[1:]]), encoding="utf-8")
    record = load_record(older)
    mission = load_mission(SHUTTLE, {}, profile=CREATE2)
    packets = tuple(record.header["packets"])
    feed, _ = replay_into_feed(record, mission, CREATE2, packets, 115200, "older")
    shown = run_view(feed)
    assert shown["started"] == "" and shown["robot"] == ""


def test_a_program_builds_a_live_monitor_from_typed_options(tmp_path: Path) -> None:
    """``LiveMonitor`` took ``run``'s argparse namespace, read by attribute names a program
    had to guess (``monitor_readonly``, ``fast``...): it takes :class:`MonitorOptions`, which
    ``run`` converts its options into."""
    import argparse

    from roomba_bt.cli.monitor_cmd import LiveMonitor, MonitorOptions
    from roomba_bt.mission import load_mission

    mission = load_mission(SHUTTLE)
    options = MonitorOptions(mission=SHUTTLE, watch=True, virtual_clock=True)
    monitor = LiveMonitor(
        options, mission, simulator=None, packets=(7,), loader=load_mission, robot="by hand"
    )
    assert monitor.session.state.watching == str(SHUTTLE)
    assert monitor.bind() is None and monitor.server is None  # no address: no page
    monitor.finish(None)
    assert monitor.feed.finished == "the run did not start"
    args = argparse.Namespace(
        mission=str(SHUTTLE), monitor=("127.0.0.1", 0), monitor_readonly=True,
        monitor_token=None, monitor_force=False, watch=False, fast=True,
    )  # fmt: skip
    assert MonitorOptions.from_args(args) == MonitorOptions(
        mission=SHUTTLE, address=("127.0.0.1", 0), readonly=True, virtual_clock=True
    )


def test_a_recorded_view_draws_the_world_its_record_names_from_where_the_robot_started(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], viewed_record: ServedRecord
) -> None:
    """The recorded page drew the bare odometry in its own frame (no rooms, no dock) though
    the record's header names the world: a shipped one by its name, a file by its path from
    the record's folder (found as ``replay`` finds the mission). A world gone since is said on
    stderr, and the page draws the odometry alone; a robot's record names none."""
    from roomba_bt.monitor.recorded import recorded_world
    from roomba_bt.runtime.recording import SIMULATOR, load_record
    from roomba_bt.sim.world import WORLDS_DIR, load_world

    shipped = tmp_path / "shipped.jsonl"
    _record_the_shuttle(shipped, "--world", "apartment")
    drawn = recorded_world(load_record(shipped), SHUTTLE)
    assert isinstance(drawn, tuple)
    world, start = drawn
    apartment = load_world("apartment")
    assert world["name"] == apartment.name and world["rooms"] and world["dock"] is not None
    assert start == (apartment.start.x, apartment.start.y, apartment.start.theta)

    own = tmp_path / "worlds" / "mine.yaml"
    own.parent.mkdir()
    own.write_text((WORLDS_DIR / "apartment.yaml").read_text())
    (tmp_path / "records").mkdir()
    (tmp_path / "missions").mkdir()
    mission = tmp_path / "missions" / "shuttle.yaml"  # records/, missions/, worlds/: one project
    mission.write_text(SHUTTLE.read_text())
    by_path = tmp_path / "records" / "run.jsonl"
    _record_the_shuttle(by_path, "--world", str(own), mission=mission)
    record = load_record(by_path)
    assert record.header[SIMULATOR]["world"] == "../worlds/mine.yaml"
    drawn = recorded_world(record, mission)
    assert isinstance(drawn, tuple) and drawn[0]["rooms"] == world["rooms"]
    capsys.readouterr()

    own.unlink()
    problem = recorded_world(load_record(by_path), mission)
    assert isinstance(problem, str) and problem.startswith("its world ../worlds/mine.yaml: ")
    assert problem.endswith("; the page draws the odometry alone")
    _, err = viewed_record(by_path)
    assert f"monitor: {by_path}: its world ../worlds/mine.yaml: " in err, err
    assert_quoted("docs/monitor.md", "monitor: R.jsonl: its world ../worlds/mine.yaml", err,
                  names={str(by_path): "R.jsonl"})  # fmt: skip

    robot = load_record(shipped)
    del robot.header[SIMULATOR]
    assert recorded_world(robot, SHUTTLE) is None


def test_a_records_world_outside_its_folder_is_not_read_and_its_header_texts_are_escaped(
    tmp_path: Path, viewed_record: ServedRecord
) -> None:
    """A stranger's record named ``../home/.pgpass`` (or ``/etc/shadow``) as its world, and
    ``monitor RECORD`` opened it and quoted its lines in the world's errors: a user pasting
    that output sent the record's author their secrets. A world is read only inside the
    folder that holds the record and its mission, as the record's include folders are; its
    name reaches the terminal escaped, as the label does."""
    from roomba_bt.monitor.recorded import recorded_world
    from roomba_bt.runtime.recording import SIMULATOR, load_record

    secret = tmp_path / "home" / ".pgpass"
    secret.parent.mkdir()
    secret.write_text("db.example.com:5432:prod:admin:S3cretPgPass\n")
    project = tmp_path / "shared"
    project.mkdir()
    mission = project / "shuttle.yaml"
    mission.write_text(SHUTTLE.read_text())
    made = project / "made.jsonl"
    _record_the_shuttle(made, mission=mission)
    lines = made.read_text().splitlines()
    header = json.loads(lines[0])
    for world in ("../home/.pgpass", str(secret)):
        header[SIMULATOR]["world"] = world
        stranger = project / "stranger.jsonl"
        stranger.write_text("\n".join([json.dumps(header), *lines[1:]]) + "\n")
        problem = recorded_world(load_record(stranger), mission)
        assert isinstance(problem, str) and "S3cret" not in problem, problem
        assert f"its world {world} is outside the folder that holds the record" in problem
        _, err = viewed_record(stranger)
        assert "S3cret" not in err and "is outside the folder" in err, err
        if world == str(secret):  # docs/runtime.md's, a record naming /etc/shadow
            page = {str(stranger): "r.jsonl", str(secret): "/etc/shadow"}
            assert_quoted("docs/runtime.md", "monitor: r.jsonl: its world /etc/shadow", err,
                          names=page)  # fmt: skip

    header[SIMULATOR]["world"] = "W\x1b]0;PWNED\x07\u202e"
    stranger.write_text("\n".join([json.dumps(header), *lines[1:]]) + "\n")
    _, err = viewed_record(stranger)
    assert "\x1b" not in err and "\u202e" not in err, err
    assert "its world W\\x1b]0;PWNED\\x07\\u202e" in err, err


def test_a_world_given_by_name_is_recorded_by_name_and_drawn_from_the_users_world_folders(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, viewed_record: ServedRecord
) -> None:
    """A world of ``ROOMBA_BT_WORLDS``'s, given by name, was recorded as its path from the
    record's folder (``../../worlds/living.yaml``), and ``monitor RECORD`` refused it as
    outside the folder holding the record and its mission: with nothing to grant it. It is
    recorded by its name now, and found again through the variable; a record made before,
    naming a file in one of the user's world folders, is read; and ``--world`` draws the
    world the user gives, the refusal naming it."""
    from roomba_bt.monitor.recorded import recorded_world
    from roomba_bt.monitor.views import world_drawing
    from roomba_bt.runtime.recording import SIMULATOR, load_record
    from roomba_bt.sim.world import WORLDS_DIR, load_world

    worlds = tmp_path / "worlds"  # beside the project, as the variable invites
    worlds.mkdir()
    own = worlds / "living.yaml"
    own.write_text((WORLDS_DIR / "apartment.yaml").read_text())
    project = tmp_path / "project"
    (project / "records").mkdir(parents=True)
    (project / "missions").mkdir()
    mission = project / "missions" / "shuttle.yaml"
    mission.write_text(SHUTTLE.read_text())
    record = project / "records" / "run.jsonl"
    monkeypatch.setenv("ROOMBA_BT_WORLDS", str(worlds))
    _record_the_shuttle(record, "--world", "living", mission=mission)
    assert load_record(record).header[SIMULATOR]["world"] == "living"
    drawn = recorded_world(load_record(record), mission)
    assert isinstance(drawn, tuple) and drawn[0] == world_drawing(load_world(own))
    _, err = viewed_record(record)
    assert "its world" not in err, err

    lines = record.read_text().splitlines()
    header = json.loads(lines[0])
    header[SIMULATOR]["world"] = "../../worlds/living.yaml"  # as a record made before says it
    before = project / "records" / "before.jsonl"
    before.write_text("\n".join([json.dumps(header), *lines[1:]]) + "\n")
    assert isinstance(recorded_world(load_record(before), mission), tuple)

    monkeypatch.delenv("ROOMBA_BT_WORLDS")  # another shell: neither is found nor granted
    for made, said in ((record, "living: no such world"), (before, "living.yaml is outside")):
        problem = recorded_world(load_record(made), mission)
        assert isinstance(problem, str) and said in problem, problem
        assert "monitor --world FILE_OR_NAME" in problem, problem
        assert isinstance(recorded_world(load_record(made), mission, load_world(own)), tuple)
        _, err = viewed_record(made, "--world", str(own))
        assert "its world" not in err, err


def test_a_records_world_of_another_digest_is_said_and_not_drawn(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, viewed_record: ServedRecord
) -> None:
    """The world a record names was found by name (or path) and drawn without its digest
    looked at: a world of that name in another folder, or the file edited since, was drawn as
    the one the run used. It is said on stderr, with both digests, and not drawn (the
    odometry alone); ``--world`` still draws the one the user gives; the same file is."""
    from roomba_bt.monitor.recorded import recorded_world
    from roomba_bt.runtime.recording import SIMULATOR, load_record
    from roomba_bt.sim.world import WORLDS_DIR, load_world

    worlds, elsewhere = tmp_path / "worlds", tmp_path / "elsewhere"
    worlds.mkdir()
    elsewhere.mkdir()
    (worlds / "living.yaml").write_text((WORLDS_DIR / "apartment.yaml").read_text())
    (elsewhere / "living.yaml").write_text(
        (WORLDS_DIR / "empty-room.yaml").read_text().replace("empty-room", "living")
    )
    mission = tmp_path / "shuttle.yaml"
    mission.write_text(SHUTTLE.read_text())
    record = tmp_path / "run.jsonl"
    monkeypatch.setenv("ROOMBA_BT_WORLDS", str(worlds))
    _record_the_shuttle(record, "--world", "living", mission=mission)
    recorded = load_record(record).header[SIMULATOR]["world_sha256"]
    assert isinstance(recorded_world(load_record(record), mission), tuple)

    monkeypatch.setenv("ROOMBA_BT_WORLDS", str(elsewhere))  # another world of that name
    problem = recorded_world(load_record(record), mission)
    assert isinstance(problem, str), problem
    assert problem.startswith(
        f"its world living ({elsewhere / 'living.yaml'}) is not the file the run used: its "
        "SHA-256 is "
    ), problem
    assert f"the record's {recorded[:12]}... (edited since, or another world of that name)" in (
        problem
    )
    assert problem.endswith(
        "not drawn (monitor --world FILE_OR_NAME draws the one you give); the page draws the "
        "odometry alone"
    ), problem
    _, err = viewed_record(record)
    assert f"monitor: {record}: its world living (" in err and "not the file the run" in err
    found = hashlib.sha256((elsewhere / "living.yaml").read_bytes()).hexdigest()
    page = {str(record): "R.jsonl", str(elsewhere): "/home/me/worlds",
            found[:12]: "3f2a9c01b7e4", recorded[:12]: "dac2aafaa32f"}  # fmt: skip
    assert_quoted("docs/monitor.md", "monitor: R.jsonl: its world living", err, names=page)
    _, err = viewed_record(record, "--world", str(elsewhere / "living.yaml"))
    assert "its world" not in err, err

    monkeypatch.setenv("ROOMBA_BT_WORLDS", str(worlds))  # the same name, the file edited
    own = worlds / "living.yaml"
    own.write_text(own.read_text() + "# a chair moved\n")
    problem = recorded_world(load_record(record), mission)
    assert isinstance(problem, str) and "is not the file the run used" in problem, problem
    assert isinstance(recorded_world(load_record(record), mission, load_world(own)), tuple)


def test_monitor_world_that_cannot_be_read_is_exit_2_before_the_replay(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``monitor --world`` is the user's own choice, as ``run --world`` is: a name that finds
    no world, or a broken file, is said as ``run`` says it (each problem at its file:line:col)
    and ends the command before the record is read."""
    record = tmp_path / "run.jsonl"
    _record_the_shuttle(record)
    broken = tmp_path / "broken.yaml"
    broken.write_text("name: broken\nrooms: 3\n")
    capsys.readouterr()
    for given, said in (("nosuch", "roomba-bt monitor: nosuch: "), (str(broken), f"{broken}:2:")):
        assert main(["monitor", str(record), "--monitor", "0", "--world", given]) == 2
        captured = capsys.readouterr()
        assert said in captured.err and "monitor: http" not in captured.out, captured
