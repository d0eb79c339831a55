"""``roomba-bt replay`` interrupted by Ctrl-C or SIGTERM: the operator's stop, exit 130, as
every command (docs/runtime.md, Endings), not a verdict on the bytes it cut short."""

from __future__ import annotations

import signal
import threading
from pathlib import Path

import pytest
from quoted import assert_quoted  # tests/quoted.py: the docs' quoted lines

from roomba_bt.cli import main, run_cmd
from roomba_bt.runtime.summary import ExitCode


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_a_replay_interrupted_exits_130_and_judges_no_bytes(
    signum: int, tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:  # fmt: skip
    """A signal sent at random moments into ``replay`` of a 10-minute record exited 1 (17 of
    30: the interrupted run's drive 0 said as "first difference", the record's verdict
    after it) or 0 (5 of 30), 130 seven times. It is the operator's stop: exit 130, the
    summary's INTERRUPTED, and no verdict on bytes the replay never reached."""
    record = tmp_path / "run.jsonl"
    ran = ["run", "bump-and-turn", "-p", "duration=20s", "--fast", "--display", "none"]
    assert main([*ran, "--record", str(record)]) == ExitCode.OK
    capsys.readouterr()
    main_thread = threading.main_thread().ident or 0

    def progress(who: str, recorded: object) -> object:
        def at(fraction: float) -> None:  # the replay's progress, in its reading thread
            if 0.3 < fraction < 0.5:
                signal.pthread_kill(main_thread, signum)

        return at

    monkeypatch.setattr(run_cmd, "replay_progress", progress)
    code = main(["replay", str(record), "--display", "none"])
    out = capsys.readouterr().out
    assert code == ExitCode.INTERRUPTED, out
    assert "outcome      INTERRUPTED" in out
    assert "first difference" not in out and "the same" not in out, out
    assert "replay: interrupted at mission time " in out and "no verdict" in out, out
    assert_quoted("docs/runtime.md", "replay: interrupted at mission time", out, numbers=True)
