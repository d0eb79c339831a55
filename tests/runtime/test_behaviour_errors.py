"""A behaviour's exception says where: the behaviour's path in the tree and the file:line in
its module (a plugin file), the traceback under ``-v``, and exit code 4 (not 1, a mission
that failed), after the safe stop."""

from __future__ import annotations

from pathlib import Path

import pytest

from roomba_bt.cli import main
from roomba_bt.runtime.summary import ExitCode

PLUGIN = '''
from roomba_bt.behaviours import Condition, declare


@declare("fragile", kind="condition", reads=(27,))
class Fragile(Condition):
    """Divides by the wall signal: a bug on a quiet frame."""

    def check(self, snapshot):
        return 1000 // snapshot.frame[27] > 3
'''

MISSION = """\
plugins: [./fragile.py]
tree:
  sequence:
    name: outer
    children:
      - mode: safe
      - wait: 1s
      - fragile
"""


@pytest.fixture
def mission(tmp_path: Path) -> Path:
    (tmp_path / "fragile.py").write_text(PLUGIN)
    path = tmp_path / "m.yaml"
    path.write_text(MISSION)
    return path


def _run(mission: Path, *extra: str) -> list[str]:
    return [*extra, "run", str(mission), "--fast", "--display", "none", "--timeout", "10s",
            "--allow-plugin-files"]  # fmt: skip


def test_names_the_behaviour_and_the_plugin_line(
    mission: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(_run(mission)) == ExitCode.BEHAVIOUR_ERROR == 4
    out, err = capsys.readouterr()
    assert "behaviour outer / fragile raised ZeroDivisionError" in err
    assert f"(at {mission.parent / 'fragile.py'}:10)" in err
    assert "Traceback" not in out + err
    assert "run with -v for the traceback" in err
    assert "safe stop    sent" in out


def test_the_traceback_under_verbose(mission: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(_run(mission, "-v")) == 4
    _, err = capsys.readouterr()
    assert "Traceback (most recent call last)" in err
    assert "return 1000 // snapshot.frame[27] > 3" in err
