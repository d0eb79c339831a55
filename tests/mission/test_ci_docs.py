"""docs/ci.md's pre-commit hook and GitHub Actions step, run as written.

A lab team's hook validated only the staged files (pre-commit's ``pass_filenames``): renaming
a subtree in the shared library passed it and broke the missions that use the subtree. The
page recommends a hook that validates every mission; this test takes the hook's ``entry`` and
the job's ``validate`` step from the page's YAML, runs them as pre-commit and a GitHub runner
would (the entry split as a command line, with no file names appended; the step under
``bash -e``) in a team's repository, with ``roomba-bt`` this checkout, and sees them pass on
the clean repository and fail, naming the broken missions, once only the library changed.
"""

from __future__ import annotations

import os
import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
import yaml
from team_repo import ESCAPES, team_repo  # beside this file
from waits import HANG_S  # tests/waits.py: a hang's bound

ROOT = Path(__file__).resolve().parents[2]
CI_DOC = ROOT / "docs" / "ci.md"


def yaml_blocks() -> list[dict]:
    text = CI_DOC.read_text(encoding="utf-8")
    return [yaml.safe_load(m[1]) for m in re.finditer(r"^```yaml\n(.*?)^```", text, re.M | re.S)]


def precommit_hook() -> dict:
    [config] = [block for block in yaml_blocks() if "repos" in block]
    [hook] = [h for repo in config["repos"] for h in repo["hooks"] if "roomba-bt" in h["entry"]]
    return hook


def validate_step() -> str:
    [workflow] = [block for block in yaml_blocks() if "jobs" in block]
    steps = workflow["jobs"]["validate"]["steps"]
    [step] = [s for s in steps if s.get("name") == "validate every mission"]
    return step["run"]


@pytest.fixture
def repo(tmp_path: Path) -> Path:
    """A team's repository in git, its library whole; ``roomba-bt`` on the PATH is this
    checkout's."""
    root = tmp_path / "repo"
    root.mkdir()
    team_repo(root)
    (root / "missions/common/lib/escapes.yaml").write_text(ESCAPES.replace("parsecs", "cm"))
    subprocess.run(["git", "init", "-q"], cwd=root, check=True, timeout=HANG_S)
    subprocess.run(["git", "add", "."], cwd=root, check=True, timeout=HANG_S)
    bin_dir = tmp_path / "bin"
    bin_dir.mkdir()
    shim = bin_dir / "roomba-bt"
    shim.write_text(f'#!/bin/sh\nexec "{sys.executable}" -m roomba_bt "$@"\n')
    shim.chmod(0o755)
    return root


def run_in(repo: Path, argv: list[str]) -> subprocess.CompletedProcess[str]:
    env = dict(os.environ)
    env["PATH"] = f"{repo.parent / 'bin'}{os.pathsep}{env['PATH']}"
    env["PYTHONPATH"] = str(ROOT)
    return subprocess.run(argv, cwd=repo, env=env, capture_output=True, text=True, timeout=HANG_S)


def break_the_library(repo: Path) -> None:
    """Rename a subtree in the library alone, as a commit that stages only the library does:
    ``safe_drive.yaml`` and ``square.yaml`` still use the old name."""
    library = repo / "missions/common/lib/escapes.yaml"
    library.write_text(library.read_text().replace("escape_bump:", "escape_on_bump:"))
    subprocess.run(
        ["git", "add", "missions/common/lib/escapes.yaml"], cwd=repo, check=True, timeout=HANG_S
    )


def test_the_hook_validates_every_mission_and_names_those_a_library_change_breaks(
    repo: Path,
) -> None:
    hook = precommit_hook()
    assert hook["pass_filenames"] is False  # the point of the page: no file names passed
    argv = shlex.split(hook["entry"])  # as pre-commit runs a hook: no shell, no file names
    clean = run_in(repo, argv)
    assert clean.returncode == 0, clean.stdout + clean.stderr
    assert clean.stdout == ""  # -q: the files that passed are not listed
    break_the_library(repo)
    broken = run_in(repo, argv)
    assert broken.returncode == 2, broken.stdout + broken.stderr
    failed = [
        line.split(": failed")[0] for line in broken.stdout.splitlines() if ": failed" in line
    ]
    assert failed == [
        "missions/common/lib/safe_drive.yaml",
        "missions/delivery/square.yaml",
        "missions/delivery/to-kitchen.yaml",
    ]


def test_the_actions_step_annotates_the_broken_missions(repo: Path) -> None:
    argv = ["bash", "-e", "-c", validate_step()]  # how a runner runs a step's run:
    clean = run_in(repo, argv)
    assert clean.returncode == 0, clean.stdout + clean.stderr
    break_the_library(repo)
    broken = run_in(repo, argv)
    assert broken.returncode == 2, broken.stdout + broken.stderr
    annotated = {
        line.split(",")[0].removeprefix("::error file=")
        for line in broken.stdout.splitlines()
        if line.startswith("::error ")
    }
    # each error at its place (safe_drive's use of the subtree, square's), and to-kitchen,
    # which fails through safe_drive, at its include line
    assert annotated == {
        "missions/common/lib/safe_drive.yaml",
        "missions/delivery/square.yaml",
        "missions/delivery/to-kitchen.yaml",
    }
    assert "::error file=missions/delivery/to-kitchen.yaml,line=2,col=11," in broken.stdout


def reverse_view_command() -> str:
    """The page's ``jq`` one-liner: which files include a library."""
    text = CI_DOC.read_text(encoding="utf-8")
    [command] = [m[1] for m in re.finditer(r"^```sh\n(.*?)^```", text, re.M | re.S) if "jq" in m[1]]
    return command


@pytest.mark.skipif(shutil.which("jq") is None, reason="the page's one-liner needs jq")
def test_the_reverse_view_lists_every_file_that_includes_the_library(repo: Path) -> None:
    """Which missions include a library (what to re-run when it changes) had no answer but
    reading every file: validate's JSON said include chains only of errors. Its
    ``includes`` answers it, through the library that includes it too, valid or not."""
    argv = ["bash", "-e", "-c", reverse_view_command()]

    def listed() -> list[str]:
        done = run_in(repo, argv)
        assert done.returncode == 0, done.stderr
        return done.stdout.splitlines()

    expected = [
        "missions/common/lib/safe_drive.yaml",
        "missions/delivery/square.yaml",
        "missions/delivery/to-kitchen.yaml",
    ]
    assert listed() == expected
    break_the_library(repo)  # the missions fail now: still listed, their includes read
    assert listed() == expected


#: a student's file name: spaces, brackets and letters git quotes (``core.quotePath``)
STUDENT = "missions/delivery/s26 Zoë Müller mission (final) v2.yaml"
#: compiles, with a warning: a drive in Full mode with no cliff check (``--strict`` fails it)
WARNED = "tree:\n  sequence:\n    - mode: full\n    - drive: {velocity: 100 mm/s, distance: 1 m}\n"


@pytest.mark.parametrize(
    ("text", "code"),
    [("tree: {mde: safe}\n", 2), (WARNED, 7)],
    ids=["an error: 2", "a warning alone: 7"],
)
def test_the_actions_step_checks_a_name_with_spaces_and_accents_as_one_file(
    text: str, code: int, repo: Path
) -> None:
    """``$(git ls-files 'missions/*.yaml')`` made "s26 Zoë Müller ... v2.yaml" six missing
    files (split at the spaces, the letters octal-escaped), and ``xargs`` would give 123 for
    an error and a warning alike: the step as written checks the file, exit 2 or 7."""
    (repo / STUDENT).write_text(text, encoding="utf-8")
    subprocess.run(["git", "add", "."], cwd=repo, check=True, timeout=HANG_S)
    done = run_in(repo, ["bash", "-e", "-c", validate_step()])
    assert done.returncode == code, done.stdout + done.stderr
    assert "no such mission file" not in done.stdout + done.stderr
    annotated = {line.split(",")[0] for line in done.stdout.splitlines() if line[:2] == "::"}
    assert annotated == {"::error file=missions/delivery/s26 Zoë Müller mission (final) v2.yaml"}
    assert done.stdout.splitlines()[-1].startswith("5 files: 4 ok, ")  # the team's 4 and it
