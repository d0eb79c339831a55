"""What ``roomba-bt behaviours`` says of the mission language's own words (``retry``,
``timeout``, ``until``, ``include``): they are no behaviours, but a user asking about one
is asking a fair question, so the answer is the word's meaning and options from the
language table, exit 0, and ``behaviours --words`` lists them all. The description is the
language table's (:mod:`roomba_bt.behaviours.language`), not a page: docs/missions.md is in
the project's repository, not in the wheel a pip user has.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from roomba_bt.behaviours.declare import Param

#: what each shape of the language's words is called (docs/missions.md, "Nodes")
_WORD_KINDS = {
    "children": "a composite",
    "do": "a decorator",
    "child or do": "a decorator",
    "subtree": "a word (the node that uses a subtree)",
}

#: the file sections a node could be mistaken for (the rest of RESERVED are words and
#: modifiers), each with what it holds
_SECTIONS = {
    "include": "other files whose subtrees (and blackboard, plugins) this one uses",
    "tree": "the mission's root node",
}

#: said after a word's description: where every word is listed, for a pip user too
EVERY_WORD = "every word of the language: roomba-bt behaviours --words"


def language_word(name: str) -> str | None:
    """What ``behaviours NAME`` says of a word of the mission language (a composite, a
    decorator, ``subtree``, a modifier, a file section), which is no behaviour: what it is
    and its options; None for any other name. ``behaviours retry`` said ``unknown behaviour
    'retry' (did you mean 'odometry'?)``."""
    facts = word_facts(name)
    if facts is None:
        return None
    what, doc, options = facts
    listed = "; ".join(f"{p.name}: {p.describe()}" for p in options)
    takes = f" (options: {listed})" if listed else ""
    return f"{name!r} is {what}, not a behaviour: {doc}{takes}"


def word_markdown(name: str) -> str | None:
    """A word of the mission language as ``behaviours --markdown`` prints it, in a
    behaviour's entry's shape (:func:`roomba_bt.behaviours.reference.markdown_entry`): what
    it is and its text, then its options' table. It was said as text on stderr, and stdout,
    the Markdown a contributor pastes, was empty. None for any other name."""
    from roomba_bt.behaviours.reference import TABLE_HEAD, param_row

    facts = word_facts(name)
    if facts is None:
        return None
    what, doc, options = facts
    lines = [f"**`{name}`**: {what}, not a behaviour: {doc}  "]
    if options:
        lines += ["", *TABLE_HEAD]
        lines += ["| " + " | ".join(param_row(p)) + " |" for p in options]
    return "\n".join(lines) + "\n"


def word_facts(name: str) -> tuple[str, str, tuple[Param, ...]] | None:
    """What a word of the mission language is (``a decorator of the mission language``),
    its description and its options: said as text by :func:`language_word`, as data by
    ``behaviours --json``. None for any other name."""
    from roomba_bt.behaviours.language import MODIFIERS, WORDS

    kind = WORDS.get(name)
    if kind is not None:
        return f"{_WORD_KINDS[kind.shape.value]} of the mission language", kind.doc, kind.options
    if name in MODIFIERS:
        what = "a modifier of the mission language, written beside any node's word"
        return what, MODIFIERS[name], ()
    if name in _SECTIONS:
        return "a section of a mission file", _SECTIONS[name], ()
    return None


def every_word() -> list[str]:
    """``behaviours --words``: each word of the language, modifier and section a node could
    be mistaken for, one line each, in the language table's order."""
    from roomba_bt.behaviours.language import MODIFIERS, WORDS

    names = [*WORDS, *MODIFIERS, *_SECTIONS]
    return [said for said in map(language_word, names) if said is not None]
