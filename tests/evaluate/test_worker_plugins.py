"""A worker that cannot compile a mission the evaluation compiled (a plugin installed on the
evaluating machine and not on the worker) is said once, naming the mission and its files as
given and what to install, and the evaluation exits 3, the run environment's failure. Each
episode raised it, and ``eval`` ended as an internal error (exit 70) naming the worker's copy
of the files under ``/tmp/roomba-bt-...`` (session 32)."""

from __future__ import annotations

import pickle
import socket
from pathlib import Path

import pytest
from quoted import assert_quoted  # tests/quoted.py: the docs' quotes

from roomba_bt.cli import main
from roomba_bt.evaluate import episode_specs, run_episode
from roomba_bt.evaluate.episode import MissionNotCompiled, self_contained
from roomba_bt.mission import Permissions

#: A plugin file that imports, in a child process only (a pool's or Dask's worker), a package
#: no machine has: as a worker without the lab's package installed would
_ON_THIS_MACHINE_ONLY = '''\
import multiprocessing

from py_trees.common import Status

from roomba_bt.behaviours import Action, declare

if multiprocessing.parent_process() is not None:
    import roomba_lab_sensors  # noqa: F401


@declare("lab_ready", kind="action")
class LabReady(Action):
    """Succeeds at once (its package's sensors, on the lab's machine only)."""

    def update(self):
        return Status.SUCCESS
'''

_MISSION = "plugins: [lab.py]\ntree:\n  sequence:\n    - lab_ready\n    - wait: 0.1 s\n"


def _mission(folder: Path, plugin: str = _ON_THIS_MACHINE_ONLY) -> Path:
    (folder / "lab.py").write_text(plugin, encoding="utf-8")
    mission = folder / "lab.yaml"
    mission.write_text(_MISSION, encoding="utf-8")
    return mission


def test_an_episode_that_cannot_compile_names_the_files_as_given(tmp_path: Path) -> None:
    """The worker's copy of the bundle is no file the user knows: the error names the
    mission and its plugin file by the paths the evaluation was given. It is pickled from
    the worker as it is."""
    everywhere = _ON_THIS_MACHINE_ONLY.replace("is not None", "is None or True")
    mission = _mission(tmp_path, everywhere)
    (spec,) = episode_specs(str(mission), runs=1, timeout_s=2.0,
                            permissions=Permissions(plugin_files=True))  # fmt: skip
    with pytest.raises(MissionNotCompiled) as refused:
        run_episode(self_contained(spec))
    said = str(refused.value)
    assert said.startswith(f"{mission} was compiled here, but not on the worker "), said
    assert (
        f"{mission}:1:11: plugin {tmp_path / 'lab.py'}: failed to import: ModuleNotFoundError: "
        f"No module named 'roomba_lab_sensors' (at {tmp_path / 'lab.py'}:8)"
    ) in said, said
    assert "roomba-bt-" not in said  # the copy's folder
    again = pickle.loads(pickle.dumps(refused.value))
    assert (str(again), again.mission) == (said, str(mission))


def test_eval_says_a_worker_without_the_plugin_once_and_exits_3(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """On a local Dask cluster, whose worker imports the plugin file again (a pool's forked
    worker has it already): three episodes, one message, exit 3."""
    pytest.importorskip("distributed")
    _mission(tmp_path)
    monkeypatch.chdir(tmp_path)
    code = main(["eval", "lab.yaml", "--runs", "3", "--engine", "dask", "--jobs", "1",
                 "--allow-plugin-files", "--no-progress"])  # fmt: skip
    err = capsys.readouterr().err
    assert code == 3, err
    assert err.count("was compiled here, but not on the worker") == 1, err
    assert (
        "roomba-bt eval: lab.yaml:1:11: plugin lab.py: failed to import: ModuleNotFoundError: "
        "No module named 'roomba_lab_sensors' (at lab.py:8) [plugins[0]]\n"
    ) in err
    assert (
        "roomba-bt eval: install on every worker what its plugin files import, and this "
        "roomba-bt release (exit 3: the run environment failed, not the mission)\n"
    ) in err
    assert "internal error" not in err
    # docs/evaluation.md's: its mission m4.yaml, its plugin lab4.py and node helped4, a
    # worker of another machine
    page = {"lab.yaml": "m4.yaml", "lab.py": "lab4.py", "lab_ready": "helped4",
            socket.gethostname(): "lab-7"}  # fmt: skip
    assert_quoted("docs/evaluation.md", "roomba-bt eval: m4.yaml", err, numbers=True, names=page)
    assert_quoted("docs/evaluation.md", "roomba-bt eval: install on every worker", err)


#: A plugin file that writes a key its mission does not declare (line 11)
_WRITES_UNDECLARED = '''\
from py_trees.common import Status

from roomba_bt.behaviours import Action, declare, write_key


@declare("lab_ready", kind="action")
class LabReady(Action):
    """Writes a key the mission does not declare."""

    def update(self):
        write_key("secret", 5, self.name)
        return Status.SUCCESS
'''


def test_an_undeclared_key_written_on_a_worker_names_the_plugin_file_as_given(
    tmp_path: Path,
) -> None:
    """The warning's ``at FILE:LINE`` named the worker's copy of the plugin file
    (``/tmp/roomba-bt-.../lab.py:11``), where the local engine names the file itself: now
    the path the evaluation was given, as a mission a worker cannot compile is said."""
    mission = _mission(tmp_path, _WRITES_UNDECLARED)
    (spec,) = episode_specs(str(mission), runs=1, timeout_s=2.0,
                            permissions=Permissions(plugin_files=True))  # fmt: skip
    result = run_episode(self_contained(spec))
    assert result.undeclared == (("secret", f" by 'lab_ready' at {tmp_path / 'lab.py'}:11"),)
