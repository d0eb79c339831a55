"""Packet 35 on a Roomba 600 reads the OI mode + 1. The parser and the reply decoder are built
with the profile (or what the session learned), and a frame reads its mode through it: a
library user of a roomba600 read Passive as Safe (``frame.oi_mode``) while the CLI, which
corrected the byte a second time, showed Passive."""

from __future__ import annotations

import pickle

import pytest

from roomba_bt.oi import commands as C
from roomba_bt.oi.frames import layout_for
from roomba_bt.oi.modes import OIMode
from roomba_bt.oi.profiles import CREATE2, ROOMBA600, RobotProfile
from roomba_bt.oi.stream import StreamParser, decode_reply
from roomba_bt.sim import SimLink, Simulator, load_world

#: (profile, the byte packet 35 carries in Passive)
PASSIVE_BYTES = [(CREATE2, 1), (ROOMBA600, 2)]


@pytest.mark.parametrize(("profile", "raw"), PASSIVE_BYTES, ids=lambda p: getattr(p, "name", p))
def test_a_streamed_frame_reads_passive_on_either_profile(profile: RobotProfile, raw: int) -> None:
    link = SimLink(Simulator(load_world("empty-room"), profile=profile))
    link.write(C.start().data + C.stream([35]).data)
    frame = StreamParser([35], profile).feed(link.read(0.1))[0]
    assert (frame.oi_mode, frame.oi_mode_raw) == (OIMode.PASSIVE, raw)
    assert frame.as_dict()["oi_mode"] is OIMode.PASSIVE


@pytest.mark.parametrize(("profile", "raw"), PASSIVE_BYTES, ids=lambda p: getattr(p, "name", p))
def test_a_reply_reads_every_mode_through_the_profile(profile: RobotProfile, raw: int) -> None:
    for mode in OIMode:
        frame = decode_reply([35], bytes((int(mode) + raw - 1,)), profile)
        assert frame.oi_mode is mode and frame.as_dict()["oi_mode"] is mode


def test_what_the_session_learned_overrides_the_profile() -> None:
    """A 600 connected with the create2 profile: the connection learns the offset and tells
    the parser, so the frames read right although the profile says otherwise."""
    learned = StreamParser([35], CREATE2, mode_plus_one=True).layout
    assert learned.decode(b"\x23\x02").oi_mode is OIMode.PASSIVE
    ruled_out = decode_reply([35], b"\x02", ROOMBA600, mode_plus_one=False)
    assert ruled_out.oi_mode is OIMode.SAFE


def test_a_byte_that_is_no_mode_reads_the_nearest_end_and_stays_as_sent_by_name() -> None:
    low, high = decode_reply([35], b"\x00", ROOMBA600), decode_reply([35], b"\x05", ROOMBA600)
    assert (low.oi_mode, high.oi_mode) == (OIMode.OFF, OIMode.FULL)
    assert (low.as_dict()["oi_mode"], high.as_dict()["oi_mode"]) == (0, 5)


def test_the_offset_survives_a_pickle() -> None:
    frame = decode_reply([35], b"\x02", CREATE2, mode_plus_one=True)
    assert pickle.loads(pickle.dumps(frame)).oi_mode is OIMode.PASSIVE


def test_layout_for_takes_a_list_and_refuses_what_is_no_list_of_ids() -> None:
    assert layout_for([29, 13]) is layout_for((29, 13))
    with pytest.raises(ValueError, match=r"sensors: packet ids must be a list of packet ids"):
        layout_for(29)  # type: ignore[arg-type]
