"""The docs run as written: every shell command and every mission in README.md and docs/.

Fenced blocks are read from the Markdown. A *command* is a line of a ``sh``/``console``/plain
block that starts with one of :data:`PROGRAMS` (a leading ``$ ``, a leading ``nice `` (a
priority, docs/routines.md's long evaluations) and a trailing ``# comment`` are dropped,
``\\`` continues a line, ``&&`` chains; a line ``cd DIR && roomba-bt ...`` is one too, and
must be in :data:`NOT_RUN`: this test runs none from another folder); other lines of plain
blocks are output, diagrams or byte layouts. A *mission* is a ``yaml`` block with a
``tree:`` or ``subtrees:`` key; it is written to ``<its mission name>.yaml`` (``mission:``,
else ``doc-N``) in the directory the commands run in, so ``roomba-bt run square.yaml``
runs the block above it; a *world* is a ``yaml`` block with a ``rooms:`` key, written to
``<its name>.yaml``. A *file* is a ``python`` block whose first line is a comment naming a
relative path (``# plugins/near_wall.py``), written to that path: docs/plugins.md's reader
makes the plugin file its mission's ``plugins:`` names, and its commands use those two, as
a wheel's user has no ``missions/examples`` (session 39's stranger: the page ran the
repository's copies).
A mission that names ``plugins:`` is validated with ``--allow-plugin-files``, as the docs
show it.

Every command is run as a wheel's user runs it: in a scratch directory holding only the
missions, worlds and files its own page has the reader write (no ``missions/``, ``worlds/`` or
``plugins/roomba-bt-dirt`` of the repository's, which a wheel does not hold: session 39's
stranger met ``missions/dock.yaml``, exit 2, on five pages this test had run in a folder
holding a copy of them). A command its page frames as a checkout's (:data:`CHECKOUT`, each
with its reason) runs in a checkout's directory instead: the docs' files, a copy of
``missions/``, a link to ``worlds/`` and, in its ``plugins/``, a link to each package of the
repository's. Exit code 0 is expected, after the rewrites of :func:`fast_variant`:

* no robot: ``--port URL`` becomes the built-in simulator on the virtual clock (``--fast``);
  ``sensors`` stops after one refresh (``--count 1``);
* no real time: ``run`` gets ``--fast`` (the same tree, the virtual clock);
* short: ``eval`` runs 2 episodes (``--runs N`` -> 2), one job (``--jobs N`` dropped: 1 is
  the default); an ``eval`` given a ``--timeout`` (the docs give one to clean.yaml's long
  episodes, about 15 minutes of mission time, seconds of CPU each) runs 1 episode a variant
  (:data:`LONG_EPISODE_RUNS`), clean.yaml's cleaning 2 minutes of its 20
  (:data:`SHORT_CLEAN`): what this test checks is that the command as written runs,
  and the statistics over many episodes are tests/evaluate's; ``sim`` serves for 0.1 s
  (``--duration 0.1``, :data:`SIM_SERVES_S`) on a free TCP port (``--tcp HOST:0``,
  ``--rfc2217 HOST:0``);
* ``doctor --port URL`` runs against a simulator this test serves: ``roomba-bt sim --rfc2217``,
  asleep, at 19200, so every step up to the BRC wake is taken;
* placeholders get a value: ``[NAME...]`` -> ``drive``, ``A.yaml``/``B.yaml`` (two missions
  of the reader's) -> the shipped ``dock``/``dock-builtin``;
* ``make run`` runs the command its Makefile recipe runs.

The docs give some commands more than once (the same ``eval`` in three tables of
docs/routines.md, ``doctor --port /dev/ttyUSB0`` in README.md and docs/doctor.md): a command
line whose rewritten argv was already run in this session, in the same kind of directory
(and, where it names a file of its page's, with the same files), is not run again: its exit
code, output and errors are the first run's (:data:`RAN`), and its own case checks them. An
``eval`` episode the session already ran (the same spec: mission and world texts, seed,
options, wall-clock limit) is not simulated again either: the command line runs as written
and gets that episode's result as its pool would (:data:`EPISODES`).

docs/doctor.md's transcripts (a ``text`` block that starts ``$ roomba-bt doctor``) are run
against the simulator their paragraph names and compared with what doctor prints, line for
line (:func:`transcripts`).

A command that cannot run here is listed in :data:`NOT_RUN` with the reason; a listed
command the docs no longer hold fails the test too (the list cannot go stale), and so does a
command that is neither run nor listed.
"""

from __future__ import annotations

import glob
import importlib.util
import re
import shlex
import shutil
import sys
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import docs_inputs  # tests/docs_inputs.py: the files that make the docs' diagnostics
import pytest
import yaml
from quoted import assert_quoted, begins, kind_of, quotes  # tests/quoted.py: the docs' quotes
from waits import finished  # tests/waits.py: a child run to its end, no fixed wait

from roomba_bt.cli import main

ROOT = Path(__file__).resolve().parents[1]
DOCS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
PROGRAMS = ("roomba-bt", "make", "pip", "pytest", "dask", ". .venv")
SHELL_LANGS = ("", "sh", "console", "shell", "bash")

#: Commands the test does not run, and why (exact text as in the docs, comment dropped).
NOT_RUN: dict[str, str] = {
    "make test": "this test suite is what it runs",
    "pip install 'roomba-bt[cluster]'": "an install from the package index; `make test` "
    "installs the cluster extra into the venv these tests run in",
    "dask scheduler": "a server that runs until stopped (a Dask cluster's scheduler)",
    "dask worker tcp://HOST:8786 --nthreads 1": "a server that runs until stopped, and "
    "HOST is the user's machine",
    "roomba-bt eval dock --world apartment --runs 2000 "
    "--scheduler tcp://HOST:8786 --out apartment.jsonl": "needs the Dask cluster the two "
    "commands above start (HOST is the user's); the Dask engine itself is tested in "
    "tests/evaluate",
    "roomba-bt eval MISSION [MISSION_B ...] [--world W] [--runs N] [--seed S] [--jobs J]": (
        "a synopsis (every word a placeholder), not a command; the eval commands above it are run"
    ),
    "roomba-bt eval --from ab.jsonl other-machine.jsonl --json": "other-machine.jsonl is "
    "another machine's results; tests/evaluate/test_seeds_and_from.py merges two files",
    "pip install roomba-bt": "an install from the package index (network, and a new venv); "
    "the two roomba-bt commands after it are run",
    "pip install -e plugins/roomba-bt-dirt": "`make venv` / `make test` installed it into "
    "the venv these tests run in; the plugin's entry point is tested in "
    "plugins/roomba-bt-dirt/tests",
    "pytest plugins/roomba-bt-dirt": "the suite collects plugins/ itself (testpaths), "
    "so those tests run beside this one",
    "pip install ./roomba-bt-near-wall": "docs/plugins.md §5: an install into the reader's "
    "venv, never this one; tests/behaviours/test_docs_plugins.py reads the page's toml with "
    "setuptools and serves its entry point to the two commands after it",
    "roomba-bt behaviours near_wall": "docs/plugins.md §5, with its package installed: "
    "tests/behaviours/test_docs_plugins.py runs it and compares the page's output",
    "roomba-bt run custom_condition.yaml --world corridor --fast": "docs/plugins.md §5, the "
    "mission without its plugins: line, its package installed: tests/behaviours/"
    "test_docs_plugins.py runs it",
    "pip install 'roomba-bt[monitor]'": "an install from the package index; `make test` "
    "installs the monitor extra into the venv these tests run in",
    "roomba-bt run dock --world apartment --monitor": "serves the page until "
    "the run ends in real time; tests/monitor runs the monitor in a real browser",
    "roomba-bt run dock --port /dev/ttyUSB0 --monitor 9000": "needs a robot",
    "roomba-bt run dock --monitor 0.0.0.0:8765": "serves on every address "
    "until stopped; the token rule is tested in tests/monitor",
    "roomba-bt run mymission.yaml --monitor --watch": "watches a file until stopped; "
    "tests/monitor changes a mission under --watch",
    "roomba-bt monitor dock.jsonl": "serves the page until stopped; tests/monitor opens "
    "a recorded run in a browser",
    "cd records && roomba-bt run ../missions/off-the-dock.yaml --fast --world "
    "../worlds/lab.yaml --seed 0 --timeout 10min --include-dir ../missions/common --record "
    "off-the-dock.jsonl": "docs/runtime.md: the reader's repository of the record header "
    "above (missions/off-the-dock.yaml, its library folder missions/common, the world "
    "worlds/lab.yaml, records/), which no page has the reader write; "
    "tests/runtime/test_record_checkouts.py builds such a repository and makes a record "
    "again from its header, in the record's folder, byte for byte",
    "roomba-bt run missions/dock.yaml --fast --world worlds/lab.yaml --reproducible --record "
    "records/dock.jsonl > records/dock.summary.txt": "docs/runtime.md's CI job, at the top of "
    "the reader's repository (its missions/, its world worlds/lab.yaml, the records/ it "
    "commits), which no page has the reader write; tests/runtime/test_record_checkouts.py "
    "runs --reproducible there twice and compares the record and the summary",
    "roomba-bt validate --format json --include-dir missions/common missions "
    "| jq -r --arg lib missions/common/lib/escapes.yaml '.files[] | "
    "select(.includes | any(. == $lib)) | .file'": "a team's repository (missions/common "
    "and its library); tests/mission/test_ci_docs.py builds one and runs this line in it",
}


@dataclass(frozen=True)
class Block:
    doc: str
    line: int
    lang: str
    text: str


def blocks() -> list[Block]:
    found = []
    for path in DOCS:
        text = path.read_text(encoding="utf-8")
        for match in re.finditer(r"^```(\w*)\n(.*?)^```", text, re.M | re.S):
            line = text.count("\n", 0, match.start()) + 1
            found.append(Block(path.relative_to(ROOT).as_posix(), line, match[1], match[2]))
    return found


def commands() -> list[tuple[str, str]]:
    """(where, command) for every command line of every shell block."""
    found = []
    for block in blocks():
        if block.lang not in SHELL_LANGS:
            continue
        text = re.sub(r"\\\n\s*", " ", block.text)  # continued lines
        for offset, raw in enumerate(text.splitlines()):
            line = raw.strip().removeprefix("$ ").removeprefix("nice ")
            elsewhere = re.match(r"cd \S+ && ", line)  # run from another folder
            if not line.removeprefix(elsewhere[0] if elsewhere else "").startswith(PROGRAMS):
                continue
            line = re.sub(r"\s+#.*$", "", line)
            line = re.sub(r"\s+", " ", line).strip()
            found.append((f"{block.doc}:{block.line + 1 + offset}", line))
    return found


def missions() -> list[tuple[str, str, str]]:
    """(where, file name, text) of every mission block."""
    found = []
    for i, block in enumerate(blocks()):
        if block.lang != "yaml" or not re.search(r"^(tree|subtrees):", block.text, re.M):
            continue
        name = yaml.safe_load(block.text).get("mission") or f"doc-{i}"
        found.append((f"{block.doc}:{block.line}", f"{name}.yaml", block.text))
    return found


def files() -> list[tuple[str, str, str]]:
    """(where, path, text) of every file block: a ``python`` block whose first line is
    ``# PATH.py``, a path relative to the folder the commands run in."""
    found = []
    for block in blocks():
        named = re.match(r"# ([\w-]+(?:/[\w-]+)*\.py)\n", block.text)
        if block.lang == "python" and named:
            found.append((f"{block.doc}:{block.line}", named[1], block.text))
    return found


def worlds() -> list[tuple[str, str, str]]:
    """(where, file name, text) of every world block: a ``yaml`` block with a ``rooms:``
    key, written to ``<its name>.yaml`` (``docs/simulator.md``: a world of your own)."""
    found = []
    for block in blocks():
        if block.lang != "yaml" or not re.search(r"^rooms:", block.text, re.M):
            continue
        name = yaml.safe_load(block.text).get("name")
        assert name, f"{block.doc}:{block.line}: a world block needs a name: to be written"
        found.append((f"{block.doc}:{block.line}", f"{name}.yaml", block.text))
    return found


def make_run_command() -> str:
    """What ``make run`` runs: the recipe's command with its RUN_ARGS."""
    makefile = (ROOT / "Makefile").read_text()
    args = re.search(r"^RUN_ARGS \?= (.*)$", makefile, re.M)
    recipe = re.search(r"^run: .*\n\t\$\(BIN\)/(.*)$", makefile, re.M)
    assert args is not None and recipe is not None
    return recipe[1].replace("$(RUN_ARGS)", args[1])


PLACEHOLDERS = {"[NAME...]": "drive", "A.yaml": "dock", "B.yaml": "dock-builtin"}

#: Commands run in a checkout's directory (a copy of ``missions/``, the repository's worlds and
#: plugin packages), not a wheel's user's, and why: each is framed by its page as a
#: checkout's (exact text as in the docs, comment dropped).
CHECKOUT: dict[str, str] = {
    "make run": "README's quick start, in a checkout: the Makefile is the repository's",
    "roomba-bt validate --strict missions/*.yaml missions/lib/*.yaml": "docs/ci.md runs "
    "them from a checkout's root (roomba-bt's own missions and their library, as a team's "
    "CI runs them on its repository), and says so",
    "roomba-bt -q validate --strict --format github missions/*.yaml missions/lib/*.yaml": (
        "docs/ci.md, the same: from a checkout's root"
    ),
    "roomba-bt validate --format json missions/*.yaml > validate.json": "docs/ci.md, the "
    "same: from a checkout's root",
    "roomba-bt run plugins/roomba-bt-dirt/examples/dirt.yaml --world "
    "plugins/roomba-bt-dirt/examples/dirty-room.yaml --fast": "docs/plugins.md §5: the "
    "example package is in roomba-bt's source (a checkout or the sdist), as the page says",
}


#: Episodes a docs ``eval`` runs: two, so its summary is over more than one episode ...
EVAL_RUNS = "2"
#: ... but one where the command gives a ``--timeout``: clean.yaml's episodes (about 15
#: minutes of mission time) cost seconds of CPU each, the docs give nine such commands, and
#: a second seed proves no more that the command runs.
LONG_EPISODE_RUNS = "1"
#: ... and that one, of the shipped clean.yaml, cleans for 2 minutes of its 20 (its way home
#: after it as written): a 20-minute clean cost about 9 s of CPU an episode (the docs run
#: eleven such episodes), 2 minutes about 2 s, and what this test checks (that the command
#: as written runs, its options, sweep and ``--out``) is the same; clean.yaml's whole
#: episodes are tests/missions/test_clean.py's. Not where :data:`NOT_SAID` watches what
#: the command says of a run (the reader's own world: all of its time is looked at).
SHORT_CLEAN = ["-p", "duration=2min"]


#: How long a docs ``sim`` serves: nobody connects to it, so what its case checks is that it
#: starts, serves and ends with exit 0; the 0.5 s it served before waited for nothing.
SIM_SERVES_S = "0.1"


def fast_variant(command: str) -> list[str]:
    """The command as run here (see the module's docstring), as argv."""
    if command == "make run":
        command = make_run_command()
    argv = shlex.split(command)
    argv = [PLACEHOLDERS.get(word, word) for word in argv]
    sub = argv[1] if len(argv) > 1 else ""
    if "--port" in argv:
        i = argv.index("--port")
        del argv[i : i + 2]
        if sub == "run":
            argv.append("--fast")
        if sub == "sensors":
            argv += ["--count", "1"]
    if sub == "run" and "--fast" not in argv:
        argv.append("--fast")
    if sub == "eval" and "--seeds" in argv:  # a list of seeds: its first two, no --runs
        i = argv.index("--seeds")
        argv[i + 1] = ",".join(str(seed) for seed in range(1, int(EVAL_RUNS) + 1))
    elif sub == "eval":
        runs = LONG_EPISODE_RUNS if "--timeout" in argv else EVAL_RUNS
        if "--runs" in argv:
            argv[argv.index("--runs") + 1] = runs
        else:
            argv += ["--runs", runs]
        if "--jobs" in argv:
            i = argv.index("--jobs")
            del argv[i : i + 2]
        if (
            runs == LONG_EPISODE_RUNS
            and argv[2] == "clean"
            and not any(word.startswith("duration=") for word in argv)
            and not any(word in command for word in NOT_SAID)
        ):
            argv += SHORT_CLEAN
    if sub == "sim":
        for option in ("--tcp", "--rfc2217"):
            if option in argv:
                i = argv.index(option)
                argv[i + 1] = argv[i + 1].rsplit(":", 1)[0] + ":0"
        argv += ["--duration", SIM_SERVES_S]
    return argv


COMMANDS = commands()
MISSIONS = missions()
WORLDS = worlds()
FILES = files()


def page_files(doc: str) -> list[tuple[str, str]]:
    """(path, text) of each mission, world and file that page ``doc`` has its reader write."""
    return [(f, t) for where, f, t in (*MISSIONS, *WORLDS, *FILES) if where.startswith(f"{doc}:")]


def doc_of(where: str) -> str:
    """The page of a ``doc:line`` place."""
    return where.rsplit(":", 1)[0]


@pytest.fixture
def scratch(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Callable[..., Path]:
    """The directory a page's commands run in, made the current one: what the page ``doc``
    has the reader write and nothing else (a wheel's user's), or with ``checkout=True`` also
    a copy of ``missions/``, the worlds and, in ``plugins/``, each package of the
    repository's (:data:`CHECKOUT`)."""

    def made(doc: str, checkout: bool = False) -> Path:
        if checkout:
            shutil.copytree(ROOT / "missions", tmp_path / "missions")
            (tmp_path / "worlds").symlink_to(ROOT / "worlds")
            (tmp_path / "plugins").mkdir()  # the docs' plugin files beside the packages
            for package in (ROOT / "plugins").iterdir():
                (tmp_path / "plugins" / package.name).symlink_to(package)
        for file, text in page_files(doc):
            (tmp_path / file).parent.mkdir(parents=True, exist_ok=True)
            (tmp_path / file).write_text(text)
        monkeypatch.chdir(tmp_path)
        return tmp_path

    return made


def test_the_docs_hold_commands_and_missions() -> None:
    assert len(COMMANDS) > 30 and len(MISSIONS) >= 4
    assert "plugins/near_wall.py" in {path for _, path, _ in FILES}  # docs/plugins.md, §2
    assert ("docs/missions.md:31", "roomba-bt validate square.yaml") in COMMANDS


def test_every_listed_command_is_still_in_the_docs() -> None:
    documented = {command for _, command in COMMANDS}
    stale = [command for command in (*NOT_RUN, *CHECKOUT) if command not in documented]
    assert not stale, f"NOT_RUN or CHECKOUT lists commands the docs no longer hold: {stale}"
    assert not set(NOT_RUN) & set(CHECKOUT), "a command is either run or not"


def test_every_command_is_run_or_listed_with_a_reason() -> None:
    for where, command in COMMANDS:
        for part in command.split(" && "):
            program = part.split()[0]
            listed = part in NOT_RUN or command in NOT_RUN  # a `cd DIR && ...` whole
            assert program == "roomba-bt" or listed or part == "make run", (
                f"{where}: {part!r} is neither run by this test nor listed in NOT_RUN"
            )


@pytest.mark.parametrize(("where", "file", "text"), MISSIONS, ids=[m[0] for m in MISSIONS])
def test_every_mission_in_the_docs_validates(
    where: str,
    file: str,
    text: str,
    scratch: Callable[..., Path],
    capsys: pytest.CaptureFixture[str],
) -> None:
    scratch(doc_of(where))  # beside what its page has the reader write, no more
    # A mission that names plugin files is validated as the docs show it: with the permission.
    allow = ["--allow-plugin-files"] if (yaml.safe_load(text) or {}).get("plugins") else []
    assert main(["validate", file, *allow]) == 0, f"{where}: {capsys.readouterr()}"


#: Python blocks run as written, in the scratch directory of the docs' missions (the page, the
#: heading of the section that holds one block, and the name it makes): each makes what it
#: uses (session 37's stranger met a NameError in missions.md's, which never made its
#: ``robot``; session 39's one in simulator.md's coverage, which made no ``world``). The
#: blocks of docs/runtime.md are tests/runtime/test_docs_python.py's; the rest are fragments
#: of a program (an ``except`` clause, a test) or need a robot.
PYTHON_RUN = [
    ("docs/missions.md", "## From Python", "mission"),
    ("docs/plugins.md", "### A behaviour in your own program", "mission"),
    ("docs/simulator.md", "## Running it", "link"),
    ("docs/simulator.md", "## Swept area and coverage", "sim"),
]


def python_block(doc: str, heading: str) -> str:
    """The first ``python`` block of the section ``heading`` of ``doc``."""
    text = (ROOT / doc).read_text(encoding="utf-8")
    assert f"\n{heading}\n" in text, f"{doc} lost its section {heading!r}"
    block = re.search(r"^```python\n(.*?)^```", text.split(f"\n{heading}\n", 1)[1], re.M | re.S)
    assert block is not None, f"{doc}: {heading!r} holds no python block"
    return block[1]


@pytest.mark.parametrize(
    ("doc", "heading", "made"), PYTHON_RUN, ids=[f"{d}:{h}" for d, h, _ in PYTHON_RUN]
)
def test_the_python_examples_run(
    doc: str, heading: str, made: str, scratch: Callable[..., Path]
) -> None:
    scratch(doc)
    namespace: dict[str, object] = {"__name__": "docs_example"}
    exec(compile(python_block(doc, heading), f"{doc}:{heading}", "exec"), namespace)
    assert namespace.get(made) is not None  # each made what it is about


def test_the_simulator_s_signature_on_its_page_is_the_code_s() -> None:
    """docs/simulator.md's ``Simulator(world, ...)`` names every parameter, in order: it
    left out ``coverage``, ``trace`` and ``cycle_commands_pause``, which its own examples
    pass (session 39's stranger)."""
    import inspect

    from roomba_bt.sim import Simulator

    text = (ROOT / "docs" / "simulator.md").read_text(encoding="utf-8")
    shown = re.search(r"`Simulator\((world, [^`]*)\)`", text)
    assert shown is not None, "docs/simulator.md lost its Simulator(world, ...) signature"
    names = [part.split("=")[0].strip() for part in " ".join(shown[1].split()).split(", ")]
    assert [n for n in names if n != "*"] == list(inspect.signature(Simulator).parameters)


#: Commands a page gives in its prose, not in a block, that a wheel's user runs as written:
#: (the page, the command). Each runs in that page's scratch folder and exits 0: the page
#: said ``roomba-bt validate missions/*.yaml worlds/*.yaml``, exit 2 in a wheel's user's
#: folder (session 39's stranger).
PROSE_RUN = [("docs/simulator.md", "roomba-bt validate dock my-flat.yaml")]


@pytest.mark.parametrize(("doc", "command"), PROSE_RUN, ids=[c for _, c in PROSE_RUN])
def test_the_prose_commands_run_as_a_wheel_s_user_runs_them(
    doc: str, command: str, scratch: Callable[..., Path], capsys: pytest.CaptureFixture[str]
) -> None:
    scratch(doc)
    page = " ".join((ROOT / doc).read_text(encoding="utf-8").split())
    assert f"`{command}`" in page, f"{doc} no longer gives `{command}`"
    assert main(shlex.split(command)[1:]) == 0, capsys.readouterr()


#: A mission that ends at once (a quote's command needs a file, not a run)
TINY = "mission: m\ntree:\n  sequence:\n    - mode: safe\n    - stop\n"
#: a mission whose one warning (a YAML 1.1 number) fails it under --strict
W1 = (
    (
        "w1.yaml",
        "mission: w1\nblackboard:\n  k: {type: int, initial: 1_0}\ntree: {sequence: [stop]}\n",
    ),
)


@dataclass(frozen=True)
class Quoted:
    """A line a page quotes as a command prints it (tests/quoted.py): the page, how the quote
    begins, the command that prints it, its exit code, and what the command needs: the
    environment, files beside the page's (None: one of the page's taken away), commands
    run first, a file a child holds as a run holds its ``--record``."""

    doc: str
    start: str
    command: str
    code: int
    env: tuple[tuple[str, str], ...] = ()
    files: tuple[tuple[str, str | None], ...] = ()
    first: tuple[str, ...] = ()
    held: str | None = None
    #: where the command prints the line: stderr (a command's message), or stdout
    #: (``validate``'s diagnostics)
    stream: str = "err"
    #: the page's name of the folder the command ran in (``/home/me/lab``), where the line
    #: names it
    workdir_as: str | None = None


#: Every quote of a ``roomba-bt CMD: ...`` line whose command is cheap to run: each is run
#: in its page's scratch folder and must print the line (docs/robot.md quoted the
#: ROOMBA_BT_PROFILE error without its ``(roomba-bt run --help, --profile)`` end: session
#: 39's stranger; session 40 held every other quote, :data:`QUOTED_ELSEWHERE` the rest).
QUOTED = [
    Quoted("docs/robot.md", "roomba-bt run: ROOMBA_BT_PROFILE=", "roomba-bt run dock --fast", 2,
           env=(("ROOMBA_BT_PROFILE", "roomba560"),)),
    Quoted("docs/robot.md", "roomba-bt clock: the iRobot Create 2", "roomba-bt clock --set-now",
           2),
    Quoted("docs/ci.md", "roomba-bt eval: w1.yaml: failed --strict",
           "roomba-bt eval w1.yaml --strict --runs 1", 7,
           files=W1),
    Quoted("docs/evaluation.md", "roomba-bt eval: w1.yaml: failed --strict",
           "roomba-bt eval w1.yaml --strict --runs 1", 7,
           files=W1),
    Quoted("docs/evaluation.md", "roomba-bt eval: 2 of 3 missions",
           "roomba-bt eval dock nope.yaml gone.yaml", 2),
    Quoted("docs/evaluation.md", "roomba-bt eval: warning: ./dock.yaml is dock.yaml again",
           "roomba-bt eval dock.yaml ./dock.yaml --runs 1", 0, files=(("dock.yaml", TINY),)),
    Quoted("docs/evaluation.md", "roomba-bt eval: --out ab.jsonl: the file already holds",
           "roomba-bt eval x.yaml --runs 1 --out ab.jsonl", 2, files=(("x.yaml", TINY),),
           first=("roomba-bt eval x.yaml --runs 1 --out ab.jsonl",)),
    Quoted("docs/missions.md", "roomba-bt validate: reading a mission from standard input",
           "roomba-bt validate -", 2),
    Quoted("docs/missions.md", "roomba-bt validate: warning: ./x.yaml is x.yaml again",
           "roomba-bt validate x.yaml ./x.yaml", 0, files=(("x.yaml", TINY),)),
    Quoted("docs/monitor.md", "roomba-bt run: --monitor-readonly is for --monitor",
           "roomba-bt run dock --fast --monitor-readonly", 2),
    Quoted("docs/runtime.md", "roomba-bt run: missions/: a directory",
           "roomba-bt run missions/ --fast", 2, files=(("missions/m.yaml", TINY),)),
    Quoted("docs/runtime.md", "roomba-bt replay: ...", "roomba-bt replay nope.jsonl", 2),
    Quoted("docs/runtime.md", "roomba-bt monitor: ...", "roomba-bt monitor nope.jsonl", 2),
    Quoted("docs/runtime.md", "roomba-bt show: ...", "roomba-bt show missions/", 2,
           files=(("missions/m.yaml", TINY),)),
    Quoted("docs/runtime.md", "roomba-bt run: --record run.jsonl: another roomba-bt",
           "roomba-bt run dock --fast --record run.jsonl", 2, held="run.jsonl"),
    Quoted("docs/simulator.md", "roomba-bt run: ROOMBA_BT_WORLDS:", "roomba-bt run dock --fast",
           2, env=(("ROOMBA_BT_WORLDS", "/home/me/worlds"),)),
    Quoted("docs/simulator.md", "roomba-bt sensors: my-flat.yaml: world:",
           "roomba-bt sensors --world my-flat.yaml --count 1", 2,
           files=(("my-flat.yaml", None),)),
    Quoted("docs/simulator.md", "roomba-bt sim: invalid world:",
           "roomba-bt sim --world bad.yaml --tcp 127.0.0.1:0", 2,
           files=(("bad.yaml", "name: bad\nrooms: 3\n"),)),
    Quoted("docs/ci.md", "roomba-bt: w1.yaml: failed --strict",
           "roomba-bt run w1.yaml --strict --fast", 7, files=W1),
    Quoted("docs/runtime.md", "roomba-bt: w1.yaml: failed --strict",
           "roomba-bt run w1.yaml --strict --fast", 7, files=W1),
    Quoted("docs/runtime.md", "strict passed:", "roomba-bt run m.yaml --strict --fast", 0,
           files=(("m.yaml", TINY),), stream="out"),
    Quoted("docs/runtime.md", "replay: m2.yaml is not the recorded mission",
           "roomba-bt replay r.jsonl --mission m2.yaml", 1,
           files=(("m.yaml", TINY), ("m2.yaml", "tree: {sequence: [{mode: safe}, wait: 1s]}\n")),
           first=("roomba-bt run m.yaml --fast --record r.jsonl",), stream="out"),
    Quoted("docs/runtime.md", "roomba-bt replay: nope.jsonl: record:",
           "roomba-bt replay nope.jsonl", 2),
    *(Quoted("docs/simulator.md", start, command, code, files=files, stream=stream)
      for start, command, code, files, stream in docs_inputs.SIMULATOR_MD),
    *(Quoted("docs/missions.md", start, f"roomba-bt validate {argv}", code, files=files,
             stream="out") for start, argv, code, files in docs_inputs.MISSIONS_MD),
    *(Quoted("docs/plugins.md", start, "roomba-bt validate lab.yaml --allow-plugin-files", 2,
             files=files, stream="out", workdir_as="/home/me/lab")
      for start, files in docs_inputs.PLUGINS_MD),
    Quoted("docs/monitor.md", "main.yaml:2:11: plugin", "roomba-bt validate main.yaml "
           "--allow-plugin-files", 2, files=docs_inputs.BROKEN_PLUGIN, stream="out"),
]  # fmt: skip

#: The quotes whose command is a test of its own (a hung episode, a lost Dask worker, a
#: broken plugin installed): the test that makes the line holds the page to it with
#: ``quoted.assert_quoted`` (the page, how the quote begins: the test named).
QUOTED_ELSEWHERE: dict[tuple[str, str], str] = {
    ("docs/robot.md", "roomba-bt clock: the robot's clock button is pressed"): "tests/cli/"
    "test_clock_cmd.py::test_a_clock_button_held_sends_nothing_and_says_why",
    ("docs/robot.md", "weekly.yaml:3:11: found"): "tests/cli/"
    "test_clock_cmd.py::test_the_schedule_file_fault_docs_quote",
    ("docs/simulator.md", "roomba-bt sim: the robot's clock reads"): "tests/cli/"
    "test_sim_cmd.py::test_the_served_simulator_says_the_clock_and_schedule_a_client_set",
    **{
        ("docs/doctor.md", start): "tests/cli/test_sensors_cmd.py::test_sensors_on_a_cable_"
        "losing_bytes_says_what_it_lost_as_run_s_summary_does"
        for start in ("roomba-bt sensors: frames", "roomba-bt sensors: link")
    },
    ("docs/runtime.md", "replay: interrupted at mission time"): "tests/cli/"
    "test_replay_interrupted.py::test_a_replay_interrupted_exits_130_and_judges_no_bytes",
    ("docs/runtime.md", "roomba-bt: SIGINT came while Python ran"): "tests/cli/test_entry.py::"
    "test_an_interrupt_python_dropped_while_validate_reads_a_file_ends_it_at_the_next",
    ("docs/evaluation.md", "roomba-bt eval: 3 episode(s) hung"): "tests/evaluate/"
    "test_stuck_threads.py::test_a_sweep_whose_episodes_each_hang_in_terminate_stops_at_the_cap",
    ("docs/evaluation.md", "roomba-bt eval: the sweep stopped:"): "tests/evaluate/"
    "test_stuck_threads.py::test_a_sweep_whose_episodes_each_hang_in_terminate_stops_at_the_cap",
    ("docs/evaluation.md", "roomba-bt eval: 2 episode(s) ran again"): "tests/evaluate/"
    "test_cluster.py::test_the_seeds_run_again_are_named_from_their_keys",
    ("docs/evaluation.md", "roomba-bt eval: the same command with --resume"): "tests/evaluate/"
    "test_resume.py::test_an_interrupted_evaluation_says_its_plot_is_not_drawn",
    ("docs/evaluation.md", "roomba-bt eval: --plot ab.png not drawn"): "tests/evaluate/"
    "test_resume.py::test_an_interrupted_evaluation_says_its_plot_is_not_drawn",
    ("docs/evaluation.md", "roomba-bt eval: --from ab.jsonl.partial.jsonl:"): "tests/evaluate/"
    "test_seeds_and_from.py::test_from_leaves_out_the_last_record_a_killed_sweep_cut_short",
    ("docs/evaluation.md", "ab.jsonl:41:201: not JSON"): "tests/evaluate/test_seeds_and_"
    "from.py::test_from_a_file_that_holds_no_results_says_which_and_why_in_one_line",
    ("docs/runtime.md", "safe stop nothing to send: the tree's Stop"): "tests/runtime/"
    "test_tree_ends_the_oi.py::test_a_tree_that_turns_the_oi_off_ends_the_run_at_once",
    ("docs/runtime.md", "final mode Off"): "tests/runtime/"
    "test_tree_ends_the_oi.py::test_a_tree_that_turns_the_oi_off_ends_the_run_at_once",
    ("docs/runtime.md", "roomba-bt: the summary was lost with stdout"): "tests/cli/"
    "test_streams.py::test_a_closed_pipe_keeps_a_failed_runs_exit_code_and_says_its_outcome",
    ("docs/runtime.md", "roomba-bt: the report was cut short:"): "tests/cli/"
    "test_exit_signals.py::test_last_words_that_never_end_are_ended_with_the_signal_s_code",
    ("docs/missions.md", "many.yaml:3:50005: checking stopped"): "tests/mission/"
    "test_hostile_files.py::test_a_missions_check_stops_at_the_cap_and_says_so_among_the_"
    "first_listed",
    ("docs/missions.md", "w.yaml:10002:31: warning: warnings stopped"): "tests/mission/"
    "test_hostile_files.py::test_a_missions_warnings_stop_at_the_cap_and_say_so_among_the_"
    "first_listed",
    ("docs/missions.md", "roomba-bt: warning: .../pyproject.toml:"): "tests/mission/"
    "test_include_path.py::test_a_project_file_grants_nothing_outside_its_own_folder",
    ("docs/missions.md", "roomba-bt validate: warning: plugin ..."): "tests/mission/"
    "test_half_loaded_plugin.py::test_the_pages_quote_what_each_command_says_of_it",
    ("docs/plugins.md", "roomba-bt behaviours: an installed plugin did not"): "tests/mission/"
    "test_half_loaded_plugin.py::test_the_pages_quote_what_each_command_says_of_it",
    ("docs/plugins.md", "roomba-bt validate: warning: plugin 'keys'"): "tests/mission/"
    "test_half_loaded_plugin.py::test_the_pages_quote_what_each_command_says_of_it",
    ("docs/plugins.md", "roomba-bt schema: error: plugin 'lab'"): "tests/mission/"
    "test_broken_plugin_cli.py::test_the_page_quotes_what_schema_and_behaviours_say_of_a_"
    "plugin_that_does_not_import",
    ("docs/plugins.md", "roomba-bt behaviours: error: ..."): "tests/mission/"
    "test_broken_plugin_cli.py::test_the_page_quotes_what_schema_and_behaviours_say_of_a_"
    "plugin_that_does_not_import",
    ("docs/runtime.md", "m.yaml:1:1: cannot read mission file"): "tests/mission/"
    "test_hostile_files.py::test_a_mission_file_that_cannot_be_read_is_named_with_what_is_"
    "wanted",
    ("docs/ci.md", "w.yaml:1:1: cannot read file"): "tests/mission/"
    "test_hostile_files.py::test_validate_names_a_file_it_cannot_read_as_either",
    ("docs/simulator.md", "roomba-bt run: w.yaml: world: cannot be read"): "tests/cli/"
    "test_world_files.py::test_a_world_file_that_cannot_be_read_says_what_is_wanted",
    ("docs/evaluation.md", "roomba-bt eval: warning: slowest tick"): "tests/runtime/test_"
    "tick_watch.py::test_eval_reproducible_says_the_slow_tick_on_stderr_its_report_the_same_"
    "bytes",
    ("docs/runtime.md", "replay: the recorded run wrote Stop (173)"): "tests/runtime/test_"
    "replay_of_old_end_in_records.py::test_an_old_record_whose_stop_is_not_its_last_bytes_"
    "says_what_differs",
    # session 41: the quotes held by the tests that make them
    ("docs/runtime.md", "outcome CONNECTION LOST (the recorded run's"): (
        "tests/runtime/test_replay_of_link_faults.py::test_the_replay_of_a_run_whose_link_"
        "failed_compares_the_tree_up_to_there_and_exits_0"
    ),
    ("docs/runtime.md", "safe stop not replayed"): (
        "tests/runtime/test_replay_of_link_faults.py::test_the_replay_of_a_run_whose_link_"
        "failed_compares_the_tree_up_to_there_and_exits_0"
    ),
    ("docs/runtime.md", "replay: the recorded run lost its link at"): (
        "tests/runtime/test_replay_of_link_faults.py::test_the_replay_of_a_run_whose_link_"
        "failed_compares_the_tree_up_to_there_and_exits_0"
    ),
    ("docs/runtime.md", "replay: past there the replay"): (
        "tests/runtime/test_replay_of_link_faults.py::test_the_replay_of_a_run_whose_link_"
        "failed_compares_the_tree_up_to_there_and_exits_0"
    ),
    ("docs/runtime.md", "replay: the recorded run lost its link before"): (
        "tests/runtime/test_replay_of_link_faults.py::test_the_replay_of_a_run_whose_link_"
        "failed_compares_the_tree_up_to_there_and_exits_0"
    ),
    ("docs/runtime.md", "replay: the tree wrote the same 28 bytes as"): (
        "tests/runtime/test_replay_of_link_faults.py::test_the_replay_of_a_run_whose_link_"
        "failed_compares_the_tree_up_to_there_and_exits_0"
    ),
    (
        "docs/runtime.md",
        "outcome CONNECTION LOST (the safe stop did not reach the "
        "robot (the run had ended: success",
    ): (
        "tests/runtime/test_stop_unheard.py::test_a_run_whose_stop_the_robot_never_heard_is_no_"
        "success"
    ),
    ("docs/runtime.md", "safe stop NOT DELIVERED: ... unconfirmed: the port"): (
        "tests/runtime/test_silence_causes.py::test_a_stop_at_a_followed_rate_the_robot_does_"
        "not_answer_is_unconfirmed"
    ),
    ("docs/reliability.md", "safe stop NOT DELIVERED: ... the stop was"): (
        "tests/runtime/test_silence_causes.py::test_a_stop_at_a_followed_rate_the_robot_does_"
        "not_answer_is_unconfirmed"
    ),
    ("docs/reliability.md", "final mode unknown: last seen in ..."): (
        "tests/runtime/test_silence_causes.py::test_a_stop_at_a_followed_rate_the_robot_does_"
        "not_answer_is_unconfirmed"
    ),
    ("docs/runtime.md", "safe stop sent pause_resume_stream, start$"): (
        "tests/runtime/test_silence_causes.py::test_a_roomba500_read_by_the_default_profile_"
        "ends_the_run_at_the_watchdog_trip"
    ),
    ("docs/runtime.md", "unread 1 gap(s)"): (
        "tests/runtime/test_loop.py::test_a_gap_nobody_read_is_counted_and_said"
    ),
    ("docs/runtime.md", "safe stop nothing to stop"): (
        "tests/runtime/test_interrupts.py::test_a_ctrl_c_before_the_first_byte_says_nothing_"
        "needed_stopping"
    ),
    ("docs/runtime.md", "final mode Passive (not in"): (
        "tests/runtime/test_summary.py::test_the_final_mode_of_a_stream_without_packet_35_is_"
        "said_as_the_models"
    ),
    ("docs/runtime.md", "roomba-bt: timeout: --fast's"): (
        "tests/runtime/test_cli_run.py::test_fast_without_a_timeout_stops_at_its_own_limit_and_"
        "says_how_to_change_it"
    ),
    ("docs/runtime.md", "roomba-bt: no --timeout was given"): (
        "tests/runtime/test_cli_run.py::test_fast_without_a_timeout_stops_at_its_own_limit_and_"
        "says_how_to_change_it"
    ),
    ("docs/runtime.md", "safe stop drive 0, motors off before"): (
        "tests/runtime/test_terminate_never_returns.py::test_ctrl_c_while_the_run_waits_for_a_"
        "terminate_that_never_returns_is_exit_130"
    ),
    ("docs/runtime.md", "roomba-bt: interrupted$"): (
        "tests/cli/test_entry.py::test_a_signal_as_soon_as_the_command_takes_it_is_exit_130_"
        "without_a_traceback"
    ),
    ("docs/architecture.md", "roomba-bt: interrupted$"): (
        "tests/cli/test_entry.py::test_a_signal_as_soon_as_the_command_takes_it_is_exit_130_"
        "without_a_traceback"
    ),
    ("docs/runtime.md", "roomba-bt: interrupted by SIGQUIT"): (
        "tests/cli/test_entry.py::test_a_signal_as_soon_as_the_command_takes_it_is_exit_130_"
        "without_a_traceback"
    ),
    ("docs/runtime.md", "roomba-bt: interrupted by SIGTERM$"): (
        "tests/cli/test_streams.py::test_a_signal_python_wraps_in_a_runtime_error_is_still_exit_130"
    ),
    ("docs/runtime.md", "roomba-bt: stdout is closed"): (
        "tests/cli/test_streams.py::test_a_closed_stdout_is_no_traceback"
    ),
    ("docs/runtime.md", "roomba-bt: cannot write to stdout"): (
        "tests/cli/test_streams.py::test_a_full_disk_on_stdout_is_one_line_and_the_outcomes_"
        "exit_code"
    ),
    ("docs/runtime.md", "ticks 447"): (
        "tests/runtime/test_docs_replays.py::test_a_reproducible_run_s_ticks_line_is_the_count_"
        "alone"
    ),
    ("docs/runtime.md", "replay: the tree wrote the same 43 bytes as"): (
        "tests/runtime/test_docs_replays.py::test_a_replay_of_the_same_bytes_says_how_many"
    ),
    ("docs/runtime.md", "replay: compared up to"): (
        "tests/runtime/test_docs_replays.py::test_a_replay_cut_with_to_says_how_far_it_compared"
    ),
    ("docs/monitor.md", "replay: compared up to"): (
        "tests/runtime/test_docs_replays.py::test_a_replay_cut_with_to_says_how_far_it_compared"
    ),
    ("docs/runtime.md", "replay: recorded with roomba-bt 0.2.0 (this release too)"): (
        "tests/runtime/test_docs_replays.py::test_a_replay_on_an_edited_library_counts_the_"
        "files_changed"
    ),
    ("docs/runtime.md", "replay: the record ends at"): (
        "tests/runtime/test_docs_replays.py::test_a_record_cut_short_is_compared_up_to_its_end"
    ),
    ("docs/runtime.md", "replay: the tree wrote the same 28 bytes up to"): (
        "tests/runtime/test_docs_replays.py::test_a_record_cut_short_is_compared_up_to_its_end"
    ),
    ("docs/runtime.md", "replay: first difference at mission time 1.005 s"): (
        "tests/runtime/test_docs_replays.py::test_another_mission_s_first_difference_names_"
        "both_commands"
    ),
    ("docs/runtime.md", "r.jsonl: mission '../missions/x.yaml' is not beside"): (
        "tests/runtime/test_docs_replays.py::test_a_record_moved_out_of_its_repository_replays_"
        "the_mission_where_recorded"
    ),
    ("docs/runtime.md", "outcome SUCCESS$"): (
        "tests/runtime/test_strict.py::test_a_leaf_driving_on_after_a_fall_succeeds_without_"
        "strict_but_warns"
    ),
    ("docs/runtime.md", "strict FAILED (exit 7)"): (
        "tests/runtime/test_strict.py::test_with_strict_it_exits_7_naming_each_count_and_its_"
        "first_instance"
    ),
    ("docs/runtime.md", "roomba-bt: --strict: the mode guard refused"): (
        "tests/runtime/test_strict.py::test_with_strict_it_exits_7_naming_each_count_and_its_"
        "first_instance"
    ),
    ("docs/runtime.md", "roomba-bt: the monitor's web server (aiohttp)"): (
        "tests/cli/test_broken_installation.py::test_a_half_installed_extra_names_its_extra_"
        "and_shows_the_traceback_with_v"
    ),
    ("docs/runtime.md", "roomba-bt: timeout: ..."): (
        "tests/runtime/test_cli_run.py::test_fast_without_a_timeout_stops_at_its_own_limit_and_"
        "says_how_to_change_it"
    ),
    ("docs/runtime.md", "falls the robot fell"): (
        "tests/runtime/test_summary.py::test_falls_of_several_causes_are_said_the_commonest_first"
    ),
    ("docs/runtime.md", "charger docked 2 times"): (
        "tests/runtime/test_summary.py::test_dockings_are_counted_apart_from_the_falls_with_"
        "the_time_on_the_charger"
    ),
    ("docs/runtime.md", "battery 67%"): (
        "tests/runtime/test_summary.py::test_the_lowest_battery_level_is_said_when_it_was_"
        "lower_than_the_last"
    ),
    ("docs/runtime.md", "roomba-bt: warning: r.jsonl: include"): (
        "tests/runtime/test_record_checkouts.py::test_a_record_grants_no_folder_outside_the_"
        "one_that_holds_it_and_its_mission"
    ),
    ("docs/runtime.md", "replay: recorded by roomba-bt 0.1.0 or earlier"): (
        "tests/runtime/test_replay_of_0_1_0_records.py::test_a_0_1_0_record_that_differs_says_"
        "which_release_made_it"
    ),
    ("docs/runtime.md", "replay: the record's mission m.yaml is refused"): (
        "tests/runtime/test_replay_of_0_1_0_records.py::test_a_0_1_0_record_whose_mission_is_"
        "refused_says_to_pass_the_fixed_file"
    ),
    ("docs/runtime.md", "replay: first difference at mission time 1.020 s"): (
        "tests/runtime/test_recording.py::test_a_command_the_replayed_tree_writes_before_its_"
        "frames_is_a_difference"
    ),
    ("docs/runtime.md", "replay: roomba-bt:lib/undock.yaml changed"): (
        "tests/runtime/test_recording.py::test_a_replay_that_differs_names_the_files_changed_"
        "since_the_record_was_made"
    ),
    ("docs/runtime.md", "r.jsonl: mission '/usr/lib/"): (
        "tests/runtime/test_recording.py::test_a_record_of_a_shipped_mission_made_before_"
        "replays_it_where_its_path_is_gone"
    ),
    ("docs/runtime.md", "replay: recorded with roomba-bt 0.2.0 (this is"): (
        "tests/runtime/test_recording.py::test_a_replay_says_in_one_line_that_it_ran_on_other_"
        "files_than_the_record_was_made_with"
    ),
    ("docs/monitor.md", "monitor: ended by SIGTERM"): (
        "tests/monitor/test_cli.py::test_monitor_of_a_record_ends_on_sigterm_as_on_ctrl_c"
    ),
    ("docs/monitor.md", "monitor: long.jsonl: interrupted"): (
        "tests/monitor/test_cli.py::test_a_signal_while_the_record_is_read_ends_monitor_without_a_page"
    ),
    ("docs/monitor.md", "roomba-bt: interrupted"): (
        "tests/monitor/test_cli.py::test_a_ctrl_c_python_dropped_as_the_mission_loads_ends_monitor"
        "_without_a_page"
    ),
    ("docs/monitor.md", "monitor: http://127.0.0.1:8765/"): (
        "tests/monitor/test_cli.py::test_the_url_is_said_once_the_robot_s_port_is_open_with_"
        "the_mission_and_robot"
    ),
    ("docs/monitor.md", "monitor: http://127.0.0.1:8766/"): (
        "tests/monitor/test_cli.py::test_a_run_s_label_is_on_its_url_line_page_summary_and_record"
    ),
    ("docs/monitor.md", "monitor: http://0.0.0.0:8765/?token=CONTROL"): (
        "tests/monitor/test_cli.py::test_a_wildcard_address_is_said_by_the_machine_s_lan_"
        "addresses_too"
    ),
    ("docs/monitor.md", "monitor: it listens on every address"): (
        "tests/monitor/test_cli.py::test_a_wildcard_address_is_said_by_the_machine_s_lan_"
        "addresses_too"
    ),
    ("docs/monitor.md", "monitor: view only: http://0.0.0.0:8765/view/?token=VIEW"): (
        "tests/monitor/test_cli.py::test_a_wildcard_address_is_said_by_the_machine_s_lan_"
        "addresses_too"
    ),
    ("docs/monitor.md", "monitor: view only: it listens"): (
        "tests/monitor/test_cli.py::test_a_wildcard_address_is_said_by_the_machine_s_lan_"
        "addresses_too"
    ),
    ("docs/monitor.md", "monitor: http://0.0.0.0:8765/ (dock on"): (
        "tests/monitor/test_cli.py::test_a_chosen_token_outlives_the_run_and_is_printed_nowhere"
    ),
    ("docs/monitor.md", "monitor: view only: http://0.0.0.0:8765/view/ (add"): (
        "tests/monitor/test_cli.py::test_a_chosen_view_token_opens_the_page_without_controls_"
        "and_is_printed_nowhere"
    ),
    ("docs/monitor.md", "monitor: reading long.jsonl"): (
        "tests/monitor/test_cli.py::test_a_record_of_a_megabyte_says_at_once_that_it_is_read_"
        "before_its_page"
    ),
    ("docs/monitor.md", "monitor: R.jsonl: its world ../worlds/mine.yaml"): (
        "tests/monitor/test_cli.py::test_a_recorded_view_draws_the_world_its_record_names_from_"
        "where_the_robot_started"
    ),
    ("docs/runtime.md", "monitor: r.jsonl: its world /etc/shadow"): (
        "tests/monitor/test_cli.py::test_a_records_world_outside_its_folder_is_not_read_and_"
        "its_header_texts_are_escaped"
    ),
    ("docs/monitor.md", "monitor: R.jsonl: its world living"): (
        "tests/monitor/test_cli.py::test_a_records_world_of_another_digest_is_said_and_not_drawn"
    ),
    ("docs/monitor.md", "monitor: key r (resume) refused"): (
        "tests/monitor/test_keys.py::test_a_key_that_does_nothing_says_why"
    ),
    ("docs/monitor.md", "monitor: key 'x' does nothing"): (
        "tests/monitor/test_keys.py::test_a_key_that_does_nothing_says_why"
    ),
    ("docs/monitor.md", "monitor: keys: off"): (
        "tests/monitor/test_keys.py::test_a_terminal_that_hangs_up_turns_the_keys_off_once"
    ),
    ("docs/runtime.md", "replay: the recorded run was stopped by"): (
        "tests/monitor/test_keys.py::test_p_pauses_r_resumes_q_stops_and_the_terminal_is_given_back"
    ),
    ("docs/monitor.md", "paused 369.20 s"): (
        "tests/monitor/test_operator.py::test_a_run_never_paused_has_no_paused_line"
    ),
    ("docs/doctor.md", "roomba-bt: wrong profile: PORT:"): (
        "tests/cli/test_wrong_profile.py::test_sensors_with_the_default_profile_on_a_roomba500_"
        "names_the_profile"
    ),
    ("docs/robot.md", "roomba-bt: wrong profile: ...$"): (
        "tests/cli/test_wrong_profile.py::test_sensors_with_the_default_profile_on_a_roomba500_"
        "names_the_profile"
    ),
    ("docs/runtime.md", "roomba-bt: wrong profile: PORT:"): (
        "tests/cli/test_wrong_profile.py::test_run_with_the_default_profile_on_a_roomba500_"
        "names_the_profile"
    ),
    ("docs/unattended.md", "outcome WRONG PROFILE"): (
        "tests/cli/test_wrong_profile.py::test_run_with_the_default_profile_on_a_roomba500_"
        "names_the_profile"
    ),
    ("docs/robot.md", "outcome WRONG PROFILE ("): (
        "tests/cli/test_wrong_profile.py::test_a_wrong_profile_set_elsewhere_is_fixed_where_it_"
        "was_set"
    ),
    ("docs/robot.md", "roomba-bt: wrong profile: /dev/ttyUSB0"): (
        "tests/cli/test_wrong_profile.py::test_a_wrong_profile_set_elsewhere_is_fixed_where_it_"
        "was_set"
    ),
    ("docs/runtime.md", "final mode unknown: last seen in Passive, the run set"): (
        "tests/runtime/test_summary.py::test_an_unconfirmed_stop_of_a_robot_the_run_set_"
        "nothing_going_is_said_calmly"
    ),
    ("docs/runtime.md", "replay: 30% of long.jsonl"): (
        "tests/runtime/test_recording.py::test_the_replay_of_a_long_record_says_how_far_it_has_gone"
    ),
    ("docs/monitor.md", "monitor: 10% of long.jsonl"): (
        "tests/runtime/test_recording.py::test_the_replay_of_a_long_record_says_how_far_it_has_gone"
    ),
    ("docs/runtime.md", "outcome INTERRUPTED (Ctrl-C or kill -INT"): (
        "tests/runtime/test_stuck_tick.py::test_an_interrupt_in_a_stuck_tick_names_the_leaf_"
        "and_its_line"
    ),
    ("docs/runtime.md", "outcome HUNG (--wall-limit"): (
        "tests/runtime/test_stuck_tick.py::test_the_wall_limit_ends_a_stuck_run_naming_the_"
        "leaf_after_the_safe_stop"
    ),
    ("docs/runtime.md", "ticks 8001 ("): (
        "tests/runtime/test_tick_watch.py::test_a_tick_the_host_kept_from_running_is_said_so_"
        "not_blamed_on_its_behaviour"
    ),
    ("docs/runtime.md", "tick guard 7 slow tick(s)"): (
        "tests/runtime/test_tick_guard.py::test_a_tick_that_blocks_with_the_motors_on_gets_"
        "them_off_and_back_after"
    ),
    ("docs/runtime.md", "replay: the end note counts 38 bytes"): (
        "tests/runtime/test_cli_pty.py::_an_older_records_count_is_said_as_its_miscount"
    ),
    ("docs/runtime.md", "replay: the end note counts no bytes"): (
        "tests/runtime/test_replay_of_old_stall_records.py::test_an_old_ctrl_c_in_a_stall_noted_"
        "without_a_count_replays_to_its_stop"
    ),
    ("docs/plugins.md", "replay: plugin roomba-bt-dirt 0.1.0's code"): (
        "tests/runtime/test_recording.py::test_a_record_names_its_plugins_and_a_replay_that_"
        "differs_names_the_one_changed"
    ),
    ("docs/runtime.md", "replay: plugin roomba-bt-dirt changed"): (
        "tests/runtime/test_recording.py::test_a_record_names_its_plugins_and_a_replay_that_"
        "differs_names_the_one_changed"
    ),
    ("docs/plugins.md", "roomba-bt: this record was made with plugin"): (
        "tests/runtime/test_recording.py::test_a_replay_whose_recorded_plugin_is_not_installed_"
        "says_so_first"
    ),
    ("docs/plugins.md", "replay: the record's mission lab.yaml"): (
        "tests/runtime/test_recording.py::test_a_replay_whose_recorded_plugin_is_not_installed_"
        "says_so_first"
    ),
    ("docs/robot.md", "safe stop sent drive, motors, pause_resume_stream, start ("): (
        "tests/runtime/test_cli_pty.py::test_a_bridge_that_drops_the_run_gets_the_stop_through_"
        "a_new_connection"
    ),
    ("docs/doctor.md", "outcome NO CONNECTION"): (
        "tests/runtime/test_cli_pty.py::test_no_robot_at_any_rate_has_its_summary_and_names_"
        "its_port"
    ),
    ("docs/doctor.md", "safe stop nothing of the mission sent"): (
        "tests/runtime/test_cli_pty.py::test_no_robot_at_any_rate_has_its_summary_and_names_"
        "its_port"
    ),
    ("docs/runtime.md", "roomba-bt: internal error: RuntimeError"): (
        "tests/cli/test_internal_errors.py::test_a_bug_in_the_runner_after_the_safe_stop_"
        "closes_the_port_and_exits_70"
    ),
    ("docs/unattended.md", "roomba-bt: connection lost: ..."): (
        "tests/runtime/test_cli_run.py::test_a_long_lost_link_line_is_said_a_clause_a_line_for_"
        "the_journal"
    ),
    ("docs/unattended.md", "roomba-bt: the watchdog sent drive 0"): (
        "tests/runtime/test_cli_run.py::test_a_long_lost_link_line_is_said_a_clause_a_line_for_"
        "the_journal"
    ),
    ("docs/robot.md", "safe stop sent ... (the robot had moved to 300"): (
        "tests/runtime/test_stop_at_another_rate.py::test_a_robot_a_lost_byte_put_on_300_baud_"
        "is_stopped_there_and_put_back"
    ),
    ("docs/reliability.md", "safe stop sent ... (not taken at first"): (
        "tests/runtime/test_stop_swallowed.py::test_the_record_of_a_stop_written_again_replays_"
        "byte_for_byte"
    ),
    ("docs/reliability.md", "unheard the robot did not do"): (
        "tests/runtime/test_unheard_commands.py::test_a_drive_whose_byte_was_lost_is_sent_"
        "again_and_the_robot_drives"
    ),
    ("docs/simulator.md", "falls the robot fell"): (
        "tests/runtime/test_passive_after_a_fall.py::test_the_wall_charger_plugged_in_mid_"
        "drive_is_followed_and_named"
    ),
    ("docs/evaluation.md", "falls the robot fell to Passive by itself 5 times"): (
        "tests/evaluate/test_falls.py::test_each_episode_carries_its_falls_and_the_report_sums_them"
    ),
    ("docs/evaluation.md", "falls the robot fell to Passive by itself 3 times"): (
        "tests/evaluate/test_falls.py::test_the_charger_s_falls_are_dockings_said_apart_from_"
        "the_hazards"
    ),
    ("docs/evaluation.md", "charger docked 10 times in 10 of 10"): (
        "tests/evaluate/test_falls.py::test_the_charger_s_falls_are_dockings_said_apart_from_"
        "the_hazards"
    ),
    ("docs/monitor.md", "safe stop replayed drive"): (
        "tests/monitor/test_session.py::test_a_replayed_pause_says_its_safe_stop_was_replayed_"
        "not_sent"
    ),
    ("docs/evaluation.md", "variant"): (
        "tests/evaluate/test_docs_reports.py::test_each_variant_s_lines_are_the_reports"
    ),
    ("docs/evaluation.md", "success"): (
        "tests/evaluate/test_docs_reports.py::test_each_variant_s_lines_are_the_reports"
    ),
    ("docs/evaluation.md", "time"): (
        "tests/evaluate/test_docs_reports.py::test_each_variant_s_lines_are_the_reports"
    ),
    ("docs/evaluation.md", "trapped"): (
        "tests/evaluate/test_docs_reports.py::test_each_variant_s_lines_are_the_reports"
    ),
    ("docs/evaluation.md", "A/B"): (
        "tests/evaluate/test_docs_reports.py::test_the_a_b_lines_are_the_reports"
    ),
    ("docs/evaluation.md", "paired"): (
        "tests/evaluate/test_docs_reports.py::test_the_a_b_lines_are_the_reports"
    ),
    ("docs/robot.md", "roomba-bt run: --profile auto:"): (
        "tests/cli/test_profile_auto.py::test_run_profile_auto_identifies_the_robot_and_the_"
        "summary_says_how"
    ),
    ("docs/robot.md", "profile roomba600"): (
        "tests/cli/test_profile_auto.py::test_run_profile_auto_identifies_the_robot_and_the_"
        "summary_says_how"
    ),
    ("docs/evaluation.md", "roomba-bt eval: m4.yaml"): (
        "tests/evaluate/test_worker_plugins.py::test_eval_says_a_worker_without_the_plugin_"
        "once_and_exits_3"
    ),
    ("docs/evaluation.md", "roomba-bt eval: install on every worker"): (
        "tests/evaluate/test_worker_plugins.py::test_eval_says_a_worker_without_the_plugin_"
        "once_and_exits_3"
    ),
    ("docs/robot.md", "final mode Off$"): "tests/runtime/"
    "test_cli_pty.py::test_end_in_stop_leaves_the_simulator_in_off_and_says_so",
    ("docs/runtime.md", "safe stop sent drive, motors, pause_resume_stream, stop ("): "tests/"
    "runtime/test_cli_pty.py::test_end_in_stop_leaves_the_simulator_in_off_and_says_so",
    ("docs/robot.md", "final mode Passive$"): "tests/runtime/"
    "test_stop_at_another_rate.py::test_end_in_stop_found_at_another_rate_ends_as_the_summary_says",
}


@pytest.mark.parametrize("quoted", QUOTED, ids=[f"{q.doc}:{q.start}" for q in QUOTED])
def test_each_quoted_line_is_what_the_command_prints(
    quoted: Quoted,
    scratch: Callable[..., Path],
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
    record_held: Callable[[Path], object],
) -> None:
    workdir = scratch(quoted.doc)
    for name, value in quoted.env:
        monkeypatch.setenv(name, value)
    for file, text in quoted.files:
        if text is None:
            (workdir / file).unlink()
        else:
            (workdir / file).parent.mkdir(parents=True, exist_ok=True)
            (workdir / file).write_text(text)
    for command in quoted.first:
        assert main(shlex.split(command)[1:]) == 0, capsys.readouterr()
    if quoted.held is not None:
        record_held(workdir / quoted.held)
    capsys.readouterr()
    assert main(shlex.split(quoted.command)[1:]) == quoted.code, capsys.readouterr()
    out, err = capsys.readouterr()
    names = {str(workdir): quoted.workdir_as} if quoted.workdir_as else None
    assert_quoted(quoted.doc, quoted.start, err if quoted.stream == "err" else out, names=names)


def _listed(doc: str, quote: str, listed: set[tuple[str, str]]) -> bool:
    """``quote`` of ``doc`` is one of ``listed``: (the page, how it begins, or ``kind:NAME``
    for every quote of that kind on the page)."""
    return any(
        d == doc and (begins(quote, start) or start == f"kind:{kind_of(quote)}")
        for d, start in listed
    )


#: How far before a quote of history its page says so (a sentence's clause: "it was `...`")
HISTORY_WITHIN = 200


def history_said(doc: str, quote: str) -> tuple[int, int]:
    """How many of the page's inline quotes ``quote`` are said to be history (a marker of
    :data:`HISTORY` for it within :data:`HISTORY_WITHIN` characters before), of how many."""
    page = " ".join((ROOT / doc).read_text(encoding="utf-8").split())
    markers = [
        marker
        for (d, start), said in HISTORY.items()
        if d == doc and begins(quote, start)
        for marker in said
    ]
    at = [m.start() for m in re.finditer(re.escape(f"`{quote}`"), page)]
    said = [i for i in at if any(m in page[max(0, i - HISTORY_WITHIN) : i] for m in markers)]
    return len(said), len(at)


def _all_history(doc: str, quote: str) -> bool:
    said, at = history_said(doc, quote)
    return said == at > 0


def test_every_quoted_line_is_held_to_what_its_command_prints() -> None:
    """A quote of a line a command prints (tests/quoted.py: ``roomba-bt CMD: ...``, a
    diagnostic, ``roomba-bt: ...``, ``replay: ...``, ``monitor: ...``, a record's, a summary
    line) on any page is in :data:`QUOTED` or :data:`QUOTED_ELSEWHERE`, whose test holds it
    (this test reads that it does), or in :data:`NOT_YET_HELD` with the reason: a new quote,
    or one reworded past its start, is not left unchecked, and a listed one gone fails."""
    held = {(q.doc, q.start) for q in QUOTED} | set(QUOTED_ELSEWHERE)
    pages = [path.relative_to(ROOT).as_posix() for path in DOCS]
    found = [(doc, quote) for doc in pages for quote in quotes(doc)]
    unheld = [
        f"{doc}: `{quote}`"
        for doc, quote in found
        if not _listed(doc, quote, held | set(NOT_YET_HELD))
        and not (_listed(doc, quote, set(HISTORY)) and _all_history(doc, quote))
    ]
    assert not unheld, "quoted lines no test compares with the command's:\n" + "\n".join(unheld)
    for doc, start in (*held, *NOT_YET_HELD, *HISTORY):
        assert any(_listed(d, q, {(doc, start)}) for d, q in found), (
            f"{doc} quotes no line that begins {start!r} (listed in this test)"
        )
    for (doc, start), test in QUOTED_ELSEWHERE.items():
        file, name = test.split("::")
        source = (ROOT / file).read_text(encoding="utf-8")
        body = source.split(f"\ndef {name}(", 1)[-1].split("\ndef ", 1)[0]
        called = "".join(f'assert_quoted("{doc}", "{start}"'.split())
        # a start too long for a line is two literals side by side: ``"a " "b"`` is ``"a b"``
        assert called in "".join(body.split()).replace('""', ""), (
            f"{test} does not hold {doc}'s `{start}...` (assert_quoted)"
        )


#: Quotes of what the program printed before (an older release, or before a fix), by page
#: and how they begin (tests/quoted.py's ``begins``), each with the words of the page that
#: say so just before it (:data:`HISTORY_WITHIN`): a reader is not to take them for today's
#: output, and no test runs them. A quote said both as history and as today's line (the
#: same words) is held too; one quoted only as history needs its words at each place.
HISTORY: dict[tuple[str, str], tuple[str, ...]] = {
    # a stop the robot did not hear, before it was checked against the stream (session 24),
    # and the tester's relay, its host-to-robot wire cut; a stop written after the watchdog
    # had tripped
    ("docs/runtime.md", "outcome SUCCESS$"): (
        "unchecked, the run ended",
        "wire cut at 6 s) it was",
    ),
    ("docs/runtime.md", "final mode Passive$"): (
        "unchecked, the run ended",
        "wire cut at 6 s) it was",
        "it said `sent` and",
    ),
    ("docs/runtime.md", "safe stop sent ...$"): ("unchecked, the run ended",),
    ("docs/runtime.md", "safe stop sent pause_resume_stream, start$"): ("wire cut at 6 s) it was",),
    ("docs/runtime.md", "roomba-bt: ...$"): ("before, `run` and `replay` said",),
    ("docs/runtime.md", "roomba-bt: interrupted by SIGTERM$"): ("it was 130,",),
    ("docs/runtime.md", "replay: first difference ...$"): ("Before, each of these was",),
    # a false baud change over RFC 2217 (session 24)
    ("docs/reliability.md", "safe stop sent pause_resume_stream, start$"): ("its summary said",),
    ("docs/reliability.md", "final mode Passive$"): ("its summary said",),
    ("docs/reliability.md", "stalls 11 (watchdog drive 0)"): ("while the summary said",),
    ("docs/plugins.md", "roomba-bt: interrupted$"): ("where it said",),
    # the rfc2217 pulses that each tripped the watchdog; a replay of a cut record
    ("docs/runtime.md", "stalls 12"): ("each pulse tripped the watchdog:",),
    ("docs/runtime.md", "safe stop NOT DELIVERED$"): ("heard nothing past the cut and said",),
    # a plugin's import error, said before as a warning
    ("docs/plugins.md", "roomba-bt: warning:$"): ("0.1.0 said them as",),
}


def test_each_quote_of_history_is_said_to_be_history() -> None:
    """Each quote :data:`HISTORY` lists has its marker just before it on its page, at one
    place at least (every place, where no test holds it as today's line: the meta-test
    above)."""
    for (doc, start), markers in HISTORY.items():
        listed = [q for q in quotes(doc) if begins(q, start)]
        assert listed, f"{doc} quotes no line that begins {start!r} (HISTORY)"
        for quote in listed:
            said, _ = history_said(doc, quote)
            assert said, f"{doc}: `{quote}` is not said to be history ({markers} before it)"


#: The pages written for the project's own people, which keep its history by session: the
#: layers' map, the measurements' log, the release procedure. Every other page is a user's.
PROJECT_PAGES = frozenset({"architecture.md", "performance.md", "releasing.md"})


def test_the_user_pages_speak_in_releases_not_sessions() -> None:
    """A user knows releases, not the project's working sessions: "since session 38" told a
    reader nothing (docs/routines.md said it 72 times until a helper reworded it, after
    every other page had been). History on a user page is "in 0.1.0" or "since 0.2.0"."""
    said = [
        f"{page.relative_to(ROOT)}:{number}: {line.strip()}"
        for page in DOCS
        if page.name not in PROJECT_PAGES
        for number, line in enumerate(page.read_text(encoding="utf-8").splitlines(), 1)
        if re.search(r"\bsessions? \d", line, re.IGNORECASE)
    ]
    assert not said, "\n".join(said)


#: The quotes no test holds yet, by page and how they begin (``kind:NAME``: every quote of
#: that kind on the page), each with why: sessions 40 and 41 held the rest, and these are
#: what is left, said here so that none is skipped unsaid.
NOT_YET_HELD: dict[tuple[str, str], str] = {
    ("docs/ci.md", "missions/common/lib/escapes.yaml:12:52:"): "the output block of a "
    "four-mission repository (dock-home.yaml, hallway-patrol.yaml, includes at line 5) that "
    "tests/mission/team_repo.py is not; missions.md's quote of the same chain is held on "
    "team_repo's",
    ("docs/evaluation.md", "key "): "wall-ahead.yaml's keys over 20 apartment episodes; "
    "its command runs (2 episodes), whose key lines say fewer values",
    ("docs/monitor.md", "forced by the operator: no bump to SUCCESS"): "one force released; "
    "tests/monitor/test_session.py's run forces two, and its line holds both",
    ("docs/monitor.md", "paused 4 min without keep-awake"): "the sleep's warning 4 minutes "
    "into a pause; tests/monitor/test_session.py makes it at 1.5 s (its limits patched), "
    "said in seconds",
    ("docs/monitor.md", "monitor: run1.jsonl: replay diverged"): "a record of an older "
    "roomba-bt that diverges on a Motors; tests/monitor/test_cli.py's diverges on another "
    "mission's Drive",
    ("docs/plugins.md", "roomba-bt: interrupted while importing plugin 'slow'"): "a Ctrl-C in "
    "an installed package's import (named with its distribution); "
    "tests/runtime/test_what_a_plugin_raises.py holds a plugin file's",
    ("docs/plugins.md", "m.yaml:5:7: unknown node 'u_metres'"): "a package installed with "
    "its distribution's name; tests/behaviours/test_plugin_errors.py loads the entry point "
    "without one",
    ("docs/plugins.md", "lab.yaml:14:7: unknown node 'wall_follow_for'"): "the record's "
    "mission at its line; tests/runtime/test_recording.py's is far.yaml's far_s29 (its other "
    "two lines are held there)",
    ("docs/reliability.md", "falls the robot fell to Passive by itself once (unknown)"): "a "
    "wheel command's lost byte; tests/runtime/test_unheard_commands.py's is the stream "
    "request's",
    ("docs/routines.md", "outcome SUCCESS"): "the outcome of a routine's run: minutes of "
    "mission time each",
    ("docs/runtime.md", "roomba-bt: the run's record, monitor and port are being closed"): (
        "a signal while the run's record, monitor and port are closed: no test sends one there"
    ),
    ("docs/runtime.md", "safe stop NOT DELIVERED: ... the safe stop's wait"): "a link whose "
    "clock stands still; tests/robot/test_undelivered_stop.py holds the connection's report, "
    "not a run's summary",
    ("docs/runtime.md", "r.jsonl: replaying /old/venv/"): "a record whose installation is "
    "still on the machine, another roomba-bt's",
    ("docs/runtime.md", "ticks 90 (21 overruns"): "a wall-clock run's overruns; "
    "tests/runtime/test_tick_watch.py's run is --fast's, whose ticks line says host time",
    ("docs/runtime.md", "replay: first difference at mission time 5.025 s"): "a shipped "
    "library changed by an upgrade (its drive at 150 mm/s); tests/runtime/test_recording.py "
    "holds the line that names the library",
}


#: docs/evaluation.md's pandas example that reads the A/B records of the ``eval`` command
#: above it (pandas is no dependency, nor installed for these tests: its own lines are run
#: alone, on the records that command writes)
PANDAS_AB = ("docs/evaluation.md", "dock-ab.jsonl")


def test_the_pandas_a_b_example_names_the_variants_its_eval_wrote(
    scratch: Callable[..., Path], capsys: pytest.CaptureFixture[str]
) -> None:
    """Its ``df.mission.map(...)`` gives each row the name its ``paired[...]`` indexes by.
    The column holds the mission as given, ``roomba-bt:dock.yaml`` for a shipped one named
    alone (as the page's command names both): ``Path(m).stem`` made that
    ``roomba-bt:dock``, and ``paired["dock-builtin"]`` a KeyError (session 39's stranger)."""
    import ast
    import json

    doc, records = PANDAS_AB
    workdir = scratch(doc)
    [block] = [b for b in blocks() if b.doc == doc and b.lang == "python" and records in b.text]
    tree = ast.parse(block.text)
    [mapper] = [
        node.args[0]
        for node in ast.walk(tree)
        if isinstance(node, ast.Call) and ast.unparse(node.func) == "df.mission.map"
    ]
    indexed = {
        node.slice.value
        for node in ast.walk(tree)
        if isinstance(node, ast.Subscript)
        and ast.unparse(node.value) == "paired"
        and isinstance(node.slice, ast.Constant)
    }
    [command] = [c for _, c in COMMANDS if f"--out {records}" in c and c.split()[1] == "eval"]
    assert main(fast_variant(command)[1:]) == 0, capsys.readouterr()
    name_of = eval(compile(ast.Expression(mapper), f"{doc}:{block.line}", "eval"), {"Path": Path})
    written = (workdir / records).read_text(encoding="utf-8").splitlines()
    names = {name_of(json.loads(row)["mission"]) for row in written}
    assert len(indexed) == 2 and indexed <= names, (
        f"{doc}:{block.line}: indexes {sorted(indexed)}; the rows map to {sorted(names)}"
    )


@pytest.mark.parametrize(("where", "file", "text"), WORLDS, ids=[w[0] for w in WORLDS])
def test_every_world_in_the_docs_loads(where: str, file: str, text: str) -> None:
    from roomba_bt.sim import parse_world

    parse_world(text, file)  # WorldError (its problems) if the docs' world does not load


#: a word of a command that needs one of pyproject.toml's extras (the ``extra`` mark of
#: tests/conftest.py: skipped where it is not installed, failed under CI=true)
NEEDS_EXTRA = {"--plot": "plot", "--monitor": "monitor", "--engine dask": "cluster"}
#: words of a command that needs the example plugin installed (`make test` installs it)
NEEDS_PLUGIN = ("dirt_detect", "plugins/roomba-bt-dirt/")
PLUGIN_INSTALLED = pytest.mark.skipif(
    importlib.util.find_spec("roomba_bt_dirt") is None,
    reason="needs the example plugin installed: pip install -e plugins/roomba-bt-dirt",
)


def needs(command: str) -> list[pytest.MarkDecorator]:
    """What a command needs beyond roomba-bt itself, as marks of its case."""
    marks = [pytest.mark.extra(extra) for word, extra in NEEDS_EXTRA.items() if word in command]
    if any(word in command for word in NEEDS_PLUGIN):
        marks.append(PLUGIN_INSTALLED)
    return marks


RUN = [
    pytest.param(w, c, marks=needs(c), id=w)
    for w, c in COMMANDS
    if c not in NOT_RUN and not c.startswith("make test")
]


#: What a command's output must not say, by a word of the command: the docs' own world
#: (docs/simulator.md, my-flat.yaml) fences its stairs, so the docs' eval in it sees no fall
#: (its one virtual wall left the landing open from the north: a fall in every episode).
NOT_SAID = {"my-flat.yaml": "fell to Passive by itself"}


#: (exit code, stdout, stderr) of each whole command line run so far, by its argv as run, the
#: kind of directory and the files of its page where it names one: a line the docs give again
#: (the same argv, in a scratch directory of the same files) ran the same way, and is not
#: run twice (the module's docstring).
RAN: dict[tuple[object, ...], tuple[int, str, str]] = {}


#: Each episode a docs ``eval`` ran in this session, by its spec made self-contained (the
#: mission's and its files' texts, the world's) and the wall-clock limit it ran under: the
#: docs run the same episode from several command lines (docs/routines.md's seed 0 in the
#: living room from four tables, again with ``--out``; evaluation.md's dock on seeds 1 and 2
#: beside ``dock-builtin``), each of which cost a 21-minute clean again, up to 10 s of CPU.
#: "Same spec, same result" (:class:`~roomba_bt.evaluate.EpisodeSpec`): a command line that
#: meets one again gets its result as its pool would have given it; the rest of the command
#: (its arguments, the sweep, the summary, ``--out``) runs as written.
EPISODES: dict[tuple[object, float | None], Any] = {}


def _each_episode_once(original: Callable[..., list[Any]]) -> Callable[..., list[Any]]:
    """``parallel.run_episodes`` that runs only the specs not in :data:`EPISODES` (through
    ``original``, its pool, its wall-clock limit) and keeps what they gave; a stuck or dead
    worker's result (HUNG, DIED: the machine's, not the spec's) is not kept."""
    from roomba_bt.evaluate.episode import DIED, HUNG, self_contained
    from roomba_bt.evaluate.parallel import LocalRun

    def run_episodes(
        specs: list[Any],
        jobs: int = 1,
        progress: Callable[[int, int, Any], None] | None = None,
        run: LocalRun | None = None,
        wall_limit_s: float | None = None,
    ) -> list[Any]:
        run = run if run is not None else LocalRun()
        keys = [(self_contained(spec), wall_limit_s) for spec in specs]
        new = [i for i, key in enumerate(keys) if key not in EPISODES]
        for i, key in enumerate(keys):
            if i not in new:
                run.results[i] = EPISODES[key]
                if progress is not None:
                    progress(len(run.results), len(specs), run.results[i])
        seen = len(run.results)

        def said(done: int, total: int, result: Any) -> None:
            if progress is not None:
                progress(seen + done, len(specs), result)

        ran = LocalRun()
        try:
            if new:
                original([specs[i] for i in new], jobs, said, ran, wall_limit_s)
        finally:  # what finished before a Ctrl-C is the caller's too, as the pool's
            run.retried += ran.retried
            for j, result in ran.results.items():
                run.results[new[j]] = result
                if result.outcome not in (HUNG, DIED):
                    EPISODES[keys[new[j]]] = result
        return run.in_order()

    return run_episodes


@pytest.fixture
def episodes_once(monkeypatch: pytest.MonkeyPatch) -> None:
    """:func:`_each_episode_once` in place of the local pool's ``run_episodes``."""
    from roomba_bt.evaluate import parallel

    monkeypatch.setattr(parallel, "run_episodes", _each_episode_once(parallel.run_episodes))


def test_the_wheel_s_user_has_no_checkout(scratch: Callable[..., Path]) -> None:
    """The folder a wheel's user runs a page's commands in holds what the page writes and no
    more: a command naming ``missions/dock.yaml`` fails there, as it does for such a user."""
    workdir = scratch("README.md")
    assert not (workdir / "missions").exists() and not (workdir / "worlds").exists()
    assert sorted(p.name for p in workdir.iterdir()) == sorted(
        f for f, _ in page_files("README.md")
    )
    assert main(["validate", "missions/dock.yaml"]) == 2


@pytest.mark.parametrize(("where", "command"), RUN)
def test_every_command_in_the_docs_runs(
    where: str,
    command: str,
    scratch: Callable[..., Path],
    capsys: pytest.CaptureFixture[str],
    served_sim: Callable[..., Any],
    episodes_once: None,
) -> None:
    checkout = command in CHECKOUT
    workdir = scratch(doc_of(where), checkout=checkout)
    for part in command.split(" && "):
        redirect = None
        if " > " in part:
            part, redirect = part.split(" > ")
        argv = fast_variant(part)
        expanded = [w for word in argv for w in (sorted(glob.glob(word)) or [word])]
        assert expanded[0] == "roomba-bt", f"{where}: {part}"
        if part == command:  # the whole line: it needs no file an earlier part wrote
            files = page_files(doc_of(where))
            named = any(f in word for word in expanded for f, _ in files)
            key = (checkout, tuple(files) if named else (), *expanded)
            code, out, err = RAN.get(key) or _run(expanded, capsys, served_sim)
            RAN[key] = code, out, err
        else:
            code, out, err = _run(expanded, capsys, served_sim)
        assert code == 0, f"{where}: {' '.join(expanded)} exited {code}\n{out}\n{err}"
        for word, unsaid in NOT_SAID.items():
            assert word not in part or unsaid not in out, f"{where}: {part} said {unsaid!r}\n{out}"
        if redirect is not None:
            (workdir / redirect).write_text(out)
            assert out.strip(), f"{where}: {part} wrote nothing to {redirect}"


def _run(
    argv: list[str], capsys: pytest.CaptureFixture[str], served_sim: Callable[..., Any]
) -> tuple[int, str, str]:
    """``roomba-bt ...`` (``argv`` as rewritten): its exit code, stdout and stderr."""
    if argv[1] == "doctor":
        return _doctor_on_a_simulator(argv, served_sim)
    if argv[1] == "sim":  # serves until stopped: its own process
        done = finished([sys.executable, "-m", "roomba_bt.cli", *argv[1:]])
        return done.returncode, done.stdout, done.stderr
    code = main(argv[1:])
    out, err = capsys.readouterr()
    return code, out, err


#: The robot the docs' ``doctor`` commands find, ``roomba-bt sim`` with these options: asleep,
#: at 19200, behind RFC 2217 (the endpoint that carries the BRC pulse), so every step up to the
#: wake is taken.
DOCTOR_SIM = ("--rfc2217", "127.0.0.1:0", "--asleep", "--baud", "19200")


def _doctor_on_a_simulator(argv: list[str], served_sim: Callable[..., Any]) -> tuple[int, str, str]:
    """``roomba-bt doctor`` (its ``--port`` already dropped) against :data:`DOCTOR_SIM`. Each
    waits only for its event: the simulator's address printed, doctor's end, the
    simulator's end once told (a ceiling that stops a hung one, no fixed bet)."""
    sim = served_sim(*DOCTOR_SIM)
    assert sim.address, f"the simulator printed no address: {sim.stop()}"
    try:
        done = finished([sys.executable, "-m", "roomba_bt.cli", *argv[1:], "--port", sim.address])
        assert "found: " in done.stdout, done.stdout
        return done.returncode, done.stdout, done.stderr
    finally:
        sim.stop()


#: docs/doctor.md's transcripts: a ``text`` block whose first line is ``$ roomba-bt doctor
#: ...``, of the simulator its paragraph names (the last ``roomba-bt sim ...`` in backquotes
#: since the block before). Each is run against that simulator, served here, and must print
#: what the page shows (session 39's stranger found the ``setting`` step, which doctor prints
#: after ``profile``, in none of them).
DOCTOR_DOC = "docs/doctor.md"
#: the steps whose lines are measured on the wall clock (frames counted in 0.5 s, the
#: intervals between reads): compared by their step alone, not their words or verdict
MEASURED_STEPS = ("stream", "timing")


def transcripts() -> list[tuple[str, list[str], list[str], list[str]]]:
    """(where, the simulator's argv, doctor's argv, the lines shown) of each transcript."""
    text = (ROOT / DOCTOR_DOC).read_text(encoding="utf-8")
    found = []
    for match in re.finditer(
        r"^```text\n\$ (roomba-bt doctor [^\n]*)\n(.*?)^```", text, re.M | re.S
    ):
        before = text[: match.start()].rsplit("```", 1)[-1]
        sims = re.findall(r"`(roomba-bt sim [^`]*)`", before)
        where = f"{DOCTOR_DOC}:{text.count(chr(10), 0, match.start()) + 1}"
        assert sims, f"{where}: the transcript's paragraph names no `roomba-bt sim ...`"
        sim = shlex.split(" ".join(sims[-1].split()))[2:]
        for option in ("--tcp", "--rfc2217"):  # a free port, as the docs' sim commands get
            if option in sim:
                i = sim.index(option) + 1
                sim[i] = sim[i].rsplit(":", 1)[0] + ":0"
        found.append((where, sim, shlex.split(match[1]), match[2].splitlines()))
    return found


def _same_line(shown: str, printed: str) -> bool:
    step = re.match(r"\[(?:ok|--|warn|FAIL)\]\s+(\w+)", shown)
    if step and step[1] in MEASURED_STEPS:
        return re.match(rf"\[(?:ok|--|warn|FAIL)\]\s+{step[1]}\b", printed) is not None
    return shown == printed


TRANSCRIPTS = transcripts()


def test_the_doctor_page_holds_its_transcripts() -> None:
    assert len(TRANSCRIPTS) >= 4


@pytest.mark.parametrize(
    ("where", "sim_args", "argv", "shown"), TRANSCRIPTS, ids=[t[0] for t in TRANSCRIPTS]
)
def test_each_doctor_transcript_is_what_doctor_prints(
    where: str,
    sim_args: list[str],
    argv: list[str],
    shown: list[str],
    served_sim: Callable[..., Any],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Line for line, the port the page shows being the served one's; a ``...`` line stands
    for the lines it leaves out."""
    monkeypatch.delenv("ROOMBA_BT_PROFILE", raising=False)  # the `setting` step reads it
    sim = served_sim(*sim_args)
    assert sim.address, f"the simulator printed no address: {sim.stop()}"
    try:
        port = argv[argv.index("--port") + 1]
        command = [*argv[2:]]
        command[command.index("--port") + 1] = sim.address
        done = finished([sys.executable, "-m", "roomba_bt.cli", "doctor", *command])
    finally:
        sim.stop()
    printed = done.stdout.replace(sim.address, port)
    printed = printed.replace(sim.address.split("://")[-1], port.split("://")[-1])
    lines = printed.splitlines()
    head, elided, tail = "\n".join(shown).partition("\n...\n")
    expected_head, expected_tail = head.splitlines(), tail.splitlines()
    got = lines[: len(expected_head)] + (lines[-len(expected_tail) :] if expected_tail else [])
    shown_count = len(expected_head) + len(expected_tail)
    assert len(lines) >= shown_count if elided else len(lines) == shown_count, (
        f"{where}: the page shows {shown_count} lines, doctor printed {len(lines)}:\n{done.stdout}"
    )
    for shown_line, printed_line in zip(expected_head + expected_tail, got, strict=True):
        assert _same_line(shown_line, printed_line), (
            f"{where}: the page shows\n{shown_line}\ndoctor printed\n{printed_line}\n"
            f"(all of it:)\n{done.stdout}{done.stderr}"
        )
    assert done.returncode == (0 if lines[-1].startswith("found: ") else 5), done.stderr
