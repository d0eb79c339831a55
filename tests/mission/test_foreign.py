"""BehaviorTree.CPP's words, values and habits, each told what roomba-bt writes instead
(roomba_bt/mission/foreign.py): they got no hint, or a wrong one (``script`` -> ``spot``)."""

from __future__ import annotations

import re
from collections.abc import Callable

import pytest
import yaml

from roomba_bt.behaviours.declare import Param
from roomba_bt.behaviours.language import MODIFIERS, WORDS
from roomba_bt.behaviours.registry import builtin_registry
from roomba_bt.mission.foreign import BTCPP

Errors = Callable[..., list[str]]

_HEAD = "blackboard: {target: distance}\nsubtrees: {back_off: {tree: stop}}\ntree:\n  sequence:\n"


@pytest.mark.parametrize(
    ("node", "said"),
    [
        ("RetryUntilSuccessful: {num_attempts: 3, do: stop}",
         "unknown node 'RetryUntilSuccessful' (BehaviorTree.CPP's RetryUntilSuccessful is "
         "'retry' here: retry: {times: N, do: NODE}, times at least 1)"),
        ("retry_until_successful: {do: stop}", "RetryUntilSuccessful is 'retry' here"),
        ("KeepRunningUntilFailure: {do: stop}",
         "is 'repeat' here: repeat: {do: NODE} without times re-runs it after each success "
         "until it fails"),
        ("RunOnce: stop", "RunOnce is 'oneshot' here"),
        ("Sleep: {msec: 100}", "Sleep is 'wait' here: wait: 500ms"),
        ("SequenceWithMemory: [stop]",
         "is 'sequence' here: roomba-bt's sequence has memory: it resumes a RUNNING child"),
        ("sequence_star: [stop]", "SequenceStar is 'sequence' here: roomba-bt's sequence has "),
        ("retry: {num_attempts: 3, do: stop}",
         "retry: unknown option 'num_attempts' (BehaviorTree.CPP's num_attempts is 'times' "
         "here: times: N (at least 1)); known: do, times"),
        ("repeat: {num_cycles: 3, do: stop}", "num_cycles is 'times' here"),
        ("timeout: {msec: 500, do: stop}",
         "msec is 'after' here: a time with its unit, such as 2s or 500ms); known: do, after"),
        ("delay: {delay_msec: 500, do: stop}", "delay_msec is 'for' here"),
        ("wait: {msec: 500}", "wait: unknown parameter 'msec' (BehaviorTree.CPP's msec is "
         "'duration' here"),
        ("parallel: {success_count: 1, children: [stop]}",
         "success_count is 'policy' here: policy: all, one or selected (the children "
         "selected: [NAME, ...] names); there are no counts"),
        ("parallel: {failure_count: 1, children: [stop]}", "failure_count is 'policy' here"),
        ("ParallelAll: {max_failures: 1, children: [stop]}",
         "ParallelAll is 'parallel' here: parallel: [NODE, NODE] (policy: all, the default)"),
        ("parallel: {max_failures: 2, children: [stop]}",
         "max_failures is 'policy' here: policy: all, one or selected (the children selected: "
         "[NAME, ...] names); there are no counts, and any failure fails"),
        ("RunOnce: stop", "oneshot: {policy: on_completion, do: NODE} until it ends either way"),
        ("subtree: {ID: back_off}",
         "subtree needs id: NAME; found 'ID' (BehaviorTree.CPP's ID is 'id' here"),
        # none here: said so, with what to write; never 'spot' or 'force_success'
        ("script: 'x := 1'", "Script has no counterpart here: there are no scripts: set: "),
        ("Script: {code: 'x := 1'}", "Script has no counterpart here"),
        ("{wait: 1s, _post: stop}",
         "unknown node '_post' next to 'wait' (BehaviorTree.CPP's _post has no counterpart"),
        ("{stop: {}, _skipIf: {bump: any}}",
         "_skipIf has no counterpart here: fallback: [CONDITION, NODE] does not run NODE"),
        ("{stop: {}, _failureIf: {bump: any}}",
         "_failureIf has no counterpart here: sequence: [{inverter: CONDITION}, NODE]"),
        ("{wait: 1s, _successIf: {bump: any}}",
         "_successIf is 'until' here: until: CONDITION, written beside the node's word"),
        ("{wait: 1s, _while: {bump: any}}", "_while is 'while' here"),
        # a modifier inside a word's value; a list under a decorator of one child
        ("force_success: {do: stop, while: {bump: any}}",
         "force_success: unknown option 'while' (while is a modifier: write it beside the "
         "word, in the node's own mapping ({force_success: ..., while: ...}), not inside "
         "force_success's value); known: do"),
        ("inverter: [{bump: any}]",
         "inverter takes exactly one child, got a list of 1 (drop the list: inverter: NODE)"),
        ("timeout: {after: 1s, do: [stop]}", "got a list of 1 (drop the list: do: NODE)"),
        ("timeout: {after: 1s, do: [stop, stop]}", "got a list of 2 (wrap them in a sequence)"),
        # BT.CPP's {key} and a script's ${key} as values
        ("drive: {velocity: 200 mm/s, distance: '{target}'}",
         "drive.distance: '{target}' is BehaviorTree.CPP's port remapping; a blackboard value "
         'is written "@target" here'),
        ("drive: {velocity: 200 mm/s, distance: '{tagret}'}",
         "written \"@tagret\" here (no key 'tagret' is declared)"),
        ("drive: {velocity: 200 mm/s, distance: '${target}'}",
         "drive.distance: unknown parameter ${target}: 'target' is a blackboard key, and a "
         'blackboard value is written "@target" here'),
    ],
)  # fmt: skip
def test_a_behavior_tree_cpp_habit_is_told_what_to_write_here(
    errors_of: Errors, node: str, said: str
) -> None:
    errors = errors_of(_HEAD + f"    - mode: safe\n    - {node}\n")
    assert any(said in e for e in errors), errors
    assert not any("'spot'" in e or "'force_success'?" in e for e in errors), errors


def test_a_subtree_parameter_refuses_a_blackboard_value_and_says_why(errors_of: Errors) -> None:
    """``subtree: {id: go, dist: "@d"}`` (BT.CPP's port remapping) said only "not allowed
    here"."""
    errors = errors_of(
        "blackboard: {d: {type: distance, initial: 20cm}}\n"
        "subtrees: {go: {parameters: {dist: {type: distance}}, tree: {wait: 1s}}}\n"
        "tree: {sequence: [{subtree: {id: go, dist: '@d'}}, {subtree: {id: go, dist: '{d}'}}]}\n"
    )
    why = (
        "a blackboard value (@key) is not allowed here: a subtree's parameters are fixed when "
        "the mission is compiled, before any key holds a value; read the key inside the "
        "subtree (@key): keys are the whole mission's"
    )
    assert errors == [
        f"3:44: go.dist: {why}",
        f"3:77: go.dist: '{{d}}' is BehaviorTree.CPP's port remapping; {why}",
    ]


def test_a_text_value_in_braces_is_text() -> None:
    """``{x}`` is only BT.CPP's remapping where a text cannot go: a log may say it."""
    from roomba_bt.mission.foreign import port_remapping

    assert port_remapping("{target}") == "target"
    assert port_remapping("at {target} now") is None


def test_every_word_the_table_names_is_one_of_ours() -> None:
    """The table is data about our words: each counterpart it names is a word, a modifier,
    a behaviour, or an option or parameter of one, so a renamed word cannot leave it
    pointing at nothing."""
    registry = builtin_registry()
    ours = {*WORDS, *MODIFIERS, *registry.names()}
    ours |= {p.name for kind in WORDS.values() for p in kind.options}
    ours |= {p.name for name in registry.names() for p in registry.get(name).params}  # type: ignore[union-attr]
    named = {word for entry in BTCPP.values() for word in entry.ours}
    assert named and named <= ours, named - ours
    assert all(entry.note for entry in BTCPP.values())


#: what a note's placeholders stand for in the mission a suggestion is tried in
_FILLED = {"NODE": "stop", "CONDITION": "{bump: any}", "IF": "{bump: any}", "THEN": "{wait: 1s}",
           "ELSE": "stop", "KEY": "k", "VALUE": "1", "N": "2", "NAME": "back_off"}  # fmt: skip
_PLACEHOLDER = re.compile(r"\b(" + "|".join(_FILLED) + r")\b")
#: ``word: `` where a suggestion may start (not a key inside one's mapping: ``{key: ``)
_WRITTEN = re.compile(r"(?<![\w{])(\w+): ")
#: an option's values as a note lists them: ``all, one or selected``
_LISTED = re.compile(r"\w+(?:, \w+)*(?: or \w+)?")


def _value_end(text: str, start: int) -> int:
    """Where the value starting at ``start`` ends: a flow mapping or list's closing
    bracket, or the end of a plain word."""
    if text[start] not in "{[":
        found = re.compile(r"[^\s,;)]+").match(text, start)
        assert found is not None, text[start:]
        return found.end()
    depth = 0
    for end in range(start, len(text)):
        depth += {"{": 1, "[": 1, "}": -1, "]": -1}.get(text[end], 0)
        if depth == 0:
            return end + 1
    raise AssertionError(f"unclosed in {text!r}")


def _suggested(note: str, words: set[str]) -> list[str]:
    """The YAML a note suggests: each ``word: value`` of a node word or modifier in it,
    a flow value whole (``retry: {times: N, do: NODE}``)."""
    found, at = [], 0
    while (written := _WRITTEN.search(note, at)) is not None:
        at = written.end()
        if written.group(1) in words:
            at = _value_end(note, written.end())
            found.append(note[written.start() : at])
    return found


def test_every_hint_suggests_what_validates(errors_of: Errors) -> None:
    """What a hint tells a BT.CPP user to write is held to the language as it is: each
    node or modifier it suggests validates (placeholders filled in), and each option value
    it names is one the option takes, so a renamed option, value or word cannot leave a
    hint that the validator then refuses. A note with no suggestion says what to write
    in words (a counterpart's option)."""
    registry = builtin_registry()
    words = {*WORDS, *registry.names(), "subtree"}
    head = (
        "blackboard: {k: {type: int, initial: 0}}\n"
        "subtrees: {back_off: {parameters: {parameter: {type: str, default: x}}, tree: stop}}\n"
        "tree:\n  sequence:\n    - mode: safe\n"
    )
    tried = 0
    for theirs, entry in BTCPP.items():
        for suggestion in _suggested(entry.note, words | set(MODIFIERS)):
            filled = _PLACEHOLDER.sub(lambda m: _FILLED[m.group(1)], suggestion)
            if filled.partition(":")[0] in MODIFIERS:  # written beside a node's word
                filled = "{wait: 1s, " + filled + "}"
            elif not filled.startswith("{"):
                filled = "{" + filled + "}"
            assert errors_of(head + f"    - {filled}\n") == [], (theirs, suggestion)
            tried += 1
        options = {o.name: o for kind in WORDS.values() for o in kind.options}
        for option in (word for word in entry.ours if word in options):
            for written in re.finditer(rf"\b{option}: ", entry.note):
                listed = _LISTED.match(entry.note, written.end())
                assert listed is not None, (theirs, entry.note)
                for value in re.split(r", | or ", _PLACEHOLDER.sub(
                        lambda m: _FILLED[m.group(1)], listed.group())):  # fmt: skip
                    takes = [kind.option(option) for kind in WORDS.values()]
                    assert any(_takes(p, value) for p in takes if p is not None), (theirs, value)
                    tried += 1
    assert tried > len(BTCPP)


def _takes(param: Param, written: str) -> bool:
    """Whether ``param`` takes the value ``written`` (YAML) in its type and range."""
    try:
        value = param.type.parse(yaml.safe_load(written))
    except ValueError:
        return False
    return param.check_range(value) is None
