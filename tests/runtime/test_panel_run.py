"""The clock panel's leaves on the simulator: the bytes the spec gives, and the edge form
of the button condition (``button_pressed``): one press, one SUCCESS, where ``button`` is
SUCCESS on every frame the button is held (a maker's one press beeped 11 times)."""

from __future__ import annotations

from pathlib import Path

from roomba_bt.oi.encode import decode_command
from roomba_bt.oi.profiles import ROOMBA600
from roomba_bt.runtime.summary import Outcome

from .simrun import RunMission

PANEL = """
mission: panel
tree:
  sequence:
    - mode: safe
    - display: "hi!"
    - schedule_leds: {days: [mon, fri], leds: [clock, colon]}
    - press: clean
"""


def _sent(written: bytes, opcodes: set[int]) -> list[list[int]]:
    """The commands of ``opcodes`` in ``written``, each as its bytes."""
    found, rest = [], written
    while rest and (decoded := decode_command(rest)) is not None:
        command, size = decoded
        if command.opcode in opcodes:
            found.append(list(rest[:size]))
        rest = rest[size:]
    return found


def test_the_panel_leaves_send_the_specs_bytes(run_mission: RunMission) -> None:
    run = run_mission(PANEL, profile=ROOMBA600)
    assert run.summary.outcome is Outcome.SUCCESS
    assert _sent(run.link.written, {162, 164, 165}) == [
        [164, 104, 105, 33, 32],  # "hi!" padded with a space, lowercase as written
        [162, 0b100010, 0b1001],  # mon (bit 1), fri (bit 5); colon (bit 0), clock (bit 3)
        [165, 1],
    ]


def _plays(run_mission: RunMission, condition: str) -> int:
    """The Play commands of a repeat that plays each time ``condition`` holds, for a second
    in which Clean is pressed once (Buttons 165: held 1/6 s, about 11 frames), as the
    maker's toy beeped."""
    mission = f"""
mission: beeps
tree:
  sequence:
    - mode: safe
    - song: {{number: 0, notes: [C5 16ms]}}
    - parallel:
        policy: all
        children:
          - sequence: [{{wait: 300ms}}, {{press: clean}}]
          - force_success:
              timeout:
                after: 1s
                do:
                  repeat:
                    do:
                      sequence:
                        - wait: 1h
                          until: {{{condition}: clean}}
                        - play: 0
"""
    run = run_mission(mission, timeout=5.0)
    assert run.summary.outcome is Outcome.SUCCESS, run.summary
    return len(_sent(run.link.written, {141}))


def test_button_pressed_is_one_success_a_press_where_button_is_one_a_frame(
    run_mission: RunMission,
) -> None:
    assert _plays(run_mission, "button_pressed") == 1
    assert _plays(run_mission, "button") > 5


#: the empty room, with a finger on Clean at 2 s (a world's ``press`` event)
PRESSED_AT_2S = """
name: pressed
rooms: [{rect: [0, 0, 4, 4]}]
robot: {start: {at: [2, 2], heading: 0}}
events: [{at: 2, kind: press, button: clean}]
"""


def test_a_worlds_press_ends_a_wait_for_the_button_in_safe(
    run_mission: RunMission, tmp_path: Path
) -> None:
    """A simulated run scripts a press in its world: the mission waiting in Safe for
    ``button_pressed: clean`` goes on at the press, and the robot starts no cycle of its
    own (Safe does not answer the buttons)."""
    world = tmp_path / "pressed.yaml"
    world.write_text(PRESSED_AT_2S)
    mission = """
mission: wait-for-clean
tree:
  sequence:
    - mode: safe
    - wait: 10s
      until: {button_pressed: clean}
"""
    run = run_mission(mission, world=str(world), timeout=20.0)
    assert run.summary.outcome is Outcome.SUCCESS, run.summary
    assert 2.0 <= run.simulator.time < 2.2  # ended at the press, not at the 10 s wait's end
    assert not [e for e in run.simulator.events if e.kind == "builtin"]
