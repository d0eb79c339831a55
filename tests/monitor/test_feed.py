"""The monitor's feed: what it says of a failed node, on the page and in its event log."""

from __future__ import annotations

import py_trees
from py_trees.common import Status

from .live import feed_of_run

#: what a plugin's message may hold: code sets it, no file's check refuses it
HOSTILE = "\x1b[2J\n[ok] robot stopped"


class Sayer(py_trees.behaviour.Behaviour):
    """A plugin-like leaf that fails saying :data:`HOSTILE`."""

    def update(self) -> Status:
        self.feedback_message = HOSTILE
        return Status.FAILURE


def test_a_failed_leaf_s_message_is_one_line_on_the_page_and_in_the_events() -> None:
    """A leaf's ``feedback_message`` went to the page and the event log as it was (a failed
    composite's reason was escaped already, by ``failure_reason``): "\\n[ok] ..." started an
    event line of its own. Escaped where the feed takes it; the leaf keeps its message."""
    sayer = Sayer(name="sayer")
    root = py_trees.composites.Sequence("steps", memory=True, children=[sayer])
    feed = feed_of_run(root, "sayer", history=100)
    said = "\\x1b[2J\\x0a[ok] robot stopped"
    newest = feed.latest()
    assert newest is not None
    assert newest.reasons[[info.name for info in feed.infos].index("sayer")] == said
    events = [e.text for e in feed.events if e.kind == "status"]
    assert f"sayer -> FAILURE: {said}" in events, events
    assert "steps -> FAILURE: sayer: " + said in events, events
    assert sayer.feedback_message == HOSTILE
