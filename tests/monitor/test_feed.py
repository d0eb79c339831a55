"""The monitor's feed: what it says of a failed node, on the page and in its event log."""

from __future__ import annotations

import py_trees
from py_trees.common import Status

from roomba_bt.monitor.feed import RunFeed
from roomba_bt.oi.profiles import CREATE2
from roomba_bt.runtime.stack import RunStack, TreeMission
from roomba_bt.sim import SimLink, Simulator, load_world

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
    feed = RunFeed(history=100, mission_name="sayer")
    feed.set_tree(root)
    link = SimLink(Simulator(load_world("empty-room"), CREATE2, seed=0))
    stack = RunStack(TreeMission(root, "sayer"), link, profile=CREATE2, timeout_s=1.0,
                     observer=feed.observe)  # fmt: skip
    try:
        stack.run()
    finally:
        stack.close()
    said = "\\x1b[2J\\x0a[ok] robot stopped"
    newest = feed.latest()
    assert newest is not None
    assert newest.reasons[[info.name for info in feed.infos].index("sayer")] == said
    events = [e.text for e in feed.events if e.kind == "status"]
    assert f"sayer -> FAILURE: {said}" in events, events
    assert "steps -> FAILURE: sayer: " + said in events, events
    assert sayer.feedback_message == HOSTILE
