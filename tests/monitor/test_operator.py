"""What the run says of its operator: how long it was paused (the summary's ``paused``), who
asked for each act (the event log), and a node named as a script would name it (the API's
``node`` by name or path, not only by index)."""

from __future__ import annotations

import json
import re
from collections.abc import Callable

import pytest
from quoted import assert_quoted  # tests/quoted.py: the docs' quotes

from roomba_bt.monitor.feed import NodeInfo
from roomba_bt.monitor.session import find_node
from roomba_bt.runtime.summary import RunSummary

from .test_server import _control, _serve
from .test_session import Rig

BACK = "drive(velocity=-100 mm/s, distance=3 cm)"


def test_the_summary_says_how_long_the_run_was_paused(until: Callable[..., None]) -> None:
    """Neither the page nor the summary said it: the user subtracted mission from wall time."""
    rig = Rig()
    paused_ticks: list[int] = []

    def operator(rig: Rig) -> None:
        until(lambda: rig.ticks(ticked=True) > 50)
        rig.session.request("pause")
        until(lambda: rig.session.state.paused)
        began = rig.session.state.paused_tick
        assert began is not None
        until(lambda: rig.ticks(ticked=False) > 100)
        rig.session.request("step")
        until(lambda: rig.session.state.pause_reason == "stepped one tick")
        until(lambda: rig.ticks(ticked=False) > 150)
        rig.session.request("resume")
        until(lambda: not rig.session.state.paused)
        paused_ticks.append(sum(1 for r in rig.feed.since(0)[0] if not r.ticked))
        rig.session.request("stop")

    summary = rig.run_with(operator)
    assert (summary.pauses, summary.steps) == (1, 1)
    # the frames it stood still: the unticked records, less the frame after each resume
    # (the tree waits for one that shows the mode back) and give or take the step's frames
    assert abs(summary.paused_s - paused_ticks[0] * 0.015) <= 4 * 0.015, summary.paused_s
    [line] = [line for line in summary.lines() if line.startswith("paused")]
    assert re.fullmatch(
        r"paused       \d+\.\d\d s in 1 pause, 1 step, left out of mission time", line
    ), line
    # what mission time left out: the two add up to the stream's time
    newest = rig.feed.latest()
    assert newest is not None
    assert abs(summary.mission_time_s + summary.paused_s - newest.tick * 0.015) <= 4 * 0.015


def test_a_run_never_paused_has_no_paused_line() -> None:
    assert not [line for line in RunSummary("m").lines() if line.startswith("paused")]
    two = RunSummary("m", paused_s=369.2, pauses=2)
    assert "paused       369.20 s in 2 pauses, left out of mission time" in two.lines()
    stepped = RunSummary("m", paused_s=369.2, pauses=2, steps=1)  # docs/monitor.md's
    assert_quoted("docs/monitor.md", "paused 369.20 s", "\n".join(stepped.lines()))


def test_the_event_log_says_who_asked_for_each_act(until: Callable[..., None]) -> None:
    """Two browsers open: "pause (paused by the operator)" did not say from which."""
    rig = Rig()

    def operator(rig: Rig) -> None:
        until(lambda: rig.ticks(ticked=True) > 20)
        rig.session.request("pause", by="192.0.2.7")
        until(lambda: rig.session.state.paused)
        rig.session.request("resume", by="the terminal's keys")
        until(lambda: not rig.session.state.paused)
        rig.session.request("stop", by="192.0.2.8")

    rig.run_with(operator)
    said = [e.text for e in rig.feed.events if e.kind == "control"]
    assert said[0].startswith("pause (paused by the operator)")
    assert said[0].endswith("; from 192.0.2.7"), said
    assert said[1].endswith("; from the terminal's keys"), said
    assert said[2] == "stop: the run ends (as on Ctrl-C); from 192.0.2.8", said


def test_a_node_is_found_by_its_path_or_its_name_if_only_one_has_it() -> None:
    def info(index: int, name: str, parent: int | None) -> NodeInfo:
        return NodeInfo(index, name, "behaviour", 0, parent, (), False)

    infos = [info(0, "root", None), info(1, "dock", 0), info(2, "drive", 1),
             info(3, "drive", 0), info(4, "a/b", 0)]  # fmt: skip
    assert find_node(infos, "dock") == 1
    assert find_node(infos, "root/dock/drive") == 2
    assert find_node(infos, "root/drive") == 3
    assert find_node(infos, "a/b") == 4  # a name with a slash in it
    ambiguous = r"2 nodes have that name \(indices 2, 3\).*'root/dock/drive'"
    with pytest.raises(ValueError, match=ambiguous):
        find_node(infos, "drive")
    with pytest.raises(ValueError, match=r"no node has that name or path; give an index 0\.\.4"):
        find_node(infos, "undock")


def test_a_string_of_digits_is_an_index_unless_a_node_has_that_name() -> None:
    """``"node": "3"`` was refused as "no node has that name" by an error that listed the
    indices: a script that quoted the index, or read it from a text field, is taken at its
    word; a node named ``3`` still wins, and ``"٣"`` (an Arabic-Indic three) is no index."""

    def info(index: int, name: str, parent: int | None) -> NodeInfo:
        return NodeInfo(index, name, "behaviour", 0, parent, (), False)

    infos = [info(0, "root", None), info(1, "dock", 0), info(2, "drive", 0)]
    assert find_node(infos, "2") == 2
    assert find_node(infos, "0") == 0
    named = [*infos, info(3, "1", 0)]  # a node named "1": its name, not index 1
    assert find_node(named, "1") == 3
    with pytest.raises(ValueError, match="no node has that name"):
        find_node(infos, "\u0663")


def test_the_api_takes_a_node_by_name_and_says_who_asked() -> None:
    server = _serve()
    try:
        session = server.session
        assert session is not None
        index = [info.name for info in session.feed.infos].index(BACK)
        got, body = _control(server, {"action": "break", "node": BACK, "value": "start"})
        assert got == 202, body
        path = "sequence/while reactive_sequence/repeat/there and back/" + BACK
        got, body = _control(server, {"action": "break", "node": path, "value": "end"})
        assert got == 202, body
        queued = [session._requests.get_nowait() for _ in range(2)]
        assert [(r.node, r.value, r.by) for r in queued] == [
            (index, "start", "127.0.0.1"),
            (index, "end", "127.0.0.1"),
        ]
        got, body = _control(server, {"action": "break", "node": "nothing", "value": "start"})
        assert got == 400 and "no node has that name or path" in body["error"], json.dumps(body)
        got, body = _control(server, {"action": "break", "node": str(index), "value": "end"})
        assert got == 202, body  # a quoted index
        assert session._requests.get_nowait().node == index
        too_far = str(len(session.feed.infos))
        got, body = _control(server, {"action": "break", "node": too_far, "value": "end"})
        assert got == 400, body
        assert f"node {too_far}: allowed 0..{int(too_far) - 1}" in body["error"], body
    finally:
        server.close()
