"""``eval``'s results as a team commits them: what made them, their verdict, and the same
bytes when the same episodes run again (session 29)."""

from __future__ import annotations

import csv
import hashlib
import json
from pathlib import Path

import pytest
from runtime.installed import another_installation  # tests/runtime: installations

from roomba_bt import __version__
from roomba_bt.cli import main
from roomba_bt.evaluate.records import read_results
from roomba_bt.mission.shipped import SHIPPED_DIR

MISSIONS = Path(__file__).resolve().parents[2] / "missions"
#: the shipped file itself, not the checkout's link to it (missions/bump-and-turn.yaml): an
#: sdist holds that link as a copy, a file of the user's, whose sources are not the shipped name
BUMP = str(SHIPPED_DIR / "bump-and-turn.yaml")
EVAL = [BUMP, "--runs", "3", "--seed", "3", "-p", "duration=2s", "--no-progress"]


def _eval(capsys: pytest.CaptureFixture[str], *extra: str) -> tuple[int, str]:
    code = main(["eval", *EVAL, *extra])
    return code, capsys.readouterr().out


def test_reproducible_results_are_the_same_bytes_whatever_the_jobs(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Two evaluations of the same episodes differed in every row's ``wall_time``,
    ``cpu_time`` and ``worker`` (a pid), and in the summary's engine and times: a committed
    results file changed on every run. ``--reproducible`` leaves them empty (the columns
    stay: readers rely on them), and the files read back."""
    made = []
    for jobs, out in (("1", "one"), ("2", "two")):
        code, summary = _eval(capsys, "--jobs", jobs, "--reproducible", "--json", "--out",
                              str(tmp_path / f"{out}.jsonl"))  # fmt: skip
        assert code == 0
        assert _eval(capsys, "--jobs", jobs, "--reproducible", "--out",
                     str(tmp_path / f"{out}.csv"))[0] == 0  # fmt: skip
        made.append([summary, *((tmp_path / f"{out}.{x}").read_bytes() for x in ("jsonl", "csv"))])
    assert made[0] == made[1]
    rows = [json.loads(line) for line in (tmp_path / "one.jsonl").read_text().splitlines()]
    assert {(r["wall_time"], r["cpu_time"], r["worker"]) for r in rows} == {(None, None, None)}
    summary = json.loads(made[0][0])
    assert summary["engine"] is None and summary["variants"][0]["wall_time"] is None
    assert len(read_results(tmp_path / "one.jsonl")) == len(read_results(tmp_path / "two.csv")) == 3
    code, text = _eval(capsys, "--reproducible")
    assert code == 0 and "CPU time" not in text and "engine" not in text
    code, text = _eval(capsys)  # without: the times, as before
    assert "CPU time" in text and "engine       1 local process" in text


def test_a_shipped_mission_named_alone_is_named_the_same_in_every_installation(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """``eval dock --reproducible`` wrote the shipped file's site-packages path into every
    row's ``mission``, the summary and ``--json``: two venvs with the same wheel wrote
    different files. A shipped mission named alone is named by its shipped name, as a
    record and the rows' ``sources`` name it."""
    monkeypatch.chdir(tmp_path)  # no file called bump-and-turn here: the shipped one
    made = []
    for venv in ("one", "two"):
        out = tmp_path / f"{venv}.jsonl"
        with monkeypatch.context() as patched:
            another_installation(patched, tmp_path / venv)
            argv = ["eval", "bump-and-turn", *EVAL[1:], "--reproducible"]
            assert main([*argv, "--out", str(out)]) == 0
            text = capsys.readouterr().out
            assert main([*argv, "--json"]) == 0
            summary = json.loads(capsys.readouterr().out)
        made.append((text, summary, out.read_bytes()))
    assert made[0] == made[1]
    text, summary, rows = made[0]
    name = "roomba-bt:bump-and-turn.yaml"
    assert f"mission      {name} in empty-room" in text
    assert summary["variants"][0]["mission"] == name
    assert {json.loads(row)["mission"] for row in rows.splitlines()} == {name}


def test_results_say_what_made_them_and_the_json_its_verdict(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The ``--out`` rows had no roomba-bt version, no digest of the mission's files or of
    the world, no plugin; ``--json`` had no plugin versions, nor the ``--min-rate`` it was
    judged against, nor whether it passed."""
    out = tmp_path / "results.jsonl"
    code, text = _eval(capsys, "--min-rate", "50%", "--json", "--out", str(out))
    assert code == 0
    digest = hashlib.sha256(Path(BUMP).read_bytes()).hexdigest()
    row = json.loads(out.read_text().splitlines()[0])
    assert row["roomba_bt_version"] == __version__
    assert next(iter(row["sources"].items())) == ("roomba-bt:bump-and-turn.yaml", digest)
    assert "roomba-bt:lib/undock.yaml" in row["sources"]  # its library too
    assert row["plugins"] == {}
    world = MISSIONS.parent / "worlds" / "empty-room.yaml"
    if not world.is_file():  # the shipped worlds' folder, wherever the package keeps it
        from roomba_bt.sim.world import WORLDS_DIR

        world = WORLDS_DIR / "empty-room.yaml"
    assert row["world_sha256"] == hashlib.sha256(world.read_bytes()).hexdigest()
    summary = json.loads(text)
    assert summary["conditions"]["min_rate"] == 0.5 and summary["passed"] is True
    assert summary["conditions"]["world_sha256"] == row["world_sha256"]
    assert summary["plugins"] == {} and summary["variants"][0]["passed"] is True
    assert summary["variants"][0]["sources"] == row["sources"]
    code, text = _eval(
        capsys, "--min-rate", "100%", "-p", "duration=1h", "--timeout", "3s", "--json"
    )
    assert code == 1 and json.loads(text)["passed"] is False
    code, text = _eval(capsys, "--json")
    assert code == 0 and json.loads(text)["passed"] is None
    table = tmp_path / "results.csv"
    assert _eval(capsys, "--out", str(table))[0] == 0
    with table.open(newline="") as rows:
        first = next(csv.DictReader(rows))
    assert first["sources"].startswith(f"roomba-bt:bump-and-turn.yaml={digest};")
    assert first["roomba_bt_version"] == __version__
