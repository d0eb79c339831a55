"""``run --monitor`` and ``roomba-bt monitor`` on the command line: usage errors are exit 2,
before anything moves."""

from __future__ import annotations

import socket
from pathlib import Path

import pytest

from roomba_bt.cli import main

SHUTTLE = Path(__file__).resolve().parent / "missions" / "shuttle.yaml"


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
