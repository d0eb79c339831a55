"""``import roomba_bt``: the names a Python program needs, each imported from its module when
first asked for (``roomba_bt/__init__.py``); ``import roomba_bt`` gave nothing but
``__version__``."""

from __future__ import annotations

import ast
import doctest
import importlib
import os
import re
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest
from waits import HANG_S  # tests/waits.py: a hang's bound

import roomba_bt

INIT = Path(roomba_bt.__file__)
EXPORTS = [name for name in roomba_bt.__all__ if name != "__version__"]


NEEDED = ("load_mission", "Connection", "RunStack", "TreeMission", "RunSummary", "Outcome",
          "RunFailed", "CREATE2", "PROFILES", "SimLink", "Simulator")  # fmt: skip


def test_the_names_a_program_needs_are_there() -> None:
    for name in NEEDED:
        assert name in roomba_bt.__all__ and name in dir(roomba_bt), name


def test_the_blackboard_s_names_a_program_meets_are_there() -> None:
    """A tree with py_trees client keys run beside another run ends with
    ``SharedBlackboard`` (its message says why and what to use instead), which a program
    catches; ``stack.runner.blackboard`` is a ``RunBoard``. Both from the package, as the
    other errors are, and from ``roomba_bt.behaviours``, where ``read_key`` is."""
    from roomba_bt.behaviours import blackboard

    for name in ("SharedBlackboard", "RunBoard"):
        assert name in roomba_bt.__all__ and name in roomba_bt.behaviours.__all__, name
        assert getattr(roomba_bt, name) is getattr(roomba_bt.behaviours, name)
        assert getattr(roomba_bt, name) is getattr(blackboard, name)
    assert issubclass(roomba_bt.SharedBlackboard, roomba_bt.RoombaBtError)


@pytest.mark.parametrize("name", EXPORTS)
def test_every_name_is_kept_once_asked_for(name: str) -> None:
    value = getattr(roomba_bt, name)
    assert vars(roomba_bt)[name] is value  # the module __getattr__ is not asked again


def test_type_checkers_see_the_same_names() -> None:
    """The ``if TYPE_CHECKING:`` imports name every export, from the module it is taken from
    when asked for (a name added to one and not the other fails here)."""
    tree = ast.parse(INIT.read_text())
    [checking] = [n for n in tree.body if isinstance(n, ast.If)]
    seen = {
        alias.name: node.module
        for node in checking.body
        if isinstance(node, ast.ImportFrom)
        for alias in node.names
    }
    assert sorted(seen) == sorted(EXPORTS)
    for name, module in seen.items():
        assert getattr(importlib.import_module(str(module)), name) is getattr(roomba_bt, name)


def test_the_packages_example_runs_as_help_shows_it() -> None:
    """``help(roomba_bt)`` showed no example: its docstring's example (a shipped mission
    on the simulator, its summary read) is run here as a doctest, output compared."""
    assert roomba_bt.__doc__ is not None
    example = doctest.DocTestParser().get_doctest(roomba_bt.__doc__, {}, "roomba_bt", str(INIT), 0)
    assert any("RunStack" in step.source for step in example.examples)
    runner = doctest.DocTestRunner(optionflags=doctest.REPORT_NDIFF)
    runner.run(example)
    assert runner.summarize(verbose=False) == (0, len(example.examples))
    session = roomba_bt.__doc__.split("::\n\n", 1)[1].split("\n\n", 1)[0]
    docs = (INIT.parents[1] / "docs" / "runtime.md").read_text(encoding="utf-8")
    assert f"```pycon\n{textwrap.dedent(session)}\n```" in docs  # the docs show the same


#: An embedder's program, as mypy --strict found it: ``interrupt.summary`` is a RunSummary (a
#: bare KeyboardInterrupt has none), a name the package does not have is an error, not Any (the
#: package's ``__getattr__`` made every name Any to a type checker), ``stack.ticks()`` is a
#: generator a program may close, ``RobotHandle`` and ``NoAnswer`` are the package's. Two
#: mistakes planted (in tests/runtime/test_library_api.py until session 42).
TYPED = """\
import roomba_bt

def run(stack: roomba_bt.RunStack) -> roomba_bt.RunSummary:
    try:
        return stack.run()
    except roomba_bt.Interrupted as interrupt:
        print(interrupt.summary.outcome)
        planted: int = interrupt.summary
        raise

def step(stack: roomba_bt.RunStack, robot: roomba_bt.RobotHandle) -> float:
    steps = stack.ticks()
    time = next(steps).time + robot.snapshot.time
    steps.close()  # a generator to mypy (typed Iterator, it had no close())
    return time

try:
    roomba_bt.Connection.open("/dev/ttyUSB0").start()
except roomba_bt.NoAnswer as silent:
    print(silent.likely_causes)

roomba_bt.RunStak
"""


@pytest.fixture(scope="module")
def strict_mypy(tmp_path_factory: pytest.TempPathFactory) -> dict[str, str]:
    """``mypy --strict`` over the programs of this module's tests, in one process: what it
    said of each (its lines naming that file), and its last line. Each run checks roomba_bt
    itself first, about 11 s of CPU where the suite runs without PYTHONPATH (as ``make test``
    does): two runs in two test files (two workers, two caches) cost it twice. Its cache
    starts as a copy of the checkout's (``make test`` runs ``make typecheck`` first): mypy
    takes from it only what it finds up to date for these options and checks the rest, so
    what it says is a fresh run's, in about 1 s of CPU where roomba_bt has not changed."""
    pytest.importorskip("mypy", reason="the test extra: pip install 'roomba-bt[test]'")
    assert roomba_bt.__doc__ is not None
    example = doctest.DocTestParser().get_doctest(roomba_bt.__doc__, {}, "roomba_bt", str(INIT), 0)
    folder = tmp_path_factory.mktemp("typed")
    programs = {
        "user.py": "".join(step.source for step in example.examples),
        "typed.py": TYPED,
        "by_hand.py": _by_hand_example(),
    }
    for name, text in programs.items():
        (folder / name).write_text(text)
    checkout = INIT.parents[1]  # this roomba_bt, not another one installed in the venv
    env = {"MYPYPATH": str(checkout)} if (checkout / "pyproject.toml").is_file() else {}
    if (checkout / ".mypy_cache").is_dir():
        shutil.copytree(checkout / ".mypy_cache", folder / "cache", symlinks=True)
    done = subprocess.run(
        [sys.executable, "-m", "mypy", "--strict", "--cache-dir", str(folder / "cache"), *programs],
        capture_output=True, text=True, timeout=300, cwd=folder, env={**os.environ, **env},
    )  # fmt: skip
    lines = done.stdout.splitlines()
    said = {name: "\n".join(x for x in lines if x.startswith(f"{name}:")) for name in programs}
    return {**said, "end": (lines or [""])[-1], "all": done.stdout + done.stderr}


def _by_hand_example() -> str:
    """docs/runtime.md's program that drives the robot by hand, then hands its connection to
    a mission (the pycreate2 user's first program)."""
    page = (INIT.parents[1] / "docs" / "runtime.md").read_text(encoding="utf-8")
    section = page.split("## From Python: a connection driven by hand, then a mission", 1)[1]
    [block] = re.findall(r"```python\n(.*?)```", section.split("\n## ", 1)[0], flags=re.DOTALL)
    return str(block)


def test_the_by_hand_example_type_checks_as_a_user_copies_it(strict_mypy: dict[str, str]) -> None:
    """It read ``robot.latest.frame``: ``latest`` is None until a frame has come, and a
    pycreate2 user who copied the page into a typed program got ``mypy --strict``'s
    union-attr error (the package ships ``py.typed``)."""
    assert strict_mypy["by_hand.py"] == "", strict_mypy["all"]
    assert strict_mypy["end"].endswith("(checked 3 source files)"), strict_mypy["all"]


def test_the_packages_example_type_checks_as_a_user_copies_it(strict_mypy: dict[str, str]) -> None:
    """The example called ``.label`` on ``summary.final_mode``, which is None when no robot
    answered: a user who copied it into a program got ``mypy --strict``'s union-attr error
    (the package ships ``py.typed``). Its lines, as a file, pass ``mypy --strict``: nothing
    said of it, in a run that checked it (three files: :data:`TYPED` and the page's program
    driven by hand beside it)."""
    assert strict_mypy["user.py"] == "", strict_mypy["all"]
    assert strict_mypy["end"].endswith("(checked 3 source files)"), strict_mypy["all"]


def test_the_typed_interrupt_pattern_passes_mypy_strict(strict_mypy: dict[str, str]) -> None:
    """:data:`TYPED`: the two planted mistakes are mypy's only findings (an embedder's mypy
    --strict findings, each mended, would be a third). roomba_bt's own modules are checked by
    ``make typecheck`` with every extra installed (from an sdist without them, mypy finds no
    matplotlib for the modules that import it, and says so there)."""
    said = strict_mypy["typed.py"].splitlines()
    errors = [line.split(": error: ", 1)[1] for line in said if ": error: " in line]
    assert errors == [  # the two planted mistakes, and nothing else
        'Incompatible types in assignment (expression has type "RunSummary", variable has type '
        '"int")  [assignment]',
        'Module has no attribute "RunStak"; maybe "RunStack"?  [attr-defined]',
    ], strict_mypy["all"]


def test_an_unknown_name_is_an_attribute_error() -> None:
    with pytest.raises(AttributeError) as raised:
        roomba_bt.nope  # noqa: B018
    assert str(raised.value) == "module 'roomba_bt' has no attribute 'nope'"


def test_import_roomba_bt_loads_no_layer() -> None:
    """Every ``roomba-bt`` command imports the package first: it loads none of the exports'
    modules (nor py_trees, transitions, pyserial, YAML) until a name is asked for."""
    script = (
        "import sys\n"
        "import roomba_bt\n"
        "print(sorted(m for m in sys.modules if m.startswith(('roomba_bt', 'py_trees', "
        "'transitions', 'serial', 'yaml'))))\n"
        "from roomba_bt import RunFailed\n"
        "print(RunFailed.__module__, 'roomba_bt.runtime.stack' in sys.modules)\n"
    )
    output = subprocess.check_output([sys.executable, "-c", script], text=True, timeout=HANG_S)
    loaded, taken = output.splitlines()
    # the lazy names' module too, since session 36, at the first name asked for
    assert loaded == "['roomba_bt', 'roomba_bt._safe_path']"
    assert taken == "roomba_bt.runtime.summary False"


def test_the_version_is_written_once_and_is_past_the_previous_release_s() -> None:
    """Both builds said 0.1.0 (``--version``, eval's ``roomba_bt_version``, the wheel's name)
    after a release of breaking changes (the previous, e80f20a, and this one): nobody could
    tell which build made a result file. The version is written in ``__version__`` alone
    (``pyproject.toml`` reads it from there), as MAJOR.MINOR.PATCH, past 0.1.0."""
    import tomllib

    pyproject = tomllib.loads((INIT.parents[1] / "pyproject.toml").read_text(encoding="utf-8"))
    assert "version" not in pyproject["project"] and "version" in pyproject["project"]["dynamic"]
    assert pyproject["tool"]["setuptools"]["dynamic"]["version"] == {
        "attr": "roomba_bt.__version__"
    }
    release = tuple(int(part) for part in roomba_bt.__version__.split("."))
    assert len(release) == 3 and release > (0, 1, 0)


def test_the_readme_says_how_to_use_it_from_python_and_its_pages_hold_that() -> None:
    """A pycreate2 user reads the README first, which spoke of the command line and YAML
    alone: its From Python section names the calls and the pages, and each holds what it
    says there."""
    root = Path(__file__).resolve().parents[1]
    readme = root.joinpath("README.md").read_text(encoding="utf-8")
    section = readme.split("\n## From Python\n", 1)[1].split("\n## ", 1)[0]
    for said in ("Connection.open(port)", "commands.drive_direct(200, 200)", "help(roomba_bt)"):
        assert said in section, said
    assert (Path(roomba_bt.__file__).parent / "py.typed").is_file()
    assert ">>> " in (roomba_bt.__doc__ or "")  # help(roomba_bt): a whole run
    pages = {page: root.joinpath("docs", f"{page}.md").read_text(encoding="utf-8")
             for page in ("robot", "runtime", "plugins")}  # fmt: skip
    assert "### Odometry in a program's own loop" in pages["robot"]
    assert "Connection.open(" in pages["robot"]
    assert "## From Python: a run tick by tick" in pages["runtime"]
    assert "### A behaviour in your own program" in pages["plugins"]
