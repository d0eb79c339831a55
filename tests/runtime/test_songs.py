"""Songs played as a maker writes them: ``play``, a wait until packet 37 shows the song
over, the next ``play`` (the way past 16 notes: docs/missions.md, "Songs")."""

from __future__ import annotations

from roomba_bt.runtime.summary import Outcome

from .simrun import RunMission

CHAIN = """\
mission: chain
tree:
  sequence:
    - mode: safe
    - song: {number: 0, notes: [C4 250ms, D4 250ms, E4 250ms, F4 250ms]}
    - song: {number: 1, notes: [G4 250ms, C4 500ms]}
    - play: 0
    - wait: 10s
      until: {sensor: song_playing == 0}
    - play: 1
    - wait: 10s
      until: {sensor: song_playing == 0}
"""


def test_two_songs_chained_on_packet_37_both_play_one_after_the_other(
    run_mission: RunMission,
) -> None:
    """Until session 32 ``play`` succeeded on the tick it was sent, the wait read the frame
    from before the Play (no song playing) and passed, and the outbox kept only the second
    of the two Plays of that tick: song 0 never played, the run said SUCCESS after 0.01 s."""
    run = run_mission(CHAIN)
    assert run.summary.outcome is Outcome.SUCCESS
    plays = [(t, data) for t, data in run.link.writes if data[:1] == bytes([141])]
    assert [data for _, data in plays] == [bytes([141, 0]), bytes([141, 1])]
    (first, _), (second, _) = plays
    assert second - first >= 1.0  # song 0's length: song 1 waited for its end
    assert run.summary.mission_time_s >= 1.0 + 0.75
    assert not [e for e in run.simulator.events if e.kind == "refused"]


OVERLAP = """\
mission: overlap
tree:
  sequence:
    - mode: safe
    - song: {number: 0, notes: [C4 1s]}
    - song: {number: 1, notes: [G4 250ms]}
    - play: 0
    - play: 1
    - log: {message: "song 1 played"}
  until: {sensor: song_number == 7}
"""


def test_a_play_the_robot_ignores_fails_when_packet_36_is_read(run_mission: RunMission) -> None:
    """Song 0 still plays when song 1's Play comes: the robot (and the simulator) ignore it,
    and packet 37 shows a song playing all the same. With packet 36 read (the ``until``
    reads it), ``play: 1`` fails, said, where it succeeded on song 0's packet 37."""
    run = run_mission(OVERLAP)
    assert run.summary.outcome is Outcome.FAILURE, run.summary
    refused = [e.detail for e in run.simulator.events if e.kind == "refused"]
    assert refused == ["play 1 ignored: song 0 still playing"]
    assert "song 1 did not start: packet 36 showed song 0" in str(run.summary)
