"""``roomba-bt monitor RECORD.jsonl``: a recorded run, replayed into a feed for the page.

The record's sensor bytes go through the same parser, mode model and tree as ``replay`` does
(:class:`~roomba_bt.runtime.recording.ReplayTransport`), and every tick is kept, so the page's
timeline covers the whole run. A record holds no simulator truth: the path is the odometry.
Notes in the record (a condition forced from the page) become events.
"""

from __future__ import annotations

from typing import Any

from roomba_bt.monitor.feed import RunFeed
from roomba_bt.runtime.recording import Record
from roomba_bt.runtime.stack import replay_record
from roomba_bt.runtime.summary import RunSummary

#: Ticks kept of a recorded run (about 100 min): the whole run, within a bound.
RECORD_HISTORY = 400_000


def replay_into_feed(
    record: Record, mission: Any, profile: Any, packets: tuple[int, ...], baud: int, name: str
) -> tuple[RunFeed, RunSummary]:
    """Replay ``record`` through ``mission``; the feed holds every tick."""
    feed = RunFeed(history=RECORD_HISTORY, source="record", mission_name=mission.name)
    feed.set_tree(mission.root)
    summary, _ = replay_record(
        record, mission, profile=profile, packets=packets, baud=baud, name=name,
        observer=lambda r: _ignore(feed.observe(r)),
    )  # fmt: skip
    for t, note in record.notes:
        feed.event("force" if "force" in note else "note", _note_text(note), t)
    feed.finished = f"{summary.outcome.value} (recorded run, {summary.ticks} ticks)"
    return feed, summary


def _note_text(note: dict[str, Any]) -> str:
    if "force" in note:
        to = note.get("to")
        return f"{note['force']} forced to {to}" if to != "none" else f"{note['force']} released"
    return ", ".join(f"{k}={v}" for k, v in note.items())


def _ignore(_: object) -> None:
    """An observer returns nothing."""
