"""Sensor frames leave the process: pickled (multiprocessing, Dask, a saved frame) and copied.

A frame's layout holds a compiled ``struct.Struct``, which does not pickle: a frame could not
be sent to a worker or saved ("cannot pickle '_struct.Struct' object")."""

from __future__ import annotations

import copy
import pickle
import subprocess
import sys

import pytest
from waits import HANG_S  # tests/waits.py: a hang's bound

from roomba_bt.oi.bits import ChargingState
from roomba_bt.oi.frames import SensorFrame, layout_for
from roomba_bt.oi.profiles import ROOMBA500

IDS = (7, 21, 25, 26, 43, 44)
VALUES = {7: 1, 21: 2, 25: 1500, 26: 3000, 43: 100, 44: 65531}


def _frame(with_ids: bool) -> SensorFrame:
    layout = layout_for(IDS, ROOMBA500, with_ids)
    payload = layout.pack(VALUES)
    return layout.decode(payload)


@pytest.mark.parametrize("with_ids", [True, False], ids=["stream", "reply"])
@pytest.mark.parametrize("protocol", range(2, pickle.HIGHEST_PROTOCOL + 1))
def test_a_frame_pickles_and_reads_the_same(with_ids: bool, protocol: int) -> None:
    frame = _frame(with_ids)
    back = pickle.loads(pickle.dumps(frame, protocol))
    assert type(back) is SensorFrame and back == frame and back.values == frame.values
    assert back.layout.packet_ids == IDS and back.layout.with_ids is with_ids
    assert back.layout.profile == ROOMBA500  # its profile's rules, not the default's
    assert back.any_bump and back.charging_state is ChargingState.FULL_CHARGING
    assert back.battery_percent == 50.0 and back.right_encoder_counts == 65531
    assert back.layout.frame_size == frame.layout.frame_size


@pytest.mark.parametrize("copier", [copy.copy, copy.deepcopy], ids=["copy", "deepcopy"])
def test_a_frame_copies(copier: object) -> None:
    frame = _frame(True)
    copied = copier(frame)  # type: ignore[operator]
    assert copied == frame and copied.as_dict() == frame.as_dict()
    assert copied.layout.struct.size == frame.layout.struct.size


def test_a_pickled_frame_loads_in_another_process() -> None:
    """The bytes a worker would receive: a fresh interpreter, no layout cached yet."""
    script = (
        "import pickle, sys\n"
        "frame = pickle.loads(bytes.fromhex(sys.argv[1]))\n"
        "print(frame.layout.profile.name, frame.left_encoder_counts, frame.any_bump)\n"
    )
    data = pickle.dumps(_frame(True)).hex()
    done = subprocess.run(
        [sys.executable, "-c", script, data], capture_output=True, text=True, timeout=HANG_S
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ["roomba500", "100", "True"]
