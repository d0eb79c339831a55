"""A plugin as 0.1.0 wrote it, calling ``encode(...)`` after ``from roomba_bt.oi import
encode``: in 0.2.0 that name is the encoder's module, and the plugin failed mid-run (on its
first bump) with Python's bare "'module' object is not callable". The module is callable for
this release: the plugin works, and its author is told the new spelling at the plugin's own
line (a DeprecationWarning that the command shows: CHANGELOG, "Upgrading from 0.1.0")."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest
from runtime.installed import install_distribution, installed_registry
from waits import HANG_S  # tests/waits.py: a hang's bound

from roomba_bt.cli import main
from roomba_bt.oi import encode
from roomba_bt.oi.encode import ENCODE_MODULE_CALLED

#: the upgrader's plugin ``roomba-bt-mine``, as written for 0.1.0 (its own formatting)
PLUGIN = '''"""My behaviours: ``count_bumps`` (action, writes a key) and ``battery_ok`` (condition)."""

from __future__ import annotations

from py_trees.common import Status

from roomba_bt.behaviours import INT, PERCENT, STR, Action, Condition, Param, declare, read_key, write_key
from roomba_bt.oi import commands, encode
from roomba_bt.oi.opcodes import opcodes
from roomba_bt.oi.packets import packet_ids
from roomba_bt.robot.interface import Snapshot


@declare(
    "count_bumps",
    kind="action",
    params=(
        Param("key", STR, required=True, from_blackboard=False, doc="int key to add bumps to"),
        Param("beep", INT, default=0, minimum=0, maximum=1, doc="1: beep-free LED flash"),
    ),
    reads=packet_ids("bumps_wheel_drops"),
    sends=opcodes("leds"),
    writes_keys=("key",),
    reads_keys=("key",),
    primary="key",
)
class CountBumps(Action):
    """Add 1 to the key if a bumper is pressed now; always succeeds at once."""

    def update(self) -> Status:
        f = self.snapshot.frame
        key = str(self.value("key"))
        n = read_key(key)
        if f.bumps.bump_left or f.bumps.bump_right:
            n += 1
            if self.number("beep"):
                cmd = encode("leds", 8, 0, 128)   # check-robot LED on
                self.send(cmd)
                self.feedback_message = f"bump {n}: sent {cmd.data.hex()}"
            else:
                self.feedback_message = f"bump {n}"
        write_key(key, n, self.name)
        return Status.SUCCESS
'''  # noqa: E501  (as its author wrote it)
#: the upgrader's mission: the plugin's behaviour counts bumps while the robot drives into
#: the corridor's wall
BUMPIT = """mission: bumpit
blackboard:
  bumps: {type: int, initial: 0}
tree:
  sequence:
    - mode: safe
    - turn: 90deg
    - parallel:
        policy: one
        children:
          - drive: {velocity: 200 mm/s, duration: 10s}
          - repeat:
              do:
                sequence:
                  - wait: 1s
                  - count_bumps: {key: bumps, beep: 1}
    - stop
    - mode: passive
"""
RUN = ["run", "bumpit.yaml", "--fast", "--world", "corridor", "--display", "none"]


def test_the_module_called_as_0_1_0_s_function_encodes_and_warns() -> None:
    with pytest.warns(DeprecationWarning) as warned:
        command = encode("leds", 8, 0, 128)  # type: ignore[operator]  (0.1.0's spelling)
    assert command == encode.leds(8, 0, 128) and command.data.hex() == "8b080080"
    [warning] = warned
    assert str(warning.message) == ENCODE_MODULE_CALLED
    assert warning.filename == __file__  # the caller's line: the plugin's, for its author
    assert "roomba_bt.oi.encode.encode(...)" in ENCODE_MODULE_CALLED  # the new spelling
    assert "from roomba_bt.oi.encode import encode" in ENCODE_MODULE_CALLED


def test_a_0_1_0_plugin_s_run_succeeds_with_the_warning(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    import roomba_bt.behaviours.registry as registries

    registry = installed_registry(tmp_path, monkeypatch, ("roomba-bt-mine", "s33_mine", PLUGIN))
    monkeypatch.setattr(registries, "_DEFAULT", registry)
    monkeypatch.chdir(tmp_path)
    Path("bumpit.yaml").write_text(BUMPIT)
    with pytest.warns(DeprecationWarning, match="roomba_bt.oi.encode is the encoder's module"):
        assert main(RUN) == 0
    out = capsys.readouterr().out
    assert "outcome      SUCCESS" in out and "not callable" not in out


def test_the_command_shows_the_warning_at_the_plugin_s_line(tmp_path: Path) -> None:
    """Python hides a DeprecationWarning raised outside ``__main__``: ``roomba-bt`` shows
    this one, where the plugin's author reads it."""
    site = tmp_path / "site"
    site.mkdir()
    install_distribution(site, "roomba-bt-mine", "s33_mine", PLUGIN)
    (tmp_path / "bumpit.yaml").write_text(BUMPIT)
    root = Path(__file__).resolve().parents[2]
    env = {**os.environ, "PYTHONPATH": os.pathsep.join((str(root), str(site)))}
    env.pop("PYTHONWARNINGS", None)
    done = subprocess.run(
        [sys.executable, "-m", "roomba_bt", *RUN],
        cwd=tmp_path, env=env, capture_output=True, text=True, check=False, timeout=HANG_S,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert "outcome      SUCCESS" in done.stdout
    [said] = [line for line in done.stderr.splitlines() if "DeprecationWarning" in line]
    line = 1 + next(n for n, text in enumerate(PLUGIN.splitlines()) if "encode(" in text)
    assert said == f"{site / 's33_mine.py'}:{line}: DeprecationWarning: {ENCODE_MODULE_CALLED}"
