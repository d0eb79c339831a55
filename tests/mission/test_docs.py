"""docs/missions.md documents every word of the language and every built-in behaviour."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from roomba_bt.behaviours.actions import ACTIONS
from roomba_bt.behaviours.cleaning import CLEANING
from roomba_bt.behaviours.conditions import CONDITIONS
from roomba_bt.behaviours.coverage_map import COVERAGE
from roomba_bt.behaviours.homing import HOMING
from roomba_bt.behaviours.language import MODIFIERS, WORDS, Shape
from roomba_bt.behaviours.panel import PANEL
from roomba_bt.behaviours.reference import entry_text, param_row
from roomba_bt.behaviours.wall import WALL_FOLLOWING
from roomba_bt.mission.loader import TOP_LEVEL

DOC = (Path(__file__).resolve().parents[2] / "docs" / "missions.md").read_text(encoding="utf-8")


def test_every_language_word_is_documented() -> None:
    for word in (*WORDS, *MODIFIERS, *TOP_LEVEL):
        assert f"`{word}" in DOC, word


def test_every_builtin_behaviour_and_parameter_is_documented() -> None:
    for cls in (*ACTIONS, *PANEL, *CONDITIONS, *CLEANING, *COVERAGE, *HOMING, *WALL_FOLLOWING):
        decl = cls.declaration
        assert f"**`{decl.name}`**" in DOC, decl.name
        for param in decl.params:
            assert f"| `{param.name}` |" in DOC, f"{decl.name}.{param.name}"


def _param_rows(name: str) -> dict[str, tuple[str, str, str]]:
    """The type, range and default columns of behaviour ``name``'s parameter table in the
    docs."""
    found = re.search(rf"^\*\*`{name}`\*\*.*?(?=^\*\*`|^#)", DOC, re.S | re.M)
    assert found is not None, f"docs/missions.md has no section for {name}"
    rows = re.findall(r"^\| `(\w+)` \| ([^|]*)\| ([^|]*)\| ([^|]*)\|", found.group(0), re.M)
    return {
        param: (kind.strip(), span.strip(), default.strip()) for param, kind, span, default in rows
    }


@pytest.mark.parametrize(
    "cls",
    [*ACTIONS, *PANEL, *CONDITIONS, *CLEANING, *COVERAGE, *HOMING, *WALL_FOLLOWING],
    ids=lambda cls: cls.declaration.name,
)
def test_every_parameters_type_range_and_default_in_the_docs_is_the_declarations(
    cls: type,
) -> None:
    """The tables are checked against the declarations, by the function ``roomba-bt
    behaviours --markdown`` prints them with: a default changed in the code and not in the
    docs (cover's turn_speed read 200 mm/s, declared 300) fails."""
    rows = _param_rows(cls.declaration.name)
    for param in cls.declaration.params:
        _, kind, span, default, _ = param_row(param)
        assert rows[param.name] == (kind, span, default), f"{cls.declaration.name}.{param.name}"


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


def test_the_runtime_packets_the_docs_list_are_the_constants() -> None:
    """The docs listed battery 25-26 among ``RUNTIME_PACKETS``, which has not got them (the
    bandwidth error prints the constant: the reader saw two lists)."""
    from roomba_bt.mission import RUNTIME_PACKETS

    found = re.search(r"`roomba_bt\.mission\.RUNTIME_PACKETS`: ([^)]*)\)", DOC)
    assert found is not None
    listed: set[int] = set()
    for low, high in re.findall(r"(\d+)(?:-(\d+))?", found.group(1)):
        listed.update(range(int(low), int(high or low) + 1))
    assert listed == set(RUNTIME_PACKETS)


def test_every_value_type_is_in_the_values_table() -> None:
    """``radius`` (a parameter and blackboard type, in the schema) was missing."""
    from roomba_bt.behaviours.units import VALUE_TYPES

    table = DOC.split("## Values")[1].split("\n#")[0]
    rows = {row.split("|")[1] for row in table.splitlines() if row.startswith("| `")}
    written = " ".join(rows)
    for name in VALUE_TYPES:
        assert f"`{name}`" in written, name


def _entry(name: str) -> str:
    """A behaviour's text in docs/missions.md, ``**`name`**: text  `` up to its line break."""
    found = re.search(rf"^\*\*`{name}`\*\*: (.*?)  $", DOC, re.M)
    assert found is not None, f"docs/missions.md has no entry for {name}"
    return found.group(1)


@pytest.mark.parametrize(
    "cls",
    [*ACTIONS, *PANEL, *CONDITIONS, *CLEANING, *COVERAGE, *HOMING, *WALL_FOLLOWING],
    ids=lambda cls: cls.declaration.name,
)
def test_every_behaviours_text_in_the_docs_starts_with_its_declaration(cls: type) -> None:
    """Each entry starts with the declaration's text, word for word, as ``roomba-bt behaviours
    --markdown`` prints it (the docs may say more after it). ``cover``, ``home_by_map`` and
    ``spiral`` read differently in the two; only the parameter tables were compared."""
    assert _entry(cls.declaration.name).replace("``", "`").startswith(entry_text(cls.declaration))


@pytest.mark.parametrize(
    "cls",
    [*ACTIONS, *PANEL, *CONDITIONS, *CLEANING, *COVERAGE, *HOMING, *WALL_FOLLOWING],
    ids=lambda cls: cls.declaration.name,
)
def test_every_parameters_text_in_the_docs_is_its_declarations(cls: type) -> None:
    found = re.search(rf"^\*\*`{cls.declaration.name}`\*\*.*?(?=^\*\*`|^#)", DOC, re.S | re.M)
    assert found is not None
    rows = dict(re.findall(r"^\| `(\w+)` \| [^|]*\|[^|]*\|[^|]*\| (.*) \|$", found.group(0), re.M))
    for param in cls.declaration.params:
        said = rows.get(param.name, "").strip().replace("`", "")
        meaning = param_row(param)[-1]
        assert said == meaning.replace("`", ""), f"{cls.declaration.name}.{param.name}"
