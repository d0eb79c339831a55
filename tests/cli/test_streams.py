"""The command's stdout and stderr as a headless run has them (over SSH, from cron, under
systemd, into a pipe): a reader gone, a closed descriptor, a full disk, an ASCII locale, a
pipe nobody reads. Whatever they do, the exit code is the outcome's, with no traceback, and
what goes to stderr and to files still arrives (``roomba_bt/cli/streams.py``).

Each runs the command as a process (its streams are the process's own); none depends on
timing: a pipe's reader is closed before the process starts, or its buffer filled first.
"""

from __future__ import annotations

import fcntl
import io
import os
import signal
import subprocess
import sys
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import Any

import pytest
from quoted import assert_quoted  # tests/quoted.py: the docs' quoted lines
from waits import HANG_S, line  # tests/waits.py: a hang's bound, a line within it

from roomba_bt.cli import main
from roomba_bt.runtime.recording import load_record

CLI = [sys.executable, "-m", "roomba_bt.cli"]
DOCK = Path(__file__).resolve().parents[2] / "missions" / "dock.yaml"


def _env(**extra: str) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if k not in ("NO_COLOR", "PYTHONIOENCODING")}
    env["PYTHONUTF8"] = "1"
    env.update(extra)
    return env


def _reader_gone(args: list[str], cwd: Path) -> subprocess.CompletedProcess[str]:
    """``args`` with stdout a pipe whose reader closed before the process wrote anything
    (``| head -1`` that already has its line): every write to it is EPIPE."""
    read_end, write_end = os.pipe()
    os.close(read_end)
    try:
        proc = subprocess.Popen(
            [*CLI, *args], stdout=write_end, stderr=subprocess.PIPE, stdin=subprocess.DEVNULL,
            text=True, cwd=cwd, env=_env(),
        )  # fmt: skip
    finally:
        os.close(write_end)
    _, err = proc.communicate(timeout=HANG_S)
    return subprocess.CompletedProcess(proc.args, proc.returncode, "", err)


def test_a_closed_pipe_keeps_a_failed_runs_exit_code_and_says_its_outcome(
    tmp_path: Path,
) -> None:
    """``run dock ... | head -5``: the tree before the run hit EPIPE and the process exited
    0 before it connected; now the run runs, exits 1 (its timeout), and stderr says how it
    ended, with the summary's outcome, since stdout lost it."""
    done = _reader_gone(["run", "dock", "--fast", "--timeout", "1s"], tmp_path)
    assert done.returncode == 1, done.stderr
    assert "Traceback" not in done.stderr
    assert "roomba-bt: timeout: --timeout 1 s" in done.stderr
    lost = "roomba-bt: the summary was lost with stdout (Broken pipe): outcome TIMEOUT"
    assert lost in done.stderr
    assert "final mode Passive" in done.stderr
    assert_quoted("docs/runtime.md", "roomba-bt: the summary was lost with stdout", done.stderr)


def test_a_closed_pipe_keeps_validates_exit_code(tmp_path: Path) -> None:
    """``validate bad.yaml | head -1``: an invalid mission exited 0 (or 120, the
    interpreter's flush failing at exit)."""
    bad = tmp_path / "bad.yaml"
    bad.write_text("mission: bad\ntree:\n  sequence:\n    - no_such_leaf: {}\n")
    done = _reader_gone(["validate", str(bad)], tmp_path)
    assert done.returncode == 2, done.stderr
    assert "Traceback" not in done.stderr and "Exception ignored" not in done.stderr


def test_a_closed_pipe_keeps_a_differing_replays_exit_code(mission: Path, tmp_path: Path) -> None:
    """``replay r.jsonl -p speed=250mm/s | head -2``: a replay that differs exited 0."""
    record = tmp_path / "r.jsonl"
    assert main(["run", str(mission), "--fast", "--display", "none", "--record", str(record)]) == 0
    done = _reader_gone(["replay", str(record), "-p", "speed=250mm/s"], tmp_path)
    assert done.returncode == 1, done.stderr
    assert "Traceback" not in done.stderr


@pytest.mark.extra("plot")
def test_the_plot_is_written_when_stdout_is_gone(tmp_path: Path) -> None:
    """``run ... --plot p.png | head -1``: the report stopped at the first failed print, and
    the plot after it was never drawn."""
    plot = tmp_path / "p.png"
    done = _reader_gone(
        ["run", "dock", "--fast", "--timeout", "60s", "--plot", str(plot)], tmp_path
    )
    assert done.returncode == 0, done.stderr
    assert plot.stat().st_size > 0
    assert f"trajectory written to {plot}" in done.stderr


def _closed_stdout() -> None:
    os.close(1)


@pytest.mark.parametrize(
    ("args", "code"),
    [(["missions"], 0), (["run", "dock", "--fast", "--timeout", "60s"], 0)],
    ids=["missions", "run"],
)
def test_a_closed_stdout_is_no_traceback(tmp_path: Path, args: list[str], code: int) -> None:
    """``roomba-bt ... >&-``: py_trees read ``sys.stdout.encoding`` at import, and
    ``sys.stdout`` is None: an AttributeError traceback in every subcommand, exit 1."""
    done = subprocess.run(
        [*CLI, *args], stderr=subprocess.PIPE, stdin=subprocess.DEVNULL, text=True,
        cwd=tmp_path, env=_env(), preexec_fn=_closed_stdout, timeout=HANG_S,
    )  # fmt: skip
    assert done.returncode == code, done.stderr
    assert "Traceback" not in done.stderr
    assert "stdout is closed" in done.stderr or "lost with stdout (closed)" in done.stderr
    if args[0] == "run":
        assert "outcome SUCCESS" in done.stderr
    else:  # docs/runtime.md's `>&-`
        assert_quoted("docs/runtime.md", "roomba-bt: stdout is closed", done.stderr)


def test_a_closed_stdout_nothing_was_printed_to_is_not_said(tmp_path: Path) -> None:
    """``validate -q dock.yaml >&-`` from cron: nothing was printed to stdout, so nothing was
    lost, yet every run said "stdout is closed: what the command printed there is lost"."""
    done = subprocess.run(
        [*CLI, "validate", "-q", str(DOCK)], stderr=subprocess.PIPE, stdin=subprocess.DEVNULL,
        text=True, cwd=tmp_path, env=_env(), preexec_fn=_closed_stdout, timeout=HANG_S,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert done.stderr == ""


def test_a_character_the_stream_cannot_encode_is_escaped_not_a_closed_stream() -> None:
    """A stream ``reconfigure`` could not set ``errors=`` on raised UnicodeEncodeError (a
    ValueError) at ``✓``: the guard called that "closed" and dropped all the rest."""
    from roomba_bt.cli.streams import GuardedStream

    raw = io.BytesIO()
    guarded = GuardedStream(io.TextIOWrapper(raw, encoding="ascii"), "stdout")
    guarded.write("\u2713 ok\n")
    guarded.write("done\n")
    guarded.flush()
    assert guarded.failure is None
    assert raw.getvalue() == b"\\u2713 ok\ndone\n"


def test_a_stream_closed_under_the_command_is_said_as_it_failed(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A stream a program closed (``I/O operation on closed file.``) is not a descriptor
    closed before the process started (``>&-``): the end of the command says which."""
    from roomba_bt.cli import streams

    wrapped = io.TextIOWrapper(io.BytesIO(), encoding="utf-8")
    wrapped.close()
    guarded = streams.GuardedStream(wrapped, "stdout")
    guarded.write("summary\n")
    assert guarded.failure == "I/O operation on closed file."
    monkeypatch.setattr(sys, "stdout", guarded)
    assert streams.stdout_problem() == (
        "cannot write to stdout (I/O operation on closed file.): the rest of the output is lost"
    )


def test_a_full_disk_on_stdout_is_one_line_and_the_outcomes_exit_code(tmp_path: Path) -> None:
    """``run ... > /dev/full``: an OSError traceback and exit 1 before the robot started."""
    with open("/dev/full", "w") as full:
        done = subprocess.run(
            [*CLI, "run", "dock", "--fast", "--timeout", "60s"], stdout=full,
            stderr=subprocess.PIPE, stdin=subprocess.DEVNULL, text=True, cwd=tmp_path,
            env=_env(), timeout=HANG_S,
        )  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert "Traceback" not in done.stderr
    assert "(No space left on device): outcome SUCCESS" in done.stderr
    # a command with no summary to keep: docs/runtime.md's line of any other stdout failure
    with open("/dev/full", "w") as full:
        done = subprocess.run(
            [*CLI, "missions"], stdout=full, stderr=subprocess.PIPE, stdin=subprocess.DEVNULL,
            text=True, cwd=tmp_path, env=_env(), timeout=HANG_S,
        )  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert_quoted("docs/runtime.md", "roomba-bt: cannot write to stdout", done.stderr)


@pytest.mark.parametrize(
    "env",
    [{"PYTHONIOENCODING": "ascii"}, {"LC_ALL": "POSIX", "LANG": "C", "PYTHONUTF8": "0"}],
    ids=["PYTHONIOENCODING=ascii", "LC_ALL=POSIX"],
)
def test_an_ascii_stdout_gets_an_ascii_report_and_the_outcomes_exit_code(
    tmp_path: Path, env: dict[str, str]
) -> None:
    """The end report's ``✓``/``✕`` and ``m²`` raised UnicodeEncodeError after a dock that
    succeeded: exit 1, the summary lost. Now ``[ok]``, ``[x]``, ``m2``; and a node's name
    that is not ASCII is written escaped, not a traceback before the run."""
    mission = tmp_path / "named.yaml"
    mission.write_text(
        "mission: fahrt\ntree:\n  sequence:\n    name: Gr\u00fc\u00dfe\n    children:\n"
        "      - mode: safe\n      - wait: 0.5s\n      - mode: passive\n",
        encoding="utf-8",
    )
    for args in (["run", "clean", "--fast", "--timeout", "30s"], ["run", str(mission), "--fast"]):
        done = subprocess.run(
            [*CLI, *args], capture_output=True, stdin=subprocess.DEVNULL, cwd=tmp_path,
            env=_env(**env), timeout=HANG_S,
        )  # fmt: skip
        out, err = done.stdout.decode("ascii"), done.stderr.decode("ascii")  # all ASCII
        assert "Traceback" not in err
        if args[1] == "clean":
            assert done.returncode == 1, err  # its timeout
            assert " m2 of reachable floor" in out
        else:
            assert done.returncode == 0, err
            assert "Gr\\xfc\\xdfe [ok]" in out


def _full_pipe() -> tuple[int, int]:
    """A pipe whose buffer is full: a write to it blocks until someone reads."""
    read_end, write_end = os.pipe()
    fcntl.fcntl(write_end, fcntl.F_SETFL, os.O_NONBLOCK)
    try:
        while True:
            os.write(write_end, b"x" * 4096)
    except BlockingIOError:
        pass
    fcntl.fcntl(write_end, fcntl.F_SETFL, 0)  # the process's writes block
    return read_end, write_end


def test_a_report_blocked_on_a_pipe_nobody_reads_can_be_ended(tmp_path: Path) -> None:
    """``run ... 2>&1 | less`` with nobody scrolling: the run ends and the robot is stopped,
    but the report blocks on the full pipe; TERM, INT and HUP were ignored then (held for
    the summary), and only SIGKILL ended the process. Now the signal ends it. A SIGTERM
    that lands while the run still closes (its record, its port) is ignored, as it must be
    (``tests/runtime/test_signal_while_closing.py``): one is sent every 10 ms until the
    process ends, as an operator presses Ctrl-C again, and the first in the report ends it
    2 s later, with 143: the report cut short by SIGTERM (the run's own code, its timeout's
    1, in sessions 37 and 38, which told a script its report was whole)."""
    record = tmp_path / "r.jsonl"
    read_end, write_end = _full_pipe()
    try:
        proc = subprocess.Popen(
            [*CLI, "run", "dock", "--fast", "--timeout", "1s", "--display", "none",
             "--record", str(record)],
            stdout=write_end, stderr=write_end, stdin=subprocess.DEVNULL, cwd=tmp_path,
            env=_env(),
        )  # fmt: skip
    finally:
        os.close(write_end)
    try:
        for _ in _until(lambda: proc.poll() is not None or _record_ended(record)):
            pass
        assert proc.poll() is None  # blocked on the pipe: the report after the record's end
        for _ in _until(lambda: proc.poll() is not None):  # a report never ended fails
            proc.send_signal(signal.SIGTERM)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(timeout=HANG_S)
        os.close(read_end)
    # ended by the thread the signal set going (robot/safety.py, LAST_WORDS_S) with 128 +
    # the signal: the report cut short (the run's own answer, its timeout's exit 1, in
    # sessions 37 and 38; the signal's default action, -15, before session 36)
    assert proc.returncode == 128 + signal.SIGTERM


def _record_ended(record: Path) -> bool:
    try:
        return load_record(record).ending is not None
    except Exception:  # not there yet, or half written
        return False


def _until(ready: Callable[[], bool]) -> Iterator[None]:
    """Yield until ``ready()`` (polled every 10 ms, for up to :data:`~waits.HANG_S`: a hang
    fails; 3000 polls before, 30 s, which a run's start on a loaded machine may take)."""
    import time

    deadline = time.monotonic() + HANG_S
    while time.monotonic() < deadline:
        if ready():
            return
        yield
        time.sleep(0.01)
    pytest.fail(f"the process never got there in {HANG_S:g} s")


def _plugin_run(tmp_path: Path, plugin: str) -> list[str]:
    """``run m.yaml --fast``'s arguments, for a mission whose plugin file is ``plugin``."""
    (tmp_path / "plugin.py").write_text(plugin)
    mission = tmp_path / "m.yaml"
    mission.write_text("mission: m\nplugins: [./plugin.py]\ntree:\n  sequence:\n    - mode: safe\n")
    return ["run", str(mission), "--fast", "--allow-plugin-files"]


@pytest.mark.parametrize(
    ("signum", "started_as"),
    [(signal.SIGTERM, "a terminal's command"), (signal.SIGINT, "a script's background job")],
    ids=["SIGTERM", "SIGINT-ignored-at-start"],
)
def test_a_signal_before_the_run_took_it_is_exit_130(
    tmp_path: Path,
    signum: int,
    started_as: str,
    child: Callable[[Sequence[str]], subprocess.Popen[str]],
    script_job: Callable[[Sequence[str]], subprocess.Popen[str]],
) -> None:
    """A SIGTERM in the first half second (imports, loading, before the run's handlers) ended
    the process with 143 and no word; the exit-code table says 130 for SIGTERM. A script's
    ``roomba-bt run ... &`` starts with SIGINT ignored, and Python keeps it so: its ``kill
    -INT $!`` then was lost until the run's handlers came, and the whole mission ran, exit
    0 (session 35). A plugin file whose import waits holds the process there."""
    waits = "import os, time\nos.write(2, b'plugin importing\\n')\ntime.sleep(600)\n"
    args = _plugin_run(tmp_path, waits)
    if started_as == "a script's background job":
        proc = script_job(args)
    else:
        proc = child([*CLI, *args])
    assert proc.stderr is not None
    said = line(proc.stderr, "the plugin's import under way")
    assert "plugin importing" in said, said
    proc.send_signal(signum)
    _, err = proc.communicate(timeout=HANG_S)
    assert proc.returncode == 130, err
    by = " by SIGTERM" if signum == signal.SIGTERM else ""  # a Ctrl-C is said as none
    # the import under way is named, at its line (session 38)
    # (at its write, line 2, or its sleep, line 3: where the signal finds it)
    plugin = tmp_path / "plugin.py"
    said = f"roomba-bt: interrupted{by} while importing plugin {plugin} (at {plugin}:"
    assert err.endswith((f"{said}2)\n", f"{said}3)\n")), err
    assert "Traceback" not in err


def test_a_signal_python_wraps_in_a_runtime_error_is_still_exit_130(
    tmp_path: Path, child: Callable[[Sequence[str]], subprocess.Popen[str]]
) -> None:
    """A signal whose handler raises inside a class body's ``__set_name__`` (a dataclass's
    fields, as ``runtime/summary.py`` is imported) comes out of Python before 3.12 as
    ``RuntimeError: Error calling __set_name__``: a SIGTERM 0.35 to 0.6 s into a run on a
    loaded machine was a 40-line traceback and exit 1, "mission failed" (session 35). A
    plugin's class body here sends itself the SIGTERM there."""
    plugin = (
        "import os, signal\n"
        "class Lands:\n"
        "    def __set_name__(self, owner, name):\n"
        "        os.kill(os.getpid(), signal.SIGTERM)\n"
        "class Holder:\n"
        "    field = Lands()\n"
    )
    proc = child([*CLI, *_plugin_run(tmp_path, plugin)])
    _, err = proc.communicate(timeout=HANG_S)
    assert proc.returncode == 130, err
    assert err.endswith("roomba-bt: interrupted by SIGTERM\n")
    assert "Traceback" not in err
    assert_quoted("docs/runtime.md", "roomba-bt: interrupted by SIGTERM$", err)


def test_record_to_stdout_is_refused(tmp_path: Path, monkeypatch: Any) -> None:
    """``--record -`` wrote a file named ``-`` in the current directory."""
    monkeypatch.chdir(tmp_path)
    with pytest.raises(SystemExit) as exited:
        main(["run", "dock", "--fast", "--record", "-"])
    assert exited.value.code == 2
    assert not (tmp_path / "-").exists()
