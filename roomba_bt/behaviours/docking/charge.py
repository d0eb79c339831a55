"""``dock_wait_charge`` (charging confirmed) and ``dock_time_limit`` (the bound on a whole
docking run, naming the stage that was running)."""

from __future__ import annotations

import py_trees
from py_trees.common import Status

from roomba_bt.behaviours.base import Action
from roomba_bt.behaviours.blackboard import run_board
from roomba_bt.behaviours.declare import Param, declare
from roomba_bt.behaviours.docking.common import (
    FAILED,
    OK,
    PAST_SEARCH_KEY,
    RUN_KEY,
    RUNNING,
    STAGE_KEY,
    DockingRun,
    current_stage,
    note_stage,
    past_search,
)
from roomba_bt.behaviours.lean import behaviour_tick, tick_ended
from roomba_bt.behaviours.units import DURATION
from roomba_bt.oi.frames import CHARGING_SOURCES_PACKETS, CHARGING_STATE_PACKETS
from roomba_bt.printable import duration_said

_DEBUG = py_trees.logging.Level.DEBUG
_LOGGING = py_trees.logging  # its level read on every tick (lean.py's _LOGGING)


@declare(
    "dock_wait_charge",
    kind="action",
    params=(
        Param("timeout", DURATION, default="10s", minimum=0.1,
              doc="FAILURE if charging is not confirmed by then"),
    ),
    reads=(*CHARGING_STATE_PACKETS, *CHARGING_SOURCES_PACKETS),
)  # fmt: skip
class DockWaitCharge(Action):
    """SUCCESS when charging is confirmed: packet 34's home-base bit AND a charging state
    (reconditioning, full, trickle, or waiting: 4, which a full battery on the dock often
    reads) in packet 21. The robot charges only in Passive: put a ``mode: passive`` before
    this leaf."""

    stage = "wait for charge"

    def start(self) -> None:
        note_stage(self.stage)
        self._t0 = self.snapshot.time
        self._limit = self.number("timeout") - 1e-9  # read once a start

    def update(self) -> Status:
        snap = self.snapshot
        frame = snap.frame
        home = frame.charging_sources.home_base
        if home and frame.charging_state.is_charging:
            return OK
        if snap.time - self._t0 >= self._limit:
            why = "charging state stays" if home else "the home base is not powering the robot;"
            state = frame.charging_state.name.lower().replace("_", " ")
            self.feedback_message = (
                f"{self.stage}: {why} {state} after {duration_said(self.number('timeout'))}"
                if home
                else f"{self.stage}: {why} charging state {state}"
            )
            return FAILED
        return RUNNING

    _t0 = 0.0
    _limit = 0.0


#: What a docking run that never got past the search adds to its time limit's message:
#: the dock unreachable (behind a closed door) or unpowered read the same as a search that
#: was merely slow, "stage search was running", and an owner whose robot could not get home
#: was not told why it might be
#: (after the stage's parentheses, which ``eval`` reads the stage from)
_NO_BEAM = (
    ": no receiver saw the dock's beams; is the dock powered, and can the robot get to it "
    "(a closed door, a virtual wall)?"
)


@declare(
    "dock_time_limit",
    kind="action",
    params=(Param("limit", DURATION, required=True, minimum=1,
                  doc="give up after this much mission time"),),
    primary="limit",
    may_succeed=lambda params: False,  # RUNNING, then FAILURE
)  # fmt: skip
class DockTimeLimit(Action):
    """RUNNING until ``limit`` has passed, then FAILURE: ``gave up after 300 s in stage
    approach``. Run it in a ``parallel`` (policy ``one``) beside the docking stages."""

    def start(self) -> None:
        self._t0 = self.snapshot.time
        storage, board = py_trees.blackboard.Blackboard.storage, run_board()
        storage.pop(board.name(STAGE_KEY), None)  # a new docking run
        storage.pop(board.name(PAST_SEARCH_KEY), None)
        storage[board.name(RUN_KEY)] = DockingRun(id(self), self._t0, self.name)
        self._limit = self.number("limit") - 1e-9  # read once a start

    def tick_direct(self, started: bool = False) -> None:
        """The leaf tick (:func:`~roomba_bt.behaviours.lean.behaviour_tick`), its steps for a
        running limit written here: :meth:`update` (the node's own, a subclass's or this
        one), and :func:`~roomba_bt.behaviours.lean.tick_ended` once it says other than
        RUNNING. Ticked beside the stages on every tick of a docking run, through
        ``behaviour_tick`` it made that function's attribute reads, specialised for the
        running stage, switch class twice a tick."""
        if started or self.status is not RUNNING or _LOGGING.level is _DEBUG:
            behaviour_tick(self, started)
            return
        new_status = self.update()
        if new_status is not RUNNING:
            tick_ended(self, new_status)

    def update(self) -> Status:
        robot = self.robot  # the handle's snapshot, without the property's call (every tick)
        if (robot.snapshot if robot is not None else self.snapshot).time - self._t0 >= self._limit:
            stage = current_stage() or "search"
            self.feedback_message = (
                f"{stage}: gave up after the time limit of {duration_said(self.number('limit'))} "
                f"(stage {stage} was running){'' if past_search() else _NO_BEAM}"
            )
            return FAILED
        return RUNNING

    _t0 = 0.0
    _limit = 0.0
