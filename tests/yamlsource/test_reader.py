"""The shared YAML reader: positions, refused tags, duplicate keys, plain data."""

from __future__ import annotations

import re
from collections.abc import Callable
from pathlib import Path

import pytest
import yaml
from hypothesis import given, settings
from hypothesis import strategies as st

from roomba_bt import yamlsource
from roomba_bt.yamlsource import KEY


def root(text: str) -> yaml.Node:
    node = yamlsource.compose(text)
    assert node is not None
    return node


def raw(text: str) -> yaml.Node:
    """Composed without the alias and tag refusal, to test the layers behind it."""
    node = yaml.compose(text, Loader=yamlsource.FAST_LOADER)
    assert node is not None
    return node


def test_every_value_and_key_has_its_line_and_column() -> None:
    data, marks = yamlsource.to_data(root("name: room\nrooms:\n  - [[0, 0], [1, 2]]\n"), "{tag}")
    assert data == {"name": "room", "rooms": [[[0, 0], [1, 2]]]}
    assert marks[("name",)] == (1, 7)
    assert marks[("name", KEY)] == (1, 1)
    assert marks[("rooms", KEY)] == (2, 1)
    assert marks[("rooms", 0, 1, 1)] == (3, 18)


def test_a_key_written_twice_names_both_places_and_its_path() -> None:
    with pytest.raises(yamlsource.DuplicateKey) as caught:
        yamlsource.to_data(root("dock:\n  at: [1, 1]\n  at: [2, 2]\n"), "{tag}")
    dup = caught.value
    assert (dup.key, dup.path) == ("at", ("dock", "at"))
    assert yamlsource.position(dup.node) == (3, 3)
    assert yamlsource.position(dup.first) == (2, 3)


def test_keys_compare_by_type_and_value_one_and_true_are_two_keys() -> None:
    """As Python values ``1 == True``: ``true:`` was reported a duplicate of ``1:``."""
    node = root("1: a\ntrue: b\n")
    assert isinstance(node, yaml.MappingNode)
    assert [k for k, _, _ in yamlsource.pairs(node)] == [1, True]
    with pytest.raises(yamlsource.DuplicateKey):
        list(yamlsource.pairs(root("1: a\n0x1: b\n")))


def test_a_tagged_collection_is_refused_with_the_callers_words_never_built() -> None:
    with pytest.raises(yaml.constructor.ConstructorError) as caught:
        yamlsource.to_data(raw("x: !!python/object:os.system {}\n"), "no {tag!r} here")
    assert caught.value.problem == "no 'tag:yaml.org,2002:python/object:os.system' here"
    assert yamlsource.error_position(caught.value) == (1, 4)


def test_a_scalar_tag_without_a_safe_constructor_is_an_error_not_an_object() -> None:
    node = raw("!!python/name:os.system x\n")
    assert not yamlsource.is_plain(node)
    with pytest.raises(yaml.constructor.ConstructorError):
        yamlsource.scalar(node)
    assert yamlsource.scalar(root("42\n")) == 42  # the failure left nothing behind


@pytest.mark.parametrize(
    ("text", "plain"),
    [("3\n", True), ("2020-01-01\n", True), ("!foo x\n", False), ("!!set {a}\n", False)],
)
def test_only_core_schema_values_are_plain(text: str, plain: bool) -> None:
    assert yamlsource.is_plain(raw(text)) is plain


def test_syntax_errors_have_a_position_and_an_empty_document_is_none() -> None:
    with pytest.raises(yaml.YAMLError) as caught:
        yamlsource.compose("rooms: [[[0, 0]\n", yamlsource.PURE_LOADER)
    assert yamlsource.error_position(caught.value) == (2, 1)
    assert yamlsource.compose("") is None


def test_merge_keys_are_merged() -> None:
    data, _ = yamlsource.to_data(raw("a: &b {x: 1}\nc: {<<: *b, y: 2}\n"), "{tag}")
    assert data["c"] == {"x": 1, "y": 2}


def _bomb(levels: int, as_subtree: bool) -> str:
    lines = ["a0: &a0 [x, x, x, x, x, x, x, x, x, x]"]
    for i in range(1, levels + 1):
        lines.append(f"a{i}: &a{i} [" + ", ".join([f"*a{i - 1}"] * 10) + "]")
    use = (
        f"tree: {{sequence: *a{levels}}}"
        if not as_subtree
        else (f"subtrees:\n  s:\n    tree: {{sequence: [{{wait: 1s}}, *a{levels}]}}")
    )
    return "\n".join([*lines, use]) + "\n"


@pytest.mark.parametrize("loader", [yamlsource.FAST_LOADER, yamlsource.PURE_LOADER])
@pytest.mark.parametrize("levels", [6, 7, 8])
@pytest.mark.parametrize("as_subtree", [False, True])
def test_an_alias_bomb_is_refused_at_its_first_alias(
    loader: type, levels: int, as_subtree: bool
) -> None:
    """6 levels in 857 bytes took 18 s to validate; now nothing is composed: the first alias
    is refused where it is written (no timing asserted: refusal before any expansion)."""
    with pytest.raises(yamlsource.Refused) as caught:
        yamlsource.compose(_bomb(levels, as_subtree), loader)
    assert yamlsource.error_position(caught.value) == (2, 10)
    assert "alias *a0 is not allowed" in str(caught.value.problem)


@pytest.mark.parametrize(
    ("text", "where", "shown"),
    [("wait: !!int 1s\n", (1, 7), "!!int"), ("x: [1, !!float 2]\n", (1, 8), "!!float"),
     ("x: {y: !!bool yes}\n", (1, 8), "!!bool"), ("x: !!str 3\n", (1, 4), "!!str"),
     ("x: !!python/object:os.system {}\n", (1, 4), "!!python/object:os.system"),
     ("- !custom 3\n", (1, 3), "!custom"), ("x: !!map {}\n", (1, 4), "!!map")],
)  # fmt: skip
def test_an_explicit_tag_is_refused_where_it_is_written(
    text: str, where: tuple[int, int], shown: str
) -> None:
    with pytest.raises(yamlsource.Refused) as caught:
        yamlsource.compose(text)
    assert yamlsource.error_position(caught.value) == where
    assert f"explicit tag {shown} is not allowed" in str(caught.value.problem)


def test_an_anchor_alone_and_quoted_values_are_fine() -> None:
    data, _ = yamlsource.to_data(root("a: &x 1\nb: '2'\nc: \"3\"\n"), "{tag}")
    assert data == {"a": 1, "b": "2", "c": "3"}


def _checked_first(text: str, loader: type) -> yaml.Node | None:
    """The reader as it was before texts without ``*`` or ``!`` skipped the event pass."""
    yamlsource.refuse_aliases_and_tags(text, loader)
    return yaml.compose(text, Loader=loader)


def _outcome(read: Callable[[], yaml.Node | None]) -> object:
    """What reading gives, comparable: the node's events, or the error with its place."""
    try:
        node = read()
    except yaml.YAMLError as exc:
        return type(exc).__name__, str(exc), yamlsource.error_position(exc)
    return None if node is None else [repr(e) for e in yaml.serialize(node, stream=None)]


@pytest.mark.parametrize("loader", [yamlsource.FAST_LOADER, yamlsource.PURE_LOADER])
def test_a_syntax_error_after_the_first_document_is_the_parsers_not_the_composers(
    loader: type,
) -> None:
    """Composing stops at a second document; the event pass reads on to the error. A text
    with no ``*`` or ``!`` is composed without the event pass, which still decides the error
    when composing fails."""
    with pytest.raises(yaml.YAMLError) as caught:
        yamlsource.compose("a: 1\n---\nb: [1\n", loader)
    assert not isinstance(caught.value, yaml.composer.ComposerError)
    assert yamlsource.error_position(caught.value) == (4, 1)
    with pytest.raises(yaml.composer.ComposerError, match="another document"):
        yamlsource.compose("a: 1\n---\nb: 2\n", loader)


_PIECES = st.sampled_from(
    ["a: 1", "- x", "b: [1, 2]", "c: {d: e}", "---", "...", "  f: g", "&h i", "j: &k l",
     "m: [", "]", "}", "'n'", '"o: p"', "q:", "  - r", "s: t: u", "#v", "%YAML 1.1", "\t", ""]
)  # fmt: skip


@settings(max_examples=300, deadline=None)
@given(st.lists(_PIECES, max_size=8), st.sampled_from(["fast", "pure"]))
def test_a_text_without_aliases_or_tags_reads_as_with_the_event_pass_first(
    lines: list[str], which: str
) -> None:
    loader = yamlsource.FAST_LOADER if which == "fast" else yamlsource.PURE_LOADER
    text = "\n".join(lines) + "\n"
    assert _outcome(lambda: yamlsource.compose(text, loader)) == _outcome(
        lambda: _checked_first(text, loader)
    )


def test_a_long_value_is_quoted_cut_with_its_length() -> None:
    assert yamlsource.quoted("200 mm/s") == "'200 mm/s'"
    page = "root:x:0:0:root:/root:/bin/bash\n" * 40
    shown = yamlsource.quoted(page)
    assert shown == repr(page)[: yamlsource.QUOTE_LIMIT] + "... (1,280 characters)"


def test_a_quoted_value_keeps_its_backslashes_as_written() -> None:
    """A Windows path given where a duration goes was said ``'C:\\\\missions\\\\a.yaml'``:
    a user searching the file for two backslashes found none. A control character stays
    escaped: the terminal would obey it."""
    assert yamlsource.quoted("C:\\missions\\a.yaml") == "'C:\\missions\\a.yaml'"
    assert yamlsource.quoted(["a\\b"]) == "['a\\b']"
    assert yamlsource.quoted("a\x1b[2J") == "'a\\x1b[2J'"


def test_a_tab_where_yaml_stops_is_named() -> None:
    text = "tree:\n\tsequence: []\n"
    assert yamlsource.tab_hint(text, 2, 1) == " (a tab: YAML indents with spaces)"
    assert yamlsource.tab_hint(text, 1, 1) == ""
    assert yamlsource.tab_hint(text, 9, 1) == ""  # a position past the text: no hint


def test_the_first_byte_that_is_not_utf8_is_placed() -> None:
    data = "tree:\n  x: é\n".encode() + b"  y: \xff\n"
    with pytest.raises(UnicodeDecodeError) as info:
        data.decode("utf-8")
    assert yamlsource.undecodable_position(info.value) == (3, 6)


def _nested(levels: int) -> str:
    """A mapping ``x`` holding lists nested so that the deepest is ``levels`` deep."""
    return "x: " + "[" * (levels - 1) + "1" + "]" * (levels - 1) + "\n"


@pytest.mark.parametrize("loader", [yamlsource.FAST_LOADER, yamlsource.PURE_LOADER])
def test_nesting_up_to_the_limit_reads_and_deeper_is_refused_where_it_goes_over(
    loader: type,
) -> None:
    """A world nested 990 deep was a RecursionError traceback, a mission's description an
    "internal error"; PyYAML's own composer fails at about 600 (it recurses), libyaml at 1000
    with its own "exceeded maximum nesting depth", flow or block."""
    limit = yamlsource.MAX_NESTING
    assert yamlsource.compose(_nested(limit), loader) is not None
    for levels in (limit + 1, 700, 990, 1001, 5000):
        with pytest.raises(yamlsource.Refused) as caught:
            yamlsource.compose(_nested(levels), loader)
        assert yamlsource.error_position(caught.value) == (1, 3 + limit)
        assert f"nested more than {limit} deep" in str(caught.value.problem)


@pytest.mark.parametrize("loader", [yamlsource.FAST_LOADER, yamlsource.PURE_LOADER])
def test_block_nesting_past_libyamls_own_bound_gets_the_documented_message(loader: type) -> None:
    """libyaml refuses 1,000 block levels with its own words ("exceeded maximum nesting
    depth"), which named no bound a user could find in the docs."""
    text = "x:\n" + "".join(" " * level + "-\n" for level in range(1, 1100))
    with pytest.raises(yamlsource.Refused) as caught:
        yamlsource.compose(text, loader)
    assert f"nested more than {yamlsource.MAX_NESTING} deep" in str(caught.value.problem)


def test_the_deepest_collection_first_in_the_file_is_the_one_named() -> None:
    deep = "[" * yamlsource.MAX_NESTING + "1" + "]" * yamlsource.MAX_NESTING
    text = f"a: 1\nb: [2, 3]\nc: {deep}\nd: {deep}\n"
    with pytest.raises(yamlsource.Refused) as caught:
        yamlsource.compose(text)
    assert yamlsource.error_position(caught.value) == (3, 3 + yamlsource.MAX_NESTING)


def test_a_file_over_the_limit_is_refused_before_it_is_read(tmp_path: Path) -> None:
    """A generated 3 MB mission took 8 s and 500 MB to validate."""
    folder = tmp_path
    at_limit = folder / "at.yaml"
    at_limit.write_bytes(b"a: 1\r\n" + b"#" * (yamlsource.MAX_FILE_BYTES - 6))
    assert yamlsource.read_text(at_limit).startswith("a: 1\n")  # newlines as read_text's
    over = folder / "over.yaml"
    over.write_bytes(b"#" * (yamlsource.MAX_FILE_BYTES + 1))
    with pytest.raises(yamlsource.FileTooLarge) as caught:
        yamlsource.read_text(over)
    assert caught.value.size == yamlsource.MAX_FILE_BYTES + 1
    assert str(caught.value).startswith(f"{yamlsource.MAX_FILE_BYTES + 1:,} bytes; at most ")


@pytest.mark.parametrize("loader", [yamlsource.FAST_LOADER, yamlsource.PURE_LOADER])
@pytest.mark.parametrize(
    ("text", "where", "named"),
    [("mission: nul\ntree: stop\n\x00\n", (3, 1), "control character U+0000"),
     ("a: 1\n  # bell \x07 here\n", (2, 10), "control character U+0007"),
     ("a: \"é ü \x1b[31m\"\n", (1, 9), "control character U+001B"),  # libyaml counts bytes
     ("é: 1\nb: x\x9by\n", (2, 5), "control character U+009B"),
     ("a: \ufffe\n", (1, 4), "character U+FFFE")],
    ids=["nul", "bel-in-a-comment", "esc-after-non-ascii", "c1", "not-a-character"],
)  # fmt: skip
def test_a_character_the_reader_refuses_is_placed_and_named(
    loader: type, text: str, where: tuple[int, int], named: str
) -> None:
    """PyYAML said "unacceptable character #x0000 ... position 52" of "<unicode string>" on a
    second line, and its mark was 1:1; libyaml's position is in bytes, PyYAML's in
    characters: both now give the character's own line and column."""
    with pytest.raises(yamlsource.Refused) as caught:
        yamlsource.compose(text, loader)
    assert yamlsource.error_position(caught.value) == where
    problem = str(caught.value.problem)
    assert problem.startswith(f"{named} is not allowed in a YAML file: ")
    assert "printable characters, tabs and line breaks" in problem
    assert "\n" not in problem


@pytest.mark.parametrize("loader", [yamlsource.FAST_LOADER, yamlsource.PURE_LOADER])
@pytest.mark.parametrize(
    ("text", "where", "named", "role"),
    [('mission: "\\e[31mred"\n', (1, 10), "U+001B", "value"),
     ('a:\n  - "ok"\n  - "\\x1b]0;title\\a"\n', (3, 5), "U+001B", "value"),
     ('a: {"\\u001b[2Jdrvie": 1}\n', (1, 5), "U+001B", "key"),
     ('a: "bell \\a"\n', (1, 4), "U+0007", "value"),
     ('a: "ok\\rFAILED"\n', (1, 4), "U+000D", "value"),
     ('a: "\\x9b2J"\n', (1, 4), "U+009B", "value"),
     ('a: "\\0"\nb: "\\e"\n', (1, 4), "U+0000", "value")],
    ids=["esc", "osc-in-a-list", "in-a-key", "bel", "carriage-return", "c1-csi", "first-one"],
)  # fmt: skip
def test_a_control_character_written_as_an_escape_is_refused_at_its_text(
    loader: type, text: str, where: tuple[int, int], named: str, role: str
) -> None:
    """The reader refuses a raw ESC, but ``"\\e[2J"`` in double quotes made one: a shared
    mission file reached the user's terminal (``show``, the live tree, the log, error lines)."""
    with pytest.raises(yamlsource.Refused) as caught:
        yamlsource.compose(text, loader)
    assert yamlsource.error_position(caught.value) == where
    assert str(caught.value.problem).startswith(
        f"control character {named} (an escape such as \\e, \\x1b or \\a in quotes) is not "
        f"allowed in a {role}: a text may hold printable characters, tabs and line breaks only"
    )


def test_tabs_newlines_and_backslashes_as_written_are_fine() -> None:
    data, _ = yamlsource.to_data(root("a: \"x\\ty\\nz\"\nb: C:\\e\\x1b\nc: '\\e'\n"), "{tag}")
    assert data == {"a": "x\ty\nz", "b": "C:\\e\\x1b", "c": "\\e"}


@pytest.mark.parametrize("loader", [yamlsource.FAST_LOADER, yamlsource.PURE_LOADER])
@pytest.mark.parametrize(
    ("text", "expected"),
    [("- &a stop\n- *a\n- !!python/object:os.system ls\n- {\"\\a\": \"\\e\"}\n- *a\n",
      [((2, 3), "alias *a"), ((3, 3), "explicit tag !!python/object:os.system"),
       ((4, 4), "control character U+0007"), ((4, 10), "control character U+001B"),
       ((5, 3), "alias *a")]),
     ("a: \"\\e\"\nb: [\"\\a\", {\"\\r\": 1}]\n",  # no * nor !: found in the composed nodes
      [((1, 4), "control character U+001B"), ((2, 5), "control character U+0007"),
       ((2, 12), "control character U+000D")]),
     ("a: *x\nb: !!int 1\nc: [\n", [((1, 4), "alias *x"), ((2, 4), "explicit tag !!int")])],
    ids=["aliases-tags-controls", "controls-only", "then-a-syntax-error"],
)  # fmt: skip
def test_every_refusal_is_raised_at_once_in_the_files_order(
    loader: type, text: str, expected: list[tuple[tuple[int, int], str]]
) -> None:
    """An alias hid a ``!!python/object`` tag on the next line: a stranger fixing one error
    met the next. The first is raised, the others in its ``more``; a syntax error past them
    is the parser's to report once they are gone."""
    with pytest.raises(yamlsource.Refused) as caught:
        yamlsource.compose(text, loader)
    found = [
        (yamlsource.error_position(each), re.split(r" is not| \(an escape", str(each.problem))[0])
        for each in caught.value.every()
    ]
    assert found == expected


def test_every_duplicate_of_a_mapping_is_found_and_can_be_left_out() -> None:
    """A reader that reports every duplicate first goes on with the first of each key."""
    node = root("a: 1\nb: 2\na: 3\n1: x\n0x1: y\na: 4\n")
    assert isinstance(node, yaml.MappingNode)
    found = [(d.key, yamlsource.position(d.node), yamlsource.position(d.first))
             for d in yamlsource.duplicate_keys(node)]  # fmt: skip
    assert found == [("a", (3, 1), (1, 1)), (1, (5, 1), (4, 1)), ("a", (6, 1), (1, 1))]
    kept = [(k, v.value) for k, _, v in yamlsource.pairs(node, skip_duplicates=True)]
    assert kept == [("a", "1"), ("b", "2"), (1, "x")]


@pytest.mark.parametrize("loader", [yamlsource.FAST_LOADER, yamlsource.PURE_LOADER])
@pytest.mark.parametrize(
    ("text", "where", "named"),
    [("# comment \x85 with NEL\nmission: t\n", (1, 11), "control character U+0085 (NEL)"),
     ('mission: t\ndescription: "pasted \x85 here"\n', (2, 22), "control character U+0085 (NEL)"),
     ("# comment \u2028 with LS\nmission: t\n", (1, 11), "line separator U+2028"),
     ("mission: t\ndescription: a \u2029 b\n", (2, 16), "paragraph separator U+2029")],
    ids=["nel-in-a-comment", "nel-in-quotes", "ls-in-a-comment", "ps-in-a-text"],
)  # fmt: skip
def test_a_line_break_editors_do_not_show_is_refused_at_its_own_place(
    loader: type, text: str, where: tuple[int, int], named: str
) -> None:
    """YAML reads NEL, U+2028 and U+2029 as line breaks, editors do not: a NEL in a comment
    was a syntax error one line off, one in a value numbered every later line one off."""
    with pytest.raises(yamlsource.Refused) as caught:
        yamlsource.compose(text, loader)
    assert yamlsource.error_position(caught.value) == where
    assert str(caught.value.problem).startswith(f"{named} is not allowed")


def test_keys_are_compared_by_type_and_value() -> None:
    """``1``, ``true`` and ``1.0`` are three keys (Python's ``1 == True == 1.0`` made the
    second and third "duplicate key 'True'"); ``0x1`` is ``1`` written again."""
    root = yamlsource.compose("1: a\ntrue: b\n1.0: c\n0x1: d\n")
    assert [yamlsource.position(d.node) for d in yamlsource.every_duplicate_key(root)] == [(4, 1)]


def test_an_integer_too_long_to_read_is_refused_where_it_is_written() -> None:
    """Python reads at most 4,300 digits: the ValueError came from far away, "internal error
    while compiling" at 1:1 of a mission, a traceback (exit 1) for a world."""
    digits = "9" * 5000
    root = yamlsource.compose(f"a: 1\nb: [2, {digits}]\n? {digits}\n: 3\n")
    assert root is not None
    with pytest.raises(yamlsource.Refused) as refused:
        yamlsource.to_data(root, "{tag}")
    assert yamlsource.error_position(refused.value) == (2, 8)
    assert refused.value.problem == (
        "an integer of 5,000 digits is too large a number: at most 4,300 digits are read "
        "(a file generated wrong?)"
    )
    assert yamlsource.every_duplicate_key(root) == []  # a key of as many: read as its text
