"""docs/missions.md documents every word of the language and every built-in behaviour."""

from __future__ import annotations

from pathlib import Path

from roomba_bt.behaviours.actions import ACTIONS
from roomba_bt.behaviours.cleaning import CLEANING
from roomba_bt.behaviours.conditions import CONDITIONS
from roomba_bt.behaviours.coverage_map import COVERAGE
from roomba_bt.behaviours.homing import HOMING
from roomba_bt.behaviours.language import MODIFIERS, WORDS, Shape
from roomba_bt.behaviours.wall import WALL_FOLLOWING
from roomba_bt.mission.loader import TOP_LEVEL

DOC = (Path(__file__).resolve().parents[2] / "docs" / "missions.md").read_text(encoding="utf-8")


def test_every_language_word_is_documented() -> None:
    for word in (*WORDS, *MODIFIERS, *TOP_LEVEL):
        assert f"`{word}" in DOC, word


def test_every_builtin_behaviour_and_parameter_is_documented() -> None:
    for cls in (*ACTIONS, *CONDITIONS, *CLEANING, *COVERAGE, *HOMING, *WALL_FOLLOWING):
        decl = cls.declaration
        assert f"**`{decl.name}`**" in DOC, decl.name
        for param in decl.params:
            assert f"| `{param.name}` |" in DOC, f"{decl.name}.{param.name}"


def test_every_option_of_every_word_is_documented_in_its_row() -> None:
    """The composite and decorator tables of docs/missions.md against the language table."""
    rows = {
        line.split("|")[1].strip(): line
        for line in DOC.split("### Composites")[1].split("### Subtrees")[0].splitlines()
        if line.startswith("| `") and line.count("|") >= 4
    }
    for kind in WORDS.values():
        if kind.shape is Shape.SUBTREE:
            continue
        row = next((r for key, r in rows.items() if f"`{kind.word}`" in key), None)
        assert row is not None, f"docs/missions.md has no table row for {kind.word}"
        if kind.shape is Shape.CHILDREN:
            continue  # composite options are shown once, in the long-form example
        for option in kind.options:
            assert f"`{option.name}`" in row, f"{kind.word}.{option.name}"
    for kind in WORDS.values():
        if kind.shape is Shape.CHILDREN:
            for option in kind.options:
                assert f"  {option.name}:" in DOC, f"{kind.word}.{option.name}"


def test_every_sensor_packet_a_comparison_takes_is_listed_with_its_range() -> None:
    """``sensor: cliff_left == 0`` in a shipped mission used a name no page listed: the
    table under Comparisons has every packet, its range on each model."""
    from roomba_bt.oi.packets import PACKETS
    from roomba_bt.oi.profiles import PROFILES

    table = DOC.split("### Comparisons")[1].split("\n## ")[0]
    for pid, spec in PACKETS.items():
        [row] = [r for r in table.splitlines() if r.startswith(f"| {pid} | `{spec.name}` |")]
        for profile in PROFILES.values():
            bounds = profile.packet(pid)
            assert f"{bounds.minimum}..{bounds.maximum}" in row, (spec.name, profile.name)
