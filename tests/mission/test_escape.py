"""``$$`` in a mission text is one literal ``$``, anywhere (Python's ``string.Template`` rule):
``$${x}`` is the text ``${x}`` and ``$$${x}`` a ``$`` and then x's value. Before session 28 a
log line or a text parameter could not say ``${`` at all, and a ``${`` that started no
parameter (``"${speed"``) was passed on as text, so a typo in a use went unseen; and
``$${x}`` was a ``$`` and x's value, so where x is a parameter that changed meaning: a
warning at its place says so. Both ways: the escape gives the text, and every error about a
``${`` says how to write one."""

from __future__ import annotations

import logging
from collections.abc import Callable
from pathlib import Path

import pytest
from runtime.simrun import SHORT_DRIVE  # tests/runtime: the short drive

from roomba_bt.mission import CompiledMission, compile_mission, load_mission
from roomba_bt.oi.modes import OIMode
from roomba_bt.robot.testing import StubRobot

Compile = Callable[..., CompiledMission]
Errors = Callable[..., list[str]]
ESCAPE_HINT = 'a literal "${" is written "$${"'


def _logged(mission: CompiledMission, caplog: pytest.LogCaptureFixture) -> list[str]:
    """What the mission's ``log`` leaves write in one tick (each succeeds at once)."""
    robot = StubRobot(mode=OIMode.SAFE)
    mission.setup(robot)
    robot.set_frame({7: 0, 35: 2})
    with caplog.at_level(logging.INFO, logger="roomba_bt.mission"):
        mission.root.tick_once()
    return [r.message for r in caplog.records if r.name == "roomba_bt.mission"]


def test_a_doubled_dollar_writes_a_literal_opening(
    compile_text: Compile, caplog: pytest.LogCaptureFixture
) -> None:
    mission = compile_text(
        """
        mission: m
        description: "Say $${who} to ${who}"
        parameters:
          who: {type: str, default: bob}
          said: {type: str, default: "it costs $${price}"}
        tree:
          sequence:
            - log: "hello ${who}, $${who} is not replaced"
            - log: "$${who}"
            - log: "${said}"
            - log: "${said}, ${who}"
            - log: "$$${who}"
            - log: "cost $$5, $5, $$$$ and $"
        """
    )
    assert _logged(mission, caplog) == [
        "hello bob, ${who} is not replaced",
        "${who}",
        "it costs ${price}",  # an escape in a parameter's default: its value, substituted once
        "it costs ${price}, bob",
        "$bob",  # "$$" is one "$", then the value: string.Template's rule
        "cost $5, $5, $$ and $",  # "$$" is one "$" anywhere; a "$" before anything else is itself
    ]
    assert mission.description == "Say ${who} to bob"
    names = [node.name for node in mission.root.iterate()]
    assert "log(hello bob, ${who} is not replaced)" in names, names


def test_a_default_may_hold_the_escape_but_not_a_parameter(errors_of: Errors) -> None:
    """A default cannot refer to a parameter; ``$${x}`` refers to none."""
    head = "mission: m\nparameters:\n  a: {type: str, default: "
    assert errors_of(head + '"$${a}"}\ntree: {log: "${a}"}\n') == []
    (error,) = errors_of(head + '"${a}"}\ntree: {log: "${a}"}\n')
    assert "a default cannot refer to itself" in error


@pytest.mark.parametrize(
    ("value", "said"),
    [
        ('"cost ${ x"',
         "4:25: log.message: \"${\" at character 6 of 'cost ${ x' starts no parameter"),
        ('"${who"', "4:25: log.message: \"${\" at character 1 of '${who' starts no parameter"),
        ('"${who} and ${"', "of '${who} and ${' starts no parameter"),
        ('"${whoo}"', "4:25: log.message: unknown parameter ${whoo} (did you mean 'who'?)"),
        ('"hi ${whoo}"', "4:25: log.message: unknown parameter ${whoo} (did you mean 'who'?)"),
    ],
)  # fmt: skip
def test_a_stray_or_unknown_opening_is_an_error_that_names_the_escape(
    errors_of: Errors, value: str, said: str
) -> None:
    """``"${who"`` was logged as written: the closing brace forgotten went unseen."""
    errors = errors_of(
        "mission: m\nparameters:\n  who: {type: str, default: bob}\ntree: {sequence: [{log: "
        + value
        + "}]}\n"
    )
    assert len(errors) == 1, errors
    assert said in errors[0], errors
    assert errors[0].endswith(ESCAPE_HINT), errors


def test_a_stray_opening_in_a_typed_value_is_named_not_its_unit(errors_of: Errors) -> None:
    """``velocity: "${speed"`` said "expected a speed", as if the text were a number."""
    # the short drive with its velocity's closing brace left out (line 7, the drive's)
    (error,) = errors_of(SHORT_DRIVE.replace('"${speed}"', '"${speed"'))
    assert error.startswith("7:25: drive.velocity: \"${\" at character 1 of '${speed'"), error
    assert error.endswith(ESCAPE_HINT)


#: The upgrade report's mission (e80f20a logged "budget: $5 for 20cm")
BUDGET = """
mission: m
description: "costs $${price}"
parameters:
  price: {type: int, default: 5}
  dist: {type: distance, default: 20cm}
tree:
  sequence:
    - log: "budget: $${price} for ${dist}"
    - log: "budget: $$${price}, not $${cost}"
    - log:
        message: "said
          $${price}"
"""


def test_a_dollar_before_a_value_is_written_with_three(
    compile_text: Compile, caplog: pytest.LogCaptureFixture
) -> None:
    """``$${price}`` was ``$5`` at e80f20a and is the text ``${price}`` now: a warning at
    each such place (its own column where the text is on one line, else where the value
    starts), naming the spelling of the old meaning; ``$$${price}`` is that meaning, and a
    ``$${cost}`` that names no parameter is the text it always was."""
    mission = compile_text(BUDGET)
    assert _logged(mission, caplog) == [
        "budget: ${price} for 20cm",
        "budget: $5, not ${cost}",
        "said ${price}",
    ]
    assert mission.description == "costs ${price}"
    said = [f"{w.line}:{w.column}: {w.message}" for w in mission.warnings]
    file = mission.warnings[0].file
    tail = (
        '"$${price}" is the text "${price}"; a "$" before the value is written "$$${price}" '
        '(in 0.1.0, "$${price}" was a "$" and then the value); if the text is meant, say so '
        f"at the top of {file}: literal: [price]"
    )
    assert said == [
        f"2:21: description: {tail}",
        f"8:21: log.message: {tail}",
        f"11:18: log.message: {tail}",  # on two lines: where the text starts
    ], said
    assert all(w.severity == "warning" for w in mission.warnings)


def test_the_escape_warning_is_said_once_for_a_subtree_used_twice(compile_text: Compile) -> None:
    mission = compile_text(
        """
        mission: m
        subtrees:
          s:
            parameters: {price: {type: int, default: 5}}
            tree: {log: "$${price}"}
        tree: {sequence: [{subtree: s}, {subtree: {id: s, price: 6}}]}
        """
    )
    assert [(w.line, w.column) for w in mission.warnings] == [(5, 18)]


def test_a_default_may_not_use_a_parameter_after_a_dollar(errors_of: Errors) -> None:
    """``$$${a}`` uses ``a`` (a ``$``, then its value): refused in a default as ``${a}`` is."""
    head = "mission: m\nparameters:\n  a: {type: str, default: "
    (error,) = errors_of(head + '"$$${a}"}\ntree: {log: "${a}"}\n')
    assert "a default cannot refer to itself" in error


#: 0.1.0 (e80f20a) read no "$" but that of ``${name}``: each "$$" below was two dollars
DOUBLED = """
mission: m
description: "costs $$ 5"
parameters:
  price: {type: int, default: 5}
  note: {type: str, default: "pay $$"}
tree:
  sequence:
    - log: "cost $$5, $$$$5, $$$5 and $5"
    - log: "$$${price} and $$$$"
    - log: "ok"
      name: "pay $$5"
    - sequence:
        name: "spend $$"
        children: [{log: "${note}"}]
"""


def test_a_lone_doubled_dollar_is_warned_of_where_0_1_0_read_two(
    compile_text: Compile, caplog: pytest.LogCaptureFixture
) -> None:
    """``"cost $$5"`` logged ``cost $$5`` in 0.1.0 and logs ``cost $5`` now, with no word
    said: a warning at each lone ``$$`` (a description, a value, a parameter's default, a
    ``name:``), saying what was found, what it reads now and both spellings. ``$$$$`` (two
    now) and ``$$${price}`` (a ``$`` and the value) are the only spellings of what they say
    now, and are not warned of."""
    mission = compile_text(DOUBLED)
    assert _logged(mission, caplog) == ["cost $5, $$5, $$5 and $5", "$5 and $$", "ok", "pay $"]
    said = [f"{w.line}:{w.column}: {w.message}" for w in mission.warnings]
    assert said == [
        '2:21: description: "$$ " reads "$ " since 0.2.0 ("$$" is one "$", as in Python\'s '
        'string.Template); in 0.1.0 it read "$$ ": write "$ " for one "$", or "$$$$ " to keep two',
        '5:35: parameter note: "$$" reads "$" since 0.2.0 ("$$" is one "$", as in Python\'s '
        'string.Template); in 0.1.0 it read "$$": write "$" for one "$", or "$$$$" to keep two',
        '8:18: log.message: "$$5" reads "$5" since 0.2.0 ("$$" is one "$", as in Python\'s '
        'string.Template); in 0.1.0 it read "$$5": write "$5" for one "$", or "$$$$5" to keep two',
        '11:18: name: "$$5" reads "$5" since 0.2.0 ("$$" is one "$", as in Python\'s '
        'string.Template); in 0.1.0 it read "$$5": write "$5" for one "$", or "$$$$5" to keep two',
        '13:22: sequence.name: "$$" reads "$" since 0.2.0 ("$$" is one "$", as in Python\'s '
        'string.Template); in 0.1.0 it read "$$": write "$" for one "$", or "$$$$" to keep two',
    ], said
    names = [node.name for node in mission.root.iterate()]
    assert "pay $5" in names and "spend $" in names, names


def test_the_spellings_a_doubled_dollar_warning_gives_are_not_warned_of(
    compile_text: Compile, caplog: pytest.LogCaptureFixture
) -> None:
    """Following either spelling the warning gives leaves a mission with no warning."""
    mission = compile_text(
        'mission: m\ntree: {sequence: [{log: "cost $5"}, {log: "cost $$$$5"}, {log: "$$$$"}]}\n'
    )
    assert _logged(mission, caplog) == ["cost $5", "cost $$5", "$$"]
    assert mission.warnings == ()


def test_literal_says_the_text_is_meant_and_a_right_mission_passes_strict(
    compile_text: Compile, caplog: pytest.LogCaptureFixture, errors_of: Errors
) -> None:
    """``$${`` is the only spelling of a literal ``${``: a mission that means the text
    ``${price}`` (price a parameter) was warned of on every run and could never pass
    ``--strict``. ``literal: [price]`` says it is meant: the texts read as before, and only
    the names listed are not warned of (``$${dist}`` still is)."""
    mission = compile_text("literal: [price]" + BUDGET.replace("for ${dist}", "for $${dist}"))
    assert _logged(mission, caplog)[:1] == ["budget: ${price} for ${dist}"]
    assert mission.description == "costs ${price}"
    said = [f"{w.line}:{w.column}: {w.message}" for w in mission.warnings]
    assert [line[:40] for line in said] == ['9:35: log.message: "$${dist}" is the tex']
    (error,) = errors_of("literal: [price, 2x]" + BUDGET)
    assert error.startswith("1:18: literal: '2x' is no parameter name"), error
    (error,) = errors_of("literal: price" + BUDGET)
    assert error.startswith("1:10: literal must be a list"), error


def test_literal_refuses_a_name_no_text_of_the_file_can_mean(errors_of: Errors) -> None:
    """``literal: [lpas]`` was taken without a word, and the ``$${laps}`` it was written for
    still warned with no hint why: a name that is no parameter in scope in the file (the
    mission's, or one of a subtree it defines) is refused at its place, with the names
    allowed and the closest of them."""
    mission = (
        "literal: [lpas, say_n]\nparameters:\n  laps: {type: int, default: 2}\n"
        "subtrees:\n  say:\n    parameters: {say_n: {type: int, default: 1}}\n"
        '    tree: {log: "n is $${say_n}"}\ntree: {log: "$${laps}"}\n'
    )
    assert errors_of(mission) == [
        "1:11: literal: found 'lpas', no parameter in scope in this file (did you mean "
        "'laps'?); allowed: laps, say_n (the mission's parameters and those of the subtrees "
        "this file defines)"
    ]
    assert errors_of('literal: [price]\ntree: {log: "$${price}"}\n') == [
        "1:11: literal: found 'price', no parameter in scope in this file; allowed: none: "
        "neither the mission nor a subtree this file defines has a parameter"
    ]


def test_a_library_s_literal_may_name_the_mission_s_parameters(tmp_path: Path) -> None:
    """A library's subtrees see the including mission's parameters too, so its ``literal:``
    may name them; a name that is neither is refused at the library's line, and a library
    validated alone (no mission: no parameters known) is not refused for one."""
    library = tmp_path / "lib.yaml"
    library.write_text('literal: [n, spede]\nsubtrees:\n  say:\n    tree: {log: "$${n}"}\n')
    mission = tmp_path / "m.yaml"
    mission.write_text(
        "include: [lib.yaml]\nparameters:\n  n: {type: int, default: 2}\n"
        "tree: {subtree: {id: say}}\n"
    )
    _, problems = compile_mission(mission)
    assert [(Path(p.file).name, p.line, p.column, p.message[:30]) for p in problems] == [
        ("lib.yaml", 1, 14, "literal: found 'spede', no par")
    ]
    _, alone = compile_mission(library, require_tree=False)
    assert alone == []


def test_literal_is_the_file_s_own(tmp_path: Path) -> None:
    """A library's ``literal:`` covers the texts written in it, a mission's its own: a
    library that means ``${n}`` says so itself, and a mission that includes it is not
    silenced by it."""
    (tmp_path / "lib.yaml").write_text(
        "literal: [n]\nsubtrees:\n  say:\n    parameters: {n: {type: int, default: 1}}\n"
        '    tree: {log: "n is $${n}"}\n'
    )
    mission = tmp_path / "m.yaml"
    mission.write_text(
        "include: [lib.yaml]\nparameters:\n  n: {type: int, default: 2}\ntree:\n"
        '  sequence:\n    - subtree: {id: say}\n    - log: "mine $${n}"\n'
    )
    warnings = load_mission(mission).warnings
    assert [(Path(w.file).name, w.line) for w in warnings] == [("m.yaml", 7)]
